//! # A grid's samples sharing their F1 points
//!
//! The n-sphere radius depends on F1's point alone, and a grid's
//! neighbouring samples mostly share that point: a grid's samples take F1
//! with its ID from the grid tiles (the per-sample kernel's bits), and each
//! point is evaluated once for all the samples it is F1 of. Two ways:
//! - **by point** ([`SimdNSphere::by_points`]), where the IDs are shown to
//!   tell the points apart: the runs of one ID along each row share one
//!   evaluation at the point's exact position, taken from the generated
//!   cells, with no search for F1 or its point;
//! - **by sample** ([`SimdNSphere::by_samples`]) otherwise, or where the
//!   samples are too sparse for the box of cells the first needs: samples
//!   with the same ID and position share the per-sample path's result.

use std::collections::HashMap;

use super::super::super::batch::in_cell;
use super::super::super::coherent::GridRows;
use super::super::super::lanes::Eight;
use super::super::super::region::{next_cell, Region};
use super::super::super::tiles::Nearest;
use super::super::super::{Features32, Grid};
use super::{sphere, NSphere32, SimdNSphere};
use crate::definition::{FRACTION_BITS, INVALID_ID, MAX_CELL_COORD};

impl<const D: usize> SimdNSphere<D> {
    /// Rows `first..` of a grid (whole rows; `rows` from a kernel of this
    /// configuration) into `out`: the bits [`SimdNSphere::n_sphere_grid`]
    /// writes for them. The radius depends on F1's point alone, and a
    /// grid's neighbouring samples mostly share it, so F1 with its ID comes
    /// from the grid tiles (the per-sample kernel's bits) and the samples
    /// share the evaluations of their points: by ID where the IDs tell the
    /// points apart ([`SimdNSphere::by_points`]), by ID and position
    /// otherwise ([`SimdNSphere::by_samples`]).
    pub(crate) fn grid_rows_into(&self, rows: &GridRows<'_, D>, first: usize, out: &mut [NSphere32]) {
        if out.is_empty() {
            return;
        }
        let grid = rows.grid();
        if dense(grid, first, out.len(), self.first.pattern.scale()) {
            let mut f1 = vec![Nearest::default(); out.len()];
            self.ids.grid_rows_into(rows, first, &mut f1);
            if self.by_points(grid, first, &f1, out) {
                return;
            }
        }
        let mut f1 = vec![Features32::<D, 1>::default(); out.len()];
        self.first.grid_rows_into(rows, first, &mut f1);
        self.by_samples(grid, first, &f1, out);
    }

