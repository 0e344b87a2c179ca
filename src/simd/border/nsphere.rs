//! # The n-sphere radius in lanes
//!
//! The same quantity as [`Reference::n_sphere`](crate::Reference::n_sphere):
//! half the distance from the sample's F1 point to the feature point
//! nearest to it, with that point's ID. Circles of this radius around the
//! feature points never overlap and each fits inside its own cell.
//!
//! ## How
//! 1. **F1's point, exactly.** The border's first two steps
//!    ([`SimdBorder`](super::SimdBorder)): F1 with its delta and ID from
//!    the kernel's own search, then the point of that ID whose delta has
//!    F1's bits, as integers in lane units (2^−24 cells) relative to the
//!    sample's cell. Its cell and its 24-bit fraction follow exactly.
//! 2. **F2 at that point.** The kernel of order 2 evaluated in that cell
//!    at that fraction ([`Simd::evaluate8_in_cell`]): F1 is the point
//!    itself at distance 0, F2 its nearest neighbour, certified like every
//!    F_n. Where another point shares the centre's very position and has
//!    the smaller ID, the kernel puts it first: it is then the neighbour,
//!    at distance 0, as in the reference.
//!
//! On a grid ([`SimdNSphere::n_sphere_grid`]) F1 and its ID come from the
//! grid tiles, and every point is evaluated once for all the samples of a
//! band of rows it is F1 of, since the radius depends on F1's point alone.
//! Where the IDs tell the points apart (checked on the generated cells
//! around the samples), the point's position comes from those cells and
//! only step 2 runs; otherwise one sample per point runs both steps.
//!
//! The radius is F2's distance halved (exact in f32), so its error is F2's
//! at an exact position: at most 2ε(2r + 1/S) against the f64 reference,
//! with ε = 2^−23 and S the pattern's scale (`tests/lanes/border.rs`).
//!
//! Euclidean only, as the border: F1's point is met again through the
//! Euclidean gaps of the border's search. Bad input (NaN, ±∞, cells out of
//! range) gives a NaN radius and [`INVALID_ID`] in its own lane only; in
//! [`Mode::Window`](crate::Mode::Window) a centre whose 3^d block holds no
//! other point gives +∞ and [`INVALID_ID`] for the neighbour.

use wide::{f32x8, u32x8};

use super::super::batch::in_cell;
use super::super::best::Best;
use super::super::generate::UNIT;
use super::super::lanes::{Eight, Lanes, One, WIDEST};
use super::super::locate::Located;
use super::super::periodic::wrap;
use super::super::{by_eights, Grid, Outputs, Period, Point, Simd, SizeError, SERIAL_BAND};
use super::search::Frame;
use crate::config::{Config, ConfigError, Metric};
use crate::definition::{FRACTION_BITS, INVALID_ID};

mod shared;

/// One sample's n-sphere radius (user units) with the IDs of the sphere's
/// centre (F1's point) and of the point nearest to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NSphere32 {
    /// The radius (NaN for bad input, +∞ in window mode without a second
    /// point around the centre).
    pub radius: f32,
    /// The ID of F1's point, the sphere's centre.
    pub feature: u32,
    /// The ID of the point nearest to the centre.
    pub neighbour: u32,
}

impl NSphere32 {
    /// The result for bad input: NaN and [`INVALID_ID`] twice.
    pub const INVALID: NSphere32 = NSphere32 { radius: f32::NAN, feature: INVALID_ID, neighbour: INVALID_ID };
}

/// Eight samples' n-sphere radii, lane i the i-th sample.
#[derive(Clone, Copy, Debug)]
pub struct NSphere8 {
    /// The radii.
    pub radius: f32x8,
    /// The IDs of the centres.
    pub feature: u32x8,
    /// The IDs of the centres' nearest points.
    pub neighbour: u32x8,
}

impl NSphere8 {
    /// Lane `i` (0..8).
    pub fn lane(&self, i: usize) -> NSphere32 {
        NSphere32 {
            radius: self.radius.to_array()[i],
            feature: self.feature.to_array()[i],
            neighbour: self.neighbour.to_array()[i],
        }
    }

