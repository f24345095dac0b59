//! aerie native v1: one fixed 132-byte little-endian datagram per simulator frame, protected by a
//! CRC-32. Layout (byte offsets; specified in `sim-bridge/PROTOCOL.md`):
//!
//! | off | size | field |
//! |----:|-----:|-------|
//! | 0 | 4 | magic `"AERP"` (0x41 0x45 0x52 0x50) |
//! | 4 | 2 | version u16 = 1 |
//! | 6 | 2 | flags u16: bit 0 position is local ENU (else WGS84), bit 1 velocity valid, bit 2 rates valid; others 0 |
//! | 8 | 4 | sequence u32 (+1 per datagram, wraps) |
//! | 12 | 2 | size u16 = 132 |
//! | 14 | 2 | reserved, 0 |
//! | 16 | 8 | sim time f64, s |
//! | 24 | 8 | frame u64 |
//! | 32 | 24 | position f64×3: lat°, lon°, alt m (WGS84) or x, y, z m (ENU) |
//! | 56 | 24 | attitude f64×3: heading, pitch, roll, degrees |
//! | 80 | 24 | velocity f64×3: east, north, up, m/s |
//! | 104 | 24 | rates f64×3: heading, pitch, roll rates, deg/s |
//! | 128 | 4 | CRC-32 (IEEE, as zlib's `crc32`) of bytes 0..128 |

pub use super::native_query::{
    decode_query, decode_reply, encode_query, encode_reply, is_query, QUERY_MAGIC, QUERY_SIZE,
    QUERY_VERSION, REPLY_MAGIC, REPLY_SIZE,
};

use super::protocol::{validated, DecodeError, Protocol};
use super::wire::{ByteOrder, Rd, Wr};
use crate::pose::{Pose, PosePosition};

/// First four bytes of every native datagram.
pub const MAGIC: [u8; 4] = *b"AERP";
/// The version this module reads and writes.
pub const VERSION: u16 = 1;
/// Datagram size in bytes.
pub const SIZE: usize = 132;
/// Flag: the position is local ENU metres (else WGS84 lat/lon/alt).
pub const FLAG_LOCAL_ENU: u16 = 1 << 0;
/// Flag: the velocity field is valid.
pub const FLAG_VELOCITY: u16 = 1 << 1;
/// Flag: the rates field is valid.
pub const FLAG_RATES: u16 = 1 << 2;
const KNOWN_FLAGS: u16 = FLAG_LOCAL_ENU | FLAG_VELOCITY | FLAG_RATES;
const CRC_OFFSET: usize = 128;

const P: Protocol = Protocol::Aerie;

/// A decoded native datagram.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NativePose {
    /// The sender's datagram sequence number.
    pub sequence: u32,
    /// The pose, validated.
    pub pose: Pose,
}

/// Encodes `pose` with datagram sequence number `sequence`.
pub fn encode(pose: &Pose, sequence: u32) -> [u8; SIZE] {
    let mut flags = 0u16;
    let (position, local) = pose.position.wire();
    if local {
        flags |= FLAG_LOCAL_ENU;
    }
    if pose.velocity_enu.is_some() {
        flags |= FLAG_VELOCITY;
    }
    if pose.angular_rates_deg_s.is_some() {
        flags |= FLAG_RATES;
    }
    let mut w = Wr::new(ByteOrder::Little, SIZE);
    w.raw(&MAGIC)
        .u16(VERSION)
        .u16(flags)
        .u32(sequence)
        .u16(SIZE as u16)
        .u16(0)
        .f64(pose.sim_time_s)
        .u64(pose.frame);
    let vectors = [
        position,
        pose.attitude_deg,
        pose.velocity_enu.unwrap_or([0.0; 3]),
        pose.angular_rates_deg_s.unwrap_or([0.0; 3]),
    ];
    for v in vectors.iter().flatten() {
        w.f64(*v);
    }
    let crc = crc32fast::hash(&w.buf);
    w.u32(crc);
    w.finish()
}

