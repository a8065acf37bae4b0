/*
 * gradient_u.comp — link gradients (GLOW_LINK_GRADIENT), after the pull: for each node some coded link
 * reads, u = M (p_B - c) with p_B = the node's luma-flux moments over its luma flux (u = 0 where that
 * flux is not positive), c and M from the CPU system's load-time tables (glow_backend.h
 * glow_solver_tables.gradient_cm), as runtime/src/system.c sub_ratio_range does. The CPU stores u as
 * IEEE halves (signed_half: round to nearest on the bits, |u| below 2^-14 to 0, above 65504 to 65504);
 * the same rounding here, kept as floats, so both read the same values but for float rounding in p_B.
 * One invocation per such node.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_GRADIENT_GROUP
#error "GLOW_GRADIENT_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_GRADIENT_GROUP) in;

layout(std430, binding = GLOW_BINDING_FLUX) readonly buffer GlowFlux { vec4 glow_flux[]; };
layout(std430, binding = GLOW_BINDING_MOMENTS) readonly buffer GlowMoments { vec4 glow_mom[]; };
layout(std430, binding = GLOW_BINDING_GRADIENT_NODES) readonly buffer GlowGradNodes { uint glow_grad_nodes[]; };
layout(std430, binding = GLOW_BINDING_GRADIENT_CM) readonly buffer GlowGradCm { float glow_grad_cm[]; };
layout(std430, binding = GLOW_BINDING_GRADIENT_U) writeonly buffer GlowGradU { vec4 glow_grad_u[]; };
uniform uint glow_gradient_count;

/* x rounded as runtime/src/system.c signed_half, returned as the float the CPU kernel decodes */
float glow_signed_half(float x) {
    float a = abs(x);
    a = a < 65504.0 ? a : 65504.0;
    float r = uintBitsToFloat(((floatBitsToUint(a) + 0x1000u) >> 13) << 13);
    r = a >= 6.103515625e-05 ? r : 0.0;
    return x < 0.0 ? -r : r;
}

void main() {
    uint k = glow_global_index(GLOW_GRADIENT_GROUP);
    if (k >= glow_gradient_count) return;
    /* value q of node k at 48 (k / 4) + 4 q + k % 4 (blocks of four nodes, glow_backend.h) */
    uint n = glow_grad_nodes[k], b = 48u * (k / 4u) + k % 4u;
    float y = glow_flux[n].x;
    vec3 u = vec3(0.0);
    if (y > 0.0) {
        float inv = 1.0 / y;
        vec3 m = glow_mom[n].xyz;
        vec3 d = vec3(m.x * inv - glow_grad_cm[b], m.y * inv - glow_grad_cm[b + 4u], m.z * inv - glow_grad_cm[b + 8u]);
        for (uint i = 0u; i < 3u; ++i) {
            uint r = b + 12u + 12u * i;
            u[i] = glow_signed_half(glow_grad_cm[r] * d.x + glow_grad_cm[r + 4u] * d.y + glow_grad_cm[r + 8u] * d.z);
        }
    }
    glow_grad_u[n] = vec4(u, 0.0);
}
