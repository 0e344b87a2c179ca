//! Step 2 of compact smooth F1 (see the [parent module's text](super)):
//! every feature point within the reach of each lane's F1, kept per lane in
//! the order met ([`Near`]), or all of them for a lane searched again alone
//! ([`All`]).

use wide::f32x8;

use super::super::super::generate::UNIT;
use super::super::super::lanes::{Eight, Lanes, WIDEST};
use super::super::super::locate::Located;
use super::super::super::search::outside;
use super::super::super::Simd;
use super::super::search::{CellAt, Frame};
use super::KEPT;
use crate::config::Mode;
use crate::reference::{shell, MAX_SHELLS};

/// Where the search around F1 puts the points within reach.
pub(super) trait Collect<const D: usize> {
    /// One point, in the lanes of the bit mask `inside`.
    fn push<L: Lanes>(&mut self, inside: u32, d2: L::F, delta: &[L::F; D]);
}

/// The points within reach, per lane in the order met: squared distance
/// and delta (x − p), lane units; `count` may pass [`KEPT`] (then only the
/// first [`KEPT`] are kept).
pub(super) struct Near<const D: usize> {
    pub(super) count: [usize; WIDEST],
    pub(super) d2: [[f32; KEPT]; WIDEST],
    pub(super) delta: [[[f32; D]; KEPT]; WIDEST],
}

impl<const D: usize> Near<D> {
    pub(super) fn new() -> Self {
        Near { count: [0; WIDEST], d2: [[0.0; KEPT]; WIDEST], delta: [[[0.0; D]; KEPT]; WIDEST] }
    }
}

/// Every point within reach of a one-lane search, however many.
pub(super) struct All<const D: usize> {
    pub(super) d2: Vec<f32>,
    pub(super) delta: Vec<[f32; D]>,
}

impl<const D: usize> Collect<D> for All<D> {
    fn push<L: Lanes>(&mut self, inside: u32, d2: L::F, delta: &[L::F; D]) {
        if inside & 1 != 0 {
            let mut v = [0f32; WIDEST];
            L::f_store(d2, &mut v[..L::N]);
            self.d2.push(v[0]);
            self.delta.push(std::array::from_fn(|a| {
                L::f_store(delta[a], &mut v[..L::N]);
                v[0]
            }));
        }
    }
}

impl<const D: usize> Collect<D> for Near<D> {
    #[inline(always)]
    fn push<L: Lanes>(&mut self, inside: u32, d2: L::F, delta: &[L::F; D]) {
        let mut d2s = [0f32; WIDEST];
        L::f_store(d2, &mut d2s[..L::N]);
        let mut deltas = [[0f32; WIDEST]; D];
        for (out, v) in deltas.iter_mut().zip(delta) {
            L::f_store(*v, &mut out[..L::N]);
        }
        let mut bits = inside;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let k = self.count[i];
            if k < KEPT {
                self.d2[i][k] = d2s[i];
                self.delta[i][k] = std::array::from_fn(|a| deltas[a][i]);
            }
            self.count[i] = k + 1;
        }
    }
}

impl<const D: usize> Simd<D, 1> {
    /// [`Simd::near_points`] in eight lanes through its AVX2 copy where
    /// this build lacks AVX2 and the CPU has it, as the border's search
    /// runs (the same operations, so the same bits).
    #[inline(always)]
    pub(super) fn near_points8(&self, at: &Located<Eight, D>, reach: f32x8, near: &mut Near<D>) -> u32 {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if super::super::super::runtime_avx2() {
            // SAFETY: `near_points_avx2` requires AVX2 and nothing else,
            // and `runtime_avx2` has just seen the CPU report it.
            #[allow(unsafe_code)]
            return unsafe { near_points_avx2(self, at, reach, near) };
        }
        self.near_points::<Eight, _>(at, reach, near)
    }
}

/// [`Simd::near_points`] compiled with AVX2 enabled (see
/// [`dispatch_avx2`](super::super::super::entry::dispatch_avx2)).
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
#[target_feature(enable = "avx2")]
fn near_points_avx2<const D: usize>(
    kernel: &Simd<D, 1>,
    at: &Located<Eight, D>,
    reach: f32x8,
    near: &mut Near<D>,
) -> u32 {
    kernel.near_points::<Eight, _>(at, reach, near)
}

