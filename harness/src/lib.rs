//! # The shared harness
//!
//! One harness proves every evaluator right and measures how fast it is. It
//! takes the implementation under test as a parameter (anything that
//! implements [`Kernel`]) and runs a seeded [`Campaign`]:
//!
//! - **throughput**: every sample through [`Kernel::evaluate_batch`] on one
//!   thread, in samples per second;
//! - **oracle**: a share of the samples against the brute-force
//!   [`oracle::brute_force`], counting per order the distances that differ by
//!   more than the kernel's [`Kernel::error_bound`] and the IDs that differ
//!   where the distance is not a tie;
//! - **continuity**: pairs of points straddling cell faces, edges and corners
//!   (and pairs one ulp apart on exact lattice planes); F_k is 1-Lipschitz in
//!   its own metric, so a pair is a violation when |F_k(a) − F_k(b)| exceeds
//!   the metric distance between a and b plus both error bounds;
//! - **statistics**: mean F1, the Kolmogorov–Smirnov distance between the
//!   sampled F1 and the Poisson law P(F1 > r) = exp(−ρ·V·r^d), and the grid
//!   bias (mean F1 at cell centres over mean F1 at cell corners, minus one);
//! - **repeated strips**: cells whose hashes repeat along a run, against the
//!   uniform-hash expectation ([`repeats`]);
//! - **grid identity**: grids through the coherent path against the
//!   per-sample kernel, bit for bit ([`grids`]).
//!
//! Samples are drawn from a counter-based generator, so every figure is
//! reproducible from the campaign's seed, and the parallel parts give the
//! same counts on any number of threads.
//!
//! With the `runs` feature, the `runs` module runs a campaign at a
//! dimension and order chosen at run time, with every kernel it needs
//! compiled in this crate, where the workspace's test binaries share them.

pub mod continuity;
pub use continuity::{continuity, filtered_continuity, first_in_cell, lattice_coordinate, FilteredContinuity};
pub mod fuzz;
pub mod grids;
pub mod oracle;
pub mod repeats;
pub mod report;
#[cfg(feature = "runs")]
pub mod runs;

use std::time::Instant;

use worley::config::{Config, Mode, MAX_ORDER};
use worley::definition::Pattern;
use worley::reference::{outside_distance, Features, Reference};

pub use report::{OrderReport, Report};

/// An evaluator under test.
pub trait Kernel<const D: usize>: Sync {
    /// A short name for reports.
    fn name(&self) -> String;
    /// The configuration it was built from.
    fn config(&self) -> &Config;
    /// Its point set.
    fn pattern(&self) -> &Pattern<D>;
    /// F1..Fn at one point.
    fn evaluate(&self, x: [f64; D]) -> Features<D>;
    /// F1..Fn at many points (the throughput path); `out.len() == xs.len()`.
    fn evaluate_batch(&self, xs: &[[f64; D]], out: &mut [Features<D>]) {
        for (x, o) in xs.iter().zip(out.iter_mut()) {
            *o = self.evaluate(*x);
        }
    }
    /// The largest |F_k(kernel) − F_k(exact)| the kernel claims at a sample
    /// whose largest |coordinate| is `magnitude` and whose F_k is `f`,
    /// counting the rounding of x·S as part of the error.
    fn error_bound(&self, magnitude: f64, f: f64) -> f64;
    /// `grids` grids of the [`grids`] campaign against the kernel's own
    /// per-sample results, for kernels with a grid path of their own.
    fn grid_identity(&self, _seed: u64, _grids: usize, _range: f64) -> Option<grids::GridIdentity> {
        None
    }
}

impl<const D: usize> Kernel<D> for Reference<D> {
    fn name(&self) -> String {
        "reference-f64".into()
    }
    fn config(&self) -> &Config {
        Reference::config(self)
    }
    fn pattern(&self) -> &Pattern<D> {
        Reference::pattern(self)
    }
    fn evaluate(&self, x: [f64; D]) -> Features<D> {
        Reference::evaluate(self, x)
    }
    /// A few ulps of the distance, plus the rounding of x·S (half an ulp of
    /// the coordinate per axis, so at most √d·ulp(|x|) in any Lp metric).
    fn error_bound(&self, magnitude: f64, f: f64) -> f64 {
        8.0 * f64::EPSILON * (f + 2.0 * magnitude + 1.0)
    }
}

