//! Analytic gradients of a texture and normal perturbation for bump
//! mapping.

use wide::f32x8;

use super::{Sample, Texture};
use crate::config::Metric;

/// Values and gradients of eight samples.
#[derive(Clone, Copy, Debug)]
pub struct Gradient8<const D: usize> {
    /// The values.
    pub value: f32x8,
    /// ∂value/∂x_a per axis, with respect to the input coordinates.
    pub gradient: [f32x8; D],
    /// Per lane, whether the gradient exists (see [`Sample::defined`]).
    pub defined: [bool; 8],
}

impl<const D: usize, const N: usize> Texture<D, N> {
    /// Eight values and their analytic gradients ([`Texture::filtered_gradient8`]
    /// with zero footprints, the same bits).
    pub fn gradient8(&self, x: &[[f64; D]; 8]) -> Gradient8<D> {
        self.filtered_gradient8(x, [0.0; 8])
    }

    /// Eight values standing for footprints, as [`Texture::filtered8`] (the
    /// same bits), and their gradients: each octave's gradient times its
    /// weight (the footprint taken as locally constant), so fine octaves'
    /// bumps fade where the footprint cannot show them.
    pub fn filtered_gradient8(&self, x: &[[f64; D]; 8], width: [f32; 8]) -> Gradient8<D> {
        self.gradient_lanes::<false>(x, width)
    }

    /// [`Texture::filtered_gradient8`], with `ONE` as in
    /// [`Texture::filtered_lanes`].
    #[inline(always)]
    pub(super) fn gradient_lanes<const ONE: bool>(&self, x: &[[f64; D]; 8], width: [f32; 8]) -> Gradient8<D> {
        let metric = self.values.config().metric;
        let mut value = f32x8::splat(0.0);
        let mut gradient = [f32x8::splat(0.0); D];
        let mut defined = [true; 8];
        for (i, &(frequency, amplitude, period)) in self.octaves.iter().enumerate() {
            let alpha = self.weights(&width, frequency);
            let blend = |v: f32x8| if alpha == [1.0; 8] { v } else { self.blend_curve().blend8(v, alpha) };
            if alpha.iter().all(|&a| a == 0.0) {
                let v = self.unresolved(x, frequency, period);
                value = if i == 0 { v } else { value + f32x8::splat(amplitude) * v };
                for (d, v) in defined.iter_mut().zip(v.to_array()) {
                    *d &= !v.is_nan();
                }
                continue;
            }
            // ∂/∂x of amplitude · C(frequency · x) = amplitude · frequency · ∇C,
            // times the octave's weight.
            let chain = f32x8::splat(amplitude * frequency as f32 * self.input_scale);
            let chain = if alpha == [1.0; 8] { chain } else { chain * f32x8::from(alpha) };
            if let Some((own, normal)) = self.own_kernel::<ONE>(x, frequency, period) {
                let v = blend(own);
                value = if i == 0 { v } else { value + f32x8::splat(amplitude) * v };
                for (sum, n) in gradient.iter_mut().zip(&normal) {
                    *sum += chain * *n;
                }
                for (d, v) in defined.iter_mut().zip(own.to_array()) {
                    *d &= v.is_finite();
                }
                continue;
            }
            let f = self.features::<ONE>(&self.deltas, x, frequency, period);
            let v = blend(self.combination.value(&f.distance));
            value = if i == 0 { v } else { value + f32x8::splat(amplitude) * v };
            let w = self.combination.weights(&f.distance);
            for ((wk, fk), dk) in w.iter().zip(&f.distance).zip(&f.delta) {
                if wk.to_array().iter().all(|&v| v == 0.0) {
                    continue;
                }
                let (g, ok) = metric_gradient(metric, *fk, dk);
                for (sum, ga) in gradient.iter_mut().zip(g) {
                    *sum += chain * *wk * ga;
                }
                for (d, o) in defined.iter_mut().zip(ok) {
                    *d &= o;
                }
            }
        }
        for (d, v) in defined.iter_mut().zip(value.to_array()) {
            *d &= !v.is_nan();
        }
        Gradient8 { value, gradient, defined }
    }

    /// One value and its gradient (lane 0 of [`Texture::gradient8`]).
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::default(), None).unwrap();
    /// let (sample, g) = t.gradient([0.3, 0.7]);
    /// // The Euclidean F1 has a unit gradient wherever it is defined.
    /// assert!(!sample.defined || ((g[0] * g[0] + g[1] * g[1]).sqrt() - 1.0).abs() < 1e-5);
    /// ```
    pub fn gradient(&self, x: [f64; D]) -> (Sample, [f32; D]) {
        let g = self.gradient_lanes::<true>(&[x; 8], [0.0; 8]);
        let sample = Sample { value: g.value.to_array()[0], defined: g.defined[0] };
        (sample, g.gradient.map(|v| v.to_array()[0]))
    }
}

/// ∇F_k per lane for the metric, from F_k and its delta (sample − point),
/// and whether it exists.
fn metric_gradient<const D: usize>(metric: Metric, f: f32x8, delta: &[f32x8; D]) -> ([f32x8; D], [bool; 8]) {
    let fs = f.to_array();
    let d: [[f32; 8]; D] = delta.map(|v| v.to_array());
    let mut g = [[0f32; 8]; D];
    let mut ok = [true; 8];
    for i in 0..8 {
        let di: [f32; D] = std::array::from_fn(|a| d[a][i]);
        let fi = fs[i];
        if !(fi.is_finite() && fi > 0.0) {
            ok[i] = false;
            continue;
        }
        let mut gi = [0f32; D];
        match metric {
            Metric::Euclidean => {
                for a in 0..D {
                    gi[a] = di[a] / fi;
                }
            }
            Metric::Manhattan | Metric::Minkowski(1.0) => {
                for a in 0..D {
                    gi[a] = di[a].signum();
                    ok[i] &= di[a] != 0.0;
                }
            }
            Metric::Chebyshev => {
                // The dominant axis; a tie for it is a diagonal, where no
                // gradient exists.
                let m = di.iter().fold(0f32, |m, v| m.max(v.abs()));
                let a = (0..D).position(|a| di[a].abs() == m).unwrap_or(0);
                ok[i] &= (0..D).filter(|&b| di[b].abs() == m).count() == 1;
                gi[a] = di[a].signum();
            }
            Metric::Minkowski(p) => {
                let p = p as f32;
                for a in 0..D {
                    gi[a] = di[a].signum() * (di[a].abs() / fi).powf(p - 1.0);
                }
            }
        }
        for a in 0..D {
            g[a][i] = gi[a];
        }
    }
    (g.map(f32x8::from), ok)
}

/// Perturbs a unit normal by a texture gradient: the tangential part of
/// `gradient` scaled by `strength` is subtracted and the result normalised,
/// so the surface looks as if displaced by `strength · value` along the
/// normal. A zero or non-finite result leaves the normal unchanged.
pub fn bump(normal: glam::Vec3, gradient: glam::Vec3, strength: f32) -> glam::Vec3 {
    let tangential = gradient - normal * normal.dot(gradient);
    let n = (normal - strength * tangential).normalize_or_zero();
    if n == glam::Vec3::ZERO || !n.is_finite() {
        normal
    } else {
        n
    }
}
