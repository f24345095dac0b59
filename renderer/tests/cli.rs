//! The `aerie` binary end to end: a good render writes a PNG and a JSON summary; every bad
//! input gives a one-line error naming the file or argument, exit code 2, and no PNG.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn aerie(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aerie"))
        .args(args)
        .env("RUST_LOG", "error")
        .output()
        .expect("run aerie")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A small raw f32 DEM (a hill) with its sidecar.
fn raw_dem(dir: &Path) -> PathBuf {
    let (w, h) = (65usize, 49usize);
    let mut bytes = Vec::new();
    for r in 0..h {
        for c in 0..w {
            let (dx, dy) = (c as f32 - 32.0, r as f32 - 24.0);
            let z = 100.0 + 400.0 * (-(dx * dx + dy * dy) / 300.0).exp();
            bytes.extend_from_slice(&z.to_le_bytes());
        }
    }
    let p = dir.join("hill.f32");
    std::fs::write(&p, bytes).unwrap();
    std::fs::write(
        dir.join("hill.f32.json"),
        format!(r#"{{"width": {w}, "height": {h}, "spacing_x": 25.0, "spacing_y": 25.0}}"#),
    )
    .unwrap();
    p
}

#[test]
fn render_writes_png_and_json_summary() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let out = dir.path().join("frame.png");
    let o = aerie(&[
        "render",
        "--dem",
        dem.to_str().unwrap(),
        "--camera",
        "800,-400,900,0,-30,0",
        "--size",
        "96x64",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&out).unwrap().to_rgba8();
    assert_eq!((img.width(), img.height()), (96, 64));
    // Terrain in the lower half differs from the sky at the top.
    assert_ne!(img.get_pixel(48, 0), img.get_pixel(48, 60));
    let line = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(line.trim()).expect("one JSON line");
    assert!(v["triangles"].as_u64().unwrap() > 0);
    assert!(v["device"].as_str().unwrap().len() > 1);
    assert!(v["gpu_ms"].as_f64().unwrap() >= 0.0);
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("frame.json")).unwrap())
            .unwrap();
    assert_eq!(saved, v);
}

#[test]
fn fly_writes_frames_csv_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let out = dir.path().join("flight");
    let o = aerie(&[
        "fly",
        "--dem",
        dem.to_str().unwrap(),
        "--frames",
        "4",
        "--every",
        "2",
        "--speed",
        "50",
        "--size",
        "64x36",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("frame_0000.png").is_file() && out.join("frame_0002.png").is_file());
    assert!(!out.join("frame_0001.png").exists());
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 5, "header + 4 frames");
    assert!(rows[0].starts_with("time_s,x_m,y_m"));
    assert!(rows[0].contains("tiles_late") && rows[0].contains("gpu_terrain_ms"));
    // The camera moves east-north-east at 50 m/s, 30 fps.
    let x = |r: &str| r.split(',').nth(1).unwrap().parse::<f64>().unwrap();
    let dx = x(rows[2]) - x(rows[1]);
    assert!(
        (dx - 50.0 / 30.0 * 70f64.to_radians().sin()).abs() < 0.02,
        "dx {dx}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["frames"], 4);
    assert_eq!(summary["pngs"], 2);
}

