//! A selection carried across frames: the nodes a ring tile was refined into, kept while the
//! eye moves, each with a certificate that its bound still holds — so the next frame draws
//! them again without walking the tile. On a 16385² plane at 720p, 99.9 % of a frame's drawn
//! nodes were drawn the same way the frame before (`select_target`'s coherence figures).
//!
//! **What is carried.** The refinement of one ring tile from the pools (`refine_ring_tile`:
//! the nodes, their parts, no node missing τ), made with one view and no horizon culling, on
//! the flat plane or on the ellipsoid. The walk above the ring tiles is made afresh every frame; where it reaches
//! a ring tile with a record that still holds, the record's nodes are drawn.
//!
//! **Why a record still holds** (DESIGN.md's bound `ρ = ε·f·g / (z_min − ε)`). Every bound the
//! walk formed for a drawn node is, for some parts i of it, `max εᵢ·(f/τ)·gᵢ / (zᵢ − εᵢ)`:
//! zᵢ the smallest view depth (clamped to the near plane) of a box within the node's box (its
//! bottom carrying at most the sag of cells two levels up), gᵢ the vertical gain over a box
//! within the ring tile's box R, never below the frustum's least gain g₀. Each part's ρᵢ ≤ ρ,
//! so εᵢ ≤ zᵢ·ρ/(f·g₀/τ + ρ). When the eye moves by m and turns (‖R₁ − R₀‖ = k, Frobenius),
//! a point at distance D moves in view space by at most m + k·D, and a box's curvature drop
//! on the plane by at most (2D + m)·m / 2R: together μ(D). Then:
//! - a depth falls by at most μ, so a part's first factor grows by at most
//!   `(z − ε)/(z − μ − ε)`, largest for the node's own depth z and ε its own or
//!   z·ρ/(f·g₀/τ + ρ), whichever is larger;
//! - a gain grows by at most `(|w_z| + k)·(2 + A + B)·μ_R/(z_R − μ_R) + k·√(2 + A² + B²)`
//!   while R stays wholly in front of the eye (z_R its smallest depth, unclamped): the view
//!   ratios a = x/z, b = y/z of a box in R, clamped to the frustum's tangents (at most A and
//!   B), each move by at most μ_R·(1 + A)/(z_R − μ_R) (resp. B), the gain is |w_z|-Lipschitz
//!   in them (|w_z| when the record was made: the turn adds at most k), and √(2 + A² + B²)·|Δw|
//!   bounds what the turn of the world vertical w does; over g₀ — the least gain when the
//!   record was made, which every gain then was at least — that is the relative growth.
//!
//! **On the ellipsoid** (geographic and UTM grids) a node's boxes are fixed in the world (no
//! curvature drop moves with the eye; μ keeps that term, which only adds room), and its gain
//! is `g(u) + s·c` (`bound::spread_gain_of`): u the node's normal in view space, s its slack,
//! c = √(1 + a² + b²) over its (a, b). Every node of the ring tile has its normal within the
//! tile's spread σ of the tile's normal u_R, and g is √(1 + A² + B²)-Lipschitz in u, so the
//! record's least gain is the frustum's for u_R less σ·√(2 + A² + B²), and its |w_z| is
//! |u_R,z| + σ; c moves by at most |Δa| + |Δb| and is ≥ 1, so the slack's part grows by at most
//! the ratio `(2 + A + B)·μ_R/(z_R − μ_R)` of itself — added to the relative growth. A
//! record whose least gain is not positive is not kept.
//!
//! So each node's bound times the two factors bounds its error now; a record is drawn again
//! while every node's stays ≤ τ (with a margin far beyond rounding), every part the walk
//! culled is still outside the same frustum plane by more than μ, nothing came within μ of
//! the eye plane, and until it falls due ([`max_age`] frames) — a walk afresh then finds the
//! coarser nodes a receding eye allows; at most [`AGED_WALKS_PER_FRAME`] records a frame are
//! walked for their age, the others drawn again (still certified) for up to [`AGE_GRACE`]
//! frames more. Drawn again, a node's ρ is that bound: larger than a fresh
//! walk's, never smaller than its error.

