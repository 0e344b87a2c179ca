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
//!   inflated twice by [`SLACK_REL`] and [`SLACK_ABS`], far more than the
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

#[cfg(target_feature = "avx512f")]
use super::lanes::Sixteen;
use super::lanes::{Eight, Lanes, One, WIDEST};
use super::{
    distance_of_rank, per_axis, Best, Chebyshev, Euclid, Features32, Grid, Located, Manhattan, Metric32, Minkowski,
    Outputs, PointConstants, Simd, INVALID_ID, UNIT, WHOLE,
};
use crate::config::{Metric, Mode, MAX_ORDER};
use crate::definition::{axis_term, axis_word, feature_id, hash_words, MAX_CELL_COORD};
use std::cell::Cell;

/// Rows of a grid per band on all cores; a band's cells are generated once.
#[cfg(feature = "parallel")]
pub(crate) const BAND: usize = 64;
/// Rows per band of a serial call: twice as many share the band's margin of
/// cells, so fewer cells are generated twice (docs/simd.md has the
/// measurement), where the parallel call keeps more bands for more cores.
pub(crate) const SERIAL_BAND: usize = 128;
/// Asks the CPU to bring the cache lines of `v` in, ready to be written:
/// a tile's outputs, one tile ahead of the tile that writes them (see
/// [`Simd::tiles`]). On targets without the hint, nothing; the tiles then
/// fill each stripe of outputs in order first ([`PREFETCH`]).
#[inline(always)]
fn prefetch_write<T>(v: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_ET0};
        let start = v.as_ptr().cast::<i8>();
        let bytes = std::mem::size_of_val(v);
        // From the line that holds the first byte to the one that holds the
        // last; the pointers are only handed to the hint, never read.
        let first_line = start.wrapping_sub(start as usize % 64);
        let lines = (start as usize % 64 + bytes).div_ceil(64);
        for i in 0..lines {
            // SAFETY: a prefetch is a hint to the cache: it reads nothing
            // into the program and does not fault, whatever the address
            // (Intel SDM, PREFETCHh and PREFETCHW). SSE, which the intrinsic
            // needs, is part of every x86-64 CPU.
            #[allow(unsafe_code)]
            unsafe {
                _mm_prefetch::<_MM_HINT_ET0>(first_line.wrapping_add(64 * i))
            };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}

/// Whether [`prefetch_write`] does anything on this target.
const PREFETCH: bool = cfg!(target_arch = "x86_64");

/// Relative slack of the candidate and certificate tests.
const SLACK_REL: f32 = 1.0 / 256.0;
/// Absolute slack of the same tests, in lane units (2^−24 cells).
const SLACK_ABS: f32 = 16.0;

/// The feature points of a box of cells, generated once, as
/// struct-of-arrays: cell i's points are `start[i]..start[i + 1]`, cells
/// numbered with axis 0 fastest.
pub(super) struct Region<const D: usize> {
    origin: [i64; D],
    side: [usize; D],
    start: Vec<u32>,
    /// Fixed-point coordinates (the 24-bit integers, exact in f32), padded
    /// by [`WIDEST`] so that a group of lanes read from any cell stays in
    /// bounds.
    q: [Vec<f32>; D],
    /// Each point's cell along axis 0, from the region's first (exact:
    /// fewer than 2^24 cells), padded like `q`.
    x_cell: Vec<f32>,
    /// IDs, when the tiles read them (whole results with IDs; empty
    /// otherwise).
    id: Vec<u32>,
}

impl<const D: usize> Region<D> {
    /// The points of the cells `lo ..= hi` (inclusive per axis), with
    /// their IDs if `ids`, in the widest lanes the build has.
    fn generate<const N: usize>(simd: &Simd<D, N>, lo: [i64; D], hi: [i64; D], ids: bool) -> Self {
        #[cfg(target_feature = "avx512f")]
        return Self::generate_in::<Sixteen, N>(simd, lo, hi, ids);
        #[cfg(not(target_feature = "avx512f"))]
        Self::generate_in::<Eight, N>(simd, lo, hi, ids)
    }

