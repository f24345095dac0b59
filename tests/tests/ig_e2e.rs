//! `aerie run --headless` as an image generator, driven by a CIGI 3.3 host written with the
//! project's own codec (the CIGI Class Library host is in `cigi_host.rs`): the Database Number
//! switches datasets through the `[databases]` table (Start of Frame says 1, then −2 while
//! database 2 loads, then 2), HOT answers come from the dataset drawn (the oracle: the terrain
//! crate's query service on the same file, then exactly the flat database's height), and the
//! host's Celestial Sphere and Atmosphere Controls set the frame's sun and haze.

use std::net::UdpSocket;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

use aerie::sim::pose_input::GeoMapping;
use aerie::sim::terrain_queries::DatasetQueries;
use aerie_sim_bridge::codec::cigi::{
    decode_ig_message, AtmosphereControl, CelestialSphereControl, CigiResponse, CigiVersion,
    CoordinateSystem, EntityControl, HatHotRequest, HatHotRequestType, IgControl,
};
use aerie_sim_bridge::codec::ByteOrder;
use aerie_sim_bridge::ig::environment::{sun_direction_enu, Celestial};
use aerie_sim_bridge::query::TerrainQueries;
use aerie_sim_bridge::PosePosition;
use aerie_terrain::bake::{bake, BakeParams};
use aerie_terrain::dataset::load_dataset;
use aerie_terrain::query::InMemorySource;
use aerie_tests::aerie_bin;

const LAT: f64 = 47.3;
const LON: f64 = 11.4;
const ALT: f64 = 4000.0;
const FLAT_M: i16 = 1000;

/// An SRTM3 tile named like the demo's, every sample at `FLAT_M`: the same geo-reference, a
/// different ground.
fn write_flat_tile(path: &Path) {
    let mut bytes = Vec::with_capacity(1201 * 1201 * 2);
    for _ in 0..1201 * 1201 {
        bytes.extend_from_slice(&FLAT_M.to_be_bytes());
    }
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, bytes).unwrap();
}

/// HOT at (LAT, LON) on `dem`, by the query service on the full-resolution surface.
fn oracle_hot(dem: &Path) -> f64 {
    let ds = Arc::new(load_dataset(dem).unwrap());
    let params = BakeParams {
        tile_size: aerie::render::frame::DEFAULT_TILE_SIZE,
        levels: 0,
    };
    let b = Arc::new(bake(&ds, params, &|_, _| {}));
    let geo = GeoMapping::of_dataset(&ds).unwrap();
    let q = DatasetQueries::new(InMemorySource::new(ds, b).unwrap(), Some(geo));
    q.height_of_terrain(&PosePosition::Geodetic {
        lat_deg: LAT,
        lon_deg: LON,
        alt_m: ALT,
    })
    .ready()
    .expect("the demo tile has terrain there")
    .height_m
}

fn spawn(bin: &Path, args: &[String]) -> Child {
    Command::new(bin)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("spawn {}: {e}", bin.display()))
}

/// One host message: IG Control (database `db`), the ownship, and what `extra` adds.
fn message(frame: u32, db: i8, extra: &[Vec<u8>]) -> Vec<u8> {
    let order = ByteOrder::Big;
    let mut m = IgControl {
        database: db,
        ig_mode: 1,
        minor_version: 3,
        host_frame: frame,
        ..IgControl::default()
    }
    .encode_as(CigiVersion::V3_3, order);
    m.extend_from_slice(
        &EntityControl {
            entity_id: 0,
            entity_state: 1,
            lat_deg: LAT,
            lon_deg: LON,
            alt_m: ALT,
            yaw_deg: 45.0,
            pitch_deg: -10.0,
            ..EntityControl::default()
        }
        .encode(order),
    );
    for e in extra {
        m.extend_from_slice(e);
    }
    m
}

/// The demo DEM copied to `dir/inn/` and `dir/ig.toml` naming it database 1 and `db2`
/// (relative to `dir`) database 2: (the DEM, the config).
fn demo_and_databases(dir: &Path, db2: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let inn = dir.join("inn/N47E011.hgt.zip");
    std::fs::create_dir_all(inn.parent().unwrap()).unwrap();
    std::fs::copy(aerie_tests::demo_dem(), &inn).unwrap();
    let cfg = dir.join("ig.toml");
    std::fs::write(
        &cfg,
        format!("[databases]\n1 = \"inn/N47E011.hgt.zip\"\n2 = \"{db2}\"\n"),
    )
    .unwrap();
    (inn, cfg)
}

/// What a host saw: (database in Start of Frame, valid HOT answers of that message) per IG
/// message, the run's JSON summary and its stderr.
type Switch = (Vec<(i8, Vec<f64>)>, serde_json::Value, String);

