//! The point process is Poisson, isotropic and scaled to mean F1 = 1.
//!
//! Bounds at 10^6 samples: the standard error of the mean F1 is about
//! 0.0005, so |mean − 1| ≤ 0.004 leaves room for the table's quantisation;
//! a well-mixed Poisson process gives a KS distance of about 0.001, bound
//! 0.005; the grid bias's standard error is about 0.05 %, bound 0.3 %. The
//! other metrics' laws run at a tenth of the samples by default (their KS
//! and grid-bias bounds √10 times wider) and whole under `cargo test --
//! --ignored` ([`worley_harness::Tier`]).

use worley::{Config, Metric, Reference};
use worley_harness::{self as harness, Campaign, Report, Tier};

fn stats<const D: usize>(config: Config) -> Report {
    stats_of::<D>(config, Tier::Full)
}

fn stats_of<const D: usize>(config: Config, tier: Tier) -> Report {
    let n = tier.of(1_000_000);
    let campaign = Campaign { seed: 5, samples: n, oracle_samples: 0, range: 10_000.0, pairs: 0, grid_cells: n };
    let kernel = Reference::<D>::new(config).unwrap();
    let mut report = Report::new::<D>("reference".into(), &config, kernel.pattern(), &campaign);
    harness::throughput_and_statistics(&kernel, &campaign, &mut report);
    report.grid_bias = harness::grid_bias(&kernel, &campaign);
    report
}

fn check(report: &Report) {
    let t = report.to_table();
    assert!((report.mean_f1 - 1.0).abs() < 0.004, "mean F1\n{t}");
    assert!(report.ks < 0.005, "KS\n{t}");
    assert!(report.grid_bias.abs() < 0.003, "grid bias\n{t}");
}

#[test]
fn euclidean_f1_is_poisson_with_mean_one_and_no_grid_bias() {
    check(&stats::<2>(Config::default()));
    check(&stats::<3>(Config::default()));
    check(&stats::<4>(Config::default()));
}

fn other_metrics(tier: Tier) {
    // Same points, other ball volumes: the KS distance tests the metric.
    // Both statistics' errors shrink as 1/√n.
    let widen = (1_000_000.0 / tier.of(1_000_000) as f64).sqrt();
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
        let r = stats_of::<3>(Config { metric, seed: 9, ..Config::default() }, tier);
        assert!(r.ks < 0.005 * widen, "{}", r.to_table());
        assert!(r.grid_bias.abs() < 0.003 * widen, "{}", r.to_table());
    }
}

worley_harness::tiered!(
    other_metrics_follow_the_poisson_law_of_their_own_ball,
    campaign_other_metrics_follow_the_poisson_law_of_their_own_ball,
    other_metrics
);

#[test]
fn a_wrong_law_is_rejected() {
    // Sanity of the KS bound: F1 of a Manhattan pattern tested against the
    // Euclidean ball's law must fail clearly.
    let campaign = Campaign { seed: 5, samples: 200_000, oracle_samples: 0, range: 1000.0, pairs: 0, grid_cells: 0 };
    let kernel = Reference::<3>::new(Config { metric: Metric::Manhattan, ..Config::default() }).unwrap();
    let mut f1: Vec<f64> = (0..campaign.samples)
        .map(|i| kernel.evaluate(harness::sample_point(campaign.seed, i, campaign.range)).distance[0])
        .collect();
    let rho_v = kernel.pattern().user_density() * Metric::Euclidean.unit_ball_volume(3);
    let ks = harness::ks_distance(&mut f1, |r| 1.0 - (-rho_v * r.powi(3)).exp());
    assert!(ks > 0.05, "{ks}");
}

#[test]
fn worley_bump_costs_isotropy() {
    // The bump of low populations is measurably anisotropic: the reason the
    // default table has none.
    let r = stats::<3>(Config { density: 2.5, bump: 0.75, ..Config::default() });
    assert!(r.grid_bias.abs() > 0.01, "{}", r.to_table());
}
