//! The sorted list of the n best candidates per lane ([`Best`]): every
//! path of the kernel inserts its candidates here, in the crate's order
//! (rank, then ID), so the result does not depend on the order they arrive
//! in.

use super::lanes::Lanes;
use crate::definition::INVALID_ID;

/// The n best candidates per lane.
#[derive(Clone, Copy)]
pub(super) struct Best<L: Lanes, const D: usize, const N: usize> {
    pub(super) rank: [L::F; N],
    pub(super) delta: [[L::F; D]; N],
    pub(super) id: [L::U; N],
}

impl<L: Lanes, const D: usize, const N: usize> Best<L, D, N> {
    /// No candidate yet: ranks +∞, zero deltas, [`INVALID_ID`].
    #[inline(always)]
    pub(super) fn empty() -> Self {
        Best { rank: [L::f(f32::INFINITY); N], delta: [[L::f(0.0); D]; N], id: [L::u(INVALID_ID); N] }
    }

    /// Back to [`Best::empty`], writing only what the outputs use (the
    /// others are never changed from it).
    #[inline(always)]
    pub(super) fn reset<const IDS: bool, const DELTAS: bool>(&mut self) {
        self.rank = [L::f(f32::INFINITY); N];
        if IDS {
            self.id = [L::u(INVALID_ID); N];
        }
        if DELTAS {
            self.delta = [[L::f(0.0); D]; N];
        }
    }

    /// Inserts one candidate per lane (rank +∞ in lanes that have none).
    /// With IDs the order is the crate's canonical one, rank then ID (see
    /// [`reference`](crate::reference)), so the result does not depend on
    /// the order points arrive in; a lane without a candidate must then
    /// carry [`INVALID_ID`], which nothing precedes. Without IDs only the
    /// sorted ranks are reported, and those do not depend on the order.
    #[inline(always)]
    pub(super) fn insert<const IDS: bool, const DELTAS: bool>(&mut self, rank: L::F, delta: [L::F; D], id: L::U) {
        let (mut r, mut d, mut i) = (rank, delta, id);
        if !IDS && !DELTAS {
            // The same choice as below, as a minimum and a maximum.
            for k in 0..N {
                let kept = self.rank[k];
                self.rank[k] = L::min(kept, r);
                r = L::max(r, kept);
            }
            return;
        }
        for k in 0..N {
            let lt = if IDS {
                L::or(L::lt(r, self.rank[k]), L::and(L::eq(r, self.rank[k]), L::u_lt(i, self.id[k])))
            } else {
                L::lt(r, self.rank[k])
            };
            let kept = self.rank[k];
            self.rank[k] = L::select(lt, r, kept);
            r = L::select(lt, kept, r);
            if DELTAS {
                for (slot, cand) in self.delta[k].iter_mut().zip(d.iter_mut()) {
                    let kept = *slot;
                    *slot = L::select(lt, *cand, kept);
                    *cand = L::select(lt, kept, *cand);
                }
            }
            if IDS {
                let kept = self.id[k];
                self.id[k] = L::select_u(lt, i, kept);
                i = L::select_u(lt, kept, i);
            }
        }
    }
}
