//! The per-frame uniform block: camera, sun, sky and the source's grid (pure).

use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::ClipmapDesc;
use aerie_terrain::geodesy::GeoGrid;
use aerie_terrain::source::SourceGrid;

use crate::render::atmosphere::{Atmosphere, FOG_SCALE_HEIGHT_M, SUN_DISC_DEG};
use crate::render::gpu::{FrameUniforms, IMAGERY_STREAM_LEVELS};

/// Linear-light sky colour of the plain look (clear colour and haze).
pub const SKY_LINEAR: [f32; 3] = [0.38, 0.55, 0.80];

/// Ambient share of the shading (the sun direction's fourth component).
const AMBIENT: f32 = 0.22;
/// Haze distance scale in metres, haze = 1 − e^(−d/scale) (the sky colour's fourth component),
/// when no host sets a visibility: a 40 km visibility (a clear summer day's haze).
pub const HAZE_DISTANCE_M: f32 = 10_225.0;
/// Koschmieder's constant: the meteorological visibility V is the distance at which contrast
/// falls to 2 % (e^(−3.912) = 0.02), so a visibility V is a haze scale of V / 3.912.
const KOSCHMIEDER: f64 = 3.912;
/// The procedural patterns repeat every 8192 m (shaders/landcover.glsl NOISE_PERIOD_M): the
/// eye's position is handed to the shader modulo this, exact in f32 anywhere.
pub const NOISE_PERIOD_M: f64 = 8192.0;

/// The shader's flag bit (`grid_size.w`) for a geographic grid drawn on the ellipsoid:
/// slope, aspect and fog heights are then taken in the local frame (shaders/terrain.frag).
pub const FLAG_GEOGRAPHIC: i32 = 8;
/// The shader's flag bit for lighting level tiles with the levels' normal maps
/// (shaders/normal_map.glsl); set when the renderer keeps them (`--normal-maps on`).
pub const FLAG_NORMAL_MAP: i32 = 16;

/// How the terrain and the sky are drawn (`--look`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Look {
    /// Hypsometric ramp, Lambert sun, constant haze, a flat sky colour (the cost baseline).
    Plain,
    /// Land cover derived from the terrain, Preetham sky and sun disc, aerial perspective.
    #[default]
    Full,
    /// The land-cover classes' flat colours, unlit, over the full look's sky (for checking
    /// the class rules).
    Classes,
    /// The shading normal as colour, local east-north-up (red x, green y, ×½ + ½) and in blue
    /// where it came from: (L + 1)·16/255 from the level-L normal map, 0 per vertex (for
    /// checking the normal maps).
    Normals,
}

impl Look {
    /// The shader's flag bits (`grid_size.w`: 2 full look, 4 class view, 32 normal view).
    pub fn flags(self) -> i32 {
        match self {
            Look::Plain => 0,
            Look::Full => 2,
            Look::Classes => 4,
            Look::Normals => 32,
        }
    }

    /// Whether the sky pass draws (the plain look keeps the clear colour).
    pub fn draws_sky(self) -> bool {
        self != Look::Plain
    }
}

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

    /// The meteorological visibility the haze scale stands for, metres.
    pub fn visibility_m(&self) -> f64 {
        f64::from(self.haze_distance_m) * KOSCHMIEDER
    }

    /// The sky, sun colour and fog of this light.
    pub fn atmosphere(&self) -> Atmosphere {
        Atmosphere::new(self.sun_enu, self.visibility_m(), AMBIENT)
    }
}

/// A light with its atmosphere, made once per light: [`Atmosphere::new`] (Perez coefficients,
/// zenith, the sky's radiance for the ambient) was ~4 % of the frame thread's samples after the
/// plan (the Northern England manoeuvre on lavapipe), and a light is held for many frames (the
/// default one, a host's sun and visibility until it sends others).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameLight {
    lighting: Lighting,
    atmosphere: Atmosphere,
}

impl FrameLight {
    pub fn new(lighting: Lighting) -> Self {
        Self {
            lighting,
            atmosphere: lighting.atmosphere(),
        }
    }

    pub fn lighting(&self) -> &Lighting {
        &self.lighting
    }

    pub fn atmosphere(&self) -> &Atmosphere {
        &self.atmosphere
    }

    /// Takes `lighting`; its atmosphere is made again only where it differs from the light
    /// held (bit for bit: a NaN, which `Lighting::from_host` never keeps, always differs).
    /// True when it did.
    pub fn set(&mut self, lighting: Lighting) -> bool {
        if lighting == self.lighting {
            return false;
        }
        *self = Self::new(lighting);
        true
    }
}

impl Default for FrameLight {
    fn default() -> Self {
        Self::new(Lighting::default())
    }
}

