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
//!   (s_k = A_k·s₀ + C_k, [`lcg_jump`]) instead of a chain of dependent
//!   multiplies.
//! - **Minkowski** ranks are the distance itself, computed per lane in f64
//!   scaled by the largest component ([`Metric::rank`]) and rounded once, so
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
//!   generics; the metric and the outputs (distances, IDs, deltas) are
//!   dispatched once per call into monomorphised loops, so nothing the caller
//!   did not ask for is computed in the hot loop.
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
//! samples/s on random points (one thread). A unit test keeps the two copies bit for bit equal.
//! The other metrics' kernels stay out of the copy and run the build's own
//! instructions: copying all twelve kernels (four metrics, three output
//! choices) doubled the optimised build of the crate, and the Euclidean
//! metric is the one the speed figures are about.
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

#[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
mod avx512;
pub mod batch;
pub mod border;
mod coherent;
pub mod lanes;
mod level;
pub mod periodic;

pub use batch::{by_eights, Grid, Point, SizeError, TILE};
pub use border::{Border32, Border8, SimdBorder};
pub(crate) use coherent::GridRows;
#[cfg(feature = "parallel")]
pub(crate) use coherent::BAND;
#[cfg(not(feature = "parallel"))]
pub(crate) use coherent::SERIAL_BAND;
pub use level::{runtime_avx2, runtime_avx512, set_simd_cap, simd_cap, simd_level, SimdCap};
pub use periodic::{Period, PeriodError, MAX_PERIOD};

use std::cell::Cell;
use wide::{f32x8, u32x8};

use crate::config::{Config, ConfigError, Metric, Mode};
use crate::definition::{axis_term, lcg_jump, Pattern, AXIS_MUL, FRACTION_BITS, INVALID_ID, TABLE_SIZE};
use crate::reference::{shell, MAX_SHELLS};
use lanes::{Eight, Lanes, One, WIDEST};

/// `[f(0), f(1), …, f(D − 1)]` (`D ≥ 1`; per axis, or per order where a
/// `Best` is built): `array::from_fn` as a counted loop. The kernel uses it,
/// or plain loops, wherever it builds lane sets per axis: in the run-time
/// AVX-512 copy of a default build the iterator machinery behind `from_fn`
/// stayed an out-of-line call compiled without the caller's instructions.
#[inline(always)]
fn per_axis<T: Copy, const D: usize>(mut f: impl FnMut(usize) -> T) -> [T; D] {
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

/// F1..Fn of one sample, in f32.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Features32<const D: usize, const N: usize> {
    /// F_k at index k − 1, user units; NaN for bad input.
    pub distance: [f32; N],
    /// Vector from the k-th closest point to the sample (zero when not asked for).
    pub delta: [[f32; D]; N],
    /// The k-th closest point's ID ([`INVALID_ID`] when not asked for or bad input).
    pub id: [u32; N],
}

/// F1..Fn of eight samples, one per lane.
#[derive(Clone, Copy, Debug)]
pub struct Features8<const D: usize, const N: usize> {
    /// F_k at index k − 1.
    pub distance: [f32x8; N],
    /// Delta vectors per axis.
    pub delta: [[f32x8; D]; N],
    /// Feature IDs.
    pub id: [u32x8; N],
}

/// No feature point found: distances +∞, zero deltas, [`INVALID_ID`], what
/// a window-mode search reports for an F_k its block lacks. A value to fill
/// the buffers of the slice and grid calls with.
///
/// ```
/// use worley::{Features32, Simd, Config, Outputs};
/// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Ids).unwrap();
/// let mut out = vec![Features32::<2, 1>::default(); 4];
/// basis.evaluate_slice(&[[0.5, 0.5]; 4], &mut out).unwrap();
/// assert_eq!(out[3], basis.evaluate([0.5, 0.5]));
/// ```
impl<const D: usize, const N: usize> Default for Features32<D, N> {
    fn default() -> Self {
        Features32 { distance: [f32::INFINITY; N], delta: [[0.0; D]; N], id: [INVALID_ID; N] }
    }
}

/// Every lane [`Features32::default`].
impl<const D: usize, const N: usize> Default for Features8<D, N> {
    fn default() -> Self {
        Features8 {
            distance: [f32x8::splat(f32::INFINITY); N],
            delta: [[f32x8::splat(0.0); D]; N],
            id: [u32x8::splat(INVALID_ID); N],
        }
    }
}

impl<const D: usize, const N: usize> Features8<D, N> {
    /// Lane `i` (0..8), as [`lane`] gives it.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Ids).unwrap();
    /// let points: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64 * 0.3, 0.1, 2.0]);
    /// let f = basis.evaluate8(&points);
    /// assert_eq!(f.lane(5), basis.evaluate(points[5]));
    /// assert_eq!(f.lanes()[7], f.lane(7));
    /// ```
    pub fn lane(&self, i: usize) -> Features32<D, N> {
        lane(self, i)
    }

    /// Every lane.
    pub fn lanes(&self) -> [Features32<D, N>; 8] {
        std::array::from_fn(|i| lane(self, i))
    }

    /// One sample's features in all eight lanes.
    pub fn splat(f: &Features32<D, N>) -> Self {
        Features8 {
            distance: f.distance.map(f32x8::splat),
            delta: f.delta.map(|d| d.map(f32x8::splat)),
            id: f.id.map(u32x8::splat),
        }
    }
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

/// A lane's located sample: the axis words of the cells around it and its
/// fraction in its own cell.
struct Located<L: Lanes, const D: usize> {
    /// Axis words ([`axis_word`](crate::definition::axis_word)) of the cells at offsets −1, 0, +1, per axis.
    words: [[L::U; 3]; D],
    /// The fraction f ∈ [0, 1] per axis, rounded to f32.
    f: [L::F; D],
    /// The lanes' own cells, for the wide search.
    cells: Cells<L, D>,
    /// Lanes with a valid input.
    valid: [bool; WIDEST],
    /// Cells per axis after which the pattern repeats (periodic variant):
    /// every cell is wrapped into [0, period) before it is hashed.
    period: Option<[i64; D]>,
}

/// Where the wide search finds the lanes' own cells.
enum Cells<L: Lanes, const D: usize> {
    /// Every lane within [`FAST_RANGE`]: per axis, the cell's low word (its
    /// raw axis term), from which the cell follows by sign extension.
    Low([L::U; D]),
    /// Some lane beyond it: the cells themselves, per axis and lane.
    Full([[i64; WIDEST]; D]),
}

impl<L: Lanes, const D: usize> Located<L, D> {
    /// Lanes from per-lane i64 cells and fractions (already in units of
    /// [`UNIT`]): the full axis words of every neighbour, kept cells.
    fn lanewise(cell: [[i64; WIDEST]; D], f: &[[f32; WIDEST]; D], valid: [bool; WIDEST]) -> Self {
        Self::wrapped(cell, f, valid, None)
    }

