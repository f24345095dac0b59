//! Simulator pose input for `aerie run` (issue 6 item 7, issue 7 item 4): the pose of each frame
//! from a UDP or shared-memory stream ([`aerie_sim_bridge`]), converted into the dataset's local
//! frame, either carried forward to the frame's display time or locked to a host frame number.
//!
//! Pure decisions, tested without sockets or a device:
//! - [`GeoMapping`]: WGS84 latitude/longitude/altitude ↔ the world frame a geographic dataset
//!   is drawn in (ENU at its south-west sample, the terrain on the ellipsoid), and ↔ the grid
//!   metres its samples are indexed by;
//! - [`FrameHistory`]: the last poses keyed by host frame counter, and which one a frame renders
//!   in frame-locked mode (`--sync-frames k`);
//! - [`aircraft_pose`]: a wire [`Pose`] → the renderer's [`AircraftPose`].
//!
//! [`SimInput`] does the I/O: it owns the receiver thread and the [`PoseReader`], and is polled
//! by the frame loop (never blocking).

use std::collections::VecDeque;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};

use aerie_sim_bridge::codec::ProtocolChoice;
use aerie_sim_bridge::shm::{shm_path, ShmConfig, ShmSource};
use aerie_sim_bridge::timing::{extrapolate, monotonic_s, ExtrapolationParams, Stamped};
use aerie_sim_bridge::udp::{RposRequest, UdpConfig, UdpReceiver};
use aerie_sim_bridge::{Pose, PoseLimits, PosePosition, PoseReader, StatsSnapshot, StreamState};
use glam::DVec3;

use crate::sim::channel::AircraftPose;
use aerie_terrain::camera::Attitude;
use aerie_terrain::geodesy::geoid::GeoidCells;
use aerie_terrain::geodesy::GeoidCache;

pub use crate::sim::geo_mapping::GeoMapping;

/// The vertical datum of a host's geodetic altitudes (`aerie run --host-heights`,
/// `[input] host_heights`; PROTOCOL.md "Datums and placement").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HostHeights {
    /// Above mean sea level, as CIGI specifies and SRTM heights are: used as they are.
    #[default]
    Msl,
    /// Above the WGS84 ellipsoid (a GNSS height): the EGM96 geoid undulation N is taken off,
    /// H = h − N, before the pose is placed over terrain in MSL heights.
    Ellipsoidal,
}

impl HostHeights {
    /// The config's name of it.
    pub fn of_config(h: aerie_config::HostHeightsName) -> Self {
        match h {
            aerie_config::HostHeightsName::Msl => HostHeights::Msl,
            aerie_config::HostHeightsName::Ellipsoidal => HostHeights::Ellipsoidal,
        }
    }
}

impl std::str::FromStr for HostHeights {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        aerie_config::HostHeightsName::parse(s)
            .map(Self::of_config)
            .ok_or_else(|| {
                format!(
                    "unknown height datum `{s}` (expected {})",
                    aerie_config::HostHeightsName::NAMES
                )
            })
    }
}

/// A host's geodetic altitudes brought into the data's datum: as they are for
/// [`HostHeights::Msl`], less the geoid undulation (kept per place in a [`GeoidCache`]) for
/// [`HostHeights::Ellipsoidal`].
#[derive(Debug, Clone, Copy, Default)]
pub struct HostDatum {
    pub heights: HostHeights,
    geoid: GeoidCache,
}

impl HostDatum {
    pub fn new(heights: HostHeights) -> Self {
        Self {
            heights,
            geoid: GeoidCache::default(),
        }
    }

    /// A host altitude at (lat, lon) → metres in the data's datum (MSL).
    pub fn to_data_m(&mut self, lat_deg: f64, lon_deg: f64, alt_m: f64) -> f64 {
        match self.heights {
            HostHeights::Msl => alt_m,
            HostHeights::Ellipsoidal => self.geoid.msl_of_ellipsoidal(lat_deg, lon_deg, alt_m),
        }
    }

    /// A wire pose with its geodetic altitude in the data's datum (local poses unchanged).
    pub fn pose_in_data_datum(&mut self, pose: &Pose) -> Pose {
        let mut p = *pose;
        if let PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } = pose.position
        {
            p.position = PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m: self.to_data_m(lat_deg, lon_deg, alt_m),
            };
        }
        p
    }
}

