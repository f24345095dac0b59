//! `[[channel]]` tables: what parses, what each bad input says (file, key, line, reason), the
//! presets, and the round trip through `to_toml`.

use std::path::Path;

use aerie_config::{
    load, parse, Channel, ChannelDisplay, ChannelFrustum, ConfigError, EyeOffset, FullscreenMode,
    Location, MonitorSelector, PresentMode, RenderConfig, ViewOffset,
};

const FILE: &str = "wall.toml";

fn err(text: &str) -> ConfigError {
    match parse(text, FILE) {
        Ok(cfg) => panic!("expected an error for {text:?}, got {cfg:?}"),
        Err(e) => e,
    }
}

/// The error is one line starting with the file name, is about `key`, and says `reason`.
fn assert_error(text: &str, key: &str, line: usize, reason: &str) -> String {
    let e = err(text);
    let msg = e.to_string();
    assert!(!msg.contains('\n'), "not one line: {msg:?}");
    assert!(msg.starts_with(&format!("{FILE}:")), "no file name: {msg}");
    assert_eq!(e.key(), Some(key), "{msg}");
    assert!(
        msg.contains(&format!(": {key}: ")),
        "key not in message: {msg}"
    );
    assert!(msg.contains(reason), "reason {reason:?} not in: {msg}");
    assert_eq!(e.location().map(|l| l.line), Some(line), "{msg}");
    msg
}

fn two_channels(second: &str) -> String {
    format!("[[channel]]\nname = \"a\"\n\n[[channel]]\nname = \"b\"\n{second}")
}

#[test]
fn no_channel_tables_means_no_channels() {
    let cfg = parse("[render]\nsize = \"640x360\"\n", FILE).unwrap();
    assert!(cfg.channels.is_empty());
    assert_eq!(
        RenderConfig::default().channels,
        Vec::<Channel>::new(),
        "default has none"
    );
}

#[test]
fn minimal_channel_takes_render_defaults() {
    let cfg = parse(
        "[render]\nsize = \"800x600\"\nfov_deg = 75\ntau_px = 2\n[[channel]]\nname = \"only\"\n",
        FILE,
    )
    .unwrap();
    assert_eq!(
        cfg.channels,
        vec![Channel {
            name: "only".into(),
            monitor: None,
            display: ChannelDisplay::Window {
                x: None,
                y: None,
                width: 800,
                height: 600
            },
            resolution: None,
            present_mode: PresentMode::Fifo,
            tau_px: 2.0,
            view: ViewOffset::default(),
            frustum: ChannelFrustum::Symmetric {
                hfov_deg: 75.0,
                vfov_deg: None
            },
            eye: EyeOffset::default(),
            cigi_view: 0,
        }]
    );
    assert_eq!(cfg.channels[0].nominal_size(), Some((800, 600)));
}

