//! The harness on one kernel and configuration chosen at run time, for
//! `worley check` and the main job: the harness's [`worley_harness::runs`],
//! called from this library rather than from the binary.
//!
//! In release builds those functions are `#[inline]`, so the crate that
//! calls them compiles their kernels; called here, that is this library,
//! where the textures of `render`, `bake` and `tune` compile the same
//! kernels, so each is compiled once. Called from the binary, a fresh
//! `cargo build --release` compiled them a second time there (the binary
//! 122 s instead of 6). In the test profile they are the harness's own
//! copies, which the test binaries share.

use worley::Config;
use worley_harness::{Campaign, Report};

/// The SIMD kernel at the configuration's order: [`worley_harness::runs::run_simd`].
pub fn run_simd(dim: usize, config: Config, campaign: &Campaign) -> Result<Report, String> {
    worley_harness::runs::run_simd(dim, config, campaign)
}

/// The f64 reference kernel at any order: [`worley_harness::runs::run_reference`].
pub fn run_reference(dim: usize, config: Config, campaign: &Campaign) -> Result<Report, String> {
    worley_harness::runs::run_reference(dim, config, campaign)
}