/// The host's datum for heights at many places (entities, terrain-query points and their
/// answers): [`HostDatum`] with N kept per place ([`GeoidCells`]).
#[derive(Debug, Clone, Default)]
pub struct HostDatumAtPlaces {
    pub heights: HostHeights,
    cells: GeoidCells,
}

impl HostDatumAtPlaces {
    pub fn new(heights: HostHeights) -> Self {
        Self {
            heights,
            cells: GeoidCells::default(),
        }
    }

    /// A host altitude at (lat, lon) → metres in the data's datum (MSL).
    pub fn to_data_m(&mut self, lat_deg: f64, lon_deg: f64, alt_m: f64) -> f64 {
        match self.heights {
            HostHeights::Msl => alt_m,
            HostHeights::Ellipsoidal => alt_m - self.cells.undulation_m(lat_deg, lon_deg),
        }
    }

    /// A height in the data's datum at (lat, lon) → the host's datum (an answer's).
    pub fn to_host_m(&mut self, lat_deg: f64, lon_deg: f64, h_m: f64) -> f64 {
        match self.heights {
            HostHeights::Msl => h_m,
            HostHeights::Ellipsoidal => h_m + self.cells.undulation_m(lat_deg, lon_deg),
        }
    }
}

/// A wire pose as the renderer's aircraft pose: local ENU positions (and their attitudes) as
/// they are, against the dataset's origin; geodetic ones at their exact point with the attitude
/// taken at that point ([`GeoMapping::to_world`], [`GeoMapping::attitude_at`]) — an error when
/// the dataset has no geographic reference (the reason from [`GeoMapping::of_dataset`]).
pub fn aircraft_pose(pose: &Pose, geo: Result<&GeoMapping, &str>) -> Result<AircraftPose, String> {
    let [h, p, r] = pose.attitude_deg;
    let attitude = Attitude::from_degrees(h, p, r);
    Ok(match pose.position {
        PosePosition::LocalEnu { x, y, z } => AircraftPose {
            position: DVec3::new(x, y, z),
            attitude,
        },
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => {
            let g =
                geo.map_err(|why| format!("received a geodetic pose (lat/lon/alt) but {why}"))?;
            AircraftPose {
                position: g.to_world(lat_deg, lon_deg, alt_m),
                attitude: g.attitude_at(lat_deg, lon_deg, attitude),
            }
        }
    })
}

/// `a − b` for host frame counters compared as 32-bit serial numbers (RFC 1982): CIGI's frame
/// counter is a u32 that wraps, and a native sequence's low 32 bits step the same way. Positive
/// when `a` is newer.
pub fn frame_diff(a: u64, b: u64) -> i64 {
    i64::from((a as u32).wrapping_sub(b as u32) as i32)
}

/// What [`FrameHistory::insert`] did with a pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Inserted {
    /// Kept (newest, or an older frame filled in).
    Kept,
    /// That frame number is already there.
    Duplicate,
    /// Older than everything kept and the history is full.
    TooOld,
    /// So far behind the newest that the host must have restarted: history cleared, kept.
    Restart,
}

/// Which pose a frame renders in frame-locked mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pick {
    /// The wanted host frame: newest − k.
    pub target: u64,
    /// The pose rendered: host frame `target` when it arrived, else the newest one before it
    /// (a lost packet). Never a frame after the target.
    pub sample: Stamped,
    /// `sample` is host frame `target`.
    pub exact: bool,
}

/// The last poses keyed by host frame counter (CIGI IG Control frame, native frame number),
/// for frame-locked rendering: every process on the stream renders frame `newest − k` with that
/// frame's own pose, so channels on different machines show the same host instant.
///
/// k trades latency for agreement: with k = 0 each machine renders whatever frame is newest when
/// its own frame starts, and two machines differ whenever a packet reaches one just before its
/// frame and the other just after; with k ≥ 1 a frame is rendered only once the next k have
/// arrived, which absorbs up to k host frames of network jitter between machines at the price
/// of k host frames of extra latency.
#[derive(Debug, Clone)]
pub struct FrameHistory {
    capacity: usize,
    /// Ordered oldest → newest by [`frame_diff`].
    entries: VecDeque<Stamped>,
}

/// Poses kept: a second of a 60 Hz host.
pub const HISTORY_FRAMES: usize = 64;

impl Default for FrameHistory {
    fn default() -> Self {
        Self::new(HISTORY_FRAMES)
    }
}

