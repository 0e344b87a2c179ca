//! # Binned batches: unordered samples that share cells share their points
//!
//! A renderer's hits come in any order, but a frame's hits are dense: a
//! feature a few to a hundred pixels wide holds tens to thousands of them.
//! [`Simd::evaluate_slice`] therefore bins a batch by blocks of
//! [`BLOCK`]^d cells before it evaluates it. A block that holds at least
//! [`MIN_SHARED`] samples generates its cells' points once (with a margin of
//! one cell, a [`Region`]), sorts its samples by cell, and evaluates them
//! in *tiles* of `L::N` lanes against the points that can matter to the
//! tile, each broadcast to every lane: the grid tiles' idea (see
//! [`coherent`](super::coherent)) for samples that are not on a grid. The
//! other samples (sparse blocks, bad or far coordinates, lanes a tile cannot
//! certify) take the per-sample kernel; results are written back in input
//! order.
//!
//! ## Why the bits are the per-sample kernel's
//! A lane computes a candidate's delta as the per-sample kernel does: its
//! fraction minus the candidate cell's offset from its own cell (an exact
//! multiple of [`UNIT`]) minus the point's 24-bit coordinate, and its rank
//! with [`Metric32::rank`]. Points are ordered by rank and then by ID, so
//! the result depends only on which points a lane meets, and every point
//! that can be among a lane's n closest is met (below).
//!
//! ## Why every point that matters is met
//! The tile's own cells (the box of its lanes' cells) are inserted in every
//! lane first; the largest F_n of any lane then, U, bounds every lane's F_n
//! for good. Of the cells within one cell of the own box, a cell or a point
//! farther than U from the lanes' bounding box is skipped (U inflated twice
//! by the grid tiles' slack, far more than any rounding here). A lane is
//! certified when its F_n is within U inflated once and strictly inside its
//! distance to the outside of the searched cells, deflated by the slack;
//! a lane that is not certified is evaluated again by the per-sample
//! kernel, which is exact on its own.
//!
//! ## When it runs
//! In [`Mode::Exact`] only (window mode's answer depends on the 3^d block
//! of each sample, which a tile's wider search could beat), and only when a
//! strided probe of the batch finds samples sharing blocks: random points
//! spread over a large volume never pay for the binning. The scratch
//! buffers (the bins, the located samples, the region) live in a
//! thread-local value that grows to the largest batch seen, so a renderer
//! that calls the batch per tile does not reach the allocator once warm.

use super::batch::Point;
use super::coherent::{inflate, lanes_from, lanes_of, largest, next_cell, write_lanes, Region, SLACK_ABS, SLACK_REL};
use super::lanes::{Lanes, One, WIDEST};
use super::{
    distance_of_rank, per_axis, Best, Chebyshev, Euclid, Features32, Manhattan, Metric32, Minkowski, Outputs, Simd,
    FAST_RANGE, ROUNDING, UNIT,
};
use crate::config::{Metric, Mode};
use std::any::Any;
use std::cell::RefCell;

/// Cells per axis of a bin.
pub(crate) const BLOCK: i64 = 4;
/// Fewest samples in a bin for it to take the shared path: below, the
/// region's cells cost more than the per-sample kernel they save.
pub(crate) const MIN_SHARED: usize = 48;
/// Samples the probe looks at before a batch is binned.
const PROBE: usize = 512;
/// Smallest batch that is binned at all.
const MIN_BATCH: usize = 256;

/// A located sample: its cell and its fraction in lane units, as the
/// per-sample kernel's fast path computes them.
#[derive(Clone, Copy)]
struct Located<const D: usize> {
    cell: [i64; D],
    f: [f32; D],
}

/// What one batch call keeps between calls.
struct Scratch<const D: usize, const N: usize> {
    /// Per sample, in input order: its bin (or [`NONE`]).
    bin: Vec<u32>,
    /// Per sample, in input order, where located.
    at: Vec<Located<D>>,
    /// The bins' keys and sample counts, then their first index in `order`.
    keys: Vec<[i64; D]>,
    count: Vec<u32>,
    /// Open addressing from a bin's key to its index in `keys`.
    table: Vec<u32>,
    /// Sample indices grouped by bin.
    order: Vec<u32>,
    /// A bin's samples sorted by cell.
    sorted: Vec<u32>,
    /// Samples for the per-sample kernel: their indices, points, results.
    rest: Vec<u32>,
    rest_points: Vec<[f64; D]>,
    rest_out: Vec<Features32<D, N>>,
    region: Region<D>,
}

