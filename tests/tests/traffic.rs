//! Other traffic (issue 18) drawn on lavapipe with the validation layer on: three default
//! aircraft at different distances over the Inn valley (golden image, one LOD level each),
//! depth-tested against the terrain (an aircraft under the ground leaves the frame as it was),
//! and the frame's triangles and entity counts.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::entity_instances::EntityDraw;
use aerie::render::entity_lod::LodParams;
use aerie::render::frame::TerrainRenderer;
use aerie::render::models::{ModelLibrary, DEFAULT_MODEL};
use aerie::terrain::load_dem;
use aerie::terrain::query::{height_of_terrain, InMemorySource, Lookup};
use aerie_sim_bridge::ig::entities::body_to_enu;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;

/// South of Innsbruck, looking north across the Inn valley (as gpu_render.rs's golden view).
fn inn_camera() -> Camera {
    Camera::new(
        DVec3::new(30500.0, 12000.0, 4500.0),
        Attitude::from_degrees(0.0, -15.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), W, H),
    )
}

/// An aircraft `ahead_m` along the view, `right_m` to its right, heading east (seen side on).
fn aircraft(id: u16, cam: &Camera, ahead_m: f64, right_m: f64, up_m: f64) -> EntityDraw {
    let b = cam.attitude.body_to_world();
    EntityDraw {
        id,
        model: DEFAULT_MODEL,
        position: cam.position + b.x_axis * ahead_m + b.y_axis * right_m - b.z_axis * up_m,
        body_to_world: body_to_enu(90.0, 0.0, 0.0),
    }
}

struct Frame {
    rgba: Vec<u8>,
    depth: Vec<f32>,
    triangles: u64,
    entities: Option<aerie::render::entity_instances::EntityFrameStats>,
}

/// Renders `cam` once without entities and once with the entities `place` makes (given the
/// ground height at a point), one renderer, validation on.
fn render_with(place: impl FnOnce(&dyn Fn(f64, f64) -> f64) -> Vec<EntityDraw>) -> (Frame, Frame) {
    let hf = load_dem(&demo_dem()).expect("demo DEM loads");
    let desc = test_desc(W, H);
    let (ds, bake) = prepare(&desc, &hf);
    let src = InMemorySource::new(ds.clone(), bake.clone()).expect("queries");
    let ground = |x: f64, y: f64| match height_of_terrain(&src, x, y) {
        Lookup::Ready(g) => g.height_m,
        other => panic!("no ground at {x}, {y}: {other:?}"),
    };
    let entities = place(&ground);
    let cam = inn_camera();
    let mut r = TerrainRenderer::new(&desc).expect("renderer");
    r.load_terrain(ds, bake, cam.position).expect("terrain");
    let frame = |r: &mut TerrainRenderer| {
        let stats = r.render(&cam).expect("render");
        Frame {
            rgba: r.colour_rgba(),
            depth: r.depth(),
            triangles: stats.triangles,
            entities: r.entity_stats(),
        }
    };
    let plain = frame(&mut r);
    r.set_entity_models(&ModelLibrary::with_default(), 1.0, LodParams::default())
        .expect("entity models");
    r.set_entities(entities);
    let with = frame(&mut r);
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    (plain, with)
}

fn pixel(cam: &Camera, p: DVec3) -> usize {
    let (px, _) = cam.project_px(p, W, H).expect("in front");
    (px.y as usize).min(H as usize - 1) * W as usize + (px.x as usize).min(W as usize - 1)
}

#[test]
fn three_aircraft_at_three_distances_over_the_inn_valley() {
    let cam = inn_camera();
    // Radius ≈ 5.8 m, f = 128 px: ≈ 53 px at 14 m (level 0), 18.6 px at 40 m (level 1),
    // 5 px at 150 m (level 2).
    let planes = vec![
        aircraft(1, &cam, 14.0, 4.0, -3.0),
        aircraft(2, &cam, 40.0, -14.0, 3.0),
        aircraft(3, &cam, 150.0, 20.0, 8.0),
    ];
    let (plain, with) = render_with(|_| planes.clone());
    let s = with.entities.expect("entity stats");
    assert_eq!((s.known, s.drawn, s.culled), (3, 3, 0), "{s:?}");
    assert_eq!(s.instances_per_level, [1, 1, 1], "{s:?}");
    assert_eq!(s.draws, 3);
    assert_eq!(with.triangles, plain.triangles + s.triangles(), "{s:?}");
    assert!(s.triangles_per_level[0] > s.triangles_per_level[1]);
    assert!(s.triangles_per_level[1] > s.triangles_per_level[2]);
    // Each aircraft is in front of the terrain where its fuselage is drawn: nearer depth
    // (reversed-Z: larger) and a different colour than the terrain-only frame.
    for p in &planes {
        let i = pixel(&cam, p.position);
        assert!(
            with.depth[i] > plain.depth[i],
            "aircraft {}: depth {} vs terrain {}",
            p.id,
            with.depth[i],
            plain.depth[i]
        );
        assert_ne!(with.rgba[i * 4..i * 4 + 3], plain.rgba[i * 4..i * 4 + 3]);
    }
    let golden = Rendered {
        width: W,
        height: H,
        rgba: with.rgba,
        depth: with.depth,
        stats: Default::default(),
    };
    check_golden("traffic_inn_valley_256x144", &golden, GOLDEN_TOLERANCE);
}