    /// Every lane.
    pub fn lanes(&self) -> [NSphere32; 8] {
        std::array::from_fn(|i| self.lane(i))
    }

    /// One sample's result in all eight lanes.
    pub fn splat(n: &NSphere32) -> Self {
        NSphere8 {
            radius: f32x8::splat(n.radius),
            feature: u32x8::splat(n.feature),
            neighbour: u32x8::splat(n.neighbour),
        }
    }
}

/// The n-sphere radius, eight samples at a time (see the
/// [module's text](self)). Euclidean only.
///
/// ```
/// use worley::{Config, NSphere32, Reference, SimdNSphere};
/// let spheres = SimdNSphere::<3>::new(Config::default()).unwrap();
/// let x = [0.3, -2.0, 7.5];
/// let (n, want) = (spheres.n_sphere(x), Reference::<3>::new(Config::default()).unwrap().n_sphere(x));
/// assert_eq!((n.feature, n.neighbour), (want.feature, want.neighbour));
/// assert!((f64::from(n.radius) - want.radius).abs() < 1e-5);
/// assert_eq!(spheres.n_sphere([f64::NAN, 0.0, 0.0]).feature, NSphere32::INVALID.feature);
/// ```
#[derive(Clone, Debug)]
pub struct SimdNSphere<const D: usize> {
    /// F1 with its delta and ID, as the border's kernel.
    first: Simd<D, 1>,
    /// F1 and F2 with IDs, evaluated at F1's point.
    around: Simd<D, 2>,
    /// F1 with its ID alone: what a grid's samples need to share their
    /// points ([`SimdNSphere::by_points`]).
    ids: Simd<D, 1>,
}

/// Per lane: whether F1's point was found, its ID, its cell and its
/// fraction (exact).
struct Centres<const D: usize> {
    found: [bool; WIDEST],
    feature: [u32; WIDEST],
    cell: [[i64; D]; WIDEST],
    fraction: [[f32; D]; WIDEST],
}

