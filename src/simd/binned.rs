//! # Binned batches: unordered samples that share cells share their points
//!
//! A renderer's hits come in any order, but a frame's hits are dense where
//! the texture is magnified: a feature tens of pixels wide holds hundreds
//! of them. [`Simd::evaluate_slice`] therefore sorts such a batch by cell
//! before it evaluates it:
//!
//! 1. **Bins.** Every sample is located as the per-sample kernel locates it
//!    (eight at a time), and counted in its bin of 2^d cells (a small
//!    open-addressing table; consecutive samples in one bin skip it).
//! 2. **Grouping.** A bin of at least eight samples per cell
//!    ([`min_shared`]) takes the shared path; its samples are grouped by
//!    bin (a counting sort), then by cell, into struct-of-arrays.
//! 3. **Tiles.** The bin's cells and a margin of one are generated once (a
//!    [`Region`]); each cell's samples run in tiles of up to `K × L::N`
//!    lanes against the points that can matter to the tile, each point
//!    broadcast to every lane: the grid tiles' idea (see
//!    [`coherent`](super::coherent)) for samples that are not on a grid.
//! 4. **The rest** (sparse bins, cells of fewer than [`MIN_RUN`] samples,
//!    bad or far coordinates, lanes a tile cannot certify) take the
//!    per-sample kernel; results are written back in input order.
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
//! The tile's own cell is inserted in every lane first; the largest F_n of
//! any lane then, U, bounds every lane's F_n for good. Of the cells around
//! it, a cell or a point farther than U from the lanes' bounding box is
//! skipped (U inflated twice by the grid tiles' slack, far more than any
//! rounding here). A lane is certified when its F_n is within U inflated
//! once and strictly inside its distance to the outside of the 3^d block,
//! deflated by the slack; a lane that is not certified is evaluated again
//! by the per-sample kernel, which is exact on its own.
//!
//! ## When it runs, and what it costs
//! In [`Mode::Exact`] only (window mode's answer depends on each sample's
//! own 3^d block, which a tile's wider candidates could beat), and only
//! when a strided probe of the batch finds samples sharing bins, and the
//! bins then find at least 30 % of the samples in dense bins: random
//! points spread over a large volume never pay for the bins, and a batch
//! that pays for them and finds them sparse takes the per-sample kernel in
//! input order. docs/simd.md has the measured cost of each step per
//! sample. The scratch buffers (the bins, the sorted samples, the region)
//! live in a thread-local value that grows to the largest batch seen, so a
//! renderer that calls the batch per tile does not reach the allocator
//! once warm.

use super::batch::Point;
use super::coherent::{inflate, lanes_from, largest, next_cell, write_lanes, Region, SLACK_ABS, SLACK_REL};
use super::lanes::{Lanes, One, WIDEST};
use super::{
    distance_of_rank, per_axis, Best, Chebyshev, Euclid, Features32, Manhattan, Metric32, Minkowski, Outputs, Simd,
    FAST_RANGE, ROUNDING, UNIT,
};
use crate::config::{Metric, Mode};
use std::any::Any;
use std::cell::RefCell;

/// Cells per axis of a bin: 2^[`BLOCK_BITS`].
pub(crate) const BLOCK: i64 = 1 << BLOCK_BITS;
/// Bits per axis of a cell's place in its bin.
const BLOCK_BITS: u32 = 1;
/// Fewest samples in a bin of 2^d cells for it to take the shared path
/// (eight per cell on average): below, the region's 4^d cells and the
/// sorting cost more than the per-sample kernel they save.
const fn min_shared<const D: usize>() -> usize {
    8 << D
}
/// Samples the probe looks at before a batch is binned.
const PROBE: usize = 512;
/// Smallest batch that is binned at all.
const MIN_BATCH: usize = 256;
/// Fewest samples of one cell that take a tile.
const MIN_RUN: usize = 8;

/// A located sample as the bins hold it: its fraction, and its cell's
/// place in its bin (base [`BLOCK`] digits, axis 0 lowest).
#[derive(Clone, Copy)]
struct Packed<const D: usize> {
    f: [f32; D],
    local: u32,
}

