//! A store's imagery layer drawn on lavapipe with the validation layer on (issue 17, item 3):
//! level 0 of the layer draws the very image the same raster draped in memory draws; a
//! `--drape-mb` that admits only a coarse level draws that level where the CPU bilinear
//! oracle says (the texture spans the level's texels, not the grid); and end to end,
//! `aerie import --imagery` writes the layer that `render` then draws from the store, streamed
//! or read whole, with its errors named (overlap, an existing layer, bad texels per sample),
//! and a store replaced without imagery loses the old store's layer.

use std::path::Path;
use std::process::{Command, Output};
use std::sync::Arc;
use std::time::Duration;

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::drape_textures::DrapeInput;
use aerie::render::frame::{Look, RendererDesc, TerrainRenderer};
use aerie::terrain::bake::ErrorBake;
use aerie::terrain::dataset::Dataset;
use aerie::terrain::drape::{encode_geotiff, read_raster, EncodeRef, LevelDraper};
use aerie::terrain::source::TerrainSource;
use aerie::terrain::store::{
    imagery_path, open_imagery_beside, read_level, store_grid, write_imagery_in, write_store,
    ImportParams, Store,
};
use aerie::terrain::stream::{StreamParams, StreamedStore};
use aerie_tests::drape_fixtures::*;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;

fn camera() -> Camera {
    Camera::new(
        DVec3::new(1920.0, 1920.0, 2500.0),
        Attitude::from_degrees(0.0, -90.0, 0.0),
        Frustum::symmetric(60f64.to_radians(), W, H),
    )
}

fn desc() -> RendererDesc {
    let mut d = test_desc(W, H);
    d.look = Look::Classes;
    d
}

/// The UTM terrain imported as a store in `dir`, with the checkerboard as its imagery layer
/// at the texels per sample the in-memory drape picks (2: 1" pixels on 30 m samples).
fn store_with_imagery(dir: &Path) -> (std::path::PathBuf, Arc<Dataset>, Arc<ErrorBake>) {
    let d = desc();
    let (ds, b) = prepare(&d, &utm_terrain(&[]));
    let path = dir.join("utm.aerie");
    let ip = ImportParams {
        sources: vec!["utm".into()],
        page_tiles: 2,
        zstd_level: 1,
    };
    write_store(&path, &ds, &b, &ip, &|_, _| {}).expect("import");
    let (tif, _) = checkerboard(dir);
    let raster = read_raster(&tif).unwrap();
    let store = Store::open(&path).unwrap();
    let grid = store_grid(&store).unwrap();
    let k = aerie::terrain::drape::store_texels_per_sample(&grid, std::slice::from_ref(&raster));
    assert_eq!(k, 2);
    let draper = LevelDraper::new(&grid, &[raster], k, store.header().levels).unwrap();
    write_imagery_in(
        aerie_io::real(),
        &store,
        &draper,
        vec!["board.tif".into()],
        1,
        &|_, _| {},
    )
    .unwrap();
    (path, ds, b)
}

/// Renders the store streamed until nothing is pending; the image and what was draped.
fn render_store(
    desc: &RendererDesc,
    path: &Path,
) -> (
    Vec<u8>,
    Option<Arc<aerie::render::drape_textures::DrapedRasters>>,
) {
    let (store, bake) = StreamedStore::open(path, StreamParams::default()).expect("open");
    let rects = desc.start_up_rects(store.grid());
    store
        .wait_resident(&rects, Duration::from_secs(60))
        .expect("coarsest level");
    let mut r = TerrainRenderer::new(desc).expect("renderer");
    r.load_source(Arc::new(store), bake, camera().position)
        .expect("load");
    for _ in 0..2000 {
        let s = r.render(&camera()).expect("render");
        if s.tiles_late_stream == 0 && s.cells_pending == 0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let rgba = r.colour_rgba();
    let (draped, _) = r.draped();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    (rgba, draped)
}

#[test]
fn level_0_of_a_stores_layer_draws_what_the_raster_draped_in_memory_draws() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, b) = store_with_imagery(dir.path());
    let (store_img, draped) = render_store(&desc(), &path);
    let level = draped
        .unwrap()
        .layer_level
        .clone()
        .expect("the layer is draped");
    assert_eq!((level.level, level.texels_per_sample), (0, 2));

    let mut mem = desc();
    mem.drape = Some(Arc::new(DrapeInput {
        imagery: vec![read_raster(&dir.path().join("board.tif")).unwrap()],
        landcover: None,
        table: [255; 256],
        budget_bytes: mem.drape_budget_bytes,
    }));
    let mut r = TerrainRenderer::new(&mem).expect("renderer");
    r.load_terrain(ds, b, camera().position).expect("load");
    r.render(&camera()).expect("render");
    let mem_img = r.colour_rgba();
    let (draped, _) = r.draped();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    assert_eq!(
        draped
            .unwrap()
            .imagery
            .as_ref()
            .unwrap()
            .0
            .texels_per_sample,
        2
    );

    let worst = store_img
        .iter()
        .zip(&mem_img)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    let board = store_img
        .chunks(4)
        .filter(|p| {
            COLOURS
                .iter()
                .any(|c| (0..3).all(|i| p[i].abs_diff(c[i]) <= 3))
        })
        .count();
    eprintln!("store vs in-memory imagery: worst channel difference {worst}, {board} board pixels");
    assert!(worst <= 1, "worst channel difference {worst}");
    assert!(
        board > (W * H / 2) as usize,
        "{board} pixels show the board"
    );
}

