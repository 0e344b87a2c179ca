//! Footprint-aware evaluation: what a point sample is worth when it stands
//! for a footprint (a pixel's preimage on a surface) rather than a point.
//!
//! A renderer shading a pixel wants the average of a texture C over the
//! pixel's footprint, A_w(x), not C at one point: where the footprint
//! covers many cells, a point sample of F_n, of a cell's colour or of a
//! fractal sum's fine octaves is aliasing (moiré, salt-and-pepper noise).
//! A [`BlendCurve`] turns one point sample into an estimate of A_w.
//!
//! # The blend, derived
//! Given C(x) and the field's mean μ, the linear estimate
//! μ + β·(C(x) − μ) with the least expected squared error over the
//! stationary random field has
//!
//! β(w) = Cov(C(x), A_w(x)) / Var C = E_{y ∈ B_w}[ρ(y)],
//!
//! the footprint's average of C's autocorrelation ρ (B_w: a square of side
//! w in a plane through x, the preimage of a box-filtered pixel). β(0) = 1
//! is the point sample; β falls to 0 as the footprint covers many cells;
//! the expected squared error left is Var A_w − β²·Var C.
//!
//! For a field of identifiers coloured independently per cell (a
//! flagstone's colour from its feature ID), Cov(col(x), col(x + y)) =
//! Var(col) · P(id(x) = id(x + y)), so β is the footprint's average
//! probability that a point lies in the sample's cell
//! ([`BlendCurve::measure_identity`]).
//!
//! # Measured once per field
//! ρ has no closed form for F_n, so β is measured: [`PAIRS`] random points x
//! uniform in [−1000, 1000]^D, each with a random plane through it and an
//! offset uniform in the unit square of that plane, scaled to each of
//! [`KNOTS`] widths from 2^−6 to 2^6 input units (four per octave). Every
//! width uses the same points, planes and offsets, so the curve's noise is
//! common to its knots and the curve is smooth; β's standard error is about
//! 1/√[`PAIRS`] ≈ 0.011.
//!
//! # Renormalised and cut
//! The weight used is α = (β − β₀)/(1 − β₀), clamped to [0, 1] and made
//! non-increasing in w, with β₀ = 1/16: a point sample of weight β removes
//! β²·Var C of the squared error, so below β₀ it removes less than 1/256 of
//! the field's variance, and the evaluation is skipped ([`Texture`] does so
//! octave by octave, so a sample's cost falls as its footprint grows). α
//! is linear in w from 1 at w = 0 to the first knot and linear in log w
//! between knots, so values are continuous in the footprint; α is 1 exactly
//! at w = 0, where the blend returns the point sample's bits, and 0 from
//! [`BlendCurve::cutoff`] on (at the latest from the last knot, 2^6).
//!
//! [`Texture`]: crate::texture::Texture

use wide::f32x8;

/// Random points per measured curve.
pub const PAIRS: usize = 8192;

/// Widths at which β is measured: 2^(−6 + j/4) for j in 0..KNOTS.
pub const KNOTS: usize = 49;

/// log2 of the first knot's width.
const FIRST: f32 = -6.0;

/// Knots per doubling of the width.
const PER_OCTAVE: f32 = 4.0;

/// β₀: the point sample's weight below which it is dropped.
pub const FLOOR: f32 = 1.0 / 16.0;

/// The weight a point sample keeps as a function of the footprint's width,
/// and the mean it is blended towards.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendCurve {
    mean: f32,
    /// α at each knot; non-increasing, the last 0.
    alpha: Vec<f32>,
}

impl BlendCurve {
    /// Measures the curve of a stationary field in D dimensions: `field`
    /// gives eight values at eight points (input units). Non-finite values
    /// are left out of the statistics; a field without variance (a
    /// constant) gets α = 1 everywhere but the last knot.
    ///
    /// ```
    /// use worley::filter::BlendCurve;
    /// use worley::{Config, Outputs, Simd};
    /// let f1 = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let curve = BlendCurve::measure(|p: &[[f64; 2]; 8]| f1.evaluate8(p).distance[0].to_array(), 1);
    /// assert_eq!(curve.weight(0.0), 1.0);
    /// assert!(curve.weight(0.5) < 1.0 && curve.weight(100.0) == 0.0);
    /// assert!((curve.mean() - 1.0).abs() < 0.05); // mean F1 is 1 in user units
    /// ```
    pub fn measure<const D: usize>(field: impl Fn(&[[f64; D]; 8]) -> [f32; 8], seed: u64) -> Self {
        let pairs = Pairs::<D>::new(seed);
        let centre = pairs.values(&field, None);
        let finite: Vec<f64> = centre.iter().filter(|v| v.is_finite()).map(|&v| f64::from(v)).collect();
        let mean = finite.iter().sum::<f64>() / finite.len().max(1) as f64;
        let variance = finite.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / finite.len().max(1) as f64;
        let beta = (0..KNOTS)
            .map(|j| {
                let moved = pairs.values(&field, Some(knot_width(j)));
                let (mut sum, mut count) = (0.0f64, 0usize);
                for (&a, &b) in centre.iter().zip(&moved) {
                    if a.is_finite() && b.is_finite() {
                        sum += (f64::from(a) - mean) * (f64::from(b) - mean);
                        count += 1;
                    }
                }
                if variance > 0.0 && count > 0 {
                    (sum / count as f64 / variance) as f32
                } else {
                    1.0
                }
            })
            .collect();
        BlendCurve::from_beta(mean as f32, beta)
    }

