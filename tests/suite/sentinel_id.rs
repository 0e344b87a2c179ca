//! No real feature point carries the sentinel ID.
//!
//! A point's ID is an LCG state, so some cells hold a point whose state is
//! `0xFFFFFFFF` = `INVALID_ID`; the definition reports it as `INVALID_ID − 1`.
//! The test does not search for such cells at random: it inverts the LCG and
//! the cell hash (every step is a bijection of a 32-bit word) to construct
//! one in 2D, 3D and 4D, checks that the hash of the constructed cell is the
//! state it aimed at, and evaluates a sample on the point through every
//! entry point, expecting F1 = 0 and ID `INVALID_ID − 1`.

use worley::definition::{lcg_step, SeedKeys, AXIS_MUL, LCG_ADD, LCG_MUL};
use worley::{Config, Outputs, Period, Reference, Simd, INVALID_ID};

/// The multiplicative inverse of an odd number mod 2^32 (Newton's iteration
/// doubles the correct low bits each step).
fn inverse(a: u32) -> u32 {
    let mut x = a;
    for _ in 0..5 {
        x = x.wrapping_mul(2u32.wrapping_sub(a.wrapping_mul(x)));
    }
    assert_eq!(a.wrapping_mul(x), 1);
    x
}

/// Undoes `h ^= h >> s`.
fn unshift(h: u32, s: u32) -> u32 {
    let mut x = h;
    for _ in 0..32 / s + 1 {
        x = h ^ (x >> s);
    }
    x
}

/// The inverse of MurmurHash3's finaliser as the definition's text gives it.
fn unmix(mut h: u32) -> u32 {
    h = unshift(h, 16);
    h = h.wrapping_mul(inverse(0xC2B2_AE35));
    h = unshift(h, 13);
    h = h.wrapping_mul(inverse(0x85EB_CA6B));
    unshift(h, 16)
}

fn mix(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 13;
    h = h.wrapping_mul(0xC2B2_AE35);
    h ^ (h >> 16)
}

/// (A_k, C_k): the LCG advanced k steps, s_k = A_k·s₀ + C_k.
fn jump(k: u32) -> (u32, u32) {
    (0..k).fold((1u32, 0u32), |(a, c), _| (a.wrapping_mul(LCG_MUL), c.wrapping_mul(LCG_MUL).wrapping_add(LCG_ADD)))
}

/// Cells with coordinates in [0, 2^16) on every axis: small enough for a
/// period and for f32 user coordinates to find the same point.
const SMALL: u32 = 1 << 16;

/// A cell with every coordinate in [0, [`SMALL`]) whose point `j` has the ID
/// state 0xFFFFFFFF, and `j`.
fn sentinel_cell<const D: usize>(seed: u64, table: &[u8; 256]) -> ([i64; D], usize) {
    let keys = SeedKeys::new(seed);
    let last = D - 1;
    for j in 0..16u32 {
        // The initial state s₀ that puts 0xFFFFFFFF at point j's ID state
        // s_{1 + j(d+1)}; it must hold more than j points.
        let (a, c) = jump(1 + j * (D as u32 + 1));
        let s0 = u32::MAX.wrapping_sub(c).wrapping_mul(inverse(a));
        if u32::from(table[(s0 >> 24) as usize]) <= j {
            continue;
        }
        // The chain's state after the last axis plus the other axes' words.
        let end = unmix(s0) ^ keys.finish;
        // Choose the other axes' cells, run the chain over them, and solve
        // for the last axis's word, term and cell; keep the first small one.
        for prefix in 0..u64::from(SMALL).pow(last as u32).min(1 << 20) {
            let mut cell = [0i64; D];
            let mut h = keys.init;
            let mut sum = 0u32;
            let mut rest = prefix;
            for a in 0..last {
                cell[a] = (rest % u64::from(SMALL)) as i64;
                rest /= u64::from(SMALL);
                let w = mix((cell[a] as u32) ^ AXIS_MUL[a]);
                h = (h ^ w).wrapping_mul(AXIS_MUL[a]);
                h ^= h >> 16;
                sum = sum.wrapping_add(w);
            }
            let chain = end.wrapping_sub(sum);
            let word = unshift(chain, 16).wrapping_mul(inverse(AXIS_MUL[last])) ^ h;
            let term = unmix(word) ^ AXIS_MUL[last];
            if term < SMALL {
                cell[last] = i64::from(term);
                return (cell, j as usize);
            }
        }
    }
    panic!("no small cell found for seed {seed}")
}

