//! A selection carried across frames: the nodes a ring tile was refined into, kept while the
//! eye moves, each with a certificate that its bound still holds — so the next frame draws
//! them again without walking the tile. On a 16385² plane at 720p, 99.9 % of a frame's drawn
//! nodes were drawn the same way the frame before (`select_target`'s coherence figures).
//!
//! **What is carried.** The refinement of one ring tile from the pools (`refine_ring_tile`:
//! the nodes, their parts, no node missing τ), made with one view on the flat plane and no
//! horizon culling. The walk above the ring tiles is made afresh every frame; where it reaches
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
//!   in them, and √(2 + A² + B²)·|Δw| bounds what the turn of the world vertical w does; over
//!   g₀ that is the relative growth.
//!
//! So each node's bound times the two factors bounds its error now; a record is drawn again
//! while every node's stays ≤ τ (with a margin far beyond rounding), every part the walk
//! culled is still outside the same frustum plane by more than μ, nothing came within μ of
//! the eye plane, and for at most [`max_age`] frames — a walk afresh then finds the coarser
//! nodes a receding eye allows. Drawn again, a node's ρ is that bound: larger than a fresh
//! walk's, never smaller than its error.

use std::collections::HashMap;

use glam::{DMat3, DVec3};

use crate::fast_hash::FastHash;
use crate::tiles::Aabb;

use super::bound::{ViewCorners, EARTH_RADIUS_M};
use super::cdlod_morph::Morph;

/// A node as `refine_ring_tile` lists it: (level, tx, ty, ε, ρ px).
pub(super) type Node = (u32, u32, u32, f32, f32);

/// Relative room kept below τ and above rounding (the bounds are formed in f64 from values
/// stored in f32, whose rounding is 6·10⁻⁸).
const ROOM: f64 = 1e-6;

/// Frames a record is drawn again at most: 16 to 23, staggered by tile so that the records
/// made in one frame are not all walked again in another.
pub(super) fn max_age(level: u32, tx: u32, ty: u32) -> u64 {
    16 + (tx.wrapping_mul(3) ^ ty.wrapping_mul(5) ^ level.wrapping_mul(7)) as u64 % 8
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
    /// The ring tile's box: smallest depth (unclamped) and reach (every gain came from a box
    /// within it).
    ring_z: f64,
    ring_reach: f64,
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
}

/// Counts of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CarryStats {
    /// Ring tiles drawn from their records, and their nodes.
    pub carried_tiles: u32,
    pub carried_nodes: u32,
    /// Ring tiles walked (a record made of each that can be carried).
    pub walked_tiles: u32,
}

/// The records of the ring tiles of the last frame, for selections with parameters `P`.
#[derive(Debug, Default)]
pub struct Carry<P> {
    key: Option<CarryKey<P>>,
    frame: u64,
    tiles: HashMap<(u32, u32, u32), CarriedTile, FastHash>,
    /// This frame's counts.
    pub stats: CarryStats,
}

impl<P: PartialEq> Carry<P> {
    /// A frame begins: records of another key are dropped.
    pub(super) fn begin(&mut self, key: Option<CarryKey<P>>) {
        self.frame += 1;
        self.stats = CarryStats::default();
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
        if frame - t.made_at >= max_age(key.0, key.1, key.2) {
            return false;
        }
        let m = (now.eye - t.view.eye).length();
        let k = frobenius(now.rotation - t.view.rotation);
        let mu = |reach: f64| m + (2.0 * reach + m) * m / (2.0 * EARTH_RADIUS_M) + k * reach;
        let mu_ring = mu(t.ring_reach);
        if t.ring_z - mu_ring <= 1e-6 {
            return false;
        }
        let lip = (optics.w_z + k) * (2.0 + optics.a + optics.b);
        let gain = 1.0 + (lip * mu_ring / (t.ring_z - mu_ring) + k * optics.turn) / optics.floor;
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
        self.stats.carried_tiles += 1;
        self.stats.carried_nodes += t.nodes.len() as u32;
        true
    }

    /// Keeps ring tile `key`'s refinement just walked at `now`: `nodes` and `morphs` as
    /// `refine_ring_tile` left them, `culled` the parts its walk found outside the frustum
    /// (level, tx, ty), `boxes` the box of a node (level, tx, ty) with the sag of cells
    /// `drawn` levels up, in view space (corners) with the eye at the origin.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn record(
        &mut self,
        key: (u32, u32, u32),
        now: &ViewNow,
        optics: &Optics,
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
        // Stored ε and ρ are f32: rounded up by more than their rounding.
        let up = |v: f32| v as f64 * (1.0 + ROOM);
        let least_gain = optics.floor * optics.focal / optics.tau;
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
            ring_z,
            ring_reach,
        });
        (t.made_at, t.used_at, t.view) = (frame, frame, *now);
        (t.ring_z, t.ring_reach) = (ring_z, ring_reach);
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

    #[test]
    fn frobenius_bounds_a_turn() {
        let r0 = DMat3::from_rotation_z(0.3);
        let r1 = DMat3::from_rotation_z(0.3 + 1e-3);
        let k = frobenius(r1 - r0);
        let v = DVec3::new(100.0, -40.0, 7.0);
        assert!((r1 * v - r0 * v).length() <= k * v.length());
        assert!(k < 2e-3);
    }

    #[test]
    fn ages_are_staggered_between_16_and_23() {
        let ages: std::collections::HashSet<u64> =
            (0..64).map(|t| max_age(t % 5, t, t / 3)).collect();
        assert!(ages.len() > 4);
        assert!(ages.iter().all(|a| (16..24).contains(a)));
    }
}
