/*
 * surfel_direct.comp — PIC step 2a: the host's direct light at every surfel, through the host hook
 * spliced in by the backend (glow_gl.h: glow_gl_desc.hook_glsl). One invocation per surfel:
 * E = glow_host_surfel_irradiance(position, normal, material), checked like the CPU hook's values:
 * NaN/Inf -> stored as 0 and counted (status.nonfinite, status.first_bad), negatives -> 0 and counted.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_SURFEL_GROUP
#error "GLOW_SURFEL_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_SURFEL_GROUP) in;

layout(std430, binding = GLOW_BINDING_SURFEL_GEOM) readonly buffer GlowSurfelGeom { glow_gl_surfel_geom glow_geom[]; };
layout(std430, binding = GLOW_BINDING_SURFEL_MAT) readonly buffer GlowSurfelMat { glow_gl_surfel_mat glow_mat[]; };
layout(std430, binding = GLOW_BINDING_DIRECT) writeonly buffer GlowDirect { vec4 glow_direct[]; };
layout(std430, binding = GLOW_BINDING_STATUS) buffer GlowStatus { glow_gl_status glow_status; };

/* The surfel being lit, in the bake's surfel order, for hooks that read per-surfel data (e.g. precomputed
 * sky visibility: glow_gl_lights). Hooks test GLOW_SURFEL_INDEX_AVAILABLE, which other stages lack. */
#define GLOW_SURFEL_INDEX_AVAILABLE 1
uint glow_surfel_index = 0u;

/* ---- host hook ---- */
GLOW_HOST_HOOK_SOURCE
/* ---- end of host hook ---- */
#ifndef GLOW_HOST_SURFEL_IRRADIANCE_DEFINED
#error "the host hook must #define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED and define vec3 glow_host_surfel_irradiance(vec3 position, vec3 normal, uint material)"
#endif

void main() {
    uint i = glow_global_index(GLOW_SURFEL_GROUP);
    if (i >= glow_p.surfel_count) return;
    glow_gl_surfel_geom g = glow_geom[i];
    glow_surfel_index = i;
    vec3 e = glow_host_surfel_irradiance(g.position_area.xyz, g.normal.xyz, glow_mat[i].material);
    if (any(isnan(e)) || any(isinf(e))) {
        atomicAdd(glow_status.nonfinite, 1u);
        atomicMin(glow_status.first_bad, i);
        e = vec3(0.0);
    }
    if (any(lessThan(e, vec3(0.0)))) {
        atomicAdd(glow_status.negative, uint(e.r < 0.0) + uint(e.g < 0.0) + uint(e.b < 0.0));
        e = max(e, vec3(0.0));
    }
    glow_direct[i] = vec4(e, 0.0);
}
