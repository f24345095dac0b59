//! The CIGI host test kit: the host program written with the CIGI Class Library
//! (`tests/cigi-host/`, built on demand into a cache), its JSON-lines output, and the
//! independent references the answers are checked against (the SRTM samples read here, the
//! geodetic ↔ grid mapping restated).

mod output;
mod program;
mod reference;
mod run;
mod srtm;

pub use output::HostOutput;
pub use program::{ccl_source_dir, host_program, Arch, HostProgram};
pub use reference::{entity_relative, normal_az_el, terrain, Terrain};
pub use run::{angle_diff, f, ig_run, IgRun, Problems};
pub use srtm::{Bilinear, Srtm};
