//! A bench suite file: datasets × flights and the run's settings, parsed and checked. Every
//! error is one line naming the file, the dotted key, its line:column when known, and why
//! (the style of `aerie_config`).
//!
//! ```toml
//! [run]                       # every key optional
//! size = "480x270"
//! fov = 90.0
//! frames = 24                 # measured frames per flight (+ warmup)
//! warmup = 3
//! settle = 30                 # start-up fill: at most 30 frames at the first pose (default 0)
//! replays = 3                 # fly the measured frames 3 times, each frame's fastest kept (default 1;
//!                              # `--replays` replaces it)
//! fps = 10.0
//! modes = ["bounded", "clipmap", "distance", "cdlod"]
//! tau = [0.5, 1, 2, 5]
//! clipmap_n = [129, 257, 513]
//! distance_scale = [0.5, 1, 2, 4]
//! cdlod_range = [2, 4, 8, 16]
//! tile_sizes = [17, 9]        # every tiled mode at each tile size (default: 17 only)
//! oracle_nodes = 0
//!
//! [[dataset]]
//! name = "inn"
//! path = "srtm3_single/N47E011.hgt.zip"   # relative to --data, else to the suite file
//!
//! [[dataset]]
//! name = "mixed"
//! generate = { kind = "mixed", size = 4097, spacing = 10.0, seed = 1 }
//!
//! [[flight]]
//! name = "cruise"
//! kind = "cruise"             # cruise | follow | approach | manoeuvre
//! heading = 70.0              # degrees from north (default 70)
//! speed = 250.0               # m/s
//! pitch = -12.0               # cruise, follow
//! agl = 3000.0                # cruise, manoeuvre: above the highest sample; follow: above ground
//! # approach: glide = 3.0, to_agl = 50.0; manoeuvre: pitch_range = [-60, 30], roll = 90
//! datasets = ["inn"]          # optional: only these datasets
//! ```

use serde::Deserialize;

use aerie_config::key_location;

