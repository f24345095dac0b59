//! The IG session: a pure state machine between the host's messages and the IG's frames. No
//! sockets and no clocks: messages come in with their sender, frames with their number and
//! time, and each frame hands back the datagrams to send.
//!
//! - **One message per IG frame** to the host: Start of Frame (IG frame, last host frame
//!   received, IG mode, database, timestamp — in the host's CIGI version and byte order), then
//!   every HAT/HOT and line-of-sight response due that frame. However many host messages
//!   arrived in between, the host gets one Start of Frame per frame; a synchronous host is
//!   paced by the IG.
//! - **IG Mode**: a host message in Reset/Standby drops what the host created (requests,
//!   entities but the ownship) on entering it, ignores every packet but IG Control while it
//!   lasts, and Start of Frame reports Standby until the host asks for Operate (Debug and
//!   Offline Maintenance are run as Operate).
//! - **Database Number**: the host's last non-zero request is exposed; the frame says what is
//!   loaded ([`DatabaseStatus`]), and Start of Frame reports it (−n while loading, per CIGI).
//! - **Native queries** (`AERQ`) are answered in the same step, to their sender.

use std::collections::VecDeque;
use std::net::SocketAddr;

use crate::codec::cigi::{CigiMessage, CigiVersion, IgMode, RateFrame, StartOfFrame};
use crate::codec::native;
use crate::codec::ByteOrder;
use crate::query::{Answer, TerrainQueries, TerrainReply, TerrainRequest, MAX_PENDING_FRAMES};

use super::cigi_map;
use super::entities::{EntityChange, EntityRates, EntityTable};
use super::environment::Environment;
use super::requests::{Added, Completion, Job, Outcome, RequestTable, Response};
use super::stats::IgStats;

/// A message to the host is kept under this many bytes (responses that do not fit go first in
/// the next frame's message): well inside a CIGI host's usual receive buffer.
pub const MAX_MESSAGE_BYTES: usize = 16_384;
/// Native queries waiting for their terrain at most; further ones are answered "timed out".
pub const MAX_NATIVE_QUERIES: usize = 4096;

/// Where the IG's CIGI messages go.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum CigiReply {
    /// Never send.
    Off,
    /// To the address the host's last message came from.
    #[default]
    ToSender,
    /// To a fixed address (hosts that listen on another port than they send from); Start of
    /// Frame goes out from the first frame on, before the host said anything.
    To(SocketAddr),
}

/// The session's settings.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct IgConfig {
    /// Where CIGI messages go.
    pub reply: CigiReply,
}

/// What the IG has loaded, as the frame tells the session.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DatabaseStatus {
    /// Database `n` is loaded (Start of Frame says n).
    Ready(i8),
    /// Database `n` is loading (Start of Frame says −n).
    Loading(i8),
    /// The requested database does not exist (Start of Frame says −128).
    Unavailable,
}

impl Default for DatabaseStatus {
    fn default() -> Self {
        DatabaseStatus::Ready(0)
    }
}

impl DatabaseStatus {
    /// The Start of Frame's Database Number.
    pub fn wire(self) -> i8 {
        match self {
            DatabaseStatus::Ready(n) => n,
            DatabaseStatus::Loading(n) => n.checked_neg().unwrap_or(i8::MIN),
            DatabaseStatus::Unavailable => i8::MIN,
        }
    }
}

/// One IG frame as the frame loop announces it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IgFrame {
    /// IG frame counter (Start of Frame's).
    pub ig_frame: u32,
    /// The frame's time, seconds (Start of Frame's timestamp in 10 µs ticks; the ephemeris
    /// clock).
    pub time_s: f64,
    /// What is loaded.
    pub database: DatabaseStatus,
}

/// One datagram to send.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Datagram {
    /// Destination.
    pub to: SocketAddr,
    /// Payload.
    pub bytes: Vec<u8>,
}

/// What one frame sends.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameAnswers {
    /// The datagrams: the CIGI message first (if any), then native answers.
    pub datagrams: Vec<Datagram>,
    /// A Start of Frame is among them.
    pub start_of_frame: bool,
    /// CIGI responses in the message.
    pub responses: usize,
    /// Native answers.
    pub native: usize,
    /// Responses left for the next message (it was full).
    pub deferred: usize,
    /// CPU time spent answering, µs (measured by the caller; 0 from the pure session).
    pub cpu_us: f64,
}

