//! Fuzz target: byte copies of the shared-memory pose file (body: `aerie_sim_bridge::fuzzing::decode_shm`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_sim_bridge::fuzzing::decode_shm(data);
});
