// The sky and aerial perspective, shared by sky.frag and terrain.frag (include after the
// FrameBlock declaration). The per-frame coefficients come from renderer/src/render/
// atmosphere.rs, whose `Atmosphere::sky_radiance` and `fog` are the CPU twins of these
// functions: Preetham, Shirley & Smits, "A Practical Analytic Model for Daylight" (SIGGRAPH
// 1999), i.e. the Perez distribution F(θ, γ) = (1 + A e^(B/cos θ))(1 + C e^(Dγ) + E cos²γ) for
// Y, x, y scaled by the zenith values; exponential height fog whose in-scattered light is the
// sky's colour in the view direction, so distant terrain fades into the sky behind it.

// The sky on a moonless night, linear (atmosphere.rs NIGHT_SKY).
const vec3 NIGHT_SKY = vec3(0.0015, 0.0022, 0.0045);

// Twilight tints (atmosphere.rs): towards the sun, away from it at the horizon, overhead.
const vec3 TWILIGHT_TOWARD = vec3(1.3, 0.42, 0.12);
const vec3 TWILIGHT_AWAY = vec3(0.8, 0.55, 0.55);
const vec3 TWILIGHT_ZENITH = vec3(0.45, 0.6, 1.25);
// The glow around the sun: strength and angular width (radians).
const float HALO = 0.35;
const float HALO_RAD = 0.06;

// Preetham's model has no sunset colours: towards a low sun the sky turns orange, away from it
// and overhead blue. `v` is the view direction raised to the horizon, `up` its height.
vec3 twilight_tint(vec3 v, float up) {
    vec2 s = frame.sky_sun.xy;
    float sl = length(s);
    float vl = length(v.xy);
    float toward = (sl > 1e-6 && vl > 1e-6) ? 0.5 + 0.5 * dot(v.xy, s) / (sl * vl) : 0.5;
    vec3 warm = mix(TWILIGHT_AWAY, TWILIGHT_TOWARD, toward * toward);
    return mix(warm, TWILIGHT_ZENITH, sqrt(up));
}

// Linear sRGB of the sky towards unit `dir` (world ENU), without the sun disc. Below the
// horizon: the horizon's colour.
vec3 sky_radiance(vec3 dir) {
    float up = max(dir.z, 0.0);
    float cos_theta = max(up, 0.02);
    float hl = max(length(dir.xy), 1e-9);
    vec3 v = vec3(dir.xy * (sqrt(1.0 - up * up) / hl), up);
    float cos_gamma = clamp(dot(v, frame.sky_sun.xyz), -1.0, 1.0);
    float gamma = acos(cos_gamma);
    vec3 f = (1.0 + frame.perez_a.xyz * exp(frame.perez_b.xyz / cos_theta))
           * (1.0 + frame.perez_c.xyz * exp(frame.perez_d.xyz * gamma)
                  + frame.perez_e.xyz * cos_gamma * cos_gamma);
    vec3 yxy = frame.sky_zenith.xyz * f;
    float lum = max(yxy.x, 0.0);
    float y = max(yxy.z, 1e-4);
    vec3 xyz = vec3(yxy.y / y * lum, lum, (1.0 - yxy.y - y) / y * lum);
    // CIE XYZ -> linear sRGB (D65), written row by row.
    vec3 rgb = vec3(dot(vec3(3.2406, -1.5372, -0.4986), xyz),
                    dot(vec3(-0.9689, 1.8758, 0.0415), xyz),
                    dot(vec3(0.0557, -0.2040, 1.0570), xyz));
    // Per channel, so the glare near the sun whitens as it does to an eye.
    vec3 mapped = 1.0 - exp(-max(rgb, vec3(0.0)) * frame.ambient_colour.w);
    vec3 tint = twilight_tint(v, up);
    float halo = exp(-gamma / HALO_RAD) * HALO;
    vec3 sky = mapped * (1.0 + (tint - 1.0) * frame.perez_b.w) + halo * frame.sun_colour.rgb;
    // Scaled, not clipped, into range: an orange stays orange.
    sky /= max(1.0, max(sky.r, max(sky.g, sky.b)));
    return sky * frame.sky_sun.w + NIGHT_SKY;
}

// Transmittance of the air from the eye (height eye_z) to a point `dist` metres away at
// `point_z` (metres above sea level): σ(z) = σ₀ e^(−z/H) integrated along the straight ray.
float fog_transmittance(float eye_z, float point_z, float dist) {
    float hscale = frame.eye_world.w;
    float x = (point_z - eye_z) / hscale;
    float g = abs(x) < 1e-3 ? 1.0 - 0.5 * x : (1.0 - exp(-x)) / x;
    float tau = frame.sky_zenith.w * exp(-eye_z / hscale) * dist * g;
    return exp(-max(tau, 0.0));
}