impl FrameHistory {
    pub fn new(capacity: usize) -> Self {
        Self {
            capacity: capacity.max(1),
            entries: VecDeque::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The newest host frame number kept.
    pub fn newest(&self) -> Option<u64> {
        self.entries.back().map(|s| s.pose.frame)
    }

    /// Adds a pose under its host frame number (`pose.frame`), in frame order whatever the
    /// arrival order; keeps the newest `capacity` frames.
    pub fn insert(&mut self, s: Stamped) -> Inserted {
        let key = s.pose.frame;
        let Some(newest) = self.newest() else {
            self.entries.push_back(s);
            return Inserted::Kept;
        };
        let d = frame_diff(key, newest);
        if d < -(2 * self.capacity as i64) {
            self.entries.clear();
            self.entries.push_back(s);
            return Inserted::Restart;
        }
        // First entry not older than `key`.
        let at = self
            .entries
            .partition_point(|e| frame_diff(e.pose.frame, key) < 0);
        if self
            .entries
            .get(at)
            .is_some_and(|e| frame_diff(e.pose.frame, key) == 0)
        {
            return Inserted::Duplicate;
        }
        if at == 0 && self.entries.len() >= self.capacity {
            return Inserted::TooOld;
        }
        self.entries.insert(at, s);
        while self.entries.len() > self.capacity {
            self.entries.pop_front();
        }
        Inserted::Kept
    }

    /// The pose to render for `--sync-frames k` (see [`Pick`]); `None` while no kept frame is
    /// at or before newest − k (just started: fewer than k + 1 frames seen).
    pub fn pick(&self, k: u32) -> Option<Pick> {
        let newest = self.newest()?;
        let target = newest.wrapping_sub(u64::from(k));
        // First entry newer than the target.
        let at = self
            .entries
            .partition_point(|e| frame_diff(e.pose.frame, target) <= 0);
        let sample = self.entries[at.checked_sub(1)?];
        let exact = frame_diff(sample.pose.frame, target) == 0;
        Some(Pick {
            target,
            sample,
            exact,
        })
    }
}

/// `--protocol`: a UDP protocol choice or shared memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputProtocol {
    Udp(ProtocolChoice),
    Shm,
}

impl std::str::FromStr for InputProtocol {
    type Err = String;
    /// The command-line words: auto, native, cigi, xplane, fgfs, shm (and the aliases
    /// [`ProtocolChoice`] knows, e.g. `aerie` for native).
    fn from_str(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("shm") {
            return Ok(InputProtocol::Shm);
        }
        s.parse::<ProtocolChoice>()
            .map(InputProtocol::Udp)
            .map_err(|_| {
                format!("unknown protocol `{s}` (expected auto, native, cigi, xplane, fgfs or shm)")
            })
    }
}

/// Everything needed to open the input (from the command line).
#[derive(Debug, Clone)]
pub struct InputSpec {
    pub protocol: InputProtocol,
    pub listen: SocketAddr,
    pub multicast: Option<Ipv4Addr>,
    /// Interface for the multicast join (0.0.0.0: the kernel chooses).
    pub multicast_interface: Ipv4Addr,
    pub allow: Vec<IpAddr>,
    pub shm_name: String,
    /// Extrapolation cap, seconds (0: never carried forward).
    pub cap_s: f64,
    /// Frame-locked mode: render host frame newest − k.
    pub sync_frames: Option<u32>,
    /// Local poses beyond ±this (any axis), metres, are dropped as implausible.
    pub world_bound_m: f64,
    /// Ask an X-Plane to stream RPOS to the port (`--xplane`).
    pub xplane_rpos: Option<RposRequest>,
    /// The datum of the host's geodetic altitudes (`--host-heights`).
    pub host_heights: HostHeights,
}

/// How long without a pose before the stream is reported lost when the extrapolation cap is
/// smaller (a cap of 0 must not make every frame "lost").
const MIN_LOST_AFTER_S: f64 = 0.1;

enum Transport {
    Udp(UdpReceiver),
    Shm(ShmSource),
}

/// What the frame loop learns about the pose it drew.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseInfo {
    /// Host frame number of the pose used (`pose.frame`).
    pub host_frame: u64,
    /// Frame-locked mode: the host frame wanted (newest − k).
    pub sync_target: Option<u64>,
    /// Sim time of the pose drawn (the sent one plus the extrapolation).
    pub sim_time_s: f64,
    /// Predicted display time minus the sample's arrival, seconds.
    pub age_s: f64,
    /// The pose was carried forward from the received one.
    pub extrapolated: bool,
    pub state: StreamState,
}

