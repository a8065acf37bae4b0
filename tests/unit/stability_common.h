/* stability_common.h — shared helpers of the stability suite (tests/unit/test_stability_*.c, issue 4):
 * bake a scene to a temporary file and load it, read what a cache delivers, enumerate the lightmap
 * texels a triangle's bilinear lookups read, and a brute-force ray cast over the bake's triangles
 * (independent of the linker's Embree scene). Header-only (static functions), so each test stays one
 * source file for the tests/CMakeLists.txt glob. */
#ifndef GLOW_TESTS_STABILITY_COMMON_H
#define GLOW_TESTS_STABILITY_COMMON_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "glow/glow.h"
#include "glow/glow_precompute.h"
#include "runtime_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct stab_bake {
    glow_context *ctx;
    glow_bake *bake;
    char path[256];
} stab_bake;

/* Bakes `scene` with `settings` to /tmp and loads it; 0 on success. */
static inline int stab_bake_load(const char *scene, const char *tag, const glow_pc_settings *settings, stab_bake *out) {
    memset(out, 0, sizeof *out);
    snprintf(out->path, sizeof out->path, "/tmp/glow_stability_%s_%d.glow", tag, (int)getpid());
    glow_pc_stats st;
    if (glow_pc_bake(scene, out->path, settings, &st) != GLOW_OK) {
        fprintf(stderr, "bake of %s failed: %s\n", scene, st.error);
        out->path[0] = 0;
        return -1;
    }
    if (glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION}, &out->ctx) != GLOW_OK) return -1;
    if (glow_bake_load_file(out->ctx, out->path, &out->bake) != GLOW_OK) return -1;
    return 0;
}

static inline void stab_bake_free(stab_bake *b) {
    glow_bake_destroy(b->bake);
    glow_context_destroy(b->ctx);
    if (b->path[0]) remove(b->path);
    memset(b, 0, sizeof *b);
}

static inline double stab_luma(const float rgb[3]) { return 0.25 * rgb[0] + 0.5 * rgb[1] + 0.25 * rgb[2]; }

/* What a cache delivers, luma (Y) in W/(m²·sr): lightmap caches the diffuse shading along their
 * normal (glow_shade_sh, exponent 1: the cosine-weighted mean incident radiance E/π), grid caches the
 * mean incident radiance over the sphere (c00 y00). */
static inline double stab_cache_luma(const glow_cache_outputs *o, const glow_bake_cache *caches, uint32_t c) {
    const float *sh = o->cache_sh + (size_t)c * o->coeff_count;
    if (c < o->grid_cache_count) return sh[0] * 0.28209479177387814;
    float n[3], rgb[3];
    glow__oct_decode(caches[c].normal_oct, n);
    glow_shade_sh(sh, o->sh_bands_luma, o->sh_bands_chroma, n, 1.0f, rgb);
    return stab_luma(rgb);
}

/* Triangle t of the bake's geometry: corners (m) and lightmap UVs in [0,1]. */
static inline void stab_triangle(const glow_bake_geometry *g, uint32_t t, double p[3][3], double uv[3][2]) {
    const unsigned char *base = (const unsigned char *)g->positions + (size_t)t * g->stride;
    const float *pos = (const float *)base;
    const uint16_t *luv = (const uint16_t *)((const unsigned char *)g->lightmap_uv + (size_t)t * g->stride);
    for (int k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) p[k][a] = pos[3 * k + a];
        uv[k][0] = luv[2 * k] / 65535.0;
        uv[k][1] = luv[2 * k + 1] / 65535.0;
    }
}

static inline void stab_normal(const double p[3][3], double n[3]) {
    double e1[3], e2[3];
    for (int a = 0; a < 3; ++a) {
        e1[a] = p[1][a] - p[0][a];
        e2[a] = p[2][a] - p[0][a];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3; ++a) n[a] = l > 0.0 ? n[a] / l : 0.0;
}

/* Do the 2-D triangle t and the open box (x0,x1)x(y0,y1) share interior points? Separating axes:
 * the box's two axes and the triangle's three edge normals; touching counts as separate. */
