//! The border distance in lanes (`SimdBorder`) against the f64 reference
//! (`Reference::border`, itself held to a brute-force oracle in
//! `tests/suite/border.rs`), the same bits through every entry point, bad
//! lanes kept to themselves, the hard cases, and the texture built on it.

use worley::texture::{Combination, Fractal, Texture, TextureError};
use worley::{Border32, Config, ConfigError, Grid, Metric, Mode, Period, Reference, SimdBorder, INVALID_ID};
use worley_harness::{chunked, sample_point};

/// The stated bound: b comes from deltas of length up to F1 + 2b, each
/// within a few f32 roundings, and from u = p_j − p₁ rounded once.
fn bound(f1: f64, b: f64, inv_scale: f64) -> f64 {
    4.0 * f64::from(f32::EPSILON) * (2.0 * f1 + 2.0 * b + inv_scale)
}

/// Largest |f32 − f64| of the distance over the bound, and of the normal.
#[derive(Default)]
struct Agreement {
    distance: f64,
    normal: f64,
    /// Samples whose border is +∞ (window mode, fewer than two points).
    unbounded: usize,
}

fn agrees<const D: usize>(config: Config, points: &[[f64; D]]) -> Agreement {
    let reference = Reference::<D>::new(config).unwrap();
    let simd = SimdBorder::<D>::new(config).unwrap();
    let f1 = Reference::<D>::new(Config { order: 1, ..config }).unwrap();
    let inv_scale = 1.0 / reference.pattern().scale();
    let mut got = vec![simd.border(points[0]); points.len()];
    simd.border_slice(points, &mut got).unwrap();
    let mut worst = Agreement::default();
    for (x, g) in points.iter().zip(&got) {
        let want = reference.border(*x).unwrap();
        assert_eq!(g.feature, want.feature, "{D}D at {x:?}: F1's ID ({g:?} against {want:?})");
        if !want.distance.is_finite() {
            worst.unbounded += 1;
            assert_eq!(f64::from(g.distance), want.distance, "{D}D at {x:?}: {g:?} against {want:?}");
            assert!(g.normal.iter().all(|v| v.is_nan()), "{D}D at {x:?}: a normal without a plane: {g:?}");
            continue;
        }
        assert_eq!(g.neighbour, want.neighbour, "{D}D at {x:?}: the neighbour ({g:?} against {want:?})");
        let error = (f64::from(g.distance) - want.distance).abs();
        let allowed = bound(f1.evaluate(*x).distance[0], want.distance, inv_scale);
        assert!(error <= allowed, "{D}D at {x:?}: {} against {} (bound {allowed:e})", g.distance, want.distance);
        worst.distance = worst.distance.max(error / allowed);
        for a in 0..D {
            let e = (f64::from(g.normal[a]) - want.normal[a]).abs();
            assert!(e <= 1e-6, "{D}D at {x:?}: normal {:?} against {:?}", g.normal, want.normal);
            worst.normal = worst.normal.max(e);
        }
    }
    worst
}

fn random<const D: usize>(seed: u64, n: usize, range: f64) -> Vec<[f64; D]> {
    (0..n).map(|i| sample_point::<D>(seed, i, range)).collect()
}

#[test]
fn simd_border_agrees_with_the_reference_in_every_dimension() {
    let c = |seed, density| Config { seed, density, ..Config::default() };
    let runs = chunked(7, |range| {
        range
            .map(|run| match run {
                0 => ("2D", agrees::<2>(c(0, 5.0), &random(1, 200_000, 1000.0))),
                1 => ("3D", agrees::<3>(c(0, 5.0), &random(2, 100_000, 1000.0))),
                2 => ("4D", agrees::<4>(c(0, 5.0), &random(3, 25_000, 1000.0))),
                // Sparse points: the border search widens into shells.
                3 => ("2D λ 0.5", agrees::<2>(c(7, 0.5), &random(4, 50_000, 1000.0))),
                4 => ("3D λ 0.5", agrees::<3>(c(7, 0.5), &random(5, 20_000, 1000.0))),
                5 => ("3D window", agrees::<3>(Config { mode: Mode::Window, ..c(1, 1.0) }, &random(6, 20_000, 100.0))),
                // Sparse enough that some 3 × 3 windows hold one point or none:
                // then b = +∞ (and F1 = +∞ with no point), as the reference says.
                _ => (
                    "2D window λ 0.3",
                    agrees::<2>(Config { mode: Mode::Window, ..c(2, 0.3) }, &random(7, 20_000, 100.0)),
                ),
            })
            .collect::<Vec<_>>()
    });
    for (what, a) in runs.into_iter().flatten() {
        println!(
            "{what}: largest distance error {:.3} of the bound, normal error {:.2e}, {} without a border",
            a.distance, a.normal, a.unbounded
        );
        if what.contains("λ 0.3") {
            assert!(a.unbounded > 100, "{what}: only {} windows with fewer than two points", a.unbounded);
        }
    }
}

