//! The 8-lane kernel beside the peers, 3D, one thread, the same sample
//! positions for everybody:
//! - `random`: 2^18 seeded points in [−1000, 1000]^3;
//! - `grid`: a 256 × 256 slice (step 0.125, z = 0.5);
//! - `frame`: the hits of a pinhole camera, 640 × 360 pixels, 60° vertical
//!   field of view, 2 units above a ground plane that rises 12° away from
//!   it, looking 20° down, in pixel order: a feature spans about forty
//!   pixels at the bottom of the frame and less than one near the top
//!   (see [`frame`]); `frame-shuffled` is the same points in a random order
//!   (a bounce's hits), `frame-fine` the same at 8x the frequency (a
//!   fractal's fourth octave). Each frame has a border row too
//!   (`SimdBorder::border_slice` on its hits), beside its F2 − F1.
//!
//! What each one computes (none of the peers is the same function):
//! - `worley` F1 / F1F2: Poisson process, λ 5 per cell (the default), exact (certified
//!   search), isotropic; mean F1 = 1 user unit (one point per 1.8 units³^⅓).
//! - quick-noise `Cellular` (batch, one octave): one jittered point per cell
//!   on a 3^3 window; its own output scale.
//! - simdnoise `cellular_3d` / `cellular2_3d`: one jittered point per cell
//!   (jitter 0.25), 3^3 window, F1 squared / F2−F1 (`Distance2Sub`). Grids
//!   through its builder; random points through its AVX2 entry points,
//!   which are `unsafe` functions of `__m256` lanes (called only when the
//!   CPU reports AVX2, eight points at a time).
//! - fastnoise-lite `Cellular`: one jittered point per cell, scalar.
//! - noise (noise-rs) `Worley`: f64, one point per cell from a fixed table.
//!
//! - `binning floor` (frames only): what a binned `evaluate_slice` would
//!   spend moving the samples, with no search (see [`BinningFloor`]).
//!
//! After criterion's groups, one round-robin run of every contestant in
//! this process prints the headline table: median M samples/s of 15 rounds
//! after 3 unmeasured ones (a single call takes a millisecond or less, so
//! the first rounds mostly measure a cold cache and a waking core),
//! with the ratios of ours to the peers, the time of the border, smooth
//! F1 and the n-sphere radius as a multiple of worley's F2 − F1 on the same
//! workload, and the build flags.
//!
//! Peers get frequency 0.55 (cell side ≈ 1.8 units, the same feature
//! density as ours); simdnoise's grid, which steps by 1 per sample, gets
//! 0.55 · 0.125. Build flags decide everybody's SIMD path; quick-noise and
//! simdnoise also detect at run time.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use simdnoise::Cell2ReturnType;
use std::hint::black_box;
use std::time::Instant;
use worley::{
    Border32, Config, Features32, Grid, NSphere32, Outputs, Simd, SimdBorder, SimdNSphere, SimdSmooth, Smooth32,
};
use worley_harness::sample_point;

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

/// Frame width and height in pixels.
const FRAME: (usize, usize) = (640, 360);
/// Texture frequency on the ground plane: world units to texture units.
const FRAME_FREQUENCY: f64 = 6.0;

/// The frame's hits in texture space, in pixel order (rows from the top).
/// The camera sits at the origin, 2 units above the plane, looking along
/// +y and pitched 20° down; the plane rises 12° along +y, so every pixel's
/// ray meets it, the top rows about 60 units away.
fn frame() -> Vec<[f32; 3]> {
    let (w, h) = FRAME;
    let tan_half = (30.0f64).to_radians().tan();
    let (pitch, tilt) = ((-20.0f64).to_radians(), (12.0f64).to_radians());
    // The plane: points p with n · p = −2·cos(tilt) (through (0, 0, −2)).
    let n = [0.0, -tilt.sin(), tilt.cos()];
    let offset = -2.0 * tilt.cos();
    let mut hits = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let sx = (2.0 * (i as f64 + 0.5) / w as f64 - 1.0) * tan_half * w as f64 / h as f64;
            let sy = (1.0 - 2.0 * (j as f64 + 0.5) / h as f64) * tan_half;
            // Camera frame: x right, y forward, z up, then the pitch.
            let d = [sx, pitch.cos() - sy * pitch.sin(), pitch.sin() + sy * pitch.cos()];
            let t = offset / (n[1] * d[1] + n[2] * d[2]);
            let p = [t * d[0], t * d[1], t * d[2] + 2.0];
            hits.push(p.map(|v| (v * FRAME_FREQUENCY) as f32));
        }
    }
    hits
}

