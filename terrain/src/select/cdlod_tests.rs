//! `cdlod.rs`'s tests: the ranges, the decisions, the ground tiled once, the morphs, the
//! quadtree above the coarsest clipmap level and the ellipsoid's boxes.

use super::*;

#[test]
fn ranges_double_per_level() {
    assert_eq!(cdlod_range_m(3.0, 160.0, 0), 480.0);
    assert_eq!(cdlod_range_m(3.0, 160.0, 1), 960.0);
    assert_eq!(cdlod_range_m(3.0, 160.0, 4), 7680.0);
}

#[test]
fn box_distance_is_zero_inside_and_euclidean_outside() {
    let b = Aabb {
        min: DVec3::new(0.0, 0.0, 0.0),
        max: DVec3::new(10.0, 10.0, 5.0),
    };
    assert_eq!(box_distance(DVec3::new(5.0, 5.0, 1.0), &b), 0.0);
    assert_eq!(box_distance(DVec3::new(13.0, 14.0, 5.0), &b), 5.0);
    assert_eq!(box_distance(DVec3::new(5.0, 5.0, 17.0), &b), 12.0);
}

#[test]
fn decisions_follow_lod_select() {
    use CdlodDecision::*;
    // Outside its own range: the parent covers it, even when invisible.
    assert_eq!(
        cdlod_decide(101.0, 100.0, Some(50.0), false, true),
        LeftToParent
    );
    assert_eq!(
        cdlod_decide(101.0, 100.0, Some(50.0), false, false),
        LeftToParent
    );
    // A root has no range limit.
    assert_eq!(cdlod_decide(1e9, 100.0, Some(50.0), true, true), Draw);
    // In range but unseen: done.
    assert_eq!(cdlod_decide(80.0, 100.0, Some(50.0), false, false), Culled);
    // In range, beyond the finer range: whole; within it: split; finest: whole.
    assert_eq!(cdlod_decide(80.0, 100.0, Some(50.0), false, true), Draw);
    assert_eq!(cdlod_decide(50.0, 100.0, Some(50.0), false, true), Split);
    assert_eq!(cdlod_decide(10.0, 100.0, None, false, true), Draw);
}

/// A 257² bumpy dataset, its bake and clipmap (level-0 tiles of 16 quads × 10 m).
fn scene() -> (crate::bake::ErrorBake, crate::clipmap::ClipmapDesc) {
    use crate::bake::{bake, BakeParams};
    use crate::dataset::Dataset;
    use crate::Heightfield;
    let n = 257;
    let hf = Heightfield {
        width: n,
        height: n,
        spacing_x: 10.0,
        spacing_y: 10.0,
        heights: (0..n * n)
            .map(|k| ((k % n) as f32 * 0.3).sin() * 20.0 + ((k / n) as f32 * 0.17).cos() * 9.0)
            .collect(),
        geo: None,
        voids_filled: 0,
        spacing_note: String::new(),
    };
    let ds = Dataset::from_heightfield(hf, "t".into());
    let b = bake(
        &ds,
        BakeParams {
            tile_size: 17,
            levels: 0,
        },
        &|_, _| {},
    );
    let desc = crate::clipmap::ClipmapDesc {
        tile_quads: 16,
        patch_tiles: 8,
        margin_tiles: 2,
        width: n as u32,
        height: n as u32,
    };
    (b, desc)
}

fn select(range: f64, eye: DVec3, pitch: f64) -> (Selection, crate::bake::ErrorBake) {
    use crate::camera::{Attitude, Frustum};
    use crate::clipmap::place_levels;
    let (b, desc) = scene();
    let params = SelectParams {
        mode: crate::select::LodMode::Cdlod,
        cdlod_range: range,
        max_refinement: 6,
        ..SelectParams::default()
    };
    let cam = Camera::new(
        eye,
        Attitude::from_degrees(30.0, pitch, 0.0),
        Frustum::symmetric(170f64.to_radians(), 64, 64),
    );
    let placements = place_levels(&desc, [eye.x / 10.0, eye.y / 10.0]);
    let mut sel = Selection::default();
    crate::select::select_tiles(&b, &desc, &placements, &cam, (64, 64), &params, &mut sel);
    (sel, b)
}

