/* test_surfels.c — k-d tree (kdtree.c) and surfel placement (surfels.c, PIC 4.2).
 * Scenes are built by hand here (no importer): tri_count, pos, nrm, tri_material, materials, area. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pc_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ------------------------------------------------------------------ helpers */
static uint32_t rng_state = 12345u;
static double rnd(void) {
    rng_state = rng_state * 1664525u + 1013904223u;
    return (double)(rng_state >> 8) / 16777216.0;
}

typedef struct test_scene {
    glow__scene sc;
    uint32_t cap;
    glow__material mats[4];
    glow__texture tex;
    float texels[2][12];
} test_scene;

static void ts_init(test_scene *ts, uint32_t cap) {
    memset(ts, 0, sizeof *ts);
    ts->cap = cap;
    ts->sc.pos = calloc(3u * cap, sizeof *ts->sc.pos);
    ts->sc.nrm = calloc(3u * cap, sizeof *ts->sc.nrm);
    ts->sc.tri_material = calloc(cap, sizeof *ts->sc.tri_material);
    assert_non_null(ts->sc.pos);
    assert_non_null(ts->sc.nrm);
    assert_non_null(ts->sc.tri_material);
    for (int m = 0; m < 4; ++m) {
        snprintf(ts->mats[m].name, sizeof ts->mats[m].name, "m%d", m);
        ts->mats[m].albedo[0] = 0.2f + 0.1f * (float)m;
        ts->mats[m].albedo[1] = 0.5f;
        ts->mats[m].albedo[2] = 0.8f - 0.1f * (float)m;
        ts->mats[m].texture = -1;
    }
    ts->sc.materials = ts->mats;
    ts->sc.material_count = 4;
    for (int k = 0; k < 3; ++k) {
        ts->sc.bounds_min[k] = INFINITY;
        ts->sc.bounds_max[k] = -INFINITY;
    }
    snprintf(ts->sc.source, sizeof ts->sc.source, "builtin:test");
}

static double tri_area(const float a[3], const float b[3], const float c[3]) {
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
    }
    double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
    return 0.5 * sqrt(x * x + y * y + z * z);
}

/* Adds a triangle with flat (geometric) normals unless n is given. */
static void ts_tri(test_scene *ts, const float a[3], const float b[3], const float c[3], const float (*n)[3],
                   uint32_t material) {
    assert_true(ts->sc.tri_count < ts->cap);
    uint32_t t = ts->sc.tri_count++;
    memcpy(ts->sc.pos[3 * t], a, sizeof(float[3]));
    memcpy(ts->sc.pos[3 * t + 1], b, sizeof(float[3]));
    memcpy(ts->sc.pos[3 * t + 2], c, sizeof(float[3]));
    float e1[3], e2[3], g[3];
    glow__sub(b, a, e1);
    glow__sub(c, a, e2);
    glow__cross(e1, e2, g);
    float len = sqrtf(glow__dot(g, g));
    for (int k = 0; k < 3; ++k) g[k] /= len;
    for (int v = 0; v < 3; ++v) memcpy(ts->sc.nrm[3 * t + v], n ? n[v] : g, sizeof(float[3]));
    ts->sc.tri_material[t] = material;
    for (int v = 0; v < 3; ++v)
        for (int k = 0; k < 3; ++k) {
            float p = ts->sc.pos[3 * t + v][k];
            if (p < ts->sc.bounds_min[k]) ts->sc.bounds_min[k] = p;
            if (p > ts->sc.bounds_max[k]) ts->sc.bounds_max[k] = p;
        }
    ts->sc.area += tri_area(a, b, c);
}

/* Axis-aligned rectangle [x0,x1] x [y0,y1] at height z, split into 2*(sub*sub) triangles. */
static void ts_rect(test_scene *ts, float x0, float y0, float x1, float y1, float z, uint32_t sub, uint32_t mat) {
    for (uint32_t i = 0; i < sub; ++i)
        for (uint32_t j = 0; j < sub; ++j) {
            float xa = x0 + (x1 - x0) * (float)i / (float)sub, xb = x0 + (x1 - x0) * (float)(i + 1) / (float)sub;
            float ya = y0 + (y1 - y0) * (float)j / (float)sub, yb = y0 + (y1 - y0) * (float)(j + 1) / (float)sub;
            float p00[3] = {xa, ya, z}, p10[3] = {xb, ya, z}, p11[3] = {xb, yb, z}, p01[3] = {xa, yb, z};
            ts_tri(ts, p00, p10, p11, NULL, mat);
            ts_tri(ts, p00, p11, p01, NULL, mat);
        }
}

static void ts_free(test_scene *ts) {
    free(ts->sc.pos);
    free(ts->sc.nrm);
    free(ts->sc.uv0);
    free(ts->sc.tri_material);
    memset(ts, 0, sizeof *ts);
}

