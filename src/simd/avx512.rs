//! Sixteen AVX-512 lanes chosen at run time, for a build compiled without
//! AVX-512: the default x86_64 build on a CPU that has it.
//!
//! `wide` chooses its instructions when it is compiled, so in a default
//! build its `f32x16` is four SSE registers wherever it is inlined. The
//! slice kernel here is the crate's one kernel (`search` and its parts),
//! instantiated over a lane set whose every operation is one AVX-512
//! intrinsic and compiled inside a function with the x86-64-v4 features
//! enabled, so it runs the instructions an AVX-512 build runs.
//!
//! Another way was measured first, 3D F1 on random points in the default
//! build (`benches/throughput.rs`): plain `[f32; 16]` arrays with
//! lane-by-lane loops left to the compiler's vectoriser ran 3.2-5.4 M
//! samples/s against 9.7 for the default build's eight AVX2 lanes and 24
//! for the AVX-512 build, because the vectoriser took the loop over a
//! cell's points as the one to vectorise and gathered each point's
//! constants four lanes at a time; there is no stable way to steer it.
//! Intrinsics leave it nothing to choose.
//!
//! # Safety
//! Every operation of [`Avx512`] calls an AVX-512 intrinsic, which is
//! sound only on a CPU that has AVX-512. The type is private to this
//! module, so the only code that can instantiate the kernel over it is
//! [`slice_avx512`] and [`tiles_avx512`] (the coherent path's
//! tiles) below, and their only calls are in [`evaluate_slice`] and
//! [`tiles`], after [`runtime_avx512`] has seen the CPU report the
//! features. [`Avx512::broadcast_add_on_fma`] calls the one instruction of
//! inline assembly in `lanes.rs` ([`broadcast_fma`]: the compiler does not
//! emit that form). This module, the run-time AVX2 calls in `entry.rs`,
//! `coherent.rs` and `border/search.rs`, the grid tiles' prefetch of their
//! outputs in `tiles.rs` (a cache hint, which reads nothing and cannot
//! fault) and that instruction are the crate's only `unsafe` code.
//!
//! With the sixteen lanes here the default build ran 3D F1 on random
//! points at 25.1-25.7 M samples/s against 22.7-23.3 for the AVX-512 build
//! on `wide`'s `f32x16` in the same run: masks live in mask registers here,
//! where `wide` keeps them as float vectors.

#![allow(unsafe_code)]

use std::arch::x86_64::{
    __m512, __m512i, __mmask16, _mm512_abs_ps, _mm512_add_epi32, _mm512_add_ps, _mm512_and_si512, _mm512_castps_si512,
    _mm512_castsi512_ps, _mm512_cmp_ps_mask, _mm512_cmpeq_epu32_mask, _mm512_cmplt_epu32_mask, _mm512_cvtepi32_ps,
    _mm512_div_ps, _mm512_fmadd_ps, _mm512_loadu_epi32, _mm512_loadu_ps, _mm512_mask_blend_epi32, _mm512_mask_blend_ps,
    _mm512_max_ps, _mm512_min_epu32, _mm512_min_ps, _mm512_mul_ps, _mm512_mullo_epi32, _mm512_set1_epi32,
    _mm512_set1_ps, _mm512_sqrt_ps, _mm512_srli_epi32, _mm512_storeu_epi32, _mm512_storeu_ps, _mm512_sub_epi32,
    _mm512_sub_ps, _mm512_xor_si512, _CMP_EQ_OQ, _CMP_LE_OQ, _CMP_LT_OQ,
};

use super::lanes::Lanes;
use super::lanes::{broadcast_fma, WIDEST};
use super::region::Band;
use super::sample::Point;
use super::search::{FIRST, REST};
use super::tiles::GridSample;
use super::{runtime_avx512, Euclid, Features32, Outputs, Simd};
use std::cell::Cell;

/// Sixteen lanes in one AVX-512 register each, masks in a mask register.
/// Every operation is the IEEE operation [`One`](super::lanes::One) does,
/// lane by lane, so a lane's bits are the one-lane kernel's (tested against
/// it in `tests` below, and through `evaluate_slice` in `tests/lanes/simd.rs`
/// and at each ceiling in `tests/lanes/levels.rs`).
#[derive(Clone, Copy, Debug)]
struct Avx512;

