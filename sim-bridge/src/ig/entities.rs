//! The entities a host has created (Entity Control, Conformal Clamped Entity Control, Rate
//! Control), kept in a bounded table, and entity-relative points resolved to the world.
//!
//! Body axes are CIGI's: x forward, y right, z down, rotated from the local north-east-down
//! frame by heading (yaw), pitch and roll in that order. Positions are geodetic with the
//! altitude the host gives (mean sea level); an offset of a few hundred metres is taken in the
//! local tangent plane at the entity, where the geoid's slope changes heights by micrometres.
//! Drawing entities is a later step; this table is what it will read.

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
                }),
                true,
            )),
        }
    }

    /// Applies an Entity Control sent in host frame `host_frame`.
    pub fn apply_control(&mut self, c: &EntityControlUpdate, host_frame: u32) -> EntityChange {
        if c.state == 2 {
            return match self.entities.remove(&c.id) {
                Some(_) => EntityChange::Destroyed,
                None => EntityChange::Ignored,
            };
        }
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
        let (e, new) = match self.slot(id) {
            Ok(x) => x,
            Err(change) => return change,
        };
        e.placement = Placement::Clamped { lat_deg, lon_deg };
        e.attitude_deg = [yaw_deg, 0.0, 0.0];
        e.host_frame = host_frame;
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
mod tests {
    use super::*;

    fn control(id: u16, lat: f64, lon: f64, alt: f64, att: [f64; 3]) -> EntityControlUpdate {
        EntityControlUpdate {
            id,
            state: 1,
            attached: false,
            parent: 0,
            entity_type: 7,
            alpha: 255,
            lat_or_x: lat,
            lon_or_y: lon,
            alt_or_z: alt,
            attitude_deg: att,
        }
    }

    fn flat(height: f64) -> impl Fn(f64, f64) -> Answer<Surface> {
        move |_, _| {
            Answer::Ready(Surface {
                height_m: height,
                normal_enu: [0.0, 0.0, 1.0],
            })
        }
    }

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).length() < tol
    }

    #[test]
    fn body_axes_follow_heading_pitch_roll() {
        let m = body_to_enu(0.0, 0.0, 0.0);
        assert!(close(m.x_axis, DVec3::Y, 1e-12), "forward is north");
        assert!(close(m.y_axis, DVec3::X, 1e-12), "right is east");
        assert!(close(m.z_axis, -DVec3::Z, 1e-12), "down is down");
        let m = body_to_enu(90.0, 0.0, 0.0);
        assert!(
            close(m.x_axis, DVec3::X, 1e-12),
            "heading 90: forward is east"
        );
        assert!(close(m.y_axis, -DVec3::Y, 1e-12), "right of east is south");
        let m = body_to_enu(0.0, 90.0, 0.0);
        assert!(close(m.x_axis, DVec3::Z, 1e-12), "nose up");
        let m = body_to_enu(0.0, 0.0, 90.0);
        assert!(close(m.y_axis, -DVec3::Z, 1e-12), "right wing down");
        // A general attitude: the columns stay orthonormal and right-handed.
        let m = body_to_enu(123.0, -17.0, 41.0);
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        assert!(close(m.x_axis.cross(m.y_axis), m.z_axis, 1e-12));
        // Forward at heading 123, pitch −17: its horizontal part points 123° from north.
        let f = m.x_axis;
        assert!((f.x.atan2(f.y).to_degrees() - 123.0).abs() < 1e-9);
        assert!((f.z.asin().to_degrees() + 17.0).abs() < 1e-9);
    }

    #[test]
    fn entity_relative_points_land_where_the_geodesy_says() {
        let mut t = EntityTable::default();
        let origin = Geodetic::new(47.25, 11.4, 1500.0);
        assert_eq!(
            t.apply_control(
                &control(
                    5,
                    origin.lat_deg,
                    origin.lon_deg,
                    origin.alt_m,
                    [90.0, 0.0, 0.0]
                ),
                1
            ),
            EntityChange::Created
        );
        let ltp = LocalTangentPlane::new(origin);
        // 100 m ahead of an east-facing entity is 100 m east; 50 m "down" is 50 m lower.
        for (offset, want) in [
            ([100.0, 0.0, 0.0], DVec3::new(100.0, 0.0, 0.0)),
            ([0.0, 20.0, 0.0], DVec3::new(0.0, -20.0, 0.0)),
            ([0.0, 0.0, 50.0], DVec3::new(0.0, 0.0, -50.0)),
        ] {
            let placed = t
                .anchor(5, offset)
                .unwrap()
                .place(&flat(0.0))
                .ready()
                .unwrap();
            let got = ltp.geodetic_to_enu(placed.point);
            assert!(close(got, want, 1e-6), "{offset:?}: {got} vs {want}");
        }
        // Pitched up 30° heading north: 1 km ahead is 866 m north and 500 m up.
        t.apply_control(
            &control(
                6,
                origin.lat_deg,
                origin.lon_deg,
                origin.alt_m,
                [0.0, 30.0, 0.0],
            ),
            2,
        );
        let p = t.anchor(6, [1000.0, 0.0, 0.0]).unwrap().place(&flat(0.0));
        let got = ltp.geodetic_to_enu(p.ready().unwrap().point);
        let want = DVec3::new(0.0, 1000.0 * 30f64.to_radians().cos(), 500.0);
        assert!(close(got, want, 1e-6), "{got} vs {want}");
        // The body axes at the point: forward still 30° up, 1 km away (the tangent planes
        // differ by 0.009°).
        let axes = p.ready().unwrap().body_to_enu();
        assert!((axes.x_axis.z.asin().to_degrees() - 30.0).abs() < 0.02);
    }

    #[test]
    fn attached_chains_compose_and_loops_are_refused() {
        let mut t = EntityTable::default();
        let origin = Geodetic::new(-33.9, 151.2, 100.0);
        t.apply_control(
            &control(
                1,
                origin.lat_deg,
                origin.lon_deg,
                origin.alt_m,
                [90.0, 0.0, 0.0],
            ),
            1,
        );
        // A child 10 m ahead of its parent, turned a further 90° (so it faces south).
        let child = EntityControlUpdate {
            attached: true,
            parent: 1,
            ..control(2, 10.0, 0.0, 0.0, [90.0, 0.0, 0.0])
        };
        t.apply_control(&child, 1);
        let ltp = LocalTangentPlane::new(origin);
        // 5 m ahead of the child = 10 m east, then 5 m south.
        let p = t.anchor(2, [5.0, 0.0, 0.0]).unwrap().place(&flat(0.0));
        let got = ltp.geodetic_to_enu(p.ready().unwrap().point);
        assert!(close(got, DVec3::new(10.0, -5.0, 0.0), 1e-6), "{got}");
        assert!(close(
            p.ready().unwrap().body_to_enu().x_axis,
            -DVec3::Y,
            1e-5
        ));
        // A loop: 3 → 4 → 3.
        for (id, parent) in [(3, 4), (4, 3)] {
            t.apply_control(
                &EntityControlUpdate {
                    attached: true,
                    parent,
                    ..control(id, 0.0, 0.0, 0.0, [0.0; 3])
                },
                1,
            );
        }
        assert_eq!(t.anchor(3, [0.0; 3]), Err(AnchorError::ChainTooDeep(3)));
        assert_eq!(t.anchor(9, [0.0; 3]), Err(AnchorError::UnknownEntity(9)));
        let orphan = EntityControlUpdate {
            attached: true,
            parent: 77,
            ..control(8, 0.0, 0.0, 0.0, [0.0; 3])
        };
        t.apply_control(&orphan, 1);
        assert_eq!(t.anchor(8, [0.0; 3]), Err(AnchorError::UnknownEntity(77)));
    }

    #[test]
    fn clamped_entities_sit_on_the_terrain_and_follow_its_slope() {
        let mut t = EntityTable::default();
        assert_eq!(
            t.apply_clamped(12, 0.0, 46.0, 7.0, 3),
            EntityChange::Created
        );
        // A slope rising to the north by 10°: normal tilted towards the south.
        let tilt = 10f64.to_radians();
        let ground = move |_: f64, _: f64| {
            Answer::Ready(Surface {
                height_m: 640.0,
                normal_enu: [0.0, -tilt.sin(), tilt.cos()],
            })
        };
        let a = t.anchor(12, [0.0, 0.0, 0.0]).unwrap();
        let p = a.place(&ground).ready().unwrap();
        assert!((p.point.alt_m - 640.0).abs() < 1e-9);
        // Facing north up the slope: nose up by 10°.
        assert!((p.body_to_enu().x_axis.z.asin().to_degrees() - 10.0).abs() < 1e-9);
        assert!(p.body_to_enu().y_axis.z.abs() < 1e-12, "no roll");
        // Not ready or no terrain: said so.
        assert_eq!(a.place(&|_, _| Answer::Pending), Answer::Pending);
        assert_eq!(a.place(&|_, _| Answer::NoTerrain), Answer::NoTerrain);
    }

    #[test]
    fn destroy_rates_reset_and_the_bound() {
        let mut t = EntityTable::default();
        t.apply_control(&control(0, 1.0, 2.0, 3.0, [0.0; 3]), 1);
        t.apply_control(&control(4, 1.0, 2.0, 3.0, [0.0; 3]), 1);
        assert_eq!(
            t.apply_rates(4, EntityRates::default(), 2),
            EntityChange::Updated
        );
        assert_eq!(
            t.apply_rates(99, EntityRates::default(), 2),
            EntityChange::Ignored
        );
        assert!(t.get(4).unwrap().rates.is_some());
        let inactive = EntityControlUpdate {
            state: 0,
            ..control(4, 1.0, 2.0, 3.0, [0.0; 3])
        };
        assert_eq!(t.apply_control(&inactive, 3), EntityChange::Updated);
        assert_eq!(t.get(4).unwrap().state, EntityState::Inactive);
        assert_eq!((t.len(), t.active()), (2, 1));
        let destroy = EntityControlUpdate {
            state: 2,
            ..inactive
        };
        assert_eq!(t.apply_control(&destroy, 4), EntityChange::Destroyed);
        assert_eq!(t.apply_control(&destroy, 4), EntityChange::Ignored);
        assert_eq!(t.len(), 1);
        for id in 1..=MAX_ENTITIES as u16 {
            t.apply_control(&control(id, 0.0, 0.0, 0.0, [0.0; 3]), 5);
        }
        assert_eq!(t.len(), MAX_ENTITIES);
        let one_more = control(MAX_ENTITIES as u16 + 1, 0.0, 0.0, 0.0, [0.0; 3]);
        assert_eq!(t.apply_control(&one_more, 5), EntityChange::Full);
        // Known entities still update when full.
        assert_eq!(
            t.apply_control(&control(3, 5.0, 5.0, 5.0, [0.0; 3]), 6),
            EntityChange::Updated
        );
        assert_eq!(t.clear_host_entities(), MAX_ENTITIES - 1);
        assert_eq!(t.len(), 1);
        assert!(t.get(OWNSHIP_ID).is_some());
    }
}