/// Looking straight down from high up every tile is seen: the nodes tile the ground
/// exactly once, each drawn node is beyond the next finer range (it was not split), and a
/// longer range draws more nodes.
#[test]
fn nodes_tile_the_ground_once_and_follow_the_ranges() {
    let eye = DVec3::new(700.0, 1900.0, 250.0);
    let mut counts = Vec::new();
    for range in [2.0, 4.0, 8.0] {
        let (sel, b) = select(range, eye, -89.9);
        let mut cover = vec![0u32; 16 * 16];
        for it in &sel.items {
            let l = it.node_level;
            assert!(it.node_level + it.refinement >= it.level, "{it:?}");
            for y in (it.node_ty << l)..((it.node_ty + 1) << l) {
                for x in (it.node_tx << l)..((it.node_tx + 1) << l) {
                    if x < 16 && y < 16 {
                        cover[(y * 16 + x) as usize] += 1;
                    }
                }
            }
            if l > 0 {
                let t = Ctx::seen_for_test(&b, l, it.node_tx, it.node_ty, eye);
                assert!(
                    t > cdlod_range_m(range, 160.0, l - 1),
                    "range {range}: {it:?} at {t} m should have split"
                );
            }
        }
        assert!(cover.iter().all(|&c| c == 1), "range {range}: {cover:?}");
        counts.push(sel.items.len());
    }
    assert!(counts[0] < counts[1] && counts[1] < counts[2], "{counts:?}");
}

/// The quadtree starts two levels above the coarsest clipmap level (`coarser_roots`): a
/// node there is drawn as the clipmap's tiles under it — sixteenths of a root, quadrants
/// of its children —, each beyond the range below the level it is drawn at (the node was
/// not split), in fewer triangles than the quadtree that starts at the clipmap's level,
/// the ground still tiled once (`nodes_tile_the_ground_once_and_follow_the_ranges`).
#[test]
fn the_quadtree_reaches_above_the_coarsest_clipmap_level() {
    use crate::camera::{Attitude, Frustum};
    use crate::clipmap::place_levels;
    let eye = DVec3::new(700.0, 1900.0, 250.0);
    let (b, desc) = scene();
    let placements = place_levels(&desc, [eye.x / 10.0, eye.y / 10.0]);
    let tiles = placements.last().unwrap().level;
    let cam = Camera::new(
        eye,
        Attitude::from_degrees(30.0, -89.9, 0.0),
        Frustum::symmetric(170f64.to_radians(), 64, 64),
    );
    let triangles = |taller: bool| {
        let params = SelectParams {
            mode: crate::select::LodMode::Cdlod,
            cdlod_range: 2.0,
            max_refinement: 6,
            coarser_roots: taller,
            ..SelectParams::default()
        };
        let mut sel = Selection::default();
        crate::select::select_tiles(&b, &desc, &placements, &cam, (64, 64), &params, &mut sel);
        let mut up = [0; 3];
        for it in &sel.items {
            let k = it.morph.levels_up();
            up[k as usize] += 1;
            let drawn = it.node_level + k;
            if drawn > tiles {
                // The node drawn, or the quadrant of it its child left to it: beyond the
                // range of the level below the one drawn.
                assert_eq!(it.node_level, tiles, "{it:?}");
                let (x, y) = (it.node_tx >> (k - 1), it.node_ty >> (k - 1));
                let d = Ctx::seen_for_test(&b, drawn - 1, x, y, eye);
                assert!(d > cdlod_range_m(2.0, 160.0, drawn - 1), "{it:?} at {d} m");
            }
        }
        let q = 16u32;
        (
            up[0] * 2 * q * q + up[1] * q * q / 2 + up[2] * q * q / 8,
            up,
        )
    };
    let (taller, up) = triangles(true);
    let (clipmap_top, up_before) = triangles(false);
    assert!(up[2] > 0, "no sixteenth drawn for a root: {up:?}");
    assert_eq!(up_before[2], 0);
    assert!(taller < clipmap_top, "{taller} vs {clipmap_top}");
}

