//! Packet codecs: aerie native v1 (poses, and the terrain queries and answers), CIGI 3.0–3.3
//! (the IG side), X-Plane `RPOS`, FlightGear FGNetFDM v24 and v25. Layouts are specified in
//! `sim-bridge/PROTOCOL.md`.
//!
//! Every decoder takes arbitrary bytes and either returns a validated [`Pose`] (plus whatever
//! else the packet carried) or a [`DecodeError`] that names the reason; none panics.

pub mod cigi;
pub mod fgfs;
pub mod native;
mod native_query;
pub(crate) mod protocol;
pub(crate) mod wire;
pub mod xplane;

use crate::pose::Pose;

pub use protocol::{DecodeError, Protocol, ProtocolChoice};
pub use wire::ByteOrder;

/// A decoded datagram.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// The protocol it was decoded as.
    pub protocol: Protocol,
    /// The ownship pose, validated, if the datagram carried one.
    pub pose: Option<Pose>,
    /// The sender's sequence number (native sequence, CIGI host frame), for ordering.
    pub sequence: Option<u32>,
    /// The whole CIGI message (IG Control, entities, views, requests, counts) when `protocol`
    /// is CIGI.
    pub cigi: Option<cigi::CigiMessage>,
}

impl Decoded {
    fn pose(protocol: Protocol, pose: Pose, sequence: Option<u32>) -> Self {
        Self {
            protocol,
            pose: Some(pose),
            sequence,
            cigi: None,
        }
    }
}

/// Recognises a datagram's protocol from its first bytes (and, for FGNetFDM, its size):
/// `AERP` → aerie; `RPOS` → X-Plane; packet ID 1 with size 24 (a CIGI 3.2/3.3 IG Control) or
/// 16 (3.0/3.1) → CIGI; big-endian u32 24 or 25 at offset 0, or exactly 408 or 552 bytes →
/// FlightGear. A native terrain query (`AERQ`) is not a pose and is not detected: check
/// [`native::is_query`] first.
pub fn detect(bytes: &[u8]) -> Option<Protocol> {
    if bytes.starts_with(&native::MAGIC) {
        Some(Protocol::Aerie)
    } else if bytes.starts_with(xplane::HEADER) {
        Some(Protocol::XPlane)
    } else if bytes.len() >= 2
        && bytes[0] == cigi::IG_CONTROL_ID
        && (bytes[1] == cigi::IG_CONTROL_SIZE || bytes[1] == cigi::IG_CONTROL_SIZE_V3_0)
    {
        Some(Protocol::Cigi)
    } else if fgfs::looks_like(bytes) {
        Some(Protocol::Fgfs)
    } else {
        None
    }
}

/// Decodes one datagram as `protocol`.
pub fn decode_as(protocol: Protocol, bytes: &[u8]) -> Result<Decoded, DecodeError> {
    match protocol {
        Protocol::Aerie => {
            let p = native::decode(bytes)?;
            Ok(Decoded::pose(protocol, p.pose, Some(p.sequence)))
        }
        Protocol::Cigi => {
            let m = cigi::decode(bytes)?;
            Ok(Decoded {
                protocol,
                pose: m.ownship_pose(),
                sequence: Some(m.ig_control.host_frame),
                cigi: Some(m),
            })
        }
        Protocol::XPlane => Ok(Decoded::pose(protocol, xplane::decode(bytes)?, None)),
        Protocol::Fgfs => Ok(Decoded::pose(protocol, fgfs::decode(bytes)?, None)),
    }
}

