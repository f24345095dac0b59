//! Hand-made cases: the domain and its borders, normals, cliffs, spikes, vertical rays, rays
//! along grid lines and diagonals, rays leaving the data or starting below it, bad input.

use std::sync::Arc;

use glam::DVec3;

use super::oracle::{
    all_triangles, assert_agrees, dataset, dem_window, first_hit as oracle_hit, source, Rng,
};
use crate::bake::{bake, BakeParams};
use crate::query::{
    first_hit, height_of_terrain, InMemorySource, Lookup, Ray, RayError, SourceError, SurfaceSource,
};

fn ray(o: [f64; 3], d: [f64; 3], t_max: f64) -> Ray {
    Ray::new(DVec3::from(o), DVec3::from(d), 0.0, t_max).unwrap()
}

fn hit(l: Lookup<Option<crate::query::RayHit>>) -> crate::query::RayHit {
    match l {
        Lookup::Ready(Some(h)) => h,
        other => panic!("expected a hit, got {other:?}"),
    }
}

#[test]
fn only_real_data_is_terrain() {
    // 20 × 12 real samples, padded to 33 × 17 east and north.
    let src = source(dataset(20, 12, (10.0, 15.0), |c, r| (c + 2 * r) as f32), 5);
    let (east, north) = src.grid().real_extent_m();
    assert_eq!((east, north), (190.0, 165.0));
    for (x, y) in [
        (-1e-9, 5.0),
        (5.0, -1e-9),
        (190.0 + 1e-9, 5.0), // over the east padding
        (5.0, 165.0 + 1e-9), // over the north padding
        (250.0, 200.0),      // padding in both
        (1e6, 1e6),          // outside the grid
        (f64::NAN, 5.0),
        (5.0, f64::INFINITY),
    ] {
        assert_eq!(
            height_of_terrain(&src, x, y),
            Lookup::NoTerrain,
            "({x}, {y})"
        );
    }
    // The borders themselves are real: the corners are their samples.
    let at = |x, y| height_of_terrain(&src, x, y).ready().unwrap().height_m;
    assert_eq!(at(0.0, 0.0), 0.0);
    assert_eq!(at(190.0, 0.0), 19.0);
    assert_eq!(at(0.0, 165.0), 22.0);
    assert_eq!(at(190.0, 165.0), 41.0);
}

#[test]
fn normals_are_the_containing_triangles() {
    // One plane: every normal is the plane's, every height exact.
    let (a, b) = (3.0, -2.0);
    let src = source(
        dataset(17, 17, (10.0, 20.0), |c, r| {
            (a * c as f64 + b * r as f64) as f32 + 500.0
        }),
        5,
    );
    let want = DVec3::new(-a / 10.0, -b / 20.0, 1.0).normalize();
    let mut rng = Rng(7);
    for _ in 0..100 {
        let (x, y) = (rng.range(0.0, 160.0), rng.range(0.0, 320.0));
        let g = height_of_terrain(&src, x, y).ready().unwrap();
        assert!((g.normal - want).length() < 1e-12);
        assert!((g.height_m - (500.0 + a * x / 10.0 + b * y / 20.0)).abs() < 1e-9);
    }
    // One raised corner: quad (0, 0) has sw = se = nw = 0, ne = 10 (spacing 10 m), so its
    // south-east triangle rises north (0, 1 m/m) and its north-west triangle rises east.
    let src = source(
        dataset(5, 5, (10.0, 10.0), |c, r| {
            if (c, r) == (1, 1) {
                10.0
            } else {
                0.0
            }
        }),
        3,
    );
    let n = |x, y| height_of_terrain(&src, x, y).ready().unwrap().normal;
    let se = DVec3::new(0.0, -1.0, 1.0).normalize();
    let nw = DVec3::new(-1.0, 0.0, 1.0).normalize();
    assert!((n(7.0, 2.0) - se).length() < 1e-12);
    assert!((n(2.0, 7.0) - nw).length() < 1e-12);
    // On the diagonal: the south-east triangle.
    assert!((n(5.0, 5.0) - se).length() < 1e-12);
    // On a grid line inside the data: the quad east (north) of it. x = 10 is quad (1, 0)'s
    // west edge; at y = 2 (u 0, v 0.2) that is its north-west triangle (sw 0, nw 10, ne 0),
    // which falls east and rises north.
    let west_edge = n(10.0, 2.0);
    assert!((west_edge - DVec3::new(1.0, -1.0, 1.0).normalize()).length() < 1e-12);
}

