/* host_math.h — the small vector helpers of the CPU hosts (host.c, shadow_map.c) and the GPU lights
 * (../gl_lights/gl_lights.c). One copy on purpose: the GPU shadow maps must place their texel grids exactly
 * where the software maps do (the same orthonormal basis), or the two hosts stop agreeing. Not installed. */
#ifndef GLOW_HOST_MATH_H
#define GLOW_HOST_MATH_H

#include <math.h>
#include <stdbool.h>

#include "sky_rays.h"

static inline float glow__dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* out = in / |in| (in double); false for zero-length or non-finite input. */
static inline bool glow__normalize3(const float in[3], float out[3]) {
    double len = sqrt((double)in[0] * in[0] + (double)in[1] * in[1] + (double)in[2] * in[2]);
    if (!(len > 1e-12) || !isfinite(len)) return false;
    for (int i = 0; i < 3; ++i) out[i] = (float)(in[i] / len);
    return true;
}

/* Orthonormal basis (x, y) around unit z: the seam's (runtime/src/bake/sky_rays.h), which the linker's
 * sky transfer uses too, so that a surfel's sky rays are the same on both sides. */
static inline void glow__onb(const float z[3], float x[3], float y[3]) { glow__seam_onb(z, x, y); }

#endif /* GLOW_HOST_MATH_H */
