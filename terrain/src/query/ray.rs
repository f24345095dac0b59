//! Line of sight: the first point of a ray (or segment) on or below the level-0 triangles,
//! found by a front-to-back descent of the max-height hierarchy.
//!
//! **What is answered.** For a ray `p(t) = origin + t · dir` (`dir` unit, `t` in metres) over
//! `[t_min, t_max]`, let `T` be the part of that range where `p(t)` is over the real data
//! (the closed rectangle of [`SurfaceGrid::real_extent_m`]). The hit is the smallest `t ∈ T`
//! with `p(t).z ≤ h(p(t).xy)`, `h` the level-0 surface. So a ray that starts on or below the
//! ground hits at its start (range `t_min`, the point is the start itself), and a ray that
//! enters the data from outside below the terrain's height hits where it enters (the data's
//! edge acts as a wall); nothing beyond the real data is ever hit. `T` empty → `NoTerrain`.
//!
//! **Descent.** A node is a square of `2^s × 2^s` quads: `s ≥ j` are the bake's level-`(s−j)`
//! tiles (their maximum is the bake's), `1 ≤ s < j` the fine blocks of one level-0 tile
//! ([`super::hierarchy`]), `s = 0` a quad (the max of its corners). For each node the ray's
//! parameter interval over the node's rectangle is clipped (slabs), and the node is skipped when
//! the ray's lower end over that interval is above the node's maximum (the ray is straight, so
//! its lowest point over an interval is at one end). Children are visited in the order the ray
//! enters them, so the first quad with a hit holds the answer. In a quad, the interval is split
//! where the ray crosses the diagonal, and on each piece the ray's height above the piece's
//! plane is linear in `t`: its first zero (or the piece's start, when already ≤ 0) is the hit.
//!
//! **Pending.** A level-0 tile that the ray cannot skip and whose samples are not resident
//! makes the answer `Pending` naming it (every node in front of it was a miss, so the answer
//! hinges on it). Rays passing above a tile's maximum never need its samples.

use glam::DVec3;

use super::source::{SurfaceGrid, SurfaceSource, TileView};
use super::surface::{height_of_terrain, Quad};
use super::Lookup;

/// Why a ray was refused; names the bad argument.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RayError {
    /// A coordinate or range is NaN or infinite (only `t_max` may be +∞).
    #[error("ray {field} is not finite: {value}")]
    NotFinite { field: &'static str, value: String },
    /// The direction has no length.
    #[error("ray direction is zero")]
    ZeroDirection,
    /// `t_min > t_max`.
    #[error("ray range is empty: t_min {t_min} > t_max {t_max}")]
    EmptyRange { t_min: f64, t_max: f64 },
}

/// A ray or segment in local metres (x east, y north, z up, from sample (0, 0)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
}

fn finite(field: &'static str, v: DVec3) -> Result<(), RayError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(RayError::NotFinite {
            field,
            value: format!("{v}"),
        })
    }
}

impl Ray {
    /// The ray from `origin` along `direction` (normalised here, so ranges are metres),
    /// between `t_min` and `t_max` metres from `origin` (`t_max` may be +∞).
    pub fn new(origin: DVec3, direction: DVec3, t_min: f64, t_max: f64) -> Result<Ray, RayError> {
        finite("origin", origin)?;
        finite("direction", direction)?;
        if !t_min.is_finite() {
            return Err(RayError::NotFinite {
                field: "t_min",
                value: t_min.to_string(),
            });
        }
        if t_max.is_nan() || t_max == f64::NEG_INFINITY {
            return Err(RayError::NotFinite {
                field: "t_max",
                value: t_max.to_string(),
            });
        }
        let len = direction.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err(RayError::ZeroDirection);
        }
        if t_min > t_max {
            return Err(RayError::EmptyRange { t_min, t_max });
        }
        Ok(Ray {
            origin,
            dir: direction / len,
            t_min,
            t_max,
        })
    }

    /// The segment `from → to` (ranges from `from`). A segment of length 0 is the point
    /// `from`, tested as a downward ray of range 0 (a hit when it is on or below the ground).
    pub fn segment(from: DVec3, to: DVec3) -> Result<Ray, RayError> {
        finite("from", from)?;
        finite("to", to)?;
        let d = to - from;
        let len = d.length();
        if !len.is_finite() {
            return Err(RayError::NotFinite {
                field: "to − from",
                value: format!("{d}"),
            });
        }
        if len == 0.0 {
            return Ray::new(from, DVec3::NEG_Z, 0.0, 0.0);
        }
        Ray::new(from, d, 0.0, len)
    }

    /// The point at range `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }

    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// Unit direction.
    pub fn dir(&self) -> DVec3 {
        self.dir
    }

    pub fn t_min(&self) -> f64 {
        self.t_min
    }

    pub fn t_max(&self) -> f64 {
        self.t_max
    }
}