use std::collections::HashMap;

use glam::{DMat3, DVec3};

use crate::fast_hash::FastHash;
use crate::tiles::Aabb;

use crate::camera::Frustum;

use super::bound::{frustum_gain_floor, ViewCorners, EARTH_RADIUS_M};
use super::cdlod_morph::Morph;

/// A node as `refine_ring_tile` lists it: (level, tx, ty, ε, ρ px).
pub(super) type Node = (u32, u32, u32, f32, f32);

/// Relative room kept below τ and above rounding (the bounds are formed in f64 from values
/// stored in f32, whose rounding is 6·10⁻⁸).
const ROOM: f64 = 1e-6;

/// Frames after which a record falls due to be walked afresh: 16 to 23, staggered by tile so
/// that the records made in one frame are not all walked again in another.
pub(super) fn max_age(level: u32, tx: u32, ty: u32) -> u64 {
    16 + (tx.wrapping_mul(3) ^ ty.wrapping_mul(5) ^ level.wrapping_mul(7)) as u64 % 8
}

/// Records walked afresh for their age in one frame, at most (but see [`AGE_GRACE`]). The
/// staggered ages alone leave waves: records of one age made in one frame fall due together
/// every time, and two waves meeting made the 16385² plane's slowest frames (10–16 walked for
/// age where the median frame walks 4).
pub const AGED_WALKS_PER_FRAME: u32 = 6;

/// Frames a record due by its age may wait for a frame with room: past `max_age + AGE_GRACE`
/// it is walked afresh whatever the count.
pub const AGE_GRACE: u64 = 8;

/// Whether a record `age` frames old, falling due at `due`, is walked afresh for its age in a
/// frame that has walked `aged` records for theirs before it. Only the cost of a frame hangs on
/// this: a record drawn again is certified by its bounds, however old.
pub(super) fn walk_for_age(age: u64, due: u64, aged: u32) -> bool {
    age >= due && (aged < AGED_WALKS_PER_FRAME || age >= due + AGE_GRACE)
}

/// What every record of a frame shares: the dataset, the selection's parameters `P` and the
/// view's optics. A frame with other ones drops the records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct CarryKey<P> {
    pub bake: usize,
    pub checksum: u32,
    pub params: P,
    /// focal (px), τ, near and the four tangents, bit for bit.
    pub optics: [u64; 7],
}

/// The one view of a frame, as the certificates read it.
#[derive(Debug, Clone, Copy)]
pub(super) struct ViewNow {
    pub eye: DVec3,
    pub rotation: DMat3,
}

/// A drawn node's certificate: its bound when the record was made, an ε no part of it exceeds,
/// the smallest view depth of its box (sag of cells two levels up; clamped to the near plane
/// as the bound clamps it) and the farthest distance from the eye to that box.
#[derive(Debug, Clone, Copy)]
struct NodeCert {
    rho_norm: f64,
    eps: f64,
    z: f64,
    reach: f64,
}

/// A part the walk culled: how far every corner of its box (cells two levels up) lies outside
/// one frustum plane, and the farthest distance from the eye to it.
#[derive(Debug, Clone, Copy)]
struct CulledCert {
    margin: f64,
    reach: f64,
}

/// One ring tile's refinement, kept for the next frames.
#[derive(Debug, Clone)]
struct CarriedTile {
    made_at: u64,
    used_at: u64,
    view: ViewNow,
    nodes: Vec<Node>,
    morphs: Vec<(usize, Morph)>,
    certs: Vec<NodeCert>,
    culled: Vec<CulledCert>,
    /// How much its gains can grow.
    growth: Growth,
}

/// What bounds a record's gains as the eye moves: its ring tile's box (smallest depth,
/// unclamped, and reach: every gain came from a box within it) and, when the record was made,
/// the least gain of any of its nodes (> 0), the largest |w_z| of their verticals in view
/// space, and whether their gains hold a slack part (the ellipsoid's).
#[derive(Debug, Clone, Copy)]
struct Growth {
    ring_z: f64,
    ring_reach: f64,
    floor: f64,
    w_z: f64,
    slack: bool,
}

