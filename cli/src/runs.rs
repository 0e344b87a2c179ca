//! The harness on one kernel and configuration, for `worley check` and the
//! main job.
//!
//! Non-generic functions of the library, so that the kernel instantiations
//! they need (every dimension, and the SIMD kernel's orders 1, 2, 4 and 8)
//! are compiled here, beside the same kernels `tune` uses, and the binary
//! compiles none: an optimised crate compiles its own copy of every generic
//! function it instantiates.

use worley::{Config, Outputs, Reference, Simd};
use worley_harness::{self as harness, Campaign, Report};

/// The SIMD kernel at the configuration's order (a const generic, so each
/// supported order is a separate instantiation): orders 1, 2, 4 and 8, as
/// `tune` measures; every instantiation compiles the whole kernel (every
/// entry point, metric and output set) once per dimension. The reference
/// kernel takes every order.
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
