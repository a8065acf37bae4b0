/* test_flip.c — LDR-FLIP and HDR-FLIP of glow_eval (tools/eval/flip.c) against the published
 * definitions: the filters' normalisations, closed forms for constant images (where the filters
 * drop out and FLIP is the colour term alone), an independent brute-force implementation that
 * follows NVlabs/flip's Python version (python/flip_api.py: full 2D filters, double precision), the
 * exposure range of HDR-FLIP, and properties (0 for identical images, [0,1], symmetry, monotonic
 * growth with the distortion).
 *
 * Published values reproduced here (each test says which):
 *   - default 67.02 pixels per degree = 0.7 m from a 0.7 m wide 3840-pixel monitor (FLIP paper §5,
 *     NVlabs/flip FLIP.h Parameters: calculatePPD(0.7, 3840, 0.7)), filter radii 10 and 9 pixels;
 *   - c_max is the distance between pure green and pure blue, so FLIP(green, blue) = 1 exactly
 *     (FLIP paper §4.1, "the maximum error ... green and blue");
 *   - p_c / p_t remap: an error of p_c c_max maps to p_t = 0.95;
 *   - the ACES tone mapper maps x_max = 2.1189 to 0.85 ([H] §3, FLIP.h computeExposures);
 *   - the exposure count max(2, ceil(stop - start)): NVlabs/flip's test (flip_evaluator/tests/
 *     test.py) names its HDR result "...hdr.aces.m12.5423_to_p0.9427.14.png": 14 exposures from
 *     -12.5423 to 0.9427.
 * Not reproduced: the repository's mean FLIP of its reference/test images (LDR 0.159691, HDR
 * 0.283478): the images are not available here. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "glow_eval.h"

#define PI 3.14159265358979323846

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

static void fill_rgb(glow_eval_image *img, double r, double g, double b) {
    for (size_t i = 0; i < (size_t)img->width * img->height; i++) {
        img->rgb[3 * i] = (float)r;
        img->rgb[3 * i + 1] = (float)g;
        img->rgb[3 * i + 2] = (float)b;
    }
}

static uint32_t lcg_state;
static double lcg01(void) {
    lcg_state = lcg_state * 1664525u + 1013904223u;
    return (double)(lcg_state >> 8) / 16777216.0;
}

/* Smooth colourful pattern with edges, values in [0, 1] * scale. */
static void fill_pattern(glow_eval_image *img, double scale) {
    for (uint32_t y = 0; y < img->height; y++)
        for (uint32_t x = 0; x < img->width; x++) {
            float *p = img->rgb + ((size_t)y * img->width + x) * 3;
            p[0] = (float)(scale * (0.5 + 0.4 * sin(0.45 * x) * cos(0.3 * y)));
            p[1] = (float)(scale * (0.3 + 0.3 * (double)x / img->width + 0.1 * ((x / 5 + y / 4) % 2)));
            p[2] = (float)(scale * (0.1 + 0.6 * (double)((x / 3 + y / 6) % 2)));
        }
}

static glow_eval_flip_result run_flip(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                                      glow_eval_flip_params p, float *map) {
    glow_eval_flip_result r;
    char msg[256] = "";
    glow_result res = glow_eval_flip(test, ref, mask, &p, map, &r, msg, sizeof msg);
    if (res != GLOW_OK) print_error("glow_eval_flip: %s\n", msg);
    assert_int_equal(res, GLOW_OK);
    return r;
}

/* ---- an independent implementation, written from python/flip_api.py (2D filters, double) ---- */

static const double M_RGB2XYZ[3][3] = {{10135552.0 / 24577794, 8788810.0 / 24577794, 4435075.0 / 24577794},
                                       {2613072.0 / 12288897, 8788810.0 / 12288897, 887015.0 / 12288897},
                                       {1425312.0 / 73733382, 8788810.0 / 73733382, 70074185.0 / 73733382}};
static const double M_XYZ2RGB[3][3] = {{3.241003275, -1.537398934, -0.498615861},
                                       {-0.969224334, 1.875930071, 0.041554224},
                                       {0.055639423, -0.204011202, 1.057148933}};
static const double ILL[3] = {0.950428545, 1.0, 1.088900371};

static void ref_hunt_lab(const double rgb[3], double out[3]) {
    double f[3];
    for (int i = 0; i < 3; i++) {
        double t = (M_RGB2XYZ[i][0] * rgb[0] + M_RGB2XYZ[i][1] * rgb[1] + M_RGB2XYZ[i][2] * rgb[2]) / ILL[i];
        const double d = 6.0 / 29.0;
        f[i] = t > d * d * d ? cbrt(t) : t / (3 * d * d) + 4.0 / 29.0;
    }
    double L = 116 * f[1] - 16;
    out[0] = L;
    out[1] = 0.01 * L * 500 * (f[0] - f[1]);
    out[2] = 0.01 * L * 200 * (f[1] - f[2]);
}

