//! What a texture is built from beside its configuration and combination:
//! the fractal sum ([`Fractal`]), and the errors a build can meet
//! ([`TextureError`]).

use crate::config::ConfigError;
use crate::simd::PeriodError;

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

    pub(super) fn validate(&self) -> Result<(), TextureError> {
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
    /// The smoothness of [`Combination::Smooth`](super::Combination::Smooth)
    /// is negative, infinite or NaN.
    Smoothness(f32),
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
            TextureError::Smoothness(v) => write!(f, "smoothness {v} is invalid: use a finite number >= 0"),
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
