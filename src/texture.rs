//! Textures on the basis: combinations of F1..Fn, the distance to the
//! cell's border ([`Combination::Border`]), compact smooth F1
//! ([`Combination::Smooth`]) or the n-sphere radius
//! ([`Combination::NSphere`]), fractal sums, their analytic
//! gradients, a periodic (tileable) domain, and normal perturbation for bump
//! mapping, all on the 8-lane kernel.
//!
//! A [`Texture`] is built once from a [`Config`], a [`Combination`], a
//! [`Fractal`] and optionally a [`Period`]; every parameter is checked
//! there, so evaluation never meets an invalid one. One point is lane 0 of
//! an 8-lane call, so [`Texture::value`] and [`Texture::value8`] agree bit for
//! bit.
//!
//! ```
//! use worley::texture::{Combination, Fractal, Texture};
//! use worley::Config;
//! // The chapter's "crumple": F1 summed over octaves, as a bump.
//! let crumple = Texture::<3, 1>::new(Config::default(), Combination::f(1), Fractal::octaves(5), None).unwrap();
//! let (g, grad) = crumple.gradient([0.3, 1.2, 5.0]);
//! assert!(g.value > 0.0 && g.defined && grad.iter().all(|v| v.is_finite()));
//! ```

use std::sync::OnceLock;

use wide::f32x8;

use crate::config::{Config, Mode};
use crate::filter::BlendCurve;
use crate::simd::{
    Border8, Features8, NSphere8, Outputs, Period, PeriodError, Simd, SimdBorder, SimdNSphere, SimdSmooth, Smooth8,
};

mod batch;
mod combination;
mod gradient;
mod range;
mod settings;

pub use combination::{Combination, STANDARD};
pub use gradient::{bump, Gradient8};
pub use range::{default_range, Range, DEFAULT_RANGES};
pub use settings::{Fractal, TextureError};

/// A value and whether its gradient exists.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The texture's value (NaN for a bad input).
    pub value: f32,
    /// False where the metric's gradient does not exist at some term: the
    /// sample sits on a feature point, on a Manhattan axis plane through one,
    /// or on a Chebyshev diagonal, or the input is bad.
    pub defined: bool,
}

/// A texture: a combination of F1..FN, summed over octaves, on an unbounded
/// or periodic domain.
///
/// # Value ranges
///
/// In user units, with the default scale (mean Euclidean F1 = 1):
///
/// | output | range | typical values |
/// |---|---|---|
/// | F_k, Σ c_k·F_k with c_k ≥ 0, F1·F2, F3² − F2² | [0, ∞): no upper bound (a Poisson process has arbitrarily empty regions), ≥ 0 because F1 ≤ F2 ≤ … | the 0.1 % and 99.9 % quantiles of one octave in [`DEFAULT_RANGES`] (`worley ranges` measured them; a test re-measures them) |
/// | F2 − F1 | [0, ∞); 0 exactly on cell borders | as above |
/// | [`Combination::Border`] | [0, ∞); at least (F2 − F1)/2 | [`Texture::measure_range`] |
/// | [`Combination::Smooth`] with smoothness s | (−s, ∞): at most F1, above √(F1² + s²) − 2s | [`Texture::measure_range`] |
/// | [`Combination::NSphere`] | [0, ∞); at most (F1 + F2)/2 | [`Texture::measure_range`] |
/// | a fractal sum of n octaves | Σ a_i·C_i with a_i = gain^i: at least Σ a_i·lo_i, and at least 1 − n·0.1 % of samples at most Σ a_i·hi_i (a union bound on the octaves' quantiles) | [`Texture::measure_range`] |
///
/// NaN marks bad input only. For display, [`Texture::measure_range`] gives
/// the quantiles of this texture and [`Range::remap`] maps onto [0, 1]
/// (`examples/plane.rs` does both).
#[derive(Clone, Debug)]
pub struct Texture<const D: usize, const N: usize> {
    values: Simd<D, N>,
    deltas: Simd<D, N>,
    /// The border kernel, for [`Combination::Border`].
    border: Option<SimdBorder<D>>,
    /// Compact smooth F1 and its smoothness, for [`Combination::Smooth`].
    smooth: Option<(SimdSmooth<D>, f32)>,
    /// The n-sphere radius, for [`Combination::NSphere`].
    n_sphere: Option<SimdNSphere<D>>,
    combination: Combination,
    fractal: Fractal,
    period: Option<Period<D>>,
    /// Per octave: frequency, amplitude and, when periodic, period.
    octaves: Vec<(f64, f32, Option<Period<D>>)>,
    /// ∂(user coordinate)/∂(input coordinate): 1, or 1/S for periodic
    /// textures addressed in cells.
    input_scale: f32,
    /// The first octave's blend curve, measured on first use by a filtered
    /// call ([`Texture::blend_curve`]).
    curve: OnceLock<BlendCurve>,
}

