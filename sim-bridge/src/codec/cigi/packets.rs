//! The packets aerie reads or writes, one struct each with its decoder or encoder.

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd, Wr};

use super::format::*;

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

    pub(super) fn decode(r: &Rd) -> Option<Self> {
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

    pub(super) fn decode(r: &Rd) -> Option<Self> {
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

    pub(super) fn decode(r: &Rd) -> Option<Self> {
        Some(Self {
            view_id: r.u16(2)?,
            group_id: r.u8(4)?,
            enable: r.u8(5)? & 0x3F,
            entity_id: r.u16(6)?,
            offset_m: [r.f32(8)?, r.f32(12)?, r.f32(16)?],
            roll_pitch_yaw_deg: [r.f32(20)?, r.f32(24)?, r.f32(28)?],
        })
    }

    pub(super) fn check(&self) -> Result<(), DecodeError> {
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

    pub(super) fn decode(r: &Rd) -> Option<Self> {
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

    pub(super) fn values(&self) -> [f32; 6] {
        [
            self.near_m,
            self.far_m,
            self.left_deg,
            self.right_deg,
            self.top_deg,
            self.bottom_deg,
        ]
    }

    pub(super) fn check(&self) -> Result<(), DecodeError> {
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
