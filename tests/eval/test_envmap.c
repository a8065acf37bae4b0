/* test_envmap.c — HDR environment maps (tools/eval/glow_envmap.h, docs/envmap.md) against answers known
 * without them:
 *   (a) orientation: the documented directions of the image's centre column, u = 0, u = 0.75, the top
 *       row, and the sense of rotation_deg (a lit texel is found where the doc says);
 *   (b) sampling: the pdf sums to 1 over the sphere, a sample's pdf and radiance are what pdf() and
 *       eval() give for its direction, and a histogram of 200 000 samples matches Y Ω / Σ Y Ω per texel
 *       (chi-square);
 *   (c) SH: the projection of analytic maps (1 + 0.5 y + 0.3 xz; 1 + x_map turned 90°) matches the
 *       analytic coefficients, and a blobby map's matches a sub-texel quadrature with the runtime's own
 *       basis (glow_sh_eval): the same ordering and normalisation;
 *   (d) the sun split recovers a planted sun's direction and irradiance (glow_eval_skymap) and keeps the
 *       energy; a sky without a sun has none; the generator's sun integrates to its irradiance;
 *   (e) errors: a missing file, not an EXR, negative / NaN texels, a 3:2 image, bad rotation and scale,
 *       each with its code and a message naming the file. */
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

#include "glow_envmap.h"

#define PI_D 3.14159265358979323846

static void assert_dir(const float *d, double x, double y, double z, double tol) {
    if (fabs(d[0] - x) > tol || fabs(d[1] - y) > tol || fabs(d[2] - z) > tol)
        fail_msg("direction (%g, %g, %g), want (%g, %g, %g)", (double)d[0], (double)d[1], (double)d[2], x, y, z);
}

/* A W x W/2 map from f(map-frame direction) at texel centres. */
static void make_map(uint32_t W, void (*f)(const float d[3], float out[3]), float rotation_deg, glow_eval_envmap *m) {
    glow_eval_image img;
    assert_int_equal(glow_eval_image_alloc(&img, W, W / 2), GLOW_OK);
    glow_eval_envmap frame = {.width = W, .height = W / 2}; /* rotation 0: glow_eval_envmap_direction's frame */
    for (uint32_t j = 0; j < W / 2; ++j)
        for (uint32_t i = 0; i < W; ++i) {
            float d[3];
            glow_eval_envmap_direction(&frame, (i + 0.5) / W, (j + 0.5) / (W / 2), d);
            f(d, img.rgb + 3 * ((size_t)j * W + i));
        }
    char msg[256];
    assert_int_equal(glow_eval_envmap_from_image(&img, rotation_deg, 1.0f, "test", m, msg, sizeof msg), GLOW_OK);
    glow_eval_image_free(&img);
}

