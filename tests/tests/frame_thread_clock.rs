//! The frame thread's own CPU clock, end to end through the `aerie` binary: `fly` (drawn on
//! lavapipe) and `fly --no-draw` write each frame's `cpu_thread_us` (the whole CPU frame) and
//! `cpu_thread_plan_us` (its part up to the plan) in frames.csv, and their percentiles in
//! summary.json.

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use aerie_tests::*;

fn fly(args: &[&str]) {
    let out = Command::new(aerie_bin())
        .args(args)
        .output()
        .expect("run aerie");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "aerie {args:?} failed:\n{err}");
}

/// frames.csv as rows of column → value.
fn frames(dir: &Path) -> Vec<HashMap<String, f64>> {
    let text = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            let fields = l.split(',').map(|f| f.parse::<f64>().unwrap_or(f64::NAN));
            header.iter().map(|h| h.to_string()).zip(fields).collect()
        })
        .collect()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// median > 0 and median ≤ p99 ≤ max of a `median_p99_max` entry.
fn ordered(v: &serde_json::Value, key: &str) {
    let at = |k: &str| {
        v[key][k]
            .as_f64()
            .unwrap_or_else(|| panic!("{key}.{k} in {v}"))
    };
    let (median, p99, max) = (at("median"), at("p99"), at("max"));
    assert!(
        median > 0.0 && median <= p99 && p99 <= max,
        "{key}: {}",
        v[key]
    );
}

#[test]
fn fly_reports_the_frame_threads_cpu_time_drawn_and_undrawn() {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(demo_dem(), &dem).unwrap();
    let dem = dem.to_str().unwrap();
    let (drawn, undrawn) = (dir.path().join("drawn"), dir.path().join("undrawn"));
    let common = [
        "--dem", dem, "--frames", "3", "--size", "48x32", "--every", "100",
    ];
    fly(&[&["fly"][..], &common, &["--out", drawn.to_str().unwrap()]].concat());
    let no_draw = [
        "fly",
        "--no-draw",
        "--pace",
        "0",
        "--dem",
        dem,
        "--frames",
        "3",
    ];
    fly(&[
        &no_draw[..],
        &["--size", "48x32", "--out", undrawn.to_str().unwrap()],
    ]
    .concat());

    // Drawn: the whole frame's thread time, and within it the selection and plan.
    for r in frames(&drawn) {
        let (whole, plan) = (r["cpu_thread_us"], r["cpu_thread_plan_us"]);
        assert!(
            plan > 0.0 && plan <= whole,
            "frame {}: {plan} of {whole} µs",
            r["frame"]
        );
    }
    let s = summary(&drawn);
    ordered(&s, "frame_thread_cpu_us");
    ordered(&s, "stage_record_submit_thread_cpu_us");
    // Undrawn: no staging or recording, so the whole is the plan's part.
    for r in frames(&undrawn) {
        let (whole, plan) = (r["cpu_thread_us"], r["cpu_thread_plan_us"]);
        assert!(
            whole > 0.0 && plan == whole,
            "frame {}: {plan} vs {whole} µs",
            r["frame"]
        );
    }
    ordered(&summary(&undrawn), "frame_thread_cpu_us");
}
