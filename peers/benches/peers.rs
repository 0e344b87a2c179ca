//! The 8-lane kernel beside the peers, 3D, one thread, the same sample
//! positions for everybody:
//! - `random`: 2^18 seeded points in [−1000, 1000]^3;
//! - `grid`: a 256 × 256 slice (step 0.125, z = 0.5).
//!
//! What each one computes (none of the peers is the same function):
//! - `worley` F1 / F1F2: Poisson process, λ 5 per cell (the default), exact (certified
//!   search), isotropic; mean F1 = 1 user unit (one point per 1.8 units³^⅓).
//! - quick-noise `Cellular` (batch, one octave): one jittered point per cell
//!   on a 3^3 window; its own output scale.
//! - simdnoise `cellular_3d` / `cellular2_3d`: one jittered point per cell
//!   (jitter 0.25), 3^3 window, F1 squared / F2−F1 style outputs; grid only,
//!   since its per-point entry is an `unsafe` intrinsic API.
//! - fastnoise-lite `Cellular`: one jittered point per cell, scalar.
//! - noise (noise-rs) `Worley`: f64, one point per cell from a fixed table.
//!
//! Peers get frequency 0.55 (cell side ≈ 1.8 units, the same feature
//! density as ours); simdnoise's grid, which steps by 1 per sample, gets
//! 0.55 · 0.125. Build flags decide everybody's SIMD path; quick-noise and
//! simdnoise also detect at run time.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use worley_harness::sample_point;
use worley::{Config, Features32, Outputs, Simd};

const RANDOM: usize = 1 << 18;
const SIDE: usize = 256;
const STEP: f64 = 0.125;
const FREQUENCY: f32 = 0.55;

fn points() -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let random = (0..RANDOM).map(|i| sample_point::<3>(11, i, 1000.0).map(|v| v as f32)).collect();
    let grid =
        (0..SIDE * SIDE).map(|i| [(i % SIDE) as f32 * STEP as f32, (i / SIDE) as f32 * STEP as f32, 0.5]).collect();
    (random, grid)
}

fn ours<const N: usize>(c: &mut Criterion, random: &[[f32; 3]], grid: &[[f32; 3]]) {
    let mut group = c.benchmark_group(format!("peers/3d/F{N}"));
    group.sample_size(10);
    let simd = Simd::<3, N>::new(Config { order: N, ..Config::default() }, Outputs::Distances).unwrap();
    for (name, pts) in [("random", random), ("grid", grid)] {
        group.throughput(Throughput::Elements(pts.len() as u64));
        let mut out = vec![Features32::<3, N> { distance: [0.0; N], delta: [[0.0; 3]; N], id: [0; N] }; pts.len()];
        group.bench_function(BenchmarkId::new("worley", name), |b| {
            b.iter(|| simd.evaluate_slice(black_box(pts), &mut out).unwrap());
        });
    }
    group.finish();
}

fn peers(c: &mut Criterion, random: &[[f32; 3]], grid: &[[f32; 3]]) {
    use quick_noise::simd::SimdSliceIterExt;
    let mut group = c.benchmark_group("peers/3d/F1");
    group.sample_size(10);
    for (name, pts) in [("random", random), ("grid", grid)] {
        group.throughput(Throughput::Elements(pts.len() as u64));
        let xs: Vec<f32> = pts.iter().map(|p| p[0]).collect();
        let ys: Vec<f32> = pts.iter().map(|p| p[1]).collect();
        let zs: Vec<f32> = pts.iter().map(|p| p[2]).collect();
        let mut out = vec![0.0f32; pts.len()];
        group.bench_function(BenchmarkId::new("quick-noise", name), |b| {
            b.iter(|| {
                quick_noise::BatchNoise::<3, quick_noise::Fbm, quick_noise::Cellular>::builder(
                    xs.simd_iter_static(),
                    ys.simd_iter_static(),
                    zs.simd_iter_static(),
                )
                .octaves(1)
                .frequency(FREQUENCY)
                .fill(black_box(out.as_mut_slice()))
            });
        });
        let mut lite = fastnoise_lite::FastNoiseLite::new();
        lite.set_noise_type(Some(fastnoise_lite::NoiseType::Cellular));
        lite.set_frequency(Some(FREQUENCY));
        group.bench_function(BenchmarkId::new("fastnoise-lite", name), |b| {
            b.iter(|| black_box(pts).iter().map(|p| lite.get_noise_3d(p[0], p[1], p[2])).sum::<f32>());
        });
        use noise::NoiseFn;
        let worley = noise::Worley::new(7).set_frequency(FREQUENCY as f64);
        group.bench_function(BenchmarkId::new("noise-rs", name), |b| {
            b.iter(|| black_box(pts).iter().map(|p| worley.get([p[0] as f64, p[1] as f64, p[2] as f64])).sum::<f64>());
        });
    }
    group.throughput(Throughput::Elements((SIDE * SIDE) as u64));
    let freq = FREQUENCY * STEP as f32;
    group.bench_function(BenchmarkId::new("simdnoise", "grid"), |b| {
        b.iter(|| simdnoise::NoiseBuilder::cellular_3d(SIDE, SIDE, 1).with_freq(freq).generate());
    });
    group.finish();
    let mut group = c.benchmark_group("peers/3d/F2");
    group.sample_size(10);
    group.throughput(Throughput::Elements((SIDE * SIDE) as u64));
    group.bench_function(BenchmarkId::new("simdnoise-cellular2", "grid"), |b| {
        b.iter(|| simdnoise::NoiseBuilder::cellular2_3d(SIDE, SIDE, 1).with_freq(freq).generate());
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    println!("SIMD level: {}", worley::simd_level());
    let (random, grid) = points();
    ours::<1>(c, &random, &grid);
    ours::<2>(c, &random, &grid);
    peers(c, &random, &grid);
}

criterion_group!(peers_group, benches);
criterion_main!(peers_group);
