//! # The definition of the basis
//!
//! This module fixes, bit for bit, which feature points exist. Every
//! evaluator in the crate (the f64 reference, the brute-force oracle of the
//! harness, the SIMD kernel) measures distances to exactly these points, and a
//! second implementation that follows the text below reproduces them exactly.
//!
//! ## Cells
//! The input x (in user units) is multiplied by the scale S of the pattern
//! ([`Pattern::scale`]) to give cell coordinates u = x·S. Space is diced into
//! unit cells (squares in 2D, cubes in 3D, hypercubes in 4D); the cell of u
//! is c = ⌊u⌋ per axis, an `i64`. A cell index c is fed to the hash as one
//! 32-bit word, its *axis term*
//!
//! ```text
//! lo = c mod 2^32                      (the low 32 bits)
//! hi = (c − sign_extend_32(lo)) / 2^32 (exact; 0 for every c in i32 range)
//! t  = lo + hi · 0x165667B1            (mod 2^32)
//! ```
//!
//! so cells in the `i32` range hash from their low word alone, and larger
//! indices fold their upper word in without colliding with their neighbours.
//! Results are supported for |u| ≤ [`MAX_CELL_COORD`] (2^53, where f64 stops
//! having fractional bits); see [`Pattern::scale`] for that limit in user units.
//!
//! ## The cell hash
//! The 64-bit seed is folded once into two 32-bit keys: with
//! `z = splitmix64(seed)` (the finaliser of Steele, Lea and Flood's SplitMix64
//! applied to `seed + 0x9E3779B97F4A7C15`), `k_init = z mod 2^32` and
//! `k_final = z / 2^32`. Each axis term first goes through a full mix of its
//! own, its *axis word*, and the words are then chained, in wrapping 32-bit
//! arithmetic:
//!
//! ```text
//! w_a = fmix32(t_a ^ M_a)                       for each axis a = 0 .. d−1
//! h = k_init
//! for each axis a = 0 .. d−1:   h = (h ^ w_a) · M_a;  h = h ^ (h >> 16)
//! s = w_0 + … + w_{d−2}                          (every axis but the last)
//! h = fmix32((h + s) ^ k_final)
//! ```
//!
//! with `M = [0x9E3779B1, 0x85EBCA77, 0xC2B2AE3D, 0x27D4EB2F]` (the 32-bit
//! primes of xxHash) and `fmix32` MurmurHash3's finaliser
//! (`h ^= h >> 16; h *= 0x85EBCA6B; h ^= h >> 13; h *= 0xC2B2AE35; h ^= h >> 16`).
//! Every step is a bijection of a 32-bit word, so there is no period at 256,
//! 289 or 2^16 cells, one axis step changes every output bit with probability
//! ½, and the key pair (a bijection of the seed) changes the whole pattern.
//!
//! **Why each axis word is mixed before it enters the chain.** If a term
//! entered the chain as it is (`h ^ t_a`), two rows of cells whose chains
//! before axis a differ by δ (`h_A ^ h_B = δ`) would hold the same points at
//! `t` and `t ^ δ` for every `t`: whole rows, pencils or planes of cells
//! copied with a shift, and for some seeds many such pairs lie a few cells
//! apart. With a non-linear word, `h_A ^ w(t) = h_B ^ w(t')` holds for a
//! pair of cells by chance only, never along a run, so no strip of cells
//! repeats (the harness's `repeated_runs` counts this).
//!
//! **Why the sum s.** The chain summarises the axes before the last in 32
//! bits, so two rows of cells along the last axis whose chains meet before
//! it (chance 2^−32 per pair of rows: about one pair among the 45^3 rows of
//! a 4D window) would be copies along the whole axis. The sum of their words
//! is a second, independent 32-bit summary, so such rows repeat only where
//! both meet (2^−64 per pair). It costs d − 1 additions.
//!
//! The words of one sample's neighbouring cells are shared, so a kernel
//! mixes three words per axis per sample, not one per cell; the chain costs
//! d + 2 multiplies per cell.
//!
//! ## Population
//! The hash is the state s₀ of the linear congruential generator
//! `s_{k+1} = A·s_k + C mod 2^32` with A = 747796405 (a multiplier with a good
//! lattice structure from L'Ecuyer's 1999 tables) and C = 2891336453 (odd, so
//! the period is 2^32). The number of feature points in the cell is
//! `table[s₀ >> 24]`, the entry of a 256-entry [`PopulationTable`] picked by
//! the state's top 8 bits.
//!
//! ## Feature points
//! Point j (0-based) of a cell takes the d + 1 states s_{1+j(d+1)} ..
//! s_{(j+1)(d+1)}: the first is its **feature ID** (the state itself, except
//! that the state `0xFFFFFFFF`, which is [`INVALID_ID`], is reported as
//! `0xFFFFFFFE`: see [`feature_id`]), the next d give its
//! coordinates. A coordinate is the state's top 24 bits as a fixed-point
//! fraction of the cell, `(s >> 8) / 2^24`, in [0, 1 − 2^−24]; the point's
//! cell coordinates are `c_a + (s >> 8) · 2^−24`, which an f32 holds exactly
//! relative to its cell. Because the k-th state is `A_k·s₀ + C_k` with
//! constants computable once ([`lcg_jump`]), a SIMD kernel may produce every
//! coordinate with one independent multiply-add instead of a dependent chain.
//!
//! ## Scale
//! For a Poisson process of ρ points per unit volume, P(F1 > r) =
//! exp(−ρ·V_d·r^d) (V_d the volume of the unit ball) and so
//! E(F1) = Γ(1 + 1/d) / (ρ·V_d)^(1/d). With ρ = μ, the table's mean
//! population per cell, the scale S = Γ(1 + 1/d) / (μ·V_d)^(1/d) (cells per
//! user unit) makes the Euclidean F1 have mean 1.0 in user units. All
//! distances and delta vectors are reported in user units (cell-unit values
//! divided by S). Other metrics measure the same points, so their mean F1
//! differs.

