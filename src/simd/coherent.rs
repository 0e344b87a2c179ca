//! # The coherent path: samples close together share their cells' points
//!
//! A grid's neighbouring samples need the same few cells. Instead of
//! hashing and generating those cells again for every sample, this path
//! generates every cell of a band of the grid once ([`Region`]: the points as
//! struct-of-arrays, each with its cell along axis 0, and IDs when asked
//! for), then evaluates *tiles* of 8 × [`K`] samples (eight along axis 0 in
//! each vector, `K` rows) against the points that can matter to the tile,
//! each point broadcast to every lane.
//!
//! ## Why it is cheap
//! - A grid's row lies along axis 0, so a sample's position on the other
//!   axes is its row's. The rank folds axis 0's term in last
//!   ([`Metric32::rank`]), so for each candidate the rest of the rank is
//!   computed once per row (the eight rows in the lanes of one vector) and
//!   each vector of eight samples adds one term.
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

use wide::{f32x8, u32x8};

use super::lanes::{Eight, Lanes, One, WIDEST};
use super::{
    distance_of_rank, Best, Chebyshev, Euclid, Features32, Grid, Located, Manhattan, Metric32, Minkowski, Outputs,
    Simd, INVALID_ID, UNIT, WHOLE,
};
use crate::config::{Metric, Mode};
use crate::definition::{axis_term, axis_word, feature_id, hash_words, MAX_CELL_COORD};

/// Vectors per tile: a tile is 8 samples along axis 0 times `K` rows; the
/// rows' values are held one per lane, so `K` is the lane count.
pub(super) const K: usize = 8;
/// Rows of a grid per band; a band's cells are generated once.
const BAND: usize = 64;
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
    /// by eight so that a group of eight read from any cell stays in bounds.
    q: [Vec<f32>; D],
    /// Each point's cell along axis 0, from the region's first (exact:
    /// fewer than 2^24 cells), padded like `q`.
    x_cell: Vec<f32>,
    /// IDs, when the outputs ask for them (empty otherwise).
    id: Vec<u32>,
}

