//! `aerie render`: one frame of a DEM from a fixed camera to a PNG, with a JSON summary printed
//! and written next to it.

use std::path::PathBuf;

use clap::Args;

use crate::app::args::GpuArgs;
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::out_path::prepare_out_file;
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
    /// Output PNG (its folder is created); a JSON summary is written next to it (same name,
    /// .json).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(a: RenderArgs) -> Result<(), Failure> {
    let s = setup(&a.gpu)?;
    let (position, attitude) =
        parse_camera_arg(&a.camera).map_err(|e| bad_input(format!("--camera: {e}")))?;
    prepare_out_file("--out", &a.out)?;
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
    write_text(&a.out.with_extension("json"), &format!("{line}\n")).map_err(runtime)?;
    println!("{line}");
    Ok(())
}
