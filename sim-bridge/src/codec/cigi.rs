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

use super::wire::{ByteOrder, Rd, Wr};
use super::{DecodeError, Protocol};
use crate::pose::{Pose, PoseError, PosePosition};

/// IG Control packet ID.
pub const IG_CONTROL_ID: u8 = 1;
/// IG Control size in bytes.
pub const IG_CONTROL_SIZE: u8 = 24;
/// Entity Control packet ID.
pub const ENTITY_CONTROL_ID: u8 = 2;
/// Entity Control size in bytes.
pub const ENTITY_CONTROL_SIZE: u8 = 48;
/// View Control packet ID.
pub const VIEW_CONTROL_ID: u8 = 16;
/// View Control size in bytes.
pub const VIEW_CONTROL_SIZE: u8 = 32;
/// View Definition packet ID.
pub const VIEW_DEFINITION_ID: u8 = 21;
/// View Definition size in bytes.
pub const VIEW_DEFINITION_SIZE: u8 = 32;
/// Start of Frame packet ID (IG → host).
pub const START_OF_FRAME_ID: u8 = 101;
/// Start of Frame size in bytes.
pub const START_OF_FRAME_SIZE: u8 = 24;
/// CIGI major version read here.
pub const MAJOR_VERSION: u8 = 3;
/// CIGI minor version written in Start of Frame (3.3).
pub const MINOR_VERSION: u8 = 3;
/// The byte-swap magic as written by the sender in its own byte order.
pub const BYTE_SWAP_MAGIC: u16 = 0x8000;
/// Entity ID of the ownship.
pub const OWNSHIP: u16 = 0;
/// At most this many distinct views are tracked; packets for further view IDs are ignored.
pub const MAX_VIEWS: usize = 64;
/// IG mode value "Operate".
pub const IG_MODE_OPERATE: u8 = 1;

const P: Protocol = Protocol::Cigi;

fn cut() -> DecodeError {
    DecodeError::truncated(P)
}

fn finite32(field: &'static str, v: f32) -> Result<(), DecodeError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(DecodeError::Invalid {
            protocol: P,
            error: PoseError::NotFinite {
                field,
                value: v.into(),
            },
        })
    }
}

/// IG Control (packet 1).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IgControl {
    /// Database number (signed; 0 = no change).
    pub database: i8,
    /// IG mode (0 Reset/Standby, 1 Operate, 2 Debug, 3 Offline Maintenance).
    pub ig_mode: u8,
    /// Timestamp field is valid.
    pub timestamp_valid: bool,
    /// Extrapolation/interpolation (smoothing) enable.
    pub smoothing: bool,
    /// CIGI minor version (upper nibble of byte 4).
    pub minor_version: u8,
    /// Host frame counter.
    pub host_frame: u32,
    /// Host timestamp, 10 µs ticks.
    pub timestamp: u32,
    /// The last IG frame number the host received.
    pub last_ig_frame: u32,
}

impl IgControl {
    /// Encodes the packet in `order` (host side; used by tests and the example sender).
    pub fn encode(&self, order: ByteOrder) -> [u8; IG_CONTROL_SIZE as usize] {
        let mut w = Wr::new(order, IG_CONTROL_SIZE.into());
        let flags = ((self.minor_version & 0x0F) << 4)
            | (u8::from(self.smoothing) << 3)
            | (u8::from(self.timestamp_valid) << 2)
            | (self.ig_mode & 0x03);
        w.u8(IG_CONTROL_ID)
            .u8(IG_CONTROL_SIZE)
            .u8(MAJOR_VERSION)
            .u8(self.database as u8)
            .u8(flags)
            .u8(0)
            .u16(BYTE_SWAP_MAGIC)
            .u32(self.host_frame)
            .u32(self.timestamp)
            .u32(self.last_ig_frame)
            .u32(0);
        w.finish()
    }

    fn decode(r: &Rd) -> Option<Self> {
        let flags = r.u8(4)?;
        Some(Self {
            database: r.u8(3)? as i8,
            ig_mode: flags & 0x03,
            timestamp_valid: flags & 0x04 != 0,
            smoothing: flags & 0x08 != 0,
            minor_version: flags >> 4,
            host_frame: r.u32(8)?,
            timestamp: r.u32(12)?,
            last_ig_frame: r.u32(16)?,
        })
    }
}