#[test]
fn full_channel_parses() {
    let text = r#"
[[channel]]
name = "front"
monitor = "DP-1"
fullscreen = "exclusive"
resolution = "1920x1200"
present_mode = "mailbox"
tau_px = 0.5
view = { heading = -12.5, pitch = -3, roll = 1 }
frustum = { left = -40, right = 35, down = -20, up = 25 }
eye = { forward = 1.5, right = -0.4, up = 0.9 }

[[channel]]
name = "side"
monitor = 2
window = { x = 10, y = -20, width = 640, height = 480 }
present_mode = "immediate"
[channel.frustum]
hfov = 50
vfov = 40
"#;
    let cfg = parse(text, FILE).unwrap();
    let [front, side] = &cfg.channels[..] else {
        panic!("two channels expected: {cfg:?}")
    };
    assert_eq!(front.monitor, Some(MonitorSelector::Name("DP-1".into())));
    assert_eq!(
        front.display,
        ChannelDisplay::Fullscreen(FullscreenMode::Exclusive)
    );
    assert!(front.is_fullscreen());
    assert_eq!(front.resolution, Some((1920, 1200)));
    assert_eq!(front.nominal_size(), Some((1920, 1200)));
    assert_eq!(front.present_mode, PresentMode::Mailbox);
    assert_eq!(front.tau_px, 0.5);
    assert_eq!(
        front.view,
        ViewOffset {
            heading_deg: -12.5,
            pitch_deg: -3.0,
            roll_deg: 1.0
        }
    );
    assert_eq!(
        front.frustum,
        ChannelFrustum::Asymmetric {
            left_deg: -40.0,
            right_deg: 35.0,
            down_deg: -20.0,
            up_deg: 25.0
        }
    );
    assert_eq!(
        front.eye,
        EyeOffset {
            forward_m: 1.5,
            right_m: -0.4,
            up_m: 0.9
        }
    );
    assert_eq!(side.monitor, Some(MonitorSelector::Index(2)));
    assert_eq!(
        side.display,
        ChannelDisplay::Window {
            x: Some(10),
            y: Some(-20),
            width: 640,
            height: 480
        }
    );
    assert_eq!(side.present_mode, PresentMode::Immediate);
    assert_eq!(
        side.frustum,
        ChannelFrustum::Symmetric {
            hfov_deg: 50.0,
            vfov_deg: Some(40.0)
        }
    );
    assert_eq!(side.tau_px, 1.0, "render.tau_px default");
}

#[test]
fn duplicate_names_are_refused_naming_both() {
    let msg = assert_error(
        "[[channel]]\nname = \"left\"\n[[channel]]\nname = \"centre\"\n[[channel]]\nname = \"left\"\n",
        "channel[2].name",
        6,
        "duplicate channel name \"left\"",
    );
    assert!(msg.contains("channel[0].name"), "{msg}");
    assert!(msg.starts_with("wall.toml:6:8: channel[2].name: "), "{msg}");
}

#[test]
fn names_are_required_and_not_empty() {
    assert_error(
        "[[channel]]\nmonitor = 0\n",
        "channel[0].name",
        1,
        "missing",
    );
    assert_error(
        "[[channel]]\nname = \"  \"\n",
        "channel[0].name",
        2,
        "must not be empty",
    );
}

#[test]
fn left_must_be_less_than_right_and_down_less_than_up() {
    let f = |l: f64, r: f64, d: f64, u: f64| {
        two_channels(&format!(
            "[channel.frustum]\nleft = {l:?}\nright = {r:?}\ndown = {d:?}\nup = {u:?}\n"
        ))
    };
    assert_error(
        &f(30.0, 30.0, -10.0, 10.0),
        "channel[1].frustum.left",
        7,
        "must be less than right (30), got 30",
    );
    assert_error(
        &f(40.0, -40.0, -10.0, 10.0),
        "channel[1].frustum.left",
        7,
        "must be less than right",
    );
    assert_error(
        &f(-30.0, 30.0, 10.0, 10.0),
        "channel[1].frustum.down",
        9,
        "must be less than up (10), got 10",
    );
    // An off-axis frustum (both edges right of the axis) is fine.
    let cfg = parse(&f(10.0, 50.0, -5.0, 30.0), FILE).unwrap();
    assert!(matches!(
        cfg.channels[1].frustum,
        ChannelFrustum::Asymmetric { left_deg, .. } if left_deg == 10.0
    ));
}