impl<const D: usize, const N: usize> Kernel<D> for worley::simd::Simd<D, N> {
    fn name(&self) -> String {
        // The lanes of a slice, and the SIMD level in force (its first
        // word: avx512f, avx2, sse4.1, sse2), so that every report names it.
        let level = worley::simd_level().split(' ').next().unwrap_or("");
        format!("simd-f32x{} {level}", self.slice_lanes())
    }
    fn config(&self) -> &Config {
        worley::simd::Simd::config(self)
    }
    fn pattern(&self) -> &Pattern<D> {
        worley::simd::Simd::pattern(self)
    }
    /// The 1-lane instantiation.
    fn evaluate(&self, x: [f64; D]) -> Features<D> {
        widen_features(&worley::simd::Simd::evaluate(self, x))
    }
    /// The 8-lane instantiation through the slice API.
    fn evaluate_batch(&self, xs: &[[f64; D]], out: &mut [Features<D>]) {
        let mut lanes = [worley::simd::Features32::<D, N> { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; 64];
        for (chunk, dst) in xs.chunks(64).zip(out.chunks_mut(64)) {
            self.evaluate_slice(chunk, &mut lanes).expect("a chunk of 64 fits 64 results");
            for (o, r) in dst.iter_mut().zip(&lanes) {
                *o = widen_features(r);
            }
        }
    }
    /// f32 arithmetic relative to the cell: the fraction is rounded to f32
    /// once and each delta and rank a few more times, about 2^−22 relative
    /// to F plus 2^−23 cell units absolute; independent of |x|.
    fn error_bound(&self, _magnitude: f64, f: f64) -> f64 {
        let cell = 1.0 / self.pattern().scale();
        4.0 * f32::EPSILON as f64 * (f + cell)
    }
    fn grid_identity(&self, seed: u64, grids: usize, range: f64) -> Option<grids::GridIdentity> {
        let mut found = grids::grid_identity(self, seed, grids, range);
        (found.texture_samples, found.texture_differing) =
            grids::texture_identity::<D, N>(*self.config(), seed, grids, range);
        Some(found)
    }
}

/// An f32 result as the harness's f64 [`Features`].
pub fn widen_features<const D: usize, const N: usize>(r: &worley::simd::Features32<D, N>) -> Features<D> {
    let mut out = Features::empty(N);
    for k in 0..N {
        out.distance[k] = r.distance[k] as f64;
        out.delta[k] = r.delta[k].map(f64::from);
        out.id[k] = r.id[k];
    }
    // The SIMD kernel does not report how far it searched: 0 marks that
    // unknown, and the report then shows the widened share as n/a.
    out.shells = 0;
    out
}

/// A seeded test campaign.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Campaign {
    /// Seed of the sample generator (not of the pattern).
    pub seed: u64,
    /// Random samples for throughput and statistics.
    pub samples: usize,
    /// Of those, how many are checked against the brute-force oracle.
    pub oracle_samples: usize,
    /// Samples are uniform in [−range, range]^d (user units).
    pub range: f64,
    /// Straddling pairs for the continuity check.
    pub pairs: usize,
    /// Cells sampled at centre and corner for the grid bias.
    pub grid_cells: usize,
}

impl Default for Campaign {
    fn default() -> Self {
        Campaign {
            seed: 1,
            samples: 1_000_000,
            oracle_samples: 200_000,
            range: 1000.0,
            pairs: 200_000,
            grid_cells: 1_000_000,
        }
    }
}

/// A uniform f64 in [0, 1) from a seed and a counter (the kernel crate's
/// generator, so the harness and `Texture::measure_range` draw alike).
pub use worley::math::uniform;

/// Sample i of a campaign: uniform in [−range, range]^d.
#[inline]
pub fn sample_point<const D: usize>(seed: u64, i: usize, range: f64) -> [f64; D] {
    std::array::from_fn(|a| (2.0 * uniform(seed, (i * D + a) as u64) - 1.0) * range)
}