    /// The grid's samples (rows `first..`, F1 of each with its ID in `f1`)
    /// sharing one evaluation per F1 point, the points told apart by their
    /// IDs alone. That holds where no two points that could be a sample's
    /// F1 share an ID, which this checks: every such point lies within the
    /// samples' box of cells widened by the largest F1 at the ends of the
    /// rows' runs of one ID (or two of the box's points share an ID), and
    /// the box's points are generated and their IDs matched against the
    /// samples'.
    /// Each point is then evaluated at its exact position, as the
    /// per-sample path finds it (F2 there), with no search for F1 or its
    /// point.
    ///
    /// False, with nothing written, where two of the box's points carry one
    /// of the samples' IDs (for any one ID about n/2^32, n the box's
    /// points), the widened box has more cells than there are samples, or
    /// a sample has an ID but no finite F1.
    fn by_points(&self, grid: &Grid<D>, first: usize, f1: &[Nearest], out: &mut [NSphere32]) -> bool {
        let width = grid.size[0];
        // The samples as runs of one ID along a row: where each run ends
        // (an index into `out`) and 1 + the index of its ID in `ids`, or 0
        // for none (bad input or an empty window: INVALID_ID, which no real
        // point carries). A run has one point once the IDs are shown to
        // tell the points apart.
        let mut runs: Vec<(usize, u32)> = Vec::new();
        let mut ids: Vec<u32> = Vec::new();
        let mut index = IdTable::new();
        // The largest F1 at the runs' ends, as bits (finite distances are
        // not negative, so their bits order as they do). The box widened
        // by it holds every sample's F1 point, or else two of its points
        // share an ID and the box shows it. The F1 points of a run's ends
        // are within it of those ends. If the two are one point P, every
        // sample between them has F1 at most its distance to P, which
        // along the row is largest at an end: its own F1 point is within
        // the reach too. (The margin's extra cell covers the rounding of
        // f32 distances.)
        let mut reach = 0u32;
        // The previous row's runs, in `runs`.
        let mut above = 0..0;
        // Where the current row's runs start (and, last, its width).
        let mut starts: Vec<usize> = Vec::with_capacity(width + 1);
        for (r, row) in f1.chunks_exact(width).enumerate() {
            run_starts(row, &mut starts);
            let here = runs.len();
            // The run above column `c`: the first of `above` ending past it.
            let mut p = above.start;
            for (&c, &end) in starts.iter().zip(&starts[1..]) {
                let id = row[c].id;
                let k = if id == INVALID_ID {
                    0
                } else {
                    let ends = [row[c].distance, row[end - 1].distance];
                    if !ends.iter().all(|d| d.is_finite()) || ids.len() >= u32::MAX as usize - 1 {
                        return false;
                    }
                    reach = ends.iter().fold(reach, |m, d| m.max(d.to_bits()));
                    while p < above.end && runs[p].0 <= (r - 1) * width + c {
                        p += 1;
                    }
                    match runs.get(p) {
                        // The sample above has the same ID: the same point.
                        Some(&(_, k)) if p < above.end && k != 0 && ids[k as usize - 1] == id => k,
                        _ => {
                            let j = index.get_or_insert(id, ids.len());
                            if j == ids.len() {
                                ids.push(id);
                            }
                            j as u32 + 1
                        }
                    }
                };
                runs.push((r * width + end, k));
            }
            above = here..runs.len();
        }
        let reach = f32::from_bits(reach);
        let Some((lo, hi)) = cell_box(grid, first, out.len(), self.first.pattern.scale(), f64::from(reach))
            .filter(|(lo, hi)| cells_in(lo, hi).is_some_and(|n| n <= out.len()))
        else {
            return false;
        };
        // Each ID's point in the box: its cell and fraction.
        let region = Region::generate(&self.ids, lo, hi, true);
        let mut found = vec![false; ids.len()];
        let mut cells_of = vec![[0i64; D]; ids.len()];
        let mut fractions = vec![[0f32; D]; ids.len()];
        let mut c = lo;
        for k in 0..region.start.len() - 1 {
            for p in region.start[k] as usize..region.start[k + 1] as usize {
                if let Some(j) = index.get(region.id[p]) {
                    if found[j] {
                        return false;
                    }
                    found[j] = true;
                    cells_of[j] = c;
                    fractions[j] = std::array::from_fn(|a| region.q[a][p] / (1u32 << FRACTION_BITS) as f32);
                }
            }
            next_cell(&mut c, lo, hi);
        }
        if found.contains(&false) {
            return false;
        }
        // F2 at each point, eight points at a time; entry 0 for no F1.
        let mut results = vec![NSphere32::INVALID; ids.len() + 1];
        for (k, dst) in results[1..].chunks_mut(8).enumerate() {
            let last = dst.len() - 1;
            let at = |j: usize| 8 * k + j.min(last);
            let cells: [[i64; D]; 8] = std::array::from_fn(|j| cells_of[at(j)]);
            let within: [[f32; D]; 8] = std::array::from_fn(|j| fractions[at(j)]);
            let f = self.around.dispatch8(&in_cell::<Eight, D>(&cells, &within));
            for (j, r) in dst.iter_mut().enumerate() {
                *r = sphere(ids[at(j)], f.rank.map(|v| v.to_array()[j]), f.id.map(|v| v.to_array()[j]));
            }
        }
        let mut from = 0;
        for &(end, k) in &runs {
            out[from..end].fill(results[k as usize]);
            from = end;
        }
        true
    }

