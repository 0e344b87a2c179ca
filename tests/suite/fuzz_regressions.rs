//! The fuzz targets' checks on stable: every input kept under
//! `fuzz/regressions/`, both the named files in `<target>/` (inputs that once
//! failed) and `<target>.hex`, the fuzzers' minimised corpus, one input per
//! line in hex; then a few thousand seeded random byte strings.

use std::path::Path;
use worley_harness::{fuzz, Tier};

type Check = fn(&[u8]);

const TARGETS: [(&str, Check); 6] = [
    ("differential", fuzz::differential),
    ("continuity", fuzz::continuity),
    ("bad_input", fuzz::bad_input),
    ("config", fuzz::config),
    ("border", fuzz::border),
    ("filtered", fuzz::filtered),
];

/// Every input kept for `target`: the named files in its folder, where it
/// has one, then its minimised corpus, which every target has. One test per
/// target, so that the test threads share the replays.
fn replay(target: &str, check: Check) {
    let mut replayed = 0;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions").join(target);
    for entry in std::fs::read_dir(&dir).into_iter().flatten() {
        let path = entry.unwrap().path();
        if path.is_file() && path.extension().is_none_or(|e| e != "md") {
            let data = std::fs::read(&path).unwrap();
            if std::panic::catch_unwind(|| check(&data)).is_err() {
                panic!("{target}: {} fails", path.display());
            }
            replayed += 1;
        }
    }
    let hex = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("fuzz/regressions/{target}.hex"));
    let text = std::fs::read_to_string(&hex).unwrap_or_else(|e| panic!("{}: {e}", hex.display()));
    assert!(text.lines().count() > 0, "{}: no inputs", hex.display());
    for (line, input) in text.lines().enumerate() {
        let data: Vec<u8> = (0..input.len() / 2)
            .map(|i| u8::from_str_radix(&input[2 * i..2 * i + 2], 16).expect("hex digits"))
            .collect();
        if std::panic::catch_unwind(|| check(&data)).is_err() {
            panic!("{target}: line {} of {} fails", line + 1, hex.display());
        }
        replayed += 1;
    }
    println!("{target}: replayed {replayed} kept inputs");
}

/// One test per fuzz target replaying its kept inputs.
macro_rules! kept_inputs {
    ($($test:ident: $target:literal),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                let (_, check) = TARGETS.iter().find(|(t, _)| *t == $target).expect("a target of TARGETS");
                replay($target, *check);
            }
        )*
        /// Every target of [`TARGETS`] has its test above.
        #[test]
        fn every_target_replays_its_kept_inputs() {
            let tested = [$($target),*];
            for (target, _) in TARGETS {
                assert!(tested.contains(&target), "{target} has no replay test");
            }
        }
    };
}

kept_inputs!(
    kept_differential_inputs_replay_cleanly: "differential",
    kept_continuity_inputs_replay_cleanly: "continuity",
    kept_bad_input_inputs_replay_cleanly: "bad_input",
    kept_config_inputs_replay_cleanly: "config",
    kept_border_inputs_replay_cleanly: "border",
    kept_filtered_inputs_replay_cleanly: "filtered",
);

/// 3000 seeded byte strings per target in the whole campaign.
fn seeded(tier: Tier) {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    for (target, check) in TARGETS {
        for case in 0..tier.of(3000) {
            let len = (next() % 160) as usize;
            let data: Vec<u8> = (0..len).map(|_| next() as u8).collect();
            if std::panic::catch_unwind(|| check(&data)).is_err() {
                panic!("{target}: seeded case {case} fails: {data:?}");
            }
        }
    }
}

worley_harness::tiered!(seeded_random_inputs_pass_every_check, campaign_seeded_random_inputs_pass_every_check, seeded);