impl<const D: usize> Region<D> {
    /// The points of the cells `lo ..= hi` (inclusive per axis).
    fn generate<const N: usize>(simd: &Simd<D, N>, lo: [i64; D], hi: [i64; D]) -> Self {
        let side: [usize; D] = std::array::from_fn(|a| (hi[a] - lo[a] + 1) as usize);
        let cells: usize = side.iter().product();
        // The axis words of each row of cells, mixed once per axis value.
        let words: [Vec<u32>; D] =
            std::array::from_fn(|a| (0..side[a]).map(|i| axis_word(a, axis_term(lo[a] + i as i64))).collect());
        let keys = simd.pattern.keys();
        let table = simd.pattern.table();
        let ids = simd.outputs != Outputs::Distances;
        let guess = cells * (table.mean().ceil() as usize + 1) + 8;
        let mut start = Vec::with_capacity(cells + 1);
        let mut q: [Vec<f32>; D] = std::array::from_fn(|_| Vec::with_capacity(guess));
        let mut x_cell = Vec::with_capacity(guess);
        let mut id = Vec::with_capacity(if ids { guess } else { 0 });
        let mut index = [0usize; D];
        for _ in 0..cells {
            start.push(x_cell.len() as u32);
            let w: [u32; D] = std::array::from_fn(|a| words[a][index[a]]);
            let h = hash_words(keys, &w);
            for p in &simd.points[..table.population(h) as usize] {
                if ids {
                    id.push(feature_id(p.id.0.wrapping_mul(h).wrapping_add(p.id.1)));
                }
                x_cell.push(index[0] as f32);
                for (qa, (m, c)) in q.iter_mut().zip(p.coordinate) {
                    qa.push((m.wrapping_mul(h).wrapping_add(c) >> 8) as f32);
                }
            }
            for a in 0..D {
                index[a] += 1;
                if index[a] < side[a] {
                    break;
                }
                index[a] = 0;
            }
        }
        start.push(x_cell.len() as u32);
        for v in q.iter_mut().chain([&mut x_cell]) {
            v.resize(v.len() + 8, 0.0);
        }
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

/// One tile of samples, 8 × [`K`] lanes, in the frame of its `reference`
/// cell (the smallest cell of its lanes on every axis). Every row of a grid
/// lies along axis 0, so axis 0 varies with the lane and the other axes
/// only with the row: those are held with row k in lane k.
struct Tile<const D: usize> {
    /// Axis 0 per lane: the fraction in the lane's own cell (lane units),
    /// and that cell minus the reference, times [`UNIT`] (exact).
    x_f: f32x8,
    x_cl: f32x8,
    /// The other axes per row, the same two quantities (lane k is row k;
    /// index 0 is unused).
    row_f: [f32x8; D],
    row_cl: [f32x8; D],
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
struct CellRow<const D: usize> {
    /// The region's index of the row's first cell.
    base: usize,
    /// The metric's terms of its gaps to the tiles' box on axes 1..,
    /// folded.
    rest: f32,
    /// Whether it holds the tiles' own cells on axes 1...
    own: bool,
    /// Each row of samples' position minus the corner on axes 1.. (lane k
    /// is row k; 0 unused).
    shift: [f32x8; D],
}

/// The gap on one axis between the cell whose lower corner is at `frame`
/// and the box `lo ..= hi` (lane units): zero where they overlap.
#[inline(always)]
fn cell_gap(frame: f32, lo: f32, hi: f32) -> f32 {
    (frame - hi).max(lo - (frame + UNIT)).max(0.0)
}

/// The gap on one axis between points at `p` and the box `lo ..= hi`.
#[inline(always)]
fn point_gap(p: f32x8, lo: f32x8, hi: f32x8) -> f32x8 {
    Eight::max(Eight::max(lo - p, p - hi), f32x8::ZERO)
}

/// A distance (lane units) grown by the slack.
#[inline(always)]
fn inflate(d: f32) -> f32 {
    d * (1.0 + SLACK_REL) + SLACK_ABS
}

/// A band of grid rows and its cells' points: what every tile of the band
/// reads.
struct Band<'a, const D: usize> {
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
        Some(Axes { cell, f })
    }

    /// [`Simd::evaluate_grid`] by bands of [`BAND`] rows on the coherent
    /// path, serially or on all cores; false (nothing written) if the grid
    /// does not suit it.
    pub(super) fn grid_coherent(&self, grid: &Grid<D>, out: &mut [Features32<D, N>], parallel: bool) -> bool {
        let Some(axes) = self.grid_axes(grid) else {
            return false;
        };
        let width = grid.size[0];
        if width == 0 || out.is_empty() {
            return true;
        }
        let band = |(b, dst): (usize, &mut [Features32<D, N>])| self.band(grid, &axes, b * BAND, dst);
        #[cfg(feature = "parallel")]
        if parallel {
            use rayon::prelude::*;
            out.par_chunks_mut(BAND * width).enumerate().for_each(band);
            return true;
        }
        let _ = parallel;
        out.chunks_mut(BAND * width).enumerate().for_each(band);
        true
    }

    /// Rows `first..` of the grid into `out` (whole rows).
    fn band(&self, grid: &Grid<D>, axes: &Axes<D>, first: usize, out: &mut [Features32<D, N>]) {
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
            self.grid_range(grid, first * grid.size[0], out);
            return;
        }
        let band = Band { grid, axes, first, region: Region::generate(self, lo, hi) };
        match (self.config.metric, self.outputs) {
            (Metric::Euclidean, o) => self.tiles_euclid(o, &band, out),
            (Metric::Manhattan, o) => self.tiles_outputs(Manhattan, o, &band, out),
            (Metric::Chebyshev, o) => self.tiles_outputs(Chebyshev, o, &band, out),
            (Metric::Minkowski(p), o) => self.tiles_outputs(Minkowski(p), o, &band, out),
        }
    }

