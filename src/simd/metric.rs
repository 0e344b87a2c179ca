//! The metrics in lanes: one term per axis, folded into a rank.

use std::cell::Cell;

use super::lanes::{Lanes, WIDEST};
use crate::config::Metric;

pub(super) fn distance_of_rank<L: Lanes>(metric: Metric, r: L::F) -> L::F {
    match metric {
        Metric::Euclidean => L::sqrt(r),
        Metric::Manhattan | Metric::Chebyshev | Metric::Minkowski(_) => r,
    }
}

/// Applies a scalar function of D lanes' values to every lane.
#[inline(always)]
fn per_lane<L: Lanes, const D: usize>(v: &[L::F; D], f: impl Fn([f32; D]) -> f32) -> L::F {
    let mut a = [[0f32; WIDEST]; D];
    for (lanes, x) in a.iter_mut().zip(v) {
        L::f_store(*x, &mut lanes[..L::N]);
    }
    let mut out = [0f32; WIDEST];
    for (i, o) in out.iter_mut().enumerate().take(L::N) {
        *o = f(std::array::from_fn(|k| a[k][i]));
    }
    L::f_load(&out[..L::N])
}

/// A metric in lanes; the rank is the reference's (squared distance for
/// Euclidean, the distance itself otherwise): the fold of one term per axis.
pub trait Metric32: Copy {
    /// One axis's term of the rank: x², |x| or |x|^p.
    fn term<L: Lanes>(&self, x: L::F) -> L::F;
    /// Combines two partial ranks: a sum, or a maximum for Chebyshev.
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F;
    /// [`Metric32::fold`] of the value in `a[k]` (in every lane) and `b`, the
    /// same bits; a sum is computed by [`Lanes::broadcast_add_on_fma`]
    /// (`one` is 1 in every lane).
    #[inline(always)]
    fn fold_on_fma<L: Lanes>(&self, (a, k): (&[Cell<f32>; WIDEST], usize), b: L::F, one: L::F) -> L::F {
        let _ = one;
        self.fold::<L>(L::f(a[k].get()), b)
    }
    /// Rank of a length.
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F;
    /// Whether [`Metric32::rank`] is, bit for bit, axis 0's term folded
    /// into [`Metric32::rest`]: then a row of samples along axis 0 shares
    /// the rest of every candidate (the coherent path relies on it).
    const SPLITS: bool = true;
    /// [`Metric32::SPLITS`] for this value of the metric: a metric chosen at
    /// run time answers per value.
    #[inline(always)]
    fn splits(&self) -> bool {
        Self::SPLITS
    }
    /// Rank of a vector: the terms of axes 1, 2, … folded in order
    /// ([`Metric32::rest`]), then axis 0's term folded in last.
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let first = self.term::<L>(v[0]);
        if D == 1 {
            return first;
        }
        self.fold::<L>(self.rest::<L, D>(v), first)
    }
    /// The terms of axes 1, 2, … folded in order; `v[0]` is not read.
    /// Needs D ≥ 2.
    #[inline(always)]
    fn rest<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let mut s = self.term::<L>(v[1]);
        for x in &v[2..] {
            s = self.fold::<L>(s, self.term::<L>(*x));
        }
        s
    }
}

/// Euclidean in lanes.
#[derive(Clone, Copy, Debug)]
pub struct Euclid;
/// Manhattan in lanes.
#[derive(Clone, Copy, Debug)]
pub struct Manhattan;
/// Chebyshev in lanes.
#[derive(Clone, Copy, Debug)]
pub struct Chebyshev;
/// Minkowski in lanes: the rank is the distance itself, computed per lane in
/// f64 scaled by the largest component (see [`Metric::rank`]), so that no
/// power overflows or underflows for any p ≥ 1, and rounded to f32 once.
#[derive(Clone, Copy, Debug)]
pub struct Minkowski(pub f64);

/// Manhattan, Chebyshev and Minkowski as one type, the metric chosen at
/// run time: the kernel instantiated once for the three rarer metrics
/// instead of once each (each instantiation of the search is a sizeable
/// part of a build). Every value runs the operations of its own type
/// above ([`Manhattan`], [`Chebyshev`], [`Minkowski`]), so the bits are
/// theirs; the choice is a branch on a value that never changes within a
/// call.
#[derive(Clone, Copy, Debug)]
pub(super) enum Others {
    /// As [`Manhattan`].
    Manhattan,
    /// As [`Chebyshev`].
    Chebyshev,
    /// As [`Minkowski`].
    Minkowski(f64),
}

impl Others {
    /// The metric in lanes for a configuration's metric other than
    /// Euclidean; `None` for Euclidean.
    pub(super) fn of(metric: Metric) -> Option<Self> {
        match metric {
            Metric::Euclidean => None,
            Metric::Manhattan => Some(Others::Manhattan),
            Metric::Chebyshev => Some(Others::Chebyshev),
            Metric::Minkowski(p) => Some(Others::Minkowski(p)),
        }
    }
}

impl Metric32 for Others {
    #[inline(always)]
    fn splits(&self) -> bool {
        !matches!(self, Others::Minkowski(_))
    }
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::abs(x)
    }
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        match *self {
            Others::Manhattan => Manhattan.fold::<L>(a, b),
            Others::Chebyshev => Chebyshev.fold::<L>(a, b),
            Others::Minkowski(p) => Minkowski(p).fold::<L>(a, b),
        }
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        match *self {
            Others::Manhattan => Manhattan.rank::<L, D>(v),
            Others::Chebyshev => Chebyshev.rank::<L, D>(v),
            Others::Minkowski(p) => Minkowski(p).rank::<L, D>(v),
        }
    }
}

impl Metric32 for Euclid {
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::mul(x, x)
    }
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        L::add(a, b)
    }
    #[inline(always)]
    fn fold_on_fma<L: Lanes>(&self, (a, k): (&[Cell<f32>; WIDEST], usize), b: L::F, one: L::F) -> L::F {
        L::broadcast_add_on_fma(a, k, b, one)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        L::mul(d, d)
    }
}

impl Metric32 for Manhattan {
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::abs(x)
    }
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        L::add(a, b)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
}

impl Metric32 for Chebyshev {
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::abs(x)
    }
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        L::max(a, b)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
}

impl Metric32 for Minkowski {
    /// The rank is computed from the whole vector at once.
    const SPLITS: bool = false;
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::abs(x)
    }
    /// The Lp length of the pair (a, b), each itself an Lp length of some
    /// axes, so folding the axes' terms in order gives the vector's length.
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        let p = self.0;
        per_lane::<L, 2>(&[a, b], |v| Metric::Minkowski(p).rank(&v.map(f64::from)) as f32)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let p = self.0;
        per_lane::<L, D>(v, |v| Metric::Minkowski(p).rank(&v.map(f64::from)) as f32)
    }
}