/// `aerie run` on `inn` with `cfg`, driven by a host that asks HOT under the aircraft every 8th
/// message and sets the sun and haze every 30th: database 0 (the `--dem`) until three answers
/// came, then database 2 until three answers came on it.
fn switch_to_database_2(dir: &Path, cfg: &Path, inn: &Path) -> Switch {
    let host = UdpSocket::bind("127.0.0.1:0").unwrap();
    host.set_read_timeout(Some(Duration::from_millis(2)))
        .unwrap();
    let port = UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let json = dir.join("run.json");
    let s = |p: &Path| p.display().to_string();
    let child = spawn(
        aerie_bin(),
        &[
            "run".into(),
            "--headless".into(),
            "--config".into(),
            s(cfg),
            "--dem".into(),
            s(inn),
            "--size".into(),
            "64x36".into(),
            "--seconds".into(),
            "10".into(),
            "--fps".into(),
            "30".into(),
            "--listen".into(),
            format!("127.0.0.1:{port}"),
            "--protocol".into(),
            "cigi".into(),
            "--json".into(),
            s(&json),
        ],
    );
    let to = format!("127.0.0.1:{port}");
    let order = ByteOrder::Big;
    let celestial = CelestialSphereControl {
        hour: 12,
        minute: 30,
        ephemeris_enabled: false,
        sun_enabled: true,
        date_valid: true,
        month: 6,
        day: 21,
        year: 2026,
        ..CelestialSphereControl::default()
    };
    let atmosphere = AtmosphereControl {
        visibility_m: 5000.0,
        ..AtmosphereControl::default()
    };
    // (database in Start of Frame, HOT answers of that message)
    let mut seen: Vec<(i8, Vec<f64>)> = Vec::new();
    let mut buf = [0u8; 65_536];
    let start = Instant::now();
    let mut frame = 0u32;
    let mut next = Instant::now();
    let mut want_db = 0i8;
    while start.elapsed() < Duration::from_secs(25) {
        if Instant::now() >= next {
            next += Duration::from_millis(16);
            frame += 1;
            let mut extra = Vec::new();
            if frame.is_multiple_of(8) {
                extra.push(
                    HatHotRequest {
                        request_id: frame as u16,
                        request_type: HatHotRequestType::Hot,
                        coordinate_system: CoordinateSystem::Geodetic,
                        update_period: 0,
                        entity_id: 0,
                        point: [LAT, LON, ALT],
                    }
                    .encode(CigiVersion::V3_3, order)
                    .to_vec(),
                );
            }
            if frame.is_multiple_of(30) {
                extra.push(celestial.encode(order).to_vec());
                extra.push(atmosphere.encode(order).to_vec());
            }
            host.send_to(&message(frame, want_db, &extra), &to).unwrap();
        }
        while let Ok((n, _)) = host.recv_from(&mut buf) {
            let m = decode_ig_message(&buf[..n]).expect("the IG's message decodes");
            let hots = m
                .responses
                .iter()
                .filter_map(|r| match r {
                    CigiResponse::HatHot(h) if h.valid => Some(h.height_m),
                    _ => None,
                })
                .collect();
            seen.push((m.start_of_frame.database, hots));
        }
        let answered_on = |db: i8| {
            seen.iter()
                .filter(|(d, h)| *d == db && !h.is_empty())
                .count()
        };
        if want_db == 0 && answered_on(1) >= 3 {
            want_db = 2;
        }
        if answered_on(2) >= 3 {
            break;
        }
    }
    drop(host);
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "aerie run failed:\n{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    (seen, summary, stderr)
}

