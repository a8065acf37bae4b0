/*
 * outputs.comp — the output textures: every non-empty grid cell and lightmap texel (the bake's map,
 * lightmap gutter and seam texels included: they name the cache they copy, so this is also the seam
 * copy) gets its cache's coefficients, 4 per RGBA32F texel: plane p holds coefficients 4p..4p+3 of
 * the cache layout (Y luma², Co chroma², Cg chroma², zero-padded). Empty texels stay 0 (cleared at create).
 * A lightmap of pages (format 1.7) has page g's planes at layers g * planes + p.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_OUTPUT_GROUP
#error "GLOW_OUTPUT_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_OUTPUT_GROUP) in;

layout(std430, binding = GLOW_BINDING_OUTPUT_PAIRS) readonly buffer GlowPairs { uvec2 glow_pairs[]; };
layout(std430, binding = GLOW_BINDING_CACHE_SH) readonly buffer GlowCacheSh { float glow_cache_sh[]; };
/* GLOW_OUTPUT_RGBA16F (GLOW_GL_FLAG_RGBA16F_OUTPUTS): the textures are RGBA16F, and a value beyond a
 * half's largest is clamped to it first (as the CPU's GLOW_OUTPUT_PLANES_RGBA16F planes), not stored as
 * an infinity */
#ifdef GLOW_OUTPUT_RGBA16F
#define GLOW_OUT_FORMAT rgba16f
#define GLOW_OUT_VALUE(x) clamp((x), -65504.0, 65504.0)
#else
#define GLOW_OUT_FORMAT rgba32f
#define GLOW_OUT_VALUE(x) (x)
#endif
layout(GLOW_OUT_FORMAT, binding = GLOW_IMAGE_GRID) uniform writeonly image3D glow_grid;
layout(GLOW_OUT_FORMAT, binding = GLOW_IMAGE_LIGHTMAP) uniform writeonly image2DArray glow_lightmap;
/* a refined grid's brick atlas: corner (x, y, z) of brick b, plane p, at
 * (S (b % ax) + x, S (b / ax) + y, z + S p), S = refine + 1, ax = fine_atlas_x */
layout(GLOW_OUT_FORMAT, binding = GLOW_IMAGE_GRID_FINE) uniform writeonly image3D glow_grid_fine;

float glow_coeff(uint base, uint k) { return k < glow_p.coeff_count ? GLOW_OUT_VALUE(glow_cache_sh[base + k]) : 0.0; }

void main() {
    uint i = glow_global_index(GLOW_OUTPUT_GROUP);
    if (i >= glow_p.grid_used + glow_p.lightmap_used + glow_p.fine_used) return;
    uvec2 pr = glow_pairs[i];
    uint base = pr.y * glow_p.coeff_count;
    bool grid = i < glow_p.grid_used;
    if (i >= glow_p.grid_used + glow_p.lightmap_used) { /* pr.x = brick * S³ + corner */
        uint S = glow_p.grid_refine + 1u, S3 = S * S * S, b = pr.x / S3, k = pr.x % S3;
        ivec3 at = ivec3(S * (b % glow_p.fine_atlas_x) + k % S, S * (b / glow_p.fine_atlas_x) + (k / S) % S, k / (S * S));
        for (uint p = 0u; p < glow_p.planes; ++p) {
            vec4 v = vec4(glow_coeff(base, 4u * p), glow_coeff(base, 4u * p + 1u), glow_coeff(base, 4u * p + 2u),
                          glow_coeff(base, 4u * p + 3u));
            imageStore(glow_grid_fine, at + ivec3(0, 0, int(p * S)), v);
        }
        return;
    }
    uint dx = glow_p.grid_dx, dxy = glow_p.grid_dx * glow_p.grid_dy, W = glow_p.lightmap_width;
    ivec3 cell = ivec3(pr.x % dx, (pr.x / dx) % glow_p.grid_dy, pr.x / dxy);
    /* a lightmap texel page * W * H + y * W + x: plane p of page g at layer g * planes + p (format 1.7) */
    uint row = pr.x / max(W, 1u), H = max(glow_p.lightmap_height, 1u);
    ivec2 texel = ivec2(pr.x % max(W, 1u), row % H);
    uint layer0 = (row / H) * glow_p.planes;
    for (uint p = 0u; p < glow_p.planes; ++p) {
        vec4 v = vec4(glow_coeff(base, 4u * p), glow_coeff(base, 4u * p + 1u), glow_coeff(base, 4u * p + 2u),
                      glow_coeff(base, 4u * p + 3u));
        if (grid) imageStore(glow_grid, cell + ivec3(0, 0, int(p * glow_p.grid_dz)), v);
        else imageStore(glow_lightmap, ivec3(texel, int(layer0 + p)), v);
    }
}
