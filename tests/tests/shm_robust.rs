//! Shared memory against the real processes (issue 16 items 2 and 8): a C++11 writer built from
//! `aerie_pose.h` feeds `aerie listen`, a C99 writer drives `aerie run --headless`, and a writer
//! that shrinks and regrows the file cannot crash the reader. The compiler tests skip with a note
//! when `gcc`/`g++` is missing (CI installs them: scripts/setup-debian.sh).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use aerie_sim_bridge::shm::ShmWriter;
use aerie_sim_bridge::{Pose, PosePosition};
use aerie_tests::aerie_bin;

/// The timed shrinking-file test runs alone: not while another test here renders on lavapipe
/// or compiles a writer on the same two cores.
static SERIAL: Mutex<()> = Mutex::new(());

/// Builds `sim-bridge/tests/c/shm_writer.c` from `aerie_pose.h` with `compiler` and `std_args`,
/// warnings as errors, into `dir`; `None` (with a note) when the compiler is missing.
fn build_writer(dir: &Path, compiler: &str, std_args: &[&str]) -> Option<PathBuf> {
    if Command::new(compiler).arg("--version").output().is_err() {
        eprintln!("skipped: no {compiler} (CI installs it: scripts/setup-debian.sh)");
        return None;
    }
    let root = aerie_tests::repo_root();
    let exe = dir.join("writer");
    let out = Command::new(compiler)
        .args(std_args)
        .args(["-Wall", "-Wextra", "-pedantic", "-Werror", "-I"])
        .arg(root.join("sim-bridge/include"))
        .arg(root.join("sim-bridge/tests/c/shm_writer.c"))
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{compiler}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(exe)
}

/// `aerie listen` on the shm file, with its stderr read by a thread so the test can wait until
/// it reads (a loaded machine can take seconds to start the process).
struct Listener {
    child: std::process::Child,
    ready: std::sync::mpsc::Receiver<()>,
    stderr: std::thread::JoinHandle<String>,
}

