//! Simulator pose input for `aerie run` (issue 6 item 7, issue 7 item 4): the pose of each frame
//! from a UDP or shared-memory stream ([`aerie_sim_bridge`]), converted into the dataset's local
//! frame, either carried forward to the frame's display time or locked to a host frame number.
//!
//! Pure decisions, tested without sockets or a device:
//! - [`GeoMapping`]: WGS84 latitude/longitude/altitude ↔ the dataset's local metres, the same
//!   mapping the terrain loaders use to place a geographic grid;
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
use aerie_terrain::dataset::Dataset;
use aerie_terrain::GeoReference;

/// Where geodetic poses land in the dataset's local frame.
///
/// The terrain loaders put a geographic grid (SRTM `.hgt`, geographic GeoTIFF, stitched tiles)
/// on a regular metric grid: sample (col, row) sits at `x = col · spacing_x`, `y = row ·
/// spacing_y`, where col/row count `dlon`/`dlat` steps from the south-west sample and the
/// spacings are the WGS84 arc lengths of one step at the grid's centre latitude
/// (`terrain::load::geographic_spacing_m`). A pose must land on the ground the terrain shows
/// there, so it goes through the *same* linear map:
///
/// ```text
/// x = (lon − west_lon) / dlon · spacing_x      y = (lat − south_lat) / dlat · spacing_y
/// z = altitude as sent (metres; the grid's heights are metres above sea level, like CIGI's)
/// ```
///
/// North is +y everywhere on this grid, so headings need no correction. It is not a tangent
/// plane: far from the centre latitude the east-west scale differs from the true one by
/// `cos(lat)/cos(centre)` — the terrain is drawn with the same distortion, so the aircraft
/// stays over the right ground. Longitudes are taken the short way round from `west_lon`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoMapping {
    pub south_lat_deg: f64,
    pub west_lon_deg: f64,
    pub dlat_deg: f64,
    pub dlon_deg: f64,
    pub spacing_x: f64,
    pub spacing_y: f64,
}

impl GeoMapping {
    /// The mapping of a dataset with a geographic geo-reference; `Err` names why there is none.
    pub fn of_dataset(ds: &Dataset) -> Result<Self, String> {
        match &ds.hf.geo {
            Some(GeoReference::Geographic {
                south_lat_deg,
                west_lon_deg,
                dlat_deg,
                dlon_deg,
            }) => Ok(Self {
                south_lat_deg: *south_lat_deg,
                west_lon_deg: *west_lon_deg,
                dlat_deg: *dlat_deg,
                dlon_deg: *dlon_deg,
                spacing_x: ds.hf.spacing_x,
                spacing_y: ds.hf.spacing_y,
            }),
            Some(GeoReference::Projected { crs, .. }) => Err(format!(
                "{}: projected grid ({crs}); geodetic poses need a geographic (lat/lon) dataset, send local x/y/z instead",
                ds.source
            )),
            None => Err(format!(
                "{}: no geo-reference; geodetic poses need a geo-referenced dataset (e.g. SRTM .hgt), send local x/y/z instead",
                ds.source
            )),
        }
    }

    /// Latitude/longitude (degrees) and altitude (metres) → local metres.
    pub fn to_local(&self, lat_deg: f64, lon_deg: f64, alt_m: f64) -> DVec3 {
        let dlon = (lon_deg - self.west_lon_deg + 180.0).rem_euclid(360.0) - 180.0;
        DVec3::new(
            dlon / self.dlon_deg * self.spacing_x,
            (lat_deg - self.south_lat_deg) / self.dlat_deg * self.spacing_y,
            alt_m,
        )
    }

    /// Local metres → (latitude, longitude in [−180, 180), altitude).
    pub fn to_geodetic(&self, p: DVec3) -> (f64, f64, f64) {
        let lon = self.west_lon_deg + p.x / self.spacing_x * self.dlon_deg;
        (
            self.south_lat_deg + p.y / self.spacing_y * self.dlat_deg,
            (lon + 180.0).rem_euclid(360.0) - 180.0,
            p.z,
        )
    }
}

