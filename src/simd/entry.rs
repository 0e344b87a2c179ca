//! The per-sample kernel's entry points: building an evaluator, one point,
//! eight, lanes per axis, and the dispatch from the configuration's metric
//! and outputs to a monomorphised search ([`search`](super::search)).

use wide::f32x8;

use super::best::Best;
use super::features::{Features32, Features8};
use super::generate::{PointConstants, Splat, WideConstants, UNIT};
use super::lanes::{Eight, Lanes, One, WIDEST};
use super::locate::Located;
use super::metric::{distance_of_rank, Euclid, Others};
use super::search::{logical_block, mark_invalid, Stages, WHOLE};
use super::{runtime_avx512, Outputs, Simd};
use crate::config::{Config, ConfigError, Metric};
use crate::definition::{lcg_jump, Pattern};

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
        let best = self.dispatch_one(&located).0;
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
    /// the CPU has it (see [`runtime_avx2`](super::runtime_avx2)): the same operations, so the
    /// same bits, in fewer instructions.
    #[inline(always)]
    pub(super) fn dispatch8(&self, at: &Located<Eight, D>) -> Best<Eight, D, N> {
        self.dispatch8_whole(at).0
    }

    /// [`dispatch8_whole`], for the entry points that take a kernel.
    #[inline(always)]
    pub(super) fn dispatch8_whole(&self, at: &Located<Eight, D>) -> Stages<Eight, D, N> {
        dispatch8_whole(self, at)
    }

    /// [`dispatch_one`], for the entry points that take a kernel.
    #[inline(always)]
    pub(super) fn dispatch_one(&self, at: &Located<One, D>) -> Stages<One, D, N> {
        dispatch_one(self, at)
    }
}

/// The whole 8-lane search ([`Simd::dispatch8_stage`]), out of line:
/// one copy per kernel that every eight-lane entry point calls (eight
/// points, periodic, in a cell, a grid's per-sample lanes, the border),
/// where each would otherwise compile the search into itself.
#[inline(never)]
pub(super) fn dispatch8_whole<const D: usize, const N: usize>(
    kernel: &Simd<D, N>,
    at: &Located<Eight, D>,
) -> Stages<Eight, D, N> {
    kernel.dispatch8_stage::<WHOLE>(at, Best::empty())
}

/// The whole one-lane search, out of line for the same reason as
/// [`dispatch8_whole`]: one point, periodic, in a cell, the
/// border's one point.
#[inline(never)]
pub(super) fn dispatch_one<const D: usize, const N: usize>(
    kernel: &Simd<D, N>,
    at: &Located<One, D>,
) -> Stages<One, D, N> {
    kernel.dispatch_stage::<One, WHOLE>(at, Best::empty())
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// [`Simd::dispatch8`], or one stage of the search (see [`Stages`]).
    #[inline(always)]
    pub(super) fn dispatch8_stage<const STAGE: u8>(
        &self,
        at: &Located<Eight, D>,
        start: Best<Eight, D, N>,
    ) -> Stages<Eight, D, N> {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if super::runtime_avx2() {
            // SAFETY: `dispatch_avx2` requires AVX2 and nothing else, and
            // `runtime_avx2` has just seen the CPU report it.
            #[allow(unsafe_code)]
            return unsafe { dispatch_avx2::<D, N, STAGE>(self, at, start) };
        }
        self.dispatch_stage::<Eight, STAGE>(at, start)
    }
}

/// [`Simd::dispatch_stage`] in eight lanes, compiled with AVX2 enabled: `wide`
/// keeps the SSE2 code it was built with, but LLVM lowers the Euclidean
/// kernels inlined here again, turning the scalar fallbacks inside them
/// (the 32-bit lane multiply above all) into AVX2 instructions. The
/// other metrics go through the out-of-line `search_outputs`.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
#[target_feature(enable = "avx2")]
pub(super) fn dispatch_avx2<const D: usize, const N: usize, const STAGE: u8>(
    kernel: &Simd<D, N>,
    at: &Located<Eight, D>,
    start: Best<Eight, D, N>,
) -> Stages<Eight, D, N> {
    kernel.dispatch_stage::<Eight, STAGE>(at, start)
}

