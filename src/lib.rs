//! # worley
//!
//! Steven Worley's cellular texture basis: F1..Fn, the distances from a
//! sample to its n closest feature points, with each point's delta vector
//! and feature ID, in 2, 3 and 4 dimensions and under the Euclidean,
//! Manhattan, Chebyshev and Minkowski metrics, on Worley's point process (a
//! Poisson number of points per cell).
//!
//! # Quick start
//!
//! ```
//! use worley::{Config, Outputs, Simd};
//!
//! // F1 and F2 with feature IDs in 3D; build once, share between threads.
//! let basis = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Ids).unwrap();
//! let f = basis.evaluate([1.0, 2.0, 3.0]);
//! let crackle = f.distance[1] - f.distance[0]; // F2 − F1
//! assert!(crackle >= 0.0 && f.id[0] != worley::INVALID_ID);
//! ```
//!
//! # Choosing an entry point
//!
//! Every call below gives the same bits for the same point. `Simd<D, N>`
//! computes F1..FN in f32 (N is a const generic, so the loops are sized at
//! compile time); [`Reference`] computes the same function in f64 and is
//! the one to read or to test against.
//!
//! | you have | call | notes |
//! |---|---|---|
//! | one point | [`Simd::evaluate`], [`Simd::evaluate_f32`], [`Simd::evaluate_vec3`] (and `vec2`, `vec3a`, `vec4`) | the 1-lane instantiation of the kernel |
//! | eight points (a ray packet) | [`Simd::evaluate8`], [`Simd::evaluate8_vec3`], [`Simd::evaluate_lanes`]; [`by_eights`] to shade any slice of points by eights | one `f32x8` per output and axis |
//! | a slice of points | [`Simd::evaluate_slice`] into your buffer; [`Simd::evaluate_slice_parallel`] on all cores | any [`Point`]: `[f64; D]`, `[f32; D]`, glam vectors |
//! | a regular grid or image tile | [`Simd::evaluate_grid`], [`Simd::evaluate_grid_parallel`]; [`Simd::evaluate_grid_distances`] for the distances alone; [`Grid::fill_by_eights`] for your own shading per eight points | axis 0 fastest; dense grids share their cells' points ([`Simd::coherent_grid`]) |
//! | a huge world | [`Simd::evaluate_in_cell`], [`Simd::evaluate8_in_cell`], [`Reference::evaluate_in_cell`] | an `i64` cell plus a fraction: no precision lost far from the origin |
//! | a tileable texture | [`Simd::evaluate_periodic`], [`Simd::evaluate8_periodic`] with a [`Period`] | samples in cells |
//! | combinations, fractal sums, gradients | [`texture::Texture`] | F2 − F1, Σ gain^i·C(lacunarity^i·x), analytic gradients |
//! | a pixel's footprint (a filter width per sample) | [`texture::Texture::filtered8`], `filtered`, `filtered_values`, `filtered_grid`, `filtered_gradient8`; [`filter`] | unresolved octaves skipped, values blended towards their means; zero width = the point sample's bits |
//! | the distance to the cell's border (even mortar) | [`SimdBorder::border`], [`SimdBorder::border8`], `border_slice`, `border_grid`, `border_in_cell`, `border_periodic`; [`Reference::border`] | with the neighbour's ID and the border's normal; Euclidean |
//! | smooth F1 (rounded cells) | compact: [`SimdSmooth::smooth`], [`SimdSmooth::smooth8`], `smooth_slice`, `smooth_grid`, `smooth_in_cell`, `smooth_periodic`; [`Reference::smooth_f1_compact`]; log-sum-exp: [`Reference::smooth_f1`] | C∞, with its gradient; compact: exact, points within F1 + 2s, lanes Euclidean; log-sum-exp: f64, certified to [`SMOOTH_TOLERANCE`]; any metric in f64 |
//! | the n-sphere radius (circles that fit their cells) | [`SimdNSphere::n_sphere`], [`SimdNSphere::n_sphere8`], `n_sphere_slice`, `n_sphere_grid`, `n_sphere_in_cell`, `n_sphere_periodic`; [`Reference::n_sphere`]; textures' [`Combination::NSphere`](texture::Combination::NSphere) | half the distance from F1's point to its nearest, with both IDs; lanes Euclidean |
//! | Perlin noise beside it | [`perlin::Perlin`] | one point or eight |
//!
//! [`Outputs`] says whether IDs and deltas are computed at all: asking for
//! distances only keeps them out of the hot loop.
//!
//! # Crate features
//!
//! - `parallel` (default): [`Simd::evaluate_slice_parallel`],
//!   [`Simd::evaluate_grid_parallel`] and grids of textures on all cores,
//!   with rayon. Without it the same calls run on the calling thread (the
//!   `_parallel` variants are not compiled).
//! - `serde`: `Serialize`/`Deserialize` for [`Config`], [`Metric`], [`Mode`]
//!   and [`texture::Range`].
//!
//! The crate's only other dependencies are `glam` (vector types in the API)
//! and `wide` (the lanes).
//!
//! # The order, one rule
//!
//! A typed evaluator's order is its type's: `N` in [`Simd<D, N>`](Simd)
//! and [`texture::Texture<D, N>`], 1 for [`SimdBorder`]. Their constructors
//! set [`Config::order`] to it whatever it held; the field is read by
//! [`Reference`] and the command line.
//!
//! # One point, eight, or many
//!
//! The one-point calls run the kernel's one-lane instantiation, with the
//! bits of the point's lane among eight. A point costs about what a packet
//! of eight does, so a renderer with many points calls the slice and grid
//! calls, or shades its own points by eights with [`by_eights`]
//! (`examples/plane.rs`: a camera, a plane, pixel footprints). Measured by
//! `cargo bench --bench single`, 3D, M points/s, default build:
//!
//! | output | one point | slice, per point (AVX2 / AVX-512 lanes) | f64 reference |
//! |---|---|---|---|
//! | F1 | 4.4 | 11.0 / 27.3 | 2.4 |
//! | F2 − F1 | 4.0 | 9.0 / 20.4 | 1.9 |
//! | border | 0.9 | 1.9 | 0.9 |
//! | 5-octave F2 − F1 texture | 0.65 | 1.7 | 0.4 |
//!
//! # Keeping a renderer's build fast
//!
//! The kernel is generic over dimension, order and point type, so each
//! instantiation (`Simd<3, 2>` and the calls made on it, `SimdBorder<3>`, a
//! `Texture`) is compiled in the crate that names it, with every metric and
//! output set (they are chosen at run time) and every SIMD path. A release
//! rebuild, after a touch of its `main.rs`, of a crate that uses five
//! kernels (`Simd<3, 2>::evaluate_slice`, `Simd<3, 1>::evaluate8`,
//! `Simd<3, 4>::evaluate`, `SimdBorder<3>::border_slice`, a five-octave
//! `Texture<3, 2>`) took 8.8 s on 2 cores (docs/simd.md). Name the kernels
//! in a small crate of their own
//! in your workspace, behind plain functions (`pub fn crackle(points:
//! &[[f64; 3]], out: &mut [f32])`): the crate that changes all day then
//! rebuilds in 0.1 s, and the kernels only when they change.
//!
//! # Which SIMD level runs
//!
//! `wide` fixes its instructions when it is compiled: build with
//! `RUSTFLAGS="-C target-cpu=native"` (or `x86-64-v3`) for AVX2. A build
//! without target flags on x86_64 still runs the Euclidean 8-lane kernels
//! recompiled for AVX2 when the CPU has it ([`simd::runtime_avx2`]), and
//! Euclidean slices in sixteen AVX-512 lanes when the CPU has AVX-512
//! ([`simd::runtime_avx512`]).
//! [`simd_level`] says which path a call takes. The environment variable
//! `WORLEY_SIMD` (`sse2`, `avx2`, `avx512`, `auto`) or
//! [`simd::set_simd_cap`] puts a ceiling on the run-time choices, so one
//! machine measures each level it has (the same bits at every level;
//! instructions compiled in stay):
//!
//! ```
//! use worley::simd::{set_simd_cap, SimdCap};
//! let before = set_simd_cap(SimdCap::Avx2); // what a CPU without AVX-512 runs
//! println!("worley runs {}", worley::simd_level());
//! set_simd_cap(before);
//! ```
//!
//! # Guarantees, and the test that enforces each
//!
//! - **Exact search** ([`Mode::Exact`], the default): the search widens
//!   until no unvisited cell can hold a closer point, so F_k is the true
//!   k-th distance of the point set for every order, metric and dimension
//!   (`tests/suite/oracle.rs`: 0 wrong on 10^6 random points per dimension against
//!   brute force; `tests/lanes/simd.rs` and the fuzz targets for continuity).
//!   [`Mode::Window`] is Worley's 3^d search, faster and sometimes wrong.
//! - **Error bound**: the f64 reference is within a few ulps; the f32
//!   kernel within 4·ε_f32·(F + 1/S) of it (S = [`Pattern::scale`]), however
//!   far the sample is from the origin, for every Minkowski exponent
//!   (`tests/lanes/simd.rs`, `tests/lanes/hard_cases.rs`, `tests/suite/minkowski.rs`, the
//!   `differential` fuzz target).
//! - **Bit identity**: one point gives the same bits through every entry
//!   point, lane, batch and thread count, and in a default and an AVX2
//!   build (`tests/lanes/simd.rs`, run by CI in both builds; a unit test holds the
//!   runtime-AVX2 copy equal to the SSE2 code).
//! - **Bad input** (NaN, ±∞, |x·S| > 2^53) gives NaN distances and deltas
//!   and [`INVALID_ID`], never a panic; no real feature point carries
//!   [`INVALID_ID`] (`tests/suite/sentinel_id.rs`, the `bad_input` fuzz target).
//!   An invalid [`Config`] is a [`ConfigError`] at construction.
//! - **The point set** is fixed bit for bit by [`definition`]: a second
//!   implementation that follows its text reproduces every point (a unit
//!   test re-derives a cell by hand), and it has the Poisson statistics and
//!   no repeated strips of cells (`tests/suite/statistics.rs`,
//!   `tests/suite/cell_hash.rs`).
//!
//! # Modules
//! - [`definition`] fixes the point set: the cell hash, the LCG, the Poisson
//!   population table, the fixed-point feature points and the scale that
//!   makes the mean Euclidean F1 equal to 1.
//! - [`reference`](mod@reference): the f64 kernel, plain loops written to be read.
//! - [`simd`]: the 8-lane f32 kernel on `wide` and its batch APIs.
//! - [`texture`], [`perlin`]: combinations, fractal sums, gradients, bump;
//!   Perlin noise.
//! - [`filter`]: what a sample is worth when it stands for a footprint:
//!   the blend curves, measured once per texture, and the cell cover.
//!
//! The harness that checks all of this against a brute-force oracle is the
//! `worley-harness` crate beside this one; the `worley` command is
//! `worley-cli`.
// Two fenced exceptions: the calls into the AVX2 copies of the 8-lane
// kernel and the coherent tiles after the CPU check (`simd::runtime_avx2`),
// and the module `simd::avx512` (AVX-512 intrinsics behind
// `simd::runtime_avx512`).
#![deny(unsafe_code)]
#![deny(missing_docs)]

