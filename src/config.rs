//! What a caller asks for: seed, order, metric, search mode and density, and
//! the errors returned when a request is invalid.
//!
//! Every evaluator is built from a [`Config`]; building validates it, so an
//! evaluator that exists is always valid and its kernel never has to check.

use std::fmt;

use crate::math::{euclidean_ball_volume, gamma};

/// The largest order n for which F1..Fn can be asked.
pub const MAX_ORDER: usize = 16;

/// The default mean density λ (feature points per cube) of the population
/// table. Chosen by measurement with `worley tune`: of the densities swept,
/// λ 5 keeps the 8-lane kernel closest to the fastest setting of every order
/// and dimension at once; see the README's "Density" section.
pub const DEFAULT_DENSITY: f64 = 5.0;

/// Smallest and largest accepted density λ.
pub const DENSITY_RANGE: (f64, f64) = (0.25, 32.0);

/// A distance metric. Every metric measures the distance to the same feature
/// points; changing the metric changes the distances, never the point set.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Metric {
    /// √(Σ dᵢ²): round cells, smooth F1 inside a cell.
    Euclidean,
    /// Σ |dᵢ|: diamond-shaped distance, cells with straight 45° walls.
    Manhattan,
    /// max |dᵢ|: square distance, cells with axis-aligned and 45° walls.
    Chebyshev,
    /// (Σ |dᵢ|^p)^(1/p) for a finite p ≥ 1 (p = 1 is Manhattan, p = 2 is
    /// Euclidean up to rounding).
    Minkowski(f64),
}

impl Metric {
    /// Checks the metric's parameter.
    pub fn validate(self) -> Result<(), ConfigError> {
        match self {
            Metric::Minkowski(p) if !(p.is_finite() && p >= 1.0) => Err(ConfigError::MinkowskiExponent(p)),
            _ => Ok(()),
        }
    }

    /// A monotone "rank" of the length of `v`: the squared length for
    /// Euclidean, the length itself otherwise. Searches compare ranks so that
    /// no square root is taken per candidate point.
    ///
    /// For Minkowski the length is computed as m·(Σ(|vᵢ|/m)^p)^(1/p) with
    /// m = max|vᵢ|: every power is of a number in [0, 1] and the sum lies in
    /// [1, d], so nothing overflows or underflows for any finite p ≥ 1
    /// (Σ|vᵢ|^p itself overflows f64 for |vᵢ| = 3 at p ≈ 650 and flushes to
    /// zero for |vᵢ| = 0.1 at p ≈ 310). A term that underflows is below the
    /// sum's rounding, so dropping it is exact to rounding.
    #[inline]
    pub fn rank(self, v: &[f64]) -> f64 {
        match self {
            Metric::Euclidean => v.iter().map(|x| x * x).sum(),
            Metric::Manhattan => v.iter().map(|x| x.abs()).sum(),
            Metric::Chebyshev => v.iter().fold(0.0, |m, x| m.max(x.abs())),
            Metric::Minkowski(p) => {
                let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                if m == 0.0 || m.is_infinite() {
                    return m;
                }
                let sum: f64 = v.iter().map(|x| (x.abs() / m).powf(p)).sum();
                m * sum.powf(1.0 / p)
            }
        }
    }

    /// The rank of a vector of length `d` (inverse of [`Metric::distance_of_rank`]).
    #[inline]
    pub fn rank_of_distance(self, d: f64) -> f64 {
        match self {
            Metric::Euclidean => d * d,
            Metric::Manhattan | Metric::Chebyshev | Metric::Minkowski(_) => d,
        }
    }

    /// The length whose rank is `r`.
    #[inline]
    pub fn distance_of_rank(self, r: f64) -> f64 {
        match self {
            Metric::Euclidean => r.sqrt(),
            Metric::Manhattan | Metric::Chebyshev | Metric::Minkowski(_) => r,
        }
    }

    /// The length of `v` in this metric.
    pub fn distance(self, v: &[f64]) -> f64 {
        self.distance_of_rank(self.rank(v))
    }

    /// Volume of the metric's unit ball in `dim` dimensions, used by the
    /// Poisson law P(F1 > r) = exp(−ρ·V·r^d).
    pub fn unit_ball_volume(self, dim: usize) -> f64 {
        let d = dim as f64;
        match self {
            Metric::Euclidean => euclidean_ball_volume(dim),
            // the cross-polytope: 2^d / d!
            Metric::Manhattan => 2f64.powi(dim as i32) / gamma(d + 1.0),
            // the cube [−1, 1]^d
            Metric::Chebyshev => 2f64.powi(dim as i32),
            // the superball: (2 Γ(1 + 1/p))^d / Γ(1 + d/p)
            Metric::Minkowski(p) => (2.0 * gamma(1.0 + 1.0 / p)).powi(dim as i32) / gamma(1.0 + d / p),
        }
    }

