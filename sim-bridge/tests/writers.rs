//! The simulator-side writers shipped for shared memory — the C header and the Python example —
//! produce files the Rust reader accepts. Each test skips (with a note) when its tool (`cc`,
//! `python3`) is not installed.

use std::path::{Path, PathBuf};
use std::process::Command;

use aerie_sim_bridge::shm::{ShmRead, ShmReader};
use aerie_sim_bridge::PosePosition;

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

const C_WRITER: &str = r#"
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>
#include "aerie_pose.h"
int main(int argc, char **argv) {
    if (argc != 2) return 3;
    int fd = open(argv[1], O_RDWR | O_CREAT, 0644);
    if (fd < 0 || ftruncate(fd, AERIE_POSE_SIZE) != 0) return 1;
    struct aerie_pose *p = mmap(NULL, AERIE_POSE_SIZE, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (p == MAP_FAILED) return 1;
    aerie_pose_init(p);
    for (int k = 1; k <= 3; k++) {
        aerie_pose_begin(p);
        p->flags = AERIE_POSE_VELOCITY | AERIE_POSE_RATES;
        p->frame = 1000 + k;
        p->sim_time_s = 12.5;
        p->position[0] = 47.25; p->position[1] = 11.5; p->position[2] = 2500.0;
        p->attitude_deg[0] = 270.0; p->attitude_deg[1] = -3.0; p->attitude_deg[2] = 15.0;
        p->velocity_enu[0] = -100.0; p->velocity_enu[1] = 5.0; p->velocity_enu[2] = 1.0;
        p->rates_deg_s[0] = 2.0; p->rates_deg_s[1] = 0.0; p->rates_deg_s[2] = -1.0;
        aerie_pose_end(p);
    }
    struct aerie_pose copy;
    return aerie_pose_read(p, &copy, 10) && copy.frame == 1003 ? 0 : 2;
}
"#;

#[test]
fn c_header_writer_is_read_back() {
    if !have("cc") {
        eprintln!("skipped: no C compiler (`cc`)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("writer.c");
    let exe = dir.path().join("writer");
    std::fs::write(&src, C_WRITER).unwrap();
    let out = Command::new("cc")
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-O2", "-I"])
        .arg(manifest_dir().join("include"))
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "aerie_pose.h does not compile cleanly:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let file = dir.path().join("pose");
    let status = Command::new(&exe).arg(&file).status().unwrap();
    assert!(status.success(), "C writer failed: {status}");
    let p = read_new(&file);
    assert_eq!(p.frame, 1003);
    assert_eq!(
        p.position,
        PosePosition::Geodetic {
            lat_deg: 47.25,
            lon_deg: 11.5,
            alt_m: 2500.0
        }
    );
    assert_eq!(p.attitude_deg, [270.0, -3.0, 15.0]);
    assert_eq!(p.velocity_enu, Some([-100.0, 5.0, 1.0]));
    assert_eq!(p.angular_rates_deg_s, Some([2.0, 0.0, -1.0]));
    p.validate().unwrap();
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
