//! Draped rasters on lavapipe with the validation layer on (issue 17): a geographic
//! checkerboard over a UTM terrain lands on the samples the f64 geodesy says, in the class
//! view (unlit); a land-cover raster's classes match the CPU twin; a golden of imagery in the
//! full look; rasters that cannot be placed are refused naming the file.

use std::sync::Arc;

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::drape_textures::DrapeInput;
use aerie::render::frame::{Lighting, Look, RendererDesc, TerrainRenderer};
use aerie::render::landcover::{
    class_colour_srgb, class_corners, class_weights, raster_weights, CoverInputs, NO_CLASS,
};
use aerie::terrain::drape::{read_raster, EncodeRef};
use aerie::terrain::Heightfield;
use aerie_tests::drape_fixtures::*;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;

fn desc_with(look: Look, input: DrapeInput) -> RendererDesc {
    // A UTM grid is drawn on the exact ellipsoid (curvature cannot be turned off there).
    let mut desc = test_desc(W, H);
    desc.look = look;
    desc.drape = Some(Arc::new(input));
    desc
}

fn down_camera() -> Camera {
    Camera::new(
        DVec3::new(1920.0, 1920.0, 6500.0),
        Attitude::from_degrees(0.0, -90.0, 0.0),
        Frustum::symmetric(60f64.to_radians(), W, H),
    )
}

/// Renders one frame; returns it and the renderer's draped rasters (validation clean).
fn render_one(
    desc: &RendererDesc,
    hf: &Heightfield,
    cam: Camera,
    light: Lighting,
) -> (
    Rendered,
    Option<Arc<aerie::render::drape_textures::DrapedRasters>>,
    u64,
) {
    let (ds, b) = prepare(desc, hf);
    let mut r = TerrainRenderer::new(desc).expect("create renderer");
    r.load_terrain(ds, b, cam.position).expect("upload terrain");
    r.set_lighting(light);
    let stats = r.render(&cam).expect("render");
    let f = Rendered {
        width: W,
        height: H,
        rgba: r.colour_rgba(),
        depth: r.depth(),
        stats,
    };
    let (draped, bytes) = r.draped();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    (f, draped, bytes)
}

fn pixel(f: &Rendered, cam: &Camera, p: DVec3) -> Option<[u8; 3]> {
    let (px, _) = cam.project_px(p, W, H)?;
    // The screen pixel whose centre is nearest the point.
    let (x, y) = (px.x.floor(), px.y.floor());
    if x < 1.0 || y < 1.0 || x >= f64::from(W - 1) || y >= f64::from(H - 1) {
        return None;
    }
    let i = (y as u32 * W + x as u32) as usize;
    assert!(f.depth[i] > 0.0, "no terrain at {x},{y}");
    let c = &f.rgba[i * 4..][..3];
    Some([c[0], c[1], c[2]])
}

