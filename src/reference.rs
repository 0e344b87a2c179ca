//! # The f64 reference kernel
//!
//! Plain loops, no SIMD, written to be read. It is the function every other
//! evaluator is judged against.
//!
//! ## Search
//! 1. Locate the sample: cell c = ⌊x·S⌋ and fraction f ∈ [0, 1]^d.
//! 2. Visit the sample's own cell, then the rest of the 3^d block nearest
//!    first (the 2d face neighbours, then edges, then corners, as Worley's
//!    code does). A cell is skipped when the nearest point of the cell is
//!    already farther than the current F_n: in any Lp metric that nearest
//!    distance is the norm of the per-axis gaps between f and the cell's
//!    extent (Worley's pruning, written for every metric at once).
//! 3. After the block of radius r (Chebyshev radius, r = 1 for the 3^d
//!    block), every unvisited cell lies outside the box
//!    [c − r, c + r + 1]^d, and in every Lp metric the distance from the
//!    sample to the outside of that box is B_r = min over axes of
//!    min(f_a + r, r + 1 − f_a), since moving along one axis has the same
//!    length in every Lp norm. If F_n < B_r no unvisited cell can hold a
//!    point as close, not even a tie, and the result is certified; otherwise
//!    the next shell of cells (Chebyshev radius r + 1) is searched, pruned
//!    the same way.
//!
//! In [`Mode::Window`] step 3 is skipped. Ranks ([`Metric::rank`]: squared
//! distances for Euclidean, the distance itself otherwise) are compared
//! instead of distances, so no square root is taken per candidate.
//!
//! **Ties.** Points are ordered by rank, then by ID: of two points at the
//! same rank the one with the smaller ID comes first, whatever order the
//! cells are visited in. So that no point that ties F_n is missed, a cell is
//! skipped only when its nearest possible point is strictly farther than
//! F_n, and the search stops only when F_n is strictly inside B_r. Every
//! evaluator of the crate follows this order, which is what lets paths that
//! visit points in different orders give the same IDs and deltas. (Two
//! distinct points with the same rank and the same ID, a chance of 2^−32
//! among ties, are reported in visiting order.)
//!
//! ## Bad input
//! A non-finite coordinate, or one with |x·S| > [`MAX_CELL_COORD`], gives
//! NaN distances and deltas and [`INVALID_ID`] for every order. The search
//! stops at Chebyshev radius [`MAX_SHELLS`]; a search that would need more
//! (it never happens for valid configurations: it needs an empty region of
//! hundreds of cells) reports the unfound orders as NaN rather than a wrong
//! value.

use crate::config::{Config, ConfigError, Metric, Mode, MAX_ORDER};
use crate::definition::{Pattern, INVALID_ID, MAX_CELL_COORD};

pub mod border;
pub mod smooth;
pub use border::Border;
pub use smooth::{NSphere, Smooth, SMOOTH_TOLERANCE};

/// The largest Chebyshev radius of cells an exact search visits.
pub const MAX_SHELLS: u32 = 16;

/// What an evaluation returns: F1..Fn, the delta vectors and the feature IDs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Features<const D: usize> {
    /// n, the number of valid leading entries below.
    pub order: usize,
    /// F_k for k = 1..n at index k − 1, in user units, ascending.
    pub distance: [f64; MAX_ORDER],
    /// The vector from the k-th closest feature point to the sample, in user
    /// units; its length in the metric is F_k.
    pub delta: [[f64; D]; MAX_ORDER],
    /// The ID of the k-th closest feature point.
    pub id: [u32; MAX_ORDER],
    /// The Chebyshev radius of the block of cells the search covered: 1 for
    /// the 3^d block, more when the exact search widened, 0 for bad input.
    pub shells: u32,
}

impl<const D: usize> Features<D> {
    /// An empty result for order n: infinite distances, NaN deltas, invalid IDs.
    pub fn empty(order: usize) -> Self {
        Features {
            order,
            distance: [f64::INFINITY; MAX_ORDER],
            delta: [[f64::NAN; D]; MAX_ORDER],
            id: [INVALID_ID; MAX_ORDER],
            shells: 0,
        }
    }

    /// The documented result for bad input: NaN distances and deltas,
    /// [`INVALID_ID`].
    pub fn invalid(order: usize) -> Self {
        Features { distance: [f64::NAN; MAX_ORDER], ..Self::empty(order) }
    }

    /// F1..Fn as a slice.
    pub fn distances(&self) -> &[f64] {
        &self.distance[..self.order]
    }
}

/// The f64 reference evaluator for dimension `D` (2, 3 or 4).
#[derive(Clone, Debug)]
pub struct Reference<const D: usize> {
    config: Config,
    pattern: Pattern<D>,
    /// The 3^d − 1 neighbours of the centre cell, faces first, then edges,
    /// then corners.
    neighbours: Vec<[i64; D]>,
}

