/* test_parallel_squares.c — the whole chain (linker -> runtime solver -> SH shading) against an
 * analytic radiative-transfer answer: two directly opposed parallel unit squares (side a = b = 1 m)
 * a distance c apart (tests/data/scenes/parallel-squares.obj: c = 0.5 m; parallel-squares-far.obj:
 * c = 1 m), the upper one emitting radiance L = 1 W/(m²·sr) downwards, both black (albedo 0: only
 * direct transfer).
 *
 * Irradiance at a receiver point p is E(p) = π L F_dA(p), F_dA the differential configuration
 * factor from the point to the emitter (four corner rectangles); over the receiver, mean E =
 * π L F_12 (reciprocity with equal areas: A_1 F_12 = A_2 F_21), F_12 Howell's C-11 ("two parallel,
 * directly opposed rectangles"). The runtime's estimate at a lightmap cache is
 * E = π · glow_shade_sh(cache SH, normal, exponent 1).
 *
 * Two expectations per cache:
 *   E_true(p)  the closed form above;
 *   E_B(p)     what a *perfect* B-band solver returns: the exact incident radiance projected onto
 *              bands l < B and convolved with the cosine lobe, by the addition theorem
 *                  E_B = π L Σ_{l<B} s_l (2l+1)/(4π) ∫_emitter P_l(cos θ) dω,
 *              integrated over the emitter by Gauss-Legendre quadrature, s_l = 2∫_0^1 t P_l(t) dt
 *              also by quadrature (independent of the runtime's code).
 * E_B - E_true is the SH truncation error of a perfect B-band projection: with 3 bands the cosine
 * lobe's l = 4, 6, ... terms (s_4 = -1/24, s_6 = 1/64) are dropped, which over-estimates compact
 * sources near the normal (a point source at the zenith by 6.25 %) and more so near the horizon;
 * measured here: +0.4 % mean at c = 0.5 m, +2.9 % at c = 1 m (the emitter subtends less). The
 * linker's cone fit (cone_fit.c) sizes each lightmap link's cone so that its B-band response at the
 * cache normal is the exact cosine-weighted one, so at the normal the solver is judged against
 * E_true at every band count (until 2026-11-29 the fit targeted the B-band kernel and the solver
 * was judged against E_B).
 *
 * The closed forms are checked against each other and against brute-force quadrature of
 * cosθ cosθ' / (π r²); E_B against E_true for B = 64.
 *
 * Layers, each checked on its own:
 *   1. the solver's arithmetic: each receiver cache's E re-summed in double from the bake's own links
 *      (node radiance = L x emitting area fraction, cone factors, addition theorem): 1e-4 relative
 *      (measured 3e-6);
 *   2. the links + solver against E_B (what a perfect B-band solver gives). What remains is link
 *      discretisation: 128 cones per cache stand for the emitter, each with its node's visible solid
 *      angle (normalised per cache to ray-measured visibility: factor 0.96-1.04 here) but round and
 *      centred on the node's mean direction. Per cache this is noisy: the decoded links' solid angles
 *      alone are off by up to +-6.5 % at c = 1 m (per-cache E follows them within 0.1 %), which the
 *      mean over ~1000 caches averages out;
 *   3. sampling: the mean over caches is a midpoint rule over texel centres (all texel centres lie
 *      inside the square here); its own bias against the area mean, E_true averaged at the caches
 *      vs π L F_12, is measured too (-0.7 % at c = 0.5, -0.4 % at c = 1) and must stay below 1 %.
 * Tolerances: 3 % for the means, for the centre (the mean of the ~30 caches within 0.1 m, and a
 * bilinear lightmap sample there) and for the rms over the caches; 10 % for the worst single
 * interior cache (covers the +-6.5 % per-cache solid-angle error of layer 2 plus SH and cone-shape
 * error; a single cache has no averaging).
 * Measured (seed 1; solver vs E_B / vs E_true; the bake has 3 bands, the 8-band system reads it with
 * more bands than its cones were fitted for, so there the fit's correction of the 3-band truncation is
 * wrong by about that truncation: bake with the bands you run):
 *   c = 0.5, 3 bands: mean -0.44 % / +0.00 %, rms 1.4 %, worst cache 3.9 %, centre -0.91 % / -0.10 %
 *   c = 0.5, 8 bands: mean -0.32 % / -0.23 %, worst cache 5.0 %, centre -0.97 % (vs E_true)
 *   c = 1,   3 bands: mean -2.57 % / +0.27 % (the truncation alone is +2.9 %), worst 7.1 %, centre +0.94 %
 *   c = 1,   8 bands: an 8-band bake mean +0.34 % / +0.27 %, worst cache 7.2 % (vs E_true); the 3-band
 *            bake read with 8 bands -2.55 % / -2.62 %, rms 3.5 %, centre -2.92 % (not tested: above)
 * (until 2026-11-29, cones fitted to the 3-band kernel: c = 1, 3 bands +0.35 % / +3.3 %; 8 bands
 * +0.34 % / +0.27 %.)
 * Printed on every run. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bake/bake_format.h"
#include "glow/glow.h"
#include "glow/glow_precompute.h"
#include "runtime_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define SIDE 1.0     /* a = b, m */
#define RADIANCE 1.0 /* emitter Ke, W/(m² sr) */
#define MAXB 64      /* bands of the band-limited reference's self-check */

