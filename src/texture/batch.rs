//! A texture over many points: slices in any order, filtered slices, and
//! grids, whose octaves share each band's located rows.

use wide::f32x8;

use super::Texture;
use crate::simd::{GridRows, Point};

impl<const D: usize, const N: usize> Texture<D, N> {
    /// Values of many points into a caller's buffer ([`Texture::value8`]
    /// eight at a time).
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out` is shorter than `xs`; nothing is written.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<3, 2>::new(worley::Config::default(), Combination::crackle(), Fractal::default(), None).unwrap();
    /// let points: Vec<[f32; 3]> = (0..50).map(|i| [i as f32 * 0.2, 0.0, 0.0]).collect();
    /// let mut out = vec![0.0; 50];
    /// t.values(&points, &mut out).unwrap();
    /// assert_eq!(out[17], t.value([17.0f32 * 0.2, 0.0, 0.0].map(f64::from)));
    /// ```
    pub fn values<P: Point<D>>(&self, xs: &[P], out: &mut [f32]) -> Result<(), crate::SizeError> {
        self.filtered_values(xs, None, out)
    }

    /// Values of many points, point i standing for a footprint of side
    /// `widths[i]` ([`Texture::filtered8`] eight at a time); `None` is the
    /// point samples of [`Texture::values`].
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out` or `widths` is shorter than `xs`;
    /// nothing is written.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::octaves(3), None).unwrap();
    /// let points: Vec<[f64; 2]> = (0..20).map(|i| [i as f64 * 0.3, 1.0]).collect();
    /// let widths: Vec<f32> = (0..20).map(|i| i as f32 * 0.05).collect();
    /// let mut out = vec![0.0; 20];
    /// t.filtered_values(&points, Some(&widths), &mut out).unwrap();
    /// assert_eq!(out[9], t.filtered(points[9], widths[9]));
    /// ```
    pub fn filtered_values<P: Point<D>>(
        &self,
        xs: &[P],
        widths: Option<&[f32]>,
        out: &mut [f32],
    ) -> Result<(), crate::SizeError> {
        if out.len() < xs.len() {
            return Err(crate::SizeError { needed: xs.len(), given: out.len() });
        }
        if let Some(w) = widths.filter(|w| w.len() < xs.len()) {
            return Err(crate::SizeError { needed: xs.len(), given: w.len() });
        }
        for (c, (chunk, dst)) in xs.chunks(8).zip(out.chunks_mut(8)).enumerate() {
            let mut block = [[0.0; D]; 8];
            let mut width = [0.0; 8];
            for (i, p) in chunk.iter().enumerate() {
                block[i] = p.coordinates();
                width[i] = widths.map_or(0.0, |w| w[c * 8 + i]);
            }
            let v = self.filtered8(&block, width).to_array();
            dst.copy_from_slice(&v[..dst.len()]);
        }
        Ok(())
    }

    /// Values of every point of a grid (axis 0 fastest), on all cores when
    /// the `parallel` feature is on; identical to the serial result and to
    /// [`Texture::value`] at each [`Grid::point`](crate::Grid::point).
    ///
    /// Without a period, and when every octave's frequency is a power of two
    /// (the default lacunarity 2), octave i of the grid is itself a grid,
    /// with origin and step scaled by its frequency, whose points are the
    /// octave's coordinates bit for bit (scaling by a power of two is exact
    /// and commutes with rounding): each octave then takes the coherent grid
    /// path of [`Simd::evaluate_grid_distances`](crate::Simd::evaluate_grid_distances), a band of rows at a time
    /// for all octaves, and the combination and the sum run in the order
    /// [`Texture::value8`] runs them. Other textures take eight points at a
    /// time through [`Texture::value8`].
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out.len() != grid.len()`.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// use worley::Grid;
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::octaves(2), None).unwrap();
    /// let grid = Grid { origin: [0.0, 0.0], step: [0.1, 0.1], size: [32, 16] };
    /// let mut image = vec![0.0; 32 * 16];
    /// t.values_grid(&grid, &mut image).unwrap();
    /// assert_eq!(image[32 + 3], t.value(grid.point(32 + 3)));
    /// ```
    pub fn values_grid(&self, grid: &crate::Grid<D>, out: &mut [f32]) -> Result<(), crate::SizeError> {
        self.filtered_grid(grid, 0.0, out)
    }