use crate::config::{Config, ConfigError};
pub use crate::math::splitmix64;
use crate::math::{euclidean_ball_volume, gamma};

/// LCG multiplier A.
pub const LCG_MUL: u32 = 747_796_405;
/// LCG increment C.
pub const LCG_ADD: u32 = 2_891_336_453;
/// Bits of a feature point's fixed-point coordinate.
pub const FRACTION_BITS: u32 = 24;
/// One unit in the last place of a fixed-point coordinate, 2^−24.
pub const FRACTION_ULP: f64 = 1.0 / (1u64 << FRACTION_BITS) as f64;
/// Entries in a population table.
pub const TABLE_SIZE: usize = 256;
/// Largest supported |u| in cell coordinates: 2^53.
pub const MAX_CELL_COORD: f64 = 9_007_199_254_740_992.0;
/// The feature ID reported where no feature point is reported (invalid input,
/// or a window-mode F_k with fewer than k points in the block).
pub const INVALID_ID: u32 = u32::MAX;

/// Per-axis multipliers of the cell hash (xxHash's 32-bit primes).
pub const AXIS_MUL: [u32; 4] = [0x9E37_79B1, 0x85EB_CA77, 0xC2B2_AE3D, 0x27D4_EB2F];
/// Multiplier that folds the upper word of a cell index into its axis term.
pub const HIGH_WORD_MUL: u32 = 0x1656_67B1;

/// One step of the LCG.
#[inline]
pub const fn lcg_step(s: u32) -> u32 {
    s.wrapping_mul(LCG_MUL).wrapping_add(LCG_ADD)
}

/// Constants (A_k, C_k) with s_k = A_k·s₀ + C_k (mod 2^32): the LCG advanced
/// k steps in closed form.
pub const fn lcg_jump(k: u32) -> (u32, u32) {
    let (mut a, mut c) = (1u32, 0u32);
    let mut i = 0;
    while i < k {
        a = a.wrapping_mul(LCG_MUL);
        c = c.wrapping_mul(LCG_MUL).wrapping_add(LCG_ADD);
        i += 1;
    }
    (a, c)
}

