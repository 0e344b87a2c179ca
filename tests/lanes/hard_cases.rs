//! Named hard cases, each with its reason, through the reference kernel (and,
//! at the end, each of the 8 lanes of the SIMD kernel) in
//! 2D, 3D and 4D, each value placed on every axis in turn. Every result is
//! compared with the brute-force oracle, and with the result one ulp away
//! for continuity.

use worley::{Config, Features, Metric, Reference, INVALID_ID};
use worley_harness::oracle::{brute_force, brute_force_in_cell};
use worley_harness::{first_in_cell, lattice_coordinate};

/// A hard coordinate value in user units, derived from the scale S.
struct Case {
    name: &'static str,
    reason: &'static str,
    value: fn(scale: f64) -> f64,
}

const CASES: &[Case] = &[
    Case { name: "zero", reason: "the origin: cell 0, fraction 0", value: |_| 0.0 },
    Case { name: "negative zero", reason: "floor(−0.0) is −0.0: must behave as +0.0", value: |_| -0.0 },
    Case { name: "lattice +1", reason: "x·S exactly 1: on a cell face", value: |s| lattice_coordinate(1, s).unwrap() },
    Case {
        name: "lattice −1",
        reason: "x·S exactly −1: on a negative face",
        value: |s| lattice_coordinate(-1, s).unwrap(),
    },
    Case {
        name: "lattice 1000 + ulp",
        reason: "one ulp above the first coordinate of a cell (on its face when x·S = 1000 exists)",
        value: |s| first_in_cell(1000, s).next_up(),
    },
    Case {
        name: "lattice −1000 − ulp",
        reason: "the last coordinate before a negative face",
        value: |s| first_in_cell(-1000, s).next_down(),
    },
    Case {
        name: "tiny negative", reason: "−1e−300: u + 1 rounds to a fraction of exactly 1.0", value: |_| -1e-300
    },
    Case { name: "2^23", reason: "f32 spacing reaches 1: the f32 kernel's precision edge", value: |_| 8_388_608.0 },
    Case { name: "2^24 + 0.5", reason: "f32 cannot hold this; f64 must", value: |_| 16_777_216.5 },
    Case { name: "−2^24 cells", reason: "f32 integer limit as a cell index", value: |s| -16_777_216.0 / s },
    Case { name: "−1e9", reason: "large negative: floor and the hash of negative cells", value: |_| -1e9 },
    Case { name: "2^31 cells − ε", reason: "last cell of the i32 range", value: |s| (2_147_483_648.0 - 0.25) / s },
    Case {
        name: "2^31 cells + ε",
        reason: "first cell beyond i32: the hash folds the upper word",
        value: |s| (2_147_483_648.0 + 0.25) / s,
    },
    Case { name: "−2^40 cells", reason: "cell index far beyond 32 bits", value: |s| -1_099_511_627_776.5 / s },
    Case {
        name: "largest cell",
        reason: "|x·S| just under 2^53, the documented limit",
        value: |s| (9_007_199_254_740_990.0 / s).next_down(),
    },
];

fn check_value<const D: usize>(basis: &Reference<D>, case: &Case, axis: usize) {
    let s = basis.pattern().scale();
    let metric = basis.config().metric;
    let order = basis.config().order;
    let v = (case.value)(s);
    let mut x: [f64; D] = std::array::from_fn(|a| 0.37 + a as f64 * 1.3);
    x[axis] = v;
    let got = basis.evaluate(x);
    let want = brute_force(basis.pattern(), metric, order, x, &mut Vec::new());
    let ctx = format!("{} ({}) on axis {axis} of {D}D: x = {x:?}", case.name, case.reason);
    assert!(got.distance[0].is_finite(), "{ctx}: not evaluated");
    for k in 0..order {
        assert_eq!(got.distance[k], want.distance[k], "{ctx}: F{}", k + 1);
    }
    for neighbour in [v.next_up(), v.next_down()] {
        let mut y = x;
        y[axis] = neighbour;
        let other = basis.evaluate(y);
        let step = (neighbour - v).abs();
        let slack = 64.0 * f64::EPSILON * (v.abs() + 1.0);
        for k in 0..order {
            let jump = (got.distance[k] - other.distance[k]).abs();
            assert!(jump <= step + slack, "{ctx}: F{} jumps {jump} over one ulp", k + 1);
        }
    }
}

