//! The full look on the ellipsoid (lavapipe, validation on): on a geographic grid whose test
//! landscape lies 600 km east of the dataset's south-west corner — where world z is tilted
//! 5.4° from the local up and lies some 28 km below the eye's height — the land-cover classes
//! the shader draws are the CPU rules' classes for the local slope and aspect, and the aerial
//! perspective is the CPU transmittance for the eye's height above the ellipsoid
//! (`tests/tests/look.rs` checks the same near a flat dataset's origin).

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::{Lighting, Look};
use aerie::render::landcover::{class_colour_srgb, class_weights, dominant, Class, CoverInputs};
use aerie::terrain::geodesy::{GeoGrid, Geodetic};
use aerie::terrain::load::geographic_spacing_m;
use aerie::terrain::{GeoReference, Heightfield};
use aerie_tests::*;

const W: u32 = 256;
const H: u32 = 144;
const SOUTH: f64 = 47.0;
const WEST: f64 = 5.0;
const DLAT: f64 = 0.003;
const DLON: f64 = 0.0044;
/// Samples a side (about 333 m apart); the landscape starts at column C0, 600 km east of the
/// corner.
const COLS: usize = 2049;
const ROWS: usize = 2049;
const C0: usize = 1800;
/// The landscape's south half is the rows below this one.
const SPLIT: usize = 128;
const WGS84_A: f64 = 6_378_137.0;
const WGS84_E2: f64 = 6.694_379_990_14e-3;

/// East-west spacing in metres at a row (the parallel's radius times the longitude step).
fn east_m(row: usize) -> f64 {
    let phi = (SOUTH + row as f64 * DLAT).to_radians();
    WGS84_A * phi.cos() / (1.0 - WGS84_E2 * phi.sin().powi(2)).sqrt() * DLON.to_radians()
}

/// look.rs's landscape made wide enough for 333 m samples, east of C0, by distance east in
/// metres. South half: sea at 0 m, a plain at 400 m, a 45° wall up to a plateau at 3500 m.
/// North half: a plain at 200 m, a 20° slope rising east to 1800 m, then a pasture at 1800 m.
/// West of C0: a plain at 1000 m for the fog.
fn height(col: usize, row: usize) -> f32 {
    if col < C0 {
        return 1000.0;
    }
    let x = (col - C0) as f64 * east_m(row);
    let h = if row < SPLIT {
        match x {
            x if x < 10_000.0 => 0.0,
            x if x < 20_000.0 => 400.0,
            x if x < 23_100.0 => 400.0 + (x - 20_000.0),
            _ => 3500.0,
        }
    } else {
        let rise = (x - 5000.0).max(0.0) * 20f64.to_radians().tan();
        (200.0 + rise).min(1800.0)
    };
    h as f32
}

/// The local normal (east, north, up) at an interior sample, from the heights' central
/// differences over the sample spacings there.
fn local_normal(col: usize, row: usize) -> [f32; 3] {
    let gx = (height(col + 1, row) - height(col - 1, row)) as f64 / (2.0 * east_m(row));
    let gy = (height(col, row + 1) - height(col, row - 1)) as f64 / (2.0 * 333.6);
    let len = (gx * gx + gy * gy + 1.0).sqrt();
    [(-gx / len) as f32, (-gy / len) as f32, (1.0 / len) as f32]
}

fn strip() -> (Heightfield, GeoGrid) {
    let mut hf = synthetic(COLS, ROWS, 1.0, 0.0, &[]);
    let (sx, sy) = geographic_spacing_m(SOUTH + DLAT * ROWS as f64 / 2.0, DLAT, DLON);
    hf.spacing_x = sx;
    hf.spacing_y = sy;
    for row in 0..ROWS {
        for col in 0..COLS {
            hf.heights[row * COLS + col] = height(col, row);
        }
    }
    hf.geo = Some(GeoReference::Geographic {
        south_lat_deg: SOUTH,
        west_lon_deg: WEST,
        dlat_deg: DLAT,
        dlon_deg: DLON,
    });
    let grid = GeoGrid::of(hf.geo.as_ref(), sx, sy).expect("geographic");
    (hf, grid)
}

fn lat_lon(col: f64, row: f64) -> (f64, f64) {
    (SOUTH + row * DLAT, WEST + col * DLON)
}

/// A camera at (col, row) and height h, attitude taken in the local frame there.
fn camera(grid: &GeoGrid, at: [f64; 3], hpr: [f64; 3], fov_deg: f64) -> Camera {
    let (lat, lon) = lat_lon(at[0], at[1]);
    Camera::new(
        grid.world_of_geodetic(Geodetic::new(lat, lon, at[2])),
        Attitude::from_degrees(hpr[0], hpr[1], hpr[2]).in_frame(grid.local_enu_axes(lat, lon)),
        Frustum::symmetric(fov_deg.to_radians(), W, H),
    )
}