/// MurmurHash3's 32-bit finaliser: a bijection with full avalanche.
#[inline]
pub const fn fmix32(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 13;
    h = h.wrapping_mul(0xC2B2_AE35);
    h ^= h >> 16;
    h
}

/// The two 32-bit keys a seed is folded into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeedKeys {
    /// Starts the per-axis chain.
    pub init: u32,
    /// Enters just before the final mix.
    pub finish: u32,
}

impl SeedKeys {
    /// Folds a 64-bit seed into its keys.
    pub const fn new(seed: u64) -> Self {
        let z = splitmix64(seed);
        SeedKeys { init: z as u32, finish: (z >> 32) as u32 }
    }
}

/// The 32-bit word a cell index contributes to the hash (see module docs).
#[inline]
pub const fn axis_term(c: i64) -> u32 {
    let lo = c as u32;
    let hi = (c.wrapping_sub(lo as i32 as i64) >> 32) as u32;
    lo.wrapping_add(hi.wrapping_mul(HIGH_WORD_MUL))
}

/// The axis word of axis `axis`'s term `t`: the term mixed on its own
/// before it enters the chain (see module docs).
#[inline]
pub const fn axis_word(axis: usize, t: u32) -> u32 {
    fmix32(t ^ AXIS_MUL[axis])
}

/// The hash of a cell (the LCG's initial state s₀), from the cell's axis
/// words ([`axis_word`]).
#[inline]
pub fn hash_words(keys: SeedKeys, words: &[u32]) -> u32 {
    let mut h = keys.init;
    for (w, m) in words.iter().zip(AXIS_MUL) {
        h = (h ^ w).wrapping_mul(m);
        h ^= h >> 16;
    }
    let s = words[..words.len().saturating_sub(1)].iter().fold(0u32, |s, w| s.wrapping_add(*w));
    fmix32(h.wrapping_add(s) ^ keys.finish)
}

/// The hash of a cell given by its integer coordinates.
#[inline]
pub fn cell_hash<const D: usize>(keys: SeedKeys, cell: [i64; D]) -> u32 {
    let words: [u32; D] = std::array::from_fn(|a| axis_word(a, axis_term(cell[a])));
    hash_words(keys, &words)
}

/// The feature ID of a point whose ID state is `s`: the state itself, except
/// that the one state equal to [`INVALID_ID`] is reported as
/// `INVALID_ID − 1`, so that no real feature point carries the sentinel. IDs
/// stay uniform over the other 2^32 − 1 values, with `0xFFFF_FFFE` twice as
/// likely as any other (2^−31 instead of 2^−32 per point).
#[inline]
pub const fn feature_id(s: u32) -> u32 {
    if s == INVALID_ID {
        INVALID_ID - 1
    } else {
        s
    }
}

/// A 256-entry table of cell populations.
///
/// Generated, not pasted: entry i is the smallest m whose Poisson(λ)
/// cumulative probability exceeds (i + ½)/256, i.e. the table is the Poisson
/// quantile function sampled at 256 evenly spaced probabilities. Each count m
/// then fills round-to-nearest of 256·P(m) entries (with the rounding carried
/// along the cumulative sum), so the table is as close to Poisson as 8 bits
/// allow. An optional *bump* raises an evenly spaced fraction of the 0 and 1
/// entries by one, as Worley's tuned table does.
#[derive(Clone, Debug, PartialEq)]
pub struct PopulationTable {
    entries: [u8; TABLE_SIZE],
    density: f64,
    bump: f64,
}