/* ------------------------------------------------------------------------------ analytics */
/* Howell C-11: two parallel, directly opposed rectangles a x b at distance c; X = a/c, Y = b/c. */
static double f_parallel_rects(double X, double Y) {
    double X2 = X * X, Y2 = Y * Y;
    double t = log(sqrt((1.0 + X2) * (1.0 + Y2) / (1.0 + X2 + Y2))) + X * sqrt(1.0 + Y2) * atan(X / sqrt(1.0 + Y2)) +
               Y * sqrt(1.0 + X2) * atan(Y / sqrt(1.0 + X2)) - X * atan(X) - Y * atan(Y);
    return 2.0 / (M_PI * X * Y) * t;
}

/* Differential element to a parallel rectangle A x B (in units of the distance) with one corner
 * on the element's normal. */
static double f_corner(double A, double B) {
    if (A <= 0.0 || B <= 0.0) return 0.0;
    double sa = sqrt(1.0 + A * A), sb = sqrt(1.0 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2.0 * M_PI);
}

static double clamp_side(double x) { return x < 0.0 ? 0.0 : (x > SIDE ? SIDE : x); }

/* Point (x, z) on the receiver (its projection lies inside the emitter), distance c: four corner
 * rectangles. */
static double f_point(double x, double z, double c) {
    x = clamp_side(x);
    z = clamp_side(z);
    double xs[2] = {x, SIDE - x}, zs[2] = {z, SIDE - z}, f = 0.0;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) f += f_corner(xs[i] / c, zs[j] / c);
    return f;
}

static double exact_irradiance(double x, double z, double c) { return M_PI * RADIANCE * f_point(x, z, c); }

/* Gauss-Legendre nodes/weights on [-1, 1] (Newton on P_n). */
static void gauss_legendre(int n, double *x, double *w) {
    for (int i = 0; i < n; ++i) {
        double t = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (t * p1 - p0) / (t * t - 1.0);
            double dt = p1 / dp;
            t -= dt;
            if (fabs(dt) < 1e-15) break;
        }
        x[i] = t;
        w[i] = 2.0 / ((1.0 - t * t) * dp * dp);
    }
}

/* Composite Gauss-Legendre rule on [0, SIDE]: QP panels x QN nodes. */
enum { QN = 8, QP = 4, QTOT = QN * QP };
static double q_x[QTOT], q_w[QTOT];
/* s_l of the cosine lobe, 2 ∫_0^1 t P_l(t) dt, by 16-node Gauss-Legendre (exact to degree 31) */
static double s_cos[MAXB];

