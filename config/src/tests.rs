//! Unit tests: every error path names the file and the key.

use super::*;
use proptest::prelude::*;

const FILE: &str = "site.toml";

fn err(text: &str) -> ConfigError {
    match parse(text, FILE) {
        Ok(cfg) => panic!("expected an error for {text:?}, got {cfg:?}"),
        Err(e) => e,
    }
}

/// Asserts the error is one line, starts with the file name and names `key`.
fn assert_names(e: &ConfigError, key: &str) -> String {
    let msg = e.to_string();
    assert!(!msg.contains('\n'), "not one line: {msg:?}");
    assert!(msg.starts_with(FILE), "no file name: {msg}");
    assert!(msg.contains(key), "no key {key:?}: {msg}");
    msg
}

fn assert_invalid(text: &str, key: &str) -> ConfigError {
    let e = err(text);
    assert_names(&e, key);
    assert_eq!(e.key(), Some(key), "{e}");
    e
}

#[test]
fn empty_file_gives_defaults() {
    let cfg = parse("", FILE).unwrap();
    assert_eq!(cfg, RenderConfig::default());
    assert_eq!((cfg.render.width, cfg.render.height), (1920, 1080));
    assert_eq!(cfg.render.tile_size, 17);
    assert_eq!(cfg.render.staging_budget_bytes(), 8 << 20);
    assert!(!cfg.render.validation && cfg.render.gpu.is_none() && cfg.dem.path.is_none());
}

#[test]
fn full_file_parses() {
    let text = r#"
        # every key
        [render]
        size = "1280x720"
        fov_deg = 60
        tau_px = 0.5
        tile_size = 33
        staging_budget_mib = 64
        validation = true
        gpu = "llvmpipe"

        [dem]
        path = "data/puget.tif"
    "#;
    let cfg = parse(text, FILE).unwrap();
    let r = &cfg.render;
    assert_eq!((r.width, r.height), (1280, 720));
    assert_eq!((r.fov_deg, r.tau_px), (60.0, 0.5));
    assert_eq!((r.tile_size, r.staging_budget_mib), (33, 64));
    assert!(r.validation);
    assert_eq!(r.gpu.as_deref(), Some("llvmpipe"));
    assert_eq!(cfg.dem.path.as_deref(), Some(Path::new("data/puget.tif")));
}

#[test]
fn width_and_height_keys_and_dotted_or_inline_forms() {
    let a = parse("[render]\nwidth = 800\nheight = 600\n", FILE).unwrap();
    let b = parse("render.size = \"800X600\"\n", FILE).unwrap();
    let c = parse("render = { width = 800, height = 600 }\n", FILE).unwrap();
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert_eq!((a.render.width, a.render.height), (800, 600));
}

#[test]
fn unknown_keys_are_named_with_their_path() {
    let e = assert_invalid("[render]\nsize = \"1x1\"\nfov = 90\n", "render.fov");
    assert!(e.to_string().contains("unknown field `fov`"), "{e}");
    assert_eq!(e.location(), Some(Location { line: 3, column: 1 }), "{e}");
    assert_invalid("[renderer]\nfov_deg = 90\n", "renderer");
    assert_invalid("debug = true\n", "debug");
    assert_invalid("[dem]\npath = \"a\"\nformat = \"tif\"\n", "dem.format");
    assert_invalid("[render.extra]\nx = 1\n", "render.extra");
    assert_invalid("render.dpi = 96\n", "render.dpi");
    assert_invalid("[render]\n\"odd key\" = 1\n", "render.\"odd key\"");
}

