/* test_caches.c — cache placement (PIC 4.4, caches.c): no grid cache inside solid geometry, grid
 * caches everywhere in a room's air, lightmap caches on their triangles, texels under a box
 * invalid and filled, every texel a bilinear lookup inside a triangle reads is non-empty, the
 * mesh's own UV set is followed, surfel feedback is valid, target counts are met and the result is
 * the same for 1 and 3 threads. Scenes are built by hand (no dependency on the importer). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake/bake_format.h"
#include "pc_internal.h"

/* ------------------------------------------------------------------ scene building */
typedef struct builder {
    uint32_t n, cap;
    float (*pos)[3];
} builder;

static void b_tri(builder *b, const double p0[3], const double p1[3], const double p2[3]) {
    if (b->n == b->cap) {
        b->cap = b->cap ? 2 * b->cap : 256;
        b->pos = realloc(b->pos, (size_t)b->cap * 3 * sizeof *b->pos);
        assert_non_null(b->pos);
    }
    const double *p[3] = {p0, p1, p2};
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) b->pos[3 * (size_t)b->n + (size_t)k][a] = (float)p[k][a];
    b->n++;
}

/* nu x nv quads spanning o + s*eu + t*ev; front side = eu x ev. */
static void b_grid(builder *b, const double o[3], const double eu[3], const double ev[3], int nu, int nv) {
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            double q[4][3];
            for (int a = 0; a < 3; ++a) {
                q[0][a] = o[a] + eu[a] * i / nu + ev[a] * j / nv;
                q[1][a] = o[a] + eu[a] * (i + 1) / nu + ev[a] * j / nv;
                q[2][a] = o[a] + eu[a] * (i + 1) / nu + ev[a] * (j + 1) / nv;
                q[3][a] = o[a] + eu[a] * i / nu + ev[a] * (j + 1) / nv;
            }
            b_tri(b, q[0], q[1], q[2]);
            b_tri(b, q[0], q[2], q[3]);
        }
}

/* Axis-aligned box, faces outward (a solid block) or inward (a room), each face sub x sub quads.
 * Face order: -x, +x, -y, +y, -z, +z. */
static void b_box(builder *b, const double lo[3], const double hi[3], bool outward, int sub) {
    double X[3] = {hi[0] - lo[0], 0, 0}, Y[3] = {0, hi[1] - lo[1], 0}, Z[3] = {0, 0, hi[2] - lo[2]};
    double hx[3] = {hi[0], lo[1], lo[2]}, hy[3] = {lo[0], hi[1], lo[2]}, hz[3] = {lo[0], lo[1], hi[2]};
    const double *faces[6][3] = {{lo, Z, Y}, {hx, Y, Z}, {lo, X, Z}, {hy, Z, X}, {lo, Y, X}, {hz, X, Y}};
    for (int f = 0; f < 6; ++f)
        if (outward)
            b_grid(b, faces[f][0], faces[f][1], faces[f][2], sub, sub);
        else
            b_grid(b, faces[f][0], faces[f][2], faces[f][1], sub, sub);
}

static void b_finish(builder *b, glow__scene *s) {
    memset(s, 0, sizeof *s);
    s->tri_count = b->n;
    s->pos = b->pos;
    s->nrm = calloc(3 * (size_t)b->n, sizeof *s->nrm);
    s->tri_material = calloc(b->n, sizeof *s->tri_material);
    assert_non_null(s->nrm);
    assert_non_null(s->tri_material);
    for (int a = 0; a < 3; ++a) {
        s->bounds_min[a] = INFINITY;
        s->bounds_max[a] = -INFINITY;
    }
    double area = 0.0;
    for (uint32_t t = 0; t < b->n; ++t) {
        float(*p)[3] = s->pos + 3 * (size_t)t;
        double e1[3], e2[3], n[3];
        for (int a = 0; a < 3; ++a) {
            e1[a] = (double)p[1][a] - p[0][a];
            e2[a] = (double)p[2][a] - p[0][a];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        area += 0.5 * l;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) {
                s->nrm[3 * (size_t)t + (size_t)k][a] = l > 0 ? (float)(n[a] / l) : 0.0f;
                if (p[k][a] < s->bounds_min[a]) s->bounds_min[a] = p[k][a];
                if (p[k][a] > s->bounds_max[a]) s->bounds_max[a] = p[k][a];
            }
    }
    s->area = area;
    s->material_count = 1;
    s->materials = calloc(1, sizeof *s->materials);
    assert_non_null(s->materials);
    s->materials[0].albedo[0] = s->materials[0].albedo[1] = s->materials[0].albedo[2] = 0.5f;
    s->materials[0].texture = -1;
    snprintf(s->source, sizeof s->source, "test");
    b->pos = NULL;
    b->n = b->cap = 0;
}

static void scene_free(glow__scene *s) {
    free(s->pos);
    free(s->nrm);
    free(s->uv1);
    free(s->tri_material);
    free(s->materials);
    memset(s, 0, sizeof *s);
}

/* Deterministic surfels: `count` points at LCG-random barycentrics of area-random triangles. */
static void make_surfels(const glow__scene *s, uint32_t count, glow__surfels *out) {
    out->count = count;
    out->s = calloc(count, sizeof *out->s);
    assert_non_null(out->s);
    out->area = (float)(s->area / count);
    uint64_t rng = 12345;
#define NEXT() ((rng = rng * 6364136223846793005ull + 1442695040888963407ull) >> 11) * (1.0 / 9007199254740992.0)
    for (uint32_t i = 0; i < count; ++i) {
        glow__surfel *sf = &out->s[i];
        sf->area = out->area;
        sf->tri = (uint32_t)(NEXT() * s->tri_count) % s->tri_count;
        double u = NEXT(), v = NEXT();
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        sf->bary[0] = (float)u;
        sf->bary[1] = (float)v;
        const float(*p)[3] = s->pos + 3 * (size_t)sf->tri;
        for (int a = 0; a < 3; ++a) {
            sf->pos[a] = (float)((1 - u - v) * p[0][a] + u * p[1][a] + v * p[2][a]);
            sf->nrm[a] = s->nrm[3 * (size_t)sf->tri][a];
        }
    }
#undef NEXT
}

/* ------------------------------------------------------------------ geometry helpers */
static void tri_normal(const glow__scene *s, uint32_t t, double n[3]) {
    const float(*p)[3] = s->pos + 3 * (size_t)t;
    double e1[3], e2[3];
    for (int a = 0; a < 3; ++a) {
        e1[a] = (double)p[1][a] - p[0][a];
        e2[a] = (double)p[2][a] - p[0][a];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3; ++a) n[a] /= l;
}

/* Distance from q to triangle t (3-D): plane distance when the projection is inside, else the
 * nearest edge (dense sampling is plenty for a test). */