impl Growth {
    /// A record's, made at `now` with `optics`, its ring tile's box at (`ring_z`, `ring_reach`)
    /// and its normal on the ellipsoid; `None` where its least gain is not positive.
    fn of(
        optics: &Optics,
        now: &ViewNow,
        normal: Option<RingNormal>,
        ring_z: f64,
        ring_reach: f64,
    ) -> Option<Self> {
        let (floor, w_z) = match normal {
            None => (optics.floor, optics.w_z),
            Some(n) => {
                let u = now.rotation * n.up;
                let floor = frustum_gain_floor(&optics.frustum, u) - n.spread * optics.turn;
                (floor, u.z.abs() + n.spread)
            }
        };
        // NaN is no floor either.
        (floor > 0.0).then_some(Self {
            ring_z,
            ring_reach,
            floor,
            w_z,
            slack: normal.is_some(),
        })
    }

    /// The factor by which no gain of the record has grown after the eye moved by `m` and
    /// turned by `k` (the module's bound); `None` once the ring tile may reach the eye plane.
    fn gain(&self, m: f64, k: f64, optics: &Optics) -> Option<f64> {
        let mu_ring = moved(self.ring_reach, m, k);
        if self.ring_z - mu_ring <= 1e-6 {
            return None;
        }
        // Σ: how far a and b together move, at most, for a box within the ring tile.
        let sigma = (2.0 + optics.a + optics.b) * mu_ring / (self.ring_z - mu_ring);
        let slack = if self.slack { sigma } else { 0.0 };
        Some(1.0 + ((self.w_z + k) * sigma + k * optics.turn) / self.floor + slack)
    }
}

/// μ(D): how far a point at distance `reach` from the eye moves in view space, at most, when
/// the eye moves by `m` and turns by `k`, the plane's curvature drop included.
fn moved(reach: f64, m: f64, k: f64) -> f64 {
    m + (2.0 * reach + m) * m / (2.0 * EARTH_RADIUS_M) + k * reach
}

/// The frame's frustum and gains, what every certificate of it uses.
#[derive(Debug, Clone, Copy)]
pub(super) struct Optics {
    pub tau: f64,
    /// Focal length (px).
    pub focal: f64,
    pub near: f64,
    /// Largest |tangent| across (A) and up or down (B).
    pub a: f64,
    pub b: f64,
    /// √(2 + A² + B²): bounds what a turn of the world vertical does to a gain.
    pub turn: f64,
    /// The least vertical gain in the frustum (`frustum_gain_floor`), > 0.
    pub floor: f64,
    /// |w_z| of the world vertical in view space.
    pub w_z: f64,
    /// The frustum, for a ring tile's own least gain on the ellipsoid.
    pub frustum: Frustum,
}

/// The normal of a ring tile on the ellipsoid: its centre's (world axes) and how far every
/// normal within it turns from it (`NodeGeometry::spread`).
#[derive(Debug, Clone, Copy)]
pub(super) struct RingNormal {
    pub up: DVec3,
    pub spread: f64,
}

/// Counts of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CarryStats {
    /// Ring tiles drawn from their records, and their nodes.
    pub carried_tiles: u32,
    pub carried_nodes: u32,
    /// Ring tiles walked (a record made of each that can be carried).
    pub walked_tiles: u32,
    /// Walked ring tiles not recorded: at this frame's motion their record would not hold
    /// one frame.
    pub unkept_tiles: u32,
    /// Ring tiles walked afresh because their record fell due ([`walk_for_age`]).
    pub aged_tiles: u32,
    /// Records due by their age drawn again, waiting for a frame with room.
    pub deferred_tiles: u32,
}

/// The records of the ring tiles of the last frame, for selections with parameters `P`.
#[derive(Debug, Default)]
pub struct Carry<P> {
    key: Option<CarryKey<P>>,
    frame: u64,
    tiles: HashMap<(u32, u32, u32), CarriedTile, FastHash>,
    /// The view of the frame before, and how far the eye moved and turned since (m, k).
    last: Option<ViewNow>,
    motion: Option<(f64, f64)>,
    /// This frame's counts.
    pub stats: CarryStats,
}

