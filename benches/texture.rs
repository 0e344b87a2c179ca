//! Textures against the plain basis on the same 4096 random points in
//! [−1000, 1000]^3: F1 alone, F2 − F1 and F1·F2, fractal sums of 2 and 4
//! octaves, and analytic gradients; and the paper's claim that F1 and F2
//! together cost about as much as one scale of Perlin noise (improved
//! noise, 8 lanes). And texture grids: whole grids against the same values
//! eight points at a time. And footprints: the same fractal sum filtered
//! over widths from zero to many cells across, where the cost per sample falls as
//! octaves drop below the footprint.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;
use worley::perlin::Perlin;
use worley::texture::{Combination, Fractal, Texture};
use worley::{Config, Features32, Grid, Outputs, Simd};
use worley_harness::sample_point;

const POINTS: usize = 4096;

fn points() -> Vec<[f64; 3]> {
    (0..POINTS).map(|i| sample_point(7, i, 1000.0)).collect()
}

fn textures(c: &mut Criterion) {
    let mut group = c.benchmark_group("texture/3d");
    group.throughput(Throughput::Elements(POINTS as u64));
    group.sample_size(20).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    let xs = points();
    let mut out = vec![0f32; POINTS];
    let config = Config::default();
    let one = Fractal::default();
    type Run = Box<dyn Fn(&[[f64; 3]], &mut [f32])>;
    let cases: Vec<(&str, Run)> = vec![
        ("F1", {
            let t = Texture::<3, 1>::new(config, Combination::f(1), one, None).unwrap();
            Box::new(move |x, o| t.values(x, o).unwrap())
        }),
        ("F2-F1", {
            let t = Texture::<3, 2>::new(config, Combination::crackle(), one, None).unwrap();
            Box::new(move |x, o| t.values(x, o).unwrap())
        }),
        ("F1*F2", {
            let t = Texture::<3, 2>::new(config, Combination::Product, one, None).unwrap();
            Box::new(move |x, o| t.values(x, o).unwrap())
        }),
        ("G1-2-octaves", {
            let t = Texture::<3, 1>::new(config, Combination::f(1), Fractal::octaves(2), None).unwrap();
            Box::new(move |x, o| t.values(x, o).unwrap())
        }),
        ("G1-4-octaves", {
            let t = Texture::<3, 1>::new(config, Combination::f(1), Fractal::octaves(4), None).unwrap();
            Box::new(move |x, o| t.values(x, o).unwrap())
        }),
        ("F1-gradient", {
            let t = Texture::<3, 1>::new(config, Combination::f(1), one, None).unwrap();
            Box::new(move |x, o| {
                for (chunk, dst) in x.chunks_exact(8).zip(o.chunks_exact_mut(8)) {
                    let g = t.gradient8(chunk.try_into().unwrap());
                    dst.copy_from_slice(&(g.value + g.gradient[0]).to_array());
                }
            })
        }),
    ];
    for (name, run) in &cases {
        group.bench_function(BenchmarkId::new("values", name), |b| b.iter(|| run(black_box(&xs), &mut out)));
    }
    group.finish();
}

/// A texture over a 256 × 256 slice of a 3D grid (a sixteenth of a unit
/// apart): [`Texture::values_grid`] against the same values eight points at
/// a time through [`Texture::value8`], the same bits. Both run on all cores
/// with the `parallel` feature; `RAYON_NUM_THREADS=1` measures one core.
fn texture_grids(c: &mut Criterion) {
    let mut group = c.benchmark_group("texture-grid/3d");
    let grid = Grid { origin: [0.3, -0.7, 0.5], step: [0.0625, 0.0625, 1.0], size: [256, 256, 1] };
    group.throughput(Throughput::Elements(grid.len().unwrap() as u64));
    group.sample_size(20).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    let mut out = vec![0f32; grid.len().unwrap()];
    let config = Config::default();
    type Run = Box<dyn Fn(&Grid<3>, &mut [f32], bool)>;
    fn both<const N: usize>(t: Texture<3, N>) -> Run {
        Box::new(move |g, o, whole| {
            if whole {
                t.values_grid(g, o).unwrap()
            } else {
                g.fill_by_eights(o, |x| t.value8(x).to_array()).unwrap()
            }
        })
    }
    let cases: Vec<(&str, Run)> = vec![
        ("F1", both(Texture::<3, 1>::new(config, Combination::f(1), Fractal::default(), None).unwrap())),
        ("F2-F1", both(Texture::<3, 2>::new(config, Combination::crackle(), Fractal::default(), None).unwrap())),
        ("G1-4-octaves", both(Texture::<3, 1>::new(config, Combination::f(1), Fractal::octaves(4), None).unwrap())),
    ];
    for (name, run) in &cases {
        for (path, whole) in [("by-eights", false), ("values_grid", true)] {
            group.bench_function(BenchmarkId::new(path, name), |b| b.iter(|| run(black_box(&grid), &mut out, whole)));
        }
    }
    group.finish();
}

/// F1 and F2 together (distances only) against one octave of Perlin noise,
/// both eight lanes per call.
fn perlin_ratio(c: &mut Criterion) {
    let mut group = c.benchmark_group("f1f2-vs-perlin/3d");
    group.throughput(Throughput::Elements(POINTS as u64));
    group.sample_size(20).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    let xs = points();
    let kernel = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Distances).unwrap();
    let mut features = vec![Features32::<3, 2> { distance: [0.0; 2], delta: [[0.0; 3]; 2], id: [0; 2] }; POINTS];
    group.bench_function("F1+F2", |b| b.iter(|| kernel.evaluate_slice(black_box(&xs), &mut features).unwrap()));
    let noise = Perlin::new(0);
    let mut out = vec![0f32; POINTS];
    group.bench_function("perlin", |b| {
        b.iter(|| {
            for (chunk, dst) in black_box(&xs).chunks_exact(8).zip(out.chunks_exact_mut(8)) {
                dst.copy_from_slice(&noise.noise8(chunk.try_into().unwrap()).to_array());
            }
        })
    });
    group.finish();
}

/// A four-octave fractal F1 and a one-octave F2 − F1 on the same points,
/// every sample with the same footprint width: zero (today's values, through
/// the filtered entry point) and widths from a sixteenth of a unit to
/// sixteen units (the mean F1 is one unit). Octaves finer than the footprint are replaced by their
/// mean, so the cost falls with the width.
fn footprints(c: &mut Criterion) {
    let mut group = c.benchmark_group("texture-filtered/3d");
    group.throughput(Throughput::Elements(POINTS as u64));
    group.sample_size(20).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    let xs = points();
    let mut out = vec![0f32; POINTS];
    let config = Config::default();
    let fractal = Texture::<3, 1>::new(config, Combination::f(1), Fractal::octaves(4), None).unwrap();
    let crackle = Texture::<3, 2>::new(config, Combination::crackle(), Fractal::default(), None).unwrap();
    // Measured once, outside the timing.
    let _ = (fractal.blend_curve(), crackle.blend_curve());
    for width in [0.0f32, 0.0625, 0.25, 1.0, 4.0, 16.0] {
        let widths = vec![width; POINTS];
        group.bench_function(BenchmarkId::new("G1-4-octaves", width), |b| {
            b.iter(|| fractal.filtered_values(black_box(&xs), Some(&widths), &mut out).unwrap())
        });
        group.bench_function(BenchmarkId::new("F2-F1", width), |b| {
            b.iter(|| crackle.filtered_values(black_box(&xs), Some(&widths), &mut out).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, textures, texture_grids, perlin_ratio, footprints);
criterion_main!(benches);
