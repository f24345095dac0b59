//! The embedded DEM (N47E011, 3" SRTM, 62.7 m × 92.6 m spacing): random points and rays on a
//! window against every triangle of it, and 10 km lines of sight on the whole tile against
//! every triangle under the line's bounding box.

use glam::DVec3;

use super::oracle::{
    all_triangles, assert_agrees, dem_window, embedded_dem, first_hit as oracle_hit, hot, source,
    triangles_in, OracleHit, Rng,
};
use crate::mesh::quad_surface;
use crate::query::{first_hit, height_of_terrain, Lookup, Ray, SurfaceSource};

#[test]
fn heights_match_the_triangles_drawn_on_a_dem_window() {
    // 101 × 77 real samples of the Inn valley's north slope, padded to 129².
    let ds = dem_window(600, 500, 101, 77);
    let tris = all_triangles(&ds, 17);
    let hf = ds.hf.clone();
    let src = source(ds, 17);
    let (east, north) = src.grid().real_extent_m();
    let mut rng = Rng(0x5eed_0001);
    for _ in 0..400 {
        let (x, y) = (rng.range(0.0, east), rng.range(0.0, north));
        let g = height_of_terrain(&src, x, y)
            .ready()
            .expect("inside the data");
        let (h, normals) = hot(&tris, x, y).expect("oracle finds a triangle");
        assert!(
            (g.height_m - h).abs() < 1e-9,
            "({x}, {y}): {} vs {h}",
            g.height_m
        );
        assert!(normals.iter().any(|n| (*n - g.normal).length() < 1e-9));
        assert!((g.normal.length() - 1.0).abs() < 1e-12 && g.normal.z > 0.0);
    }
    // At every sample the height is the sample itself (what the mesh's vertex holds).
    for r in (0..77).step_by(7) {
        for c in (0..101).step_by(9) {
            let (x, y) = (c as f64 * hf.spacing_x, r as f64 * hf.spacing_y);
            let g = height_of_terrain(&src, x, y).ready().unwrap();
            assert_eq!(g.height_m, f64::from(hf.at(c, r)), "sample ({c}, {r})");
        }
    }
    // And in a quad it is mesh::quad_surface, bit for bit.
    let (c, r, u, v) = (40usize, 30usize, 0.3125, 0.8125);
    let g = height_of_terrain(
        &src,
        (c as f64 + u) * hf.spacing_x,
        (r as f64 + v) * hf.spacing_y,
    );
    let h = |c: usize, r: usize| f64::from(hf.at(c, r));
    let want = quad_surface(h(c, r), h(c + 1, r), h(c, r + 1), h(c + 1, r + 1), u, v);
    assert_eq!(g.ready().unwrap().height_m, want);
}

#[test]
fn random_rays_on_a_dem_window_match_every_triangle() {
    let ds = dem_window(600, 500, 101, 77);
    let tris = all_triangles(&ds, 17);
    let (lo, hi) = ds.hf.min_max();
    let src = source(ds, 17);
    let extent = src.grid().real_extent_m();
    let mut rng = Rng(0x5eed_0002);
    let (mut hits, mut clear, mut none) = (0, 0, 0);
    for i in 0..600 {
        // Origins inside and around the window, from below the lowest to above the highest
        // sample; directions mostly shallow (the hard case), some steep.
        let o = DVec3::new(
            rng.range(-0.2 * extent.0, 1.2 * extent.0),
            rng.range(-0.2 * extent.1, 1.2 * extent.1),
            rng.range(f64::from(lo) - 50.0, f64::from(hi) + 200.0),
        );
        let az = rng.range(0.0, std::f64::consts::TAU);
        let el = if i % 4 == 0 {
            rng.range(-1.5, 1.5)
        } else {
            rng.range(-0.3, 0.1)
        };
        let d = DVec3::new(az.cos() * el.cos(), az.sin() * el.cos(), el.sin());
        let ray = Ray::new(o, d, rng.range(0.0, 100.0), rng.range(100.0, 9000.0)).unwrap();
        let want = oracle_hit(&tris, extent, &ray);
        match want {
            OracleHit::Hit(..) => hits += 1,
            OracleHit::Clear => clear += 1,
            OracleHit::NoTerrain => none += 1,
        }
        assert_agrees(first_hit(&src, &ray), want, &ray, 1e-6);
    }
    // The sample exercises every kind of answer.
    assert!(
        hits > 100 && clear > 50 && none > 10,
        "{hits} {clear} {none}"
    );
}

