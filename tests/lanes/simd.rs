//! The 8-lane kernel: the same function as the reference (through the shared
//! harness), one lane and eight lanes bit-identical, bad lanes isolated.

use worley::simd::lane;
use worley::{Config, Features32, Metric, Mode, Outputs, Simd, INVALID_ID};
use worley_harness::{self as harness, sample_point, Campaign, Report, Tier};

fn check<const D: usize, const N: usize>(config: Config, samples: usize) -> Report {
    let kernel = Simd::<D, N>::new(config, Outputs::IdsAndDeltas).unwrap();
    let campaign =
        Campaign { seed: 21, samples: 0, oracle_samples: samples, range: 1000.0, pairs: samples, grid_cells: 0 };
    let mut report = Report::new::<D>("simd".into(), &config, kernel.pattern(), &campaign);
    harness::compare_with_oracle(&kernel, &campaign, &mut report);
    harness::continuity(&kernel, &campaign, &mut report);
    // Exact: every F_k within the kernel's stated bound 4ε(F + 1/S) of the
    // oracle, IDs equal, no discontinuity; F1..F4 also within 1e-6.
    assert!(report.is_exact(), "{}", report.to_table());
    for o in report.orders.iter().take(4) {
        assert!(o.max_error <= 1e-6, "{}", report.to_table());
    }
    report
}

fn agrees_with_brute_force(tier: Tier) {
    let c = |order| Config { order, ..Config::default() };
    check::<2, 1>(c(1), tier.of(200_000));
    check::<3, 1>(c(1), tier.of(200_000));
    check::<4, 1>(c(1), tier.of(100_000));
    check::<2, 4>(c(4), tier.of(200_000));
    check::<3, 4>(c(4), tier.of(200_000));
    check::<4, 4>(c(4), tier.of(50_000));
    check::<2, 8>(c(8), tier.of(50_000));
    check::<3, 8>(c(8), tier.of(50_000));
}

worley_harness::tiered!(
    simd_agrees_with_brute_force_within_1e_6,
    campaign_simd_agrees_with_brute_force_within_1e_6,
    agrees_with_brute_force
);

fn every_metric(tier: Tier) {
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
        check::<3, 2>(Config { order: 2, metric, seed: 4, ..Config::default() }, tier.of(30_000));
        check::<2, 8>(Config { order: 8, metric, seed: 4, ..Config::default() }, tier.of(20_000));
    }
    // Low density: most F8 samples need the wider search.
    let r = check::<2, 8>(Config { order: 8, density: 0.5, ..Config::default() }, tier.of(20_000));
    assert!(r.orders[7].needs_wider > tier.of(5_000) as u64);
}

worley_harness::tiered!(
    simd_agrees_for_every_metric_and_widens_when_needed,
    campaign_simd_agrees_for_every_metric_and_widens_when_needed,
    every_metric
);

fn assert_same<const D: usize, const N: usize>(a: &Features32<D, N>, b: &Features32<D, N>, what: &str) {
    assert_eq!(a.distance.map(f32::to_bits), b.distance.map(f32::to_bits), "{what}: distances");
    assert_eq!(a.id, b.id, "{what}: ids");
    assert_eq!(a.delta.map(|d| d.map(f32::to_bits)), b.delta.map(|d| d.map(f32::to_bits)), "{what}: deltas");
}

fn bit_identity<const D: usize, const N: usize>(config: Config) {
    for outputs in [Outputs::Distances, Outputs::Ids, Outputs::IdsAndDeltas] {
        let kernel = Simd::<D, N>::new(config, outputs).unwrap();
        for batch in 0..2000 {
            let points: [[f64; D]; 8] = std::array::from_fn(|i| sample_point(3, batch * 8 + i, 50.0));
            let eight = kernel.evaluate8(&points);
            for (i, p) in points.iter().enumerate() {
                assert_same(&kernel.evaluate(*p), &lane(&eight, i), &format!("{outputs:?} lane {i} at {p:?}"));
            }
        }
    }
}

#[test]
fn one_lane_and_eight_lanes_are_bit_identical() {
    bit_identity::<2, 3>(Config { order: 3, ..Config::default() });
    bit_identity::<3, 1>(Config::default());
    bit_identity::<3, 4>(Config { order: 4, metric: Metric::Manhattan, ..Config::default() });
    bit_identity::<4, 2>(Config { order: 2, metric: Metric::Chebyshev, ..Config::default() });
    bit_identity::<2, 8>(Config { order: 8, density: 0.5, ..Config::default() });
    bit_identity::<3, 2>(Config { order: 2, mode: Mode::Window, ..Config::default() });
}

