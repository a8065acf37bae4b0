/* test_sample_screenshot.c — what the GL samples put on screen is Glow's indirect light: the sample
 * renderer (samples/common/sample_gl.h) draws the built-in Cornell box and a sphere from the GL
 * backend's textures (glow_gl.h) in its `indirect` view; the image is read back (float target) with
 * each pixel's lightmap uv, material, normal and position (the renderer's aux targets), and every
 * covered pixel is shaded again on the CPU from the CPU system's outputs:
 *     bake triangles:  albedo · (glow_shade_sh(glow_sample_lightmap(uv), n, 1) + glow_sample_lightmap_detail(uv))
 *     the sphere:      albedo · glow_shade_sh(glow_sample_grid_oriented(p, n), n, 1)
 * Both systems are made from the same bake and lit by the same direct light (an analytic point light
 * pushed to the CPU system with glow_system_set_surfel_irradiance; the GL system has no hook and
 * uploads it), and updated the same number of times.
 *
 * TOLERANCE: relative RMSE over the covered pixels' channels, sqrt(Σ (gpu - cpu)² / Σ cpu²) < 1e-3,
 * per group (triangles, sphere). Why 1e-3: the GPU and CPU cache SH agree to about 1e-6 relative
 * (tests/gpu/test_gl_agreement.c: the same sums in another order), and the shading is the same float
 * maths in GLSL and C (SH basis, bilinear/trilinear weights), so the images should agree to ~1e-5
 * (measured on llvmpipe: 2e-7 on the triangles, 1.4e-7 on the sphere, max abs diff 7e-7); 1e-3 leaves two orders of magnitude for rounding while one bounce more or less (a few percent of
 * the indirect light here: measured 5e-2) fails by more than an order of magnitude — checked below: the GPU image
 * after N updates against the CPU after N + 1 must NOT pass. The sphere's grid lookup picks its
 * corner visibility by octant (t >= 0.5): a pixel on an octant boundary may fall on different sides
 * in GLSL and C, a legitimate difference that shows in the max abs diff, not in the RMSE.
 * Also: the final view (emission + indirect, no direct light without a hook) with per-material
 * emission/albedo scales and a lower bounce intensity, which the renderer reads from the CPU system.
 * Exits 77 (skipped) without a GL 4.5 context. */
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
#include "glow/glow_backend.h"
#include "glow/glow_gl.h"
#include "glow/glow_glctx.h"
#include "glow/glow_precompute.h"

#include "../../samples/common/sample_gl.h"

#define W 160
#define H 120

static glow_glctx *g_gl;
static char g_bake_path[256];

typedef struct fixture {
    glow_context *ctx;
    glow_bake *bake;
    glow_system *cpu;
    glow_gl_system *gpu;
    sample_gl r;
} fixture;

static void logger(void *user, glow_log_level level, glow_result code, const char *msg, const char *file, int line) {
    (void)user, (void)code, (void)file, (void)line;
    if (level <= GLOW_LOG_WARNING) fprintf(stderr, "glow: %s\n", msg);
}