    /// Measures the curve of a field of identifiers (a cell's ID): β is
    /// the probability that a point of the footprint has the sample's ID.
    /// The mean is NaN: the caller blends towards its own mean colour.
    ///
    /// ```
    /// use worley::filter::BlendCurve;
    /// use worley::{Config, Outputs, Simd};
    /// let cells = Simd::<2, 1>::new(Config::default(), Outputs::Ids).unwrap();
    /// let curve = BlendCurve::measure_identity(|p: &[[f64; 2]; 8]| cells.evaluate8(p).id[0].to_array(), 1);
    /// assert!(curve.weight(0.01) > 0.9 && curve.weight(50.0) == 0.0);
    /// ```
    pub fn measure_identity<const D: usize>(ids: impl Fn(&[[f64; D]; 8]) -> [u32; 8], seed: u64) -> Self {
        let pairs = Pairs::<D>::new(seed);
        let centre = pairs.values(&ids, None);
        let beta = (0..KNOTS)
            .map(|j| {
                let moved = pairs.values(&ids, Some(knot_width(j)));
                let same = centre.iter().zip(&moved).filter(|(a, b)| a == b).count();
                same as f32 / PAIRS as f32
            })
            .collect();
        BlendCurve::from_beta(f32::NAN, beta)
    }

    /// α from measured β: renormalised above β₀, clamped, non-increasing,
    /// the last knot 0.
    fn from_beta(mean: f32, beta: Vec<f32>) -> Self {
        let mut alpha = Vec::with_capacity(KNOTS);
        let mut previous = 1.0f32;
        for (j, b) in beta.into_iter().enumerate() {
            let a = if j + 1 == KNOTS { 0.0 } else { ((b - FLOOR) / (1.0 - FLOOR)).clamp(0.0, 1.0) };
            previous = previous.min(if a.is_nan() { 0.0 } else { a });
            alpha.push(previous);
        }
        BlendCurve { mean, alpha }
    }

    /// The field's mean, the value a footprint covering many cells tends to.
    pub fn mean(&self) -> f32 {
        self.mean
    }

    /// The curve with another mean (a closed form where one is known).
    pub fn with_mean(self, mean: f32) -> Self {
        BlendCurve { mean, ..self }
    }

    /// The smallest width from which the weight is 0.
    pub fn cutoff(&self) -> f32 {
        let j = self.alpha.iter().position(|&a| a == 0.0).unwrap_or(KNOTS - 1);
        knot_width(j) as f32
    }

    /// α: the point sample's weight for a footprint of side `width` (input
    /// units): 1 at 0, non-increasing, continuous, 0 from
    /// [`BlendCurve::cutoff`] on; NaN for a NaN or negative width.
    pub fn weight(&self, width: f32) -> f32 {
        if width.is_nan() || width < 0.0 {
            return f32::NAN;
        }
        if width == 0.0 {
            return 1.0;
        }
        let first = (FIRST).exp2();
        if width < first {
            return 1.0 + (self.alpha[0] - 1.0) * (width / first);
        }
        let p = (width.log2() - FIRST) * PER_OCTAVE;
        if p >= (KNOTS - 1) as f32 {
            return 0.0;
        }
        let j = p as usize;
        let t = p - j as f32;
        self.alpha[j] + (self.alpha[j + 1] - self.alpha[j]) * t
    }

    /// α per lane.
    pub fn weight8(&self, width: [f32; 8]) -> [f32; 8] {
        width.map(|w| self.weight(w))
    }

