//! Sends a scripted flight (a level circle) to aerie over UDP, in any supported protocol —
//! what a flight simulator would send. For CIGI it also counts the IG's Start of Frame answers.
//!
//! ```sh
//! aerie listen --seconds 12 &
//! cargo run -p aerie-sim-bridge --example udp_sender -- --protocol cigi --rate 60 --seconds 10
//! ```
//!
//! Options: `--to ADDR` (127.0.0.1:47800), `--protocol aerie|cigi|xplane|fgfs` (aerie),
//! `--rate HZ` (60), `--seconds S` (10), `--lat DEG` (47.26), `--lon DEG` (11.35),
//! `--alt M` (3000), `--radius M` (3000), `--speed M/S` (120).

use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use aerie_sim_bridge::codec::cigi::{EntityControl, IgControl, StartOfFrame};
use aerie_sim_bridge::codec::{fgfs, native, xplane, ByteOrder};
use aerie_sim_bridge::{Pose, PosePosition, Protocol, ProtocolChoice};

struct Args {
    to: SocketAddr,
    protocol: Protocol,
    rate: f64,
    seconds: f64,
    lat: f64,
    lon: f64,
    alt: f64,
    radius: f64,
    speed: f64,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        to: "127.0.0.1:47800".parse().map_err(|e| format!("{e}"))?,
        protocol: Protocol::Aerie,
        rate: 60.0,
        seconds: 10.0,
        lat: 47.26,
        lon: 11.35,
        alt: 3000.0,
        radius: 3000.0,
        speed: 120.0,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or_else(|| format!("{flag}: missing value"))?;
        let num = |v: &str| v.parse::<f64>().map_err(|e| format!("{flag} {v}: {e}"));
        match flag.as_str() {
            "--to" => a.to = value.parse().map_err(|e| format!("--to {value}: {e}"))?,
            "--protocol" => {
                a.protocol = match value.parse::<ProtocolChoice>()? {
                    ProtocolChoice::Only(p) => p,
                    ProtocolChoice::Auto => return Err("--protocol: pick one protocol".into()),
                }
            }
            "--rate" => a.rate = num(&value)?,
            "--seconds" => a.seconds = num(&value)?,
            "--lat" => a.lat = num(&value)?,
            "--lon" => a.lon = num(&value)?,
            "--alt" => a.alt = num(&value)?,
            "--radius" => a.radius = num(&value)?,
            "--speed" => a.speed = num(&value)?,
            other => return Err(format!("unknown option {other}")),
        }
    }
    if !(a.rate > 0.0 && a.radius > 0.0 && a.seconds >= 0.0) {
        return Err("--rate and --radius must be positive, --seconds not negative".into());
    }
    Ok(a)
}

/// A level clockwise circle around the centre (spherical Earth is close enough for a demo).
fn circle(a: &Args, frame: u64) -> Pose {
    let t = frame as f64 / a.rate;
    let omega = a.speed / a.radius;
    let ang = omega * t;
    let (east, north) = (a.radius * ang.sin(), a.radius * ang.cos());
    let r_earth = 6_371_000.0;
    Pose {
        position: PosePosition::Geodetic {
            lat_deg: a.lat + (north / r_earth).to_degrees(),
            lon_deg: a.lon + (east / (r_earth * a.lat.to_radians().cos())).to_degrees(),
            alt_m: a.alt,
        },
        attitude_deg: [
            (ang.to_degrees() + 90.0).rem_euclid(360.0),
            0.0,
            (a.speed * a.speed / (9.80665 * a.radius))
                .atan()
                .to_degrees(),
        ],
        sim_time_s: t,
        frame,
        velocity_enu: Some([a.speed * ang.cos(), -a.speed * ang.sin(), 0.0]),
        angular_rates_deg_s: Some([omega.to_degrees(), 0.0, 0.0]),
    }
}

fn datagram(protocol: Protocol, pose: &Pose, seq: u32) -> Vec<u8> {
    match protocol {
        Protocol::Aerie => native::encode(pose, seq).to_vec(),
        Protocol::XPlane => xplane::encode(&xplane::Rpos::from_pose(pose, 0.0)).to_vec(),
        Protocol::Fgfs => fgfs::encode(&fgfs::FdmPose::from_pose(pose)).to_vec(),
        Protocol::Cigi => {
            let PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } = pose.position
            else {
                unreachable!("the demo flight is geodetic")
            };
            let [h, p, r] = pose.attitude_deg;
            let order = ByteOrder::Little;
            let mut b = IgControl {
                ig_mode: 1,
                timestamp_valid: true,
                minor_version: 3,
                host_frame: seq,
                timestamp: (pose.sim_time_s * 1e5) as u32,
                ..IgControl::default()
            }
            .encode(order)
            .to_vec();
            b.extend(
                EntityControl {
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
                .encode(order),
            );
            b
        }
    }
}

fn main() {
    let a = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("udp_sender: {e}");
            std::process::exit(2);
        }
    };
    let socket = UdpSocket::bind(if a.to.is_ipv4() {
        "0.0.0.0:0"
    } else {
        "[::]:0"
    })
    .expect("bind a local UDP socket");
    socket.set_nonblocking(true).expect("non-blocking socket");
    let start = Instant::now();
    let (mut frame, mut answers, mut buf) = (0u64, 0u64, [0u8; 64]);
    while frame as f64 / a.rate <= a.seconds {
        let pose = circle(&a, frame);
        if let Err(e) = socket.send_to(&datagram(a.protocol, &pose, frame as u32 + 1), a.to) {
            eprintln!("udp_sender: send to {}: {e}", a.to);
        }
        while let Ok((n, _)) = socket.recv_from(&mut buf) {
            if StartOfFrame::decode(&buf[..n]).is_ok() {
                answers += 1;
            }
        }
        frame += 1;
        let due = start + Duration::from_secs_f64(frame as f64 / a.rate);
        if let Some(d) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
    print!("sent {frame} {} datagrams to {}", a.protocol, a.to);
    if a.protocol == Protocol::Cigi {
        print!(", {answers} Start of Frame answers");
    }
    println!();
}
