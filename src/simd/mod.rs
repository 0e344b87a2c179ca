//! # The SIMD kernel
//!
//! The same function as the [`Reference`](crate::Reference), on the same
//! feature points bit for bit, computed in f32 lanes eight samples at a time.
//!
//! ## How
//! - **Locating** a sample is done in f64, exactly as the reference does it
//!   (u = x·S, c = ⌊u⌋), so the cell is the reference's and the fraction
//!   f ∈ [0, 1] loses only its rounding to f32. When every lane is within
//!   2^31 cells of the origin this is straight-line code that vectorises (the
//!   floor by adding and subtracting 1.5·2^52, the cell's low word from the
//!   bits of the sum); otherwise each lane goes through
//!   [`Pattern::locate`] and the full i64 axis terms. Distances are then
//!   computed in f32 relative to the sample's own cell, so precision does not
//!   depend on how far the sample is from the origin.
//! - **Units.** Lane geometry is held in units of 2^−24 cells, one step of
//!   a feature point's fixed-point coordinate, so a coordinate is its 24-bit
//!   integer converted exactly, with no multiply. Scaling by a power of two
//!   is exact: every value is the cell-unit value times 2^24, bit for bit.
//! - **The cell hash and the LCG** run in `u32` lanes. The axis words of a
//!   sample's 3 × d neighbouring axis terms are mixed once, when it is
//!   located, and shared by every cell that uses them. Each point coordinate
//!   comes from the cell's state with one independent multiply-add
//!   (s_k = A_k·s₀ + C_k, [`lcg_jump`](crate::definition::lcg_jump)) instead of a chain of dependent
//!   multiplies.
//! - **Minkowski** ranks are the distance itself, computed per lane in f64
//!   scaled by the largest component ([`Metric::rank`](crate::Metric::rank)) and rounded once, so
//!   no power overflows for any p; the other metrics stay in f32 lanes.
//! - **Populations.** The default table never decreases, so point j of a
//!   cell exists exactly where the state's top byte reaches a threshold: one
//!   compare in lanes, no table lookup. Points are produced while any lane
//!   that needs the cell has one more. Bumped (unsorted) tables take a
//!   lookup per lane.
//! - **Divergence.** The 3^d block is visited in a mirrored frame per lane:
//!   on each axis the lane's near neighbour (−1 if f < ½, else +1) comes
//!   before the far one. The first stage is every lane's 2^d block: its
//!   own cell and the 2^d − 1 cells around its nearest lattice corner, all
//!   hashed up front as independent chains, then the same number of point
//!   steps in every cell: the largest population of any cell in any lane,
//!   so that the point loop's end repeats from cell to cell; a point a
//!   lane's cell lacks has rank +∞ there. The second stage is the far
//!   cells, each visited only for the lanes whose F_n could reach it
//!   (Worley's pruning per lane), and skipped together when every lane's
//!   F_n is within its nearest far face. A lane's result depends on that
//!   lane alone, which is what makes one, eight and sixteen lanes
//!   bit-identical, and lets [`Simd::evaluate_slice`] run the first stage
//!   on every block and gather the samples it leaves open (a few percent
//!   at F1, more at higher orders; docs/simd.md) into blocks of their own
//!   that continue from their candidates with the second stage. Where
//!   the build has AVX-512 (`avx512f`), slices run in blocks of sixteen
//!   lanes: one instruction covers twice the samples, while the point
//!   loop's shared trip count, the largest of 128 populations instead of
//!   64, grows from 10.9 to 11.6 steps per cell on average at λ 5.
//! - **Exact.** After the block, a lane whose F_n is farther than the block's
//!   outside (or as far, when IDs are asked for and a tie must be seen)
//!   takes the wider search, shell by shell, masked to the lanes that still
//!   need it (a cold path: 0.003 % of samples for 3D F8 at λ 5).
//! - **Compile-time choices.** Dimension `D` and order `N` are const
//!   generics; the Euclidean metric and the outputs (distances, IDs,
//!   deltas) are dispatched once per call into monomorphised loops, so
//!   nothing the caller did not ask for is computed in the hot loop. The
//!   other three metrics share one instantiation (the metric a value tested
//!   per fold, IDs and deltas always tracked): they are the rarer ones, and
//!   each instantiation of the search is a sizeable part of a build.
//! - **Batches** ([`batch`]): slices of any [`Point`] type, regular
//!   [`Grid`]s, rayon tiles (feature `parallel`) and points given as a cell
//!   plus a fraction for large worlds.
//! - **Grids share their cells.** [`Simd::evaluate_grid`] generates the
//!   points of a band of rows once and evaluates tiles of 8 × 8 samples
//!   (16 × 16 in AVX-512 lanes)
//!   against the few points that can matter to the tile, each broadcast to
//!   every lane; lanes it cannot certify take the per-sample kernel
//!   ([`Simd::coherent_grid`] says when the path applies). Deltas are
//!   computed exactly as the per-sample kernel computes them, so a grid
//!   sample is that kernel's result bit for bit.
//!   [`Simd::evaluate_grid_distances`] runs the same tiles and writes the
//!   distances alone, 4 bytes per sample and order.
//! - **Ties** are ordered by ID: of two points at the same rank the one with
//!   the smaller ID comes first (see [`reference`](crate::reference)), so
//!   paths that meet points in different orders agree on IDs and deltas.
//!
//! ## The parts
//! Each file imports only from the ones listed before it (and the
//! evaluator type [`Simd`], declared here):
//!
//! | file | what it holds |
//! |---|---|
//! | `lanes.rs`, `level.rs` | the lane sets (one, eight, sixteen lanes) and the SIMD level in force |
//! | `metric.rs`, `features.rs`, `best.rs` | the metrics in lanes, the output types, the sorted list of candidates per lane |
//! | `generate.rs` | the cell hash and the point generator |
//! | `locate.rs` | a lane's cell, its neighbours' axis words and its fraction |
//! | `search.rs` | the per-sample search and its certified widening |
//! | `entry.rs` | building an evaluator, one point, eight, and the dispatch to a monomorphised search |
//! | `grid.rs`, `sample.rs`, `region.rs` | a regular grid of samples; what batches read per sample and how a result's lanes are written; a box of cells generated once and a band of grid rows |
//! | `tiles.rs`, `tile.rs`, `coherent.rs` | the coherent path: rows of tiles and what a tile writes per sample, one tile's bound and certificate, the grid calls |
//! | `avx512.rs` | the run-time sixteen-lane copies of slices and tiles |
//! | `batch.rs`, `periodic.rs` | slices, grids and points given as a cell plus a fraction; the tileable variant |
//! | `border.rs`, `border/search.rs`, `border/tiles.rs` | the distance to the cell's border, its per-sample search and its grid tiles |
//! | `border/nsphere.rs`, `border/smooth.rs`, `border/smooth/near.rs` | the n-sphere radius; compact smooth F1 and its search for the points within reach |
//!
//! The functions a kernel is compiled into, the `#[inline(never)]` and
//! `#[target_feature]` ones that the `#[inline(always)]` parts inline into
//! (`widen`, `tile_per_sample`, `dispatch_avx2`, `tiles_others`, …), are
//! free functions of the file that holds them, taking the kernel as their
//! first argument, not methods of [`Simd`]. rustc compiles a method in the
//! codegen unit of its type's module, and LLVM optimises a codegen unit on
//! one thread: as methods they were one unit, four fifths of the machine
//! code of a crate that instantiates kernels, and a build optimised it on
//! one core while the other idled (docs/measurements.md, "One codegen unit
//! per part").
//!
//! ## Build flags
//! `wide` chooses its instructions at compile time only. Build with
//! `RUSTFLAGS="-C target-cpu=native"` (or `x86-64-v3`) for the AVX2 path;
//! [`simd_level`] reports what runs. Results are bit-identical between
//! builds: no operation used here differs between them.
//!
//! A build without AVX2 (the x86_64 default) also carries the Euclidean
//! 8-lane kernels compiled inside a `#[target_feature(enable = "avx2")]`
//! function and runs that copy when the CPU reports AVX2
//! ([`runtime_avx2`]). `wide`'s SSE2 code stays what it is, but LLVM lowers
//! it again there: the 32-bit lane multiply, a scalar fallback on SSE2,
//! becomes `vpmulld`, and VEX encodings drop register copies. Calling that
//! function is one of the crate's two fenced `unsafe` operations, behind the
//! CPU check; it took the default build's 3D F1 from 7.9 to 10.8 M
//! samples/s on random points (one thread). `tests/lanes/levels.rs` keeps
//! the two copies bit for bit equal.
//! The other metrics' kernels stay out of the copy and run the build's own
//! instructions: copying all twelve kernels (four metrics, three output
//! choices) doubled the optimised build of the crate, and the Euclidean
//! metric is the one the speed figures are about. The Euclidean grid tiles
//! exist in such a build only in that copy and the AVX-512 one: on a CPU
//! without AVX2 (or under a ceiling of SSE2) its grids take the per-sample
//! kernel, the same bits.
//!
//! Where the CPU also has AVX-512, a build without it runs Euclidean slices
//! ([`Simd::evaluate_slice`]) and the coherent path's tiles of grids
//! ([`Simd::evaluate_grid`], 16 × 16 samples where sixteen steps along
//! axis 0 span at most one cell) in sixteen AVX-512 lanes chosen at run time
//! ([`runtime_avx512`]): the one kernel instantiated over a private lane set
//! of AVX-512 intrinsics, compiled inside a function with the x86-64-v4
//! features. Recompiling `wide`'s code cannot get there (its sixteen lanes
//! are four SSE registers in such a build), and lanes of plain arrays left
//! to the compiler's vectoriser ran slower than the AVX2 copy; the module
//! `avx512` keeps the measurements and its safety argument. It is the
//! other fenced `unsafe` operation, and unit tests hold it to the one-lane
//! rule per operation and to the eight- and one-lane bits per slice.
//!
//! A build for AVX2 without AVX-512 (`-C target-cpu=x86-64-v3`, or `native`
//! on such a CPU) runs the Euclidean grid tiles in sixteen lanes as two
//! AVX2 halves (1.2-1.3× its eight lanes on 3D grids, docs/simd.md); a build
//! without target flags keeps eight lanes in its run-time AVX2 copy.

