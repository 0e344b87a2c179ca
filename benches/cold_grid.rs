//! A grid call that starts with cold caches, as a renderer's call between
//! other work does (docs/simd.md, "Outputs written in order first"): 3D F1
//! `evaluate_grid_distances` on the peers bench's 256 × 256 slice (step
//! 0.125, z = 0.5), one call at a time, with something else run untimed
//! before each call. A plain program, like `throughput`: run
//! `cargo bench --bench cold_grid` (add `RUSTFLAGS="-C target-cpu=native"`
//! to match the peers bench). Prints the median of 15 rounds of 20 calls
//! per case, M samples/s, the cases round-robin.

use std::hint::black_box;
use std::time::Instant;
use worley::{Config, Grid, Outputs, Simd};
use worley_harness::sample_point;

const SIDE: usize = 256;

fn main() {
    let spec = Grid { origin: [0.0, 0.0, 0.5], step: [0.125, 0.125, 1.0], size: [SIDE, SIDE, 1] };
    let f1 = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    let mut out = vec![[0f32; 1]; SIDE * SIDE];
    let f2 = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    let points: Vec<[f32; 3]> = (0..1 << 20).map(|i| sample_point::<3>(3, i, 1000.0).map(|v| v as f32)).collect();
    let mut slice_out = vec![f2.evaluate([0.0; 3]); points.len()];
    let mut junk = vec![1u64; 8 << 20];
    let mut flush = || {
        junk.iter_mut().for_each(|v| *v = v.wrapping_mul(3).wrapping_add(1));
        black_box(&junk);
    };
    // What runs before each timed call.
    let cases = [
        "nothing (the same call back to back)",
        "nothing, each call at a shifted origin",
        "a 2^20-point slice of F2 with IDs and deltas",
        "64 MB written",
        "64 MB written, then the output written once",
    ];
    let mut rates = vec![Vec::new(); cases.len()];
    let mut calls = 0usize;
    for _ in 0..15 {
        for (k, rate) in rates.iter_mut().enumerate() {
            let mut seconds = 0.0;
            for _ in 0..20 {
                calls += 1;
                let mut grid = spec;
                match k {
                    1 => {
                        grid.origin[0] += 7.31 * calls as f64;
                        grid.origin[1] += 3.17 * calls as f64;
                    }
                    2 => f2.evaluate_slice(black_box(&points), &mut slice_out).map(|_| ()).unwrap(),
                    3 => flush(),
                    4 => {
                        flush();
                        out.fill([0.0]);
                        black_box(&out);
                    }
                    _ => {}
                }
                let start = Instant::now();
                f1.evaluate_grid_distances(black_box(&grid), &mut out).unwrap();
                seconds += start.elapsed().as_secs_f64();
            }
            rate.push((20 * SIDE * SIDE) as f64 / seconds / 1e6);
        }
    }
    println!("3D F1 evaluate_grid_distances, 256 x 256 slice, one call at a time; before each call:");
    for (name, r) in cases.iter().zip(&mut rates) {
        r.sort_by(f64::total_cmp);
        println!("  {name:<48} {:>7.1} M samples/s (median of 15 rounds)", r[r.len() / 2]);
    }
}
