//! Fuzz target: recording files (body: `aerie_sim_bridge::fuzzing::parse_recording`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_sim_bridge::fuzzing::parse_recording(data);
});
