//! Horizon culling: nodes hidden behind nearer terrain are neither refined nor drawn (issue 15
//! item 3). A hidden node has no visible error, so dropping it keeps the bound.
//!
//! **Built in a first pass**, before the selection walks: every tile of one *occluder level*
//! (the finest level with at most [`MAX_OCCLUDERS`] tiles) becomes a solid column — its
//! full-resolution **minimum** height (the bake's), lowered by the curvature drop at its
//! farthest corner, over its footprint. Per azimuth sector (1024 over 360°) and per distance
//! bin (log-spaced), [`Horizon`] keeps the highest elevation slope `tan α` below which every
//! ray of that sector is guaranteed to enter one of the columns lying wholly within that
//! distance of the eye.
//!
//! **Invariant**: a node [`Horizon::hides`] has no point of its box — hence no level-0 sample
//! and no corner of a drawn triangle, all inside the box — that the eye can see: the segment
//! from the eye to any such point passes below the level-0 surface before reaching it.
//!
//! Why it holds (each approximation errs towards *visible*):
//! - An occluder only fills sectors its azimuth range covers *wholly*, so every ray of such a
//!   sector crosses its footprint (a convex set seen from outside it).
//! - A ray of slope t crossing a column of top z (eye-relative) somewhere at horizontal
//!   distance d ∈ [d_near, d_far] is below the top there when t < z/d; the slope credited is the
//!   smallest z/d over that range (z/d_far when z > 0, z/d_near otherwise), and the level-0
//!   surface over the footprint is at least the column top (the minimum of its samples, the
//!   triangles interpolating them; the drawn curvature drop at most the farthest corner's).
//! - The slope is credited to the distance bin at or beyond d_far; a node is tested against the
//!   bin at or before its nearest point, so every occluder credited lies wholly nearer: the
//!   segment to any point of the node crosses it on the way.
//! - The node's steepest slope from the eye is bounded by its box's top over its nearest
//!   (top above the eye) or farthest (below) horizontal distance; it must be *below* the
//!   credited slope in every sector the node's azimuth range touches. Boxes containing the eye's
//!   vertical, nearer than the first bin or wider than half a turn are never hidden.
//! - On the ellipsoid the frame is the eye's local vertical; a column's footprint is the quad of
//!   its corners' positions at the minimum height, shrunk towards its centre by 2 m + 10⁻³ of its
//!   distance (the foot of a point below it moves radially by its depth × d/R: the shrink covers
//!   depths to ≈ 6 km), its top the lowest corner less the tile's sag.

use glam::{DMat3, DVec2, DVec3};

use crate::bake::ErrorBake;
use crate::geodesy::GeoGrid;
use crate::tiles::Aabb;

use super::bound::{curvature_interpolation_error, EARTH_RADIUS_M};

/// Azimuth sectors over 360°.
pub const SECTORS: usize = 1024;
/// Distance bins: bin b's edge is `BIN0_M · 2^(b/4)` (8 m to ≈ 8 400 km).
const BINS: usize = 81;
const BIN0_M: f64 = 8.0;
/// Most occluder tiles per frame: the occluder level is the finest within this count.
pub const MAX_OCCLUDERS: u32 = 16_384;

const SECTOR_RAD: f64 = std::f64::consts::TAU / SECTORS as f64;

fn bin_edge(b: usize) -> f64 {
    BIN0_M * (b as f64 * 0.25).exp2()
}

/// Smallest bin whose edge is at or beyond `d` (`None` beyond the last).
fn bin_at_or_beyond(d: f64) -> Option<usize> {
    let mut b = (4.0 * (d / BIN0_M).log2()).ceil().max(0.0) as usize;
    while b > 0 && bin_edge(b - 1) >= d {
        b -= 1;
    }
    while b < BINS && bin_edge(b) < d {
        b += 1;
    }
    (b < BINS).then_some(b)
}

/// Largest bin whose edge is at or before `d` (`None` before the first).
fn bin_at_or_before(d: f64) -> Option<usize> {
    if d.is_nan() || d < BIN0_M {
        return None;
    }
    let mut b = ((4.0 * (d / BIN0_M).log2()).floor() as usize).min(BINS - 1);
    while b > 0 && bin_edge(b) > d {
        b -= 1;
    }
    while b + 1 < BINS && bin_edge(b + 1) <= d {
        b += 1;
    }
    (bin_edge(b) <= d).then_some(b)
}

/// Horizontal footprint of a convex set seen from the eye (at the origin): azimuth range,
/// nearest and farthest horizontal distance. `None` when it holds (or nearly holds) the eye's
/// vertical.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    pub az_lo: f64,
    pub az_hi: f64,
    pub d_near: f64,
    pub d_far: f64,
}

