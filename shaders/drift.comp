/*
 * drift.comp — converged light (glow_update_desc.converged_epsilon): how much the light the caches read
 * changed since the last budgeted update. For nodes [0, glow_drift_count) (the tree's and the proxies)
 * each workgroup writes (Σ |y - y_prev|, Σ |y|) of its nodes' radiance luma y = flux.x · flux.w to
 * DRIFT_PARTIAL[group] and stores y as y_prev; the backend sums the partials in double, as
 * runtime/src/system.c schedule() sums its nodes. The per-workgroup order is fixed (a tree in shared
 * memory), so the result is deterministic.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_DRIFT_GROUP
#error "GLOW_DRIFT_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_DRIFT_GROUP) in;

layout(std430, binding = GLOW_BINDING_FLUX) readonly buffer GlowFlux { vec4 glow_flux[]; };
layout(std430, binding = GLOW_BINDING_RAD_PREV) buffer GlowRadPrev { float glow_rad_prev[]; };
layout(std430, binding = GLOW_BINDING_DRIFT_PARTIAL) writeonly buffer GlowDrift { vec2 glow_drift[]; };
uniform uint glow_drift_count;

shared vec2 glow_part[GLOW_DRIFT_GROUP];

void main() {
    uint i = glow_global_index(GLOW_DRIFT_GROUP), lid = gl_LocalInvocationID.x;
    vec2 v = vec2(0.0);
    if (i < glow_drift_count) {
        vec4 f = glow_flux[i];
        float y = f.x * f.w;
        v = vec2(abs(y - glow_rad_prev[i]), abs(y));
        glow_rad_prev[i] = y;
    }
    glow_part[lid] = v;
    barrier();
    for (uint w = uint(GLOW_DRIFT_GROUP) / 2u; w > 0u; w >>= 1u) {
        if (lid < w) glow_part[lid] += glow_part[lid + w];
        barrier();
    }
    if (lid == 0u) glow_drift[glow_group_index()] = glow_part[0];
}
