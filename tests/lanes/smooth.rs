//! Compact smooth F1 in lanes (`SimdSmooth`) against the f64 reference
//! (`Reference::smooth_f1_compact`, itself held to brute force in
//! `tests/suite/compact.rs`), the periodic pattern against brute force
//! over its images, the same bits through every entry point, and bad lanes
//! kept to themselves.

use super::images::{d2, nearest};
use worley::{
    Config, ConfigError, Grid, Metric, Mode, Outputs, Period, Reference, Simd, SimdSmooth, Smooth32, INVALID_ID,
};
use worley_harness::oracle::periodic_images;
use worley_harness::{chunked, sample_point, uniform};

/// The stated bound: S moves by at most the largest F_j error of the
/// points within the reach R, 4ε(R + 1/S_p), plus S's own f32 rounding.
fn bound(reach: f64, value: f64, inv_scale: f64) -> f64 {
    2.0 * f64::from(f32::EPSILON) * (reach + inv_scale) + f64::from(f32::EPSILON) * value.abs()
}

/// Largest value error over the bound, largest gradient error, and how
/// many values were +∞.
fn agrees<const D: usize>(config: Config, s: f32, seed: u64, n: usize, range: f64) -> (f64, f64, usize) {
    let reference = Reference::<D>::new(config).unwrap();
    let simd = SimdSmooth::<D>::new(config).unwrap();
    let inv_scale = 1.0 / reference.pattern().scale();
    let points: Vec<[f64; D]> = (0..n).map(|i| sample_point::<D>(seed, i, range)).collect();
    let mut got = vec![Smooth32::INVALID; n];
    simd.smooth_slice(&points, s, &mut got).unwrap();
    let (mut worst, mut worst_gradient, mut unbounded) = (0f64, 0f64, 0);
    let sd = f64::from(s);
    for (x, g) in points.iter().zip(&got) {
        let want = reference.smooth_f1_compact(*x, sd);
        assert_eq!(g.feature, want.feature, "{D}D s {s} at {x:?}: {g:?} against {want:?}");
        if want.value.is_infinite() {
            unbounded += 1;
            assert_eq!(f64::from(g.value), want.value, "{D}D at {x:?}");
            continue;
        }
        let f1 = reference.evaluate(*x).distance[0];
        let h1 = (f1 * f1 + sd * sd).sqrt() - sd;
        let reach = ((h1 + 2.0 * sd).powi(2) - sd * sd).sqrt();
        let (error, allowed) = ((f64::from(g.value) - want.value).abs(), bound(reach, want.value, inv_scale));
        assert!(error <= allowed, "{D}D s {s} at {x:?}: {} against {} (bound {allowed:e})", g.value, want.value);
        worst = worst.max(error / allowed);
        for a in 0..D {
            worst_gradient = worst_gradient.max((f64::from(g.gradient[a]) - want.gradient[a]).abs());
        }
    }
    (worst, worst_gradient, unbounded)
}

#[test]
fn simd_smooth_agrees_with_the_reference_in_every_dimension() {
    let c = |seed, density| Config { seed, density, ..Config::default() };
    let window = |seed, density| Config { mode: Mode::Window, ..c(seed, density) };
    let runs = chunked(8, |range| {
        range
            .map(|run| match run {
                0 => ("2D s 0.1", agrees::<2>(c(0, 5.0), 0.1, 1, 100_000, 1000.0)),
                1 => ("2D s 0.3", agrees::<2>(c(0, 5.0), 0.3, 2, 100_000, 1000.0)),
                2 => ("3D s 0.1", agrees::<3>(c(0, 5.0), 0.1, 3, 50_000, 1000.0)),
                3 => ("3D s 0.3", agrees::<3>(c(0, 5.0), 0.3, 4, 50_000, 1000.0)),
                4 => ("4D s 0.3", agrees::<4>(c(0, 5.0), 0.3, 5, 10_000, 1000.0)),
                // Sparse points per cell: the reach spans shells of cells.
                5 => ("3D λ 0.5 s 0.3", agrees::<3>(c(7, 0.5), 0.3, 6, 20_000, 1000.0)),
                // More points within reach than a lane keeps on the
                // stack: the lane searches again alone and keeps them all.
                6 => ("3D s 1.5", agrees::<3>(c(0, 5.0), 1.5, 7, 3_000, 1000.0)),
                // Windows that hold no point: +∞, as the reference says.
                _ => ("2D window λ 0.3 s 0.3", agrees::<2>(window(2, 0.3), 0.3, 8, 20_000, 100.0)),
            })
            .collect::<Vec<_>>()
    });
    for (name, (worst, gradient, unbounded)) in runs.into_iter().flatten() {
        println!(
            "{name}: worst value error {worst:.3} of the bound, worst gradient error {gradient:.2e}, {unbounded} +∞"
        );
        // The gradient is the weighted mean of unit-length vectors whose
        // weights move with the values' f32 error relative to s.
        assert!(gradient < 2e-4, "{name}: gradient error {gradient}");
        if name.contains("window") {
            assert!(unbounded > 0, "{name}: no empty window, so +∞ went untested");
        }
    }
}

