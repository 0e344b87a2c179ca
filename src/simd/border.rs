//! # The distance to the border of the sample's cell, in lanes
//!
//! The same quantity as [`Reference::border`](crate::Reference::border)
//! (read its [module's text](crate::reference::border) for the geometry
//! and the certification), computed in f32 lanes eight samples at a time.
//!
//! ## How
//! 1. **F1 with its delta and ID**: the SIMD kernel's own search
//!    ([`Simd`] of order 1, IDs and deltas), so F1 is the kernel's, bit for
//!    bit, and its exactness is the kernel's.
//! 2. **F1's point as integers**: the point of F1's ID whose delta has F1's
//!    bits is met again: first in the one cell where the sample minus F1's
//!    delta falls, then, in the lanes where it was not there (a point beyond
//!    the neighbouring cells, or one that rounding put across a face), among
//!    the cells no farther than F1. Its position relative to the sample's
//!    cell is kept as integers in lane units (2^−24 cells): a cell's corner
//!    plus the point's 24-bit coordinates, exact in i32.
//! 3. **The border search**: every lane visits its own cell, then the rest
//!    of the 3^d block near side first (the kernel's mirrored frame), then
//!    Chebyshev shells, each cell only for the lanes whose F1 + 2b reaches
//!    it, until the outside of the block covered is beyond F1 + 2b in every
//!    lane; a point's plane is computed only where some lane has the point
//!    itself within F1 + 2b (no point beyond can hold the nearest plane:
//!    at distance d_j, its b_j is at least (d_j − F1)/2 > b). For each
//!    point p_j, u = p_j − p₁ is the exact integer difference rounded once
//!    to f32, and b_j = k_j / (2|u|) with k_j = −u·(δ₁ + δ_j) and δ the
//!    sample minus the point: no difference of squared distances, whose
//!    cancellation near the border would cost digits, and no normal tilted
//!    by rounding when two points lie close together (where F2 − F1 draws
//!    its wedges). Planes are compared as k_j²·|u|² < k²·|u_j|² in cells²,
//!    all terms non-negative, so no point costs a square root or a
//!    division; b itself is taken once per cell, for the skip test.
//!
//! In [`Mode::Window`](crate::Mode::Window) both searches stop at the 3^d block, as the
//! reference's window mode does.
//!
//! Every delta comes from the one routine the kernel uses for every point
//! it meets, and a cell enters it the same way in every stage, so the
//! search meets F1's point with F1's bits; u = 0 exactly for it and for a
//! point at its very position, which are skipped (they share one cell, as
//! in the reference).
//!
//! ## Bits
//! Each lane's result depends on that lane alone, through IEEE operations
//! that are the same in every build (add, subtract, multiply, divide,
//! square root, compare, select): [`SimdBorder::border`], the eight-lane,
//! slice, grid, large-world and periodic entry points give a point the
//! same bits, in the default and the AVX2 and AVX-512 builds.
//!
//! ## Error
//! δ in f32 carries a few roundings of the sample's distance to the point,
//! and u one rounding of its length, so b is within
//! 4ε_f32·(2·F1 + 2·b + 1/S) of the f64 reference (S the pattern's scale),
//! and the normal within a few ε_f32; the neighbour is the reference's
//! except where two planes lie that close. `tests/lanes/border.rs`
//! measures both: at most 0.18 of that bound and 1.4·10^−7 on the normal,
//! over random samples in 2D, 3D and 4D, lattice values, sparse points,
//! window mode and samples around pairs of points 10^−3 cells apart. The
//! skip and stop tests carry a relative slack of 2^−12 on the side of
//! visiting more, far above that rounding, so no plane the reference could
//! pick is left unvisited.
//!
//! ## Grids
//! [`SimdBorder::border_grid`] and [`SimdBorder::border_grid_parallel`]
//! (and textures of the border on grids) take the grid tiles where
//! [`Simd::coherent_grid`] does: F1 from the tiles' search, then F1's
//! point and the nearest plane from the points of the band's cells,
//! broadcast to the tile's lanes (`border/tiles.rs` has the argument for
//! the bits and the certificate). The nearest plane is the first in one
//! total order of the points (see `Plane::offer`), so the tiles and the
//! per-sample search, which meet the points in different orders, choose
//! the same plane.
//!
//! ## Speed
//! On scattered samples one border costs about 4 F2 − F1 evaluations (F1,
//! then a search that reaches F1 + 2b, farther than F2, over the union of
//! the cells the eight lanes need; finding F1's point again is one cell in
//! nearly every lane, and a point's plane is skipped where no lane has it
//! within reach); about 3 on a frame's hits in pixel order, whose packets
//! of neighbouring pixels share most of their cells; on a grid about 5.6
//! through the tiles (23 to 32 per sample before). The peers bench
//! (`peers/`) reports it beside F2 − F1 on each workload.