impl PopulationTable {
    /// The table for mean density λ = `density` and bump fraction `bump`.
    pub fn poisson(density: f64, bump: f64) -> Result<Self, ConfigError> {
        Config { density, bump, ..Config::default() }.validate()?;
        let mut entries = [0u8; TABLE_SIZE];
        let mut m = 0u32;
        let mut p = (-density).exp(); // P(0)
        let mut cdf = p;
        for (i, e) in entries.iter_mut().enumerate() {
            let q = (i as f64 + 0.5) / TABLE_SIZE as f64;
            while cdf <= q {
                m += 1;
                p *= density / m as f64;
                cdf += p;
            }
            *e = m as u8;
        }
        // Raise floor(N·bump) of the N low (0 or 1) entries, evenly spaced.
        let mut rank = 0.0f64;
        for e in entries.iter_mut().filter(|e| **e <= 1) {
            if ((rank + 1.0) * bump).floor() > (rank * bump).floor() {
                *e += 1;
            }
            rank += 1.0;
        }
        Ok(PopulationTable { entries, density, bump })
    }

    /// The population of a cell whose LCG state is `s0`.
    #[inline]
    pub fn population(&self, s0: u32) -> u32 {
        self.entries[(s0 >> 24) as usize] as u32
    }

    /// The 256 entries.
    pub fn entries(&self) -> &[u8; TABLE_SIZE] {
        &self.entries
    }

    /// The largest population a cell can have.
    pub fn max_population(&self) -> u32 {
        *self.entries.iter().max().unwrap_or(&0) as u32
    }

    /// μ, the mean population per cell (the realised density).
    pub fn mean(&self) -> f64 {
        self.entries.iter().map(|&e| e as f64).sum::<f64>() / TABLE_SIZE as f64
    }

    /// The λ the table was generated for.
    pub fn density(&self) -> f64 {
        self.density
    }

    /// The bump fraction the table was generated with.
    pub fn bump(&self) -> f64 {
        self.bump
    }
}

/// A feature point as the definition produces it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FeaturePoint<const D: usize> {
    /// The feature ID.
    pub id: u32,
    /// Fixed-point coordinates within the cell, each in [0, 2^24).
    pub fraction: [u32; D],
}

impl<const D: usize> FeaturePoint<D> {
    /// The point's offset from its cell's lower corner, in cell units.
    #[inline]
    pub fn offset(&self) -> [f64; D] {
        self.fraction.map(|f| f as f64 * FRACTION_ULP)
    }
}

/// The point set of one seed, density and dimension: everything an
/// evaluator needs to produce feature points and to scale distances.
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern<const D: usize> {
    keys: SeedKeys,
    table: PopulationTable,
    scale: f64,
}

impl<const D: usize> Pattern<D> {
    /// The pattern of `config`'s seed, density and bump.
    ///
    /// # Errors
    /// The configuration's first invalid field.
    pub fn new(config: &Config) -> Result<Self, ConfigError> {
        const { assert!(D >= 1 && D <= 4, "dimensions 1 to 4 are supported") };
        config.validate()?;
        let table = PopulationTable::poisson(config.density, config.bump)?;
        let d = D as f64;
        let scale = gamma(1.0 + 1.0 / d) / (table.mean() * euclidean_ball_volume(D)).powf(1.0 / d);
        Ok(Pattern { keys: SeedKeys::new(config.seed), table, scale })
    }

    /// S, cell units per user unit: u = x·S. The largest supported user
    /// coordinate is therefore [`MAX_CELL_COORD`] / S.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The population table.
    pub fn table(&self) -> &PopulationTable {
        &self.table
    }

    /// The seed's keys.
    pub fn keys(&self) -> SeedKeys {
        self.keys
    }

    /// Feature points per unit volume in user units (ρ = μ·S^d).
    pub fn user_density(&self) -> f64 {
        self.table.mean() * self.scale.powi(D as i32)
    }

    /// The cell and the fraction within it (in [0, 1]) of a user coordinate,
    /// or `None` for a non-finite or out-of-range coordinate.
    #[inline]
    pub fn locate(&self, x: [f64; D]) -> Option<([i64; D], [f64; D])> {
        let mut cell = [0i64; D];
        let mut frac = [0f64; D];
        for a in 0..D {
            let u = x[a] * self.scale;
            if u.is_nan() || u.abs() > MAX_CELL_COORD {
                return None;
            }
            let floor = u.floor();
            cell[a] = floor as i64;
            // Exact (Sterbenz) except for −1 < u < 0, where u + 1 rounds and
            // may give 1.0: the search is then exact for the rounded point.
            frac[a] = u - floor;
        }
        Some((cell, frac))
    }