static double ref_hyab(const double a[3], const double b[3]) {
    return fabs(a[0] - b[0]) + hypot(a[1] - b[1], a[2] - b[2]);
}

static double ref_cmax(void) {
    const double g[3] = {0, 1, 0}, b[3] = {0, 0, 1};
    double lg[3], lb[3];
    ref_hunt_lab(g, lg);
    ref_hunt_lab(b, lb);
    return pow(ref_hyab(lg, lb), 0.7);
}

/* flip_api.py redistribute_errors (p_c = 0.4, p_t = 0.95). */
static double ref_remap(double e) {
    double cmax = ref_cmax(), pccmax = 0.4 * cmax;
    return e < pccmax ? 0.95 / pccmax * e : 0.95 + (e - pccmax) / (cmax - pccmax) * 0.05;
}

/* FLIP of two constant images: the filters sum to 1 and leave them constant, features are 0, so
 * FLIP = the remapped colour term of the two colours. */
static double ref_flip_constant(const double a[3], const double b[3]) {
    double la[3], lb[3];
    ref_hunt_lab(a, la);
    ref_hunt_lab(b, lb);
    return ref_remap(pow(ref_hyab(la, lb), 0.7));
}

/* Correlation of plane src (W x H) with a (2r+1)^2 kernel, clamp-to-edge borders (cv.filter2D with
 * BORDER_REPLICATE). */
static void filter2d(const double *src, int W, int H, const double *k, int r, double *dst) {
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double s = 0;
            for (int j = -r; j <= r; j++)
                for (int i = -r; i <= r; i++) {
                    int xx = x + i < 0 ? 0 : x + i >= W ? W - 1 : x + i;
                    int yy = y + j < 0 ? 0 : y + j >= H ? H - 1 : y + j;
                    s += k[(j + r) * (2 * r + 1) + (i + r)] * src[yy * W + xx];
                }
            dst[y * W + x] = s;
        }
}

/* LDR-FLIP map of two linear-RGB images in [0,1] (interleaved double), as flip_api.py
 * compute_ldrflip (without its sRGB round trip). */
