//! `aerie render`: one frame of a DEM from a fixed camera to a PNG, with a JSON summary printed
//! and written next to it as `<png>.json` (`notes.png` → `notes.png.json`, so a `notes.json`
//! beside it is never touched). An existing `<png>.json` that is not an earlier render's
//! summary is refused before anything is rendered.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::app::args::{GpuArgs, StoreArgs};
use crate::app::failure::{bad_input, renderer_failure, runtime, Failure};
use crate::app::out_path::{prepare_out_file, with_suffix};
use crate::app::prepare::prepare_source;
use crate::app::renderer_setup::setup;
use crate::render::frame::{Lighting, TerrainRenderer};
use crate::sim::geo_mapping::GeoMapping;
use crate::sim::sun_clock::SunClock;
use crate::tools::output::{write_png, write_text};
use aerie_terrain::camera::{parse_camera_arg, parse_geodetic_camera_arg, Camera};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Elevation model: .hgt, .hgt.zip, a folder of SRTM tiles, GeoTIFF, 16-bit .png,
    /// raw .f32/.u16 with a .json sidecar, .npy/.npz. Its error bake is read from (or written
    /// to) `<name>.aerie-bake` next to it. A tile store (`<name>.aerie`) is streamed.
    #[arg(long)]
    pub dem: PathBuf,
    #[command(flatten)]
    pub store: StoreArgs,
    /// Camera as x,y,z,heading,pitch,roll: metres from the DEM's south-west sample (z above sea
    /// level; geographic data: East-North-Up at that sample on the WGS84 ellipsoid, so far away
    /// the ground falls below z = its height), degrees (heading clockwise from north, pitch
    /// nose-up, roll right-wing-down).
    #[arg(
        long,
        allow_hyphen_values = true,
        required_unless_present = "camera_geo",
        conflicts_with = "camera_geo"
    )]
    pub camera: Option<String>,
    /// Camera as lat,lon,alt,heading,pitch,roll on a geo-referenced dataset (geographic or
    /// UTM): WGS84 degrees, metres above the data's vertical datum (mean sea level for SRTM),
    /// the attitude in degrees in the north-east-down frame at that point — exactly where a
    /// CIGI host's pose would put the eye.
    #[arg(long, allow_hyphen_values = true)]
    pub camera_geo: Option<String>,
    #[command(flatten)]
    pub gpu: GpuArgs,
    /// Output PNG (its folder is created); a JSON summary is written next to it as
    /// `<out>.json` (frame.png → frame.png.json).
    #[arg(long)]
    pub out: PathBuf,
    /// The sun as azimuth,elevation in degrees (azimuth clockwise from north, elevation
    /// negative below the horizon); default 315,40.
    #[arg(long, allow_hyphen_values = true, conflicts_with = "time")]
    pub sun: Option<String>,
    /// The sun where it stands over the eye at this UTC date and time (`2026-06-21T12:00:00Z`),
    /// on a geo-referenced dataset — the ephemeris a CIGI host's Celestial Sphere Control sets.
    #[arg(long)]
    pub time: Option<String>,
    /// Meteorological visibility at sea level, metres (default 40 km).
    #[arg(long)]
    pub visibility: Option<f64>,
}

/// `--sun az,el` (degrees) as a unit vector towards the sun (east-north-up).
fn parse_sun(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let nums: Vec<f64> = parts
        .iter()
        .map(|p| {
            p.parse::<f64>()
                .map_err(|_| format!("{p:?} is not a number"))
        })
        .collect::<Result<_, _>>()?;
    match nums.as_slice() {
        [az, el] if az.is_finite() && (-90.0..=90.0).contains(el) => {
            let (az, el) = (az.to_radians(), el.to_radians());
            Ok([el.cos() * az.sin(), el.cos() * az.cos(), el.sin()])
        }
        [_, _] => Err(format!("{s}: elevation must be within -90..=90 degrees")),
        _ => Err(format!("{s}: expected azimuth,elevation in degrees")),
    }
}

