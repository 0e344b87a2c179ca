//! # The SIMD kernel
//!
//! The same function as the [`Reference`](crate::Reference), on the same
//! feature points bit for bit, computed in f32 lanes eight samples at a time.
//!
//! ## How
//! - **Locating** a sample is done per lane in f64, exactly as the reference
//!   does it (u = x·S, c = ⌊u⌋ as `i64`), so the cell is the reference's and
//!   the fraction f ∈ [0, 1] loses only its rounding to f32. Distances are
//!   then computed in f32 relative to the sample's own cell, so precision does
//!   not depend on how far the sample is from the origin.
//! - **The cell hash and the LCG** run in `u32` lanes. Each point coordinate
//!   comes from the cell's state with one independent multiply-add
//!   (s_k = A_k·s₀ + C_k, [`lcg_jump`]) instead of a chain of dependent
//!   multiplies. The 24-bit fractions convert to f32 exactly.
//! - **Divergence.** Cells of the 3^d block are visited in a fixed order
//!   (own cell, faces, edges, corners). A cell is skipped when no lane needs
//!   it (Worley's pruning per lane: the cell's nearest point is no closer than
//!   that lane's F_n); otherwise its points are generated once for all lanes,
//!   up to the largest population among the lanes, and each lane keeps only
//!   its own candidates (masked). A lane's result therefore depends on that
//!   lane alone, which is what makes one lane and eight lanes bit-identical.
//! - **Exact.** After the block, a lane whose F_n is farther than the block's
//!   outside takes the wider search, shell by shell, masked to the lanes that
//!   still need it (a cold path: 0.03 % of samples for 3D F4 at λ 3).
//! - **Compile-time choices.** Dimension `D` and order `N` are const
//!   generics; the metric and the outputs (distances, IDs, deltas) are
//!   dispatched once per call into monomorphised loops, so nothing the caller
//!   did not ask for is computed in the hot loop.
//!
//! ## Build flags
//! `wide` chooses its instructions at compile time only. Build with
//! `RUSTFLAGS="-C target-cpu=native"` (or `x86-64-v3`) for the AVX2 path;
//! [`simd_level`] reports what was compiled in. Results are bit-identical
//! between builds: no operation used here differs between them.

pub mod lanes;

use wide::{f32x8, u32x8};

use crate::config::{Config, ConfigError, Metric, Mode};
use crate::definition::{axis_term, lcg_jump, Pattern, AXIS_MUL, FRACTION_ULP, INVALID_ID, TABLE_SIZE};
use crate::reference::{shell, MAX_SHELLS};
use lanes::{Eight, Lanes, One};

/// The SIMD instruction set `wide` was compiled for.
pub fn simd_level() -> &'static str {
    if cfg!(target_feature = "avx512f") {
        "avx512f (8-lane ops on AVX2 paths)"
    } else if cfg!(target_feature = "avx2") {
        "avx2"
    } else if cfg!(target_feature = "sse4.1") {
        "sse4.1"
    } else if cfg!(target_feature = "sse2") {
        "sse2 (default x86_64 build: 8-lane integer ops are split or emulated)"
    } else {
        "scalar fallback"
    }
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

/// The 8-lane evaluator for dimension `D` and order `N` (F1..FN).
#[derive(Clone, Debug)]
pub struct Simd<const D: usize, const N: usize> {
    config: Config,
    pattern: Pattern<D>,
    outputs: Outputs,
    table: [u8; TABLE_SIZE],
    /// (A_k, C_k) for every LCG state a point can use.
    jump: Vec<(u32, u32)>,
    /// The 3^d block: own cell, then faces, edges, corners.
    block: Vec<[i64; D]>,
    inv_scale: f32,
}

/// A lane's located sample: its cell (per axis, per lane) and fraction.
struct Located<L: Lanes, const D: usize> {
    cell: [[i64; 8]; D],
    f: [L::F; D],
    valid: [bool; 8],
}