#[test]
fn ten_km_lines_of_sight_on_the_whole_tile() {
    let ds = embedded_dem().clone();
    let (sx, sy) = (ds.hf.spacing_x, ds.hf.spacing_y);
    let src = source(ds.clone(), 17);
    let extent = src.grid().real_extent_m();
    let mut rng = Rng(0x5eed_0003);
    let mut hits = 0;
    for _ in 0..60 {
        // Eye 2–300 m above the ground, target on the ground (+0–30 m) 10 km away.
        let (ex, ey) = (
            rng.range(0.1 * extent.0, 0.9 * extent.0),
            rng.range(0.1 * extent.1, 0.9 * extent.1),
        );
        let az = rng.range(0.0, std::f64::consts::TAU);
        let (tx, ty) = (ex + 10_000.0 * az.cos(), ey + 10_000.0 * az.sin());
        if !(0.0..=extent.0).contains(&tx) || !(0.0..=extent.1).contains(&ty) {
            continue;
        }
        let hz = |x, y| height_of_terrain(&src, x, y).ready().unwrap().height_m;
        let from = DVec3::new(ex, ey, hz(ex, ey) + rng.range(2.0, 300.0));
        let to = DVec3::new(tx, ty, hz(tx, ty) + rng.range(0.0, 30.0));
        let ray = Ray::segment(from, to).unwrap();
        // The oracle: every triangle of every quad in the segment's bounding box (+1 quad).
        let q = |a: f64, b: f64, s: f64| {
            let lo = (a.min(b) / s).floor().max(1.0) as usize - 1;
            lo..(a.max(b) / s).ceil() as usize + 2
        };
        let tris = triangles_in(&ds, 17, q(ex, tx, sx), q(ey, ty, sy));
        let want = oracle_hit(&tris, extent, &ray);
        hits += matches!(want, OracleHit::Hit(..)) as u32;
        assert_agrees(first_hit(&src, &ray), want, &ray, 1e-6);
    }
    assert!(hits > 5, "{hits} of the lines are blocked");
}

#[test]
fn grazing_the_highest_vertex() {
    // The highest sample of a large region, and a window centred on it: the peak is above
    // every other point of the window's surface, so a horizontal ray through it misses when
    // 1 mm above it and hits when 1 mm below.
    let dem = embedded_dem();
    let (mut best, mut at) = (f32::MIN, (0, 0));
    for r in 200..1000 {
        for c in 200..1000 {
            if dem.hf.at(c, r) > best {
                (best, at) = (dem.hf.at(c, r), (c, r));
            }
        }
    }
    let ds = dem_window(at.0 - 32, at.1 - 32, 65, 65);
    let hf = ds.hf.clone();
    assert_eq!(hf.at(32, 32), best);
    assert_eq!(hf.heights.iter().filter(|&&h| h >= best - 0.01).count(), 1);
    let at = (32, 32);
    let tris = all_triangles(&ds, 17);
    let src = source(ds, 17);
    let extent = src.grid().real_extent_m();
    let peak = DVec3::new(
        at.0 as f64 * hf.spacing_x,
        at.1 as f64 * hf.spacing_y,
        f64::from(best),
    );
    let mut rng = Rng(0x5eed_0004);
    for _ in 0..40 {
        let az = rng.range(0.0, std::f64::consts::TAU);
        let d = DVec3::new(az.cos(), az.sin(), 0.0);
        for (dz, hit) in [(1e-3, false), (-1e-3, true)] {
            let o = peak + DVec3::new(0.0, 0.0, dz) - d * 3000.0;
            let ray = Ray::new(o, d, 0.0, 6000.0).unwrap();
            let got = first_hit(&src, &ray);
            let want = oracle_hit(&tris, extent, &ray);
            match got {
                Lookup::Ready(Some(h)) => {
                    assert!(hit, "hit 1 mm above the peak: {h:?}");
                    // Just before the peak: every other sample is ≥ 1 cm lower, so only the
                    // peak's own slopes reach 1 mm below its top.
                    assert!(h.range_m <= 3000.0 && h.range_m > 2900.0, "{h:?}");
                }
                Lookup::Ready(None) => assert!(!hit, "missed 1 mm below the peak"),
                other => panic!("{other:?}"),
            }
            assert_agrees(got, want, &ray, 1e-6);
        }
    }
}
