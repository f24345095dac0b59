// A node's place on the WGS84 ellipsoid (render/geo_instances.rs `GeoEye::node_fields`): the
// vertex arithmetic shared by the clipmap tiles (terrain.vert, one GeoFields per tile instance)
// and the tessellation baseline (terrain_tess.tese, one per base-mesh cell). DESIGN.md
// "Precision": the CPU gives each node its centre relative to the eye in f64; here the vertex's
// offset from that centre is formed in f32 from small, well-conditioned factors.
// render/geo_instances.rs `emulate_vertex` repeats this arithmetic on the CPU: keep them in step.
// Needs gpu_types.glsl (GeoFields).

const float WGS84_A = 6378137.0;
const float WGS84_E2 = 0.00669438;

// sin x and 1 - cos x by their series: the GPU's sin/cos may err by 2^-11, kilometres at the
// Earth's radius, while the angles inside a node are small.
void sincos_small(float x, out float s, out float omc) {
    float x2 = x * x;
    s = x * (1.0 - x2 * (1.0 / 6.0 - x2 * (1.0 / 120.0 - x2 * (1.0 / 5040.0
        - x2 * (1.0 / 362880.0 - x2 * (1.0 / 39916800.0))))));
    omc = x2 * (0.5 - x2 * (1.0 / 24.0 - x2 * (1.0 / 720.0 - x2 * (1.0 / 40320.0
        - x2 * (1.0 / 3628800.0)))));
}

// Position relative to the node's centre vertex in its meridian frame (radial, east, polar)
// of the sample `d` samples (E, N) from it at height h, and the local east/north/up there.
// Every term is a product of factors known to f32 precision, none a difference of two large
// numbers: cos(p) - cos(p0) = -2 sin(p0 + dp/2) sin(dp/2), W^2 - W0^2 = -e2 (sin p - sin p0)
// (sin p + sin p0), 1/W - 1/W0 = (W0^2 - W^2) / (W W0 (W + W0)).
vec3 ellipsoid_offset(GeoFields t, vec2 d, float h, out mat3 enu, out float east_m) {
    float dphi = d.y * t.geo_origin.w;
    float dlam = d.x * t.geo_radius.x;
    float sp0 = t.geo_axis_r.w;
    float cp0 = t.geo_axis_t.w;
    float w0 = t.geo_axis_z.w;
    float sh, omch, sd, omcd, sl, omcl;
    sincos_small(0.5 * dphi, sh, omch);
    sincos_small(dphi, sd, omcd);
    sincos_small(dlam, sl, omcl);
    float ch = 1.0 - omch;
    float cd = 1.0 - omcd;
    float sinp = sp0 * cd + cp0 * sd;
    float cosp = cp0 * cd - sp0 * sd;
    float sm = sp0 * ch + cp0 * sh;
    float cm = cp0 * ch - sp0 * sh;
    float dcos = -2.0 * sm * sh;
    float dsin = 2.0 * cm * sh;
    float dw2 = -WGS84_E2 * dsin * (sinp + sp0);
    float w = sqrt(w0 * w0 + dw2);
    float dinv = -dw2 / (w * w0 * (w + w0));
    float dr = WGS84_A * (dcos / w + cp0 * dinv) + h * cosp;
    float dz = (WGS84_A * (1.0 - WGS84_E2)) * (dsin / w + sp0 * dinv) + h * sinp;
    // r = r0_hi + r0_lo + dr; x = r cos(dlam) - r0, y = r sin(dlam).
    float rs = t.geo_radius.z + dr;
    float x = dr - (t.geo_radius.y * omcl + rs * omcl);
    float y = t.geo_radius.y * sl + rs * sl;
    float cl = 1.0 - omcl;
    enu = mat3(vec3(-sl, cl, 0.0), vec3(-sinp * cl, -sinp * sl, cosp), vec3(cosp * cl, cosp * sl, sinp));
    east_m = (t.geo_radius.y + rs) * t.geo_radius.x;
    return vec3(x, y, dz);
}

// A projected (UTM) node's vertex at (u, v), height h: its offset from the node's centre (world
// axes) from the cubic polynomials S and N (gpu_types.glsl), the unit normal there, and S's
// derivatives in u and v (for the shading normal).
vec3 projected_offset(GeoFields t, vec2 uv, float h, out vec3 up, out vec3 su, out vec3 sv) {
    float u = uv.x;
    float v = uv.y;
    float b[9] = float[9](u, v, u * u, u * v, v * v, u * u * u, u * u * v, u * v * v, v * v * v);
    float bu[9] = float[9](1.0, 0.0, 2.0 * u, v, 0.0, 3.0 * u * u, 2.0 * u * v, v * v, 0.0);
    float bv[9] = float[9](0.0, 1.0, 0.0, u, 2.0 * v, 0.0, u * u, 2.0 * u * v, 3.0 * v * v);
    vec3 s = vec3(0.0);
    vec3 nrm = t.geo_n[0].xyz;
    su = vec3(0.0);
    sv = vec3(0.0);
    for (int k = 0; k < 9; k++) {
        s += t.geo_s[k].xyz * b[k];
        nrm += t.geo_n[k + 1].xyz * b[k];
        su += t.geo_s[k].xyz * bu[k];
        sv += t.geo_s[k].xyz * bv[k];
    }
    up = normalize(nrm);
    return s + nrm * h;
}

// What a drawn vertex on the ellipsoid needs: its position relative to the eye, its shading
// normal, the local up and north (world axes).
struct GeoVertex {
    vec3 rel;
    vec3 normal;
    vec3 up;
    vec3 north;
};

// The vertex `d` samples (east, north) from the node's centre, drawn at height h (a skirt's
// lowered height), whose surface rises `dh` metres per sample along the grid's axes.
GeoVertex geo_vertex(GeoFields t, vec2 d, float h, vec2 dh) {
    GeoVertex o;
    if (t.geo_radius.w != 0.0) {
        // A projected grid: the node's centre plus its polynomial offset; tangents per sample
        // along the grid's axes.
        vec3 su, sv;
        o.rel = t.geo_origin.xyz + projected_offset(t, d * t.geo_origin.w, h, o.up, su, sv);
        vec3 tx = su * t.geo_origin.w + o.up * dh.x;
        vec3 ty = sv * t.geo_origin.w + o.up * dh.y;
        vec3 north0 = vec3(t.geo_s[0].w, t.geo_s[1].w, t.geo_s[2].w);
        o.normal = normalize(cross(tx, ty));
        o.north = normalize(north0 - dot(north0, o.up) * o.up);
        return o;
    }
    // Geographic: the node's frame plus the vertex's offset from its centre.
    mat3 enu;
    float east_m;
    vec3 off = ellipsoid_offset(t, d, h, enu, east_m);
    mat3 axes = mat3(t.geo_axis_r.xyz, t.geo_axis_t.xyz, t.geo_axis_z.xyz);
    float north_m = WGS84_A * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * enu[2].z * enu[2].z)
        / sqrt(1.0 - WGS84_E2 * enu[2].z * enu[2].z) * t.geo_origin.w;
    vec2 slope = dh / vec2(east_m, north_m);
    o.rel = t.geo_origin.xyz + axes * off;
    o.normal = axes * normalize(enu * vec3(-slope.x, -slope.y, 1.0));
    o.up = axes * enu[2];
    o.north = axes * enu[1];
    return o;
}
