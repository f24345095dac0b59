//! `aerie fly --channels` (issue 7 item 5): every channel of a preset rendered offscreen from one
//! pose per frame, per-channel PNGs, and a stitched panorama whose pixels come from the
//! channels' own pixels — with no gap at the seams. Run in-process through the CLI (validation
//! on: the command itself fails on any validation message).

use std::path::{Path, PathBuf};

use aerie::app::cli::{run, Cli};
use aerie::app::commands::fly::plan_channels;
use aerie::tools::panorama::{canvas_for, PanoramaChannel, PanoramaMap, MAX_CANVAS, NO_CHANNEL};
use clap::Parser;

/// wall3's 1920×1080 channels at 1/12: 160×90.
const SCALE: &str = "0.0833333333";

fn fly(args: &[&str]) -> Result<(), (i32, String)> {
    let cli = Cli::try_parse_from(std::iter::once("aerie").chain(args.iter().copied()))
        .map_err(|e| (2, e.to_string()))?;
    run(cli).map_err(|f| (f.code, f.message))
}

fn png(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8();
    (img.width(), img.height(), img.into_raw())
}

/// The demo DEM copied into `dir` (the command writes its bake next to the dataset).
fn demo_copy(dir: &Path) -> PathBuf {
    let p = dir.join("N47E011.hgt.zip");
    std::fs::copy(aerie_tests::demo_dem(), &p).unwrap();
    p
}

#[test]
fn wall3_channels_and_panorama_from_one_pose() {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_copy(dir.path());
    let out = dir.path().join("out");
    let wall3 = aerie_tests::repo_root().join("config/presets/wall3.toml");
    let s = |p: &Path| p.display().to_string();
    fly(&[
        "fly",
        "--dem",
        &s(&dem),
        "--channels",
        &s(&wall3),
        "--channel-scale",
        SCALE,
        "--frames",
        "2",
        "--validate",
        "--out",
        &s(&out),
    ])
    .unwrap_or_else(|(c, m)| panic!("exit {c}: {m}"));

    let names = ["left", "centre", "right"];
    // Every channel's PNGs at 160×90 and a panorama per frame.
    let mut frames = Vec::new();
    for name in names {
        for f in 0..2 {
            let (w, h, _) = png(&out.join(name).join(format!("frame_{f:04}.png")));
            assert_eq!((w, h), (160, 90), "{name}");
        }
        frames.push(png(&out.join(name).join("frame_0001.png")).2);
    }
    let (pw, ph, pano) = png(&out.join("panorama_0001.png"));
    assert!(out.join("panorama_0000.png").is_file());

    // frames.csv: one row per frame per channel, the channel first.
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut lines = csv.lines();
    assert!(lines.next().unwrap().starts_with("channel,time_s,"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 2 * 3);
    for (k, row) in rows.iter().enumerate() {
        assert!(row.starts_with(&format!("{},", names[k % 3])), "{row}");
    }
    // summary.json lists the channels, one selection served them all, validation was on.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let listed: Vec<&str> = summary["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(listed, names);
    assert_eq!(summary["one_selection_for_all_channels"], true);
    assert_eq!(summary["validation"]["enabled"], true);
    assert_eq!(summary["validation"]["errors"], 0);
    assert_eq!(summary["panorama"]["canvas"]["width"], pw);
    assert_eq!(summary["panorama"]["canvas"]["height"], ph);

    // The same canvas and lookup from the public projection: every mapped panorama pixel
    // (off the border lines) equals its channel's pixel.
    let (_, chans) = plan_channels(&wall3, SCALE.parse().unwrap()).unwrap();
    let pcs: Vec<PanoramaChannel> = chans
        .iter()
        .map(|c| PanoramaChannel::new(&c.channel, c.size))
        .collect();
    let canvas = canvas_for(&pcs, MAX_CANVAS);
    assert_eq!((canvas.width, canvas.height), (pw, ph));
    let map = PanoramaMap::new(&pcs, canvas);
    let px = |img: &[u8], w: u32, x: u32, y: u32| -> [u8; 4] {
        let o = ((y * w + x) * 4) as usize;
        [img[o], img[o + 1], img[o + 2], img[o + 3]]
    };
    let mut checked = [0u32; 3];
    for k in (0..map.sources.len()).step_by(97) {
        let Some(src) = map.sources[k] else {
            assert_eq!(px(&pano, pw, k as u32 % pw, k as u32 / pw), NO_CHANNEL);
            continue;
        };
        if map.border[k] {
            continue;
        }
        let (i, j) = (k as u32 % pw, k as u32 / pw);
        let c = src.channel as usize;
        assert_eq!(
            px(&pano, pw, i, j),
            px(&frames[c], 160, src.x, src.y),
            "canvas ({i}, {j}) from {} ({}, {})",
            names[c],
            src.x,
            src.y
        );
        checked[c] += 1;
    }
    assert!(checked.iter().all(|&n| n >= 60), "{checked:?}");

    // The seam between left and centre (azimuth −30°): in every row where that direction is
    // seen at all (near the top and bottom the frusta's corners curve away from the canvas
    // rows and nobody sees it), the first centre pixel directly follows the last left pixel
    // and no dark-grey pixel lies between them.
    let seam = ((-30.0 - canvas.az0_deg) / canvas.az_span_deg * pw as f64) as usize;
    let mut seam_rows = 0;
    for j in 0..ph {
        let row = &map.sources[(j * pw) as usize..((j + 1) * pw) as usize];
        if row[seam].is_none() {
            continue;
        }
        seam_rows += 1;
        let l = row.iter().rposition(|s| s.is_some_and(|s| s.channel == 0));
        let c = row.iter().position(|s| s.is_some_and(|s| s.channel == 1));
        let (l, c) = (l.expect("left in the row"), c.expect("centre in the row"));
        assert_eq!(c, l + 1, "row {j}: gap between left ({l}) and centre ({c})");
        assert!(
            l.abs_diff(seam) <= 1,
            "row {j}: seam at {l}, expected {seam}"
        );
        for i in l..=c {
            assert_ne!(px(&pano, pw, i as u32, j), NO_CHANNEL, "row {j} col {i}");
        }
    }
    assert!(seam_rows as u32 >= ph * 4 / 5, "{seam_rows} of {ph} rows");
}

#[test]
fn bad_channel_configs_are_one_line_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let s = |p: &Path| p.display().to_string();
    // The DEM is never read: the config is checked first.
    let dem = dir.path().join("none.hgt");
    let run_with = |cfg: &Path, extra: &[&str]| {
        let (d, c, o) = (s(&dem), s(cfg), s(&out));
        let mut args = vec!["fly", "--dem", &d, "--channels", &c, "--out", &o];
        args.extend_from_slice(extra);
        fly(&args).expect_err("bad input")
    };
    let (code, msg) = run_with(&dir.path().join("missing.toml"), &[]);
    assert_eq!(code, 2);
    assert!(msg.contains("missing.toml") && !msg.contains('\n'), "{msg}");

    let dup = dir.path().join("dup.toml");
    std::fs::write(
        &dup,
        "[[channel]]\nname = \"a\"\nwindow = { width = 64, height = 36 }\n\
         [[channel]]\nname = \"a\"\nwindow = { width = 64, height = 36 }\n",
    )
    .unwrap();
    let (code, msg) = run_with(&dup, &[]);
    assert_eq!(code, 2);
    assert!(
        msg.starts_with(&format!("{}:5:", dup.display())) && msg.contains("channel[1].name"),
        "{msg}"
    );

    let none = dir.path().join("none.toml");
    std::fs::write(&none, "[render]\nsize = \"64x36\"\n").unwrap();
    let (code, msg) = run_with(&none, &[]);
    assert_eq!(code, 2);
    assert!(msg.contains("no [[channel]]"), "{msg}");

    let wall3 = aerie_tests::repo_root().join("config/presets/wall3.toml");
    let (code, msg) = run_with(&wall3, &["--channel-scale", "0"]);
    assert_eq!(code, 2);
    assert!(msg.starts_with("--channel-scale: 0"), "{msg}");
    assert!(!out.exists(), "nothing written on bad input");
}