/// What one batch call keeps between calls.
struct Scratch<const D: usize, const N: usize> {
    /// Per sample, in input order: its bin (or [`NONE`]).
    bin: Vec<u32>,
    /// Per sample, in input order, where located.
    at: Vec<Packed<D>>,
    /// The bins' keys, and their sample counts, then their first index in
    /// `order`, then the index after their last.
    keys: Vec<u128>,
    count: Vec<u32>,
    /// Open addressing from a bin's key to its index in `keys`.
    table: Vec<u32>,
    /// The shared samples' input indices, grouped by bin.
    order: Vec<u32>,
    /// One bin's samples sorted by cell: input index and fraction per axis
    /// (struct-of-arrays, padded by [`WIDEST`]).
    sorted: Vec<u32>,
    fraction: [Vec<f32>; D],
    /// Samples for the per-sample kernel: their indices, points, results.
    rest: Vec<u32>,
    rest_points: Vec<[f64; D]>,
    rest_out: Vec<Features32<D, N>>,
    region: Region<D>,
}

const NONE: u32 = u32::MAX;

impl<const D: usize, const N: usize> Scratch<D, N> {
    /// The index of the bin with `key`, a new bin if there is none (open
    /// addressing; the table is kept at most half full).
    #[inline(never)]
    fn find(&mut self, key: u128) -> u32 {
        let mut cap = self.table.len();
        if 2 * (self.keys.len() + 1) > cap {
            cap *= 4;
            self.table.clear();
            self.table.resize(cap, NONE);
            for (i, &k) in self.keys.iter().enumerate() {
                let mut slot = hash_key(k) & (cap - 1);
                while self.table[slot] != NONE {
                    slot = (slot + 1) & (cap - 1);
                }
                self.table[slot] = i as u32;
            }
        }
        let mut slot = hash_key(key) & (cap - 1);
        loop {
            let b = self.table[slot];
            if b == NONE {
                let b = self.keys.len() as u32;
                self.table[slot] = b;
                self.keys.push(key);
                self.count.push(0);
                return b;
            }
            if self.keys[b as usize] == key {
                return b;
            }
            slot = (slot + 1) & (cap - 1);
        }
    }

