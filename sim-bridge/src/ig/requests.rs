//! The host's HAT/HOT and line-of-sight requests between arrival and answer, and the answers'
//! content, per the CIGI ICD:
//!
//! - a request is answered in the IG's next message (the first frame begun after it arrived);
//! - update period 0 answers once; n > 0 answers every n-th IG frame until the host sends the
//!   same ID with period 0 (which answers once more and ends it) or the entity it is relative
//!   to is destroyed (a host's Reset drops every request);
//! - a request with the ID of a live one replaces it (HAT/HOT and LOS IDs are separate);
//! - a point the terrain cannot answer yet ([`Answer::Pending`]) is asked again next frame,
//!   and answered invalid after [`MAX_PENDING_FRAMES`] frames.
//!
//! Each frame runs in three steps so that the terrain is asked without holding the session:
//! [`RequestTable::due`] copies out [`Job`]s (points already placed against the entity table),
//! [`Job::ask`] asks the terrain, [`RequestTable::complete`] turns each outcome into a
//! [`Response`] or keeps the request for the next frame.

use std::collections::BTreeMap;

use glam::DVec3;

use crate::geodesy::{Geodetic, LocalTangentPlane};
use crate::pose::PosePosition;
use crate::query::{Answer, LosHit, Surface, TerrainQueries, MAX_PENDING_FRAMES};

use super::entities::{Anchor, AnchorError, EntityTable, Placed};

/// Live requests of each kind (HAT/HOT, LOS) at most; further IDs are answered invalid at once.
pub const MAX_REQUESTS: usize = 4096;

/// A request's point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RequestPoint {
    /// Latitude, longitude (degrees), altitude (metres above mean sea level).
    Geodetic(Geodetic),
    /// An offset in an entity's body axes (x forward, y right, z down), metres.
    Entity {
        /// The entity.
        entity: u16,
        /// The offset.
        offset_m: [f64; 3],
    },
}

impl RequestPoint {
    fn entity(&self) -> Option<u16> {
        match self {
            RequestPoint::Entity { entity, .. } => Some(*entity),
            RequestPoint::Geodetic(_) => None,
        }
    }
}

/// What a HAT/HOT request asks for (its response packet follows).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HotKind {
    /// Height above terrain → HAT/HOT Response.
    Hat,
    /// Height of terrain → HAT/HOT Response.
    Hot,
    /// Both, with material and normal → HAT/HOT Extended Response.
    Extended,
}

/// A HAT/HOT Request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HotRequest {
    /// HAT/HOT ID.
    pub id: u16,
    /// What to answer.
    pub kind: HotKind,
    /// The test point.
    pub at: RequestPoint,
    /// Frames between answers; 0 answers once (3.0/3.1 hosts have no such field: 0).
    pub period: u8,
}

/// A line-of-sight test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LosShape {
    /// Segment Request: from the source to the destination.
    Segment {
        /// Source.
        from: RequestPoint,
        /// Destination.
        to: RequestPoint,
    },
    /// Vector Request: a ray from the source between two ranges. For an entity-relative source
    /// the direction is in the entity's body axes (azimuth from x towards y, elevation up from
    /// the x-y plane), otherwise in the local frame (azimuth from true north, elevation up).
    Vector {
        /// Source.
        from: RequestPoint,
        /// Degrees.
        azimuth_deg: f64,
        /// Degrees.
        elevation_deg: f64,
        /// Metres.
        min_range_m: f64,
        /// Metres.
        max_range_m: f64,
    },
}

/// A LOS Segment or Vector Request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LosRequest {
    /// LOS ID (shared by segments and vectors).
    pub id: u16,
    /// Extended response wanted.
    pub extended: bool,
    /// The test.
    pub shape: LosShape,
    /// Frames between answers; 0 answers once.
    pub period: u8,
}

/// A request as the session receives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HostRequest {
    /// HAT/HOT.
    Hot(HotRequest),
    /// Line of sight.
    Los(LosRequest),
}

/// A HAT/HOT answer (Response or Extended Response, per `kind`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HotResponse {
    /// HAT/HOT ID.
    pub id: u16,
    /// The request's kind.
    pub kind: HotKind,
    /// False when the terrain could not answer (outside the data, not loaded in time, or an
    /// entity that is not known).
    pub valid: bool,
    /// Height above terrain, metres (0 when invalid).
    pub hat_m: f64,
    /// Height of terrain, metres above mean sea level (0 when invalid).
    pub hot_m: f64,
    /// Surface normal azimuth, degrees clockwise from true north (−180 … 180).
    pub normal_azimuth_deg: f32,
    /// Surface normal elevation, degrees above the local horizontal.
    pub normal_elevation_deg: f32,
    /// Material code (0 until land cover exists).
    pub material_code: u32,
}