    /// As [`Located::lanewise`], with the cells wrapped by `period`.
    fn wrapped(
        cell: [[i64; WIDEST]; D],
        f: &[[f32; WIDEST]; D],
        valid: [bool; WIDEST],
        period: Option<[i64; D]>,
    ) -> Self {
        Located {
            words: per_axis(|a| per_axis(|o| words::<L>(a, &cell[a], o as i64 - 1, period.map(|p| p[a])))),
            f: per_axis(|a| L::f_load(&f[a][..L::N])),
            cells: Cells::Full(cell),
            valid,
            period,
        }
    }
}

impl<L: Lanes, const D: usize> Located<L, D> {
    /// The lanes' own cells, per axis and lane.
    #[inline(always)]
    fn cells_i64(&self) -> [[i64; WIDEST]; D] {
        match &self.cells {
            Cells::Full(cell) => *cell,
            Cells::Low(low) => per_axis(|a| {
                let mut lo = [0u32; WIDEST];
                L::u_store(low[a], &mut lo[..L::N]);
                lo.map(|t| i64::from(t as i32))
            }),
        }
    }
}

/// The n best candidates per lane.
#[derive(Clone, Copy)]
struct Best<L: Lanes, const D: usize, const N: usize> {
    rank: [L::F; N],
    delta: [[L::F; D]; N],
    id: [L::U; N],
}

/// The whole search (see [`Simd::search`]).
const WHOLE: u8 = 0;
/// The first stage of the search only: each lane's 2^d block.
const FIRST: u8 = 1;
/// The rest of the search after [`FIRST`]: the far cells and the widening.
const REST: u8 = 2;

/// What a stage of the search gives: the lanes' results as a caller sees
/// them (distances in user units, bad lanes marked), the lanes left open
/// (after [`FIRST`]; none otherwise), and the candidates as the kernel holds
/// them, from which [`REST`] continues.
type Stages<L, const D: usize, const N: usize> = (Best<L, D, N>, <L as Lanes>::M, Best<L, D, N>);

/// 2^24: lane geometry is held in units of one fixed-point step of a
/// feature-point coordinate, so that a coordinate is its 24-bit integer
/// converted exactly, with no multiply. Scaling by a power of two is exact,
/// so every value is the cell-unit value times 2^24, bit for bit.
const UNIT: f32 = (1u32 << FRACTION_BITS) as f32;

/// The LCG constants of one point index j: (A_k, C_k) for its ID state and
/// its coordinate states.
#[derive(Clone, Copy, Debug)]
struct PointConstants<const D: usize> {
    id: (u32, u32),
    coordinate: [(u32, u32); D],
    /// The same constants repeated in every lane, read by the per-sample
    /// kernel as whole lane sets: a load folds into the instruction that
    /// uses it, where a scalar constant needs a broadcast of its own.
    wide: WideConstants<D>,
}

/// One value in every lane of the widest lane set.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Splat<T>([T; WIDEST]);

/// [`PointConstants`] in every lane (see its `wide`).
#[derive(Clone, Copy, Debug)]
struct WideConstants<const D: usize> {
    /// What [`Simd::population`] is compared with: for a sorted table the
    /// threshold the state's top byte must exceed for the point to exist,
    /// for an unsorted one the point's index j, which the cell's
    /// population must exceed.
    key: Splat<f32>,
    id: (Splat<u32>, Splat<u32>),
    coordinate: [(Splat<u32>, Splat<u32>); D],
}

/// 1.5·2^52: adding and subtracting it rounds an f64 below 2^51 in magnitude
/// to an integer, and the integer's low 32 bits are then the sum's low bits.
const ROUNDING: f64 = 6_755_399_441_055_744.0;

/// Largest |u| located in lanes: the cell and both its neighbours stay in
/// the i32 range, where the axis term is the cell's low word.
const FAST_RANGE: f64 = 2_147_483_645.0;

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Builds the evaluator of F1..FN. The order is the type's `N`, as for
    /// every typed evaluator: `config.order` is set to `N` whatever it held
    /// ([`Config::order`]).
    ///
    /// # Errors
    /// The first invalid field of `config` ([`ConfigError::Order`] if `N`
    /// is 0 or above [`crate::MAX_ORDER`]).
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let f2 = Simd::<3, 2>::new(Config::default(), Outputs::Distances).unwrap();
    /// assert_eq!(f2.outputs(), Outputs::Distances);
    /// // The order is the const generic.
    /// assert_eq!(f2.config().order, 2);
    /// ```
    pub fn new(config: Config, outputs: Outputs) -> Result<Self, ConfigError> {
        let config = Config { order: N, ..config };
        let pattern = Pattern::<D>::new(&config)?;
        let table = *pattern.table().entries();
        let most = pattern.table().max_population();
        let sorted = table.windows(2).all(|w| w[0] <= w[1]);
        let points = (0..most)
            .map(|j| {
                let base = 1 + j * (D as u32 + 1);
                // In a sorted table, point j exists where the state's top
                // byte reaches the first entry above j.
                let threshold = table.iter().position(|&n| u32::from(n) > j).map_or(f32::INFINITY, |b| b as f32 - 0.5);
                let id = lcg_jump(base);
                let coordinate: [(u32, u32); D] = std::array::from_fn(|a| lcg_jump(base + 1 + a as u32));
                let splat = |(m, c): (u32, u32)| (Splat([m; WIDEST]), Splat([c; WIDEST]));
                let key = if sorted { threshold } else { j as f32 };
                PointConstants {
                    id,
                    coordinate,
                    wide: WideConstants { key: Splat([key; WIDEST]), id: splat(id), coordinate: coordinate.map(splat) },
                }
            })
            .collect();
        let block = logical_block::<D>();
        let near = block.iter().take_while(|o| o.iter().all(|&v| v <= 0)).count();
        let inv_scale = (1.0 / pattern.scale()) as f32;
        Ok(Simd { config, pattern, outputs, table, sorted, points, block, near, inv_scale })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The point set.
    pub fn pattern(&self) -> &Pattern<D> {
        &self.pattern
    }

    /// The outputs computed.
    pub fn outputs(&self) -> Outputs {
        self.outputs
    }

    /// One sample (the 1-lane instantiation of the kernel).
    ///
    /// A point costs about what a packet of eight costs: 3D F1 ran 4.4 M
    /// points/s one at a time against 11.0 per point through
    /// [`Simd::evaluate_slice`] with AVX2 and 27.3 where slices run sixteen
    /// AVX-512 lanes (f64 [`crate::Reference`]: 2.4; `cargo bench --bench
    /// single`, default build). Shade many points through the slice call or
    /// [`crate::by_eights`].
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<2, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    /// let f = basis.evaluate([0.3, -1.7]);
    /// assert!(f.distance[0] <= f.distance[1]);
    /// // The delta's length is F1.
    /// let [dx, dy] = f.delta[0];
    /// assert!(((dx * dx + dy * dy).sqrt() - f.distance[0]).abs() < 1e-6);
    /// // Bad input: NaN distances and the invalid ID.
    /// assert!(basis.evaluate([f64::NAN, 0.0]).distance[0].is_nan());
    /// ```
    pub fn evaluate(&self, x: [f64; D]) -> Features32<D, N> {
        let located = self.locate::<One>(&[x]);
        let best = self.dispatch::<One>(&located);
        Features32 { distance: best.rank, delta: best.delta, id: best.id }
    }

    /// One sample given in f32.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// assert_eq!(basis.evaluate_f32([1.5, 2.0, 0.25]).distance, basis.evaluate([1.5, 2.0, 0.25]).distance);
    /// ```
    pub fn evaluate_f32(&self, x: [f32; D]) -> Features32<D, N> {
        self.evaluate(x.map(f64::from))
    }

    /// Eight samples, one per lane (the 8-lane instantiation).
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Ids).unwrap();
    /// let points: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64, 0.5, -2.0]);
    /// let f = basis.evaluate8(&points);
    /// // Lane i is bit for bit the single-point result.
    /// assert_eq!(f.distance[0].to_array()[3].to_bits(), basis.evaluate(points[3]).distance[0].to_bits());
    /// ```
    pub fn evaluate8(&self, x: &[[f64; D]; 8]) -> Features8<D, N> {
        let located = self.locate::<Eight>(x);
        let best = self.dispatch8(&located);
        Features8 { distance: best.rank, delta: best.delta, id: best.id }
    }

