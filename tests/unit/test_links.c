/* test_links.c — SH basis, cone factors (DESIGN §3) and link generation (PIC 4.5/4.6). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/bake_format.h"
#include "cone_fit.h"
#include "pc_internal.h"

/* Gauss-Legendre-free midpoint quadrature over the sphere in (cos theta, phi): plenty for l <= 8. */
static void test_sh_orthonormal(void **state) {
    (void)state;
    enum { NT = 400, NP = 800, B = 8, C = B * B };
    static double gram[C][C];
    memset(gram, 0, sizeof gram);
    float y[C];
    for (int i = 0; i < NT; ++i) {
        double z = -1.0 + (i + 0.5) * 2.0 / NT, r = sqrt(1.0 - z * z);
        for (int j = 0; j < NP; ++j) {
            double phi = (j + 0.5) * 2.0 * GLOW__PI / NP;
            float d[3] = {(float)(r * cos(phi)), (float)(r * sin(phi)), (float)z};
            glow__sh_eval(B, d, y);
            double w = (2.0 / NT) * (2.0 * GLOW__PI / NP);
            for (int a = 0; a < C; ++a)
                for (int b = a; b < C; ++b) gram[a][b] += w * y[a] * y[b];
        }
    }
    for (int a = 0; a < C; ++a)
        for (int b = a; b < C; ++b) {
            double expect = a == b ? 1.0 : 0.0;
            if (fabs(gram[a][b] - expect) > 2e-3) fail_msg("<y%d, y%d> = %g, expected %g", a, b, gram[a][b], expect);
        }
    /* band 1 is (y, z, x) * sqrt(3/4pi) */
    float d[3] = {0.3f, -0.5f, 0.8124038f};
    glow__sh_eval(2, d, y);
    double c = sqrt(3.0 / (4.0 * GLOW__PI));
    assert_true(fabs(y[0] - 0.5 / sqrt(GLOW__PI)) < 1e-6);
    assert_true(fabs(y[1] - c * d[1]) < 1e-6);
    assert_true(fabs(y[2] - c * d[2]) < 1e-6);
    assert_true(fabs(y[3] - c * d[0]) < 1e-6);
}

/* k_l(x) y_lm(d) must equal the SH projection of the cone's indicator (axis d, cos half-angle x).
 * Integrate numerically around the z axis: only m = 0 survives, so k_l(x) * y_l0(z) = ∫_cone y_l0. */
static void test_cone_factors_quadrature(void **state) {
    (void)state;
    const double xs[] = {0.99, 0.9, 0.5, 0.0, -0.3, -0.9};
    /* l + 1 <= GLOW_MAX_SH_BANDS: the SH basis has 8 bands (l = 0..7); asking for 9 leaves y unset (an
     * earlier l <= 8 here read uninitialised memory and failed at random) */
    for (uint32_t l = 0; l < GLOW_MAX_SH_BANDS; ++l) {
        for (size_t k = 0; k < sizeof xs / sizeof xs[0]; ++k) {
            double x = xs[k];
            /* ∫_0^{2π} ∫_x^1 y_l0(t) dt dφ by midpoint rule on t */
            enum { N = 20000 };
            double sum = 0.0;
            float y[81];
            for (int i = 0; i < N; ++i) {
                double t = x + (i + 0.5) * (1.0 - x) / N;
                float d[3] = {(float)sqrt(fmax(0.0, 1.0 - t * t)), 0.0f, (float)t};
                glow__sh_eval(l + 1, d, y);
                sum += y[l * l + l] * (1.0 - x) / N;
            }
            sum *= 2.0 * GLOW__PI;
            float up[3] = {0, 0, 1};
            glow__sh_eval(l + 1, up, y);
            double closed = glow__cone_factor(l, x) * y[l * l + l];
            if (fabs(closed - sum) > 1e-4 * (1.0 + fabs(sum)))
                fail_msg("k_%u(%g): closed form %g vs quadrature %g", l, x, closed, sum);
        }
    }
    /* the full sphere: only l = 0 survives, k_0(-1) = 4π */
    assert_true(fabs(glow__cone_factor(0, -1.0) - 4.0 * GLOW__PI) < 1e-12);
    for (uint32_t l = 1; l <= 8; ++l) assert_true(fabs(glow__cone_factor(l, -1.0)) < 1e-12);
}

/* ------------------------------------------------------------------ link generation */
typedef struct world {
    glow__scene scene;
    glow__rt *rt;
    glow__surfels surfels;
    glow__hierarchy h;
    glow__pool *pool;
    glow__log log;
} world;

static void world_make(world *w, const char *builtin, uint32_t surfels, uint32_t threads) {
    memset(w, 0, sizeof *w);
    assert_int_equal(glow__scene_builtin(builtin, &w->log, &w->scene), GLOW_OK);
    assert_int_equal(glow__rt_create(&w->scene, &w->log, &w->rt), GLOW_OK);
    w->pool = glow__pool_create(threads);
    glow__surfel_settings ss = {.count = surfels, .seed = 1, .relax_iterations = 4};
    assert_int_equal(glow__surfels_place(&w->scene, &ss, w->pool, &w->log, &w->surfels), GLOW_OK);
    assert_int_equal(glow__hierarchy_build(&w->surfels, w->scene.bounds_min, w->scene.bounds_max, w->pool, &w->log, &w->h),
                     GLOW_OK);
}
static void world_free(world *w) {
    glow__hierarchy_free(&w->h);
    glow__surfels_free(&w->surfels);
    glow__rt_destroy(w->rt);
    glow__scene_free(&w->scene);
    glow__pool_destroy(w->pool);
}

