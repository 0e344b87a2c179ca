//! The n-sphere radius in lanes (`SimdNSphere`) against the f64 reference
//! (`Reference::n_sphere`, itself held to brute force in
//! `tests/suite/smooth.rs`), the periodic pattern against brute force over
//! its images, the same bits through every entry point, and bad lanes kept
//! to themselves.

use super::images::{d2, nearest};
use worley::{Config, ConfigError, Grid, Metric, Mode, NSphere32, Period, Reference, SimdNSphere, INVALID_ID};
use worley_harness::oracle::periodic_images;
use worley_harness::{chunked, sample_point, uniform};

/// The stated bound: the radius is F2 halved at an exact centre, and F2
/// is within 4ε(F2 + 1/S) of the exact distance.
fn bound(radius: f64, inv_scale: f64) -> f64 {
    2.0 * f64::from(f32::EPSILON) * (2.0 * radius + inv_scale)
}

/// Largest error over the bound, and how many radii were +∞.
fn agrees<const D: usize>(config: Config, seed: u64, n: usize, range: f64) -> (f64, usize) {
    let reference = Reference::<D>::new(config).unwrap();
    let simd = SimdNSphere::<D>::new(config).unwrap();
    let inv_scale = 1.0 / reference.pattern().scale();
    let points: Vec<[f64; D]> = (0..n).map(|i| sample_point::<D>(seed, i, range)).collect();
    let mut got = vec![NSphere32::INVALID; n];
    simd.n_sphere_slice(&points, &mut got).unwrap();
    let (mut worst, mut unbounded) = (0f64, 0);
    for (x, g) in points.iter().zip(&got) {
        let want = reference.n_sphere(*x);
        assert_eq!((g.feature, g.neighbour), (want.feature, want.neighbour), "{D}D at {x:?}: {g:?} against {want:?}");
        if want.radius.is_nan() {
            // Window mode with no point around the sample: no centre.
            assert!(g.radius.is_nan() && want.feature == INVALID_ID, "{D}D at {x:?}: {g:?} against {want:?}");
            continue;
        }
        if want.radius.is_infinite() {
            unbounded += 1;
            assert_eq!(f64::from(g.radius), want.radius, "{D}D at {x:?}");
            continue;
        }
        let (error, allowed) = ((f64::from(g.radius) - want.radius).abs(), bound(want.radius, inv_scale));
        assert!(error <= allowed, "{D}D at {x:?}: {} against {} (bound {allowed:e})", g.radius, want.radius);
        worst = worst.max(error / allowed);
    }
    (worst, unbounded)
}

#[test]
fn simd_n_sphere_agrees_with_the_reference_in_every_dimension() {
    let c = |seed, density| Config { seed, density, ..Config::default() };
    let window = |seed, density| Config { mode: Mode::Window, ..c(seed, density) };
    let runs = chunked(6, |range| {
        range
            .map(|run| match run {
                0 => ("2D", agrees::<2>(c(0, 5.0), 1, 100_000, 1000.0)),
                1 => ("3D", agrees::<3>(c(0, 5.0), 2, 50_000, 1000.0)),
                2 => ("4D", agrees::<4>(c(0, 5.0), 3, 10_000, 1000.0)),
                // Sparse points: F1's point lies cells away, and so may its
                // neighbour.
                3 => ("3D λ 0.5", agrees::<3>(c(7, 0.5), 4, 20_000, 1000.0)),
                4 => ("2D λ 32", agrees::<2>(c(3, 32.0), 5, 20_000, 100.0)),
                // Sparse enough that some windows around a centre hold no
                // other point: +∞, as the reference says.
                _ => ("2D window λ 0.3", agrees::<2>(window(2, 0.3), 6, 20_000, 100.0)),
            })
            .collect::<Vec<_>>()
    });
    for (name, (worst, unbounded)) in runs.into_iter().flatten() {
        println!("{name}: worst error {worst:.3} of the bound, {unbounded} unbounded");
        if name.contains("window") {
            assert!(unbounded > 0, "{name}: no window without a second point, so +∞ went untested");
        }
    }
}

