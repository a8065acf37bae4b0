/* test_gl_agreement.c — the CPU solver (glow_system_update) and the GL backend (glow_gl_system_update)
 * give the same cache SH (issue 5, "CPU and GPU agree"): built-in Cornell box and two-rooms, after 1
 * and after 20 bounce updates, every coefficient of every cache.
 *
 * Tolerance: |gpu - cpu| <= 1e-3 · scale + 1e-6 · global, scale = the largest |coefficient| of that
 * cache's channel block (Y, Co or Cg) on the CPU, global = the largest over all caches. Per-coefficient
 * relative error is meaningless near 0 (coefficients cross zero), the block scale is what a shaded
 * pixel's error is relative to, and the global floor admits float noise in caches that see (almost)
 * nothing (two-rooms' closed room: |c| ~ 1e-8 of the lit room's). The
 * two sum the same float terms in a different order (8-lane SIMD vs a 64-invocation reduction) and the
 * GPU normalises link directions with its own sqrt, so they are not bit-identical.
 *
 * Also: the GLSL hook path (an analytic point light written once in C and once in GLSL), lights that
 * change between updates (emission override, material scales), a hook that does not compile
 * (GLOW_ERROR_HOST_CALLBACK with the GL log), a hook that returns NaN (counted, stored as 0: the
 * caches stay finite; with GLOW_GL_FLAG_CHECK_HOOK the update fails and keeps the previous outputs),
 * the GLSL SH constants against the runtime's, and light across systems (a world's GL systems attached to
 * each other, against the CPU solvers attached the same way), and the visible sky of the grid caches
 * (glow_gl_system_set_sky against glow_system_set_sky, test_sky). Exits 77 (skipped) without a GL 4.5
 * context. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "glow/glow.h"
#include "glow/glow_backend.h"
#include "glow/glow_gl.h"
#include "glow/glow_glctx.h"
#include "glow/glow_glfns.h"
#include "glow/glow_precompute.h"

static glow_glctx *g_gl;

/* A loader that hides one entry point, and one whose context claims GL 4.3: missing GL features. */
static const char *g_hidden;
static glow_gl_proc hiding_loader(const char *name) {
    if (g_hidden && !strcmp(name, g_hidden)) return NULL;
    return glow_glctx_get_proc_address(g_gl)(name);
}
static PFNGLGETINTEGERVPROC g_real_getintegerv;
static void APIENTRY old_getintegerv(GLenum pname, GLint *v) {
    g_real_getintegerv(pname, v);
    if (pname == GL_MINOR_VERSION) *v = 3;
}
static glow_gl_proc old_loader(const char *name) {
    if (!strcmp(name, "glGetIntegerv")) {
        glow_gl_proc p = glow_glctx_get_proc_address(g_gl)(name);
        memcpy(&g_real_getintegerv, &p, sizeof p);
        return (glow_gl_proc)old_getintegerv;
    }
    return glow_glctx_get_proc_address(g_gl)(name);
}

typedef struct fixture {
    glow_context *ctx;
    glow_bake *bake;
    glow_system *cpu;
    glow_gl_system *gpu;
    char path[256];
} fixture;

static int g_log_errors;
/* make_fixture bakes with link gradients (glow_pc_settings.link_gradients) instead of link subsets */
static bool g_gradient;
static char g_last_log[4096];
static void logger(void *user, glow_log_level level, glow_result code, const char *msg, const char *file, int line) {
    (void)user, (void)code, (void)file, (void)line;
    if (level == GLOW_LOG_ERROR) g_log_errors++;
    snprintf(g_last_log, sizeof g_last_log, "%s", msg);
}

/* the analytic light, C and GLSL: an unshadowed point light (W/sr) at P */
static const float LP[3] = {0.1f, 0.7f, 0.2f}, LI[3] = {2.0f, 1.6f, 1.2f};
static const char *HOOK_POINT =
    "#define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED\n"
    "uniform vec3 u_light_pos = vec3(0.1, 0.7, 0.2);\n"
    "vec3 glow_host_surfel_irradiance(vec3 p, vec3 n, uint material) {\n"
    "    vec3 d = u_light_pos - p; float r2 = dot(d, d);\n"
    "    return vec3(2.0, 1.6, 1.2) * max(dot(n, d * inversesqrt(r2)), 0.0) / r2;\n"
    "}\n";
static glow_result cpu_point(void *user, const glow_surfel_batch *b, float *out, uint32_t worker) {
    (void)user, (void)worker;
    for (uint32_t i = 0; i < b->count; ++i) {
        const float *p = b->positions + 4 * (size_t)i, *n = b->normals + 4 * (size_t)i;
        float d[3] = {LP[0] - p[0], LP[1] - p[1], LP[2] - p[2]};
        float r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], inv = 1.0f / sqrtf(r2);
        float c = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) * inv;
        c = c > 0.0f ? c : 0.0f;
        for (int k = 0; k < 3; ++k) out[3 * (size_t)i + k] = LI[k] * c / r2;
    }
    return GLOW_OK;
}

static int make_fixture(fixture *f, const char *scene, const char *hook, uint32_t luma, uint32_t chroma, uint32_t flags) {
    memset(f, 0, sizeof *f);
    snprintf(f->path, sizeof f->path, "/tmp/glow_gpu_agree_%d_%s%s.glow", (int)getpid(), scene + 8,
             g_gradient ? "-grad" : "");
    if (access(f->path, R_OK) != 0) {
        glow_pc_settings st = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 96, .bands = 3, .threads = 2, .seed = 1,
                               .link_gradients = g_gradient};
        glow_pc_stats stats;
        if (glow_pc_bake(scene, f->path, &st, &stats) != GLOW_OK) {
            fprintf(stderr, "bake %s: %s\n", scene, stats.error);
            return -1;
        }
    }
    glow_context_desc cd = {.api_version = GLOW_VERSION, .tasks = {.worker_count = 2}, .logger = {logger, NULL}};
    if (glow_context_create(&cd, &f->ctx) != GLOW_OK || glow_bake_load_file(f->ctx, f->path, &f->bake) != GLOW_OK) return -1;
    glow_system_desc sd = {.bake = f->bake, .sh_bands_luma = luma, .sh_bands_chroma = chroma,
                           .lighting = {hook ? cpu_point : NULL, NULL}};
    if (glow_system_create(f->ctx, &sd, &f->cpu) != GLOW_OK) return -1;
    glow_solver_tables tables;
    if (glow_system_get_solver_tables(f->cpu, &tables) != GLOW_OK || (g_gradient ? !tables.link_gradients : !tables.link_subsets)) {
        fprintf(stderr, "%s: the bake has no link %s (LSUB): the GPU's %s path would go untested\n", scene,
                g_gradient ? "gradients" : "subsets", g_gradient ? "gradient" : "subset");
        return -1;
    }
    if (g_gradient && (!(tables.link_kind & GLOW_LINK_KIND_GRADIENT) || !tables.gradient_node_count)) {
        fprintf(stderr, "%s: no link reads a gradient: the GPU's gradient path would go untested\n", scene);
        return -1;
    }
    if (!tables.detail_texels || !tables.detail_links) {
        fprintf(stderr, "%s: the bake has no lightmap detail (LDET): the GPU's detail kernel would go untested\n", scene);
        return -1;
    }
    glow_gl_desc gd = {.system = f->cpu, .get_proc_address = glow_glctx_get_proc_address(g_gl), .hook_glsl = hook,
                       .flags = flags, .label = scene, .logger = {logger, NULL}};
    glow_result r = glow_gl_system_create(&gd, &f->gpu);
    if (r != GLOW_OK) {
        fprintf(stderr, "glow_gl_system_create: %s\n%s\n", glow_result_string(r), g_last_log);
        return -1;
    }
    return 0;
}

