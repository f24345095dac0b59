#version 450
// Clipmap tiles: one instance per tile, vertices generated from gl_VertexIndex (grid, then the
// skirts under the perimeter, a ring per drawn stride), heights from the level's toroidal
// texture (r = 0) or from the refined-tile pool r, positions relative to the eye with the
// Earth-curvature drop (DESIGN.md "The terrain technique", "Precision", "Earth curvature");
// geographic grids on the WGS84 ellipsoid from each node's relative-to-eye frame, projected
// (UTM) grids there from each node's polynomials (geo_node.glsl; render/geo_instances.rs
// `emulate_vertex` repeats its arithmetic: keep them in step).
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"
#include "geo_node.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };
layout(set = 0, binding = 1, std430) readonly buffer Instances { TileInstance tiles[]; };
layout(set = 0, binding = 2) uniform sampler2DArray clipmap;
layout(set = 0, binding = 3) uniform sampler2DArray pools[6];
// A projected grid's node polynomials, element i for instance i (one zero element otherwise).
layout(set = 0, binding = 8, std430) readonly buffer Polynomials { GeoPolynomial polys[]; };

layout(location = 0) out vec3 v_rel;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out float v_height;
layout(location = 3) flat out uint v_tile;
// The local up and north at the vertex (the ellipsoid normal and the meridian's tangent), world
// axes: the fragment shader's slope, aspect and fog heights are taken against them on a
// geographic grid (terrain.frag FLAG_GEOGRAPHIC); on the flat path world z and y.
layout(location = 4) out vec3 v_up;
layout(location = 5) out vec3 v_north;
// The vertex's level-0 grid coordinates (sample units, column then row from the grid's first
// sample), for textures registered to the grid (normal maps, imagery, land cover).
layout(location = 6) out vec2 v_grid;

// Height at node vertex ij (may be one outside the node, for normals).
float fetch(TileInstance t, ivec2 ij) {
    if (t.refinement == 0u) {
        int T = frame.clipmap.x;
        // Level-L vertex coordinates (arithmetic shift: ij = -1 gives -1); +T keeps the
        // toroidal modulo non-negative. A node is drawn from its own level (step 2^L) or, a
        // quadrant of its ring tile drawn at the tile's resolution (step 2^(L-1)), from the
        // tile's: its even vertices are the tile's samples, its odd ones morphed onto them.
        ivec2 v = (t.origin_sample + ij * int(t.step)) >> int(t.level);
        return texelFetch(clipmap, ivec3((v + T) % T, int(t.level)), 0).r;
    }
    // A pool packs its slots several to a layer when it has more than the device's layers
    // (render/pool_atlas.rs): slot_x, slot_y name the node's south-west texel in the layer, and
    // its slot's cell is the multiple of the slot side at or below it (the node lies inside its
    // slot). Reads are clamped into that cell, as `PoolAtlas::read_texel` does on the CPU.
    int side = (frame.grid_size.z << t.refinement) + 1;
    ivec2 sw = ivec2(t.slot_x, t.slot_y);
    ivec2 cell = (sw / side) * side;
    ivec2 texel = sw + ij * int(t.slot_stride);
    ivec3 c = ivec3(clamp(texel, cell, cell + side - 1), int(t.slot));
    switch (t.refinement) {
        case 1u: return texelFetch(pools[0], c, 0).r;
        case 2u: return texelFetch(pools[1], c, 0).r;
        case 3u: return texelFetch(pools[2], c, 0).r;
        case 4u: return texelFetch(pools[3], c, 0).r;
        case 5u: return texelFetch(pools[4], c, 0).r;
        default: return texelFetch(pools[5], c, 0).r;
    }
}

// CDLOD's geomorph (terrain/src/select/cdlod_morph.rs, whose `morph_k` and `morph_vertex` are
// this arithmetic on the CPU: keep them in step). The morph factor of a vertex `dist` metres
// from the eye in `zone` (start, end); 0 for an empty zone.
float morph_k(vec2 zone, float dist) {
    return zone.y > 0.0 ? clamp((dist - zone.x) / max(zone.y - zone.x, 1e-3), 0.0, 1.0) : 0.0;
}

// Vertex ij slid by k1 onto the next coarser grid — an odd coordinate towards its lower-left
// neighbour, along the row, the column or the quads' south-west → north-east diagonal, its
// height along that edge — and, for a quadrant drawn for its parent (k1 = 1), by k2 onto the
// grid after. Returns the fractional vertex; `h` becomes its height.
vec2 morph_vertex(TileInstance t, ivec2 ij, float k1, float k2, inout float h) {
    ivec2 odd = ij & 1;
    vec2 f = vec2(ij);
    if (k1 > 0.0 && odd != ivec2(0)) {
        h = mix(h, fetch(t, ij - odd), k1);
        f -= vec2(odd) * k1;
    }
    if (k2 > 0.0) {
        ivec2 p = ij - odd;
        ivec2 odd2 = (p >> 1) & 1;
        if (odd2 != ivec2(0)) {
            h = mix(h, fetch(t, p - 2 * odd2), k2);
            f -= 2.0 * vec2(odd2) * k2;
        }
    }
    return f;
}

// Perimeter vertex k of a node of n quads a side: the same walk as
// terrain::mesh::perimeter_vertex (south edge west→east, east, north, west).
ivec2 perimeter_ij(int n, int k) {
    int e = k / n;
    int s = k % n;
    return e == 0 ? ivec2(s, 0) : e == 1 ? ivec2(n, s) : e == 2 ? ivec2(n - s, n) : ivec2(0, n - s);
}