#[test]
fn a_cliff_is_hit_on_its_slope() {
    // A vertical step of 500 m between columns 9 and 10: the surface is the one-quad slope
    // between them, z = 100 + 500 u.
    let ds = dataset(
        33,
        33,
        (10.0, 10.0),
        |c, _| if c < 10 { 100.0 } else { 600.0 },
    );
    let tris = all_triangles(&ds, 9);
    let src = source(ds, 9);
    let extent = src.grid().real_extent_m();
    let r = ray([5.0, 55.0, 300.0], [1.0, 0.0, 0.0], 1000.0);
    let h = hit(first_hit(&src, &r));
    let x = 90.0 + (300.0 - 100.0) / 500.0 * 10.0;
    assert!((h.range_m - (x - 5.0)).abs() < 1e-9, "{h:?}");
    assert!((h.normal - DVec3::new(-50.0, 0.0, 1.0).normalize()).length() < 1e-12);
    // From the top, looking west and down: it misses the wall's top (it is over the upper
    // terrace there) and hits the low terrace.
    let r = ray([101.0, 55.0, 650.0], [-1.0, 0.0, -10.0], 1000.0);
    let h = hit(first_hit(&src, &r));
    assert!(
        h.point.x < 90.0 && (h.point.z - 100.0).abs() < 1e-9,
        "{h:?}"
    );
    // Every direction, against the oracle.
    let mut rng = Rng(11);
    for _ in 0..200 {
        let o = DVec3::new(
            rng.range(0.0, 320.0),
            rng.range(0.0, 320.0),
            rng.range(50.0, 700.0),
        );
        let az = rng.range(0.0, std::f64::consts::TAU);
        let el = rng.range(-0.8, 0.3);
        let d = DVec3::new(az.cos() * el.cos(), az.sin() * el.cos(), el.sin());
        let r = Ray::new(o, d, 0.0, 500.0).unwrap();
        assert_agrees(first_hit(&src, &r), oracle_hit(&tris, extent, &r), &r, 1e-6);
    }
}

#[test]
fn a_single_sample_spike() {
    // A 1000 m needle on flat ground: invisible to every coarse level's ε but not to the max.
    let ds = dataset(33, 33, (10.0, 10.0), |c, r| {
        if (c, r) == (16, 16) {
            1000.0
        } else {
            0.0
        }
    });
    let tris = all_triangles(&ds, 9);
    let src = source(ds, 9);
    let extent = src.grid().real_extent_m();
    let top = DVec3::new(160.0, 160.0, 1000.0);
    let mut rng = Rng(13);
    for _ in 0..50 {
        let az = rng.range(0.0, std::f64::consts::TAU);
        let d = DVec3::new(az.cos(), az.sin(), 0.0);
        for (dz, hits) in [(1e-3, false), (-1e-3, true)] {
            let o = top + DVec3::new(0.0, 0.0, dz) - d * 150.0;
            let r = Ray::new(o, d, 0.0, 300.0).unwrap();
            let got = first_hit(&src, &r);
            match got {
                // The faces rise ≥ 100 m per metre near the top: the hit is within 1e-4 m.
                Lookup::Ready(Some(h)) => {
                    assert!(hits && (h.range_m - 150.0).abs() < 1e-4, "{h:?}")
                }
                Lookup::Ready(None) => assert!(!hits, "missed 1 mm below the top"),
                other => panic!("{other:?}"),
            }
            assert_agrees(got, oracle_hit(&tris, extent, &r), &r, 1e-6);
        }
    }
    // Rays towards the needle's faces from every side, low and high.
    for _ in 0..200 {
        let o = DVec3::new(
            rng.range(100.0, 220.0),
            rng.range(100.0, 220.0),
            rng.range(1.0, 1100.0),
        );
        let to = DVec3::new(
            rng.range(140.0, 180.0),
            rng.range(140.0, 180.0),
            rng.range(0.0, 900.0),
        );
        let r = Ray::segment(o, to).unwrap();
        assert_agrees(first_hit(&src, &r), oracle_hit(&tris, extent, &r), &r, 1e-6);
    }
}

