//! The entities a host has created (Entity Control, Conformal Clamped Entity Control, Rate
//! Control), kept in a bounded table, and entity-relative points resolved to the world.
//!
//! Body axes are CIGI's: x forward, y right, z down, rotated from the local north-east-down
//! frame by heading (yaw), pitch and roll in that order. Positions are geodetic with the
//! altitude the host gives (mean sea level); an offset of a few hundred metres is taken in the
//! local tangent plane at the entity, where the geoid's slope changes heights by micrometres.
//! The renderer draws the table each frame (`renderer/src/sim/traffic.rs`): the entities
//! dead-reckoned by their Rate Control from the last time the host placed them
//! ([`EntityTable::advanced`]), then placed with [`EntityTable::anchor`].

use std::collections::BTreeMap;

use glam::{DMat3, DVec3};

use crate::geodesy::{Geodetic, LocalTangentPlane};
use crate::query::{Answer, Surface};

/// Entity ID of the ownship (kept through a host's Reset).
pub const OWNSHIP_ID: u16 = 0;
/// At most this many entities are kept; Entity Controls creating more are refused and counted.
pub const MAX_ENTITIES: usize = 1024;
/// Deepest chain of attached entities followed when resolving a point (a longer chain, or a
/// loop, cannot be resolved).
pub const MAX_ATTACH_DEPTH: usize = 16;

/// An entity's state as the host set it (a destroyed entity leaves the table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EntityState {
    /// Inactive / standby: kept, not drawn.
    Inactive,
    /// Active.
    Active,
}

/// Where an entity is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// Latitude, longitude (degrees) and altitude (metres above mean sea level).
    Geodetic(Geodetic),
    /// Conformal clamped: on the terrain at this latitude and longitude, pitched and rolled
    /// with its slope (the IG supplies altitude, pitch and roll).
    Clamped {
        /// Degrees.
        lat_deg: f64,
        /// Degrees.
        lon_deg: f64,
    },
    /// Attached to a parent: an offset in the parent's body axes (x forward, y right, z down),
    /// metres; the attitude is then relative to the parent's.
    Attached {
        /// The parent entity.
        parent: u16,
        /// Offset from the parent's reference point, metres.
        offset_m: [f64; 3],
    },
}

/// Rates set by Rate Control for the entity itself (not an articulated part).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EntityRates {
    /// x, y, z linear rates, m/s.
    pub linear_m_s: [f32; 3],
    /// Roll, pitch, yaw rates, degrees per second.
    pub angular_deg_s: [f32; 3],
    /// Rates in the world frame (CIGI 3.2+ coordinate system flag), else in body axes.
    pub world_frame: bool,
}

/// One entity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entity {
    /// Entity ID.
    pub id: u16,
    /// Entity type (the host's model number).
    pub entity_type: u16,
    /// Active or inactive.
    pub state: EntityState,
    /// Alpha, 0 transparent … 255 opaque.
    pub alpha: u8,
    /// Where it is.
    pub placement: Placement,
    /// Heading, pitch, roll, degrees (relative to the parent when attached; pitch and roll are
    /// the terrain's when clamped).
    pub attitude_deg: [f64; 3],
    /// The last Rate Control for the entity.
    pub rates: Option<EntityRates>,
    /// The host frame of the last packet that touched it.
    pub host_frame: u32,
    /// Which placement of the table last set its position or attitude (Entity Control or
    /// Conformal Clamped; rates do not count): dead reckoning runs from that moment.
    pub placed: u64,
}

/// An Entity Control, as the table takes it (from any CIGI version).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EntityControlUpdate {
    /// Entity ID.
    pub id: u16,
    /// 0 inactive, 1 active, 2 destroyed.
    pub state: u8,
    /// Attached to `parent` (the position is then an offset).
    pub attached: bool,
    /// Parent entity ID.
    pub parent: u16,
    /// Entity type.
    pub entity_type: u16,
    /// Alpha.
    pub alpha: u8,
    /// Latitude or x offset.
    pub lat_or_x: f64,
    /// Longitude or y offset.
    pub lon_or_y: f64,
    /// Altitude or z offset.
    pub alt_or_z: f64,
    /// Heading (yaw), pitch, roll, degrees.
    pub attitude_deg: [f64; 3],
}

