//! Geographic terrain on the WGS84 ellipsoid (issue 14), checked on the CPU against f64:
//! - every vertex of every node a real selection draws, computed with the vertex shader's f32
//!   arithmetic (`aerie::render::geo_instances::emulate_vertex`, the shader written again),
//!   lies within 0.05 m of its exact position relative to the eye (f64 ECEF − eye) over
//!   10°×10° regions at the equator, at 60°N and across the ±180° seam;
//! - a fixed terrain point's screen position through the f32 path (frame, offset, matrix)
//!   stays within 1/8 px of the f64 projection while the eye creeps towards it, at those places;
//! - drawn summits are as far apart as Karney's geodesics (geographiclib-rs) say.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::geo_instances::{emulate_vertex, GeoEye};
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::clipmap::{place_levels, ClipmapDesc};
use aerie::terrain::dataset::Dataset;
use aerie::terrain::gen::{generate, DemKind, GenParams};
use aerie::terrain::geodesy::{GeoGrid, Geodetic};
use aerie::terrain::load::geographic_spacing_m;
use aerie::terrain::select::{select_tiles, SelectParams, Selection};
use aerie::terrain::GeoReference;
use glam::{DVec2, DVec3, Vec3};

const M: u32 = 17;
const Q: u32 = M - 1;
const W: u32 = 1920;
const H: u32 = 1080;

/// splitmix64, so failures reproduce.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

struct GeoScene {
    ds: Dataset,
    bake: ErrorBake,
    clip: ClipmapDesc,
    grid: GeoGrid,
}

/// A 1025² geographic grid of `d`° steps whose south-west sample is at (lat, lon): 10.24° a
/// side at d = 0.01°; mountains up to a few kilometres.
fn geo_scene(lat: f64, lon: f64, d: f64) -> GeoScene {
    let n = 1025;
    let mut hf = generate(&GenParams {
        size: n,
        spacing: 1000.0,
        kind: DemKind::Ridged,
        seed: 5,
    });
    let (sx, sy) = geographic_spacing_m(lat + d * (n - 1) as f64 / 2.0, d, d);
    hf.spacing_x = sx;
    hf.spacing_y = sy;
    hf.geo = Some(GeoReference::Geographic {
        south_lat_deg: lat,
        west_lon_deg: lon,
        dlat_deg: d,
        dlon_deg: d,
    });
    scene_of(hf, format!("geo {lat},{lon}"))
}

/// A 1025² UTM grid of `spacing` metres whose south-west sample is at (easting, northing) in
/// `crs`; mountains up to a few kilometres.
fn utm_scene(crs: &str, easting: f64, northing: f64, spacing: f64) -> GeoScene {
    let mut hf = generate(&GenParams {
        size: 1025,
        spacing,
        kind: DemKind::Ridged,
        seed: 5,
    });
    hf.geo = Some(GeoReference::Projected {
        crs: crs.into(),
        easting,
        northing,
    });
    scene_of(hf, format!("{crs} {easting},{northing}"))
}

fn scene_of(hf: aerie::terrain::Heightfield, name: String) -> GeoScene {
    let (sx, sy) = (hf.spacing_x, hf.spacing_y);
    let ds = Dataset::from_heightfield(hf, name);
    let bake = bake(
        &ds,
        BakeParams {
            tile_size: M,
            levels: 0,
        },
        &|_, _| {},
    );
    let clip = ClipmapDesc {
        tile_quads: Q,
        patch_tiles: 8,
        margin_tiles: 2,
        width: ds.hf.width as u32,
        height: ds.hf.height as u32,
    };
    let extent = DVec2::from(ds.hf.extent_m());
    let grid = GeoGrid::of_projected(ds.hf.geo.as_ref(), sx, sy, extent)
        .expect("placed")
        .expect("on the ellipsoid");
    GeoScene {
        ds,
        bake,
        clip,
        grid,
    }
}

/// A camera `agl` metres above the ground at grid position `g`, attitude taken at that point.
fn camera_at(s: &GeoScene, g: DVec2, agl: f64, hpr: [f64; 3], fov_deg: f64) -> Camera {
    let hf = &s.ds.hf;
    let ground = hf.height_at_m(g.x, g.y);
    let (lat, lon) = s.grid.lat_lon_of_grid(g);
    let position = s
        .grid
        .world_of_geodetic(Geodetic::new(lat, lon, ground + agl));
    let attitude =
        Attitude::from_degrees(hpr[0], hpr[1], hpr[2]).in_frame(s.grid.local_enu_axes(lat, lon));
    Camera::new(
        position,
        attitude,
        Frustum::symmetric(fov_deg.to_radians(), W, H),
    )
}