impl<const D: usize> Simd<D, 1> {
    /// Every point nearer than `reach` (squared, lane units; negative for
    /// lanes left out) per lane, into `near`; returns the bit mask of lanes
    /// whose reach passed [`MAX_SHELLS`] (never seen for valid input: their
    /// result is NaN).
    #[inline(always)]
    pub(super) fn near_points<L: Lanes, C: Collect<D>>(&self, at: &Located<L, D>, reach: L::F, near: &mut C) -> u32 {
        let mut open = L::le(L::f(0.0), reach);
        let frame = Frame::<L, D>::new(at);
        // The 2^d block (the own cell and the cells around the nearest
        // corner, `block[..near]`) as the kernel's first stage visits it:
        // every cell hashed up front as independent chains, then the same
        // number of point steps in each cell some lane reaches.
        let h = self.block_hashes::<L>(&frame.terms);
        let mut most = L::f(-1.0);
        let mut top = [L::f(0.0); 16];
        let mut needs = [L::lt(L::f(1.0), L::f(0.0)); 16];
        for offset in &self.block[..self.near] {
            // Cell `index` of the hashes is, on axis a, the near neighbour
            // where bit a is set: the offset whose −1s are its bits.
            let index = corner_index(offset);
            let cell = frame.cell(offset);
            needs[index] = L::and(open, L::le(cell.rank, reach));
            if L::any(needs[index]) {
                top[index] = self.population::<L>(h[index]);
                most = L::max(most, L::select(needs[index], top[index], L::f(-1.0)));
            }
        }
        let count = self.points.iter().take_while(|p| L::any(L::lt(self.key::<L>(p), most))).count();
        for offset in &self.block[..self.near] {
            let index = corner_index(offset);
            if !L::any(needs[index]) {
                continue;
            }
            let cell = frame.cell(offset);
            for p in &self.points[..count] {
                let active = L::and(needs[index], L::lt(self.key::<L>(p), top[index]));
                near_point::<L, D, C>(&cell.shifted, Self::coordinates_of::<L>(p, h[index]), active, reach, near);
            }
        }
        for offset in &self.block[self.near..] {
            let c = frame.cell(offset);
            let needs = L::and(open, L::le(c.rank, reach));
            if L::any(needs) {
                self.near_cell::<L, C>(&c, needs, reach, near);
            }
        }
        if self.config.mode == Mode::Window {
            return 0;
        }
        let cell = at.cells_i64();
        for r in 1..=MAX_SHELLS {
            let edge = outside::<L, D>(&at.f, r as f32 * UNIT);
            open = L::and(open, L::le(L::mul(edge, edge), reach));
            if !L::any(open) || r == MAX_SHELLS {
                break;
            }
            for offset in shell::<D>(r + 1) {
                let c = Frame::<L, D>::far_cell(at, &cell, &offset);
                let needs = L::and(open, L::le(c.rank, reach));
                if L::any(needs) {
                    self.near_cell::<L, C>(&c, needs, reach, near);
                }
            }
        }
        L::bits(open)
    }

    /// The points of cell `c` nearer than `reach`, in the lanes of `needs`.
    #[inline(always)]
    fn near_cell<L: Lanes, C: Collect<D>>(&self, c: &CellAt<L, D>, needs: L::M, reach: L::F, near: &mut C) {
        self.cell_points::<L>(c, needs, |active, q, _| near_point::<L, D, C>(&c.shifted, q, active, reach, near));
    }
}

/// One point (`q`, its 24-bit coordinates in a cell whose corner the
/// sample lies `shifted` from) into `near` in the lanes of `active` that
/// it lies within `reach` of: its delta and squared distance as the
/// kernel computes them.
#[inline(always)]
fn near_point<L: Lanes, const D: usize, C: Collect<D>>(
    shifted: &[L::F; D],
    q: [L::U; D],
    active: L::M,
    reach: L::F,
    near: &mut C,
) {
    let mut delta = [L::f(0.0); D];
    let mut d2 = L::f(0.0);
    for (a, v) in delta.iter_mut().enumerate() {
        *v = L::sub(shifted[a], L::u24_to_f(q[a]));
        d2 = L::add(d2, L::mul(*v, *v));
    }
    let inside = L::bits(L::and(active, L::lt(d2, reach)));
    if inside != 0 {
        near.push::<L>(inside, d2, &delta);
    }
}

/// The index in [`Simd::block_hashes`] of a cell of the 2^d block given as
/// its mirrored offset (−1 near, 0 own): bit a set where axis a is near.
fn corner_index<const D: usize>(offset: &[i64; D]) -> usize {
    (0..D).filter(|&a| offset[a] < 0).map(|a| 1 << a).sum()
}
