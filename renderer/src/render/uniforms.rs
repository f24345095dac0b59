//! The per-frame uniform block: camera, sun, sky and the dataset's grid (pure).

use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::ClipmapDesc;
use aerie_terrain::dataset::Dataset;

use crate::render::gpu::FrameUniforms;

/// Linear-light sky colour (clear colour and haze).
pub const SKY_LINEAR: [f32; 3] = [0.38, 0.55, 0.80];

/// Ambient share of the shading (the sun direction's fourth component).
const AMBIENT: f32 = 0.22;
/// Haze distance scale in metres, haze = 1 − e^(−d/scale) (the sky colour's fourth component),
/// when no host sets a visibility.
pub const HAZE_DISTANCE_M: f32 = 90_000.0;
/// Koschmieder's constant: the meteorological visibility V is the distance at which contrast
/// falls to 2 % (e^(−3.912) = 0.02), so a visibility V is a haze scale of V / 3.912.
const KOSCHMIEDER: f64 = 3.912;

/// Sun from the north-west (the cartographic convention for shaded relief), 40° up.
pub fn sun_direction() -> [f32; 3] {
    let (az, el) = (315f64.to_radians(), 40f64.to_radians());
    [
        (el.cos() * az.sin()) as f32,
        (el.cos() * az.cos()) as f32,
        el.sin() as f32,
    ]
}

/// The light a frame is drawn in: a host may set the sun (CIGI Celestial Sphere Control: date
/// and time) and the visibility (Atmosphere Control); otherwise the fixed defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Unit vector towards the sun, local east-north-up.
    pub sun_enu: [f32; 3],
    /// Haze distance scale, metres.
    pub haze_distance_m: f32,
}

impl Default for Lighting {
    fn default() -> Self {
        Self {
            sun_enu: sun_direction(),
            haze_distance_m: HAZE_DISTANCE_M,
        }
    }
}

impl Lighting {
    /// The default light with a host's sun direction (unit ENU, any elevation: below the
    /// horizon only the ambient term lights the ground) and visibility (metres), where given.
    pub fn from_host(sun_enu: Option<[f64; 3]>, visibility_m: Option<f64>) -> Self {
        let mut l = Lighting::default();
        if let Some(s) = sun_enu {
            let n = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            if n.is_finite() && n > 0.0 {
                l.sun_enu = [(s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32];
            }
        }
        if let Some(v) = visibility_m.filter(|v| v.is_finite() && *v > 0.0) {
            l.haze_distance_m = (v / KOSCHMIEDER).clamp(1.0, 1.0e7) as f32;
        }
        l
    }
}

/// The uniforms of a frame drawn from `camera`: `curvature` bends the terrain by the Earth's
/// radius, `debug_tiles` colours tiles by level and refinement.
pub fn frame_uniforms(
    camera: &Camera,
    dataset: &Dataset,
    clipmap: &ClipmapDesc,
    curvature: bool,
    debug_tiles: bool,
    lighting: &Lighting,
) -> FrameUniforms {
    let m = camera.relative_world_to_clip_f32();
    let s = lighting.sun_enu;
    let hf = &dataset.hf;
    let curvature = if curvature {
        (1.0 / (2.0 * aerie_terrain::select::EARTH_RADIUS_M)) as f32
    } else {
        0.0
    };
    FrameUniforms {
        relative_world_to_clip: m.to_cols_array_2d(),
        sun_dir: [s[0], s[1], s[2], AMBIENT],
        sky_colour: [
            SKY_LINEAR[0],
            SKY_LINEAR[1],
            SKY_LINEAR[2],
            lighting.haze_distance_m,
        ],
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

    #[test]
    fn host_light_sets_the_sun_and_the_haze_from_visibility() {
        assert_eq!(Lighting::from_host(None, None), Lighting::default());
        let l = Lighting::from_host(Some([0.0, -2.0, 0.0]), Some(10_000.0));
        assert_eq!(l.sun_enu, [0.0, -1.0, 0.0]);
        // At the visibility distance the haze leaves 2 % of the contrast.
        let contrast = (-10_000.0f64 / f64::from(l.haze_distance_m)).exp();
        assert!((contrast - 0.02).abs() < 1e-3, "{contrast}");
        // Nonsense from a host keeps the defaults.
        let bad = Lighting::from_host(Some([0.0; 3]), Some(-5.0));
        assert_eq!(bad, Lighting::default());
        let nan = Lighting::from_host(Some([f64::NAN, 0.0, 1.0]), Some(f64::NAN));
        assert_eq!(nan, Lighting::default());
    }
}