    /// The 8-lane kernel, recompiled for AVX2 when this build lacks it and
    /// the CPU has it (see [`runtime_avx2`]): the same operations, so the
    /// same bits, in fewer instructions.
    #[inline(always)]
    fn dispatch8(&self, at: &Located<Eight, D>) -> Best<Eight, D, N> {
        self.dispatch8_stage::<WHOLE>(at, Best::empty()).0
    }

    /// [`Simd::dispatch8`], or one stage of the search (see [`Stages`]).
    #[inline(always)]
    fn dispatch8_stage<const STAGE: u8>(
        &self,
        at: &Located<Eight, D>,
        start: Best<Eight, D, N>,
    ) -> Stages<Eight, D, N> {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if runtime_avx2() {
            // SAFETY: `dispatch_avx2` requires AVX2 and nothing else, and
            // `runtime_avx2` has just seen the CPU report it.
            #[allow(unsafe_code)]
            return unsafe { self.dispatch_avx2::<STAGE>(at, start) };
        }
        self.dispatch_stage::<Eight, STAGE>(at, start)
    }

    /// [`Simd::dispatch`] in eight lanes, compiled with AVX2 enabled: `wide`
    /// keeps the SSE2 code it was built with, but LLVM lowers the Euclidean
    /// kernels inlined here again, turning the scalar fallbacks inside them
    /// (the 32-bit lane multiply above all) into AVX2 instructions. The
    /// other metrics go through the out-of-line `search_outputs`.
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
    #[target_feature(enable = "avx2")]
    fn dispatch_avx2<const STAGE: u8>(&self, at: &Located<Eight, D>, start: Best<Eight, D, N>) -> Stages<Eight, D, N> {
        self.dispatch_stage::<Eight, STAGE>(at, start)
    }

    /// Lanes per block in [`Simd::evaluate_slice`] for this kernel on this
    /// CPU: sixteen where AVX-512 is compiled in, or, for the Euclidean
    /// metric, where the CPU has it ([`runtime_avx512`]); eight otherwise.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// assert!(basis.slice_lanes() == 8 || basis.slice_lanes() == 16);
    /// ```
    pub fn slice_lanes(&self) -> usize {
        let runtime = self.config.metric == Metric::Euclidean && runtime_avx512();
        if cfg!(target_feature = "avx512f") || runtime {
            16
        } else {
            8
        }
    }

    /// Eight samples as lanes per axis.
    ///
    /// ```
    /// use wide::f32x8;
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let x = f32x8::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
    /// let f = basis.evaluate_lanes([x, f32x8::splat(0.5)]);
    /// assert_eq!(f.distance[0].to_array()[2], basis.evaluate_f32([2.0, 0.5]).distance[0]);
    /// ```
    pub fn evaluate_lanes(&self, x: [f32x8; D]) -> Features8<D, N> {
        let arrays = x.map(|v| v.to_array());
        let points: [[f64; D]; 8] = std::array::from_fn(|i| std::array::from_fn(|a| arrays[a][i] as f64));
        self.evaluate8(&points)
    }

    /// Locates every lane. The common case (every lane valid and within
    /// [`FAST_RANGE`] cells of the origin) runs as straight-line f64 code
    /// that vectorises: the floor by the rounding constant, the axis term
    /// from the bits of the rounded sum. Anything else takes the per-lane
    /// path through [`Pattern::locate`]. Both give the reference's cell and
    /// the reference's f64 fraction, rounded to f32.
    #[inline(always)]
    fn locate<L: Lanes>(&self, xs: &[[f64; D]]) -> Located<L, D> {
        let scale = self.pattern.scale();
        let mut lo = [[0u32; WIDEST]; D];
        let mut f = [[0f32; WIDEST]; D];
        let mut fast = true;
        for a in 0..D {
            for i in 0..L::N {
                let u = xs[i][a] * scale;
                let r = (u + ROUNDING) - ROUNDING;
                let floor = if r > u { r - 1.0 } else { r };
                lo[a][i] = (floor + ROUNDING).to_bits() as u32;
                f[a][i] = (u - floor) as f32 * UNIT;
                fast &= u.abs() < FAST_RANGE;
            }
        }
        if !fast {
            return self.locate_lanewise(xs);
        }
        let (mut words, mut lanes, mut low) = ([[L::u(0); 3]; D], [L::f(0.0); D], [L::u(0); D]);
        for a in 0..D {
            let t = L::u_load(&lo[a][..L::N]);
            // Written out: an array `map` here stayed a call with copies.
            words[a] = [word::<L>(a, L::u_add(t, L::u(u32::MAX))), word::<L>(a, t), word::<L>(a, L::u_add(t, L::u(1)))];
            lanes[a] = L::f_load(&f[a][..L::N]);
            low[a] = t;
        }
        Located { words, f: lanes, cells: Cells::Low(low), valid: [true; WIDEST], period: None }
    }

    #[inline(never)]
    #[cold]
    fn locate_lanewise<L: Lanes>(&self, xs: &[[f64; D]]) -> Located<L, D> {
        let mut cell = [[0i64; WIDEST]; D];
        let mut f = [[0f32; WIDEST]; D];
        let mut valid = [false; WIDEST];
        for (i, x) in xs.iter().enumerate().take(L::N) {
            if let Some((c, fr)) = self.pattern.locate(*x) {
                valid[i] = true;
                for a in 0..D {
                    cell[a][i] = c[a];
                    f[a][i] = fr[a] as f32 * UNIT;
                }
            }
        }
        Located::lanewise(cell, &f, valid)
    }

    /// Picks the monomorphised kernel for the metric and outputs, then
    /// converts ranks to distances and marks bad lanes.
    #[inline(always)]
    fn dispatch<L: Lanes>(&self, at: &Located<L, D>) -> Best<L, D, N> {
        self.dispatch_stage::<L, WHOLE>(at, Best::empty()).0
    }