/// Entity Control (packet 2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EntityControl {
    /// Entity ID (0 = ownship).
    pub entity_id: u16,
    /// Entity state (0 inactive/standby, 1 active, 2 destroyed).
    pub entity_state: u8,
    /// Attached to a parent entity (position is then an offset; unsupported for the ownship).
    pub attached: bool,
    /// Byte 4 bits 3..7 (collision detection, inherit alpha, ground clamp), kept raw.
    pub flags_hi: u8,
    /// Byte 5 (animation direction/loop/state, smoothing), kept raw.
    pub animation_flags: u8,
    /// Alpha (0 transparent … 255 opaque).
    pub alpha: u8,
    /// Entity type.
    pub entity_type: u16,
    /// Parent entity ID.
    pub parent_id: u16,
    /// Roll, degrees (−180 … 180).
    pub roll_deg: f32,
    /// Pitch, degrees (−90 … 90).
    pub pitch_deg: f32,
    /// Yaw (true heading), degrees (0 … 360).
    pub yaw_deg: f32,
    /// Latitude, degrees (or X offset when attached).
    pub lat_deg: f64,
    /// Longitude, degrees (or Y offset when attached).
    pub lon_deg: f64,
    /// Altitude above mean sea level, metres (or Z offset when attached).
    pub alt_m: f64,
}

impl EntityControl {
    /// Encodes the packet in `order`.
    pub fn encode(&self, order: ByteOrder) -> [u8; ENTITY_CONTROL_SIZE as usize] {
        let mut w = Wr::new(order, ENTITY_CONTROL_SIZE.into());
        let b4 =
            (self.entity_state & 0x03) | (u8::from(self.attached) << 2) | (self.flags_hi & 0xF8);
        w.u8(ENTITY_CONTROL_ID)
            .u8(ENTITY_CONTROL_SIZE)
            .u16(self.entity_id)
            .u8(b4)
            .u8(self.animation_flags)
            .u8(self.alpha)
            .u8(0)
            .u16(self.entity_type)
            .u16(self.parent_id)
            .f32(self.roll_deg)
            .f32(self.pitch_deg)
            .f32(self.yaw_deg)
            .f64(self.lat_deg)
            .f64(self.lon_deg)
            .f64(self.alt_m);
        w.finish()
    }

    fn decode(r: &Rd) -> Option<Self> {
        let b4 = r.u8(4)?;
        Some(Self {
            entity_id: r.u16(2)?,
            entity_state: b4 & 0x03,
            attached: b4 & 0x04 != 0,
            flags_hi: b4 & 0xF8,
            animation_flags: r.u8(5)?,
            alpha: r.u8(6)?,
            entity_type: r.u16(8)?,
            parent_id: r.u16(10)?,
            roll_deg: r.f32(12)?,
            pitch_deg: r.f32(16)?,
            yaw_deg: r.f32(20)?,
            lat_deg: r.f64(24)?,
            lon_deg: r.f64(32)?,
            alt_m: r.f64(40)?,
        })
    }
}

/// View Control enable bits (byte 5).
pub mod view_enable {
    /// X offset enable.
    pub const X: u8 = 1 << 0;
    /// Y offset enable.
    pub const Y: u8 = 1 << 1;
    /// Z offset enable.
    pub const Z: u8 = 1 << 2;
    /// Roll enable.
    pub const ROLL: u8 = 1 << 3;
    /// Pitch enable.
    pub const PITCH: u8 = 1 << 4;
    /// Yaw enable.
    pub const YAW: u8 = 1 << 5;
}

/// View Definition enable bits (byte 5, bits 0..5; bits 6..7 are the mirror mode).
pub mod fov_enable {
    /// Near enable.
    pub const NEAR: u8 = 1 << 0;
    /// Far enable.
    pub const FAR: u8 = 1 << 1;
    /// Left enable.
    pub const LEFT: u8 = 1 << 2;
    /// Right enable.
    pub const RIGHT: u8 = 1 << 3;
    /// Top enable.
    pub const TOP: u8 = 1 << 4;
    /// Bottom enable.
    pub const BOTTOM: u8 = 1 << 5;
}

/// View Control (packet 16): a view's eye offset and rotation relative to an entity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewControl {
    /// View ID.
    pub view_id: u16,
    /// View group ID.
    pub group_id: u8,
    /// Which fields apply ([`view_enable`] bits); disabled fields keep their previous value.
    pub enable: u8,
    /// Entity the view is attached to.
    pub entity_id: u16,
    /// X (forward), Y (right), Z (down) offset from the entity's reference point, metres.
    pub offset_m: [f32; 3],
    /// Roll, pitch, yaw relative to the entity, degrees.
    pub roll_pitch_yaw_deg: [f32; 3],
}

impl ViewControl {
    /// Encodes the packet in `order`.
    pub fn encode(&self, order: ByteOrder) -> [u8; VIEW_CONTROL_SIZE as usize] {
        let mut w = Wr::new(order, VIEW_CONTROL_SIZE.into());
        w.u8(VIEW_CONTROL_ID)
            .u8(VIEW_CONTROL_SIZE)
            .u16(self.view_id)
            .u8(self.group_id)
            .u8(self.enable & 0x3F)
            .u16(self.entity_id);
        for v in self.offset_m.iter().chain(&self.roll_pitch_yaw_deg) {
            w.f32(*v);
        }
        w.finish()
    }

