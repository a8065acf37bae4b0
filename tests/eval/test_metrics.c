/* test_metrics.c — glow_eval's metrics against hand-computed values, closed forms and independent
 * brute-force versions (SSIM: direct clipped 11 x 11 window per pixel; block error: per-block loops).
 * FLIP has its own file, test_flip.c. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "glow_eval.h"

/* ---- helpers ---- */

/* cmocka's assert_float_equal works in float; these checks need double. */
#define assert_near(a, b, tol) assert_near_impl((double)(a), (double)(b), (double)(tol), __FILE__, __LINE__)
static void assert_near_impl(double a, double b, double tol, const char *file, int line) {
    if (!(fabs(a - b) <= tol)) {
        print_error("%.17g != %.17g (tolerance %g)\n", a, b, tol);
        _fail(file, line);
    }
}

static glow_eval_image make_image(uint32_t w, uint32_t h) {
    glow_eval_image img;
    assert_int_equal(glow_eval_image_alloc(&img, w, h), GLOW_OK);
    return img;
}

static void fill_grey(glow_eval_image *img, float v) {
    for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++) img->rgb[i] = v;
}

static uint32_t lcg_state;
static double lcg01(void) { /* deterministic uniform [0,1) */
    lcg_state = lcg_state * 1664525u + 1013904223u;
    return (double)(lcg_state >> 8) / 16777216.0;
}

/* Inverse of the sRGB curve, written independently from the library. */
static double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4); }

/* Smooth colourful test image with values in a moderate HDR range. */
static void fill_pattern(glow_eval_image *img) {
    for (uint32_t y = 0; y < img->height; y++)
        for (uint32_t x = 0; x < img->width; x++) {
            float *p = img->rgb + ((size_t)y * img->width + x) * 3;
            p[0] = (float)(0.3 + 0.25 * sin(0.31 * x) * cos(0.17 * y));
            p[1] = (float)(0.2 + 0.15 * (double)x / img->width + 0.1 * sin(0.5 * y));
            p[2] = (float)(0.05 + 0.4 * (double)((x / 4 + y / 3) % 2));
        }
}

/* Brute-force SSIM per the header: display luma, clipped renormalised 11x11 Gaussian (sigma 1.5),
 * mean over unmasked centres. */
static double encode_ref(double x) {
    if (!(x > 0)) return 0;
    if (x > 1) x = 1;
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1 / 2.4) - 0.055;
}
static double ssim_brute(const glow_eval_image *a, const glow_eval_image *b, const uint8_t *mask, double e) {
    int W = (int)a->width, H = (int)a->height;
    double *la = malloc(sizeof(double) * (size_t)W * H), *lb = malloc(sizeof(double) * (size_t)W * H);
    assert_non_null(la);
    assert_non_null(lb);
    for (int i = 0; i < W * H; i++) {
        const float *p = a->rgb + 3 * i, *q = b->rgb + 3 * i;
        la[i] = 0.2126 * encode_ref(p[0] * e) + 0.7152 * encode_ref(p[1] * e) + 0.0722 * encode_ref(p[2] * e);
        lb[i] = 0.2126 * encode_ref(q[0] * e) + 0.7152 * encode_ref(q[1] * e) + 0.0722 * encode_ref(q[2] * e);
    }
    double total = 0;
    int n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            if (mask && !mask[y * W + x]) continue;
            double ws = 0, mx = 0, my = 0;
            for (int j = -5; j <= 5; j++)
                for (int i = -5; i <= 5; i++) {
                    int xx = x + i, yy = y + j;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
                    double w = exp(-(i * i + j * j) / (2 * 1.5 * 1.5));
                    ws += w;
                    mx += w * la[yy * W + xx];
                    my += w * lb[yy * W + xx];
                }
            mx /= ws;
            my /= ws;
            double vx = 0, vy = 0, cxy = 0; /* central moments, two-pass */
            for (int j = -5; j <= 5; j++)
                for (int i = -5; i <= 5; i++) {
                    int xx = x + i, yy = y + j;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
                    double w = exp(-(i * i + j * j) / (2 * 1.5 * 1.5)) / ws;
                    double dx = la[yy * W + xx] - mx, dy = lb[yy * W + xx] - my;
                    vx += w * dx * dx;
                    vy += w * dy * dy;
                    cxy += w * dx * dy;
                }
            const double C1 = 0.0001, C2 = 0.0009;
            total += (2 * mx * my + C1) * (2 * cxy + C2) / ((mx * mx + my * my + C1) * (vx + vy + C2));
            n++;
        }
    free(la);
    free(lb);
    return total / n;
}

/* ---- sRGB ---- */

