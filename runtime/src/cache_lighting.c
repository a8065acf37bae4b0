/* cache_lighting.c — PIC step 4, the hot loop: every cache sums its links into SH of incident
 * radiance with runtime projection (PIC 4.6):
 *     L_lm += R[node] · k_l(1 - omc) · y_lm(dir)           for l < luma (Y), l < chroma (Co, Cg)
 * where R is the node's radiance in YCoCg (flux / (π area), converted once per node, never per link).
 *
 * Layout (DESIGN §5): the bake's links come in SoA blocks of 16 (bake_format.h), so the kernel works
 * on 8 or 16 lanes at a time *across links*, with no per-link branch: decode node, 12-bit octahedral
 * direction and half-float cone, gather the three node radiances, evaluate the scaled cone factors
 * k~_l and the scaled basis y~_lm (sh_kernel.h) on vectors, and accumulate luma² + 2·chroma²
 * coefficients per lane; each cache reduces its lanes once, in a fixed order, so the result does not
 * depend on which worker ran it, and multiplies each sum by its constant (glow__cl_coeff_scale).
 *
 * Three builds of the same source (cache_kernel.inc): AVX-512F, AVX2+FMA+F16C (hardware gathers and
 * half conversion) and a portable one; chosen once at run time with __builtin_cpu_supports. The band
 * counts are compile-time constants in the common instantiations so the band loops unroll (by
 * pragma: GCC -O2 does not). This file is compiled with -ffp-contract=fast (CMake) so a*b+c becomes
 * FMA where the target has it. Also here: the output-plane writer (glow__cl_write_planes). */
#include <math.h>
#include <string.h>

#include "cache_lighting.h"

/* Four translation units in the runtime library (GLOW_CL_SPLIT, runtime/CMakeLists.txt): this file
 * compiled as part 0 (the dispatcher, output planes, expansion) and included by cache_lighting_avx2.c
 * (part 1), cache_lighting_avx512.c (part 2) and cache_lighting_generic.c (part 3, the portable kernel),
 * so the build compiles the three kernels in parallel (one file took 51 s at -O2 on the 2-core machine,
 * on every build's critical path). Without GLOW_CL_SPLIT this file is the whole kernel in one unit, as
 * tools/kernel_ab.sh and the fuzz build include it. */
#ifdef GLOW_CL_SPLIT
#define GLOW__CL_PART_MAIN (GLOW_CL_PART == 0)
#define GLOW__CL_PART_AVX2 (GLOW_CL_PART == 1)
#define GLOW__CL_PART_AVX512 (GLOW_CL_PART == 2)
#define GLOW__CL_PART_GENERIC (GLOW_CL_PART == 3)
#define GLOW__CL_KLINK /* external: part 0's dispatcher calls them */
#define light_range_avx2 glow__cl_light_range_avx2
#define light_range_avx512 glow__cl_light_range_avx512
#define light_range_generic glow__cl_light_range_generic
#else
#define GLOW__CL_PART_MAIN 1
#define GLOW__CL_PART_GENERIC 1
#define GLOW__CL_PART_AVX2 1
#define GLOW__CL_PART_AVX512 1
#define GLOW__CL_KLINK static
#endif

/* The helpers below pass 32-byte vectors by value; they are static and always inlined, so no ABI
 * boundary exists and GCC's note about the AVX calling convention does not apply. */
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpsabi"
/* the unroll pragmas are hints; in the run-time band-count instantiation they cannot apply */
#pragma clang diagnostic ignored "-Wpass-failed"
#elif defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

#define GATHER3_PLAIN(a, node, y, co, cg)                                                                 \
    do {                                                                                                    \
        const VU idx = (node) * ((a)->rad_stride ? (a)->rad_stride : 1u);                                   \
        (y) = GATHER((a)->rad_y, (idx));                                                                    \
        (co) = GATHER((a)->rad_co, (idx));                                                                  \
        (cg) = GATHER((a)->rad_cg, (idx));                                                                  \
    } while (0)

/* GATHER3 and the bits of each lane's fourth record float (grad_uz's u_x u_y) */
#define GATHER4_PLAIN(a, node, y, co, cg, w)                                                              \
    do {                                                                                                    \
        GATHER3_PLAIN(a, node, y, co, cg);                                                                  \
        (w) = GATHER_U((const uint32_t *)(const void *)((a)->rad_y + 3),                                    \
                       (node) * ((a)->rad_stride ? (a)->rad_stride : 1u));                                  \
    } while (0)

/* The kernel sums R k̃_l ỹ_lm (sh_kernel.h's scaled basis and the scaled cone factors of
 * cache_kernel.inc); this is the constant per output coefficient that makes it R k_l y_lm:
 * y_lm / ỹ_lm times t_l = k_l / k̃_l (t_0 = 2π, t_l = 2π σ(l, 1) / (l (l + 1))). Luma² then Co
 * chroma², Cg chroma², as in cache_sh. */
#if GLOW__CL_PART_MAIN
#define GLOW__TWO_PI 6.283185307179586476925
void glow__cl_coeff_scale(uint32_t L, uint32_t C, float *scale) {
    for (uint32_t i = 0; i < GLOW__CL_SCALE_FLOATS; ++i) scale[i] = 0.0f;
    double t[GLOW__MAX_BANDS];
    for (uint32_t l = 0; l < L; ++l)
        t[l] = l == 0 ? GLOW__TWO_PI : GLOW__TWO_PI * glow__sh_sigma(l, 1) / ((double)l * (double)(l + 1u));
    for (uint32_t l = 0; l < L; ++l)
        for (uint32_t k = l * l; k < (l + 1) * (l + 1); ++k) {
            const float v = (float)(glow__sh_scaled_factor(k) * t[l]);
            scale[k] = v;
            if (l < C) scale[L * L + k] = scale[L * L + C * C + k] = v;
        }
}
#endif

