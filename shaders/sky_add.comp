/*
 * sky_add.comp — the visible sky of the grid caches (glow_gl_system_set_sky; docs/sky.md "The grid:
 * visible sky"): after the bounce iterations, each of the first glow_sky_count floats of CACHE_SH (the
 * grid caches' rows) is saved to SKY_BACKUP and gets V ⊗ L added from SKY (computed on the CPU per
 * set_sky call, in CACHE_SH's layout). The backend copies SKY_BACKUP back before the next update's
 * surfel flux reads the caches, so the sky never enters the bounce; runtime/src/system.c does the same.
 * One float add per element: bit for bit the CPU solver's sum.
 */
#include "glow_kernel_common.glsl"
#ifndef GLOW_SKY_GROUP
#error "GLOW_SKY_GROUP must be defined (glow_shared.h)"
#endif
layout(local_size_x = GLOW_SKY_GROUP) in;

layout(std430, binding = GLOW_BINDING_CACHE_SH) buffer GlowCacheSh { float glow_cache_sh[]; };
layout(std430, binding = GLOW_BINDING_SKY) readonly buffer GlowSky { float glow_sky[]; };
layout(std430, binding = GLOW_BINDING_SKY_BACKUP) writeonly buffer GlowSkyBackup { float glow_sky_backup[]; };
uniform uint glow_sky_count;

void main() {
    uint i = glow_global_index(GLOW_SKY_GROUP);
    if (i >= glow_sky_count) return;
    float c = glow_cache_sh[i];
    glow_sky_backup[i] = c;
    glow_cache_sh[i] = c + glow_sky[i];
}