/* A cluttered scene: random triangles of widely varying size and orientation. */
static void ts_random(test_scene *ts, uint32_t count) {
    ts_init(ts, count);
    for (uint32_t t = 0; t < count; ++t) {
        float c[3] = {(float)(rnd() * 10.0), (float)(rnd() * 5.0), (float)(rnd() * 8.0)};
        float s = (float)pow(10.0, -2.5 + 3.0 * rnd());
        float p[3][3];
        for (int v = 0; v < 3; ++v)
            for (int k = 0; k < 3; ++k) p[v][k] = c[k] + s * (float)(rnd() * 2.0 - 1.0);
        if (tri_area(p[0], p[1], p[2]) < 1e-9) { --t; continue; }
        ts_tri(ts, p[0], p[1], p[2], NULL, t % 3u);
    }
}

static char last_msg[1024];
static void capture_log(void *user, glow_log_level level, const char *msg) {
    (void)user;
    (void)level;
    snprintf(last_msg, sizeof last_msg, "%s", msg);
}

static double nn_dist(const glow__surfels *s, uint32_t i) {
    double best = INFINITY;
    for (uint32_t j = 0; j < s->count; ++j) {
        if (j == i) continue;
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            double d = (double)s->s[i].pos[k] - s->s[j].pos[k];
            d2 += d * d;
        }
        if (d2 < best) best = d2;
    }
    return sqrt(best);
}

/* Every surfel lies on its own triangle: barycentrics inside, position = interpolation, on the plane. */
static void check_on_triangles(const test_scene *ts, const glow__surfels *s) {
    double scale = 0.0;
    for (int k = 0; k < 3; ++k) {
        double e = (double)ts->sc.bounds_max[k] - ts->sc.bounds_min[k];
        if (e > scale) scale = e;
    }
    for (uint32_t i = 0; i < s->count; ++i) {
        const glow__surfel *x = &s->s[i];
        assert_true(x->tri < ts->sc.tri_count);
        assert_true(x->bary[0] >= 0.0f && x->bary[1] >= 0.0f);
        assert_true(x->bary[0] + x->bary[1] <= 1.0f + 1e-6f);
        const float *p0 = ts->sc.pos[3 * x->tri], *p1 = ts->sc.pos[3 * x->tri + 1], *p2 = ts->sc.pos[3 * x->tri + 2];
        double e1[3], e2[3], g[3], q[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)p1[k] - p0[k];
            e2[k] = (double)p2[k] - p0[k];
            q[k] = (double)x->pos[k] - p0[k];
        }
        g[0] = e1[1] * e2[2] - e1[2] * e2[1];
        g[1] = e1[2] * e2[0] - e1[0] * e2[2];
        g[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        double plane = fabs(q[0] * g[0] + q[1] * g[1] + q[2] * g[2]) / gl;
        assert_true(plane < 1e-5 * scale);
        for (int k = 0; k < 3; ++k) {
            double expect = p0[k] + x->bary[0] * e1[k] + x->bary[1] * e2[k];
            assert_true(fabs(expect - x->pos[k]) < 1e-5 * scale);
        }
        assert_true(fabs(glow__dot(x->nrm, x->nrm) - 1.0f) < 1e-5f);
        assert_int_equal(x->material, ts->sc.tri_material[x->tri]);
    }
}

/* ------------------------------------------------------------------ k-d tree */
typedef struct cand { float d2; uint32_t i; } cand;
static int cand_cmp(const void *a, const void *b) {
    const cand *x = a, *y = b;
    if (x->d2 < y->d2) return -1;
    if (x->d2 > y->d2) return 1;
    return x->i < y->i ? -1 : x->i > y->i;
}

