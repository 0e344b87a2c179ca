//! # worley
//!
//! Steven Worley's cellular texture basis: F1..Fn, the distances from a
//! sample to its n closest feature points, with each point's delta vector
//! and feature ID, in 2, 3 and 4 dimensions and under the Euclidean,
//! Manhattan, Chebyshev and Minkowski metrics.
//!
//! - [`definition`] fixes the point set bit for bit: the cell hash, the LCG,
//!   the Poisson population table, the fixed-point feature points and the
//!   scale that makes the mean Euclidean F1 equal to 1.
//! - [`Reference`] is the f64 reference kernel: plain loops, exact by
//!   construction (it widens its search until no unvisited cell can hold a
//!   closer point), written to be read.
//! - [`Simd`] is the 8-lane f32 kernel on `wide`: the same points, the same
//!   certified search, one sample or eight per call, bit-identical between
//!   the two.
//! - [`harness`] checks any evaluator against a brute-force oracle, for
//!   continuity across cell boundaries and against the Poisson law, and
//!   measures its throughput.
//!
//! ```
//! use worley::{Config, Reference};
//! let basis = Reference::<3>::new(Config { order: 2, ..Config::default() }).unwrap();
//! let f = basis.evaluate([1.0, 2.0, 3.0]);
//! let (f1, f2) = (f.distance[0], f.distance[1]);
//! assert!(0.0 <= f1 && f1 <= f2);
//! ```
//!
//! # Crate features
//! - `parallel` (default): the harness runs its oracle, continuity and grid
//!   campaigns on all cores with rayon. Throughput is always measured on one
//!   thread.
// One fenced exception: the call into the AVX2 copy of the 8-lane kernel
// after the CPU check (`simd::runtime_avx2`).
#![deny(unsafe_code)]
#![deny(missing_docs)]

pub mod config;
pub mod definition;
pub mod harness;
pub mod math;
pub mod perlin;
pub mod picture;
pub mod reference;
pub mod render;
pub mod simd;
pub mod texture;

pub use config::{Config, ConfigError, Metric, Mode, MAX_ORDER};
pub use definition::{Pattern, INVALID_ID};
pub use reference::{Features, Reference};
pub use simd::{simd_level, Features32, Features8, Grid, Outputs, Period, PeriodError, Point, Simd, SizeError};
