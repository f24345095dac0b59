//! A UTM grid drawn on the ellipsoid by the GPU (lavapipe, validation on): near a zone's
//! western edge, 60 km from the dataset's south-west corner — where the grid's axes are turned
//! about 2° from true north and its metres are 0.04 % long, so a grid drawn flat would put the
//! ground kilometres away — a nadir camera placed over a sample through the projection sees,
//! at the screen centre (from the depth buffer), that very sample at its exact distance.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::terrain::geodesy::{GeoGrid, Geodetic};
use aerie::terrain::GeoReference;
use aerie_tests::*;
use glam::DVec2;

const W: u32 = 256;
const H: u32 = 144;
const N: usize = 1025;
const SPACING: f64 = 90.0;

/// A ramp rising 10 % east and 5 % north (so a wrong place reads as a wrong height).
fn height(col: usize, row: usize) -> f32 {
    (200.0 + 0.1 * col as f64 * SPACING + 0.05 * row as f64 * SPACING) as f32
}

#[test]
fn a_nadir_camera_over_a_utm_sample_sees_it_at_the_screen_centre() {
    let mut hf = synthetic(N, N, SPACING, 0.0, &[]);
    for row in 0..N {
        for col in 0..N {
            hf.heights[row * N + col] = height(col, row);
        }
    }
    // Zone 32N from 4.7° E (1.3° west of the zone's edge) at 46.5° N.
    hf.geo = Some(GeoReference::Projected {
        crs: "EPSG:32632".into(),
        easting: 170_000.0,
        northing: 5_150_000.0,
    });
    let grid = GeoGrid::of(hf.geo.as_ref(), SPACING, SPACING).expect("UTM on the ellipsoid");
    let desc = test_desc(W, H);
    let (ds, b) = prepare(&desc, &hf);
    let mut cams = Vec::new();
    let targets = [(700usize, 600usize, 2_000.0), (300, 900, 800.0)];
    for (col, row, agl) in targets {
        let g = DVec2::new(col as f64 * SPACING, row as f64 * SPACING);
        let (lat, lon) = grid.lat_lon_of_grid(g);
        let h = height(col, row) as f64;
        cams.push(Camera::new(
            grid.world_of_geodetic(Geodetic::new(lat, lon, h + agl)),
            Attitude::from_degrees(0.0, -90.0, 0.0).in_frame(grid.local_enu_axes(lat, lon)),
            Frustum::symmetric(50f64.to_radians(), W, H),
        ));
    }
    let frames = render_dataset(&desc, ds, b, &cams);
    for ((col, row, agl), (cam, f)) in targets.iter().zip(cams.iter().zip(&frames)) {
        // The centre lies between four pixels: average their reconstructed points.
        let mut sum = glam::DVec3::ZERO;
        for (x, y) in [
            (W / 2 - 1, H / 2 - 1),
            (W / 2, H / 2 - 1),
            (W / 2 - 1, H / 2),
            (W / 2, H / 2),
        ] {
            let i = (y * W + x) as usize;
            assert!(
                f.depth[i] > 0.0,
                "no terrain under the camera at ({col}, {row})"
            );
            let dir = cam
                .pixel_ray(x as f64 + 0.5, y as f64 + 0.5, W, H)
                .normalize();
            let z_view = cam.near / f.depth[i] as f64;
            let axis = cam.attitude.body_to_world().x_axis;
            sum += cam.position + dir * (z_view / dir.dot(axis));
        }
        let hit = sum / 4.0;
        let range = (hit - cam.position).length();
        let g = grid.grid_of_world(hit);
        let want = DVec2::new(*col as f64 * SPACING, *row as f64 * SPACING);
        eprintln!(
            "UTM nadir over ({col}, {row}): range {range:.2} m (want {agl}), hit {:.2} m from the sample",
            (g.truncate() - want).length()
        );
        assert!((range - agl).abs() < 2.0, "range {range} vs {agl}");
        assert!(
            (g.truncate() - want).length() < 15.0,
            "hit {g:?} vs {want:?}"
        );
    }
}
