//! # The coherent path: samples close together share their cells' points
//!
//! A grid's neighbouring samples need the same few cells. Instead of
//! hashing and generating those cells again for every sample, this path
//! generates every cell of a band of the grid once ([`Region`]: the points as
//! struct-of-arrays, each with its cell along axis 0, and IDs when asked
//! for), then evaluates *tiles* of samples (one vector of `L::N` along axis
//! 0 per row, `L::N` rows) against the points that can matter to the tile,
//! each point broadcast to every lane. Tiles are 16 × 16 samples in
//! AVX-512 lanes (an AVX-512 build, or a default build on a CPU that has
//! AVX-512) when sixteen steps along axis 0 span at most one cell, and
//! 8 × 8 otherwise: the bigger tile shares its bound, its candidate search
//! and its certificate among four times the samples, while a candidate
//! costs a row about the same.
//!
//! ## Why it is cheap
//! - A grid's row lies along axis 0, so a sample's position on the other
//!   axes is its row's. The rank folds axis 0's term in last
//!   ([`Metric32::rank`]), so for each candidate the rest of the rank is
//!   computed once per row (the tile's rows in the lanes of one vector)
//!   and each row's vector of samples adds one term.
//! - A row of tiles shares its rows of cells: for every point in them, the
//!   fold of its gap terms to the tiles' box on the axes other than 0 is
//!   computed once ([`Simd::cell_rows`]), and a tile's point test adds axis
//!   0's term. A row's remaining cells are consecutive in the region, so
//!   their points are read as one run.
//!
//! ## Why the bits are the per-sample path's
//! - A lane computes a candidate's delta exactly as the per-sample kernel
//!   does: the sample's fraction minus the candidate cell's offset from the
//!   sample's own cell (an exact multiple of [`UNIT`]), minus the point's
//!   24-bit coordinate. Its rank is [`Metric32::rank`] of that delta, axis
//!   0's term folded into the rest of the axes' in the same order. The
//!   tile's frame is used only to choose candidates, never for a result.
//! - The insertion and the final scaling are the same functions.
//! - Points are ordered by rank and then by ID (see
//!   [`reference`](crate::reference)), so the order in which a path meets
//!   the points does not matter: only which points it meets.
//!
//! ## Why every point that matters is met
//! - **The bound.** Every point of the tile's own cells is inserted in
//!   every lane first; the largest F_n of any lane then, U, bounds F_n of
//!   every lane for good. When the own cells hold fewer than n points, U is
//!   the n-th smallest farthest distance from the tile's box to the points
//!   of the cells around.
//! - **The candidates.** Of the cells within one cell of the tile's cells,
//!   a cell whose box is farther than U from the tile's box is skipped, and
//!   so is a point farther than U from it. Both tests are made with U
//!   inflated twice by [`SLACK_REL`](super::tiles::SLACK_REL) and [`SLACK_ABS`](super::tiles::SLACK_ABS), far more than the
//!   rounding of any f32 quantity here, so a skipped point is strictly
//!   farther than any lane's F_n.
//! - **The certificate.** A lane is certified when its F_n is within U
//!   inflated once (so the skipped points cannot reach it) and strictly
//!   inside the distance from the lane to the outside of the cells searched,
//!   deflated by the same slack. A lane that is not certified is evaluated
//!   by the per-sample kernel, which is exact on its own.
//!
//! ## When it runs
//! [`Simd::evaluate_grid`] and [`Simd::evaluate_grid_parallel`] take it in
//! [`Mode::Exact`] when eight steps along axis 0 span at most one cell, every
//! coordinate of the grid is valid, and the band's cells are not many more
//! than its samples. A tile whose samples span more than two cells on some
//! axis (rows far apart) takes the per-sample kernel.

use super::generate::UNIT;
#[cfg(any(target_feature = "avx512f", target_feature = "avx2"))]
use super::lanes::Sixteen;
use super::lanes::{Eight, Lanes};
use super::metric::Others;
use super::region::{Axes, Band, Region};
use super::tiles::{min_max, GridSample};
use super::{Euclid, Grid, Metric32, Outputs, Simd};
use crate::config::{Metric, Mode};
use crate::definition::MAX_CELL_COORD;

