//! The statistics overlay on the GPU (issue 7 item 7): the CPU-rasterised panel is copied into
//! the top-left corner of the colour target — inside the panel the read-back frame equals the
//! panel byte for byte, outside it equals the same frame rendered without the overlay — with the
//! validation layer on (image layouts and usage flags checked).

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::TerrainRenderer;
use aerie::tools::overlay::{OverlayInfo, OverlayState};
use aerie_tests::{assert_validation_clean, prepare, synthetic, test_desc};
use glam::DVec3;

const W: u32 = 320;
const H: u32 = 180;

#[test]
fn overlay_panel_is_copied_exactly_and_nothing_else_changes() {
    let desc = test_desc(W, H);
    let hf = synthetic(257, 257, 15.0, 100.0, &[(100, 100, 140, 140, 180.0)]);
    let (ds, b) = prepare(&desc, &hf);
    let cam = Camera::new(
        DVec3::new(1920.0, 1600.0, 450.0),
        Attitude::from_degrees(10.0, -20.0, 0.0),
        Frustum::symmetric(70f64.to_radians(), W, H),
    );
    let mut r = TerrainRenderer::new(&desc).unwrap();
    r.load_terrain(ds, b, cam.position).unwrap();
    // Warm up until every refined tile is resident, so the frames below draw the same thing.
    let mut stats = r.render(&cam).unwrap();
    for _ in 0..3 {
        stats = r.render(&cam).unwrap();
    }
    assert_eq!(stats.tiles_late, 0);
    let plain = r.colour_rgba();

    let mut state = OverlayState::new(true);
    state.record(12.5, OverlayInfo::from_stats(&stats, 1.0));
    let panel = state.panel((W, H), Some(3.0)).unwrap();
    assert!(panel.width < W && panel.height < H);
    r.set_overlay(Some(panel.clone()));
    let s2 = r.render(&cam).unwrap();
    assert_eq!(s2.selection_digest, stats.selection_digest);
    let with = r.colour_rgba();
    // Off again: the overlay leaves nothing behind.
    r.set_overlay(None);
    r.render(&cam).unwrap();
    let after = r.colour_rgba();

    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);

    let mut inside = 0;
    for y in 0..H {
        for x in 0..W {
            let o = ((y * W + x) * 4) as usize;
            let got = &with[o..o + 4];
            if x < panel.width && y < panel.height {
                assert_eq!(got, panel.pixel(x, y), "panel pixel ({x}, {y})");
                inside += 1;
            } else {
                assert_eq!(got, &plain[o..o + 4], "outside pixel ({x}, {y})");
            }
        }
    }
    assert_eq!(inside, panel.width * panel.height);
    // The panel really covers what the terrain drew there (the test would pass vacuously if
    // the frame were panel-coloured already).
    assert_ne!(&plain[..4], panel.pixel(0, 0));
    assert_eq!(after, plain);
}
