//! Every ceiling on the run-time SIMD choices (`WORLEY_SIMD`,
//! `set_simd_cap`) gives the same bits. In a build with AVX-512 compiled in
//! the ceilings change nothing; in an AVX2 build the slices and grid tiles
//! run eight AVX2 lanes or sixteen AVX-512 lanes chosen at run time; in a
//! default build SSE2, the AVX2 copies or the AVX-512 lanes. The ceiling is
//! global: the other tests of this binary only ever assert results that
//! every path gives alike.

use worley::math::uniform;
use worley::simd::{lane, runtime_avx2, runtime_avx512, set_simd_cap, simd_cap, simd_level, SimdCap};
use worley::{Config, Features32, Grid, Metric, Outputs, Simd};

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
    let before = set_simd_cap(SimdCap::Sse2);
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
    set_simd_cap(before);
}
