/* test_render_furnace.c — glow-render's library (tools/render/lib/glow_render.h) against answers known
 * without it:
 *   (a) the white furnace (builtin:furnace: a closed cube whose walls all emit L_e = 1 with albedo ρ):
 *       the radiance everywhere inside is L_e / (1 - ρ): 2 at ρ = 0.5, 10 at ρ = 0.9 (albedo_scale 1.8).
 *       The direct image is exactly L_e (every camera ray sees an emitting front face, and there are no
 *       host lights), the indirect image carries the rest. The mean over 32 x 32 pixels must be within
 *       1 % of the answer; the sample standard error of that mean, measured with this seed, is 0.27 %
 *       (ρ = 0.5, 16 spp) and about 0.25 % (ρ = 0.9, 128 spp), so 1 % is about 4 standard errors;
 *       the test also checks the error against 5 x the standard error it measures.
 *   (b) determinism: one thread and two give bit-identical images; another seed gives another image.
 *   (c) a point light and a sun over a floor (an OBJ written here): the direct image at the centre
 *       pixel is ρ/π (I cos θ / d² + E_sun cos θ_sun), computed here from the geometry, and the
 *       indirect image is exactly 0 (nothing else to bounce off, black sky).
 *   (d) Glow's view of the furnace (a low-quality bake made here) converges to the same 2 and 10
 *       within 2 % / 3 %, and its direct image equals the reference's bit for bit (same seed).
 *   (e) errors: a missing scene file, a bake made from another mesh, an unwritable output prefix
 *       (nothing is left behind), and the files written are read back. */
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
    char dir[256];
    char furnace_json[300], floor_json[300], bake[300];
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
    snprintf(f.dir, sizeof f.dir, "/tmp/glow_render_test_%d", (int)getpid());
    if (mkdir(f.dir, 0755) != 0) return -1;
    snprintf(f.furnace_json, sizeof f.furnace_json, "%s/furnace.json", f.dir);
    /* inside the cube [-1,1]^3, looking at a corner region (edges and corners are in view) */
    if (write_file(f.furnace_json,
                   "{\"mesh\": \"builtin:furnace\", \"camera\": {\"position\": [0.3, 0.2, 0.5], \"target\": [-1, -0.3, -1],"
                   " \"vfov_deg\": 90, \"width\": 32, \"height\": 32}}\n"))
        return -1;
    char path[300];
    snprintf(path, sizeof path, "%s/floor.mtl", f.dir);
    if (write_file(path, "newmtl grey\nKd 0.5 0.5 0.5\n")) return -1;
    snprintf(path, sizeof path, "%s/floor.obj", f.dir);
    /* a 10 x 10 m floor at y = 0 facing +y (counter-clockwise seen from above) */
    if (write_file(path, "mtllib floor.mtl\nv -5 0 -5\nv -5 0 5\nv 5 0 5\nv 5 0 -5\nusemtl grey\nf 1 2 3\nf 1 3 4\n")) return -1;
    snprintf(f.floor_json, sizeof f.floor_json, "%s/floor.json", f.dir);
    /* the camera looks at (1, 0, 0.5) with a 0.1 degree field: the centre pixel spans ~1 mm */
    if (write_file(f.floor_json,
                   "{\"mesh\": \"floor.obj\",\n"
                   " \"camera\": {\"position\": [0, 3, 0], \"target\": [1, 0, 0.5], \"up\": [0, 1, 0], \"vfov_deg\": 0.1,"
                   " \"width\": 9, \"height\": 9},\n"
                   " \"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": [2, 3, 4]},\n"
                   "            {\"type\": \"sun\", \"direction\": [0, -1, -1], \"irradiance\": [1, 0.5, 0.25]}]}\n"))
        return -1;
    char msg[512];
    if (glow_render_scene_load(f.furnace_json, &f.furnace, msg, sizeof msg) != GLOW_OK ||
        glow_render_scene_load(f.floor_json, &f.floor, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "scene load failed: %s\n", msg);
        return -1;
    }
    snprintf(f.bake, sizeof f.bake, "%s/furnace.glow", f.dir);
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 96, .bands = 3, .threads = 2, .seed = 1};
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
    char path[400];
    static const char *names[] = {"furnace.json", "floor.json", "floor.obj", "floor.mtl", "furnace.glow", "out.exr",
                                  "out_direct.exr", "out_indirect.exr", "out.png", "lit.json"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        snprintf(path, sizeof path, "%s/%s", f->dir, names[i]);
        remove(path);
    }
    rmdir(f->dir);
    return 0;
}