    /// α·v + (1 − α)·mean per lane; v itself (its bits) where α is 1, and
    /// the mean where α is 0, whatever v is (an infinite distance of an
    /// empty window included) unless v is NaN: a NaN value (bad input) or a
    /// NaN weight (a bad width) gives NaN, as the texture's octaves that
    /// are not evaluated do.
    pub fn blend8(&self, value: f32x8, alpha: [f32; 8]) -> f32x8 {
        let v = value.to_array();
        f32x8::from(std::array::from_fn::<f32, 8, _>(|i| {
            if alpha[i] == 1.0 || v[i].is_nan() {
                v[i]
            } else if alpha[i] == 0.0 {
                self.mean
            } else {
                alpha[i] * v[i] + (1.0 - alpha[i]) * self.mean
            }
        }))
    }
}

/// The share of a footprint that lies in each of a sample's N nearest
/// cells, from Euclidean F1..FN with their deltas: what a cell's colour
/// keyed on its feature ID should be weighed by, where a point sample gives
/// F1's cell everything.
///
/// Neighbour k's share is the part of a footprint of side w beyond the
/// bisector plane between F1's point and F_k's: ½ − b_k / w, clamped to
/// [0, 1] (a box filter across a straight edge), with b_k = (F_k² − F1²) /
/// (2·|p_k − p₁|) the sample's distance to that plane. F1's cell keeps the
/// rest; where the shares add up to more than 1 (a footprint over a corner
/// where the half-spaces overlap) they are scaled to sum to 1. It is an
/// approximation that treats each bisector as a whole plane and sees no
/// cell beyond the N-th point, so it serves footprints up to about a cell;
/// beyond, blend it towards the mean colour with
/// [`BlendCurve::measure_identity`]'s weight.
///
/// A zero width puts everything in F1's cell; a NaN or negative width or a
/// NaN delta (bad input) gives NaN shares. Lane i of the result's entry k
/// is F_{k+1}'s share.
///
/// ```
/// use worley::filter::cell_cover8;
/// use worley::{Config, Outputs, Simd};
/// let cells = Simd::<2, 3>::new(Config { order: 3, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
/// let f = cells.evaluate8(&[[0.3, 0.8]; 8]);
/// let share = cell_cover8(&f, [0.0, 0.5, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0]);
/// assert_eq!((share[0][0], share[1][0]), (1.0, 0.0));
/// let total: f32 = share.iter().map(|s| s[2]).sum();
/// assert!((total - 1.0).abs() < 1e-6);
/// ```
pub fn cell_cover8<const D: usize, const N: usize>(
    features: &crate::simd::Features8<D, N>,
    width: [f32; 8],
) -> [[f32; 8]; N] {
    let distance = features.distance.map(|v| v.to_array());
    let delta = features.delta.map(|d| d.map(|v| v.to_array()));
    let mut share = [[0f32; 8]; N];
    for i in 0..8 {
        let w = width[i];
        if w.is_nan() || w < 0.0 || (0..N).any(|k| (0..D).any(|a| delta[k][a][i].is_nan())) {
            share.iter_mut().for_each(|s| s[i] = f32::NAN);
            continue;
        }
        let mut others = 0.0f32;
        for k in 1..N {
            if w == 0.0 {
                break;
            }
            // p_k − p₁ = δ₁ − δ_k (deltas are sample − point).
            let gap = (0..D).map(|a| (delta[0][a][i] - delta[k][a][i]).powi(2)).sum::<f32>().sqrt();
            let b = (distance[k][i] * distance[k][i] - distance[0][i] * distance[0][i]) / (2.0 * gap);
            let c = if b.is_finite() { (0.5 - b / w).clamp(0.0, 1.0) } else { 0.0 };
            share[k][i] = c;
            others += c;
        }
        if others > 1.0 {
            (1..N).for_each(|k| share[k][i] /= others);
            share[0][i] = 0.0;
        } else {
            share[0][i] = 1.0 - others;
        }
    }
    share
}

/// Knot j's width, 2^(−6 + j/4).
fn knot_width(j: usize) -> f64 {
    f64::from(FIRST + j as f32 / PER_OCTAVE).exp2()
}

/// The measurement's random points, planes and offsets.
struct Pairs<const D: usize> {
    points: Vec<[f64; D]>,
    /// Per point, the offset for a unit width: u₁·e₁ + u₂·e₂.
    offsets: Vec<[f64; D]>,
}

