//! The sending side, as a simulator would do it: scripted-flight samples turned into poses and
//! datagrams of any protocol. Plain data decisions used by the `aerie-send` binary (which only
//! adds sockets, pacing and printing) and by tests.

use glam::DVec3;

use crate::codec::cigi::{EntityControl, IgControl, IG_MODE_OPERATE, MINOR_VERSION};
use crate::codec::{fgfs, native, xplane, ByteOrder, Protocol};
use crate::geodesy::{Geodetic, LocalTangentPlane};
use crate::pose::{Pose, PosePosition};
use crate::script::ScriptSample;

/// Where `aerie-send` puts the poses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SendProtocol {
    /// A UDP protocol.
    Udp(Protocol),
    /// The shared-memory file.
    Shm,
}

impl std::str::FromStr for SendProtocol {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.to_ascii_lowercase().as_str() {
            "native" | "aerie" => SendProtocol::Udp(Protocol::Aerie),
            "cigi" => SendProtocol::Udp(Protocol::Cigi),
            "xplane" | "x-plane" | "rpos" => SendProtocol::Udp(Protocol::XPlane),
            "fgfs" | "flightgear" => SendProtocol::Udp(Protocol::Fgfs),
            "shm" => SendProtocol::Shm,
            other => {
                return Err(format!(
                    "unknown protocol `{other}` (expected native, cigi, xplane, fgfs or shm)"
                ))
            }
        })
    }
}

impl SendProtocol {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SendProtocol::Udp(Protocol::Aerie) => "native",
            SendProtocol::Udp(p) => p.name(),
            SendProtocol::Shm => "shm",
        }
    }

    /// Whether the protocol can only carry WGS84 positions (so an `--origin` is needed to
    /// send a local script).
    pub fn needs_geodetic(self) -> bool {
        matches!(
            self,
            SendProtocol::Udp(Protocol::Cigi | Protocol::XPlane | Protocol::Fgfs)
        )
    }
}

/// Number of packets that cover `[0, seconds]` at `rate_hz`, both ends included (packet `i`
/// is sent for script time `i / rate_hz`). A tiny tolerance keeps `10 s × 60 Hz` at 601, not
/// 600 through rounding.
pub fn packet_count(seconds: f64, rate_hz: f64) -> u64 {
    if !(seconds >= 0.0 && rate_hz > 0.0) {
        return 0;
    }
    (seconds * rate_hz + 1e-6).floor() as u64 + 1
}

/// The pose sent for script time `t_s` with frame counter `frame`: local ENU as scripted, or —
/// with an origin — WGS84 through the origin's tangent plane, the velocity turned into the
/// ENU frame at the aircraft. The attitude is sent unchanged (relative to the script frame's
/// north; the meridian convergence to true north at the aircraft is < 0.1° within 10 km of
/// the origin at mid latitudes, and aerie's receiving side uses the same convention).
pub fn pose_for(
    sample: &ScriptSample,
    t_s: f64,
    frame: u64,
    origin: Option<&LocalTangentPlane>,
) -> Pose {
    let [x, y, z] = sample.position;
    let (position, velocity) = match origin {
        None => (PosePosition::LocalEnu { x, y, z }, sample.velocity),
        Some(ltp) => {
            let g = ltp.enu_to_geodetic(DVec3::new(x, y, z));
            let v_ecef = ltp.enu_axes() * DVec3::from_array(sample.velocity);
            let here = LocalTangentPlane::new(Geodetic::new(g.lat_deg, g.lon_deg, 0.0));
            let v = here.enu_axes().transpose() * v_ecef;
            (
                PosePosition::Geodetic {
                    lat_deg: g.lat_deg,
                    lon_deg: g.lon_deg,
                    alt_m: g.alt_m,
                },
                v.to_array(),
            )
        }
    };
    Pose {
        position,
        attitude_deg: sample.attitude_deg,
        sim_time_s: t_s,
        frame,
        velocity_enu: Some(velocity),
        angular_rates_deg_s: Some(sample.rates_deg_s),
    }
}

