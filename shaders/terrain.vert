#version 450
// Clipmap tiles: one instance per tile, vertices generated from gl_VertexIndex (grid, then the
// skirt under the perimeter), heights from the level's toroidal texture (r = 0) or from the
// refined-tile pool r, positions relative to the eye with the Earth-curvature drop
// (DESIGN.md "The terrain technique", "Precision", "Earth curvature"); geographic grids on the
// WGS84 ellipsoid from each node's relative-to-eye frame, projected (UTM) grids there from each
// node's polynomials (render/geo_instances.rs, whose `emulate_vertex` repeats the arithmetic of
// `ellipsoid_offset` and `projected_offset` below: keep them in step).
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameUniforms frame; };
layout(set = 0, binding = 1, std430) readonly buffer Instances { TileInstance tiles[]; };
layout(set = 0, binding = 2) uniform sampler2DArray clipmap;
layout(set = 0, binding = 3) uniform sampler2DArray pools[6];

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
        // Level-L vertex coordinates; +T keeps the toroidal modulo non-negative at ij = -1.
        ivec2 v = (t.origin_sample >> int(t.level)) + ij;
        return texelFetch(clipmap, ivec3((v + T) % T, int(t.level)), 0).r;
    }
    int side = (frame.grid_size.z << t.refinement) + 1;
    ivec2 texel = ivec2(t.slot_x, t.slot_y) + ij * int(t.slot_stride);
    ivec3 c = ivec3(clamp(texel, ivec2(0), ivec2(side - 1)), int(t.slot));
    switch (t.refinement) {
        case 1u: return texelFetch(pools[0], c, 0).r;
        case 2u: return texelFetch(pools[1], c, 0).r;
        case 3u: return texelFetch(pools[2], c, 0).r;
        case 4u: return texelFetch(pools[3], c, 0).r;
        case 5u: return texelFetch(pools[4], c, 0).r;
        default: return texelFetch(pools[5], c, 0).r;
    }
}

const float WGS84_A = 6378137.0;
const float WGS84_E2 = 0.00669438;

// sin x and 1 - cos x by their series: the GPU's sin/cos may err by 2^-11, kilometres at the
// Earth's radius, while the angles inside a node are small.
void sincos_small(float x, out float s, out float omc) {
    float x2 = x * x;
    s = x * (1.0 - x2 * (1.0 / 6.0 - x2 * (1.0 / 120.0 - x2 * (1.0 / 5040.0
        - x2 * (1.0 / 362880.0 - x2 * (1.0 / 39916800.0))))));
    omc = x2 * (0.5 - x2 * (1.0 / 24.0 - x2 * (1.0 / 720.0 - x2 * (1.0 / 40320.0
        - x2 * (1.0 / 3628800.0)))));
}