impl<const D: usize> Reference<D> {
    /// Validates `config` and builds the evaluator.
    ///
    /// # Errors
    /// The first invalid field of `config`.
    ///
    /// ```
    /// use worley::{Config, Metric, Reference};
    /// let basis = Reference::<3>::new(Config { order: 4, metric: Metric::Minkowski(3.0), ..Config::default() }).unwrap();
    /// assert_eq!(basis.config().order, 4);
    /// assert!(Reference::<3>::new(Config { order: 0, ..Config::default() }).is_err());
    /// ```
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        let pattern = Pattern::new(&config)?;
        let mut neighbours = shell(1);
        neighbours.sort_by_key(|o| o.iter().filter(|&&v| v != 0).count());
        Ok(Reference { config, pattern, neighbours })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The point set.
    pub fn pattern(&self) -> &Pattern<D> {
        &self.pattern
    }

    /// F1..Fn, deltas and IDs at `x` (user units).
    ///
    /// ```
    /// use worley::{Config, Reference};
    /// let basis = Reference::<2>::new(Config { order: 3, ..Config::default() }).unwrap();
    /// let f = basis.evaluate([10.5, -3.25]);
    /// assert!(f.distances().windows(2).all(|w| w[0] <= w[1]));
    /// assert!(f.shells >= 1); // the 3^d block, or more when the search widened
    /// ```
    pub fn evaluate(&self, x: [f64; D]) -> Features<D> {
        match self.pattern.locate(x) {
            Some((cell, f)) => self.evaluate_in_cell(cell, f),
            None => Features::invalid(self.config.order),
        }
    }

    /// F1..Fn at the point `cell + fraction` given in cell units (x·S), for
    /// samples whose user coordinate would lose bits in one f64 (large
    /// worlds), and for placing samples exactly (ties, lattice planes).
    ///
    /// A fraction outside [0, 1] (or NaN) or a cell beyond
    /// ±[`MAX_CELL_COORD`] gives the invalid result.
    ///
    /// ```
    /// use worley::{Config, Reference};
    /// let basis = Reference::<3>::new(Config::default()).unwrap();
    /// // The same sample, given in user units and as a cell plus a fraction.
    /// let x = [2.0, -1.0, 0.5];
    /// let (cell, fraction) = basis.pattern().locate(x).unwrap();
    /// assert_eq!(basis.evaluate(x).distance[0], basis.evaluate_in_cell(cell, fraction).distance[0]);
    /// ```
    pub fn evaluate_in_cell(&self, cell: [i64; D], fraction: [f64; D]) -> Features<D> {
        let order = self.config.order;
        if !valid_in_cell(&cell, &fraction) {
            return Features::invalid(order);
        }
        let (best, r, gave_up) = self.search(cell, fraction, order);
        best.finish(self.config.metric, self.pattern.scale(), r, gave_up)
    }

    /// The search of steps 2 and 3 for the `order` closest points, in cell
    /// units: the list, the Chebyshev radius covered, and whether the exact
    /// search gave up at [`MAX_SHELLS`].
    fn search(&self, cell: [i64; D], f: [f64; D], order: usize) -> (Nearest<D>, u32, bool) {
        let metric = self.config.metric;
        let mut best = Nearest::<D>::new(order);
        let visit = |offset: [i64; D], best: &mut Nearest<D>| {
            if metric.rank(&gaps(&f, &offset)) > best.worst() {
                return;
            }
            self.for_each_point_at(cell, offset, |point, id| {
                let delta: [f64; D] = std::array::from_fn(|a| f[a] - point[a]);
                best.insert(metric.rank(&delta), delta, id, point);
            });
        };

        visit([0; D], &mut best);
        for &offset in &self.neighbours {
            visit(offset, &mut best);
        }
        let mut r = 1;
        if self.config.mode == Mode::Exact {
            while best.worst() >= metric.rank_of_distance(outside_distance(&f, r)) {
                if r == MAX_SHELLS {
                    return (best, r, true);
                }
                r += 1;
                for offset in shell(r) {
                    visit(offset, &mut best);
                }
            }
        }
        (best, r, false)
    }

    /// Every feature point of the cell at `offset` from `cell`: its position
    /// relative to `cell`'s lower corner, in cell units (exact: a small
    /// integer plus a 24-bit fraction), and its ID.
    #[inline]
    fn for_each_point_at(&self, cell: [i64; D], offset: [i64; D], mut visit: impl FnMut([f64; D], u32)) {
        let neighbour = std::array::from_fn(|a| cell[a] + offset[a]);
        self.pattern.for_each_point(neighbour, |p| {
            let o = p.offset();
            visit(std::array::from_fn(|a| offset[a] as f64 + o[a]), p.id);
        });
    }
}

/// Whether a cell and fraction are within the documented domain: every
/// fraction in [0, 1] (not NaN), every cell within ±[`MAX_CELL_COORD`].
fn valid_in_cell<const D: usize>(cell: &[i64; D], fraction: &[f64; D]) -> bool {
    let limit = MAX_CELL_COORD as u64;
    fraction.iter().all(|f| (0.0..=1.0).contains(f)) && cell.iter().all(|c| c.unsigned_abs() <= limit)
}