impl<P: PartialEq> Carry<P> {
    /// A frame begins with view `now` (`None`: not carrying): records of another key are
    /// dropped.
    pub(super) fn begin(&mut self, key: Option<CarryKey<P>>, now: Option<ViewNow>) {
        self.frame += 1;
        self.stats = CarryStats::default();
        self.motion = match (self.last, now) {
            (Some(a), Some(b)) => {
                Some(((b.eye - a.eye).length(), frobenius(b.rotation - a.rotation)))
            }
            _ => None,
        };
        self.last = now;
        if key.is_none() || key != self.key {
            self.tiles.clear();
        }
        self.key = key;
    }

    /// The frame ends: records the walk did not reach are dropped (their ground is drawn
    /// otherwise now).
    pub(super) fn end(&mut self) {
        let frame = self.frame;
        self.tiles.retain(|_, t| t.used_at == frame);
    }

    /// Records held.
    pub fn len(&self) -> usize {
        self.tiles.len()
    }

    /// No record held.
    pub fn is_empty(&self) -> bool {
        self.tiles.is_empty()
    }

    /// The record of ring tile `key` when it still holds for `now`: its nodes with ρ the
    /// certified bounds (appended to `nodes`), and its morphs.
    pub(super) fn take(
        &mut self,
        key: (u32, u32, u32),
        now: &ViewNow,
        optics: &Optics,
        nodes: &mut Vec<Node>,
        morphs: &mut Vec<(usize, Morph)>,
    ) -> bool {
        if self.key.is_none() {
            return false;
        }
        let frame = self.frame;
        let Some(t) = self.tiles.get_mut(&key) else {
            return false;
        };
        let (age, due) = (frame - t.made_at, max_age(key.0, key.1, key.2));
        if walk_for_age(age, due, self.stats.aged_tiles) {
            self.stats.aged_tiles += 1;
            return false;
        }
        let m = (now.eye - t.view.eye).length();
        let k = frobenius(now.rotation - t.view.rotation);
        let mu = |reach: f64| moved(reach, m, k);
        let Some(gain) = t.growth.gain(m, k, optics) else {
            return false;
        };
        if t.culled
            .iter()
            .any(|c| mu(c.reach) >= c.margin * (1.0 - ROOM))
        {
            return false;
        }
        let first = nodes.len();
        for (n, c) in t.nodes.iter().zip(&t.certs) {
            let mu = mu(c.reach);
            let z = c.z - mu - c.eps;
            if z <= 1e-6 {
                nodes.truncate(first);
                return false;
            }
            let bound = c.rho_norm * (c.z - c.eps) / z * gain;
            // NaN fails too.
            if bound.is_nan() || bound > 1.0 - ROOM {
                nodes.truncate(first);
                return false;
            }
            nodes.push((n.0, n.1, n.2, n.3, (bound * optics.tau) as f32));
        }
        morphs.extend_from_slice(&t.morphs);
        t.used_at = frame;
        if age >= due {
            self.stats.deferred_tiles += 1;
        }
        self.stats.carried_tiles += 1;
        self.stats.carried_nodes += t.nodes.len() as u32;
        true
    }