/// A LOS answer (Response or Extended Response).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LosResponse {
    /// LOS ID.
    pub id: u16,
    /// Extended response.
    pub extended: bool,
    /// An intersection was found.
    pub valid: bool,
    /// Segments: the destination is visible from the source (the terrain answered and the
    /// segment is clear). Vectors: false.
    pub visible: bool,
    /// Range from the source to the intersection, metres (0 without one).
    pub range_m: f64,
    /// The intersection (zero without one).
    pub point: Geodetic,
    /// Surface normal azimuth at the intersection, degrees from true north.
    pub normal_azimuth_deg: f32,
    /// Surface normal elevation, degrees.
    pub normal_elevation_deg: f32,
    /// Material code (0).
    pub material_code: u32,
    /// Responses to this request in this frame (aerie reports the first intersection: 1).
    pub count: u8,
}

/// One answer for the host.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Response {
    /// HAT/HOT.
    Hot(HotResponse),
    /// Line of sight.
    Los(LosResponse),
}

/// A point copied out for a frame's job.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Located {
    /// Geodetic already.
    Point(Geodetic),
    /// Relative to an entity (placed when the job runs).
    Anchored(Anchor),
    /// Relative to an entity that cannot be placed.
    Unknown(AnchorError),
}

impl Located {
    fn of(p: &RequestPoint, entities: &EntityTable) -> Located {
        match *p {
            RequestPoint::Geodetic(g) => Located::Point(g),
            RequestPoint::Entity { entity, offset_m } => match entities.anchor(entity, offset_m) {
                Ok(a) => Located::Anchored(a),
                Err(e) => Located::Unknown(e),
            },
        }
    }

    /// The point, and (for an entity-relative one) where the entity's body axes are.
    fn place(&self, terrain: &dyn TerrainQueries) -> Result<(Geodetic, Option<Placed>), Miss> {
        match self {
            Located::Point(g) => Ok((*g, None)),
            Located::Unknown(_) => Err(Miss::Unresolved),
            Located::Anchored(a) => {
                let ground = |lat_deg: f64, lon_deg: f64| {
                    terrain.height_of_terrain(&PosePosition::Geodetic {
                        lat_deg,
                        lon_deg,
                        alt_m: 0.0,
                    })
                };
                match a.place(&ground) {
                    Answer::Ready(p) => Ok((p.point, Some(p))),
                    Answer::NoTerrain => Err(Miss::NoTerrain),
                    Answer::Pending => Err(Miss::Pending),
                }
            }
        }
    }
}

/// Why a job has no answer (yet).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Miss {
    Pending,
    NoTerrain,
    Unresolved,
}

/// Which table a job belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum JobKind {
    /// HAT/HOT.
    Hot,
    /// Line of sight.
    Los,
}

/// Identifies the request a job was copied from (a request replaced meanwhile has another
/// generation, and the stale outcome is dropped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JobKey {
    /// Table.
    pub kind: JobKind,
    /// Request ID.
    pub id: u16,
    generation: u64,
}

/// What a job asks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JobQuery {
    /// HAT/HOT at a point.
    Hot(Located),
    /// Segment.
    Segment(Located, Located),
    /// Vector.
    Vector {
        /// Source.
        from: Located,
        /// Degrees (see [`LosShape::Vector`]).
        azimuth_deg: f64,
        /// Degrees.
        elevation_deg: f64,
        /// Metres.
        min_range_m: f64,
        /// Metres.
        max_range_m: f64,
    },
}

/// One request's work for one frame: plain data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Job {
    /// The request.
    pub key: JobKey,
    /// The question.
    pub query: JobQuery,
}

/// A job's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    result: Result<Found, Miss>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Found {
    /// The terrain under a point at altitude `alt_m`.
    Hot { surface: Surface, alt_m: f64 },
    /// A line of sight, `None` when clear.
    Los(Option<LosHit>),
}

impl Outcome {
    /// True when the terrain was not ready.
    pub fn is_pending(&self) -> bool {
        self.result == Err(Miss::Pending)
    }
}

fn answer<T>(a: Answer<T>) -> Result<T, Miss> {
    match a {
        Answer::Ready(t) => Ok(t),
        Answer::NoTerrain => Err(Miss::NoTerrain),
        Answer::Pending => Err(Miss::Pending),
    }
}

