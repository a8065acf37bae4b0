/*
 * detail.comp — the lightmap detail (bake LDET, docs/linker.md "Lightmap detail"): every detail texel
 * that covers a surface sums its links, signed weights times the radiance of a leaf surfel (flux · w of
 * the FLUX buffer, YCoCg), and stores the RGB correction with coverage 1 in the detail image. Texels
 * that cover no surface keep the (0, 0, 0, 0) they were created with. The C reference is the runtime's
 * detail_range (runtime/src/system.c).
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_DETAIL_GROUP
#error "GLOW_DETAIL_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_DETAIL_GROUP) in;

layout(std430, binding = GLOW_BINDING_DETAIL_TEXELS) readonly buffer GlowDetailTexels { uvec2 glow_det_texel[]; };
layout(std430, binding = GLOW_BINDING_DETAIL_LINKS) readonly buffer GlowDetailLinks { uvec2 glow_det_link[]; };
layout(std430, binding = GLOW_BINDING_FLUX) readonly buffer GlowFlux { vec4 glow_flux[]; };
layout(rgba32f, binding = GLOW_IMAGE_DETAIL) uniform writeonly image2D glow_detail;

void main() {
    uint i = glow_global_index(GLOW_DETAIL_GROUP);
    if (i >= glow_p.detail_texels) return;
    uvec2 tx = glow_det_texel[i];          /* (texel y * width + x, first link) */
    uint end = glow_det_texel[i + 1u].y;   /* one more entry closes the last range */
    vec3 ycc = vec3(0.0);
    for (uint k = tx.y; k < end; ++k) {
        uvec2 l = glow_det_link[k];         /* (surfel, floatBits(weight)) */
        vec4 f = glow_flux[l.x];
        ycc += uintBitsToFloat(l.y) * (f.xyz * f.w);
    }
    vec3 rgb = vec3(ycc.x + ycc.y - ycc.z, ycc.x + ycc.z, ycc.x - ycc.y - ycc.z); /* glow_ycocg_to_rgb */
    uint W = max(glow_p.detail_width, 1u);
    imageStore(glow_detail, ivec2(int(tx.x % W), int(tx.x / W)), vec4(rgb, 1.0));
}