/// `v` in a seeded random order (Fisher-Yates).
fn shuffled(v: &[[f32; 3]]) -> Vec<[f32; 3]> {
    let mut v = v.to_vec();
    for i in (1..v.len()).rev() {
        let j = (worley::math::uniform(99, i as u64) * (i + 1) as f64) as usize;
        v.swap(i, j.min(i));
    }
    v
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
    let mut out = vec![Features32::<3, N> { distance: [0.0; N], delta: [[0.0; 3]; N], id: [0; N] }; SIDE * SIDE];
    group.throughput(Throughput::Elements((SIDE * SIDE) as u64));
    group.bench_function(BenchmarkId::new("worley-evaluate_grid", "grid"), |b| {
        b.iter(|| simd.evaluate_grid(black_box(&grid_spec()), &mut out).unwrap());
    });
    let mut distances = vec![[0.0f32; N]; SIDE * SIDE];
    group.bench_function(BenchmarkId::new("worley-evaluate_grid_distances", "grid"), |b| {
        b.iter(|| simd.evaluate_grid_distances(black_box(&grid_spec()), &mut distances).unwrap());
    });
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
        b.iter(|| {
            simdnoise::NoiseBuilder::cellular2_3d(SIDE, SIDE, 1)
                .with_freq(freq)
                .with_return_type(Cell2ReturnType::Distance2Sub)
                .generate()
        });
    });
    group.finish();
}

/// simdnoise on scattered points: its AVX2 entry points, eight points at a
/// time, coordinates scaled by [`FREQUENCY`] as its builder scales a grid's.
/// `f2` picks `cellular2_3d` (F2 − F1) over `cellular_3d` (F1). Returns
/// false, writing nothing, when the CPU lacks AVX2 or FMA.
fn simdnoise_points(xs: &[Vec<f32>; 3], out: &mut [f32], f2: bool) -> bool {
    if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
        return false;
    }
    // SAFETY: the CPU has just reported AVX2 and FMA, the only features the
    // function is compiled for.
    #[allow(unsafe_code)]
    unsafe {
        simdnoise_points_avx2(xs, out, f2)
    };
    true
}