    /// [`Simd::dispatch`], or one stage of the search (see [`Stages`]),
    /// from the candidates in `start`.
    #[inline(always)]
    fn dispatch_stage<L: Lanes, const STAGE: u8>(&self, at: &Located<L, D>, start: Best<L, D, N>) -> Stages<L, D, N> {
        let (raw, open) = match (self.config.metric, self.outputs) {
            (Metric::Euclidean, Outputs::Distances) => self.search::<L, Euclid, false, false, STAGE>(Euclid, at, start),
            (Metric::Euclidean, Outputs::Ids) => self.search::<L, Euclid, true, false, STAGE>(Euclid, at, start),
            (Metric::Euclidean, Outputs::IdsAndDeltas) => {
                self.search::<L, Euclid, true, true, STAGE>(Euclid, at, start)
            }
            (Metric::Manhattan, o) => self.search_outputs::<L, Manhattan, STAGE>(Manhattan, o, at, start),
            (Metric::Chebyshev, o) => self.search_outputs::<L, Chebyshev, STAGE>(Chebyshev, o, at, start),
            (Metric::Minkowski(p), o) => self.search_outputs::<L, Minkowski, STAGE>(Minkowski(p), o, at, start),
        };
        let mut best = raw;
        self.finish::<L, true>(&mut best);
        if at.valid[..L::N].iter().any(|v| !v) {
            mark_invalid(&mut best, &at.valid);
        }
        (best, open, raw)
    }

    /// Ranks in lane units to distances in user units, and deltas to user
    /// units (unless `DELTAS` is false: then they are zero and stay so): the
    /// last step of every path.
    #[inline(always)]
    fn finish<L: Lanes, const DELTAS: bool>(&self, best: &mut Best<L, D, N>) {
        let (unit, inv) = (L::f(1.0 / UNIT), L::f(self.inv_scale));
        let metric = self.config.metric;
        for k in 0..N {
            best.rank[k] = L::mul(L::mul(distance_of_rank::<L>(metric, best.rank[k]), unit), inv);
            for a in (0..D).filter(|_| DELTAS) {
                best.delta[k][a] = L::mul(L::mul(best.delta[k][a], unit), inv);
            }
        }
    }

    /// The kernels of the other metrics, kept out of line: a default
    /// build's AVX2 copy then holds only the Euclidean kernels (see
    /// [`Simd::dispatch_avx2`]), and the other metrics run the build's own
    /// instructions.
    ///
    /// One instantiation per metric serves every output set: the search
    /// with IDs and deltas, then the outputs not asked for put back to what
    /// the search without them leaves (`start`'s, never written). The
    /// distances are the same bits: the list holds the same N smallest
    /// ranks whether ties are ordered by ID or not. Each instantiation of
    /// the search is a sizeable part of a user's build, and these metrics
    /// are the rarer ones: a third of the copies, paid for by tracking IDs
    /// and deltas where only distances are asked (not measured).
    #[inline(never)]
    fn search_outputs<L: Lanes, M: Metric32, const STAGE: u8>(
        &self,
        m: M,
        o: Outputs,
        at: &Located<L, D>,
        start: Best<L, D, N>,
    ) -> (Best<L, D, N>, L::M) {
        let (id, delta) = (start.id, start.delta);
        let (mut best, open) = self.search::<L, M, true, true, STAGE>(m, at, start);
        if o != Outputs::IdsAndDeltas {
            best.delta = delta;
        }
        if o == Outputs::Distances {
            best.id = id;
        }
        (best, open)
    }

    /// The kernel: the 3^d block, then the certified widening.
    ///
    /// The block is visited in a per-lane mirrored frame: on each axis a
    /// lane's *near* neighbour (offset −1 if f < ½, else +1) comes first. In
    /// that frame every lane visits its own cell, then the 2^d − 1 cells
    /// around its nearest lattice corner, then the cells on the far sides,
    /// so the lanes agree on which visits still matter and all of them can
    /// usually stop after the near cells.
    ///
    /// `STAGE` says which part runs, from the candidates in `start`:
    /// [`WHOLE`] (from no candidate), [`FIRST`] (the 2^d block only; the
    /// lanes whose far cells could still hold a candidate are returned as
    /// open, and their results are not final) or [`REST`] (the far cells
    /// and the widening, from a first stage's candidates: a lane then ends
    /// with the bits [`WHOLE`] gives it). After [`WHOLE`] and [`REST`] every
    /// lane is final and the mask returned is empty.
    #[inline(always)]
    fn search<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool, const STAGE: u8>(
        &self,
        metric: M,
        at: &Located<L, D>,
        start: Best<L, D, N>,
    ) -> (Best<L, D, N>, L::M) {
        let mut best = start;
        let one = L::f(UNIT);
        // Per axis, indexed by the mirrored offset + 1 (near, own, far): the
        // axis word, the sample minus the cell's corner, and the metric's
        // term of the gap between the sample and the cell.
        let mut terms = [[L::u(0); 3]; D];
        let mut shifted = [[L::f(0.0); 3]; D];
        let mut gap = [[L::f(0.0); 3]; D];
        for a in 0..D {
            let f = at.f[a];
            let flip = L::lt(L::f(0.5 * UNIT), f);
            let t = at.words[a];
            terms[a] = [L::select_u(flip, t[2], t[0]), t[1], L::select_u(flip, t[0], t[2])];
            let (below, above) = (L::add(f, one), L::sub(f, one));
            shifted[a] = [L::select(flip, above, below), f, L::select(flip, below, above)];
            let rest = L::sub(one, f);
            gap[a] =
                [metric.term::<L>(L::select(flip, rest, f)), L::f(0.0), metric.term::<L>(L::select(flip, f, rest))];
        }
        // Stage 1, the lane's 2^d block (its own cell and the cells around
        // its nearest lattice corner): every cell hashed up front as
        // independent chains, then, cell by cell, the same number of point
        // steps, the largest population of any cell in any lane, so that the
        // inner loop's trip count repeats from cell to cell. A point a
        // lane's cell lacks has rank +∞ there. Cell c of the block is, on
        // axis a, the lane's near neighbour where bit a of c is set and its
        // own cell's column otherwise.
        if STAGE != REST {
            let cells = 1usize << D;
            let pick = |c: usize, a: usize| 1 - ((c >> a) & 1);
            let h = self.block_hashes::<L>(&terms);
            let mut top = [L::f(0.0); 16];
            let mut most = L::f(-1.0);
            for c in 0..cells {
                top[c] = self.population::<L>(h[c]);
                most = L::max(most, top[c]);
            }
            let count = self.points.iter().take_while(|p| L::any(L::lt(self.key::<L>(p), most))).count();
            for c in 0..cells {
                let sh = per_axis(|a| shifted[a][pick(c, a)]);
                for p in &self.points[..count] {
                    self.point::<L, M, IDS, DELTAS>(metric, p, h[c], sh, L::lt(self.key::<L>(p), top[c]), &mut best);
                }
            }
        }
        // Stage 2, the far cells, per lane only where one could still hold a
        // candidate; skipped together when no lane's F_n reaches its nearest
        // far face.
        let mut nearest_far = gap[0][2];
        for g in &gap[1..] {
            nearest_far = L::min(nearest_far, g[2]);
        }
        let far = may_enter::<L, IDS>(nearest_far, best.rank[N - 1]);
        if STAGE == FIRST {
            return (best, far);
        }
        if L::any(far) {
            for offset in &self.block[self.near..] {
                let index: [usize; D] = per_axis(|a| (offset[a] + 1) as usize);
                let mut rank = gap[0][index[0]];
                for a in 1..D {
                    rank = metric.fold::<L>(rank, gap[a][index[a]]);
                }
                let needs = may_enter::<L, IDS>(rank, best.rank[N - 1]);
                if !L::any(needs) {
                    continue;
                }
                let h = self.hash::<L>(per_axis(|a| terms[a][index[a]]));
                let sh: [L::F; D] = per_axis(|a| shifted[a][index[a]]);
                self.visit::<L, M, IDS, DELTAS>(metric, h, sh, needs, &mut best);
            }
        }
        if self.config.mode == Mode::Exact {
            let open =
                may_enter::<L, IDS>(metric.rank_of_distance::<L>(outside::<L, D>(&at.f, UNIT)), best.rank[N - 1]);
            if L::any(open) {
                self.widen::<L, M, IDS, DELTAS>(metric, at, open, &mut best);
            }
        }
        // Every lane is final: no lane is open.
        (best, L::lt(one, L::f(0.0)))
    }

