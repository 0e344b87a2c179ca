//! # Smooth F1 and the n-sphere radius
//!
//! ## Smooth F1
//! F1 has a crease wherever two points are equally near: its cells meet in
//! sharp valleys. Smooth F1 replaces the minimum by a smooth minimum of the
//! distances to *all* feature points, with a smoothness `s` (a length in
//! user units):
//!
//! S(x) = −s · ln Σ_j exp(−h_j / s), h_j = √(F_j² + s²) − s,
//!
//! where F_j is the distance from x to point j in the configured metric.
//!
//! - **Why this form.** The log-sum-exp is the smooth minimum whose
//!   parameter is a length: every point within a few `s` of F1 pulls the
//!   value down, none farther does. It is C∞ wherever every h_j is, and
//!   h_j, the hyperbolic distance, is C∞ everywhere in the Euclidean metric,
//!   also at the feature point itself, where F_j has the tip of a cone (a
//!   log-sum-exp over F_j would keep that tip). In the other metrics S is
//!   as smooth as their distance (their creases along axes remain).
//! - **Limits.** h_j ≤ F_j, so S ≤ F1 for every s; h_j → F_j as s → 0,
//!   and S ≥ h_1 − s·ln N over N points, so S → F1. `s = 0` gives F1
//!   itself.
//! - **Gradient.** ∇S = Σ_j w_j ∇h_j / Σ_j w_j with w_j = exp(−h_j/s) and
//!   ∇h_j = F_j ∇F_j / √(F_j² + s²); in the Euclidean metric
//!   ∇h_j = (x − p_j) / √(F_j² + s²).
//!
//! ### Certification
//! The sum runs over every point of the Chebyshev block of cells of radius
//! r around the sample's cell, r = 1, 2, …, until what lies outside
//! weighs at most [`SMOOTH_TOLERANCE`] of what was summed. Outside the block
//! of radius r, a point of shell r + k is at least B_r + k − 1 cells away
//! (B_r the distance to the block's outside, the same in every Lp metric),
//! a shell holds (2(r+k)+1)^d − (2(r+k)−1)^d cells of at most
//! [`max_population`](crate::definition::PopulationTable::max_population)
//! points each, and h ≥ F − s makes a point's weight at most
//! e·exp(−F/s). The bound on the rest, summed over k, is compared with the
//! sum so far; when it is below the tolerance, the value is within
//! s · [`SMOOTH_TOLERANCE`] of the sum over every point (ln(1 + t) ≤ t), and
//! the gradient within 2 · [`SMOOTH_TOLERANCE`] · max|∇h_j| (at most 1 in
//! the Euclidean metric, √d in the others). The value is therefore
//! continuous to within that tolerance: where the search stops one shell
//! later, it adds at most the bound. Larger `s` needs larger blocks: a
//! search that would pass [`MAX_SHELLS`] gives NaN. At the default density
//! (mean F1 = 1) that is s above about 2 in 3D and 3 in 2D; in 3D, s = 0.1
//! sums a block of radius 1 or 2, s = 0.3 one of radius 3 and s = 1 one
//! of radius 8 (2000 random samples, counted by a program not kept in the
//! repository).
//!
//! S is a smooth minimum over every point, not a distance: where s is a
//! good part of the spacing of the points, many of them weigh, and S falls
//! below 0 (−s·ln N for N points at the same distance). At the default
//! density in 3D, over the same 2000 samples, its smallest value was 0.02
//! for s = 0.1, −0.16 for s = 0.3 and −2.75 for s = 1.
//!
//! The sum is kept as a running log-sum-exp (the smallest h so far and the
//! weights relative to it), so no weight underflows however small `s`.
//!
//! ## Compact smooth F1
//! The log-sum-exp above lets every point pull, so its search runs to
//! about F1 + 14s before the rest weighs under 10^−6. The compact form
//! lets only the points near F1 pull, and is exact: S is the root of
//!
//! Σ_j φ((h_j − S)/s) = 1, φ(t) = exp(1 − 1/(1 − t)) for t < 1, 0 for t ≥ 1,
//!
//! with h_j the hyperbolic distance above.
//!
//! - **Why this form.** φ is C∞ (all its derivatives vanish at t = 1),
//!   falls from φ(0) = 1 to 0, and is 0 beyond t = 1. The sum grows with S,
//!   is at least 1 at S = h_1 (F1's point alone gives φ(0)) and is 0 at
//!   S = h_1 − s, so the root is unique and lies in (h_1 − s, h_1]; by the
//!   implicit function theorem it is C∞ in the h_j, hence in position (the
//!   sum's derivative in S is never 0, and which points take part changes
//!   only where their φ and all its derivatives are 0).
//! - **Reach.** A point takes part only if h_j < S + s ≤ h_1 + s, that is
//!   F_j < √((h_1 + 2s)² − s²) < F1 + 2s: the search is a certified search
//!   of radius below F1 + 2s, with nothing left out and no tolerance.
//! - **Limits.** S ≤ h_1 ≤ F1, S > h_1 − s ≥ F1 − 2s, so S → F1 as s → 0;
//!   where F1's point stands alone within that reach, S = h_1 exactly.
//! - **Gradient.** ∇S = Σ_j w_j ∇h_j / Σ_j w_j with
//!   w_j = −φ'(t_j) = φ(t_j)/(1 − t_j)², t_j = (h_j − S)/s: a weighted mean
//!   of the ∇h_j, so |∇S| ≤ 1 in the Euclidean metric.
//!
//! The reference finds the root by bisection of (h_1 − s, h_1] until the
//! interval stops shrinking in f64.
//!
//! ## The n-sphere radius
//! Half the distance from F1's point p₁ to the point nearest to it: the
//! largest radius at which no two points' spheres overlap around p₁, a
//! dot that fits inside p₁'s cell. It is F2 evaluated at p₁ itself (whose F1 is
//! p₁, at distance 0), halved, by the same certified search as F_n; p₁'s
//! position is exact in f64 (a cell plus a 24-bit fraction), so the search
//! starts from the point, not from a rounded copy. A point at p₁'s very
//! position makes the radius 0.