use wide::{f32x8, u32x8};

pub mod nsphere;
mod search;
pub mod smooth;
mod tiles;

pub use nsphere::{NSphere32, NSphere8, SimdNSphere};
pub use smooth::{SimdSmooth, Smooth32, Smooth8};

use super::batch::in_cell;
use super::best::Best;
use super::coherent::GridRows;
use super::generate::UNIT;
use super::lanes::{Eight, Lanes, One, WIDEST};
use super::locate::Located;
use super::periodic::wrap;
use super::{by_eights, per_axis, Grid, Outputs, Period, Point, Simd, SizeError};
use crate::config::{Config, ConfigError, Metric};
use crate::definition::INVALID_ID;

/// Relative slack of the skip and stop tests (see the module's text).
const SLACK: f32 = 1.0 + 1.0 / 4096.0;

/// The border of one sample's cell, in f32: the f32 counterpart of
/// [`Border`](crate::Border).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Border32<const D: usize> {
    /// The distance to the nearest bisector plane, user units; NaN for bad
    /// input, +∞ in window mode when the 3^d block holds fewer than two
    /// points.
    pub distance: f32,
    /// The unit normal of that plane, pointing into the sample's cell: the
    /// gradient of `distance`. NaN where `distance` is not finite.
    pub normal: [f32; D],
    /// The ID of F1's point, whose cell holds the sample.
    pub feature: u32,
    /// The ID of the point across the nearest border.
    pub neighbour: u32,
}

/// The borders of eight samples, one per lane.
#[derive(Clone, Copy, Debug)]
pub struct Border8<const D: usize> {
    /// Distances to the nearest bisector plane.
    pub distance: f32x8,
    /// Unit normals per axis.
    pub normal: [f32x8; D],
    /// IDs of F1's points.
    pub feature: u32x8,
    /// IDs of the points across the nearest borders.
    pub neighbour: u32x8,
}

/// No border found: distance +∞, normal NaN, [`INVALID_ID`] for both IDs
/// (what a window-mode search reports when its block holds fewer than two
/// points). A value to fill the buffers of the slice and grid calls with.
impl<const D: usize> Default for Border32<D> {
    fn default() -> Self {
        Border32 { distance: f32::INFINITY, normal: [f32::NAN; D], feature: INVALID_ID, neighbour: INVALID_ID }
    }
}

/// Every lane [`Border32::default`].
impl<const D: usize> Default for Border8<D> {
    fn default() -> Self {
        Border8 {
            distance: f32x8::splat(f32::INFINITY),
            normal: [f32x8::splat(f32::NAN); D],
            feature: u32x8::splat(INVALID_ID),
            neighbour: u32x8::splat(INVALID_ID),
        }
    }
}

impl<const D: usize> Border8<D> {
    /// Lane `i` (0..8).
    pub fn lane(&self, i: usize) -> Border32<D> {
        Border32 {
            distance: self.distance.to_array()[i],
            normal: self.normal.map(|v| v.to_array()[i]),
            feature: self.feature.to_array()[i],
            neighbour: self.neighbour.to_array()[i],
        }
    }

    /// Every lane.
    pub fn lanes(&self) -> [Border32<D>; 8] {
        std::array::from_fn(|i| self.lane(i))
    }

    /// One sample's border in all eight lanes.
    pub fn splat(b: &Border32<D>) -> Self {
        Border8 {
            distance: f32x8::splat(b.distance),
            normal: b.normal.map(f32x8::splat),
            feature: u32x8::splat(b.feature),
            neighbour: u32x8::splat(b.neighbour),
        }
    }
}