    /// The cold path: shells of radius 2, 3, … for the lanes in `open`.
    #[inline(never)]
    fn widen<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        at: &Located<L, D>,
        mut open: L::M,
        best: &mut Best<L, D, N>,
    ) {
        let cell = at.cells_i64();
        for r in 2..=MAX_SHELLS {
            for offset in shell::<D>(r) {
                let t: [L::U; D] = per_axis(|a| words::<L>(a, &cell[a], offset[a], at.period.map(|p| p[a])));
                let gaps: [L::F; D] = per_axis(|a| {
                    let o = offset[a];
                    if o > 0 {
                        L::sub(L::f(o as f32 * UNIT), at.f[a])
                    } else if o < 0 {
                        L::sub(at.f[a], L::f((o + 1) as f32 * UNIT))
                    } else {
                        L::f(0.0)
                    }
                });
                let needs = L::and(open, may_enter::<L, IDS>(metric.rank::<L, D>(&gaps), best.rank[N - 1]));
                if L::any(needs) {
                    let sh: [L::F; D] = per_axis(|a| L::sub(at.f[a], L::f(offset[a] as f32 * UNIT)));
                    self.visit::<L, M, IDS, DELTAS>(metric, self.hash::<L>(t), sh, needs, best);
                }
            }
            let edge = metric.rank_of_distance::<L>(outside::<L, D>(&at.f, r as f32 * UNIT));
            open = L::and(open, may_enter::<L, IDS>(edge, best.rank[N - 1]));
            if !L::any(open) {
                return;
            }
        }
        // Uncertified after MAX_SHELLS (never seen for valid configurations):
        // NaN rather than a possibly wrong value.
        for k in 0..N {
            best.rank[k] = L::select(open, L::f(f32::NAN), best.rank[k]);
        }
    }

    /// The cell hash (see [`definition`](crate::definition)) in u32 lanes,
    /// from the cell's axis words.
    #[inline(always)]
    fn hash<L: Lanes>(&self, words: [L::U; D]) -> L::U {
        let mut h = L::u(self.pattern.keys().init);
        for (a, t) in words.iter().enumerate() {
            h = axis_round::<L>(h, *t, a);
        }
        let mut sum = L::u(0);
        for w in &words[..D - 1] {
            sum = L::u_add(sum, *w);
        }
        self.hash_finish::<L>(h, sum)
    }

    /// The hash's last step, from the chain `h` after its axis rounds and
    /// the sum of the words of axes 0..d − 1: the sum added (modulo 2^32,
    /// so the same in any order), the finishing key, MurmurHash3's mix.
    #[inline(always)]
    fn hash_finish<L: Lanes>(&self, h: L::U, sum: L::U) -> L::U {
        fmix32::<L>(L::u_xor(L::u_add(h, sum), L::u(self.pattern.keys().finish)))
    }

    /// The hashes of the lanes' 2^d blocks: [`Simd::hash`] of cell c, which
    /// takes on axis a the near neighbour's word (`terms[a][0]`) where bit a
    /// of c is set and the own column's (`terms[a][1]`) where it is clear.
    /// The chain's round for axis a reads the words of axes 0..=a only, so
    /// the 2^d chains share their first rounds as a tree: 2 + 4 + … + 2^d
    /// rounds instead of d·2^d, and the sum of the words added after the
    /// rounds (a sum modulo 2^32, so in any order) is shared the same way.
    #[inline(always)]
    fn block_hashes<L: Lanes>(&self, terms: &[[L::U; 3]; D]) -> [L::U; 16] {
        let mut h = [L::u(self.pattern.keys().init); 16];
        let mut sum = [L::u(0); 16];
        for (a, words) in terms.iter().enumerate() {
            // Cells below 2^a hold the chains over axes 0..a; each splits in
            // two on axis a, its own column (bit a clear) and the near one.
            for c in 0..1usize << a {
                let (base, s) = (h[c], sum[c]);
                for near in 0..2 {
                    let t = words[1 - near];
                    let at = c | near << a;
                    h[at] = axis_round::<L>(base, t, a);
                    sum[at] = if a + 1 < D { L::u_add(s, t) } else { s };
                }
            }
        }
        for c in 0..1usize << D {
            h[c] = self.hash_finish::<L>(h[c], sum[c]);
        }
        h
    }

    /// Visits one cell for the lanes in `needs`: `h` is its hash, `shifted`
    /// the sample minus the cell's corner, per lane.
    #[inline(always)]
    fn visit<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        h: L::U,
        shifted: [L::F; D],
        needs: L::M,
        best: &mut Best<L, D, N>,
    ) {
        // Points are produced in index order while some lane that needs the
        // cell has one more.
        let top = self.population::<L>(h);
        for p in &self.points {
            let active = L::and(needs, L::lt(self.key::<L>(p), top));
            if !L::any(active) {
                break;
            }
            self.point::<L, M, IDS, DELTAS>(metric, p, h, shifted, active, best);
        }
    }

    /// What a cell's points are tested against, from its hash `h`: the
    /// state's top byte, exact in f32, for a sorted table (point j exists
    /// where its threshold is below it), or the population itself for an
    /// unsorted one (point j exists where j is below it). See
    /// [`Simd::key`].
    #[inline(always)]
    fn population<L: Lanes>(&self, h: L::U) -> L::F {
        let top = L::u24_to_f(L::u_shr24(h));
        if self.sorted {
            top
        } else {
            self.counts::<L>(top)
        }
    }

    /// Point `p`'s side of the existence test against [`Simd::population`]:
    /// its threshold, or its index for an unsorted table.
    #[inline(always)]
    fn key<L: Lanes>(&self, p: &PointConstants<D>) -> L::F {
        L::f_load(&p.wide.key.0)
    }

    /// Point `p` of the cell with hash `h` (`shifted` is the sample minus
    /// the cell's corner) inserted in the lanes of `active`; the others get
    /// rank +∞ and [`INVALID_ID`], which change nothing.
    #[inline(always)]
    fn point<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        p: &PointConstants<D>,
        h: L::U,
        shifted: [L::F; D],
        active: L::M,
        best: &mut Best<L, D, N>,
    ) {
        let delta = Self::delta_of::<L>(p, h, shifted);
        let rank = L::select(active, metric.rank::<L, D>(&delta), L::f(f32::INFINITY));
        let id = if IDS {
            // Lanes without the point carry INVALID_ID, which loses every
            // tie.
            L::select_u(active, Self::id_of::<L>(p, h), L::u(INVALID_ID))
        } else {
            L::u(0)
        };
        best.insert::<IDS, DELTAS>(rank, delta, id);
    }

    /// The sample minus point `p` of the cell with hash `h`, in lane units
    /// (`shifted` is the sample minus the cell's corner): every path that
    /// meets a point computes its delta here, so the same point gives the
    /// same bits whichever path, cell order or lane meets it.
    #[inline(always)]
    fn delta_of<L: Lanes>(p: &PointConstants<D>, h: L::U, shifted: [L::F; D]) -> [L::F; D] {
        let c = Self::coordinates_of::<L>(p, h);
        // A loop, not a closure: in the run-time AVX-512 copy a closure here
        // stayed an out-of-line call without its instructions (`per_axis`).
        let mut delta = shifted;
        for (d, c) in delta.iter_mut().zip(c) {
            *d = L::sub(*d, L::u24_to_f(c));
        }
        delta
    }

    /// Point `p` of the cell with hash `h` in the cell: its 24-bit
    /// fixed-point coordinates, each below 2^24 (lane units).
    #[inline(always)]
    fn coordinates_of<L: Lanes>(p: &PointConstants<D>, h: L::U) -> [L::U; D] {
        let mut c = [L::u(0); D];
        for (a, c) in c.iter_mut().enumerate() {
            let (am, cm) = &p.wide.coordinate[a];
            *c = L::u_shr8(L::u_add(L::u_mul(h, L::u_load(&am.0)), L::u_load(&cm.0)));
        }
        c
    }

    /// The ID of point `p` of the cell with hash `h`. The sentinel state is
    /// reported as INVALID_ID − 1 (`definition::feature_id`): an unsigned
    /// minimum.
    #[inline(always)]
    fn id_of<L: Lanes>(p: &PointConstants<D>, h: L::U) -> L::U {
        let (am, cm) = &p.wide.id;
        L::u_min(L::u_add(L::u_mul(h, L::u_load(&am.0)), L::u_load(&cm.0)), L::u(INVALID_ID - 1))
    }

    /// Populations of an unsorted (bumped) table: a lookup per lane.
    #[inline(never)]
    fn counts<L: Lanes>(&self, top: L::F) -> L::F {
        let mut c = [0f32; WIDEST];
        L::f_store(top, &mut c[..L::N]);
        for v in c.iter_mut().take(L::N) {
            *v = f32::from(self.table[*v as usize]);
        }
        L::f_load(&c[..L::N])
    }
}