/// Per-axis gaps between the sample (fraction `f` of the centre cell) and the
/// cell at `offset`; their norm is the distance to the cell's nearest point.
#[inline]
pub(crate) fn gaps<const D: usize>(f: &[f64; D], offset: &[i64; D]) -> [f64; D] {
    std::array::from_fn(|a| {
        let o = offset[a];
        if o > 0 {
            o as f64 - f[a]
        } else if o < 0 {
            f[a] - (o + 1) as f64
        } else {
            0.0
        }
    })
}

/// B_r: the distance (in any Lp metric) from the sample to the outside of
/// the block of cells within Chebyshev radius r of its cell.
#[inline]
pub fn outside_distance<const D: usize>(f: &[f64; D], r: u32) -> f64 {
    let r = r as f64;
    f.iter().fold(f64::INFINITY, |m, &fa| m.min(fa + r).min(r + 1.0 - fa))
}

/// The cell offsets at Chebyshev radius exactly `r`, in lexicographic order.
pub fn shell<const D: usize>(r: u32) -> Vec<[i64; D]> {
    let r = r as i64;
    let side = 2 * r + 1;
    let total = (side as usize).pow(D as u32);
    (0..total)
        .map(|mut i| {
            std::array::from_fn(|_| {
                let v = (i % side as usize) as i64 - r;
                i /= side as usize;
                v
            })
        })
        .filter(|o: &[i64; D]| o.iter().any(|v| v.abs() == r))
        .collect()
}

/// The n closest points found so far, sorted by rank (insertion sort: n is
/// small).
struct Nearest<const D: usize> {
    order: usize,
    rank: [f64; MAX_ORDER],
    delta: [[f64; D]; MAX_ORDER],
    id: [u32; MAX_ORDER],
    /// Each point's position relative to the sample's cell (cell units).
    point: [[f64; D]; MAX_ORDER],
}

impl<const D: usize> Nearest<D> {
    fn new(order: usize) -> Self {
        Nearest {
            order,
            rank: [f64::INFINITY; MAX_ORDER],
            delta: [[f64::NAN; D]; MAX_ORDER],
            id: [INVALID_ID; MAX_ORDER],
            point: [[f64::NAN; D]; MAX_ORDER],
        }
    }

    /// The rank of F_n so far (+∞ until n points are found).
    #[inline]
    fn worst(&self) -> f64 {
        self.rank[self.order - 1]
    }

    #[inline]
    fn insert(&mut self, rank: f64, delta: [f64; D], id: u32, point: [f64; D]) {
        let last = self.order - 1;
        if (rank, id) >= (self.rank[last], self.id[last]) {
            return;
        }
        let mut i = last;
        while i > 0 && (self.rank[i - 1], self.id[i - 1]) > (rank, id) {
            self.rank[i] = self.rank[i - 1];
            self.delta[i] = self.delta[i - 1];
            self.id[i] = self.id[i - 1];
            self.point[i] = self.point[i - 1];
            i -= 1;
        }
        self.rank[i] = rank;
        self.delta[i] = delta;
        self.id[i] = id;
        self.point[i] = point;
    }

    /// Converts to user units. `gave_up` marks a search that hit
    /// [`MAX_SHELLS`] uncertified: every distance becomes NaN.
    fn finish(&self, metric: Metric, scale: f64, shells: u32, gave_up: bool) -> Features<D> {
        let inv = 1.0 / scale;
        let mut out = Features::empty(self.order);
        out.shells = shells;
        for k in 0..self.order {
            if self.rank[k].is_finite() {
                out.distance[k] = metric.distance_of_rank(self.rank[k]) * inv;
                out.delta[k] = self.delta[k].map(|v| v * inv);
                out.id[k] = self.id[k];
            }
            if gave_up {
                out.distance[k] = f64::NAN;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shells_partition_the_block() {
        assert_eq!(shell::<2>(0), vec![[0, 0]]);
        assert_eq!(shell::<2>(1).len(), 8);
        assert_eq!(shell::<3>(1).len(), 26);
        assert_eq!(shell::<3>(2).len(), 125 - 27);
        assert_eq!(shell::<4>(1).len(), 80);
    }

    #[test]
    fn gaps_are_distances_to_the_cell_extent() {
        let f = [0.25, 0.75];
        assert_eq!(gaps(&f, &[0, 0]), [0.0, 0.0]);
        assert_eq!(gaps(&f, &[1, -1]), [0.75, 0.75]);
        assert_eq!(gaps(&f, &[-2, 2]), [1.25, 1.25]);
    }

    #[test]
    fn outside_distance_is_the_nearest_face() {
        assert_eq!(outside_distance(&[0.25, 0.5], 1), 1.25);
        assert_eq!(outside_distance(&[0.9, 0.5], 1), 2.0 - 0.9);
        assert_eq!(outside_distance(&[0.5, 0.5, 0.5], 2), 2.5);
    }
}