/// Where a ray meets the terrain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Metres from the ray's origin.
    pub range_m: f64,
    /// The ray's point at that range, local metres.
    pub point: DVec3,
    /// Unit normal of the triangle hit (on an edge shared by two triangles, either one's).
    pub normal: DVec3,
}

/// The first intersection of `ray` with the level-0 surface: `Ready(Some(hit))`, `Ready(None)`
/// when clear, `NoTerrain` when no part of the ray's range is over real data, `Pending` when
/// a tile it needs is not resident. See the module documentation for the exact definition.
pub fn first_hit<S: SurfaceSource + ?Sized>(src: &S, ray: &Ray) -> Lookup<Option<RayHit>> {
    let grid = src.grid();
    if ray.dir.x == 0.0 && ray.dir.y == 0.0 {
        return vertical(src, ray);
    }
    let w = Walker::new(src, ray);
    let (east, north) = grid.real_extent_m();
    let Some((t0, t1)) = w.clip(0.0, east, 0.0, north, ray.t_min, ray.t_max) else {
        return Lookup::NoTerrain;
    };
    // The top nodes: every tile of the bake's coarsest level.
    let top = grid.levels - 1;
    let (nx, ny) = grid.tiles(top);
    let s = w.j + top;
    let mut order = Vec::with_capacity(4);
    for ty in 0..ny {
        for tx in 0..nx {
            if let Some(c) = w.candidate(s, tx, ty, t0, t1, None) {
                order.push(c);
            }
        }
    }
    order.sort_by(|a, b| a.t0.total_cmp(&b.t0));
    for c in order {
        match w.visit(c, None) {
            Step::Miss => {}
            Step::Hit(h) => return Lookup::Ready(Some(h)),
            Step::Pending(t) => return Lookup::Pending { tile: t },
        }
    }
    Lookup::Ready(None)
}

/// A ray with no horizontal motion stays over one point: the answer follows from the height
/// of terrain there.
fn vertical<S: SurfaceSource + ?Sized>(src: &S, ray: &Ray) -> Lookup<Option<RayHit>> {
    let o = ray.origin;
    let g = match height_of_terrain(src, o.x, o.y) {
        Lookup::Ready(g) => g,
        Lookup::NoTerrain => return Lookup::NoTerrain,
        Lookup::Pending { tile } => return Lookup::Pending { tile },
    };
    let z0 = o.z + ray.t_min * ray.dir.z;
    let t = if z0 <= g.height_m {
        Some(ray.t_min)
    } else if ray.dir.z < 0.0 {
        // dir.z = −1: the ground is (z0 − h) further down.
        let t = ray.t_min + (z0 - g.height_m);
        (t <= ray.t_max).then_some(t)
    } else {
        None
    };
    Lookup::Ready(t.map(|t| RayHit {
        range_m: t,
        point: ray.at(t),
        normal: g.normal,
    }))
}

