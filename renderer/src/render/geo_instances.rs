//! Relative-to-eye frames of the nodes of a geographic dataset drawn on the WGS84 ellipsoid
//! (issue 14; DESIGN.md "Precision"), pure.
//!
//! A sample's position is ECEF(φ, λ, h) minus the eye's: millions of metres on both sides, so
//! it cannot be formed in f32. Per drawn node the CPU computes in f64 the node's centre vertex
//! (height 0) relative to the eye, in world axes, and the world axes of the meridian frame
//! there (radial, east, polar); the vertex shader adds the vertex's offset from that centre,
//! which it forms in f32 from the *differences* of latitude and longitude alone — products of
//! small, well-conditioned factors (cos φ − cos φ0 = −2 sin((φ+φ0)/2) sin((φ−φ0)/2), and the
//! like), sines of small angles by their series (GPU `sin`/`cos` are allowed 2^-11 absolute
//! error: kilometres at the Earth's radius). Every rounding is then relative to the offset or to
//! the eye distance, never to the Earth's radius.
//!
//! A projected (UTM) grid has no constant latitude/longitude step per sample: its node carries
//! cubic polynomials in the vertex's normalised offset (u, v) for its position and normal
//! (`aerie_terrain::geodesy::projected::NodePolynomial`, fitted in f64 on the CPU, its error
//! bounded in the node's box and ε), rotated to world axes; the shader evaluates them in f32
//! (`projected_offset`). Offsets stay within half a node, so every rounding is relative to it.
//!
//! The shader side is `shaders/geo_node.glsl`, shared by the tiles and the tessellation
//! baseline. [`emulate_vertex`] is its arithmetic written again in f32, operation for
//! operation, so that its precision is tested on the CPU against the f64 reference
//! (`tests/tests/geodesy.rs`). Keep the two in step.

use glam::{DMat3, DVec2, DVec3, Mat3, Vec3};

use aerie_terrain::fast_hash::FastHash;
use aerie_terrain::geodesy::projected::ProjectedGrid;
use aerie_terrain::geodesy::wgs84::{WGS84_A, WGS84_E2};
use aerie_terrain::geodesy::{GeoGrid, Geodetic};

use bytemuck::Zeroable;

pub use crate::render::gpu::GeoFields;
use crate::render::gpu::GeoPolynomial;

/// The eye of a frame over a geographic grid: what every node's frame is computed from.
#[derive(Debug, Clone, Copy)]
pub struct GeoEye {
    grid: GeoGrid,
    eye_ecef: DVec3,
    to_world: DMat3,
    dlat_rad: f64,
    dlon_rad: f64,
}

impl GeoEye {
    /// The eye at `eye_world` (world metres: ENU at the grid's south-west sample).
    pub fn new(grid: &GeoGrid, eye_world: DVec3) -> Self {
        Self {
            grid: *grid,
            eye_ecef: grid.world.enu_to_ecef(eye_world),
            to_world: grid.ecef_to_world_rotation(),
            dlat_rad: grid.dlat_deg.to_radians(),
            dlon_rad: grid.dlon_deg.to_radians(),
        }
    }

    /// Whether the grid is projected (UTM): its nodes carry polynomials (`geo_s`, `geo_n`,
    /// drawn from the `GeoPolynomial` buffer); a geographic grid's leave them zero.
    pub fn projected(&self) -> bool {
        self.grid.projected.is_some()
    }

    /// The fields of the node whose south-west vertex is sample `origin` (col, row), drawn
    /// with `q` quads per side of `step` samples: its frame sits at the centre vertex, so
    /// offsets stay within half a node.
    pub fn node_fields(&self, origin: [i64; 2], step: u32, q: u32) -> GeoFields {
        self.node_fields_rel(origin, step, q).0
    }

    /// [`Self::node_fields`] and the f64 vector from the eye to the node's centre vertex (what
    /// `geo_origin.xyz` rounds): with the eye at the world origin, the centre's world position.
    pub fn node_fields_rel(&self, origin: [i64; 2], step: u32, q: u32) -> (GeoFields, DVec3) {
        let (frame, poly) = self.node_frame(origin, step, q);
        let rel = self.centre_rel(&frame);
        (frame.fields.with(&poly, f32x3(rel)), rel)
    }

