/* flip.c — LDR-FLIP and HDR-FLIP of glow_eval.h, written from the papers:
 *
 *   [F]  P. Andersson, J. Nilsson, T. Akenine-Möller, M. Oskarsson, K. Åström, M. D. Fairchild,
 *        "FLIP: A Difference Evaluator for Alternating Images", HPG 2020 (PACMCGIT 3(2)).
 *   [H]  P. Andersson, J. Nilsson, P. Shirley, T. Akenine-Möller, "Visualizing Errors in Rendered
 *        High Dynamic Range Images", Eurographics 2021 short papers.
 *
 * Constants are those of the reference implementation, NVlabs/flip (BSD-3-Clause), read in its
 * flip_evaluator/cpp/FLIP.h (v1.4+, "FLIP.h" below) and python/flip_api.py (v1.1, "flip_api.py");
 * each constant below names where it comes from. No code is copied; this is a C re-derivation that
 * follows the same arithmetic (float planes, same filter radii, same clamp-to-edge borders), so that
 * per-pixel values agree with the reference to float rounding.
 *
 * Pipeline of one LDR-FLIP evaluation (inputs: linear RGB in [0,1]):
 *   colour:  linear RGB -> XYZ (D65) -> YCxCz [F §4.1]; each opponent channel convolved with its
 *            contrast sensitivity filter (a Gaussian, a sum of two for blue-yellow), separably;
 *            -> XYZ -> linear RGB, clamped to [0,1] -> CIELAB -> Hunt-adjusted (a, b scaled by
 *            0.01 L) -> HyAB distance -> ^q_c -> the compressed remap with p_c, p_t and c_max.
 *   feature: normalised achromatic channel (Y+16)/116 of the *unfiltered* YCxCz, convolved with the
 *            1st (edges) and 2nd (points) derivative of a Gaussian in x and y [F §4.2]; the
 *            difference of the gradient magnitudes, ΔE_f = (max(edge, point) / √2)^q_f.
 *   FLIP    = ΔE_c^(1 − ΔE_f).
 * The 2D filters are separable exactly (a Gaussian is a product; the blue-yellow sum of two
 * Gaussians is the sum of two separable filters; the derivative filters are a 1D derivative times a
 * 1D Gaussian, each normalised on its own as the 2D normalisation factors into them), so each is
 * applied as a horizontal then a vertical 1D pass over planar float rows.
 *
 * HDR-FLIP [H]: for each exposure c in [c_start, c_stop] (evenly spaced, n of them), both images are
 * scaled by 2^c, tone mapped by the ACES filmic fit of Narkowicz (2016) with the 0.6 pre-exposure
 * folded into the coefficients, clamped to [0,1], and LDR-FLIP is computed; HDR-FLIP is the
 * per-pixel maximum. c_start = log2(x_max / Y_max), c_stop = log2(x_max / Y_median) of the
 * reference's luminance, x_max the input the tone mapper maps to t = 0.85, n = max(2, ceil(c_stop −
 * c_start)). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glow_cli.h"
#include "eval_internal.h"
#include "glow_eval.h"

#define FLIP_PI 3.14159265358979323846

/* ---- constants ---- */

/* [F] eq. 4 / FLIP.h xFLIPConstants: q_c = 0.7 (colour exponent), p_c = 0.4, p_t = 0.95 (error
 * compression), w = 0.082 degrees (peak-to-trough width of the edge detector, 2 standard
 * deviations), q_f = 0.5 (feature exponent). */
#define FLIP_QC 0.7f
#define FLIP_PC 0.4f
#define FLIP_PT 0.95f
#define FLIP_W 0.082
#define FLIP_QF 0.5f

/* [F] Table 1 / FLIP.h xGaussianConstants: CSF of each opponent channel as
 * a1 sqrt(pi/b1) exp(-pi^2 x^2 / b1) + a2 sqrt(pi/b2) exp(-pi^2 x^2 / b2), x in degrees.
 * Achromatic (A, on Y) and red-green (RG, on Cx) have a2 = 0; blue-yellow (BY, on Cz) is a sum. The
 * b2 = 1e-5 of A and RG only enters the radius (flip_api.py: "avoid division by 0"). */
