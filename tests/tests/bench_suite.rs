//! `aerie bench --suite`: a tiny suite (one generated dataset, one short flight, two settings
//! per mode, 160×90) runs end to end on lavapipe; its combined report has the ratio table, a
//! row per baseline × metric, a curve point per configuration, a folder per flight; and every
//! ratio in it is what the two curves in `curves.csv` give — recomputed here independently
//! (efficient points, log–log interpolation, largest ratio over the common errors).

use std::collections::HashMap;
use std::path::Path;

const SUITE: &str = r#"
[run]
size = "160x90"
fov = 90.0
frames = 3
warmup = 1
fps = 10.0
modes = ["bounded", "clipmap", "distance", "cdlod"]
tau = [1.0, 4.0]
clipmap_n = [129, 257]
distance_scale = [0.5, 2.0]
cdlod_range = [2.0, 8.0]

[[dataset]]
name = "mixed"
generate = { kind = "mixed", size = 513, spacing = 30.0, seed = 3 }

[[flight]]
name = "follow"
kind = "follow"
agl = 150.0
speed = 80.0
pitch = -10.0
"#;

fn aerie(args: &[&str]) -> Result<(), aerie::app::failure::Failure> {
    use clap::Parser as _;
    let mut v = vec!["aerie"];
    v.extend_from_slice(args);
    let cli = aerie::app::cli::Cli::try_parse_from(v).expect("arguments parse");
    aerie::app::cli::run(cli)
}

/// CSV text → rows of column name → cell.
/// Runs `aerie bench` on a copy of the demo DEM in a temporary folder with `args` (besides
/// `--dem`, `--size 160x90`, `--oracle-nodes 0` and `--out`); the folder (kept alive by the
/// returned guard) and the output folder.
fn bench_demo(args: &[&str]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(aerie_tests::demo_dem(), &dem).unwrap();
    let out = dir.path().join("out");
    let mut all = vec!["bench", "--dem", dem.to_str().unwrap()];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--size", "160x90", "--oracle-nodes", "0"]);
    all.extend_from_slice(&["--out", out.to_str().unwrap()]);
    aerie(&all).map_err(|f| f.message).expect("bench runs");
    (dir, out)
}

fn table(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), head.len(), "{}: {l}", path.display());
            head.iter()
                .cloned()
                .zip(cells.iter().map(|c| c.to_string()))
                .collect()
        })
        .collect()
}

/// The efficient points of (error, cost), error ascending.
fn efficient(mut p: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    p.retain(|&(e, c)| e.is_finite() && c.is_finite() && e > 0.0 && c > 0.0);
    p.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let mut out: Vec<(f64, f64)> = Vec::new();
    for q in p {
        if out.last().is_none_or(|l| q.1 < l.1) {
            out.push(q);
        }
    }
    out
}

/// Cost at `e` by log–log interpolation; None outside the points.
fn read(c: &[(f64, f64)], e: f64) -> Option<f64> {
    if c.is_empty() || e < c[0].0 || e > c[c.len() - 1].0 {
        return None;
    }
    for w in c.windows(2) {
        if e >= w[0].0 && e <= w[1].0 {
            let t = (e.ln() - w[0].0.ln()) / (w[1].0.ln() - w[0].0.ln());
            return Some((w[0].1.ln() + t * (w[1].1.ln() - w[0].1.ln())).exp());
        }
    }
    c.iter().find(|p| p.0 == e).map(|p| p.1)
}

