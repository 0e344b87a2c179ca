//! Compact smooth F1 (`Reference::smooth_f1_compact`) against brute force
//! written from its definition (the root of Σ φ((h_j − S)/s) = 1 over every
//! point of a wide block, found by regula falsi rather than the reference's
//! bisection), and the properties it must have: its bounds around F1, the
//! gradient against central differences, continuity along lines that cross
//! cell faces and the edge of its reach, and bad input.

use worley::definition::Pattern;
use worley::{Config, Metric, Mode, Reference, INVALID_ID};
use worley_harness::sample_point;

use crate::block;

fn phi(t: f64) -> f64 {
    if t < 1.0 {
        (1.0 - 1.0 / (1.0 - t)).exp()
    } else {
        0.0
    }
}

/// The root over every point of a block `r` cells wide (user units).
fn brute_compact<const D: usize>(pattern: &Pattern<D>, metric: Metric, x: [f64; D], s: f64, r: i64) -> f64 {
    let (cell, f) = pattern.locate(x).unwrap();
    let scale = pattern.scale();
    let h: Vec<f64> = block(pattern, cell, r)
        .iter()
        .map(|(p, _)| {
            let delta: Vec<f64> = (0..D).map(|a| (f[a] - p[a]) / scale).collect();
            let d = metric.distance(&delta);
            (d * d + s * s).sqrt() - s
        })
        .collect();
    let least = h.iter().copied().fold(f64::INFINITY, f64::min);
    let g = |v: f64| h.iter().map(|&hj| phi((hj - v) / s)).sum::<f64>() - 1.0;
    // g(least − s) = −1 < 0 ≤ g(least): regula falsi (Illinois), 200 steps.
    let (mut a, mut b, mut ga, mut gb) = (least - s, least, -1.0, g(least));
    if gb == 0.0 {
        return least;
    }
    let mut side = 0;
    for _ in 0..200 {
        let c = (a * gb - b * ga) / (gb - ga);
        let gc = g(c);
        if gc == 0.0 || c <= a || c >= b {
            return c.clamp(a, b);
        }
        if gc > 0.0 {
            (b, gb) = (c, gc);
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            (a, ga) = (c, gc);
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
    }
    0.5 * (a + b)
}

#[test]
fn compact_smooth_f1_is_the_root_over_every_point() {
    fn check<const D: usize>(config: Config, s: f64, r: i64, n: usize) {
        let basis = Reference::<D>::new(config).unwrap();
        let mut worst = 0f64;
        for i in 0..n {
            let x = sample_point::<D>(71 + D as u64, i, 300.0);
            let got = basis.smooth_f1_compact(x, s).value;
            let want = brute_compact(basis.pattern(), config.metric, x, s, r);
            let error = (got - want).abs();
            assert!(error <= 1e-12 * (1.0 + want.abs()), "{D}D {config:?} s {s} at {x:?}: {got} against {want}");
            worst = worst.max(error);
        }
        println!("{D}D {:?} s = {s}: largest error {worst:.2e}", config.metric);
    }
    // Blocks wider than F1 + 2s reaches at these densities.
    check::<2>(Config::default(), 0.1, 3, 400);
    check::<2>(Config::default(), 0.3, 3, 400);
    check::<2>(Config::default(), 1.0, 4, 200);
    check::<3>(Config::default(), 0.1, 2, 200);
    check::<3>(Config::default(), 0.3, 3, 200);
    check::<3>(Config { density: 1.0, seed: 3, ..Config::default() }, 0.3, 4, 100);
    check::<3>(Config { metric: Metric::Manhattan, ..Config::default() }, 0.3, 3, 100);
    check::<3>(Config { metric: Metric::Chebyshev, ..Config::default() }, 0.3, 3, 100);
    check::<4>(Config::default(), 0.2, 2, 40);
}

#[test]
fn compact_smooth_f1_lies_within_2s_below_f1_and_is_the_hyperbolic_distance_alone() {
    let basis = Reference::<3>::new(Config { order: 2, ..Config::default() }).unwrap();
    let (mut alone, mut shared) = (0, 0);
    for i in 0..1000 {
        let x = sample_point::<3>(5, i, 100.0);
        let f = basis.evaluate(x);
        let (f1, f2) = (f.distance[0], f.distance[1]);
        assert_eq!(basis.smooth_f1_compact(x, 0.0).value, f1, "s = 0 is F1");
        for s in [1e-6, 0.1, 0.3, 1.0] {
            let v = basis.smooth_f1_compact(x, s);
            let h1 = (f1 * f1 + s * s).sqrt() - s;
            assert!(v.value <= h1 + 1e-12 && v.value > h1 - s, "{x:?} s {s}: {} against h1 {h1}", v.value);
            assert_eq!(v.feature, f.id[0]);
            // F2 beyond the reach: F1's point alone takes part.
            if f2 * f2 >= (h1 + 2.0 * s).powi(2) - s * s {
                assert!((v.value - h1).abs() <= 1e-12, "{x:?} s {s}: alone, {} against h1 {h1}", v.value);
                alone += 1;
            } else {
                shared += 1;
            }
        }
    }
    // Both cases occur.
    assert!(alone > 100 && shared > 100, "{alone} alone, {shared} shared");
}

#[test]
fn compact_smooth_f1_gradient_matches_central_differences() {
    fn check<const D: usize>(metric: Metric, s: f64) {
        let basis = Reference::<D>::new(Config { metric, ..Config::default() }).unwrap();
        let mut worst = 0f64;
        for i in 0..300 {
            let x = sample_point::<D>(29, i, 50.0);
            let g = basis.smooth_f1_compact(x, s).gradient;
            let h = 1e-6;
            for a in 0..D {
                let (mut up, mut down) = (x, x);
                up[a] += h;
                down[a] -= h;
                let numeric =
                    (basis.smooth_f1_compact(up, s).value - basis.smooth_f1_compact(down, s).value) / (2.0 * h);
                worst = worst.max((numeric - g[a]).abs());
            }
        }
        println!("{D}D {metric:?} s {s}: largest gradient error {worst:.2e}");
        // O(h²) terms of a smooth function plus the values' rounding over 2h.
        assert!(worst < 1e-4, "{D}D {metric:?} s {s}: {worst}");
    }
    check::<2>(Metric::Euclidean, 0.3);
    check::<3>(Metric::Euclidean, 0.1);
    check::<3>(Metric::Euclidean, 0.3);
    check::<4>(Metric::Euclidean, 0.3);
    check::<3>(Metric::Minkowski(3.0), 0.3);
}

#[test]
fn compact_smooth_f1_is_continuous_along_lines_across_faces_and_its_reach() {
    // Walk lines in small steps: |ΔS| ≤ |Δx| (|∇S| ≤ 1) at every step, so
    // no jump where a cell face is crossed or a point enters the reach.
    let basis = Reference::<3>::new(Config::default()).unwrap();
    let step = 1e-3;
    let mut worst = 0f64;
    for line in 0..40 {
        let start = sample_point::<3>(43, line, 60.0);
        let dir = {
            let d = sample_point::<3>(47, line, 1.0);
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            d.map(|v| v / n)
        };
        for s in [0.1, 0.3] {
            let mut last = basis.smooth_f1_compact(start, s).value;
            for k in 1..3000 {
                let x: [f64; 3] = std::array::from_fn(|a| start[a] + dir[a] * step * k as f64);
                let v = basis.smooth_f1_compact(x, s).value;
                worst = worst.max((v - last).abs() / step);
                last = v;
            }
        }
    }
    println!("largest |ΔS| / |Δx| along the lines: {worst:.6}");
    assert!(worst <= 1.0 + 1e-6, "{worst}");
}

#[test]
fn smooth_f1_bad_input_gives_the_documented_result_in_both_forms() {
    let basis = Reference::<2>::new(Config::default()).unwrap();
    for (x, s) in [
        ([f64::NAN, 0.0], 0.3),
        ([f64::INFINITY, 0.0], 0.3),
        ([1e300, 0.0], 0.3),
        ([0.5, 0.5], -0.1),
        ([0.5, 0.5], f64::NAN),
        ([0.5, 0.5], f64::INFINITY),
    ] {
        // Both forms: the compact one and the log-sum-exp.
        for v in [basis.smooth_f1_compact(x, s), basis.smooth_f1(x, s)] {
            assert!(v.value.is_nan() && v.gradient.iter().all(|g| g.is_nan()), "{x:?} s {s}: {v:?}");
            assert_eq!(v.feature, INVALID_ID);
        }
    }
    // A reach beyond the widest search: NaN.
    assert!(basis.smooth_f1_compact([0.5, 0.5], 1e4).value.is_nan());
    // Window mode: the 3^d block's points; an empty block is +∞ for every
    // s, 0 included (F1 itself is +∞ there), in both forms.
    let window = Reference::<2>::new(Config { mode: Mode::Window, ..Config::default() }).unwrap();
    assert!(window.smooth_f1_compact([0.5, 0.5], 0.3).value.is_finite());
    let sparse =
        Reference::<2>::new(Config { mode: Mode::Window, density: 0.3, seed: 2, ..Config::default() }).unwrap();
    let mut empty = 0;
    for i in 0..2000 {
        let x = sample_point::<2>(8, i, 100.0);
        if sparse.evaluate(x).distance[0].is_infinite() {
            empty += 1;
            for s in [0.0, 0.3] {
                let (c, l) = (sparse.smooth_f1_compact(x, s), sparse.smooth_f1(x, s));
                assert!(c.value == f64::INFINITY && c.feature == INVALID_ID, "{x:?} s {s}: {c:?}");
                assert!(l.value == f64::INFINITY && l.feature == INVALID_ID, "{x:?} s {s}: {l:?}");
            }
        }
    }
    assert!(empty > 0, "no empty window among the samples");
}
