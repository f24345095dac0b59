// Rasters draped on the terrain (renderer/src/render/drape_textures.rs): imagery (RGBA8 sRGB,
// mipmapped: the sampler returns linear light) and land-cover classes (R8_UINT, 255 = none),
// registered to the terrain's grid so that they cover its cells: the grid position `g`
// (level-0 samples, v_grid) is at uv = (g + 0.5) / grid size, whatever the texture's size.
// The imagery texture spans frame.clipmap.zw level-0 samples (`DrapedRasters::imagery_span`):
// the grid for a raster draped here; for level L of a store's layer at k texels per sample
// (texel t centred at g = (t + 0.5)·2^L/k − 0.5) its texels · 2^L/k, a little more than the
// grid at coarse levels.
// Without rasters both are 1×1 placeholders (transparent, no class).

layout(set = 0, binding = 5) uniform sampler2D drape_imagery_tex;
layout(set = 0, binding = 6) uniform usampler2D drape_classes_tex;

const uint DRAPE_NO_CLASS = 255u;

vec2 drape_uv(vec2 grid) { return (grid + 0.5) / vec2(frame.grid_size.xy); }

vec2 drape_imagery_uv(vec2 grid) { return (grid + 0.5) / vec2(frame.clipmap.zw); }

// Linear RGB and coverage of the imagery at grid position `grid`.
vec4 drape_imagery(vec2 grid) { return texture(drape_imagery_tex, drape_imagery_uv(grid)); }

// The class at texel `t` of the class texture, or DRAPE_NO_CLASS outside it.
uint drape_class_texel(ivec2 t) {
    ivec2 size = textureSize(drape_classes_tex, 0);
    if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, size))) return DRAPE_NO_CLASS;
    return texelFetch(drape_classes_tex, t, 0).r;
}