    /// [`Region::generate`] in lanes `L`: the cells' hashes and populations
    /// first, then each cell's points `L::N` at a time, point j in lane j
    /// (the jump-ahead constants make point j one multiply-add of the cell's
    /// hash). Every group of lanes is stored whole: the lanes past the
    /// cell's population land where the next cell's points go, or in the
    /// padding, and are overwritten or cleared. Integer arithmetic and an
    /// exact conversion: the same values as one point at a time.
    #[inline(always)]
    fn generate_in<L: Lanes, const N: usize>(simd: &Simd<D, N>, lo: [i64; D], hi: [i64; D], ids: bool) -> Self {
        let side: [usize; D] = std::array::from_fn(|a| (hi[a] - lo[a] + 1) as usize);
        let cells: usize = side.iter().product();
        // The axis words of each row of cells, mixed once per axis value.
        let words: [Vec<u32>; D] =
            std::array::from_fn(|a| (0..side[a]).map(|i| axis_word(a, axis_term(lo[a] + i as i64))).collect());
        let keys = simd.pattern.keys();
        let table = simd.pattern.table();
        let mut start = Vec::with_capacity(cells + 1);
        let mut hashes = Vec::with_capacity(cells);
        let mut c = lo;
        let mut total = 0u32;
        for _ in 0..cells {
            start.push(total);
            let w: [u32; D] = std::array::from_fn(|a| words[a][(c[a] - lo[a]) as usize]);
            let h = hash_words(keys, &w);
            hashes.push(h);
            total += table.population(h);
            next_cell(&mut c, lo, hi);
        }
        start.push(total);
        // The jump-ahead constants by point index, padded to whole groups.
        let groups = simd.points.len().div_ceil(L::N).max(1);
        let constants = |f: &dyn Fn(&PointConstants<D>) -> (u32, u32)| -> [Vec<u32>; 2] {
            let mut m = vec![0; groups * L::N];
            let mut c = vec![0; groups * L::N];
            for (j, p) in simd.points.iter().enumerate() {
                (m[j], c[j]) = f(p);
            }
            [m, c]
        };
        let coordinate: [[Vec<u32>; 2]; D] = std::array::from_fn(|a| constants(&|p| p.coordinate[a]));
        let id_constants = constants(&|p| p.id);
        let len = total as usize + WIDEST;
        let mut q: [Vec<f32>; D] = std::array::from_fn(|_| vec![0.0; len]);
        let mut x_cell = vec![0.0; len];
        let mut id = vec![0; if ids { len } else { 0 }];
        for (i, &h) in hashes.iter().enumerate() {
            let (s, e) = (start[i] as usize, start[i + 1] as usize);
            // Cells are numbered with axis 0 fastest.
            let (hv, x) = (L::u(h), L::f((i % side[0]) as f32));
            let mut j = 0;
            while s + j < e {
                let at = s + j;
                L::f_store(x, &mut x_cell[at..at + L::N]);
                for (qa, [m, c]) in q.iter_mut().zip(&coordinate) {
                    let state = L::u_add(L::u_mul(L::u_load(&m[j..j + L::N]), hv), L::u_load(&c[j..j + L::N]));
                    L::f_store(L::u24_to_f(L::u_shr8(state)), &mut qa[at..at + L::N]);
                }
                if ids {
                    let [m, c] = &id_constants;
                    let state = L::u_add(L::u_mul(L::u_load(&m[j..j + L::N]), hv), L::u_load(&c[j..j + L::N]));
                    let mut lanes = [0u32; WIDEST];
                    L::u_store(state, &mut lanes[..L::N]);
                    for (o, &v) in id[at..at + L::N].iter_mut().zip(&lanes) {
                        *o = feature_id(v);
                    }
                }
                j += L::N;
            }
        }
        // The padding past the last point: zeros, whatever the last group
        // stored there.
        for v in q.iter_mut().chain([&mut x_cell]) {
            v[total as usize..].fill(0.0);
        }
        id.truncate(total as usize);
        Region { origin: lo, side, start, q, x_cell, id }
    }

    /// The index of cell `c`, which must lie in the region.
    #[inline(always)]
    fn cell(&self, c: [i64; D]) -> usize {
        let mut i = 0;
        for a in (0..D).rev() {
            i = i * self.side[a] + (c[a] - self.origin[a]) as usize;
        }
        i
    }
}

/// One tile of samples, `L::N` along axis 0 times `L::N` rows, in the
/// frame of its `reference` cell (the smallest cell of its lanes on every
/// axis). Every row of a grid lies along axis 0, so axis 0 varies with the
/// lane and the other axes only with the row: those are held with row k in
/// lane k.
struct Tile<L: Lanes, const D: usize> {
    /// Axis 0 per lane: the fraction in the lane's own cell (lane units),
    /// and that cell minus the reference, times [`UNIT`] (exact).
    x_f: L::F,
    x_cl: L::F,
    /// The other axes per row, the same two quantities (lane k is row k;
    /// index 0 is unused).
    row_f: [L::F; D],
    row_cl: [L::F; D],
    reference: [i64; D],
    /// The lanes' cells: largest per axis (the smallest is the reference).
    hi: [i64; D],
    /// The bounding box of the lanes in the tile's frame, lane units.
    blo: [f32; D],
    bhi: [f32; D],
}

/// One cell along axis 0 of a tile's searched cells.
#[derive(Clone, Copy, Default)]
struct AxisCell {
    /// Its offset from the start of its row of cells in the region.
    index: usize,
    /// The metric's term of its gap to the tile's box on axis 0.
    term: f32,
    /// Whether it is one of the tile's own cells on axis 0.
    own: bool,
}

/// A row of cells along axis 0 searched by a row of tiles.
struct CellRow<L: Lanes, const D: usize> {
    /// The region's index of the row's first cell.
    base: usize,
    /// The metric's terms of its gaps to the tiles' box on axes 1..,
    /// folded.
    rest: f32,
    /// Whether it holds the tiles' own cells on axes 1...
    own: bool,
    /// Each row of samples' position minus the corner on axes 1.. (lane k
    /// is row k; 0 unused).
    shift: [L::F; D],
}

/// The gap on one axis between the cell whose lower corner is at `frame`
/// and the box `lo ..= hi` (lane units): zero where they overlap.
#[inline(always)]
fn cell_gap(frame: f32, lo: f32, hi: f32) -> f32 {
    (frame - hi).max(lo - (frame + UNIT)).max(0.0)
}

/// The gap on one axis between points at `p` and the box `lo ..= hi`.
#[inline(always)]
fn point_gap<L: Lanes>(p: L::F, lo: L::F, hi: L::F) -> L::F {
    L::max(L::max(L::sub(lo, p), L::sub(p, hi)), L::f(0.0))
}

/// A distance (lane units) grown by the slack.
#[inline(always)]
fn inflate(d: f32) -> f32 {
    d * (1.0 + SLACK_REL) + SLACK_ABS
}

/// A band of grid rows and its cells' points: what every tile of the band
/// reads.
pub(super) struct Band<'a, const D: usize> {
    grid: &'a Grid<D>,
    axes: &'a Axes<D>,
    /// The band's first row.
    first: usize,
    region: Region<D>,
}

/// The grid's coordinates per axis, located once: cell and fraction (lane
/// units) of every index.
struct Axes<const D: usize> {
    cell: [Vec<i64>; D],
    f: [Vec<f32>; D],
    /// Whether sixteen steps along axis 0 span at most one cell, so that
    /// tiles sixteen samples wide stay within two cells.
    sixteen: bool,
}

