//! Textures on the basis: combinations of F1..Fn or the distance to the
//! cell's border ([`Combination::Border`]), fractal sums, their analytic
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

use crate::config::{Config, ConfigError, Metric, Mode};
use crate::filter::BlendCurve;
use crate::simd::{Border8, Features8, GridRows, Outputs, Period, PeriodError, Point, Simd, SimdBorder};

/// How F1..Fn are combined into one value.
#[derive(Clone, Debug, PartialEq)]
pub enum Combination {
    /// Σ c_k F_k with `c[k − 1]` the coefficient of F_k (at most n of them).
    Linear(Vec<f32>),
    /// F1 · F2.
    Product,
    /// F3² − F2².
    SquareDifference,
    /// The distance to the border of the sample's Voronoi cell
    /// ([`SimdBorder`]): even lines whatever the spacing of the points,
    /// where F2 − F1 widens between close pairs. Euclidean only; its
    /// gradient is the border plane's normal.
    Border,
}

impl Combination {
    /// F_k alone.
    pub fn f(k: usize) -> Self {
        let mut c = vec![0.0; k.max(1)];
        c[k.max(1) - 1] = 1.0;
        Combination::Linear(c)
    }

    /// F2 − F1, the "crackle" of cell borders.
    pub fn crackle() -> Self {
        Combination::Linear(vec![-1.0, 1.0])
    }

    /// The smallest order that computes this combination.
    pub fn order(&self) -> usize {
        match self {
            Combination::Linear(c) => c.len(),
            Combination::Product => 2,
            Combination::SquareDifference => 3,
            Combination::Border => 1,
        }
    }

    /// A short name, e.g. `F2-F1`, `0.5F1+2F3`, `F1*F2`, `border`.
    pub fn name(&self) -> String {
        match self {
            Combination::Product => "F1*F2".into(),
            Combination::Border => "border".into(),
            Combination::SquareDifference => "F3^2-F2^2".into(),
            Combination::Linear(c) => {
                let mut s = String::new();
                for (k, &v) in c.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                    let sign = if v < 0.0 {
                        "-"
                    } else if s.is_empty() {
                        ""
                    } else {
                        "+"
                    };
                    let m = v.abs();
                    let coefficient = if m == 1.0 { String::new() } else { format!("{m}") };
                    s += &format!("{sign}{coefficient}F{}", k + 1);
                }
                if s.is_empty() {
                    "0".into()
                } else {
                    s
                }
            }
        }
    }

    fn validate(&self, compiled: usize) -> Result<(), TextureError> {
        if let Combination::Linear(c) = self {
            if c.is_empty() {
                return Err(TextureError::NoCoefficients);
            }
            if let Some(k) = c.iter().position(|v| !v.is_finite()) {
                return Err(TextureError::Coefficient { index: k + 1, value: c[k] });
            }
        }
        if self.order() > compiled {
            return Err(TextureError::Order { needs: self.order(), compiled });
        }
        Ok(())
    }

    /// The combination of distances, in lanes. [`Combination::Border`] is
    /// not a function of distances: textures evaluate it through their
    /// [`SimdBorder`] and never call this for it (NaN if they did).
    #[inline(always)]
    fn value<const N: usize>(&self, f: &[f32x8; N]) -> f32x8 {
        match self {
            Combination::Border => f32x8::splat(f32::NAN),
            Combination::Linear(c) => {
                let mut v = f32x8::splat(0.0);
                for (ck, fk) in c.iter().zip(f) {
                    v += f32x8::splat(*ck) * *fk;
                }
                v
            }
            Combination::Product => f[0] * f[1],
            Combination::SquareDifference => f[2] * f[2] - f[1] * f[1],
        }
    }

    /// d(combination)/d(F_k) for each k, in lanes (none for
    /// [`Combination::Border`], whose gradient is its plane's normal).
    fn weights<const N: usize>(&self, f: &[f32x8; N]) -> [f32x8; N] {
        let mut w = [f32x8::splat(0.0); N];
        match self {
            Combination::Border => {}
            Combination::Linear(c) => {
                for (wk, ck) in w.iter_mut().zip(c) {
                    *wk = f32x8::splat(*ck);
                }
            }
            Combination::Product => {
                w[0] = f[1];
                w[1] = f[0];
            }
            Combination::SquareDifference => {
                w[1] = f32x8::splat(-2.0) * f[1];
                w[2] = f32x8::splat(2.0) * f[2];
            }
        }
        w
    }
}

