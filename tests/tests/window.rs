//! Windowed presentation on lavapipe (issue 7): real X11 windows, surfaces and swapchains, with
//! the Khronos validation layer counting every message, including objects left at teardown.
//!
//! Display: every test runs on one private Xvfb server that the first test starts
//! (`Xvfb -displayfd … -fbdir …`: it picks a free display number itself and exposes its
//! framebuffer as a file, so tests can look at what the windows show). A watchdog shell kills
//! it and removes its files when this test process ends. If Xvfb cannot be started, an existing
//! `DISPLAY` is used (without the pixel checks); with neither, each test prints a note and
//! passes without running.
//!
//! winit allows one event loop per process, so the loop lives on one thread that runs the
//! tests' sessions one after the other (`run_app_on_demand`); the tests send it closures.

use std::io::{BufRead, BufReader};
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::sync::{Mutex, OnceLock};
use std::time::Duration;

use aerie::app::window::{
    new_event_loop, required_instance_extensions, run_channels, Action, EventLoop, ExitReason,
    RunOptions, RunReport, ScheduledAction, WindowError,
};
use aerie::camera::Attitude;
use aerie::render::frame::{RendererDesc, TerrainRenderer};
use aerie::render::uniforms::Look;
use aerie::sim::channel::AircraftPose;
use aerie::vk::DeviceDesc;
use aerie_config::{
    Channel, ChannelDisplay, ChannelFrustum, FullscreenMode, MonitorSelector, PresentMode,
    ViewOffset,
};
use aerie_tests::{assert_validation_clean, prepare, synthetic, test_desc};
use glam::DVec3;

/// A note on the real stderr, past libtest's output capture, so skips are seen in CI logs.
macro_rules! note {
    ($($t:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), "window tests: {}", format!($($t)*));
    }};
}

type Job = Box<dyn FnOnce(&mut EventLoop<()>) + Send>;

struct Ui {
    jobs: Mutex<mpsc::Sender<Job>>,
    /// Xvfb's framebuffer (XWD file) when we run our own server.
    framebuffer: Option<PathBuf>,
}

/// Sky colour on screen (sRGB of the renderer's linear sky colour), tolerance per channel.
fn is_sky(rgb: [u8; 3]) -> bool {
    let sky = [166u8, 196, 231];
    rgb.iter().zip(sky).all(|(&a, b)| a.abs_diff(b) <= 6)
}

/// Starts a private Xvfb; returns its display number and framebuffer file.
fn start_xvfb() -> Result<(u32, PathBuf), String> {
    let dir = std::env::temp_dir().join(format!("aerie-xvfb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    // The shell starts Xvfb (which writes its display number on our pipe once it accepts
    // connections), then waits for this process to end and stops the server.
    let script = r#"
        Xvfb -displayfd 1 -screen 0 1280x1024x24 -nolisten tcp -fbdir "$AERIE_FB_DIR" \
            2>"$AERIE_FB_DIR/xvfb.log" &
        x=$!
        while kill -0 "$AERIE_PARENT" 2>/dev/null && kill -0 "$x" 2>/dev/null; do sleep 0.5; done
        kill "$x" 2>/dev/null
        wait "$x" 2>/dev/null
        rm -rf "$AERIE_FB_DIR"
    "#;
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(script)
        .env("AERIE_FB_DIR", &dir)
        .env("AERIE_PARENT", std::process::id().to_string())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot run sh: {e}"))?;
    let stdout = child.stdout.take().expect("piped");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stdout).read_line(&mut line);
        let _ = tx.send(line);
    });
    let line = rx
        .recv_timeout(Duration::from_secs(20))
        .map_err(|_| "Xvfb did not report a display within 20 s".to_string())?;
    let log = || std::fs::read_to_string(dir.join("xvfb.log")).unwrap_or_default();
    let n: u32 = line
        .trim()
        .parse()
        .map_err(|_| format!("Xvfb did not start: {}", log().trim()))?;
    Ok((n, dir.join("Xvfb_screen0")))
}

fn ui() -> Option<&'static Ui> {
    static UI: OnceLock<Option<Ui>> = OnceLock::new();
    UI.get_or_init(|| {
        let framebuffer = match start_xvfb() {
            Ok((n, fb)) => {
                // Every other test thread is blocked in this initialisation.
                std::env::set_var("DISPLAY", format!(":{n}"));
                Some(fb)
            }
            Err(why) if std::env::var_os("DISPLAY").is_some() => {
                note!(
                    "{why}; using DISPLAY={:?} (no pixel checks)",
                    std::env::var("DISPLAY")
                );
                None
            }
            Err(why) => {
                note!("SKIPPED: Xvfb cannot be started ({why}) and DISPLAY is not set");
                return None;
            }
        };
        let (tx, rx) = mpsc::channel::<Job>();
        let (ready_tx, ready_rx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut event_loop = match new_event_loop(true) {
                Ok(l) => {
                    let _ = ready_tx.send(Ok(()));
                    l
                }
                Err(e) => {
                    let _ = ready_tx.send(Err(e.to_string()));
                    return;
                }
            };
            for job in rx {
                job(&mut event_loop);
            }
        });
        match ready_rx.recv() {
            Ok(Ok(())) => Some(Ui {
                jobs: Mutex::new(tx),
                framebuffer,
            }),
            Ok(Err(e)) => panic!("the display is there but winit cannot use it: {e}"),
            Err(_) => panic!("event loop thread died"),
        }
    })
    .as_ref()
}