#[test]
fn wrong_types_are_named_with_their_path() {
    for (text, key, line) in [
        ("[render]\ntile_size = \"17\"\n", "render.tile_size", 2),
        ("[render]\nfov_deg = \"wide\"\n", "render.fov_deg", 2),
        ("[render]\n\nvalidation = \"yes\"\n", "render.validation", 3),
        ("[render]\nsize = 1920\n", "render.size", 2),
        ("[render]\nwidth = -1\nheight = 10\n", "render.width", 2),
        (
            "[render]\nstaging_budget_mib = 1.5\n",
            "render.staging_budget_mib",
            2,
        ),
        ("[render]\ngpu = 3\n", "render.gpu", 2),
        ("[dem]\npath = 3\n", "dem.path", 2),
        ("render = 3\n", "render", 1),
        ("dem = \"x.tif\"\n", "dem", 1),
        ("render.tile_size = 17.0\n", "render.tile_size", 1),
        ("render = { tau_px = \"1\" }\n", "render.tau_px", 1),
    ] {
        let e = assert_invalid(text, key);
        assert!(e.to_string().contains("invalid"), "{e}");
        assert!(
            !e.to_string().contains("Raw"),
            "internal type name leaked: {e}"
        );
        assert_eq!(e.location().map(|l| l.line), Some(line), "{e}");
    }
}

#[test]
fn tile_size_must_be_power_of_two_plus_one() {
    let e = assert_invalid("[render]\ntile_size = 16\n", "render.tile_size");
    let msg = e.to_string();
    assert!(msg.contains("got 16") && msg.contains("2^j+1"), "{msg}");
    assert_eq!(
        e.location(),
        Some(Location {
            line: 2,
            column: 13
        })
    );
    for bad in [0, 1, 2, 4, 18, 255, 513, 1025] {
        assert_invalid(
            &format!("[render]\ntile_size = {bad}\n"),
            "render.tile_size",
        );
    }
    for good in TILE_SIZES {
        let cfg = parse(&format!("[render]\ntile_size = {good}\n"), FILE).unwrap();
        assert_eq!(cfg.render.tile_size, good);
    }
}

#[test]
fn fov_must_be_strictly_between_0_and_180() {
    for bad in ["0", "0.0", "180", "180.0", "-30", "nan", "inf", "360"] {
        let e = assert_invalid(&format!("[render]\nfov_deg = {bad}\n"), "render.fov_deg");
        assert!(e.to_string().contains("less than 180"), "{e}");
        assert_eq!(e.location().map(|l| l.line), Some(2));
    }
    for good in ["0.001", "1", "90.0", "179.9"] {
        parse(&format!("[render]\nfov_deg = {good}\n"), FILE).unwrap();
    }
}

#[test]
fn size_must_be_positive_and_well_formed() {
    let e = assert_invalid("[render]\nsize = \"0x10\"\n", "render.size");
    assert!(e.to_string().contains("\"0x10\""), "{e}");
    for bad in [
        "10x0",
        "1920*1080",
        "1920x",
        "x1080",
        "1920 x 1080",
        "+1920x1080",
        "16385x10",
        "99999999999999999999x1",
        "",
    ] {
        assert_invalid(&format!("[render]\nsize = {bad:?}\n"), "render.size");
    }
    let cfg = parse("[render]\nsize = \"16384x1\"\n", FILE).unwrap();
    assert_eq!((cfg.render.width, cfg.render.height), (16384, 1));
}

#[test]
fn width_and_height_rules() {
    assert_invalid("[render]\nwidth = 0\nheight = 10\n", "render.width");
    assert_invalid("[render]\nwidth = 10\nheight = 16385\n", "render.height");
    assert_invalid("[render]\nwidth = 10\n", "render.height");
    assert_invalid("[render]\nheight = 10\n", "render.width");
    let e = assert_invalid(
        "[render]\nsize = \"10x10\"\nwidth = 10\nheight = 10\n",
        "render.size",
    );
    assert!(e.to_string().contains("not both"), "{e}");
}

#[test]
fn tau_must_be_positive_and_finite() {
    for bad in ["0", "-1.0", "nan", "inf"] {
        assert_invalid(&format!("[render]\ntau_px = {bad}\n"), "render.tau_px");
    }
}

