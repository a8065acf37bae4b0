/* test_render_ddish.c — DDISH-GI on Glow's caches (glow_render_ddish, docs/ddish.md).
 *
 * - The hysteresis blend, by hand, and applied F times to a constant from 0: c (1 - a^F).
 * - The furnace (builtin:furnace, closed box, albedo 0.5, every wall L_e = 1): the incident radiance
 *   is 2 everywhere, so the view's indirect image is ρ · 2 = 1 at every pixel. DDISH's caches, with the
 *   cold start as a running mean, give a mean within 2 % of it; without the ramp and a = 0.5, 3 frames
 *   give 1 - 0.5³ = 0.875 (the blend inside the pipeline); more rays x frames make the error smaller
 *   (4x fewer in the error's square at 32x the samples, asserted as at least 2x smaller).
 * - Its direct image is the reference's, bit for bit (same camera rays and random numbers).
 * - Glow's view after a light change (the lag's counterpart): the dimmed furnace after 1, 2 and 64
 *   feedback iterations, against the fixed point iteration by hand.
 * - Bad input: a hysteresis of 1, a move after the last frame, a moved scene of another mesh. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "glow/glow_precompute.h"
#include "glow_render.h"

typedef struct fixture {
    char dir[128], furnace_json[192], floor_json[192], bake[192];
    glow_render_scene *furnace, *floor;
} fixture;

static int write_file(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fputs(text, f);
    return fclose(f);
}

static int setup(void **state) {
    static fixture f;
    memset(&f, 0, sizeof f);
    snprintf(f.dir, sizeof f.dir, "/tmp/glow_test_ddish_%d", (int)getpid());
    if (mkdir(f.dir, 0755) != 0) return -1;
    snprintf(f.furnace_json, sizeof f.furnace_json, "%s/furnace.json", f.dir);
    /* inside the cube [-1,1]^3, looking at a corner region (edges and corners are in view) */
    if (write_file(f.furnace_json,
                   "{\"mesh\": \"builtin:furnace\", \"camera\": {\"position\": [0.3, 0.2, 0.5], \"target\": [-1, -0.3, -1],"
                   " \"vfov_deg\": 90, \"width\": 32, \"height\": 32}}\n"))
        return -1;
    char path[256];
    snprintf(path, sizeof path, "%s/floor.obj", f.dir);
    if (write_file(path, "v -5 0 -5\nv -5 0 5\nv 5 0 5\nv 5 0 -5\nf 1 2 3\nf 1 3 4\n")) return -1;
    snprintf(f.floor_json, sizeof f.floor_json, "%s/floor.json", f.dir);
    if (write_file(f.floor_json, "{\"mesh\": \"floor.obj\"}\n")) return -1;
    char msg[512];
    if (glow_render_scene_load(f.furnace_json, &f.furnace, msg, sizeof msg) != GLOW_OK ||
        glow_render_scene_load(f.floor_json, &f.floor, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "scene load failed: %s\n", msg);
        return -1;
    }
    snprintf(f.bake, sizeof f.bake, "%s/furnace.glow", f.dir);
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 2048, .links = 32, .bands = 3, .threads = 2, .seed = 1};
    glow_pc_stats st;
    if (glow_pc_bake("builtin:furnace", f.bake, &s, &st) != GLOW_OK) {
        fprintf(stderr, "bake failed: %s\n", st.error);
        return -1;
    }
    *state = &f;
    return 0;
}

static int teardown(void **state) {
    fixture *f = *state;
    glow_render_scene_destroy(f->furnace);
    glow_render_scene_destroy(f->floor);
    char path[300];
    static const char *names[] = {"furnace.json", "floor.json", "floor.obj", "furnace.glow"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        snprintf(path, sizeof path, "%s/%s", f->dir, names[i]);
        remove(path);
    }
    rmdir(f->dir);
    return 0;
}

