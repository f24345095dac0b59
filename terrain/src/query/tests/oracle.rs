//! The brute-force oracle: the level-0 triangles enumerated from the GPU mesh's own index
//! buffer ([`mesh::tile_indices`]), Möller–Trumbore against every one of them, point-in-triangle
//! by barycentric coordinates — none of the query's code (slabs, hierarchy, quad planes).

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use glam::DVec3;

use crate::bake::{bake, BakeParams};
use crate::dataset::{load_dataset, Dataset};
use crate::mesh::tile_indices;
use crate::query::{InMemorySource, Lookup, Ray, RayHit};
use crate::Heightfield;

/// One level-0 triangle, vertices counter-clockwise seen from above.
#[derive(Debug, Clone, Copy)]
pub struct Tri {
    pub a: DVec3,
    pub b: DVec3,
    pub c: DVec3,
}

impl Tri {
    pub fn normal(&self) -> DVec3 {
        (self.b - self.a).cross(self.c - self.a).normalize()
    }

    /// Height at (x, y) and whether (x, y) is inside (edges included, within `tol` in
    /// barycentric units).
    pub fn height_at(&self, x: f64, y: f64, tol: f64) -> Option<f64> {
        let (a, b, c) = (self.a, self.b, self.c);
        let det = (b.y - c.y) * (a.x - c.x) + (c.x - b.x) * (a.y - c.y);
        let l1 = ((b.y - c.y) * (x - c.x) + (c.x - b.x) * (y - c.y)) / det;
        let l2 = ((c.y - a.y) * (x - c.x) + (a.x - c.x) * (y - c.y)) / det;
        let l3 = 1.0 - l1 - l2;
        (l1 >= -tol && l2 >= -tol && l3 >= -tol).then_some(l1 * a.z + l2 * b.z + l3 * c.z)
    }

    /// Möller–Trumbore: the ray parameter where origin + t·dir meets the triangle (edges
    /// included), if it does and is not parallel to it.
    pub fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let e1 = self.b - self.a;
        let e2 = self.c - self.a;
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-14 * e1.length() * e2.length() {
            return None;
        }
        let inv = 1.0 / det;
        let s = origin - self.a;
        let u = s.dot(p) * inv;
        let tol = 1e-12;
        if !(-tol..=1.0 + tol).contains(&u) {
            return None;
        }
        let qv = s.cross(e1);
        let v = dir.dot(qv) * inv;
        if v < -tol || u + v > 1.0 + tol {
            return None;
        }
        Some(e2.dot(qv) * inv)
    }
}

/// The level-0 triangles over real quads with col in `cols`, row in `rows` (quad indices),
/// taken from the mesh's index buffer for `m × m` tiles.
pub fn triangles_in(
    ds: &Dataset,
    m: u32,
    cols: std::ops::Range<usize>,
    rows: std::ops::Range<usize>,
) -> Vec<Tri> {
    let hf = &ds.hf;
    let q = (m - 1) as usize;
    let idx = tile_indices(m);
    let p = |c: usize, r: usize| {
        DVec3::new(
            c as f64 * hf.spacing_x,
            r as f64 * hf.spacing_y,
            f64::from(hf.at(c, r)),
        )
    };
    let mut out = Vec::new();
    let tx_range = cols.start / q..cols.end.div_ceil(q).min((hf.width - 1) / q);
    let ty_range = rows.start / q..rows.end.div_ceil(q).min((hf.height - 1) / q);
    for ty in ty_range {
        for tx in tx_range.clone() {
            for t in idx.chunks(3) {
                let v: Vec<(usize, usize)> = t
                    .iter()
                    .map(|&k| {
                        let k = k as usize;
                        (tx * q + k % m as usize, ty * q + k / m as usize)
                    })
                    .collect();
                let qc = v.iter().map(|p| p.0).min().unwrap();
                let qr = v.iter().map(|p| p.1).min().unwrap();
                let real = qc + 1 < ds.valid_width && qr + 1 < ds.valid_height;
                if real && cols.contains(&qc) && rows.contains(&qr) {
                    out.push(Tri {
                        a: p(v[0].0, v[0].1),
                        b: p(v[1].0, v[1].1),
                        c: p(v[2].0, v[2].1),
                    });
                }
            }
        }
    }
    out
}

/// Every real level-0 triangle.
pub fn all_triangles(ds: &Dataset, m: u32) -> Vec<Tri> {
    triangles_in(ds, m, 0..ds.hf.width, 0..ds.hf.height)
}

/// Height of terrain by search: the heights of every triangle containing (x, y) (they agree),
/// and their normals; `None` when no triangle contains it.
pub fn hot(tris: &[Tri], x: f64, y: f64) -> Option<(f64, Vec<DVec3>)> {
    let mut h = None;
    let mut normals = Vec::new();
    for t in tris {
        if let Some(z) = t.height_at(x, y, 1e-11) {
            h.get_or_insert(z);
            normals.push(t.normal());
        }
    }
    h.map(|h| (h, normals))
}

