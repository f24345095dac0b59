//! Fuzz target: `dem` (body: `aerie_fuzz::bodies::dem`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_fuzz::bodies::dem(data);
});
