/* sh.c — the shading maths in C (PIC 3.2, App. B), the reference for the GLSL includes: SH basis,
 * cone and lobe factors, YCoCg, lobe convolution, grid and lightmap sampling. */
#include <math.h>
#include <string.h>

#include "runtime_internal.h"
#include "sh_kernel.h"

#define PI_D 3.14159265358979323846

void glow_sh_eval(uint32_t bands, const float dir[3], float *out) {
    if (!dir || !out || bands == 0) return;
    if (bands > GLOW__MAX_BANDS) bands = GLOW__MAX_BANDS;
    glow__v8f x = {dir[0]}, y = {dir[1]}, z = {dir[2]}; /* lane 0 used */
    glow__v8f v[GLOW__MAX_BANDS * GLOW__MAX_BANDS];
    glow__sh_eval_v8(bands, &x, &y, &z, v);
    for (uint32_t k = 0; k < bands * bands; ++k) out[k] = v[k][0];
}

void glow__legendre_all(uint32_t n, double x, double *p) {
    p[0] = 1.0;
    if (n >= 1) p[1] = x;
    for (uint32_t l = 1; l < n; ++l) p[l + 1] = ((2.0 * l + 1.0) * x * p[l] - l * p[l - 1]) / (l + 1.0);
}

double glow__cone_factor_omc(uint32_t l, double omc) {
    if (l == 0) return 2.0 * PI_D * omc;
    /* the recurrence of glow__legendre_all with a sliding window (any l): (a, b) = (P_k, P_{k+1}) */
    const double x = 1.0 - omc;
    double a = 1.0, b = x, pl_minus_1 = 1.0;
    for (uint32_t k = 1; k <= l; ++k) {
        const double c = ((2.0 * k + 1.0) * x * b - k * a) / (k + 1.0);
        pl_minus_1 = a; /* P_{k-1} */
        a = b;
        b = c;
    }
    return 2.0 * PI_D / (2.0 * l + 1.0) * (pl_minus_1 - b);
}

float glow_sh_cone_factor(uint32_t l, float x) { return (float)glow__cone_factor_omc(l, 1.0 - (double)x); }

float glow_sh_lobe_factor(uint32_t l, float n) {
    /* s_0 = 1, s_1 = (n+1)/(n+2), s_l = s_{l-2} (n+2-l)/(n+1+l) */
    double s = (l & 1u) ? ((double)n + 1.0) / ((double)n + 2.0) : 1.0;
    for (uint32_t k = (l & 1u) ? 3u : 2u; k <= l; k += 2u) s *= ((double)n + 2.0 - k) / ((double)n + 1.0 + k);
    return (float)s;
}

float glow_sh_window_factor(uint32_t l, uint32_t bands) {
    if (l >= bands) return 0.0f;
    if (l == 0) return 1.0f;
    const double x = PI_D * (double)l / (double)bands;
    return (float)(sin(x) / x);
}

void glow_rgb_to_ycocg(const float rgb[3], float out[3]) {
    const float r = rgb[0], g = rgb[1], b = rgb[2];
    out[0] = 0.25f * r + 0.5f * g + 0.25f * b;
    out[1] = 0.5f * r - 0.5f * b;
    out[2] = -0.25f * r + 0.5f * g - 0.25f * b;
}

void glow_ycocg_to_rgb(const float ycocg[3], float out[3]) {
    const float y = ycocg[0], co = ycocg[1], cg = ycocg[2];
    out[0] = y + co - cg;
    out[1] = y + cg;
    out[2] = y - co - cg;
}

void glow_shade_sh_factors(const float *coeffs, uint32_t luma, uint32_t chroma, const float axis[3],
                           const float *factors, float out_rgb[3]) {
    if (!out_rgb) return;
    out_rgb[0] = out_rgb[1] = out_rgb[2] = 0.0f;
    if (!coeffs || !axis || !factors || luma == 0 || luma > GLOW__MAX_BANDS || chroma > luma) return;
    float y[GLOW__MAX_BANDS * GLOW__MAX_BANDS];
    glow_sh_eval(luma, axis, y);
    const float *co = coeffs + luma * luma, *cg = co + chroma * chroma;
    float ycc[3] = {0, 0, 0};
    for (uint32_t l = 0; l < luma; ++l) {
        const float s = factors[l];
        float sy = 0.0f, sco = 0.0f, scg = 0.0f;
        for (uint32_t k = l * l; k < (l + 1) * (l + 1); ++k) {
            sy += coeffs[k] * y[k];
            if (l < chroma) {
                sco += co[k] * y[k];
                scg += cg[k] * y[k];
            }
        }
        ycc[0] += s * sy;
        ycc[1] += s * sco;
        ycc[2] += s * scg;
    }
    glow_ycocg_to_rgb(ycc, out_rgb);
}

