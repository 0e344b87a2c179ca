//! The SIMD kernel's entry points and lanes: one lane, eight, sixteen,
//! slices, grids and parallel batches give the single-point bits,
//! agree with brute force, keep bad lanes to themselves, and hold on the
//! hard cases (huge coordinates, lattice values, ties, NaN and ±inf). Grid
//! tiles and the border kernel are the `grid_border` binary's.
//!
//! A binary of its own, apart from `tests/suite/`, because CI runs it again
//! in each SIMD build (default, AVX2, AVX-512: `wide` picks its code path at
//! compile time), and each of those builds then compiles only what it runs.

mod hard_cases;
mod levels;
mod simd;