/// The oracle's answer to a ray: the definition in `ray.rs` restated directly. `extent`: the
/// real data's east and north extent.
pub enum OracleHit {
    NoTerrain,
    Clear,
    /// Range, and the normals that are acceptable (every triangle at that range).
    Hit(f64, Vec<DVec3>),
}

pub fn first_hit(tris: &[Tri], extent: (f64, f64), ray: &Ray) -> OracleHit {
    let (o, d) = (ray.origin(), ray.dir());
    // Where the ray is over the data: solved per axis, written out without slabs.
    let mut lo = ray.t_min();
    let mut hi = ray.t_max();
    for (oc, dc, e) in [(o.x, d.x, extent.0), (o.y, d.y, extent.1)] {
        if dc == 0.0 {
            if oc < 0.0 || oc > e {
                return OracleHit::NoTerrain;
            }
        } else {
            let (ta, tb) = ((0.0 - oc) / dc, (e - oc) / dc);
            lo = lo.max(ta.min(tb));
            hi = hi.min(ta.max(tb));
        }
    }
    if lo > hi {
        return OracleHit::NoTerrain;
    }
    let start = ray.at(lo);
    // Clamp into the rectangle against rounding, to find the triangles under the entry point.
    let (sx, sy) = (start.x.clamp(0.0, extent.0), start.y.clamp(0.0, extent.1));
    if let Some((h, normals)) = hot(tris, sx, sy) {
        if start.z <= h {
            return OracleHit::Hit(lo, normals);
        }
    }
    let hits: Vec<(f64, DVec3)> = tris
        .iter()
        .filter_map(|t| {
            let s = t.intersect(o, d)?;
            (s >= lo - 1e-9 && s <= hi + 1e-9).then(|| (s, t.normal()))
        })
        .collect();
    let Some(best) = hits.iter().map(|h| h.0).min_by(f64::total_cmp) else {
        return OracleHit::Clear;
    };
    let normals = hits
        .iter()
        .filter(|h| h.0 <= best + 1e-6)
        .map(|h| h.1)
        .collect();
    OracleHit::Hit(best.max(lo), normals)
}

/// Asserts the query's answer is the oracle's: same kind, range within `tol` metres, the hit
/// point on the ray, and the normal one of the triangles there.
pub fn assert_agrees(got: Lookup<Option<RayHit>>, want: OracleHit, ray: &Ray, tol: f64) {
    match (got, want) {
        (Lookup::NoTerrain, OracleHit::NoTerrain) | (Lookup::Ready(None), OracleHit::Clear) => {}
        (Lookup::Ready(Some(h)), OracleHit::Hit(t, normals)) => {
            assert!(
                (h.range_m - t).abs() <= tol,
                "range {} vs oracle {t} for {ray:?}",
                h.range_m
            );
            assert!((h.point - ray.at(h.range_m)).length() <= 1e-9 * (1.0 + h.range_m));
            assert!(
                normals.iter().any(|n| (*n - h.normal).length() < 1e-9),
                "normal {} not among {normals:?} for {ray:?}",
                h.normal
            );
        }
        (got, want) => panic!(
            "query {got:?} vs oracle {} for {ray:?}",
            match want {
                OracleHit::NoTerrain => "no terrain".to_string(),
                OracleHit::Clear => "clear".to_string(),
                OracleHit::Hit(t, _) => format!("hit at {t}"),
            }
        ),
    }
}

/// A dataset from a function of (col, row).
pub fn dataset(
    w: usize,
    h: usize,
    spacing: (f64, f64),
    f: impl Fn(usize, usize) -> f32,
) -> Dataset {
    let mut heights = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            heights.push(f(c, r));
        }
    }
    Dataset::from_heightfield(
        Heightfield {
            width: w,
            height: h,
            spacing_x: spacing.0,
            spacing_y: spacing.1,
            heights,
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        },
        "test grid".into(),
    )
}

/// The in-memory source of `ds` baked with `m × m` tiles.
pub fn source(ds: Dataset, m: u32) -> InMemorySource {
    let b = bake(
        &ds,
        BakeParams {
            tile_size: m,
            levels: 0,
        },
        &|_, _| {},
    );
    InMemorySource::new(Arc::new(ds), Arc::new(b)).expect("bake of the same dataset")
}

/// The embedded DEM (N47E011, loaded once per test binary).
pub fn embedded_dem() -> &'static Dataset {
    static DEM: OnceLock<Dataset> = OnceLock::new();
    DEM.get_or_init(|| {
        let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/dem/N47E011.hgt.zip");
        load_dataset(&p).expect("embedded DEM loads")
    })
}

/// A `w × h` window of the embedded DEM from sample (c0, r0), as its own dataset (padded).
pub fn dem_window(c0: usize, r0: usize, w: usize, h: usize) -> Dataset {
    let dem = embedded_dem();
    dataset(w, h, (dem.hf.spacing_x, dem.hf.spacing_y), |c, r| {
        dem.hf.at(c0 + c, r0 + r)
    })
}

/// A small deterministic generator (xorshift64*), so tests need no seed handling.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}