    fn decode(r: &Rd) -> Option<Self> {
        Some(Self {
            view_id: r.u16(2)?,
            group_id: r.u8(4)?,
            enable: r.u8(5)? & 0x3F,
            entity_id: r.u16(6)?,
            offset_m: [r.f32(8)?, r.f32(12)?, r.f32(16)?],
            roll_pitch_yaw_deg: [r.f32(20)?, r.f32(24)?, r.f32(28)?],
        })
    }

    fn check(&self) -> Result<(), DecodeError> {
        const NAMES: [&str; 6] = [
            "view_control.x_offset",
            "view_control.y_offset",
            "view_control.z_offset",
            "view_control.roll",
            "view_control.pitch",
            "view_control.yaw",
        ];
        for (i, v) in self
            .offset_m
            .iter()
            .chain(&self.roll_pitch_yaw_deg)
            .enumerate()
        {
            if self.enable & (1 << i) != 0 {
                finite32(NAMES[i], *v)?;
            }
        }
        Ok(())
    }
}

/// View Definition (packet 21): a view's frustum.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewDefinition {
    /// View ID.
    pub view_id: u16,
    /// View group ID.
    pub group_id: u8,
    /// Which frustum fields apply ([`fov_enable`] bits).
    pub enable: u8,
    /// Mirror mode (0 none, 1 horizontal, 2 vertical, 3 both).
    pub mirror_mode: u8,
    /// Pixel replication mode (0..7).
    pub pixel_replication: u8,
    /// Orthographic projection (else perspective).
    pub orthographic: bool,
    /// Reorder (bring this view's window to the top).
    pub reorder: bool,
    /// View type (0..7, IG defined).
    pub view_type: u8,
    /// Near clipping distance, metres.
    pub near_m: f32,
    /// Far clipping distance, metres.
    pub far_m: f32,
    /// Left half-angle, degrees (negative left of the view axis).
    pub left_deg: f32,
    /// Right half-angle, degrees.
    pub right_deg: f32,
    /// Top half-angle, degrees.
    pub top_deg: f32,
    /// Bottom half-angle, degrees (negative below the view axis).
    pub bottom_deg: f32,
}

impl ViewDefinition {
    /// Encodes the packet in `order`.
    pub fn encode(&self, order: ByteOrder) -> [u8; VIEW_DEFINITION_SIZE as usize] {
        let mut w = Wr::new(order, VIEW_DEFINITION_SIZE.into());
        let b5 = (self.enable & 0x3F) | ((self.mirror_mode & 0x03) << 6);
        let b6 = (self.pixel_replication & 0x07)
            | (u8::from(self.orthographic) << 3)
            | (u8::from(self.reorder) << 4)
            | ((self.view_type & 0x07) << 5);
        w.u8(VIEW_DEFINITION_ID)
            .u8(VIEW_DEFINITION_SIZE)
            .u16(self.view_id)
            .u8(self.group_id)
            .u8(b5)
            .u8(b6)
            .u8(0);
        for v in [
            self.near_m,
            self.far_m,
            self.left_deg,
            self.right_deg,
            self.top_deg,
            self.bottom_deg,
        ] {
            w.f32(v);
        }
        w.finish()
    }

    fn decode(r: &Rd) -> Option<Self> {
        let b5 = r.u8(5)?;
        let b6 = r.u8(6)?;
        Some(Self {
            view_id: r.u16(2)?,
            group_id: r.u8(4)?,
            enable: b5 & 0x3F,
            mirror_mode: b5 >> 6,
            pixel_replication: b6 & 0x07,
            orthographic: b6 & 0x08 != 0,
            reorder: b6 & 0x10 != 0,
            view_type: b6 >> 5,
            near_m: r.f32(8)?,
            far_m: r.f32(12)?,
            left_deg: r.f32(16)?,
            right_deg: r.f32(20)?,
            top_deg: r.f32(24)?,
            bottom_deg: r.f32(28)?,
        })
    }

    fn values(&self) -> [f32; 6] {
        [
            self.near_m,
            self.far_m,
            self.left_deg,
            self.right_deg,
            self.top_deg,
            self.bottom_deg,
        ]
    }

    fn check(&self) -> Result<(), DecodeError> {
        const NAMES: [&str; 6] = [
            "view_definition.near",
            "view_definition.far",
            "view_definition.left",
            "view_definition.right",
            "view_definition.top",
            "view_definition.bottom",
        ];
        for (i, v) in self.values().iter().enumerate() {
            if self.enable & (1 << i) != 0 {
                finite32(NAMES[i], *v)?;
            }
        }
        Ok(())
    }
}

/// Start of Frame (packet 101), IG → host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StartOfFrame {
    /// Database number loaded (negative while loading).
    pub database: i8,
    /// IG status code (0 = normal).
    pub ig_status: u8,
    /// IG mode (1 = Operate).
    pub ig_mode: u8,
    /// Timestamp field is valid.
    pub timestamp_valid: bool,
    /// Earth reference model (0 = WGS84).
    pub earth_reference_model: u8,
    /// Minor version (3 for CIGI 3.3).
    pub minor_version: u8,
    /// IG frame counter.
    pub ig_frame: u32,
    /// IG timestamp, 10 µs ticks.
    pub timestamp: u32,
    /// The host frame this answers (the last host frame counter received).
    pub last_host_frame: u32,
}