/// Runs `render` with one bad part and checks: exit code 2, one line naming `needle`, no PNG.
fn assert_bad(dem: &Path, camera: &str, size: &str, needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let o = aerie(&[
        "render",
        "--dem",
        dem.to_str().unwrap(),
        "--camera",
        camera,
        "--size",
        size,
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(
        o.status.code(),
        Some(2),
        "expected exit 2 for {needle}: {err}"
    );
    assert!(
        err.contains(needle),
        "message should name {needle:?}: {err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "one-line error: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no file left behind"
    );
}

#[test]
fn bad_inputs_exit_2_with_a_named_reason_and_no_png() {
    let dir = tempfile::tempdir().unwrap();
    let good = raw_dem(dir.path());
    let cam = "0,0,500,0,-10,0";

    assert_bad(&dir.path().join("missing.hgt"), cam, "64x36", "missing.hgt");

    let truncated = dir.path().join("N47E011.hgt");
    std::fs::write(&truncated, vec![0u8; 1000]).unwrap();
    assert_bad(&truncated, cam, "64x36", "N47E011.hgt");

    let rgb = dir.path().join("rgb.png");
    image::RgbImage::new(4, 4).save(&rgb).unwrap();
    assert_bad(&rgb, cam, "64x36", "rgb.png");

    let nan = dir.path().join("nan.f32");
    let mut bytes: Vec<u8> = [1.0f32, 2.0, f32::NAN, 4.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    bytes.extend_from_slice(&[0u8; 0]);
    std::fs::write(&nan, &bytes).unwrap();
    std::fs::write(
        dir.path().join("nan.f32.json"),
        r#"{"width": 2, "height": 2}"#,
    )
    .unwrap();
    assert_bad(&nan, cam, "64x36", "byte offset 8");

    assert_bad(&good, "1,2,3", "64x36", "--camera");
    assert_bad(&good, "0,0,nan,0,0,0", "64x36", "--camera");
    assert_bad(&good, cam, "64x0", "--size");
    assert_bad(&good, cam, "wide", "--size");
}

#[test]
fn fly_follows_waypoints_and_names_bad_lines() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let path = dir.path().join("path.csv");
    std::fs::write(
        &path,
        "# t,x,y,z,h,p,r\n0,100,100,800,45,-20,0\n1,700,500,900,90,-10,5\n",
    )
    .unwrap();
    let out = dir.path().join("wp");
    let args = |p: &Path| {
        vec![
            "fly".to_string(),
            "--dem".into(),
            dem.display().to_string(),
            "--path".into(),
            p.display().to_string(),
            "--frames".into(),
            "3".into(),
            "--fps".into(),
            "2".into(),
            "--size".into(),
            "48x32".into(),
            "--out".into(),
            out.display().to_string(),
        ]
    };
    let a = args(&path);
    let o = aerie(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let row1: Vec<f64> = csv
        .lines()
        .nth(2)
        .unwrap()
        .split(',')
        .take(5)
        .map(|v| v.parse().unwrap())
        .collect();
    // t = 0.5 s: halfway between the waypoints.
    assert_eq!(row1[0], 0.5);
    assert!(
        (row1[1] - 400.0).abs() < 0.01 && (row1[2] - 300.0).abs() < 0.01,
        "{row1:?}"
    );
    assert!((row1[4] - 67.5).abs() < 0.01, "heading {row1:?}");

    std::fs::write(&path, "0,0,0,0,0,0,0\n1,2,oops,0,0,0,0\n").unwrap();
    let o = aerie(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("path.csv:2:") && err.contains("y_m"), "{err}");
}

/// A temporary copy of the embedded Inn valley tile: the CLI writes its `.aerie-bake` next to
/// the dataset, which must not be the repository's assets folder.
fn inn_valley_copy(dir: &Path) -> PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/dem/N47E011.hgt.zip");
    let dst = dir.join("N47E011.hgt.zip");
    std::fs::copy(&src, &dst).expect("copy the Inn valley DEM");
    dst
}

#[test]
fn render_and_fly_create_nested_output_folders() {
    let dir = tempfile::tempdir().unwrap();
    let dem = inn_valley_copy(dir.path());
    let still = dir.path().join("out/a/b/still.png");
    let o = aerie(&[
        "render",
        "--dem",
        dem.to_str().unwrap(),
        "--camera",
        "30500,12000,4500,0,-15,0",
        "--size",
        "64x36",
        "--out",
        still.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&still).unwrap().to_rgba8();
    assert_eq!((img.width(), img.height()), (64, 36));
    assert!(dir.path().join("out/a/b/still.json").is_file());

    let flight = dir.path().join("out/c/d/flight");
    let o = aerie(&[
        "fly",
        "--dem",
        dem.to_str().unwrap(),
        "--frames",
        "2",
        "--size",
        "64x36",
        "--out",
        flight.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "frame_0000.png",
        "frame_0001.png",
        "frames.csv",
        "summary.json",
    ] {
        assert!(flight.join(f).is_file(), "{f} written");
    }
}

#[test]
fn an_output_folder_that_cannot_be_made_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let blocker = dir.path().join("not-a-folder");
    std::fs::write(&blocker, b"x").unwrap();
    let out = blocker.join("x.png");
    let o = aerie(&[
        "render",
        "--dem",
        dem.to_str().unwrap(),
        "--camera",
        "800,-400,900,0,-30,0",
        "--size",
        "64x36",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("cannot create folder {}", blocker.display())),
        "{err}"
    );
}
