/* metrics.c — the error metrics of glow_eval.h (relative HDR RMSE, display RMSE / PSNR, SSIM, block
 * error of block means, mean ratio; FLIP is in flip.c).
 * Sums in double. Non-finite pixels anywhere in either image make the individual metric functions
 * return NAN and glow_eval_compare fail with GLOW_ERROR_INVALID_ARGUMENT naming the first one. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eval_internal.h"
#include "glow_eval.h"

#define SSIM_RADIUS 5 /* 11 x 11 window */
#define SSIM_SIGMA 1.5
#define SSIM_C1 (0.01 * 0.01) /* (K1 L)^2, L = 1 */
#define SSIM_C2 (0.03 * 0.03) /* (K2 L)^2 */

#define set_message glow__eval_set_message

/* IEC 61966-2-1 encoding of a linear value clamped to [0,1] (NaN -> 0), in double. */
static double encode_d(double x) {
    if (!(x > 0.0)) return 0.0;
    if (x >= 1.0) return 1.0;
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

float glow_eval_srgb_encode(float linear) { return (float)encode_d((double)linear); }

static double display_d(float v, double exposure) { return encode_d((double)v * exposure); }

static int image_ok(const glow_eval_image *img) { return img && img->rgb && img->width > 0 && img->height > 0; }

static int same_size(const glow_eval_image *a, const glow_eval_image *b) {
    return a->width == b->width && a->height == b->height;
}

/* Index of the first non-finite float, or SIZE_MAX. */
static size_t first_nonfinite(const glow_eval_image *img) {
    size_t n = (size_t)img->width * img->height * 3;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(img->rgb[i])) return i;
    return SIZE_MAX;
}

typedef struct sums {
    double err2, ref2, disp_err2;
    double ref[3], test[3];
    uint64_t pixels;
} sums;

static void accumulate(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask, double exposure,
                       int want_display, sums *s) {
    memset(s, 0, sizeof *s);
    size_t n = (size_t)test->width * test->height;
    for (size_t i = 0; i < n; i++) {
        if (mask && !mask[i]) continue;
        const float *t = test->rgb + 3 * i, *r = ref->rgb + 3 * i;
        for (int c = 0; c < 3; c++) {
            double d = (double)t[c] - (double)r[c];
            s->err2 += d * d;
            s->ref2 += (double)r[c] * r[c];
            s->ref[c] += r[c];
            s->test[c] += t[c];
            if (want_display) {
                double dd = display_d(t[c], exposure) - display_d(r[c], exposure);
                s->disp_err2 += dd * dd;
            }
        }
        s->pixels++;
    }
}

static double rel_rmse_of(const sums *s) {
    if (s->pixels == 0) return NAN;
    if (s->ref2 == 0.0) return s->err2 == 0.0 ? 0.0 : INFINITY;
    return sqrt(s->err2 / s->ref2);
}

static double rmse_display_of(const sums *s) {
    return s->pixels ? sqrt(s->disp_err2 / (3.0 * (double)s->pixels)) : NAN;
}

static double psnr_of(double rmse) {
    if (isnan(rmse)) return NAN;
    return rmse == 0.0 ? INFINITY : 20.0 * log10(1.0 / rmse);
}

/* Display luma Y' of row y into out[width]. */
static void luma_row(const glow_eval_image *img, uint32_t y, double exposure, double *out) {
    const float *p = img->rgb + (size_t)y * img->width * 3;
    for (uint32_t x = 0; x < img->width; x++, p += 3)
        out[x] = 0.2126 * display_d(p[0], exposure) + 0.7152 * display_d(p[1], exposure) +
                 0.0722 * display_d(p[2], exposure);
}

/* Mean SSIM over the unmasked window centres. The window's Gaussian is separable and a clipped
 * window is a rectangle, so filtering rows then columns, each renormalised by the weights that fall
 * inside the image, equals the renormalised clipped 2D window. Horizontal results of the last 11
 * rows live in a ring buffer: memory O(width). Returns GLOW_ERROR_OUT_OF_MEMORY or GLOW_OK. */
