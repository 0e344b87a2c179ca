//! The border on the coherent path: a grid tile's F1 from the F_n tiles
//! ([`Simd::tile`]), then F1's point and the nearest bisector plane from
//! the same points of the band's region, broadcast to the tile's lanes.
//!
//! ## Why the bits are the per-sample border's
//! F1 is the tiles' distance, and so the per-sample kernel's bits. Its
//! point is the one whose rank, computed as the tiles compute it, has those
//! bits, the smallest ID first: the kernel's own choice among equal ranks,
//! so the ID and the delta are the kernel's too. A candidate's delta is
//! computed as the tiles compute it, which is
//! how the per-sample search computes it (the sample's fraction minus the
//! cell's offset, an exact multiple of [`UNIT`], minus the point's 24-bit
//! coordinate); u = p_j − p₁ is the same exact integer difference in the
//! tile's frame as in the sample's, rounded once; k and |u|² are summed
//! over the axes in the same order. The nearest plane is the first in the
//! total order of [`Plane::offer`](super::Plane::offer), whatever the order
//! in which the points are met.
//!
//! ## Why every plane that matters is met
//! A point j farther than F1 + 2b from the sample has b_j ≥ (d_j − F1)/2 > b
//! (the triangle inequality), so it cannot be the nearest plane. F1's point
//! is looked for among the points no farther from the tile's box than the
//! largest F1 of its lanes; every point of the tile's own cells is then
//! offered to every lane, which bounds each lane's F1 + 2b, and the other
//! points of the searched cells (one more on every side) are offered where
//! they lie within the largest such bound of the tile's box and within a
//! lane's own bound. Both tests carry the tiles' slack on the side of
//! offering more. A lane is certified when F1's point was met and its
//! F1 + 2b, inflated, lies strictly inside the distance to the outside of
//! the searched cells, deflated; any other lane is evaluated by the
//! per-sample border.

use super::super::best::Best;
use super::super::generate::UNIT;
use super::super::grid::Grid;
use super::super::lanes::{Lanes, One, WIDEST};
use super::super::locate::Located;
use super::super::region::Region;
use super::super::tiles::{
    inflate, lanes_from, lanes_of, largest, load, point_gap, AxisCell, CellRow, GridSample, Tile, TileAt, TileCells,
    SLACK_ABS, SLACK_REL,
};
use super::super::{Metric32, Simd};
use super::{border_one, eight_of, Border32, Plane, Results, SLACK};
use crate::definition::FRACTION_BITS;

/// The border through the grid tiles: the kernel's [`Simd::tile`] gives
/// F1's distance, [`Simd::border_tile`] its point and the rest.
impl<const D: usize> GridSample<D, 1> for Border32<D> {
    // F1's distance alone (the tiles' fastest search), and the IDs for
    // the rest.
    const FULL: bool = false;
    const REGION_IDS: bool = true;

    #[inline(always)]
    fn tile_out<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
        simd: &Simd<D, 1>,
        metric: M,
        cells: TileCells<'_, L, D>,
        best: &mut [Best<L, D, 1>; K],
        out: &mut [Self],
        at: &TileAt,
    ) {
        simd.border_tile::<L, K, M>(metric, cells, best, out, at)
    }

    fn per_sample(simd: &Simd<D, 1>, grid: &Grid<D>, first: usize, dst: &mut [Self]) {
        for (c, chunk) in dst.chunks_mut(8).enumerate() {
            let start = first + c * 8;
            let block: [[f64; D]; 8] = std::array::from_fn(|i| grid.point(start + i.min(chunk.len() - 1)));
            let lanes = eight_of(simd, &simd.locate(&block)).lanes();
            chunk.copy_from_slice(&lanes[..chunk.len()]);
        }
    }
}

