//! Display channels: `[[channel]]` tables (issue 7). Each channel is one window or one
//! fullscreen display showing the aircraft's view through its own view offset and frustum.
//!
//! ```toml
//! [[channel]]
//! name = "left"                 # required, unique; `aerie run --channel left`
//! monitor = 1                   # optional: index in the list of monitors, or its name ("DP-2")
//! fullscreen = "borderless"     # or "exclusive" (video mode change); omit for a window
//! resolution = "1920x1080"      # render size, pixels; default: the window's (or monitor's) size
//! present_mode = "fifo"         # fifo (default, vsync) | mailbox | immediate
//! tau_px = 1.0                  # error bound τ for this channel; default: render.tau_px
//! cigi_view = 0                 # CIGI view ID of this channel, 0..=65535, unique; default: the
//!                               # channel's index in the file (View Control / View Definition
//!                               # for this view replace `view`, `eye` and `frustum`)
//! window = { x = 0, y = 0, width = 1280, height = 720 }   # windowed: rectangle (x, y optional,
//!                                                          # relative to `monitor` when given)
//! [channel.view]                # view offset relative to the aircraft, degrees
//! heading = -60.0               # clockwise, (−360, 360)
//! pitch = 0.0                   # up +, [−90, 90]
//! roll = 0.0                    # right down +, [−180, 180]
//! [channel.frustum]             # degrees; either symmetric ...
//! hfov = 60.0                   #   horizontal field of view (0, 180); vfov optional, else from
//!                               #   the resolution's aspect (square pixels)
//! # left = -30.0                # ... or asymmetric, CIGI View Definition style: angles of the
//! # right = 30.0                #   edges from the view axis, right and up positive, each within
//! # down = -20.0                #   (−90, 90), left < right, down < up
//! # up = 25.0
//! [channel.eye]                 # eye offset from the aircraft reference point, body frame, metres
//! forward = 0.0
//! right = 0.0
//! up = 0.0
//! ```
//!
//! Every error is one line naming the file, the key (`channel[1].frustum.left`), its line and
//! column when known, and the reason; a config with any bad channel is refused as a whole.

use std::fmt;

use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};

use crate::locate::Seg;
use crate::settings::RenderSettings;
use crate::size::{parse_size, MAX_DIMENSION};

/// One display channel, validated.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Unique name (`aerie run --channel <name>`).
    pub name: String,
    /// The monitor the window or fullscreen display goes on; `None`: the window system decides
    /// (windows) or the primary monitor (fullscreen).
    pub monitor: Option<MonitorSelector>,
    /// Window rectangle or fullscreen mode.
    pub display: ChannelDisplay,
    /// Render resolution, pixels; `None`: follow the window's size.
    pub resolution: Option<(u32, u32)>,
    pub present_mode: PresentMode,
    /// Error bound τ for this channel, pixels.
    pub tau_px: f64,
    pub view: ViewOffset,
    pub frustum: ChannelFrustum,
    pub eye: EyeOffset,
    /// CIGI view ID (`cigi_view`, default: the channel's index in the file): the host's View
    /// Control and View Definition for this view replace `view`, `eye` and `frustum`.
    pub cigi_view: u16,
}

impl Channel {
    /// A windowed channel looking straight ahead with a symmetric `hfov_deg` frustum: what
    /// `aerie run` uses when a config has no `[[channel]]`.
    pub fn window(name: &str, width: u32, height: u32, hfov_deg: f64, tau_px: f64) -> Self {
        Self {
            name: name.to_owned(),
            monitor: None,
            display: ChannelDisplay::Window {
                x: None,
                y: None,
                width,
                height,
            },
            resolution: None,
            present_mode: PresentMode::Fifo,
            tau_px,
            view: ViewOffset::default(),
            frustum: ChannelFrustum::Symmetric {
                hfov_deg,
                vfov_deg: None,
            },
            eye: EyeOffset::default(),
            cigi_view: 0,
        }
    }

    /// The size the channel is drawn at when known without a monitor: the resolution, else the
    /// window's size; `None` for a fullscreen channel without a resolution.
    pub fn nominal_size(&self) -> Option<(u32, u32)> {
        self.resolution.or(match self.display {
            ChannelDisplay::Window { width, height, .. } => Some((width, height)),
            ChannelDisplay::Fullscreen(_) => None,
        })
    }