static void free_fixture(fixture *f) {
    glow_gl_system_destroy(f->gpu);
    glow_system_destroy(f->cpu);
    glow_bake_destroy(f->bake);
    glow_context_destroy(f->ctx);
}

/* Compares every coefficient; returns the worst error in units of the tolerance (<= 1 passes). */
static double compare(fixture *f, const char *what) {
    const glow_cache_outputs *o = glow_system_outputs(f->cpu);
    const size_t n = (size_t)o->cache_count * o->coeff_count;
    float *g = malloc(n * sizeof *g);
    assert_non_null(g);
    assert_int_equal(glow_gl_system_read_cache_sh(f->gpu, g, n), GLOW_OK);
    const uint32_t L2 = o->sh_bands_luma * o->sh_bands_luma, C2 = o->sh_bands_chroma * o->sh_bands_chroma;
    double worst = 0.0, max_abs = 0.0, sum_rel = 0.0, global = 0.0;
    for (size_t i = 0; i < n; ++i) global = fmax(global, fabs(o->cache_sh[i]));
    size_t nonfinite = 0, wc = 0, wk = 0;
    for (uint32_t c = 0; c < o->cache_count; ++c) {
        const float *a = o->cache_sh + (size_t)c * o->coeff_count, *b = g + (size_t)c * o->coeff_count;
        const uint32_t starts[4] = {0, L2, L2 + C2, L2 + 2 * C2};
        for (int blk = 0; blk < 3; ++blk) {
            double scale = 0.0;
            for (uint32_t k = starts[blk]; k < starts[blk + 1]; ++k) scale = fmax(scale, fabs(a[k]));
            for (uint32_t k = starts[blk]; k < starts[blk + 1]; ++k) {
                if (!isfinite(b[k])) nonfinite++;
                double e = fabs((double)b[k] - a[k]) / (1e-3 * scale + 1e-6 * global);
                sum_rel += scale > 0 ? fabs((double)b[k] - a[k]) / scale : 0.0;
                if (e > worst) worst = e, wc = c, wk = k;
                max_abs = fmax(max_abs, fabs(a[k]));
            }
        }
    }
    printf("  %-34s %u caches x %u coeffs: worst %.3f of tolerance (cache %zu coeff %zu: cpu %.6g gpu %.6g), "
           "mean rel %.2e, max |c| %.4g\n",
           what, o->cache_count, o->coeff_count, worst, wc, wk, o->cache_sh[wc * o->coeff_count + wk],
           g[wc * o->coeff_count + wk], sum_rel / (double)n, max_abs);
    free(g);
    assert_int_equal(nonfinite, 0);
    assert_true(max_abs > 0.0); /* something was lit: a comparison of zeros proves nothing */
    return worst;
}

/* The lightmap detail texture against the CPU's detail plane (RGB and coverage), in units of the
 * tolerance: 1e-3 of the largest |value| of the plane plus 1e-6 absolute. */
static double compare_detail(fixture *f, const char *what) {
    const glow_cache_outputs *o = glow_system_outputs(f->cpu);
    const glow_gl_outputs *go = glow_gl_system_outputs(f->gpu);
    assert_non_null(o->lightmap_detail);
    assert_int_not_equal(go->lightmap_detail_texture, 0);
    assert_int_equal(go->detail_width, o->detail_width);
    assert_int_equal(go->detail_height, o->detail_height);
    const size_t n = (size_t)o->detail_width * o->detail_height * 4u;
    float *g = malloc(n * sizeof *g);
    assert_non_null(g);
    glow_glfns fns;
    assert_true(glow_glfns_load(&fns, glow_glctx_get_proc_address(g_gl), NULL, 0));
    fns.MemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    fns.GetTextureImage(go->lightmap_detail_texture, 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof *g), g);
    double scale = 0.0, worst = 0.0;
    size_t covered = 0, wi = 0, nonzero = 0;
    for (size_t i = 0; i < n; ++i) scale = fmax(scale, fabs(o->lightmap_detail[i]));
    for (size_t i = 0; i < n; ++i) {
        assert_true(isfinite(g[i]));
        const double e = fabs((double)g[i] - o->lightmap_detail[i]) / (1e-3 * scale + 1e-6);
        if (e > worst) worst = e, wi = i;
        if (i % 4 == 3) covered += o->lightmap_detail[i] == 1.0f;
        else nonzero += o->lightmap_detail[i] != 0.0f;
    }
    printf("  %-34s detail %ux%u, %zu texels cover a surface, %zu non-zero values: worst %.3f of tolerance "
           "(value %zu: cpu %.6g gpu %.6g)\n",
           what, o->detail_width, o->detail_height, covered, nonzero, worst, wi, o->lightmap_detail[wi], g[wi]);
    free(g);
    assert_true(covered > 0 && nonzero > 0); /* a comparison of zeros proves nothing */
    return worst;
}

/* both solvers, `updates` updates with the same inputs */
static void run_both(fixture *f, uint32_t updates, uint32_t flags) {
    for (uint32_t u = 0; u < updates; ++u) {
        uint32_t fl = u == 0 ? flags : (flags & ~GLOW_UPDATE_FLAG_RESET_BOUNCE);
        assert_int_equal(glow_system_update(f->cpu, &(glow_update_desc){.flags = fl}), GLOW_OK);
        assert_int_equal(glow_gl_system_update(f->gpu, &(glow_update_desc){.flags = fl}), GLOW_OK);
    }
}

/* pushed irradiance (no hook): the same direct light in both */
static void push_light(fixture *f, float scale) {
    glow_surfel_view v;
    glow_system_get_surfels(f->cpu, &v);
    float *e = malloc((size_t)v.count * 3 * sizeof *e);
    glow_surfel_batch b = {.first = 0, .count = v.count, .positions = v.positions, .normals = v.normals, .materials = v.materials};
    cpu_point(NULL, &b, e, 0);
    for (size_t i = 0; i < (size_t)v.count * 3; ++i) e[i] *= scale;
    assert_int_equal(glow_system_set_surfel_irradiance(f->cpu, 0, v.count, e), GLOW_OK);
    free(e);
}