/// How much of a long test campaign runs. `cargo test` runs each long
/// campaign in part ([`Tier::Quick`]), so that the suite answers in about a
/// minute; `cargo test -- --ignored` runs the same campaigns whole
/// ([`Tier::Full`], the tests named `campaign_…`). CI runs both.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    /// A tenth of each campaign (at least one case).
    Quick,
    /// The whole campaign.
    Full,
}

impl Tier {
    /// The number of cases this tier runs of a campaign of `full` cases.
    ///
    /// ```
    /// use worley_harness::Tier;
    /// assert_eq!(Tier::Full.of(1_000_000), 1_000_000);
    /// assert_eq!(Tier::Quick.of(1_000_000), 100_000);
    /// assert_eq!(Tier::Quick.of(3), 1);
    /// ```
    pub fn of(self, full: usize) -> usize {
        match self {
            Tier::Quick => full.div_ceil(10),
            Tier::Full => full,
        }
    }
}

/// Two tests of one campaign, `campaign(tier)`: `$quick` runs it in part
/// ([`Tier::Quick`]), `$whole` (ignored, so that `cargo test -- --ignored`
/// runs it; named `campaign_…` by convention) whole.
///
/// ```
/// fn strips(tier: worley_harness::Tier) {
///     assert!(tier.of(6) >= 1);
/// }
/// worley_harness::tiered!(no_repeated_strips, campaign_no_repeated_strips, strips);
/// ```
#[macro_export]
macro_rules! tiered {
    ($quick:ident, $whole:ident, $campaign:path) => {
        #[test]
        fn $quick() {
            $campaign($crate::Tier::Quick);
        }

        #[test]
        #[ignore = "campaign: cargo test -- --ignored"]
        fn $whole() {
            $campaign($crate::Tier::Full);
        }
    };
}

/// `f(i, chunk)` for every chunk `i` of `size` items of `out` (the last may
/// be shorter), on all cores with the `parallel` feature: the command
/// line's bands of image rows. A `dyn` closure, as in [`chunked`].
pub fn for_each_chunk<T: Send>(out: &mut [T], size: usize, f: &(dyn Fn(usize, &mut [T]) + Sync)) {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        out.par_chunks_mut(size.max(1)).enumerate().for_each(|(i, chunk)| f(i, chunk));
    }
    #[cfg(not(feature = "parallel"))]
    out.chunks_mut(size.max(1)).enumerate().for_each(|(i, chunk)| f(i, chunk));
}

/// Runs `f` over `0..n` in chunks, on all cores with the `parallel`
/// feature, and returns the chunks' results in order.
pub fn chunked<A: Send>(n: usize, f: impl Fn(std::ops::Range<usize>) -> A + Sync + Send) -> Vec<A> {
    chunked_dyn(n, &f)
}

/// [`chunked`] with its work as a `dyn` closure: rayon's generic machinery
/// is compiled once per result type, not once per caller and kernel.
fn chunked_dyn<A: Send>(n: usize, f: &(dyn Fn(std::ops::Range<usize>) -> A + Sync)) -> Vec<A> {
    const CHUNK: usize = 4096;
    let chunks = n.div_ceil(CHUNK);
    let range = move |c: usize| c * CHUNK..((c + 1) * CHUNK).min(n);
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        (0..chunks).into_par_iter().map(|c| f(range(c))).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        (0..chunks).map(|c| f(range(c))).collect()
    }
}

/// Runs the whole campaign against `kernel`.
pub fn run<const D: usize, K: Kernel<D>>(kernel: &K, campaign: &Campaign) -> Report {
    let config = *kernel.config();
    let mut report = Report::new::<D>(kernel.name(), &config, kernel.pattern(), campaign);
    throughput_and_statistics(kernel, campaign, &mut report);
    compare_with_oracle(kernel, campaign, &mut report);
    continuity(kernel, campaign, &mut report);
    report.grid_bias = grid_bias(kernel, campaign);
    // As many cells as the grid bias samples, at least 2 per axis.
    let side = (campaign.grid_cells as f64).powf(1.0 / D as f64).floor().max(2.0) as i64;
    let keys = kernel.pattern().keys();
    report.repeats = Some(repeats::repeated_runs::<D>(side, |c| worley::definition::cell_hash(keys, c)));
    // About one grid sample per oracle sample.
    report.grids = kernel.grid_identity(campaign.seed, campaign.oracle_samples.div_ceil(400), campaign.range);
    report
}

