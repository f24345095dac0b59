//! `aerie run` as the image generator fed by a simulator (issue 6 item 7, issue 7 item 4), end to
//! end through real processes: `aerie-send` (or a sender thread) → UDP / shared memory →
//! `aerie run --headless` → its `--stats` CSV. For every rendered frame the camera the renderer
//! used must equal the sent pose (after the geodetic → dataset-grid conversion) within 1 mm and
//! 0.001°. Debug builds run with the validation layer on and `aerie run` exits non-zero on any
//! validation message, so a clean exit also means a clean validation log.
//!
//! The binaries are found next to this test's executable (target/<profile>/); if `aerie-send` or
//! `aerie` is missing they are built once with cargo.

use std::collections::HashMap;
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use aerie::sim::flight::Waypoints;
use aerie_sim_bridge::codec::native;
use aerie_sim_bridge::{Geodetic, LocalTangentPlane, Pose, PosePosition};

const MM: f64 = 1e-3;
const DEG: f64 = 1e-3;

/// The renderer and the test sender.
fn bins() -> (&'static PathBuf, &'static PathBuf) {
    (aerie_tests::aerie_bin(), aerie_tests::aerie_send_bin())
}

/// The demo DEM copied (with its bake, made once) into a folder shared by every test here, so
/// processes running at the same time never write a bake next to each other's data.
fn demo_dem() -> PathBuf {
    static DEM: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, p) = DEM.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("N47E011.hgt.zip");
        std::fs::copy(aerie_tests::demo_dem(), &p).unwrap();
        let out = Command::new(bins().0)
            .arg("bake")
            .arg(&p)
            .output()
            .expect("run aerie bake");
        assert!(out.status.success(), "bake: {}", text(&out.stderr));
        (dir, p)
    });
    p.clone()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
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