/// What an update did to the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EntityChange {
    /// A new entity.
    Created,
    /// An existing one changed.
    Updated,
    /// Destroyed and removed (requests relative to it are cancelled).
    Destroyed,
    /// Refused: the table is full.
    Full,
    /// Nothing (a destroy or rate for an unknown entity).
    Ignored,
}

/// The table of entities, by ID.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EntityTable {
    entities: BTreeMap<u16, Entity>,
    /// Placements applied so far (stamps [`Entity::placed`]).
    placements: u64,
}

impl EntityTable {
    /// Known entities (the ownship included once the host sent it).
    pub fn len(&self) -> usize {
        self.entities.len()
    }

    /// True when no entity is known.
    pub fn is_empty(&self) -> bool {
        self.entities.is_empty()
    }

    /// The entity `id`.
    pub fn get(&self, id: u16) -> Option<&Entity> {
        self.entities.get(&id)
    }

    /// Every entity, by ascending ID.
    pub fn iter(&self) -> impl Iterator<Item = &Entity> {
        self.entities.values()
    }

    /// How many are active.
    pub fn active(&self) -> usize {
        self.iter()
            .filter(|e| e.state == EntityState::Active)
            .count()
    }

    fn slot(&mut self, id: u16) -> Result<(&mut Entity, bool), EntityChange> {
        let len = self.entities.len();
        match self.entities.entry(id) {
            std::collections::btree_map::Entry::Occupied(o) => Ok((o.into_mut(), false)),
            std::collections::btree_map::Entry::Vacant(_) if len >= MAX_ENTITIES => {
                Err(EntityChange::Full)
            }
            std::collections::btree_map::Entry::Vacant(v) => Ok((
                v.insert(Entity {
                    id,
                    entity_type: 0,
                    state: EntityState::Active,
                    alpha: 255,
                    placement: Placement::Clamped {
                        lat_deg: 0.0,
                        lon_deg: 0.0,
                    },
                    attitude_deg: [0.0; 3],
                    rates: None,
                    host_frame: 0,
                    placed: 0,
                }),
                true,
            )),
        }
    }

    /// Applies an Entity Control sent in host frame `host_frame`.
    /// Destroying an entity destroys every entity attached to it, down the chain (CIGI: a
    /// parent's children go with it).
    pub fn apply_control(&mut self, c: &EntityControlUpdate, host_frame: u32) -> EntityChange {
        if c.state == 2 {
            return match self.destroy(c.id) {
                0 => EntityChange::Ignored,
                _ => EntityChange::Destroyed,
            };
        }
        self.placements += 1;
        let placed = self.placements;
        let (e, new) = match self.slot(c.id) {
            Ok(x) => x,
            Err(change) => return change,
        };
        e.entity_type = c.entity_type;
        e.state = if c.state == 1 {
            EntityState::Active
        } else {
            EntityState::Inactive
        };
        e.alpha = c.alpha;
        e.placement = if c.attached {
            Placement::Attached {
                parent: c.parent,
                offset_m: [c.lat_or_x, c.lon_or_y, c.alt_or_z],
            }
        } else {
            Placement::Geodetic(Geodetic::new(c.lat_or_x, c.lon_or_y, c.alt_or_z))
        };
        e.attitude_deg = c.attitude_deg;
        e.host_frame = host_frame;
        e.placed = placed;
        if new {
            EntityChange::Created
        } else {
            EntityChange::Updated
        }
    }