/// Rows of a grid per band on all cores; a band's cells are generated once.
#[cfg(feature = "parallel")]
pub(crate) const BAND: usize = 64;
/// Rows per band of a serial call: twice as many share the band's margin of
/// cells, so fewer cells are generated twice (docs/simd.md has the
/// measurement), where the parallel call keeps more bands for more cores.
pub(crate) const SERIAL_BAND: usize = 128;

/// A grid located once, for a caller that combines several grids' results
/// band by band (a texture's octaves, see [`crate::texture::Texture::values_grid`]).
pub(crate) struct GridRows<'g, const D: usize> {
    grid: &'g Grid<D>,
    /// `None` where the grid does not suit the coherent path: its rows then
    /// take the per-sample kernel.
    axes: Option<Axes<D>>,
}

impl<const D: usize> GridRows<'_, D> {
    /// The grid.
    pub(crate) fn grid(&self) -> &Grid<D> {
        self.grid
    }
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Whether [`Simd::evaluate_grid`] takes the coherent path for `grid`:
    /// [`Mode::Exact`], eight steps along axis 0 within one cell
    /// (`8·|step[0]|·S ≤ 1`, S the [scale](crate::Pattern::scale)), rows
    /// spanning fewer than 2^23 cells, and every coordinate valid. The
    /// results are the same bits either way; only the speed differs. (A
    /// build without AVX2 runs the Euclidean tiles only where the CPU has
    /// AVX2; elsewhere such a grid's samples take the per-sample kernel.)
    ///
    /// ```
    /// use worley::{Config, Grid, Mode, Outputs, Simd};
    /// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let image = Grid { origin: [0.0, 0.0], step: [0.05, 0.05], size: [64, 64] };
    /// assert!(basis.coherent_grid(&image));
    /// // Samples a cell or more apart share nothing.
    /// assert!(!basis.coherent_grid(&Grid { step: [5.0, 5.0], ..image }));
    /// let window = Simd::<2, 1>::new(Config { mode: Mode::Window, ..Config::default() }, Outputs::Distances).unwrap();
    /// assert!(!window.coherent_grid(&image));
    /// ```
    pub fn coherent_grid(&self, grid: &Grid<D>) -> bool {
        self.grid_axes(grid).is_some()
    }

    /// Locates every coordinate of the grid, as [`Simd::locate`] would;
    /// `None` if one is invalid or the grid does not suit the path.
    fn grid_axes(&self, grid: &Grid<D>) -> Option<Axes<D>> {
        let scale = self.pattern.scale();
        let tile_width = grid.step[0].abs() * scale * 8.0;
        if self.config.mode != Mode::Exact || tile_width.is_nan() || tile_width > 1.0 {
            return None;
        }
        let mut cell: [Vec<i64>; D] = std::array::from_fn(|_| Vec::new());
        let mut f: [Vec<f32>; D] = std::array::from_fn(|_| Vec::new());
        for a in 0..D {
            for i in 0..grid.size[a] {
                let u = (grid.origin[a] + grid.step[a] * i as f64) * scale;
                if u.is_nan() || u.abs() > MAX_CELL_COORD {
                    return None;
                }
                let floor = u.floor();
                cell[a].push(floor as i64);
                f[a].push((u - floor) as f32 * UNIT);
            }
        }
        // Axis 0's cells are held relative to the band's first cell, times
        // UNIT, in f32: exact only within 2^24 cells.
        let (lo, hi) = min_max(&cell[0]);
        if hi.saturating_sub(lo) >= 1 << 23 {
            return None;
        }
        Some(Axes { cell, f, sixteen: 2.0 * tile_width <= 1.0 })
    }

    /// [`Simd::evaluate_grid`] on the coherent path, serially by bands of
    /// [`SERIAL_BAND`] rows or on all cores by bands of `BAND`; false
    /// (nothing written) if the grid does not suit it.
    pub(super) fn grid_coherent<T: GridSample<D, N>>(&self, grid: &Grid<D>, out: &mut [T], parallel: bool) -> bool {
        let Some(axes) = self.grid_axes(grid) else {
            return false;
        };
        let width = grid.size[0];
        if width == 0 || out.is_empty() {
            return true;
        }
        #[cfg(feature = "parallel")]
        if parallel {
            crate::parallel::for_each_chunk(out, BAND * width, &|b, dst| self.band(grid, &axes, b * BAND, dst));
            return true;
        }
        let _ = parallel;
        let band = |(b, dst): (usize, &mut [T])| self.band(grid, &axes, b * SERIAL_BAND, dst);
        out.chunks_mut(SERIAL_BAND * width).enumerate().for_each(band);
        true
    }

    /// `grid` located once, for evaluation a band of rows at a time.
    pub(crate) fn grid_rows<'g>(&self, grid: &'g Grid<D>) -> GridRows<'g, D> {
        GridRows { grid, axes: self.grid_axes(grid) }
    }

    /// Rows `first..` of the grid into `out` (whole rows, one band), the
    /// bits [`Simd::evaluate_grid`] or [`Simd::evaluate_grid_distances`]
    /// writes for them.
    pub(super) fn grid_rows_into<T: GridSample<D, N>>(&self, rows: &GridRows<'_, D>, first: usize, out: &mut [T]) {
        match &rows.axes {
            _ if out.is_empty() => {}
            Some(axes) => self.band(rows.grid, axes, first, out),
            None => T::per_sample(self, rows.grid, first * rows.grid.size[0], out),
        }
    }

    /// [`Simd::grid_rows_into`] for the distances alone (a texture's octaves).
    pub(crate) fn grid_rows_distances(&self, rows: &GridRows<'_, D>, first: usize, out: &mut [[f32; N]]) {
        self.grid_rows_into(rows, first, out)
    }

    /// Rows `first..` of the grid into `out` (whole rows).
    fn band<T: GridSample<D, N>>(&self, grid: &Grid<D>, axes: &Axes<D>, first: usize, out: &mut [T]) {
        let width = grid.size[0];
        let rows = out.len() / width;
        let row_cells = |r: usize| -> [i64; D] {
            let mut rest = first + r;
            std::array::from_fn(|a| {
                if a == 0 {
                    return 0;
                }
                let i = rest % grid.size[a];
                rest /= grid.size[a];
                axes.cell[a][i]
            })
        };
        let (x_lo, x_hi) = min_max(&axes.cell[0]);
        let mut lo = [i64::MAX; D];
        let mut hi = [i64::MIN; D];
        (lo[0], hi[0]) = (x_lo, x_hi);
        for r in 0..rows {
            let c = row_cells(r);
            for a in 1..D {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        let lo = lo.map(|v| v - 1);
        let hi = hi.map(|v| v + 1);
        let cells = (0..D).try_fold(1u128, |n, a| n.checked_mul((hi[a] - lo[a] + 1) as u128));
        if cells.is_none_or(|n| n > 4 * out.len() as u128 + 256) {
            // Rows far apart: generating their cells would cost more than
            // it saves.
            T::per_sample(self, grid, first * grid.size[0], out);
            return;
        }
        // IDs only where the tiles read them: whole results with IDs asked
        // for, distances with IDs, or the other metrics, whose tiles always
        // track them.
        let ids = T::REGION_IDS
            || T::IDS_ONLY
            || (T::FULL && (self.outputs != Outputs::Distances || self.config.metric != Metric::Euclidean));
        let band = Band { grid, axes, first, region: Region::generate(self, lo, hi, ids) };
        match Others::of(self.config.metric) {
            None => self.tiles_euclid(self.outputs, &band, out),
            Some(m) => tiles_others(self, m, &band, out),
        }
    }

    /// The Euclidean tile loops in the widest lanes the CPU runs: sixteen
    /// where the build has AVX-512, or where the CPU has it at run time
    /// ([`avx512`](super::avx512)), when sixteen steps along axis 0 span at
    /// most one cell; otherwise eight, recompiled for AVX2 when this build
    /// lacks it and the CPU has it, as [`Simd::dispatch8`] does for the
    /// per-sample kernel. Every lane runs the same operations, so the bits
    /// are the same whichever is taken.
    #[inline(always)]
    fn tiles_euclid<T: GridSample<D, N>>(&self, o: Outputs, band: &Band<'_, D>, out: &mut [T]) {
        #[cfg(target_feature = "avx512f")]
        if band.axes.sixteen {
            return self.tiles_for::<Sixteen, 16, _, T>(Euclid, o, band, out);
        }
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
        if band.axes.sixteen && super::avx512::tiles(self, o, band, out) {
            return;
        }
        // A build for AVX2 (`-C target-cpu=x86-64-v3`, or native on a CPU
        // without AVX-512) runs sixteen lanes as two AVX2 halves: each
        // candidate's broadcast and loop step serve sixteen samples, and the
        // halves' two dependency chains overlap. Grid F1 1.28x and F2 − F1
        // 1.2x eight lanes (docs/simd.md).
        #[cfg(all(target_feature = "avx2", not(target_feature = "avx512f")))]
        if band.axes.sixteen {
            return self.tiles_for::<Sixteen, 16, _, T>(Euclid, o, band, out);
        }
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        {
            if super::runtime_avx2() {
                // SAFETY: `tiles_avx2` requires AVX2 and nothing else, and
                // `runtime_avx2` has just seen the CPU report it.
                #[allow(unsafe_code)]
                return unsafe { tiles_avx2(self, o, band, out) };
            }
            // A CPU without AVX2 (x86-64 before 2013, or a ceiling of
            // SSE2): the per-sample kernel, the same bits. A copy of the
            // tile loops in SSE2 would cost every default build a tenth of
            // each kernel's code for CPUs that rarely run one.
            T::per_sample(self, band.grid, band.first * band.grid.size[0], out)
        }
        // Out of line, as the other metrics' loops: where sixteen lanes run,
        // this copy would otherwise sit inside theirs.
        #[cfg(not(all(target_arch = "x86_64", not(target_feature = "avx2"))))]
        tiles_eight(self, o, band, out)
    }
}

/// [`Simd::tiles_euclid`]'s eight-lane loops compiled with AVX2 enabled.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
#[target_feature(enable = "avx2")]
fn tiles_avx2<const D: usize, const N: usize, T: GridSample<D, N>>(
    kernel: &Simd<D, N>,
    o: Outputs,
    band: &Band<'_, D>,
    out: &mut [T],
) {
    kernel.tiles_for::<Eight, 8, _, T>(Euclid, o, band, out)
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// The tile loop in lanes `L` (`K` = `L::N`) for the outputs asked for.
    #[inline(always)]
    pub(super) fn tiles_for<L: Lanes, const K: usize, M: Metric32, T: GridSample<D, N>>(
        &self,
        m: M,
        o: Outputs,
        band: &Band<'_, D>,
        out: &mut [T],
    ) {
        // Distances alone compute nothing else, whatever the Simd was built
        // for, and distances with IDs nothing more. A branch on the
        // constants alone, so that an instantiation compiles only the loops
        // it can run.
        if T::IDS_ONLY {
            return self.tiles::<L, K, M, T, true, false>(m, band, out);
        }
        if !T::FULL {
            return self.tiles::<L, K, M, T, false, false>(m, band, out);
        }
        match o {
            Outputs::Distances => self.tiles::<L, K, M, T, false, false>(m, band, out),
            Outputs::Ids => self.tiles::<L, K, M, T, true, false>(m, band, out),
            Outputs::IdsAndDeltas => self.tiles::<L, K, M, T, true, true>(m, band, out),
        }
    }
}

/// The Euclidean tile loops in eight lanes, out of line (where the
/// build has AVX2, or is not for x86-64).
#[cfg(not(all(target_arch = "x86_64", not(target_feature = "avx2"))))]
#[inline(never)]
fn tiles_eight<const D: usize, const N: usize, T: GridSample<D, N>>(
    kernel: &Simd<D, N>,
    o: Outputs,
    band: &Band<'_, D>,
    out: &mut [T],
) {
    kernel.tiles_for::<Eight, 8, Euclid, T>(Euclid, o, band, out)
}

/// The other metrics' tile loops, eight lanes, out of line, one
/// instantiation for the three of them and every output set, as
/// `search_outputs`: whole results track IDs and deltas and write what
/// the outputs ask for ([`Simd::forget_unasked`]), distances alone
/// compute nothing else.
#[inline(never)]
fn tiles_others<const D: usize, const N: usize, T: GridSample<D, N>>(
    kernel: &Simd<D, N>,
    m: Others,
    band: &Band<'_, D>,
    out: &mut [T],
) {
    if T::IDS_ONLY {
        T::per_sample(kernel, band.grid, band.first * band.grid.size[0], out)
    } else if T::FULL {
        kernel.tiles::<Eight, 8, Others, T, true, true>(m, band, out)
    } else {
        kernel.tiles::<Eight, 8, Others, T, false, false>(m, band, out)
    }
}