void glow_shade_sh(const float *coeffs, uint32_t luma, uint32_t chroma, const float axis[3], float exponent,
                   float out_rgb[3]) {
    float s[GLOW__MAX_BANDS];
    const uint32_t n = luma < GLOW__MAX_BANDS ? luma : GLOW__MAX_BANDS;
    for (uint32_t l = 0; l < n; ++l) s[l] = glow_sh_lobe_factor(l, exponent);
    glow_shade_sh_factors(coeffs, luma, chroma, axis, s, out_rgb);
}

/* Weighted sum of cache rows; empty entries get weight 0 and the rest are renormalised. */
static glow_result blend(const glow_cache_outputs *o, const uint32_t *idx, const float *w, int n, float *out) {
    const uint32_t nc = o->coeff_count;
    memset(out, 0, nc * sizeof *out);
    float wsum = 0.0f;
    for (int i = 0; i < n; ++i)
        if (idx[i] != GLOW_MAP_EMPTY && w[i] > 0.0f) wsum += w[i];
    if (!(wsum > 0.0f)) return GLOW_ERROR_OUT_OF_RANGE;
    for (int i = 0; i < n; ++i) {
        if (idx[i] == GLOW_MAP_EMPTY || !(w[i] > 0.0f)) continue;
        const float *row = o->cache_sh + (size_t)idx[i] * nc;
        float wi = w[i] / wsum;
        for (uint32_t k = 0; k < nc; ++k) out[k] += wi * row[k];
    }
    return GLOW_OK;
}

static void axis_coord(float f, uint32_t dim, uint32_t *i0, uint32_t *i1, float *t) {
    float maxf = (float)(dim - 1u);
    if (!(f > 0.0f)) f = 0.0f; /* also NaN */
    if (f > maxf) f = maxf;
    float fl = floorf(f);
    *i0 = (uint32_t)fl;
    *i1 = *i0 + 1u < dim ? *i0 + 1u : *i0;
    *t = f - fl;
}

/* The 8 corner weights of a cell lookup: trilinear (t), the octant's visibility mask, and with a normal
 * n the backface weight about p_in (corner positions from the lattice's origin o and spacing h, the
 * cell's lowest corner lattice index i0 and the clamped upper one i1). */