static void init_quadrature(void) {
    double gx[QN], gw[QN];
    gauss_legendre(QN, gx, gw);
    for (int p = 0; p < QP; ++p)
        for (int i = 0; i < QN; ++i) {
            q_x[p * QN + i] = SIDE * (p + 0.5 * (gx[i] + 1.0)) / QP;
            q_w[p * QN + i] = SIDE * gw[i] * 0.5 / QP;
        }
    /* s_l: degree l + 1 <= 64 needs more nodes than 16 for large l: 40 nodes (exact to degree 79) */
    double hx[40], hw[40];
    gauss_legendre(40, hx, hw);
    for (int l = 0; l < MAXB; ++l) {
        double s = 0.0;
        for (int i = 0; i < 40; ++i) {
            double t = 0.5 * (hx[i] + 1.0), p0 = 1.0, p1 = t;
            for (int k = 2; k <= l; ++k) {
                double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            s += 0.5 * hw[i] * t * (l == 0 ? 1.0 : p1);
        }
        s_cos[l] = 2.0 * s;
    }
}

/* E_B(p) for B = 1..bands into out[B] (out[0] = 0), the emitter at distance c above the receiver:
 * dω = c / r³ dA and cos θ = c / r on the emitter. */
static void band_limited_irradiance(double x, double z, double c, int bands, double *out) {
    double acc[MAXB] = {0};
    for (int i = 0; i < QTOT; ++i)
        for (int j = 0; j < QTOT; ++j) {
            double dx = q_x[i] - x, dz = q_x[j] - z, r = sqrt(dx * dx + dz * dz + c * c);
            double t = c / r, w = q_w[i] * q_w[j] * c / (r * r * r);
            double p0 = 1.0, p1 = t;
            acc[0] += w;
            if (bands > 1) acc[1] += w * t;
            for (int l = 2; l < bands; ++l) {
                double p2 = ((2.0 * l - 1.0) * t * p1 - (l - 1.0) * p0) / l;
                p0 = p1;
                p1 = p2;
                acc[l] += w * p2;
            }
        }
    out[0] = 0.0;
    double e = 0.0;
    for (int l = 0; l < bands; ++l) {
        e += RADIANCE * s_cos[l] * (2.0 * l + 1.0) / 4.0 * acc[l]; /* π L s_l (2l+1)/(4π) ∫ P_l dω */
        out[l + 1] = e;
    }
}

/* The closed forms against each other and against direct quadrature of the kernel. */
static void analytic_forms(double c) {
    /* mean of the pointwise factor over the receiver == F_12 */
    double mean = 0.0;
    for (int i = 0; i < QTOT; ++i)
        for (int j = 0; j < QTOT; ++j) mean += q_w[i] * q_w[j] * f_point(q_x[i], q_x[j], c);
    double F = f_parallel_rects(SIDE / c, SIDE / c);
    print_message("c = %.1f: F_12 (Howell C-11, X = Y = %.1f) = %.6f; mean of the pointwise factor = %.6f\n", c, SIDE / c,
                  F, mean);
    assert_true(fabs(mean - F) < 1e-6 * F);
    /* the pointwise factor against the kernel cosθ cosθ' / (π r²) = c² / (π r⁴) over the emitter, and
     * the band-limited irradiance against the exact one as B grows */
    const double pts[3][2] = {{0.5, 0.5}, {0.2, 0.7}, {0.03, 0.95}};
    for (int p = 0; p < 3; ++p) {
        double q = 0.0;
        for (int i = 0; i < QTOT; ++i)
            for (int j = 0; j < QTOT; ++j) {
                double dx = q_x[i] - pts[p][0], dz = q_x[j] - pts[p][1];
                double r2 = dx * dx + dz * dz + c * c;
                q += q_w[i] * q_w[j] * c * c / (M_PI * r2 * r2);
            }
        double f = f_point(pts[p][0], pts[p][1], c);
        if (fabs(q - f) > 1e-6 * f) fail_msg("point (%g, %g): closed form %.8f, quadrature %.8f", pts[p][0], pts[p][1], f, q);
        double eb[MAXB + 1];
        band_limited_irradiance(pts[p][0], pts[p][1], c, MAXB, eb);
        double e = exact_irradiance(pts[p][0], pts[p][1], c);
        print_message("  point (%.2f, %.2f): E %.5f; band-limited E_3 %+.2f %%, E_8 %+.2f %%, E_64 %+.4f %%\n", pts[p][0],
                      pts[p][1], e, 100.0 * (eb[3] / e - 1.0), 100.0 * (eb[8] / e - 1.0), 100.0 * (eb[MAXB] / e - 1.0));
        if (fabs(eb[MAXB] / e - 1.0) > 2e-3) fail_msg("band-limited irradiance with %d bands %.6f vs exact %.6f", MAXB, eb[MAXB], e);
    }
}

static void test_analytic_forms(void **state) {
    (void)state;
    /* the lobe factors by quadrature: 1, 2/3, 1/4, 0, -1/24 */
    assert_true(fabs(s_cos[0] - 1.0) < 1e-12 && fabs(s_cos[1] - 2.0 / 3.0) < 1e-12 && fabs(s_cos[2] - 0.25) < 1e-12);
    assert_true(fabs(s_cos[3]) < 1e-12 && fabs(s_cos[4] + 1.0 / 24.0) < 1e-12);
    analytic_forms(0.5);
    analytic_forms(1.0);
    /* Howell's tabulated value for X = Y = 1 is 0.1998 */
    assert_true(fabs(f_parallel_rects(1.0, 1.0) - 0.19982) < 1e-4);
    /* known limits: a huge rectangle sees everything, a far one ~ A / (π c²) per unit area */
    assert_true(fabs(f_parallel_rects(1e4, 1e4) - 1.0) < 1e-3);
    assert_true(fabs(f_parallel_rects(1e-3, 1e-3) - 1e-6 / M_PI) < 1e-3 * 1e-6 / M_PI);
}

/* ------------------------------------------------------------------------------ the bake */
typedef struct fixture {
    char path[256];
    double dist; /* c */
    glow_context *ctx;
    glow_bake *bake;
} fixture;

static int setup_scene(void **state, const char *obj, double dist, uint32_t bands) {
    fixture *f = calloc(1, sizeof *f);
    if (!f) return -1;
    f->dist = dist;
    snprintf(f->path, sizeof f->path, "/tmp/glow_parallel_squares_%d_%g_%u.glow", (int)getpid(), dist, bands);
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 8192, .links = 128, .bands = bands, .threads = 2, .seed = 1};
    glow_pc_stats st;
    glow_result r = glow_pc_bake(obj, f->path, &s, &st);
    if (r != GLOW_OK) {
        print_error("bake failed: %s\n", st.error);
        free(f);
        return -1;
    }
    glow_context_desc cd = {.api_version = GLOW_VERSION, .tasks = {.worker_count = 2}};
    if (glow_context_create(&cd, &f->ctx) != GLOW_OK || glow_bake_load_file(f->ctx, f->path, &f->bake) != GLOW_OK) {
        glow_context_destroy(f->ctx);
        unlink(f->path);
        free(f);
        return -1;
    }
    *state = f;
    return 0;
}

