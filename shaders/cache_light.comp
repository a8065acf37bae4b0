/*
 * cache_light.comp — PIC step 4: every cache sums its links into SH of incident radiance with runtime
 * projection (PIC 4.6), as runtime/src/cache_lighting.c does:
 *     L_lm += R[node] · k_l(1 - omc) · y_lm(dir),   R = flux · 1/(π area) (YCoCg)
 * for l < luma (Y) and l < chroma (Co, Cg); k_0 = 2π omc, k_l = 2π/(2l+1) (P_(l-1)(x) - P_(l+1)(x)),
 * evaluated as 2π/(l(l+1)) (1 - x²) P_l'(x) with 1 - x² = omc (2 - omc), as the CPU kernel does: no
 * cancellation for narrow cones (x near 1).
 * One workgroup per cache; its GLOW_CACHE_GROUP invocations take links j = lid, lid + group, ...;
 * the partial sums are reduced through shared memory GLOW_REDUCE_CHUNK coefficients at a time, each
 * coefficient by one invocation in a fixed order (deterministic). Link block layout: glow.h
 * glow_solver_tables.link_blocks (32 uints per block of 16 links).
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_CACHE_GROUP
#error "GLOW_CACHE_GROUP must be defined (glow_shared.h)"
#endif
#define GLOW_SH_MAX_BANDS GLOW_LUMA_BANDS
#include "glow_sh.glsl"
layout(local_size_x = GLOW_CACHE_GROUP) in;

layout(std430, binding = GLOW_BINDING_LINKS) readonly buffer GlowLinks { uint glow_links[]; };
layout(std430, binding = GLOW_BINDING_FLUX) readonly buffer GlowFlux { vec4 glow_flux[]; };
layout(std430, binding = GLOW_BINDING_CACHE_SH) buffer GlowCacheSh { float glow_cache_sh[]; }; /* read: the old DC */
#ifdef GLOW_LINK_SUBSETS
/* link subsets (bake_format.h, LSUB): a link reads R[node] times the weighted luma ratio of the node's
 * four slots, as the CPU kernel does (it rounds the ratios to IEEE halves) */
layout(std430, binding = GLOW_BINDING_LINK_SUBSETS) readonly buffer GlowSubsets { uint glow_subsets[]; };
layout(std430, binding = GLOW_BINDING_NODES) readonly buffer GlowNodes { uvec4 glow_nodes[]; };
float glow_luma(uint n) { vec4 f = glow_flux[n]; return f.x * f.w; }
float glow_subset_scale(uint v, uint q, float yn) {
    if (q == 0u || !(yn > 0.0)) return 1.0;
    uint slot[4];
    if (v < glow_p.surfel_count) {
        slot[0] = slot[1] = slot[2] = slot[3] = v;
    } else {
        uvec4 nv = glow_nodes[v];
        for (int k = 0; k < 2; ++k) {
            uint ch = k == 0 ? nv.x : nv.y;
            if (ch < glow_p.surfel_count) {
                slot[2 * k] = slot[2 * k + 1] = ch;
            } else {
                uvec4 nc = glow_nodes[ch];
                slot[2 * k] = nc.x;
                slot[2 * k + 1] = nc.y;
            }
        }
    }
    float num = 0.0, den = 0.0;
    for (int i = 0; i < 4; ++i) {
        float w = float((q >> (4 * i)) & 15u);
        num += w * glow_luma(slot[i]);
        den += w;
    }
    return num / (den * yn);
}
#endif
#ifdef GLOW_LINK_GRADIENT
/* link gradients (bake_format.h, LSUB with GLOW_LINK_KIND_GRADIENT): a link with code q (bit 15 set,
 * k_x + 15, k_y + 15, k_z + 15 in bits 0-4, 5-9, 10-14) reads R[node] times
 * max(0, 1 + ((k_x u_x + k_y u_y) + k_z u_z) / 15), u the node's (gradient_u.comp, rounded to halves
 * as the CPU's), as runtime/src/cache_kernel.inc gradient_scale_r; code 0 (no bit 15) reads R[node] */
layout(std430, binding = GLOW_BINDING_LINK_SUBSETS) readonly buffer GlowSubsets { uint glow_subsets[]; };
layout(std430, binding = GLOW_BINDING_GRADIENT_U) readonly buffer GlowGradU { vec4 glow_grad_u[]; };
float glow_gradient_scale(uint v, uint q) {
    if ((q & 0x8000u) == 0u) return 1.0;
    vec3 k = vec3(float(q & 31u), float((q >> 5) & 31u), float((q >> 10) & 31u)) - 15.0;
    vec3 u = glow_grad_u[v].xyz;
    float sc = 1.0 + ((k.x * u.x + k.y * u.y) + k.z * u.z) * (1.0 / 15.0);
    return sc > 0.0 ? sc : 0.0;
}
#endif

shared float glow_red[GLOW_REDUCE_CHUNK][GLOW_CACHE_GROUP + 1];