use super::{outside_distance, shell, valid_in_cell, Reference, MAX_SHELLS};
use crate::config::{Metric, Mode};
use crate::definition::INVALID_ID;

/// The relative weight of the points a smooth F1 leaves out, at most.
pub const SMOOTH_TOLERANCE: f64 = 1e-6;

/// Smooth F1 at a sample: its value, its gradient and F1's point's ID.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Smooth<const D: usize> {
    /// S, user units: at most F1, within s·ln N of it. NaN for bad input.
    pub value: f64,
    /// ∇S with respect to the sample's position (NaN for bad input).
    pub gradient: [f64; D],
    /// The ID of F1's point (the heaviest weight).
    pub feature: u32,
    /// The Chebyshev radius of the block of cells summed (0 for bad input).
    pub shells: u32,
}

impl<const D: usize> Smooth<D> {
    /// The documented result for bad input: NaN value and gradient,
    /// [`INVALID_ID`].
    pub fn invalid() -> Self {
        Smooth { value: f64::NAN, gradient: [f64::NAN; D], feature: INVALID_ID, shells: 0 }
    }
}

/// The n-sphere radius at a sample: half the distance from F1's point to
/// its nearest other point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NSphere {
    /// The radius, user units (NaN for bad input; +∞ in window mode when
    /// the 3^d block around F1's point holds no other point).
    pub radius: f64,
    /// The ID of F1's point, the sphere's centre.
    pub feature: u32,
    /// The ID of the point nearest to it.
    pub neighbour: u32,
}

impl NSphere {
    /// The documented result for bad input: NaN radius, [`INVALID_ID`] twice.
    pub fn invalid() -> Self {
        NSphere { radius: f64::NAN, feature: INVALID_ID, neighbour: INVALID_ID }
    }
}

/// The gradient of the metric's distance at the delta `v` (x − p), `d` its
/// distance (> 0).
fn distance_gradient<const D: usize>(metric: Metric, v: &[f64; D], d: f64) -> [f64; D] {
    match metric {
        Metric::Euclidean => v.map(|a| a / d),
        Metric::Manhattan => v.map(f64::signum),
        Metric::Chebyshev => {
            let axis = (0..D).fold(0, |m, a| if v[a].abs() > v[m].abs() { a } else { m });
            std::array::from_fn(|a| if a == axis { v[a].signum() } else { 0.0 })
        }
        Metric::Minkowski(p) => v.map(|a| a.signum() * (a.abs() / d).powf(p - 1.0)),
    }
}