/// A terrain loaded after one with imagery draws without it: the renderer puts the placeholder
/// textures back (a database switch from a store with a layer to a plain DEM).
#[test]
fn a_terrain_without_imagery_loaded_after_one_with_it_draws_none() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, b) = store_with_imagery(dir.path());
    let d = desc();
    let (store, bake) = StreamedStore::open(&path, StreamParams::default()).expect("open");
    let rects = d.start_up_rects(store.grid());
    store
        .wait_resident(&rects, Duration::from_secs(60))
        .expect("coarsest level");
    let mut r = TerrainRenderer::new(&d).expect("renderer");
    r.load_source(Arc::new(store), bake, camera().position)
        .expect("load");
    let board_pixels = |rgba: &[u8]| {
        rgba.chunks(4)
            .filter(|p| {
                COLOURS
                    .iter()
                    .any(|c| (0..3).all(|i| p[i].abs_diff(c[i]) <= 3))
            })
            .count()
    };
    r.render(&camera()).expect("render");
    let with = board_pixels(&r.colour_rgba());
    assert!(r.draped().0.is_some());
    r.load_terrain(ds, b, camera().position).expect("load");
    r.render(&camera()).expect("render");
    let without = board_pixels(&r.colour_rgba());
    let (draped, bytes) = r.draped();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    eprintln!("board pixels: {with} with the layer, {without} after the plain terrain");
    assert!(
        with > (W * H / 2) as usize && without == 0,
        "{with} then {without}"
    );
    assert!(draped.is_none(), "nothing draped on the plain terrain");
    assert!(bytes < 64 * 1024, "placeholders only: {bytes} bytes");
}