impl StartOfFrame {
    /// Encodes the packet in `order`.
    pub fn encode(&self, order: ByteOrder) -> [u8; START_OF_FRAME_SIZE as usize] {
        let mut w = Wr::new(order, START_OF_FRAME_SIZE.into());
        let flags = ((self.minor_version & 0x0F) << 4)
            | ((self.earth_reference_model & 0x01) << 3)
            | (u8::from(self.timestamp_valid) << 2)
            | (self.ig_mode & 0x03);
        w.u8(START_OF_FRAME_ID)
            .u8(START_OF_FRAME_SIZE)
            .u8(MAJOR_VERSION)
            .u8(self.database as u8)
            .u8(self.ig_status)
            .u8(flags)
            .u16(BYTE_SWAP_MAGIC)
            .u32(self.ig_frame)
            .u32(self.timestamp)
            .u32(self.last_host_frame)
            .u32(0);
        w.finish()
    }

    /// Decodes a Start of Frame (host side; used by tests and the example sender).
    pub fn decode(b: &[u8]) -> Result<(Self, ByteOrder), DecodeError> {
        if b.len() < START_OF_FRAME_SIZE as usize
            || b[0] != START_OF_FRAME_ID
            || b[1] != START_OF_FRAME_SIZE
        {
            return Err(DecodeError::malformed(P, "not a Start of Frame packet"));
        }
        let order = byte_order(b)?;
        let r = Rd::new(b, order);
        let flags = r.u8(5).ok_or_else(cut)?;
        Ok((
            Self {
                database: r.u8(3).ok_or_else(cut)? as i8,
                ig_status: r.u8(4).ok_or_else(cut)?,
                ig_mode: flags & 0x03,
                timestamp_valid: flags & 0x04 != 0,
                earth_reference_model: (flags >> 3) & 0x01,
                minor_version: flags >> 4,
                ig_frame: r.u32(8).ok_or_else(cut)?,
                timestamp: r.u32(12).ok_or_else(cut)?,
                last_host_frame: r.u32(16).ok_or_else(cut)?,
            },
            order,
        ))
    }
}

/// The byte order of a CIGI message from its byte-swap magic at offset 6: `80 00` is the magic
/// 0x8000 written big-endian, `00 80` little-endian (a receiver reading natively sees 0x0080
/// when it must swap).
fn byte_order(b: &[u8]) -> Result<ByteOrder, DecodeError> {
    match b.get(6..8) {
        Some([0x80, 0x00]) => Ok(ByteOrder::Big),
        Some([0x00, 0x80]) => Ok(ByteOrder::Little),
        Some(other) => Err(DecodeError::malformed(
            P,
            format!(
                "byte-swap magic at offset 6 is {:02x} {:02x}, expected 80 00 or 00 80",
                other[0], other[1]
            ),
        )),
        None => Err(cut()),
    }
}

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
        super::validated(P, pose)?;
    }
    Ok(msg)
}

/// What the host has set for one view (fields it never enabled are `None`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewRecord {
    /// View ID.
    pub view_id: u16,
    /// Group ID (last seen).
    pub group_id: u8,
    /// Entity the view follows (View Control's entity; 0 = ownship).
    pub entity_id: u16,
    /// Eye offset X (forward), Y (right), Z (down), metres.
    pub offset_m: [Option<f32>; 3],
    /// Roll, pitch, yaw relative to the entity, degrees.
    pub roll_pitch_yaw_deg: [Option<f32>; 3],
    /// Near, far (metres), left, right, top, bottom (degrees).
    pub frustum: [Option<f32>; 6],
    /// Mirror mode from the last View Definition.
    pub mirror_mode: u8,
    /// Orthographic projection from the last View Definition.
    pub orthographic: bool,
    /// View type from the last View Definition.
    pub view_type: u8,
}

impl ViewRecord {
    /// Near clip distance, metres.
    pub fn near_m(&self) -> Option<f32> {
        self.frustum[0]
    }
    /// Far clip distance, metres.
    pub fn far_m(&self) -> Option<f32> {
        self.frustum[1]
    }
    /// Left, right, top, bottom half-angles in degrees when all four are set.
    pub fn half_angles_deg(&self) -> Option<[f32; 4]> {
        Some([
            self.frustum[2]?,
            self.frustum[3]?,
            self.frustum[4]?,
            self.frustum[5]?,
        ])
    }
}

/// The per-view state built from View Control and View Definition packets, sorted by view ID.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ViewTable {
    views: Vec<ViewRecord>,
}