/// A fractal sum G = Σ_{i < octaves} gain^i · C(lacunarity^i · x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fractal {
    /// Number of octaves (1 is the plain combination).
    pub octaves: u32,
    /// Frequency factor between octaves (> 1; a whole number for periodic
    /// textures, so each octave tiles with the same period).
    pub lacunarity: f32,
    /// Amplitude factor between octaves (0 < gain ≤ 1).
    pub gain: f32,
}

impl Default for Fractal {
    fn default() -> Self {
        Fractal { octaves: 1, lacunarity: 2.0, gain: 0.5 }
    }
}

impl Fractal {
    /// `octaves` octaves of lacunarity 2 and gain ½: Worley's G_n.
    pub fn octaves(octaves: u32) -> Self {
        Fractal { octaves, ..Fractal::default() }
    }

    fn validate(&self) -> Result<(), TextureError> {
        if !(self.lacunarity.is_finite() && self.lacunarity > 1.0) {
            return Err(TextureError::Lacunarity(self.lacunarity));
        }
        if !(self.gain.is_finite() && self.gain > 0.0 && self.gain <= 1.0) {
            return Err(TextureError::Gain(self.gain));
        }
        // The last octave must still change an f32 sum (amplitude ≥ 2^−24 of
        // the first) and its cells must stay wider than an f32 step of a
        // unit coordinate (frequency ≤ 2^24).
        let last = self.octaves.saturating_sub(1) as f64;
        let resolved = (self.gain as f64).powf(last) >= f64::from(f32::EPSILON) / 2.0
            && (self.lacunarity as f64).powf(last) <= 16_777_216.0;
        if self.octaves == 0 || self.octaves > 64 || !resolved {
            return Err(TextureError::Octaves { octaves: self.octaves, lacunarity: self.lacunarity, gain: self.gain });
        }
        Ok(())
    }
}

/// Why a texture could not be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TextureError {
    /// The configuration is invalid.
    Config(ConfigError),
    /// The period is invalid.
    Period(PeriodError),
    /// A linear combination with no coefficient.
    NoCoefficients,
    /// A coefficient is NaN or infinite.
    Coefficient {
        /// k of the coefficient of F_k.
        index: usize,
        /// Its value.
        value: f32,
    },
    /// The combination needs a higher order than the texture computes.
    Order {
        /// The order the combination needs.
        needs: usize,
        /// The texture's compile-time order.
        compiled: usize,
    },
    /// The lacunarity is not a finite number above 1 (or, for a periodic
    /// texture, not a whole number).
    Lacunarity(f32),
    /// The gain is not in (0, 1].
    Gain(f32),
    /// No octaves, or octaves beyond what f32 resolves.
    Octaves {
        /// Octaves asked for.
        octaves: u32,
        /// The lacunarity.
        lacunarity: f32,
        /// The gain.
        gain: f32,
    },
}

impl std::fmt::Display for TextureError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            TextureError::Config(e) => e.fmt(f),
            TextureError::Period(e) => e.fmt(f),
            TextureError::NoCoefficients => write!(f, "a linear combination needs at least one coefficient"),
            TextureError::Coefficient { index, value } => {
                write!(f, "coefficient of F{index} is {value}: use a finite number")
            }
            TextureError::Order { needs, compiled } => {
                write!(
                    f,
                    "the combination needs F1..F{needs} but the texture computes F1..F{compiled}: use order {needs}"
                )
            }
            TextureError::Lacunarity(l) => {
                write!(f, "lacunarity {l} is invalid: use a finite number above 1 (a whole number when periodic)")
            }
            TextureError::Gain(g) => write!(f, "gain {g} is invalid: use 0 < gain <= 1"),
            TextureError::Octaves { octaves, lacunarity, gain } => write!(
                f,
                "{octaves} octaves (lacunarity {lacunarity}, gain {gain}) are not resolved in f32: use 1 to 64, \
                 with gain^(octaves-1) >= 2^-24 and lacunarity^(octaves-1) <= 2^24"
            ),
        }
    }
}

