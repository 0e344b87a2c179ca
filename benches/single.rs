//! One point at a time against a slice, per point, and against the f64
//! reference: what a renderer that shades one hit at a time pays. A plain
//! program that prints one table (run `cargo bench --bench single`).
//!
//! 3D, the default configuration (λ 5, Euclidean, exact), 20 000 seeded
//! random points in [−1000, 1000]³, one thread. The cases run round-robin,
//! nine rounds; each figure is the median round, in millions of points per
//! second. The n-sphere radius is `SimdNSphere` against
//! `Reference::n_sphere`; compact smooth F1 (s = 0.1 and 0.3 user units)
//! is `SimdSmooth` against `Reference::smooth_f1_compact`. The texture is F2 − F1 summed over five octaves; its f64
//! reference is the same sum of `Reference` evaluations.

use std::hint::black_box;
use std::time::Instant;
use worley::texture::{Combination, Fractal, Texture};
use worley::{
    Border32, Config, Features32, NSphere32, Outputs, Reference, Simd, SimdBorder, SimdNSphere, SimdSmooth, Smooth32,
};
use worley_harness::sample_point;

const POINTS: usize = 20_000;
const ROUNDS: usize = 9;

type Case<'a> = (&'static str, &'static str, Box<dyn FnMut(&[[f64; 3]]) -> f64 + 'a>);