impl ViewTable {
    /// All views the host has described, by ascending view ID.
    pub fn views(&self) -> &[ViewRecord] {
        &self.views
    }

    /// The record of `view_id`.
    pub fn get(&self, view_id: u16) -> Option<&ViewRecord> {
        self.views
            .binary_search_by_key(&view_id, |v| v.view_id)
            .ok()
            .map(|i| &self.views[i])
    }

    fn slot(&mut self, view_id: u16) -> Option<&mut ViewRecord> {
        match self.views.binary_search_by_key(&view_id, |v| v.view_id) {
            Ok(i) => Some(&mut self.views[i]),
            Err(i) if self.views.len() < MAX_VIEWS => {
                self.views.insert(
                    i,
                    ViewRecord {
                        view_id,
                        ..ViewRecord::default()
                    },
                );
                Some(&mut self.views[i])
            }
            Err(_) => None,
        }
    }

    /// Applies a View Control (enabled fields only). Returns whether anything changed.
    pub fn apply_control(&mut self, c: &ViewControl) -> bool {
        let Some(v) = self.slot(c.view_id) else {
            return false;
        };
        let before = *v;
        v.group_id = c.group_id;
        v.entity_id = c.entity_id;
        for i in 0..3 {
            if c.enable & (1 << i) != 0 {
                v.offset_m[i] = Some(c.offset_m[i]);
            }
            if c.enable & (1 << (i + 3)) != 0 {
                v.roll_pitch_yaw_deg[i] = Some(c.roll_pitch_yaw_deg[i]);
            }
        }
        *v != before
    }

    /// Applies a View Definition (enabled frustum fields only). Returns whether anything changed.
    pub fn apply_definition(&mut self, d: &ViewDefinition) -> bool {
        let Some(v) = self.slot(d.view_id) else {
            return false;
        };
        let before = *v;
        v.group_id = d.group_id;
        v.mirror_mode = d.mirror_mode;
        v.orthographic = d.orthographic;
        v.view_type = d.view_type;
        for (i, value) in d.values().into_iter().enumerate() {
            if d.enable & (1 << i) != 0 {
                v.frustum[i] = Some(value);
            }
        }
        *v != before
    }

    /// Applies every view packet of a message in order. Returns whether anything changed.
    pub fn apply(&mut self, m: &CigiMessage) -> bool {
        let mut changed = false;
        for c in &m.view_controls {
            changed |= self.apply_control(c);
        }
        for d in &m.view_definitions {
            changed |= self.apply_definition(d);
        }
        changed
    }
}

#[cfg(test)]
mod tests {
    //! Golden bytes written by hand from the CIGI 3.3 ICD field tables (packet ID, size, then
    //! each field at its byte offset), in both byte orders.
    use super::*;
    use crate::stats::DropReason;

    /// IG Control, big-endian: database 5, IG mode Operate, timestamp valid, minor version 3,
    /// host frame 12345 (0x3039), timestamp 123456 (0x0001E240), last IG frame 7.
    const IG_CONTROL_BE: [u8; 24] = [
        0x01, 0x18, // 0: packet ID 1, 1: size 24
        0x03, // 2: major version 3
        0x05, // 3: database number 5
        0x35, // 4: minor version 3 << 4 | timestamp valid 0x04 | IG mode 1
        0x00, // 5: reserved
        0x80, 0x00, // 6: byte-swap magic 0x8000, big-endian
        0x00, 0x00, 0x30, 0x39, // 8: host frame number
        0x00, 0x01, 0xE2, 0x40, // 12: timestamp (10 µs ticks)
        0x00, 0x00, 0x00, 0x07, // 16: last IG frame number
        0x00, 0x00, 0x00, 0x00, // 20: reserved
    ];

    /// The same IG Control as a little-endian host writes it.
    const IG_CONTROL_LE: [u8; 24] = [
        0x01, 0x18, 0x03, 0x05, 0x35, 0x00, //
        0x00, 0x80, // magic 0x8000 little-endian: a big-endian reader sees 0x0080
        0x39, 0x30, 0x00, 0x00, //
        0x40, 0xE2, 0x01, 0x00, //
        0x07, 0x00, 0x00, 0x00, //
        0x00, 0x00, 0x00, 0x00,
    ];

    /// Entity Control for entity 0, big-endian: active, alpha 255, type 0x0102, parent 0,
    /// roll −10.0 (0xC1200000), pitch 2.5 (0x40200000), yaw 90.0 (0x42B40000),
    /// lat 45.0 (0x4046800000000000), lon 11.0 (0x4026000000000000), alt 1500.0 (0x4097700000000000).
    const ENTITY_BE: [u8; 48] = [
        0x02, 0x30, // 0: packet ID 2, 1: size 48
        0x00, 0x00, // 2: entity ID 0
        0x01, // 4: entity state active (bits 0-1), attach 0 (bit 2)
        0x00, // 5: animation flags
        0xFF, // 6: alpha
        0x00, // 7: reserved
        0x01, 0x02, // 8: entity type
        0x00, 0x00, // 10: parent ID
        0xC1, 0x20, 0x00, 0x00, // 12: roll
        0x40, 0x20, 0x00, 0x00, // 16: pitch
        0x42, 0xB4, 0x00, 0x00, // 20: yaw
        0x40, 0x46, 0x80, 0x00, 0x00, 0x00, 0x00, 0x00, // 24: latitude
        0x40, 0x26, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // 32: longitude
        0x40, 0x97, 0x70, 0x00, 0x00, 0x00, 0x00, 0x00, // 40: altitude
    ];

