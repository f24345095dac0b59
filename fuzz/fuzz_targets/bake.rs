//! Fuzz target: `bake` (body: `aerie_fuzz::bodies::bake`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_fuzz::bodies::bake(data);
});