use super::config::{check_tile_sizes, parse_modes, sizes_drawn, Sweeps};
use super::flights::{FlightKind, FlightSpec};
use crate::app::renderer_setup::{parse_view, patch_tiles_of};

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawRun {
    size: Option<String>,
    fov: Option<f64>,
    frames: Option<u32>,
    warmup: Option<u32>,
    settle: Option<u32>,
    replays: Option<u32>,
    fps: Option<f64>,
    modes: Option<Vec<String>>,
    tau: Option<Vec<f64>>,
    clipmap_n: Option<Vec<u32>>,
    distance_scale: Option<Vec<f64>>,
    cdlod_range: Option<Vec<f64>>,
    tess_density: Option<Vec<f64>>,
    tile_sizes: Option<Vec<u32>>,
    oracle_nodes: Option<u32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGenerate {
    kind: String,
    size: usize,
    spacing: f64,
    seed: Option<u64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDataset {
    name: String,
    path: Option<String>,
    generate: Option<RawGenerate>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFlight {
    name: String,
    kind: String,
    heading: Option<f64>,
    speed: Option<f64>,
    pitch: Option<f64>,
    agl: Option<f64>,
    glide: Option<f64>,
    to_agl: Option<f64>,
    pitch_range: Option<[f64; 2]>,
    roll: Option<f64>,
    datasets: Option<Vec<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSuite {
    #[serde(default)]
    run: RawRun,
    #[serde(default)]
    dataset: Vec<RawDataset>,
    #[serde(default)]
    flight: Vec<RawFlight>,
}

/// The settings every flight of the suite runs with.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    pub size: String,
    pub fov: f64,
    pub frames: u32,
    pub warmup: u32,
    /// `--settle`: at most this many start-up frames at the first pose.
    pub settle: u32,
    /// `--replays`: the measured frames flown this many times (1 to 20).
    pub replays: u32,
    pub fps: f64,
    /// As `--modes`, `--tau` take them.
    pub modes: String,
    pub tau: Vec<f64>,
    pub sweeps: Sweeps,
    pub oracle_nodes: u32,
}

/// Where a dataset comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum DatasetSource {
    /// A file or folder, relative to the data root unless absolute.
    Path(String),
    /// `aerie gen-dem` output.
    Generate {
        kind: String,
        size: usize,
        spacing: f64,
        seed: u64,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct DatasetSpec {
    pub name: String,
    pub source: DatasetSource,
}

/// A flight and the datasets it flies over (None: every one).
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteFlight {
    pub spec: FlightSpec,
    pub datasets: Option<Vec<String>>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Suite {
    pub run: RunSettings,
    pub datasets: Vec<DatasetSpec>,
    pub flights: Vec<SuiteFlight>,
}

impl Suite {
    /// The (dataset, flight) pairs in file order, dataset-major.
    pub fn pairs(&self) -> Vec<(&DatasetSpec, &SuiteFlight)> {
        let mut out = Vec::new();
        for d in &self.datasets {
            for f in &self.flights {
                if f.datasets.as_ref().is_none_or(|l| l.contains(&d.name)) {
                    out.push((d, f));
                }
            }
        }
        out
    }
}

/// "file:line:col: key: why" (line:column when the key is found in the text).
fn fail(source: &str, text: &str, key: &str, why: impl std::fmt::Display) -> String {
    match key_location(text, key) {
        Some(l) => format!("{source}:{l}: {key}: {why}"),
        None => format!("{source}: {key}: {why}"),
    }
}

/// A name usable as a folder: 1–40 of a–z, 0–9, `-`, `_`.
fn check_name(name: &str) -> Result<(), String> {
    let ok = (1..=40).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-' || b == b'_');
    if ok {
        Ok(())
    } else {
        Err(format!(
            "{name:?} must be 1–40 characters of a–z, 0–9, '-', '_'"
        ))
    }
}

fn positive(v: f64, what: &str) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{what} must be a finite number > 0, got {v}"))
    }
}

/// Parses suite `text` (`source` names it in errors).
pub fn parse_suite(text: &str, source: &str) -> Result<Suite, String> {
    let raw: RawSuite = toml::from_str(text).map_err(|e| {
        let at = e
            .span()
            .map(|s| format!(":{}", aerie_config::Location::from_offset(text, s.start)))
            .unwrap_or_default();
        format!("{source}{at}: {}", e.message().replace('\n', " "))
    })?;
    let f = |key: &str, why: String| fail(source, text, key, why);
    let r = raw.run;
    let size = r.size.unwrap_or_else(|| "480x270".into());
    let fov = r.fov.unwrap_or(90.0);
    parse_view(&size, fov).map_err(|e| {
        let key = if e.message.contains("--size") {
            "run.size"
        } else {
            "run.fov"
        };
        f(key, e.message)
    })?;
    let frames = r.frames.unwrap_or(24);
    if frames == 0 {
        return Err(f("run.frames", "must be at least 1".into()));
    }
    let replays = r.replays.unwrap_or(1);
    if !(1..=20).contains(&replays) {
        return Err(f(
            "run.replays",
            format!("{replays} is outside 1..=20 (1: fly the frames once)"),
        ));
    }
    let fps = positive(r.fps.unwrap_or(10.0), "the frame rate").map_err(|e| f("run.fps", e))?;
    let modes = r
        .modes
        .unwrap_or_else(|| {
            ["bounded", "clipmap", "distance", "cdlod"]
                .map(String::from)
                .into()
        })
        .join(",");
    parse_modes(&modes).map_err(|e| f("run.modes", e))?;
    let list = |v: Option<Vec<f64>>, key: &str, default: &[f64]| -> Result<Vec<f64>, String> {
        let v = v.unwrap_or_else(|| default.to_vec());
        for (i, &x) in v.iter().enumerate() {
            positive(x, "every value").map_err(|e| f(&format!("run.{key}[{i}]"), e))?;
        }
        Ok(v)
    };
    let tau = list(r.tau, "tau", &[0.5, 1.0, 2.0, 5.0])?;
    if tau.is_empty() {
        return Err(f("run.tau", "needs at least one τ".into()));
    }
    let tile_sizes = r.tile_sizes.unwrap_or_default();
    check_tile_sizes("run.tile_sizes", &tile_sizes).map_err(|e| {
        let (key, why) = e.split_once(": ").unwrap_or(("run.tile_sizes", &e));
        f(key, why.to_string())
    })?;
    let sizes = sizes_drawn(&tile_sizes);
    let clipmap_n = r.clipmap_n.unwrap_or_else(|| vec![129, 257, 513]);
    for (i, &n) in clipmap_n.iter().enumerate() {
        for &m in &sizes {
            patch_tiles_of(n, m).map_err(|e| {
                let why = e.message.trim_start_matches("--patch: ");
                f(
                    &format!("run.clipmap_n[{i}]"),
                    format!("with tiles of {m}: {why}"),
                )
            })?;
        }
    }
    let sweeps = Sweeps {
        clipmap_n,
        distance_scale: list(r.distance_scale, "distance_scale", &[0.5, 1.0, 2.0, 4.0])?,
        cdlod_range: list(r.cdlod_range, "cdlod_range", &[2.0, 4.0, 8.0, 16.0])?,
        tess_density: list(r.tess_density, "tess_density", &[0.25, 0.5, 1.0, 2.0, 4.0])?,
        tile_sizes,
    };
    let run = RunSettings {
        size,
        fov,
        frames,
        warmup: r.warmup.unwrap_or(3),
        settle: r.settle.unwrap_or(0),
        replays,
        fps,
        modes,
        tau,
        sweeps,
        oracle_nodes: r.oracle_nodes.unwrap_or(0),
    };

    if raw.dataset.is_empty() {
        return Err(f(
            "dataset",
            "the suite needs at least one [[dataset]]".into(),
        ));
    }
    let mut datasets: Vec<DatasetSpec> = Vec::new();
    for (i, d) in raw.dataset.into_iter().enumerate() {
        let key = |k: &str| format!("dataset[{i}].{k}");
        check_name(&d.name).map_err(|e| f(&key("name"), e))?;
        if datasets.iter().any(|o| o.name == d.name) {
            return Err(f(&key("name"), format!("{:?} is used twice", d.name)));
        }
        let source = match (d.path, d.generate) {
            (Some(p), None) => DatasetSource::Path(p),
            (None, Some(g)) => {
                if aerie_terrain::gen::DemKind::parse(&g.kind).is_none() {
                    return Err(f(
                        &key("generate.kind"),
                        format!(
                            "{:?} is not one of ridged, cliffs, spikes, flat, mixed",
                            g.kind
                        ),
                    ));
                }
                if !(2..=32769).contains(&g.size) {
                    return Err(f(
                        &key("generate.size"),
                        format!("{} is outside 2..=32769", g.size),
                    ));
                }
                positive(g.spacing, "the spacing").map_err(|e| f(&key("generate.spacing"), e))?;
                DatasetSource::Generate {
                    kind: g.kind,
                    size: g.size,
                    spacing: g.spacing,
                    seed: g.seed.unwrap_or(1),
                }
            }
            _ => {
                return Err(f(
                    &format!("dataset[{i}]"),
                    "needs exactly one of `path` and `generate`".into(),
                ))
            }
        };
        datasets.push(DatasetSpec {
            name: d.name,
            source,
        });
    }

    if raw.flight.is_empty() {
        return Err(f(
            "flight",
            "the suite needs at least one [[flight]]".into(),
        ));
    }
    let mut flights: Vec<SuiteFlight> = Vec::new();
    for (i, fl) in raw.flight.into_iter().enumerate() {
        let key = |k: &str| format!("flight[{i}].{k}");
        check_name(&fl.name).map_err(|e| f(&key("name"), e))?;
        if flights.iter().any(|o| o.spec.name == fl.name) {
            return Err(f(&key("name"), format!("{:?} is used twice", fl.name)));
        }
        let finite = |v: Option<f64>, k: &str, default: f64| -> Result<f64, String> {
            let v = v.unwrap_or(default);
            if v.is_finite() {
                Ok(v)
            } else {
                Err(f(&key(k), format!("{v} is not finite")))
            }
        };
        let pos = |v: Option<f64>, k: &str, default: f64| -> Result<f64, String> {
            positive(v.unwrap_or(default), "it").map_err(|e| f(&key(k), e))
        };
        // Keys a kind does not use are refused rather than ignored.
        let unused: &[(&str, bool)] = &[
            ("pitch", fl.pitch.is_some()),
            ("agl", fl.agl.is_some()),
            ("glide", fl.glide.is_some()),
            ("to_agl", fl.to_agl.is_some()),
            ("pitch_range", fl.pitch_range.is_some()),
            ("roll", fl.roll.is_some()),
        ];
        let (kind, uses): (FlightKind, &[&str]) = match fl.kind.as_str() {
            "cruise" => (
                FlightKind::Cruise {
                    pitch_deg: finite(fl.pitch, "pitch", -12.0)?,
                    agl_m: pos(fl.agl, "agl", 3000.0)?,
                },
                &["pitch", "agl"],
            ),
            "follow" => (
                FlightKind::Follow {
                    pitch_deg: finite(fl.pitch, "pitch", -8.0)?,
                    agl_m: pos(fl.agl, "agl", 150.0)?,
                },
                &["pitch", "agl"],
            ),
            "approach" => {
                let glide = pos(fl.glide, "glide", 3.0)?;
                if glide >= 45.0 {
                    return Err(f(&key("glide"), format!("{glide}° is not below 45°")));
                }
                (
                    FlightKind::Approach {
                        glide_deg: glide,
                        to_agl_m: pos(fl.to_agl, "to_agl", 50.0)?,
                    },
                    &["glide", "to_agl"],
                )
            }
            "manoeuvre" => {
                let [lo, hi] = fl.pitch_range.unwrap_or([-60.0, 30.0]);
                if !(lo.is_finite()
                    && hi.is_finite()
                    && (-90.0..=90.0).contains(&lo)
                    && lo < hi
                    && hi <= 90.0)
                {
                    return Err(f(
                        &key("pitch_range"),
                        format!("[{lo}, {hi}] must rise within −90°..90°"),
                    ));
                }
                (
                    FlightKind::Manoeuvre {
                        agl_m: pos(fl.agl, "agl", 600.0)?,
                        pitch_deg: [lo, hi],
                        roll_deg: finite(fl.roll, "roll", 90.0)?,
                    },
                    &["agl", "pitch_range", "roll"],
                )
            }
            other => {
                return Err(f(
                    &key("kind"),
                    format!("{other:?} is not one of cruise, follow, approach, manoeuvre"),
                ))
            }
        };
        if let Some((k, _)) = unused.iter().find(|(k, set)| *set && !uses.contains(k)) {
            return Err(f(
                &key(k),
                format!("a {} flight does not use `{k}`", fl.kind),
            ));
        }
        if let Some(list) = &fl.datasets {
            for (j, n) in list.iter().enumerate() {
                if !datasets.iter().any(|d| &d.name == n) {
                    return Err(f(
                        &format!("flight[{i}].datasets[{j}]"),
                        format!("no [[dataset]] is named {n:?}"),
                    ));
                }
            }
        }
        flights.push(SuiteFlight {
            spec: FlightSpec {
                name: fl.name,
                heading_deg: finite(fl.heading, "heading", 70.0)?,
                speed: pos(fl.speed, "speed", 150.0)?,
                kind,
            },
            datasets: fl.datasets,
        });
    }
    Ok(Suite {
        run,
        datasets,
        flights,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
[run]
size = "160x90"
frames = 4
tau = [1, 4]
clipmap_n = [129]

[[dataset]]
name = "inn"
path = "srtm3_single/N47E011.hgt.zip"

[[dataset]]
name = "mixed"
generate = { kind = "mixed", size = 257, spacing = 10.0 }

[[flight]]
name = "cruise"
kind = "cruise"
agl = 2000.0

[[flight]]
name = "man"
kind = "manoeuvre"
pitch_range = [-60, 30]
roll = 90
datasets = ["mixed"]
"#;

    #[test]
    fn a_good_suite_parses_with_its_defaults() {
        let s = parse_suite(GOOD, "s.toml").unwrap();
        assert_eq!(s.run.size, "160x90");
        assert_eq!(s.run.tau, vec![1.0, 4.0]);
        assert_eq!(s.run.sweeps.distance_scale, vec![0.5, 1.0, 2.0, 4.0]);
        assert_eq!(s.run.modes, "bounded,clipmap,distance,cdlod");
        assert_eq!(s.run.settle, 0, "no start-up fill unless asked");
        let settled = parse_suite(&GOOD.replace("frames = 4", "frames = 4\nsettle = 12"), "s")
            .expect("settle parses");
        assert_eq!(settled.run.settle, 12);
        assert_eq!(s.run.replays, 1, "the frames flown once unless asked");
        let replayed = parse_suite(&GOOD.replace("frames = 4", "frames = 4\nreplays = 3"), "s")
            .expect("replays parses");
        assert_eq!(replayed.run.replays, 3);
        assert!(
            s.run.sweeps.tile_sizes.is_empty(),
            "the default tiles only unless asked"
        );
        let tiled = parse_suite(
            &GOOD.replace("frames = 4", "frames = 4\ntile_sizes = [17, 9]"),
            "s",
        )
        .expect("tile_sizes parses");
        assert_eq!(tiled.run.sweeps.tile_sizes, vec![17, 9]);
        assert_eq!(
            s.datasets[1].source,
            DatasetSource::Generate {
                kind: "mixed".into(),
                size: 257,
                spacing: 10.0,
                seed: 1
            }
        );
        let pairs: Vec<(String, String)> = s
            .pairs()
            .iter()
            .map(|(d, f)| (d.name.clone(), f.spec.name.clone()))
            .collect();
        assert_eq!(
            pairs,
            [("inn", "cruise"), ("mixed", "cruise"), ("mixed", "man")]
                .map(|(a, b)| (a.to_string(), b.to_string()))
        );
        assert_eq!(
            s.flights[0].spec.kind,
            FlightKind::Cruise {
                pitch_deg: -12.0,
                agl_m: 2000.0
            }
        );
    }

    #[test]
    fn errors_name_the_key_and_its_line() {
        let cases = [
            (
                GOOD.replace("frames = 4", "frames = 0"),
                "s.toml:4:10: run.frames",
            ),
            (GOOD.replace("tau = [1, 4]", "tau = [1, -4]"), "run.tau[1]"),
            (
                GOOD.replace("clipmap_n = [129]", "clipmap_n = [65]"),
                "run.clipmap_n[0]",
            ),
            (GOOD.replace("\"160x90\"", "\"160\""), "run.size"),
            (
                GOOD.replace("frames = 4", "frames = 4\ntile_sizes = [17, 12]"),
                "run.tile_sizes[1]: tile size 12",
            ),
            (
                // 129 = 4·32 + 1: too few tiles of 33 for a patch.
                GOOD.replace("frames = 4", "frames = 4\ntile_sizes = [33]"),
                "run.clipmap_n[0]: with tiles of 33",
            ),
            (
                GOOD.replace("frames = 4", "frames = 4\nreplays = 0"),
                "s.toml:5:11: run.replays",
            ),
            (
                GOOD.replace("frames = 4", "frames = 4\nsettle = -3"),
                "s.toml:5:10: invalid value: integer `-3`",
            ),
            (
                GOOD.replace("kind = \"cruise\"", "kind = \"loop\""),
                "flight[0].kind",
            ),
            (
                GOOD.replace("agl = 2000.0", "glide = 3.0"),
                "flight[0].glide",
            ),
            (GOOD.replace("roll = 90", "roll = 90\nwobble = 1"), "wobble"),
            (
                GOOD.replace("name = \"man\"", "name = \"cruise\""),
                "flight[1].name",
            ),
            (
                GOOD.replace("name = \"inn\"", "name = \"Inn Valley\""),
                "dataset[0].name",
            ),
            (
                GOOD.replace("datasets = [\"mixed\"]", "datasets = [\"alps\"]"),
                "flight[1].datasets[0]",
            ),
            (
                GOOD.replace("kind = \"mixed\"", "kind = \"alps\""),
                "dataset[1].generate.kind",
            ),
            (
                GOOD.replace("path = \"srtm3_single/N47E011.hgt.zip\"", ""),
                "dataset[0]: needs exactly one",
            ),
            (
                GOOD.replace("[-60, 30]", "[30, -60]"),
                "flight[1].pitch_range",
            ),
            (GOOD.replace("size = \"160x90\"", "size = 5"), "s.toml:3:8"),
        ];
        for (text, want) in cases {
            let e = parse_suite(&text, "s.toml").unwrap_err();
            assert!(e.contains(want) && e.starts_with("s.toml"), "{want}: {e}");
        }
    }

    /// The committed suites parse, fly every flight over every dataset, and sweep every
    /// baseline over at least three settings.
    #[test]
    fn the_committed_suites_parse() {
        for (name, text) in [
            (
                "full.toml",
                include_str!("../../../../../bench/suites/full.toml"),
            ),
            (
                "lavapipe.toml",
                include_str!("../../../../../bench/suites/lavapipe.toml"),
            ),
            (
                "gpu-1080p.toml",
                include_str!("../../../../../bench/suites/gpu-1080p.toml"),
            ),
        ] {
            let s = parse_suite(text, name).unwrap();
            assert_eq!(s.pairs().len(), 20, "{name}");
            let w = &s.run.sweeps;
            assert!(
                w.clipmap_n.len() >= 3 && w.distance_scale.len() >= 4 && w.cdlod_range.len() >= 4
            );
            assert!(s.run.tau.len() >= 4, "{name}");
            // Late tiles are counted in flight, after the caches filled at the first pose.
            assert!(s.run.settle >= 10, "{name}");
        }
        // The tile-size study: the four real datasets' 16 flights, every tiled mode at 17 and 9.
        let text = include_str!("../../../../../bench/suites/lavapipe-tiles.toml");
        let s = parse_suite(text, "lavapipe-tiles.toml").unwrap();
        assert_eq!(s.pairs().len(), 16);
        assert_eq!(s.run.sweeps.tile_sizes, vec![17, 9]);
        assert!(!s.run.modes.contains("tess"), "{}", s.run.modes);
        // Tiles of 5 as a third size: the same 16 flights, every tiled mode at 17, 9 and 5.
        let text = include_str!("../../../../../bench/suites/lavapipe-tiles5.toml");
        let s = parse_suite(text, "lavapipe-tiles5.toml").unwrap();
        assert_eq!(s.pairs().len(), 16);
        assert_eq!(s.run.sweeps.tile_sizes, vec![17, 9, 5]);
        let base = parse_suite(
            include_str!("../../../../../bench/suites/lavapipe.toml"),
            "lavapipe.toml",
        )
        .unwrap();
        // The denser sweeps: lavapipe.toml's flights and frames without tessellation, every
        // knob at 7 settings or more and each of lavapipe.toml's among them (its curves'
        // points are this run's too), bounded's τ on to 100 px.
        let text = include_str!("../../../../../bench/suites/lavapipe-dense.toml");
        let d = parse_suite(text, "lavapipe-dense.toml").unwrap();
        assert_eq!(d.pairs().len(), 20);
        assert_eq!((&d.datasets, &d.flights), (&base.datasets, &base.flights));
        let frames = |r: &RunSettings| (r.size.clone(), r.frames, r.warmup, r.fps, r.settle);
        assert_eq!(frames(&d.run), frames(&base.run));
        assert_eq!(d.run.modes, base.run.modes.replace(",tess", ""));
        let (w, b) = (&d.run.sweeps, &base.run.sweeps);
        assert!(w.clipmap_n.len() >= 7 && w.distance_scale.len() >= 7 && w.cdlod_range.len() >= 7);
        assert!(b.clipmap_n.iter().all(|n| w.clipmap_n.contains(n)));
        assert!(b
            .distance_scale
            .iter()
            .all(|x| w.distance_scale.contains(x)));
        assert!(b.cdlod_range.iter().all(|k| w.cdlod_range.contains(k)));
        assert!(base.run.tau.iter().all(|t| d.run.tau.contains(t)));
        assert!(d.run.tau.len() >= 13 && d.run.tau.contains(&100.0));
        assert_eq!(w.tile_sizes, b.tile_sizes);
        // lavapipe.toml at twice the size without tessellation: otherwise the same run.
        let text = include_str!("../../../../../bench/suites/lavapipe-768.toml");
        let s = parse_suite(text, "lavapipe-768.toml").unwrap();
        assert_eq!(s.pairs().len(), 20);
        assert_eq!(
            (s.run.size.as_str(), base.run.size.as_str()),
            ("768x432", "384x216")
        );
        assert_eq!(s.run.modes, base.run.modes.replace(",tess", ""));
        let same = |r: &RunSettings| (r.tau.clone(), r.sweeps.clone(), r.frames, r.warmup, r.fps);
        assert_eq!(same(&s.run), same(&base.run));
        assert_eq!((&s.datasets, &s.flights), (&base.datasets, &base.flights));
        // Its tessellation column apart: the same run, bounded and tessellation only.
        let text = include_str!("../../../../../bench/suites/lavapipe-768-tess.toml");
        let t = parse_suite(text, "lavapipe-768-tess.toml").unwrap();
        assert_eq!(t.run.modes, "bounded,tess");
        assert_eq!(t.run.size, s.run.size);
        assert_eq!(same(&t.run), same(&s.run));
        assert_eq!((&t.datasets, &t.flights), (&s.datasets, &s.flights));
        // The CPU-frame measurement's flights: the four real datasets' 16, 4 s at 30 fps.
        let text = include_str!("../../../../../bench/suites/cpu-frame.toml");
        let s = parse_suite(text, "cpu-frame.toml").unwrap();
        assert_eq!(s.pairs().len(), 16);
        assert_eq!((s.run.frames, s.run.fps), (120, 30.0));
    }
}
