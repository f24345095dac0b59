//! The simulator-side writers shipped for shared memory — the C header (built as C99, C++11 and
//! C++17 with every warning an error) and the Python example — produce files the Rust reader
//! accepts, also while it polls them. Each test skips (with a note) when its tool (`gcc`,
//! `g++`, `python3`) is not installed.

use std::path::{Path, PathBuf};
use std::process::Command;

use aerie_sim_bridge::shm::{ShmRead, ShmReader};
use aerie_sim_bridge::{Pose, PosePosition};

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn have(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

fn read_new(path: &Path) -> aerie_sim_bridge::Pose {
    let mut r = ShmReader::open(path).expect("reader opens the writer's file");
    match r.read() {
        ShmRead::New { pose, seq, .. } => {
            assert_eq!(seq % 2, 0);
            pose
        }
        other => panic!("expected a pose, got {other:?}"),
    }
}

/// Pose k as `tests/c/shm_writer.c` writes it.
fn c_pose_k(k: u64) -> Pose {
    let x = k as f64;
    Pose {
        position: PosePosition::LocalEnu {
            x,
            y: -2.0 * x,
            z: 1000.0 + 0.5 * x,
        },
        attitude_deg: [(k % 360) as f64, (k % 170) as f64 - 85.0, -x / 1e4],
        sim_time_s: 0.001 * x,
        frame: k,
        velocity_enu: Some([1.0, 2.0, 3.0].map(|d| (k % 200) as f64 + d)),
        angular_rates_deg_s: (k % 2 == 0).then_some([(k % 30) as f64; 3]),
    }
}

/// Compiles `tests/c/shm_writer.c` with `compiler` (`-x c` or `-x c++` and `std`) with every
/// warning an error, runs it for `n` poses while a Rust reader polls the file, and checks
/// that every pose read is one the writer wrote, none was dropped, and the last is read.
fn c_family_writer_against_the_reader(compiler: &str, lang: &str, std: &str) {
    if !have(compiler) {
        eprintln!("skipped: no `{compiler}` (CI installs it: scripts/setup-debian.sh)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let exe = dir.path().join("writer");
    let out = Command::new(compiler)
        .args([
            "-x",
            lang,
            std,
            "-Wall",
            "-Wextra",
            "-pedantic",
            "-Werror",
            "-O2",
            "-I",
        ])
        .arg(manifest_dir().join("include"))
        .arg(manifest_dir().join("tests/c/shm_writer.c"))
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "aerie_pose.h does not compile cleanly with {compiler} {std}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    const N: u64 = 3_000;
    let file = dir.path().join("pose");
    let mut child = Command::new(&exe)
        .arg(&file)
        .arg(N.to_string())
        .spawn()
        .unwrap();
    let (mut reads, mut last, mut dropped) = (0u64, 0u64, Vec::new());
    let mut reader: Option<ShmReader> = None;
    let mut status = None;
    // Poll until the writer has exited and one more read followed its exit.
    loop {
        let exited = status.is_some();
        if reader.is_none() {
            reader = ShmReader::open(&file).ok();
        }
        if let Some(r) = reader.as_mut() {
            match r.read() {
                ShmRead::New { pose, .. } => {
                    assert_eq!(pose, c_pose_k(pose.frame), "{compiler} {std}: torn pose");
                    // >=: the writer republishes pose N after its corruption check.
                    assert!(pose.frame >= last, "{} after {last}", pose.frame);
                    last = pose.frame;
                    reads += 1;
                }
                ShmRead::Dropped(e) => dropped.push(e),
                _ => {}
            }
        }
        if exited {
            break;
        }
        status = child.try_wait().unwrap();
        std::thread::yield_now();
    }
    let status = status.unwrap();
    assert!(status.success(), "{compiler} {std} writer failed: {status}");
    // The writer's last act rewrote pose N after corrupting it (its own reader check).
    assert!(dropped.len() <= 1, "dropped {dropped:?}");
    assert_eq!(last, N, "the last pose was not read");
    eprintln!(
        "{compiler} {std}: {N} poses written, {reads} read, {} dropped",
        dropped.len()
    );
}

#[test]
fn c99_writer_from_the_header_is_read_back() {
    c_family_writer_against_the_reader("gcc", "c", "-std=c99");
}

#[test]
fn cxx11_writer_from_the_header_is_read_back() {
    c_family_writer_against_the_reader("g++", "c++", "-std=c++11");
}

#[test]
fn cxx17_writer_from_the_header_is_read_back() {
    c_family_writer_against_the_reader("g++", "c++", "-std=c++17");
}

#[test]
fn python_example_writer_is_read_back() {
    if !have("python3") {
        eprintln!("skipped: no python3");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("pose");
    let out = Command::new("python3")
        .arg(manifest_dir().join("examples/shm_writer.py"))
        .arg("--name")
        .arg(&file)
        .args([
            "--rate",
            "200",
            "--seconds",
            "0.1",
            "--lat",
            "45",
            "--lon",
            "7",
        ])
        .args(["--alt", "1500", "--radius", "2000", "--speed", "100"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "shm_writer.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let p = read_new(&file);
    p.validate().unwrap();
    // 21 poses (t = 0 … 0.1 s at 200 Hz): the last is frame 20 at t = 0.1 s.
    assert_eq!(p.frame, 20);
    assert!((p.sim_time_s - 0.1).abs() < 1e-12);
    let PosePosition::Geodetic {
        lat_deg,
        lon_deg,
        alt_m,
    } = p.position
    else {
        panic!("geodetic expected");
    };
    assert!((lat_deg - 45.0).abs() < 0.02 && (lon_deg - 7.0).abs() < 0.03);
    assert_eq!(alt_m, 1500.0);
    // Clockwise circle at 100 m/s, radius 2 km: heading rate 0.05 rad/s, right wing down.
    let rates = p.angular_rates_deg_s.unwrap();
    assert!((rates[0] - 0.05f64.to_degrees()).abs() < 1e-9);
    assert!(p.attitude_deg[2] > 0.0);
    let v = p.velocity_enu.unwrap();
    assert!(((v[0] * v[0] + v[1] * v[1]).sqrt() - 100.0).abs() < 1e-9);
}
