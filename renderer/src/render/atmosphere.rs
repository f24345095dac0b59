//! The sky and the air between the eye and the terrain (pure): what `shaders/atmosphere.glsl`
//! evaluates per pixel, computed here once per frame from the sun and the visibility, and the
//! same per-direction formulas on the CPU ([`Atmosphere::sky_radiance`], [`Atmosphere::fog`])
//! so that tests can check the shader against them.
//!
//! - **Sky**: A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic Model for Daylight",
//!   SIGGRAPH 1999: the Perez et al. (1993) all-weather distribution
//!   `F(θ, γ) = (1 + A e^(B / cos θ)) (1 + C e^(D γ) + E cos² γ)` for luminance Y and the
//!   chromaticities x, y, with coefficients linear in the turbidity T (the paper's appendix
//!   A.2), scaled by the zenith values (Y_z from χ, x_z, y_z from the cubic fits), Yxy → XYZ →
//!   linear sRGB, an exposure and `1 − e^(−Y)` on the luminance to keep it in range. The model holds for the sun
//!   above the horizon; below it the sky keeps the sunset's distribution and dims with the
//!   sun's depression (civil twilight to night, a fixed night floor).
//! - **Sun**: the direct light reddens with the air mass (Kasten & Young 1989) through
//!   Rayleigh (λ^−4) and aerosol (Ångström, β from the turbidity as in Preetham's appendix)
//!   optical depths, normalised so an overhead sun is white.
//! - **Aerial perspective**: exponential height fog, extinction `σ(z) = σ₀ e^(−z/H)` with σ₀
//!   from the visibility (Koschmieder: σ₀ = 3.912 / V at sea level) and H = [`FOG_SCALE_HEIGHT_M`];
//!   the light scattered in is the sky's own colour in the view direction, so far terrain fades
//!   into exactly the sky behind it and the horizon blends.

use std::f64::consts::PI;

/// Scale height of the haze layer, metres: the air clears by e every 1500 m above sea level.
pub const FOG_SCALE_HEIGHT_M: f32 = 1500.0;
/// The sky on a moonless night, linear sRGB (so that a night frame is dark, not black).
pub const NIGHT_SKY: [f32; 3] = [0.0015, 0.0022, 0.0045];
/// Light on the ground at night, linear (a sim pilot still sees the terrain's shapes).
pub const NIGHT_AMBIENT: f32 = 0.02;
/// Angular radius of the drawn sun disc, degrees (the real 0.27°, enlarged to stay visible at
/// the IG's pixel sizes).
pub const SUN_DISC_DEG: f64 = 0.4;
/// Exposure of the sky: `K / sqrt(Y_z)` per kcd/m², so a noon zenith (Y_z ≈ 10) is a deep blue
/// and a sunset sky is darker but not black (a partial eye adaptation).
const EXPOSURE_K: f64 = 0.25;
/// The eye adapts to the light's colour: a low sun looks this share as reddened as a
/// photometer says.
const ADAPTATION: f64 = 0.5;
/// Twilight tints (multipliers of the daylight sky): towards the sun, away from it at the
/// horizon, overhead.
const TWILIGHT_TOWARD: [f64; 3] = [1.3, 0.42, 0.12];
const TWILIGHT_AWAY: [f64; 3] = [0.8, 0.55, 0.55];
const TWILIGHT_ZENITH: [f64; 3] = [0.45, 0.6, 1.25];
/// The glow around the sun (forward scattering): its strength and angular width (radians).
const HALO: f64 = 0.35;
const HALO_RAD: f64 = 0.06;
/// Twilight: the sky dims by e every this many degrees of sun depression.
const TWILIGHT_DEG: f64 = 2.5;

/// Everything the sky and the fog need for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Atmosphere {
    /// Unit vector towards the sun (ENU), as given.
    pub sun: [f32; 3],
    /// The sun the sky model sees: elevation clamped to ≥ 0 (Preetham's range).
    pub sky_sun: [f32; 3],
    /// Preetham's turbidity T (2 clear … 10 hazy), from the visibility.
    pub turbidity: f32,
    /// Perez coefficients A…E, each for (Y, x, y).
    pub perez: [[f32; 3]; 5],
    /// Zenith (Y, x, y) divided by F(0, θs), so that a direction's value is this × F(θ, γ).
    pub zenith_over_f0: [f32; 3],
    /// Multiplier of the XYZ luminance before the tone curve.
    pub exposure: f32,
    /// 1 in daylight, falling through twilight to 0 at night.
    pub day: f32,
    /// How much of the twilight tint colours the sky: 0 with the sun above 10°, 1 at the
    /// horizon and below.
    pub dusk: f32,
    /// Direct sunlight on a surface facing the sun, linear RGB (1 = overhead sun, clear sky).
    pub sun_colour: [f32; 3],
    /// Sky light on the ground, linear RGB.
    pub ambient: [f32; 3],
    /// Extinction at sea level, 1/m.
    pub sigma0: f32,
}

