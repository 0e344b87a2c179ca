//! Locating samples: each lane's cell, the axis words of the cells around
//! it and its fraction in its cell, in units of one fixed-point step
//! ([`UNIT`]).

use super::generate::{word, words, UNIT};
use super::lanes::{Lanes, WIDEST};
use super::{per_axis, Simd};

/// A lane's located sample: the axis words of the cells around it and its
/// fraction in its own cell.
pub(super) struct Located<L: Lanes, const D: usize> {
    /// Axis words ([`axis_word`](crate::definition::axis_word)) of the cells at offsets −1, 0, +1, per axis.
    pub(super) words: [[L::U; 3]; D],
    /// The fraction f ∈ [0, 1] per axis, rounded to f32.
    pub(super) f: [L::F; D],
    /// The lanes' own cells, for the wide search.
    pub(super) cells: Cells<L, D>,
    /// Lanes with a valid input.
    pub(super) valid: [bool; WIDEST],
    /// Cells per axis after which the pattern repeats (periodic variant):
    /// every cell is wrapped into [0, period) before it is hashed.
    pub(super) period: Option<[i64; D]>,
}

/// Where the wide search finds the lanes' own cells.
pub(super) enum Cells<L: Lanes, const D: usize> {
    /// Every lane within [`FAST_RANGE`]: per axis, the cell's low word (its
    /// raw axis term), from which the cell follows by sign extension.
    Low([L::U; D]),
    /// Some lane beyond it: the cells themselves, per axis and lane.
    Full([[i64; WIDEST]; D]),
}

impl<L: Lanes, const D: usize> Located<L, D> {
    /// Lanes from per-lane i64 cells and fractions (already in units of
    /// [`UNIT`]): the full axis words of every neighbour, kept cells.
    pub(super) fn lanewise(cell: [[i64; WIDEST]; D], f: &[[f32; WIDEST]; D], valid: [bool; WIDEST]) -> Self {
        Self::wrapped(cell, f, valid, None)
    }

    /// As [`Located::lanewise`], with the cells wrapped by `period`.
    pub(super) fn wrapped(
        cell: [[i64; WIDEST]; D],
        f: &[[f32; WIDEST]; D],
        valid: [bool; WIDEST],
        period: Option<[i64; D]>,
    ) -> Self {
        Located {
            words: per_axis(|a| per_axis(|o| words::<L>(a, &cell[a], o as i64 - 1, period.map(|p| p[a])))),
            f: per_axis(|a| L::f_load(&f[a][..L::N])),
            cells: Cells::Full(cell),
            valid,
            period,
        }
    }
}

impl<L: Lanes, const D: usize> Located<L, D> {
    /// The lanes' own cells, per axis and lane.
    #[inline(always)]
    pub(super) fn cells_i64(&self) -> [[i64; WIDEST]; D] {
        match &self.cells {
            Cells::Full(cell) => *cell,
            Cells::Low(low) => per_axis(|a| {
                let mut lo = [0u32; WIDEST];
                L::u_store(low[a], &mut lo[..L::N]);
                lo.map(|t| i64::from(t as i32))
            }),
        }
    }
}

/// 1.5·2^52: adding and subtracting it rounds an f64 below 2^51 in magnitude
/// to an integer, and the integer's low 32 bits are then the sum's low bits.
pub(super) const ROUNDING: f64 = 6_755_399_441_055_744.0;

/// Largest |u| located in lanes: the cell and both its neighbours stay in
/// the i32 range, where the axis term is the cell's low word.
pub(super) const FAST_RANGE: f64 = 2_147_483_645.0;

impl<const D: usize, const N: usize> Simd<D, N> {
    /// Locates every lane. The common case (every lane valid and within
    /// [`FAST_RANGE`] cells of the origin) runs as straight-line f64 code
    /// that vectorises: the floor by the rounding constant, the axis term
    /// from the bits of the rounded sum. Anything else takes the per-lane
    /// path through [`Pattern::locate`](crate::Pattern::locate). Both give the reference's cell and
    /// the reference's f64 fraction, rounded to f32.
    #[inline(always)]
    pub(super) fn locate<L: Lanes>(&self, xs: &[[f64; D]]) -> Located<L, D> {
        let scale = self.pattern.scale();
        let mut lo = [[0u32; WIDEST]; D];
        let mut f = [[0f32; WIDEST]; D];
        let mut fast = true;
        for a in 0..D {
            for i in 0..L::N {
                let u = xs[i][a] * scale;
                let r = (u + ROUNDING) - ROUNDING;
                let floor = if r > u { r - 1.0 } else { r };
                lo[a][i] = (floor + ROUNDING).to_bits() as u32;
                f[a][i] = (u - floor) as f32 * UNIT;
                fast &= u.abs() < FAST_RANGE;
            }
        }
        if !fast {
            return self.locate_lanewise(xs);
        }
        let (mut words, mut lanes, mut low) = ([[L::u(0); 3]; D], [L::f(0.0); D], [L::u(0); D]);
        for a in 0..D {
            let t = L::u_load(&lo[a][..L::N]);
            // Written out: an array `map` here stayed a call with copies.
            words[a] = [word::<L>(a, L::u_add(t, L::u(u32::MAX))), word::<L>(a, t), word::<L>(a, L::u_add(t, L::u(1)))];
            lanes[a] = L::f_load(&f[a][..L::N]);
            low[a] = t;
        }
        Located { words, f: lanes, cells: Cells::Low(low), valid: [true; WIDEST], period: None }
    }

    #[inline(never)]
    #[cold]
    pub(super) fn locate_lanewise<L: Lanes>(&self, xs: &[[f64; D]]) -> Located<L, D> {
        let mut cell = [[0i64; WIDEST]; D];
        let mut f = [[0f32; WIDEST]; D];
        let mut valid = [false; WIDEST];
        for (i, x) in xs.iter().enumerate().take(L::N) {
            if let Some((c, fr)) = self.pattern.locate(*x) {
                valid[i] = true;
                for a in 0..D {
                    cell[a][i] = c[a];
                    f[a][i] = fr[a] as f32 * UNIT;
                }
            }
        }
        Located::lanewise(cell, &f, valid)
    }
}