/// A grid located once, for a caller that combines several grids' results
/// band by band (a texture's octaves, see [`crate::texture::Texture::values_grid`]).
pub(crate) struct GridRows<'g, const D: usize> {
    grid: &'g Grid<D>,
    /// `None` where the grid does not suit the coherent path: its rows then
    /// take the per-sample kernel.
    axes: Option<Axes<D>>,
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Whether [`Simd::evaluate_grid`] takes the coherent path for `grid`:
    /// [`Mode::Exact`], eight steps along axis 0 within one cell
    /// (`8·|step[0]|·S ≤ 1`, S the [scale](crate::Pattern::scale)), rows
    /// spanning fewer than 2^23 cells, and every coordinate valid. The results are the same bits either way; only the
    /// speed differs.
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
            use rayon::prelude::*;
            let band = |(b, dst): (usize, &mut [T])| self.band(grid, &axes, b * BAND, dst);
            out.par_chunks_mut(BAND * width).enumerate().for_each(band);
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

    /// The distances of rows `first..` of the grid into `out` (whole rows),
    /// the bits [`Simd::evaluate_grid_distances`] writes for them.
    pub(crate) fn grid_rows_distances(&self, rows: &GridRows<'_, D>, first: usize, out: &mut [[f32; N]]) {
        match &rows.axes {
            _ if out.is_empty() => {}
            Some(axes) => self.band(rows.grid, axes, first, out),
            None => GridSample::per_sample(self, rows.grid, first * rows.grid.size[0], out),
        }
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
        // IDs only where the tiles read them: whole results with IDs asked for.
        let ids = T::FULL && self.outputs != Outputs::Distances;
        let band = Band { grid, axes, first, region: Region::generate(self, lo, hi, ids) };
        match (self.config.metric, self.outputs) {
            (Metric::Euclidean, o) => self.tiles_euclid(o, &band, out),
            (Metric::Manhattan, o) => self.tiles_outputs(Manhattan, o, &band, out),
            (Metric::Chebyshev, o) => self.tiles_outputs(Chebyshev, o, &band, out),
            (Metric::Minkowski(p), o) => self.tiles_outputs(Minkowski(p), o, &band, out),
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
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if super::runtime_avx2() {
            // SAFETY: `tiles_avx2` requires AVX2 and nothing else, and
            // `runtime_avx2` has just seen the CPU report it.
            #[allow(unsafe_code)]
            return unsafe { self.tiles_avx2(o, band, out) };
        }
        // Out of line, as the other metrics' loops: where sixteen lanes run,
        // this copy would otherwise sit inside theirs.
        self.tiles_outputs(Euclid, o, band, out)
    }

    /// [`Simd::tiles_euclid`]'s eight-lane loops compiled with AVX2 enabled.
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
    #[target_feature(enable = "avx2")]
    fn tiles_avx2<T: GridSample<D, N>>(&self, o: Outputs, band: &Band<'_, D>, out: &mut [T]) {
        self.tiles_for::<Eight, 8, _, T>(Euclid, o, band, out)
    }

    /// The tile loop in lanes `L` (`K` = `L::N`) for the outputs asked for.
    #[inline(always)]
    pub(super) fn tiles_for<L: Lanes, const K: usize, M: Metric32, T: GridSample<D, N>>(
        &self,
        m: M,
        o: Outputs,
        band: &Band<'_, D>,
        out: &mut [T],
    ) {
        // Distances alone compute nothing else, whatever the Simd was built for.
        match if T::FULL { o } else { Outputs::Distances } {
            Outputs::Distances => self.tiles::<L, K, M, T, false, false>(m, band, out),
            Outputs::Ids => self.tiles::<L, K, M, T, true, false>(m, band, out),
            Outputs::IdsAndDeltas => self.tiles::<L, K, M, T, true, true>(m, band, out),
        }
    }

    /// The other metrics' tile loops, eight lanes, out of line (as
    /// `search_outputs`).
    #[inline(never)]
    fn tiles_outputs<M: Metric32, T: GridSample<D, N>>(&self, m: M, o: Outputs, band: &Band<'_, D>, out: &mut [T]) {
        self.tiles_for::<Eight, 8, M, T>(m, o, band, out)
    }

    /// Every tile of a band, `K` = `L::N` samples along axis 0 by `K` rows.
    #[inline(always)]
    fn tiles<L: Lanes, const K: usize, M: Metric32, T: GridSample<D, N>, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        band: &Band<'_, D>,
        out: &mut [T],
    ) {
        debug_assert_eq!(K, L::N);
        let Band { grid, axes, first, ref region } = *band;
        let width = grid.size[0];
        let rows = out.len() / width;
        // Axis 0 as lanes: each sample's cell relative to the band's first
        // cell, times UNIT (exact), and its fraction; padded with the last
        // sample so that a vector can be read from any x.
        let base = region.origin[0];
        let pad = |v: &mut Vec<f32>| v.resize(width + WIDEST, v[width - 1]);
        let mut x_cell: Vec<f32> = axes.cell[0].iter().map(|&c| (c - base) as f32 * UNIT).collect();
        let mut x_f = axes.f[0].clone();
        pad(&mut x_cell);
        pad(&mut x_f);
        let row_at = |r: usize| -> ([i64; D], [f32; D]) {
            let mut rest = first + r;
            let mut c = [0i64; D];
            let mut f = [0f32; D];
            for a in 1..D {
                let i = rest % grid.size[a];
                rest /= grid.size[a];
                c[a] = axes.cell[a][i];
                f[a] = axes.f[a][i];
            }
            (c, f)
        };
        let mut cell_rows = Vec::with_capacity(64);
        let mut near = vec![0f32; region.x_cell.len()];
        for r0 in (0..rows).step_by(K) {
            let rows_here = (rows - r0).min(K);
            // A tile's stores reach `K` rows a whole row apart, which the
            // hardware prefetchers do not follow, and where the output is out
            // of cache (a renderer's call between other work) each one would
            // wait for its line. So every tile asks for the next tile's lines
            // while it computes (docs/simd.md, "The next tile's outputs asked
            // for"); where the target has no such hint, the rows' outputs are
            // written once in order first, so that their lines come in as a
            // stream.
            if !PREFETCH {
                let stripe = &mut out[r0 * width..(r0 + rows_here) * width];
                let any = stripe[0];
                stripe.fill(any);
            }
            let rk: [([i64; D], [f32; D]); K] = std::array::from_fn(|k| row_at(r0 + k.min(rows_here - 1)));
            // The rows' part of every tile: reference cell, span and box on
            // the axes other than 0.
            let mut reference = [0i64; D];
            let mut hi = [0i64; D];
            let mut blo = [0f32; D];
            let mut bhi = [0f32; D];
            let mut far_apart = false;
            for a in 1..D {
                reference[a] = rk.iter().map(|r| r.0[a]).min().unwrap_or(0);
                hi[a] = rk.iter().map(|r| r.0[a]).max().unwrap_or(0);
                far_apart |= hi[a] - reference[a] > 1;
                let pos = |r: &([i64; D], [f32; D])| (r.0[a] - reference[a]) as f32 * UNIT + r.1[a];
                blo[a] = rk.iter().map(pos).fold(f32::INFINITY, f32::min);
                bhi[a] = rk.iter().map(pos).fold(f32::NEG_INFINITY, f32::max);
            }
            // Axes 1.. per row, row k in lane k: fraction, and cell minus the
            // reference times UNIT (axis 0's entries are zero, unused).
            let (mut row_f, mut row_cl) = ([[0f32; WIDEST]; D], [[0f32; WIDEST]; D]);
            for (k, (c, f)) in rk.iter().enumerate() {
                for a in 1..D {
                    row_f[a][k] = f[a];
                    row_cl[a][k] = (c[a] - reference[a]) as f32 * UNIT;
                }
            }
            let mut tile = Tile::<L, D> {
                x_f: L::f(0.0),
                x_cl: L::f(0.0),
                row_f: per_axis(|a| lanes_from::<L>(&row_f[a])),
                row_cl: per_axis(|a| lanes_from::<L>(&row_cl[a])),
                reference,
                hi,
                blo,
                bhi,
            };
            if !far_apart {
                self.cell_rows(metric, region, &tile, &mut cell_rows, &mut near);
            }
            let mut best: [Best<L, D, N>; K] = per_axis(|_| Best::empty());
            for x0 in (0..width).step_by(K) {
                let cols_here = (width - x0).min(K);
                let (first_x, last_x) = (x0, x0 + cols_here - 1);
                let (c0, c1) = (axes.cell[0][first_x], axes.cell[0][last_x]);
                tile.reference[0] = c0.min(c1);
                tile.hi[0] = c0.max(c1);
                if far_apart || tile.hi[0] - tile.reference[0] > 1 {
                    // Samples more than two cells apart: the per-sample kernel.
                    for k in 0..rows_here {
                        let o = (r0 + k) * width + x0;
                        T::per_sample(self, grid, (first + r0 + k) * width + x0, &mut out[o..o + cols_here]);
                    }
                    continue;
                }
                // Cells along axis 0 are monotone in x: the box's ends are
                // the first and last samples.
                let shift = (tile.reference[0] - base) as f32 * UNIT;
                let (p0, p1) = (x_cell[first_x] - shift + x_f[first_x], x_cell[last_x] - shift + x_f[last_x]);
                tile.blo[0] = p0.min(p1);
                tile.bhi[0] = p0.max(p1);
                tile.x_f = load::<L>(&x_f, x0);
                tile.x_cl = L::sub(load::<L>(&x_cell, x0), L::f(shift));
                if PREFETCH {
                    // The next tile's outputs: the next along this stripe, or
                    // the next stripe's first.
                    let (next_row, next_x) = if x0 + K < width { (r0, x0 + K) } else { (r0 + K, 0) };
                    let next_cols = (width - next_x).min(K);
                    for k in next_row..(next_row + K).min(rows) {
                        let o = k * width + next_x;
                        prefetch_write(&out[o..o + next_cols]);
                    }
                }
                self.tile::<L, K, M, IDS, DELTAS>(metric, region, &tile, (&cell_rows, &near), !T::FULL, &mut best);
                for (k, b) in best.iter_mut().enumerate().take(rows_here) {
                    self.finish::<L, DELTAS>(b);
                    let o = (r0 + k) * width + x0;
                    T::write::<L, IDS, DELTAS>(b, &mut out[o..o + cols_here]);
                }
            }
        }
    }

    /// The rows of cells along axis 0 that a row of tiles searches (its
    /// own cells and one more on every side, on every axis but 0), and for
    /// every point in them, the fold of its gap terms to the tiles' box on
    /// those axes, into `near` at the point's index.
    #[inline(always)]
    fn cell_rows<L: Lanes, M: Metric32>(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<L, D>,
        rows: &mut Vec<CellRow<L, D>>,
        near: &mut [f32],
    ) {
        rows.clear();
        let lo: [i64; D] = std::array::from_fn(|a| if a == 0 { region.origin[0] } else { t.reference[a] - 1 });
        let hi: [i64; D] = std::array::from_fn(|a| if a == 0 { region.origin[0] } else { t.hi[a] + 1 });
        let (blo, bhi): ([L::F; D], [L::F; D]) = (per_axis(|a| L::f(t.blo[a])), per_axis(|a| L::f(t.bhi[a])));
        let mut c = lo;
        loop {
            let frame: [f32; D] =
                std::array::from_fn(|a| if a == 0 { 0.0 } else { (c[a] - t.reference[a]) as f32 * UNIT });
            let terms: [f32; D] = std::array::from_fn(|a| metric.term::<One>(cell_gap(frame[a], t.blo[a], t.bhi[a])));
            let mut shift = [L::f(0.0); D];
            for a in 1..D {
                shift[a] = L::sub(t.row_f[a], L::sub(L::f(frame[a]), t.row_cl[a]));
            }
            let row = CellRow {
                base: region.cell(c),
                // Folded as in `Metric32::rank`: axes 1, 2, …, then 0.
                rest: terms[1..].iter().copied().reduce(|r, v| metric.fold::<One>(r, v)).unwrap_or(0.0),
                own: (1..D).all(|a| c[a] != lo[a] && c[a] != hi[a]),
                shift,
            };
            let (s, e) = (region.start[row.base] as usize, region.start[row.base + region.side[0]] as usize);
            for g in (s..e).step_by(L::N) {
                let mut gap = [L::f(0.0); D];
                for a in 1..D {
                    gap[a] = point_gap::<L>(L::add(L::f(frame[a]), load::<L>(&region.q[a], g)), blo[a], bhi[a]);
                }
                let rest = if D > 1 { metric.rest::<L, D>(&gap) } else { L::f(0.0) };
                // A whole vector (`near` is padded like the points): the
                // lanes past the row's last point land on points of rows
                // later in the region, which are written when their row is
                // reached, or never read (the scan masks them off).
                L::f_store(rest, &mut near[g..g + L::N]);
            }
            rows.push(row);
            if !next_cell(&mut c, lo, hi) {
                break;
            }
        }
    }

    /// One tile: the points of its own cells, the bound they give, the
    /// other candidates, the certificate, and the per-sample kernel for
    /// lanes left uncertified. Ranks in lane units. `rows` and `near` are
    /// the tile row's, from [`Simd::cell_rows`]. `local`: the caller
    /// writes the distances alone, so that the search may run on a local
    /// copy of the ranks.
    #[inline(always)]
    fn tile<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<L, D>,
        (rows, near): (&[CellRow<L, D>], &[f32]),
        local: bool,
        best: &mut [Best<L, D, N>; K],
    ) {
        // Sixteen lanes run only with AVX-512 and its 32 vector registers;
        // eight may run with AVX2 and its 16.
        let fits = N <= if K >= 16 { 2 } else { 1 };
        let open = if local && !IDS && !DELTAS && fits {
            // The ranks in a local array that never leaves this function,
            // so that they stay in registers through the candidates, at
            // most half the register file. Measured only where it pays:
            // 1.06-1.21x on the distances alone, 0.88x on F4 in sixteen
            // lanes (64 vectors), and 0.9x on whole results, whose writing
            // keeps them in memory.
            let mut ranks: [Best<L, D, N>; K] = per_axis(|_| Best::empty());
            let open = self.tile_search::<L, K, M, IDS, DELTAS>(metric, region, t, (rows, near), &mut ranks);
            for (b, l) in best.iter_mut().zip(&ranks) {
                b.rank = l.rank;
            }
            open
        } else {
            for b in best.iter_mut() {
                b.reset::<IDS, DELTAS>();
            }
            self.tile_search::<L, K, M, IDS, DELTAS>(metric, region, t, (rows, near), best)
        };
        if let Some(certified) = open {
            self.tile_per_sample::<L, K, M, IDS, DELTAS>(metric, t, best, certified)
        }
    }

    /// [`Simd::tile`]'s search into `best` (which must start empty): the
    /// lanes certified per row, or `None` if every lane is.
    #[inline(always)]
    fn tile_search<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<L, D>,
        (rows, near): (&[CellRow<L, D>], &[f32]),
        best: &mut [Best<L, D, N>; K],
    ) -> Option<[u32; K]> {
        let (blo, bhi) = (L::f(t.blo[0]), L::f(t.bhi[0]));
        // The searched cells (the tile's own and one more on each side).
        let lo: [i64; D] = std::array::from_fn(|a| t.reference[a] - 1);
        let hi: [i64; D] = std::array::from_fn(|a| t.hi[a] + 1);
        // Along axis 0: offset of the cell's index in its row, the metric's
        // term of the gap between the cell and the tile's box, and whether
        // it is the tile's own.
        let mut x_cells = [AxisCell::default(); 4];
        let count = (hi[0] - lo[0] + 1) as usize;
        for (xc, c) in x_cells.iter_mut().zip(lo[0]..=hi[0]) {
            *xc = AxisCell {
                index: (c - region.origin[0]) as usize,
                term: metric.term::<One>(cell_gap((c - t.reference[0]) as f32 * UNIT, t.blo[0], t.bhi[0])),
                own: c != lo[0] && c != hi[0],
            };
        }
        let x_cells = &x_cells[..count];
        // Each lane's position on axis 0 minus the corner of the cell
        // `cell` cells from the region's first (exact small integers).
        let reference = (t.reference[0] - region.origin[0]) as f32;
        let shift = |cell: f32| L::sub(t.x_f, L::sub(L::f((cell - reference) * UNIT), t.x_cl));

        let spill = Spill::default();
        // With 1 in every lane, from a value the compiler cannot see: the
        // rows' additions of a candidate's rank go to the multiply-add
        // units (`Lanes::broadcast_add_on_fma`), beside the minimums that
        // follow them.
        let spill = (&spill, std::hint::black_box(&spill), L::f(std::hint::black_box(1.0)));

        // The tile's own cells: every point is a candidate.
        for row in rows.iter().filter(|r| r.own) {
            for xc in x_cells.iter().filter(|xc| xc.own) {
                let (i, x_shift) = (row.base + xc.index, shift(xc.index as f32));
                // The cell's points as slices of one length, so that reading
                // point j checks no bounds.
                let (s, e) = (region.start[i] as usize, region.start[i + 1] as usize);
                let q: [&[f32]; D] = per_axis(|a| &region.q[a][s..e]);
                let id = if IDS { &region.id[s..e] } else { &[][..] };
                for j in 0..e - s {
                    let point = (per_axis(|a| q[a][j]), if IDS { id[j] } else { 0 });
                    self.candidate::<L, K, M, IDS, DELTAS>(metric, point, (x_shift, &row.shift), spill, best);
                }
            }
        }

        // The bound: the largest F_n of any lane so far (of the cells
        // around when the own cells hold fewer than n points).
        let mut bound = largest::<L, K>(std::array::from_fn(|k| best[k].rank[N - 1]));
        if bound == f32::INFINITY {
            bound = self.bound(metric, region, t, lo, hi);
            if bound == f32::INFINITY {
                return Some([0; K]);
            }
        }
        let once = inflate(distance_of_rank::<One>(self.config.metric, bound));
        let certify = metric.rank_of_distance::<One>(once);
        let prune = metric.rank_of_distance::<One>(inflate(once));
        let prune_lanes = L::f(prune);

        // The other cells: a cell farther than the pruning bound from the
        // tile's box is skipped, and so is a point. The cells of a row that
        // remain are consecutive in the region, so their points are read as
        // one run; each point's cell along axis 0 comes with it.
        let (own_lo, own_hi) = (L::f(0.0), L::f((t.hi[0] - t.reference[0]) as f32));
        for row in rows.iter().filter(|r| r.rest <= prune) {
            let first = usize::from(metric.fold::<One>(row.rest, x_cells[0].term) > prune);
            let last = count - 1 - usize::from(metric.fold::<One>(row.rest, x_cells[count - 1].term) > prune);
            let (s, e) = (
                region.start[row.base + x_cells[first].index] as usize,
                region.start[row.base + x_cells[last].index + 1] as usize,
            );
            let mut g = s;
            while g < e {
                let cell = L::sub(load::<L>(&region.x_cell, g), L::f(reference));
                let p = L::add(L::mul(cell, L::f(UNIT)), load::<L>(&region.q[0], g));
                let rank = metric.fold::<L>(load::<L>(near, g), metric.term::<L>(point_gap::<L>(p, blo, bhi)));
                let mut keep = L::le(rank, prune_lanes);
                if row.own {
                    // The own cells' points are in already.
                    keep = L::and(keep, L::or(L::lt(cell, own_lo), L::lt(own_hi, cell)));
                }
                let n = (e - g).min(L::N);
                let mut bits = L::bits(keep) & (u32::MAX >> (32 - n));
                while bits != 0 {
                    let p = g + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let point = (per_axis(|a| region.q[a][p]), if IDS { region.id[p] } else { 0 });
                    self.candidate::<L, K, M, IDS, DELTAS>(
                        metric,
                        point,
                        (shift(region.x_cell[p]), &row.shift),
                        spill,
                        best,
                    );
                }
                g += L::N;
            }
        }

        // The certificate, per lane: the distance to the outside of the
        // searched cells is a minimum over axes, so axis 0's part per lane
        // and the others' per row.
        let outside = |f: L::F, cl: L::F, a: usize| {
            let p = L::add(cl, f);
            let (low, high) = ((lo[a] - t.reference[a]) as f32 * UNIT, (hi[a] + 1 - t.reference[a]) as f32 * UNIT);
            L::min(L::sub(p, L::f(low)), L::sub(L::f(high), p))
        };
        let x_edge = outside(t.x_f, t.x_cl, 0);
        let mut row_edge = L::f(f32::INFINITY);
        for a in 1..D {
            row_edge = L::min(row_edge, outside(t.row_f[a], t.row_cl[a], a));
        }
        let row_edge = lanes_of::<L>(row_edge);
        let certify_lanes = L::f(certify);
        let all = u32::MAX >> (32 - L::N);
        let mut certified = [0u32; K];
        for k in 0..K {
            let edge = L::min(x_edge, L::f(row_edge[k]));
            let edge = L::max(L::sub(L::mul(edge, L::f(1.0 - SLACK_REL)), L::f(SLACK_ABS)), L::f(0.0));
            let last = best[k].rank[N - 1];
            let ok = L::and(L::le(last, certify_lanes), L::lt(last, metric.rank_of_distance::<L>(edge)));
            certified[k] = L::bits(ok);
        }
        if certified.iter().all(|&m| m == all) {
            return None;
        }
        Some(certified)
    }

    /// The n-th smallest farthest distance (as a rank) from the tile's box
    /// to the points of the cells `lo ..= hi`; +∞ if they hold fewer.
    #[inline(always)]
    fn bound<L: Lanes, M: Metric32>(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<L, D>,
        lo: [i64; D],
        hi: [i64; D],
    ) -> f32 {
        let (blo, bhi): ([L::F; D], [L::F; D]) = (per_axis(|a| L::f(t.blo[a])), per_axis(|a| L::f(t.bhi[a])));
        let index: [f32; WIDEST] = std::array::from_fn(|j| j as f32);
        let index = lanes_from::<L>(&index);
        // The n smallest per lane, sorted, by a min/max network.
        let mut least = [L::f(f32::INFINITY); N];
        let mut c = lo;
        loop {
            let i = region.cell(c);
            let (s, e) = (region.start[i] as usize, region.start[i + 1] as usize);
            for g in (s..e).step_by(L::N) {
                let far: [L::F; D] = per_axis(|a| {
                    let p = L::add(L::f((c[a] - t.reference[a]) as f32 * UNIT), load::<L>(&region.q[a], g));
                    L::max(L::sub(p, blo[a]), L::sub(bhi[a], p))
                });
                // Lanes past the cell's last point count as +∞.
                let mut v = metric.rank::<L, D>(&far);
                v = L::select(L::lt(index, L::f((e - g) as f32)), v, L::f(f32::INFINITY));
                for l in least.iter_mut() {
                    let (a, b) = (L::min(*l, v), L::max(*l, v));
                    *l = a;
                    v = b;
                }
            }
            if !next_cell(&mut c, lo, hi) {
                break;
            }
        }
        if N == 1 {
            return lanes_of::<L>(least[0])[..L::N].iter().fold(f32::INFINITY, |m, &v| m.min(v));
        }
        let mut all = [f32::INFINITY; MAX_ORDER * WIDEST];
        for (k, l) in least.iter().enumerate() {
            all[L::N * k..L::N * (k + 1)].copy_from_slice(&lanes_of::<L>(*l)[..L::N]);
        }
        let all = &mut all[..L::N * N];
        all.sort_unstable_by(f32::total_cmp);
        all[N - 1]
    }

    /// One candidate point of the region, its coordinates `q` (the 24-bit
    /// integers) and its ID, against every lane of a tile: `x_shift` is
    /// each lane's position minus the point's cell corner on axis 0,
    /// `row_shift` each row's on the other axes. Its delta is
    /// `shift − q` on every axis, so a row shares the rest of the rank
    /// ([`Metric32::rest`]) and only axis 0's term is per lane; the rest
    /// is written through the first reference of `spill` and read through
    /// the second (see [`Spill`]); the third is 1 in every lane.
    #[inline(always)]
    fn candidate<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        (q, id): ([f32; D], u32),
        (x_shift, row_shift): (L::F, &[L::F; D]),
        (spill, spilled, one): (&Spill, &Spill, L::F),
        best: &mut [Best<L, D, N>; K],
    ) {
        let dx = L::sub(x_shift, L::f(q[0]));
        let id = L::u(id);
        let d_row: [L::F; D] = per_axis(|a| if a == 0 { L::f(0.0) } else { L::sub(row_shift[a], L::f(q[a])) });
        let d_row_lanes: [[f32; WIDEST]; D] =
            if DELTAS || !M::SPLITS { per_axis(|a| lanes_of::<L>(d_row[a])) } else { [[0.0; WIDEST]; D] };
        let delta = |k: usize| -> [L::F; D] { per_axis(|a| if a == 0 { dx } else { L::f(d_row_lanes[a][k]) }) };
        if M::SPLITS && D > 1 {
            let first = metric.term::<L>(dx);
            for (cell, v) in spill.0.iter().zip(lanes_of::<L>(metric.rest::<L, D>(&d_row))) {
                cell.set(v);
            }
            for (k, b) in best.iter_mut().enumerate() {
                let rank = metric.fold_on_fma::<L>((&spilled.0, k), first, one);
                if skip::<L, D, N, IDS, DELTAS>(rank, b) {
                    continue;
                }
                let delta = if DELTAS { delta(k) } else { [L::f(0.0); D] };
                b.insert::<IDS, DELTAS>(rank, delta, id);
            }
        } else {
            for (k, b) in best.iter_mut().enumerate() {
                let delta = delta(k);
                let rank = metric.rank::<L, D>(&delta);
                if skip::<L, D, N, IDS, DELTAS>(rank, b) {
                    continue;
                }
                b.insert::<IDS, DELTAS>(rank, delta, id);
            }
        }
    }

    /// The lanes of a tile not set in `certified`, by the per-sample kernel.
    #[cold]
    #[inline(never)]
    fn tile_per_sample<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        t: &Tile<L, D>,
        best: &mut [Best<L, D, N>; K],
        certified: [u32; K],
    ) {
        let (x_f, x_cl) = (lanes_of::<L>(t.x_f), lanes_of::<L>(t.x_cl));
        let row_f: [[f32; WIDEST]; D] = per_axis(|a| lanes_of::<L>(t.row_f[a]));
        let row_cl: [[f32; WIDEST]; D] = per_axis(|a| lanes_of::<L>(t.row_cl[a]));
        for (k, b) in best.iter_mut().enumerate() {
            let mut rank: [[f32; WIDEST]; N] = per_axis(|j| lanes_of::<L>(b.rank[j]));
            let mut id = [[0u32; WIDEST]; N];
            for (j, lanes) in id.iter_mut().enumerate() {
                L::u_store(b.id[j], &mut lanes[..L::N]);
            }
            let mut delta: [[[f32; WIDEST]; D]; N] = per_axis(|j| per_axis(|a| lanes_of::<L>(b.delta[j][a])));
            for i in (0..L::N).filter(|i| certified[k] & (1 << i) == 0) {
                let (f, cl) = (
                    |a: usize| if a == 0 { x_f[i] } else { row_f[a][k] },
                    |a: usize| {
                        if a == 0 {
                            x_cl[i]
                        } else {
                            row_cl[a][k]
                        }
                    },
                );
                let cell: [[i64; WIDEST]; D] =
                    std::array::from_fn(|a| [t.reference[a] + (cl(a) / UNIT) as i64; WIDEST]);
                let fr: [[f32; WIDEST]; D] = std::array::from_fn(|a| [f(a); WIDEST]);
                let at = Located::<One, D>::lanewise(cell, &fr, [true; WIDEST]);
                let one = self.search::<One, M, IDS, DELTAS, WHOLE>(metric, &at, Best::empty()).0;
                for j in 0..N {
                    rank[j][i] = one.rank[j];
                    id[j][i] = one.id[j];
                    for (lanes, v) in delta[j].iter_mut().zip(one.delta[j]) {
                        lanes[i] = v;
                    }
                }
            }
            b.rank = per_axis(|j| lanes_from::<L>(&rank[j]));
            b.id = per_axis(|j| L::u_load(&id[j][..L::N]));
            b.delta = per_axis(|j| per_axis(|a| lanes_from::<L>(&delta[j][a])));
        }
    }
}