static double dist_to_tri(const glow__scene *s, uint32_t t, const double q[3]) {
    const float(*p)[3] = s->pos + 3 * (size_t)t;
    double n[3];
    tri_normal(s, t, n);
    double d = 0;
    for (int a = 0; a < 3; ++a) d += (q[a] - p[0][a]) * n[a];
    double r[3];
    for (int a = 0; a < 3; ++a) r[a] = q[a] - d * n[a];
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
        const float *a0 = p[k], *a1 = p[(k + 1) % 3];
        double e[3] = {(double)a1[0] - a0[0], (double)a1[1] - a0[1], (double)a1[2] - a0[2]};
        double w[3] = {r[0] - a0[0], r[1] - a0[1], r[2] - a0[2]};
        double c[3] = {e[1] * w[2] - e[2] * w[1], e[2] * w[0] - e[0] * w[2], e[0] * w[1] - e[1] * w[0]};
        if (c[0] * n[0] + c[1] * n[1] + c[2] * n[2] < -1e-12) inside = false;
    }
    if (inside) return fabs(d);
    double best = INFINITY;
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i <= 1000; ++i) {
            double f = i / 1000.0, e[3];
            for (int a = 0; a < 3; ++a) e[a] = p[k][a] + f * (p[(k + 1) % 3][a] - p[k][a]) - q[a];
            best = fmin(best, sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]));
        }
    return best;
}

/* Distance in texels from texel centre (x, y) to triangle t's UV triangle. */
static double uv_dist(const glow__caches *c, uint32_t t, double x, double y) {
    double tc[3][2];
    for (int k = 0; k < 3; ++k) {
        tc[k][0] = c->lm_uv[3 * (size_t)t + (size_t)k][0] * (double)c->lm_width;
        tc[k][1] = c->lm_uv[3 * (size_t)t + (size_t)k][1] * (double)c->lm_height;
    }
    double w[3];
    for (int k = 0; k < 3; ++k) {
        const double *a = tc[(k + 1) % 3], *b = tc[(k + 2) % 3];
        w[k] = (a[0] - x) * (b[1] - y) - (a[1] - y) * (b[0] - x);
    }
    if ((w[0] >= 0 && w[1] >= 0 && w[2] >= 0) || (w[0] <= 0 && w[1] <= 0 && w[2] <= 0)) return 0.0;
    double best = INFINITY;
    for (int k = 0; k < 3; ++k) {
        const double *a = tc[k], *b = tc[(k + 1) % 3];
        double ex = b[0] - a[0], ey = b[1] - a[1], l2 = ex * ex + ey * ey;
        double s = l2 > 0 ? fmin(fmax(((x - a[0]) * ex + (y - a[1]) * ey) / l2, 0.0), 1.0) : 0.0;
        best = fmin(best, hypot(a[0] + s * ex - x, a[1] + s * ey - y));
    }
    return best;
}

static uint32_t map_at(const glow__caches *c, double u, double v) {
    long x = (long)floor(u * c->lm_width), y = (long)floor(v * c->lm_height);
    if (x < 0) x = 0;
    if (y < 0) y = 0;
    if (x >= (long)c->lm_width) x = (long)c->lm_width - 1;
    if (y >= (long)c->lm_height) y = (long)c->lm_height - 1;
    return c->lm_map[(size_t)y * c->lm_width + (size_t)x];
}

/* Every texel a bilinear lookup (texel centres at (x+0.5)/w, clamped) at points inside any
 * triangle reads is non-empty. */
static void check_bilinear(const glow__caches *c, const glow__scene *s) {
    const int N = 12;
    for (uint32_t t = 0; t < s->tri_count; ++t) {
        const float(*uv)[2] = c->lm_uv + 3 * (size_t)t;
        for (int i = 0; i <= N; ++i)
            for (int j = 0; i + j <= N; ++j) {
                double b1 = (double)i / N, b2 = (double)j / N, b0 = 1.0 - b1 - b2;
                double u = b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0];
                double v = b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1];
                double fx = u * c->lm_width - 0.5, fy = v * c->lm_height - 0.5;
                long x0 = (long)floor(fx), y0 = (long)floor(fy);
                for (long dy = 0; dy <= 1; ++dy)
                    for (long dx = 0; dx <= 1; ++dx) {
                        long x = x0 + dx, y = y0 + dy;
                        if (x < 0) x = 0;
                        if (y < 0) y = 0;
                        if (x >= (long)c->lm_width) x = (long)c->lm_width - 1;
                        if (y >= (long)c->lm_height) y = (long)c->lm_height - 1;
                        uint32_t m = c->lm_map[(size_t)y * c->lm_width + (size_t)x];
                        if (m == GLOW_MAP_EMPTY)
                            fail_msg("triangle %u: bilinear lookup at (%g, %g) reads empty texel %ld,%ld", t, u, v, x, y);
                        assert_true((m & GLOW_MAP_INDEX_MASK) < c->count);
                    }
            }
    }
}

/* Structural invariants of any result. */
/* The refined grid (grid_fine.c): bricks only in cells below the last layer, each named once; every
 * brick corner is EMPTY or a grid cache sitting exactly on that corner of the fine lattice (a coarse
 * cache at coarse corners, a fine one elsewhere); every fine cache is some brick's corner, no two at
 * one point. */
static void check_refined(const glow__caches *c, uint32_t coarse) {
    const uint32_t *d = c->grid_dims, R = c->grid_refine, side = R + 1, per = side * side * side;
    const uint32_t cells = d[0] * d[1] * d[2];
    const float fs = c->grid_spacing / (float)R;
    assert_true(R >= 2 && c->grid_brick_count > 0);
    uint32_t named = 0;
    uint8_t *seen = calloc(c->grid_fine_count + 1, 1);
    for (uint32_t k = 0; k < cells; ++k) {
        const uint32_t b = c->grid_brick_of_cell[k];
        if (b == GLOW_MAP_EMPTY) continue;
        ++named;
        const uint32_t x = k % d[0], y = (k / d[0]) % d[1], z = k / (d[0] * d[1]);
        assert_true(b < c->grid_brick_count && x + 1 < d[0] && y + 1 < d[1] && z + 1 < d[2]);
        uint32_t caches_here = 0;
        for (uint32_t q = 0; q < per; ++q) {
            const uint32_t e = c->grid_bricks[(size_t)b * per + q];
            if (e == GLOW_MAP_EMPTY) continue;
            ++caches_here;
            assert_true(e < c->grid_cache_count);
            const uint32_t g[3] = {x * R + q % side, y * R + (q / side) % side, z * R + q / (side * side)};
            for (int a = 0; a < 3; ++a)
                if (fabsf(c->caches[e].pos[a] - (c->grid_origin[a] + fs * (float)g[a])) > 1e-4f * (1.0f + c->grid_spacing))
                    fail_msg("brick %u corner %u: cache %u at %g, not on the fine lattice (%g)", b, q, e,
                             (double)c->caches[e].pos[a], (double)(c->grid_origin[a] + fs * (float)g[a]));
            const bool at_coarse = g[0] % R == 0 && g[1] % R == 0 && g[2] % R == 0;
            assert_true(at_coarse == (e < coarse));
            if (e >= coarse) seen[e - coarse] = 1;
        }
        assert_true(caches_here > 0); /* bricks without a cache are dropped */
    }
    assert_int_equal(named, c->grid_brick_count);
    for (uint32_t i = 0; i < c->grid_fine_count; ++i) assert_true(seen[i]);
    free(seen);
    for (uint32_t i = coarse + 1; i < c->grid_cache_count; ++i) /* one cache a point */
        assert_true(c->caches[i].pos[0] != c->caches[i - 1].pos[0] || c->caches[i].pos[1] != c->caches[i - 1].pos[1] ||
                    c->caches[i].pos[2] != c->caches[i - 1].pos[2]);
}