/// The body of [`simdnoise_points`], compiled for AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
fn simdnoise_points_avx2(xs: &[Vec<f32>; 3], out: &mut [f32], f2: bool) {
    use simdeez::avx2::{Avx2, F32x8};
    use simdnoise::{CellDistanceFunction::Euclidean, CellReturnType::Distance};
    use std::arch::x86_64::{_mm256_set1_ps, _mm256_setr_ps, _mm256_storeu_ps};
    let load = |v: &[f32]| _mm256_setr_ps(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
    let (freq, jitter) = (_mm256_set1_ps(FREQUENCY), _mm256_set1_ps(0.25));
    for (i, o) in out.chunks_exact_mut(8).enumerate() {
        let [x, y, z] = std::array::from_fn(|a| F32x8(load(&xs[a][i * 8..i * 8 + 8])) * F32x8(freq));
        // SAFETY (both calls): this function runs only where AVX2 and FMA
        // are present (see `simdnoise_points`); the functions read and write
        // nothing but their arguments.
        #[allow(unsafe_code)]
        let v = unsafe {
            if f2 {
                simdnoise::cellular::cellular2_3d::<Avx2>(
                    x,
                    y,
                    z,
                    Euclidean,
                    Cell2ReturnType::Distance2Sub,
                    F32x8(jitter),
                    0,
                    1,
                    1,
                )
                .0
            } else {
                simdnoise::avx2::cellular_3d(x.0, y.0, z.0, Euclidean, Distance, jitter, 1)
            }
        };
        // SAFETY: `o` holds exactly eight f32.
        #[allow(unsafe_code)]
        unsafe {
            _mm256_storeu_ps(o.as_mut_ptr(), v)
        };
    }
}

/// A lower bound on what a binned `evaluate_slice` must spend moving its
/// samples, with no evaluation at all: each sample located in its cell (the
/// kernel's scale, an f32 floor per axis) and keyed by a hash of the cell,
/// a counting sort of the sample indices by key (over the whole batch or
/// per window of consecutive samples), then every sample read in
/// that order and a whole result (20 bytes, `Features32<3, 1>`) written
/// back at its input index. A stand-in of three operations takes the place
/// of the search, so the loop cannot be dropped. Any design that groups
/// arbitrary points by cell and returns results in input order does at
/// least this much; the frame rows put it beside the peers' whole cost.
struct BinningFloor {
    scale: f32,
    /// Samples sorted together: the whole batch, or windows of this many.
    window: usize,
    /// Bucket bits: 2^14 counters (64 KiB) for a whole batch stay in the L2
    /// cache; a window of 4096 samples gets 2^10.
    bits: u32,
    keys: Vec<u32>,
    starts: Vec<u32>,
    order: Vec<u32>,
}

impl BinningFloor {
    fn new(n: usize, window: usize) -> Self {
        let scale = worley::Reference::<3>::new(Config::default()).unwrap().pattern().scale() as f32;
        let bits = if window >= n { 14 } else { 10 };
        BinningFloor { scale, window, bits, keys: vec![0; n], starts: vec![0; 1 << bits], order: vec![0; n] }
    }

    /// `locate` false keeps the keys of the last run: the sort and the
    /// moves alone.
    fn run(&mut self, pts: &[[f32; 3]], out: &mut [Features32<3, 1>], locate: bool) {
        let (s, shift) = (self.scale, 32 - self.bits);
        for (k, p) in self.keys.iter_mut().zip(pts).filter(|_| locate) {
            let c = p.map(|v| (v * s).floor() as i32 as u32);
            let h = c[0].wrapping_mul(0x9E37_79B1) ^ c[1].wrapping_mul(0x85EB_CA77) ^ c[2].wrapping_mul(0xC2B2_AE3D);
            *k = h >> shift;
        }
        for (w, (keys, order)) in self.keys.chunks(self.window).zip(self.order.chunks_mut(self.window)).enumerate() {
            let base = (w * self.window) as u32;
            self.starts.fill(0);
            for &k in keys {
                self.starts[k as usize] += 1;
            }
            let mut sum = 0;
            for c in self.starts.iter_mut() {
                (*c, sum) = (sum, sum + *c);
            }
            for (i, &k) in keys.iter().enumerate() {
                let slot = &mut self.starts[k as usize];
                order[*slot as usize] = base + i as u32;
                *slot += 1;
            }
        }
        for &i in &self.order {
            let (p, key) = (pts[i as usize], self.keys[i as usize]);
            let f = p.map(|v| v * s - (v * s).floor());
            out[i as usize] = Features32 { distance: [f[0] * f[0] + f[1] * f[1] + f[2] * f[2]], delta: [f], id: [key] };
        }
    }
}

/// The grid slice as a [`Grid`]: the same points as `points().1`.
fn grid_spec() -> Grid<3> {
    Grid { origin: [0.0, 0.0, 0.5], step: [STEP, STEP, 1.0], size: [SIDE, SIDE, 1] }
}

/// One contestant of the headline table: a name, the case, and a closure
/// that evaluates the case's points once.
struct Entry<'a> {
    name: &'static str,
    case: &'static str,
    run: Box<dyn FnMut() + 'a>,
    samples: usize,
    rates: Vec<f64>,
}

