//! One IG → host message (Start of Frame, then answers), decoded as a host reads it: for
//! tests, `aerie-send` and hosts written against aerie.

use crate::codec::protocol::DecodeError;
use crate::codec::wire::ByteOrder;

use super::control::StartOfFrame;
use super::counts::PacketCounts;
use super::format::*;
use super::responses::CigiResponse;
use super::version::CigiVersion;

/// An IG → host message.
#[derive(Clone, Debug, PartialEq)]
pub struct IgMessage {
    /// The byte order the IG wrote it in.
    pub byte_order: ByteOrder,
    /// The version its Start of Frame declares (16 bytes: 3.0/3.1, read as 3.0).
    pub version: CigiVersion,
    /// The Start of Frame that opens it.
    pub start_of_frame: StartOfFrame,
    /// HAT/HOT and line-of-sight responses, in message order.
    pub responses: Vec<CigiResponse>,
    /// Every packet by ID (Start of Frame included).
    pub packet_counts: PacketCounts,
    /// Packets of other IDs, skipped by their size byte.
    pub skipped: u32,
}

/// Decodes an IG → host message; any broken framing or response is an error naming it.
pub fn decode_ig_message(b: &[u8]) -> Result<IgMessage, DecodeError> {
    let (start_of_frame, version, byte_order) = StartOfFrame::decode_with_version(b)?;
    let mut msg = IgMessage {
        byte_order,
        version,
        start_of_frame,
        responses: Vec::new(),
        packet_counts: PacketCounts::default(),
        skipped: 0,
    };
    msg.packet_counts.add(START_OF_FRAME_ID);
    let start = usize::from(version.start_of_frame_size());
    each_packet(b, start, |id, _, p| {
        msg.packet_counts.add(id);
        match CigiResponse::decode(p, version, byte_order) {
            Some(r) => msg.responses.push(r?),
            None => msg.skipped += 1,
        }
        Ok(())
    })?;
    Ok(msg)
}
