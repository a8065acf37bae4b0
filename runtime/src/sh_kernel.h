/*
 * sh_kernel.h — the one spherical-harmonics basis evaluation of the runtime (DESIGN §3: "one
 * basis-evaluation routine shared by every caller"), written on 8-lane float vectors so the
 * cache-lighting kernel evaluates 8 link directions at once; glow_sh_eval (scalar, public) and the
 * linker call the same code with one lane used.
 *
 * Convention: real orthonormal SH, l bands -> l*l values, index k*k + k + m; y_k^m =
 * sqrt(2) K_k^|m| P_k^|m|(cos θ) {cos(mφ) | sin(|m|φ)}, no Condon-Shortley phase, so
 * y_1^{-1} = c·y, y_1^0 = c·z, y_1^1 = c·x with c = sqrt(3/(4π)).
 *
 * GCC/Clang vector extensions (a documented departure from strict C11: the runtime's only one;
 * MSVC would need an intrinsics port of this file and cache_lighting.c).
 */
#ifndef GLOW_SH_KERNEL_H
#define GLOW_SH_KERNEL_H

#include <stdint.h>

typedef float glow__v8f __attribute__((vector_size(32)));
typedef uint32_t glow__v8u __attribute__((vector_size(32)));
typedef int32_t glow__v8i __attribute__((vector_size(32)));
typedef float glow__v16f __attribute__((vector_size(64)));
typedef uint32_t glow__v16u __attribute__((vector_size(64)));
typedef int32_t glow__v16i __attribute__((vector_size(64)));

#define GLOW__MAX_BANDS 8u

/* K_l^|m| (times sqrt 2 for m != 0), index l*l + l + m, symmetric in m. */
static const float glow__sh_k[64] = {
    2.820947918e-01f, 4.886025119e-01f, 4.886025119e-01f, 4.886025119e-01f,
    1.820914051e-01f, 3.641828102e-01f, 6.307831305e-01f, 3.641828102e-01f,
    1.820914051e-01f, 3.933623933e-02f, 9.635371475e-02f, 3.046971996e-01f,
    7.463526652e-01f, 3.046971996e-01f, 9.635371475e-02f, 3.933623933e-02f,
    5.960340338e-03f, 1.685838828e-02f, 6.307831305e-02f, 2.676186174e-01f,
    8.462843753e-01f, 2.676186174e-01f, 6.307831305e-02f, 1.685838828e-02f,
    5.960340338e-03f, 6.945841871e-04f, 2.196468058e-03f, 9.318824751e-03f,
    4.565273129e-02f, 2.415715473e-01f, 9.356025796e-01f, 2.415715473e-01f,
    4.565273129e-02f, 9.318824751e-03f, 2.196468058e-03f, 6.945841871e-04f,
    6.572237664e-05f, 2.276689911e-04f, 1.067862224e-03f, 5.848922283e-03f,
    3.509353370e-02f, 2.219509952e-01f, 1.017107236e+00f, 2.219509952e-01f,
    3.509353370e-02f, 5.848922283e-03f, 1.067862224e-03f, 2.276689911e-04f,
    6.572237664e-05f, 5.233009454e-06f, 1.958012848e-05f, 9.983945719e-05f,
    5.990367431e-04f, 3.973560225e-03f, 2.809731381e-02f, 2.064722459e-01f,
    1.092548431e+00f, 2.064722459e-01f, 2.809731381e-02f, 3.973560225e-03f,
    5.990367431e-04f, 9.983945719e-05f, 1.958012848e-05f, 5.233009454e-06f,};

/* out[k] = y_k(x, y, z) for k < bands² (bands <= 8), lane-wise; (x, y, z) unit vectors. With `bands` a
 * compile-time constant (always_inline) the loops unroll completely. */
#define GLOW__SH_EVAL_DEFINE(NAME, VT) \
static inline __attribute__((always_inline)) void NAME(uint32_t bands, const VT *px, const VT *py, const VT *pz, VT *out) { \
    const VT x = *px, y = *py, z = *pz; \
    const VT zero = *px * 0.0f; \
    VT cm = zero + 1.0f, sm = zero; /* (x + iy)^m = sin^m θ (cos mφ + i sin mφ) */ \
    float qmm_s = 1.0f;                    /* (2m-1)!! */ \
    for (uint32_t m = 0; m < bands; ++m) { \
        if (m > 0) { \
            VT c = cm * x - sm * y; \
            sm = sm * x + cm * y; \
            cm = c; \
            qmm_s *= (float)(2u * m - 1u); \
        } \
        /* Q_l^m = P_l^m / sin^m θ: Q_m^m = (2m-1)!!, Q_{m+1}^m = (2m+1) z Q_m^m, \
         * Q_l^m = ((2l-1) z Q_{l-1}^m - (l+m-1) Q_{l-2}^m) / (l-m) */ \
        VT q_prev = zero, q = zero + qmm_s; \
        for (uint32_t l = m; l < bands; ++l) { \
            if (l == m + 1) { \
                q_prev = q; \
                q = z * ((float)(2u * m + 1u) * qmm_s); \
            } else if (l > m + 1) { \
                VT qn = (z * q * (float)(2u * l - 1u) - q_prev * (float)(l + m - 1u)) * (1.0f / (float)(l - m)); \
                q_prev = q; \
                q = qn; \
            } \
            const float k = glow__sh_k[l * l + l + m]; \
            if (m == 0) { \
                out[l * l + l] = q * k; \
            } else { \
                VT qk = q * k; \
                out[l * l + l + m] = qk * cm; \
                out[l * l + l - m] = qk * sm; \
            } \
        } \
    } \
}