/* ------------------------------------------------------------------------------ portable */
static inline glow__v8u load_u32_generic(const uint32_t *p) {
    glow__v8u v;
    memcpy(&v, p, sizeof v);
    return v;
}
static inline glow__v8u load_u16_generic(const uint16_t *p) {
    glow__v8u v;
    for (int i = 0; i < 8; ++i) v[i] = p[i];
    return v;
}
/* IEEE half -> float for finite non-negative-or-negative values including subnormals: move
 * exponent+mantissa into float position and rebias by multiplying with 2^112. */
static inline glow__v8f half8_generic(const uint16_t *p) {
    glow__v8u h = load_u16_generic(p);
    glow__v8u bits = ((h & 0x7FFFu) << 13) | ((h & 0x8000u) << 16);
    return (glow__v8f)bits * 5.192296858534828e+33f; /* 2^112 */
}
static inline glow__v8f gather_generic(const float *base, glow__v8u idx) {
    glow__v8f v;
    for (int i = 0; i < 8; ++i) v[i] = base[idx[i]];
    return v;
}
/* Lane sums in a fixed pairwise order (halves added as vectors): the same bytes whichever worker
 * runs the cache, and far fewer instructions than a scalar loop. */
static inline __attribute__((always_inline)) float reduce8(glow__v8f v) {
    typedef float v4f __attribute__((vector_size(16)));
    v4f a = __builtin_shufflevector(v, v, 0, 1, 2, 3) + __builtin_shufflevector(v, v, 4, 5, 6, 7);
    return (a[0] + a[2]) + (a[1] + a[3]);
}
static inline __attribute__((always_inline, unused)) float reduce16(glow__v16f v) {
    glow__v8f a = __builtin_shufflevector(v, v, 0, 1, 2, 3, 4, 5, 6, 7) +
                  __builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15);
    return reduce8(a);
}

static inline glow__v8u gather_u_generic(const uint32_t *base, glow__v8u idx) {
    glow__v8u v;
    for (int i = 0; i < 8; ++i) v[i] = base[idx[i]];
    return v;
}
static inline glow__v8u gather_uz_generic(const uint16_t *base, glow__v8u idx) {
    glow__v8u v;
    for (int i = 0; i < 8; ++i) v[i] = base[idx[i]];
    return v;
}
static inline glow__v8f sqrt8_generic(glow__v8f x) {
    for (int i = 0; i < 8; ++i) x[i] = sqrtf(x[i]);
    return x;
}

#if GLOW__CL_PART_GENERIC
#define VF glow__v8f
#define VU glow__v8u
#define VI glow__v8i
#define LANES 8
#define SH_EVAL glow__sh_eval_scaled_v8
#define SH_EVAL_U glow__sh_eval_scaled_v8_unrolled
#define REDUCE_STORE(acc, n, scale, out) \
    for (uint32_t i_ = 0; i_ < (n); ++i_) (out)[i_] = reduce8((acc)[i_]) * (scale)[i_]
#define KFN(name) name##_generic
#define KATTR
#define LOAD_U32(p) load_u32_generic(p)
#define LOAD_U16(p) load_u16_generic(p)
#define HALF8(p) half8_generic(p)
#define GATHER(base, idx) gather_generic((base), (idx))
#define GATHER_U(base, idx) gather_u_generic((base), (idx))
#define GATHER_PAIR(base, node, lo, hi) \
    do {                                \
        (lo) = GATHER_U((base), (node) << 1); \
        (hi) = GATHER_U((base), ((node) << 1) + 1u); \
    } while (0)
#define GATHER3(a, idx, y, co, cg) GATHER3_PLAIN(a, idx, y, co, cg)
#define GATHER4(a, idx, y, co, cg, w) GATHER4_PLAIN(a, idx, y, co, cg, w)
#define GATHER_UZ(base, idx) gather_uz_generic((base), (idx))
#define RSQRT(x) (1.0f / sqrt8_generic(x))
#include "cache_kernel.inc"
#endif /* GLOW__CL_PART_GENERIC */
#undef KFN
#undef KATTR
#undef LOAD_U32
#undef LOAD_U16
#undef HALF8
#undef GATHER
#undef GATHER_U
#undef GATHER_PAIR
#undef GATHER3
#undef GATHER4
#undef GATHER_UZ
#undef RSQRT
#undef REDUCE_STORE
#undef VF
#undef VU
#undef VI
#undef LANES
#undef SH_EVAL
#undef SH_EVAL_U

/* ------------------------------------------------------------------------------ AVX2 */
/* GCC only: the ISA-specific builds rely on GCC's target pragmas and cpu-feature names (clang gets the
 * portable kernel; a clang port would use #pragma clang attribute) */
#if (defined(__x86_64__) || defined(__i386__)) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#define GLOW__HAVE_AVX2_KERNEL 1
#if GLOW__CL_PART_AVX2
#define VF glow__v8f
#define VU glow__v8u
#define VI glow__v8i
#define LANES 8
#define SH_EVAL glow__sh_eval_scaled_v8
#define SH_EVAL_U glow__sh_eval_scaled_v8_unrolled
#define REDUCE_STORE(acc, n, scale, out) \
    for (uint32_t i_ = 0; i_ < (n); ++i_) (out)[i_] = reduce8((acc)[i_]) * (scale)[i_]