    /// The grid's samples (rows `first..`, F1 of each in `f1`) sharing one
    /// evaluation per F1 point, the points told apart by ID and position:
    /// the samples whose F1 has the same ID and, within 10^−4 user units,
    /// the same position x − δ share one sample's result, and only that
    /// sample runs the per-sample path (F1, its point, F2 there). Two
    /// different points would have to share a 32-bit ID within 10^−4 of
    /// each other to be taken for one.
    fn by_samples(&self, grid: &Grid<D>, first: usize, f1: &[Features32<D, 1>], out: &mut [NSphere32]) {
        let start = first * grid.size[0];
        // Per sample, the index in `standing` of the sample whose result it
        // takes; `standing` lists the samples evaluated.
        let mut takes = vec![0usize; out.len()];
        let mut standing: Vec<(usize, [f64; D])> = Vec::new();
        let mut by_id: HashMap<u32, usize> = HashMap::new();
        // Whether sample `j`, one step along `axis` before sample `i`, has
        // F1 at the same point: the same ID, and deltas that differ by that
        // step (within 10^−4 user units).
        let after = |i: usize, j: usize, axis: usize| {
            let (d, e) = (&f1[i].delta[0], &f1[j].delta[0]);
            let mut gap = 0.0;
            for a in 0..D {
                let step = if a == axis { grid.step[a] } else { 0.0 };
                gap += (f64::from(d[a]) - f64::from(e[a]) - step).powi(2);
            }
            f1[j].id[0] == f1[i].id[0] && f1[j].distance[0].is_finite() && gap <= 1e-8
        };
        // Rows by index, samples by column: no division per sample.
        let width = grid.size[0];
        for r in 0..out.len() / width {
            let row = start + r * width;
            // The row's first sample; the others differ along axis 0 only.
            let x0 = grid.point(row);
            // (Rows count over axis 1 first: the previous row lies one step
            // along axis 1 unless this row starts a slice.)
            let up = r > 0 && !(first + r).is_multiple_of(grid.size[1]);
            for c in 0..width {
                let i = r * width + c;
                if !f1[i].distance[0].is_finite() {
                    // Bad input or an empty window: its own evaluation.
                    takes[i] = standing.len();
                    standing.push((i, [f64::NAN; D]));
                    continue;
                }
                // The common cases first: the previous sample of the row (one
                // step along axis 0 away) or the sample of the previous row
                // (one step along axis 1) has the same point.
                if c > 0 && after(i, i - 1, 0) {
                    takes[i] = takes[i - 1];
                    continue;
                }
                if up && after(i, i - width, 1) {
                    takes[i] = takes[i - width];
                    continue;
                }
                let p: [f64; D] = std::array::from_fn(|a| {
                    let x = if a == 0 { grid.origin[0] + grid.step[0] * c as f64 } else { x0[a] };
                    x - f64::from(f1[i].delta[0][a])
                });
                let id = f1[i].id[0];
                match by_id.get(&id) {
                    Some(&k) if (0..D).map(|a| (standing[k].1[a] - p[a]).powi(2)).sum::<f64>() <= 1e-8 => takes[i] = k,
                    _ => {
                        by_id.insert(id, standing.len());
                        takes[i] = standing.len();
                        standing.push((i, p));
                    }
                }
            }
        }
        let mut results = vec![NSphere32::INVALID; standing.len()];
        for (chunk, dst) in standing.chunks(8).zip(results.chunks_mut(8)) {
            let block: [[f64; D]; 8] = std::array::from_fn(|k| grid.point(start + chunk[k.min(chunk.len() - 1)].0));
            dst.copy_from_slice(&self.n_sphere8(&block).lanes()[..dst.len()]);
        }
        for (o, &k) in out.iter_mut().zip(&takes) {
            *o = results[k];
        }
    }
}

