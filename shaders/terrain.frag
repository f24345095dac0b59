#version 450
// Terrain colour. The plain look (flags bit 2 clear): elevation colour ramp, slope rock,
// Lambert sun and distance haze. The full look (bit 2): land cover derived from height, slope
// and aspect with procedural detail (landcover.glsl), the sun's and the sky's colours, water
// that mirrors the sky, and aerial perspective into the Preetham sky (atmosphere.glsl). The
// class view (bit 4): each class's flat colour, unlit, for checking the rules.
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };

#include "atmosphere.glsl"
#include "drape.glsl"
#include "landcover.glsl"

layout(location = 0) in vec3 v_rel;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in float v_height;
layout(location = 3) flat in uint v_tile;
layout(location = 4) in vec3 v_up;
layout(location = 5) in vec3 v_north;
// Level-0 grid coordinates (samples) of the fragment, for grid-registered textures.
layout(location = 6) in vec2 v_grid;
layout(location = 0) out vec4 out_colour;

const int FLAG_DEBUG_TILES = 1;
const int FLAG_FULL_LOOK = 2;
const int FLAG_CLASS_VIEW = 4;
// A geographic grid on the ellipsoid: world z is not "up" away from the world origin.
const int FLAG_GEOGRAPHIC = 8;
// The shading normal as colour (Look::Normals, for checking the normal maps).
const int FLAG_NORMAL_VIEW = 32;

#include "normal_map.glsl"

// The normal in the local east-north-up frame at the fragment: on the flat path the world
// normal itself (bit for bit, so flat goldens stay), on the ellipsoid its components along the
// interpolated local axes (world z tilts by 1° per 111 km from the dataset's corner).
vec3 local_normal(vec3 n, int flags) {
    if ((flags & FLAG_GEOGRAPHIC) == 0) return n;
    vec3 up = normalize(v_up);
    vec3 north = normalize(v_north - dot(v_north, up) * up);
    vec3 east = cross(north, up);
    return vec3(dot(n, east), dot(n, north), dot(n, up));
}

vec3 srgb_to_linear(vec3 c) { return pow(c, vec3(2.2)); }

// The exact sRGB decode (the class view's colours read back as written).
vec3 srgb_decode(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}

// Hypsometric tints (sRGB), metres above sea level.
vec3 ramp(float h) {
    if (h <= 0.0) return vec3(0.16, 0.32, 0.50);
    const float hs[6] = float[](0.0, 400.0, 1000.0, 1700.0, 2400.0, 3000.0);
    const vec3 cs[6] = vec3[](vec3(0.42, 0.56, 0.30), vec3(0.36, 0.52, 0.26), vec3(0.30, 0.44, 0.22),
                              vec3(0.50, 0.45, 0.32), vec3(0.55, 0.52, 0.48), vec3(0.94, 0.95, 0.97));
    for (int i = 1; i < 6; ++i) {
        if (h < hs[i]) return mix(cs[i - 1], cs[i], (h - hs[i - 1]) / (hs[i] - hs[i - 1]));
    }
    return cs[5];
}

// Debug tiles (the seed's figure 3): hue by level, brighter with refinement.
vec3 tile_hue() {
    const vec3 hues[8] = vec3[](vec3(0.9, 0.2, 0.2), vec3(0.9, 0.6, 0.1), vec3(0.8, 0.9, 0.1),
                                vec3(0.2, 0.8, 0.2), vec3(0.1, 0.7, 0.8), vec3(0.2, 0.3, 0.9),
                                vec3(0.6, 0.2, 0.9), vec3(0.9, 0.3, 0.7));
    uint level = v_tile & 255u;
    uint r = v_tile >> 8;
    return mix(hues[level % 8u], vec3(1.0), 0.18 * float(r));
}