static void test_srgb_encode(void **state) {
    (void)state;
    assert_true(glow_eval_srgb_encode(0.0f) == 0.0f);
    assert_true(glow_eval_srgb_encode(1.0f) == 1.0f);
    assert_true(glow_eval_srgb_encode(-3.0f) == 0.0f);
    assert_true(glow_eval_srgb_encode(7.5f) == 1.0f);
    assert_true(glow_eval_srgb_encode(INFINITY) == 1.0f);
    assert_true(glow_eval_srgb_encode(NAN) == 0.0f);
    /* Reference values of the IEC 61966-2-1 curve (computed separately in Python). */
    assert_near(glow_eval_srgb_encode(0.5f), 0.7353569830524495, 1e-6);
    assert_near(glow_eval_srgb_encode(0.18f), 0.46135612950044164, 1e-6);
    assert_near(glow_eval_srgb_encode(0.2f), 0.48452920448170694, 1e-6);
    assert_near(glow_eval_srgb_encode(0.001f), 0.01292, 1e-7); /* linear segment */
    /* The threshold: both pieces meet there (continuous to ~1e-7). */
    assert_near(glow_eval_srgb_encode(0.0031308f), 0.040449936, 1e-6);
    assert_near(glow_eval_srgb_encode(0.00313f), 12.92 * 0.00313, 1e-7);
    assert_near(glow_eval_srgb_encode(0.0031316f), 1.055 * pow(0.0031316, 1 / 2.4) - 0.055, 1e-7);
    /* Monotonic over [0, 1]. */
    float prev = -1;
    for (int i = 0; i <= 4096; i++) {
        float v = glow_eval_srgb_encode((float)i / 4096.0f);
        assert_true(v >= prev);
        prev = v;
    }
}

/* ---- relative RMSE ---- */

static void test_rel_rmse_identity_and_scale(void **state) {
    (void)state;
    glow_eval_image ref = make_image(31, 17), test = make_image(31, 17);
    fill_pattern(&ref);
    assert_true(glow_eval_rel_rmse(&ref, &ref, NULL) == 0.0);
    const double ks[] = {0.5, 0.1, 0.01, -0.25};
    for (size_t j = 0; j < sizeof ks / sizeof ks[0]; j++) {
        for (size_t i = 0; i < (size_t)31 * 17 * 3; i++) test.rgb[i] = (float)((double)ref.rgb[i] * (1.0 + ks[j]));
        /* t = r (1 + k)  =>  sqrt(sum k^2 r^2 / sum r^2) = |k| (up to float storage of t). */
        assert_near(glow_eval_rel_rmse(&test, &ref, NULL), fabs(ks[j]), 1e-6 * fabs(ks[j]) + 1e-9);
    }
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
}

static void test_rel_rmse_hand_2x2(void **state) {
    (void)state;
    glow_eval_image ref = make_image(2, 2), test = make_image(2, 2);
    const float r[12] = {1, 1, 1, 2, 2, 2, 0, 0, 0, 1, 0, 0};
    const float t[12] = {1, 1, 1, 2, 2, 3, 1, 0, 0, 1, 0, 0};
    memcpy(ref.rgb, r, sizeof r);
    memcpy(test.rgb, t, sizeof t);
    /* sum (t-r)^2 = 1 + 1 = 2; sum r^2 = 3 + 12 + 0 + 1 = 16. */
    assert_near(glow_eval_rel_rmse(&test, &ref, NULL), sqrt(2.0 / 16.0), 1e-12);
    /* Masking pixel 2 (the (1,0,0) vs (0,0,0) one) leaves sum (t-r)^2 = 1, sum r^2 = 16. */
    const uint8_t mask[4] = {1, 1, 0, 1};
    assert_near(glow_eval_rel_rmse(&test, &ref, mask), 0.25, 1e-12);
    /* Masking pixel 1 instead: 1 / (3 + 0 + 1). */
    const uint8_t mask2[4] = {1, 0, 1, 1};
    assert_near(glow_eval_rel_rmse(&test, &ref, mask2), 0.5, 1e-12);
    /* A black reference: 0 when identical, +inf otherwise. */
    glow_eval_image zero = make_image(2, 2);
    assert_true(glow_eval_rel_rmse(&zero, &zero, NULL) == 0.0);
    assert_true(isinf(glow_eval_rel_rmse(&test, &zero, NULL)));
    glow_eval_image_free(&zero);
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
}

/* ---- display RMSE / PSNR ---- */

static void test_psnr_known_offset(void **state) {
    (void)state;
    const float exposure = 2.5f;
    glow_eval_image ref = make_image(16, 9), test = make_image(16, 9);
    lcg_state = 7;
    /* Every channel: display(ref) = v, display(test) = v + 0.1 (v in [0.1, 0.8]) => rmse 0.1 => 20 dB. */
    for (size_t i = 0; i < (size_t)16 * 9 * 3; i++) {
        double v = 0.1 + 0.7 * lcg01();
        ref.rgb[i] = (float)(srgb_decode(v) / exposure);
        test.rgb[i] = (float)(srgb_decode(v + 0.1) / exposure);
    }
    assert_near(glow_eval_psnr(&test, &ref, NULL, exposure), 20.0, 1e-4);
    assert_near(glow_eval_psnr(&ref, &test, NULL, exposure), 20.0, 1e-4);
    glow_eval_metrics m;
    char msg[256];
    assert_int_equal(glow_eval_compare(&test, &ref, NULL, exposure, &m, msg, sizeof msg), GLOW_OK);
    assert_near(m.rmse_display, 0.1, 1e-5);
    assert_near(m.psnr_db, 20.0, 1e-4);

    /* Half the pixels differ by 0.2 in every channel, half not at all: mean square 0.02. */
    for (size_t p = 0; p < (size_t)16 * 9; p++)
        for (int c = 0; c < 3; c++) {
            double v = 0.3 + 0.01 * c;
            ref.rgb[3 * p + c] = (float)(srgb_decode(v) / exposure);
            test.rgb[3 * p + c] = (float)(srgb_decode(p % 2 ? v + 0.2 : v) / exposure);
        }
    assert_near(glow_eval_psnr(&test, &ref, NULL, exposure), 20.0 * log10(1.0 / sqrt(0.02)), 1e-4);

    /* Identical => +inf; values beyond the clamp (both display 1, both 0) count as identical. */
    assert_true(isinf(glow_eval_psnr(&ref, &ref, NULL, exposure)) && glow_eval_psnr(&ref, &ref, NULL, exposure) > 0);
    fill_grey(&ref, 1.0f);
    fill_grey(&test, 50.0f);
    assert_true(isinf(glow_eval_psnr(&test, &ref, NULL, exposure)));
    fill_grey(&ref, -1.0f);
    fill_grey(&test, 0.0f);
    assert_true(isinf(glow_eval_psnr(&test, &ref, NULL, exposure)));
    /* All black vs all white: display error 1 => 0 dB; exposure scales. */
    fill_grey(&ref, 0.0f);
    fill_grey(&test, 0.4f);
    assert_near(glow_eval_psnr(&test, &ref, NULL, exposure), 0.0, 1e-9);
    assert_near(glow_eval_psnr(&test, &ref, NULL, 1.0f), -20.0 * log10(1.055 * pow(0.4, 1 / 2.4) - 0.055), 1e-5);
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
}

