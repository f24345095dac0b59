//! Environment packets with a terrain meaning: Celestial Sphere Control (9) — the sun's
//! direction from date and time — and Atmosphere Control (10) — visibility for the haze.

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Wr};

use super::format::*;

/// Celestial Sphere Control (packet 9, 16 bytes). Layout: CCL `CigiCelestialCtrl.cpp`
/// (`CigiCelestialCtrlV3::Pack`/`Unpack`): 2 hour (u8); 3 minute (u8); 4 bit 0 ephemeris
/// model enable, bit 1 sun enable, bit 2 moon enable, bit 3 star field enable, bit 4 date
/// valid; 8 date as the decimal number MMDDYYYY (u32); 12 star field intensity (f32, %).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CelestialSphereControl {
    /// Hour of day, 0–23 (UTC).
    pub hour: u8,
    /// Minute, 0–59.
    pub minute: u8,
    /// The IG advances the time of day itself (ephemeris model) from this date and time.
    pub ephemeris_enabled: bool,
    /// Draw the sun.
    pub sun_enabled: bool,
    /// Draw the moon.
    pub moon_enabled: bool,
    /// Draw the star field.
    pub star_field_enabled: bool,
    /// The date fields are valid.
    pub date_valid: bool,
    /// Month, 1–12 (from MMDDYYYY).
    pub month: u8,
    /// Day of the month, 1–31.
    pub day: u8,
    /// Year, 0–9999.
    pub year: u16,
    /// Star field intensity, 0–100 %.
    pub star_field_intensity_pct: f32,
}

impl CelestialSphereControl {
    /// The date as the wire's MMDDYYYY number.
    pub fn date_mmddyyyy(&self) -> u32 {
        u32::from(self.month) * 1_000_000 + u32::from(self.day) * 10_000 + u32::from(self.year)
    }

    /// Encodes the packet in `order` (the same in every 3.x).
    pub fn encode(&self, order: ByteOrder) -> [u8; CELESTIAL_SPHERE_CONTROL_SIZE as usize] {
        let flags = u8::from(self.ephemeris_enabled)
            | (u8::from(self.sun_enabled) << 1)
            | (u8::from(self.moon_enabled) << 2)
            | (u8::from(self.star_field_enabled) << 3)
            | (u8::from(self.date_valid) << 4);
        let mut w = Wr::new(order, CELESTIAL_SPHERE_CONTROL_SIZE.into());
        w.u8(CELESTIAL_SPHERE_CONTROL_ID)
            .u8(CELESTIAL_SPHERE_CONTROL_SIZE)
            .u8(self.hour)
            .u8(self.minute)
            .u8(flags)
            .u8(0)
            .u16(0)
            .u32(self.date_mmddyyyy())
            .f32(self.star_field_intensity_pct);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 16 bytes).
    pub fn decode(b: &[u8], order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(
            b,
            CELESTIAL_SPHERE_CONTROL_ID,
            CELESTIAL_SPHERE_CONTROL_SIZE,
            order,
        )?;
        let read = || -> Option<Self> {
            let flags = r.u8(4)?;
            let date = r.u32(8)?;
            Some(Self {
                hour: r.u8(2)?,
                minute: r.u8(3)?,
                ephemeris_enabled: flags & 0x01 != 0,
                sun_enabled: flags & 0x02 != 0,
                moon_enabled: flags & 0x04 != 0,
                star_field_enabled: flags & 0x08 != 0,
                date_valid: flags & 0x10 != 0,
                // A u32 is at most 4294967295: the month is then 4294 and fails the check.
                month: u8::try_from(date / 1_000_000).unwrap_or(u8::MAX),
                day: ((date / 10_000) % 100) as u8,
                year: (date % 10_000) as u16,
                star_field_intensity_pct: r.f32(12)?,
            })
        };
        read().ok_or_else(cut)
    }

    /// Hour 0–23, minute 0–59, star intensity 0–100 %, and when the date is valid month 1–12,
    /// day 1–31, year ≤ 9999 (CCL `CigiCelestialCtrl.cpp` setters).
    pub fn check(&self) -> Result<(), DecodeError> {
        within(
            "celestial_sphere_control.hour",
            self.hour.into(),
            0.0,
            23.0,
            "[0, 23]",
        )?;
        within(
            "celestial_sphere_control.minute",
            self.minute.into(),
            0.0,
            59.0,
            "[0, 59]",
        )?;
        within(
            "celestial_sphere_control.star_field_intensity",
            self.star_field_intensity_pct.into(),
            0.0,
            100.0,
            "[0, 100]",
        )?;
        if self.date_valid {
            within(
                "celestial_sphere_control.date.month",
                self.month.into(),
                1.0,
                12.0,
                "[1, 12]",
            )?;
            within(
                "celestial_sphere_control.date.day",
                self.day.into(),
                1.0,
                31.0,
                "[1, 31]",
            )?;
            within(
                "celestial_sphere_control.date.year",
                self.year.into(),
                0.0,
                9999.0,
                "[0, 9999]",
            )?;
        }
        Ok(())
    }
}