static glow__caches caches_alloc(uint32_t n) {
    glow__caches c;
    memset(&c, 0, sizeof c);
    c.count = n;
    c.caches = calloc(n, sizeof *c.caches);
    assert_non_null(c.caches);
    return c;
}

static glow__caches two_caches(void) {
    glow__caches c = caches_alloc(2);
    /* a grid cache in the middle of the furnace box, a lightmap cache just above the floor */
    c.caches[0] = (glow__cache){.pos = {0.1f, 0.05f, -0.07f}, .kind = GLOW_CACHE_KIND_GRID};
    c.caches[1] = (glow__cache){.pos = {0.2f, -0.999f, 0.3f}, .nrm = {0, 1, 0}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
    return c;
}

static double link_omega(const glow__link *l) { return l->one_minus_cos * 2.0 * GLOW__PI; }

/* Both cuts (--cut solid-angle, the default, and --cut error) cover the visible scene. */
static void cut_covers_visible_scene(bool cut_error) {
    world w;
    world_make(&w, "furnace", 4096, 2);
    glow__caches c = two_caches();
    const uint32_t nl = 64;
    /* the raw cut (no cone fit: it resizes lightmap cones on purpose, see test_cone_fit_response) */
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .rays_per_surfel = 1, .no_cone_fit = true,
                              .cut_error = cut_error};
    glow__links L;
    assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                     GLOW_OK);
    double expect[2] = {4.0 * GLOW__PI, 2.0 * GLOW__PI}; /* closed box: every direction sees a wall */
    double leaf_total = 0.0;
    for (uint32_t ci = 0; ci < 2; ++ci) {
        double cut_total = 0.0;
        uint32_t used = 0;
        for (uint32_t j = 0; j < nl; ++j) {
            const glow__link *l = &L.links[ci * nl + j];
            if (l->factor == 0.0f) continue;
            used++;
            assert_true(l->node < w.h.node_count);
            assert_true(l->one_minus_cos > 0.0f && l->one_minus_cos <= 2.0f);
            assert_true(fabsf(glow__dot(l->dir, l->dir) - 1.0f) < 1e-4f);
            /* factor = surfel area / node area */
            assert_true(fabsf(l->factor - w.surfels.area / w.h.nodes[l->node].area) < 1e-5f * l->factor);
            cut_total += link_omega(l);
        }
        assert_int_equal(used, nl); /* a closed box has far more visible nodes than n_L */
        /* the cut preserves the visible solid angle, and the solid angles of equal-area surfels
         * tile the sphere (hemisphere) seen from inside a closed box */
        if (fabs(cut_total - expect[ci]) > 0.05 * expect[ci])
            fail_msg("cache %u: cut solid angle %g, expected %g", ci, cut_total, expect[ci]);
        leaf_total += cut_total;
    }
    /* Σ over the cuts equals Σ over visible leaves (no visible node dropped, nothing double counted) */
    if (fabs(leaf_total - L.visible_solid_angle_total) > 1e-4 * L.visible_solid_angle_total)
        fail_msg("cut total %g vs leaf total %g", leaf_total, L.visible_solid_angle_total);
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}
static void test_cut_covers_visible_scene(void **state) {
    (void)state;
    cut_covers_visible_scene(false);
    cut_covers_visible_scene(true);
}

/* The error cut (links.c cut_priority, cut_descend; --cut error): from a room of the two-rooms scene
 * its cut differs from the solid-angle cut at equal coverage and is the same for any thread count.
 * Printed, not asserted: how many links hold surfels of the hidden room. With this test's plain HAC
 * hierarchy (glow__hierarchy_build, without the pipeline's visibility term) both cuts link such mixed
 * nodes (14 and 19 of 96): at this budget the bound splits other nodes first. What the error cut is
 * judged by is its gather against the exact one under real light (glow-bake --audit-radiance,
 * docs/linker.md "The cut"). */
static void test_cut_error(void **state) {
    (void)state;
    const uint32_t nl = 48;
    glow__links L[3];
    uint32_t mixed[3] = {0, 0, 0};
    world w;
    for (int k = 0; k < 3; ++k) {
        world_make(&w, "two-rooms", 4096, k == 2 ? 1 : 2);
        glow__caches c = caches_alloc(2);
        c.caches[0] = (glow__cache){.pos = {-2.0f, 1.25f, 0.1f}, .kind = GLOW_CACHE_KIND_GRID};
        c.caches[1] = (glow__cache){.pos = {-1.0f, 0.001f, 0.5f}, .nrm = {0, 1, 0}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
        glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .rays_per_surfel = 1, .no_cone_fit = true,
                                  .cut_error = k > 0};
        assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L[k]),
                         GLOW_OK);
        for (uint32_t j = 0; j < 2 * nl; ++j) {
            const glow__link *l = &L[k].links[j];
            if (l->factor == 0.0f) continue;
            /* every surfel under a linked node lies in room A (x < 0) */
            uint32_t stack[64], sp = 0;
            stack[sp++] = l->node;
            while (sp) {
                uint32_t v = stack[--sp];
                if (v < w.h.leaf_count) {
                    if (!(w.surfels.s[v].pos[0] < 0.05f)) {
                        mixed[k]++;
                        break;
                    }
                } else if (sp + 2 <= 64) {
                    stack[sp++] = w.h.nodes[v].child[0];
                    stack[sp++] = w.h.nodes[v].child[1];
                }
            }
        }
        free(c.caches);
        if (k < 2) world_free(&w);
    }
    printf("links holding room-B surfels: solid-angle cut %u, error cut %u\n", mixed[0], mixed[1]);
    assert_int_equal(mixed[1], mixed[2]);
    double tot[2] = {0, 0};
    uint32_t differ = 0;
    for (int k = 0; k < 2; ++k)
        for (uint32_t j = 0; j < 2 * nl; ++j) tot[k] += L[k].links[j].factor != 0.0f ? link_omega(&L[k].links[j]) : 0.0;
    for (uint32_t j = 0; j < 2 * nl; ++j) differ += L[0].links[j].node != L[1].links[j].node;
    if (fabs(tot[0] - tot[1]) > 1e-3 * tot[0]) fail_msg("coverage: solid-angle cut %g sr, error cut %g sr", tot[0], tot[1]);
    assert_true(differ > 0);
    assert_memory_equal(L[1].links, L[2].links, (size_t)2 * nl * sizeof *L[1].links);
    for (int k = 0; k < 3; ++k) glow__links_free(&L[k]);
    world_free(&w);
}