impl<const D: usize> Simd<D, 1> {
    /// A tile's borders from its F1 (`best`, raw, every lane set: the
    /// tile's uncertified lanes by the per-sample kernel), into its rows of
    /// `out`. See the [module's text](self). No closure holds lane
    /// operations: in the run-time AVX-512 copy a closure is compiled
    /// without its instructions, and each intrinsic in it would be a call.
    #[inline(always)]
    fn border_tile<L: Lanes, const K: usize, M: Metric32>(
        &self,
        metric: M,
        cells: TileCells<'_, L, D>,
        best: &[Best<L, D, 1>; K],
        out: &mut [Border32<D>],
        at: &TileAt,
    ) {
        let tile = BorderTile::new(metric, cells, at.rows);
        let t = tile.t;
        let mut s = State::<L, D, K> {
            nearest: std::array::from_fn(|k| Best { rank: best[k].rank, ..Best::empty() }),
            p1: [[L::u(0); D]; K],
            found: [L::lt(L::f(1.0), L::f(0.0)); K],
            plane: std::array::from_fn(|_| Plane::none()),
            f1: std::array::from_fn(|k| L::sqrt(best[k].rank[0])),
        };

        // F1's point per lane: of the points whose rank has F1's bits, the
        // one of smallest ID (the order of [`Best`]), with its delta and ID.
        let f1_bound = largest::<L, K>(std::array::from_fn(|k| best[k].rank[0]));
        if f1_bound < f32::INFINITY {
            let prune = metric.rank_of_distance::<One>(inflate(f1_bound.sqrt()));
            let limit = L::mul(by_row::<L, K>(std::array::from_fn(|k| best[k].rank[0])), L::f(SLACK));
            for own in [true, false] {
                for_each_point!(tile, prune, own, |p, x_shift, r| tile
                    .meet(&tile.against(p, r, x_shift, limit), &mut s));
            }
        }

        // The planes: the own cells' points in every lane that found F1's
        // point, then the others within reach. A lane whose own cells held
        // F1's point alone has b = +∞ and takes every point of the searched
        // cells.
        if s.found.iter().any(|&m| L::any(m)) {
            let all = metric.rank_of_distance::<One>(f32::INFINITY);
            let (everywhere, any_row) = ([L::f(all); K], L::f(all));
            for_each_point!(tile, all, true, |p, x_shift, r| {
                tile.offer(&tile.against(p, r, x_shift, any_row), &everywhere, &mut s)
            });
            let mut limits = [L::f(0.0); K];
            for (k, limit) in limits.iter_mut().enumerate() {
                let r = L::select(s.found[k], s.reach(k), L::f(0.0));
                *limit = L::mul(r, r);
            }
            let prune = metric.rank_of_distance::<One>(inflate(largest::<L, K>(limits).sqrt()));
            let row_limit = by_row::<L, K>(limits);
            for_each_point!(tile, prune, false, |p, x_shift, r| {
                tile.offer(&tile.against(p, r, x_shift, row_limit), &limits, &mut s)
            });
        }

        // The certificate, then the results; the per-sample border for the
        // lanes left.
        let (lo, hi) = (tile.lo, tile.hi);
        let mut x_edge = L::f(f32::INFINITY);
        let mut row_edge = L::f(f32::INFINITY);
        for a in 0..D {
            let (f, cl) = if a == 0 { (t.x_f, t.x_cl) } else { (t.row_f[a], t.row_cl[a]) };
            let p = L::add(cl, f);
            let (low, high) = ((lo[a] - t.reference[a]) as f32 * UNIT, (hi[a] + 1 - t.reference[a]) as f32 * UNIT);
            let edge = L::min(L::sub(p, L::f(low)), L::sub(L::f(high), p));
            if a == 0 {
                x_edge = edge;
            } else {
                row_edge = L::min(row_edge, edge);
            }
        }
        let row_edge = lanes_of::<L>(row_edge);
        let everyone = L::lt(L::f(0.0), L::f(1.0));
        for (k, &row_edge) in row_edge.iter().enumerate().take(at.rows) {
            let edge = L::min(x_edge, L::f(row_edge));
            let edge = L::sub(L::mul(edge, L::f(1.0 - SLACK_REL)), L::f(SLACK_ABS));
            let reached = L::add(L::mul(s.reach(k), L::f(1.0 + SLACK_REL)), L::f(SLACK_ABS));
            let certified = L::bits(L::and(s.found[k], L::lt(reached, edge)));
            let lanes = Results::<L, D>::of(self, everyone, &s.nearest[k], &s.plane[k], s.found[k]).lanes();
            let dst = at.row(out, k);
            for (i, o) in dst.iter_mut().enumerate() {
                *o = if certified & (1 << i) != 0 { lanes[i] } else { self.border_lane(t, k, i) };
            }
        }
    }

