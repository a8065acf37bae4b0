/*
 * glow_gl.h — the GL 4.5 backend of Glow's solver: the same frame as glow_system_update (PIC Fig. 2:
 * surfel lighting -> pull -> cache lighting -> output textures), as GLSL compute kernels, with the
 * host lighting the surfels through its own shadow maps in a GLSL hook. Part of glow_gl (target
 * glow::gl, integration/gpu/); the kernels (shaders/NAME.comp) are embedded at build time.
 *
 * WHAT IT MIRRORS: a CPU glow_system made from the same bake. Its solver tables (glow_backend.h, not
 * public API: glow_system_get_solver_tables: surfels, hierarchy, links, feedback weights, the non-divergence cap)
 * are uploaded at create; its artist controls (glow_system_set_params, glow_system_set_material,
 * glow_system_set_surfel_emission) apply to both and are picked up at the next GL update. So the two
 * backends give the same numbers within float tolerance (tests/gpu/test_gl_agreement.c measures it),
 * and a host can switch between them per frame. The CPU system's memory stays allocated (its cache SH
 * and outputs: Sponza moderate about 20 MB of host memory that the GL path does not use).
 *
 * USAGE
 *   glow_gl_system *gs;
 *   glow_gl_system_create(&(glow_gl_desc){ .system = sys, .get_proc_address = load,
 *                                          .hook_glsl = my_hook_source }, &gs);
 *   every frame:  (render shadow maps, bind their textures for the hook)
 *                 glow_gl_system_update(gs, NULL);
 *                 const glow_gl_outputs *o = glow_gl_system_outputs(gs);   sample o->lightmap_texture ...
 *                 in the material shader:  #include "glow_shading.glsl"  (glow_gl_shading_source())
 *
 * THE HOST HOOK (hook_glsl): GLSL source that #defines GLOW_HOST_SURFEL_IRRADIANCE_DEFINED and defines
 *     vec3 glow_host_surfel_irradiance(vec3 position, vec3 normal, uint material);
 * returning the DIRECT IRRADIANCE (W/m², RGB) at a surfel's front face from the host's lights, shadowed
 * with the host's shadow maps — the CPU hook's contract (glow.h glow_lighting_hooks), evaluated once per
 * surfel and update. It is spliced into surfel_direct.comp (#version 450 core) after Glow's declarations,
 * with `#line 1 1` so compile errors name source string 1 and the hook's own lines. It may declare
 * uniforms, samplers and buffers: Glow's kernels use no texture units and SSBO/UBO bindings below
 * GLOW_BINDING_HOST_FIRST (8) only; bind the hook's textures and buffers before each update, and set
 * its plain uniforms on glow_gl_outputs.hook_program. Inside Glow's kernel GLOW_SURFEL_INDEX_AVAILABLE is
 * defined and `uint glow_surfel_index` holds the surfel being lit (the bake's order, as
 * glow_system_get_surfels), so a hook can read per-surfel data of its own (glow_gl_lights: sky
 * visibility); a hook shared with fragment shaders guards that with #ifdef. NaN/Inf values are stored as 0 and counted
 * (glow_gl_stats.hook_nonfinite), negatives clamped to 0 and counted: a bad hook never poisons the
 * caches. With GLOW_GL_FLAG_CHECK_HOOK the update reads the counters back at once (a GPU sync) and
 * returns GLOW_ERROR_HOST_CALLBACK, keeping the previous outputs, like the CPU update.
 * Without a hook (NULL) the direct irradiance is the CPU system's (pushed with
 * glow_system_set_surfel_irradiance; uploaded when it changed).
 *
 * OUTPUTS (glow_gl_outputs): coefficients as in glow_cache_outputs (Y luma², Co chroma², Cg chroma²,
 * incident radiance W/(m²·sr)), 4 per RGBA32F texel ("planes"; RGBA16F with GLOW_GL_FLAG_RGBA16F_OUTPUTS):
 *   grid_texture      GL_TEXTURE_3D (dx, dy, dz · planes): plane p of cell (x,y,z) at (x, y, z + p·dz)
 *   grid_mask_texture GL_TEXTURE_3D RG32UI (dx, dy, dz): per cell and octant, the corners a lookup blends
 *   lightmap_texture  GL_TEXTURE_2D_ARRAY (w, h, planes · pages): plane p of page g at layer g·planes + p;
 *                     lightmap_valid_texture GL_TEXTURE_2D R8UI (w, h · pages), the pages one above another
 *   lightmap_detail_texture GL_TEXTURE_2D RGBA32F (bakes with a lightmap detail): RGB correction, A coverage,
 *                     (detail_width, detail_height · pages) likewise
 *   (pages: lightmap_pages, 1 unless the bake's lightmap has several, format 1.7; glow_sample_lightmap_page)
 *   cache_sh_buffer   SSBO float[cache_count][coeff_count] (the bounce state)
 *   flux_buffer       SSBO vec4[node_count]: node flux YCoCg, w = 1/(π area) (for debug views)
 * shaders/include/glow_shading.glsl samples them (glow_sample_grid / glow_sample_lightmap / glow_shade_sh).
 * A host that owns its textures passes them in the desc (same formats and sizes: checked at create).
 *
 * ON ERRORS: every call returns a glow_result and logs through desc.logger ("glow_gl(label): ...").
 * GLOW_ERROR_UNSUPPORTED: the context lacks GL 4.5 or a needed limit (the message names it);
 * GLOW_ERROR_INVALID_ARGUMENT: NULL, bad desc, host textures of the wrong format/size;
 * GLOW_ERROR_HOST_CALLBACK: the hook does not compile or link (the message carries the GL info log).
 * Nothing is left allocated after a failed create.
 *
 * ON THREADS: every call needs the create's GL context current on the calling thread.
 */
