//! # Which SIMD instructions run, and a ceiling on the ones chosen at run time
//!
//! `wide` fixes its instructions when the crate is compiled, so a build
//! with AVX2 (or AVX-512) compiled in runs them everywhere. A build without
//! them still chooses two paths at run time when the CPU has the features:
//! the Euclidean 8-lane kernels recompiled for AVX2 ([`runtime_avx2`]) and
//! the Euclidean slices and grid tiles in sixteen AVX-512 lanes
//! ([`runtime_avx512`]). [`SimdCap`] is a ceiling on those run-time
//! choices, so one machine can measure every level it has: the environment
//! variable `WORLEY_SIMD` (`sse2`, `avx2`, `avx512` or `auto`), read once
//! at the first call that asks, or [`set_simd_cap`] at any time. Every
//! level gives the same bits (`tests/lanes/levels.rs` runs slices, grids
//! and eight-lane calls at each level the CPU has); a ceiling above the
//! CPU's features changes nothing, and no ceiling can lower what the build
//! compiled in.

use std::sync::atomic::{AtomicU8, Ordering};

/// The highest instructions the run-time choices may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SimdCap {
    /// No run-time choice: a default x86_64 build runs `wide`'s SSE2 code
    /// everywhere, an AVX2 build its AVX2 code.
    Sse2,
    /// The run-time AVX2 copies, not the AVX-512 lanes: what a CPU without
    /// AVX-512 runs.
    Avx2,
    /// Whatever the CPU has (the default).
    Avx512,
}

impl SimdCap {
    /// Reads a ceiling as `WORLEY_SIMD` spells it: `sse2`, `avx2`, `avx512`
    /// or `auto` (= [`SimdCap::Avx512`]), in any case; `None` for anything
    /// else.
    ///
    /// ```
    /// use worley::simd::SimdCap;
    /// assert_eq!(SimdCap::parse("AVX2"), Some(SimdCap::Avx2));
    /// assert_eq!(SimdCap::parse("auto"), Some(SimdCap::Avx512));
    /// assert_eq!(SimdCap::parse("neon"), None);
    /// ```
    pub fn parse(s: &str) -> Option<SimdCap> {
        match s.trim().to_ascii_lowercase().as_str() {
            "sse2" => Some(SimdCap::Sse2),
            "avx2" => Some(SimdCap::Avx2),
            "avx512" | "auto" => Some(SimdCap::Avx512),
            _ => None,
        }
    }
}

/// The ceiling in force: 0 until it is first read or set, then 1 + the
/// [`SimdCap`] as a number.
static CAP: AtomicU8 = AtomicU8::new(0);

fn encode(cap: SimdCap) -> u8 {
    1 + cap as u8
}

/// The ceiling `encode` stored, or `None` while none is.
fn decode(v: u8) -> Option<SimdCap> {
    [SimdCap::Sse2, SimdCap::Avx2, SimdCap::Avx512].into_iter().find(|&c| encode(c) == v)
}

/// Sets the ceiling on the run-time choices for every later call on every
/// thread; returns the one it replaces. Calls already running finish on
/// the path they took.
///
/// ```
/// use worley::simd::{set_simd_cap, simd_cap, SimdCap};
/// let before = set_simd_cap(SimdCap::Avx2);
/// assert_eq!(simd_cap(), SimdCap::Avx2);
/// set_simd_cap(before);
/// ```
pub fn set_simd_cap(cap: SimdCap) -> SimdCap {
    // Read first, so that the ceiling replaced is the environment's when
    // nothing was set before.
    simd_cap();
    decode(CAP.swap(encode(cap), Ordering::Relaxed)).unwrap_or(SimdCap::Avx512)
}

/// The ceiling in force: the last [`set_simd_cap`], or else `WORLEY_SIMD`
/// as the first call found it (an unset or unreadable value, or one
/// [`SimdCap::parse`] does not know, means [`SimdCap::Avx512`]: no
/// ceiling).
pub fn simd_cap() -> SimdCap {
    match decode(CAP.load(Ordering::Relaxed)) {
        Some(cap) => cap,
        None => {
            let cap = std::env::var("WORLEY_SIMD").ok().and_then(|v| SimdCap::parse(&v)).unwrap_or(SimdCap::Avx512);
            // A concurrent `set_simd_cap` wins over the environment.
            let _ = CAP.compare_exchange(0, encode(cap), Ordering::Relaxed, Ordering::Relaxed);
            simd_cap()
        }
    }
}

/// The SIMD instructions the kernels run: those compiled in, or AVX-512 and
/// AVX2 chosen at run time in a build without them (see [`runtime_avx512`]
/// and [`runtime_avx2`]), under the ceiling of [`simd_cap`].
pub fn simd_level() -> &'static str {
    if cfg!(target_feature = "avx512f") {
        "avx512f (slices and grid tiles in 16 lanes of 512 bits; 8-lane calls on AVX2 paths)"
    } else if runtime_avx512() {
        "avx512f at run time (a build without it: Euclidean slices and grid tiles run 16 AVX-512 lanes chosen because the CPU has them; Euclidean 8-lane calls run their AVX2 copy)"
    } else if cfg!(target_feature = "avx2") {
        "avx2 (Euclidean grid tiles in 16 lanes as two 256-bit halves)"
    } else if runtime_avx2() {
        "avx2 at run time (an sse2 build: its Euclidean 8-lane kernels are recompiled for AVX2 and chosen because the CPU has it)"
    } else if cfg!(target_feature = "sse4.1") {
        "sse4.1"
    } else if cfg!(target_feature = "sse2") {
        "sse2 (default x86_64 build: 8-lane integer ops are split or emulated)"
    } else {
        "scalar fallback"
    }
}

/// Whether 8-lane calls run the kernel recompiled for AVX2 at run time:
/// true when this build was compiled without AVX2, the target is x86_64,
/// the CPU has AVX2 and the ceiling ([`simd_cap`]) allows it. A build with
/// AVX2 compiled in (or any other target) always runs its own instructions
/// and gives false.
pub fn runtime_avx2() -> bool {
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
    {
        std::arch::is_x86_feature_detected!("avx2") && simd_cap() >= SimdCap::Avx2
    }
    #[cfg(not(all(target_arch = "x86_64", not(target_feature = "avx2"))))]
    {
        false
    }
}

/// Whether [`Simd::evaluate_slice`](super::Simd::evaluate_slice) runs the
/// Euclidean kernel in sixteen lanes compiled for AVX-512 at run time: true
/// when this build was compiled without AVX-512, the target is x86_64, the
/// CPU reports AVX-512 (F, BW, DQ and VL, the x86-64-v4 set) and the
/// ceiling ([`simd_cap`]) allows it. A build with AVX-512 compiled in runs
/// its own sixteen lanes and gives false.
pub fn runtime_avx512() -> bool {
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && simd_cap() >= SimdCap::Avx512
    }
    #[cfg(not(all(target_arch = "x86_64", not(target_feature = "avx512f"))))]
    {
        false
    }
}
