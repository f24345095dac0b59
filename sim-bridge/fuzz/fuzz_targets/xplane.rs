//! Fuzz target: X-Plane RPOS datagrams (body: `aerie_sim_bridge::fuzzing::decode_xplane`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aerie_sim_bridge::fuzzing::decode_xplane(data);
});