#ifndef GLOW_GLOW_GL_H
#define GLOW_GLOW_GL_H

#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h"
#include "glow/glow_gl_loader.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GLOW_GL_FLAG_NO_TIMERS 1u  /* no GL timer queries (stats report 0 ms) */
#define GLOW_GL_FLAG_CHECK_HOOK 2u /* read the hook's NaN counter back every update (a sync; for debugging) */
#define GLOW_GL_FLAG_FINISH_TIMERS 4u /* time stages by glFinish + the CPU clock instead of timer queries: for
                                         drivers whose timestamps are not ordered with compute work (Mesa's
                                         llvmpipe resolves them on its rasteriser thread, so the split between
                                         stages is wrong there); adds a full sync per stage */
#define GLOW_GL_FLAG_RGBA16F_OUTPUTS 8u /* \since 0.2: the grid, lightmap and refined-grid textures in RGBA16F
                                           instead of RGBA32F (host-owned ones too): half their memory and their
                                           lookups' bandwidth; values clamped to +-65504, then the driver's
                                           rounding. glow_shading.glsl reads either. The detail stays RGBA32F */

typedef struct glow_gl_desc {
    glow_system *system;             /* required, borrowed: the CPU system of the same bake (must outlive) */
    glow_gl_loader get_proc_address; /* required: the current context's loader */
    const char *hook_glsl;           /* the host hook (see above), copied; NULL = the CPU system's direct light */
    uint32_t flags;                  /* GLOW_GL_FLAG_* */
    const char *label;               /* copied; names the system in messages (NULL = "gl") */
    glow_logger logger;              /* zero = silent */
    /* optional host-owned output textures (0 = Glow creates them): formats and sizes as in OUTPUTS */
    uint32_t grid_texture, lightmap_texture;
} glow_gl_desc;

typedef struct glow_gl_system glow_gl_system;

