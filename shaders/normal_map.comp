#version 450
// `--normals gpu`: the normal texels of the level strips uploaded this submission, from the
// level's own heights in the level textures (render/normal_pass.rs records it; the CPU twin is
// render/normal_map.rs `level_normal_texel`: keep the two in step). Per level-L sample the central
// difference of its level-L neighbours, 2^L grid spacings apart, in the grid's east-north-up
// frame (the CPU normal maps' frame); a neighbour outside the level's cache region is not in
// the texture (its texel holds the torus' other side) and is clamped to the region: one-sided
// differences at the region's edge. Two texels per invocation, packed as RG8_SNORM pairs into
// one uint of the output buffer, which is then copied into the normal texture.
#extension GL_GOOGLE_include_directive : require
#include "gpu_types.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform sampler2DArray levels;
layout(set = 0, binding = 1, std430) writeonly buffer Texels { uint texels[]; };
layout(push_constant, std430) uniform Push { NormalPush p; };

// Height of level-L sample s (inside the region): its toroidal texel, from non-negative offsets.
float height(ivec2 s) {
    uvec2 t = (p.texel_lo + uvec2(s - p.region_lo)) % p.side;
    return texelFetch(levels, ivec3(ivec2(t), int(p.layer)), 0).r;
}

vec2 level_normal(ivec2 s) {
    ivec2 lo = max(s - 1, p.region_lo);
    ivec2 hi = min(s + 1, p.region_hi);
    float gx = (height(ivec2(hi.x, s.y)) - height(ivec2(lo.x, s.y)))
        / (float(max(hi.x - lo.x, 1)) * p.spacing.x);
    float gy = (height(ivec2(s.x, hi.y)) - height(ivec2(s.x, lo.y)))
        / (float(max(hi.y - lo.y, 1)) * p.spacing.y);
    float len = sqrt(gx * gx + gy * gy + 1.0);
    return vec2(-gx, -gy) / len;
}

ivec2 sample_of(uint k) {
    return p.origin + ivec2(int(k % p.size.x), int(k / p.size.x));
}

void main() {
    uint count = p.size.x * p.size.y;
    uint k = gl_GlobalInvocationID.x * 2u;
    if (k >= count) return;
    vec4 pair = vec4(level_normal(sample_of(k)), 0.0, 0.0);
    if (k + 1u < count) pair.zw = level_normal(sample_of(k + 1u));
    // round(clamp(v, -1, 1) * 127), x then y of each texel, lowest byte first.
    texels[p.offset + gl_GlobalInvocationID.x] = packSnorm4x8(pair);
}
