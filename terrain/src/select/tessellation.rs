//! The per-frame half of the hardware-tessellation baseline (seed document 001, §2.2.3–2.2.5):
//! which base-mesh patches are drawn and the tessellation factors of each, and how many
//! triangles the tessellator will make of them.
//!
//! The paper's factor of an edge is `T = Td · Te · Tg`: `Td` the mean of its two vertices'
//! distance factors `Fd = 1 − clamp((d − dmin)/(dmax − dmin), 0, 0.99)` (d the vertex's distance
//! to the eye), `Te` the edge's density (`tess_density.rs`), `Tg` the user's global factor (the
//! knob, `--tess-density`). The inner factor is `Td` of the patch's first edge times the largest
//! of its edges' densities. Patches outside the frustum get no geometry (§2.2.5). Spacing
//! `fractional_odd`, triangles (the paper's hull shader).
//!
//! Departures, named:
//! - the factors are computed here, on the CPU, and handed to the control shader (the paper
//!   computes them in the hull shader): the GPU draws exactly what this module counts, and
//!   every edge's factor is a function of that edge alone, so neighbours agree bit for bit;
//! - culling is per cell (both triangles) against a box that holds the curvature drop, on the
//!   CPU (the paper zeroes the factors in the hull shader: the same triangles);
//! - a factor below 1 is raised to 1 (the paper's product is 0 on a flat edge, which would
//!   discard the patch): a flat patch is drawn as its base triangle;
//! - factors are rounded to 1/256 so that the tessellator's fixed-point rounding and this
//!   module's agree on the number of segments;
//! - on the ellipsoid (a geographic or UTM grid, [`TessPlacement`]) each cell's box and each
//!   lattice vertex's distance are taken from their true world positions (the paper's terrain
//!   is flat); the GPU places every generated vertex there too (`shaders/geo_node.glsl`);
//! - `dmin` = 0 and `dmax` the dataset's diagonal by default (the paper's listing hard-codes
//!   1 m and 6 km for its demo terrain); no coarser patches far away: the paper's base mesh is
//!   one static grid.

use glam::DVec2;

use crate::camera::Camera;
use crate::geodesy::GeoGrid;
use crate::tiles::{outside_frustum, Aabb};

use super::bound::tile_aabb;
use super::tess_density::TessDensity;

/// How the tessellator spaces an edge's segments (VkSpirv `SpacingEqual`, `SpacingFractionalOdd`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spacing {
    Equal,
    FractionalOdd,
}

/// The integer segment count a level becomes (Vulkan spec, "Tessellator Spacing"): `equal` is
/// clamped to [1, max] and rounded up; `fractional_odd` clamped to [1, max − 1] (max is even)
/// and rounded up to the next odd integer. `max` is `maxTessellationGenerationLevel`.
pub fn rounded_level(level: f32, spacing: Spacing, max: u32) -> u32 {
    match spacing {
        Spacing::Equal => level.clamp(1.0, max as f32).ceil() as u32,
        Spacing::FractionalOdd => {
            let top = if max.is_multiple_of(2) { max - 1 } else { max };
            let l = level.clamp(1.0, top as f32);
            let n = l.ceil() as u32;
            if n.is_multiple_of(2) {
                n + 1
            } else {
                n
            }
        }
    }
}

/// Triangles the tessellator emits for one triangle patch (Vulkan spec, "Triangle
/// Tessellation"): a single triangle when every level rounds to 1; otherwise concentric
/// triangles from the inner level n (an inner 1 with an outer above 1 counts as 1 + ε: n = 2 for
/// `equal`, 3 for `fractional_odd`), each inner edge of m segments; the ring between an outer
/// edge of a segments and an inner edge of b holds a + b triangles; the innermost is a point
/// (n even) or one triangle (n odd).
pub fn triangles_emitted(outer: [f32; 3], inner: f32, spacing: Spacing, max: u32) -> u64 {
    let o = outer.map(|l| rounded_level(l, spacing, max) as u64);
    let mut n = rounded_level(inner, spacing, max) as u64;
    if n == 1 {
        if o == [1, 1, 1] {
            return 1;
        }
        n = match spacing {
            Spacing::Equal => 2,
            Spacing::FractionalOdd => 3,
        };
    }
    let mut total = o.iter().sum::<u64>() + 3 * (n - 2);
    let mut m = n - 2;
    while m >= 2 {
        total += 3 * m + 3 * (m - 2);
        m -= 2;
    }
    total + (m == 1) as u64
}