/// Runs `f` on the event loop thread; panics there are re-raised here.
fn on_ui<R: Send + 'static>(f: impl FnOnce(&mut EventLoop<()>) -> R + Send + 'static) -> Option<R> {
    let ui = ui()?;
    let (tx, rx) = mpsc::channel();
    let job: Job = Box::new(move |el| {
        let r = catch_unwind(AssertUnwindSafe(|| f(el)));
        let _ = tx.send(r);
    });
    ui.jobs
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .send(job)
        .expect("event loop thread alive");
    match rx.recv().expect("job result") {
        Ok(r) => Some(r),
        Err(panic) => resume_unwind(panic),
    }
}

/// Pixels of Xvfb's framebuffer (XWD, 32 bits per pixel, little-endian BGRX).
struct Screen {
    bytes: Vec<u8>,
    offset: usize,
    stride: usize,
}

impl Screen {
    fn grab(path: &Path) -> Screen {
        let bytes = std::fs::read(path).expect("read Xvfb framebuffer");
        let field = |i: usize| u32::from_be_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap());
        let (header, bpp, stride, ncolors) = (field(0), field(11), field(12), field(19));
        assert_eq!(bpp, 32, "framebuffer depth");
        Screen {
            offset: header as usize + ncolors as usize * 12,
            stride: stride as usize,
            bytes,
        }
    }

    fn rgb(&self, x: u32, y: u32) -> [u8; 3] {
        let i = self.offset + y as usize * self.stride + x as usize * 4;
        [self.bytes[i + 2], self.bytes[i + 1], self.bytes[i]]
    }

    /// Fraction of sky pixels in a row segment.
    fn sky_fraction(&self, x0: u32, x1: u32, y: u32) -> f64 {
        let n = (x0..x1).filter(|&x| is_sky(self.rgb(x, y))).count();
        n as f64 / (x1 - x0) as f64
    }
}

/// A window's framebuffer area shows the terrain: sky along its top row, ground along its
/// bottom row.
fn assert_shows_terrain(screen: &Screen, (x, y, w, h): (u32, u32, u32, u32), what: &str) {
    let top = screen.sky_fraction(x + 2, x + w - 2, y + 2);
    let bottom = screen.sky_fraction(x + 2, x + w - 2, y + h - 3);
    assert!(top > 0.9, "{what}: top row is not sky ({top:.2})");
    assert!(
        bottom < 0.1,
        "{what}: bottom row is not ground ({bottom:.2})"
    );
}

fn window(name: &str, x: i32, y: i32, w: u32, h: u32, heading: f64) -> Channel {
    Channel {
        display: ChannelDisplay::Window {
            x: Some(x),
            y: Some(y),
            width: w,
            height: h,
        },
        view: ViewOffset {
            heading_deg: heading,
            pitch_deg: 0.0,
            roll_deg: 0.0,
        },
        frustum: ChannelFrustum::Symmetric {
            hfov_deg: 60.0,
            vfov_deg: None,
        },
        ..Channel::window(name, w, h, 60.0, 1.0)
    }
}

/// The pose every window test flies: over the middle of the synthetic field, nose down.
fn pose() -> AircraftPose {
    AircraftPose {
        position: DVec3::new(1920.0, 1600.0, 450.0),
        attitude: Attitude::from_degrees(10.0, -12.0, 0.0),
    }
}

/// A renderer able to present on this display, with a small synthetic terrain loaded.
fn renderer(event_loop: &EventLoop<()>) -> TerrainRenderer {
    let desc = RendererDesc {
        instance_extensions: required_instance_extensions(event_loop).expect("extensions"),
        device: DeviceDesc {
            swapchain: true,
            ..Default::default()
        },
        // The plain look clears to one sky colour: these tests find the terrain view on screen
        // by that colour (the full look's sky varies with the direction).
        look: Look::Plain,
        ..test_desc(320, 180)
    };
    let hf = synthetic(257, 257, 15.0, 100.0, &[(100, 100, 140, 140, 180.0)]);
    let (ds, b) = prepare(&desc, &hf);
    let mut r = TerrainRenderer::new(&desc).expect("renderer with a swapchain device");
    r.load_terrain(ds, b, pose().position).expect("terrain");
    r
}

