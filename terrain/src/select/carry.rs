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
//! - a gain grows by at most `(|w_z| + k)·√(2 + A² + B²)·μ_R/(z_R − μ_R) + k·√(2 + A² + B²)`
//!   while R stays wholly in front of the eye (z_R its smallest depth, unclamped): a point of
//!   R moved along the straight segment between its two view-space places (length ≤ μ_R,
//!   depth ≥ z_R − μ_R all along) has its view ratio a = x/z change at the rate
//!   (ẋ − a·ż)/z, at most ‖ṗ‖·√(1 + a²)/z, and its value clamped to the frustum's tangents
//!   (at most A) changes only while |a| ≤ A: by at most Δa = √(1 + A²)·μ_R/(z_R − μ_R) in all,
//!   likewise b by Δb with B; so do the ends of a box's clamped ranges. The gain
//!   √(max (w_x − a·w_z)² + max (w_y − b·w_z)²) then moves by at most |w_z|·√(Δa² + Δb²)
//!   (each root of a maximum is |w_z|-Lipschitz in the range's ends; |w_z| when the record was
//!   made: the turn adds at most k), and √(2 + A² + B²)·|Δw| bounds what the turn of the
//!   world vertical w does; over g₀ — the least gain when the record was made, which every
//!   gain then was at least — that is the relative growth.
//!
//! **On the ellipsoid** (geographic and UTM grids) a node's boxes are fixed in the world (no
//! curvature drop moves with the eye; μ keeps that term, which only adds room), and its gain
//! is `g(u) + s·c` (`bound::spread_gain_of`): u the node's normal in view space, s its slack,
//! c = √(1 + a² + b²) over its (a, b). Every node of the ring tile has its normal within the
//! tile's spread σ of the tile's normal u_R, and g is √(1 + A² + B²)-Lipschitz in u, so the
//! record's least gain is the frustum's for u_R less σ·√(2 + A² + B²), and its |w_z| is
//! |u_R,z| + σ; c moves by at most √(Δa² + Δb²) and is ≥ 1, so the slack's part grows by at
//! most the ratio `√(2 + A² + B²)·μ_R/(z_R − μ_R)` of itself — added to the relative growth. A
//! record whose least gain is not positive is not kept. The least gain is taken over the ring
//! tile's own view ratios (its box's corners' (a, b), clamped), not the whole frustum's: every
//! node's box lies within the tile's, so every gain formed was at least that.
//!
//! So each node's bound times the two factors bounds its error now; a record is drawn again
//! while every node's stays ≤ τ (with a margin far beyond rounding), every part the walk
//! culled is still wholly outside one frustum plane — its distance past that plane less the
//! eye's move along the plane's normal, k·D and the curvature drop
//! (`FrustumPlanes::still_outside`: a forward move carries the parts beside the frustum
//! further out) —, nothing came within μ of the eye plane, and until it falls due
//! ([`max_age`] frames) — a walk afresh then finds the coarser nodes a receding eye allows;
//! at most [`AGED_WALKS_PER_FRAME`] records a frame are walked for their age, the others drawn
//! again (still certified) for up to [`AGE_GRACE`] frames more. A record of which exactly one
//! node fails (98.5 % of the records broken by a node on the 16385² plane's flight, each of
//! ~22 nodes) is repaired instead of walked whole ([`Taken::AllBut`]): the others are drawn
//! again with their certified bounds, the one walked afresh, and the record made again at this
//! frame's view from both — a certified bound now is a bound now, so the argument above holds
//! from the new record on. Drawn again, a node's ρ is that bound: larger than a fresh
//! walk's, never smaller than its error.
//!
//! **Tried and dropped** (the manoeuvre flights, which roll 9.4° and pitch 2.35° a frame and
//! walk nearly every ring tile afresh: 40–60 a frame, 0–22 carried, 12–28 records a frame not
//! kept, the gains' factor ~3; Inn manoeuvre at 1280×720, τ = 1, the 4 s flight flown ten
//! times, 1,200 frames, each frame's least of three runs):
//! - *Repairing every node that fails* (up to half a record's nodes and culled parts, each
//!   walked afresh as [`Taken::AllBut`]'s one is; nodes turned out of view culled by a
//!   bounding sphere): selection 162 → 118–130 µs mean, 305 → 263 µs p99, for +33 % to +49 %
//!   triangles (331 M → 442–494 M over the flight; frames at 1.5–1.9×). The nodes that hold
//!   are those far below τ, the very ones whose coarser options come to meet τ as the view
//!   turns: a repaired record never draws them coarser, a fresh walk does. With at most a
//!   fifth repaired: 287 µs p99 for +7 % triangles.
//! - *Discounting a roll*: a roll about the view axis moves no depth and no gain at a point,
//!   |(w_x, w_y) − (a, b)·w_z|, so for a record whose ring tile lay wholly inside the frustum
//!   (no range clamped: the gain formed then bounds the largest at the corners after any
//!   roll) only the turn beyond the roll need count, and a point's move over its own depth is
//!   at most (m + m²/2R)/z + √(1 + A² + B²)·(k + m/R) however far the tile reaches. Half the
//!   records qualified (1,456 of 2,829 takes) and k fell from 0.239 to 0.058 a frame, but the
//!   factor stayed 1.31–1.41 (the 2.35° pitch: the vertical's turn over the least gain 0.11,
//!   (a, b)'s move 0.06, on the ellipsoid the slack's 0.2) and records of 30–50 nodes near τ
//!   lost several a frame: selection p99 305 → 300–304 µs, triangles +0.3 %.
//!
//! Carrying costs triangles where records outlive their view: on the suite's cruise and
//! follow flights at 5 fps (Inn, Northern England, bounded) 1.004× the triangles drawn with
//! carrying off (geometric mean of 64 configurations; at most 1.026×, Inn cruise τ = 1 px).