// Position relative to the node's centre vertex in its meridian frame (radial, east, polar)
// of the sample `d` samples (E, N) from it at height h, and the local east/north/up there.
// Every term is a product of factors known to f32 precision, none a difference of two large
// numbers: cos(p) - cos(p0) = -2 sin(p0 + dp/2) sin(dp/2), W^2 - W0^2 = -e2 (sin p - sin p0)
// (sin p + sin p0), 1/W - 1/W0 = (W0^2 - W^2) / (W W0 (W + W0)).
vec3 ellipsoid_offset(TileInstance t, vec2 d, float h, out mat3 enu, out float east_m) {
    float dphi = d.y * t.geo_origin.w;
    float dlam = d.x * t.geo_radius.x;
    float sp0 = t.geo_axis_r.w;
    float cp0 = t.geo_axis_t.w;
    float w0 = t.geo_axis_z.w;
    float sh, omch, sd, omcd, sl, omcl;
    sincos_small(0.5 * dphi, sh, omch);
    sincos_small(dphi, sd, omcd);
    sincos_small(dlam, sl, omcl);
    float ch = 1.0 - omch;
    float cd = 1.0 - omcd;
    float sinp = sp0 * cd + cp0 * sd;
    float cosp = cp0 * cd - sp0 * sd;
    float sm = sp0 * ch + cp0 * sh;
    float cm = cp0 * ch - sp0 * sh;
    float dcos = -2.0 * sm * sh;
    float dsin = 2.0 * cm * sh;
    float dw2 = -WGS84_E2 * dsin * (sinp + sp0);
    float w = sqrt(w0 * w0 + dw2);
    float dinv = -dw2 / (w * w0 * (w + w0));
    float dr = WGS84_A * (dcos / w + cp0 * dinv) + h * cosp;
    float dz = (WGS84_A * (1.0 - WGS84_E2)) * (dsin / w + sp0 * dinv) + h * sinp;
    // r = r0_hi + r0_lo + dr; x = r cos(dlam) - r0, y = r sin(dlam).
    float rs = t.geo_radius.z + dr;
    float x = dr - (t.geo_radius.y * omcl + rs * omcl);
    float y = t.geo_radius.y * sl + rs * sl;
    float cl = 1.0 - omcl;
    enu = mat3(vec3(-sl, cl, 0.0), vec3(-sinp * cl, -sinp * sl, cosp), vec3(cosp * cl, cosp * sl, sinp));
    east_m = (t.geo_radius.y + rs) * t.geo_radius.x;
    return vec3(x, y, dz);
}

// A projected (UTM) node's vertex at (u, v), height h: its offset from the node's centre (world
// axes) from the cubic polynomials S and N (gpu_types.glsl), the unit normal there, and S's
// derivatives in u and v (for the shading normal).
vec3 projected_offset(TileInstance t, vec2 uv, float h, out vec3 up, out vec3 su, out vec3 sv) {
    float u = uv.x;
    float v = uv.y;
    float b[9] = float[9](u, v, u * u, u * v, v * v, u * u * u, u * u * v, u * v * v, v * v * v);
    float bu[9] = float[9](1.0, 0.0, 2.0 * u, v, 0.0, 3.0 * u * u, 2.0 * u * v, v * v, 0.0);
    float bv[9] = float[9](0.0, 1.0, 0.0, u, 2.0 * v, 0.0, u * u, 2.0 * u * v, 3.0 * v * v);
    vec3 s = vec3(0.0);
    vec3 nrm = t.geo_n[0].xyz;
    su = vec3(0.0);
    sv = vec3(0.0);
    for (int k = 0; k < 9; k++) {
        s += t.geo_s[k].xyz * b[k];
        nrm += t.geo_n[k + 1].xyz * b[k];
        su += t.geo_s[k].xyz * bu[k];
        sv += t.geo_s[k].xyz * bv[k];
    }
    up = normalize(nrm);
    return s + nrm * h;
}