/// Runs one session and tears the renderer down; returns the report (or error) and the number
/// of pose samples, after checking that validation stayed silent through teardown (objects
/// left over are reported when the device and instance are destroyed). `on_frame` runs in the
/// pose source, once per frame, while the windows are up.
fn session_with(
    el: &mut EventLoop<()>,
    channels: Vec<Channel>,
    opts: RunOptions,
    mut on_frame: impl FnMut(u64),
) -> (Result<RunReport, WindowError>, u64) {
    let mut r = renderer(el);
    let mut calls = 0u64;
    let mut source = |frame: u64, _t: f64| {
        calls += 1;
        on_frame(frame);
        pose()
    };
    let result = run_channels(el, &mut r, &channels, &mut source, &opts);
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    (result, calls)
}

/// [`session_with`] that grabs the screen at frame `grab_at` (when we own the X server).
fn session(
    el: &mut EventLoop<()>,
    channels: Vec<Channel>,
    opts: RunOptions,
    framebuffer: Option<PathBuf>,
    grab_at: u64,
) -> (Result<RunReport, WindowError>, Option<Screen>, u64) {
    let mut shot = None;
    let (result, calls) = session_with(el, channels, opts, |frame| {
        if frame == grab_at {
            if let Some(fb) = &framebuffer {
                shot = Some(Screen::grab(fb));
            }
        }
    });
    (result, shot, calls)
}

fn framebuffer() -> Option<PathBuf> {
    ui().and_then(|u| u.framebuffer.clone())
}

#[test]
fn window_presents_60_frames_resizes_twice_and_exits_clean() {
    let fb = framebuffer();
    let out = on_ui(move |el| {
        let opts = RunOptions {
            max_frames: Some(90),
            max_seconds: None,
            actions: vec![
                ScheduledAction {
                    frame: 20,
                    action: Action::Resize {
                        channel: 0,
                        width: 400,
                        height: 240,
                    },
                },
                ScheduledAction {
                    frame: 45,
                    action: Action::Resize {
                        channel: 0,
                        width: 256,
                        height: 144,
                    },
                },
            ],
            ..Default::default()
        };
        let ch = window("main", 0, 0, 320, 180, 0.0);
        session(el, vec![ch], opts, fb, 80)
    });
    let Some((result, screen, poses)) = out else {
        return;
    };
    let report = result.expect("session");
    assert_eq!(report.exit, ExitReason::Frames);
    assert_eq!(report.frames, 90);
    assert_eq!(poses, 90, "one pose sample per frame");
    let c = &report.channels[0];
    assert!(c.presented >= 85, "{c:?}");
    assert_eq!(c.presented + c.skipped, 90, "{c:?}");
    assert_eq!(
        c.extents,
        [[320, 180], [400, 240], [256, 144]],
        "swapchain followed both resizes: {c:?}"
    );
    assert!(c.swapchain_builds >= 3, "{c:?}");
    assert_eq!(c.render_size, [256, 144], "render size follows the window");
    assert_eq!(screen.is_some(), framebuffer().is_some(), "snapshot taken");
    if let Some(s) = screen {
        assert_shows_terrain(&s, (0, 0, 256, 144), "resized window");
    }
}

#[test]
fn two_windows_at_once_on_one_device() {
    let fb = framebuffer();
    let out = on_ui(move |el| {
        let opts = RunOptions {
            max_frames: Some(60),
            ..Default::default()
        };
        let channels = vec![
            window("left", 0, 400, 320, 180, -30.0),
            window("right", 330, 400, 320, 180, 30.0),
        ];
        session(el, channels, opts, fb, 50)
    });
    let Some((result, screen, poses)) = out else {
        return;
    };
    let report = result.expect("session");
    assert_eq!((report.frames, poses), (60, 60));
    assert_eq!(report.channels.len(), 2);
    for c in &report.channels {
        assert!(c.presented >= 58, "{c:?}");
        assert_eq!(c.extents, [[320, 180]], "{c:?}");
    }
    assert_eq!(screen.is_some(), framebuffer().is_some(), "snapshot taken");
    if let Some(s) = screen {
        assert_shows_terrain(&s, (0, 400, 320, 180), "left window");
        assert_shows_terrain(&s, (330, 400, 320, 180), "right window");
        // Different view offsets: the two windows do not show the same picture.
        let differ = (0..320)
            .step_by(4)
            .flat_map(|x| (0..180).step_by(4).map(move |y| (x, y)))
            .filter(|&(x, y)| s.rgb(x, 400 + y) != s.rgb(330 + x, 400 + y))
            .count();
        assert!(differ > 100, "left and right windows look identical");
    }
}