/// Byte order of the CIGI messages `aerie-send` writes (network order, like most hosts).
pub const CIGI_ORDER: ByteOrder = ByteOrder::Big;

/// The CIGI host message for `pose`: IG Control (host frame = `frame`, timestamp = sim time in
/// 10 µs ticks) followed by an Entity Control of the ownship (entity 0). `None` for a local
/// pose (CIGI carries only WGS84).
pub fn cigi_message(pose: &Pose, frame: u32) -> Option<Vec<u8>> {
    let PosePosition::Geodetic {
        lat_deg,
        lon_deg,
        alt_m,
    } = pose.position
    else {
        return None;
    };
    let [h, p, r] = pose.attitude_deg;
    let mut b = IgControl {
        ig_mode: IG_MODE_OPERATE,
        timestamp_valid: true,
        minor_version: MINOR_VERSION,
        host_frame: frame,
        // The timestamp wraps after 11.9 h, like a real host's.
        timestamp: (pose.sim_time_s * 1e5).round() as u64 as u32,
        ..IgControl::default()
    }
    .encode(CIGI_ORDER)
    .to_vec();
    b.extend(
        EntityControl {
            entity_id: crate::codec::cigi::OWNSHIP,
            entity_state: 1,
            alpha: 255,
            roll_deg: r as f32,
            pitch_deg: p as f32,
            yaw_deg: h as f32,
            lat_deg,
            lon_deg,
            alt_m,
            ..EntityControl::default()
        }
        .encode(CIGI_ORDER),
    );
    Some(b)
}