static void test_blend_by_hand(void **state) {
    (void)state;
    float h[3] = {2.0f, -1.0f, 0.0f};
    const float fresh[3] = {4.0f, 3.0f, 10.0f};
    glow_render_ddish_blend(h, fresh, 3, 0.75f); /* 0.75 h + 0.25 fresh */
    assert_float_equal(h[0], 2.5f, 1e-6f);
    assert_float_equal(h[1], 0.0f, 1e-6f);
    assert_float_equal(h[2], 2.5f, 1e-6f);
    float c = 0.0f;
    const float one = 1.0f;
    for (int f = 0; f < 100; ++f) glow_render_ddish_blend(&c, &one, 1, 0.99f);
    assert_float_equal(c, 1.0f - powf(0.99f, 100.0f), 1e-5f); /* 0.6340 */
    glow_render_ddish_blend(&c, &one, 1, 0.0f); /* a = 0: the fresh estimate alone */
    assert_float_equal(c, 1.0f, 0.0f);
}

static double mean_green(const glow_eval_image *img) {
    double s = 0.0;
    const size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; ++i) s += img->rgb[3 * i + 1];
    return s / (double)n;
}

/* RMS of (pixel - 1) over the green channel: the furnace's indirect is 1 everywhere */
static double rms_from_one(const glow_eval_image *img) {
    double s = 0.0;
    const size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; ++i) s += (img->rgb[3 * i + 1] - 1.0) * (img->rgb[3 * i + 1] - 1.0);
    return sqrt(s / (double)n);
}

static double run(fixture *f, uint32_t rays, uint32_t frames, bool ramp, bool set_a, float a, double *rms) {
    glow_render_settings st = {.width = 24, .height = 24, .spp = 1, .seed = 3, .threads = 2};
    glow_render_glow_settings gs = {.indirect_only = true};
    glow_render_ddish_settings ds = {.rays = rays, .frames = frames, .ramp = ramp, .hysteresis_set = set_a, .hysteresis = a};
    glow_render_result res;
    glow_render_ddish_stats stats;
    char msg[512] = "";
    glow_result r = glow_render_ddish(f->furnace, f->bake, &st, &gs, &ds, &res, &stats, msg, sizeof msg);
    if (r != GLOW_OK) fail_msg("glow_render_ddish: %s", msg);
    assert_int_equal(stats.frames, frames);
    assert_true(stats.caches > 0 && stats.caches == stats.grid_caches + stats.lightmap_caches);
    assert_true(stats.rays >= (uint64_t)stats.caches * rays * frames);
    assert_true(stats.median_ms > 0.0 && stats.min_ms <= stats.median_ms);
    assert_int_equal(res.nonfinite_samples, 0);
    assert_true(res.lightmap_lookups > 0);
    const double m = mean_green(&res.indirect);
    if (rms) *rms = rms_from_one(&res.indirect);
    glow_render_result_free(&res);
    return m;
}

static void test_furnace_converges(void **state) {
    fixture *f = *state;
    double rms_small, rms_big;
    const double small = run(f, 2, 2, true, false, 0.0f, &rms_small);
    const double big = run(f, 16, 8, true, false, 0.0f, &rms_big);
    printf("furnace: 2 rays x 2 frames: mean %.4f rms %.4f; 16 x 8: mean %.4f rms %.4f (exact 1)\n", small, rms_small, big,
           rms_big);
    assert_true(fabs(big - 1.0) < 0.02);
    assert_true(fabs(small - 1.0) < 0.05);
    assert_true(rms_big < 0.5 * rms_small);
    /* no ramp, a = 0.5, 3 frames from 0: (1 - 0.5^3) of the converged value */
    const double blended = run(f, 16, 3, false, true, 0.5f, NULL);
    printf("furnace: a = 0.5, 3 frames from 0: mean %.4f (expected 0.875)\n", blended);
    assert_true(fabs(blended - 0.875) < 0.02);
}

static void test_direct_is_the_references(void **state) {
    fixture *f = *state;
    glow_render_settings st = {.width = 16, .height = 16, .spp = 2, .seed = 5, .threads = 2};
    glow_render_ddish_settings ds = {.rays = 2, .frames = 1};
    glow_render_result ref, dd;
    char msg[512] = "";
    assert_int_equal(glow_render_reference(f->furnace, &st, &ref, msg, sizeof msg), GLOW_OK);
    if (glow_render_ddish(f->furnace, f->bake, &st, NULL, &ds, &dd, NULL, msg, sizeof msg) != GLOW_OK)
        fail_msg("glow_render_ddish: %s", msg);
    assert_memory_equal(ref.direct.rgb, dd.direct.rgb, (size_t)16 * 16 * 3 * sizeof(float));
    glow_render_result_free(&ref);
    glow_render_result_free(&dd);
}