impl<const D: usize, const N: usize> Texture<D, N> {
    /// Builds a texture on F1..FN. The order is the type's `N`, as for
    /// every typed evaluator: `config.order` is set to `N` whatever it held
    /// ([`Config::order`]). With a period, the
    /// texture is addressed in cells (see [`crate::simd::periodic`]) and
    /// the lacunarity must be a whole number.
    ///
    /// # Errors
    /// The first invalid parameter, with what is accepted.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// use worley::Config;
    /// // Three octaves of F2 − F1 in 3D.
    /// let crackle: Combination = "F2-F1".parse().unwrap();
    /// let t = Texture::<3, 2>::new(Config::default(), crackle, Fractal::octaves(3), None).unwrap();
    /// assert!(t.value([0.5, 1.5, -2.0]) >= 0.0);
    /// // A combination that needs F3 cannot be built on F1..F2.
    /// assert!(Texture::<3, 2>::new(Config::default(), "F3-F1".parse().unwrap(), Fractal::default(), None).is_err());
    /// ```
    pub fn new(
        config: Config,
        combination: Combination,
        fractal: Fractal,
        period: Option<Period<D>>,
    ) -> Result<Self, TextureError> {
        let config = Config { order: N, ..config };
        combination.validate(N)?;
        fractal.validate()?;
        let values = Simd::new(config, Outputs::Distances)?;
        let deltas = Simd::new(config, Outputs::IdsAndDeltas)?;
        let border = match combination {
            Combination::Border => Some(SimdBorder::new(config)?),
            _ => None,
        };
        let smooth = match combination {
            Combination::Smooth(s) => Some((SimdSmooth::new(config)?, s)),
            _ => None,
        };
        let n_sphere = match combination {
            Combination::NSphere => Some(SimdNSphere::new(config)?),
            _ => None,
        };
        let mut octaves = Vec::new();
        let (mut frequency, mut amplitude) = (1.0f64, 1.0f32);
        for _ in 0..fractal.octaves {
            let p = match period {
                None => None,
                Some(p) => {
                    let l = fractal.lacunarity;
                    if l.fract() != 0.0 {
                        return Err(TextureError::Lacunarity(l));
                    }
                    let cells = p.cells().map(|c| c as f64 * frequency);
                    if cells.iter().any(|&c| c > crate::simd::MAX_PERIOD as f64) {
                        let axis = cells.iter().position(|&c| c > crate::simd::MAX_PERIOD as f64).unwrap_or(0);
                        return Err(PeriodError { axis, given: cells[axis] as u64 }.into());
                    }
                    Some(Period::new(cells.map(|c| c as u32))?)
                }
            };
            octaves.push((frequency, amplitude, p));
            frequency *= f64::from(fractal.lacunarity);
            amplitude *= fractal.gain;
        }
        let input_scale = if period.is_some() { (1.0 / values.pattern().scale()) as f32 } else { 1.0 };
        Ok(Texture {
            values,
            deltas,
            border,
            smooth,
            n_sphere,
            combination,
            fractal,
            period,
            octaves,
            input_scale,
            curve: OnceLock::new(),
        })
    }

    /// The same texture with another fractal sum: the same configuration,
    /// combination and period, and the blend curve if this texture has
    /// measured it already ([`Texture::blend_curve`]), since the curve
    /// depends on the first octave alone. What a tool that changes the
    /// octaves, lacunarity or gain of a filtered texture calls, so that it
    /// measures the curve once (some 10^5 evaluations); the values are
    /// those of [`Texture::new`] with `fractal`, bit for bit.
    ///
    /// # Errors
    /// As [`Texture::new`] for `fractal`.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// use worley::Config;
    /// let base = Texture::<2, 1>::new(Config::default(), Combination::f(1), Fractal::octaves(2), None).unwrap();
    /// base.blend_curve();
    /// let more = base.with_fractal(Fractal::octaves(5)).unwrap();
    /// let fresh = Texture::<2, 1>::new(Config::default(), Combination::f(1), Fractal::octaves(5), None).unwrap();
    /// assert_eq!(more.filtered([0.3, 2.5], 0.2).to_bits(), fresh.filtered([0.3, 2.5], 0.2).to_bits());
    /// ```
    pub fn with_fractal(&self, fractal: Fractal) -> Result<Self, TextureError> {
        let mut t = Texture::new(*self.values.config(), self.combination.clone(), fractal, self.period)?;
        t.curve = self.curve.clone();
        Ok(t)
    }

