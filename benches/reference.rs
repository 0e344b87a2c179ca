//! Throughput of the f64 reference kernel: F1, F2 and F4 in 2D, 3D and 4D on
//! 4096 seeded random points in [−1000, 1000]^d, and on a 64×64 grid slice;
//! and the distance to the cell's border, smooth F1 (s = 0.1 and 0.3) and
//! the n-sphere radius on the same points, to set beside F2 (which F2 − F1
//! needs).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use worley::{Config, Features, Reference};
use worley_harness::sample_point;

const POINTS: usize = 4096;

fn bench_dim<const D: usize>(c: &mut Criterion) {
    let mut group = c.benchmark_group(format!("reference/{D}d"));
    group.throughput(Throughput::Elements(POINTS as u64));
    let random: Vec<[f64; D]> = (0..POINTS).map(|i| sample_point(7, i, 1000.0)).collect();
    let grid: Vec<[f64; D]> = (0..POINTS)
        .map(|i| {
            std::array::from_fn(|a| match a {
                0 => (i % 64) as f64 * 0.05,
                1 => (i / 64) as f64 * 0.05,
                _ => 0.5,
            })
        })
        .collect();
    for order in [1, 2, 4] {
        let basis = Reference::<D>::new(Config { order, ..Config::default() }).unwrap();
        let mut out = vec![Features::<D>::empty(order); POINTS];
        for (name, points) in [("random", &random), ("grid", &grid)] {
            group.bench_function(BenchmarkId::new(name, format!("F{order}")), |b| {
                b.iter(|| {
                    for (x, o) in black_box(points).iter().zip(out.iter_mut()) {
                        *o = basis.evaluate(*x);
                    }
                    black_box(&out);
                })
            });
        }
    }
    let basis = Reference::<D>::new(Config::default()).unwrap();
    let mut values = vec![0.0f64; POINTS];
    type Output<'a, const D: usize> = (&'a str, Box<dyn Fn([f64; D]) -> f64 + 'a>);
    let outputs: [Output<'_, D>; 4] = [
        ("border", Box::new(|x| basis.border(x).map_or(f64::NAN, |b| b.distance))),
        ("smooth F1 s=0.1", Box::new(|x| basis.smooth_f1(x, 0.1).value)),
        ("smooth F1 s=0.3", Box::new(|x| basis.smooth_f1(x, 0.3).value)),
        ("n-sphere radius", Box::new(|x| basis.n_sphere(x).radius)),
    ];
    for (output, f) in &outputs {
        for (name, points) in [("random", &random), ("grid", &grid)] {
            group.bench_function(BenchmarkId::new(name, output), |b| {
                b.iter(|| {
                    for (x, o) in black_box(points).iter().zip(values.iter_mut()) {
                        *o = f(*x);
                    }
                    black_box(&values);
                })
            });
        }
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    bench_dim::<2>(c);
    bench_dim::<3>(c);
    bench_dim::<4>(c);
}

criterion_group!(reference, benches);
criterion_main!(reference);