impl<const D: usize> SimdNSphere<D> {
    /// Builds the evaluator (`config.order` is ignored).
    ///
    /// # Errors
    /// [`ConfigError::BorderMetric`] unless the metric is Euclidean, or the
    /// first other invalid field of `config`.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        if !matches!(config.metric, Metric::Euclidean) {
            return Err(ConfigError::BorderMetric(config.metric));
        }
        Ok(SimdNSphere {
            first: Simd::new(Config { order: 1, ..config }, Outputs::IdsAndDeltas)?,
            around: Simd::new(Config { order: 2, ..config }, Outputs::Ids)?,
            ids: Simd::new(Config { order: 1, ..config }, Outputs::Ids)?,
        })
    }

    /// The configuration (order 1).
    pub fn config(&self) -> &Config {
        self.first.config()
    }

    /// One sample, through the kernel's one-lane instantiation: the bits of
    /// its lane in [`SimdNSphere::n_sphere8`].
    pub fn n_sphere(&self, x: [f64; D]) -> NSphere32 {
        self.one(&self.first.locate::<One>(&[x]), None)
    }

    /// Eight samples, one per lane.
    ///
    /// ```
    /// use worley::{Config, SimdNSphere};
    /// let spheres = SimdNSphere::<2>::new(Config::default()).unwrap();
    /// let x: [[f64; 2]; 8] = std::array::from_fn(|i| [i as f64 * 0.7, -1.25]);
    /// assert_eq!(spheres.n_sphere8(&x).lane(5), spheres.n_sphere(x[5]));
    /// ```
    pub fn n_sphere8(&self, x: &[[f64; D]; 8]) -> NSphere8 {
        self.eight(&self.first.locate::<Eight>(x), None)
    }

    /// One sample given as a cell and the fraction within it, as
    /// [`Simd::evaluate_in_cell`] takes it (bad input as there).
    pub fn n_sphere_in_cell(&self, cell: [i64; D], fraction: [f32; D]) -> NSphere32 {
        self.one(&in_cell::<One, D>(&[cell], &[fraction]), None)
    }

    /// Eight samples given as cells and fractions.
    pub fn n_sphere8_in_cell(&self, cells: &[[i64; D]; 8], fractions: &[[f32; D]; 8]) -> NSphere8 {
        self.eight(&in_cell::<Eight, D>(cells, fractions), None)
    }

    /// One sample of the periodic pattern, `x` in cells, as
    /// [`Simd::evaluate_periodic`] takes it: F1's point and its nearest
    /// other point are searched among the periodic images. Inside one
    /// period, away from its faces, the ordinary pattern's radius.
    ///
    /// ```
    /// use worley::{Config, Period, SimdNSphere};
    /// let spheres = SimdNSphere::<2>::new(Config::default()).unwrap();
    /// let period = Period::new([3, 4]).unwrap();
    /// let (a, b) = (spheres.n_sphere_periodic([0.25, 1.5], &period), spheres.n_sphere_periodic([3.25, -2.5], &period));
    /// assert_eq!((a.radius.to_bits(), a.neighbour), (b.radius.to_bits(), b.neighbour));
    /// ```
    pub fn n_sphere_periodic(&self, x: [f64; D], period: &Period<D>) -> NSphere32 {
        self.one(&wrap::<One, D>(&[x], period), Some(period))
    }

    /// Eight samples of the periodic pattern, `x` in cells; lane `i` is
    /// bit-identical to [`SimdNSphere::n_sphere_periodic`] of `x[i]`.
    pub fn n_sphere8_periodic(&self, x: &[[f64; D]; 8], period: &Period<D>) -> NSphere8 {
        self.eight(&wrap::<Eight, D>(x, period), Some(period))
    }

    /// Many points into a caller's buffer, eight at a time.
    ///
    /// # Errors
    /// [`SizeError`] if `out` is shorter than `xs`; nothing is written.
    pub fn n_sphere_slice<P: Point<D>>(&self, xs: &[P], out: &mut [NSphere32]) -> Result<(), SizeError> {
        by_eights(xs, out, |block| self.n_sphere8(block).lanes())
    }

    /// Every point of a grid (axis 0 fastest): the bits of
    /// [`SimdNSphere::n_sphere`] at each, with one evaluation per feature
    /// point that is some sample's F1 (see the [module's text](self)).
    ///
    /// # Errors
    /// [`SizeError`] if `out.len() != grid.len()`; nothing is written.
    pub fn n_sphere_grid(&self, grid: &Grid<D>, out: &mut [NSphere32]) -> Result<(), SizeError> {
        let needed = grid.len().ok_or(SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(SizeError { needed, given: out.len() });
        }
        let rows = self.first.grid_rows(grid);
        for (b, dst) in out.chunks_mut(SERIAL_BAND * grid.size[0].max(1)).enumerate() {
            self.grid_rows_into(&rows, b * SERIAL_BAND, dst);
        }
        Ok(())
    }

    /// One located sample (`period` the pattern's, if it has one).
    fn one(&self, at: &Located<One, D>, period: Option<&Period<D>>) -> NSphere32 {
        let (_, _, raw) = self.first.dispatch_one(at);
        let c = self.centres::<One>(at, &raw);
        if !c.found[0] {
            return NSphere32::INVALID;
        }
        let f = self.around.dispatch_one(&centred::<One, D>(&c.cell, &c.fraction, period)).0;
        sphere(c.feature[0], f.rank, f.id)
    }

    /// Eight located samples (`period` the pattern's, if it has one).
    fn eight(&self, at: &Located<Eight, D>, period: Option<&Period<D>>) -> NSphere8 {
        let (_, _, raw) = self.first.dispatch8_whole(at);
        let c = self.centres::<Eight>(at, &raw);
        // Lanes without a centre are evaluated at a valid stand-in and
        // their result replaced.
        let cells: [[i64; D]; 8] = std::array::from_fn(|i| if c.found[i] { c.cell[i] } else { [0; D] });
        let fractions: [[f32; D]; 8] = std::array::from_fn(|i| if c.found[i] { c.fraction[i] } else { [0.0; D] });
        let f = self.around.dispatch8(&centred::<Eight, D>(&cells, &fractions, period));
        let lanes: [NSphere32; 8] = std::array::from_fn(|i| {
            if c.found[i] {
                sphere(c.feature[i], f.rank.map(|v| v.to_array()[i]), f.id.map(|v| v.to_array()[i]))
            } else {
                NSphere32::INVALID
            }
        });
        NSphere8 {
            radius: f32x8::from(lanes.map(|n| n.radius)),
            feature: u32x8::from(lanes.map(|n| n.feature)),
            neighbour: u32x8::from(lanes.map(|n| n.neighbour)),
        }
    }

    /// F1's point per lane, found again as the border finds it.
    #[inline(always)]
    fn centres<L: Lanes>(&self, at: &Located<L, D>, raw: &Best<L, D, 1>) -> Centres<D> {
        let k = &self.first;
        // Lanes of valid input with an F1 (not NaN, not +∞ from an empty
        // window).
        let open = L::and(k.good_lanes::<L>(at), L::lt(L::sqrt(raw.rank[0]), L::f(f32::INFINITY)));
        let mut c = Centres {
            found: [false; WIDEST],
            feature: [INVALID_ID; WIDEST],
            cell: [[0; D]; WIDEST],
            fraction: [[0.0; D]; WIDEST],
        };
        if !L::any(open) {
            return c;
        }
        let cell = at.cells_i64();
        let (p1, found) = k.find_nearest::<L>(at, &Frame::<L, D>::new(at), &cell, raw, open);
        let found = L::bits(L::and(open, found));
        L::u_store(raw.id[0], &mut c.feature[..L::N]);
        let mut position = [[0u32; WIDEST]; D];
        for (p, v) in position.iter_mut().zip(p1) {
            L::u_store(v, &mut p[..L::N]);
        }
        let low = (1u32 << FRACTION_BITS) - 1;
        for i in (0..L::N).filter(|&i| found & (1 << i) != 0) {
            c.found[i] = true;
            for a in 0..D {
                // The position relative to the sample's cell, two's
                // complement in lane units: its cell offset and its
                // 24-bit fraction, both exact.
                let p = position[a][i];
                c.cell[i][a] = cell[a][i] + i64::from((p as i32) >> FRACTION_BITS);
                c.fraction[i][a] = (p & low) as f32 / (1u32 << FRACTION_BITS) as f32;
            }
        }
        c
    }
}