/// The uniforms of a frame drawn from `camera`: `earth` is the grid's place on the ellipsoid
/// (`GeoGrid::of` the grid's geo-reference, made once by the plan: `PlanState::earth`; none on
/// the plane), `curvature` bends the terrain by the Earth's radius, `debug_tiles` colours
/// tiles by level and refinement, `look` chooses the shading.
#[allow(clippy::too_many_arguments)]
pub fn frame_uniforms(
    camera: &Camera,
    grid: &SourceGrid,
    earth: Option<&GeoGrid>,
    clipmap: &ClipmapDesc,
    curvature: bool,
    debug_tiles: bool,
    look: Look,
    light: &FrameLight,
) -> FrameUniforms {
    let (lighting, a) = (light.lighting(), light.atmosphere());
    let p = camera.position;
    let m = camera.relative_world_to_clip_f32();
    let s = lighting.sun_enu;
    // On the ellipsoid the eye's altitude is its height above it, not world z (which drops
    // away from the dataset's corner), and the shader takes up from the ellipsoid normal.
    let eye_height = earth.map_or(p.z, |g| g.geodetic_of_world(p).alt_m);
    let geo_flag = if earth.is_some() { FLAG_GEOGRAPHIC } else { 0 };
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
            grid.spacing_x as f32,
            grid.spacing_y as f32,
            camera.position.z as f32,
            curvature,
        ],
        grid_size: [
            grid.valid_width as i32,
            grid.valid_height as i32,
            clipmap.tile_quads as i32,
            debug_tiles as i32 | look.flags() | geo_flag,
        ],
        // The imagery spans the grid unless the frame says otherwise (a store's layer level).
        clipmap: [
            clipmap.texture_side() as i32,
            clipmap.level_count() as i32,
            grid.valid_width as i32,
            grid.valid_height as i32,
        ],
        eye_world: [
            p.x.rem_euclid(NOISE_PERIOD_M) as f32,
            p.y.rem_euclid(NOISE_PERIOD_M) as f32,
            eye_height as f32,
            FOG_SCALE_HEIGHT_M,
        ],
        sun_colour: with_w(a.sun_colour, SUN_DISC_DEG.to_radians().cos() as f32),
        ambient_colour: with_w(a.ambient, a.exposure),
        sky_sun: with_w(a.sky_sun, a.day),
        perez_a: with_w(a.perez[0], a.turbidity),
        perez_b: with_w(a.perez[1], a.dusk),
        perez_c: with_w(a.perez[2], 0.0),
        perez_d: with_w(a.perez[3], 0.0),
        perez_e: with_w(a.perez[4], 0.0),
        sky_zenith: with_w(a.zenith_over_f0, a.sigma0),
        // No streamed imagery until render/imagery_stream.rs says so.
        imagery_stream: [0; 4],
        imagery_regions: [[0; 4]; IMAGERY_STREAM_LEVELS],
    }
}

