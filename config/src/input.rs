//! The simulator pose input: the `[input]` table (issue 6). Every key is optional; `aerie run`
//! fills what is missing with its command-line flags or their defaults (flags override the
//! config), so a value here stays `None` when the file does not give it.
//!
//! ```toml
//! [input]
//! protocol = "cigi"             # auto | native (aerie) | cigi | xplane | fgfs | shm
//! listen = "0.0.0.0:47800"      # UDP address to bind (ADDR:PORT)
//! multicast = "239.1.2.3"       # join this IPv4 multicast group
//! multicast_if = "10.0.0.5"     # interface for the join (needs multicast)
//! allow = ["10.0.0.1"]          # accept poses only from these source addresses
//! shm_name = "aerie-pose"       # shared-memory pose file (protocol = "shm")
//! max_extrapolation_ms = 100.0  # carry a pose forward at most this much, ms, ≥ 0
//! sync_frames = 1               # frame-locked: draw host frame newest − K, 0..=63
//! wait_pose_s = 10.0            # headless: wait this long for the first pose, s, > 0
//! world_bound_m = 1.0e7         # local poses beyond ±this (any axis) are dropped, m, (0, 1e9]
//! host_heights = "msl"          # the host's geodetic altitudes: msl | ellipsoidal (WGS84)
//! ```

use std::net::{IpAddr, Ipv4Addr, SocketAddr};

use serde::{Deserialize, Serialize, Serializer};

/// Largest `world_bound_m`, metres (the bound every pose decoder applies:
/// `aerie_sim_bridge::pose::MAX_WORLD_BOUND_M`).
pub const MAX_WORLD_BOUND_M: f64 = 1.0e9;

/// Largest `sync_frames`: the frame-locked history keeps the newest 64 host frames.
pub const MAX_SYNC_FRAMES: u32 = 63;

/// The pose protocol of `[input] protocol`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputProtocolName {
    /// Detected per datagram.
    Auto,
    /// aerie native v1.
    Native,
    Cigi,
    Xplane,
    Fgfs,
    /// Shared memory (`shm_name`).
    Shm,
}

impl InputProtocolName {
    /// Every accepted spelling, for error messages.
    pub const NAMES: &'static str = "auto, native (or aerie), cigi, xplane, fgfs, shm";

    /// The name as `aerie run --protocol` takes it.
    pub fn as_str(&self) -> &'static str {
        match self {
            InputProtocolName::Auto => "auto",
            InputProtocolName::Native => "native",
            InputProtocolName::Cigi => "cigi",
            InputProtocolName::Xplane => "xplane",
            InputProtocolName::Fgfs => "fgfs",
            InputProtocolName::Shm => "shm",
        }
    }

    fn parse(s: &str) -> Option<Self> {
        Some(match s.to_ascii_lowercase().as_str() {
            "auto" => InputProtocolName::Auto,
            "native" | "aerie" => InputProtocolName::Native,
            "cigi" => InputProtocolName::Cigi,
            "xplane" | "x-plane" | "rpos" => InputProtocolName::Xplane,
            "fgfs" | "flightgear" => InputProtocolName::Fgfs,
            "shm" => InputProtocolName::Shm,
            _ => return None,
        })
    }
}

impl Serialize for InputProtocolName {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// The vertical datum of a host's geodetic altitudes (`[input] host_heights`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum HostHeightsName {
    /// Above mean sea level (orthometric), as CIGI specifies: the data's own datum.
    #[default]
    Msl,
    /// Above the WGS84 ellipsoid (a GNSS height).
    Ellipsoidal,
}

impl HostHeightsName {
    /// Every accepted spelling, for error messages.
    pub const NAMES: &'static str = "msl, ellipsoidal";

    pub fn as_str(&self) -> &'static str {
        match self {
            HostHeightsName::Msl => "msl",
            HostHeightsName::Ellipsoidal => "ellipsoidal",
        }
    }

    /// `msl` or `ellipsoidal` (any case).
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "msl" => HostHeightsName::Msl,
            "ellipsoidal" => HostHeightsName::Ellipsoidal,
            _ => return None,
        })
    }
}

impl Serialize for HostHeightsName {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// The `[input]` table, validated; `None` / empty: not given in the file.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct InputSettings {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub protocol: Option<InputProtocolName>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub listen: Option<SocketAddr>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub multicast: Option<Ipv4Addr>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub multicast_if: Option<Ipv4Addr>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub allow: Vec<IpAddr>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shm_name: Option<String>,
    /// Milliseconds, finite, ≥ 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_extrapolation_ms: Option<f64>,
    /// 0..=[`MAX_SYNC_FRAMES`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sync_frames: Option<u32>,
    /// Seconds, finite, > 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wait_pose_s: Option<f64>,
    /// Metres, finite, in (0, [`MAX_WORLD_BOUND_M`]]: local poses beyond ±this are dropped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub world_bound_m: Option<f64>,
    /// The datum of the host's geodetic altitudes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub host_heights: Option<HostHeightsName>,
}

impl InputSettings {
    /// True when the file has no `[input]` key at all.
    pub fn is_empty(&self) -> bool {
        *self == InputSettings::default()
    }

