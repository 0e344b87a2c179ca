//! The cell hash and the point generator in lanes: a cell's hash from its
//! axis words, its population, and point j's coordinates and ID from the
//! LCG constants of index j, bit for bit the reference's
//! ([`definition`](crate::definition)).

use super::best::Best;
use super::lanes::{Lanes, WIDEST};
use super::metric::Metric32;
use super::Simd;
use crate::definition::{axis_term, AXIS_MUL, FRACTION_BITS, INVALID_ID};

/// 2^24: lane geometry is held in units of one fixed-point step of a
/// feature-point coordinate, so that a coordinate is its 24-bit integer
/// converted exactly, with no multiply. Scaling by a power of two is exact,
/// so every value is the cell-unit value times 2^24, bit for bit.
pub(super) const UNIT: f32 = (1u32 << FRACTION_BITS) as f32;

/// The LCG constants of one point index j: (A_k, C_k) for its ID state and
/// its coordinate states.
#[derive(Clone, Copy, Debug)]
pub(super) struct PointConstants<const D: usize> {
    pub(super) id: (u32, u32),
    pub(super) coordinate: [(u32, u32); D],
    /// The same constants repeated in every lane, read by the per-sample
    /// kernel as whole lane sets: a load folds into the instruction that
    /// uses it, where a scalar constant needs a broadcast of its own.
    pub(super) wide: WideConstants<D>,
}

/// One value in every lane of the widest lane set.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Splat<T>(pub(super) [T; WIDEST]);

/// [`PointConstants`] in every lane (see its `wide`).
#[derive(Clone, Copy, Debug)]
pub(super) struct WideConstants<const D: usize> {
    /// What [`Simd::population`] is compared with: for a sorted table the
    /// threshold the state's top byte must exceed for the point to exist,
    /// for an unsorted one the point's index j, which the cell's
    /// population must exceed.
    pub(super) key: Splat<f32>,
    pub(super) id: (Splat<u32>, Splat<u32>),
    pub(super) coordinate: [(Splat<u32>, Splat<u32>); D],
}

impl<const D: usize, const N: usize> Simd<D, N> {
    /// The cell hash (see [`definition`](crate::definition)) in u32 lanes,
    /// from the cell's axis words.
    #[inline(always)]
    pub(super) fn hash<L: Lanes>(&self, words: [L::U; D]) -> L::U {
        let mut h = L::u(self.pattern.keys().init);
        for (a, t) in words.iter().enumerate() {
            h = axis_round::<L>(h, *t, a);
        }
        let mut sum = L::u(0);
        for w in &words[..D - 1] {
            sum = L::u_add(sum, *w);
        }
        self.hash_finish::<L>(h, sum)
    }

    /// The hash's last step, from the chain `h` after its axis rounds and
    /// the sum of the words of axes 0..d − 1: the sum added (modulo 2^32,
    /// so the same in any order), the finishing key, MurmurHash3's mix.
    #[inline(always)]
    pub(super) fn hash_finish<L: Lanes>(&self, h: L::U, sum: L::U) -> L::U {
        fmix32::<L>(L::u_xor(L::u_add(h, sum), L::u(self.pattern.keys().finish)))
    }

    /// The hashes of the lanes' 2^d blocks: [`Simd::hash`] of cell c, which
    /// takes on axis a the near neighbour's word (`terms[a][0]`) where bit a
    /// of c is set and the own column's (`terms[a][1]`) where it is clear.
    /// The chain's round for axis a reads the words of axes 0..=a only, so
    /// the 2^d chains share their first rounds as a tree: 2 + 4 + … + 2^d
    /// rounds instead of d·2^d, and the sum of the words added after the
    /// rounds (a sum modulo 2^32, so in any order) is shared the same way.
    #[inline(always)]
    pub(super) fn block_hashes<L: Lanes>(&self, terms: &[[L::U; 3]; D]) -> [L::U; 16] {
        let mut h = [L::u(self.pattern.keys().init); 16];
        let mut sum = [L::u(0); 16];
        for (a, words) in terms.iter().enumerate() {
            // Cells below 2^a hold the chains over axes 0..a; each splits in
            // two on axis a, its own column (bit a clear) and the near one.
            for c in 0..1usize << a {
                let (base, s) = (h[c], sum[c]);
                for near in 0..2 {
                    let t = words[1 - near];
                    let at = c | near << a;
                    h[at] = axis_round::<L>(base, t, a);
                    sum[at] = if a + 1 < D { L::u_add(s, t) } else { s };
                }
            }
        }
        for c in 0..1usize << D {
            h[c] = self.hash_finish::<L>(h[c], sum[c]);
        }
        h
    }

    /// What a cell's points are tested against, from its hash `h`: the
    /// state's top byte, exact in f32, for a sorted table (point j exists
    /// where its threshold is below it), or the population itself for an
    /// unsorted one (point j exists where j is below it). See
    /// [`Simd::key`].
    #[inline(always)]
    pub(super) fn population<L: Lanes>(&self, h: L::U) -> L::F {
        let top = L::u24_to_f(L::u_shr24(h));
        if self.sorted {
            top
        } else {
            self.counts::<L>(top)
        }
    }

    /// Point `p`'s side of the existence test against [`Simd::population`]:
    /// its threshold, or its index for an unsorted table.
    #[inline(always)]
    pub(super) fn key<L: Lanes>(&self, p: &PointConstants<D>) -> L::F {
        L::f_load(&p.wide.key.0)
    }