/// The distance to the border of the sample's Voronoi cell, eight samples
/// at a time (see the [module's text](self)). Euclidean only.
///
/// ```
/// use worley::{Config, Outputs, Simd, SimdBorder};
/// let border = SimdBorder::<3>::new(Config::default()).unwrap();
/// let f = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::Ids).unwrap();
/// let x = [0.3, -2.0, 7.5];
/// let (b, f) = (border.border(x), f.evaluate(x));
/// // Every bisector is at least (F2 − F1) / 2 away, and the nearest is no
/// // farther than F2's.
/// assert!(b.distance >= 0.5 * (f.distance[1] - f.distance[0]) * (1.0 - 1e-5));
/// assert_eq!(b.feature, f.id[0]);
/// ```
#[derive(Clone, Debug)]
pub struct SimdBorder<const D: usize> {
    /// F1 with its delta and ID.
    kernel: Simd<D, 1>,
}

/// The running nearest plane per lane, in lane units.
struct Plane<L: Lanes, const D: usize> {
    /// k = max(−u·(δ₁ + δ_j), 0) in cells² (b = k / (2|u|)); +∞ before any
    /// plane.
    key: L::F,
    /// |u|² in cells².
    uu: L::F,
    /// u = p_j − p₁ in lane units: the normal before scaling.
    u: [L::F; D],
    /// The ID of p_j.
    id: L::U,
}

/// 2^−48: lane units² to cells², exactly.
const CELLS2: f32 = 1.0 / (1u64 << 48) as f32;

/// Products of the plane test at least this large are normal f32 numbers
/// with their relative rounding (see [`Plane::offer`]).
const NORMAL: f32 = 1.0 / (1u128 << 100) as f32;
/// 1 − 2^−20: products this far apart keep their order through rounding.
const APART: f32 = 1.0 - 1.0 / (1 << 20) as f32;

impl<L: Lanes, const D: usize> Plane<L, D> {
    /// No plane yet: b = +∞.
    #[inline(always)]
    fn none() -> Self {
        Plane { key: L::f(f32::INFINITY), uu: L::f(1.0), u: [L::f(0.0); D], id: L::u(INVALID_ID) }
    }

    /// b = k / (2|u|) in lane units (+∞ before any plane).
    #[inline(always)]
    fn distance(&self) -> L::F {
        L::mul(L::div(self.key, L::sqrt(self.uu)), L::f(0.5 * UNIT))
    }

    /// A point's plane from `us` = u·(δ₁ + δ_j) and |u|² in lane units²,
    /// offered as [`Plane::offer`] does; u = 0 (F1's point itself, or one
    /// at its very position) is never taken.
    #[inline(always)]
    fn offer_point(&mut self, active: L::M, us: L::F, uu: L::F, u: [L::F; D], id: L::U) {
        // k = −u·(δ₁ + δ_j); a tie with a later ID may round to a hair
        // below zero. In cells², the products stay far inside f32's range.
        let key = L::mul(L::select(L::lt(us, L::f(0.0)), L::sub(L::f(0.0), us), L::f(0.0)), L::f(CELLS2));
        let uu = L::mul(uu, L::f(CELLS2));
        self.offer(L::and(active, L::lt(L::f(0.0), uu)), key, uu, u, id);
    }

