//! Every ceiling on the run-time SIMD choices (`WORLEY_SIMD`,
//! `set_simd_cap`) gives the same bits. In a build with AVX-512 compiled in
//! the ceilings change nothing; in an AVX2 build the slices and grid tiles
//! run eight AVX2 lanes or sixteen AVX-512 lanes chosen at run time; in a
//! default build SSE2, the AVX2 copies or the AVX-512 lanes. The ceiling is
//! global: the other tests of this binary only ever assert results that
//! every path gives alike, and the tests here that set it take [`CAP`]
//! first, so each runs its levels in turn without another changing them.
//!
//! These tests go through the public entry points only, so they compile
//! against the kernels the rest of the binary (and, in the default build,
//! the harness) already instantiates, and not into the library's own unit
//! tests, which cannot share them.

use std::sync::Mutex;
use worley::math::uniform;
use worley::simd::{lane, runtime_avx2, runtime_avx512, set_simd_cap, simd_cap, simd_level, SimdCap};
use worley::{Config, Features32, Grid, Metric, Outputs, Simd};

/// Held by every test that sets the ceiling.
static CAP: Mutex<()> = Mutex::new(());

/// Point i of a seeded set, uniform in [−range, range]^D.
#[cfg(not(target_feature = "avx512f"))]
fn sample_point<const D: usize>(seed: u64, i: usize, range: f64) -> [f64; D] {
    std::array::from_fn(|a| (2.0 * uniform(seed, (i * D + a) as u64) - 1.0) * range)
}

/// One result's distances, deltas and IDs as bits.
#[cfg(not(target_feature = "avx512f"))]
fn one_bits<const D: usize, const N: usize>(f: &Features32<D, N>) -> ([u32; N], [[u32; D]; N], [u32; N]) {
    (f.distance.map(f32::to_bits), f.delta.map(|d| d.map(f32::to_bits)), f.id)
}

fn bits<const D: usize, const N: usize>(v: &[Features32<D, N>]) -> Vec<u32> {
    v.iter()
        .flat_map(|f| {
            let d = f.distance.iter().map(|x| x.to_bits());
            let delta = f.delta.iter().flat_map(|a| a.iter().map(|x| x.to_bits()));
            d.chain(delta).chain(f.id.iter().copied()).collect::<Vec<_>>()
        })
        .collect()
}

/// Slices, grids and eight-lane calls at every ceiling give the bits of
/// the lowest one, and the ceiling decides the run-time choices.
#[test]
fn every_ceiling_gives_the_same_bits() {
    holding_the_ceiling(every_ceiling);
}

/// [`every_ceiling_gives_the_same_bits`], under the lock.
fn every_ceiling() {
    set_simd_cap(SimdCap::Sse2);
    assert!(!runtime_avx2() && !runtime_avx512(), "no run-time choice under an SSE2 ceiling");
    let points: Vec<[f64; 3]> =
        (0..3000).map(|i| std::array::from_fn(|a| (uniform(9, (3 * i + a) as u64) - 0.5) * 60.0)).collect();
    let grid = Grid { origin: [0.3, -1.7, 2.0], step: [0.05, 0.07, 1.0], size: [64, 40, 2] };
    let run = |metric: Metric| {
        let config = Config { order: 2, metric, ..Config::default() };
        let simd = Simd::<3, 2>::new(config, Outputs::IdsAndDeltas).unwrap();
        let empty = simd.evaluate([0.0; 3]);
        let mut slice = vec![empty; points.len()];
        simd.evaluate_slice(&points, &mut slice).unwrap();
        let mut tiles = vec![empty; grid.len().unwrap()];
        simd.evaluate_grid(&grid, &mut tiles).unwrap();
        let eights: Vec<Features32<3, 2>> = points
            .chunks_exact(8)
            .flat_map(|c| {
                let f = simd.evaluate8(c.try_into().unwrap());
                (0..8).map(move |i| lane(&f, i))
            })
            .collect();
        (bits(&slice), bits(&tiles), bits(&eights))
    };
    let metrics = [Metric::Euclidean, Metric::Manhattan];
    let lowest = metrics.map(run);
    for cap in [SimdCap::Avx2, SimdCap::Avx512] {
        set_simd_cap(cap);
        assert_eq!(simd_cap(), cap);
        assert!(metrics.map(run) == lowest, "{cap:?} ({}) differs from SSE2", simd_level());
    }
}