/* the direct light: an unshadowed point light (W/sr), pushed to the CPU system */
static void push_light(glow_system *sys) {
    static const float LP[3] = {0.1f, 1.6f, 0.2f}, LI[3] = {2.0f, 1.6f, 1.2f};
    glow_surfel_view v;
    assert_int_equal(glow_system_get_surfels(sys, &v), GLOW_OK);
    float *e = malloc((size_t)v.count * 3 * sizeof *e);
    assert_non_null(e);
    for (uint32_t i = 0; i < v.count; i++) {
        const float *p = v.positions + 4 * (size_t)i, *n = v.normals + 4 * (size_t)i;
        float d[3] = {LP[0] - p[0], LP[1] - p[1], LP[2] - p[2]};
        float r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        float c = fmaxf((n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / sqrtf(r2), 0.0f);
        for (int k = 0; k < 3; k++) e[3 * (size_t)i + (size_t)k] = LI[k] * c / r2;
    }
    assert_int_equal(glow_system_set_surfel_irradiance(sys, 0, v.count, e), GLOW_OK);
    free(e);
}

static void make_fixture(fixture *f) {
    memset(f, 0, sizeof *f);
    glow_context_desc cd = {.api_version = GLOW_VERSION, .tasks = {.worker_count = 2}, .logger = {logger, NULL}};
    assert_int_equal(glow_context_create(&cd, &f->ctx), GLOW_OK);
    assert_int_equal(glow_bake_load_file(f->ctx, g_bake_path, &f->bake), GLOW_OK);
    assert_int_equal(glow_system_create(f->ctx, &(glow_system_desc){.bake = f->bake, .label = "cpu"}, &f->cpu), GLOW_OK);
    glow_gl_desc gd = {.system = f->cpu, .get_proc_address = glow_glctx_get_proc_address(g_gl), .label = "gpu",
                       .logger = {logger, NULL}};
    assert_int_equal(glow_gl_system_create(&gd, &f->gpu), GLOW_OK);
    push_light(f->cpu);
    sample_gl_desc rd = {.loader = glow_glctx_get_proc_address(g_gl), .bake = f->bake, .system = f->cpu,
                         .outputs = glow_gl_system_outputs(f->gpu), .width = W, .height = H, .aux_targets = true};
    if (sample_gl_create(&f->r, &rd) != 0) fail_msg("sample_gl_create: %s", f->r.error);
}

static void free_fixture(fixture *f) {
    sample_gl_destroy(&f->r);
    glow_gl_system_destroy(f->gpu);
    glow_system_destroy(f->cpu);
    glow_bake_destroy(f->bake);
    glow_context_destroy(f->ctx);
}

static void update_both(fixture *f, int n) {
    for (int i = 0; i < n; i++) {
        assert_int_equal(glow_system_update(f->cpu, NULL), GLOW_OK);
        assert_int_equal(glow_gl_system_update(f->gpu, NULL), GLOW_OK);
    }
}

/* the camera of scenes/cornell-builtin-*.json, and a sphere in the room */
static const glow_scene_camera CAMERA = {.position = {0, 1.0f, 0.98f}, .target = {0, 1.0f, -1.0f}, .up = {0, 1, 0},
                                         .vfov_deg = 54.0f, .width = W, .height = H};
static const sample_gl_sphere SPHERE = {.center = {0.25f, 1.1f, 0.1f}, .radius = 0.22f, .albedo = {0.8f, 0.6f, 0.4f}};

typedef struct image {
    float hdr[W * H * 4], aux0[W * H * 4], aux1[W * H * 4], aux2[W * H * 4];
} image;

/* looking up at the lamp (emission in the final view) */
static const glow_scene_camera CAMERA_UP = {.position = {0, 1.0f, 0.98f}, .target = {0, 1.9f, -0.6f}, .up = {0, 1, 0},
                                            .vfov_deg = 54.0f, .width = W, .height = H};

static void render(fixture *f, int view, const glow_scene_camera *camera, image *img) {
    sample_gl_frame fr = {.view = view, .direct = true, .indirect = true, .exposure = 1.0f, .camera = camera,
                          .spheres = &SPHERE, .sphere_count = 1};
    if (sample_gl_draw(&f->r, &fr) != 0) fail_msg("sample_gl_draw: %s", f->r.error);
    assert_int_equal(sample_gl_read(&f->r, 1, img->hdr), 0);
    assert_int_equal(sample_gl_read(&f->r, 2, img->aux0), 0);
    assert_int_equal(sample_gl_read(&f->r, 3, img->aux1), 0);
    assert_int_equal(sample_gl_read(&f->r, 4, img->aux2), 0);
}

typedef struct errors {
    uint32_t pixels[2];           /* covered: [0] bake triangles, [1] sphere */
    double rel_rmse[2], max_abs[2], max_ref[2];
} errors;

/* Shades every covered pixel on the CPU from `sys`'s outputs and compares. With `final`: the final
 * view without direct light, emission (front faces, scaled) + max(indirect, 0). */
static errors compare(const fixture *f, const glow_system *sys, const image *img, bool final) {
    const glow_cache_outputs *o = glow_system_outputs(sys);
    glow_solver_tables t;
    glow_system_get_solver_tables(sys, &t);
    glow_system_params prm;
    glow_system_get_params(sys, &prm);
    double se[2] = {0, 0}, sr[2] = {0, 0};
    errors e = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};
    float coeffs[3 * GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS];
    for (size_t i = 0; i < (size_t)W * H; i++) {
        const float *a0 = img->aux0 + 4 * i, *a1 = img->aux1 + 4 * i, *a2 = img->aux2 + 4 * i, *g = img->hdr + 4 * i;
        int kind = (int)lrintf(a0[3]);
        if (kind != 1 && kind != 2) continue;
        const int grp = kind - 1;
        float albedo[3], emission[3] = {0, 0, 0}, rgb[3] = {0, 0, 0};
        if (kind == 1) {
            uint32_t m = (uint32_t)lrintf(a0[2]);
            assert_true(m < t.material_count);
            glow_material_info mi;
            assert_int_equal(glow_bake_get_material(f->bake, m, &mi), GLOW_OK);
            for (int c = 0; c < 3; c++) {
                albedo[c] = fminf(mi.albedo[c] * t.material_albedo_scale[3 * m + (uint32_t)c], 0.999f);
                emission[c] = mi.emission[c] * t.material_emission_scale[3 * m + (uint32_t)c] * prm.emission_scale;
            }
            if (glow_sample_lightmap(o, a0[0], a0[1], coeffs) == GLOW_OK) {
                glow_shade_sh(coeffs, o->sh_bands_luma, o->sh_bands_chroma, a1, 1.0f, rgb);
                float det[3];
                assert_non_null(o->lightmap_detail); /* the fixture's bake has a lightmap detail: it is drawn too */
                if (glow_sample_lightmap_detail(o, a0[0], a0[1], det) == GLOW_OK)
                    for (int c = 0; c < 3; c++) rgb[c] += det[c];
            }
        } else {
            memcpy(albedo, SPHERE.albedo, sizeof albedo);
            if (glow_sample_grid_oriented(o, a2, a1, coeffs) == GLOW_OK)
                glow_shade_sh(coeffs, o->sh_bands_luma, o->sh_bands_chroma, a1, 1.0f, rgb);
        }
        e.pixels[grp]++;
        for (int c = 0; c < 3; c++) {
            double ref = albedo[c] * rgb[c];
            if (final) ref = emission[c] + fmax(ref, 0.0);
            double d = (double)g[c] - ref;
            se[grp] += d * d;
            sr[grp] += ref * ref;
            e.max_abs[grp] = fmax(e.max_abs[grp], fabs(d));
            e.max_ref[grp] = fmax(e.max_ref[grp], fabs(ref));
        }
    }
    for (int k = 0; k < 2; k++) e.rel_rmse[k] = sr[k] > 0.0 ? sqrt(se[k] / sr[k]) : INFINITY;
    return e;
}