/* mean and standard error of the mean over the pixels (green channel; the furnace is grey) */
static void pixel_stats(const glow_eval_image *img, double *mean, double *stderr_mean) {
    size_t n = (size_t)img->width * img->height;
    double s = 0.0, s2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double v = img->rgb[3 * i + 1];
        s += v;
        s2 += v * v;
    }
    *mean = s / (double)n;
    double var = s2 / (double)n - *mean * *mean;
    *stderr_mean = sqrt(fmax(var, 0.0) / (double)n);
}

static void furnace_reference(fixture *f, float albedo_scale, uint32_t spp, double expect) {
    glow_render_settings st = {.spp = spp, .seed = 3, .threads = 2, .albedo_scale = albedo_scale};
    glow_render_result r;
    char msg[512];
    assert_int_equal(glow_render_reference(f->furnace, &st, &r, msg, sizeof msg), GLOW_OK);
    assert_int_equal(r.width, 32);
    assert_int_equal(r.height, 32);
    double mean, se;
    pixel_stats(&r.final, &mean, &se);
    printf("furnace reference rho %.2f, 32x32 x %u spp: mean %.5f (expected %.1f, %+.3f %%), std error %.3f %%, %.3f s, "
           "%.2f Mrays/s\n",
           0.5 * albedo_scale, spp, mean, expect, 100.0 * (mean / expect - 1.0), 100.0 * se / expect, r.seconds,
           r.mrays_per_s);
    assert_true(fabs(mean / expect - 1.0) < 0.01);
    assert_true(fabs(mean - expect) < 5.0 * se);
    assert_true(se / expect < 0.004); /* the noise the tolerance was chosen for */
    /* direct = the emission the camera sees: exactly 1, every pixel, every channel; final = direct + indirect */
    for (size_t i = 0; i < (size_t)32 * 32 * 3; ++i) {
        assert_true(r.direct.rgb[i] == 1.0f);
        assert_true(r.final.rgb[i] == r.direct.rgb[i] + r.indirect.rgb[i]);
        assert_true(isfinite(r.final.rgb[i]) && r.indirect.rgb[i] > 0.0f);
    }
    /* grey in, grey out */
    for (size_t i = 0; i < (size_t)32 * 32; ++i) {
        assert_true(r.final.rgb[3 * i] == r.final.rgb[3 * i + 1]);
        assert_true(r.final.rgb[3 * i + 2] == r.final.rgb[3 * i + 1]);
    }
    glow_render_result_free(&r);
}

static void test_furnace_reference_half(void **state) { furnace_reference(*state, 1.0f, 16, 2.0); }
static void test_furnace_reference_090(void **state) { furnace_reference(*state, 1.8f, 128, 10.0); }

static void test_determinism(void **state) {
    fixture *f = *state;
    char msg[512];
    glow_render_settings st = {.spp = 4, .seed = 42, .threads = 1, .width = 24, .height = 16};
    glow_render_result a, b, c;
    assert_int_equal(glow_render_reference(f->furnace, &st, &a, msg, sizeof msg), GLOW_OK);
    st.threads = 2;
    assert_int_equal(glow_render_reference(f->furnace, &st, &b, msg, sizeof msg), GLOW_OK);
    st.seed = 43;
    assert_int_equal(glow_render_reference(f->furnace, &st, &c, msg, sizeof msg), GLOW_OK);
    assert_int_equal(a.width, 24);
    assert_int_equal(a.height, 16);
    assert_int_equal(b.threads, 2);
    const size_t bytes = (size_t)24 * 16 * 3 * sizeof(float);
    assert_memory_equal(a.final.rgb, b.final.rgb, bytes);
    assert_memory_equal(a.direct.rgb, b.direct.rgb, bytes);
    assert_memory_equal(a.indirect.rgb, b.indirect.rgb, bytes);
    assert_true(memcmp(a.indirect.rgb, c.indirect.rgb, bytes) != 0);
    assert_int_equal(a.rays, b.rays);
    glow_render_result_free(&a);
    glow_render_result_free(&b);
    glow_render_result_free(&c);
}