    /// Lane `i` of row `k` of a tile by the per-sample border.
    #[cold]
    #[inline(never)]
    fn border_lane<L: Lanes>(&self, t: &Tile<L, D>, k: usize, i: usize) -> Border32<D> {
        let (x_f, x_cl) = (lanes_of::<L>(t.x_f), lanes_of::<L>(t.x_cl));
        let mut cell = [[0i64; WIDEST]; D];
        let mut fr = [[0f32; WIDEST]; D];
        for a in 0..D {
            let (f, cl) =
                if a == 0 { (x_f[i], x_cl[i]) } else { (lanes_of::<L>(t.row_f[a])[k], lanes_of::<L>(t.row_cl[a])[k]) };
            cell[a] = [t.reference[a] + (cl / UNIT) as i64; WIDEST];
            fr[a] = [f; WIDEST];
        }
        border_one(self, &Located::<One, D>::lanewise(cell, &fr, [true; WIDEST]))
    }
}

/// What a tile's border search keeps per row (row k in element k): F1 with
/// its point's delta and ID, that point's position (tile frame, lane
/// units), whether it was met, the nearest plane so far, and F1.
struct State<L: Lanes, const D: usize, const K: usize> {
    nearest: [Best<L, D, 1>; K],
    p1: [[L::U; D]; K],
    found: [L::M; K],
    plane: [Plane<L, D>; K],
    f1: [L::F; K],
}

impl<L: Lanes, const D: usize, const K: usize> State<L, D, K> {
    /// Row k's F1 + 2b, grown by the border's slack (+∞ before any plane).
    #[inline(always)]
    fn reach(&self, k: usize) -> L::F {
        let b = self.plane[k].distance();
        L::mul(L::add(self.f1[k], L::add(b, b)), L::f(SLACK))
    }
}

/// A tile with what its border search reads: the band's region, the tile,
/// its rows of cells, the searched cells (`lo ..= hi`: its own and one
/// more on every side) and, per cell along axis 0, its index in its row
/// of cells, its gap term to the tile's box and whether it is own.
struct BorderTile<'a, L: Lanes, M, const D: usize> {
    metric: M,
    region: &'a Region<D>,
    t: &'a Tile<L, D>,
    rows: &'a [CellRow<L, D>],
    near: &'a [f32],
    lo: [i64; D],
    hi: [i64; D],
    x_cells: [AxisCell; 4],
    count: usize,
    /// The tile's rows inside the grid.
    used: usize,
}

impl<'a, L: Lanes, M: Metric32, const D: usize> BorderTile<'a, L, M, D> {
    #[inline(always)]
    fn new(metric: M, (region, t, (rows, near)): TileCells<'a, L, D>, used: usize) -> Self {
        let lo: [i64; D] = std::array::from_fn(|a| t.reference[a] - 1);
        let hi: [i64; D] = std::array::from_fn(|a| t.hi[a] + 1);
        let (x_cells, count) = AxisCell::row(metric, region, t, (lo[0], hi[0]));
        BorderTile { metric, region, t, rows, near, lo, hi, x_cells, count, used }
    }