    /// Values of every point of a grid, each standing for a footprint of
    /// side `width` (a grid's samples usually stand for their step): the
    /// same bits as [`Texture::filtered8`] at each point, through the grid
    /// tiles octave by octave where [`Texture::values_grid`] takes them
    /// (octaves the footprint does not resolve are not evaluated), eight
    /// points at a time otherwise.
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out.len() != grid.len()`.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// use worley::Grid;
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::octaves(6), None).unwrap();
    /// let grid = Grid { origin: [0.0, 0.0], step: [0.5, 0.5], size: [16, 16] };
    /// let mut image = vec![0.0; 16 * 16];
    /// t.filtered_grid(&grid, 0.5, &mut image).unwrap();
    /// assert_eq!(image[16 + 3], t.filtered(grid.point(16 + 3), 0.5));
    /// ```
    pub fn filtered_grid(&self, grid: &crate::Grid<D>, width: f32, out: &mut [f32]) -> Result<(), crate::SizeError> {
        let needed = grid.len().ok_or(crate::SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(crate::SizeError { needed, given: out.len() });
        }
        self.grid_rows_with(grid, width, 0, out, true);
        Ok(())
    }

    /// Rows `first..` of a grid, as many whole rows as `out` holds
    /// ([`Grid::rows`](crate::Grid::rows) says how rows are counted): the
    /// bits [`Texture::filtered_grid`] writes for those rows, through the
    /// same path, on the calling thread. Bands baked apart (on other cores
    /// or machines) assemble into the whole grid bit for bit, as with
    /// [`Simd::evaluate_grid_rows`](crate::Simd::evaluate_grid_rows).
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out` is not whole rows or runs past the
    /// grid's last row; nothing is written.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// use worley::Grid;
    /// let t = Texture::<3, 2>::new(worley::Config::default(), Combination::crackle(), Fractal::octaves(3), None).unwrap();
    /// let grid = Grid { origin: [0.3, 0.1, 0.5], step: [0.07, 0.07, 1.0], size: [24, 20, 1] };
    /// let mut whole = vec![0.0; 24 * 20];
    /// t.filtered_grid(&grid, 0.07, &mut whole).unwrap();
    /// let mut band = vec![0.0; 24 * 5];
    /// t.filtered_grid_rows(&grid, 0.07, 11, &mut band).unwrap();
    /// assert_eq!(band[..], whole[24 * 11..24 * 16]);
    /// ```
    pub fn filtered_grid_rows(
        &self,
        grid: &crate::Grid<D>,
        width: f32,
        first: usize,
        out: &mut [f32],
    ) -> Result<(), crate::SizeError> {
        grid.check_rows(first, out.len())?;
        self.grid_rows_with(grid, width, first, out, false);
        Ok(())
    }

