/* test_stability_convergence.c — bounce convergence (issue 4, stability suite): the white furnace
 * (builtin:furnace, a closed cube whose walls all emit L_e = 1 with uniform albedo ρ) at ρ = 0.5, 0.9
 * and 0.99 (albedo scale ρ / the material's 0.5), bounce_intensity 1.
 *
 * Index convention (checked by test_first_update_is_emission): the caches start at zero, and each
 * feedback iteration lights the surfels with the previous iteration's caches, so update n (one
 * iteration each, n = 1, 2, ...) holds the emission and n - 1 bounces:
 *     L_n = L_e Σ_{i=0}^{n-1} ρ^i = L_e (1 - ρ^n) / (1 - ρ),          L_∞ = L_e / (1 - ρ).
 * Measured: m_n, the mean over the lightmap caches of the diffuse shading along the normal (E/π),
 * and over the grid caches of the mean radiance over the sphere (c00 y00); both are L_n exactly.
 *
 * Tolerance. The links carry a per-bounce transport error δ (the mean response of a cache to uniform
 * radiance, minus 1). Bounce i then arrives with ρ^i (1 + δ)^(i+1), so the partial sum's relative
 * error is about δ (1 + Σ i ρ^i / Σ ρ^i), which grows to δ / (1 - ρ). test_furnace.c sees the
 * converged means at ρ = 0.9 within 0.00 % (so δ < 5e-6) and every single cache within 0.05 %; the
 * tolerance here takes δ_tol = 5e-5 (a single cache's worst error at ρ = 0.9, divided by 9, i.e. ten
 * times the mean's bound) plus 1e-5 of float round-off: 0.011 % at ρ = 0.5, 0.05 % at ρ = 0.9,
 * 0.5 % at ρ = 0.99. δ is also measured directly (update 1 against L_e) and printed.
 * Checks, per ρ:
 *   - every update n <= N_CHECK follows L_n within the tolerance (lightmap and grid means);
 *   - monotone: m_{n+1} >= m_n (each bounce adds light), and no overshoot: m_n <= L_∞ (1 + tol);
 *   - the number of updates until m_n is within 1 % of L_∞ is the analytic
 *     n_1% = ceil(ln 0.01 / ln ρ) (7, 44, 459; in bounces, n_1% - 1), give or take one update
 *     (the transport error moves the crossing when ρ^n lands near 0.01: 0.9^44 = 0.0097);
 *   - converged (ρ^n < 1e-9) within the tolerance of L_∞, and at ρ = 0.99 no divergence over 2000
 *     bounces: finite, ≤ L_∞ (1 + tol), and the last 64 bounces change nothing beyond round-off.
 * Long runs use bounce_iterations 64 per update (one update = 64 bounces) once the per-update
 * partial sums are checked.
 *
 * The non-divergence cap (runtime: the albedo applied to indirect light is at most 0.999 π / G_s,
 * G_s = Σ_links |w_j(n_s)| of the surfel's feedback cache, docs/runtime.md): G_s is recomputed here
 * from the bake's links the same way and the surfels where the cap is below ρ are counted and
 * printed; where it bites the furnace converges below L_∞, which the tolerance would catch. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "stability_common.h"

#define N_CHECK 64u      /* updates checked one by one */
#define DELTA_TOL 5e-5   /* per-bounce transport error allowed (see the top) */

static stab_bake g_b;

static int setup(void **state) {
    /* test_furnace.c's bake (its accuracy is the tolerance's premise), with a coarser grid (0.4 m: 125
     * grid caches instead of 512) so that the ~2400 bounces stay cheap under ASan */
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 96, .bands = 3, .grid_spacing = 0.4f,
                          .threads = 2, .seed = 1};
    if (stab_bake_load("builtin:furnace", "convergence", &s, &g_b) != 0) return -1;
    *state = &g_b;
    return 0;
}

static int teardown(void **state) {
    stab_bake_free(*state);
    return 0;
}

typedef struct furnace_sys {
    glow_system *sys;
    double le;
} furnace_sys;

/* the system of the running test, destroyed by teardown_system also when an assertion jumped out */
static glow_system *g_live;

static int teardown_system(void **state) {
    (void)state;
    glow_system_destroy(g_live);
    g_live = NULL;
    return 0;
}

static void furnace_open(const stab_bake *b, double rho, furnace_sys *f) {
    assert_int_equal(glow_system_create(b->ctx, &(glow_system_desc){.bake = b->bake}, &f->sys), GLOW_OK);
    g_live = f->sys;
    glow_material_info mi;
    assert_int_equal(glow_bake_get_material(b->bake, 0, &mi), GLOW_OK);
    assert_true(mi.emission[0] > 0.0f && mi.albedo[0] > 0.0f);
    f->le = mi.emission[0];
    const float scale = (float)(rho / mi.albedo[0]);
    assert_int_equal(glow_system_set_material(f->sys, 0, NULL, (const float[3]){scale, scale, scale}), GLOW_OK);
}