#define KFN(name) name##_avx2
#define KATTR __attribute__((target("avx2,fma,f16c")))
#undef REDUCE_STORE
/* eight sums at a time by a horizontal-add tree (the same fixed order for every cache and worker)
 * and one masked store, instead of a shuffle chain and a scalar store per sum */
#define REDUCE_STORE(acc, n, scale, out) reduce_store8((acc), (n), (scale), (out))
#define LOAD_U32(p) ((glow__v8u)_mm256_loadu_si256((const __m256i *)(const void *)(p)))
#define LOAD_U16(p) ((glow__v8u)_mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(const void *)(p))))
#define HALF8(p) ((glow__v8f)_mm256_cvtph_ps(_mm_loadu_si128((const __m128i *)(const void *)(p))))
#define GATHER(base, idx) ((glow__v8f)_mm256_i32gather_ps((base), (__m256i)(idx), 4))
#define GATHER_U(base, idx) ((glow__v8u)_mm256_i32gather_epi32((const int *)(const void *)(base), (__m256i)(idx), 4))
/* Pairs of adjacent floats per lane (base[2n], base[2n + 1]; or Y Co and Cg pad of the interleaved
 * node radiance) as 4-lane qword gathers: on Zen 3 a qword gather of 4 costs about half a dword
 * gather of 8, so two of them and two shuffles replace two dword gathers, and four replace GATHER3's
 * three (docs/results.md "Link subsets"). Same values. */
#define GATHER_PAIR(base, node, lo, hi) gather_pair_avx2((const void *)(base), (node), &(lo), &(hi))
#define GATHER3(a, idx, y, co, cg) gather3_avx2((a), (idx), &(y), &(co), &(cg))
#define GATHER3_IDX(a, n, y, co, cg) gather3_idx_avx2((a), (n), &(y), &(co), &(cg))
#define GATHER4_IDX(a, n, y, co, cg, w) gather4_idx_avx2((a), (n), &(y), &(co), &(cg), &(w))
#define GATHER4(a, idx, y, co, cg, w) GATHER4_PLAIN(a, idx, y, co, cg, w)
/* 32 bits at 2-byte steps: lane l's uint16 base[node[l]] in the low half */
#define GATHER_UZ(base, node) ((glow__v8u)_mm256_i32gather_epi32((const int *)(const void *)(base), (__m256i)(node), 2))
#define GATHER_PAIR_IDX(base, n, lo, hi) gather_pair_idx_avx2((const void *)(base), (n), &(lo), &(hi))
/* rsqrt estimate (12 bits) + one Newton step: ~1e-7 relative, a fraction of the sqrt+div cost */
#define RSQRT(x) rsqrt_avx2(x)
/* the inline helpers of the .inc must also carry the target to be inlined into KATTR code */
#pragma GCC push_options
#pragma GCC target("avx2,fma,f16c")
/* idx in units of 8 bytes from base: lane l's two dwords at base + 8 idx[l] -> lo[l], hi[l] */
static inline __attribute__((always_inline)) void gather_pair_idx_avx2(const void *base, const uint32_t *n, glow__v8u *lo,
                                                                       glow__v8u *hi) {
    const double *b = (const double *)base;
#define GLOW__LD2(i, j) _mm_loadh_pd(_mm_load_sd(b + n[i]), b + n[j])
    const __m256 A = _mm256_castpd_ps(_mm256_insertf128_pd(_mm256_castpd128_pd256(GLOW__LD2(0, 1)), GLOW__LD2(4, 5), 1));
    const __m256 B = _mm256_castpd_ps(_mm256_insertf128_pd(_mm256_castpd128_pd256(GLOW__LD2(2, 3)), GLOW__LD2(6, 7), 1));
#undef GLOW__LD2
    *lo = (glow__v8u)_mm256_shuffle_ps(A, B, 0x88); /* lanes 0 2 of each pair: lo0 lo1 lo2 lo3 | lo4 .. lo7 */
    *hi = (glow__v8u)_mm256_shuffle_ps(A, B, 0xDD);
}
static inline __attribute__((always_inline)) void gather_pair_avx2(const void *base, glow__v8u idx, glow__v8u *lo,
                                                                   glow__v8u *hi) {
    uint32_t n[8];
    memcpy(n, &idx, sizeof n);
    gather_pair_idx_avx2(base, n, lo, hi);
}
/* the three radiances, and where w is not NULL the bits of the record's fourth float (GATHER4) */
static inline __attribute__((always_inline)) void gather4_idx_avx2(const glow__cl_args *a, const uint32_t *n, glow__v8f *y,
                                                                   glow__v8f *co, glow__v8f *cg, glow__v8u *w) {
    if (a->rad_stride == 4u && a->rad_co == a->rad_y + 1 && a->rad_cg == a->rad_y + 2) {
        const float *b = a->rad_y;
#define GLOW__LD2(i, j) _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(b + 4 * (size_t)n[i])), _mm_loadu_ps(b + 4 * (size_t)n[j]), 1)
        const __m256 v0 = GLOW__LD2(0, 4), v1 = GLOW__LD2(1, 5), v2 = GLOW__LD2(2, 6), v3 = GLOW__LD2(3, 7);
#undef GLOW__LD2
        const __m256 t0 = _mm256_unpacklo_ps(v0, v1), t1 = _mm256_unpackhi_ps(v0, v1);
        const __m256 t2 = _mm256_unpacklo_ps(v2, v3), t3 = _mm256_unpackhi_ps(v2, v3);
        *y = (glow__v8f)_mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(t0), _mm256_castps_pd(t2)));
        *co = (glow__v8f)_mm256_castpd_ps(_mm256_unpackhi_pd(_mm256_castps_pd(t0), _mm256_castps_pd(t2)));
        *cg = (glow__v8f)_mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(t1), _mm256_castps_pd(t3)));
        if (w) *w = (glow__v8u)_mm256_castpd_ps(_mm256_unpackhi_pd(_mm256_castps_pd(t1), _mm256_castps_pd(t3)));
    } else {
        glow__v8u node;
        memcpy(&node, n, sizeof node);
        if (w) GATHER4_PLAIN(a, node, *y, *co, *cg, *w);
        else GATHER3_PLAIN(a, node, *y, *co, *cg);
    }
}
static inline __attribute__((always_inline)) void gather3_idx_avx2(const glow__cl_args *a, const uint32_t *n, glow__v8f *y,
                                                                   glow__v8f *co, glow__v8f *cg) {
    gather4_idx_avx2(a, n, y, co, cg, NULL);
}
static inline __attribute__((always_inline)) void gather3_avx2(const glow__cl_args *a, glow__v8u node, glow__v8f *y,
                                                               glow__v8f *co, glow__v8f *cg) {
    uint32_t n[8];
    memcpy(n, &node, sizeof n);
    gather3_idx_avx2(a, n, y, co, cg);
}
static inline __attribute__((always_inline)) void reduce_store8(const glow__v8f *acc, uint32_t n, const float *scale,
                                                                float *out) {
#pragma GCC unroll 8
    for (uint32_t g = 0; g < n; g += 8u) {
        __m256 v[8];
#pragma GCC unroll 8
        for (uint32_t j = 0; j < 8u; ++j) v[j] = g + j < n ? (__m256)acc[g + j] : _mm256_setzero_ps();
        const __m256 s01 = _mm256_hadd_ps(v[0], v[1]), s23 = _mm256_hadd_ps(v[2], v[3]);
        const __m256 s45 = _mm256_hadd_ps(v[4], v[5]), s67 = _mm256_hadd_ps(v[6], v[7]);
        const __m256 q0 = _mm256_hadd_ps(s01, s23), q1 = _mm256_hadd_ps(s45, s67); /* per 128-bit half */
        const __m256 f = _mm256_add_ps(_mm256_permute2f128_ps(q0, q1, 0x20), _mm256_permute2f128_ps(q0, q1, 0x31));
        const uint32_t m = n - g < 8u ? n - g : 8u;
        const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        const __m256i mask = _mm256_cmpgt_epi32(_mm256_set1_epi32((int)m), lane);
        _mm256_maskstore_ps(out + g, mask, _mm256_mul_ps(f, _mm256_maskload_ps(scale + g, mask)));
    }
}
static inline glow__v8f rsqrt_avx2(glow__v8f x) {
    glow__v8f y = (glow__v8f)_mm256_rsqrt_ps((__m256)x);
    return y * (1.5f - 0.5f * x * y * y);
}
#define KSPLIT 1 /* the two-phase kernel (cache_kernel.inc): 16 registers cannot hold the accumulators */
#include "cache_kernel.inc"
#undef KSPLIT
#undef GATHER3_IDX
#undef GATHER4_IDX
#undef GATHER_PAIR_IDX
#pragma GCC pop_options
#undef KFN
#undef KATTR
#undef LOAD_U32
#undef LOAD_U16
#undef HALF8
#undef GATHER
#undef GATHER_U
#undef GATHER_PAIR
#undef GATHER3
#undef GATHER4
#undef GATHER_UZ
#undef RSQRT
#undef REDUCE_STORE
#undef VF
#undef VU
#undef VI
#undef LANES
#undef SH_EVAL
#undef SH_EVAL_U
#endif /* GLOW__CL_PART_AVX2 */