impl<const D: usize, const N: usize> Simd<D, N> {
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
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// The monomorphised search for the metric and outputs, then distances
    /// from ranks and bad lanes marked: the whole search, or one stage of
    /// it (see [`Stages`]), from the candidates in `start`.
    #[inline(always)]
    pub(super) fn dispatch_stage<L: Lanes, const STAGE: u8>(
        &self,
        at: &Located<L, D>,
        start: Best<L, D, N>,
    ) -> Stages<L, D, N> {
        self.dispatch_metric::<L, STAGE, true>(at, start)
    }

    /// [`Simd::dispatch_stage`] for a caller that runs only the Euclidean
    /// metric (it has checked the configuration's): the other metrics'
    /// search is not instantiated in it. Given another metric it would
    /// return `start`'s candidates with every lane final.
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
    #[inline(always)]
    pub(super) fn dispatch_euclid_stage<L: Lanes, const STAGE: u8>(
        &self,
        at: &Located<L, D>,
        start: Best<L, D, N>,
    ) -> Stages<L, D, N> {
        debug_assert_eq!(self.config.metric, Metric::Euclidean);
        self.dispatch_metric::<L, STAGE, false>(at, start)
    }

    /// The search for the configuration's metric and outputs (the other
    /// metrics only where `OTHERS`), then distances and bad lanes.
    #[inline(always)]
    fn dispatch_metric<L: Lanes, const STAGE: u8, const OTHERS: bool>(
        &self,
        at: &Located<L, D>,
        start: Best<L, D, N>,
    ) -> Stages<L, D, N> {
        let (raw, open) = match (Others::of(self.config.metric), self.outputs) {
            (None, Outputs::Distances) => self.search::<L, Euclid, false, false, STAGE>(Euclid, at, start),
            (None, Outputs::Ids) => self.search::<L, Euclid, true, false, STAGE>(Euclid, at, start),
            (None, Outputs::IdsAndDeltas) => self.search::<L, Euclid, true, true, STAGE>(Euclid, at, start),
            (Some(m), o) if OTHERS => search_outputs::<D, N, L, STAGE>(self, m, o, at, start),
            (Some(_), _) => (start, L::lt(L::f(1.0), L::f(0.0))),
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
    pub(super) fn finish<L: Lanes, const DELTAS: bool>(&self, best: &mut Best<L, D, N>) {
        let (unit, inv) = (L::f(1.0 / UNIT), L::f(self.inv_scale));
        let metric = self.config.metric;
        for k in 0..N {
            best.rank[k] = L::mul(L::mul(distance_of_rank::<L>(metric, best.rank[k]), unit), inv);
            for a in (0..D).filter(|_| DELTAS) {
                best.delta[k][a] = L::mul(L::mul(best.delta[k][a], unit), inv);
            }
        }
    }
}

/// The kernels of the other metrics, kept out of line: a default
/// build's AVX2 copy then holds only the Euclidean kernels (see
/// [`dispatch_avx2`]), and the other metrics run the build's own
/// instructions.
///
/// One instantiation serves the three metrics ([`Others`], chosen at
/// run time) and every output set: the search with IDs and deltas, then
/// the outputs not asked for put back to what the search without them
/// leaves (`start`'s, never written). The distances are the same bits:
/// the list holds the same N smallest ranks whether ties are ordered by
/// ID or not. Each instantiation of the search is a sizeable part of a
/// user's build, and these metrics are the rarer ones.
#[inline(never)]
pub(super) fn search_outputs<const D: usize, const N: usize, L: Lanes, const STAGE: u8>(
    kernel: &Simd<D, N>,
    m: Others,
    o: Outputs,
    at: &Located<L, D>,
    start: Best<L, D, N>,
) -> (Best<L, D, N>, L::M) {
    let (id, delta) = (start.id, start.delta);
    let (mut best, open) = kernel.search::<L, Others, true, true, STAGE>(m, at, start);
    if o != Outputs::IdsAndDeltas {
        best.delta = delta;
    }
    if o == Outputs::Distances {
        best.id = id;
    }
    (best, open)
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
