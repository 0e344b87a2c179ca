//! The border's search: F1's point met again, then every cell that can
//! hold a point whose bisector plane with it lies within F1 + 2b, nearest
//! first, the same in every lane set; and the frame of cells around a
//! lane's own.

use wide::f32x8;

use super::super::best::Best;
use super::super::generate::{words, UNIT};
use super::super::lanes::{Eight, Lanes, WIDEST};
use super::super::locate::Located;
use super::super::search::{far_gaps, outside};
use super::super::{per_axis, Simd};
use super::{Plane, SLACK};
use crate::config::Mode;
use crate::definition::FRACTION_BITS;
use crate::reference::{shell, MAX_SHELLS};

impl<const D: usize> Simd<D, 1> {
    /// Lanes of valid input (the others get NaN and [`INVALID_ID`](crate::INVALID_ID)).
    #[inline(always)]
    pub(super) fn good_lanes<L: Lanes>(&self, at: &Located<L, D>) -> L::M {
        let mut valid = [0f32; WIDEST];
        for (v, ok) in valid.iter_mut().zip(&at.valid) {
            *v = if *ok { 1.0 } else { 0.0 };
        }
        L::lt(L::f(0.5), L::f_load(&valid[..L::N]))
    }

    /// [`Simd::border_search`] in eight lanes, through its AVX2 copy where
    /// this build lacks AVX2 and the CPU has it, as the kernel's own eight
    /// lanes run ([`Simd::dispatch8_stage`]): the same operations, so the
    /// same bits.
    #[inline(always)]
    pub(super) fn border_search8(
        &self,
        at: &Located<Eight, D>,
        nearest: &Best<Eight, D, 1>,
    ) -> (Plane<Eight, D>, f32x8) {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if super::super::runtime_avx2() {
            // SAFETY: `border_search_avx2` requires AVX2 and nothing else,
            // and `runtime_avx2` has just seen the CPU report it.
            #[allow(unsafe_code)]
            return unsafe { border_search_avx2(self, at, nearest) };
        }
        self.border_search::<Eight>(at, nearest)
    }
}

/// [`Simd::border_search`] compiled with AVX2 enabled (see
/// [`dispatch_avx2`](super::super::entry::dispatch_avx2)): in a default build `wide`'s 32-bit lane
/// multiply of the point generator is a scalar fallback, which LLVM
/// lowers to one instruction here.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
#[target_feature(enable = "avx2")]
pub(super) fn border_search_avx2<const D: usize>(
    kernel: &Simd<D, 1>,
    at: &Located<Eight, D>,
    nearest: &Best<Eight, D, 1>,
) -> (Plane<Eight, D>, f32x8) {
    kernel.border_search::<Eight>(at, nearest)
}

impl<const D: usize> Simd<D, 1> {
    /// The nearest bisector plane between F1's point (`nearest`, as the
    /// kernel holds it: squared rank and delta in lane units) and any other
    /// point, per lane; lanes whose F1's point was not met again are left
    /// out of the mask returned (never seen: it is met where the kernel met
    /// it). Lanes without an F1 (NaN, or +∞ in an empty window) are in it
    /// and keep b = +∞.
    #[inline(always)]
    pub(super) fn border_search<L: Lanes>(&self, at: &Located<L, D>, nearest: &Best<L, D, 1>) -> (Plane<L, D>, L::M) {
        let f1 = L::sqrt(nearest.rank[0]);
        let mut plane = Plane::none();
        // Lanes with an F1 (not NaN, not +∞ from an empty window); the
        // others have no point to find and keep b = +∞.
        let mut open = L::lt(f1, L::f(f32::INFINITY));
        if !L::any(open) {
            return (plane, L::eq(f1, f1));
        }
        let frame = Frame::<L, D>::new(at);
        let cell = at.cells_i64();
        let (p1, found) = self.find_nearest::<L>(at, &frame, &cell, nearest, open);
        open = L::and(open, found);
        let reach = |plane: &Plane<L, D>| {
            let b = plane.distance();
            let r = L::mul(L::add(f1, L::add(b, b)), L::f(SLACK));
            L::mul(r, r)
        };
        for offset in &self.block {
            let c = frame.cell(offset);
            let limit = reach(&plane);
            let needs = L::and(open, L::le(c.rank, limit));
            if L::any(needs) {
                self.border_cell::<L>(&c, needs, limit, nearest, &p1, &mut plane);
            }
        }
        if self.config.mode == Mode::Window {
            return (plane, found);
        }
        for r in 1..=MAX_SHELLS {
            let edge = outside::<L, D>(&at.f, r as f32 * UNIT);
            open = L::and(open, L::le(L::mul(edge, edge), reach(&plane)));
            if !L::any(open) {
                return (plane, found);
            }
            if r == MAX_SHELLS {
                break;
            }
            for offset in shell::<D>(r + 1) {
                let c = Frame::<L, D>::far_cell(at, &cell, &offset);
                let limit = reach(&plane);
                let needs = L::and(open, L::le(c.rank, limit));
                if L::any(needs) {
                    self.border_cell::<L>(&c, needs, limit, nearest, &p1, &mut plane);
                }
            }
        }
        // Uncertified after MAX_SHELLS (never seen for valid configurations):
        // NaN rather than a possibly wrong value.
        plane.key = L::select(open, L::f(f32::NAN), plane.key);
        (plane, found)
    }