fn perez_coefficients(t: f64) -> [[f64; 3]; 5] {
    // Preetham et al. 1999, appendix A.2: rows A..E, columns Y, x, y.
    [
        [
            0.1787 * t - 1.4630,
            -0.0193 * t - 0.2592,
            -0.0167 * t - 0.2608,
        ],
        [
            -0.3554 * t + 0.4275,
            -0.0665 * t + 0.0008,
            -0.0950 * t + 0.0092,
        ],
        [
            -0.0227 * t + 5.3251,
            -0.0004 * t + 0.2125,
            -0.0079 * t + 0.2102,
        ],
        [
            0.1206 * t - 2.5771,
            -0.0641 * t - 0.8989,
            -0.0441 * t - 1.6537,
        ],
        [
            -0.0670 * t + 0.3703,
            -0.0033 * t + 0.0452,
            -0.0109 * t + 0.0529,
        ],
    ]
}

/// Zenith luminance (kcd/m²) and chromaticity for a sun at zenith angle `ts` (radians).
fn zenith(t: f64, ts: f64) -> [f64; 3] {
    let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * ts);
    let y = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
    let (t2, t3) = (ts * ts, ts * ts * ts);
    let x = t * t * (0.00166 * t3 - 0.00375 * t2 + 0.00209 * ts)
        + t * (-0.02903 * t3 + 0.06377 * t2 - 0.03202 * ts + 0.00394)
        + (0.11693 * t3 - 0.21196 * t2 + 0.06052 * ts + 0.25886);
    let yc = t * t * (0.00275 * t3 - 0.00610 * t2 + 0.00317 * ts)
        + t * (-0.04214 * t3 + 0.08970 * t2 - 0.04153 * ts + 0.00516)
        + (0.15346 * t3 - 0.26756 * t2 + 0.06670 * ts + 0.26688);
    [y, x, yc]
}

/// Perez' F for one channel's coefficients.
fn perez_f(c: [f64; 5], cos_theta: f64, gamma: f64) -> f64 {
    let cg = gamma.cos();
    (1.0 + c[0] * (c[1] / cos_theta).exp()) * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * cg * cg)
}

/// Preetham's turbidity for a meteorological visibility: T = 2 + 40 km / V, within 2…10
/// (clear air ≈ 2, a 10 km haze ≈ 6, mist 10), the range the paper's fits cover.
pub fn turbidity_for_visibility(visibility_m: f64) -> f64 {
    (2.0 + 40_000.0 / visibility_m.max(1.0)).clamp(2.0, 10.0)
}

/// Relative optical air mass at elevation `el` (radians, clamped at the horizon), Kasten &
/// Young 1989.
fn air_mass(el: f64) -> f64 {
    let el = el.max(0.0);
    1.0 / (el.sin() + 0.50572 * (el.to_degrees() + 6.07995).powf(-1.6364))
}