impl<const D: usize> Pairs<D> {
    fn new(seed: u64) -> Self {
        use crate::math::uniform;
        let mut points = Vec::with_capacity(PAIRS);
        let mut offsets = Vec::with_capacity(PAIRS);
        for i in 0..PAIRS {
            let r = |k: usize| uniform(seed ^ 0x5A17_F00D, (i * 64 + k) as u64);
            points.push(std::array::from_fn(|a| 2000.0 * r(a) - 1000.0));
            // Two orthonormal directions of a uniformly random plane: Gram-
            // Schmidt on two Gaussian vectors (Box-Muller).
            let gauss = |k: usize| (-2.0 * (1.0 - r(k)).ln()).sqrt() * (std::f64::consts::TAU * r(k + 1)).cos();
            let mut e1: [f64; D] = std::array::from_fn(|a| gauss(8 + 2 * a));
            let mut e2: [f64; D] = std::array::from_fn(|a| gauss(24 + 2 * a));
            normalise(&mut e1);
            let along: f64 = e1.iter().zip(&e2).map(|(p, q)| p * q).sum();
            for (q, p) in e2.iter_mut().zip(&e1) {
                *q -= along * p;
            }
            normalise(&mut e2);
            let (u1, u2) = (r(40) - 0.5, r(41) - 0.5);
            // In one dimension the footprint is a segment.
            let u2 = if D < 2 { 0.0 } else { u2 };
            offsets.push(std::array::from_fn(|a| u1 * e1[a] + u2 * e2[a]));
        }
        Pairs { points, offsets }
    }

    /// The field at every point, or at every point moved by its offset
    /// times `width`.
    fn values<T: Copy + Default>(&self, field: &impl Fn(&[[f64; D]; 8]) -> [T; 8], width: Option<f64>) -> Vec<T> {
        let mut out = Vec::with_capacity(PAIRS);
        for (points, offsets) in self.points.chunks(8).zip(self.offsets.chunks(8)) {
            let block: [[f64; D]; 8] = std::array::from_fn(|i| {
                let (p, o) = (points[i.min(points.len() - 1)], offsets[i.min(points.len() - 1)]);
                match width {
                    None => p,
                    Some(w) => std::array::from_fn(|a| p[a] + w * o[a]),
                }
            });
            out.extend_from_slice(&field(&block)[..points.len()]);
        }
        out
    }
}

fn normalise<const D: usize>(v: &mut [f64; D]) {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n > 0.0 {
        v.iter_mut().for_each(|x| *x /= n);
    } else {
        *v = std::array::from_fn(|a| (a == 0) as u8 as f64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(alpha: Vec<f32>) -> BlendCurve {
        BlendCurve { mean: 2.0, alpha }
    }

    #[test]
    fn the_weight_is_one_at_zero_continuous_and_zero_beyond_the_cutoff() {
        let c = BlendCurve::from_beta(2.0, (0..KNOTS).map(|j| 1.0 - j as f32 / 30.0).collect());
        assert_eq!(c.weight(0.0), 1.0);
        assert!(c.weight(-1.0).is_nan() && c.weight(f32::NAN).is_nan());
        assert_eq!(c.weight(f32::INFINITY), 0.0);
        // Non-increasing over a fine sweep, with no jump larger than the
        // slope allows.
        let mut last = 1.0;
        for k in 0..20_000 {
            let w = (k as f32 / 20_000.0 * 14.0 - 7.0).exp2();
            let a = c.weight(w);
            assert!(a <= last && last - a < 0.01, "{w}: {a} after {last}");
            last = a;
        }
        let cut = c.cutoff();
        assert_eq!(c.weight(cut), 0.0);
        assert!(c.weight(cut * 0.99) > 0.0);
    }

    #[test]
    fn the_blend_keeps_the_point_sample_s_bits_at_weight_one() {
        let c = curve(vec![1.0; KNOTS]);
        let v = f32x8::from([-0.0, 1.0, f32::NAN, 3.5, f32::INFINITY, 0.25, 1e-30, 7.0]);
        let got = c.blend8(v, [1.0; 8]).to_array();
        for (g, w) in got.iter().zip(v.to_array()) {
            assert_eq!(g.to_bits(), w.to_bits());
        }
        let half = c.blend8(v, [0.5; 8]).to_array();
        assert_eq!(half[1], 1.5);
        // Weight 0: the mean, for finite and infinite values alike; NaN
        // (bad input) stays NaN, and so does a NaN weight.
        let none = c.blend8(v, [0.0; 8]).to_array();
        assert_eq!((none[3], none[4], none[7]), (2.0, 2.0, 2.0));
        assert!(none[2].is_nan());
        assert!(c.blend8(v, [f32::NAN; 8]).to_array()[1].is_nan());
    }
}