#[test]
fn simd_smooth_gives_the_same_bits_through_every_entry_point() {
    fn check<const D: usize>(config: Config, s: f32) {
        let simd = SimdSmooth::<D>::new(config).unwrap();
        let bits = |v: &Smooth32<D>| (v.value.to_bits(), v.gradient.map(f32::to_bits), v.feature);
        // A grid whose F1 takes the grid tiles (eight steps within a cell)
        // where the mode allows them, and one whose F1 is per sample.
        let size = std::array::from_fn(|a| if a < 2 { 13 } else { 3 });
        let fine = Grid { origin: [-3.3; D], step: [0.05; D], size };
        let kernel = Simd::<D, 1>::new(config, Outputs::Distances).unwrap();
        assert_eq!(kernel.coherent_grid(&fine), config.mode == Mode::Exact, "{D}D");
        for (step, name) in [(0.05, "tiles"), (0.37, "per sample")] {
            let grid = Grid { step: [step; D], ..fine };
            let mut out = vec![Smooth32::INVALID; grid.len().unwrap()];
            simd.smooth_grid(&grid, s, &mut out).unwrap();
            for (i, g) in out.iter().enumerate() {
                assert_eq!(bits(g), bits(&simd.smooth(grid.point(i), s)), "{D}D grid ({name}) sample {i}");
            }
        }
        let grid = Grid { step: [0.37; D], ..fine };
        let mut out = vec![Smooth32::INVALID; grid.len().unwrap()];
        simd.smooth_grid(&grid, s, &mut out).unwrap();
        for (c, chunk) in out.chunks(8).enumerate().take(20) {
            if chunk.len() < 8 {
                break;
            }
            let x: [[f64; D]; 8] = std::array::from_fn(|i| grid.point(c * 8 + i));
            let eight = simd.smooth8(&x, s);
            let cells: [[i64; D]; 8] = std::array::from_fn(|i| x[i].map(|v| v.floor() as i64));
            let fractions: [[f32; D]; 8] = std::array::from_fn(|i| x[i].map(|v| (v - v.floor()) as f32));
            let in_cell = simd.smooth8_in_cell(&cells, &fractions, s);
            for i in 0..8 {
                assert_eq!(bits(&eight.lane(i)), bits(&chunk[i]), "{D}D eight, lane {i}");
                assert_eq!(
                    bits(&in_cell.lane(i)),
                    bits(&simd.smooth_in_cell(cells[i], fractions[i], s)),
                    "{D}D in cell"
                );
            }
        }
    }
    let config = Config { density: 2.0, seed: 11, ..Config::default() };
    check::<2>(config, 0.3);
    check::<3>(config, 0.1);
    check::<3>(config, 1.5);
    check::<4>(config, 0.3);
    check::<3>(Config { mode: Mode::Window, ..config }, 0.3);
}

