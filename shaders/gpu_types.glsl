// GPU structs shared with Rust (renderer/src/gpu.rs). The Rust layout test parses this file:
// keep one field per line, `type name;`, inside `struct Name { ... };`.

// std140 uniform block, one per frame.
struct FrameUniforms {
    mat4 relative_world_to_clip; // camera-relative world (metres) -> clip; reversed-Z infinite
    vec4 sun_dir;                // xyz: unit vector towards the sun (world ENU); w: ambient term
    vec4 sky_colour;             // rgb: linear sky/haze colour; w: haze distance scale (m)
    vec4 grid_spacing;           // x: spacing E-W (m); y: spacing N-S (m); z: eye height (m); w: curvature 1/(2R) or 0
    ivec4 grid_size;             // x, y: valid samples E-W, N-S; z: quads per tile side (m-1); w: flags (1 = debug tiles)
    ivec4 clipmap;               // x: level texture side (texels); y: level count; z, w: unused
};

// std430, one per drawn tile instance.
struct TileInstance {
    vec2 origin_rel;     // tile's south-west vertex relative to the eye, metres (f64 on CPU -> f32)
    ivec2 origin_sample; // dataset sample (col, row) of that vertex
    uint step;           // samples between adjacent vertices: 2^(node level)
    uint level;          // clipmap level L of the ring tile (texture layer when refinement = 0)
    uint refinement;     // r: heights from pool r (the ring tile at level L - r) when r > 0
    uint slot;           // layer of the ring tile in pool r
    float skirt_m;       // skirt depth below the tile edge, metres
    uint slot_x;         // pool texel of this node's south-west vertex (r > 0)
    uint slot_y;
    uint slot_stride;    // pool texels between adjacent vertices: 2^(node level - (L - r))
};