fn select(s: &GeoScene, cam: &Camera) -> Selection {
    let eye = s.grid.grid_of_world(cam.position);
    let viewer = [eye.x / s.ds.hf.spacing_x, eye.y / s.ds.hf.spacing_y];
    let placements = place_levels(&s.clip, viewer);
    let params = SelectParams {
        tau_px: 1.0,
        max_refinement: 6,
        earth: Some(s.grid),
        ..SelectParams::default()
    };
    let mut sel = Selection::default();
    select_tiles(
        &s.bake,
        &s.clip,
        &placements,
        cam,
        (W, H),
        &params,
        &mut sel,
    );
    sel
}

/// The exact position of sample (col, row) at height h relative to the eye, world axes.
fn exact_rel(s: &GeoScene, cam: &Camera, col: f64, row: f64, h: f64) -> DVec3 {
    let eye = s.grid.world.enu_to_ecef(cam.position);
    s.grid.ecef_to_world_rotation() * (s.grid.ecef_of_sample(col, row, h) - eye)
}

#[derive(Default, Debug)]
struct Worst {
    near: f64,
    mid: f64,
    all: f64,
    /// Beyond 200 km: the error less the f32 rounding of the result itself (2^-23 of the
    /// distance covers half an ulp on each of three axes).
    excess: f64,
    vertices: u64,
    far_m: f64,
}

fn check_drawn_vertices(s: &GeoScene, cam: &Camera, worst: &mut Worst) {
    let sel = select(s, cam);
    assert_eq!(sel.unbounded, 0);
    assert!(
        !sel.items.is_empty(),
        "nothing drawn from {:?}",
        cam.position
    );
    let eye = GeoEye::new(&s.grid, cam.position);
    let hf = &s.ds.hf;
    for item in &sel.items {
        let step = 1u32 << item.node_level;
        let node = (Q as i64) << item.node_level;
        let origin = [item.node_tx as i64 * node, item.node_ty as i64 * node];
        let t = eye.node_fields(origin, step, Q);
        for j in 0..=Q as i32 {
            for i in 0..=Q as i32 {
                let col = origin[0] + (i as i64) * step as i64;
                let row = origin[1] + (j as i64) * step as i64;
                let h = hf.at(col as usize, row as usize);
                let got = emulate_vertex(&t, step, [i, j], Q as i32, h).as_dvec3();
                let want = exact_rel(s, cam, col as f64, row as f64, h as f64);
                let err = (got - want).length();
                let dist = want.length();
                if dist < 50_000.0 {
                    worst.near = worst.near.max(err);
                } else if dist < 200_000.0 {
                    worst.mid = worst.mid.max(err);
                }
                worst.all = worst.all.max(err);
                if dist >= 200_000.0 {
                    worst.excess = worst.excess.max(err - dist / (1u64 << 23) as f64);
                }
                worst.far_m = worst.far_m.max(dist);
                worst.vertices += 1;
            }
        }
    }
}

#[test]
fn drawn_vertices_are_within_5_cm_of_the_f64_ellipsoid_over_ten_degrees() {
    // The equator, 55–65°N, and 175°E–174.76°W across the seam.
    let regions = [(-5.0, 20.0), (55.0, 10.0), (-40.0, 175.0)];
    let mut rng = Rng(14);
    for (lat, lon) in regions {
        let s = geo_scene(lat, lon, 0.01);
        let (ex, ey) = s.ds.hf.extent_m();
        let mut worst = Worst::default();
        for k in 0..6 {
            // Anywhere in the region; the last cameras on the region's edge and its seam.
            let g = match k {
                4 => DVec2::new(ex * 0.5, ey * 0.02),
                5 => DVec2::new(ex * 0.49, ey * 0.97),
                _ => DVec2::new(rng.range(0.05, 0.95) * ex, rng.range(0.05, 0.95) * ey),
            };
            let agl = [300.0, 2_000.0, 9_000.0][k % 3];
            let hpr = [
                rng.range(0.0, 360.0),
                rng.range(-60.0, -3.0),
                rng.range(-20.0, 20.0),
            ];
            let cam = camera_at(&s, g, agl, hpr, 70.0);
            check_drawn_vertices(&s, &cam, &mut worst);
        }
        eprintln!("geodesy ({lat}, {lon}): {worst:?}");
        assert!(worst.vertices > 100_000, "{worst:?}");
        // 0.05 m wherever f32 can hold it; beyond 200 km the f32 result itself rounds by up
        // to 2^-24 of the distance per axis, which comes on top.
        assert!(worst.near <= 0.05, "({lat}, {lon}) within 50 km: {worst:?}");
        assert!(worst.mid <= 0.05, "({lat}, {lon}) within 200 km: {worst:?}");
        assert!(
            worst.excess <= 0.05,
            "({lat}, {lon}) beyond 200 km: {worst:?}"
        );
        assert!(worst.far_m > 300_000.0, "{worst:?}");
    }
}