/* The error cut rates a lightmap cache's nodes by the diffuse response the cache gathers (links.c
 * cut_priority), not by their solid angle: texels on the back wall of the Cornell box just under its
 * ceiling see the ceiling at grazing incidence, a large solid angle that adds little light, and a
 * point light 0.2 m under the ceiling in a front corner makes a hot spot there a few decimetres wide
 * (docs/results.md, CornellBox-Sphere). Under that light (radiance cos/d² per surfel, unshadowed) the
 * cut's gather through node means must come closer to the exact gather through the visible surfels
 * when rated by response than by solid angle, on the mean absolute error over the texels. */
static void test_cut_error_response(void **state) {
    (void)state;
    world w;
    world_make(&w, "cornell", 8192, 2);
    const float P[3] = {0.55f, 1.8f, 0.6f};
    float *B = malloc(w.surfels.count * sizeof *B);
    assert_non_null(B);
    for (uint32_t i = 0; i < w.surfels.count; ++i) {
        float d[3];
        glow__sub(P, w.surfels.s[i].pos, d);
        const float r2 = glow__dot(d, d), c = glow__dot(d, w.surfels.s[i].nrm) / sqrtf(r2);
        B[i] = c > 0.0f ? c / r2 : 0.0f;
    }
    enum { NX = 8, NY = 3 };
    glow__caches c = caches_alloc(NX * NY);
    for (uint32_t k = 0; k < NX * NY; ++k)
        c.caches[k] = (glow__cache){.pos = {-0.85f + 1.7f * (float)(k % NX) / (NX - 1), 1.95f - 0.1f * (float)(k / NX), -0.999f},
                                    .nrm = {0, 0, 1}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
    double err[2] = {0, 0}, exact = 0.0;
    for (int k = 0; k < 2; ++k) {
        glow__link_settings ls = {.links_per_cache = 32, .sh_bands = 3, .rays_per_surfel = 1, .cut_error = true,
                                  .cut_error_omega = k == 1, .audit_radiance = B};
        glow__links L;
        assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                         GLOW_OK);
        for (uint32_t ci = 0; ci < c.count; ++ci) {
            const float *row = L.audit + (size_t)ci * GLOW__AUDIT_FIELDS;
            err[k] += fabs((double)row[1] - row[0]);
            if (k == 0) exact += row[0];
        }
        glow__links_free(&L);
    }
    printf("back-wall texels under the ceiling, mean |cut - exact| / exact: by response %.4f, by solid angle %.4f\n",
           err[0] / exact, err[1] / exact);
    assert_true(exact > 0.0);
    assert_true(err[0] < err[1]);
    free(c.caches);
    free(B);
    world_free(&w);
}

/* Nodes nearer the cache are refined further: with more links the cut gets finer, never coarser,
 * and the first split order follows the visible solid angle. With n_L >= visible leaves, every
 * link is a leaf. */
static void test_cut_refines_to_leaves(void **state) {
    (void)state;
    world w;
    world_make(&w, "furnace", 256, 1);
    glow__caches c = two_caches();
    const uint32_t nl = 1024; /* more than the 256 leaves */
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 2, .rays_per_surfel = 1};
    glow__links L;
    assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                     GLOW_OK);
    uint32_t used = 0;
    for (uint32_t j = 0; j < nl; ++j) {
        const glow__link *l = &L.links[j];
        if (l->factor == 0.0f) continue;
        used++;
        assert_true(l->node < w.h.leaf_count);
        assert_true(fabsf(l->factor - 1.0f) < 1e-6f);
    }
    assert_true(used > 200 && used <= 256); /* every surfel in a closed box faces the centre */
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}

/* A wall between the cache and half of the scene: nothing behind it is linked at leaf level,
 * and the visible solid angle still closes to 4π (the near side of the wall fills the view). */
