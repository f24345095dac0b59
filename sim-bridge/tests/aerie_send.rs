//! The `aerie-send` binary end to end: it sends the scripted flight it is given, in every
//! protocol, to a real receiver on loopback (and into shared memory); each received pose is
//! the script's pose at the packet's time; bad input is one line and exit code 2.

use std::net::SocketAddr;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use aerie_sim_bridge::geodesy::{Geodetic, LocalTangentPlane};
use aerie_sim_bridge::script::Waypoints;
use aerie_sim_bridge::shm::{ShmRead, ShmReader};
use aerie_sim_bridge::udp::{CigiReply, UdpConfig, UdpReceiver};
use aerie_sim_bridge::{PosePosition, PoseReader};

const PATH: &str = "# t,x,y,z,h,p,r\n0,100,200,1500,350,0,0\n1,300,200,1600,10,4,-10\n";

fn send(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aerie-send"))
        .args(args)
        .output()
        .expect("run aerie-send")
}

fn receiver() -> (UdpReceiver, PoseReader) {
    UdpReceiver::spawn(UdpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        cigi_reply: CigiReply::ToSender,
        ..UdpConfig::default()
    })
    .unwrap()
}

fn wait_accepted(rx: &UdpReceiver, n: u64) {
    let t = Instant::now();
    while rx.stats().accepted < n {
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "timed out: {:?}",
            rx.stats()
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn write_path(dir: &Path) -> String {
    let p = dir.join("path.csv");
    std::fs::write(&p, PATH).unwrap();
    p.display().to_string()
}

/// Every protocol: `--count` packets at `--rate` arrive, all accepted, the last one is the
/// script pose at t = (count − 1)/rate within 1 mm / 0.001° (f32 angles: 1e-4°), frame
/// counters start at `--start-frame`, and the JSON summary agrees.
#[test]
fn every_protocol_delivers_the_scripted_flight() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_path(dir.path());
    let script = Waypoints::parse(PATH, "p").unwrap();
    let origin = Geodetic::new(47.26, 11.35, 600.0);
    let ltp = LocalTangentPlane::new(origin);
    for proto in ["native", "cigi", "xplane", "fgfs"] {
        let (rx, mut reader) = receiver();
        let to = rx.local_addr().to_string();
        let json = dir.path().join(format!("{proto}.json"));
        let out = send(&[
            "--path",
            &path,
            "--protocol",
            proto,
            "--to",
            &to,
            "--rate",
            "20",
            "--count",
            "15",
            "--start-frame",
            "100",
            "--origin",
            "47.26,11.35,600",
            "--as-fast-as-possible",
            "--quiet",
            "--json",
            json.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{proto}: {out:?}");
        assert!(stdout.contains("sent 15 "), "{proto}: {stdout}");
        // Back to back on loopback: the receiver may lose none (15 datagrams).
        wait_accepted(&rx, 15);
        let got = reader.latest().expect("a pose").latest.pose;
        let want = script.sample(14.0 / 20.0);
        let enu = got.position.to_enu(&ltp);
        let err = (enu - glam::DVec3::from_array(want.position)).length();
        assert!(err < 1e-3, "{proto}: position off by {err} m");
        for i in 0..3 {
            let d = (got.attitude_deg[i] - want.attitude_deg[i] + 540.0).rem_euclid(360.0) - 180.0;
            assert!(d.abs() < 1e-4, "{proto}: angle {i} off by {d}°");
        }
        if matches!(proto, "native" | "cigi") {
            assert_eq!(got.frame, 114, "{proto}");
            assert!((got.sim_time_s - 0.7).abs() < 1e-9, "{proto}");
        }
        if proto == "fgfs" {
            // --log: one row per packet with the wire pose, exact (shortest round trip).
            let log = dir.path().join("fgfs.csv");
            let (rx2, _r2) = receiver();
            let to2 = rx2.local_addr().to_string();
            let out = send(&[
                "--path",
                &path,
                "--protocol",
                "fgfs",
                "--to",
                &to2,
                "--rate",
                "20",
                "--count",
                "3",
                "--origin",
                "47.26,11.35,600",
                "--as-fast-as-possible",
                "--quiet",
                "--log",
                log.to_str().unwrap(),
            ]);
            assert!(out.status.success(), "{out:?}");
            let text = std::fs::read_to_string(&log).unwrap();
            let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
            assert_eq!(rows.len(), 4, "{text}");
            assert_eq!(rows[0][6], "lat_deg");
            let last = &rows[3];
            let want = script.sample(0.1);
            let g = ltp.enu_to_geodetic(glam::DVec3::from_array(want.position));
            assert_eq!(last[6].parse::<f64>().unwrap(), g.lat_deg, "{text}");
            assert_eq!(last[7].parse::<f64>().unwrap(), g.lon_deg, "{text}");
            assert_eq!(last[3].parse::<f64>().unwrap(), want.position[0], "{text}");
            assert_eq!(last[15], "1");
        }
        let j: String = std::fs::read_to_string(&json).unwrap();
        assert!(
            j.contains("\"sent\":15") && j.contains("\"last_frame\":114"),
            "{j}"
        );
        if proto == "cigi" {
            // The sender counts the Start of Frame answers it saw before it finished (any
            // number: nothing ticks an IG frame here), and says so. The port's IG session
            // took every message and answers once per IG frame, not once per message.
            assert!(stdout.contains("Start of Frame answers"), "{stdout}");
            let link = rx.ig_link();
            assert_eq!(link.stats().messages, 15);
            let frame = aerie_sim_bridge::ig::IgFrame::default();
            link.begin_frame(&frame, &aerie_sim_bridge::query::NoTerrain);
            assert_eq!(rx.stats().replies, 1, "{:?}", rx.stats());
        }
    }
}

/// Native without an origin sends the local frame exactly, with the path's derivative as
/// velocity; realtime pacing spreads the packets over the script time.
#[test]
fn native_local_frame_with_velocity_paced_in_real_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_path(dir.path());
    let (rx, mut reader) = receiver();
    let to = rx.local_addr().to_string();
    let t0 = Instant::now();
    let out = send(&["--path", &path, "--to", &to, "--rate", "20", "--quiet"]);
    let took = t0.elapsed();
    assert!(out.status.success(), "{out:?}");
    // Default length = the path's duration, both ends: 0, 0.05, …, 1.0 s → 21 packets.
    wait_accepted(&rx, 21);
    // Paced: the last packet is due 1 s after the first (a lower bound, not a timing assert).
    assert!(took >= Duration::from_millis(950), "{took:?}");
    let p = reader.latest().unwrap().latest.pose;
    assert_eq!(
        p.position,
        PosePosition::LocalEnu {
            x: 300.0,
            y: 200.0,
            z: 1600.0
        }
    );
    assert_eq!(p.frame, 21);
    // At t = 1 s (the end, held) the velocity is 0; one packet earlier it was the segment's.
    assert_eq!(p.velocity_enu, Some([0.0; 3]));
    let (rx2, mut reader2) = receiver();
    let to2 = rx2.local_addr().to_string();
    let out = send(&[
        "--path", &path, "--to", &to2, "--count", "3", "--rate", "10", "--quiet",
    ]);
    assert!(out.status.success());
    wait_accepted(&rx2, 3);
    let p = reader2.latest().unwrap().latest.pose;
    assert_eq!(p.velocity_enu, Some([200.0, 0.0, 100.0]));
    assert_eq!(p.angular_rates_deg_s, Some([20.0, 4.0, -10.0]));
}

#[test]
fn shared_memory_gets_the_last_pose() {
    let dir = tempfile::tempdir().unwrap();
    let shm = dir.path().join("pose");
    let out = send(&[
        "--straight",
        "0,0,1000,90,-3,0,50",
        "--protocol",
        "shm",
        "--shm-name",
        shm.to_str().unwrap(),
        "--count",
        "11",
        "--rate",
        "10",
        "--as-fast-as-possible",
        "--quiet",
    ]);
    assert!(out.status.success(), "{out:?}");
    let mut r = ShmReader::open(&shm).unwrap();
    let ShmRead::New { pose, .. } = r.read() else {
        panic!("no pose in {}", shm.display())
    };
    // 10 packets after the first = 1 s at 50 m/s east.
    let PosePosition::LocalEnu { x, y, z } = pose.position else {
        panic!("{pose:?}")
    };
    assert!(
        (x - 50.0).abs() < 1e-9 && y.abs() < 1e-9 && z == 1000.0,
        "{pose:?}"
    );
    assert_eq!(pose.frame, 11);
    assert_eq!(pose.attitude_deg, [90.0, -3.0, 0.0]);
}

/// Bad input: one line on stderr naming the problem, exit code 2, nothing sent.
#[test]
fn bad_input_is_one_line_and_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "0,0,0,0,0,0,0\n# ok\n1,2,x,4,5,6,7\n").unwrap();
    let bad = bad.display().to_string();
    let good = write_path(dir.path());
    let cases: &[(&[&str], &str)] = &[
        (&["--path", &bad], "bad.csv:3: y_m"),
        (&["--path", "/nonexistent/p.csv"], "/nonexistent/p.csv"),
        (&["--path", &good, "--to", "not an address"], "--to"),
        (&["--path", &good, "--protocol", "cigi"], "--origin"),
        (&["--path", &good, "--protocol", "fgfs"], "--origin"),
        (&["--path", &good, "--protocol", "dis"], "dis"),
        (&["--path", &good, "--rate", "0"], "--rate"),
        (&["--path", &good, "--origin", "95,0,0"], "--origin"),
        (
            &["--path", &good, "--seconds", "1", "--count", "2"],
            "not both",
        ),
        (&["--straight", "1,2,3"], "--straight"),
        (&["--path", &good, "--bogus"], "--bogus"),
        (&[], "--path"),
    ];
    for (args, needle) in cases {
        let out = send(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

/// A multicast destination works with the sending interface pinned to loopback.
#[test]
fn sends_to_a_multicast_group() {
    let group = "239.255.71.3".parse().unwrap();
    let (rx, mut reader) = UdpReceiver::spawn(UdpConfig {
        bind: "0.0.0.0:0".parse().unwrap(),
        multicast: Some(group),
        multicast_interface: "127.0.0.1".parse().unwrap(),
        ..UdpConfig::default()
    })
    .unwrap();
    let to = SocketAddr::new(group.into(), rx.local_addr().port()).to_string();
    let out = send(&[
        "--straight",
        "0,0,1000,0,0,0,10",
        "--to",
        &to,
        "--multicast-if",
        "127.0.0.1",
        "--count",
        "5",
        "--as-fast-as-possible",
        "--quiet",
    ]);
    assert!(out.status.success(), "{out:?}");
    wait_accepted(&rx, 5);
    assert_eq!(reader.latest().unwrap().latest.pose.frame, 5);
}

/// The sender speaks the receivers' vocabulary: `--help` names the protocol words and flags of
/// `aerie run` / `aerie listen` (`native`, not the old `aerie`), and the old word still sends
/// native packets.
#[test]
fn help_uses_the_receivers_words_and_the_old_protocol_word_still_works() {
    let out = send(&["--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for word in [
        "--protocol native|cigi|xplane|fgfs|shm",
        "--shm-name",
        "--multicast-if",
        "--to",
    ] {
        assert!(help.contains(word), "{word} missing from\n{help}");
    }
    assert!(!help.contains("aerie|"), "{help}");

    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("send.json");
    let (rx, _reader) = receiver();
    let to = rx.local_addr().to_string();
    let out = send(&[
        "--straight",
        "0,0,1000,0,0,0,10",
        "--protocol",
        "aerie",
        "--to",
        &to,
        "--count",
        "2",
        "--as-fast-as-possible",
        "--quiet",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    wait_accepted(&rx, 2);
    let summary = std::fs::read_to_string(&json).unwrap();
    assert!(summary.contains("\"protocol\":\"native\""), "{summary}");
}
