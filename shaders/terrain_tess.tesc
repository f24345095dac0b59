#version 450
// Tessellation baseline (document 001, the hull shader): the control points pass through; the
// patch's factors come from its record, computed on the CPU so that the bench counts exactly
// the triangles drawn and neighbours share every edge's factor.
#extension GL_GOOGLE_include_directive : require
#include "terrain_tess.glsl"

layout(vertices = 3) out;
layout(location = 0) in vec2 c_local[];
layout(location = 1) in uint c_patch[];
layout(location = 0) out vec2 t_local[];
layout(location = 1) patch out uint t_patch;

void main() {
    t_local[gl_InvocationID] = c_local[gl_InvocationID];
    if (gl_InvocationID == 0) {
        vec4 l = patches[c_patch[0]].levels;
        gl_TessLevelOuter[0] = l.x;
        gl_TessLevelOuter[1] = l.y;
        gl_TessLevelOuter[2] = l.z;
        gl_TessLevelInner[0] = l.w;
        t_patch = c_patch[0];
    }
}