/// Samples on lattice planes, edges and corners, and a hair to either
/// side: the cell changes there, the border distance must not jump.
#[test]
fn lattice_values_agree_with_the_reference() {
    let config = Config::default();
    let scale = Reference::<3>::new(config).unwrap().pattern().scale();
    let mut points = Vec::new();
    for i in 0..3000 {
        let base = sample_point::<3>(8, i, 200.0).map(|v| (v * scale).round());
        for nudge in [0.0, 1e-9, -1e-9, 0.5] {
            let on = i % 3;
            points
                .push(std::array::from_fn(|a| if a <= on { (base[a] + nudge) / scale } else { base[a] / scale + 0.3 }));
        }
    }
    agrees::<3>(config, &points);
}

/// Pairs of feature points closer than 2·10^−3 cells: the bisector between
/// them is where F2 − F1 widens into a wedge and where a plane's normal
/// computed from rounded deltas would tilt; u = p_j − p₁ is exact here.
#[test]
fn nearly_coincident_points_agree_with_the_reference() {
    let reference = Reference::<2>::new(Config::default()).unwrap();
    let pattern = reference.pattern();
    let scale = pattern.scale();
    let mut points = Vec::new();
    let mut pairs = 0;
    for i in 0..400_000i64 {
        let cell = [i % 2000, i / 2000];
        let p = pattern.points(cell);
        for (j, a) in p.iter().enumerate() {
            for b in &p[j + 1..] {
                let (x, y) = (a.offset(), b.offset());
                let apart = ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2)).sqrt();
                if apart < 2e-3 {
                    pairs += 1;
                    let mid = [0.5 * (x[0] + y[0]), 0.5 * (x[1] + y[1])];
                    for k in 0..50 {
                        let step = sample_point::<2>(9, k, 3.0 * apart);
                        points.push(std::array::from_fn(|a| (cell[a] as f64 + mid[a] + step[a]) / scale));
                    }
                }
            }
        }
    }
    assert!(pairs >= 5, "only {pairs} close pairs in the cells scanned");
    println!("{pairs} pairs closer than 2e-3 cells, {} samples around them", points.len());
    agrees::<2>(Config::default(), &points);
}

fn assert_same<const D: usize>(a: &Border32<D>, b: &Border32<D>, what: &str) {
    assert_eq!(a.distance.to_bits(), b.distance.to_bits(), "{what}: distance {a:?} against {b:?}");
    assert_eq!(a.normal.map(f32::to_bits), b.normal.map(f32::to_bits), "{what}: normal {a:?} against {b:?}");
    assert_eq!((a.feature, a.neighbour), (b.feature, b.neighbour), "{what}: IDs {a:?} against {b:?}");
}