static void test_kdtree_matches_brute_force(void **state) {
    (void)state;
    const uint32_t n = 3000;
    float (*p)[3] = malloc(n * sizeof *p);
    cand *all = malloc(n * sizeof *all);
    assert_non_null(p);
    assert_non_null(all);
    for (uint32_t i = 0; i < n; ++i) {
        if (i >= 2500) { /* duplicates and points on a grid: exercises the index tie-break */
            memcpy(p[i], p[i % 97u], sizeof p[i]);
            if (i % 2u) { p[i][0] = (float)(i % 7u); p[i][1] = (float)(i % 5u); p[i][2] = 0.0f; }
            continue;
        }
        if (i >= 2400) { /* points beyond the grids' box, binned into its border cells */
            p[i][0] = (float)(rnd() * 16.0 - 3.0);
            p[i][1] = (float)(rnd() * 8.0 - 2.0);
            p[i][2] = (float)(rnd() * 7.0 - 2.0);
            continue;
        }
        p[i][0] = (float)(rnd() * 10.0);
        p[i][1] = (float)(rnd() * (i < 1000 ? 0.01 : 4.0)); /* a flat cluster too */
        p[i][2] = (float)(rnd() * 3.0);
    }
    glow__kdtree *tree = glow__kdtree_build((const float (*)[3])p, n);
    assert_non_null(tree);
    /* the uniform grid gives the same answers (glow__pointgrid): cells of several sizes, the last so
     * fine that the cell cap coarsens it, over the box of most points while a third of the queries and
     * 100 points lie outside it */
    const float box_lo[3] = {0.0f, 0.0f, 0.0f}, box_hi[3] = {10.0f, 4.0f, 3.0f};
    const float cells[] = {0.3f, 1.7f, 20.0f, 1e-4f};
    glow__pointgrid *grids[4];
    for (uint32_t gi = 0; gi < 4; ++gi) {
        grids[gi] = glow__pointgrid_build((const float (*)[3])p, n, box_lo, box_hi, cells[gi]);
        assert_non_null(grids[gi]);
    }
    uint32_t idx[40];
    float d2[40];
    const uint32_t ks[] = {1, 6, 17, 40};
    for (uint32_t q = 0; q < 300; ++q) {
        float qp[3];
        uint32_t exclude = UINT32_MAX;
        if (q % 3u == 0) {
            exclude = (q * 7919u) % n;
            memcpy(qp, p[exclude], sizeof qp);
        } else {
            qp[0] = (float)(rnd() * 12.0 - 1.0);
            qp[1] = (float)(rnd() * 6.0 - 1.0);
            qp[2] = (float)(rnd() * 5.0 - 1.0);
        }
        uint32_t m = 0;
        for (uint32_t i = 0; i < n; ++i) {
            if (i == exclude) continue;
            float dx = p[i][0] - qp[0], dy = p[i][1] - qp[1], dz = p[i][2] - qp[2];
            all[m].d2 = dx * dx + dy * dy + dz * dz;
            all[m].i = i;
            ++m;
        }
        qsort(all, m, sizeof *all, cand_cmp);
        if (exclude == UINT32_MAX) /* the nearest alone (the surfels' areas): the first of the list */
            for (uint32_t gi = 0; gi < 4; ++gi) {
                float nd = -1.0f;
                assert_int_equal(glow__pointgrid_nearest(grids[gi], qp, &nd), all[0].i);
                assert_true(nd == all[0].d2);
            }
        for (uint32_t ki = 0; ki < sizeof ks / sizeof ks[0]; ++ki) {
            uint32_t k = ks[ki];
            uint32_t got = glow__kdtree_knn(tree, qp, k, exclude, idx, d2);
            assert_int_equal(got, k);
            for (uint32_t j = 0; j < k; ++j) {
                assert_int_equal(idx[j], all[j].i);
                assert_true(d2[j] == all[j].d2);
            }
            for (uint32_t gi = 0; gi < 4; ++gi) {
                assert_int_equal(glow__pointgrid_knn(grids[gi], qp, k, exclude, idx, d2), k);
                for (uint32_t j = 0; j < k; ++j) {
                    assert_int_equal(idx[j], all[j].i);
                    assert_true(d2[j] == all[j].d2);
                }
            }
            /* within a radius: the brute-force list's prefix up to the radius (inclusive), at most k;
             * the radius is one of the distances (a tie at the bound is kept) or between two */
            const float radii[] = {all[k / 2].d2, 0.5f * (all[k].d2 + all[k + 1].d2), 0.0f, 1e30f};
            for (uint32_t ri = 0; ri < 4; ++ri) {
                uint32_t want = 0;
                while (want < k && all[want].d2 <= radii[ri]) ++want;
                got = glow__kdtree_knn_within(tree, qp, k, exclude, radii[ri], idx, d2);
                assert_int_equal(got, want);
                for (uint32_t j = 0; j < got; ++j) {
                    assert_int_equal(idx[j], all[j].i);
                    assert_true(d2[j] <= radii[ri]);
                }
                for (uint32_t gi = 0; gi < 4; ++gi) { /* the grid's, the same */
                    got = glow__pointgrid_knn_within(grids[gi], qp, k, exclude, radii[ri], idx, d2);
                    assert_int_equal(got, want);
                    for (uint32_t j = 0; j < got; ++j) {
                        assert_int_equal(idx[j], all[j].i);
                        assert_true(d2[j] == all[j].d2);
                    }
                }
            }
        }
    }
    glow__kdtree_free(tree);
    for (uint32_t gi = 0; gi < 4; ++gi) glow__pointgrid_free(grids[gi]);
    glow__pointgrid *g3 = glow__pointgrid_build((const float (*)[3])p, 3, box_lo, box_hi, 0.5f);
    assert_non_null(g3);
    assert_int_equal(glow__pointgrid_knn(g3, p[0], 10, 0, idx, d2), 2); /* fewer points than k */
    glow__pointgrid_free(g3);
    { /* ties across rows of cells: a lattice of points (several at each place, the indices shuffled)
       * and queries halfway between them, where the nearest is the smallest index among 2-8 places
       * at the same distance in neighbouring cells */
        float lat[256][3];
        for (uint32_t i = 0; i < 256; ++i) {
            const uint32_t c = (i * 37u) % 64u; /* 4 points at each of 64 places */
            lat[i][0] = (float)(c % 4u);
            lat[i][1] = (float)((c / 4u) % 4u);
            lat[i][2] = (float)(c / 16u);
        }
        const float llo[3] = {0.0f, 0.0f, 0.0f}, lhi[3] = {3.0f, 3.0f, 3.0f};
        const float lcells[] = {0.6f, 0.45f, 1.0f};
        for (uint32_t gi = 0; gi < 3; ++gi) {
            glow__pointgrid *lg = glow__pointgrid_build((const float (*)[3])lat, 256, llo, lhi, lcells[gi]);
            assert_non_null(lg);
            for (uint32_t qi = 0; qi < 343; ++qi) {
                const float qp[3] = {0.5f * (float)(qi % 7u), 0.5f * (float)((qi / 7u) % 7u), 0.5f * (float)(qi / 49u)};
                float bd = INFINITY;
                uint32_t bi = UINT32_MAX;
                for (uint32_t i = 0; i < 256; ++i) {
                    const float dx = lat[i][0] - qp[0], dy = lat[i][1] - qp[1], dz = lat[i][2] - qp[2];
                    const float dd = dx * dx + dy * dy + dz * dz;
                    if (dd < bd || (dd == bd && i < bi)) { bd = dd; bi = i; }
                }
                float nd = -1.0f;
                assert_int_equal(glow__pointgrid_nearest(lg, qp, &nd), bi);
                assert_true(nd == bd);
                assert_int_equal(glow__pointgrid_knn(lg, qp, 1, UINT32_MAX, idx, d2), 1);
                assert_int_equal(idx[0], bi);
            }
            glow__pointgrid_free(lg);
        }
    }
    glow__pointgrid *g0 = glow__pointgrid_build((const float (*)[3])p, 0, box_lo, box_hi, 0.5f);
    assert_non_null(g0);
    float nd0 = 0.0f;
    assert_int_equal(glow__pointgrid_nearest(g0, p[0], &nd0), UINT32_MAX); /* no points */
    assert_true(nd0 == INFINITY);
    glow__pointgrid_free(g0);

    /* small and empty trees */
    glow__kdtree *t3 = glow__kdtree_build((const float (*)[3])p, 3);
    assert_non_null(t3);
    assert_int_equal(glow__kdtree_knn(t3, p[0], 10, UINT32_MAX, idx, d2), 3);
    assert_int_equal(idx[0], 0);
    assert_int_equal(glow__kdtree_knn(t3, p[0], 10, 0, idx, d2), 2);
    for (uint32_t j = 0; j < 2; ++j) assert_int_not_equal(idx[j], 0);
    glow__kdtree_free(t3);
    glow__kdtree *t0 = glow__kdtree_build((const float (*)[3])p, 0);
    assert_non_null(t0);
    assert_int_equal(glow__kdtree_knn(t0, p[0], 4, UINT32_MAX, idx, d2), 0);
    glow__kdtree_free(t0);
    glow__kdtree_free(NULL);
    free(p);
    free(all);
}

