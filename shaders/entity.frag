#version 450
// Entity models: the instance's tint, Lambert sun with the terrain's ambient term, and the
// same distance haze as the terrain so far traffic fades like the ground under it.
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(push_constant, std430) uniform Push { EntityPush push; };

layout(location = 0) in vec3 v_rel;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec3 v_tint;
layout(location = 0) out vec4 out_colour;

void main() {
    vec3 n = normalize(v_normal);
    float ambient = push.sun_dir.w;
    // Two-sided: a face seen from behind (open meshes) is lit as its side facing the eye.
    if (dot(n, v_rel) > 0.0) n = -n;
    float lambert = max(dot(n, push.sun_dir.xyz), 0.0);
    vec3 c = v_tint * (ambient + (1.0 - ambient) * lambert);
    float haze = 1.0 - exp(-length(v_rel) / push.sky_colour.w);
    out_colour = vec4(mix(c, push.sky_colour.rgb, 0.6 * haze), 1.0);
}