/// [`Footprint`] of the convex hull of `points` (eye-relative horizontal positions).
pub fn footprint(points: &[DVec2]) -> Option<Footprint> {
    footprint_of_polygon(&convex_hull(points))
}

/// [`Footprint`] of a quad already convex and in order (either way round): no hull to build.
fn footprint_of_quad(q: &[DVec2; 4]) -> Option<Footprint> {
    let area2: f64 = (0..4).map(|i| q[i].perp_dot(q[(i + 1) % 4])).sum();
    if area2 >= 0.0 {
        footprint_of_polygon(q)
    } else {
        footprint_of_polygon(&[q[3], q[2], q[1], q[0]])
    }
}

/// [`Footprint`] of a counter-clockwise convex polygon.
fn footprint_of_polygon(hull: &[DVec2]) -> Option<Footprint> {
    if hull.len() < 3 {
        return None;
    }
    let mut d_near = f64::INFINITY;
    let mut inside = true;
    for i in 0..hull.len() {
        let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
        let e = b - a;
        // Counter-clockwise hull: the origin is inside when left of every edge.
        if e.perp_dot(-a) < 0.0 {
            inside = false;
        }
        let t = ((-a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        d_near = d_near.min((a + e * t).length());
    }
    if inside || d_near < 1e-3 {
        return None;
    }
    let d_far = hull.iter().map(|p| p.length()).fold(0.0, f64::max);
    let c = hull.iter().copied().sum::<DVec2>() / hull.len() as f64;
    let ac = c.y.atan2(c.x);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in hull {
        let d = (p.y.atan2(p.x) - ac + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        (lo, hi) = (lo.min(d), hi.max(d));
    }
    Some(Footprint {
        az_lo: ac + lo,
        az_hi: ac + hi,
        d_near,
        d_far,
    })
}

/// Counter-clockwise convex hull (Andrew's monotone chain); duplicates dropped.
fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

/// The horizon of one eye (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct Horizon {
    eye: DVec3,
    /// World → eye-local rotation (local z: the eye's vertical).
    to_local: DMat3,
    /// `SECTORS × BINS` credited slopes, prefix maxima over the bins; −∞ where nothing is.
    slope: Vec<f64>,
    /// Occluder columns credited this frame.
    pub occluders: u32,
}

/// Corner positions of the occluder level on the ellipsoid, kept across frames.
#[derive(Debug, Clone, Default)]
struct CornerTable {
    key: Option<(u32, u32, u32, u64, u64)>,
    /// Per tile corner (row-major, (tiles_x + 1) per row): world position at height 0 and the
    /// world normal (a position at height h is `p + h·n`, exactly).
    points: Vec<(DVec3, DVec3)>,
}

/// Horizons of a frame's eyes, with what they reuse across frames.
#[derive(Debug, Clone, Default)]
pub struct HorizonSet {
    pub views: Vec<Horizon>,
    corners: CornerTable,
}

/// The occluder level: the finest with at most [`MAX_OCCLUDERS`] tiles.
fn occluder_level(bake: &ErrorBake) -> usize {
    bake.levels
        .iter()
        .position(|t| t.tiles_x * t.tiles_y <= MAX_OCCLUDERS)
        .unwrap_or(bake.levels.len() - 1)
}

/// A level tile's horizontal rectangle in grid metres, clipped to the valid data.
fn tile_rect(bake: &ErrorBake, level: usize, tx: u32, ty: u32) -> (DVec2, DVec2) {
    let q = (bake.params.tile_size - 1) as u64;
    let side = q << level;
    let sp = DVec2::new(bake.spacing_x, bake.spacing_y);
    let vmax = DVec2::new(
        (bake.valid_width - 1) as f64 * bake.spacing_x,
        (bake.valid_height - 1) as f64 * bake.spacing_y,
    );
    let lo = DVec2::new((tx as u64 * side) as f64, (ty as u64 * side) as f64) * sp;
    let hi = lo + DVec2::splat(side as f64) * sp;
    (lo.min(vmax), hi.min(vmax))
}

/// n×n occluder-level tiles from (tx, ty) and their lowest full-resolution sample.
struct Block {
    level: usize,
    tx: u32,
    ty: u32,
    n: u32,
    min_h: f64,
}

impl Block {
    fn rect(&self, bake: &ErrorBake) -> (DVec2, DVec2) {
        let (lo, _) = tile_rect(bake, self.level, self.tx, self.ty);
        let (_, hi) = tile_rect(bake, self.level, self.tx + self.n - 1, self.ty + self.n - 1);
        (lo, hi)
    }
}

impl HorizonSet {
    /// Builds one horizon per eye. `earth`: the ellipsoid (geographic data), else the flat
    /// plane with the curvature drop when `curvature`.
    pub fn build(
        &mut self,
        bake: &ErrorBake,
        earth: Option<&GeoGrid>,
        curvature: bool,
        eyes: &[DVec3],
    ) {
        if bake.levels.is_empty() {
            self.views.clear();
            return;
        }
        let level = occluder_level(bake);
        if let Some(g) = earth {
            self.corners.fill(bake, level, g);
        }
        self.views.resize_with(eyes.len(), Horizon::default);
        for (h, &eye) in self.views.iter_mut().zip(eyes) {
            let to_local = match earth {
                Some(g) => {
                    let geo = g.geodetic_of_world(eye);
                    g.local_enu_axes(geo.lat_deg, geo.lon_deg).transpose()
                }
                None => DMat3::IDENTITY,
            };
            h.build(bake, level, earth, curvature, eye, to_local, &self.corners);
        }
    }

    /// Whether view `view`'s eye sees nothing of `aabb` (world box) — see [`Horizon::hides`].
    pub fn hides(&self, view: usize, aabb: &Aabb) -> bool {
        self.views.get(view).is_some_and(|h| h.hides(aabb))
    }
}

impl CornerTable {
    fn fill(&mut self, bake: &ErrorBake, level: usize, g: &GeoGrid) {
        let t = &bake.levels[level];
        let key = (
            level as u32,
            t.tiles_x,
            t.tiles_y,
            g.spacing_x.to_bits() ^ g.south_lat_deg.to_bits(),
            g.spacing_y.to_bits() ^ g.west_lon_deg.to_bits(),
        );
        if self.key == Some(key) {
            return;
        }
        self.points.clear();
        let side = ((bake.params.tile_size - 1) as u64) << level;
        let vmax = DVec2::new(
            (bake.valid_width - 1) as f64 * bake.spacing_x,
            (bake.valid_height - 1) as f64 * bake.spacing_y,
        );
        for cy in 0..=t.tiles_y {
            for cx in 0..=t.tiles_x {
                let gp = DVec2::new(
                    (cx as u64 * side) as f64 * bake.spacing_x,
                    (cy as u64 * side) as f64 * bake.spacing_y,
                )
                .min(vmax);
                let p0 = g.world_of_grid(gp, 0.0);
                let n = g.world_of_grid(gp, 1.0) - p0;
                self.points.push((p0, n));
            }
        }
        self.key = Some(key);
    }
}

impl Horizon {
    #[allow(clippy::too_many_arguments)]
    fn build(
        &mut self,
        bake: &ErrorBake,
        level: usize,
        earth: Option<&GeoGrid>,
        curvature: bool,
        eye: DVec3,
        to_local: DMat3,
        corners: &CornerTable,
    ) {
        self.eye = eye;
        self.to_local = to_local;
        self.slope.clear();
        self.slope.resize(SECTORS * BINS, f64::NEG_INFINITY);
        self.occluders = 0;
        let t = &bake.levels[level];
        let cell = DVec2::new(bake.spacing_x, bake.spacing_y) * (1u64 << level) as f64;
        // Single tiles, then 2×2 blocks at stride 1: a sector straddling the seam between two
        // tiles is wholly inside neither, but inside the block holding both.
        for n in [1u32, 2] {
            for ty in 0..t.tiles_y.saturating_sub(n - 1) {
                for tx in 0..t.tiles_x.saturating_sub(n - 1) {
                    let mut min_h = f64::INFINITY;
                    let mut terrain = true;
                    for (dx, dy) in (0..n).flat_map(|dy| (0..n).map(move |dx| (dx, dy))) {
                        let i = ((ty + dy) * t.tiles_x + tx + dx) as usize;
                        terrain &= t.terrain[i];
                        min_h = min_h.min(t.min[i] as f64);
                    }
                    if !terrain {
                        continue;
                    }
                    let block = Block {
                        level,
                        tx,
                        ty,
                        n,
                        min_h,
                    };
                    let column = match earth {
                        Some(g) => self.geo_column(bake, &block, g, corners),
                        None => self.flat_column(bake, &block, curvature, cell),
                    };
                    if let Some((fp, top)) = column {
                        self.credit(&fp, top);
                    }
                }
            }
        }
        // Prefix maxima: a bin holds every occluder wholly within its edge.
        for s in 0..SECTORS {
            let row = &mut self.slope[s * BINS..(s + 1) * BINS];
            for b in 1..BINS {
                row[b] = row[b].max(row[b - 1]);
            }
        }
    }

    /// A flat-plane column: the block's rectangle, its minimum less the farthest corner's drop.
    fn flat_column(
        &self,
        bake: &ErrorBake,
        b: &Block,
        curvature: bool,
        cell: DVec2,
    ) -> Option<(Footprint, f64)> {
        let (lo, hi) = b.rect(bake);
        let e = self.eye.truncate();
        let quad = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)].map(|p| p - e);
        let fp = footprint_of_quad(&quad)?;
        let mut top = b.min_h - self.eye.z;
        if curvature {
            top -= fp.d_far * fp.d_far / (2.0 * EARTH_RADIUS_M)
                + curvature_interpolation_error(cell.length());
        }
        Some((fp, top))
    }

    /// An ellipsoid column: the corners at the minimum height in the eye's frame, the quad
    /// shrunk (module documentation), the top the lowest corner less the block's sag.
    fn geo_column(
        &self,
        bake: &ErrorBake,
        b: &Block,
        g: &GeoGrid,
        corners: &CornerTable,
    ) -> Option<(Footprint, f64)> {
        let row = bake.levels[b.level].tiles_x as usize + 1;
        let (x0, y0, n) = (b.tx as usize, b.ty as usize, b.n as usize);
        let idx = [
            y0 * row + x0,
            y0 * row + x0 + n,
            (y0 + n) * row + x0 + n,
            (y0 + n) * row + x0,
        ];
        let local = idx.map(|i| {
            let (p0, up) = corners.points[i];
            self.to_local * (p0 + up * b.min_h - self.eye)
        });
        let flat = local.map(|p| p.truncate());
        let c = flat.iter().copied().sum::<DVec2>() / 4.0;
        let half_diag = flat.iter().map(|p| (*p - c).length()).fold(0.0, f64::max);
        let shrink = 2.0 + 1e-3 * c.length();
        if half_diag <= shrink {
            return None;
        }
        let k = 1.0 - shrink / half_diag;
        let quad = flat.map(|p| c + (p - c) * k);
        let fp = footprint_of_quad(&quad)?;
        let (lo, hi) = b.rect(bake);
        let sag = g.cell_sag_m(lo, hi, 1, b.min_h as f32, b.min_h as f32)
            + curvature_interpolation_error((hi - lo).length());
        let top = local.iter().map(|p| p.z).fold(f64::INFINITY, f64::min) - sag - 0.05;
        Some((fp, top))
    }

    /// Credits a column (eye-relative top `top`) to the sectors it covers wholly.
    fn credit(&mut self, fp: &Footprint, top: f64) {
        let Some(bin) = bin_at_or_beyond(fp.d_far) else {
            return;
        };
        let slope = if top > 0.0 {
            top / fp.d_far
        } else {
            top / fp.d_near
        };
        // Shrunk by a hair against rounding: only sectors strictly inside count.
        let k0 = ((fp.az_lo + 1e-9) / SECTOR_RAD).ceil() as i64;
        let k1 = ((fp.az_hi - 1e-9) / SECTOR_RAD).floor() as i64;
        if k1 <= k0 {
            return;
        }
        self.occluders += 1;
        for k in k0..k1 {
            let s = k.rem_euclid(SECTORS as i64) as usize;
            let v = &mut self.slope[s * BINS + bin];
            *v = v.max(slope);
        }
    }

    /// Whether the eye sees no point of `aabb` (world box): see the module's invariant.
    pub fn hides(&self, aabb: &Aabb) -> bool {
        if self.slope.is_empty() {
            return false;
        }
        let local = aabb.corners().map(|c| self.to_local * (c - self.eye));
        // On the flat plane the box stays axis-aligned: its footprint is its base rectangle.
        let fp = if self.to_local == DMat3::IDENTITY {
            let (lo, hi) = (aabb.min - self.eye, aabb.max - self.eye);
            footprint_of_quad(&[
                DVec2::new(lo.x, lo.y),
                DVec2::new(hi.x, lo.y),
                DVec2::new(hi.x, hi.y),
                DVec2::new(lo.x, hi.y),
            ])
        } else {
            footprint(&local.map(|p| p.truncate()))
        };
        let Some(fp) = fp else {
            return false;
        };
        let Some(bin) = bin_at_or_before(fp.d_near) else {
            return false;
        };
        let top = local.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
        let steepest = if top > 0.0 {
            top / fp.d_near
        } else {
            top / fp.d_far
        };
        let k0 = ((fp.az_lo - 1e-9) / SECTOR_RAD).floor() as i64;
        let k1 = ((fp.az_hi + 1e-9) / SECTOR_RAD).floor() as i64;
        if k1 - k0 >= SECTORS as i64 / 2 {
            return false;
        }
        let margin = 1e-9 * (1.0 + steepest.abs());
        (k0..=k1).all(|k| {
            let s = k.rem_euclid(SECTORS as i64) as usize;
            self.slope[s * BINS + bin] > steepest + margin
        })
    }
}

#[cfg(test)]
#[path = "horizon_tests.rs"]
mod tests;
