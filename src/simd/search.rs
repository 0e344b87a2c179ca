//! The per-sample search: the lane's 2^d block, the far cells of its 3^d
//! block, and the certified widening shell by shell, each candidate kept
//! in a sorted list per lane ([`Best`]).

use super::best::Best;
use super::generate::{words, UNIT};
use super::lanes::{Lanes, One, WIDEST};
use super::locate::Located;
use super::metric::Metric32;
use super::{per_axis, per_axis_slots, Simd};
use crate::config::Mode;
use crate::definition::INVALID_ID;
use crate::reference::{shell, MAX_SHELLS};

/// The whole search (see [`Simd::search`]).
pub(super) const WHOLE: u8 = 0;
/// The first stage of the search only: each lane's 2^d block.
pub(super) const FIRST: u8 = 1;
/// The rest of the search after [`FIRST`]: the far cells and the widening.
pub(super) const REST: u8 = 2;

/// What a stage of the search gives: the lanes' results as a caller sees
/// them (distances in user units, bad lanes marked), the lanes left open
/// (after [`FIRST`]; none otherwise), and the candidates as the kernel holds
/// them, from which [`REST`] continues.
pub(super) type Stages<L, const D: usize, const N: usize> = (Best<L, D, N>, <L as Lanes>::M, Best<L, D, N>);

impl<const D: usize, const N: usize> Simd<D, N> {
    /// The kernel: the 3^d block, then the certified widening.
    ///
    /// The block is visited in a per-lane mirrored frame: on each axis a
    /// lane's *near* neighbour (offset −1 if f < ½, else +1) comes first. In
    /// that frame every lane visits its own cell, then the 2^d − 1 cells
    /// around its nearest lattice corner, then the cells on the far sides,
    /// so the lanes agree on which visits still matter and all of them can
    /// usually stop after the near cells.
    ///
    /// `STAGE` says which part runs, from the candidates in `start`:
    /// [`WHOLE`] (from no candidate), [`FIRST`] (the 2^d block only; the
    /// lanes whose far cells could still hold a candidate are returned as
    /// open, and their results are not final) or [`REST`] (the far cells
    /// and the widening, from a first stage's candidates: a lane then ends
    /// with the bits [`WHOLE`] gives it). After [`WHOLE`] and [`REST`] every
    /// lane is final and the mask returned is empty.
    #[inline(always)]
    pub(super) fn search<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool, const STAGE: u8>(
        &self,
        metric: M,
        at: &Located<L, D>,
        start: Best<L, D, N>,
    ) -> (Best<L, D, N>, L::M) {
        let mut best = start;
        let one = L::f(UNIT);
        // Per axis, indexed by the mirrored offset + 1 (near, own, far): the
        // axis word, the sample minus the cell's corner, and the metric's
        // term of the gap between the sample and the cell.
        let mut terms = [[L::u(0); 3]; D];
        let mut shifted = [[L::f(0.0); 3]; D];
        let mut gap = [[L::f(0.0); 3]; D];
        for a in 0..D {
            let f = at.f[a];
            let flip = L::lt(L::f(0.5 * UNIT), f);
            let t = at.words[a];
            terms[a] = [L::select_u(flip, t[2], t[0]), t[1], L::select_u(flip, t[0], t[2])];
            let (below, above) = (L::add(f, one), L::sub(f, one));
            shifted[a] = [L::select(flip, above, below), f, L::select(flip, below, above)];
            let rest = L::sub(one, f);
            gap[a] =
                [metric.term::<L>(L::select(flip, rest, f)), L::f(0.0), metric.term::<L>(L::select(flip, f, rest))];
        }
        // Stage 1, the lane's 2^d block (its own cell and the cells around
        // its nearest lattice corner): every cell hashed up front as
        // independent chains, then, cell by cell, the same number of point
        // steps, the largest population of any cell in any lane, so that the
        // inner loop's trip count repeats from cell to cell. A point a
        // lane's cell lacks has rank +∞ there. Cell c of the block is, on
        // axis a, the lane's near neighbour where bit a of c is set and its
        // own cell's column otherwise.
        if STAGE != REST {
            let cells = 1usize << D;
            let pick = |c: usize, a: usize| 1 - ((c >> a) & 1);
            let h = self.block_hashes::<L>(&terms);
            let mut top = [L::f(0.0); 16];
            let mut most = L::f(-1.0);
            for c in 0..cells {
                top[c] = self.population::<L>(h[c]);
                most = L::max(most, top[c]);
            }
            let count = self.points.iter().take_while(|p| L::any(L::lt(self.key::<L>(p), most))).count();
            for c in 0..cells {
                let sh = per_axis_slots(|a| shifted[a][pick(c, a)]);
                for p in &self.points[..count] {
                    self.point::<L, M, IDS, DELTAS>(metric, p, h[c], sh, L::lt(self.key::<L>(p), top[c]), &mut best);
                }
            }
        }
        // Stage 2, the far cells, per lane only where one could still hold a
        // candidate; skipped together when no lane's F_n reaches its nearest
        // far face.
        let mut nearest_far = gap[0][2];
        for g in &gap[1..] {
            nearest_far = L::min(nearest_far, g[2]);
        }
        let far = may_enter::<L, IDS>(nearest_far, best.rank[N - 1]);
        if STAGE == FIRST {
            return (best, far);
        }
        if L::any(far) {
            for offset in &self.block[self.near..] {
                let index: [usize; D] = per_axis(|a| (offset[a] + 1) as usize);
                let mut rank = gap[0][index[0]];
                for a in 1..D {
                    rank = metric.fold::<L>(rank, gap[a][index[a]]);
                }
                let needs = may_enter::<L, IDS>(rank, best.rank[N - 1]);
                if !L::any(needs) {
                    continue;
                }
                let h = self.hash::<L>(per_axis(|a| terms[a][index[a]]));
                let sh: [L::F; D] = per_axis(|a| shifted[a][index[a]]);
                self.visit::<L, M, IDS, DELTAS>(metric, h, sh, needs, &mut best);
            }
        }
        if self.config.mode == Mode::Exact {
            let open =
                may_enter::<L, IDS>(metric.rank_of_distance::<L>(outside::<L, D>(&at.f, UNIT)), best.rank[N - 1]);
            if L::any(open) {
                widen::<D, N, L, M, IDS, DELTAS>(self, metric, at, open, &mut best);
            }
        }
        // Every lane is final: no lane is open.
        (best, L::lt(one, L::f(0.0)))
    }
}