#[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
mod avx512;
pub mod batch;
mod best;
pub mod border;
mod coherent;
mod entry;
mod features;
mod generate;
mod grid;
pub mod lanes;
mod level;
mod locate;
mod metric;
pub mod periodic;
mod region;
mod sample;
mod search;
mod tile;
mod tiles;

pub use batch::{by_eights, Grid, Point, SizeError, TILE};
pub use border::{Border32, Border8, NSphere32, NSphere8, SimdBorder, SimdNSphere, SimdSmooth, Smooth32, Smooth8};
pub(crate) use coherent::GridRows;
#[cfg(feature = "parallel")]
pub(crate) use coherent::BAND;
pub(crate) use coherent::SERIAL_BAND;
pub use features::{lane, Features32, Features8};
pub use level::{runtime_avx2, runtime_avx512, set_simd_cap, simd_cap, simd_level, SimdCap};
pub use metric::{Chebyshev, Euclid, Manhattan, Metric32, Minkowski};
pub use periodic::{Period, PeriodError, MAX_PERIOD};

use crate::config::Config;
use crate::definition::{Pattern, TABLE_SIZE};
use generate::PointConstants;

/// `[f(0), f(1), …, f(D − 1)]` (`D ≥ 1`; per axis, or per order where a
/// `Best` is built): `array::from_fn` as a counted loop. The kernel uses it,
/// or plain loops, wherever it builds lane sets per axis: in the run-time
/// AVX-512 copy of a default build the iterator machinery behind `from_fn`
/// stayed an out-of-line call compiled without the caller's instructions.
///
/// An index loop, not a `for` over `iter_mut().enumerate().skip(1)`: every
/// closure is a type of its own, so each call is a copy per kernel type
/// (some 3,500 in the command line's library), and this loop's LLVM IR is
/// about half the iterator's (docs/measurements.md). One call keeps the
/// iterator: [`per_axis_slots`].
#[inline(always)]
#[allow(clippy::needless_range_loop)] // the index loop is the point: see above
pub(super) fn per_axis<T: Copy, const D: usize>(mut f: impl FnMut(usize) -> T) -> [T; D] {
    let mut r = [f(0); D];
    for a in 1..D {
        r[a] = f(a);
    }
    r
}

