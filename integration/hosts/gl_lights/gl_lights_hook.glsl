// gl_lights_hook.glsl - glow_gl_lights' surfel lighting hook (glow_gl_lights.h, THE HOOK).
// ASCII only (GLSL's character set; the embedded bytes are a char array).
// Embedded into gl_lights.c at configure time (CMakeLists.txt); gl_lights.c puts the GLOW_GL_LIGHTS_* sizes and bindings
// in front of it. Valid in compute and fragment shaders (texelFetch only, no derivatives).
// It mirrors integration/hosts/cpu/host.c (light_term) and shadow_map.c (glow__dm_visibility): change
// them together. Block layout: the std140 structs in gl_lights.c.

#define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED

struct glow_gl_lights_light {
    vec4 position;  // xyz: point/spot position (m); w: unused
    vec4 direction; // xyz: unit spot axis / sun travel direction; w: cos(outer_deg)
    vec4 power;     // rgb: intensity (W/sr) or sun irradiance (W/m^2); w: cos(inner_deg)
    ivec4 info;     // x: type (1 point, 2 spot, 3 sun); y: first map; z: maps (0, 1 or 6 = cube); w: unused
};

struct glow_gl_lights_map {
    vec4 origin;    // xyz: the eye (perspective) or the bounds centre (orthographic); w: 1 = perspective
    vec4 ax;        // xyz: right axis; w: perspective 1/tan(half field of view)
    vec4 ay;        // xyz: up axis; w: texel size (orthographic: m; perspective: at distance 1)
    vec4 az;        // xyz: view axis; w: near plane (perspective)
    vec4 params;    // x, y: orthographic view-plane coordinates of texel corner (0, 0); z: depth of
                    // stored 0; w: depth range (stored d means view-axis distance z + d * w)
    ivec4 info;     // x: resolution; y: layer; z: array (0 = glow_gl_lights_maps, 1 = cube faces); w: unused
};

layout(std140, binding = GLOW_GL_LIGHTS_UBO_BINDING) uniform glow_gl_lights_block {
    vec4 environment; // rgb: sky radiance * pi (W/m^2); w: 1 = the sky is sky_sh instead
    vec4 shadow;      // x: depth_bias, y: slope_bias, z: normal_offset (texels); w: unused
    ivec4 counts;     // x: lights; y: PCF radius; z: per-surfel sky visibility values S (0 = none);
                      // w: per-surfel sky transfers T (0 = none), 9 floats each after the S values
    vec4 sky_sh[9];   // rgb: the sky's radiance SH (l <= 2, glow_sh_eval's basis; docs/sky.md)
    glow_gl_lights_light lights[GLOW_GL_LIGHTS_LIGHTS];
    glow_gl_lights_map maps[GLOW_GL_LIGHTS_MAPS];
} glow_gl_lights;

#ifdef GLOW_SURFEL_INDEX_AVAILABLE
// Per-surfel sky visibility S (glow_gl_lights_set_sky_visibility), then per-surfel sky transfer T
// (glow_gl_lights_set_sky_transfer, 9 floats a surfel), read inside Glow's surfel kernel.
layout(std430, binding = GLOW_GL_LIGHTS_UBO_BINDING) readonly buffer glow_gl_lights_sky_block { float glow_gl_lights_sky[]; };
#endif

layout(binding = GLOW_GL_LIGHTS_MAP_UNIT) uniform sampler2DArray glow_gl_lights_maps;
layout(binding = GLOW_GL_LIGHTS_CUBE_UNIT) uniform sampler2DArray glow_gl_lights_cube_faces;

// The face of a cube (+x, -x, +y, -y, +z, -z) that direction d from the eye falls in.
int glow_gl_lights_cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0 ? 0 : 1;
    if (a.y >= a.z) return d.y >= 0.0 ? 2 : 3;
    return d.z >= 0.0 ? 4 : 5;
}

// Fraction of PCF taps of map `mi` in which p (unit normal n, unit direction to the light l) is lit.
float glow_gl_lights_visibility(int mi, vec3 p, vec3 n, vec3 l) {
    vec3 o = glow_gl_lights.maps[mi].origin.xyz;
    bool persp = glow_gl_lights.maps[mi].origin.w > 0.5;
    vec3 ax = glow_gl_lights.maps[mi].ax.xyz, ay = glow_gl_lights.maps[mi].ay.xyz, az = glow_gl_lights.maps[mi].az.xyz;
    float inv_s = glow_gl_lights.maps[mi].ax.w, near_z = glow_gl_lights.maps[mi].az.w;
    vec4 prm = glow_gl_lights.maps[mi].params;
    ivec4 info = glow_gl_lights.maps[mi].info;
    float texel = glow_gl_lights.maps[mi].ay.w;
    if (persp) {
        float vz = dot(p - o, az);
        if (!(vz > near_z)) return 1.0; // at the light itself: nothing in front
        texel *= vz;
    }
    vec3 q = p + n * (glow_gl_lights.shadow.z * texel) - o;
    vec3 v = vec3(dot(q, ax), dot(q, ay), dot(q, az));
    if (persp && !(v.z > near_z)) return 1.0;
    float c = clamp(dot(n, l), 1e-4, 1.0);
    float tan_t = min(sqrt(max(1.0 - c * c, 0.0)) / c, 10.0);
    float bias = texel * (glow_gl_lights.shadow.x + glow_gl_lights.shadow.y * tan_t);
    float res = float(info.x);
    vec2 s;
    if (persp) s = (v.xy * (1.0 / v.z) * inv_s + 1.0) * (0.5 * res);
    else s = (v.xy - prm.xy) / glow_gl_lights.maps[mi].ay.w;
    if (!(abs(s.x) < 1e9) || !(abs(s.y) < 1e9)) return 1.0;
    float z = v.z - bias;
    ivec2 base = ivec2(floor(s));
    int r = glow_gl_lights.counts.y, lit = 0, taps = 0;
    for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
            ivec2 t = base + ivec2(dx, dy);
            ++taps;
            if (t.x < 0 || t.y < 0 || t.x >= info.x || t.y >= info.x) {
                ++lit;
                continue;
            }
            float d = info.z == 0 ? texelFetch(glow_gl_lights_maps, ivec3(t, info.y), 0).r
                                  : texelFetch(glow_gl_lights_cube_faces, ivec3(t, info.y), 0).r;
            if (d >= 1.0 || z <= prm.z + d * prm.w) ++lit; // 1 = cleared: nothing there
        }
    }
    return float(lit) / float(taps);
}

