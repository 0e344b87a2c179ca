//! The coherent path's rows of tiles: a band's tiles in order, each row of
//! tiles sharing its rows of cells ([`Simd::cell_rows`]), the outputs
//! prefetched a tile ahead, and what a tile writes per sample
//! ([`GridSample`]: whole results or distances alone).

use super::best::Best;
use super::generate::UNIT;
use super::grid::Grid;
use super::lanes::{Lanes, One, WIDEST};
use super::region::{next_cell, Band, Region};
use super::sample::write_lanes;
use super::{per_axis, Features32, Metric32, Outputs, Simd};
use crate::definition::INVALID_ID;
use std::cell::Cell;

/// Asks the CPU to bring the cache lines of `v` in, ready to be written:
/// a tile's outputs, one tile ahead of the tile that writes them (see
/// [`Simd::tiles`]). On targets without the hint, nothing; the tiles then
/// fill each stripe of outputs in order first ([`PREFETCH`]).
#[inline(always)]
pub(super) fn prefetch_write<T>(v: &[T]) {
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
pub(super) const PREFETCH: bool = cfg!(target_arch = "x86_64");

/// Relative slack of the candidate and certificate tests.
pub(super) const SLACK_REL: f32 = 1.0 / 256.0;
/// Absolute slack of the same tests, in lane units (2^−24 cells).
pub(super) const SLACK_ABS: f32 = 16.0;

/// One tile of samples, `L::N` along axis 0 times `L::N` rows, in the
/// frame of its `reference` cell (the smallest cell of its lanes on every
/// axis). Every row of a grid lies along axis 0, so axis 0 varies with the
/// lane and the other axes only with the row: those are held with row k in
/// lane k.
pub(super) struct Tile<L: Lanes, const D: usize> {
    /// Axis 0 per lane: the fraction in the lane's own cell (lane units),
    /// and that cell minus the reference, times [`UNIT`] (exact).
    pub(super) x_f: L::F,
    pub(super) x_cl: L::F,
    /// The other axes per row, the same two quantities (lane k is row k;
    /// index 0 is unused).
    pub(super) row_f: [L::F; D],
    pub(super) row_cl: [L::F; D],
    pub(super) reference: [i64; D],
    /// The lanes' cells: largest per axis (the smallest is the reference).
    pub(super) hi: [i64; D],
    /// The bounding box of the lanes in the tile's frame, lane units.
    pub(super) blo: [f32; D],
    pub(super) bhi: [f32; D],
}

/// Where a tile's results go: the grid band's width, the tile's first row
/// and column, and how many of its rows and columns lie in the band.
pub(super) struct TileAt {
    pub(super) width: usize,
    pub(super) r0: usize,
    pub(super) x0: usize,
    pub(super) rows: usize,
    pub(super) cols: usize,
}

impl TileAt {
    /// The outputs of the tile's row `k`.
    #[inline(always)]
    pub(super) fn row<'o, T>(&self, out: &'o mut [T], k: usize) -> &'o mut [T] {
        let o = (self.r0 + k) * self.width + self.x0;
        &mut out[o..o + self.cols]
    }
}

/// What a tile's results are computed from: the band's region, the tile,
/// and its row of tiles' rows of cells with their points' gap terms
/// ([`Simd::cell_rows`]).
pub(super) type TileCells<'a, L, const D: usize> = (&'a Region<D>, &'a Tile<L, D>, (&'a [CellRow<L, D>], &'a [f32]));

/// One cell along axis 0 of a tile's searched cells.
#[derive(Clone, Copy, Default)]
pub(super) struct AxisCell {
    /// Its offset from the start of its row of cells in the region.
    pub(super) index: usize,
    /// The metric's term of its gap to the tile's box on axis 0.
    pub(super) term: f32,
    /// Whether it is one of the tile's own cells on axis 0.
    pub(super) own: bool,
}