static void print_errors(const char *what, const errors *e) {
    static const char *const groups[2] = {"triangles (lightmap)", "sphere (grid)"};
    for (int k = 0; k < 2; k++)
        printf("  %-38s %-22s %5u px: rel RMSE %.3e, max |diff| %.3e (max value %.4g W/(m2 sr))\n", what, groups[k],
               e->pixels[k], e->rel_rmse[k], e->max_abs[k], e->max_ref[k]);
}

#define TOLERANCE 1e-3

static void test_indirect_view(void **state) {
    (void)state;
    fixture f;
    make_fixture(&f);
    static image img;
    update_both(&f, 4);
    render(&f, SAMPLE_VIEW_INDIRECT, &CAMERA, &img);
    errors e = compare(&f, f.cpu, &img, false);
    print_errors("indirect view, 4 bounce updates", &e);
    assert_true(e.pixels[0] > W * H / 2); /* the room fills the image */
    assert_true(e.pixels[1] > 200);       /* and the sphere is in it */
    assert_true(e.max_ref[0] > 1e-3 && e.max_ref[1] > 1e-3); /* lit: zeros prove nothing */
    assert_true(e.rel_rmse[0] < TOLERANCE);
    assert_true(e.rel_rmse[1] < TOLERANCE);

    /* The comparison can fail: the same GPU image against the CPU one bounce further. A second CPU
     * system takes 5 updates (glow_system outputs are per system, so f.cpu stays at 4). */
    glow_system *cpu5 = NULL;
    assert_int_equal(glow_system_create(f.ctx, &(glow_system_desc){.bake = f.bake, .label = "cpu5"}, &cpu5), GLOW_OK);
    push_light(cpu5);
    for (int i = 0; i < 5; i++) assert_int_equal(glow_system_update(cpu5, NULL), GLOW_OK);
    errors wrong = compare(&f, cpu5, &img, false);
    print_errors("GPU after 4 vs CPU after 5 (must fail)", &wrong);
    assert_true(wrong.rel_rmse[0] > 10 * TOLERANCE);
    assert_true(wrong.rel_rmse[1] > 10 * TOLERANCE);
    glow_system_destroy(cpu5);

    /* one update further, both agree again */
    update_both(&f, 1);
    render(&f, SAMPLE_VIEW_INDIRECT, &CAMERA, &img);
    e = compare(&f, f.cpu, &img, false);
    print_errors("indirect view, 5 bounce updates", &e);
    assert_true(e.rel_rmse[0] < TOLERANCE && e.rel_rmse[1] < TOLERANCE);
    free_fixture(&f);
}