pub fn run(a: RenderArgs) -> Result<(), Failure> {
    let s = setup(&a.gpu)?;
    let mut sun = match &a.sun {
        Some(v) => Some(parse_sun(v).map_err(|e| bad_input(format!("--sun: {e}")))?),
        None => None,
    };
    let clock = match &a.time {
        Some(t) => Some(SunClock::parse(t).map_err(|e| bad_input(format!("--time: {e}")))?),
        None => None,
    };
    if let Some(v) = a.visibility.filter(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(bad_input(format!(
            "--visibility: {v} must be a positive number of metres"
        )));
    }
    let local = match &a.camera {
        Some(c) => Some(parse_camera_arg(c).map_err(|e| bad_input(format!("--camera: {e}")))?),
        None => None,
    };
    let geo = match &a.camera_geo {
        Some(c) => Some(
            parse_geodetic_camera_arg(c).map_err(|e| bad_input(format!("--camera-geo: {e}")))?,
        ),
        None => None,
    };
    prepare_out_file("--out", &a.out)?;
    let json_path = with_suffix(&a.out, ".json");
    check_summary_path(&a.out, &json_path)?;
    let terrain = prepare_source(&a.dem, &s.desc, &a.store)?;
    // Geodetic positions of the data (for `--camera-geo` and `centre_hit`): none without a
    // geo-reference.
    let mapping = GeoMapping::of_source(terrain.grid());
    let (position, attitude) = match (local, geo) {
        (Some(l), _) => l,
        (None, Some(g)) => {
            let m = mapping
                .as_ref()
                .map_err(|e| bad_input(format!("--camera-geo: {e}")))?;
            (
                m.to_world(g.lat_deg, g.lon_deg, g.alt_m),
                m.attitude_at(g.lat_deg, g.lon_deg, g.attitude),
            )
        }
        // clap requires one of the two.
        (None, None) => return Err(bad_input("--camera or --camera-geo is required")),
    };
    if let Some(c) = clock {
        let m = mapping
            .as_ref()
            .map_err(|e| bad_input(format!("--time: the sun's place needs latitudes: {e}")))?;
        sun = c.sun_world(0.0, m, position);
    }
    let mut r = TerrainRenderer::new(&s.desc).map_err(runtime)?;
    let source = terrain.source.clone();
    r.load_source(source, terrain.bake.clone(), position)
        .map_err(renderer_failure)?;
    let lighting = Lighting::from_host(sun, a.visibility);
    r.set_lighting(lighting);
    let sun_drawn = lighting.sun_enu;
    let camera = Camera::new(position, attitude, s.view.frustum);
    // One still image: frames are drawn until nothing is late for streaming and every
    // streamed imagery window is filled (each frame asks for what it lacked and never waits;
    // the pause between frames lets the pages arrive). The imagery cells resident are copied
    // before each frame, not a frame's share at a time.
    let t = std::time::Instant::now();
    let mut warm_up_frames = 0u32;
    r.fill_imagery(position).map_err(runtime)?;
    let mut stats = r.render(&camera).map_err(runtime)?;
    let waiting = |s: &crate::render::stats::FrameStats| {
        let heights =
            terrain.streamed.is_some() && (s.tiles_late_stream > 0 || s.cells_pending > 0);
        heights || s.imagery_cells_pending > 0
    };
    while waiting(&stats) && t.elapsed() < WARM_UP_LIMIT {
        std::thread::sleep(std::time::Duration::from_millis(5));
        r.fill_imagery(position).map_err(runtime)?;
        stats = r.render(&camera).map_err(runtime)?;
        warm_up_frames += 1;
    }
    let rgba = r.colour_rgba();
    let (width, height) = (s.view.width, s.view.height);
    let mapping = mapping.ok();
    let centre_hit = centre_hit(&camera, &r.depth(), (width, height), mapping.as_ref());
    let device = r.device_name().to_string();
    let drape = crate::app::renderer_setup::drape_json(&r);
    r.destroy();
    r.validation_counters().verdict().map_err(runtime)?;
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
        "gpu_terrain_ms": stats.gpu_terrain_ms,
        "look": format!("{:?}", s.desc.look).to_lowercase(),
        "normal_maps": s.desc.normal_maps,
        "cpu_select_us": stats.cpu_select_us,
        "tiles_late_stream": stats.tiles_late_stream,
        "warm_up_frames": warm_up_frames,
        "stream": stream_json(&stats),
        "camera": camera_json(&camera, mapping.as_ref()),
        "centre_hit": centre_hit,
        "sun": sun_drawn,
        "drape": drape,
        "out": a.out.display().to_string(),
    });
    let line = summary.to_string();
    write_text(&json_path, &format!("{line}\n")).map_err(runtime)?;
    println!("{line}");
    Ok(())
}