#[test]
fn every_present_mode_runs_or_is_refused_with_the_supported_list() {
    for mode in [
        PresentMode::Mailbox,
        PresentMode::Immediate,
        PresentMode::Fifo,
    ] {
        let out = on_ui(move |el| {
            let opts = RunOptions {
                max_frames: Some(12),
                ..Default::default()
            };
            let ch = Channel {
                present_mode: mode,
                ..window("modes", 700, 0, 160, 90, 0.0)
            };
            session(el, vec![ch], opts, None, u64::MAX)
        });
        let Some((result, _, poses)) = out else {
            return;
        };
        match result {
            Ok(report) => {
                assert_eq!(report.channels[0].present_mode, mode.as_str());
                assert_eq!(report.channels[0].presented, 12, "{mode:?}");
            }
            Err(WindowError::Channel { key, message, .. }) => {
                assert_ne!(mode, PresentMode::Fifo, "FIFO is always supported");
                assert_eq!(key, "present_mode");
                assert!(message.contains("supported: "), "{message}");
                assert_eq!(poses, 0, "refused before the first frame");
            }
            Err(e) => panic!("{mode:?}: {e}"),
        }
    }
}

#[test]
fn unknown_monitor_stops_before_the_first_frame_listing_the_monitors() {
    let out = on_ui(|el| {
        let opts = RunOptions {
            max_frames: Some(10),
            ..Default::default()
        };
        // The first channel opens fine; the second names a monitor that does not exist: no
        // frame is drawn and the first window is closed again.
        let good = window("good", 0, 0, 160, 90, 0.0);
        let bad = Channel {
            monitor: Some(MonitorSelector::Name("NOPE-9".into())),
            ..window("bad", 200, 0, 160, 90, 0.0)
        };
        let by_index = Channel {
            monitor: Some(MonitorSelector::Index(7)),
            ..window("bad", 200, 0, 160, 90, 0.0)
        };
        let a = session(el, vec![good.clone(), bad], opts.clone(), None, u64::MAX);
        let b = session(el, vec![by_index], opts, None, u64::MAX);
        (a, b)
    });
    let Some(((a, _, poses_a), (b, _, poses_b))) = out else {
        return;
    };
    for (result, poses, sel) in [(a, poses_a, "\"NOPE-9\""), (b, poses_b, "7")] {
        let e = result.expect_err("unknown monitor must fail");
        assert!(e.is_bad_input(), "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains(&format!(
                ".monitor: unknown monitor {sel}; monitors found: 0: "
            )),
            "{msg}"
        );
        assert_eq!(poses, 0, "no frame drawn");
    }
}

#[test]
fn fullscreen_borderless_on_a_monitor_chosen_by_name_and_by_index() {
    let out = on_ui(|el| {
        let opts = RunOptions {
            max_frames: Some(10),
            ..Default::default()
        };
        // Xvfb's RandR output is called "screen".
        let mut reports = Vec::new();
        for sel in [
            MonitorSelector::Name("screen".into()),
            MonitorSelector::Index(0),
        ] {
            let ch = Channel {
                monitor: Some(sel),
                display: ChannelDisplay::Fullscreen(FullscreenMode::Borderless),
                resolution: Some((320, 180)),
                ..Channel::window("full", 320, 180, 60.0, 1.0)
            };
            reports.push(session(el, vec![ch], opts.clone(), None, u64::MAX).0);
        }
        reports
    });
    let Some(reports) = out else {
        return;
    };
    for r in reports {
        let report = r.expect("fullscreen session");
        let c = &report.channels[0];
        assert_eq!(c.fullscreen.as_deref(), Some("borderless"));
        assert_eq!(c.monitor.as_deref(), Some("screen"));
        assert_eq!(c.presented, 10);
        assert_eq!(
            c.render_size,
            [320, 180],
            "fixed resolution, scaled to the window"
        );
    }
}

