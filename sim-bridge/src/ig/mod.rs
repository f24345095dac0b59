//! The image generator's side of a host session: what a CIGI host (or a native query sender)
//! set up, and what the IG says back once per IG frame.
//!
//! ```text
//! UDP thread: datagram ─► Ingest (pose, views) ─► IgLink::receive ─► IgSession (mode, entities,
//!             environment, pending requests)
//! frame loop: IgLink::begin_frame(frame, terrain) ─► Start of Frame + the answers due ─► host
//! ```
//!
//! - [`session`]: the pure state machine (no sockets, no clocks).
//! - [`requests`]: HAT/HOT and line-of-sight requests between arrival and answer.
//! - [`entities`]: the entity table and entity-relative points.
//! - [`environment`]: celestial (sun direction) and atmosphere (visibility).
//! - [`link`]: [`IgLink`], the session shared by the receiver thread and the frame loop.

mod cigi_map;
pub mod entities;
pub mod environment;
pub mod link;
pub mod requests;
pub mod session;
pub mod stats;

pub use link::IgLink;
pub use session::{
    CigiReply, DatabaseStatus, Datagram, FrameAnswers, IgConfig, IgFrame, IgSession, IgState,
};
pub use stats::IgStats;
