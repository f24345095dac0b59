//! Fuzz target: auto-detected datagrams through the whole ingest path (body: `aerie_sim_bridge::fuzzing::decode_auto`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_sim_bridge::fuzzing::decode_auto(data);
});
