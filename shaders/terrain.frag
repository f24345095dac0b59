#version 450
// Elevation colour ramp, slope rock, Lambert sun and distance haze.
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };

layout(location = 0) in vec3 v_rel;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in float v_height;
layout(location = 3) flat in uint v_tile;
layout(location = 0) out vec4 out_colour;

vec3 srgb_to_linear(vec3 c) { return pow(c, vec3(2.2)); }

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

void main() {
    vec3 n = normalize(v_normal);
    vec3 base = ramp(v_height);
    // Steep faces show rock, except under snow.
    float steep = smoothstep(0.55, 0.8, 1.0 - n.z);
    if (v_height < 2600.0) base = mix(base, vec3(0.45, 0.42, 0.40), steep);
    if ((frame.grid_size.w & 1) != 0) {
        // Debug tiles (the seed's figure 3): hue by level, brighter with refinement.
        const vec3 hues[8] = vec3[](vec3(0.9, 0.2, 0.2), vec3(0.9, 0.6, 0.1), vec3(0.8, 0.9, 0.1),
                                    vec3(0.2, 0.8, 0.2), vec3(0.1, 0.7, 0.8), vec3(0.2, 0.3, 0.9),
                                    vec3(0.6, 0.2, 0.9), vec3(0.9, 0.3, 0.7));
        uint level = v_tile & 255u;
        uint r = v_tile >> 8;
        base = mix(hues[level % 8u], vec3(1.0), 0.18 * float(r));
    }
    vec3 albedo = srgb_to_linear(base);
    float ambient = frame.sun_dir.w;
    float lambert = max(dot(n, frame.sun_dir.xyz), 0.0);
    vec3 c = albedo * (ambient + (1.0 - ambient) * lambert);
    float haze = 1.0 - exp(-length(v_rel) / frame.sky_colour.w);
    out_colour = vec4(mix(c, frame.sky_colour.rgb, 0.6 * haze), 1.0);
}