static void set_iterations(furnace_sys *f, uint32_t iterations) {
    assert_int_equal(glow_system_set_params(f->sys, &(glow_system_params){.bounce_intensity = 1.0f, .emission_scale = 1.0f,
                                                                           .bounce_iterations = iterations}),
                     GLOW_OK);
}

/* Means over the lightmap caches and over the grid caches; every cache must be finite. */
static void means(const stab_bake *b, const furnace_sys *f, double *lm, double *grid) {
    const glow_cache_outputs *o = glow_system_outputs(f->sys);
    const glow_bake_cache *caches = glow__bake_caches(b->bake);
    double s[2] = {0.0, 0.0};
    for (uint32_t c = 0; c < o->cache_count; ++c) {
        const double v = stab_cache_luma(o, caches, c);
        assert_true(isfinite(v));
        s[c < o->grid_cache_count] += v;
    }
    *lm = s[0] / o->lightmap_cache_count;
    *grid = s[1] / o->grid_cache_count;
}

/* Relative tolerance of L_n (n updates) for a per-bounce error DELTA_TOL, see the top. */
static double tolerance(double rho, uint32_t n) {
    double s0 = 0.0, s1 = 0.0, p = 1.0;
    for (uint32_t i = 0; i < n; ++i, p *= rho) {
        s0 += p;
        s1 += i * p;
    }
    return 1e-5 + DELTA_TOL * (1.0 + s1 / s0);
}

static double partial_sum(double le, double rho, uint32_t n) { return le * (1.0 - pow(rho, n)) / (1.0 - rho); }

/* The cap of the albedo applied to indirect light, 0.999 π / G_s, recomputed per surfel from the
 * bake's links (docs/runtime.md); returns how many surfels it holds below rho, and the lowest cap. */
static uint32_t cap_bites(const stab_bake *b, double rho, double *out_min_cap) {
    const glow_bake_meta *m = glow__bake_meta(b->bake);
    const glow_bake_surfel *sf = glow__bake_surfels(b->bake);
    const glow_bake_link_block *blocks = glow__bake_link_blocks(b->bake);
    const uint32_t L = m->sh_bands;
    double sl[GLOW_MAX_SH_BANDS];
    for (uint32_t l = 0; l < L; ++l) sl[l] = glow_sh_lobe_factor(l, 1.0f);
    uint32_t bites = 0;
    *out_min_cap = INFINITY;
    for (uint32_t i = 0; i < m->surfel_count; ++i) {
        const float *n = sf[i].normal;
        double G = 0.0;
        for (uint32_t j = 0; j < m->links_per_cache; ++j) {
            const glow_bake_link_block *bb = blocks + (size_t)sf[i].feedback * m->link_blocks_per_cache + j / GLOW_LINK_BLOCK;
            const uint32_t lane = j % GLOW_LINK_BLOCK;
            const float omc = glow__half_to_float(bb->one_minus_cos[lane]);
            if (!(omc > 0.0f)) continue;
            uint32_t du, dv;
            glow_bake_link_dir12(bb, lane, &du, &dv);
            float d[3];
            glow__oct_decode12(du, dv, d);
            double Pt[GLOW_MAX_SH_BANDS + 2];
            glow__legendre_all(L, d[0] * n[0] + d[1] * n[1] + d[2] * n[2], Pt);
            double w = 0.0;
            for (uint32_t l = 0; l < L; ++l)
                w += sl[l] * glow__cone_factor_omc(l, omc) * (2.0 * l + 1.0) / (4.0 * M_PI) * Pt[l];
            G += fabs(w) * M_PI;
        }
        const double cap = G > 0.0 ? 0.999 * M_PI / G : 0.999;
        *out_min_cap = fmin(*out_min_cap, cap);
        bites += cap < rho;
    }
    return bites;
}

/* Update 1 gathers the emission alone: L_1 = L_e (the convention above; it also measures δ). */
static void test_first_update_is_emission(void **state) {
    const stab_bake *b = *state;
    furnace_sys f;
    furnace_open(b, 0.9, &f);
    set_iterations(&f, 1);
    assert_int_equal(glow_system_update(f.sys, NULL), GLOW_OK);
    double lm, grid;
    means(b, &f, &lm, &grid);
    printf("update 1 (emission only): lightmap mean %.6f, grid mean %.6f (L_e = %.1f): transport error delta %+.2e / %+.2e\n",
           lm, grid, f.le, lm / f.le - 1.0, grid / f.le - 1.0);
    assert_true(fabs(lm / f.le - 1.0) < DELTA_TOL);
    assert_true(fabs(grid / f.le - 1.0) < DELTA_TOL);
    /* update 2 = one bounce more: L_e (1 + ρ), not L_e (1 + ρ + ρ²) */
    assert_int_equal(glow_system_update(f.sys, NULL), GLOW_OK);
    means(b, &f, &lm, &grid);
    assert_true(fabs(lm / (f.le * 1.9) - 1.0) < tolerance(0.9, 2));
    teardown_system(NULL);
}

