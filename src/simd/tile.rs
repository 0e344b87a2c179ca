//! One tile of the coherent path: its own cells' points, the bound they
//! give, the other candidates broadcast to its lanes, the certificate, and
//! the per-sample kernel for the lanes left uncertified.

use super::best::Best;
use super::generate::UNIT;
use super::lanes::{Lanes, One, WIDEST};
use super::locate::Located;
use super::metric::distance_of_rank;
use super::region::{next_cell, Region};
use super::search::search_one;
use super::tiles::{
    inflate, lanes_from, lanes_of, largest, load, point_gap, AxisCell, CellRow, Spill, Tile, SLACK_ABS, SLACK_REL,
};
use super::{per_axis, Metric32, Simd};
use crate::config::MAX_ORDER;

impl<const D: usize, const N: usize> Simd<D, N> {
    /// One tile: the points of its own cells, the bound they give, the
    /// other candidates, the certificate, and the per-sample kernel for
    /// lanes left uncertified. Ranks in lane units. `rows` and `near` are
    /// the tile row's, from [`Simd::cell_rows`]. `LOCAL`: the caller
    /// writes the distances alone, so that the search may run on a local
    /// copy of the ranks (a constant, so that an instantiation compiles
    /// only the search it runs).
    #[inline(always)]
    pub(super) fn tile<
        L: Lanes,
        const K: usize,
        M: Metric32,
        const IDS: bool,
        const DELTAS: bool,
        const LOCAL: bool,
    >(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<L, D>,
        (rows, near): (&[CellRow<L, D>], &[f32]),
        best: &mut [Best<L, D, N>; K],
    ) {
        if LOCAL && !IDS && !DELTAS && N <= L::LOCAL_RANKS {
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
            if let Some(certified) = open {
                tile_per_sample::<D, N, L, K, M, IDS, DELTAS>(self, metric, t, best, certified)
            }
            return;
        }
        for b in best.iter_mut() {
            b.reset::<IDS, DELTAS>();
        }
        if let Some(certified) = self.tile_search::<L, K, M, IDS, DELTAS>(metric, region, t, (rows, near), best) {
            tile_per_sample::<D, N, L, K, M, IDS, DELTAS>(self, metric, t, best, certified)
        }
    }

    /// [`Simd::tile`]'s search into `best` (which must start empty): the
    /// lanes certified per row, or `None` if every lane is.
    #[inline(always)]
    pub(super) fn tile_search<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
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
        let (x_cells, count) = AxisCell::row(metric, region, t, (lo[0], hi[0]));
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
    pub(super) fn bound<L: Lanes, M: Metric32>(
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
    pub(super) fn candidate<L: Lanes, const K: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
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
            if DELTAS || !metric.splits() { per_axis(|a| lanes_of::<L>(d_row[a])) } else { [[0.0; WIDEST]; D] };
        let delta = |k: usize| -> [L::F; D] { per_axis(|a| if a == 0 { dx } else { L::f(d_row_lanes[a][k]) }) };
        if metric.splits() && D > 1 {
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
}

/// The lanes of a tile not set in `certified`, by the per-sample kernel.
#[cold]
#[inline(never)]
pub(super) fn tile_per_sample<
    const D: usize,
    const N: usize,
    L: Lanes,
    const K: usize,
    M: Metric32,
    const IDS: bool,
    const DELTAS: bool,
>(
    kernel: &Simd<D, N>,
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
            let cell: [[i64; WIDEST]; D] = std::array::from_fn(|a| [t.reference[a] + (cl(a) / UNIT) as i64; WIDEST]);
            let fr: [[f32; WIDEST]; D] = std::array::from_fn(|a| [f(a); WIDEST]);
            let at = Located::<One, D>::lanewise(cell, &fr, [true; WIDEST]);
            let one = search_one::<D, N, M, IDS, DELTAS>(kernel, metric, &at);
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

/// Whether inserting a candidate of rank `rank` into `b` would change no
/// lane, tested only where the insertion carries IDs or deltas: a lane
/// takes it only if its rank is at most the lane's F_n (equal ranks are
/// ordered by ID), and a NaN on either side fails both tests. The
/// distances alone insert by a minimum and a maximum, cheaper than the
/// branch.
#[inline(always)]
pub(super) fn skip<L: Lanes, const D: usize, const N: usize, const IDS: bool, const DELTAS: bool>(
    rank: L::F,
    b: &Best<L, D, N>,
) -> bool {
    (IDS || DELTAS) && L::bits(L::le(rank, b.rank[N - 1])) == 0
}