const NONE: u32 = u32::MAX;

impl<const D: usize, const N: usize> Scratch<D, N> {
    fn new() -> Self {
        Scratch {
            bin: Vec::new(),
            at: Vec::new(),
            keys: Vec::new(),
            count: Vec::new(),
            table: Vec::new(),
            order: Vec::new(),
            sorted: Vec::new(),
            rest: Vec::new(),
            rest_points: Vec::new(),
            rest_out: Vec::new(),
            region: Region::empty(),
        }
    }
}

thread_local! {
    /// One [`Scratch`] per dimension and order this thread has used.
    static SCRATCH: RefCell<Vec<Box<dyn Any>>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's scratch for `D` and `N` (a fresh one if the
/// thread's is in use).
fn with_scratch<const D: usize, const N: usize, R>(f: impl FnOnce(&mut Scratch<D, N>) -> R) -> R {
    let taken = SCRATCH.with(|s| {
        let mut all = s.try_borrow_mut().ok()?;
        let at = all.iter().position(|b| b.is::<Scratch<D, N>>())?;
        Some(all.swap_remove(at))
    });
    let mut boxed: Box<dyn Any> = taken.unwrap_or_else(|| Box::new(Scratch::<D, N>::new()));
    let r = f(boxed.downcast_mut::<Scratch<D, N>>().expect("the scratch of this type"));
    SCRATCH.with(|s| {
        if let Ok(mut all) = s.try_borrow_mut() {
            all.push(boxed);
        }
    });
    r
}

/// The bin of a cell.
#[inline(always)]
fn bin_key<const D: usize>(cell: &[i64; D]) -> [i64; D] {
    per_axis(|a| cell[a].div_euclid(BLOCK))
}

#[inline(always)]
fn hash_key<const D: usize>(k: &[i64; D]) -> u32 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for &v in k {
        h = (h ^ v as u64).wrapping_mul(0xff51_afd7_ed55_8ccd);
    }
    (h >> 32) as u32 ^ h as u32
}

/// A tile: up to `L::N` samples of one bin, in the frame of its
/// `reference` cell (the smallest of its lanes' cells per axis).
struct Tile<L: Lanes, const D: usize> {
    /// Per axis: the fraction in the lane's own cell (lane units), and that
    /// cell minus the reference, times [`UNIT`] (exact).
    f: [L::F; D],
    cl: [L::F; D],
    reference: [i64; D],
    /// The lanes' cells: largest per axis.
    hi: [i64; D],
    /// The lanes' bounding box in the tile's frame, lane units.
    blo: [f32; D],
    bhi: [f32; D],
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Locates `x` as the per-sample kernel's fast path does, or `None`
    /// where that path would not run (a bad coordinate or one beyond
    /// [`FAST_RANGE`] cells): such samples keep the per-sample kernel.
    #[inline(always)]
    fn locate_one(&self, x: [f64; D]) -> Option<Located<D>> {
        let scale = self.pattern.scale();
        let mut cell = [0i64; D];
        let mut f = [0f32; D];
        for a in 0..D {
            let u = x[a] * scale;
            if !(u.abs() < FAST_RANGE) {
                return None;
            }
            let r = (u + ROUNDING) - ROUNDING;
            let floor = if r > u { r - 1.0 } else { r };
            cell[a] = floor as i64;
            f[a] = (u - floor) as f32 * UNIT;
        }
        Some(Located { cell, f })
    }

