/* cache_lighting_generic.c — the portable cache-lighting kernel, its own translation unit so that the
 * build compiles the three kernels in parallel (cache_lighting.c, GLOW_CL_SPLIT). */
#define GLOW_CL_SPLIT 1
#define GLOW_CL_PART 3
#include "cache_lighting.c"
