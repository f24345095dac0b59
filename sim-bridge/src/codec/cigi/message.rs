//! One host → IG message: its version and byte order from IG Control, then each packet in
//! turn — decoded, checked and counted.

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd};
use crate::pose::{Pose, PosePosition};

use super::control::{IgControl, StartOfFrame};
use super::counts::PacketCounts;
use super::entities::{ConformalClampedEntityControl, EntityControl, RateControl};
use super::environment::{AtmosphereControl, CelestialSphereControl};
use super::format::*;
use super::requests::{CigiRequest, HatHotRequest, LosSegmentRequest, LosVectorRequest};
use super::version::CigiVersion;
use super::view_packets::{ViewControl, ViewDefinition};

/// A well-formed packet whose values failed their checks (or whose enumerated field holds a
/// reserved value). It is left out of the message; the rest of the message stands.
#[derive(Clone, Debug, PartialEq)]
pub struct RejectedPacket {
    /// Its packet ID.
    pub packet_id: u8,
    /// Its byte offset in the message.
    pub offset: usize,
    /// The request ID (HAT/HOT ID, LOS ID) of a rejected request, so that it can still be
    /// answered as invalid.
    pub request_id: Option<u16>,
    /// The rejected request as decoded, when its fields could be read (a reserved request
    /// type cannot): its type tells which response answers it.
    pub request: Option<CigiRequest>,
    /// What is wrong, naming the field.
    pub error: DecodeError,
}

/// One host → IG message, as far as aerie reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct CigiMessage {
    /// The byte order the host wrote the message in.
    pub byte_order: ByteOrder,
    /// The CIGI version the host speaks (from IG Control); answers go out in it.
    pub version: CigiVersion,
    /// The IG Control packet that opens the message.
    pub ig_control: IgControl,
    /// The last Entity Control for the ownship (entity 0) in the message.
    pub ownship: Option<EntityControl>,
    /// Every Entity Control that passed its checks (the ownship's included), in message order.
    pub entities: Vec<EntityControl>,
    /// Conformal Clamped Entity Control packets, in message order.
    pub conformal_clamped: Vec<ConformalClampedEntityControl>,
    /// Rate Control packets, in message order.
    pub rate_controls: Vec<RateControl>,
    /// The last Celestial Sphere Control of the message.
    pub celestial: Option<CelestialSphereControl>,
    /// The last Atmosphere Control of the message.
    pub atmosphere: Option<AtmosphereControl>,
    /// View Control packets, in message order.
    pub view_controls: Vec<ViewControl>,
    /// View Definition packets, in message order.
    pub view_definitions: Vec<ViewDefinition>,
    /// HAT/HOT and line-of-sight requests that passed their checks, in message order.
    pub requests: Vec<CigiRequest>,
    /// Every packet of the message by packet ID (IG Control, rejected and unknown ones
    /// included).
    pub packet_counts: PacketCounts,
    /// Packets left out because a value failed its check.
    pub rejected: Vec<RejectedPacket>,
    /// Packets of IDs aerie does not read, skipped by their size byte.
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

    /// The host frame number's four low bits, as 3.2+ responses carry them.
    pub fn host_frame_lsn(&self) -> u8 {
        (self.ig_control.host_frame & 0x0F) as u8
    }

    /// A Start of Frame in Operate that names this message's host frame and database.
    pub fn start_of_frame(&self, ig_frame: u32, timestamp: u32) -> StartOfFrame {
        StartOfFrame {
            database: self.ig_control.database.max(0),
            ig_status: 0,
            ig_mode: IG_MODE_OPERATE,
            timestamp_valid: true,
            earth_reference_model: 0,
            ig_frame,
            timestamp,
            last_host_frame: self.ig_control.host_frame,
        }
    }

    /// [`start_of_frame`](Self::start_of_frame) encoded in the host's version and byte order.
    pub fn answer(&self, ig_frame: u32, timestamp: u32) -> Vec<u8> {
        self.start_of_frame(ig_frame, timestamp)
            .encode(self.version, self.byte_order)
    }

    fn reject(&mut self, packet_id: u8, offset: usize, e: DecodeError) {
        self.rejected.push(RejectedPacket {
            packet_id,
            offset,
            request_id: None,
            request: None,
            error: e,
        });
    }

    /// Files a decoded request, or rejects it keeping its ID (read apart from the packet's
    /// bytes when the request itself could not be decoded).
    fn take_request(
        &mut self,
        packet_id: u8,
        offset: usize,
        raw_id: Option<u16>,
        decoded: Result<CigiRequest, DecodeError>,
    ) {
        let (request, error) = match decoded {
            Ok(r) => match r.check() {
                Ok(()) => return self.requests.push(r),
                Err(e) => (Some(r), e),
            },
            Err(e) => (None, e),
        };
        self.rejected.push(RejectedPacket {
            packet_id,
            offset,
            request_id: request.map(|r| r.request_id()).or(raw_id),
            request,
            error,
        });
    }

    /// Decodes, checks and files one packet (the size already matched its ID's).
    fn take(&mut self, id: u8, off: usize, p: &[u8]) -> Result<(), DecodeError> {
        let (v, o) = (self.version, self.byte_order);
        // A request's ID is read apart so that an undecodable request can still be answered.
        let raw_id = Rd::new(p, o).u16(2);
        macro_rules! checked {
            ($decoded:expr, |$x:ident| $file:expr) => {
                match $decoded.and_then(|$x| $x.check().map(|()| $x)) {
                    Ok($x) => $file,
                    Err(e) => self.reject(id, off, e),
                }
            };
        }
        match id {
            ENTITY_CONTROL_ID => {
                expect_size(id, off, p, ENTITY_CONTROL_SIZE)?;
                let e = EntityControl::decode(p, v, o)?;
                if e.entity_id == OWNSHIP {
                    // The ownship is validated as a pose, and a bad one drops the message.
                    self.ownship = Some(e);
                    self.entities.push(e);
                } else {
                    checked!(Ok(e), |e| self.entities.push(e));
                }
            }
            CONFORMAL_CLAMPED_ENTITY_CONTROL_ID => {
                expect_size(id, off, p, CONFORMAL_CLAMPED_ENTITY_CONTROL_SIZE)?;
                checked!(ConformalClampedEntityControl::decode(p, o), |c| self
                    .conformal_clamped
                    .push(c));
            }
            RATE_CONTROL_ID => {
                expect_size(id, off, p, RATE_CONTROL_SIZE)?;
                checked!(RateControl::decode(p, v, o), |r| self.rate_controls.push(r));
            }
            CELESTIAL_SPHERE_CONTROL_ID => {
                expect_size(id, off, p, CELESTIAL_SPHERE_CONTROL_SIZE)?;
                checked!(CelestialSphereControl::decode(p, o), |c| self.celestial =
                    Some(c));
            }
            ATMOSPHERE_CONTROL_ID => {
                expect_size(id, off, p, ATMOSPHERE_CONTROL_SIZE)?;
                checked!(AtmosphereControl::decode(p, o), |a| self.atmosphere =
                    Some(a));
            }
            VIEW_CONTROL_ID => {
                expect_size(id, off, p, VIEW_CONTROL_SIZE)?;
                let c = ViewControl::decode(&Rd::new(p, o)).ok_or_else(cut)?;
                c.check()?;
                self.view_controls.push(c);
            }
            VIEW_DEFINITION_ID => {
                expect_size(id, off, p, VIEW_DEFINITION_SIZE)?;
                let d = ViewDefinition::decode(&Rd::new(p, o)).ok_or_else(cut)?;
                d.check()?;
                self.view_definitions.push(d);
            }
            HAT_HOT_REQUEST_ID => {
                expect_size(id, off, p, HAT_HOT_REQUEST_SIZE)?;
                self.take_request(
                    id,
                    off,
                    raw_id,
                    HatHotRequest::decode(p, v, o).map(CigiRequest::HatHot),
                );
            }
            LOS_SEGMENT_REQUEST_ID => {
                expect_size(id, off, p, LOS_SEGMENT_REQUEST_SIZE)?;
                self.take_request(
                    id,
                    off,
                    raw_id,
                    LosSegmentRequest::decode(p, v, o).map(CigiRequest::LosSegment),
                );
            }
            LOS_VECTOR_REQUEST_ID => {
                expect_size(id, off, p, LOS_VECTOR_REQUEST_SIZE)?;
                self.take_request(
                    id,
                    off,
                    raw_id,
                    LosVectorRequest::decode(p, v, o).map(CigiRequest::LosVector),
                );
            }
            IG_CONTROL_ID => self.reject(
                id,
                off,
                DecodeError::malformed(P, format!("a second IG Control at offset {off}")),
            ),
            _ => self.skipped += 1,
        }
        Ok(())
    }
}

