#version 450
// Tessellation baseline (document 001): three control points per patch, generated from
// gl_VertexIndex and the patch records; the control and evaluation shaders do the rest.
#extension GL_GOOGLE_include_directive : require
#include "terrain_tess.glsl"

// The corner, in samples from the cell's south-west sample.
layout(location = 0) out vec2 c_local;
// The patch's record (the draws come in chunks: gl_PrimitiveID restarts with each).
layout(location = 1) out uint c_patch;

void main() {
    TessPatchGpu p = patches[gl_VertexIndex / 3];
    int k = gl_VertexIndex % 3;
    vec2 ne = vec2(p.extent);
    vec2 second = p.north_west == 0u ? vec2(ne.x, 0.0) : ne;
    vec2 third = p.north_west == 0u ? ne : vec2(0.0, ne.y);
    c_patch = uint(gl_VertexIndex / 3);
    c_local = k == 0 ? vec2(0.0) : k == 1 ? second : third;
}
