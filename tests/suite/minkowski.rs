//! Minkowski metrics at every accepted exponent, against an oracle that
//! cannot overflow: distances in the log domain (ln d = ln m + ln Σ
//! exp(p·(ln|xᵢ| − ln m)) / p with m the largest component), over every
//! feature point of the 7^d block around the sample, sorted. It shares only
//! the point set (`Pattern::for_each_point`) with the kernels.

use worley::{Config, Grid, Metric, Outputs, Reference, Simd};
use worley_harness::{sample_point, Tier};

const EXPONENTS: [f64; 10] = [1.0, 1.5, 2.0, 3.0, 8.0, 30.0, 100.0, 400.0, 1000.0, 1e6];

/// The Lp length of `v` through logarithms.
fn log_domain_length(v: &[f64], p: f64) -> f64 {
    let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 {
        return 0.0;
    }
    let ln_m = m.ln();
    let sum: f64 = v.iter().filter(|x| **x != 0.0).map(|x| (p * (x.abs().ln() - ln_m)).exp()).sum();
    (ln_m + sum.ln() / p).exp()
}

/// F1..F4 (user units) and their IDs at `x`, from every point of the 7^d
/// block; asserts that F4 is closer than the block's outside.
fn oracle<const D: usize>(basis: &Reference<D>, x: [f64; D], p: f64) -> Vec<(f64, u32)> {
    let pattern = basis.pattern();
    let (cell, f) = pattern.locate(x).unwrap();
    let mut all = Vec::new();
    for index in 0..7usize.pow(D as u32) {
        let offset: [i64; D] = std::array::from_fn(|a| (index / 7usize.pow(a as u32) % 7) as i64 - 3);
        let neighbour: [i64; D] = std::array::from_fn(|a| cell[a] + offset[a]);
        pattern.for_each_point(neighbour, |q| {
            let o = q.offset();
            let delta: Vec<f64> = (0..D).map(|a| f[a] - (offset[a] as f64 + o[a])).collect();
            all.push((log_domain_length(&delta, p), q.id));
        });
    }
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let outside = f.iter().fold(f64::INFINITY, |m, &v| m.min(v + 3.0).min(4.0 - v));
    assert!(all[3].0 <= outside, "F4 not certified by the 7^d block at {x:?}");
    all.truncate(4);
    all.iter().map(|&(d, id)| (d / pattern.scale(), id)).collect()
}

/// Whether F_k is within `tol` of F_{k−1} or F_{k+1} (a tie: either ID is right).
fn tied(want: &[(f64, u32)], k: usize, tol: f64) -> bool {
    (k > 0 && want[k].0 - want[k - 1].0 <= tol) || (k + 1 < want.len() && want[k + 1].0 - want[k].0 <= tol)
}

fn check<const D: usize>(samples: usize) {
    for p in EXPONENTS {
        let config = Config { order: 4, metric: Metric::Minkowski(p), ..Config::default() };
        let reference = Reference::<D>::new(config).unwrap();
        let simd = Simd::<D, 4>::new(config, Outputs::Ids).unwrap();
        let scale = reference.pattern().scale();
        let points: Vec<[f64; D]> = (0..samples).map(|i| sample_point(p.to_bits() ^ D as u64, i, 50.0)).collect();
        let mut slice = vec![simd.evaluate(points[0]); samples];
        simd.evaluate_slice(&points, &mut slice).unwrap();
        let (mut worst_ref, mut worst_simd) = (0.0f64, 0.0f64);
        for (i, x) in points.iter().enumerate() {
            let want = oracle(&reference, *x, p);
            let what = format!("{D}D p = {p} at {x:?}");
            // The reference: within a few f64 ulps, the same IDs.
            let r = reference.evaluate(*x);
            for k in 0..4 {
                let err = (r.distance[k] - want[k].0).abs() / want[k].0.max(1e-300);
                worst_ref = worst_ref.max(err);
                assert!(err < 1e-12, "{what}: reference F{} = {}, oracle {}", k + 1, r.distance[k], want[k].0);
                assert!(tied(&want, k, 1e-12) || r.id[k] == want[k].1, "{what}: reference ID of F{}", k + 1);
            }
            // The 8-lane kernel: within its stated bound 4ε_f32(F + 1/S),
            // the same bits through the single-point call, the eight lanes
            // and the slice.
            let single = simd.evaluate(*x);
            let block: [[f64; D]; 8] = std::array::from_fn(|l| points[(i / 8) * 8 + l.min(samples - 1 - (i / 8) * 8)]);
            let eight = simd.evaluate8(&block);
            let lane = i % 8;
            for k in 0..4 {
                let tol = 4.0 * f64::from(f32::EPSILON) * (want[k].0 + 1.0 / scale);
                let got = f64::from(single.distance[k]);
                worst_simd = worst_simd.max((got - want[k].0).abs());
                assert!((got - want[k].0).abs() <= tol, "{what}: SIMD F{} = {got}, oracle {}", k + 1, want[k].0);
                assert!(tied(&want, k, 2.0 * tol) || single.id[k] == want[k].1, "{what}: SIMD ID of F{}", k + 1);
                assert_eq!(eight.distance[k].to_array()[lane].to_bits(), single.distance[k].to_bits(), "{what}");
                assert_eq!(slice[i].distance[k].to_bits(), single.distance[k].to_bits(), "{what}: slice");
                assert_eq!(slice[i].id[k], single.id[k], "{what}: slice");
            }
        }
        // The grid and the cell + fraction entry points on a few points.
        let grid =
            Grid { origin: points[0], step: [0.37; D], size: std::array::from_fn(|a| if a < 2 { 5 } else { 1 }) };
        let mut out = vec![simd.evaluate(points[0]); 25];
        simd.evaluate_grid(&grid, &mut out).unwrap();
        for (i, o) in out.iter().enumerate() {
            let x = grid.point(i);
            assert_eq!(o.distance.map(f32::to_bits), simd.evaluate(x).distance.map(f32::to_bits), "grid p = {p}");
            let (cell, f) = simd.pattern().locate(x).unwrap();
            let in_cell = simd.evaluate_in_cell(cell, f.map(|v| v as f32));
            let want = oracle(&reference, x, p);
            for (got, (w, _)) in in_cell.distance.iter().zip(&want) {
                let tol = 4.0 * f64::from(f32::EPSILON) * (w + 1.0 / scale);
                assert!((f64::from(*got) - w).abs() <= tol, "evaluate_in_cell p = {p}");
            }
        }
        eprintln!("{D}D p = {p}: reference max rel. error {worst_ref:.1e}, SIMD max abs. error {worst_simd:.1e}");
    }
}

#[test]
fn minkowski_2d_every_exponent() {
    check::<2>(1500);
}

fn minkowski_3d(tier: Tier) {
    check::<3>(tier.of(3000));
}

fn minkowski_4d(tier: Tier) {
    check::<4>(tier.of(600));
}

worley_harness::tiered!(minkowski_3d_every_exponent, campaign_minkowski_3d_every_exponent, minkowski_3d);
worley_harness::tiered!(minkowski_4d_every_exponent, campaign_minkowski_4d_every_exponent, minkowski_4d);