#if GLOW__CL_PART_AVX512
/* AVX-512: a whole 16-link block per step, and 32 vector registers, so the luma² + 2 chroma²
 * accumulators of l = 3 stay in registers instead of spilling (the AVX2 build's main cost). */
#pragma GCC push_options
#pragma GCC target("avx512f,fma,f16c")
GLOW__SH_EVAL_SCALED_DEFINE(glow__sh_eval_scaled_v16, glow__v16f)
static inline glow__v16f rsqrt_avx512(glow__v16f x) {
    glow__v16f y = (glow__v16f)_mm512_rsqrt14_ps((__m512)x);
    return y * (1.5f - 0.5f * x * y * y);
}
#define VF glow__v16f
#define VU glow__v16u
#define VI glow__v16i
#define LANES 16
#define SH_EVAL glow__sh_eval_scaled_v16
#define SH_EVAL_U glow__sh_eval_scaled_v16_unrolled
/* 16 accumulators at a time: three rounds of two shuffles and an add halve the vector count
 * (128-bit blocks, then within them), the fourth leaves the 16 sums in one vector: 45 operations
 * per 16 sums instead of 8 per sum. The inputs are taken in the order that puts the sums in
 * natural order (lane 4k + e is the sum of the vector fed as v[k + 4e]). */