fn geodetic(g: Geodetic) -> PosePosition {
    PosePosition::Geodetic {
        lat_deg: g.lat_deg,
        lon_deg: g.lon_deg,
        alt_m: g.alt_m,
    }
}

/// Azimuth (clockwise from north) and elevation of an east-north-up direction, degrees.
pub fn azimuth_elevation_deg(v: DVec3) -> (f64, f64) {
    let horizontal = v.x.hypot(v.y);
    (
        v.x.atan2(v.y).to_degrees(),
        v.z.atan2(horizontal).to_degrees(),
    )
}

impl Job {
    /// Asks the terrain (placing entity-relative points first).
    pub fn ask(&self, terrain: &dyn TerrainQueries) -> Outcome {
        let result = match &self.query {
            JobQuery::Hot(at) => at.place(terrain).and_then(|(p, _)| {
                answer(terrain.height_of_terrain(&geodetic(p))).map(|surface| Found::Hot {
                    surface,
                    alt_m: p.alt_m,
                })
            }),
            JobQuery::Segment(from, to) => from.place(terrain).and_then(|(a, _)| {
                let (b, _) = to.place(terrain)?;
                answer(terrain.line_of_sight(&geodetic(a), &geodetic(b))).map(Found::Los)
            }),
            JobQuery::Vector {
                from,
                azimuth_deg,
                elevation_deg,
                min_range_m,
                max_range_m,
            } => from.place(terrain).and_then(|(p, body)| {
                // An entity's vector is in its body axes: turned into the local frame here.
                let (az, el) = match body {
                    None => (*azimuth_deg, *elevation_deg),
                    Some(placed) => {
                        let (sa, ca) = azimuth_deg.to_radians().sin_cos();
                        let (se, ce) = elevation_deg.to_radians().sin_cos();
                        azimuth_elevation_deg(
                            placed.body_to_enu() * DVec3::new(ce * ca, ce * sa, -se),
                        )
                    }
                };
                answer(terrain.line_of_sight_vector(
                    &geodetic(p),
                    az,
                    el,
                    *min_range_m,
                    *max_range_m,
                ))
                .map(Found::Los)
            }),
        };
        Outcome { result }
    }
}

#[derive(Clone, Debug)]
struct Entry<R> {
    req: R,
    generation: u64,
    /// The frame tick it is next due at.
    due: u64,
    /// Consecutive frames the terrain said "pending".
    pending: u32,
    /// The tick it arrived at, until its first answer (for the latency).
    arrived: Option<u64>,
}

/// What [`RequestTable::complete`] decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Completion {
    /// An answer for the host; `latency_frames` is set for a request's first answer (frames
    /// from the frame it arrived in to this one).
    Answer {
        /// The response.
        response: Response,
        /// Frames since arrival (first answers only).
        latency_frames: Option<u64>,
        /// Answered invalid because the terrain stayed pending for [`MAX_PENDING_FRAMES`].
        timed_out: bool,
    },
    /// Asked again next frame.
    Retry,
    /// The request was replaced or cancelled meanwhile.
    Stale,
}

/// What [`RequestTable::add`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Added {
    /// A new request.
    New,
    /// It replaced a live one with the same ID (a periodic request so cancelled if this one
    /// has period 0).
    Replaced {
        /// The replaced one was periodic.
        was_periodic: bool,
    },
    /// The table is full: answered invalid next frame.
    Full,
}

/// The live requests.
#[derive(Clone, Debug, Default)]
pub struct RequestTable {
    hot: BTreeMap<u16, Entry<HotRequest>>,
    los: BTreeMap<u16, Entry<LosRequest>>,
    /// Requests refused because the table was full: answered invalid next frame.
    refused: Vec<HostRequest>,
    generation: u64,
}

fn insert<R>(
    map: &mut BTreeMap<u16, Entry<R>>,
    id: u16,
    e: Entry<R>,
    period: fn(&R) -> u8,
) -> Added {
    let len = map.len();
    match map.entry(id) {
        std::collections::btree_map::Entry::Occupied(mut o) => {
            let was_periodic = period(&o.get().req) > 0;
            o.insert(e);
            Added::Replaced { was_periodic }
        }
        std::collections::btree_map::Entry::Vacant(_) if len >= MAX_REQUESTS => Added::Full,
        std::collections::btree_map::Entry::Vacant(v) => {
            v.insert(e);
            Added::New
        }
    }
}