    /// Calls `visit` with each feature point of `cell`, in index order.
    #[inline]
    pub fn for_each_point(&self, cell: [i64; D], mut visit: impl FnMut(FeaturePoint<D>)) {
        let s0 = cell_hash(self.keys, cell);
        let mut s = s0;
        for _ in 0..self.table.population(s0) {
            s = lcg_step(s);
            let id = feature_id(s);
            let mut fraction = [0u32; D];
            for f in fraction.iter_mut() {
                s = lcg_step(s);
                *f = s >> (32 - FRACTION_BITS);
            }
            visit(FeaturePoint { id, fraction });
        }
    }

    /// The feature points of `cell`, collected (for tests and tools).
    pub fn points(&self, cell: [i64; D]) -> Vec<FeaturePoint<D>> {
        let mut v = Vec::new();
        self.for_each_point(cell, |p| v.push(p));
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jump_ahead_matches_iteration() {
        let mut s = 0x1234_5678u32;
        let s0 = s;
        for k in 0..50 {
            let (a, c) = lcg_jump(k);
            assert_eq!(a.wrapping_mul(s0).wrapping_add(c), s, "k = {k}");
            s = lcg_step(s);
        }
    }

    #[test]
    fn axis_term_is_the_low_word_in_i32_range_and_folds_beyond() {
        for c in [0i64, 1, -1, i32::MAX as i64, i32::MIN as i64, 12345, -98765] {
            assert_eq!(axis_term(c), c as u32);
        }
        // Beyond i32 the upper word is folded in: these would alias on the
        // low word alone.
        let a = axis_term(1i64 << 32);
        let b = axis_term(0);
        assert_ne!(a, b);
        assert_eq!(a, HIGH_WORD_MUL);
        assert_ne!(axis_term(-(1i64 << 32)), axis_term(0));
        assert_ne!(axis_term((1i64 << 32) + 5), axis_term(5));
    }

    #[test]
    fn table_follows_the_poisson_law_to_table_resolution() {
        for lambda in [0.5f64, 1.0, 2.5, 3.0, 4.0, 8.0] {
            let t = PopulationTable::poisson(lambda, 0.0).unwrap();
            // The table is sorted (a quantile function).
            assert!(t.entries().windows(2).all(|w| w[0] <= w[1]));
            // Each count's share differs from P(m) by at most one entry.
            let mut p = (-lambda).exp();
            let mut cdf = p;
            let mut counted = 0usize;
            for m in 0..64u32 {
                if m > 0 {
                    p *= lambda / m as f64;
                    cdf += p;
                }
                counted += t.entries().iter().filter(|&&e| e as u32 == m).count();
                let expected = cdf * 256.0;
                assert!(
                    (counted as f64 - expected).abs() <= 1.0,
                    "λ {lambda}, m {m}: {counted} entries up to m, Poisson says {expected}"
                );
            }
            assert!((t.mean() - lambda).abs() < 0.02 * lambda.max(1.0), "λ {lambda}: mean {}", t.mean());
        }
    }

    #[test]
    fn default_table_has_poisson_dispersion() {
        // The README's reason for λ 5 over λ 6: at λ 5 the table's variance
        // equals its mean, as a Poisson law's does, to 10^-4.
        let dispersion = |lambda: f64| {
            let t = PopulationTable::poisson(lambda, 0.0).unwrap();
            let n = t.entries().len() as f64;
            let mean = t.entries().iter().map(|&e| e as f64).sum::<f64>() / n;
            let var = t.entries().iter().map(|&e| (e as f64 - mean).powi(2)).sum::<f64>() / n;
            var / mean
        };
        assert!((dispersion(crate::config::DEFAULT_DENSITY) - 1.0).abs() < 1e-4);
        assert!(dispersion(6.0) < 0.995 && dispersion(3.0) < 0.996);
        let t = PopulationTable::poisson(crate::config::DEFAULT_DENSITY, 0.0).unwrap();
        assert_eq!(t.max_population(), 13);
    }

    #[test]
    fn bump_raises_the_stated_fraction_of_low_entries() {
        let plain = PopulationTable::poisson(2.5, 0.0).unwrap();
        let bumped = PopulationTable::poisson(2.5, 0.75).unwrap();
        let low = plain.entries().iter().filter(|&&e| e <= 1).count();
        let raised = plain.entries().iter().zip(bumped.entries()).filter(|(a, b)| a != b).count();
        assert_eq!(raised, (low as f64 * 0.75).floor() as usize);
        assert!(plain.entries().iter().zip(bumped.entries()).all(|(a, b)| *b == *a || (*a <= 1 && *b == *a + 1)));
    }

    #[test]
    fn scale_makes_the_poisson_mean_one() {
        // E[F1] = Γ(1 + 1/d) / (ρ V)^(1/d) with ρ = μ S^d must be 1.
        fn check<const D: usize>() {
            let p = Pattern::<D>::new(&Config::default()).unwrap();
            let rho = p.user_density();
            let mean = gamma(1.0 + 1.0 / D as f64) / (rho * euclidean_ball_volume(D)).powf(1.0 / D as f64);
            assert!((mean - 1.0).abs() < 1e-12, "D = {D}: {mean}");
        }
        check::<2>();
        check::<3>();
        check::<4>();
    }

    #[test]
    fn points_follow_the_documented_recipe() {
        // Re-derive cell (3, −7, 11)'s points by hand from the module docs.
        let pattern = Pattern::<3>::new(&Config { seed: 42, ..Config::default() }).unwrap();
        let z = splitmix64(42);
        let mut h = z as u32;
        let mut sum = 0u32;
        for (axis, (c, m)) in [3i64, -7, 11].into_iter().zip(AXIS_MUL).enumerate() {
            let w = fmix32((c as u32) ^ m);
            h = (h ^ w).wrapping_mul(m);
            h ^= h >> 16;
            if axis < 2 {
                sum = sum.wrapping_add(w);
            }
        }
        let s0 = fmix32(h.wrapping_add(sum) ^ (z >> 32) as u32);
        let n = pattern.table().entries()[(s0 >> 24) as usize] as usize;
        let points = pattern.points([3, -7, 11]);
        assert_eq!(points.len(), n);
        for (j, p) in points.iter().enumerate() {
            let (a, c) = lcg_jump(1 + 4 * j as u32);
            let state = a.wrapping_mul(s0).wrapping_add(c);
            assert_eq!(p.id, if state == u32::MAX { u32::MAX - 1 } else { state });
            for axis in 0..3 {
                let (a, c) = lcg_jump(2 + 4 * j as u32 + axis as u32);
                assert_eq!(p.fraction[axis], a.wrapping_mul(s0).wrapping_add(c) >> 8);
            }
        }
    }

    #[test]
    fn locate_rejects_non_finite_and_out_of_range() {
        let p = Pattern::<2>::new(&Config::default()).unwrap();
        assert!(p.locate([f64::NAN, 0.0]).is_none());
        assert!(p.locate([0.0, f64::INFINITY]).is_none());
        assert!(p.locate([f64::NEG_INFINITY, 0.0]).is_none());
        assert!(p.locate([2.0 * MAX_CELL_COORD / p.scale(), 0.0]).is_none());
        let (cell, frac) = p.locate([-0.0, -1e-300]).unwrap();
        assert_eq!(cell, [0, -1]);
        assert_eq!(frac[0], 0.0);
        // −1e-300·S + 1 rounds to 1.0: the sample sits on its cell's upper face.
        assert_eq!(frac[1], 1.0);
    }
}
