//! Entity models and their level-of-detail chains (pure: meshes in, meshes out).
//!
//! A model is one triangle mesh in its body axes (x forward, y right, z down, metres; CIGI's
//! entity axes). Every model has [`LOD_LEVELS`] levels: level 0 is the mesh itself, levels 1
//! and 2 are made at load by meshoptimizer's simplifier (document 004's half-edge collapse,
//! done by a library), aiming at ¼ and 1⁄16 of the triangles, each level's geometric error
//! (metres, as meshoptimizer measures it) kept for the report. All levels of a model share its
//! vertices; the library packs every model into one vertex and one index list.
//!
//! The built-in default model ([`default_aircraft`]) is drawn for entity types the
//! configuration does not map: a light aircraft 8 m long with an 11 m span, generated here so
//! no asset file is needed.

use std::collections::BTreeMap;

use aerie_config::entities::LOD_LEVELS;
use glam::Vec3;

use crate::render::gpu::EntityVertex;

/// A triangle mesh in body axes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions, metres.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals (same length as `positions`).
    pub normals: Vec<[f32; 3]>,
    /// Triangle list.
    pub indices: Vec<u32>,
}

impl MeshData {
    /// Triangles.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends `other` (its indices shifted).
    pub fn append(&mut self, other: &MeshData) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// A bounding sphere (centre of the box, radius to the farthest vertex).
    pub fn bounding_sphere(&self) -> ([f32; 3], f32) {
        if self.positions.is_empty() {
            return ([0.0; 3], 0.0);
        }
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in &self.positions {
            lo = lo.min(Vec3::from_array(*p));
            hi = hi.max(Vec3::from_array(*p));
        }
        let c = 0.5 * (lo + hi);
        let r = self
            .positions
            .iter()
            .map(|p| (Vec3::from_array(*p) - c).length())
            .fold(0.0f32, f32::max);
        (c.to_array(), r)
    }
}

/// One level of a model in the library's index list.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LevelRange {
    /// First index in the library's index list.
    pub first_index: u32,
    /// Indices (3 per triangle).
    pub index_count: u32,
    /// Geometric error of this level against level 0, metres (0 for level 0).
    pub error_m: f32,
}

impl LevelRange {
    /// Triangles of this level.
    pub fn triangles(&self) -> u32 {
        self.index_count / 3
    }
}

/// A model in the library.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Where it came from (a path, or "built-in default").
    pub name: String,
    /// Added to every index of its levels (its first vertex in the library).
    pub vertex_offset: i32,
    /// Levels 0 (finest) … 2.
    pub levels: [LevelRange; LOD_LEVELS],
    /// Bounding sphere centre, body axes, metres.
    pub centre: [f32; 3],
    /// Bounding sphere radius, metres.
    pub radius: f32,
    /// Linear tint of its instances.
    pub tint: [f32; 3],
}

/// Every model, packed for the GPU, and which model each entity type uses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelLibrary {
    /// Every model's vertices.
    pub vertices: Vec<EntityVertex>,
    /// Every model's levels' indices (relative to the model's first vertex).
    pub indices: Vec<u32>,
    /// Model 0 is the default.
    pub models: Vec<Model>,
    /// Entity type → model.
    pub by_type: BTreeMap<u16, usize>,
}

/// Index of the default model in every library.
pub const DEFAULT_MODEL: usize = 0;
/// Linear tint of the default model (a white-and-red light aircraft seen from afar: light grey).
const DEFAULT_TINT: [f32; 3] = [0.80, 0.78, 0.74];
/// Linear tint of configured models (glTF materials are not read).
const MODEL_TINT: [f32; 3] = [0.85, 0.55, 0.20];

impl ModelLibrary {
    /// A library holding the default model only.
    pub fn with_default() -> Self {
        let mut lib = Self::default();
        lib.add("built-in default".into(), &default_aircraft(), DEFAULT_TINT);
        lib
    }

    /// Adds `mesh` with its LOD chain; returns its index.
    pub fn add(&mut self, name: String, mesh: &MeshData, tint: [f32; 3]) -> usize {
        let chain = lod_chain(mesh);
        let vertex_offset = self.vertices.len() as i32;
        self.vertices.extend(
            mesh.positions
                .iter()
                .zip(&mesh.normals)
                .map(|(p, n)| EntityVertex {
                    position: [p[0], p[1], p[2], 1.0],
                    normal: [n[0], n[1], n[2], 0.0],
                }),
        );
        let mut levels = [LevelRange::default(); LOD_LEVELS];
        for (level, (indices, error_m)) in levels.iter_mut().zip(chain) {
            *level = LevelRange {
                first_index: self.indices.len() as u32,
                index_count: indices.len() as u32,
                error_m,
            };
            self.indices.extend_from_slice(&indices);
        }
        let (centre, radius) = mesh.bounding_sphere();
        self.models.push(Model {
            name,
            vertex_offset,
            levels,
            centre,
            radius,
            tint,
        });
        self.models.len() - 1
    }

