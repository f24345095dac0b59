//! CDLOD's geomorph on lavapipe with validation on, against a CPU oracle: every pixel of the
//! frame is ray-cast against the morphed meshes of the nodes the selection drew — each vertex
//! slid by the factor of its own distance to the eye (`aerie_terrain::select::cdlod_morph`, the
//! shader's arithmetic on the CPU) — and the depth the GPU drew must be that surface's. The same
//! oracle without the morph must miss a visible share of the pixels (so the test sees the morph),
//! and the frame's triangle count must count each quadrant drawn for its parent as the parent's
//! quarter mesh. CDLOD draws no skirts (the morph closes its seams, as in Strugar's paper): no
//! pixel whose ray meets the grid may be left without terrain.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::TerrainRenderer;
use aerie::terrain::heightfield::Heightfield;
use aerie::terrain::select::cdlod_morph::{morph_k, morph_vertex};
use aerie::terrain::select::{DrawItem, LodMode, SelectParams};
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;
const N: usize = 513;
const SPACING: f64 = 10.0;

fn hills() -> Heightfield {
    aerie_tests::hills::hills(N, SPACING, SPACING, 12.0, None)
}

/// A node's triangles, world metres.
type Mesh = Vec<[DVec3; 3]>;

/// Möller–Trumbore: the ray's distance to triangle (a, b, c), if it hits.
fn ray_triangle(o: DVec3, d: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    let eps = 1e-9;
    if u < -eps || v < -eps || u + v > 1.0 + eps {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// The node's mesh as the shader draws it (morphed unless `morph` is false), world metres.
fn node_triangles(
    hf: &Heightfield,
    it: &DrawItem,
    q: u32,
    eye: DVec3,
    morph: bool,
) -> Vec<[DVec3; 3]> {
    let step = 1i64 << it.node_level;
    let node = q as i64 * step;
    let origin = [it.node_tx as i64 * node, it.node_ty as i64 * node];
    let sample = |ij: [i32; 2]| {
        let c = (origin[0] + ij[0] as i64 * step) as usize;
        let r = (origin[1] + ij[1] as i64 * step) as usize;
        hf.heights[r * hf.width + c]
    };
    let side = q as i32 + 1;
    let m = it.morph;
    let verts: Vec<DVec3> = (0..side * side)
        .map(|k| {
            let ij = [k % side, k / side];
            let world = |f: [f32; 2], h: f32| {
                DVec3::new(
                    (origin[0] as f64 + f[0] as f64 * step as f64) * SPACING,
                    (origin[1] as f64 + f[1] as f64 * step as f64) * SPACING,
                    h as f64,
                )
            };
            let p0 = world([ij[0] as f32, ij[1] as f32], sample(ij));
            if !morph {
                return p0;
            }
            let dist = (p0 - eye).length() as f32;
            let (k1, k2) = if m.quadrant {
                (1.0, morph_k(m.parent_zone, dist))
            } else {
                (morph_k(m.zone, dist), 0.0)
            };
            let (f, h) = morph_vertex(ij, k1, k2, sample);
            world(f, h)
        })
        .collect();
    // The mesh the renderer draws: a quadrant's is the quarter mesh over the even vertices (a
    // sixteenth's over every fourth), whose vertices each morph by their own distance — the
    // full mesh's odd vertices, folded onto them, would each morph by theirs. Grid triangles
    // only (CDLOD hangs no skirts).
    use aerie::terrain::mesh::{
        skirted_coarse_tile_indices, skirted_sixteenth_tile_indices, skirted_tile_indices,
    };
    let indices = match (it.morph.quadrant && morph, it.morph.sixteenth) {
        (false, _) => skirted_tile_indices(side as u32),
        (true, false) => skirted_coarse_tile_indices(side as u32),
        (true, true) => skirted_sixteenth_tile_indices(side as u32),
    };
    let grid = (side * side) as u32;
    indices
        .chunks(3)
        .filter(|t| t.iter().all(|&v| v < grid))
        .map(|t| {
            [
                verts[t[0] as usize],
                verts[t[1] as usize],
                verts[t[2] as usize],
            ]
        })
        .collect()
}

#[test]
fn the_morphed_surface_is_drawn_and_quadrants_count_as_quarter_meshes() {
    let hf = hills();
    let mut desc = test_desc(W, H);
    desc.select = SelectParams {
        mode: LodMode::Cdlod,
        cdlod_range: 3.0,
        curvature: false,
        ..SelectParams::default()
    };
    let (ds, bake) = prepare(&desc, &hf);
    let eye = DVec3::new(2560.0, 400.0, 900.0);
    let cam = Camera::new(
        eye,
        Attitude::from_degrees(0.0, -18.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), W, H),
    );
    let mut r = TerrainRenderer::new(&desc).expect("renderer");
    r.load_terrain(ds, bake, eye).expect("load");
    let stats = render_settled(&mut r, &cam, 3);
    let depth = r.depth();
    let items = r.selection().items.clone();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    assert_eq!(stats.tiles_late, 0, "{stats:?}");

    // The count: whole tiles' grids (2q² triangles, no skirts), less what each quadrant's
    // quarter mesh saves.
    let q = desc.tile_size - 1;
    let quadrants = items.iter().filter(|i| i.morph.quadrant).count() as u64;
    let morphing = items.iter().filter(|i| i.morph.zone[1] > 0.0).count();
    let grid = |q: u32| 2 * q as u64 * q as u64;
    assert_eq!(
        stats.triangles,
        items.len() as u64 * grid(q) - quadrants * (grid(q) - grid(q / 2))
    );
    eprintln!(
        "{} nodes, {morphing} with a morph zone, {quadrants} quadrants for their parents; {} triangles",
        items.len(),
        stats.triangles
    );
    assert!(quadrants > 0 && morphing > 0);

    // Each node's meshes, morphed and not, for the nodes inside the grid's last sample.
    let inside = |it: &DrawItem| {
        let node = (q as usize) << it.node_level;
        (it.node_tx as usize + 1) * node < N && (it.node_ty as usize + 1) * node < N
    };
    let meshes: Vec<(&DrawItem, Mesh, Mesh)> = items
        .iter()
        .filter(|it| inside(it))
        .map(|it| {
            (
                it,
                node_triangles(&hf, it, q, eye, true),
                node_triangles(&hf, it, q, eye, false),
            )
        })
        .collect();
    let (mut covered, mut matched, mut unmorphed_off, mut in_quadrant) = (0, 0, 0, 0);
    // Holes: pixels without terrain whose ray comes down through the hills' lowest height
    // inside the grid (the hills lie between 0 and 500 m; the ray must meet them).
    let mut holes = Vec::new();
    let extent = (N - 1) as f64 * SPACING;
    for py in 0..H {
        for px in 0..W {
            let z = depth[(py * W + px) as usize];
            if z == 0.0 {
                let dir = cam.pixel_ray(px as f64 + 0.5, py as f64 + 0.5, W, H);
                let t = (0.0 - eye.z) / dir.z;
                let p = eye + dir * t;
                let inner = 30.0 * SPACING;
                if dir.z < 0.0 && [p.x, p.y].iter().all(|&c| c > inner && c < extent - inner) {
                    holes.push((px, py));
                }
            }
            let Some(p) = cam.unproject_px(px, py, W, H, z) else {
                continue;
            };
            let d = p - eye;
            let t_gpu = d.length();
            let dir = d / t_gpu;
            let node_of = meshes.iter().find(|(it, _, _)| {
                let side = ((q as u64) << it.node_level) as f64 * SPACING;
                let (x0, y0) = (it.node_tx as f64 * side, it.node_ty as f64 * side);
                (x0..=x0 + side).contains(&p.x) && (y0..=y0 + side).contains(&p.y)
            });
            let Some((it, morphed, flat)) = node_of else {
                continue;
            };
            covered += 1;
            let nearest = |tris: &[[DVec3; 3]]| {
                tris.iter()
                    .filter_map(|t| ray_triangle(eye, dir, t[0], t[1], t[2]))
                    .fold(f64::INFINITY, f64::min)
            };
            let tol = 1e-3 * t_gpu + 0.02;
            if (nearest(morphed) - t_gpu).abs() <= tol {
                matched += 1;
                in_quadrant += it.morph.quadrant as u32;
            }
            if (nearest(flat) - t_gpu).abs() > tol {
                unmorphed_off += 1;
            }
        }
    }
    eprintln!(
        "{covered} pixels over nodes inside the grid: {matched} on the morphed surface ({in_quadrant} in quadrants), {unmorphed_off} off the unmorphed one"
    );
    assert!(covered > (W * H / 3) as usize, "{covered}");
    assert!(
        holes.is_empty(),
        "{} pixels without terrain: {holes:?}",
        holes.len()
    );
    // No skirts: every pixel lies on the morphed surface but for a few at node edges, where
    // the rasteriser's pixel and the oracle's triangle meet (5 of 23,923 here).
    assert!(
        matched as f64 >= 0.999 * covered as f64,
        "{matched} of {covered}"
    );
    assert!(in_quadrant > 0);
    // Without the morph the oracle misses a visible share: the frame shows it.
    assert!(
        unmorphed_off as f64 >= 0.05 * covered as f64,
        "{unmorphed_off} of {covered}"
    );
}
