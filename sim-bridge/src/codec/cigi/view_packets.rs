//! View Control (16) and View Definition (21): the host's view offsets and frusta (the same
//! 32-byte layouts in every 3.x: CCL `CigiViewCtrlV3.cpp`, `CigiViewDefV3.cpp`).

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd, Wr};

use super::format::*;

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
