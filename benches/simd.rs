//! The 8-lane kernel against the f64 reference on the same points: orders
//! 1, 2 and 4 in 2D, 3D and 4D (Euclidean), every metric in 3D at order 2,
//! on 4096 seeded random points in [−1000, 1000]^d and on a 64 × 64 grid
//! slice with step 0.125. Build flags decide the SIMD path (see the README).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;
use worley::{Config, Features32, Metric, Outputs, Reference, Simd};
use worley_harness::sample_point;

const POINTS: usize = 4096;

fn pair<const D: usize, const N: usize>(c: &mut Criterion, metric: Metric) {
    let name = if metric == Metric::Euclidean { format!("{D}d/F{N}") } else { format!("{D}d/F{N}/{}", metric.name()) };
    let mut group = c.benchmark_group(format!("simd-vs-reference/{name}"));
    group.throughput(Throughput::Elements(POINTS as u64));
    group.sample_size(20).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    let config = Config { order: N, metric, ..Config::default() };
    let simd = Simd::<D, N>::new(config, Outputs::Distances).unwrap();
    let reference = Reference::<D>::new(config).unwrap();
    let random: Vec<[f64; D]> = (0..POINTS).map(|i| sample_point(7, i, 1000.0)).collect();
    let grid: Vec<[f64; D]> = (0..POINTS)
        .map(|i| std::array::from_fn(|a| if a < 2 { ((i >> (6 * a)) % 64) as f64 * 0.125 } else { 0.5 }))
        .collect();
    let mut out = vec![Features32::<D, N> { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; POINTS];
    for (kind, points) in [("random", &random), ("grid", &grid)] {
        group.bench_function(BenchmarkId::new("simd", kind), |b| {
            b.iter(|| simd.evaluate_slice(black_box(points), &mut out).unwrap());
        });
        group.bench_function(BenchmarkId::new("reference", kind), |b| {
            b.iter(|| black_box(points).iter().map(|x| reference.evaluate(*x).distance[N - 1]).sum::<f64>());
        });
    }
    group.finish();
}

/// The rayon batch against the serial one: a 512 × 512 grid, 3D F1.
fn parallel(c: &mut Criterion) {
    use worley::Grid;
    let mut group = c.benchmark_group("parallel/3d/F1/grid-512x512");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    let simd = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    let grid = Grid { origin: [0.0, 0.0, 0.5], step: [0.125, 0.125, 1.0], size: [512, 512, 1] };
    let n = grid.len().unwrap();
    group.throughput(Throughput::Elements(n as u64));
    let mut out = vec![Features32::<3, 1> { distance: [0.0], delta: [[0.0; 3]], id: [0] }; n];
    group.bench_function(BenchmarkId::new("serial", rayon::current_num_threads()), |b| {
        b.iter(|| simd.evaluate_grid(black_box(&grid), &mut out).unwrap());
    });
    group.bench_function(BenchmarkId::new("rayon", rayon::current_num_threads()), |b| {
        b.iter(|| simd.evaluate_grid_parallel(black_box(&grid), &mut out).unwrap());
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    parallel(c);
    println!("SIMD level: {}", worley::simd_level());
    pair::<2, 1>(c, Metric::Euclidean);
    pair::<2, 2>(c, Metric::Euclidean);
    pair::<2, 4>(c, Metric::Euclidean);
    pair::<3, 1>(c, Metric::Euclidean);
    pair::<3, 2>(c, Metric::Euclidean);
    pair::<3, 4>(c, Metric::Euclidean);
    pair::<4, 1>(c, Metric::Euclidean);
    pair::<4, 2>(c, Metric::Euclidean);
    pair::<4, 4>(c, Metric::Euclidean);
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
        pair::<3, 2>(c, metric);
    }
}

criterion_group!(simd, benches);
criterion_main!(simd);