    /// Whether a batch of `xs` is worth binning: exact mode, enough
    /// samples, and a strided probe in which samples share bins.
    fn worth_binning<P: Point<D>>(&self, xs: &[P]) -> bool {
        if self.config.mode != Mode::Exact || xs.len() < MIN_BATCH {
            return false;
        }
        let step = (xs.len() / PROBE).max(1);
        let mut keys: Vec<[i64; D]> = Vec::with_capacity(PROBE);
        let mut probed = 0usize;
        for x in xs.iter().step_by(step).take(PROBE) {
            probed += 1;
            if let Some(at) = self.locate_one(x.coordinates()) {
                keys.push(bin_key(&at.cell));
            }
        }
        keys.sort_unstable();
        keys.dedup();
        // With a bin per MIN_SHARED samples over the whole batch, the probe
        // (one sample in `step`) sees about MIN_SHARED / step samples per
        // bin: ask for a tenth of that much sharing.
        let per_bin = probed as f64 / keys.len().max(1) as f64;
        let expected = 1.0 + (MIN_SHARED as f64 / step as f64 - 1.0).max(0.0);
        per_bin >= 1.0 + 0.1 * (expected - 1.0) && per_bin > 1.05
    }

    /// [`Simd::evaluate_slice`] through the bins, if the batch is worth it;
    /// false (and nothing written) otherwise.
    pub(super) fn slice_binned<P: Point<D>>(&self, xs: &[P], out: &mut [Features32<D, N>]) -> bool {
        if !self.worth_binning(xs) {
            return false;
        }
        with_scratch::<D, N, _>(|s| self.binned(xs, out, s));
        true
    }

