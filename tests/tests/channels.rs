//! Multi-channel: one tile selection shared by every channel (issue 7 item 3) — each shared tile
//! gets one resolution, every channel's visible ground is covered once, and the seam between two
//! adjacent channels of a three-channel wall shows the same terrain.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::TerrainRenderer;
use aerie::terrain::clipmap::{place_levels, ClipmapDesc};
use aerie::terrain::load_dem;
use aerie::terrain::select::{select_tiles_multi, SelectParams, Selection, View};
use aerie_tests::*;
use glam::DVec3;
use std::collections::HashMap;

const W: u32 = 160;
const H: u32 = 120;

/// Three 60° channels at −60°/0°/+60° of a level aircraft (the wall3 preset's geometry).
fn wall3(eye: DVec3, heading: f64, pitch: f64) -> Vec<Camera> {
    [-60.0, 0.0, 60.0]
        .iter()
        .map(|off| {
            Camera::new(
                eye,
                Attitude::from_degrees(heading + off, pitch, 0.0),
                Frustum::symmetric(60f64.to_radians(), W, H),
            )
        })
        .collect()
}

#[test]
fn shared_selection_gives_each_tile_one_resolution_and_covers_every_channel() {
    let hf = load_dem(&demo_dem()).unwrap();
    let desc = test_desc(W, H);
    let (ds, b) = prepare(&desc, &hf);
    let clip = ClipmapDesc {
        tile_quads: 16,
        patch_tiles: 8,
        margin_tiles: 2,
        width: ds.hf.width as u32,
        height: ds.hf.height as u32,
    };
    let eye = DVec3::new(30500.0, 12000.0, 3200.0);
    let cams = wall3(eye, 10.0, -8.0);
    let views: Vec<View> = cams
        .iter()
        .map(|c| View {
            camera: c,
            viewport: (W, H),
            tau_px: 1.0,
        })
        .collect();
    let placements = place_levels(&clip, [eye.x / ds.hf.spacing_x, eye.y / ds.hf.spacing_y]);
    let mut sel = Selection::default();
    select_tiles_multi(
        &b,
        &clip,
        &placements,
        &views,
        &SelectParams::default(),
        &mut sel,
    );
    // One refinement per ring tile.
    let mut r_of: HashMap<(u32, u32, u32), u32> = HashMap::new();
    for i in &sel.items {
        let r = *r_of.entry((i.level, i.tx, i.ty)).or_insert(i.refinement);
        assert_eq!(
            r,
            i.refinement,
            "tile {:?} has two refinements",
            (i.level, i.tx, i.ty)
        );
    }
    // Every channel's visible ground is drawn exactly once.
    let q = 16usize;
    let hfp = &ds.hf;
    let cells = (hfp.width - 1) * (hfp.height - 1);
    let mut count = vec![0u8; cells];
    for i in &sel.items {
        let side = q << i.node_level;
        let (c0, r0) = (i.node_tx as usize * side, i.node_ty as usize * side);
        for row in r0..(r0 + side).min(hfp.height - 1) {
            for c in c0..(c0 + side).min(hfp.width - 1) {
                count[row * (hfp.width - 1) + c] += 1;
            }
        }
    }
    assert!(count.iter().all(|&n| n <= 1), "overlapping nodes");
    let r = aerie::terrain::select::EARTH_RADIUS_M;
    let mut visible_per_channel = vec![0; cams.len()];
    for row in (0..ds.valid_height - 1).step_by(3) {
        for c in (0..ds.valid_width - 1).step_by(3) {
            let (x, y) = (
                (c as f64 + 0.5) * hfp.spacing_x,
                (row as f64 + 0.5) * hfp.spacing_y,
            );
            let d2 = (x - eye.x).powi(2) + (y - eye.y).powi(2);
            let z = hfp.height_at_m(x, y) - d2 / (2.0 * r);
            for (k, cam) in cams.iter().enumerate() {
                if let Some((p, _)) = cam.project_px(DVec3::new(x, y, z), W, H) {
                    if p.x >= 0.0 && p.x <= W as f64 && p.y >= 0.0 && p.y <= H as f64 {
                        visible_per_channel[k] += 1;
                        assert_eq!(
                            count[row * (hfp.width - 1) + c],
                            1,
                            "channel {k}: cell ({c}, {row}) not drawn"
                        );
                    }
                }
            }
        }
    }
    assert!(
        visible_per_channel.iter().all(|&n| n > 100),
        "{visible_per_channel:?}"
    );
}

#[test]
fn wall3_seam_columns_see_the_same_terrain() {
    let hf = load_dem(&demo_dem()).unwrap();
    let desc = test_desc(W, H);
    let (ds, b) = prepare(&desc, &hf);
    // Level flight: heading offsets then compose exactly with the aircraft attitude.
    let cams = wall3(DVec3::new(30500.0, 12000.0, 3200.0), 10.0, 0.0);
    // The seam: the left channel's right edge and the centre channel's left edge are one direction.
    let a = cams[0].pixel_ray(W as f64, H as f64 / 2.0, W, H);
    let b_dir = cams[1].pixel_ray(0.0, H as f64 / 2.0, W, H);
    assert!((a - b_dir).length() < 1e-9, "{a} vs {b_dir}");

    let mut r = TerrainRenderer::new(&desc).unwrap();
    r.load_terrain(ds, b, cams[1].position).unwrap();
    r.set_channels(cams.iter().map(|c| (*c, (W, H), 1.0)).collect());
    let mut images = Vec::new();
    let mut digests = Vec::new();
    for cam in &cams {
        let stats = r.render(cam).unwrap();
        digests.push(stats.selection_digest);
        images.push(r.colour_rgba());
    }
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    assert!(
        digests.windows(2).all(|w| w[0] == w[1]),
        "channels drew different selections"
    );
    let column = |img: &[u8], x: u32| -> Vec<u8> {
        (0..H)
            .flat_map(|y| img[((y * W + x) * 4) as usize..][..3].to_vec())
            .collect()
    };
    for (left, right) in [(0, 1), (1, 2)] {
        let a = column(&images[left], W - 1);
        let b = column(&images[right], 0);
        let mean = a
            .iter()
            .zip(&b)
            .map(|(x, y)| x.abs_diff(*y) as f64)
            .sum::<f64>()
            / a.len() as f64;
        // Adjacent pixel columns one pixel apart in angle: nearly the same colours.
        assert!(
            mean < 12.0,
            "seam {left}|{right}: mean difference {mean:.1}"
        );
        // And not trivially equal because the image is blank.
        assert!(a.iter().any(|&v| v != a[0]));
    }
}