static void corner_weights(const float t[3], uint32_t vis, const float *n, const float p_in[3], const float o[3],
                           float h, const uint32_t i0[3], const uint32_t i1[3], float w[8]) {
    for (int c = 0; c < 8; ++c) {
        w[c] = ((c & 1) ? t[0] : 1.0f - t[0]) * ((c & 2) ? t[1] : 1.0f - t[1]) * ((c & 4) ? t[2] : 1.0f - t[2]);
        if (!((vis >> c) & 1u)) w[c] = 0.0f;
        if (n && w[c] > 0.0f) { /* corners behind the surface count less (see glow.h) */
            const uint32_t x = (c & 1) ? i1[0] : i0[0], y = (c & 2) ? i1[1] : i0[1], z = (c & 4) ? i1[2] : i0[2];
            const float d[3] = {o[0] + h * (float)x - p_in[0], o[1] + h * (float)y - p_in[1], o[2] + h * (float)z - p_in[2]};
            const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            const float hw = len > 0.0f ? 0.5f * (1.0f + (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / len) : 1.0f;
            w[c] *= hw * hw + GLOW_GRID_BACKFACE_FLOOR;
        }
    }
}

/* The refined grid's lookup at p (the moved point) in brick b of coarse cell c0 (f: p in coarse cell units). */
static glow_result brick_lookup(const glow_cache_outputs *o, const float f[3], const uint32_t c0[3], uint32_t b,
                                const float p_in[3], const float *n, float *out) {
    const uint32_t R = o->grid_refine, side = R + 1u;
    uint32_t i0[3], i1[3];
    float t[3], fo[3];
    for (int a = 0; a < 3; ++a) {
        float u = (f[a] - (float)c0[a]) * (float)R; /* in [0, R] */
        if (!(u > 0.0f)) u = 0.0f;
        if (u > (float)R) u = (float)R;
        float fl = floorf(u);
        if (fl > (float)(R - 1u)) fl = (float)(R - 1u);
        i0[a] = (uint32_t)fl;
        i1[a] = i0[a] + 1u;
        t[a] = u - fl;
    }
    const float h = o->grid_spacing / (float)R;
    for (int a = 0; a < 3; ++a) fo[a] = o->grid_origin[a] + o->grid_spacing * (float)c0[a]; /* the brick's lattice origin */
    uint32_t vis = 0xFFu;
    if (o->grid_brick_visibility) {
        const uint32_t oct = (t[0] >= 0.5f ? 1u : 0u) | (t[1] >= 0.5f ? 2u : 0u) | (t[2] >= 0.5f ? 4u : 0u);
        const size_t cell = ((size_t)i0[2] * R + i0[1]) * R + i0[0];
        vis = o->grid_brick_visibility[((size_t)b * R * R * R + cell) * 8u + oct];
    }
    float w[8];
    uint32_t idx[8];
    corner_weights(t, vis, n, p_in, fo, h, i0, i1, w);
    const uint32_t *e = o->grid_bricks + (size_t)b * side * side * side;
    for (int c = 0; c < 8; ++c) {
        const uint32_t x = (c & 1) ? i1[0] : i0[0], y = (c & 2) ? i1[1] : i0[1], z = (c & 4) ? i1[2] : i0[2];
        idx[c] = e[((size_t)z * side + y) * side + x];
    }
    return blend(o, idx, w, 8, out);
}

/* The grid lookup of glow_sample_grid (n == NULL) and glow_sample_grid_oriented (unit normal n): the
 * fine cell of the point's brick when the grid is refined there and one of its corners may be blended,
 * else the coarse cell. */
static glow_result grid_lookup(const glow_cache_outputs *o, const float p_in[3], const float *n, float *out) {
    if (!o || !p_in || !out || !o->grid_map || o->grid_dims[0] == 0 || !(o->grid_spacing > 0.0f))
        return GLOW_ERROR_INVALID_ARGUMENT;
    float p[3] = {p_in[0], p_in[1], p_in[2]};
    if (n)
        for (int a = 0; a < 3; ++a) p[a] += GLOW_GRID_NORMAL_BIAS * o->grid_spacing / (o->grid_refine ? (float)o->grid_refine : 1.0f) * n[a];
    uint32_t i0[3], i1[3];
    float t[3], f[3];
    for (int a = 0; a < 3; ++a) {
        f[a] = (p[a] - o->grid_origin[a]) / o->grid_spacing;
        axis_coord(f[a], o->grid_dims[a], &i0[a], &i1[a], &t[a]);
    }
    const uint32_t dx = o->grid_dims[0], dxy = dx * o->grid_dims[1];
    if (o->grid_refine >= 2 && o->grid_bricks && o->grid_brick_of_cell) {
        int inside = 1; /* a point outside the grid's box takes the clamped coarse lookup */
        for (int a = 0; a < 3; ++a) inside &= f[a] >= 0.0f && f[a] <= (float)(o->grid_dims[a] - 1u);
        if (inside) {
            uint32_t c0[3];
            for (int a = 0; a < 3; ++a) c0[a] = i0[a] + 1u < o->grid_dims[a] ? i0[a] : i0[a] - 1u; /* the last point: the cell below */
            const uint32_t b = o->grid_brick_of_cell[(size_t)c0[2] * dxy + (size_t)c0[1] * dx + c0[0]];
            if (b != 0xFFFFFFFFu && b < o->grid_brick_count && brick_lookup(o, f, c0, b, p_in, n, out) == GLOW_OK)
                return GLOW_OK;
        }
    }
    uint32_t idx[8];
    float w[8];
    uint32_t vis = 0xFFu;
    if (o->grid_visibility) { /* the corners visible from this octant of the cell (GVIS) */
        const uint32_t oct = (t[0] >= 0.5f ? 1u : 0u) | (t[1] >= 0.5f ? 2u : 0u) | (t[2] >= 0.5f ? 4u : 0u);
        vis = o->grid_visibility[((size_t)i0[2] * dxy + (size_t)i0[1] * dx + i0[0]) * 8u + oct];
    }
    corner_weights(t, vis, n, p_in, o->grid_origin, o->grid_spacing, i0, i1, w);
    for (int c = 0; c < 8; ++c) {
        uint32_t x = (c & 1) ? i1[0] : i0[0], y = (c & 2) ? i1[1] : i0[1], z = (c & 4) ? i1[2] : i0[2];
        idx[c] = o->grid_map[(size_t)z * dxy + (size_t)y * dx + x];
    }
    return blend(o, idx, w, 8, out);
}

glow_result glow_sample_grid(const glow_cache_outputs *o, const float p[3], float *out) {
    return grid_lookup(o, p, NULL, out);
}

glow_result glow_sample_grid_oriented(const glow_cache_outputs *o, const float p[3], const float normal[3], float *out) {
    if (!normal) return GLOW_ERROR_INVALID_ARGUMENT;
    const float l2 = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2];
    if (!(l2 > 0.0f) || !isfinite(l2)) return GLOW_ERROR_INVALID_ARGUMENT;
    const float inv = 1.0f / sqrtf(l2), n[3] = {normal[0] * inv, normal[1] * inv, normal[2] * inv};
    return grid_lookup(o, p, n, out);
}

