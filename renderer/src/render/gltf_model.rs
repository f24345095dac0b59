//! glTF 2.0 models (`.gltf` with its buffers beside it, or `.glb`) read into one body-axis
//! mesh: every triangle primitive of the default scene's nodes, with the nodes' transforms
//! applied, merged (the LOD chain is then made from the merged mesh). Materials and textures
//! are not read.
//!
//! glTF's axes are +Y up, +Z forward, −X right (the glTF 2.0 specification, "Coordinate
//! System and Units"); CIGI's body axes are x forward, y right, z down, so a glTF point
//! (x, y, z) is the body point (z, −x, −y) — a rotation, handedness kept.

use std::path::Path;

use glam::{Mat3, Mat4, Vec3};

use crate::render::models::MeshData;

/// Largest model accepted, vertices (a model is drawn many times; a scanned city is not one).
pub const MAX_MODEL_VERTICES: usize = 1 << 20;
/// Largest model file read, bytes.
pub const MAX_MODEL_BYTES: u64 = 256 << 20;

/// Why a model could not be read: the file and the reason (the mesh, primitive or accessor).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}: {reason}")]
pub struct ModelError {
    /// The model file.
    pub path: String,
    /// What is wrong.
    pub reason: String,
}

/// Reads the model at `path`.
pub fn load_model(path: &Path) -> Result<MeshData, ModelError> {
    let err = |reason: String| ModelError {
        path: path.display().to_string(),
        reason,
    };
    let size = std::fs::metadata(path)
        .map_err(|e| err(format!("cannot read: {e}")))?
        .len();
    if size > MAX_MODEL_BYTES {
        return Err(err(format!(
            "{size} bytes, more than the {} MiB a model may have",
            MAX_MODEL_BYTES >> 20
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse_model(&bytes, &|uri| {
        let p = dir.join(uri);
        std::fs::read(&p).map_err(|e| format!("buffer {}: {e}", p.display()))
    })
    .map_err(err)
}

/// Parses glTF or GLB `bytes`; `external` reads a buffer's relative URI.
pub fn parse_model(
    bytes: &[u8],
    external: &dyn Fn(&str) -> Result<Vec<u8>, String>,
) -> Result<MeshData, String> {
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| format!("not glTF 2.0: {e}"))?;
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in gltf.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => gltf
                .blob
                .clone()
                .ok_or_else(|| format!("buffer {}: no binary chunk in the file", b.index()))?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                return Err(format!(
                    "buffer {}: embedded data URIs are not read (use .glb or a .bin file)",
                    b.index()
                ))
            }
            gltf::buffer::Source::Uri(uri) => external(uri)?,
        };
        if data.len() < b.length() {
            return Err(format!(
                "buffer {}: {} bytes, the file says {}",
                b.index(),
                data.len(),
                b.length()
            ));
        }
        buffers.push(data);
    }
    let scene = gltf
        .default_scene()
        .or_else(|| gltf.scenes().next())
        .ok_or("no scene")?;
    let mut mesh = MeshData::default();
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut visited = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > 100_000 {
            return Err("more than 100000 nodes (or a cycle)".into());
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(m) = node.mesh() {
            for p in m.primitives() {
                let what = format!("mesh {} primitive {}", m.index(), p.index());
                append_primitive(&mut mesh, &p, &buffers, world)
                    .map_err(|e| format!("{what}: {e}"))?;
                if mesh.positions.len() > MAX_MODEL_VERTICES {
                    return Err(format!("more than {MAX_MODEL_VERTICES} vertices"));
                }
            }
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    if mesh.indices.is_empty() {
        return Err("no triangles in the default scene".into());
    }
    Ok(mesh)
}

/// glTF (x up-y, z forward, −x right) → body (x forward, y right, z down).
fn to_body(v: Vec3) -> [f32; 3] {
    [v.z, -v.x, -v.y]
}

fn append_primitive(
    mesh: &mut MeshData,
    p: &gltf::Primitive,
    buffers: &[Vec<u8>],
    world: Mat4,
) -> Result<(), String> {
    if p.mode() != gltf::mesh::Mode::Triangles {
        // Points and lines have no surface to draw.
        return Ok(());
    }
    let reader = p.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or("no POSITION attribute")?
        .collect();
    if positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err("a position is not finite".into());
    }
    let n = positions.len() as u32;
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..n).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(format!("{} indices, not whole triangles", indices.len()));
    }
    if let Some(bad) = indices.iter().find(|&&i| i >= n) {
        return Err(format!("index {bad} past the {n} vertices"));
    }
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let normals: Vec<[f32; 3]> = match reader.read_normals() {
        Some(it) => it.collect(),
        None => face_normals(&positions, &indices),
    };
    if normals.len() != positions.len() {
        return Err("NORMAL and POSITION counts differ".into());
    }
    let part = MeshData {
        positions: positions
            .iter()
            .map(|p| to_body(world.transform_point3(Vec3::from_array(*p))))
            .collect(),
        normals: normals
            .iter()
            .map(|v| to_body((normal_matrix * Vec3::from_array(*v)).normalize_or(Vec3::Y)))
            .collect(),
        indices,
    };
    mesh.append(&part);
    Ok(())
}