static void ref_ldr_flip(const double *refrgb, const double *testrgb, int W, int H, double ppd, double *map) {
    const int N = W * H;
    const double a1[3] = {1, 1, 34.1}, b1[3] = {0.0047, 0.0053, 0.04};
    const double a2[3] = {0, 0, 13.5}, b2[3] = {1e-5, 1e-5, 0.025};
    int r = (int)ceil(3 * sqrt(0.04 / (2 * PI * PI)) * ppd), n = 2 * r + 1;
    double sd = 0.5 * 0.082 * ppd;
    int rf = (int)ceil(3 * sd), nf = 2 * rf + 1;
    double *csf = malloc(sizeof(double) * 3 * n * n), *edge = malloc(sizeof(double) * nf * nf),
           *point = malloc(sizeof(double) * nf * nf), *edge_t = malloc(sizeof(double) * nf * nf),
           *point_t = malloc(sizeof(double) * nf * nf);
    double *ycc = malloc(sizeof(double) * 6 * N), *filt = malloc(sizeof(double) * 6 * N),
           *feat = malloc(sizeof(double) * 8 * N), *yn = malloc(sizeof(double) * 2 * N);
    assert_non_null(csf);
    assert_non_null(edge);
    assert_non_null(point);
    assert_non_null(edge_t);
    assert_non_null(point_t);
    assert_non_null(ycc);
    assert_non_null(filt);
    assert_non_null(feat);
    assert_non_null(yn);
    for (int c = 0; c < 3; c++) { /* generate_spatial_filter */
        double sum = 0;
        for (int j = -r; j <= r; j++)
            for (int i = -r; i <= r; i++) {
                double z = (i / ppd) * (i / ppd) + (j / ppd) * (j / ppd);
                double s = a1[c] * sqrt(PI / b1[c]) * exp(-PI * PI * z / b1[c]) +
                           a2[c] * sqrt(PI / b2[c]) * exp(-PI * PI * z / b2[c]);
                csf[c * n * n + (j + r) * n + (i + r)] = s;
                sum += s;
            }
        for (int k = 0; k < n * n; k++) csf[c * n * n + k] /= sum;
    }
    for (int kind = 0; kind < 2; kind++) { /* feature_detection */
        double *K = kind ? point : edge, *KT = kind ? point_t : edge_t, pos = 0, neg = 0;
        for (int j = -rf; j <= rf; j++)
            for (int i = -rf; i <= rf; i++) {
                double g = exp(-(double)(i * i + j * j) / (2 * sd * sd));
                double v = kind ? ((double)i * i / (sd * sd) - 1) * g : -(double)i * g;
                K[(j + rf) * nf + (i + rf)] = v;
                if (v < 0) neg -= v;
                else pos += v;
            }
        for (int k = 0; k < nf * nf; k++) K[k] = K[k] < 0 ? K[k] / neg : K[k] / pos;
        for (int j = 0; j < nf; j++)
            for (int i = 0; i < nf; i++) KT[j * nf + i] = K[i * nf + j];
    }
    const double *imgs[2] = {refrgb, testrgb};
    for (int im = 0; im < 2; im++)
        for (int p = 0; p < N; p++) {
            double xyz[3];
            for (int i = 0; i < 3; i++)
                xyz[i] = (M_RGB2XYZ[i][0] * imgs[im][3 * p] + M_RGB2XYZ[i][1] * imgs[im][3 * p + 1] +
                          M_RGB2XYZ[i][2] * imgs[im][3 * p + 2]) /
                         ILL[i];
            ycc[(im * 3 + 0) * N + p] = 116 * xyz[1] - 16;
            ycc[(im * 3 + 1) * N + p] = 500 * (xyz[0] - xyz[1]);
            ycc[(im * 3 + 2) * N + p] = 200 * (xyz[1] - xyz[2]);
            yn[im * N + p] = (ycc[(im * 3) * N + p] + 16) / 116;
        }
    for (int im = 0; im < 2; im++) {
        for (int c = 0; c < 3; c++) filter2d(ycc + (im * 3 + c) * N, W, H, csf + c * n * n, r, filt + (im * 3 + c) * N);
        filter2d(yn + im * N, W, H, edge, rf, feat + (im * 4 + 0) * N);
        filter2d(yn + im * N, W, H, edge_t, rf, feat + (im * 4 + 1) * N);
        filter2d(yn + im * N, W, H, point, rf, feat + (im * 4 + 2) * N);
        filter2d(yn + im * N, W, H, point_t, rf, feat + (im * 4 + 3) * N);
    }
    for (int p = 0; p < N; p++) {
        double lab[2][3];
        for (int im = 0; im < 2; im++) {
            double fy = (filt[(im * 3) * N + p] + 16) / 116;
            double xyz[3] = {(fy + filt[(im * 3 + 1) * N + p] / 500) * ILL[0], fy * ILL[1],
                             (fy - filt[(im * 3 + 2) * N + p] / 200) * ILL[2]};
            double rgb[3];
            for (int i = 0; i < 3; i++) {
                double v = M_XYZ2RGB[i][0] * xyz[0] + M_XYZ2RGB[i][1] * xyz[1] + M_XYZ2RGB[i][2] * xyz[2];
                rgb[i] = v < 0 ? 0 : v > 1 ? 1 : v;
            }
            ref_hunt_lab(rgb, lab[im]);
        }
        double dc = ref_remap(pow(ref_hyab(lab[0], lab[1]), 0.7));
        double e0 = hypot(feat[0 * N + p], feat[1 * N + p]), e1 = hypot(feat[4 * N + p], feat[5 * N + p]);
        double p0 = hypot(feat[2 * N + p], feat[3 * N + p]), p1 = hypot(feat[6 * N + p], feat[7 * N + p]);
        double df = pow(fmax(fabs(e0 - e1), fabs(p0 - p1)) / sqrt(2.0), 0.5);
        map[p] = pow(dc, 1 - df);
    }
    free(csf);
    free(edge);
    free(point);
    free(edge_t);
    free(point_t);
    free(ycc);
    free(filt);
    free(feat);
    free(yn);
}

/* ACES fit with the 0.6 pre-exposure, written from the formula in [H] and Narkowicz's post. */
static double ref_aces(double x) {
    x *= 0.6;
    double y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    return y < 0 ? 0 : y > 1 ? 1 : y;
}

