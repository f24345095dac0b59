// Land cover derived from the terrain: the class rules (CPU twin and the rule table:
// renderer/src/render/landcover.rs) and each class's procedural detail (no texture assets).
// `landcover_weights` takes only height, normal and a jitter, so a land-cover raster can
// replace its output and a normal map its normal input later.

#define CLASS_COUNT 8
#define WATER 0
#define SAND 1
#define GRASS 2
#define CROPS 3
#define FOREST 4
#define ROCK 5
#define SNOW 6
#define URBAN 7

// sRGB base colours (landcover.rs CLASS_ALBEDO_SRGB).
const vec3 CLASS_ALBEDO[CLASS_COUNT] = vec3[](
    vec3(0.07, 0.16, 0.22), vec3(0.62, 0.57, 0.46), vec3(0.31, 0.41, 0.18), vec3(0.52, 0.50, 0.28),
    vec3(0.16, 0.25, 0.12), vec3(0.44, 0.42, 0.40), vec3(0.93, 0.95, 0.98), vec3(0.50, 0.47, 0.45));

const float JITTER_M = 60.0;
const float JITTER_DEG = 3.0;

// The rules of landcover.rs, as layers: each takes its coverage from everything below it.
void landcover_layer(inout float w[CLASS_COUNT], int k, float c) {
    for (int i = 0; i < CLASS_COUNT; ++i) w[i] *= 1.0 - c;
    w[k] += c;
}

void landcover_weights(float h, vec3 n, float jitter, out float w[CLASS_COUNT]) {
    float s = degrees(acos(clamp(n.z, -1.0, 1.0)));
    float hj = h + JITTER_M * jitter;
    float sj = s + JITTER_DEG * jitter;
    for (int i = 0; i < CLASS_COUNT; ++i) w[i] = 0.0;
    w[GRASS] = 1.0;
    float above_beach = smoothstep(4.0, 8.0, h);
    float crops = (1.0 - smoothstep(900.0, 1100.0, hj)) * (1.0 - smoothstep(3.0, 6.0, sj));
    landcover_layer(w, CROPS, crops * above_beach);
    float tree_line = 2000.0 - 250.0 * n.y;
    float forest = smoothstep(6.0, 10.0, sj) * (1.0 - smoothstep(tree_line - 60.0, tree_line + 60.0, hj));
    landcover_layer(w, FOREST, forest * above_beach);
    float beach = (1.0 - smoothstep(4.0, 8.0, h)) * (1.0 - smoothstep(6.0, 10.0, s));
    float bare_line = tree_line + 450.0;
    float scree = smoothstep(bare_line - 100.0, bare_line + 100.0, hj);
    landcover_layer(w, SAND, max(beach, scree));
    float r = 42.0 - 12.0 * smoothstep(1200.0, 2800.0, h);
    landcover_layer(w, ROCK, smoothstep(r - 4.0, r + 4.0, sj));
    float snow_line = 2900.0 - 600.0 * n.y;
    float snow = smoothstep(snow_line - 80.0, snow_line + 80.0, hj) * (1.0 - smoothstep(50.0, 58.0, s));
    landcover_layer(w, SNOW, snow);
    float water = (1.0 - smoothstep(0.5, 1.5, h)) * (1.0 - smoothstep(1.0, 2.5, s));
    landcover_layer(w, WATER, water);
}

// The land-cover raster (drape.glsl's class texture) where it has a class replaces the
// derived weights: the 4 class texels around the grid position, weighted bilinearly, so class
// borders blend over one texel; texels without a class leave the derived weights. The derived
// rock is kept on steep faces whatever the raster says (10–100 m rasters do not resolve
// cliffs: "grass" on a 50° face is drawn as rock). CPU twin: landcover.rs `raster_weights`.
void landcover_raster(vec2 grid, inout float w[CLASS_COUNT]) {
    ivec2 size = textureSize(drape_classes_tex, 0);
    vec2 t = drape_uv(grid) * vec2(size) - 0.5;
    ivec2 i = ivec2(floor(t));
    vec2 f = t - vec2(i);
    float r[CLASS_COUNT];
    for (int k = 0; k < CLASS_COUNT; ++k) r[k] = 0.0;
    float covered = 0.0;
    const ivec2 corner[4] = ivec2[](ivec2(0, 0), ivec2(1, 0), ivec2(0, 1), ivec2(1, 1));
    for (int c = 0; c < 4; ++c) {
        vec2 b = mix(1.0 - f, f, vec2(corner[c]));
        float wt = b.x * b.y;
        uint cls = drape_class_texel(i + corner[c]);
        if (cls < uint(CLASS_COUNT) && wt > 0.0) {
            r[cls] += wt;
            covered += wt;
        }
    }
    if (covered <= 0.0) return;
    float rock = w[ROCK];
    for (int k = 0; k < CLASS_COUNT; ++k) {
        float raster = r[k] / covered * (1.0 - rock) + (k == ROCK ? rock : 0.0);
        w[k] = mix(w[k], raster, covered);
    }
}

// World-anchored value noise. Coordinates are metres with the eye's position taken modulo
// NOISE_PERIOD_M (uniforms.rs), and every lattice is wrapped to that period, so the pattern
// is seamless and exact in f32 anywhere in a large world.
const float NOISE_PERIOD_M = 8192.0;