/// The datagram for `pose` in a UDP `protocol`, with sequence / frame counter `sequence`
/// (native sequence, CIGI host frame; RPOS and FGNetFDM carry none). `None` when the protocol
/// cannot carry the pose (a local pose in a geodetic-only protocol).
pub fn datagram(protocol: Protocol, pose: &Pose, sequence: u32) -> Option<Vec<u8>> {
    let geodetic = matches!(pose.position, PosePosition::Geodetic { .. });
    match protocol {
        Protocol::Aerie => Some(native::encode(pose, sequence).to_vec()),
        Protocol::Cigi => cigi_message(pose, sequence),
        Protocol::XPlane => {
            geodetic.then(|| xplane::encode(&xplane::Rpos::from_pose(pose, 0.0)).to_vec())
        }
        Protocol::Fgfs => geodetic.then(|| fgfs::encode(&fgfs::FdmPose::from_pose(pose)).to_vec()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::{decode, ProtocolChoice};
    use crate::script::Waypoints;

    fn ltp() -> LocalTangentPlane {
        LocalTangentPlane::new(Geodetic::new(47.0, 11.0, 500.0))
    }

    fn sample() -> ScriptSample {
        Waypoints::parse(
            "0,1000,-2000,1500,80,5,-10\n10,2000,-2000,1600,100,5,10\n",
            "p",
        )
        .unwrap()
        .sample(2.0)
    }

    #[test]
    fn counts_cover_both_ends() {
        assert_eq!(packet_count(10.0, 60.0), 601);
        assert_eq!(packet_count(0.0, 60.0), 1);
        assert_eq!(packet_count(0.05, 60.0), 4);
        assert_eq!(packet_count(-1.0, 60.0), 0);
        assert_eq!(packet_count(1.0, 0.0), 0);
    }

    #[test]
    fn protocols_parse_and_know_their_position_kind() {
        for name in ["native", "cigi", "xplane", "fgfs", "shm"] {
            let p: SendProtocol = name.parse().unwrap();
            assert_eq!(p.name(), name);
            assert_eq!(
                p.needs_geodetic(),
                matches!(name, "cigi" | "xplane" | "fgfs")
            );
        }
        assert!("dis".parse::<SendProtocol>().unwrap_err().contains("dis"));
    }

    /// Every protocol's datagram decodes back to the scripted pose: position through the
    /// origin within 1 mm, attitude within the wire's f32 precision.
    #[test]
    fn every_protocol_round_trips_the_scripted_pose() {
        let s = sample();
        let ltp = ltp();
        let geo = pose_for(&s, 2.0, 121, Some(&ltp));
        let local = pose_for(&s, 2.0, 121, None);
        assert_eq!(
            local.position,
            PosePosition::LocalEnu {
                x: 1200.0,
                y: -2000.0,
                z: 1520.0
            }
        );
        for p in Protocol::ALL {
            let bytes = datagram(p, &geo, 121).unwrap();
            let d = decode(ProtocolChoice::Auto, &bytes).unwrap();
            assert_eq!(d.protocol, p);
            let got = d.pose.unwrap();
            let back = got.position.to_enu(&ltp);
            assert!(
                (back - DVec3::from_array(s.position)).length() < 1e-3,
                "{p}: {back}"
            );
            for i in 0..3 {
                let da =
                    (got.attitude_deg[i] - s.attitude_deg[i] + 540.0).rem_euclid(360.0) - 180.0;
                assert!(da.abs() < 1e-4, "{p}: angle {i} {da}");
            }
            match p {
                Protocol::Aerie | Protocol::Cigi => assert_eq!(d.sequence, Some(121)),
                _ => assert_eq!(d.sequence, None),
            }
            if p != Protocol::Cigi {
                // The path's derivative travels along (f32 on RPOS / FGNetFDM).
                let v = got.velocity_enu.unwrap();
                let want = geo.velocity_enu.unwrap();
                for i in 0..3 {
                    assert!((v[i] - want[i]).abs() < 1e-3, "{p}: velocity {v:?}");
                }
            }
        }
        // Native carries the local frame, sim time and frame counter exactly.
        let d = native::decode(&datagram(Protocol::Aerie, &local, 7).unwrap()).unwrap();
        assert_eq!(d.pose, local);
        assert_eq!(d.sequence, 7);
        // Geodetic-only protocols refuse a local pose.
        assert!(datagram(Protocol::Cigi, &local, 1).is_none());
        assert!(datagram(Protocol::XPlane, &local, 1).is_none());
        assert!(datagram(Protocol::Fgfs, &local, 1).is_none());
    }

    #[test]
    fn geodetic_velocity_is_rotated_into_the_aircraft_frame() {
        // 100 km east of the origin the local east axis has turned (meridian convergence);
        // the speed is kept and the direction follows the aircraft's own ENU frame.
        let s = ScriptSample {
            position: [100_000.0, 0.0, 0.0],
            attitude_deg: [90.0, 0.0, 0.0],
            velocity: [100.0, 0.0, 0.0],
            rates_deg_s: [0.0; 3],
        };
        let p = pose_for(&s, 0.0, 1, Some(&ltp()));
        let v = p.velocity_enu.unwrap();
        assert!((DVec3::from_array(v).length() - 100.0).abs() < 1e-9);
        // Convergence ≈ Δlon · sin(lat) ≈ 1.3° · 0.73 ≈ 0.96°.
        let angle = v[1].atan2(v[0]).to_degrees();
        assert!(angle.abs() > 0.5 && angle.abs() < 1.5, "{angle}");
    }

    #[test]
    fn cigi_message_carries_frame_and_timestamp() {
        let pose = pose_for(&sample(), 2.5, 9, Some(&ltp()));
        let m = crate::codec::cigi::decode(&cigi_message(&pose, 9).unwrap()).unwrap();
        assert_eq!(m.ig_control.host_frame, 9);
        assert_eq!(m.ig_control.timestamp, 250_000);
        assert!(m.ig_control.timestamp_valid);
        assert!((m.ownship_pose().unwrap().sim_time_s - 2.5).abs() < 1e-9);
    }
}
