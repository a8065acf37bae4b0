/* test_render_envmap.c — glow-render with a scene "environment_map" (docs/envmap.md), against answers
 * known without it:
 *   (a) a constant map (× scale 2) renders the same image as the same constant `environment`, and so
 *       does half the constant plus the map × 1 (the two add): a floor with a box under the sky, camera
 *       rays that escape, bounces between box and floor; the per-pixel difference has mean 0 within 4
 *       standard errors in every channel;
 *   (b) a sunny map (glow_eval_skymap: a 5° sun of 12 W/m² at 50° elevation) over a Lambertian floor
 *       seen from above: every pixel's expected radiance is ρ/π · Σ_upper-hemisphere L_texel ∫ cos θ dω
 *       (exact for the piecewise-constant map). Importance sampling + MIS (the default) and BSDF sampling
 *       alone (envmap_bsdf_only) both hit it within 4 standard errors, and MIS's pixel variance is
 *       below a quarter of BSDF sampling's (about 1 % of it, measured);
 *   (c) the same with a GGX layer (roughness 0.3): MIS and BSDF-only agree within 4 combined standard
 *       errors, MIS with less variance;
 *   (d) Glow's view: its direct image with a map equals the reference's bit for bit (same seed), and its
 *       --indirect-only image equals its full view's indirect (the map's random numbers keep the streams
 *       aligned);
 *   (e) errors: a scene whose environment_map is missing or not an EXR fails with a message naming the
 *       scene and the image;
 *   (f) Glow's caches carry the map's light: a box on a floor under the sunny map, Glow's view (the host
 *       lit by the map's sun as a shadowed sun light and the rest as SH through the bake's sky transfer)
 *       has the reference's mean indirect light within 12 % per channel (without the map's light in the
 *       host, its indirect would be 0: nothing else lights the scene). */
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
#include "glow_envmap.h"
#include "glow_render.h"

#define PI_D 3.14159265358979323846

typedef struct fixture {
    char dir[256];
} fixture;
static fixture F;

static char *at(const char *name) {
    static char buf[8][400];
    static int k;
    k = (k + 1) % 8;
    snprintf(buf[k], sizeof buf[k], "%s/%s", F.dir, name);
    return buf[k];
}

static int write_file(const char *name, const char *text) {
    FILE *f = fopen(at(name), "w");
    if (!f) return -1;
    fputs(text, f);
    return fclose(f);
}

#define PLANE "v -5 0 -5\nv -5 0 5\nv 5 0 5\nv 5 0 -5\nusemtl grey\nf 1 2 3\nf 1 3 4\n"
#define CAM_TOP "\"camera\": {\"position\": [0, 3, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1], \"vfov_deg\": 20, " \
                "\"width\": 64, \"height\": 64}"
#define CAM_BOX "\"camera\": {\"position\": [2.5, 2, 3], \"target\": [0, 0.4, 0], \"vfov_deg\": 50, \"width\": 48, \"height\": 32}"