/// Throughput on one thread; mean F1, KS distance and widening from the same
/// evaluations.
pub fn throughput_and_statistics<const D: usize, K: Kernel<D>>(kernel: &K, campaign: &Campaign, report: &mut Report) {
    const BATCH: usize = 1024;
    let order = kernel.config().order;
    // On the heap: a batch of results is too large for the stack.
    let mut points = vec![[0.0; D]; BATCH].into_boxed_slice();
    let mut out = vec![Features::<D>::empty(order); BATCH].into_boxed_slice();
    let mut f1 = Vec::with_capacity(campaign.samples);
    let mut widened = 0usize;
    let mut max_shells = 0u32;
    let mut seconds = 0.0;
    let mut start = 0;
    while start < campaign.samples {
        let n = BATCH.min(campaign.samples - start);
        for (i, p) in points[..n].iter_mut().enumerate() {
            *p = sample_point(campaign.seed, start + i, campaign.range);
        }
        let t = Instant::now();
        kernel.evaluate_batch(&points[..n], &mut out[..n]);
        seconds += t.elapsed().as_secs_f64();
        for o in &out[..n] {
            f1.push(o.distance[0]);
            widened += (o.shells > 1) as usize;
            max_shells = max_shells.max(o.shells);
        }
        start += n;
    }
    report.throughput = campaign.samples as f64 / seconds.max(1e-12);
    // A kernel that reports no search radius (max_shells 0) has no widened share.
    report.widened = if max_shells == 0 { f64::NAN } else { widened as f64 / campaign.samples.max(1) as f64 };
    report.max_shells = max_shells;
    report.mean_f1 = f1.iter().sum::<f64>() / f1.len().max(1) as f64;
    let config = kernel.config();
    let rho_v = kernel.pattern().user_density() * config.metric.unit_ball_volume(D);
    report.ks = ks_distance(&mut f1, |r| 1.0 - (-rho_v * r.powi(D as i32)).exp());
}

/// The Kolmogorov–Smirnov distance between the sample and a CDF.
pub fn ks_distance(sample: &mut [f64], cdf: impl Fn(f64) -> f64) -> f64 {
    sample.sort_by(|a, b| a.total_cmp(b));
    let n = sample.len() as f64;
    let mut d: f64 = 0.0;
    for (i, &r) in sample.iter().enumerate() {
        let g = cdf(r);
        d = d.max((i as f64 + 1.0) / n - g).max(g - i as f64 / n);
    }
    d
}

/// Oracle agreement per order, and per order the fraction of samples whose
/// exact F_k lies beyond the 3^d block's outside (those need a wider search).
pub fn compare_with_oracle<const D: usize, K: Kernel<D>>(kernel: &K, campaign: &Campaign, report: &mut Report) {
    let config = *kernel.config();
    let order = config.order;
    let pattern = kernel.pattern();
    let parts = chunked(campaign.oracle_samples, |range| {
        let mut part = vec![OrderReport::default(); order];
        let mut scratch = Vec::new();
        for i in range {
            let x = sample_point::<D>(campaign.seed, i, campaign.range);
            let got = kernel.evaluate(x);
            // One order more than asked, so that a tie between F_n and
            // F_{n+1} is seen as one.
            let known = (order + 1).min(MAX_ORDER);
            let want = oracle::brute_force(pattern, config.metric, known, x, &mut scratch);
            let magnitude = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let f = pattern.locate(x).map(|(_, f)| f).unwrap_or([0.0; D]);
            let block_edge = outside_distance(&f, 1) / pattern.scale();
            for (k, p) in part.iter_mut().enumerate() {
                let tol = kernel.error_bound(magnitude, want.distance[k]);
                let err = (got.distance[k] - want.distance[k]).abs();
                let wrong = err.is_nan() || err > tol; // NaN or ∞ counts as wrong
                p.oracle_disagreements += wrong as u64;
                if !wrong {
                    p.max_error = p.max_error.max(err);
                }
                let tied = (k > 0 && want.distance[k] - want.distance[k - 1] <= 2.0 * tol)
                    || (k + 1 < known && want.distance[k + 1] - want.distance[k] <= 2.0 * tol);
                p.id_disagreements += (!wrong && !tied && got.id[k] != want.id[k]) as u64;
                p.needs_wider += (want.distance[k] > block_edge) as u64;
            }
        }
        part
    });
    for part in parts {
        for (total, p) in report.orders.iter_mut().zip(part) {
            total.oracle_disagreements += p.oracle_disagreements;
            total.id_disagreements += p.id_disagreements;
            total.needs_wider += p.needs_wider;
            total.max_error = total.max_error.max(p.max_error);
        }
    }
}