/// The centres as the kernel of order 2 takes them: a cell and its
/// fraction ([`Simd::evaluate_in_cell`]), the cell wrapped into the period
/// where the pattern has one (the centre of a sample near a face may lie
/// in the cell beyond it).
fn centred<L: Lanes, const D: usize>(
    cells: &[[i64; D]],
    fractions: &[[f32; D]],
    period: Option<&Period<D>>,
) -> Located<L, D> {
    let Some(period) = period else {
        return in_cell::<L, D>(cells, fractions);
    };
    let p = period.cells().map(i64::from);
    let mut cell = [[0i64; WIDEST]; D];
    let mut f = [[0f32; WIDEST]; D];
    for i in 0..L::N {
        for a in 0..D {
            cell[a][i] = cells[i][a].rem_euclid(p[a]);
            f[a][i] = fractions[i][a] * UNIT;
        }
    }
    Located::wrapped(cell, &f, [true; WIDEST], Some(p))
}

/// The radius and the neighbour from F1 and F2 (`distance`, `id`) at the
/// centre whose ID is `feature`: the nearest point other than the centre
/// itself (see the module's text for a point at the centre's position).
fn sphere(feature: u32, distance: [f32; 2], id: [u32; 2]) -> NSphere32 {
    let k = usize::from(id[0] == feature);
    let d = distance[k];
    if d.is_nan() {
        return NSphere32::INVALID;
    }
    NSphere32 { radius: 0.5 * d, feature, neighbour: if d.is_finite() { id[k] } else { INVALID_ID } }
}