/* ---- SSIM ---- */

static void test_ssim_identity_and_constant(void **state) {
    (void)state;
    glow_eval_image a = make_image(40, 30), b = make_image(40, 30);
    fill_pattern(&a);
    assert_near(glow_eval_ssim(&a, &a, NULL, 1.0f), 1.0, 1e-12);
    /* Constant grey images with display values x and y: zero variance everywhere, so
     * SSIM = (2xy + C1) / (x^2 + y^2 + C1) (luma of grey = the grey value). */
    const double pairs[][2] = {{0.5, 0.6}, {0.2, 0.8}, {0.9, 0.1}, {0.0, 0.3}};
    for (size_t k = 0; k < sizeof pairs / sizeof pairs[0]; k++) {
        double x = pairs[k][0], y = pairs[k][1];
        fill_grey(&a, (float)srgb_decode(x));
        fill_grey(&b, (float)srgb_decode(y));
        double want = (2 * x * y + 1e-4) / (x * x + y * y + 1e-4);
        assert_near(glow_eval_ssim(&a, &b, NULL, 1.0f), want, 1e-5);
    }
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
}

static void test_ssim_matches_brute_force(void **state) {
    (void)state;
    /* Sizes smaller and larger than the window exercise the clipping at every border. */
    const uint32_t sizes[][2] = {{23, 17}, {7, 4}, {1, 13}, {12, 1}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        uint32_t W = sizes[s][0], H = sizes[s][1];
        glow_eval_image a = make_image(W, H), b = make_image(W, H);
        fill_pattern(&a);
        lcg_state = 1234 + (uint32_t)s;
        for (size_t i = 0; i < (size_t)W * H * 3; i++) b.rgb[i] = a.rgb[i] * (float)(0.6 + 0.8 * lcg01());
        double got = glow_eval_ssim(&a, &b, NULL, 1.7f), want = ssim_brute(&a, &b, NULL, (double)1.7f);
        assert_near(got, want, 1e-9);
        assert_true(got < 0.999);
        /* With a mask: only the selected centres are averaged. */
        uint8_t *mask = malloc((size_t)W * H);
        assert_non_null(mask);
        for (size_t i = 0; i < (size_t)W * H; i++) mask[i] = (uint8_t)(i % 3 != 1);
        assert_near(glow_eval_ssim(&a, &b, mask, 1.7f), ssim_brute(&a, &b, mask, (double)1.7f), 1e-9);
        free(mask);
        glow_eval_image_free(&a);
        glow_eval_image_free(&b);
    }
}

static void test_ssim_monotonic_and_symmetric(void **state) {
    (void)state;
    glow_eval_image a = make_image(48, 32), b = make_image(48, 32);
    fill_pattern(&a);
    double noise[48 * 32 * 3];
    lcg_state = 99;
    for (size_t i = 0; i < sizeof noise / sizeof noise[0]; i++) noise[i] = lcg01() - 0.5;
    const double amp[] = {0.0, 0.01, 0.03, 0.1, 0.3};
    double prev = 2.0;
    for (size_t k = 0; k < sizeof amp / sizeof amp[0]; k++) {
        for (size_t i = 0; i < sizeof noise / sizeof noise[0]; i++) b.rgb[i] = a.rgb[i] + (float)(amp[k] * noise[i]);
        double s = glow_eval_ssim(&b, &a, NULL, 1.0f);
        assert_true(s < prev);
        assert_true(s <= 1.0 && s > -1.0);
        assert_near(s, glow_eval_ssim(&a, &b, NULL, 1.0f), 1e-12); /* symmetric */
        prev = s;
    }
    assert_true(prev < 0.8);
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
}

/* ---- block error and mean ratio ---- */

/* Block error per glow_eval.h, written directly: for each block the means of its unmasked pixels,
 * weighted by their count. */
