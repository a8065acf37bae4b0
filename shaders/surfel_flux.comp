/*
 * surfel_flux.comp — PIC step 2b: surfel flux, the leaves of the hierarchy (runtime/src/system.c
 * task_flux, the same arithmetic). One invocation per surfel:
 *   E_ind = Σ_q w_q · cache_sh[feedback][q] (luma² Y, chroma² Co and Cg; YCoCg -> RGB)
 *   B = rho · E_direct + rho_ind · bounce · max(0, E_ind) + emit;   flux = B · area (YCoCg)
 * written as vec4(flux Y, Co, Cg, 1/(π area)) so the gather reads radiance with one load.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_SURFEL_GROUP
#error "GLOW_SURFEL_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_SURFEL_GROUP) in;

layout(std430, binding = GLOW_BINDING_SURFEL_GEOM) readonly buffer GlowSurfelGeom { glow_gl_surfel_geom glow_geom[]; };
layout(std430, binding = GLOW_BINDING_SURFEL_MAT) readonly buffer GlowSurfelMat { glow_gl_surfel_mat glow_mat[]; };
layout(std430, binding = GLOW_BINDING_DIRECT) readonly buffer GlowDirect { vec4 glow_direct[]; };
layout(std430, binding = GLOW_BINDING_FEEDBACK_W) readonly buffer GlowFeedbackW { float glow_fbw[]; };
layout(std430, binding = GLOW_BINDING_CACHE_SH) readonly buffer GlowCacheSh { float glow_cache_sh[]; };
layout(std430, binding = GLOW_BINDING_NODES) readonly buffer GlowNodes { uvec4 glow_nodes[]; };
layout(std430, binding = GLOW_BINDING_FLUX) writeonly buffer GlowFlux { vec4 glow_flux[]; };
#ifdef GLOW_LINK_GRADIENT
/* link gradients: each leaf's luma-flux moment Yflux p (runtime/src/system.c task_flux's mom) */
layout(std430, binding = GLOW_BINDING_MOMENTS) writeonly buffer GlowMoments { vec4 glow_mom[]; };
#endif

void main() {
    uint i = glow_global_index(GLOW_SURFEL_GROUP);
    if (i >= glow_p.surfel_count) return;
    glow_gl_surfel_mat m = glow_mat[i];
    vec3 ind = vec3(0.0);
    float bounce = glow_p.bounce_intensity;
    if (bounce > 0.0) {
        uint sh = m.feedback * glow_p.coeff_count, w = i * uint(GLOW_L2);
        float y = 0.0, co = 0.0, cg = 0.0;
        for (int q = 0; q < GLOW_L2; ++q) y += glow_fbw[w + q] * glow_cache_sh[sh + q];
        for (int q = 0; q < GLOW_C2; ++q) {
            co += glow_fbw[w + q] * glow_cache_sh[sh + GLOW_L2 + q];
            cg += glow_fbw[w + q] * glow_cache_sh[sh + GLOW_L2 + GLOW_C2 + q];
        }
        ind = vec3(y + co - cg, y + cg, y - co - cg);
    }
    vec3 e_ind = max(ind, vec3(0.0)) * bounce;
    vec3 B = m.rho.rgb * glow_direct[i].rgb + m.rho_ind.rgb * e_ind + m.emit.rgb;
    float area = glow_geom[i].position_area.w; /* the surfel's own (bake format 1.3: may differ per surfel) */
    vec3 f = vec3((0.25 * B.r + 0.5 * B.g + 0.25 * B.b) * area, (0.5 * B.r - 0.5 * B.b) * area,
                  (-0.25 * B.r + 0.5 * B.g - 0.25 * B.b) * area);
    glow_flux[i] = vec4(f, uintBitsToFloat(glow_nodes[i].z));
#ifdef GLOW_LINK_GRADIENT
    glow_mom[i] = vec4(f.x * glow_geom[i].position_area.xyz, 0.0);
#endif
}