#[test]
fn half_angles_of_90_degrees_or_more_are_refused() {
    for (key, value) in [
        ("left", -90.0),
        ("right", 90.0),
        ("down", -95.0),
        ("up", 135.0),
    ] {
        let mut edges = vec![
            ("left", -30.0),
            ("right", 30.0),
            ("down", -20.0),
            ("up", 20.0),
        ];
        for e in &mut edges {
            if e.0 == key {
                e.1 = value;
            }
        }
        let body: String = edges
            .iter()
            .map(|(k, v)| format!("{k} = {v:?}\n"))
            .collect();
        let line = 7 + edges.iter().position(|e| e.0 == key).unwrap();
        assert_error(
            &two_channels(&format!("[channel.frustum]\n{body}")),
            &format!("channel[1].frustum.{key}"),
            line,
            "must be within (-90, 90) degrees",
        );
    }
    for (key, v) in [
        ("hfov", 180.0),
        ("hfov", 0.0),
        ("hfov", -10.0),
        ("vfov", 200.0),
    ] {
        let text = if key == "hfov" {
            format!("[[channel]]\nname = \"x\"\nfrustum = {{ hfov = {v:?} }}\n")
        } else {
            format!("[[channel]]\nname = \"x\"\nfrustum = {{ hfov = 60.0, vfov = {v:?} }}\n")
        };
        assert_error(
            &text,
            &format!("channel[0].frustum.{key}"),
            3,
            "greater than 0 and less than 180 degrees",
        );
    }
    let nan =
        "[[channel]]\nname = \"x\"\nfrustum = { left = nan, right = 1.0, down = -1.0, up = 1.0 }\n";
    assert_error(nan, "channel[0].frustum.left", 3, "within (-90, 90)");
}

#[test]
fn frustum_forms_are_not_mixed_or_partial() {
    assert_error(
        "[[channel]]\nname = \"x\"\n[channel.frustum]\nhfov = 60\nleft = -30\n",
        "channel[0].frustum.hfov",
        4,
        "not both",
    );
    assert_error(
        "[[channel]]\nname = \"x\"\n[channel.frustum]\nleft = -30\nright = 30\nup = 20\n",
        "channel[0].frustum.down",
        3,
        "missing: an asymmetric frustum needs left, right, down and up",
    );
    assert_error(
        "[[channel]]\nname = \"x\"\n[channel.frustum]\nvfov = 40\n",
        "channel[0].frustum.hfov",
        3,
        "vfov needs hfov",
    );
    assert_error(
        "[[channel]]\nname = \"x\"\n[channel.frustum]\nfov = 40\n",
        "channel[0].frustum.fov",
        4,
        "unknown field `fov`",
    );
}

#[test]
fn zero_and_negative_sizes_are_refused() {
    for (text, key, line, reason) in [
        (
            "[[channel]]\nname = \"x\"\nwindow = { width = 0, height = 600 }\n",
            "channel[0].window.width",
            3,
            "must be 1..=16384 pixels, got 0",
        ),
        (
            "[[channel]]\nname = \"x\"\n[channel.window]\nwidth = 800\nheight = -600\n",
            "channel[0].window.height",
            5,
            "must be 1..=16384 pixels, got -600",
        ),
        (
            "[[channel]]\nname = \"x\"\n[channel.window]\nwidth = 800\n",
            "channel[0].window.height",
            3,
            "missing: a window rectangle needs width and height",
        ),
        (
            "[[channel]]\nname = \"x\"\nresolution = \"0x1080\"\n",
            "channel[0].resolution",
            3,
            "must each be 1..=16384 pixels",
        ),
        (
            "[[channel]]\nname = \"x\"\nresolution = \"-1920x1080\"\n",
            "channel[0].resolution",
            3,
            "expected \"WIDTHxHEIGHT\"",
        ),
        (
            "[[channel]]\nname = \"x\"\nresolution = \"1920\"\n",
            "channel[0].resolution",
            3,
            "expected \"WIDTHxHEIGHT\"",
        ),
    ] {
        assert_error(text, key, line, reason);
    }
}