    /// [`Self::node_fields`] through `cache`, which keeps each node's [`NodeFrame`] across
    /// frames: per frame only the centre relative to the eye is formed (the same fields bit for
    /// bit). `cache` must have begun the frame on this eye's grid ([`GeoNodeCache::begin`]).
    pub fn node_fields_cached(
        &self,
        cache: &mut GeoNodeCache,
        origin: [i64; 2],
        step: u32,
        q: u32,
    ) -> GeoFields {
        let (fields, poly, rel) = self.node_fields_in(cache, origin, step, q);
        fields.with(poly.unwrap_or(&GeoPolynomial::zeroed()), rel)
    }

    /// [`Self::node_fields_cached`] without copying the record: the cached frame fields, whose
    /// `geo_origin.xyz` the caller replaces with the returned centre relative to this eye (the
    /// rest is eye-independent), and on a projected grid the node's polynomials. A frame of
    /// 1,400 nodes copied the ~400-byte record four times per node on its way into the
    /// instance (6 % of `fly --no-draw`'s CPU on Sierra Nevada); the frames are kept apart from
    /// the polynomials so that a geographic grid's frame reads ~100 bytes a node, not ~400.
    pub fn node_fields_in<'c>(
        &self,
        cache: &'c mut GeoNodeCache,
        origin: [i64; 2],
        step: u32,
        q: u32,
    ) -> (&'c FrameFields, Option<&'c GeoPolynomial>, [f32; 3]) {
        debug_assert_eq!(
            cache.grid.as_ref(),
            Some(&self.grid),
            "the cache began elsewhere"
        );
        let key = (
            ((origin[0] as u64) << 32) | (origin[1] as u64 & 0xffff_ffff),
            ((step as u64) << 16) | q as u64,
        );
        let next = cache.frames.len() as u32;
        let at = *cache.index.entry(key).or_insert(next);
        if at == next {
            let (frame, poly) = self.node_frame(origin, step, q);
            cache.frames.push(frame);
            if self.projected() {
                cache.polys.push(poly);
            }
        }
        let frame = &cache.frames[at as usize];
        let rel = self.centre_rel(frame);
        (&frame.fields, cache.polys.get(at as usize), f32x3(rel))
    }

    /// The vector from this eye to the node's centre vertex, in world axes (f64).
    fn centre_rel(&self, frame: &NodeFrame) -> DVec3 {
        self.to_world * (frame.centre_ecef - self.eye_ecef)
    }

    /// Everything of a node's fields that does not depend on the eye: its frame, and on a
    /// projected grid its polynomials (zero on a geographic one).
    fn node_frame(&self, origin: [i64; 2], step: u32, q: u32) -> (NodeFrame, GeoPolynomial) {
        let half = (q / 2) as i64 * step as i64;
        if let Some(p) = &self.grid.projected {
            return self.projected_fields(p, origin, half);
        }
        let (col, row) = ((origin[0] + half) as f64, (origin[1] + half) as f64);
        let lat_deg = self.grid.south_lat_deg + row * self.grid.dlat_deg;
        let lon_deg = self.grid.west_lon_deg + col * self.grid.dlon_deg;
        let centre = aerie_terrain::geodesy::geodetic_to_ecef(Geodetic::new(lat_deg, lon_deg, 0.0));
        let (sp, cp) = lat_deg.to_radians().sin_cos();
        let (sl, cl) = lon_deg.to_radians().sin_cos();
        let axis_r = self.to_world * DVec3::new(cl, sl, 0.0);
        let axis_t = self.to_world * DVec3::new(-sl, cl, 0.0);
        let axis_z = self.to_world * DVec3::Z;
        let w0 = (1.0 - WGS84_E2 * sp * sp).sqrt();
        let r0 = WGS84_A * cp / w0;
        let r0_hi = r0 as f32;
        let r0_lo = (r0 - r0_hi as f64) as f32;
        let v4 = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        let fields = FrameFields {
            geo_origin: [0.0, 0.0, 0.0, self.dlat_rad as f32],
            geo_axis_r: v4(axis_r, sp),
            geo_axis_t: v4(axis_t, cp),
            geo_axis_z: v4(axis_z, w0),
            geo_radius: [self.dlon_rad as f32, r0_hi, r0_lo, 0.0],
        };
        let frame = NodeFrame {
            centre_ecef: centre,
            fields,
        };
        (frame, GeoPolynomial::zeroed())
    }

    /// A projected grid's node (see the module documentation): `half` samples from its
    /// south-west vertex `origin` to its centre.
    fn projected_fields(
        &self,
        p: &ProjectedGrid,
        origin: [i64; 2],
        half: i64,
    ) -> (NodeFrame, GeoPolynomial) {
        let (sx, sy) = (self.grid.spacing_x, self.grid.spacing_y);
        let centre = DVec2::new(
            (origin[0] + half) as f64 * sx,
            (origin[1] + half) as f64 * sy,
        );
        let half_m = DVec2::new(half as f64 * sx, half as f64 * sy);
        let poly = p.node_polynomial(centre, half_m);
        let north = self
            .grid
            .local_enu_axes(poly.lat0_deg, poly.lon0_deg)
            .y_axis;
        let v = |d: DVec3, w: f64| {
            let d = self.to_world * d;
            [d.x as f32, d.y as f32, d.z as f32, w as f32]
        };
        let mut geo_s = [[0.0f32; 4]; 9];
        let mut geo_n = [[0.0f32; 4]; 10];
        let north = north.to_array();
        for k in 0..9 {
            geo_s[k] = v(poly.pos[k], north.get(k).copied().unwrap_or(0.0));
            geo_n[k + 1] = v(poly.normal[k], 0.0);
        }
        geo_n[0] = v(poly.normal0, 0.0);
        let fields = FrameFields {
            geo_origin: [0.0, 0.0, 0.0, (1.0 / half.max(1) as f64) as f32],
            geo_radius: [0.0, 0.0, 0.0, 1.0],
            ..Default::default()
        };
        let frame = NodeFrame {
            centre_ecef: poly.centre_ecef,
            fields,
        };
        (frame, GeoPolynomial { geo_s, geo_n })
    }
}

