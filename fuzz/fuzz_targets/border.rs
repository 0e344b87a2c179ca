//! See [`worley_harness::fuzz::border`] for what this target decodes and asserts.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| worley_harness::fuzz::border(data));