    /// Applies a Conformal Clamped Entity Control (an unknown entity is created active).
    pub fn apply_clamped(
        &mut self,
        id: u16,
        yaw_deg: f64,
        lat_deg: f64,
        lon_deg: f64,
        host_frame: u32,
    ) -> EntityChange {
        self.placements += 1;
        let placed = self.placements;
        let (e, new) = match self.slot(id) {
            Ok(x) => x,
            Err(change) => return change,
        };
        e.placement = Placement::Clamped { lat_deg, lon_deg };
        e.attitude_deg = [yaw_deg, 0.0, 0.0];
        e.host_frame = host_frame;
        e.placed = placed;
        if new {
            EntityChange::Created
        } else {
            EntityChange::Updated
        }
    }

    /// Applies a Rate Control for the entity itself (rates for an unknown entity are ignored:
    /// there is nothing to move).
    pub fn apply_rates(&mut self, id: u16, rates: EntityRates, host_frame: u32) -> EntityChange {
        match self.entities.get_mut(&id) {
            Some(e) => {
                e.rates = Some(rates);
                e.host_frame = host_frame;
                EntityChange::Updated
            }
            None => EntityChange::Ignored,
        }
    }

    /// Removes `id` and, down the chain, every entity attached to it. Returns how many went.
    pub fn destroy(&mut self, id: u16) -> usize {
        let mut gone = vec![id];
        let mut removed = 0;
        while let Some(at) = gone.pop() {
            if self.entities.remove(&at).is_none() {
                continue;
            }
            removed += 1;
            gone.extend(self.entities.values().filter_map(|e| match e.placement {
                Placement::Attached { parent, .. } if parent == at => Some(e.id),
                _ => None,
            }));
        }
        removed
    }

    /// The table with every entity that has rates moved by them for `elapsed_s(entity)`
    /// seconds (the time since the host last placed it): dead reckoning between host frames.
    /// Children follow their parents because they stay relative to them.
    pub fn advanced(&self, elapsed_s: impl Fn(&Entity) -> f64) -> EntityTable {
        let mut out = self.clone();
        for e in out.entities.values_mut() {
            if let Some(r) = e.rates {
                let dt = elapsed_s(e);
                if dt.is_finite() && dt > 0.0 {
                    *e = dead_reckon(e, &r, dt.min(MAX_DEAD_RECKONING_S));
                }
            }
        }
        out
    }

    /// Forgets every entity but the ownship (a host's Reset). Returns how many were removed.
    pub fn clear_host_entities(&mut self) -> usize {
        let before = self.entities.len();
        self.entities.retain(|&id, _| id == OWNSHIP_ID);
        before - self.entities.len()
    }

    /// The point `offset_m` (body axes of entity `id`) as an [`Anchor`]: the attachment chain
    /// followed to its root. Errors name why it cannot be placed.
    pub fn anchor(&self, id: u16, offset_m: [f64; 3]) -> Result<Anchor, AnchorError> {
        let mut offset = DVec3::from_array(offset_m);
        let mut rotation = DMat3::IDENTITY;
        let mut at = id;
        for _ in 0..=MAX_ATTACH_DEPTH {
            let e = self.get(at).ok_or(AnchorError::UnknownEntity(at))?;
            let [h, p, r] = e.attitude_deg;
            match e.placement {
                Placement::Attached { parent, offset_m } => {
                    // Into the parent's body axes: the child's attitude is relative to it.
                    let rel = body_to_parent(h, p, r);
                    offset = DVec3::from_array(offset_m) + rel * offset;
                    rotation = rel * rotation;
                    at = parent;
                }
                Placement::Geodetic(g) => {
                    return Ok(Anchor {
                        root: Root::Geodetic {
                            position: g,
                            attitude_deg: e.attitude_deg,
                        },
                        offset_m: offset,
                        rotation,
                    })
                }
                Placement::Clamped { lat_deg, lon_deg } => {
                    return Ok(Anchor {
                        root: Root::Clamped {
                            lat_deg,
                            lon_deg,
                            heading_deg: h,
                        },
                        offset_m: offset,
                        rotation,
                    })
                }
            }
        }
        Err(AnchorError::ChainTooDeep(id))
    }
}

