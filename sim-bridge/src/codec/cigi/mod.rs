//! CIGI 3.0–3.3 (Common Image Generator Interface, SISO-STD-013), the IG side: host → IG
//! messages decoded, checked and counted; the IG's answers encoded in the host's minor version
//! and byte order. Every layout is taken from the CIGI Class Library's Pack/Unpack code
//! (`../shared/tools/cigi-ccl`, cited on each packet).
//!
//! Read (host → IG): **IG Control** (1; 16 bytes in 3.0/3.1, 24 in 3.2/3.3 — the version is
//! read from it, [`CigiVersion`]), **Entity Control** (2, every entity), **Conformal Clamped
//! Entity Control** (3), **Rate Control** (8), **Celestial Sphere Control** (9), **Atmosphere
//! Control** (10), **View Control** (16) and **View Definition** (21) — kept as per-view
//! records ([`ViewTable`]) — and the terrain requests **HAT/HOT Request** (24), **Line of
//! Sight Segment Request** (25) and **Line of Sight Vector Request** (26). Every other packet
//! is skipped by its size byte; all are counted per ID ([`PacketCounts`]).
//!
//! Written (IG → host): **Start of Frame** (101), **HAT/HOT Response** (102), **HAT/HOT
//! Extended Response** (103), **Line of Sight Response** (104), **Line of Sight Extended
//! Response** (105) ([`CigiResponse`]); [`decode_ig_message`] reads them back as a host does.
//! Field tables: `sim-bridge/PROTOCOL.md`.

mod control;
mod counts;
mod entities;
mod environment;
mod format;
mod ig_message;
mod message;
mod requests;
mod responses;
mod version;
mod view_packets;
mod views;

pub use control::{IgControl, IgMode, StartOfFrame};
pub use counts::{packet_name, PacketCounts};
pub use entities::{ConformalClampedEntityControl, EntityControl, RateControl, RateFrame};
pub use environment::{AtmosphereControl, CelestialSphereControl};
pub use format::{
    ATMOSPHERE_CONTROL_ID, ATMOSPHERE_CONTROL_SIZE, BYTE_SWAP_MAGIC, CELESTIAL_SPHERE_CONTROL_ID,
    CELESTIAL_SPHERE_CONTROL_SIZE, CONFORMAL_CLAMPED_ENTITY_CONTROL_ID,
    CONFORMAL_CLAMPED_ENTITY_CONTROL_SIZE, ENTITY_CONTROL_ID, ENTITY_CONTROL_SIZE,
    HAT_HOT_EXTENDED_RESPONSE_ID, HAT_HOT_EXTENDED_RESPONSE_SIZE, HAT_HOT_REQUEST_ID,
    HAT_HOT_REQUEST_SIZE, HAT_HOT_RESPONSE_ID, HAT_HOT_RESPONSE_SIZE, IG_CONTROL_ID,
    IG_CONTROL_SIZE, IG_CONTROL_SIZE_V3_0, IG_MODE_OPERATE, IG_MODE_STANDBY,
    LOS_EXTENDED_RESPONSE_ID, LOS_EXTENDED_RESPONSE_SIZE, LOS_RESPONSE_ID, LOS_RESPONSE_SIZE,
    LOS_SEGMENT_REQUEST_ID, LOS_SEGMENT_REQUEST_SIZE, LOS_VECTOR_REQUEST_ID,
    LOS_VECTOR_REQUEST_SIZE, MAJOR_VERSION, MAX_VIEWS, MINOR_VERSION, OWNSHIP, RATE_CONTROL_ID,
    RATE_CONTROL_SIZE, START_OF_FRAME_ID, START_OF_FRAME_SIZE, START_OF_FRAME_SIZE_V3_0,
    VIEW_CONTROL_ID, VIEW_CONTROL_SIZE, VIEW_DEFINITION_ID, VIEW_DEFINITION_SIZE,
};
pub use ig_message::{decode_ig_message, IgMessage};
pub use message::{decode, CigiMessage, RejectedPacket};
pub use requests::{
    CigiRequest, CoordinateSystem, HatHotRequest, HatHotRequestType, LosRequestType,
    LosSegmentRequest, LosVectorRequest,
};
pub use responses::{
    CigiResponse, HatHotExtendedResponse, HatHotResponse, HatHotResponseType, LosExtendedResponse,
    LosResponse,
};
pub use version::CigiVersion;
pub use view_packets::{fov_enable, view_enable, ViewControl, ViewDefinition};
pub use views::{ViewRecord, ViewTable};

#[cfg(test)]
mod tests;