/// Where a candidate's rests of the rank per row of samples wait for the
/// rows to read them: in memory, read one at a time. Held in a register
/// instead, each row's value is moved across lanes by a shuffle, sixteen per
/// candidate in AVX-512 lanes, and these took a third of the insertions'
/// time; read from memory, the load that feeds the addition broadcasts it
/// (in AVX-512 lanes inside the multiply-add itself,
/// [`Lanes::broadcast_add_on_fma`]). A tile writes through one reference
/// and reads through another that the compiler cannot see to be the same
/// ([`std::hint::black_box`], once per tile), so that it keeps the loads:
/// 1.1x on the 3D F1 grid (docs/simd.md).
#[derive(Default)]
struct Spill([Cell<f32>; WIDEST]);

/// The largest value in any lane of `v`, by halving trees (a short chain
/// of dependent operations: the tile's scan waits for it).
#[inline(always)]
fn largest<L: Lanes, const K: usize>(mut v: [L::F; K]) -> f32 {
    debug_assert!(K.is_power_of_two() && L::N.is_power_of_two());
    let mut width = K;
    while width > 1 {
        width /= 2;
        for k in 0..width {
            v[k] = L::max(v[k], v[k + width]);
        }
    }
    let mut a = lanes_of::<L>(v[0]);
    let mut width = L::N;
    while width > 1 {
        width /= 2;
        for i in 0..width {
            a[i] = a[i].max(a[i + width]);
        }
    }
    a[0]
}

