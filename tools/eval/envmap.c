/* envmap.c — HDR environment maps (glow_envmap.h, docs/envmap.md): lat-long OpenEXR skies, lookup,
 * importance sampling, SH l <= 2 projection, the sun split and a simple sky generator. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eval_internal.h"
#include "glow_envmap.h"

#define set_message glow__eval_set_message
#define PI_D 3.14159265358979323846

static inline double luma(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

void glow_eval_envmap_free(glow_eval_envmap *m) {
    if (!m) return;
    free(m->rgb);
    free(m->cos_theta);
    free(m->row_cdf);
    free(m->col_cdf);
    memset(m, 0, sizeof *m);
}

/* Ω of a texel in row j (every column of a row has the same). */
static inline double texel_omega(const glow_eval_envmap *m, uint32_t j) {
    return 2.0 * PI_D / m->width * (m->cos_theta[j] - m->cos_theta[j + 1]);
}

/* Builds cos_theta and the CDFs of m (width, height, rgb set). */
static glow_result build_tables(glow_eval_envmap *m) {
    const uint32_t W = m->width, H = m->height;
    m->cos_theta = malloc((H + 1) * sizeof *m->cos_theta);
    m->row_cdf = malloc((H + 1) * sizeof *m->row_cdf);
    m->col_cdf = malloc((size_t)H * (W + 1) * sizeof *m->col_cdf);
    double *row_w = malloc(H * sizeof *row_w);
    if (!m->cos_theta || !m->row_cdf || !m->col_cdf || !row_w) {
        free(row_w);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    for (uint32_t j = 0; j <= H; ++j) m->cos_theta[j] = cos(PI_D * j / H);
    m->cos_theta[0] = 1.0;
    m->cos_theta[H] = -1.0;
    if (H % 2 == 0) m->cos_theta[H / 2] = 0.0; /* the horizon exactly */
    double total = 0.0;
    for (uint32_t j = 0; j < H; ++j) {
        float *cdf = m->col_cdf + (size_t)j * (W + 1);
        double s = 0.0;
        cdf[0] = 0.0f;
        for (uint32_t i = 0; i < W; ++i) {
            s += luma(m->rgb + 3 * ((size_t)j * W + i));
            cdf[i + 1] = (float)s;
        }
        for (uint32_t i = 1; i <= W; ++i) cdf[i] = s > 0.0 ? (float)((double)cdf[i] / s) : (float)i / (float)W;
        cdf[W] = 1.0f;
        row_w[j] = s * texel_omega(m, j);
        total += row_w[j];
    }
    m->lum_integral = total;
    double s = 0.0;
    m->row_cdf[0] = 0.0f;
    for (uint32_t j = 0; j < H; ++j) {
        s += row_w[j];
        m->row_cdf[j + 1] = total > 0.0 ? (float)(s / total) : (float)(j + 1) / (float)H;
    }
    m->row_cdf[H] = 1.0f;
    free(row_w);
    return GLOW_OK;
}

glow_result glow_eval_envmap_from_image(const glow_eval_image *img, float rotation_deg, float scale, const char *name,
                                        glow_eval_envmap *out, char *message, size_t message_size) {
    if (!name) name = "envmap";
    if (out) memset(out, 0, sizeof *out);
    if (!img || !out || !img->rgb) {
        set_message(message, message_size, "%s: NULL argument to glow_eval_envmap_from_image", name);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!isfinite(rotation_deg)) {
        set_message(message, message_size, "%s: rotation_deg (%g) is not finite", name, (double)rotation_deg);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!isfinite(scale) || scale < 0.0f) {
        set_message(message, message_size, "%s: scale (%g) must be finite and >= 0", name, (double)scale);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t W = img->width, H = img->height;
    if (H < 2 || W != 2 * H) {
        set_message(message, message_size,
                    "%s: %ux%u is not a latitude-longitude map (the width must be twice the height, at least 4x2)", name,
                    (unsigned)W, (unsigned)H);
        return GLOW_ERROR_CORRUPT_DATA;
    }
    static const char ch[3] = {'R', 'G', 'B'};
    const size_t n = (size_t)W * H * 3;
    for (size_t i = 0; i < n; ++i) {
        const float v = img->rgb[i];
        if (!isfinite(v) || v < 0.0f) {
            set_message(message, message_size, "%s: texel (%u, %u) channel %c is %g (%s)", name,
                        (unsigned)((i / 3) % W), (unsigned)((i / 3) / W), ch[i % 3], (double)v,
                        isfinite(v) ? "negative" : "not finite");
            return GLOW_ERROR_CORRUPT_DATA;
        }
    }
    out->rgb = malloc(n * sizeof *out->rgb);
    if (!out->rgb) {
        set_message(message, message_size, "%s: out of memory", name);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    memcpy(out->rgb, img->rgb, n * sizeof *out->rgb);
    out->width = W;
    out->height = H;
    out->scale = scale;
    out->rotation_deg = rotation_deg;
    out->rot_rad = (double)rotation_deg * PI_D / 180.0;
    if (build_tables(out) != GLOW_OK) {
        glow_eval_envmap_free(out);
        set_message(message, message_size, "%s: out of memory", name);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    return GLOW_OK;
}

glow_result glow_eval_envmap_load(const char *path, float rotation_deg, float scale, glow_eval_envmap *out,
                                  char *message, size_t message_size) {
    if (out) memset(out, 0, sizeof *out);
    if (!path || !out) {
        set_message(message, message_size, "%s: NULL argument to glow_eval_envmap_load", path ? path : "(null)");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_eval_image img;
    glow_result r = glow_eval_read_exr(path, &img, message, message_size);
    if (r != GLOW_OK) return r;
    r = glow_eval_envmap_from_image(&img, rotation_deg, scale, path, out, message, message_size);
    glow_eval_image_free(&img);
    return r;
}

/* ---------------------------------------------------------------------------------- directions */

/* world direction of map angles (θ given by its cosine, φ_map) */
static inline void dir_of(const glow_eval_envmap *m, double cos_t, double phi_map, double d[3]) {
    const double s = sqrt(fmax(0.0, 1.0 - cos_t * cos_t)), phi = phi_map - m->rot_rad;
    d[0] = -s * sin(phi);
    d[1] = cos_t;
    d[2] = s * cos(phi);
}

/* sin and cos of the world φ of every column's centre (2W doubles, malloc'd; NULL when out of memory) */
static double *column_trig(const glow_eval_envmap *m) {
    double *t = malloc(2 * (size_t)m->width * sizeof *t);
    if (!t) return NULL;
    for (uint32_t i = 0; i < m->width; ++i) {
        const double phi = 2.0 * PI_D * (i + 0.5) / m->width - m->rot_rad;
        t[2 * i] = sin(phi);
        t[2 * i + 1] = cos(phi);
    }
    return t;
}

/* the world direction of texel (i, j)'s centre from column_trig's table and the row's cos θ, sin θ */
static inline void texel_dir(const double *trig, uint32_t i, double ct, double st, double d[3]) {
    d[0] = -st * trig[2 * i];
    d[1] = ct;
    d[2] = st * trig[2 * i + 1];
}

void glow_eval_envmap_direction(const glow_eval_envmap *m, double u, double v, float out[3]) {
    double d[3];
    dir_of(m, cos(PI_D * v), 2.0 * PI_D * u, d);
    for (int k = 0; k < 3; ++k) out[k] = (float)d[k];
}

/* the texel holding unit world direction dir */
static inline size_t texel_of(const glow_eval_envmap *m, const float dir[3], uint32_t *out_j) {
    const double y = fmin(fmax((double)dir[1], -1.0), 1.0);
    double u = (atan2(-(double)dir[0], (double)dir[2]) + m->rot_rad) * (0.5 / PI_D);
    u -= floor(u);
    const double v = acos(y) / PI_D;
    uint32_t i = (uint32_t)(u * m->width), j = (uint32_t)(v * m->height);
    if (i >= m->width) i = m->width - 1;
    if (j >= m->height) j = m->height - 1;
    /* the rows are cut at cos θ_j: keep the texel consistent with the sampler's exact boundaries */
    while (j > 0 && y > m->cos_theta[j]) --j;
    while (j + 1 < m->height && y < m->cos_theta[j + 1]) ++j;
    if (out_j) *out_j = j;
    return (size_t)j * m->width + i;
}

void glow_eval_envmap_eval(const glow_eval_envmap *m, const float dir[3], float out[3]) {
    const float *t = m->rgb + 3 * texel_of(m, dir, NULL);
    for (int k = 0; k < 3; ++k) out[k] = m->scale * t[k];
}

float glow_eval_envmap_pdf(const glow_eval_envmap *m, const float dir[3]) {
    if (!(m->lum_integral > 0.0) || !(m->scale > 0.0f)) return 0.0f;
    return (float)(luma(m->rgb + 3 * texel_of(m, dir, NULL)) / m->lum_integral);
}

/* first k in [0, n) with cdf[k + 1] > u (cdf[0] = 0, cdf[n] = 1, u in [0, 1)) */
static inline uint32_t cdf_find(const float *cdf, uint32_t n, float u) {
    uint32_t lo = 0, hi = n - 1;
    while (lo < hi) {
        const uint32_t mid = (lo + hi) / 2;
        if (cdf[mid + 1] > u) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

float glow_eval_envmap_sample(const glow_eval_envmap *m, float u1, float u2, float out_dir[3], float out_rgb[3]) {
    for (int k = 0; k < 3; ++k) out_dir[k] = out_rgb[k] = 0.0f;
    if (!(m->lum_integral > 0.0) || !(m->scale > 0.0f)) return 0.0f;
    const uint32_t W = m->width, H = m->height;
    const uint32_t j = cdf_find(m->row_cdf, H, u1);
    const float *cc = m->col_cdf + (size_t)j * (W + 1);
    const uint32_t i = cdf_find(cc, W, u2);
    const double w1 = (double)m->row_cdf[j + 1] - m->row_cdf[j], w2 = (double)cc[i + 1] - cc[i];
    const double t1 = w1 > 0.0 ? fmin(fmax(((double)u1 - m->row_cdf[j]) / w1, 0.0), 1.0) : 0.5;
    const double t2 = w2 > 0.0 ? fmin(fmax(((double)u2 - cc[i]) / w2, 0.0), 1.0) : 0.5;
    const float *t = m->rgb + 3 * ((size_t)j * W + i);
    const double Y = luma(t);
    if (!(Y > 0.0)) return 0.0f; /* float CDF rounding picked an empty texel: no sample (never seen) */
    double d[3];
    dir_of(m, m->cos_theta[j] + t1 * (m->cos_theta[j + 1] - m->cos_theta[j]), 2.0 * PI_D * ((double)i + t2) / W, d);
    const double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int k = 0; k < 3; ++k) {
        out_dir[k] = (float)(d[k] / l);
        out_rgb[k] = m->scale * t[k];
    }
    return (float)(Y / m->lum_integral);
}

void glow_eval_envmap_integral(const glow_eval_envmap *m, double out[3]) {
    out[0] = out[1] = out[2] = 0.0;
    for (uint32_t j = 0; j < m->height; ++j) {
        double s[3] = {0, 0, 0};
        const float *row = m->rgb + 3 * (size_t)j * m->width;
        for (uint32_t i = 0; i < m->width; ++i)
            for (int k = 0; k < 3; ++k) s[k] += row[3 * i + k];
        const double om = texel_omega(m, j);
        for (int k = 0; k < 3; ++k) out[k] += s[k] * om;
    }
    for (int k = 0; k < 3; ++k) out[k] *= m->scale;
}

/* ------------------------------------------------------------------------------------------ SH */

void glow_eval_envmap_sh9(const glow_eval_envmap *m, double out[27]) {
    memset(out, 0, 27 * sizeof *out);
    const uint32_t W = m->width, H = m->height;
    /* per column: the φ integrals over [a, b] (world φ = map φ - rotation) of 1, sin, cos, sin², cos², sin cos */
    double (*P)[6] = malloc((size_t)W * sizeof *P);
    if (!P) return;
    for (uint32_t i = 0; i < W; ++i) {
        const double a = 2.0 * PI_D * i / W - m->rot_rad, b = 2.0 * PI_D * (i + 1) / W - m->rot_rad;
        const double sa = sin(a), sb = sin(b), ca = cos(a), cb = cos(b);
        P[i][0] = b - a;
        P[i][1] = ca - cb;
        P[i][2] = sb - sa;
        P[i][3] = 0.5 * (b - a) - 0.25 * (sin(2.0 * b) - sin(2.0 * a));
        P[i][4] = 0.5 * (b - a) + 0.25 * (sin(2.0 * b) - sin(2.0 * a));
        P[i][5] = 0.5 * (sb * sb - sa * sa);
    }
    for (uint32_t j = 0; j < H; ++j) {
        /* the θ integrals with the measure sin θ dθ, t = cos θ from t0 (top) to t1 */
        const double t0 = m->cos_theta[j], t1 = m->cos_theta[j + 1];
        const double th0 = PI_D * j / H, th1 = PI_D * (j + 1) / H;
        const double s0 = sin(th0), s1 = sin(th1);
        const double T0 = t0 - t1;                                  /* ∫ sin θ */
        const double Tc = 0.5 * (t0 * t0 - t1 * t1);                /* ∫ cos θ sin θ */
        const double Tcc = (t0 * t0 * t0 - t1 * t1 * t1) / 3.0;     /* ∫ cos² θ sin θ */
        const double Ts = 0.5 * (th1 - th0) - 0.25 * (sin(2.0 * th1) - sin(2.0 * th0)); /* ∫ sin² θ */
        const double Tsc = (s1 * s1 * s1 - s0 * s0 * s0) / 3.0;     /* ∫ sin² θ cos θ */
        const double Tss = T0 - Tcc;                                /* ∫ sin³ θ */
        double acc[9][3];
        memset(acc, 0, sizeof acc);
        const float *row = m->rgb + 3 * (size_t)j * W;
        for (uint32_t i = 0; i < W; ++i) {
            const double *p = P[i];
            /* monomials over the texel: x = -sin θ sin φ, y = cos θ, z = sin θ cos φ */
            const double one = T0 * p[0], x = -Ts * p[1], y = Tc * p[0], z = Ts * p[2];
            const double xy = -Tsc * p[1], yz = Tsc * p[2], xz = -Tss * p[5];
            const double xx = Tss * p[3], zz = Tss * p[4], yy = Tcc * p[0];
            const double b[9] = {0.28209479177387814 * one, 0.48860251190291992 * y, 0.48860251190291992 * z,
                                 0.48860251190291992 * x,   1.0925484305920792 * xy, 1.0925484305920792 * yz,
                                 0.31539156525252005 * (3.0 * zz - one), 1.0925484305920792 * xz,
                                 0.54627421529603959 * (xx - yy)};
            for (int k = 0; k < 9; ++k)
                for (int c = 0; c < 3; ++c) acc[k][c] += b[k] * row[3 * i + c];
        }
        for (int k = 0; k < 9; ++k)
            for (int c = 0; c < 3; ++c) out[3 * k + c] += acc[k][c];
    }
    free(P);
    for (int k = 0; k < 27; ++k) out[k] *= m->scale;
}

void glow_eval_envmap_irradiance(const glow_eval_envmap *m, const float n[3], double out[3]) {
    out[0] = out[1] = out[2] = 0.0;
    double *trig = column_trig(m);
    if (!trig) {
        out[0] = out[1] = out[2] = NAN;
        return;
    }
    for (uint32_t j = 0; j < m->height; ++j) {
        const double om = texel_omega(m, j), th = PI_D * (j + 0.5) / m->height, ct = cos(th), st = sin(th);
        const float *row = m->rgb + 3 * (size_t)j * m->width;
        for (uint32_t i = 0; i < m->width; ++i) {
            double d[3];
            texel_dir(trig, i, ct, st, d);
            const double c = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
            if (c > 0.0)
                for (int k = 0; k < 3; ++k) out[k] += c * om * row[3 * i + k];
        }
    }
    free(trig);
    for (int k = 0; k < 3; ++k) out[k] *= m->scale;
}

void glow_eval_sh9_irradiance(const double sh[27], const float n[3], double out[3]) {
    const double x = n[0], y = n[1], z = n[2];
    const double a0 = PI_D, a1 = 2.0 * PI_D / 3.0, a2 = PI_D / 4.0;
    const double b[9] = {a0 * 0.28209479177387814,      a1 * 0.48860251190291992 * y,
                         a1 * 0.48860251190291992 * z,  a1 * 0.48860251190291992 * x,
                         a2 * 1.0925484305920792 * x * y, a2 * 1.0925484305920792 * y * z,
                         a2 * 0.31539156525252005 * (3.0 * z * z - 1.0), a2 * 1.0925484305920792 * x * z,
                         a2 * 0.54627421529603959 * (x * x - y * y)};
    for (int c = 0; c < 3; ++c) {
        out[c] = 0.0;
        for (int k = 0; k < 9; ++k) out[c] += b[k] * sh[3 * k + c];
    }
}

/* ------------------------------------------------------------------------------------------ sun */

glow_result glow_eval_envmap_extract_sun(const glow_eval_envmap *m, const glow_eval_envmap_sun_params *params,
                                         glow_eval_envmap_sun *out, glow_eval_envmap *out_residual, char *message,
                                         size_t message_size) {
    if (out) memset(out, 0, sizeof *out);
    if (out_residual) memset(out_residual, 0, sizeof *out_residual);
    if (!m || !out || !m->rgb) {
        set_message(message, message_size, "envmap: NULL argument to glow_eval_envmap_extract_sun");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_eval_envmap_sun_params p = params ? *params : (glow_eval_envmap_sun_params){0};
    if (p.max_radius_deg == 0.0f) p.max_radius_deg = 5.0f;
    if (p.threshold == 0.0f) p.threshold = 8.0f;
    if (!isfinite(p.max_radius_deg) || p.max_radius_deg < 0.0f || p.max_radius_deg > 45.0f || !isfinite(p.threshold) ||
        p.threshold < 1.0f) {
        set_message(message, message_size, "envmap: sun parameters: max_radius_deg %g must be in (0, 45], threshold %g >= 1",
                    (double)p.max_radius_deg, (double)p.threshold);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t W = m->width, H = m->height;
    glow_eval_image res = {0};
    double *trig = column_trig(m);
    if (!trig || glow_eval_image_alloc(&res, W, H) != GLOW_OK) {
        free(trig);
        set_message(message, message_size, "envmap: out of memory");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    memcpy(res.rgb, m->rgb, (size_t)W * H * 3 * sizeof *res.rgb);
    /* (1) the brightest texel */
    size_t best = 0;
    double ybest = -1.0;
    for (size_t t = 0, n = (size_t)W * H; t < n; ++t) {
        const double y = luma(m->rgb + 3 * t);
        if (y > ybest) {
            ybest = y;
            best = t;
        }
    }
    const uint32_t bi = (uint32_t)(best % W), bj = (uint32_t)(best / W);
    double d0[3];
    dir_of(m, cos(PI_D * (bj + 0.5) / H), 2.0 * PI_D * (bi + 0.5) / W, d0);
    double R = (double)p.max_radius_deg * PI_D / 180.0;
    if (R < 2.0 * PI_D / H) R = 2.0 * PI_D / H;
    const double cosR = cos(R), cos2R = cos(fmin(2.0 * R, PI_D));
    /* (2) the surroundings */
    double bg[3] = {0, 0, 0}, bg_w = 0.0;
    for (uint32_t j = 0; j < H; ++j) {
        const double om = texel_omega(m, j), th = PI_D * (j + 0.5) / H, ct = cos(th), st = sin(th);
        if (cos(fabs(th - acos(fmin(fmax(d0[1], -1.0), 1.0)))) < cos2R) continue; /* the whole row is too far */
        for (uint32_t i = 0; i < W; ++i) {
            double d[3];
            texel_dir(trig, i, ct, st, d);
            const double c = d[0] * d0[0] + d[1] * d0[1] + d[2] * d0[2];
            if (c < cosR && c >= cos2R) {
                const float *t = m->rgb + 3 * ((size_t)j * W + i);
                for (int k = 0; k < 3; ++k) bg[k] += om * t[k];
                bg_w += om;
            }
        }
    }
    float lbg[3] = {0, 0, 0};
    if (bg_w > 0.0)
        for (int k = 0; k < 3; ++k) lbg[k] = (float)(bg[k] / bg_w);
    const double T = p.threshold * luma(lbg);
    const float *bt = m->rgb + 3 * best;
    for (int k = 0; k < 3; ++k) {
        out->background[k] = m->scale * lbg[k];
        out->brightest[k] = m->scale * bt[k];
    }
    /* (3), (4) the sun's texels */
    if (ybest > T && ybest > 0.0) {
        double e[3] = {0, 0, 0}, c[3] = {0, 0, 0}, om_sun = 0.0;
        uint32_t count = 0;
        for (uint32_t j = 0; j < H; ++j) {
            const double om = texel_omega(m, j), th = PI_D * (j + 0.5) / H, ct = cos(th), st = sin(th);
            for (uint32_t i = 0; i < W; ++i) {
                const size_t t = (size_t)j * W + i;
                const float *L = m->rgb + 3 * t;
                if (!(luma(L) > T)) continue;
                double d[3];
                texel_dir(trig, i, ct, st, d);
                if (d[0] * d0[0] + d[1] * d0[1] + d[2] * d0[2] < cosR) continue;
                float rest[3], gone[3];
                for (int k = 0; k < 3; ++k) {
                    rest[k] = fminf(L[k], lbg[k]);
                    gone[k] = L[k] - rest[k];
                    e[k] += om * gone[k];
                    res.rgb[3 * t + k] = rest[k];
                }
                const double wy = luma(gone) * om;
                for (int k = 0; k < 3; ++k) c[k] += wy * d[k];
                om_sun += om;
                count++;
            }
        }
        const double cl = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        out->found = count > 0;
        for (int k = 0; k < 3; ++k) {
            out->to_sun[k] = (float)(cl > 0.0 ? c[k] / cl : d0[k]);
            out->irradiance[k] = (float)(m->scale * e[k]);
        }
        out->solid_angle_sr = (float)om_sun;
        out->radius_deg = (float)(acos(fmax(-1.0, 1.0 - om_sun / (2.0 * PI_D))) * 180.0 / PI_D);
        out->texel_count = count;
    }
    free(trig);
    glow_result r = GLOW_OK;
    if (out_residual)
        r = glow_eval_envmap_from_image(&res, m->rotation_deg, m->scale, "envmap residual", out_residual, message,
                                        message_size);
    glow_eval_image_free(&res);
    return r;
}

glow_result glow_eval_envmap_sky_sh(const glow_eval_envmap *m, bool split, const glow_eval_envmap_sun_params *params,
                                    float out[27], glow_eval_envmap_sun *out_sun, char *message, size_t message_size) {
    if (out) memset(out, 0, 27 * sizeof *out);
    if (out_sun) memset(out_sun, 0, sizeof *out_sun);
    if (!m || !m->rgb || !out || (split && !out_sun)) {
        set_message(message, message_size, "envmap: NULL argument to glow_eval_envmap_sky_sh");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    double sh[27];
    if (!split) {
        glow_eval_envmap_sh9(m, sh);
    } else {
        glow_eval_envmap res;
        glow_result r = glow_eval_envmap_extract_sun(m, params, out_sun, &res, message, message_size);
        if (r != GLOW_OK) return r;
        glow_eval_envmap_sh9(&res, sh);
        glow_eval_envmap_free(&res);
    }
    for (int k = 0; k < 27; ++k) out[k] = (float)sh[k];
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------------- generator */

glow_eval_skymap_params glow_eval_skymap_defaults(void) {
    return (glow_eval_skymap_params){.width = 512,
                                     .sun_elevation_deg = 35.0f,
                                     .sun_azimuth_deg = 30.0f,
                                     .sun_radius_deg = 0.5f,
                                     .sun_irradiance = {9.0f, 8.5f, 7.5f},
                                     .zenith = {0.2f, 0.3f, 0.55f},
                                     .horizon = {0.45f, 0.5f, 0.55f},
                                     .ground = {0.08f, 0.07f, 0.06f}};
}

static bool nonneg3(const float v[3]) {
    for (int k = 0; k < 3; ++k)
        if (!isfinite(v[k]) || v[k] < 0.0f) return false;
    return true;
}

glow_result glow_eval_skymap(const glow_eval_skymap_params *pp, glow_eval_image *out, char *message,
                             size_t message_size) {
    if (out) memset(out, 0, sizeof *out);
    if (!pp || !out) {
        set_message(message, message_size, "skymap: NULL argument");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_eval_skymap_params p = *pp;
    if (p.width == 0) p.width = 512;
    if (p.sun_radius_deg == 0.0f) p.sun_radius_deg = 0.5f;
    if (p.width < 4 || p.width > 16384 || p.width % 2) {
        set_message(message, message_size, "skymap: width %u must be even and in 4..16384", (unsigned)p.width);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!isfinite(p.sun_elevation_deg) || fabsf(p.sun_elevation_deg) > 90.0f || !isfinite(p.sun_azimuth_deg) ||
        !isfinite(p.sun_radius_deg) || !(p.sun_radius_deg > 0.0f) || p.sun_radius_deg > 45.0f) {
        set_message(message, message_size,
                    "skymap: sun elevation %g must be in [-90, 90], azimuth %g finite, radius %g in (0, 45]",
                    (double)p.sun_elevation_deg, (double)p.sun_azimuth_deg, (double)p.sun_radius_deg);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!nonneg3(p.sun_irradiance) || !nonneg3(p.zenith) || !nonneg3(p.horizon) || !nonneg3(p.ground)) {
        set_message(message, message_size, "skymap: colours and the sun's irradiance must be finite and >= 0");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t W = p.width, H = p.width / 2;
    if (glow_eval_image_alloc(out, W, H) != GLOW_OK) {
        set_message(message, message_size, "skymap: out of memory");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    /* a map frame with rotation 0, for the texel geometry */
    glow_eval_envmap geo = {.width = W, .height = H};
    geo.cos_theta = malloc((H + 1) * sizeof *geo.cos_theta);
    float *cov = calloc((size_t)W * H, sizeof *cov);
    if (!geo.cos_theta || !cov) {
        free(geo.cos_theta);
        free(cov);
        glow_eval_image_free(out);
        set_message(message, message_size, "skymap: out of memory");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    for (uint32_t j = 0; j <= H; ++j) geo.cos_theta[j] = cos(PI_D * j / H);
    geo.cos_theta[0] = 1.0;
    geo.cos_theta[H] = -1.0;
    geo.cos_theta[H / 2] = 0.0;
    const double el = (double)p.sun_elevation_deg * PI_D / 180.0, az = (double)p.sun_azimuth_deg * PI_D / 180.0;
    const double sd[3] = {sin(az) * cos(el), sin(el), -cos(az) * cos(el)};
    const double rr = (double)p.sun_radius_deg * PI_D / 180.0, cos_r = cos(rr);
    /* texels whose centre is within the disc + 2 texel diagonals are sub-sampled */
    const double cos_near = cos(fmin(PI_D, rr + 2.0 * 1.5 * 2.0 * PI_D / W));
    const bool sun = p.sun_irradiance[0] > 0.0f || p.sun_irradiance[1] > 0.0f || p.sun_irradiance[2] > 0.0f;
    double cov_w = 0.0;
    for (uint32_t j = 0; j < H; ++j) {
        const double ct = cos(PI_D * (j + 0.5) / H), om = texel_omega(&geo, j);
        for (uint32_t i = 0; i < W; ++i) {
            double d[3];
            dir_of(&geo, ct, 2.0 * PI_D * (i + 0.5) / W, d);
            float *L = out->rgb + 3 * ((size_t)j * W + i);
            if (d[1] >= 0.0) {
                const double s = pow(d[1], 0.4);
                for (int k = 0; k < 3; ++k) L[k] = (float)(p.horizon[k] + (p.zenith[k] - p.horizon[k]) * s);
            } else {
                for (int k = 0; k < 3; ++k) L[k] = p.ground[k];
            }
            if (!sun || d[0] * sd[0] + d[1] * sd[1] + d[2] * sd[2] < cos_near) continue;
            int in = 0;
            for (int a = 0; a < 8; ++a)
                for (int b = 0; b < 8; ++b) {
                    double e[3];
                    const double c = geo.cos_theta[j] + (a + 0.5) / 8.0 * (geo.cos_theta[j + 1] - geo.cos_theta[j]);
                    dir_of(&geo, c, 2.0 * PI_D * (i + (b + 0.5) / 8.0) / W, e);
                    in += e[0] * sd[0] + e[1] * sd[1] + e[2] * sd[2] >= cos_r;
                }
            cov[(size_t)j * W + i] = (float)in / 64.0f;
            cov_w += in / 64.0 * om;
        }
    }
    if (sun && !(cov_w > 0.0)) { /* a disc smaller than the sub-samples: the texel holding its centre */
        const float fd[3] = {(float)sd[0], (float)sd[1], (float)sd[2]};
        uint32_t j;
        const size_t t = texel_of(&geo, fd, &j);
        cov[t] = 1.0f;
        cov_w = texel_omega(&geo, j);
    }
    if (sun)
        for (size_t t = 0, n = (size_t)W * H; t < n; ++t)
            if (cov[t] > 0.0f)
                for (int k = 0; k < 3; ++k) out->rgb[3 * t + k] += (float)(p.sun_irradiance[k] * cov[t] / cov_w);
    free(cov);
    free(geo.cos_theta);
    return GLOW_OK;
}