impl std::error::Error for TextureError {}

impl From<ConfigError> for TextureError {
    fn from(e: ConfigError) -> Self {
        TextureError::Config(e)
    }
}

impl From<PeriodError> for TextureError {
    fn from(e: PeriodError) -> Self {
        TextureError::Period(e)
    }
}

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

/// An empirical output range: the remap to [0, 1] the chapter recommends.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Range {
    /// The 0.1 % quantile.
    pub lo: f32,
    /// The 99.9 % quantile.
    pub hi: f32,
}

impl Range {
    /// (v − lo) / (hi − lo), clamped to [0, 1]; NaN stays NaN.
    pub fn remap(&self, v: f32) -> f32 {
        ((v - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0)
    }
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
            combination,
            fractal,
            period,
            octaves,
            input_scale,
            curve: OnceLock::new(),
        })
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
        match &self.border {
            Some(border) => self.borders::<ONE>(border, x, frequency, period).distance,
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
            Combination::Product | Combination::Border => return None,
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
    fn gradient_lanes<const ONE: bool>(&self, x: &[[f64; D]; 8], width: [f32; 8]) -> Gradient8<D> {
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
            if let Some(border) = &self.border {
                let b = self.borders::<ONE>(border, x, frequency, period);
                let v = blend(b.distance);
                value = if i == 0 { v } else { value + f32x8::splat(amplitude) * v };
                for (sum, n) in gradient.iter_mut().zip(&b.normal) {
                    *sum += chain * *n;
                }
                for (d, v) in defined.iter_mut().zip(b.distance.to_array()) {
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

    /// Values of many points into a caller's buffer ([`Texture::value8`]
    /// eight at a time).
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out` is shorter than `xs`; nothing is written.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<3, 2>::new(worley::Config::default(), Combination::crackle(), Fractal::default(), None).unwrap();
    /// let points: Vec<[f32; 3]> = (0..50).map(|i| [i as f32 * 0.2, 0.0, 0.0]).collect();
    /// let mut out = vec![0.0; 50];
    /// t.values(&points, &mut out).unwrap();
    /// assert_eq!(out[17], t.value([17.0f32 * 0.2, 0.0, 0.0].map(f64::from)));
    /// ```
    pub fn values<P: Point<D>>(&self, xs: &[P], out: &mut [f32]) -> Result<(), crate::SizeError> {
        self.filtered_values(xs, None, out)
    }

    /// Values of many points, point i standing for a footprint of side
    /// `widths[i]` ([`Texture::filtered8`] eight at a time); `None` is the
    /// point samples of [`Texture::values`].
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out` or `widths` is shorter than `xs`;
    /// nothing is written.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::octaves(3), None).unwrap();
    /// let points: Vec<[f64; 2]> = (0..20).map(|i| [i as f64 * 0.3, 1.0]).collect();
    /// let widths: Vec<f32> = (0..20).map(|i| i as f32 * 0.05).collect();
    /// let mut out = vec![0.0; 20];
    /// t.filtered_values(&points, Some(&widths), &mut out).unwrap();
    /// assert_eq!(out[9], t.filtered(points[9], widths[9]));
    /// ```
    pub fn filtered_values<P: Point<D>>(
        &self,
        xs: &[P],
        widths: Option<&[f32]>,
        out: &mut [f32],
    ) -> Result<(), crate::SizeError> {
        if out.len() < xs.len() {
            return Err(crate::SizeError { needed: xs.len(), given: out.len() });
        }
        if let Some(w) = widths.filter(|w| w.len() < xs.len()) {
            return Err(crate::SizeError { needed: xs.len(), given: w.len() });
        }
        for (c, (chunk, dst)) in xs.chunks(8).zip(out.chunks_mut(8)).enumerate() {
            let mut block = [[0.0; D]; 8];
            let mut width = [0.0; 8];
            for (i, p) in chunk.iter().enumerate() {
                block[i] = p.coordinates();
                width[i] = widths.map_or(0.0, |w| w[c * 8 + i]);
            }
            let v = self.filtered8(&block, width).to_array();
            dst.copy_from_slice(&v[..dst.len()]);
        }
        Ok(())
    }

    /// Values of every point of a grid (axis 0 fastest), on all cores when
    /// the `parallel` feature is on; identical to the serial result and to
    /// [`Texture::value`] at each [`Grid::point`](crate::Grid::point).
    ///
    /// Without a period, and when every octave's frequency is a power of two
    /// (the default lacunarity 2), octave i of the grid is itself a grid,
    /// with origin and step scaled by its frequency, whose points are the
    /// octave's coordinates bit for bit (scaling by a power of two is exact
    /// and commutes with rounding): each octave then takes the coherent grid
    /// path of [`Simd::evaluate_grid_distances`], a band of rows at a time
    /// for all octaves, and the combination and the sum run in the order
    /// [`Texture::value8`] runs them. Other textures take eight points at a
    /// time through [`Texture::value8`].
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out.len() != grid.len()`.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// use worley::Grid;
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::octaves(2), None).unwrap();
    /// let grid = Grid { origin: [0.0, 0.0], step: [0.1, 0.1], size: [32, 16] };
    /// let mut image = vec![0.0; 32 * 16];
    /// t.values_grid(&grid, &mut image).unwrap();
    /// assert_eq!(image[32 + 3], t.value(grid.point(32 + 3)));
    /// ```
    pub fn values_grid(&self, grid: &crate::Grid<D>, out: &mut [f32]) -> Result<(), crate::SizeError> {
        self.filtered_grid(grid, 0.0, out)
    }

    /// Values of every point of a grid, each standing for a footprint of
    /// side `width` (a grid's samples usually stand for their step): the
    /// same bits as [`Texture::filtered8`] at each point, through the grid
    /// tiles octave by octave where [`Texture::values_grid`] takes them
    /// (octaves the footprint does not resolve are not evaluated), eight
    /// points at a time otherwise.
    ///
    /// # Errors
    /// [`crate::SizeError`] if `out.len() != grid.len()`.
    ///
    /// ```
    /// use worley::texture::{Combination, Fractal, Texture};
    /// use worley::Grid;
    /// let t = Texture::<2, 1>::new(worley::Config::default(), Combination::f(1), Fractal::octaves(6), None).unwrap();
    /// let grid = Grid { origin: [0.0, 0.0], step: [0.5, 0.5], size: [16, 16] };
    /// let mut image = vec![0.0; 16 * 16];
    /// t.filtered_grid(&grid, 0.5, &mut image).unwrap();
    /// assert_eq!(image[16 + 3], t.filtered(grid.point(16 + 3), 0.5));
    /// ```
    pub fn filtered_grid(&self, grid: &crate::Grid<D>, width: f32, out: &mut [f32]) -> Result<(), crate::SizeError> {
        let alpha: Vec<f32> = self.octaves.iter().map(|&(f, _, _)| self.weights(&[width; 8], f)[0]).collect();
        let Some(octaves) = self.octave_grids(grid, &alpha) else {
            return grid.fill_by_eights(out, |block| self.filtered8(block, [width; 8]).to_array());
        };
        let needed = grid.len().ok_or(crate::SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(crate::SizeError { needed, given: out.len() });
        }
        let width = grid.size[0];
        if needed == 0 {
            return Ok(());
        }
        let mean = if alpha.iter().all(|&a| a == 1.0) { f32::NAN } else { self.blend_curve().mean() };
        // Only the octaves the footprint resolves are evaluated.
        let rows: Vec<Option<GridRows<'_, D>>> =
            octaves.iter().zip(&alpha).map(|(g, &a)| (a != 0.0).then(|| self.values.grid_rows(g))).collect();
        // Rows `first..` of every octave, combined and summed into `dst`,
        // in the order and with the operations of `filtered8`.
        let band = |first: usize, dst: &mut [f32]| {
            let mut distances = vec![[0f32; N]; dst.len()];
            for (i, (octave, &(_, amplitude, _))) in rows.iter().zip(&self.octaves).enumerate() {
                let a = alpha[i];
                let Some(octave) = octave else {
                    for s in dst.iter_mut() {
                        *s = if i == 0 { mean } else { *s + amplitude * mean };
                    }
                    continue;
                };
                self.values.grid_rows_distances(octave, first, &mut distances);
                for (sum, d) in dst.chunks_mut(8).zip(distances.chunks(8)) {
                    let f: [f32x8; N] =
                        std::array::from_fn(|k| f32x8::from(std::array::from_fn(|j| d[j.min(d.len() - 1)][k])));
                    let v = self.combination.value(&f).to_array();
                    for (s, v) in sum.iter_mut().zip(v) {
                        let v = if a == 1.0 { v } else { a * v + (1.0 - a) * mean };
                        *s = if i == 0 { v } else { *s + amplitude * v };
                    }
                }
            }
        };
        #[cfg(feature = "parallel")]
        {
            use rayon::prelude::*;
            let rows = crate::simd::BAND;
            out.par_chunks_mut(rows * width).enumerate().for_each(|(b, dst)| band(b * rows, dst));
        }
        #[cfg(not(feature = "parallel"))]
        {
            let rows = crate::simd::SERIAL_BAND;
            out.chunks_mut(rows * width).enumerate().for_each(|(b, dst)| band(b * rows, dst));
        }
        Ok(())
    }

    /// Octave i of `grid` as a grid of its own (origin and step times the
    /// octave's frequency), where that gives the octave's coordinates bit
    /// for bit: no period, every frequency a power of two, and nothing
    /// scaled near overflow, no NaN or infinite origin or step.
    ///
    /// An octave the footprint does not resolve (weight 0) is its mean
    /// without evaluation, which is its value only where the kernel can
    /// locate every point: such an octave also needs the grid's extent
    /// within the kernel's range (else eight points at a time, which give
    /// NaN where the kernel would). A NaN weight takes eight points at a
    /// time too.
    fn octave_grids(&self, grid: &crate::Grid<D>, alpha: &[f32]) -> Option<Vec<crate::Grid<D>>> {
        let power_of_two = |f: f64| f.is_normal() && f > 0.0 && f.to_bits() & ((1u64 << 52) - 1) == 0;
        // The largest magnitude any point's coordinate or partial sum takes.
        let extent = (0..D).fold(0f64, |m, a| m.max(grid.origin[a].abs() + grid.step[a].abs() * grid.size[a] as f64));
        let finite = grid.origin.iter().chain(&grid.step).all(|v| v.is_finite());
        let suits = finite
            && self.border.is_none()
            && self.period.is_none()
            && self.octaves.iter().all(|&(f, _, _)| power_of_two(f) && extent * f < 1e300)
            && alpha.iter().zip(&self.octaves).all(|(&a, &(f, _, _))| {
                (0.0..=1.0).contains(&a)
                    && (a != 0.0
                        || extent * f * self.values.pattern().scale() < crate::definition::MAX_CELL_COORD / 2.0)
            });
        suits.then(|| {
            self.octaves
                .iter()
                .map(|&(f, _, _)| crate::Grid {
                    origin: grid.origin.map(|o| o * f),
                    step: grid.step.map(|s| s * f),
                    size: grid.size,
                })
                .collect()
        })
    }

    /// The range of values over `samples` random points (uniform in
    /// [−1000, 1000]^D, or over one period when periodic): the 0.1 % and
    /// 99.9 % quantiles.
    pub fn measure_range(&self, samples: usize, seed: u64) -> Range {
        let extent: [f64; D] = match self.period {
            Some(p) => p.cells().map(f64::from),
            None => [2000.0; D],
        };
        let offset = if self.period.is_some() { 0.0 } else { -1000.0 };
        let points: Vec<[f64; D]> = (0..samples)
            .map(|i| std::array::from_fn(|a| offset + extent[a] * crate::math::uniform(seed, (i * D + a) as u64)))
            .collect();
        let mut v = vec![0f32; samples];
        self.values(&points, &mut v).expect("buffer sized to the points");
        v.retain(|x| x.is_finite());
        v.sort_by(f32::total_cmp);
        if v.is_empty() {
            return Range { lo: f32::NAN, hi: f32::NAN };
        }
        let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
        Range { lo: q(0.001), hi: q(0.999) }
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

impl std::str::FromStr for Combination {
    type Err = String;

    /// `F1*F2`, `F3^2-F2^2`, `border`, or a linear sum of terms `[c]F<k>`
    /// such as `F2-F1`, `0.5F1+2F3`, `-1.5*F2+F4` (k from 1 to 16).
    fn from_str(s: &str) -> Result<Self, String> {
        let t: String = s.chars().filter(|c| !c.is_whitespace()).collect();
        let usage = "use F1*F2, F3^2-F2^2, border, or a sum of terms [c]Fk such as F2-F1 or 0.5F1+2F3";
        match t.as_str() {
            "F1*F2" => return Ok(Combination::Product),
            "border" => return Ok(Combination::Border),
            "F3^2-F2^2" => return Ok(Combination::SquareDifference),
            "" => return Err(format!("empty combination: {usage}")),
            _ => {}
        }
        let mut coefficients = Vec::new();
        let mut rest = t.as_str();
        while !rest.is_empty() {
            let sign = match rest.as_bytes()[0] {
                b'-' => -1.0,
                _ => 1.0,
            };
            if rest.starts_with(['+', '-']) {
                rest = &rest[1..];
            }
            let f = rest.find('F').ok_or_else(|| format!("{s:?}: a term without F: {usage}"))?;
            let number = rest[..f].trim_end_matches('*');
            let c: f32 = if number.is_empty() {
                1.0
            } else {
                number.parse().map_err(|_| format!("{s:?}: coefficient {number:?} is not a number: {usage}"))?
            };
            let digits = rest[f + 1..].find(['+', '-']).map_or(rest.len(), |e| f + 1 + e);
            let k: usize = rest[f + 1..digits]
                .parse()
                .map_err(|_| format!("{s:?}: F{} is not F1..F16: {usage}", &rest[f + 1..digits]))?;
            if !(1..=crate::config::MAX_ORDER).contains(&k) {
                return Err(format!("{s:?}: F{k} is not F1..F16: {usage}"));
            }
            if coefficients.len() < k {
                coefficients.resize(k, 0.0);
            }
            coefficients[k - 1] += sign * c;
            rest = &rest[digits..];
        }
        Ok(Combination::Linear(coefficients))
    }
}

/// The standard combinations whose output ranges are tabulated.
pub const STANDARD: [&str; 7] = ["F1", "F2", "F3", "F4", "F2-F1", "F1*F2", "F3^2-F2^2"];

/// Output ranges of the [`STANDARD`] combinations for the default
/// configuration (seed 0, λ 5, Euclidean, one octave): (dimension,
/// combination, 0.1 % quantile, 99.9 % quantile) over 10^6 random samples,
/// as printed by `worley ranges`. A test re-measures them.
pub const DEFAULT_RANGES: &[(usize, &str, f32, f32)] = &[
    (2, "F1", 0.0353, 2.9690),
    (2, "F2", 0.2399, 3.4230),
    (2, "F3", 0.4959, 3.7802),
    (2, "F4", 0.7349, 4.0744),
    (2, "F2-F1", 0.0006, 2.3685),
    (2, "F1*F2", 0.0201, 9.5644),
    (2, "F3^2-F2^2", 0.0012, 8.8061),
    (3, "F1", 0.1115, 2.1357),
    (3, "F2", 0.3986, 2.3518),
    (3, "F3", 0.6416, 2.5108),
    (3, "F4", 0.8438, 2.6390),
    (3, "F2-F1", 0.0004, 1.5385),
    (3, "F1*F2", 0.0779, 4.8133),
    (3, "F3^2-F2^2", 0.0007, 3.6044),
    (4, "F1", 0.1972, 1.7898),
    (4, "F2", 0.5120, 1.9220),
    (4, "F3", 0.7301, 2.0203),
    (4, "F4", 0.8911, 2.0962),
    (4, "F2-F1", 0.0003, 1.1843),
    (4, "F1*F2", 0.1545, 3.3332),
    (4, "F3^2-F2^2", 0.0004, 2.2042),
];

/// The tabulated range of a standard combination in the default
/// configuration, if there is one.
pub fn default_range(dim: usize, combination: &Combination) -> Option<Range> {
    DEFAULT_RANGES
        .iter()
        .find(|(d, n, _, _)| *d == dim && n.parse::<Combination>().as_ref() == Ok(combination))
        .map(|&(_, _, lo, hi)| Range { lo, hi })
}