impl RequestTable {
    /// Live requests (HAT/HOT, LOS).
    pub fn len(&self) -> (usize, usize) {
        (self.hot.len(), self.los.len())
    }

    /// True when no request is live.
    pub fn is_empty(&self) -> bool {
        self.hot.is_empty() && self.los.is_empty() && self.refused.is_empty()
    }

    /// Periodic requests live.
    pub fn periodic(&self) -> usize {
        self.hot.values().filter(|e| e.req.period > 0).count()
            + self.los.values().filter(|e| e.req.period > 0).count()
    }

    /// Takes a request that arrived after frame tick `tick` began (due at the next one).
    pub fn add(&mut self, req: HostRequest, tick: u64) -> Added {
        self.generation += 1;
        let generation = self.generation;
        let due = tick + 1;
        let added = match req {
            HostRequest::Hot(r) => insert(
                &mut self.hot,
                r.id,
                Entry {
                    req: r,
                    generation,
                    due,
                    pending: 0,
                    arrived: Some(tick),
                },
                |r| r.period,
            ),
            HostRequest::Los(r) => insert(
                &mut self.los,
                r.id,
                Entry {
                    req: r,
                    generation,
                    due,
                    pending: 0,
                    arrived: Some(tick),
                },
                |r| r.period,
            ),
        };
        if added == Added::Full {
            self.refused.push(req);
        }
        added
    }

    /// Answers `req` invalid next frame without keeping it (a request packet whose values
    /// failed their checks).
    pub fn refuse(&mut self, req: HostRequest) {
        self.refused.push(req);
    }

    /// Drops every request (a host's Reset). Returns how many were live.
    pub fn clear(&mut self) -> usize {
        let n = self.hot.len() + self.los.len() + self.refused.len();
        self.hot.clear();
        self.los.clear();
        self.refused.clear();
        n
    }

    /// Cancels the periodic requests relative to `entity` (destroyed). Returns how many.
    pub fn cancel_for_entity(&mut self, entity: u16) -> usize {
        let before = self.hot.len() + self.los.len();
        self.hot
            .retain(|_, e| e.req.period == 0 || e.req.at.entity() != Some(entity));
        self.los.retain(|_, e| {
            let uses = match e.req.shape {
                LosShape::Segment { from, to } => {
                    from.entity() == Some(entity) || to.entity() == Some(entity)
                }
                LosShape::Vector { from, .. } => from.entity() == Some(entity),
            };
            e.req.period == 0 || !uses
        });
        before - self.hot.len() - self.los.len()
    }

    /// The jobs due at frame tick `tick`, points placed against `entities`; plus the invalid
    /// answers owed to requests refused for a full table.
    pub fn due(&mut self, tick: u64, entities: &EntityTable) -> (Vec<Job>, Vec<Response>) {
        let mut jobs = Vec::new();
        for (&id, e) in self.hot.iter().filter(|(_, e)| e.due <= tick) {
            jobs.push(Job {
                key: JobKey {
                    kind: JobKind::Hot,
                    id,
                    generation: e.generation,
                },
                query: JobQuery::Hot(Located::of(&e.req.at, entities)),
            });
        }
        for (&id, e) in self.los.iter().filter(|(_, e)| e.due <= tick) {
            let query = match &e.req.shape {
                LosShape::Segment { from, to } => {
                    JobQuery::Segment(Located::of(from, entities), Located::of(to, entities))
                }
                LosShape::Vector {
                    from,
                    azimuth_deg,
                    elevation_deg,
                    min_range_m,
                    max_range_m,
                } => JobQuery::Vector {
                    from: Located::of(from, entities),
                    azimuth_deg: *azimuth_deg,
                    elevation_deg: *elevation_deg,
                    min_range_m: *min_range_m,
                    max_range_m: *max_range_m,
                },
            };
            jobs.push(Job {
                key: JobKey {
                    kind: JobKind::Los,
                    id,
                    generation: e.generation,
                },
                query,
            });
        }
        let refused = std::mem::take(&mut self.refused)
            .into_iter()
            .map(|r| match r {
                HostRequest::Hot(h) => Response::Hot(hot_response(&h, Err(Miss::Unresolved))),
                HostRequest::Los(l) => Response::Los(los_response(&l, Err(Miss::Unresolved))),
            })
            .collect();
        (jobs, refused)
    }