    pub fn is_fullscreen(&self) -> bool {
        matches!(self.display, ChannelDisplay::Fullscreen(_))
    }
}

/// A monitor by its index in the window system's list, or by its name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MonitorSelector {
    Index(u32),
    Name(String),
}

impl fmt::Display for MonitorSelector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MonitorSelector::Index(i) => write!(f, "{i}"),
            MonitorSelector::Name(n) => write!(f, "{n:?}"),
        }
    }
}

/// Where the channel is shown.
#[derive(Clone, Debug, PartialEq)]
pub enum ChannelDisplay {
    /// A window of `width`×`height` pixels at (`x`, `y`) (relative to the monitor when one is
    /// given; the window system places it when omitted).
    Window {
        x: Option<i32>,
        y: Option<i32>,
        width: u32,
        height: u32,
    },
    Fullscreen(FullscreenMode),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FullscreenMode {
    /// A borderless window covering the monitor at its current video mode.
    Borderless,
    /// Exclusive fullscreen: the monitor switches to the video mode of the channel's resolution.
    Exclusive,
}

/// How frames reach the screen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PresentMode {
    /// Wait for vertical blank, no tearing (always supported).
    #[default]
    Fifo,
    /// Newest frame at vertical blank, no tearing, no waiting.
    Mailbox,
    /// No waiting, may tear.
    Immediate,
}

impl PresentMode {
    pub fn as_str(&self) -> &'static str {
        match self {
            PresentMode::Fifo => "fifo",
            PresentMode::Mailbox => "mailbox",
            PresentMode::Immediate => "immediate",
        }
    }
}

/// View direction relative to the aircraft body, degrees, applied heading, pitch, roll.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ViewOffset {
    #[serde(rename = "heading")]
    pub heading_deg: f64,
    #[serde(rename = "pitch")]
    pub pitch_deg: f64,
    #[serde(rename = "roll")]
    pub roll_deg: f64,
}

/// The channel's frustum, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChannelFrustum {
    /// Centred on the view axis; the vertical angle follows the aspect when `vfov_deg` is `None`.
    Symmetric {
        hfov_deg: f64,
        vfov_deg: Option<f64>,
    },
    /// Edge angles from the view axis (CIGI View Definition style), right and up positive.
    Asymmetric {
        left_deg: f64,
        right_deg: f64,
        down_deg: f64,
        up_deg: f64,
    },
}

/// Eye position relative to the aircraft reference point in the body frame, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct EyeOffset {
    #[serde(rename = "forward")]
    pub forward_m: f64,
    #[serde(rename = "right")]
    pub right_m: f64,
    #[serde(rename = "up")]
    pub up_m: f64,
}

// ---------------------------------------------------------------------------------------------
// Raw (as written) form.

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table of channel settings")]
pub(crate) struct RawChannel {
    name: Option<String>,
    monitor: Option<MonitorSelector>,
    fullscreen: Option<FullscreenMode>,
    window: Option<RawWindow>,
    resolution: Option<String>,
    present_mode: Option<PresentMode>,
    tau_px: Option<f64>,
    view: Option<RawView>,
    frustum: Option<RawFrustum>,
    eye: Option<RawEye>,
    cigi_view: Option<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with width, height and optional x, y"
)]
struct RawWindow {
    x: Option<i32>,
    y: Option<i32>,
    width: Option<i64>,
    height: Option<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with heading, pitch, roll (degrees)"
)]
struct RawView {
    heading: Option<f64>,
    pitch: Option<f64>,
    roll: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with hfov (and vfov) or left, right, down, up (degrees)"
)]
struct RawFrustum {
    hfov: Option<f64>,
    vfov: Option<f64>,
    left: Option<f64>,
    right: Option<f64>,
    down: Option<f64>,
    up: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with forward, right, up (metres)"
)]
struct RawEye {
    forward: Option<f64>,
    right: Option<f64>,
    up: Option<f64>,
}