/// The 3^d block in the mirrored frame (−1 is the near side), ordered by the
/// number of far axes, then of near axes: own cell, the near cells, then the
/// far ones.
fn logical_block<const D: usize>() -> Vec<[i64; D]> {
    let mut block = shell::<D>(1);
    block.push([0; D]);
    block.sort_by_key(|o| {
        let far = o.iter().filter(|&&v| v > 0).count();
        let near = o.iter().filter(|&&v| v < 0).count();
        (far, near, *o)
    });
    block
}

/// Per-lane axis words of axis `axis` of the cells at `offset` from `cell`,
/// wrapped into [0, period) when the pattern is periodic.
#[inline(always)]
fn words<L: Lanes>(axis: usize, cell: &[i64; WIDEST], offset: i64, period: Option<i64>) -> L::U {
    let mut t = [0u32; WIDEST];
    for (ti, c) in t.iter_mut().zip(cell).take(L::N) {
        let c = c.wrapping_add(offset);
        *ti = axis_term(match period {
            Some(p) => c.rem_euclid(p),
            None => c,
        });
    }
    word::<L>(axis, L::u_load(&t[..L::N]))
}

/// One axis round of the cell hash's chain in lanes: the axis word `t`
/// enters, axis `axis`'s multiplier, a shift-xor.
#[inline(always)]
fn axis_round<L: Lanes>(h: L::U, t: L::U, axis: usize) -> L::U {
    let x = L::u_mul(L::u_xor(h, t), L::u(AXIS_MUL[axis]));
    L::u_xor(x, L::u_shr16(x))
}

/// MurmurHash3's finaliser in lanes ([`definition::fmix32`](crate::definition::fmix32)).
#[inline(always)]
fn fmix32<L: Lanes>(mut h: L::U) -> L::U {
    h = L::u_xor(h, L::u_shr16(h));
    h = L::u_mul(h, L::u(0x85EB_CA6B));
    h = L::u_xor(h, L::u_shr13(h));
    h = L::u_mul(h, L::u(0xC2B2_AE35));
    L::u_xor(h, L::u_shr16(h))
}

/// An axis word in lanes ([`axis_word`](crate::definition::axis_word)): the raw axis term `t` mixed on its
/// own.
#[inline(always)]
fn word<L: Lanes>(axis: usize, t: L::U) -> L::U {
    fmix32::<L>(L::u_xor(t, L::u(AXIS_MUL[axis])))
}

impl<L: Lanes, const D: usize, const N: usize> Best<L, D, N> {
    /// No candidate yet: ranks +∞, zero deltas, [`INVALID_ID`].
    #[inline(always)]
    fn empty() -> Self {
        Best { rank: [L::f(f32::INFINITY); N], delta: [[L::f(0.0); D]; N], id: [L::u(INVALID_ID); N] }
    }

    /// Back to [`Best::empty`], writing only what the outputs use (the
    /// others are never changed from it).
    #[inline(always)]
    fn reset<const IDS: bool, const DELTAS: bool>(&mut self) {
        self.rank = [L::f(f32::INFINITY); N];
        if IDS {
            self.id = [L::u(INVALID_ID); N];
        }
        if DELTAS {
            self.delta = [[L::f(0.0); D]; N];
        }
    }

