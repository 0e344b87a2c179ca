//! Output ranges for display: a measured [`Range`] per texture and the
//! tabulated quantiles of one octave of each standard combination.

use super::{Combination, Texture};

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

impl<const D: usize, const N: usize> Texture<D, N> {
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
}

/// Output ranges of the [`STANDARD`](super::STANDARD) combinations for the default
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