/// UTM grids (123 km a side at 120 m) at a zone's western edge near 46.5° N — reaching 1.3°
/// past it — and in the middle of a southern zone: every drawn vertex through the shader's
/// projected branch (`emulate_vertex` on a projected node) within 0.05 m of the f64 ECEF − eye.
fn utm_scenes() -> [GeoScene; 2] {
    [
        utm_scene("EPSG:32632", 170_000.0, 5_150_000.0, 120.0),
        utm_scene("EPSG:32733", 440_000.0, 6_000_000.0, 120.0),
    ]
}

#[test]
fn drawn_utm_vertices_are_within_5_cm_of_the_f64_ellipsoid() {
    let mut rng = Rng(32);
    for s in utm_scenes() {
        let (ex, ey) = s.ds.hf.extent_m();
        let mut worst = Worst::default();
        for k in 0..6 {
            let g = match k {
                4 => DVec2::new(ex * 0.01, ey * 0.5),
                5 => DVec2::new(ex * 0.97, ey * 0.03),
                _ => DVec2::new(rng.range(0.05, 0.95) * ex, rng.range(0.05, 0.95) * ey),
            };
            let agl = [300.0, 2_000.0, 9_000.0][k % 3];
            // The cameras on the edges look inwards (east, north-west).
            let heading = match k {
                4 => 90.0,
                5 => 315.0,
                _ => rng.range(0.0, 360.0),
            };
            let hpr = [heading, rng.range(-60.0, -3.0), rng.range(-20.0, 20.0)];
            let cam = camera_at(&s, g, agl, hpr, 70.0);
            check_drawn_vertices(&s, &cam, &mut worst);
        }
        eprintln!("geodesy {}: {worst:?}", s.ds.source);
        assert!(worst.vertices > 20_000, "{worst:?}");
        assert!(worst.all <= 0.05, "{}: {worst:?}", s.ds.source);
        assert!(worst.far_m > 50_000.0, "{worst:?}");
    }
}

/// Pixel of a vertex through the f32 path: emulated shader position, the f32 camera-relative
/// matrix, the divide and the viewport.
fn shader_px(cam: &Camera, rel: Vec3) -> DVec2 {
    let clip = cam.relative_world_to_clip_f32() * rel.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    DVec2::new(
        ((ndc.x + 1.0) * 0.5 * W as f32) as f64,
        ((ndc.y + 1.0) * 0.5 * H as f32) as f64,
    )
}