use std::collections::HashMap;

use glam::{DMat3, DVec3};

use crate::fast_hash::FastHash;
use crate::tiles::Aabb;

use crate::camera::Frustum;

use super::bound::{clamped_ranges, gain_floor_over, ViewCorners, EARTH_RADIUS_M};
use super::cdlod_morph::Morph;

/// A node as `refine_ring_tile` lists it: (level, tx, ty, ε, ρ px).
pub(super) type Node = (u32, u32, u32, f32, f32);

/// Relative room kept below τ and above rounding (the bounds are formed in f64 from values
/// stored in f32, whose rounding is 6·10⁻⁸).
const ROOM: f64 = 1e-6;

/// Frames after which a record falls due to be walked afresh: 32 to 47, staggered by tile so
/// that the records made in one frame are not all walked again in another. Only the triangles
/// hang on it (a record is certified however old): on the 16385² plane's flight of
/// `select_target`, 0.26 % more than with 16 to 23 (nodes a fresh walk would draw coarser, for
/// a receding eye), for about half the walks for age.
pub(super) fn max_age(level: u32, tx: u32, ty: u32) -> u64 {
    32 + (tx.wrapping_mul(3) ^ ty.wrapping_mul(5) ^ level.wrapping_mul(7)) as u64 % 16
}

/// Records walked afresh for their age in one frame, at most (but see [`AGE_GRACE`]). The
/// staggered ages alone leave waves: records of one age made in one frame fall due together
/// every time, and two waves meeting made the 16385² plane's slowest frames (10–16 walked for
/// age where the median frame walks 4, with ages of 16 to 23 and 6 a frame).
pub const AGED_WALKS_PER_FRAME: u32 = 3;

/// Frames a record due by its age may wait for a frame with room: past `max_age + AGE_GRACE`
/// it is walked afresh whatever the count.
pub const AGE_GRACE: u64 = 16;

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
/// each frustum plane (near, then the four sides; negative where some corner is inside it), and
/// the farthest distance from the eye to it.
#[derive(Debug, Clone, Copy)]
struct CulledCert {
    margins: [f64; 5],
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
    /// The culled parts (level, tx, ty), to be recorded again with a repaired record.
    culled_keys: Vec<(u32, u32, u32)>,
    /// How much its gains can grow.
    growth: Growth,
}