static void agree_scene(const char *scene, uint32_t luma, uint32_t chroma) {
    fixture f;
    if (make_fixture(&f, scene, NULL, luma, chroma, 0) != 0) fail_msg("fixture %s", scene);
    printf("%s, l = %u/%u, pushed irradiance:\n", scene, luma, chroma);
    push_light(&f, 1.0f);
    run_both(&f, 1, 0);
    assert_true(compare(&f, "after 1 bounce update") <= 1.0);
    run_both(&f, 19, 0);
    assert_true(compare(&f, "after 20 bounce updates") <= 1.0);
    assert_true(compare_detail(&f, "lightmap detail, 20 updates") <= 1.0);
    /* artist controls through the CPU system reach the GPU at the next update */
    glow_system_params p = {.bounce_intensity = 0.6f, .emission_scale = 3.0f, .bounce_iterations = 3};
    assert_int_equal(glow_system_set_params(f.cpu, &p), GLOW_OK);
    assert_int_equal(glow_system_set_material(f.cpu, 0, (float[3]){2, 2, 2}, (float[3]){0.5f, 0.8f, 1.0f}), GLOW_OK);
    push_light(&f, 0.5f);
    run_both(&f, 2, 0);
    assert_true(compare(&f, "params, material, new light") <= 1.0);
    assert_true(compare_detail(&f, "lightmap detail, new light") <= 1.0);
    run_both(&f, 1, GLOW_UPDATE_FLAG_RESET_BOUNCE);
    assert_true(compare(&f, "after a bounce reset") <= 1.0);
    /* a material change alone: the GL side notices it by the tables' material_revision */
    assert_int_equal(glow_system_set_material(f.cpu, 0, NULL, (float[3]){0.1f, 0.2f, 0.9f}), GLOW_OK);
    run_both(&f, 2, 0);
    assert_true(compare(&f, "a material change alone") <= 1.0);
    free_fixture(&f);
}

/* A budget on the GPU (max_caches, focus): the GL backend chooses the same cache groups as the CPU
 * solver (glow_budget_choose) and gathers only those, so budgeted updates agree as unbudgeted ones do;
 * the first one from zero lights only the chosen groups (at most max_caches rounded up to groups). */
static void test_budget(void **state) {
    (void)state;
    fixture f;
    if (make_fixture(&f, "builtin:cornell", NULL, 3, 3, 0) != 0) fail_msg("fixture");
    const glow_cache_outputs *o = glow_system_outputs(f.cpu);
    const uint32_t C = o->cache_count, budget = C / 4;
    const float focus[3] = {-0.5f, 0.2f, 0.3f};
    const glow_update_desc d = {.max_caches = budget, .focus = focus, .focus_count = 1};
    printf("builtin:cornell, max_caches %u of %u, a focus point:\n", budget, C);
    push_light(&f, 1.0f);
    assert_int_equal(glow_system_update(f.cpu, &d), GLOW_OK);
    assert_int_equal(glow_gl_system_update(f.gpu, &d), GLOW_OK);
    const size_t n = (size_t)C * o->coeff_count;
    float *g = malloc(n * sizeof *g);
    assert_int_equal(glow_gl_system_read_cache_sh(f.gpu, g, n), GLOW_OK);
    uint32_t lit = 0;
    for (uint32_t c = 0; c < C; ++c) {
        int any = 0;
        for (uint32_t k = 0; k < o->coeff_count; ++k) any |= g[(size_t)c * o->coeff_count + k] != 0.0f;
        lit += any;
    }
    free(g);
    glow_gl_stats gs;
    assert_int_equal(glow_gl_system_get_stats(f.gpu, &gs), GLOW_OK);
    assert_int_equal(gs.caches_gathered, lit);
    printf("  first budgeted update: %u caches lit on the GPU (budget %u)\n", lit, budget);
    assert_true(lit > 0 && lit <= (budget + GLOW_BUDGET_GROUP - 1u) / GLOW_BUDGET_GROUP * GLOW_BUDGET_GROUP);
    assert_true(compare(&f, "after 1 budgeted update") <= 1.0);
    for (int u = 0; u < 7; ++u) {
        assert_int_equal(glow_system_update(f.cpu, &d), GLOW_OK);
        assert_int_equal(glow_gl_system_update(f.gpu, &d), GLOW_OK);
    }
    assert_true(compare(&f, "after 8 budgeted updates") <= 1.0);
    free_fixture(&f);
    /* budget_ms: GPU times (here with GLOW_GL_FLAG_FINISH_TIMERS, so that every update's are there at
     * the next): nothing learned yet, the first update gathers every cache; then a budget far below one
     * group's time gathers one group (always some progress), a budget far above it every cache */
    if (make_fixture(&f, "builtin:cornell", NULL, 3, 3, GLOW_GL_FLAG_FINISH_TIMERS) != 0) fail_msg("fixture");
    push_light(&f, 1.0f);
    glow_gl_stats gs2;
    const glow_update_desc tiny = {.budget_ms = 1e-6f}, huge = {.budget_ms = 1e6f};
    uint32_t gathered[4];
    for (int u = 0; u < 4; ++u) {
        assert_int_equal(glow_gl_system_update(f.gpu, u < 3 ? &tiny : &huge), GLOW_OK);
        assert_int_equal(glow_gl_system_get_stats(f.gpu, &gs2), GLOW_OK);
        gathered[u] = gs2.caches_gathered;
    }
    printf("  budget_ms 1e-6: %u, %u, %u caches gathered; then 1e6: %u (of %u)\n", gathered[0], gathered[1], gathered[2],
           gathered[3], C);
    assert_int_equal(gathered[0], C);
    assert_int_equal(gathered[1], GLOW_BUDGET_GROUP);
    assert_int_equal(gathered[2], GLOW_BUDGET_GROUP);
    assert_int_equal(gathered[3], C);
    assert_int_equal(glow_gl_system_update(f.gpu, &(glow_update_desc){.budget_ms = -1.0f}), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_update(f.gpu, &(glow_update_desc){.budget_ms = INFINITY}), GLOW_ERROR_INVALID_ARGUMENT);
    free_fixture(&f);
}

/* converged_epsilon on the GPU skips the groups the CPU solver skips: under a still light both gather
 * every group while the bounces settle, then fewer, then none, with the same counts update by update;
 * the caches agree; a brighter light (the drift of the node luma) brings every group back on both. */