fn f32x3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// A node's frame on the ellipsoid as the tail of its tile instance holds it: [`GeoFields`]
/// less the polynomials (`GeoPolynomial`, a projected grid's alone).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameFields {
    pub geo_origin: [f32; 4],
    pub geo_axis_r: [f32; 4],
    pub geo_axis_t: [f32; 4],
    pub geo_axis_z: [f32; 4],
    pub geo_radius: [f32; 4],
}

impl FrameFields {
    /// The whole [`GeoFields`]: these, `poly`, and `geo_origin.xyz` = `rel`.
    pub fn with(&self, poly: &GeoPolynomial, rel: [f32; 3]) -> GeoFields {
        GeoFields {
            geo_origin: [rel[0], rel[1], rel[2], self.geo_origin[3]],
            geo_axis_r: self.geo_axis_r,
            geo_axis_t: self.geo_axis_t,
            geo_axis_z: self.geo_axis_z,
            geo_radius: self.geo_radius,
            geo_s: poly.geo_s,
            geo_n: poly.geo_n,
        }
    }
}

/// A node's frame on the ellipsoid without the eye: its centre in ECEF and every frame field
/// but `geo_origin.xyz` (the centre relative to the eye, formed each frame).
#[derive(Debug, Clone, Copy)]
struct NodeFrame {
    centre_ecef: DVec3,
    fields: FrameFields,
}

/// Nodes held before the cache starts afresh: a frame draws one to two thousand, a record is
/// 104 bytes (and on a projected grid 304 more), so at most ~7 MB; starting afresh costs one
/// frame its trigonometry again.
const GEO_CACHE_CAPACITY: usize = 1 << 14;

/// Each drawn node's [`NodeFrame`] kept across frames (a frame's nodes are mostly the last
/// frame's): the latitude and longitude trigonometry, and a UTM node's polynomial fit, are done
/// once per node instead of once per frame. It starts afresh when the grid changes or it holds
/// [`GEO_CACHE_CAPACITY`] nodes.
#[derive(Debug, Default)]
pub struct GeoNodeCache {
    grid: Option<GeoGrid>,
    /// Each node's place in `frames`, keyed by (south-west sample column << 32 | row,
    /// step << 16 | quads): two hashing rounds (sample indices of a grid at most 2^32 wide,
    /// steps and quads far below 2^16). The records sit apart from the table, so growing it
    /// moves 20-byte entries, not the records.
    index: std::collections::HashMap<(u64, u64), u32, FastHash>,
    frames: Vec<NodeFrame>,
    /// On a projected grid each node's polynomials, beside its frame in `frames`; else empty.
    polys: Vec<GeoPolynomial>,
}