#[test]
fn staging_budget_range() {
    for bad in [0, 1025] {
        assert_invalid(
            &format!("[render]\nstaging_budget_mib = {bad}\n"),
            "render.staging_budget_mib",
        );
    }
    for good in [1, MAX_STAGING_BUDGET_MIB] {
        parse(&format!("[render]\nstaging_budget_mib = {good}\n"), FILE).unwrap();
    }
}

#[test]
fn empty_strings_are_rejected() {
    assert_invalid("[render]\ngpu = \" \"\n", "render.gpu");
    assert_invalid("[dem]\npath = \"\"\n", "dem.path");
}

#[test]
fn syntax_error_reports_line_and_column() {
    let text = "[render]\nfov_deg = 90.0\ntile_size = = 17\n";
    let e = err(text);
    let msg = assert_names(&e, "TOML syntax error");
    assert!(matches!(e, ConfigError::Syntax { .. }), "{e:?}");
    assert_eq!(e.location().map(|l| l.line), Some(3), "{msg}");
    assert!(msg.starts_with("site.toml:3:"), "{msg}");

    let e = err("[render\nfov_deg = 1\n");
    assert!(e.to_string().starts_with("site.toml:1:"), "{e}");
    assert!(!e.to_string().contains('\n'));
}

#[test]
fn duplicate_key_is_a_syntax_error_naming_the_key() {
    let e = err("[render]\nfov_deg = 90\nfov_deg = 60\n");
    let msg = assert_names(&e, "fov_deg");
    assert!(msg.starts_with("site.toml:3:"), "{msg}");
}

#[test]
fn missing_file_names_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nope.toml");
    let e = load(&path).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ConfigError::Io { .. }), "{e:?}");
    assert!(msg.contains(&path.display().to_string()), "{msg}");
    assert!(!msg.contains('\n'));
}

#[test]
fn load_names_the_file_in_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, "[render]\ntile_size = 16\n").unwrap();
    let msg = load(&path).unwrap_err().to_string();
    assert!(
        msg.starts_with(&format!("{}:2:13: render.tile_size:", path.display())),
        "{msg}"
    );

    std::fs::write(&path, "[render]\nsize = \"640x480\"\n").unwrap();
    let cfg = load(&path).unwrap();
    assert_eq!((cfg.render.width, cfg.render.height), (640, 480));
}

#[test]
fn location_from_offset_counts_characters() {
    let text = "a\néé = 1\n";
    assert_eq!(
        Location::from_offset(text, 0),
        Location { line: 1, column: 1 }
    );
    assert_eq!(
        Location::from_offset(text, 2),
        Location { line: 2, column: 1 }
    );
    // Byte 7 is the `=`, after two two-byte characters and a space.
    assert_eq!(
        Location::from_offset(text, 7),
        Location { line: 2, column: 4 }
    );
    // Inside a multi-byte character: moved back to its start.
    assert_eq!(
        Location::from_offset(text, 3),
        Location { line: 2, column: 1 }
    );
    assert_eq!(
        Location::from_offset(text, 999),
        Location { line: 3, column: 1 }
    );
}