/// The whole search in one lane, as ranks in lane units (no distances,
/// no bad lanes marked), out of line: the coherent paths' lanes left
/// uncertified take it, and one copy serves every lane set's tiles.
#[inline(never)]
pub(super) fn search_one<const D: usize, const N: usize, M: Metric32, const IDS: bool, const DELTAS: bool>(
    kernel: &Simd<D, N>,
    metric: M,
    at: &Located<One, D>,
) -> Best<One, D, N> {
    kernel.search::<One, M, IDS, DELTAS, WHOLE>(metric, at, Best::empty()).0
}

/// The cold path: shells of radius 2, 3, … for the lanes in `open`.
#[inline(never)]
pub(super) fn widen<const D: usize, const N: usize, L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
    kernel: &Simd<D, N>,
    metric: M,
    at: &Located<L, D>,
    mut open: L::M,
    best: &mut Best<L, D, N>,
) {
    let cell = at.cells_i64();
    for r in 2..=MAX_SHELLS {
        for offset in shell::<D>(r) {
            let t: [L::U; D] = per_axis(|a| words::<L>(a, &cell[a], offset[a], at.period.map(|p| p[a])));
            let gaps = far_gaps::<L, D>(&at.f, &offset);
            let needs = L::and(open, may_enter::<L, IDS>(metric.rank::<L, D>(&gaps), best.rank[N - 1]));
            if L::any(needs) {
                let sh: [L::F; D] = per_axis(|a| L::sub(at.f[a], L::f(offset[a] as f32 * UNIT)));
                kernel.visit::<L, M, IDS, DELTAS>(metric, kernel.hash::<L>(t), sh, needs, best);
            }
        }
        let edge = metric.rank_of_distance::<L>(outside::<L, D>(&at.f, r as f32 * UNIT));
        open = L::and(open, may_enter::<L, IDS>(edge, best.rank[N - 1]));
        if !L::any(open) {
            return;
        }
    }
    // Uncertified after MAX_SHELLS (never seen for valid configurations):
    // NaN rather than a possibly wrong value.
    for k in 0..N {
        best.rank[k] = L::select(open, L::f(f32::NAN), best.rank[k]);
    }
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Visits one cell for the lanes in `needs`: `h` is its hash, `shifted`
    /// the sample minus the cell's corner, per lane.
    #[inline(always)]
    pub(super) fn visit<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        h: L::U,
        shifted: [L::F; D],
        needs: L::M,
        best: &mut Best<L, D, N>,
    ) {
        // Points are produced in index order while some lane that needs the
        // cell has one more.
        let top = self.population::<L>(h);
        for p in &self.points {
            let active = L::and(needs, L::lt(self.key::<L>(p), top));
            if !L::any(active) {
                break;
            }
            self.point::<L, M, IDS, DELTAS>(metric, p, h, shifted, active, best);
        }
    }
}

