//! Textures on the basis: the periodic variant against brute force over
//! periodic images, bit-identity across the wrap, combinations and fractal
//! sums against their definitions, analytic gradients against finite
//! differences, and rejected parameters.

use worley::texture::{bump, Combination, Fractal, Texture, TextureError};
use worley::{Config, Grid, Metric, Outputs, Period, Simd};
use worley_harness::oracle;
use worley_harness::{uniform, Tier};

/// Brute force over the periodic point set ([`oracle::periodic_images`]: enough
/// for the periods used here, at least 3 cells, and F4 is within 2 cells).
/// Sorted (distance in user units, id) pairs of the sample `x` given in
/// cells.
fn periodic_brute_force<const D: usize>(
    kernel: &Simd<D, 4>,
    period: [u32; D],
    x: [f64; D],
    metric: Metric,
) -> Vec<(f64, u32)> {
    let s = kernel.pattern().scale();
    let r: [f64; D] = std::array::from_fn(|a| x[a].rem_euclid(period[a] as f64));
    let mut found: Vec<(f64, u32)> = oracle::periodic_images(kernel.pattern(), period)
        .into_iter()
        .map(|(at, id)| (metric.distance(&(0..D).map(|a| (r[a] - at[a]) / s).collect::<Vec<_>>()), id))
        .collect();
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    found.truncate(5);
    found
}

fn periodic_against_brute_force<const D: usize>(period: [u32; D], metric: Metric, tier: Tier) {
    let config = Config { order: 4, metric, seed: 9, ..Config::default() };
    let kernel = Simd::<D, 4>::new(config, Outputs::Ids).unwrap();
    let p = Period::new(period).unwrap();
    let bound = |f: f64| 4.0 * f32::EPSILON as f64 * (f + 1.0 / kernel.pattern().scale());
    for i in 0..tier.of(400) {
        let x: [f64; D] = std::array::from_fn(|a| (uniform(5, (i * D + a) as u64) - 0.5) * 40.0 * period[a] as f64);
        let got = kernel.evaluate_periodic(x, &p);
        let want = periodic_brute_force(&kernel, period, x, metric);
        for k in 0..4 {
            let err = (got.distance[k] as f64 - want[k].0).abs();
            assert!(
                err <= bound(want[k].0),
                "{D}D {metric:?} x {x:?} F{}: {} vs {}",
                k + 1,
                got.distance[k],
                want[k].0
            );
            // IDs agree unless F_k ties its neighbour within the bound.
            let tie = (k > 0 && want[k].0 - want[k - 1].0 <= 2.0 * bound(want[k].0))
                || want[k + 1].0 - want[k].0 <= 2.0 * bound(want[k].0);
            assert!(tie || got.id[k] == want[k].1, "{D}D x {x:?} F{} id", k + 1);
        }
    }
}

worley_harness::tiered!(
    periodic_kernel_agrees_with_brute_force_over_periodic_images,
    campaign_periodic_kernel_agrees_with_brute_force_over_periodic_images,
    periodic_images
);

fn periodic_images(tier: Tier) {
    periodic_against_brute_force::<2>([3, 5], Metric::Euclidean, tier);
    periodic_against_brute_force::<2>([4, 3], Metric::Manhattan, tier);
    periodic_against_brute_force::<3>([3, 4, 3], Metric::Euclidean, tier);
    periodic_against_brute_force::<3>([3, 3, 5], Metric::Chebyshev, tier);
    periodic_against_brute_force::<4>([3, 3, 3, 4], Metric::Euclidean, tier);
}