#[test]
fn outputs_not_asked_for_are_not_reported_and_distances_do_not_change() {
    let full = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    let bare = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Distances).unwrap();
    let x = [1.5, -2.25, 7.0];
    let (a, b) = (full.evaluate(x), bare.evaluate(x));
    assert_eq!(a.distance, b.distance);
    assert_eq!(b.id, [INVALID_ID; 2]);
    assert_eq!(b.delta, [[0.0; 3]; 2]);
    assert!(a.id[0] != INVALID_ID && a.delta[0] != [0.0; 3]);
}

#[test]
fn bad_lanes_give_nan_and_leave_their_neighbours_alone() {
    let kernel = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    let good = [0.25, 10.5, -3.0];
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300];
    for (slot, value) in bad.iter().enumerate() {
        let mut points = [good; 8];
        points[slot * 2][slot % 3] = *value;
        let r = kernel.evaluate8(&points);
        for i in 0..8 {
            let got = lane(&r, i);
            if i == slot * 2 {
                assert!(got.distance.iter().all(|d| d.is_nan()), "{value}");
                assert_eq!(got.id, [INVALID_ID; 2]);
                assert!(got.delta.iter().flatten().all(|d| d.is_nan()));
            } else {
                assert_same(&got, &kernel.evaluate(good), "good lane");
            }
        }
    }
}

#[test]
fn the_order_comes_from_the_type_and_other_fields_are_still_checked() {
    // The order rule itself is held in `tests/suite/texture.rs`.
    let f = Simd::<3, 2>::new(Config { order: 3, ..Config::default() }, Outputs::Distances).unwrap();
    assert_eq!(f.config().order, 2);
    let err = Simd::<3, 2>::new(Config { order: 2, density: -1.0, ..Config::default() }, Outputs::Distances);
    assert!(err.unwrap_err().to_string().contains("density -1"));
}

#[test]
fn hard_values_in_every_lane_match_the_reference_within_1e_6() {
    // Far from the origin the f32 kernel keeps its precision because the
    // sample is located in f64 and distances are taken relative to its cell.
    let config = Config { order: 4, ..Config::default() };
    let kernel = Simd::<3, 4>::new(config, Outputs::Ids).unwrap();
    let reference = worley::Reference::<3>::new(config).unwrap();
    let s = kernel.pattern().scale();
    let values = [
        0.0,
        -0.0,
        1.0 / s,
        -1.0 / s,
        8_388_608.0,
        16_777_216.5,
        -1e9,
        2_147_483_647.75 / s,
        2_147_483_648.25 / s,
        -1e7,
        1e12,
    ];
    for v in values {
        for slot in 0..8 {
            for axis in 0..3 {
                let mut points = [[0.3, 0.6, 0.9]; 8];
                points[slot][axis] = v;
                let got = lane(&kernel.evaluate8(&points), slot);
                let want = reference.evaluate(points[slot]);
                for k in 0..4 {
                    let err = (got.distance[k] as f64 - want.distance[k]).abs();
                    assert!(err <= 1e-6, "{v} in lane {slot}, axis {axis}: F{} off by {err}", k + 1);
                }
            }
        }
    }
}

#[test]
fn glam_entry_points_give_the_same_bits_as_arrays() {
    let c = |order| Config { order, ..Config::default() };
    let k3 = Simd::<3, 2>::new(c(2), Outputs::IdsAndDeltas).unwrap();
    let p = glam::Vec3::new(1.25, -7.5, 300.125);
    assert_same(&k3.evaluate_vec3(p), &k3.evaluate_f32(p.to_array()), "Vec3");
    assert_same(&k3.evaluate_vec3a(p.into()), &k3.evaluate_f32(p.to_array()), "Vec3A");
    let eight = k3.evaluate8_vec3(&[p; 8]);
    assert_same(&lane(&eight, 5), &k3.evaluate_f32(p.to_array()), "[Vec3; 8]");
    let k2 = Simd::<2, 1>::new(c(1), Outputs::Ids).unwrap();
    assert_same(&k2.evaluate_vec2(glam::Vec2::new(3.0, -4.0)), &k2.evaluate([3.0, -4.0]), "Vec2");
    let k4 = Simd::<4, 1>::new(c(1), Outputs::Ids).unwrap();
    let q = glam::Vec4::new(0.5, 1.5, -2.5, 9.0);
    assert_same(&k4.evaluate_vec4(q), &k4.evaluate_f32(q.to_array()), "Vec4");
}