static void test_visibility_blocks_other_room(void **state) {
    (void)state;
    world w;
    world_make(&w, "two-rooms", 8192, 2);
    glow__caches c = caches_alloc(1);
    c.caches[0] = (glow__cache){.pos = {-2.0f, 1.25f, 0.1f}, .kind = GLOW_CACHE_KIND_GRID}; /* room A */
    const uint32_t nl = 2048;
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .rays_per_surfel = 1};
    glow__links L;
    assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                     GLOW_OK);
    double total = 0.0;
    for (uint32_t j = 0; j < nl; ++j) {
        const glow__link *l = &L.links[j];
        if (l->factor == 0.0f) continue;
        total += link_omega(l);
        if (l->node < w.h.leaf_count) assert_true(w.surfels.s[l->node].pos[0] < 0.0f); /* room A side only */
    }
    if (fabs(total - 4.0 * GLOW__PI) > 0.05 * 4.0 * GLOW__PI) fail_msg("visible solid angle %g, expected 4pi", total);
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}

/* Full-SH links (PIC Eq. 2): the DC coefficient equals the runtime projection's (ω * y00 * factor),
 * and the first-order coefficients point along the link direction. */
static void test_full_sh_matches_runtime_dc(void **state) {
    (void)state;
    world w;
    world_make(&w, "furnace", 2048, 2);
    glow__caches c = two_caches();
    const uint32_t nl = 32;
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .full_sh = true, .rays_per_surfel = 1,
                              .no_cone_fit = true};
    glow__links L;
    assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                     GLOW_OK);
    assert_non_null(L.sh);
    double y00 = 0.5 / sqrt(GLOW__PI);
    for (uint32_t j = 0; j < 2 * nl; ++j) {
        const glow__link *l = &L.links[j];
        if (l->factor == 0.0f) continue;
        const float *sh = L.sh + (size_t)j * 9;
        double dc = link_omega(l) * y00 * l->factor;
        assert_true(fabs(sh[0] - dc) < 1e-4 * dc);
        /* band 1 vector (index 3 = x, 1 = y, 2 = z) is parallel to the mean direction */
        float b1[3] = {sh[3], sh[1], sh[2]};
        float len = sqrtf(glow__dot(b1, b1));
        if (len > 1e-6f * (float)dc) assert_true(glow__dot(b1, l->dir) / len > 0.999f);
    }
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}

/* Caches right beside a wall or in a corner: the near field is measured with rays, so the visible
 * solid angle still closes (with disc solid angles alone a corner texel missed half its hemisphere). */
static void test_near_field_closes(void **state) {
    (void)state;
    world w;
    world_make(&w, "furnace", 8192, 2);
    glow__caches c = caches_alloc(4);
    float h = 2e-4f * sqrtf(12.0f); /* the lift caches.c gives texels: 1e-4 x diagonal, doubled */
    c.caches[0] = (glow__cache){.pos = {-1.0f + 0.01f, 0.2f, 0.3f}, .kind = GLOW_CACHE_KIND_GRID}; /* 1 cm from a wall */
    c.caches[1] = (glow__cache){.pos = {-1.0f + 0.01f, -1.0f + 0.01f, -1.0f + 0.01f}, .kind = GLOW_CACHE_KIND_GRID};
    c.caches[2] = (glow__cache){.pos = {-1.0f + 0.002f, -1.0f + h, 0.4f}, .nrm = {0, 1, 0}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
    c.caches[3] = (glow__cache){.pos = {-1.0f + h, 0.5f, 1.0f - 0.002f}, .nrm = {1, 0, 0}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
    const uint32_t nl = 128;
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .rays_per_surfel = 1};
    glow__links L;
    assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                     GLOW_OK);
    for (uint32_t ci = 0; ci < 4; ++ci) {
        double total = 0.0, expect = ci < 2 ? 4.0 * GLOW__PI : 2.0 * GLOW__PI;
        for (uint32_t j = 0; j < nl; ++j)
            if (L.links[ci * nl + j].factor != 0.0f) total += link_omega(&L.links[ci * nl + j]);
        if (fabs(total / expect - 1.0) > 0.05) fail_msg("cache %u: solid angle %g, expected %g", ci, total, expect);
    }
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}

/* Solid angle of the rectangle [x0, x1] x [z0, z1] in the plane y = 0 seen from (0, h, 0), h > 0:
 * the signed sum over its corners of atan(x z / (h sqrt(x² + z² + h²))). */
static double rect_solid_angle(double x0, double x1, double z0, double z1, double h) {
    double xs[2] = {x0, x1}, zs[2] = {z0, z1}, sum = 0.0;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
            double sign = (i == j) ? 1.0 : -1.0;
            sum += sign * atan(xs[i] * zs[j] / (h * sqrt(xs[i] * xs[i] + zs[j] * zs[j] + h * h)));
        }
    return sum;
}

/* An open scene: one 2 x 2 m floor (front face up, 8 x 8 quads) under the sky. The normalisation
 * must not pull the visible solid angle towards 4π: rays into the sky and onto back faces count
 * nothing, so the links add up to the floor's solid angle (analytic) seen from above, and to nothing
 * from below. */