/// Decodes and validates a native datagram.
pub fn decode(b: &[u8]) -> Result<NativePose, DecodeError> {
    if !b.starts_with(&MAGIC) {
        return Err(DecodeError::BadMagic { protocol: P });
    }
    let r = Rd::new(b, ByteOrder::Little);
    let t = || DecodeError::truncated(P);
    let version = r.u16(4).ok_or_else(t)?;
    if version != VERSION {
        return Err(DecodeError::BadVersion {
            protocol: P,
            found: version.into(),
            expected: VERSION.into(),
        });
    }
    if b.len() != SIZE {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: SIZE,
        });
    }
    let found = r.u32(CRC_OFFSET).ok_or_else(t)?;
    let computed = crc32fast::hash(&b[..CRC_OFFSET]);
    if found != computed {
        return Err(DecodeError::BadCrc {
            protocol: P,
            found,
            computed,
        });
    }
    let size = r.u16(12).ok_or_else(t)?;
    if usize::from(size) != SIZE {
        return Err(DecodeError::malformed(
            P,
            format!("size field (offset 12) is {size}, expected {SIZE}"),
        ));
    }
    let flags = r.u16(6).ok_or_else(t)?;
    if flags & !KNOWN_FLAGS != 0 {
        return Err(DecodeError::malformed(
            P,
            format!("unknown flag bits {:#06x} (offset 6)", flags & !KNOWN_FLAGS),
        ));
    }
    if r.u16(14).ok_or_else(t)? != 0 {
        return Err(DecodeError::malformed(
            P,
            "reserved field (offset 14) is not 0",
        ));
    }
    let v3 = |off: usize| -> Result<[f64; 3], DecodeError> {
        Ok([
            r.f64(off).ok_or_else(t)?,
            r.f64(off + 8).ok_or_else(t)?,
            r.f64(off + 16).ok_or_else(t)?,
        ])
    };
    let [a, b2, c] = v3(32)?;
    let position = if flags & FLAG_LOCAL_ENU != 0 {
        PosePosition::LocalEnu { x: a, y: b2, z: c }
    } else {
        PosePosition::Geodetic {
            lat_deg: a,
            lon_deg: b2,
            alt_m: c,
        }
    };
    let pose = Pose {
        position,
        attitude_deg: v3(56)?,
        sim_time_s: r.f64(16).ok_or_else(t)?,
        frame: r.u64(24).ok_or_else(t)?,
        velocity_enu: (flags & FLAG_VELOCITY != 0).then_some(v3(80)?),
        angular_rates_deg_s: (flags & FLAG_RATES != 0).then_some(v3(104)?),
    };
    Ok(NativePose {
        sequence: r.u32(8).ok_or_else(t)?,
        pose: validated(P, pose)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::DropReason;
    use proptest::prelude::*;

    fn sample() -> Pose {
        Pose {
            position: PosePosition::Geodetic {
                lat_deg: 47.2692,
                lon_deg: 11.4041,
                alt_m: 2400.5,
            },
            attitude_deg: [271.5, -4.25, 12.0],
            sim_time_s: 3600.125,
            frame: 216_007,
            velocity_enu: Some([-150.0, 12.5, -3.0]),
            angular_rates_deg_s: Some([0.75, -0.1, 5.0]),
        }
    }

    fn reason(b: &[u8]) -> DropReason {
        decode(b).unwrap_err().reason()
    }

    /// Rewrites the CRC after a deliberate edit so that the edit itself is what gets rejected.
    fn recrc(b: &mut [u8; SIZE]) {
        let crc = crc32fast::hash(&b[..CRC_OFFSET]);
        b[CRC_OFFSET..].copy_from_slice(&crc.to_le_bytes());
    }

    #[test]
    fn round_trip_geodetic_with_motion() {
        let p = sample();
        let d = decode(&encode(&p, 0xDEAD_BEEF)).unwrap();
        assert_eq!(d.sequence, 0xDEAD_BEEF);
        assert_eq!(d.pose, p);
    }

    #[test]
    fn round_trip_local_without_motion() {
        let p = Pose {
            position: PosePosition::LocalEnu {
                x: 30_500.25,
                y: -12.0,
                z: 4500.0,
            },
            velocity_enu: None,
            angular_rates_deg_s: None,
            ..sample()
        };
        let b = encode(&p, 7);
        assert_eq!(u16::from_le_bytes([b[6], b[7]]), FLAG_LOCAL_ENU);
        assert_eq!(decode(&b).unwrap().pose, p);
    }

    #[test]
    fn layout_offsets() {
        let b = encode(&sample(), 0x0403_0201);
        assert_eq!(&b[0..4], b"AERP");
        assert_eq!(&b[4..6], &[1, 0]);
        assert_eq!(&b[6..8], &(FLAG_VELOCITY | FLAG_RATES).to_le_bytes());
        assert_eq!(&b[8..12], &[1, 2, 3, 4]);
        assert_eq!(&b[12..14], &[132, 0]);
        assert_eq!(&b[16..24], &3600.125f64.to_le_bytes());
        assert_eq!(&b[24..32], &216_007u64.to_le_bytes());
        assert_eq!(&b[32..40], &47.2692f64.to_le_bytes());
        assert_eq!(&b[56..64], &271.5f64.to_le_bytes());
        assert_eq!(&b[80..88], &(-150.0f64).to_le_bytes());
        assert_eq!(&b[120..128], &5.0f64.to_le_bytes());
        // CRC-32/IEEE of the first 128 bytes, checked against the standard check value.
        assert_eq!(crc32fast::hash(b"123456789"), 0xCBF4_3926);
        assert_eq!(&b[128..], &crc32fast::hash(&b[..128]).to_le_bytes());
    }

    #[test]
    fn any_flipped_bit_is_a_crc_error() {
        let good = encode(&sample(), 1);
        for byte in 16..CRC_OFFSET + 4 {
            for bit in [0, 3, 7] {
                let mut b = good;
                b[byte] ^= 1 << bit;
                assert_eq!(reason(&b), DropReason::BadCrc, "byte {byte} bit {bit}");
            }
        }
    }

    #[test]
    fn header_errors_are_named() {
        let good = encode(&sample(), 1);
        let mut b = good;
        b[0] = b'X';
        assert_eq!(reason(&b), DropReason::Unknown);
        let mut b = good;
        b[4] = 2;
        let e = decode(&b).unwrap_err();
        assert_eq!(e.reason(), DropReason::BadVersion);
        assert!(e.to_string().contains("version 2"), "{e}");
        assert_eq!(reason(&good[..131]), DropReason::BadSize);
        assert_eq!(reason(&good[..5]), DropReason::Malformed);
        let mut long = good.to_vec();
        long.push(0);
        assert_eq!(reason(&long), DropReason::BadSize);
        let mut b = good;
        b[6] |= 0x80;
        recrc(&mut b);
        assert_eq!(reason(&b), DropReason::Malformed);
        let mut b = good;
        b[12] = 100;
        recrc(&mut b);
        assert_eq!(reason(&b), DropReason::Malformed);
    }

    #[test]
    fn invalid_values_are_rejected_after_the_crc() {
        for (off, value, field) in [
            (32, 91.0, "position.lat_deg"),
            (40, f64::NAN, "position.lon_deg"),
            (48, 1_500_000.0, "position.alt_m"),
            (64, 95.0, "attitude_deg.pitch"),
            (16, f64::INFINITY, "sim_time_s"),
            (88, f64::NAN, "velocity_enu.north"),
        ] {
            let mut b = encode(&sample(), 1);
            b[off..off + 8].copy_from_slice(&value.to_le_bytes());
            recrc(&mut b);
            match decode(&b).unwrap_err() {
                DecodeError::Invalid { error, .. } => assert_eq!(error.field(), field),
                e => panic!("{field}: {e}"),
            }
        }
    }

    proptest! {
        #[test]
        fn round_trip_any_valid_pose(
            lat in -90.0..=90.0f64, lon in -180.0..360.0f64, alt in -1000.0..=100_000.0f64,
            att in prop::array::uniform3(-90.0..=90.0f64), t in 0.0..1e7f64, frame in any::<u64>(),
            seq in any::<u32>(), vel in prop::option::of(prop::array::uniform3(-1e3..1e3f64)),
        ) {
            let p = Pose {
                position: PosePosition::Geodetic { lat_deg: lat, lon_deg: lon, alt_m: alt },
                attitude_deg: att, sim_time_s: t, frame, velocity_enu: vel, angular_rates_deg_s: None,
            };
            let d = decode(&encode(&p, seq)).unwrap();
            prop_assert_eq!(d.pose, p);
            prop_assert_eq!(d.sequence, seq);
        }
    }
}