    fn new() -> Self {
        Scratch {
            bin: Vec::new(),
            at: Vec::new(),
            keys: Vec::new(),
            count: Vec::new(),
            table: Vec::new(),
            order: Vec::new(),
            sorted: Vec::new(),
            fraction: std::array::from_fn(|_| Vec::new()),
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

/// The bin of a cell, its coordinates (each within the i32 range, since a
/// located cell is) packed 32 bits per axis.
#[inline(always)]
fn bin_key<const D: usize>(cell: &[i64; D]) -> u128 {
    let mut k = 0u128;
    for (a, &c) in cell.iter().enumerate() {
        k |= u128::from((c >> BLOCK_BITS) as i32 as u32) << (32 * a);
    }
    k
}

#[inline(always)]
fn hash_key(k: u128) -> usize {
    let h = ((k as u64) ^ ((k >> 64) as u64).rotate_left(29)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    (h >> 32) as usize
}

/// Lane vectors per tile: a tile's candidate search is shared by
/// `K × L::N` samples.
const K: usize = 8;

impl<const D: usize, const N: usize> Simd<D, N> {
    /// The cell of `x` as the per-sample kernel's fast path finds it, or
    /// `None` where that path would not run (a bad coordinate or one beyond
    /// [`FAST_RANGE`] cells).
    fn cell_of(&self, x: [f64; D]) -> Option<[i64; D]> {
        let scale = self.pattern.scale();
        let mut cell = [0i64; D];
        for a in 0..D {
            let u = x[a] * scale;
            if !(u.abs() < FAST_RANGE) {
                return None;
            }
            cell[a] = u.floor() as i64;
        }
        Some(cell)
    }

    /// Whether a batch of `xs` is worth binning: exact mode, enough
    /// samples, and a strided probe in which samples share bins.
    fn worth_binning<P: Point<D>>(&self, xs: &[P]) -> bool {
        if self.config.mode != Mode::Exact || xs.len() < MIN_BATCH {
            return false;
        }
        let step = (xs.len() / PROBE).max(1);
        let mut keys: Vec<u128> = Vec::with_capacity(PROBE);
        let mut probed = 0usize;
        for x in xs.iter().step_by(step).take(PROBE) {
            probed += 1;
            if let Some(cell) = self.cell_of(x.coordinates()) {
                keys.push(bin_key(&cell));
            }
        }
        keys.sort_unstable();
        keys.dedup();
        // Random points over a volume much larger than the batch's samples
        // land in a bin each; a frame's hits share bins even one sample in
        // `step` apart.
        probed as f64 > 1.05 * keys.len() as f64
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
        s.table.clear();
        s.table.resize(1024, NONE);
        // The bins: a key per sample, counted; each sample's fraction and
        // its cell's place in the bin, 16 bytes in 3D. Located eight at a
        // time as the per-sample kernel's fast path does (straight-line
        // code the compiler vectorises).
        let scale = self.pattern.scale();
        let mut last = (u128::MAX, NONE);
        for chunk in xs.chunks(8) {
            let mut u = [[0f64; 8]; D];
            for (i, x) in chunk.iter().enumerate() {
                let c = x.coordinates();
                for a in 0..D {
                    u[a][i] = c[a] * scale;
                }
            }
            let mut cell = [[0i32; 8]; D];
            let mut f = [[0f32; 8]; D];
            let mut ok = [true; 8];
            for a in 0..D {
                for i in 0..8 {
                    let v = u[a][i];
                    let r = (v + ROUNDING) - ROUNDING;
                    let floor = if r > v { r - 1.0 } else { r };
                    // The low word of the rounded sum is the floor's (see
                    // `Simd::locate`).
                    cell[a][i] = (floor + ROUNDING).to_bits() as u32 as i32;
                    f[a][i] = (v - floor) as f32 * UNIT;
                    ok[i] &= v.abs() < FAST_RANGE;
                }
            }
            for i in 0..chunk.len() {
                if !ok[i] {
                    s.bin.push(NONE);
                    s.at.push(Packed { f: [0.0; D], local: 0 });
                    continue;
                }
                let mut key = 0u128;
                let mut local = 0u32;
                for a in 0..D {
                    key |= u128::from((cell[a][i] >> BLOCK_BITS) as u32) << (32 * a);
                    local |= ((cell[a][i] & (BLOCK as i32 - 1)) as u32) << (BLOCK_BITS * a as u32);
                }
                let b = if key == last.0 { last.1 } else { s.find(key) };
                last = (key, b);
                s.count[b as usize] += 1;
                s.bin.push(b);
                s.at.push(Packed { f: per_axis(|a| f[a][i]), local });
            }
        }
        // A batch whose samples seldom share a bin takes the per-sample
        // kernel as it is, in input order.
        let dense: usize = s.count.iter().filter(|&&m| m as usize >= min_shared::<D>()).map(|&m| m as usize).sum();
        if dense * 10 < n * 3 {
            self.slice_per_sample(xs, out);
            return 0;
        }
        // Sparse bins go to the per-sample kernel; the others' samples are
        // grouped by bin (counts become each bin's first index, then the
        // index past its last).
        let mut total = 0u32;
        for c in s.count.iter_mut() {
            let m = *c;
            if (m as usize) < min_shared::<D>() {
                *c = NONE;
            } else {
                *c = total;
                total += m;
            }
        }
        s.order.clear();
        s.order.resize(total as usize, 0);
        for (i, &b) in s.bin.iter().enumerate() {
            if b == NONE || s.count[b as usize] == NONE {
                s.rest.push(i as u32);
                continue;
            }
            let slot = &mut s.count[b as usize];
            s.order[*slot as usize] = i as u32;
            *slot += 1;
        }
        // Each shared bin: its region, its samples by cell, its tiles.
        let ids = self.outputs != Outputs::Distances;
        let mut from = 0usize;
        while from < s.order.len() {
            let b = s.bin[s.order[from] as usize] as usize;
            let to = s.count[b] as usize;
            self.bin_tiles(out, s, b, from..to, ids);
            from = to;
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

    /// The samples `order[range]` of bin `b`: sorted by cell into
    /// struct-of-arrays, the region of their cells and a margin, and the
    /// tiles, one cell's samples each.
    fn bin_tiles(
        &self,
        out: &mut [Features32<D, N>],
        s: &mut Scratch<D, N>,
        b: usize,
        range: std::ops::Range<usize>,
        ids: bool,
    ) {
        let key = s.keys[b];
        let mut base = [0i64; D];
        for (a, b) in base.iter_mut().enumerate() {
            *b = i64::from((key >> (32 * a)) as u32 as i32) << BLOCK_BITS;
        }
        // Cell `k` of the bin (a place, see [`Packed`]).
        let cell_at = |k: usize| -> [i64; D] {
            let mut c = base;
            for (a, c) in c.iter_mut().enumerate() {
                *c += ((k >> (BLOCK_BITS * a as u32)) & (BLOCK as usize - 1)) as i64;
            }
            c
        };
        // By cell: a counting sort on the cell's place in the bin.
        let mut start = [0u32; (1 << (BLOCK_BITS as usize * 4)) + 1];
        for &i in &s.order[range.clone()] {
            start[s.at[i as usize].local as usize + 1] += 1;
        }
        let cells = 1usize << (BLOCK_BITS as usize * D);
        let (mut lo, mut hi) = ([i64::MAX; D], [i64::MIN; D]);
        for k in 0..cells {
            if start[k + 1] > 0 {
                let c = cell_at(k);
                for a in 0..D {
                    lo[a] = lo[a].min(c[a]);
                    hi[a] = hi[a].max(c[a]);
                }
            }
            start[k + 1] += start[k];
        }
        // Grown, never shrunk: the slots are all written below, and the
        // padding past them holds valid fractions (see `bin_run`).
        let len = range.len();
        if s.sorted.len() < len + WIDEST {
            s.sorted.resize(len + WIDEST, 0);
            for v in s.fraction.iter_mut() {
                v.resize(len + WIDEST, 0.0);
            }
        }
        for &i in &s.order[range] {
            let at = s.at[i as usize];
            let slot = &mut start[at.local as usize];
            let k = *slot as usize;
            s.sorted[k] = i;
            for (v, f) in s.fraction.iter_mut().zip(at.f) {
                v[k] = f;
            }
            *slot += 1;
        }
        let region_lo: [i64; D] = per_axis(|a| lo[a] - 1);
        let region_hi: [i64; D] = per_axis(|a| hi[a] + 1);
        s.region.fill(self, region_lo, region_hi, ids);
        // Each cell's slots: start[k] has moved to the cell's last + 1.
        let mut first = 0usize;
        for k in 0..cells {
            let end = start[k] as usize;
            if end > first {
                let run = Run { cell: cell_at(k), slots: first..end };
                let job = (&s.sorted[..], &s.fraction, &s.region);
                if end - first < MIN_RUN {
                    s.rest.extend_from_slice(&s.sorted[first..end]);
                } else {
                    self.bin_dispatch(run, job, &mut (&mut *out, &mut s.rest));
                }
            }
            first = end;
        }
    }

    /// Picks the tiles' monomorphised loop for the metric and outputs, in
    /// the widest lanes the build has.
    fn bin_dispatch(&self, run: Run<D>, job: Job<'_, D>, out: &mut Out<'_, D, N>) {
        #[cfg(target_feature = "avx512f")]
        type L = super::lanes::Sixteen;
        #[cfg(not(target_feature = "avx512f"))]
        type L = super::lanes::Eight;
        match (self.config.metric, self.outputs) {
            (Metric::Euclidean, o) => self.bin_outputs::<L, Euclid>(Euclid, o, run, job, out),
            (Metric::Manhattan, o) => self.bin_outputs::<L, Manhattan>(Manhattan, o, run, job, out),
            (Metric::Chebyshev, o) => self.bin_outputs::<L, Chebyshev>(Chebyshev, o, run, job, out),
            (Metric::Minkowski(p), o) => self.bin_outputs::<L, Minkowski>(Minkowski(p), o, run, job, out),
        }
    }

    fn bin_outputs<L: Lanes, M: Metric32>(
        &self,
        m: M,
        o: Outputs,
        run: Run<D>,
        job: Job<'_, D>,
        out: &mut Out<'_, D, N>,
    ) {
        match o {
            Outputs::Distances => self.bin_run::<L, M, false, false>(m, run, job, out),
            Outputs::Ids => self.bin_run::<L, M, true, false>(m, run, job, out),
            Outputs::IdsAndDeltas => self.bin_run::<L, M, true, true>(m, run, job, out),
        }
    }

    /// One cell's samples (`run.slots` of the sorted arrays) in tiles of
    /// up to `K × L::N`. The last vector of a tile may reach past the run:
    /// its extra lanes read the next samples' fractions (or the zero
    /// padding), valid positions in the cell whose results are dropped.
    fn bin_run<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        run: Run<D>,
        (sorted, fraction, region): Job<'_, D>,
        (out, rest): &mut Out<'_, D, N>,
    ) {
        let mut first = run.slots.start;
        while first < run.slots.end {
            let len = (run.slots.end - first).min(K * L::N);
            let used = len.div_ceil(L::N);
            // Vectors past `used` repeat the first; they are never read.
            let f: [[L::F; D]; K] = per_axis(|v| {
                let at = first + if v < used { v * L::N } else { 0 };
                per_axis(|a| L::f_load(&fraction[a][at..at + L::N]))
            });
            let mut best: [Best<L, D, N>; K] = per_axis(|_| Best::empty());
            let certified = self.bin_tile::<L, M, IDS, DELTAS>(metric, region, run.cell, &f, used, &mut best);
            for (v, b) in best.iter_mut().enumerate().take(used) {
                self.finish::<L, DELTAS>(b);
                let mut results = [Features32 { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; WIDEST];
                write_lanes::<L, D, N, IDS, DELTAS>(b, &mut results[..L::N]);
                let from = first + v * L::N;
                let mine = &sorted[from..(from + L::N).min(first + len)];
                for (j, &i) in mine.iter().enumerate() {
                    if certified[v] & (1 << j) != 0 {
                        out[i as usize] = results[j];
                    } else {
                        rest.push(i);
                    }
                }
            }
            first += len;
        }
    }

    /// One tile's search into `best` (empty): the lanes' fractions `f` in
    /// their common `cell`, `used` vectors of them. The cell's points in
    /// every lane, the bound they give, the other candidates, and the
    /// certificate. Returns the certified lanes of each vector as bits.
    #[inline(always)]
    fn bin_tile<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        region: &Region<D>,
        cell: [i64; D],
        f: &[[L::F; D]; K],
        used: usize,
        best: &mut [Best<L, D, N>; K],
    ) -> [u32; K] {
        // Point `p` into every vector: each lane's delta is its fraction
        // minus the point's cell corner relative to the lane's own cell,
        // f − (c − own)·UNIT (the `shift`), minus the point's coordinate.
        let candidate = |shift: &[[L::F; D]; K], p: usize, best: &mut [Best<L, D, N>; K]| {
            let q: [L::F; D] = per_axis(|a| L::f(region.q[a][p]));
            let id = if IDS { L::u(region.id[p]) } else { L::u(0) };
            for (v, b) in best.iter_mut().enumerate().take(used) {
                let delta: [L::F; D] = per_axis(|a| L::sub(shift[v][a], q[a]));
                let rank = metric.rank::<L, D>(&delta);
                if (IDS || DELTAS) && L::bits(L::le(rank, b.rank[N - 1])) == 0 {
                    continue;
                }
                b.insert::<IDS, DELTAS>(rank, if DELTAS { delta } else { [L::f(0.0); D] }, id);
            }
        };
        let shift_of =
            |corner: &[f32; D]| -> [[L::F; D]; K] { per_axis(|v| per_axis(|a| L::sub(f[v][a], L::f(corner[a])))) };
        // The own cell: every point in every lane.
        let own = region.cell(cell);
        let shift = shift_of(&[0.0; D]);
        for p in region.start[own] as usize..region.start[own + 1] as usize {
            candidate(&shift, p, best);
        }
        // The bound, and what it allows to skip; the lanes' box.
        let mut worst = best[0].rank[N - 1];
        let (mut blo, mut bhi) = (f[0], f[0]);
        for v in 1..used {
            worst = L::max(worst, best[v].rank[N - 1]);
            for a in 0..D {
                blo[a] = L::min(blo[a], f[v][a]);
                bhi[a] = L::max(bhi[a], f[v][a]);
            }
        }
        let bound = largest::<L, 1>([worst]);
        let (certify, prune) = if bound.is_finite() {
            let once = inflate(distance_of_rank::<One>(self.config.metric, bound));
            (metric.rank_of_distance::<One>(once), metric.rank_of_distance::<One>(inflate(once)))
        } else {
            (f32::INFINITY, f32::INFINITY)
        };
        let (blo, bhi): ([f32; D], [f32; D]) =
            (per_axis(|a| -largest::<L, 1>([L::sub(L::f(0.0), blo[a])])), per_axis(|a| largest::<L, 1>([bhi[a]])));
        let (blo_l, bhi_l): ([L::F; D], [L::F; D]) = (per_axis(|a| L::f(blo[a])), per_axis(|a| L::f(bhi[a])));
        // Per axis, the metric's term of the gap between the box and the
        // cells below, at and above the own cell.
        let terms: [[f32; 3]; D] =
            per_axis(|a| [metric.term::<One>(blo[a].max(0.0)), 0.0, metric.term::<One>((UNIT - bhi[a]).max(0.0))]);
        let index: [f32; WIDEST] = std::array::from_fn(|j| j as f32);
        let index = lanes_from::<L>(&index);
        let lo: [i64; D] = per_axis(|a| cell[a] - 1);
        let hi: [i64; D] = per_axis(|a| cell[a] + 1);
        let mut c = lo;
        loop {
            let o: [usize; D] = per_axis(|a| (c[a] - lo[a]) as usize);
            let mut gap = terms[0][o[0]];
            for a in 1..D {
                gap = metric.fold::<One>(gap, terms[a][o[a]]);
            }
            if c != cell && gap <= prune {
                // The cell's points, L::N at a time (the region is padded):
                // those within the pruning bound of the lanes' box.
                let corner: [f32; D] = per_axis(|a| (c[a] - cell[a]) as f32 * UNIT);
                let i = region.cell(c);
                let (s, e) = (region.start[i] as usize, region.start[i + 1] as usize);
                let mut g = s;
                while g < e {
                    let gaps: [L::F; D] = per_axis(|a| {
                        let x = L::add(L::f(corner[a]), L::f_load(&region.q[a][g..g + L::N]));
                        L::max(L::max(L::sub(blo_l[a], x), L::sub(x, bhi_l[a])), L::f(0.0))
                    });
                    let keep =
                        L::and(L::le(metric.rank::<L, D>(&gaps), L::f(prune)), L::lt(index, L::f((e - g) as f32)));
                    let mut bits = L::bits(keep);
                    if bits != 0 {
                        let shift = shift_of(&corner);
                        while bits != 0 {
                            let p = g + bits.trailing_zeros() as usize;
                            bits &= bits - 1;
                            candidate(&shift, p, best);
                        }
                    }
                    g += L::N;
                }
            }
            if !next_cell(&mut c, lo, hi) {
                break;
            }
        }
        // The certificate, per lane: the distance to the outside of the
        // own cell and its neighbours, deflated by the slack.
        let mut certified = [0u32; K];
        for (v, b) in best.iter().enumerate().take(used) {
            let mut edge = L::f(f32::INFINITY);
            for a in 0..D {
                edge = L::min(edge, L::min(L::add(f[v][a], L::f(UNIT)), L::sub(L::f(2.0 * UNIT), f[v][a])));
            }
            let edge = L::max(L::sub(L::mul(edge, L::f(1.0 - SLACK_REL)), L::f(SLACK_ABS)), L::f(0.0));
            let last = b.rank[N - 1];
            let ok = L::and(L::le(last, L::f(certify)), L::lt(last, metric.rank_of_distance::<L>(edge)));
            certified[v] = L::bits(ok);
        }
        certified
    }
}

/// One cell's run of sorted samples.
struct Run<const D: usize> {
    cell: [i64; D],
    slots: std::ops::Range<usize>,
}

/// What every tile of a bin reads: the sorted samples' input indices and
/// fractions, and the bin's region.
type Job<'a, const D: usize> = (&'a [u32], &'a [Vec<f32>; D], &'a Region<D>);

/// Where the tiles write: the results, and the samples left to the
/// per-sample kernel.
type Out<'a, const D: usize, const N: usize> = (&'a mut [Features32<D, N>], &'a mut Vec<u32>);

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
            // Tighter in 4D, where a cell has more neighbours to share with.
            let radius = [0.3, 1.0, 1.5][cluster % 3] * if D == 4 { 0.5 } else { 1.0 };
            for _ in 0..300 {
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
            agrees::<3, 2>(Config { order: 2, metric, seed: 7, ..Config::default() }, 0.4);
        }
        agrees::<2, 1>(Config { seed: 3, ..Config::default() }, 0.4);
        agrees::<4, 4>(Config { order: 4, seed: 11, ..Config::default() }, 0.3);
        // Sparse points: own cells often empty, so the bound comes from the
        // cells around or not at all.
        agrees::<3, 2>(Config { order: 2, density: 0.3, seed: 5, ..Config::default() }, 0.2);
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