/// Dead reckoning stops after this long without a placement from the host (a host that went
/// quiet does not fly its traffic off the map).
pub const MAX_DEAD_RECKONING_S: f64 = 10.0;
/// Integration step of dead reckoning: attitude rates turn the velocity, so a turn is
/// followed as an arc rather than a chord.
const DEAD_RECKONING_STEP_S: f64 = 0.05;

/// `e` moved by rates `r` for `dt` seconds. Linear rates are in body axes (x forward, y right,
/// z down) or, with the world flag, in the parent's axes (north-east-down for a top-level
/// entity); angular rates (roll, pitch, yaw, deg/s) turn the attitude. A clamped entity moves
/// horizontally and turns by its yaw rate only (the terrain sets its height, pitch and roll).
fn dead_reckon(e: &Entity, r: &EntityRates, dt: f64) -> Entity {
    let mut out = *e;
    let v = DVec3::from_array(r.linear_m_s.map(f64::from));
    let [roll_rate, pitch_rate, yaw_rate] = r.angular_deg_s.map(f64::from);
    let steps = (dt / DEAD_RECKONING_STEP_S).ceil().clamp(1.0, 1000.0) as usize;
    let h = dt / steps as f64;
    // Displacement in the parent's (or north-east-down) axes, integrated at mid-step attitude.
    let mut moved = DVec3::ZERO;
    let mut att = e.attitude_deg;
    let clamped = matches!(e.placement, Placement::Clamped { .. });
    for _ in 0..steps {
        let mut mid = att;
        mid[0] += 0.5 * h * yaw_rate;
        if !clamped {
            mid[1] += 0.5 * h * pitch_rate;
            mid[2] += 0.5 * h * roll_rate;
        }
        let step = if r.world_frame {
            v
        } else {
            body_to_parent(mid[0], mid[1], mid[2]) * v
        };
        moved += step * h;
        att[0] += h * yaw_rate;
        if !clamped {
            att[1] += h * pitch_rate;
            att[2] += h * roll_rate;
        }
    }
    att[0] = att[0].rem_euclid(360.0);
    out.attitude_deg = att;
    out.placement = match e.placement {
        Placement::Geodetic(g) => {
            // North-east-down → east-north-up in the tangent plane at the entity.
            let enu = DVec3::new(moved.y, moved.x, -moved.z);
            Placement::Geodetic(LocalTangentPlane::new(g).enu_to_geodetic(enu))
        }
        Placement::Clamped { lat_deg, lon_deg } => {
            let at = LocalTangentPlane::new(Geodetic::new(lat_deg, lon_deg, 0.0));
            let p = at.enu_to_geodetic(DVec3::new(moved.y, moved.x, 0.0));
            Placement::Clamped {
                lat_deg: p.lat_deg,
                lon_deg: p.lon_deg,
            }
        }
        Placement::Attached { parent, offset_m } => Placement::Attached {
            parent,
            offset_m: (DVec3::from_array(offset_m) + moved).to_array(),
        },
    };
    out
}

/// Why an entity-relative point could not be placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnchorError {
    /// The entity (or a parent in its chain) is not known.
    UnknownEntity(u16),
    /// The attachment chain from this entity is longer than [`MAX_ATTACH_DEPTH`] (or a loop).
    ChainTooDeep(u16),
}

impl std::fmt::Display for AnchorError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AnchorError::UnknownEntity(id) => write!(f, "entity {id} is not known"),
            AnchorError::ChainTooDeep(id) => write!(
                f,
                "entity {id}: attachment chain deeper than {MAX_ATTACH_DEPTH} (or a loop)"
            ),
        }
    }
}

/// The root of an attachment chain, copied out of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Root {
    /// Placed by the host.
    Geodetic {
        /// Position.
        position: Geodetic,
        /// Heading, pitch, roll, degrees.
        attitude_deg: [f64; 3],
    },
    /// On the terrain (its height and slope are needed to place it).
    Clamped {
        /// Degrees.
        lat_deg: f64,
        /// Degrees.
        lon_deg: f64,
        /// Degrees.
        heading_deg: f64,
    },
}

