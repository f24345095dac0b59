//! The packets that place entities: Entity Control (2), Conformal Clamped Entity Control (3)
//! and Rate Control (8).

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd, Wr};

use super::format::*;
use super::version::CigiVersion;

/// Entity Control (packet 2, 48 bytes in every 3.x). Layout: CCL `CigiEntityCtrlV3.cpp`
/// (3.0–3.2) and `CigiEntityCtrlV3_3.cpp` (3.3, adds the smoothing bit):
/// 2 entity ID (u16); 4 bits 0–1 entity state, bit 2 attach, bit 3 collision detection,
/// bit 4 inherit alpha, bits 5–6 ground clamp; 5 bit 0 animation direction, bit 1 loop mode,
/// bits 2–3 animation state, bit 4 smoothing (3.3); 6 alpha; 8 entity type (u16);
/// 10 parent ID (u16); 12 roll, 16 pitch, 20 yaw (f32, °); 24 latitude / x, 32 longitude / y,
/// 40 altitude / z (f64, ° or m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EntityControl {
    /// Entity ID (0 = ownship).
    pub entity_id: u16,
    /// Entity state (0 inactive/standby, 1 active, 2 destroyed).
    pub entity_state: u8,
    /// Attached to a parent entity (position is then an offset; unsupported for the ownship).
    pub attached: bool,
    /// Collision detection enabled.
    pub collision_detection: bool,
    /// Inherit the parent's alpha.
    pub inherit_alpha: bool,
    /// Ground/ocean clamp (0 none, 1 non-conformal, 2 conformal).
    pub ground_clamp: u8,
    /// Animation direction backward (else forward).
    pub animation_backward: bool,
    /// Animation loops (else plays once).
    pub animation_loop: bool,
    /// Animation state (0 stop, 1 pause, 2 play, 3 continue).
    pub animation_state: u8,
    /// Extrapolation/interpolation enabled (3.3 only; decoded as false before).
    pub smoothing: bool,
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
    /// Latitude, degrees (or X offset when attached, metres).
    pub lat_deg: f64,
    /// Longitude, degrees (or Y offset when attached, metres).
    pub lon_deg: f64,
    /// Altitude above mean sea level, metres (or Z offset when attached).
    pub alt_m: f64,
}

