//! One-thread throughput of the 8-lane kernel through `evaluate_slice`, for
//! comparing builds side by side: run `cargo bench --bench throughput` from
//! two builds in turn (say a default build and `RUSTFLAGS="-C
//! target-cpu=native"` with its own `--target-dir`) a few times, so that both
//! see the same machine state. A bench target rather than an example: `cargo
//! test` builds every example, and this one's six kernels took about seven
//! minutes of an optimised test build.
//!
//! Each case is the best of nine passes over 2^18 points: seeded random
//! points in [−1000, 1000]^d, or a 512 × 512 grid with step 0.125 (in the
//! plane x₂ = 0.5 beyond 2D) given as a slice of points (`evaluate_slice`)
//! and as a [`Grid`] (the coherent path: `evaluate_grid`, whole results,
//! and `evaluate_grid_distances`, the distances alone). `Outputs::Distances`,
//! λ 5, Euclidean, exact mode.

use std::time::Instant;
use worley::{Config, Features32, Grid, Outputs, Simd};
use worley_harness::sample_point;

const POINTS: usize = 1 << 18;

/// Where the samples are.
#[derive(Clone, Copy, PartialEq)]
enum Points {
    Random,
    GridSlice,
    Grid,
    GridDistances,
}

/// A case: its name and its measurement.
type Case = (&'static str, fn(Points) -> f64);

fn run<const D: usize, const N: usize>(points: Points) -> f64 {
    let simd = Simd::<D, N>::new(Config { order: N, ..Config::default() }, Outputs::Distances).unwrap();
    let grid = Grid::<D> {
        origin: std::array::from_fn(|a| if a < 2 { 0.0 } else { 0.5 }),
        step: std::array::from_fn(|a| if a < 2 { 0.125 } else { 1.0 }),
        size: std::array::from_fn(|a| if a < 2 { 512 } else { 1 }),
    };
    let case = points;
    let points: Vec<[f64; D]> = if points != Points::Random {
        (0..POINTS)
            .map(|i| std::array::from_fn(|a| if a < 2 { ((i >> (9 * a)) % 512) as f64 * 0.125 } else { 0.5 }))
            .collect()
    } else {
        (0..POINTS).map(|i| sample_point(7, i, 1000.0)).collect()
    };
    let mut out = vec![Features32::<D, N> { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; POINTS];
    let mut distances = vec![[0.0; N]; POINTS];
    let mut best = f64::MAX;
    for _ in 0..9 {
        let start = Instant::now();
        match case {
            Points::Grid => simd.evaluate_grid(std::hint::black_box(&grid), &mut out).unwrap(),
            Points::GridDistances => simd.evaluate_grid_distances(std::hint::black_box(&grid), &mut distances).unwrap(),
            Points::Random | Points::GridSlice => simd.evaluate_slice(std::hint::black_box(&points), &mut out).unwrap(),
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    POINTS as f64 / best / 1e6
}

fn main() {
    println!("SIMD level: {}", worley::simd_level());
    println!("M samples/s, one thread, best of 9 passes over {POINTS} points");
    println!("case      random  grid (slice)  grid (evaluate_grid)  grid (evaluate_grid_distances)");
    let rows: [Case; 6] = [
        ("2D F1", run::<2, 1>),
        ("3D F1", run::<3, 1>),
        ("3D F2", run::<3, 2>),
        ("3D F4", run::<3, 4>),
        ("4D F1", run::<4, 1>),
        ("4D F2", run::<4, 2>),
    ];
    for (name, f) in rows {
        println!(
            "{name}  {:>9.2} {:>12.2} {:>12.2} {:>12.2}",
            f(Points::Random),
            f(Points::GridSlice),
            f(Points::Grid),
            f(Points::GridDistances)
        );
    }
}
