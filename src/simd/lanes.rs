//! The lane abstraction the SIMD kernel is written over.
//!
//! The kernel is written once against [`Lanes`] and instantiated for
//! [`One`] (plain `f32`/`u32`), [`Eight`] (`wide`'s `f32x8`/`u32x8`) and
//! [`Sixteen`] (`f32x16`/`u32x16`, which slices use in AVX-512 builds).
//! Every operation here is one IEEE operation per lane with the same result
//! in every build: no approximate reciprocal, no horizontal reduction whose
//! order could change, and no fused multiply-add but a · 1 + b, which
//! rounds a + b once as the addition does ([`Lanes::add_on_fma`]). A single point evaluated
//! through `One` and the same point in any lane of `Eight` or `Sixteen` are
//! therefore bit-identical, in the default, AVX2 and AVX-512 builds alike.
//! `Eight` and `Sixteen` are one macro over `wide`'s types of each width,
//! so the two cannot drift apart.

use std::cell::Cell;
use wide::{f32x16, f32x8, i32x16, i32x8, u32x16, u32x8};

/// The widest lane set's width: per-lane arrays in the kernel (cells,
/// fractions, validity) are sized for it and used up to [`Lanes::N`].
pub const WIDEST: usize = 16;

/// A set of lanes: float, unsigned and mask types and the operations the
/// kernel needs.
pub trait Lanes: Copy + 'static {
    /// Number of lanes.
    const N: usize;
    /// How many ranks of lanes a tile may keep in registers through its
    /// candidates (at most half the register file): two of sixteen lanes
    /// in AVX-512's 32 registers, one otherwise (eight lanes, or sixteen
    /// as two AVX2 halves in its 16 registers, where two ranks measured
    /// 0.89x of one on grid F2).
    const LOCAL_RANKS: usize = 1;
    /// f32 lanes.
    type F: Copy;
    /// u32 lanes.
    type U: Copy;
    /// A per-lane condition.
    type M: Copy;

    /// Every lane `v`.
    fn f(v: f32) -> Self::F;
    /// Every lane `v`.
    fn u(v: u32) -> Self::U;
    /// Lanes from an array (`a.len() == N`).
    fn f_load(a: &[f32]) -> Self::F;
    /// Lanes from an array (`a.len() == N`).
    fn u_load(a: &[u32]) -> Self::U;
    /// Lanes into an array (`out.len() == N`).
    fn f_store(v: Self::F, out: &mut [f32]);
    /// Lanes into an array (`out.len() == N`).
    fn u_store(v: Self::U, out: &mut [u32]);

    /// a + b
    fn add(a: Self::F, b: Self::F) -> Self::F;
    /// a + b computed as a · `one` + b, `one` being 1 in every lane: the
    /// same bits as [`Lanes::add`] (a · 1 is exact, so a fused and an
    /// unfused multiply-add both round a + b once). Where the build has FMA
    /// it runs on the multiply-add units, which on AMD's Zen 4 are not the
    /// ones that add and take minimums. `one` must come from a value the
    /// compiler cannot see, or it turns the product back into an addition.
    #[inline(always)]
    fn add_on_fma(a: Self::F, b: Self::F, one: Self::F) -> Self::F {
        let _ = one;
        Self::add(a, b)
    }
    /// The value in `a[k]` in every lane, plus b, computed as
    /// [`Lanes::add_on_fma`] computes it (the same bits as
    /// `add(f(a[k].get()), b)`). Where the lanes are one AVX-512 register, the
    /// multiply-add reads `a[k]` from memory and broadcasts it itself (an
    /// embedded broadcast), where a broadcast of its own would take a slot
    /// on the vector units: on Zen 4, a loop of these and minimums ran in
    /// two thirds of the time (docs/simd.md).
    #[inline(always)]
    fn broadcast_add_on_fma(a: &[Cell<f32>; WIDEST], k: usize, b: Self::F, one: Self::F) -> Self::F {
        Self::add_on_fma(Self::f(a[k].get()), b, one)
    }
    /// a − b
    fn sub(a: Self::F, b: Self::F) -> Self::F;
    /// −a (the sign flipped, as scalar negation flips it: −0 from 0)
    fn neg(a: Self::F) -> Self::F;
    /// a · b (rounded once; never fused)
    fn mul(a: Self::F, b: Self::F) -> Self::F;
    /// a / b (correctly rounded; no approximate reciprocal)
    fn div(a: Self::F, b: Self::F) -> Self::F;
    /// min(a, b) for non-NaN lanes
    fn min(a: Self::F, b: Self::F) -> Self::F;
    /// max(a, b) for non-NaN lanes
    fn max(a: Self::F, b: Self::F) -> Self::F;
    /// |a|
    fn abs(a: Self::F) -> Self::F;
    /// √a, correctly rounded
    fn sqrt(a: Self::F) -> Self::F;
    /// a < b
    fn lt(a: Self::F, b: Self::F) -> Self::M;
    /// `a <= b` per lane (false where either is NaN).
    fn le(a: Self::F, b: Self::F) -> Self::M;
    /// `a == b` per lane (false where either is NaN).
    fn eq(a: Self::F, b: Self::F) -> Self::M;
    /// Unsigned `a < b` per lane.
    fn u_lt(a: Self::U, b: Self::U) -> Self::M;
    /// `a == b` per lane.
    fn u_eq(a: Self::U, b: Self::U) -> Self::M;
    /// m ? a : b
    fn select(m: Self::M, a: Self::F, b: Self::F) -> Self::F;
    /// m ? a : b
    fn select_u(m: Self::M, a: Self::U, b: Self::U) -> Self::U;
    /// a ∧ b
    fn and(a: Self::M, b: Self::M) -> Self::M;
    /// Either condition.
    fn or(a: Self::M, b: Self::M) -> Self::M;
    /// Any lane true.
    fn any(m: Self::M) -> bool;
    /// Bit i set where lane i is true.
    fn bits(m: Self::M) -> u32;

    /// a + b (wrapping)
    fn u_add(a: Self::U, b: Self::U) -> Self::U;
    /// a − b (wrapping)
    fn u_sub(a: Self::U, b: Self::U) -> Self::U;
    /// a · b (wrapping)
    fn u_mul(a: Self::U, b: Self::U) -> Self::U;
    /// a ^ b
    fn u_xor(a: Self::U, b: Self::U) -> Self::U;
    /// a & b
    fn u_and(a: Self::U, b: Self::U) -> Self::U;
    /// min(a, b), unsigned
    fn u_min(a: Self::U, b: Self::U) -> Self::U;
    /// a >> 16
    fn u_shr16(a: Self::U) -> Self::U;
    /// a >> 13
    fn u_shr13(a: Self::U) -> Self::U;
    /// a >> 8
    fn u_shr8(a: Self::U) -> Self::U;
    /// a >> 24
    fn u_shr24(a: Self::U) -> Self::U;
    /// a as f32 for a < 2^24 (exact)
    fn u24_to_f(a: Self::U) -> Self::F;
    /// The bits of `a` read as an i32, converted to f32 (rounded to
    /// nearest, ties to even; exact below 2^24 in magnitude).
    fn i_to_f(a: Self::U) -> Self::F;
}

