/* shadow_map.c — software depth maps (see shadow_map.h): a half-space rasteriser with texel-centre
 * sampling, near-plane clipping for perspective maps and perspective-correct depth (1/z interpolated
 * in screen space, z in view space). */
#include "shadow_map.h"
#include "host_math.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>



void glow__dm_setup_ortho(glow__depth_map *m, const float dir[3], const float bmin[3], const float bmax[3], uint32_t res,
                          uint32_t margin) {
    float *keep = m->depth;
    uint32_t keep_res = m->res;
    memset(m, 0, sizeof *m);
    m->depth = keep;
    m->res = keep_res;
    memcpy(m->az, dir, sizeof m->az);
    glow__onb(m->az, m->ax, m->ay);
    for (int i = 0; i < 3; ++i) m->origin[i] = 0.5f * (bmin[i] + bmax[i]);
    float xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY, zlo = INFINITY, zhi = -INFINITY;
    for (int c = 0; c < 8; ++c) {
        float p[3] = {(c & 1 ? bmax[0] : bmin[0]) - m->origin[0], (c & 2 ? bmax[1] : bmin[1]) - m->origin[1],
                      (c & 4 ? bmax[2] : bmin[2]) - m->origin[2]};
        float x = glow__dot3(p, m->ax), y = glow__dot3(p, m->ay), z = glow__dot3(p, m->az);
        xlo = fminf(xlo, x);
        xhi = fmaxf(xhi, x);
        ylo = fminf(ylo, y);
        yhi = fmaxf(yhi, y);
        zlo = fminf(zlo, z);
        zhi = fmaxf(zhi, z);
    }
    float extent = fmaxf(fmaxf(xhi - xlo, yhi - ylo), 1e-6f);
    m->box_z[0] = zlo;
    m->box_z[1] = zhi;
    m->extent = extent;
    uint32_t inner = res > 2 * margin + 1 ? res - 2 * margin : 1;
    m->texel = extent / (float)inner;
    m->off_x = 0.5f * (xlo + xhi) - 0.5f * (float)res * m->texel;
    m->off_y = 0.5f * (ylo + yhi) - 0.5f * (float)res * m->texel;
    m->persp = false;
    if (m->res != res) glow__dm_free(m);
    m->res = res;
}

void glow__dm_setup_persp(glow__depth_map *m, const float eye[3], const float axis[3], float tan_half, uint32_t res,
                          uint32_t margin, float near_z) {
    float *keep = m->depth;
    uint32_t keep_res = m->res;
    memset(m, 0, sizeof *m);
    m->depth = keep;
    m->res = keep_res;
    memcpy(m->origin, eye, sizeof m->origin);
    memcpy(m->az, axis, sizeof m->az);
    glow__onb(m->az, m->ax, m->ay);
    uint32_t inner = res > 2 * margin + 1 ? res - 2 * margin : 1;
    float s = tan_half * (float)res / (float)inner;
    m->inv_s = 1.0f / s;
    m->texel = 2.0f * s / (float)res;
    m->near_z = near_z;
    m->persp = true;
    if (m->res != res) glow__dm_free(m);
    m->res = res;
}

void glow__dm_setup_cube(glow__depth_map m[6], const float eye[3], uint32_t res, uint32_t margin, float near_z) {
    for (int f = 0; f < 6; ++f) {
        float axis[3] = {0.0f, 0.0f, 0.0f};
        axis[f >> 1] = (f & 1) ? -1.0f : 1.0f;
        glow__dm_setup_persp(&m[f], eye, axis, 1.0f, res, margin, near_z);
    }
}

int glow__dm_cube_face(const float d[3]) {
    float ax = fabsf(d[0]), ay = fabsf(d[1]), az = fabsf(d[2]);
    if (ax >= ay && ax >= az) return d[0] >= 0.0f ? 0 : 1;
    if (ay >= az) return d[1] >= 0.0f ? 2 : 3;
    return d[2] >= 0.0f ? 4 : 5;
}

void glow__dm_free(glow__depth_map *m) {
    free(m->depth);
    m->depth = NULL;
}

/* --------------------------------------------------------------------------- rasteriser */

typedef struct svert {
    float x, y; /* texel coordinates (texel (i, j) spans [i, i+1) x [j, j+1)) */
    float d;    /* ortho: z; persp: 1/z (both linear in screen space) */
} svert;

static void raster_tri(glow__depth_map *m, const svert *a, const svert *b, const svert *c) {
    float area = (b->x - a->x) * (c->y - a->y) - (b->y - a->y) * (c->x - a->x);
    if (!(fabsf(area) > 1e-12f)) return;
    float inv_area = 1.0f / area;
    float fx0 = fminf(a->x, fminf(b->x, c->x)), fx1 = fmaxf(a->x, fmaxf(b->x, c->x));
    float fy0 = fminf(a->y, fminf(b->y, c->y)), fy1 = fmaxf(a->y, fmaxf(b->y, c->y));
    float lim = (float)m->res;
    if (fx1 < 0.0f || fy1 < 0.0f || fx0 > lim || fy0 > lim) return;
    int x0 = (int)fmaxf(floorf(fx0 - 0.5f), 0.0f), x1 = (int)fminf(ceilf(fx1 - 0.5f), lim - 1.0f);
    int y0 = (int)fmaxf(floorf(fy0 - 0.5f), 0.0f), y1 = (int)fminf(ceilf(fy1 - 0.5f), lim - 1.0f);
    for (int j = y0; j <= y1; ++j) {
        float py = (float)j + 0.5f;
        float *row = m->depth + (size_t)j * m->res;
        for (int i = x0; i <= x1; ++i) {
            float px = (float)i + 0.5f;
            /* barycentrics, normalised so they are >= 0 inside for either winding */
            float w0 = ((b->x - px) * (c->y - py) - (b->y - py) * (c->x - px)) * inv_area;
            float w1 = ((c->x - px) * (a->y - py) - (c->y - py) * (a->x - px)) * inv_area;
            float w2 = 1.0f - w0 - w1;
            if (w0 < 0.0f || w1 < 0.0f || w2 < 0.0f) continue;
            float d = w0 * a->d + w1 * b->d + w2 * c->d;
            float z = m->persp ? 1.0f / d : d;
            if (z < row[i]) row[i] = z;
        }
    }
}