impl<'de> Deserialize<'de> for MonitorSelector {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = MonitorSelector;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a monitor index (0, 1, …) or a monitor name")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<MonitorSelector, E> {
                u32::try_from(v)
                    .map(MonitorSelector::Index)
                    .map_err(|_| E::invalid_value(de::Unexpected::Signed(v), &self))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<MonitorSelector, E> {
                u32::try_from(v)
                    .map(MonitorSelector::Index)
                    .map_err(|_| E::invalid_value(de::Unexpected::Unsigned(v), &self))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<MonitorSelector, E> {
                if v.trim().is_empty() {
                    return Err(E::invalid_value(de::Unexpected::Str(v), &self));
                }
                Ok(MonitorSelector::Name(v.to_owned()))
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for MonitorSelector {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            MonitorSelector::Index(i) => s.serialize_u32(*i),
            MonitorSelector::Name(n) => s.serialize_str(n),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Writing back (RenderConfig::to_toml): the raw form, so that `parse` reads it back equal.

#[derive(Serialize)]
struct ChannelOut<'a> {
    name: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    monitor: Option<&'a MonitorSelector>,
    #[serde(skip_serializing_if = "Option::is_none")]
    fullscreen: Option<FullscreenMode>,
    #[serde(skip_serializing_if = "Option::is_none")]
    resolution: Option<String>,
    present_mode: PresentMode,
    tau_px: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    window: Option<WindowOut>,
    view: ViewOffset,
    frustum: FrustumOut,
    eye: EyeOffset,
    cigi_view: u16,
}

#[derive(Serialize)]
struct WindowOut {
    #[serde(skip_serializing_if = "Option::is_none")]
    x: Option<i32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    y: Option<i32>,
    width: u32,
    height: u32,
}

#[derive(Serialize)]
struct FrustumOut {
    #[serde(skip_serializing_if = "Option::is_none")]
    hfov: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    vfov: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    left: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    right: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    down: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    up: Option<f64>,
}

impl Serialize for Channel {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let (fullscreen, window) = match self.display {
            ChannelDisplay::Fullscreen(m) => (Some(m), None),
            ChannelDisplay::Window {
                x,
                y,
                width,
                height,
            } => (
                None,
                Some(WindowOut {
                    x,
                    y,
                    width,
                    height,
                }),
            ),
        };
        let frustum = match self.frustum {
            ChannelFrustum::Symmetric { hfov_deg, vfov_deg } => FrustumOut {
                hfov: Some(hfov_deg),
                vfov: vfov_deg,
                left: None,
                right: None,
                down: None,
                up: None,
            },
            ChannelFrustum::Asymmetric {
                left_deg,
                right_deg,
                down_deg,
                up_deg,
            } => FrustumOut {
                hfov: None,
                vfov: None,
                left: Some(left_deg),
                right: Some(right_deg),
                down: Some(down_deg),
                up: Some(up_deg),
            },
        };
        ChannelOut {
            name: &self.name,
            monitor: self.monitor.as_ref(),
            fullscreen,
            resolution: self.resolution.map(|(w, h)| format!("{w}x{h}")),
            present_mode: self.present_mode,
            tau_px: self.tau_px,
            window,
            view: self.view,
            frustum,
            eye: self.eye,
            cigi_view: self.cigi_view,
        }
        .serialize(s)
    }
}

// ---------------------------------------------------------------------------------------------
// Validation.

/// A channel validation failure: where (as a path) and why.
#[derive(Debug)]
pub(crate) struct ChannelInvalid {
    pub(crate) path: Vec<Seg>,
    pub(crate) message: String,
}

impl ChannelInvalid {
    /// `channel[1].frustum.left`.
    pub(crate) fn dotted(&self) -> String {
        let mut out = String::new();
        for s in &self.path {
            match s {
                Seg::Key(k) => {
                    if !out.is_empty() {
                        out.push('.');
                    }
                    out.push_str(k);
                }
                Seg::Index(i) => out.push_str(&format!("[{i}]")),
            }
        }
        out
    }
}

/// Validates every channel in order; the first problem is returned with its key path.
pub(crate) fn validate(
    raw: Vec<RawChannel>,
    render: &RenderSettings,
) -> Result<Vec<Channel>, ChannelInvalid> {
    let mut out: Vec<Channel> = Vec::with_capacity(raw.len());
    for (i, r) in raw.into_iter().enumerate() {
        let at = |keys: &[&'static str], message: String| ChannelInvalid {
            path: [Seg::Key("channel"), Seg::Index(i)]
                .into_iter()
                .chain(keys.iter().map(|k| Seg::Key(k)))
                .collect(),
            message,
        };
        let ch = validate_one(r, render, i, &at)?;
        if let Some(j) = out.iter().position(|c| c.name == ch.name) {
            return Err(at(
                &["name"],
                format!(
                    "duplicate channel name {:?} (also channel[{j}].name); names must be unique",
                    ch.name
                ),
            ));
        }
        if let Some(j) = out.iter().position(|c| c.cigi_view == ch.cigi_view) {
            // A view ID drives one channel: two channels on one ID would both follow the host.
            return Err(at(
                &["cigi_view"],
                format!(
                    "CIGI view {} is also channel[{j}]'s (a channel without cigi_view takes its index); view IDs must be unique",
                    ch.cigi_view
                ),
            ));
        }
        out.push(ch);
    }
    Ok(out)
}

type At<'a> = &'a dyn Fn(&[&'static str], String) -> ChannelInvalid;

fn validate_one(
    r: RawChannel,
    render: &RenderSettings,
    index: usize,
    at: At<'_>,
) -> Result<Channel, ChannelInvalid> {
    let name = match r.name {
        None => {
            return Err(at(
                &["name"],
                "missing: every channel needs a unique name".to_owned(),
            ))
        }
        Some(n) if n.trim().is_empty() => {
            return Err(at(&["name"], "must not be empty".to_owned()))
        }
        Some(n) => n,
    };

    let resolution = match r.resolution.as_deref() {
        None => None,
        Some(s) => Some(parse_size(s).map_err(|m| at(&["resolution"], m))?),
    };

    let display =
        match (r.fullscreen, r.window) {
            (Some(_), Some(_)) => return Err(at(
                &["window"],
                "a fullscreen channel takes no window rectangle: remove `window` or `fullscreen`"
                    .to_owned(),
            )),
            (Some(mode), None) => ChannelDisplay::Fullscreen(mode),
            (None, Some(w)) => {
                let side = |key: &'static str, v: Option<i64>| -> Result<u32, ChannelInvalid> {
                    match v {
                        None => Err(at(
                            &["window", key],
                            "missing: a window rectangle needs width and height".to_owned(),
                        )),
                        Some(v) if (1..=i64::from(MAX_DIMENSION)).contains(&v) => Ok(v as u32),
                        Some(v) => Err(at(
                            &["window", key],
                            format!("must be 1..={MAX_DIMENSION} pixels, got {v}"),
                        )),
                    }
                };
                ChannelDisplay::Window {
                    x: w.x,
                    y: w.y,
                    width: side("width", w.width)?,
                    height: side("height", w.height)?,
                }
            }
            (None, None) => {
                let (width, height) = resolution.unwrap_or((render.width, render.height));
                ChannelDisplay::Window {
                    x: None,
                    y: None,
                    width,
                    height,
                }
            }
        };

    let tau_px = r.tau_px.unwrap_or(render.tau_px);
    if !(tau_px.is_finite() && tau_px > 0.0) {
        return Err(at(
            &["tau_px"],
            format!("must be a finite number of pixels greater than 0, got {tau_px}"),
        ));
    }

    let v = r.view.unwrap_or_default();
    let view = ViewOffset {
        heading_deg: v.heading.unwrap_or(0.0),
        pitch_deg: v.pitch.unwrap_or(0.0),
        roll_deg: v.roll.unwrap_or(0.0),
    };
    for (key, value, limit, open) in [
        ("heading", view.heading_deg, 360.0, true),
        ("pitch", view.pitch_deg, 90.0, false),
        ("roll", view.roll_deg, 180.0, false),
    ] {
        let inside = if open {
            value.abs() < limit
        } else {
            value.abs() <= limit
        };
        if !(value.is_finite() && inside) {
            let range = if open {
                format!("(-{limit}, {limit})")
            } else {
                format!("[-{limit}, {limit}]")
            };
            return Err(at(
                &["view", key],
                format!("must be within {range} degrees, got {value}"),
            ));
        }
    }

    let frustum = validate_frustum(r.frustum.unwrap_or_default(), render, at)?;

    let e = r.eye.unwrap_or_default();
    let eye = EyeOffset {
        forward_m: e.forward.unwrap_or(0.0),
        right_m: e.right.unwrap_or(0.0),
        up_m: e.up.unwrap_or(0.0),
    };
    for (key, value) in [
        ("forward", eye.forward_m),
        ("right", eye.right_m),
        ("up", eye.up_m),
    ] {
        if !(value.is_finite() && value.abs() <= 1000.0) {
            return Err(at(
                &["eye", key],
                format!("must be a finite offset within ±1000 metres, got {value}"),
            ));
        }
    }

    let cigi_view = match r.cigi_view {
        None => u16::try_from(index).map_err(|_| {
            at(
                &["cigi_view"],
                format!("channel index {index} is not a CIGI view ID: give cigi_view (0..=65535)"),
            )
        })?,
        Some(v) => u16::try_from(v).map_err(|_| {
            at(
                &["cigi_view"],
                format!("must be a CIGI view ID 0..=65535, got {v}"),
            )
        })?,
    };

    Ok(Channel {
        name,
        monitor: r.monitor,
        display,
        resolution,
        present_mode: r.present_mode.unwrap_or_default(),
        tau_px,
        view,
        frustum,
        eye,
        cigi_view,
    })
}

fn validate_frustum(
    f: RawFrustum,
    render: &RenderSettings,
    at: At<'_>,
) -> Result<ChannelFrustum, ChannelInvalid> {
    let edges = [
        ("left", f.left),
        ("right", f.right),
        ("down", f.down),
        ("up", f.up),
    ];
    let asymmetric = edges.iter().any(|(_, v)| v.is_some());
    if asymmetric {
        if f.hfov.is_some() || f.vfov.is_some() {
            let key = if f.hfov.is_some() { "hfov" } else { "vfov" };
            return Err(at(
                &["frustum", key],
                "give either hfov (and optionally vfov) or left, right, down and up, not both"
                    .to_owned(),
            ));
        }
        let mut v = [0.0; 4];
        for (slot, (key, value)) in v.iter_mut().zip(edges) {
            let Some(value) = value else {
                return Err(at(
                    &["frustum", key],
                    "missing: an asymmetric frustum needs left, right, down and up".to_owned(),
                ));
            };
            if !(value.is_finite() && value.abs() < 90.0) {
                return Err(at(
                    &["frustum", key],
                    format!(
                        "must be within (-90, 90) degrees of the view axis (a half-angle of 90° or more does not project), got {value}"
                    ),
                ));
            }
            *slot = value;
        }
        let [left, right, down, up] = v;
        if left >= right {
            return Err(at(
                &["frustum", "left"],
                format!("must be less than right ({right}), got {left}"),
            ));
        }
        if down >= up {
            return Err(at(
                &["frustum", "down"],
                format!("must be less than up ({up}), got {down}"),
            ));
        }
        return Ok(ChannelFrustum::Asymmetric {
            left_deg: left,
            right_deg: right,
            down_deg: down,
            up_deg: up,
        });
    }
    let check = |key: &'static str, v: f64| {
        if v.is_finite() && v > 0.0 && v < 180.0 {
            Ok(v)
        } else {
            Err(at(
                &["frustum", key],
                format!(
                    "must be greater than 0 and less than 180 degrees (a half-angle below 90°), got {v}"
                ),
            ))
        }
    };
    let hfov_deg = match (f.hfov, f.vfov) {
        (None, Some(_)) => {
            return Err(at(
                &["frustum", "hfov"],
                "missing: vfov needs hfov (or give left, right, down and up)".to_owned(),
            ))
        }
        (Some(h), _) => check("hfov", h)?,
        (None, None) => render.fov_deg,
    };
    let vfov_deg = f.vfov.map(|v| check("vfov", v)).transpose()?;
    Ok(ChannelFrustum::Symmetric { hfov_deg, vfov_deg })
}