#[test]
fn an_aircraft_under_the_ground_is_hidden_by_the_terrain() {
    let cam = inn_camera();
    // Where the ray through a point low in the view meets the ground, 300 m under it: a
    // point under a heightfield is hidden from any eye above it.
    let (plain, with) = render_with(|ground| {
        let dir = cam.pixel_ray(W as f64 * 0.5, H as f64 * 0.8, W, H);
        let hit = (1..4000)
            .map(|k| cam.position + dir * (k as f64 * 10.0))
            .find(|p| p.z < ground(p.x, p.y))
            .expect("the ray meets the ground");
        let mut a = aircraft(9, &cam, 0.0, 0.0, 0.0);
        a.position = DVec3::new(hit.x, hit.y, ground(hit.x, hit.y) - 300.0);
        vec![a]
    });
    let s = with.entities.expect("entity stats");
    assert_eq!(s.drawn, 1, "in the frustum, so drawn: {s:?}");
    assert!(with.triangles > plain.triangles);
    assert_eq!(with.rgba, plain.rgba, "the terrain hides it");
}

/// The CCL host (`cigi-host traffic`) creates, moves, attaches, parks in Standby and destroys
/// entities while `aerie run --headless` draws them: the counts in the run summary follow, and
/// the frame's triangles grow while the aircraft are drawn and come back when they are gone.
#[test]
fn a_ccl_host_creates_moves_attaches_and_destroys_entities() {
    use aerie_tests::cigi_host::{ig_run, Arch};
    let args = [
        "--start",
        "47.3,11.4,3000,0,0,0",
        "--standby",
        "30,45",
        "--destroy-frame",
        "70",
    ];
    let r = ig_run(Arch::Native, 3, 150, 30, "traffic", &args);
    let ig = &r.summary["ig"];
    let t = &ig["traffic"];
    let label = &r.label;
    assert!(
        r.host.sent("traffic_destroyed").count() == 1,
        "{label}: the host never got to its destroy frame"
    );
    // Entity Control (2), Conformal Clamped (3) and Rate Control (8) arrived.
    for id in ["2", "3", "8"] {
        assert!(
            ig["packets"][id].as_u64().unwrap_or(0) > 0,
            "{label}: no packet {id}: {}",
            ig["packets"]
        );
    }
    // Ownship + lead + wingman + truck at most; after the destroy the ownship and the truck.
    assert_eq!(t["known_max"], 4, "{label}: {t}");
    assert_eq!(ig["entities"], 2, "{label}: {ig}");
    assert_eq!(t["placed_last"], 1, "{label}: only the truck is left: {t}");
    // The lead and its wingman (30 m to its right) are drawn 400 m ahead; the truck on the
    // ground far below the level view is culled.
    assert_eq!(t["drawn_max"], 2, "{label}: {t}");
    assert_eq!(t["drawn_last"], 0, "{label}: {t}");
    assert_eq!(t["culled_last"], 1, "{label}: {t}");
    let levels = t["instances_per_level"].as_array().unwrap();
    assert!(levels.iter().any(|n| n.as_u64() > Some(0)), "{label}: {t}");
    // The frame's triangles: the same before creation and after destruction, more between.
    let tri: Vec<u64> = r
        .rows
        .iter()
        .filter_map(|row| row.get("triangles")?.parse().ok())
        .collect();
    let (first, last) = (tri[0], *tri.last().unwrap());
    let most = *tri.iter().max().unwrap();
    assert_eq!(first, last, "{label}: triangles {tri:?}");
    assert!(most > first, "{label}: triangles never grew: {tri:?}");
    // While entity 1 is in Standby only the wingman is drawn: three distinct counts.
    let mut distinct = tri.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() >= 3, "{label}: {distinct:?}");
}

/// Figures for the report, not assertions (`cargo test -p aerie-tests --test traffic
/// gpu_figures -- --ignored --nocapture`): the terrain + entity pass's GPU time on this device
/// at 1280×720 with 1000 default aircraft in view, against the terrain alone.
#[test]
#[ignore]
fn gpu_figures() {
    let (w, h) = (1280, 720);
    let hf = load_dem(&demo_dem()).expect("demo DEM loads");
    let mut desc = test_desc(w, h);
    desc.validation = false;
    let (ds, bake) = prepare(&desc, &hf);
    let cam = Camera::new(
        DVec3::new(30500.0, 12000.0, 4500.0),
        Attitude::from_degrees(0.0, -15.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), w, h),
    );
    let mut r = TerrainRenderer::new(&desc).expect("renderer");
    r.load_terrain(ds, bake, cam.position).expect("terrain");
    let time = |r: &mut TerrainRenderer, label: &str| {
        let mut ms: Vec<f64> = (0..10)
            .map(|_| r.render(&cam).expect("render").gpu_terrain_ms)
            .collect();
        ms.sort_by(f64::total_cmp);
        let s = r.entity_stats();
        println!(
            "{label}: terrain pass median {:.2} ms GPU; entities {s:?}",
            ms[5]
        );
    };
    // Rows of 40 aircraft 20 m apart, 25 m between rows, from 30 m ahead.
    let planes = || -> Vec<EntityDraw> {
        (0..1000)
            .map(|i| {
                let (row, col) = ((i / 40) as f64, (i % 40) as f64);
                let up = (i % 5) as f64 * 10.0 - 20.0;
                aircraft(i as u16, &cam, 30.0 + row * 25.0, col * 20.0 - 400.0, up)
            })
            .collect()
    };
    time(&mut r, "terrain only");
    r.set_entity_models(&ModelLibrary::with_default(), 1.0, LodParams::default())
        .expect("models");
    r.set_entities(planes());
    time(&mut r, "1000 aircraft, LOD on");
    r.set_entity_models(
        &ModelLibrary::with_default(),
        1.0,
        LodParams {
            thresholds_px: [0.0002, 0.0001],
            hysteresis: 0.0,
        },
    )
    .expect("models");
    r.set_entities(planes());
    time(&mut r, "1000 aircraft, LOD off (level 0)");
    r.destroy();
}