impl<const D: usize> Reference<D> {
    /// Smooth F1 at `x` (user units) with smoothness `s` (user units), as
    /// the [module's text](self) defines it, certified to within
    /// s · [`SMOOTH_TOLERANCE`]. `s = 0` gives F1 and its gradient; a
    /// negative, infinite or NaN `s`, or bad `x`, gives [`Smooth::invalid`];
    /// in [`Mode::Window`] an empty 3^d block gives +∞ for every `s`.
    ///
    /// ```
    /// use worley::{Config, Reference};
    /// let basis = Reference::<3>::new(Config::default()).unwrap();
    /// let x = [1.5, -0.25, 4.0];
    /// let f1 = basis.evaluate(x).distance[0];
    /// let smooth = basis.smooth_f1(x, 0.3);
    /// assert!(smooth.value <= f1 && smooth.value > f1 - 0.3 * 10.0);
    /// assert_eq!(basis.smooth_f1(x, 0.0).value, f1);
    /// ```
    pub fn smooth_f1(&self, x: [f64; D], s: f64) -> Smooth<D> {
        match self.pattern.locate(x) {
            Some((cell, f)) => self.smooth_in_cell(cell, f, s),
            None => Smooth::invalid(),
        }
    }

    /// [`Reference::smooth_f1`] at `cell + fraction` (cell units), as
    /// [`Reference::evaluate_in_cell`] takes it.
    pub fn smooth_f1_in_cell(&self, cell: [i64; D], fraction: [f64; D], s: f64) -> Smooth<D> {
        if !valid_in_cell(&cell, &fraction) {
            return Smooth::invalid();
        }
        self.smooth_in_cell(cell, fraction, s)
    }

    fn smooth_in_cell(&self, cell: [i64; D], f: [f64; D], s: f64) -> Smooth<D> {
        if !(s >= 0.0 && s.is_finite()) {
            return Smooth::invalid();
        }
        let metric = self.config.metric;
        let scale = self.pattern.scale();
        if s == 0.0 {
            // F1 as `evaluate` gives it, bit for bit.
            let (nearest, shells, gave_up) = self.search(cell, f, 1);
            let f1 = nearest.finish(metric, scale, shells, gave_up);
            if f1.distance[0].is_nan() {
                return Smooth::invalid();
            }
            if f1.distance[0].is_infinite() {
                // Window mode, and the 3^d block is empty: +∞ as for s > 0.
                return Smooth { value: f64::INFINITY, gradient: [f64::NAN; D], feature: INVALID_ID, shells };
            }
            let d = metric.distance_of_rank(nearest.rank[0]);
            let gradient = if d > 0.0 { distance_gradient(metric, &nearest.delta[0], d) } else { [0.0; D] };
            return Smooth { value: f1.distance[0], gradient, feature: f1.id[0], shells };
        }
        let sc = s * scale;
        let mut sum = Sum::<D>::new(sc);
        let add = |sum: &mut Sum<D>, offset: [i64; D]| {
            self.for_each_point_at(cell, offset, |point, id| {
                let delta: [f64; D] = std::array::from_fn(|a| f[a] - point[a]);
                sum.add(metric, &delta, id);
            });
        };
        add(&mut sum, [0; D]);
        for &offset in &self.neighbours {
            add(&mut sum, offset);
        }
        let most = f64::from(self.pattern.table().max_population());
        // Whether the points outside the block of radius r weigh at most
        // the tolerance of the sum: ln of the bound on their weight,
        // relative to exp(−least/s) as `sum.weight` is.
        let certified = |sum: &Sum<D>, r: u32| {
            let rest = outside_weight::<D>(outside_distance(&f, r), r, sc, most) + sum.least / sc;
            rest <= (SMOOTH_TOLERANCE * sum.weight).ln()
        };
        let mut r = 1;
        // Window mode sums the 3^d block alone, as its F_n search does.
        while self.config.mode == Mode::Exact && !certified(&sum, r) {
            if r == MAX_SHELLS {
                return Smooth::invalid();
            }
            r += 1;
            for offset in shell(r) {
                add(&mut sum, offset);
            }
        }
        if sum.weight == 0.0 {
            // Window mode, and the 3^d block is empty.
            return Smooth { value: f64::INFINITY, gradient: [f64::NAN; D], feature: INVALID_ID, shells: r };
        }
        Smooth {
            value: (sum.least - sc * sum.weight.ln()) / scale,
            gradient: sum.gradient.map(|g| g / sum.weight),
            feature: sum.nearest.1,
            shells: r,
        }
    }

