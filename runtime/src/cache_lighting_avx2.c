/* cache_lighting_avx2.c — the AVX2+FMA+F16C cache-lighting kernel, its own translation unit so that the
 * build compiles the three kernels in parallel (cache_lighting.c, GLOW_CL_SPLIT). */
#define GLOW_CL_SPLIT 1
#define GLOW_CL_PART 1
#include "cache_lighting.c"