    /// A point's plane (`key`, `uu` in cells², `u`, `id`) in the lanes of
    /// `active`, where it is nearer than the running one.
    ///
    /// The planes are ordered by the f64 value k²/|u|² (one rounding of
    /// exact f32 inputs) and then by ID: a total order in which every point
    /// has its own place, so the nearest plane does not depend on the order
    /// in which a search meets the points (the per-sample search and the
    /// grid tiles meet them in different orders). The
    /// f32 products k_j²·|u|² and k²·|u_j|² decide it where they lie more
    /// than 2^−20 apart and are normal: each carries two roundings of 2^−24,
    /// so the exact products, and the f64 ratios, are in the same order. The
    /// rare lanes closer than that are decided by the f64 ratios themselves.
    #[inline(always)]
    fn offer(&mut self, active: L::M, key: L::F, uu: L::F, u: [L::F; D], id: L::U) {
        let mine = L::mul(L::mul(key, key), self.uu);
        let theirs = L::mul(L::mul(self.key, self.key), uu);
        let below = L::and(L::lt(mine, L::mul(theirs, L::f(APART))), L::le(L::f(NORMAL), theirs));
        let above = L::and(L::lt(theirs, L::mul(mine, L::f(APART))), L::le(L::f(NORMAL), mine));
        let close = L::and(active, L::lt(L::select(L::or(below, above), L::f(1.0), L::f(0.0)), L::f(0.5)));
        let mut better = L::and(active, below);
        if L::any(close) {
            better = L::or(better, self.nearer_f64(close, key, uu, id));
        }
        self.key = L::select(better, key, self.key);
        self.uu = L::select(better, uu, self.uu);
        self.id = L::select_u(better, id, self.id);
        for (slot, ua) in self.u.iter_mut().zip(u) {
            *slot = L::select(better, ua, *slot);
        }
    }

    /// The lanes of `close` where the point's plane comes first in the
    /// order of [`Plane::offer`], by the f64 ratios and the IDs.
    #[cold]
    #[inline(never)]
    fn nearer_f64(&self, close: L::M, key: L::F, uu: L::F, id: L::U) -> L::M {
        let lanes = |v: L::F| {
            let mut a = [0f32; WIDEST];
            L::f_store(v, &mut a[..L::N]);
            a
        };
        let ids = |v: L::U| {
            let mut a = [0u32; WIDEST];
            L::u_store(v, &mut a[..L::N]);
            a
        };
        let (k, uu, id) = (lanes(key), lanes(uu), ids(id));
        let (pk, puu, pid) = (lanes(self.key), lanes(self.uu), ids(self.id));
        let ratio = |k: f32, uu: f32| f64::from(k) * f64::from(k) / f64::from(uu);
        let mut nearer = [0f32; WIDEST];
        for i in (0..L::N).filter(|&i| L::bits(close) & (1 << i) != 0) {
            let (mine, theirs) = (ratio(k[i], uu[i]), ratio(pk[i], puu[i]));
            if mine < theirs || (mine == theirs && id[i] < pid[i]) {
                nearer[i] = 1.0;
            }
        }
        L::lt(L::f(0.5), L::f_load(&nearer[..L::N]))
    }
}