static const double CSF_A1[3] = {1.0, 1.0, 34.1};
static const double CSF_B1[3] = {0.0047, 0.0053, 0.04};
static const double CSF_A2[3] = {0.0, 0.0, 13.5};
static const double CSF_B2[3] = {1e-5, 1e-5, 0.025};

/* D65 white (FLIP.h DEFAULT_ILLUMINANT / INV_DEFAULT_ILLUMINANT). */
static const float WHITE[3] = {0.950428545f, 1.000000000f, 1.088900371f};
static const float INV_WHITE[3] = {1.052156925f, 1.000000000f, 0.918357670f};

/* Linear sRGB <-> XYZ (D65) as in FLIP.h color3::LinearRGBToXYZ / XYZToLinearRGB, which cite
 * image-engineering.de technote 958; the inverse constants are the reference's rounded inverse. */
static const float RGB2XYZ[3][3] = {
    {10135552.0f / 24577794.0f, 8788810.0f / 24577794.0f, 4435075.0f / 24577794.0f},
    {2613072.0f / 12288897.0f, 8788810.0f / 12288897.0f, 887015.0f / 12288897.0f},
    {1425312.0f / 73733382.0f, 8788810.0f / 73733382.0f, 70074185.0f / 73733382.0f},
};
static const float XYZ2RGB[3][3] = {
    {3.241003275f, -1.537398934f, -0.498615861f},
    {-0.969224334f, 1.875930071f, 0.041554224f},
    {0.055639423f, -0.204011202f, 1.057148933f},
};

/* ACES filmic fit (Narkowicz 2016: (x (2.51 x + 0.03)) / (x (2.43 x + 0.59) + 0.14)) with the 0.6
 * pre-exposure of that post folded in, as [H] §3 and FLIP.h ToneMappingCoefficients[1]:
 * y = (k0 x^2 + k1 x + k2) / (k3 x^2 + k4 x + k5). */
static const double ACES_K[6] = {0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14};
/* [H] §3 / FLIP.h computeExposures: the start exposure maps the reference's largest luminance to
 * t = 0.85 of the tone mapper's output, the stop exposure maps its median luminance there. */
#define FLIP_T_EXPOSURE 0.85

#define set_message glow__eval_set_message

double glow_eval_flip_ppd(double distance_m, double resolution_x, double monitor_width_m) {
    /* FLIP.h calculatePPD: distance * (pixels / width) * pi / 180 (pixels per degree at the centre). */
    return distance_m * (resolution_x / monitor_width_m) * (FLIP_PI / 180.0);
}

/* ---- filters ---- */

static int csf_radius(double ppd) {
    /* FLIP.h calculateSpatialFilterRadius / flip_api.py generate_spatial_filter: 3 standard
     * deviations of the widest Gaussian (largest b; sigma = sqrt(b / (2 pi^2)) degrees). */
    double bmax = 0.0;
    for (int c = 0; c < 3; c++) bmax = fmax(bmax, fmax(CSF_B1[c], CSF_B2[c]));
    return (int)ceil(3.0 * sqrt(bmax / (2.0 * FLIP_PI * FLIP_PI)) * ppd);
}

static int feature_radius(double ppd) {
    /* FLIP.h setFeatureFilter / flip_api.py feature_detection: sigma = w/2 * ppd pixels, radius
     * ceil(3 sigma). */
    return (int)ceil(3.0 * (0.5 * FLIP_W * ppd));
}