/// The knob and limits of one frame's factors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TessParams {
    /// Tg, the global factor (an edge of density 1 at the eye gets Tg segments).
    pub global: f64,
    /// dmin, dmax of the distance factor, metres.
    pub d_min_m: f64,
    pub d_max_m: f64,
    /// The device's `maxTessellationGenerationLevel`.
    pub max_level: u32,
    /// Include the Earth-curvature drop in the cull boxes (as the drawing does).
    pub curvature: bool,
}

/// One triangle patch to draw: its cell, which half, its factors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TessPatch {
    /// The cell (cx, cy) of the base mesh.
    pub cell: [u32; 2],
    /// false: the south-east half (SW, SE, NE); true: the north-west half (SW, NE, NW).
    pub north_west: bool,
    /// `gl_TessLevelOuter[0..3]`: the edges opposite the first, second and third corner.
    pub outer: [f32; 3],
    /// `gl_TessLevelInner[0]`.
    pub inner: f32,
}

/// What one frame's patch selection did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TessStats {
    pub cells: u32,
    pub culled: u32,
    pub patches: u32,
    /// Triangles the tessellator emits for the drawn patches.
    pub triangles: u64,
}

/// The distance factor of a vertex at distance `d` (paper eq. 7, clamped as its listing does).
pub fn distance_factor(d: f64, d_min: f64, d_max: f64) -> f64 {
    1.0 - ((d - d_min) / (d_max - d_min).max(1e-9)).clamp(0.0, 0.99)
}

/// The factor of one edge from its density and its two vertices' distance factors: symmetric
/// in the two vertices, so both patches sharing the edge compute the same value.
pub fn edge_factor(density: f32, fd_a: f64, fd_b: f64, global: f64, max_level: u32) -> f32 {
    let td = 0.5 * (fd_a + fd_b);
    quantise(td * density as f64 * global, max_level)
}

/// Clamped to [1, the largest odd level] and rounded to 1/256.
fn quantise(level: f64, max_level: u32) -> f32 {
    let top = if max_level.is_multiple_of(2) {
        max_level - 1
    } else {
        max_level
    };
    ((level.clamp(1.0, top as f64) * 256.0).round() / 256.0) as f32
}

/// The base mesh placed on the WGS84 ellipsoid: each cell's world box and each lattice
/// vertex's world position. World axes (ENU at the grid's south-west sample) do not move with
/// the eye, so both are computed once, at load.
#[derive(Debug, Clone, PartialEq)]
pub struct TessPlacement {
    /// Per cell, `cy * cells[0] + cx`: a box holding the cell's surface between its lowest and
    /// highest sample (`GeoGrid::node_geometry`, the ellipsoid's sag included).
    pub boxes: Vec<Aabb>,
    /// Per lattice vertex, `ly * (cells[0] + 1) + lx`: its world position at its height.
    pub corners: Vec<glam::DVec3>,
}

impl TessPlacement {
    /// `density`'s cells over `grid` (grid metres = samples × the grid's spacings).
    pub fn new(density: &TessDensity, grid: &GeoGrid) -> Self {
        let [nx, ny] = density.cells;
        let sp = DVec2::new(grid.spacing_x, grid.spacing_y);
        let at = |lx: u32, ly: u32| {
            let s = density.corner_sample(lx, ly);
            DVec2::new(s[0] as f64, s[1] as f64) * sp
        };
        let mut boxes = Vec::with_capacity((nx * ny) as usize);
        for cy in 0..ny {
            for cx in 0..nx {
                let [lo, hi] = density.cell_range[(cy * nx + cx) as usize];
                let (a, b) = (at(cx, cy), at(cx + 1, cy + 1));
                boxes.push(grid.node_geometry(a, b, lo, hi).aabb);
            }
        }
        let corners = (0..=ny)
            .flat_map(|ly| (0..=nx).map(move |lx| (lx, ly)))
            .map(|(lx, ly)| grid.world_of_grid(at(lx, ly), density.corner_height(lx, ly) as f64))
            .collect();
        Self { boxes, corners }
    }
}

