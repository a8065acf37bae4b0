/* format_util.c — small codecs the bake format shares between writer and reader:
 * CRC-32 (zlib polynomial, slicing-by-8 tables), octahedral unit vectors (snorm16 x2, and the
 * links' unsigned 12-bit x2) and IEEE binary16 <-> binary32 conversion. libc/libm only: no zlib,
 * no F16C. */
#include <math.h>
#include <stdbool.h>
#include <stdatomic.h>
#include <string.h>

#include "bake/bake_format.h"

/* ------------------------------------------------------------------------------ CRC-32 */
/* Reflected CRC-32, polynomial 0xEDB88320, init/xorout 0xFFFFFFFF: the zlib/PNG CRC, so
 * glow__crc32(0, p, n) == crc32(0, p, n) and calls chain the same way. The eight tables are
 * built once, on first use, by whichever thread gets there first (the others wait on the state
 * flag; building takes microseconds). */
static uint32_t crc_table[8][256];
static atomic_int crc_state; /* 0 = not built, 1 = being built, 2 = ready */

static void crc_build(void) {
    for (uint32_t i = 0; i < 256; i++) {
        uint32_t c = i;
        for (int k = 0; k < 8; k++) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        crc_table[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; i++)
        for (int s = 1; s < 8; s++)
            crc_table[s][i] = (crc_table[s - 1][i] >> 8) ^ crc_table[0][crc_table[s - 1][i] & 0xFFu];
}

static void crc_init(void) {
    if (atomic_load_explicit(&crc_state, memory_order_acquire) == 2) return;
    int expected = 0;
    if (atomic_compare_exchange_strong_explicit(&crc_state, &expected, 1, memory_order_acq_rel,
                                                memory_order_acquire)) {
        crc_build();
        atomic_store_explicit(&crc_state, 2, memory_order_release);
        return;
    }
    while (atomic_load_explicit(&crc_state, memory_order_acquire) != 2) {
        /* another thread is building the tables */
    }
}

static inline uint32_t load_le32(const unsigned char *p) {
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

uint32_t glow__crc32(uint32_t crc, const void *data, size_t size) {
    if (!data || size == 0) return crc;
    crc_init();
    const unsigned char *p = (const unsigned char *)data;
    crc = ~crc;
    while (size >= 8) {
        uint32_t a = load_le32(p) ^ crc;
        uint32_t b = load_le32(p + 4);
        crc = crc_table[7][a & 0xFFu] ^ crc_table[6][(a >> 8) & 0xFFu] ^ crc_table[5][(a >> 16) & 0xFFu] ^
              crc_table[4][a >> 24] ^ crc_table[3][b & 0xFFu] ^ crc_table[2][(b >> 8) & 0xFFu] ^
              crc_table[1][(b >> 16) & 0xFFu] ^ crc_table[0][b >> 24];
        p += 8;
        size -= 8;
    }
    while (size--) crc = crc_table[0][(crc ^ *p++) & 0xFFu] ^ (crc >> 8);
    return ~crc;
}

/* ------------------------------------------------------------------------------ octahedral */
/* Octahedral map (Meyer et al. 2010 / Cigolle et al. 2014): project onto |x|+|y|+|z| = 1, fold
 * the lower hemisphere over the diagonals, quantise x, y to snorm16 (value / 32767, -32768 reads
 * as -1). The encoder tries the four quantisation neighbours and keeps the one that decodes
 * closest to the input ("precise" encoding): worst-case error ~0.002 degrees. Zero-length or
 * non-finite input encodes as +z (0, 0). */
static float sign_nonneg(float v) { return v >= 0.0f ? 1.0f : -1.0f; }

/* Octahedron coordinates (px, py) in [-1, 1]² of n, and n normalised in double. False for a
 * zero-length or non-finite n. */
static bool oct_project(const float n[3], double *px, double *py, double nd[3]) {
    float x = n[0], y = n[1], z = n[2];
    float l1 = fabsf(x) + fabsf(y) + fabsf(z);
    if (!(l1 > 0.0f) || !isfinite(l1)) return false;
    float fx = x / l1, fy = y / l1;
    if (z < 0.0f) { /* fold the lower hemisphere over the diagonals */
        float tx = (1.0f - fabsf(fy)) * sign_nonneg(fx);
        float ty = (1.0f - fabsf(fx)) * sign_nonneg(fy);
        fx = tx;
        fy = ty;
    }
    double len = sqrt((double)x * x + (double)y * y + (double)z * z);
    nd[0] = x / len;
    nd[1] = y / len;
    nd[2] = z / len;
    *px = fx;
    *py = fy;
    return true;
}

/* The inverse: octahedron coordinates to a unit vector. */
static void oct_unfold_d(double x, double y, double out[3]) {
    double z = 1.0 - fabs(x) - fabs(y);
    if (z < 0.0) {
        double t = x;
        x = (1.0 - fabs(y)) * (t >= 0.0 ? 1.0 : -1.0);
        y = (1.0 - fabs(t)) * (y >= 0.0 ? 1.0 : -1.0);
    }
    double len = sqrt(x * x + y * y + z * z);
    out[0] = x / len;
    out[1] = y / len;
    out[2] = z / len;
}
static void oct_unfold_f(float x, float y, float out[3]) {
    float z = 1.0f - fabsf(x) - fabsf(y);
    if (z < 0.0f) {
        float t = x;
        x = (1.0f - fabsf(y)) * sign_nonneg(t);
        y = (1.0f - fabsf(t)) * sign_nonneg(y);
    }
    float inv = 1.0f / sqrtf(x * x + y * y + z * z); /* >= 1/sqrt(3): never 0 */
    out[0] = x * inv;
    out[1] = y * inv;
    out[2] = z * inv;
}

/* Quantisation grid coordinate = q * step + offset, q in [lo, hi]: of the four grid points around
 * (px, py), the one that decodes closest to nd ("precise" encoding). */
static void oct_nearest(double px, double py, const double nd[3], double step, double offset, int32_t lo, int32_t hi,
                        int32_t *out_u, int32_t *out_v) {
    double fx = floor((px - offset) / step), fy = floor((py - offset) / step);
    double best = -2.0;
    int32_t bu = lo, bv = lo;
    for (int dy = 0; dy < 2; dy++) {
        for (int dx = 0; dx < 2; dx++) {
            double cu = fmin(fmax(fx + dx, (double)lo), (double)hi);
            double cv = fmin(fmax(fy + dy, (double)lo), (double)hi);
            double d[3];
            oct_unfold_d(cu * step + offset, cv * step + offset, d);
            double dot = d[0] * nd[0] + d[1] * nd[1] + d[2] * nd[2];
            if (dot > best) {
                best = dot;
                bu = (int32_t)cu;
                bv = (int32_t)cv;
            }
        }
    }
    *out_u = bu;
    *out_v = bv;
}

/* snorm16: coordinate = q / 32767, q in [-32767, 32767] (-32768 reads as -1). */
void glow__oct_encode2(const float n[3], int16_t *out_u, int16_t *out_v) {
    double px, py, nd[3];
    int32_t u = 0, v = 0;
    if (oct_project(n, &px, &py, nd)) oct_nearest(px, py, nd, 1.0 / 32767.0, 0.0, -32767, 32767, &u, &v);
    *out_u = (int16_t)u;
    *out_v = (int16_t)v;
}

void glow__oct_decode2(int16_t u, int16_t v, float out_n[3]) {
    float x = u < -32767 ? -1.0f : (float)u / 32767.0f;
    float y = v < -32767 ? -1.0f : (float)v / 32767.0f;
    oct_unfold_f(x, y, out_n);
}

uint32_t glow__oct_encode(const float n[3]) {
    int16_t u, v;
    glow__oct_encode2(n, &u, &v);
    return (uint32_t)(uint16_t)u | ((uint32_t)(uint16_t)v << 16);
}

void glow__oct_decode(uint32_t packed, float out_n[3]) {
    uint16_t lo = (uint16_t)(packed & 0xFFFFu), hi = (uint16_t)(packed >> 16);
    /* two's complement reinterpretation without implementation-defined conversions */
    int16_t u = (int16_t)(lo < 0x8000u ? (int32_t)lo : (int32_t)lo - 65536);
    int16_t v = (int16_t)(hi < 0x8000u ? (int32_t)hi : (int32_t)hi - 65536);
    glow__oct_decode2(u, v, out_n);
}

/* 12-bit unsigned variant for links: q in [0, 4095] <-> s = q * (2/4095) - 1, so both ends (-1 and
 * +1) are exact and 0 is not (the axes +-z are off by half a step, ~0.01 degrees). Worst case
 * ~0.04 degrees. Zero-length or non-finite input encodes as (nearly) +z. */
#define OCT12_MAX 4095u

void glow__oct_encode12(const float n[3], uint32_t *out_u, uint32_t *out_v) {
    static const float up[3] = {0.0f, 0.0f, 1.0f};
    double px, py, nd[3];
    if (!oct_project(n, &px, &py, nd)) oct_project(up, &px, &py, nd);
    int32_t u, v;
    oct_nearest(px, py, nd, 2.0 / 4095.0, -1.0, 0, (int32_t)OCT12_MAX, &u, &v);
    *out_u = (uint32_t)u;
    *out_v = (uint32_t)v;
}

void glow__oct_decode12(uint32_t u, uint32_t v, float out_n[3]) {
    /* bits above the 12 are ignored, so any packed value decodes to a unit vector */
    oct_unfold_f((float)(u & OCT12_MAX) * (2.0f / 4095.0f) - 1.0f, (float)(v & OCT12_MAX) * (2.0f / 4095.0f) - 1.0f,
                 out_n);
}

/* ------------------------------------------------------------------------------ half */
uint16_t glow__half_from_float(float f) {
    uint32_t x;
    memcpy(&x, &f, sizeof x);
    uint16_t sign = (uint16_t)((x >> 16) & 0x8000u);
    uint32_t ax = x & 0x7FFFFFFFu;
    if (ax >= 0x7F800000u) {                    /* Inf or NaN */
        if (ax == 0x7F800000u) return (uint16_t)(sign | 0x7C00u);
        return (uint16_t)(sign | 0x7E00u | ((ax >> 13) & 0x3FFu)); /* quiet NaN, top payload bits */
    }
    if (ax >= 0x477FF000u) return (uint16_t)(sign | 0x7C00u); /* >= 65520 rounds to Inf */
    if (ax < 0x38800000u) {                                     /* below 2^-14: half subnormal or 0 */
        if (ax < 0x33000000u) return sign;                      /* below 2^-25: rounds to 0 */
        uint32_t e = ax >> 23;                                  /* 102 .. 112 */
        uint32_t m = (ax & 0x7FFFFFu) | 0x800000u;
        uint32_t shift = 126u - e;                              /* 14 .. 24 */
        uint32_t q = m >> shift;
        uint32_t rem = m & ((1u << shift) - 1u);
        uint32_t half = 1u << (shift - 1u);
        if (rem > half || (rem == half && (q & 1u))) q++;       /* may carry into the smallest normal */
        return (uint16_t)(sign | q);
    }
    uint32_t h = (ax - 0x38000000u) >> 13;                      /* rebias 127 -> 15 */
    uint32_t rem = ax & 0x1FFFu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u))) h++;     /* carry may reach Inf only above 65520 */
    return (uint16_t)(sign | h);
}

float glow__half_to_float(uint16_t h) {
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16;
    uint32_t e = (h >> 10) & 0x1Fu;
    uint32_t m = h & 0x3FFu;
    uint32_t x;
    if (e == 0) {
        if (m == 0) {
            x = sign;
        } else { /* subnormal: m * 2^-24, exact in binary32 */
            float v = (float)m * 5.9604644775390625e-8f;
            return sign ? -v : v;
        }
    } else if (e == 31) {
        x = sign | 0x7F800000u | (m << 13); /* Inf, or NaN with its payload */
    } else {
        x = sign | ((e + 112u) << 23) | (m << 13);
    }
    float f;
    memcpy(&f, &x, sizeof f);
    return f;
}