/// The host-visible state, for the frame loop.
#[derive(Clone, Debug, PartialEq)]
pub struct IgState {
    /// The mode Start of Frame reports (Standby or Operate).
    pub mode: IgMode,
    /// Times the host reset the IG (the renderer watches it: views back to the configuration).
    pub resets: u64,
    /// The host's last non-zero Database Number.
    pub database_request: Option<i8>,
    /// Celestial and atmosphere settings.
    pub environment: Environment,
    /// The host's CIGI version and byte order (from its last message).
    pub host_version: Option<(CigiVersion, ByteOrder)>,
    /// Where the host's last message came from.
    pub host: Option<SocketAddr>,
    /// The host frame counter of its last message.
    pub last_host_frame: Option<u32>,
    /// Entities known (the ownship included).
    pub entities: usize,
    /// Requests live (HAT/HOT + LOS), periodic ones included.
    pub requests_live: usize,
}

impl Default for IgState {
    fn default() -> Self {
        Self {
            mode: IgMode::Operate,
            resets: 0,
            database_request: None,
            environment: Environment::default(),
            host_version: None,
            host: None,
            last_host_frame: None,
            entities: 0,
            requests_live: 0,
        }
    }
}

/// What [`IgSession::receive`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Received {
    /// The message put the IG into Standby (host-created state was dropped).
    pub reset: bool,
    /// Requests taken.
    pub requests: usize,
}

#[derive(Clone, Debug)]
struct NativeQuery {
    from: SocketAddr,
    id: u32,
    request: TerrainRequest,
    pending: u32,
}

/// The work of one frame, copied out of the session (to be asked without holding it).
#[derive(Clone, Debug)]
pub struct FrameWork {
    frame: IgFrame,
    tick: u64,
    jobs: Vec<Job>,
    refused: Vec<Response>,
    native: Vec<NativeQuery>,
}

/// A frame's work with the terrain's answers.
#[derive(Clone, Debug)]
pub struct AskedFrame {
    work: FrameWork,
    outcomes: Vec<Outcome>,
    replies: Vec<TerrainReply>,
}

fn pending_reply(r: &TerrainRequest) -> TerrainReply {
    match r {
        TerrainRequest::HeightOfTerrain { .. } => TerrainReply::HeightOfTerrain(Answer::Pending),
        _ => TerrainReply::LineOfSight(Answer::Pending),
    }
}

impl FrameWork {
    /// Asks the terrain every question of the frame.
    pub fn ask(self, terrain: &dyn TerrainQueries) -> AskedFrame {
        let outcomes = self.jobs.iter().map(|j| j.ask(terrain)).collect();
        let replies = self
            .native
            .iter()
            .map(|q| {
                if q.pending >= MAX_PENDING_FRAMES {
                    pending_reply(&q.request)
                } else {
                    q.request.ask(terrain)
                }
            })
            .collect();
        AskedFrame {
            work: self,
            outcomes,
            replies,
        }
    }

    /// Questions in this frame (CIGI and native).
    pub fn questions(&self) -> usize {
        self.jobs.len() + self.native.len()
    }
}

/// The IG session.
#[derive(Clone, Debug, Default)]
pub struct IgSession {
    config: IgConfig,
    /// Frames begun.
    tick: u64,
    /// The last frame's time (when a celestial setting arrives, its ephemeris clock starts).
    now_s: f64,
    standby: bool,
    state: IgState,
    entities: EntityTable,
    requests: RequestTable,
    deferred: VecDeque<Response>,
    native: Vec<NativeQuery>,
    stats: IgStats,
}

impl IgSession {
    /// A session with no host yet.
    pub fn new(config: IgConfig) -> Self {
        Self {
            config,
            ..Self::default()
        }
    }

    /// The host-visible state.
    pub fn state(&self) -> IgState {
        let mut s = self.state.clone();
        s.entities = self.entities.len();
        let (h, l) = self.requests.len();
        s.requests_live = h + l;
        s
    }

    /// Counters.
    pub fn stats(&self) -> IgStats {
        let mut s = self.stats.clone();
        let (h, l) = self.requests.len();
        s.requests_live = (h + l) as u64;
        s.periodic_live = self.requests.periodic() as u64;
        s.native_waiting = self.native.len() as u64;
        s.entities = self.entities.len() as u64;
        s
    }

    /// The entity table.
    pub fn entities(&self) -> &EntityTable {
        &self.entities
    }