/* The pages are stacked (page * width * height + y * width + x); a lookup stays within its page. */
glow_result glow_sample_lightmap_page(const glow_cache_outputs *o, uint32_t page, float u, float v, float *out) {
    if (!out || !o || !o->lightmap_map || o->lightmap_width == 0) return GLOW_ERROR_INVALID_ARGUMENT;
    if (page > 0 && page >= o->lightmap_pages) return GLOW_ERROR_INVALID_ARGUMENT;
    uint32_t x0, x1, y0, y1;
    float tx, ty;
    axis_coord(u * (float)o->lightmap_width - 0.5f, o->lightmap_width, &x0, &x1, &tx);
    axis_coord(v * (float)o->lightmap_height - 0.5f, o->lightmap_height, &y0, &y1, &ty);
    const uint32_t W = o->lightmap_width;
    const uint32_t *map = o->lightmap_map + (size_t)page * W * o->lightmap_height;
    uint32_t idx[4] = {map[(size_t)y0 * W + x0], map[(size_t)y0 * W + x1], map[(size_t)y1 * W + x0],
                       map[(size_t)y1 * W + x1]};
    float w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
    return blend(o, idx, w, 4, out);
}

glow_result glow_sample_lightmap(const glow_cache_outputs *o, float u, float v, float *out) {
    return glow_sample_lightmap_page(o, 0u, u, v, out);
}

glow_result glow_sample_lightmap_detail(const glow_cache_outputs *o, float u, float v, float out[3]) {
    return glow_sample_lightmap_detail_page(o, 0u, u, v, out);
}

glow_result glow_sample_lightmap_detail_page(const glow_cache_outputs *o, uint32_t page, float u, float v,
                                             float out[3]) {
    if (!out) return GLOW_ERROR_INVALID_ARGUMENT;
    out[0] = out[1] = out[2] = 0.0f;
    if (!o || !o->lightmap_detail || o->detail_width == 0 || o->detail_height == 0) return GLOW_ERROR_INVALID_ARGUMENT;
    if (page > 0 && page >= o->lightmap_pages) return GLOW_ERROR_INVALID_ARGUMENT;
    uint32_t x0, x1, y0, y1;
    float tx, ty;
    axis_coord(u * (float)o->detail_width - 0.5f, o->detail_width, &x0, &x1, &tx);
    axis_coord(v * (float)o->detail_height - 0.5f, o->detail_height, &y0, &y1, &ty);
    const size_t W = o->detail_width;
    const size_t idx[4] = {(size_t)y0 * W + x0, (size_t)y0 * W + x1, (size_t)y1 * W + x0, (size_t)y1 * W + x1};
    const float w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
    float rgb[3] = {0.0f, 0.0f, 0.0f}, a = 0.0f;
    for (int i = 0; i < 4; ++i) {
        const float *t = o->lightmap_detail + 4 * ((size_t)page * W * o->detail_height + idx[i]);
        for (int k = 0; k < 3; ++k) rgb[k] += w[i] * t[k];
        a += w[i] * t[3];
    }
    if (!(a > 1e-6f)) return GLOW_ERROR_OUT_OF_RANGE;
    for (int k = 0; k < 3; ++k) out[k] = rgb[k] / a;
    return GLOW_OK;
}

/* ------------------------------------------------------------------ sky SH (docs/sky.md) */
/* RGB l <= 2 SH, coefficient-major: sh[3 k + c], k < 9 (glow_sh_eval's order), c = R, G, B. */