    /// Adds a configured model for `entity_type`.
    pub fn add_for_type(&mut self, entity_type: u16, name: String, mesh: &MeshData) {
        let i = self.add(name, mesh, MODEL_TINT);
        self.by_type.insert(entity_type, i);
    }

    /// The model of an entity type (the default one when not configured).
    pub fn model_for(&self, entity_type: u16) -> usize {
        self.by_type
            .get(&entity_type)
            .copied()
            .unwrap_or(DEFAULT_MODEL)
    }
}

/// Share of level 0's triangles each level aims at.
pub const LEVEL_TARGETS: [f32; LOD_LEVELS] = [1.0, 0.25, 1.0 / 16.0];
/// Largest error each level may reach, as a fraction of the model's extent (meshoptimizer's
/// relative error): the simplifier stops at whichever of target and error comes first.
const LEVEL_MAX_ERROR: [f32; LOD_LEVELS] = [0.0, 0.02, 0.08];

/// The LOD chain of `mesh`: per level its index list (into `mesh`'s vertices) and geometric
/// error in metres. When the topology-preserving simplifier cannot get below ¾ of the
/// previous level (many small separate parts), the "sloppy" simplifier is used instead.
pub fn lod_chain(mesh: &MeshData) -> Vec<(Vec<u32>, f32)> {
    let mut out = vec![(mesh.indices.clone(), 0.0f32)];
    if mesh.indices.is_empty() {
        out.resize(LOD_LEVELS, (Vec::new(), 0.0));
        return out;
    }
    let bytes: &[u8] = bytemuck::cast_slice(&mesh.positions);
    let adapter = match meshopt::VertexDataAdapter::new(bytes, 12, 0) {
        Ok(a) => a,
        Err(_) => {
            out.resize(LOD_LEVELS, (mesh.indices.clone(), 0.0));
            return out;
        }
    };
    let scale = meshopt::simplify_scale(&adapter);
    for level in 1..LOD_LEVELS {
        let target = ((mesh.indices.len() as f32 * LEVEL_TARGETS[level]) as usize / 3 * 3).max(3);
        let max_error = LEVEL_MAX_ERROR[level];
        let mut error = 0.0f32;
        let mut indices = meshopt::simplify(
            &mesh.indices,
            &adapter,
            target,
            max_error,
            meshopt::SimplifyOptions::Prune,
            Some(&mut error),
        );
        let previous = out[level - 1].0.len();
        if indices.len() * 4 > previous * 3 || indices.is_empty() {
            let mut sloppy_error = 0.0f32;
            let sloppy = meshopt::simplify_sloppy(
                &mesh.indices,
                &adapter,
                target,
                max_error,
                Some(&mut sloppy_error),
            );
            if !sloppy.is_empty() && sloppy.len() < indices.len().max(1) {
                indices = sloppy;
                error = sloppy_error;
            }
        }
        if indices.is_empty() {
            indices = out[level - 1].0.clone();
            error = out[level - 1].1 / scale.max(f32::MIN_POSITIVE);
        }
        out.push((indices, error * scale));
    }
    out
}