    /// Compact smooth F1 at `x` (user units) with smoothness `s` (user
    /// units), as the [module's text](self) defines it: exact (every point
    /// that takes part is found by a certified search, the root to f64
    /// precision). `s = 0` gives F1 and its gradient, as
    /// [`Reference::smooth_f1`]; a negative, infinite or NaN `s`, or bad
    /// `x`, gives [`Smooth::invalid`]. In [`Mode::Window`] the points of
    /// the 3^d block take part; an empty block gives +∞.
    ///
    /// ```
    /// use worley::{Config, Reference};
    /// let basis = Reference::<3>::new(Config::default()).unwrap();
    /// let x = [1.5, -0.25, 4.0];
    /// let f1 = basis.evaluate(x).distance[0];
    /// let smooth = basis.smooth_f1_compact(x, 0.3);
    /// assert!(smooth.value <= f1 && smooth.value > f1 - 2.0 * 0.3);
    /// ```
    pub fn smooth_f1_compact(&self, x: [f64; D], s: f64) -> Smooth<D> {
        match self.pattern.locate(x) {
            Some((cell, f)) => self.compact_in_cell(cell, f, s),
            None => Smooth::invalid(),
        }
    }

    /// [`Reference::smooth_f1_compact`] at `cell + fraction` (cell units).
    pub fn smooth_f1_compact_in_cell(&self, cell: [i64; D], fraction: [f64; D], s: f64) -> Smooth<D> {
        if !valid_in_cell(&cell, &fraction) {
            return Smooth::invalid();
        }
        self.compact_in_cell(cell, fraction, s)
    }

    fn compact_in_cell(&self, cell: [i64; D], f: [f64; D], s: f64) -> Smooth<D> {
        if !(s > 0.0 && s.is_finite()) {
            // s = 0 is F1 itself; the rest is invalid.
            return self.smooth_in_cell(cell, f, s);
        }
        let metric = self.config.metric;
        let scale = self.pattern.scale();
        let sc = s * scale;
        let (nearest, _, gave_up) = self.search(cell, f, 1);
        let f1 = metric.distance_of_rank(nearest.rank[0]);
        if gave_up || f1.is_nan() {
            return Smooth::invalid();
        }
        if f1.is_infinite() {
            // Window mode, and the 3^d block is empty.
            return Smooth { value: f64::INFINITY, gradient: [f64::NAN; D], feature: INVALID_ID, shells: 1 };
        }
        let h1 = f1.hypot(sc) - sc;
        let reach = ((h1 + 2.0 * sc).powi(2) - sc * sc).sqrt();
        // Every point nearer than the reach: h_j and ∇h_j (cell units).
        let mut near: Vec<(f64, [f64; D])> = Vec::new();
        let mut add = |offset: [i64; D]| {
            self.for_each_point_at(cell, offset, |point, _| {
                let delta: [f64; D] = std::array::from_fn(|a| f[a] - point[a]);
                let d = metric.distance(&delta);
                if d < reach {
                    let root = d.hypot(sc);
                    let g = if d > 0.0 { distance_gradient(metric, &delta, d).map(|g| g * d / root) } else { [0.0; D] };
                    near.push((root - sc, g));
                }
            });
        };
        add([0; D]);
        for &offset in &self.neighbours {
            add(offset);
        }
        let mut r = 1;
        while self.config.mode == Mode::Exact && outside_distance(&f, r) < reach {
            if r == MAX_SHELLS {
                return Smooth::invalid();
            }
            r += 1;
            for offset in shell(r) {
                add(offset);
            }
        }
        // The root of Σ φ((h_j − S)/s) = 1 in (h1 − s, h1], by bisection.
        let total = |v: f64| near.iter().map(|&(h, _)| bump((h - v) / sc)).sum::<f64>();
        let (mut lo, mut hi) = (h1 - sc, h1);
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if total(mid) >= 1.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let value = hi;
        let mut weight = 0.0;
        let mut gradient = [0.0; D];
        for (h, g) in &near {
            let t = (h - value) / sc;
            let w = if t < 1.0 { bump(t) / ((1.0 - t) * (1.0 - t)) } else { 0.0 };
            weight += w;
            for (sum, g) in gradient.iter_mut().zip(g) {
                *sum += w * g;
            }
        }
        Smooth { value: value / scale, gradient: gradient.map(|g| g / weight), feature: nearest.id[0], shells: r }
    }

    /// The n-sphere radius at `x` (user units): half the distance from F1's
    /// point to its nearest other point (see the [module's text](self)),
    /// exact by certification in [`Mode::Exact`]; [`NSphere::invalid`] for
    /// bad input.
    ///
    /// ```
    /// use worley::{Config, Reference};
    /// let basis = Reference::<2>::new(Config::default()).unwrap();
    /// let n = basis.n_sphere([3.0, 1.5]);
    /// assert_eq!(n.feature, basis.evaluate([3.0, 1.5]).id[0]);
    /// assert!(n.radius > 0.0 && n.neighbour != n.feature);
    /// ```
    pub fn n_sphere(&self, x: [f64; D]) -> NSphere {
        match self.pattern.locate(x) {
            Some((cell, f)) => self.n_sphere_in_cell(cell, f),
            None => NSphere::invalid(),
        }
    }