    /// The combination.
    pub fn combination(&self) -> &Combination {
        &self.combination
    }

    /// The fractal parameters.
    pub fn fractal(&self) -> Fractal {
        self.fractal
    }

    /// The period, if the texture tiles.
    pub fn period(&self) -> Option<Period<D>> {
        self.period
    }

    /// The kernel underneath.
    pub fn kernel(&self) -> &Simd<D, N> {
        &self.values
    }

    /// Eight values ([`Texture::filtered8`] with zero footprints, the same
    /// bits).
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::default(), None).unwrap();
    /// let points: [[f64; 2]; 8] = std::array::from_fn(|i| [i as f64 * 0.3, 1.0]);
    /// assert_eq!(t.value8(&points).to_array()[4], t.value(points[4]));
    /// ```
    pub fn value8(&self, x: &[[f64; D]; 8]) -> f32x8 {
        self.filtered8(x, [0.0; 8])
    }

    /// Eight values, each standing for a footprint: a square of side
    /// `width[i]` (in the texture's input units: user units, or cells for a
    /// periodic texture) on a surface through `x[i]`, such as a pixel's
    /// preimage. Octave i blends its point sample towards the combination's
    /// mean with the weight of [`Texture::blend_curve`] at `width[i]` ·
    /// frequency_i ([`crate::filter`] derives it); an octave that no lane
    /// resolves is not evaluated, so the cost falls as the footprint grows.
    ///
    /// A zero width gives [`Texture::value8`]'s bits; values are continuous
    /// in position and in width; an infinite width gives the fractal sum of
    /// the means. A NaN or negative width, non-finite coordinates, or
    /// coordinates beyond the kernel's range in any octave give NaN, as the
    /// point sample does.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<3, 2>::new(worley::Config::default(), Combination::crackle(), Fractal::octaves(4), None).unwrap();
    /// let x: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64 * 0.7, 0.2, -3.0]);
    /// // A zero footprint is the point sample; a huge one the mean.
    /// assert_eq!(t.filtered8(&x, [0.0; 8]).to_array(), t.value8(&x).to_array());
    /// let far = t.filtered8(&x, [1e6; 8]).to_array();
    /// assert!(far.iter().all(|&v| v == far[0]));
    /// ```
    pub fn filtered8(&self, x: &[[f64; D]; 8], width: [f32; 8]) -> f32x8 {
        self.filtered_lanes::<false>(x, width)
    }

    /// [`Texture::filtered8`]; with `ONE`, the eight lanes hold one point
    /// (the one-point calls spread it so), and each octave's kernel runs its
    /// one-lane instantiation and spreads the result: the same bits at an
    /// eighth of the search. A const parameter, so that a caller of the
    /// eight-lane calls alone does not compile the one-lane kernels.
    #[inline(always)]
    fn filtered_lanes<const ONE: bool>(&self, x: &[[f64; D]; 8], width: [f32; 8]) -> f32x8 {
        let mut sum = f32x8::splat(0.0);
        for (i, &(frequency, amplitude, period)) in self.octaves.iter().enumerate() {
            let alpha = self.weights(&width, frequency);
            let v = if alpha.iter().all(|&a| a == 0.0) {
                self.unresolved(x, frequency, period)
            } else if alpha == [1.0; 8] {
                self.octave_value::<ONE>(x, i)
            } else {
                self.blend_curve().blend8(self.octave_value::<ONE>(x, i), alpha)
            };
            sum = if i == 0 { v } else { sum + f32x8::splat(amplitude) * v };
        }
        sum
    }

    /// One value standing for a footprint of side `width` (lane 0 of
    /// [`Texture::filtered8`]).
    pub fn filtered(&self, x: [f64; D], width: f32) -> f32 {
        self.filtered_lanes::<true>(&[x; 8], [width; 8]).to_array()[0]
    }

    /// The blend curve of the texture's first octave (its combination at
    /// frequency 1, in its input units), measured on first use by a
    /// filtered call and kept (about 4·10^5 evaluations of one octave);
    /// octave i reads it at width · frequency_i. Its mean is the Poisson
    /// process's closed form where one is known (linear combinations of F_n
    /// and F3² − F2², in exact mode with no bump and no period), else the
    /// measured mean.
    pub fn blend_curve(&self) -> &BlendCurve {
        self.curve.get_or_init(|| {
            let curve =
                BlendCurve::measure(|x: &[[f64; D]; 8]| self.octave_value::<false>(x, 0).to_array(), 0x0F17_7E25);
            match self.poisson_mean() {
                Some(mean) => curve.with_mean(mean),
                None => curve,
            }
        })
    }

    /// How many octaves a footprint of side `width` evaluates (the others
    /// contribute their mean): the cost of [`Texture::filtered8`] relative
    /// to [`Texture::value8`].
    pub fn resolved_octaves(&self, width: f32) -> usize {
        self.octaves.iter().filter(|&&(f, _, _)| self.weights(&[width; 8], f)[0] != 0.0).count()
    }

    /// The point samples' weights in an octave of frequency `frequency`;
    /// all 1, without measuring the curve, for zero widths.
    fn weights(&self, width: &[f32; 8], frequency: f64) -> [f32; 8] {
        if width.iter().all(|&w| w == 0.0) {
            return [1.0; 8];
        }
        let curve = self.blend_curve();
        width.map(|w| if w == 0.0 { 1.0 } else { curve.weight(w * frequency as f32) })
    }

    /// Octave i's combination (no amplitude) at eight points.
    #[inline(always)]
    fn octave_value<const ONE: bool>(&self, x: &[[f64; D]; 8], i: usize) -> f32x8 {
        let (frequency, _, period) = self.octaves[i];
        match self.own_kernel::<ONE>(x, frequency, period) {
            Some((value, _)) => value,
            None => self.combination.value(&self.features::<ONE>(&self.values, x, frequency, period).distance),
        }
    }

    /// An octave no lane resolves: the mean, and NaN where evaluating it
    /// would have given NaN (coordinates the kernel cannot locate).
    fn unresolved(&self, x: &[[f64; D]; 8], frequency: f64, period: Option<Period<D>>) -> f32x8 {
        let mean = self.blend_curve().mean();
        let (y, p) = self.octave(x, frequency, period);
        let pattern = self.values.pattern();
        f32x8::from(y.map(|q| {
            let located = match p {
                Some(_) => q.iter().all(|v| v.is_finite()),
                None => pattern.locate(q).is_some(),
            };
            if located {
                mean
            } else {
                f32::NAN
            }
        }))
    }

    /// The combination's mean under the Poisson process, in closed form,
    /// where one is known: E[F_k] = Γ(k + 1/d) / (Γ(k) Γ(1 + 1/d)) ·
    /// (V_2/V_m)^(1/d) and E[F_k²] = Γ(k + 2/d) / (Γ(k) Γ(1 + 1/d)²) ·
    /// (V_2/V_m)^(2/d), with V_2 and V_m the Euclidean and the metric's unit
    /// ball volumes (the scale makes the Euclidean E[F1] one).
    fn poisson_mean(&self) -> Option<f32> {
        use crate::math::{euclidean_ball_volume, gamma};
        let config = self.values.config();
        if config.mode != Mode::Exact || config.bump != 0.0 || self.period.is_some() {
            return None;
        }
        let d = D as f64;
        let ratio = euclidean_ball_volume(D) / config.metric.unit_ball_volume(D);
        let moment = |k: usize, m: f64| {
            let k = k as f64;
            gamma(k + m / d) / (gamma(k) * gamma(1.0 + 1.0 / d).powf(m)) * ratio.powf(m / d)
        };
        let mean = match &self.combination {
            Combination::Linear(c) => c.iter().enumerate().map(|(k, &ck)| f64::from(ck) * moment(k + 1, 1.0)).sum(),
            Combination::SquareDifference => moment(3, 2.0) - moment(2, 2.0),
            Combination::Product | Combination::Border | Combination::Smooth(_) | Combination::NSphere => {
                return None;
            }
        };
        Some(mean as f32)
    }

    /// One value: each octave's kernel runs one lane, with the bits of the
    /// point's lane in [`Texture::value8`]. Five octaves of F2 − F1 in 3D:
    /// 0.65 M points/s, 0.4 of [`Texture::values`]' per-point rate (1.7)
    /// and 1.7 times the same sum through the f64 reference (`cargo bench
    /// --bench single`).
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<3, 1>::new(worley::Config::default(), Combination::f(1), Fractal::default(), None).unwrap();
    /// let f1 = worley::Simd::<3, 1>::new(worley::Config::default(), worley::Outputs::Distances).unwrap();
    /// assert_eq!(t.value([1.0, 2.0, 3.0]), f1.evaluate([1.0, 2.0, 3.0]).distance[0]);
    /// ```
    pub fn value(&self, x: [f64; D]) -> f32 {
        self.filtered_lanes::<true>(&[x; 8], [0.0; 8]).to_array()[0]
    }

    /// The eight lanes' borders at `frequency · x` ([`Texture::octave`]);
    /// with `ONE`, lane 0's in one lane, spread.
    #[inline(always)]
    fn borders<const ONE: bool>(
        &self,
        border: &SimdBorder<D>,
        x: &[[f64; D]; 8],
        frequency: f64,
        period: Option<Period<D>>,
    ) -> Border8<D> {
        match (self.octave(x, frequency, period), ONE) {
            ((y, Some(p)), true) => Border8::splat(&border.border_periodic(y[0], &p)),
            ((y, None), true) => Border8::splat(&border.border(y[0])),
            ((y, Some(p)), false) => border.border8_periodic(&y, &p),
            ((y, None), false) => border.border8(&y),
        }
    }

    /// The combinations with a kernel of their own ([`Combination::Border`],
    /// [`Combination::Smooth`], [`Combination::NSphere`]): the eight lanes'
    /// value at `frequency · x` and its gradient there (the border plane's
    /// normal, ∇S, 0); `None` for the combinations of F1..Fn. With `ONE`,
    /// lane 0's in one lane, spread.
    #[inline(always)]
    fn own_kernel<const ONE: bool>(
        &self,
        x: &[[f64; D]; 8],
        frequency: f64,
        period: Option<Period<D>>,
    ) -> Option<(f32x8, [f32x8; D])> {
        if let Some(border) = &self.border {
            let b = self.borders::<ONE>(border, x, frequency, period);
            return Some((b.distance, b.normal));
        }
        if let Some(spheres) = &self.n_sphere {
            let n = match (self.octave(x, frequency, period), ONE) {
                ((y, Some(p)), true) => NSphere8::splat(&spheres.n_sphere_periodic(y[0], &p)),
                ((y, None), true) => NSphere8::splat(&spheres.n_sphere(y[0])),
                ((y, Some(p)), false) => spheres.n_sphere8_periodic(&y, &p),
                ((y, None), false) => spheres.n_sphere8(&y),
            };
            // Constant over each cell: 0, and NaN where the radius is NaN
            // (bad input) or +∞ (an empty window), as smooth F1's.
            let zero = n.radius * f32x8::splat(0.0);
            return Some((n.radius, [zero; D]));
        }
        let (smooth, s) = self.smooth.as_ref()?;
        let v = match (self.octave(x, frequency, period), ONE) {
            ((y, Some(p)), true) => Smooth8::splat(&smooth.smooth_periodic(y[0], &p, *s)),
            ((y, None), true) => Smooth8::splat(&smooth.smooth(y[0], *s)),
            ((y, Some(p)), false) => smooth.smooth8_periodic(&y, &p, *s),
            ((y, None), false) => smooth.smooth8(&y, *s),
        };
        Some((v.value, v.gradient))
    }

    /// The eight lanes' features at `frequency · x` ([`Texture::octave`]);
    /// with `ONE`, lane 0's in one lane, spread.
    #[inline(always)]
    fn features<const ONE: bool>(
        &self,
        kernel: &Simd<D, N>,
        x: &[[f64; D]; 8],
        frequency: f64,
        period: Option<Period<D>>,
    ) -> Features8<D, N> {
        match (self.octave(x, frequency, period), ONE) {
            ((y, Some(p)), true) => Features8::splat(&kernel.evaluate_periodic(y[0], &p)),
            ((y, None), true) => Features8::splat(&kernel.evaluate(y[0])),
            ((y, Some(p)), false) => kernel.evaluate8_periodic(&y, &p),
            ((y, None), false) => kernel.evaluate8(&y),
        }
    }

    /// The eight lanes' coordinates in an octave of frequency `frequency`,
    /// and the octave's period when the texture tiles.
    #[inline(always)]
    fn octave(
        &self,
        x: &[[f64; D]; 8],
        frequency: f64,
        period: Option<Period<D>>,
    ) -> ([[f64; D]; 8], Option<Period<D>>) {
        match (period, self.period) {
            (Some(p), Some(base)) => {
                // Reduce into the base period first, so that x and x + k·P
                // give the same octave coordinates bit for bit.
                let base = base.cells().map(f64::from);
                (x.map(|q| std::array::from_fn(|a| q[a].rem_euclid(base[a]) * frequency)), Some(p))
            }
            // v · 1 is v: the first octave's coordinates are the input's.
            _ if frequency == 1.0 => (*x, None),
            _ => (x.map(|q| q.map(|v| v * frequency)), None),
        }
    }
}