/// Every drawn node morphs over its own level's zone — the coarsest level not at all — and
/// a quadrant drawn for its parent is fully morphed onto the parent's grid, then over the
/// parent's zone; the selection itself (which nodes) is the same as without morphing.
#[test]
fn nodes_carry_their_levels_morph_zone() {
    let eye = DVec3::new(700.0, 1900.0, 250.0);
    let mut quadrants = 0;
    for range in [2.0, 4.0, 8.0] {
        let (sel, _) = select(range, eye, -60.0);
        // The roots, whose range is unbounded: two levels above the coarsest clipmap
        // level's tiles (`levels_above`).
        let (b, desc) = scene();
        let places = crate::clipmap::place_levels(&desc, [eye.x / 10.0, eye.y / 10.0]);
        let tiles = places.last().unwrap().level;
        let top = tiles + levels_above(&b, tiles, &SelectParams::default());
        assert_eq!(top, tiles + 2);
        let zones = morph_zones(|l| cdlod_range_m(range, 160.0, l), top);
        let zone = |l: u32| {
            let z = zones[l as usize];
            [z[0] as f32, z[1] as f32]
        };
        assert!(!sel.items.is_empty());
        for it in &sel.items {
            let m = it.morph;
            if m.quadrant {
                quadrants += 1;
                // Drawn at its parent's resolution, or (a sixteenth, the coarsest
                // clipmap level's tile under a root) its grandparent's.
                let parent = it.node_level + m.levels_up();
                assert!(!m.sixteenth || (it.node_level == tiles && parent == top));
                let want = if parent == top {
                    [0.0, 0.0]
                } else {
                    zone(parent)
                };
                assert_eq!(m.parent_zone, want, "{it:?}");
                assert_eq!(m.to_gpu()[..2], [-1.0, 0.0]);
            } else if it.node_level == top {
                assert_eq!(m, Morph::NONE, "{it:?}");
            } else {
                assert_eq!(m.zone, zone(it.node_level), "{it:?}");
                assert!(m.zone[0] < m.zone[1]);
            }
        }
    }
    assert!(quadrants > 0, "no quadrant drawn for its parent");
}

/// On the ellipsoid a node's distance is to the box the renderer draws it in
/// (`GeoGrid::node_geometry`), not to its flat grid rectangle: far from the grid's origin
/// the two part (a 1/120° grid at 47° N, a level-3 node beside the origin's).
#[test]
fn on_the_ellipsoid_a_nodes_box_is_where_it_is_drawn() {
    let (b, _) = scene();
    let earth = crate::geodesy::GeoGrid::test_geographic(47.0, 11.0, 1.0 / 120.0, 47.0);
    let (level, tx, ty) = (3, 1, 1);
    let side = (16u64 << level) as f64 * 10.0;
    let lo = DVec2::new(tx as f64 * side, ty as f64 * side);
    let valid = DVec2::new(256.0 * 10.0, 256.0 * 10.0);
    let (lo, hi) = (lo.min(valid), (lo + DVec2::splat(side)).min(valid));
    let (min_h, max_h) = b.bounds(level, tx, ty);
    let drawn = earth.node_geometry(lo, hi, min_h, max_h).aabb;
    // An eye 500 m beside the drawn box's east face, level with it.
    let eye = DVec3::new(
        drawn.max.x + 500.0,
        0.5 * (drawn.min.y + drawn.max.y),
        drawn.max.z,
    );
    let on_earth = Ctx::seen_on(&b, Some(earth), level, tx, ty, eye);
    assert!(
        (on_earth - box_distance(eye, &drawn)).abs() < 1e-9,
        "{on_earth}"
    );
    let flat = Ctx::seen_for_test(&b, level, tx, ty, eye);
    // The flat rectangle's box is elsewhere (0.39 m here, 2.6 km from the origin; tens of
    // metres across a mosaic).
    assert!(
        (flat - on_earth).abs() > 0.1,
        "flat {flat} vs drawn {on_earth}"
    );
}