void glow_sh_sky_constant(const float radiance_rgb[3], float out_rgb[GLOW_SKY_SH_FLOATS]) {
    if (!out_rgb) return;
    memset(out_rgb, 0, GLOW_SKY_SH_FLOATS * sizeof *out_rgb);
    if (!radiance_rgb) return;
    const float s = (float)sqrt(4.0 * PI_D); /* y_0 = 1/sqrt(4π): L_0 = L sqrt(4π) */
    for (int c = 0; c < 3; ++c) out_rgb[c] = radiance_rgb[c] * s;
}

/* Band-2 constants of glow_sh_eval: y_4 = C2 xy, y_5 = C2 yz, y_6 = C0 (3z² - 1), y_7 = C2 xz,
 * y_8 = C1 (x² - y²) */
#define SH_C2 1.0925484305920792
#define SH_C0 0.31539156525252005
#define SH_C1 0.54627421529603959

void glow_sh_rotate_l2(const float rotation[9], const float in_rgb[GLOW_SKY_SH_FLOATS], float out_rgb[GLOW_SKY_SH_FLOATS]) {
    if (!rotation || !in_rgb || !out_rgb) return;
    double R[3][3], o[GLOW_SKY_SH_FLOATS];
    for (int i = 0; i < 9; ++i) R[i / 3][i % 3] = rotation[i];
    for (int c = 0; c < 3; ++c) {
        o[c] = in_rgb[c];
        /* band 1 is a linear form v·ω, v = (x, y, z) = (in_3, in_1, in_2): it turns to R v */
        const double v[3] = {in_rgb[9 + c], in_rgb[3 + c], in_rgb[6 + c]};
        double w[3];
        for (int i = 0; i < 3; ++i) w[i] = R[i][0] * v[0] + R[i][1] * v[1] + R[i][2] * v[2];
        o[9 + c] = w[0];
        o[3 + c] = w[1];
        o[6 + c] = w[2];
        /* band 2 is a traceless quadratic form ω^T Q ω: it turns to R Q R^T */
        const double a = in_rgb[12 + c] * SH_C2, b = in_rgb[15 + c] * SH_C2, g = in_rgb[18 + c] * SH_C0,
                     d = in_rgb[21 + c] * SH_C2, e = in_rgb[24 + c] * SH_C1;
        const double Q[3][3] = {{e - g, 0.5 * a, 0.5 * d}, {0.5 * a, -e - g, 0.5 * b}, {0.5 * d, 0.5 * b, 2.0 * g}};
        double RQ[3][3], P[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) RQ[i][j] = R[i][0] * Q[0][j] + R[i][1] * Q[1][j] + R[i][2] * Q[2][j];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) P[i][j] = RQ[i][0] * R[j][0] + RQ[i][1] * R[j][1] + RQ[i][2] * R[j][2];
        o[12 + c] = 2.0 * P[0][1] / SH_C2;
        o[15 + c] = 2.0 * P[1][2] / SH_C2;
        o[18 + c] = 0.5 * P[2][2] / SH_C0;
        o[21 + c] = 2.0 * P[0][2] / SH_C2;
        o[24 + c] = 0.5 * (P[0][0] - P[1][1]) / SH_C1;
    }
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k) out_rgb[k] = (float)o[k]; /* in == out allowed */
}

void glow_sh_rotate_y(const float in_rgb[GLOW_SKY_SH_FLOATS], float angle_radians, float out_rgb[GLOW_SKY_SH_FLOATS]) {
    const double c = cos((double)angle_radians), s = sin((double)angle_radians);
    const float R[9] = {(float)c, 0.0f, (float)s, 0.0f, 1.0f, 0.0f, (float)-s, 0.0f, (float)c};
    glow_sh_rotate_l2(R, in_rgb, out_rgb);
}

void glow_sh_sky_irradiance(const float transfer[9], const float sky_rgb[GLOW_SKY_SH_FLOATS], float out_rgb[3]) {
    if (!out_rgb) return;
    out_rgb[0] = out_rgb[1] = out_rgb[2] = 0.0f;
    if (!transfer || !sky_rgb) return;
    float e[3] = {0.0f, 0.0f, 0.0f};
    for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c) e[c] += transfer[k] * sky_rgb[3 * k + c];
    for (int c = 0; c < 3; ++c) out_rgb[c] = e[c] > 0.0f ? e[c] : 0.0f; /* also NaN -> 0 */
}

/* The triple products ∫ y_i y_j y_k over the sphere (Gaunt coefficients of the real basis) that are not
 * zero for i, j, k < 9: 83 entries, from
 *   A = 1/(2√π), B = √(3/(20π)), C = 1/(2√(5π)), D = 2C, E = √5/(7√π), F = √15/(14√π), G = E/2,
 * checked against quadrature in tests/unit/test_sky.c. */
