/*
 * pull_tail.comp — the narrow top of the hierarchy in one dispatch: a single workgroup walks levels
 * [glow_tail.x, glow_tail.y) (each at most a few workgroups wide), with a barrier between levels, so the
 * pull costs one dispatch per wide level plus one, not one per level (Sponza moderate: ~40 levels, most
 * of them narrow). The same sums as pull.comp: flux = flux(child0) + flux(child1), and with link
 * gradients the luma-flux moments.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_PULL_GROUP
#error "GLOW_PULL_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_PULL_GROUP) in;

layout(std430, binding = GLOW_BINDING_NODES) readonly buffer GlowNodes { uvec4 glow_nodes[]; };
layout(std430, binding = GLOW_BINDING_FLUX) coherent buffer GlowFlux { vec4 glow_flux[]; };
layout(std430, binding = GLOW_BINDING_LEVELS) readonly buffer GlowLevels { uint glow_levels[]; };
#ifdef GLOW_LINK_GRADIENT
layout(std430, binding = GLOW_BINDING_MOMENTS_TAIL) coherent buffer GlowMoments { vec4 glow_mom[]; };
#endif
uniform uvec2 glow_tail; /* first level, end level */

void main() {
    for (uint lv = glow_tail.x; lv < glow_tail.y; ++lv) {
        uint first = glow_levels[lv], end = glow_levels[lv + 1u];
        for (uint n = first + gl_LocalInvocationID.x; n < end; n += uint(GLOW_PULL_GROUP)) {
            uvec4 nd = glow_nodes[n];
            glow_flux[n] = vec4(glow_flux[nd.x].xyz + glow_flux[nd.y].xyz, uintBitsToFloat(nd.z));
#ifdef GLOW_LINK_GRADIENT
            glow_mom[n] = glow_mom[nd.x] + glow_mom[nd.y];
#endif
        }
        memoryBarrierBuffer();
        barrier();
    }
}