/// Decodes one datagram, detecting its protocol or insisting on the configured one.
pub fn decode(choice: ProtocolChoice, bytes: &[u8]) -> Result<Decoded, DecodeError> {
    match choice {
        ProtocolChoice::Only(p) => decode_as(p, bytes),
        ProtocolChoice::Auto => match detect(bytes) {
            Some(p) => decode_as(p, bytes),
            None => Err(DecodeError::Unknown { len: bytes.len() }),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::PosePosition;
    use crate::stats::DropReason;
    use proptest::prelude::*;

    fn pose() -> Pose {
        Pose {
            position: PosePosition::Geodetic {
                lat_deg: 47.26,
                lon_deg: 11.35,
                alt_m: 1800.0,
            },
            attitude_deg: [92.0, 3.0, -8.0],
            sim_time_s: 10.0,
            frame: 600,
            velocity_enu: Some([120.0, -4.0, 1.0]),
            angular_rates_deg_s: Some([1.0, 0.0, -3.0]),
        }
    }

    #[test]
    fn detection_by_first_bytes() {
        let n = native::encode(&pose(), 1);
        assert_eq!(detect(&n), Some(Protocol::Aerie));
        let x = xplane::encode(&xplane::Rpos::default());
        assert_eq!(detect(&x), Some(Protocol::XPlane));
        let f = fgfs::encode(&fgfs::FdmPose::default());
        assert_eq!(detect(&f), Some(Protocol::Fgfs));
        for v in cigi::CigiVersion::ALL {
            let c = cigi::IgControl::default().encode_as(v, ByteOrder::Big);
            assert_eq!(detect(&c), Some(Protocol::Cigi), "{v}");
        }
        assert_eq!(detect(&[1, 20, 3, 0]), None, "IG Control of neither size");
        let f25 = fgfs::encode_v25(&fgfs::FdmPose::default());
        assert_eq!(detect(&f25), Some(Protocol::Fgfs));
        assert_eq!(detect(&f25[..100]), Some(Protocol::Fgfs), "by its version");
        assert!(decode(ProtocolChoice::Auto, &f25).is_ok());
        // A native terrain query is not a pose: detection leaves it to `native::is_query`.
        let q = native::encode_query(
            9,
            &crate::query::TerrainRequest::HeightOfTerrain {
                at: pose().position,
            },
        );
        assert!(native::is_query(&q) && !native::is_query(&n));
        assert_eq!(detect(&q), None);
        let e = decode(ProtocolChoice::Auto, &q).unwrap_err();
        assert_eq!(e.reason(), DropReason::Unknown, "{e}");
        let a = native::encode_reply(
            9,
            &crate::query::TerrainReply::HeightOfTerrain(crate::query::Answer::NoTerrain),
        );
        assert_eq!(detect(&a), None);
        assert_eq!(detect(b"hello"), None);
        assert_eq!(detect(&[]), None);
        assert_eq!(
            decode(ProtocolChoice::Auto, b"hello").unwrap_err().reason(),
            DropReason::Unknown
        );
        // A configured protocol refuses the others.
        let e = decode(ProtocolChoice::Only(Protocol::Aerie), &x).unwrap_err();
        assert_eq!(e.reason(), DropReason::Unknown, "{e}");
    }

    #[test]
    fn protocol_names_parse() {
        for p in Protocol::ALL {
            assert_eq!(
                p.name().parse::<ProtocolChoice>(),
                Ok(ProtocolChoice::Only(p))
            );
        }
        assert_eq!("AUTO".parse::<ProtocolChoice>(), Ok(ProtocolChoice::Auto));
        assert!("dis".parse::<ProtocolChoice>().unwrap_err().contains("dis"));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4096))]

        /// Random bytes never panic any decoder (auto-detected or forced).
        #[test]
        fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
            let _ = decode(ProtocolChoice::Auto, &bytes);
            for p in Protocol::ALL {
                let _ = decode_as(p, &bytes);
            }
            let _ = native::decode_query(&bytes);
            let _ = native::decode_reply(&bytes);
        }

        /// Random bodies behind each protocol's real header never panic either (reaching past
        /// the magic/size checks into field decoding).
        #[test]
        fn random_bodies_never_panic(
            body in prop::collection::vec(any::<u8>(), 0..600),
            which in 0usize..8,
            len_hint in prop::sample::select(vec![69usize, 132, 408, 552, 24, 16, 72, 76, 84, 104, 0]),
        ) {
            let mut bytes = match which {
                0 => native::MAGIC.to_vec(),
                1 => vec![1, 24, 3, 0, 0, 0, 0x80, 0x00],
                2 => b"RPOS4".to_vec(),
                3 => fgfs::VERSION.to_be_bytes().to_vec(),
                4 => fgfs::VERSION_25.to_be_bytes().to_vec(),
                5 => native::QUERY_MAGIC.to_vec(),
                6 => native::REPLY_MAGIC.to_vec(),
                _ => vec![1, 16, 3, 0, 0, 0, 0x00, 0x80],
            };
            bytes.extend_from_slice(&body);
            if len_hint > 0 {
                bytes.resize(len_hint, 0);
            }
            let _ = decode(ProtocolChoice::Auto, &bytes);
            let _ = cigi::decode(&bytes);
            let _ = native::decode_query(&bytes);
            let _ = native::decode_reply(&bytes);
        }
    }
}