static double block_error_brute(const glow_eval_image *t, const glow_eval_image *r, const uint8_t *mask, uint32_t b) {
    double num = 0, den = 0;
    for (uint32_t by = 0; by < r->height; by += b)
        for (uint32_t bx = 0; bx < r->width; bx += b) {
            double st[3] = {0, 0, 0}, sr[3] = {0, 0, 0}, n = 0;
            for (uint32_t y = by; y < by + b && y < r->height; y++)
                for (uint32_t x = bx; x < bx + b && x < r->width; x++) {
                    size_t i = (size_t)y * r->width + x;
                    if (mask && !mask[i]) continue;
                    for (int c = 0; c < 3; c++) st[c] += t->rgb[3 * i + c], sr[c] += r->rgb[3 * i + c];
                    n++;
                }
            if (n == 0) continue;
            for (int c = 0; c < 3; c++) {
                num += n * (st[c] / n - sr[c] / n) * (st[c] / n - sr[c] / n);
                den += n * (sr[c] / n) * (sr[c] / n);
            }
        }
    return sqrt(num / den);
}

static void test_block_error_hand(void **state) {
    (void)state;
    /* 3 x 3 grey images; test = ref + delta:
     *   ref  1 2 3     delta  +1 -1 +2
     *        3 4 5            +1 +1  0
     *        6 7 8             0 +3 -4
     * 2 x 2 blocks: A (4 px) ref mean 2.5, delta mean 0.5; B (right column, 2 px) 4, 1;
     * C (bottom row, 2 px) 6.5, 1.5; D (corner, 1 px) 8, -4. Per channel
     *   Σ n (ΔT)² = 4·0.25 + 2·1 + 2·2.25 + 16 = 23.5,  Σ n R² = 4·6.25 + 2·16 + 2·42.25 + 64 = 205.5. */
    glow_eval_image ref = make_image(3, 3), test = make_image(3, 3);
    const float r[9] = {1, 2, 3, 3, 4, 5, 6, 7, 8}, d[9] = {1, -1, 2, 1, 1, 0, 0, 3, -4};
    for (int i = 0; i < 9; i++)
        for (int c = 0; c < 3; c++) ref.rgb[3 * i + c] = r[i], test.rgb[3 * i + c] = r[i] + d[i];
    assert_near(glow_eval_block_error(&test, &ref, NULL, 2), sqrt(23.5 / 205.5), 1e-12);
    /* One block (3 x 3, or any larger size: a single partial block): ref mean 39/9, delta mean 3/9:
     * (1/3) / (13/3) = 1/13. */
    assert_near(glow_eval_block_error(&test, &ref, NULL, 3), 1.0 / 13.0, 1e-12);
    assert_near(glow_eval_block_error(&test, &ref, NULL, 100), 1.0 / 13.0, 1e-12);
    /* 1 x 1 blocks are rel_rmse: Σ δ² = 33, Σ r² = 213. */
    assert_near(glow_eval_block_error(&test, &ref, NULL, 1), sqrt(33.0 / 213.0), 1e-12);
    assert_near(glow_eval_block_error(&test, &ref, NULL, 1), glow_eval_rel_rmse(&test, &ref, NULL), 1e-12);
    /* Mask out (0,0) and the corner (2,2): A keeps 3 px (ref 2,3,4 mean 3; delta -1,+1,+1 mean 1/3),
     * D is skipped: Σ n ΔT² = 3/9 + 2 + 4.5, Σ n R² = 27 + 32 + 84.5. */
    const uint8_t mask[9] = {0, 1, 1, 1, 1, 1, 1, 1, 0};
    assert_near(glow_eval_block_error(&test, &ref, mask, 2), sqrt((1.0 / 3 + 6.5) / 143.5), 1e-12);
    /* Mean ratio: Σ test / Σ ref = 42 / 39; with the mask 36 / 30. */
    assert_near(glow_eval_mean_ratio(&test, &ref, NULL), 42.0 / 39.0, 1e-12);
    assert_near(glow_eval_mean_ratio(&test, &ref, mask), 1.2, 1e-12);
    /* Block size 0 = the default 8: one partial block here. */
    assert_near(glow_eval_block_error(&test, &ref, NULL, 0), 1.0 / 13.0, 1e-12);
    /* Channels count separately: a colour error that cancels in the grey sum still counts. */
    memcpy(test.rgb, ref.rgb, sizeof(float) * 27);
    for (int i = 0; i < 9; i++) test.rgb[3 * i] += 1.0f, test.rgb[3 * i + 2] -= 1.0f;
    /* one block, per channel R mean error 1, G 0, B -1: sqrt(9 (1 + 1) / (9 · 3 (39/9)²)). */
    assert_near(glow_eval_block_error(&test, &ref, NULL, 3), sqrt(2.0 / (3.0 * (39.0 / 9) * (39.0 / 9))), 1e-12);
    assert_near(glow_eval_mean_ratio(&test, &ref, NULL), 1.0, 1e-12);
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
}

