//! Skirts only where the neighbours' resolutions differ, on lavapipe with validation on. A
//! bounded frame at τ = 3 px, 20–30 m above rough hills (many nodes at different resolutions
//! side by side, cracks wide enough to see) is drawn three ways: skirts on every edge, skirts
//! where resolutions differ (the default), and none. Without skirts the frame must show
//! cracks — pixels that see past the surface the frame with every skirt drew — so the scene
//! can see a missing skirt; with the default rule it must show none, in fewer triangles. On
//! the flat plane and on a geographic grid (each node's vertices from its own frame on the
//! ellipsoid). A rule that also left out the skirts against coarser nodes at another
//! resolution shows 33 and 19 such pixels here. Where the node across is drawn exactly one
//! resolution coarser the finer node fills the crack instead (`mesh::fill_edge_indices`, no
//! skirt on either side): commands that drew no fill show 38 and 29 such pixels here.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::TerrainRenderer;
use aerie::render::tile_instances::SkirtRule;
use aerie::terrain::heightfield::GeoReference;
use aerie::terrain::heightfield::Heightfield;
use aerie::terrain::select::{LodMode, SelectParams};
use aerie_tests::hills::eye_above;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;
const N: usize = 513;

/// The hills, the finest waves 30 m high.
fn hills(spacing_x: f64, spacing_y: f64, geo: Option<GeoReference>) -> Heightfield {
    aerie_tests::hills::hills(N, spacing_x, spacing_y, 30.0, geo)
}

/// One frame per rule: (depth, triangles).
fn frames(
    hf: &Heightfield,
    eye: DVec3,
    heading: f64,
    pitch: f64,
    rules: &[SkirtRule],
) -> Vec<(Vec<f32>, u64)> {
    let cam = Camera::new(
        eye,
        Attitude::from_degrees(heading, pitch, 0.0),
        Frustum::symmetric(90f64.to_radians(), W, H),
    );
    rules
        .iter()
        .map(|&skirts| {
            let mut desc = test_desc(W, H);
            desc.select = SelectParams {
                mode: LodMode::Bounded,
                tau_px: 3.0,
                ..SelectParams::default()
            };
            desc.skirts = skirts;
            // A low minimum depth: the skirts' reach is what closes the cracks.
            desc.skirt_min_m = 0.05;
            let (ds, bake) = prepare(&desc, hf);
            let mut r = TerrainRenderer::new(&desc).expect("renderer");
            r.load_terrain(ds, bake, eye).expect("load");
            let stats = render_settled(&mut r, &cam, 3);
            let depth = r.depth();
            let counters = r.validation_counters();
            r.destroy();
            assert_validation_clean(&counters);
            assert_eq!(stats.tiles_late, 0, "{stats:?}");
            (depth, stats.triangles)
        })
        .collect()
}

/// Pixels through which `depth` sees past the surface `reference` drew: sky, or terrain more
/// than 1 % farther (reversed Z: the depth is the near plane over the distance) — a crack,
/// through which the ground behind or the sky shows.
fn cracks(depth: &[f32], reference: &[f32]) -> usize {
    depth
        .iter()
        .zip(reference)
        .filter(|&(&z, &r)| r != 0.0 && z < 0.99 * r)
        .count()
}

/// The three frames from `eye` looking along `heading` (degrees from north) and `pitch`.
fn check(name: &str, hf: &Heightfield, eye: DVec3, heading: f64, pitch: f64) {
    let f = frames(
        hf,
        eye,
        heading,
        pitch,
        &[
            SkirtRule::Everywhere,
            SkirtRule::WhereResolutionsDiffer,
            SkirtRule::None,
        ],
    );
    let (everywhere, needed, none) = (&f[0], &f[1], &f[2]);
    let terrain = everywhere.0.iter().filter(|&&z| z != 0.0).count();
    let (needed_cracks, bare_cracks) = (
        cracks(&needed.0, &everywhere.0),
        cracks(&none.0, &everywhere.0),
    );
    eprintln!(
        "{name}: {terrain} terrain pixels; triangles {} everywhere, {} where needed, {} without; pixels through a crack where needed {needed_cracks}, without {bare_cracks}",
        everywhere.1, needed.1, none.1
    );
    assert!(terrain > (W * H / 3) as usize, "{terrain}");
    assert!(
        bare_cracks >= 20,
        "the scene shows no crack to close: {bare_cracks}"
    );
    assert_eq!(
        needed_cracks, 0,
        "{name}: skirts left out where a crack opens"
    );
    assert!(none.1 < needed.1 && needed.1 < everywhere.1);
}

#[test]
fn skirts_where_resolutions_differ_close_every_crack_on_the_plane() {
    let hf = hills(10.0, 10.0, None);
    check("plane", &hf, eye_above(&hf, 600.0, 500.0, 20.0), 30.0, -8.0);
}

#[test]
fn skirts_where_resolutions_differ_close_every_crack_on_the_ellipsoid() {
    let hf = aerie_tests::hills::geographic_hills(N, 30.0);
    check(
        "ellipsoid",
        &hf,
        eye_above(&hf, 2000.0, 3000.0, 30.0),
        0.0,
        -6.0,
    );
}