/// `L::N` values from `v[at..]` (the region's padding keeps it in bounds).
#[inline(always)]
fn load<L: Lanes>(v: &[f32], at: usize) -> L::F {
    L::f_load(&v[at..at + L::N])
}

/// Lanes into an array, of which the first `L::N` are set.
#[inline(always)]
fn lanes_of<L: Lanes>(v: L::F) -> [f32; WIDEST] {
    let mut a = [0.0; WIDEST];
    L::f_store(v, &mut a[..L::N]);
    a
}

/// Lanes from the first `L::N` of an array.
#[inline(always)]
fn lanes_from<L: Lanes>(a: &[f32; WIDEST]) -> L::F {
    L::f_load(&a[..L::N])
}

/// Steps `c` to the next cell of the box `lo ..= hi` (axis 0 fastest);
/// false when `c` was the last. A loop over it, rather than a closure
/// called per cell, keeps the body inline in the run-time AVX-512 copy.
#[inline(always)]
fn next_cell<const D: usize>(c: &mut [i64; D], lo: [i64; D], hi: [i64; D]) -> bool {
    for a in 0..D {
        c[a] += 1;
        if c[a] <= hi[a] {
            return true;
        }
        c[a] = lo[a];
    }
    false
}

fn min_max(v: &[i64]) -> (i64, i64) {
    v.iter().fold((i64::MAX, i64::MIN), |(lo, hi), &c| (lo.min(c), hi.max(c)))
}

