//! The SIMD kernel's entry points and lanes: one lane, eight, sixteen,
//! slices, grids and parallel batches give the single-point bits, agree
//! with brute force, keep bad lanes to themselves, and hold on the hard
//! cases (huge coordinates, lattice values, ties, NaN and ±inf); the grid
//! tiles (the coherent path) give the per-sample kernel's bits; the border,
//! the n-sphere radius and compact smooth F1 in lanes give the reference's
//! result through every entry point.
//!
//! A binary of its own, apart from `tests/suite/`, because CI runs it again
//! in each SIMD build (default, AVX2, AVX-512: `wide` picks its code path at
//! compile time), and each of those builds then compiles only what it runs.
//! One binary rather than two: the per-sample kernels these modules share
//! are then compiled once per build.
//!
//! The long campaigns run in part here and whole with `cargo test --
//! --ignored` ([`worley_harness::Tier`]).

mod border;
mod coherent;
mod hard_cases;
mod images;
mod levels;
mod nsphere;
mod simd;
mod smooth;