#[test]
fn simd_n_sphere_gives_the_same_bits_through_every_entry_point() {
    fn check<const D: usize>(config: Config) {
        let simd = SimdNSphere::<D>::new(config).unwrap();
        let bits = |n: &NSphere32| (n.radius.to_bits(), n.feature, n.neighbour);
        // A grid whose F1 takes the grid tiles and whose samples share
        // their centres many times over, and one whose F1 is per sample.
        let size = std::array::from_fn(|a| if a < 2 { 40 } else { 3 });
        let fine = Grid { origin: [-3.3; D], step: [0.05; D], size };
        let kernel = worley::Simd::<D, 1>::new(config, worley::Outputs::Distances).unwrap();
        assert_eq!(kernel.coherent_grid(&fine), config.mode == Mode::Exact, "{D}D");
        for (step, name) in [(0.05, "tiles"), (0.37, "per sample")] {
            let grid = Grid { step: [step; D], ..fine };
            let mut out = vec![NSphere32::INVALID; grid.len().unwrap()];
            simd.n_sphere_grid(&grid, &mut out).unwrap();
            for (i, g) in out.iter().enumerate() {
                assert_eq!(bits(g), bits(&simd.n_sphere(grid.point(i))), "{D}D grid ({name}) sample {i}");
            }
        }
        let grid = Grid { step: [0.37; D], ..fine };
        let mut out = vec![NSphere32::INVALID; grid.len().unwrap()];
        simd.n_sphere_grid(&grid, &mut out).unwrap();
        for (c, chunk) in out.chunks(8).enumerate().take(20) {
            if chunk.len() < 8 {
                break;
            }
            let x: [[f64; D]; 8] = std::array::from_fn(|i| grid.point(c * 8 + i));
            let eight = simd.n_sphere8(&x);
            // The same numbers read as cells and fractions (other points
            // of the pattern): eight lanes against one.
            let cells: [[i64; D]; 8] = std::array::from_fn(|i| x[i].map(|v| v.floor() as i64));
            let fractions: [[f32; D]; 8] = std::array::from_fn(|i| x[i].map(|v| (v - v.floor()) as f32));
            let in_cell = simd.n_sphere8_in_cell(&cells, &fractions);
            for i in 0..8 {
                assert_eq!(bits(&eight.lane(i)), bits(&chunk[i]), "{D}D eight, lane {i}");
                assert_eq!(
                    bits(&in_cell.lane(i)),
                    bits(&simd.n_sphere_in_cell(cells[i], fractions[i])),
                    "{D}D in cell"
                );
            }
        }
    }
    let config = Config { density: 2.0, seed: 11, ..Config::default() };
    check::<2>(config);
    check::<3>(config);
    check::<4>(config);
    check::<3>(Config { mode: Mode::Window, ..config });
}

#[test]
fn simd_n_sphere_keeps_bad_lanes_to_themselves_and_refuses_other_metrics() {
    let simd = SimdNSphere::<3>::new(Config::default()).unwrap();
    let mut x: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64 * 0.61, 2.5, -7.25]);
    let good = simd.n_sphere8(&x);
    x[2][1] = f64::NAN;
    x[5][0] = f64::INFINITY;
    x[6][2] = -1e300;
    let mixed = simd.n_sphere8(&x);
    for i in 0..8 {
        let n = mixed.lane(i);
        if [2, 5, 6].contains(&i) {
            assert!(n.radius.is_nan() && n.feature == INVALID_ID && n.neighbour == INVALID_ID, "lane {i}: {n:?}");
        } else {
            assert_eq!(n, good.lane(i), "lane {i} changed with its neighbours");
            assert!(n.radius > 0.0 && n.neighbour != n.feature, "lane {i}: {n:?}");
        }
    }
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
        let config = Config { metric, ..Config::default() };
        assert_eq!(SimdNSphere::<3>::new(config).unwrap_err(), ConfigError::BorderMetric(metric));
    }
}