    /// A short name for file names: `minkowski3` without the colon that
    /// [`Display`](fmt::Display) writes (the spelling [`str::parse`] reads).
    pub fn name(self) -> String {
        match self {
            Metric::Euclidean => "euclidean".into(),
            Metric::Manhattan => "manhattan".into(),
            Metric::Chebyshev => "chebyshev".into(),
            Metric::Minkowski(p) => format!("minkowski{p}"),
        }
    }
}

/// Parses `euclidean`, `manhattan`, `chebyshev` or `minkowski:P` (P ≥ 1,
/// finite), the spelling of the command line; anything else is an error
/// message saying what is accepted.
impl std::str::FromStr for Metric {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let metric = match s {
            "euclidean" => Metric::Euclidean,
            "manhattan" => Metric::Manhattan,
            "chebyshev" => Metric::Chebyshev,
            _ => match s.strip_prefix("minkowski:").map(str::parse::<f64>) {
                Some(Ok(p)) => Metric::Minkowski(p),
                _ => {
                    return Err(format!(
                        "unknown metric '{s}': use euclidean, manhattan, chebyshev or minkowski:P (P >= 1)"
                    ))
                }
            },
        };
        metric.validate().map_err(|e| e.to_string())?;
        Ok(metric)
    }
}

/// The command line's spelling, which [`str::parse`] reads back:
/// `euclidean`, `manhattan`, `chebyshev`, `minkowski:P` (P in Rust's
/// shortest round-trip form).
impl fmt::Display for Metric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Metric::Minkowski(p) => write!(f, "minkowski:{p}"),
            m => f.write_str(&m.name()),
        }
    }
}

/// How far the search goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Mode {
    /// Search the 3^d block, then widen shell by shell until no unvisited cube
    /// can hold a closer point: F1..Fn are exact for every order, metric and
    /// dimension.
    Exact,
    /// Search the 3^d block only, as Worley's code does. Fast, but F_k is
    /// wrong (and discontinuous) wherever fewer than k points of the block lie
    /// closer than its outside; a k-th point missing from the whole block is
    /// reported as an infinite distance.
    Window,
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Mode::Exact => "exact",
            Mode::Window => "window",
        })
    }
}

/// A request for an evaluator. Build one with struct update syntax over
/// [`Config::default`] and pass it to an evaluator's constructor, which
/// validates it.
///
/// ```
/// use worley::{Config, Metric, Reference};
/// let config = Config { order: 4, metric: Metric::Manhattan, ..Config::default() };
/// let basis = Reference::<3>::new(config).unwrap();
/// let f = basis.evaluate([0.5, 1.25, -3.0]);
/// assert!(f.distance[0] <= f.distance[3]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Config {
    /// Any 64-bit seed; every seed gives a different pattern.
    pub seed: u64,
    /// n: F1..Fn are computed (1 ..= [`MAX_ORDER`]). Read by
    /// [`Reference`](crate::Reference) and the command line; the typed
    /// evaluators take their order from their type instead (`N` of
    /// [`Simd<D, N>`](crate::Simd) and [`Texture<D, N>`](crate::texture::Texture),
    /// 1 for [`SimdBorder`](crate::SimdBorder)) and set this field to it,
    /// whatever it held.
    pub order: usize,
    /// The distance metric.
    pub metric: Metric,
    /// Exact (certified) or window (3^d block only) search.
    pub mode: Mode,
    /// Mean density λ of the Poisson population table, feature points per
    /// cube. Changes the pattern (and the speed), not the mean of F1.
    pub density: f64,
    /// Fraction in [0, 1] of the table's 0 and 1 populations raised by one,
    /// as in Worley's tuned table. 0 (the default) keeps a true Poisson
    /// process; anything else costs isotropy.
    pub bump: f64,
}

impl Default for Config {
    fn default() -> Self {
        Config { seed: 0, order: 1, metric: Metric::Euclidean, mode: Mode::Exact, density: DEFAULT_DENSITY, bump: 0.0 }
    }
}

impl Config {
    /// Checks every field; the error names the first invalid one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.order == 0 || self.order > MAX_ORDER {
            return Err(ConfigError::Order(self.order));
        }
        self.metric.validate()?;
        let (lo, hi) = DENSITY_RANGE;
        if !(self.density >= lo && self.density <= hi) {
            return Err(ConfigError::Density(self.density));
        }
        if !(0.0..=1.0).contains(&self.bump) {
            return Err(ConfigError::Bump(self.bump));
        }
        Ok(())
    }
}