/// What [`Carry::take`] made of a ring tile's record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Taken {
    /// Every node holds: drawn again.
    Whole,
    /// Every node holds but this one (its bound may have passed τ): the others are drawn again
    /// and this one is walked afresh — the record is then made again from both
    /// ([`Carry::record`], the others' certified bounds standing for their bounds now).
    AllBut(Node, Morph),
    /// The ring tile is walked afresh.
    Walk,
}

/// What bounds a record's gains as the eye moves: its ring tile's box (smallest depth,
/// unclamped, and reach: every gain came from a box within it) and, when the record was made,
/// the least gain of any of its nodes (> 0: the least over the ring tile's own (a, b) ranges,
/// which every node's box lies within, not the whole frustum's), the largest |w_z| of their
/// verticals in view space, and whether their gains hold a slack part (the ellipsoid's).
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
    /// with view-space corners `ring` and its normal on the ellipsoid; `None` where its least
    /// gain is not positive.
    fn of(
        optics: &Optics,
        now: &ViewNow,
        normal: Option<RingNormal>,
        ring: &ViewCorners,
        ring_reach: f64,
    ) -> Option<Self> {
        let ring_z = ring.z.iter().fold(f64::INFINITY, |a, &z| a.min(z));
        // Every node's box lies within the ring tile's, so its (a, b) ranges, clamped, lie
        // within the tile's clamped ranges, and its gain — the largest over them — is at least
        // the least over the tile's.
        let (a, b) = clamped_ranges(ring, &optics.frustum);
        let (floor, w_z) = match normal {
            None => (gain_floor_over(optics.up, a, b), optics.w_z),
            Some(n) => {
                let u = now.rotation * n.up;
                let floor = gain_floor_over(u, a, b) - n.spread * optics.turn;
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
        // Σ: how far (a, b) together move, at most (√(Δa² + Δb²)), for a box within the ring
        // tile.
        let sigma = optics.turn * mu_ring / (self.ring_z - mu_ring);
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
    /// √(2 + A² + B²), A and B the largest |tangent| across and up or down: bounds what a
    /// turn of the world vertical does to a gain, and how far (a, b) move.
    pub turn: f64,
    /// The world vertical in view space, and its |w_z|.
    pub up: DVec3,
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
    /// Records of which one node was walked afresh, the others drawn again ([`Taken::AllBut`]).
    pub repaired_tiles: u32,
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
    /// certified bounds (appended to `nodes`), and its morphs. When all but one of its nodes
    /// hold (and its gains, culled parts and age do), those are appended, the one returned
    /// ([`Taken::AllBut`]) and the record's culled parts appended to `culled`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn take(
        &mut self,
        key: (u32, u32, u32),
        now: &ViewNow,
        optics: &Optics,
        planes: &FrustumPlanes,
        nodes: &mut Vec<Node>,
        morphs: &mut Vec<(usize, Morph)>,
        culled: &mut Vec<(u32, u32, u32)>,
    ) -> Taken {
        if self.key.is_none() {
            return Taken::Walk;
        }
        let frame = self.frame;
        let Some(t) = self.tiles.get_mut(&key) else {
            return Taken::Walk;
        };
        let (age, due) = (frame - t.made_at, max_age(key.0, key.1, key.2));
        if walk_for_age(age, due, self.stats.aged_tiles) {
            self.stats.aged_tiles += 1;
            return Taken::Walk;
        }
        let m = (now.eye - t.view.eye).length();
        let k = frobenius(now.rotation - t.view.rotation);
        let mu = |reach: f64| moved(reach, m, k);
        let Some(gain) = t.growth.gain(m, k, optics) else {
            return Taken::Walk;
        };
        // A culled part stays outside a plane while the eye's move along that plane's normal,
        // the turn and the curvature drop leave it outside (`FrustumPlanes::still_outside`).
        let step = now.rotation * (now.eye - t.view.eye);
        if t.culled
            .iter()
            .any(|c| !planes.still_outside(&c.margins, step, mu(c.reach) - m))
        {
            return Taken::Walk;
        }
        let first = nodes.len();
        // The one node whose certificate no longer holds, by index in the record.
        let mut failing: Option<usize> = None;
        for (j, (n, c)) in t.nodes.iter().zip(&t.certs).enumerate() {
            let mu = mu(c.reach);
            let z = c.z - mu - c.eps;
            let bound = c.rho_norm * (c.z - c.eps) / z * gain;
            // NaN fails too; so does a box that may reach the eye plane.
            if z <= 1e-6 || bound.is_nan() || bound > 1.0 - ROOM {
                if failing.is_some() {
                    nodes.truncate(first);
                    return Taken::Walk;
                }
                failing = Some(j);
                continue;
            }
            nodes.push((n.0, n.1, n.2, n.3, (bound * optics.tau) as f32));
        }
        t.used_at = frame;
        if let Some(j) = failing {
            // The others' morphs, indexed past the one left out.
            morphs.extend(t.morphs.iter().filter(|&&(i, _)| i != j).map(|&(i, m)| {
                let i = if i > j { i - 1 } else { i };
                (first + i, m)
            }));
            culled.extend_from_slice(&t.culled_keys);
            self.stats.repaired_tiles += 1;
            self.stats.carried_nodes += t.nodes.len() as u32 - 1;
            let morph = t
                .morphs
                .iter()
                .find(|&&(i, _)| i == j)
                .map_or(Morph::NONE, |m| m.1);
            return Taken::AllBut(t.nodes[j], morph);
        }
        morphs.extend(t.morphs.iter().map(|&(i, m)| (first + i, m)));
        if age >= due {
            self.stats.deferred_tiles += 1;
        }
        self.stats.carried_tiles += 1;
        self.stats.carried_nodes += t.nodes.len() as u32;
        Taken::Whole
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
        if self.key.is_none() {
            return;
        }
        // Smallest depth (unclamped) and reach of a box, and its corners.
        let depth_reach = |l: u32, x: u32, y: u32| {
            let (c, b) = corners(l, x, y);
            let z = c.z.iter().fold(f64::INFINITY, |a, &z| a.min(z));
            (z, reach(&b, now.eye), c)
        };
        let (_, ring_reach, ring) = depth_reach(key.0, key.1, key.2);
        let Some(growth) = Growth::of(optics, now, normal, &ring, ring_reach) else {
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
            culled_keys: Vec::new(),
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
        t.culled_keys.clear();
        t.culled_keys.extend_from_slice(culled);
        t.culled.clear();
        t.culled.extend(culled.iter().map(|&(l, x, y)| {
            let (_, reach, c) = depth_reach(l, x, y);
            CulledCert {
                margins: planes.margins(&c),
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
    /// planes); ≤ 0 when no plane has them all outside. (The tests' check of a box's cull.)
    #[cfg(test)]
    fn outside_margin(&self, c: &ViewCorners) -> f64 {
        self.margins(c)
            .into_iter()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// How far every corner lies outside each plane: the near plane's, then the four sides'
    /// (negative where some corner is inside it).
    pub(super) fn margins(&self, c: &ViewCorners) -> [f64; 5] {
        let mut m = [f64::INFINITY; 5];
        for i in 0..8 {
            let p = DVec3::new(c.x[i], c.y[i], c.z[i]);
            m[0] = m[0].min(self.near - p.z);
            for (k, n) in self.normals.iter().enumerate() {
                m[k + 1] = m[k + 1].min(n.dot(p));
            }
        }
        m
    }

    /// Whether a box `margins` outside the planes (as [`Self::margins`] gave them) is still
    /// wholly outside one of them after the eye moved by `step` (view axes of now) and its
    /// points moved by at most `drift` more (the turn, k·D, and the curvature drop). A point p
    /// at distance d = n·R(p − e) past a plane through the eye is, after the eye moves to e'
    /// and turns to R', at n·R'(p − e') = d + n·(R' − R)(p − e) − n·R'(e' − e): at least
    /// d − drift − n·step. (The near plane's offset is the same before and after.)
    pub(super) fn still_outside(&self, margins: &[f64; 5], step: DVec3, drift: f64) -> bool {
        let near = DVec3::new(0.0, 0.0, -1.0);
        std::iter::once(near)
            .chain(self.normals)
            .zip(margins)
            .any(|(n, &d)| d > 0.0 && d * (1.0 - ROOM) - n.dot(step) - drift > 0.0)
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
#[path = "carry_tests.rs"]
mod tests;
