#version 450
// The sky (Preetham, shaders/atmosphere.glsl) and the sun disc, for the pixels the terrain left.
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };

#include "atmosphere.glsl"

layout(location = 0) in vec4 v_ray;
layout(location = 0) out vec4 out_colour;

void main() {
    vec3 dir = normalize(v_ray.xyz / v_ray.w);
    vec3 c = sky_radiance(dir);
    // The disc: the direct sun's colour, bright enough to saturate, soft over its last tenth
    // of radius; only above the horizon (below it the Earth hides the sun).
    float cos_r = frame.sun_colour.w;
    float cd = dot(dir, frame.sun_dir.xyz);
    float disc = smoothstep(cos_r - 0.1 * (1.0 - cos_r), cos_r, cd) * step(0.0, dir.z);
    c += disc * frame.sun_colour.rgb * 4.0;
    out_colour = vec4(c, 1.0);
}
