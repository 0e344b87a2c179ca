//! Batches for the SIMD kernel: slices, regular grids, rayon tiles and
//! points given as a cell plus a fraction. Every entry point feeds the same
//! kernel (eight lanes, or sixteen for slices where the build or, for the
//! Euclidean metric, the CPU has AVX-512), so a point gives the same bits
//! whichever way it arrives.

use super::best::Best;
use super::generate::UNIT;
pub use super::grid::{Grid, SizeError, TILE};
use super::locate::Located;
use super::sample::write_lanes;
pub use super::sample::Point;
use super::search::{Stages, FIRST, REST};
use super::tiles::GridSample;
use super::{Features32, Simd};
use crate::definition::MAX_CELL_COORD;
#[cfg(target_feature = "avx512f")]
use crate::simd::lanes::Sixteen;
use crate::simd::lanes::{Eight, Lanes, One, WIDEST};

/// Shades arbitrary points eight at a time, the shape of a renderer's loop
/// over its hits: `f` gets each block of eight points (a last block of fewer
/// repeats its last point) and returns eight results, of which those of real
/// points are written to `out`, in order. On the calling thread.
///
/// ```
/// use worley::{by_eights, Config, Outputs, Simd};
/// let basis = Simd::<3, 2>::new(Config::default(), Outputs::Ids).unwrap();
/// let hits: Vec<[f32; 3]> = (0..13).map(|i| [i as f32 * 0.31, 0.5, -2.0]).collect();
/// let mut crackle = vec![0f32; hits.len()];
/// by_eights(&hits, &mut crackle, |x| {
///     let f = basis.evaluate8(x);
///     (f.distance[1] - f.distance[0]).to_array()
/// })
/// .unwrap();
/// let one = basis.evaluate([12.0 * 0.31f32 as f64, 0.5, -2.0]);
/// assert_eq!(crackle[12], one.distance[1] - one.distance[0]);
/// ```
///
/// # Errors
/// [`SizeError`] if `out` is shorter than `xs`; nothing is written.
pub fn by_eights<const D: usize, P: Point<D>, T: Copy>(
    xs: &[P],
    out: &mut [T],
    mut f: impl FnMut(&[[f64; D]; 8]) -> [T; 8],
) -> Result<(), SizeError> {
    if out.len() < xs.len() {
        return Err(SizeError { needed: xs.len(), given: out.len() });
    }
    for (chunk, dst) in xs.chunks(8).zip(out.chunks_mut(8)) {
        let block: [[f64; D]; 8] = std::array::from_fn(|i| chunk[i.min(chunk.len() - 1)].coordinates());
        let values = f(&block);
        dst[..chunk.len()].copy_from_slice(&values[..chunk.len()]);
    }
    Ok(())
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Many samples into a caller's buffer, sixteen at a time where the
    /// build has AVX-512 or the metric is Euclidean and the CPU has it, and
    /// eight otherwise ([`Simd::slice_lanes`]; a short tail is padded).
    /// Results are the same as [`Simd::evaluate`]'s, bit for bit, in every
    /// build and on every CPU.
    ///
    /// # Errors
    /// [`SizeError`] if `out` is shorter than `xs`; nothing is written.
    ///
    /// ```
    /// use worley::{Config, Features32, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let points: Vec<glam::Vec3> = (0..100).map(|i| glam::Vec3::new(i as f32 * 0.1, 0.0, 1.0)).collect();
    /// let mut out = vec![Features32 { distance: [0.0; 1], delta: [[0.0; 3]; 1], id: [0; 1] }; points.len()];
    /// basis.evaluate_slice(&points, &mut out).unwrap();
    /// assert_eq!(out[42].distance, basis.evaluate_vec3(points[42]).distance);
    /// ```
    pub fn evaluate_slice<P: Point<D>>(&self, xs: &[P], out: &mut [Features32<D, N>]) -> Result<(), SizeError> {
        if out.len() < xs.len() {
            return Err(SizeError { needed: xs.len(), given: out.len() });
        }
        // Sixteen lanes where the build has AVX-512, eight otherwise (with
        // the run-time AVX2 copy in a default build): the same operations
        // per lane, so the same bits.
        #[cfg(target_feature = "avx512f")]
        self.slice_in_stages::<Sixteen, P>(
            xs,
            out,
            |at, start| self.dispatch_stage::<Sixteen, FIRST>(at, start),
            |at, start| self.dispatch_stage::<Sixteen, REST>(at, start),
        );
        // A default build on a CPU with AVX-512 runs the sixteen lanes an
        // AVX-512 build runs, compiled for them at run time.
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
        if super::avx512::evaluate_slice(self, xs, out) {
            return Ok(());
        }
        #[cfg(not(target_feature = "avx512f"))]
        self.slice_in_stages::<Eight, P>(
            xs,
            out,
            |at, start| self.dispatch8_stage::<FIRST>(at, start),
            |at, start| self.dispatch8_stage::<REST>(at, start),
        );
        Ok(())
    }

    /// Scattered samples in blocks of `L::N`: every block runs the first
    /// stage of the search (`first`: each lane's 2^d block), and the lanes
    /// it leaves open are gathered, with their candidates so far, into
    /// blocks of their own for the rest of the search (`rest`), so a far
    /// cell is visited for lanes that need it rather than masked inside
    /// every block. A lane's result depends on that lane alone, so this
    /// gives the bits of the whole search on any block.
    #[inline(always)]
    pub(super) fn slice_in_stages<L: Lanes, P: Point<D>>(
        &self,
        xs: &[P],
        out: &mut [Features32<D, N>],
        first: impl Fn(&Located<L, D>, Best<L, D, N>) -> Stages<L, D, N>,
        rest: impl Fn(&Located<L, D>, Best<L, D, N>) -> Stages<L, D, N>,
    ) {
        let mut open = Open::<D, N>::empty();
        for (c, chunk) in xs.chunks(L::N).enumerate() {
            let mut block = [[0.0; D]; WIDEST];
            for (b, p) in block.iter_mut().zip(chunk) {
                *b = p.coordinates();
            }
            let (best, left, raw) = first(&self.locate::<L>(&block), Best::empty());
            write_lanes::<L, D, N, true, true>(&best, &mut out[c * L::N..c * L::N + chunk.len()]);
            let mut lanes = L::bits(left) & ((1 << chunk.len()) - 1);
            if lanes == 0 {
                continue;
            }
            let held = Held::<D, N>::from_lanes::<L>(&raw);
            while lanes != 0 {
                let i = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                open.push(block[i], c * L::N + i, held.get(i));
                if open.len == L::N {
                    self.finish_open::<L>(&mut open, out, &rest);
                }
            }
        }
        if open.len > 0 {
            self.finish_open::<L>(&mut open, out, &rest);
        }
    }

    /// The rest of the search for the gathered open lanes, from their
    /// first stage's candidates, into their slots of `out`; empties `open`.
    /// Inlined, so that the run-time AVX-512 copy compiles it with its own
    /// instructions.
    #[inline(always)]
    fn finish_open<L: Lanes>(
        &self,
        open: &mut Open<D, N>,
        out: &mut [Features32<D, N>],
        rest: &impl Fn(&Located<L, D>, Best<L, D, N>) -> Stages<L, D, N>,
    ) {
        let n = open.len;
        // Lanes past the gathered ones repeat the first; their results are
        // dropped.
        while open.len < L::N {
            open.push(open.points[0], 0, open.held.get(0));
        }
        let mut results = [Features32 { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; WIDEST];
        let (best, _, _) = rest(&self.locate::<L>(&open.points), open.held.to_lanes::<L>());
        write_lanes::<L, D, N, true, true>(&best, &mut results[..L::N]);
        for (slot, r) in open.slots[..n].iter().zip(results) {
            out[*slot] = r;
        }
        open.len = 0;
    }

    /// [`Simd::evaluate_slice`] on all cores (rayon), in tiles of [`TILE`]
    /// points; the results are identical to the serial call's.
    ///
    /// # Errors
    /// [`SizeError`] if `out` is shorter than `xs`; nothing is written.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let points: Vec<[f64; 2]> = (0..10_000).map(|i| [i as f64 * 0.01, 3.0]).collect();
    /// let mut out = vec![basis.evaluate([0.0, 0.0]); points.len()];
    /// basis.evaluate_slice_parallel(&points, &mut out).unwrap();
    /// assert_eq!(out[9_999].distance, basis.evaluate(points[9_999]).distance);
    /// ```
    #[cfg(feature = "parallel")]
    pub fn evaluate_slice_parallel<P: Point<D> + Sync>(
        &self,
        xs: &[P],
        out: &mut [Features32<D, N>],
    ) -> Result<(), SizeError> {
        if out.len() < xs.len() {
            return Err(SizeError { needed: xs.len(), given: out.len() });
        }
        crate::parallel::for_each_chunk(&mut out[..xs.len()], TILE, &|t, dst| {
            // Of the same length as `dst`, so this cannot fail.
            let _ = self.evaluate_slice(&xs[t * TILE..t * TILE + dst.len()], dst);
        });
        Ok(())
    }

    /// Every point of a regular grid, into a caller's buffer of exactly
    /// `grid.len()` results (axis 0 fastest).
    ///
    /// # Errors
    /// [`SizeError`] if `out.len() != grid.len()` (or the grid's size
    /// overflows); nothing is written.
    ///
    /// ```
    /// use worley::{Config, Grid, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let tile = Grid { origin: [0.0, 0.0, 0.5], step: [0.125, 0.125, 1.0], size: [64, 32, 1] };
    /// let mut out = vec![basis.evaluate([0.0; 3]); tile.len().unwrap()];
    /// basis.evaluate_grid(&tile, &mut out).unwrap();
    /// // Point (i, j) is at origin + step · (i, j), axis 0 fastest.
    /// assert_eq!(out[64 * 3 + 5].distance, basis.evaluate([5.0 * 0.125, 3.0 * 0.125, 0.5]).distance);
    /// ```
    pub fn evaluate_grid(&self, grid: &Grid<D>, out: &mut [Features32<D, N>]) -> Result<(), SizeError> {
        let needed = grid.len().ok_or(SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(SizeError { needed, given: out.len() });
        }
        if !self.grid_coherent(grid, out, false) {
            self.grid_range(grid, 0, out);
        }
        Ok(())
    }

    /// The distances alone of every point of a regular grid: F1..Fn of
    /// point i in `out[i]`, the same bits as the `distance` field
    /// [`Simd::evaluate_grid`] gives (NaN for a point whose coordinates are
    /// bad input), whatever outputs the [`Simd`] was built for. It is the
    /// call for a renderer that needs no IDs or deltas: on the coherent path
    /// ([`Simd::coherent_grid`]) it computes and writes nothing else, 4·n
    /// bytes per point where a [`Features32`] takes (4 + 4·d + 4)·n.
    ///
    /// # Errors
    /// [`SizeError`] if `out.len() != grid.len()` (or the grid's size
    /// overflows); nothing is written.
    ///
    /// ```
    /// use worley::{Config, Grid, Outputs, Simd};
    /// let basis = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Ids).unwrap();
    /// let tile = Grid { origin: [0.0, 0.0, 0.5], step: [0.125, 0.125, 1.0], size: [64, 32, 1] };
    /// let mut crackle = vec![[0.0; 2]; tile.len().unwrap()];
    /// basis.evaluate_grid_distances(&tile, &mut crackle).unwrap();
    /// let mut whole = vec![basis.evaluate([0.0; 3]); tile.len().unwrap()];
    /// basis.evaluate_grid(&tile, &mut whole).unwrap();
    /// assert!(crackle.iter().zip(&whole).all(|(d, f)| d.map(f32::to_bits) == f.distance.map(f32::to_bits)));
    /// ```
    pub fn evaluate_grid_distances(&self, grid: &Grid<D>, out: &mut [[f32; N]]) -> Result<(), SizeError> {
        let needed = grid.len().ok_or(SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(SizeError { needed, given: out.len() });
        }
        if !self.grid_coherent(grid, out, false) {
            GridSample::per_sample(self, grid, 0, out);
        }
        Ok(())
    }

    /// Rows `first..` of a grid, as many whole rows as `out` holds ([`Grid::rows`]
    /// says how rows are counted): the bits [`Simd::evaluate_grid`] writes
    /// for those rows, through the same path, on the calling thread. A bake
    /// split into bands of rows, on cores or on machines, assembles into the
    /// whole grid's results bit for bit. A sub-grid with a shifted origin
    /// carries no such guarantee: `origin + step · i` and `(origin + step ·
    /// first) + step · (i − first)` round differently (in 39 % of the rows of
    /// one measurement), and although the f32 results rarely change with
    /// one f64 ulp of the coordinate, a sample on a cell face or an f32
    /// rounding boundary can.
    ///
    /// # Errors
    /// [`SizeError`] if `out` is not whole rows or runs past the grid's
    /// last row; nothing is written.
    ///
    /// ```
    /// use worley::{Config, Grid, Outputs, Simd};
    /// let basis = Simd::<2, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    /// let image = Grid { origin: [0.1, -2.0], step: [0.03, 0.03], size: [40, 30] };
    /// let mut whole = vec![basis.evaluate([0.0; 2]); 40 * 30];
    /// basis.evaluate_grid(&image, &mut whole).unwrap();
    /// // Rows 7..19 alone, as a farm's second job would bake them.
    /// let mut band = vec![basis.evaluate([0.0; 2]); 40 * 12];
    /// basis.evaluate_grid_rows(&image, 7, &mut band).unwrap();
    /// assert_eq!(band[..], whole[40 * 7..40 * 19]);
    /// assert!(basis.evaluate_grid_rows(&image, 25, &mut band).is_err());
    /// ```
    pub fn evaluate_grid_rows(
        &self,
        grid: &Grid<D>,
        first: usize,
        out: &mut [Features32<D, N>],
    ) -> Result<(), SizeError> {
        grid.check_rows(first, out.len())?;
        let rows = self.grid_rows(grid);
        let width = grid.size[0].max(1);
        for (b, dst) in out.chunks_mut(super::SERIAL_BAND * width).enumerate() {
            self.grid_rows_into(&rows, first + b * super::SERIAL_BAND, dst);
        }
        Ok(())
    }

    /// [`Simd::evaluate_grid`] on all cores (rayon), in tiles of [`TILE`]
    /// points; the results are identical to the serial call's.
    ///
    /// # Errors
    /// As [`Simd::evaluate_grid`].
    ///
    /// ```
    /// use worley::{Config, Grid, Outputs, Simd};
    /// let basis = Simd::<2, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Ids).unwrap();
    /// let image = Grid { origin: [0.0, 0.0], step: [0.05, 0.05], size: [256, 128] };
    /// let (mut serial, mut parallel) = (vec![basis.evaluate([0.0; 2]); 256 * 128], vec![basis.evaluate([0.0; 2]); 256 * 128]);
    /// basis.evaluate_grid(&image, &mut serial).unwrap();
    /// basis.evaluate_grid_parallel(&image, &mut parallel).unwrap();
    /// assert_eq!(serial, parallel);
    /// ```
    #[cfg(feature = "parallel")]
    pub fn evaluate_grid_parallel(&self, grid: &Grid<D>, out: &mut [Features32<D, N>]) -> Result<(), SizeError> {
        let needed = grid.len().ok_or(SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(SizeError { needed, given: out.len() });
        }
        if !self.grid_coherent(grid, out, true) {
            crate::parallel::for_each_chunk(out, TILE, &|t, dst| self.grid_range(grid, t * TILE, dst));
        }
        Ok(())
    }

    /// Grid points `first..first + out.len()`.
    pub(super) fn grid_range(&self, grid: &Grid<D>, first: usize, out: &mut [Features32<D, N>]) {
        for (c, dst) in out.chunks_mut(8).enumerate() {
            let start = first + c * 8;
            let mut block = [[0.0; D]; 8];
            for (i, b) in block.iter_mut().enumerate().take(dst.len()) {
                *b = grid.point(start + i);
            }
            self.write8(&block, dst);
        }
    }

    /// Eight samples into up to eight results.
    #[inline]
    pub(super) fn write8(&self, block: &[[f64; D]; 8], dst: &mut [Features32<D, N>]) {
        write_lanes::<Eight, D, N, true, true>(&self.dispatch8(&self.locate::<Eight>(block)), dst);
    }

    /// One sample given as a cell of the pattern (see
    /// [`Pattern::locate`](crate::Pattern::locate)) and the fraction within
    /// it: the large-world entry point. The distances are within the
    /// kernel's bound 4ε_f32(F + 1/S) of
    /// [`Reference::evaluate_in_cell`](crate::Reference::evaluate_in_cell)
    /// on the same cell and fraction, however far the cell is from the
    /// origin, because nothing is computed relative to the origin.
    ///
    /// A fraction outside [0, 1] (or not finite) or a cell beyond
    /// ±[`MAX_CELL_COORD`] gives the invalid result (NaN distances,
    /// [`INVALID_ID`](crate::INVALID_ID)), as in the reference.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// // A sample 2^40 cells from the origin, with the full f32 fraction.
    /// let f = basis.evaluate_in_cell([1 << 40, -7, 3], [0.25, 0.5, 0.125]);
    /// assert!(f.distance[0] > 0.0 && f.distance[0] < 4.0);
    /// // A fraction outside [0, 1] is bad input.
    /// assert!(basis.evaluate_in_cell([0; 3], [1.5, 0.0, 0.0]).distance[0].is_nan());
    /// ```
    pub fn evaluate_in_cell(&self, cell: [i64; D], fraction: [f32; D]) -> Features32<D, N> {
        let located = in_cell::<One, D>(&[cell], &[fraction]);
        let best = self.dispatch_one(&located).0;
        Features32 { distance: best.rank, delta: best.delta, id: best.id }
    }

    /// Eight samples given as cells and fractions ([`Simd::evaluate_in_cell`]).
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let cells: [[i64; 2]; 8] = std::array::from_fn(|i| [i as i64 * 1_000_000_007, 5]);
    /// let f = basis.evaluate8_in_cell(&cells, &[[0.5, 0.5]; 8]);
    /// assert_eq!(f.distance[0].to_array()[6], basis.evaluate_in_cell(cells[6], [0.5, 0.5]).distance[0]);
    /// ```
    pub fn evaluate8_in_cell(&self, cells: &[[i64; D]; 8], fractions: &[[f32; D]; 8]) -> super::Features8<D, N> {
        let located = in_cell::<Eight, D>(cells, fractions);
        let best = self.dispatch8(&located);
        super::Features8 { distance: best.rank, delta: best.delta, id: best.id }
    }
}

/// Samples of a slice left open by the first stage of the search, waiting
/// for the rest of it: their positions, their indices in the output and
/// their candidates so far.
struct Open<const D: usize, const N: usize> {
    points: [[f64; D]; WIDEST],
    slots: [usize; WIDEST],
    held: Held<D, N>,
    len: usize,
}

impl<const D: usize, const N: usize> Open<D, N> {
    fn empty() -> Self {
        Open { points: [[0.0; D]; WIDEST], slots: [0; WIDEST], held: Held::empty(), len: 0 }
    }

    /// Appends the sample at `point` (output slot `slot`) with its
    /// candidates `lane`.
    fn push(&mut self, point: [f64; D], slot: usize, lane: Lane<D, N>) {
        self.points[self.len] = point;
        self.slots[self.len] = slot;
        self.held.set(self.len, lane);
        self.len += 1;
    }
}

/// One lane's candidates.
#[derive(Clone, Copy)]
struct Lane<const D: usize, const N: usize> {
    rank: [f32; N],
    delta: [[f32; D]; N],
    id: [u32; N],
}

/// The kernel's candidates ([`Best`]) as per-lane values, so that lanes of
/// different blocks can be gathered into one.
struct Held<const D: usize, const N: usize> {
    rank: [[f32; WIDEST]; N],
    delta: [[[f32; WIDEST]; D]; N],
    id: [[u32; WIDEST]; N],
}

impl<const D: usize, const N: usize> Held<D, N> {
    fn empty() -> Self {
        Held { rank: [[0.0; WIDEST]; N], delta: [[[0.0; WIDEST]; D]; N], id: [[0; WIDEST]; N] }
    }

    #[inline(always)]
    fn from_lanes<L: Lanes>(b: &Best<L, D, N>) -> Self {
        let mut h = Self::empty();
        for k in 0..N {
            L::f_store(b.rank[k], &mut h.rank[k][..L::N]);
            L::u_store(b.id[k], &mut h.id[k][..L::N]);
            for a in 0..D {
                L::f_store(b.delta[k][a], &mut h.delta[k][a][..L::N]);
            }
        }
        h
    }

    /// Lane `i`'s candidates.
    fn get(&self, i: usize) -> Lane<D, N> {
        Lane {
            rank: std::array::from_fn(|k| self.rank[k][i]),
            delta: std::array::from_fn(|k| std::array::from_fn(|a| self.delta[k][a][i])),
            id: std::array::from_fn(|k| self.id[k][i]),
        }
    }

    /// Sets lane `i`'s candidates.
    fn set(&mut self, i: usize, lane: Lane<D, N>) {
        for k in 0..N {
            self.rank[k][i] = lane.rank[k];
            self.id[k][i] = lane.id[k];
            for a in 0..D {
                self.delta[k][a][i] = lane.delta[k][a];
            }
        }
    }

    #[inline(always)]
    fn to_lanes<L: Lanes>(&self) -> Best<L, D, N> {
        Best {
            rank: super::per_axis(|k| L::f_load(&self.rank[k][..L::N])),
            delta: super::per_axis(|k| super::per_axis(|a| L::f_load(&self.delta[k][a][..L::N]))),
            id: super::per_axis(|k| L::u_load(&self.id[k][..L::N])),
        }
    }
}

/// Lanes located by cell and fraction; invalid lanes get cell 0.
pub(super) fn in_cell<L: Lanes, const D: usize>(cells: &[[i64; D]], fractions: &[[f32; D]]) -> Located<L, D> {
    let limit = MAX_CELL_COORD as u64;
    let mut cell = [[0i64; WIDEST]; D];
    let mut f = [[0f32; WIDEST]; D];
    let mut valid = [false; WIDEST];
    for i in 0..L::N {
        let ok =
            fractions[i].iter().all(|v| (0.0..=1.0).contains(v)) && cells[i].iter().all(|c| c.unsigned_abs() <= limit);
        valid[i] = ok;
        if ok {
            for a in 0..D {
                cell[a][i] = cells[i][a];
                f[a][i] = fractions[i][a] * UNIT;
            }
        }
    }
    Located::lanewise(cell, &f, valid)
}