/// Zenith optical depths (R, G, B at 680, 550, 450 nm): Rayleigh 0.0088 λ^−4.05 plus aerosol
/// β λ^−1.3 with β = 0.04608 T − 0.04586 (Preetham's appendix).
fn zenith_optical_depth(t: f64) -> [f64; 3] {
    let beta = 0.04608 * t - 0.04586;
    [0.68f64, 0.55, 0.45].map(|l| 0.0088 * l.powf(-4.05) + beta * l.powf(-1.3))
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// CIE XYZ → linear sRGB (D65).
fn xyz_to_rgb(x: f64, y: f64, z: f64) -> [f64; 3] {
    [
        3.2406 * x - 1.5372 * y - 0.4986 * z,
        -0.9689 * x + 1.8758 * y + 0.0415 * z,
        0.0557 * x - 0.2040 * y + 1.0570 * z,
    ]
}

impl Atmosphere {
    /// The atmosphere for a unit sun vector (ENU) and a visibility at sea level (metres).
    pub fn new(sun: [f32; 3], visibility_m: f64, ambient_share: f32) -> Self {
        let s = sun.map(f64::from);
        let el = s[2].clamp(-1.0, 1.0).asin();
        let el_sky = el.max(0.0);
        let h = (s[0] * s[0] + s[1] * s[1]).sqrt();
        // A sun straight up or down has no azimuth: any horizontal direction will do.
        let (hx, hy) = if h > 1e-9 {
            (s[0] / h, s[1] / h)
        } else {
            (0.0, 1.0)
        };
        let sky_sun = [hx * el_sky.cos(), hy * el_sky.cos(), el_sky.sin()];
        let t = turbidity_for_visibility(visibility_m);
        let ts = PI / 2.0 - el_sky;
        let perez = perez_coefficients(t);
        let z = zenith(t, ts);
        let mut zenith_over_f0 = [0.0f32; 3];
        for (c, out) in zenith_over_f0.iter_mut().enumerate() {
            let coeffs = [0, 1, 2, 3, 4].map(|r| perez[r][c]);
            *out = (z[c] / perez_f(coeffs, 1.0, ts)) as f32;
        }
        let exposure = EXPOSURE_K / z[0].max(0.1).sqrt();
        let depression = (-el.to_degrees()).max(0.0);
        let day = (-depression / TWILIGHT_DEG).exp();
        // Direct light: transmittance along the air mass relative to overhead; none once the
        // sun's disc has set.
        let tau = zenith_optical_depth(t);
        let m = air_mass(el);
        let above = smoothstep(-0.5, 0.5, el.to_degrees());
        let sun_colour = tau.map(|k| ((-k * ADAPTATION * (m - 1.0)).exp() * above) as f32);
        let mut a = Atmosphere {
            sun,
            sky_sun: sky_sun.map(|v| v as f32),
            turbidity: t as f32,
            perez: perez.map(|r| r.map(|v| v as f32)),
            zenith_over_f0,
            exposure: exposure as f32,
            day: day as f32,
            dusk: smoothstep(10.0, 0.0, el.to_degrees()) as f32,
            sun_colour,
            ambient: [0.0; 3],
            sigma0: (3.912 / visibility_m.max(1.0)) as f32,
        };
        // Sky light takes the zenith's hue (half-way to white) and dims with the day.
        let zen = a.sky_radiance([0.0, 0.0, 1.0]);
        let mean = (zen[0] + zen[1] + zen[2]) / 3.0;
        a.ambient = zen.map(|c| {
            let tint = if mean > 1e-6 {
                0.5 + 0.5 * c / mean
            } else {
                1.0
            };
            ambient_share * a.day * tint + NIGHT_AMBIENT
        });
        a
    }

    /// Linear sRGB of the sky in direction `dir` (unit, ENU), without the sun disc: the CPU
    /// twin of `sky_radiance` in `shaders/atmosphere.glsl`. Directions below the horizon take
    /// the horizon's colour (no terrain there: beyond the dataset's edge).
    pub fn sky_radiance(&self, dir: [f32; 3]) -> [f32; 3] {
        let d = dir.map(f64::from);
        let cos_theta = d[2].max(0.0).max(0.02);
        let sun = self.sky_sun.map(f64::from);
        // The angle to the sun measured with the view direction raised to the horizon.
        let h = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-9);
        let up = d[2].max(0.0);
        let scale = (1.0 - up * up).sqrt() / h;
        let v = [d[0] * scale, d[1] * scale, up];
        let cg = (v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2]).clamp(-1.0, 1.0);
        let gamma = cg.acos();
        let mut yxy = [0.0f64; 3];
        for (c, out) in yxy.iter_mut().enumerate() {
            let coeffs = [0, 1, 2, 3, 4].map(|r| f64::from(self.perez[r][c]));
            *out = f64::from(self.zenith_over_f0[c]) * perez_f(coeffs, cos_theta, gamma);
        }
        let (lum, x, y) = (yxy[0].max(0.0), yxy[1], yxy[2].max(1e-4));
        let xyz = [x / y * lum, lum, (1.0 - x - y) / y * lum];
        let rgb = xyz_to_rgb(xyz[0], xyz[1], xyz[2]);
        let (e, day) = (f64::from(self.exposure), f64::from(self.day));
        // Per channel, so the glare near the sun whitens as it does to an eye.
        let mapped = rgb.map(|c| 1.0 - (-c.max(0.0) * e).exp());
        let tint = self.twilight_tint(v, up);
        let dusk = f64::from(self.dusk);
        let halo = (-gamma / HALO_RAD).exp() * HALO;
        let sky: [f64; 3] = [0, 1, 2].map(|c| {
            mapped[c] * (1.0 + (tint[c] - 1.0) * dusk) + halo * f64::from(self.sun_colour[c])
        });
        // Scaled, not clipped, into range: an orange stays orange.
        let top = sky[0].max(sky[1]).max(sky[2]).max(1.0);
        [0, 1, 2].map(|c| (sky[c] / top * day) as f32 + NIGHT_SKY[c])
    }

    /// Preetham's model has no sunset colours: towards a low sun the sky turns orange, away
    /// from it and overhead blue (the same in `twilight_tint` of the shader). `v` is the view
    /// direction raised to the horizon, `up` its height.
    fn twilight_tint(&self, v: [f64; 3], up: f64) -> [f64; 3] {
        let s = self.sky_sun.map(f64::from);
        let (sl, vl) = (
            (s[0] * s[0] + s[1] * s[1]).sqrt(),
            (v[0] * v[0] + v[1] * v[1]).sqrt(),
        );
        let toward = if sl > 1e-6 && vl > 1e-6 {
            0.5 + 0.5 * (v[0] * s[0] + v[1] * s[1]) / (sl * vl)
        } else {
            0.5
        };
        let k = toward * toward;
        let height = up.sqrt();
        [0, 1, 2].map(|c| {
            let warm = TWILIGHT_AWAY[c] + (TWILIGHT_TOWARD[c] - TWILIGHT_AWAY[c]) * k;
            warm + (TWILIGHT_ZENITH[c] - warm) * height
        })
    }

    /// Transmittance of the air between the eye at height `eye_z` and a point `dist` metres away
    /// at height `point_z` (metres above sea level): the CPU twin of `fog_transmittance`.
    pub fn transmittance(&self, eye_z: f32, point_z: f32, dist: f32) -> f32 {
        let h = f64::from(FOG_SCALE_HEIGHT_M);
        let x = f64::from(point_z - eye_z) / h;
        // (1 − e^−x)/x, the mean of e^(−Δz/H) along the ray; → 1 for a level ray.
        let g = if x.abs() < 1e-3 {
            1.0 - 0.5 * x
        } else {
            (1.0 - (-x).exp()) / x
        };
        let tau = f64::from(self.sigma0) * (-f64::from(eye_z) / h).exp() * f64::from(dist) * g;
        (-tau.max(0.0)).exp() as f32
    }

    /// A surface colour `lit` seen through the air along `dir` (unit), `dist` metres away at
    /// `point_z`: mixed towards the sky's colour in that direction.
    pub fn fog(
        &self,
        lit: [f32; 3],
        dir: [f32; 3],
        eye_z: f32,
        point_z: f32,
        dist: f32,
    ) -> [f32; 3] {
        let t = self.transmittance(eye_z, point_z, dist);
        let sky = self.sky_radiance(dir);
        [0, 1, 2].map(|c| lit[c] * t + sky[c] * (1.0 - t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sun_at(az_deg: f64, el_deg: f64) -> [f32; 3] {
        let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
        [
            (el.cos() * az.sin()) as f32,
            (el.cos() * az.cos()) as f32,
            el.sin() as f32,
        ]
    }

    fn luminance(c: [f32; 3]) -> f32 {
        0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    }

    #[test]
    fn daylight_zenith_is_blue_and_the_horizon_brighter_and_paler() {
        let a = Atmosphere::new(sun_at(180.0, 50.0), 40_000.0, 0.22);
        let zen = a.sky_radiance([0.0, 0.0, 1.0]);
        assert!(zen[2] > zen[1] && zen[1] > zen[0], "zenith {zen:?}");
        assert!(zen[2] > 0.4 && zen[2] < 0.95, "zenith {zen:?}");
        // Away from the sun, at the horizon: brighter than the zenith, less saturated.
        let hor = a.sky_radiance([0.0, 1.0, 0.0]);
        assert!(luminance(hor) > luminance(zen), "{hor:?} vs {zen:?}");
        assert!(hor[2] / hor[0] < zen[2] / zen[0], "{hor:?} vs {zen:?}");
        // Near the sun is brighter than opposite it.
        let toward = a.sky_radiance(sun_at(180.0, 30.0));
        let away = a.sky_radiance(sun_at(0.0, 30.0));
        assert!(
            luminance(toward) > luminance(away),
            "{toward:?} vs {away:?}"
        );
        // Below the horizon: the horizon's colour.
        let below = a.sky_radiance([0.0, 0.8, -0.6]);
        assert_eq!(below, hor);
    }

    #[test]
    fn the_sky_dims_through_twilight_to_the_night_floor() {
        let noon = Atmosphere::new(sun_at(180.0, 60.0), 40_000.0, 0.22);
        let low = Atmosphere::new(sun_at(270.0, 3.0), 40_000.0, 0.22);
        let civil = Atmosphere::new(sun_at(270.0, -4.0), 40_000.0, 0.22);
        let night = Atmosphere::new(sun_at(270.0, -30.0), 40_000.0, 0.22);
        let l = |a: &Atmosphere| luminance(a.sky_radiance([0.0, 0.0, 1.0]));
        assert!(l(&noon) > l(&low) && l(&low) > l(&civil) && l(&civil) > l(&night));
        let n = night.sky_radiance([0.0, 0.0, 1.0]);
        for c in 0..3 {
            assert!((n[c] - NIGHT_SKY[c]).abs() < 1e-4, "{n:?}");
        }
        assert_eq!(night.day.min(1e-3), night.day);
        // No direct light once the sun has set; ambient down to the night floor.
        assert_eq!(night.sun_colour, [0.0; 3]);
        assert!(night
            .ambient
            .iter()
            .all(|&c| (c - NIGHT_AMBIENT).abs() < 1e-3));
        assert!(noon.ambient.iter().all(|&c| c > 0.15));
    }

    #[test]
    fn the_low_sun_is_red_and_the_high_sun_white() {
        let noon = Atmosphere::new(sun_at(180.0, 90.0), 40_000.0, 0.22).sun_colour;
        for c in noon {
            assert!((c - 1.0).abs() < 1e-4, "{noon:?}");
        }
        let low = Atmosphere::new(sun_at(270.0, 2.0), 40_000.0, 0.22).sun_colour;
        assert!(low[0] > low[1] && low[1] > low[2], "{low:?}");
        assert!(low[2] < 0.1 * low[0], "{low:?}");
        // Hazier air reddens more.
        let hazy = Atmosphere::new(sun_at(270.0, 10.0), 5_000.0, 0.22).sun_colour;
        let clear = Atmosphere::new(sun_at(270.0, 10.0), 100_000.0, 0.22).sun_colour;
        assert!(hazy[2] < clear[2], "{hazy:?} vs {clear:?}");
    }

    #[test]
    fn turbidity_follows_the_visibility_within_the_models_range() {
        assert!((turbidity_for_visibility(1e9) - 2.0).abs() < 1e-3);
        assert!((turbidity_for_visibility(10_000.0) - 6.0).abs() < 1e-12);
        assert_eq!(turbidity_for_visibility(100.0), 10.0);
        assert_eq!(turbidity_for_visibility(0.0), 10.0);
    }

    #[test]
    fn koschmieder_holds_at_sea_level_and_the_air_clears_with_height() {
        let a = Atmosphere::new(sun_at(180.0, 45.0), 20_000.0, 0.22);
        // A level ray at sea level over the visibility keeps 2 % of the contrast.
        let t = a.transmittance(0.0, 0.0, 20_000.0);
        assert!((t - 0.02).abs() < 1e-3, "{t}");
        // Higher up the same distance is clearer; looking down into the haze, less clear.
        assert!(a.transmittance(3000.0, 3000.0, 20_000.0) > 0.5);
        let down = a.transmittance(3000.0, 0.0, 20_000.0);
        let level = a.transmittance(3000.0, 3000.0, 20_000.0);
        assert!(down < level && down > t, "{down} {level} {t}");
        // The closed form against a numerical integral of σ(z) along the ray.
        let (ez, pz, d) = (2500.0f32, 400.0f32, 30_000.0f32);
        let n = 10_000;
        let mut tau = 0.0f64;
        for i in 0..n {
            let z = f64::from(ez) + (f64::from(pz - ez)) * (i as f64 + 0.5) / n as f64;
            tau += f64::from(a.sigma0) * (-z / f64::from(FOG_SCALE_HEIGHT_M)).exp() * f64::from(d)
                / n as f64;
        }
        let want = (-tau).exp() as f32;
        assert!((a.transmittance(ez, pz, d) - want).abs() < 1e-4);
        // Far enough, terrain takes exactly the sky's colour: the horizon blends.
        let dir = [0.0, 1.0, 0.0];
        let far = a.fog([0.3, 0.2, 0.1], dir, 100.0, 100.0, 1.0e7);
        assert_eq!(far, a.sky_radiance(dir));
    }
}
