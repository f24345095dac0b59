// GPU structs shared with Rust (renderer/src/gpu.rs). The Rust layout test parses this file:
// keep one field per line, `type name;`, inside `struct Name { ... };`.

// std140 uniform block, one per frame.
struct FrameUniforms {
    mat4 relative_world_to_clip; // camera-relative world (metres) -> clip; reversed-Z infinite
    vec4 sun_dir;                // xyz: unit vector towards the sun (world ENU); w: ambient term
    vec4 sky_colour;             // rgb: linear sky/haze colour; w: haze distance scale (m)
    vec4 grid_spacing;           // x: spacing E-W (m); y: spacing N-S (m); z: eye height (m); w: curvature 1/(2R) or 0
    ivec4 grid_size;             // x, y: valid samples E-W, N-S; z: quads per tile side (m-1); w: flags (1 debug tiles, 2 full look, 4 class view, 8 geographic)
    ivec4 clipmap;               // x: level texture side (texels); y: level count; z, w: level-0 samples the imagery texture spans (E-W, N-S)
    // The look (render/atmosphere.rs, render/uniforms.rs): sky, sun, fog, noise anchor.
    vec4 eye_world;              // xy: eye E, N modulo the noise period (m); z: eye height above sea level (m; on the ellipsoid, above it in the data's datum); w: fog scale height (m)
    vec4 sun_colour;             // rgb: direct sunlight, linear (1 = overhead, clear air); w: cos of the sun disc radius
    vec4 ambient_colour;         // rgb: sky light on the ground, linear; w: sky exposure
    vec4 sky_sun;                // xyz: the sun the sky model sees (elevation >= 0); w: day factor (1 day, 0 night)
    vec4 perez_a;                // Perez coefficient A for (Y, x, y); w: turbidity
    vec4 perez_b;                // B; w: twilight tint strength (0 sun above 10 deg, 1 at the horizon)
    vec4 perez_c;                // C
    vec4 perez_d;                // D
    vec4 perez_e;                // E
    vec4 sky_zenith;             // xyz: zenith (Y, x, y) / F(0, sun zenith angle); w: fog extinction at sea level (1/m)
    // The streamed imagery windows (render/imagery_stream.rs, shaders/drape.glsl).
    ivec4 imagery_stream;        // x: streamed levels (0 none); y: texels per level sample k; z: window side (texels)
    ivec4 imagery_regions[12];   // per level (IMAGERY_STREAM_LEVELS): xy its window's first texel (absolute), z 1 when complete
};

// std430: a node's place on the WGS84 ellipsoid (render/geo_instances.rs `GeoEye::node_fields`,
// read by geo_node.glsl): TileInstance's tail and then GeoPolynomial's fields, in the same order;
// one per base-mesh cell of the tessellation baseline (terrain_tess.tese). All zero on the flat
// path.
struct GeoFields {
    vec4 geo_origin;
    vec4 geo_axis_r;
    vec4 geo_axis_t;
    vec4 geo_axis_z;
    vec4 geo_radius;
    vec4 geo_s[9];
    vec4 geo_n[10];
};