/// One lane: plain scalars.
#[derive(Clone, Copy, Debug)]
pub struct One;

/// Eight lanes: `wide`'s 256-bit types.
#[derive(Clone, Copy, Debug)]
pub struct Eight;

/// Sixteen lanes: `wide`'s 512-bit types, one AVX-512 register each where
/// the build has `avx512f` and two 256-bit halves otherwise.
#[derive(Clone, Copy, Debug)]
pub struct Sixteen;

impl Lanes for One {
    const N: usize = 1;
    type F = f32;
    type U = u32;
    type M = bool;

    #[inline(always)]
    fn f(v: f32) -> f32 {
        v
    }
    #[inline(always)]
    fn u(v: u32) -> u32 {
        v
    }
    #[inline(always)]
    fn f_load(a: &[f32]) -> f32 {
        a[0]
    }
    #[inline(always)]
    fn u_load(a: &[u32]) -> u32 {
        a[0]
    }
    #[inline(always)]
    fn f_store(v: f32, out: &mut [f32]) {
        out[0] = v;
    }
    #[inline(always)]
    fn u_store(v: u32, out: &mut [u32]) {
        out[0] = v;
    }
    #[inline(always)]
    fn add(a: f32, b: f32) -> f32 {
        a + b
    }
    #[inline(always)]
    fn sub(a: f32, b: f32) -> f32 {
        a - b
    }
    #[inline(always)]
    fn neg(a: f32) -> f32 {
        -a
    }
    #[inline(always)]
    fn mul(a: f32, b: f32) -> f32 {
        a * b
    }
    #[inline(always)]
    fn div(a: f32, b: f32) -> f32 {
        a / b
    }
    #[inline(always)]
    fn min(a: f32, b: f32) -> f32 {
        if b < a {
            b
        } else {
            a
        }
    }
    #[inline(always)]
    fn max(a: f32, b: f32) -> f32 {
        if b > a {
            b
        } else {
            a
        }
    }
    #[inline(always)]
    fn abs(a: f32) -> f32 {
        a.abs()
    }
    #[inline(always)]
    fn sqrt(a: f32) -> f32 {
        a.sqrt()
    }
    #[inline(always)]
    fn lt(a: f32, b: f32) -> bool {
        a < b
    }
    #[inline(always)]
    fn le(a: f32, b: f32) -> bool {
        a <= b
    }
    #[inline(always)]
    fn eq(a: f32, b: f32) -> bool {
        a == b
    }
    #[inline(always)]
    fn u_lt(a: u32, b: u32) -> bool {
        a < b
    }
    #[inline(always)]
    fn u_eq(a: u32, b: u32) -> bool {
        a == b
    }
    #[inline(always)]
    fn select(m: bool, a: f32, b: f32) -> f32 {
        if m {
            a
        } else {
            b
        }
    }
    #[inline(always)]
    fn select_u(m: bool, a: u32, b: u32) -> u32 {
        if m {
            a
        } else {
            b
        }
    }
    #[inline(always)]
    fn and(a: bool, b: bool) -> bool {
        a & b
    }
    #[inline(always)]
    fn or(a: bool, b: bool) -> bool {
        a | b
    }
    #[inline(always)]
    fn any(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn bits(m: bool) -> u32 {
        u32::from(m)
    }
    #[inline(always)]
    fn u_add(a: u32, b: u32) -> u32 {
        a.wrapping_add(b)
    }
    #[inline(always)]
    fn u_sub(a: u32, b: u32) -> u32 {
        a.wrapping_sub(b)
    }
    #[inline(always)]
    fn u_mul(a: u32, b: u32) -> u32 {
        a.wrapping_mul(b)
    }
    #[inline(always)]
    fn u_xor(a: u32, b: u32) -> u32 {
        a ^ b
    }
    #[inline(always)]
    fn u_and(a: u32, b: u32) -> u32 {
        a & b
    }
    #[inline(always)]
    fn u_min(a: u32, b: u32) -> u32 {
        a.min(b)
    }
    #[inline(always)]
    fn u_shr16(a: u32) -> u32 {
        a >> 16
    }
    #[inline(always)]
    fn u_shr13(a: u32) -> u32 {
        a >> 13
    }
    #[inline(always)]
    fn u_shr8(a: u32) -> u32 {
        a >> 8
    }
    #[inline(always)]
    fn u_shr24(a: u32) -> u32 {
        a >> 24
    }
    #[inline(always)]
    fn u24_to_f(a: u32) -> f32 {
        a as i32 as f32
    }
    #[inline(always)]
    fn i_to_f(a: u32) -> f32 {
        a as i32 as f32
    }
}

/// The lanes of `wide`'s float and integer types of one width: the same
/// code for eight and sixteen lanes, so that both follow one lane rule.
macro_rules! wide_lanes {
    ($name:ident, $n:literal, $f:ident, $u:ident, $i:ident, $from:ident $(, $broadcast:ident)?) => {
        impl Lanes for $name {
            const N: usize = $n;
            const LOCAL_RANKS: usize = if $n >= 16 && cfg!(target_feature = "avx512f") { 2 } else { 1 };
            type F = $f;
            type U = $u;
            type M = $f;

            #[inline(always)]
            fn f(v: f32) -> $f {
                $f::splat(v)
            }
            #[inline(always)]
            fn u(v: u32) -> $u {
                $u::splat(v)
            }
            #[inline(always)]
            fn f_load(a: &[f32]) -> $f {
                let mut v = [0.0; $n];
                v.copy_from_slice(&a[..$n]);
                $f::new(v)
            }
            #[inline(always)]
            fn u_load(a: &[u32]) -> $u {
                let mut v = [0; $n];
                v.copy_from_slice(&a[..$n]);
                $u::new(v)
            }
            #[inline(always)]
            fn f_store(v: $f, out: &mut [f32]) {
                out[..$n].copy_from_slice(&v.to_array());
            }
            #[inline(always)]
            fn u_store(v: $u, out: &mut [u32]) {
                out[..$n].copy_from_slice(&v.to_array());
            }
            #[inline(always)]
            fn add(a: $f, b: $f) -> $f {
                a + b
            }
            #[inline(always)]
            fn add_on_fma(a: $f, b: $f, one: $f) -> $f {
                if cfg!(target_feature = "fma") {
                    a.mul_add(one, b)
                } else {
                    a + b
                }
            }
            $(
                #[inline(always)]
                fn broadcast_add_on_fma(a: &[Cell<f32>; WIDEST], k: usize, b: $f, one: $f) -> $f {
                    $broadcast(a, k, b, one)
                }
            )?
            #[inline(always)]
            fn sub(a: $f, b: $f) -> $f {
                a - b
            }
            #[inline(always)]
            fn neg(a: $f) -> $f {
                -a
            }
            #[inline(always)]
            fn mul(a: $f, b: $f) -> $f {
                a * b
            }
            #[inline(always)]
            fn div(a: $f, b: $f) -> $f {
                a / b
            }
            #[inline(always)]
            fn min(a: $f, b: $f) -> $f {
                // Same lane rule as `One::min`: take b only where b < a. On x86
                // that is the minimum instruction with b first, in every build
                // (`fast_min` is `minps` on SSE and AVX, and the same comparison in
                // `wide`'s scalar code); elsewhere a comparison and a select.
                #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
                return b.fast_min(a);
                #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
                return b.simd_lt(a).select(b, a);
            }
            #[inline(always)]
            fn max(a: $f, b: $f) -> $f {
                // Take b only where a < b, as `One::max`: `maxps` with b first.
                #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
                return b.fast_max(a);
                #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
                return a.simd_lt(b).select(b, a);
            }
            #[inline(always)]
            fn abs(a: $f) -> $f {
                a.abs()
            }
            #[inline(always)]
            fn sqrt(a: $f) -> $f {
                a.sqrt()
            }
            #[inline(always)]
            fn lt(a: $f, b: $f) -> $f {
                a.simd_lt(b)
            }
            #[inline(always)]
            fn le(a: $f, b: $f) -> $f {
                a.simd_le(b)
            }
            #[inline(always)]
            fn eq(a: $f, b: $f) -> $f {
                a.simd_eq(b)
            }
            #[inline(always)]
            fn u_lt(a: $u, b: $u) -> $f {
                // Unsigned order is signed order with the top bit flipped.
                let flip = $u::splat(0x8000_0000);
                let (x, y): ($i, $i) = (bytemuck::cast(a ^ flip), bytemuck::cast(b ^ flip));
                bytemuck::cast(x.simd_lt(y))
            }
            #[inline(always)]
            fn u_eq(a: $u, b: $u) -> $f {
                let (x, y): ($i, $i) = (bytemuck::cast(a), bytemuck::cast(b));
                bytemuck::cast(x.simd_eq(y))
            }
            #[inline(always)]
            fn select(m: $f, a: $f, b: $f) -> $f {
                m.select(a, b)
            }
            #[inline(always)]
            fn select_u(m: $f, a: $u, b: $u) -> $u {
                m.select(a, b)
            }
            #[inline(always)]
            fn and(a: $f, b: $f) -> $f {
                a & b
            }
            #[inline(always)]
            fn or(a: $f, b: $f) -> $f {
                a | b
            }
            #[inline(always)]
            fn any(m: $f) -> bool {
                m.any()
            }
            #[inline(always)]
            fn bits(m: $f) -> u32 {
                m.to_bitmask()
            }
            #[inline(always)]
            fn u_add(a: $u, b: $u) -> $u {
                a + b
            }
            #[inline(always)]
            fn u_sub(a: $u, b: $u) -> $u {
                a - b
            }
            #[inline(always)]
            fn u_mul(a: $u, b: $u) -> $u {
                a * b
            }
            #[inline(always)]
            fn u_xor(a: $u, b: $u) -> $u {
                a ^ b
            }
            #[inline(always)]
            fn u_and(a: $u, b: $u) -> $u {
                a & b
            }
            #[inline(always)]
            fn u_min(a: $u, b: $u) -> $u {
                a.min(b)
            }
            #[inline(always)]
            fn u_shr16(a: $u) -> $u {
                a >> 16_u32
            }
            #[inline(always)]
            fn u_shr13(a: $u) -> $u {
                a >> 13_u32
            }
            #[inline(always)]
            fn u_shr8(a: $u) -> $u {
                a >> 8_u32
            }
            #[inline(always)]
            fn u_shr24(a: $u) -> $u {
                a >> 24_u32
            }
            #[inline(always)]
            fn u24_to_f(a: $u) -> $f {
                let i: $i = bytemuck::cast(a);
                $f::$from(i)
            }
            #[inline(always)]
            fn i_to_f(a: $u) -> $f {
                let i: $i = bytemuck::cast(a);
                $f::$from(i)
            }
        }
    };
}

wide_lanes!(Eight, 8, f32x8, u32x8, i32x8, from_i32x8);
wide_lanes!(Sixteen, 16, f32x16, u32x16, i32x16, from_i32x16, broadcast_add_sixteen);

/// [`Lanes::broadcast_add_on_fma`] for [`Sixteen`]: in an AVX-512 build,
/// [`broadcast_fma`]; elsewhere the broadcast, then [`Lanes::add_on_fma`].
#[inline(always)]
fn broadcast_add_sixteen(a: &[Cell<f32>; WIDEST], k: usize, b: f32x16, one: f32x16) -> f32x16 {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx512f"))]
    {
        use std::arch::x86_64::__m512;
        let _ = &a[k];
        // SAFETY: `f32x16` is sixteen f32 in one 64-byte AVX-512 register in
        // this build (`wide` holds an `__m512`), so the transmutes only
        // rename the type, and every bit pattern is valid in both. The build
        // has AVX-512F and `k` was checked against the array just above,
        // which is what `broadcast_fma` needs.
        #[allow(unsafe_code)]
        unsafe {
            let (b, one) = (std::mem::transmute::<f32x16, __m512>(b), std::mem::transmute::<f32x16, __m512>(one));
            std::mem::transmute::<__m512, f32x16>(broadcast_fma(a, k, b, one))
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx512f")))]
    Sixteen::add_on_fma(Sixteen::f(a[k].get()), b, one)
}

/// `a[k]` broadcast, times `one`, plus `b`: the multiply-add that
/// [`Lanes::broadcast_add_on_fma`] asks for in AVX-512 lanes, as one
/// `vfmadd231ps` with the broadcast embedded (`{1to16}`), which the compiler
/// does not choose by itself (it broadcasts into a register first). The
/// address is the array's plus `k` in a register, so that the sixteen rows
/// of a tile share one base. Used by `wide`'s sixteen lanes in AVX-512
/// builds and by the run-time AVX-512 lanes of other builds.
///
/// # Safety
/// The CPU must have AVX-512F, and `k` must be below `WIDEST`. The
/// instruction then reads the four bytes of `a[k]`, a live `Cell<f32>` that
/// nothing writes meanwhile, and writes only its output register.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
#[allow(unsafe_code)]
pub(super) unsafe fn broadcast_fma(
    a: &[Cell<f32>; WIDEST],
    k: usize,
    b: std::arch::x86_64::__m512,
    one: std::arch::x86_64::__m512,
) -> std::arch::x86_64::__m512 {
    let mut sum = b;
    // The caller upholds the contract above; the instruction reads `a[k]`
    // and nothing else in memory.
    unsafe {
        std::arch::asm!(
            "vfmadd231ps {sum}, {one}, dword ptr [{a} + 4 * {k}]{{1to16}}",
            sum = inout(zmm_reg) sum,
            one = in(zmm_reg) one,
            a = in(reg) a.as_ptr(),
            k = in(reg) k,
            options(pure, readonly, nostack, preserves_flags),
        );
    }
    sum
}

#[cfg(test)]
mod tests;