    /// Takes one accepted CIGI message from `from`.
    pub fn receive(&mut self, m: &CigiMessage, from: SocketAddr) -> Received {
        let st = &mut self.stats;
        st.messages += 1;
        st.packets.merge(&m.packet_counts);
        st.rejected_packets += m.rejected.len() as u64;
        self.state.host = Some(from);
        self.state.host_version = Some((m.version, m.byte_order));
        let host_frame = m.ig_control.host_frame;
        self.state.last_host_frame = Some(host_frame);
        if m.ig_control.database != 0 {
            self.state.database_request = Some(m.ig_control.database);
        }
        let mut out = Received::default();
        if m.ig_control.mode() == IgMode::ResetOrStandby {
            if !self.standby {
                self.standby = true;
                self.state.resets += 1;
                self.state.mode = IgMode::ResetOrStandby;
                self.stats.requests_dropped += self.requests.clear() as u64;
                self.stats.requests_dropped += self.deferred.len() as u64;
                self.deferred.clear();
                self.entities.clear_host_entities();
                out.reset = true;
            }
            // Standby: nothing but IG Control is applied.
            self.stats.ignored_in_standby += m.packet_counts.total().saturating_sub(1);
            return out;
        }
        if self.standby {
            self.standby = false;
            self.state.mode = IgMode::Operate;
        }
        for e in &m.entities {
            let change = self
                .entities
                .apply_control(&cigi_map::entity_control(e), host_frame);
            self.count_entity(change, e.entity_id);
        }
        for c in &m.conformal_clamped {
            let change = self.entities.apply_clamped(
                c.entity_id,
                c.yaw_deg.into(),
                c.lat_deg,
                c.lon_deg,
                host_frame,
            );
            self.count_entity(change, c.entity_id);
        }
        for r in &m.rate_controls {
            if r.apply_to_articulated_part {
                self.stats.part_rates_ignored += 1;
                continue;
            }
            let rates = EntityRates {
                linear_m_s: r.linear_m_s,
                angular_deg_s: r.angular_deg_s,
                world_frame: r.frame == RateFrame::WorldOrParent,
            };
            self.entities.apply_rates(r.entity_id, rates, host_frame);
        }
        if let Some(c) = &m.celestial {
            self.state.environment.celestial = Some(cigi_map::celestial(c, self.now_s));
        }
        if let Some(a) = &m.atmosphere {
            self.state.environment.atmosphere = Some(cigi_map::atmosphere(a));
        }
        for r in &m.requests {
            self.take_request(cigi_map::request(r));
            out.requests += 1;
        }
        for r in &m.rejected {
            // Answered invalid once, with the response its type asks for when it could be read.
            let req = match &r.request {
                Some(req) => Some(cigi_map::request(req)),
                None => r
                    .request_id
                    .and_then(|id| cigi_map::rejected_request(r.packet_id, id)),
            };
            if let Some(req) = req {
                self.stats.requests_rejected += 1;
                self.requests.refuse(req);
            }
        }
        out
    }

    fn take_request(&mut self, r: super::requests::HostRequest) {
        self.stats.requests_received += 1;
        match self.requests.add(r, self.tick) {
            Added::New => {}
            Added::Replaced { was_periodic } => {
                if was_periodic {
                    self.stats.requests_cancelled += 1;
                }
            }
            Added::Full => self.stats.requests_refused += 1,
        }
    }

    fn count_entity(&mut self, change: EntityChange, id: u16) {
        match change {
            EntityChange::Created => self.stats.entities_created += 1,
            EntityChange::Destroyed => {
                self.stats.entities_destroyed += 1;
                self.stats.requests_cancelled += self.requests.cancel_for_entity(id) as u64;
            }
            EntityChange::Full => self.stats.entities_refused += 1,
            EntityChange::Updated | EntityChange::Ignored => {}
        }
    }

    /// Takes a native terrain query (`AERQ`) from `from`.
    pub fn receive_native(&mut self, id: u32, request: TerrainRequest, from: SocketAddr) {
        self.stats.native_received += 1;
        let pending = if self.native.len() >= MAX_NATIVE_QUERIES {
            // Answered "timed out" at once rather than queued without bound.
            self.stats.native_refused += 1;
            MAX_PENDING_FRAMES
        } else {
            0
        };
        self.native.push(NativeQuery {
            from,
            id,
            request,
            pending,
        });
    }

    /// Starts frame `f`: the work to ask the terrain (then [`FrameWork::ask`] and
    /// [`finish`](Self::finish)). Requests arriving from now on are due next frame.
    pub fn prepare(&mut self, f: &IgFrame) -> FrameWork {
        self.tick += 1;
        if f.time_s.is_finite() {
            self.now_s = f.time_s;
        }
        let (jobs, refused) = self.requests.due(self.tick, &self.entities);
        FrameWork {
            frame: *f,
            tick: self.tick,
            jobs,
            refused,
            native: std::mem::take(&mut self.native),
        }
    }

