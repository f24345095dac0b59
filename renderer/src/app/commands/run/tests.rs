//! The run command's decisions without a device: flag checks, settings over the config, the
//! pose source of the window path.

use std::net::{IpAddr, Ipv4Addr};

use aerie_config::RenderConfig;
use aerie_sim_bridge::codec::native;
use aerie_sim_bridge::codec::ProtocolChoice;
use aerie_sim_bridge::{Pose, PosePosition};
use aerie_terrain::dataset::Dataset;
use aerie_terrain::Heightfield;
use glam::DVec3;
use std::time::Duration;

use crate::app::commands::input_args::InputArgs;
use crate::app::commands::run::args::RunArgs;
use crate::app::commands::run::plan::{plan, Plan};
use crate::app::commands::run::poses::{RunPoses, StraightPassSource};
use crate::app::commands::run::settings::{resolve_settings, RunSettings};
use crate::app::failure::Failure;
use crate::app::window::pose_source::PoseSource;
use crate::render::frame::FrameStats;
use crate::sim::flight::StraightPass;
use crate::sim::pose_input::{GeoMapping, InputProtocol, InputSpec, SimInput};
use crate::tools::stats_csv::StatsWriter;

fn flat() -> Dataset {
    let n = 65;
    Dataset::from_heightfield(
        Heightfield {
            width: n,
            height: n,
            spacing_x: 30.0,
            spacing_y: 30.0,
            heights: vec![500.0; n * n],
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        },
        "flat".into(),
    )
}

fn pose(seq: u64, position: PosePosition) -> Pose {
    Pose {
        position,
        attitude_deg: [45.0, -3.0, 7.0],
        sim_time_s: seq as f64 / 60.0,
        frame: seq,
        velocity_enu: Some([100.0, 0.0, 0.0]),
        angular_rates_deg_s: None,
    }
}

#[derive(clap::Parser)]
struct Cli {
    #[command(flatten)]
    args: RunArgs,
}

fn plan_of(extra: &[&str]) -> Result<Plan, Failure> {
    use clap::Parser;
    let argv = ["run", "--dem", "x.hgt"].iter().chain(extra);
    plan(&Cli::try_parse_from(argv).expect("parses").args)
}

#[test]
fn bad_input_flag_combinations_stop_before_anything_opens() {
    for (args, says) in [
        (
            &["--sync-frames", "1"][..],
            "--sync-frames: needs a pose input",
        ),
        (
            &["--headless"],
            "--headless: give --frames N or --seconds S",
        ),
        (&["--size", "160x90"], "--size: only with --headless"),
        (&["--as-fast-as-possible"], "only with --headless"),
        (&["--headless", "--frames", "2", "--size", "0x9"], "--size:"),
        (
            &["--headless", "--frames", "2", "--windowed"],
            "exclude each other",
        ),
        (&["--max-extrapolation-ms=-1"], "--max-extrapolation-ms: -1"),
        (&["--fps", "0"], "--fps: 0"),
        (
            &["--protocol", "shm", "--listen", "127.0.0.1:9"],
            "UDP only",
        ),
        (
            &["--protocol", "cigi", "--shm-name", "x"],
            "--shm-name: only with",
        ),
        (
            &["--multicast-if", "127.0.0.1", "--protocol", "native"],
            "only with --multicast",
        ),
        (
            // A folder that cannot be made (under a file): named in the error.
            &["--stats", "/dev/null/sub/s.csv"],
            "--stats /dev/null/sub/s.csv: cannot create folder /dev/null/sub",
        ),
    ] {
        let Err(f) = plan_of(args) else {
            panic!("{args:?} accepted")
        };
        assert_eq!(f.code, 2, "{args:?}: {}", f.message);
        assert!(f.message.contains(says), "{args:?}: {}", f.message);
    }
    // Input flags: defaults and what turns the input on.
    let spec = |extra: &[&str]| {
        use clap::Parser;
        let argv = ["run", "--dem", "x"].iter().chain(extra);
        let args = Cli::try_parse_from(argv).unwrap().args;
        resolve_settings(&args, &RenderConfig::default())
            .unwrap()
            .input
    };
    assert!(spec(&[]).is_none());
    let s = spec(&["--protocol", "cigi"]).unwrap();
    assert_eq!(s.listen, "127.0.0.1:47800".parse().unwrap());
    assert_eq!(s.cap_s, 0.1);
    let s = spec(&["--multicast", "239.1.2.3", "--sync-frames", "2"]).unwrap();
    assert_eq!(s.listen, "0.0.0.0:47800".parse().unwrap());
    assert_eq!(s.protocol, InputProtocol::Udp(ProtocolChoice::Auto));
    assert_eq!(s.sync_frames, Some(2));
    let s = spec(&["--shm-name", "sim"]).unwrap();
    assert_eq!(
        (s.protocol, s.shm_name.as_str()),
        (InputProtocol::Shm, "sim")
    );
    assert!(plan_of(&[
        "--headless",
        "--frames",
        "3",
        "--size",
        "160x90",
        "--protocol",
        "shm"
    ])
    .is_ok());
}