/// Where the runs of one F1 ID along `row` start, in order, and then
/// `row.len()`, into `starts`. The IDs are compared 64 samples at a time
/// into a mask with no branch between them, and the mask's bits read
/// after: the branch that ends a run costs a misprediction per row, not
/// one per run.
fn run_starts(row: &[Nearest], starts: &mut Vec<usize>) {
    starts.clear();
    for lo in (0..row.len()).step_by(64) {
        let hi = (lo + 64).min(row.len());
        // The IDs of samples lo − 1 .. lo + 64, side by side (past the row
        // the last ID again: no run starts there).
        let mut id = [0u32; 65];
        id[0] = row[lo.max(1) - 1].id;
        for (k, slot) in id[1..].iter_mut().enumerate() {
            *slot = row[(lo + k).min(hi - 1)].id;
        }
        let mut mask = u64::from(lo == 0);
        for k in 0..64 {
            mask |= u64::from(id[k + 1] != id[k]) << k;
        }
        while mask != 0 {
            starts.push(lo + mask.trailing_zeros() as usize);
            mask &= mask - 1;
        }
    }
    starts.push(row.len());
}

/// The box of cells (inclusive per axis) of a grid's samples in rows
/// `first..` (`len` samples, whole rows), widened by `reach` user units
/// and one cell for rounding; `None` beyond the supported coordinates.
fn cell_box<const D: usize>(
    grid: &Grid<D>,
    first: usize,
    len: usize,
    scale: f64,
    reach: f64,
) -> Option<([i64; D], [i64; D])> {
    let width = grid.size[0];
    let margin = reach * scale + 1.0;
    let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
    for r in 0..len / width {
        let x = grid.point((first + r) * width);
        for a in 0..D {
            let along = if a == 0 { grid.step[0] * (width - 1) as f64 } else { 0.0 };
            let (u, v) = (x[a] * scale, (x[a] + along) * scale);
            lo[a] = lo[a].min(u.min(v) - margin);
            hi[a] = hi[a].max(u.max(v) + margin);
        }
    }
    // (Written so that NaN fails.)
    if (0..D).any(|a| !(lo[a].abs() <= MAX_CELL_COORD && hi[a].abs() <= MAX_CELL_COORD)) {
        return None;
    }
    Some((lo.map(|u| u.floor() as i64), hi.map(|u| u.floor() as i64)))
}

/// The number of cells in the box `lo ..= hi`, if it fits a `usize`.
fn cells_in<const D: usize>(lo: &[i64; D], hi: &[i64; D]) -> Option<usize> {
    (0..D).try_fold(1usize, |n, a| n.checked_mul(usize::try_from(hi[a].checked_sub(lo[a])?.checked_add(1)?).ok()?))
}

/// Whether a grid's rows `first..` (`len` samples) are dense enough for
/// [`SimdNSphere::by_points`]: their box of cells, one cell wider each
/// way, has at most a quarter as many cells as samples. Sparser samples
/// share few points, and the per-sample sharing costs less than the box.
fn dense<const D: usize>(grid: &Grid<D>, first: usize, len: usize, scale: f64) -> bool {
    cell_box(grid, first, len, scale, 0.0).and_then(|(lo, hi)| cells_in(&lo, &hi)).is_some_and(|n| 4 * n <= len)
}

/// Indices by feature ID: an open-addressing table with linear probing,
/// [`INVALID_ID`] (which no real point carries) marking empty slots. The
/// IDs are hashes already, so one multiplication places them.
struct IdTable {
    keys: Vec<u32>,
    values: Vec<u32>,
    /// Entries held.
    len: usize,
}

impl IdTable {
    fn new() -> Self {
        IdTable { keys: vec![INVALID_ID; 1024], values: vec![0; 1024], len: 0 }
    }

    /// The first slot to probe for `id`.
    fn slot(&self, id: u32) -> usize {
        let bits = self.keys.len().trailing_zeros();
        (id.wrapping_mul(0x9E37_79B9) >> (32 - bits)) as usize
    }