/// Waits for `child` at most `limit`; kills it (and fails) when it takes longer.
fn wait(mut child: Child, limit: Duration, what: &str) -> Output {
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "{what} did not finish within {limit:?}; stderr:\n{}",
                text(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Stops a sender that runs longer than the renderer needs.
fn stop(mut child: Child) {
    let _ = child.kill();
    let _ = child.wait();
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn args(list: &[&str]) -> Vec<String> {
    list.iter().map(|a| a.to_string()).collect()
}

type Row = HashMap<String, String>;

fn read_csv(path: &Path) -> Vec<Row> {
    let t = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = t.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    lines
        .map(|l| {
            let cols: Vec<&str> = l.split(',').collect();
            assert_eq!(cols.len(), header.len(), "{l}");
            header
                .iter()
                .zip(cols)
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

fn num(r: &Row, k: &str) -> f64 {
    r[k].parse()
        .unwrap_or_else(|_| panic!("column {k} = {:?} in {r:?}", r[k]))
}

fn angle_diff(a: f64, b: f64) -> f64 {
    ((a - b + 540.0).rem_euclid(360.0) - 180.0).abs()
}

/// A 20 s flight over the Inn valley: climbing, turning through north, rolling.
const WAYPOINTS: &str = "\
# t_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg
0,30000,20000,3500,330,-5,0
5,29400,21000,3600,350,-3,-10
10,29300,22100,3700,15,0,12
20,30200,24000,3650,40,2,0
";

/// What the stats CSV must show for the pose the sender sent at script time `t`.
struct Expected {
    position: [f64; 3],
    attitude: [f64; 3],
}

/// Runs `aerie run --headless` on `dem` with `run_args`, then `aerie-send` with `send_args`
/// (flying [`WAYPOINTS`] unless they ask for `--straight`); returns the stats rows and the JSON
/// summary.
fn fly(
    dir: &Path,
    dem: &Path,
    run_args: &[String],
    send_args: &[String],
) -> (Vec<Row>, serde_json::Value) {
    let (aerie, send) = bins();
    let stats = dir.join("stats.csv");
    let json = dir.join("run.json");
    let path = dir.join("flight.csv");
    std::fs::write(&path, WAYPOINTS).unwrap();
    let mut a = args(&[
        "run",
        "--headless",
        "--frames",
        "20",
        "--size",
        "160x90",
        "--wait-pose-s",
        "30",
    ]);
    a.extend([
        "--dem".into(),
        s(dem),
        "--stats".into(),
        s(&stats),
        "--json".into(),
        s(&json),
    ]);
    a.extend_from_slice(run_args);
    let run = spawn(aerie, &a);
    let mut b = args(&["--quiet"]);
    if !send_args.iter().any(|a| a == "--straight") {
        // Past the path's end the last waypoint is held: the sender outlives a slow start.
        b.extend(["--path".into(), s(&path), "--seconds".into(), "60".into()]);
    }
    b.extend_from_slice(send_args);
    let sender = spawn(send, &b);
    let out = wait(run, Duration::from_secs(90), "aerie run");
    stop(sender);
    assert!(
        out.status.success(),
        "aerie run exit {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    (read_csv(&stats), summary)
}

/// Every frame's camera equals `expect(sim time)`; the frames came from the stream, were not
/// extrapolated, and the aircraft moved during the run.
fn check_rows(rows: &[Row], summary: &serde_json::Value, expect: impl Fn(f64) -> Expected) {
    check_rows_as(rows, summary, false, expect)
}

fn check_rows_as(
    rows: &[Row],
    summary: &serde_json::Value,
    extrapolating: bool,
    expect: impl Fn(f64) -> Expected,
) {
    assert_eq!(rows.len(), 20, "one row per frame");
    assert_eq!(summary["frames"], 20);
    assert_eq!(summary["validation"]["enabled"], true);
    assert_eq!(summary["validation"]["errors"], 0);
    assert_eq!(summary["validation"]["warnings"], 0);
    assert!(
        summary["input"]["accepted"].as_u64().unwrap() > 0,
        "{summary}"
    );
    assert_eq!(summary["input"]["dropped_total"], 0, "{summary}");
    let mut times = Vec::new();
    let ages = &summary["input"]["pose_age_ms"];
    assert!(ages["max"].as_f64().unwrap() >= ages["median"].as_f64().unwrap());
    let pct = summary["input"]["extrapolated_pct"].as_f64().unwrap();
    if !extrapolating {
        assert_eq!(pct, 0.0);
    }
    let mut carried = 0;
    for r in rows {
        // From the stream (live; "lost" only if the sender stalled > 100 ms on a loaded box).
        assert!(r["stream"] == "live" || r["stream"] == "lost", "{r:?}");
        if !extrapolating {
            assert_eq!(r["extrapolated"], "0", "{r:?}");
        }
        carried += usize::from(r["extrapolated"] == "1");
        let t = num(r, "sim_time_s");
        let e = expect(t);
        for (k, want) in ["x_m", "y_m", "z_m"].iter().zip(e.position) {
            let got = num(r, k);
            assert!(
                (got - want).abs() <= MM,
                "frame {} t {t}: {k} {got} vs {want}",
                r["frame"]
            );
        }
        for (k, want) in ["heading_deg", "pitch_deg", "roll_deg"]
            .iter()
            .zip(e.attitude)
        {
            let got = num(r, k);
            assert!(
                angle_diff(got, want) <= DEG,
                "frame {} t {t}: {k} {got} vs {want}",
                r["frame"]
            );
        }
        times.push(t);
    }
    assert_eq!(pct, 100.0 * carried as f64 / rows.len() as f64);
    if extrapolating {
        assert!(
            carried >= rows.len() / 2,
            "{carried} of {} extrapolated",
            rows.len()
        );
    }
    times.dedup();
    assert!(
        times.len() >= 5,
        "the pose should change during the run: sim times {times:?}"
    );
    assert!(times.windows(2).all(|w| w[1] > w[0]), "{times:?}");
}

fn local_expected(w: &Waypoints) -> impl Fn(f64) -> Expected + '_ {
    move |t| {
        let (p, a) = w.pose_at(t);
        Expected {
            position: p.to_array(),
            attitude: [a.heading, a.pitch, a.roll].map(f64::to_degrees),
        }
    }
}

#[test]
fn native_local_poses_reach_the_camera_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let port = free_port();
    let to = format!("127.0.0.1:{port}");
    let (rows, summary) = fly(
        dir.path(),
        &demo_dem(),
        &args(&[
            "--listen",
            &to,
            "--protocol",
            "native",
            "--max-extrapolation-ms",
            "0",
        ]),
        &args(&["--protocol", "native", "--to", &to, "--rate", "60"]),
    );
    let w = Waypoints::parse(WAYPOINTS, "flight.csv").unwrap();
    check_rows(&rows, &summary, local_expected(&w));
    // Host frame = sequence, 1 at script time 0, +1 per 1/60 s.
    for r in &rows {
        let f = num(r, "host_frame");
        assert!(
            (f - 1.0 - 60.0 * num(r, "sim_time_s")).abs() < 1e-6,
            "{r:?}"
        );
    }
}

/// With the default cap (100 ms) each frame's pose is carried forward to its display time with
/// the sent velocity: on a straight pass that is exactly the pass at the reported sim time.
#[test]
fn extrapolated_poses_follow_the_flight_to_the_display_time() {
    let dir = tempfile::tempdir().unwrap();
    let port = free_port();
    let to = format!("127.0.0.1:{port}");
    let (x0, y0, z0, heading, speed) = (30000.0, 20000.0, 3500.0, 60.0f64, 200.0);
    let (rows, summary) = fly(
        dir.path(),
        &demo_dem(),
        &args(&["--listen", &to, "--protocol", "native"]),
        &args(&[
            "--straight",
            &format!("{x0},{y0},{z0},{heading},-4,2,{speed}"),
            "--seconds",
            "60",
            "--rate",
            "30",
            "--to",
            &to,
        ]),
    );
    check_rows_as(&rows, &summary, true, |t| {
        let h = heading.to_radians();
        Expected {
            position: [x0 + h.sin() * speed * t, y0 + h.cos() * speed * t, z0],
            attitude: [heading, -4.0, 2.0],
        }
    });
    for r in &rows {
        // Never carried further than the cap past the packet's own sim time (30 Hz frames).
        let sent = (num(r, "host_frame") - 1.0) / 30.0;
        let ahead = num(r, "sim_time_s") - sent;
        assert!((-1e-9..=0.1 + 1e-9).contains(&ahead), "{r:?}");
    }
}

#[test]
fn cigi_geodetic_poses_land_at_their_exact_point() {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_dem();
    let port = free_port();
    let to = format!("127.0.0.1:{port}");
    // The sender's local frame is the tangent plane at the dataset's south-west corner.
    let (lat0, lon0) = (47.0, 11.0);
    let (rows, summary) = fly(
        dir.path(),
        &dem,
        &args(&[
            "--listen",
            &to,
            "--protocol",
            "cigi",
            "--max-extrapolation-ms",
            "0",
        ]),
        // 50 Hz: script times k/50 s are whole 10 µs CIGI timestamp ticks.
        &args(&[
            "--protocol",
            "cigi",
            "--to",
            &to,
            "--rate",
            "50",
            "--origin",
            "47,11,0",
        ]),
    );
    let w = Waypoints::parse(WAYPOINTS, "flight.csv").unwrap();
    let ltp = LocalTangentPlane::new(Geodetic::new(lat0, lon0, 0.0));
    // The dataset is drawn on the ellipsoid in the ENU frame at its south-west sample — the
    // sender's frame here —, so each pose lands on the waypoint itself, and its attitude (taken
    // at the aircraft's own position) turns by the local frame's angle to the origin's.
    let ds = aerie::terrain::dataset::load_dataset(&dem).unwrap();
    let grid =
        aerie::terrain::geodesy::GeoGrid::of(ds.hf.geo.as_ref(), ds.hf.spacing_x, ds.hf.spacing_y)
            .unwrap();
    let geodetic = |t: f64| {
        let (p, _) = w.pose_at(t);
        ltp.enu_to_geodetic(p)
    };
    check_rows(&rows, &summary, |t| {
        let g = geodetic(t);
        let (p, a) = w.pose_at(t);
        let a = a.in_frame(grid.local_enu_axes(g.lat_deg, g.lon_deg));
        Expected {
            position: p.to_array(),
            attitude: [a.heading, a.pitch, a.roll].map(f64::to_degrees),
        }
    });
    // The geodetic columns give back what was sent (1e-8° ≈ 1 mm).
    for r in &rows {
        let g = geodetic(num(r, "sim_time_s"));
        assert!((num(r, "lat_deg") - g.lat_deg).abs() < 1e-8, "{r:?}");
        assert!((num(r, "lon_deg") - g.lon_deg).abs() < 1e-8, "{r:?}");
        assert!((num(r, "alt_m") - g.alt_m).abs() < MM, "{r:?}");
    }
}

#[test]
fn shared_memory_poses_reach_the_camera_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let name = format!("aerie-e2e-{}", std::process::id());
    let (rows, summary) = fly(
        dir.path(),
        &demo_dem(),
        &args(&[
            "--protocol",
            "shm",
            "--shm-name",
            &name,
            "--max-extrapolation-ms",
            "0",
        ]),
        &args(&["--protocol", "shm", "--shm-name", &name, "--rate", "60"]),
    );
    let _ = std::fs::remove_file(Path::new("/dev/shm").join(&name));
    let w = Waypoints::parse(WAYPOINTS, "flight.csv").unwrap();
    check_rows(&rows, &summary, local_expected(&w));
}

/// The pose of host frame `f` in the frame-locked test: moving and turning every frame.
fn frame_pose(f: u64) -> Pose {
    Pose {
        position: PosePosition::LocalEnu {
            x: 30000.0 + 2.5 * f as f64,
            y: 20000.0 + 1.25 * f as f64,
            z: 3500.0,
        },
        attitude_deg: [(f as f64 * 0.7).rem_euclid(360.0), -5.0, 0.0],
        sim_time_s: f as f64 / 5.0,
        frame: f,
        velocity_enu: Some([50.0, 25.0, 0.0]),
        angular_rates_deg_s: Some([14.0, 0.0, 0.0]),
    }
}

#[test]
fn one_process_per_channel_renders_the_same_host_frame_with_the_same_pose() {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_dem();
    let (aerie, _) = bins();
    let wall3 = aerie_tests::repo_root().join("config/presets/wall3.toml");
    // Both processes on one multicast group and port (shared with SO_REUSEADDR), joined on the
    // loopback interface so no multicast route is needed.
    let group = std::net::Ipv4Addr::new(239, 255, 47, 90);
    let port = free_port();
    let mut runs = Vec::new();
    for channel in ["left", "centre"] {
        let mut a = args(&[
            "run",
            "--headless",
            "--frames",
            "20",
            "--size",
            "160x90",
            "--sync-frames",
            "1",
            "--fps",
            "10",
            "--protocol",
            "native",
            "--wait-pose-s",
            "30",
            "--channel",
            channel,
        ]);
        a.extend([
            "--config".into(),
            s(&wall3),
            "--dem".into(),
            s(&dem),
            "--listen".into(),
            format!("0.0.0.0:{port}"),
            "--multicast".into(),
            group.to_string(),
            "--multicast-if".into(),
            "127.0.0.1".into(),
            "--stats".into(),
            s(&dir.path().join(format!("{channel}.csv"))),
        ]);
        runs.push(spawn(aerie, &a));
    }
    // One host at 5 Hz, both processes paced at 10 Hz: each host frame is drawn by both most of
    // the time.
    let done = Arc::new(AtomicBool::new(false));
    let sender = {
        let done = done.clone();
        std::thread::spawn(move || {
            let socket =
                aerie_sim_bridge::udp::multicast_sender(std::net::Ipv4Addr::LOCALHOST).unwrap();
            let mut f = 1u64;
            while !done.load(Ordering::Relaxed) && f < 5 * 120 {
                let bytes = native::encode(&frame_pose(f), f as u32);
                socket.send_to(&bytes, (group, port)).unwrap();
                f += 1;
                std::thread::sleep(Duration::from_millis(200));
            }
        })
    };
    let outs: Vec<Output> = runs
        .into_iter()
        .map(|r| wait(r, Duration::from_secs(90), "aerie run --channel"))
        .collect();
    done.store(true, Ordering::Relaxed);
    sender.join().unwrap();
    for o in &outs {
        assert!(
            o.status.success(),
            "exit {:?}: {}",
            o.status.code(),
            text(&o.stderr)
        );
    }
    let by_frame = |channel: &str| -> HashMap<u64, Row> {
        let rows = read_csv(&dir.path().join(format!("{channel}.csv")));
        assert_eq!(rows.len(), 20);
        rows.into_iter()
            .map(|r| {
                let f: u64 = r["host_frame"].parse().unwrap();
                // Frame-locked: host frame newest − 1 (or older after a loss), drawn with its
                // own pose exactly as sent, never extrapolated.
                let target: u64 = r["sync_target"].parse().unwrap();
                assert!(f <= target, "{r:?}");
                assert_eq!(r["extrapolated"], "0", "{r:?}");
                let sent = frame_pose(f);
                let PosePosition::LocalEnu { x, y, z } = sent.position else {
                    unreachable!()
                };
                assert_eq!([num(&r, "x_m"), num(&r, "y_m"), num(&r, "z_m")], [x, y, z]);
                assert!(angle_diff(num(&r, "heading_deg"), sent.attitude_deg[0]) < 1e-9);
                (f, r)
            })
            .collect()
    };
    let (left, centre) = (by_frame("left"), by_frame("centre"));
    let pose_columns = [
        "sim_time_s",
        "x_m",
        "y_m",
        "z_m",
        "lat_deg",
        "lon_deg",
        "alt_m",
        "heading_deg",
        "pitch_deg",
        "roll_deg",
    ];
    let mut common = 0;
    for (f, l) in &left {
        if let Some(c) = centre.get(f) {
            common += 1;
            for k in pose_columns {
                assert_eq!(l[k], c[k], "host frame {f}: {k} differs between channels");
            }
        }
    }
    assert!(
        common >= 3,
        "only {common} host frames drawn by both channels: left {:?}, centre {:?}",
        left.keys().collect::<Vec<_>>(),
        centre.keys().collect::<Vec<_>>()
    );
}

#[test]
fn bad_streams_stop_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let (aerie, send) = bins();
    // A dataset without geo-reference fed geodetic poses: exit 2 naming the reason.
    let (w, h) = (65usize, 65usize);
    let bytes: Vec<u8> = (0..w * h).flat_map(|_| 500f32.to_le_bytes()).collect();
    let raw = dir.path().join("flat.f32");
    std::fs::write(&raw, bytes).unwrap();
    std::fs::write(
        dir.path().join("flat.f32.json"),
        format!(r#"{{"width": {w}, "height": {h}, "spacing_x": 30.0, "spacing_y": 30.0}}"#),
    )
    .unwrap();
    let port = free_port();
    let to = format!("127.0.0.1:{port}");
    let mut a = args(&[
        "run",
        "--headless",
        "--frames",
        "5",
        "--size",
        "160x90",
        "--protocol",
        "native",
        "--wait-pose-s",
        "30",
        "--listen",
        &to,
    ]);
    a.extend(["--dem".into(), s(&raw)]);
    let run = spawn(aerie, &a);
    let sender = spawn(
        send,
        &args(&[
            "--straight",
            "900,900,1500,90,0,0,100",
            "--origin",
            "47,11,0",
            "--to",
            &to,
            "--seconds",
            "30",
            "--quiet",
        ]),
    );
    let out = wait(run, Duration::from_secs(60), "aerie run (geodetic)");
    stop(sender);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("geodetic") && err.contains("no geo-reference"),
        "{err}"
    );

    // Nothing arrives: after --wait-pose-s, exit 1 naming the address, protocol and counters.
    let port = free_port();
    let mut a = args(&[
        "run",
        "--headless",
        "--frames",
        "5",
        "--size",
        "160x90",
        "--protocol",
        "cigi",
        "--wait-pose-s",
        "0.5",
        "--listen",
    ]);
    a.extend([format!("127.0.0.1:{port}"), "--dem".into(), s(&raw)]);
    let out = wait(
        spawn(aerie, &a),
        Duration::from_secs(60),
        "aerie run (silent)",
    );
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains(&format!("127.0.0.1:{port}")), "{err}");
    assert!(
        err.contains("(cigi)") && err.contains("received 0"),
        "{err}"
    );
}

/// A private Xvfb for the windowed run: its display number, or why there is none.
struct Xvfb {
    child: Child,
    display: u32,
}

impl Xvfb {
    fn start() -> Result<Self, String> {
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x1024x24",
                "-nolisten",
                "tcp",
            ])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("cannot run Xvfb: {e}"))?;
        let stdout = child.stdout.take().expect("piped");
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            use std::io::BufRead;
            let mut line = String::new();
            let _ = std::io::BufReader::new(stdout).read_line(&mut line);
            let _ = tx.send(line);
        });
        match rx
            .recv_timeout(Duration::from_secs(20))
            .ok()
            .and_then(|l| l.trim().parse().ok())
        {
            Some(display) => Ok(Self { child, display }),
            None => {
                stop(child);
                Err("Xvfb did not report a display".into())
            }
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The CIGI host of the view tests: the ownship pose over the Inn valley, View Control for
/// view 5, a good View Definition for view 1 and a bad one (left ≥ right) for view 9, every
/// 50 ms in one datagram, until `done`.
fn cigi_view_host(port: u16, done: Arc<AtomicBool>) -> std::thread::JoinHandle<()> {
    use aerie_sim_bridge::codec::cigi::{ViewControl, ViewDefinition};
    use aerie_sim_bridge::send::{cigi_message, CIGI_ORDER};
    std::thread::spawn(move || {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        let mut f = 1u32;
        while !done.load(Ordering::Relaxed) && f < 20 * 90 {
            let pose = Pose {
                position: PosePosition::Geodetic {
                    lat_deg: 47.3,
                    lon_deg: 11.4,
                    alt_m: 3500.0,
                },
                attitude_deg: [70.0, -5.0, 0.0],
                sim_time_s: f as f64 / 20.0,
                frame: f.into(),
                velocity_enu: None,
                angular_rates_deg_s: None,
            };
            let mut m = cigi_message(&pose, f).unwrap();
            m.extend(
                ViewControl {
                    view_id: 5,
                    enable: 0x3F,
                    entity_id: 0,
                    offset_m: [1.5, -0.5, -2.0],
                    roll_pitch_yaw_deg: [1.25, -4.5, 33.25],
                    ..ViewControl::default()
                }
                .encode(CIGI_ORDER),
            );
            let def = |view_id, [left, right, top, bottom]: [f32; 4]| ViewDefinition {
                view_id,
                enable: 0x3F,
                near_m: 2.0,
                far_m: 50_000.0,
                left_deg: left,
                right_deg: right,
                top_deg: top,
                bottom_deg: bottom,
                ..ViewDefinition::default()
            };
            m.extend(def(1, [-20.0, 25.0, 15.0, -10.0]).encode(CIGI_ORDER));
            m.extend(def(9, [30.0, 20.0, 15.0, -10.0]).encode(CIGI_ORDER));
            socket.send_to(&m, ("127.0.0.1", port)).unwrap();
            f += 1;
            std::thread::sleep(Duration::from_millis(50));
        }
    })
}

/// The view-test config: channel "front" is CIGI view 5 by `cigi_view`, "side" view 1 by its
/// index; `[input]` picks the protocol and the extrapolation cap.
const VIEWS_CONFIG: &str = "[render]\nsize = \"160x90\"\n\n\
    [input]\nprotocol = \"cigi\"\nmax_extrapolation_ms = 0\nwait_pose_s = 30\n\n\
    [[channel]]\nname = \"front\"\ncigi_view = 5\nframes = 0\nfrustum = { hfov = 60.0 }\n\n\
    [[channel]]\nname = \"side\"\nview = { heading = 60.0 }\nfrustum = { hfov = 60.0 }\n";

/// Runs `aerie run` with [`VIEWS_CONFIG`] (`--listen` on the command line adds the port) and
/// `mode` args, fed by [`cigi_view_host`] (or the same views from `aerie-send --view
/// --view-frustum` with `use_aerie_send`); checks that every channel was drawn with the host's
/// view (within 0.001° / 1 mm) and returns the summary, the stats rows and stderr.
fn run_with_cigi_views(
    mode: &[&str],
    display: Option<u32>,
    use_aerie_send: bool,
) -> (serde_json::Value, Vec<Row>, String) {
    let dir = tempfile::tempdir().unwrap();
    let dem = demo_dem();
    let (aerie, send) = bins();
    let config = dir.path().join("ig.toml");
    let port = free_port();
    let json = dir.path().join("run.json");
    let stats = dir.path().join("stats.csv");
    let mut a = args(&["run"]);
    a.extend(args(mode));
    a.extend([
        "--config".into(),
        s(&config),
        "--dem".into(),
        s(&dem),
        "--listen".into(),
        format!("127.0.0.1:{port}"),
        "--json".into(),
        s(&json),
        "--stats".into(),
        s(&stats),
    ]);
    let command = |a: &[String]| {
        let mut c = Command::new(aerie);
        c.args(a).stdin(Stdio::null());
        if let Some(d) = display {
            c.env("DISPLAY", format!(":{d}"))
                .env_remove("WAYLAND_DISPLAY");
        }
        c
    };
    // An unknown key is refused naming the file, line, column and key, before anything opens.
    std::fs::write(&config, VIEWS_CONFIG).unwrap();
    let out = command(&a).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(
        err.contains("ig.toml:12:1: channel[0].frames: unknown field `frames`"),
        "{err}"
    );
    std::fs::write(&config, VIEWS_CONFIG.replace("frames = 0\n", "")).unwrap();
    let run = command(&a)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = if use_aerie_send {
        let to = format!("127.0.0.1:{port}");
        let sender = spawn(
            send,
            &args(&[
                "--quiet",
                "--protocol",
                "cigi",
                "--to",
                &to,
                "--origin",
                "47.3,11.4,0",
                "--straight",
                "0,0,3500,70,-5,0,0",
                "--rate",
                "20",
                "--seconds",
                "90",
                "--view",
                "5,33.25,-4.5,1.25,1.5,-0.5,-2",
                "--view-frustum",
                "1,-20,25,-10,15,2,50000",
                "--view-frustum",
                "9,30,20,-10,15,2,50000",
            ]),
        );
        let out = wait(run, Duration::from_secs(90), "aerie run (CIGI views)");
        stop(sender);
        out
    } else {
        let done = Arc::new(AtomicBool::new(false));
        let sender = cigi_view_host(port, done.clone());
        let out = wait(run, Duration::from_secs(90), "aerie run (CIGI views)");
        done.store(true, Ordering::Relaxed);
        sender.join().unwrap();
        out
    };
    assert!(
        out.status.success(),
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let views = &summary["input"]["views"];
    let close = |v: &serde_json::Value, want: f64| (v.as_f64().unwrap() - want).abs() < DEG;
    let front = &views["channels"][0];
    assert_eq!(front["name"], "front");
    assert_eq!(front["host_view"], true, "{views:#}");
    assert!(close(&front["view"]["heading"], 33.25), "{front}");
    assert!(close(&front["view"]["pitch"], -4.5), "{front}");
    assert!(close(&front["view"]["roll"], 1.25), "{front}");
    // CIGI's body frame is forward, right, down; the eye's up is −z.
    for (k, want) in [("forward", 1.5), ("right", -0.5), ("up", 2.0)] {
        assert!(
            (front["eye"][k].as_f64().unwrap() - want).abs() < MM,
            "{front}"
        );
    }
    assert_eq!(front["frustum"]["hfov"], 60.0, "{front}");
    let side = &views["channels"][1];
    assert_eq!(
        (side["cigi_view"].as_u64(), side["host_view"].as_bool()),
        (Some(1), Some(false))
    );
    assert_eq!(side["host_frustum"], true, "{side}");
    assert!(close(&side["view"]["heading"], 60.0), "{side}");
    for (k, want) in [
        ("left", -20.0),
        ("right", 25.0),
        ("up", 15.0),
        ("down", -10.0),
    ] {
        assert!(close(&side["frustum"][k], want), "{side}");
    }
    assert_eq!(side["near_m"], 2.0);
    assert_eq!(views["rejected"], 1, "{views:#}");
    assert!(
        views["last_rejection"]
            .as_str()
            .unwrap()
            .contains("view 9: left half-angle 30° must be less than right"),
        "{views:#}"
    );
    let err = text(&out.stderr);
    assert!(err.contains("CIGI view 9: left half-angle"), "{err}");
    // The config's cap 0 was used: nothing extrapolated.
    assert_eq!(summary["input"]["extrapolated_pct"], 0.0);
    (summary, read_csv(&stats), err)
}

/// CIGI View Control (16) and View Definition (21) drive the channels (issue 6 item 3, issue 7),
/// headless: the host's view 5 (channel "front" by `cigi_view = 5`) gets a view and eye offset,
/// view 1 (channel "side" by its index) an asymmetric frustum and near clip, and a bad definition
/// of view 9 (left ≥ right) is counted and ignored. `--overlay` draws the panel into every
/// headless channel frame.
#[test]
fn cigi_views_replace_channel_view_offsets_and_frusta() {
    let (summary, rows, _) = run_with_cigi_views(
        &["--headless", "--frames", "6", "--fps", "10", "--overlay"],
        None,
        false,
    );
    assert_eq!(summary["overlay_frames"], 12);
    assert_eq!(rows.len(), 6);
    assert!(rows.iter().all(|r| num(r, "triangles") > 0.0));
}

/// The same in windows (private Xvfb), the views sent by `aerie-send --view --view-frustum`: the
/// window path applies the host's views too, and its `--stats` rows carry the triangles of the
/// frame.
#[test]
fn cigi_views_drive_windowed_channels_and_stats_count_triangles() {
    let xvfb = match Xvfb::start() {
        Ok(x) => x,
        Err(why) => {
            eprintln!("SKIPPED: {why}");
            return;
        }
    };
    let (summary, rows, _) =
        run_with_cigi_views(&["--frames", "10", "--windowed"], Some(xvfb.display), true);
    assert_eq!(summary["frames"], 10);
    assert_eq!(rows.len(), 10);
    let from_stream: Vec<&Row> = rows.iter().filter(|r| r["stream"] != "waiting").collect();
    assert!(!from_stream.is_empty(), "no frame drew a received pose");
    assert!(rows.iter().all(|r| num(r, "triangles") > 0.0), "{rows:?}");
    drop(xvfb);
}