static void test_point_and_sun_over_floor(void **state) {
    fixture *f = *state;
    char msg[512];
    glow_render_settings st = {.spp = 64, .seed = 1, .threads = 2};
    glow_render_result r;
    assert_int_equal(glow_render_reference(f->floor, &st, &r, msg, sizeof msg), GLOW_OK);
    /* the centre pixel sees q = (1, 0, 0.5): point light at (0, 1, 0): d² = 2.25, cos θ = 1/1.5;
       sun travelling (0, -1, -1)/√2: cos θ = 1/√2 */
    const double rho = 0.5, d2 = 2.25, cos_p = 1.0 / 1.5, cos_s = 1.0 / sqrt(2.0);
    const double I[3] = {2, 3, 4}, Es[3] = {1, 0.5, 0.25};
    const size_t centre = 4 * 9 + 4;
    for (int k = 0; k < 3; ++k) {
        double expect = rho / 3.14159265358979323846 * (I[k] * cos_p / d2 + Es[k] * cos_s);
        double got = r.direct.rgb[3 * centre + k];
        printf("floor: centre pixel channel %d: direct %.6f, expected %.6f (%+.4f %%)\n", k, got, expect,
               100.0 * (got / expect - 1.0));
        /* the pixel spans ~0.6 mm (~1 mm on the tilted floor): E changes by about ±0.1 % across it, linearly, so
           the mean of 64 jittered samples is within ~0.02 % of the centre value */
        assert_true(fabs(got / expect - 1.0) < 5e-4);
    }
    for (size_t i = 0; i < (size_t)9 * 9 * 3; ++i) assert_true(r.indirect.rgb[i] == 0.0f);
    glow_render_result_free(&r);
}

/* Irradiance probes (glow_render_irradiance): in the furnace every wall point receives E = π L with
 * L = L_e / (1 - ρ) = 2 (all of it emitted or reflected: nothing is excluded); under the floor scene's
 * point light and sun a point on the open floor receives nothing (the only other surface is the floor
 * itself), and the estimates are deterministic per seed and index. */
static void test_irradiance_probes(void **state) {
    fixture *f = *state;
    char msg[512];
    glow_render_settings st = {.seed = 3, .threads = 2};
    const float pts[4 * 6] = {-1, 0.1f, 0.2f, 1, 0, 0,     0.3f, -1, -0.7f, 0, 1, 0,
                              0.95f, 0.95f, 1, 0, 0, -1,  -0.2f, 1, 0.4f, 0, -1, 0};
    float e[4 * 3], e2[4 * 3];
    uint64_t rays = 0;
    assert_int_equal(glow_render_irradiance(f->furnace, NULL, 0, &st, pts, 4, 4096, 0, e, &rays, msg, sizeof msg), GLOW_OK);
    assert_true(rays > 4 * 4096);
    for (int i = 0; i < 4; ++i) {
        printf("furnace probe %d: E = %.4f (expected %.4f)\n", i, e[3 * i], 2.0 * 3.14159265358979323846);
        /* 4096 paths, each an unbiased estimate with a relative spread of about 0.6 (path length): ~1 % */
        assert_true(fabs(e[3 * i] / (2.0 * 3.14159265358979323846) - 1.0) < 0.04);
    }
    assert_int_equal(glow_render_irradiance(f->furnace, NULL, 0, &st, pts, 4, 4096, 0, e2, NULL, msg, sizeof msg), GLOW_OK);
    assert_memory_equal(e, e2, sizeof e);
    st.threads = 1;
    assert_int_equal(glow_render_irradiance(f->furnace, NULL, 0, &st, pts, 4, 4096, 0, e2, NULL, msg, sizeof msg), GLOW_OK);
    assert_memory_equal(e, e2, sizeof e);
    const float floor_pt[6] = {1, 0, 0.5f, 0, 1, 0};
    assert_int_equal(glow_render_irradiance(f->floor, NULL, 0, &st, floor_pt, 1, 256, 0, e, NULL, msg, sizeof msg), GLOW_OK);
    assert_true(e[0] == 0.0f && e[1] == 0.0f && e[2] == 0.0f);
    assert_int_equal(glow_render_irradiance(f->floor, NULL, 0, &st, floor_pt, 1, 0, 0, e, NULL, msg, sizeof msg),
                     GLOW_ERROR_INVALID_ARGUMENT);
}