#[test]
fn other_bad_values_name_their_keys() {
    for (text, key, line, reason) in [
        (
            "[[channel]]\nname = \"x\"\ncigi_view = 70000\n",
            "channel[0].cigi_view",
            3,
            "must be a CIGI view ID 0..=65535, got 70000",
        ),
        (
            "[[channel]]\nname = \"x\"\ncigi_view = 1\n[[channel]]\nname = \"y\"\n",
            "channel[1].cigi_view",
            4,
            "CIGI view 1 is also channel[0]'s",
        ),
        (
            "[[channel]]\nname = \"x\"\npresent_mode = \"vsync\"\n",
            "channel[0].present_mode",
            3,
            "unknown variant `vsync`, expected one of `fifo`, `mailbox`, `immediate`",
        ),
        (
            "[[channel]]\nname = \"x\"\nfullscreen = \"yes\"\n",
            "channel[0].fullscreen",
            3,
            "unknown variant `yes`",
        ),
        (
            "[[channel]]\nname = \"x\"\nfullscreen = \"borderless\"\nwindow = { width = 10, height = 10 }\n",
            "channel[0].window",
            4,
            "a fullscreen channel takes no window rectangle",
        ),
        (
            "[[channel]]\nname = \"x\"\nmonitor = -1\n",
            "channel[0].monitor",
            3,
            "expected a monitor index (0, 1, …) or a monitor name",
        ),
        (
            "[[channel]]\nname = \"x\"\nmonitor = \"\"\n",
            "channel[0].monitor",
            3,
            "a monitor index",
        ),
        (
            "[[channel]]\nname = \"x\"\nmonitor = 1.5\n",
            "channel[0].monitor",
            3,
            "a monitor index",
        ),
        (
            "[[channel]]\nname = \"x\"\ntau_px = 0\n",
            "channel[0].tau_px",
            3,
            "greater than 0",
        ),
        (
            "[[channel]]\nname = \"x\"\n[channel.view]\npitch = 91\n",
            "channel[0].view.pitch",
            4,
            "must be within [-90, 90] degrees, got 91",
        ),
        (
            "[[channel]]\nname = \"x\"\n[channel.view]\nheading = 360\n",
            "channel[0].view.heading",
            4,
            "(-360, 360)",
        ),
        (
            "[[channel]]\nname = \"x\"\n[channel.eye]\nup = inf\n",
            "channel[0].eye.up",
            4,
            "finite offset",
        ),
        (
            "[[channel]]\nname = \"x\"\nsize = \"1x1\"\n",
            "channel[0].size",
            3,
            "unknown field `size`",
        ),
        ("channel = 3\n", "channel", 1, "invalid type"),
    ] {
        assert_error(text, key, line, reason);
    }
}

#[test]
fn first_bad_channel_stops_everything() {
    // The second channel is bad: no channel is returned at all (no half-configured start).
    let e = err("[[channel]]\nname = \"ok\"\n[[channel]]\nname = \"bad\"\ntau_px = -1\n");
    assert_eq!(e.key(), Some("channel[1].tau_px"));
    assert_eq!(
        e.location(),
        Some(Location {
            line: 5,
            column: 10
        })
    );
}

#[test]
fn to_toml_round_trips_with_channels() {
    let text = r#"
[render]
size = "640x360"
[[channel]]
name = "front"
monitor = "DP-1"
fullscreen = "borderless"
resolution = "1920x1080"
frustum = { left = -40, right = 35, down = -20, up = 25 }
eye = { forward = 1.5, right = -0.4, up = 0.9 }
[[channel]]
name = "side"
monitor = 2
window = { x = 10, width = 640, height = 480 }
view = { heading = 70, pitch = -5, roll = 0 }
frustum = { hfov = 50, vfov = 40 }
[[channel]]
name = "plain"
"#;
    let cfg = parse(text, FILE).unwrap();
    let out = cfg.to_toml().unwrap();
    let back = parse(&out, FILE).unwrap_or_else(|e| panic!("{e}\n{out}"));
    assert_eq!(back, cfg, "{out}");
}