/* Masses of coincident points: ties resolve to the smallest indices, and stay cheap. */
static void test_kdtree_coincident_points(void **state) {
    (void)state;
    const uint32_t n = 50000;
    float (*p)[3] = malloc(n * sizeof *p);
    assert_non_null(p);
    for (uint32_t i = 0; i < n; ++i) {
        p[i][0] = 1.0f;
        p[i][1] = 2.0f;
        p[i][2] = 3.0f;
    }
    glow__kdtree *tree = glow__kdtree_build((const float (*)[3])p, n);
    assert_non_null(tree);
    uint32_t idx[6];
    float d2[6];
    for (uint32_t q = 0; q < n; q += 7) {
        assert_int_equal(glow__kdtree_knn(tree, p[q], 6, q, idx, d2), 6);
        uint32_t expect = 0;
        for (uint32_t j = 0; j < 6; ++j, ++expect) {
            if (expect == q) ++expect;
            assert_int_equal(idx[j], expect);
            assert_true(d2[j] == 0.0f);
        }
    }
    glow__kdtree_free(tree);
    free(p);
}

/* ------------------------------------------------------------------ placement */
static void test_count_area_on_triangles(void **state) {
    (void)state;
    test_scene ts;
    ts_random(&ts, 300);
    const uint32_t counts[] = {1, 7, 1000, 4999};
    for (uint32_t ci = 0; ci < sizeof counts / sizeof counts[0]; ++ci) {
        for (uint32_t relax = 0; relax <= 5; relax += 5) {
            glow__surfel_settings set = {.count = counts[ci], .seed = 3, .relax_iterations = relax};
            glow__surfels s;
            assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s), GLOW_OK);
            assert_int_equal(s.count, counts[ci]);
            /* the total is the scene's area (surfels.area is a float: 1e-6 relative is its precision) */
            double total = (double)s.area * (double)s.count;
            assert_true(fabs(total - ts.sc.area) <= 1e-6 * ts.sc.area);
            check_on_triangles(&ts, &s);
            glow__surfels_free(&s);
            assert_null(s.s);
        }
    }
    ts_free(&ts);
}