fn settings_of(config: &str, extra: &[&str]) -> Result<RunSettings, Failure> {
    use clap::Parser;
    let cfg = aerie_config::parse(config, "ig.toml").unwrap();
    let argv = ["run", "--dem", "x"].iter().chain(extra);
    resolve_settings(&Cli::try_parse_from(argv).unwrap().args, &cfg)
}

/// The world bound: the default, else `input.world_bound_m`, else `--world-bound-m`; a bad
/// flag value is refused by the parser.
#[test]
fn world_bound_comes_from_the_flag_the_config_or_the_default() {
    let bound = |cfg: &str, extra: &[&str]| {
        settings_of(cfg, extra)
            .unwrap()
            .input
            .expect("an input")
            .world_bound_m
    };
    let udp = "[input]\nprotocol = \"native\"\n";
    assert_eq!(bound(udp, &[]), 1.0e7);
    let cfg = "[input]\nprotocol = \"native\"\nworld_bound_m = 5e7\n";
    assert_eq!(bound(cfg, &[]), 5.0e7);
    assert_eq!(bound(cfg, &["--world-bound-m", "2e3"]), 2.0e3);
    use clap::Parser;
    for bad in ["1e300", "0", "-5", "nan", "x"] {
        let Err(e) = Cli::try_parse_from(["run", "--dem", "x", "--world-bound-m", bad]) else {
            panic!("--world-bound-m {bad} accepted");
        };
        assert!(e.to_string().contains("--world-bound-m"), "{e}");
    }
}

