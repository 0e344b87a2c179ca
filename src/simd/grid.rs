//! A regular grid of samples (its points, rows and sizes) and the error of
//! a batch call whose output does not fit its input.

/// Points per rayon task in the parallel batches: large enough that a task
/// is worth scheduling, small enough that two cores share the tail evenly.
pub const TILE: usize = 4096;

/// A regular grid of samples: point `i` (per axis, `i[a] < size[a]`) is at
/// `origin[a] + step[a] · i[a]`, computed in f64. Points are stored with axis
/// 0 fastest (an image row, then the next row, then the next slab).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid<const D: usize> {
    /// The position of the first point, user units.
    pub origin: [f64; D],
    /// The spacing per axis, user units.
    pub step: [f64; D],
    /// The number of points per axis.
    pub size: [usize; D],
}

impl<const D: usize> Grid<D> {
    /// The number of points, or `None` if it overflows `usize`.
    pub fn len(&self) -> Option<usize> {
        self.size.iter().try_fold(1usize, |n, &s| n.checked_mul(s))
    }

    /// Whether the grid has no points.
    pub fn is_empty(&self) -> bool {
        self.size.contains(&0)
    }

    /// Fills `out` with one value per point (axis 0 fastest) from `f`,
    /// which gets eight points at a time: the shape of a renderer's shading
    /// loop over an image tile. Tiles of [`TILE`] points run on all cores
    /// with the `parallel` feature; a tile's last block of fewer than eight
    /// repeats its last point.
    ///
    /// ```
    /// use worley::{Config, Grid, Outputs, Simd};
    /// let basis = Simd::<2, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Distances).unwrap();
    /// let grid = Grid { origin: [0.0, 0.0], step: [0.1, 0.1], size: [64, 48] };
    /// let mut crackle = vec![0f32; 64 * 48];
    /// grid.fill_by_eights(&mut crackle, |points| {
    ///     let f = basis.evaluate8(points);
    ///     (f.distance[1] - f.distance[0]).to_array()
    /// })
    /// .unwrap();
    /// assert!(crackle.iter().all(|v| *v >= 0.0));
    /// ```
    ///
    /// # Errors
    /// [`SizeError`] if `out.len() != self.len()`; nothing is written.
    pub fn fill_by_eights<T: Copy + Send>(
        &self,
        out: &mut [T],
        f: impl Fn(&[[f64; D]; 8]) -> [T; 8] + Sync,
    ) -> Result<(), SizeError> {
        let needed = self.len().ok_or(SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(SizeError { needed, given: out.len() });
        }
        let tile = |t: usize, dst: &mut [T]| self.eights_into(t * TILE, dst, &f);
        #[cfg(feature = "parallel")]
        crate::parallel::for_each_chunk(out, TILE, &tile);
        #[cfg(not(feature = "parallel"))]
        for (t, dst) in out.chunks_mut(TILE).enumerate() {
            tile(t, dst);
        }
        Ok(())
    }

    /// The points from index `first` on, eight at a time on the calling
    /// thread, through `f` into `dst` (one value per point); a last block of
    /// fewer than eight repeats its last point.
    pub(crate) fn eights_into<T: Copy>(
        &self,
        first: usize,
        dst: &mut [T],
        mut f: impl FnMut(&[[f64; D]; 8]) -> [T; 8],
    ) {
        for (c, d8) in dst.chunks_mut(8).enumerate() {
            let start = first + c * 8;
            let block: [[f64; D]; 8] = std::array::from_fn(|i| self.point(start + i.min(d8.len() - 1)));
            d8.copy_from_slice(&f(&block)[..d8.len()]);
        }
    }

    /// The number of rows: lines of points along axis 0, counted over axis
    /// 1 fastest, then axis 2 and 3 (the image rows of a 2D grid, the rows
    /// of every slab in turn of a 3D one). `None` if it overflows `usize`.
    pub fn rows(&self) -> Option<usize> {
        self.size[1..].iter().try_fold(1usize, |n, &s| n.checked_mul(s))
    }

    /// Checks that `given` results are whole rows `first..` of the grid
    /// (none when the grid has no points); the error's `needed` is the
    /// longest whole-row length that would fit.
    pub(crate) fn check_rows(&self, first: usize, given: usize) -> Result<(), SizeError> {
        let width = self.size[0];
        let rows = self.rows().ok_or(SizeError { needed: usize::MAX, given })?;
        let left = rows.saturating_sub(first);
        let fits = given.checked_div(width).map_or(0, |rows| rows.min(left));
        let needed = fits.checked_mul(width).ok_or(SizeError { needed: usize::MAX, given })?;
        if needed != given {
            return Err(SizeError { needed, given });
        }
        Ok(())
    }

    /// The position of the point with linear index `index` (axis 0 fastest).
    pub fn point(&self, mut index: usize) -> [f64; D] {
        std::array::from_fn(|a| {
            let i = index % self.size[a].max(1);
            index /= self.size[a].max(1);
            self.origin[a] + self.step[a] * i as f64
        })
    }
}

/// The caller's output buffer does not match the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SizeError {
    /// Results the call produces.
    pub needed: usize,
    /// Length of the buffer given.
    pub given: usize,
}

impl std::fmt::Display for SizeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "output buffer holds {} results, the input needs {}", self.given, self.needed)
    }
}

impl std::error::Error for SizeError {}
