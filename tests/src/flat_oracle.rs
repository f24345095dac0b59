//! Brute-force oracles of a selection on the flat plane, independent of the bake and of the
//! selection's bound (DESIGN.md "What within τ means when tested"): the largest on-screen
//! distance between a drawn node's true samples and the surface drawn over it, and whether the
//! drawn nodes cover the visible ground exactly once; and the scenes they are run on.

use aerie::camera::Camera;
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::clipmap::ClipmapDesc;
use aerie::terrain::dataset::Dataset;
use aerie::terrain::load_dem;
use aerie::terrain::select::{DrawItem, EARTH_RADIUS_M};
use aerie::terrain::Heightfield;
use glam::{DVec2, DVec3};

/// A dataset baked for `m`-vertex tiles, with the renderer's default clipmap over it.
pub struct Scene {
    pub name: &'static str,
    pub ds: Dataset,
    pub bake: ErrorBake,
    pub clip: ClipmapDesc,
}

/// [`Scene`] of `hf` (2^K + 1 samples a side: the oracles assume no padding).
pub fn scene(name: &'static str, hf: Heightfield, m: u32) -> Scene {
    let ds = Dataset::from_heightfield(hf, name.into());
    assert_eq!(
        (ds.valid_width, ds.valid_height),
        (ds.hf.width, ds.hf.height),
        "oracle scenes are 2^K+1: no padding"
    );
    let bake = bake(
        &ds,
        BakeParams {
            tile_size: m,
            levels: 0,
        },
        &|_, _| {},
    );
    let clip = ClipmapDesc {
        tile_quads: m - 1,
        patch_tiles: 8,
        margin_tiles: 2,
        width: ds.hf.width as u32,
        height: ds.hf.height as u32,
    };
    Scene {
        name,
        ds,
        bake,
        clip,
    }
}

/// A 1025² crop of the Inn valley tile (Karwendel, Nordkette, Innsbruck).
pub fn alpine() -> Heightfield {
    let full = load_dem(&crate::demo_dem()).expect("demo DEM");
    let (n, c0, r0) = (1025usize, 88usize, 88usize);
    let mut heights = Vec::with_capacity(n * n);
    for r in 0..n {
        heights.extend_from_slice(&full.heights[(r0 + r) * full.width + c0..][..n]);
    }
    Heightfield {
        width: n,
        height: n,
        heights,
        ..full
    }
}

/// Curvature drop of the point (x, y) seen from `eye`: d²/2R for its horizontal distance d.
pub fn curvature_drop(eye: DVec3, x: f64, y: f64) -> f64 {
    (DVec2::new(x, y) - eye.truncate()).length_squared() / (2.0 * EARTH_RADIUS_M)
}

/// The drawn surface at sample (c, row) of a node starting at sample `origin` and `side`
/// samples wide, drawn every `step` samples: the GPU's interpolation (SW–NE diagonal) of its
/// cell's vertices, `vertex(c, row)` a height (the plane) or a position (the ellipsoid).
pub fn drawn_at<T>(
    c: usize,
    row: usize,
    origin: (usize, usize),
    side: usize,
    step: usize,
    vertex: impl Fn(usize, usize) -> T,
) -> T
where
    T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
{
    let (c0, r0) = origin;
    // The drawn cell and the position inside it.
    let (ci, ri) = (
        ((c - c0) / step).min(side / step - 1),
        ((row - r0) / step).min(side / step - 1),
    );
    let (vc, vr) = (c0 + ci * step, r0 + ri * step);
    let u = (c - vc) as f64 / step as f64;
    let v = (row - vr) as f64 / step as f64;
    let sw = vertex(vc, vr);
    let se = vertex(vc + step, vr);
    let nw = vertex(vc, vr + step);
    let ne = vertex(vc + step, vr + step);
    if u >= v {
        sw * (1.0 - u) + se * (u - v) + ne * v
    } else {
        sw * (1.0 - v) + nw * (v - u) + ne * u
    }
}