#[test]
fn periodic_results_are_bit_identical_across_the_wrap() {
    fn go<const D: usize>(period: [u32; D]) {
        let kernel = Simd::<D, 4>::new(Config { order: 4, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
        let p = Period::new(period).unwrap();
        for i in 0..2000 {
            // Dyadic points, so that x + k·P is exact.
            let x: [f64; D] = std::array::from_fn(|a| {
                ((uniform(7, (i * D + a) as u64) * period[a] as f64) * 1024.0).floor() / 1024.0
            });
            let base = kernel.evaluate_periodic(x, &p);
            let k = (i % 7) as f64 - 3.0;
            let moved: [f64; D] = std::array::from_fn(|a| x[a] + k * period[a] as f64 * ((a + 1) as f64));
            let lanes = kernel.evaluate8_periodic(&[moved; 8], &p);
            let other = worley::simd::lane(&lanes, i % 8);
            assert_eq!(base.distance.map(f32::to_bits), other.distance.map(f32::to_bits), "{x:?} vs {moved:?}");
            assert_eq!(base.id, other.id);
            assert_eq!(base.delta.map(|d| d.map(f32::to_bits)), other.delta.map(|d| d.map(f32::to_bits)));
        }
        // Non-finite coordinates give the invalid result.
        let mut bad = [0.5; D];
        bad[D - 1] = f64::NAN;
        assert!(kernel.evaluate_periodic(bad, &p).distance.iter().all(|v| v.is_nan()));
    }
    go::<2>([7, 1]);
    go::<3>([5, 6, 2]);
    go::<4>([3, 4, 5, 6]);
}

#[test]
fn a_periodic_fractal_tiles_with_integer_lacunarity() {
    let p = Period::new([4, 6, 5]).unwrap();
    for lacunarity in [2.0, 3.0] {
        let t = Texture::<3, 2>::new(
            Config::default(),
            Combination::crackle(),
            Fractal { octaves: 4, lacunarity, gain: 0.5 },
            Some(p),
        )
        .unwrap();
        for i in 0..500 {
            let x: [f64; 3] = std::array::from_fn(|a| (uniform(3, (i * 3 + a) as u64) * 20.0 * 64.0).floor() / 64.0);
            let y = [x[0] + 4.0, x[1] - 12.0, x[2] + 50.0];
            assert_eq!(t.value(x).to_bits(), t.value(y).to_bits(), "lacunarity {lacunarity}: {x:?}");
        }
    }
    // A fractional lacunarity cannot tile.
    let e = Texture::<3, 1>::new(
        Config::default(),
        Combination::f(1),
        Fractal { octaves: 3, lacunarity: 2.5, gain: 0.5 },
        Some(p),
    );
    assert!(matches!(e, Err(TextureError::Lacunarity(_))));
}

#[test]
fn combinations_and_fractal_sums_follow_their_definitions() {
    let config = Config { order: 4, ..Config::default() };
    let kernel = Simd::<3, 4>::new(config, Outputs::Distances).unwrap();
    type Formula = fn(&[f64; 4]) -> f64;
    let combos: [(Combination, Formula); 4] = [
        (Combination::Linear(vec![0.5, -1.0, 0.25, 2.0]), |f| 0.5 * f[0] - f[1] + 0.25 * f[2] + 2.0 * f[3]),
        (Combination::crackle(), |f| f[1] - f[0]),
        (Combination::Product, |f| f[0] * f[1]),
        (Combination::SquareDifference, |f| f[2] * f[2] - f[1] * f[1]),
    ];
    for (combo, formula) in combos {
        let fractal = Fractal { octaves: 3, lacunarity: 2.0, gain: 0.5 };
        let t = Texture::<3, 4>::new(config, combo.clone(), fractal, None).unwrap();
        for i in 0..300 {
            let x: [f64; 3] = std::array::from_fn(|a| (uniform(11, (i * 3 + a) as u64) - 0.5) * 200.0);
            let mut want = 0.0;
            for o in 0..3 {
                let scale = 2f64.powi(o);
                let f = kernel.evaluate(x.map(|v| v * scale)).distance.map(f64::from);
                want += formula(&f) / scale;
            }
            let got = t.value(x) as f64;
            assert!((got - want).abs() <= 1e-5 * (1.0 + want.abs()), "{}: {got} vs {want}", combo.name());
        }
    }
}

/// Central differences of a single-octave texture, where the gradient is
/// smooth: no feature changes rank within ±h on any axis and the sample is
/// away from the metric's kinks (Manhattan axis planes, Chebyshev diagonals).
fn gradients_match_differences<const N: usize>(metric: Metric, combo: Combination, fractal: Fractal) {
    let config = Config { order: N, metric, ..Config::default() };
    let t = Texture::<3, N>::new(config, combo.clone(), fractal, None).unwrap();
    let ids = Simd::<3, N>::new(config, Outputs::IdsAndDeltas).unwrap();
    let h = 1e-3;
    let mut tested = 0;
    for i in 0..600 {
        let x: [f64; 3] = std::array::from_fn(|a| (uniform(13, (i * 3 + a) as u64) - 0.5) * 100.0);
        let (sample, grad) = t.gradient(x);
        // Away from kinks: at every octave, the same features within ±2h.
        let smooth = (0..fractal.octaves).all(|o| {
            let freq = (fractal.lacunarity as f64).powi(o as i32);
            let at = |y: [f64; 3]| ids.evaluate(y.map(|v| v * freq));
            let centre = at(x);
            let kink_free = centre.delta.iter().all(|d| {
                let m: Vec<f32> = d.iter().map(|v| v.abs()).collect();
                let mut sorted = m.clone();
                sorted.sort_by(f32::total_cmp);
                match metric {
                    Metric::Manhattan => m.iter().all(|&v| v as f64 > 4.0 * h * freq),
                    Metric::Chebyshev => (sorted[2] - sorted[1]) as f64 > 4.0 * h * freq,
                    _ => true,
                }
            });
            kink_free
                && (0..3).all(|a| {
                    [-2.0 * h, 2.0 * h].iter().all(|&s| {
                        let mut y = x;
                        y[a] += s;
                        at(y).id == centre.id
                    })
                })
        });
        if !smooth {
            continue;
        }
        tested += 1;
        assert!(sample.defined, "{metric:?} {}: gradient flagged at a smooth point {x:?}", combo.name());
        for a in 0..3 {
            let (mut lo, mut hi) = (x, x);
            lo[a] -= h;
            hi[a] += h;
            let fd = (t.value(hi) as f64 - t.value(lo) as f64) / (2.0 * h);
            let scale = (fractal.lacunarity as f64).powi(fractal.octaves as i32 - 1);
            let tol = 2e-3 * (1.0 + grad[a].abs() as f64) * scale + 1e-3 * scale;
            assert!(
                (fd - grad[a] as f64).abs() <= tol,
                "{metric:?} {} axis {a} at {x:?}: analytic {} vs differences {fd}",
                combo.name(),
                grad[a]
            );
        }
    }
    assert!(tested > 200, "{metric:?} {}: only {tested} smooth samples", combo.name());
}

#[test]
fn analytic_gradients_match_finite_differences() {
    let one = Fractal::default();
    for metric in [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
        gradients_match_differences::<1>(metric, Combination::f(1), one);
        gradients_match_differences::<2>(metric, Combination::crackle(), one);
    }
    gradients_match_differences::<2>(Metric::Euclidean, Combination::Product, one);
    gradients_match_differences::<3>(Metric::Euclidean, Combination::SquareDifference, one);
    gradients_match_differences::<4>(Metric::Euclidean, Combination::Linear(vec![0.3, -1.0, 0.5, 1.5]), one);
    gradients_match_differences::<1>(Metric::Euclidean, Combination::f(1), Fractal::octaves(3));
    gradients_match_differences::<2>(Metric::Manhattan, Combination::crackle(), Fractal::octaves(2));
}

#[test]
fn gradients_are_flagged_where_the_metric_has_none() {
    // Periodic textures are addressed in cells, so a feature point's
    // position is exact in the input and the kinks can be hit exactly.
    let period = Period::new([8, 8]).unwrap();
    let build = |metric| {
        let config = Config { metric, ..Config::default() };
        Texture::<2, 1>::new(config, Combination::f(1), Fractal::default(), Some(period)).unwrap()
    };
    let (euclid, manhattan, chebyshev) = (build(Metric::Euclidean), build(Metric::Manhattan), build(Metric::Chebyshev));
    let point = euclid.kernel().pattern().points([3, 4])[0];
    let at = [3.0 + point.offset()[0], 4.0 + point.offset()[1]];
    // On the feature point: F1 = 0, no gradient for any metric.
    for t in [&euclid, &manhattan, &chebyshev] {
        let (sample, _) = t.gradient(at);
        assert_eq!(sample.value, 0.0);
        assert!(!sample.defined);
    }
    // Manhattan: on the axis line through the point, just beside it.
    let beside = [at[0], at[1] + 1e-3];
    let (sample, grad) = manhattan.gradient(beside);
    assert!(sample.value > 0.0 && sample.value < 0.01 && !sample.defined, "{sample:?} {grad:?}");
    let (sample, _) = euclid.gradient(beside);
    assert!(sample.defined);
    // Chebyshev: on the diagonal through the point.
    let diagonal = [at[0] + 1.0 / 1024.0, at[1] - 1.0 / 1024.0];
    let (sample, _) = chebyshev.gradient(diagonal);
    assert!(sample.value > 0.0 && !sample.defined, "{sample:?}");
    let (sample, _) = chebyshev.gradient([at[0] + 1.0 / 1024.0, at[1] - 1.0 / 2048.0]);
    assert!(sample.defined);
    // Bad input: NaN value, no gradient.
    let (sample, _) = euclid.gradient([f64::NAN, 0.0]);
    assert!(sample.value.is_nan() && !sample.defined);
}

#[test]
fn bump_tilts_the_normal_against_the_gradient() {
    let n = glam::Vec3::Z;
    let b = bump(n, glam::Vec3::new(1.0, 0.0, 5.0), 0.5);
    assert!((b.length() - 1.0).abs() < 1e-6);
    assert!(b.x < 0.0 && b.y == 0.0 && b.z > 0.0);
    // The normal component of the gradient does not tilt anything.
    assert_eq!(bump(n, glam::Vec3::new(0.0, 0.0, 3.0), 1.0), n);
    assert_eq!(bump(n, glam::Vec3::splat(f32::NAN), 1.0), n);
}

#[test]
fn invalid_texture_parameters_are_rejected_with_the_reason() {
    let c = Config::default();
    let f = Fractal::default();
    let cases: Vec<(Result<Texture<3, 2>, TextureError>, &str)> = vec![
        (Texture::new(c, Combination::Linear(vec![1.0, f32::NAN]), f, None), "coefficient of F2 is NaN"),
        (Texture::new(c, Combination::Linear(vec![]), f, None), "at least one coefficient"),
        (Texture::new(c, Combination::SquareDifference, f, None), "use order 3"),
        (Texture::new(c, Combination::Product, Fractal { octaves: 0, ..f }, None), "0 octaves"),
        (Texture::new(c, Combination::Product, Fractal { octaves: 40, ..f }, None), "not resolved in f32"),
        (Texture::new(c, Combination::Product, Fractal { lacunarity: 1.0, ..f }, None), "lacunarity 1"),
        (Texture::new(c, Combination::Product, Fractal { gain: f32::INFINITY, ..f }, None), "gain inf"),
        (Texture::new(Config { density: -1.0, ..c }, Combination::Product, f, None), "density -1"),
        (Texture::new(c, Combination::Smooth(-0.5), f, None), "smoothness -0.5"),
        (Texture::new(Config { metric: Metric::Manhattan, ..c }, Combination::Smooth(0.3), f, None), "Euclidean"),
        (Texture::new(Config { metric: Metric::Chebyshev, ..c }, Combination::NSphere, f, None), "Euclidean"),
    ];
    for (result, words) in cases {
        let e = result.expect_err(words).to_string();
        assert!(e.contains(words), "{e:?} should say {words:?}");
    }
    assert!(Period::new([3, 0, 2]).unwrap_err().to_string().contains("period 0 on axis 1"));
    assert!(Period::<2>::new([1 << 25, 2]).is_err());
    // A period that overflows after the octaves' lacunarity.
    let big = Period::new([1 << 23, 1, 1]).unwrap();
    assert!(Texture::<3, 1>::new(c, Combination::f(1), Fractal::octaves(3), Some(big)).is_err());
}

#[test]
fn tabulated_ranges_match_a_fresh_measurement() {
    // A quarter of the campaign: at a tenth, 5σ would cover every share
    // from 0 to twice the expected one.
    tabulated_ranges(50_000);
}

#[test]
#[ignore = "campaign: cargo test -- --ignored"]
fn campaign_tabulated_ranges_match_a_fresh_measurement() {
    tabulated_ranges(200_000);
}

fn tabulated_ranges(samples: usize) {
    use worley::texture::{default_range, DEFAULT_RANGES, STANDARD};
    // Fresh samples (another seed than `worley ranges` uses): the share below
    // the tabulated 0.1 % quantile and the share above the 99.9 % one are each
    // binomial with p = 0.001, σ = √(p(1 − p)/n) (7.1e-5 at 200,000 samples);
    // allow 5σ.
    fn shares<const D: usize>(c: &Combination, lo: f32, hi: f32, samples: usize) -> (f64, f64) {
        let t = Texture::<D, 4>::new(Config::default(), c.clone(), Fractal::default(), None).unwrap();
        let points: Vec<[f64; D]> = (0..samples).map(|i| worley_harness::sample_point(99, i, 1000.0)).collect();
        let mut v = vec![0f32; samples];
        t.values(&points, &mut v).unwrap();
        let below = v.iter().filter(|&&x| x < lo).count() as f64 / samples as f64;
        let above = v.iter().filter(|&&x| x > hi).count() as f64 / samples as f64;
        (below, above)
    }
    let tolerance = 5.0 * (0.001f64 * 0.999 / samples as f64).sqrt();
    assert_eq!(DEFAULT_RANGES.len(), 3 * STANDARD.len());
    for &(dim, name, lo, hi) in DEFAULT_RANGES {
        let c: Combination = name.parse().unwrap();
        assert_eq!(default_range(dim, &c), Some(worley::texture::Range { lo, hi }));
        let (below, above) = match dim {
            2 => shares::<2>(&c, lo, hi, samples),
            3 => shares::<3>(&c, lo, hi, samples),
            _ => shares::<4>(&c, lo, hi, samples),
        };
        assert!(
            (below - 0.001).abs() <= tolerance && (above - 0.001).abs() <= tolerance,
            "{dim}D {name}: {below} below {lo} and {above} above {hi}, expected 0.001 each within {tolerance}"
        );
    }
    assert_eq!(default_range(3, &Combination::crackle()).map(|r| r.remap(0.0004)), Some(0.0));
    assert!(default_range(3, &Combination::Linear(vec![0.3, 0.7])).is_none());
}

#[test]
fn combinations_parse_from_their_written_form() {
    assert_eq!("F2-F1".parse::<Combination>(), Ok(Combination::crackle()));
    assert_eq!("F1 * F2".parse::<Combination>(), Ok(Combination::Product));
    assert_eq!("F3^2-F2^2".parse::<Combination>(), Ok(Combination::SquareDifference));
    assert_eq!("0.5F1+2*F3-F1".parse::<Combination>(), Ok(Combination::Linear(vec![-0.5, 0.0, 2.0])));
    assert_eq!("smooth:0.25".parse::<Combination>(), Ok(Combination::Smooth(0.25)));
    assert_eq!(Combination::Smooth(0.25).name().parse::<Combination>(), Ok(Combination::Smooth(0.25)));
    assert_eq!(Combination::NSphere.name().parse::<Combination>(), Ok(Combination::NSphere));
    for bad in
        ["", "G1", "F0", "F17", "xF1", "F1+", "2", "smooth:", "smooth:-1", "smooth:inf", "smooth:x", "n-sphere:1"]
    {
        assert!(bad.parse::<Combination>().is_err(), "{bad:?} must be rejected");
    }
}

/// `values_grid` against `value` at every point of `grid`, bit for bit.
fn grid_matches_points<const D: usize, const N: usize>(t: &Texture<D, N>, grid: &Grid<D>) {
    let mut image = vec![0.0; grid.len().unwrap()];
    t.values_grid(grid, &mut image).unwrap();
    for (i, v) in image.iter().enumerate() {
        let want = t.value(grid.point(i));
        assert_eq!(v.to_bits(), want.to_bits(), "sample {i} at {:?}: {v} vs {want}", grid.point(i));
    }
}

#[test]
fn texture_grids_give_each_points_value_on_every_path() {
    let c = Config::default();
    let fbm = Fractal::octaves(4);
    // Lacunarity 2: every octave a grid of its own; the first octaves on
    // the coherent path, the last (a step of 0.9 cells) per sample. More
    // than one band of rows, a width that is no multiple of eight, an
    // origin on a lattice plane and a negative step.
    let t = Texture::<2, 1>::new(c, Combination::f(1), fbm, None).unwrap();
    let grid = Grid { origin: [-3.0, 7.25], step: [0.1125, -0.07], size: [45, 300] };
    let scale = t.kernel().pattern().scale();
    let octave = |f: f64| Grid { origin: grid.origin.map(|o| o * f), step: grid.step.map(|s| s * f), size: grid.size };
    assert!(t.kernel().coherent_grid(&octave(1.0)) && !t.kernel().coherent_grid(&octave(8.0)), "scale {scale}");
    grid_matches_points(&t, &grid);
    // Combinations of several distances, other metrics, 3D and 4D.
    let crackle = Texture::<3, 2>::new(c, Combination::crackle(), Fractal::octaves(3), None).unwrap();
    grid_matches_points(&crackle, &Grid { origin: [0.3, -1.7, 2.5], step: [0.04, 0.05, 0.3], size: [37, 21, 3] });
    // The border, whose octaves take its own grid tiles; smooth F1, eight
    // points at a time.
    let border = Texture::<3, 1>::new(c, Combination::Border, Fractal::octaves(3), None).unwrap();
    grid_matches_points(&border, &Grid { origin: [0.3, -1.7, 2.5], step: [0.04, 0.05, 0.3], size: [37, 21, 3] });
    let smooth = Texture::<3, 1>::new(c, Combination::Smooth(0.3), Fractal::octaves(3), None).unwrap();
    grid_matches_points(&smooth, &Grid { origin: [0.3, -1.7, 2.5], step: [0.04, 0.05, 0.3], size: [37, 21, 3] });
    let spheres = Texture::<3, 1>::new(c, Combination::NSphere, Fractal::octaves(3), None).unwrap();
    grid_matches_points(&spheres, &Grid { origin: [0.3, -1.7, 2.5], step: [0.04, 0.05, 0.3], size: [37, 21, 3] });
    let product = Config { metric: Metric::Manhattan, seed: 4, ..c };
    let t = Texture::<3, 2>::new(product, Combination::Product, Fractal::octaves(2), None).unwrap();
    grid_matches_points(&t, &Grid { origin: [10.0, 0.0, -0.5], step: [0.03, 0.0, 0.2], size: [64, 1, 5] });
    let t = Texture::<4, 1>::new(c, Combination::f(1), Fractal::octaves(2), None).unwrap();
    grid_matches_points(&t, &Grid { origin: [0.5, 0.5, 0.5, 0.5], step: [0.05, 0.1, 0.2, 0.5], size: [17, 5, 3, 2] });
    // A lacunarity that is no power of two, and a periodic texture: eight
    // points at a time, the same values.
    let odd = Fractal { lacunarity: 1.9, ..fbm };
    let t = Texture::<2, 1>::new(c, Combination::f(1), odd, None).unwrap();
    grid_matches_points(&t, &Grid { origin: [0.0, 0.0], step: [0.05, 0.05], size: [30, 20] });
    let t = Texture::<2, 1>::new(c, Combination::f(1), fbm, Some(Period::new([4, 4]).unwrap())).unwrap();
    grid_matches_points(&t, &Grid { origin: [0.0, 0.0], step: [0.05, 0.05], size: [30, 20] });
    // Coordinates near the limits and NaN: the per-point results.
    grid_matches_points(
        &Texture::<2, 1>::new(c, Combination::f(1), fbm, None).unwrap(),
        &Grid { origin: [1e300, f64::NAN], step: [1e299, 0.1], size: [9, 2] },
    );
}

/// Every one-point call against its lane of the eight-lane call, where the
/// other seven lanes hold other points (so the eight-lane kernel runs, while
/// the one-point call runs the one-lane kernel): bit for bit, bad input
/// included.
fn one_point_is_its_lane<const D: usize, const N: usize>(t: &Texture<D, N>, points: &[[f64; D]], width: f32) {
    for (i, x) in points.iter().enumerate() {
        let mut eight: [[f64; D]; 8] = std::array::from_fn(|k| points[(i + 3 * k + 1) % points.len()]);
        let lane = i % 8;
        eight[lane] = *x;
        let what = format!("{} at {x:?}", t.combination().name());
        let bits = |v: f32| v.to_bits();
        assert_eq!(bits(t.value(*x)), bits(t.value8(&eight).to_array()[lane]), "value, {what}");
        let wide = [width; 8];
        assert_eq!(bits(t.filtered(*x, width)), bits(t.filtered8(&eight, wide).to_array()[lane]), "filtered, {what}");
        let (sample, gradient) = t.gradient(*x);
        let g8 = t.gradient8(&eight);
        assert_eq!(bits(sample.value), bits(g8.value.to_array()[lane]), "gradient's value, {what}");
        assert_eq!(sample.defined, g8.defined[lane], "gradient defined, {what}");
        let lanes: [f32; D] = std::array::from_fn(|a| g8.gradient[a].to_array()[lane]);
        assert_eq!(gradient.map(bits), lanes.map(bits), "gradient, {what}");
    }
}

#[test]
fn one_point_calls_give_the_bits_of_their_lane_among_eight() {
    let c = Config { seed: 9, ..Config::default() };
    let mut points: Vec<[f64; 3]> =
        (0..200).map(|i| std::array::from_fn(|a| 40.0 * uniform(5, (3 * i + a) as u64) - 20.0)).collect();
    points.extend([
        [f64::NAN, 0.0, 1.0],
        [f64::INFINITY, 2.0, 0.0],
        [1e300, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [3.0, -2.0, 7.0],
    ]);
    let crackle = Texture::<3, 2>::new(c, Combination::crackle(), Fractal::octaves(4), None).unwrap();
    one_point_is_its_lane(&crackle, &points, 0.0);
    one_point_is_its_lane(&crackle, &points, 0.3);
    let border = Texture::<3, 1>::new(c, Combination::Border, Fractal::octaves(3), None).unwrap();
    one_point_is_its_lane(&border, &points, 0.0);
    let smooth = Texture::<3, 1>::new(c, Combination::Smooth(0.2), Fractal::octaves(3), None).unwrap();
    one_point_is_its_lane(&smooth, &points, 0.0);
    one_point_is_its_lane(&smooth, &points, 0.3);
    let spheres = Texture::<3, 1>::new(c, Combination::NSphere, Fractal::octaves(3), None).unwrap();
    one_point_is_its_lane(&spheres, &points, 0.0);
    one_point_is_its_lane(&spheres, &points, 0.3);
    let manhattan = Config { metric: Metric::Manhattan, ..c };
    let product = Texture::<3, 2>::new(manhattan, Combination::Product, Fractal::octaves(2), None).unwrap();
    one_point_is_its_lane(&product, &points, 0.05);
    // Periodic: addressed in cells, the wrap taken per lane.
    let period = Some(Period::new([4, 5, 3]).unwrap());
    let tiled = Texture::<3, 2>::new(c, Combination::crackle(), Fractal::octaves(3), period).unwrap();
    one_point_is_its_lane(&tiled, &points, 0.0);
    let tiled_border = Texture::<3, 1>::new(c, Combination::Border, Fractal::octaves(2), period).unwrap();
    one_point_is_its_lane(&tiled_border, &points, 0.0);
}

/// The typed evaluators take their order from their type (`N`, 1 for the
/// border), whatever the configuration says: one rule, the same results.
#[test]
fn the_order_is_the_types_whatever_the_configuration_says() {
    let x = [0.25, -1.5, 3.75];
    let base = Config { seed: 3, ..Config::default() };
    let want = Simd::<3, 2>::new(Config { order: 2, ..base }, Outputs::Ids).unwrap().evaluate(x);
    let crackle = Texture::<3, 2>::new(Config { order: 2, ..base }, Combination::crackle(), Fractal::default(), None)
        .unwrap()
        .value(x);
    let border = worley::SimdBorder::<3>::new(base).unwrap().border(x);
    for order in [0, 1, 2, 3, worley::MAX_ORDER, worley::MAX_ORDER + 1, usize::MAX] {
        let config = Config { order, ..base };
        let simd = Simd::<3, 2>::new(config, Outputs::Ids).unwrap();
        assert_eq!(simd.config().order, 2, "Simd given order {order}");
        assert_eq!(simd.evaluate(x), want, "Simd given order {order}");
        let t = Texture::<3, 2>::new(config, Combination::crackle(), Fractal::default(), None).unwrap();
        assert_eq!(t.kernel().config().order, 2, "Texture given order {order}");
        assert_eq!(t.value(x).to_bits(), crackle.to_bits(), "Texture given order {order}");
        let b = worley::SimdBorder::<3>::new(config).unwrap();
        assert_eq!(b.config().order, 1, "SimdBorder given order {order}");
        assert_eq!(b.border(x), border, "SimdBorder given order {order}");
    }
    // An order the type cannot have is the configuration error everywhere.
    assert_eq!(Simd::<3, 0>::new(base, Outputs::Ids).unwrap_err(), worley::ConfigError::Order(0));
    let too_high = Texture::<3, 17>::new(base, Combination::crackle(), Fractal::default(), None);
    assert!(matches!(too_high, Err(TextureError::Config(worley::ConfigError::Order(17)))), "{too_high:?}");
}

#[test]
fn smooth_textures_are_the_fractal_sum_of_simd_smooth_with_its_gradient() {
    let c = Config { seed: 5, ..Config::default() };
    let fractal = Fractal { octaves: 3, lacunarity: 2.0, gain: 0.5 };
    let s = 0.3;
    let t = Texture::<3, 1>::new(c, Combination::Smooth(s), fractal, None).unwrap();
    let tiled =
        Texture::<3, 1>::new(c, Combination::Smooth(s), fractal, Some(Period::new([3, 4, 5]).unwrap())).unwrap();
    let kernel = worley::SimdSmooth::<3>::new(c).unwrap();
    for i in 0..300 {
        // Dyadic, so that moving by whole periods is exact.
        let x: [f64; 3] =
            std::array::from_fn(|a| ((uniform(17, (i * 3 + a) as u64) - 0.5) * 204_800.0).floor() / 1024.0);
        // Octave o at frequency 2^o with amplitude 0.5^o, summed in f32 in
        // octave order; its gradient is frequency · amplitude · ∇S.
        let (mut want, mut want_gradient) = (0f32, [0f32; 3]);
        for o in 0..3 {
            let f = 2f64.powi(o);
            let y = if o == 0 { x } else { x.map(|v| v * f) };
            let v = kernel.smooth(y, s);
            let amplitude = 0.5f32.powi(o);
            want = if o == 0 { v.value } else { want + amplitude * v.value };
            for (g, d) in want_gradient.iter_mut().zip(v.gradient) {
                *g += amplitude * f as f32 * d;
            }
        }
        assert_eq!(t.value(x).to_bits(), want.to_bits(), "at {x:?}");
        // Periodic: octave o in cells, reduced into the base period, with
        // the period times 2^o; the same bits one period away.
        let cells = [3.0, 4.0, 5.0];
        let mut want_tiled = 0f32;
        for o in 0..3 {
            let z: [f64; 3] = std::array::from_fn(|a| x[a].rem_euclid(cells[a]) * 2f64.powi(o));
            let p = Period::new([3, 4, 5].map(|c| c << o)).unwrap();
            let v = kernel.smooth_periodic(z, &p, s).value;
            want_tiled = if o == 0 { v } else { want_tiled + 0.5f32.powi(o) * v };
        }
        assert_eq!(tiled.value(x).to_bits(), want_tiled.to_bits(), "tiled at {x:?}");
        let moved = [x[0] - 3.0 * 5.0, x[1] + 4.0 * 3.0, x[2]];
        assert_eq!(tiled.value(moved).to_bits(), want_tiled.to_bits(), "tiled at {moved:?}");
        let (sample, gradient) = t.gradient(x);
        assert!(sample.defined, "at {x:?}");
        for a in 0..3 {
            assert!((gradient[a] - want_gradient[a]).abs() <= 1e-5 * (1.0 + want_gradient[a].abs()), "at {x:?}");
            // Smooth everywhere: central differences agree at every sample.
            let h = 2e-4;
            let (mut lo, mut hi) = (x, x);
            lo[a] -= h;
            hi[a] += h;
            let fd = (f64::from(t.value(hi)) - f64::from(t.value(lo))) / (2.0 * h);
            // The f32 values' rounding over 2h (3e-4 here) and the O(h²)
            // term, whose third derivatives reach a few hundred where the
            // last octave's s is 0.075 in x (5e-3 was seen at h = 1e-3); a
            // wrong chain factor or weight is off by 0.1 or more.
            let tol = 2e-3;
            assert!((fd - f64::from(gradient[a])).abs() <= tol, "axis {a} at {x:?}: {} vs {fd}", gradient[a]);
        }
    }
}

/// The n-sphere texture is the fractal sum of `SimdNSphere`'s radii, with
/// a zero gradient; periodic, the sum of the periodic radii, repeating
/// bit for bit one period away.
#[test]
fn n_sphere_textures_are_the_fractal_sum_of_simd_n_sphere() {
    let c = Config { seed: 6, ..Config::default() };
    let fractal = Fractal { octaves: 3, lacunarity: 2.0, gain: 0.5 };
    let kernel = worley::SimdNSphere::<3>::new(c).unwrap();
    let t = Texture::<3, 1>::new(c, Combination::NSphere, fractal, None).unwrap();
    let period = Period::new([3, 4, 5]).unwrap();
    let tiled = Texture::<3, 1>::new(c, Combination::NSphere, fractal, Some(period)).unwrap();
    for i in 0..300 {
        // Dyadic, so that moving by whole periods is exact.
        let x: [f64; 3] =
            std::array::from_fn(|a| ((uniform(19, (i * 3 + a) as u64) - 0.5) * 204_800.0).floor() / 1024.0);
        // Octave o at frequency 2^o with amplitude 0.5^o, summed in f32 in
        // octave order; periodic octaves in cells, reduced into the base
        // period first, with the period times 2^o.
        let (mut want, mut want_tiled) = (0f32, 0f32);
        for o in 0..3 {
            let f = 2f64.powi(o);
            let y = if o == 0 { x } else { x.map(|v| v * f) };
            let cells = [3.0, 4.0, 5.0];
            let z: [f64; 3] = std::array::from_fn(|a| x[a].rem_euclid(cells[a]) * f);
            let p = Period::new([3, 4, 5].map(|c| c * (1 << o))).unwrap();
            let (v, w) = (kernel.n_sphere(y).radius, kernel.n_sphere_periodic(z, &p).radius);
            let amplitude = 0.5f32.powi(o);
            want = if o == 0 { v } else { want + amplitude * v };
            want_tiled = if o == 0 { w } else { want_tiled + amplitude * w };
        }
        assert_eq!(t.value(x).to_bits(), want.to_bits(), "at {x:?}");
        assert!(want > 0.0 && want_tiled > 0.0, "at {x:?}");
        let (sample, gradient) = t.gradient(x);
        assert_eq!((sample.value.to_bits(), gradient), (want.to_bits(), [0.0; 3]), "at {x:?}");
        assert_eq!(tiled.value(x).to_bits(), want_tiled.to_bits(), "tiled at {x:?}");
        let moved = [x[0] + 3.0 * 7.0, x[1] - 4.0, x[2] + 5.0 * 2.0];
        assert_eq!(tiled.value(moved).to_bits(), want_tiled.to_bits(), "tiled at {moved:?}");
    }
    assert!(t.value([f64::NAN, 0.0, 0.0]).is_nan() && tiled.value([0.0, f64::INFINITY, 0.0]).is_nan());
}
