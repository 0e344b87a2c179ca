//! Small numerical helpers: the gamma function, ball volumes and a seeded
//! uniform generator.
//!
//! The scale constant of the basis and the statistical tests need Γ at a few
//! arguments (Γ(1 + 1/d), Γ(1 + d/2), Γ(1 + d/p)). A Lanczos approximation is
//! accurate to about 1e-15 relative for positive arguments, far below the
//! statistical resolution of any test here.

/// Coefficients of the Lanczos series with g = 7 and nine terms, as published
/// by Paul Godfrey; they give Γ to about 15 significant digits.
const LANCZOS_G: f64 = 7.0;
const LANCZOS: [f64; 9] = [
    0.999_999_999_999_809_9,
    676.520_368_121_885_1,
    -1_259.139_216_722_402_8,
    771.323_428_777_653_1,
    -176.615_029_162_140_6,
    12.507_343_278_686_905,
    -0.138_571_095_265_720_12,
    9.984_369_578_019_572e-6,
    1.505_632_735_149_311_6e-7,
];

/// The gamma function Γ(x) for real x that is not a non-positive integer.
///
/// Uses the reflection formula below 1/2 and the Lanczos series above.
pub fn gamma(x: f64) -> f64 {
    if x < 0.5 {
        // Γ(x) Γ(1 − x) = π / sin(πx)
        std::f64::consts::PI / ((std::f64::consts::PI * x).sin() * gamma(1.0 - x))
    } else {
        let z = x - 1.0;
        let mut series = LANCZOS[0];
        for (i, c) in LANCZOS.iter().enumerate().skip(1) {
            series += c / (z + i as f64);
        }
        let t = z + LANCZOS_G + 0.5;
        (2.0 * std::f64::consts::PI).sqrt() * t.powf(z + 0.5) * (-t).exp() * series
    }
}

/// SplitMix64's output function applied to `seed + γ`.
pub const fn splitmix64(seed: u64) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A uniform f64 in [0, 1) from a seed and a counter (SplitMix64 twice): a
/// counter-based generator, so point i of a seeded set needs no other point.
/// The harness draws its samples with it, and
/// [`Texture::measure_range`](crate::texture::Texture::measure_range) its
/// sample points.
#[inline]
pub fn uniform(seed: u64, counter: u64) -> f64 {
    (splitmix64(seed ^ splitmix64(counter)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Volume of the Euclidean unit ball in `dim` dimensions: π^(d/2) / Γ(d/2 + 1).
pub fn euclidean_ball_volume(dim: usize) -> f64 {
    let d = dim as f64;
    std::f64::consts::PI.powf(d / 2.0) / gamma(d / 2.0 + 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_matches_factorials_and_half_integers() {
        // Γ(n) = (n − 1)! and Γ(1/2) = √π are exact identities.
        let mut factorial = 1.0;
        for n in 1..15 {
            let rel = (gamma(n as f64) - factorial).abs() / factorial;
            assert!(rel < 1e-13, "Γ({n}) off by {rel}");
            factorial *= n as f64;
        }
        let sqrt_pi = std::f64::consts::PI.sqrt();
        assert!((gamma(0.5) - sqrt_pi).abs() < 1e-14);
        assert!((gamma(1.5) - sqrt_pi / 2.0).abs() < 1e-14);
    }

    #[test]
    fn gamma_of_one_plus_inverse_matches_an_integral() {
        // Γ(1 + 1/d) = ∫₀^∞ exp(−t^d) dt: check by the trapezoid rule.
        for d in 2..=4 {
            let h: f64 = 1e-4;
            let mut sum = 0.5;
            let mut t = h;
            while t < 8.0 {
                sum += (-t.powi(d)).exp();
                t += h;
            }
            let integral = sum * h;
            let rel = (gamma(1.0 + 1.0 / d as f64) - integral).abs();
            assert!(rel < 1e-7, "d = {d}: {integral} vs {}", gamma(1.0 + 1.0 / d as f64));
        }
    }

    #[test]
    fn ball_volumes_match_closed_forms() {
        let pi = std::f64::consts::PI;
        assert!((euclidean_ball_volume(2) - pi).abs() < 1e-13);
        assert!((euclidean_ball_volume(3) - 4.0 * pi / 3.0).abs() < 1e-13);
        assert!((euclidean_ball_volume(4) - pi * pi / 2.0).abs() < 1e-13);
    }
}