static void test_orientation(void **state) {
    (void)state;
    glow_eval_envmap m0 = {.width = 8, .height = 4};
    float d[3];
    glow_eval_envmap_direction(&m0, 0.5, 0.5, d);
    assert_dir(d, 0, 0, -1, 1e-6); /* centre column: -Z */
    glow_eval_envmap_direction(&m0, 0.0, 0.5, d);
    assert_dir(d, 0, 0, 1, 1e-6); /* u = 0: +Z */
    glow_eval_envmap_direction(&m0, 0.75, 0.5, d);
    assert_dir(d, 1, 0, 0, 1e-6); /* u = 0.75: +X */
    glow_eval_envmap_direction(&m0, 0.25, 0.5, d);
    assert_dir(d, -1, 0, 0, 1e-6);
    glow_eval_envmap_direction(&m0, 0.3, 0.0, d);
    assert_dir(d, 0, 1, 0, 1e-6); /* top row: up */
    /* rotation 90°: map +Z (u = 0) appears at world +X (right-handed about +Y) */
    m0.rot_rad = PI_D / 2;
    glow_eval_envmap_direction(&m0, 0.0, 0.5, d);
    assert_dir(d, 1, 0, 0, 1e-6);
    /* a lit texel at u = 0.75 on the equator (column 6 of 8, row 1 of 4 just above the horizon) */
    glow_eval_image img;
    assert_int_equal(glow_eval_image_alloc(&img, 8, 4), GLOW_OK);
    float *t = img.rgb + 3 * (1 * 8 + 6);
    t[0] = 5.0f, t[1] = 6.0f, t[2] = 7.0f;
    glow_eval_envmap m;
    char msg[256];
    assert_int_equal(glow_eval_envmap_from_image(&img, 0.0f, 2.0f, "t", &m, msg, sizeof msg), GLOW_OK);
    /* the texel's middle, u = 0.8125, v = 0.375: θ = 67.5°, φ = 292.5° */
    const float mid[3] = {0.853553f, 0.382683f, 0.353553f}, px[3] = {0.995f, 0.0998f, 0.0f}, nz[3] = {0, 0.1f, -0.995f};
    float L[3];
    glow_eval_envmap_direction(&m, 0.8125, 0.375, d);
    assert_dir(d, mid[0], mid[1], mid[2], 1e-5);
    glow_eval_envmap_eval(&m, mid, L);
    assert_true(L[0] == 10.0f && L[1] == 12.0f && L[2] == 14.0f); /* scale 2 */
    glow_eval_envmap_eval(&m, px, L); /* +X is the texel's left edge (u = 0.75) */
    assert_true(L[0] == 10.0f);
    glow_eval_envmap_eval(&m, nz, L);
    assert_true(L[0] == 0.0f);
    glow_eval_envmap_free(&m);
    /* turned by -90° about +Y: x' = -z, z' = x, so the texel's middle moves to (-0.354, 0.383, 0.854) */
    assert_int_equal(glow_eval_envmap_from_image(&img, -90.0f, 1.0f, "t", &m, msg, sizeof msg), GLOW_OK);
    const float turned[3] = {-0.353553f, 0.382683f, 0.853553f};
    glow_eval_envmap_eval(&m, mid, L);
    assert_true(L[0] == 0.0f);
    glow_eval_envmap_eval(&m, turned, L);
    assert_true(L[0] == 5.0f);
    glow_eval_envmap_direction(&m, 0.8125, 0.375, d);
    assert_dir(d, turned[0], turned[1], turned[2], 1e-5);
    glow_eval_envmap_free(&m);
    glow_eval_image_free(&img);
}

static void blobs(const float d[3], float out[3]) {
    const double a = exp(-20.0 * (1.0 - (0.6 * d[0] + 0.64 * d[1] + 0.48 * d[2])));
    const double b = exp(-5.0 * (1.0 + d[2]));
    out[0] = (float)(0.2 + 30.0 * a + b);
    out[1] = (float)(0.3 + 20.0 * a + 2.0 * b);
    out[2] = (float)(0.1 + 10.0 * a * fabs(d[0]) + 0.5 * b);
}