/// A running pose input: the receiver thread, its reader, and the frame-locked history.
pub struct SimInput {
    transport: Option<Transport>,
    reader: PoseReader,
    /// "udp 127.0.0.1:47800 (aerie)" — for messages.
    pub what: String,
    geo: Result<GeoMapping, String>,
    params: ExtrapolationParams,
    sync_frames: Option<u32>,
    history: FrameHistory,
    datum: HostDatum,
}

impl SimInput {
    /// The datum of the host's geodetic heights (`--host-heights`), for its entities and
    /// terrain queries too.
    pub fn host_heights(&self) -> HostHeights {
        self.datum.heights
    }
}

pub fn state_name(s: StreamState) -> &'static str {
    match s {
        StreamState::Waiting => "waiting",
        StreamState::Live => "live",
        StreamState::Lost => "lost",
    }
}

/// "received 12, accepted 10, dropped 2 (bad_crc 2)".
pub fn counters_text(s: &StatsSnapshot) -> String {
    let parts: Vec<String> = s
        .dropped_by_reason()
        .into_iter()
        .map(|(r, n)| format!("{r} {n}"))
        .collect();
    format!(
        "received {}, accepted {}, without pose {}, dropped {}{}{}",
        s.received,
        s.accepted,
        s.no_pose,
        s.dropped_total(),
        if parts.is_empty() {
            String::new()
        } else {
            format!(" ({})", parts.join(", "))
        },
        if s.shm_shrinks > 0 {
            format!(", shared-memory file shrank {} times", s.shm_shrinks)
        } else {
            String::new()
        }
    )
}

impl SimInput {
    /// Starts the receiver (binds the port, joins the group, or starts polling shared memory).
    pub fn open(spec: &InputSpec, geo: Result<GeoMapping, String>) -> Result<Self, String> {
        let params = ExtrapolationParams {
            cap_s: spec.cap_s,
            ..ExtrapolationParams::default()
        };
        // The reader's own cap only decides when the stream counts as lost; extrapolation
        // uses `params` (see `sample`).
        let monitor = ExtrapolationParams {
            cap_s: spec.cap_s.max(MIN_LOST_AFTER_S),
            ..params
        };
        let limits = PoseLimits::with_world_bound(spec.world_bound_m)?;
        let (transport, reader, what) = match spec.protocol {
            InputProtocol::Shm => {
                let path = shm_path(&spec.shm_name);
                let (src, reader) = ShmSource::spawn(ShmConfig {
                    path: path.clone(),
                    extrapolation: monitor,
                    limits,
                    ..ShmConfig::default()
                })
                .map_err(|e| format!("shared memory {}: {e}", path.display()))?;
                (
                    Transport::Shm(src),
                    reader,
                    format!("shared memory {} (shm)", path.display()),
                )
            }
            InputProtocol::Udp(protocol) => {
                let (rx, reader) = UdpReceiver::spawn(UdpConfig {
                    bind: spec.listen,
                    protocol,
                    multicast: spec.multicast,
                    multicast_interface: spec.multicast_interface,
                    allow: spec.allow.clone(),
                    extrapolation: monitor,
                    limits,
                    xplane_rpos: spec.xplane_rpos,
                    ..UdpConfig::default()
                })
                .map_err(|e| e.to_string())?;
                let p = match protocol {
                    ProtocolChoice::Auto => "auto".to_string(),
                    ProtocolChoice::Only(p) => p.to_string(),
                };
                let what = format!(
                    "udp {}{} ({p})",
                    rx.local_addr(),
                    spec.multicast
                        .map(|g| format!(" group {g}"))
                        .unwrap_or_default()
                );
                (Transport::Udp(rx), reader, what)
            }
        };
        Ok(Self {
            transport: Some(transport),
            reader,
            what,
            geo,
            params,
            sync_frames: spec.sync_frames,
            history: FrameHistory::default(),
            datum: HostDatum::new(spec.host_heights),
        })
    }

