//! The kernel crate's integration tests, one module per subject, built as
//! one test binary: every test reaches the kernel through its generic entry
//! points, and one binary compiles each instantiation (dimension, order,
//! metric, outputs, lanes) once, where a binary per file compiled it again
//! in each file that used it; in a workspace `cargo test`, the kernels the
//! harness's `runs` feature compiled are linked from there instead. Filter
//! by module: `cargo test --test suite oracle::`. The SIMD kernel's entry points and lanes, which CI tests
//! again in each SIMD build, are the `lanes` binary (`tests/lanes/`).
//! The long campaigns run in part by default and whole under `cargo test
//! -- --ignored` ([`worley_harness::Tier`]).

mod border;
mod cell_hash;
mod compact;
mod filter;
mod fuzz_regressions;
mod minkowski;
mod oracle;
mod perlin;
mod properties;
mod sentinel_id;
mod smooth;
mod statistics;
mod texture;

/// Every point of the block of Chebyshev radius `r` around the sample's
/// cell, relative to that cell's corner (cell units), with its ID.
pub(crate) fn block<const D: usize>(
    pattern: &worley::definition::Pattern<D>,
    cell: [i64; D],
    r: i64,
) -> Vec<([f64; D], u32)> {
    let side = 2 * r + 1;
    let mut points = Vec::new();
    for index in 0..side.pow(D as u32) {
        let mut rest = index;
        let offset: [i64; D] = std::array::from_fn(|_| {
            let o = rest % side - r;
            rest /= side;
            o
        });
        let c: [i64; D] = std::array::from_fn(|a| cell[a] + offset[a]);
        for p in pattern.points(c) {
            let q = p.offset();
            points.push((std::array::from_fn(|a| offset[a] as f64 + q[a]), p.id));
        }
    }
    points
}