impl AxisCell {
    /// The searched cells `lo ..= hi` of tile `t` along axis 0 (its own
    /// and one more on each side; at most four): each one's offset in its
    /// row of the region's cells, the metric's term of its gap to the
    /// tile's box, and whether it is own; and how many there are.
    #[inline(always)]
    pub(super) fn row<L: Lanes, M: Metric32, const D: usize>(
        metric: M,
        region: &Region<D>,
        t: &Tile<L, D>,
        (lo, hi): (i64, i64),
    ) -> ([AxisCell; 4], usize) {
        let mut cells = [AxisCell::default(); 4];
        for (xc, c) in cells.iter_mut().zip(lo..=hi) {
            *xc = AxisCell {
                index: (c - region.origin[0]) as usize,
                term: metric.term::<One>(cell_gap((c - t.reference[0]) as f32 * UNIT, t.blo[0], t.bhi[0])),
                own: c != lo && c != hi,
            };
        }
        (cells, (hi - lo + 1) as usize)
    }
}

/// A row of cells along axis 0 searched by a row of tiles.
pub(super) struct CellRow<L: Lanes, const D: usize> {
    /// The region's index of the row's first cell.
    pub(super) base: usize,
    /// The metric's terms of its gaps to the tiles' box on axes 1..,
    /// folded.
    pub(super) rest: f32,
    /// Whether it holds the tiles' own cells on axes 1...
    pub(super) own: bool,
    /// Its cell minus the tiles' reference cell on axes 1.. (0 unused).
    pub(super) offset: [i64; D],
    /// Each row of samples' position minus the corner on axes 1.. (lane k
    /// is row k; 0 unused).
    pub(super) shift: [L::F; D],
}

/// The gap on one axis between the cell whose lower corner is at `frame`
/// and the box `lo ..= hi` (lane units): zero where they overlap.
#[inline(always)]
pub(super) fn cell_gap(frame: f32, lo: f32, hi: f32) -> f32 {
    (frame - hi).max(lo - (frame + UNIT)).max(0.0)
}

/// The gap on one axis between points at `p` and the box `lo ..= hi`.
#[inline(always)]
pub(super) fn point_gap<L: Lanes>(p: L::F, lo: L::F, hi: L::F) -> L::F {
    L::max(L::max(L::sub(lo, p), L::sub(p, hi)), L::f(0.0))
}