    /// F1's point again, as an integer position relative to the sample's
    /// cell (lane units), so that u = p_j − p₁ is exact: it is the point of
    /// F1's ID whose delta has F1's bits, in a cell no farther than F1.
    #[inline(always)]
    pub(super) fn find_nearest<L: Lanes>(
        &self,
        at: &Located<L, D>,
        frame: &Frame<L, D>,
        cell: &[[i64; WIDEST]; D],
        nearest: &Best<L, D, 1>,
        open: L::M,
    ) -> ([L::U; D], L::M) {
        let limit = L::mul(nearest.rank[0], L::f(SLACK * SLACK));
        let mut p1 = [L::u(0); D];
        // 1 where the point is still to be found, as lanes of f32.
        let mut missing = L::select(open, L::f(1.0), L::f(0.0));
        let mut look = |c: &CellAt<L, D>, lanes: L::M, missing: &mut L::F| {
            let needs = L::and(lanes, L::and(L::lt(L::f(0.5), *missing), L::le(c.rank, limit)));
            if !L::any(needs) {
                return;
            }
            self.cell_points::<L>(c, needs, |active, q, id| {
                let mut same = L::and(active, L::u_eq(id, nearest.id[0]));
                for (a, qa) in q.iter().enumerate() {
                    same = L::and(same, L::eq(L::sub(c.shifted[a], L::u24_to_f(*qa)), nearest.delta[0][a]));
                }
                for a in 0..D {
                    p1[a] = L::select_u(same, L::u_add(c.corner[a], q[a]), p1[a]);
                }
                *missing = L::select(same, L::f(0.0), *missing);
            });
        };
        let all = L::lt(L::f(0.0), L::f(1.0));
        // First the one cell where the sample minus F1's delta falls, which
        // nearly always holds the point: lanes it does not settle (a point
        // beyond the neighbouring cells, or one that rounding put across a
        // face) search every cell within F1 below, as if it had not been
        // tried.
        let (guess, near) = Self::guess_cell::<L>(at, &nearest.delta[0]);
        look(&guess, near, &mut missing);
        if L::any(L::lt(L::f(0.5), missing)) {
            for offset in &self.block {
                look(&frame.cell(offset), all, &mut missing);
            }
        }
        for r in 2..=MAX_SHELLS {
            if !L::any(L::lt(L::f(0.5), missing)) {
                break;
            }
            for offset in shell::<D>(r) {
                look(&Frame::<L, D>::far_cell(at, cell, &offset), all, &mut missing);
            }
        }
        (p1, L::lt(missing, L::f(0.5)))
    }