    fn reversed_fields(be: &[u8], widths: &[usize]) -> Vec<u8> {
        // Re-writes a big-endian packet little-endian, field by field.
        let mut out = Vec::new();
        let mut off = 0;
        for &w in widths {
            out.extend(be[off..off + w].iter().rev());
            off += w;
        }
        assert_eq!(off, be.len());
        out
    }

    const ENTITY_WIDTHS: [usize; 15] = [1, 1, 2, 1, 1, 1, 1, 2, 2, 4, 4, 4, 8, 8, 8];

    /// View Control, big-endian: view 2, group 1, all six enables, entity 0,
    /// x 1.5 (0x3FC00000), y −0.5 (0xBF000000), z 0.25 (0x3E800000),
    /// roll 0, pitch −5.0 (0xC0A00000), yaw 60.0 (0x42700000).
    const VIEW_CONTROL_BE: [u8; 32] = [
        0x10, 0x20, // 0: packet ID 16, 1: size 32
        0x00, 0x02, // 2: view ID
        0x01, // 4: group ID
        0x3F, // 5: enables x, y, z, roll, pitch, yaw
        0x00, 0x00, // 6: entity ID
        0x3F, 0xC0, 0x00, 0x00, // 8: x offset
        0xBF, 0x00, 0x00, 0x00, // 12: y offset
        0x3E, 0x80, 0x00, 0x00, // 16: z offset
        0x00, 0x00, 0x00, 0x00, // 20: roll
        0xC0, 0xA0, 0x00, 0x00, // 24: pitch
        0x42, 0x70, 0x00, 0x00, // 28: yaw
    ];

    /// View Definition, big-endian: view 2, group 1, near/far/left/right/top/bottom enabled,
    /// mirror none, perspective; near 0.5 (0x3F000000), far 50000 (0x47435000),
    /// left −30 (0xC1F00000), right 30 (0x41F00000), top 20 (0x41A00000), bottom −20 (0xC1A00000).
    const VIEW_DEFINITION_BE: [u8; 32] = [
        0x15, 0x20, // 0: packet ID 21, 1: size 32
        0x00, 0x02, // 2: view ID
        0x01, // 4: group ID
        0x3F, // 5: enables (bits 0-5), mirror mode 0 (bits 6-7)
        0x00, // 6: pixel replication 0, projection perspective, reorder 0, view type 0
        0x00, // 7: reserved
        0x3F, 0x00, 0x00, 0x00, // 8: near
        0x47, 0x43, 0x50, 0x00, // 12: far
        0xC1, 0xF0, 0x00, 0x00, // 16: left
        0x41, 0xF0, 0x00, 0x00, // 20: right
        0x41, 0xA0, 0x00, 0x00, // 24: top
        0xC1, 0xA0, 0x00, 0x00, // 28: bottom
    ];

    const VIEW_WIDTHS: [usize; 12] = [1, 1, 2, 1, 1, 2, 4, 4, 4, 4, 4, 4];
    const VIEW_DEF_WIDTHS: [usize; 13] = [1, 1, 2, 1, 1, 1, 1, 4, 4, 4, 4, 4, 4];

    fn expected_ig() -> IgControl {
        IgControl {
            database: 5,
            ig_mode: 1,
            timestamp_valid: true,
            smoothing: false,
            minor_version: 3,
            host_frame: 12345,
            timestamp: 123_456,
            last_ig_frame: 7,
        }
    }

    fn expected_entity() -> EntityControl {
        EntityControl {
            entity_id: 0,
            entity_state: 1,
            attached: false,
            flags_hi: 0,
            animation_flags: 0,
            alpha: 255,
            entity_type: 0x0102,
            parent_id: 0,
            roll_deg: -10.0,
            pitch_deg: 2.5,
            yaw_deg: 90.0,
            lat_deg: 45.0,
            lon_deg: 11.0,
            alt_m: 1500.0,
        }
    }

    fn message(parts: &[&[u8]]) -> Vec<u8> {
        parts.concat()
    }

    fn le_entity() -> Vec<u8> {
        reversed_fields(&ENTITY_BE, &ENTITY_WIDTHS)
    }

