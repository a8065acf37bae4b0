/* test_furnace.c — the white furnace (issue 3, correctness): the built-in closed cube, every wall
 * emitting radiance L_e with uniform albedo ρ, must converge to the analytic radiosity: the radiance
 * arriving anywhere inside is L = L_e / (1 - ρ) (B = E/(1-ρ) with E = π L_e). Checked within 2 % for
 * ρ = 0.5 and 0.9 at every lightmap cache (diffuse-shaded along its normal: the cosine-weighted
 * mean incident radiance) and every grid cache (the SH average over the sphere).
 *
 * At ρ = 0.9 a per-bounce error δ in the transport is amplified ρ/(1-ρ) = 9 times, so this checks
 * the whole chain: link coverage (the linker's ray normalisation), the cone fit, SH projection and
 * convolution, the feedback, and the non-divergence cap (which must not bite here). */
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

#include "glow/glow.h"
#include "glow/glow_precompute.h"
#include "runtime_internal.h"

typedef struct fixture {
    glow_context *ctx;
    glow_bake *bake;
    char path[256];
} fixture;

static int setup(void **state) {
    static fixture f;
    snprintf(f.path, sizeof f.path, "/tmp/glow_furnace_%d.glow", (int)getpid());
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 96, .bands = 3, .threads = 2, .seed = 1,
                          .sh_links = true}; /* SHLK too, for GLOW_LINK_MODE_SH */
    glow_pc_stats st;
    if (glow_pc_bake("builtin:furnace", f.path, &s, &st) != GLOW_OK) {
        fprintf(stderr, "bake failed: %s\n", st.error);
        return -1;
    }
    if (glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION}, &f.ctx) != GLOW_OK) return -1;
    if (glow_bake_load_file(f.ctx, f.path, &f.bake) != GLOW_OK) return -1;
    *state = &f;
    return 0;
}

static int teardown(void **state) {
    fixture *f = *state;
    glow_bake_destroy(f->bake);
    glow_context_destroy(f->ctx);
    remove(f->path);
    return 0;
}

static void furnace(fixture *f, float rho, glow_link_mode mode) {
    glow_system *sys;
    assert_int_equal(glow_system_create(f->ctx, &(glow_system_desc){.bake = f->bake, .link_mode = mode}, &sys), GLOW_OK);
    glow_update_stats us;
    assert_int_equal(glow_system_get_stats(sys, &us), GLOW_OK);
    assert_int_equal(us.link_mode, mode == GLOW_LINK_MODE_DEFAULT ? GLOW_LINK_MODE_COMPACT : mode);
    glow_material_info mi;
    assert_int_equal(glow_bake_get_material(f->bake, 0, &mi), GLOW_OK);
    assert_true(mi.emission[0] > 0.0f);
    const float le = mi.emission[0];
    const float scale = rho / mi.albedo[0];
    assert_int_equal(glow_system_set_material(sys, 0, NULL, (float[3]){scale, scale, scale}), GLOW_OK);
    assert_int_equal(glow_system_set_params(sys, &(glow_system_params){.bounce_intensity = 1.0f, .emission_scale = 1.0f,
                                                                        .bounce_iterations = 64}),
                     GLOW_OK);
    /* 192 bounces: 0.9^192 ~ 2e-9 of the first bounce is left */
    for (int i = 0; i < 3; ++i) assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);

    const glow_cache_outputs *o = glow_system_outputs(sys);
    const glow_bake_cache *caches = glow__bake_caches(f->bake);
    const double expect = le / (1.0 - rho);
    double lm_sum = 0.0, lm_worst = 0.0, grid_sum = 0.0, grid_worst = 0.0;
    for (uint32_t c = 0; c < o->cache_count; ++c) {
        const float *sh = o->cache_sh + (size_t)c * o->coeff_count;
        double v;
        if (c < o->grid_cache_count) {
            v = sh[0] * 0.28209479177387814; /* the mean over the sphere: c00 * y00 */
            grid_sum += v;
            grid_worst = fmax(grid_worst, fabs(v / expect - 1.0));
        } else {
            float n[3], rgb[3];
            glow__oct_decode(caches[c].normal_oct, n);
            glow_shade_sh(sh, o->sh_bands_luma, o->sh_bands_chroma, n, 1.0f, rgb);
            v = rgb[1];
            assert_true(fabs(rgb[0] - rgb[1]) < 1e-4 * expect && fabs(rgb[2] - rgb[1]) < 1e-4 * expect); /* grey */
            lm_sum += v;
            lm_worst = fmax(lm_worst, fabs(v / expect - 1.0));
        }
    }
    const double lm_mean = lm_sum / o->lightmap_cache_count, grid_mean = grid_sum / o->grid_cache_count;
    printf("furnace (%s links) rho %.2f: expected %.4f; lightmap caches mean %.4f (%+.2f %%, worst %.2f %%), grid caches mean %.4f "
           "(%+.2f %%, worst %.2f %%)\n",
           us.link_mode == GLOW_LINK_MODE_COMPACT ? "compact" : us.link_mode == GLOW_LINK_MODE_SH ? "full-SH" : "expanded", rho, expect, lm_mean, 100.0 * (lm_mean / expect - 1.0), 100.0 * lm_worst, grid_mean,
           100.0 * (grid_mean / expect - 1.0), 100.0 * grid_worst);
    assert_true(fabs(lm_mean / expect - 1.0) < 0.02);
    assert_true(fabs(grid_mean / expect - 1.0) < 0.02);
    /* every single cache, not only the mean (corners and edges are where links are hardest). The
     * full-SH links are the comparison baseline (PIC Eq. 2 as published): their lightmap caches at
     * the cube's edges are off by up to 8.7 % at rho 0.5 (leaf sums that straddle the texel's horizon,
     * which the cone links' edge fix and cone fit correct; docs/results.md), so for them only the
     * means and the grid caches are held to the product's bounds */
    if (mode != GLOW_LINK_MODE_SH) assert_true(lm_worst < 0.05);
    assert_true(grid_worst < 0.05);
    glow_system_destroy(sys);
}