/// A slice at each ceiling (sixteen AVX-512 lanes chosen at run time where
/// the CPU has them, the AVX2 copy of the eight lanes, `wide`'s own eight)
/// and point by point through the one-lane kernel: the same bits, on
/// ordinary points, points beyond 2^31 cells (the lane-wise locate) and
/// NaN, infinite and out-of-range coordinates. A build with AVX-512
/// compiled in has one path only, tested by the rest of this binary.
#[cfg(not(target_feature = "avx512f"))]
fn slices_at_each_ceiling<const D: usize, const N: usize>(config: Config) {
    let mut points: Vec<[f64; D]> =
        (0..3001).map(|i| sample_point(17, i, if i % 5 == 0 { 3.0e10 } else { 40.0 })).collect();
    for (i, bad) in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1.0e300].into_iter().enumerate() {
        points[97 * i + 5][i % D] = bad;
    }
    for outputs in [Outputs::Distances, Outputs::Ids, Outputs::IdsAndDeltas] {
        let kernel = Simd::<D, N>::new(config, outputs).unwrap();
        let one: Vec<_> = points.iter().map(|p| kernel.evaluate(*p)).collect();
        for cap in [SimdCap::Sse2, SimdCap::Avx2, SimdCap::Avx512] {
            set_simd_cap(cap);
            let mut slice = vec![one[0]; points.len()];
            kernel.evaluate_slice(&points, &mut slice).unwrap();
            for (i, p) in points.iter().enumerate() {
                assert_eq!(
                    one_bits(&slice[i]),
                    one_bits(&one[i]),
                    "{D}D F{N} {outputs:?} under {cap:?}, point {i} {p:?}"
                );
            }
        }
    }
}

/// Runs `body` holding [`CAP`], then restores the ceiling it found.
fn holding_the_ceiling(body: impl FnOnce()) {
    let _held = CAP.lock().unwrap_or_else(|e| e.into_inner());
    let before = simd_cap();
    body();
    set_simd_cap(before);
}

/// `$check::<D, N>(config)` on each configuration the run-time copies are
/// compared on: every dimension, orders 1 to 8, a sparse pattern, window
/// mode and Worley's bump.
#[cfg(not(target_feature = "avx512f"))]
macro_rules! on_each_configuration {
    ($check:ident) => {
        $check::<2, 3>(Config { order: 3, ..Config::default() });
        $check::<3, 1>(Config::default());
        $check::<3, 2>(Config { order: 2, ..Config::default() });
        $check::<3, 4>(Config { order: 4, ..Config::default() });
        $check::<4, 2>(Config { order: 2, ..Config::default() });
        $check::<2, 8>(Config { order: 8, density: 0.5, ..Config::default() });
        $check::<3, 2>(Config { order: 2, mode: worley::Mode::Window, ..Config::default() });
        $check::<3, 2>(Config { order: 2, bump: 0.5, ..Config::default() });
    };
}

#[test]
#[cfg(not(target_feature = "avx512f"))]
fn slices_give_the_one_point_bits_at_every_ceiling() {
    holding_the_ceiling(|| {
        set_simd_cap(SimdCap::Avx512);
        if !runtime_avx512() {
            eprintln!("this CPU lacks AVX-512: the run-time sixteen lanes are not tested here");
        }
        on_each_configuration!(slices_at_each_ceiling);
    });
}