#[test]
fn slices_grids_and_parallel_batches_give_the_single_point_bits() {
    use worley::Grid;
    let kernel = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    let empty = Features32::<3, 2> { distance: [0.0; 2], delta: [[0.0; 3]; 2], id: [0; 2] };
    // 8197 points: a parallel tile boundary and a tail shorter than eight.
    let points: Vec<[f64; 3]> = (0..8197).map(|i| sample_point(5, i, 300.0)).collect();
    let mut serial = vec![empty; points.len()];
    kernel.evaluate_slice(&points, &mut serial).unwrap();
    let mut parallel = vec![empty; points.len()];
    kernel.evaluate_slice_parallel(&points, &mut parallel).unwrap();
    for (i, p) in points.iter().enumerate() {
        let one = kernel.evaluate(*p);
        assert_same(&serial[i], &one, &format!("slice point {i}"));
        assert_same(&parallel[i], &one, &format!("parallel point {i}"));
    }
    // f32 and glam inputs through the slice API.
    let small: Vec<glam::Vec3> =
        points.iter().take(100).map(|p| glam::Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)).collect();
    let mut out = vec![empty; small.len()];
    kernel.evaluate_slice(&small, &mut out).unwrap();
    for (o, p) in out.iter().zip(&small) {
        assert_same(o, &kernel.evaluate_vec3(*p), "Vec3 slice");
    }
    // A 67 × 41 × 3 grid: rows that are not a multiple of eight.
    let grid = Grid { origin: [-3.5, 1e4, 0.25], step: [0.0625, 0.125, 0.5], size: [67, 41, 3] };
    let n = grid.len().unwrap();
    let mut a = vec![empty; n];
    let mut b = vec![empty; n];
    kernel.evaluate_grid(&grid, &mut a).unwrap();
    kernel.evaluate_grid_parallel(&grid, &mut b).unwrap();
    for i in 0..n {
        let x = grid.point(i);
        let (ix, iy, iz) = (i % 67, (i / 67) % 41, i / (67 * 41));
        assert_eq!(x, [-3.5 + 0.0625 * ix as f64, 1e4 + 0.125 * iy as f64, 0.25 + 0.5 * iz as f64]);
        let one = kernel.evaluate(x);
        assert_same(&a[i], &one, &format!("grid point {i}"));
        assert_same(&b[i], &one, &format!("parallel grid point {i}"));
    }
}

/// A slice's samples whose first stage leaves them open are finished in
/// blocks gathered from across the slice: each must still be the single
/// point's result, whatever its neighbours in the slice, bad lanes included.
fn slice_identity<const D: usize, const N: usize>(config: Config, len: usize) {
    for outputs in [Outputs::Distances, Outputs::Ids, Outputs::IdsAndDeltas] {
        let kernel = Simd::<D, N>::new(config, outputs).unwrap();
        let points: Vec<[f64; D]> = (0..len)
            .map(|i| {
                let mut p = sample_point(17, i, 200.0);
                // Bad lanes (NaN, ±∞) and lanes beyond 2^31 cells among good ones.
                match i % 37 {
                    5 => p[0] = f64::NAN,
                    11 => p[D - 1] = f64::INFINITY,
                    19 => p[0] = f64::NEG_INFINITY,
                    23 => p[1] = 3.0e10 + i as f64,
                    _ => {}
                }
                p
            })
            .collect();
        let mut out = vec![Features32::<D, N> { distance: [-1.0; N], delta: [[-1.0; D]; N], id: [7; N] }; len];
        kernel.evaluate_slice(&points, &mut out).unwrap();
        for (i, p) in points.iter().enumerate() {
            assert_same(&out[i], &kernel.evaluate(*p), &format!("{config:?} {outputs:?} slice point {i} at {p:?}"));
        }
    }
}

#[test]
fn slices_finish_open_samples_with_the_single_point_bits() {
    let c = |order| Config { order, ..Config::default() };
    // Lengths that leave a gathered block partly full at the end.
    slice_identity::<2, 1>(c(1), 3001);
    slice_identity::<3, 2>(c(2), 4093);
    slice_identity::<3, 4>(Config { order: 4, density: 0.5, ..Config::default() }, 2005);
    slice_identity::<4, 3>(c(3), 1203);
    slice_identity::<3, 8>(c(8), 1001);
    slice_identity::<3, 2>(Config { order: 2, mode: Mode::Window, ..Config::default() }, 2011);
    slice_identity::<3, 2>(Config { order: 2, bump: 0.5, ..Config::default() }, 2011);
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(1.5)] {
        slice_identity::<3, 2>(Config { order: 2, metric, ..Config::default() }, 1003);
    }
}

