//! Repeated strips of cells: a statistical check of the cell hash.
//!
//! Two cells with the same hash hold the same feature points (IDs and
//! offsets). A uniform 32-bit hash gives such pairs by chance, about
//! C(n, 2)/2^32 among n cells, but two *runs* of neighbouring cells that
//! repeat together (a cell and its neighbour along an axis, both equal to
//! another such pair) come by chance with probability 2^−64 per pair of runs:
//! about 10^−5 expected in a window of 2^22 cells. A hash with structure
//! (for example one whose terms enter the chain linearly, so that a row of
//! cells is another row shifted) repeats whole rows, pencils or planes and
//! gives thousands.
//!
//! [`repeated_runs`] counts both in a window of cells around the origin, for
//! any hash, so that a test can hold the crate's hash to the uniform
//! expectation and show that the count catches a hash with that structure.

/// What [`repeated_runs`] found in a window.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Repeats {
    /// Cells in the window.
    pub cells: usize,
    /// Pairs of distinct cells with equal hashes.
    pub equal_cells: u64,
    /// What a uniform hash gives for `equal_cells`: C(cells, 2)/2^32.
    pub expected_equal_cells: f64,
    /// Pairs of distinct runs (a cell and its neighbour along the same axis,
    /// any axis) whose two hashes are equal in order: repeated strips.
    pub equal_runs: u64,
    /// What a uniform hash gives for `equal_runs`: about
    /// d·C(cells, 2)/2^64, effectively zero.
    pub expected_equal_runs: f64,
}

/// Counts equal cells and repeated runs of two cells among the `side^D`
/// cells of the window `[−side/2, side/2)^D`, hashed by `hash`.
pub fn repeated_runs<const D: usize>(side: i64, hash: impl Fn([i64; D]) -> u32 + Sync) -> Repeats {
    let cells = (side as usize).pow(D as u32);
    let cell_of = |mut index: usize| -> [i64; D] {
        std::array::from_fn(|_| {
            let c = (index % side as usize) as i64 - side / 2;
            index /= side as usize;
            c
        })
    };
    let mut hashes: Vec<u32> = collect(cells, |i| hash(cell_of(i)));
    let mut equal_runs = 0;
    for axis in 0..D {
        let mut runs: Vec<u64> = collect(cells, |i| {
            let c = cell_of(i);
            let mut next = c;
            next[axis] += 1;
            (u64::from(hashes[i]) << 32) | u64::from(hash(next))
        });
        equal_runs += equal_pairs(&mut runs);
    }
    hashes.sort_unstable();
    let equal_cells = equal_pairs(&mut hashes);
    let pairs = cells as f64 * (cells as f64 - 1.0) / 2.0;
    Repeats {
        cells,
        equal_cells,
        expected_equal_cells: pairs / 2f64.powi(32),
        equal_runs,
        expected_equal_runs: D as f64 * pairs / 2f64.powi(64),
    }
}

/// The number of pairs of equal entries (sorts `v`).
fn equal_pairs<T: Ord + Copy>(v: &mut [T]) -> u64 {
    v.sort_unstable();
    let mut pairs = 0u64;
    let mut run = 1u64;
    for w in v.windows(2) {
        if w[0] == w[1] {
            run += 1;
        } else {
            pairs += run * (run - 1) / 2;
            run = 1;
        }
    }
    pairs + run * (run - 1) / 2
}

/// `f(0..n)` into a vector, on all cores with the `parallel` feature.
fn collect<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    super::chunked(n, |range| range.map(&f).collect::<Vec<T>>()).into_iter().flatten().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_pairs_counts_every_pair() {
        assert_eq!(equal_pairs(&mut [3, 1, 3, 2, 3, 1]), 3 + 1);
        assert_eq!(equal_pairs::<u32>(&mut []), 0);
        assert_eq!(equal_pairs(&mut [7]), 0);
    }

    #[test]
    fn a_hash_of_one_axis_repeats_along_the_others() {
        // Hashing only axis 0 makes every row along axis 1 a copy: each of
        // the side·(side − 1)/2 pairs of rows repeats at every cell.
        let r = repeated_runs::<2>(16, |c| (c[0] as u32).wrapping_mul(0x9E37_79B1));
        assert!(r.equal_runs > 1000, "{r:?}");
    }
}
