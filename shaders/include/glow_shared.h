/*
 * glow_shared.h — what Glow's GL kernels and their C host (integration/gpu/) must agree on: buffer
 * bindings, struct layouts (std430 / std140 with only 4-byte scalars and vec4s, so C and GLSL lay them
 * out alike), workgroup sizes. Valid C11 and GLSL 4.50: the embed step defines GLOW_GLSL before it.
 *
 * Bindings are per kernel (the backend binds before every dispatch); the HOST HOOK (surfel_direct.comp)
 * may use any texture unit and SSBO/UBO bindings >= GLOW_BINDING_HOST_FIRST. Glow's kernels use no
 * texture units and image units 0..2 only (outputs.comp, detail.comp).
 *
 *   kernel            SSBO bindings (see GLOW_BINDING_*)                         UBO 0
 *   surfel_direct     SURFEL_GEOM, DIRECT (w), STATUS (rw)                       params
 *   surfel_flux       SURFEL_MAT, DIRECT, FEEDBACK_W, CACHE_SH, NODES, FLUX (w) params
 *   pull              NODES, FLUX (rw)                          uniform uvec2 glow_level (first, count)
 *   pull_tail         NODES, FLUX (rw), LEVELS                  uniform uvec2 glow_tail (first level, end)
 *   cache_light       LINKS, FLUX, CACHE_SH (w)                                  params
 *   outputs           OUTPUT_PAIRS, CACHE_SH; images 0 grid, 1 lightmap          params
 *   detail            DETAIL_TEXELS, DETAIL_LINKS, FLUX; image 2 detail           params
 *   proxy_fill        PROXY_SRC (a neighbour's FLUX), PROXY_MAP, FLUX (w)    uniform uvec2 glow_proxy_range
 *   drift             FLUX, RAD_PREV (rw), DRIFT_PARTIAL (w)                 uniform uint glow_drift_count
 *   cache_light with converged_epsilon also CACHE_DELTA (w), CACHE_SH read too   uniform uint glow_cache_delta
 *   sky_add           CACHE_SH (rw), SKY, SKY_BACKUP (w)                     uniform uint glow_sky_count
 */
#ifndef GLOW_SHARED_H
#define GLOW_SHARED_H

#ifndef GLOW_GLSL
#include <stdint.h>
typedef uint32_t glow_uint;
typedef float glow_float;
typedef struct glow_vec4 { float x, y, z, w; } glow_vec4;
#define GLOW_STRUCT(name) typedef struct name name; struct name
#else
#define glow_uint uint
#define glow_float float
#define glow_vec4 vec4
#define GLOW_STRUCT(name) struct name
#endif

/* SSBO bindings */
#define GLOW_BINDING_SURFEL_GEOM 0  /* glow_gl_surfel_geom[S] */
#define GLOW_BINDING_SURFEL_MAT 1   /* glow_gl_surfel_mat[S] */
#define GLOW_BINDING_DIRECT 2       /* vec4[S]: direct irradiance W/m² (rgb), w unused */
#define GLOW_BINDING_FEEDBACK_W 3   /* float[S][luma²]: π s_l(1) y_lm(n) */
#define GLOW_BINDING_LINK_SUBSETS 3 /* cache_light only (with GLOW_LINK_SUBSETS): uint[]: the bake's LSUB */
#define GLOW_BINDING_STATUS 3       /* surfel_direct only: glow_gl_status */
#define GLOW_BINDING_CACHE_SH 4     /* float[C][coeff_count]: Y luma², Co chroma², Cg chroma² */
#define GLOW_BINDING_NODES 5        /* uvec4[N]: child0, child1, floatBits(1/(π area)), 0 */
#define GLOW_BINDING_FLUX 6         /* vec4[N]: flux Y Co Cg (W), w = 1/(π area): radiance = xyz * w */
#define GLOW_BINDING_LINKS 7        /* uint[]: the bake's link blocks (32 uints = 16 links each) */
#define GLOW_BINDING_OUTPUT_PAIRS 7 /* outputs only: uvec2[grid_used + lightmap_used] (cell/texel, cache) */
#define GLOW_BINDING_LEVELS 7       /* pull_tail only: uint[level_count + 1] level starts */
#define GLOW_BINDING_DETAIL_TEXELS 0 /* detail only: uvec2[texels + 1] (texel y * width + x, first link) */
#define GLOW_BINDING_DETAIL_LINKS 1  /* detail only: uvec2[links] (leaf surfel, floatBits(weight)) */
#define GLOW_BINDING_PROXY_SRC 5    /* proxy_fill only: vec4[]: a neighbouring system's FLUX */
#define GLOW_BINDING_PROXY_MAP 7    /* proxy_fill only: uvec2[]: (neighbour node, own proxy node N + p) */
#define GLOW_BINDING_CACHE_LIST 2   /* cache_light only: uint[]: the caches a budget gathers (uniform
                                       glow_cache_list_count > 0), else every cache */
