//! The cell hash against the uniform-hash expectation: no repeated strips
//! of cells (rows, pencils, planes) and the chance number of equal cells, for
//! several seeds and every dimension; and the count shown to catch a hash
//! whose axis terms enter the chain unmixed, as the crate's did before.

use worley::definition::{axis_term, cell_hash, fmix32, SeedKeys, AXIS_MUL};
use worley_harness::repeats::{repeated_runs, Repeats};
use worley_harness::Tier;

/// About 4·10^6 cells per dimension.
fn side(dim: usize) -> i64 {
    match dim {
        2 => 2048,
        3 => 160,
        _ => 45,
    }
}

fn assert_uniform(r: &Repeats, what: &str) {
    assert_eq!(r.equal_runs, 0, "{what}: {r:?} (a uniform hash gives {:.1e})", r.expected_equal_runs);
    // Equal cells are a Poisson count: within six standard deviations.
    let (got, want) = (r.equal_cells as f64, r.expected_equal_cells);
    assert!((got - want).abs() < 6.0 * want.sqrt() + 3.0, "{what}: {r:?}");
}

fn check<const D: usize>(seed: u64) {
    let keys = SeedKeys::new(seed);
    let r = repeated_runs::<D>(side(D), |c| cell_hash(keys, c));
    eprintln!("{D}D seed {seed}: {r:?}");
    assert_uniform(&r, &format!("{D}D seed {seed}"));
}

/// Six seeds in the whole campaign, the first in the quick tier.
fn strips(tier: Tier) {
    let seeds = [0, 1, 2, 3, 0xDEAD_BEEF, u64::MAX];
    for seed in &seeds[..tier.of(seeds.len())] {
        check::<2>(*seed);
        check::<3>(*seed);
        check::<4>(*seed);
    }
}

worley_harness::tiered!(
    no_repeated_strips_for_any_seed_or_dimension,
    campaign_no_repeated_strips_for_any_seed_or_dimension,
    strips
);

/// The hash as it was before axis words and their sum: each raw term xored
/// into the chain.
fn unmixed<const D: usize>(keys: SeedKeys, cell: [i64; D]) -> u32 {
    let mut h = keys.init;
    for (c, m) in cell.into_iter().zip(AXIS_MUL) {
        h = (h ^ axis_term(c)).wrapping_mul(m);
        h ^= h >> 16;
    }
    fmix32(h ^ keys.finish)
}

#[test]
fn the_count_catches_unmixed_terms() {
    // 3D, seed 0: pencils along axis 2 whose chains differ by a small xor δ
    // hold the same points at c2 and c2 ^ δ.
    let keys = SeedKeys::new(0);
    let r = repeated_runs::<3>(side(3), |c| unmixed(keys, c));
    eprintln!("unmixed terms, 3D seed 0: {r:?}");
    assert!(r.equal_runs > 100, "{r:?}");
}