/// Mean F1 at cell centres over mean F1 at cell corners, minus one.
pub fn grid_bias<const D: usize, K: Kernel<D>>(kernel: &K, campaign: &Campaign) -> f64 {
    let scale = kernel.pattern().scale();
    let cells = (campaign.range * scale).floor().max(1.0);
    let seed = campaign.seed ^ 0x6121_D0B1_A5ED;
    let parts = chunked(campaign.grid_cells, |range| {
        let (mut centre, mut corner) = (0.0, 0.0);
        for i in range {
            let c: [f64; D] =
                std::array::from_fn(|a| ((2.0 * uniform(seed, (i * D + a) as u64) - 1.0) * cells).floor());
            centre += kernel.evaluate(c.map(|v| (v + 0.5) / scale)).distance[0];
            corner += kernel.evaluate(c.map(|v| v / scale)).distance[0];
        }
        (centre, corner)
    });
    let (centre, corner) = parts.iter().fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d));
    centre / corner - 1.0
}

/// Builds the window-mode twin of a configuration (for wrong-rate tables).
pub fn window_of(config: Config) -> Config {
    Config { mode: Mode::Window, ..config }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ks_distance_of_a_perfect_sample_is_one_over_n() {
        let mut s: Vec<f64> = (0..1000).map(|i| (i as f64 + 0.5) / 1000.0).collect();
        let d = ks_distance(&mut s, |r| r.clamp(0.0, 1.0));
        assert!((d - 0.0005).abs() < 1e-12, "{d}");
        // A shifted sample is detected.
        let mut t: Vec<f64> = (0..1000).map(|i| (i as f64 + 0.5) / 1000.0 * 0.9).collect();
        assert!(ks_distance(&mut t, |r| r.clamp(0.0, 1.0)) > 0.09);
    }

    #[test]
    fn lattice_coordinates_land_on_the_lattice() {
        let scale = 0.4123456789;
        let mut found = 0;
        for k in -1000..1000 {
            if let Some(x) = lattice_coordinate(k, scale) {
                assert_eq!(x * scale, k as f64);
                found += 1;
            }
        }
        // Not every integer is x·S for some double x (the products skip some
        // when ulp(x)·S exceeds ulp(k)), but most are.
        assert!(found > 1000, "{found}");
    }

    #[test]
    fn first_in_cell_is_the_boundary_of_the_cell() {
        for scale in [0.4123456789, 0.5780, 1.0, 3.0f64.sqrt()] {
            for k in [-1_000_000i64, -1000, -1, 0, 1, 7, 1000, 1 << 40] {
                let x = first_in_cell(k, scale);
                assert!((x * scale).floor() == k as f64, "S {scale}, k {k}: x {x}");
                assert!((x.next_down() * scale) < k as f64, "S {scale}, k {k}: x {x} is not the first");
                if lattice_coordinate(k, scale).is_some() {
                    assert_eq!(x * scale, k as f64, "S {scale}, k {k}: a face exists but x {x} is past it");
                }
            }
        }
    }

    #[test]
    fn uniform_is_in_range_and_not_constant() {
        let v: Vec<f64> = (0..1000).map(|i| uniform(7, i)).collect();
        assert!(v.iter().all(|x| (0.0..1.0).contains(x)));
        let mean = v.iter().sum::<f64>() / 1000.0;
        assert!((mean - 0.5).abs() < 0.05);
    }
}
