// Rasters draped on the terrain (renderer/src/render/drape_textures.rs): imagery (RGBA8 sRGB,
// mipmapped: the sampler returns linear light) and land-cover classes (R8_UINT, 255 = none),
// registered to the terrain's grid so that they cover its cells: the grid position `g`
// (level-0 samples, v_grid) is at uv = (g + 0.5) / grid size, whatever the texture's size.
// The imagery texture spans frame.clipmap.zw level-0 samples (`DrapedRasters::imagery_span`):
// the grid for a raster draped here; for level L of a store's layer at k texels per sample
// (texel t centred at g = (t + 0.5)·2^L/k − 0.5) its texels · 2^L/k, a little more than the
// grid at coarse levels.
// Without rasters both are 1×1 placeholders (transparent, no class).
// Over that texture, the finer levels of a store's imagery layer may be streamed in windows
// around the eye (render/imagery_stream.rs): binding 7 holds level L's window, side² texels,
// in layer L, toroidally (absolute texel t at t mod side: the sampler repeats), and
// frame.imagery_regions[L] says where the window starts and whether it is complete.

layout(set = 0, binding = 5) uniform sampler2D drape_imagery_tex;
layout(set = 0, binding = 6) uniform usampler2D drape_classes_tex;
layout(set = 0, binding = 7) uniform sampler2DArray drape_stream_tex;

const uint DRAPE_NO_CLASS = 255u;

vec2 drape_uv(vec2 grid) { return (grid + 0.5) / vec2(frame.grid_size.xy); }

vec2 drape_imagery_uv(vec2 grid) { return (grid + 0.5) / vec2(frame.clipmap.zw); }

// Streamed level `level`'s colour at grid position `grid`, when its window is complete and
// holds the bilinear footprint of the point; `margin`: texels from the point to the window's
// nearest edge. Level L's texel t is centred at g = (t + 0.5)·2^L/k − 0.5.
bool drape_stream_sample(int level, vec2 grid, out vec4 colour, out float margin) {
    colour = vec4(0.0);
    margin = -1.0;
    ivec4 r = frame.imagery_regions[level];
    if (r.z == 0) return false;
    float side = float(frame.imagery_stream.z);
    vec2 t = (grid + 0.5) * float(frame.imagery_stream.y) / float(1 << level) - 0.5;
    vec2 rel = t - vec2(r.xy);
    margin = min(min(rel.x, rel.y), min(side - 1.0 - rel.x, side - 1.0 - rel.y));
    if (margin < 0.0) return false;
    colour = textureLod(drape_stream_tex, vec3((t + 0.5) / side, float(level)), 0.0);
    return true;
}

// Linear RGB and coverage of the imagery at grid position `grid`; call in uniform control
// flow (it takes the grid's screen derivatives). The streamed level whose texel is about a
// pixel is drawn where its window holds the point, blended towards the next coarser one as
// the footprint grows and over the window's outer eighth (no seam where a window ends);
// elsewhere, and beyond the finest complete window, the whole texture with its mips.
vec4 drape_imagery(vec2 grid) {
    vec2 dx = dFdx(grid), dy = dFdy(grid);
    vec2 span = vec2(frame.clipmap.zw);
    vec4 base = textureGrad(drape_imagery_tex, drape_imagery_uv(grid), dx / span, dy / span);
    int n = frame.imagery_stream.x;
    if (n == 0) return base;
    // Level-0 texels per pixel; level L's texels are 2^L times as wide.
    float footprint = max(length(dx), length(dy)) * float(frame.imagery_stream.y);
    float lod = log2(max(footprint, 1e-6));
    float fade = 0.125 * float(frame.imagery_stream.z);
    for (int level = clamp(int(floor(lod)), 0, n); level < n; ++level) {
        vec4 fine;
        float margin;
        if (!drape_stream_sample(level, grid, fine, margin)) continue;
        float w = min(clamp(margin / fade, 0.0, 1.0), clamp(float(level) + 1.0 - lod, 0.0, 1.0));
        if (w >= 1.0) return fine;
        vec4 coarse = base;
        vec4 c;
        float m;
        if (level + 1 < n && drape_stream_sample(level + 1, grid, c, m)) coarse = c;
        return mix(coarse, fine, w);
    }
    return base;
}

// The class at texel `t` of the class texture, or DRAPE_NO_CLASS outside it.
uint drape_class_texel(ivec2 t) {
    ivec2 size = textureSize(drape_classes_tex, 0);
    if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, size))) return DRAPE_NO_CLASS;
    return texelFetch(drape_classes_tex, t, 0).r;
}