#define GLOW_BINDING_RAD_PREV 0      /* drift only: float[N + P]: each node's radiance luma at the last drift */
#define GLOW_BINDING_DRIFT_PARTIAL 1 /* drift only: vec2[groups]: per workgroup (Σ |y - y_prev|, Σ |y|) */
#define GLOW_BINDING_CACHE_DELTA 1   /* cache_light only (uniform glow_cache_delta != 0): vec2[list]: per listed
                                        cache (|new DC - old DC|, |new DC|) of its luma, for the convergence test */
/* link gradients (GLOW_LINK_GRADIENT; glow_backend.h glow_solver_tables.link_gradients) */
#define GLOW_BINDING_MOMENTS 7       /* surfel_flux, pull, gradient_u: vec4[N]: luma-flux moments sum Yflux p (xyz), 0 */
#define GLOW_BINDING_MOMENTS_TAIL 0  /* pull_tail: the same buffer (its 7 is LEVELS) */
#define GLOW_BINDING_GRADIENT_U 0    /* gradient_u, cache_light: vec4[N + P]: u (xyz, IEEE-half values), 0;
                                        0 for nodes no coded link reads and the proxies */
#define GLOW_BINDING_GRADIENT_NODES 1 /* gradient_u only: uint[]: the nodes some coded link reads */
#define GLOW_BINDING_GRADIENT_CM 2    /* gradient_u only: float[][12]: per such node c (3), M (9, row-major) */
#define GLOW_BINDING_SKY 0            /* sky_add only: float[grid caches][coeff_count]: V ⊗ L (YCoCg) to add */
#define GLOW_BINDING_SKY_BACKUP 1     /* sky_add only: float[grid caches][coeff_count]: the rows without it (w) */
#define GLOW_BINDING_HOST_FIRST 8   /* first SSBO/UBO binding the host hook may use */
/* UBO binding of glow_gl_params */
#define GLOW_BINDING_PARAMS 0
/* image units of outputs.comp */
#define GLOW_IMAGE_GRID 0     /* image3D rgba32f: plane p of cell (x,y,z) at (x, y, z + p * dz) */
#define GLOW_IMAGE_LIGHTMAP 1 /* image2DArray rgba32f: plane p of texel (x,y) at layer p */
#define GLOW_IMAGE_DETAIL 2   /* detail.comp: image2D rgba32f, the lightmap detail (RGB correction, coverage) */
#define GLOW_IMAGE_GRID_FINE 3 /* image3D rgba32f: a refined grid's brick atlas, see glow_gl.h grid_fine_texture */

/* workgroup sizes (the kernels #error without them; the backend defines them from here) */
#define GLOW_SURFEL_GROUP 64
#define GLOW_PULL_GROUP 64
#define GLOW_PULL_TAIL_MAX 256 /* levels of at most this many nodes (and all above them) go to pull_tail */
#define GLOW_CACHE_GROUP 64   /* one workgroup per cache, threads across its links */
#define GLOW_OUTPUT_GROUP 64
#define GLOW_DETAIL_GROUP 64
#define GLOW_PROXY_GROUP 64
#define GLOW_GRADIENT_GROUP 64
#define GLOW_SKY_GROUP 64
#define GLOW_DRIFT_GROUP 256  /* a power of two (drift.comp's reduction) */
#define GLOW_REDUCE_CHUNK 32  /* coefficients reduced per shared-memory pass */
#define GLOW_MAX_GROUPS_X 65535u /* dispatches wider than this use y (index = y * 65535 + x) */

/* Per-surfel material state, recomputed on the CPU when albedo/emission scales change:
 * B = rho · E_direct + rho_ind · bounce · max(0, E_indirect) + emit;  flux = B · surfel_area. */
GLOW_STRUCT(glow_gl_surfel_mat) {
    glow_vec4 rho;     /* rgb: albedo × material scale, clamped to [0, 0.999] */
    glow_vec4 rho_ind; /* rgb: min(rho, the non-divergence cap) */
    glow_vec4 emit;    /* rgb: π L_e · emission_scale · material emission scale (W/m²) */
    glow_uint feedback, material, reserved0, reserved1;
};

GLOW_STRUCT(glow_gl_surfel_geom) {
    glow_vec4 position_area; /* m, m² */
    glow_vec4 normal;        /* unit, w = 0 */
};

/* Counters the hook kernel raises (read back only when the host asks for stats). */
GLOW_STRUCT(glow_gl_status) {
    glow_uint nonfinite; /* surfels whose hook value was NaN/Inf (stored as 0) */
    glow_uint negative;  /* channels clamped to 0 */
    glow_uint first_bad; /* lowest surfel index with a non-finite value (0xFFFFFFFF = none) */
    glow_uint reserved;
};

/* std140 with 4-byte scalars only: C and GLSL agree without padding rules. */
GLOW_STRUCT(glow_gl_params) {
    glow_uint surfel_count, node_count, cache_count, coeff_count;
    glow_uint blocks_per_cache, grid_used, lightmap_used, planes;
    glow_uint grid_dx, grid_dy, grid_dz, lightmap_width;
    glow_uint lightmap_height, detail_texels, detail_width, reserved2;
    glow_float surfel_area, bounce_intensity, reserved3, reserved4;
    glow_uint fine_used, grid_refine, fine_atlas_x, reserved5; /* a refined grid's brick atlas (outputs.comp) */
};

#endif /* GLOW_SHARED_H */