/// A distance (lane units) grown by the slack.
#[inline(always)]
pub(super) fn inflate(d: f32) -> f32 {
    d * (1.0 + SLACK_REL) + SLACK_ABS
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Every tile of a band, `K` = `L::N` samples along axis 0 by `K` rows.
    #[inline(always)]
    pub(super) fn tiles<
        L: Lanes,
        const K: usize,
        M: Metric32,
        T: GridSample<D, N>,
        const IDS: bool,
        const DELTAS: bool,
    >(
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
                if T::FULL {
                    self.tile::<L, K, M, IDS, DELTAS, false>(metric, region, &tile, (&cell_rows, &near), &mut best);
                } else {
                    self.tile::<L, K, M, IDS, DELTAS, true>(metric, region, &tile, (&cell_rows, &near), &mut best);
                }
                let at = TileAt { width, r0, x0, rows: rows_here, cols: cols_here };
                T::tile_out::<L, K, M, IDS, DELTAS>(
                    self,
                    metric,
                    (region, &tile, (&cell_rows, &near)),
                    &mut best,
                    out,
                    &at,
                );
            }
        }
    }

    /// The outputs a search tracked that the evaluator was not built for
    /// put back to what a search without them leaves (zero deltas,
    /// [`INVALID_ID`]): the other metrics' tiles track both whatever the
    /// outputs (`tiles_others`). A test on values fixed for the call, where
    /// the tracked outputs are the asked ones.
    #[inline(always)]
    pub(super) fn forget_unasked<L: Lanes, const IDS: bool, const DELTAS: bool>(&self, b: &mut Best<L, D, N>) {
        if DELTAS && self.outputs != Outputs::IdsAndDeltas {
            b.delta = [[L::f(0.0); D]; N];
        }
        if IDS && self.outputs == Outputs::Distances {
            b.id = [L::u(INVALID_ID); N];
        }
    }

    /// The rows of cells along axis 0 that a row of tiles searches (its
    /// own cells and one more on every side, on every axis but 0), and for
    /// every point in them, the fold of its gap terms to the tiles' box on
    /// those axes, into `near` at the point's index.
    #[inline(always)]
    pub(super) fn cell_rows<L: Lanes, M: Metric32>(
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
                offset: std::array::from_fn(|a| if a == 0 { 0 } else { c[a] - t.reference[a] }),
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
pub(super) struct Spill(pub(super) [Cell<f32>; WIDEST]);

/// The largest value in any lane of `v`, by halving trees (a short chain
/// of dependent operations: the tile's scan waits for it).
#[inline(always)]
pub(super) fn largest<L: Lanes, const K: usize>(mut v: [L::F; K]) -> f32 {
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
pub(super) fn load<L: Lanes>(v: &[f32], at: usize) -> L::F {
    L::f_load(&v[at..at + L::N])
}

/// Lanes into an array, of which the first `L::N` are set.
#[inline(always)]
pub(super) fn lanes_of<L: Lanes>(v: L::F) -> [f32; WIDEST] {
    let mut a = [0.0; WIDEST];
    L::f_store(v, &mut a[..L::N]);
    a
}

/// Lanes from the first `L::N` of an array.
#[inline(always)]
pub(super) fn lanes_from<L: Lanes>(a: &[f32; WIDEST]) -> L::F {
    L::f_load(&a[..L::N])
}

/// A sample's F1 (user units) and the ID of its point, 8 bytes where
/// [`Features32`] takes 12 + 4·D: what a grid's n-sphere radii read to
/// share their points ([`SimdNSphere`](super::SimdNSphere)), from a kernel
/// built with IDs (the per-sample kernel, which some samples take, reports
/// them only then).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Nearest {
    /// F1 (NaN for bad input, +∞ for an empty window).
    pub(crate) distance: f32,
    /// Its point's ID ([`INVALID_ID`] where there is none).
    pub(crate) id: u32,
}

impl<const D: usize> GridSample<D, 1> for Nearest {
    const FULL: bool = true;
    const IDS_ONLY: bool = true;
    #[inline(always)]
    fn tile_out<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        simd: &Simd<D, 1>,
        _: M,
        _: TileCells<'_, L, D>,
        best: &mut [Best<L, D, 1>; K],
        out: &mut [Self],
        at: &TileAt,
    ) {
        for (k, b) in best.iter_mut().enumerate().take(at.rows) {
            simd.finish::<L, false>(b);
            let (mut distance, mut id) = ([0.0; WIDEST], [INVALID_ID; WIDEST]);
            L::f_store(b.rank[0], &mut distance[..L::N]);
            L::u_store(b.id[0], &mut id[..L::N]);
            for (i, o) in at.row(out, k).iter_mut().enumerate() {
                *o = Nearest { distance: distance[i], id: id[i] };
            }
        }
    }
    fn per_sample(simd: &Simd<D, 1>, grid: &Grid<D>, first: usize, dst: &mut [Self]) {
        let mut whole = [Features32 { distance: [0.0], delta: [[0.0; D]], id: [0] }; 8];
        for (c, chunk) in dst.chunks_mut(8).enumerate() {
            simd.grid_range(grid, first + c * 8, &mut whole[..chunk.len()]);
            for (o, f) in chunk.iter_mut().zip(&whole) {
                *o = Nearest { distance: f.distance[0], id: f.id[0] };
            }
        }
    }
}

pub(super) fn min_max(v: &[i64]) -> (i64, i64) {
    v.iter().fold((i64::MAX, i64::MIN), |(lo, hi), &c| (lo.min(c), hi.max(c)))
}

/// What the coherent grid path writes per sample: whole results
/// ([`Features32`], the outputs the [`Simd`] was built for), the distances
/// alone (`[f32; N]`, see [`Simd::evaluate_grid_distances`]), F1 with its
/// ID ([`Nearest`]), or the border's results (`Border32`, in the border's
/// tiles). `Copy`, since a stripe of outputs is filled before its tiles
/// write it.
pub(super) trait GridSample<const D: usize, const N: usize>: Sized + Send + Copy {
    /// Whether the tiles compute the outputs the [`Simd`] was built for;
    /// false: distances only, whatever it was built for (the distances are
    /// the same bits either way).
    const FULL: bool;
    /// Whether the tiles compute distances and IDs alone (the same bits as
    /// with deltas), and only for the Euclidean metric: the other metrics'
    /// samples then take the per-sample kernel, so that no tile loop of
    /// theirs is compiled for it.
    const IDS_ONLY: bool = false;
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