/// Round-robin: every entry once per round, 3 unmeasured rounds and then
/// 15 measured, medians.
fn headline(random: &[[f32; 3]], grid: &[[f32; 3]]) {
    let frame_pts = frame();
    // In the order of `names` below.
    let frames: [Vec<[f32; 3]>; 3] =
        [frame_pts.clone(), shuffled(&frame_pts), frame_pts.iter().map(|p| p.map(|v| v * 8.0)).collect()];
    use quick_noise::simd::SimdSliceIterExt;
    let f1 = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    let f2 = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Distances).unwrap();
    let f2_ids = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    let f4 = Simd::<3, 4>::new(Config { order: 4, ..Config::default() }, Outputs::Distances).unwrap();
    let border = SimdBorder::<3>::new(Config::default()).unwrap();
    let smooth = SimdSmooth::<3>::new(Config::default()).unwrap();
    let spheres = SimdNSphere::<3>::new(Config::default()).unwrap();
    let spec = grid_spec();
    let n = grid.len();
    let axes = |pts: &[[f32; 3]]| -> [Vec<f32>; 3] { std::array::from_fn(|a| pts.iter().map(|p| p[a]).collect()) };
    let (gx, rx) = (axes(grid), axes(random));
    let quick = |xs: &[Vec<f32>; 3], out: &mut [f32]| {
        quick_noise::BatchNoise::<3, quick_noise::Fbm, quick_noise::Cellular>::builder(
            xs[0].simd_iter_static(),
            xs[1].simd_iter_static(),
            xs[2].simd_iter_static(),
        )
        .octaves(1)
        .frequency(FREQUENCY)
        .fill(black_box(out))
    };
    let freq = FREQUENCY * STEP as f32;
    let (mut o1, mut o2, mut o4) = (vec![[0f32; 1]; n], vec![[0f32; 2]; n], vec![[0f32; 4]; n]);
    let (mut whole1, mut o2i) = (
        vec![Features32::<3, 1> { distance: [0.0; 1], delta: [[0.0; 3]; 1], id: [0; 1] }; n],
        vec![Features32::<3, 2> { distance: [0.0; 2], delta: [[0.0; 3]; 2], id: [0; 2] }; n],
    );
    let (mut qg, mut qr, mut crackle) = (vec![0f32; n], vec![0f32; random.len()], vec![0f32; n]);
    let (mut sr, mut sr2, mut crackle_r) =
        (vec![0f32; random.len()], vec![0f32; random.len()], vec![0f32; random.len()]);
    let mut slice_out = vec![Features32::<3, 1> { distance: [0.0; 1], delta: [[0.0; 3]; 1], id: [0; 1] }; random.len()];
    let mut slice_out2 =
        vec![Features32::<3, 2> { distance: [0.0; 2], delta: [[0.0; 3]; 2], id: [0; 2] }; random.len()];
    // 2D and 4D: the same slice's points, the other axes at 0.5.
    let f1_2d = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    let f1_4d = Simd::<4, 1>::new(Config::default(), Outputs::Distances).unwrap();
    let spec_2d = Grid { origin: [0.0, 0.0], step: [STEP, STEP], size: [SIDE, SIDE] };
    let spec_4d = Grid { origin: [0.0, 0.0, 0.5, 0.5], step: [STEP, STEP, 1.0, 1.0], size: [SIDE, SIDE, 1, 1] };
    let (mut o1_2d, mut o1_4d) = (vec![[0f32; 1]; n], vec![[0f32; 1]; n]);
    let (mut border_g, mut border_r) = (vec![border.border([0.0; 3]); n], vec![border.border([0.0; 3]); random.len()]);
    // The frames: every contestant on the same hits.
    let frame_axes: Vec<[Vec<f32>; 3]> = frames.iter().map(|pts| axes(pts)).collect();
    let m = frame_pts.len();
    let mut frame_out: Vec<(Vec<f32>, Vec<f32>, Vec<f32>)> =
        (0..3).map(|_| (vec![0f32; m], vec![0f32; m], vec![0f32; m])).collect();
    let mut frame_f1: Vec<Vec<Features32<3, 1>>> = (0..3).map(|_| slice_out[..1].repeat(m)).collect();
    let mut frame_f2: Vec<Vec<Features32<3, 2>>> = (0..3).map(|_| slice_out2[..1].repeat(m)).collect();
    let mut frame_crackle: Vec<Vec<f32>> = (0..3).map(|_| vec![0f32; m]).collect();
    let mut frame_floor: Vec<Vec<Features32<3, 1>>> = (0..3).map(|_| slice_out[..1].repeat(m)).collect();
    let mut frame_moves: Vec<Vec<Features32<3, 1>>> = (0..3).map(|_| slice_out[..1].repeat(m)).collect();
    let mut frame_windows: Vec<Vec<Features32<3, 1>>> = (0..3).map(|_| slice_out[..1].repeat(m)).collect();
    let mut frame_border: Vec<Vec<Border32<3>>> = (0..3).map(|_| border_r[..1].repeat(m)).collect();
    let mut smooth_g: Vec<Vec<Smooth32<3>>> = (0..2).map(|_| vec![Smooth32::INVALID; n]).collect();
    let mut smooth_r: Vec<Vec<Smooth32<3>>> = (0..2).map(|_| vec![Smooth32::INVALID; random.len()]).collect();
    let (mut spheres_g, mut spheres_r) = (vec![NSphere32::INVALID; n], vec![NSphere32::INVALID; random.len()]);
    let mut entries: Vec<Entry> = Vec::new();
    fn add<'a>(
        entries: &mut Vec<Entry<'a>>,
        name: &'static str,
        case: &'static str,
        samples: usize,
        run: Box<dyn FnMut() + 'a>,
    ) {
        entries.push(Entry { name, case, run, samples, rates: Vec::new() })
    }
    add(&mut entries, "quick-noise 0.3 F1", "grid F1", n, Box::new(|| quick(&gx, &mut qg)));
    add(
        &mut entries,
        "simdnoise 3.1 F1",
        "grid F1",
        n,
        Box::new(|| {
            black_box(simdnoise::NoiseBuilder::cellular_3d(SIDE, SIDE, 1).with_freq(freq).generate());
        }),
    );
    add(
        &mut entries,
        "simdnoise 3.1 F2−F1",
        "grid F2−F1",
        n,
        Box::new(|| {
            black_box(
                simdnoise::NoiseBuilder::cellular2_3d(SIDE, SIDE, 1)
                    .with_freq(freq)
                    .with_return_type(Cell2ReturnType::Distance2Sub)
                    .generate(),
            );
        }),
    );
    add(&mut entries, "quick-noise 0.3 F1", "random F1", random.len(), Box::new(|| quick(&rx, &mut qr)));
    if simdnoise_points(&rx, &mut sr, false) {
        add(
            &mut entries,
            "simdnoise 3.1 F1",
            "random F1",
            random.len(),
            Box::new(|| {
                simdnoise_points(&rx, &mut sr, false);
                black_box(&sr);
            }),
        );
        add(
            &mut entries,
            "simdnoise 3.1 F2−F1",
            "random F2−F1",
            random.len(),
            Box::new(|| {
                simdnoise_points(&rx, &mut sr2, true);
                black_box(&sr2);
            }),
        );
    }
    add(
        &mut entries,
        "worley evaluate_grid_distances F1",
        "grid F1",
        n,
        Box::new(|| f1.evaluate_grid_distances(&spec, &mut o1).unwrap()),
    );
    add(
        &mut entries,
        "worley evaluate_grid F1 (whole results)",
        "grid F1",
        n,
        Box::new(|| f1.evaluate_grid(&spec, &mut whole1).unwrap()),
    );
    add(
        &mut entries,
        "worley evaluate_grid_distances F2−F1",
        "grid F2−F1",
        n,
        Box::new(|| {
            f2.evaluate_grid_distances(&spec, &mut o2).unwrap();
            for (c, d) in crackle.iter_mut().zip(&o2) {
                *c = d[1] - d[0];
            }
            black_box(&crackle);
        }),
    );
    add(
        &mut entries,
        "worley evaluate_grid F2, IDs and deltas",
        "grid F2 + IDs",
        n,
        Box::new(|| f2_ids.evaluate_grid(&spec, &mut o2i).unwrap()),
    );
    add(
        &mut entries,
        "worley evaluate_grid_distances F4",
        "grid F4",
        n,
        Box::new(|| f4.evaluate_grid_distances(&spec, &mut o4).unwrap()),
    );
    add(
        &mut entries,
        "worley evaluate_grid_distances F1",
        "2D grid F1",
        n,
        Box::new(|| f1_2d.evaluate_grid_distances(&spec_2d, &mut o1_2d).unwrap()),
    );
    add(
        &mut entries,
        "worley evaluate_grid_distances F1",
        "4D grid F1",
        n,
        Box::new(|| f1_4d.evaluate_grid_distances(&spec_4d, &mut o1_4d).unwrap()),
    );
    add(
        &mut entries,
        "worley evaluate_slice F1",
        "random F1",
        random.len(),
        Box::new(|| f1.evaluate_slice(black_box(random), &mut slice_out).unwrap()),
    );
    add(
        &mut entries,
        "worley evaluate_slice F2−F1",
        "random F2−F1",
        random.len(),
        Box::new(|| {
            f2.evaluate_slice(black_box(random), &mut slice_out2).unwrap();
            for (c, f) in crackle_r.iter_mut().zip(&slice_out2) {
                *c = f.distance[1] - f.distance[0];
            }
            black_box(&crackle_r);
        }),
    );
    // The distance to the cell's border beside F2 − F1: even mortar where
    // F2 − F1 widens (with the neighbour's ID and the border's normal).
    add(
        &mut entries,
        "worley SimdBorder border_grid",
        "grid border",
        n,
        Box::new(|| border.border_grid(&spec, &mut border_g).unwrap()),
    );
    add(
        &mut entries,
        "worley SimdBorder border_slice",
        "random border",
        random.len(),
        Box::new(|| border.border_slice(black_box(random), &mut border_r).unwrap()),
    );
    // Compact smooth F1 (s = 0.1 and 0.3 user units) and the n-sphere
    // radius, per sample on both workloads.
    let smoothness =
        [(0.1, "grid smooth s 0.1", "random smooth s 0.1"), (0.3, "grid smooth s 0.3", "random smooth s 0.3")];
    for ((g, r), (s, grid_case, random_case)) in smooth_g.iter_mut().zip(smooth_r.iter_mut()).zip(smoothness) {
        let (smooth, spec) = (&smooth, &spec);
        add(
            &mut entries,
            "worley SimdSmooth smooth_grid",
            grid_case,
            n,
            Box::new(move || smooth.smooth_grid(spec, s, g).unwrap()),
        );
        add(
            &mut entries,
            "worley SimdSmooth smooth_slice",
            random_case,
            random.len(),
            Box::new(move || smooth.smooth_slice(black_box(random), s, r).unwrap()),
        );
    }
    add(
        &mut entries,
        "worley SimdNSphere n_sphere_grid",
        "grid n-sphere",
        n,
        Box::new(|| spheres.n_sphere_grid(&spec, &mut spheres_g).unwrap()),
    );
    add(
        &mut entries,
        "worley SimdNSphere n_sphere_slice",
        "random n-sphere",
        random.len(),
        Box::new(|| spheres.n_sphere_slice(black_box(random), &mut spheres_r).unwrap()),
    );
    let names: [[&'static str; 3]; 3] = [
        ["frame F1", "frame F2−F1", "frame border"],
        ["frame-shuffled F1", "frame-shuffled F2−F1", "frame-shuffled border"],
        ["frame-fine F1", "frame-fine F2−F1", "frame-fine border"],
    ];
    let simd_ok = simdnoise_points(&frame_axes[0], &mut frame_out[0].1, false);
    for (k, ((((((((xs, (q, s1, s2)), o1f), o2f), cr), floor_out), moves_out), windows_out), bf)) in frame_axes
        .iter()
        .zip(frame_out.iter_mut())
        .zip(frame_f1.iter_mut())
        .zip(frame_f2.iter_mut())
        .zip(frame_crackle.iter_mut())
        .zip(frame_floor.iter_mut())
        .zip(frame_moves.iter_mut())
        .zip(frame_windows.iter_mut())
        .zip(frame_border.iter_mut())
        .enumerate()
    {
        let pts: &[[f32; 3]] = &frames[k];
        let [c1, c2, c3] = names[k];
        add(&mut entries, "quick-noise 0.3 F1", c1, m, Box::new(move || quick(xs, q)));
        if simd_ok {
            let peers = [("simdnoise 3.1 F1", c1, false, s1), ("simdnoise 3.1 F2−F1", c2, true, s2)];
            for (name, case, f2, out) in peers {
                add(
                    &mut entries,
                    name,
                    case,
                    m,
                    Box::new(move || {
                        simdnoise_points(xs, out, f2);
                        black_box(&out);
                    }),
                );
            }
        }
        let (mut floor, mut moves, mut windows) =
            (BinningFloor::new(m, m), BinningFloor::new(m, m), BinningFloor::new(m, 4096));
        moves.run(pts, floor_out, true);
        windows.run(pts, floor_out, true);
        add(
            &mut entries,
            "binning floor: locate, sort by cell and back, no search",
            c1,
            m,
            Box::new(move || floor.run(black_box(pts), black_box(&mut floor_out[..]), true)),
        );
        add(
            &mut entries,
            "binning floor, cells given: sort and back only",
            c1,
            m,
            Box::new(move || moves.run(black_box(pts), black_box(&mut moves_out[..]), false)),
        );
        add(
            &mut entries,
            "binning floor, cells given: sort in windows of 4096 and back",
            c1,
            m,
            Box::new(move || windows.run(black_box(pts), black_box(&mut windows_out[..]), false)),
        );
        let (f1, f2) = (&f1, &f2);
        add(
            &mut entries,
            "worley evaluate_slice F1",
            c1,
            m,
            Box::new(move || f1.evaluate_slice(black_box(pts), o1f).unwrap()),
        );
        add(
            &mut entries,
            "worley evaluate_slice F2−F1",
            c2,
            m,
            Box::new(move || {
                f2.evaluate_slice(black_box(pts), o2f).unwrap();
                for (c, f) in cr.iter_mut().zip(o2f.iter()) {
                    *c = f.distance[1] - f.distance[0];
                }
                black_box(&cr);
            }),
        );
        let border = &border;
        add(
            &mut entries,
            "worley SimdBorder border_slice",
            c3,
            m,
            Box::new(move || border.border_slice(black_box(pts), bf).unwrap()),
        );
    }
    for round in 0..3 + 15 {
        for e in entries.iter_mut() {
            let start = Instant::now();
            (e.run)();
            if round >= 3 {
                e.rates.push(e.samples as f64 / start.elapsed().as_secs_f64() / 1e6);
            }
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let medians: Vec<(&str, &str, f64)> = entries.iter_mut().map(|e| (e.name, e.case, median(&mut e.rates))).collect();
    let of = |name: &str, case: &str| medians.iter().find(|m| m.0 == name && m.1 == case).map(|m| m.2);
    println!();
    println!(
        "3D unless the case says 2D or 4D, one thread, same points at the same feature density; \
         median M samples/s of 15 round-robin rounds after 3 unmeasured"
    );
    println!(
        "build: RUSTFLAGS={:?}; compiled with avx2: {}, fma: {}, avx512f: {}; ceiling {:?} (WORLEY_SIMD={:?}); worley runs: {}",
        std::env::var("RUSTFLAGS").unwrap_or_default(),
        cfg!(target_feature = "avx2"),
        cfg!(target_feature = "fma"),
        cfg!(target_feature = "avx512f"),
        worley::simd::simd_cap(),
        std::env::var("WORLEY_SIMD").unwrap_or_default(),
        worley::simd_level()
    );
    println!("| case | contestant | M samples/s | / quick-noise F1 | / simdnoise | time / worley F2−F1 |");
    println!("|---|---|---|---|---|---|");
    for (name, case, rate) in &medians {
        // The peers run in 3D only: the 2D and 4D rows have no ratio.
        // Ratios within a workload (the case's first word): F1 against the
        // peers' F1, F2 − F1 and the border against simdnoise's F2 − F1.
        let (workload, what) = case.split_once(' ').unwrap_or((case, ""));
        let quick_ref = of("quick-noise 0.3 F1", &format!("{workload} F1"));
        let simd_ref = match what {
            "F1" => of("simdnoise 3.1 F1", &format!("{workload} F1")),
            "F2−F1" | "border" | "n-sphere" => of("simdnoise 3.1 F2−F1", &format!("{workload} F2−F1")),
            _ if what.starts_with("smooth") => of("simdnoise 3.1 F2−F1", &format!("{workload} F2−F1")),
            _ => None,
        };
        let ratio = |r: Option<f64>| r.map_or("".to_string(), |r| format!("{:.2}", rate / r));
        // The border, smooth F1 and the n-sphere radius beside worley's own
        // F2 − F1 on the same workload: how many times its time they take.
        let derived = matches!(what, "border" | "n-sphere") || what.starts_with("smooth");
        let f2_case = format!("{workload} F2−F1");
        let own = derived
            .then(|| {
                of("worley evaluate_grid_distances F2−F1", &f2_case).or(of("worley evaluate_slice F2−F1", &f2_case))
            })
            .flatten();
        let times = own.map_or("".to_string(), |f2| format!("{:.2}×", f2 / rate));
        println!("| {case} | {name} | {rate:.1} | {} | {} | {times} |", ratio(quick_ref), ratio(simd_ref));
    }
}

fn benches(c: &mut Criterion) {
    println!("SIMD level: {}", worley::simd_level());
    let (random, grid) = points();
    ours::<1>(c, &random, &grid);
    ours::<2>(c, &random, &grid);
    peers(c, &random, &grid);
    headline(&random, &grid);
}

criterion_group!(peers_group, benches);
criterion_main!(peers_group);