static int setup_near(void **state) { return setup_scene(state, GLOW_TEST_DATA_DIR "/scenes/parallel-squares.obj", 0.5, 3); }
static int setup_far(void **state) { return setup_scene(state, GLOW_TEST_DATA_DIR "/scenes/parallel-squares-far.obj", 1.0, 3); }
/* an 8-band bake: its cones are fitted for 8 bands (cone_fit.c) */
static int setup_far8(void **state) { return setup_scene(state, GLOW_TEST_DATA_DIR "/scenes/parallel-squares-far.obj", 1.0, 8); }

static int teardown(void **state) {
    fixture *f = *state;
    glow_bake_destroy(f->bake);
    glow_context_destroy(f->ctx);
    unlink(f->path);
    free(f);
    return 0;
}

/* E at every receiver cache of a system with `luma` bands (0 = the bake's), against E_B and E_true
 * at the cache positions, the area mean, and the centre. `vs_true`: also hold the solver to E_true. */
static void check_receiver(fixture *f, uint32_t luma, bool vs_true) {
    const double tol_mean = 0.03, tol_centre = 0.03, tol_rms = 0.03, tol_worst = 0.10, tol_links = 1e-4;
    glow_system *sys;
    glow_system_desc sd = {.bake = f->bake, .sh_bands_luma = luma, .label = "parallel-squares"};
    assert_int_equal(glow_system_create(f->ctx, &sd, &sys), GLOW_OK);
    /* no hook and nothing pushed: the emitter's emission is the only light; albedo 0 anyway */
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(sys);
    const glow_bake_meta *m = glow__bake_meta(f->bake);
    const glow_bake_cache *caches = glow__bake_caches(f->bake);
    assert_int_equal(o->cache_count, m->cache_count);
    const int B = (int)o->sh_bands_luma;
    const double c = f->dist;
    /* node radiance: L times the emitting fraction of the node's area, summed up the tree here */
    const glow_bake_surfel *sf = glow__bake_surfels(f->bake);
    const glow_bake_node *nodes = glow__bake_nodes(f->bake);
    const uint32_t *lv = glow__bake_level_starts(f->bake);
    double *emit_area = calloc(m->node_count, sizeof *emit_area);
    assert_non_null(emit_area);
    for (uint32_t i = 0; i < m->surfel_count; ++i) emit_area[i] = sf[i].emission[1] > 0.0f ? nodes[i].area : 0.0;
    for (uint32_t L = 1; L < m->level_count; ++L)
        for (uint32_t v = lv[L]; v < lv[L + 1]; ++v) emit_area[v] = emit_area[nodes[v].child[0]] + emit_area[nodes[v].child[1]];
    const glow_bake_link_block *lb = glow__bake_link_blocks(f->bake);
    double worst_links = 0.0;

    const float up[3] = {0.0f, 1.0f, 0.0f};
    const double h = 1.0 / m->texel_density; /* texel size in m (the charts are not scaled) */
    uint32_t n_all = 0, n_in = 0, n_emitter_side = 0, n_centre = 0;
    double sum_rt = 0.0, sum_ex = 0.0, sum_eb = 0.0, sum_rt_in = 0.0, sum_ex_in = 0.0, worst = 0.0, sq = 0.0;
    double centre_rt = 0.0, centre_ex = 0.0, centre_eb = 0.0;
    for (uint32_t k = 0; k < m->cache_count; ++k) {
        if (caches[k].kind != GLOW_CACHE_KIND_LIGHTMAP) continue;
        float n[3];
        glow__oct_decode(caches[k].normal_oct, n);
        const float *p = caches[k].position;
        float rgb[3];
        glow_shade_sh(o->cache_sh + (size_t)k * o->coeff_count, o->sh_bands_luma, o->sh_bands_chroma, n, 1.0f, rgb);
        if (p[1] > 0.5 * c) { /* the emitter's caches face down into empty space: they receive nothing */
            assert_true(n[1] < -0.99f);
            n_emitter_side++;
            for (int q = 0; q < 3; ++q) assert_true(fabsf(rgb[q]) < 1e-3f);
            continue;
        }
        assert_true(n[1] > 0.99f);
        assert_true(p[0] >= -1e-3f && p[0] <= 1.001f && p[2] >= -1e-3f && p[2] <= 1.001f);
        glow_shade_sh(o->cache_sh + (size_t)k * o->coeff_count, o->sh_bands_luma, o->sh_bands_chroma, up, 1.0f, rgb);
        /* white emitter, black surfaces: no chroma */
        assert_true(fabsf(rgb[0] - rgb[1]) < 1e-4f * (fabsf(rgb[1]) + 1e-3f));
        assert_true(fabsf(rgb[2] - rgb[1]) < 1e-4f * (fabsf(rgb[1]) + 1e-3f));
        double e_rt = M_PI * rgb[1];
        double e_ex = exact_irradiance(p[0], p[2], c);
        double eb[GLOW_MAX_SH_BANDS + 1];
        band_limited_irradiance(clamp_side(p[0]), clamp_side(p[2]), c, B, eb);
        const double e_ref = e_ex; /* the solver is held to the closed form (cone_fit.c) */
        /* the cache's own links, re-summed here in double: E = π Σ_j R_j Σ_{l<B} s_l k_l(x_j) (2l+1)/(4π)
         * P_l(d_j·n) (addition theorem; k_l the DESIGN §3 cone factor, checked by test_shading) */
        double e_links = 0.0;
        for (uint32_t j = 0; j < m->links_per_cache; ++j) {
            const glow_bake_link_block *b = lb + (size_t)k * m->link_blocks_per_cache + j / GLOW_LINK_BLOCK;
            const uint32_t lane = j % GLOW_LINK_BLOCK, node = glow_bake_link_node(b, lane);
            const double omc = glow__half_to_float(b->one_minus_cos[lane]);
            if (omc == 0.0 || emit_area[node] == 0.0) continue;
            uint32_t du, dv;
            float d[3];
            glow_bake_link_dir12(b, lane, &du, &dv);
            glow__oct_decode12(du, dv, d);
            const double R = RADIANCE * emit_area[node] / nodes[node].area, x = 1.0 - omc, t = d[1];
            double px[GLOW_MAX_SH_BANDS + 2] = {1.0, x}, pt[GLOW_MAX_SH_BANDS + 1] = {1.0, t};
            for (int l = 1; l <= B; ++l) px[l + 1] = ((2.0 * l + 1.0) * x * px[l] - l * px[l - 1]) / (l + 1.0);
            for (int l = 1; l + 1 < B; ++l) pt[l + 1] = ((2.0 * l + 1.0) * t * pt[l] - l * pt[l - 1]) / (l + 1.0);
            for (int l = 0; l < B; ++l) {
                double kl = l == 0 ? 2.0 * M_PI * omc : 2.0 * M_PI / (2.0 * l + 1.0) * (px[l - 1] - px[l + 1]);
                e_links += R * s_cos[l] * kl * (2.0 * l + 1.0) / 4.0 * pt[l];
            }
        }
        if (fabs(e_rt - e_links) > worst_links * e_links) worst_links = fabs(e_rt - e_links) / e_links;
        sum_rt += e_rt;
        sum_ex += e_ex;
        sum_eb += eb[B];
        n_all++;
        double rel = e_rt / e_ref - 1.0;
        sq += rel * rel;
        /* interior: at least one texel from every edge */
        if (p[0] > h && p[0] < SIDE - h && p[2] > h && p[2] < SIDE - h && fabs(e_rt / e_ref - 1.0) > worst)
            worst = fabs(e_rt / e_ref - 1.0);
        /* texel centre inside the square (a border texel's cache would sit on the edge) */
        if (p[0] > 1e-3f && p[0] < 0.999f && p[2] > 1e-3f && p[2] < 0.999f) {
            sum_rt_in += e_rt;
            sum_ex_in += e_ex;
            n_in++;
        }
        /* the caches within 0.1 m of the centre (~30): E is nearly flat there */
        double d2 = (p[0] - 0.5) * (p[0] - 0.5) + (p[2] - 0.5) * (p[2] - 0.5);
        if (d2 < 0.01) {
            centre_rt += e_rt;
            centre_ex += e_ex;
            centre_eb += eb[B];
            n_centre++;
        }
    }
    assert_true(n_all > 500);
    assert_true(n_in > 0.8 * n_all);
    assert_true(n_emitter_side > 500);
    assert_true(n_centre >= 16);
    free(emit_area);
    centre_rt /= n_centre;
    centre_ex /= n_centre;
    centre_eb /= n_centre;
    const double F = f_parallel_rects(SIDE / c, SIDE / c), e_mean_area = M_PI * RADIANCE * F;
    const double mean_rt = sum_rt / n_all, mean_ex = sum_ex / n_all, mean_eb = sum_eb / n_all;
    const double mean_rt_in = sum_rt_in / n_in, mean_ex_in = sum_ex_in / n_in;
    const double e_centre = exact_irradiance(0.5, 0.5, c);
    double eb_centre[GLOW_MAX_SH_BANDS + 1];
    band_limited_irradiance(0.5, 0.5, c, B, eb_centre);

    /* the centre through the public lightmap sampler, at the UV of the receiver's centre vertex */
    glow_bake_geometry g;
    assert_int_equal(glow_bake_get_geometry(f->bake, &g), GLOW_OK);
    double sampled_centre = -1.0;
    for (uint32_t t = 0; t < g.triangle_count && sampled_centre < 0.0; ++t) {
        const float *pos = (const float *)((const char *)g.positions + (size_t)t * g.stride);
        const uint16_t *uv = (const uint16_t *)((const char *)g.lightmap_uv + (size_t)t * g.stride);
        for (int q = 0; q < 3; ++q)
            if (fabsf(pos[3 * q] - 0.5f) < 1e-6f && fabsf(pos[3 * q + 1]) < 1e-6f && fabsf(pos[3 * q + 2] - 0.5f) < 1e-6f) {
                float coeffs[3 * GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS], rgb[3];
                assert_int_equal(glow_sample_lightmap(o, uv[2 * q] / 65535.0f, uv[2 * q + 1] / 65535.0f, coeffs), GLOW_OK);
                glow_shade_sh(coeffs, o->sh_bands_luma, o->sh_bands_chroma, up, 1.0f, rgb);
                sampled_centre = M_PI * rgb[1];
                break;
            }
    }
    assert_true(sampled_centre >= 0.0);

    print_message("c = %.1f m, %d luma bands, %u receiver caches (%u with the texel centre inside), texel %.4f m\n", c, B,
                  n_all, n_in, h);
    print_message("  solver vs its own links re-summed in double: worst %.2e relative\n", worst_links);
    print_message("  at the caches: solver mean %.5f; E_%d %.5f (solver %+.2f %%, rms %.2f %%); E_true %.5f (solver %+.2f %%, "
                  "truncation alone %+.2f %%); worst interior cache %.2f %% (vs %s)\n",
                  mean_rt, B, mean_eb, 100.0 * (mean_rt / mean_eb - 1.0), 100.0 * sqrt(sq / n_all), mean_ex,
                  100.0 * (mean_rt / mean_ex - 1.0), 100.0 * (mean_eb / mean_ex - 1.0), 100.0 * worst, vs_true ? "E_true" : "E_B");
    print_message("  area mean: interior caches %.5f (E_true there %.5f) vs pi L F_12 = %.5f: %+.2f %% (sampling alone %+.2f %%)\n",
                  mean_rt_in, mean_ex_in, e_mean_area, 100.0 * (mean_rt_in / e_mean_area - 1.0),
                  100.0 * (mean_ex_in / e_mean_area - 1.0));
    print_message("  centre: %u caches within 0.1 m %.5f vs E_%d %.5f (%+.2f %%), E_true %.5f (%+.2f %%); lightmap sample %.5f vs "
                  "E_%d %.5f (%+.2f %%), E_true %.5f (%+.2f %%)\n",
                  n_centre, centre_rt, B, centre_eb, 100.0 * (centre_rt / centre_eb - 1.0), centre_ex,
                  100.0 * (centre_rt / centre_ex - 1.0), sampled_centre, B, eb_centre[B],
                  100.0 * (sampled_centre / eb_centre[B] - 1.0), e_centre, 100.0 * (sampled_centre / e_centre - 1.0));

    /* the solver's arithmetic against its own links */
    assert_true(worst_links < tol_links);
    /* the solver against the closed form at every band count: the linker fits each lightmap link's
     * cone so that its B-band response at the cache normal is the exact cosine-weighted one
     * (cone_fit.c), so the truncation error E_B - E_true is not there at the normal */
    assert_true(fabs(mean_rt / mean_ex - 1.0) < tol_mean);
    assert_true(sqrt(sq / n_all) < tol_rms);
    assert_true(fabs(centre_rt / centre_ex - 1.0) < tol_centre);
    assert_true(fabs(sampled_centre / e_centre - 1.0) < tol_centre);
    assert_true(worst < tol_worst);
    /* and it is not the B-band answer where that one is off: 3 bands at c = 1 m overstate by 2.9 % */
    if (B == 3 && c > 0.75) assert_true(mean_rt / mean_eb - 1.0 < -0.015);
    /* the sampling bias of the interior set itself must be small, or the area check tests nothing */
    assert_true(fabs(mean_ex_in / e_mean_area - 1.0) < 0.01);
    /* and against the truth, where the band limit allows it */
    if (vs_true) {
        assert_true(fabs(mean_rt / mean_ex - 1.0) < tol_mean);
        assert_true(fabs(mean_rt_in / e_mean_area - 1.0) < tol_mean);
        assert_true(fabs(centre_rt / centre_ex - 1.0) < tol_centre);
        assert_true(fabs(sampled_centre / e_centre - 1.0) < tol_centre);
    }
    glow_system_destroy(sys);
}