    #[test]
    fn golden_ig_control_both_orders() {
        assert_eq!(expected_ig().encode(ByteOrder::Big), IG_CONTROL_BE);
        assert_eq!(expected_ig().encode(ByteOrder::Little), IG_CONTROL_LE);
        for (bytes, order) in [
            (IG_CONTROL_BE, ByteOrder::Big),
            (IG_CONTROL_LE, ByteOrder::Little),
        ] {
            let m = decode(&bytes).unwrap();
            assert_eq!(m.byte_order, order);
            assert_eq!(m.ig_control, expected_ig());
            assert_eq!(m.ownship, None);
            assert_eq!(m.ownship_pose(), None);
        }
    }

    #[test]
    fn golden_entity_control_both_orders() {
        assert_eq!(expected_entity().encode(ByteOrder::Big), ENTITY_BE);
        assert_eq!(
            expected_entity().encode(ByteOrder::Little).to_vec(),
            le_entity()
        );
        for (ig, ent) in [
            (IG_CONTROL_BE.to_vec(), ENTITY_BE.to_vec()),
            (IG_CONTROL_LE.to_vec(), le_entity()),
        ] {
            let m = decode(&message(&[&ig, &ent])).unwrap();
            assert_eq!(m.ownship, Some(expected_entity()));
            let p = m.ownship_pose().unwrap();
            assert_eq!(
                p.position,
                PosePosition::Geodetic {
                    lat_deg: 45.0,
                    lon_deg: 11.0,
                    alt_m: 1500.0
                }
            );
            assert_eq!(p.attitude_deg, [90.0, 2.5, -10.0]);
            assert_eq!(p.frame, 12345);
            assert!((p.sim_time_s - 1.23456).abs() < 1e-12);
        }
    }

    #[test]
    fn golden_views_both_orders() {
        let vc = ViewControl {
            view_id: 2,
            group_id: 1,
            enable: 0x3F,
            entity_id: 0,
            offset_m: [1.5, -0.5, 0.25],
            roll_pitch_yaw_deg: [0.0, -5.0, 60.0],
        };
        let vd = ViewDefinition {
            view_id: 2,
            group_id: 1,
            enable: 0x3F,
            near_m: 0.5,
            far_m: 50_000.0,
            left_deg: -30.0,
            right_deg: 30.0,
            top_deg: 20.0,
            bottom_deg: -20.0,
            ..ViewDefinition::default()
        };
        assert_eq!(vc.encode(ByteOrder::Big), VIEW_CONTROL_BE);
        assert_eq!(vd.encode(ByteOrder::Big), VIEW_DEFINITION_BE);
        let vc_le = reversed_fields(&VIEW_CONTROL_BE, &VIEW_WIDTHS);
        let vd_le = reversed_fields(&VIEW_DEFINITION_BE, &VIEW_DEF_WIDTHS);
        assert_eq!(vc.encode(ByteOrder::Little).to_vec(), vc_le);
        assert_eq!(vd.encode(ByteOrder::Little).to_vec(), vd_le);
        for bytes in [
            message(&[&IG_CONTROL_BE, &VIEW_CONTROL_BE, &VIEW_DEFINITION_BE]),
            message(&[&IG_CONTROL_LE, &vc_le, &vd_le]),
        ] {
            let m = decode(&bytes).unwrap();
            assert_eq!(m.view_controls, vec![vc]);
            assert_eq!(m.view_definitions, vec![vd]);
            let mut t = ViewTable::default();
            assert!(t.apply(&m));
            assert!(!t.apply(&m), "same packets again change nothing");
            let v = t.get(2).unwrap();
            assert_eq!(v.offset_m, [Some(1.5), Some(-0.5), Some(0.25)]);
            assert_eq!(v.roll_pitch_yaw_deg, [Some(0.0), Some(-5.0), Some(60.0)]);
            assert_eq!(v.near_m(), Some(0.5));
            assert_eq!(v.far_m(), Some(50_000.0));
            assert_eq!(v.half_angles_deg(), Some([-30.0, 30.0, 20.0, -20.0]));
        }
    }

    #[test]
    fn golden_start_of_frame_both_orders() {
        // Start of Frame: database 5, status 0, Operate, timestamp valid, WGS84, minor 3,
        // IG frame 42, timestamp 0x01020304, last host frame 12345.
        let be: [u8; 24] = [
            0x65, 0x18, // 0: packet ID 101, 1: size 24
            0x03, // 2: major version
            0x05, // 3: database number
            0x00, // 4: IG status
            0x35, // 5: minor 3 << 4 | earth model 0 (bit 3) | timestamp valid 0x04 | Operate 1
            0x80, 0x00, // 6: byte-swap magic
            0x00, 0x00, 0x00, 0x2A, // 8: IG frame number
            0x01, 0x02, 0x03, 0x04, // 12: timestamp
            0x00, 0x00, 0x30, 0x39, // 16: last host frame number
            0x00, 0x00, 0x00, 0x00, // 20: reserved
        ];
        let le = reversed_fields(&be, &[1, 1, 1, 1, 1, 1, 2, 4, 4, 4, 4]);
        let m = decode(&IG_CONTROL_BE).unwrap();
        assert_eq!(m.answer(42, 0x0102_0304), be);
        let m = decode(&IG_CONTROL_LE).unwrap();
        assert_eq!(m.answer(42, 0x0102_0304).to_vec(), le);
        let (sof, order) = StartOfFrame::decode(&le).unwrap();
        assert_eq!(order, ByteOrder::Little);
        assert_eq!(
            (sof.ig_frame, sof.last_host_frame, sof.ig_mode),
            (42, 12345, 1)
        );
        assert_eq!(StartOfFrame::decode(&be).unwrap().0, sof);
    }