/* An open floor, [-1, 1]² in y = 0 facing +y, as Q x Q quads; the scene is finalised, not traced. */
static void make_open_floor(world *w) {
    enum { Q = 8 };
    memset(w, 0, sizeof *w);
    glow__scene *sc = &w->scene;
    sc->tri_count = 2 * Q * Q;
    sc->pos = malloc((size_t)sc->tri_count * 3 * sizeof *sc->pos);
    sc->tri_material = calloc(sc->tri_count, sizeof *sc->tri_material);
    sc->materials = calloc(1, sizeof *sc->materials);
    assert_true(sc->pos && sc->tri_material && sc->materials);
    sc->material_count = 1;
    for (int k = 0; k < 3; ++k) sc->materials[0].albedo[k] = 0.5f;
    uint32_t t = 0;
    for (int i = 0; i < Q; ++i)
        for (int j = 0; j < Q; ++j) {
            float x0 = -1.0f + 2.0f * i / Q, x1 = -1.0f + 2.0f * (i + 1) / Q;
            float z0 = -1.0f + 2.0f * j / Q, z1 = -1.0f + 2.0f * (j + 1) / Q;
            /* counter-clockwise seen from +y: (x0,z1) -> (x1,z1) -> (x1,z0) -> (x0,z0) */
            float quad[4][3] = {{x0, 0, z1}, {x1, 0, z1}, {x1, 0, z0}, {x0, 0, z0}};
            const int idx[2][3] = {{0, 1, 2}, {0, 2, 3}};
            for (int a = 0; a < 2; ++a, ++t)
                for (int c = 0; c < 3; ++c) memcpy(sc->pos[3 * t + c], quad[idx[a][c]], sizeof quad[0]);
        }
    assert_int_equal(glow__scene_finalize(sc, &w->log), GLOW_OK);
}

static void test_normalise_open_floor(void **state) {
    (void)state;
    world w;
    make_open_floor(&w);
    glow__scene *sc = &w.scene;
    assert_int_equal(glow__rt_create(sc, &w.log, &w.rt), GLOW_OK);
    w.pool = glow__pool_create(2);
    glow__surfel_settings ss = {.count = 4096, .seed = 1, .relax_iterations = 4};
    assert_int_equal(glow__surfels_place(sc, &ss, w.pool, &w.log, &w.surfels), GLOW_OK);
    assert_int_equal(glow__hierarchy_build(&w.surfels, sc->bounds_min, sc->bounds_max, w.pool, &w.log, &w.h), GLOW_OK);
    /* the floor is in y = 0 and faces +y */
    assert_true(w.surfels.s[0].nrm[1] > 0.99f);

    glow__caches c = caches_alloc(4);
    c.caches[0] = (glow__cache){.pos = {0.0f, 0.5f, 0.0f}, .kind = GLOW_CACHE_KIND_GRID};
    c.caches[1] = (glow__cache){.pos = {0.4f, 0.25f, -0.3f}, .kind = GLOW_CACHE_KIND_GRID};
    c.caches[2] = (glow__cache){.pos = {-0.2f, 0.1f, 0.5f}, .kind = GLOW_CACHE_KIND_GRID};
    c.caches[3] = (glow__cache){.pos = {0.1f, -0.5f, 0.0f}, .kind = GLOW_CACHE_KIND_GRID}; /* sees the back */
    const uint32_t nl = 256;
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .rays_per_surfel = 1};
    glow__links L;
    assert_int_equal(glow__links_build(sc, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L), GLOW_OK);
    for (uint32_t ci = 0; ci < 4; ++ci) {
        const float *p = c.caches[ci].pos;
        double expect = p[1] > 0.0f ? rect_solid_angle(-1.0 - p[0], 1.0 - p[0], -1.0 - p[2], 1.0 - p[2], p[1]) : 0.0;
        double total = 0.0;
        for (uint32_t j = 0; j < nl; ++j)
            if (L.links[ci * nl + j].factor != 0.0f) total += link_omega(&L.links[ci * nl + j]);
        print_message("open floor, cache %u: solid angle %.4f, analytic %.4f\n", ci, total, expect);
        if (fabs(total - expect) > 0.015 * expect + 1e-6)
            fail_msg("cache %u: solid angle %g, expected %g", ci, total, expect);
    }
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}

/* A system of a bake split into systems (glow__rt_create_system): another system's surface occludes,
 * reports foreign hits, and counts for the normalisation as the sky does. The open floor is the
 * system; a 1 x 1 ceiling tile of another system hangs at y = 0.8 over its middle, facing down. Below
 * it, a cache sees the whole floor and its links must sum to the floor's analytic solid angle (had the
 * tile's underside counted as visible geometry, the normalisation would have scaled them up by the
 * tile's share); above it, the tile hides the whole floor (its shadow from y = 1.2 is 3 x 3). */