    /// Every sample of `xs` into `out` through the bins; returns how many
    /// the tiles certified (the others took the per-sample kernel).
    fn binned<P: Point<D>>(&self, xs: &[P], out: &mut [Features32<D, N>], s: &mut Scratch<D, N>) -> usize {
        let n = xs.len();
        s.bin.clear();
        s.at.clear();
        s.keys.clear();
        s.count.clear();
        s.rest.clear();
        let mut cap = 1024usize;
        s.table.clear();
        s.table.resize(cap, NONE);
        // The bins: a key per sample, counted.
        let mut last: Option<([i64; D], u32)> = None;
        for x in xs {
            let Some(at) = self.locate_one(x.coordinates()) else {
                s.bin.push(NONE);
                s.at.push(Located { cell: [0; D], f: [0.0; D] });
                continue;
            };
            let key = bin_key(&at.cell);
            let b = match last {
                Some((k, b)) if k == key => b,
                _ => {
                    if 2 * (s.keys.len() + 1) > cap {
                        cap *= 4;
                        s.table.clear();
                        s.table.resize(cap, NONE);
                        for (i, k) in s.keys.iter().enumerate() {
                            let mut slot = hash_key(k) as usize & (cap - 1);
                            while s.table[slot] != NONE {
                                slot = (slot + 1) & (cap - 1);
                            }
                            s.table[slot] = i as u32;
                        }
                    }
                    let mut slot = hash_key(&key) as usize & (cap - 1);
                    loop {
                        let b = s.table[slot];
                        if b == NONE {
                            let b = s.keys.len() as u32;
                            s.table[slot] = b;
                            s.keys.push(key);
                            s.count.push(0);
                            break b;
                        }
                        if s.keys[b as usize] == key {
                            break b;
                        }
                        slot = (slot + 1) & (cap - 1);
                    }
                }
            };
            last = Some((key, b));
            s.count[b as usize] += 1;
            s.bin.push(b);
            s.at.push(at);
        }
        // Sparse bins go to the per-sample kernel; the others' samples are
        // grouped by bin (counts become each bin's first index).
        let mut total = 0u32;
        for c in s.count.iter_mut() {
            let m = *c;
            if (m as usize) < MIN_SHARED {
                *c = NONE;
            } else {
                *c = total;
                total += m;
            }
        }
        s.order.clear();
        s.order.resize(total as usize, 0);
        let mut next = s.count.clone();
        for i in 0..n {
            let b = s.bin[i];
            if b == NONE || next[b as usize] == NONE {
                s.rest.push(i as u32);
                continue;
            }
            s.order[next[b as usize] as usize] = i as u32;
            next[b as usize] += 1;
        }
        // Each shared bin: its region, its samples by cell, its tiles.
        let ids = self.outputs != Outputs::Distances;
        let mut b_start = 0usize;
        while b_start < s.order.len() {
            let b = s.bin[s.order[b_start] as usize] as usize;
            let b_end = next[b] as usize;
            self.bin_tiles(xs, out, s, b_start, b_end, ids);
            b_start = b_end;
        }
        let shared = n - s.rest.len();
        // The rest, sample by sample, and written back in place.
        if !s.rest.is_empty() {
            s.rest_points.clear();
            s.rest_points.extend(s.rest.iter().map(|&i| xs[i as usize].coordinates()));
            let empty = Features32 { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] };
            s.rest_out.clear();
            s.rest_out.resize(s.rest.len(), empty);
            self.slice_per_sample(&s.rest_points, &mut s.rest_out);
            for (&i, r) in s.rest.iter().zip(&s.rest_out) {
                out[i as usize] = *r;
            }
        }
        shared
    }

    /// The samples `order[from..to]` of one bin: the region of their
    /// cells and a margin, the samples sorted by cell, and the tiles.
    fn bin_tiles<P: Point<D>>(
        &self,
        xs: &[P],
        out: &mut [Features32<D, N>],
        s: &mut Scratch<D, N>,
        from: usize,
        to: usize,
        ids: bool,
    ) {
        let _ = xs;
        let mut lo = [i64::MAX; D];
        let mut hi = [i64::MIN; D];
        for &i in &s.order[from..to] {
            let c = s.at[i as usize].cell;
            for a in 0..D {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        // By cell: a counting sort on the cell's index in the bin's box.
        let side: [usize; D] = per_axis(|a| (hi[a] - lo[a] + 1) as usize);
        let cells: usize = side.iter().product();
        let index = |c: &[i64; D]| {
            let mut k = 0usize;
            for a in (0..D).rev() {
                k = k * side[a] + (c[a] - lo[a]) as usize;
            }
            k
        };
        let mut start = [0u32; 257];
        let start = &mut start[..cells + 1];
        for &i in &s.order[from..to] {
            start[index(&s.at[i as usize].cell) + 1] += 1;
        }
        for k in 0..cells {
            start[k + 1] += start[k];
        }
        s.sorted.clear();
        s.sorted.resize(to - from, 0);
        for &i in &s.order[from..to] {
            let k = index(&s.at[i as usize].cell);
            s.sorted[start[k] as usize] = i;
            start[k] += 1;
        }
        let region_lo: [i64; D] = per_axis(|a| lo[a] - 1);
        let region_hi: [i64; D] = per_axis(|a| hi[a] + 1);
        s.region.fill(self, region_lo, region_hi, ids);
        let (sorted, at, region, rest) = (&s.sorted, &s.at, &s.region, &mut s.rest);
        self.bin_dispatch(sorted, at, region, out, rest);
    }

    /// Picks the tiles' monomorphised loop for the metric and outputs, in
    /// the widest lanes the build has.
    fn bin_dispatch(
        &self,
        sorted: &[u32],
        at: &[Located<D>],
        region: &Region<D>,
        out: &mut [Features32<D, N>],
        rest: &mut Vec<u32>,
    ) {
        #[cfg(target_feature = "avx512f")]
        type L = super::lanes::Sixteen;
        #[cfg(not(target_feature = "avx512f"))]
        type L = super::lanes::Eight;
        let job = (sorted, at, region);
        match (self.config.metric, self.outputs) {
            (Metric::Euclidean, o) => self.bin_outputs::<L, Euclid>(Euclid, o, job, out, rest),
            (Metric::Manhattan, o) => self.bin_outputs::<L, Manhattan>(Manhattan, o, job, out, rest),
            (Metric::Chebyshev, o) => self.bin_outputs::<L, Chebyshev>(Chebyshev, o, job, out, rest),
            (Metric::Minkowski(p), o) => self.bin_outputs::<L, Minkowski>(Minkowski(p), o, job, out, rest),
        }
    }

    fn bin_outputs<L: Lanes, M: Metric32>(
        &self,
        m: M,
        o: Outputs,
        job: (&[u32], &[Located<D>], &Region<D>),
        out: &mut [Features32<D, N>],
        rest: &mut Vec<u32>,
    ) {
        match o {
            Outputs::Distances => self.bin_run::<L, M, false, false>(m, job, out, rest),
            Outputs::Ids => self.bin_run::<L, M, true, false>(m, job, out, rest),
            Outputs::IdsAndDeltas => self.bin_run::<L, M, true, true>(m, job, out, rest),
        }
    }

    /// The tiles of one bin's sorted samples: consecutive samples whose
    /// cells stay within two per axis share a tile.
    fn bin_run<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        (sorted, at, region): (&[u32], &[Located<D>], &Region<D>),
        out: &mut [Features32<D, N>],
        rest: &mut Vec<u32>,
    ) {
        let mut k = 0;
        while k < sorted.len() {
            // The tile's lanes.
            let first = at[sorted[k] as usize].cell;
            let (mut lo, mut hi) = (first, first);
            let mut len = 0;
            while len < L::N && k + len < sorted.len() {
                let c = at[sorted[k + len] as usize].cell;
                let (nlo, nhi): ([i64; D], [i64; D]) = (per_axis(|a| lo[a].min(c[a])), per_axis(|a| hi[a].max(c[a])));
                if (0..D).any(|a| nhi[a] - nlo[a] > 1) {
                    break;
                }
                (lo, hi) = (nlo, nhi);
                len += 1;
            }
            let lanes = &sorted[k..k + len];
            k += len;
            let mut f = [[0f32; WIDEST]; D];
            let mut cl = [[0f32; WIDEST]; D];
            let mut blo = [f32::INFINITY; D];
            let mut bhi = [f32::NEG_INFINITY; D];
            for j in 0..L::N {
                // Lanes past the tile's samples repeat its first.
                let s = &at[lanes[if j < len { j } else { 0 }] as usize];
                for a in 0..D {
                    f[a][j] = s.f[a];
                    cl[a][j] = (s.cell[a] - lo[a]) as f32 * UNIT;
                    let p = cl[a][j] + f[a][j];
                    blo[a] = blo[a].min(p);
                    bhi[a] = bhi[a].max(p);
                }
            }
            let t = Tile::<L, D> {
                f: per_axis(|a| lanes_from::<L>(&f[a])),
                cl: per_axis(|a| lanes_from::<L>(&cl[a])),
                reference: lo,
                hi,
                blo,
                bhi,
            };
            let mut best = Best::<L, D, N>::empty();
            let certified = self.bin_tile::<L, M, IDS, DELTAS>(metric, region, &t, &mut best);
            self.finish::<L, true>(&mut best);
            let mut results = [Features32 { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; WIDEST];
            write_lanes::<L, D, N, true, true>(&best, &mut results[..L::N]);
            for (j, &i) in lanes.iter().enumerate() {
                if certified & (1 << j) != 0 {
                    out[i as usize] = results[j];
                } else {
                    rest.push(i);
                }
            }
        }
    }

    /// One tile's search into `best` (empty): the own cells, the bound
    /// they give, the other candidates, and the certificate. Returns the
    /// certified lanes as bits.
    #[inline(always)]
    fn bin_tile<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        region: &Region<D>,
        t: &Tile<L, D>,
        best: &mut Best<L, D, N>,
    ) -> u32 {
        // Each lane's fraction minus the corner of cell `c`, relative to
        // its own cell: f − (c − own)·UNIT, with (c − own)·UNIT an exact
        // difference of exact multiples of UNIT.
        let shift = |c: &[i64; D]| -> [L::F; D] {
            per_axis(|a| L::sub(t.f[a], L::sub(L::f((c[a] - t.reference[a]) as f32 * UNIT), t.cl[a])))
        };
        let insert_cell = |c: &[i64; D], prune: Option<f32>, best: &mut Best<L, D, N>| {
            let i = region.cell(*c);
            let (s, e) = (region.start[i] as usize, region.start[i + 1] as usize);
            let sh = shift(c);
            let corner: [f32; D] = per_axis(|a| (c[a] - t.reference[a]) as f32 * UNIT);
            for p in s..e {
                let q: [f32; D] = per_axis(|a| region.q[a][p]);
                if let Some(prune) = prune {
                    let gap: [f32; D] = per_axis(|a| {
                        let x = corner[a] + q[a];
                        (t.blo[a] - x).max(x - t.bhi[a]).max(0.0)
                    });
                    if metric.rank::<One, D>(&gap) > prune {
                        continue;
                    }
                }
                let delta: [L::F; D] = per_axis(|a| L::sub(sh[a], L::f(q[a])));
                let rank = metric.rank::<L, D>(&delta);
                if (IDS || DELTAS) && L::bits(L::le(rank, best.rank[N - 1])) == 0 {
                    continue;
                }
                let id = if IDS { L::u(region.id[p]) } else { L::u(0) };
                best.insert::<IDS, DELTAS>(rank, if DELTAS { delta } else { [L::f(0.0); D] }, id);
            }
        };
        // The own cells: every point in every lane.
        let mut c = t.reference;
        loop {
            insert_cell(&c, None, best);
            if !next_cell(&mut c, t.reference, t.hi) {
                break;
            }
        }
        // The bound, and what it allows to skip.
        let bound = largest::<L, 1>([best.rank[N - 1]]);
        let (certify, prune) = if bound.is_finite() {
            let once = inflate(distance_of_rank::<One>(self.config.metric, bound));
            (metric.rank_of_distance::<One>(once), metric.rank_of_distance::<One>(inflate(once)))
        } else {
            (f32::INFINITY, f32::INFINITY)
        };
        let lo: [i64; D] = per_axis(|a| t.reference[a] - 1);
        let hi: [i64; D] = per_axis(|a| t.hi[a] + 1);
        let mut c = lo;
        loop {
            let own = (0..D).all(|a| c[a] >= t.reference[a] && c[a] <= t.hi[a]);
            if !own {
                let gap: [f32; D] = per_axis(|a| {
                    let corner = (c[a] - t.reference[a]) as f32 * UNIT;
                    (corner - t.bhi[a]).max(t.blo[a] - (corner + UNIT)).max(0.0)
                });
                if metric.rank::<One, D>(&gap) <= prune {
                    insert_cell(&c, if prune.is_finite() { Some(prune) } else { None }, best);
                }
            }
            if !next_cell(&mut c, lo, hi) {
                break;
            }
        }
        // The certificate, per lane.
        let mut edge = L::f(f32::INFINITY);
        for a in 0..D {
            let p = L::add(t.cl[a], t.f[a]);
            let (low, high) = (-UNIT, (hi[a] + 1 - t.reference[a]) as f32 * UNIT);
            edge = L::min(edge, L::min(L::sub(p, L::f(low)), L::sub(L::f(high), p)));
        }
        let edge = L::max(L::sub(L::mul(edge, L::f(1.0 - SLACK_REL)), L::f(SLACK_ABS)), L::f(0.0));
        let last = best.rank[N - 1];
        let ok = L::and(L::le(last, L::f(certify)), L::lt(last, metric.rank_of_distance::<L>(edge)));
        let _ = lanes_of::<L>;
        L::bits(ok)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::math::uniform;

    /// A renderer's kind of batch, in cells of the pattern: clusters of
    /// samples a few cells wide (dense enough to share), in a shuffled
    /// order, with samples on cell faces and lattice corners, repeated
    /// samples (ties in every lane of a tile), bad coordinates (NaN, ±∞,
    /// beyond 2^31 cells) and a sprinkle of far, lonely samples.
    fn batch<const D: usize>(seed: u64, scale: f64) -> Vec<[f64; D]> {
        let mut k = 0u64;
        let mut u = || {
            k += 1;
            uniform(seed, k)
        };
        let mut xs = Vec::new();
        for cluster in 0..12 {
            let centre: [f64; D] = std::array::from_fn(|_| (u() - 0.5) * 200.0);
            let radius = [0.3, 1.0, 1.5][cluster % 3];
            for _ in 0..200 {
                let mut x: [f64; D] = std::array::from_fn(|a| centre[a] + (u() - 0.5) * 2.0 * radius);
                match (u() * 16.0) as u32 {
                    // On a lattice corner, or on one face.
                    0 => x = x.map(|v| v.round()),
                    1 => x[0] = x[0].round(),
                    _ => {}
                }
                xs.push(x.map(|v| v / scale));
            }
        }
        let n = xs.len();
        for i in 0..40 {
            let j = (u() * n as f64) as usize;
            xs.push(xs[j]);
            let mut bad = xs[(u() * n as f64) as usize];
            bad[i % D] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 3.0e10 / scale, -1.0e300][i % 5];
            xs.push(bad);
            xs.push(std::array::from_fn(|_| (u() - 0.5) * 1.0e6));
        }
        // Shuffled (Fisher-Yates).
        for i in (1..xs.len()).rev() {
            let j = (u() * (i + 1) as f64) as usize;
            xs.swap(i, j.min(i));
        }
        xs
    }

    fn same_bits<const D: usize, const N: usize>(a: &Features32<D, N>, b: &Features32<D, N>) -> bool {
        let bits = |f: &Features32<D, N>| (f.distance.map(f32::to_bits), f.id, f.delta.map(|d| d.map(f32::to_bits)));
        bits(a) == bits(b)
    }

    /// The bins give the per-sample kernel's bits for every sample, and the
    /// tiles, not the fallback, gave most of them.
    fn agrees<const D: usize, const N: usize>(config: Config, least_shared: f64) {
        for outputs in [Outputs::Distances, Outputs::Ids, Outputs::IdsAndDeltas] {
            let simd = Simd::<D, N>::new(config, outputs).unwrap();
            let xs = batch::<D>(config.seed ^ 0x5eed, simd.pattern.scale());
            let empty = Features32 { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] };
            let mut binned = vec![empty; xs.len()];
            let mut scratch = Scratch::<D, N>::new();
            let shared = simd.binned(&xs, &mut binned, &mut scratch);
            // Again with the warm scratch: the same bits.
            let mut again = vec![empty; xs.len()];
            assert_eq!(simd.binned(&xs, &mut again, &mut scratch), shared);
            let mut per_sample = vec![empty; xs.len()];
            simd.slice_per_sample(&xs, &mut per_sample);
            for (i, x) in xs.iter().enumerate() {
                assert!(
                    same_bits(&binned[i], &per_sample[i]) && same_bits(&again[i], &binned[i]),
                    "{config:?} {outputs:?} sample {i} at {x:?}: binned {:?}, per sample {:?}",
                    binned[i],
                    per_sample[i]
                );
            }
            // One in ten against the one-point entry, which shares no code
            // with either batch path's loop.
            for (x, r) in xs.iter().zip(&binned).step_by(10) {
                assert!(same_bits(r, &simd.evaluate(*x)), "{config:?} {outputs:?} at {x:?}");
            }
            assert!(
                shared as f64 >= least_shared * xs.len() as f64,
                "{config:?}: only {shared} of {} samples shared",
                xs.len()
            );
        }
    }

    #[test]
    fn bins_agree_with_the_per_sample_kernel() {
        for metric in [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0)] {
            agrees::<3, 2>(Config { order: 2, metric, seed: 7, ..Config::default() }, 0.5);
        }
        agrees::<2, 1>(Config { seed: 3, ..Config::default() }, 0.5);
        agrees::<4, 4>(Config { order: 4, seed: 11, ..Config::default() }, 0.5);
        // Sparse points: own cells often empty, so the bound comes from the
        // cells around or not at all.
        agrees::<3, 2>(Config { order: 2, density: 0.3, seed: 5, ..Config::default() }, 0.25);
    }

    #[test]
    fn only_dense_exact_batches_are_binned() {
        let simd = Simd::<3, 1>::new(Config::default(), Outputs::Distances).unwrap();
        let scale = simd.pattern.scale();
        let dense = batch::<3>(1, scale);
        assert!(simd.worth_binning(&dense));
        let random: Vec<[f64; 3]> =
            (0..20_000).map(|i| std::array::from_fn(|a| (uniform(2, (3 * i + a) as u64) - 0.5) * 2000.0)).collect();
        assert!(!simd.worth_binning(&random));
        let window = Simd::<3, 1>::new(Config { mode: Mode::Window, ..Config::default() }, Outputs::Distances).unwrap();
        assert!(!window.worth_binning(&dense));
    }
}