int glow_eval_flip_kernel(glow_eval_flip_kernel_kind kind, double ppd, float *weights, size_t capacity) {
    if (!(ppd > 0.0) || !isfinite(ppd)) return -1;
    int csf = kind >= GLOW_EVAL_FLIP_KERNEL_CSF_A && kind <= GLOW_EVAL_FLIP_KERNEL_CSF_BY2;
    int feat = kind >= GLOW_EVAL_FLIP_KERNEL_FEATURE_GAUSS && kind <= GLOW_EVAL_FLIP_KERNEL_FEATURE_POINT;
    if (!csf && !feat) return -1;
    int r = csf ? csf_radius(ppd) : feature_radius(ppd);
    if (r > 100000) return -1;
    size_t n = 2 * (size_t)r + 1;
    if (!weights || capacity < n) return r;
    double *w = malloc(sizeof(double) * n * 2);
    if (!w) return -1;
    double *w2 = w + n;
    if (csf) {
        /* 1D factors of the 2D CSF filter in degrees x = i / ppd. A and RG: one Gaussian, normalised
         * to sum 1 (the 2D filter is its outer product and sums to 1). BY: the two terms' factors are
         * sqrt(a sqrt(pi/b)) exp(-pi^2 x^2 / b) (FLIP.h GaussianSqrt), both divided by
         * sqrt(S1^2 + S2^2) so that the 2D sum S1^2 + S2^2 of the two outer products is 1
         * (NVlabs/flip misc/separatedConvolutions.pdf). */
        int c = kind == GLOW_EVAL_FLIP_KERNEL_CSF_A ? 0 : kind == GLOW_EVAL_FLIP_KERNEL_CSF_RG ? 1 : 2;
        double s1 = 0.0, s2 = 0.0;
        for (int i = -r; i <= r; i++) {
            double x2 = ((double)i / ppd) * ((double)i / ppd);
            if (c < 2) {
                w[i + r] = CSF_A1[c] * sqrt(FLIP_PI / CSF_B1[c]) * exp(-FLIP_PI * FLIP_PI * x2 / CSF_B1[c]);
                w2[i + r] = 0.0;
            } else {
                w[i + r] = sqrt(CSF_A1[2] * sqrt(FLIP_PI / CSF_B1[2])) * exp(-FLIP_PI * FLIP_PI * x2 / CSF_B1[2]);
                w2[i + r] = sqrt(CSF_A2[2] * sqrt(FLIP_PI / CSF_B2[2])) * exp(-FLIP_PI * FLIP_PI * x2 / CSF_B2[2]);
            }
            s1 += w[i + r];
            s2 += w2[i + r];
        }
        double norm = c < 2 ? 1.0 / s1 : 1.0 / sqrt(s1 * s1 + s2 * s2);
        const double *src = kind == GLOW_EVAL_FLIP_KERNEL_CSF_BY2 ? w2 : w;
        for (size_t i = 0; i < n; i++) weights[i] = (float)(src[i] * norm);
    } else {
        /* Gaussian g (sum 1); edge: -x g, positive weights scaled to sum 1 and negative ones to -1;
         * point: (x^2/sigma^2 - 1) g, likewise ([F] §4.2, FLIP.h setFeatureFilter). */
        double sd = 0.5 * FLIP_W * ppd, pos = 0.0, neg = 0.0;
        for (int i = -r; i <= r; i++) {
            double g = exp(-(double)i * i / (2.0 * sd * sd)), v;
            if (kind == GLOW_EVAL_FLIP_KERNEL_FEATURE_GAUSS) v = g;
            else if (kind == GLOW_EVAL_FLIP_KERNEL_FEATURE_EDGE) v = -(double)i * g;
            else v = ((double)i * i / (sd * sd) - 1.0) * g;
            w[i + r] = v;
            if (v > 0.0) pos += v;
            else neg -= v;
        }
        for (size_t i = 0; i < n; i++) {
            double v = w[i];
            if (kind == GLOW_EVAL_FLIP_KERNEL_FEATURE_GAUSS) v /= pos;
            else v = v > 0.0 ? v / pos : (neg > 0.0 ? v / neg : 0.0);
            weights[i] = (float)v;
        }
    }
    free(w);
    return r;
}

/* ---- colour ---- */

static inline float lab_f(float t) {
    const float d = 6.0f / 29.0f;
    return t > d * d * d ? cbrtf(t) : t / (3.0f * d * d) + 4.0f / 29.0f;
}

/* Linear RGB (any range) -> Hunt-adjusted CIELAB: L, 0.01 L a, 0.01 L b ([F] §4.1). */
static inline void rgb_to_hunt_lab(float r, float g, float b, float out[3]) {
    float X = (RGB2XYZ[0][0] * r + RGB2XYZ[0][1] * g + RGB2XYZ[0][2] * b) * INV_WHITE[0];
    float Y = (RGB2XYZ[1][0] * r + RGB2XYZ[1][1] * g + RGB2XYZ[1][2] * b) * INV_WHITE[1];
    float Z = (RGB2XYZ[2][0] * r + RGB2XYZ[2][1] * g + RGB2XYZ[2][2] * b) * INV_WHITE[2];
    float fx = lab_f(X), fy = lab_f(Y), fz = lab_f(Z);
    float L = 116.0f * fy - 16.0f;
    out[0] = L;
    out[1] = 0.01f * L * (500.0f * (fx - fy));
    out[2] = 0.01f * L * (200.0f * (fy - fz));
}