/// Smooth normals from the triangles (area-weighted) for a primitive that has none.
fn face_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from_array(positions[i as usize]));
        let n = (b - a).cross(c - a);
        for &i in t {
            acc[i as usize] += n;
        }
    }
    acc.iter()
        .map(|n| n.normalize_or(Vec3::Y).to_array())
        .collect()
}

/// Writes `mesh` (body axes) as a minimal GLB: one buffer, positions, normals, u32 indices.
/// For tests and for making a model to configure; the inverse of [`parse_model`].
pub fn write_glb(mesh: &MeshData) -> Vec<u8> {
    let from_body = |p: &[f32; 3]| [-p[1], -p[2], p[0]];
    let pos: Vec<[f32; 3]> = mesh.positions.iter().map(from_body).collect();
    let nrm: Vec<[f32; 3]> = mesh.normals.iter().map(from_body).collect();
    let mut bin: Vec<u8> = Vec::new();
    bin.extend_from_slice(bytemuck::cast_slice(&pos));
    bin.extend_from_slice(bytemuck::cast_slice(&nrm));
    bin.extend_from_slice(bytemuck::cast_slice(&mesh.indices));
    let (lo, hi) = pos
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        });
    let vbytes = pos.len() * 12;
    let json = serde_json::json!({
        "asset": {"version": "2.0", "generator": "aerie"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": vbytes, "target": 34962},
            {"buffer": 0, "byteOffset": vbytes, "byteLength": vbytes, "target": 34962},
            {"buffer": 0, "byteOffset": 2 * vbytes, "byteLength": mesh.indices.len() * 4, "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": pos.len(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": nrm.len(), "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": mesh.indices.len(), "type": "SCALAR"},
        ],
    });
    let mut json = serde_json::to_vec(&json).expect("a JSON value serialises");
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::models::{default_aircraft, lod_chain};

    fn no_files(uri: &str) -> Result<Vec<u8>, String> {
        Err(format!("no file {uri}"))
    }

    #[test]
    fn a_glb_round_trips_in_body_axes() {
        let m = default_aircraft();
        let glb = write_glb(&m);
        let back = parse_model(&glb, &no_files).unwrap();
        assert_eq!(back.indices, m.indices);
        assert_eq!(back.positions.len(), m.positions.len());
        for (a, b) in back.positions.iter().zip(&m.positions) {
            assert!((Vec3::from_array(*a) - Vec3::from_array(*b)).length() < 1e-6);
        }
        for (a, b) in back.normals.iter().zip(&m.normals) {
            assert!((Vec3::from_array(*a) - Vec3::from_array(*b)).length() < 1e-5);
        }
        // A single-mesh model gets its three levels.
        assert_eq!(lod_chain(&back).len(), 3);
    }

    #[test]
    fn gltf_axes_map_to_body_axes() {
        // A triangle at glTF +Z (forward), +Y (up), −X (right).
        let m = MeshData {
            positions: vec![[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
            normals: vec![[0.0, 0.0, 1.0]; 3],
            indices: vec![0, 1, 2],
        };
        // write_glb takes body axes: forward (1,0,0) is glTF +Z, up (0,0,−1) is glTF +Y.
        let glb = write_glb(&m);
        let json_end = 20 + u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let json: serde_json::Value = serde_json::from_slice(&glb[20..json_end]).unwrap();
        assert_eq!(json["accessors"][0]["max"][2], 1.0, "forward is glTF +Z");
        assert_eq!(json["accessors"][0]["max"][1], 1.0, "up is glTF +Y");
        let back = parse_model(&glb, &no_files).unwrap();
        assert_eq!(back.positions, m.positions);
    }

    #[test]
    fn broken_models_are_refused_with_the_reason() {
        assert!(parse_model(b"not a model", &no_files)
            .unwrap_err()
            .contains("not glTF"));
        let m = default_aircraft();
        let mut glb = write_glb(&m);
        // Cut the binary chunk short: the buffer is smaller than the file says.
        glb.truncate(glb.len() - 64);
        let n = glb.len() as u32;
        glb[8..12].copy_from_slice(&n.to_le_bytes());
        let chunk = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let bin_len_at = 20 + chunk;
        let bin_len = (glb.len() - bin_len_at - 8) as u32;
        glb[bin_len_at..bin_len_at + 4].copy_from_slice(&bin_len.to_le_bytes());
        let e = parse_model(&glb, &no_files).unwrap_err();
        assert!(e.contains("buffer 0"), "{e}");
        // A .gltf whose buffer file is missing names it.
        let json = br#"{"asset":{"version":"2.0"},"buffers":[{"uri":"plane.bin","byteLength":12}],"scenes":[{"nodes":[]}]}"#;
        let e = parse_model(json, &no_files).unwrap_err();
        assert!(e.contains("plane.bin"), "{e}");
    }
}