#[test]
fn simd_smooth_keeps_bad_lanes_to_themselves_and_refuses_other_metrics() {
    let simd = SimdSmooth::<3>::new(Config::default()).unwrap();
    let f1 = Simd::<3, 1>::new(Config::default(), Outputs::Ids).unwrap();
    let mut x: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64 * 0.61, 2.5, -7.25]);
    // s = 0 is F1 itself, bit for bit.
    let zero = simd.smooth8(&x, 0.0);
    let want = f1.evaluate8(&x);
    for i in 0..8 {
        assert_eq!(zero.lane(i).value.to_bits(), want.distance[0].to_array()[i].to_bits());
        assert_eq!(zero.lane(i).feature, want.id[0].to_array()[i]);
    }
    let good = simd.smooth8(&x, 0.3);
    x[2][1] = f64::NAN;
    x[5][0] = f64::INFINITY;
    x[6][2] = -1e300;
    let mixed = simd.smooth8(&x, 0.3);
    for i in 0..8 {
        let v = mixed.lane(i);
        if [2, 5, 6].contains(&i) {
            assert!(v.value.is_nan() && v.gradient.iter().all(|g| g.is_nan()) && v.feature == INVALID_ID, "lane {i}");
        } else {
            assert_eq!(v, good.lane(i), "lane {i} changed with its neighbours");
            assert!(v.value.is_finite(), "lane {i}: {v:?}");
        }
    }
    for s in [-0.1, f32::NAN, f32::INFINITY] {
        assert!(simd.smooth8(&x, s).lanes().iter().all(|v| v.value.is_nan() && v.feature == INVALID_ID), "s {s}");
    }
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
        let config = Config { metric, ..Config::default() };
        assert_eq!(SimdSmooth::<3>::new(config).unwrap_err(), ConfigError::BorderMetric(metric));
    }
}

/// Compact smooth F1 by brute force over the periodic images (`x` in
/// cells, `s` and the result in user units, `scale` cells per user unit):
/// every image's h, the root of Σ φ((h_j − S)/s) = 1 by plain bisection,
/// the gradient as the weighted mean of ∇h_j. Returns (S, ∇S, F1's ID,
/// the reach).
fn periodic_smooth<const D: usize>(
    images: &[([f64; D], u32)],
    period: [u32; D],
    x: [f64; D],
    s: f64,
    scale: f64,
) -> (f64, [f64; D], u32, f64) {
    let r: [f64; D] = std::array::from_fn(|a| x[a].rem_euclid(f64::from(period[a])));
    let first = nearest(images, &r, None);
    let f1 = d2(&images[first].0, &r).sqrt() / scale;
    let h1 = f1.hypot(s) - s;
    let reach = ((h1 + 2.0 * s).powi(2) - s * s).sqrt();
    // (h_j, ∇h_j) of the images within the reach.
    let near: Vec<(f64, [f64; D])> = images
        .iter()
        .filter_map(|(p, _)| {
            let f = d2(p, &r).sqrt() / scale;
            let root = f.hypot(s);
            (f < reach).then(|| (root - s, std::array::from_fn(|a| (r[a] - p[a]) / scale / root)))
        })
        .collect();
    let phi = |t: f64| if t < 1.0 { (1.0 - 1.0 / (1.0 - t)).exp() } else { 0.0 };
    let total = |v: f64| near.iter().map(|(h, _)| phi((h - v) / s)).sum::<f64>();
    let (mut lo, mut hi) = (h1 - s, h1);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if total(mid) >= 1.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let (mut weight, mut gradient) = (0.0, [0.0; D]);
    for (h, g) in &near {
        let t = (h - hi) / s;
        let w = if t < 1.0 { phi(t) / ((1.0 - t) * (1.0 - t)) } else { 0.0 };
        weight += w;
        for (sum, g) in gradient.iter_mut().zip(g) {
            *sum += w * g;
        }
    }
    (hi, gradient.map(|g| g / weight), images[first].1, reach)
}