GLOW__SH_EVAL_DEFINE(glow__sh_eval_v8, glow__v8f)

/* ---- Scaled basis for the cache-lighting kernel -------------------------------------------------
 * y_lm = glow__sh_scaled_factor(l, m) * ỹ_lm, with ỹ chosen so that the fewest multiplies remain
 * per direction (the constants move to one multiply per cache coefficient after the sum):
 *   ỹ_l^{±m} = Q̃_l^m(z) {c_m, s_m}, c_m + i s_m = (x + iy)^m   (c_0 = 1, c_1 = x, s_1 = y)
 *   Q̃_m^m = 1, Q̃_{m+1}^m = z, Q̃_l^m = z Q̃_{l-1}^m - β(l, m) Q̃_{l-2}^m
 * where Q_l^m = P_l^m / sin^m θ = σ(l, m) Q̃_l^m. For l = 3 that is 6 multiplies for 9 values
 * (against 2 per value with the normalised recurrence above). */

/* ρ(j, m) = σ(j, m) / σ(j-1, m) for j >= m + 1 */
static inline double glow__sh_rho(uint32_t j, uint32_t m) {
    return j == m + 1u ? (double)(2u * m + 1u) : (double)(2u * j - 1u) / (double)(j - m);
}
/* β(l, m) for l >= m + 2 */
static inline double glow__sh_beta(uint32_t l, uint32_t m) {
    return (double)(l + m - 1u) / ((double)(2u * l - 1u) * glow__sh_rho(l - 1u, m));
}
/* σ(l, m), l >= m: σ(m, m) = (2m-1)!! */
static inline double glow__sh_sigma(uint32_t l, uint32_t m) {
    double s = 1.0;
    for (uint32_t j = 1; j <= m; ++j) s *= (double)(2u * j - 1u);
    for (uint32_t j = m + 1u; j <= l; ++j) s *= glow__sh_rho(j, m);
    return s;
}
/* y_lm / ỹ_lm for coefficient index k = l*l + l + m */
static inline double glow__sh_scaled_factor(uint32_t k) {
    uint32_t l = 0;
    while ((l + 1u) * (l + 1u) <= k) ++l;
    const int32_t m = (int32_t)k - (int32_t)(l * l + l);
    const uint32_t am = (uint32_t)(m < 0 ? -m : m);
    return (double)glow__sh_k[k] * glow__sh_sigma(l, am);
}

/* out[k] = ỹ_k for k < bands², (x, y, z) unit vectors; UNROLL as above. */
#define GLOW__SH_EVAL_SCALED_DEFINE_U(NAME, VT, UNROLL) \
static inline __attribute__((always_inline)) void NAME(uint32_t bands, const VT *px, const VT *py, const VT *pz, VT *out) { \
    if (bands > GLOW__MAX_BANDS) __builtin_unreachable(); \
    const VT x = *px, y = *py, z = *pz; \
    VT cm = x, sm = y; \
    UNROLL \
    for (uint32_t m = 0; m < bands; ++m) { \
        if (m >= 2u) { \
            const VT c = cm * x - sm * y; \
            sm = sm * x + cm * y; \
            cm = c; \
        } \
        VT q_prev = z, q = z; /* Q̃_{l-2}, Q̃_{l-1}; Q̃_m = 1 is never multiplied */ \
        UNROLL \
        for (uint32_t l = m; l < bands; ++l) { \
            const uint32_t c0 = l * l + l; \
            if (l == m) { \
                if (m == 0) out[0] = (VT){0} + 1.0f; \
                else { out[c0 + m] = cm; out[c0 - m] = sm; } \
                continue; \
            } \
            if (l == m + 1u) q = z; \
            else if (l == m + 2u) { q_prev = q; q = z * q - (float)glow__sh_beta(l, m); } \
            else { const VT qn = z * q - q_prev * (float)glow__sh_beta(l, m); q_prev = q; q = qn; } \
            if (m == 0) out[c0] = q; \
            else { out[c0 + m] = q * cm; out[c0 - m] = q * sm; } \
        } \
    } \
}
#define GLOW__SH_EVAL_SCALED_DEFINE(NAME, VT) \
    GLOW__SH_EVAL_SCALED_DEFINE_U(NAME, VT, ) \
    GLOW__SH_EVAL_SCALED_DEFINE_U(NAME##_unrolled, VT, _Pragma("GCC unroll 16"))

GLOW__SH_EVAL_SCALED_DEFINE(glow__sh_eval_scaled_v8, glow__v8f)

#endif /* GLOW_SH_KERNEL_H */