    /// The Euclidean tile loops, recompiled for AVX2 when this build lacks
    /// it and the CPU has it, as [`Simd::dispatch8`] does for the
    /// per-sample kernel: the same operations, so the same bits.
    #[inline(always)]
    fn tiles_euclid(&self, o: Outputs, band: &Band<'_, D>, out: &mut [Features32<D, N>]) {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if super::runtime_avx2() {
            // SAFETY: `tiles_avx2` requires AVX2 and nothing else, and
            // `runtime_avx2` has just seen the CPU report it.
            #[allow(unsafe_code)]
            return unsafe { self.tiles_avx2(o, band, out) };
        }
        self.tiles_for(Euclid, o, band, out)
    }

    /// [`Simd::tiles_euclid`]'s loops compiled with AVX2 enabled.
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
    #[target_feature(enable = "avx2")]
    fn tiles_avx2(&self, o: Outputs, band: &Band<'_, D>, out: &mut [Features32<D, N>]) {
        self.tiles_for(Euclid, o, band, out)
    }

    /// The tile loop for the outputs asked for.
    #[inline(always)]
    fn tiles_for<M: Metric32>(&self, m: M, o: Outputs, band: &Band<'_, D>, out: &mut [Features32<D, N>]) {
        match o {
            Outputs::Distances => self.tiles::<M, false, false>(m, band, out),
            Outputs::Ids => self.tiles::<M, true, false>(m, band, out),
            Outputs::IdsAndDeltas => self.tiles::<M, true, true>(m, band, out),
        }
    }

    /// The other metrics' tile loops, out of line (as `search_outputs`).
    #[inline(never)]
    fn tiles_outputs<M: Metric32>(&self, m: M, o: Outputs, band: &Band<'_, D>, out: &mut [Features32<D, N>]) {
        self.tiles_for(m, o, band, out)
    }

    /// Every tile of a band.
    #[inline(always)]
    fn tiles<M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        band: &Band<'_, D>,
        out: &mut [Features32<D, N>],
    ) {
        let Band { grid, axes, first, ref region } = *band;
        let width = grid.size[0];
        let rows = out.len() / width;
        // Axis 0 as lanes: each sample's cell relative to the band's first
        // cell, times UNIT (exact), and its fraction; padded with the last
        // sample so that eight lanes can be read from any x.
        let base = region.origin[0];
        let pad = |v: &mut Vec<f32>| v.resize(width + 8, v[width - 1]);
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
            let row_f = std::array::from_fn(|a| f32x8::new(std::array::from_fn(|k| rk[k].1[a])));
            let row_cl =
                std::array::from_fn(|a| f32x8::new(std::array::from_fn(|k| (rk[k].0[a] - reference[a]) as f32 * UNIT)));
            let mut tile = Tile { x_f: f32x8::ZERO, x_cl: f32x8::ZERO, row_f, row_cl, reference, hi, blo, bhi };
            if !far_apart {
                self.cell_rows(metric, region, &tile, &mut cell_rows, &mut near);
            }
            let mut best: [Best<Eight, D, N>; K] = std::array::from_fn(|_| Best::empty());
            for x0 in (0..width).step_by(8) {
                let cols_here = (width - x0).min(8);
                let (first_x, last_x) = (x0, x0 + cols_here - 1);
                let (c0, c1) = (axes.cell[0][first_x], axes.cell[0][last_x]);
                tile.reference[0] = c0.min(c1);
                tile.hi[0] = c0.max(c1);
                if far_apart || tile.hi[0] - tile.reference[0] > 1 {
                    for k in 0..rows_here {
                        let o = (r0 + k) * width + x0;
                        let start = (first + r0 + k) * width + x0;
                        let block: [[f64; D]; 8] = std::array::from_fn(|i| grid.point(start + i.min(cols_here - 1)));
                        self.write8(&block, &mut out[o..o + cols_here]);
                    }
                    continue;
                }
                // Cells along axis 0 are monotone in x: the box's ends are
                // the first and last samples.
                let shift = (tile.reference[0] - base) as f32 * UNIT;
                let (p0, p1) = (x_cell[first_x] - shift + x_f[first_x], x_cell[last_x] - shift + x_f[last_x]);
                tile.blo[0] = p0.min(p1);
                tile.bhi[0] = p0.max(p1);
                tile.x_f = load(&x_f, x0);
                tile.x_cl = load(&x_cell, x0) - f32x8::splat(shift);
                self.tile::<M, IDS, DELTAS>(metric, region, &tile, &cell_rows, &near, &mut best);
                for (k, b) in best.iter_mut().enumerate().take(rows_here) {
                    self.finish::<Eight, DELTAS>(b);
                    let o = (r0 + k) * width + x0;
                    write_lanes::<Eight, D, N, IDS, DELTAS>(b, &mut out[o..o + cols_here]);
                }
            }
        }
    }

    /// The rows of cells along axis 0 that a row of tiles searches (its
    /// own cells and one more on every side, on every axis but 0), and for
    /// every point in them, the fold of its gap terms to the tiles' box on
    /// those axes, into `near` at the point's index.
    fn cell_rows<M: Metric32>(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<D>,
        rows: &mut Vec<CellRow<D>>,
        near: &mut [f32],
    ) {
        rows.clear();
        let lo: [i64; D] = std::array::from_fn(|a| if a == 0 { region.origin[0] } else { t.reference[a] - 1 });
        let hi: [i64; D] = std::array::from_fn(|a| if a == 0 { region.origin[0] } else { t.hi[a] + 1 });
        let (blo, bhi): ([f32x8; D], [f32x8; D]) =
            (std::array::from_fn(|a| f32x8::splat(t.blo[a])), std::array::from_fn(|a| f32x8::splat(t.bhi[a])));
        for_cells(lo, hi, |c| {
            let frame: [f32; D] =
                std::array::from_fn(|a| if a == 0 { 0.0 } else { (c[a] - t.reference[a]) as f32 * UNIT });
            let terms: [f32; D] = std::array::from_fn(|a| metric.term::<One>(cell_gap(frame[a], t.blo[a], t.bhi[a])));
            let row = CellRow {
                base: region.cell(c),
                // Folded as in `Metric32::rank`: axes 1, 2, …, then 0.
                rest: terms[1..].iter().copied().reduce(|r, v| metric.fold::<One>(r, v)).unwrap_or(0.0),
                own: (1..D).all(|a| c[a] != lo[a] && c[a] != hi[a]),
                shift: std::array::from_fn(|a| {
                    if a == 0 {
                        f32x8::ZERO
                    } else {
                        t.row_f[a] - (f32x8::splat(frame[a]) - t.row_cl[a])
                    }
                }),
            };
            let (s, e) = (region.start[row.base] as usize, region.start[row.base + region.side[0]] as usize);
            for g in (s..e).step_by(8) {
                let gap: [f32x8; D] = std::array::from_fn(|a| {
                    if a == 0 {
                        return f32x8::ZERO;
                    }
                    point_gap(f32x8::splat(frame[a]) + load(&region.q[a], g), blo[a], bhi[a])
                });
                let rest = if D > 1 { metric.rest::<Eight, D>(&gap) } else { f32x8::ZERO };
                let n = (e - g).min(8);
                near[g..g + n].copy_from_slice(&rest.to_array()[..n]);
            }
            rows.push(row);
        });
    }

    /// One tile: the points of its own cells, the bound they give, the
    /// other candidates, the certificate, and the per-sample kernel for
    /// lanes left uncertified. Ranks in lane units. `rows` and `near` are
    /// the tile row's, from [`Simd::cell_rows`].
    #[inline(always)]
    fn tile<M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<D>,
        rows: &[CellRow<D>],
        near: &[f32],
        best: &mut [Best<Eight, D, N>; K],
    ) {
        for b in best.iter_mut() {
            b.reset::<IDS, DELTAS>();
        }
        let (blo, bhi) = (f32x8::splat(t.blo[0]), f32x8::splat(t.bhi[0]));
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
        let shift = |cell: f32| t.x_f - (f32x8::splat((cell - reference) * UNIT) - t.x_cl);

        // The tile's own cells: every point is a candidate.
        for row in rows.iter().filter(|r| r.own) {
            for xc in x_cells.iter().filter(|xc| xc.own) {
                let (i, x_shift) = (row.base + xc.index, shift(xc.index as f32));
                for p in region.start[i] as usize..region.start[i + 1] as usize {
                    self.candidate::<M, IDS, DELTAS>(metric, region, p, x_shift, &row.shift, best);
                }
            }
        }

        // The bound: the largest F_n of any lane so far (of the cells
        // around when the own cells hold fewer than n points).
        let bound = best.iter().fold(f32x8::ZERO, |m, b| Eight::max(m, b.rank[N - 1]));
        let mut bound = bound.to_array().into_iter().fold(0.0, f32::max);
        if bound == f32::INFINITY {
            bound = self.bound(metric, region, t, lo, hi);
            if bound == f32::INFINITY {
                return self.tile_per_sample::<M, IDS, DELTAS>(metric, t, best, [0; K]);
            }
        }
        let once = inflate(distance_of_rank::<One>(self.config.metric, bound));
        let certify = metric.rank_of_distance::<One>(once);
        let prune = metric.rank_of_distance::<One>(inflate(once));
        let prune8 = f32x8::splat(prune);

        // The other cells: a cell farther than the pruning bound from the
        // tile's box is skipped, and so is a point. The cells of a row that
        // remain are consecutive in the region, so their points are read as
        // one run; each point's cell along axis 0 comes with it.
        let (own_lo, own_hi) = (f32x8::ZERO, f32x8::splat((t.hi[0] - t.reference[0]) as f32));
        for row in rows.iter().filter(|r| r.rest <= prune) {
            let first = usize::from(metric.fold::<One>(row.rest, x_cells[0].term) > prune);
            let last = count - 1 - usize::from(metric.fold::<One>(row.rest, x_cells[count - 1].term) > prune);
            let (s, e) = (
                region.start[row.base + x_cells[first].index] as usize,
                region.start[row.base + x_cells[last].index + 1] as usize,
            );
            let mut g = s;
            while g < e {
                let cell = load(&region.x_cell, g) - f32x8::splat(reference);
                let p = cell * f32x8::splat(UNIT) + load(&region.q[0], g);
                let rank = metric.fold::<Eight>(load(near, g), metric.term::<Eight>(point_gap(p, blo, bhi)));
                let mut keep = Eight::le(rank, prune8);
                if row.own {
                    // The own cells' points are in already.
                    keep = Eight::and(keep, Eight::or(Eight::lt(cell, own_lo), Eight::lt(own_hi, cell)));
                }
                let mut bits = keep.to_bitmask() & ((1u32 << (e - g).min(8)) - 1);
                while bits != 0 {
                    let p = g + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    self.candidate::<M, IDS, DELTAS>(metric, region, p, shift(region.x_cell[p]), &row.shift, best);
                }
                g += 8;
            }
        }

        // The certificate, per lane: the distance to the outside of the
        // searched cells is a minimum over axes, so axis 0's part per lane
        // and the others' per row.
        let outside = |f: f32x8, cl: f32x8, a: usize| {
            let p = cl + f;
            let (low, high) = ((lo[a] - t.reference[a]) as f32 * UNIT, (hi[a] + 1 - t.reference[a]) as f32 * UNIT);
            Eight::min(p - f32x8::splat(low), f32x8::splat(high) - p)
        };
        let x_edge = outside(t.x_f, t.x_cl, 0);
        let mut row_edge = f32x8::splat(f32::INFINITY);
        for a in 1..D {
            row_edge = Eight::min(row_edge, outside(t.row_f[a], t.row_cl[a], a));
        }
        let row_edge = row_edge.to_array();
        let certify8 = f32x8::splat(certify);
        let mut certified = [0u32; K];
        for k in 0..K {
            let edge = Eight::min(x_edge, f32x8::splat(row_edge[k]));
            let edge = Eight::max(edge * f32x8::splat(1.0 - SLACK_REL) - f32x8::splat(SLACK_ABS), f32x8::ZERO);
            let last = best[k].rank[N - 1];
            let ok = Eight::and(Eight::le(last, certify8), Eight::lt(last, metric.rank_of_distance::<Eight>(edge)));
            certified[k] = ok.to_bitmask();
        }
        if certified.iter().all(|&m| m == 0xFF) {
            return;
        }
        self.tile_per_sample::<M, IDS, DELTAS>(metric, t, best, certified)
    }

    /// The n-th smallest farthest distance (as a rank) from the tile's box
    /// to the points of the cells `lo ..= hi`; +∞ if they hold fewer.
    #[inline(always)]
    fn bound<M: Metric32>(&self, metric: M, region: &Region<D>, t: &Tile<D>, lo: [i64; D], hi: [i64; D]) -> f32 {
        let (blo, bhi): ([f32x8; D], [f32x8; D]) =
            (std::array::from_fn(|a| f32x8::splat(t.blo[a])), std::array::from_fn(|a| f32x8::splat(t.bhi[a])));
        // The n smallest per lane, sorted, by a min/max network.
        let mut least = [f32x8::splat(f32::INFINITY); N];
        for_cells(lo, hi, |c| {
            let i = region.cell(c);
            let (s, e) = (region.start[i] as usize, region.start[i + 1] as usize);
            for g in (s..e).step_by(8) {
                let far: [f32x8; D] = std::array::from_fn(|a| {
                    let p = f32x8::splat((c[a] - t.reference[a]) as f32 * UNIT) + load(&region.q[a], g);
                    Eight::max(p - blo[a], bhi[a] - p)
                });
                let mut v = metric.rank::<Eight, D>(&far);
                if e - g < 8 {
                    v = f32x8::new(std::array::from_fn(|j| if j < e - g { 0.0 } else { 1.0 }))
                        .simd_lt(f32x8::splat(0.5))
                        .select(v, f32x8::splat(f32::INFINITY));
                }
                for l in least.iter_mut() {
                    let (a, b) = (Eight::min(*l, v), Eight::max(*l, v));
                    *l = a;
                    v = b;
                }
            }
        });
        if N == 1 {
            return least[0].to_array().into_iter().fold(f32::INFINITY, f32::min);
        }
        let mut all = [f32::INFINITY; 128];
        for (k, l) in least.iter().enumerate() {
            all[8 * k..8 * k + 8].copy_from_slice(&l.to_array());
        }
        let all = &mut all[..8 * N];
        all.sort_unstable_by(f32::total_cmp);
        all[N - 1]
    }

    /// One candidate point `p` of the region against every lane of a tile:
    /// `x_shift` is each lane's position minus the point's cell corner on
    /// axis 0, `row_shift` each row's on the other axes. Its delta is
    /// `shift − q` on every axis, so a row shares the rest of the rank
    /// ([`Metric32::rest`]) and only axis 0's term is per lane.
    #[inline(always)]
    fn candidate<M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        region: &Region<D>,
        p: usize,
        x_shift: f32x8,
        row_shift: &[f32x8; D],
        best: &mut [Best<Eight, D, N>; K],
    ) {
        let dx = x_shift - f32x8::splat(region.q[0][p]);
        let id = if IDS { u32x8::splat(region.id[p]) } else { u32x8::ZERO };
        let d_row: [f32x8; D] =
            std::array::from_fn(|a| if a == 0 { f32x8::ZERO } else { row_shift[a] - f32x8::splat(region.q[a][p]) });
        let d_row_lanes: [[f32; K]; D] = if DELTAS || !M::SPLITS { d_row.map(|v| v.to_array()) } else { [[0.0; K]; D] };
        let delta = |k: usize| -> [f32x8; D] {
            std::array::from_fn(|a| if a == 0 { dx } else { f32x8::splat(d_row_lanes[a][k]) })
        };
        if M::SPLITS && D > 1 {
            let first = metric.term::<Eight>(dx);
            let rest = metric.rest::<Eight, D>(&d_row).to_array();
            for (k, b) in best.iter_mut().enumerate() {
                let rank = metric.fold::<Eight>(f32x8::splat(rest[k]), first);
                let delta = if DELTAS { delta(k) } else { [f32x8::ZERO; D] };
                b.insert::<IDS, DELTAS>(rank, delta, id);
            }
        } else {
            for (k, b) in best.iter_mut().enumerate() {
                let delta = delta(k);
                b.insert::<IDS, DELTAS>(metric.rank::<Eight, D>(&delta), delta, id);
            }
        }
    }

    /// The lanes of a tile not set in `certified`, by the per-sample kernel.
    #[cold]
    #[inline(never)]
    fn tile_per_sample<M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        t: &Tile<D>,
        best: &mut [Best<Eight, D, N>; K],
        certified: [u32; K],
    ) {
        let (x_f, x_cl) = (t.x_f.to_array(), t.x_cl.to_array());
        let row_f: [[f32; 8]; D] = t.row_f.map(|v| v.to_array());
        let row_cl: [[f32; 8]; D] = t.row_cl.map(|v| v.to_array());
        for (k, b) in best.iter_mut().enumerate() {
            let mut rank = b.rank.map(|v| v.to_array());
            let mut id = b.id.map(|v| v.to_array());
            let mut delta = b.delta.map(|d| d.map(|v| v.to_array()));
            for i in (0..8).filter(|i| certified[k] & (1 << i) == 0) {
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
            b.rank = rank.map(f32x8::new);
            b.id = id.map(u32x8::new);
            b.delta = delta.map(|d| d.map(f32x8::new));
        }
    }
}

/// Eight values from `v[at..]` (the region's padding keeps it in bounds).
#[inline(always)]
fn load(v: &[f32], at: usize) -> f32x8 {
    let s: &[f32; 8] = v[at..at + 8].try_into().expect("padded");
    f32x8::new(*s)
}

/// Calls `visit` for every cell of the box `lo ..= hi`.
#[inline(always)]
fn for_cells<const D: usize>(lo: [i64; D], hi: [i64; D], mut visit: impl FnMut([i64; D])) {
    let mut c = lo;
    loop {
        visit(c);
        let mut a = 0;
        loop {
            if a == D {
                return;
            }
            c[a] += 1;
            if c[a] <= hi[a] {
                break;
            }
            c[a] = lo[a];
            a += 1;
        }
    }
}

fn min_max(v: &[i64]) -> (i64, i64) {
    v.iter().fold((i64::MAX, i64::MIN), |(lo, hi), &c| (lo.min(c), hi.max(c)))
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
