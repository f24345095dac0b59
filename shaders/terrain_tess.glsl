// The tessellation baseline's records (render/tess_pass.rs `TessPatchGpu`; document 001): one
// triangle patch of the base mesh and its tessellation factors, computed on the CPU
// (aerie_terrain::select::tessellation). std430, 64 bytes.
struct TessPatchGpu {
    vec2 origin_rel;     // the cell's south-west sample relative to the eye, metres (f64 -> f32; flat path)
    ivec2 origin_sample; // that sample (col, row)
    ivec2 extent;        // samples from it to the cell's north-east corner
    uint north_west;     // 0: corners (SW, SE, NE); 1: corners (SW, NE, NW)
    uint geo_cell;       // the cell's frame in `cells` (terrain_tess.tese)
    vec4 levels;         // gl_TessLevelOuter[0..2], gl_TessLevelInner[0]
    ivec2 geo_centre;    // samples from the south-west sample to that frame's centre
    uvec2 pad;
};

layout(set = 0, binding = 1, std430) readonly buffer Patches { TessPatchGpu patches[]; };