#[test]
fn every_entry_point_gives_the_same_bits() {
    let config = Config { seed: 5, ..Config::default() };
    let border = SimdBorder::<3>::new(config).unwrap();
    let reference = Reference::<3>::new(config).unwrap();
    let pattern = reference.pattern();
    // A grid with an odd step and origin, its points through every call.
    let grid = Grid { origin: [-3.3, 0.7, 2.0], step: [0.137, 0.211, 0.05], size: [37, 11, 3] };
    let mut from_grid = vec![border.border([0.0; 3]); 37 * 11 * 3];
    border.border_grid(&grid, &mut from_grid).unwrap();
    let points: Vec<[f64; 3]> = (0..from_grid.len()).map(|i| grid.point(i)).collect();
    let mut on_all_cores = vec![border.border([0.0; 3]); points.len()];
    border.border_grid_parallel(&grid, &mut on_all_cores).unwrap();
    let mut from_slice = vec![border.border([0.0; 3]); points.len()];
    border.border_slice(&points, &mut from_slice).unwrap();
    let as_f32: Vec<[f32; 3]> = points.iter().map(|p| p.map(|v| v as f32)).collect();
    let mut from_f32 = vec![border.border([0.0; 3]); points.len()];
    border.border_slice(&as_f32, &mut from_f32).unwrap();
    let texture = Texture::<3, 1>::new(config, Combination::Border, Fractal::default(), None).unwrap();
    let mut from_texture = vec![0f32; points.len()];
    texture.values_grid(&grid, &mut from_texture).unwrap();
    for (i, x) in points.iter().enumerate() {
        let one = border.border(*x);
        assert_same(&from_grid[i], &one, "grid");
        assert_same(&on_all_cores[i], &one, "grid on all cores");
        assert_same(&from_slice[i], &one, "slice");
        // Eight lanes, the sample in each position among others.
        let mut eight: [[f64; 3]; 8] = std::array::from_fn(|k| points[(i + 7 * k) % points.len()]);
        eight[i % 8] = *x;
        assert_same(&border.border8(&eight).lane(i % 8), &one, "eight lanes");
        // A cell and a fraction, as the large-world calls take them.
        let (cell, fraction) = pattern.locate(*x).unwrap();
        assert_same(&border.border_in_cell(cell, fraction.map(|v| v as f32)), &one, "in cell");
        // f32 input: the f32 point's bits, through the slice and the lanes.
        let x32 = as_f32[i].map(f64::from);
        let lanes = border.border_lanes(std::array::from_fn(|a| wide::f32x8::splat(as_f32[i][a])));
        assert_same(&lanes.lane(3), &border.border(x32), "f32 lanes");
        assert_same(&from_f32[i], &border.border(x32), "f32 slice");
        // The texture of one octave is the distance, its gradient the normal.
        assert_eq!(from_texture[i].to_bits(), one.distance.to_bits(), "texture grid");
        let (value, gradient) = texture.gradient(*x);
        assert_eq!(value.value.to_bits(), one.distance.to_bits(), "texture gradient's value");
        assert_eq!(gradient.map(f32::to_bits), one.normal.map(f32::to_bits), "texture gradient");
    }
}

#[test]
fn bad_lanes_give_nan_and_the_invalid_id_and_leave_their_neighbours_alone() {
    let border = SimdBorder::<2>::new(Config::default()).unwrap();
    let bad = [[f64::NAN, 0.0], [f64::INFINITY, 1.0], [0.5, f64::NEG_INFINITY], [1e300, 2.0]];
    let mut eight: [[f64; 2]; 8] = std::array::from_fn(|i| [i as f64 * 0.37, -2.5]);
    for (i, b) in bad.iter().enumerate() {
        eight[2 * i] = *b;
    }
    let got = border.border8(&eight);
    for (i, x) in eight.iter().enumerate() {
        let lane = got.lane(i);
        if i % 2 == 0 {
            assert!(lane.distance.is_nan() && lane.normal.iter().all(|v| v.is_nan()), "lane {i}: {lane:?}");
            assert_eq!((lane.feature, lane.neighbour), (INVALID_ID, INVALID_ID), "lane {i}");
        } else {
            assert_same(&lane, &border.border(*x), "a good lane beside bad ones");
            assert!(lane.distance.is_finite() && lane.distance >= 0.0);
        }
    }
    // A fraction outside [0, 1] and a cell beyond the pattern's range.
    assert!(border.border_in_cell([0, 0], [1.5, 0.0]).distance.is_nan());
    assert_eq!(border.border_in_cell([i64::MAX, 0], [0.5, 0.5]).feature, INVALID_ID);
}