static inline float hyab(const float a[3], const float b[3]) {
    float da = a[1] - b[1], db = a[2] - b[2];
    return fabsf(a[0] - b[0]) + sqrtf(da * da + db * db);
}

/* YCxCz (filtered) -> linear RGB clamped to [0,1] -> Hunt-adjusted CIELAB. */
static inline void ycxcz_to_hunt_lab(float Yc, float Cx, float Cz, float out[3]) {
    float fy = (Yc + 16.0f) / 116.0f;
    float X = (fy + Cx / 500.0f) * WHITE[0], Y = fy * WHITE[1], Z = (fy - Cz / 200.0f) * WHITE[2];
    float rgb[3];
    for (int i = 0; i < 3; i++) {
        float v = XYZ2RGB[i][0] * X + XYZ2RGB[i][1] * Y + XYZ2RGB[i][2] * Z;
        rgb[i] = v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v;
    }
    rgb_to_hunt_lab(rgb[0], rgb[1], rgb[2], out);
}

/* c_max = HyAB(green, blue)^q_c in Hunt-adjusted CIELAB: the largest colour difference of the
 * RGB cube ([F] §4.1; FLIP.h computeMaxDistance). */
static float flip_cmax(void) {
    float g[3], b[3];
    rgb_to_hunt_lab(0.0f, 1.0f, 0.0f, g);
    rgb_to_hunt_lab(0.0f, 0.0f, 1.0f, b);
    return powf(hyab(g, b), FLIP_QC);
}

/* ---- the LDR-FLIP core ---- */

typedef struct flip_ctx {
    uint32_t w, h;
    int rc, rf;             /* CSF and feature filter radii */
    float *kc[4];           /* CSF: A (Y), RG (Cx), BY term 1, BY term 2 (Cz); 2 rc + 1 each */
    float *kf[3];           /* feature: Gaussian, edge, point; 2 rf + 1 each */
    float *ycc[2][3];       /* per image (0 ref, 1 test): Y, Cx, Cz planes */
    float *hp[2][4];        /* horizontal-pass planes */
    float *pad;             /* one row with clamp-to-edge padding */
    float *rows[2][4];      /* vertical-pass output rows */
    float *colour;          /* ΔE_c plane */
    float cmax, pccmax;
    void *block;
} flip_ctx;

static void ctx_free(flip_ctx *c) { free(c->block); }

static glow_result ctx_init(flip_ctx *c, uint32_t w, uint32_t h, double ppd) {
    memset(c, 0, sizeof *c);
    c->w = w;
    c->h = h;
    c->rc = glow_eval_flip_kernel(GLOW_EVAL_FLIP_KERNEL_CSF_A, ppd, NULL, 0);
    c->rf = glow_eval_flip_kernel(GLOW_EVAL_FLIP_KERNEL_FEATURE_GAUSS, ppd, NULL, 0);
    if (c->rc < 0 || c->rf < 0) return GLOW_ERROR_INVALID_ARGUMENT;
    size_t nc = 2 * (size_t)c->rc + 1, nf = 2 * (size_t)c->rf + 1, plane = (size_t)w * h;
    size_t rmax = (size_t)(c->rc > c->rf ? c->rc : c->rf);
    size_t total = 4 * nc + 3 * nf + 6 * plane + 8 * plane + (w + 2 * rmax) + 8 * (size_t)w + plane;
    float *p = malloc(sizeof(float) * total);
    if (!p) return GLOW_ERROR_OUT_OF_MEMORY;
    c->block = p;
    int ok = 1;
    for (int k = 0; k < 4; k++, p += nc) {
        c->kc[k] = p;
        ok &= glow_eval_flip_kernel((glow_eval_flip_kernel_kind)(GLOW_EVAL_FLIP_KERNEL_CSF_A + k), ppd, p, nc) >= 0;
    }
    for (int k = 0; k < 3; k++, p += nf) {
        c->kf[k] = p;
        ok &= glow_eval_flip_kernel((glow_eval_flip_kernel_kind)(GLOW_EVAL_FLIP_KERNEL_FEATURE_GAUSS + k), ppd, p, nf) >= 0;
    }
    if (!ok) return GLOW_ERROR_OUT_OF_MEMORY; /* the kernels' scratch allocation */
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 3; k++, p += plane) c->ycc[i][k] = p;
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 4; k++, p += plane) c->hp[i][k] = p;
    c->pad = p;
    p += w + 2 * rmax;
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 4; k++, p += w) c->rows[i][k] = p;
    c->colour = p;
    c->cmax = flip_cmax();
    c->pccmax = FLIP_PC * c->cmax;
    return GLOW_OK;
}