static void test_furnace_half(void **state) { furnace(*state, 0.5f, GLOW_LINK_MODE_DEFAULT); }
static void test_furnace_090(void **state) { furnace(*state, 0.9f, GLOW_LINK_MODE_DEFAULT); }
/* the expanded links (half-float k_l y_lm per link, computed at create) must agree as well */
static void test_furnace_090_expanded(void **state) { furnace(*state, 0.9f, GLOW_LINK_MODE_EXPANDED); }
/* the bake's full-SH links (PIC Eq. 2): projected from the visible leaves, not a cone. A uniform
 * field over a hemisphere has no even bands above 0, so 3 bands shade it exactly: the remaining
 * error is the links' leaf sums (measured at rho 0.9: means -1.1 % / -1.2 %, lightmap worst 9.3 %) */
static void test_furnace_050_sh(void **state) { furnace(*state, 0.5f, GLOW_LINK_MODE_SH); }
/* SH mode asks for the bake's full-SH links: refused without them, and above the bake's bands */
static void test_sh_mode_errors(void **state) {
    fixture *f = *state;
    glow_system *sys = (glow_system *)1;
    assert_int_equal(glow_system_create(f->ctx, &(glow_system_desc){.bake = f->bake, .link_mode = GLOW_LINK_MODE_SH,
                                                                     .sh_bands_luma = 4},
                                        &sys),
                     GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(sys);
    /* fewer bands than the bake's: the kernel reads the first 2² rows of each 3-band SHLK block */
    assert_int_equal(glow_system_create(f->ctx, &(glow_system_desc){.bake = f->bake, .link_mode = GLOW_LINK_MODE_SH,
                                                                     .sh_bands_luma = 2, .sh_bands_chroma = 1},
                                        &sys),
                     GLOW_OK);
    assert_int_equal(glow_system_set_params(sys, &(glow_system_params){.bounce_intensity = 1.0f, .emission_scale = 1.0f,
                                                                        .bounce_iterations = 64}),
                     GLOW_OK);
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(sys);
    assert_int_equal(o->coeff_count, 4u + 2u);
    double mean = 0.0;
    for (uint32_t c = 0; c < o->grid_cache_count; ++c) mean += o->cache_sh[(size_t)c * o->coeff_count] * 0.28209479177387814;
    mean /= o->grid_cache_count;
    assert_true(fabs(mean / 2.0 - 1.0) < 0.02); /* albedo 0.5, L_e 1 */
    glow_system_destroy(sys);
    char path[256];
    snprintf(path, sizeof path, "/tmp/glow_furnace_nosh_%d.glow", (int)getpid());
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 1024, .links = 32, .bands = 3, .threads = 2, .seed = 1};
    assert_int_equal(glow_pc_bake("builtin:furnace", path, &s, NULL), GLOW_OK);
    glow_bake *b;
    assert_int_equal(glow_bake_load_file(f->ctx, path, &b), GLOW_OK);
    sys = (glow_system *)1;
    assert_int_equal(glow_system_create(f->ctx, &(glow_system_desc){.bake = b, .link_mode = GLOW_LINK_MODE_SH}, &sys),
                     GLOW_ERROR_UNSUPPORTED);
    assert_null(sys);
    glow_bake_destroy(b);
    remove(path);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_furnace_half), cmocka_unit_test(test_furnace_090),
                                       cmocka_unit_test(test_furnace_090_expanded), cmocka_unit_test(test_furnace_050_sh),
                                       cmocka_unit_test(test_sh_mode_errors)};
    return cmocka_run_group_tests(tests, setup, teardown);
}