fn main() {
    let points: Vec<[f64; 3]> = (0..POINTS).map(|i| sample_point(11, i, 1000.0)).collect();
    let c2 = Config { order: 2, ..Config::default() };
    let f1 = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    let f2 = Simd::<3, 2>::new(c2, Outputs::Distances).unwrap();
    let border = SimdBorder::<3>::new(Config::default()).unwrap();
    let spheres = SimdNSphere::<3>::new(Config::default()).unwrap();
    let smooth = SimdSmooth::<3>::new(Config::default()).unwrap();
    let texture = Texture::<3, 2>::new(c2, Combination::crackle(), Fractal::octaves(5), None).unwrap();
    let reference1 = Reference::<3>::new(Config::default()).unwrap();
    let reference2 = Reference::<3>::new(c2).unwrap();
    let fractal = Fractal::octaves(5);
    let (mut o1, mut o2) = (vec![Features32::<3, 1>::default(); POINTS], vec![Features32::<3, 2>::default(); POINTS]);
    let mut ob = vec![Border32::<3>::default(); POINTS];
    let mut on = vec![NSphere32::INVALID; POINTS];
    let (mut os1, mut os3) = (vec![Smooth32::INVALID; POINTS], vec![Smooth32::INVALID; POINTS]);
    let mut ov = vec![0f32; POINTS];
    let crackle = |f: &worley::Features<3>| f.distances()[1] - f.distances()[0];
    let mut cases: Vec<Case> = vec![
        ("F1", "one point", Box::new(|p| p.iter().map(|&x| f64::from(f1.evaluate(x).distance[0])).sum())),
        (
            "F1",
            "slice",
            Box::new(|p| {
                f1.evaluate_slice(p, &mut o1).unwrap();
                o1.iter().map(|f| f64::from(f.distance[0])).sum()
            }),
        ),
        ("F1", "f64 reference", Box::new(|p| p.iter().map(|&x| reference1.evaluate(x).distances()[0]).sum())),
        (
            "F2-F1",
            "one point",
            Box::new(|p| p.iter().map(|&x| f2.evaluate(x).distance).map(|d| f64::from(d[1] - d[0])).sum()),
        ),
        (
            "F2-F1",
            "slice",
            Box::new(|p| {
                f2.evaluate_slice(p, &mut o2).unwrap();
                o2.iter().map(|f| f64::from(f.distance[1] - f.distance[0])).sum()
            }),
        ),
        ("F2-F1", "f64 reference", Box::new(|p| p.iter().map(|&x| crackle(&reference2.evaluate(x))).sum())),
        ("border", "one point", Box::new(|p| p.iter().map(|&x| f64::from(border.border(x).distance)).sum())),
        (
            "border",
            "slice",
            Box::new(|p| {
                border.border_slice(p, &mut ob).unwrap();
                ob.iter().map(|b| f64::from(b.distance)).sum()
            }),
        ),
        ("border", "f64 reference", Box::new(|p| p.iter().map(|&x| reference1.border(x).unwrap().distance).sum())),
        ("n-sphere", "one point", Box::new(|p| p.iter().map(|&x| f64::from(spheres.n_sphere(x).radius)).sum())),
        (
            "n-sphere",
            "slice",
            Box::new(|p| {
                spheres.n_sphere_slice(p, &mut on).unwrap();
                on.iter().map(|n| f64::from(n.radius)).sum()
            }),
        ),
        ("n-sphere", "f64 reference", Box::new(|p| p.iter().map(|&x| reference1.n_sphere(x).radius).sum())),
        (
            "smooth F1, s 0.1",
            "one point",
            Box::new(|p| p.iter().map(|&x| f64::from(smooth.smooth(x, 0.1).value)).sum()),
        ),
        (
            "smooth F1, s 0.1",
            "slice",
            Box::new(|p| {
                smooth.smooth_slice(p, 0.1, &mut os1).unwrap();
                os1.iter().map(|v| f64::from(v.value)).sum()
            }),
        ),
        (
            "smooth F1, s 0.1",
            "f64 reference",
            Box::new(|p| p.iter().map(|&x| reference1.smooth_f1_compact(x, 0.1).value).sum()),
        ),
        (
            "smooth F1, s 0.3",
            "one point",
            Box::new(|p| p.iter().map(|&x| f64::from(smooth.smooth(x, 0.3).value)).sum()),
        ),
        (
            "smooth F1, s 0.3",
            "slice",
            Box::new(|p| {
                smooth.smooth_slice(p, 0.3, &mut os3).unwrap();
                os3.iter().map(|v| f64::from(v.value)).sum()
            }),
        ),
        (
            "smooth F1, s 0.3",
            "f64 reference",
            Box::new(|p| p.iter().map(|&x| reference1.smooth_f1_compact(x, 0.3).value).sum()),
        ),
        ("texture", "one point", Box::new(|p| p.iter().map(|&x| f64::from(texture.value(x))).sum())),
        (
            "texture",
            "slice",
            Box::new(|p| {
                texture.values(p, &mut ov).unwrap();
                ov.iter().map(|&v| f64::from(v)).sum()
            }),
        ),
        (
            "texture",
            "f64 reference",
            Box::new(|p| {
                p.iter()
                    .map(|&x| {
                        let (mut sum, mut frequency, mut amplitude) = (0.0, 1.0, 1.0);
                        for _ in 0..fractal.octaves {
                            sum += amplitude * crackle(&reference2.evaluate(x.map(|v| v * frequency)));
                            frequency *= f64::from(fractal.lacunarity);
                            amplitude *= f64::from(fractal.gain);
                        }
                        sum
                    })
                    .sum()
            }),
        ),
    ];
    let mut rates = vec![Vec::new(); cases.len()];
    for _ in 0..ROUNDS {
        for (case, rate) in cases.iter_mut().zip(&mut rates) {
            let start = Instant::now();
            black_box((case.2)(black_box(&points)));
            rate.push(POINTS as f64 / start.elapsed().as_secs_f64() / 1e6);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let medians: Vec<f64> = rates.iter_mut().map(median).collect();
    println!("simd level: {}", worley::simd_level());
    println!("| output | one point | slice, per point | f64 reference | one / slice | one / reference |");
    println!("|---|---|---|---|---|---|");
    for (i, chunk) in cases.chunks(3).enumerate() {
        let [one, slice, reference] = [medians[3 * i], medians[3 * i + 1], medians[3 * i + 2]];
        println!(
            "| {} | {one:.2} | {slice:.2} | {reference:.2} | {:.2} | {:.2} |",
            chunk[0].0,
            one / slice,
            one / reference
        );
    }
}
