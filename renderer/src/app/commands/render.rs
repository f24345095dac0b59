//! `aerie render`: one frame of a DEM from a fixed camera to a PNG, with a JSON summary printed
//! and written next to it as `<png>.json` (`notes.png` → `notes.png.json`, so a `notes.json`
//! beside it is never touched). An existing `<png>.json` that is not an earlier render's
//! summary is refused before anything is rendered.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::app::args::GpuArgs;
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::out_path::{prepare_out_file, with_suffix};
use crate::app::prepare::prepare_terrain;
use crate::app::renderer_setup::setup;
use crate::render::frame::TerrainRenderer;
use crate::tools::output::{write_png, write_text};
use aerie_terrain::camera::{parse_camera_arg, Camera};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Elevation model: .hgt, .hgt.zip, a folder of SRTM tiles, GeoTIFF, 16-bit .png,
    /// raw .f32/.u16 with a .json sidecar, .npy/.npz. Its error bake is read from (or written
    /// to) `<name>.aerie-bake` next to it.
    #[arg(long)]
    pub dem: PathBuf,
    /// Camera as x,y,z,heading,pitch,roll: metres from the DEM's south-west sample (z above sea
    /// level), degrees (heading clockwise from north, pitch nose-up, roll right-wing-down).
    #[arg(long, allow_hyphen_values = true)]
    pub camera: String,
    #[command(flatten)]
    pub gpu: GpuArgs,
    /// Output PNG (its folder is created); a JSON summary is written next to it as
    /// `<out>.json` (frame.png → frame.png.json).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(a: RenderArgs) -> Result<(), Failure> {
    let s = setup(&a.gpu)?;
    let (position, attitude) =
        parse_camera_arg(&a.camera).map_err(|e| bad_input(format!("--camera: {e}")))?;
    prepare_out_file("--out", &a.out)?;
    let json_path = with_suffix(&a.out, ".json");
    check_summary_path(&a.out, &json_path)?;
    let (ds, b) = prepare_terrain(&a.dem, s.desc.tile_size)?;
    let mut r = TerrainRenderer::new(&s.desc).map_err(runtime)?;
    r.load_terrain(ds, b, position).map_err(runtime)?;
    let camera = Camera::new(position, attitude, s.view.frustum);
    let stats = r.render(&camera).map_err(runtime)?;
    let rgba = r.colour_rgba();
    let device = r.device_name().to_string();
    r.destroy();
    r.validation_counters().verdict().map_err(runtime)?;
    let (width, height) = (s.view.width, s.view.height);
    write_png(&a.out, width, height, &rgba).map_err(runtime)?;
    let summary = serde_json::json!({
        "device": device,
        "dem": a.dem.display().to_string(),
        "size": [width, height],
        "lod": s.desc.select.mode,
        "tau_px": s.desc.select.tau_px,
        "triangles": stats.triangles,
        "tiles_drawn": stats.tiles_drawn,
        "tiles_culled": stats.tiles_culled,
        "tiles_by_refinement": stats.tiles_by_refinement,
        "tiles_late": stats.tiles_late,
        "instances": stats.instances,
        "draw_calls": stats.draw_calls,
        "gpu_ms": stats.gpu_upload_ms + stats.gpu_terrain_ms,
        "cpu_select_us": stats.cpu_select_us,
        "out": a.out.display().to_string(),
    });
    let line = summary.to_string();
    write_text(&json_path, &format!("{line}\n")).map_err(runtime)?;
    println!("{line}");
    Ok(())
}

/// The keys every render summary has: a file with all of them is an earlier render's.
const SUMMARY_KEYS: [&str; 4] = ["device", "dem", "triangles", "out"];

/// Refuses (exit 2) to replace `json` unless it is missing or an earlier `aerie render`
/// summary: the summary's name is derived from `--out`, and a file of the same name the user
/// keeps there must not be lost.
fn check_summary_path(out: &Path, json: &Path) -> Result<(), Failure> {
    let refuse = |why: &str| {
        Err(bad_input(format!(
            "--out {}: {} {why}; refusing to replace it with the render summary (move it or \
             choose another --out)",
            out.display(),
            json.display()
        )))
    };
    match std::fs::symlink_metadata(json) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return refuse(&format!("cannot be inspected ({e})")),
        Ok(m) if !m.is_file() => return refuse("exists and is not a regular file"),
        Ok(_) => {}
    }
    let ours = std::fs::read(json)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|v| v.as_object().cloned())
        .is_some_and(|o| SUMMARY_KEYS.iter().all(|k| o.contains_key(*k)));
    if ours {
        Ok(())
    } else {
        refuse("exists and is not an aerie render summary")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_missing_file_or_an_earlier_summary_is_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("notes.png");
        let json = with_suffix(&out, ".json");
        assert_eq!(json, dir.path().join("notes.png.json"));
        check_summary_path(&out, &json).unwrap();
        std::fs::write(
            &json,
            r#"{"device":"x","dem":"d","triangles":3,"out":"notes.png","tau_px":1}"#,
        )
        .unwrap();
        check_summary_path(&out, &json).unwrap();
        for other in [&b"{\"title\": \"my notes\"}"[..], b"not json", b"[1,2]"] {
            std::fs::write(&json, other).unwrap();
            let e = check_summary_path(&out, &json).unwrap_err();
            assert_eq!(e.code, 2);
            assert!(
                e.message.contains("notes.png.json") && e.message.contains("not an aerie render"),
                "{}",
                e.message
            );
        }
        std::fs::remove_file(&json).unwrap();
        std::fs::create_dir(&json).unwrap();
        let e = check_summary_path(&out, &json).unwrap_err();
        assert!(e.message.contains("not a regular file"), "{}", e.message);
    }
}