/* out[x] = Σ_k k[j] src[clamp(x + j - r)] for one row. */
static void hpass(const flip_ctx *c, const float *src, const float *kern, int r, float *out) {
    const uint32_t w = c->w;
    float *pad = c->pad;
    for (int i = 0; i < r; i++) pad[i] = src[0], pad[(size_t)r + w + (size_t)i] = src[w - 1];
    memcpy(pad + r, src, sizeof(float) * w);
    for (uint32_t x = 0; x < w; x++) out[x] = 0.0f;
    for (int j = 0; j <= 2 * r; j++) {
        const float kj = kern[j], *s = pad + j;
        for (uint32_t x = 0; x < w; x++) out[x] += kj * s[x];
    }
}

/* out[x] = Σ_k k[j] plane[clamp(y + j - r)][x]. */
static void vpass(const flip_ctx *c, const float *plane, uint32_t y, const float *kern, int r, float *out) {
    const uint32_t w = c->w;
    for (uint32_t x = 0; x < w; x++) out[x] = 0.0f;
    for (int j = 0; j <= 2 * r; j++) {
        int64_t yy = (int64_t)y + j - r;
        yy = yy < 0 ? 0 : yy >= (int64_t)c->h ? (int64_t)c->h - 1 : yy;
        const float kj = kern[j], *s = plane + (size_t)yy * w;
        for (uint32_t x = 0; x < w; x++) out[x] += kj * s[x];
    }
}

/* LDR-FLIP of two interleaved linear-RGB images with values in [0,1] (rgb[0] reference, rgb[1]
 * test); combines into map with max (map_max) or stores (otherwise). */