    /// True when the file asks for a pose input (protocol, listen, multicast or shm_name given).
    pub fn wants_input(&self) -> bool {
        self.protocol.is_some()
            || self.listen.is_some()
            || self.multicast.is_some()
            || self.shm_name.is_some()
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table of pose input settings")]
pub(crate) struct RawInput {
    protocol: Option<String>,
    listen: Option<String>,
    multicast: Option<String>,
    multicast_if: Option<String>,
    allow: Option<Vec<String>>,
    shm_name: Option<String>,
    max_extrapolation_ms: Option<f64>,
    sync_frames: Option<i64>,
    wait_pose_s: Option<f64>,
    world_bound_m: Option<f64>,
    host_heights: Option<String>,
}

type Invalid = (&'static str, String);

/// `v` as a short number: scientific notation when plain would be long (1e300, not 301 digits).
fn short(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

fn ipv4(key: &'static str, s: &str) -> Result<Ipv4Addr, Invalid> {
    s.trim().parse().map_err(|_| {
        (
            key,
            format!("expected an IPv4 address such as 239.1.2.3, got {s:?}"),
        )
    })
}

impl RawInput {
    pub(crate) fn validate(self) -> Result<InputSettings, Invalid> {
        let protocol = match self.protocol.as_deref() {
            None => None,
            Some(p) => Some(InputProtocolName::parse(p.trim()).ok_or_else(|| {
                (
                    "input.protocol",
                    format!(
                        "unknown protocol {p:?} (expected {})",
                        InputProtocolName::NAMES
                    ),
                )
            })?),
        };
        let host_heights = match self.host_heights.as_deref() {
            None => None,
            Some(h) => Some(HostHeightsName::parse(h).ok_or_else(|| {
                (
                    "input.host_heights",
                    format!(
                        "unknown height datum {h:?} (expected {})",
                        HostHeightsName::NAMES
                    ),
                )
            })?),
        };
        let listen = match self.listen.as_deref() {
            None => None,
            Some(s) => Some(s.trim().parse::<SocketAddr>().map_err(|_| {
                (
                    "input.listen",
                    format!("expected ADDR:PORT such as \"127.0.0.1:47800\", got {s:?}"),
                )
            })?),
        };
        let multicast = match self.multicast.as_deref() {
            None => None,
            Some(s) => {
                let g = ipv4("input.multicast", s)?;
                if !g.is_multicast() {
                    return Err((
                        "input.multicast",
                        format!("{g} is not a multicast group (224.0.0.0 to 239.255.255.255)"),
                    ));
                }
                Some(g)
            }
        };
        let multicast_if = self
            .multicast_if
            .as_deref()
            .map(|s| ipv4("input.multicast_if", s))
            .transpose()?;
        let mut allow = Vec::new();
        for s in self.allow.unwrap_or_default() {
            allow.push(s.trim().parse::<IpAddr>().map_err(|_| {
                (
                    "input.allow",
                    format!("expected IP addresses such as \"10.0.0.1\", got {s:?}"),
                )
            })?);
        }
        if self
            .shm_name
            .as_deref()
            .is_some_and(|n| n.trim().is_empty())
        {
            return Err(("input.shm_name", "must not be empty".to_owned()));
        }
        if let Some(ms) = self.max_extrapolation_ms {
            if !(ms.is_finite() && ms >= 0.0) {
                return Err((
                    "input.max_extrapolation_ms",
                    format!("must be a finite number of milliseconds ≥ 0, got {ms}"),
                ));
            }
        }
        let sync_frames = match self.sync_frames {
            None => None,
            Some(k) if (0..=i64::from(MAX_SYNC_FRAMES)).contains(&k) => Some(k as u32),
            Some(k) => {
                return Err((
                    "input.sync_frames",
                    format!(
                        "must be 0..={MAX_SYNC_FRAMES} host frames (the frame-locked history keeps 64), got {k}"
                    ),
                ))
            }
        };
        if let Some(s) = self.wait_pose_s {
            if !(s.is_finite() && s > 0.0) {
                return Err((
                    "input.wait_pose_s",
                    format!("must be a finite number of seconds greater than 0, got {s}"),
                ));
            }
        }
        if let Some(b) = self.world_bound_m {
            if !(b.is_finite() && b > 0.0 && b <= MAX_WORLD_BOUND_M) {
                return Err((
                    "input.world_bound_m",
                    format!(
                        "must be a finite number of metres greater than 0 and at most {MAX_WORLD_BOUND_M:e}, got {}",
                        short(b)
                    ),
                ));
            }
        }
        // Keys that cannot apply together are refused here, as the flags are.
        if multicast_if.is_some() && multicast.is_none() {
            return Err((
                "input.multicast_if",
                "only with input.multicast (the interface to join the group on)".to_owned(),
            ));
        }
        // Without a protocol, shm_name means shared memory (as --shm-name does).
        let shm = protocol == Some(InputProtocolName::Shm)
            || (protocol.is_none() && self.shm_name.is_some());
        if shm {
            for (key, set) in [
                ("input.listen", listen.is_some()),
                ("input.multicast", multicast.is_some()),
                ("input.allow", !allow.is_empty()),
            ] {
                if set {
                    return Err((
                        key,
                        "applies to UDP only; protocol \"shm\" reads shared memory".to_owned(),
                    ));
                }
            }
        } else if protocol.is_some() && self.shm_name.is_some() {
            return Err((
                "input.shm_name",
                "only with protocol = \"shm\" (or without protocol, which then means shm)"
                    .to_owned(),
            ));
        }
        Ok(InputSettings {
            protocol,
            listen,
            multicast,
            multicast_if,
            allow,
            shm_name: self.shm_name,
            max_extrapolation_ms: self.max_extrapolation_ms,
            sync_frames,
            wait_pose_s: self.wait_pose_s,
            world_bound_m: self.world_bound_m,
            host_heights,
        })
    }
}