    /// Ends a frame: records the answers, keeps what is still pending, and builds the
    /// datagrams (the CIGI message first).
    pub fn finish(&mut self, asked: AskedFrame) -> FrameAnswers {
        let AskedFrame {
            work,
            outcomes,
            replies,
        } = asked;
        let tick = work.tick;
        let mut due: Vec<Response> = self.deferred.drain(..).collect();
        for r in work.refused {
            self.stats.answered_invalid += 1;
            self.stats.note_latency(1);
            due.push(r);
        }
        for (job, outcome) in work.jobs.iter().zip(outcomes) {
            match self.requests.complete(job.key, outcome, tick) {
                Completion::Answer {
                    response,
                    latency_frames,
                    timed_out,
                } => {
                    if let Some(l) = latency_frames {
                        self.stats.note_latency(l);
                    }
                    self.stats.timed_out += u64::from(timed_out);
                    if response_valid(&response) {
                        self.stats.answered += 1;
                    } else {
                        self.stats.answered_invalid += 1;
                    }
                    due.push(response);
                }
                Completion::Retry => self.stats.retries += 1,
                Completion::Stale => self.stats.stale += 1,
            }
        }
        let mut out = FrameAnswers::default();
        if let Some((to, bytes, sent, deferred)) = self.message(&work.frame, due) {
            out.start_of_frame = true;
            out.responses = sent;
            out.deferred = deferred;
            out.datagrams.push(Datagram { to, bytes });
            self.stats.start_of_frames += 1;
            self.stats.responses_sent += sent as u64;
            self.stats.deferred += deferred as u64;
        }
        for (mut q, reply) in work.native.into_iter().zip(replies) {
            if TerrainRequest::is_pending(&reply) {
                q.pending += 1;
                if q.pending < MAX_PENDING_FRAMES {
                    self.native.push(q);
                    continue;
                }
                self.stats.native_timed_out += 1;
            }
            self.stats.native_answered += 1;
            out.native += 1;
            out.datagrams.push(Datagram {
                to: q.from,
                bytes: native::encode_reply(q.id, &reply),
            });
        }
        out
    }

    /// The frame's CIGI message: destination, bytes, responses in it, responses deferred.
    /// `None` when there is no one to send it to (or replies are off: the answers are
    /// dropped).
    fn message(
        &mut self,
        f: &IgFrame,
        due: Vec<Response>,
    ) -> Option<(SocketAddr, Vec<u8>, usize, usize)> {
        let to = match self.config.reply {
            CigiReply::Off => None,
            CigiReply::ToSender => self.state.host,
            CigiReply::To(a) => Some(a),
        };
        let Some(to) = to else {
            self.stats.responses_unsent += due.len() as u64;
            return None;
        };
        // Before any host message: the newest version, little-endian (most hosts' order).
        let (version, order) = self
            .state
            .host_version
            .unwrap_or((CigiVersion::V3_3, ByteOrder::Little));
        let host_frame = self.state.last_host_frame.unwrap_or(0);
        let sof = StartOfFrame {
            database: f.database.wire(),
            ig_status: 0,
            ig_mode: if self.standby {
                IgMode::ResetOrStandby.bits()
            } else {
                IgMode::Operate.bits()
            },
            timestamp_valid: f.time_s.is_finite() && f.time_s >= 0.0,
            earth_reference_model: 0,
            ig_frame: f.ig_frame,
            timestamp: timestamp_ticks(f.time_s),
            last_host_frame: host_frame,
        };
        let mut bytes = sof.encode(version, order);
        let mut sent = 0;
        let mut rest = due.into_iter();
        let mut packet = Vec::with_capacity(64);
        for r in rest.by_ref() {
            packet.clear();
            cigi_map::response(&r, host_frame).encode_into(version, order, &mut packet);
            if bytes.len() + packet.len() > MAX_MESSAGE_BYTES {
                self.deferred.push_back(r);
                break;
            }
            bytes.extend_from_slice(&packet);
            sent += 1;
        }
        self.deferred.extend(rest);
        Some((to, bytes, sent, self.deferred.len()))
    }

    /// One whole frame: [`prepare`](Self::prepare), [`FrameWork::ask`],
    /// [`finish`](Self::finish).
    pub fn begin_frame(&mut self, f: &IgFrame, terrain: &dyn TerrainQueries) -> FrameAnswers {
        let work = self.prepare(f);
        let asked = work.ask(terrain);
        self.finish(asked)
    }

    /// Adds the CPU time the caller measured for a frame's answers.
    pub fn record_cpu_us(&mut self, us: f64) {
        self.stats.note_cpu_us(us);
    }

    /// Counts datagrams the transport failed to send.
    pub fn record_send_errors(&mut self, n: u64) {
        self.stats.send_errors += n;
    }
}

fn response_valid(r: &Response) -> bool {
    match r {
        Response::Hot(h) => h.valid,
        // A clear segment is an answer too (valid = "an intersection was found").
        Response::Los(l) => l.valid || l.visible,
    }
}

/// Seconds → CIGI's 10 µs timestamp ticks (wrapping, as hosts expect after 11.9 h).
pub fn timestamp_ticks(time_s: f64) -> u32 {
    if time_s.is_finite() && time_s >= 0.0 {
        ((time_s * 1e5) as u64) as u32
    } else {
        0
    }
}

#[cfg(test)]
#[path = "session_tests.rs"]
mod tests;