/// What the coherent grid path writes per sample: whole results
/// ([`Features32`], the outputs the [`Simd`] was built for) or the distances
/// alone (`[f32; N]`, see [`Simd::evaluate_grid_distances`]). `Copy`, since a
/// stripe of outputs is filled before its tiles write it.
pub(super) trait GridSample<const D: usize, const N: usize>: Sized + Send + Copy {
    /// Whether the tiles compute the outputs the [`Simd`] was built for;
    /// false: distances only, whatever it was built for (the distances are
    /// the same bits either way).
    const FULL: bool;
    /// Up to [`Lanes::N`] lanes of a finished result into `dst`.
    fn write<L: Lanes, const IDS: bool, const DELTAS: bool>(b: &Best<L, D, N>, dst: &mut [Self]);
    /// Grid points `first..first + dst.len()` by the per-sample kernel.
    fn per_sample(simd: &Simd<D, N>, grid: &Grid<D>, first: usize, dst: &mut [Self]);
}

impl<const D: usize, const N: usize> GridSample<D, N> for Features32<D, N> {
    const FULL: bool = true;
    #[inline(always)]
    fn write<L: Lanes, const IDS: bool, const DELTAS: bool>(b: &Best<L, D, N>, dst: &mut [Self]) {
        write_lanes::<L, D, N, IDS, DELTAS>(b, dst)
    }
    fn per_sample(simd: &Simd<D, N>, grid: &Grid<D>, first: usize, dst: &mut [Self]) {
        simd.grid_range(grid, first, dst)
    }
}

