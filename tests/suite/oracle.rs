//! The reference kernel against the brute-force oracle: 10^6 random points
//! per dimension in exact mode (a tenth in the quick tier,
//! [`worley_harness::Tier`]), plus every metric and the window mode's known
//! failure.

use worley::{Config, Metric, Mode, Reference};
use worley_harness::{self as harness, Campaign, Report, Tier};

fn campaign(oracle_samples: usize, pairs: usize) -> Campaign {
    Campaign { seed: 11, samples: 0, oracle_samples, range: 1000.0, pairs, grid_cells: 0 }
}

fn run<const D: usize>(config: Config, campaign: &Campaign) -> Report {
    let kernel = Reference::<D>::new(config).unwrap();
    let mut report = Report::new::<D>("reference".into(), &config, kernel.pattern(), campaign);
    harness::compare_with_oracle(&kernel, campaign, &mut report);
    harness::continuity(&kernel, campaign, &mut report);
    report
}

fn assert_exact(report: &Report) {
    assert!(report.is_exact(), "{}", report.to_table());
}

/// 10^6 points per dimension in the whole campaign.
fn exact_mode(tier: Tier) {
    let config = Config { order: 4, ..Config::default() };
    let c = campaign(tier.of(1_000_000), tier.of(100_000));
    assert_exact(&run::<2>(config, &c));
    assert_exact(&run::<3>(config, &c));
    assert_exact(&run::<4>(config, &c));
}

worley_harness::tiered!(
    exact_mode_agrees_with_brute_force_per_dimension,
    campaign_exact_mode_agrees_with_brute_force_on_a_million_points_per_dimension,
    exact_mode
);

fn every_metric(tier: Tier) {
    let c = campaign(tier.of(20_000), tier.of(20_000));
    for metric in
        [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(1.5), Metric::Minkowski(3.0)]
    {
        let config = Config { order: 8, metric, seed: 3, ..Config::default() };
        assert_exact(&run::<2>(config, &c));
        assert_exact(&run::<3>(config, &c));
        assert_exact(&run::<4>(config, &campaign(tier.of(5_000), tier.of(5_000))));
    }
}

worley_harness::tiered!(
    every_metric_and_high_orders_agree_with_brute_force,
    campaign_every_metric_and_high_orders_agree_with_brute_force,
    every_metric
);

#[test]
fn low_density_forces_wide_searches_that_stay_exact() {
    // At λ = 0.5 F8 needs several shells: the widening path is exercised often.
    let config = Config { order: 8, density: 0.5, ..Config::default() };
    let c = campaign(50_000, 50_000);
    let r2 = run::<2>(config, &c);
    assert_exact(&r2);
    assert!(r2.orders[7].needs_wider > 10_000, "{}", r2.to_table());
    assert_exact(&run::<3>(config, &c));
}

#[test]
fn window_mode_is_measurably_wrong_at_high_order() {
    // The harness must be able to see failures: Worley's 3^d window misses
    // points for F8 in 2D at λ 3 (about 2 % of samples).
    let config = Config { order: 8, mode: Mode::Window, density: 3.0, ..Config::default() };
    let r = run::<2>(config, &campaign(100_000, 100_000));
    assert!(r.orders[7].oracle_disagreements > 100, "{}", r.to_table());
    assert!(r.orders[7].continuity_violations > 100, "{}", r.to_table());
    assert_eq!(r.orders[0].oracle_disagreements, 0, "{}", r.to_table());
}
