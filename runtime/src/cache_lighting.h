/* cache_lighting.h — the cache-lighting kernel (cache_lighting.c), shared by system.c and tests. */
#ifndef GLOW_CACHE_LIGHTING_H
#define GLOW_CACHE_LIGHTING_H

#include <string.h>

#include "runtime_internal.h"
#include "sh_kernel.h"

typedef enum glow__cl_isa { GLOW__CL_GENERIC = 0, GLOW__CL_AVX2 = 1, GLOW__CL_AVX512 = 2 } glow__cl_isa;

typedef struct glow__cl_args {
    const glow_bake_link_block *blocks; /* [cache_count * blocks_per_cache] */
    uint32_t blocks_per_cache;
    const float *rad_y, *rad_co, *rad_cg; /* node radiance, YCoCg: node n's at rad_x[n * rad_stride] */
    uint32_t rad_stride;                  /* floats between nodes; 0 = 1 (planar). The system interleaves
                                             (stride 4: Y Co Cg pad), so the three gathers of a lane hit
                                             one cache line */
    uint32_t luma, chroma;                /* bands: 1 <= chroma <= luma <= 8 */
    uint32_t coeffs;                      /* floats per cache in cache_sh (>= luma² + 2 chroma²) */
    float *cache_sh;                      /* out: [cache][coeffs]: Y luma², Co chroma², Cg chroma² */
    glow__cl_isa isa;
    /* expanded links (GLOW_LINK_MODE_EXPANDED), when not NULL: per block of 16 links, uint32_t
     * node[16] then IEEE-half weight[luma²][16] (k_l(cos α) y_lm(dir), coefficient-major);
     * glow__cl_xblock_size(luma) bytes each, blocks_per_cache per cache */
    const unsigned char *xblocks;
    size_t xblock_size; /* bytes per expanded block; 0 = glow__cl_xblock_size(luma). The bake's full-SH
                           links (SHLK, same layout with the bake's sh_bands² rows) pass their own */
    const float *coeff_scale; /* compact links: glow__cl_coeff_scale(luma, chroma) computed once by
                                 the caller, or NULL (computed per call) */
    const uint16_t *subsets; /* LSUB weights, one per link in blocks' order (bake_format.h), or NULL:
                                each link reads its node's radiance scaled by the weighted luma
                                ratio of the node's four slots */
    const uint32_t *sub_ratio; /* with subsets: [node] four IEEE halves Y[slot_i] / Y[node] (slot 0 in
                                  the low half of the first uint32), read as uint32 pairs */
    bool link_gradient; /* with subsets: they are link gradient codes (GLOW_LINK_KIND_GRADIENT) and
                           sub_ratio holds per node u_x u_y u_z 0 as signed IEEE halves: each link reads
                           its node's radiance times max(0, 1 + (k / 15) . u) (cache_kernel.inc) */
    const uint16_t *grad_uz; /* with link_gradient and the interleaved radiance (rad_stride 4, rad_co =
                                rad_y + 1, rad_cg = rad_y + 2), when not NULL: u_x u_y of node n are the
                                two halves in the bits of rad_y[4 n + 3] (u_x low) and u_z is grad_uz[n],
                                so one gather of the record brings the radiance and u_x u_y, and u_z is a
                                32-bit read at grad_uz + n (one uint16 past the last node is read);
                                sub_ratio is not read. Same values as sub_ratio's u_x u_y u_z 0 */
    float xscale;       /* expanded links only: every cache coefficient times this (SHLK: the bake's
                           factor_scale, with rad_* the node flux); 0 = 1 */
} glow__cl_args;

/* The compact kernel sums R k~_l y~_lm (sh_kernel.h's scaled basis, cache_kernel.inc's scaled cone
 * factors); scale[i] is the constant that makes output coefficient i sum R k_l y_lm: luma², then Co
 * and Cg chroma², zero-padded to GLOW__CL_SCALE_FLOATS. */
#define GLOW__CL_SCALE_FLOATS (3u * 64u + 16u)
void glow__cl_coeff_scale(uint32_t luma, uint32_t chroma, float *scale);

