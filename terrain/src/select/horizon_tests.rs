//! Unit tests of the horizon's pure parts: footprints, distance bins, and a wall hiding what
//! lies behind it (but not what rises above it or stands in front of it).

use glam::{DVec2, DVec3};

use super::*;
use crate::bake::{bake, BakeParams};
use crate::dataset::Dataset;
use crate::Heightfield;

#[test]
fn footprint_of_a_square_east_of_the_eye() {
    let sq = [
        DVec2::new(10.0, -1.0),
        DVec2::new(12.0, -1.0),
        DVec2::new(12.0, 1.0),
        DVec2::new(10.0, 1.0),
    ];
    let fp = footprint(&sq).expect("eye outside");
    assert!((fp.d_near - 10.0).abs() < 1e-12);
    assert!((fp.d_far - (144.0f64 + 1.0).sqrt()).abs() < 1e-12);
    assert!((fp.az_lo + (1.0f64 / 10.0).atan()).abs() < 1e-12);
    assert!((fp.az_hi - (1.0f64 / 10.0).atan()).abs() < 1e-12);
    // Across the ±180° seam (west of the eye) the range stays contiguous.
    let west = sq.map(|p| -p);
    let fp = footprint(&west).expect("eye outside");
    assert!((fp.az_hi - fp.az_lo - 2.0 * (0.1f64).atan()).abs() < 1e-12);
    // A quad taken either way round, without a hull, gives the same footprint.
    let rev = [sq[3], sq[2], sq[1], sq[0]];
    assert_eq!(footprint_of_quad(&rev), footprint(&sq));
    assert_eq!(footprint_of_quad(&sq), footprint(&sq));
    // Holding the eye: no footprint.
    let around = sq.map(|p| p - DVec2::new(11.0, 0.0));
    assert!(footprint(&around).is_none());
}

#[test]
fn bins_bracket_distances() {
    for d in [8.0, 9.5, 100.0, 1234.5, 1e5, 3e6] {
        let b = bin_at_or_beyond(d).unwrap();
        assert!(bin_edge(b) >= d && (b == 0 || bin_edge(b - 1) < d), "{d}");
        let b = bin_at_or_before(d).unwrap();
        assert!(
            bin_edge(b) <= d && (b + 1 == BINS || bin_edge(b + 1) > d),
            "{d}"
        );
    }
    assert!(bin_at_or_before(7.9).is_none());
}

/// A 65×65 grid at 10 m: flat at 0 m with a wall 100 m high along x ∈ [280, 360] m.
fn wall_bake() -> ErrorBake {
    let n = 65usize;
    let mut h = vec![0.0f32; n * n];
    for y in 0..n {
        for x in 28..=36 {
            h[y * n + x] = 100.0;
        }
    }
    let hf = Heightfield {
        width: n,
        height: n,
        spacing_x: 10.0,
        spacing_y: 10.0,
        heights: h,
        geo: None,
        voids_filled: 0,
        spacing_note: String::new(),
    };
    let ds = Dataset::from_heightfield(hf, "wall".into());
    bake(
        &ds,
        BakeParams {
            tile_size: 5,
            levels: 0,
        },
        &|_, _| {},
    )
}

fn boxed(lo: DVec3, hi: DVec3) -> Aabb {
    Aabb { min: lo, max: hi }
}

#[test]
fn a_wall_hides_the_ground_behind_it_only() {
    let bake = wall_bake();
    let mut set = HorizonSet::default();
    let eye = DVec3::new(100.0, 320.0, 10.0);
    set.build(&bake, None, false, &[eye]);
    assert!(set.views[0].occluders > 0);
    // Ground behind the wall, low: hidden.
    assert!(set.hides(
        0,
        &boxed(DVec3::new(450.0, 300.0, 0.0), DVec3::new(490.0, 340.0, 5.0))
    ));
    // The same ground but rising above the wall's line of sight: seen.
    assert!(!set.hides(
        0,
        &boxed(
            DVec3::new(450.0, 300.0, 0.0),
            DVec3::new(490.0, 340.0, 200.0)
        )
    ));
    // Ground in front of the wall: seen.
    assert!(!set.hides(
        0,
        &boxed(DVec3::new(200.0, 300.0, 0.0), DVec3::new(240.0, 340.0, 5.0))
    ));
    // From high above, the wall hides nothing behind it.
    let mut high = HorizonSet::default();
    high.build(&bake, None, false, &[DVec3::new(100.0, 320.0, 500.0)]);
    assert!(!high.hides(
        0,
        &boxed(DVec3::new(450.0, 300.0, 0.0), DVec3::new(490.0, 340.0, 5.0))
    ));
}