/// The worst projected distance (px, on a `size` viewport) between the true samples of
/// level-`level` tile (tx, ty) of `m`-vertex tiles and the surface drawn over it: the
/// level-`drawn` grid (the tile's own level, its parent's for a quadrant drawn at the
/// parent's resolution, its grandparent's for a sixteenth), triangulated over the SW–NE
/// diagonal, vertices dropped by curvature and interpolated linearly as on the GPU.
#[allow(clippy::too_many_arguments)]
pub fn tile_error_px(
    hf: &Heightfield,
    cam: &Camera,
    size: (u32, u32),
    m: u32,
    level: u32,
    tx: u32,
    ty: u32,
    drawn: u32,
) -> f64 {
    let (w, h) = size;
    let q = (m - 1) as usize;
    let side = q << level;
    let step = 1usize << drawn;
    let (c0, r0) = (tx as usize * side, ty as usize * side);
    let eye = cam.position;
    let vertex = |c: usize, row: usize| {
        let (x, y) = (c as f64 * hf.spacing_x, row as f64 * hf.spacing_y);
        hf.at(c, row) as f64 - curvature_drop(eye, x, y)
    };
    let on_screen = |p: DVec2| p.x >= 0.0 && p.x <= w as f64 && p.y >= 0.0 && p.y <= h as f64;
    let mut worst: f64 = 0.0;
    for row in r0..=r0 + side {
        for c in c0..=c0 + side {
            let (x, y) = (c as f64 * hf.spacing_x, row as f64 * hf.spacing_y);
            let truth = hf.at(c, row) as f64 - curvature_drop(eye, x, y);
            let drawn = drawn_at(c, row, (c0, r0), side, step, vertex);
            let a = cam.project_px(DVec3::new(x, y, truth), w, h);
            let b = cam.project_px(DVec3::new(x, y, drawn), w, h);
            if let (Some((pa, _)), Some((pb, _))) = (a, b) {
                if on_screen(pa) || on_screen(pb) {
                    worst = worst.max((pa - pb).length());
                }
            }
        }
    }
    worst
}

/// Rasterises the drawn nodes' footprints onto level-0 cells and panics (naming `what`) when
/// a cell is drawn twice or a cell whose ground is visible on the `size` viewport is not drawn
/// (culling and level boundaries must leave no hole). Returns the visible cells.
pub fn assert_covered_once(
    hf: &Heightfield,
    cam: &Camera,
    size: (u32, u32),
    m: u32,
    items: &[DrawItem],
    what: &str,
) -> usize {
    let (w, h) = size;
    let q = (m - 1) as usize;
    let mut count = vec![0u8; (hf.width - 1) * (hf.height - 1)];
    for item in items {
        let side = q << item.node_level;
        let (c0, r0) = (item.node_tx as usize * side, item.node_ty as usize * side);
        for row in r0..(r0 + side).min(hf.height - 1) {
            for c in c0..(c0 + side).min(hf.width - 1) {
                count[row * (hf.width - 1) + c] += 1;
            }
        }
    }
    assert!(count.iter().all(|&n| n <= 1), "{what}: overlapping nodes");
    let mut visible = 0;
    for row in 0..hf.height - 1 {
        for c in 0..hf.width - 1 {
            let (x, y) = (
                (c as f64 + 0.5) * hf.spacing_x,
                (row as f64 + 0.5) * hf.spacing_y,
            );
            let z = hf.height_at_m(x, y) - curvature_drop(cam.position, x, y);
            let Some((p, _)) = cam.project_px(DVec3::new(x, y, z), w, h) else {
                continue;
            };
            if p.x >= 0.0 && p.x <= w as f64 && p.y >= 0.0 && p.y <= h as f64 {
                visible += 1;
                assert_eq!(
                    count[row * (hf.width - 1) + c],
                    1,
                    "{what}: visible cell ({c}, {row}) is not drawn"
                );
            }
        }
    }
    visible
}