#[test]
fn vertical_rays() {
    let src = source(dem_window(200, 700, 65, 65), 17);
    let (east, north) = src.grid().real_extent_m();
    let mut rng = Rng(17);
    for _ in 0..100 {
        let (x, y) = (rng.range(0.0, east), rng.range(0.0, north));
        let g = height_of_terrain(&src, x, y).ready().unwrap();
        // Down from 500 m above: the ground, with the height-of-terrain normal.
        let h = hit(first_hit(
            &src,
            &ray([x, y, g.height_m + 500.0], [0.0, 0.0, -1.0], 1e4),
        ));
        assert!((h.range_m - 500.0).abs() < 1e-9 && h.normal == g.normal);
        assert!((h.point.z - g.height_m).abs() < 1e-9);
        // Too short to reach it, or looking up: clear.
        let r = ray([x, y, g.height_m + 500.0], [0.0, 0.0, -1.0], 499.0);
        assert_eq!(first_hit(&src, &r), Lookup::Ready(None));
        let r = ray([x, y, g.height_m + 1.0], [0.0, 0.0, 1.0], 1e4);
        assert_eq!(first_hit(&src, &r), Lookup::Ready(None));
        // From below, either way: a hit at the start.
        for dz in [1.0, -1.0] {
            let h = hit(first_hit(
                &src,
                &ray([x, y, g.height_m - 2.0], [0.0, 0.0, dz], 1e4),
            ));
            assert_eq!(h.range_m, 0.0);
            assert_eq!(h.point, DVec3::new(x, y, g.height_m - 2.0));
        }
        // Almost vertical: the general path agrees.
        let h2 = hit(first_hit(
            &src,
            &ray([x, y, g.height_m + 500.0], [1e-9, 1e-9, -1.0], 1e4),
        ));
        assert!((h2.range_m - 500.0).abs() < 1e-5, "{h2:?}");
    }
    let r = ray([east + 1.0, 5.0, 1e4], [0.0, 0.0, -1.0], 1e5);
    assert_eq!(first_hit(&src, &r), Lookup::NoTerrain);
}

#[test]
fn rays_along_grid_lines_and_diagonals() {
    let ds = dem_window(900, 900, 65, 65);
    let (sx, sy) = (ds.hf.spacing_x, ds.hf.spacing_y);
    let tris = all_triangles(&ds, 17);
    let (lo, hi) = ds.hf.min_max();
    let src = source(ds, 17);
    let extent = src.grid().real_extent_m();
    let mut rng = Rng(19);
    let dirs = [
        [1.0, 0.0],
        [-1.0, 0.0],
        [0.0, 1.0],
        [0.0, -1.0],
        [sx, sy], // along the mesh's diagonals
        [-sx, -sy],
        [sx, -sy], // across them
        [-sx, sy],
    ];
    let mut hits = 0;
    for k in 0..400 {
        // Start on a vertex, a vertical grid line or a horizontal one.
        let (c, r) = ((rng.next_u64() % 65) as f64, (rng.next_u64() % 65) as f64);
        let (x, y) = match k % 3 {
            0 => (c * sx, r * sy),
            1 => (c * sx, rng.range(0.0, extent.1)),
            _ => (rng.range(0.0, extent.0), r * sy),
        };
        let d = dirs[k % dirs.len()];
        let slope = if k % 5 == 0 {
            0.0
        } else {
            rng.range(-0.4, 0.2)
        };
        let z = rng.range(f64::from(lo), f64::from(hi) + 100.0);
        let d = DVec3::new(d[0], d[1], 0.0).normalize() + DVec3::new(0.0, 0.0, slope);
        let r = Ray::new(DVec3::new(x, y, z), d, 0.0, 8000.0).unwrap();
        let want = oracle_hit(&tris, extent, &r);
        hits += matches!(want, super::oracle::OracleHit::Hit(..)) as u32;
        assert_agrees(first_hit(&src, &r), want, &r, 1e-6);
    }
    assert!(hits > 100, "{hits}");
}

