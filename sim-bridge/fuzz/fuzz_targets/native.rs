//! Fuzz target: aerie native v1 datagrams (body: `aerie_sim_bridge::fuzzing::decode_native`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_sim_bridge::fuzzing::decode_native(data);
});
