use super::*;
use crate::app::commands::bench::config::BenchConfig;
use crate::app::commands::bench::report::{ImageSummary, Quantiles};
use crate::app::commands::bench::suite_config::parse_suite;
use aerie_terrain::select::LodMode;

const SUITE: &str = r#"
[run]
size = "160x90"
frames = 3
modes = ["bounded", "clipmap"]
tau = [1.0, 4.0]

[[dataset]]
name = "mixed"
generate = { kind = "mixed", size = 513, spacing = 30.0, seed = 3 }

[[flight]]
name = "follow"
kind = "follow"
agl = 150.0
"#;

fn q(base: f64) -> Quantiles {
    Quantiles {
        median: base,
        p95: base * 1.5,
        p99: base * 2.0 + 0.1,
        max: base * 3.0 + 1e-9,
    }
}

/// A bounded summary with an image error and a clipmap one without τ, oracle or image.
fn summaries() -> Vec<Summary> {
    let bounded = Summary {
        config: BenchConfig {
            mode: LodMode::Bounded,
            tau_px: Some(1.0),
            knob: None,
            tile_size: None,
        },
        frames: 3,
        frame_ms: q(12.345_678_901_234),
        cpu_ms: q(0.1 + 0.2),
        gpu_ms: q(1.0 / 3.0),
        triangles: q(123_456.0),
        instances: q(789.0),
        draw_calls: q(1.0),
        bytes_uploaded: q(4096.0),
        bytes_uploaded_mean: 4096.5,
        tiles_drawn: 190,
        tiles_late: 2,
        tiles_late_stream: 1,
        terrain_data_us_max: 231.3,
        tiles_unbounded: 0,
        image: Some(ImageSummary {
            max_px: 0.94,
            raw_max_px: 1.01,
            p99_px: 0.1016,
            mean_px: 0.007_55,
            fraction_over_tau: 0.0,
            holes_px: 42,
            hole_max_px: 1.0,
            frames_over_target: 0,
            frame_max: q(0.9),
        }),
        oracle_max_px: Some(0.76),
        bound_max_px: None,
    };
    let clipmap = Summary {
        config: BenchConfig {
            mode: LodMode::Clipmap,
            tau_px: None,
            knob: Some(257.0),
            tile_size: None,
        },
        image: None,
        oracle_max_px: None,
        ..bounded.clone()
    };
    vec![bounded, clipmap]
}

/// The bench's options as a default command line gives them.
const COMMAND_LINE: &str = "patch 129 curvature true skirts Needed";

fn print_of(text: &str) -> String {
    print_with(text, COMMAND_LINE)
}

fn print_with(text: &str, command_line: &str) -> String {
    let s = parse_suite(text, "test.toml").unwrap();
    fingerprint(&s.run, &s.datasets[0], &s.flights[0], command_line)
}

#[test]
fn a_record_reads_back_equal_and_only_for_its_own_settings() {
    let dir = tempfile::tempdir().unwrap();
    let print = print_of(SUITE);
    let rec = FlightRecord::new(
        print.clone(),
        "llvmpipe".into(),
        "513x513 samples".into(),
        summaries(),
    );
    write_record(dir.path(), &rec).unwrap();
    match read_record(dir.path(), &print) {
        Resume::Record(r) => assert_eq!(*r, rec),
        Resume::Run(why) => panic!("not resumed: {why}"),
    }
    // Every setting that changes the flight's results changes the fingerprint.
    for (from, to) in [
        ("frames = 3", "frames = 4"),
        ("tau = [1.0, 4.0]", "tau = [1.0, 5.0]"),
        ("seed = 3", "seed = 4"),
        ("agl = 150.0", "agl = 151.0"),
        ("size = \"160x90\"", "size = \"320x180\""),
    ] {
        let other = print_of(&SUITE.replace(from, to));
        assert_ne!(other, print, "{to}");
        match read_record(dir.path(), &other) {
            Resume::Run(why) => assert!(why.contains("other run settings"), "{why}"),
            Resume::Record(_) => panic!("resumed across {from} → {to}"),
        }
    }
    // So does an option of the command line that changes them.
    let other = print_with(SUITE, "patch 129 curvature true skirts Everywhere");
    assert_ne!(other, print);
    assert!(
        matches!(read_record(dir.path(), &other), Resume::Run(w) if w.contains("other run settings"))
    );
    remove_record(dir.path()).unwrap();
    assert!(matches!(read_record(dir.path(), &print), Resume::Run(w) if w.contains("no record")));
    // Removing what is not there is no error.
    remove_record(dir.path()).unwrap();
}

#[test]
fn non_finite_values_survive_the_record() {
    let mut s = summaries();
    s[0].gpu_ms.max = f64::NAN;
    s[0].frame_ms.max = f64::INFINITY;
    let rec = FlightRecord::new("x".into(), "d".into(), "ds".into(), s);
    let text = toml::to_string(&rec).unwrap();
    let back = parse_record(&text, "x").unwrap();
    assert!(back.summaries[0].gpu_ms.max.is_nan());
    assert_eq!(back.summaries[0].frame_ms.max, f64::INFINITY);
    assert_eq!(back.summaries[1], rec.summaries[1]);
}

#[test]
fn a_damaged_or_foreign_record_means_flying_again_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let print = print_of(SUITE);
    let rec = FlightRecord::new(print.clone(), "d".into(), "ds".into(), summaries());
    let text = toml::to_string(&rec).unwrap();
    let path = dir.path().join(RECORD_FILE);
    let cases = [
        (text[..text.len() / 2].to_string(), "unreadable"),
        ("garbage = [".to_string(), "unreadable"),
        (
            text.replace("version = 1", "version = 99"),
            "record format 99",
        ),
        (
            toml::to_string(&FlightRecord::new(
                print.clone(),
                "d".into(),
                "ds".into(),
                vec![],
            ))
            .unwrap(),
            "no configuration",
        ),
    ];
    for (body, why) in cases {
        std::fs::write(&path, body).unwrap();
        match read_record(dir.path(), &print) {
            Resume::Run(w) => assert!(w.contains(why) && w.contains(RECORD_FILE), "{w}"),
            Resume::Record(_) => panic!("resumed a record that should say {why}"),
        }
    }
}