    /// Takes the newest accepted pose (and the one before it) into the frame history. Called
    /// every frame, and while a frame loop waits, so that few host frames are missed when the
    /// host sends faster than frames are drawn.
    pub fn poll(&mut self) {
        if self.sync_frames.is_none() {
            return;
        }
        if let Some(s) = self.reader.latest() {
            if let Some(p) = s.previous {
                self.history.insert(p);
            }
            self.history.insert(s.latest);
        }
    }

    /// The pose for a frame displayed at `display_s` ([`monotonic_s`] timeline): `None` before
    /// the first pose; `Err` when the pose cannot be placed (geodetic without geo-reference).
    ///
    /// Free-running: the newest pose carried forward to `display_s`, at most the cap.
    /// Frame-locked: host frame newest − k with its own pose as sent, never carried forward, so
    /// every process on the stream draws the same pose for the same host frame.
    pub fn sample(&mut self, display_s: f64) -> Result<Option<(AircraftPose, PoseInfo)>, String> {
        // Drives the live/lost state and its log lines.
        let _ = self.reader.pose_at(display_s);
        let state = self.reader.state();
        let (pose, info) = match self.sync_frames {
            Some(k) => {
                self.poll();
                let Some(pick) = self.history.pick(k) else {
                    return Ok(None);
                };
                let s = pick.sample;
                (
                    s.pose,
                    PoseInfo {
                        host_frame: s.pose.frame,
                        sync_target: Some(pick.target),
                        sim_time_s: s.pose.sim_time_s,
                        age_s: display_s - s.arrival_s,
                        extrapolated: false,
                        state,
                    },
                )
            }
            None => {
                let Some(s) = self.reader.latest() else {
                    return Ok(None);
                };
                let f = extrapolate(&s.latest, s.previous.as_ref(), display_s, &self.params);
                (
                    f.pose,
                    PoseInfo {
                        host_frame: f.pose.frame,
                        sync_target: None,
                        sim_time_s: f.pose.sim_time_s,
                        age_s: f.age_s,
                        extrapolated: f.extrapolated(),
                        state,
                    },
                )
            }
        };
        let pose = self.datum.pose_in_data_datum(&pose);
        let aircraft = aircraft_pose(&pose, self.geo.as_ref().map_err(String::as_str))?;
        Ok(Some((aircraft, info)))
    }

    /// [`Self::sample`] now.
    pub fn sample_now(&mut self, lead_s: f64) -> Result<Option<(AircraftPose, PoseInfo)>, String> {
        self.sample(monotonic_s() + lead_s)
    }

    /// The IG session of a UDP input (CIGI hosts and native queries are answered through it),
    /// `None` for shared memory.
    pub fn ig_link(&self) -> Option<aerie_sim_bridge::ig::IgLink> {
        match &self.transport {
            Some(Transport::Udp(rx)) => Some(rx.ig_link()),
            _ => None,
        }
    }

    /// Geodetic poses land through this mapping from now on (a new dataset was loaded).
    pub fn set_geo(&mut self, geo: Result<GeoMapping, String>) {
        self.geo = geo;
    }

    /// The UDP address bound (port 0 picks one), `None` for shared memory.
    pub fn local_addr(&self) -> Option<SocketAddr> {
        match &self.transport {
            Some(Transport::Udp(rx)) => Some(rx.local_addr()),
            _ => None,
        }
    }

    /// `--sync-frames k`.
    pub fn sync_frames(&self) -> Option<u32> {
        self.sync_frames
    }

    /// The host's latest CIGI views (View Control / View Definition), empty for other protocols.
    pub fn views(&mut self) -> &aerie_sim_bridge::codec::cigi::ViewTable {
        self.reader.views()
    }

    /// Counters now.
    pub fn stats(&self) -> StatsSnapshot {
        self.reader.stats()
    }

    /// The mapping to geodetic coordinates, when the dataset has one.
    pub fn geo(&self) -> Option<&GeoMapping> {
        self.geo.as_ref().ok()
    }

    /// Stops the receiver thread; the counters stay readable.
    pub fn stop(&mut self) {
        match self.transport.take() {
            Some(Transport::Udp(rx)) => {
                if let Err(e) = rx.stop() {
                    tracing::warn!("{}: {e}", self.what);
                }
            }
            Some(Transport::Shm(src)) => src.stop(),
            None => {}
        }
    }
}

impl Drop for SimInput {
    fn drop(&mut self) {
        self.stop();
    }
}

#[cfg(test)]
#[path = "pose_input_tests.rs"]
mod tests;