float lattice_hash(ivec2 c) {
    uvec2 q = uvec2(c) * uvec2(1597334673u, 3812015801u);
    uint n = (q.x ^ q.y) * 1597334673u;
    return float(n >> 8) * (1.0 / 16777216.0);
}

// Value noise in [0, 1] on a lattice of `cell` metres (a power of two ≤ the period).
float vnoise(vec2 p, float cell) {
    vec2 g = p / cell;
    vec2 f = fract(g);
    ivec2 i = ivec2(floor(g));
    int mask = int(NOISE_PERIOD_M / cell) - 1;
    vec2 u = f * f * (3.0 - 2.0 * f);
    float a = lattice_hash(i & mask);
    float b = lattice_hash((i + ivec2(1, 0)) & mask);
    float c = lattice_hash((i + ivec2(0, 1)) & mask);
    float d = lattice_hash((i + ivec2(1, 1)) & mask);
    return mix(mix(a, b, u.x), mix(c, d, u.x), u.y);
}

// An octave fades out as the pixel footprint reaches its cell size (no shimmering).
float octave_weight(float cell, float footprint) {
    return 1.0 - smoothstep(0.5 * cell, 2.0 * cell, footprint);
}

// Three octaves from `cell` down, centred on 0 (about ±0.5), band-limited by `footprint`.
float detail_noise(vec2 p, float cell, float footprint) {
    float sum = 0.0;
    float amp = 0.5;
    for (int k = 0; k < 3; ++k) {
        sum += amp * octave_weight(cell, footprint) * (vnoise(p, cell) - 0.5);
        cell *= 0.25;
        amp *= 0.6;
    }
    return 2.0 * sum;
}

// The jitter of the class borders, in [-1, 1]: 512 m and 128 m features.
float landcover_jitter(vec2 p) {
    return clamp(1.3 * (vnoise(p, 512.0) - 0.5) + 0.9 * (vnoise(p, 128.0) - 0.5), -1.0, 1.0);
}

// Detail of a 2-D pattern on a surface: projected from above on gentle slopes, triplanar
// (the three axis planes blended by the normal) on steep faces, so cliffs are not smeared.
float surface_noise(vec3 p, vec3 n, float cell, float footprint) {
    if (n.z > 0.8) return detail_noise(p.xy, cell, footprint);
    vec3 b = pow(abs(n), vec3(4.0));
    b /= b.x + b.y + b.z;
    return b.z * detail_noise(p.xy, cell, footprint)
         + b.y * detail_noise(p.xz, cell, footprint)
         + b.x * detail_noise(p.yz, cell, footprint);
}

// sRGB albedo of class k at world point p (x, y modulo the period; z the height) with
// normal n, `footprint` metres per pixel.
vec3 class_albedo(int k, vec3 p, vec3 n, float footprint) {
    vec3 base = CLASS_ALBEDO[k];
    if (k == WATER) {
        return base * (1.0 + 0.15 * detail_noise(p.xy, 64.0, footprint));
    } else if (k == SAND) {
        return base * (1.0 + 0.2 * surface_noise(p, n, 32.0, footprint));
    } else if (k == GRASS) {
        float t = detail_noise(p.xy, 256.0, footprint);
        return base * (1.0 + 0.25 * t) + vec3(0.03, 0.02, -0.01) * detail_noise(p.xy, 16.0, footprint);
    } else if (k == CROPS) {
        // Strips of fields 64 m deep and 128 m long, each strip shifted along by its own
        // amount (no chequerboard), each field one crop colour.
        int strip = int(floor(p.y / 64.0));
        float shift = 128.0 * lattice_hash(ivec2(strip & 127, 7));
        ivec2 field = ivec2(int(floor((p.x + shift) / 128.0)), strip);
        float pick = lattice_hash(field & ivec2(63, 127));
        vec3 crop = pick < 0.3 ? vec3(0.64, 0.56, 0.30)
                  : pick < 0.55 ? vec3(0.42, 0.50, 0.22)
                  : pick < 0.8 ? vec3(0.48, 0.42, 0.31) : vec3(0.55, 0.56, 0.30);
        // Far away the fields average to the class colour.
        float resolved = octave_weight(64.0, footprint);
        return mix(base, crop, resolved) * (1.0 + 0.1 * detail_noise(p.xy, 16.0, footprint));
    } else if (k == FOREST) {
        // Clumps of crowns, darker gaps.
        float crowns = detail_noise(p.xy, 32.0, footprint);
        return base * (1.0 + 0.35 * crowns);
    } else if (k == ROCK) {
        // Strata along the height, broken by noise; triplanar on cliffs.
        float strata = sin(p.z * 0.45 + 6.0 * vnoise(p.xy, 64.0)) * octave_weight(8.0, footprint);
        return base * (1.0 + 0.25 * surface_noise(p, n, 64.0, footprint) + 0.08 * strata);
    } else if (k == SNOW) {
        return base * (1.0 + 0.04 * surface_noise(p, n, 64.0, footprint));
    }
    // Urban (from a raster, later): blocks.
    return base * (1.0 + 0.2 * detail_noise(p.xy, 64.0, footprint));
}