/// A node to visit: `2^s × 2^s` quads at node index (nx, ny), and the ray's interval over it.
#[derive(Debug, Clone, Copy)]
struct Node {
    s: u32,
    nx: u32,
    ny: u32,
    t0: f64,
    t1: f64,
}

enum Step {
    Miss,
    Hit(RayHit),
    Pending([u32; 2]),
}

struct Walker<'a, S: ?Sized> {
    src: &'a S,
    grid: &'a SurfaceGrid,
    ray: &'a Ray,
    /// 1 / dir.x, 1 / dir.y (unused where the component is 0).
    inv: [f64; 2],
    j: u32,
    /// Real quads per axis (`valid − 1`): nodes starting at or beyond are padding.
    real: [u64; 2],
}

impl<'a, S: SurfaceSource + ?Sized> Walker<'a, S> {
    fn new(src: &'a S, ray: &'a Ray) -> Self {
        let grid = src.grid();
        Walker {
            src,
            grid,
            ray,
            inv: [1.0 / ray.dir.x, 1.0 / ray.dir.y],
            j: grid.log2_tile_quads(),
            real: [grid.valid_width as u64 - 1, grid.valid_height as u64 - 1],
        }
    }

    /// The ray's interval over [x0, x1] × [y0, y1] within [t0, t1]. Shared edges are computed
    /// from the same numbers on both sides, so neighbours' intervals meet exactly.
    #[inline]
    fn clip(&self, x0: f64, x1: f64, y0: f64, y1: f64, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let (lo, hi) = slab(self.ray.origin.x, self.ray.dir.x, self.inv[0], x0, x1)?;
        let (t0, t1) = (t0.max(lo), t1.min(hi));
        let (lo, hi) = slab(self.ray.origin.y, self.ray.dir.y, self.inv[1], y0, y1)?;
        let (t0, t1) = (t0.max(lo), t1.min(hi));
        (t0 <= t1).then_some((t0, t1))
    }

    /// Node (s, nx, ny) if the ray meets it within [t0, t1] low enough to hit something.
    #[inline]
    fn candidate(
        &self,
        s: u32,
        nx: u32,
        ny: u32,
        t0: f64,
        t1: f64,
        tile: Option<&TileView<'_>>,
    ) -> Option<Node> {
        let (q0x, q0y) = (u64::from(nx) << s, u64::from(ny) << s);
        if q0x >= self.real[0] || q0y >= self.real[1] {
            return None;
        }
        let n = 1u64 << s;
        let (sx, sy) = (self.grid.spacing_x, self.grid.spacing_y);
        let (t0, t1) = self.clip(
            q0x as f64 * sx,
            (q0x + n) as f64 * sx,
            q0y as f64 * sy,
            (q0y + n) as f64 * sy,
            t0,
            t1,
        )?;
        let low = self.z(t0).min(self.z(t1));
        if low > self.max_of(s, nx, ny, tile) {
            return None;
        }
        Some(Node { s, nx, ny, t0, t1 })
    }

    #[inline]
    fn z(&self, t: f64) -> f64 {
        self.ray.origin.z + t * self.ray.dir.z
    }

    /// Upper bound of the heights of node (s, nx, ny).
    #[inline]
    fn max_of(&self, s: u32, nx: u32, ny: u32, tile: Option<&TileView<'_>>) -> f64 {
        if s >= self.j {
            return f64::from(self.src.tile_max(s - self.j, nx, ny));
        }
        // Below a level-0 tile the parent handed its view down.
        let Some(v) = tile else {
            return f64::INFINITY;
        };
        let local = (1u32 << (self.j - s)) - 1;
        let (bi, bj) = ((nx & local) as usize, (ny & local) as usize);
        if s == 0 {
            self.quad(v, bi, bj).max()
        } else {
            v.block_max(s, bi, bj)
        }
    }

    #[inline]
    fn quad(&self, v: &TileView<'_>, i: usize, j: usize) -> Quad {
        Quad {
            sw: v.h(i, j),
            se: v.h(i + 1, j),
            nw: v.h(i, j + 1),
            ne: v.h(i + 1, j + 1),
        }
    }