fn srgb8_from_linear(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

#[test]
fn classes_and_fog_600_km_from_the_corner_match_the_cpu_twins() {
    let (hf, grid) = strip();
    let mut desc = test_desc(W, H);
    desc.look = Look::Classes;
    let (ds, b) = prepare(&desc, &hf);

    // Classes: straight down from 40 km over the landscape's middle.
    let mid = C0 as f64 + 22_000.0 / east_m(SPLIT);
    let cam = camera(
        &grid,
        [mid, SPLIT as f64, 40_000.0],
        [0.0, -90.0, 0.0],
        75.0,
    );
    let f = &render_lit(&desc, &ds, &b, &[(cam, Lighting::default())])[0];
    // look.rs's classes (x metres east of C0, row), each in the middle of its region.
    let points = [
        (5000.0, 100, Class::Water),
        (15_000.0, 100, Class::Crops),
        (21_550.0, 100, Class::Rock),
        (38_000.0, 100, Class::Snow),
        (7200.0, 156, Class::Forest),
        (38_000.0, 156, Class::Grass),
    ];
    for (x, row, want) in points {
        let col = C0 + (x / east_m(row)).round() as usize;
        let h = height(col, row);
        let n = local_normal(col, row);
        let at = |jitter| {
            class_weights(&CoverInputs {
                height_m: h,
                normal: n,
                jitter,
            })
        };
        let w = at(0.0);
        assert_eq!(dominant(&w), want, "rules at ({col}, {row})");
        assert_eq!(at(-1.0), w, "jitter changes the class at ({col}, {row})");
        assert_eq!(at(1.0), w, "jitter changes the class at ({col}, {row})");
        let expected = class_colour_srgb(&w).map(|c| (c * 255.0).round() as u8);
        let (lat, lon) = lat_lon(col as f64, row as f64);
        let p = grid.world_of_geodetic(Geodetic::new(lat, lon, h as f64));
        let (px, _) = cam.project_px(p, W, H).expect("in front of the camera");
        let (x, y) = (px.x as u32, px.y as u32);
        assert!(x < W && y < H, "({col}, {row}) projects off screen: {px}");
        assert!(f.depth[(y * W + x) as usize] > 0.0, "no terrain at {x},{y}");
        let got = &f.rgba[((y * W + x) * 4) as usize..][..3];
        for c in 0..3 {
            assert!(
                got[c].abs_diff(expected[c]) <= 2,
                "{want:?} at ({col}, {row}) → pixel {x},{y}: {got:?}, rules say {expected:?}"
            );
        }
        eprintln!("{want:?} at ({col}, {row}): pixel {got:?}, rules {expected:?}");
    }

    // Fog: over the 1000 m plain west of the landscape, 30 m up, looking west to the horizon
    // and down at the ground, in a 2 km visibility. Each drawn point's distance and height
    // come from the depth buffer.
    desc.look = Look::Full;
    let eye = [C0 as f64 - 400.0, SPLIT as f64, 1030.0];
    let horizon = camera(&grid, eye, [270.0, 0.0, 0.0], 20.0);
    let ground = camera(&grid, eye, [270.0, -30.0, 0.0], 60.0);
    let light = Lighting::from_host(None, Some(2_000.0));
    let frames = render_lit(&desc, &ds, &b, &[(horizon, light), (ground, light)]);
    let atmos = light.atmosphere();
    let (mut far, mut near, mut worst) = (0, 0, 0.0f32);
    for (cam, f) in [horizon, ground].iter().zip(&frames) {
        let axis = cam.attitude.body_to_world().x_axis;
        for y in 0..H {
            for x in 0..W {
                let i = (y * W + x) as usize;
                if f.depth[i] == 0.0 {
                    continue;
                }
                let dir = cam.pixel_ray(x as f64 + 0.5, y as f64 + 0.5, W, H);
                let z_view = cam.near / f.depth[i] as f64;
                let dist = z_view / dir.normalize().dot(axis);
                let point = cam.position + dir.normalize() * dist;
                let point_h = grid.geodetic_of_world(point).alt_m;
                let tr = atmos.transmittance(1030.0, point_h as f32, dist as f32);
                let sky = atmos
                    .sky_radiance([dir.x as f32, dir.y as f32, dir.z as f32])
                    .map(srgb8_from_linear);
                let got = &f.rgba[i * 4..][..3];
                let diff = (0..3).map(|c| got[c].abs_diff(sky[c])).max().unwrap();
                let allowed = 3.0 + 255.0 * tr;
                worst = worst.max(f32::from(diff) - allowed);
                assert!(
                    f32::from(diff) <= allowed,
                    "pixel {x},{y} at {dist:.0} m, {point_h:.0} m (T = {tr:.3}): {got:?} vs sky {sky:?}"
                );
                if tr < 0.01 {
                    far += 1;
                } else if tr > 0.9 {
                    assert!(diff > 20, "pixel {x},{y} at {dist:.0} m looks like the sky");
                    near += 1;
                }
            }
        }
    }
    eprintln!("fog: {far} far pixels at the sky's colour, {near} near ones their own");
    assert!(far > 200 && near > 200, "far {far}, near {near}");
}
