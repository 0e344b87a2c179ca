//! The points of a box of cells generated once, as struct-of-arrays
//! ([`Region`]), and a band of grid rows with its region ([`Band`]): what
//! the coherent path's tiles read.

use super::generate::PointConstants;
use super::grid::Grid;
#[cfg(not(target_feature = "avx512f"))]
use super::lanes::Eight;
#[cfg(target_feature = "avx512f")]
use super::lanes::Sixteen;
use super::lanes::{Lanes, WIDEST};
use super::Simd;
use crate::definition::{axis_term, axis_word, feature_id, hash_words};

/// The feature points of a box of cells, generated once, as
/// struct-of-arrays: cell i's points are `start[i]..start[i + 1]`, cells
/// numbered with axis 0 fastest.
pub(super) struct Region<const D: usize> {
    pub(super) origin: [i64; D],
    pub(super) side: [usize; D],
    pub(super) start: Vec<u32>,
    /// Fixed-point coordinates (the 24-bit integers, exact in f32), padded
    /// by [`WIDEST`] so that a group of lanes read from any cell stays in
    /// bounds.
    pub(super) q: [Vec<f32>; D],
    /// Each point's cell along axis 0, from the region's first (exact:
    /// fewer than 2^24 cells), padded like `q`.
    pub(super) x_cell: Vec<f32>,
    /// IDs, when the tiles read them (whole results with IDs; empty
    /// otherwise).
    pub(super) id: Vec<u32>,
}

impl<const D: usize> Region<D> {
    /// The points of the cells `lo ..= hi` (inclusive per axis), with
    /// their IDs if `ids`, in the widest lanes the build has.
    pub(super) fn generate<const N: usize>(simd: &Simd<D, N>, lo: [i64; D], hi: [i64; D], ids: bool) -> Self {
        #[cfg(target_feature = "avx512f")]
        return Self::generate_in::<Sixteen, N>(simd, lo, hi, ids);
        #[cfg(not(target_feature = "avx512f"))]
        Self::generate_in::<Eight, N>(simd, lo, hi, ids)
    }

