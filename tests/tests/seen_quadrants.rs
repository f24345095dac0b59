//! A node that meets τ but crosses a frustum plane is drawn as only its seen quadrants (a
//! quadrant that crosses one too as its seen sixteenths), each read from the node's own level
//! texture (`select::seen_quadrants`, `terrain.vert`'s fetch),
//! on lavapipe with validation on. The frame must be the frame the node whole draws — the
//! same surface, depth and colour, where the frame shows — in fewer triangles; the quadrants
//! far from the eye lie outside the finer level's texture, so a quadrant read from its own
//! level's texture (or at the wrong texel) would show. On the flat plane and on a geographic
//! grid on the ellipsoid.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::TerrainRenderer;
use aerie::terrain::heightfield::Heightfield;
use aerie::terrain::select::{LodMode, SelectParams};
use aerie_tests::hills::eye_above;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;
const N: usize = 513;

/// What one frame drew: depth, colour, triangles, and the seen quadrants among its items.
struct Drawn {
    depth: Vec<f32>,
    colour: Vec<u8>,
    triangles: u64,
    /// Quadrants and sixteenths drawn from their node's texture.
    seen_quadrants: [usize; 2],
}

fn frame(hf: &Heightfield, cam: &Camera, seen_quadrants: bool, normal_maps: bool) -> Drawn {
    let mut desc = test_desc(W, H);
    desc.normal_maps = normal_maps;
    desc.select = SelectParams {
        mode: LodMode::Bounded,
        tau_px: 4.0,
        seen_quadrants,
        ..SelectParams::default()
    };
    let (ds, bake) = prepare(&desc, hf);
    let mut r = TerrainRenderer::new(&desc).expect("renderer");
    r.load_terrain(ds, bake, cam.position).expect("load");
    let stats = render_settled(&mut r, cam, 3);
    let parts = |up: u32| {
        r.selection()
            .items
            .iter()
            .filter(|i| i.refinement == 0 && i.node_level + up == i.level)
            .count()
    };
    let seen = [parts(1), parts(2)];
    let drawn = Drawn {
        depth: r.depth(),
        colour: r.colour_rgba(),
        triangles: stats.triangles,
        seen_quadrants: seen,
    };
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    assert_eq!(stats.tiles_late, 0, "{stats:?}");
    drawn
}

/// Both frames from `eye`, lit by the level textures' normal maps and by the vertices'
/// normals (the quadrants' from their node's texels): they must agree pixel for pixel (depth
/// within 0.1 %, colour within 2 of 255 per channel), the seen quadrants in fewer triangles.
fn check(name: &str, hf: &Heightfield, eye: DVec3, heading: f64, pitch: f64) {
    let cam = Camera::new(
        eye,
        Attitude::from_degrees(heading, pitch, 0.0),
        Frustum::symmetric(70f64.to_radians(), W, H),
    );
    for normal_maps in [true, false] {
        let whole = frame(hf, &cam, false, normal_maps);
        let parts = frame(hf, &cam, true, normal_maps);
        let terrain = whole.depth.iter().filter(|&&z| z != 0.0).count();
        let depth_off = whole
            .depth
            .iter()
            .zip(&parts.depth)
            .filter(|&(&a, &b)| (a - b).abs() > 1e-3 * a.abs().max(b.abs()))
            .count();
        let colour_off = whole
            .colour
            .chunks(4)
            .zip(parts.colour.chunks(4))
            .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.abs_diff(*y) > 2))
            .count();
        eprintln!(
            "{name}, normal maps {normal_maps}: {terrain} terrain pixels; triangles {} whole, {} in seen parts ({} quadrants, {} sixteenths); pixels apart: depth {depth_off}, colour {colour_off}",
            whole.triangles, parts.triangles, parts.seen_quadrants[0], parts.seen_quadrants[1]
        );
        assert!(terrain > (W * H / 3) as usize, "{terrain}");
        assert_eq!(whole.seen_quadrants, [0, 0]);
        assert!(
            parts.seen_quadrants[0] >= 4 && parts.seen_quadrants[1] >= 2,
            "{name}: the scene drew too few nodes in their seen parts: {:?}",
            parts.seen_quadrants
        );
        assert!(parts.triangles < whole.triangles);
        assert_eq!(depth_off, 0, "{name}: the quadrants drew another surface");
        assert_eq!(colour_off, 0, "{name}: the quadrants shade otherwise");
    }
}

#[test]
fn seen_quadrants_draw_the_whole_nodes_frame_on_the_plane() {
    let hf = aerie_tests::hills::hills(N, 10.0, 10.0, 30.0, None);
    check(
        "plane",
        &hf,
        eye_above(&hf, 1500.0, 1200.0, 600.0),
        40.0,
        -20.0,
    );
}

#[test]
fn seen_quadrants_draw_the_whole_nodes_frame_on_the_ellipsoid() {
    let hf = aerie_tests::hills::geographic_hills(N, 30.0);
    check(
        "ellipsoid",
        &hf,
        eye_above(&hf, 2000.0, 3000.0, 600.0),
        20.0,
        -20.0,
    );
}