static void test_area_proportional(void **state) {
    (void)state;
    for (int order = 0; order < 2; ++order) {
        test_scene ts;
        ts_init(&ts, 2);
        /* right triangles of area 1 and 3, far apart */
        float a0[3] = {0, 0, 0}, a1[3] = {2, 0, 0}, a2[3] = {0, 1, 0};
        float b0[3] = {10, 0, 0}, b1[3] = {16, 0, 0}, b2[3] = {10, 1, 0};
        if (order == 0) {
            ts_tri(&ts, a0, a1, a2, NULL, 0);
            ts_tri(&ts, b0, b1, b2, NULL, 1);
        } else {
            ts_tri(&ts, b0, b1, b2, NULL, 1);
            ts_tri(&ts, a0, a1, a2, NULL, 0);
        }
        assert_true(fabs(ts.sc.area - 4.0) < 1e-9);
        const uint32_t counts[] = {4, 400, 1001};
        for (uint32_t ci = 0; ci < 3; ++ci) {
            glow__surfel_settings set = {.count = counts[ci], .seed = 11, .relax_iterations = 3};
            glow__surfels s;
            assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s), GLOW_OK);
            uint32_t on_small = 0;
            for (uint32_t i = 0; i < s.count; ++i) on_small += s.s[i].material == 0;
            double expect = 0.25 * counts[ci];
            assert_true(fabs((double)on_small - expect) <= 1.0);
            check_on_triangles(&ts, &s);
            glow__surfels_free(&s);
        }
        ts_free(&ts);
    }
}

/* Triangles far smaller than a surfel accumulate their area until one of them spawns a surfel. */
static void test_small_triangles_accumulate(void **state) {
    (void)state;
    test_scene ts;
    ts_init(&ts, 1001);
    /* 1000 tiny triangles of area 1e-3 each (1 in total), then one of area 1 */
    for (uint32_t t = 0; t < 1000; ++t) {
        float x = (float)t * 0.1f;
        float p0[3] = {x, 5, 0}, p1[3] = {x + 0.05f, 5, 0}, p2[3] = {x, 5.04f, 0};
        ts_tri(&ts, p0, p1, p2, NULL, 0);
    }
    float q0[3] = {0, 0, 0}, q1[3] = {2, 0, 0}, q2[3] = {0, 1, 0};
    ts_tri(&ts, q0, q1, q2, NULL, 1);
    /* 200 surfels of area 0.01: every tiny triangle holds a tenth of one */
    glow__surfel_settings set = {.count = 200, .seed = 5, .relax_iterations = 0};
    glow__surfels s;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s), GLOW_OK);
    uint32_t *per_tri = calloc(ts.sc.tri_count, sizeof *per_tri);
    assert_non_null(per_tri);
    for (uint32_t i = 0; i < s.count; ++i) per_tri[s.s[i].tri]++;
    uint32_t tiny_total = 0, last = 0, max_gap = 0;
    for (uint32_t t = 0; t < 1000; ++t) {
        assert_true(per_tri[t] <= 1);
        if (per_tri[t]) {
            if (t - last > max_gap) max_gap = t - last;
            last = t;
        }
        tiny_total += per_tri[t];
    }
    assert_true(tiny_total >= 99 && tiny_total <= 101);
    assert_true(max_gap <= 11); /* one surfel per ~10 consecutive tiny triangles */
    assert_true(per_tri[1000] >= 99 && per_tri[1000] <= 101);
    check_on_triangles(&ts, &s);
    free(per_tri);
    glow__surfels_free(&s);
    ts_free(&ts);
}