static inline bool stab_tri_box_open(const double t[3][2], double x0, double x1, double y0, double y1) {
    double mnx = fmin(fmin(t[0][0], t[1][0]), t[2][0]), mxx = fmax(fmax(t[0][0], t[1][0]), t[2][0]);
    double mny = fmin(fmin(t[0][1], t[1][1]), t[2][1]), mxy = fmax(fmax(t[0][1], t[1][1]), t[2][1]);
    if (mxx <= x0 || mnx >= x1 || mxy <= y0 || mny >= y1) return false;
    const double bx[4] = {x0, x1, x1, x0}, by[4] = {y0, y0, y1, y1};
    for (int k = 0; k < 3; ++k) {
        double ax = t[(k + 1) % 3][1] - t[k][1], ay = t[k][0] - t[(k + 1) % 3][0];
        if (ax == 0.0 && ay == 0.0) continue;
        double tlo = INFINITY, thi = -INFINITY, blo = INFINITY, bhi = -INFINITY;
        for (int i = 0; i < 3; ++i) {
            double q = t[i][0] * ax + t[i][1] * ay;
            tlo = fmin(tlo, q);
            thi = fmax(thi, q);
        }
        for (int i = 0; i < 4; ++i) {
            double q = bx[i] * ax + by[i] * ay;
            blo = fmin(blo, q);
            bhi = fmax(bhi, q);
        }
        if (thi <= blo || tlo >= bhi) return false;
    }
    return true;
}

/* The texels glow_sample_lightmap reads with non-zero weight somewhere on the triangle whose UVs
 * are uv: a lookup at texel-space X = u·width weighs texel i by max(0, 1 - |X - (i + 0.5)|), non-zero
 * exactly for X in (i - 0.5, i + 1.5); so texel (i, j) is used when the UV triangle (in texel units)
 * overlaps the open square (i - 0.5, i + 1.5) x (j - 0.5, j + 1.5) — the union over the triangle of
 * the 2x2 bilinear footprints. (Lookups clamp to the atlas edge; charts keep 2 texels of padding,
 * so no footprint reaches past it.) Writes up to `max` texel indices (y·width + x); returns the count. */
static inline uint32_t stab_used_texels(const double uv[3][2], uint32_t w, uint32_t h, uint32_t *out, uint32_t max) {
    double t[3][2];
    for (int k = 0; k < 3; ++k) {
        t[k][0] = uv[k][0] * w;
        t[k][1] = uv[k][1] * h;
    }
    double mnx = fmin(fmin(t[0][0], t[1][0]), t[2][0]), mxx = fmax(fmax(t[0][0], t[1][0]), t[2][0]);
    double mny = fmin(fmin(t[0][1], t[1][1]), t[2][1]), mxy = fmax(fmax(t[0][1], t[1][1]), t[2][1]);
    long i0 = (long)floor(mnx - 1.5), i1 = (long)ceil(mxx + 0.5), j0 = (long)floor(mny - 1.5), j1 = (long)ceil(mxy + 0.5);
    uint32_t n = 0;
    for (long j = j0 < 0 ? 0 : j0; j <= j1 && j < (long)h; ++j)
        for (long i = i0 < 0 ? 0 : i0; i <= i1 && i < (long)w; ++i)
            if (stab_tri_box_open((const double(*)[2])t, i - 0.5, i + 1.5, j - 0.5, j + 1.5) && n < max)
                out[n++] = (uint32_t)(j * (long)w + i);
    return n;
}

/* Brute-force first hit of the ray o + t d (t > tmin) over all of the bake's triangles (Möller-
 * Trumbore in double). Returns the hit distance (INFINITY for none); *back_face tells whether the
 * ray met the triangle's back (d · geometric normal > 0; front faces are counter-clockwise). */
static inline double stab_ray_first_hit(const glow_bake_geometry *g, const double o[3], const double d[3], double tmin,
                                 bool *back_face) {
    double best = INFINITY;
    *back_face = false;
    for (uint32_t t = 0; t < g->triangle_count; ++t) {
        double p[3][3], uv[3][2];
        stab_triangle(g, t, p, uv);
        double e1[3], e2[3], s[3], pv[3], qv[3];
        for (int a = 0; a < 3; ++a) {
            e1[a] = p[1][a] - p[0][a];
            e2[a] = p[2][a] - p[0][a];
            s[a] = o[a] - p[0][a];
        }
        pv[0] = d[1] * e2[2] - d[2] * e2[1];
        pv[1] = d[2] * e2[0] - d[0] * e2[2];
        pv[2] = d[0] * e2[1] - d[1] * e2[0];
        double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
        if (fabs(det) < 1e-14) continue;
        double inv = 1.0 / det, u = (s[0] * pv[0] + s[1] * pv[1] + s[2] * pv[2]) * inv;
        if (u < 0.0 || u > 1.0) continue;
        qv[0] = s[1] * e1[2] - s[2] * e1[1];
        qv[1] = s[2] * e1[0] - s[0] * e1[2];
        qv[2] = s[0] * e1[1] - s[1] * e1[0];
        double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) * inv;
        if (v < 0.0 || u + v > 1.0) continue;
        double tt = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
        if (tt > tmin && tt < best) {
            best = tt;
            *back_face = det < 0.0; /* det = -d · (e1 x e2): negative when d runs along the normal */
        }
    }
    return best;
}

#endif /* GLOW_TESTS_STABILITY_COMMON_H */