static void test_block_error_offset_scale_noise(void **state) {
    (void)state;
    /* 20 x 13 in 8 x 8 blocks: 3 x 2 blocks, the last column 4 wide and the last row 5 high. */
    const uint32_t W = 20, H = 13;
    glow_eval_image ref = make_image(W, H), test = make_image(W, H);
    /* A uniform offset d on a constant reference r: every block mean is off by d: d / r. */
    fill_grey(&ref, 0.5f);
    fill_grey(&test, 0.5f + 0.0625f);
    assert_near(glow_eval_block_error(&test, &ref, NULL, 8), 0.125, 1e-12);
    assert_near(glow_eval_mean_ratio(&test, &ref, NULL), 1.125, 1e-12);
    /* On a pattern: d over the pixel-weighted RMS of the reference's block means. */
    fill_pattern(&ref);
    const float d = 0.03f;
    for (size_t i = 0; i < (size_t)W * H * 3; i++) test.rgb[i] = ref.rgb[i] + d;
    double rms = 0, n = 0;
    for (uint32_t by = 0; by < H; by += 8)
        for (uint32_t bx = 0; bx < W; bx += 8) {
            uint32_t bw = bx + 8 <= W ? 8 : W - bx, bh = by + 8 <= H ? 8 : H - by;
            for (int c = 0; c < 3; c++) {
                double s = 0;
                for (uint32_t y = by; y < by + bh; y++)
                    for (uint32_t x = bx; x < bx + bw; x++) s += ref.rgb[((size_t)y * W + x) * 3 + c];
                rms += (double)bw * bh * (s / (bw * bh)) * (s / (bw * bh));
                n += (double)bw * bh;
            }
        }
    rms = sqrt(rms / n);
    assert_near(glow_eval_block_error(&test, &ref, NULL, 8), d / rms, 1e-6 * d / rms);
    double sum_r = 0, sum_t = 0;
    for (size_t i = 0; i < (size_t)W * H * 3; i++) sum_r += ref.rgb[i], sum_t += test.rgb[i];
    assert_near(glow_eval_mean_ratio(&test, &ref, NULL), sum_t / sum_r, 1e-12);
    /* A uniform scale (1 + k): |k| at every block size. */
    for (size_t i = 0; i < (size_t)W * H * 3; i++) test.rgb[i] = (float)((double)ref.rgb[i] * 0.9);
    for (uint32_t b = 1; b <= 32; b *= 2) assert_near(glow_eval_block_error(&test, &ref, NULL, b), 0.1, 1e-6);
    assert_near(glow_eval_mean_ratio(&test, &ref, NULL), 0.9, 1e-6);
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
    /* Noise that averages out within each 8 x 8 block (a ±e checkerboard) does not count; the
     * per-pixel rel_rmse sees it. */
    glow_eval_image r2 = make_image(16, 24), t2 = make_image(16, 24);
    fill_grey(&r2, 0.25f);
    for (uint32_t y = 0; y < 24; y++)
        for (uint32_t x = 0; x < 16; x++)
            for (int c = 0; c < 3; c++) t2.rgb[((size_t)y * 16 + x) * 3 + c] = ((x + y) % 2) ? 0.3125f : 0.1875f;
    assert_true(glow_eval_block_error(&t2, &r2, NULL, 8) == 0.0);
    assert_near(glow_eval_rel_rmse(&t2, &r2, NULL), 0.25, 1e-12);
    assert_near(glow_eval_mean_ratio(&t2, &r2, NULL), 1.0, 1e-12);
    glow_eval_image_free(&r2);
    glow_eval_image_free(&t2);
}

static void test_block_error_brute_force(void **state) {
    (void)state;
    const uint32_t sizes[][2] = {{37, 21}, {8, 8}, {1, 19}, {9, 1}};
    const uint32_t blocks[] = {1, 2, 3, 8, 16, 40};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        uint32_t W = sizes[s][0], H = sizes[s][1];
        glow_eval_image ref = make_image(W, H), test = make_image(W, H);
        fill_pattern(&ref);
        lcg_state = 40 + (uint32_t)s;
        for (size_t i = 0; i < (size_t)W * H * 3; i++) test.rgb[i] = ref.rgb[i] * (float)(0.7 + 0.6 * lcg01());
        uint8_t *mask = malloc((size_t)W * H);
        assert_non_null(mask);
        for (size_t i = 0; i < (size_t)W * H; i++) mask[i] = (uint8_t)(lcg01() < 0.7);
        mask[0] = 1;
        for (size_t k = 0; k < sizeof blocks / sizeof blocks[0]; k++) {
            uint32_t b = blocks[k];
            assert_near(glow_eval_block_error(&test, &ref, NULL, b), block_error_brute(&test, &ref, NULL, b), 1e-12);
            assert_near(glow_eval_block_error(&test, &ref, mask, b), block_error_brute(&test, &ref, mask, b), 1e-12);
        }
        assert_near(glow_eval_block_error(&test, &ref, mask, 1), glow_eval_rel_rmse(&test, &ref, mask), 1e-12);
        free(mask);
        glow_eval_image_free(&ref);
        glow_eval_image_free(&test);
    }
}

static void test_block_error_edge_cases(void **state) {
    (void)state;
    glow_eval_image a = make_image(5, 4), b = make_image(5, 4), z = make_image(5, 4), w = make_image(4, 5);
    fill_grey(&a, 0.5f);
    fill_grey(&b, 0.25f);
    /* Black reference: 0 when the test is black too, else +inf; mean ratio 1 or ±inf. */
    assert_true(glow_eval_block_error(&z, &z, NULL, 8) == 0.0);
    assert_true(isinf(glow_eval_block_error(&a, &z, NULL, 8)));
    assert_true(glow_eval_mean_ratio(&z, &z, NULL) == 1.0);
    assert_true(isinf(glow_eval_mean_ratio(&a, &z, NULL)) && glow_eval_mean_ratio(&a, &z, NULL) > 0);
    fill_grey(&b, -0.25f);
    assert_true(isinf(glow_eval_mean_ratio(&b, &z, NULL)) && glow_eval_mean_ratio(&b, &z, NULL) < 0);
    /* NAN: size mismatch, NULL, non-finite pixels, a mask leaving nothing. */
    assert_true(isnan(glow_eval_block_error(&a, &w, NULL, 8)));
    assert_true(isnan(glow_eval_mean_ratio(&a, &w, NULL)));
    assert_true(isnan(glow_eval_block_error(NULL, &a, NULL, 8)));
    uint8_t none[20] = {0};
    assert_true(isnan(glow_eval_block_error(&a, &b, none, 8)));
    assert_true(isnan(glow_eval_mean_ratio(&a, &b, none)));
    b.rgb[4] = NAN;
    assert_true(isnan(glow_eval_block_error(&a, &b, NULL, 8)));
    assert_true(isnan(glow_eval_mean_ratio(&b, &a, NULL)));
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
    glow_eval_image_free(&z);
    glow_eval_image_free(&w);
}