static void check_structure(const glow__caches *c, const glow__scene *s, const glow__surfels *sf) {
    assert_int_equal(c->count, c->grid_cache_count + c->lm_cache_count);
    const uint32_t cells = c->grid_dims[0] * c->grid_dims[1] * c->grid_dims[2];
    const uint32_t coarse = c->grid_cache_count - c->grid_fine_count;
    assert_int_equal(cells, coarse + c->grid_inside);
    if (c->grid_refine) check_refined(c, coarse);
    for (uint32_t i = 0; i < coarse; ++i) {
        const glow__cache *ca = &c->caches[i];
        assert_int_equal(ca->kind, GLOW_CACHE_KIND_GRID);
        assert_true(ca->texel < cells);
        assert_int_equal(c->grid_map[ca->texel], i);
        assert_true(ca->nrm[0] == 0.0f && ca->nrm[1] == 0.0f && ca->nrm[2] == 0.0f);
        uint32_t x = ca->texel % c->grid_dims[0], y = (ca->texel / c->grid_dims[0]) % c->grid_dims[1],
                 z = ca->texel / (c->grid_dims[0] * c->grid_dims[1]);
        assert_true(fabsf(ca->pos[0] - (c->grid_origin[0] + c->grid_spacing * (float)x)) < 1e-5f);
        assert_true(fabsf(ca->pos[1] - (c->grid_origin[1] + c->grid_spacing * (float)y)) < 1e-5f);
        assert_true(fabsf(ca->pos[2] - (c->grid_origin[2] + c->grid_spacing * (float)z)) < 1e-5f);
        if (i) assert_true(ca->texel > c->caches[i - 1].texel);
    }
    for (uint32_t k = 0; k < cells; ++k) {
        uint32_t m = c->grid_map[k];
        if (m == GLOW_MAP_EMPTY) continue;
        if (m & GLOW_MAP_COPY_BIT) assert_true((m & GLOW_MAP_INDEX_MASK) < c->grid_cache_count);
        else assert_true(m < c->grid_cache_count && c->caches[m].texel == k);
    }
    const size_t texels = (size_t)c->lm_width * c->lm_height;
    assert_true(c->lm_width % 4 == 0 && c->lm_height % 4 == 0);
    for (uint32_t i = c->grid_cache_count; i < c->count; ++i) {
        const glow__cache *ca = &c->caches[i];
        assert_int_equal(ca->kind, GLOW_CACHE_KIND_LIGHTMAP);
        assert_true(ca->texel < texels);
        assert_int_equal(c->lm_map[ca->texel], i);
        assert_true(fabsf(ca->nrm[0] * ca->nrm[0] + ca->nrm[1] * ca->nrm[1] + ca->nrm[2] * ca->nrm[2] - 1.0f) < 1e-4f);
        if (i > c->grid_cache_count) assert_true(ca->texel > c->caches[i - 1].texel);
    }
    for (size_t k = 0; k < texels; ++k) {
        uint32_t m = c->lm_map[k];
        if (m == GLOW_MAP_EMPTY) continue;
        uint32_t idx = m & GLOW_MAP_INDEX_MASK;
        assert_true(idx >= c->grid_cache_count && idx < c->count);
        if (!(m & GLOW_MAP_COPY_BIT)) assert_true(c->caches[idx].texel == k);
    }
    for (size_t i = 0; i < 3 * (size_t)s->tri_count; ++i)
        assert_true(c->lm_uv[i][0] >= 0.0f && c->lm_uv[i][0] <= 1.0f && c->lm_uv[i][1] >= 0.0f &&
                    c->lm_uv[i][1] <= 1.0f);
    if (sf) {
        assert_non_null(c->surfel_feedback);
        for (uint32_t i = 0; i < sf->count; ++i) assert_true(c->surfel_feedback[i] < c->count);
    }
}