// std430, one per drawn tile instance.
struct TileInstance {
    vec2 origin_rel;     // tile's south-west vertex relative to the eye, metres (f64 on CPU -> f32)
    ivec2 origin_sample; // dataset sample (col, row) of that vertex
    uint step;           // samples between adjacent vertices: 2^(node level)
    uint level;          // clipmap level L of the ring tile (texture layer when refinement = 0)
    uint refinement;     // r: heights from pool r (the ring tile at level L - r) when r > 0
    uint slot;           // layer of the ring tile's slot in pool r
    float skirt_m;       // skirt depth below the tile edge, metres
    uint slot_x;         // texel of this node's south-west vertex in that layer (its slot's cell + its place in the slot; r > 0)
    uint slot_y;
    uint slot_stride;    // pool texels between adjacent vertices: 2^(node level - (L - r))
    // CDLOD's geomorph (terrain/src/select/cdlod_morph.rs `Morph::to_gpu`); all zero in other modes.
    vec4 morph;          // xy: the node's zone (start, end), metres from the eye, y = 0 none; x = -1: a quadrant drawn for its parent (fully morphed), zw its parent's zone
    // Geographic grids on the WGS84 ellipsoid (render/geo_instances.rs); all zero on the flat path.
    vec4 geo_origin;     // xyz: node's centre vertex at h = 0 relative to the eye, world metres (f64 -> f32); w: latitude step per sample (rad), or on a projected grid samples -> u; 0 = flat
    vec4 geo_axis_r;     // xyz: world axis of the centre's meridian frame pointing away from the polar axis; w: sin(lat0)
    vec4 geo_axis_t;     // xyz: world axis of that frame pointing east; w: cos(lat0)
    vec4 geo_axis_z;     // xyz: world axis of that frame along the polar axis; w: W0 = sqrt(1 - e2 sin2(lat0))
    vec4 geo_radius;     // x: longitude step per sample (rad); y, z: N(lat0) cos(lat0) as f32 hi + lo; w: 1 = projected grid (GeoPolynomial), 0 = geographic
};

// std430, a projected (UTM) node's polynomials (geodesy/projected.rs NodePolynomial), element i
// for tile instance i, in a buffer of their own written only for projected grids (the tiles of
// other grids leave 304 bytes each unstaged): a vertex at (u, v) = offset from the centre in
// samples times geo_origin.w, height h, is drawn at geo_origin.xyz + S(u, v) + h N(u, v), S and N
// cubic in (u, v) on the basis [u, v, uu, uv, vv, uuu, uuv, uvv, vvv].
struct GeoPolynomial {
    vec4 geo_s[9];       // xyz: S's coefficients, world axes, metres; w of [0..2]: the centre's north (world axes)
    vec4 geo_n[10];      // xyz: N's constant term, then its coefficients; w: unused
};

// Entity models (render/models.rs): one vertex of a model, in the model's body axes
// (x forward, y right, z down), metres. Read as vertex attributes 0 and 1.
struct EntityVertex {
    vec4 position;       // xyz: metres; w: 1
    vec4 normal;         // xyz: unit normal; w: 0
};

// One drawn entity (render/entity_pass.rs), read as per-instance vertex attributes 2..5.
struct EntityInstance {
    vec4 offset_scale;   // xyz: model origin relative to the eye, metres (f64 on CPU -> f32); w: scale
    vec4 axis_x;         // xyz: body x (forward) in world ENU; w: tint red (linear)
    vec4 axis_y;         // xyz: body y (right) in world ENU; w: tint green
    vec4 axis_z;         // xyz: body z (down) in world ENU; w: tint blue
};

// Push constants of the entity pipeline.
struct EntityPush {
    mat4 relative_world_to_clip; // as FrameUniforms
    vec4 sun_dir;                // as FrameUniforms
    vec4 sky_colour;             // as FrameUniforms
};

// Push constants of the GPU normal pass (shaders/normal_map.comp, render/normal_pass.rs): one
// job, `size` texels of level `layer` from level-L sample `origin` (texel = sample mod side),
// its neighbours read within the level's cache region [region_lo, region_hi].
struct NormalPush {
    ivec2 origin;        // level-L sample of the job's first texel
    uvec2 size;          // texels, row-major in the output
    ivec2 region_lo;     // the level's cache region, level-L samples, first
    ivec2 region_hi;     // and last
    uvec2 texel_lo;      // texel of region_lo (region_lo mod side, taken on the CPU)
    vec2 spacing;        // metres between level-L samples, east and north
    uint layer;          // level
    uint side;           // texels per level-texture side
    uint offset;         // first uint of the job's packed texels in the output buffer
    uint pad;
};