typedef struct glow_gl_outputs {
    uint32_t sh_bands_luma, sh_bands_chroma, coeff_count;
    uint32_t planes;                      /* RGBA texels per cache: ceil(coeff_count / 4) */
    uint32_t grid_texture, grid_mask_texture; /* 0 without a grid */
    uint32_t grid_dims[3];
    float grid_origin[3], grid_spacing;
    uint32_t lightmap_texture, lightmap_valid_texture; /* 0 without a lightmap */
    uint32_t lightmap_width, lightmap_height;
    uint32_t cache_sh_buffer;
    uint32_t flux_buffer;                 /* SSBO vec4[node_count]: flux (W) Y Co Cg of every hierarchy node after
                                             the last update's pull, w = 1/(π area): radiance = xyz · w (debug views) */
    uint32_t cache_count;
    uint32_t hook_program;                /* the program running the hook (0 without one) */
    uint64_t update_index;
    /* bakes with a lightmap detail (glow_cache_outputs.lightmap_detail; 0 otherwise): GL_TEXTURE_2D
     * RGBA32F detail_width x detail_height, RGB the correction, A 1 where a detail texel covers a surface
     * (glow_shading.glsl glow_sample_lightmap_detail) */
    uint32_t lightmap_detail_texture;
    uint32_t detail_width, detail_height;
    /* \since 0.2, bakes with a refined grid (glow_cache_outputs.grid_refine = R; 0 otherwise), for
     * glow_shading.glsl glow_sample_grid_refined: grid_brick_texture GL_TEXTURE_3D R32UI (dx, dy, dz),
     * each cell's brick or 0xFFFFFFFF; grid_fine_texture GL_TEXTURE_3D RGBA32F or 16F (S ax, S ay, S planes),
     * S = R + 1, ax = grid_fine_atlas_x: corner (x, y, z) of brick b, plane p, at (S (b % ax) + x,
     * S (b / ax) + y, z + S p); grid_fine_mask_texture GL_TEXTURE_3D RG32UI (R ax, R ay, R): per fine
     * cell and octant the corners a lookup blends (visible and holding a cache), as grid_mask_texture */
    uint32_t grid_refine, grid_fine_atlas_x;
    uint32_t grid_brick_texture, grid_fine_texture, grid_fine_mask_texture;
    /* \since 0.2: the lightmap's pages (glow_cache_outputs.lightmap_pages; 0 without a lightmap). With P
     * pages lightmap_texture has planes · P layers (page g's plane p at layer g · planes + p), and
     * lightmap_valid_texture and lightmap_detail_texture are P pages high (page g's rows from g · height);
     * lightmap_height and detail_height stay a page's. glow_shading.glsl glow_sample_lightmap_page and
     * glow_sample_lightmap_detail_page take the page (a triangle's: glow_bake_geometry.lightmap_page). */
    uint32_t lightmap_pages;
    /* \since 0.2: the grid, lightmap and fine-grid textures' internal format: GL_RGBA32F (0x8814), or
     * GL_RGBA16F (0x881A) with GLOW_GL_FLAG_RGBA16F_OUTPUTS */
    uint32_t output_internal_format;
} glow_gl_outputs;

/* GPU time of the last update, per stage, from GL timer queries (ms). */
typedef struct glow_gl_stats {
    double surfel_lighting_ms; /* hook kernel + flux kernel */
    double host_ms;            /* the hook kernel (0 without a hook: includes the upload then) */
    double pull_ms, cache_lighting_ms, output_ms, total_ms;
    uint32_t hook_nonfinite;   /* surfels whose hook value was NaN/Inf in the last update (stored as 0) */
    uint32_t hook_negative;    /* channels clamped to 0 */
    uint32_t pull_dispatches;  /* one per hierarchy level */
    uint64_t updates;
    uint64_t gpu_memory_bytes; /* buffers and textures Glow allocated */
    char renderer[96];         /* GL_RENDERER */
    uint32_t caches_gathered;  /* caches the last update gathered (all, or a budget's) \since 0.2 */
    uint32_t caches_skipped_converged; /* ... left as converged (converged_epsilon) \since 0.2 */
} glow_gl_stats;

/** Compiles the kernels for the system's band counts (and the hook), uploads the solver tables,
 * creates the outputs (zero). \returns see ON ERRORS; *out is NULL on failure. */
GLOW_API glow_result glow_gl_system_create(const glow_gl_desc *desc, glow_gl_system **out);
/** Deletes every GL object it made (NULL is a no-op). The CPU system is not touched. */
GLOW_API void glow_gl_system_destroy(glow_gl_system *system);
/** Light across systems (a system of a world, glow-bake --system-area; docs/runtime.md "A world of
 * systems"): attaches the GL system of `neighbour` as dependency `dependency` of `system`, as
 * glow_system_set_neighbour does for their CPU systems (which it also calls: same checks, same
 * errors). Before each cache gather the proxy nodes copy the neighbour's node flux as its last GL update
 * left it; NULL detaches (the proxies keep what they last read, zero if never attached). Both must
 * live in the same GL context (or share objects). A GL system another reads is not destroyed until
 * detached. \since 0.2 */