static glow__rt *make_rt(const glow__scene *s) {
    glow__log log = {0};
    glow__rt *rt = NULL;
    assert_int_equal(glow__rt_create(s, &log, &rt), GLOW_OK);
    return rt;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------------ tests */
static const double BOX_LO[3] = {0.6, 0.0, 0.6}, BOX_HI[3] = {1.2, 0.6, 1.2};

/* A closed 2 m room (faces inward) with a closed block (faces outward) standing on its floor. */
static void room_with_box(glow__scene *s) {
    builder b = {0};
    b_box(&b, (double[3]){0, 0, 0}, (double[3]){2, 2, 2}, false, 2);
    b_box(&b, BOX_LO, BOX_HI, true, 1);
    b_finish(&b, s);
}

static bool in_box(const float p[3], double margin) {
    for (int a = 0; a < 3; ++a)
        if (!(p[a] > BOX_LO[a] + margin && p[a] < BOX_HI[a] - margin)) return false;
    return true;
}

static void test_room_with_box(void **state) {
    (void)state;
    glow__scene s;
    room_with_box(&s);
    glow__rt *rt = make_rt(&s);
    glow__surfels sf;
    make_surfels(&s, 3000, &sf);
    glow__pool *pool = glow__pool_create(2);
    glow__log log = {0};
    glow__cache_settings set = {.grid_spacing = 0.1f, .texel_density = 20.0f};
    glow__caches c;
    double t0 = now();
    assert_int_equal(glow__caches_build(&s, rt, &sf, &set, pool, &log, &c), GLOW_OK);
    double secs = now() - t0;
    check_structure(&c, &s, &sf);

    /* grid: 20^3 cells at centres 0.05 + 0.1k; the 6x6x6 centres inside the block are rejected */
    assert_int_equal(c.grid_dims[0], 20);
    assert_int_equal(c.grid_dims[1], 20);
    assert_int_equal(c.grid_dims[2], 20);
    assert_true(fabsf(c.grid_origin[0] - 0.05f) < 1e-5f && fabsf(c.grid_origin[1] - 0.05f) < 1e-5f);
    for (uint32_t i = 0; i < c.grid_cache_count; ++i)
        if (in_box(c.caches[i].pos, 0.0)) fail_msg("grid cache %u at %g %g %g is inside the block", i,
                                                   (double)c.caches[i].pos[0], (double)c.caches[i].pos[1],
                                                   (double)c.caches[i].pos[2]);
    uint32_t air = 0;
    for (uint32_t k = 0; k < 8000; ++k) {
        float p[3] = {0.05f + 0.1f * (float)(k % 20), 0.05f + 0.1f * (float)((k / 20) % 20), 0.05f + 0.1f * (float)(k / 400)};
        bool solid = in_box(p, -1e-3);
        uint32_t m = c.grid_map[k];
        if (!solid) {
            if (m == GLOW_MAP_EMPTY || (m & GLOW_MAP_COPY_BIT)) fail_msg("air point %g %g %g is no cache", (double)p[0], (double)p[1], (double)p[2]);
            ++air;
        } else {
            /* inside: a copy of a grid cache at most 3 cells away (3 dilation layers reach the block's core) */
            assert_true(m != GLOW_MAP_EMPTY && (m & GLOW_MAP_COPY_BIT));
            const float *q = c.caches[m & GLOW_MAP_INDEX_MASK].pos;
            for (int a = 0; a < 3; ++a) assert_true(fabsf(q[a] - p[a]) < 0.3f + 1e-4f);
        }
    }
    assert_int_equal(c.grid_cache_count, air);
    assert_int_equal(c.grid_inside, 216);

    /* lightmap caches lie on their triangles, lifted along the normal */
    double diag = sqrt(12.0), off = 1e-4 * diag;
    for (uint32_t i = c.grid_cache_count; i < c.count; ++i) {
        const glow__cache *ca = &c.caches[i];
        double q[3];
        for (int a = 0; a < 3; ++a) q[a] = (double)ca->pos[a] - off * ca->nrm[a];
        double tx = ca->texel % c.lm_width + 0.5, ty = ca->texel / c.lm_width + 0.5;
        bool found = false;
        for (uint32_t t = 0; t < s.tri_count && !found; ++t) {
            double n[3];
            tri_normal(&s, t, n);
            if (n[0] * ca->nrm[0] + n[1] * ca->nrm[1] + n[2] * ca->nrm[2] < 0.9999) continue;
            if (dist_to_tri(&s, t, q) > 1e-5) continue;
            if (uv_dist(&c, t, tx, ty) > 0.7072) continue; /* the texel overlaps the triangle */
            found = true;
        }
        if (!found) fail_msg("lightmap cache %u (texel %u) lies on no triangle that covers its texel", i, ca->texel);
        if (in_box(ca->pos, 2 * off)) fail_msg("lightmap cache %u is inside the block", i);
    }

    /* floor texels well under the block are invalid and filled with copies */
    uint32_t under = 0;
    for (uint32_t t = 0; t < s.tri_count; ++t) {
        double n[3];
        tri_normal(&s, t, n);
        const float(*p)[3] = s.pos + 3 * (size_t)t;
        if (!(n[1] > 0.999 && p[0][1] == 0.0f)) continue; /* floor triangles */
        for (int i = 0; i <= 40; ++i)
            for (int j = 0; i + j <= 40; ++j) {
                double b1 = i / 40.0, b2 = j / 40.0, b0 = 1 - b1 - b2;
                float q[3];
                for (int a = 0; a < 3; ++a) q[a] = (float)(b0 * p[0][a] + b1 * p[1][a] + b2 * p[2][a]);
                q[1] = 0.3f;
                if (!in_box(q, 0.1)) continue; /* > 2 texels inside the footprint */
                const float(*uv)[2] = c.lm_uv + 3 * (size_t)t;
                uint32_t m = map_at(&c, b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0],
                                    b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1]);
                assert_true(m != GLOW_MAP_EMPTY);
                if (!(m & GLOW_MAP_COPY_BIT)) fail_msg("floor point %g %g under the block has a cache", (double)q[0], (double)q[2]);
                ++under;
            }
    }
    assert_true(under > 50);
    /* the block covers 0.36 m² of floor: about 12x12 texels */
    assert_true(c.lm_invalid >= 100 && c.lm_invalid <= 250);
    check_bilinear(&c, &s);

    /* surfel feedback: the texel's own cache where there is one; never far away */
    uint32_t direct = 0;
    for (uint32_t i = 0; i < sf.count; ++i) {
        const glow__surfel *su = &sf.s[i];
        const float(*uv)[2] = c.lm_uv + 3 * (size_t)su->tri;
        double b1 = su->bary[0], b2 = su->bary[1], b0 = 1 - b1 - b2;
        uint32_t m = map_at(&c, b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0], b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1]);
        assert_true(m != GLOW_MAP_EMPTY);
        assert_int_equal(c.surfel_feedback[i], m & GLOW_MAP_INDEX_MASK);
        direct += !(m & GLOW_MAP_COPY_BIT);
        const float *q = c.caches[c.surfel_feedback[i]].pos;
        double d = sqrt(pow(q[0] - su->pos[0], 2) + pow(q[1] - su->pos[1], 2) + pow(q[2] - su->pos[2], 2));
        if (d > 0.45) fail_msg("surfel %u re-emits the light of a cache %g m away", i, d);
    }
    assert_true(direct > sf.count * 9 / 10);
    print_message("room+box: grid %ux%ux%u (%u caches, %u inside), lightmap %ux%u (%u caches, %u invalid, %u charts) "
                  "in %.0f ms\n", c.grid_dims[0], c.grid_dims[1], c.grid_dims[2], c.grid_cache_count, c.grid_inside,
                  c.lm_width, c.lm_height, c.lm_cache_count, c.lm_invalid, c.chart_count, 1e3 * secs);
    glow__caches_free(&c);
    glow__pool_destroy(pool);
    free(sf.s);
    glow__rt_destroy(rt);
    scene_free(&s);
}

/* A rug entirely under the block: all its texels are invalid and none is near a valid texel of
 * its chart, so its map stays empty and its surfels fall back to the nearest grid cache. */