#[test]
fn rays_leaving_the_data_never_hit_beyond_it() {
    // Real data 20 × 12 rising east to 190 m; the east padding repeats column 19 (190 m).
    let ds = dataset(20, 12, (10.0, 10.0), |c, _| (10 * c) as f32);
    let padded = ds.hf.clone();
    let src = source(ds, 5);
    // Down-slope eastwards: above the real data all the way, it would reach the padding's
    // 190 m at x = 250.
    let r = ray([150.0, 50.0, 200.0], [1.0, 0.0, -0.1], 1000.0);
    assert_eq!(first_hit(&src, &r), Lookup::Ready(None));
    // The same heights as real data (nothing padded) are hit there: the padding is what the
    // first answer ignored.
    let all_real = source(
        crate::dataset::Dataset::from_heightfield(padded, "p".into()),
        5,
    );
    let h = hit(first_hit(&all_real, &r));
    assert!((h.point.x - 250.0).abs() < 1e-6, "{h:?}");
    // Entirely outside (over padding, or off the grid): no terrain.
    let r = ray([200.0, 50.0, 500.0], [1.0, 0.0, -1.0], 1000.0);
    assert_eq!(first_hit(&src, &r), Lookup::NoTerrain);
    let r = ray([-100.0, -100.0, 0.0], [-1.0, 0.0, 0.0], 1000.0);
    assert_eq!(first_hit(&src, &r), Lookup::NoTerrain);
    // Entering from outside below the terrain's height: the data's edge is a wall.
    let src = source(
        dataset(20, 12, (10.0, 10.0), |c, _| (100 + 10 * c) as f32),
        5,
    );
    let h = hit(first_hit(
        &src,
        &ray([-50.0, 55.0, 50.0], [1.0, 0.0, 0.0], 1000.0),
    ));
    assert!(
        (h.range_m - 50.0).abs() < 1e-12 && h.point.x.abs() < 1e-12,
        "{h:?}"
    );
    // Entering above it: the slope ahead.
    let h = hit(first_hit(
        &src,
        &ray([-50.0, 55.0, 150.0], [1.0, 0.0, 0.0], 1000.0),
    ));
    assert!((h.point.x - 50.0).abs() < 1e-9, "{h:?}");
}

#[test]
fn rays_and_segments_starting_below_ground() {
    let src = source(dem_window(400, 400, 65, 65), 17);
    let g = height_of_terrain(&src, 1000.0, 1500.0).ready().unwrap();
    let o = DVec3::new(1000.0, 1500.0, g.height_m - 5.0);
    for d in [[1.0, 0.0, 0.0], [0.3, -0.2, 0.9], [0.0, 1.0, -0.5]] {
        let h = hit(first_hit(
            &src,
            &Ray::new(o, DVec3::from(d), 0.0, 5000.0).unwrap(),
        ));
        assert_eq!((h.range_m, h.point), (0.0, o));
        assert_eq!(h.normal, g.normal);
    }
    // A range that starts later starts where it starts: straight up from below, the part
    // from 10 m on is above ground.
    let r = Ray::new(o, DVec3::Z, 10.0, 100.0).unwrap();
    assert_eq!(first_hit(&src, &r), Lookup::Ready(None));
    // Segments: a point segment is a point test; a segment stops where it ends.
    let above = o + DVec3::new(0.0, 0.0, 10.0);
    assert_eq!(
        hit(first_hit(&src, &Ray::segment(o, o).unwrap())).range_m,
        0.0
    );
    assert_eq!(
        first_hit(&src, &Ray::segment(above, above).unwrap()),
        Lookup::Ready(None)
    );
    let down = above - DVec3::new(0.0, 0.0, 20.0);
    let h = hit(first_hit(&src, &Ray::segment(above, down).unwrap()));
    assert!((h.range_m - 5.0).abs() < 1e-9);
    let short = above - DVec3::new(0.0, 0.0, 4.9);
    assert_eq!(
        first_hit(&src, &Ray::segment(above, short).unwrap()),
        Lookup::Ready(None)
    );
}