impl<const D: usize> SimdBorder<D> {
    /// Builds the evaluator. Its order is 1 (F1's point and its nearest
    /// bisector), as the typed evaluators take theirs from their type:
    /// `config.order` is set to 1 whatever it held ([`Config::order`]).
    ///
    /// # Errors
    /// [`ConfigError::BorderMetric`] unless the metric is Euclidean, or the
    /// first other invalid field of `config`.
    ///
    /// ```
    /// use worley::{Config, ConfigError, Metric, SimdBorder};
    /// let manhattan = Config { metric: Metric::Manhattan, ..Config::default() };
    /// assert_eq!(SimdBorder::<2>::new(manhattan).unwrap_err(), ConfigError::BorderMetric(Metric::Manhattan));
    /// ```
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        if !matches!(config.metric, Metric::Euclidean) {
            return Err(ConfigError::BorderMetric(config.metric));
        }
        Ok(SimdBorder { kernel: Simd::new(Config { order: 1, ..config }, Outputs::IdsAndDeltas)? })
    }

    /// The configuration (order 1).
    pub fn config(&self) -> &Config {
        self.kernel.config()
    }

    /// One sample, through the kernel's one-lane instantiation: the bits of
    /// its lane in [`SimdBorder::border8`]. 3D: 0.9 M points/s, as fast as
    /// the f64 [`crate::Reference::border`] and half the per-point rate of
    /// [`SimdBorder::border_slice`] (1.9; `cargo bench --bench single`).
    pub fn border(&self, x: [f64; D]) -> Border32<D> {
        self.one(&self.kernel.locate::<One>(&[x]))
    }

    /// Eight samples, one per lane.
    ///
    /// ```
    /// use worley::{Config, SimdBorder};
    /// let border = SimdBorder::<2>::new(Config::default()).unwrap();
    /// let x: [[f64; 2]; 8] = std::array::from_fn(|i| [i as f64 * 0.7, -1.25]);
    /// assert_eq!(border.border8(&x).lane(5), border.border(x[5]));
    /// ```
    pub fn border8(&self, x: &[[f64; D]; 8]) -> Border8<D> {
        self.eight(&self.kernel.locate::<Eight>(x))
    }

    /// Eight samples as lanes per axis (each lane's f32 coordinates, as
    /// [`Simd::evaluate_lanes`] takes them).
    pub fn border_lanes(&self, x: [f32x8; D]) -> Border8<D> {
        let arrays = x.map(|v| v.to_array());
        self.border8(&std::array::from_fn(|i| std::array::from_fn(|a| f64::from(arrays[a][i]))))
    }

    /// One sample given as a cell and the fraction within it, as
    /// [`Simd::evaluate_in_cell`] takes it (bad input as there).
    pub fn border_in_cell(&self, cell: [i64; D], fraction: [f32; D]) -> Border32<D> {
        self.one(&in_cell::<One, D>(&[cell], &[fraction]))
    }

    /// Eight samples given as cells and fractions.
    pub fn border8_in_cell(&self, cells: &[[i64; D]; 8], fractions: &[[f32; D]; 8]) -> Border8<D> {
        self.eight(&in_cell::<Eight, D>(cells, fractions))
    }

    /// One sample of the periodic pattern, `x` in cells, as
    /// [`Simd::evaluate_periodic`] takes it.
    pub fn border_periodic(&self, x: [f64; D], period: &Period<D>) -> Border32<D> {
        self.one(&wrap::<One, D>(&[x], period))
    }

    /// Eight samples of the periodic pattern, `x` in cells.
    pub fn border8_periodic(&self, x: &[[f64; D]; 8], period: &Period<D>) -> Border8<D> {
        self.eight(&wrap::<Eight, D>(x, period))
    }

    /// Many points into a caller's buffer, eight at a time.
    ///
    /// # Errors
    /// [`SizeError`] if `out` is shorter than `xs`; nothing is written.
    pub fn border_slice<P: Point<D>>(&self, xs: &[P], out: &mut [Border32<D>]) -> Result<(), SizeError> {
        by_eights(xs, out, |block| self.border8(block).lanes())
    }

    /// Every point of a grid (axis 0 fastest), eight at a time on the
    /// calling thread.
    ///
    /// # Errors
    /// [`SizeError`] if `out.len() != grid.len()`; nothing is written.
    ///
    /// ```
    /// use worley::{Config, Grid, SimdBorder};
    /// let border = SimdBorder::<2>::new(Config::default()).unwrap();
    /// let grid = Grid { origin: [0.0, 0.0], step: [0.1, 0.1], size: [20, 10] };
    /// let mut out = vec![border.border([0.0; 2]); 200];
    /// border.border_grid(&grid, &mut out).unwrap();
    /// assert_eq!(out[47], border.border(grid.point(47)));
    /// ```
    pub fn border_grid(&self, grid: &Grid<D>, out: &mut [Border32<D>]) -> Result<(), SizeError> {
        let needed = grid.len().ok_or(SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(SizeError { needed, given: out.len() });
        }
        if self.kernel.grid_coherent(grid, out, false) {
            return Ok(());
        }
        grid.eights_into(0, out, |block| self.border8(block).lanes());
        Ok(())
    }

    /// [`SimdBorder::border_grid`] on all cores ([`Grid::fill_by_eights`]),
    /// with the same bits.
    ///
    /// # Errors
    /// [`SizeError`] if `out.len() != grid.len()`; nothing is written.
    #[cfg(feature = "parallel")]
    pub fn border_grid_parallel(&self, grid: &Grid<D>, out: &mut [Border32<D>]) -> Result<(), SizeError> {
        if grid.len() == Some(out.len()) && self.kernel.grid_coherent(grid, out, true) {
            return Ok(());
        }
        grid.fill_by_eights(out, |block| self.border8(block).lanes())
    }

    /// Rows `first..` of a located grid (whole rows), the bits
    /// [`SimdBorder::border_grid`] writes for them: a texture's octaves.
    pub(crate) fn grid_rows_into(&self, rows: &GridRows<'_, D>, first: usize, out: &mut [Border32<D>]) {
        self.kernel.grid_rows_into(rows, first, out)
    }

    /// Eight located lanes.
    fn eight(&self, at: &Located<Eight, D>) -> Border8<D> {
        eight_of(&self.kernel, at)
    }

    /// One located sample.
    fn one(&self, at: &Located<One, D>) -> Border32<D> {
        border_one(&self.kernel, at)
    }
}