void plain_look(vec3 n, int flags, vec4 imagery) {
    vec3 base = ramp(v_height);
    // Steep faces show rock, except under snow.
    float steep = smoothstep(0.55, 0.8, 1.0 - local_normal(n, flags).z);
    if (v_height < 2600.0) base = mix(base, vec3(0.45, 0.42, 0.40), steep);
    if ((flags & FLAG_DEBUG_TILES) != 0) base = tile_hue();
    vec3 albedo = srgb_to_linear(base);
    if ((flags & FLAG_DEBUG_TILES) == 0) albedo = mix(albedo, imagery.rgb, imagery.a);
    float ambient = frame.sun_dir.w;
    float lambert = max(dot(n, frame.sun_dir.xyz), 0.0);
    vec3 c = albedo * (ambient + (1.0 - ambient) * lambert);
    float haze = 1.0 - exp(-length(v_rel) / frame.sky_colour.w);
    out_colour = vec4(mix(c, frame.sky_colour.rgb, 0.6 * haze), 1.0);
}

void main() {
    int flags = frame.grid_size.w;
    vec3 n = shading_normal(normalize(v_normal), flags);
    // Draped imagery (linear, with its coverage), sampled here in uniform control flow.
    vec4 imagery = drape_imagery(v_grid);
    if ((flags & FLAG_NORMAL_VIEW) != 0) {
        float source = uses_normal_map(flags) ? float((v_tile & 255u) + 1u) * 16.0 / 255.0 : 0.0;
        out_colour = vec4(srgb_decode(vec3(local_normal(n, flags).xy * 0.5 + 0.5, source)), 1.0);
        return;
    }
    if ((flags & (FLAG_FULL_LOOK | FLAG_CLASS_VIEW)) == 0) {
        plain_look(n, flags, imagery);
        return;
    }
    // World point for the procedural patterns: x, y modulo the noise period, z the height.
    vec3 p = vec3(v_rel.xy + frame.eye_world.xy, v_height);
    float footprint = max(length(fwidth(v_rel)), 1e-3);
    float w[CLASS_COUNT];
    landcover_weights(v_height, local_normal(n, flags), landcover_jitter(p.xy), w);
    landcover_raster(v_grid, w);
    if ((flags & FLAG_CLASS_VIEW) != 0) {
        vec3 flat_colour = vec3(0.0);
        for (int k = 0; k < CLASS_COUNT; ++k) flat_colour += w[k] * CLASS_ALBEDO[k];
        // Imagery shows through the class view unlit (registration checks read it back).
        out_colour = vec4(mix(srgb_decode(flat_colour), imagery.rgb, imagery.a), 1.0);
        return;
    }
    vec3 base = vec3(0.0);
    for (int k = 0; k < CLASS_COUNT; ++k) {
        if (w[k] > 0.004) base += w[k] * class_albedo(k, p, n, footprint);
    }
    if ((flags & FLAG_DEBUG_TILES) != 0) base = tile_hue();
    vec3 albedo = srgb_to_linear(clamp(base, 0.0, 1.0));
    if ((flags & FLAG_DEBUG_TILES) == 0) albedo = mix(albedo, imagery.rgb, imagery.a);

    float dist = length(v_rel);
    vec3 view = v_rel / max(dist, 1e-3);
    float lambert = max(dot(n, frame.sun_dir.xyz), 0.0);
    vec3 c = albedo * (frame.ambient_colour.rgb + frame.sun_colour.rgb * lambert);
    if (w[WATER] > 0.0) {
        // Water mirrors the sky (Schlick's Fresnel, n = 1.33) and glints in the sun.
        vec3 r = reflect(view, n);
        float cos_i = clamp(-dot(view, n), 0.0, 1.0);
        float fresnel = 0.02 + 0.98 * pow(1.0 - cos_i, 5.0);
        float glint = pow(max(dot(r, frame.sun_dir.xyz), 0.0), 400.0) * 2.0;
        vec3 mirror = mix(c, sky_radiance(r), fresnel) + glint * frame.sun_colour.rgb;
        c = mix(c, mirror, w[WATER]);
    }
    // Aerial perspective: the eye's height comes from the uniforms (on the ellipsoid, its
    // height above it in the data's datum), the point's from the vertex height (metres above
    // sea level, curvature drop excluded).
    float t = fog_transmittance(frame.eye_world.z, v_height, dist);
    out_colour = vec4(mix(sky_radiance(view), c, t), 1.0);
}
