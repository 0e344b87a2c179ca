//! Footprint-aware textures: a zero footprint is the point sample, the
//! blend is the least-squares estimate of the footprint's average, the
//! means are the Poisson process's, values are continuous in position and
//! footprint, and the cost falls as the footprint grows.

use worley::filter::{BlendCurve, FLOOR};
use worley::texture::{Combination, Fractal, Texture};
use worley::{Config, Grid, Metric, Mode, Outputs, Period, Simd};
use worley_harness::{filtered_continuity, uniform};

/// Σ amplitude_i · C(frequency_i · x) from the kernel, in the order the
/// texture sums (the first octave, then sum + amplitude · value).
fn point_sum<const D: usize, const N: usize>(
    kernel: &Simd<D, N>,
    combine: impl Fn(&[f32; N]) -> f32,
    fractal: Fractal,
    x: [f64; D],
) -> f32 {
    let (mut frequency, mut amplitude, mut sum) = (1.0f64, 1.0f32, 0.0f32);
    for i in 0..fractal.octaves {
        let f = kernel.evaluate(x.map(|v| v * frequency));
        let v = combine(&f.distance);
        sum = if i == 0 { v } else { sum + amplitude * v };
        frequency *= f64::from(fractal.lacunarity);
        amplitude *= fractal.gain;
    }
    sum
}

#[test]
fn a_zero_footprint_is_the_point_sample_through_every_entry_point() {
    let config = Config { order: 2, ..Config::default() };
    let kernel = Simd::<3, 2>::new(config, Outputs::Distances).unwrap();
    let fractal = Fractal::octaves(4);
    let t = Texture::<3, 2>::new(config, Combination::crackle(), fractal, None).unwrap();
    let xs: Vec<[f64; 3]> =
        (0..203).map(|i| std::array::from_fn(|a| 40.0 * uniform(7, (i * 3 + a) as u64) - 20.0)).collect();
    let mut out = vec![0.0; xs.len()];
    t.filtered_values(&xs, Some(&vec![0.0; xs.len()]), &mut out).unwrap();
    for (x, got) in xs.iter().zip(&out) {
        let want = point_sum(&kernel, |f| f[1] - f[0], fractal, *x);
        assert_eq!(got.to_bits(), want.to_bits(), "{x:?}");
        assert_eq!(t.filtered(*x, 0.0).to_bits(), want.to_bits());
    }
    let block: [[f64; 3]; 8] = std::array::from_fn(|i| xs[i]);
    let (g, p) = (t.filtered_gradient8(&block, [0.0; 8]), t.gradient8(&block));
    assert_eq!(g.value.to_array().map(f32::to_bits), p.value.to_array().map(f32::to_bits));
    for a in 0..3 {
        assert_eq!(g.gradient[a].to_array().map(f32::to_bits), p.gradient[a].to_array().map(f32::to_bits));
    }
    let grid = Grid { origin: [-3.3, 1.7, 0.25], step: [0.0625, 0.125, 0.0], size: [37, 11, 1] };
    let mut image = vec![0.0; 37 * 11];
    t.filtered_grid(&grid, 0.0, &mut image).unwrap();
    for (i, v) in image.iter().enumerate() {
        assert_eq!(v.to_bits(), point_sum(&kernel, |f| f[1] - f[0], fractal, grid.point(i)).to_bits());
    }
}

/// The brute-force average of a 2D field over the axis-aligned square of
/// side `w` centred on x (a 24 × 24 grid of points).
fn box_average(t: &Texture<2, 1>, x: [f64; 2], w: f64) -> f64 {
    let n = 24;
    let mut sum = 0.0;
    for j in 0..n {
        for i in 0..n {
            let p = [x[0] + w * ((i as f64 + 0.5) / n as f64 - 0.5), x[1] + w * ((j as f64 + 0.5) / n as f64 - 0.5)];
            sum += f64::from(t.value(p));
        }
    }
    sum / (n * n) as f64
}