#[test]
fn channel_flights_keep_their_folder_rules_and_summaries_through_failed_writes() {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_copy(dir.path());
    let out = dir.path().join("out");
    let cfg = dir.path().join("two.toml");
    std::fs::write(
        &cfg,
        "[[channel]]\nname = \"a\"\nresolution = \"48x32\"\nview = { heading = -30.0 }\n\
         frustum = { hfov = 60.0 }\n\
         [[channel]]\nname = \"b\"\nresolution = \"48x32\"\nview = { heading = 30.0 }\n\
         frustum = { hfov = 60.0 }\n",
    )
    .unwrap();
    let s = |p: &Path| p.display().to_string();
    let (d, c, o) = (s(&dem), s(&cfg), s(&out));
    let run_with = |frames: &str, extra: &[&str]| {
        let mut args = vec![
            "fly",
            "--dem",
            &d,
            "--channels",
            &c,
            "--frames",
            frames,
            "--out",
            &o,
        ];
        args.extend_from_slice(extra);
        fly(&args)
    };
    run_with("3", &[]).unwrap_or_else(|(c, m)| panic!("exit {c}: {m}"));
    assert!(out.join("b/frame_0002.png").is_file() && out.join("panorama_0002.png").is_file());

    // A used folder is refused, naming it and --overwrite.
    let (code, msg) = run_with("1", &[]).expect_err("used folder");
    assert_eq!(code, 2);
    assert!(msg.contains(&o) && msg.contains("--overwrite"), "{msg}");

    // With --overwrite a shorter flight leaves no stale frame; frame 0's panorama cannot be
    // written (a folder stands in its place), and the summary still says so.
    std::fs::remove_file(out.join("panorama_0000.png")).unwrap();
    std::fs::create_dir_all(out.join("panorama_0000.png/x")).unwrap();
    let (code, msg) = run_with("1", &["--overwrite"]).expect_err("a failed write");
    assert_eq!(code, 1, "{msg}");
    assert!(
        msg.starts_with("frame 0: ") && msg.contains(&s(&out.join("panorama_0000.png"))),
        "{msg}"
    );
    for ch in ["a", "b"] {
        assert!(out.join(ch).join("frame_0000.png").is_file(), "{ch}");
        for f in 1..3 {
            assert!(
                !out.join(ch).join(format!("frame_{f:04}.png")).exists(),
                "{ch} {f}"
            );
        }
    }
    assert!(!out.join("panorama_0001.png").exists() && !out.join("panorama_0002.png").exists());
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2, "header + 1 frame × 2 channels");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["frames"], 1);
    assert_eq!(summary["pngs"], 2);
    assert_eq!(summary["panorama"]["pngs"], 0);
    assert_eq!(summary["failed_frames"], serde_json::json!([0]));
}
