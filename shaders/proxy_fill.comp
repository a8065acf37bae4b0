/*
 * proxy_fill.comp — light across systems (a system of a world, bake format 1.4 XREF): before the cache
 * gather, each proxy node N + p of this system takes the flux (and 1/(π area)) of the node of the
 * neighbouring system it stands for, as that system's last update left it; runtime/src/system.c
 * fill_proxies does the same on the CPU. One dispatch per attached neighbour: glow_proxy_range =
 * (first, count) of its entries in PROXY_MAP.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_PROXY_GROUP
#error "GLOW_PROXY_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_PROXY_GROUP) in;

layout(std430, binding = GLOW_BINDING_PROXY_SRC) readonly buffer GlowProxySrc { vec4 glow_src[]; };
layout(std430, binding = GLOW_BINDING_PROXY_MAP) readonly buffer GlowProxyMap { uvec2 glow_map[]; };
layout(std430, binding = GLOW_BINDING_FLUX) writeonly buffer GlowFlux { vec4 glow_flux[]; };
uniform uvec2 glow_proxy_range;

void main() {
    uint i = glow_global_index(GLOW_PROXY_GROUP);
    if (i >= glow_proxy_range.y) return;
    uvec2 m = glow_map[glow_proxy_range.x + i];
    glow_flux[m.y] = glow_src[m.x];
}
