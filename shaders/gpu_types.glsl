// GPU structs shared with Rust (renderer/src/gpu.rs). The Rust layout test parses this file:
// keep one field per line, `type name;`, inside `struct Name { ... };`.

// std140 uniform block, one per frame.
struct FrameUniforms {
    mat4 relative_world_to_clip; // camera-relative world (metres) -> clip; reversed-Z infinite
    vec4 sun_dir;                // xyz: unit vector towards the sun (world ENU); w: ambient term
    vec4 sky_colour;             // rgb: linear sky/haze colour; w: haze distance scale (m)
    vec4 grid_spacing;           // x: spacing E-W (m); y: spacing N-S (m); z: eye height (m); w: unused
    ivec4 grid_size;             // x: samples E-W; y: samples N-S; z: quads per tile side (m-1); w: flags
};

// std430, one per drawn tile instance.
struct TileInstance {
    vec2 origin_rel;   // tile's south-west vertex relative to the eye, metres (f64 on CPU -> f32)
    ivec2 origin_texel; // texel (col, row) of that vertex in the height texture
    float step;        // samples between adjacent vertices (2^level)
    uint level;        // clipmap level (0 = full resolution)
    uint refinement;   // refinement r (0 = none)
    uint pad0;
};
