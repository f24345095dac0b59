//! Absurd values end to end (issue 16 item 5, 6): through the `aerie` binary, a grid spacing of
//! 1e300 and oversized configs are bad input (exit 2, the key or limit named), and poses with
//! ±1.797e308 behind a valid CRC are dropped and counted as implausible, never drawn.

use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use aerie_sim_bridge::codec::native;
use aerie_sim_bridge::{Pose, PosePosition};
use aerie_tests::aerie_bin;

/// A flat 65×65 raw f32 grid with `sidecar` (the JSON text) next to it.
fn raw_dem(dir: &Path, sidecar: &str) -> PathBuf {
    let bytes: Vec<u8> = (0..65 * 65).flat_map(|_| 500f32.to_le_bytes()).collect();
    let p = dir.join("flat.f32");
    std::fs::write(&p, bytes).unwrap();
    std::fs::write(dir.join("flat.f32.json"), sidecar).unwrap();
    p
}

/// Runs `aerie args…`, returning the exit code and stderr.
fn aerie_exit(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(aerie_bin())
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("run aerie");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_spacing_of_1e300_is_bad_input_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(
        dir.path(),
        r#"{"width": 65, "height": 65, "spacing_x": 1e300, "spacing_y": 30}"#,
    );
    let png = dir.path().join("out.png");
    let (code, err) = aerie_exit(&[
        "render",
        "--dem",
        dem.to_str().unwrap(),
        "--camera",
        "900,900,1500,0,-10,0",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("flat.f32.json") && err.contains("spacing_x") && err.contains("1e300"),
        "{err}"
    );
    assert!(!png.exists(), "an image was written");
}

#[test]
fn oversized_configs_are_bad_input_naming_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path(), r#"{"width": 65, "height": 65}"#);
    let mut many = String::from("[render]\nsize = \"32x18\"\n");
    for i in 0..10_000 {
        many.push_str(&format!("[[channel]]\nname = \"c{i}\"\n"));
    }
    let many_path = dir.path().join("wall.toml");
    std::fs::write(&many_path, many).unwrap();
    let big_path = dir.path().join("big.toml");
    std::fs::write(&big_path, format!("#{}\n", "x".repeat(2 << 20))).unwrap();
    for (config, names) in [
        (many_path.to_str().unwrap(), "limit of 64"),
        (big_path.to_str().unwrap(), "1024 KiB limit"),
        ("/dev/zero", "1024 KiB limit"),
    ] {
        let out = dir.path().join("fly");
        let (code, err) = aerie_exit(&[
            "fly",
            "--dem",
            dem.to_str().unwrap(),
            "--channels",
            config,
            "--frames",
            "1",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, Some(2), "{config}: {err}");
        assert!(err.contains(config) && err.contains(names), "{err}");
    }
}

fn local(x: f64, frame: u64) -> Pose {
    Pose {
        position: PosePosition::LocalEnu {
            x,
            y: 900.0,
            z: 1500.0,
        },
        attitude_deg: [90.0, -5.0, 0.0],
        sim_time_s: frame as f64 / 60.0,
        frame,
        velocity_enu: None,
        angular_rates_deg_s: None,
    }
}

#[test]
fn absurd_native_poses_are_counted_and_never_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(
        dir.path(),
        r#"{"width": 65, "height": 65, "spacing_x": 30, "spacing_y": 30}"#,
    );
    let port = UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let to = format!("127.0.0.1:{port}");
    let (json, stats) = (dir.path().join("run.json"), dir.path().join("stats.csv"));
    let run = Command::new(aerie_bin())
        .args([
            "run",
            "--headless",
            "--frames",
            "5",
            "--size",
            "160x90",
            "--protocol",
            "native",
            "--max-extrapolation-ms",
            "0",
            "--wait-pose-s",
            "30",
            "--listen",
            &to,
            "--dem",
            dem.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn aerie run");
    // Every sequence number alternates: an outlier (±1.797e308 with a valid CRC), then a
    // plausible pose; the outliers must never reach a frame.
    let done = Arc::new(AtomicBool::new(false));
    let sender = {
        let (done, to) = (done.clone(), to.clone());
        std::thread::spawn(move || {
            let s = UdpSocket::bind("127.0.0.1:0").unwrap();
            let mut seq = 1u32;
            let mut f = 0u64;
            while !done.load(Ordering::Relaxed) && f < 60 * 60 {
                let sign = if f.is_multiple_of(2) { 1.0 } else { -1.0 };
                let _ = s.send_to(&native::encode(&local(sign * 1.797e308, f), seq), &to);
                seq += 1;
                let _ = s.send_to(&native::encode(&local(900.0, f), seq), &to);
                seq += 1;
                f += 1;
                std::thread::sleep(Duration::from_millis(16));
            }
        })
    };
    let out = run.wait_with_output().expect("wait for aerie run");
    done.store(true, Ordering::Relaxed);
    sender.join().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "exit {:?}: {err}", out.status.code());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let input = &summary["input"];
    let implausible = input["dropped"]["implausible"].as_u64().unwrap();
    assert!(implausible >= 1, "{input}");
    assert_eq!(
        input["dropped_total"].as_u64(),
        Some(implausible),
        "{input}"
    );
    let csv = std::fs::read_to_string(&stats).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let x = header.iter().position(|h| *h == "x_m").expect("x_m column");
    let mut rows = 0;
    for l in lines {
        let v: f64 = l.split(',').nth(x).unwrap().parse().unwrap();
        assert!(
            v.is_finite() && v.abs() < 1e4,
            "a frame drawn at x = {v}: {l}"
        );
        rows += 1;
    }
    assert_eq!(rows, 5, "{csv}");
}

/// Imagery that cannot be registered onto the terrain is bad input (exit 2) naming the file
/// and the reason, whether the terrain has no geo-reference or the raster lies elsewhere.
#[test]
fn imagery_that_cannot_be_registered_is_bad_input_naming_the_file() {
    use aerie::terrain::drape::{encode_geotiff, EncodeRef};
    let dir = tempfile::tempdir().unwrap();
    let far = dir.path().join("far.tif");
    let g = EncodeRef {
        epsg: 4326,
        west: 100.0,
        north: 10.0,
        dx: 0.001,
        dy: 0.001,
    };
    std::fs::write(&far, encode_geotiff(4, 4, 3, &[9; 48], Some(g)).unwrap()).unwrap();
    let flat = raw_dem(
        dir.path(),
        r#"{"width": 65, "height": 65, "spacing_x": 30, "spacing_y": 30}"#,
    );
    let inn = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(aerie_tests::demo_dem(), &inn).unwrap();
    let png = dir.path().join("out.png");
    for (dem, camera, why) in [
        (&flat, "900,900,800,0,-30,0", "no geo-reference"),
        (&inn, "30500,12000,4500,0,-15,0", "no overlap"),
    ] {
        let (code, err) = aerie_exit(&[
            "render",
            "--dem",
            dem.to_str().unwrap(),
            "--camera",
            camera,
            "--size",
            "64x36",
            "--imagery",
            far.to_str().unwrap(),
            "--out",
            png.to_str().unwrap(),
        ]);
        assert_eq!(code, Some(2), "{}: {err}", dem.display());
        assert!(err.contains("far.tif") && err.contains(why), "{err}");
        assert!(!png.exists(), "no picture is written for a refused run");
    }
}