/* Glow's view after its light changes (glow_render_glow_settings.moved): the furnace's walls emit half
 * as much. The caches were converged at an incident radiance of 2; each feedback iteration after the
 * change gives L = 0.5 + ρ L_previous = 0.5 + 0.5 L: 1.5 after one (indirect ρ L = 0.75), 1.25 after
 * two (0.625), 1 when converged (0.5). */
static void test_glow_after_a_light_change(void **state) {
    fixture *f = *state;
    char path[256], msg[512] = "";
    snprintf(path, sizeof path, "%s/dim.json", f->dir);
    assert_int_equal(write_file(path, "{\"mesh\": \"builtin:furnace\", \"emission_scale\": 0.5, \"camera\": "
                                      "{\"position\": [0.3, 0.2, 0.5], \"target\": [-1, -0.3, -1], \"vfov_deg\": 90}}\n"),
                     0);
    glow_render_scene *dim = NULL;
    assert_int_equal(glow_render_scene_load(path, &dim, msg, sizeof msg), GLOW_OK);
    static const uint32_t its[] = {1, 2, 64};
    static const double expected[] = {0.75, 0.625, 0.5};
    for (int i = 0; i < 3; ++i) {
        glow_render_settings st = {.width = 16, .height = 16, .spp = 1, .seed = 3, .threads = 2};
        glow_render_glow_settings gs = {.indirect_only = true, .moved = dim, .moved_iterations = its[i]};
        glow_render_result res;
        if (glow_render_glow(f->furnace, f->bake, &st, &gs, &res, msg, sizeof msg) != GLOW_OK)
            fail_msg("glow_render_glow: %s", msg);
        const double m = mean_green(&res.indirect);
        printf("furnace dimmed to half, %u iterations after: indirect %.4f (expected %.4f)\n", its[i], m, expected[i]);
        assert_true(fabs(m / expected[i] - 1.0) < 0.02);
        glow_render_result_free(&res);
    }
    glow_render_glow_settings gs = {.indirect_only = true, .moved = f->floor, .moved_iterations = 1};
    glow_render_settings st = {.width = 8, .height = 8, .spp = 1, .threads = 1};
    glow_render_result res;
    assert_int_equal(glow_render_glow(f->furnace, f->bake, &st, &gs, &res, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "same mesh"));
    glow_render_scene_destroy(dim);
    remove(path);
}

static void test_bad_input(void **state) {
    fixture *f = *state;
    glow_render_settings st = {.width = 8, .height = 8, .spp = 1, .threads = 1};
    glow_render_result res;
    char msg[512] = "";
    glow_render_ddish_settings ds = {.rays = 1, .frames = 2, .hysteresis_set = true, .hysteresis = 1.0f};
    assert_int_equal(glow_render_ddish(f->furnace, f->bake, &st, NULL, &ds, &res, NULL, msg, sizeof msg),
                     GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "hysteresis"));
    ds = (glow_render_ddish_settings){.rays = 1, .frames = 2, .moved = f->furnace, .move_frame = 2};
    assert_int_equal(glow_render_ddish(f->furnace, f->bake, &st, NULL, &ds, &res, NULL, msg, sizeof msg),
                     GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "frame 2"));
    ds = (glow_render_ddish_settings){.rays = 1, .frames = 2, .moved = f->floor, .move_frame = 1};
    assert_int_equal(glow_render_ddish(f->furnace, f->bake, &st, NULL, &ds, &res, NULL, msg, sizeof msg),
                     GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "same mesh"));
    ds = (glow_render_ddish_settings){.rays = 1, .frames = 1};
    assert_int_not_equal(glow_render_ddish(f->floor, f->bake, &st, NULL, &ds, &res, NULL, msg, sizeof msg), GLOW_OK);
    assert_non_null(strstr(msg, "another mesh"));
    assert_int_not_equal(glow_render_ddish(f->furnace, "/nonexistent/x.glow", &st, NULL, &ds, &res, NULL, msg, sizeof msg),
                         GLOW_OK);
    assert_non_null(strstr(msg, "/nonexistent/x.glow"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_blend_by_hand),
        cmocka_unit_test(test_furnace_converges),
        cmocka_unit_test(test_direct_is_the_references),
        cmocka_unit_test(test_glow_after_a_light_change),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