// SAFETY, for every `unsafe` block in this impl: the intrinsic needs
// AVX-512 (F, and VL/BW/DQ for none of these), and `Avx512` is only ever
// used inside `slice_avx512`, which runs only after the CPU reported
// the x86-64-v4 features (see the module docs). Loads and stores go through
// slices already cut to sixteen elements, so the pointers are in bounds.
impl Lanes for Avx512 {
    const N: usize = 16;
    const LOCAL_RANKS: usize = 2;
    type F = __m512;
    type U = __m512i;
    type M = __mmask16;

    #[inline(always)]
    fn f(v: f32) -> __m512 {
        unsafe { _mm512_set1_ps(v) }
    }
    #[inline(always)]
    fn u(v: u32) -> __m512i {
        unsafe { _mm512_set1_epi32(v as i32) }
    }
    #[inline(always)]
    fn f_load(a: &[f32]) -> __m512 {
        let a: &[f32; 16] = a[..16].try_into().expect("sixteen lanes");
        unsafe { _mm512_loadu_ps(a.as_ptr()) }
    }
    #[inline(always)]
    fn u_load(a: &[u32]) -> __m512i {
        let a: &[u32; 16] = a[..16].try_into().expect("sixteen lanes");
        unsafe { _mm512_loadu_epi32(a.as_ptr().cast()) }
    }
    #[inline(always)]
    fn f_store(v: __m512, out: &mut [f32]) {
        let out: &mut [f32; 16] = (&mut out[..16]).try_into().expect("sixteen lanes");
        unsafe { _mm512_storeu_ps(out.as_mut_ptr(), v) }
    }
    #[inline(always)]
    fn u_store(v: __m512i, out: &mut [u32]) {
        let out: &mut [u32; 16] = (&mut out[..16]).try_into().expect("sixteen lanes");
        unsafe { _mm512_storeu_epi32(out.as_mut_ptr().cast(), v) }
    }
    #[inline(always)]
    fn add(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_add_ps(a, b) }
    }
    #[inline(always)]
    fn add_on_fma(a: __m512, b: __m512, one: __m512) -> __m512 {
        unsafe { _mm512_fmadd_ps(a, one, b) }
    }
    #[inline(always)]
    fn broadcast_add_on_fma(a: &[Cell<f32>; WIDEST], k: usize, b: __m512, one: __m512) -> __m512 {
        // `broadcast_fma` needs the CPU's AVX-512F (as every operation
        // here) and `k` within the array, which this index checks.
        let _ = &a[k];
        unsafe { broadcast_fma(a, k, b, one) }
    }
    #[inline(always)]
    fn sub(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_sub_ps(a, b) }
    }
    #[inline(always)]
    fn neg(a: __m512) -> __m512 {
        // The sign bit flipped, as scalar negation flips it.
        unsafe { _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), _mm512_set1_epi32(i32::MIN))) }
    }
    #[inline(always)]
    fn mul(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_mul_ps(a, b) }
    }
    #[inline(always)]
    fn div(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_div_ps(a, b) }
    }
    #[inline(always)]
    fn min(a: __m512, b: __m512) -> __m512 {
        // `vminps x, y` is `x < y ? x : y`, so with b first it is the
        // one-lane rule, take b only where b < a.
        unsafe { _mm512_min_ps(b, a) }
    }
    #[inline(always)]
    fn max(a: __m512, b: __m512) -> __m512 {
        // `vmaxps x, y` is `x > y ? x : y`: take b only where b > a.
        unsafe { _mm512_max_ps(b, a) }
    }
    #[inline(always)]
    fn abs(a: __m512) -> __m512 {
        unsafe { _mm512_abs_ps(a) }
    }
    #[inline(always)]
    fn sqrt(a: __m512) -> __m512 {
        unsafe { _mm512_sqrt_ps(a) }
    }
    #[inline(always)]
    fn lt(a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b) }
    }
    #[inline(always)]
    fn le(a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b) }
    }
    #[inline(always)]
    fn eq(a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b) }
    }
    #[inline(always)]
    fn u_lt(a: __m512i, b: __m512i) -> __mmask16 {
        unsafe { _mm512_cmplt_epu32_mask(a, b) }
    }
    #[inline(always)]
    fn u_eq(a: __m512i, b: __m512i) -> __mmask16 {
        unsafe { _mm512_cmpeq_epu32_mask(a, b) }
    }
    #[inline(always)]
    fn select(m: __mmask16, a: __m512, b: __m512) -> __m512 {
        // A blend takes its second operand where the mask is set.
        unsafe { _mm512_mask_blend_ps(m, b, a) }
    }
    #[inline(always)]
    fn select_u(m: __mmask16, a: __m512i, b: __m512i) -> __m512i {
        unsafe { _mm512_mask_blend_epi32(m, b, a) }
    }
    #[inline(always)]
    fn and(a: __mmask16, b: __mmask16) -> __mmask16 {
        a & b
    }
    #[inline(always)]
    fn or(a: __mmask16, b: __mmask16) -> __mmask16 {
        a | b
    }
    #[inline(always)]
    fn any(m: __mmask16) -> bool {
        m != 0
    }
    #[inline(always)]
    fn bits(m: __mmask16) -> u32 {
        u32::from(m)
    }
    #[inline(always)]
    fn u_add(a: __m512i, b: __m512i) -> __m512i {
        unsafe { _mm512_add_epi32(a, b) }
    }
    #[inline(always)]
    fn u_sub(a: __m512i, b: __m512i) -> __m512i {
        unsafe { _mm512_sub_epi32(a, b) }
    }
    #[inline(always)]
    fn u_mul(a: __m512i, b: __m512i) -> __m512i {
        unsafe { _mm512_mullo_epi32(a, b) }
    }
    #[inline(always)]
    fn u_xor(a: __m512i, b: __m512i) -> __m512i {
        unsafe { _mm512_xor_si512(a, b) }
    }
    #[inline(always)]
    fn u_and(a: __m512i, b: __m512i) -> __m512i {
        unsafe { _mm512_and_si512(a, b) }
    }
    #[inline(always)]
    fn u_min(a: __m512i, b: __m512i) -> __m512i {
        unsafe { _mm512_min_epu32(a, b) }
    }
    #[inline(always)]
    fn u_shr16(a: __m512i) -> __m512i {
        unsafe { _mm512_srli_epi32::<16>(a) }
    }
    #[inline(always)]
    fn u_shr13(a: __m512i) -> __m512i {
        unsafe { _mm512_srli_epi32::<13>(a) }
    }
    #[inline(always)]
    fn u_shr8(a: __m512i) -> __m512i {
        unsafe { _mm512_srli_epi32::<8>(a) }
    }
    #[inline(always)]
    fn u_shr24(a: __m512i) -> __m512i {
        unsafe { _mm512_srli_epi32::<24>(a) }
    }
    #[inline(always)]
    fn u24_to_f(a: __m512i) -> __m512 {
        unsafe { _mm512_cvtepi32_ps(a) }
    }
    #[inline(always)]
    fn i_to_f(a: __m512i) -> __m512 {
        unsafe { _mm512_cvtepi32_ps(a) }
    }
}