/// The 3^d block in the mirrored frame (−1 is the near side), ordered by the
/// number of far axes, then of near axes: own cell, the near cells, then the
/// far ones.
pub(super) fn logical_block<const D: usize>() -> Vec<[i64; D]> {
    let mut block = shell::<D>(1);
    block.push([0; D]);
    block.sort_by_key(|o| {
        let far = o.iter().filter(|&&v| v > 0).count();
        let near = o.iter().filter(|&&v| v < 0).count();
        (far, near, *o)
    });
    block
}

/// Whether a candidate at rank `bound` or beyond may still enter the list
/// whose last rank is `last`: strictly below without IDs, and also at equal
/// rank with IDs, where a tie is decided by the ID.
#[inline(always)]
pub(super) fn may_enter<L: Lanes, const IDS: bool>(bound: L::F, last: L::F) -> L::M {
    if IDS {
        L::le(bound, last)
    } else {
        L::lt(bound, last)
    }
}

/// Per axis, the gap between the sample (its fraction `f` of its cell, per
/// lane) and the cell at `offset` from its own, in lane units: zero on an
/// axis where the offset is zero. The widening's test of a cell, and the
/// border's, which must visit the cells the widening visits.
#[inline(always)]
pub(super) fn far_gaps<L: Lanes, const D: usize>(f: &[L::F; D], offset: &[i64; D]) -> [L::F; D] {
    per_axis(|a| {
        let o = offset[a];
        if o > 0 {
            L::sub(L::f(o as f32 * UNIT), f[a])
        } else if o < 0 {
            L::sub(f[a], L::f((o + 1) as f32 * UNIT))
        } else {
            L::f(0.0)
        }
    })
}

/// B_r per lane: distance from the sample to the outside of the block of
/// Chebyshev radius r.
#[inline(always)]
pub(super) fn outside<L: Lanes, const D: usize>(f: &[L::F; D], r: f32) -> L::F {
    let mut b = L::f(f32::INFINITY);
    for fa in f {
        b = L::min(b, L::min(L::add(*fa, L::f(r)), L::sub(L::f(r + UNIT), *fa)));
    }
    b
}

pub(super) fn mark_invalid<L: Lanes, const D: usize, const N: usize>(best: &mut Best<L, D, N>, valid: &[bool; WIDEST]) {
    let mut bad = [0f32; WIDEST];
    for (b, v) in bad.iter_mut().zip(valid) {
        *b = if *v { 0.0 } else { 1.0 };
    }
    let bad = L::lt(L::f(0.5), L::f_load(&bad[..L::N]));
    for k in 0..N {
        best.rank[k] = L::select(bad, L::f(f32::NAN), best.rank[k]);
        best.id[k] = L::select_u(bad, L::u(INVALID_ID), best.id[k]);
        for a in 0..D {
            best.delta[k][a] = L::select(bad, L::f(f32::NAN), best.delta[k][a]);
        }
    }
}
