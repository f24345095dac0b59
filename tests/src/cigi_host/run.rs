//! One `aerie run --headless` on the demo DEM driven by one run of the host program, and the
//! collector of what a run got wrong.
//!
//! The aerie binary is built with cargo once per test process (a no-op when up to date) and
//! found next to the test executable (target/<profile>/); the DEM is copied, with its bake,
//! into a temporary folder so aerie never writes next to the repository's copy. The host is
//! started after aerie and sends from its first message on: aerie renders its first frame
//! only when the host's first pose has arrived, so the host hears every Start of Frame.

use std::collections::HashMap;
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{host_program, Arch, HostOutput};
use crate::aerie_bin;

/// The demo DEM copied (with its bake, made once) into a temporary folder: aerie never writes
/// a bake next to the repository's copy.
pub fn demo_dem_copy() -> &'static PathBuf {
    static DEM: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    &DEM.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("N47E011.hgt.zip");
        std::fs::copy(crate::demo_dem(), &p).unwrap();
        let out = Command::new(aerie_bin())
            .arg("bake")
            .arg(&p)
            .output()
            .unwrap();
        assert!(out.status.success(), "bake: {}", text(&out.stderr));
        (dir, p)
    })
    .1
}

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

pub fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A child whose stdout and stderr are read on two threads from the moment it is started: a
/// chatty process (the host prints a line per message) must never block on a full pipe while
/// the test waits for another one.
pub struct Drained {
    child: Child,
    out: std::thread::JoinHandle<Vec<u8>>,
    err: std::thread::JoinHandle<Vec<u8>>,
}

fn read_all(mut r: impl std::io::Read + Send + 'static) -> std::thread::JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut b = Vec::new();
        r.read_to_end(&mut b).ok();
        b
    })
}

/// Starts reading `child`'s piped stdout and stderr now.
pub fn drain(mut child: Child) -> Drained {
    let out = read_all(child.stdout.take().expect("stdout piped"));
    let err = read_all(child.stderr.take().expect("stderr piped"));
    Drained { child, out, err }
}

impl Drained {
    /// Waits at most `limit`; kills the child and returns `Err` with its stderr if longer.
    pub fn wait(mut self, limit: Duration, what: &str) -> Result<Output, String> {
        let start = Instant::now();
        let status = loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                break Some(s);
            }
            if start.elapsed() > limit {
                let _ = self.child.kill();
                let _ = self.child.wait();
                break None;
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let (stdout, stderr) = (self.out.join().unwrap(), self.err.join().unwrap());
        match status {
            Some(status) => Ok(Output {
                status,
                stdout,
                stderr,
            }),
            None => Err(format!(
                "{what} did not finish within {limit:?}; stderr:\n{}",
                text(&stderr)
            )),
        }
    }
}

/// One `aerie run` driven by one host.
pub struct IgRun {
    pub label: String,
    pub arch: Arch,
    pub minor: u8,
    pub frames: u64,
    pub summary: Value,
    pub rows: Vec<HashMap<String, String>>,
    pub host: HostOutput,
}

/// Runs `aerie run --headless` for `frames` frames at `fps`, and the host program (`command`,
/// `--version 3.<minor>`, `args`) on `arch` against it.
pub fn ig_run(arch: Arch, minor: u8, frames: u64, fps: u32, command: &str, args: &[&str]) -> IgRun {
    let label = format!("{command} 3.{minor} {}", arch.byte_order());
    let host = host_program(arch).unwrap_or_else(|e| panic!("{e}"));
    let dir = tempfile::tempdir().unwrap();
    let (stats, json) = (dir.path().join("stats.csv"), dir.path().join("run.json"));
    let port = free_port();
    let listen = format!("127.0.0.1:{port}");
    let s = |p: &Path| p.display().to_string();
    let run_args = [
        "run",
        "--headless",
        "--size",
        "64x36",
        "--protocol",
        "cigi",
        "--max-extrapolation-ms",
        "0",
        // A host whose every message is refused fails in 20 s rather than hanging.
        "--wait-pose-s",
        "20",
    ];
    let aerie = Command::new(aerie_bin())
        .args(run_args)
        .args(["--frames", &frames.to_string(), "--fps", &fps.to_string()])
        .args(["--listen", &listen, "--dem", &s(demo_dem_copy())])
        .args(["--stats", &s(&stats), "--json", &s(&json)])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn aerie run");
    let aerie = drain(aerie);
    let mut host_args: Vec<String> = vec![
        command.into(),
        "--ig".into(),
        listen,
        "--version".into(),
        format!("3.{minor}"),
        // The IG is done when it has been silent this long; never longer than the test's limit.
        "--idle-exit-s".into(),
        "1.5".into(),
        "--seconds".into(),
        "100".into(),
    ];
    host_args.extend(args.iter().map(|a| a.to_string()));
    let host_child = host
        .command(&host_args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{label}: spawn {}: {e}", host.exe.display()));
    let host_child = drain(host_child);
    let aerie_out = aerie.wait(Duration::from_secs(120), "aerie run");
    let host_out = host_child
        .wait(Duration::from_secs(120), "cigi-host")
        .unwrap_or_else(|e| panic!("{label}: {e}"));
    let aerie_out = aerie_out.unwrap_or_else(|e| panic!("{label}: {e}"));
    assert!(
        aerie_out.status.success(),
        "{label}: aerie run exit {:?}\nstderr:\n{}\nhost stderr:\n{}",
        aerie_out.status.code(),
        text(&aerie_out.stderr),
        text(&host_out.stderr)
    );
    assert!(
        host_out.status.success(),
        "{label}: cigi-host exit {:?}\nstderr:\n{}",
        host_out.status.code(),
        text(&host_out.stderr)
    );
    let host =
        HostOutput::parse(&text(&host_out.stdout)).unwrap_or_else(|e| panic!("{label}: {e}"));
    let summary: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    IgRun {
        label,
        arch,
        minor,
        frames,
        summary,
        rows: read_csv(&stats),
        host,
    }
}

pub fn read_csv(path: &Path) -> Vec<HashMap<String, String>> {
    let t = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = t.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

// ---------------------------------------------------------------- findings

/// Every problem a run shows, reported together (one failing check does not hide the others).
pub struct Problems {
    pub label: String,
    pub list: Vec<String>,
}

impl Problems {
    pub fn new(label: &str) -> Self {
        Self {
            label: label.to_string(),
            list: Vec::new(),
        }
    }

    pub fn check(&mut self, ok: bool, what: impl FnOnce() -> String) {
        if !ok {
            self.list.push(what());
        }
    }

    pub fn finish(self) {
        if self.list.is_empty() {
            return;
        }
        let shown: Vec<&String> = self.list.iter().take(40).collect();
        panic!(
            "{}: {} problem(s):\n  {}{}",
            self.label,
            self.list.len(),
            shown
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join("\n  "),
            if self.list.len() > 40 { "\n  …" } else { "" }
        );
    }
}

pub fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

pub fn angle_diff(a: f64, b: f64) -> f64 {
    ((a - b + 540.0).rem_euclid(360.0) - 180.0).abs()
}
