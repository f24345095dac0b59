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
    uint step;           // samples between adjacent vertices: 2^(level - refinement)
    uint level;          // clipmap level L (0 = full resolution)
    uint refinement;     // r: drawn with 2^r (m-1) + 1 vertices per side; heights from pool r when r > 0
    uint slot;           // layer of the tile in pool r
    float skirt_m;       // skirt depth below the tile edge, metres
    uint pad0;
    uint pad1;
    uint pad2;
};