/// `[input]` of the config is used; each flag given overrides its key; a flag choosing the
/// other transport drops the config's keys of the first.
#[test]
fn config_input_is_used_and_flags_override_it() {
    let cfg = "[render]\nfps = 30\n[input]\nprotocol = \"cigi\"\nlisten = \"127.0.0.1:47999\"\nallow = [\"127.0.0.2\"]\nmax_extrapolation_ms = 40\nsync_frames = 2\nwait_pose_s = 3\n";
    let s = settings_of(cfg, &[]).unwrap();
    let i = s.input.as_ref().expect("the config turns the input on");
    assert_eq!(
        i.protocol,
        InputProtocol::Udp(ProtocolChoice::Only(
            aerie_sim_bridge::codec::Protocol::Cigi
        ))
    );
    assert_eq!(i.listen, "127.0.0.1:47999".parse().unwrap());
    assert_eq!(i.allow, ["127.0.0.2".parse::<IpAddr>().unwrap()]);
    assert_eq!((i.cap_s, i.sync_frames), (0.04, Some(2)));
    assert_eq!(
        (s.max_extrapolation_ms, s.wait_pose_s, s.fps),
        (40.0, 3.0, 30.0)
    );

    let s = settings_of(
        cfg,
        &[
            "--protocol",
            "native",
            "--listen",
            "127.0.0.1:5000",
            "--allow",
            "127.0.0.3",
            "--max-extrapolation-ms",
            "0",
            "--sync-frames",
            "0",
            "--wait-pose-s",
            "1",
            "--fps",
            "90",
        ],
    )
    .unwrap();
    let i = s.input.as_ref().unwrap();
    assert_eq!(
        i.protocol,
        InputProtocol::Udp(ProtocolChoice::Only(
            aerie_sim_bridge::codec::Protocol::Aerie
        ))
    );
    assert_eq!(i.listen, "127.0.0.1:5000".parse().unwrap());
    assert_eq!(i.allow, ["127.0.0.3".parse::<IpAddr>().unwrap()]);
    assert_eq!((i.cap_s, i.sync_frames), (0.0, Some(0)));
    assert_eq!(
        (s.max_extrapolation_ms, s.wait_pose_s, s.fps),
        (0.0, 1.0, 90.0)
    );

    // --shm-name switches to shared memory: the config's UDP keys no longer apply.
    let i = settings_of(cfg, &["--shm-name", "sim"])
        .unwrap()
        .input
        .unwrap();
    assert_eq!(
        (i.protocol, i.shm_name.as_str()),
        (InputProtocol::Shm, "sim")
    );
    // A config on shared memory and --listen on the command line: UDP.
    let i = settings_of(
        "[input]\nshm_name = \"sim\"\n",
        &["--listen", "127.0.0.1:7"],
    )
    .unwrap()
    .input
    .unwrap();
    assert_eq!(i.protocol, InputProtocol::Udp(ProtocolChoice::Auto));
    assert_eq!(i.listen, "127.0.0.1:7".parse().unwrap());
    // Multicast from the config: bound on all interfaces; interface from the flag.
    let i = settings_of(
        "[input]\nmulticast = \"239.1.2.3\"\n",
        &["--multicast-if", "127.0.0.1"],
    )
    .unwrap()
    .input
    .unwrap();
    assert_eq!(i.listen, "0.0.0.0:47800".parse().unwrap());
    assert_eq!(i.multicast_interface, Ipv4Addr::LOCALHOST);
    // Tuning keys alone do not turn the input on; defaults without anything.
    let s = settings_of("[input]\nmax_extrapolation_ms = 5\n", &[]).unwrap();
    assert!(s.input.is_none());
    assert_eq!(
        (s.max_extrapolation_ms, s.wait_pose_s, s.fps),
        (5.0, 10.0, 60.0)
    );
    // Sync frames beyond the history, from a flag: refused naming the flag.
    let f = settings_of("[input]\nprotocol = \"cigi\"\n", &["--sync-frames", "64"]).unwrap_err();
    assert_eq!(f.code, 2);
    assert!(f.message.starts_with("--sync-frames: 64"), "{}", f.message);
}

/// Window path: a frame's `--stats` row waits for the frame's statistics (the triangles of
/// every channel drawn, summed); a frame never reported drawn keeps the column empty.
#[test]
fn window_frames_get_their_triangles_in_the_stats_rows() {
    let ds = flat();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("s.csv");
    let pass = StraightPass::over(&ds, 70.0, -10.0, 150.0, 600.0, 10.0);
    let mut src = RunPoses::new(
        None,
        StraightPassSource {
            pass,
            period_s: 10.0,
        },
        0.0,
        Some(StatsWriter::create(&csv, None).unwrap()),
    );
    let stats = |triangles| FrameStats {
        triangles,
        ..FrameStats::default()
    };
    let _ = PoseSource::pose(&mut src, 0, 0.0);
    src.frame_drawn(0, &[stats(1200), stats(34)]);
    let _ = PoseSource::pose(&mut src, 1, 0.1);
    // Frame 1 is never reported drawn (e.g. every window minimised).
    let _ = PoseSource::pose(&mut src, 2, 0.2);
    src.frame_drawn(2, &[stats(7)]);
    src.finish().unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let col = crate::tools::stats_csv::HEADER
        .split(',')
        .position(|h| h == "triangles")
        .unwrap();
    let tri: Vec<String> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(col).unwrap().to_string())
        .collect();
    assert_eq!(tri, ["1234", "", "7"]);
}