/* a budget's caches (glow_budget_choose): workgroup i gathers cache glow_cache_list[i]; 0 = every cache */
uniform uint glow_cache_list_count;
layout(std430, binding = GLOW_BINDING_CACHE_LIST) readonly buffer GlowCacheList { uint glow_cache_list[]; };
/* converged_epsilon: workgroup i also writes (|new - old|, |new|) of its cache's luma DC to glow_cache_delta_out[i]
 * (runtime/src/system.c task_caches_sel's measure of a gather's change) */
uniform uint glow_cache_delta;
layout(std430, binding = GLOW_BINDING_CACHE_DELTA) writeonly buffer GlowCacheDelta { vec2 glow_cache_delta_out[]; };

void main() {
    uint c = glow_group_index(), slot = c;
    if (glow_cache_list_count != 0u) {
        if (c >= glow_cache_list_count) return; /* whole workgroup: uniform */
        c = glow_cache_list[c];
    }
    if (c >= glow_p.cache_count) return; /* whole workgroup: uniform */
    uint lid = gl_LocalInvocationID.x;
    float acc[GLOW_NCO];
    for (int i = 0; i < GLOW_NCO; ++i) acc[i] = 0.0;
    uint nlinks = glow_p.blocks_per_cache * 16u;
    for (uint j = lid; j < nlinks; j += uint(GLOW_CACHE_GROUP)) {
        uint base = (c * glow_p.blocks_per_cache + j / 16u) * 32u, lane = j & 15u;
        uint nd = glow_links[base + lane];
        uint w16 = glow_links[base + 16u + lane / 2u], lo16 = glow_links[base + 24u + lane / 2u];
        uint shift = (lane & 1u) * 16u;
        float omc = unpackHalf2x16((w16 >> shift) & 0xFFFFu).x;
        if (!(omc > 0.0)) continue; /* unused lanes: k_l(1) = 0, they add nothing */
        uint lo = (lo16 >> shift) & 0xFFFFu;
        vec3 d = glow_oct_decode12(((nd >> 24) << 4) | (lo & 15u), lo >> 4);
        vec4 f = glow_flux[nd & 0x00FFFFFFu];
        vec3 R = f.xyz * f.w;
#ifdef GLOW_LINK_SUBSETS
        uint li = (c * glow_p.blocks_per_cache + j / 16u) * 16u + lane;
        R *= glow_subset_scale(nd & 0x00FFFFFFu, (glow_subsets[li >> 1] >> ((li & 1u) * 16u)) & 0xFFFFu, R.x);
#endif
#ifdef GLOW_LINK_GRADIENT
        uint lg = (c * glow_p.blocks_per_cache + j / 16u) * 16u + lane;
        R *= glow_gradient_scale(nd & 0x00FFFFFFu, (glow_subsets[lg >> 1] >> ((lg & 1u) * 16u)) & 0xFFFFu);
#endif
        float y[GLOW_L2];
        glow_sh_eval(GLOW_LUMA_BANDS, d, y);
        float x = 1.0 - omc, g = omc * (2.0 - omc);
        float dp = 0.0, p = 1.0; /* P'_(l-1)(x), P'_l(x) */
        for (int l = 0; l < GLOW_LUMA_BANDS; ++l) {
            float k = omc * float(2.0 * GLOW_PI);
            if (l > 0) {
                k = float(2.0 * GLOW_PI) / float(l * (l + 1)) * g * p;
                float pn = (float(2 * l + 1) * x * p - float(l + 1) * dp) / float(l);
                dp = p;
                p = pn;
            }
            vec3 w = R * k;
            for (int i = l * l; i < (l + 1) * (l + 1); ++i) acc[i] += w.x * y[i];
            if (l < GLOW_CHROMA_BANDS)
                for (int i = l * l; i < (l + 1) * (l + 1); ++i) {
                    acc[GLOW_L2 + i] += w.y * y[i];
                    acc[GLOW_L2 + GLOW_C2 + i] += w.z * y[i];
                }
        }
    }
    /* reduce: chunk by chunk, invocation q sums coefficient base + q over all invocations */
    for (int base = 0; base < GLOW_NCO; base += GLOW_REDUCE_CHUNK) {
        for (int q = 0; q < GLOW_REDUCE_CHUNK; ++q)
            if (base + q < GLOW_NCO) glow_red[q][lid] = acc[base + q];
        barrier();
        if (lid < uint(GLOW_REDUCE_CHUNK) && base + int(lid) < GLOW_NCO) {
            float s = 0.0;
            for (int t = 0; t < GLOW_CACHE_GROUP; ++t) s += glow_red[lid][t];
            uint at = c * glow_p.coeff_count + uint(base) + lid;
            if (glow_cache_delta != 0u && base == 0 && lid == 0u)
                glow_cache_delta_out[slot] = vec2(abs(s - glow_cache_sh[at]), abs(s));
            glow_cache_sh[at] = s;
        }
        barrier();
    }
}