/// Decodes a host → IG message of any CIGI 3.x minor version, in either byte order. The
/// message is dropped (an error naming the offset or field) when its IG Control or any
/// packet's framing is broken, when a known packet has the wrong size, when the ownship pose
/// or an enabled view value is invalid; a request, another entity or an environment packet
/// whose values fail their checks is left out and listed in [`CigiMessage::rejected`].
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
    if b.len() < usize::from(IG_CONTROL_SIZE_V3_0) {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: IG_CONTROL_SIZE_V3_0.into(),
        });
    }
    let Some(version) = CigiVersion::from_ig_control(b[1], b[4]) else {
        return Err(DecodeError::malformed(
            P,
            format!(
                "IG Control size byte is {}, expected 16 (CIGI 3.0/3.1) or 24 (3.2/3.3)",
                b[1]
            ),
        ));
    };
    let size = usize::from(version.ig_control_size());
    if b.len() < size {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: size,
        });
    }
    let order = byte_order(b)?;
    let mut msg = CigiMessage {
        byte_order: order,
        version,
        ig_control: IgControl::decode(&b[..size], version, order)?,
        ownship: None,
        entities: Vec::new(),
        conformal_clamped: Vec::new(),
        rate_controls: Vec::new(),
        celestial: None,
        atmosphere: None,
        view_controls: Vec::new(),
        view_definitions: Vec::new(),
        requests: Vec::new(),
        packet_counts: PacketCounts::default(),
        rejected: Vec::new(),
        skipped: 0,
    };
    msg.packet_counts.add(IG_CONTROL_ID);
    each_packet(b, size, |id, off, p| {
        msg.packet_counts.add(id);
        msg.take(id, off, p)
    })?;
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