static inline __attribute__((always_inline)) void reduce_store16(const glow__v16f *acc, uint32_t n, const float *scale,
                                                                float *out) {
#pragma GCC unroll 16
    for (uint32_t g = 0; g < n; g += 16u) {
        __m512 v[16];
#pragma GCC unroll 16
        for (uint32_t j = 0; j < 16u; ++j) {
            const uint32_t i = g + 4u * (j % 4u) + j / 4u;
            v[j] = i < n ? (__m512)acc[i] : _mm512_setzero_ps();
        }
        __m512 w[8], z[4], r[2];
#pragma GCC unroll 8
        for (uint32_t i = 0; i < 8u; ++i)
            w[i] = _mm512_add_ps(_mm512_shuffle_f32x4(v[2 * i], v[2 * i + 1], 0x44),
                                 _mm512_shuffle_f32x4(v[2 * i], v[2 * i + 1], 0xEE));
#pragma GCC unroll 4
        for (uint32_t i = 0; i < 4u; ++i)
            z[i] = _mm512_add_ps(_mm512_shuffle_f32x4(w[2 * i], w[2 * i + 1], 0x88),
                                 _mm512_shuffle_f32x4(w[2 * i], w[2 * i + 1], 0xDD));
#pragma GCC unroll 2
        for (uint32_t i = 0; i < 2u; ++i)
            r[i] = _mm512_add_ps(_mm512_unpacklo_ps(z[2 * i], z[2 * i + 1]), _mm512_unpackhi_ps(z[2 * i], z[2 * i + 1]));
        const __m512 f = _mm512_add_ps(_mm512_shuffle_ps(r[0], r[1], 0x44), _mm512_shuffle_ps(r[0], r[1], 0xEE));
        const uint32_t m = n - g < 16u ? n - g : 16u;
        _mm512_mask_storeu_ps(out + g, (__mmask16)((1u << m) - 1u), _mm512_mul_ps(f, _mm512_loadu_ps(scale + g)));
    }
}
#define REDUCE_STORE(acc, n, scale, out) reduce_store16((acc), (n), (scale), (out))
#define KFN(name) name##_avx512
#define KATTR __attribute__((target("avx512f,fma,f16c")))
#define LOAD_U32(p) ((glow__v16u)_mm512_loadu_si512((const void *)(p)))
#define LOAD_U16(p) ((glow__v16u)_mm512_cvtepu16_epi32(_mm256_loadu_si256((const __m256i *)(const void *)(p))))
#define HALF8(p) ((glow__v16f)_mm512_cvtph_ps(_mm256_loadu_si256((const __m256i *)(const void *)(p))))
#define GATHER(base, idx) ((glow__v16f)_mm512_i32gather_ps((__m512i)(idx), (base), 4))
#define GATHER_U(base, idx) ((glow__v16u)_mm512_i32gather_epi32((__m512i)(idx), (const void *)(base), 4))
#define GATHER_PAIR(base, node, lo, hi) \
    do {                                \
        (lo) = GATHER_U((base), (node) << 1); \
        (hi) = GATHER_U((base), ((node) << 1) + 1u); \
    } while (0)
/* With the system's interleaved node radiance (Y Co Cg pad per node, 16 bytes) a lane's three
 * values are two adjacent qwords: four 8-lane qword gathers (32 element loads) and three two-source
 * permutes replace three 16-lane dword gathers (48 element loads). Same floats, same results. */
static inline __attribute__((always_inline)) void gather4_avx512(const glow__cl_args *a, glow__v16u node, glow__v16f *y,
                                                                 glow__v16f *co, glow__v16f *cg, glow__v16u *w) {
    if (a->rad_stride == 4u && a->rad_co == a->rad_y + 1 && a->rad_cg == a->rad_y + 2) {
        const glow__v16u idx = node << 2;
        const __m256i lo = _mm512_castsi512_si256((__m512i)idx), hi = _mm512_extracti64x4_epi64((__m512i)idx, 1);
        const float *b = a->rad_y;
        const __m512i g0 = _mm512_i32gather_epi64(lo, (const void *)b, 4), g1 = _mm512_i32gather_epi64(hi, (const void *)b, 4);
        const __m512i g2 = _mm512_i32gather_epi64(lo, (const void *)(b + 2), 4);
        const __m512i g3 = _mm512_i32gather_epi64(hi, (const void *)(b + 2), 4);
        const __m512i even = _mm512_set_epi32(30, 28, 26, 24, 22, 20, 18, 16, 14, 12, 10, 8, 6, 4, 2, 0);
        const __m512i odd = _mm512_set_epi32(31, 29, 27, 25, 23, 21, 19, 17, 15, 13, 11, 9, 7, 5, 3, 1);
        *y = (glow__v16f)_mm512_permutex2var_ps(_mm512_castsi512_ps(g0), even, _mm512_castsi512_ps(g1));
        *co = (glow__v16f)_mm512_permutex2var_ps(_mm512_castsi512_ps(g0), odd, _mm512_castsi512_ps(g1));
        *cg = (glow__v16f)_mm512_permutex2var_ps(_mm512_castsi512_ps(g2), even, _mm512_castsi512_ps(g3));
        if (w) *w = (glow__v16u)_mm512_permutex2var_epi32(g2, odd, g3); /* the pad: grad_uz's u_x u_y */
    } else {
        const glow__v16u idx = node * (a->rad_stride ? a->rad_stride : 1u);
        *y = GATHER(a->rad_y, idx);
        *co = GATHER(a->rad_co, idx);
        *cg = GATHER(a->rad_cg, idx);
        if (w) *w = GATHER_U((const uint32_t *)(const void *)(a->rad_y + 3), idx);
    }
}
/* The interleaved records by 16-byte loads, one a lane, and a 4 x 4 transpose per 128-bit block
 * (r_i's block j holds node 4 j + i, so the transposed lanes come out in natural order): 16 loads,
 * 12 inserts and 8 unpacks instead of four qword gathers (32 element loads) and three permutes.
 * Same floats. The kernel alone on Sponza moderate (gradients, one thread, in-process A/B):
 * 0.871x (min 3.17 -> 2.70 ms) on a Zen 5 VM. */