    /// The cell of the 3^d block that holds the point at delta `delta` from
    /// each lane's sample (lane units), as [`Frame::cell`] gives it (its
    /// words, the sample minus its corner with the frame's bits, and the
    /// corner), with the lanes where that point lies within the block; its
    /// rank is 0, since the cell is tried whatever its distance.
    #[inline(always)]
    fn guess_cell<L: Lanes>(at: &Located<L, D>, delta: &[L::F; D]) -> (CellAt<L, D>, L::M) {
        let one = L::f(UNIT);
        let (up, down) = (L::u(1 << FRACTION_BITS), L::u((1u32 << FRACTION_BITS).wrapping_neg()));
        let mut inside = L::lt(L::f(0.0), L::f(1.0));
        let mut c = CellAt { rank: L::f(0.0), terms: [L::u(0); D], shifted: [L::f(0.0); D], corner: [L::u(0); D] };
        for (a, &d) in delta.iter().enumerate() {
            let f = at.f[a];
            let at_point = L::sub(f, d);
            let (below, above) = (L::lt(at_point, L::f(0.0)), L::le(one, at_point));
            inside = L::and(inside, L::and(L::le(L::f(-UNIT), at_point), L::lt(at_point, L::f(2.0 * UNIT))));
            let t = at.words[a];
            c.terms[a] = L::select_u(below, t[0], L::select_u(above, t[2], t[1]));
            c.shifted[a] = L::select(below, L::add(f, one), L::select(above, L::sub(f, one), f));
            c.corner[a] = L::select_u(below, down, L::select_u(above, up, L::u(0)));
        }
        (c, inside)
    }

    /// The points of cell `c` against the running plane, in the lanes of
    /// `needs` and within `reach` (squared, lane units², the lanes'
    /// F1 + 2b with the slack); `p1` is F1's point (see
    /// [`Simd::find_nearest`]).
    #[inline(always)]
    pub(super) fn border_cell<L: Lanes>(
        &self,
        c: &CellAt<L, D>,
        needs: L::M,
        reach: L::F,
        nearest: &Best<L, D, 1>,
        p1: &[L::U; D],
        plane: &mut Plane<L, D>,
    ) {
        let d1 = nearest.delta[0];
        self.cell_points::<L>(c, needs, |active, q, id| {
            let dj: [L::F; D] = per_axis(|a| L::sub(c.shifted[a], L::u24_to_f(q[a])));
            let mut rank = L::mul(dj[0], dj[0]);
            for d in &dj[1..] {
                rank = L::add(rank, L::mul(*d, *d));
            }
            // Only points within the lane's F1 + 2b can hold the nearest
            // plane (the reach test of the cells, point by point).
            let active = L::and(active, L::le(rank, reach));
            if !L::any(active) {
                return;
            }
            // u = p_j − p₁ exactly in integers, then rounded once;
            // b = u·(m − x) / |u| with m − x = −(δ₁ + δ_j) / 2, that is
            // b = k / (2|u|) with k = −u·(δ₁ + δ_j).
            let mut uu = L::f(0.0);
            let mut us = L::f(0.0);
            let mut u = [L::f(0.0); D];
            for a in 0..D {
                u[a] = L::i_to_f(L::u_sub(L::u_add(c.corner[a], q[a]), p1[a]));
                uu = L::add(uu, L::mul(u[a], u[a]));
                us = L::add(us, L::mul(u[a], L::add(d1[a], dj[a])));
            }
            plane.offer_point(active, us, uu, u, id);
        });
    }

    /// The points of cell `c` in the lanes of `needs`, in the generator's
    /// order: `visit` gets each point slot that some lane's population
    /// reaches, with those lanes, the point's coordinates in the cell (24
    /// bits, lane units) and its ID.
    #[inline(always)]
    pub(super) fn cell_points<L: Lanes>(
        &self,
        c: &CellAt<L, D>,
        needs: L::M,
        mut visit: impl FnMut(L::M, [L::U; D], L::U),
    ) {
        let h = self.hash::<L>(c.terms);
        let top = self.population::<L>(h);
        for p in &self.points {
            let active = L::and(needs, L::lt(self.key::<L>(p), top));
            if !L::any(active) {
                break;
            }
            visit(active, Self::coordinates_of::<L>(p, h), Self::id_of::<L>(p, h));
        }
    }
}