fn all_cases<const D: usize>() {
    for metric in [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev] {
        let basis = Reference::<D>::new(Config { order: 6, metric, seed: 77, ..Config::default() }).unwrap();
        for case in CASES {
            for axis in 0..D {
                check_value(&basis, case, axis);
            }
        }
    }
}

#[test]
fn hard_values_agree_with_brute_force_and_stay_continuous_2d() {
    all_cases::<2>();
}

#[test]
fn hard_values_agree_with_brute_force_and_stay_continuous_3d() {
    all_cases::<3>();
}

#[test]
fn hard_values_agree_with_brute_force_and_stay_continuous_4d() {
    all_cases::<4>();
}

#[test]
fn negative_zero_is_bit_identical_to_zero() {
    let basis = Reference::<3>::new(Config { order: 4, ..Config::default() }).unwrap();
    let a = basis.evaluate([0.0, 1.0, 2.0]);
    let b = basis.evaluate([-0.0, 1.0, 2.0]);
    assert_eq!(a.distance.map(f64::to_bits), b.distance.map(f64::to_bits));
    assert_eq!(a.id, b.id);
}

#[test]
fn the_largest_cell_index_is_supported_and_one_beyond_is_not() {
    // Cell units: the limit is 2^53 cells on either side.
    let basis = Reference::<3>::new(Config { order: 4, ..Config::default() }).unwrap();
    let last = 1i64 << 53;
    for cell in [[last - 1, 0, 0], [0, -last, 0], [last, last, last]] {
        let got = basis.evaluate_in_cell(cell, [0.5, 0.25, 0.75]);
        let want = brute_force_in_cell(basis.pattern(), Metric::Euclidean, 4, cell, [0.5, 0.25, 0.75], &mut Vec::new());
        assert!(got.distance[3].is_finite());
        assert_eq!(got.distance, want.distance, "{cell:?}");
    }
    let beyond = basis.evaluate_in_cell([last + 1, 0, 0], [0.5; 3]);
    assert!(beyond.distance[0].is_nan() && beyond.id[0] == INVALID_ID);
    let x = basis.evaluate([2.0 * (last as f64) / basis.pattern().scale(), 0.0, 0.0]);
    assert!(x.distance[0].is_nan());
}

#[test]
fn exact_ties_between_two_feature_points() {
    // The midpoint of two feature points is exactly equidistant from both
    // (the points are 24-bit fixed point, so the midpoint and both deltas
    // are exact in f64): the two must appear as consecutive equal distances,
    // with both IDs, and the oracle must agree on the distances.
    for metric in [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev] {
        let basis = Reference::<3>::new(Config { order: 8, metric, seed: 5, ..Config::default() }).unwrap();
        let pattern = basis.pattern();
        let mut ties = 0;
        for i in 0..200i64 {
            let (ca, cb) = ([i, -i, 3], [i + 1, -i, 3]);
            let (Some(p), Some(q)) = (pattern.points(ca).first().copied(), pattern.points(cb).first().copied()) else {
                continue;
            };
            // Midpoint in cell units, as cell + fraction.
            let pa: [f64; 3] = std::array::from_fn(|a| ca[a] as f64 + p.offset()[a]);
            let pb: [f64; 3] = std::array::from_fn(|a| cb[a] as f64 + q.offset()[a]);
            let m: [f64; 3] = std::array::from_fn(|a| (pa[a] + pb[a]) / 2.0);
            let cell = m.map(|v| v.floor() as i64);
            let frac: [f64; 3] = std::array::from_fn(|a| m[a] - cell[a] as f64);
            let got: Features<3> = basis.evaluate_in_cell(cell, frac);
            let want = brute_force_in_cell(pattern, metric, 8, cell, frac, &mut Vec::new());
            assert_eq!(got.distance, want.distance);
            let Some(k) = (0..8).find(|&k| got.id[k] == p.id || got.id[k] == q.id) else { continue };
            if k == 7 {
                continue;
            }
            assert_eq!(got.distance[k], got.distance[k + 1], "{metric}: tie not exact");
            let pair = [got.id[k], got.id[k + 1]];
            assert!(pair.contains(&p.id) && pair.contains(&q.id), "{metric}: tie lost a point");
            ties += 1;
        }
        assert!(ties > 50, "{metric}: only {ties} ties exercised");
    }
}