#[test]
fn other_metrics_are_refused_with_a_clear_error() {
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
        let config = Config { metric, ..Config::default() };
        assert_eq!(SimdBorder::<3>::new(config).unwrap_err(), ConfigError::BorderMetric(metric));
        let texture = Texture::<3, 1>::new(config, Combination::Border, Fractal::default(), None);
        assert_eq!(texture.unwrap_err(), TextureError::Config(ConfigError::BorderMetric(metric)));
    }
    assert_eq!("border".parse::<Combination>(), Ok(Combination::Border));
    assert_eq!(Combination::Border.name(), "border");
}

/// Far from the origin the border is computed relative to the sample's
/// cell, so a cell 2^40 away keeps the bound against the reference there.
#[test]
fn large_worlds_agree_with_the_reference_in_cell() {
    let config = Config::default();
    let (reference, border) = (Reference::<3>::new(config).unwrap(), SimdBorder::<3>::new(config).unwrap());
    let inv_scale = 1.0 / reference.pattern().scale();
    for i in 0..20_000 {
        let cell = [(1i64 << 40) + i as i64, -(1i64 << 35), 7];
        let fraction = sample_point::<3>(10, i, 0.5).map(|v| (v + 0.5) as f32);
        let got = border.border_in_cell(cell, fraction);
        let want = reference.border_in_cell(cell, fraction.map(f64::from)).unwrap();
        assert_eq!((got.feature, got.neighbour), (want.feature, want.neighbour), "cell {cell:?} + {fraction:?}");
        let f1 = Reference::<3>::new(Config { order: 1, ..config }).unwrap();
        let allowed = bound(f1.evaluate_in_cell(cell, fraction.map(f64::from)).distance[0], want.distance, inv_scale);
        assert!((f64::from(got.distance) - want.distance).abs() <= allowed, "cell {cell:?}: {got:?} against {want:?}");
    }
}

/// Inside one period the periodic pattern is the ordinary one, so the
/// periodic border of x (in cells) is the border at the same cell and
/// fraction, bit for bit; one period away it repeats.
#[test]
fn periodic_borders_are_the_ordinary_ones_inside_a_period_and_repeat() {
    let config = Config { seed: 2, ..Config::default() };
    let border = SimdBorder::<2>::new(config).unwrap();
    let period = Period::new([4096, 2048]).unwrap();
    for i in 0..20_000 {
        let cell = [20 + (i as i64 * 7) % 4000, 20 + (i as i64 * 13) % 2000];
        let fraction = sample_point::<2>(11, i, 0.5).map(|v| (v + 0.5) as f32);
        let x: [f64; 2] = std::array::from_fn(|a| cell[a] as f64 + f64::from(fraction[a]));
        let periodic = border.border_periodic(x, &period);
        assert_same(&periodic, &border.border_in_cell(cell, fraction), "periodic inside the period");
        let shifted = [x[0] + 4096.0 * 3.0, x[1] - 2048.0];
        assert_same(&border.border_periodic(shifted, &period), &periodic, "one period away");
    }
}

/// The border distance is 1-Lipschitz: pairs a small step apart, many
/// across a lattice plane, differ by no more than the step (and the
/// rounding bound).
#[test]
fn border_is_continuous_across_cell_faces() {
    let config = Config { seed: 3, ..Config::default() };
    let border = SimdBorder::<3>::new(config).unwrap();
    let scale = Reference::<3>::new(config).unwrap().pattern().scale();
    for i in 0..100_000 {
        let mut x = sample_point::<3>(12, i, 100.0);
        if i % 2 == 0 {
            x[i % 3] = (x[i % 3] * scale).round() / scale - 2e-7;
        }
        let step = sample_point::<3>(13, i, 4e-7);
        let y: [f64; 3] = std::array::from_fn(|a| x[a] + step[a]);
        let apart = step.iter().map(|v| v * v).sum::<f64>().sqrt();
        let (bx, by) = (border.border(x), border.border(y));
        let slack = 2e-6 * (1.0 + f64::from(bx.distance));
        assert!(
            f64::from((bx.distance - by.distance).abs()) <= apart + slack,
            "at {x:?}: {} and {} a step of {apart:e} apart",
            bx.distance,
            by.distance
        );
    }
}

