#version 450
// Full-resolution tiles: one instance per tile, vertices generated from gl_VertexIndex,
// heights fetched from the R32F texture, positions relative to the eye (DESIGN.md "Precision").
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };
layout(set = 0, binding = 1, std430) readonly buffer Instances { TileInstance tiles[]; };
layout(set = 0, binding = 2) uniform sampler2D heights;

layout(location = 0) out vec3 v_rel;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out float v_height;

float height_at(ivec2 t) {
    return texelFetch(heights, clamp(t, ivec2(0), frame.grid_size.xy - 1), 0).r;
}

void main() {
    TileInstance t = tiles[gl_InstanceIndex];
    int m = frame.grid_size.z + 1;
    ivec2 ij = ivec2(gl_VertexIndex % m, gl_VertexIndex / m);
    int step = int(t.step);
    // Vertices past the grid's last sample collapse onto it (zero-area triangles).
    ivec2 texel = min(t.origin_texel + ij * step, frame.grid_size.xy - 1);
    float h = height_at(texel);
    vec2 d = vec2(texel - t.origin_texel) * frame.grid_spacing.xy;
    vec3 rel = vec3(t.origin_rel + d, h - frame.grid_spacing.z);

    // Normal from central differences of the full-resolution heights (one-sided at the edges).
    ivec2 lo = max(texel - ivec2(step), ivec2(0));
    ivec2 hi = min(texel + ivec2(step), frame.grid_size.xy - 1);
    float dx = float(max(hi.x - lo.x, 1)) * frame.grid_spacing.x;
    float dy = float(max(hi.y - lo.y, 1)) * frame.grid_spacing.y;
    float dhdx = (height_at(ivec2(hi.x, texel.y)) - height_at(ivec2(lo.x, texel.y))) / dx;
    float dhdy = (height_at(ivec2(texel.x, hi.y)) - height_at(ivec2(texel.x, lo.y))) / dy;

    v_rel = rel;
    v_normal = normalize(vec3(-dhdx, -dhdy, 1.0));
    v_height = h;
    gl_Position = frame.relative_world_to_clip * vec4(rel, 1.0);
}