static void test_converged(void **state) {
    (void)state;
    fixture f;
    if (make_fixture(&f, "builtin:cornell", NULL, 3, 3, 0) != 0) fail_msg("fixture");
    const uint32_t C = glow_system_outputs(f.cpu)->cache_count;
    const glow_update_desc d = {.converged_epsilon = 1e-3f};
    push_light(&f, 1.0f);
    enum { U = 40 };
    uint32_t cg[U], gg[U], differ = 0, first_none = U, set_differ = 0;
    glow_update_stats cs;
    glow_gl_stats gs;
    /* which caches each backend changed in an update: equal counts can hide two groups that tipped
     * opposite ways in the same update (one gathered here, another there), so the sets are compared */
    const size_t n = (size_t)C * glow_system_outputs(f.cpu)->coeff_count;
    float *prev[2] = {calloc(n, sizeof(float)), calloc(n, sizeof(float))}, *now_g = malloc(n * sizeof(float));
    assert_true(prev[0] && prev[1] && now_g);
    for (int u = 0; u < U; ++u) {
        assert_int_equal(glow_system_update(f.cpu, &d), GLOW_OK);
        assert_int_equal(glow_gl_system_update(f.gpu, &d), GLOW_OK);
        assert_int_equal(glow_system_get_stats(f.cpu, &cs), GLOW_OK);
        assert_int_equal(glow_gl_system_get_stats(f.gpu, &gs), GLOW_OK);
        cg[u] = cs.caches_gathered;
        gg[u] = gs.caches_gathered;
        const float *now_c = glow_system_outputs(f.cpu)->cache_sh;
        assert_int_equal(glow_gl_system_read_cache_sh(f.gpu, now_g, n), GLOW_OK);
        const size_t K = n / C;
        bool sets_differ = false;
        for (uint32_t c = 0; c < C && !sets_differ; ++c)
            sets_differ = (memcmp(now_c + c * K, prev[0] + c * K, K * sizeof(float)) != 0) !=
                          (memcmp(now_g + c * K, prev[1] + c * K, K * sizeof(float)) != 0);
        memcpy(prev[0], now_c, n * sizeof(float));
        memcpy(prev[1], now_g, n * sizeof(float));
        set_differ += sets_differ;
        differ += cg[u] != gg[u] || sets_differ;
        if (gg[u] == 0 && first_none == U) first_none = (uint32_t)u;
    }
    free(prev[0]);
    free(prev[1]);
    free(now_g);
    printf("builtin:cornell, converged_epsilon 1e-3, still light: caches gathered CPU / GPU per update:");
    for (int u = 0; u < U; ++u) printf(" %u/%u", cg[u], gg[u]);
    printf("\n  %u of %d updates differ (%u of them in which caches changed alone); none gathered from update %u; "
           "skipped as converged %u (CPU %u)\n", differ, U, set_differ, first_none, gs.caches_skipped_converged,
           cs.caches_skipped_converged);
    assert_int_equal(cg[0], C);
    assert_int_equal(gg[0], C);
    assert_true(first_none < U - 5);        /* converged: it stops costing */
    assert_int_equal(cg[U - 1], 0);
    assert_int_equal(gs.caches_skipped_converged, C);
    assert_int_equal(cs.caches_skipped_converged, C);
    assert_true(differ <= U / 10);          /* the same decisions (a group at the threshold may tip either way) */
    /* Where a group tipped (one backend stopped gathering it an update before the other), that
     * backend's copy stays up to about its last relative change, below converged_epsilon, times
     * ρ/(1 − ρ) of further bounces behind: a few 1e-3 of the group's own values, so up to ten of the
     * compare's tolerances (1e-3 of the plane's largest value). Without a tip, one tolerance. The
     * bake of 2026-11-29 (lightmap cones fitted to the exact cosine) tips one group of 16 at update
     * 14 (CPU 64, GPU 48 caches gathered): 3.4 of tolerance. The bake of 2026-11-30 (mixed clusters
     * read by their parts, links.c) tips two groups opposite ways in one update with equal counts,
     * which only the sets of changed caches show: 2.9 of tolerance. */
    assert_true(compare(&f, "converged") <= (differ ? 10.0 : 1.0));
    push_light(&f, 2.0f); /* the light changed: every group again, on both */
    assert_int_equal(glow_system_update(f.cpu, &d), GLOW_OK);
    assert_int_equal(glow_gl_system_update(f.gpu, &d), GLOW_OK);
    assert_int_equal(glow_system_get_stats(f.cpu, &cs), GLOW_OK);
    assert_int_equal(glow_gl_system_get_stats(f.gpu, &gs), GLOW_OK);
    printf("  brighter light: CPU %u, GPU %u caches gathered\n", cs.caches_gathered, gs.caches_gathered);
    assert_int_equal(cs.caches_gathered, C);
    assert_int_equal(gs.caches_gathered, C);
    assert_int_equal(glow_gl_system_update(f.gpu, &(glow_update_desc){.converged_epsilon = -1.0f}), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_update(f.gpu, &(glow_update_desc){.converged_epsilon = NAN}), GLOW_ERROR_INVALID_ARGUMENT);
    free_fixture(&f);
}

static void test_cornell(void **state) {
    (void)state;
    agree_scene("builtin:cornell", 3, 3);
}
static void test_two_rooms(void **state) {
    (void)state;
    agree_scene("builtin:two-rooms", 3, 3);
}
static void test_bands(void **state) {
    (void)state;
    agree_scene("builtin:cornell", 2, 1);
    agree_scene("builtin:cornell", 5, 2);
}

/* Link gradients (glow-bake --link-subsets gradient): the GPU pulls the luma-flux moments, computes each
 * coded node's u (gradient_u.comp, rounded to halves as the CPU) and scales the coded links, as the CPU
 * solver does; the same checks as agree_scene, and a budget. */
static void test_link_gradients(void **state) {
    (void)state;
    g_gradient = true;
    agree_scene("builtin:cornell", 3, 3);
    fixture f;
    const int made = make_fixture(&f, "builtin:cornell", NULL, 3, 3, 0);
    g_gradient = false;
    if (made != 0) fail_msg("fixture (link gradients)");
    glow_solver_tables t;
    assert_int_equal(glow_system_get_solver_tables(f.cpu, &t), GLOW_OK);
    size_t coded = 0, links = (size_t)t.cache_count * t.link_blocks_per_cache * 16u;
    for (size_t j = 0; j < links; ++j) coded += (t.link_gradients[j] & 0x8000u) != 0;
    printf("builtin:cornell, link gradients: %zu of %zu link slots carry a code, %u nodes read with one; a budget:\n",
           coded, links, t.gradient_node_count);
    assert_true(coded > 0);
    push_light(&f, 1.0f);
    const float focus[3] = {-0.5f, 0.2f, 0.3f};
    const glow_update_desc d = {.max_caches = t.cache_count / 4, .focus = focus, .focus_count = 1};
    for (int u = 0; u < 8; ++u) {
        assert_int_equal(glow_system_update(f.cpu, &d), GLOW_OK);
        assert_int_equal(glow_gl_system_update(f.gpu, &d), GLOW_OK);
    }
    assert_true(compare(&f, "gradients, 8 budgeted updates") <= 1.0);
    free_fixture(&f);
}

