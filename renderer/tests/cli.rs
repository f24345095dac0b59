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
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("frame.png.json")).unwrap())
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
    assert!(dir.path().join("out/a/b/still.png.json").is_file());

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

/// `fly` over the hill: `frames` frames at 48×32 into `out`, plus `extra` arguments.
fn fly_hill(dem: &Path, out: &Path, frames: u32, extra: &[&str]) -> Output {
    let frames = frames.to_string();
    let mut args = vec![
        "fly",
        "--dem",
        dem.to_str().unwrap(),
        "--frames",
        &frames,
        "--size",
        "48x32",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    aerie(&args)
}

fn summary_json(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn fly_refuses_a_used_folder_and_overwrite_clears_only_its_own_files() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let out = dir.path().join("flight");
    let o = fly_hill(&dem, &out, 3, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();
    let o = fly_hill(&dem, &out, 1, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&out.display().to_string()) && err.contains("--overwrite"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        out.join("frame_0002.png").is_file(),
        "a refusal removes nothing"
    );
    let o = fly_hill(&dem, &out, 1, &["--overwrite"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("frame_0000.png").is_file());
    for stale in ["frame_0001.png", "frame_0002.png"] {
        assert!(!out.join(stale).exists(), "stale {stale} removed");
    }
    assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "header + the new run's one frame");
    let s = summary_json(&out);
    assert_eq!(s["frames"], 1);
    assert_eq!(s["failed_frames"], serde_json::json!([]));
}

#[test]
fn a_frame_that_cannot_be_written_still_leaves_csv_and_summary_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let out = dir.path().join("flight");
    // A folder where frame 2's PNG goes: its write fails even for root (rename onto a folder),
    // and --overwrite keeps it (it is not a file an earlier fly wrote).
    std::fs::create_dir_all(out.join("frame_0002.png")).unwrap();
    std::fs::write(out.join("frame_0002.png/keep.txt"), b"x").unwrap();
    let o = fly_hill(&dem, &out, 4, &["--overwrite"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let bad = out.join("frame_0002.png").display().to_string();
    assert!(
        err.contains("frame 2: ") && err.contains(&bad) && err.contains("os error"),
        "names the first failed file and the OS reason: {err}"
    );
    assert!(err.contains("summary.json lists them"), "{err}");
    // The flight went on: later frames written, every frame in frames.csv.
    for f in ["frame_0000.png", "frame_0001.png", "frame_0003.png"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5, "header + 4 frames");
    let s = summary_json(&out);
    assert_eq!(s["frames"], 4);
    assert_eq!(s["pngs"], 3);
    assert_eq!(s["failed_frames"], serde_json::json!([2]));
    let files = s["failed_files"].as_array().unwrap();
    assert_eq!(files.len(), 1);
    assert_eq!(files[0]["file"], bad.as_str());
    assert!(
        files[0]["error"].as_str().unwrap().contains("os error"),
        "{files:?}"
    );
    // Nothing half-written is left next to the frames.
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
}

#[test]
fn render_writes_its_json_as_png_json_and_never_replaces_a_foreign_file() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let out = dir.path().join("notes.png");
    let notes = dir.path().join("notes.json");
    std::fs::write(&notes, b"{\"todo\": \"keep me\"}").unwrap();
    let render = || {
        aerie(&[
            "render",
            "--dem",
            dem.to_str().unwrap(),
            "--camera",
            "800,-400,900,0,-30,0",
            "--size",
            "48x32",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = render();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&notes).unwrap(), b"{\"todo\": \"keep me\"}");
    let json = dir.path().join("notes.png.json");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["triangles"].as_u64().unwrap() > 0);
    // Rendering again replaces its own summary.
    let o = render();
    assert!(o.status.success(), "{}", stderr(&o));
    // A file of that name it did not write is refused before rendering: exit 2, untouched.
    std::fs::write(&json, b"my own notes").unwrap();
    std::fs::remove_file(&out).unwrap();
    let o = render();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&json.display().to_string()), "{err}");
    assert_eq!(std::fs::read(&json).unwrap(), b"my own notes");
    assert!(!out.exists(), "no PNG when refused");
}

/// `bench` with one cheap configuration over the hill into `out`.
fn bench_hill(dem: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "bench",
        "--dem",
        dem.to_str().unwrap(),
        "--frames",
        "1",
        "--warmup",
        "0",
        "--modes",
        "clipmap",
        "--no-image-error",
        "--oracle-nodes",
        "0",
        "--size",
        "48x32",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    aerie(&args)
}

#[test]
fn bench_refuses_a_used_folder_and_still_writes_the_rest_when_a_file_fails() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let out = dir.path().join("bench");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("results.csv"), b"stale").unwrap();
    let o = bench_hill(&dem, &out, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&out.display().to_string()) && err.contains("--overwrite"),
        "{err}"
    );
    assert_eq!(std::fs::read(out.join("results.csv")).unwrap(), b"stale");
    // summary.csv cannot be written (a folder is in its place); everything else is.
    std::fs::create_dir_all(out.join("summary.csv/x")).unwrap();
    let o = bench_hill(&dem, &out, &["--overwrite"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let bad = out.join("summary.csv").display().to_string();
    assert!(err.contains(&bad) && err.contains("os error"), "{err}");
    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(
        results.lines().count() >= 2 && results != "stale",
        "{results}"
    );
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(
        md.contains("Files not written") && md.contains(&bad),
        "{md}"
    );
    assert!(out.join("time_vs_error.png").is_file());
}