    /// Keeps ring tile `key`'s refinement just walked at `now`: `nodes` and `morphs` as
    /// `refine_ring_tile` left them, `culled` the parts its walk found outside the frustum
    /// (level, tx, ty), `corners` the box of a node (level, tx, ty) with the sag of cells two
    /// levels up, in view space (corners) with the eye at the origin, and its world box;
    /// `normal` the ring tile's on the ellipsoid (`None` on the plane).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn record(
        &mut self,
        key: (u32, u32, u32),
        now: &ViewNow,
        optics: &Optics,
        normal: Option<RingNormal>,
        nodes: &[Node],
        morphs: &[(usize, Morph)],
        culled: &[(u32, u32, u32)],
        planes: &FrustumPlanes,
        corners: impl Fn(u32, u32, u32) -> (ViewCorners, Aabb),
    ) {
        self.stats.walked_tiles += 1;
        if self.key.is_none() {
            return;
        }
        // Smallest depth (unclamped) and reach of a box, and its corners.
        let depth_reach = |l: u32, x: u32, y: u32| {
            let (c, b) = corners(l, x, y);
            let z = c.z.iter().fold(f64::INFINITY, |a, &z| a.min(z));
            (z, reach(&b, now.eye), c)
        };
        let (ring_z, ring_reach, _) = depth_reach(key.0, key.1, key.2);
        let Some(growth) = Growth::of(optics, now, normal, ring_z, ring_reach) else {
            self.tiles.remove(&key);
            return;
        };
        let floor = growth.floor;
        // A record is worth its certificates only if it could hold a frame of the motion just
        // seen: its nodes' bounds grow at least by the gains' factor. (A cost rule: whether
        // a record holds is decided when it is taken.)
        if let Some((m, k)) = self.motion {
            let worst = nodes.iter().fold(0f32, |a, n| a.max(n.4)) as f64 / optics.tau;
            let holds = growth
                .gain(m, k, optics)
                .is_some_and(|g| worst * g <= 1.0 - ROOM);
            if !holds {
                self.tiles.remove(&key);
                self.stats.unkept_tiles += 1;
                return;
            }
        }
        // Stored ε and ρ are f32: rounded up by more than their rounding.
        let up = |v: f32| v as f64 * (1.0 + ROOM);
        let least_gain = floor * optics.focal / optics.tau;
        // The tile's earlier record, if any, lends its vectors (walked again, it is replaced).
        let frame = self.frame;
        let t = self.tiles.entry(key).or_insert_with(|| CarriedTile {
            made_at: frame,
            used_at: frame,
            view: *now,
            nodes: Vec::new(),
            morphs: Vec::new(),
            certs: Vec::new(),
            culled: Vec::new(),
            growth,
        });
        (t.made_at, t.used_at, t.view, t.growth) = (frame, frame, *now, growth);
        t.nodes.clear();
        t.nodes.extend_from_slice(nodes);
        t.morphs.clear();
        t.morphs.extend_from_slice(morphs);
        t.certs.clear();
        t.certs.extend(nodes.iter().map(|n| {
            let (z, reach, _) = depth_reach(n.0, n.1, n.2);
            // As the bound clamps it.
            let z = z.max(optics.near);
            let rho_norm = up(n.4) / optics.tau;
            let eps_parts = z * rho_norm / (least_gain + rho_norm) * (1.0 + ROOM);
            NodeCert {
                rho_norm,
                eps: up(n.3).max(eps_parts),
                z,
                reach,
            }
        }));
        t.culled.clear();
        t.culled.extend(culled.iter().map(|&(l, x, y)| {
            let (_, reach, c) = depth_reach(l, x, y);
            CulledCert {
                margin: planes.outside_margin(&c),
                reach,
            }
        }));
    }
}

/// The frustum's planes through the eye (view space, y down), as unit normals pointing out:
/// a point's distance outside a plane is its dot product with the normal.
#[derive(Debug, Clone, Copy)]
pub(super) struct FrustumPlanes {
    normals: [DVec3; 4],
    near: f64,
}

impl FrustumPlanes {
    pub(super) fn of(f: &crate::camera::Frustum, near: f64) -> Self {
        let n = |v: DVec3| v / v.length();
        Self {
            normals: [
                // x > tan_right·z, x < tan_left·z, −y > tan_up·z, −y < tan_down·z: outside.
                n(DVec3::new(1.0, 0.0, -f.tan_right)),
                n(DVec3::new(-1.0, 0.0, f.tan_left)),
                n(DVec3::new(0.0, -1.0, -f.tan_up)),
                n(DVec3::new(0.0, 1.0, f.tan_down)),
            ],
            near,
        }
    }