/// The window path's pose source: default view and a "waiting" row until the first pose,
/// then the pose as sent (cap 0), and a bad-input failure for a geodetic pose on a dataset
/// without geo-reference (the window loop ends the session on it).
#[test]
fn stream_source_waits_then_follows_then_fails_on_unplaceable_poses() {
    let ds = flat();
    let spec = InputSpec {
        protocol: InputProtocol::Udp(ProtocolChoice::Auto),
        listen: "127.0.0.1:0".parse().unwrap(),
        multicast: None,
        multicast_interface: Ipv4Addr::UNSPECIFIED,
        allow: Vec::new(),
        shm_name: String::new(),
        cap_s: 0.0,
        sync_frames: None,
        world_bound_m: 1.0e7,
        xplane_rpos: None,
        host_heights: Default::default(),
    };
    let input = SimInput::open(&spec, GeoMapping::of_dataset(&ds)).unwrap();
    let to = input.local_addr().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("s.csv");
    let pass = StraightPass::over(&ds, 70.0, -10.0, 150.0, 600.0, 10.0);
    let mut src = RunPoses::new(
        Some(input),
        StraightPassSource {
            pass,
            period_s: 10.0,
        },
        0.0,
        Some(StatsWriter::create(&csv, None).unwrap()),
    );
    let held = PoseSource::pose(&mut src, 0, 0.0);
    assert_eq!(held, src.default_view());
    assert_eq!((src.waiting_frames, src.input_frames), (1, 0));
    assert!(src.failure().is_none());

    let socket = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let local = PosePosition::LocalEnu {
        x: 1000.0,
        y: 900.0,
        z: 1500.0,
    };
    socket
        .send_to(&native::encode(&pose(1, local), 1), to)
        .unwrap();
    let mut frame = 1;
    let got = loop {
        let p = PoseSource::pose(&mut src, frame, 0.0);
        frame += 1;
        if src.input_frames > 0 {
            break p;
        }
        assert!(frame < 2000, "no pose arrived");
        std::thread::sleep(Duration::from_millis(1));
    };
    assert_eq!(got.position, DVec3::new(1000.0, 900.0, 1500.0));
    assert!((got.attitude.roll.to_degrees() - 7.0).abs() < 1e-12);
    assert!(src.pose_age_ms().is_some());

    let geodetic = PosePosition::Geodetic {
        lat_deg: 47.0,
        lon_deg: 11.0,
        alt_m: 1500.0,
    };
    socket
        .send_to(&native::encode(&pose(2, geodetic), 2), to)
        .unwrap();
    let why = loop {
        let _ = PoseSource::pose(&mut src, frame, 0.0);
        frame += 1;
        if let Some(w) = src.failure() {
            break w;
        }
        assert!(frame < 4000, "the geodetic pose never failed");
        std::thread::sleep(Duration::from_millis(1));
    };
    assert!(
        why.contains("geodetic") && why.contains("flat: no geo-reference"),
        "{why}"
    );
    assert_eq!(src.fail.as_ref().unwrap().code, 2);
    src.finish().unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<&str> = text.lines().skip(1).collect();
    assert!(rows[0].contains(",waiting,"), "{}", rows[0]);
    assert!(rows.iter().any(|r| r.contains(",1000,900,1500,")), "{text}");
}