/* the GLSL hook against the same light as a CPU hook */
static void test_hook(void **state) {
    (void)state;
    fixture f;
    if (make_fixture(&f, "builtin:cornell", HOOK_POINT, 3, 3, 0) != 0) fail_msg("fixture");
    printf("builtin:cornell, GLSL hook vs CPU hook:\n");
    run_both(&f, 1, 0);
    assert_true(compare(&f, "hook, after 1 update") <= 1.0);
    run_both(&f, 19, 0);
    assert_true(compare(&f, "hook, after 20 updates") <= 1.0);
    glow_gl_stats st;
    assert_int_equal(glow_gl_system_get_stats(f.gpu, &st), GLOW_OK);
    assert_int_equal(st.hook_nonfinite, 0);
    assert_true(st.pull_dispatches > 0);
    printf("  GPU ms (%s): surfel %.3f (hook %.3f) pull %.3f (%u dispatches) cache %.3f output %.3f total %.3f\n",
           st.renderer, st.surfel_lighting_ms, st.host_ms, st.pull_ms, st.pull_dispatches, st.cache_lighting_ms,
           st.output_ms, st.total_ms);
    free_fixture(&f);
}

/* bad hooks: a compile error is reported with the log; NaN never reaches the caches */
static void test_bad_hooks(void **state) {
    (void)state;
    fixture f;
    g_log_errors = 0;
    const char *broken = "#define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED\nvec3 glow_host_surfel_irradiance(vec3 p, vec3 n, uint m) { return undefined_thing; }\n";
    memset(&f, 0, sizeof f);
    assert_int_equal(make_fixture(&f, "builtin:cornell", NULL, 3, 3, 0), 0);
    glow_gl_system *bad = NULL;
    glow_gl_desc gd = {.system = f.cpu, .get_proc_address = glow_glctx_get_proc_address(g_gl), .hook_glsl = broken,
                       .logger = {logger, NULL}};
    assert_int_equal(glow_gl_system_create(&gd, &bad), GLOW_ERROR_HOST_CALLBACK);
    assert_null(bad);
    assert_non_null(strstr(g_last_log, "host hook"));
    printf("  broken hook: %.160s...\n", g_last_log);
    gd.hook_glsl = "vec3 glow_host_surfel_irradiance(vec3 p, vec3 n, uint m) { return vec3(1.0); }\n"; /* no #define */
    assert_int_equal(glow_gl_system_create(&gd, &bad), GLOW_ERROR_HOST_CALLBACK);
    assert_non_null(strstr(g_last_log, "GLOW_HOST_SURFEL_IRRADIANCE_DEFINED"));
    /* NaN for some surfels: stored as 0 and counted; caches finite. The NaN is built from its bits:
     * NVIDIA's compiler may fold a 0.0 / 0.0 of constants to a finite value. */
    const char *nan_hook = "#define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED\n"
                           "vec3 glow_host_surfel_irradiance(vec3 p, vec3 n, uint m) {\n"
                           "  float q = uintBitsToFloat(0x7fc00000u); return p.y > 0.5 ? vec3(q) : vec3(4.0) * max(n.y, 0.0) + vec3(1.0); }\n";
    gd.hook_glsl = nan_hook;
    glow_gl_system *g = NULL;
    assert_int_equal(glow_gl_system_create(&gd, &g), GLOW_OK);
    /* bad budgets (test_budget and test_converged run the good ones) */
    assert_int_equal(glow_gl_system_update(g, &(glow_update_desc){.converged_epsilon = INFINITY}), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_update(g, &(glow_update_desc){.max_caches = 16, .focus_radius = NAN}),
                     GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_update(g, &(glow_update_desc){.max_caches = 16, .focus_count = 1}),
                     GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_update(g, NULL), GLOW_OK);
    glow_gl_stats st;
    assert_int_equal(glow_gl_system_get_stats(g, &st), GLOW_OK);
    assert_true(st.hook_nonfinite > 0);
    const glow_gl_outputs *o = glow_gl_system_outputs(g);
    size_t n = (size_t)o->cache_count * o->coeff_count;
    float *sh = malloc(n * sizeof *sh);
    assert_int_equal(glow_gl_system_read_cache_sh(g, sh, n), GLOW_OK);
    double total = 0.0;
    for (size_t i = 0; i < n; ++i) {
        assert_true(isfinite(sh[i]));
        total += fabs(sh[i]);
    }
    assert_true(total > 0.0);
    printf("  NaN hook: %u surfels counted, caches finite\n", st.hook_nonfinite);
    glow_gl_system_destroy(g);
    /* CHECK_HOOK: the update fails and the outputs stay those of the last good update (the hook's
     * uniform switches the NaN on after one good update) */
    gd.flags = GLOW_GL_FLAG_CHECK_HOOK;
    gd.hook_glsl = "#define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED\n"
                   "uniform int u_nan = 0;\n"
                   "vec3 glow_host_surfel_irradiance(vec3 p, vec3 n, uint m) {\n"
                   "  float q = uintBitsToFloat(0x7fc00000u); return (u_nan != 0 && p.y > 0.5) ? vec3(q) : vec3(2.0) * max(n.y, 0.0) + vec3(1.0); }\n";
    assert_int_equal(glow_gl_system_create(&gd, &g), GLOW_OK);
    assert_int_equal(glow_gl_system_update(g, NULL), GLOW_OK);
    float *before = malloc(n * sizeof *before);
    assert_int_equal(glow_gl_system_read_cache_sh(g, before, n), GLOW_OK);
    glow_glfns fns;
    assert_true(glow_glfns_load(&fns, glow_glctx_get_proc_address(g_gl), NULL, 0));
    const GLuint prog = glow_gl_system_outputs(g)->hook_program;
    assert_true(prog != 0);
    fns.ProgramUniform1i(prog, fns.GetUniformLocation(prog, "u_nan"), 1);
    assert_int_equal(glow_gl_system_update(g, NULL), GLOW_ERROR_HOST_CALLBACK);
    assert_int_equal(glow_gl_system_read_cache_sh(g, sh, n), GLOW_OK);
    assert_memory_equal(sh, before, n * sizeof *sh);
    fns.ProgramUniform1i(prog, fns.GetUniformLocation(prog, "u_nan"), 0);
    assert_int_equal(glow_gl_system_update(g, NULL), GLOW_OK); /* usable again */
    glow_gl_system_destroy(g);
    free(before);
    free(sh);
    /* missing GL features: a missing entry point, an older context */
    gd.flags = 0;
    gd.hook_glsl = NULL;
    g_hidden = "glDispatchCompute";
    gd.get_proc_address = hiding_loader;
    assert_int_equal(glow_gl_system_create(&gd, &g), GLOW_ERROR_UNSUPPORTED);
    assert_null(g);
    assert_non_null(strstr(g_last_log, "glDispatchCompute"));
    printf("  missing entry point: %s\n", g_last_log);
    gd.get_proc_address = old_loader;
    assert_int_equal(glow_gl_system_create(&gd, &g), GLOW_ERROR_UNSUPPORTED);
    assert_non_null(strstr(g_last_log, "4.3"));
    printf("  old context: %s\n", g_last_log);
    gd.get_proc_address = glow_glctx_get_proc_address(g_gl);
    /* host textures of the wrong size */
    {
        glow_glfns f2;
        assert_true(glow_glfns_load(&f2, glow_glctx_get_proc_address(g_gl), NULL, 0));
        GLuint tex;
        f2.CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &tex);
        f2.TextureStorage3D(tex, 1, GL_RGBA32F, 8, 8, 1);
        gd.lightmap_texture = tex;
        assert_int_equal(glow_gl_system_create(&gd, &g), GLOW_ERROR_INVALID_ARGUMENT);
        assert_non_null(strstr(g_last_log, "lightmap"));
        printf("  wrong host texture: %s\n", g_last_log);
        gd.lightmap_texture = 0;
        f2.DeleteTextures(1, &tex);
    }
    /* bad arguments */
    assert_int_equal(glow_gl_system_create(NULL, &g), GLOW_ERROR_INVALID_ARGUMENT);
    gd.system = NULL;
    assert_int_equal(glow_gl_system_create(&gd, &g), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_update(NULL, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_update(f.gpu, &(glow_update_desc){.flags = 0x100}), GLOW_ERROR_INVALID_ARGUMENT);
    glow_gl_system_destroy(NULL);
    free_fixture(&f);
}