static float lum(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

static void test_sampling(void **state) {
    (void)state;
    glow_eval_envmap m;
    make_map(64, blobs, 30.0f, &m);
    const uint32_t W = m.width, H = m.height;
    /* Σ pdf Ω = 1, and Ω sums to 4π */
    double s = 0.0, om_all = 0.0;
    for (uint32_t j = 0; j < H; ++j) {
        const double om = 2.0 * PI_D / W * (m.cos_theta[j] - m.cos_theta[j + 1]);
        for (uint32_t i = 0; i < W; ++i) {
            float d[3];
            glow_eval_envmap_direction(&m, (i + 0.5) / W, (j + 0.5) / H, d);
            s += glow_eval_envmap_pdf(&m, d) * om;
            om_all += om;
        }
    }
    assert_true(fabs(s - 1.0) < 1e-5);
    assert_true(fabs(om_all - 4.0 * PI_D) < 1e-9);
    /* samples: consistent with pdf() and eval(); histogram by texel */
    const uint32_t N = 200000;
    uint32_t *hist = calloc((size_t)W * H, sizeof *hist);
    assert_non_null(hist);
    uint64_t x = 12345;
    double est[3] = {0, 0, 0};
    for (uint32_t n = 0; n < N; ++n) {
        float u[2];
        for (int k = 0; k < 2; ++k) {
            x = x * 6364136223846793005ull + 1442695040888963407ull;
            u[k] = (float)(x >> 40) * 0x1p-24f;
        }
        float d[3], L[3], L2[3];
        const float p = glow_eval_envmap_sample(&m, u[0], u[1], d, L);
        assert_true(p > 0.0f);
        assert_true(fabs(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.0) < 1e-5);
        const float p2 = glow_eval_envmap_pdf(&m, d);
        if (fabsf(p - p2) > 1e-5f * p) fail_msg("sample %u: pdf %g but pdf(dir) %g", n, (double)p, (double)p2);
        glow_eval_envmap_eval(&m, d, L2);
        assert_true(L[0] == L2[0] && L[1] == L2[1] && L[2] == L2[2]);
        for (int k = 0; k < 3; ++k) est[k] += L[k] / p / N;
        /* the texel (rotation undone) */
        double u_ = (atan2(-(double)d[0], (double)d[2]) + m.rot_rad) / (2.0 * PI_D);
        u_ -= floor(u_);
        uint32_t i = (uint32_t)(u_ * W), j = (uint32_t)(acos(fmin(fmax(d[1], -1.0), 1.0)) / PI_D * H);
        hist[(size_t)(j < H ? j : H - 1) * W + (i < W ? i : W - 1)]++;
    }
    /* the estimate of ∫ L dω (its luminance is exact: L / pdf has constant luminance) */
    double I[3];
    glow_eval_envmap_integral(&m, I);
    const float Ie[3] = {(float)est[0], (float)est[1], (float)est[2]}, If[3] = {(float)I[0], (float)I[1], (float)I[2]};
    assert_true(fabs(lum(Ie) - lum(If)) < 1e-4 * lum(If));
    for (int k = 0; k < 3; ++k) assert_true(fabs(est[k] - I[k]) < 0.05 * I[k]);
    /* chi-square over texels with an expected count >= 20 (the rest pooled) */
    double chi2 = 0.0, pool_e = 0.0, pool_o = 0.0;
    int dof = 0;
    for (uint32_t j = 0; j < H; ++j) {
        const double om = 2.0 * PI_D / W * (m.cos_theta[j] - m.cos_theta[j + 1]);
        for (uint32_t i = 0; i < W; ++i) {
            const double e = N * lum(m.rgb + 3 * ((size_t)j * W + i)) * om / m.lum_integral;
            const double o = hist[(size_t)j * W + i];
            if (e >= 20.0) {
                chi2 += (o - e) * (o - e) / e;
                dof++;
            } else {
                pool_e += e;
                pool_o += o;
            }
        }
    }
    if (pool_e > 0.0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof++;
    }
    /* dof - 1 degrees of freedom: mean dof, sd sqrt(2 dof); 5 sd is far out */
    if (chi2 > dof + 5.0 * sqrt(2.0 * dof)) fail_msg("chi-square %g with %d bins", chi2, dof);
    assert_true(dof > 100);
    free(hist);
    glow_eval_envmap_free(&m);
    /* a black map, or scale 0: nothing to sample */
    glow_eval_image img;
    assert_int_equal(glow_eval_image_alloc(&img, 8, 4), GLOW_OK);
    char msg[128];
    assert_int_equal(glow_eval_envmap_from_image(&img, 0.0f, 1.0f, "t", &m, msg, sizeof msg), GLOW_OK);
    float d[3], L[3];
    assert_true(glow_eval_envmap_sample(&m, 0.3f, 0.7f, d, L) == 0.0f);
    assert_true(glow_eval_envmap_pdf(&m, (const float[3]){0, 1, 0}) == 0.0f);
    glow_eval_envmap_free(&m);
    glow_eval_image_free(&img);
}

static void lin_y(const float d[3], float out[3]) {
    const float v = 1.0f + 0.5f * d[1] + 0.3f * d[0] * d[2];
    out[0] = out[1] = out[2] = v;
}
static void lin_x(const float d[3], float out[3]) {
    out[0] = 1.0f + d[0];
    out[1] = 2.0f;
    out[2] = 0.0f;
}

static void test_sh(void **state) {
    (void)state;
    /* L = 1 + 0.5 y + 0.3 xz (world = map frame): c0 = √(4π), c1 = 0.4886 · 0.5 · 4π/3, c7 = 1.0925 · 0.3 · 4π/15 */
    glow_eval_envmap m;
    make_map(256, lin_y, 0.0f, &m);
    double c[27];
    glow_eval_envmap_sh9(&m, c);
    double want[9] = {0};
    want[0] = 0.28209479177387814 * 4.0 * PI_D;
    want[1] = 0.48860251190291992 * 0.5 * 4.0 * PI_D / 3.0;
    want[7] = 1.0925484305920792 * 0.3 * 4.0 * PI_D / 15.0;
    for (int k = 0; k < 9; ++k)
        for (int ch = 0; ch < 3; ++ch)
            if (fabs(c[3 * k + ch] - want[k]) > 2e-3)
                fail_msg("1 + 0.5y + 0.3xz: c%d[%d] = %.6f, want %.6f", k, ch, c[3 * k + ch], want[k]);
    /* its irradiance facing up: π · 1 + 0.5 · 2π/3 (the xz term integrates to 0), from the texels and from
     * the SH (exact for a radiance of degree <= 2) */
    const float up[3] = {0.0f, 1.0f, 0.0f};
    double e_map[3], e_sh[3];
    glow_eval_envmap_irradiance(&m, up, e_map);
    glow_eval_sh9_irradiance(c, up, e_sh);
    const double e_want = PI_D + 0.5 * 2.0 * PI_D / 3.0;
    for (int ch = 0; ch < 3; ++ch)
        if (fabs(e_map[ch] - e_want) > 2e-3 || fabs(e_sh[ch] - e_want) > 2e-3)
            fail_msg("irradiance up: texels %.6f, SH %.6f, want %.6f", e_map[ch], e_sh[ch], e_want);
    glow_eval_envmap_free(&m);
    /* L = 1 + x_map turned by 90°: world L = 1 - z (map x = -world z), so c2 = -0.4886 · 4π/3 and c3 = 0 */
    make_map(256, lin_x, 90.0f, &m);
    glow_eval_envmap_sh9(&m, c);
    for (int k = 0; k < 9; ++k) {
        const double w0 = k == 0 ? 0.28209479177387814 * 4.0 * PI_D : k == 2 ? -0.48860251190291992 * 4.0 * PI_D / 3.0 : 0.0;
        const double w1 = k == 0 ? 2.0 * 0.28209479177387814 * 4.0 * PI_D : 0.0;
        if (fabs(c[3 * k] - w0) > 2e-3 || fabs(c[3 * k + 1] - w1) > 2e-3 || fabs(c[3 * k + 2]) > 1e-9)
            fail_msg("turned 1 + x: c%d = (%.6f %.6f %.6f), want (%.6f %.6f 0)", k, c[3 * k], c[3 * k + 1], c[3 * k + 2],
                     w0, w1);
    }
    glow_eval_envmap_free(&m);
    /* a blobby map turned by 30°: against 8 x 8 sub-texel quadrature with the runtime's glow_sh_eval */
    make_map(64, blobs, 30.0f, &m);
    glow_eval_envmap_sh9(&m, c);
    double q[27] = {0};
    const uint32_t W = m.width, H = m.height;
    for (uint32_t j = 0; j < H; ++j)
        for (uint32_t a = 0; a < 8; ++a) {
            const double c0 = m.cos_theta[j], c1 = m.cos_theta[j + 1];
            const double ca = c0 + (c1 - c0) * a / 8.0, cb = c0 + (c1 - c0) * (a + 1) / 8.0;
            const double om = 2.0 * PI_D / (8.0 * W) * (ca - cb), v = acos(0.5 * (ca + cb)) / PI_D;
            for (uint32_t i = 0; i < W; ++i)
                for (uint32_t b = 0; b < 8; ++b) {
                    float d[3], y[9], L[3];
                    glow_eval_envmap_direction(&m, (i + (b + 0.5) / 8.0) / W, v, d);
                    glow_sh_eval(3, d, y);
                    glow_eval_envmap_eval(&m, d, L);
                    for (int k = 0; k < 9; ++k)
                        for (int ch = 0; ch < 3; ++ch) q[3 * k + ch] += om * y[k] * L[ch];
                }
        }
    for (int k = 0; k < 27; ++k)
        if (fabs(c[k] - q[k]) > 2e-3 * fabs(q[0]))
            fail_msg("blobs: c[%d] = %.6f, quadrature with glow_sh_eval %.6f", k, c[k], q[k]);
    glow_eval_envmap_free(&m);
}

static void sky_params(glow_eval_skymap_params *p, float el, float az, float e) {
    *p = glow_eval_skymap_defaults();
    p->width = 256;
    p->sun_elevation_deg = el;
    p->sun_azimuth_deg = az;
    p->sun_radius_deg = 1.0f;
    p->sun_irradiance[0] = 2.0f * e;
    p->sun_irradiance[1] = 1.8f * e;
    p->sun_irradiance[2] = 1.5f * e;
}

static void test_sun(void **state) {
    (void)state;
    glow_eval_skymap_params p;
    sky_params(&p, 40.0f, -60.0f, 10.0f);
    glow_eval_image sky, plain;
    char msg[256];
    assert_int_equal(glow_eval_skymap(&p, &sky, msg, sizeof msg), GLOW_OK);
    glow_eval_skymap_params p0 = p;
    p0.sun_irradiance[0] = p0.sun_irradiance[1] = p0.sun_irradiance[2] = 0.0f;
    assert_int_equal(glow_eval_skymap(&p0, &plain, msg, sizeof msg), GLOW_OK);
    const double el = 40.0 * PI_D / 180.0, az = -60.0 * PI_D / 180.0;
    const double sd[3] = {sin(az) * cos(el), sin(el), -cos(az) * cos(el)};
    for (int rot = 0; rot < 2; ++rot) {
        const float rdeg = rot ? 90.0f : 0.0f;
        glow_eval_envmap m, m0, res;
        assert_int_equal(glow_eval_envmap_from_image(&sky, rdeg, 0.5f, "sky", &m, msg, sizeof msg), GLOW_OK);
        assert_int_equal(glow_eval_envmap_from_image(&plain, rdeg, 0.5f, "plain", &m0, msg, sizeof msg), GLOW_OK);
        /* the generator's sun integrates to its irradiance exactly (× scale 0.5) */
        double I[3], I0[3], Ir[3];
        glow_eval_envmap_integral(&m, I);
        glow_eval_envmap_integral(&m0, I0);
        for (int k = 0; k < 3; ++k)
            if (fabs(I[k] - I0[k] - 0.5 * p.sun_irradiance[k]) > 1e-4 * p.sun_irradiance[k])
                fail_msg("generator: sun integral %g, want %g", I[k] - I0[k], 0.5 * p.sun_irradiance[k]);
        glow_eval_envmap_sun sun;
        assert_int_equal(glow_eval_envmap_extract_sun(&m, NULL, &sun, &res, msg, sizeof msg), GLOW_OK);
        assert_true(sun.found);
        /* world direction: rotation α maps map (x, z) to (x cos α + z sin α, -x sin α + z cos α) */
        const double ca = cos(rdeg * PI_D / 180.0), sa = sin(rdeg * PI_D / 180.0);
        const double w[3] = {sd[0] * ca + sd[2] * sa, sd[1], -sd[0] * sa + sd[2] * ca};
        const double dot = sun.to_sun[0] * w[0] + sun.to_sun[1] * w[1] + sun.to_sun[2] * w[2];
        const double err_deg = acos(fmin(dot, 1.0)) * 180.0 / PI_D;
        if (err_deg > 0.25) fail_msg("rotation %g: sun direction off by %g degrees", (double)rdeg, err_deg);
        /* irradiance within 1 % (the sky behind the disc, L_bg, stays in the residual) */
        for (int k = 0; k < 3; ++k)
            if (fabs(sun.irradiance[k] - 0.5 * p.sun_irradiance[k]) > 0.01 * 0.5 * p.sun_irradiance[k])
                fail_msg("sun irradiance[%d] %g, want %g", k, (double)sun.irradiance[k], 0.5 * p.sun_irradiance[k]);
        assert_true(sun.radius_deg >= 1.0f && sun.radius_deg < 3.0f);
        assert_true(sun.texel_count >= 4);
        /* energy: residual + sun = the map */
        glow_eval_envmap_integral(&res, Ir);
        for (int k = 0; k < 3; ++k)
            if (fabs(Ir[k] + sun.irradiance[k] - I[k]) > 1e-5 * I[k])
                fail_msg("energy: residual %g + sun %g != map %g", Ir[k], (double)sun.irradiance[k], I[k]);
        /* the sun's texels now hold the surroundings' level (the sky behind the sun) */
        float Lr[3];
        glow_eval_envmap_eval(&res, sun.to_sun, Lr);
        for (int k = 0; k < 3; ++k)
            if (fabsf(Lr[k] - sun.background[k]) > 1e-6f * sun.background[k])
                fail_msg("residual at the sun %g, surroundings %g", (double)Lr[k], (double)sun.background[k]);
        /* the residual has no sun left: its brightest texel is sky-level */
        glow_eval_envmap_sun again;
        assert_int_equal(glow_eval_envmap_extract_sun(&res, NULL, &again, NULL, msg, sizeof msg), GLOW_OK);
        assert_false(again.found);
        assert_true(lum(again.brightest) < 1.0f);
        /* a sky without a sun has none */
        assert_int_equal(glow_eval_envmap_extract_sun(&m0, NULL, &again, NULL, msg, sizeof msg), GLOW_OK);
        assert_false(again.found);
        /* the host's one call: the residual's SH (float, coefficient-major) and the same sun; unsplit: the map's */
        float hsh[27];
        glow_eval_envmap_sun hsun;
        double rsh[27], msh[27];
        glow_eval_envmap_sh9(&res, rsh);
        glow_eval_envmap_sh9(&m, msh);
        assert_int_equal(glow_eval_envmap_sky_sh(&m, true, NULL, hsh, &hsun, msg, sizeof msg), GLOW_OK);
        assert_true(hsun.found && memcmp(hsun.to_sun, sun.to_sun, sizeof sun.to_sun) == 0 &&
                    memcmp(hsun.irradiance, sun.irradiance, sizeof sun.irradiance) == 0);
        for (int k = 0; k < 27; ++k) assert_true(hsh[k] == (float)rsh[k]);
        assert_int_equal(glow_eval_envmap_sky_sh(&m, false, NULL, hsh, NULL, msg, sizeof msg), GLOW_OK);
        for (int k = 0; k < 27; ++k) assert_true(hsh[k] == (float)msh[k]);
        assert_true(fabs(msh[0] - rsh[0]) > 0.1); /* the sun was in the map's SH */
        glow_eval_envmap_free(&m);
        glow_eval_envmap_free(&m0);
        glow_eval_envmap_free(&res);
    }
    /* a sub-texel sun (0.05°) on a coarse map still carries its irradiance, in one texel */
    p.width = 64;
    p.sun_radius_deg = 0.05f;
    glow_eval_image small;
    assert_int_equal(glow_eval_skymap(&p, &small, msg, sizeof msg), GLOW_OK);
    glow_eval_envmap m;
    assert_int_equal(glow_eval_envmap_from_image(&small, 0.0f, 1.0f, "small", &m, msg, sizeof msg), GLOW_OK);
    glow_eval_envmap_sun sun;
    assert_int_equal(glow_eval_envmap_extract_sun(&m, NULL, &sun, NULL, msg, sizeof msg), GLOW_OK);
    assert_true(sun.found);
    assert_int_equal(sun.texel_count, 1);
    assert_true(fabs(sun.irradiance[0] - p.sun_irradiance[0]) < 0.02 * p.sun_irradiance[0]);
    glow_eval_envmap_free(&m);
    glow_eval_image_free(&small);
    /* bad parameters */
    glow_eval_skymap_params bad = p;
    bad.width = 7;
    assert_int_equal(glow_eval_skymap(&bad, &small, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    bad = p;
    bad.sun_elevation_deg = 91.0f;
    assert_int_equal(glow_eval_skymap(&bad, &small, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    bad = p;
    bad.zenith[1] = -1.0f;
    assert_int_equal(glow_eval_skymap(&bad, &small, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(small.rgb);
    glow_eval_image_free(&sky);
    glow_eval_image_free(&plain);
}

static void expect_error(const char *path, float rot, float scale, glow_result code, const char *needle) {
    glow_eval_envmap m;
    char msg[512] = "";
    const glow_result r = glow_eval_envmap_load(path, rot, scale, &m, msg, sizeof msg);
    if (r != code || !strstr(msg, path) || !strstr(msg, needle))
        fail_msg("%s: got %d \"%s\", want %d with \"%s\"", path, (int)r, msg, (int)code, needle);
    assert_null(m.rgb);
    assert_int_equal(m.width, 0);
}

static void test_errors(void **state) {
    (void)state;
    char dir[128], path[256], msg[512];
    snprintf(dir, sizeof dir, "/tmp/glow_envmap_test_%d", (int)getpid());
    snprintf(path, sizeof path, "%s_missing.exr", dir);
    expect_error(path, 0.0f, 1.0f, GLOW_ERROR_IO, "cannot open");
    /* not an EXR */
    snprintf(path, sizeof path, "%s_text.exr", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("hello, not an image\n", f);
    fclose(f);
    expect_error(path, 0.0f, 1.0f, GLOW_ERROR_CORRUPT_DATA, "not an OpenEXR file");
    remove(path);
    /* bad texels and sizes, written as real EXRs */
    glow_eval_image img;
    assert_int_equal(glow_eval_image_alloc(&img, 8, 4), GLOW_OK);
    snprintf(path, sizeof path, "%s_ok.exr", dir);
    assert_int_equal(glow_eval_write_exr(&img, path, msg, sizeof msg), GLOW_OK);
    glow_eval_envmap m;
    assert_int_equal(glow_eval_envmap_load(path, 10.0f, 2.0f, &m, msg, sizeof msg), GLOW_OK);
    assert_int_equal(m.width, 8);
    glow_eval_envmap_free(&m);
    expect_error(path, NAN, 1.0f, GLOW_ERROR_INVALID_ARGUMENT, "rotation_deg");
    expect_error(path, 0.0f, -1.0f, GLOW_ERROR_INVALID_ARGUMENT, "scale");
    expect_error(path, 0.0f, INFINITY, GLOW_ERROR_INVALID_ARGUMENT, "scale");
    img.rgb[3 * (2 * 8 + 5) + 1] = -0.5f;
    assert_int_equal(glow_eval_write_exr(&img, path, msg, sizeof msg), GLOW_OK);
    expect_error(path, 0.0f, 1.0f, GLOW_ERROR_CORRUPT_DATA, "texel (5, 2) channel G is -0.5 (negative)");
    img.rgb[3 * (2 * 8 + 5) + 1] = NAN;
    assert_int_equal(glow_eval_write_exr(&img, path, msg, sizeof msg), GLOW_OK);
    expect_error(path, 0.0f, 1.0f, GLOW_ERROR_CORRUPT_DATA, "texel (5, 2) channel G is nan (not finite)");
    glow_eval_image_free(&img);
    assert_int_equal(glow_eval_image_alloc(&img, 9, 6), GLOW_OK);
    assert_int_equal(glow_eval_write_exr(&img, path, msg, sizeof msg), GLOW_OK);
    expect_error(path, 0.0f, 1.0f, GLOW_ERROR_CORRUPT_DATA, "9x6 is not a latitude-longitude map");
    glow_eval_image_free(&img);
    remove(path);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orientation), cmocka_unit_test(test_sampling), cmocka_unit_test(test_sh),
        cmocka_unit_test(test_sun),         cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