#[test]
fn non_finite_input_gives_the_documented_invalid_result() {
    let basis = Reference::<4>::new(Config { order: 3, ..Config::default() }).unwrap();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -f64::NAN, f64::MAX, f64::MIN] {
        for axis in 0..4 {
            let mut x = [0.5; 4];
            x[axis] = bad;
            let f = basis.evaluate(x);
            for k in 0..3 {
                assert!(f.distance[k].is_nan(), "{bad} on axis {axis}");
                assert!(f.delta[k].iter().all(|v| v.is_nan()));
                assert_eq!(f.id[k], INVALID_ID);
            }
            assert_eq!(f.shells, 0);
        }
    }
    // A fraction outside [0, 1] in the cell-unit entry point is bad input too.
    assert!(basis.evaluate_in_cell([0; 4], [1.5, 0.0, 0.0, 0.0]).distance[0].is_nan());
    assert!(basis.evaluate_in_cell([0; 4], [f64::NAN, 0.0, 0.0, 0.0]).distance[0].is_nan());
}

#[test]
fn window_mode_reports_missing_points_as_infinite() {
    // At λ 0.25 in 2D a 3×3 block often holds fewer than 8 points.
    let basis =
        Reference::<2>::new(Config { order: 8, density: 0.25, mode: worley::Mode::Window, ..Config::default() })
            .unwrap();
    let mut missing = 0;
    for i in 0..1000 {
        let f = basis.evaluate([i as f64 * 0.731, i as f64 * -1.17]);
        if f.distance[7].is_infinite() {
            assert_eq!(f.id[7], INVALID_ID);
            assert!(f.delta[7][0].is_nan());
            missing += 1;
        }
    }
    assert!(missing > 100, "{missing}");
}

/// Every named case through the 8-lane kernel: the value on each axis, in
/// each of the 8 lanes in turn (the other lanes ordinary), in 2D, 3D and 4D.
/// The lane must match the single-point call bit for bit and the oracle
/// within the kernel's stated bound 4ε_f32(F + 1/S), with the oracle's IDs.
fn simd_lanes<const D: usize>() {
    use worley::simd::lane;
    use worley::{Outputs, Simd};
    let config = Config { order: 3, ..Config::default() };
    let kernel = Simd::<D, 3>::new(config, Outputs::Ids).unwrap();
    let s = kernel.pattern().scale();
    for case in CASES {
        let v = (case.value)(s);
        for axis in 0..D {
            for slot in 0..8 {
                let mut points: [[f64; D]; 8] =
                    std::array::from_fn(|i| std::array::from_fn(|a| 0.37 + a as f64 * 1.3 + i as f64 * 0.71));
                points[slot][axis] = v;
                let got = lane(&kernel.evaluate8(&points), slot);
                let single = kernel.evaluate(points[slot]);
                let ctx = format!("{} ({}) on axis {axis} of {D}D in lane {slot}", case.name, case.reason);
                assert_eq!(got.distance.map(f32::to_bits), single.distance.map(f32::to_bits), "{ctx}");
                assert_eq!(got.id, single.id, "{ctx}");
                let want = brute_force(kernel.pattern(), Metric::Euclidean, 4, points[slot], &mut Vec::new());
                for k in 0..3 {
                    let tol = 4.0 * f32::EPSILON as f64 * (want.distance[k] + 1.0 / s);
                    let err = (got.distance[k] as f64 - want.distance[k]).abs();
                    assert!(err <= tol, "{ctx}: F{} off by {err}", k + 1);
                    let tied = (k > 0 && want.distance[k] - want.distance[k - 1] <= 2.0 * tol)
                        || want.distance[k + 1] - want.distance[k] <= 2.0 * tol;
                    assert!(tied || got.id[k] == want.id[k], "{ctx}: F{} ID", k + 1);
                }
            }
        }
    }
}

#[test]
fn every_hard_case_in_every_lane_of_the_simd_kernel() {
    simd_lanes::<2>();
    simd_lanes::<3>();
    simd_lanes::<4>();
}
