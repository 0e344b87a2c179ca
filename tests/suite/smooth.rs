//! Smooth F1 and the n-sphere radius (`Reference::smooth_f1`,
//! `Reference::n_sphere`) against brute force written from their
//! definitions, and the properties they must have: the limits in s, the
//! gradient against central differences, continuity across cell faces, and
//! the documented results for bad input.

use worley::definition::Pattern;
use worley::{Config, Metric, Mode, Reference, INVALID_ID, SMOOTH_TOLERANCE};
use worley_harness::sample_point;

use crate::block;

/// −s·ln Σ exp(−(√(F² + s²) − s)/s) over a block `r` cells wide, summed
/// plainly from the nearest point (user units): the definition, with no
/// search and no running rescale.
fn brute_smooth<const D: usize>(pattern: &Pattern<D>, metric: Metric, x: [f64; D], s: f64, r: i64) -> f64 {
    let (cell, f) = pattern.locate(x).unwrap();
    let scale = pattern.scale();
    let mut h: Vec<f64> = block(pattern, cell, r)
        .iter()
        .map(|(p, _)| {
            let delta: Vec<f64> = (0..D).map(|a| (f[a] - p[a]) / scale).collect();
            let d = metric.distance(&delta);
            (d * d + s * s).sqrt() - s
        })
        .collect();
    h.sort_by(f64::total_cmp);
    let sum: f64 = h.iter().map(|v| (-(v - h[0]) / s).exp()).sum();
    h[0] - s * sum.ln()
}

#[test]
fn smooth_f1_is_the_sum_over_every_point_within_its_tolerance() {
    fn check<const D: usize>(config: Config, s: f64, r: i64, n: usize) {
        let basis = Reference::<D>::new(config).unwrap();
        let mut worst = 0f64;
        for i in 0..n {
            let x = sample_point::<D>(17 + D as u64, i, 300.0);
            let got = basis.smooth_f1(x, s).value;
            let want = brute_smooth(basis.pattern(), config.metric, x, s, r);
            let error = (got - want).abs();
            // The certified part plus the f64 rounding of two sums.
            assert!(error <= s * SMOOTH_TOLERANCE + 1e-12, "{D}D {config:?} s {s} at {x:?}: {got} against {want}");
            worst = worst.max(error / s);
        }
        println!("{D}D {:?} s = {s}: largest error {worst:.2e} s", config.metric);
    }
    // Blocks wide enough that what lies outside weighs far less than 1e−6
    // of the sum (e^−(edge/s) with the edge 3 to 5 cells, s under a cell).
    check::<2>(Config::default(), 0.1, 3, 300);
    check::<2>(Config::default(), 0.3, 4, 300);
    check::<2>(Config::default(), 1.0, 7, 100);
    check::<3>(Config::default(), 0.1, 3, 100);
    check::<3>(Config::default(), 0.3, 3, 100);
    check::<3>(Config { density: 1.0, seed: 3, ..Config::default() }, 0.3, 5, 60);
    check::<3>(Config { metric: Metric::Manhattan, ..Config::default() }, 0.3, 3, 50);
    check::<3>(Config { metric: Metric::Chebyshev, ..Config::default() }, 0.3, 3, 50);
    check::<4>(Config::default(), 0.2, 3, 20);
}

#[test]
fn smooth_f1_lies_below_f1_and_tends_to_it() {
    let basis = Reference::<3>::new(Config::default()).unwrap();
    for i in 0..500 {
        let x = sample_point::<3>(5, i, 100.0);
        let f = basis.evaluate(x);
        let zero = basis.smooth_f1(x, 0.0);
        assert_eq!(zero.value, f.distance[0], "s = 0 is F1");
        assert_eq!(zero.feature, f.id[0]);
        let mut last = f.distance[0];
        for s in [1e-9, 1e-4, 0.01, 0.1, 0.5, 2.0] {
            let v = basis.smooth_f1(x, s);
            assert!(
                v.value <= last + 1e-12 + s * SMOOTH_TOLERANCE,
                "{x:?}: S falls as s grows ({s}: {} after {last})",
                v.value
            );
            assert_eq!(v.feature, f.id[0], "the heaviest point is F1's");
            last = v.value;
        }
        // Within s of F1 when F1 stands alone (the next point far beyond s).
        let tiny = basis.smooth_f1(x, 1e-9).value;
        assert!((tiny - f.distance[0]).abs() <= 1e-8, "{x:?}: {tiny} against F1 {}", f.distance[0]);
    }
}

#[test]
fn smooth_f1_gradient_matches_central_differences() {
    fn check<const D: usize>(metric: Metric) {
        let basis = Reference::<D>::new(Config { metric, ..Config::default() }).unwrap();
        let mut worst = 0f64;
        for i in 0..300 {
            let x = sample_point::<D>(23, i, 50.0);
            let s = 0.3;
            let g = basis.smooth_f1(x, s).gradient;
            let h = 1e-6;
            for a in 0..D {
                let (mut up, mut down) = (x, x);
                up[a] += h;
                down[a] -= h;
                let numeric = (basis.smooth_f1(up, s).value - basis.smooth_f1(down, s).value) / (2.0 * h);
                worst = worst.max((numeric - g[a]).abs());
            }
        }
        println!("{D}D {metric:?}: largest gradient error {worst:.2e}");
        // Central differences of a C∞ function: O(h²) plus the values'
        // rounding over 2h and the certified tolerance over 2h.
        assert!(worst < 1e-4, "{D}D {metric:?}: {worst}");
    }
    check::<2>(Metric::Euclidean);
    check::<3>(Metric::Euclidean);
    check::<4>(Metric::Euclidean);
    check::<3>(Metric::Minkowski(3.0));
}

