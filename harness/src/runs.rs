//! The harness on one kernel and configuration chosen at run time, for
//! `worley check` and the main job (the `runs` feature).
//!
//! Non-generic functions that dispatch to every kernel they need (every
//! dimension, the SIMD kernel's orders 1, 2, 4 and 8, the reference), so
//! that the command line's binary compiles none of them. Where they are
//! compiled depends on the build:
//!
//! - **With debug assertions (the test and dev profiles)** they are
//!   compiled here. At opt-level 0 and 1 rustc shares a generic function's
//!   instances between crates, so a crate below this one that calls a
//!   kernel function compiled here (the out-of-line searches and tiles of
//!   `Simd<D, N>`, with the same parameters) links to this copy instead of
//!   compiling its own. With the feature on, a workspace `cargo test`
//!   compiled the command line's library in 20 s instead of 257, the
//!   `suite` tests in 17 instead of 190 and the `lanes` tests in 43
//!   instead of 157, for 201 s here (docs/measurements.md).
//! - **Without (release)** nothing is shared between crates, and copies
//!   compiled here would be compiled again in the command line's library,
//!   whose textures use the same kernels. There they are `#[inline]`, so
//!   the crate that calls them (the command line's library) compiles them
//!   beside its other kernels, once.

use crate::{self as harness, Campaign, Report};
use worley::{Config, Outputs, Reference, Simd};

/// The SIMD kernel at the configuration's order (a const generic, so each
/// supported order is a separate instantiation): orders 1, 2, 4 and 8, as
/// `tune` measures; every instantiation compiles the whole kernel (every
/// entry point, metric and output set) once per dimension. The reference
/// kernel takes every order.
#[cfg_attr(not(debug_assertions), inline)]
pub fn run_simd(dim: usize, config: Config, campaign: &Campaign) -> Result<Report, String> {
    fn go<const D: usize, const N: usize>(config: Config, campaign: &Campaign) -> Result<Report, String> {
        let kernel = Simd::<D, N>::new(config, Outputs::Ids).map_err(|e| e.to_string())?;
        Ok(harness::run(&kernel, campaign))
    }
    fn orders<const D: usize>(config: Config, campaign: &Campaign) -> Result<Report, String> {
        match config.order {
            1 => go::<D, 1>(config, campaign),
            2 => go::<D, 2>(config, campaign),
            4 => go::<D, 4>(config, campaign),
            8 => go::<D, 8>(config, campaign),
            n => Err(format!(
                "order {n} is not built into the SIMD kernel's command line: use 1, 2, 4 or 8 (or --kernel reference)"
            )),
        }
    }
    match dim {
        2 => orders::<2>(config, campaign),
        3 => orders::<3>(config, campaign),
        4 => orders::<4>(config, campaign),
        _ => Err(format!("dimension {dim} is not supported: use 2, 3 or 4")),
    }
}

/// The f64 reference kernel at any order.
#[cfg_attr(not(debug_assertions), inline)]
pub fn run_reference(dim: usize, config: Config, campaign: &Campaign) -> Result<Report, String> {
    fn go<const D: usize>(config: Config, campaign: &Campaign) -> Result<Report, String> {
        let kernel = Reference::<D>::new(config).map_err(|e| e.to_string())?;
        Ok(harness::run(&kernel, campaign))
    }
    match dim {
        2 => go::<2>(config, campaign),
        3 => go::<3>(config, campaign),
        4 => go::<4>(config, campaign),
        _ => Err(format!("dimension {dim} is not supported: use 2, 3 or 4")),
    }
}