static void test_feedback_falls_back_to_grid(void **state) {
    (void)state;
    builder b = {0};
    b_box(&b, (double[3]){0, 0, 0}, (double[3]){2, 2, 2}, false, 1);
    b_box(&b, BOX_LO, BOX_HI, true, 1);
    uint32_t rug = b.n;
    b_grid(&b, (double[3]){0.7, 0.01, 0.7}, (double[3]){0, 0, 0.4}, (double[3]){0.4, 0, 0}, 1, 1); /* faces +y */
    glow__scene s;
    b_finish(&b, &s);
    glow__rt *rt = make_rt(&s);
    glow__surfels sf;
    make_surfels(&s, 4000, &sf);
    glow__log log = {0};
    glow__cache_settings set = {.grid_spacing = 0.25f, .texel_density = 20.0f};
    glow__caches c;
    assert_int_equal(glow__caches_build(&s, rt, &sf, &set, NULL, &log, &c), GLOW_OK);
    check_structure(&c, &s, &sf);
    uint32_t on_rug = 0;
    for (uint32_t i = 0; i < sf.count; ++i) {
        const glow__surfel *su = &sf.s[i];
        if (su->tri < rug) continue;
        ++on_rug;
        const float(*uv)[2] = c.lm_uv + 3 * (size_t)su->tri;
        double b1 = su->bary[0], b2 = su->bary[1], b0 = 1 - b1 - b2;
        assert_int_equal(map_at(&c, b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0],
                                b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1]),
                         GLOW_MAP_EMPTY);
        /* brute force: the nearest grid cache (ties: lowest index) */
        uint32_t best = UINT32_MAX;
        double bd = INFINITY;
        for (uint32_t k = 0; k < c.grid_cache_count; ++k) {
            const float *q = c.caches[k].pos;
            double d = pow((double)q[0] - su->pos[0], 2) + pow((double)q[1] - su->pos[1], 2) +
                       pow((double)q[2] - su->pos[2], 2);
            if (d < bd) {
                bd = d;
                best = k;
            }
        }
        assert_int_equal(c.surfel_feedback[i], best);
        assert_int_equal(c.caches[best].kind, GLOW_CACHE_KIND_GRID);
        assert_false(in_box(c.caches[best].pos, 0.0));
    }
    assert_true(on_rug > 20);
    glow__caches_free(&c);
    free(sf.s);
    glow__rt_destroy(rt);
    scene_free(&s);
}

/* A wall poking through the floor: floor texels inside the wall's solid are invalid. */
static void test_wall_through_floor(void **state) {
    (void)state;
    builder b = {0};
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){0, 0, 2}, (double[3]){2, 0, 0}, 1, 1); /* floor, faces +y */
    b_box(&b, (double[3]){0.8, -0.5, 0.2}, (double[3]){1.2, 1.0, 1.8}, true, 1);        /* solid wall */
    glow__scene s;
    b_finish(&b, &s);
    glow__rt *rt = make_rt(&s);
    glow__log log = {0};
    glow__cache_settings set = {.grid_spacing = 0.25f, .texel_density = 20.0f};
    glow__caches c;
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, NULL, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    assert_null(c.surfel_feedback);
    /* 0.4 x 1.6 m of floor inside the wall: ~8 x 32 texels */
    /* Invalid: the floor inside the wall (0.4 x 1.6 m, ~8 x 32 texels) and the wall's sides below
     * the floor, which see the floor's back (2 x 1.6 x 0.5 m + 2 x 0.4 x 0.5 m, ~800 texels). The
     * wall's bottom face sees nothing and stays; so do the end faces' texels that see past the
     * floor's edge. */
    assert_true(c.lm_invalid >= 800 && c.lm_invalid <= 1200);
    for (uint32_t i = c.grid_cache_count; i < c.count; ++i) {
        const float *p = c.caches[i].pos;
        if (p[0] > 0.81f && p[0] < 1.19f && p[2] > 0.21f && p[2] < 1.79f && p[1] < 0.99f && p[1] > -0.49f)
            fail_msg("cache %u at %g %g %g is inside the wall", i, (double)p[0], (double)p[1], (double)p[2]);
        /* well under the floor (near its edges points see past it and may stay) */
        if (p[1] < -0.01f && p[1] > -0.3f && p[2] > 0.5f && p[2] < 1.5f)
            fail_msg("cache %u at %g %g %g is below the floor", i, (double)p[0], (double)p[1], (double)p[2]);
    }
    check_bilinear(&c, &s);
    glow__caches_free(&c);
    glow__rt_destroy(rt);
    scene_free(&s);
}

/* With a second UV set the texels follow it: four walls, each given its own quarter of [0,1]². */
static void test_uv1_followed(void **state) {
    (void)state;
    builder b = {0};
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){0, 0, 2}, (double[3]){2, 0, 0}, 1, 1);  /* floor  +y */
    b_grid(&b, (double[3]){0, 2, 0}, (double[3]){2, 0, 0}, (double[3]){0, 0, 2}, 1, 1);  /* ceiling -y */
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){2, 0, 0}, (double[3]){0, 2, 0}, 1, 1);  /* back wall +z */
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){0, 2, 0}, (double[3]){0, 0, 2}, 1, 1);  /* left wall +x */
    glow__scene s;
    b_finish(&b, &s);
    s.uv1 = malloc(3 * (size_t)s.tri_count * sizeof *s.uv1);
    assert_non_null(s.uv1);
    /* corners of b_grid quads: q0 (0,0) q1 (1,0) q2 (1,1) q3 (0,1); triangles (q0,q1,q2), (q0,q2,q3) */
    const float local[6][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
    for (uint32_t q = 0; q < 4; ++q)
        for (int k = 0; k < 6; ++k) {
            s.uv1[6 * q + (uint32_t)k][0] = 0.5f * (float)(q % 2) + 0.05f + 0.4f * local[k][0];
            s.uv1[6 * q + (uint32_t)k][1] = 0.5f * (float)(q / 2) + 0.05f + 0.4f * local[k][1];
        }
    glow__rt *rt = make_rt(&s);
    glow__log log = {0};
    glow__cache_settings set = {.grid_spacing = 0.5f, .target_lightmap = 3000};
    glow__caches c;
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, NULL, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    assert_int_equal(c.chart_count, 0);
    assert_int_equal(c.lm_width, c.lm_height);
    for (size_t i = 0; i < 3 * (size_t)s.tri_count; ++i) {
        assert_true(fabsf(c.lm_uv[i][0] - s.uv1[i][0]) <= 1.0f / 65535.0f);
        assert_true(fabsf(c.lm_uv[i][1] - s.uv1[i][1]) <= 1.0f / 65535.0f);
    }
    /* 4 x 0.16 of the atlas covered: about 0.64 * w*h texels */
    double expect = 0.64 * c.lm_width * c.lm_height;
    assert_true(c.lm_cache_count > 0.9 * expect && c.lm_cache_count < 1.15 * expect);
    assert_true(c.lm_cache_count > 1500 && c.lm_cache_count < 6000);
    /* each texel's cache lies on the wall whose quarter holds the texel, at the matching spot */
    for (uint32_t i = c.grid_cache_count; i < c.count; ++i) {
        const glow__cache *ca = &c.caches[i];
        double u = (ca->texel % c.lm_width + 0.5) / c.lm_width, v = (ca->texel / c.lm_width + 0.5) / c.lm_height;
        uint32_t q = (u >= 0.5) + 2u * (v >= 0.5);
        double lu = (u - 0.5 * (q % 2) - 0.05) / 0.4, lv = (v - 0.5 * (q / 2) - 0.05) / 0.4;
        lu = fmin(fmax(lu, 0.0), 1.0);
        lv = fmin(fmax(lv, 0.0), 1.0);
        const float(*p)[3] = s.pos + 3 * (size_t)(2 * q); /* q0, q1, q2 of the quad */
        for (int a = 0; a < 3; ++a) {
            double expect_a = p[0][a] + lu * (p[1][a] - p[0][a]) + lv * (p[2][a] - p[1][a]);
            if (fabs(ca->pos[a] - expect_a) > 2.0 * 2.0 / (0.4 * c.lm_width) + 1e-3)
                fail_msg("texel %u: cache at %g %g %g, expected on quad %u near axis %d = %g", ca->texel,
                         (double)ca->pos[0], (double)ca->pos[1], (double)ca->pos[2], q, a, expect_a);
        }
    }
    check_bilinear(&c, &s);
    glow__caches_free(&c);
    glow__rt_destroy(rt);
    scene_free(&s);
}