impl<const D: usize, const N: usize> GridSample<D, N> for [f32; N] {
    const FULL: bool = false;
    #[inline(always)]
    fn write<L: Lanes, const IDS: bool, const DELTAS: bool>(b: &Best<L, D, N>, dst: &mut [Self]) {
        if N == 1 && dst.len() == L::N {
            // One store of the lanes, the common case of a full tile row.
            return L::f_store(b.rank[0], dst.as_flattened_mut());
        }
        let mut distance = [[0.0; WIDEST]; N];
        for (k, lanes) in distance.iter_mut().enumerate() {
            L::f_store(b.rank[k], &mut lanes[..L::N]);
        }
        for (i, o) in dst.iter_mut().enumerate() {
            *o = std::array::from_fn(|k| distance[k][i]);
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

/// Whether inserting a candidate of rank `rank` into `b` would change no
/// lane, tested only where the insertion carries IDs or deltas: a lane
/// takes it only if its rank is at most the lane's F_n (equal ranks are
/// ordered by ID), and a NaN on either side fails both tests. The
/// distances alone insert by a minimum and a maximum, cheaper than the
/// branch.
#[inline(always)]
fn skip<L: Lanes, const D: usize, const N: usize, const IDS: bool, const DELTAS: bool>(
    rank: L::F,
    b: &Best<L, D, N>,
) -> bool {
    (IDS || DELTAS) && L::bits(L::le(rank, b.rank[N - 1])) == 0
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