/// The n best candidates per lane.
struct Best<L: Lanes, const D: usize, const N: usize> {
    rank: [L::F; N],
    delta: [[L::F; D]; N],
    id: [L::U; N],
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Builds the evaluator. `config.order` must equal `N`.
    ///
    /// # Errors
    /// The first invalid field of `config`, or an order that differs from `N`.
    pub fn new(config: Config, outputs: Outputs) -> Result<Self, ConfigError> {
        if config.order != N {
            return Err(ConfigError::OrderMismatch { asked: config.order, compiled: N });
        }
        let pattern = Pattern::<D>::new(&config)?;
        let table = *pattern.table().entries();
        let states = pattern.table().max_population() * (D as u32 + 1) + 1;
        let jump = (0..=states).map(lcg_jump).collect();
        let mut block = shell::<D>(1);
        block.sort_by_key(|o| o.iter().filter(|&&v| v != 0).count());
        block.insert(0, [0; D]);
        let inv_scale = (1.0 / pattern.scale()) as f32;
        Ok(Simd { config, pattern, outputs, table, jump, block, inv_scale })
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
    pub fn evaluate(&self, x: [f64; D]) -> Features32<D, N> {
        let located = self.locate::<One>(&[x]);
        let best = self.dispatch::<One>(&located);
        Features32 { distance: best.rank, delta: best.delta, id: best.id }
    }

    /// One sample given in f32.
    pub fn evaluate_f32(&self, x: [f32; D]) -> Features32<D, N> {
        self.evaluate(x.map(f64::from))
    }

    /// Eight samples, one per lane (the 8-lane instantiation).
    pub fn evaluate8(&self, x: &[[f64; D]; 8]) -> Features8<D, N> {
        let located = self.locate::<Eight>(x);
        let best = self.dispatch::<Eight>(&located);
        Features8 { distance: best.rank, delta: best.delta, id: best.id }
    }

    /// Eight samples as lanes per axis.
    pub fn evaluate_lanes(&self, x: [f32x8; D]) -> Features8<D, N> {
        let arrays = x.map(|v| v.to_array());
        let points: [[f64; D]; 8] = std::array::from_fn(|i| std::array::from_fn(|a| arrays[a][i] as f64));
        self.evaluate8(&points)
    }

    /// Many samples into a caller's buffer (`out.len() >= xs.len()`), eight
    /// at a time; a tail shorter than eight is padded.
    pub fn evaluate_slice(&self, xs: &[[f64; D]], out: &mut [Features32<D, N>]) {
        assert!(out.len() >= xs.len(), "output buffer shorter than input");
        for (chunk, dst) in xs.chunks(8).zip(out.chunks_mut(8)) {
            let mut block = [[0.0; D]; 8];
            block[..chunk.len()].copy_from_slice(chunk);
            let r = self.evaluate8(&block);
            for (i, o) in dst.iter_mut().take(chunk.len()).enumerate() {
                *o = lane(&r, i);
            }
        }
    }

    fn locate<L: Lanes>(&self, xs: &[[f64; D]]) -> Located<L, D> {
        let mut cell = [[0i64; 8]; D];
        let mut f = [[0f32; 8]; D];
        let mut valid = [false; 8];
        for (i, x) in xs.iter().enumerate().take(L::N) {
            if let Some((c, fr)) = self.pattern.locate(*x) {
                valid[i] = true;
                for a in 0..D {
                    cell[a][i] = c[a];
                    f[a][i] = fr[a] as f32;
                }
            }
        }
        Located { cell, f: std::array::from_fn(|a| L::f_load(&f[a][..L::N])), valid }
    }

    /// Picks the monomorphised kernel for the metric and outputs, then
    /// converts ranks to distances and marks bad lanes.
    fn dispatch<L: Lanes>(&self, at: &Located<L, D>) -> Best<L, D, N> {
        let mut best = match (self.config.metric, self.outputs) {
            (Metric::Euclidean, Outputs::Distances) => self.search::<L, Euclid, false, false>(Euclid, at),
            (Metric::Euclidean, Outputs::Ids) => self.search::<L, Euclid, true, false>(Euclid, at),
            (Metric::Euclidean, Outputs::IdsAndDeltas) => self.search::<L, Euclid, true, true>(Euclid, at),
            (Metric::Manhattan, o) => self.search_outputs::<L, Manhattan>(Manhattan, o, at),
            (Metric::Chebyshev, o) => self.search_outputs::<L, Chebyshev>(Chebyshev, o, at),
            (Metric::Minkowski(p), o) => self.search_outputs::<L, Minkowski>(Minkowski(p as f32), o, at),
        };
        let inv = L::f(self.inv_scale);
        let metric = self.config.metric;
        for k in 0..N {
            best.rank[k] = L::mul(distance_of_rank::<L>(metric, best.rank[k]), inv);
            for a in 0..D {
                best.delta[k][a] = L::mul(best.delta[k][a], inv);
            }
        }
        if at.valid[..L::N].iter().any(|v| !v) {
            mark_invalid(&mut best, &at.valid);
        }
        best
    }

    fn search_outputs<L: Lanes, M: Metric32>(&self, m: M, o: Outputs, at: &Located<L, D>) -> Best<L, D, N> {
        match o {
            Outputs::Distances => self.search::<L, M, false, false>(m, at),
            Outputs::Ids => self.search::<L, M, true, false>(m, at),
            Outputs::IdsAndDeltas => self.search::<L, M, true, true>(m, at),
        }
    }

    /// The kernel: the 3^d block, then the certified widening.
    #[inline(always)]
    fn search<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        at: &Located<L, D>,
    ) -> Best<L, D, N> {
        let mut best =
            Best::<L, D, N> { rank: [L::f(f32::INFINITY); N], delta: [[L::f(0.0); D]; N], id: [L::u(INVALID_ID); N] };
        // Axis terms of the cells at offsets −1, 0, +1, per axis and lane.
        let terms: [[L::U; 3]; D] =
            std::array::from_fn(|a| std::array::from_fn(|o| self.terms::<L>(at, a, o as i64 - 1)));
        let all = L::lt(L::f(0.0), L::f(1.0));
        for offset in &self.block {
            let t: [L::U; D] = std::array::from_fn(|a| terms[a][(offset[a] + 1) as usize]);
            self.visit::<L, M, IDS, DELTAS>(metric, t, offset, &at.f, all, &mut best);
        }
        if self.config.mode == Mode::Exact {
            let open = L::lt(metric.rank_of_distance::<L>(outside::<L, D>(&at.f, 1.0)), best.rank[N - 1]);
            if L::any(open) {
                self.widen::<L, M, IDS, DELTAS>(metric, at, open, &mut best);
            }
        }
        best
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
        for r in 2..=MAX_SHELLS {
            for offset in shell::<D>(r) {
                let t: [L::U; D] = std::array::from_fn(|a| self.terms::<L>(at, a, offset[a]));
                self.visit::<L, M, IDS, DELTAS>(metric, t, &offset, &at.f, open, best);
            }
            let edge = metric.rank_of_distance::<L>(outside::<L, D>(&at.f, r as f32));
            open = L::and(open, L::lt(edge, best.rank[N - 1]));
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

    /// Per-lane axis terms of the cells at `offset` along axis `a`.
    #[inline(always)]
    fn terms<L: Lanes>(&self, at: &Located<L, D>, a: usize, offset: i64) -> L::U {
        let mut t = [0u32; 8];
        for (ti, c) in t.iter_mut().zip(at.cell[a]).take(L::N) {
            *ti = axis_term(c.wrapping_add(offset));
        }
        L::u_load(&t[..L::N])
    }

    /// Visits one cell for the lanes in `mask` that it can still improve.
    #[inline(always)]
    fn visit<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        terms: [L::U; D],
        offset: &[i64; D],
        f: &[L::F; D],
        mask: L::M,
        best: &mut Best<L, D, N>,
    ) {
        // Pruning: the cell's nearest point against each lane's F_n.
        let gaps: [L::F; D] = std::array::from_fn(|a| {
            let o = offset[a];
            if o > 0 {
                L::sub(L::f(o as f32), f[a])
            } else if o < 0 {
                L::sub(f[a], L::f((o + 1) as f32))
            } else {
                L::f(0.0)
            }
        });
        let needs = L::and(mask, L::lt(metric.rank::<L, D>(&gaps), best.rank[N - 1]));
        if !L::any(needs) {
            return;
        }
        // The cell hash (see `definition`), in u32 lanes.
        let keys = self.pattern.keys();
        let mut h = L::u(keys.init);
        for (t, m) in terms.iter().zip(AXIS_MUL) {
            h = L::u_mul(L::u_xor(h, *t), L::u(m));
            h = L::u_xor(h, L::u_shr16(h));
        }
        h = L::u_xor(h, L::u(keys.finish));
        h = L::u_xor(h, L::u_shr16(h));
        h = L::u_mul(h, L::u(0x85EB_CA6B));
        h = L::u_xor(h, L::u_shr13(h));
        h = L::u_mul(h, L::u(0xC2B2_AE35));
        h = L::u_xor(h, L::u_shr16(h));
        // Populations: a table lookup per lane (there is no gather).
        let mut hs = [0u32; 8];
        L::u_store(h, &mut hs[..L::N]);
        let mut counts = [0f32; 8];
        let mut most = 0u8;
        for (c, s) in counts.iter_mut().zip(hs).take(L::N) {
            let n = self.table[(s >> 24) as usize];
            *c = n as f32;
            most = most.max(n);
        }
        let count = L::f_load(&counts[..L::N]);
        let shifted: [L::F; D] = std::array::from_fn(|a| L::sub(f[a], L::f(offset[a] as f32)));
        let ulp = L::f(FRACTION_ULP as f32);
        for j in 0..most as usize {
            let active = L::and(needs, L::lt(L::f(j as f32), count));
            let base = 1 + j * (D + 1);
            let delta: [L::F; D] = std::array::from_fn(|a| {
                let (am, cm) = self.jump[base + 1 + a];
                let s = L::u_add(L::u_mul(h, L::u(am)), L::u(cm));
                L::sub(shifted[a], L::mul(L::u24_to_f(L::u_shr8(s)), ulp))
            });
            let rank = L::select(active, metric.rank::<L, D>(&delta), L::f(f32::INFINITY));
            let id = if IDS {
                let (am, cm) = self.jump[base];
                L::u_add(L::u_mul(h, L::u(am)), L::u(cm))
            } else {
                L::u(0)
            };
            best.insert::<IDS, DELTAS>(rank, delta, id);
        }
    }
}

impl<L: Lanes, const D: usize, const N: usize> Best<L, D, N> {
    /// Inserts one candidate per lane (rank +∞ in lanes that have none).
    /// Ties keep the earlier point, as in the reference.
    #[inline(always)]
    fn insert<const IDS: bool, const DELTAS: bool>(&mut self, rank: L::F, delta: [L::F; D], id: L::U) {
        let (mut r, mut d, mut i) = (rank, delta, id);
        for k in 0..N {
            let lt = L::lt(r, self.rank[k]);
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

/// B_r per lane: distance from the sample to the outside of the block of
/// Chebyshev radius r.
#[inline(always)]
fn outside<L: Lanes, const D: usize>(f: &[L::F; D], r: f32) -> L::F {
    let mut b = L::f(f32::INFINITY);
    for fa in f {
        b = L::min(b, L::min(L::add(*fa, L::f(r)), L::sub(L::f(r + 1.0), *fa)));
    }
    b
}

fn distance_of_rank<L: Lanes>(metric: Metric, r: L::F) -> L::F {
    match metric {
        Metric::Euclidean => L::sqrt(r),
        Metric::Manhattan | Metric::Chebyshev => r,
        Metric::Minkowski(p) => per_lane::<L>(r, |v| v.powf(1.0 / p as f32)),
    }
}

fn mark_invalid<L: Lanes, const D: usize, const N: usize>(best: &mut Best<L, D, N>, valid: &[bool; 8]) {
    let mut bad = [0f32; 8];
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

/// Applies a scalar function to every lane.
#[inline(always)]
fn per_lane<L: Lanes>(v: L::F, f: impl Fn(f32) -> f32) -> L::F {
    let mut a = [0f32; 8];
    L::f_store(v, &mut a[..L::N]);
    for x in a.iter_mut().take(L::N) {
        *x = f(*x);
    }
    L::f_load(&a[..L::N])
}

/// Lane `i` of an 8-lane result.
pub fn lane<const D: usize, const N: usize>(r: &Features8<D, N>, i: usize) -> Features32<D, N> {
    Features32 {
        distance: r.distance.map(|v| v.to_array()[i]),
        delta: r.delta.map(|d| d.map(|v| v.to_array()[i])),
        id: r.id.map(|v| v.to_array()[i]),
    }
}

/// A metric in lanes; the rank is the reference's (squared distance, Σ|d|^p).
pub trait Metric32: Copy {
    /// Rank of a vector.
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F;
    /// Rank of a length.
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F;
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
/// Minkowski in lanes (the power is taken per lane).
#[derive(Clone, Copy, Debug)]
pub struct Minkowski(pub f32);

impl Metric32 for Euclid {
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let mut s = L::mul(v[0], v[0]);
        for x in &v[1..] {
            s = L::add(s, L::mul(*x, *x));
        }
        s
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        L::mul(d, d)
    }
}

impl Metric32 for Manhattan {
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let mut s = L::abs(v[0]);
        for x in &v[1..] {
            s = L::add(s, L::abs(*x));
        }
        s
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
}

impl Metric32 for Chebyshev {
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let mut s = L::abs(v[0]);
        for x in &v[1..] {
            s = L::max(s, L::abs(*x));
        }
        s
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        d
    }
}

impl Metric32 for Minkowski {
    #[inline(always)]
    fn rank<L: Lanes, const D: usize>(&self, v: &[L::F; D]) -> L::F {
        let p = self.0;
        let mut s = per_lane::<L>(v[0], |x| x.abs().powf(p));
        for x in &v[1..] {
            s = L::add(s, per_lane::<L>(*x, |x| x.abs().powf(p)));
        }
        s
    }
    #[inline(always)]
    fn rank_of_distance<L: Lanes>(&self, d: L::F) -> L::F {
        let p = self.0;
        per_lane::<L>(d, |x| x.powf(p))
    }
}

impl<const N: usize> Simd<2, N> {
    /// One point given as a `glam::Vec2`.
    pub fn evaluate_vec2(&self, p: glam::Vec2) -> Features32<2, N> {
        self.evaluate_f32(p.to_array())
    }
}

impl<const N: usize> Simd<3, N> {
    /// One point given as a `glam::Vec3`.
    pub fn evaluate_vec3(&self, p: glam::Vec3) -> Features32<3, N> {
        self.evaluate_f32(p.to_array())
    }

    /// One point given as a `glam::Vec3A`.
    pub fn evaluate_vec3a(&self, p: glam::Vec3A) -> Features32<3, N> {
        self.evaluate_f32(p.to_array())
    }

    /// Eight points given as `glam::Vec3`s.
    pub fn evaluate8_vec3(&self, p: &[glam::Vec3; 8]) -> Features8<3, N> {
        self.evaluate8(&p.map(|v| v.to_array().map(f64::from)))
    }
}

impl<const N: usize> Simd<4, N> {
    /// One point given as a `glam::Vec4`.
    pub fn evaluate_vec4(&self, p: glam::Vec4) -> Features32<4, N> {
        self.evaluate_f32(p.to_array())
    }
}