    fn visit(&self, node: Node, tile: Option<&TileView<'_>>) -> Step {
        if node.s == 0 {
            return match tile {
                Some(v) => self.leaf(node, v),
                None => Step::Miss,
            };
        }
        let owned;
        let tile = if node.s == self.j {
            match self.src.tile(node.nx, node.ny) {
                Some(v) => {
                    owned = v;
                    Some(&owned)
                }
                None => return Step::Pending([node.nx, node.ny]),
            }
        } else {
            tile
        };
        let s = node.s - 1;
        let mut kids: [Option<Node>; 4] = [None; 4];
        let mut n = 0;
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            if let Some(c) = self.candidate(
                s,
                2 * node.nx + dx,
                2 * node.ny + dy,
                node.t0,
                node.t1,
                tile,
            ) {
                // Insertion by entry range: front to back.
                let mut k = n;
                while k > 0 && kids[k - 1].is_some_and(|p| p.t0 > c.t0) {
                    kids[k] = kids[k - 1];
                    k -= 1;
                }
                kids[k] = Some(c);
                n += 1;
            }
        }
        for c in kids.into_iter().take(n).flatten() {
            match self.visit(c, tile) {
                Step::Miss => {}
                done => return done,
            }
        }
        Step::Miss
    }

    /// The first hit inside one quad over [t0, t1], if any.
    fn leaf(&self, node: Node, v: &TileView<'_>) -> Step {
        let local = (1u32 << self.j) - 1;
        let (i, j) = ((node.nx & local) as usize, (node.ny & local) as usize);
        let quad = self.quad(v, i, j);
        let (c, r) = (f64::from(node.nx), f64::from(node.ny));
        let (sx, sy) = (self.grid.spacing_x, self.grid.spacing_y);
        let uv = |t: f64| {
            let p = self.ray.at(t);
            (p.x / sx - c, p.y / sy - r, p.z)
        };
        // Split where the ray crosses the diagonal, so each piece lies in one triangle.
        let (u0, v0, _) = uv(node.t0);
        let (u1, v1, _) = uv(node.t1);
        let (g0, g1) = (Quad::side(u0, v0), Quad::side(u1, v1));
        let mut pieces = [(node.t0, node.t1), (node.t1, node.t1)];
        let mut count = 1;
        if (g0 < 0.0) != (g1 < 0.0) && g0 != g1 {
            let tm = node.t0 + (node.t1 - node.t0) * (g0 / (g0 - g1));
            if tm > node.t0 && tm < node.t1 {
                pieces = [(node.t0, tm), (tm, node.t1)];
                count = 2;
            }
        }
        for &(a, b) in &pieces[..count] {
            let (um, vm, _) = uv(0.5 * (a + b));
            let plane = quad.plane(um, vm);
            let above = |t: f64| {
                let (u, v, z) = uv(t);
                z - plane.z(u, v)
            };
            let fa = above(a);
            let t = if fa <= 0.0 {
                a
            } else {
                let fb = above(b);
                if fb > 0.0 {
                    continue;
                }
                (a + (b - a) * (fa / (fa - fb))).clamp(a, b)
            };
            return Step::Hit(RayHit {
                range_m: t,
                point: self.ray.at(t),
                normal: plane.normal(self.grid),
            });
        }
        Step::Miss
    }
}

/// The interval of `t` where `o + t · d` is within [lo, hi]; everything when `d = 0` and `o`
/// is inside, nothing when outside.
#[inline]
fn slab(o: f64, d: f64, inv: f64, lo: f64, hi: f64) -> Option<(f64, f64)> {
    if d == 0.0 {
        return (o >= lo && o <= hi).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let (a, b) = ((lo - o) * inv, (hi - o) * inv);
    Some(if a <= b { (a, b) } else { (b, a) })
}