static void test_foreign_occluders(void **state) {
    (void)state;
    world w;
    make_open_floor(&w);
    glow__scene *sc = &w.scene;
    /* counter-clockwise seen from -y */
    const float tile[2][9] = {{-0.5f, 0.8f, -0.5f, 0.5f, 0.8f, -0.5f, 0.5f, 0.8f, 0.5f},
                              {-0.5f, 0.8f, -0.5f, 0.5f, 0.8f, 0.5f, -0.5f, 0.8f, 0.5f}};
    assert_int_equal(glow__rt_create_system(sc, &tile[0][0], 2, &w.log, &w.rt), GLOW_OK);
    const float below[3] = {0.0f, 0.5f, 0.0f}, above[3] = {0.0f, 1.2f, 0.0f}, up[3] = {0, 1, 0}, down[3] = {0, -1, 0};
    glow__hit h = glow__rt_intersect(w.rt, below, up, 0.0f, INFINITY);
    assert_true(h.foreign && h.tri == UINT32_MAX && !h.back_face && fabsf(h.t - 0.3f) < 1e-4f);
    h = glow__rt_intersect(w.rt, above, down, 0.0f, INFINITY);
    assert_true(h.foreign && h.back_face && fabsf(h.t - 0.4f) < 1e-4f);
    h = glow__rt_intersect(w.rt, below, down, 0.0f, INFINITY); /* the system's own floor */
    assert_true(!h.foreign && h.tri < sc->tri_count && fabsf(h.t - 0.5f) < 1e-4f);
    assert_true(glow__rt_occluded(w.rt, above, down, 0.0f, 1.0f));

    w.pool = glow__pool_create(2);
    glow__surfel_settings ss = {.count = 4096, .seed = 1, .relax_iterations = 4};
    assert_int_equal(glow__surfels_place(sc, &ss, w.pool, &w.log, &w.surfels), GLOW_OK);
    assert_int_equal(glow__hierarchy_build(&w.surfels, sc->bounds_min, sc->bounds_max, w.pool, &w.log, &w.h), GLOW_OK);
    glow__caches c = caches_alloc(2);
    c.caches[0] = (glow__cache){.pos = {0.0f, 0.5f, 0.0f}, .kind = GLOW_CACHE_KIND_GRID};
    c.caches[1] = (glow__cache){.pos = {0.0f, 1.2f, 0.0f}, .kind = GLOW_CACHE_KIND_GRID};
    const uint32_t nl = 256;
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .rays_per_surfel = 1};
    glow__links L;
    assert_int_equal(glow__links_build(sc, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L), GLOW_OK);
    double total[2] = {0.0, 0.0};
    for (uint32_t ci = 0; ci < 2; ++ci)
        for (uint32_t j = 0; j < nl; ++j)
            if (L.links[ci * nl + j].factor != 0.0f) total[ci] += link_omega(&L.links[ci * nl + j]);
    const double floor_below = rect_solid_angle(-1.0, 1.0, -1.0, 1.0, 0.5);
    print_message("foreign tile: below %.4f (floor %.4f), above %.4f\n", total[0], floor_below, total[1]);
    if (fabs(total[0] - floor_below) > 0.015 * floor_below)
        fail_msg("below the tile: links %g sr, the floor %g sr", total[0], floor_below);
    if (!(total[1] < 0.01 * floor_below)) fail_msg("above the tile: links %g sr, the floor is hidden", total[1]);
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}

/* Lightmap caches are shaded with their cosine-weighted irradiance, so after the normalisation the
 * links must carry the right cosine moment too, not only the right total: from anywhere on the
 * furnace box's floor, Σ ω (n · dir) over the links = ∫ cos θ over the hemisphere = π. With n_L
 * above the leaf count every link is one surfel, so this measures the leaves themselves. When the
 * surfels that relaxation pushed onto the floor's edges were dropped as "below the horizon", the
 * walls lost ~12 % of their solid angle within 7° of the horizon, the normalisation spread that
 * over the hemisphere, and the moment came out high: 1.011-1.023 (mean of 25 texels, surfel seeds
 * 1-5). Now 0.990-0.999: a little low, because the edge surfels sit at the very bottom of the strip
 * they stand for (relaxation piles them up at the edge). */
static void test_normalise_keeps_cosine_moment(void **state) {
    (void)state;
    world w;
    world_make(&w, "furnace", 2048, 2);
    enum { G = 5 };
    glow__caches c = caches_alloc(G * G);
    const float lift = 1e-4f * sqrtf(12.0f); /* caches.c: 1e-4 x the scene diagonal */
    for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j)
            c.caches[i * G + j] = (glow__cache){.pos = {-0.8f + 1.6f * i / (G - 1), -1.0f + lift,
                                                        -0.8f + 1.6f * j / (G - 1)},
                                                .nrm = {0, 1, 0}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
    const uint32_t nl = 2048;
    glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 2, .rays_per_surfel = 1, .no_cone_fit = true};
    glow__links L;
    assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                     GLOW_OK);
    double mean_total = 0.0, mean_cos = 0.0;
    for (uint32_t ci = 0; ci < G * G; ++ci) {
        double total = 0.0, cosm = 0.0;
        for (uint32_t j = 0; j < nl; ++j) {
            const glow__link *l = &L.links[ci * nl + j];
            if (l->factor == 0.0f) continue;
            assert_true(l->node < w.h.leaf_count); /* every link is a leaf */
            total += link_omega(l);
            cosm += link_omega(l) * glow__dot(l->dir, c.caches[ci].nrm);
        }
        assert_true(fabs(total / (2.0 * GLOW__PI) - 1.0) < 1e-3); /* closed box: normalised to 2π */
        mean_total += total / (2.0 * GLOW__PI) / (G * G);
        mean_cos += cosm / GLOW__PI / (G * G);
    }
    print_message("floor texels: solid angle / 2π %.5f, cosine moment / π %.5f\n", mean_total, mean_cos);
    if (!(mean_cos > 0.98 && mean_cos < 1.008)) fail_msg("cosine moment %g of π, expected 0.98-1.008", mean_cos);
    glow__links_free(&L);
    free(c.caches);
    world_free(&w);
}

static void test_links_deterministic_across_threads(void **state) {
    (void)state;
    glow__links out[2];
    for (int t = 0; t < 2; ++t) {
        world w;
        world_make(&w, "cornell", 2048, t == 0 ? 1 : 3);
        glow__caches c = two_caches();
        glow__link_settings ls = {.links_per_cache = 48, .sh_bands = 3, .full_sh = true, .rays_per_surfel = 2};
        assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &out[t]),
                         GLOW_OK);
        free(c.caches);
        world_free(&w);
    }
    assert_memory_equal(out[0].links, out[1].links, sizeof(glow__link) * 2 * 48);
    assert_memory_equal(out[0].sh, out[1].sh, sizeof(float) * 2 * 48 * 9);
    glow__links_free(&out[0]);
    glow__links_free(&out[1]);
}