/// The pose-input flags are the shared ones: the spellings `aerie listen` used before parse to
/// the same values here too, and `--help` shows only the current names, under "Pose input".
#[test]
fn run_takes_the_shared_input_flags_and_their_old_spellings() {
    use clap::{CommandFactory, Parser};
    let input = |extra: &[&str]| -> InputArgs {
        let argv = ["run", "--dem", "x"].iter().chain(extra);
        Cli::try_parse_from(argv).expect("parses").args.input
    };
    assert_eq!(
        input(&[
            "--bind",
            "127.0.0.1:5000",
            "--protocol",
            "aerie",
            "--cap-ms",
            "20"
        ]),
        input(&[
            "--listen",
            "127.0.0.1:5000",
            "--protocol",
            "native",
            "--max-extrapolation-ms",
            "20"
        ])
    );
    assert_eq!(input(&["--shm", "sim"]), input(&["--shm-name", "sim"]));
    let s = settings_of("", &["--shm", "sim"]).unwrap().input.unwrap();
    assert_eq!(
        (s.protocol, s.shm_name.as_str()),
        (InputProtocol::Shm, "sim")
    );

    let help = Cli::command().render_long_help().to_string();
    let heading = help.find("Pose input:").expect("a Pose input section");
    for name in [
        "--listen",
        "--shm-name",
        "--max-extrapolation-ms",
        "--sync-frames",
        "--wait-pose-s",
    ] {
        let at = help.find(name).unwrap_or_else(|| panic!("{name}: {help}"));
        assert!(at > heading, "{name} outside the Pose input section");
    }
    // The run-only flags after the input section keep their own heading.
    assert!(help.find("--headless").unwrap() < heading, "{help}");
    for old in ["--bind", "--cap-ms", "--shm "] {
        assert!(!help.contains(old), "{old} shown in\n{help}");
    }
}

/// The host heights' datum: msl by default, else `input.host_heights`, else `--host-heights`;
/// a bad value is refused by the parser, the flag without a pose input by the settings.
#[test]
fn host_heights_come_from_the_flag_the_config_or_the_default() {
    use crate::sim::pose_input::HostHeights;
    let heights = |cfg: &str, extra: &[&str]| {
        settings_of(cfg, extra)
            .unwrap()
            .input
            .expect("an input")
            .host_heights
    };
    let udp = "[input]\nprotocol = \"cigi\"\n";
    assert_eq!(heights(udp, &[]), HostHeights::Msl);
    let cfg = "[input]\nprotocol = \"cigi\"\nhost_heights = \"ellipsoidal\"\n";
    assert_eq!(heights(cfg, &[]), HostHeights::Ellipsoidal);
    assert_eq!(heights(cfg, &["--host-heights", "msl"]), HostHeights::Msl);
    assert_eq!(
        heights(udp, &["--host-heights", "ELLIPSOIDAL"]),
        HostHeights::Ellipsoidal
    );
    use clap::Parser;
    let Err(e) = Cli::try_parse_from(["run", "--dem", "x", "--host-heights", "wgs84"]) else {
        panic!("--host-heights wgs84 accepted");
    };
    assert!(e.to_string().contains("msl, ellipsoidal"), "{e}");
    let e = settings_of("", &["--host-heights", "ellipsoidal"]).unwrap_err();
    assert!(
        format!("{e:?}").contains("--host-heights: needs a pose input"),
        "{e:?}"
    );
}

/// The image generator starts every load with the views around the eye (`warm_start.rs`): the
/// host may turn the view anywhere; the library's default, and a still image, do not.
#[test]
fn the_image_generator_selects_the_views_around_the_eye_after_a_load() {
    use clap::Parser;
    let argv = ["run", "--dem", "x.hgt"];
    let args = Cli::try_parse_from(argv).expect("parses").args;
    let p = plan(&args).expect("plans");
    let desc = crate::app::commands::run::plan::renderer_desc(&args, &p, (64, 36), None);
    assert!(desc.warm_start);
    assert!(!crate::render::desc::RendererDesc::default().warm_start);
}