    /// A point (index `p`, row of cells `r`, its lanes' axis-0 position
    /// minus its cell's corner) against the tile's rows: the rows whose
    /// lower bound on the rank is within `limit` (row k in lane k), and
    /// what every row shares.
    #[inline(always)]
    fn against(&self, p: usize, r: usize, x_shift: L::F, limit: L::F) -> PointRows<L, D> {
        let (region, t, metric) = (self.region, self.t, self.metric);
        let mut d_row = [L::f(0.0); D];
        for (a, d) in d_row.iter_mut().enumerate().skip(1) {
            *d = L::sub(self.rows[r].shift[a], L::f(region.q[a][p]));
        }
        let cell = (region.x_cell[p] - (t.reference[0] - region.origin[0]) as f32) * UNIT;
        let gap = point_gap::<One>(cell + region.q[0][p], t.blo[0], t.bhi[0]);
        let rest = if D > 1 { metric.rest::<L, D>(&d_row) } else { L::f(0.0) };
        let least = metric.fold::<L>(rest, L::f(metric.term::<One>(gap)));
        let dx = L::sub(x_shift, L::f(region.q[0][p]));
        // The position in the tile's frame, exact integers in lane units.
        let mut q = [0u32; D];
        let mut rows = [[0f32; WIDEST]; D];
        for a in 0..D {
            let c = if a == 0 {
                region.x_cell[p] as i64 + region.origin[0] - t.reference[0]
            } else {
                self.rows[r].offset[a]
            };
            q[a] = ((c << FRACTION_BITS) as u32).wrapping_add(region.q[a][p] as u32);
            L::f_store(d_row[a], &mut rows[a][..L::N]);
        }
        let mut rest_rows = [0f32; WIDEST];
        L::f_store(rest, &mut rest_rows[..L::N]);
        PointRows {
            bits: L::bits(L::le(least, limit)) & (u32::MAX >> (32 - self.used)),
            d_row: rows,
            rest: rest_rows,
            dx,
            dx_term: metric.term::<L>(dx),
            q,
            id: L::u(region.id[p]),
        }
    }

    /// Row k's delta to a point (axis 0 per lane, the others the row's) and
    /// its rank, bit for bit [`Metric32::rank`] of that delta.
    #[inline(always)]
    fn row_delta(&self, pr: &PointRows<L, D>, k: usize) -> ([L::F; D], L::F) {
        let mut dj = [pr.dx; D];
        for (a, d) in dj.iter_mut().enumerate().skip(1) {
            *d = L::f(pr.d_row[a][k]);
        }
        let rank = if D > 1 { self.metric.fold::<L>(L::f(pr.rest[k]), pr.dx_term) } else { pr.dx_term };
        (dj, rank)
    }

    /// A point as F1's point in the lanes where its rank has F1's bits and
    /// its ID is the smallest such so far.
    #[inline(always)]
    fn meet<const K: usize>(&self, pr: &PointRows<L, D>, s: &mut State<L, D, K>) {
        let mut bits = pr.bits;
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (dj, rank) = self.row_delta(pr, k);
            let n = &mut s.nearest[k];
            let same = L::eq(rank, n.rank[0]);
            let first = L::lt(L::select(s.found[k], L::f(1.0), L::f(0.0)), L::f(0.5));
            let take = L::and(same, L::or(L::u_lt(pr.id, n.id[0]), first));
            if !L::any(take) {
                continue;
            }
            n.id[0] = L::select_u(take, pr.id, n.id[0]);
            for (a, d) in dj.into_iter().enumerate() {
                n.delta[0][a] = L::select(take, d, n.delta[0][a]);
                s.p1[k][a] = L::select_u(take, L::u(pr.q[a]), s.p1[k][a]);
            }
            s.found[k] = L::or(s.found[k], take);
        }
    }

    /// A point's plane to the lanes of its rows within `limits` (ranks).
    #[inline(always)]
    fn offer<const K: usize>(&self, pr: &PointRows<L, D>, limits: &[L::F; K], s: &mut State<L, D, K>) {
        let mut bits = pr.bits;
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (dj, rank) = self.row_delta(pr, k);
            // Most rows visited have most lanes within their limit: no
            // branch on it.
            let active = L::and(s.found[k], L::le(rank, limits[k]));
            let d1 = s.nearest[k].delta[0];
            let (mut uu, mut us) = (L::f(0.0), L::f(0.0));
            let mut u = [L::f(0.0); D];
            for a in 0..D {
                u[a] = L::i_to_f(L::u_sub(L::u(pr.q[a]), s.p1[k][a]));
                uu = L::add(uu, L::mul(u[a], u[a]));
                us = L::add(us, L::mul(u[a], L::add(d1[a], dj[a])));
            }
            s.plane[k].offer_point(active, us, uu, u, pr.id);
        }
    }
}