#[test]
fn a_fixed_point_stays_within_an_eighth_of_a_pixel_at_the_equator_60n_the_seam_and_on_utm() {
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    let scenes = [(-5.0, 20.0), (55.0, 10.0), (-40.0, 175.0)]
        .map(|(lat, lon)| geo_scene(lat, lon, 0.01))
        .into_iter()
        .chain(utm_scenes());
    for s in scenes {
        let hf = &s.ds.hf;
        let name = &s.ds.source;
        // Terrain points near the region's middle, its north-east and on the seam (col 500
        // is 180° for the last region).
        for (col, row) in [(512usize, 512usize), (1000, 990), (500, 37)] {
            let h = hf.at(col, row);
            let target = s
                .grid
                .world
                .ecef_to_enu(s.grid.ecef_of_sample(col as f64, row as f64, h as f64));
            for (dist, step) in [(800.0, 1u32), (12_000.0, 16), (150_000.0, 64)] {
                // Eyes creeping towards the point by a non-dyadic step, looking at it.
                let (plat, plon) = s.grid.lat_lon_of_grid(DVec2::new(
                    col as f64 * hf.spacing_x,
                    row as f64 * hf.spacing_y,
                ));
                let enu = s.grid.local_enu_axes(plat, plon);
                for n in 0..40 {
                    let back = dist * (1.0 - 0.000_37 * n as f64);
                    let eye = target - enu.y_axis * back + enu.z_axis * (0.2 * back + 50.0);
                    let look = (target - eye).normalize();
                    // Heading/pitch of `look` in the local frame at the point.
                    let l = enu.transpose() * look;
                    let att = Attitude {
                        heading: l.x.atan2(l.y),
                        pitch: l.z.asin(),
                        roll: 0.1,
                    }
                    .in_frame(enu);
                    let cam = Camera::new(eye, att, Frustum::symmetric(40f64.to_radians(), W, H));
                    let Some((want, _)) = cam.project_px(target, W, H) else {
                        panic!("target behind the eye");
                    };
                    // The point drawn as a vertex of the node holding it at a level fit for
                    // the distance, at each of the node's positions (corner, middle).
                    for off in [0i64, (Q / 2) as i64, Q as i64] {
                        let span = (Q * step) as i64;
                        let ox = (col as i64 - off * step as i64).clamp(0, 1024 - span);
                        let oy = (row as i64 - off * step as i64).clamp(0, 1024 - span);
                        if (col as i64 - ox) % step as i64 != 0
                            || (row as i64 - oy) % step as i64 != 0
                        {
                            continue;
                        }
                        let ij = [
                            ((col as i64 - ox) / step as i64) as i32,
                            ((row as i64 - oy) / step as i64) as i32,
                        ];
                        let t = GeoEye::new(&s.grid, cam.position).node_fields([ox, oy], step, Q);
                        let got = shader_px(&cam, emulate_vertex(&t, step, ij, Q as i32, h));
                        let err = (got - want).length();
                        worst = worst.max(err);
                        checked += 1;
                        assert!(
                            err < 0.125,
                            "{name} sample ({col}, {row}) from {dist} m, node step {step}: {err} px"
                        );
                    }
                }
            }
        }
    }
    eprintln!("geodetic screen jitter: {checked} positions, worst {worst:.2e} px from f64");
    assert!(checked > 500, "{checked}");
}

/// A flat geographic dataset (height 0, a 500 m block at sample (800, 700)) over 55–65.24°N,
/// 10–20.24°E, and its pose mapping.
fn flat_geo() -> (
    aerie::terrain::Heightfield,
    aerie::sim::pose_input::GeoMapping,
) {
    let d = 0.01;
    let mut hf = aerie_tests::synthetic(1025, 1025, 1.0, 0.0, &[(798, 698, 802, 702, 500.0)]);
    let (sx, sy) = geographic_spacing_m(55.0 + 5.12, d, d);
    hf.spacing_x = sx;
    hf.spacing_y = sy;
    hf.geo = Some(GeoReference::Geographic {
        south_lat_deg: 55.0,
        west_lon_deg: 10.0,
        dlat_deg: d,
        dlon_deg: d,
    });
    let ds = Dataset::from_heightfield(hf.clone(), "flat geo".into());
    let geo = aerie::sim::pose_input::GeoMapping::of_dataset(&ds).expect("geographic");
    (hf, geo)
}

