//! The SIMD kernel's grid tiles (the coherent path) and the border kernel
//! in lanes: every grid sample is the per-sample kernel's bits, and the
//! border gives the reference's result through every entry point.
//!
//! A binary of its own, apart from `tests/lanes/`, for the same reason that
//! one is apart from `tests/suite/` (CI runs both again in each SIMD build),
//! and so that the two halves compile in parallel there: each binary
//! compiles every kernel instantiation it uses on one core.

mod border;
mod coherent;