/* Artist controls set on the CPU system reach both the GL system (next update) and the renderer. */
static void test_final_view_controls(void **state) {
    (void)state;
    fixture f;
    make_fixture(&f);
    static image img;
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(f.bake, &info), GLOW_OK);
    uint32_t lamp = UINT32_MAX, left = UINT32_MAX;
    for (uint32_t m = 0; m < info.material_count; m++) {
        glow_material_info mi;
        assert_int_equal(glow_bake_get_material(f.bake, m, &mi), GLOW_OK);
        if (!strcmp(mi.name, "light")) lamp = m;
        if (!strcmp(mi.name, "left")) left = m;
    }
    assert_true(lamp != UINT32_MAX && left != UINT32_MAX);
    assert_int_equal(glow_system_set_material(f.cpu, lamp, (float[3]){0.5f, 1.0f, 2.0f}, NULL), GLOW_OK);
    assert_int_equal(glow_system_set_material(f.cpu, left, NULL, (float[3]){0.5f, 1.0f, 1.0f}), GLOW_OK);
    glow_system_params p = {.bounce_intensity = 0.5f, .emission_scale = 0.7f, .bounce_iterations = 2};
    assert_int_equal(glow_system_set_params(f.cpu, &p), GLOW_OK);
    update_both(&f, 3);
    render(&f, SAMPLE_VIEW_FINAL, &CAMERA_UP, &img);
    errors e = compare(&f, f.cpu, &img, true);
    print_errors("final view (no direct), scaled materials", &e);
    assert_true(e.pixels[0] > W * H / 2 && e.pixels[1] > 100);
    assert_true(e.max_ref[0] > 3.0); /* the lamp is in view: 17 W/(m2 sr) red x 0.5 x 0.7 */
    assert_true(e.rel_rmse[0] < TOLERANCE);
    assert_true(e.rel_rmse[1] < TOLERANCE);
    free_fixture(&f);
}

/* The charts view marks texels without a cache in magenta and nothing else: every pixel that is
 * magenta has lightmap_valid == 0 at its texel on the CPU side (lightmap_map empty), and the
 * display target decodes. */
static void test_charts_view(void **state) {
    (void)state;
    fixture f;
    make_fixture(&f);
    update_both(&f, 1);
    sample_gl_frame fr = {.view = SAMPLE_VIEW_CHARTS, .exposure = 1.0f, .camera = &CAMERA};
    if (sample_gl_draw(&f.r, &fr) != 0) fail_msg("sample_gl_draw: %s", f.r.error);
    static uint8_t rgba[W * H * 4];
    static float aux0[W * H * 4];
    assert_int_equal(sample_gl_read(&f.r, 0, rgba), 0);
    assert_int_equal(sample_gl_read(&f.r, 2, aux0), 0);
    const glow_cache_outputs *o = glow_system_outputs(f.cpu);
    uint32_t magenta = 0, covered = 0, mismatched = 0;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        if (lrintf(aux0[4 * i + 3]) != 1) continue;
        covered++;
        uint32_t x = (uint32_t)fminf(floorf(aux0[4 * i] * (float)o->lightmap_width), (float)o->lightmap_width - 1);
        uint32_t y = (uint32_t)fminf(floorf(aux0[4 * i + 1] * (float)o->lightmap_height), (float)o->lightmap_height - 1);
        bool empty = o->lightmap_map[(size_t)y * o->lightmap_width + x] == UINT32_MAX;
        bool is_magenta = rgba[4 * i] == 255 && rgba[4 * i + 1] == 0 && rgba[4 * i + 2] == 255;
        magenta += is_magenta;
        mismatched += empty != is_magenta;
    }
    printf("  charts view: %u covered pixels, %u magenta (texels without a cache), %u disagree with lightmap_map\n",
           covered, magenta, mismatched);
    assert_true(covered > W * H / 2);
    assert_true(magenta < covered / 4);
    assert_true(mismatched <= covered / 1000 + 2); /* a texel boundary may round differently */
    free_fixture(&f);
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
    snprintf(g_bake_path, sizeof g_bake_path, "/tmp/glow_sample_screenshot_%d.glow", (int)getpid());
    glow_pc_settings st = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 96, .bands = 3, .threads = 2, .seed = 1};
    glow_pc_stats stats;
    if (glow_pc_bake("builtin:cornell", g_bake_path, &st, &stats) != GLOW_OK) {
        fprintf(stderr, "bake of builtin:cornell failed: %s\n", stats.error);
        glow_glctx_destroy(g_gl);
        return 1;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_indirect_view),
        cmocka_unit_test(test_final_view_controls),
        cmocka_unit_test(test_charts_view),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    remove(g_bake_path);
    glow_glctx_destroy(g_gl);
    return rc;
}
