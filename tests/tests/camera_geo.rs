//! Geodetic cameras on the command line (issue 14, item 6), end to end through the `aerie`
//! binary on lavapipe (debug builds run the validation layer; a message fails the command): `render --camera-geo` puts the eye at the
//! given latitude, longitude and altitude, and `centre_hit` (read back from the depth buffer)
//! is the ground under a nadir view — its height the full-resolution surface's there, as the
//! CPU height-of-terrain query answers it; `fly --path` with a `geo` file flies the poses
//! the f64 geodesy places; datasets without a geo-reference are refused naming the flag.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use aerie::sim::pose_input::GeoMapping;
use aerie::terrain::load::load_dem;
use aerie::terrain::query::{height_of_terrain, InMemorySource, Lookup};
use aerie_tests::*;

fn run(args: &[&str]) -> Output {
    let out = Command::new(aerie_bin())
        .args(args)
        .output()
        .expect("run aerie");
    out
}

fn ok(args: &[&str]) -> String {
    let out = run(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "aerie {args:?} failed:\n{err}");
    err
}

/// The demo tile copied into `dir` (the CLI writes its bake next to the dataset).
fn demo_copy(dir: &Path) -> PathBuf {
    let dem = dir.join("N47E011.hgt.zip");
    std::fs::copy(demo_dem(), &dem).expect("copy the demo DEM");
    dem
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

/// Metres between two nearby geodetic points (local sphere; the test distances are < 1 km).
fn ground_distance_m(lat0: f64, lon0: f64, lat1: f64, lon1: f64) -> f64 {
    let r = 6_371_000.0;
    let dn = (lat1 - lat0).to_radians() * r;
    let de = (lon1 - lon0).to_radians() * r * lat0.to_radians().cos();
    dn.hypot(de)
}

#[test]
fn a_geodetic_nadir_camera_sees_the_full_resolution_ground_under_it_at_the_centre() {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_copy(dir.path());
    let hf = load_dem(&dem).expect("demo DEM loads");
    let desc = test_desc(64, 64);
    let (ds, bake) = prepare(&desc, &hf);
    let mapping = GeoMapping::of_dataset(&ds).expect("SRTM is geographic");
    let src = InMemorySource::new(ds, bake).expect("queries");
    // Near the origin (the south-west sample), in the middle, and near the far corner, where a
    // plane tangent at the origin would be hundreds of metres off.
    for (k, (lat, lon, alt)) in [
        (47.05, 11.07, 4200.0),
        (47.27, 11.39, 3200.0),
        (47.93, 11.91, 3000.0),
    ]
    .into_iter()
    .enumerate()
    {
        let (w, h) = (192u32, 128u32);
        let out = dir.path().join(format!("nadir_{k}.png"));
        let cam = format!("{lat},{lon},{alt},30,-90,0");
        ok(&[
            "render",
            "--dem",
            dem.to_str().unwrap(),
            "--camera-geo",
            &cam,
            "--lod",
            "full",
            "--fov",
            "60",
            "--size",
            &format!("{w}x{h}"),
            "--out",
            out.to_str().unwrap(),
        ]);
        let summary = json(&out.with_file_name(format!("nadir_{k}.png.json")));
        let c = &summary["camera"];
        assert!((num(c, "lat") - lat).abs() < 1e-9, "{c}");
        assert!((num(c, "lon") - lon).abs() < 1e-9, "{c}");
        assert!((num(c, "alt") - alt).abs() < 1e-6, "{c}");
        let hit = &summary["centre_hit"];
        assert!(hit.is_object(), "nadir view of the ground: {summary}");
        let (hlat, hlon, hh) = (num(hit, "lat"), num(hit, "lon"), num(hit, "height"));
        let range = num(hit, "range_m");
        // The centre pixel's centre is half a pixel off the optical axis on both axes: within
        // one pixel's footprint of the point under the eye (the default 60° horizontal field
        // of view spans 2·tan 30° · range over the width).
        let pixel_m = 2.0 * 30f64.to_radians().tan() * range / f64::from(w);
        let off = ground_distance_m(lat, lon, hlat, hlon);
        eprintln!(
            "view {k} ({lat}, {lon}): centre hit {off:.2} m from nadir (pixel {pixel_m:.2} m), \
             drawn height {hh:.3} m"
        );
        assert!(
            off < pixel_m,
            "view {k}: hit {off:.2} m from nadir, pixel {pixel_m:.2} m"
        );
        // The drawn surface is the level-0 surface (`--lod full`): the read-back point lies on
        // it, as the CPU query at that latitude and longitude says.
        let g = mapping.to_local(hlat, hlon, 0.0);
        let Lookup::Ready(ground) = height_of_terrain(&src, g.x, g.y) else {
            panic!("no ground at {hlat}, {hlon}");
        };
        assert!(
            (hh - ground.height_m).abs() < 0.3,
            "view {k}: drawn {hh:.3} m, surface {:.3} m",
            ground.height_m
        );
        // Nadir: the range is the height above that ground, along the normal.
        assert!(
            (range - (alt - hh)).abs() < 0.5 + pixel_m * 0.05,
            "view {k}: range {range:.2} m, height above {:.2} m",
            alt - hh
        );
    }
}

#[test]
fn sky_has_no_centre_hit_and_datasets_without_a_geo_reference_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_copy(dir.path());
    let out = dir.path().join("sky.png");
    ok(&[
        "render",
        "--dem",
        dem.to_str().unwrap(),
        "--camera-geo",
        "47.3,11.4,4000,0,45,0",
        "--size",
        "48x32",
        "--out",
        out.to_str().unwrap(),
    ]);
    let summary = json(&dir.path().join("sky.png.json"));
    assert!(summary["centre_hit"].is_null(), "{summary}");

    let local = dir.path().join("gen.f32");
    ok(&[
        "gen-dem",
        "--size",
        "65",
        "--kind",
        "flat",
        "--out",
        local.to_str().unwrap(),
    ]);
    let out = run(&[
        "render",
        "--dem",
        local.to_str().unwrap(),
        "--camera-geo",
        "47.3,11.4,4000,0,-45,0",
        "--size",
        "48x32",
        "--out",
        dir.path().join("x.png").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--camera-geo") && err.contains("geo-reference"),
        "{err}"
    );
    // Both kinds of camera at once, or a latitude past the pole: refused before any work.
    for (args, says) in [
        (
            vec!["--camera", "1,2,3,0,0,0", "--camera-geo", "47,11,3,0,0,0"],
            "cannot be used",
        ),
        (vec!["--camera-geo", "95,11,3000,0,0,0"], "lat"),
    ] {
        let mut all = vec![
            "render",
            "--dem",
            dem.to_str().unwrap(),
            "--out",
            "unused.png",
        ];
        all.extend(args);
        let out = run(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(says), "{err}");
    }
    // A geo waypoint file on that dataset: refused naming --path.
    let path = dir.path().join("geo.csv");
    std::fs::write(
        &path,
        "geo\n0,47.3,11.4,3000,0,-10,0\n1,47.31,11.4,3000,0,-10,0\n",
    )
    .unwrap();
    let out = run(&[
        "fly",
        "--dem",
        local.to_str().unwrap(),
        "--path",
        path.to_str().unwrap(),
        "--frames",
        "2",
        "--size",
        "32x32",
        "--out",
        dir.path().join("fly").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--path") && err.contains("geo-referenced"),
        "{err}"
    );
}

#[test]
fn a_geo_waypoint_file_flies_the_poses_the_geodesy_places_across_the_tile() {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_copy(dir.path());
    let hf = load_dem(&dem).expect("demo DEM loads");
    let (ds, _) = prepare(&test_desc(32, 32), &hf);
    let mapping = GeoMapping::of_dataset(&ds).unwrap();
    // A 60 km leg from the south-west to the north-east of the tile, climbing, turning.
    let path = dir.path().join("leg.csv");
    std::fs::write(
        &path,
        "# a geo leg\ngeo\n0,47.1,11.1,3500,45,-10,0\n4,47.5,11.6,3900,60,-5,10\n",
    )
    .unwrap();
    let out = dir.path().join("fly");
    ok(&[
        "fly",
        "--dem",
        dem.to_str().unwrap(),
        "--path",
        path.to_str().unwrap(),
        "--frames",
        "5",
        "--fps",
        "1",
        "--every",
        "100",
        "--size",
        "48x32",
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut rows = 0;
    for line in csv.lines().skip(1) {
        let v: Vec<f64> = line
            .split(',')
            .take(7)
            .map(|x| x.parse().unwrap())
            .collect();
        let t = v[0];
        let s = t / 4.0;
        let (lat, lon, alt) = (47.1 + 0.4 * s, 11.1 + 0.5 * s, 3500.0 + 400.0 * s);
        let want = mapping.to_world(lat, lon, alt);
        // frames.csv keeps centimetres.
        let got = glam::DVec3::new(v[1], v[2], v[3]);
        assert!((got - want).length() < 0.02, "t {t}: {got:?} vs {want:?}");
        let att = mapping.attitude_at(
            lat,
            lon,
            aerie::camera::Attitude::from_degrees(45.0 + 15.0 * s, -10.0 + 5.0 * s, 10.0 * s),
        );
        assert!(
            (v[4] - att.heading.to_degrees()).abs() < 2e-3
                && (v[5] - att.pitch.to_degrees()).abs() < 2e-3
                && (v[6] - att.roll.to_degrees()).abs() < 2e-3,
            "t {t}: {v:?} vs {att:?}"
        );
        rows += 1;
    }
    assert_eq!(rows, 5);
}
