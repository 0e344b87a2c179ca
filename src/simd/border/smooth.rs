//! # Compact smooth F1 in lanes
//!
//! The same quantity as
//! [`Reference::smooth_f1_compact`](crate::Reference::smooth_f1_compact)
//! (its module text defines it): S, the root of Σ_j φ((h_j − S)/s) = 1 over
//! the feature points, with h_j = √(F_j² + s²) − s and φ a C∞ weight that
//! is 0 from t = 1 on, so that only the points within √((h_1 + 2s)² − s²)
//! (less than F1 + 2s) take part.
//!
//! ## How
//! 1. **F1** with its delta and ID, from the kernel's own search (on a
//!    grid, through the grid tiles, which give the same bits).
//! 2. **Every point within the reach**, per lane: the 2^d block as the
//!    kernel's first stage visits it (its cells hashed up front, the same
//!    number of point steps in each cell some lane reaches: 6 % faster
//!    than cell by cell), the far cells of the 3^d block in the kernel's
//!    mirrored frame, then the shells around it until the block's outside
//!    lies beyond every open lane's reach (the border's search,
//!    [`SimdBorder`](super::SimdBorder), with a fixed radius in place of
//!    its shrinking one). Each point's squared distance and delta are
//!    kept per lane, in the order met, up to [`KEPT`] of them.
//! 3. **The root**, per lane in f64: Halley's method from S = h_1, kept
//!    inside the bracket (h_1 − s, h_1] by bisection, until Newton's step
//!    is below 10^−7 s (the error after it then O(10^−21) s; 3.4
//!    evaluations where Newton's method to 10^−12 s took 4.7); a lane
//!    with F1's point alone within reach needs no step (S = h_1). The
//!    gradient is the weighted mean of the ∇h_j.
//!
//! A lane with more than [`KEPT`] points within reach (s well beyond the
//! spacing of the points) searches again alone, keeping every point on
//! the heap, and takes the same root: the same operations in the same
//! order, so the same bits as if it had fitted.
//!
//! The periodic entry points ([`SimdSmooth::smooth_periodic`]) run the
//! same steps on the periodic pattern: the kernel's periodic F1, and cells
//! wrapped into the period in the search around it.
//!
//! ## Error
//! S moves with each h_j by a weight between 0 and 1, the weights summing
//! to 1, and h_j with F_j by at most 1: S is within the largest F_j error
//! of the points that take part, 4ε(R + 1/S_p) with R the reach in user
//! units, ε = 2^−24 and S_p the pattern's scale, plus the f32 rounding of
//! S (`tests/lanes/smooth.rs` measures it against the reference).
//!
//! Every entry point runs the same operations per lane, so a sample gets
//! the same bits through [`SimdSmooth::smooth`], [`SimdSmooth::smooth8`],
//! the slices and the grids. Euclidean only, as the border. Bad input (NaN,
//! ±∞, cells out of range) gives NaN and [`INVALID_ID`] in its own lane; a
//! negative, infinite or NaN `s` gives them in every lane; `s = 0` gives F1
//! as [`Simd::evaluate`] does, with ∇F1. In
//! [`Mode::Window`](crate::config::Mode::Window) the 3^d block's points take part,
//! and an empty block gives +∞ and [`INVALID_ID`].

use wide::{f32x8, u32x8};

use super::super::batch::in_cell;
use super::super::best::Best;
use super::super::coherent::GridRows;
use super::super::generate::UNIT;
use super::super::lanes::{Eight, Lanes, One, WIDEST};
use super::super::locate::Located;
use super::super::periodic::wrap;
use super::super::{by_eights, Features32, Grid, Outputs, Period, Point, Simd, SizeError, SERIAL_BAND};
use super::SLACK;
use crate::config::{Config, ConfigError, Metric};
use crate::definition::INVALID_ID;

mod near;
use near::{All, Near};

/// Points within reach kept per lane on the stack for the root; a lane
/// with more searches again alone and keeps them on the heap.
pub const KEPT: usize = 24;

/// One sample's compact smooth F1 (user units), its gradient and F1's ID.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Smooth32<const D: usize> {
    /// S: at most F1, more than F1 − 2s (NaN for bad input).
    pub value: f32,
    /// ∇S with respect to the sample's position.
    pub gradient: [f32; D],
    /// The ID of F1's point.
    pub feature: u32,
}

impl<const D: usize> Smooth32<D> {
    /// The result for bad input: NaN and [`INVALID_ID`].
    pub const INVALID: Self = Smooth32 { value: f32::NAN, gradient: [f32::NAN; D], feature: INVALID_ID };
}