    /// [`Reference::n_sphere`] at `cell + fraction` (cell units).
    pub fn n_sphere_in_cell(&self, cell: [i64; D], fraction: [f64; D]) -> NSphere {
        if !valid_in_cell(&cell, &fraction) {
            return NSphere::invalid();
        }
        let (nearest, _, gave_up) = self.search(cell, fraction, 1);
        let (feature, point) = (nearest.id[0], nearest.point[0]);
        if gave_up || feature == INVALID_ID {
            return NSphere::invalid();
        }
        // F1's point as its own cell and fraction, exactly.
        let whole = point.map(f64::floor);
        let centre: [i64; D] = std::array::from_fn(|a| cell[a] + whole[a] as i64);
        let at: [f64; D] = std::array::from_fn(|a| point[a] - whole[a]);
        let (around, _, gave_up) = self.search(centre, at, 2);
        if gave_up {
            return NSphere::invalid();
        }
        // The nearest point other than the centre itself (which is first,
        // at distance 0, unless a point shares its position and has a
        // smaller ID: that one is then the neighbour, at distance 0).
        let k = usize::from(around.id[0] == feature);
        let metric = self.config.metric;
        NSphere {
            radius: 0.5 * metric.distance_of_rank(around.rank[k]) / self.pattern.scale(),
            feature,
            neighbour: if around.rank[k].is_finite() { around.id[k] } else { INVALID_ID },
        }
    }
}

/// A running log-sum-exp of −h/s (cell units): the smallest h so far, the
/// weights exp(−(h − least)/s) summed, their weighted ∇h, and the nearest
/// point's (distance, ID).
struct Sum<const D: usize> {
    s: f64,
    least: f64,
    weight: f64,
    gradient: [f64; D],
    nearest: (f64, u32),
}

impl<const D: usize> Sum<D> {
    fn new(s: f64) -> Self {
        Sum { s, least: f64::INFINITY, weight: 0.0, gradient: [0.0; D], nearest: (f64::INFINITY, INVALID_ID) }
    }

    /// One point at `delta` (x − p) from the sample.
    fn add(&mut self, metric: Metric, delta: &[f64; D], id: u32) {
        let d = metric.distance(delta);
        let root = d.hypot(self.s);
        let h = root - self.s;
        if h < self.least {
            // Rescale what was summed to the new smallest h.
            let shrink = ((h - self.least) / self.s).exp();
            self.weight *= shrink;
            self.gradient = self.gradient.map(|g| g * shrink);
            self.least = h;
        }
        let w = (-(h - self.least) / self.s).exp();
        self.weight += w;
        if d > 0.0 {
            let g = distance_gradient(metric, delta, d);
            for (sum, g) in self.gradient.iter_mut().zip(g) {
                *sum += w * g * d / root;
            }
        }
        if (d, id) < self.nearest {
            self.nearest = (d, id);
        }
    }
}

/// ln of a bound on Σ e·exp(−F/s) over the points outside the Chebyshev
/// block of radius `r`, whose outside is `edge` cells from the sample
/// (cell units, `most` points per cell at most); +∞ where the sum does not
/// settle within a thousand shells.
fn outside_weight<const D: usize>(edge: f64, r: u32, s: f64, most: f64) -> f64 {
    let cells = |j: f64| (2.0 * j + 1.0).powi(D as i32) - (2.0 * j - 1.0).powi(D as i32);
    // Terms relative to the first, in logs; summed until a term is 2^−60
    // of the sum and falling.
    let first = cells(f64::from(r) + 1.0).ln() - edge / s;
    let mut sum = 1.0;
    for k in 2..1000 {
        let j = f64::from(r) + k as f64;
        let term = (cells(j).ln() - (edge + (k - 1) as f64) / s - first).exp();
        sum += term;
        let next = (cells(j + 1.0).ln() - (edge + k as f64) / s - first).exp();
        if next <= term && term < sum * 2f64.powi(-60) {
            return 1.0 + most.ln() + first + sum.ln();
        }
    }
    f64::INFINITY
}

/// φ(t) = exp(1 − 1/(1 − t)) below 1, 0 from 1 on: the compact form's
/// weight, C∞, φ(0) = 1.
fn bump(t: f64) -> f64 {
    if t < 1.0 {
        (1.0 - 1.0 / (1.0 - t)).exp()
    } else {
        0.0
    }
}
