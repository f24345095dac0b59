#version 450
// Tessellation baseline (document 001, the domain shader): each generated vertex is placed on
// the level-0 surface — the heights of the full-resolution grid, interpolated over the drawn
// meshes' triangles (south-west to north-east diagonal), so that at a high density the surface
// converges to `--lod full`'s — relative to the eye: with the curvature drop of the flat path,
// or on the WGS84 ellipsoid from its cell's frame as terrain.vert places the tiles
// (geo_node.glsl) — and given the varyings terrain.frag reads (same locations as terrain.vert).
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"
#include "terrain_tess.glsl"
#include "geo_node.glsl"

layout(triangles, fractional_odd_spacing, ccw) in;

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };
// The valid level-0 samples, row-major, grid_size.x per row, south row first.
layout(set = 0, binding = 2, std430) readonly buffer Heights { float heights[]; };
// The drawn cells' frames on the ellipsoid; one zeroed record (geo_origin.w = 0) when flat.
layout(set = 0, binding = 3, std430) readonly buffer Cells { GeoFields cells[]; };

layout(location = 0) in vec2 t_local[];
layout(location = 1) patch in uint t_patch;

layout(location = 0) out vec3 v_rel;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out float v_height;
layout(location = 3) flat out uint v_tile;
layout(location = 4) out vec3 v_up;
layout(location = 5) out vec3 v_north;
layout(location = 6) out vec2 v_grid;

float sample_at(ivec2 s) {
    return heights[s.y * frame.grid_size.x + s.x];
}

// The level-0 surface at grid point g (samples): the triangle of its cell, as the meshes draw it.
float height_at(vec2 g) {
    ivec2 size = frame.grid_size.xy;
    g = clamp(g, vec2(0.0), vec2(size - 1));
    ivec2 c = min(ivec2(floor(g)), size - 2);
    vec2 f = g - vec2(c);
    float h00 = sample_at(c);
    float h11 = sample_at(c + ivec2(1, 1));
    if (f.x >= f.y) {
        float h10 = sample_at(c + ivec2(1, 0));
        return h00 + f.x * (h10 - h00) + f.y * (h11 - h10);
    }
    float h01 = sample_at(c + ivec2(0, 1));
    return h00 + f.y * (h01 - h00) + f.x * (h11 - h01);
}

void main() {
    TessPatchGpu p = patches[t_patch];
    vec3 b = gl_TessCoord;
    vec2 local = b.x * t_local[0] + b.y * t_local[1] + b.z * t_local[2];
    vec2 g = vec2(p.origin_sample) + local;
    float h = height_at(g);
    v_grid = g;
    // Debug tiles: the hue of the patch's inner level's octave.
    v_tile = uint(findMSB(uint(max(gl_TessLevelInner[0], 1.0))));
    v_height = h;
    // Heights per sample from central differences one sample either side, as terrain.vert at
    // full resolution.
    vec2 dh = 0.5 * vec2(height_at(g + vec2(1.0, 0.0)) - height_at(g - vec2(1.0, 0.0)),
        height_at(g + vec2(0.0, 1.0)) - height_at(g - vec2(0.0, 1.0)));
    GeoFields cell = cells[p.geo_cell];
    if (cell.geo_origin.w != 0.0) {
        GeoVertex gv = geo_vertex(cell, local - vec2(p.geo_centre), h, dh);
        v_rel = gv.rel;
        v_normal = gv.normal;
        v_up = gv.up;
        v_north = gv.north;
        gl_Position = frame.relative_world_to_clip * vec4(gv.rel, 1.0);
        return;
    }
    vec2 xy = p.origin_rel + local * frame.grid_spacing.xy;
    float z = h - frame.grid_spacing.z - frame.grid_spacing.w * dot(xy, xy);
    vec2 slope = dh / frame.grid_spacing.xy;
    v_rel = vec3(xy, z);
    v_normal = normalize(vec3(-slope.x, -slope.y, 1.0));
    v_up = vec3(0.0, 0.0, 1.0);
    v_north = vec3(0.0, 1.0, 0.0);
    gl_Position = frame.relative_world_to_clip * vec4(xy, z, 1.0);
}