    /// Records a job's outcome at frame tick `tick`.
    pub fn complete(&mut self, key: JobKey, outcome: Outcome, tick: u64) -> Completion {
        match key.kind {
            JobKind::Hot => finish(
                &mut self.hot,
                key,
                outcome,
                tick,
                |r| r.period,
                |r, o| Response::Hot(hot_response(r, o)),
            ),
            JobKind::Los => finish(
                &mut self.los,
                key,
                outcome,
                tick,
                |r| r.period,
                |r, o| Response::Los(los_response(r, o)),
            ),
        }
    }
}

fn finish<R>(
    map: &mut BTreeMap<u16, Entry<R>>,
    key: JobKey,
    outcome: Outcome,
    tick: u64,
    period: fn(&R) -> u8,
    respond: impl Fn(&R, Result<Found, Miss>) -> Response,
) -> Completion {
    let Some(e) = map
        .get_mut(&key.id)
        .filter(|e| e.generation == key.generation)
    else {
        return Completion::Stale;
    };
    let mut result = outcome.result;
    let mut timed_out = false;
    if result == Err(Miss::Pending) {
        e.pending += 1;
        if e.pending < MAX_PENDING_FRAMES {
            e.due = tick + 1;
            return Completion::Retry;
        }
        timed_out = true;
        result = Err(Miss::NoTerrain);
    }
    let response = respond(&e.req, result);
    let latency_frames = e.arrived.take().map(|a| tick.saturating_sub(a));
    e.pending = 0;
    let p = period(&e.req);
    if p == 0 {
        map.remove(&key.id);
    } else {
        e.due = tick + u64::from(p);
    }
    Completion::Answer {
        response,
        latency_frames,
        timed_out,
    }
}

fn normal_angles(n: [f64; 3]) -> (f32, f32) {
    let (az, el) = azimuth_elevation_deg(DVec3::from_array(n));
    (az as f32, el as f32)
}

fn hot_response(r: &HotRequest, result: Result<Found, Miss>) -> HotResponse {
    let mut out = HotResponse {
        id: r.id,
        kind: r.kind,
        valid: false,
        hat_m: 0.0,
        hot_m: 0.0,
        normal_azimuth_deg: 0.0,
        normal_elevation_deg: 0.0,
        material_code: 0,
    };
    if let Ok(Found::Hot { surface, alt_m }) = result {
        let (az, el) = normal_angles(surface.normal_enu);
        out.valid = true;
        out.hot_m = surface.height_m;
        out.hat_m = alt_m - surface.height_m;
        out.normal_azimuth_deg = az;
        out.normal_elevation_deg = el;
    }
    out
}

fn los_response(r: &LosRequest, result: Result<Found, Miss>) -> LosResponse {
    let segment = matches!(r.shape, LosShape::Segment { .. });
    let mut out = LosResponse {
        id: r.id,
        extended: r.extended,
        valid: false,
        visible: false,
        range_m: 0.0,
        point: Geodetic::new(0.0, 0.0, 0.0),
        normal_azimuth_deg: 0.0,
        normal_elevation_deg: 0.0,
        material_code: 0,
        count: 1,
    };
    match result {
        Ok(Found::Los(Some(hit))) => {
            let (az, el) = normal_angles(hit.normal_enu);
            out.valid = true;
            out.range_m = hit.range_m;
            out.point = match hit.point {
                PosePosition::Geodetic {
                    lat_deg,
                    lon_deg,
                    alt_m,
                } => Geodetic::new(lat_deg, lon_deg, alt_m),
                // The terrain answers in the frame it was asked in (geodetic here); a local
                // point would mean a terrain without a geo-reference.
                PosePosition::LocalEnu { .. } => Geodetic::new(0.0, 0.0, 0.0),
            };
            out.normal_azimuth_deg = az;
            out.normal_elevation_deg = el;
        }
        Ok(Found::Los(None)) => out.visible = segment,
        _ => {}
    }
    out
}

/// The point `range_m` along the ray from `from` towards (`azimuth_deg`, `elevation_deg`) in the
/// local frame at `from` (for tests and hosts checking a vector answer).
pub fn along_ray(from: Geodetic, azimuth_deg: f64, elevation_deg: f64, range_m: f64) -> Geodetic {
    let (sa, ca) = azimuth_deg.to_radians().sin_cos();
    let (se, ce) = elevation_deg.to_radians().sin_cos();
    LocalTangentPlane::new(from).enu_to_geodetic(DVec3::new(ce * sa, ce * ca, se) * range_m)
}

#[cfg(test)]
#[path = "requests_tests.rs"]
mod tests;