/// On the GPU (lavapipe): a geodetic pose 860 km from the dataset's origin looking straight
/// down sees the block under it at the range the altitudes give, and a level pose there sees a
/// level horizon at the dip the ellipsoid gives (the world frame's "level" would tilt it by
/// the turn of the normal between origin and aircraft, degrees).
#[test]
fn geodetic_pose_sees_the_ground_under_it_and_a_level_horizon_on_the_gpu() {
    const GW: u32 = 256;
    const GH: u32 = 144;
    let (hf, geo) = flat_geo();
    let fov = 40f64.to_radians();
    let pose = |lat: f64, lon: f64, alt: f64, hpr: [f64; 3]| {
        Camera::new(
            geo.to_world(lat, lon, alt),
            geo.attitude_at(lat, lon, Attitude::from_degrees(hpr[0], hpr[1], hpr[2])),
            Frustum::symmetric(fov, GW, GH),
        )
    };
    let nadir = pose(62.0, 18.0, 1000.0, [30.0, -90.0, 0.0]);
    let level = pose(60.0, 15.0, 3000.0, [0.0, 0.0, 0.0]);
    let frames = aerie_tests::render_frames(&aerie_tests::test_desc(GW, GH), &hf, &[nadir, level]);

    // Nadir: every pixel near the centre sees the block's top 500 m below.
    let f = &frames[0];
    for (px, py) in [
        (GW / 2, GH / 2),
        (GW / 2 - 20, GH / 2 + 10),
        (GW / 2 + 30, GH / 2 - 15),
    ] {
        let depth = f.depth[(py * GW + px) as usize] as f64;
        let ray = nadir.pixel_ray(px as f64 + 0.5, py as f64 + 0.5, GW, GH);
        // Range along the view axis to the plane 500 m below the eye, the block's top.
        let axis = nadir.attitude.body_to_world().x_axis;
        let t = 500.0 / ray.dot(-geo.grid().local_enu_axes(62.0, 18.0).z_axis);
        let z_view = t * ray.dot(axis);
        let want = nadir.near / z_view;
        assert!(
            (depth / want - 1.0).abs() < 0.01,
            "pixel ({px}, {py}): depth {depth} vs {want} (view depth {z_view} m)"
        );
    }

    // Level: the first ground row of each column (sky has depth 0).
    let f = &frames[1];
    let horizon_row = |px: u32| (0..GH).find(|&py| f.depth[(py * GW + px) as usize] > 0.0);
    let rows: Vec<u32> = [8, GW / 2, GW - 9]
        .iter()
        .map(|&px| horizon_row(px).expect("ground in the column"))
        .collect();
    assert!(
        rows[0].abs_diff(rows[2]) <= 1,
        "horizon not level: rows {rows:?} across the screen"
    );
    // Dip below the local horizontal: acos(R / (R + h)) with R the radius at 60°N.
    let r = 6_384_000.0f64;
    let dip = (r / (r + 3000.0)).acos();
    let (_, fy) = level.frustum.focal_px(GW, GH);
    let want = GH as f64 / 2.0 + dip.tan() * fy;
    assert!(
        (rows[1] as f64 - want).abs() <= 2.0,
        "horizon at row {} vs {want:.1} (dip {:.2}°)",
        rows[1],
        dip.to_degrees()
    );
}

/// Drawn positions (the vertex shader's f32 arithmetic, [`emulate_vertex`]) of `samples`
/// (col, row, height) relative to an eye over the scene's middle, f64.
fn drawn(s: &GeoScene, samples: &[(i64, i64, f32)]) -> Vec<DVec3> {
    let (ex, ey) = s.ds.hf.extent_m();
    let cam = camera_at(
        s,
        DVec2::new(ex / 2.0, ey / 2.0),
        3000.0,
        [0.0, -30.0, 0.0],
        60.0,
    );
    let eye = GeoEye::new(&s.grid, cam.position);
    let q = Q as i64;
    samples
        .iter()
        .map(|&(col, row, h)| {
            let origin = [col.div_euclid(q) * q, row.div_euclid(q) * q];
            let t = eye.node_fields(origin, 1, Q);
            let ij = [(col - origin[0]) as i32, (row - origin[1]) as i32];
            emulate_vertex(&t, 1, ij, Q as i32, h).as_dvec3()
        })
        .collect()
}

/// What two points at heights `h1`, `h2` above the ellipsoid are apart in space when
/// Karney's geodesic between their feet is `s12` long with azimuth `azi_deg` at mid-latitude
/// `lat_deg`: the chord of the normal section's radius of curvature R_α (Euler:
/// 1/R_α = cos²α/M + sin²α/N), lifted by the heights as on a sphere of that radius. Against
/// the exact ellipsoid this errs by a few millimetres at 10 km and under 2 m at 500 km.
fn spatial_distance(s12: f64, azi_deg: f64, lat_deg: f64, h1: f64, h2: f64) -> f64 {
    const A: f64 = 6_378_137.0;
    const F: f64 = 1.0 / 298.257_223_563;
    let e2 = F * (2.0 - F);
    let sl = lat_deg.to_radians().sin();
    let w = (1.0 - e2 * sl * sl).sqrt();
    let m = A * (1.0 - e2) / (w * w * w);
    let n = A / w;
    let (sa, ca) = azi_deg.to_radians().sin_cos();
    let r = 1.0 / (ca * ca / m + sa * sa / n);
    let chord = 2.0 * r * (s12 / (2.0 * r)).sin();
    ((h1 - h2).powi(2) + chord * chord * (1.0 + h1 / r) * (1.0 + h2 / r)).sqrt()
}