/* A closed 2 m Cornell-style room with a short and a tall block: the target counts are met. */
static void cornell(glow__scene *s) {
    builder b = {0};
    b_box(&b, (double[3]){0, 0, 0}, (double[3]){2, 2, 2}, false, 1);
    b_box(&b, (double[3]){0.3, 0, 0.3}, (double[3]){0.9, 0.6, 0.9}, true, 1);
    b_box(&b, (double[3]){1.1, 0, 0.9}, (double[3]){1.7, 1.2, 1.5}, true, 1);
    b_finish(&b, s);
}

static void test_targets(void **state) {
    (void)state;
    glow__scene s;
    cornell(&s);
    glow__rt *rt = make_rt(&s);
    glow__surfels sf;
    make_surfels(&s, 2000, &sf);
    glow__pool *pool = glow__pool_create(2);
    glow__log log = {0};
    glow__cache_settings set = {.target_grid = 2000, .target_lightmap = 8000};
    glow__caches c;
    double t0 = now();
    assert_int_equal(glow__caches_build(&s, rt, &sf, &set, pool, &log, &c), GLOW_OK);
    double secs = now() - t0;
    check_structure(&c, &s, &sf);
    uint32_t cells = c.grid_dims[0] * c.grid_dims[1] * c.grid_dims[2];
    print_message("cornell targets 2000/8000: grid %ux%ux%u spacing %.3f (%u cells, %u caches), lightmap %ux%u at "
                  "%.1f texels/m (%u caches, %u invalid, %u charts) in %.0f ms\n",
                  c.grid_dims[0], c.grid_dims[1], c.grid_dims[2], (double)c.grid_spacing, cells, c.grid_cache_count,
                  c.lm_width, c.lm_height, (double)c.texel_density, c.lm_cache_count, c.lm_invalid, c.chart_count,
                  1e3 * secs);
    assert_true(cells >= 1000 && cells <= 4000);
    assert_true(c.grid_cache_count >= 1000);
    assert_true(c.lm_cache_count + c.lm_invalid >= 4000 && c.lm_cache_count + c.lm_invalid <= 16000);
    /* 6 room faces + 2 x 6 block faces, and the floor cut in two where a block stands on it (charts.c:
     * a chart does not reach across a contact, where both sides would share texels) */
    assert_true(c.chart_count == 19);
    check_bilinear(&c, &s);
    glow__caches_free(&c);
    glow__pool_destroy(pool);
    free(sf.s);
    glow__rt_destroy(rt);
    scene_free(&s);
}

static void test_deterministic_threads(void **state) {
    (void)state;
    glow__scene s;
    cornell(&s);
    glow__rt *rt = make_rt(&s);
    glow__surfels sf;
    make_surfels(&s, 1500, &sf);
    glow__log log = {0};
    glow__cache_settings set = {.target_grid = 1500, .target_lightmap = 5000};
    glow__caches c[2];
    for (int k = 0; k < 2; ++k) {
        glow__pool *pool = glow__pool_create(k ? 3 : 1);
        assert_int_equal(glow__caches_build(&s, rt, &sf, &set, pool, &log, &c[k]), GLOW_OK);
        glow__pool_destroy(pool);
    }
    assert_int_equal(c[0].count, c[1].count);
    assert_int_equal(c[0].grid_cache_count, c[1].grid_cache_count);
    assert_int_equal(c[0].lm_width, c[1].lm_width);
    assert_int_equal(c[0].lm_height, c[1].lm_height);
    assert_int_equal(c[0].lm_invalid, c[1].lm_invalid);
    assert_memory_equal(c[0].caches, c[1].caches, c[0].count * sizeof *c[0].caches);
    assert_memory_equal(c[0].grid_map, c[1].grid_map,
                        (size_t)c[0].grid_dims[0] * c[0].grid_dims[1] * c[0].grid_dims[2] * sizeof(uint32_t));
    assert_memory_equal(c[0].lm_map, c[1].lm_map, (size_t)c[0].lm_width * c[0].lm_height * sizeof(uint32_t));
    assert_memory_equal(c[0].lm_uv, c[1].lm_uv, 3 * (size_t)s.tri_count * sizeof *c[0].lm_uv);
    assert_memory_equal(c[0].surfel_feedback, c[1].surfel_feedback, sf.count * sizeof(uint32_t));
    glow__caches_free(&c[0]);
    glow__caches_free(&c[1]);
    free(sf.s);
    glow__rt_destroy(rt);
    scene_free(&s);
}

