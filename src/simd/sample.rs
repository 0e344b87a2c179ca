//! What the batch and grid calls read and write per sample: any point type
//! ([`Point`]) or a regular [`Grid`] of samples in, whole results or
//! distances alone ([`GridSample`]) out.

use super::best::Best;
use super::lanes::{Lanes, WIDEST};
use super::tiles::{TileAt, TileCells};
use super::{Features32, Metric32, Simd};
use crate::definition::INVALID_ID;

/// A sample position the kernel accepts, converted to f64 user units.
pub trait Point<const D: usize>: Copy {
    /// The coordinates in f64 (exact for every implementor here).
    fn coordinates(&self) -> [f64; D];
}

impl<const D: usize> Point<D> for [f64; D] {
    #[inline(always)]
    fn coordinates(&self) -> [f64; D] {
        *self
    }
}

impl<const D: usize> Point<D> for [f32; D] {
    #[inline(always)]
    fn coordinates(&self) -> [f64; D] {
        self.map(f64::from)
    }
}

macro_rules! glam_point {
    ($d:literal, $($t:ty),*) => {$(
        impl Point<$d> for $t {
            #[inline(always)]
            fn coordinates(&self) -> [f64; $d] {
                self.to_array().map(f64::from)
            }
        }
    )*};
}
glam_point!(2, glam::Vec2, glam::DVec2);
glam_point!(3, glam::Vec3, glam::Vec3A, glam::DVec3);
glam_point!(4, glam::Vec4, glam::DVec4);

/// What the coherent grid path writes per sample: whole results
/// ([`Features32`], the outputs the [`Simd`] was built for) or the distances
/// alone (`[f32; N]`, see [`Simd::evaluate_grid_distances`]). `Copy`, since a
/// stripe of outputs is filled before its tiles write it.
pub(super) trait GridSample<const D: usize, const N: usize>: Sized + Send + Copy {
    /// Whether the tiles compute the outputs the [`Simd`] was built for;
    /// false: distances only, whatever it was built for (the distances are
    /// the same bits either way).
    const FULL: bool;
    /// Whether the region holds the points' IDs even where the tiles do not
    /// read them (the border reads them after the tiles' search).
    const REGION_IDS: bool = false;
    /// A tile's results into its rows of `out`, from its search's raw
    /// results (`best`, ranks in lane units, as [`Simd::tile`] leaves them)
    /// and what the search read.
    fn tile_out<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        simd: &Simd<D, N>,
        metric: M,
        cells: TileCells<'_, L, D>,
        best: &mut [Best<L, D, N>; K],
        out: &mut [Self],
        at: &TileAt,
    );
    /// Grid points `first..first + dst.len()` by the per-sample kernel.
    fn per_sample(simd: &Simd<D, N>, grid: &Grid<D>, first: usize, dst: &mut [Self]);
}

impl<const D: usize, const N: usize> GridSample<D, N> for Features32<D, N> {
    const FULL: bool = true;
    #[inline(always)]
    fn tile_out<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        simd: &Simd<D, N>,
        _: M,
        _: TileCells<'_, L, D>,
        best: &mut [Best<L, D, N>; K],
        out: &mut [Self],
        at: &TileAt,
    ) {
        for (k, b) in best.iter_mut().enumerate().take(at.rows) {
            simd.finish::<L, DELTAS>(b);
            simd.forget_unasked::<L, IDS, DELTAS>(b);
            write_lanes::<L, D, N, IDS, DELTAS>(b, at.row(out, k));
        }
    }
    fn per_sample(simd: &Simd<D, N>, grid: &Grid<D>, first: usize, dst: &mut [Self]) {
        simd.grid_range(grid, first, dst)
    }
}

impl<const D: usize, const N: usize> GridSample<D, N> for [f32; N] {
    const FULL: bool = false;
    #[inline(always)]
    fn tile_out<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        simd: &Simd<D, N>,
        _: M,
        _: TileCells<'_, L, D>,
        best: &mut [Best<L, D, N>; K],
        out: &mut [Self],
        at: &TileAt,
    ) {
        for (k, b) in best.iter_mut().enumerate().take(at.rows) {
            simd.finish::<L, DELTAS>(b);
            let dst = at.row(out, k);
            if N == 1 && dst.len() == L::N {
                // One store of the lanes, the common case of a full tile row.
                L::f_store(b.rank[0], dst.as_flattened_mut());
                continue;
            }
            let mut distance = [[0.0; WIDEST]; N];
            for (j, lanes) in distance.iter_mut().enumerate() {
                L::f_store(b.rank[j], &mut lanes[..L::N]);
            }
            for (i, o) in dst.iter_mut().enumerate() {
                *o = std::array::from_fn(|j| distance[j][i]);
            }
        }
    }
    fn per_sample(simd: &Simd<D, N>, grid: &Grid<D>, first: usize, dst: &mut [Self]) {
        let mut whole = [Features32 { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; 8];
        for (c, chunk) in dst.chunks_mut(8).enumerate() {
            simd.grid_range(grid, first + c * 8, &mut whole[..chunk.len()]);
            for (o, f) in chunk.iter_mut().zip(&whole) {
                *o = f.distance;
            }
        }
    }
}

/// Up to [`Lanes::N`] lanes of a finished result into `dst`. Without `IDS`
/// the IDs are written as [`INVALID_ID`] and without `DELTAS` the deltas as
/// zero, which is what a result holds when they were not asked for and
/// every lane is valid; the general caller passes both as true.
#[inline(always)]
pub(super) fn write_lanes<L: Lanes, const D: usize, const N: usize, const IDS: bool, const DELTAS: bool>(
    b: &Best<L, D, N>,
    dst: &mut [Features32<D, N>],
) {
    // Stores in loops rather than array `map`s: the maps stayed out-of-line
    // calls in the run-time AVX-512 copy, compiled without its instructions.
    let mut distance = [[0.0; WIDEST]; N];
    for (k, lanes) in distance.iter_mut().enumerate() {
        L::f_store(b.rank[k], &mut lanes[..L::N]);
    }
    if !IDS && !DELTAS {
        for (i, o) in dst.iter_mut().enumerate() {
            *o = Features32 {
                distance: std::array::from_fn(|k| distance[k][i]),
                delta: [[0.0; D]; N],
                id: [INVALID_ID; N],
            };
        }
        return;
    }
    let mut id = [[INVALID_ID; WIDEST]; N];
    let mut delta = [[[0.0; WIDEST]; D]; N];
    for k in 0..N {
        if IDS {
            L::u_store(b.id[k], &mut id[k][..L::N]);
        }
        for a in (0..D).filter(|_| DELTAS) {
            L::f_store(b.delta[k][a], &mut delta[k][a][..L::N]);
        }
    }
    for (i, o) in dst.iter_mut().enumerate() {
        o.distance = std::array::from_fn(|k| distance[k][i]);
        o.id = std::array::from_fn(|k| id[k][i]);
        o.delta = std::array::from_fn(|k| std::array::from_fn(|a| delta[k][a][i]));
    }
}

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