/// Distances between drawn points against geodesics computed independently of aerie's
/// geodesy (Karney's method, geographiclib-rs): the highest sample of each 100 × 100 block of
/// the real SRTM tile N47E011 (summits 2–3.5 km high), every pair 7–13 km apart, within 1 m;
/// points 480–520 km apart on a generated 10° region, within 0.01 %. The geodesic knows
/// only the samples' latitudes and longitudes (south-west corner + index · step).
#[test]
fn drawn_summits_are_as_far_apart_as_karneys_geodesics_say() {
    use geographiclib_rs::{Geodesic, InverseGeodesic};
    let g = Geodesic::wgs84();
    let hf = aerie::terrain::load::load_dem(&aerie_tests::demo_dem()).expect("demo DEM");
    let Some(GeoReference::Geographic {
        south_lat_deg,
        west_lon_deg,
        dlat_deg,
        dlon_deg,
    }) = hf.geo.clone()
    else {
        panic!("SRTM is geographic");
    };
    let (w, h) = (hf.width, hf.height);
    let s = scene_of(hf, "N47E011".into());
    let mut summits = Vec::new();
    for by in (0..h - 1).step_by(100) {
        for bx in (0..w - 1).step_by(100) {
            let best = (by..(by + 100).min(h))
                .flat_map(|r| (bx..(bx + 100).min(w)).map(move |c| (c, r)))
                .max_by(|a, b| s.ds.hf.at(a.0, a.1).total_cmp(&s.ds.hf.at(b.0, b.1)))
                .unwrap();
            summits.push((best.0 as i64, best.1 as i64, s.ds.hf.at(best.0, best.1)));
        }
    }
    let at = |c: i64, r: i64| {
        (
            south_lat_deg + r as f64 * dlat_deg,
            west_lon_deg + c as f64 * dlon_deg,
        )
    };
    let pos = drawn(&s, &summits);
    let (mut pairs, mut worst) = (0, 0.0f64);
    for i in 0..summits.len() {
        for j in i + 1..summits.len() {
            let ((la, lo), (lb, lob)) = (
                at(summits[i].0, summits[i].1),
                at(summits[j].0, summits[j].1),
            );
            let (s12, azi1, azi2, _): (f64, f64, f64, f64) = g.inverse(la, lo, lb, lob);
            if !(7_000.0..=13_000.0).contains(&s12) {
                continue;
            }
            let want = spatial_distance(
                s12,
                (azi1 + azi2) / 2.0,
                (la + lb) / 2.0,
                summits[i].2 as f64,
                summits[j].2 as f64,
            );
            let got = (pos[i] - pos[j]).length();
            worst = worst.max((got - want).abs());
            pairs += 1;
        }
    }
    eprintln!("N47E011: {pairs} summit pairs 7–13 km apart, worst {worst:.3} m");
    assert!(pairs > 200, "{pairs} pairs");
    assert!(worst < 1.0, "worst {worst} m");

    let d = 0.01;
    let s = geo_scene(40.0, -3.0, d);
    let pts: Vec<(i64, i64, f32)> = [
        (40, 40),
        (600, 40),
        (40, 500),
        (470, 470),
        (980, 60),
        (60, 980),
        (900, 900),
        (500, 500),
    ]
    .iter()
    .map(|&(c, r)| (c, r, 0.0))
    .collect();
    let pos = drawn(&s, &pts);
    let (mut pairs, mut worst) = (0, 0.0f64);
    for i in 0..pts.len() {
        for j in i + 1..pts.len() {
            let (la, lo) = (40.0 + pts[i].1 as f64 * d, -3.0 + pts[i].0 as f64 * d);
            let (lb, lob) = (40.0 + pts[j].1 as f64 * d, -3.0 + pts[j].0 as f64 * d);
            let (s12, azi1, azi2, _): (f64, f64, f64, f64) = g.inverse(la, lo, lb, lob);
            if !(480_000.0..=520_000.0).contains(&s12) {
                continue;
            }
            let want = spatial_distance(s12, (azi1 + azi2) / 2.0, (la + lb) / 2.0, 0.0, 0.0);
            let got = (pos[i] - pos[j]).length();
            worst = worst.max((got - want).abs() / want);
            pairs += 1;
        }
    }
    eprintln!(
        "10° region: {pairs} pairs 480–520 km apart, worst {:.5} %",
        worst * 100.0
    );
    assert!(pairs >= 3, "{pairs} pairs");
    assert!(worst < 1e-4, "worst {:.5} %", worst * 100.0);
}