void main() {
    TileInstance t = tiles[gl_InstanceIndex];
    // Every instance is one m×m node; its vertex spacing is `step` samples.
    int n = frame.grid_size.z;
    int side = n + 1;
    int vi = gl_VertexIndex;
    bool skirt = vi >= side * side;
    ivec2 ij;
    // A skirt vertex: perimeter vertex pk of the ring of the stride its mesh is drawn at
    // (terrain::mesh::skirt_vertex: rings for strides 1, 2, 4).
    int pk = 0;
    int skirt_stride = 1;
    if (!skirt) {
        ij = ivec2(vi % side, vi / side);
    } else {
        int r = vi - side * side;
        skirt_stride = 1 << (r / (4 * n));
        pk = r % (4 * n);
        ij = perimeter_ij(n, pk);
    }
    int step = int(t.step);
    // Vertices past the last valid sample collapse onto the first vertex at or past it, so the
    // padding added for the clipmap is never drawn as terrain.
    ivec2 lim = (frame.grid_size.xy - 1 - t.origin_sample + step - 1) / step;
    ij = min(ij, lim);
    float h = fetch(t, ij);
    // A skirt vertex hangs skirt_m below the lowest of its perimeter vertex and that vertex's
    // two neighbours at the drawn stride (terrain::mesh::skirt_bottom), so the skirt's bottom
    // between every other vertex lies below the edge: the neighbours' lower height here, the
    // vertex's own after any morph below.
    float skirt_low = 1e30;
    if (skirt) {
        int p = 4 * n;
        float before = fetch(t, min(perimeter_ij(n, (pk + p - skirt_stride) % p), lim));
        float after = fetch(t, min(perimeter_ij(n, (pk + skirt_stride) % p), lim));
        skirt_low = min(before, after);
    }
    // Heights per sample along the grid's axes, from central differences at the drawn
    // resolution (neighbours outside the node come from the same texture; a pool slot clamps at
    // its edge): the shading normal.
    // One texel of the texture read either side: two vertices for a quadrant read from its
    // ring tile's level (terrain/src/select/seen_quadrants.rs).
    int texel = t.refinement == 0u ? max(1, (1 << int(t.level)) / int(t.step)) : 1;
    ivec2 lo = ij - texel;
    ivec2 hi = ij + texel;
    vec2 dh = vec2(fetch(t, ivec2(hi.x, ij.y)) - fetch(t, ivec2(lo.x, ij.y)),
        fetch(t, ivec2(ij.x, hi.y)) - fetch(t, ivec2(ij.x, lo.y))) / (vec2(hi - lo) * float(step));
    bool geo = t.geo_origin.w != 0.0;
    GeoFields g;
    g.geo_origin = t.geo_origin;
    g.geo_axis_r = t.geo_axis_r;
    g.geo_axis_t = t.geo_axis_t;
    g.geo_axis_z = t.geo_axis_z;
    g.geo_radius = t.geo_radius;
    // Only a projected node reads its polynomials (geo_vertex's branch on geo_radius.w).
    if (t.geo_radius.w != 0.0) {
        g.geo_s = polys[gl_InstanceIndex].geo_s;
        g.geo_n = polys[gl_InstanceIndex].geo_n;
    } else {
        for (int k = 0; k < 9; k++) {
            g.geo_s[k] = vec4(0.0);
            g.geo_n[k] = vec4(0.0);
        }
        g.geo_n[9] = vec4(0.0);
    }
    // CDLOD: the factors from the unmorphed vertex's distance to the eye (the reference's
    // `eyeDist`), then the vertex morphed.
    vec2 f = vec2(ij);
    bool quadrant = t.morph.x < 0.0;
    if (t.morph.y > 0.0 || quadrant) {
        vec3 rel0;
        if (geo) {
            rel0 = geo_vertex(g, vec2((ij - n / 2) * step), h, dh).rel;
        } else {
            vec2 xy0 = t.origin_rel + vec2(ij) * float(step) * frame.grid_spacing.xy;
            rel0 = vec3(xy0, h - frame.grid_spacing.z - frame.grid_spacing.w * dot(xy0, xy0));
        }
        float dist = length(rel0);
        float k1 = quadrant ? 1.0 : morph_k(t.morph.xy, dist);
        float k2 = quadrant ? morph_k(t.morph.zw, dist) : 0.0;
        f = morph_vertex(t, ij, k1, k2, h);
    }
    float h_drawn = skirt ? min(skirt_low, h) - t.skirt_m : h;
    v_grid = vec2(t.origin_sample) + f * float(step);
    v_height = h;
    // The level whose samples (and normal map) the node is drawn from.
    v_tile = (t.refinement == 0u ? t.level : uint(findMSB(t.step))) | (t.refinement << 8);
    if (geo) {
        // On the ellipsoid (geographic or projected): the node's frame plus the vertex's offset.
        GeoVertex gv = geo_vertex(g, (f - vec2(n / 2)) * float(step), h_drawn, dh);
        v_rel = gv.rel;
        v_normal = gv.normal;
        v_up = gv.up;
        v_north = gv.north;
        gl_Position = frame.relative_world_to_clip * vec4(gv.rel, 1.0);
        return;
    }
    vec2 xy = t.origin_rel + f * float(step) * frame.grid_spacing.xy;
    float z = h_drawn - frame.grid_spacing.z - frame.grid_spacing.w * dot(xy, xy);
    vec2 slope = dh / frame.grid_spacing.xy;
    v_rel = vec3(xy, z);
    v_normal = normalize(vec3(-slope.x, -slope.y, 1.0));
    v_up = vec3(0.0, 0.0, 1.0);
    v_north = vec3(0.0, 1.0, 0.0);
    gl_Position = frame.relative_world_to_clip * vec4(xy, z, 1.0);
}