    /// Point `p` of the cell with hash `h` (`shifted` is the sample minus
    /// the cell's corner) inserted in the lanes of `active`; the others get
    /// rank +∞ and [`INVALID_ID`], which change nothing.
    #[inline(always)]
    pub(super) fn point<L: Lanes, M: Metric32, const IDS: bool, const DELTAS: bool>(
        &self,
        metric: M,
        p: &PointConstants<D>,
        h: L::U,
        shifted: [L::F; D],
        active: L::M,
        best: &mut Best<L, D, N>,
    ) {
        let delta = Self::delta_of::<L>(p, h, shifted);
        let rank = L::select(active, metric.rank::<L, D>(&delta), L::f(f32::INFINITY));
        let id = if IDS {
            // Lanes without the point carry INVALID_ID, which loses every
            // tie.
            L::select_u(active, Self::id_of::<L>(p, h), L::u(INVALID_ID))
        } else {
            L::u(0)
        };
        best.insert::<IDS, DELTAS>(rank, delta, id);
    }

    /// The sample minus point `p` of the cell with hash `h`, in lane units
    /// (`shifted` is the sample minus the cell's corner): every path that
    /// meets a point computes its delta here, so the same point gives the
    /// same bits whichever path, cell order or lane meets it.
    #[inline(always)]
    pub(super) fn delta_of<L: Lanes>(p: &PointConstants<D>, h: L::U, shifted: [L::F; D]) -> [L::F; D] {
        let c = Self::coordinates_of::<L>(p, h);
        // A loop, not a closure: in the run-time AVX-512 copy a closure here
        // stayed an out-of-line call without its instructions (`per_axis`).
        let mut delta = shifted;
        for (d, c) in delta.iter_mut().zip(c) {
            *d = L::sub(*d, L::u24_to_f(c));
        }
        delta
    }

    /// Point `p` of the cell with hash `h` in the cell: its 24-bit
    /// fixed-point coordinates, each below 2^24 (lane units).
    #[inline(always)]
    pub(super) fn coordinates_of<L: Lanes>(p: &PointConstants<D>, h: L::U) -> [L::U; D] {
        let mut c = [L::u(0); D];
        for (a, c) in c.iter_mut().enumerate() {
            let (am, cm) = &p.wide.coordinate[a];
            *c = L::u_shr8(L::u_add(L::u_mul(h, L::u_load(&am.0)), L::u_load(&cm.0)));
        }
        c
    }

    /// The ID of point `p` of the cell with hash `h`. The sentinel state is
    /// reported as INVALID_ID − 1 (`definition::feature_id`): an unsigned
    /// minimum.
    #[inline(always)]
    pub(super) fn id_of<L: Lanes>(p: &PointConstants<D>, h: L::U) -> L::U {
        let (am, cm) = &p.wide.id;
        L::u_min(L::u_add(L::u_mul(h, L::u_load(&am.0)), L::u_load(&cm.0)), L::u(INVALID_ID - 1))
    }

    /// Populations of an unsorted (bumped) table: a lookup per lane.
    #[inline(never)]
    pub(super) fn counts<L: Lanes>(&self, top: L::F) -> L::F {
        let mut c = [0f32; WIDEST];
        L::f_store(top, &mut c[..L::N]);
        for v in c.iter_mut().take(L::N) {
            *v = f32::from(self.table[*v as usize]);
        }
        L::f_load(&c[..L::N])
    }
}

/// Per-lane axis words of axis `axis` of the cells at `offset` from `cell`,
/// wrapped into [0, period) when the pattern is periodic.
#[inline(always)]
pub(super) fn words<L: Lanes>(axis: usize, cell: &[i64; WIDEST], offset: i64, period: Option<i64>) -> L::U {
    let mut t = [0u32; WIDEST];
    for (ti, c) in t.iter_mut().zip(cell).take(L::N) {
        let c = c.wrapping_add(offset);
        *ti = axis_term(match period {
            Some(p) => c.rem_euclid(p),
            None => c,
        });
    }
    word::<L>(axis, L::u_load(&t[..L::N]))
}

/// One axis round of the cell hash's chain in lanes: the axis word `t`
/// enters, axis `axis`'s multiplier, a shift-xor.
#[inline(always)]
pub(super) fn axis_round<L: Lanes>(h: L::U, t: L::U, axis: usize) -> L::U {
    let x = L::u_mul(L::u_xor(h, t), L::u(AXIS_MUL[axis]));
    L::u_xor(x, L::u_shr16(x))
}

/// MurmurHash3's finaliser in lanes ([`definition::fmix32`](crate::definition::fmix32)).
#[inline(always)]
pub(super) fn fmix32<L: Lanes>(mut h: L::U) -> L::U {
    h = L::u_xor(h, L::u_shr16(h));
    h = L::u_mul(h, L::u(0x85EB_CA6B));
    h = L::u_xor(h, L::u_shr13(h));
    h = L::u_mul(h, L::u(0xC2B2_AE35));
    L::u_xor(h, L::u_shr16(h))
}

/// An axis word in lanes ([`axis_word`](crate::definition::axis_word)): the raw axis term `t` mixed on its
/// own.
#[inline(always)]
pub(super) fn word<L: Lanes>(axis: usize, t: L::U) -> L::U {
    fmix32::<L>(L::u_xor(t, L::u(AXIS_MUL[axis])))
}