/* x with ref_aces(x) = t, by bisection. */
static double ref_aces_inverse(double t) {
    double lo = 0, hi = 100;
    for (int i = 0; i < 200; i++) {
        double mid = 0.5 * (lo + hi);
        if (ref_aces(mid) < t) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* ---- tests ---- */

/* Published: 67 ppd default (0.7 m, 3840 px, 0.7 m); the CSF and feature filters' normalisations. */
static void test_kernels(void **state) {
    (void)state;
    const double ppd = glow_eval_flip_ppd(0.7, 3840, 0.7);
    assert_near(ppd, 3840 * PI / 180, 1e-12);
    assert_near(ppd, 67.0206432765823, 1e-9);
    float w[4][64], f[3][64];
    int rc = 0, rf = 0;
    for (int k = 0; k < 4; k++) {
        rc = glow_eval_flip_kernel((glow_eval_flip_kernel_kind)(GLOW_EVAL_FLIP_KERNEL_CSF_A + k), ppd, w[k], 64);
        assert_int_equal(rc, 10); /* ceil(3 sqrt(0.04 / (2 pi^2)) 67.02) = ceil(9.05) */
    }
    for (int k = 0; k < 3; k++) {
        glow_eval_flip_kernel_kind kind = (glow_eval_flip_kernel_kind)(GLOW_EVAL_FLIP_KERNEL_FEATURE_GAUSS + k);
        rf = glow_eval_flip_kernel(kind, ppd, f[k], 64);
        assert_int_equal(rf, 9); /* sigma = 0.041 * 67.02 = 2.748, ceil(3 sigma) = 9 */
    }
    /* Capacity too small: the radius only. */
    assert_int_equal(glow_eval_flip_kernel(GLOW_EVAL_FLIP_KERNEL_CSF_A, ppd, NULL, 0), 10);
    assert_int_equal(glow_eval_flip_kernel(GLOW_EVAL_FLIP_KERNEL_CSF_A, -1.0, w[0], 64), -1);
    assert_int_equal(glow_eval_flip_kernel((glow_eval_flip_kernel_kind)0, ppd, w[0], 64), -1);
    double s[4] = {0, 0, 0, 0};
    for (int k = 0; k < 4; k++)
        for (int i = 0; i <= 2 * rc; i++) s[k] += w[k][i];
    assert_near(s[0], 1.0, 1e-6);
    assert_near(s[1], 1.0, 1e-6);
    assert_near(s[2] * s[2] + s[3] * s[3], 1.0, 1e-6); /* BY1 x BY1 + BY2 x BY2 sums to 1 */
    /* The A filter is exp(-pi^2 x^2 / 0.0047), x = i / ppd degrees, up to its normalisation. */
    for (int i = 0; i <= 2 * rc; i++) {
        double x = (i - rc) / ppd;
        assert_near(w[0][i] / w[0][rc], exp(-PI * PI * x * x / 0.0047), 1e-6);
        assert_near(w[0][i], w[0][2 * rc - i], 0); /* symmetric */
    }
    /* The BY terms: their ratio at the centre is sqrt(34.1 sqrt(pi/0.04)) / sqrt(13.5 sqrt(pi/0.025)). */
    assert_near(w[2][rc] / w[3][rc], sqrt(34.1 * sqrt(PI / 0.04)) / sqrt(13.5 * sqrt(PI / 0.025)), 1e-5);
    /* Feature filters: Gaussian sums to 1; derivatives' positive weights sum to 1, negative to -1;
     * edge antisymmetric, point symmetric. */
    double g = 0, pe = 0, ne = 0, pp = 0, np = 0;
    for (int i = 0; i <= 2 * rf; i++) {
        g += f[0][i];
        if (f[1][i] > 0) pe += f[1][i];
        else ne += f[1][i];
        if (f[2][i] > 0) pp += f[2][i];
        else np += f[2][i];
        assert_near(f[1][i], -f[1][2 * rf - i], 1e-7);
        assert_near(f[2][i], f[2][2 * rf - i], 1e-7);
    }
    assert_near(g, 1, 1e-6);
    assert_near(pe, 1, 1e-6);
    assert_near(ne, -1, 1e-6);
    assert_near(pp, 1, 1e-6);
    assert_near(np, -1, 1e-6);
    assert_true(f[1][rf - 1] > 0); /* -x g: positive left of the centre */
    assert_true(f[2][rf] < 0);     /* (x^2/s^2 - 1) g: negative at the centre */
}

static void test_identical_is_zero(void **state) {
    (void)state;
    glow_eval_image a = make_image(37, 23);
    fill_pattern(&a, 3.0);
    float map[37 * 23];
    glow_eval_flip_result r = run_flip(&a, &a, NULL, (glow_eval_flip_params){0}, map);
    assert_true(r.mean == 0.0);
    assert_true(r.max == 0.0);
    for (size_t i = 0; i < 37 * 23; i++) assert_true(map[i] == 0.0f);
    r = run_flip(&a, &a, NULL, (glow_eval_flip_params){.ldr = 1}, NULL);
    assert_true(r.mean == 0.0);
    assert_true(glow_eval_hdr_flip(&a, &a, NULL) == 0.0);
    glow_eval_image_free(&a);
}

/* Published: c_max is HyAB(green, blue)^0.7, so green vs blue is 1; p_c c_max maps to p_t. Other
 * constant pairs against the closed form. */
static void test_constant_images(void **state) {
    (void)state;
    glow_eval_image a = make_image(24, 16), b = make_image(24, 16);
    fill_rgb(&a, 0, 1, 0);
    fill_rgb(&b, 0, 0, 1);
    glow_eval_flip_params ldr = {.ldr = 1};
    glow_eval_flip_result r = run_flip(&b, &a, NULL, ldr, NULL);
    assert_near(r.mean, 1.0, 2e-5);
    assert_near(r.max, 1.0, 2e-5);
    /* Black vs white: HyAB = 100 (L only), 100^0.7 = 25.12 > p_c c_max = 16.51: 0.95 + ... = 0.9674. */
    const double black[3] = {0, 0, 0}, white[3] = {1, 1, 1};
    double bw = ref_flip_constant(black, white);
    assert_near(bw, 0.95 + (pow(100.0, 0.7) - 0.4 * ref_cmax()) / (0.6 * ref_cmax()) * 0.05, 1e-4);
    assert_near(bw, 0.96737, 5e-5);
    fill_rgb(&a, 0, 0, 0);
    fill_rgb(&b, 1, 1, 1);
    assert_near(run_flip(&b, &a, NULL, ldr, NULL).mean, bw, 2e-5);
    /* The remap's knee: the colour term at p_c c_max maps to p_t = 0.95, below it linearly. */
    assert_near(ref_remap(0.4 * ref_cmax()), 0.95, 1e-12);
    assert_near(ref_remap(0.2 * ref_cmax()), 0.475, 1e-12);
    /* Random pairs of colours. */
    lcg_state = 3;
    for (int k = 0; k < 12; k++) {
        double ca[3], cb[3];
        for (int c = 0; c < 3; c++) ca[c] = lcg01(), cb[c] = lcg01();
        if (k == 11) cb[0] = ca[0], cb[1] = ca[1] + 0.01, cb[2] = ca[2]; /* a small difference */
        fill_rgb(&a, ca[0], ca[1], ca[2]);
        fill_rgb(&b, cb[0], cb[1], cb[2]);
        double want = ref_flip_constant(ca, cb);
        r = run_flip(&b, &a, NULL, ldr, NULL);
        assert_near(r.mean, want, 1e-4);
        assert_near(r.max, want, 1e-4);
    }
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
}

/* The separable float implementation against the 2D double brute force of flip_api.py. */
static void test_matches_brute_force(void **state) {
    (void)state;
    const uint32_t sizes[][2] = {{29, 19}, {7, 5}, {1, 12}};
    const double ppds[] = {0.0, 20.0, 67.0206432765823};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (size_t q = 0; q < sizeof ppds / sizeof ppds[0]; q++) {
            if (s > 0 && q == 0) continue;
            const int W = (int)sizes[s][0], H = (int)sizes[s][1], N = W * H;
            glow_eval_image a = make_image((uint32_t)W, (uint32_t)H), b = make_image((uint32_t)W, (uint32_t)H);
            fill_pattern(&a, 1.0);
            lcg_state = 11 + (uint32_t)(s * 7 + q);
            for (int i = 0; i < 3 * N; i++) {
                double v = a.rgb[i] * (0.7 + 0.6 * lcg01()) + (i % 17 == 0 ? 0.3 : 0.0);
                b.rgb[i] = (float)(v > 1 ? 1 : v);
            }
            double *ra = malloc(sizeof(double) * 3 * N), *rb = malloc(sizeof(double) * 3 * N),
                   *want = malloc(sizeof(double) * N);
            float *got = malloc(sizeof(float) * N);
            assert_non_null(ra);
            assert_non_null(rb);
            assert_non_null(want);
            assert_non_null(got);
            for (int i = 0; i < 3 * N; i++) ra[i] = a.rgb[i], rb[i] = b.rgb[i];
            double ppd = ppds[q] ? ppds[q] : 67.0206432765823;
            ref_ldr_flip(ra, rb, W, H, ppd, want);
            glow_eval_flip_result r = run_flip(&b, &a, NULL, (glow_eval_flip_params){.ldr = 1, .ppd = ppds[q]}, got);
            double mean = 0, maxdiff = 0;
            for (int i = 0; i < N; i++) {
                mean += want[i];
                maxdiff = fmax(maxdiff, fabs(want[i] - got[i]));
            }
            mean /= N;
            /* float vs double: measured 2.3e-6 at most per pixel, 3.3e-7 on the mean */
            if (maxdiff > 2e-5) print_error("size %dx%d ppd %g: max per-pixel difference %g\n", W, H, ppd, maxdiff);
            assert_true(maxdiff <= 2e-5);
            assert_near(r.mean, mean, 2e-6);
            assert_near(r.ppd, ppd, 1e-12);
            assert_true(r.mean > 0.01);
            free(ra);
            free(rb);
            free(want);
            free(got);
            glow_eval_image_free(&a);
            glow_eval_image_free(&b);
        }
}

/* HDR-FLIP is the per-pixel maximum of LDR-FLIP over the ACES-tone-mapped exposures. */
static void test_hdr_is_max_over_exposures(void **state) {
    (void)state;
    const uint32_t W = 31, H = 21, N = W * H;
    glow_eval_image a = make_image(W, H), b = make_image(W, H), ta = make_image(W, H), tb = make_image(W, H);
    fill_pattern(&a, 5.0);
    a.rgb[3 * 40] = 60.0f; /* a bright pixel widens the exposure range */
    lcg_state = 77;
    for (size_t i = 0; i < 3 * N; i++) b.rgb[i] = a.rgb[i] * (float)(0.8 + 0.4 * lcg01());
    b.rgb[7] = -0.5f; /* negatives count as 0 */
    float hdr[31 * 21], ldr[31 * 21], mx[31 * 21];
    glow_eval_flip_result r = run_flip(&b, &a, NULL, (glow_eval_flip_params){0}, hdr);
    assert_true(r.num_exposures >= 2);
    assert_int_equal(r.num_exposures, (int)fmax(2, ceil(r.stop_exposure - r.start_exposure)));
    memset(mx, 0, sizeof mx);
    double step = (r.stop_exposure - r.start_exposure) / (r.num_exposures - 1);
    for (int e = 0; e < r.num_exposures; e++) {
        double scale = exp2(r.start_exposure + e * step);
        for (size_t i = 0; i < 3 * N; i++) {
            ta.rgb[i] = (float)glow_eval_flip_aces((double)a.rgb[i] * scale);
            tb.rgb[i] = (float)glow_eval_flip_aces((double)b.rgb[i] * scale);
            assert_near(ta.rgb[i], ref_aces(a.rgb[i] > 0 ? a.rgb[i] * scale : 0), 1e-6);
        }
        run_flip(&tb, &ta, NULL, (glow_eval_flip_params){.ldr = 1}, ldr);
        for (size_t i = 0; i < N; i++) mx[i] = fmaxf(mx[i], ldr[i]);
    }
    double mean = 0;
    for (size_t i = 0; i < N; i++) {
        assert_near(hdr[i], mx[i], 1e-7);
        mean += mx[i];
    }
    assert_near(r.mean, mean / N, 1e-9);
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
    glow_eval_image_free(&ta);
    glow_eval_image_free(&tb);
}

/* Published: x_max = 2.1189 maps to 0.85; start/stop from Y_max and the median; the count rule
 * (NVlabs/flip's test: -12.5423 .. 0.9427 -> 14 exposures). */
static void test_hdr_exposures(void **state) {
    (void)state;
    const double xmax = ref_aces_inverse(0.85);
    assert_near(xmax, 2.1189, 1e-4);
    assert_near(glow_eval_flip_aces(xmax), 0.85, 1e-9);
    assert_near(glow_eval_flip_aces(1e30), 1.0, 0);
    assert_near(glow_eval_flip_aces(-5), 0.0, 0);
    assert_near(glow_eval_flip_aces(0.18), ref_aces(0.18), 1e-12);
    /* 5 x 1 grey image: luminances 0.5, 1, 2, 4, 16 -> Y_max 16, median (index 2) 2. */
    glow_eval_image a = make_image(5, 1), b = make_image(5, 1);
    const float v[5] = {1, 0.5f, 16, 2, 4};
    for (int i = 0; i < 5; i++) a.rgb[3 * i] = a.rgb[3 * i + 1] = a.rgb[3 * i + 2] = v[i];
    memcpy(b.rgb, a.rgb, sizeof(float) * 15);
    b.rgb[0] = 1.5f;
    glow_eval_flip_result r = run_flip(&b, &a, NULL, (glow_eval_flip_params){0}, NULL);
    assert_near(r.start_exposure, log2(xmax / 16), 1e-6);
    assert_near(r.stop_exposure, log2(xmax / 2), 1e-6);
    assert_int_equal(r.num_exposures, 3); /* max(2, ceil(3)) */
    /* Even count: the element at index n/2 (the upper median, as FLIP.h's nth_element). */
    glow_eval_image c = make_image(4, 1), d = make_image(4, 1);
    const float u[4] = {8, 1, 2, 4};
    for (int i = 0; i < 4; i++) c.rgb[3 * i] = c.rgb[3 * i + 1] = c.rgb[3 * i + 2] = u[i];
    fill_rgb(&d, 1, 1, 1);
    r = run_flip(&d, &c, NULL, (glow_eval_flip_params){0}, NULL);
    assert_near(r.start_exposure, log2(xmax / 8), 1e-6);
    assert_near(r.stop_exposure, log2(xmax / 4), 1e-6);
    assert_int_equal(r.num_exposures, 2); /* max(2, ceil(1)) */
    /* A mask restricts the luminances: pixels 1..2 only -> Y 1 and 2, max 2, median 2. */
    const uint8_t mask[4] = {0, 1, 1, 0};
    r = run_flip(&d, &c, mask, (glow_eval_flip_params){0}, NULL);
    assert_near(r.start_exposure, log2(xmax / 2), 1e-6);
    assert_near(r.stop_exposure, log2(xmax / 2), 1e-6);
    assert_int_equal(r.num_exposures, 1); /* empty range: one exposure */
    assert_int_equal(r.pixels, 2);
    /* Over half black: the median of the non-zero luminances (0, 0, 0, 1, 4 -> 1 and 4 -> 4). */
    const float z[5] = {0, 0, 4, 0, 1};
    for (int i = 0; i < 5; i++) a.rgb[3 * i] = a.rgb[3 * i + 1] = a.rgb[3 * i + 2] = z[i];
    r = run_flip(&b, &a, NULL, (glow_eval_flip_params){0}, NULL);
    assert_near(r.start_exposure, log2(xmax / 4), 1e-6);
    assert_near(r.stop_exposure, log2(xmax / 4), 1e-6);
    /* A black reference: start = stop = 0, one exposure. */
    fill_rgb(&a, 0, 0, 0);
    r = run_flip(&b, &a, NULL, (glow_eval_flip_params){0}, NULL);
    assert_true(r.start_exposure == 0 && r.stop_exposure == 0);
    assert_int_equal(r.num_exposures, 1);
    assert_true(r.mean > 0.1);
    /* NVlabs/flip tests/test.py: -12.5423 to 0.9427 gives 14 exposures. */
    r = run_flip(&b, &a, NULL,
                 (glow_eval_flip_params){.fixed_exposures = 1, .start_exposure = -12.5423, .stop_exposure = 0.9427},
                 NULL);
    assert_int_equal(r.num_exposures, 14);
    r = run_flip(&b, &a, NULL,
                 (glow_eval_flip_params){.fixed_exposures = 1, .start_exposure = -1, .stop_exposure = 2,
                                         .num_exposures = 7},
                 NULL);
    assert_int_equal(r.num_exposures, 7);
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
    glow_eval_image_free(&c);
    glow_eval_image_free(&d);
}

/* [0,1], LDR symmetry, growth with the distortion, masks. */
static void test_properties(void **state) {
    (void)state;
    const uint32_t W = 48, H = 32, N = W * H;
    glow_eval_image a = make_image(W, H), b = make_image(W, H);
    fill_pattern(&a, 2.0);
    double noise[48 * 32 * 3];
    lcg_state = 5;
    for (size_t i = 0; i < 3 * N; i++) noise[i] = lcg01() - 0.5;
    const double amp[] = {0.0, 0.02, 0.05, 0.15, 0.4, 1.0};
    double prev_hdr = -1, prev_ldr = -1;
    float map[48 * 32];
    for (size_t k = 0; k < sizeof amp / sizeof amp[0]; k++) {
        for (size_t i = 0; i < 3 * N; i++) b.rgb[i] = (float)(a.rgb[i] * (1.0 + amp[k] * noise[i]));
        glow_eval_flip_result h = run_flip(&b, &a, NULL, (glow_eval_flip_params){0}, map);
        for (size_t i = 0; i < N; i++) assert_true(map[i] >= 0.0f && map[i] <= 1.0f);
        assert_true(h.mean > prev_hdr);
        prev_hdr = h.mean;
        /* LDR-FLIP is symmetric in its two images. */
        glow_eval_flip_result l1 = run_flip(&b, &a, NULL, (glow_eval_flip_params){.ldr = 1, .ppd = 30}, NULL);
        glow_eval_flip_result l2 = run_flip(&a, &b, NULL, (glow_eval_flip_params){.ldr = 1, .ppd = 30}, NULL);
        assert_near(l1.mean, l2.mean, 1e-12);
        assert_true(l1.mean > prev_ldr);
        prev_ldr = l1.mean;
        /* HDR-FLIP is not symmetric (the exposures come from the reference), but close here. */
        glow_eval_flip_result h2 = run_flip(&a, &b, NULL, (glow_eval_flip_params){0}, NULL);
        assert_near(h.mean, h2.mean, 0.25 * h.mean + 1e-12);
    }
    assert_true(prev_hdr > 0.1); /* 0.141 at +-50 % per-channel noise */
    /* Random images over a wide range stay in [0, 1]. */
    lcg_state = 9;
    for (size_t i = 0; i < 3 * N; i++) a.rgb[i] = (float)pow(10.0, 4 * lcg01() - 2), b.rgb[i] = (float)lcg01();
    glow_eval_flip_result h = run_flip(&b, &a, NULL, (glow_eval_flip_params){0}, map);
    for (size_t i = 0; i < N; i++) assert_true(map[i] >= 0.0f && map[i] <= 1.0f);
    assert_true(h.max <= 1.0 && h.mean > 0.1);
    /* A uniform scale of the whole image: larger factors, larger error. */
    fill_pattern(&a, 2.0);
    double prev = 0;
    const double scale[] = {1.05, 1.2, 1.5, 2.5};
    for (size_t k = 0; k < 4; k++) {
        for (size_t i = 0; i < 3 * N; i++) b.rgb[i] = (float)(a.rgb[i] * scale[k]);
        double m = glow_eval_hdr_flip(&b, &a, NULL);
        assert_true(m > prev);
        prev = m;
    }
    /* Mask: the mean over the unmasked pixels of the same map (the exposures come from them too,
     * so use fixed exposures to compare maps). */
    uint8_t mask[48 * 32];
    for (size_t i = 0; i < N; i++) mask[i] = (uint8_t)(i % W < 20);
    glow_eval_flip_params fixed = {.fixed_exposures = 1, .start_exposure = -2, .stop_exposure = 1};
    run_flip(&b, &a, NULL, fixed, map);
    glow_eval_flip_result m = run_flip(&b, &a, mask, fixed, NULL);
    double sum = 0;
    for (size_t i = 0; i < N; i++) sum += mask[i] ? map[i] : 0.0;
    assert_near(m.mean, sum / (20 * H), 1e-9);
    assert_int_equal(m.pixels, 20 * H);
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
}

static void test_errors(void **state) {
    (void)state;
    glow_eval_image a = make_image(6, 4), b = make_image(4, 6), c = make_image(6, 4);
    fill_rgb(&a, 0.5, 0.5, 0.5);
    fill_rgb(&b, 0.5, 0.5, 0.5);
    fill_rgb(&c, 0.25, 0.5, 0.5);
    glow_eval_flip_result r;
    char msg[256] = "";
    assert_int_equal(glow_eval_flip(&a, &b, NULL, NULL, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "size mismatch"));
    assert_int_equal(glow_eval_flip(NULL, &a, NULL, NULL, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_flip(&a, &c, NULL, NULL, NULL, NULL, NULL, 0), GLOW_ERROR_INVALID_ARGUMENT);
    c.rgb[(2 * 6 + 3) * 3 + 2] = NAN;
    assert_int_equal(glow_eval_flip(&a, &c, NULL, NULL, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "reference image pixel (3, 2) channel B is NaN"));
    assert_true(isnan(glow_eval_hdr_flip(&a, &c, NULL)));
    c.rgb[(2 * 6 + 3) * 3 + 2] = 0.5f;
    uint8_t mask[24] = {0};
    assert_int_equal(glow_eval_flip(&a, &c, mask, NULL, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "mask"));
    glow_eval_flip_params p = {.ppd = -3};
    assert_int_equal(glow_eval_flip(&a, &c, NULL, &p, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    p = (glow_eval_flip_params){.fixed_exposures = 1, .start_exposure = 2, .stop_exposure = 1};
    assert_int_equal(glow_eval_flip(&a, &c, NULL, &p, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    p = (glow_eval_flip_params){.num_exposures = -1};
    assert_int_equal(glow_eval_flip(&a, &c, NULL, &p, NULL, &r, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_flip(&a, &c, NULL, NULL, NULL, &r, msg, sizeof msg), GLOW_OK);
    assert_true(r.mean > 0 && r.mean <= 1);
    glow_eval_image_free(&a);
    glow_eval_image_free(&b);
    glow_eval_image_free(&c);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kernels),
        cmocka_unit_test(test_identical_is_zero),
        cmocka_unit_test(test_constant_images),
        cmocka_unit_test(test_matches_brute_force),
        cmocka_unit_test(test_hdr_is_max_over_exposures),
        cmocka_unit_test(test_hdr_exposures),
        cmocka_unit_test(test_properties),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
