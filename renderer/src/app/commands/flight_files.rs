//! The files every headless flight writes (`fly`, `fly --no-draw`): `frames.csv` (one row per
//! frame: the pose, then every frame statistic) and `summary.json`, and the spreads the
//! summaries give.

use std::path::Path;

use glam::DVec3;

use crate::app::failure::Failure;
use crate::app::out_path::WriteFailures;
use crate::render::frame::FrameStats;
use crate::tools::output::write_text;
use crate::tools::percentile::percentile;
use aerie_terrain::camera::Attitude;

/// The end of every flight: `frames.csv`, then `summary.json` with `failed_frames` and
/// `failed_files` (both empty on a clean run), each tried even when files before it failed.
/// Ok when every file of the run was written, else exit 1 naming the first that was not.
pub fn write_csv_and_summary(
    out: &Path,
    csv: &str,
    mut summary: serde_json::Value,
    failures: &mut WriteFailures,
) -> Result<(), Failure> {
    let csv_path = out.join("frames.csv");
    failures.check(None, &csv_path, write_text(&csv_path, csv));
    summary["failed_frames"] = serde_json::json!(failures.failed_frames());
    summary["failed_files"] = failures.json();
    let path = out.join("summary.json");
    let written = write_text(&path, &format!("{summary:#}\n"));
    let written = failures.check(None, &path, written);
    failures.verdict(written.then_some(path.as_path()))
}

/// Header of `frames.csv`.
pub fn frames_csv_header() -> String {
    format!(
        "time_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg,{}\n",
        FrameStats::CSV_HEADER
    )
}

/// `summary.json`'s spread of sorted samples: median, p99 and max.
pub fn median_p99_max(sorted: &[f64]) -> serde_json::Value {
    serde_json::json!({
        "median": percentile(sorted, 0.5),
        "p99": percentile(sorted, 0.99),
        "max": percentile(sorted, 1.0),
    })
}

/// `summary.json`'s median and max of sorted samples.
pub fn median_max(sorted: &[f64]) -> serde_json::Value {
    serde_json::json!({"median": percentile(sorted, 0.5), "max": percentile(sorted, 1.0)})
}

/// One CSV row per frame: the pose, then every frame statistic.
pub fn csv_row(s: &FrameStats, t: f64, pos: DVec3, att: Attitude) -> String {
    format!(
        "{:.4},{:.2},{:.2},{:.2},{:.3},{:.3},{:.3},{}\n",
        t,
        pos.x,
        pos.y,
        pos.z,
        att.heading.to_degrees(),
        att.pitch.to_degrees(),
        att.roll.to_degrees(),
        s.csv_row()
    )
}