/// The registration test on the GPU: at every terrain sample inside a cell by 1.3
/// imagery pixels (half a pixel each for the registration's and the sampler's bilinear
/// filters, a quarter for the screen pixel: from 2.5 km up a screen pixel is 10 m, the
/// imagery is magnified, no mip blurs it), the drawn pixel is that
/// cell's colour; the cell comes from the sample's UTM coordinates through the f64 inverse
/// projection. A registration off by one grid sample (1.4 imagery pixels) fails it.
#[test]
fn checkerboard_imagery_lands_on_the_samples_the_geodesy_says() {
    let dir = tempfile::tempdir().unwrap();
    let (path, g) = checkerboard(dir.path());
    let input = DrapeInput {
        imagery: vec![read_raster(&path).unwrap()],
        landcover: None,
        table: [NO_CLASS; 256],
        budget_bytes: u64::MAX,
    };
    let desc = desc_with(Look::Classes, input);
    let cam = Camera::new(
        DVec3::new(1920.0, 1920.0, 2500.0),
        Attitude::from_degrees(0.0, -90.0, 0.0),
        Frustum::symmetric(60f64.to_radians(), W, H),
    );
    let (f, draped, bytes) = render_one(&desc, &utm_terrain(&[]), cam, Lighting::default());
    let size = draped.unwrap().imagery.as_ref().unwrap().0;
    eprintln!(
        "imagery {}×{} ({} texels per sample), {} bytes on the GPU with mips",
        size.width, size.height, size.texels_per_sample, bytes
    );
    let (mut checked, mut colours_seen) = (0, [0; 2]);
    for row in 0..N {
        for col in 0..N {
            let (lat, lon) = zone()
                .lat_lon(E0 + col as f64 * SPACING, N0 + row as f64 * SPACING)
                .unwrap();
            let (x, y) = ((lon - g.west) / g.dx, (g.north - lat) / g.dy);
            let c = f64::from(CELL);
            let border = |v: f64| (v - c * (v / c).round()).abs();
            if border(x) < 1.3 || border(y) < 1.3 {
                continue;
            }
            let p = sample_world(col, row, 500.0);
            let Some(got) = pixel(&f, &cam, p) else {
                continue;
            };
            let k = ((x as u32 / CELL + y as u32 / CELL) % 2) as usize;
            let want = COLOURS[k];
            assert!(
                (0..3).all(|i| got[i].abs_diff(want[i]) <= 3),
                "sample ({col}, {row}) at imagery pixel ({x:.1}, {y:.1}): drawn {got:?}, cell {want:?}"
            );
            checked += 1;
            colours_seen[k] += 1;
        }
    }
    assert!(
        checked > 1000 && colours_seen.iter().all(|&n| n > 300),
        "{checked} samples, {colours_seen:?}"
    );
}

/// WorldCover codes in stripes (forest, urban, water, and 200, unknown): in the class view each
/// stripe's interior is the CPU twin's colour for the raster's class at that sample, the
/// unknown stripe the derived crops, and the summary counts the unknown code.
#[test]
fn land_cover_raster_classes_match_the_cpu_twin() {
    let dir = tempfile::tempdir().unwrap();
    // 60 m pixels in the terrain's own CRS, a little larger than the terrain.
    let (w, h) = (70u32, 70u32);
    let codes: Vec<u8> = (0..w * h)
        .map(|i| [10u8, 50, 80, 200][((i % w) * 4 / w) as usize])
        .collect();
    let g = EncodeRef {
        epsg: 32632,
        west: E0 - 90.0,
        north: N0 + 3930.0,
        dx: 60.0,
        dy: 60.0,
    };
    let path = write_tif(dir.path(), "lc.tif", w, h, 1, &codes, g);
    let table =
        aerie_config::landcover::LandcoverMap::preset(aerie_config::landcover::Preset::WorldCover)
            .table();
    let input = DrapeInput {
        imagery: Vec::new(),
        landcover: Some(read_raster(&path).unwrap()),
        table,
        budget_bytes: u64::MAX,
    };
    let desc = desc_with(Look::Classes, input);
    let cam = down_camera();
    let (f, draped, _) = render_one(&desc, &utm_terrain(&[]), cam, Lighting::default());
    let draped = draped.unwrap();
    let (size, classes) = draped.classes.as_ref().unwrap();
    assert_eq!(
        draped.unknown_code_texels(&table),
        draped.code_counts.as_ref().unwrap().codes[200]
    );
    assert!(draped.unknown_code_texels(&table) > 0);
    let derived = class_weights(&CoverInputs {
        height_m: 500.0,
        normal: [0.0, 0.0, 1.0],
        jitter: 0.0,
    });
    let mut checked = [0; 4];
    // Inner samples only: the grid is turned by the zone's convergence (≈ 1.5° here), so an
    // edge sample's nearest pixel centre may lie just off the terrain.
    for row in (3..N - 1).step_by(3) {
        for col in (3..N - 1).step_by(3) {
            let p = sample_world(col, row, 500.0);
            let Some(got) = pixel(&f, &cam, p) else {
                continue;
            };
            // Stripe of the sample (raster column from its easting), away from stripe borders.
            let x = (col as f64 * SPACING + 90.0) / 60.0 - 0.5;
            let stripe = (x * 4.0 / f64::from(w)).floor() as usize;
            let edge = (x * 4.0 / f64::from(w) - (x * 4.0 / f64::from(w)).round()).abs()
                * f64::from(w)
                / 4.0;
            if edge < 2.0 {
                continue;
            }
            let corners = class_corners(
                classes,
                (size.width, size.height),
                (N as u32, N as u32),
                (col as f32, row as f32),
            );
            let want = class_colour_srgb(&raster_weights(&derived, &corners))
                .map(|c| (c * 255.0).round() as u8);
            assert!(
                (0..3).all(|i| got[i].abs_diff(want[i]) <= 2),
                "sample ({col}, {row}) stripe {stripe}: drawn {got:?}, CPU twin {want:?}"
            );
            checked[stripe] += 1;
        }
    }
    assert!(checked.iter().all(|&n| n > 10), "{checked:?}");
    // The stripes are the raster's classes (forest, urban, water) and the derived crops.
    let colour = |k: usize| {
        aerie::render::landcover::CLASS_ALBEDO_SRGB[k].map(|c| (c * 255.0).round() as u8)
    };
    let probe = |col: usize| pixel(&f, &cam, sample_world(col, 64, 500.0)).unwrap();
    for (col, class) in [(10, 4), (45, 7), (80, 0), (115, 3)] {
        let (got, want) = (probe(col), colour(class));
        assert!(
            (0..3).all(|i| got[i].abs_diff(want[i]) <= 2),
            "column {col}: {got:?} vs class {class} {want:?}"
        );
    }
}