/// The periodic value (`smooth_periodic`, one lane and eight) against brute
/// force over the periodic images, for periods of a few cells where the
/// search wraps around; s = 1.5 keeps more points than fit on the stack.
#[test]
fn periodic_smooth_agrees_with_brute_force_over_periodic_images() {
    fn go<const D: usize>(period: [u32; D], s: f32, seed: u64) -> (f64, f64) {
        let config = Config { seed, ..Config::default() };
        let simd = SimdSmooth::<D>::new(config).unwrap();
        let p = Period::new(period).unwrap();
        let scale = Reference::<D>::new(config).unwrap().pattern().scale();
        let images = periodic_images(Reference::<D>::new(config).unwrap().pattern(), period);
        let (mut worst, mut worst_gradient) = (0f64, 0f64);
        for block in 0..25 {
            let x: [[f64; D]; 8] = std::array::from_fn(|i| {
                std::array::from_fn(|a| {
                    (uniform(seed, ((block * 8 + i) * D + a) as u64) - 0.5) * 30.0 * f64::from(period[a])
                })
            });
            let eight = simd.smooth8_periodic(&x, &p, s);
            for (i, &x) in x.iter().enumerate() {
                let got = simd.smooth_periodic(x, &p, s);
                assert_eq!(got, eight.lane(i), "{D}D {x:?}: one and eight");
                let (value, gradient, feature, reach) = periodic_smooth(&images, period, x, f64::from(s), scale);
                assert_eq!(got.feature, feature, "{D}D {period:?} s {s} at {x:?}");
                let allowed = bound(reach, value, 1.0 / scale);
                let error = (f64::from(got.value) - value).abs();
                assert!(error <= allowed, "{D}D {period:?} s {s} at {x:?}: {} against {value}", got.value);
                worst = worst.max(error / allowed);
                for (g, want) in got.gradient.iter().zip(gradient) {
                    worst_gradient = worst_gradient.max((f64::from(*g) - want).abs());
                }
            }
        }
        (worst, worst_gradient)
    }
    for (name, (worst, gradient)) in [
        ("2D [3, 4] s 0.3", go::<2>([3, 4], 0.3, 1)),
        ("2D [5, 3] s 1.5", go::<2>([5, 3], 1.5, 2)),
        ("3D [3, 3, 4] s 0.1", go::<3>([3, 3, 4], 0.1, 3)),
        ("3D [3, 4, 3] s 1.5", go::<3>([3, 4, 3], 1.5, 4)),
        ("4D [3, 3, 3, 3] s 0.3", go::<4>([3, 3, 3, 3], 0.3, 5)),
    ] {
        println!("periodic smooth F1 {name}: worst value error {worst:.3} of the bound, gradient {gradient:.2e}");
        assert!(gradient < 2e-4, "{name}: gradient error {gradient}");
    }
}

/// Inside one period, away from its faces, the periodic pattern is the
/// ordinary one, so periodic smooth F1 of x (in cells) is the value at the
/// same cell and fraction, bit for bit; periods away it repeats.
#[test]
fn periodic_smooth_is_the_ordinary_one_inside_a_period_and_repeats() {
    let simd = SimdSmooth::<2>::new(Config { seed: 2, ..Config::default() }).unwrap();
    let period = Period::new([4096, 2048]).unwrap();
    for s in [0.3, 1.5] {
        for i in 0..5_000 {
            let cell = [20 + (i as i64 * 7) % 4000, 20 + (i as i64 * 13) % 2000];
            let fraction = sample_point::<2>(11, i, 0.5).map(|v| (v + 0.5) as f32);
            let x: [f64; 2] = std::array::from_fn(|a| cell[a] as f64 + f64::from(fraction[a]));
            let periodic = simd.smooth_periodic(x, &period, s);
            assert_eq!(periodic, simd.smooth_in_cell(cell, fraction, s), "s {s} at {x:?}");
            let shifted = [x[0] - 4096.0 * 2.0, x[1] + 2048.0 * 5.0];
            assert_eq!(simd.smooth_periodic(shifted, &period, s), periodic, "s {s} at {shifted:?}");
        }
    }
    assert!(simd.smooth_periodic([f64::NAN, 1.0], &period, 0.3).value.is_nan());
}