impl EntityControl {
    /// Encodes the packet in `order` with every field as set (the 3.3 layout; a 3.0–3.2 host
    /// leaves `smoothing` false, the bit being reserved there).
    pub fn encode(&self, order: ByteOrder) -> [u8; ENTITY_CONTROL_SIZE as usize] {
        let b4 = (self.entity_state & 0x03)
            | (u8::from(self.attached) << 2)
            | (u8::from(self.collision_detection) << 3)
            | (u8::from(self.inherit_alpha) << 4)
            | ((self.ground_clamp & 0x03) << 5);
        let b5 = u8::from(self.animation_backward)
            | (u8::from(self.animation_loop) << 1)
            | ((self.animation_state & 0x03) << 2)
            | (u8::from(self.smoothing) << 4);
        let mut w = Wr::new(order, ENTITY_CONTROL_SIZE.into());
        w.u8(ENTITY_CONTROL_ID)
            .u8(ENTITY_CONTROL_SIZE)
            .u16(self.entity_id)
            .u8(b4)
            .u8(b5)
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

    /// Decodes the packet (`b` is exactly its 48 bytes) as `version` has it.
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, ENTITY_CONTROL_ID, ENTITY_CONTROL_SIZE, order)?;
        Self::read(&r, version).ok_or_else(cut)
    }

    fn read(r: &Rd, version: CigiVersion) -> Option<Self> {
        let b4 = r.u8(4)?;
        let b5 = r.u8(5)?;
        Some(Self {
            entity_id: r.u16(2)?,
            entity_state: b4 & 0x03,
            attached: b4 & 0x04 != 0,
            collision_detection: b4 & 0x08 != 0,
            inherit_alpha: b4 & 0x10 != 0,
            ground_clamp: (b4 >> 5) & 0x03,
            animation_backward: b5 & 0x01 != 0,
            animation_loop: b5 & 0x02 != 0,
            animation_state: (b5 >> 2) & 0x03,
            smoothing: version.has_smoothing() && b5 & 0x10 != 0,
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

    /// The value checks of the ICD (CCL `CigiBaseEntityCtrl.cpp`, `CigiEntityCtrlV3_3.cpp`
    /// setters): entity state 0–2, ground clamp 0–2, roll −180…180, pitch −90…90,
    /// yaw 0…360, the position finite and, unless attached, a latitude/longitude in range.
    /// (The ownship's pose is validated as a pose instead, by the message decoder.)
    pub fn check(&self) -> Result<(), DecodeError> {
        within(
            "entity_control.entity_state",
            self.entity_state.into(),
            0.0,
            2.0,
            "[0, 2]",
        )?;
        within(
            "entity_control.ground_clamp",
            self.ground_clamp.into(),
            0.0,
            2.0,
            "[0, 2]",
        )?;
        within(
            "entity_control.roll",
            self.roll_deg.into(),
            -180.0,
            180.0,
            "[-180, 180]",
        )?;
        within(
            "entity_control.pitch",
            self.pitch_deg.into(),
            -90.0,
            90.0,
            "[-90, 90]",
        )?;
        within(
            "entity_control.yaw",
            self.yaw_deg.into(),
            0.0,
            360.0,
            "[0, 360]",
        )?;
        finite64("entity_control.altitude", self.alt_m)?;
        if self.attached {
            finite64("entity_control.x_offset", self.lat_deg)?;
            finite64("entity_control.y_offset", self.lon_deg)
        } else {
            lat_lon(
                "entity_control.latitude",
                self.lat_deg,
                "entity_control.longitude",
                self.lon_deg,
            )
        }
    }
}

/// Conformal Clamped Entity Control (packet 3, 24 bytes): an entity clamped to the terrain.
/// Layout: CCL `CigiConfClampEntityCtrlV3.cpp`: 2 entity ID (u16); 4 yaw (f32, °);
/// 8 latitude, 16 longitude (f64, °).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConformalClampedEntityControl {
    /// Entity ID.
    pub entity_id: u16,
    /// Yaw (true heading), degrees (0 … 360).
    pub yaw_deg: f32,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
}

impl ConformalClampedEntityControl {
    /// Encodes the packet in `order` (the same in every 3.x).
    pub fn encode(&self, order: ByteOrder) -> [u8; CONFORMAL_CLAMPED_ENTITY_CONTROL_SIZE as usize] {
        let mut w = Wr::new(order, CONFORMAL_CLAMPED_ENTITY_CONTROL_SIZE.into());
        w.u8(CONFORMAL_CLAMPED_ENTITY_CONTROL_ID)
            .u8(CONFORMAL_CLAMPED_ENTITY_CONTROL_SIZE)
            .u16(self.entity_id)
            .f32(self.yaw_deg)
            .f64(self.lat_deg)
            .f64(self.lon_deg);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 24 bytes).
    pub fn decode(b: &[u8], order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(
            b,
            CONFORMAL_CLAMPED_ENTITY_CONTROL_ID,
            CONFORMAL_CLAMPED_ENTITY_CONTROL_SIZE,
            order,
        )?;
        let read = || -> Option<Self> {
            Some(Self {
                entity_id: r.u16(2)?,
                yaw_deg: r.f32(4)?,
                lat_deg: r.f64(8)?,
                lon_deg: r.f64(16)?,
            })
        };
        read().ok_or_else(cut)
    }

    /// Yaw 0…360, latitude −90…90, longitude −180…180 (CCL `CigiBaseConfClampEntityCtrl.cpp`).
    pub fn check(&self) -> Result<(), DecodeError> {
        within(
            "conformal_clamped_entity_control.yaw",
            self.yaw_deg.into(),
            0.0,
            360.0,
            "[0, 360]",
        )?;
        lat_lon(
            "conformal_clamped_entity_control.latitude",
            self.lat_deg,
            "conformal_clamped_entity_control.longitude",
            self.lon_deg,
        )
    }
}

/// The frame Rate Control's rates are in (3.2+; 3.0/3.1 rates are always world/parent).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RateFrame {
    /// 0: the world (top-level entity) or the parent entity (attached entity).
    #[default]
    WorldOrParent,
    /// 1: the entity's own body axes.
    Local,
}