static void convergence(const stab_bake *b, double rho) {
    furnace_sys f;
    furnace_open(b, rho, &f);
    const double linf = f.le / (1.0 - rho);
    const double tol_inf = tolerance(rho, 100000);
    /* n_1%: the first n with ρ^n <= 0.01 */
    const uint32_t n_analytic = (uint32_t)ceil(log(0.01) / log(rho));
    uint32_t n_measured = 0, n = 0;
    double worst_lm = 0.0, worst_grid = 0.0, prev = 0.0;
    set_iterations(&f, 1);
    /* one iteration per update: the first N_CHECK partial sums, and up to the 1 % crossing */
    while (n < N_CHECK || (n_measured == 0 && n + 64 < n_analytic - 2)) {
        if (n >= N_CHECK) { /* far from the crossing: 64 bounces at a time */
            set_iterations(&f, 64);
            assert_int_equal(glow_system_update(f.sys, NULL), GLOW_OK);
            n += 64;
            set_iterations(&f, 1);
        } else {
            assert_int_equal(glow_system_update(f.sys, NULL), GLOW_OK);
            n++;
        }
        double lm, grid;
        means(b, &f, &lm, &grid);
        const double ln = partial_sum(f.le, rho, n), tol = tolerance(rho, n);
        if (n <= N_CHECK) {
            worst_lm = fmax(worst_lm, fabs(lm / ln - 1.0) / tol);
            worst_grid = fmax(worst_grid, fabs(grid / ln - 1.0) / tol);
            if (fabs(lm / ln - 1.0) > tol || fabs(grid / ln - 1.0) > tol)
                fail_msg("rho %.2f, update %u: lightmap mean %.6f, grid mean %.6f, analytic %.6f (tolerance %.3g %%)", rho, n,
                         lm, grid, ln, 100.0 * tol);
        }
        assert_true(lm >= prev * (1.0 - 1e-6)); /* monotone */
        assert_true(lm <= linf * (1.0 + tol_inf));  /* no overshoot */
        prev = lm;
        if (n_measured == 0 && fabs(lm / linf - 1.0) <= 0.01) n_measured = n;
    }
    /* single updates through the crossing */
    while (n_measured == 0) {
        assert_int_equal(glow_system_update(f.sys, NULL), GLOW_OK);
        n++;
        double lm, grid;
        means(b, &f, &lm, &grid);
        assert_true(lm >= prev * (1.0 - 1e-6));
        assert_true(lm <= linf * (1.0 + tol_inf));
        assert_true(fabs(lm / partial_sum(f.le, rho, n) - 1.0) <= tolerance(rho, n));
        prev = lm;
        if (fabs(lm / linf - 1.0) <= 0.01) n_measured = n;
        assert_true(n < 2 * n_analytic + 8);
    }
    /* on to convergence (ρ^n < 1e-9; 2000 bounces at ρ = 0.99: non-divergence) */
    const uint32_t n_conv = rho > 0.98 ? 2000u : (uint32_t)ceil(log(1e-9) / log(rho));
    set_iterations(&f, 64);
    double before_last = prev, lm = prev, grid = 0.0;
    while (n < n_conv) {
        before_last = lm;
        assert_int_equal(glow_system_update(f.sys, NULL), GLOW_OK);
        n += 64;
        means(b, &f, &lm, &grid);
        assert_true(lm <= linf * (1.0 + tol_inf) && grid <= linf * (1.0 + tol_inf));
    }
    means(b, &f, &lm, &grid);
    double min_cap;
    const uint32_t bites = cap_bites(b, rho, &min_cap);
    printf("rho %.2f: partial sums of %u updates within %.2f of the tolerance (lightmap) / %.2f (grid); 1 %% reached after "
           "%u updates (analytic %u); after %u bounces lightmap %.5f, grid %.5f, L_inf %.5f (%+.3f %% / %+.3f %%, "
           "tolerance %.3f %%); last 64 bounces changed it by %.2e; the non-divergence cap is below rho at %u surfels "
           "(lowest cap %.4f)\n",
           rho, N_CHECK, worst_lm, worst_grid, n_measured, n_analytic, n, lm, grid, linf, 100.0 * (lm / linf - 1.0),
           100.0 * (grid / linf - 1.0), 100.0 * tol_inf, fabs(lm - before_last) / linf, bites, min_cap);
    assert_true(n_measured + 1 >= n_analytic && n_measured <= n_analytic + 1);
    assert_true(fabs(lm / linf - 1.0) <= tol_inf);
    assert_true(fabs(grid / linf - 1.0) <= tol_inf);
    assert_true(fabs(lm - before_last) <= 1e-5 * linf + 2.0 * pow(rho, n - 64) * linf);
    teardown_system(NULL);
}

static void test_convergence_050(void **state) { convergence(*state, 0.5); }
static void test_convergence_090(void **state) { convergence(*state, 0.9); }
static void test_convergence_099(void **state) { convergence(*state, 0.99); }

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test_teardown(test_first_update_is_emission, teardown_system),
                                       cmocka_unit_test_teardown(test_convergence_050, teardown_system),
                                       cmocka_unit_test_teardown(test_convergence_090, teardown_system),
                                       cmocka_unit_test_teardown(test_convergence_099, teardown_system)};
    return cmocka_run_group_tests(tests, setup, teardown);
}