/// Eight located lanes: F1 and the border search through the kernel's
/// eight-lane dispatch (its AVX2 copy where that runs).
pub(super) fn eight_of<const D: usize>(k: &Simd<D, 1>, at: &Located<Eight, D>) -> Border8<D> {
    let (_, _, raw) = k.dispatch8_whole(at);
    let (plane, found) = k.border_search8(at, &raw);
    let r = Results::<Eight, D>::of(k, k.good_lanes::<Eight>(at), &raw, &plane, found);
    Border8 { distance: r.distance, normal: r.normal, feature: r.feature, neighbour: r.neighbour }
}

/// One located sample, in the one-lane instantiation: the same operations
/// per lane as [`eight_of`], so the same bits.
pub(super) fn border_one<const D: usize>(k: &Simd<D, 1>, at: &Located<One, D>) -> Border32<D> {
    let (_, _, raw) = k.dispatch_one(at);
    let (plane, found) = k.border_search::<One>(at, &raw);
    let r = Results::<One, D>::of(k, k.good_lanes::<One>(at), &raw, &plane, found);
    Border32 { distance: r.distance, normal: r.normal, feature: r.feature, neighbour: r.neighbour }
}

/// [`Border8`]'s fields in any lane set.
struct Results<L: Lanes, const D: usize> {
    distance: L::F,
    normal: [L::F; D],
    feature: L::U,
    neighbour: L::U,
}

impl<L: Lanes, const D: usize> Results<L, D> {
    /// The border, its normal and the two IDs from F1 (`raw`, as the
    /// kernel holds it) and the nearest plane, in the lanes of `valid`
    /// (the others, and lanes without a number, NaN and [`INVALID_ID`]).
    #[inline(always)]
    fn of(k: &Simd<D, 1>, valid: L::M, raw: &Best<L, D, 1>, plane: &Plane<L, D>, found: L::M) -> Self {
        let b = plane.distance();
        // A comparison with NaN is false.
        let numbers = L::and(L::le(L::f(0.0), raw.rank[0]), L::le(L::f(0.0), b));
        let good = L::and(found, L::and(valid, numbers));
        let scale = L::mul(L::f(1.0 / UNIT), L::f(k.inv_scale));
        let distance = L::mul(b, scale);
        let length = L::mul(L::sqrt(plane.uu), L::f(UNIT));
        // No normal without a plane (+∞ in window mode with one point).
        let planar = L::and(good, L::lt(b, L::f(f32::INFINITY)));
        let normal = per_axis(|a| L::select(planar, L::div(L::neg(plane.u[a]), length), L::f(f32::NAN)));
        Results {
            distance: L::select(good, distance, L::f(f32::NAN)),
            normal,
            feature: L::select_u(good, raw.id[0], L::u(INVALID_ID)),
            neighbour: L::select_u(good, plane.id, L::u(INVALID_ID)),
        }
    }

    /// Every lane as a [`Border32`].
    #[inline(always)]
    fn lanes(&self) -> [Border32<D>; WIDEST] {
        let mut distance = [0f32; WIDEST];
        L::f_store(self.distance, &mut distance[..L::N]);
        let mut normal = [[0f32; WIDEST]; D];
        for (lanes, v) in normal.iter_mut().zip(self.normal) {
            L::f_store(v, &mut lanes[..L::N]);
        }
        let (mut feature, mut neighbour) = ([0u32; WIDEST], [0u32; WIDEST]);
        L::u_store(self.feature, &mut feature[..L::N]);
        L::u_store(self.neighbour, &mut neighbour[..L::N]);
        std::array::from_fn(|i| Border32 {
            distance: distance[i],
            normal: std::array::from_fn(|a| normal[a][i]),
            feature: feature[i],
            neighbour: neighbour[i],
        })
    }
}