static void view(const glow__depth_map *m, const float p[3], float out[3]) {
    float q[3] = {p[0] - m->origin[0], p[1] - m->origin[1], p[2] - m->origin[2]};
    out[0] = glow__dot3(q, m->ax);
    out[1] = glow__dot3(q, m->ay);
    out[2] = glow__dot3(q, m->az);
}

static svert project(const glow__depth_map *m, const float v[3]) {
    svert s;
    float half = 0.5f * (float)m->res;
    if (m->persp) {
        float iz = 1.0f / v[2];
        s.x = (v[0] * iz * m->inv_s + 1.0f) * half;
        s.y = (v[1] * iz * m->inv_s + 1.0f) * half;
        s.d = iz;
    } else {
        s.x = (v[0] - m->off_x) / m->texel;
        s.y = (v[1] - m->off_y) / m->texel;
        s.d = v[2];
    }
    return s;
}

bool glow__dm_render(glow__depth_map *m, const float *tris, uint32_t tri_count) {
    size_t n = (size_t)m->res * m->res;
    if (!m->depth) {
        m->depth = malloc(n * sizeof *m->depth);
        if (!m->depth) return false;
    }
    for (size_t i = 0; i < n; ++i) m->depth[i] = INFINITY;
    for (uint32_t t = 0; t < tri_count; ++t) {
        float v[3][3];
        for (int k = 0; k < 3; ++k) view(m, tris + 9 * (size_t)t + 3 * k, v[k]);
        if (!m->persp) {
            svert s[3] = {project(m, v[0]), project(m, v[1]), project(m, v[2])};
            raster_tri(m, &s[0], &s[1], &s[2]);
            continue;
        }
        float nz = m->near_z;
        if (v[0][2] < nz && v[1][2] < nz && v[2][2] < nz) continue;
        /* clip the triangle against z >= near (Sutherland-Hodgman: at most 4 vertices) */
        float poly[4][3];
        int pn = 0;
        for (int k = 0; k < 3; ++k) {
            const float *a = v[k], *b = v[(k + 1) % 3];
            bool ain = a[2] >= nz, bin = b[2] >= nz;
            if (ain) memcpy(poly[pn++], a, sizeof poly[0]);
            if (ain != bin) {
                float t2 = (nz - a[2]) / (b[2] - a[2]);
                for (int i = 0; i < 3; ++i) poly[pn][i] = a[i] + t2 * (b[i] - a[i]);
                poly[pn++][2] = nz;
            }
        }
        svert s[4];
        for (int k = 0; k < pn; ++k) s[k] = project(m, poly[k]);
        for (int k = 1; k + 1 < pn; ++k) raster_tri(m, &s[0], &s[k], &s[k + 1]);
    }
    return true;
}

/* ------------------------------------------------------------------------------ lookup */

float glow__dm_visibility(const glow__depth_map *m, const float p[3], const float n[3], const float l[3],
                          const glow__shadow_params *sp) {
    if (!m->depth) return 1.0f;
    float v[3];
    view(m, p, v);
    float texel = m->texel;
    if (m->persp) {
        if (!(v[2] > m->near_z)) return 1.0f; /* at the light itself: nothing in front */
        texel *= v[2];
    }
    float q[3];
    for (int i = 0; i < 3; ++i) q[i] = p[i] + n[i] * sp->normal_offset * texel;
    view(m, q, v);
    if (m->persp && !(v[2] > m->near_z)) return 1.0f;
    float c = fminf(fmaxf(glow__dot3(n, l), 1e-4f), 1.0f);
    float tan_t = fminf(sqrtf(fmaxf(1.0f - c * c, 0.0f)) / c, 10.0f);
    float bias = texel * (sp->depth_bias + sp->slope_bias * tan_t);
    svert s = project(m, v);
    float z = v[2] - bias;
    int ix = (int)floorf(s.x), iy = (int)floorf(s.y), r = sp->pcf_radius, res = (int)m->res;
    if (!(fabsf(s.x) < 1e9f) || !(fabsf(s.y) < 1e9f)) return 1.0f;
    int lit = 0, taps = 0;
    for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
            int x = ix + dx, y = iy + dy;
            ++taps;
            if (x < 0 || y < 0 || x >= res || y >= res || z <= m->depth[(size_t)y * m->res + (size_t)x]) ++lit;
        }
    }
    return (float)lit / (float)taps;
}
