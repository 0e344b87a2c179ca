//! The kernel crate's integration tests, one module per subject, built as
//! one test binary: every test reaches the kernel through its generic entry
//! points, and one binary compiles each instantiation (dimension, order,
//! metric, outputs, lanes) once, where a binary per file compiled it again
//! in each file that used it. Filter by module: `cargo test --test suite
//! oracle::`. The SIMD kernel's entry points and lanes, which CI tests
//! again in each SIMD build, are the `lanes` binary (`tests/lanes/`).
//! The long campaigns run in part by default and whole under `cargo test
//! -- --ignored` ([`worley_harness::Tier`]).

mod border;
mod cell_hash;
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