/// Rate Control (packet 8, 32 bytes): linear and angular rates of an entity or articulated
/// part. Layout: CCL `CigiRateCtrlV3.cpp` / `CigiRateCtrlV3_2.cpp`: 2 entity ID (u16);
/// 4 articulated part ID (u8); 5 bit 0 apply to articulated part, bit 1 coordinate system
/// (3.2+); 8 x, 12 y, 16 z rate (f32, m/s); 20 roll, 24 pitch, 28 yaw rate (f32, °/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RateControl {
    /// Entity ID.
    pub entity_id: u16,
    /// Articulated part ID (meaningful when `apply_to_articulated_part`).
    pub articulated_part_id: u8,
    /// The rates apply to the articulated part (else to the entity).
    pub apply_to_articulated_part: bool,
    /// The frame of the rates (3.2+; world/parent before).
    pub frame: RateFrame,
    /// X, Y, Z linear rates, m/s.
    pub linear_m_s: [f32; 3],
    /// Roll, pitch, yaw angular rates, °/s.
    pub angular_deg_s: [f32; 3],
}

impl RateControl {
    /// Encodes the packet as `version` has it (the coordinate-system bit only in 3.2+).
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; RATE_CONTROL_SIZE as usize] {
        let local = version.is_3_2_or_later() && self.frame == RateFrame::Local;
        let flags = u8::from(self.apply_to_articulated_part) | (u8::from(local) << 1);
        let mut w = Wr::new(order, RATE_CONTROL_SIZE.into());
        w.u8(RATE_CONTROL_ID)
            .u8(RATE_CONTROL_SIZE)
            .u16(self.entity_id)
            .u8(self.articulated_part_id)
            .u8(flags)
            .u16(0);
        for v in self.linear_m_s.iter().chain(&self.angular_deg_s) {
            w.f32(*v);
        }
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 32 bytes) as `version` has it.
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, RATE_CONTROL_ID, RATE_CONTROL_SIZE, order)?;
        let read = || -> Option<Self> {
            let flags = r.u8(5)?;
            Some(Self {
                entity_id: r.u16(2)?,
                articulated_part_id: r.u8(4)?,
                apply_to_articulated_part: flags & 0x01 != 0,
                frame: if version.is_3_2_or_later() && flags & 0x02 != 0 {
                    RateFrame::Local
                } else {
                    RateFrame::WorldOrParent
                },
                linear_m_s: [r.f32(8)?, r.f32(12)?, r.f32(16)?],
                angular_deg_s: [r.f32(20)?, r.f32(24)?, r.f32(28)?],
            })
        };
        read().ok_or_else(cut)
    }

    /// Every rate finite.
    pub fn check(&self) -> Result<(), DecodeError> {
        const NAMES: [&str; 6] = [
            "rate_control.x_rate",
            "rate_control.y_rate",
            "rate_control.z_rate",
            "rate_control.roll_rate",
            "rate_control.pitch_rate",
            "rate_control.yaw_rate",
        ];
        for (name, v) in NAMES
            .iter()
            .zip(self.linear_m_s.iter().chain(&self.angular_deg_s))
        {
            finite32(name, *v)?;
        }
        Ok(())
    }
}
