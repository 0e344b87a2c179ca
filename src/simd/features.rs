//! What the per-sample kernel returns: one sample's features
//! ([`Features32`]) and eight samples' in lanes ([`Features8`]).

use wide::{f32x8, u32x8};

use crate::definition::INVALID_ID;

/// F1..Fn of one sample, in f32.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Features32<const D: usize, const N: usize> {
    /// F_k at index k − 1, user units; NaN for bad input.
    pub distance: [f32; N],
    /// Vector from the k-th closest point to the sample (zero when not asked for).
    pub delta: [[f32; D]; N],
    /// The k-th closest point's ID ([`INVALID_ID`] when not asked for or bad input).
    pub id: [u32; N],
}

/// F1..Fn of eight samples, one per lane.
#[derive(Clone, Copy, Debug)]
pub struct Features8<const D: usize, const N: usize> {
    /// F_k at index k − 1.
    pub distance: [f32x8; N],
    /// Delta vectors per axis.
    pub delta: [[f32x8; D]; N],
    /// Feature IDs.
    pub id: [u32x8; N],
}

/// No feature point found: distances +∞, zero deltas, [`INVALID_ID`], what
/// a window-mode search reports for an F_k its block lacks. A value to fill
/// the buffers of the slice and grid calls with.
///
/// ```
/// use worley::{Features32, Simd, Config, Outputs};
/// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Ids).unwrap();
/// let mut out = vec![Features32::<2, 1>::default(); 4];
/// basis.evaluate_slice(&[[0.5, 0.5]; 4], &mut out).unwrap();
/// assert_eq!(out[3], basis.evaluate([0.5, 0.5]));
/// ```
impl<const D: usize, const N: usize> Default for Features32<D, N> {
    fn default() -> Self {
        Features32 { distance: [f32::INFINITY; N], delta: [[0.0; D]; N], id: [INVALID_ID; N] }
    }
}

/// Every lane [`Features32::default`].
impl<const D: usize, const N: usize> Default for Features8<D, N> {
    fn default() -> Self {
        Features8 {
            distance: [f32x8::splat(f32::INFINITY); N],
            delta: [[f32x8::splat(0.0); D]; N],
            id: [u32x8::splat(INVALID_ID); N],
        }
    }
}

impl<const D: usize, const N: usize> Features8<D, N> {
    /// Lane `i` (0..8), as [`lane`] gives it.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Ids).unwrap();
    /// let points: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64 * 0.3, 0.1, 2.0]);
    /// let f = basis.evaluate8(&points);
    /// assert_eq!(f.lane(5), basis.evaluate(points[5]));
    /// assert_eq!(f.lanes()[7], f.lane(7));
    /// ```
    pub fn lane(&self, i: usize) -> Features32<D, N> {
        lane(self, i)
    }

    /// Every lane.
    pub fn lanes(&self) -> [Features32<D, N>; 8] {
        std::array::from_fn(|i| lane(self, i))
    }

    /// One sample's features in all eight lanes.
    pub fn splat(f: &Features32<D, N>) -> Self {
        Features8 {
            distance: f.distance.map(f32x8::splat),
            delta: f.delta.map(|d| d.map(f32x8::splat)),
            id: f.id.map(u32x8::splat),
        }
    }
}

/// Lane `i` of an 8-lane result.
pub fn lane<const D: usize, const N: usize>(r: &Features8<D, N>, i: usize) -> Features32<D, N> {
    Features32 {
        distance: r.distance.map(|v| v.to_array()[i]),
        delta: r.delta.map(|d| d.map(|v| v.to_array()[i])),
        id: r.id.map(|v| v.to_array()[i]),
    }
}