/// Nodes room is made for at the start (a frame draws one to two thousand): the cache grows
/// past it by doubling, each time copying its records once.
const GEO_CACHE_RESERVE: usize = 4096;

impl GeoNodeCache {
    /// Starts a frame on `grid`: forgets every node when the grid changed or the cache is full.
    pub fn begin(&mut self, grid: &GeoGrid) {
        if self.grid.as_ref() != Some(grid) || self.frames.len() >= GEO_CACHE_CAPACITY {
            self.index.clear();
            self.frames.clear();
            self.polys.clear();
            self.index.reserve(GEO_CACHE_RESERVE);
            self.frames.reserve(GEO_CACHE_RESERVE);
            self.grid = Some(*grid);
        }
    }

    /// Nodes held.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }
}

/// Whether a renderer drawing with `curvature` (off: `--no-curvature`) may draw a dataset
/// with this geo-reference: a geographic or UTM grid is always drawn on the exact ellipsoid, so
/// a flat Earth there is refused, naming why, rather than silently ignored.
pub fn check_curvature_choice(
    curvature: bool,
    geo: Option<&aerie_terrain::GeoReference>,
) -> Result<(), String> {
    if curvature || GeoGrid::of(geo, 1.0, 1.0).is_none() {
        return Ok(());
    }
    let what = match geo {
        Some(aerie_terrain::GeoReference::Projected { crs, .. }) => {
            format!("projected ({crs}, UTM on WGS84)")
        }
        _ => "geographic (latitude/longitude on WGS84)".to_string(),
    };
    Err(format!(
        "--no-curvature: this dataset is {what}, and such a grid is always drawn on the exact \
         ellipsoid (README \"On the ellipsoid\"); there is no flat Earth to draw it on. Drop \
         the flag (it applies to local grids and projected ones in other CRSs, whose curvature \
         is the d²/2R drop)"
    ))
}

/// WGS84 as the shader has it (f32 constants).
const A_F32: f32 = 6_378_137.0;
const E2_F32: f32 = 0.006_694_38;

/// sin x and 1 − cos x by their series, as `sincos_small` in `shaders/terrain.vert`: exact to
/// f32 rounding for |x| < 1 (a node spans less).
pub fn sincos_small(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x
        * (1.0
            - x2 * (1.0 / 6.0
                - x2 * (1.0 / 120.0
                    - x2 * (1.0 / 5040.0 - x2 * (1.0 / 362_880.0 - x2 * (1.0 / 39_916_800.0))))));
    let omc = x2
        * (0.5
            - x2 * (1.0 / 24.0
                - x2 * (1.0 / 720.0 - x2 * (1.0 / 40_320.0 - x2 * (1.0 / 3_628_800.0)))));
    (s, omc)
}

/// A vertex of a node on the ellipsoid as the vertex shader computes it (f32): `t` the node's
/// fields (what terrain.vert assembles from its instance and polynomial), `step` samples between
/// its vertices, `ij` the vertex in the node (0..=q), `h` its height (skirt already
/// subtracted). Returns the position relative to the eye in world axes.
pub fn emulate_vertex(t: &GeoFields, step: u32, ij: [i32; 2], q: i32, h: f32) -> Vec3 {
    if t.geo_radius[3] != 0.0 {
        return emulate_projected_vertex(t, step, ij, q, h);
    }
    let c = q / 2;
    let step = step as i32;
    let d = [((ij[0] - c) * step) as f32, ((ij[1] - c) * step) as f32];
    let dphi = d[1] * t.geo_origin[3];
    let dlam = d[0] * t.geo_radius[0];
    let (sp0, cp0, w0) = (t.geo_axis_r[3], t.geo_axis_t[3], t.geo_axis_z[3]);
    let (sh, omch) = sincos_small(0.5 * dphi);
    let (sd, omcd) = sincos_small(dphi);
    let (sl, omcl) = sincos_small(dlam);
    let (ch, cd) = (1.0 - omch, 1.0 - omcd);
    let sinp = sp0 * cd + cp0 * sd;
    let cosp = cp0 * cd - sp0 * sd;
    let sm = sp0 * ch + cp0 * sh;
    let cm = cp0 * ch - sp0 * sh;
    let dcos = -2.0 * sm * sh;
    let dsin = 2.0 * cm * sh;
    let dw2 = -E2_F32 * dsin * (sinp + sp0);
    let w = (w0 * w0 + dw2).sqrt();
    let dinv = -dw2 / (w * w0 * (w + w0));
    let dr = A_F32 * (dcos / w + cp0 * dinv) + h * cosp;
    let dz = (A_F32 * (1.0 - E2_F32)) * (dsin / w + sp0 * dinv) + h * sinp;
    let rs = t.geo_radius[2] + dr;
    let x = dr - (t.geo_radius[1] * omcl + rs * omcl);
    let y = t.geo_radius[1] * sl + rs * sl;
    let axes = Mat3::from_cols(
        Vec3::from_slice(&t.geo_axis_r[..3]),
        Vec3::from_slice(&t.geo_axis_t[..3]),
        Vec3::from_slice(&t.geo_axis_z[..3]),
    );
    Vec3::from_slice(&t.geo_origin[..3]) + axes * Vec3::new(x, y, dz)
}

