//! The periodic (tileable) variant of the SIMD kernel.
//!
//! A periodic pattern repeats every `period[a]` cells along axis `a`: the
//! feature points of cell `c` are those of cell `c mod period` of the
//! ordinary pattern, shifted back by whole periods. Feature IDs come from
//! the wrapped cell's hash, so a point keeps its ID across the wrap. The
//! search is the ordinary certified search over this periodic point set,
//! so the result is exact in the same sense as everywhere else.
//!
//! Periodic samples are addressed in **cells** (lattice units), not in user
//! units: a period of `P` cells is then the whole number `P` in the input,
//! and a coordinate is reduced with `x mod P`, which is exact in f64. Hence
//! `F(x + k·P)` is bit-identical to `F(x)` whenever `x + k·P` is itself
//! exact. Distances and deltas are in user units, as in the rest of the
//! crate (mean F1 = 1); multiply a user coordinate by
//! [`Pattern::scale`](crate::Pattern::scale) to get cells.

use super::generate::UNIT;
use super::locate::Located;
use super::{Features32, Features8, Simd};
use crate::simd::lanes::{Eight, Lanes, One, WIDEST};

/// The largest period per axis, in cells (2^24: a reduced coordinate keeps
/// at least 29 fraction bits in f64).
pub const MAX_PERIOD: u32 = 1 << 24;

/// A validated period: whole cells per axis, 1 to [`MAX_PERIOD`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Period<const D: usize>([u32; D]);

/// A period that cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeriodError {
    /// The axis whose period is out of range.
    pub axis: usize,
    /// The period given.
    pub given: u64,
}

impl std::fmt::Display for PeriodError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "period {} on axis {} is invalid: use whole cells from 1 to {}", self.given, self.axis, MAX_PERIOD)
    }
}

impl std::error::Error for PeriodError {}

impl<const D: usize> Period<D> {
    /// Cells per axis.
    ///
    /// # Errors
    /// [`PeriodError`] for a period of 0 or above [`MAX_PERIOD`].
    pub fn new(cells: [u32; D]) -> Result<Self, PeriodError> {
        match cells.iter().position(|&p| p == 0 || p > MAX_PERIOD) {
            Some(axis) => Err(PeriodError { axis, given: u64::from(cells[axis]) }),
            None => Ok(Period(cells)),
        }
    }

    /// Cells per axis.
    pub fn cells(&self) -> [u32; D] {
        self.0
    }
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// One sample of the periodic pattern, `x` in cells. A non-finite
    /// coordinate gives the invalid result (NaN distances,
    /// [`INVALID_ID`](crate::INVALID_ID)).
    ///
    /// ```
    /// use worley::{Config, Outputs, Period, Simd};
    /// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Ids).unwrap();
    /// let period = Period::new([8, 8]).unwrap();
    /// let (a, b) = (basis.evaluate_periodic([1.25, 3.5], &period), basis.evaluate_periodic([9.25, -4.5], &period));
    /// assert_eq!((a.distance, a.id), (b.distance, b.id)); // one period apart
    /// ```
    pub fn evaluate_periodic(&self, x: [f64; D], period: &Period<D>) -> Features32<D, N> {
        let located = wrap::<One, D>(&[x], period);
        let best = self.dispatch_one(&located).0;
        Features32 { distance: best.rank, delta: best.delta, id: best.id }
    }

    /// Eight samples of the periodic pattern, `x` in cells; lane `i` is
    /// bit-identical to [`Simd::evaluate_periodic`] of `x[i]`.
    ///
    /// ```
    /// use worley::{Config, Outputs, Period, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let period = Period::new([4, 4, 4]).unwrap();
    /// let points: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64 * 0.5, 1.0, 2.0]);
    /// let f = basis.evaluate8_periodic(&points, &period);
    /// assert_eq!(f.distance[0].to_array()[1], basis.evaluate_periodic(points[1], &period).distance[0]);
    /// ```
    pub fn evaluate8_periodic(&self, x: &[[f64; D]; 8], period: &Period<D>) -> Features8<D, N> {
        let located = wrap::<Eight, D>(x, period);
        let best = self.dispatch8(&located);
        Features8 { distance: best.rank, delta: best.delta, id: best.id }
    }
}

/// Lanes reduced into the period: r = x mod P (exact), the cell ⌊r⌋ and the
/// fraction r − ⌊r⌋ (exact), the cell wrapped once more in case the
/// remainder of a tiny negative x rounded up to P.
pub(super) fn wrap<L: Lanes, const D: usize>(xs: &[[f64; D]], period: &Period<D>) -> Located<L, D> {
    let p = period.0.map(i64::from);
    let mut cell = [[0i64; WIDEST]; D];
    let mut f = [[0f32; WIDEST]; D];
    let mut valid = [false; WIDEST];
    for (i, x) in xs.iter().enumerate().take(L::N) {
        if x.iter().all(|v| v.is_finite()) {
            valid[i] = true;
            for a in 0..D {
                let r = x[a].rem_euclid(p[a] as f64);
                let floor = r.floor();
                cell[a][i] = (floor as i64).rem_euclid(p[a]);
                f[a][i] = (r - floor) as f32 * UNIT;
            }
        }
    }
    Located::wrapped(cell, &f, valid, Some(p))
}