#[test]
fn a_tiny_suite_reports_ratios_read_off_its_curves() {
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("tiny.toml");
    std::fs::write(&suite, SUITE).unwrap();
    let out = dir.path().join("out");
    // `aerie bench --suite <suite> --out <out>` and more flags.
    let bench = |extra: &[&str]| {
        let mut args = vec![
            "bench",
            "--suite",
            suite.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        aerie(&args)
    };
    bench(&[]).map_err(|f| f.message).unwrap();

    // One folder per flight with its own bench report, and the flight's waypoints.
    for f in [
        "summary.md",
        "summary.csv",
        "triangles_vs_error.png",
        "time_vs_error.png",
    ] {
        assert!(out.join("mixed-follow").join(f).is_file(), "{f}");
    }
    let waypoints = std::fs::read_to_string(out.join("flights/mixed-follow.csv")).unwrap();
    assert_eq!(waypoints.lines().filter(|l| !l.starts_with('#')).count(), 5);

    // A curve point per configuration: 2 per mode.
    let curves = table(&out.join("curves.csv"));
    assert_eq!(curves.len(), 8);
    for mode in ["bounded", "clipmap", "distance", "cdlod"] {
        assert_eq!(
            curves.iter().filter(|r| r["mode"] == mode).count(),
            2,
            "{mode}"
        );
    }
    let points = |mode: &str, err: &str, cost: &str| -> Vec<(f64, f64)> {
        curves
            .iter()
            .filter(|r| r["mode"] == mode)
            .map(|r| (r[err].parse().unwrap_or(f64::NAN), r[cost].parse().unwrap()))
            .collect()
    };

    // A row per baseline × metric, each the interpolation of its two curves.
    let ratios = table(&out.join("ratios.csv"));
    assert_eq!(ratios.len(), 9);
    let mut in_range = 0;
    for r in &ratios {
        let (err, cost) = match r["metric"].as_str() {
            "triangles_at_max_error" => ("max_error_px", "triangles_median"),
            "triangles_at_p99_error" => ("p99_error_px", "triangles_median"),
            "frame_ms_at_max_error" => ("max_error_px", "frame_ms_median"),
            m => panic!("unknown metric {m}"),
        };
        let ours = efficient(points("bounded", err, cost));
        let base = efficient(points(&r["baseline"], err, cost));
        let (lo, hi) = (
            ours[0].0.max(base[0].0),
            ours[ours.len() - 1].0.min(base[base.len() - 1].0),
        );
        let expect = ours
            .iter()
            .chain(&base)
            .filter(|p| p.0 >= lo && p.0 <= hi)
            .filter_map(|p| Some((read(&ours, p.0)? / read(&base, p.0)?, p.0)))
            .max_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
        match expect {
            Some((ratio, at)) => {
                let got: f64 = r["ratio"].parse().expect("a ratio in range");
                let got_at: f64 = r["at_error_px"].parse().unwrap();
                assert!(
                    (got - ratio).abs() <= 1e-9 * ratio && got_at == at,
                    "{r:?}: expected {ratio} at {at}"
                );
                in_range += 1;
            }
            None => {
                assert!(r["ratio"].is_empty(), "{r:?}: no common error");
                // Apart: bounded across the gap when the curve below is the cheaper one.
                let (o, b) = (ours[ours.len() - 1], base[0]);
                let (bo, bb) = (base[base.len() - 1], ours[0]);
                let bound = if o.0 < b.0 && o.1 < b.1 {
                    Some(("upper", o.1 / b.1))
                } else if bo.0 < bb.0 && bo.1 < bb.1 {
                    Some(("lower", bb.1 / bo.1))
                } else {
                    None
                };
                match bound {
                    Some((kind, ratio)) => {
                        let got: f64 = r["bound_ratio"].parse().expect("a bound");
                        assert!(
                            r["bound"] == kind && (got - ratio).abs() <= 1e-9 * ratio,
                            "{r:?}: expected the {kind} bound {ratio}"
                        );
                        in_range += 1;
                    }
                    None => assert!(r["note"].contains("out of range"), "{r:?}"),
                }
            }
        }
    }

    // The table: a column per baseline × metric, the flight's row and the geometric means.
    let md = std::fs::read_to_string(out.join("suite.md")).unwrap();
    for col in ["clipmap tri @max", "distance tri @p99", "cdlod time @max"] {
        assert!(md.contains(col), "{col}");
    }
    let row = md
        .lines()
        .find(|l| l.starts_with("| mixed-follow |"))
        .expect("the flight's row");
    assert_eq!(row.matches('|').count(), 11, "{row}");
    assert_eq!(row.matches('×').count(), in_range, "{row}");
    assert!(md.contains("| **geometric mean** |"));
    assert!(md.contains("frames over τ + 0.5 px"));

    // A used folder is refused without --overwrite, naming it.
    let e = bench(&[]).unwrap_err();
    assert_eq!(e.code, 2);
    assert!(
        e.message.contains("--out") && e.message.contains("not empty"),
        "{}",
        e.message
    );

    // --resume takes the flight from its record instead of flying it again (its results.csv is
    // not rewritten) and writes the same combined report.
    let results = out.join("mixed-follow/results.csv");
    let modified = |p: &Path| std::fs::metadata(p).unwrap().modified().unwrap();
    let read = |name: &str| std::fs::read_to_string(out.join(name)).unwrap();
    let (flown, md, ratios) = (modified(&results), read("suite.md"), read("ratios.csv"));
    let resume = || bench(&["--resume"]).map_err(|f| f.message).unwrap();
    resume();
    assert_eq!(modified(&results), flown, "the flight was flown again");
    assert_eq!(read("suite.md"), md);
    assert_eq!(read("ratios.csv"), ratios);
    // Other settings: the record does not match, the flight is flown again with them.
    std::fs::write(&suite, SUITE.replace("frames = 3", "frames = 2")).unwrap();
    resume();
    assert_ne!(modified(&results), flown);
    let summary = table(&out.join("mixed-follow/summary.csv"));
    assert!(summary.iter().all(|r| r["frames"] == "2"), "{summary:?}");
    assert!(read("suite.md").contains("2 measured frames"));
}

/// A bad suite is refused before anything runs, naming the file, line and key.
#[test]
fn a_bad_suite_names_its_key() {
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("bad.toml");
    std::fs::write(&suite, SUITE.replace("agl = 150.0", "agl = -150.0")).unwrap();
    let out = dir.path().join("out");
    let e = aerie(&[
        "bench",
        "--suite",
        suite.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap_err();
    assert_eq!(e.code, 2);
    assert!(
        e.message.contains("bad.toml:21:7: flight[0].agl"),
        "{}",
        e.message
    );
    assert!(!out.exists(), "nothing written");
}

/// `aerie bench --feature-costs`: the first configuration is drawn again with each look
/// feature off (land cover/sky/atmosphere, normal maps); features.csv has the base and a row
/// per feature with the terrain pass's GPU time measured on every frame, summary.md the table.
#[test]
fn feature_costs_draw_the_first_configuration_with_each_feature_off() {
    let (_dir, out) = bench_demo(&[
        "--modes",
        "bounded,clipmap",
        "--tau",
        "2",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--no-image-error",
        "--feature-costs",
    ]);
    let rows = table(&out.join("features.csv"));
    let off: Vec<&str> = rows.iter().map(|r| r["feature_off"].as_str()).collect();
    assert_eq!(
        off,
        ["none", "look_plain", "no_normal_maps", "normals_gpu"],
        "{rows:?}"
    );
    for r in &rows {
        assert_eq!(r["configuration"], "bounded τ=2", "{r:?}");
        assert_eq!(r["frames"], "3", "{r:?}");
        let ms: f64 = r["gpu_terrain_ms_median"].parse().unwrap();
        assert!(ms.is_finite() && ms > 0.0, "{r:?}");
    }
    // The variants are not configurations of the report.
    let summary = table(&out.join("summary.csv"));
    assert_eq!(summary.len(), 2, "{summary:?}");
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("## What each feature costs"), "{md}");
    assert!(md.contains("| normal maps |"), "{md}");
}

/// `--no-holes` measures the image-space error without drawing the `full` reference: no
/// reference lane, every frame's error measured, zero holes, and the report says why.
#[test]
fn no_holes_measures_the_error_without_the_full_reference() {
    let (_dir, out) = bench_demo(&[
        "--modes",
        "bounded",
        "--tau",
        "1",
        "--frames",
        "3",
        "--warmup",
        "0",
        "--no-holes",
    ]);
    let rows = table(&out.join("results.csv"));
    assert_eq!(
        rows.len(),
        3,
        "one configuration, no reference lane: {rows:?}"
    );
    for r in &rows {
        assert_eq!(r["mode"], "bounded", "{r:?}");
        let measured: u64 = r["img_measured_px"].parse().unwrap();
        assert!(measured > 0, "{r:?}");
        let max: f64 = r["img_confirmed_max_px"].parse().unwrap();
        assert!(max.is_finite() && max <= 1.5, "{r:?}");
        assert_eq!(r["img_holes_px"], "0", "{r:?}");
    }
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("Holes not measured (`--no-holes`"), "{md}");
}

/// `--settle`: every configuration renders the first pose until nothing is late or pending
/// before the measured frames; summary.md says how many frames each took, and a configuration
/// that filled starts the flight with no late tile.
#[test]
fn settle_fills_every_configuration_before_the_first_frame() {
    let (_dir, out) = bench_demo(&[
        "--modes",
        "bounded,clipmap",
        "--tau",
        "0.5",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--settle",
        "12",
        "--no-image-error",
    ]);
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    let line = md
        .lines()
        .find(|l| l.contains("start-up fill (at most 12 frames"))
        .unwrap_or_else(|| panic!("no start-up line: {md}"));
    for label in ["bounded τ=0.5", "clipmap"] {
        let frames: u32 = line
            .split(&format!("{label} "))
            .nth(1)
            .and_then(|t| t.split([',', ' ']).next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{label} filled, with its frame count: {line}"));
        assert!((1..=12).contains(&frames), "{line}");
    }
    for r in table(&out.join("results.csv")) {
        assert_eq!(r["warmup"], "0");
        assert_eq!(
            (r["tiles_late"].as_str(), r["cells_pending"].as_str()),
            ("0", "0"),
            "{r:?}"
        );
    }
}

/// `--replays`: every configuration flies the measured frames again by fresh renderers; the
/// plans do not depend on timing, so every replay does each frame's work again (none differs),
/// and each frame keeps the least of its times, never more than its first flight's.
#[test]
fn replays_fly_the_same_frames_again_and_keep_each_frames_least_time() {
    let (_dir, out) = bench_demo(&[
        "--modes",
        "bounded,clipmap,cdlod",
        "--tau",
        "1",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--settle",
        "8",
        "--replays",
        "3",
        "--no-image-error",
    ]);
    let rows = table(&out.join("results.csv"));
    assert_eq!(rows.len(), 12, "3 configurations × 4 frames: {rows:?}");
    let mut from_replay = 0;
    for r in &rows {
        assert_eq!(
            (r["replays_same"].as_str(), r["replays_differed"].as_str()),
            ("3", "0"),
            "every replay drew the same selection, triangles and uploads: {r:?}"
        );
        let kept: u32 = r["replay_kept"].parse().unwrap();
        assert!(kept < 3, "{r:?}");
        let (ms, first): (f64, f64) = (
            r["frame_ms"].parse().unwrap(),
            r["frame_ms_first"].parse().unwrap(),
        );
        // frame_ms_first is written to 3 decimals, frame_ms too.
        assert!(ms <= first + 1e-3, "the least time kept: {r:?}");
        if kept > 0 && r["warmup"] == "0" {
            from_replay += 1;
        }
    }
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    let line = md
        .lines()
        .find(|l| l.contains("replays: the measured frames flown 3 times"))
        .unwrap_or_else(|| panic!("no replays line: {md}"));
    assert!(
        line.contains(&format!("{from_replay} of 9 frames timed by a replay"))
            && line.contains("0 with a replay that did other work"),
        "{line}"
    );
}

/// `--replays` takes 1 to 20 flights; 0 or 21 is refused by the command line, naming the flag.
#[test]
fn replays_outside_one_to_twenty_are_refused_naming_the_flag() {
    use clap::Parser as _;
    let parse = |replays: &str| {
        aerie::app::cli::Cli::try_parse_from([
            "aerie",
            "bench",
            "--dem",
            "x.hgt",
            "--out",
            "o",
            "--replays",
            replays,
        ])
        .map(|_| ())
    };
    for bad in ["0", "21", "two"] {
        let err = parse(bad).expect_err(bad);
        assert!(err.to_string().contains("--replays"), "{bad}: {err}");
    }
    parse("20").expect("20 replays parse");
}

/// `--tile-sizes`: every tiled mode is drawn once per tile size (tessellation once), each
/// renderer with its own tiles (more, smaller nodes over the same ground) and its own bake,
/// bounded within τ + 0.5 px and every node the oracle checks within its bound at either size;
/// a size the renderer cannot draw, or a patch that does not divide into it, is refused naming
/// the flag.
#[test]
fn tile_sizes_draw_every_tiled_mode_with_each_size() {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(aerie_tests::demo_dem(), &dem).unwrap();
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        let mut all = vec!["bench", "--dem", dem.to_str().unwrap()];
        all.extend_from_slice(&["--size", "160x90", "--frames", "2", "--warmup", "0"]);
        all.extend_from_slice(&["--out", out.to_str().unwrap(), "--overwrite"]);
        all.extend_from_slice(extra);
        aerie(&all)
    };
    run(&[
        "--modes",
        "bounded,cdlod,tess",
        "--tau",
        "1",
        "--cdlod-range",
        "4",
        "--tess-density",
        "0.5",
        "--tile-sizes",
        "17,9",
        "--oracle-nodes",
        "64",
    ])
    .map_err(|f| f.message)
    .expect("bench runs");
    let rows = table(&out.join("results.csv"));
    let mut configs: Vec<&str> = Vec::new();
    for r in &rows {
        if !configs.contains(&r["config"].as_str()) {
            configs.push(&r["config"]);
        }
    }
    assert_eq!(
        configs,
        [
            "bounded_tau1",
            "bounded_tau1_m9",
            "cdlod_k4",
            "cdlod_k4_m9",
            "tess_x0.5"
        ],
        "{rows:?}"
    );
    let instances = |config: &str| -> Vec<u64> {
        rows.iter()
            .filter(|r| r["config"] == config)
            .map(|r| r["instances"].parse().unwrap())
            .collect()
    };
    // A node of 9 vertices covers a quarter of one of 17: the same ground takes more of them.
    for (whole, small) in [
        ("bounded_tau1", "bounded_tau1_m9"),
        ("cdlod_k4", "cdlod_k4_m9"),
    ] {
        for (a, b) in instances(whole).iter().zip(instances(small)) {
            assert!(b > *a, "{small} {b} instances, {whole} {a}");
        }
    }
    for r in rows.iter().filter(|r| r["mode"] == "bounded") {
        let max: f64 = r["img_confirmed_max_px"].parse().unwrap();
        assert!(max <= 1.5, "within τ + 0.5 px: {r:?}");
        let (oracle, bound): (f64, f64) = (
            r["oracle_max_px"].parse().unwrap(),
            r["bound_max_px"].parse().unwrap(),
        );
        assert!(r["oracle_nodes"].parse::<u32>().unwrap() > 0, "{r:?}");
        assert!(
            oracle <= bound * (1.0 + 1e-6) + 1e-9 && bound <= 1.0 + 1e-9,
            "{r:?}"
        );
    }
    for (args, flag) in [
        (
            &["--modes", "bounded", "--tile-sizes", "17,12"][..],
            "--tile-sizes",
        ),
        (
            &["--modes", "bounded", "--tile-sizes", "9.5"][..],
            "--tile-sizes 9.5: 9.5 is not a whole number",
        ),
        (
            &["--modes", "bounded", "--tile-sizes", "33"][..],
            "--patch 129: with tiles of 33",
        ),
        (
            &[
                "--modes",
                "clipmap",
                "--clipmap-n",
                "129,257",
                "--patch",
                "257",
                "--tile-sizes",
                "33",
            ][..],
            "--clipmap-n 129,257: with tiles of 33",
        ),
    ] {
        let e = run(args).expect_err(flag);
        assert_eq!(e.code, 2, "{}", e.message);
        assert!(e.message.starts_with(flag), "{flag}: {}", e.message);
    }
}