GLOW_API glow_result glow_gl_system_set_neighbour(glow_gl_system *system, uint32_t dependency,
                                                  glow_gl_system *neighbour);
/** One frame on the GPU (flags: GLOW_UPDATE_FLAG_RESET_BOUNCE, GLOW_UPDATE_FLAG_KEEP_LIGHTING), x the CPU
 * system's bounce_iterations. Allocates nothing; does not wait for the GPU (unless CHECK_HOOK).
 * Budgets (\since 0.2): desc->max_caches and desc->budget_ms, with desc->focus / focus_count /
 * focus_radius, gather the cache groups glow_system_update would choose (the same priority, the same
 * function, glow_budget_choose), the others keep their last values. budget_ms is GPU time, learnt from
 * earlier budgeted updates' timer queries once they are available (never waited for; with
 * GLOW_GL_FLAG_FINISH_TIMERS, the CPU clock around glFinish): until then every group is gathered.
 * desc->converged_epsilon skips the groups the CPU solver would (each group's change at its last gather,
 * read back at the next budgeted update, and the drift of the node luma, computed on the GPU and read
 * back at once: the update then waits for its pull to finish, its one wait).
 * GLOW_ERROR_INVALID_ARGUMENT for a bad focus, budget_ms or converged_epsilon. */
GLOW_API glow_result glow_gl_system_update(glow_gl_system *system, const glow_update_desc *desc);
/** The visible sky in the GL grid caches, as glow_system_set_sky does on the CPU solver (glow.h; docs/sky.md
 * "The grid: visible sky"): from the next update on, each grid cache's SH (cache_sh_buffer, the grid
 * textures) also holds V ⊗ L, the part of the sky `sh_rgb` (RGB l <= 2 SH, coefficient-major,
 * GLOW_SKY_SH_FLOATS) the cache sees, in YCoCg (bands above 2 get nothing, chroma only up to
 * sh_bands_chroma). It is added after the bounce and taken out again before the next update's surfel
 * flux, so it is never fed back (the hook lights the surfels with the sky already:
 * glow_gl_lights_set_environment_sh); lightmap caches are not changed. V ⊗ L is computed here on the CPU
 * (9 x 27 multiply-adds per grid cache, the CPU solver's arithmetic) and uploaded; an update then costs
 * one small dispatch and one buffer copy over the grid caches' rows. The first call creates two GPU
 * buffers of the grid caches' SH (8 · grid caches · coeff_count bytes). NULL removes the sky. Independent
 * of the CPU system's own glow_system_set_sky (call both when a host switches backends). Needs the GL
 * context current and a bake with the sky transfer (format 1.6 SKYT).
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL system, a non-finite coefficient or one beyond
 * GLOW_MAX_IRRADIANCE: nothing changes); GLOW_ERROR_UNSUPPORTED (a bake without SKYT);
 * GLOW_ERROR_OUT_OF_MEMORY. \since 0.2 */
GLOW_API glow_result glow_gl_system_set_sky(glow_gl_system *system, const float sh_rgb[GLOW_SKY_SH_FLOATS]);
/** Waits for the last update's queries and fills `out`. */
GLOW_API glow_result glow_gl_system_get_stats(glow_gl_system *system, glow_gl_stats *out);
/** The output textures and buffers (owned by the system). */
GLOW_API const glow_gl_outputs *glow_gl_system_outputs(const glow_gl_system *system);
/** Reads the cache SH back (count floats: cache_count x coeff_count, the CPU system's cache_sh layout). Syncs. */
GLOW_API glow_result glow_gl_system_read_cache_sh(glow_gl_system *system, float *out, size_t count);
/** shaders/include/glow_shading.glsl with its includes resolved (embedded; no file is read), for hosts
 * that prepend it to their material shaders after #defining GLOW_SH_BANDS_LUMA / _CHROMA. */
GLOW_API const char *glow_gl_shading_source(void);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_GL_H */
