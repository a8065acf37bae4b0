/* test_render_finite.c — glow-render's files hold the images it rendered: every pixel finite and
 * bit-identical after glow_render_write and glow_eval_read_exr.
 *
 * Regression: the shared Cornell box at 64 x 64, 64 spp, seeds 2 and 6 (also 15, 23) rendered finite
 * images, but PREFIX.exr and PREFIX_indirect.exr read back with NaN and ±3e38 in rows 32-47: OpenEXR
 * 3.1 kept a ZIP chunk's deflate stream that came out exactly as long as the raw chunk, and readers
 * take a chunk of that size for raw floats (tools/eval/image.c, exr_compress_or_store_raw;
 * tests/eval/test_image_io.c reaches the case on purpose). Skipped without ../shared/scenes. */
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

#include "glow_render.h"

static const char *const cornell = GLOW_SHARED_DIR "/scenes/cornell-box/cornell.json";

static bool file_exists(const char *p) {
    FILE *f = fopen(p, "rb");
    if (!f) return false;
    fclose(f);
    return true;
}

static void assert_all_finite(const glow_eval_image *img, const char *what) {
    const size_t n = (size_t)img->width * img->height * 3;
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(img->rgb[i]))
            fail_msg("%s: pixel (%zu, %zu) channel %zu is %g", what, i / 3 % img->width, i / 3 / img->width, i % 3,
                     (double)img->rgb[i]);
}

static void test_cornell_files_finite(void **state) {
    (void)state;
    if (!file_exists(cornell)) skip();
    char msg[1024] = "";
    glow_render_scene *sc = NULL;
    assert_int_equal(glow_render_scene_load(cornell, &sc, msg, sizeof msg), GLOW_OK);
    char dir[128];
    snprintf(dir, sizeof dir, "/tmp/glow_render_finite_%d", (int)getpid());
    assert_int_equal(mkdir(dir, 0755), 0);
    static const uint64_t seeds[] = {2, 6};
    static const char *const suffix[3] = {".exr", "_direct.exr", "_indirect.exr"};
    for (size_t s = 0; s < sizeof seeds / sizeof seeds[0]; ++s) {
        glow_render_settings st = {.width = 64, .height = 64, .spp = 64, .seed = seeds[s], .threads = 2};
        glow_render_result res;
        assert_int_equal(glow_render_reference(sc, &st, &res, msg, sizeof msg), GLOW_OK);
        assert_int_equal(res.nonfinite_samples, 0);
        const glow_eval_image *img[3] = {&res.final, &res.direct, &res.indirect};
        for (int i = 0; i < 3; ++i) assert_all_finite(img[i], suffix[i]);
        char prefix[160];
        snprintf(prefix, sizeof prefix, "%s/seed%llu", dir, (unsigned long long)seeds[s]);
        assert_int_equal(glow_render_write(&res, prefix, 1.0f, msg, sizeof msg), GLOW_OK);
        for (int i = 0; i < 3; ++i) {
            char path[200];
            snprintf(path, sizeof path, "%s%s", prefix, suffix[i]);
            glow_eval_image back;
            assert_int_equal(glow_eval_read_exr(path, &back, msg, sizeof msg), GLOW_OK);
            assert_int_equal(back.width, 64);
            assert_int_equal(back.height, 64);
            assert_all_finite(&back, path);
            assert_memory_equal(back.rgb, img[i]->rgb, sizeof(float) * 64 * 64 * 3);
            glow_eval_image_free(&back);
            remove(path);
        }
        char png[200];
        snprintf(png, sizeof png, "%s.png", prefix);
        remove(png);
        glow_render_result_free(&res);
    }
    assert_int_equal(rmdir(dir), 0);
    glow_render_scene_destroy(sc);
}

/* An emission texture (map_Ke) in the path tracer: under a screen whose left half is white and right
 * half black, the floor under the white half receives more light than the floor under the black half
 * (with a constant emission the two points would be symmetric). */
static void test_emission_texture_render(void **state) {
    (void)state;
    char msg[512];
    glow_render_scene *sc = NULL;
    assert_int_equal(glow_render_scene_load(GLOW_TEST_DATA_DIR "/scenes/emissive/emissive.json", &sc, msg, sizeof msg), GLOW_OK);
    glow_render_settings st = {.seed = 5, .threads = 2, .max_depth = 1};
    const float pts[12] = {0.3f, 0.01f, 1.0f, 0, 1, 0, 1.7f, 0.01f, 1.0f, 0, 1, 0};
    float e[6];
    assert_int_equal(glow_render_irradiance(sc, NULL, 0, &st, pts, 2, 2048, 0, e, NULL, msg, sizeof msg), GLOW_OK);
    printf("emission texture: E under the white half %.4f, under the black half %.4f W/m2\n", e[0], e[3]);
    assert_true(e[3] > 0.0f && e[0] > 1.5f * e[3]);
    glow_render_scene_destroy(sc);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_emission_texture_render),
        cmocka_unit_test(test_cornell_files_finite)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
