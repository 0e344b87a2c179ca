//! See [`worley_harness::fuzz::filtered`] for what this target decodes and asserts.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| worley_harness::fuzz::filtered(data));
