//! Arbitrary bit patterns (NaN payloads, ±inf, subnormals, ±0, huge values)
//! and configurations through the reference kernel: no panic, no hang, and
//! either the documented invalid result or sorted, finite distances.
#![no_main]

use libfuzzer_sys::fuzz_target;
use worley::{Config, Metric, Mode, Reference, INVALID_ID};

fuzz_target!(|data: &[u8]| {
    if data.len() < 40 {
        return;
    }
    let word = |i: usize| u64::from_le_bytes(data[i * 8..i * 8 + 8].try_into().unwrap());
    let metric = match data[32] % 4 {
        0 => Metric::Euclidean,
        1 => Metric::Manhattan,
        2 => Metric::Chebyshev,
        _ => Metric::Minkowski(f64::from(data[33]) / 16.0),
    };
    let config = Config {
        seed: word(3),
        order: usize::from(data[34] % 20),
        metric,
        mode: if data[35] & 1 == 0 { Mode::Exact } else { Mode::Window },
        density: f64::from(data[36]) / 8.0,
        bump: f64::from(data[37]) / 200.0,
    };
    let Ok(basis) = Reference::<3>::new(config) else {
        assert!(config.validate().is_err());
        return;
    };
    let x = [f64::from_bits(word(0)), f64::from_bits(word(1)), f64::from_bits(word(2))];
    let f = basis.evaluate(x);
    if basis.pattern().locate(x).is_none() {
        assert!(f.distance[0].is_nan() && f.id[0] == INVALID_ID);
        return;
    }
    for k in 1..config.order {
        assert!(f.distance[k - 1] <= f.distance[k] || f.distance[k].is_nan());
    }
});