/* Light across systems on the GPU (glow_gl_system_set_neighbour, proxy_fill.comp): the pillar hall baked
 * as a world of systems of at most 100 m², each system's GL backend attached to its neighbours' GL
 * systems, agrees with the CPU solvers attached the same way, after 1 and after 6 rounds of updates of
 * every system in turn (each round's light crossing the borders one update late on both). A GL system
 * that another reads is not destroyed until detached. */
#define WORLD_MAX 16
static void test_world_systems(void **state) {
    (void)state;
    char dir[128], out[200];
    snprintf(dir, sizeof dir, "/tmp/glow_gpu_world_%d", (int)getpid());
    snprintf(out, sizeof out, "%s/w.json", dir);
    assert_int_equal(mkdir(dir, 0700), 0);
    glow_pc_settings st = {.surfels = 1024, .links = 32, .lightmap_caches = 300, .lightmap_detail = 1, .threads = 2,
                           .seed = 1, .system_area = 100.0f};
    glow_pc_stats stats;
    if (glow_pc_bake("builtin:pillar-hall", out, &st, &stats) != GLOW_OK) fail_msg("world bake: %s", stats.error);
    assert_true(stats.systems >= 2 && stats.systems <= WORLD_MAX && stats.proxies > 0);
    DIR *d = opendir(dir);
    assert_non_null(d);
    char names[WORLD_MAX][300];
    uint32_t n = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (strncmp(e->d_name, "w.s", 3) == 0 && strstr(e->d_name, ".glow") && n < WORLD_MAX && strlen(e->d_name) < 100)
            snprintf(names[n++], sizeof names[0], "%s/%.100s", dir, e->d_name);
    closedir(d);
    assert_int_equal(n, stats.systems);
    fixture f[WORLD_MAX];
    memset(f, 0, sizeof f);
    for (uint32_t i = 0; i < n; ++i) {
        glow_context_desc cd = {.api_version = GLOW_VERSION, .tasks = {.worker_count = 2}, .logger = {logger, NULL}};
        assert_int_equal(glow_context_create(&cd, &f[i].ctx), GLOW_OK);
        assert_int_equal(glow_bake_load_file(f[i].ctx, names[i], &f[i].bake), GLOW_OK);
        assert_int_equal(glow_system_create(f[i].ctx, &(glow_system_desc){.bake = f[i].bake, .label = names[i]}, &f[i].cpu),
                         GLOW_OK);
        glow_gl_desc gd = {.system = f[i].cpu, .get_proc_address = glow_glctx_get_proc_address(g_gl), .label = names[i],
                           .logger = {logger, NULL}};
        assert_int_equal(glow_gl_system_create(&gd, &f[i].gpu), GLOW_OK);
        push_light(&f[i], 1.0f);
    }
    uint32_t attached = 0;
    for (uint32_t i = 0; i < n; ++i) {
        glow_bake_info bi;
        glow_bake_get_info(f[i].bake, &bi);
        for (uint32_t dep = 0; dep < bi.dependency_count; ++dep) {
            uint64_t key = 0;
            assert_int_equal(glow_bake_get_dependency(f[i].bake, dep, &key), GLOW_OK);
            for (uint32_t j = 0; j < n; ++j) {
                glow_bake_info bj;
                glow_bake_get_info(f[j].bake, &bj);
                if (bj.system_key != key) continue;
                assert_int_equal(glow_gl_system_set_neighbour(f[i].gpu, dep, f[j].gpu), GLOW_OK); /* and the CPUs' */
                attached++;
            }
        }
    }
    assert_true(attached > 0);
    assert_int_equal(glow_gl_system_set_neighbour(f[0].gpu, 64, f[1].gpu), GLOW_ERROR_INVALID_ARGUMENT);
    printf("pillar hall in %u systems, %u dependencies attached on the CPU and the GPU:\n", n, attached);
    for (uint32_t round = 0; round < 6; ++round) {
        for (uint32_t i = 0; i < n; ++i) assert_int_equal(glow_system_update(f[i].cpu, NULL), GLOW_OK);
        for (uint32_t i = 0; i < n; ++i) assert_int_equal(glow_gl_system_update(f[i].gpu, NULL), GLOW_OK);
        if (round != 0 && round != 5) continue;
        for (uint32_t i = 0; i < n; ++i) {
            char what[64];
            snprintf(what, sizeof what, "system %u, round %u", i, round + 1);
            assert_true(compare(&f[i], what) <= 1.0);
        }
    }
    /* a GL system another reads is not destroyed (logged, still usable) */
    glow_bake_info b0;
    glow_bake_get_info(f[0].bake, &b0);
    uint64_t k0 = 0;
    assert_int_equal(glow_bake_get_dependency(f[0].bake, 0, &k0), GLOW_OK);
    for (uint32_t j = 0; j < n; ++j) {
        glow_bake_info bj;
        glow_bake_get_info(f[j].bake, &bj);
        if (bj.system_key != k0) continue;
        glow_gl_system_destroy(f[j].gpu);
        assert_int_equal(glow_gl_system_update(f[j].gpu, NULL), GLOW_OK);
    }
    for (uint32_t i = 0; i < n; ++i) { /* detach everything, then free */
        glow_bake_info bi;
        glow_bake_get_info(f[i].bake, &bi);
        for (uint32_t dep = 0; dep < bi.dependency_count; ++dep)
            assert_int_equal(glow_gl_system_set_neighbour(f[i].gpu, dep, NULL), GLOW_OK);
    }
    for (uint32_t i = 0; i < n; ++i) {
        free_fixture(&f[i]);
        remove(names[i]);
    }
    remove(out);
    rmdir(dir);
}

/* The GL grid texture against the CPU's grid_sh, cell by cell: the cell's coefficients within 1e-3 of
 * the largest |c| of its Y, Co or Cg block plus 1e-6 of the largest of all (compare's tolerance).
 * Returns the worst error in units of the tolerance. */