#[test]
fn the_blend_is_the_least_squares_estimate_of_the_footprint_average() {
    // Independent of the curve's measurement: footprint averages by brute
    // force, and the weight that fits them best by least squares.
    let t = Texture::<2, 1>::new(Config::default(), Combination::f(1), Fractal::default(), None).unwrap();
    let curve = t.blend_curve();
    for w in [0.25, 0.5, 1.0, 2.0] {
        let (mut num, mut den) = (0.0, 0.0);
        let (mut point, mut filtered, mut mean) = (0.0, 0.0, 0.0);
        let mu = f64::from(curve.mean());
        for i in 0..1500 {
            let x = [2000.0 * uniform(3, 2 * i) - 1000.0, 2000.0 * uniform(3, 2 * i + 1) - 1000.0];
            let a = box_average(&t, x, w);
            let c = f64::from(t.value(x));
            num += (c - mu) * (a - mu);
            den += (c - mu) * (c - mu);
            point += (c - a) * (c - a);
            filtered += (f64::from(t.filtered(x, w as f32)) - a).powi(2);
            mean += (mu - a) * (mu - a);
        }
        let best = num / den;
        let alpha = f64::from(curve.weight(w as f32));
        // The curve's weight is β renormalised above β₀.
        let beta = if alpha > 0.0 { f64::from(FLOOR) + alpha * (1.0 - f64::from(FLOOR)) } else { 0.0 };
        let slack = if alpha == 0.0 { f64::from(FLOOR) } else { 0.0 };
        assert!((beta - best).abs() < 0.08 + slack, "w {w}: curve β {beta}, least squares {best}");
        assert!(
            filtered < point && filtered <= mean * 1.02,
            "w {w}: errors filtered {filtered}, point {point}, mean {mean}"
        );
    }
}