static void ldr_flip(flip_ctx *c, const float *const rgb[2], float *map, int map_max) {
    const uint32_t w = c->w, h = c->h;
    const size_t n = (size_t)w * h;
    /* linear RGB -> XYZ -> YCxCz (FLIP.h XYZToYCxCz: 116 Y/Yw - 16, 500 (X/Xw - Y/Yw), 200 (Y/Yw - Z/Zw)) */
    for (int i = 0; i < 2; i++) {
        const float *p = rgb[i];
        float *Yp = c->ycc[i][0], *Cxp = c->ycc[i][1], *Czp = c->ycc[i][2];
        for (size_t k = 0; k < n; k++, p += 3) {
            float X = (RGB2XYZ[0][0] * p[0] + RGB2XYZ[0][1] * p[1] + RGB2XYZ[0][2] * p[2]) * INV_WHITE[0];
            float Y = (RGB2XYZ[1][0] * p[0] + RGB2XYZ[1][1] * p[1] + RGB2XYZ[1][2] * p[2]) * INV_WHITE[1];
            float Z = (RGB2XYZ[2][0] * p[0] + RGB2XYZ[2][1] * p[1] + RGB2XYZ[2][2] * p[2]) * INV_WHITE[2];
            Yp[k] = 116.0f * Y - 16.0f;
            Cxp[k] = 500.0f * (X - Y);
            Czp[k] = 200.0f * (Y - Z);
        }
    }
    /* colour pipeline: horizontal CSF pass (Y, Cx, Cz with both BY terms) ... */
    for (int i = 0; i < 2; i++)
        for (uint32_t y = 0; y < h; y++) {
            size_t o = (size_t)y * w;
            hpass(c, c->ycc[i][0] + o, c->kc[0], c->rc, c->hp[i][0] + o);
            hpass(c, c->ycc[i][1] + o, c->kc[1], c->rc, c->hp[i][1] + o);
            hpass(c, c->ycc[i][2] + o, c->kc[2], c->rc, c->hp[i][2] + o);
            hpass(c, c->ycc[i][2] + o, c->kc[3], c->rc, c->hp[i][3] + o);
        }
    /* ... vertical pass, back to clamped RGB, Hunt-adjusted CIELAB, HyAB, remap ([F] eq. 3-4). */
    for (uint32_t y = 0; y < h; y++) {
        for (int i = 0; i < 2; i++)
            for (int k = 0; k < 4; k++) vpass(c, c->hp[i][k], y, c->kc[k], c->rc, c->rows[i][k]);
        for (uint32_t x = 0; x < w; x++) {
            float a[3], b[3];
            ycxcz_to_hunt_lab(c->rows[0][0][x], c->rows[0][1][x], c->rows[0][2][x] + c->rows[0][3][x], a);
            ycxcz_to_hunt_lab(c->rows[1][0][x], c->rows[1][1][x], c->rows[1][2][x] + c->rows[1][3][x], b);
            float d = powf(hyab(a, b), FLIP_QC);
            /* [F] eq. 4: [0, p_c c_max) -> [0, p_t) linearly, [p_c c_max, c_max] -> [p_t, 1]. */
            d = d < c->pccmax ? d * (FLIP_PT / c->pccmax)
                              : FLIP_PT + ((d - c->pccmax) / (c->cmax - c->pccmax)) * (1.0f - FLIP_PT);
            c->colour[(size_t)y * w + x] = d;
        }
    }
    /* feature pipeline on the normalised achromatic channel (Y + 16) / 116 of the unfiltered YCxCz:
     * horizontal pass gives x-derivatives (edge, point) and the Gaussian for the y-derivatives. */
    for (int i = 0; i < 2; i++) {
        float *yn = c->hp[i][3]; /* scratch: the BY term 2 plane is no longer needed */
        for (size_t k = 0; k < n; k++) yn[k] = c->ycc[i][0][k] * (1.0f / 116.0f) + 16.0f / 116.0f;
        for (uint32_t y = 0; y < h; y++) {
            size_t o = (size_t)y * w;
            hpass(c, yn + o, c->kf[1], c->rf, c->hp[i][0] + o); /* d/dx */
            hpass(c, yn + o, c->kf[2], c->rf, c->hp[i][1] + o); /* d2/dx2 */
            hpass(c, yn + o, c->kf[0], c->rf, c->hp[i][2] + o); /* Gaussian in x */
        }
    }
    const float inv_sqrt2 = 0.70710678118654752f;
    for (uint32_t y = 0; y < h; y++) {
        for (int i = 0; i < 2; i++) {
            vpass(c, c->hp[i][0], y, c->kf[0], c->rf, c->rows[i][0]); /* edge x */
            vpass(c, c->hp[i][1], y, c->kf[0], c->rf, c->rows[i][1]); /* point x */
            vpass(c, c->hp[i][2], y, c->kf[1], c->rf, c->rows[i][2]); /* edge y */
            vpass(c, c->hp[i][2], y, c->kf[2], c->rf, c->rows[i][3]); /* point y */
        }
        for (uint32_t x = 0; x < w; x++) {
            float er = sqrtf(c->rows[0][0][x] * c->rows[0][0][x] + c->rows[0][2][x] * c->rows[0][2][x]);
            float et = sqrtf(c->rows[1][0][x] * c->rows[1][0][x] + c->rows[1][2][x] * c->rows[1][2][x]);
            float pr = sqrtf(c->rows[0][1][x] * c->rows[0][1][x] + c->rows[0][3][x] * c->rows[0][3][x]);
            float pt = sqrtf(c->rows[1][1][x] * c->rows[1][1][x] + c->rows[1][3][x] * c->rows[1][3][x]);
            float fd = fmaxf(fabsf(er - et), fabsf(pr - pt));
            float df = powf(inv_sqrt2 * fd, FLIP_QF);
            size_t k = (size_t)y * w + x;
            float e = powf(c->colour[k], 1.0f - df); /* [F] eq. 6 */
            if (map_max) {
                if (e > map[k]) map[k] = e;
            } else {
                map[k] = e;
            }
        }
    }
}

/* ---- HDR ---- */

static double aces(double x) {
    double y = (ACES_K[0] * x * x + ACES_K[1] * x + ACES_K[2]) / (ACES_K[3] * x * x + ACES_K[4] * x + ACES_K[5]);
    return isfinite(y) ? (y < 0.0 ? 0.0 : y > 1.0 ? 1.0 : y) : 1.0; /* huge x: k0/k3 > 1, clamps to 1 */
}