/// An entity-relative point, with everything needed to place it: plain data, so a frame can
/// copy it out of the table and resolve it without holding the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    /// The chain's root entity.
    pub root: Root,
    /// The point's offset from the root's reference point, in the root's body axes, metres.
    pub offset_m: DVec3,
    /// The referenced entity's body axes expressed in the root's body axes.
    pub rotation: DMat3,
}

/// A placed point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    /// Where it is.
    pub point: Geodetic,
    /// The referenced entity's body axes (columns x forward, y right, z down) in ECEF.
    pub body_to_ecef: DMat3,
}

impl Placed {
    /// The referenced entity's body axes in the local east-north-up frame at the point (only
    /// a vector's direction needs them: computed on demand).
    pub fn body_to_enu(&self) -> DMat3 {
        LocalTangentPlane::new(self.point).enu_axes().transpose() * self.body_to_ecef
    }
}

impl Anchor {
    /// Places the point. A clamped root asks `ground` for the terrain under it (its answer is
    /// passed on when not ready).
    pub fn place(&self, ground: &dyn Fn(f64, f64) -> Answer<Surface>) -> Answer<Placed> {
        let (origin, root_axes) = match self.root {
            Root::Geodetic {
                position,
                attitude_deg: [h, p, r],
            } => (position, body_to_enu(h, p, r)),
            Root::Clamped {
                lat_deg,
                lon_deg,
                heading_deg,
            } => match ground(lat_deg, lon_deg) {
                Answer::Ready(s) => (
                    Geodetic::new(lat_deg, lon_deg, s.height_m),
                    clamped_axes(heading_deg, s.normal_enu),
                ),
                Answer::NoTerrain => return Answer::NoTerrain,
                Answer::Pending => return Answer::Pending,
            },
        };
        let ltp = LocalTangentPlane::new(origin);
        let point = ltp.enu_to_geodetic(root_axes * self.offset_m);
        Answer::Ready(Placed {
            point,
            body_to_ecef: ltp.enu_axes() * root_axes * self.rotation,
        })
    }
}

/// Columns: the body x (forward), y (right), z (down) axes in east-north-up, for heading
/// (clockwise from north), pitch (nose up) and roll (right wing down), degrees — the aerospace
/// Z-Y-X rotation from north-east-down, its axes reordered to east-north-up.
pub fn body_to_enu(heading_deg: f64, pitch_deg: f64, roll_deg: f64) -> DMat3 {
    let ned = body_to_parent(heading_deg, pitch_deg, roll_deg);
    // NED → ENU: swap the first two rows and negate the third.
    let to_enu = DMat3::from_cols(
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, -1.0),
    );
    to_enu * ned
}

/// The direction-cosine matrix from body axes to the parent's (or north-east-down) axes for
/// yaw, pitch, roll in degrees: `Rz(yaw) · Ry(pitch) · Rx(roll)`.
fn body_to_parent(yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> DMat3 {
    DMat3::from_rotation_z(yaw_deg.to_radians())
        * DMat3::from_rotation_y(pitch_deg.to_radians())
        * DMat3::from_rotation_x(roll_deg.to_radians())
}

/// Body axes of a vehicle on a slope: z down along the surface normal, x along the heading's
/// direction projected onto the surface.
fn clamped_axes(heading_deg: f64, normal_enu: [f64; 3]) -> DMat3 {
    let n = DVec3::from_array(normal_enu).normalize_or(DVec3::Z);
    let (s, c) = heading_deg.to_radians().sin_cos();
    let ahead = DVec3::new(s, c, 0.0);
    let x = (ahead - ahead.dot(n) * n).normalize_or(ahead);
    let z = -n;
    DMat3::from_cols(x, z.cross(x), z)
}

#[cfg(test)]
#[path = "entities_tests.rs"]
mod tests;