/// A small raw f32 DEM with its sidecar, for the command-level test.
fn raw_dem(dir: &Path) -> PathBuf {
    let (w, h) = (129usize, 129usize);
    let mut bytes = Vec::new();
    for r in 0..h {
        for c in 0..w {
            let (dx, dy) = (c as f32 - 64.0, r as f32 - 64.0);
            let z = 100.0 + 300.0 * (-(dx * dx + dy * dy) / 800.0).exp();
            bytes.extend_from_slice(&z.to_le_bytes());
        }
    }
    let p = dir.join("hill.f32");
    std::fs::write(&p, bytes).unwrap();
    std::fs::write(
        dir.join("hill.f32.json"),
        format!(r#"{{"width": {w}, "height": {h}, "spacing_x": 30.0, "spacing_y": 30.0}}"#),
    )
    .unwrap();
    p
}

#[derive(clap::Parser)]
struct RunCli {
    #[command(flatten)]
    args: aerie::app::commands::run::RunArgs,
}

fn run_command(args: Vec<String>) -> Option<Result<serde_json::Value, (i32, String)>> {
    use clap::Parser;
    on_ui(move |el| {
        let cli = RunCli::try_parse_from(std::iter::once("run".to_string()).chain(args))
            .expect("arguments parse");
        aerie::app::commands::run::run_on(el, &cli.args).map_err(|f| (f.code, f.message))
    })
}

#[test]
fn aerie_run_opens_every_channel_of_wall3_or_only_the_named_one() {
    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let wall3 = aerie_tests::repo_root().join("config/presets/wall3.toml");
    let json = dir.path().join("run.json");
    let s = |p: &Path| p.display().to_string();
    let base = vec![
        "--config".to_string(),
        s(&wall3),
        "--dem".into(),
        s(&dem),
        "--windowed".into(),
        "--window-size".into(),
        "160x90".into(),
        "--frames".into(),
        "20".into(),
    ];
    let mut all = base.clone();
    all.extend(["--json".to_string(), s(&json), "--overlay".into()]);
    let Some(result) = run_command(all) else {
        return;
    };
    let summary = result.unwrap_or_else(|(c, m)| panic!("exit {c}: {m}"));
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The file holds the summary (floats compared loosely: JSON text does not round-trip them
    // to the last bit).
    for key in [
        "channels",
        "frames",
        "exit",
        "validation",
        "config",
        "device",
    ] {
        assert_eq!(written[key], summary[key], "{key}");
    }
    let median = |v: &serde_json::Value| v["frame_ms"]["median"].as_f64().unwrap();
    assert!((median(&written) - median(&summary)).abs() < 1e-9);
    assert_eq!(summary["frames"], 20);
    assert_eq!(summary["exit"], "frames");
    assert_eq!(summary["validation"]["errors"], 0);
    assert_eq!(summary["validation"]["warnings"], 0);
    assert_eq!(summary["validation"]["enabled"], true);
    let names: Vec<&str> = summary["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["left", "centre", "right"]);
    for c in summary["channels"].as_array().unwrap() {
        assert_eq!(c["presented"], 20, "{c}");
        // --overlay: the statistics panel on every frame from the start.
        assert_eq!(c["overlay_frames"], 20, "{c}");
        assert_eq!(c["render_size"], serde_json::json!([160, 90]), "{c}");
    }
    assert!(summary["frame_ms"]["median"].as_f64().unwrap() > 0.0);

    // One process per channel: only the named one opens.
    let mut one = base.clone();
    one.extend(["--channel".to_string(), "centre".into()]);
    let summary = run_command(one)
        .unwrap()
        .unwrap_or_else(|(c, m)| panic!("{c}: {m}"));
    assert_eq!(summary["channels"].as_array().unwrap().len(), 1);
    assert_eq!(summary["channels"][0]["name"], "centre");
    assert_eq!(
        summary["channels"][0]["overlay_frames"], 0,
        "off by default"
    );

    // An unknown channel name is bad input listing the channels.
    let mut bad = base.clone();
    bad.extend(["--channel".to_string(), "middle".into()]);
    let (code, msg) = run_command(bad).unwrap().expect_err("unknown channel");
    assert_eq!(code, 2);
    assert!(
        msg.contains("--channel middle: no such channel in") && msg.contains("left, centre, right"),
        "{msg}"
    );

    // Without --windowed, wall3 asks for monitors 0, 1 and 2: Xvfb has one. The error names
    // the file, the line and column of the key, the key, and the monitors found.
    let fullscreen: Vec<String> = base[..4]
        .iter()
        .cloned()
        .chain(["--frames".to_string(), "5".into()])
        .collect();
    let (code, msg) = run_command(fullscreen)
        .unwrap()
        .expect_err("monitor 1 is missing");
    assert_eq!(code, 2, "{msg}");
    assert!(
        msg.contains("wall3.toml:")
            && msg.contains(": channel[1].monitor: unknown monitor 1; monitors found: 0: "),
        "{msg}"
    );
}

/// A second X client that plays the user: finds our window by its geometry, presses Esc in it
/// (XTest) or asks the window to close (WM_DELETE_WINDOW, as a window manager's close button).
struct FakeUser {
    xlib: x11_dl::xlib::Xlib,
    xtest: x11_dl::xtest::Xf86vmode,
    display: *mut x11_dl::xlib::Display,
}

impl FakeUser {
    fn open() -> FakeUser {
        let xlib = x11_dl::xlib::Xlib::open().expect("libX11");
        let xtest = x11_dl::xtest::Xf86vmode::open().expect("libXtst");
        // SAFETY: libX11 is loaded; a null name opens $DISPLAY (our private Xvfb), checked below.
        let display = unsafe { (xlib.XOpenDisplay)(std::ptr::null()) };
        assert!(!display.is_null(), "second connection to the X server");
        FakeUser {
            xlib,
            xtest,
            display,
        }
    }

    /// The mapped top-level window at (x, y) of size w×h.
    fn find(&self, x: i32, y: i32, w: i32, h: i32) -> Option<u64> {
        use x11_dl::xlib;
        // XQueryTree's `children` holds `n` windows until XFree, which we copy first; XWindowAttributes is plain data that
        // XGetWindowAttributes fills.
        // SAFETY: `display` is an open connection (checked non-null in `open`, closed only in Drop).
        unsafe {
            let root = (self.xlib.XDefaultRootWindow)(self.display);
            let (mut r, mut p, mut children, mut n) = (0, 0, std::ptr::null_mut(), 0);
            (self.xlib.XQueryTree)(self.display, root, &mut r, &mut p, &mut children, &mut n);
            let list = if children.is_null() {
                Vec::new()
            } else {
                std::slice::from_raw_parts(children, n as usize).to_vec()
            };
            if !children.is_null() {
                (self.xlib.XFree)(children.cast());
            }
            list.into_iter().rev().find(|&win| {
                let mut a: xlib::XWindowAttributes = std::mem::zeroed();
                (self.xlib.XGetWindowAttributes)(self.display, win, &mut a) != 0
                    && a.map_state == xlib::IsViewable
                    && (a.x, a.y, a.width, a.height) == (x, y, w, h)
            })
        }
    }

    fn press_escape(&self, window: u64) {
        self.press_key(window, x11_dl::keysym::XK_Escape);
    }

    /// Focuses `window` and presses and releases the key of `keysym` in it (XTest).
    fn press_key(&self, window: u64, keysym: std::os::raw::c_uint) {
        use x11_dl::xlib;
        // SAFETY: `display` is an open connection (see `find`); the calls take plain values.
        unsafe {
            (self.xlib.XSetInputFocus)(
                self.display,
                window,
                xlib::RevertToParent,
                xlib::CurrentTime,
            );
            let key = (self.xlib.XKeysymToKeycode)(self.display, keysym as std::os::raw::c_ulong);
            (self.xtest.XTestFakeKeyEvent)(self.display, key as u32, xlib::True, 0);
            (self.xtest.XTestFakeKeyEvent)(self.display, key as u32, xlib::False, 0);
            (self.xlib.XSync)(self.display, xlib::False);
        }
    }

    fn close(&self, window: u64) {
        use x11_dl::xlib;
        // Atom names are NUL-terminated C string literals; the event is a fully initialised
        // ClientMessage that XSendEvent reads.
        // SAFETY: `display` is an open connection (see `find`).
        unsafe {
            let atom = |name: &std::ffi::CStr| {
                (self.xlib.XInternAtom)(self.display, name.as_ptr(), xlib::False)
            };
            let mut data = xlib::ClientMessageData::default();
            data.set_long(0, atom(c"WM_DELETE_WINDOW") as std::os::raw::c_long);
            data.set_long(1, xlib::CurrentTime as std::os::raw::c_long);
            let mut event = xlib::XEvent {
                client_message: xlib::XClientMessageEvent {
                    type_: xlib::ClientMessage,
                    serial: 0,
                    send_event: xlib::True,
                    display: self.display,
                    window,
                    message_type: atom(c"WM_PROTOCOLS"),
                    format: 32,
                    data,
                },
            };
            (self.xlib.XSendEvent)(
                self.display,
                window,
                xlib::False,
                xlib::NoEventMask,
                &mut event,
            );
            (self.xlib.XSync)(self.display, xlib::False);
        }
    }
}

impl FakeUser {
    /// Marks the window minimised the way a window manager does (`_NET_WM_STATE_HIDDEN`), or
    /// restores it.
    fn set_minimised(&self, window: u64, minimised: bool) {
        use x11_dl::xlib;
        // The property data is one atom (32-bit format, 1 element) that outlives the call.
        // SAFETY: `display` is an open connection (see `find`).
        unsafe {
            let atom = |name: &std::ffi::CStr| {
                (self.xlib.XInternAtom)(self.display, name.as_ptr(), xlib::False)
            };
            let state = atom(c"_NET_WM_STATE");
            if minimised {
                let hidden = [atom(c"_NET_WM_STATE_HIDDEN")];
                (self.xlib.XChangeProperty)(
                    self.display,
                    window,
                    state,
                    xlib::XA_ATOM,
                    32,
                    xlib::PropModeReplace,
                    hidden.as_ptr().cast(),
                    1,
                );
            } else {
                (self.xlib.XDeleteProperty)(self.display, window, state);
            }
            (self.xlib.XSync)(self.display, xlib::False);
        }
    }
}

impl Drop for FakeUser {
    fn drop(&mut self) {
        // SAFETY: the connection opened in `open` is closed once, here, and not used after.
        unsafe { (self.xlib.XCloseDisplay)(self.display) };
    }
}

#[test]
fn escape_and_the_close_button_end_the_session_with_everything_destroyed() {
    if framebuffer().is_none() {
        // Only on our private Xvfb: never type into someone's desktop.
        if ui().is_some() {
            note!("skipped: needs the private Xvfb to fake key presses");
        }
        return;
    }
    let out = on_ui(|el| {
        let mut results = Vec::new();
        for close in [false, true] {
            let opts = RunOptions {
                max_frames: Some(600),
                ..Default::default()
            };
            let user = FakeUser::open();
            let (w, h) = (176, 99);
            let ch = window("user", 900, 700, w, h, 0.0);
            let mut sent_at = None;
            let (result, frames) = session_with(el, vec![ch], opts, |frame| {
                if frame >= 10 && sent_at.is_none() {
                    if let Some(win) = user.find(900, 700, w as i32, h as i32) {
                        if close {
                            user.close(win);
                        } else {
                            user.press_escape(win);
                        }
                        sent_at = Some(frame);
                    }
                }
            });
            results.push((close, result, frames, sent_at));
        }
        results
    });
    let Some(results) = out else {
        return;
    };
    for (close, result, frames, sent_at) in results {
        let report = result.expect("session");
        let sent = sent_at.expect("our window was found on the X server");
        let expected = if close {
            ExitReason::Closed
        } else {
            ExitReason::Escape
        };
        assert_eq!(report.exit, expected);
        assert!(
            frames <= sent + 30,
            "{expected:?} took {} frames to end the session",
            frames - sent
        );
    }
}

#[test]
fn minimised_window_waits_without_spinning_then_resumes() {
    if framebuffer().is_none() {
        if ui().is_some() {
            note!("skipped: needs the private Xvfb to play the window manager");
        }
        return;
    }
    let hidden_ms = 700u64;
    let out = on_ui(move |el| {
        let opts = RunOptions {
            max_frames: Some(30),
            ..Default::default()
        };
        let user = FakeUser::open();
        let (w, h) = (144, 81);
        let ch = window("minimise", 600, 800, w, h, 0.0);
        let mut hidden_at = None;
        let (result, poses) = session_with(el, vec![ch], opts, |frame| {
            if frame == 10 {
                let win = user
                    .find(600, 800, w as i32, h as i32)
                    .expect("our window on the X server");
                user.set_minimised(win, true);
                hidden_at = Some(std::time::Instant::now());
                // Another client restores it later (the loop itself is asleep meanwhile).
                std::thread::spawn(move || {
                    std::thread::sleep(Duration::from_millis(hidden_ms));
                    FakeUser::open().set_minimised(win, false);
                });
            }
        });
        let waited = hidden_at.map(|t| t.elapsed());
        (result, poses, waited)
    });
    let Some((result, poses, waited)) = out else {
        return;
    };
    let report = result.expect("session");
    assert_eq!(report.exit, ExitReason::Frames);
    assert_eq!((report.frames, poses), (30, 30), "no frame while minimised");
    assert!(waited.expect("minimised at frame 10") >= Duration::from_millis(hidden_ms));
    // Asleep while minimised: woken by events or every 100 ms, not thousands of times.
    let expected = hidden_ms / 100;
    assert!(
        (expected / 2..=expected * 4).contains(&report.idle_waits),
        "{} idle wake-ups in {hidden_ms} ms",
        report.idle_waits
    );
    // The longest gap between frames is the minimised time.
    let longest = report.frame_ms.iter().cloned().fold(0.0, f64::max);
    assert!(longest >= hidden_ms as f64, "{longest} ms");
    assert_eq!(report.channels[0].presented, 30);
}

#[test]
fn overlay_key_toggles_the_statistics_panel_on_screen() {
    if framebuffer().is_none() {
        if ui().is_some() {
            note!("skipped: needs the private Xvfb to fake key presses");
        }
        return;
    }
    let fb = framebuffer();
    let out = on_ui(move |el| {
        let opts = RunOptions {
            max_frames: Some(40),
            ..Default::default()
        };
        let user = FakeUser::open();
        let (x, y, w, h) = (300, 520, 160, 90);
        let ch = window("overlay", x, y, w, h, 0.0);
        let (mut before, mut after, mut pressed_at) = (None, None, None);
        let (result, _) = session_with(el, vec![ch], opts, |frame| {
            let grab = || fb.as_deref().map(Screen::grab);
            if frame == 8 {
                before = grab();
            }
            if frame >= 10 && pressed_at.is_none() {
                if let Some(win) = user.find(x, y, w as i32, h as i32) {
                    user.press_key(win, x11_dl::keysym::XK_o);
                    pressed_at = Some(frame);
                }
            }
            if frame == 36 {
                after = grab();
            }
        });
        (result, before, after, pressed_at)
    });
    let Some((result, before, after, pressed_at)) = out else {
        return;
    };
    let report = result.expect("session");
    let pressed = pressed_at.expect("our window was found on the X server");
    let c = &report.channels[0];
    assert_eq!(c.presented, 40);
    // Off until the key, on after it: some frames with and some without.
    assert!(
        c.overlay_frames > 0 && c.overlay_frames <= 40 - pressed,
        "{} overlay frames, key at frame {pressed}",
        c.overlay_frames
    );
    // On screen: the top-left corner (inside the panel's padding) shows sky before and the
    // panel's dark background after.
    let (before, after) = (before.expect("grab"), after.expect("grab"));
    assert!(is_sky(before.rgb(302, 522)), "{:?}", before.rgb(302, 522));
    let dark = after.rgb(302, 522);
    assert!(dark.iter().all(|&v| v < 50), "{dark:?}");
    // Outside the panel the picture is still the terrain view (sky at the top right).
    assert!(
        is_sky(after.rgb(300 + 155, 522)),
        "{:?}",
        after.rgb(455, 522)
    );
}

/// `aerie run --windowed` is an image generator too: the window loop takes the same IG step at
/// the start of every frame (`PoseSource::begin_frame`), so a host's native height-of-terrain
/// questions are answered from the drawn dataset's full-resolution surface while the window
/// presents.
#[test]
fn windowed_run_answers_the_hosts_terrain_questions() {
    use aerie_sim_bridge::codec::native;
    use aerie_sim_bridge::query::{Answer, TerrainReply, TerrainRequest};
    use aerie_sim_bridge::{Pose, PosePosition};
    use std::net::UdpSocket;

    let dir = tempfile::tempdir().unwrap();
    let dem = raw_dem(dir.path());
    let json = dir.path().join("run.json");
    let port = UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let to = format!("127.0.0.1:{port}");
    let s = |p: &Path| p.display().to_string();
    let args = vec![
        "--dem".to_string(),
        s(&dem),
        "--windowed".into(),
        "--window-size".into(),
        "160x90".into(),
        "--frames".into(),
        "40".into(),
        "--listen".into(),
        to.clone(),
        "--protocol".into(),
        "auto".into(),
        "--json".into(),
        s(&json),
    ];
    // The host: local poses over the hill and a question per pose about the sample (64, 40).
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let host = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
            sock.set_read_timeout(Some(Duration::from_millis(10)))
                .unwrap();
            let mut answers = Vec::new();
            let mut buf = [0u8; 256];
            let mut seq = 0u32;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) && seq < 3000 {
                seq += 1;
                let pose = Pose {
                    position: PosePosition::LocalEnu {
                        x: 1920.0,
                        y: 600.0,
                        z: 900.0,
                    },
                    attitude_deg: [0.0, -20.0, 0.0],
                    sim_time_s: f64::from(seq) / 60.0,
                    frame: u64::from(seq),
                    velocity_enu: None,
                    angular_rates_deg_s: None,
                };
                let _ = sock.send_to(&native::encode(&pose, seq), &to);
                let ask = TerrainRequest::HeightOfTerrain {
                    at: PosePosition::LocalEnu {
                        x: 64.0 * 30.0,
                        y: 40.0 * 30.0,
                        z: 900.0,
                    },
                };
                let _ = sock.send_to(&native::encode_query(seq, &ask), &to);
                while let Ok((n, _)) = sock.recv_from(&mut buf) {
                    if let Ok((_, reply)) = native::decode_reply(&buf[..n]) {
                        answers.push(reply);
                    }
                }
            }
            answers
        })
    };
    let result = run_command(args);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let answers = host.join().unwrap();
    let Some(result) = result else {
        return;
    };
    let summary = result.unwrap_or_else(|(c, m)| panic!("exit {c}: {m}"));
    assert_eq!(summary["frames"], 40);
    assert_eq!(summary["validation"]["errors"], 0);
    let ig = &summary["ig"];
    assert!(ig["native_answered"].as_u64().unwrap() > 0, "{ig:#}");
    assert!(
        ig["ig_frames"].as_u64().unwrap() >= 40,
        "one IG step per presented frame: {ig:#}"
    );
    // The raw DEM's sample (64, 40): 100 + 300·e^(−(0² + 24²)/800), as f32.
    let expect = f64::from(100.0f32 + 300.0 * (-(24.0f32 * 24.0) / 800.0).exp());
    let heights: Vec<f64> = answers
        .iter()
        .filter_map(|r| match r {
            TerrainReply::HeightOfTerrain(Answer::Ready(s)) => Some(s.height_m),
            _ => None,
        })
        .collect();
    assert!(!heights.is_empty(), "answers: {answers:?}");
    for h in heights {
        assert!((h - expect).abs() < 1e-4, "HOT {h} vs the sample {expect}");
    }
}
