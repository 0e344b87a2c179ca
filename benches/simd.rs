//! The 8-lane kernel against the f64 reference on the same points: 3D F1, F2
//! and F4 on 4096 seeded random points in [−1000, 1000]^3 and on a 64×64
//! grid slice. Build flags decide the SIMD path (see the README).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use worley::harness::sample_point;
use worley::{Config, Features32, Outputs, Reference, Simd};

const POINTS: usize = 4096;

fn order<const N: usize>(c: &mut Criterion, random: &[[f64; 3]], grid: &[[f64; 3]]) {
    let mut group = c.benchmark_group(format!("simd-vs-reference/3d/F{N}"));
    group.throughput(Throughput::Elements(POINTS as u64));
    let config = Config { order: N, ..Config::default() };
    let simd = Simd::<3, N>::new(config, Outputs::Distances).unwrap();
    let reference = Reference::<3>::new(config).unwrap();
    let mut out = vec![Features32::<3, N> { distance: [0.0; N], delta: [[0.0; 3]; N], id: [0; N] }; POINTS];
    for (name, points) in [("random", random), ("grid", grid)] {
        group.bench_function(BenchmarkId::new("simd", name), |b| {
            b.iter(|| simd.evaluate_slice(black_box(points), &mut out).unwrap());
        });
        group.bench_function(BenchmarkId::new("reference", name), |b| {
            b.iter(|| {
                let mut sum = 0.0;
                for x in black_box(points) {
                    sum += reference.evaluate(*x).distance[N - 1];
                }
                sum
            });
        });
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    println!("SIMD level compiled in: {}", worley::simd_level());
    let random: Vec<[f64; 3]> = (0..POINTS).map(|i| sample_point(7, i, 1000.0)).collect();
    let grid: Vec<[f64; 3]> = (0..POINTS).map(|i| [(i % 64) as f64 * 0.05, (i / 64) as f64 * 0.05, 0.5]).collect();
    order::<1>(c, &random, &grid);
    order::<2>(c, &random, &grid);
    order::<4>(c, &random, &grid);
}

criterion_group!(simd, benches);
criterion_main!(simd);