fn with_w(v: [f32; 3], w: f32) -> [f32; 4] {
    [v[0], v[1], v[2], w]
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

    #[test]
    fn the_look_and_the_atmosphere_reach_the_uniforms() {
        use aerie_terrain::camera::{Attitude, Frustum};
        use aerie_terrain::heightfield::Heightfield;
        use glam::DVec3;
        let hf = Heightfield {
            width: 65,
            height: 65,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights: vec![0.0; 65 * 65],
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        };
        let ds = aerie_terrain::dataset::Dataset::from_heightfield(hf, "t".into());
        let grid = ds.source_grid();
        let clipmap = ClipmapDesc {
            tile_quads: 16,
            patch_tiles: 8,
            margin_tiles: 2,
            width: ds.hf.width as u32,
            height: ds.hf.height as u32,
        };
        // Far from the origin: the noise anchor wraps, the height does not.
        let cam = Camera::new(
            DVec3::new(-100.0, 3.0 * NOISE_PERIOD_M + 5.5, 2500.0),
            Attitude::from_degrees(0.0, 0.0, 0.0),
            Frustum::symmetric(1.0, 64, 36),
        );
        let light = Lighting::from_host(Some([0.0, 1.0, 1.0]), Some(8_000.0));
        let lit = FrameLight::new(light);
        let u = |look, debug| frame_uniforms(&cam, &grid, None, &clipmap, true, debug, look, &lit);
        assert_eq!(u(Look::Plain, false).grid_size[3], 0);
        assert_eq!(u(Look::Full, false).grid_size[3], 2);
        assert_eq!(u(Look::Classes, true).grid_size[3], 5);
        assert!(Look::Full.draws_sky() && Look::Classes.draws_sky() && !Look::Plain.draws_sky());
        let f = u(Look::Full, false);
        assert_eq!(f.eye_world, [8092.0, 5.5, 2500.0, FOG_SCALE_HEIGHT_M]);
        // The imagery spans the grid's real samples unless the frame says otherwise.
        assert_eq!(
            f.clipmap[2..],
            [grid.valid_width as i32, grid.valid_height as i32]
        );
        // The atmosphere of this light, field by field.
        let a = light.atmosphere();
        assert!((light.visibility_m() - 8_000.0).abs() < 1e-3);
        assert_eq!(f.sky_zenith, with_w(a.zenith_over_f0, a.sigma0));
        assert!((f.sky_zenith[3] - 3.912 / 8_000.0).abs() < 1e-9);
        assert_eq!(f.sky_sun, with_w(a.sky_sun, a.day));
        assert_eq!(f.ambient_colour, with_w(a.ambient, a.exposure));
        assert_eq!(
            [f.perez_a, f.perez_b, f.perez_c, f.perez_d, f.perez_e].map(|v| [v[0], v[1], v[2]]),
            a.perez
        );
        assert_eq!((f.perez_a[3], f.perez_b[3]), (a.turbidity, a.dusk));
        assert_eq!(&f.sun_colour[..3], &a.sun_colour);
        assert!((f.sun_colour[3] - SUN_DISC_DEG.to_radians().cos() as f32).abs() < 1e-7);
    }

    #[test]
    fn a_frame_light_makes_its_atmosphere_again_only_for_another_light() {
        let noon = Lighting::from_host(Some([0.0, 0.3, 1.0]), Some(30_000.0));
        let dusk = Lighting::from_host(Some([1.0, 0.0, 0.05]), Some(30_000.0));
        let hazy = Lighting::from_host(Some([0.0, 0.3, 1.0]), Some(2_000.0));
        let mut light = FrameLight::new(noon);
        assert_eq!(*light.atmosphere(), noon.atmosphere());
        assert!(!light.set(noon), "the same light keeps its atmosphere");
        assert_eq!(*light.atmosphere(), noon.atmosphere());
        // Another sun, then another visibility: each time the atmosphere of the light held.
        for next in [dusk, hazy, noon] {
            assert!(light.set(next));
            assert_eq!(*light.lighting(), next);
            assert_eq!(*light.atmosphere(), next.atmosphere());
        }
        assert_ne!(dusk.atmosphere(), noon.atmosphere());
        assert_ne!(hazy.atmosphere(), noon.atmosphere());
        assert_eq!(FrameLight::default(), FrameLight::new(Lighting::default()));
    }

    #[test]
    fn on_the_ellipsoid_the_eye_height_is_above_it_and_the_flag_is_set() {
        use aerie_terrain::camera::{Attitude, Frustum};
        use aerie_terrain::geodesy::Geodetic;
        use aerie_terrain::heightfield::Heightfield;
        use aerie_terrain::GeoReference;
        let d = 0.01;
        let (sx, sy) = aerie_terrain::load::geographic_spacing_m(47.0, d, d);
        let geo = GeoReference::Geographic {
            south_lat_deg: 47.0,
            west_lon_deg: 5.0,
            dlat_deg: d,
            dlon_deg: d,
        };
        let hf = Heightfield {
            width: 65,
            height: 65,
            spacing_x: sx,
            spacing_y: sy,
            heights: vec![0.0; 65 * 65],
            geo: Some(geo),
            voids_filled: 0,
            spacing_note: String::new(),
        };
        let ds = aerie_terrain::dataset::Dataset::from_heightfield(hf, "g".into());
        let clipmap = ClipmapDesc {
            tile_quads: 16,
            patch_tiles: 8,
            margin_tiles: 2,
            width: 65,
            height: 65,
        };
        let grid = GeoGrid::of(ds.hf.geo.as_ref(), sx, sy).unwrap();
        // 600 km east of the corner world z is about 28 km below the eye's height.
        let pos = grid.world_of_geodetic(Geodetic::new(47.0, 13.0, 2500.0));
        assert!(pos.z < -20_000.0, "{pos}");
        let cam = Camera::new(
            pos,
            Attitude::from_degrees(0.0, 0.0, 0.0),
            Frustum::symmetric(1.0, 64, 36),
        );
        let light = Lighting::default();
        let f = frame_uniforms(
            &cam,
            &ds.source_grid(),
            Some(&grid),
            &clipmap,
            true,
            false,
            Look::Full,
            &FrameLight::new(light),
        );
        assert!((f.eye_world[2] - 2500.0).abs() < 0.01, "{:?}", f.eye_world);
        assert_eq!(f.grid_size[3], Look::Full.flags() | FLAG_GEOGRAPHIC);
    }
}