/* An open scene (a floor plane and a single-sided screen): grid points that see mostly sky stay. */
static void test_open_scene_keeps_air(void **state) {
    (void)state;
    builder b = {0};
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){0, 0, 4}, (double[3]){4, 0, 0}, 2, 2);  /* floor +y */
    b_grid(&b, (double[3]){1, 0, 2}, (double[3]){2, 0, 0}, (double[3]){0, 3, 0}, 1, 1);  /* screen +z */
    glow__scene s;
    b_finish(&b, &s);
    glow__rt *rt = make_rt(&s);
    glow__log log = {0};
    glow__cache_settings set = {.grid_spacing = 0.5f, .texel_density = 4.0f};
    glow__caches c;
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, NULL, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    /* 8 x 6 x 8 points above the floor. Those that see mostly sky stay, also where part of what
     * they see is the screen's back; only points right behind the screen (it fills about half
     * their view) count as inside it. */
    assert_int_equal(c.grid_dims[0] * c.grid_dims[1] * c.grid_dims[2], 8 * 6 * 8);
    uint32_t kept_far = 0;
    for (uint32_t k = 0; k < 8 * 6 * 8; ++k) {
        float p[3] = {0.25f + 0.5f * (float)(k % 8), 0.25f + 0.5f * (float)((k / 8) % 6), 0.25f + 0.5f * (float)(k / 48)};
        bool cache = !(c.grid_map[k] & GLOW_MAP_COPY_BIT) && c.grid_map[k] != GLOW_MAP_EMPTY;
        bool near_back = p[2] < 2.0f && p[2] > 1.2f && p[0] > 0.9f && p[0] < 3.1f;
        if (!near_back) {
            if (!cache) fail_msg("open-air point %g %g %g was rejected", (double)p[0], (double)p[1], (double)p[2]);
            ++kept_far;
        }
    }
    assert_int_equal(kept_far, 8 * 6 * 8 - 4 * 2 * 6); /* only the 4 x 2 x 6 points behind may go */
    assert_true(c.grid_inside <= 4 * 2 * 6);
    assert_true(c.lm_invalid < 2 * 8 * 2); /* at most a strip of floor right behind the screen */
    glow__caches_free(&c);
    glow__rt_destroy(rt);
    scene_free(&s);
}

/* Linear texel density (texels per m) of triangle t in the atlas. */
static double tri_texel_density(const glow__caches *c, const glow__scene *s, uint32_t t) {
    const float(*q)[2] = c->lm_uv + 3 * (size_t)t;
    const double ua = 0.5 * fabs(((double)q[1][0] - q[0][0]) * ((double)q[2][1] - q[0][1]) -
                                 ((double)q[1][1] - q[0][1]) * ((double)q[2][0] - q[0][0])) *
                      c->lm_width * c->lm_height;
    return sqrt(ua / glow__tri_area(s, t));
}

/* Texel density per chart (caches.c): a 0.3 m slot between two facing walls gets finer texels than an
 * open floor with texel_adapt 4, the same with 1; the lightmap budget holds either way, so the floor's
 * texels get coarser. */
static void test_texel_adapt(void **state) {
    (void)state;
    builder b = {0};
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){0, 0, 10}, (double[3]){10, 0, 0}, 4, 4);   /* floor +y */
    b_grid(&b, (double[3]){30, 10, 0}, (double[3]){0, 2, 0}, (double[3]){0, 0, 10}, 1, 1);  /* wall +x */
    b_grid(&b, (double[3]){30.3, 10, 0}, (double[3]){0, 0, 10}, (double[3]){0, 2, 0}, 1, 1); /* wall -x */
    glow__scene s;
    b_finish(&b, &s);
    glow__rt *rt = make_rt(&s);
    glow__pool *pool = glow__pool_create(2);
    glow__log log = {0};
    double floor_d[2], slot_d[2];
    uint32_t texels[2];
    for (int k = 0; k < 2; ++k) {
        glow__cache_settings set = {.grid_spacing = 4.0f, .target_lightmap = 1500, .texel_adapt = k ? 4.0f : 1.0f,
                                    .adapt_reach = 1.0f};
        glow__caches c;
        assert_int_equal(glow__caches_build(&s, rt, NULL, &set, pool, &log, &c), GLOW_OK);
        check_structure(&c, &s, NULL);
        floor_d[k] = tri_texel_density(&c, &s, 0);
        slot_d[k] = 0.5 * (tri_texel_density(&c, &s, 32) + tri_texel_density(&c, &s, 34));
        texels[k] = c.lm_cache_count + c.lm_invalid;
        print_message("texel_adapt %g: floor %.3f texels/m, slot %.3f (%.2fx), %u texels (density %.3f..%.3f)\n",
                      (double)set.texel_adapt, floor_d[k], slot_d[k], slot_d[k] / floor_d[k], texels[k],
                      (double)c.texel_density, (double)c.texel_density_max);
        assert_true(fabs(floor_d[k] / c.texel_density - 1.0) < 0.02);
        assert_true(c.texel_density_max >= c.texel_density);
        glow__caches_free(&c);
    }
    assert_true(fabs(slot_d[0] / floor_d[0] - 1.0) < 0.02); /* uniform */
    /* facing walls 0.3 m apart see each other through most of their rays within 1 m: f > 0.6, so the
     * area density is > 2.8x and the linear density > 1.67x the floor's */
    assert_true(slot_d[1] / floor_d[1] > 1.67);
    assert_true(slot_d[1] / floor_d[1] <= 2.0 + 1e-3); /* at most sqrt(4) */
    /* the budget is shared: the open floor pays (100 m² of floor, 40 m² of slot at about 3x) */
    assert_true(floor_d[1] < 0.9 * floor_d[0]);
    for (int k = 0; k < 2; ++k) assert_true(texels[k] >= 1500 / 1.2 && texels[k] <= 1500 * 1.2);
    glow__pool_destroy(pool);
    glow__rt_destroy(rt);
    scene_free(&s);
}

/* The grid refined near geometry (grid_fine.c): an 8 x 8 floor with a 1 x 4 x 1 pillar in the middle,
 * fine spacing 0.6 (coarse 1.2). The refined grid's coarse lattice spans the box grown by 0.3 on every
 * side: x, z = -0.8 .. 8.8 (9 points), y = -0.4 .. 4.4 (5 points), 8 x 4 x 8 cells. A cell is a brick
 * when a triangle comes within 0.6 of it: the whole bottom layer (y in [-0.4, 0.8] holds the floor; the
 * next layer is 0.8 above it), and above it only the 2 x 2 columns of cells that hold the pillar
 * (x, z in [2.8, 5.2]; the next cells out are 0.7 from it). So 64 + 3 x 4 bricks. Fine points inside
 * the pillar (x = z = 4.0, y = 0.2 | 1.4 | 2.6 | 3.8) and under the floor are no caches. At the same
 * fine spacing the uniform grid holds more caches; with a budget, the refined grid's points stay
 * within it. */