fn listen(path: &Path, seconds: &str, json: &Path) -> Listener {
    let mut child = Command::new(aerie_bin())
        .args(["listen", "--protocol", "shm", "--shm-name"])
        .arg(path)
        .args(["--seconds", seconds, "--json"])
        .arg(json)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start aerie listen");
    let err = child.stderr.take().expect("piped stderr");
    let (tx, ready) = std::sync::mpsc::channel();
    let stderr = std::thread::spawn(move || {
        use std::io::BufRead;
        let mut all = String::new();
        for line in std::io::BufReader::new(err).lines().map_while(Result::ok) {
            if line.starts_with("listening on") {
                let _ = tx.send(());
            }
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    Listener {
        child,
        ready,
        stderr,
    }
}

impl Listener {
    /// Blocks until `aerie listen` says it is listening (or gave up).
    fn wait_ready(&self) {
        let _ = self.ready.recv_timeout(Duration::from_secs(120));
    }

    /// Waits for the exit and returns the JSON summary.
    fn summary(self, json: &Path) -> serde_json::Value {
        let out = self.child.wait_with_output().unwrap();
        let stderr = self.stderr.join().unwrap_or_default();
        assert!(
            out.status.success(),
            "aerie listen: {}\n{stderr}",
            out.status
        );
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
    }
}

fn u(v: &serde_json::Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("{key} in {v}"))
}

#[test]
fn a_cxx11_writer_from_the_header_feeds_aerie_listen() {
    let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let Some(exe) = build_writer(dir.path(), "g++", &["-x", "c++", "-std=c++11"]) else {
        return;
    };
    let (file, json) = (dir.path().join("pose"), dir.path().join("listen.json"));
    let _ = aerie_bin();
    let child = listen(&file, "4", &json);
    // aerie waits for the file; the writer creates it and writes 10,000 poses (~1 s).
    let status = Command::new(&exe).arg(&file).arg("10000").status().unwrap();
    assert!(status.success(), "writer: {status}");
    let s = child.summary(&json);
    eprintln!("aerie listen fed by the C++11 writer: {s}");
    assert!(u(&s, "accepted") > 0, "{s}");
    assert_eq!(s["last_pose"]["frame"].as_u64(), Some(10_000), "{s}");
    assert_eq!(s["last_pose"]["position"]["x_m"].as_f64(), Some(10_000.0));
    assert_eq!(s["last_pose"]["velocity_enu"][0].as_f64(), Some(1.0));
    // At most the one record the writer corrupts on purpose at the end (its own check).
    let d = &s["dropped"];
    assert!(u(d, "bad_crc") <= 1, "{s}");
    assert_eq!(u(&s, "dropped_total"), u(d, "bad_crc"), "{s}");
}

/// One try of the shrinking-file scenario: the listener's summary and the last frame written.
fn shrinking_file_run() -> (serde_json::Value, u64) {
    let dir = tempfile::tempdir().unwrap();
    let (file, json) = (dir.path().join("pose"), dir.path().join("listen.json"));
    let pose = |k: u64| Pose {
        position: PosePosition::LocalEnu {
            x: k as f64,
            y: 0.0,
            z: 1000.0,
        },
        attitude_deg: [90.0, 0.0, 0.0],
        sim_time_s: k as f64 * 1e-3,
        frame: k,
        velocity_enu: None,
        angular_rates_deg_s: None,
    };
    let mut w = ShmWriter::create(&file).unwrap();
    w.write(&pose(1));
    let _ = aerie_bin();
    let child = listen(&file, "4", &json);
    child.wait_ready();
    // 20 Hz for 2 s: cut the file, regrow it, write for the rest of the 50 ms.
    let (start, mut k) = (Instant::now(), 1u64);
    for cycle in 0..40u32 {
        std::fs::OpenOptions::new()
            .write(true)
            .open(&file)
            .unwrap()
            .set_len([0, 8, 70, 140][cycle as usize % 4])
            .unwrap();
        std::thread::sleep(Duration::from_millis(15));
        drop(w);
        w = ShmWriter::create(&file).unwrap();
        while start.elapsed() < Duration::from_millis(50) * (cycle + 1) {
            k += 1;
            w.write(&pose(k));
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    (child.summary(&json), k)
}

/// The scenario is timed (a 4 s listener, 40 cuts 50 ms apart). It runs alone (`SERIAL`: not
/// beside the lavapipe frames of the other tests) and is tried up to three times: a listener
/// thread that the machine did not schedule for a second (other test binaries run beside
/// this one) reads too little to judge, and is reported.
#[test]
fn aerie_listen_survives_a_file_shrinking_under_it() {
    let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let (mut s, mut k) = shrinking_file_run();
    for _ in 0..2 {
        if u(&s, "shm_shrinks") >= 10 {
            break;
        }
        eprintln!("aerie listen read too little to judge (machine busy?), trying again: {s}");
        (s, k) = shrinking_file_run();
    }
    eprintln!("aerie listen under a shrinking file: {s}");
    assert!(u(&s, "shm_shrinks") >= 10, "{s}");
    assert!(u(&s, "shm_shrinks") <= 40, "{s}");
    assert_eq!(
        s["last_pose"]["frame"].as_u64(),
        Some(k),
        "did not recover: {s}"
    );
    // Only records cut by the shrinks (zeroed header, cut checksum) are dropped.
    let d = &s["dropped"];
    assert_eq!(
        u(&s, "dropped_total"),
        u(d, "unknown") + u(d, "bad_crc") + u(d, "bad_size") + u(d, "bad_version"),
        "{s}"
    );
}

#[test]
fn a_c99_writer_from_the_header_drives_aerie_run() {
    let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let Some(exe) = build_writer(dir.path(), "gcc", &["-std=c99"]) else {
        return;
    };
    let dem = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(aerie_tests::demo_dem(), &dem).unwrap();
    let (file, stats) = (dir.path().join("pose"), dir.path().join("stats.csv"));
    // The writer starts first and holds its last pose; the IG then renders 30 frames from it.
    let status = Command::new(&exe).arg(&file).arg("3000").status().unwrap();
    assert!(status.success(), "writer: {status}");
    let run = Command::new(aerie_bin())
        .args(["run", "--headless", "--size", "64x36", "--frames", "30"])
        .arg("--dem")
        .arg(&dem)
        .args(["--protocol", "shm", "--shm-name"])
        .arg(&file)
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "aerie run: {}\n{}",
        run.status,
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(&stats).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 30, "{csv}");
    for r in &rows {
        // Every frame drew the C writer's last pose (frame 3000 at x = 3000, y = −6000 m).
        assert_eq!(r[col("host_frame")], "3000", "{csv}");
        let x: f64 = r[col("x_m")].parse().unwrap();
        let y: f64 = r[col("y_m")].parse().unwrap();
        assert!(x.is_finite() && y.is_finite(), "{csv}");
        assert!(
            (x - 3000.0).abs() < 1000.0 && (y + 6000.0).abs() < 1000.0,
            "{csv}"
        );
    }
}