/// Brute force over the periodic point set (`x` and the radius in cells):
/// F1's image the nearest to `x` (reduced into the period), then the
/// nearest other image to it. Returns (radius in cells, centre ID,
/// neighbour ID).
fn periodic_n_sphere<const D: usize>(config: Config, period: [u32; D], x: [f64; D]) -> (f64, u32, u32) {
    let images = periodic_images(Reference::<D>::new(config).unwrap().pattern(), period);
    let r: [f64; D] = std::array::from_fn(|a| x[a].rem_euclid(f64::from(period[a])));
    let c = nearest(&images, &r, None);
    let n = nearest(&images, &images[c].0, Some(c));
    (0.5 * d2(&images[n].0, &images[c].0).sqrt(), images[c].1, images[n].1)
}

/// The periodic radius (`n_sphere_periodic`, eight lanes and one) against
/// brute force over the periodic images, for periods of a few cells where
/// the search wraps around.
#[test]
fn periodic_n_sphere_agrees_with_brute_force_over_periodic_images() {
    fn go<const D: usize>(period: [u32; D], seed: u64) -> f64 {
        let config = Config { seed, ..Config::default() };
        let simd = SimdNSphere::<D>::new(config).unwrap();
        let p = Period::new(period).unwrap();
        let scale = Reference::<D>::new(config).unwrap().pattern().scale();
        let mut worst = 0f64;
        for block in 0..40 {
            let x: [[f64; D]; 8] = std::array::from_fn(|i| {
                std::array::from_fn(|a| {
                    (uniform(seed, ((block * 8 + i) * D + a) as u64) - 0.5) * 30.0 * f64::from(period[a])
                })
            });
            let eight = simd.n_sphere8_periodic(&x, &p);
            for (i, &x) in x.iter().enumerate() {
                let got = simd.n_sphere_periodic(x, &p);
                assert_eq!(got.radius.to_bits(), eight.lane(i).radius.to_bits(), "{D}D {x:?}: one and eight");
                let (radius, feature, neighbour) = periodic_n_sphere(config, period, x);
                assert_eq!((got.feature, got.neighbour), (feature, neighbour), "{D}D {period:?} at {x:?}");
                // In user units, as the lanes give it.
                let want = radius / scale;
                let allowed = bound(want, 1.0 / scale);
                let error = (f64::from(got.radius) - want).abs();
                assert!(error <= allowed, "{D}D {period:?} at {x:?}: {} against {want}", got.radius);
                worst = worst.max(error / allowed);
            }
        }
        worst
    }
    for (name, worst) in [
        ("2D [3, 4]", go::<2>([3, 4], 1)),
        ("2D [5, 3]", go::<2>([5, 3], 2)),
        ("3D [3, 3, 4]", go::<3>([3, 3, 4], 3)),
        ("4D [3, 3, 3, 3]", go::<4>([3, 3, 3, 3], 4)),
    ] {
        println!("periodic n-sphere {name}: worst error {worst:.3} of the bound");
    }
}

/// Inside one period, away from its faces, the periodic pattern is the
/// ordinary one, so the periodic radius of x (in cells) is the radius at
/// the same cell and fraction, bit for bit; periods away it repeats.
#[test]
fn periodic_n_spheres_are_the_ordinary_ones_inside_a_period_and_repeat() {
    let spheres = SimdNSphere::<2>::new(Config { seed: 2, ..Config::default() }).unwrap();
    let period = Period::new([4096, 2048]).unwrap();
    for i in 0..20_000 {
        let cell = [20 + (i as i64 * 7) % 4000, 20 + (i as i64 * 13) % 2000];
        let fraction = sample_point::<2>(11, i, 0.5).map(|v| (v + 0.5) as f32);
        let x: [f64; 2] = std::array::from_fn(|a| cell[a] as f64 + f64::from(fraction[a]));
        let periodic = spheres.n_sphere_periodic(x, &period);
        assert_eq!(periodic, spheres.n_sphere_in_cell(cell, fraction), "at {x:?}");
        assert!(periodic.radius > 0.0);
        let shifted = [x[0] - 4096.0 * 2.0, x[1] + 2048.0 * 5.0];
        assert_eq!(spheres.n_sphere_periodic(shifted, &period), periodic, "at {shifted:?}");
    }
    assert!(spheres.n_sphere_periodic([f64::NAN, 1.0], &period).radius.is_nan());
}