pub mod config;
pub mod definition;
pub mod filter;
pub mod math;
#[cfg(feature = "parallel")]
mod parallel;
pub mod perlin;
pub mod reference;
pub mod simd;
pub mod texture;

/// The lane types of the 8-lane API (`f32x8`, `u32x8` in [`Features8`],
/// [`Border8`], [`Simd::evaluate_lanes`]), from the `wide` version this
/// crate is built with, so a caller needs no matching dependency of its own.
pub use wide;

pub use config::{Config, ConfigError, Metric, Mode, MAX_ORDER};
pub use definition::{Pattern, INVALID_ID};
pub use reference::{Border, Features, NSphere, Reference, Smooth, SMOOTH_TOLERANCE};
pub use simd::{
    by_eights, simd_level, Border32, Border8, Features32, Features8, Grid, NSphere32, NSphere8, Outputs, Period,
    PeriodError, Point, Simd, SimdBorder, SimdNSphere, SimdSmooth, SizeError, Smooth32, Smooth8,
};

// The README's and the documentation pages' Rust blocks run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
#[cfg(doctest)]
#[doc = include_str!("../docs/simd.md")]
struct SimdPageDoctests;
#[cfg(doctest)]
#[doc = include_str!("../docs/tools.md")]
struct ToolsPageDoctests;
#[cfg(doctest)]
#[doc = include_str!("../docs/accuracy.md")]
struct AccuracyPageDoctests;
#[cfg(doctest)]
#[doc = include_str!("../docs/definition.md")]
struct DefinitionPageDoctests;