static inline __attribute__((always_inline)) void gather4_idx_avx512(const glow__cl_args *a, const uint32_t *n, glow__v16f *y,
                                                                     glow__v16f *co, glow__v16f *cg, glow__v16u *w) {
    if (a->rad_stride == 4u && a->rad_co == a->rad_y + 1 && a->rad_cg == a->rad_y + 2) {
        const float *b = a->rad_y;
#define GLOW__R(i) _mm512_insertf32x4(_mm512_insertf32x4(_mm512_insertf32x4(_mm512_castps128_ps512(_mm_loadu_ps(b + 4 * (size_t)n[i])), \
                        _mm_loadu_ps(b + 4 * (size_t)n[4 + i]), 1), _mm_loadu_ps(b + 4 * (size_t)n[8 + i]), 2), _mm_loadu_ps(b + 4 * (size_t)n[12 + i]), 3)
        const __m512 r0 = GLOW__R(0), r1 = GLOW__R(1), r2 = GLOW__R(2), r3 = GLOW__R(3);
#undef GLOW__R
        const __m512d t0 = _mm512_castps_pd(_mm512_unpacklo_ps(r0, r1)), t1 = _mm512_castps_pd(_mm512_unpackhi_ps(r0, r1));
        const __m512d t2 = _mm512_castps_pd(_mm512_unpacklo_ps(r2, r3)), t3 = _mm512_castps_pd(_mm512_unpackhi_ps(r2, r3));
        *y = (glow__v16f)_mm512_castpd_ps(_mm512_unpacklo_pd(t0, t2));
        *co = (glow__v16f)_mm512_castpd_ps(_mm512_unpackhi_pd(t0, t2));
        *cg = (glow__v16f)_mm512_castpd_ps(_mm512_unpacklo_pd(t1, t3));
        if (w) *w = (glow__v16u)_mm512_castpd_ps(_mm512_unpackhi_pd(t1, t3));
    } else {
        glow__v16u node;
        memcpy(&node, n, sizeof node);
        gather4_avx512(a, node, y, co, cg, w);
    }
}
static inline __attribute__((always_inline)) void gather3_idx_avx512(const glow__cl_args *a, const uint32_t *n, glow__v16f *y,
                                                                     glow__v16f *co, glow__v16f *cg) {
    gather4_idx_avx512(a, n, y, co, cg, NULL);
}
static inline __attribute__((always_inline)) void gather_pair_idx_avx512(const void *base, const uint32_t *n, glow__v16u *lo,
                                                                         glow__v16u *hi) {
    glow__v16u node;
    memcpy(&node, n, sizeof node);
    GATHER_PAIR(base, node, *lo, *hi);
}
#define GATHER3_IDX(a, n, y, co, cg) gather3_idx_avx512((a), (n), &(y), &(co), &(cg))
#define GATHER4_IDX(a, n, y, co, cg, w) gather4_idx_avx512((a), (n), &(y), &(co), &(cg), &(w))
#define GATHER_PAIR_IDX(base, n, lo, hi) gather_pair_idx_avx512((const void *)(base), (n), &(lo), &(hi))
#define GATHER3(a, idx, y, co, cg) gather4_avx512((a), (idx), &(y), &(co), &(cg), NULL)
#define GATHER4(a, idx, y, co, cg, w) gather4_avx512((a), (idx), &(y), &(co), &(cg), &(w))
/* 32 bits at 2-byte steps: lane l's uint16 base[node[l]] in the low half */
#define GATHER_UZ(base, node) ((glow__v16u)_mm512_i32gather_epi32((__m512i)(node), (const void *)(base), 2))
/* rsqrt14 (exactly specified by the ISA, so bit-identical across vendors) + one Newton step */
#define RSQRT(x) rsqrt_avx512(x)
#include "cache_kernel.inc"
#pragma GCC pop_options
#endif /* GLOW__CL_PART_AVX512 */
#define GLOW__HAVE_AVX512_KERNEL 1
#endif

#if GLOW__CL_PART_MAIN
#ifdef GLOW_CL_SPLIT
#ifdef GLOW__HAVE_AVX2_KERNEL
void glow__cl_light_range_avx2(const glow__cl_args *a, uint32_t first, uint32_t count);
void glow__cl_light_range_avx512(const glow__cl_args *a, uint32_t first, uint32_t count);
#endif
void glow__cl_light_range_generic(const glow__cl_args *a, uint32_t first, uint32_t count);
#endif

/* ------------------------------------------------------------------------------ output planes */
/* All planes of a range of texels at once: each texel's cache row (nc floats, contiguous) is read
 * once and its values go to nc planes, each written in order. The former plane-at-a-time writer
 * gathered one float per texel and plane (nc passes over the map, a cache line touched per value). */
static const float glow__cl_zero_row[GLOW__CL_SCALE_FLOATS] = {0};
static void write_planes_generic(float *dst, size_t stride, const uint32_t *map, size_t first, size_t end, const float *sh,
                                 uint32_t nc) {
    for (size_t t = first; t < end; ++t) {
        const float *r = map[t] == GLOW__CL_EMPTY ? glow__cl_zero_row : sh + (size_t)map[t] * nc;
        for (uint32_t k = 0; k < nc; ++k) dst[(size_t)k * stride + t] = r[k];
    }
}
/* RGBA16F texels [first, end) (glow__cl_write_rgba16f): the page and the place in it kept as t goes */
static void write_rgba16f_generic(uint16_t *dst, size_t ps, const uint32_t *map, size_t first, size_t end, const float *sh,
                                  uint32_t nc) {
    const uint32_t Q = (nc + 3u) / 4u;
    size_t g = first / ps, r = first - g * ps;
    for (size_t t = first; t < end; ++t) {
        const float *row = map[t] == GLOW__CL_EMPTY ? glow__cl_zero_row : sh + (size_t)map[t] * nc;
        glow__rgba16f_put(dst + (g * Q * ps + r) * 4u, ps, nc, row);
        if (++r == ps) r = 0, ++g;
    }
}
#ifdef GLOW__HAVE_AVX2_KERNEL
/* Eight texels at a time: four coefficients of each of the eight rows (two rows to a 256-bit
 * register), a 4 x 8 transpose, four plane stores of eight texels. The last nc % 4 coefficients
 * are loaded masked (a row's end may be the array's). Same values as the generic writer. */