#[test]
fn input_table_parses_and_round_trips() {
    let text = r#"
        [render]
        fps = 30

        [input]
        protocol = "CIGI"
        listen = "0.0.0.0:47900"
        multicast = "239.1.2.3"
        multicast_if = "127.0.0.1"
        allow = ["127.0.0.1", "::1"]
        max_extrapolation_ms = 0
        sync_frames = 2
        wait_pose_s = 2.5
        world_bound_m = 5e7
        host_heights = "Ellipsoidal"
    "#;
    let cfg = parse(text, FILE).unwrap();
    let i = &cfg.input;
    assert_eq!(i.host_heights, Some(HostHeightsName::Ellipsoidal));
    assert_eq!(i.protocol, Some(InputProtocolName::Cigi));
    assert_eq!(i.listen, Some("0.0.0.0:47900".parse().unwrap()));
    assert_eq!(i.multicast, Some("239.1.2.3".parse().unwrap()));
    assert_eq!(i.multicast_if, Some("127.0.0.1".parse().unwrap()));
    assert_eq!(i.allow.len(), 2);
    assert_eq!(
        (i.max_extrapolation_ms, i.sync_frames, i.wait_pose_s),
        (Some(0.0), Some(2), Some(2.5))
    );
    assert_eq!(i.world_bound_m, Some(5e7));
    assert_eq!(cfg.render.fps, Some(30.0));
    assert!(i.wants_input());
    assert_eq!(parse(&cfg.to_toml().unwrap(), FILE).unwrap(), cfg);
    // No [input]: nothing set, no input wanted; an [input] of tuning keys only wants none.
    assert!(parse("", FILE).unwrap().input.is_empty());
    let tuning = parse("[input]\nmax_extrapolation_ms = 50\n", FILE).unwrap();
    assert!(!tuning.input.wants_input() && !tuning.input.is_empty());
    // shm_name alone means shared memory.
    let shm = parse("[input]\nshm_name = \"sim\"\n", FILE).unwrap();
    assert_eq!(shm.input.shm_name.as_deref(), Some("sim"));
}

#[test]
fn input_errors_name_the_key_line_and_reason() {
    for (text, key, says) in [
        (
            "[input]\nprotocol = \"udp\"\n",
            "input.protocol",
            "unknown protocol \"udp\"",
        ),
        (
            "[input]\nlisten = \"localhost\"\n",
            "input.listen",
            "expected ADDR:PORT",
        ),
        (
            "[input]\nlisten = \"127.0.0.1:99999\"\n",
            "input.listen",
            "99999",
        ),
        (
            "[input]\nmulticast = \"10.0.0.1\"\n",
            "input.multicast",
            "not a multicast group",
        ),
        (
            "[input]\nmulticast = \"239.1.2\"\n",
            "input.multicast",
            "IPv4 address",
        ),
        (
            "[input]\nallow = [\"10.0.0.300\"]\n",
            "input.allow",
            "10.0.0.300",
        ),
        (
            "[input]\nmax_extrapolation_ms = -5\n",
            "input.max_extrapolation_ms",
            "≥ 0, got -5",
        ),
        (
            "[input]\nmax_extrapolation_ms = nan\n",
            "input.max_extrapolation_ms",
            "got NaN",
        ),
        ("[input]\nsync_frames = -1\n", "input.sync_frames", "0..=63"),
        ("[input]\nsync_frames = 64\n", "input.sync_frames", "got 64"),
        (
            "[input]\nwait_pose_s = 0\n",
            "input.wait_pose_s",
            "greater than 0",
        ),
        (
            "[input]\nworld_bound_m = 1e300\n",
            "input.world_bound_m",
            "at most 1e9, got 1e300",
        ),
        (
            "[input]\nhost_heights = \"wgs84\"\n",
            "input.host_heights",
            "expected msl, ellipsoidal",
        ),
        (
            "[input]\nworld_bound_m = 0\n",
            "input.world_bound_m",
            "greater than 0",
        ),
        (
            "[input]\nshm_name = \" \"\n",
            "input.shm_name",
            "must not be empty",
        ),
        (
            "[input]\nmulticast_if = \"127.0.0.1\"\n",
            "input.multicast_if",
            "only with input.multicast",
        ),
        (
            "[input]\nprotocol = \"shm\"\nlisten = \"127.0.0.1:9\"\n",
            "input.listen",
            "UDP only",
        ),
        (
            "[input]\nshm_name = \"x\"\nallow = [\"::1\"]\n",
            "input.allow",
            "UDP only",
        ),
        (
            "[input]\nprotocol = \"cigi\"\nshm_name = \"x\"\n",
            "input.shm_name",
            "only with protocol",
        ),
        ("[input]\nport = 5\n", "input", "unknown field `port`"),
        (
            "[input]\nsync_frames = \"2\"\n",
            "input.sync_frames",
            "invalid type",
        ),
        ("[render]\nfps = 0\n", "render.fps", "got 0"),
        ("[render]\nfps = 5000\n", "render.fps", "at most 1000"),
    ] {
        let e = err(text);
        let msg = assert_names(&e, key);
        assert!(msg.contains(says), "{text:?}: {msg}");
        // The value's line (the last line of every case) is named.
        let line = text.lines().count();
        assert!(
            msg.starts_with(&format!("{FILE}:{line}:")),
            "{text:?}: no line {line}: {msg}"
        );
    }
}

