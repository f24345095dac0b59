//! Fuzz target: CIGI 3.3 host messages (body: `aerie_sim_bridge::fuzzing::decode_cigi`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_sim_bridge::fuzzing::decode_cigi(data);
});
