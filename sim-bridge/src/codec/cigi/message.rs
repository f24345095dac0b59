//! One host → IG message: its byte order, then each packet in turn.

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd};
use crate::pose::{Pose, PosePosition};

use super::format::*;
use super::packets::*;

/// One host → IG message, as far as aerie reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct CigiMessage {
    /// The byte order the host wrote the message in.
    pub byte_order: ByteOrder,
    /// The IG Control packet that opens the message.
    pub ig_control: IgControl,
    /// The last Entity Control for the ownship (entity 0) in the message.
    pub ownship: Option<EntityControl>,
    /// View Control packets, in message order.
    pub view_controls: Vec<ViewControl>,
    /// View Definition packets, in message order.
    pub view_definitions: Vec<ViewDefinition>,
    /// Packets skipped by their size byte (other entities, other packet types).
    pub skipped: u32,
}

impl CigiMessage {
    /// The ownship pose: CIGI yaw/pitch/roll become heading/pitch/roll; the sim time is the
    /// IG Control timestamp (10 µs ticks) when valid, else 0; the frame is the host frame.
    pub fn ownship_pose(&self) -> Option<Pose> {
        self.ownship.map(|e| Pose {
            position: PosePosition::Geodetic {
                lat_deg: e.lat_deg,
                lon_deg: e.lon_deg,
                alt_m: e.alt_m,
            },
            attitude_deg: [e.yaw_deg.into(), e.pitch_deg.into(), e.roll_deg.into()],
            sim_time_s: if self.ig_control.timestamp_valid {
                f64::from(self.ig_control.timestamp) * 1e-5
            } else {
                0.0
            },
            frame: self.ig_control.host_frame.into(),
            velocity_enu: None,
            angular_rates_deg_s: None,
        })
    }

    /// The Start of Frame that answers this message, in the host's byte order.
    pub fn answer(&self, ig_frame: u32, timestamp: u32) -> [u8; START_OF_FRAME_SIZE as usize] {
        StartOfFrame {
            database: self.ig_control.database.max(0),
            ig_status: 0,
            ig_mode: IG_MODE_OPERATE,
            timestamp_valid: true,
            earth_reference_model: 0,
            minor_version: MINOR_VERSION,
            ig_frame,
            timestamp,
            last_host_frame: self.ig_control.host_frame,
        }
        .encode(self.byte_order)
    }
}

/// Decodes a host → IG message; validates the ownship pose and every enabled view value.
pub fn decode(b: &[u8]) -> Result<CigiMessage, DecodeError> {
    if b.first() != Some(&IG_CONTROL_ID) {
        return Err(DecodeError::malformed(
            P,
            "a CIGI message starts with IG Control (packet 1)",
        ));
    }
    if let Some(&v) = b.get(2) {
        if v != MAJOR_VERSION {
            return Err(DecodeError::BadVersion {
                protocol: P,
                found: v.into(),
                expected: MAJOR_VERSION.into(),
            });
        }
    }
    if b.len() < IG_CONTROL_SIZE as usize {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: IG_CONTROL_SIZE.into(),
        });
    }
    if b[1] != IG_CONTROL_SIZE {
        return Err(DecodeError::malformed(
            P,
            format!("IG Control size byte is {}, expected 24", b[1]),
        ));
    }
    let order = byte_order(b)?;
    let mut msg = CigiMessage {
        byte_order: order,
        ig_control: IgControl::decode(&Rd::new(b, order)).ok_or_else(cut)?,
        ownship: None,
        view_controls: Vec::new(),
        view_definitions: Vec::new(),
        skipped: 0,
    };
    let mut off = IG_CONTROL_SIZE as usize;
    while off < b.len() {
        let (id, size) = match b.get(off..off + 2) {
            Some(&[id, size]) => (id, usize::from(size)),
            _ => {
                return Err(DecodeError::malformed(
                    P,
                    format!("packet header cut at offset {off}"),
                ))
            }
        };
        if size < 2 {
            return Err(DecodeError::malformed(
                P,
                format!("packet {id} at offset {off} has size {size}"),
            ));
        }
        let Some(p) = b.get(off..off + size) else {
            return Err(DecodeError::malformed(
                P,
                format!(
                    "packet {id} at offset {off} (size {size}) runs past the end ({} bytes)",
                    b.len()
                ),
            ));
        };
        let expect = |want: u8| -> Result<Rd, DecodeError> {
            if size == usize::from(want) {
                Ok(Rd::new(p, order))
            } else {
                Err(DecodeError::malformed(
                    P,
                    format!("packet {id} at offset {off} has size {size}, expected {want}"),
                ))
            }
        };
        match id {
            ENTITY_CONTROL_ID => {
                let e = EntityControl::decode(&expect(ENTITY_CONTROL_SIZE)?).ok_or_else(cut)?;
                if e.entity_id == OWNSHIP {
                    msg.ownship = Some(e);
                } else {
                    msg.skipped += 1;
                }
            }
            VIEW_CONTROL_ID => {
                let v = ViewControl::decode(&expect(VIEW_CONTROL_SIZE)?).ok_or_else(cut)?;
                v.check()?;
                msg.view_controls.push(v);
            }
            VIEW_DEFINITION_ID => {
                let v = ViewDefinition::decode(&expect(VIEW_DEFINITION_SIZE)?).ok_or_else(cut)?;
                v.check()?;
                msg.view_definitions.push(v);
            }
            _ => msg.skipped += 1,
        }
        off += size;
    }
    if let Some(e) = msg.ownship {
        if e.attached {
            return Err(DecodeError::Unsupported {
                protocol: P,
                what: "ownship attached to a parent entity",
            });
        }
    }
    if let Some(pose) = msg.ownship_pose() {
        crate::codec::protocol::validated(P, pose)?;
    }
    Ok(msg)
}