static inline size_t glow__cl_xblock_size(uint32_t luma) { return (size_t)64u + (size_t)32u * luma * luma; }

/* Fills the expanded blocks of caches [first, first + count) from the bake's links. */
void glow__cl_expand(const glow_bake_link_block *blocks, uint32_t blocks_per_cache, uint32_t luma,
                     unsigned char *xblocks, uint32_t first, uint32_t count);

/* Lights caches [first, first + count). Reads only `a`'s inputs, writes only those caches' rows. */
void glow__cl_light_caches(const glow__cl_args *a, uint32_t first, uint32_t count);
/* Output planes (glow.h's planar layout), texels [first, end) of all nc planes:
 * dst[k * stride + t] = sh[map[t] * nc + k], 0 where map[t] is GLOW__CL_EMPTY; sh holds rows of nc
 * floats, nc <= GLOW__CL_SCALE_FLOATS - 16. */
#define GLOW__CL_EMPTY 0xFFFFFFFFu
void glow__cl_write_planes(glow__cl_isa isa, float *dst, size_t stride, const uint32_t *map, size_t first, size_t end,
                           const float *sh, uint32_t nc);
/* The same values as RGBA16F texels (GLOW_OUTPUT_PLANES_RGBA16F): a table of n cells or texels in
 * pages of ps = n / pages, Q = (nc + 3) / 4 planes; coefficient k of texel t = g ps + r (page g) goes to
 * halves ((g Q + k / 4) ps + r) 4 + k % 4, as glow__f16 of it (padding 0). The AVX2 and AVX-512 builds
 * convert with F16C, whose bits glow__f16 reproduces. */
void glow__cl_write_rgba16f(glow__cl_isa isa, uint16_t *dst, size_t n, uint32_t pages, const uint32_t *map, size_t first,
                            size_t end, const float *sh, uint32_t nc);

/* x as an IEEE half: clamped to [-65504, 65504] first (a NaN to 65504, as x86's minps then maxps),
 * then rounded to nearest even, subnormal halves included: the bits F16C's vcvtps2ph gives for the
 * clamped value with _MM_FROUND_TO_NEAREST_INT. (The bake's link codes use their own conversions.) */
static inline uint16_t glow__f16(float x) {
    x = x < 65504.0f ? x : 65504.0f;
    x = x > -65504.0f ? x : -65504.0f;
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    const uint32_t sign = (u >> 16) & 0x8000u;
    u &= 0x7FFFFFFFu;
    if (u < (113u << 23)) { /* below 2^-14: a subnormal half or zero; the float addition rounds to nearest even */
        const float magic = 0.5f; /* 2^-1: its last mantissa bit weighs 2^-24, the smallest half */
        float a;
        memcpy(&a, &u, sizeof a);
        a += magic;
        uint32_t b;
        memcpy(&b, &a, sizeof b);
        return (uint16_t)(sign | (b - 0x3F000000u));
    }
    const uint32_t odd = (u >> 13) & 1u; /* ties to even */
    u += 0xC8000FFFu + odd;                /* the exponent rebiased (-112 << 23) and half an ulp less one */
    return (uint16_t)(sign | (u >> 13));
}

/* One texel of glow__cl_write_rgba16f's layout from its cache row (nc floats): d is its place in the
 * first plane (glow__rgba16f_at), ps the texels of a plane's page. */
static inline void glow__rgba16f_put(uint16_t *d, size_t ps, uint32_t nc, const float *row) {
    for (uint32_t q = 0; 4u * q < nc; ++q, d += ps * 4u)
        for (uint32_t c = 0; c < 4u; ++c) d[c] = 4u * q + c < nc ? glow__f16(row[4u * q + c]) : (uint16_t)0u;
}
static inline size_t glow__rgba16f_at(size_t ps, uint32_t nc, size_t t) {
    const size_t g = t / ps;
    return (g * ((nc + 3u) / 4u) * ps + (t - g * ps)) * 4u;
}
glow__cl_isa glow__cl_best_isa(void);
int glow__cl_isa_supported(glow__cl_isa isa); /* this CPU runs it */
const char *glow__cl_isa_name(glow__cl_isa isa);

#endif /* GLOW_CACHE_LIGHTING_H */