static void test_normals_and_materials(void **state) {
    (void)state;
    test_scene ts;
    ts_init(&ts, 2);
    float p0[3] = {0, 0, 0}, p1[3] = {1, 0, 0}, p2[3] = {0, 1, 0};
    float n[3][3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, -0.6f, 0.8f}};
    ts_tri(&ts, p0, p1, p2, (const float (*)[3])n, 2);
    float r0[3] = {0, 0, 1}, r1[3] = {0, 1, 1}, r2[3] = {1, 0, 1};
    ts_tri(&ts, r0, r1, r2, NULL, 1);
    ts.mats[2].emission[0] = 3.0f;
    ts.mats[2].emission[1] = 2.0f;
    ts.mats[2].emission[2] = 1.0f;
    glow__surfel_settings set = {.count = 500, .seed = 9, .relax_iterations = 4};
    glow__surfels s;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s), GLOW_OK);
    uint32_t seen[2] = {0, 0};
    for (uint32_t i = 0; i < s.count; ++i) {
        const glow__surfel *x = &s.s[i];
        seen[x->tri]++;
        const glow__material *m = &ts.mats[x->material];
        for (int k = 0; k < 3; ++k) {
            assert_true(x->albedo[k] == m->albedo[k]);
            assert_true(x->emission[k] == m->emission[k]);
        }
        double b1 = x->bary[0], b2 = x->bary[1], b0 = 1.0 - b1 - b2, e[3], len = 0.0;
        for (int k = 0; k < 3; ++k) {
            const float *c0 = ts.sc.nrm[3 * x->tri], *c1 = ts.sc.nrm[3 * x->tri + 1], *c2 = ts.sc.nrm[3 * x->tri + 2];
            e[k] = b0 * c0[k] + b1 * c1[k] + b2 * c2[k];
            len += e[k] * e[k];
        }
        for (int k = 0; k < 3; ++k) assert_true(fabs(e[k] / sqrt(len) - x->nrm[k]) < 1e-5);
    }
    assert_int_equal(seen[0], 250);
    assert_int_equal(seen[1], 250);
    /* the corner normals differ, so the interpolated normals must vary */
    float minx = 1.0f, maxx = -1.0f;
    for (uint32_t i = 0; i < s.count; ++i)
        if (s.s[i].tri == 0) {
            if (s.s[i].nrm[0] < minx) minx = s.s[i].nrm[0];
            if (s.s[i].nrm[0] > maxx) maxx = s.s[i].nrm[0];
        }
    assert_true(maxx - minx > 0.3f);
    glow__surfels_free(&s);
    ts_free(&ts);
}

/* albedo = material albedo x texture: a constant-colour texture must scale it exactly. */
static void test_textured_albedo(void **state) {
    (void)state;
    test_scene ts;
    ts_init(&ts, 2);
    ts_rect(&ts, 0, 0, 2, 1, 0, 1, 3);
    ts.sc.uv0 = calloc(3u * ts.sc.tri_count, sizeof *ts.sc.uv0);
    assert_non_null(ts.sc.uv0);
    for (uint32_t t = 0; t < ts.sc.tri_count; ++t)
        for (int v = 0; v < 3; ++v) {
            ts.sc.uv0[3 * t + v][0] = ts.sc.pos[3 * t + v][0] * 0.5f;
            ts.sc.uv0[3 * t + v][1] = ts.sc.pos[3 * t + v][1];
        }
    const float texel[3] = {0.5f, 0.25f, 1.0f};
    ts.tex.width = ts.tex.height = 2;
    ts.tex.level_count = 2;
    for (int l = 0; l < 2; ++l) {
        for (int i = 0; i < 4; ++i) memcpy(&ts.texels[l][3 * i], texel, sizeof texel);
        ts.tex.levels[l] = ts.texels[l];
    }
    ts.sc.textures = &ts.tex;
    ts.sc.texture_count = 1;
    ts.mats[3].texture = 0;
    glow__surfel_settings set = {.count = 64, .seed = 1, .relax_iterations = 2};
    glow__surfels s;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s), GLOW_OK);
    for (uint32_t i = 0; i < s.count; ++i)
        for (int k = 0; k < 3; ++k) assert_true(fabsf(s.s[i].albedo[k] - ts.mats[3].albedo[k] * texel[k]) < 1e-5f);
    glow__surfels_free(&s);
    ts_free(&ts);
}

typedef struct nn_stats { double min, mean; } nn_stats;
static nn_stats measure_nn(const glow__surfels *s) {
    nn_stats st = {INFINITY, 0.0};
    for (uint32_t i = 0; i < s->count; ++i) {
        double d = nn_dist(s, i);
        if (d < st.min) st.min = d;
        st.mean += d;
    }
    st.mean /= s->count;
    return st;
}

