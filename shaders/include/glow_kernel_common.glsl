/*
 * glow_kernel_common.glsl — declarations every Glow kernel shares (not for hosts): the parameter block
 * and the flat dispatch index. Kernels are compiled by the GL backend with a prelude of #defines
 * (GLOW_GLSL, band counts, workgroup sizes) and glow_shared.h.
 */
#ifndef GLOW_KERNEL_COMMON_GLSL
#define GLOW_KERNEL_COMMON_GLSL
#include "glow_shared.h"

#ifndef GLOW_LUMA_BANDS
#error "GLOW_LUMA_BANDS must be defined (1..8)"
#endif
#ifndef GLOW_CHROMA_BANDS
#error "GLOW_CHROMA_BANDS must be defined (1..GLOW_LUMA_BANDS)"
#endif
#define GLOW_L2 (GLOW_LUMA_BANDS * GLOW_LUMA_BANDS)
#define GLOW_C2 (GLOW_CHROMA_BANDS * GLOW_CHROMA_BANDS)
#define GLOW_NCO (GLOW_L2 + 2 * GLOW_C2)

layout(std140, binding = GLOW_BINDING_PARAMS) uniform GlowParams { glow_gl_params glow_p; };

/* Dispatches wider than GLOW_MAX_GROUPS_X groups use y: group index = y * GLOW_MAX_GROUPS_X + x. */
uint glow_group_index() { return gl_WorkGroupID.y * GLOW_MAX_GROUPS_X + gl_WorkGroupID.x; }
/* (a macro: gl_WorkGroupSize is only declared after the kernel's local_size layout, which follows this file) */
#define glow_global_index(group) (glow_group_index() * uint(group) + gl_LocalInvocationID.x)

#endif