static void furnace_glow(fixture *f, float albedo_scale, double expect, double tol) {
    char msg[512];
    glow_render_settings st = {.spp = 4, .seed = 9, .threads = 2, .albedo_scale = albedo_scale};
    glow_render_glow_settings gs = {.bounce_iterations = 192};
    glow_render_result g, ref;
    assert_int_equal(glow_render_glow(f->furnace, f->bake, &st, &gs, &g, msg, sizeof msg), GLOW_OK);
    assert_int_equal(glow_render_reference(f->furnace, &st, &ref, msg, sizeof msg), GLOW_OK);
    double mean, se;
    pixel_stats(&g.final, &mean, &se);
    printf("furnace glow view rho %.2f: mean %.5f (expected %.1f, %+.3f %%), solve %.3f s; first hits: lightmap %llu, "
           "grid %llu, none %llu\n",
           0.5 * albedo_scale, mean, expect, 100.0 * (mean / expect - 1.0), g.solve_seconds,
           (unsigned long long)g.lightmap_lookups, (unsigned long long)g.grid_lookups,
           (unsigned long long)g.missed_lookups);
    assert_true(fabs(mean / expect - 1.0) < tol);
    assert_int_equal(g.missed_lookups, 0);
    assert_true(g.lightmap_lookups > 0);
    const size_t bytes = (size_t)32 * 32 * 3 * sizeof(float);
    assert_memory_equal(g.direct.rgb, ref.direct.rgb, bytes); /* same seed: the same direct term, bit for bit */
    glow_render_result_free(&g);
    glow_render_result_free(&ref);
}

static void test_furnace_glow_half(void **state) { furnace_glow(*state, 1.0f, 2.0, 0.02); }
static void test_furnace_glow_090(void **state) { furnace_glow(*state, 1.8f, 10.0, 0.03); }

static void test_glow_direct_matches_with_lights(void **state) {
    /* with host lights the direct term has shadow rays and a first-bounce sky ray: still identical */
    fixture *f = *state;
    char msg[512];
    glow_render_scene *s;
    char path[300];
    snprintf(path, sizeof path, "%s/lit.json", f->dir);
    assert_int_equal(write_file(path,
                                "{\"mesh\": \"builtin:furnace\", \"camera\": {\"position\": [0.3, 0.2, 0.5], \"target\": [-1, -0.3, -1],"
                                " \"vfov_deg\": 90, \"width\": 16, \"height\": 16}, \"environment\": [0.1, 0.2, 0.3],"
                                " \"lights\": [{\"type\": \"spot\", \"position\": [0, 0.9, 0], \"direction\": [0, -1, 0.2],"
                                " \"intensity\": [3, 2, 1], \"outer_deg\": 50, \"inner_deg\": 20}], \"emission_scale\": 0.5}\n"),
                     0);
    assert_int_equal(glow_render_scene_load(path, &s, msg, sizeof msg), GLOW_OK);
    glow_render_settings st = {.spp = 2, .seed = 5, .threads = 2};
    glow_render_glow_settings gs = {.bounce_iterations = 8, .sky_rays = 16};
    glow_render_result g, ref;
    assert_int_equal(glow_render_glow(s, f->bake, &st, &gs, &g, msg, sizeof msg), GLOW_OK);
    assert_int_equal(glow_render_reference(s, &st, &ref, msg, sizeof msg), GLOW_OK);
    assert_memory_equal(g.direct.rgb, ref.direct.rgb, (size_t)16 * 16 * 3 * sizeof(float));
    assert_true(ref.mean_direct[0] > 0.5); /* the emission 0.5 plus some spot light */
    glow_render_result_free(&g);
    glow_render_result_free(&ref);
    glow_render_scene_destroy(s);
}