static void test_relaxation_spreads_surfels(void **state) {
    (void)state;
    test_scene ts;
    ts_init(&ts, 32);
    ts_rect(&ts, 0, 0, 2, 1, 0, 4, 0); /* 32 triangles */
    const uint32_t n = 2000;
    const double spacing = sqrt(2.0 / n);
    nn_stats st[2];
    for (int r = 0; r < 2; ++r) {
        glow__surfel_settings set = {.count = n, .seed = 17, .relax_iterations = r ? 6u : 0u};
        glow__surfels s;
        assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s), GLOW_OK);
        check_on_triangles(&ts, &s);
        for (uint32_t i = 0; i < n; ++i) assert_true(s.s[i].pos[2] == 0.0f);
        st[r] = measure_nn(&s);
        glow__surfels_free(&s);
    }
    print_message("nearest-neighbour distance / sqrt(a): no relaxation min %.3f mean %.3f; 6 iterations min %.3f mean %.3f\n",
                  st[0].min / spacing, st[0].mean / spacing, st[1].min / spacing, st[1].mean / spacing);
    assert_true(st[1].mean > st[0].mean * 1.05);
    assert_true(st[1].min > st[0].min * 1.5);
    /* a hexagonal packing of equal area has spacing 1.075 sqrt(a); relaxed points get close to it */
    assert_true(st[1].mean > 0.85 * spacing);
    assert_true(st[1].min > 0.3 * spacing);
    ts_free(&ts);
}

static void test_deterministic_across_threads(void **state) {
    (void)state;
    test_scene ts;
    ts_random(&ts, 200);
    glow__surfel_settings set = {.count = 6000, .seed = 21, .relax_iterations = 4};
    glow__surfels ref;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &ref), GLOW_OK);
    for (uint32_t threads = 1; threads <= 3; ++threads) {
        glow__pool *pool = glow__pool_create(threads);
        assert_non_null(pool);
        glow__surfels s;
        assert_int_equal(glow__surfels_place(&ts.sc, &set, pool, NULL, &s), GLOW_OK);
        assert_int_equal(s.count, ref.count);
        assert_true(s.area == ref.area);
        assert_memory_equal(s.s, ref.s, (size_t)s.count * sizeof *s.s);
        glow__surfels_free(&s);
        glow__pool_destroy(pool);
    }
    /* another seed moves the surfels but keeps the per-triangle counts */
    glow__surfel_settings set2 = set;
    set2.seed = 22;
    glow__surfels other;
    assert_int_equal(glow__surfels_place(&ts.sc, &set2, NULL, NULL, &other), GLOW_OK);
    uint32_t moved = 0;
    for (uint32_t i = 0; i < ref.count; ++i) {
        assert_int_equal(other.s[i].tri, ref.s[i].tri);
        moved += memcmp(other.s[i].pos, ref.s[i].pos, sizeof ref.s[i].pos) != 0;
    }
    assert_true(moved > ref.count / 2);
    glow__surfels_free(&other);
    glow__surfels_free(&ref);
    ts_free(&ts);
}

/* Adaptive density (surfels.c "adaptive density", "areas from the placement"): a 4 x 4 m floor
 * meeting a 4 x 2 m wall. Within the near field of the crease the surfels must be denser and
 * smaller; every surfel's area is its share of the surface, so the areas sum to each surface's area,
 * and to a region's far from the crease; the same bytes on any thread count. */
static void add_floor_and_wall(test_scene *ts) {
    ts_init(ts, 64);
    ts_rect(ts, 0.0f, 0.0f, 4.0f, 4.0f, 0.0f, 4, 0); /* floor z = 0, normal +z */
    const float w0[3] = {0, 0, 0}, w1[3] = {0, 4, 0}, w2[3] = {0, 4, 2}, w3[3] = {0, 0, 2};
    ts_tri(ts, w0, w1, w2, NULL, 1); /* wall x = 0, normal +x (towards the floor) */
    ts_tri(ts, w0, w2, w3, NULL, 1);
}