double glow_eval_flip_aces(double x) { return aces(x > 0.0 ? x : 0.0); }

/* The tone-mapper input that maps to t: the larger root of (k0 - t k3) x^2 + (k1 - t k4) x +
 * (k2 - t k5) = 0 (FLIP.h solveSecondDegree / flip_api.py compute_exposure_params). 2.1189 for ACES
 * and t = 0.85. */
static double aces_inverse(double t) {
    double a = ACES_K[0] - t * ACES_K[3], b = ACES_K[1] - t * ACES_K[4], cc = ACES_K[2] - t * ACES_K[5];
    if (a == 0.0) return -cc / b;
    double d1 = -0.5 * b / a, d2 = sqrt(d1 * d1 - cc / a);
    return d1 + d2;
}


/* Start and stop exposure from the reference's luminance (negatives clamped to 0) over the
 * unmasked pixels: Y_max and the median Y (the element at index n/2 of the sorted luminances, as
 * FLIP.h's nth_element). Returns GLOW_ERROR_OUT_OF_MEMORY or GLOW_OK. */
static glow_result exposures_from(const glow_eval_image *ref, const uint8_t *mask, double *start, double *stop) {
    size_t n = (size_t)ref->width * ref->height, m = 0;
    double *lum = malloc(sizeof(double) * (n ? n : 1));
    if (!lum) return GLOW_ERROR_OUT_OF_MEMORY;
    for (size_t i = 0; i < n; i++) {
        if (mask && !mask[i]) continue;
        const float *p = ref->rgb + 3 * i;
        double r = p[0] > 0 ? p[0] : 0, g = p[1] > 0 ? p[1] : 0, b = p[2] > 0 ? p[2] : 0;
        lum[m++] = 0.2126 * r + 0.7152 * g + 0.0722 * b; /* FLIP.h linearRGBToLuminance */
    }
    qsort(lum, m, sizeof(double), glow_cli_cmp_double);
    double ymax = m ? lum[m - 1] : 0.0, ymed = m ? lum[m / 2] : 0.0;
    if (ymed <= 0.0 && ymax > 0.0) {
        /* Over half the pixels black: the reference implementation's stop exposure would be +inf.
         * Use the median of the non-zero luminances instead (a Glow choice, documented). */
        size_t first = 0;
        while (lum[first] <= 0.0) first++;
        ymed = lum[first + (m - first) / 2];
    }
    free(lum);
    double xmax = aces_inverse(FLIP_T_EXPOSURE);
    if (ymax <= 0.0) {
        *start = *stop = 0.0; /* all black: flip_api.py compute_exposure_params returns 0, 0 */
    } else {
        *start = log2(xmax / ymax);
        *stop = log2(xmax / ymed);
    }
    return GLOW_OK;
}

static int image_ok(const glow_eval_image *img) { return img && img->rgb && img->width > 0 && img->height > 0; }

