/*
 * pull.comp — PIC step 3: flux summed up the hierarchy, one dispatch per level (the bake stores nodes
 * sorted by level, so a level is a contiguous range whose children all lie in lower levels).
 * One invocation per node of the level: flux = flux(child0) + flux(child1); with link gradients
 * (GLOW_LINK_GRADIENT) the luma-flux moments likewise, as the CPU pull does.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_PULL_GROUP
#error "GLOW_PULL_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_PULL_GROUP) in;

layout(std430, binding = GLOW_BINDING_NODES) readonly buffer GlowNodes { uvec4 glow_nodes[]; };
layout(std430, binding = GLOW_BINDING_FLUX) buffer GlowFlux { vec4 glow_flux[]; };
#ifdef GLOW_LINK_GRADIENT
layout(std430, binding = GLOW_BINDING_MOMENTS) buffer GlowMoments { vec4 glow_mom[]; };
#endif
uniform uvec2 glow_level; /* first node, node count */

void main() {
    uint k = glow_global_index(GLOW_PULL_GROUP);
    if (k >= glow_level.y) return;
    uint n = glow_level.x + k;
    uvec4 nd = glow_nodes[n];
    glow_flux[n] = vec4(glow_flux[nd.x].xyz + glow_flux[nd.y].xyz, uintBitsToFloat(nd.z));
#ifdef GLOW_LINK_GRADIENT
    glow_mom[n] = glow_mom[nd.x] + glow_mom[nd.y];
#endif
}