    /// How far every corner lies outside one plane (the largest such distance over the five
    /// planes); ≤ 0 when no plane has them all outside.
    pub(super) fn outside_margin(&self, c: &ViewCorners) -> f64 {
        let mut best = (0..8)
            .map(|i| self.near - c.z[i])
            .fold(f64::INFINITY, f64::min);
        for n in &self.normals {
            let least = (0..8)
                .map(|i| n.dot(DVec3::new(c.x[i], c.y[i], c.z[i])))
                .fold(f64::INFINITY, f64::min);
            best = best.max(least);
        }
        best
    }
}

/// The farthest distance from `eye` to a corner of `b`.
fn reach(b: &Aabb, eye: DVec3) -> f64 {
    let far = DVec3::new(
        (b.min.x - eye.x).abs().max((b.max.x - eye.x).abs()),
        (b.min.y - eye.y).abs().max((b.max.y - eye.y).abs()),
        (b.min.z - eye.z).abs().max((b.max.z - eye.z).abs()),
    );
    far.length()
}

/// ‖M‖_F, which bounds ‖M·v‖ / ‖v‖.
fn frobenius(m: DMat3) -> f64 {
    (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corners_of(b: &Aabb) -> ViewCorners {
        let c = b.corners();
        ViewCorners {
            x: c.map(|p| p.x),
            y: c.map(|p| p.y),
            z: c.map(|p| p.z),
        }
    }

    /// A box wholly right of the right plane is outside it by its nearest corner's distance;
    /// one straddling the plane is not outside.
    #[test]
    fn outside_margin_is_the_nearest_corners_distance_past_a_plane() {
        let f = crate::camera::Frustum {
            tan_left: -1.0,
            tan_right: 1.0,
            tan_down: -0.5,
            tan_up: 0.5,
        };
        let planes = FrustumPlanes::of(&f, 1.0);
        // x − z > 0 at every corner; the nearest to the plane x = z is (20, ·, 10): 10/√2.
        let b = Aabb {
            min: DVec3::new(20.0, -1.0, 5.0),
            max: DVec3::new(30.0, 1.0, 10.0),
        };
        let m = planes.outside_margin(&corners_of(&b));
        assert!((m - 10.0 / 2f64.sqrt()).abs() < 1e-12, "{m}");
        let straddling = Aabb {
            min: DVec3::new(0.0, -1.0, 5.0),
            max: DVec3::new(30.0, 1.0, 10.0),
        };
        assert!(planes.outside_margin(&corners_of(&straddling)) <= 0.0);
        // Behind the near plane: its distance past it.
        let behind = Aabb {
            min: DVec3::new(-1.0, -1.0, -5.0),
            max: DVec3::new(1.0, 1.0, 0.5),
        };
        assert!((planes.outside_margin(&corners_of(&behind)) - 0.5).abs() < 1e-12);
    }

    use super::super::equivalence_tests::Rng;

    /// A random unit vector.
    fn unit(rng: &mut Rng) -> DVec3 {
        loop {
            let v = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            if (0.1..1.0).contains(&v.length()) {
                return v.normalize();
            }
        }
    }

    /// The growth bound of the module's doc, by brute force: a node's gain over a box within
    /// its ring tile's box, formed afresh after the eye moved by m and turned by k, is never
    /// more than its gain when the record was made times `Growth::gain` — on the plane (the
    /// world vertical, no slack) and on the ellipsoid (the node's normal within the tile's
    /// spread of the tile's, a slack part).
    #[test]
    fn a_gain_grows_at_most_by_the_records_factor() {
        use super::super::bound::{spread_gain_of, vertical_gain_of};
        let mut rng = Rng(0x15_0f);
        let (mut checked, mut tight) = (0u32, 0f64);
        for case in 0..20_000 {
            let ellipsoid = case % 2 == 1;
            let f = crate::camera::Frustum::symmetric(rng.range(40f64, 110.0).to_radians(), 16, 9);
            // World → view at the record: looking along a random direction, below the horizon
            // mostly; the world vertical is +Z.
            let r0 = DMat3::from_euler(
                glam::EulerRot::ZXY,
                rng.range(0.0, 6.3),
                rng.range(-1.6, 1.6),
                rng.range(-0.6, 0.6),
            );
            let eye0 = DVec3::new(
                rng.range(-50.0, 50.0),
                rng.range(-50.0, 50.0),
                rng.range(0.0, 900.0),
            );
            // The ring tile's box: somewhere in front of the eye at the record.
            let ahead =
                r0.transpose() * DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.3, 0.3), 1.0);
            let centre = eye0 + ahead * rng.range(200.0, 20_000.0);
            let half = DVec3::new(
                rng.range(5.0, 3000.0),
                rng.range(5.0, 3000.0),
                rng.range(1.0, 500.0),
            );
            let ring = Aabb {
                min: centre - half,
                max: centre + half,
            };
            // A node's box within it.
            let pick = |rng: &mut Rng, lo: f64, hi: f64| {
                let (a, b) = (rng.range(lo, hi), rng.range(lo, hi));
                (a.min(b), a.max(b))
            };
            let (x0, x1) = pick(&mut rng, ring.min.x, ring.max.x);
            let (y0, y1) = pick(&mut rng, ring.min.y, ring.max.y);
            let (z0, z1) = pick(&mut rng, ring.min.z, ring.max.z);
            let node = Aabb {
                min: DVec3::new(x0, y0, z0),
                max: DVec3::new(x1, y1, z1),
            };
            // The tile's normal, its spread, the node's normal within it and the node's slack.
            let (up_ring, spread, up_node, slack) = if ellipsoid {
                let up = (DVec3::Z + unit(&mut rng) * 0.05).normalize();
                let spread = rng.range(0.0, 0.02);
                let tilt = unit(&mut rng) * spread * rng.next();
                (up, spread, (up + tilt).normalize(), rng.range(0.0, 1.0))
            } else {
                (DVec3::Z, 0.0, DVec3::Z, 0.0)
            };
            let corners = |r: DMat3, eye: DVec3, b: &Aabb| {
                let c = b.corners().map(|p| r * (p - eye));
                (
                    c,
                    ViewCorners {
                        x: c.map(|p| p.x),
                        y: c.map(|p| p.y),
                        z: c.map(|p| p.z),
                    },
                )
            };
            let (ring0, ring_c) = corners(r0, eye0, &ring);
            let ring_z = ring0.iter().fold(f64::INFINITY, |a, p| a.min(p.z));
            if ring_z <= 1.0 {
                continue;
            }
            let _ = ring_c;
            let a = f.tan_left.abs().max(f.tan_right.abs());
            let b = f.tan_up.abs().max(f.tan_down.abs());
            let turn = (2.0 + a * a + b * b).sqrt();
            let u0 = r0 * DVec3::Z;
            let optics = Optics {
                tau: 1.0,
                focal: 1000.0,
                near: 0.5,
                a,
                b,
                turn,
                floor: frustum_gain_floor(&f, u0),
                w_z: u0.z.abs(),
                frustum: f,
            };
            let view = ViewNow {
                eye: eye0,
                rotation: r0,
            };
            let normal = ellipsoid.then_some(RingNormal {
                up: up_ring,
                spread,
            });
            let Some(growth) = Growth::of(&optics, &view, normal, ring_z, reach(&ring, eye0))
            else {
                continue;
            };
            if growth.floor <= 1e-3 {
                continue;
            }
            // What the record takes of every normal within the tile's spread: its least gain
            // and |w_z| (a normal turned by the whole spread, any way).
            if ellipsoid {
                let turned = r0 * (up_ring + unit(&mut rng) * spread).normalize();
                assert!(
                    frustum_gain_floor(&f, turned) >= growth.floor,
                    "case {case}: floor"
                );
                assert!(turned.z.abs() <= growth.w_z, "case {case}: w_z");
            }
            let gain = |r: DMat3, eye: DVec3| {
                let (c, _) = corners(r, eye, &node);
                if ellipsoid {
                    spread_gain_of(&c, &f, r * up_node, slack)
                } else {
                    vertical_gain_of(&c, &f, r * up_node)
                }
            };
            let then = gain(r0, eye0);
            // The eye moves and turns a little (a frame or a few of a fast flight).
            let turned = DMat3::from_axis_angle(unit(&mut rng), rng.range(0.0, 0.02)) * r0;
            let eye1 = eye0 + unit(&mut rng) * rng.range(0.0, 30.0);
            let (m, k) = ((eye1 - eye0).length(), frobenius(turned - r0));
            let Some(factor) = growth.gain(m, k, &optics) else {
                continue;
            };
            let now = gain(turned, eye1);
            assert!(
                now <= then * factor * (1.0 + 1e-9),
                "case {case}: gain {then} → {now}, more than ×{factor} (m {m}, k {k})"
            );
            if now > then {
                tight = tight.max((now - then) / (then * (factor - 1.0)));
            }
            checked += 1;
        }
        eprintln!("{checked} gains checked; the largest growth used {tight:.3} of the bound's");
        assert!(checked > 5_000, "{checked}");
    }

    #[test]
    fn frobenius_bounds_a_turn() {
        let r0 = DMat3::from_rotation_z(0.3);
        let r1 = DMat3::from_rotation_z(0.3 + 1e-3);
        let k = frobenius(r1 - r0);
        let v = DVec3::new(100.0, -40.0, 7.0);
        assert!((r1 * v - r0 * v).length() <= k * v.length());
        assert!(k < 2e-3);
    }

    /// Records made together fall due in waves; the budget spreads their walks: over a long
    /// run of records walked afresh as the rule says, no frame walks more than
    /// [`AGED_WALKS_PER_FRAME`] for age unless one has waited [`AGE_GRACE`] frames past due,
    /// none waits longer, and the busiest frame walks fewer than without the budget.
    #[test]
    fn records_due_by_age_are_walked_a_few_a_frame() {
        // 110 ring tiles (the 16385² plane's at 720p), all recorded in frame 0.
        let tiles: Vec<(u32, u32, u32)> = (0..110u32).map(|i| (i % 6, i * 7 % 23, i / 5)).collect();
        let run = |budget: bool| {
            let mut made = vec![0u64; tiles.len()];
            let (mut busiest, mut oldest_over) = (0u32, 0u64);
            for frame in 1..400u64 {
                let mut aged = 0u32;
                for (t, &(l, x, y)) in tiles.iter().enumerate() {
                    let (age, due) = (frame - made[t], max_age(l, x, y));
                    let walk = if budget {
                        walk_for_age(age, due, aged)
                    } else {
                        age >= due
                    };
                    if walk {
                        if budget && aged >= AGED_WALKS_PER_FRAME {
                            assert!(age >= due + AGE_GRACE, "frame {frame}: walked over budget");
                        }
                        aged += 1;
                        made[t] = frame;
                    } else {
                        oldest_over = oldest_over.max(age.saturating_sub(due - 1));
                    }
                }
                busiest = busiest.max(aged);
            }
            (busiest, oldest_over)
        };
        let (with, waited) = run(true);
        let (without, _) = run(false);
        assert!(
            waited <= AGE_GRACE,
            "a record waited {waited} frames past due"
        );
        assert!(waited > 0, "no record waited: the budget never bit");
        assert!(
            with < without,
            "busiest frame {with} with the budget, {without} without"
        );
        // Not due: never walked for age; due with room: walked; due without room: waits,
        // until the grace is spent.
        assert!(!walk_for_age(15, 16, 0));
        assert!(walk_for_age(16, 16, AGED_WALKS_PER_FRAME - 1));
        assert!(!walk_for_age(16, 16, AGED_WALKS_PER_FRAME));
        assert!(!walk_for_age(16 + AGE_GRACE - 1, 16, AGED_WALKS_PER_FRAME));
        assert!(walk_for_age(16 + AGE_GRACE, 16, AGED_WALKS_PER_FRAME));
    }

    #[test]
    fn ages_are_staggered_between_16_and_23() {
        let ages: std::collections::HashSet<u64> =
            (0..64).map(|t| max_age(t % 5, t, t / 3)).collect();
        assert!(ages.len() > 4);
        assert!(ages.iter().all(|a| (16..24).contains(a)));
    }
}