/// Batch `batch` of eight points: ordinary points in even batches, points
/// beyond 2^31 cells (the lane-wise locate) in odd ones, and in every
/// seventh a NaN lane among good ones.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
fn eight_points<const D: usize>(seed: u64, batch: usize) -> [[f64; D]; 8] {
    let range = [40.0, 3.0e10][batch % 2];
    let mut points: [[f64; D]; 8] = std::array::from_fn(|i| sample_point(seed, batch * 8 + i, range));
    if batch.is_multiple_of(7) {
        points[batch % 8][0] = f64::NAN;
    }
    points
}

/// `call` on the batches of [`eight_points`] under an SSE2 ceiling and
/// under AVX2: the same lanes, compared as `call` gives them (bits).
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
fn with_and_without_avx2<const D: usize, T: PartialEq + std::fmt::Debug>(
    seed: u64,
    what: &str,
    call: impl Fn(&[[f64; D]; 8]) -> [T; 8],
) {
    for batch in 0..1500 {
        let points = eight_points::<D>(seed, batch);
        set_simd_cap(SimdCap::Sse2);
        let plain = call(&points);
        set_simd_cap(SimdCap::Avx2);
        let avx2 = call(&points);
        for (i, (p, a)) in plain.iter().zip(&avx2).enumerate() {
            assert_eq!(p, a, "{what}, batch {batch} lane {i}");
        }
    }
}

/// Eight-lane calls of a default build with and without the kernel's AVX2
/// recompilation. An AVX2 build has no second copy.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
fn eights_with_and_without_avx2<const D: usize, const N: usize>(config: Config) {
    for outputs in [Outputs::Distances, Outputs::Ids, Outputs::IdsAndDeltas] {
        let kernel = Simd::<D, N>::new(config, outputs).unwrap();
        // The batches must reach the lane-wise locate: a lane NaN or beyond
        // its fast range of cells (2^31 − 3) in at least 700 of them.
        let scale = kernel.pattern().scale();
        let lanewise = (0..1500)
            .filter(|&b| {
                eight_points::<D>(11, b).iter().flatten().any(|x| x.is_nan() || (x * scale).abs() >= 2_147_483_645.0)
            })
            .count();
        assert!(lanewise >= 700, "{D}D: only {lanewise} of 1500 batches reach the lane-wise locate");
        with_and_without_avx2(11, &format!("{D}D F{N} {outputs:?}"), |points| {
            let f = kernel.evaluate8(points);
            std::array::from_fn(|i| one_bits(&lane(&f, i)))
        });
    }
}

/// The border's eight-lane calls of a default build with and without the
/// AVX2 recompilation of its search (and of F1 before it).
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
fn borders_with_and_without_avx2<const D: usize>(config: Config) {
    let bits = |b: &worley::Border32<D>| (b.distance.to_bits(), b.normal.map(f32::to_bits), b.feature, b.neighbour);
    let border = worley::SimdBorder::<D>::new(config).unwrap();
    with_and_without_avx2(12, &format!("{D}D border"), |points| {
        let b = border.border8(points);
        std::array::from_fn(|i| bits(&b.lane(i)))
    });
}

/// The kernel's and the border search's AVX2 recompilations in a default
/// build give the bits of the code they stand in for.
#[test]
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
fn the_avx2_recompilations_give_the_sse2_bits() {
    holding_the_ceiling(|| {
        set_simd_cap(SimdCap::Avx2);
        if !runtime_avx2() {
            eprintln!("this CPU has no AVX2: only the SSE2 kernel exists to test");
            return;
        }
        // Euclidean only: the other metrics run the same out-of-line code
        // in both copies.
        on_each_configuration!(eights_with_and_without_avx2);
        borders_with_and_without_avx2::<2>(Config::default());
        borders_with_and_without_avx2::<3>(Config::default());
        borders_with_and_without_avx2::<4>(Config::default());
        borders_with_and_without_avx2::<2>(Config { density: 0.5, ..Config::default() });
        borders_with_and_without_avx2::<3>(Config { mode: worley::Mode::Window, density: 1.0, ..Config::default() });
    });
}