static glow_result ssim_compute(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                                double exposure, double *out) {
    enum { K = 2 * SSIM_RADIUS + 1, M = 5 }; /* moments: x, y, xx, yy, xy */
    const uint32_t W = test->width, H = test->height;
    double g[K];
    for (int d = -SSIM_RADIUS; d <= SSIM_RADIUS; d++)
        g[d + SSIM_RADIUS] = exp(-(double)(d * d) / (2.0 * SSIM_SIGMA * SSIM_SIGMA));

    double *buf = malloc(sizeof(double) * (size_t)W * (2 + (size_t)K * M));
    if (!buf) return GLOW_ERROR_OUT_OF_MEMORY;
    double *lx = buf, *ly = buf + W, *ring = buf + 2 * (size_t)W; /* ring[(slot * M + m) * W + x] */

    double total = 0.0;
    uint64_t count = 0;
    int64_t next_row = 0; /* first row whose horizontal pass is not yet in the ring */
    for (uint32_t y = 0; y < H; y++) {
        int64_t y_lo = (int64_t)y - SSIM_RADIUS < 0 ? 0 : (int64_t)y - SSIM_RADIUS;
        int64_t y_hi = (int64_t)y + SSIM_RADIUS >= H ? (int64_t)H - 1 : (int64_t)y + SSIM_RADIUS;
        for (; next_row <= y_hi; next_row++) {
            luma_row(test, (uint32_t)next_row, exposure, lx);
            luma_row(ref, (uint32_t)next_row, exposure, ly);
            double *h = ring + (size_t)(next_row % K) * M * W;
            for (uint32_t x = 0; x < W; x++) {
                int64_t x_lo = (int64_t)x - SSIM_RADIUS < 0 ? 0 : (int64_t)x - SSIM_RADIUS;
                int64_t x_hi = (int64_t)x + SSIM_RADIUS >= W ? (int64_t)W - 1 : (int64_t)x + SSIM_RADIUS;
                double ws = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
                for (int64_t i = x_lo; i <= x_hi; i++) {
                    double w = g[i - (int64_t)x + SSIM_RADIUS], a = lx[i], b = ly[i];
                    ws += w;
                    sx += w * a;
                    sy += w * b;
                    sxx += w * a * a;
                    syy += w * b * b;
                    sxy += w * a * b;
                }
                h[0 * (size_t)W + x] = sx / ws;
                h[1 * (size_t)W + x] = sy / ws;
                h[2 * (size_t)W + x] = sxx / ws;
                h[3 * (size_t)W + x] = syy / ws;
                h[4 * (size_t)W + x] = sxy / ws;
            }
        }
        double wsum = 0;
        for (int64_t j = y_lo; j <= y_hi; j++) wsum += g[j - (int64_t)y + SSIM_RADIUS];
        for (uint32_t x = 0; x < W; x++) {
            if (mask && !mask[(size_t)y * W + x]) continue;
            double m[M] = {0, 0, 0, 0, 0};
            for (int64_t j = y_lo; j <= y_hi; j++) {
                double w = g[j - (int64_t)y + SSIM_RADIUS];
                const double *h = ring + (size_t)(j % K) * M * W + x;
                for (int k = 0; k < M; k++) m[k] += w * h[(size_t)k * W];
            }
            for (int k = 0; k < M; k++) m[k] /= wsum;
            double mx = m[0], my = m[1];
            double vx = m[2] - mx * mx, vy = m[3] - my * my, cxy = m[4] - mx * my;
            if (vx < 0) vx = 0; /* rounding */
            if (vy < 0) vy = 0;
            double s = ((2.0 * mx * my + SSIM_C1) * (2.0 * cxy + SSIM_C2)) /
                       ((mx * mx + my * my + SSIM_C1) * (vx + vy + SSIM_C2));
            total += s;
            count++;
        }
    }
    free(buf);
    *out = count ? total / (double)count : NAN;
    return GLOW_OK;
}

/* Block error (see glow_eval.h): one row of blocks at a time, per block column the test and
 * reference sums of each channel and the unmasked pixel count. Memory O(width / block). Returns
 * GLOW_ERROR_OUT_OF_MEMORY or GLOW_OK; *out is NAN when no pixel is unmasked. */
static glow_result block_error_compute(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                                       uint32_t bs, double *out) {
    enum { S = 7 }; /* test RGB, reference RGB, count */
    const uint32_t W = test->width, H = test->height;
    const size_t nbx = ((size_t)W + bs - 1) / bs;
    double *acc = malloc(sizeof(double) * S * nbx);
    if (!acc) return GLOW_ERROR_OUT_OF_MEMORY;
    double num = 0.0, den = 0.0;
    uint64_t pixels = 0;
    for (uint32_t y0 = 0; y0 < H; y0 += bs) {
        memset(acc, 0, sizeof(double) * S * nbx);
        uint32_t y1 = H - y0 < bs ? H : y0 + bs;
        for (uint32_t y = y0; y < y1; y++)
            for (uint32_t x = 0; x < W; x++) {
                size_t i = (size_t)y * W + x;
                if (mask && !mask[i]) continue;
                double *a = acc + S * (size_t)(x / bs);
                for (int c = 0; c < 3; c++) {
                    a[c] += test->rgb[3 * i + c];
                    a[3 + c] += ref->rgb[3 * i + c];
                }
                a[6] += 1.0;
            }
        for (size_t b = 0; b < nbx; b++) {
            const double *a = acc + S * b, n = a[6];
            if (n == 0.0) continue;
            for (int c = 0; c < 3; c++) {
                double t = a[c] / n, r = a[3 + c] / n;
                num += n * (t - r) * (t - r);
                den += n * r * r;
            }
            pixels += (uint64_t)n;
        }
    }
    free(acc);
    if (pixels == 0) *out = NAN;
    else if (den == 0.0) *out = num == 0.0 ? 0.0 : INFINITY;
    else *out = sqrt(num / den);
    return GLOW_OK;
}

