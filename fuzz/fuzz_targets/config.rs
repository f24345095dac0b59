//! Fuzz target: `config` (body: `aerie_fuzz::bodies::config`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_fuzz::bodies::config(data);
});