fn check<const D: usize>(seed: u64) {
    let config = Config { seed, order: 2, ..Config::default() };
    let reference = Reference::<D>::new(config).unwrap();
    let pattern = reference.pattern();
    let (cell, j) = sentinel_cell::<D>(seed, pattern.table().entries());
    let what = format!("{D}D seed {seed}: cell {cell:?}, point {j}");

    // The construction really aimed at this cell: re-run the LCG from the
    // definition's hash to the ID state.
    let s0 = worley::definition::cell_hash(pattern.keys(), cell);
    let state = (0..1 + j * (D + 1)).fold(s0, |s, _| lcg_step(s));
    assert_eq!(state, u32::MAX, "{what}");
    let point = pattern.points(cell)[j];
    assert_eq!(point.id, INVALID_ID - 1, "{what}");

    let fraction = point.offset();
    let s = pattern.scale();
    let x: [f64; D] = std::array::from_fn(|a| (cell[a] as f64 + fraction[a]) / s);
    let x32 = x.map(|v| v as f32);
    let cells_x: [f64; D] = std::array::from_fn(|a| cell[a] as f64 + fraction[a]);
    // F1 is zero up to the rounding of the sample: 2^-8 cells per axis for
    // f32 user coordinates near 2^16 cells.
    let expect = |name: &str, f1: f64, id: u32| {
        assert_eq!(id, INVALID_ID - 1, "{what}: {name} gave ID {id:#x}");
        assert!(f1 < 0.01, "{what}: {name} gave F1 {f1}");
    };

    let r = reference.evaluate(x);
    expect("Reference::evaluate", r.distance[0], r.id[0]);
    let r = reference.evaluate_in_cell(cell, fraction);
    expect("Reference::evaluate_in_cell", r.distance[0], r.id[0]);
    assert_eq!(r.distance[0], 0.0, "{what}");

    for outputs in [Outputs::Ids, Outputs::IdsAndDeltas] {
        let simd = Simd::<D, 2>::new(config, outputs).unwrap();
        let f = simd.evaluate(x);
        expect("Simd::evaluate", f.distance[0].into(), f.id[0]);
        let f = simd.evaluate_f32(x32);
        expect("Simd::evaluate_f32", f.distance[0].into(), f.id[0]);
        let f = simd.evaluate_in_cell(cell, fraction.map(|v| v as f32));
        expect("Simd::evaluate_in_cell", f.distance[0].into(), f.id[0]);
        let period = Period::new([SMALL; D]).unwrap();
        let f = simd.evaluate_periodic(cells_x, &period);
        expect("Simd::evaluate_periodic", f.distance[0].into(), f.id[0]);

        // Eight lanes: the point in lane `i`, ordinary points elsewhere.
        for i in [0, 5] {
            let mut xs: [[f64; D]; 8] = std::array::from_fn(|l| std::array::from_fn(|a| (l * 3 + a) as f64 * 0.7));
            xs[i] = x;
            let f = simd.evaluate8(&xs);
            expect("Simd::evaluate8", f.distance[0].to_array()[i].into(), f.id[0].to_array()[i]);
            let lanes: [wide::f32x8; D] = std::array::from_fn(|a| wide::f32x8::new(xs.map(|p| p[a] as f32)));
            let f = simd.evaluate_lanes(lanes);
            expect("Simd::evaluate_lanes", f.distance[0].to_array()[i].into(), f.id[0].to_array()[i]);
            let mut cells = [[1i64; D]; 8];
            let mut fractions = [[0.25f32; D]; 8];
            cells[i] = cell;
            fractions[i] = fraction.map(|v| v as f32);
            let f = simd.evaluate8_in_cell(&cells, &fractions);
            expect("Simd::evaluate8_in_cell", f.distance[0].to_array()[i].into(), f.id[0].to_array()[i]);
            let mut periodic = xs.map(|p| p.map(|v| v * s));
            periodic[i] = cells_x;
            let f = simd.evaluate8_periodic(&periodic, &period);
            expect("Simd::evaluate8_periodic", f.distance[0].to_array()[i].into(), f.id[0].to_array()[i]);

            // Slices of f64 and f32 points, the point at index 8 + i.
            let mut many = vec![[0.5f64; D]; 19];
            many[8 + i] = x;
            let mut out = vec![simd.evaluate(x); 19];
            simd.evaluate_slice(&many, &mut out).unwrap();
            expect("Simd::evaluate_slice", out[8 + i].distance[0].into(), out[8 + i].id[0]);
            let many32: Vec<[f32; D]> = many.iter().map(|p| p.map(|v| v as f32)).collect();
            simd.evaluate_slice(&many32, &mut out).unwrap();
            expect("Simd::evaluate_slice (f32)", out[8 + i].distance[0].into(), out[8 + i].id[0]);
        }

        // A grid whose point 11 is the feature point (axis 0 fastest).
        let step = 1e-3 / s;
        let mut origin = x;
        origin[0] -= 11.0 * step;
        let grid = worley::Grid { origin, step: [step; D], size: std::array::from_fn(|a| if a == 0 { 16 } else { 1 }) };
        let mut out = vec![simd.evaluate(x); 16];
        simd.evaluate_grid(&grid, &mut out).unwrap();
        expect("Simd::evaluate_grid", out[11].distance[0].into(), out[11].id[0]);
        simd.evaluate_grid_parallel(&grid, &mut out).unwrap();
        expect("Simd::evaluate_grid_parallel", out[11].distance[0].into(), out[11].id[0]);
    }
}

#[test]
fn a_point_whose_id_state_is_the_sentinel_reports_the_documented_id() {
    for seed in [0, 7, u64::MAX] {
        check::<2>(seed);
        check::<3>(seed);
        check::<4>(seed);
    }
}
