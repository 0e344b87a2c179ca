//! Properties of the basis that hold at every point, checked with proptest.

use proptest::prelude::*;
use worley::{Config, Features, Metric, Reference};

fn metric_strategy() -> impl Strategy<Value = Metric> {
    prop_oneof![
        Just(Metric::Euclidean),
        Just(Metric::Manhattan),
        Just(Metric::Chebyshev),
        (1.0f64..6.0).prop_map(Metric::Minkowski),
    ]
}

fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![-1e3f64..1e3, -1e7f64..1e7, -4.0f64..4.0]
}

fn basis3(metric: Metric, seed: u64, order: usize) -> Reference<3> {
    Reference::new(Config { metric, seed, order, ..Config::default() }).unwrap()
}

fn tolerance(x: &[f64], f: f64) -> f64 {
    let m = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    1e-14 * (f + 2.0 * m + 1.0) * 8.0
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn distances_are_sorted_and_match_their_deltas(
        metric in metric_strategy(), seed in any::<u64>(), order in 1usize..=16,
        x in [coordinate(), coordinate(), coordinate()],
    ) {
        let f = basis3(metric, seed, order).evaluate(x);
        for k in 0..order {
            prop_assert!(f.distance[k].is_finite() && f.distance[k] >= 0.0);
            if k > 0 { prop_assert!(f.distance[k - 1] <= f.distance[k]); }
            let d = metric.distance(&f.delta[k]);
            prop_assert!((d - f.distance[k]).abs() <= tolerance(&x, d), "{} vs {}", d, f.distance[k]);
        }
    }

    #[test]
    fn every_order_is_1_lipschitz(
        metric in metric_strategy(), seed in any::<u64>(),
        x in [coordinate(), coordinate(), coordinate()],
        step in [-1e-2f64..1e-2, -1e-2f64..1e-2, -1e-2f64..1e-2],
    ) {
        let basis = basis3(metric, seed, 8);
        let y = [x[0] + step[0], x[1] + step[1], x[2] + step[2]];
        let (a, b) = (basis.evaluate(x), basis.evaluate(y));
        let diff = [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
        let dist = metric.distance(&diff);
        for k in 0..8 {
            let jump = (a.distance[k] - b.distance[k]).abs();
            prop_assert!(jump <= dist + 2.0 * tolerance(&x, a.distance[k]), "F{}: {} > {}", k + 1, jump, dist);
        }
    }

    #[test]
    fn euclidean_gradient_is_the_unit_delta(
        seed in any::<u64>(), x in [-100.0f64..100.0, -100.0f64..100.0, -100.0f64..100.0],
    ) {
        let basis = basis3(Metric::Euclidean, seed, 2);
        let f = basis.evaluate(x);
        let h = 1e-6;
        // Only where the nearest point is clearly the nearest across ±h.
        prop_assume!(f.distance[1] - f.distance[0] > 1e-3 && f.distance[0] > 1e-3);
        for a in 0..3 {
            let mut xp = x;
            let mut xm = x;
            xp[a] += h;
            xm[a] -= h;
            let slope = (basis.evaluate(xp).distance[0] - basis.evaluate(xm).distance[0]) / (xp[a] - xm[a]);
            let unit = f.delta[0][a] / f.distance[0];
            prop_assert!((slope - unit).abs() < 1e-4, "axis {}: {} vs {}", a, slope, unit);
        }
    }

    #[test]
    fn evaluation_is_deterministic(seed in any::<u64>(), x in [coordinate(), coordinate()]) {
        let a = Reference::<2>::new(Config { seed, order: 4, ..Config::default() }).unwrap();
        let b = a.clone();
        let (fa, fb): (Features<2>, Features<2>) = (a.evaluate(x), b.evaluate(x));
        prop_assert_eq!(fa.distance.map(f64::to_bits), fb.distance.map(f64::to_bits));
        prop_assert_eq!(fa.id, fb.id);
    }

    #[test]
    fn another_seed_gives_another_pattern(seed in any::<u64>(), other in any::<u64>()) {
        prop_assume!(seed != other);
        let a = Reference::<2>::new(Config { seed, ..Config::default() }).unwrap();
        let b = Reference::<2>::new(Config { seed: other, ..Config::default() }).unwrap();
        let same = (0..32)
            .filter(|&i| {
                let x = [i as f64 * 1.37, i as f64 * -2.11];
                a.evaluate(x).id[0] == b.evaluate(x).id[0]
            })
            .count();
        prop_assert!(same <= 1, "{} of 32 nearest IDs shared", same);
    }
}

#[test]
fn no_wrap_around_at_common_hash_periods() {
    // Peers' hashes repeat every 256 or 289 cells (permutation tables) or
    // 2^16; shifting by those many cells must give an unrelated pattern.
    let basis = Reference::<3>::new(Config { order: 1, ..Config::default() }).unwrap();
    for period in [256i64, 289, 1 << 16, 1 << 32] {
        for axis in 0..3 {
            let mut same = 0;
            for i in 0..64 {
                let cell = [i, 2 * i, -3 * i];
                let mut shifted = cell;
                shifted[axis] += period;
                let frac = [0.3, 0.6, 0.9];
                let a = basis.evaluate_in_cell(cell, frac);
                let b = basis.evaluate_in_cell(shifted, frac);
                same += (a.distance[0] == b.distance[0]) as u32;
            }
            assert!(same <= 1, "period {period} on axis {axis}: {same} of 64 equal");
        }
    }
}

#[test]
fn neighbouring_cells_are_uncorrelated() {
    // Population of a cell against its +x neighbour: the correlation of
    // counts over 10^5 cells is within noise (|r| < 0.02, σ ≈ 0.003).
    let basis = Reference::<3>::new(Config::default()).unwrap();
    let p = basis.pattern();
    let n = 100_000;
    let counts: Vec<(f64, f64)> = (0..n as i64)
        .map(|i| {
            let c = [i % 317, i / 317, 7];
            (p.points(c).len() as f64, p.points([c[0] + 1, c[1], c[2]]).len() as f64)
        })
        .collect();
    let mean = |f: &dyn Fn(&(f64, f64)) -> f64| counts.iter().map(f).sum::<f64>() / n as f64;
    let (ma, mb) = (mean(&|c| c.0), mean(&|c| c.1));
    let cov = mean(&|c| (c.0 - ma) * (c.1 - mb));
    let va = mean(&|c| (c.0 - ma).powi(2));
    let vb = mean(&|c| (c.1 - mb).powi(2));
    let r = cov / (va * vb).sqrt();
    assert!(r.abs() < 0.02, "correlation {r}");
}

#[test]
fn one_axis_step_flips_half_the_hash_bits() {
    // Avalanche of the cell hash: the mean number of output bits that change
    // when one cell index changes by one is 16 ± 0.1 for a well-mixed hash.
    let keys = worley::definition::SeedKeys::new(1);
    let mut flips = 0u64;
    let n = 30_000i64;
    for i in 0..n {
        let c = [i * 7919 % 10_007 - 5000, i / 3, -i];
        for axis in 0..3 {
            let mut d = c;
            d[axis] += 1;
            let a = worley::definition::cell_hash(keys, c);
            let b = worley::definition::cell_hash(keys, d);
            flips += (a ^ b).count_ones() as u64;
        }
    }
    let mean = flips as f64 / (3 * n) as f64;
    assert!((mean - 16.0).abs() < 0.1, "{mean}");
}