fn arb_config() -> impl Strategy<Value = RenderConfig> {
    (
        (1..=MAX_DIMENSION, 1..=MAX_DIMENSION),
        (1e-6..179.999_f64, 1e-6..1e3_f64),
        (
            prop::sample::select(TILE_SIZES.to_vec()),
            1..=MAX_STAGING_BUDGET_MIB,
        ),
        any::<bool>(),
        prop::option::of("[a-zA-Z0-9 _-]{0,12}[a-zA-Z0-9]"),
        prop::option::of("[a-z0-9_/.-]{1,20}"),
    )
        .prop_map(
            |(
                (width, height),
                (fov_deg, tau_px),
                (tile_size, staging_budget_mib),
                validation,
                gpu,
                path,
            )| {
                RenderConfig {
                    render: RenderSettings {
                        width,
                        height,
                        fov_deg,
                        tau_px,
                        tile_size,
                        staging_budget_mib,
                        validation,
                        gpu,
                        fps: None,
                    },
                    dem: DemSettings {
                        path: path.map(PathBuf::from),
                    },
                    input: InputSettings::default(),
                    channels: Vec::new(),
                    databases: Default::default(),
                    entities: Default::default(),
                    landcover: None,
                }
            },
        )
}

proptest! {
    #[test]
    fn to_toml_round_trips(cfg in arb_config()) {
        let text = cfg.to_toml().unwrap();
        prop_assert_eq!(parse(&text, FILE).unwrap(), cfg);
    }

    #[test]
    fn tile_size_accepted_iff_listed(m in prop_oneof![0..600u32, any::<u32>()]) {
        let r = parse(&format!("[render]\ntile_size = {m}\n"), FILE);
        prop_assert_eq!(r.is_ok(), is_valid_tile_size(m));
        prop_assert_eq!(is_valid_tile_size(m), (3..=257).contains(&m) && (m - 1).is_power_of_two());
    }
}

#[test]
fn landcover_table_parses_round_trips_and_names_bad_keys() {
    let text = r#"
        [landcover]
        raster = "cover/worldcover.tif"
        preset = "worldcover"

        [landcover.codes]
        10 = "rock"
        200 = "none"
    "#;
    let cfg = parse(text, FILE).unwrap();
    let lc = cfg.landcover.as_ref().expect("[landcover] read");
    assert_eq!(
        lc.raster.as_deref(),
        Some(Path::new("cover/worldcover.tif"))
    );
    let t = lc.map.table();
    // 10 overridden to rock (5), 40 from the preset (crops, 3), 200 explicitly none.
    assert_eq!((t[10], t[40], t[200]), (5, 3, landcover::NO_CLASS));
    assert_eq!(parse(&cfg.to_toml().unwrap(), FILE).unwrap(), cfg);
    assert!(parse("", FILE).unwrap().landcover.is_none());
    for (text, key) in [
        ("[landcover]\npreset = \"modis\"\n", "landcover.preset"),
        (
            "[landcover.codes]\n300 = \"forest\"\n",
            "landcover.codes.300",
        ),
        ("[landcover.codes]\n12 = \"jungle\"\n", "landcover.codes.12"),
        ("[landcover]\nraster = \"a.tif\"\n", "landcover"),
        (
            "[landcover]\npreset = \"corine\"\nraster = \"\"\n",
            "landcover.raster",
        ),
    ] {
        assert_invalid(text, key);
    }
    let e = err("[landcover]\npreset = \"corine\"\ncolour = 1\n");
    assert_names(&e, "landcover.colour");
}