fn preset(name: &str) -> RenderConfig {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("presets")
        .join(name);
    load(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn single_preset_is_one_1920x1080_window() {
    let cfg = preset("single.toml");
    assert_eq!(cfg.channels.len(), 1);
    let c = &cfg.channels[0];
    assert!(!c.is_fullscreen());
    assert_eq!(c.nominal_size(), Some((1920, 1080)));
    assert_eq!(c.view, ViewOffset::default());
}

#[test]
fn wall3_preset_is_three_60_degree_channels_meeting_at_their_edges() {
    let cfg = preset("wall3.toml");
    let headings: Vec<f64> = cfg.channels.iter().map(|c| c.view.heading_deg).collect();
    assert_eq!(headings, [-60.0, 0.0, 60.0]);
    for (i, c) in cfg.channels.iter().enumerate() {
        assert_eq!(
            c.frustum,
            ChannelFrustum::Symmetric {
                hfov_deg: 60.0,
                vfov_deg: None
            },
            "{}",
            c.name
        );
        assert_eq!(c.monitor, Some(MonitorSelector::Index(i as u32)));
        assert!(c.is_fullscreen());
    }
}

#[test]
fn cockpit5_preset_has_asymmetric_frusta_whose_edges_meet() {
    let cfg = preset("cockpit5.toml");
    assert_eq!(cfg.channels.len(), 5);
    let edges = |c: &Channel| match c.frustum {
        ChannelFrustum::Asymmetric {
            left_deg,
            right_deg,
            down_deg,
            up_deg,
        } => (left_deg, right_deg, down_deg, up_deg),
        other => panic!("{}: {other:?} is not asymmetric", c.name),
    };
    let by = |n: &str| {
        cfg.channels
            .iter()
            .find(|c| c.name == n)
            .unwrap_or_else(|| panic!("no channel {n}"))
    };
    let (front, left, right) = (by("front"), by("left"), by("right"));
    let (fl, fr, fd, _) = edges(front);
    let (_, lr, _, _) = edges(left);
    let (rl, _, _, _) = edges(right);
    // Side channels continue the front one horizontally.
    assert!((left.view.heading_deg + lr - fl).abs() < 1e-9);
    assert!((right.view.heading_deg + rl - fr).abs() < 1e-9);
    // Chin channels look down and their top edge meets the front's bottom edge.
    for n in ["chin-left", "chin-right"] {
        let c = by(n);
        let (_, _, _, up) = edges(c);
        assert!(c.view.pitch_deg < 0.0, "{n} looks down");
        assert!((c.view.pitch_deg + up - fd).abs() < 1e-9, "{n}");
    }
}

#[test]
fn key_location_finds_dotted_keys_with_indices() {
    let text = "[render]\ntau_px = 2.0\n\n[[channel]]\nname = \"a\"\n\n[[channel]]\nname = \"b\"\nmonitor = 3\n[channel.frustum]\nhfov = 50.0\n";
    let at = |k: &str| aerie_config::key_location(text, k).map(|l| (l.line, l.column));
    assert_eq!(at("render.tau_px"), Some((2, 10)));
    assert_eq!(at("channel[1].monitor"), Some((9, 11)));
    assert_eq!(at("channel[1].frustum.hfov"), Some((11, 8)));
    assert_eq!(at("channel[0].name"), Some((5, 8)));
    assert_eq!(at("channel[0].monitor"), None);
    assert_eq!(at("channel[5].name"), None);
}

#[test]
fn cigi_view_defaults_to_the_channel_index() {
    let cfg = aerie_config::parse(
        "[[channel]]\nname = \"a\"\n[[channel]]\nname = \"b\"\ncigi_view = 7\n[[channel]]\nname = \"c\"\n",
        "v.toml",
    )
    .unwrap();
    let ids: Vec<u16> = cfg.channels.iter().map(|c| c.cigi_view).collect();
    assert_eq!(ids, [0, 7, 2]);
    let back = aerie_config::parse(&cfg.to_toml().unwrap(), "v.toml").unwrap();
    assert_eq!(back, cfg);
}