glow_result glow_eval_flip(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                           const glow_eval_flip_params *params, float *out_map, glow_eval_flip_result *out,
                           char *message, size_t message_size) {
    if (out) memset(out, 0, sizeof *out);
    if (!out || !image_ok(test) || !image_ok(ref)) {
        set_message(message, message_size, "flip: NULL or empty %s",
                    !out ? "output" : !image_ok(test) ? "test image" : "reference image");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (test->width != ref->width || test->height != ref->height) {
        set_message(message, message_size, "flip: size mismatch (test %ux%u, reference %ux%u)", (unsigned)test->width,
                    (unsigned)test->height, (unsigned)ref->width, (unsigned)ref->height);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t W = ref->width, H = ref->height;
    const size_t n = (size_t)W * H;
    const glow_eval_image *imgs[2] = {test, ref};
    static const char *const names[2] = {"test image", "reference image"};
    for (int k = 0; k < 2; k++)
        for (size_t i = 0; i < 3 * n; i++)
            if (!isfinite(imgs[k]->rgb[i])) {
                set_message(message, message_size, "flip: %s pixel (%u, %u) channel %c is %s", names[k],
                            (unsigned)(i / 3 % W), (unsigned)(i / 3 / W), "RGB"[i % 3],
                            isnan(imgs[k]->rgb[i]) ? "NaN" : "infinite");
                return GLOW_ERROR_INVALID_ARGUMENT;
            }
    uint64_t pixels = 0;
    for (size_t i = 0; i < n; i++) pixels += !mask || mask[i];
    if (pixels == 0) {
        set_message(message, message_size, "flip: the mask leaves no pixel to compare");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_eval_flip_params p = params ? *params : (glow_eval_flip_params){0};
    double ppd = p.ppd == 0.0 ? glow_eval_flip_ppd(0.7, 3840.0, 0.7) : p.ppd;
    if (!(ppd > 0.0) || !isfinite(ppd) || ppd > 10000.0) {
        set_message(message, message_size, "flip: pixels per degree %g is not in (0, 10000]", ppd);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    double start = 0.0, stop = 0.0;
    int count = 0;
    if (!p.ldr) {
        if (p.fixed_exposures) {
            start = p.start_exposure;
            stop = p.stop_exposure;
            if (!isfinite(start) || !isfinite(stop) || start > stop || fabs(start) > 1000.0 || fabs(stop) > 1000.0) {
                set_message(message, message_size, "flip: exposures %g .. %g are not finite and ordered", start, stop);
                return GLOW_ERROR_INVALID_ARGUMENT;
            }
        } else if (exposures_from(ref, mask, &start, &stop) != GLOW_OK) {
            set_message(message, message_size, "flip: out of memory");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        if (p.num_exposures < 0 || p.num_exposures > 1024) {
            set_message(message, message_size, "flip: %d exposures is not in [0, 1024]", p.num_exposures);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
        /* [H] §3 / FLIP.h evaluate: n = max(2, ceil(stop - start)); one when the range is empty. */
        count = p.num_exposures ? p.num_exposures : start == stop ? 1 : (int)fmax(2.0, ceil(stop - start));
    }

    flip_ctx ctx;
    glow_result r = ctx_init(&ctx, W, H, ppd);
    float *map = out_map ? out_map : malloc(sizeof(float) * n);
    float *buf = malloc(sizeof(float) * 6 * n);
    if (r != GLOW_OK || !map || !buf) {
        if (map != out_map) free(map);
        free(buf);
        ctx_free(&ctx);
        set_message(message, message_size, "flip: out of memory");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    const float *rgb[2] = {buf, buf + 3 * n}; /* reference, test */
    if (p.ldr) {
        for (size_t i = 0; i < 3 * n; i++) {
            float a = ref->rgb[i], b = test->rgb[i];
            buf[i] = a < 0.0f ? 0.0f : a > 1.0f ? 1.0f : a;
            buf[3 * n + i] = b < 0.0f ? 0.0f : b > 1.0f ? 1.0f : b;
        }
        ldr_flip(&ctx, rgb, map, 0);
    } else {
        for (size_t i = 0; i < n; i++) map[i] = 0.0f;
        double step = count > 1 ? (stop - start) / (count - 1) : 0.0;
        for (int e = 0; e < count; e++) {
            double scale = exp2(start + e * step);
            for (size_t i = 0; i < 3 * n; i++) {
                buf[i] = (float)aces(ref->rgb[i] > 0.0f ? (double)ref->rgb[i] * scale : 0.0);
                buf[3 * n + i] = (float)aces(test->rgb[i] > 0.0f ? (double)test->rgb[i] * scale : 0.0);
            }
            ldr_flip(&ctx, rgb, map, 1);
        }
    }
    double sum = 0.0, mx = 0.0;
    for (size_t i = 0; i < n; i++) {
        if (mask && !mask[i]) continue;
        sum += map[i];
        if (map[i] > mx) mx = map[i];
    }
    out->mean = sum / (double)pixels;
    out->max = mx;
    out->ppd = ppd;
    out->start_exposure = start;
    out->stop_exposure = stop;
    out->num_exposures = count;
    out->pixels = pixels;
    if (map != out_map) free(map);
    free(buf);
    ctx_free(&ctx);
    return GLOW_OK;
}

double glow_eval_hdr_flip(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask) {
    glow_eval_flip_result res;
    if (glow_eval_flip(test, ref, mask, NULL, NULL, &res, NULL, 0) != GLOW_OK) return NAN;
    return res.mean;
}