// The sky's share: S at this surfel (Glow's kernel, when S was set), or GLOW_GL_LIGHTS_PIXEL_SKY (an
// expression the including shader may define, e.g. S looked up at the pixel), else 1 (unshadowed).
float glow_gl_lights_sky_visibility() {
#if defined(GLOW_SURFEL_INDEX_AVAILABLE)
    if (uint(glow_gl_lights.counts.z) > glow_surfel_index) return glow_gl_lights_sky[glow_surfel_index];
    return 1.0;
#elif defined(GLOW_GL_LIGHTS_PIXEL_SKY)
    return GLOW_GL_LIGHTS_PIXEL_SKY;
#else
    return 1.0;
#endif
}

// The SH sky's irradiance max(0, sum_k T_k L_k): T the surfel's transfer (Glow's kernel, when set), else
// the unoccluded cosine lobe about n, T_k = A_l y_k(n) with A = (pi, 2 pi / 3, pi / 4), times the sky's
// visible share glow_gl_lights_sky_visibility() (S when set, GLOW_GL_LIGHTS_PIXEL_SKY at a pixel, else 1).
// Mirrors host.c's sky_T.
vec3 glow_gl_lights_sky_sh(vec3 n) {
    float t[9];
    float share = 1.0;
#if defined(GLOW_SURFEL_INDEX_AVAILABLE)
    if (uint(glow_gl_lights.counts.w) > glow_surfel_index) {
        uint b = uint(glow_gl_lights.counts.z) + 9u * glow_surfel_index;
        for (int k = 0; k < 9; ++k) t[k] = glow_gl_lights_sky[b + uint(k)];
    } else
#endif
    {
        const float a0 = 3.14159265 * 0.2820947918, a1 = 2.0943951 * 0.4886025119, a2 = 0.78539816;
        t[0] = a0;
        t[1] = a1 * n.y;
        t[2] = a1 * n.z;
        t[3] = a1 * n.x;
        t[4] = a2 * 1.0925484306 * n.x * n.y;
        t[5] = a2 * 1.0925484306 * n.y * n.z;
        t[6] = a2 * 0.3153915653 * (3.0 * n.z * n.z - 1.0);
        t[7] = a2 * 1.0925484306 * n.x * n.z;
        t[8] = a2 * 0.5462742153 * (n.x * n.x - n.y * n.y);
        share = glow_gl_lights_sky_visibility();
    }
    vec3 e = vec3(0.0);
    for (int k = 0; k < 9; ++k) e += t[k] * glow_gl_lights.sky_sh[k].rgb;
    return max(e, vec3(0.0)) * share;
}

vec3 glow_host_surfel_irradiance(vec3 position, vec3 normal, uint material) {
    vec3 e = glow_gl_lights.environment.rgb;
    if (glow_gl_lights.environment.w > 0.5) e = glow_gl_lights_sky_sh(normal);
    else if (e.r > 0.0 || e.g > 0.0 || e.b > 0.0) e *= glow_gl_lights_sky_visibility();
    int count = glow_gl_lights.counts.x;
    for (int i = 0; i < count; ++i) {
        vec3 power = glow_gl_lights.lights[i].power.rgb;
        if (power.r == 0.0 && power.g == 0.0 && power.b == 0.0) continue;
        ivec4 info = glow_gl_lights.lights[i].info;
        vec3 dir = glow_gl_lights.lights[i].direction.xyz;
        vec3 l;
        float f;
        if (info.x == 3) { // sun
            l = -dir;
            f = max(dot(normal, l), 0.0);
        } else {
            vec3 d = glow_gl_lights.lights[i].position.xyz - position;
            float d2 = dot(d, d);
            if (!(d2 > 1e-20)) continue;
            l = d / sqrt(d2);
            float c = dot(normal, l);
            if (!(c > 0.0)) continue;
            f = c / d2;
            if (info.x == 2) { // spot: smoothstep falloff between the outer and inner cones
                float cos_outer = glow_gl_lights.lights[i].direction.w;
                float cos_inner = glow_gl_lights.lights[i].power.w;
                float cos_theta = -dot(l, dir);
                float t;
                if (cos_inner > cos_outer) t = clamp((cos_theta - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
                else t = cos_theta >= cos_outer ? 1.0 : 0.0;
                f *= t * t * (3.0 - 2.0 * t);
            }
        }
        if (!(f > 0.0)) continue;
        if (info.z > 0) {
            int mi = info.y;
            if (info.z == 6) mi += glow_gl_lights_cube_face(position - glow_gl_lights.lights[i].position.xyz);
            f *= glow_gl_lights_visibility(mi, position, normal, l);
        }
        e += f * power;
    }
    return e;
}