/// A vertex of a projected node as `projected_offset` in `shaders/terrain.vert` computes it
/// (f32, same order of operations): the position relative to the eye in world axes.
pub fn emulate_projected_vertex(t: &GeoFields, step: u32, ij: [i32; 2], q: i32, h: f32) -> Vec3 {
    let c = q / 2;
    let step = step as i32;
    let u = ((ij[0] - c) * step) as f32 * t.geo_origin[3];
    let v = ((ij[1] - c) * step) as f32 * t.geo_origin[3];
    let b = [
        u,
        v,
        u * u,
        u * v,
        v * v,
        u * u * u,
        u * u * v,
        u * v * v,
        v * v * v,
    ];
    let mut s = Vec3::ZERO;
    let mut nrm = Vec3::from_slice(&t.geo_n[0][..3]);
    for (k, bk) in b.iter().enumerate() {
        s += Vec3::from_slice(&t.geo_s[k][..3]) * *bk;
        nrm += Vec3::from_slice(&t.geo_n[k + 1][..3]) * *bk;
    }
    Vec3::from_slice(&t.geo_origin[..3]) + (s + nrm * h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_terrain::GeoReference;

    fn grid(lat: f64, lon: f64, d: f64) -> GeoGrid {
        GeoGrid::of(
            Some(&GeoReference::Geographic {
                south_lat_deg: lat,
                west_lon_deg: lon,
                dlat_deg: d,
                dlon_deg: d,
            }),
            30.0,
            30.0,
        )
        .unwrap()
    }

    /// A node's fields from the cache, filled under other eyes, are the fields computed afresh
    /// for this eye, bit for bit, on a geographic and a UTM grid; a cache that began on another
    /// grid forgets its nodes.
    #[test]
    fn cached_node_fields_equal_fresh_ones_whatever_eye_filled_the_cache() {
        let utm = GeoReference::Projected {
            crs: "EPSG:32632".into(),
            easting: 170_000.0,
            northing: 5_200_000.0,
        };
        let grids = [
            grid(47.0, 11.0, 1.0 / 1200.0),
            GeoGrid::of(Some(&utm), 30.0, 30.0).unwrap(),
        ];
        let nodes = [([0i64, 0], 1u32), ([1024, 2048], 32), ([4096, 512], 8)];
        let eyes = [
            glam::DVec2::new(0.0, 0.0),
            glam::DVec2::new(40_000.0, 60_000.0),
            glam::DVec2::new(-5_000.0, 90_000.0),
        ];
        let mut cache = GeoNodeCache::default();
        for g in &grids {
            for (k, e) in eyes.iter().enumerate() {
                let eye = GeoEye::new(g, g.world_of_grid(*e, 1500.0 + 700.0 * k as f64));
                cache.begin(g);
                for &(origin, step) in &nodes {
                    let cached = eye.node_fields_cached(&mut cache, origin, step, 16);
                    let fresh = eye.node_fields(origin, step, 16);
                    assert_eq!(
                        bytemuck::bytes_of(&cached),
                        bytemuck::bytes_of(&fresh),
                        "{origin:?} step {step}, eye {k}"
                    );
                }
                assert_eq!(cache.len(), nodes.len(), "filled once per grid");
            }
        }
    }

    #[test]
    fn a_flat_earth_is_refused_only_on_data_placed_on_the_ellipsoid() {
        let geo = GeoReference::Geographic {
            south_lat_deg: 47.0,
            west_lon_deg: 11.0,
            dlat_deg: 0.01,
            dlon_deg: 0.01,
        };
        let why = check_curvature_choice(false, Some(&geo)).unwrap_err();
        assert!(
            why.contains("--no-curvature") && why.contains("ellipsoid"),
            "{why}"
        );
        assert_eq!(check_curvature_choice(true, Some(&geo)), Ok(()));
        assert_eq!(check_curvature_choice(false, None), Ok(()));
        let utm = GeoReference::Projected {
            crs: "EPSG:32632".into(),
            easting: 500_000.0,
            northing: 5_200_000.0,
        };
        let why = check_curvature_choice(false, Some(&utm)).unwrap_err();
        assert!(why.contains("EPSG:32632"), "{why}");
        let lv95 = GeoReference::Projected {
            crs: "EPSG:2056".into(),
            easting: 2_600_000.0,
            northing: 1_200_000.0,
        };
        assert_eq!(check_curvature_choice(false, Some(&lv95)), Ok(()));
    }

    #[test]
    fn series_match_f64_trigonometry() {
        for x in [-0.9f64, -0.2, -1e-3, 0.0, 1e-7, 0.05, 0.3, 0.9] {
            let (s, omc) = sincos_small(x as f32);
            let xf = x as f32 as f64;
            assert!(
                (s as f64 - xf.sin()).abs() <= 2e-7 * xf.abs().max(1e-30),
                "{x}"
            );
            let want = 2.0 * (xf / 2.0).sin().powi(2);
            assert!(
                (omc as f64 - want).abs() <= 3e-7 * want.max(1e-30),
                "{x}: {omc} vs {want}"
            );
        }
    }

    #[test]
    fn the_centre_vertex_is_the_node_origin_and_the_far_corner_is_close() {
        let g = grid(47.0, 11.0, 1.0 / 1200.0);
        let eye_world = g.world_of_grid(glam::DVec2::new(40_000.0, 60_000.0), 3000.0);
        let eye = GeoEye::new(&g, eye_world);
        let (origin, step, q) = ([512i64, 768], 4u32, 16u32);
        let t = eye.node_fields(origin, step, q);
        let eye_ecef = g.world.enu_to_ecef(eye_world);
        for (ij, h) in [
            ([8, 8], 0.0f32),
            ([0, 0], 1234.5),
            ([16, 16], 3000.0),
            ([3, 11], -50.0),
        ] {
            let col = origin[0] as f64 + (ij[0] as u32 * step) as f64;
            let row = origin[1] as f64 + (ij[1] as u32 * step) as f64;
            let want =
                g.ecef_to_world_rotation() * (g.ecef_of_sample(col, row, h as f64) - eye_ecef);
            let got = emulate_vertex(&t, step, ij, q as i32, h).as_dvec3();
            assert!((got - want).length() < 0.01, "{ij:?}: {got:?} vs {want:?}");
        }
    }

    /// A UTM node at a zone's edge (zone 32N, 170 km easting, 47° N): the emulated f32 vertex
    /// is within 1 cm of the f64 ECEF − eye at its corners, centre and inside, heights included.
    #[test]
    fn projected_vertices_match_the_f64_reference() {
        let geo = GeoReference::Projected {
            crs: "EPSG:32632".into(),
            easting: 170_000.0,
            northing: 5_200_000.0,
        };
        let g = GeoGrid::of(Some(&geo), 30.0, 30.0).unwrap();
        let eye_world = g.world_of_grid(glam::DVec2::new(40_000.0, 60_000.0), 3000.0);
        let eye = GeoEye::new(&g, eye_world);
        let eye_ecef = g.world.enu_to_ecef(eye_world);
        let (origin, step, q) = ([1024i64, 2048], 32u32, 16u32);
        let t = eye.node_fields(origin, step, q);
        for (ij, h) in [
            ([8, 8], 0.0f32),
            ([0, 0], 1234.5),
            ([16, 16], 3000.0),
            ([3, 11], -50.0),
            ([16, 0], 4500.0),
        ] {
            let col = origin[0] as f64 + (ij[0] as u32 * step) as f64;
            let row = origin[1] as f64 + (ij[1] as u32 * step) as f64;
            let want =
                g.ecef_to_world_rotation() * (g.ecef_of_sample(col, row, h as f64) - eye_ecef);
            let got = emulate_vertex(&t, step, ij, q as i32, h).as_dvec3();
            assert!((got - want).length() < 0.01, "{ij:?}: {got:?} vs {want:?}");
        }
    }
}