    /// Rows `first..` of the grid into `out` (whole rows, checked by the
    /// caller), on all cores with `parallel` and the `parallel` feature.
    fn grid_rows_with(&self, grid: &crate::Grid<D>, width: f32, first: usize, out: &mut [f32], parallel: bool) {
        let row = grid.size[0];
        if out.is_empty() || row == 0 {
            return;
        }
        let alpha: Vec<f32> = self.octaves.iter().map(|&(f, _, _)| self.weights(&[width; 8], f)[0]).collect();
        let Some(octaves) = self.octave_grids(grid, &alpha) else {
            // Eight points at a time, each at its own grid index.
            let each = |start: usize, dst: &mut [f32]| {
                grid.eights_into(first * row + start, dst, |block| self.filtered8(block, [width; 8]).to_array());
            };
            #[cfg(feature = "parallel")]
            if parallel {
                let tile = crate::simd::TILE;
                crate::parallel::for_each_chunk(out, tile, &|t, dst| each(t * tile, dst));
                return;
            }
            let _ = parallel;
            return each(0, out);
        };
        let mean = if alpha.iter().all(|&a| a == 1.0) { f32::NAN } else { self.blend_curve().mean() };
        // Only the octaves the footprint resolves are evaluated.
        let rows: Vec<Option<GridRows<'_, D>>> =
            octaves.iter().zip(&alpha).map(|(g, &a)| (a != 0.0).then(|| self.values.grid_rows(g))).collect();
        // Rows `first..` of every octave, combined and summed into `dst`,
        // in the order and with the operations of `filtered8`.
        let band = |first: usize, dst: &mut [f32]| {
            let own = self.border.is_some() || self.smooth.is_some() || self.n_sphere.is_some();
            let mut distances = vec![[0f32; N]; if own { 0 } else { dst.len() }];
            let (mut borders, mut smooths, mut spheres) = (None, None, None);
            for (i, (octave, &(_, amplitude, _))) in rows.iter().zip(&self.octaves).enumerate() {
                let a = alpha[i];
                let Some(octave) = octave else {
                    for s in dst.iter_mut() {
                        *s = if i == 0 { mean } else { *s + amplitude * mean };
                    }
                    continue;
                };
                let sum = |sum: &mut [f32], v: &[f32]| {
                    for (s, &v) in sum.iter_mut().zip(v) {
                        let v = if a == 1.0 { v } else { a * v + (1.0 - a) * mean };
                        *s = if i == 0 { v } else { *s + amplitude * v };
                    }
                };
                if let Some(border) = &self.border {
                    // The border through the grid tiles, its distance the value.
                    let borders = borders.get_or_insert_with(|| vec![crate::Border32::default(); dst.len()]);
                    border.grid_rows_into(octave, first, borders);
                    for (s, b) in dst.chunks_mut(8).zip(borders.chunks(8)) {
                        sum(s, &std::array::from_fn::<f32, 8, _>(|j| b[j.min(b.len() - 1)].distance));
                    }
                    continue;
                }
                if let Some((smooth, s)) = &self.smooth {
                    // Smooth F1 from the grid tiles' F1.
                    let smooths = smooths.get_or_insert_with(|| vec![crate::Smooth32::INVALID; dst.len()]);
                    smooth.grid_rows_into(octave, first, *s, smooths);
                    for (d, v) in dst.chunks_mut(8).zip(smooths.chunks(8)) {
                        sum(d, &std::array::from_fn::<f32, 8, _>(|j| v[j.min(v.len() - 1)].value));
                    }
                    continue;
                }
                if let Some(n_sphere) = &self.n_sphere {
                    // The radius from the grid tiles' F1, shared by the
                    // samples of one centre.
                    let spheres = spheres.get_or_insert_with(|| vec![crate::NSphere32::INVALID; dst.len()]);
                    n_sphere.grid_rows_into(octave, first, spheres);
                    for (d, v) in dst.chunks_mut(8).zip(spheres.chunks(8)) {
                        sum(d, &std::array::from_fn::<f32, 8, _>(|j| v[j.min(v.len() - 1)].radius));
                    }
                    continue;
                }
                self.values.grid_rows_distances(octave, first, &mut distances);
                for (s, d) in dst.chunks_mut(8).zip(distances.chunks(8)) {
                    let f: [f32x8; N] =
                        std::array::from_fn(|k| f32x8::from(std::array::from_fn(|j| d[j.min(d.len() - 1)][k])));
                    sum(s, &self.combination.value(&f).to_array());
                }
            }
        };
        #[cfg(feature = "parallel")]
        if parallel {
            let rows = crate::simd::BAND;
            crate::parallel::for_each_chunk(out, rows * row, &|b, dst| band(first + b * rows, dst));
            return;
        }
        let rows = crate::simd::SERIAL_BAND;
        out.chunks_mut(rows * row).enumerate().for_each(|(b, dst)| band(first + b * rows, dst));
    }

    /// Octave i of `grid` as a grid of its own (origin and step times the
    /// octave's frequency), where that gives the octave's coordinates bit
    /// for bit: no period, every frequency a power of two, and nothing
    /// scaled near overflow, no NaN or infinite origin or step.
    ///
    /// An octave the footprint does not resolve (weight 0) is its mean
    /// without evaluation, which is its value only where the kernel can
    /// locate every point: such an octave also needs the grid's extent
    /// within the kernel's range (else eight points at a time, which give
    /// NaN where the kernel would). A NaN weight takes eight points at a
    /// time too.
    pub(super) fn octave_grids(&self, grid: &crate::Grid<D>, alpha: &[f32]) -> Option<Vec<crate::Grid<D>>> {
        let power_of_two = |f: f64| f.is_normal() && f > 0.0 && f.to_bits() & ((1u64 << 52) - 1) == 0;
        // The largest magnitude any point's coordinate or partial sum takes.
        let extent = (0..D).fold(0f64, |m, a| m.max(grid.origin[a].abs() + grid.step[a].abs() * grid.size[a] as f64));
        let finite = grid.origin.iter().chain(&grid.step).all(|v| v.is_finite());
        let suits = finite
            && self.period.is_none()
            && self.octaves.iter().all(|&(f, _, _)| power_of_two(f) && extent * f < 1e300)
            && alpha.iter().zip(&self.octaves).all(|(&a, &(f, _, _))| {
                (0.0..=1.0).contains(&a)
                    && (a != 0.0
                        || extent * f * self.values.pattern().scale() < crate::definition::MAX_CELL_COORD / 2.0)
            });
        suits.then(|| {
            self.octaves
                .iter()
                .map(|&(f, _, _)| crate::Grid {
                    origin: grid.origin.map(|o| o * f),
                    step: grid.step.map(|s| s * f),
                    size: grid.size,
                })
                .collect()
        })
    }
}
