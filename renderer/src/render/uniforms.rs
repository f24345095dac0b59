//! The per-frame uniform block: camera, sun, sky and the dataset's grid (pure).

use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::ClipmapDesc;
use aerie_terrain::dataset::Dataset;

use crate::render::gpu::FrameUniforms;

/// Linear-light sky colour (clear colour and haze).
pub const SKY_LINEAR: [f32; 3] = [0.38, 0.55, 0.80];

/// Ambient share of the shading (the sun direction's fourth component).
const AMBIENT: f32 = 0.22;
/// Haze distance scale in metres, haze = 1 − e^(−d/scale) (the sky colour's fourth component).
const HAZE_DISTANCE_M: f32 = 90_000.0;

/// Sun from the north-west (the cartographic convention for shaded relief), 40° up.
pub fn sun_direction() -> [f32; 3] {
    let (az, el) = (315f64.to_radians(), 40f64.to_radians());
    [
        (el.cos() * az.sin()) as f32,
        (el.cos() * az.cos()) as f32,
        el.sin() as f32,
    ]
}

/// The uniforms of a frame drawn from `camera`: `curvature` bends the terrain by the Earth's
/// radius, `debug_tiles` colours tiles by level and refinement.
pub fn frame_uniforms(
    camera: &Camera,
    dataset: &Dataset,
    clipmap: &ClipmapDesc,
    curvature: bool,
    debug_tiles: bool,
) -> FrameUniforms {
    let m = camera.relative_world_to_clip_f32();
    let s = sun_direction();
    let hf = &dataset.hf;
    let curvature = if curvature {
        (1.0 / (2.0 * aerie_terrain::select::EARTH_RADIUS_M)) as f32
    } else {
        0.0
    };
    FrameUniforms {
        relative_world_to_clip: m.to_cols_array_2d(),
        sun_dir: [s[0], s[1], s[2], AMBIENT],
        sky_colour: [SKY_LINEAR[0], SKY_LINEAR[1], SKY_LINEAR[2], HAZE_DISTANCE_M],
        grid_spacing: [
            hf.spacing_x as f32,
            hf.spacing_y as f32,
            camera.position.z as f32,
            curvature,
        ],
        grid_size: [
            dataset.valid_width as i32,
            dataset.valid_height as i32,
            clipmap.tile_quads as i32,
            debug_tiles as i32,
        ],
        clipmap: [
            clipmap.texture_side() as i32,
            clipmap.level_count() as i32,
            0,
            0,
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sun_is_a_unit_vector_from_the_north_west_and_above() {
        let s = sun_direction();
        let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-6, "{s:?}");
        assert!(s[0] < 0.0 && s[1] > 0.0 && s[2] > 0.0, "{s:?}");
        assert!((s[2] - 40f32.to_radians().sin()).abs() < 1e-6);
    }
}