#[test]
fn buffers_of_the_wrong_size_are_an_error_and_nothing_is_written() {
    use worley::{Grid, SizeError};
    let kernel = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    let marker = Features32::<2, 1> { distance: [-7.0], delta: [[0.0; 2]], id: [7] };
    let mut out = vec![marker; 3];
    assert_eq!(kernel.evaluate_slice(&[[0.0f64; 2]; 4], &mut out), Err(SizeError { needed: 4, given: 3 }));
    assert_eq!(kernel.evaluate_slice_parallel(&[[0.0f64; 2]; 4], &mut out), Err(SizeError { needed: 4, given: 3 }));
    let grid = Grid { origin: [0.0; 2], step: [1.0; 2], size: [2, 2] };
    assert_eq!(kernel.evaluate_grid(&grid, &mut out), Err(SizeError { needed: 4, given: 3 }));
    assert_eq!(kernel.evaluate_grid_parallel(&grid, &mut out), Err(SizeError { needed: 4, given: 3 }));
    assert!(out.iter().all(|o| o.distance[0] == -7.0));
    let huge = Grid { origin: [0.0; 2], step: [1.0; 2], size: [usize::MAX, 2] };
    assert!(kernel.evaluate_grid(&huge, &mut out).is_err());
}

#[test]
fn large_worlds_keep_the_fraction_and_stay_within_the_stated_bound() {
    use worley::Reference;
    let config = Config { order: 3, ..Config::default() };
    let kernel = Simd::<3, 3>::new(config, Outputs::Ids).unwrap();
    let reference = Reference::<3>::new(config).unwrap();
    let bound = |f: f64| 4.0 * f32::EPSILON as f64 * (f + 1.0 / kernel.pattern().scale());
    // Cell plus fraction: the same bound at every distance from the origin.
    let bases: [i64; 6] = [0, -1, 1 << 31, -(1 << 31) - 1, 1 << 40, (1 << 53) - 1];
    for base in bases {
        for i in 0..500 {
            let u: [f64; 3] = sample_point(9, i, 1.0);
            let fraction = u.map(|v| (v * 0.5 + 0.5) as f32);
            let cell = [base, base.wrapping_neg().min(1 << 53), (i as i64) - 250];
            let got = kernel.evaluate_in_cell(cell, fraction);
            let want = reference.evaluate_in_cell(cell, fraction.map(f64::from));
            for k in 0..3 {
                let err = (got.distance[k] as f64 - want.distance[k]).abs();
                assert!(err <= bound(want.distance[k]), "cell {cell:?} {fraction:?}: F{} off by {err}", k + 1);
            }
        }
    }
    // Eight lanes by cell agree with one.
    let cells: [[i64; 3]; 8] = std::array::from_fn(|i| [1 << 45, -(i as i64), 3]);
    let fractions: [[f32; 3]; 8] = std::array::from_fn(|i| [0.125 * i as f32, 0.5, 0.999]);
    let eight = kernel.evaluate8_in_cell(&cells, &fractions);
    for i in 0..8 {
        assert_same(&lane(&eight, i), &kernel.evaluate_in_cell(cells[i], fractions[i]), "in-cell lane");
    }
    // Outside the documented domain: the invalid result.
    for (cell, fraction) in [([0; 3], [1.5, 0.0, 0.0]), ([0; 3], [f32::NAN, 0.0, 0.0]), ([i64::MAX, 0, 0], [0.5; 3])] {
        let r = kernel.evaluate_in_cell(cell, fraction);
        assert!(r.distance.iter().all(|d| d.is_nan()) && r.id == [INVALID_ID; 3], "{cell:?} {fraction:?}");
    }
    // f64 user coordinates at |x| ≈ 1e7, 1e9 and 2^31 cells, through the
    // harness against the brute-force oracle.
    let s = kernel.pattern().scale();
    for range in [1e7, 1e9, 2_147_483_648.0 / s * 1.5] {
        let campaign = Campaign { seed: 8, samples: 0, oracle_samples: 20_000, range, pairs: 0, grid_cells: 0 };
        let mut report = Report::new::<3>("simd".into(), &config, kernel.pattern(), &campaign);
        harness::compare_with_oracle(&kernel, &campaign, &mut report);
        assert!(report.is_exact(), "range {range}: {}", report.to_table());
    }
}
