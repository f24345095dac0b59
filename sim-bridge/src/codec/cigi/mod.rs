//! CIGI 3.3 (Common Image Generator Interface, SISO-STD-013), the host → IG subset aerie reads:
//!
//! - **IG Control** (packet 1, 24 bytes) — always the first packet of a host message; carries the
//!   host frame counter and the byte-swap magic `0x8000` (the message is in the host's byte
//!   order: bytes `80 00` at offset 6 mean big-endian, `00 80` little-endian);
//! - **Entity Control** (packet 2, 48 bytes) — entity 0 is the ownship: lat/lon/alt f64,
//!   roll/pitch/yaw f32, degrees and metres;
//! - **View Control** (16, 32 bytes) and **View Definition** (21, 32 bytes) — kept as per-view
//!   records ([`ViewTable`]) for the renderer's channels;
//! - every other packet is skipped by its size byte.
//!
//! The IG answers each host message with a **Start of Frame** (packet 101, 24 bytes), encoded by
//! [`StartOfFrame::encode`]. Field tables: `sim-bridge/PROTOCOL.md`.

mod format;
mod message;
mod packets;
mod views;

pub use format::{
    BYTE_SWAP_MAGIC, ENTITY_CONTROL_ID, ENTITY_CONTROL_SIZE, IG_CONTROL_ID, IG_CONTROL_SIZE,
    IG_MODE_OPERATE, MAJOR_VERSION, MAX_VIEWS, MINOR_VERSION, OWNSHIP, START_OF_FRAME_ID,
    START_OF_FRAME_SIZE, VIEW_CONTROL_ID, VIEW_CONTROL_SIZE, VIEW_DEFINITION_ID,
    VIEW_DEFINITION_SIZE,
};
pub use message::{decode, CigiMessage};
pub use packets::{
    fov_enable, view_enable, EntityControl, IgControl, StartOfFrame, ViewControl, ViewDefinition,
};
pub use views::{ViewRecord, ViewTable};

#[cfg(test)]
mod tests;