/// A wire pose as the renderer's aircraft pose: local ENU positions as they are, geodetic ones
/// through `geo` (an error when the dataset has none: the reason from [`GeoMapping::of_dataset`]).
pub fn aircraft_pose(pose: &Pose, geo: Result<&GeoMapping, &str>) -> Result<AircraftPose, String> {
    let position = match pose.position {
        PosePosition::LocalEnu { x, y, z } => DVec3::new(x, y, z),
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => geo
            .map_err(|why| format!("received a geodetic pose (lat/lon/alt) but {why}"))?
            .to_local(lat_deg, lon_deg, alt_m),
    };
    let [h, p, r] = pose.attitude_deg;
    Ok(AircraftPose {
        position,
        attitude: Attitude::from_degrees(h, p, r),
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
mod tests {
    use super::*;

    fn stamped(frame: u64, arrival_s: f64) -> Stamped {
        Stamped {
            pose: Pose {
                position: PosePosition::LocalEnu {
                    x: frame as f64,
                    y: 0.0,
                    z: 100.0,
                },
                attitude_deg: [0.0; 3],
                sim_time_s: frame as f64 / 60.0,
                frame,
                velocity_enu: None,
                angular_rates_deg_s: None,
            },
            arrival_s,
            sample: frame,
        }
    }

    fn frames(h: &FrameHistory) -> Vec<u64> {
        h.entries.iter().map(|s| s.pose.frame).collect()
    }

    #[test]
    fn serial_frame_numbers_wrap() {
        assert_eq!(frame_diff(5, 3), 2);
        assert_eq!(frame_diff(3, 5), -2);
        assert_eq!(frame_diff(1, u64::from(u32::MAX)), 2);
        assert_eq!(frame_diff(u64::from(u32::MAX), 1), -2);
    }

    #[test]
    fn newest_minus_k_with_reordering() {
        let mut h = FrameHistory::new(8);
        for f in [10, 12, 11, 14, 13] {
            assert_eq!(h.insert(stamped(f, 0.0)), Inserted::Kept, "{f}");
        }
        assert_eq!(frames(&h), [10, 11, 12, 13, 14]);
        assert_eq!(h.insert(stamped(12, 1.0)), Inserted::Duplicate);
        let p = h.pick(0).unwrap();
        assert_eq!((p.target, p.sample.pose.frame, p.exact), (14, 14, true));
        let p = h.pick(2).unwrap();
        assert_eq!((p.target, p.sample.pose.frame, p.exact), (12, 12, true));
        // Fewer than k + 1 frames seen: nothing yet (never a frame after the target).
        assert!(h.pick(5).is_none());
        assert_eq!(h.pick(4).unwrap().sample.pose.frame, 10);
        assert!(FrameHistory::new(4).pick(0).is_none());
    }

    #[test]
    fn gap_renders_the_newest_frame_before_the_target() {
        let mut h = FrameHistory::new(8);
        for f in [20, 21, 23, 24] {
            h.insert(stamped(f, 0.0));
        }
        // 22 was lost: newest − 2 = 22 → 21, not exact.
        let p = h.pick(2).unwrap();
        assert_eq!((p.target, p.sample.pose.frame, p.exact), (22, 21, false));
        // The late 22 fills the gap.
        assert_eq!(h.insert(stamped(22, 0.1)), Inserted::Kept);
        let p = h.pick(2).unwrap();
        assert_eq!((p.sample.pose.frame, p.exact), (22, true));
    }

    #[test]
    fn capacity_and_wraparound() {
        let mut h = FrameHistory::new(4);
        let max = u64::from(u32::MAX);
        for f in [max - 2, max - 1, max, 0, 1] {
            assert_eq!(h.insert(stamped(f, 0.0)), Inserted::Kept, "{f}");
        }
        // Wrapped frame numbers are newer; the oldest was dropped to keep 4.
        assert_eq!(frames(&h), [max - 1, max, 0, 1]);
        assert_eq!(h.newest(), Some(1));
        let p = h.pick(2).unwrap();
        assert_eq!((p.sample.pose.frame, p.exact), (max, true));
        // Older than everything kept while full.
        assert_eq!(h.insert(stamped(max - 3, 0.0)), Inserted::TooOld);
        // A host restart far behind: start over.
        assert_eq!(h.insert(stamped(max - 1000, 0.0)), Inserted::Restart);
        assert_eq!(frames(&h), [max - 1000]);
    }

    #[test]
    fn picks_agree_for_any_arrival_order() {
        // Two machines receiving the same frames in different orders and at different times
        // render the same pose for the same target once the target has arrived.
        let order_a = [1u64, 2, 3, 4, 5, 6, 7, 8];
        let order_b = [2u64, 1, 4, 3, 6, 5, 8, 7];
        let (mut a, mut b) = (FrameHistory::new(16), FrameHistory::new(16));
        for (fa, fb) in order_a.iter().zip(order_b) {
            a.insert(stamped(*fa, 0.0));
            b.insert(stamped(fb, 0.5));
            for k in 0..3 {
                if let (Some(pa), Some(pb)) = (a.pick(k), b.pick(k)) {
                    assert!(pa.sample.pose.frame <= pa.target);
                    if pa.target == pb.target && pa.exact && pb.exact {
                        assert_eq!(pa.sample.pose, pb.sample.pose);
                    }
                }
            }
        }
        assert_eq!(
            a.pick(1).unwrap().sample.pose,
            b.pick(1).unwrap().sample.pose
        );
    }

    fn inn_valley() -> GeoMapping {
        // N47E011 at 3": spacing at the centre latitude 47.5°.
        let (sx, sy) = aerie_terrain::load::geographic_spacing_m(47.5, 1.0 / 1200.0, 1.0 / 1200.0);
        GeoMapping {
            south_lat_deg: 47.0,
            west_lon_deg: 11.0,
            dlat_deg: 1.0 / 1200.0,
            dlon_deg: 1.0 / 1200.0,
            spacing_x: sx,
            spacing_y: sy,
        }
    }

    #[test]
    fn geodetic_lands_on_the_sample_grid() {
        let g = inn_valley();
        // Sample (col 600, row 300) is at lon 11.5°, lat 47.25°.
        let p = g.to_local(47.25, 11.5, 2500.0);
        assert!((p.x - 600.0 * g.spacing_x).abs() < 1e-6, "{p}");
        assert!((p.y - 300.0 * g.spacing_y).abs() < 1e-6, "{p}");
        assert_eq!(p.z, 2500.0);
        let (lat, lon, alt) = g.to_geodetic(p);
        assert!((lat - 47.25).abs() < 1e-12 && (lon - 11.5).abs() < 1e-12 && alt == 2500.0);
        // Longitudes given in [180, 360) or across the antimeridian go the short way.
        let w = GeoMapping {
            west_lon_deg: 179.5,
            ..g
        };
        let a = w.to_local(47.0, -179.75, 0.0);
        assert!((a.x - 900.0 * g.spacing_x).abs() < 1e-6, "{a}");
        let b = w.to_local(47.0, 180.25, 0.0);
        assert!((a.x - b.x).abs() < 1e-6);
    }

    #[test]
    fn geodetic_pose_needs_a_geo_reference() {
        let pose = Pose {
            position: PosePosition::Geodetic {
                lat_deg: 47.1,
                lon_deg: 11.2,
                alt_m: 3000.0,
            },
            attitude_deg: [90.0, -5.0, 10.0],
            sim_time_s: 0.0,
            frame: 1,
            velocity_enu: None,
            angular_rates_deg_s: None,
        };
        let e = aircraft_pose(&pose, Err("gen.f32: no geo-reference")).unwrap_err();
        assert!(
            e.contains("geodetic") && e.contains("gen.f32: no geo-reference"),
            "{e}"
        );
        let g = inn_valley();
        let a = aircraft_pose(&pose, Ok(&g)).unwrap();
        assert_eq!(a.position, g.to_local(47.1, 11.2, 3000.0));
        assert!((a.attitude.heading.to_degrees() - 90.0).abs() < 1e-12);
        assert!((a.attitude.roll.to_degrees() - 10.0).abs() < 1e-12);
        // Local poses need nothing.
        let local = Pose {
            position: PosePosition::LocalEnu {
                x: 1.0,
                y: 2.0,
                z: 3.0,
            },
            ..pose
        };
        let a = aircraft_pose(&local, Err("none")).unwrap();
        assert_eq!(a.position, DVec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn protocols_parse() {
        assert_eq!("shm".parse::<InputProtocol>(), Ok(InputProtocol::Shm));
        assert_eq!(
            "cigi".parse::<InputProtocol>(),
            Ok(InputProtocol::Udp(ProtocolChoice::Only(
                aerie_sim_bridge::Protocol::Cigi
            )))
        );
        assert!("ftp".parse::<InputProtocol>().unwrap_err().contains("shm"));
    }
}