fn srgb_to_linear(c: u8) -> f64 {
    let f = f64::from(c) / 255.0;
    if f <= 0.04045 {
        f / 12.92
    } else {
        ((f + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(l: f64) -> f64 {
    let s = if l <= 0.003_130_8 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    s * 255.0
}

/// The level raster's colour at texel coordinate (x, y), bilinear in linear light (the
/// sampler's filter on an sRGB texture), clamped to the edge.
fn bilinear(l: &aerie::terrain::store::LevelImagery, x: f64, y: f64) -> [f64; 3] {
    let (fx, fy) = (x.floor(), y.floor());
    let (u, v) = (x - fx, y - fy);
    let mut out = [0.0; 3];
    for (dx, dy, w) in [
        (0, 0, (1.0 - u) * (1.0 - v)),
        (1, 0, u * (1.0 - v)),
        (0, 1, (1.0 - u) * v),
        (1, 1, u * v),
    ] {
        let c = (fx as i64 + dx).clamp(0, l.width as i64 - 1) as usize;
        let r = (fy as i64 + dy).clamp(0, l.height as i64 - 1) as usize;
        let p = &l.rgba[(r * l.width + c) * 4..][..3];
        for i in 0..3 {
            out[i] += w * srgb_to_linear(p[i]);
        }
    }
    out.map(linear_to_srgb)
}

/// A budget of 10,000 bytes admits level 3 (33 × 33 texels, 4 samples each: the texture spans
/// 132 samples over the grid's 129). Every sample is drawn within 4 levels of the oracle's
/// colour range over ±0.15 texel around the sample's texel coordinate (the screen pixel is
/// 0.1 texel); taking the texture as spanning the grid instead puts the far half of the
/// terrain 0.4–0.75 texel off, across the board's edges.
#[test]
fn a_coarse_level_chosen_by_the_budget_is_drawn_where_the_oracle_says() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _, _) = store_with_imagery(dir.path());
    let mut d = desc();
    d.drape_budget_bytes = 10_000;
    let (img, draped) = render_store(&d, &path);
    let level = draped
        .unwrap()
        .layer_level
        .clone()
        .expect("the layer is draped");
    assert_eq!(level.level, 3);
    let store = Store::open(&path).unwrap();
    let layer = open_imagery_beside(&aerie_io::real(), &path, &store)
        .unwrap()
        .unwrap();
    let (raster, failed) = read_level(&layer, 3, &|_, _| {});
    assert!(failed.is_empty(), "{failed:?}");
    assert_eq!((raster.width, raster.height), (33, 33));
    let cam = camera();
    let (mut checked, mut worst) = (0, 0.0f64);
    for row in 0..N {
        for col in 0..N {
            let Some((px, _)) = cam.project_px(sample_world(col, row, 500.0), W, H) else {
                continue;
            };
            let (x, y) = (px.x.floor(), px.y.floor());
            if x < 1.0 || y < 1.0 || x >= f64::from(W - 1) || y >= f64::from(H - 1) {
                continue;
            }
            let got = &img[((y as u32 * W + x as u32) * 4) as usize..][..3];
            let t = |g: usize| (g as f64 + 0.5) * 2.0 / 8.0 - 0.5;
            let (tx, ty) = (t(col), t(row));
            let mut lo = [f64::MAX; 3];
            let mut hi = [f64::MIN; 3];
            for dx in [-0.15, 0.0, 0.15] {
                for dy in [-0.15, 0.0, 0.15] {
                    let c = bilinear(&raster, tx + dx, ty + dy);
                    for i in 0..3 {
                        lo[i] = lo[i].min(c[i]);
                        hi[i] = hi[i].max(c[i]);
                    }
                }
            }
            for i in 0..3 {
                let g = f64::from(got[i]);
                let off = (lo[i] - g).max(g - hi[i]).max(0.0);
                worst = worst.max(off);
                assert!(
                    off <= 4.0,
                    "sample ({col}, {row}) at level-3 texel ({tx:.2}, {ty:.2}): drawn {got:?}, oracle {lo:?}..{hi:?}"
                );
            }
            checked += 1;
        }
    }
    eprintln!(
        "{checked} samples checked against the level-3 oracle, worst {worst:.2} outside its range"
    );
    assert!(checked > 3000, "{checked}");
}

fn aerie(args: &[&str]) -> Output {
    Command::new(aerie_bin())
        .args(args)
        .output()
        .expect("run aerie")
}

fn ok(args: &[&str]) -> (String, String) {
    let out = aerie(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "aerie {args:?} failed:\n{err}");
    (String::from_utf8_lossy(&out.stdout).to_string(), err)
}

fn refused(args: &[&str], says: &[&str]) {
    let out = aerie(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "aerie {args:?}:\n{err}");
    for s in says {
        assert!(err.contains(s), "aerie {args:?} should say {s:?}:\n{err}");
    }
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// A geographic checkerboard at 3" (the tile's own spacing: 1 texel per sample) over
/// 47.2–47.4°N, 11.3–11.5°E of the demo tile: 240 × 240 pixels, cells of 12.
fn demo_board(dir: &Path, west: f64) -> std::path::PathBuf {
    let d = 3.0 / 3600.0;
    let mut data = Vec::new();
    for r in 0..240u32 {
        for c in 0..240u32 {
            data.extend_from_slice(&COLOURS[((c / 12 + r / 12) % 2) as usize]);
        }
    }
    let g = EncodeRef {
        epsg: 4326,
        west,
        north: 47.4,
        dx: d,
        dy: d,
    };
    let p = dir.join(format!("board_{west}.tif"));
    std::fs::write(&p, encode_geotiff(240, 240, 3, &data, Some(g)).unwrap()).unwrap();
    p
}

#[test]
fn import_writes_the_layer_render_draws_it_and_errors_name_the_cause() {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(demo_dem(), &dem).unwrap();
    let board = demo_board(dir.path(), 11.3);
    let store = dir.path().join("inn.aerie");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let sj = dir.path().join("import.json");
    let (out, _) = ok(&[
        "import",
        &s(&dem),
        "--out",
        &s(&store),
        "--imagery",
        &s(&board),
        "--json",
        &s(&sj),
    ]);
    assert!(
        out.contains("imagery ") && out.contains("1 texels/sample"),
        "{out}"
    );
    let summary = json(&sj);
    let im = &summary["imagery"];
    assert_eq!(im["texels_per_sample"], 1, "{summary}");
    assert!(im["covered_pages"].as_u64().unwrap() > 0, "{summary}");
    assert!(imagery_path(&store).is_file());

    // Drawn from the store, streamed and read whole: the board under a nadir view.
    let mut first: Option<image::RgbImage> = None;
    for whole in [false, true] {
        let png = dir.path().join(format!("nadir_{whole}.png"));
        let mut args = vec![
            "render".to_string(),
            "--dem".into(),
            s(&store),
            "--camera-geo".into(),
            "47.3,11.4,6000,0,-90,0".into(),
            "--look".into(),
            "classes".into(),
            "--size".into(),
            "96x64".into(),
            "--out".into(),
            s(&png),
        ];
        if whole {
            args.push("--load-whole".into());
        }
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        ok(&a);
        let j = json(&png.with_file_name(format!("nadir_{whole}.png.json")));
        let l = &j["drape"]["imagery_layer"];
        assert_eq!(l["level"], 0, "{j}");
        assert_eq!(l["texels_per_sample"], 1, "{j}");
        let img = image::open(&png).unwrap().to_rgb8();
        let board_px = img
            .pixels()
            .filter(|p| {
                COLOURS
                    .iter()
                    .any(|c| (0..3).all(|i| p[i].abs_diff(c[i]) <= 3))
            })
            .count();
        // A cell is 11 screen pixels: a third of them blend two cells' texels.
        assert!(
            board_px > 96 * 64 / 3,
            "{board_px} board pixels (whole: {whole})"
        );
        match &first {
            None => first = Some(img),
            Some(f) => {
                let worst = f
                    .as_raw()
                    .iter()
                    .zip(img.as_raw())
                    .map(|(a, b)| a.abs_diff(*b))
                    .max();
                assert!(
                    worst <= Some(1),
                    "streamed and read whole differ by {worst:?}"
                );
            }
        }
    }

    // info describes the layer and --verify reads every page of it.
    let info = aerie(&["info", &s(&store), "--json", "--verify"]);
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    let im = &v["imagery"];
    assert_eq!(im["texels_per_sample"], 1, "{v}");
    assert_eq!(im["pages"], v["pages"], "{v}");
    assert_eq!(im["verify"]["pages_ok"], v["pages"], "{v}");
    assert_eq!(im["verify"]["checksum_errors"], 0, "{v}");
    let (text, _) = ok(&["info", &s(&store)]);
    assert!(
        text.contains("imagery layer") && text.contains(&s(&board)),
        "{text}"
    );

    // A damaged page of level 0 is named by info --verify (exit 2); render names it and draws
    // the rest.
    let layer = imagery_path(&store);
    let good = std::fs::read(&layer).unwrap();
    let mut bad = good.clone();
    // The first stored page (pages are written in index order, level 0 first; empty ones take
    // no bytes) begins right after the header.
    let opened = Store::open(&store).unwrap();
    let l = open_imagery_beside(&aerie_io::real(), &store, &opened)
        .unwrap()
        .unwrap();
    let at = l.header().header_size as usize + 40;
    bad[at] ^= 0x5a;
    std::fs::write(&layer, &bad).unwrap();
    refused(
        &["info", &s(&store), "--verify"],
        &["bad imagery pages", "aerie-imagery"],
    );
    let png = dir.path().join("damaged.png");
    let (_, err) = ok(&[
        "render",
        "--dem",
        &s(&store),
        "--camera-geo",
        "47.3,11.4,6000,0,-90,0",
        "--size",
        "48x32",
        "--out",
        &s(&png),
    ]);
    assert!(
        err.contains("aerie-imagery") && err.contains("drawn without imagery"),
        "{err}"
    );
    std::fs::write(&layer, &good).unwrap();

    // Adding to a store that has a layer needs --overwrite; bad k and no overlap are named.
    let add = |tif: &Path, out: &Path, extra: &[&str]| -> Vec<String> {
        let mut v = vec![
            "import".into(),
            "--imagery".into(),
            s(tif),
            "--out".into(),
            s(out),
        ];
        v.extend(extra.iter().map(|e| e.to_string()));
        v
    };
    refused(
        &strs(&add(&board, &store, &[])),
        &["aerie-imagery", "--overwrite"],
    );
    let k3 = add(&board, &store, &["--overwrite", "--imagery-texels", "3"]);
    refused(&strs(&k3), &["--imagery-texels 3"]);
    refused(
        &[
            "import",
            &s(&dem),
            "--out",
            &s(&store),
            "--overwrite",
            "--imagery-texels",
            "2",
        ],
        &["--imagery"],
    );
    let far = demo_board(dir.path(), 30.0);
    let off = add(&far, &store, &["--overwrite"]);
    refused(&strs(&off), &["no overlap", "board_30.tif"]);
    let none = add(&board, &dir.path().join("none.aerie"), &[]);
    refused(&strs(&none), &["no store there"]);
    let k2 = add(&board, &store, &["--overwrite", "--imagery-texels", "2"]);
    let (out, _) = ok(&strs(&k2));
    assert!(out.contains("2 texels/sample"), "{out}");
    // Replacing the store without --imagery removes the old store's layer, which it would refuse.
    let (_, err) = ok(&["import", &s(&dem), "--out", &s(&store), "--overwrite"]);
    assert!(
        err.contains("removed") && !imagery_path(&store).exists(),
        "{err}"
    );
}