static double compare_grid(fixture *f, const char *what) {
    const glow_cache_outputs *o = glow_system_outputs(f->cpu);
    const glow_gl_outputs *go = glow_gl_system_outputs(f->gpu);
    assert_non_null(o->grid_sh);
    assert_int_not_equal(go->grid_texture, 0);
    const uint32_t dx = o->grid_dims[0], dy = o->grid_dims[1], dz = o->grid_dims[2], nc = o->coeff_count;
    const size_t cells = (size_t)dx * dy * dz, n = cells * 4u * go->planes;
    float *g = malloc(n * sizeof *g);
    assert_non_null(g);
    glow_glfns fns;
    assert_true(glow_glfns_load(&fns, glow_glctx_get_proc_address(g_gl), NULL, 0));
    fns.MemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    fns.GetTextureImage(go->grid_texture, 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof *g), g);
    const uint32_t L2 = o->sh_bands_luma * o->sh_bands_luma, C2 = o->sh_bands_chroma * o->sh_bands_chroma;
    const uint32_t starts[4] = {0, L2, L2 + C2, L2 + 2 * C2};
    double global = 0.0, worst = 0.0;
    for (size_t i = 0; i < cells * nc; ++i) global = fmax(global, fabs(o->grid_sh[i]));
    size_t filled = 0;
    for (size_t cell = 0; cell < cells; ++cell) {
        if (o->grid_map[cell] == 0xFFFFFFFFu) continue;
        filled++;
        const size_t z = cell / ((size_t)dx * dy), xy = cell % ((size_t)dx * dy);
        for (int blk = 0; blk < 3; ++blk) {
            double scale = 0.0;
            for (uint32_t k = starts[blk]; k < starts[blk + 1]; ++k) scale = fmax(scale, fabs(o->grid_sh[k * cells + cell]));
            for (uint32_t k = starts[blk]; k < starts[blk + 1]; ++k) {
                const size_t texel = (z + (size_t)(k / 4u) * dz) * dx * dy + xy; /* plane k/4 at z + p dz */
                const double e = fabs((double)g[4 * texel + k % 4u] - o->grid_sh[k * cells + cell]) / (1e-3 * scale + 1e-6 * global);
                worst = fmax(worst, e);
            }
        }
    }
    printf("  %-34s grid %ux%ux%u, %zu cells hold a cache: worst %.3f of tolerance\n", what, dx, dy, dz, filled, worst);
    free(g);
    assert_true(filled > 0 && global > 0.0);
    return worst;
}

/* The visible sky of the grid caches on the GPU (glow_gl_system_set_sky) against the CPU solver's
 * (glow_system_set_sky): the same errors; after a bounce reset (whose bounce does not depend on the
 * past) the caches with the sky minus those without it are the sky's V ⊗ L on both, within compare's
 * tolerance, non-zero in the grid caches and zero in the lightmap caches; budgeted updates with the sky
 * (caches not gathered keep their rows: the sky must be taken out and put back, not added again), a
 * turned sky, and the sky removed all agree. */