    #[test]
    fn unknown_packets_are_skipped_by_size() {
        // An 8-byte unknown packet (ID 200), a Celestial-sphere-like 16-byte packet (ID 9)
        // and an entity other than the ownship, around the ownship.
        let mut other_entity = ENTITY_BE;
        other_entity[3] = 7;
        let unknown8 = [200u8, 8, 1, 2, 3, 4, 5, 6];
        let unknown16 = [9u8, 16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        let m = decode(&message(&[
            &IG_CONTROL_BE,
            &unknown8,
            &other_entity,
            &ENTITY_BE,
            &unknown16,
        ]))
        .unwrap();
        assert_eq!(m.skipped, 3);
        assert_eq!(m.ownship, Some(expected_entity()));
    }

    #[test]
    fn broken_messages_are_rejected_with_a_reason() {
        let reason = |b: &[u8]| decode(b).unwrap_err().reason();
        // Size byte 0 would loop forever; size past the end; cut header.
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &[50, 0]])),
            DropReason::Malformed
        );
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &[50, 16, 0]])),
            DropReason::Malformed
        );
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &[50]])),
            DropReason::Malformed
        );
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &ENTITY_BE[..40]])),
            DropReason::Malformed
        );
        // Known packet with the wrong size.
        let mut e = ENTITY_BE.to_vec();
        e[1] = 40;
        e.truncate(40);
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &e])),
            DropReason::Malformed
        );
        // Not starting with IG Control, wrong version, short, bad magic.
        assert_eq!(reason(&ENTITY_BE), DropReason::Malformed);
        let mut v2 = IG_CONTROL_BE;
        v2[2] = 2;
        assert_eq!(reason(&v2), DropReason::BadVersion);
        assert_eq!(reason(&IG_CONTROL_BE[..20]), DropReason::BadSize);
        let mut magic = IG_CONTROL_BE;
        magic[6] = 0x12;
        assert_eq!(reason(&magic), DropReason::Malformed);
        // Ownship out of range / not finite / attached.
        let mut lat = ENTITY_BE;
        lat[24..32].copy_from_slice(&95.0f64.to_be_bytes());
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &lat])),
            DropReason::Invalid
        );
        let mut roll = ENTITY_BE;
        roll[12..16].copy_from_slice(&f32::NAN.to_be_bytes());
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &roll])),
            DropReason::Invalid
        );
        let mut attached = ENTITY_BE;
        attached[4] |= 0x04;
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &attached])),
            DropReason::Unsupported
        );
        // A NaN in an enabled view field; the same NaN with the field disabled is fine.
        let mut vc = VIEW_CONTROL_BE;
        vc[24..28].copy_from_slice(&f32::NAN.to_be_bytes());
        assert_eq!(
            reason(&message(&[&IG_CONTROL_BE, &vc])),
            DropReason::Invalid
        );
        vc[5] = 0x2F;
        decode(&message(&[&IG_CONTROL_BE, &vc])).unwrap();
    }

    #[test]
    fn disabled_view_fields_keep_their_values() {
        let mut t = ViewTable::default();
        let full = ViewControl {
            view_id: 1,
            enable: 0x3F,
            offset_m: [1.0, 2.0, 3.0],
            roll_pitch_yaw_deg: [4.0, 5.0, 6.0],
            ..ViewControl::default()
        };
        t.apply_control(&full);
        let yaw_only = ViewControl {
            view_id: 1,
            enable: view_enable::YAW,
            offset_m: [9.0; 3],
            roll_pitch_yaw_deg: [9.0, 9.0, -45.0],
            ..ViewControl::default()
        };
        assert!(t.apply_control(&yaw_only));
        let v = t.get(1).unwrap();
        assert_eq!(v.offset_m, [Some(1.0), Some(2.0), Some(3.0)]);
        assert_eq!(v.roll_pitch_yaw_deg, [Some(4.0), Some(5.0), Some(-45.0)]);
        // The table is bounded.
        for id in 0..200u16 {
            t.apply_control(&ViewControl {
                view_id: id,
                ..ViewControl::default()
            });
        }
        assert_eq!(t.views().len(), MAX_VIEWS);
        assert!(t.views().windows(2).all(|w| w[0].view_id < w[1].view_id));
    }
}