/* Clustered visibility (links.c cl_runs, the pipeline's default: angle 0.3, 4 rays a cluster) against
 * the exact pass, one ray per (cache, surfel): in the pillar hall (16k surfels, 0.08 m apart, so that
 * clusters look small from a few metres), 48 lightmap caches on the floor and 16 grid caches in the
 * air. Per cache, the raw visible solid angle (no normalisation) and the gather of a radiance with a
 * hard step (the hall's two halves, 1 against 4) through the cut must agree within 1 % on average and
 * 5 % at worst (measured: 0.56 % / 2.3 % and 0.87 % / 2.9 %, 0.52 / 1.9 and 0.63 / 2.1 before mixed
 * clusters kept their parts (links.c mixed_part); a cluster solid angle 10 % too large
 * fails it); the clustered pass must cast at most half the rays (it casts a tenth) and give the same
 * bytes for any thread count. */
static double node_mean(const world *w, const float *B, uint32_t v) {
    uint32_t stack[128], sp = 0, cnt = 0;
    double sum = 0.0;
    stack[sp++] = v;
    while (sp) {
        const uint32_t u = stack[--sp];
        if (u < w->h.leaf_count) { sum += B[u]; cnt++; continue; }
        if (sp + 2 > 128) fail_msg("node_mean: stack");
        stack[sp++] = w->h.nodes[u].child[0];
        stack[sp++] = w->h.nodes[u].child[1];
    }
    return cnt ? sum / cnt : 0.0;
}
static void test_clustered_matches_exact(void **state) {
    (void)state;
    const uint32_t nl = 96, nc = 64;
    glow__links L[3];
    world w;
    float *B = NULL;
    glow__caches c = caches_alloc(nc);
    for (uint32_t i = 0; i < nc; ++i) {
        const float fx = -5.5f + 11.0f * (float)((i * 37u) % 64u) / 63.0f, fz = -2.6f + 5.2f * (float)((i * 23u) % 64u) / 63.0f;
        if (i < 48) c.caches[i] = (glow__cache){.pos = {fx, 0.001f, fz}, .nrm = {0, 1, 0}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
        else c.caches[i] = (glow__cache){.pos = {fx, 1.2f + 0.1f * (float)(i % 7u), fz}, .kind = GLOW_CACHE_KIND_GRID};
        if (fabsf(fmodf(fabsf(fx), 2.0f)) < 0.3f && fabsf(fz) < 0.3f) c.caches[i].pos[2] += 0.6f; /* off the pillars */
    }
    for (int k = 0; k < 3; ++k) {
        world_make(&w, "pillar-hall", 16384, k == 2 ? 1 : 2);
        glow__link_settings ls = {.links_per_cache = nl, .sh_bands = 3, .rays_per_surfel = 1, .no_cone_fit = true,
                                  .no_normalize = true, .cut_error = true, .link_subsets = true,
                                  .cluster_tau = k > 0 ? 0.3f : 0.0f, .cluster_samples = 4};
        assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L[k]),
                         GLOW_OK);
        if (k < 2) world_free(&w);
    }
    B = malloc(w.h.leaf_count * sizeof *B);
    assert_non_null(B);
    for (uint32_t i = 0; i < w.h.leaf_count; ++i) B[i] = w.surfels.s[i].pos[0] < 0.0f ? 1.0f : 4.0f;
    double err_om = 0.0, err_g = 0.0, max_om = 0.0, max_g = 0.0;
    for (uint32_t ci = 0; ci < nc; ++ci) {
        double om[2] = {0, 0}, g[2] = {0, 0};
        for (int k = 0; k < 2; ++k)
            for (uint32_t j = 0; j < nl; ++j) {
                const glow__link *l = &L[k].links[ci * nl + j];
                if (l->factor == 0.0f) continue;
                om[k] += link_omega(l);
                g[k] += link_omega(l) * node_mean(&w, B, l->node);
            }
        assert_true(om[0] > 1.0);
        const double eo = fabs(om[1] / om[0] - 1.0), eg = fabs(g[1] / g[0] - 1.0);
        err_om += eo / nc;
        err_g += eg / nc;
        max_om = eo > max_om ? eo : max_om;
        max_g = eg > max_g ? eg : max_g;
    }
    printf("clustered vs exact, %u caches: solid angle mean %.4f max %.4f, gather mean %.4f max %.4f; rays %llu vs %llu\n",
           nc, err_om, max_om, err_g, max_g, (unsigned long long)L[1].visibility_rays,
           (unsigned long long)L[0].visibility_rays);
    if (err_om > 0.01 || max_om > 0.05) fail_msg("solid angle: mean %g, max %g", err_om, max_om);
    if (err_g > 0.01 || max_g > 0.05) fail_msg("gather: mean %g, max %g", err_g, max_g);
    assert_true(2 * L[1].visibility_rays <= L[0].visibility_rays);
    assert_memory_equal(L[1].links, L[2].links, (size_t)nc * nl * sizeof *L[1].links);
    for (int k = 0; k < 3; ++k) glow__links_free(&L[k]);
    free(B);
    free(c.caches);
    world_free(&w);
}