static void test_adaptive_density(void **state) {
    (void)state;
    test_scene ts;
    add_floor_and_wall(&ts);
    glow__rt *rt = NULL;
    assert_int_equal(glow__rt_create(&ts.sc, NULL, &rt), GLOW_OK);
    glow__surfel_settings set = {.count = 4000, .seed = 3, .relax_iterations = 4, .adapt = 4.0f, .rt = rt};
    glow__surfels s;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s), GLOW_OK);
    assert_int_equal(s.count, 4000);
    assert_int_equal(s.adapted, 1);
    const double nominal = ts.sc.area / 4000.0, reach = 4.0 * sqrt(nominal / M_PI); /* ADAPT_RADII */
    double sum = 0.0, floor_a = 0.0, wall_a = 0.0, far_a = 0.0, near_a = 0.0, amin = INFINITY, amax = 0.0;
    uint32_t near_n = 0, far_n = 0;
    for (uint32_t i = 0; i < s.count; ++i) {
        const glow__surfel *x = &s.s[i];
        assert_true(isfinite(x->area) && x->area > 0.0f);
        sum += x->area;
        amin = fmin(amin, x->area);
        amax = fmax(amax, x->area);
        if (x->material == 0) {
            floor_a += x->area;
            if (x->pos[0] < 0.5 * reach) { near_a += x->area; near_n++; }
            if (x->pos[0] > 1.0f) { far_a += x->area; far_n++; }
        } else {
            wall_a += x->area;
        }
    }
    printf("adaptive: areas %.4g..%.4g (nominal %.4g); floor %.4f wall %.4f; floor near the crease %u surfels "
           "(%.1f per m2), far %u (%.1f per m2, their areas %.4f of 12 m2)\n", amin, amax, nominal, floor_a, wall_a,
           near_n, near_n / (4.0 * 0.5 * reach), far_n, far_n / 12.0, far_a);
    assert_true(fabs(sum - ts.sc.area) < 1e-4 * ts.sc.area);
    assert_true(fabs(floor_a - 16.0) < 0.02 * 16.0);
    assert_true(fabs(wall_a - 8.0) < 0.02 * 8.0);
    assert_true(fabs(far_a - 12.0) < 0.03 * 12.0);        /* a region's areas are its area */
    const double near_density = near_n / (4.0 * 0.5 * reach), far_density = far_n / 12.0;
    assert_true(near_density > 1.5 * far_density);          /* denser in the crease ... */
    assert_true(near_a / near_n < 0.75 * (far_a / far_n)); /* ... with smaller surfels */
    assert_true(amin >= nominal / 16.0 && amax <= 16.0 * nominal); /* the bake's leaf-area range */

    /* the same bytes on 1 and 2 threads */
    glow__pool *pool = glow__pool_create(2);
    assert_non_null(pool);
    glow__surfels s2;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, pool, NULL, &s2), GLOW_OK);
    assert_int_equal(s2.count, s.count);
    assert_memory_equal(s2.s, s.s, (size_t)s.count * sizeof *s.s);
    glow__surfels_free(&s2);
    glow__pool_destroy(pool);

    /* the smallest count a bake allows: still exactly n, areas summing to the scene's */
    glow__surfel_settings few = set;
    few.count = 16;
    assert_int_equal(glow__surfels_place(&ts.sc, &few, NULL, NULL, &s2), GLOW_OK);
    assert_int_equal(s2.count, 16);
    double few_sum = 0.0;
    for (uint32_t i = 0; i < s2.count; ++i) few_sum += s2.s[i].area;
    assert_true(fabs(few_sum - ts.sc.area) < 1e-4 * ts.sc.area);
    glow__surfels_free(&s2);

    /* without rays (no rt) the density stays area-uniform: every surfel has the nominal area */
    set.rt = NULL;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, NULL, &s2), GLOW_OK);
    assert_int_equal(s2.adapted, 0);
    for (uint32_t i = 0; i < s2.count; ++i) assert_true(s2.s[i].area == s2.area);
    glow__surfels_free(&s2);
    glow__surfels_free(&s);
    glow__rt_destroy(rt);
    ts_free(&ts);
}

static void test_invalid_input(void **state) {
    (void)state;
    test_scene ts;
    ts_init(&ts, 2);
    ts_rect(&ts, 0, 0, 1, 1, 0, 1, 0);
    glow__log log = {.fn = capture_log};
    glow__surfels s;
    glow__surfel_settings set = {.count = 0, .seed = 1, .relax_iterations = 0};
    last_msg[0] = 0;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, &log, &s), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(last_msg, "builtin:test"));
    assert_null(s.s);
    set.count = 10;
    ts.sc.tri_material[1] = 7;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, &log, &s), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(last_msg, "triangle 1"));
    ts.sc.tri_material[1] = 0;
    uint32_t tc = ts.sc.tri_count;
    ts.sc.tri_count = 0;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, &log, &s), GLOW_ERROR_INVALID_ARGUMENT);
    ts.sc.tri_count = tc;
    double area = ts.sc.area;
    ts.sc.area = 0.0;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, &log, &s), GLOW_ERROR_INVALID_ARGUMENT);
    ts.sc.area = area;
    assert_int_equal(glow__surfels_place(&ts.sc, &set, NULL, &log, &s), GLOW_OK);
    assert_int_equal(s.count, 10);
    glow__surfels_free(&s);
    ts_free(&ts);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kdtree_matches_brute_force),
        cmocka_unit_test(test_kdtree_coincident_points),
        cmocka_unit_test(test_count_area_on_triangles),
        cmocka_unit_test(test_area_proportional),
        cmocka_unit_test(test_small_triangles_accumulate),
        cmocka_unit_test(test_normals_and_materials),
        cmocka_unit_test(test_textured_albedo),
        cmocka_unit_test(test_relaxation_spreads_surfels),
        cmocka_unit_test(test_deterministic_across_threads),
        cmocka_unit_test(test_adaptive_density),
        cmocka_unit_test(test_invalid_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