#define GA 0.28209479177387814f
#define GB 0.21850968611841584f
#define GC 0.12615662610100800f
#define GD 0.25231325220201600f
#define GE 0.18022375157286857f
#define GF 0.15607834722743985f
#define GG 0.09011187578643429f
static const struct { uint8_t i, j, k; float g; } gaunt_l2[] = {
#define A GA
#define B GB
#define C GC
#define D GD
#define E GE
#define F GF
#define G GG
    {0, 0, 0, A}, {0, 1, 1, A}, {0, 2, 2, A}, {0, 3, 3, A}, {0, 4, 4, A}, {0, 5, 5, A},
    {0, 6, 6, A}, {0, 7, 7, A}, {0, 8, 8, A}, {1, 0, 1, A}, {1, 1, 0, A}, {1, 1, 6, -C},
    {1, 1, 8, -B}, {1, 2, 5, B}, {1, 3, 4, B}, {1, 4, 3, B}, {1, 5, 2, B}, {1, 6, 1, -C},
    {1, 8, 1, -B}, {2, 0, 2, A}, {2, 1, 5, B}, {2, 2, 0, A}, {2, 2, 6, D}, {2, 3, 7, B},
    {2, 5, 1, B}, {2, 6, 2, D}, {2, 7, 3, B}, {3, 0, 3, A}, {3, 1, 4, B}, {3, 2, 7, B},
    {3, 3, 0, A}, {3, 3, 6, -C}, {3, 3, 8, B}, {3, 4, 1, B}, {3, 6, 3, -C}, {3, 7, 2, B},
    {3, 8, 3, B}, {4, 0, 4, A}, {4, 1, 3, B}, {4, 3, 1, B}, {4, 4, 0, A}, {4, 4, 6, -E},
    {4, 5, 7, F}, {4, 6, 4, -E}, {4, 7, 5, F}, {5, 0, 5, A}, {5, 1, 2, B}, {5, 2, 1, B},
    {5, 4, 7, F}, {5, 5, 0, A}, {5, 5, 6, G}, {5, 5, 8, -F}, {5, 6, 5, G}, {5, 7, 4, F},
    {5, 8, 5, -F}, {6, 0, 6, A}, {6, 1, 1, -C}, {6, 2, 2, D}, {6, 3, 3, -C}, {6, 4, 4, -E},
    {6, 5, 5, G}, {6, 6, 0, A}, {6, 6, 6, E}, {6, 7, 7, G}, {6, 8, 8, -E}, {7, 0, 7, A},
    {7, 2, 3, B}, {7, 3, 2, B}, {7, 4, 5, F}, {7, 5, 4, F}, {7, 6, 7, G}, {7, 7, 0, A},
    {7, 7, 6, G}, {7, 7, 8, F}, {7, 8, 7, F}, {8, 0, 8, A}, {8, 1, 1, -B}, {8, 3, 3, B},
    {8, 5, 5, -F}, {8, 6, 8, -E}, {8, 7, 7, F}, {8, 8, 0, A}, {8, 8, 6, -E},
#undef A
#undef B
#undef C
#undef D
#undef E
#undef F
#undef G
};

void glow_sh_sky_visible(const float visibility[9], const float sky_rgb[GLOW_SKY_SH_FLOATS], float out_rgb[GLOW_SKY_SH_FLOATS]) {
    if (!out_rgb) return;
    float o[GLOW_SKY_SH_FLOATS] = {0};
    if (visibility && sky_rgb)
        for (size_t t = 0; t < sizeof gaunt_l2 / sizeof gaunt_l2[0]; ++t) {
            const float w = gaunt_l2[t].g * visibility[gaunt_l2[t].i];
            for (int c = 0; c < 3; ++c) o[3 * gaunt_l2[t].k + c] += w * sky_rgb[3 * gaunt_l2[t].j + c];
        }
    memcpy(out_rgb, o, sizeof o); /* out may alias an input */
}

float glow_sh_gaunt_l2(uint32_t i, uint32_t j, uint32_t k) {
    for (size_t t = 0; t < sizeof gaunt_l2 / sizeof gaunt_l2[0]; ++t)
        if (gaunt_l2[t].i == i && gaunt_l2[t].j == j && gaunt_l2[t].k == k) return gaunt_l2[t].g;
    return 0.0f;
}