/* ---- masks ---- */

/* Blotches (glow_eval_blotches): a 12 x 4 image of twelve 2 x 2 texels in a 6 x 2 layout, grey 1
 * everywhere in the reference. Texel (i, j) covers pixels [2i, 2i+1] x [2j, 2j+1], id (i + 1, j + 1).
 * and cache 100 + 6 j + i. Errors: texel (0,0) +0.6 alone; (2,0) and (3,0) +0.8 and +0.7 side by side (one blotch of 2);
 * (2,1) -0.9 under (2,0) (opposite sign: its own set); (5,1) +0.4 (under the threshold). */
static void set_texel(glow_eval_image *img, uint32_t i, uint32_t j, float v, int channel_id) {
    for (uint32_t y = 2 * j; y < 2 * j + 2; y++)
        for (uint32_t x = 2 * i; x < 2 * i + 2; x++) {
            float *p = img->rgb + 3 * ((size_t)y * img->width + x);
            if (channel_id) {
                p[0] = (float)(i + 1);
                p[1] = (float)(j + 1);
                p[2] = (float)(100 + 6 * j + i + 1); /* cache 100 + 6 j + i */
            } else
                p[0] = p[1] = p[2] = v;
        }
}

static void test_blotches_hand(void **state) {
    (void)state;
    glow_eval_image ref = make_image(12, 4), test = make_image(12, 4), tex = make_image(12, 4);
    fill_grey(&ref, 1.0f);
    fill_grey(&test, 1.0f);
    for (uint32_t j = 0; j < 2; j++)
        for (uint32_t i = 0; i < 6; i++) set_texel(&tex, i, j, 0.0f, 1);
    set_texel(&test, 0, 0, 1.6f, 0);
    set_texel(&test, 2, 0, 1.8f, 0);
    set_texel(&test, 3, 0, 1.7f, 0);
    set_texel(&test, 2, 1, 0.1f, 0);
    set_texel(&test, 5, 1, 1.4f, 0);
    glow_eval_blotch_result b;
    char msg[256];
    const glow_eval_blotch_params p4 = {.threshold = 0.5, .min_pixels = 4};
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, &p4, &b, msg, sizeof msg), GLOW_OK);
    assert_int_equal(b.texels, 12);
    assert_int_equal(b.judged, 12);
    assert_int_equal(b.bad, 4);
    assert_int_equal(b.blotches, 1);
    assert_int_equal(b.judged_pixels, 48);
    assert_int_equal(b.bad_pixels, 16);
    assert_int_equal(b.blotch_pixels, 8);
    assert_int_equal(b.largest_texels, 2);
    assert_int_equal(b.largest_pixels, 8);
    assert_near(b.largest_rel, 0.75, 1e-6);
    assert_int_equal(b.largest_box[0], 4);
    assert_int_equal(b.largest_box[1], 0);
    assert_int_equal(b.largest_box[2], 7);
    assert_int_equal(b.largest_box[3], 1);
    assert_near(b.worst_rel, -0.9, 1e-6);
    assert_int_equal(b.largest_cache_count, 2);
    assert_int_equal(b.largest_caches[0], 102); /* ties in pixels: the lower texel first */
    assert_int_equal(b.largest_caches[1], 103);
    /* A lower threshold takes in (5,1) (alone: no new blotch); a higher one leaves (0,0) and (3,0) out, so
     * no set has two texels. */
    glow_eval_blotch_params p = {.threshold = 0.3, .min_pixels = 4};
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, &p, &b, msg, sizeof msg), GLOW_OK);
    assert_int_equal(b.bad, 5);
    assert_int_equal(b.blotches, 1);
    p.threshold = 0.75;
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, &p, &b, msg, sizeof msg), GLOW_OK);
    assert_int_equal(b.bad, 2);
    assert_int_equal(b.blotches, 0);
    assert_int_equal(b.largest_texels, 1);
    /* Texels seen by fewer pixels than min_pixels are not judged (default 16 > 4 here). */
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, NULL, &b, msg, sizeof msg), GLOW_OK);
    assert_int_equal(b.texels, 12);
    assert_int_equal(b.judged, 0);
    assert_int_equal(b.bad, 0);
    assert_int_equal(b.largest_texels, 0);
    /* (3,0) made negative: it no longer joins (2,0). */
    set_texel(&test, 3, 0, 0.3f, 0);
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, &p4, &b, msg, sizeof msg), GLOW_OK);
    assert_int_equal(b.blotches, 0);
    assert_int_equal(b.bad, 4);
    /* The same texel id on two places of the screen is one texel: (3,0)'s pixels get (2,0)'s id, so
     * (2,0) now has 8 pixels at +0.8 and +(-0.7): +0.05, not bad. */
    set_texel(&tex, 3, 0, 0.0f, 1);
    for (uint32_t y = 0; y < 2; y++)
        for (uint32_t x = 6; x < 8; x++) tex.rgb[3 * ((size_t)y * 12 + x)] = 3.0f;
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, &p4, &b, msg, sizeof msg), GLOW_OK);
    assert_int_equal(b.texels, 11);
    assert_int_equal(b.bad, 2);
    /* Pixels with no texel (id 0) are left out; a non-finite pixel or a size mismatch is an error. */
    fill_grey(&tex, 0.0f);
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, &p4, &b, msg, sizeof msg), GLOW_OK);
    assert_int_equal(b.texels, 0);
    assert_int_equal(b.bad, 0);
    test.rgb[5] = NAN;
    assert_int_equal(glow_eval_blotches(&test, &ref, &tex, &p4, &b, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "test image pixel (1, 0)"));
    glow_eval_image small = make_image(2, 2);
    assert_int_equal(glow_eval_blotches(&small, &ref, &tex, &p4, &b, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_blotches(&test, &ref, NULL, &p4, &b, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    glow_eval_image_free(&small);
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
    glow_eval_image_free(&tex);
}

static void test_mask_excludes_pixels(void **state) {
    (void)state;
    const uint32_t W = 40, H = 24;
    glow_eval_image ref = make_image(W, H), test = make_image(W, H);
    fill_pattern(&ref);
    for (size_t i = 0; i < (size_t)W * H * 3; i++) test.rgb[i] = ref.rgb[i] * 1.1f + 0.01f;
    uint8_t mask[40 * 24];
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) mask[y * W + x] = (uint8_t)(x < 20); /* left half */
    glow_eval_metrics m0, m1;
    char msg[256];
    assert_int_equal(glow_eval_compare(&test, &ref, mask, 1.5f, &m0, msg, sizeof msg), GLOW_OK);
    assert_int_equal(m0.pixels, 20 * 24);

    /* Change masked-out pixels far (> 5 px) from every unmasked centre: nothing may change,
     * SSIM included (its windows only reach 5 px). */
    glow_eval_image test2 = make_image(W, H);
    memcpy(test2.rgb, test.rgb, sizeof(float) * W * H * 3);
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 30; x < W; x++)
            for (int c = 0; c < 3; c++) test2.rgb[((size_t)y * W + x) * 3 + c] = 100.0f * (float)(x + y);
    assert_int_equal(glow_eval_compare(&test2, &ref, mask, 1.5f, &m1, msg, sizeof msg), GLOW_OK);
    assert_true(m0.rel_rmse == m1.rel_rmse);
    assert_true(m0.rmse_display == m1.rmse_display);
    assert_true(m0.psnr_db == m1.psnr_db);
    assert_true(m0.ssim == m1.ssim);
    assert_true(m0.block_error == m1.block_error);
    assert_true(m0.mean_ratio == m1.mean_ratio);
    for (int c = 0; c < 3; c++) {
        assert_true(m0.mean_test[c] == m1.mean_test[c]);
        assert_true(m0.mean_ref[c] == m1.mean_ref[c]);
    }
    /* Change a masked-out pixel right next to the unmasked half: HDR and display metrics stay the
     * same; SSIM changes (windows still read masked pixels — documented). */
    memcpy(test2.rgb, test.rgb, sizeof(float) * W * H * 3);
    test2.rgb[((size_t)5 * W + 20) * 3 + 1] = 50.0f;
    assert_int_equal(glow_eval_compare(&test2, &ref, mask, 1.5f, &m1, msg, sizeof msg), GLOW_OK);
    assert_true(m0.rel_rmse == m1.rel_rmse && m0.psnr_db == m1.psnr_db);
    assert_true(m1.ssim < m0.ssim);
    /* Without the mask the same change does show up in every metric. */
    glow_eval_metrics a, b;
    assert_int_equal(glow_eval_compare(&test, &ref, NULL, 1.5f, &a, msg, sizeof msg), GLOW_OK);
    assert_int_equal(glow_eval_compare(&test2, &ref, NULL, 1.5f, &b, msg, sizeof msg), GLOW_OK);
    assert_true(b.rel_rmse > a.rel_rmse && b.psnr_db < a.psnr_db);
    assert_int_equal(a.pixels, W * H);

    /* An all-zero mask leaves nothing to compare. */
    memset(mask, 0, sizeof mask);
    assert_int_equal(glow_eval_compare(&test, &ref, mask, 1.5f, &m1, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_true(isnan(glow_eval_rel_rmse(&test, &ref, mask)));
    assert_true(isnan(glow_eval_psnr(&test, &ref, mask, 1.0f)));
    assert_true(isnan(glow_eval_ssim(&test, &ref, mask, 1.0f)));
    glow_eval_image_free(&test2);
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
}

/* ---- glow_eval_compare agrees with the individual functions ---- */

static void test_compare_consistent(void **state) {
    (void)state;
    glow_eval_image ref = make_image(33, 21), test = make_image(33, 21);
    fill_pattern(&ref);
    lcg_state = 5;
    for (size_t i = 0; i < (size_t)33 * 21 * 3; i++) test.rgb[i] = ref.rgb[i] + (float)(0.05 * (lcg01() - 0.5));
    glow_eval_metrics m;
    char msg[256] = "";
    assert_int_equal(glow_eval_compare(&test, &ref, NULL, 0.8f, &m, msg, sizeof msg), GLOW_OK);
    assert_true(m.rel_rmse == glow_eval_rel_rmse(&test, &ref, NULL));
    assert_true(m.psnr_db == glow_eval_psnr(&test, &ref, NULL, 0.8f));
    assert_true(m.ssim == glow_eval_ssim(&test, &ref, NULL, 0.8f));
    assert_true(m.block_error == glow_eval_block_error(&test, &ref, NULL, 8));
    assert_int_equal(m.block_size, 8);
    assert_true(m.mean_ratio == glow_eval_mean_ratio(&test, &ref, NULL));
    assert_true(m.block_error > 0 && m.block_error < m.rel_rmse); /* the noise averages out in blocks */
    assert_near(m.psnr_db, 20 * log10(1 / m.rmse_display), 1e-9);
    assert_int_equal(m.pixels, 33 * 21);
    for (int c = 0; c < 3; c++) {
        double sr = 0, st = 0;
        for (size_t p = 0; p < (size_t)33 * 21; p++) sr += ref.rgb[3 * p + c], st += test.rgb[3 * p + c];
        assert_near(m.mean_ref[c], sr / (33 * 21), 1e-12);
        assert_near(m.mean_test[c], st / (33 * 21), 1e-12);
    }
    glow_eval_image_free(&ref);
    glow_eval_image_free(&test);
}

/* ---- errors ---- */

static void test_invalid_arguments(void **state) {
    (void)state;
    glow_eval_image a = make_image(4, 3), b = make_image(3, 4), c = make_image(4, 3);
    fill_grey(&a, 0.5f);
    fill_grey(&b, 0.5f);
    fill_grey(&c, 0.25f);
    glow_eval_metrics m;
    char msg[256] = "";
    assert_int_equal(glow_eval_compare(&a, &b, NULL, 1.0f, &m, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "size mismatch"));
    assert_true(isnan(glow_eval_rel_rmse(&a, &b, NULL)));
    assert_true(isnan(glow_eval_psnr(&a, &b, NULL, 1.0f)));
    assert_true(isnan(glow_eval_ssim(&a, &b, NULL, 1.0f)));
    assert_true(isnan(glow_eval_rel_rmse(NULL, &a, NULL)));
    assert_true(isnan(glow_eval_ssim(&a, NULL, NULL, 1.0f)));
    assert_int_equal(glow_eval_compare(NULL, &a, NULL, 1.0f, &m, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_compare(&a, &c, NULL, 1.0f, NULL, NULL, 0), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_compare(&a, &c, NULL, NAN, &m, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_compare(&a, &c, NULL, INFINITY, &m, NULL, 0), GLOW_ERROR_INVALID_ARGUMENT);
    assert_true(isnan(glow_eval_psnr(&a, &c, NULL, NAN)));
    /* Non-finite pixels: compare names the image, the pixel and the channel; metrics are NAN. */
    c.rgb[(1 * 4 + 2) * 3 + 1] = NAN;
    assert_int_equal(glow_eval_compare(&a, &c, NULL, 1.0f, &m, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "reference image pixel (2, 1) channel G is NaN"));
    assert_true(isnan(glow_eval_rel_rmse(&a, &c, NULL)));
    assert_true(isnan(glow_eval_ssim(&c, &a, NULL, 1.0f)));
    c.rgb[(1 * 4 + 2) * 3 + 1] = 0.25f;
    a.rgb[2] = -INFINITY;
    assert_int_equal(glow_eval_compare(&a, &c, NULL, 1.0f, &m, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "test image pixel (0, 0) channel B is infinite"));
    a.rgb[2] = 0.5f;
    assert_int_equal(glow_eval_compare(&a, &c, NULL, 1.0f, &m, msg, sizeof msg), GLOW_OK);
    /* Alloc / free edge cases. */
    glow_eval_image z;
    assert_int_equal(glow_eval_image_alloc(&z, 0, 5), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(z.rgb);
    assert_int_equal(glow_eval_image_alloc(NULL, 1, 1), GLOW_ERROR_INVALID_ARGUMENT);
    glow_eval_image_free(&z);
    glow_eval_image_free(NULL);
    glow_eval_image_free(&a);
    assert_null(a.rgb);
    assert_int_equal(a.width, 0);
    glow_eval_image_free(&a); /* twice is fine */
    glow_eval_image_free(&b);
    glow_eval_image_free(&c);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb_encode),
        cmocka_unit_test(test_rel_rmse_identity_and_scale),
        cmocka_unit_test(test_rel_rmse_hand_2x2),
        cmocka_unit_test(test_psnr_known_offset),
        cmocka_unit_test(test_ssim_identity_and_constant),
        cmocka_unit_test(test_ssim_matches_brute_force),
        cmocka_unit_test(test_ssim_monotonic_and_symmetric),
        cmocka_unit_test(test_block_error_hand),
        cmocka_unit_test(test_block_error_offset_scale_noise),
        cmocka_unit_test(test_block_error_brute_force),
        cmocka_unit_test(test_block_error_edge_cases),
        cmocka_unit_test(test_blotches_hand),
        cmocka_unit_test(test_mask_excludes_pixels),
        cmocka_unit_test(test_compare_consistent),
        cmocka_unit_test(test_invalid_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