/// Why a configuration was rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConfigError {
    /// The order is 0 or larger than [`MAX_ORDER`].
    Order(usize),
    /// The Minkowski exponent is below 1 (not a metric) or not finite.
    MinkowskiExponent(f64),
    /// The density is outside [`DENSITY_RANGE`] or NaN.
    Density(f64),
    /// The bump fraction is outside [0, 1] or NaN.
    Bump(f64),
    /// The distance to the cell's border was asked under a metric other
    /// than the Euclidean one, whose bisectors are not planes; or the
    /// n-sphere radius or compact smooth F1 in lanes
    /// ([`crate::SimdNSphere`], [`crate::SimdSmooth`]), which search around
    /// F1 in the border's Euclidean frame (the f64 reference takes every
    /// metric for both).
    BorderMetric(Metric),
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ConfigError::Order(n) => {
                write!(f, "order {n} is not supported: use 1 to {MAX_ORDER}")
            }
            ConfigError::MinkowskiExponent(p) => {
                write!(f, "Minkowski exponent {p} is not a metric: use a finite p >= 1 (or Chebyshev for p = infinity)")
            }
            ConfigError::Density(d) => write!(
                f,
                "density {d} is out of range: use {} to {} feature points per cube",
                DENSITY_RANGE.0, DENSITY_RANGE.1
            ),
            ConfigError::Bump(b) => {
                write!(f, "bump fraction {b} is out of range: use 0 to 1")
            }
            ConfigError::BorderMetric(m) => write!(
                f,
                "the distance to the cell border (and, in lanes, the n-sphere radius and smooth F1, which search in its frame) is defined for the Euclidean metric only, not {m}: its bisectors are not planes"
            ),
        }
    }
}

impl std::error::Error for ConfigError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_round_trip_through_their_text() {
        let exponents = [1.0, 1.5, 2.0, 3.0, 0.1 + 0.2 + 1.0, 1e6, 7.000000000000001];
        let metrics = [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev]
            .into_iter()
            .chain(exponents.map(Metric::Minkowski));
        for m in metrics {
            let text = m.to_string();
            assert_eq!(text.parse::<Metric>(), Ok(m), "{text}");
            assert!(!m.name().contains(':'), "{}", m.name());
        }
        assert_eq!(Metric::Minkowski(3.0).to_string(), "minkowski:3");
        // The error names what the user wrote.
        let e = "minkowski3".parse::<Metric>().unwrap_err();
        assert!(e.contains("'minkowski3'"), "{e}");
    }

    #[test]
    fn invalid_configurations_are_rejected_with_the_reason() {
        let bad = [
            (Config { order: 0, ..Config::default() }, "order 0"),
            (Config { order: MAX_ORDER + 1, ..Config::default() }, "order 17"),
            (Config { metric: Metric::Minkowski(0.5), ..Config::default() }, "exponent 0.5"),
            (Config { metric: Metric::Minkowski(f64::NAN), ..Config::default() }, "exponent NaN"),
            (Config { metric: Metric::Minkowski(f64::INFINITY), ..Config::default() }, "Chebyshev"),
            (Config { density: 0.0, ..Config::default() }, "density 0"),
            (Config { density: f64::NAN, ..Config::default() }, "density NaN"),
            (Config { bump: 1.5, ..Config::default() }, "bump fraction 1.5"),
            (Config { bump: -0.0 - 1e-9, ..Config::default() }, "bump fraction"),
        ];
        for (config, words) in bad {
            let err = config.validate().expect_err("must be rejected");
            assert!(err.to_string().contains(words), "{err} should mention {words}");
        }
        assert!(Config::default().validate().is_ok());
        assert!(Config { metric: Metric::Minkowski(1.0), order: MAX_ORDER, ..Config::default() }.validate().is_ok());
    }

    #[test]
    fn ball_volumes_agree_where_metrics_coincide() {
        for dim in 2..=4 {
            let e = Metric::Euclidean.unit_ball_volume(dim);
            let m2 = Metric::Minkowski(2.0).unit_ball_volume(dim);
            assert!((e - m2).abs() < 1e-12 * e, "dim {dim}: {e} vs {m2}");
            let l1 = Metric::Manhattan.unit_ball_volume(dim);
            let m1 = Metric::Minkowski(1.0).unit_ball_volume(dim);
            assert!((l1 - m1).abs() < 1e-12 * l1);
            // p → ∞ tends to the cube's volume 2^d.
            let big = Metric::Minkowski(400.0).unit_ball_volume(dim);
            assert!((big / Metric::Chebyshev.unit_ball_volume(dim) - 1.0).abs() < 0.02);
        }
    }
}
