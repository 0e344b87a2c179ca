//! What the batch calls read and write per sample: any point type
//! ([`Point`]) in, a finished result's lanes out ([`write_lanes`]). The
//! grid calls' points are a [`Grid`](super::grid::Grid), and what their
//! tiles write per sample is [`GridSample`](super::tiles::GridSample).

use super::best::Best;
use super::lanes::{Lanes, WIDEST};
use super::Features32;
use crate::definition::INVALID_ID;

/// A sample position the kernel accepts, converted to f64 user units.
pub trait Point<const D: usize>: Copy {
    /// The coordinates in f64 (exact for every implementor here).
    fn coordinates(&self) -> [f64; D];
}

impl<const D: usize> Point<D> for [f64; D] {
    #[inline(always)]
    fn coordinates(&self) -> [f64; D] {
        *self
    }
}

impl<const D: usize> Point<D> for [f32; D] {
    #[inline(always)]
    fn coordinates(&self) -> [f64; D] {
        self.map(f64::from)
    }
}

macro_rules! glam_point {
    ($d:literal, $($t:ty),*) => {$(
        impl Point<$d> for $t {
            #[inline(always)]
            fn coordinates(&self) -> [f64; $d] {
                self.to_array().map(f64::from)
            }
        }
    )*};
}
glam_point!(2, glam::Vec2, glam::DVec2);
glam_point!(3, glam::Vec3, glam::Vec3A, glam::DVec3);
glam_point!(4, glam::Vec4, glam::DVec4);

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