/* The cone fit (cone_fit.c): a lightmap cache's links are sized so that their diffuse response at
 * the cache normal, with the bake's bands, adds up to the rays' estimate for the visible geometry —
 * in the closed furnace box exactly the response of a full hemisphere of unit radiance, 1 (E/π).
 * Without the fit the equal-solid-angle cones overstate spread-out clusters: measured +0.8 % on
 * average and up to +14 % at the box's corners (4096 surfels, 96 links); with it every floor,
 * wall and corner texel is within 0.1 %. Grid caches keep their solid angle. */
static void test_cone_fit_response(void **state) {
    (void)state;
    world w;
    world_make(&w, "furnace", 4096, 2);
    enum { G = 4 };
    glow__caches c = caches_alloc(G * G + 1);
    const float lift = 1e-4f * sqrtf(12.0f);
    for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j) /* floor texels, corners included */
            c.caches[i * G + j] = (glow__cache){.pos = {-0.985f + 1.97f * i / (G - 1), -1.0f + lift,
                                                        -0.985f + 1.97f * j / (G - 1)},
                                                .nrm = {0, 1, 0}, .kind = GLOW_CACHE_KIND_LIGHTMAP};
    c.caches[G * G] = (glow__cache){.pos = {0.1f, 0.2f, 0.3f}, .kind = GLOW_CACHE_KIND_GRID};
    for (int fit = 0; fit < 2; ++fit) {
        glow__link_settings ls = {.links_per_cache = 96, .sh_bands = 3, .rays_per_surfel = 1, .no_cone_fit = !fit};
        glow__links L;
        assert_int_equal(glow__links_build(&w.scene, w.rt, &w.surfels, &w.h, &c, &ls, w.pool, &w.log, NULL, NULL, &L),
                         GLOW_OK);
        double worst = 0.0, grid_total = 0.0;
        for (uint32_t ci = 0; ci <= G * G; ++ci) {
            double resp = 0.0;
            for (uint32_t j = 0; j < 96; ++j) {
                const glow__link *l = &L.links[ci * 96 + j];
                if (l->factor == 0.0f) continue;
                if (ci == G * G) grid_total += link_omega(l);
                else resp += glow__cone_irr(3, l->one_minus_cos, glow__dot(l->dir, c.caches[ci].nrm));
            }
            if (ci < G * G) worst = fmax(worst, fabs(resp - 1.0));
        }
        print_message("cone fit %s: worst floor-texel response error %.4f\n", fit ? "on" : "off", worst);
        if (fit) assert_true(worst < 0.002);
        else assert_true(worst > 0.01); /* the bias the fit removes is really there */
        assert_true(fabs(grid_total / (4.0 * GLOW__PI) - 1.0) < 1e-3); /* grid: solid angle kept */
        glow__links_free(&L);
    }
    free(c.caches);
    world_free(&w);
}

/* The fit's target is the exact cosine (cone_fit.c): a small cone (half-angle 8°) near a texel's
 * horizon (cos 0.1 to the normal), whose 3-band response is 1.5x the cosine's ω · 0.1 / π, shrinks
 * until its 3-band response is that; a cluster at or below the horizon gets no cone; one at the
 * normal shrinks a little (K_3(1) is 1.0625 of the cosine's 1/π). */
static void test_cone_fit_exact_cosine(void **state) {
    (void)state;
    const float omc = 0.01f;
    const double omega = 2.0 * GLOW__PI * omc;
    /* the fitted cone's omc against the solid-angle cone's: measured 0.668, 0.414 and 0.947 */
    struct { double t, min_ratio, max_ratio; } cases[] = {{0.1, 0.55, 0.8}, {0.05, 0.3, 0.55}, {1.0, 0.9, 0.97}};
    for (int i = 0; i < 3; ++i) {
        const double t = cases[i].t, target = omega * glow__cos_kernel(t), k3 = glow__cone_irr(3, omc, t);
        const float fit = glow__cone_fit_omc(3, omc, t, target);
        const double got = glow__cone_irr(3, fit, t);
        print_message("cos %.2f: 3-band cone %.3e, exact %.3e, fitted cone %.3e (omc %.5f -> %.5f)\n", t, k3, target, got,
                      (double)omc, (double)fit);
        assert_true(fabs(got / target - 1.0) < 1e-4);
        assert_true(fit / omc > cases[i].min_ratio && fit / omc < cases[i].max_ratio);
    }
    assert_true(glow__cone_fit_omc(3, omc, -0.01, 0.0) == 0.0f); /* at or below the horizon: no cone */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sh_orthonormal),
        cmocka_unit_test(test_cone_factors_quadrature),
        cmocka_unit_test(test_cut_covers_visible_scene),
        cmocka_unit_test(test_cut_error),
        cmocka_unit_test(test_cut_error_response),
        cmocka_unit_test(test_cut_refines_to_leaves),
        cmocka_unit_test(test_visibility_blocks_other_room),
        cmocka_unit_test(test_full_sh_matches_runtime_dc),
        cmocka_unit_test(test_near_field_closes),
        cmocka_unit_test(test_normalise_open_floor),
        cmocka_unit_test(test_foreign_occluders),
        cmocka_unit_test(test_normalise_keeps_cosine_moment),
        cmocka_unit_test(test_cone_fit_response),
        cmocka_unit_test(test_cone_fit_exact_cosine),
        cmocka_unit_test(test_links_deterministic_across_threads),
        cmocka_unit_test(test_clustered_matches_exact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