/// Imagery in the full look, lit and fogged: a golden (`target/test-output` for review).
#[test]
fn imagery_in_the_full_look_matches_golden_image() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = checkerboard(dir.path());
    // A half-transparent red square on top, in the terrain's CRS.
    let mut top = vec![0u8; 40 * 40 * 4];
    for p in top.chunks_exact_mut(4) {
        p.copy_from_slice(&[220, 30, 30, 160]);
    }
    let g = EncodeRef {
        epsg: 32632,
        west: E0 + 1200.0,
        north: N0 + 2400.0,
        dx: 20.0,
        dy: 20.0,
    };
    let red = write_tif(dir.path(), "red.tif", 40, 40, 4, &top, g);
    let input = DrapeInput {
        imagery: vec![read_raster(&path).unwrap(), read_raster(&red).unwrap()],
        landcover: None,
        table: [NO_CLASS; 256],
        budget_bytes: u64::MAX,
    };
    let desc = desc_with(Look::Full, input);
    let cam = Camera::new(
        DVec3::new(-900.0, 600.0, 1500.0),
        Attitude::from_degrees(55.0, -20.0, 0.0),
        Frustum::symmetric(80f64.to_radians(), W, H),
    );
    let (az, el) = (210f64.to_radians(), 35f64.to_radians());
    let light = Lighting::from_host(
        Some([el.cos() * az.sin(), el.cos() * az.cos(), el.sin()]),
        None,
    );
    let hill = [(50, 50, 80, 80, 800.0)];
    let (f, _, _) = render_one(&desc, &utm_terrain(&hill), cam, light);
    let path = test_output_dir().join("drape_full_look.png");
    aerie::tools::output::write_png(&path, W, H, &f.rgba).unwrap();
    check_golden("drape_full_look_256x144", &f, GOLDEN_TOLERANCE);
}

/// Rasters that cannot be placed on the terrain stop the load with the file named.
#[test]
fn rasters_that_cannot_be_placed_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let g = EncodeRef {
        epsg: 4326,
        west: 100.0,
        north: 10.0,
        dx: 0.001,
        dy: 0.001,
    };
    let far = write_tif(dir.path(), "far.tif", 4, 4, 3, &[9; 48], g);
    let input = DrapeInput {
        imagery: vec![read_raster(&far).unwrap()],
        landcover: None,
        table: [NO_CLASS; 256],
        budget_bytes: u64::MAX,
    };
    let desc = desc_with(Look::Full, input.clone());
    let cam = down_camera();
    for (hf, why) in [
        (utm_terrain(&[]), "no overlap"),
        (synthetic(N, N, SPACING, 0.0, &[]), "no geo-reference"),
    ] {
        let (ds, b) = prepare(&desc, &hf);
        let mut r = TerrainRenderer::new(&desc).expect("create renderer");
        let e = r.load_terrain(ds, b, cam.position).unwrap_err().to_string();
        assert!(e.contains("far.tif") && e.contains(why), "{e}");
        let counters = r.validation_counters();
        r.destroy();
        assert_validation_clean(&counters);
    }
}