static void test_grid_refine(void **state) {
    (void)state;
    builder b = {0};
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){0, 0, 8}, (double[3]){8, 0, 0}, 4, 4); /* floor +y */
    b_box(&b, (double[3]){3.5, 0, 3.5}, (double[3]){4.5, 4, 4.5}, true, 2);               /* pillar */
    glow__scene s;
    b_finish(&b, &s);
    glow__rt *rt = make_rt(&s);
    glow__pool *pool = glow__pool_create(2);
    glow__log log = {0};
    glow__cache_settings set = {.grid_spacing = 0.6f, .texel_density = 2.0f, .grid_refine = 2};
    glow__caches c;
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, pool, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    assert_int_equal(c.grid_refine, 2);
    assert_true(fabsf(c.grid_spacing - 1.2f) < 1e-6f);
    assert_int_equal(c.grid_dims[0], 9);
    assert_int_equal(c.grid_dims[1], 5);
    assert_int_equal(c.grid_dims[2], 9);
    assert_true(fabsf(c.grid_origin[0] + 0.8f) < 1e-5f && fabsf(c.grid_origin[1] + 0.4f) < 1e-5f);
    uint32_t layer[4] = {0, 0, 0, 0};
    for (uint32_t z = 0; z < 8; ++z)
        for (uint32_t y = 0; y < 4; ++y)
            for (uint32_t x = 0; x < 8; ++x) {
                const bool brick = c.grid_brick_of_cell[(z * 5 + y) * 9 + x] != GLOW_MAP_EMPTY;
                const bool pillar = (x == 3 || x == 4) && (z == 3 || z == 4);
                if (brick != (y == 0 || pillar))
                    fail_msg("cell (%u, %u, %u): brick %d, expected %d", x, y, z, brick, y == 0 || pillar);
                layer[y] += brick;
            }
    assert_int_equal(layer[0], 64);
    assert_int_equal(layer[1] + layer[2] + layer[3], 12);
    assert_int_equal(c.grid_brick_count, 76);
    assert_true(c.grid_fine_count > 0);
    assert_true(c.grid_fine_inside >= 4); /* the pillar's 4, and those under the floor */
    glow__caches_free(&c);
    /* a budget: no spacing, 600 points; the refined grid's points (coarse + fine, inside ones too) fit
     * (here, where the floor fills the box, the fine spacing comes out no finer than a uniform grid's
     * of the same budget: refining pays in open air, below) */
    set = (glow__cache_settings){.target_grid = 600, .texel_density = 2.0f, .grid_refine = 2};
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, pool, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    assert_int_equal(c.grid_refine, 2);
    const uint32_t points = c.grid_dims[0] * c.grid_dims[1] * c.grid_dims[2] + c.grid_fine_count + c.grid_fine_inside;
    print_message("floor and pillar, budget 600: coarse %ux%ux%u at %g, %u bricks, %u points\n", c.grid_dims[0],
                  c.grid_dims[1], c.grid_dims[2], (double)c.grid_spacing, c.grid_brick_count, points);
    assert_true(points <= 600);
    glow__caches_free(&c);
    glow__rt_destroy(rt);
    scene_free(&s);
    /* Open air: two 0.8 m cubes at opposite corners of a 10 m box, fine spacing 0.4 (coarse 0.8,
     * lattice -0.2 .. 10.2, 13 cells an axis). Each cube is within 0.4 of 2 x 2 x 2 cells (cube A
     * [0.1, 0.9]: cells 0 and 1 along each axis, cell 2 starts 0.1 beyond the margin), so 16 bricks;
     * the uniform grid of the fine spacing has 25³ points, the refined one 14³ + at most 16 x 26 */
    builder b2 = {0};
    b_box(&b2, (double[3]){0.1, 0.1, 0.1}, (double[3]){0.9, 0.9, 0.9}, true, 1);
    b_box(&b2, (double[3]){9.1, 9.1, 9.1}, (double[3]){9.9, 9.9, 9.9}, true, 1);
    b_finish(&b2, &s);
    rt = make_rt(&s);
    set = (glow__cache_settings){.grid_spacing = 0.4f, .texel_density = 2.0f, .grid_refine = 2};
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, pool, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    assert_int_equal(c.grid_dims[0], 14);
    assert_int_equal(c.grid_brick_count, 16);
    const uint32_t refined = c.grid_cache_count;
    glow__caches_free(&c);
    set.grid_refine = 1;
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, pool, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    print_message("two cubes in 10 m: refined grid %u caches, uniform at the same fine spacing %u\n", refined,
                  c.grid_cache_count);
    assert_int_equal(c.grid_dims[0], 25);
    assert_true(refined <= 14 * 14 * 14 + 16 * 26 && refined < c.grid_cache_count / 4);
    glow__caches_free(&c);
    /* ... and at a budget of 3000 points the refined grid is finer near the cubes than the uniform one */
    set = (glow__cache_settings){.target_grid = 3000, .texel_density = 2.0f, .grid_refine = 2};
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, pool, &log, &c), GLOW_OK);
    check_structure(&c, &s, NULL);
    assert_int_equal(c.grid_refine, 2);
    const uint32_t pts = c.grid_dims[0] * c.grid_dims[1] * c.grid_dims[2] + c.grid_fine_count + c.grid_fine_inside;
    const float fine = c.grid_spacing / 2.0f;
    glow__caches_free(&c);
    set.grid_refine = 1;
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, pool, &log, &c), GLOW_OK);
    print_message("two cubes, budget 3000: refined %u points, fine spacing %g; uniform spacing %g\n", pts, (double)fine,
                  (double)c.grid_spacing);
    assert_true(pts <= 3000);
    assert_true(fine < 0.75f * c.grid_spacing);
    glow__caches_free(&c);
    glow__pool_destroy(pool);
    glow__rt_destroy(rt);
    scene_free(&s);
}

static void test_bad_arguments(void **state) {
    (void)state;
    glow__scene s;
    cornell(&s);
    glow__rt *rt = make_rt(&s);
    glow__log log = {0};
    glow__caches c;
    glow__cache_settings set = {.grid_spacing = -1.0f};
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, NULL, &log, &c), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(log.last_error, "test"));
    assert_null(c.caches);
    set.grid_spacing = 0.0f;
    set.texel_density = NAN;
    assert_int_equal(glow__caches_build(&s, rt, NULL, &set, NULL, &log, &c), GLOW_ERROR_INVALID_ARGUMENT);
    set.texel_density = 0.0f;
    assert_int_equal(glow__caches_build(&s, NULL, NULL, &set, NULL, &log, &c), GLOW_ERROR_INVALID_ARGUMENT);
    glow__caches_free(&c);
    glow__caches_free(NULL);
    glow__rt_destroy(rt);
    scene_free(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_room_with_box),   cmocka_unit_test(test_feedback_falls_back_to_grid),
        cmocka_unit_test(test_wall_through_floor),
        cmocka_unit_test(test_uv1_followed),    cmocka_unit_test(test_targets),
        cmocka_unit_test(test_deterministic_threads), cmocka_unit_test(test_open_scene_keeps_air),
        cmocka_unit_test(test_texel_adapt),     cmocka_unit_test(test_grid_refine),    cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
