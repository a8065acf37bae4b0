/* sky_rays.h — the rays a surfel's sky is traced over, shared by the linker (precompute/src/sky.c, the
 * SKYT transfer) and the CPU host (integration/hosts/cpu/host.c: the constant sky's S, and the transfer
 * of a bake without SKYT), so that both estimate the same integral ray for ray (tests/integration/
 * test_sky.c: baked and traced transfers equal). Part of the bake format's seam (docs/architecture.md):
 * SKYT's header records how many of these rays each surfel used. Pure inline maths, no state. */
#ifndef GLOW_SKY_RAYS_H
#define GLOW_SKY_RAYS_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Orthonormal basis (x, y) around unit z (Duff et al. 2017, "Building an orthonormal basis, revisited"). */
static inline void glow__seam_onb(const float z[3], float x[3], float y[3]) {
    float sign = copysignf(1.0f, z[2]);
    float a = -1.0f / (sign + z[2]);
    float b = z[0] * z[1] * a;
    x[0] = 1.0f + sign * z[0] * z[0] * a;
    x[1] = sign * b;
    x[2] = -sign * z[0];
    y[0] = b;
    y[1] = sign + z[1] * z[1] * a;
    y[2] = -z[1];
}

/* n deterministic cosine-distributed directions around +z into dirs[3 n]: a Hammersley set (i + 1/2)/n
 * and the base-2 radical inverse, lifted from the unit disk onto the hemisphere (Malley's method),
 * turned by an irrational-looking angle so that no direction lies exactly in the tangent frame's axis
 * planes (in axis-aligned scenes such a ray would run inside a neighbouring face's plane). */
static inline uint32_t glow__seam_bitrev32(uint32_t b) {
    b = (b << 16) | (b >> 16);
    b = ((b & 0x55555555u) << 1) | ((b & 0xAAAAAAAAu) >> 1);
    b = ((b & 0x33333333u) << 2) | ((b & 0xCCCCCCCCu) >> 2);
    b = ((b & 0x0F0F0F0Fu) << 4) | ((b & 0xF0F0F0F0u) >> 4);
    b = ((b & 0x00FF00FFu) << 8) | ((b & 0xFF00FF00u) >> 8);
    return b;
}
static inline void glow__seam_sky_dirs(uint32_t n, float *dirs) {
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t b = glow__seam_bitrev32(i);
        double u1 = ((double)i + 0.5) / n, u2 = (double)b * (1.0 / 4294967296.0);
        double r = sqrt(u1), phi = 2.0 * 3.14159265358979323846 * (u2 + 0.1234567);
        dirs[3 * (size_t)i + 0] = (float)(r * cos(phi));
        dirs[3 * (size_t)i + 1] = (float)(r * sin(phi));
        dirs[3 * (size_t)i + 2] = (float)sqrt(fmax(0.0, 1.0 - u1));
    }
}

/* Closest point to p on triangle abc (Ericson, Real-Time Collision Detection, 5.1.5): where a sky ray
 * starts, off the surfel's own surface (both sides pick the nearest triangle facing along n). */
static inline float glow__seam_dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline void glow__seam_closest_on_tri(const float p[3], const float a[3], const float b[3], const float c[3],
                                             float out[3]) {
    float ab[3], ac[3], ap[3];
    for (int i = 0; i < 3; ++i) {
        ab[i] = b[i] - a[i];
        ac[i] = c[i] - a[i];
        ap[i] = p[i] - a[i];
    }
    float d1 = glow__seam_dot(ab, ap), d2 = glow__seam_dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f) {
        memcpy(out, a, 12);
        return;
    }
    float bp[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]};
    float d3 = glow__seam_dot(ab, bp), d4 = glow__seam_dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3) {
        memcpy(out, b, 12);
        return;
    }
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
        float v = d1 / (d1 - d3);
        for (int i = 0; i < 3; ++i) out[i] = a[i] + v * ab[i];
        return;
    }
    float cp[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    float d5 = glow__seam_dot(ab, cp), d6 = glow__seam_dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6) {
        memcpy(out, c, 12);
        return;
    }
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
        float w = d2 / (d2 - d6);
        for (int i = 0; i < 3; ++i) out[i] = a[i] + w * ac[i];
        return;
    }
    float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
        float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int i = 0; i < 3; ++i) out[i] = b[i] + w * (c[i] - b[i]);
        return;
    }
    float denom = 1.0f / (va + vb + vc), v = vb * denom, w = vc * denom;
    for (int i = 0; i < 3; ++i) out[i] = a[i] + ab[i] * v + ac[i] * w;
}

/* The rays of glow__seam_sky_dirs(n) in azimuth order (a turn starting at 0.1234567 of one), into
 * order[n]: ray i's azimuth grows with its bit-reversed index, so sorting by that needs no trigonometry.
 * Rays next to each other by index point to opposite sides; traced 16 at a time in this order, a
 * packet looks into a sixteenth of the turn and shares most of its BVH walk (the linker's SKYT and
 * the CPU host). The order only groups rays into packets: results are summed in index order. keys is
 * the caller's scratch of n entries. */
static inline int glow__seam_cmp_u64(const void *a, const void *b) {
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}
static inline void glow__seam_sky_order(uint32_t n, uint64_t *keys, uint32_t *order) {
    for (uint32_t i = 0; i < n; ++i) keys[i] = (uint64_t)glow__seam_bitrev32(i) << 32 | i;
    qsort(keys, n, sizeof *keys, glow__seam_cmp_u64);
    for (uint32_t i = 0; i < n; ++i) order[i] = (uint32_t)keys[i];
}

#endif /* GLOW_SKY_RAYS_H */
