//! The sending side, as a simulator would do it: scripted-flight samples turned into poses and
//! datagrams of any protocol. Plain data decisions used by the `aerie-send` binary (which only
//! adds sockets, pacing and printing) and by tests.

use glam::DVec3;

use crate::codec::cigi::{
    fov_enable, view_enable, EntityControl, IgControl, ViewControl, ViewDefinition,
    IG_MODE_OPERATE, MINOR_VERSION,
};
use crate::codec::{fgfs, native, xplane, ByteOrder, Protocol};
use crate::geodesy::{Geodetic, LocalTangentPlane};
use crate::pose::{Pose, PosePosition};
use crate::script::ScriptSample;

/// `aerie-send`'s terrain queries (`--hot`, `--los`, `--los-vector`).
#[path = "send_query.rs"]
pub mod query;

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

fn numbers(flag: &str, v: &str, form: &str, counts: &[usize]) -> Result<Vec<f64>, String> {
    let bad = || format!("{flag} {v:?}: expected {form}");
    let n: Vec<f64> = v
        .split(',')
        .map(|s| s.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    if !counts.contains(&n.len()) {
        return Err(bad());
    }
    Ok(n)
}

fn view_id(flag: &str, v: &str, id: f64) -> Result<u16, String> {
    if id.fract() == 0.0 && (0.0..=65535.0).contains(&id) {
        Ok(id as u16)
    } else {
        Err(format!("{flag} {v:?}: view ID {id} is not 0..=65535"))
    }
}

/// `aerie-send --view id,heading,pitch,roll[,x,y,z]`: a CIGI View Control for view `id` of the
/// ownship (yaw = heading, degrees; x forward, y right, z down, metres; the offset fields are
/// enabled only when given). Values are sent as given: range checks are the IG's business.
pub fn parse_view_control(v: &str) -> Result<ViewControl, String> {
    const FORM: &str = "view_id,heading,pitch,roll[,x,y,z]";
    let n = numbers("--view", v, FORM, &[4, 7])?;
    let offset = n.get(4..7).map(|o| [o[0], o[1], o[2]]);
    Ok(ViewControl {
        view_id: view_id("--view", v, n[0])?,
        enable: view_enable::ROLL
            | view_enable::PITCH
            | view_enable::YAW
            | if offset.is_some() {
                view_enable::X | view_enable::Y | view_enable::Z
            } else {
                0
            },
        entity_id: crate::codec::cigi::OWNSHIP,
        offset_m: offset.unwrap_or_default().map(|x| x as f32),
        roll_pitch_yaw_deg: [n[3] as f32, n[2] as f32, n[1] as f32],
        ..ViewControl::default()
    })
}

/// `aerie-send --view-frustum id,left,right,bottom,top[,near,far]`: a CIGI View Definition for
/// view `id` (half-angles in degrees from the view axis, right and up positive; near/far in
/// metres enabled only when given).
pub fn parse_view_definition(v: &str) -> Result<ViewDefinition, String> {
    const FORM: &str = "view_id,left,right,bottom,top[,near,far]";
    let n = numbers("--view-frustum", v, FORM, &[5, 7])?;
    let near_far = n.get(5..7).map(|o| [o[0], o[1]]);
    let [near, far] = near_far.unwrap_or_default();
    Ok(ViewDefinition {
        view_id: view_id("--view-frustum", v, n[0])?,
        enable: fov_enable::LEFT
            | fov_enable::RIGHT
            | fov_enable::TOP
            | fov_enable::BOTTOM
            | if near_far.is_some() {
                fov_enable::NEAR | fov_enable::FAR
            } else {
                0
            },
        left_deg: n[1] as f32,
        right_deg: n[2] as f32,
        bottom_deg: n[3] as f32,
        top_deg: n[4] as f32,
        near_m: near as f32,
        far_m: far as f32,
        ..ViewDefinition::default()
    })
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
    fn view_flags_become_view_packets_the_ig_decodes() {
        let c = parse_view_control("5,33.25,-4.5,1.25,1.5,-0.5,-2").unwrap();
        let d = parse_view_definition("1,-20,25,-10,15,2,50000").unwrap();
        let mut m = cigi_message(&pose_for(&sample(), 0.0, 3, Some(&ltp())), 3).unwrap();
        m.extend(c.encode(CIGI_ORDER));
        m.extend(d.encode(CIGI_ORDER));
        let mut t = crate::codec::cigi::ViewTable::default();
        assert!(t.apply(&crate::codec::cigi::decode(&m).unwrap()));
        let v = t.get(5).unwrap();
        assert_eq!(v.roll_pitch_yaw_deg, [Some(1.25), Some(-4.5), Some(33.25)]);
        assert_eq!(v.offset_m, [Some(1.5), Some(-0.5), Some(-2.0)]);
        let f = t.get(1).unwrap();
        assert_eq!(f.half_angles_deg(), Some([-20.0, 25.0, 15.0, -10.0]));
        assert_eq!((f.near_m(), f.far_m()), (Some(2.0), Some(50000.0)));
        // Without the optional fields, they stay disabled.
        let c = parse_view_control("0,10,0,0").unwrap();
        assert_eq!(c.enable & 0x07, 0);
        let d = parse_view_definition("0,-1,1,-1,1").unwrap();
        assert_eq!(d.enable & 0x03, 0);
        for bad in [
            "5,1,2",
            "x,1,2,3",
            "5,1,2,3,4",
            "70000,1,2,3",
            "1.5,1,2,3",
            "5,nan,0,0",
        ] {
            let e = parse_view_control(bad).unwrap_err();
            assert!(e.starts_with("--view "), "{e}");
        }
        let e = parse_view_definition("1,2,3").unwrap_err();
        assert!(
            e.contains("view_id,left,right,bottom,top[,near,far]"),
            "{e}"
        );
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