static double mean_ratio_of(const sums *s) {
    if (s->pixels == 0) return NAN;
    double t = s->test[0] + s->test[1] + s->test[2], r = s->ref[0] + s->ref[1] + s->ref[2];
    if (r == 0.0) return t == 0.0 ? 1.0 : t > 0.0 ? INFINITY : -INFINITY;
    return t / r;
}

/* Shared argument checks of the individual metric functions. */
static int metric_args_ok(const glow_eval_image *test, const glow_eval_image *ref) {
    return image_ok(test) && image_ok(ref) && same_size(test, ref) && first_nonfinite(test) == SIZE_MAX &&
           first_nonfinite(ref) == SIZE_MAX;
}

double glow_eval_rel_rmse(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask) {
    if (!metric_args_ok(test, ref)) return NAN;
    sums s;
    accumulate(test, ref, mask, 1.0, 0, &s);
    return rel_rmse_of(&s);
}

double glow_eval_psnr(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask, float exposure) {
    if (!metric_args_ok(test, ref) || !isfinite(exposure)) return NAN;
    sums s;
    accumulate(test, ref, mask, (double)exposure, 1, &s);
    return psnr_of(rmse_display_of(&s));
}

double glow_eval_ssim(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask, float exposure) {
    if (!metric_args_ok(test, ref) || !isfinite(exposure)) return NAN;
    double v = NAN;
    if (ssim_compute(test, ref, mask, (double)exposure, &v) != GLOW_OK) return NAN;
    return v;
}

double glow_eval_block_error(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                             uint32_t block_size) {
    if (!metric_args_ok(test, ref)) return NAN;
    double v = NAN;
    if (block_error_compute(test, ref, mask, block_size ? block_size : GLOW_EVAL_BLOCK_SIZE, &v) != GLOW_OK) return NAN;
    return v;
}

double glow_eval_mean_ratio(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask) {
    if (!metric_args_ok(test, ref)) return NAN;
    sums s;
    accumulate(test, ref, mask, 1.0, 0, &s);
    return mean_ratio_of(&s);
}

glow_result glow_eval_compare(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                              float exposure, glow_eval_metrics *out, char *message, size_t message_size) {
    if (out) memset(out, 0, sizeof *out);
    if (!out || !image_ok(test) || !image_ok(ref)) {
        set_message(message, message_size, "compare: NULL or empty %s", !out ? "output" : !image_ok(test) ? "test image"
                                                                                                          : "reference image");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!same_size(test, ref)) {
        set_message(message, message_size, "compare: size mismatch (test %ux%u, reference %ux%u)",
                    (unsigned)test->width, (unsigned)test->height, (unsigned)ref->width, (unsigned)ref->height);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!isfinite(exposure)) {
        set_message(message, message_size, "compare: exposure %g is not finite", (double)exposure);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const glow_eval_image *imgs[2] = {test, ref};
    static const char *const names[2] = {"test image", "reference image"};
    for (int k = 0; k < 2; k++) {
        size_t i = first_nonfinite(imgs[k]);
        if (i != SIZE_MAX) {
            size_t p = i / 3;
            set_message(message, message_size, "compare: %s pixel (%u, %u) channel %c is %s", names[k],
                        (unsigned)(p % imgs[k]->width), (unsigned)(p / imgs[k]->width), "RGB"[i % 3],
                        isnan(imgs[k]->rgb[i]) ? "NaN" : "infinite");
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    }
    sums s;
    accumulate(test, ref, mask, (double)exposure, 1, &s);
    if (s.pixels == 0) {
        set_message(message, message_size, "compare: the mask leaves no pixel to compare");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    double ssim = NAN, block = NAN;
    if (ssim_compute(test, ref, mask, (double)exposure, &ssim) != GLOW_OK ||
        block_error_compute(test, ref, mask, GLOW_EVAL_BLOCK_SIZE, &block) != GLOW_OK) {
        set_message(message, message_size, "compare: out of memory");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    out->rel_rmse = rel_rmse_of(&s);
    out->rmse_display = rmse_display_of(&s);
    out->psnr_db = psnr_of(out->rmse_display);
    out->ssim = ssim;
    for (int c = 0; c < 3; c++) {
        out->mean_ref[c] = s.ref[c] / (double)s.pixels;
        out->mean_test[c] = s.test[c] / (double)s.pixels;
    }
    out->pixels = s.pixels;
    out->block_error = block;
    out->block_size = GLOW_EVAL_BLOCK_SIZE;
    out->mean_ratio = mean_ratio_of(&s);
    return GLOW_OK;
}