/// `aerie run --config` with a `[landcover]` table: its raster (relative to the config) and
/// code table are used; `--landcover-map` on the command line wins over the table. The run
/// summary's `drape` names the raster and counts the texels whose code the table lacks.
#[test]
fn the_run_config_landcover_table_maps_the_raster_and_flags_win() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(demo_dem(), &dem).unwrap();
    // 3 bands of codes over the valley: 10 (forest in WorldCover), 33 (no WorldCover code,
    // mapped to rock by the table), 99 (known to neither).
    let (w, h) = (30u32, 30u32);
    let codes: Vec<u8> = (0..w * h)
        .map(|i| [10u8, 33, 99][(i % w / 10) as usize])
        .collect();
    let g = EncodeRef {
        epsg: 4326,
        west: 11.2,
        north: 47.4,
        dx: 0.01,
        dy: 0.01,
    };
    write_tif(dir.path(), "codes.tif", w, h, 1, &codes, g);
    let cfg = dir.path().join("ig.toml");
    std::fs::write(
        &cfg,
        "[landcover]\nraster = \"codes.tif\"\npreset = \"worldcover\"\n[landcover.codes]\n33 = \"rock\"\n",
    )
    .unwrap();
    let run = |extra: &[&str]| -> serde_json::Value {
        let json = dir.path().join("run.json");
        let out = Command::new(aerie_bin())
            .args([
                "run",
                "--headless",
                "--frames",
                "2",
                "--size",
                "64x36",
                "--config",
            ])
            .arg(&cfg)
            .arg("--dem")
            .arg(&dem)
            .arg("--json")
            .arg(&json)
            .args(extra)
            .stdin(Stdio::null())
            .output()
            .expect("run aerie");
        assert!(
            out.status.success(),
            "aerie run {extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
    };
    let unknown = |s: &serde_json::Value| -> Vec<String> {
        let mut v: Vec<String> = s["drape"]["unknown_codes"]
            .as_object()
            .expect("unknown_codes")
            .keys()
            .cloned()
            .collect();
        v.sort();
        v
    };
    let s = run(&[]);
    let d = &s["drape"];
    assert!(
        d["landcover"]
            .as_str()
            .is_some_and(|p| p.ends_with("codes.tif")),
        "{d}"
    );
    assert!(d["landcover_covered_texels"].as_u64() > Some(0), "{d}");
    assert!(d["unknown_code_texels"].as_u64() > Some(0), "{d}");
    assert_eq!(unknown(&s), ["99"], "{d}");
    // The flag's preset replaces the table: 33 is unknown again.
    let s = run(&["--landcover-map", "worldcover"]);
    assert_eq!(unknown(&s), ["33", "99"], "{}", s["drape"]);
    // Within the default budget the classes take one texel per sample; under a 0.1 MiB budget
    // (104,857 one-byte texels) a coarser texture, told as capped.
    let texels = |s: &serde_json::Value| {
        let t = &s["drape"]["landcover_texture"]["texels"];
        t[0].as_u64().unwrap() * t[1].as_u64().unwrap()
    };
    assert_eq!(s["drape"]["capped"], false);
    assert!(texels(&s) > 1_000_000, "{}", s["drape"]);
    let s = run(&["--drape-mb", "0.1"]);
    let d = &s["drape"];
    assert_eq!(d["capped"], true, "{d}");
    assert!(texels(&s) <= 104_857 && texels(&s) > 90_000, "{d}");
    // The device rounds allocations up and holds a 1×1 placeholder for the absent imagery.
    let (gpu, budget) = (
        d["gpu_bytes"].as_u64().unwrap(),
        d["budget_bytes"].as_u64().unwrap(),
    );
    assert!(gpu <= budget + 32 * 1024, "{d}");
    assert_eq!(unknown(&s), ["99"], "{d}");
}