#[test]
fn every_tile_size_gives_the_same_answers() {
    // m = 3 has no fine blocks at all, m = 33 has four levels of them.
    let srcs: Vec<InMemorySource> = [3, 5, 9, 17, 33]
        .into_iter()
        .map(|m| source(dem_window(100, 100, 129, 129), m))
        .collect();
    let (east, north) = srcs[0].grid().real_extent_m();
    let mut rng = Rng(23);
    for _ in 0..300 {
        let o = DVec3::new(
            rng.range(0.0, east),
            rng.range(0.0, north),
            rng.range(500.0, 3000.0),
        );
        let az = rng.range(0.0, std::f64::consts::TAU);
        let el = rng.range(-0.5, 0.1);
        let d = DVec3::new(az.cos() * el.cos(), az.sin() * el.cos(), el.sin());
        let r = Ray::new(o, d, 0.0, 20_000.0).unwrap();
        let first = first_hit(&srcs[0], &r);
        for s in &srcs[1..] {
            let other = first_hit(s, &r);
            match (first, other) {
                (Lookup::Ready(Some(a)), Lookup::Ready(Some(b))) => {
                    assert!((a.range_m - b.range_m).abs() < 1e-9, "{a:?} vs {b:?}")
                }
                (a, b) => assert_eq!(a, b),
            }
        }
    }
}

#[test]
fn bad_rays_are_refused_by_name() {
    let (o, d) = (DVec3::ZERO, DVec3::X);
    assert!(matches!(
        Ray::new(DVec3::new(f64::NAN, 0.0, 0.0), d, 0.0, 1.0),
        Err(RayError::NotFinite {
            field: "origin",
            ..
        })
    ));
    assert!(matches!(
        Ray::new(o, DVec3::new(0.0, f64::INFINITY, 0.0), 0.0, 1.0),
        Err(RayError::NotFinite {
            field: "direction",
            ..
        })
    ));
    assert_eq!(
        Ray::new(o, DVec3::ZERO, 0.0, 1.0),
        Err(RayError::ZeroDirection)
    );
    assert!(matches!(
        Ray::new(o, d, 2.0, 1.0),
        Err(RayError::EmptyRange { .. })
    ));
    assert!(matches!(
        Ray::new(o, d, f64::NEG_INFINITY, 1.0),
        Err(RayError::NotFinite { field: "t_min", .. })
    ));
    assert!(matches!(
        Ray::new(o, d, 0.0, f64::NAN),
        Err(RayError::NotFinite { field: "t_max", .. })
    ));
    assert!(Ray::new(o, d, 0.0, f64::INFINITY).is_ok());
    assert!(matches!(
        Ray::segment(o, DVec3::new(1.0, f64::NAN, 0.0)),
        Err(RayError::NotFinite { field: "to", .. })
    ));
    // A non-unit direction is normalised: ranges are metres.
    let r = Ray::new(o, DVec3::new(0.0, 3.0, 4.0), 0.0, 1.0).unwrap();
    assert_eq!(r.dir(), DVec3::new(0.0, 0.6, 0.8));
}

#[test]
fn a_bake_of_other_data_is_refused_by_name() {
    let a = dataset(20, 12, (10.0, 10.0), |c, _| c as f32);
    let params = BakeParams {
        tile_size: 5,
        levels: 0,
    };
    let b = dataset(21, 12, (10.0, 10.0), |c, _| c as f32);
    let err = InMemorySource::new(Arc::new(a.clone()), Arc::new(bake(&b, params, &|_, _| {})))
        .unwrap_err();
    assert!(
        matches!(
            err,
            SourceError::Mismatch {
                field: "valid_width",
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string().contains("20") && err.to_string().contains("21"),
        "{err}"
    );
    // Same sizes, other heights: the first tile whose maximum differs is named.
    let c = dataset(20, 12, (10.0, 10.0), |c, r| {
        if (c, r) == (9, 5) {
            99.0
        } else {
            c as f32
        }
    });
    let err = InMemorySource::new(Arc::new(a), Arc::new(bake(&c, params, &|_, _| {}))).unwrap_err();
    assert!(err.to_string().contains("tile (2, 1)"), "{err}");
}