    /// [`Region::generate`] in lanes `L`: the cells' hashes and populations
    /// first, then each cell's points `L::N` at a time, point j in lane j
    /// (the jump-ahead constants make point j one multiply-add of the cell's
    /// hash). Every group of lanes is stored whole: the lanes past the
    /// cell's population land where the next cell's points go, or in the
    /// padding, and are overwritten or cleared. Integer arithmetic and an
    /// exact conversion: the same values as one point at a time.
    #[inline(always)]
    pub(super) fn generate_in<L: Lanes, const N: usize>(
        simd: &Simd<D, N>,
        lo: [i64; D],
        hi: [i64; D],
        ids: bool,
    ) -> Self {
        let side: [usize; D] = std::array::from_fn(|a| (hi[a] - lo[a] + 1) as usize);
        let cells: usize = side.iter().product();
        // The axis words of each row of cells, mixed once per axis value.
        let words: [Vec<u32>; D] =
            std::array::from_fn(|a| (0..side[a]).map(|i| axis_word(a, axis_term(lo[a] + i as i64))).collect());
        let keys = simd.pattern.keys();
        let table = simd.pattern.table();
        let mut start = Vec::with_capacity(cells + 1);
        let mut hashes = Vec::with_capacity(cells);
        let mut c = lo;
        let mut total = 0u32;
        for _ in 0..cells {
            start.push(total);
            let w: [u32; D] = std::array::from_fn(|a| words[a][(c[a] - lo[a]) as usize]);
            let h = hash_words(keys, &w);
            hashes.push(h);
            total += table.population(h);
            next_cell(&mut c, lo, hi);
        }
        start.push(total);
        // The jump-ahead constants by point index, padded to whole groups.
        let groups = simd.points.len().div_ceil(L::N).max(1);
        let constants = |f: &dyn Fn(&PointConstants<D>) -> (u32, u32)| -> [Vec<u32>; 2] {
            let mut m = vec![0; groups * L::N];
            let mut c = vec![0; groups * L::N];
            for (j, p) in simd.points.iter().enumerate() {
                (m[j], c[j]) = f(p);
            }
            [m, c]
        };
        let coordinate: [[Vec<u32>; 2]; D] = std::array::from_fn(|a| constants(&|p| p.coordinate[a]));
        let id_constants = constants(&|p| p.id);
        let len = total as usize + WIDEST;
        let mut q: [Vec<f32>; D] = std::array::from_fn(|_| vec![0.0; len]);
        let mut x_cell = vec![0.0; len];
        let mut id = vec![0; if ids { len } else { 0 }];
        for (i, &h) in hashes.iter().enumerate() {
            let (s, e) = (start[i] as usize, start[i + 1] as usize);
            // Cells are numbered with axis 0 fastest.
            let (hv, x) = (L::u(h), L::f((i % side[0]) as f32));
            let mut j = 0;
            while s + j < e {
                let at = s + j;
                L::f_store(x, &mut x_cell[at..at + L::N]);
                for (qa, [m, c]) in q.iter_mut().zip(&coordinate) {
                    let state = L::u_add(L::u_mul(L::u_load(&m[j..j + L::N]), hv), L::u_load(&c[j..j + L::N]));
                    L::f_store(L::u24_to_f(L::u_shr8(state)), &mut qa[at..at + L::N]);
                }
                if ids {
                    let [m, c] = &id_constants;
                    let state = L::u_add(L::u_mul(L::u_load(&m[j..j + L::N]), hv), L::u_load(&c[j..j + L::N]));
                    let mut lanes = [0u32; WIDEST];
                    L::u_store(state, &mut lanes[..L::N]);
                    for (o, &v) in id[at..at + L::N].iter_mut().zip(&lanes) {
                        *o = feature_id(v);
                    }
                }
                j += L::N;
            }
        }
        // The padding past the last point: zeros, whatever the last group
        // stored there.
        for v in q.iter_mut().chain([&mut x_cell]) {
            v[total as usize..].fill(0.0);
        }
        id.truncate(total as usize);
        Region { origin: lo, side, start, q, x_cell, id }
    }

    /// The index of cell `c`, which must lie in the region.
    #[inline(always)]
    pub(super) fn cell(&self, c: [i64; D]) -> usize {
        let mut i = 0;
        for a in (0..D).rev() {
            i = i * self.side[a] + (c[a] - self.origin[a]) as usize;
        }
        i
    }
}

/// A band of grid rows and its cells' points: what every tile of the band
/// reads.
pub(super) struct Band<'a, const D: usize> {
    pub(super) grid: &'a Grid<D>,
    pub(super) axes: &'a Axes<D>,
    /// The band's first row.
    pub(super) first: usize,
    pub(super) region: Region<D>,
}

/// The grid's coordinates per axis, located once: cell and fraction (lane
/// units) of every index.
pub(super) struct Axes<const D: usize> {
    pub(super) cell: [Vec<i64>; D],
    pub(super) f: [Vec<f32>; D],
    /// Whether sixteen steps along axis 0 span at most one cell, so that
    /// tiles sixteen samples wide stay within two cells.
    pub(super) sixteen: bool,
}

/// Steps `c` to the next cell of the box `lo ..= hi` (axis 0 fastest);
/// false when `c` was the last. A loop over it, rather than a closure
/// called per cell, keeps the body inline in the run-time AVX-512 copy.
#[inline(always)]
pub(super) fn next_cell<const D: usize>(c: &mut [i64; D], lo: [i64; D], hi: [i64; D]) -> bool {
    for a in 0..D {
        c[a] += 1;
        if c[a] <= hi[a] {
            return true;
        }
        c[a] = lo[a];
    }
    false
}