/// Eight samples' compact smooth F1, lane i the i-th sample.
#[derive(Clone, Copy, Debug)]
pub struct Smooth8<const D: usize> {
    /// The values.
    pub value: f32x8,
    /// The gradients, per axis.
    pub gradient: [f32x8; D],
    /// The IDs of F1's points.
    pub feature: u32x8,
}

impl<const D: usize> Smooth8<D> {
    /// Lane `i` (0..8).
    pub fn lane(&self, i: usize) -> Smooth32<D> {
        Smooth32 {
            value: self.value.to_array()[i],
            gradient: self.gradient.map(|g| g.to_array()[i]),
            feature: self.feature.to_array()[i],
        }
    }

    /// Every lane.
    pub fn lanes(&self) -> [Smooth32<D>; 8] {
        std::array::from_fn(|i| self.lane(i))
    }

    /// One sample's value in all eight lanes.
    pub fn splat(v: &Smooth32<D>) -> Self {
        Smooth8 {
            value: f32x8::splat(v.value),
            gradient: v.gradient.map(f32x8::splat),
            feature: u32x8::splat(v.feature),
        }
    }

    fn from_lanes(lanes: &[Smooth32<D>; 8]) -> Self {
        Smooth8 {
            value: f32x8::from(lanes.map(|v| v.value)),
            gradient: std::array::from_fn(|a| f32x8::from(lanes.map(|v| v.gradient[a]))),
            feature: u32x8::from(lanes.map(|v| v.feature)),
        }
    }
}

/// Compact smooth F1, eight samples at a time (see the
/// [module's text](self)). Euclidean only.
///
/// ```
/// use worley::{Config, Reference, SimdSmooth};
/// let smooth = SimdSmooth::<3>::new(Config::default()).unwrap();
/// let x = [0.3, -2.0, 7.5];
/// let got = smooth.smooth(x, 0.3);
/// let want = Reference::<3>::new(Config::default()).unwrap().smooth_f1_compact(x, 0.3);
/// assert_eq!(got.feature, want.feature);
/// assert!((f64::from(got.value) - want.value).abs() < 1e-5);
/// assert!(smooth.smooth([f64::NAN, 0.0, 0.0], 0.3).value.is_nan());
/// ```
#[derive(Clone, Debug)]
pub struct SimdSmooth<const D: usize> {
    /// F1 with its delta and ID.
    first: Simd<D, 1>,
}

/// The lanes' F1 as the kernel gives it (user units): distance, ID and
/// delta; a grid's tiles give the same bits.
struct First<const D: usize> {
    f1: [f32; WIDEST],
    id: [u32; WIDEST],
    delta: [[f32; WIDEST]; D],
}

impl<const D: usize> First<D> {
    /// From the kernel's finished results.
    #[inline(always)]
    fn of<L: Lanes>(best: &Best<L, D, 1>) -> Self {
        let mut first = First { f1: [0.0; WIDEST], id: [INVALID_ID; WIDEST], delta: [[0.0; WIDEST]; D] };
        L::f_store(best.rank[0], &mut first.f1[..L::N]);
        L::u_store(best.id[0], &mut first.id[..L::N]);
        for (out, v) in first.delta.iter_mut().zip(&best.delta[0]) {
            L::f_store(*v, &mut out[..L::N]);
        }
        first
    }

    /// From eight results.
    fn from_results(results: &[Features32<D, 1>; 8]) -> Self {
        First {
            f1: std::array::from_fn(|i| if i < 8 { results[i].distance[0] } else { 0.0 }),
            id: std::array::from_fn(|i| if i < 8 { results[i].id[0] } else { INVALID_ID }),
            delta: std::array::from_fn(|a| std::array::from_fn(|i| if i < 8 { results[i].delta[0][a] } else { 0.0 })),
        }
    }
}