/// [`per_axis`] over an iterator of the slots, for the per-sample search's
/// offsets per cell of its 2^D block (`Simd::search`, inside the loop over
/// the block's cells): there the index loop cost the per-sample border,
/// compact smooth F1 and the n-sphere radius on random points 7 to 12 % of
/// their speed (the peers bench, native build), which this form does not.
#[inline(always)]
pub(super) fn per_axis_slots<T: Copy, const D: usize>(mut f: impl FnMut(usize) -> T) -> [T; D] {
    let mut r = [f(0); D];
    for (a, slot) in r.iter_mut().enumerate().skip(1) {
        *slot = f(a);
    }
    r
}

/// Which outputs a call computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outputs {
    /// F1..Fn only.
    Distances,
    /// F1..Fn and the feature IDs.
    Ids,
    /// F1..Fn, the feature IDs and the delta vectors.
    IdsAndDeltas,
}

/// The 8-lane evaluator for dimension `D` and order `N` (F1..FN).
#[derive(Clone, Debug)]
pub struct Simd<const D: usize, const N: usize> {
    config: Config,
    pattern: Pattern<D>,
    outputs: Outputs,
    table: [u8; TABLE_SIZE],
    /// Whether the table never decreases, so that populations come from
    /// each point's threshold in lanes.
    sorted: bool,
    /// What the kernel needs to produce point j of a cell, for every j the
    /// table allows.
    points: Vec<PointConstants<D>>,
    /// The 3^d block in the mirrored frame (see `search`).
    block: Vec<[i64; D]>,
    /// How many leading cells of `block` have no far axis.
    near: usize,
    inv_scale: f32,
}