/// A cell around the lanes' samples, per lane: the squared gap from the
/// sample to it, its axis words, the sample minus its corner (f32) and its
/// corner relative to the sample's cell (integers), all in lane units.
pub(super) struct CellAt<L: Lanes, const D: usize> {
    pub(super) rank: L::F,
    pub(super) terms: [L::U; D],
    pub(super) shifted: [L::F; D],
    pub(super) corner: [L::U; D],
}

/// The 3^d block in the kernel's mirrored frame: per axis and offset + 1
/// (near, own, far), what [`CellAt`] holds, computed as the kernel's search
/// computes it, so a point's delta has the kernel's bits.
pub(super) struct Frame<L: Lanes, const D: usize> {
    pub(super) terms: [[L::U; 3]; D],
    pub(super) shifted: [[L::F; 3]; D],
    pub(super) gap: [[L::F; 3]; D],
    pub(super) corner: [[L::U; 3]; D],
}

impl<L: Lanes, const D: usize> Frame<L, D> {
    #[inline(always)]
    pub(super) fn new(at: &Located<L, D>) -> Self {
        let one = L::f(UNIT);
        let (up, down) = (L::u(1 << FRACTION_BITS), L::u((1u32 << FRACTION_BITS).wrapping_neg()));
        let mut frame = Frame {
            terms: [[L::u(0); 3]; D],
            shifted: [[L::f(0.0); 3]; D],
            gap: [[L::f(0.0); 3]; D],
            corner: [[L::u(0); 3]; D],
        };
        for a in 0..D {
            let f = at.f[a];
            let flip = L::lt(L::f(0.5 * UNIT), f);
            let t = at.words[a];
            frame.terms[a] = [L::select_u(flip, t[2], t[0]), t[1], L::select_u(flip, t[0], t[2])];
            let (below, above) = (L::add(f, one), L::sub(f, one));
            frame.shifted[a] = [L::select(flip, above, below), f, L::select(flip, below, above)];
            let rest = L::sub(one, f);
            let (near, far) = (L::select(flip, rest, f), L::select(flip, f, rest));
            frame.gap[a] = [L::mul(near, near), L::f(0.0), L::mul(far, far)];
            frame.corner[a] = [L::select_u(flip, up, down), L::u(0), L::select_u(flip, down, up)];
        }
        frame
    }

    /// The cell at `offset` of the mirrored block (−1 near, 0 own, +1 far).
    #[inline(always)]
    pub(super) fn cell(&self, offset: &[i64; D]) -> CellAt<L, D> {
        let index: [usize; D] = per_axis(|a| (offset[a] + 1) as usize);
        let mut rank = self.gap[0][index[0]];
        for (gap, i) in self.gap.iter().zip(index).skip(1) {
            rank = L::add(rank, gap[i]);
        }
        CellAt {
            rank,
            terms: per_axis(|a| self.terms[a][index[a]]),
            shifted: per_axis(|a| self.shifted[a][index[a]]),
            corner: per_axis(|a| self.corner[a][index[a]]),
        }
    }

    /// The cell at `offset` from the lanes' own cells (`cell`), beyond the
    /// 3^d block, as the kernel's widening computes it.
    #[inline(always)]
    pub(super) fn far_cell(at: &Located<L, D>, cell: &[[i64; WIDEST]; D], offset: &[i64; D]) -> CellAt<L, D> {
        let gaps = far_gaps::<L, D>(&at.f, offset);
        let mut rank = L::mul(gaps[0], gaps[0]);
        for g in &gaps[1..] {
            rank = L::add(rank, L::mul(*g, *g));
        }
        CellAt {
            rank,
            terms: per_axis(|a| words::<L>(a, &cell[a], offset[a], at.period.map(|p| p[a]))),
            shifted: per_axis(|a| L::sub(at.f[a], L::f(offset[a] as f32 * UNIT))),
            corner: per_axis(|a| L::u((offset[a] << FRACTION_BITS) as u32)),
        }
    }
}