impl<const D: usize> SimdSmooth<D> {
    /// Builds the evaluator (`config.order` is ignored).
    ///
    /// # Errors
    /// [`ConfigError::BorderMetric`] unless the metric is Euclidean, or the
    /// first other invalid field of `config`.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        if !matches!(config.metric, Metric::Euclidean) {
            return Err(ConfigError::BorderMetric(config.metric));
        }
        Ok(SimdSmooth { first: Simd::new(Config { order: 1, ..config }, Outputs::IdsAndDeltas)? })
    }

    /// The configuration (order 1).
    pub fn config(&self) -> &Config {
        self.first.config()
    }

    /// One sample with smoothness `s` (user units), through the one-lane
    /// instantiation: the bits of its lane in [`SimdSmooth::smooth8`].
    pub fn smooth(&self, x: [f64; D], s: f32) -> Smooth32<D> {
        self.one(&self.first.locate::<One>(&[x]), s)
    }

    /// Eight samples, one per lane.
    ///
    /// ```
    /// use worley::{Config, SimdSmooth};
    /// let smooth = SimdSmooth::<2>::new(Config::default()).unwrap();
    /// let x: [[f64; 2]; 8] = std::array::from_fn(|i| [i as f64 * 0.7, -1.25]);
    /// assert_eq!(smooth.smooth8(&x, 0.2).lane(5), smooth.smooth(x[5], 0.2));
    /// ```
    pub fn smooth8(&self, x: &[[f64; D]; 8], s: f32) -> Smooth8<D> {
        self.eight(&self.first.locate::<Eight>(x), s)
    }

    /// One sample given as a cell and the fraction within it, as
    /// [`Simd::evaluate_in_cell`] takes it (bad input as there).
    pub fn smooth_in_cell(&self, cell: [i64; D], fraction: [f32; D], s: f32) -> Smooth32<D> {
        self.one(&in_cell::<One, D>(&[cell], &[fraction]), s)
    }

    /// Eight samples given as cells and fractions.
    pub fn smooth8_in_cell(&self, cells: &[[i64; D]; 8], fractions: &[[f32; D]; 8], s: f32) -> Smooth8<D> {
        self.eight(&in_cell::<Eight, D>(cells, fractions), s)
    }

    /// One sample of the periodic pattern, `x` in cells, as
    /// [`Simd::evaluate_periodic`] takes it; `s` in user units, as the
    /// value. Inside one period, away from its faces, the ordinary
    /// pattern's value.
    ///
    /// ```
    /// use worley::{Config, Period, SimdSmooth};
    /// let smooth = SimdSmooth::<2>::new(Config::default()).unwrap();
    /// let period = Period::new([3, 4]).unwrap();
    /// let (a, b) = (smooth.smooth_periodic([0.25, 1.5], &period, 0.3), smooth.smooth_periodic([3.25, -2.5], &period, 0.3));
    /// assert_eq!(a.value.to_bits(), b.value.to_bits());
    /// ```
    pub fn smooth_periodic(&self, x: [f64; D], period: &Period<D>, s: f32) -> Smooth32<D> {
        self.one(&wrap::<One, D>(&[x], period), s)
    }

    /// Eight samples of the periodic pattern, `x` in cells; lane `i` is
    /// bit-identical to [`SimdSmooth::smooth_periodic`] of `x[i]`.
    pub fn smooth8_periodic(&self, x: &[[f64; D]; 8], period: &Period<D>, s: f32) -> Smooth8<D> {
        self.eight(&wrap::<Eight, D>(x, period), s)
    }

    /// Many points into a caller's buffer, eight at a time.
    ///
    /// # Errors
    /// [`SizeError`] if `out` is shorter than `xs`; nothing is written.
    pub fn smooth_slice<P: Point<D>>(&self, xs: &[P], s: f32, out: &mut [Smooth32<D>]) -> Result<(), SizeError> {
        by_eights(xs, out, |block| self.smooth8(block, s).lanes())
    }

    /// Every point of a grid (axis 0 fastest), eight at a time.
    ///
    /// # Errors
    /// [`SizeError`] if `out.len() != grid.len()`; nothing is written.
    pub fn smooth_grid(&self, grid: &Grid<D>, s: f32, out: &mut [Smooth32<D>]) -> Result<(), SizeError> {
        let needed = grid.len().ok_or(SizeError { needed: usize::MAX, given: out.len() })?;
        if out.len() != needed {
            return Err(SizeError { needed, given: out.len() });
        }
        let rows = self.first.grid_rows(grid);
        for (b, dst) in out.chunks_mut(SERIAL_BAND * grid.size[0].max(1)).enumerate() {
            self.grid_rows_into(&rows, b * SERIAL_BAND, s, dst);
        }
        Ok(())
    }

    /// Rows `first..` of a grid (whole rows; `rows` from a kernel of this
    /// configuration) into `out`: the bits [`SimdSmooth::smooth_grid`]
    /// writes for them. F1 with its ID and delta through the grid tiles,
    /// which give each point the per-sample kernel's bits; then the search
    /// within reach and the root eight points at a time.
    pub(crate) fn grid_rows_into(&self, rows: &GridRows<'_, D>, first: usize, s: f32, out: &mut [Smooth32<D>]) {
        if out.is_empty() {
            return;
        }
        let mut f1 = vec![Features32::<D, 1>::default(); out.len()];
        self.first.grid_rows_into(rows, first, &mut f1);
        let grid = rows.grid();
        let start = first * grid.size[0];
        for (c, dst) in out.chunks_mut(8).enumerate() {
            let index = |i: usize| c * 8 + i.min(dst.len() - 1);
            let block: [[f64; D]; 8] = std::array::from_fn(|i| grid.point(start + index(i)));
            let results: [Features32<D, 1>; 8] = std::array::from_fn(|i| f1[index(i)]);
            let at = self.first.locate::<Eight>(&block);
            let search = |reach, near: &mut Near<D>| self.first.near_points8(&at, reach, near);
            let lanes = self.lanes::<Eight>(&at, &First::from_results(&results), s, search);
            dst.copy_from_slice(&lanes[..dst.len()]);
        }
    }

    /// One located sample.
    fn one(&self, at: &Located<One, D>, s: f32) -> Smooth32<D> {
        let (best, _, _) = self.first.dispatch_one(at);
        let search = |reach, near: &mut Near<D>| self.first.near_points::<One, _>(at, reach, near);
        self.lanes::<One>(at, &First::of::<One>(&best), s, search)[0]
    }

    /// Eight located samples.
    fn eight(&self, at: &Located<Eight, D>, s: f32) -> Smooth8<D> {
        let (best, _, _) = self.first.dispatch8_whole(at);
        let search = |reach, near: &mut Near<D>| self.first.near_points8(at, reach, near);
        let lanes = self.lanes::<Eight>(at, &First::of::<Eight>(&best), s, search);
        Smooth8::from_lanes(&std::array::from_fn(|i| lanes[i]))
    }

    /// The located lanes' values from their F1 (`first`, as the kernel
    /// gives it), `search` finding the points within a reach
    /// ([`Simd::near_points`]).
    #[inline(always)]
    fn lanes<L: Lanes>(
        &self,
        at: &Located<L, D>,
        first: &First<D>,
        s: f32,
        search: impl FnOnce(L::F, &mut Near<D>) -> u32,
    ) -> [Smooth32<D>; WIDEST] {
        let mut out = [Smooth32::INVALID; WIDEST];
        if !(s >= 0.0 && s.is_finite()) {
            return out;
        }
        let First { f1, id, delta } = first;
        let mut open = [false; WIDEST];
        for i in 0..L::N {
            if f1[i].is_nan() {
                continue;
            }
            if f1[i].is_infinite() {
                // Window mode with an empty 3^d block.
                out[i] = Smooth32 { value: f32::INFINITY, gradient: [f32::NAN; D], feature: INVALID_ID };
            } else if s == 0.0 {
                let g = |a: usize| if f1[i] > 0.0 { delta[a][i] / f1[i] } else { 0.0 };
                out[i] = Smooth32 { value: f1[i], gradient: std::array::from_fn(g), feature: id[i] };
            } else {
                open[i] = true;
            }
        }
        if !open.contains(&true) {
            return out;
        }
        let unit = self.first.pattern().scale() * f64::from(UNIT);
        let sl = f64::from(s) * unit;
        // Each open lane's squared reach (lane units) with some slack: a
        // point beyond the exact reach has weight 0, so more is harmless.
        let mut reach = [-1f32; WIDEST];
        for i in (0..L::N).filter(|&i| open[i]) {
            let f = f64::from(f1[i]) * unit;
            let h1 = (f * f + sl * sl).sqrt() - sl;
            reach[i] = (((h1 + 2.0 * sl).powi(2) - sl * sl) * f64::from(SLACK * SLACK)) as f32;
        }
        let mut near = Near::new();
        let uncertified = search(L::f_load(&reach[..L::N]), &mut near);
        for i in (0..L::N).filter(|&i| open[i]) {
            out[i] = if uncertified & (1 << i) != 0 {
                Smooth32::INVALID
            } else {
                let n = near.count[i];
                let (value, gradient) = if n > KEPT {
                    // The lane alone, at its own cell, fraction and period:
                    // the same cells in the same order, so the same points.
                    let cells = at.cells_i64();
                    let mut f = [[0f32; WIDEST]; D];
                    for (out, v) in f.iter_mut().zip(&at.f) {
                        L::f_store(*v, &mut out[..L::N]);
                    }
                    let mut cell = [[0i64; WIDEST]; D];
                    let mut fraction = [[0f32; WIDEST]; D];
                    for a in 0..D {
                        cell[a][0] = cells[a][i];
                        fraction[a][0] = f[a][i];
                    }
                    let alone = Located::<One, D>::wrapped(cell, &fraction, [true; WIDEST], at.period);
                    let mut all = All { d2: Vec::with_capacity(2 * n), delta: Vec::with_capacity(2 * n) };
                    self.first.near_points::<One, _>(&alone, One::f(reach[i]), &mut all);
                    let (mut part, mut weights) = (vec![(0f64, 0usize); all.d2.len()], vec![0f64; all.d2.len()]);
                    solve(&all.d2, &all.delta, sl, &mut part, &mut weights)
                } else {
                    let (mut part, mut weights) = ([(0f64, 0usize); KEPT], [0f64; KEPT]);
                    solve(&near.d2[i][..n], &near.delta[i][..n], sl, &mut part[..n], &mut weights[..n])
                };
                Smooth32 { value: (value / unit) as f32, gradient: gradient.map(|g| g as f32), feature: id[i] }
            };
        }
        out
    }
}