static int setup(void **state) {
    snprintf(F.dir, sizeof F.dir, "/tmp/glow_render_envmap_%d", (int)getpid());
    if (mkdir(F.dir, 0755) != 0) return -1;
    if (write_file("floor.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl box\nKd 0.7 0.6 0.5\n")) return -1;
    if (write_file("plane.obj", "mtllib floor.mtl\n" PLANE)) return -1;
    /* the floor and a unit box on it (outward, counter-clockwise faces; no bottom) */
    if (write_file("box.obj", "mtllib floor.mtl\n" PLANE
                              "v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\nv -0.5 1 -0.5\nv 0.5 1 -0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n"
                              "usemtl box\nf 9 12 11\nf 9 11 10\nf 6 10 11\nf 6 11 7\nf 5 8 12\nf 5 12 9\nf 8 7 11\n"
                              "f 8 11 12\nf 5 9 10\nf 5 10 6\n"))
        return -1;
    if (write_file("box_env.json", "{\"mesh\": \"box.obj\", " CAM_BOX ", \"environment\": [0.3, 0.4, 0.5]}\n") ||
        write_file("box_map.json",
                   "{\"mesh\": \"box.obj\", " CAM_BOX ", \"environment_map\": {\"path\": \"const.exr\", \"scale\": 2}}\n") ||
        write_file("box_both.json", "{\"mesh\": \"box.obj\", " CAM_BOX ", \"environment\": [0.15, 0.2, 0.25],"
                                    " \"environment_map\": {\"path\": \"const.exr\"}}\n") ||
        write_file("box_sun.json", "{\"mesh\": \"box.obj\", " CAM_BOX ", \"environment_map\": {\"path\": \"sunny.exr\"}}\n") ||
        write_file("plane_sun.json", "{\"mesh\": \"plane.obj\", " CAM_TOP ", \"environment_map\": {\"path\": \"sunny.exr\"}}\n") ||
        write_file("plane_sun_ggx.json", "{\"mesh\": \"plane.obj\", " CAM_TOP ", \"environment_map\": {\"path\": \"sunny.exr\"},"
                                         " \"materials\": {\"grey\": {\"ggx\": {\"roughness\": 0.3}}}}\n") ||
        write_file("missing.json", "{\"mesh\": \"plane.obj\", \"environment_map\": {\"path\": \"nowhere.exr\"}}\n") ||
        write_file("notexr.json", "{\"mesh\": \"plane.obj\", \"environment_map\": {\"path\": \"floor.mtl\"}}\n"))
        return -1;
    char msg[256];
    glow_eval_image img;
    if (glow_eval_image_alloc(&img, 64, 32) != GLOW_OK) return -1;
    for (size_t i = 0; i < 64 * 32; ++i) {
        img.rgb[3 * i] = 0.15f;
        img.rgb[3 * i + 1] = 0.2f;
        img.rgb[3 * i + 2] = 0.25f;
    }
    glow_result r = glow_eval_write_exr(&img, at("const.exr"), msg, sizeof msg);
    glow_eval_image_free(&img);
    if (r != GLOW_OK) return -1;
    glow_eval_skymap_params p = glow_eval_skymap_defaults();
    p.width = 128;
    p.sun_elevation_deg = 50.0f;
    p.sun_azimuth_deg = 20.0f;
    p.sun_radius_deg = 5.0f;
    p.sun_irradiance[0] = 12.0f;
    p.sun_irradiance[1] = 11.0f;
    p.sun_irradiance[2] = 10.0f;
    if (glow_eval_skymap(&p, &img, msg, sizeof msg) != GLOW_OK) return -1;
    r = glow_eval_write_exr(&img, at("sunny.exr"), msg, sizeof msg);
    glow_eval_image_free(&img);
    if (r != GLOW_OK) return -1;
    *state = &F;
    return 0;
}

static int teardown(void **state) {
    (void)state;
    static const char *names[] = {"floor.mtl", "plane.obj", "box.obj", "box_env.json", "box_map.json", "box_both.json", "plane_sun.json",
                                  "plane_sun_ggx.json", "missing.json", "notexr.json", "const.exr", "sunny.exr", "plane.glow",
                                  "box_sun.json", "box.glow"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) remove(at(names[i]));
    rmdir(F.dir);
    return 0;
}