#define GLOW__TRANSPOSE_4x8(x0, x1, x2, x3, x4, x5, x6, x7, o0, o1, o2, o3)                                              \
    do {                                                                                                                  \
        const __m256 v0_ = _mm256_insertf128_ps(_mm256_castps128_ps256(x0), (x4), 1);                                     \
        const __m256 v1_ = _mm256_insertf128_ps(_mm256_castps128_ps256(x1), (x5), 1);                                     \
        const __m256 v2_ = _mm256_insertf128_ps(_mm256_castps128_ps256(x2), (x6), 1);                                     \
        const __m256 v3_ = _mm256_insertf128_ps(_mm256_castps128_ps256(x3), (x7), 1);                                     \
        const __m256d t0_ = _mm256_castps_pd(_mm256_unpacklo_ps(v0_, v1_)), t1_ = _mm256_castps_pd(_mm256_unpackhi_ps(v0_, v1_)); \
        const __m256d t2_ = _mm256_castps_pd(_mm256_unpacklo_ps(v2_, v3_)), t3_ = _mm256_castps_pd(_mm256_unpackhi_ps(v2_, v3_)); \
        (o0) = _mm256_castpd_ps(_mm256_unpacklo_pd(t0_, t2_));                                                          \
        (o1) = _mm256_castpd_ps(_mm256_unpackhi_pd(t0_, t2_));                                                          \
        (o2) = _mm256_castpd_ps(_mm256_unpacklo_pd(t1_, t3_));                                                          \
        (o3) = _mm256_castpd_ps(_mm256_unpackhi_pd(t1_, t3_));                                                          \
    } while (0)
__attribute__((target("avx2"))) static void write_planes_avx2(float *dst, size_t stride, const uint32_t *map, size_t first,
                                                              size_t end, const float *sh, uint32_t nc) {
    size_t t = first;
    const uint32_t nc4 = nc & ~3u, m = nc - nc4;
    const __m128i tail = _mm_cmpgt_epi32(_mm_set1_epi32((int)m), _mm_setr_epi32(0, 1, 2, 3));
    for (; t + 8u <= end; t += 8u) {
        const float *r0, *r1, *r2, *r3, *r4, *r5, *r6, *r7;
#define GLOW__ROW(i) (map[t + (i)] == GLOW__CL_EMPTY ? glow__cl_zero_row : sh + (size_t)map[t + (i)] * nc)
        r0 = GLOW__ROW(0), r1 = GLOW__ROW(1), r2 = GLOW__ROW(2), r3 = GLOW__ROW(3);
        r4 = GLOW__ROW(4), r5 = GLOW__ROW(5), r6 = GLOW__ROW(6), r7 = GLOW__ROW(7);
#undef GLOW__ROW
        float *d = dst + t;
        __m256 o0, o1, o2, o3;
        for (uint32_t k = 0; k < nc4; k += 4u, d += 4u * stride) {
            GLOW__TRANSPOSE_4x8(_mm_loadu_ps(r0 + k), _mm_loadu_ps(r1 + k), _mm_loadu_ps(r2 + k), _mm_loadu_ps(r3 + k),
                                _mm_loadu_ps(r4 + k), _mm_loadu_ps(r5 + k), _mm_loadu_ps(r6 + k), _mm_loadu_ps(r7 + k), o0,
                                o1, o2, o3);
            _mm256_storeu_ps(d, o0);
            _mm256_storeu_ps(d + stride, o1);
            _mm256_storeu_ps(d + 2 * stride, o2);
            _mm256_storeu_ps(d + 3 * stride, o3);
        }
        if (m) { /* masked: a row's end may be the array's */
            GLOW__TRANSPOSE_4x8(_mm_maskload_ps(r0 + nc4, tail), _mm_maskload_ps(r1 + nc4, tail), _mm_maskload_ps(r2 + nc4, tail),
                                _mm_maskload_ps(r3 + nc4, tail), _mm_maskload_ps(r4 + nc4, tail), _mm_maskload_ps(r5 + nc4, tail),
                                _mm_maskload_ps(r6 + nc4, tail), _mm_maskload_ps(r7 + nc4, tail), o0, o1, o2, o3);
            _mm256_storeu_ps(d, o0);
            if (m > 1u) _mm256_storeu_ps(d + stride, o1);
            if (m > 2u) _mm256_storeu_ps(d + 2 * stride, o2);
        }
    }
    write_planes_generic(dst, stride, map, t, end, sh, nc);
}
/* RGBA16F texels: each plane's four values of a row clamped as glow__f16 does (minps, maxps), then
 * F16C's conversion to nearest even, one 8-byte store; the last plane's values past nc loaded as 0 */
