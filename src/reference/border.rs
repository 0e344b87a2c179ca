//! # The distance to the border of the sample's cell
//!
//! The Voronoi cell of F1's point p₁ is the set of positions closer to p₁
//! than to any other feature point. In the Euclidean metric it is the
//! intersection of half-spaces, one per other point p_j, bounded by the
//! bisector plane of p₁ and p_j. The cell is convex and the sample lies
//! inside it, so the distance from the sample x to the cell's border is the
//! distance to the nearest of those planes:
//!
//! border(x) = min over j of b_j, b_j = u_j · (m_j − x) / |u_j|,
//!
//! with u_j = p_j − p₁ and m_j = (p₁ + p_j) / 2 the plane's normal and a point
//! on it. Unlike F2 − F1, whose width follows the spacing of the two nearest
//! points, it grows at the same rate, 1 per unit, from every border:
//! even mortar lines between cells, whatever the spacing of the points.
//!
//! ## Certification
//! |u_j| ≤ |x − p₁| + |x − p_j| = F1 + F_j, so b_j = (F_j² − F1²) / (2|u_j|)
//! ≥ (F_j − F1) / 2. A point can therefore only lower the border below its
//! current value b if F_j < F1 + 2b. The search visits the sample's cell, then
//! Chebyshev shells of cells, skipping a cell whose nearest possible point
//! is farther than F1 + 2b, and stops once the outside of the block covered
//! is farther than F1 + 2b: no unvisited point can then reach b, not even
//! tie it. Both tests carry a relative slack of 2^−40 on the side of
//! visiting more, so rounding in them can only cost time.
//!
//! ## Rounding
//! Positions are exact in f64 (a small integer plus a 24-bit fraction), so
//! u_j and m_j are exact; each b_j then has a few roundings of relative size
//! ε_f64 in the dot product and the square root.
//!
//! ## Ties, coincident points, other metrics
//! Of two planes at the same distance the one to the point with the smaller
//! ID is reported, the crate's order for ties. A point at exactly p₁'s
//! position (u_j = 0; a chance of about 2^−24·d per pair in one cell) has no
//! bisector and is skipped: the two share one cell. Under the Manhattan,
//! Chebyshev and Minkowski metrics bisectors are not planes (in L1 and L∞
//! they can even contain whole regions), so no formula of this kind is
//! exact there: [`Reference::border`] refuses them with
//! [`ConfigError::BorderMetric`].

use super::{gaps, outside_distance, shell, valid_in_cell, Reference, MAX_SHELLS};
use crate::config::{ConfigError, Metric, Mode};
use crate::definition::INVALID_ID;

/// Relative slack of the skip and stop tests (see the module's text).
const SLACK: f64 = 1.0 + 1.0 / (1u64 << 40) as f64;

/// The distance from a sample to the border of its Voronoi cell (the cell
/// of F1's point), with the IDs on both sides and the border's normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Border<const D: usize> {
    /// The distance to the nearest bisector plane, in user units: 0 on the
    /// border, growing at 1 per unit inside the cell. NaN for bad input,
    /// +∞ in window mode when the 3^d block holds fewer than two points.
    pub distance: f64,
    /// The gradient of `distance`: the unit normal of that plane, pointing
    /// from the neighbour's side into the sample's cell. NaN where
    /// `distance` is not finite.
    pub normal: [f64; D],
    /// The ID of F1's point, whose cell holds the sample.
    pub feature: u32,
    /// The ID of the point across the nearest border.
    pub neighbour: u32,
    /// The Chebyshev radius of the block of cells searched, for F1 or for the
    /// border, whichever went farther (0 for bad input).
    pub shells: u32,
}

impl<const D: usize> Border<D> {
    /// The documented result for bad input: NaN distance and normal,
    /// [`INVALID_ID`] on both sides.
    pub fn invalid() -> Self {
        Border { distance: f64::NAN, normal: [f64::NAN; D], feature: INVALID_ID, neighbour: INVALID_ID, shells: 0 }
    }
}