/// Atmosphere Control (packet 10, 32 bytes): the global atmosphere. Layout: CCL
/// `CigiAtmosCtrl.cpp` (`CigiAtmosCtrlV3::Pack`/`Unpack`): 2 atmospheric model enable (u8,
/// bit 0); 3 global humidity (u8, %); 4 air temperature (f32, °C); 8 visibility range (f32, m);
/// 12 horizontal wind speed (f32, m/s); 16 vertical wind speed (f32, m/s); 20 wind direction
/// (f32, ° from true north, the direction the wind blows from); 24 barometric pressure (f32,
/// mbar); 28 reserved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AtmosphereControl {
    /// The IG's atmospheric model is enabled (weather from the model, not these values).
    pub atmospheric_model_enabled: bool,
    /// Global humidity, 0–100 %.
    pub humidity_pct: u8,
    /// Air temperature, °C.
    pub air_temperature_c: f32,
    /// Visibility range, metres (≥ 0).
    pub visibility_m: f32,
    /// Horizontal wind speed, m/s (≥ 0).
    pub horizontal_wind_m_s: f32,
    /// Vertical wind speed, m/s (up +).
    pub vertical_wind_m_s: f32,
    /// Wind direction, degrees from true north (0–360).
    pub wind_direction_deg: f32,
    /// Barometric pressure, millibars (≥ 0).
    pub barometric_pressure_mbar: f32,
}

impl AtmosphereControl {
    /// Encodes the packet in `order` (the same in every 3.x).
    pub fn encode(&self, order: ByteOrder) -> [u8; ATMOSPHERE_CONTROL_SIZE as usize] {
        let mut w = Wr::new(order, ATMOSPHERE_CONTROL_SIZE.into());
        w.u8(ATMOSPHERE_CONTROL_ID)
            .u8(ATMOSPHERE_CONTROL_SIZE)
            .u8(u8::from(self.atmospheric_model_enabled))
            .u8(self.humidity_pct)
            .f32(self.air_temperature_c)
            .f32(self.visibility_m)
            .f32(self.horizontal_wind_m_s)
            .f32(self.vertical_wind_m_s)
            .f32(self.wind_direction_deg)
            .f32(self.barometric_pressure_mbar)
            .u32(0);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 32 bytes).
    pub fn decode(b: &[u8], order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, ATMOSPHERE_CONTROL_ID, ATMOSPHERE_CONTROL_SIZE, order)?;
        let read = || -> Option<Self> {
            Some(Self {
                atmospheric_model_enabled: r.u8(2)? & 0x01 != 0,
                humidity_pct: r.u8(3)?,
                air_temperature_c: r.f32(4)?,
                visibility_m: r.f32(8)?,
                horizontal_wind_m_s: r.f32(12)?,
                vertical_wind_m_s: r.f32(16)?,
                wind_direction_deg: r.f32(20)?,
                barometric_pressure_mbar: r.f32(24)?,
            })
        };
        read().ok_or_else(cut)
    }

    /// Humidity 0–100 %, visibility ≥ 0, horizontal wind ≥ 0, wind direction 0–360,
    /// pressure ≥ 0, temperature and vertical wind finite (CCL `CigiAtmosCtrl.cpp` setters).
    pub fn check(&self) -> Result<(), DecodeError> {
        within(
            "atmosphere_control.humidity",
            self.humidity_pct.into(),
            0.0,
            100.0,
            "[0, 100]",
        )?;
        finite32("atmosphere_control.air_temperature", self.air_temperature_c)?;
        within(
            "atmosphere_control.visibility_range",
            self.visibility_m.into(),
            0.0,
            f64::MAX,
            "[0, inf)",
        )?;
        within(
            "atmosphere_control.horizontal_wind_speed",
            self.horizontal_wind_m_s.into(),
            0.0,
            f64::MAX,
            "[0, inf)",
        )?;
        finite32(
            "atmosphere_control.vertical_wind_speed",
            self.vertical_wind_m_s,
        )?;
        within(
            "atmosphere_control.wind_direction",
            self.wind_direction_deg.into(),
            0.0,
            360.0,
            "[0, 360]",
        )?;
        within(
            "atmosphere_control.barometric_pressure",
            self.barometric_pressure_mbar.into(),
            0.0,
            f64::MAX,
            "[0, inf)",
        )
    }
}