    /// Inserts one candidate per lane (rank +∞ in lanes that have none).
    /// With IDs the order is the crate's canonical one, rank then ID (see
    /// [`reference`](crate::reference)), so the result does not depend on
    /// the order points arrive in; a lane without a candidate must then
    /// carry [`INVALID_ID`], which nothing precedes. Without IDs only the
    /// sorted ranks are reported, and those do not depend on the order.
    #[inline(always)]
    fn insert<const IDS: bool, const DELTAS: bool>(&mut self, rank: L::F, delta: [L::F; D], id: L::U) {
        let (mut r, mut d, mut i) = (rank, delta, id);
        if !IDS && !DELTAS {
            // The same choice as below, as a minimum and a maximum.
            for k in 0..N {
                let kept = self.rank[k];
                self.rank[k] = L::min(kept, r);
                r = L::max(r, kept);
            }
            return;
        }
        for k in 0..N {
            let lt = if IDS {
                L::or(L::lt(r, self.rank[k]), L::and(L::eq(r, self.rank[k]), L::u_lt(i, self.id[k])))
            } else {
                L::lt(r, self.rank[k])
            };
            let kept = self.rank[k];
            self.rank[k] = L::select(lt, r, kept);
            r = L::select(lt, kept, r);
            if DELTAS {
                for (slot, cand) in self.delta[k].iter_mut().zip(d.iter_mut()) {
                    let kept = *slot;
                    *slot = L::select(lt, *cand, kept);
                    *cand = L::select(lt, kept, *cand);
                }
            }
            if IDS {
                let kept = self.id[k];
                self.id[k] = L::select_u(lt, i, kept);
                i = L::select_u(lt, kept, i);
            }
        }
    }
}

/// Whether a candidate at rank `bound` or beyond may still enter the list
/// whose last rank is `last`: strictly below without IDs, and also at equal
/// rank with IDs, where a tie is decided by the ID.
#[inline(always)]
fn may_enter<L: Lanes, const IDS: bool>(bound: L::F, last: L::F) -> L::M {
    if IDS {
        L::le(bound, last)
    } else {
        L::lt(bound, last)
    }
}

/// B_r per lane: distance from the sample to the outside of the block of
/// Chebyshev radius r.
#[inline(always)]
fn outside<L: Lanes, const D: usize>(f: &[L::F; D], r: f32) -> L::F {
    let mut b = L::f(f32::INFINITY);
    for fa in f {
        b = L::min(b, L::min(L::add(*fa, L::f(r)), L::sub(L::f(r + UNIT), *fa)));
    }
    b
}

fn distance_of_rank<L: Lanes>(metric: Metric, r: L::F) -> L::F {
    match metric {
        Metric::Euclidean => L::sqrt(r),
        Metric::Manhattan | Metric::Chebyshev | Metric::Minkowski(_) => r,
    }
}

fn mark_invalid<L: Lanes, const D: usize, const N: usize>(best: &mut Best<L, D, N>, valid: &[bool; WIDEST]) {
    let mut bad = [0f32; WIDEST];
    for (b, v) in bad.iter_mut().zip(valid) {
        *b = if *v { 0.0 } else { 1.0 };
    }
    let bad = L::lt(L::f(0.5), L::f_load(&bad[..L::N]));
    for k in 0..N {
        best.rank[k] = L::select(bad, L::f(f32::NAN), best.rank[k]);
        best.id[k] = L::select_u(bad, L::u(INVALID_ID), best.id[k]);
        for a in 0..D {
            best.delta[k][a] = L::select(bad, L::f(f32::NAN), best.delta[k][a]);
        }
    }
}

/// Applies a scalar function of D lanes' values to every lane.
#[inline(always)]
fn per_lane<L: Lanes, const D: usize>(v: &[L::F; D], f: impl Fn([f32; D]) -> f32) -> L::F {
    let mut a = [[0f32; WIDEST]; D];
    for (lanes, x) in a.iter_mut().zip(v) {
        L::f_store(*x, &mut lanes[..L::N]);
    }
    let mut out = [0f32; WIDEST];
    for (i, o) in out.iter_mut().enumerate().take(L::N) {
        *o = f(std::array::from_fn(|k| a[k][i]));
    }
    L::f_load(&out[..L::N])
}

/// Lane `i` of an 8-lane result.
pub fn lane<const D: usize, const N: usize>(r: &Features8<D, N>, i: usize) -> Features32<D, N> {
    Features32 {
        distance: r.distance.map(|v| v.to_array()[i]),
        delta: r.delta.map(|d| d.map(|v| v.to_array()[i])),
        id: r.id.map(|v| v.to_array()[i]),
    }
}

/// A metric in lanes; the rank is the reference's (squared distance for
/// Euclidean, the distance itself otherwise): the fold of one term per axis.
pub trait Metric32: Copy {
    /// One axis's term of the rank: x², |x| or |x|^p.
    fn term<L: Lanes>(&self, x: L::F) -> L::F;
    /// Combines two partial ranks: a sum, or a maximum for Chebyshev.
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F;
    /// [`Metric32::fold`] of the value in `a[k]` (in every lane) and `b`, the
    /// same bits; a sum is computed by [`Lanes::broadcast_add_on_fma`]
    /// (`one` is 1 in every lane).
    #[inline(always)]
    fn fold_on_fma<L: Lanes>(&self, (a, k): (&[Cell<f32>; WIDEST], usize), b: L::F, one: L::F) -> L::F {
        let _ = one;
        self.fold::<L>(L::f(a[k].get()), b)
    }
    /// Rank of a length.
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F;
    /// Whether [`Metric32::rank`] is, bit for bit, axis 0's term folded
    /// into [`Metric32::rest`]: then a row of samples along axis 0 shares
    /// the rest of every candidate (the coherent path relies on it).
    const SPLITS: bool = true;
    /// Rank of a vector: the terms of axes 1, 2, … folded in order
    /// ([`Metric32::rest`]), then axis 0's term folded in last.
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let first = self.term::<L>(v[0]);
        if D == 1 {
            return first;
        }
        self.fold::<L>(self.rest::<L, D>(v), first)
    }
    /// The terms of axes 1, 2, … folded in order; `v[0]` is not read.
    /// Needs D ≥ 2.
    #[inline(always)]
    fn rest<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let mut s = self.term::<L>(v[1]);
        for x in &v[2..] {
            s = self.fold::<L>(s, self.term::<L>(*x));
        }
        s
    }
}

/// Euclidean in lanes.
#[derive(Clone, Copy, Debug)]
pub struct Euclid;
/// Manhattan in lanes.
#[derive(Clone, Copy, Debug)]
pub struct Manhattan;
/// Chebyshev in lanes.
#[derive(Clone, Copy, Debug)]
pub struct Chebyshev;
/// Minkowski in lanes: the rank is the distance itself, computed per lane in
/// f64 scaled by the largest component (see [`Metric::rank`]), so that no
/// power overflows or underflows for any p ≥ 1, and rounded to f32 once.
#[derive(Clone, Copy, Debug)]
pub struct Minkowski(pub f64);

impl Metric32 for Euclid {
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::mul(x, x)
    }
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        L::add(a, b)
    }
    #[inline(always)]
    fn fold_on_fma<L: Lanes>(&self, (a, k): (&[Cell<f32>; WIDEST], usize), b: L::F, one: L::F) -> L::F {
        L::broadcast_add_on_fma(a, k, b, one)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        L::mul(d, d)
    }
}

impl Metric32 for Manhattan {
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::abs(x)
    }
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        L::add(a, b)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
}

impl Metric32 for Chebyshev {
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::abs(x)
    }
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        L::max(a, b)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
}

