#version 450
// Entity models (issue 18): one instance per drawn entity, the model's body-axis vertices
// turned into world ENU by the instance's axes and placed relative to the eye (the offset is
// computed in f64 on the CPU and rounded to f32, as the terrain's tile origins are).
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(push_constant, std430) uniform Push { EntityPush push; };

layout(location = 0) in vec4 a_position;
layout(location = 1) in vec4 a_normal;
layout(location = 2) in vec4 i_offset_scale;
layout(location = 3) in vec4 i_axis_x;
layout(location = 4) in vec4 i_axis_y;
layout(location = 5) in vec4 i_axis_z;

layout(location = 0) out vec3 v_rel;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec3 v_tint;

void main() {
    mat3 body_to_world = mat3(i_axis_x.xyz, i_axis_y.xyz, i_axis_z.xyz);
    vec3 rel = i_offset_scale.xyz + body_to_world * (a_position.xyz * i_offset_scale.w);
    v_rel = rel;
    v_normal = body_to_world * a_normal.xyz;
    v_tint = vec3(i_axis_x.w, i_axis_y.w, i_axis_z.w);
    gl_Position = push.relative_world_to_clip * vec4(rel, 1.0);
}
