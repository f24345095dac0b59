//! Fuzz target: `store` (body: `aerie_fuzz::bodies::store`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_fuzz::bodies::store(data);
});