/// The largest lane of each of `v`, row k's in lane k.
#[inline(always)]
fn by_row<L: Lanes, const K: usize>(v: [L::F; K]) -> L::F {
    let mut m = [0f32; WIDEST];
    for (slot, v) in m.iter_mut().zip(v) {
        *slot = largest::<L, 1>([v]);
    }
    lanes_from::<L>(&m)
}

/// Runs `$body` for every point of a tile's searched cells no farther than
/// `$prune` (a rank) from the tile's box: of the tile's own cells if
/// `$own`, of the others if not, with `$p` the point's index in the region,
/// `$x_shift` its lanes' axis-0 position minus the point's cell corner (as
/// the tiles compute it) and `$r` its row of cells. A macro rather than a
/// function taking a closure (see [`Simd::border_tile`]).
macro_rules! for_each_point {
    ($tile:expr, $prune:expr, $own:expr, |$p:ident, $x_shift:ident, $r:ident| $body:expr) => {{
        let tile = &$tile;
        let (region, t, metric) = (tile.region, tile.t, tile.metric);
        let (prune, own) = ($prune, $own);
        let (blo, bhi) = (L::f(t.blo[0]), L::f(t.bhi[0]));
        let reference = (t.reference[0] - region.origin[0]) as f32;
        let prune_lanes = L::f(prune);
        for ($r, row) in tile.rows.iter().enumerate() {
            if row.rest > prune {
                continue;
            }
            for &AxisCell { index, term, own: own_x } in &tile.x_cells[..tile.count] {
                if own != (own_x && row.own) || metric.fold::<One>(row.rest, term) > prune {
                    continue;
                }
                let (start, end) =
                    (region.start[row.base + index] as usize, region.start[row.base + index + 1] as usize);
                let cell = L::f((index as f32 - reference) * UNIT);
                let $x_shift = L::sub(t.x_f, L::sub(cell, t.x_cl));
                let mut g = start;
                while g < end {
                    let x = L::add(cell, load::<L>(&region.q[0], g));
                    let rank = metric.fold::<L>(load::<L>(tile.near, g), metric.term::<L>(point_gap::<L>(x, blo, bhi)));
                    let n = (end - g).min(L::N);
                    let mut bits = L::bits(L::le(rank, prune_lanes)) & (u32::MAX >> (32 - n));
                    while bits != 0 {
                        let $p = g + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        $body;
                    }
                    g += L::N;
                }
            }
        }
    }};
}
use for_each_point;

/// A point against a tile's rows: the rows to visit (bits), its deltas on
/// the axes other than 0 and the fold of their terms per row (row k in
/// element k), its axis-0 delta per lane and that delta's term, its
/// position in the tile's frame and its ID.
struct PointRows<L: Lanes, const D: usize> {
    bits: u32,
    d_row: [[f32; WIDEST]; D],
    rest: [f32; WIDEST],
    dx: L::F,
    dx_term: L::F,
    q: [u32; D],
    id: L::U,
}