/// The frame's patches over `density` (cells `spacing` metres per sample; on the ellipsoid
/// where `placed` says) seen by `camera`, appended to `out` (cleared first), and what it cost.
pub fn select_patches(
    density: &TessDensity,
    spacing: [f64; 2],
    placed: Option<&TessPlacement>,
    camera: &Camera,
    params: &TessParams,
    out: &mut Vec<TessPatch>,
) -> TessStats {
    out.clear();
    let eye = camera.position;
    let [nx, ny] = density.cells;
    let corner = |lx: u32, ly: u32| {
        let s = density.corner_sample(lx, ly);
        DVec2::new(s[0] as f64 * spacing[0], s[1] as f64 * spacing[1])
    };
    // A function of the lattice vertex alone: every cell computes the same value for it.
    let fd = |lx: u32, ly: u32| {
        let p = match placed {
            Some(pl) => pl.corners[(ly * (nx + 1) + lx) as usize],
            None => corner(lx, ly).extend(density.corner_height(lx, ly) as f64),
        };
        distance_factor((p - eye).length(), params.d_min_m, params.d_max_m)
    };
    let (g, max) = (params.global, params.max_level);
    let cell_diag = (density.patch as f64) * spacing[0].hypot(spacing[1]);
    let mut stats = TessStats {
        cells: nx * ny,
        ..TessStats::default()
    };
    for cy in 0..ny {
        for cx in 0..nx {
            let aabb = match placed {
                Some(pl) => pl.boxes[(cy * nx + cx) as usize],
                None => {
                    let range = density.cell_range[(cy * nx + cx) as usize];
                    let (lo, hi) = (corner(cx, cy), corner(cx + 1, cy + 1));
                    tile_aabb(lo, hi, range[0], range[1], eye, params.curvature, cell_diag)
                }
            };
            if outside_frustum(camera, &aabb) {
                stats.culled += 1;
                continue;
            }
            let (sw, se, ne, nw) = (
                fd(cx, cy),
                fd(cx + 1, cy),
                fd(cx + 1, cy + 1),
                fd(cx, cy + 1),
            );
            let south = density.horizontal_edge(cx, cy);
            let north = density.horizontal_edge(cx, cy + 1);
            let west = density.vertical_edge(cx, cy);
            let east = density.vertical_edge(cx + 1, cy);
            let diag = density.diagonal_edge(cx, cy);
            let e_diag = edge_factor(diag, sw, ne, g, max);
            // South-east half, corners (SW, SE, NE): edges opposite them are east, diagonal, south.
            let inner_se = quantise(0.5 * (se + ne) * east.max(diag).max(south) as f64 * g, max);
            out.push(TessPatch {
                cell: [cx, cy],
                north_west: false,
                outer: [
                    edge_factor(east, se, ne, g, max),
                    e_diag,
                    edge_factor(south, sw, se, g, max),
                ],
                inner: inner_se,
            });
            // North-west half, corners (SW, NE, NW): edges opposite them are north, west, diagonal.
            let inner_nw = quantise(0.5 * (ne + nw) * north.max(west).max(diag) as f64 * g, max);
            out.push(TessPatch {
                cell: [cx, cy],
                north_west: true,
                outer: [
                    edge_factor(north, ne, nw, g, max),
                    edge_factor(west, nw, sw, g, max),
                    e_diag,
                ],
                inner: inner_nw,
            });
        }
    }
    stats.patches = out.len() as u32;
    stats.triangles = out
        .iter()
        .map(|p| triangles_emitted(p.outer, p.inner, Spacing::FractionalOdd, max))
        .sum();
    stats
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Attitude, Frustum};
    use glam::DVec3;

    #[test]
    fn levels_round_as_the_spec_says() {
        let odd = |l| rounded_level(l, Spacing::FractionalOdd, 64);
        assert_eq!(
            [
                odd(0.2),
                odd(1.0),
                odd(1.01),
                odd(3.0),
                odd(3.5),
                odd(62.5),
                odd(99.0)
            ],
            [1, 1, 3, 3, 5, 63, 63]
        );
        let eq = |l| rounded_level(l, Spacing::Equal, 64);
        assert_eq!([eq(0.5), eq(2.0), eq(2.2), eq(80.0)], [1, 2, 3, 64]);
    }

    #[test]
    fn triangle_counts_follow_the_concentric_rule() {
        let fo = |o, i| triangles_emitted(o, i, Spacing::FractionalOdd, 64);
        // Every level 1: the patch itself.
        assert_eq!(fo([1.0; 3], 1.0), 1);
        // Inner 1 with an outer edge of 2 segments (fractional odd: 3): the inner level counts
        // as 3 — one inner triangle, the ring 3 + 1 + 1 outer segments + 3 inner = 8, + 1.
        assert_eq!(fo([3.0, 1.0, 1.0], 1.0), 3 + 1 + 1 + 3 + 1);
        // Uniform levels n: the rings sum to 3n²/2 (n even) or (3n² − 1)/2 (n odd), a closed
        // form from the ring areas, independent of the loop above.
        for n in 1..=63u64 {
            let l = n as f32;
            if !n.is_multiple_of(2) {
                assert_eq!(fo([l; 3], l), (3 * n * n - 1) / 2, "odd {n}");
            }
            let eq = triangles_emitted([l; 3], l, Spacing::Equal, 64);
            let closed = if n.is_multiple_of(2) {
                3 * n * n / 2
            } else {
                (3 * n * n - 1) / 2
            };
            assert_eq!(eq, closed, "equal {n}");
        }
        // Only an outer edge changing: each segment more on it, one triangle more.
        assert_eq!(fo([7.0, 5.0, 5.0], 5.0), fo([5.0; 3], 5.0) + 2);
    }

    fn camera_at(pos: DVec3, pitch: f64) -> Camera {
        Camera::new(
            pos,
            Attitude::from_degrees(0.0, pitch, 0.0),
            Frustum::symmetric(60f64.to_radians(), 256, 144),
        )
    }

    fn heights(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Vec<f32> {
        (0..h)
            .flat_map(|r| (0..w).map(move |c| (c, r)))
            .map(|(c, r)| f(c, r))
            .collect()
    }

    fn params(global: f64) -> TessParams {
        TessParams {
            global,
            d_min_m: 0.0,
            d_max_m: 20_000.0,
            max_level: 64,
            curvature: false,
        }
    }

    #[test]
    fn flat_patches_get_the_minimum_and_rough_ones_more() {
        // West half flat, east half a field of bumps.
        let (w, h) = (129usize, 97usize);
        let hs = heights(w, h, |c, r| {
            if c < 64 {
                100.0
            } else {
                100.0 + 40.0 * (((c * c * 7 + r * r * 13 + c * r) % 5) as f32)
            }
        });
        let d = TessDensity::new(&hs, [w as u32, h as u32], 32, 0.5).unwrap();
        let cam = camera_at(DVec3::new(64.0 * 30.0, -3000.0, 3000.0), -35.0);
        let mut out = Vec::new();
        let s = select_patches(&d, [30.0, 30.0], None, &cam, &params(32.0), &mut out);
        assert!(s.patches > 0);
        let flat: Vec<_> = out.iter().filter(|p| p.cell[0] == 0).collect();
        // An inner rough cell (the grid's border rows and columns show fewer directions).
        let rough: Vec<_> = out.iter().filter(|p| p.cell == [2, 1]).collect();
        assert!(!flat.is_empty() && !rough.is_empty());
        for p in flat {
            assert_eq!((p.outer, p.inner), ([1.0; 3], 1.0), "{p:?}");
            assert_eq!(
                triangles_emitted(p.outer, p.inner, Spacing::FractionalOdd, 64),
                1
            );
        }
        for p in rough {
            assert!(p.outer.iter().all(|&f| f > 8.0) && p.inner > 8.0, "{p:?}");
        }
        // A larger knob: more triangles; nearer the eye: higher factors.
        let more = select_patches(&d, [30.0, 30.0], None, &cam, &params(64.0), &mut Vec::new());
        assert!(more.triangles > s.triangles);
        let far = camera_at(DVec3::new(64.0 * 30.0, -15000.0, 3000.0), -10.0);
        let fewer = select_patches(&d, [30.0, 30.0], None, &far, &params(32.0), &mut Vec::new());
        assert!(fewer.triangles < s.triangles, "{fewer:?} {s:?}");
    }

    /// A 1/1200° grid at 47° N, 257 × 257 samples (cells of 32: 8 × 8), on the ellipsoid.
    fn geo_grid() -> GeoGrid {
        GeoGrid::test_geographic(47.0, 11.0, 1.0 / 1200.0, 47.05)
    }

    #[test]
    fn placed_boxes_hold_every_sample_on_the_ellipsoid_and_cull_by_them() {
        let (w, h) = (257usize, 257usize);
        let hs = heights(w, h, |c, r| {
            (800.0 + 600.0 * ((c as f32 * 0.04).sin() * (r as f32 * 0.05).cos())).max(0.0)
        });
        let d = TessDensity::new(&hs, [w as u32, h as u32], 32, 0.5).unwrap();
        let grid = geo_grid();
        let placed = TessPlacement::new(&d, &grid);
        assert_eq!(placed.boxes.len(), 64);
        assert_eq!(placed.corners.len(), 81);
        let sp = DVec2::new(grid.spacing_x, grid.spacing_y);
        // Every sample of every cell (its edges included) lies in the cell's box.
        for cy in 0..8u32 {
            for cx in 0..8u32 {
                let b = placed.boxes[(cy * 8 + cx) as usize];
                for r in cy * 32..=cy * 32 + 32 {
                    for c in cx * 32..=cx * 32 + 32 {
                        let hgt = hs[r as usize * w + c as usize] as f64;
                        let p = grid.world_of_grid(DVec2::new(c as f64, r as f64) * sp, hgt);
                        assert!(
                            p.cmpge(b.min - 1e-6).all() && p.cmple(b.max + 1e-6).all(),
                            "cell ({cx}, {cy}) sample ({c}, {r}): {p:?} outside {b:?}"
                        );
                    }
                }
            }
        }
        // The far corner sits below the flat plane by the Earth's curvature (~ d²/2R).
        let far = placed.corners[80];
        let flat_z = d.corner_height(8, 8) as f64;
        let drop = (far.x * far.x + far.y * far.y) / (2.0 * 6.371e6);
        assert!(
            (flat_z - far.z - drop).abs() < 0.05 * drop,
            "{far:?} {drop}"
        );
        // Looking north from the middle of the south edge: the cells behind the eye are
        // culled, those ahead drawn, and the distances are the placed ones.
        let eye = grid.world_of_grid(DVec2::new(128.0, 100.0) * sp, 2500.0);
        let cam = camera_at(eye, -20.0);
        let mut out = Vec::new();
        let s = select_patches(
            &d,
            [sp.x, sp.y],
            Some(&placed),
            &cam,
            &params(32.0),
            &mut out,
        );
        assert!(s.culled > 0 && s.patches > 0, "{s:?}");
        assert!(
            out.iter().all(|p| p.cell[1] >= 2),
            "cells behind the eye drawn"
        );
        assert!(out.iter().any(|p| p.cell[1] == 7));
    }

    #[test]
    fn neighbours_agree_on_every_shared_edge_and_hidden_cells_are_culled() {
        let (w, h) = (161usize, 161usize);
        let hs = heights(w, h, |c, r| {
            500.0 * ((c as f32 * 0.05).sin() * (r as f32 * 0.07).cos())
        });
        let d = TessDensity::new(&hs, [w as u32, h as u32], 32, 0.5).unwrap();
        // Looking north over part of the grid from its south-west corner.
        let cam = camera_at(DVec3::new(600.0, -500.0, 1500.0), -20.0);
        let mut out = Vec::new();
        let s = select_patches(&d, [30.0, 30.0], None, &cam, &params(32.0), &mut out);
        assert!(s.culled > 0 && s.patches > 0, "{s:?}");
        assert_eq!(s.patches + 2 * s.culled, 2 * s.cells);
        let get = |cx: u32, cy: u32, nw: bool| {
            out.iter()
                .find(|p| p.cell == [cx, cy] && p.north_west == nw)
                .copied()
        };
        let mut checked = 0;
        for p in &out {
            let [cx, cy] = p.cell;
            if p.north_west {
                // The diagonal with the cell's other half.
                assert_eq!(Some(p.outer[2]), get(cx, cy, false).map(|q| q.outer[1]));
                // North edge = the south edge of the cell above; west = east of the cell west.
                if let Some(q) = get(cx, cy + 1, false) {
                    assert_eq!(p.outer[0], q.outer[2]);
                    checked += 1;
                }
                if let Some(q) = (cx > 0).then(|| get(cx - 1, cy, false)).flatten() {
                    assert_eq!(p.outer[1], q.outer[0]);
                    checked += 1;
                }
            }
        }
        assert!(checked > 10, "{checked}");
        assert!(out.iter().any(|p| p.outer[0] != p.outer[1]), "factors vary");
    }
}
