//! Random small grids (rough, with needles and walls, every tile size that fits) and random
//! rays and points over and around them, against the oracle.

use glam::DVec3;
use proptest::prelude::*;

use super::oracle::{all_triangles, assert_agrees, dataset, first_hit as oracle_hit, hot, source};
use crate::dataset::padded_side;
use crate::query::{first_hit, height_of_terrain, Lookup, Ray, SurfaceSource};

/// A grid: sizes, spacing, heights (some needles, some walls), tile size exponent.
#[derive(Debug, Clone)]
struct Grid {
    w: usize,
    h: usize,
    spacing: (f64, f64),
    heights: Vec<f32>,
    j: u32,
}

fn grid() -> impl Strategy<Value = Grid> {
    (3usize..40, 3usize..40, 1.0f64..40.0, 1.0f64..40.0, 1u32..6)
        .prop_flat_map(|(w, h, sx, sy, j)| {
            let n = w * h;
            (
                Just((w, h, sx, sy, j)),
                proptest::collection::vec(0.0f32..50.0, n),
                proptest::collection::vec((0..n, 100.0f32..500.0), 0..4),
                0..w,
            )
        })
        .prop_map(|((w, h, sx, sy, j), mut heights, needles, wall)| {
            for (i, tall) in needles {
                heights[i] += tall;
            }
            // A wall: every column east of `wall` raised by 200 m.
            for r in 0..h {
                for c in wall..w {
                    if wall > 0 {
                        heights[r * w + c] += 200.0;
                    }
                }
            }
            // Tile sizes that fit the padded grid: 2^j ≤ min side − 1.
            let side = padded_side(w).min(padded_side(h)) - 1;
            let j = j.min(side.trailing_zeros());
            Grid {
                w,
                h,
                spacing: (sx, sy),
                heights,
                j,
            }
        })
}

/// Unit-box numbers turned into a ray over and around a grid of `extent` metres.
fn ray_in(extent: (f64, f64), top: f64, p: [f64; 7]) -> Ray {
    let o = DVec3::new(
        (p[0] * 1.4 - 0.2) * extent.0,
        (p[1] * 1.4 - 0.2) * extent.1,
        p[2] * (top + 100.0) - 20.0,
    );
    let az = p[3] * std::f64::consts::TAU;
    let el = (p[4] - 0.7) * 2.0;
    let d = DVec3::new(az.cos() * el.cos(), az.sin() * el.cos(), el.sin());
    let len = (extent.0 + extent.1) * 2.0 * p[5];
    Ray::new(o, d, p[6] * 0.1 * len, len.max(p[6] * 0.1 * len)).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn random_grids_and_rays_match_the_oracle(
        g in grid(),
        rays in proptest::collection::vec(proptest::array::uniform7(0.0f64..1.0), 1..24),
        points in proptest::collection::vec((0.0f64..1.0, 0.0f64..1.0), 1..24),
    ) {
        let m = (1u32 << g.j) + 1;
        let ds = dataset(g.w, g.h, g.spacing, |c, r| g.heights[r * g.w + c]);
        let tris = all_triangles(&ds, m);
        let top = f64::from(ds.hf.min_max().1);
        let src = source(ds, m);
        let extent = src.grid().real_extent_m();
        for p in rays {
            let r = ray_in(extent, top, p);
            assert_agrees(first_hit(&src, &r), oracle_hit(&tris, extent, &r), &r, 1e-6);
        }
        for (fx, fy) in points {
            // Over the data and around it (padding, outside).
            let (x, y) = ((fx * 1.2 - 0.1) * extent.0, (fy * 1.2 - 0.1) * extent.1);
            match (height_of_terrain(&src, x, y), hot(&tris, x, y)) {
                (Lookup::Ready(gr), Some((h, normals))) => {
                    prop_assert!((gr.height_m - h).abs() < 1e-9);
                    prop_assert!(normals.iter().any(|n| (*n - gr.normal).length() < 1e-9));
                }
                (Lookup::NoTerrain, None) => {}
                (got, want) => prop_assert!(false, "({x}, {y}): {got:?} vs {want:?}"),
            }
        }
    }
}