/// An open tube along x with `ring` vertices around and `stations` (x, radius) along it,
/// closed at both ends by a point; smooth normals from the surface.
fn body_of_revolution(stations: &[(f32, f32)], ring: u32, z_offset: f32) -> MeshData {
    let mut m = MeshData::default();
    let n = stations.len() as u32;
    for (k, &(x, r)) in stations.iter().enumerate() {
        // Slope of the radius for the normal's x component.
        let (xa, ra) = stations[k.saturating_sub(1)];
        let (xb, rb) = stations[(k + 1).min(stations.len() - 1)];
        let drdx = if xb != xa { (rb - ra) / (xb - xa) } else { 0.0 };
        for j in 0..ring {
            let a = j as f32 / ring as f32 * std::f32::consts::TAU;
            let (s, c) = a.sin_cos();
            m.positions.push([x, r * c, z_offset + r * s]);
            let nrm = Vec3::new(-drdx, c, s).normalize();
            m.normals.push(nrm.to_array());
        }
    }
    for k in 0..n - 1 {
        for j in 0..ring {
            let (a, b) = (k * ring + j, k * ring + (j + 1) % ring);
            let (c, d) = (a + ring, b + ring);
            m.indices.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    m
}

/// A box from `lo` to `hi`, each face cut into `cuts.0 × cuts.1 × cuts.2` cells along x, y, z
/// (so the simplifier has something to remove), flat normals.
fn slab(lo: [f32; 3], hi: [f32; 3], cuts: [u32; 3]) -> MeshData {
    let mut m = MeshData::default();
    // Each face: the axis it faces along, the sign, and its two in-plane axes.
    for (axis, sign) in [
        (0, 1.0f32),
        (0, -1.0),
        (1, 1.0),
        (1, -1.0),
        (2, 1.0),
        (2, -1.0),
    ] {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let (nu, nv) = (cuts[u].max(1), cuts[v].max(1));
        let base = m.positions.len() as u32;
        let mut normal = [0.0f32; 3];
        normal[axis] = sign;
        for j in 0..=nv {
            for i in 0..=nu {
                let mut p = [0.0f32; 3];
                p[axis] = if sign > 0.0 { hi[axis] } else { lo[axis] };
                p[u] = lo[u] + (hi[u] - lo[u]) * i as f32 / nu as f32;
                p[v] = lo[v] + (hi[v] - lo[v]) * j as f32 / nv as f32;
                m.positions.push(p);
                m.normals.push(normal);
            }
        }
        for j in 0..nv {
            for i in 0..nu {
                let a = base + j * (nu + 1) + i;
                let (b, c, d) = (a + 1, a + nu + 1, a + nu + 2);
                if sign > 0.0 {
                    m.indices.extend_from_slice(&[a, b, d, a, d, c]);
                } else {
                    m.indices.extend_from_slice(&[a, d, b, a, c, d]);
                }
            }
        }
    }
    m
}

/// The built-in default model: a high-wing light aircraft in body axes (x forward, y right,
/// z down), 8 m long, 11 m span, about 1.9 k triangles at level 0.
pub fn default_aircraft() -> MeshData {
    // Fuselage: nose at x = +4 m, tail cone at −4 m, widest (0.7 m) behind the cockpit.
    let stations: Vec<(f32, f32)> = (0..=24)
        .map(|k| {
            let x = 4.0 - 8.0 * k as f32 / 24.0;
            let t = (4.0 - x) / 8.0; // 0 at the nose, 1 at the tail
            let r = if t < 0.3 {
                0.7 * (t / 0.3).sqrt().max(0.08)
            } else {
                0.7 - 0.55 * ((t - 0.3) / 0.7)
            };
            (x, r)
        })
        .collect();
    let mut m = body_of_revolution(&stations, 24, 0.0);
    // Wing on top of the fuselage, tailplane, fin.
    m.append(&slab([0.2, -5.5, -0.85], [1.7, 5.5, -0.7], [6, 32, 1]));
    m.append(&slab([-3.9, -1.8, -0.3], [-3.0, 1.8, -0.22], [4, 12, 1]));
    m.append(&slab([-4.0, -0.05, -1.9], [-3.0, 0.05, -0.3], [4, 1, 8]));
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_aircraft_is_a_closed_sized_model() {
        let m = default_aircraft();
        assert_eq!(m.positions.len(), m.normals.len());
        assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
        assert!(m.triangles() > 1000, "{}", m.triangles());
        let (c, r) = m.bounding_sphere();
        // Span 11 m, length 8 m: the sphere's radius is about half the span.
        assert!((5.4..6.5).contains(&r), "{r}");
        assert!(c[0].abs() < 0.5 && c[1].abs() < 0.01, "{c:?}");
        for n in &m.normals {
            assert!((Vec3::from_array(*n).length() - 1.0).abs() < 1e-4);
        }
    }

    #[test]
    fn lod_chain_halves_and_more_with_growing_error() {
        let m = default_aircraft();
        let chain = lod_chain(&m);
        assert_eq!(chain.len(), LOD_LEVELS);
        let tris: Vec<usize> = chain.iter().map(|(i, _)| i.len() / 3).collect();
        assert_eq!(tris[0], m.triangles());
        // Each level at most half of the one before it (document 004's rule of thumb, and
        // meshoptimizer aims at a quarter).
        assert!(tris[1] * 2 <= tris[0], "{tris:?}");
        assert!(tris[2] * 2 <= tris[1], "{tris:?}");
        assert!(tris[2] > 0);
        let errors: Vec<f32> = chain.iter().map(|(_, e)| *e).collect();
        assert_eq!(errors[0], 0.0);
        assert!(errors[1] > 0.0 && errors[2] >= errors[1], "{errors:?}");
        // Errors stay a small part of the 11 m model.
        assert!(errors[2] < 1.5, "{errors:?}");
        for (i, _) in &chain {
            assert!(i.iter().all(|&v| (v as usize) < m.positions.len()));
        }
    }

    #[test]
    fn library_packs_models_and_maps_types() {
        let mut lib = ModelLibrary::with_default();
        let small = slab([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0], [4, 4, 4]);
        lib.add_for_type(1234, "cube".into(), &small);
        assert_eq!(lib.models.len(), 2);
        assert_eq!(lib.model_for(1234), 1);
        assert_eq!(lib.model_for(99), DEFAULT_MODEL);
        let cube = &lib.models[1];
        assert_eq!(
            cube.vertex_offset as usize,
            default_aircraft().positions.len()
        );
        assert_eq!(cube.levels[0].triangles() as usize, small.triangles());
        // Levels lie one after another in the packed list, inside it.
        for m in &lib.models {
            for l in &m.levels {
                assert!((l.first_index + l.index_count) as usize <= lib.indices.len());
            }
        }
        assert!((cube.radius - 3f32.sqrt()).abs() < 1e-5);
    }
}