static glow_render_scene *load(const char *name) {
    glow_render_scene *s = NULL;
    char msg[600];
    if (glow_render_scene_load(at(name), &s, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    return s;
}

static void render(const glow_render_scene *s, uint32_t spp, bool bsdf_only, glow_render_result *res) {
    glow_render_settings st = {.spp = spp, .seed = 7, .threads = 2, .envmap_bsdf_only = bsdf_only};
    char msg[512];
    if (glow_render_reference(s, &st, res, msg, sizeof msg) != GLOW_OK) fail_msg("render: %s", msg);
    assert_int_equal(res->nonfinite_samples, 0);
}

/* mean and variance over pixels of channel c of img */
static void stats(const glow_eval_image *img, int c, double *mean, double *var) {
    const size_t n = (size_t)img->width * img->height;
    double s = 0.0, s2 = 0.0;
    for (size_t i = 0; i < n; ++i) s += img->rgb[3 * i + c];
    *mean = s / n;
    for (size_t i = 0; i < n; ++i) s2 += (img->rgb[3 * i + c] - *mean) * (img->rgb[3 * i + c] - *mean);
    *var = s2 / (n - 1);
}

/* a and b render the same expected image: the per-pixel difference's mean is 0 within 4 standard errors */
static void same_image(const char *what, const glow_render_result *ra, const glow_render_result *rb) {
    const size_t n = (size_t)ra->final.width * ra->final.height;
    glow_eval_image d;
    assert_int_equal(glow_eval_image_alloc(&d, ra->final.width, ra->final.height), GLOW_OK);
    for (size_t i = 0; i < 3 * n; ++i) d.rgb[i] = rb->final.rgb[i] - ra->final.rgb[i];
    for (int c = 0; c < 3; ++c) {
        double m, v, ma, va;
        stats(&d, c, &m, &v);
        stats(&ra->final, c, &ma, &va);
        const double se = sqrt(v / n);
        printf("%s vs environment, channel %d: mean %.5f vs %.5f, difference %.2e (SE %.2e)\n", what, c, ma + m, ma, m, se);
        if (!(fabs(m) < 4.0 * se + 1e-4 * ma)) fail_msg("%s, channel %d: mean difference %g, standard error %g", what, c, m, se);
        assert_true(ma > 0.1);
    }
    glow_eval_image_free(&d);
}

static void test_constant_map(void **state) {
    (void)state;
    glow_render_scene *a = load("box_env.json"), *b = load("box_map.json"), *both = load("box_both.json");
    glow_render_result ra, rb, rc;
    render(a, 32, false, &ra);
    render(b, 32, false, &rb);
    render(both, 32, false, &rc);
    same_image("constant map x 2", &ra, &rb);
    same_image("half constant + map", &ra, &rc);
    /* there is sky in view and light bounced between box and floor */
    assert_true(rb.mean_indirect[1] > 0.005);
    glow_render_result_free(&ra);
    glow_render_result_free(&rb);
    glow_render_result_free(&rc);
    glow_render_scene_destroy(a);
    glow_render_scene_destroy(b);
    glow_render_scene_destroy(both);
}

/* ρ/π · ∫_upper L cos θ dω of the piecewise-constant map (rows above the horizon), per channel */
static void floor_expected(const char *exr, double rho, double out[3]) {
    glow_eval_envmap m;
    char msg[256];
    if (glow_eval_envmap_load(at(exr), 0.0f, 1.0f, &m, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    out[0] = out[1] = out[2] = 0.0;
    for (uint32_t j = 0; j < m.height / 2; ++j) {
        const double t0 = m.cos_theta[j], t1 = m.cos_theta[j + 1], w = 2.0 * PI_D / m.width * 0.5 * (t0 * t0 - t1 * t1);
        for (uint32_t i = 0; i < m.width; ++i)
            for (int c = 0; c < 3; ++c) out[c] += w * m.rgb[3 * ((size_t)j * m.width + i) + c];
    }
    for (int c = 0; c < 3; ++c) out[c] *= rho / PI_D;
    glow_eval_envmap_free(&m);
}

static void test_sunny_floor(void **state) {
    (void)state;
    glow_render_scene *s = load("plane_sun.json");
    double want[3];
    floor_expected("sunny.exr", 0.5, want);
    glow_render_result mis, bsdf;
    render(s, 16, false, &mis);
    render(s, 16, true, &bsdf);
    const size_t n = (size_t)mis.final.width * mis.final.height;
    for (int c = 0; c < 3; ++c) {
        double m1, v1, m2, v2;
        stats(&mis.final, c, &m1, &v1);
        stats(&bsdf.final, c, &m2, &v2);
        const double se1 = sqrt(v1 / n), se2 = sqrt(v2 / n);
        printf("sunny floor, channel %d: expected %.5f; MIS %.5f (SE %.2e, pixel variance %.3e); BSDF only %.5f (SE %.2e, "
               "pixel variance %.3e): variance ratio %.4f\n",
               c, want[c], m1, se1, v1, m2, se2, v2, v1 / v2);
        if (!(fabs(m1 - want[c]) < 4.0 * se1 + 1e-3 * want[c]))
            fail_msg("MIS: channel %d mean %g, expected %g (SE %g)", c, m1, want[c], se1);
        if (!(fabs(m2 - want[c]) < 4.0 * se2 + 1e-3 * want[c]))
            fail_msg("BSDF only: channel %d mean %g, expected %g (SE %g)", c, m2, want[c], se2);
        if (!(v1 < 0.25 * v2)) fail_msg("channel %d: MIS variance %g is not below a quarter of BSDF's %g", c, v1, v2);
    }
    /* all of it is direct light (the first bounce's sky); nothing else to bounce off */
    assert_true(mis.mean_indirect[0] == 0.0 && bsdf.mean_indirect[0] == 0.0);
    glow_render_result_free(&mis);
    glow_render_result_free(&bsdf);
    glow_render_scene_destroy(s);
}

static void test_sunny_ggx(void **state) {
    (void)state;
    glow_render_scene *s = load("plane_sun_ggx.json");
    glow_render_result mis, bsdf;
    render(s, 16, false, &mis);
    render(s, 16, true, &bsdf);
    const size_t n = (size_t)mis.final.width * mis.final.height;
    for (int c = 0; c < 3; ++c) {
        double m1, v1, m2, v2;
        stats(&mis.final, c, &m1, &v1);
        stats(&bsdf.final, c, &m2, &v2);
        const double se = sqrt(v1 / n + v2 / n);
        printf("sunny GGX floor, channel %d: MIS %.5f (pixel variance %.3e), BSDF only %.5f (%.3e): variance ratio %.4f\n",
               c, m1, v1, m2, v2, v1 / v2);
        if (!(fabs(m1 - m2) < 4.0 * se)) fail_msg("channel %d: MIS %g vs BSDF only %g (combined SE %g)", c, m1, m2, se);
        if (!(v1 < 0.5 * v2)) fail_msg("channel %d: MIS variance %g, BSDF only %g", c, v1, v2);
        assert_true(m1 > 0.1);
    }
    glow_render_result_free(&mis);
    glow_render_result_free(&bsdf);
    glow_render_scene_destroy(s);
}

static void test_glow_view(void **state) {
    (void)state;
    glow_pc_settings ps = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 1024, .links = 32, .bands = 3, .threads = 2, .seed = 1};
    glow_pc_stats pst;
    if (glow_pc_bake(at("plane.obj"), at("plane.glow"), &ps, &pst) != GLOW_OK) fail_msg("bake: %s", pst.error);
    glow_render_scene *s = load("plane_sun.json");
    glow_render_settings st = {.width = 16, .height = 16, .spp = 4, .seed = 3, .threads = 2};
    glow_render_result ref, view, ind;
    char msg[512];
    if (glow_render_reference(s, &st, &ref, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    glow_render_glow_settings gs = {.bounce_iterations = 4};
    if (glow_render_glow(s, at("plane.glow"), &st, &gs, &view, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    gs.indirect_only = true;
    if (glow_render_glow(s, at("plane.glow"), &st, &gs, &ind, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    const size_t bytes = (size_t)16 * 16 * 3 * sizeof(float);
    assert_memory_equal(ref.direct.rgb, view.direct.rgb, bytes);
    assert_memory_equal(view.indirect.rgb, ind.indirect.rgb, bytes);
    assert_true(view.mean_direct[1] > 0.1); /* the map's light is in Glow's direct image */
    glow_render_result_free(&ref);
    glow_render_result_free(&view);
    glow_render_result_free(&ind);
    glow_render_scene_destroy(s);
}

static void test_glow_view_bounce(void **state) {
    (void)state;
    glow_pc_settings ps = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 64, .bands = 3, .threads = 2, .seed = 1};
    glow_pc_stats pst;
    if (glow_pc_bake(at("box.obj"), at("box.glow"), &ps, &pst) != GLOW_OK) fail_msg("bake: %s", pst.error);
    glow_render_scene *s = load("box_sun.json");
    glow_render_settings st = {.spp = 256, .seed = 5, .threads = 2};
    glow_render_result ref, view;
    char msg[512];
    if (glow_render_reference(s, &st, &ref, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    st.spp = 4;
    glow_render_glow_settings gs = {.bounce_iterations = 16};
    if (glow_render_glow(s, at("box.glow"), &st, &gs, &view, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    for (int c = 0; c < 3; ++c) {
        printf("box under the sunny map, channel %d: mean indirect Glow %.5f, reference %.5f (ratio %.3f)\n", c,
               view.mean_indirect[c], ref.mean_indirect[c], view.mean_indirect[c] / ref.mean_indirect[c]);
        assert_true(ref.mean_indirect[c] > 0.01);
        if (!(fabs(view.mean_indirect[c] / ref.mean_indirect[c] - 1.0) < 0.12))
            fail_msg("channel %d: Glow's mean indirect %g against the reference's %g", c, view.mean_indirect[c],
                     ref.mean_indirect[c]);
    }
    glow_render_result_free(&ref);
    glow_render_result_free(&view);
    glow_render_scene_destroy(s);
}

static void test_errors(void **state) {
    (void)state;
    glow_render_scene *s = NULL;
    char msg[600];
    assert_int_equal(glow_render_scene_load(at("missing.json"), &s, msg, sizeof msg), GLOW_ERROR_IO);
    assert_null(s);
    if (!strstr(msg, at("missing.json")) || !strstr(msg, "environment_map") || !strstr(msg, at("nowhere.exr")) ||
        !strstr(msg, "cannot open"))
        fail_msg("missing map: \"%s\"", msg);
    assert_int_equal(glow_render_scene_load(at("notexr.json"), &s, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    if (!strstr(msg, at("notexr.json")) || !strstr(msg, at("floor.mtl")) || !strstr(msg, "not an OpenEXR file"))
        fail_msg("not an EXR: \"%s\"", msg);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_map), cmocka_unit_test(test_sunny_floor), cmocka_unit_test(test_sunny_ggx),
        cmocka_unit_test(test_glow_view),    cmocka_unit_test(test_glow_view_bounce), cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