/// A fractal sum of borders is Σ gain^i · border(lacunarity^i · x), its
/// gradient the same sum of normals times lacunarity^i.
#[test]
fn fractal_borders_sum_the_octaves() {
    let config = Config::default();
    let border = SimdBorder::<3>::new(config).unwrap();
    let fractal = Fractal { octaves: 3, lacunarity: 2.0, gain: 0.5 };
    let texture = Texture::<3, 1>::new(config, Combination::Border, fractal, None).unwrap();
    for i in 0..5000 {
        let x = sample_point::<3>(14, i, 30.0);
        let (mut value, mut gradient) = (0f32, [0f32; 3]);
        for o in 0..3 {
            let b = border.border(x.map(|v| v * f64::from(1u32 << o)));
            let amplitude = 0.5f32.powi(o);
            value = if o == 0 { b.distance } else { value + amplitude * b.distance };
            for (g, n) in gradient.iter_mut().zip(b.normal) {
                *g += amplitude * (1u32 << o) as f32 * n;
            }
        }
        assert_eq!(texture.value(x).to_bits(), value.to_bits(), "at {x:?}");
        let (_, g) = texture.gradient(x);
        for a in 0..3 {
            assert!((g[a] - gradient[a]).abs() <= 1e-5, "at {x:?}: gradient {g:?} against {gradient:?}");
        }
    }
}

/// Grids through the tiles (fine steps, eight and sixteen samples a tile,
/// sparse and dense patterns, 2D to 4D) against the one-point call.
fn grid_is_per_sample<const D: usize>(config: Config, grid: Grid<D>) -> usize {
    let border = SimdBorder::<D>::new(config).unwrap();
    let kernel = worley::Simd::<D, 1>::new(Config { order: 1, ..config }, worley::Outputs::IdsAndDeltas).unwrap();
    assert!(kernel.coherent_grid(&grid), "{grid:?} takes the tiles");
    let n = grid.len().unwrap();
    let mut out = vec![Border32::default(); n];
    border.border_grid(&grid, &mut out).unwrap();
    let mut parallel = vec![Border32::default(); n];
    border.border_grid_parallel(&grid, &mut parallel).unwrap();
    for (i, (b, p)) in out.iter().zip(&parallel).enumerate() {
        let one = border.border(grid.point(i));
        let what = format!("{D}D {config:?} {grid:?} sample {i}");
        assert_same(b, &one, &what);
        assert_same(p, &one, &what);
    }
    n
}

#[test]
fn grid_tiles_give_the_per_sample_border_bits() {
    let mut n = 0;
    for (seed, density) in [(1, 5.0), (2, 0.5), (3, 32.0), (4, 1.5)] {
        let config = Config { seed, density, ..Config::default() };
        // Steps of a hundredth of a cell to an eighth (a tile of sixteen
        // samples, then of eight, within two cells).
        let cell = |d: usize| {
            1.0 / match d {
                2 => Reference::<2>::new(config).unwrap().pattern().scale(),
                3 => Reference::<3>::new(config).unwrap().pattern().scale(),
                _ => Reference::<4>::new(config).unwrap().pattern().scale(),
            }
        };
        for (i, part) in [97.0, 31.0, 12.0, 8.5].into_iter().enumerate() {
            let origin = -4.0 + 1.7 * i as f64;
            let step = cell(2) / part;
            n += grid_is_per_sample::<2>(
                config,
                Grid { origin: [origin, 3.1], step: [step, step * 1.3], size: [97, 70] },
            );
            let step = cell(3) / part;
            n += grid_is_per_sample::<3>(
                config,
                Grid { origin: [origin, -2.2, 0.4], step: [step, step, 0.31], size: [83, 40, 3] },
            );
            let step = cell(4) / part;
            n += grid_is_per_sample::<4>(
                config,
                Grid { origin: [0.3, origin, 1.0, -7.0], step: [step, step * 0.7, 0.2, 0.5], size: [40, 20, 2, 2] },
            );
        }
        // Lattice values: samples on cell faces and corners.
        let scale = Reference::<3>::new(config).unwrap().pattern().scale();
        let cell = 1.0 / scale;
        n += grid_is_per_sample::<3>(
            config,
            Grid { origin: [-cell, 0.0, 2.0 * cell], step: [cell / 16.0, cell / 8.0, cell], size: [64, 32, 2] },
        );
    }
    println!("{n} grid samples");
}