static void test_receiver_irradiance(void **state) { check_receiver(*state, 0, true); }

/* An 8-band system on the 3-band bake (c = 0.5 m; at 1 m see main): near the closed form too. */
static void test_receiver_irradiance_8_bands(void **state) { check_receiver(*state, 8, true); }

/* Linear in L and in the emission controls: emission_scale 2.5 and a material scale of 0.4 give
 * the same field; a black emitter gives nothing. */
static void test_emission_controls(void **state) {
    fixture *f = *state;
    glow_system *a, *b;
    glow_system_desc sd = {.bake = f->bake};
    assert_int_equal(glow_system_create(f->ctx, &sd, &a), GLOW_OK);
    assert_int_equal(glow_system_create(f->ctx, &sd, &b), GLOW_OK);
    assert_int_equal(glow_system_update(a, NULL), GLOW_OK);
    glow_system_params p = {.bounce_intensity = 1.0f, .emission_scale = 2.5f, .bounce_iterations = 1};
    assert_int_equal(glow_system_set_params(b, &p), GLOW_OK);
    uint32_t emitter = UINT32_MAX;
    for (uint32_t i = 0; i < glow__bake_meta(f->bake)->material_count; ++i) {
        glow_material_info mi;
        assert_int_equal(glow_bake_get_material(f->bake, i, &mi), GLOW_OK);
        if (strcmp(mi.name, "emitter") == 0) {
            emitter = i;
            assert_true(fabsf(mi.emission[0] - (float)RADIANCE) < 1e-6f);
            assert_true(mi.albedo[0] == 0.0f && mi.albedo[1] == 0.0f && mi.albedo[2] == 0.0f);
        }
    }
    assert_true(emitter != UINT32_MAX);
    const float es[3] = {0.4f, 0.4f, 0.4f};
    assert_int_equal(glow_system_set_material(b, emitter, es, NULL), GLOW_OK);
    assert_int_equal(glow_system_update(b, NULL), GLOW_OK);
    const glow_cache_outputs *oa = glow_system_outputs(a), *ob = glow_system_outputs(b);
    double maxa = 0.0, maxdiff = 0.0;
    for (size_t i = 0; i < (size_t)oa->cache_count * oa->coeff_count; ++i) {
        maxa = fmax(maxa, fabs(oa->cache_sh[i]));
        maxdiff = fmax(maxdiff, fabs(oa->cache_sh[i] - ob->cache_sh[i]));
    }
    assert_true(maxa > 0.1);
    assert_true(maxdiff < 1e-5 * maxa);
    const float off[3] = {0.0f, 0.0f, 0.0f};
    assert_int_equal(glow_system_set_material(b, emitter, off, NULL), GLOW_OK);
    assert_int_equal(glow_system_update(b, NULL), GLOW_OK);
    for (size_t i = 0; i < (size_t)ob->cache_count * ob->coeff_count; ++i) assert_true(ob->cache_sh[i] == 0.0f);
    glow_system_destroy(a);
    glow_system_destroy(b);
}

int main(void) {
    init_quadrature();
    const struct CMUnitTest analytic[] = {cmocka_unit_test(test_analytic_forms)};
    const struct CMUnitTest near[] = {
        cmocka_unit_test(test_receiver_irradiance),
        cmocka_unit_test(test_receiver_irradiance_8_bands),
        cmocka_unit_test(test_emission_controls),
    };
    /* at 1 m an 8-band system on the 3-band bake reads 2.6 % low (its cones carry the 3-band fit),
     * so the 8-band case there is an 8-band bake */
    const struct CMUnitTest far[] = {cmocka_unit_test(test_receiver_irradiance)};
    const struct CMUnitTest far8[] = {cmocka_unit_test(test_receiver_irradiance)};
    int failed = cmocka_run_group_tests_name("analytic", analytic, NULL, NULL);
    failed += cmocka_run_group_tests_name("c = 0.5 m", near, setup_near, teardown);
    failed += cmocka_run_group_tests_name("c = 1 m", far, setup_far, teardown);
    failed += cmocka_run_group_tests_name("c = 1 m, an 8-band bake", far8, setup_far8, teardown);
    return failed;
}