void main() {
    TileInstance t = tiles[gl_InstanceIndex];
    // Every instance is one m×m node; its vertex spacing is `step` samples.
    int n = frame.grid_size.z;
    int side = n + 1;
    int vi = gl_VertexIndex;
    bool skirt = vi >= side * side;
    ivec2 ij;
    if (!skirt) {
        ij = ivec2(vi % side, vi / side);
    } else {
        // Same perimeter walk as terrain::mesh::perimeter_vertex.
        int k = vi - side * side;
        int e = k / n;
        int s = k % n;
        ij = e == 0 ? ivec2(s, 0) : e == 1 ? ivec2(n, s) : e == 2 ? ivec2(n - s, n) : ivec2(0, n - s);
    }
    int step = int(t.step);
    // Vertices past the last valid sample collapse onto the first vertex at or past it, so the
    // padding added for the clipmap is never drawn as terrain.
    ivec2 lim = (frame.grid_size.xy - 1 - t.origin_sample + step - 1) / step;
    ij = min(ij, lim);
    float h = fetch(t, ij);
    v_grid = vec2(t.origin_sample + ij * step);
    ivec2 lo = ij - 1;
    ivec2 hi = ij + 1;
    if (t.geo_radius.w != 0.0) {
        // A projected grid on the ellipsoid: the node's centre plus its polynomial offset.
        vec3 up, su, sv;
        vec2 uv = vec2((ij - n / 2) * step) * t.geo_origin.w;
        vec3 rel = t.geo_origin.xyz + projected_offset(t, uv, skirt ? h - t.skirt_m : h, up, su, sv);
        // Tangents per sample along the grid's axes, heights from central differences.
        vec2 span = vec2(hi - lo) * float(step);
        float gx = (fetch(t, ivec2(hi.x, ij.y)) - fetch(t, ivec2(lo.x, ij.y))) / span.x;
        float gy = (fetch(t, ivec2(ij.x, hi.y)) - fetch(t, ivec2(ij.x, lo.y))) / span.y;
        vec3 tx = su * t.geo_origin.w + up * gx;
        vec3 ty = sv * t.geo_origin.w + up * gy;
        vec3 north0 = vec3(t.geo_s[0].w, t.geo_s[1].w, t.geo_s[2].w);
        v_rel = rel;
        v_normal = normalize(cross(tx, ty));
        v_height = h;
        v_up = up;
        v_north = normalize(north0 - dot(north0, up) * up);
        v_tile = uint(findMSB(t.step)) | (t.refinement << 8);
        gl_Position = frame.relative_world_to_clip * vec4(rel, 1.0);
        return;
    }
    if (t.geo_origin.w != 0.0) {
        // On the ellipsoid: the node's frame plus the vertex's offset from its centre.
        mat3 enu;
        float east_m;
        vec2 d = vec2((ij - n / 2) * step);
        vec3 off = ellipsoid_offset(t, d, skirt ? h - t.skirt_m : h, enu, east_m);
        mat3 axes = mat3(t.geo_axis_r.xyz, t.geo_axis_t.xyz, t.geo_axis_z.xyz);
        vec3 rel = t.geo_origin.xyz + axes * off;
        float north_m = WGS84_A * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * enu[2].z * enu[2].z)
            / sqrt(1.0 - WGS84_E2 * enu[2].z * enu[2].z) * t.geo_origin.w;
        vec2 gspan = vec2(hi - lo) * float(step) * vec2(east_m, north_m);
        float gx = (fetch(t, ivec2(hi.x, ij.y)) - fetch(t, ivec2(lo.x, ij.y))) / gspan.x;
        float gy = (fetch(t, ivec2(ij.x, hi.y)) - fetch(t, ivec2(ij.x, lo.y))) / gspan.y;
        v_rel = rel;
        v_normal = axes * normalize(enu * vec3(-gx, -gy, 1.0));
        v_height = h;
        v_up = axes * enu[2];
        v_north = axes * enu[1];
        v_tile = uint(findMSB(t.step)) | (t.refinement << 8);
        gl_Position = frame.relative_world_to_clip * vec4(rel, 1.0);
        return;
    }
    vec2 xy = t.origin_rel + vec2(ij) * float(step) * frame.grid_spacing.xy;
    float z = h - frame.grid_spacing.z - frame.grid_spacing.w * dot(xy, xy);
    if (skirt) z -= t.skirt_m;

    // Normal from central differences at the drawn resolution (neighbours outside the node
    // come from the same texture; a pool slot clamps at its edge).
    vec2 span = vec2(hi - lo) * float(step) * frame.grid_spacing.xy;
    float dhdx = (fetch(t, ivec2(hi.x, ij.y)) - fetch(t, ivec2(lo.x, ij.y))) / span.x;
    float dhdy = (fetch(t, ivec2(ij.x, hi.y)) - fetch(t, ivec2(ij.x, lo.y))) / span.y;

    v_rel = vec3(xy, z);
    v_normal = normalize(vec3(-dhdx, -dhdy, 1.0));
    v_height = h;
    v_up = vec3(0.0, 0.0, 1.0);
    v_north = vec3(0.0, 1.0, 0.0);
    v_tile = uint(findMSB(t.step)) | (t.refinement << 8);
    gl_Position = frame.relative_world_to_clip * vec4(xy, z, 1.0);
}