    /// The index stored for `id`.
    fn get(&self, id: u32) -> Option<usize> {
        let mask = self.keys.len() - 1;
        let mut s = self.slot(id);
        loop {
            match self.keys[s] {
                k if k == id => return Some(self.values[s] as usize),
                INVALID_ID => return None,
                _ => s = (s + 1) & mask,
            }
        }
    }

    /// The index stored for `id`, storing `next` first if there is none
    /// (`id` not [`INVALID_ID`], `next` below 2^32).
    fn get_or_insert(&mut self, id: u32, next: usize) -> usize {
        if 4 * (self.len + 1) > self.keys.len() {
            // At most a quarter full, so that misses end soon.
            let old = std::mem::replace(
                self,
                IdTable { keys: vec![INVALID_ID; 2 * self.keys.len()], values: vec![0; 2 * self.keys.len()], len: 0 },
            );
            for (&k, &v) in old.keys.iter().zip(&old.values).filter(|(k, _)| **k != INVALID_ID) {
                self.get_or_insert(k, v as usize);
            }
        }
        let mask = self.keys.len() - 1;
        let mut s = self.slot(id);
        loop {
            match self.keys[s] {
                k if k == id => return self.values[s] as usize,
                INVALID_ID => {
                    (self.keys[s], self.values[s]) = (id, next as u32);
                    self.len += 1;
                    return next;
                }
                _ => s = (s + 1) & mask,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::super::SERIAL_BAND;
    use super::*;
    use crate::config::{Config, Mode};

    fn bits(n: &NSphere32) -> (u32, u32, u32) {
        (n.radius.to_bits(), n.feature, n.neighbour)
    }

    /// Both ways of sharing on one grid, with F1 from the same tiles: by
    /// point (which must accept the grid) and by sample.
    fn both<const D: usize>(s: &SimdNSphere<D>, grid: &Grid<D>) -> (Vec<NSphere32>, Vec<NSphere32>) {
        let n = grid.len().unwrap();
        let rows = s.first.grid_rows(grid);
        let (mut nearest, mut whole) = (vec![Nearest::default(); n], vec![Features32::<D, 1>::default(); n]);
        s.ids.grid_rows_into(&rows, 0, &mut nearest);
        s.first.grid_rows_into(&rows, 0, &mut whole);
        let (mut a, mut b) = (vec![NSphere32::INVALID; n], vec![NSphere32::INVALID; n]);
        assert!(dense(grid, 0, n, s.first.pattern.scale()), "{D}D: the grid is meant to be dense");
        assert!(s.by_points(grid, 0, &nearest, &mut a), "{D}D: sharing by point declined");
        s.by_samples(grid, 0, &whole, &mut b);
        (a, b)
    }

    #[test]
    fn sharing_by_point_gives_the_bits_of_sharing_by_sample_and_of_each_sample() {
        // The number of samples without an F1.
        fn check<const D: usize>(config: Config, step: f64, tiles: bool) -> usize {
            let s = SimdNSphere::<D>::new(config).unwrap();
            let size = std::array::from_fn(|a| if a < 2 { 48 } else { 2 });
            let grid = Grid { origin: [-1.7; D], step: [step; D], size };
            assert_eq!(s.first.coherent_grid(&grid), tiles, "{D}D step {step}");
            let (a, b) = both(&s, &grid);
            let mut invalid = 0;
            for (i, (p, q)) in a.iter().zip(&b).enumerate() {
                assert_eq!(bits(p), bits(q), "{D}D {config:?} sample {i}");
                if i % 97 == 0 {
                    assert_eq!(bits(p), bits(&s.n_sphere(grid.point(i))), "{D}D {config:?} sample {i}");
                }
                invalid += usize::from(p.feature == INVALID_ID);
            }
            invalid
        }
        let config = Config { density: 2.0, seed: 5, ..Config::default() };
        for seed in 0..3 {
            assert_eq!(check::<2>(Config { seed, ..config }, 0.04, true), 0);
            assert_eq!(check::<3>(Config { seed, ..config }, 0.04, true), 0);
        }
        // Eight steps over more than a cell: F1 per sample.
        assert_eq!(check::<3>(config, 0.3, false), 0);
        // Windows that hold no point: runs without an F1 (INVALID_ID).
        let sparse = Config { mode: Mode::Window, density: 0.3, ..config };
        assert!(check::<2>(sparse, 0.2, false) > 0, "no sample without an F1, so those runs went untested");
    }

    #[test]
    fn a_grid_taller_than_a_band_gives_the_bits_of_each_sample() {
        let s = SimdNSphere::<2>::new(Config { density: 2.0, seed: 3, ..Config::default() }).unwrap();
        let grid = Grid { origin: [0.3, -4.1], step: [0.04, 0.04], size: [8, 2 * SERIAL_BAND + 44] };
        let n = grid.len().unwrap();
        assert!(dense(&grid, 0, n, s.first.pattern.scale()));
        let mut out = vec![NSphere32::INVALID; n];
        s.n_sphere_grid(&grid, &mut out).unwrap();
        for (i, g) in out.iter().enumerate() {
            assert_eq!(bits(g), bits(&s.n_sphere(grid.point(i))), "sample {i}");
        }
    }

    #[test]
    fn sharing_by_point_declines_sparse_samples_and_writes_nothing() {
        let s = SimdNSphere::<2>::new(Config::default()).unwrap();
        let grid = Grid { origin: [0.5, 0.5], step: [40.0, 40.0], size: [16, 16] };
        assert!(!dense(&grid, 0, 256, s.first.pattern.scale()));
        let rows = s.first.grid_rows(&grid);
        let mut nearest = vec![Nearest::default(); 256];
        s.ids.grid_rows_into(&rows, 0, &mut nearest);
        let mut out = vec![NSphere32 { radius: 1.0, feature: 7, neighbour: 9 }; 256];
        assert!(!s.by_points(&grid, 0, &nearest, &mut out));
        assert!(out.iter().all(|n| bits(n) == (1f32.to_bits(), 7, 9)));
        // The public call takes the other way: the bits of each sample.
        s.n_sphere_grid(&grid, &mut out).unwrap();
        for (i, n) in out.iter().enumerate() {
            assert_eq!(bits(n), bits(&s.n_sphere(grid.point(i))), "sample {i}");
        }
    }

    #[test]
    fn run_starts_are_where_the_id_changes() {
        for len in [1, 2, 63, 64, 65, 130, 200] {
            // Runs of lengths 1, 2, 3, ... with one ID met again later.
            let row: Vec<Nearest> = (0..len)
                .map(|i| Nearest { distance: 0.5, id: [3, 8, 3, 1][((i as f64 * 2.0).sqrt() as usize) % 4] })
                .collect();
            let mut starts = Vec::new();
            run_starts(&row, &mut starts);
            let want: Vec<usize> = (0..len).filter(|&c| c == 0 || row[c].id != row[c - 1].id).chain([len]).collect();
            assert_eq!(starts, want, "length {len}");
        }
    }

    #[test]
    fn the_id_table_keeps_what_it_was_given_as_it_grows() {
        let mut table = IdTable::new();
        let key = |i: u32| i.wrapping_mul(0x2545_F491) ^ 0x5bd1_e995;
        for i in 0..5000u32 {
            assert_eq!(table.get_or_insert(key(i), i as usize), i as usize);
            // Asked again: the first index given, not the new one.
            assert_eq!(table.get_or_insert(key(i), 99_999), i as usize);
        }
        assert!(table.keys.len() >= 4 * 5000);
        for i in 0..5000u32 {
            assert_eq!(table.get(key(i)), Some(i as usize));
        }
        assert_eq!((5000..6000).filter(|&i| table.get(key(i)).is_some()).count(), 0);
        assert_eq!(table.len, 5000);
    }
}