/// S (lane units) and ∇S from the points within reach (squared distances
/// and deltas, lane units, at least F1's point), `sl` the smoothness in
/// lane units; `part` and `weights` are scratch, as long as `d2`.
fn solve<const D: usize>(
    d2: &[f32],
    delta: &[[f32; D]],
    sl: f64,
    part: &mut [(f64, usize)],
    weights: &mut [f64],
) -> (f64, [f64; D]) {
    // Per point: √(F² + s²) and h = √(F² + s²) − s.
    for (j, (p, &d)) in part.iter_mut().zip(d2).enumerate() {
        *p = ((f64::from(d) + sl * sl).sqrt(), j);
    }
    let h1 = part.iter().fold(f64::INFINITY, |m, &(r, _)| m.min(r - sl));
    // The points that take part: t = (h − S)/s < 1 at S = h1 (t only grows
    // as S falls below h1), with their deltas, kept in order.
    let mut n = 0;
    for j in 0..part.len() {
        let (r, _) = part[j];
        if r - sl - h1 < sl {
            part[n] = part[j];
            n += 1;
        }
    }
    let part = &part[..n];
    let unit = |(r, j): (f64, usize)| delta[j].map(|v| f64::from(v) / r);
    if n == 1 {
        // F1's point alone: S = h1, its weight φ(0) = 1.
        return (h1, unit(part[0]));
    }
    // Halley's method on G(v) = Σ φ((h_j − v)/s) − 1, increasing in v,
    // with G(h1 − s) = −1 and G(h1) ≥ 0: with a = 1/(1 − t), φ' = −φa²
    // and φ'' = φ(2t − 1)a⁴, so the Newton step g·s/Σφa² is divided by
    // 1 − g·Σφ(2t − 1)a⁴ / (2(Σφa²)²) (Newton's own where that lies
    // outside [1/2, 2], far from the root); a step that leaves the bracket
    // bisects it instead. The weights −φ'(t_j) of the last evaluation give
    // the gradient: Newton's step there is below 10^−7 s.
    let (mut lo, mut hi) = (h1 - sl, h1);
    let mut value = h1;
    for _ in 0..64 {
        let (mut g, mut slope, mut bend) = (-1.0, 0.0, 0.0);
        for (w, &(r, _)) in weights.iter_mut().zip(part) {
            let t = (r - sl - value) / sl;
            *w = 0.0;
            if t < 1.0 {
                let a = 1.0 / (1.0 - t);
                // φ(0) = 1 exactly, without the exponential (F1's point at
                // the first step).
                let e = if t == 0.0 { 1.0 } else { (1.0 - a).exp() };
                g += e;
                *w = e * a * a;
                slope += *w;
                bend += *w * (2.0 * t - 1.0) * a * a;
            }
        }
        if g >= 0.0 {
            hi = value;
        } else {
            lo = value;
        }
        let newton = g * sl / slope;
        let shrink = 1.0 - g * bend / (2.0 * slope * slope);
        let step = if (0.5..=2.0).contains(&shrink) { newton / shrink } else { newton };
        if newton.abs() <= 1e-7 * sl {
            // Converged: Newton's step bounds the distance to the root to
            // first order, and the error after Halley's step is O(δ³), so
            // the value is within 10^−20 s of the root, and the weights
            // (their relative change 10^−7·(2a + a²)·φ) are within f32's
            // resolution of the gradient.
            value -= step;
            break;
        }
        let next = value - step;
        value = if next > lo && next < hi { next } else { 0.5 * (lo + hi) };
    }
    let mut weight = 0.0;
    let mut gradient = [0.0; D];
    for (&w, &p) in weights.iter().zip(part) {
        weight += w;
        for (g, u) in gradient.iter_mut().zip(unit(p)) {
            *g += w * u;
        }
    }
    (value, gradient.map(|g| g / weight))
}