/// The Euclidean slice kernel in sixteen AVX-512 lanes, compiled with
/// the x86-64-v4 features for a build that lacks them.
///
/// # Safety
/// The CPU must have AVX-512 F, BW, DQ and VL ([`runtime_avx512`]).
#[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl")]
unsafe fn slice_avx512<const D: usize, const N: usize, P: Point<D>>(
    kernel: &Simd<D, N>,
    xs: &[P],
    out: &mut [Features32<D, N>],
) {
    kernel.slice_in_stages::<Avx512, P>(
        xs,
        out,
        |at, start| kernel.dispatch_euclid_stage::<Avx512, FIRST>(at, start),
        |at, start| kernel.dispatch_euclid_stage::<Avx512, REST>(at, start),
    );
}

/// The coherent path's Euclidean tiles of a band in these lanes,
/// sixteen samples by sixteen rows each.
///
/// # Safety
/// As [`slice_avx512`].
#[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl")]
unsafe fn tiles_avx512<const D: usize, const N: usize, T: GridSample<D, N>>(
    kernel: &Simd<D, N>,
    o: Outputs,
    band: &Band<'_, D>,
    out: &mut [T],
) {
    kernel.tiles_for::<Avx512, 16, _, T>(Euclid, o, band, out)
}

/// Runs `simd.evaluate_slice`'s work in sixteen AVX-512 lanes and returns
/// true where the CPU has AVX-512 and the metric is Euclidean (the metric
/// the speed figures are about; copying the other metrics' kernels would
/// double the crate's build for them); returns false, having written
/// nothing, otherwise.
pub(super) fn evaluate_slice<const D: usize, const N: usize, P: Point<D>>(
    simd: &Simd<D, N>,
    xs: &[P],
    out: &mut [Features32<D, N>],
) -> bool {
    if simd.config.metric != crate::config::Metric::Euclidean || !runtime_avx512() {
        return false;
    }
    // SAFETY: `runtime_avx512` has just seen the CPU report every feature
    // `slice_avx512` enables.
    unsafe { slice_avx512(simd, xs, out) };
    true
}