#[test]
fn smooth_f1_is_continuous_across_cell_faces_and_at_feature_points() {
    let basis = Reference::<3>::new(Config::default()).unwrap();
    let scale = basis.pattern().scale();
    let s = 0.3;
    for i in 0..300 {
        // A sample on a cell face, and one a hair either side of it.
        let mut x = sample_point::<3>(31, i, 80.0);
        let axis = i % 3;
        x[axis] = (x[axis] * scale).round() / scale;
        let (mut below, mut above) = (x, x);
        below[axis] -= 1e-9;
        above[axis] += 1e-9;
        let (a, b, c) = (basis.smooth_f1(below, s), basis.smooth_f1(x, s), basis.smooth_f1(above, s));
        // |∇S| ≤ 1: 1e−9 apart moves S by 1e−9, plus the tolerance twice.
        let allowed = 1e-9 + 2.0 * s * SMOOTH_TOLERANCE;
        assert!((a.value - b.value).abs() <= allowed && (b.value - c.value).abs() <= allowed, "{x:?}");
    }
    // At a feature point itself: no cone (the hyperbolic distance is
    // smooth there), so the gradient is the others' pull, small and
    // continuous through it.
    let x = [2.0, -1.0, 0.5];
    let (cell, f) = basis.pattern().locate(x).unwrap();
    let points = block(basis.pattern(), cell, 1);
    let nearest = points
        .iter()
        .min_by(|p, q| {
            let d = |p: &[f64; 3]| (0..3).map(|a| (p[a] - f[a]).powi(2)).sum::<f64>();
            d(&p.0).total_cmp(&d(&q.0))
        })
        .unwrap();
    let at: [f64; 3] = std::array::from_fn(|a| (cell[a] as f64 + nearest.0[a]) / scale);
    let g = basis.smooth_f1(at, s).gradient;
    for a in 0..3 {
        let (mut up, mut down) = (at, at);
        up[a] += 1e-7;
        down[a] -= 1e-7;
        let (gu, gd) = (basis.smooth_f1(up, s).gradient, basis.smooth_f1(down, s).gradient);
        assert!(
            (gu[a] - g[a]).abs() < 1e-5 && (gd[a] - g[a]).abs() < 1e-5,
            "the gradient jumps at the point: {gd:?} {g:?} {gu:?}"
        );
    }
}

#[test]
fn smooth_f1_gives_nan_beyond_its_widest_search_and_sums_windows() {
    // Bad input for both forms: `tests/suite/compact.rs`.
    let basis = Reference::<2>::new(Config::default()).unwrap();
    // A smoothness too large to certify within the widest search: NaN, not
    // a value missing most of its sum.
    assert!(basis.smooth_f1([0.5, 0.5], 1e4).value.is_nan());
    // Window mode sums the 3^d block, as its F_n do.
    let window = Reference::<2>::new(Config { mode: Mode::Window, ..Config::default() }).unwrap();
    assert!(window.smooth_f1([0.5, 0.5], 0.3).value.is_finite());
}

#[test]
fn n_sphere_radius_is_half_the_distance_from_f1s_point_to_its_nearest() {
    fn check<const D: usize>(config: Config, n: usize) {
        let basis = Reference::<D>::new(config).unwrap();
        let pattern = basis.pattern();
        let scale = pattern.scale();
        for i in 0..n {
            let x = sample_point::<D>(41, i, 500.0);
            let (cell, f) = pattern.locate(x).unwrap();
            // F1's point by brute force over a wide block, then the point
            // nearest to it, both in the metric, ties to the smaller ID.
            let points = block(pattern, cell, if config.density < 1.0 { 6 } else { 4 });
            let dist = |a: &[f64; D], b: &[f64; D]| {
                let v: Vec<f64> = (0..D).map(|k| a[k] - b[k]).collect();
                config.metric.distance(&v)
            };
            let (p1, id1) =
                *points.iter().min_by(|a, b| dist(&a.0, &f).total_cmp(&dist(&b.0, &f)).then(a.1.cmp(&b.1))).unwrap();
            let (p2, id2) = *points
                .iter()
                .filter(|p| p.1 != id1)
                .min_by(|a, b| dist(&a.0, &p1).total_cmp(&dist(&b.0, &p1)).then(a.1.cmp(&b.1)))
                .unwrap();
            let got = basis.n_sphere(x);
            let want = 0.5 * dist(&p1, &p2) / scale;
            assert_eq!(got.feature, id1, "{D}D {x:?}");
            assert_eq!(got.neighbour, id2, "{D}D {x:?}");
            assert!((got.radius - want).abs() <= 1e-12 * want.max(1.0), "{D}D {x:?}: {} against {want}", got.radius);
        }
    }
    check::<2>(Config::default(), 400);
    check::<3>(Config::default(), 300);
    check::<3>(Config { density: 0.5, seed: 9, ..Config::default() }, 100);
    check::<3>(Config { metric: Metric::Manhattan, ..Config::default() }, 100);
    check::<4>(Config::default(), 60);
    // Bad input.
    let basis = Reference::<3>::new(Config::default()).unwrap();
    let bad = basis.n_sphere([f64::NAN, 0.0, 0.0]);
    assert!(bad.radius.is_nan() && bad.feature == INVALID_ID && bad.neighbour == INVALID_ID);
}
