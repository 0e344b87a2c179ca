//! The lane sets against the one-lane rule, operation by operation.

use super::*;

/// `add_on_fma` gives `add`'s bits, and `broadcast_add_on_fma` those of
/// `add` of the broadcast, with the 1 hidden from the compiler as the
/// tiles hide it: signed zeros, infinities, NaN, subnormals,
/// cancellation and rounding ties, every index of the broadcast, in
/// every lane set of the build.
#[test]
fn add_on_fma_is_the_sum_bit_for_bit() {
    fn check<L: Lanes>() {
        let special = [0.0, -0.0, 1.0, -1.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, f32::MIN_POSITIVE / 4.0];
        let mut values: Vec<f32> = special.to_vec();
        let mut state = 0x9E37_79B9u32;
        for _ in 0..4000 {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            values.push(f32::from_bits(state));
            values.push(1.0 + (state >> 9) as f32 * f32::EPSILON);
        }
        let one = L::f(std::hint::black_box(1.0));
        for pair in values.chunks(2 * L::N).filter(|c| c.len() == 2 * L::N) {
            let (a, b) = (L::f_load(&pair[..L::N]), L::f_load(&pair[L::N..]));
            for (x, y) in [(a, b), (b, a)] {
                let (mut sum, mut fused) = ([0f32; WIDEST], [0f32; WIDEST]);
                L::f_store(L::add(x, y), &mut sum);
                L::f_store(L::add_on_fma(x, y, one), &mut fused);
                for (s, f) in sum[..L::N].iter().zip(&fused[..L::N]) {
                    assert!(s.to_bits() == f.to_bits() || (s.is_nan() && f.is_nan()), "{s} vs {f}");
                }
            }
            let cells: [Cell<f32>; WIDEST] = std::array::from_fn(|i| Cell::new(pair[(7 * i) % pair.len()]));
            for k in 0..WIDEST {
                let (mut sum, mut fused) = ([0f32; WIDEST], [0f32; WIDEST]);
                L::f_store(L::add(L::f(cells[k].get()), b), &mut sum);
                L::f_store(L::broadcast_add_on_fma(&cells, k, b, one), &mut fused);
                for (s, f) in sum[..L::N].iter().zip(&fused[..L::N]) {
                    assert!(s.to_bits() == f.to_bits() || (s.is_nan() && f.is_nan()), "[{k}]: {s} vs {f}");
                }
            }
        }
    }
    check::<One>();
    check::<Eight>();
    check::<Sixteen>();
}

/// The lane multiply, whichever instructions `wide` compiled it to, is
/// the wrapping product of every lane, in eight and in sixteen lanes.
#[test]
fn lane_multiply_is_the_wrapping_product() {
    let mut state = 0x1234_5678_9ABC_DEF0u64;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 32) as u32
    };
    let edges = [0, 1, 0xFFFF, 0x1_0000, 0x8000_0000, u32::MAX, 0xFFFF_0000, 0x0000_FFFF];
    for round in 0..20_000 {
        let a: [u32; 16] = std::array::from_fn(|i| if round == 0 { edges[i % 8] } else { next() });
        let b: [u32; 16] = std::array::from_fn(|i| if round < 8 { edges[(i + round) % 8] } else { next() });
        let mut eight = [0; 16];
        Eight::u_store(Eight::u_mul(Eight::u_load(&a), Eight::u_load(&b)), &mut eight);
        let mut sixteen = [0; 16];
        Sixteen::u_store(Sixteen::u_mul(Sixteen::u_load(&a), Sixteen::u_load(&b)), &mut sixteen);
        for i in 0..16 {
            let want = a[i].wrapping_mul(b[i]);
            if i < 8 {
                assert_eq!(eight[i], want, "eight lanes: {:#x} * {:#x}", a[i], b[i]);
            }
            assert_eq!(sixteen[i], want, "sixteen lanes: {:#x} * {:#x}", a[i], b[i]);
        }
    }
}

/// Eight and sixteen lanes' minimum and maximum follow the one-lane
/// rule (take b only where b < a, or where a < b) bit for bit, signed
/// zeros, NaNs and infinities included, whichever instructions they
/// compile to.
#[test]
fn lane_minimum_and_maximum_follow_the_one_lane_rule() {
    fn check<L: Lanes>() {
        let special = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            3.5e-45,
        ];
        let n = special.len();
        for i in 0..n * n {
            let a: [f32; 16] = std::array::from_fn(|l| special[(i + l) % n]);
            let b: [f32; 16] = std::array::from_fn(|l| special[(i / n + 3 * l) % n]);
            let (mut lo, mut hi) = ([0.0; 16], [0.0; 16]);
            L::f_store(L::min(L::f_load(&a), L::f_load(&b)), &mut lo);
            L::f_store(L::max(L::f_load(&a), L::f_load(&b)), &mut hi);
            for l in 0..L::N {
                let what = format!("{} lanes: a = {:?}, b = {:?}", L::N, a[l], b[l]);
                assert_eq!(lo[l].to_bits(), One::min(a[l], b[l]).to_bits(), "min: {what}");
                assert_eq!(hi[l].to_bits(), One::max(a[l], b[l]).to_bits(), "max: {what}");
            }
        }
    }
    check::<Eight>();
    check::<Sixteen>();
}