/// The point drawn under the screen centre, read back from the depth buffer: pixel
/// (width/2, height/2)'s centre unprojected at its depth. World metres (x, y, z) and the range
/// from the eye always; latitude, longitude and height (the data's datum) on a geo-referenced
/// dataset. `null` for sky.
fn centre_hit(
    camera: &Camera,
    depth: &[f32],
    (width, height): (u32, u32),
    mapping: Option<&GeoMapping>,
) -> serde_json::Value {
    let (px, py) = (width / 2, height / 2);
    let d = depth
        .get(py as usize * width as usize + px as usize)
        .copied()
        .unwrap_or(0.0);
    let Some(p) = camera.unproject_px(px, py, width, height, d) else {
        return serde_json::Value::Null;
    };
    let mut hit = serde_json::json!({
        "pixel": [px, py],
        "x": p.x,
        "y": p.y,
        "z": p.z,
        "range_m": (p - camera.position).length(),
    });
    if let Some(m) = mapping {
        let (lat, lon, h) = m.world_to_geodetic(p);
        hit["lat"] = lat.into();
        hit["lon"] = lon.into();
        hit["height"] = h.into();
    }
    hit
}

/// The camera drawn: world metres, the attitude in the world frame (degrees), and its geodetic
/// position when the data has one.
fn camera_json(camera: &Camera, mapping: Option<&GeoMapping>) -> serde_json::Value {
    let p = camera.position;
    let a = camera.attitude;
    let mut v = serde_json::json!({
        "x": p.x, "y": p.y, "z": p.z,
        "heading_deg": a.heading.to_degrees(),
        "pitch_deg": a.pitch.to_degrees(),
        "roll_deg": a.roll.to_degrees(),
    });
    if let Some(m) = mapping {
        let (lat, lon, alt) = m.world_to_geodetic(p);
        v["lat"] = lat.into();
        v["lon"] = lon.into();
        v["alt"] = alt.into();
    }
    v
}

/// How long a still image of a streamed store waits for its pages (frames drawn meanwhile).
const WARM_UP_LIMIT: std::time::Duration = std::time::Duration::from_secs(30);

/// The source's totals after a frame, for the commands' JSON summaries.
pub fn stream_json(s: &crate::render::frame::FrameStats) -> serde_json::Value {
    serde_json::json!({
        "hits": s.stream_hits,
        "misses": s.stream_misses,
        "hit_rate": if s.stream_hits + s.stream_misses > 0 {
            s.stream_hits as f64 / (s.stream_hits + s.stream_misses) as f64
        } else {
            1.0
        },
        "loaded": s.stream_loaded,
        "failed": s.stream_failed,
        "resident_bytes": s.stream_resident_bytes,
        "budget_bytes": s.stream_budget_bytes,
    })
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

    #[test]
    fn sun_argument_is_azimuth_and_elevation_in_degrees() {
        let s = parse_sun("90,0").unwrap();
        assert!((s[0] - 1.0).abs() < 1e-12 && s[1].abs() < 1e-12 && s[2].abs() < 1e-12);
        let s = parse_sun("180, -30").unwrap();
        assert!((s[1] + 30f64.to_radians().cos()).abs() < 1e-12);
        assert!((s[2] + 0.5).abs() < 1e-12);
        for bad in ["", "90", "90,0,1", "x,10", "0,91", "inf,10"] {
            assert!(parse_sun(bad).is_err(), "{bad:?}");
        }
    }
}