static void test_sky(void **state) {
    (void)state;
    fixture f; /* a court open to the sky (the Cornell box is closed: its grid caches see none) */
    if (make_fixture(&f, "builtin:pillar-court", NULL, 3, 3, 0) != 0) fail_msg("fixture");
    const glow_cache_outputs *o = glow_system_outputs(f.cpu);
    const uint32_t C = o->cache_count, G = o->grid_cache_count, nc = o->coeff_count;
    glow_bake_sky_transfer sk;
    assert_int_equal(glow_bake_get_sky_transfer(f.bake, &sk), GLOW_OK);
    assert_int_equal(sk.grid_cache_count, G);
    assert_true(G > 0 && G < C);
    /* a sky with every coefficient non-zero: a constant part, a lobe along (0.3, 0.8, 0.5), some l = 2 */
    float sky[GLOW_SKY_SH_FLOATS];
    glow_sh_sky_constant((float[3]){0.6f, 0.8f, 1.1f}, sky);
    for (int k = 1; k < 9; ++k)
        for (int c = 0; c < 3; ++c) sky[3 * k + c] = (k < 4 ? 0.35f : 0.12f) * (float)((k * 7 + c * 3) % 5 - 2) + 0.05f * (float)c;
    /* errors: as the CPU call */
    float bad[GLOW_SKY_SH_FLOATS];
    memcpy(bad, sky, sizeof bad);
    bad[13] = NAN;
    assert_int_equal(glow_gl_system_set_sky(NULL, sky), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_set_sky(f.gpu, bad), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_system_set_sky(f.cpu, bad), GLOW_ERROR_INVALID_ARGUMENT);
    bad[13] = INFINITY;
    assert_int_equal(glow_gl_system_set_sky(f.gpu, bad), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_gl_system_set_sky(f.gpu, NULL), GLOW_OK);
    printf("builtin:pillar-court, l = 3/3, %u grid caches of %u, a sky of 27 non-zero coefficients:\n", G, C);
    push_light(&f, 1.0f);
    run_both(&f, 6, 0);
    run_both(&f, 1, GLOW_UPDATE_FLAG_RESET_BOUNCE); /* without the sky */
    const size_t n = (size_t)C * nc;
    float *ca = malloc(n * sizeof *ca), *ga = malloc(n * sizeof *ga), *gb = malloc(n * sizeof *gb);
    assert_true(ca && ga && gb);
    memcpy(ca, o->cache_sh, n * sizeof *ca);
    assert_int_equal(glow_gl_system_read_cache_sh(f.gpu, ga, n), GLOW_OK);
    assert_int_equal(glow_system_set_sky(f.cpu, sky), GLOW_OK);
    assert_int_equal(glow_gl_system_set_sky(f.gpu, sky), GLOW_OK);
    run_both(&f, 1, GLOW_UPDATE_FLAG_RESET_BOUNCE); /* the same bounce, with the sky */
    assert_true(compare(&f, "sky, after a bounce reset") <= 1.0);
    assert_true(compare_grid(&f, "sky, grid texture") <= 1.0);
    assert_int_equal(glow_gl_system_read_cache_sh(f.gpu, gb, n), GLOW_OK);
    /* with minus without: the sky's share, on both */
    const uint32_t L2 = o->sh_bands_luma * o->sh_bands_luma, C2 = o->sh_bands_chroma * o->sh_bands_chroma;
    const uint32_t starts[4] = {0, L2, L2 + C2, L2 + 2 * C2};
    double global = 0.0, worst = 0.0, sky_max = 0.0, lm_max = 0.0, lm_gpu_max = 0.0;
    uint32_t lit = 0;
    for (size_t i = 0; i < n; ++i) global = fmax(global, fabs(o->cache_sh[i]));
    for (uint32_t c = 0; c < C; ++c) {
        const float *b = o->cache_sh + (size_t)c * nc, *a = ca + (size_t)c * nc;
        const float *gbc = gb + (size_t)c * nc, *gac = ga + (size_t)c * nc;
        int any = 0;
        for (int blk = 0; blk < 3; ++blk) {
            double scale = 0.0;
            for (uint32_t k = starts[blk]; k < starts[blk + 1]; ++k) scale = fmax(scale, fabs(b[k]));
            for (uint32_t k = starts[blk]; k < starts[blk + 1]; ++k) {
                const double cd = (double)b[k] - a[k], gd = (double)gbc[k] - gac[k];
                worst = fmax(worst, fabs(gd - cd) / (1e-3 * scale + 1e-6 * global));
                if (c < G) sky_max = fmax(sky_max, fabs(cd)), any |= cd != 0.0;
                else lm_max = fmax(lm_max, fabs(cd)), lm_gpu_max = fmax(lm_gpu_max, fabs(gd));
            }
        }
        lit += any;
    }
    printf("  %-34s worst %.3g of tolerance; %u of %u grid caches changed, largest change %.4g (largest |c| %.4g); "
           "lightmap caches' largest change CPU %.3g GPU %.3g\n",
           "with sky minus without", worst, lit, G, sky_max, global, lm_max, lm_gpu_max);
    assert_true(worst <= 1.0);
    assert_true(lit > G / 2);                /* the sky reaches the grid: the check above compares something */
    assert_true(sky_max > 1e-2 * global);
    assert_true(lm_max == 0.0 && lm_gpu_max <= 1e-6 * global); /* lightmap caches: untouched */
    /* budgeted updates with the sky: caches not gathered keep their rows, without the sky added twice */
    const float focus[3] = {-0.5f, 0.2f, 0.3f};
    const glow_update_desc d = {.max_caches = C / 4, .focus = focus, .focus_count = 1};
    for (int u = 0; u < 8; ++u) {
        assert_int_equal(glow_system_update(f.cpu, &d), GLOW_OK);
        assert_int_equal(glow_gl_system_update(f.gpu, &d), GLOW_OK);
    }
    assert_true(compare(&f, "sky, 8 budgeted updates") <= 1.0);
    /* a turned sky, then none */
    float turned[GLOW_SKY_SH_FLOATS];
    glow_sh_rotate_y(sky, 1.3f, turned);
    assert_int_equal(glow_system_set_sky(f.cpu, turned), GLOW_OK);
    assert_int_equal(glow_gl_system_set_sky(f.gpu, turned), GLOW_OK);
    run_both(&f, 3, 0);
    assert_true(compare(&f, "turned sky, 3 updates") <= 1.0);
    assert_true(compare_grid(&f, "turned sky, grid texture") <= 1.0);
    assert_int_equal(glow_system_set_sky(f.cpu, NULL), GLOW_OK);
    assert_int_equal(glow_gl_system_set_sky(f.gpu, NULL), GLOW_OK);
    run_both(&f, 1, GLOW_UPDATE_FLAG_RESET_BOUNCE);
    assert_true(compare(&f, "sky removed, after a bounce reset") <= 1.0);
    assert_int_equal(glow_gl_system_read_cache_sh(f.gpu, gb, n), GLOW_OK);
    double back = 0.0; /* the reset bounce without the sky again: as before it was set */
    for (size_t i = 0; i < n; ++i) back = fmax(back, fabs((double)gb[i] - ga[i]));
    printf("  sky removed: GPU caches within %.3g of those before the sky (largest |c| %.4g)\n", back, global);
    assert_true(back <= 1e-6 * global);
    free(ca), free(ga), free(gb);
    free_fixture(&f);
    remove(f.path);
    /* a bake without the sky transfer: GLOW_ERROR_UNSUPPORTED, as on the CPU */
    char path[256];
    snprintf(path, sizeof path, "/tmp/glow_gpu_agree_%d_nosky.glow", (int)getpid());
    glow_pc_settings st = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 1024, .links = 32, .bands = 3, .threads = 2,
                           .seed = 1, .no_sky = true};
    glow_pc_stats stats;
    if (glow_pc_bake("builtin:cornell", path, &st, &stats) != GLOW_OK) fail_msg("bake: %s", stats.error);
    memset(&f, 0, sizeof f);
    glow_context_desc cd = {.api_version = GLOW_VERSION, .tasks = {.worker_count = 2}, .logger = {logger, NULL}};
    assert_int_equal(glow_context_create(&cd, &f.ctx), GLOW_OK);
    assert_int_equal(glow_bake_load_file(f.ctx, path, &f.bake), GLOW_OK);
    assert_int_equal(glow_system_create(f.ctx, &(glow_system_desc){.bake = f.bake}, &f.cpu), GLOW_OK);
    glow_gl_desc gd = {.system = f.cpu, .get_proc_address = glow_glctx_get_proc_address(g_gl), .logger = {logger, NULL}};
    assert_int_equal(glow_gl_system_create(&gd, &f.gpu), GLOW_OK);
    assert_int_equal(glow_system_set_sky(f.cpu, sky), GLOW_ERROR_UNSUPPORTED);
    assert_int_equal(glow_gl_system_set_sky(f.gpu, sky), GLOW_ERROR_UNSUPPORTED);
    printf("  no SKYT: %s\n", g_last_log);
    assert_int_equal(glow_gl_system_set_sky(f.gpu, NULL), GLOW_OK);
    assert_int_equal(glow_gl_system_update(f.gpu, NULL), GLOW_OK);
    free_fixture(&f);
    remove(path);
}

int main(void) {
    char why[512];
    glow_result r = glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_HEADLESS}, &g_gl, why, sizeof why);
    if (r != GLOW_OK) {
        printf("SKIP: no OpenGL 4.5 context (%s): %s\n", glow_result_string(r), why);
        return 77;
    }
    printf("GL: %s, %s (%s)\n", glow_glctx_renderer(g_gl), glow_glctx_version(g_gl),
           glow_glctx_kind_name(glow_glctx_get_kind(g_gl)));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell), cmocka_unit_test(test_two_rooms), cmocka_unit_test(test_bands),
        cmocka_unit_test(test_hook), cmocka_unit_test(test_bad_hooks), cmocka_unit_test(test_world_systems),
        cmocka_unit_test(test_budget), cmocka_unit_test(test_converged), cmocka_unit_test(test_link_gradients),
        cmocka_unit_test(test_sky),
    };
    if (getenv("GLOW_TEST_FILTER")) cmocka_set_test_filter(getenv("GLOW_TEST_FILTER")); /* e.g. test_link_gradients */
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    glow_glctx_destroy(g_gl);
    char path[256];
    const char *scenes[] = {"cornell", "two-rooms", "cornell-grad", "pillar-court", "nosky"};
    for (int i = 0; i < 5; ++i) {
        snprintf(path, sizeof path, "/tmp/glow_gpu_agree_%d_%s.glow", (int)getpid(), scenes[i]);
        remove(path);
    }
    return rc;
}