impl Metric32 for Minkowski {
    /// The rank is computed from the whole vector at once.
    const SPLITS: bool = false;
    #[inline(always)]
    fn term<L: Lanes>(&self, x: L::F) -> L::F {
        L::abs(x)
    }
    /// The Lp length of the pair (a, b), each itself an Lp length of some
    /// axes, so folding the axes' terms in order gives the vector's length.
    #[inline(always)]
    fn fold<L: Lanes>(&self, a: L::F, b: L::F) -> L::F {
        let p = self.0;
        per_lane::<L, 2>(&[a, b], |v| Metric::Minkowski(p).rank(&v.map(f64::from)) as f32)
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let p = self.0;
        per_lane::<L, D>(v, |v| Metric::Minkowski(p).rank(&v.map(f64::from)) as f32)
    }
}

impl<const N: usize> Simd<2, N> {
    /// One point given as a `glam::Vec2`.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<2, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// assert!(basis.evaluate_vec2(glam::Vec2::new(0.5, 0.25)).distance[0] >= 0.0);
    /// ```
    pub fn evaluate_vec2(&self, p: glam::Vec2) -> Features32<2, N> {
        self.evaluate_f32(p.to_array())
    }
}

impl<const N: usize> Simd<3, N> {
    /// One point given as a `glam::Vec3`.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let p = glam::Vec3::new(0.5, 0.25, 4.0);
    /// assert_eq!(basis.evaluate_vec3(p).distance, basis.evaluate_vec3a(p.into()).distance);
    /// ```
    pub fn evaluate_vec3(&self, p: glam::Vec3) -> Features32<3, N> {
        self.evaluate_f32(p.to_array())
    }

    /// One point given as a `glam::Vec3A`.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// assert!(basis.evaluate_vec3a(glam::Vec3A::new(1.0, 2.0, 3.0)).distance[0] >= 0.0);
    /// ```
    pub fn evaluate_vec3a(&self, p: glam::Vec3A) -> Features32<3, N> {
        self.evaluate_f32(p.to_array())
    }

    /// Eight points given as `glam::Vec3`s.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// let points: [glam::Vec3; 8] = std::array::from_fn(|i| glam::Vec3::new(i as f32 * 0.25, 1.0, 2.0));
    /// let f = basis.evaluate8_vec3(&points);
    /// assert_eq!(f.distance[0].to_array()[5], basis.evaluate_vec3(points[5]).distance[0]);
    /// ```
    pub fn evaluate8_vec3(&self, p: &[glam::Vec3; 8]) -> Features8<3, N> {
        self.evaluate8(&p.map(|v| v.to_array().map(f64::from)))
    }
}

impl<const N: usize> Simd<4, N> {
    /// One point given as a `glam::Vec4`.
    ///
    /// ```
    /// use worley::{Config, Outputs, Simd};
    /// let basis = Simd::<4, 1>::new(Config::default(), Outputs::Distances).unwrap();
    /// assert!(basis.evaluate_vec4(glam::Vec4::new(0.5, 0.25, 4.0, -1.0)).distance[0] >= 0.0);
    /// ```
    pub fn evaluate_vec4(&self, p: glam::Vec4) -> Features32<4, N> {
        self.evaluate_f32(p.to_array())
    }
}

/// The AVX2 recompilation of a default build against the code that build
/// would run without it. Every other test of the 8-lane kernel in such a
/// build goes through whichever of the two the CPU selects; this one keeps
/// the other bit for bit equal to it.
/// Point i of a seeded set, uniform in [−range, range]^D, for the tests of
/// the run-time copies (`runtime_avx2_tests`, `avx512::tests`,
/// `border::runtime_avx2_tests`).
#[cfg(all(test, target_arch = "x86_64", not(target_feature = "avx512f")))]
fn sample_point<const D: usize>(seed: u64, i: usize, range: f64) -> [f64; D] {
    std::array::from_fn(|a| (2.0 * crate::math::uniform(seed, (i * D + a) as u64) - 1.0) * range)
}

/// Batch `batch` of eight points for the tests of the run-time AVX2
/// copies: ordinary points, points beyond 2^31 cells in some lanes (the
/// lane-wise locate) and, in every seventh batch, a NaN lane among good ones.
#[cfg(all(test, target_arch = "x86_64", not(target_feature = "avx2")))]
fn test_batch<const D: usize>(seed: u64, batch: usize) -> [[f64; D]; 8] {
    let range = [40.0, 3.0e10][batch % 2];
    let mut points: [[f64; D]; 8] = std::array::from_fn(|i| sample_point(seed, batch * 8 + i, range));
    if batch.is_multiple_of(7) {
        points[batch % 8][0] = f64::NAN;
    }
    points
}

#[cfg(all(test, target_arch = "x86_64", not(target_feature = "avx2")))]
mod runtime_avx2_tests {
    use super::*;

    fn same<const D: usize, const N: usize>(config: Config) {
        if !runtime_avx2() {
            eprintln!("this CPU has no AVX2: only the SSE2 kernel exists to test");
            return;
        }
        for outputs in [Outputs::Distances, Outputs::Ids, Outputs::IdsAndDeltas] {
            let kernel = Simd::<D, N>::new(config, outputs).unwrap();
            let mut lanewise = 0;
            for batch in 0..1500 {
                let points = test_batch::<D>(11, batch);
                let located = kernel.locate::<Eight>(&points);
                lanewise += usize::from(matches!(located.cells, Cells::Full(_)));
                let plain = kernel.dispatch::<Eight>(&located);
                // SAFETY: `runtime_avx2` returned true above.
                #[allow(unsafe_code)]
                let avx2 = unsafe { kernel.dispatch_avx2::<WHOLE>(&located, Best::empty()).0 };
                for k in 0..N {
                    let what = format!("{outputs:?} F{} at batch {batch}", k + 1);
                    let bits = |v: f32x8| v.to_array().map(f32::to_bits);
                    assert_eq!(bits(plain.rank[k]), bits(avx2.rank[k]), "{what}: distances");
                    assert_eq!(plain.id[k].to_array(), avx2.id[k].to_array(), "{what}: ids");
                    for a in 0..D {
                        assert_eq!(bits(plain.delta[k][a]), bits(avx2.delta[k][a]), "{what}: deltas");
                    }
                }
            }
            assert!(lanewise >= 700, "only {lanewise} of 1500 batches took the lane-wise locate");
        }
    }

    #[test]
    fn the_avx2_recompilation_gives_the_sse2_bits() {
        // Euclidean only: the other metrics run the same out-of-line code
        // (`search_outputs`) in both copies.
        same::<2, 3>(Config { order: 3, ..Config::default() });
        same::<3, 1>(Config::default());
        same::<3, 4>(Config { order: 4, ..Config::default() });
        same::<4, 2>(Config { order: 2, ..Config::default() });
        same::<2, 8>(Config { order: 8, density: 0.5, ..Config::default() });
        same::<3, 2>(Config { order: 2, mode: Mode::Window, ..Config::default() });
        same::<3, 2>(Config { order: 2, bump: 0.5, ..Config::default() });
    }
}
