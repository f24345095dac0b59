// Normal maps of the level textures (render/normal_map.rs): per level-L sample the normal of the
// full-resolution surface filtered over the sample's footprint, x and y (east, north) in
// RG8_SNORM with z >= 0 reconstructed, in the level textures' toroidal layout (texel = level-L
// sample mod T). Sampled bilinearly with REPEAT, which is the torus: at any point of a level
// tile the four texels read are the tile's own vertices, all resident with its heights.
// Refined tiles (r >= 1) keep their per-vertex normals: they are drawn finer than any level.
// Needs v_grid, v_tile, v_up, v_north and the frame block declared before it.

layout(set = 0, binding = 4) uniform sampler2DArray normal_maps;

const int FLAG_NORMAL_MAP = 16;

// Whether this fragment is lit with the normal map: on, and a level tile.
bool uses_normal_map(int flags) {
    return (flags & FLAG_NORMAL_MAP) != 0 && (v_tile >> 8) == 0u;
}

// The level's normal at the fragment, local east-north-up (the texel's frame).
vec3 normal_map_local() {
    uint level = v_tile & 255u;
    vec2 u = v_grid / float(1u << level);
    float side = float(frame.clipmap.x);
    vec2 xy = texture(normal_maps, vec3((u + 0.5) / side, float(level))).rg;
    return normalize(vec3(xy, sqrt(max(1.0 - dot(xy, xy), 0.0))));
}

// A local east-north-up normal in world axes: on the flat path the same vector; on the
// ellipsoid along the interpolated local axes (the reverse of terrain.frag's local_normal).
vec3 world_from_local(vec3 l, int flags) {
    if ((flags & FLAG_GEOGRAPHIC) == 0) return l;
    vec3 up = normalize(v_up);
    vec3 north = normalize(v_north - dot(v_north, up) * up);
    vec3 east = cross(north, up);
    return normalize(l.x * east + l.y * north + l.z * up);
}

// The shading normal, world axes: the normal map's on level tiles, else the vertex normal.
vec3 shading_normal(vec3 vertex_normal, int flags) {
    if (!uses_normal_map(flags)) return vertex_normal;
    return world_from_local(normal_map_local(), flags);
}