impl<const D: usize> Reference<D> {
    /// The distance from `x` (user units) to the border of its Voronoi
    /// cell, exact by certification in [`Mode::Exact`] (see the
    /// [module's text](self)). The configuration's order does not matter.
    ///
    /// # Errors
    /// [`ConfigError::BorderMetric`] unless the metric is Euclidean. Bad
    /// input is not an error: it gives [`Border::invalid`].
    ///
    /// ```
    /// use worley::{Config, Reference};
    /// let basis = Reference::<2>::new(Config { order: 2, ..Config::default() }).unwrap();
    /// let x = [3.25, -7.5];
    /// let (b, f) = (basis.border(x).unwrap(), basis.evaluate(x));
    /// // Every bisector is at least (F2 − F1) / 2 away.
    /// assert!(b.distance >= 0.5 * (f.distance[1] - f.distance[0]) - 1e-12);
    /// assert_eq!(b.feature, f.id[0]);
    /// ```
    pub fn border(&self, x: [f64; D]) -> Result<Border<D>, ConfigError> {
        self.border_metric()?;
        Ok(match self.pattern.locate(x) {
            Some((cell, fraction)) => self.border_of(cell, fraction),
            None => Border::invalid(),
        })
    }

    /// [`Reference::border`] at `cell + fraction` (cell units), as
    /// [`Reference::evaluate_in_cell`] takes it.
    ///
    /// # Errors
    /// [`ConfigError::BorderMetric`] unless the metric is Euclidean.
    pub fn border_in_cell(&self, cell: [i64; D], fraction: [f64; D]) -> Result<Border<D>, ConfigError> {
        self.border_metric()?;
        Ok(if valid_in_cell(&cell, &fraction) { self.border_of(cell, fraction) } else { Border::invalid() })
    }

    fn border_metric(&self) -> Result<(), ConfigError> {
        match self.config.metric {
            Metric::Euclidean => Ok(()),
            other => Err(ConfigError::BorderMetric(other)),
        }
    }

    fn border_of(&self, cell: [i64; D], f: [f64; D]) -> Border<D> {
        let (nearest, searched, gave_up) = self.search(cell, f, 1);
        if gave_up {
            return Border::invalid();
        }
        let (f1, p1, feature) = (nearest.rank[0].sqrt(), nearest.point[0], nearest.id[0]);
        let mut best =
            Border { distance: f64::INFINITY, normal: [f64::NAN; D], feature, neighbour: INVALID_ID, shells: searched };
        if !f1.is_finite() {
            // Window mode, and the 3^d block is empty.
            return best;
        }
        let visit = |offset: [i64; D], best: &mut Border<D>| {
            let reach = (f1 + 2.0 * best.distance) * SLACK;
            if Metric::Euclidean.rank(&gaps(&f, &offset)) > reach * reach {
                return;
            }
            self.for_each_point_at(cell, offset, |point, id| {
                let u: [f64; D] = std::array::from_fn(|a| point[a] - p1[a]);
                let length = Metric::Euclidean.rank(&u).sqrt();
                if length == 0.0 {
                    return;
                }
                let along: f64 = (0..D).map(|a| u[a] * (0.5 * (p1[a] + point[a]) - f[a])).sum();
                // Ties with a later ID may round to a hair below zero.
                let b = (along / length).max(0.0);
                if (b, id) < (best.distance, best.neighbour) {
                    best.distance = b;
                    best.neighbour = id;
                    best.normal = u.map(|v| -v / length);
                }
            });
        };
        visit([0; D], &mut best);
        let mut r = 0;
        loop {
            let reach = (f1 + 2.0 * best.distance) * SLACK;
            if self.config.mode == Mode::Window && r == 1
                || self.config.mode == Mode::Exact && reach < outside_distance(&f, r)
            {
                break;
            }
            if r == MAX_SHELLS {
                return Border::invalid();
            }
            r += 1;
            for offset in shell(r) {
                visit(offset, &mut best);
            }
        }
        best.shells = r.max(searched);
        best.distance /= self.pattern.scale();
        best
    }
}