#[test]
fn database_number_switches_datasets_and_the_host_sets_the_light() {
    let dir = tempfile::tempdir().unwrap();
    write_flat_tile(&dir.path().join("flat/N47E011.hgt"));
    let (inn, cfg) = demo_and_databases(dir.path(), "flat/N47E011.hgt");
    let hot_inn = oracle_hot(&inn);

    let (seen, summary, _) = switch_to_database_2(dir.path(), &cfg, &inn);

    // Start of Frame: database 1 (the --dem is [databases] 1), −2 while 2 loads, then 2.
    let dbs: Vec<i8> = seen.iter().map(|(d, _)| *d).collect();
    let mut phases: Vec<i8> = dbs.clone();
    phases.dedup();
    assert_eq!(phases, vec![1, -2, 2], "database numbers in Start of Frame");
    // HOT from the terrain drawn: the Inn valley's full-resolution surface (also while
    // database 2 loads: it is still what is drawn), then the flat one.
    for (db, hots) in &seen {
        for h in hots {
            match db {
                1 | -2 => assert!((h - hot_inn).abs() < 1e-3, "HOT {h} vs oracle {hot_inn}"),
                2 => assert!(
                    (h - f64::from(FLAT_M)).abs() < 1e-6,
                    "HOT {h} on database 2"
                ),
                _ => unreachable!("checked above"),
            }
        }
    }

    let ig = &summary["ig"];
    assert_eq!(ig["database"], 2, "{ig:#}");
    assert_eq!(ig["database_loads"][0]["number"], 2, "{ig:#}");
    assert!(ig["database_loads"][0]["error"].is_null(), "{ig:#}");
    // One Start of Frame per IG frame at most, however many host messages arrived.
    let sofs = ig["start_of_frames"].as_u64().unwrap();
    assert!(sofs >= seen.len() as u64);
    assert!(sofs <= ig["ig_frames"].as_u64().unwrap(), "{ig:#}");
    // The light: the sun of 21 June 2026 12:30 UTC over the aircraft, haze from 5 km.
    let light = &ig["lighting"];
    assert_eq!(light["sun_from_host"], true, "{light:#}");
    assert_eq!(light["visibility_from_host"], true, "{light:#}");
    let haze = light["haze_distance_m"].as_f64().unwrap();
    assert!((haze - 5000.0 / 3.912).abs() < 0.5, "{haze}");
    let expect = sun_direction_enu(
        &Celestial {
            date: Some((2026, 6, 21)),
            seconds_utc: 12.0 * 3600.0 + 30.0 * 60.0,
            ephemeris: false,
            sun_enabled: true,
            moon_enabled: false,
            stars_enabled: false,
            star_intensity_pct: 0.0,
            set_at_s: 0.0,
        },
        LAT,
        LON,
    )
    .unwrap();
    let sun: Vec<f64> = light["sun_enu"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    // The terrain is lit in world axes, ENU at the tile's south-west corner (47°N 11°E): the
    // sun at the aircraft turned into them.
    let axes = |lat: f64, lon: f64| {
        aerie_sim_bridge::LocalTangentPlane::new(aerie_sim_bridge::Geodetic::new(lat, lon, 0.0))
            .enu_axes()
    };
    let world = axes(47.0, 11.0).transpose() * axes(LAT, LON) * glam::DVec3::from_array(expect);
    for k in 0..3 {
        // f32 in the uniforms; the eye is within metres of (LAT, LON).
        assert!((sun[k] - world[k]).abs() < 1e-4, "{sun:?} vs {world:?}");
    }
    // Midsummer noon-ish at 47°N: high in the south.
    assert!(expect[2] > 0.8 && expect[1] < 0.0, "{expect:?}");
}

/// A host's database that is a tile store is streamed like `--dem region.aerie`: the switch
/// reports −2 while only its coarsest level is fetched, the run says it streams it, and the HOT
/// answers come from its level-0 pages (pending until they are resident, then exactly the
/// flat height).
#[test]
fn a_database_that_is_a_tile_store_is_streamed() {
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("flat/N47E011.hgt");
    write_flat_tile(&flat);
    let store = dir.path().join("flat.aerie");
    let out = Command::new(aerie_bin())
        .args(["import".as_ref(), flat.as_os_str(), "--out".as_ref()])
        .arg(&store)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The tile itself is gone: database 2 can only be read from the store.
    std::fs::remove_dir_all(flat.parent().unwrap()).unwrap();
    let (inn, cfg) = demo_and_databases(dir.path(), "flat.aerie");
    let hot_inn = oracle_hot(&inn);

    let (seen, summary, stderr) = switch_to_database_2(dir.path(), &cfg, &inn);

    let mut phases: Vec<i8> = seen.iter().map(|(d, _)| *d).collect();
    phases.dedup();
    assert_eq!(phases, vec![1, -2, 2], "database numbers in Start of Frame");
    let mut on_store = 0;
    for (db, hots) in &seen {
        for h in hots {
            if *db == 2 {
                on_store += 1;
                assert!(
                    (h - f64::from(FLAT_M)).abs() < 1e-6,
                    "HOT {h} on the streamed store"
                );
            } else {
                assert!((h - hot_inn).abs() < 1e-3, "HOT {h} vs oracle {hot_inn}");
            }
        }
    }
    assert!(on_store >= 3, "{on_store} valid HOT answers on database 2");
    assert!(
        stderr.contains("database 2 ready (streamed)"),
        "the run says it streams the store:\n{stderr}"
    );
    let load = &summary["ig"]["database_loads"][0];
    assert_eq!(load["number"], 2, "{load:#}");
    assert!(load["error"].is_null(), "{load:#}");
    assert_eq!(load["streamed"], true, "{load:#}");
    assert!(load["ready_s"].as_f64().unwrap() >= 0.0, "{load:#}");
}