#[test]
fn closed_form_means_match_measured_ones() {
    fn check<const D: usize, const N: usize>(metric: Metric, combination: Combination) {
        let config = Config { metric, ..Config::default() };
        let t = Texture::<D, N>::new(config, combination.clone(), Fractal::default(), None).unwrap();
        let closed = f64::from(t.filtered([0.5; D], 1e9));
        let n = 200_000;
        let xs: Vec<[f64; D]> =
            (0..n).map(|i| std::array::from_fn(|a| 4000.0 * uniform(11, (i * D + a) as u64) - 2000.0)).collect();
        let mut v = vec![0.0; n];
        t.values(&xs, &mut v).unwrap();
        let mean = v.iter().map(|&x| f64::from(x)).sum::<f64>() / n as f64;
        let sd = (v.iter().map(|&x| (f64::from(x) - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        let error = sd / (n as f64).sqrt();
        assert!(
            (closed - mean).abs() < 5.0 * error + 1e-3 * mean.abs(),
            "{D}D {metric:?} {}: closed form {closed}, measured {mean} ± {error}",
            combination.name()
        );
    }
    check::<2, 1>(Metric::Euclidean, Combination::f(1));
    check::<3, 2>(Metric::Euclidean, Combination::crackle());
    check::<3, 4>(Metric::Euclidean, Combination::f(4));
    check::<4, 3>(Metric::Euclidean, Combination::SquareDifference);
    check::<3, 1>(Metric::Manhattan, Combination::f(1));
    check::<2, 2>(Metric::Chebyshev, Combination::f(2));
}

#[test]
fn cost_falls_with_the_footprint_and_bad_input_stays_nan() {
    let fractal = Fractal::octaves(6);
    let t = Texture::<3, 1>::new(Config::default(), Combination::f(1), fractal, None).unwrap();
    let mut last = 6;
    for k in -12..12 {
        let n = t.resolved_octaves((k as f32 / 2.0).exp2());
        assert!(n <= last, "octaves rise from {last} to {n}");
        last = n;
    }
    assert_eq!(t.resolved_octaves(0.0), 6);
    assert_eq!(last, 0);
    // No octave resolved: the fractal sum of the means.
    let mean = t.blend_curve().mean();
    let mut want = mean;
    let mut amplitude = 1.0f32;
    for _ in 1..6 {
        amplitude *= 0.5;
        want += amplitude * mean;
    }
    assert_eq!(t.filtered([1.0, 2.0, 3.0], 1e6), want);
    assert_eq!(t.filtered([1.0, 2.0, 3.0], f32::INFINITY), want);
    // Bad input gives NaN whether or not an octave is evaluated.
    for w in [0.0, 0.3, 1e6] {
        assert!(t.filtered([f64::NAN, 0.0, 0.0], w).is_nan());
        assert!(t.filtered([0.0, f64::INFINITY, 0.0], w).is_nan());
        assert!(t.filtered([1e300, 0.0, 0.0], w).is_nan());
    }
    assert!(t.filtered([0.0; 3], -1.0).is_nan() && t.filtered([0.0; 3], f32::NAN).is_nan());
    let g = t.filtered_gradient8(&[[0.0, f64::NAN, 0.0]; 8], [1e6; 8]);
    assert!(g.value.to_array()[0].is_nan() && !g.defined[0]);
}

#[test]
fn filtered_grids_their_bands_and_slices_give_each_points_filtered_value() {
    fn check<const D: usize, const N: usize>(t: &Texture<D, N>, grid: &Grid<D>) {
        for width in [0.0f32, 0.07, 0.4, 3.0, 1e4] {
            let mut image = vec![0.0; grid.len().unwrap()];
            t.filtered_grid(grid, width, &mut image).unwrap();
            for (i, v) in image.iter().enumerate() {
                let want = t.filtered(grid.point(i), width);
                assert_eq!(v.to_bits(), want.to_bits(), "width {width}, sample {i}");
            }
            // Bands of rows baked apart assemble into the whole grid.
            let row = grid.size[0];
            let mut first = 0;
            for rows in [1, 5, 2, 7].into_iter().cycle() {
                let rows = rows.min(grid.rows().unwrap() - first);
                let mut band = vec![f32::NAN; rows * row];
                t.filtered_grid_rows(grid, width, first, &mut band).unwrap();
                let whole = &image[first * row..(first + rows) * row];
                assert!(band.iter().zip(whole).all(|(a, b)| a.to_bits() == b.to_bits()), "rows {first}.., {width}");
                first += rows;
                if first == grid.rows().unwrap() {
                    break;
                }
            }
            let mut short = vec![0.0; row + 1];
            assert!(t.filtered_grid_rows(grid, width, 0, &mut short).is_err());
            let mut last = vec![0.0; 2 * row];
            assert!(t.filtered_grid_rows(grid, width, grid.rows().unwrap() - 1, &mut last).is_err());
        }
    }
    let grid = Grid { origin: [0.3, -7.1], step: [0.05, 0.0625], size: [29, 17] };
    // The tile path (lacunarity 2) and the eight-point path (lacunarity 3,
    // a period).
    let t = Texture::<2, 2>::new(Config::default(), Combination::crackle(), Fractal::octaves(5), None).unwrap();
    check(&t, &grid);
    let t3 = Texture::<2, 1>::new(
        Config::default(),
        Combination::f(1),
        Fractal { octaves: 3, lacunarity: 3.0, gain: 0.5 },
        Some(Period::new([8, 8]).unwrap()),
    )
    .unwrap();
    check(&t3, &grid);
    // The border's octaves through its own grid tiles.
    let border = Texture::<2, 1>::new(Config::default(), Combination::Border, Fractal::octaves(3), None).unwrap();
    check(&border, &grid);
}

#[test]
fn filtered_values_are_continuous_in_position_and_footprint() {
    let fractal = Fractal::octaves(4);
    // Lipschitz constant of Σ a_i C(f_i x) with weights ≤ 1: Σ a_i f_i Σ|c_k|.
    let lipschitz = |c: f64| (0..4).map(|i| 0.5f64.powi(i) * 2f64.powi(i)).sum::<f64>() * c;
    let t = Texture::<3, 2>::new(Config::default(), Combination::crackle(), fractal, None).unwrap();
    let scale = t.kernel().pattern().scale();
    let r = filtered_continuity(|x, w| t.filtered(x, w), scale, lipschitz(2.0), 1e-5, 30_000, 5);
    assert_eq!((r.position_violations, r.footprint_violations), (0, 0), "{r:?}");
    let config = Config { metric: Metric::Manhattan, mode: Mode::Window, ..Config::default() };
    let t = Texture::<2, 1>::new(config, Combination::f(1), fractal, None).unwrap();
    let scale = t.kernel().pattern().scale();
    // Window mode's F1 is still 1-Lipschitz at λ 5 but for rare misses;
    // the footprint check is what this configuration adds.
    let r = filtered_continuity(|x, w| t.filtered(x, w), scale, lipschitz(1.0) * 2.0, 1e-5, 30_000, 6);
    assert_eq!(r.footprint_violations, 0, "{r:?}");
    // The detector sees a jump: a curve whose value drops an octave at a
    // width where its weight is not yet 0.
    let curve = t.blend_curve().clone();
    let broken = |x: [f64; 2], w: f32| {
        let v = t.filtered(x, w);
        if w > 0.5 {
            v + 0.1 * curve.weight(w)
        } else {
            v
        }
    };
    let r = filtered_continuity(broken, scale, lipschitz(1.0) * 2.0, 1e-5, 3_000, 7);
    assert!(r.footprint_violations > 0 || curve.weight(0.5) == 0.0, "{r:?}");
}

#[test]
fn identity_curves_fall_from_one_and_measure_a_probability() {
    let cells = Simd::<2, 1>::new(Config::default(), Outputs::Ids).unwrap();
    let curve = BlendCurve::measure_identity(|p: &[[f64; 2]; 8]| cells.evaluate8(p).id[0].to_array(), 2);
    assert!(curve.mean().is_nan());
    // Brute force: how often a point a distance w·u away (u in the unit
    // square, a random rotation) shares the sample's cell.
    let w = 1.0;
    let (mut same, n) = (0usize, 20_000);
    for i in 0..n {
        let r = |k: u64| uniform(9, i as u64 * 8 + k);
        let x = [2000.0 * r(0) - 1000.0, 2000.0 * r(1) - 1000.0];
        let (u, v, angle) = (r(2) - 0.5, r(3) - 0.5, std::f64::consts::TAU * r(4));
        let y = [x[0] + w * (u * angle.cos() - v * angle.sin()), x[1] + w * (u * angle.sin() + v * angle.cos())];
        same += (cells.evaluate(x).id[0] == cells.evaluate(y).id[0]) as usize;
    }
    let p = same as f64 / n as f64;
    let alpha = f64::from(curve.weight(w as f32));
    let beta = f64::from(FLOOR) + alpha * (1.0 - f64::from(FLOOR));
    assert!(alpha > 0.0 && (beta - p).abs() < 0.03, "curve β {beta}, brute force {p}");
}

#[test]
fn cell_shares_approach_the_footprint_s_own_shares() {
    // Brute force: the share of a 32 × 32 grid over the square footprint
    // (axis-aligned, 2D) in each of F1..F4's cells, against the point
    // sample's (all in F1's cell) and `cell_cover8`'s.
    let config = Config { order: 4, ..Config::default() };
    let cells = Simd::<2, 4>::new(config, Outputs::IdsAndDeltas).unwrap();
    for w in [0.1f32, 0.4, 1.0] {
        let (mut point_error, mut cover_error) = (0.0, 0.0);
        for i in 0..400 {
            let x = [2000.0 * uniform(21, 2 * i) - 1000.0, 2000.0 * uniform(21, 2 * i + 1) - 1000.0];
            let f = cells.evaluate8(&[x; 8]);
            let share = worley::filter::cell_cover8(&f, [w; 8]);
            let ids = f.id.map(|v| v.to_array()[0]);
            let mut truth = [0.0f64; 4];
            let n = 32;
            for a in 0..n {
                for b in 0..n {
                    let d = |j: usize| f64::from(w) * ((j as f64 + 0.5) / n as f64 - 0.5);
                    let id = cells.evaluate([x[0] + d(a), x[1] + d(b)]).id[0];
                    if let Some(k) = ids.iter().position(|&v| v == id) {
                        truth[k] += 1.0 / (n * n) as f64;
                    }
                }
            }
            for k in 0..4 {
                let point = if k == 0 { 1.0 } else { 0.0 };
                point_error += (point - truth[k]).abs();
                cover_error += (f64::from(share[k][0]) - truth[k]).abs();
            }
        }
        assert!(cover_error < 0.5 * point_error, "w {w}: shares off by {cover_error}, point sample by {point_error}");
    }
    let f = cells.evaluate8(&[[f64::NAN, 0.0]; 8]);
    assert!(worley::filter::cell_cover8(&f, [0.3; 8])[0][0].is_nan());
    let f = cells.evaluate8(&[[0.5, 0.5]; 8]);
    assert!(worley::filter::cell_cover8(&f, [-1.0; 8])[0][0].is_nan());
    assert_eq!(worley::filter::cell_cover8(&f, [0.0; 8])[0][0], 1.0);
}

#[test]
fn a_texture_with_another_fractal_keeps_its_curve_and_gives_a_fresh_texture_s_bits() {
    let period = Some(Period::new([6, 4]).unwrap());
    for (combination, period) in
        [(Combination::crackle(), None), (Combination::Border, None), (Combination::f(1), period)]
    {
        let config = Config { seed: 9, ..Config::default() };
        // Built as order 2 so that F2 − F1 fits; the border and F1 use F1.
        let base = Texture::<2, 2>::new(config, combination.clone(), Fractal::octaves(1), period).unwrap();
        let measured = base.blend_curve().clone();
        for fractal in [Fractal::octaves(4), Fractal { octaves: 3, lacunarity: 3.0, gain: 0.7 }] {
            let derived = base.with_fractal(fractal).unwrap();
            let fresh = Texture::<2, 2>::new(config, combination.clone(), fractal, period).unwrap();
            assert_eq!(derived.fractal(), fractal);
            assert_eq!(derived.blend_curve(), &measured, "{combination:?}: the curve was measured again or changed");
            assert_eq!(
                fresh.blend_curve(),
                &measured,
                "{combination:?}: the curve depends on more than the first octave"
            );
            for i in 0..200 {
                let x = [uniform(3, 2 * i) * 40.0 - 20.0, uniform(3, 2 * i + 1) * 40.0 - 20.0];
                let w = [0.0, 0.01, 0.3, 2.0, 50.0][i as usize % 5];
                assert_eq!(
                    derived.filtered(x, w).to_bits(),
                    fresh.filtered(x, w).to_bits(),
                    "{combination:?} at {x:?}, width {w}"
                );
            }
        }
    }
    // An invalid fractal sum is refused as `new` refuses it.
    let t = Texture::<2, 1>::new(Config::default(), Combination::f(1), Fractal::default(), None).unwrap();
    assert!(t.with_fractal(Fractal { gain: 1.5, ..Fractal::default() }).is_err());
}
