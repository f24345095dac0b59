#version 450
// One triangle over the whole viewport at depth 0 (reversed-Z: infinitely far), drawn after the
// terrain with an EQUAL depth test so it only fills the pixels no terrain covered. Passes the
// homogeneous eye-relative point under each pixel on the near plane (clip z = 1): linear in
// screen space, so the fragment stage's divide gives the exact view ray of its pixel.
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };

layout(location = 0) out vec4 v_ray;

void main() {
    vec2 ndc = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    v_ray = inverse(frame.relative_world_to_clip) * vec4(ndc, 1.0, 1.0);
    gl_Position = vec4(ndc, 0.0, 1.0);
}