__attribute__((target("avx2,f16c"))) static void write_rgba16f_avx2(uint16_t *dst, size_t ps, const uint32_t *map,
                                                                    size_t first, size_t end, const float *sh, uint32_t nc) {
    const uint32_t Q = (nc + 3u) / 4u, nc4 = nc & ~3u;
    const __m128i tail = _mm_cmpgt_epi32(_mm_set1_epi32((int)(nc - nc4)), _mm_setr_epi32(0, 1, 2, 3));
    const __m128 hi = _mm_set1_ps(65504.0f), lo = _mm_set1_ps(-65504.0f);
    size_t g = first / ps, r = first - g * ps;
    for (size_t t = first; t < end; ++t) {
        const float *row = map[t] == GLOW__CL_EMPTY ? glow__cl_zero_row : sh + (size_t)map[t] * nc;
        uint16_t *d = dst + (g * Q * ps + r) * 4u;
        for (uint32_t k = 0; k < nc4; k += 4u, d += ps * 4u) {
            const __m128 v = _mm_max_ps(_mm_min_ps(_mm_loadu_ps(row + k), hi), lo);
            _mm_storel_epi64((__m128i *)d, _mm_cvtps_ph(v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
        }
        if (nc4 < nc) {
            const __m128 v = _mm_max_ps(_mm_min_ps(_mm_maskload_ps(row + nc4, tail), hi), lo);
            _mm_storel_epi64((__m128i *)d, _mm_cvtps_ph(v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
        }
        if (++r == ps) r = 0, ++g;
    }
}
#undef GLOW__TRANSPOSE_4x8
#endif

void glow__cl_write_planes(glow__cl_isa isa, float *dst, size_t stride, const uint32_t *map, size_t first, size_t end,
                           const float *sh, uint32_t nc) {
#ifdef GLOW__HAVE_AVX2_KERNEL
    if (isa == GLOW__CL_AVX2 || isa == GLOW__CL_AVX512) {
        write_planes_avx2(dst, stride, map, first, end, sh, nc);
        return;
    }
#endif
    (void)isa;
    write_planes_generic(dst, stride, map, first, end, sh, nc);
}

void glow__cl_write_rgba16f(glow__cl_isa isa, uint16_t *dst, size_t n, uint32_t pages, const uint32_t *map, size_t first,
                            size_t end, const float *sh, uint32_t nc) {
    const size_t ps = n / (pages ? pages : 1u);
#ifdef GLOW__HAVE_AVX2_KERNEL
    if (isa == GLOW__CL_AVX2 || isa == GLOW__CL_AVX512) {
        write_rgba16f_avx2(dst, ps, map, first, end, sh, nc);
        return;
    }
#endif
    (void)isa;
    write_rgba16f_generic(dst, ps, map, first, end, sh, nc);
}

static int has_avx2(void) {
#ifdef GLOW__HAVE_AVX2_KERNEL
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("f16c");
#else
    return 0;
#endif
}

static int has_avx512(void) {
#ifdef GLOW__HAVE_AVX512_KERNEL
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && has_avx2();
#else
    return 0;
#endif
}

glow__cl_isa glow__cl_best_isa(void) {
    if (has_avx512()) return GLOW__CL_AVX512;
    return has_avx2() ? GLOW__CL_AVX2 : GLOW__CL_GENERIC;
}

int glow__cl_isa_supported(glow__cl_isa isa) {
    return isa == GLOW__CL_GENERIC || (isa == GLOW__CL_AVX2 && has_avx2()) || (isa == GLOW__CL_AVX512 && has_avx512());
}

const char *glow__cl_isa_name(glow__cl_isa isa) {
    return isa == GLOW__CL_AVX512 ? "avx512f" : isa == GLOW__CL_AVX2 ? "avx2+fma+f16c" : "generic";
}

void glow__cl_light_caches(const glow__cl_args *a, uint32_t first, uint32_t count) {
#ifdef GLOW__HAVE_AVX512_KERNEL
    if (a->isa == GLOW__CL_AVX512) {
        light_range_avx512(a, first, count);
        return;
    }
#endif
#ifdef GLOW__HAVE_AVX2_KERNEL
    if (a->isa == GLOW__CL_AVX2) {
        light_range_avx2(a, first, count);
        return;
    }
#endif
    light_range_generic(a, first, count);
}

/* ------------------------------------------------------------------------------ expansion */
void glow__cl_expand(const glow_bake_link_block *blocks, uint32_t bpc, uint32_t L, unsigned char *xblocks,
                     uint32_t first, uint32_t count) {
    const size_t bs = glow__cl_xblock_size(L);
    for (size_t bi = (size_t)first * bpc; bi < (size_t)(first + count) * bpc; ++bi) {
        const glow_bake_link_block *b = blocks + bi;
        unsigned char *x = xblocks + bi * bs;
        uint32_t *nodes = (uint32_t *)(void *)x;
        uint16_t *w = (uint16_t *)(void *)(x + 64);
        for (uint32_t lane = 0; lane < GLOW_LINK_BLOCK; ++lane) {
            nodes[lane] = glow_bake_link_node(b, lane);
            const float omc = glow__half_to_float(b->one_minus_cos[lane]);
            uint32_t du, dv;
            float d[3], y[GLOW__MAX_BANDS * GLOW__MAX_BANDS];
            glow_bake_link_dir12(b, lane, &du, &dv);
            glow__oct_decode12(du, dv, d);
            glow_sh_eval(L, d, y);
            for (uint32_t l = 0; l < L; ++l) {
                /* the same cone factors as the compact kernel, in double: k_0 = 2π omc */
                const float k = (float)glow__cone_factor_omc(l, omc);
                for (uint32_t q = l * l; q < (l + 1) * (l + 1); ++q)
                    w[(size_t)q * GLOW_LINK_BLOCK + lane] = glow__half_from_float(omc > 0.0f ? k * y[q] : 0.0f);
            }
        }
    }
}
#endif /* GLOW__CL_PART_MAIN */