static void test_errors_and_files(void **state) {
    fixture *f = *state;
    char msg[512], path[400];
    glow_render_scene *s = (glow_render_scene *)1;
    snprintf(path, sizeof path, "%s/missing.json", f->dir);
    assert_int_equal(glow_render_scene_load(path, &s, msg, sizeof msg), GLOW_ERROR_IO);
    assert_null(s);
    assert_non_null(strstr(msg, "missing.json"));
    /* the furnace bake does not fit the floor's mesh */
    glow_render_settings st = {.spp = 1, .seed = 1};
    glow_render_result r;
    assert_int_equal(glow_render_glow(f->floor, f->bake, &st, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    printf("expected error: %s\n", msg);
    assert_non_null(strstr(msg, "furnace.glow"));
    assert_non_null(strstr(msg, "another mesh"));
    assert_null(r.final.rgb);
    snprintf(path, sizeof path, "%s/nothing-here.glow", f->dir);
    assert_int_equal(glow_render_glow(f->furnace, path, &st, NULL, &r, msg, sizeof msg), GLOW_ERROR_IO);
    assert_non_null(strstr(msg, "nothing-here.glow"));
    /* write, read back */
    assert_int_equal(glow_render_reference(f->floor, &st, &r, msg, sizeof msg), GLOW_OK);
    snprintf(path, sizeof path, "%s/out", f->dir);
    assert_int_equal(glow_render_write(&r, path, 1.0f, msg, sizeof msg), GLOW_OK);
    glow_eval_image back;
    snprintf(path, sizeof path, "%s/out_direct.exr", f->dir);
    assert_int_equal(glow_eval_read_exr(path, &back, msg, sizeof msg), GLOW_OK);
    assert_int_equal(back.width, 9);
    assert_memory_equal(back.rgb, r.direct.rgb, (size_t)9 * 9 * 3 * sizeof(float));
    glow_eval_image_free(&back);
    snprintf(path, sizeof path, "%s/out.png", f->dir);
    assert_int_equal(access(path, F_OK), 0);
    /* an output folder that does not exist: an error, and nothing written */
    snprintf(path, sizeof path, "%s/no-such-dir/out", f->dir);
    assert_int_not_equal(glow_render_write(&r, path, 1.0f, msg, sizeof msg), GLOW_OK);
    snprintf(path, sizeof path, "%s/no-such-dir", f->dir);
    assert_int_not_equal(access(path, F_OK), 0);
    /* bad settings */
    st.width = 8; /* without a height */
    glow_render_result_free(&r);
    assert_int_equal(glow_render_reference(f->floor, &st, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    st.width = 0;
    st.albedo_scale = NAN;
    assert_int_equal(glow_render_reference(f->floor, &st, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    glow_render_result_free(&r);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_furnace_reference_half), cmocka_unit_test(test_furnace_reference_090),
        cmocka_unit_test(test_determinism),            cmocka_unit_test(test_point_and_sun_over_floor),
        cmocka_unit_test(test_furnace_glow_half),      cmocka_unit_test(test_furnace_glow_090),
        cmocka_unit_test(test_glow_direct_matches_with_lights), cmocka_unit_test(test_errors_and_files),
        cmocka_unit_test(test_irradiance_probes)};
    return cmocka_run_group_tests(tests, setup, teardown);
}