/// Runs the coherent path's Euclidean tiles of `band` in sixteen AVX-512
/// lanes and returns true where the CPU has AVX-512; returns false, having
/// written nothing, otherwise. The caller has checked that sixteen steps
/// along axis 0 span at most one cell.
pub(super) fn tiles<const D: usize, const N: usize, T: GridSample<D, N>>(
    simd: &Simd<D, N>,
    o: Outputs,
    band: &Band<'_, D>,
    out: &mut [T],
) -> bool {
    if !runtime_avx512() {
        return false;
    }
    // SAFETY: `runtime_avx512` has just seen the CPU report every feature
    // `tiles_avx512` enables.
    unsafe { tiles_avx512(simd, o, band, out) };
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::lanes::One;

    /// Every operation of the AVX-512 lanes gives, lane by lane, the bits of
    /// the one-lane operation, on special and random values (signed zeros,
    /// NaNs, infinities, subnormals, the unsigned top bit).
    #[test]
    fn every_operation_follows_the_one_lane_rule() {
        if !runtime_avx512() {
            eprintln!("this CPU lacks AVX-512: the run-time sixteen lanes are not tested here");
            return;
        }
        let special = [0.0f32, -0.0, 1.0, -1.0, f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 3.5e-45, 0.5];
        let words = [0u32, 1, 0xFF, 0xFFFF, 0x1_0000, 0x7FFF_FFFF, 0x8000_0000, u32::MAX, 0x00FF_FFFF, 12345];
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 32) as u32
        };
        for round in 0..2_000 {
            let pick = |r: u32| special[r as usize % special.len()];
            let r: [u32; 64] = std::array::from_fn(|_| next());
            let fa: [f32; 16] = std::array::from_fn(|l| if round % 2 == 0 { pick(r[l]) } else { f32::from_bits(r[l]) });
            let fb: [f32; 16] = std::array::from_fn(|l| match round % 5 {
                0 | 3 => pick(r[16 + l]),
                1 => fa[l],
                _ => f32::from_bits(r[16 + l]),
            });
            let ua: [u32; 16] =
                std::array::from_fn(|l| if round % 2 == 0 { words[r[32 + l] as usize % 10] } else { r[32 + l] });
            let ub: [u32; 16] = std::array::from_fn(|l| match round % 5 {
                0 | 3 => words[r[48 + l] as usize % 10],
                1 => ua[l],
                _ => r[48 + l],
            });
            check(&fa, &fb, &ua, &ub);
        }
    }

    /// A float operation's name, its result in sixteen lanes and its
    /// one-lane rule.
    type Float = (&'static str, __m512, fn(f32, f32) -> f32);
    /// The same for a comparison (of the floats or of the words).
    type Compare = (&'static str, __mmask16, fn(f32, f32, u32, u32) -> bool);
    /// The same for a word operation.
    type Word = (&'static str, __m512i, fn(u32, u32) -> u32);

    /// One round of [`every_operation_follows_the_one_lane_rule`].
    fn check(fa: &[f32; 16], fb: &[f32; 16], ua: &[u32; 16], ub: &[u32; 16]) {
        type L = Avx512;
        let (a, b, x, y) = (L::f_load(fa), L::f_load(fb), L::u_load(ua), L::u_load(ub));
        let one = L::f(std::hint::black_box(1.0));
        let cells: [Cell<f32>; WIDEST] = std::array::from_fn(|l| Cell::new(fa[l]));
        for (k, &ak) in fa.iter().enumerate() {
            let mut lanes = [0.0; 16];
            L::f_store(L::broadcast_add_on_fma(&cells, k, b, one), &mut lanes);
            for l in 0..16 {
                let w = One::add(ak, fb[l]);
                let same = lanes[l].to_bits() == w.to_bits() || (lanes[l].is_nan() && w.is_nan());
                assert!(
                    same,
                    "broadcast_add_on_fma(a[{k}] = {:?}, {:?}) lane {l}: {:?} against {w:?}",
                    fa[k], fb[l], lanes[l]
                );
            }
        }
        let floats: [Float; 8] = [
            ("add", L::add(a, b), One::add),
            ("add_on_fma", L::add_on_fma(a, b, one), One::add),
            ("sub", L::sub(a, b), One::sub),
            ("mul", L::mul(a, b), One::mul),
            ("min", L::min(a, b), One::min),
            ("max", L::max(a, b), One::max),
            ("abs", L::abs(a), |a, _| One::abs(a)),
            ("sqrt", L::sqrt(a), |a, _| One::sqrt(a)),
        ];
        for (name, got, want) in floats {
            let mut lanes = [0.0; 16];
            L::f_store(got, &mut lanes);
            for l in 0..16 {
                let w = want(fa[l], fb[l]);
                // Arithmetic on a NaN agrees when both are NaN, whatever
                // payload each path kept; min and max return one of their
                // inputs, so they must match bit for bit.
                let both_nan = lanes[l].is_nan() && w.is_nan() && !matches!(name, "min" | "max");
                assert!(
                    lanes[l].to_bits() == w.to_bits() || both_nan,
                    "{name}({:?}, {:?}) lane {l}: {:?} against {:?}",
                    fa[l],
                    fb[l],
                    lanes[l],
                    w
                );
            }
        }
        let masks: [Compare; 4] = [
            ("lt", L::lt(a, b), |a, b, _, _| One::lt(a, b)),
            ("le", L::le(a, b), |a, b, _, _| One::le(a, b)),
            ("eq", L::eq(a, b), |a, b, _, _| One::eq(a, b)),
            ("u_lt", L::u_lt(x, y), |_, _, x, y| One::u_lt(x, y)),
        ];
        for (name, got, want) in masks {
            for l in 0..16 {
                assert_eq!(L::bits(got) >> l & 1 == 1, want(fa[l], fb[l], ua[l], ub[l]), "{name} lane {l}");
            }
        }
        let m = L::lt(a, b);
        let (mut sel, mut sel_u) = ([0.0; 16], [0; 16]);
        L::f_store(L::select(m, a, b), &mut sel);
        L::u_store(L::select_u(m, x, y), &mut sel_u);
        let words: [Word; 9] = [
            ("u_add", L::u_add(x, y), One::u_add),
            ("u_mul", L::u_mul(x, y), One::u_mul),
            ("u_xor", L::u_xor(x, y), One::u_xor),
            ("u_and", L::u_and(x, y), One::u_and),
            ("u_min", L::u_min(x, y), One::u_min),
            ("u_shr16", L::u_shr16(x), |x, _| One::u_shr16(x)),
            ("u_shr13", L::u_shr13(x), |x, _| One::u_shr13(x)),
            ("u_shr8", L::u_shr8(x), |x, _| One::u_shr8(x)),
            ("u_shr24", L::u_shr24(x), |x, _| One::u_shr24(x)),
        ];
        for (name, got, want) in words {
            let mut lanes = [0; 16];
            L::u_store(got, &mut lanes);
            for l in 0..16 {
                assert_eq!(lanes[l], want(ua[l], ub[l]), "{name}({:#x}, {:#x}) lane {l}", ua[l], ub[l]);
            }
        }
        let mut conv = [0.0; 16];
        let small = L::u_and(x, L::u(0x00FF_FFFF));
        L::f_store(L::u24_to_f(small), &mut conv);
        for l in 0..16 {
            let one = One::select(One::lt(fa[l], fb[l]), fa[l], fb[l]);
            assert_eq!(sel[l].to_bits(), one.to_bits(), "select lane {l}");
            let one_u = One::select_u(One::lt(fa[l], fb[l]), ua[l], ub[l]);
            assert_eq!(sel_u[l], one_u, "select_u lane {l}");
            assert_eq!(conv[l].to_bits(), One::u24_to_f(ua[l] & 0x00FF_FFFF).to_bits(), "u24_to_f lane {l}");
        }
        assert_eq!(L::any(m), (0..16).any(|l| One::lt(fa[l], fb[l])));
        assert_eq!(L::bits(L::and(m, L::le(a, b))), L::bits(m));
        assert_eq!(L::bits(L::or(m, L::eq(a, b))), L::bits(L::le(a, b)));
    }
}
