/*
 * glow_gl_lights.h — the reference GPU host lighting for the GL 4.5 backend: point, spot and sun lights
 * plus a constant sky, shadowed by depth maps rendered on the GPU, given to Glow as the GLSL surfel
 * lighting hook (and to the host's own fragment shaders, for the same direct light on screen).
 *
 * Part of glow_gl_lights (target glow::gl_lights, folder integration/hosts/gl_lights/; links glow_glfns and
 * glow_host for glow_scene.h). It is the GPU twin of glow_host.h's GLOW_HOST_KIND_SHADOW_MAP host:
 * the same light models, the same maps (placement, resolution, margins, near plane), the same bias,
 * normal offset and PCF — so the two agree surfel by surfel up to rasteriser and float rounding
 * differences at shadow edges (tests/gpu/test_gl_lights.c measures it).
 *
 * THE HOOK: glow_gl_lights_hook_source returns GLSL (no #version line) that defines
 *     #define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED
 *     vec3 glow_host_surfel_irradiance(vec3 position, vec3 normal, uint material);
 * returning the DIRECT IRRADIANCE E (W/m², linear RGB) at `position` (m) for the unit front normal
 * `normal`, exactly glow_host.h's contract (THE CONTRACT) with the shadow-map visibility and the sky's
 * S per surfel from glow_gl_lights_set_sky_visibility (the CPU host's traced values), else 1 (unshadowed,
 * as GLOW_HOST_SKY_UNSHADOWED):
 *     E = Σ_lights V_i · power_i · f_i  +  environment · π · S
 * `material` is not used. The text is valid in a `#version 450 core` compute shader (Glow splices
 * it after its own declarations) and in a fragment shader (no derivatives, no implicit-LOD
 * sampling, no compute built-ins). Its global names all start with glow_gl_lights / GLOW_GL_LIGHTS
 * (types glow_gl_lights_light, glow_gl_lights_map; uniform block glow_gl_lights_block, instance
 * glow_gl_lights; samplers glow_gl_lights_maps, glow_gl_lights_cube_faces; macros GLOW_GL_LIGHTS_*).
 * In a fragment shader, normalise interpolated normals before the call.
 *
 * BINDINGS: the hook reads one std140 uniform block at binding `ubo_binding` (default 8) and two
 * sampler2DArray at texture units `texture_unit` (default 8: sun and spot maps) and texture_unit + 1
 * (default 9: cube-map faces of point lights and of spots wider than 60°), fixed in the source with
 * layout(binding = ...). Glow's kernels use no texture units and buffer bindings 0..7 only, so the
 * defaults never collide with them; a host whose own shaders use units 8 and 9 moves them here.
 * glow_gl_lights_bind binds the three (and sampler object 0 on both units); call it before
 * glow_gl's update and before drawing with a shader that includes the hook.
 *
 * SHADOW MAPS: depth maps of every bake triangle, both faces (no culling), rendered by
 * glow_gl_lights_set on the GPU: sun = one orthographic map of shadow_map_size² covering the bake's
 * bounding box; spot = one perspective map of shadow_map_size² covering the outer cone (outer_deg
 * <= 60) or a cube of cube_map_size² per face for wider spots; point = a cube. A texel holds the
 * distance along the map's view axis (written by the fragment shader, perspective-correct, so it
 * is the CPU rasteriser's value); a lookup moves p by normal_offset texels along n, compares against
 * depth - bias with bias = texel · (depth_bias + slope_bias · tan θ) and averages pcf_size² nearest
 * texels (texelFetch: no filtering, no hardware comparison). Maps live in two GL_DEPTH_COMPONENT32F
 * 2D array textures, reallocated only when a set() needs a different number of layers; memory is
 * 4 bytes per texel: 4 MiB per sun/narrow-spot map at 1024², 6 MiB per cube at 512².
 *
 * COST: set() renders one depth pass per changed light and does not wait for the GPU; the hook costs
 * one pass over the lights per surfel and pcf_size² texelFetch per lit, shadowed light. Measured
 * figures (llvmpipe and an NVIDIA H100) are in docs/benchmarks.md and docs/gpu.md, not here: they
 * depend on the machine.
 *
 * USAGE
 *   glow_gl_lights *gll;
 *   glow_gl_lights_create(&(glow_gl_lights_desc){ .loader = glow_glctx_get_proc_address(ctx), .bake = bake }, &gll);
 *   glow_gl_lights_set(gll, scene.lights, scene.light_count, scene.environment);
 *   const char *hook = glow_gl_lights_hook_source(gll);      (give it to glow_gl, include it in shaders)
 *   every frame:  glow_gl_lights_set(gll, moved, count, env);   (when lights change: renders their maps)
 *                 glow_gl_lights_bind(gll);                      (before the GL update and the draws)
 *   glow_gl_lights_destroy(gll);
 *
 * GL STATE: set() renders with its own framebuffer, program and vertex array and restores what it
 * changes: the draw framebuffer binding, viewport, current program, vertex array binding, depth
 * test/func/mask, face culling, scissor test, GL_CLIP_DISTANCE0. It assumes the default depth range
 * [0, 1]; GL_CLIP_ORIGIN (glClipControl) is honoured. bind() changes the three bindings above.
 *
 * ON ERRORS: functions return a glow_result and send a line starting "glow_gl_lights: " to
 * desc.logger (GLOW_LOG_ERROR, same code). GL failures name the step and include the driver's info
 * log (shader compile and link) or status (framebuffer completeness, glGetError).
 *
 * ON THREADS: every call needs the GL context of create (or one sharing all its objects — framebuffers
 * and vertex arrays are not shared, so in practice that same context) current on the calling thread;
 * no two calls on one object at once.
 */
#ifndef GLOW_GLOW_GL_LIGHTS_H
#define GLOW_GLOW_GL_LIGHTS_H

#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h"
#include "glow/glow_gl_loader.h"
#include "glow/glow_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GLOW_GL_LIGHTS_MAX_LIGHTS 16u /* the largest max_lights: the uniform block stays under 16 KiB */

typedef struct glow_gl_lights glow_gl_lights;

typedef struct glow_gl_lights_desc {
    glow_gl_loader loader;    /* required: the current context's GetProcAddress */
    const glow_bake *bake;    /* required; its triangles (glow_bake_get_geometry) cast the shadows. Copied
                                 into a GL buffer at create: the bake may be destroyed afterwards */
    uint32_t max_lights;      /* lights one set() may take, 1..GLOW_GL_LIGHTS_MAX_LIGHTS; 0 = 8 */
    /* shadow maps: same meaning, ranges and defaults as glow_host_desc */
    uint32_t shadow_map_size; /* sun and spot maps, texels per side, 16..8192 (and <= GL_MAX_TEXTURE_SIZE); 0 = 1024 */
    uint32_t cube_map_size;   /* point lights and spots wider than 60°, per face, 16..8192; 0 = 512 */
    float depth_bias;         /* constant bias in texels; 0 = 1.0 (pass a tiny value for none) */
    float slope_bias;         /* texels per unit of tan θ; 0 = 2.0 */
    float normal_offset;      /* texels along the normal; 0 = 1.0 */
    uint32_t pcf_size;        /* PCF kernel width in texels: odd, 1..9; 0 = 3 */
    /* where the hook's resources are bound (see BINDINGS) */
    uint32_t ubo_binding;     /* uniform-buffer binding of the light block, >= 8; 0 = 8 */
    uint32_t texture_unit;    /* first of two texture units (maps, cube faces), >= 8; 0 = 8 */
    glow_logger logger;       /* zero = silent; must be reentrant */
} glow_gl_lights_desc;

/**
 * Loads the GL functions, uploads the bake's triangles, compiles the depth program and the hook
 * (once, as a check, in a compute shader), and creates the light block. No lights until set().
 *
 * \param desc   see glow_gl_lights_desc; must not be NULL.
 * \param out    receives the object; NULL on failure.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, settings out of range, bindings below 8 or
 * beyond the context's limits); GLOW_ERROR_EMPTY_SCENE (the bake carries no triangles);
 * GLOW_ERROR_CORRUPT_DATA (a non-finite triangle corner); GLOW_ERROR_UNSUPPORTED (a GL entry point
 * missing, a context older than 4.5, a shader that does not compile or link — the message holds the
 * info log); GLOW_ERROR_OUT_OF_MEMORY (host or GL memory).
 * \threadsafety See ON THREADS. \ownership Copies everything it keeps. \since 0.1
 */
GLOW_API glow_result glow_gl_lights_create(const glow_gl_lights_desc *desc, glow_gl_lights **out);

/** Deletes the GL objects and frees the object (NULL is a no-op). The context of create must be
 * current. \since 0.1 */
GLOW_API void glow_gl_lights_destroy(glow_gl_lights *lights);

/**
 * Replaces all lights (count may differ; 0 = none) and the constant sky radiance, uploads them and
 * renders every light's shadow maps on the GPU (queued: returns without waiting for the GPU).
 * Everything is validated first (glow_scene_light_validate, environment finite and >= 0): on a
 * validation failure nothing changes — the previous lights, maps and sky stay in use. After a GL
 * failure (out of GPU memory, incomplete framebuffer) the maps are undefined until a set() succeeds.
 *
 * \param scene_lights  count lights (directions need not be unit length); NULL when count is 0.
 * \param environment   constant sky radiance W/(m²·sr); NULL = none.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL object, count > max_lights, a light breaking the
 * schema rules: the message names it as lights[i], a bad environment); GLOW_ERROR_UNSUPPORTED (unknown
 * light type, a shadow framebuffer that is not complete); GLOW_ERROR_OUT_OF_MEMORY (map textures).
 * \threadsafety See ON THREADS. \since 0.1
 */
GLOW_API glow_result glow_gl_lights_set(glow_gl_lights *lights, const glow_scene_light *scene_lights, uint32_t count,
                                        const float environment[3]);

/** The hook's GLSL text (see THE HOOK), NUL-terminated, valid for the object's life and the same
 * for its whole life (lights change only the bound data). NULL for NULL. \since 0.1 */
GLOW_API const char *glow_gl_lights_hook_source(const glow_gl_lights *lights);

/** Binds the light block to ubo_binding and the two map arrays to texture_unit and texture_unit + 1
 * (with sampler object 0). \returns GLOW_ERROR_INVALID_ARGUMENT for NULL. \since 0.1 */
GLOW_API glow_result glow_gl_lights_bind(const glow_gl_lights *lights);

/**
 * Per-surfel sky visibility S in [0, 1] (the cosine-weighted visible fraction of the sky, glow_host.h's S;
 * glow_host_sky_visibility computes the CPU host's values) for the hook's sky term environment · π · S.
 * Read inside Glow's surfel kernel, where GLOW_SURFEL_INDEX_AVAILABLE gives the surfel (count must be the
 * bake's surfel_count). Elsewhere — a fragment shader — the hook uses the expression GLOW_GL_LIGHTS_PIXEL_SKY
 * when the including shader #defines it before the hook text (for example S looked up in a texture at the
 * pixel), else 1. NULL returns to the unshadowed sky. Bound by glow_gl_lights_bind as an SSBO at ubo_binding
 * (the SSBO and UBO binding points are separate). Persists across set().
 * 
eturns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL object, count 0 with values, a value outside [0,1]:
 * nothing changes); GLOW_ERROR_OUT_OF_MEMORY. \since 0.1
 */
GLOW_API glow_result glow_gl_lights_set_sky_visibility(glow_gl_lights *lights, const float *visibility, uint32_t count);

/**
 * The sky as SH (docs/sky.md), as glow_host_set_environment_sh: `sh_rgb` holds 27 floats, the sky's radiance
 * W/(m²·sr) as real SH l <= 2, coefficient-major (sh_rgb[3 k + c]; glow.h GLOW_SKY_SH_FLOATS). The hook's
 * sky term is then max(0, Σ_k T_k L_k) per channel instead of environment · π · S: T the surfel's sky
 * transfer (glow_gl_lights_set_sky_transfer) inside Glow's surfel kernel, else (a fragment shader, or no
 * transfer set) the unoccluded cosine lobe about the normal times the sky's visible share as the constant
 * sky takes it (S when set, GLOW_GL_LIGHTS_PIXEL_SKY at a pixel, else 1). NULL returns to the constant
 * environment.
 * Persists across set() (whose environment then waits unused). Uploaded at once (part of the light block).
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL object, a non-finite coefficient or one beyond
 * GLOW_MAX_IRRADIANCE: nothing changes). \since 0.2
 */
GLOW_API glow_result glow_gl_lights_set_environment_sh(glow_gl_lights *lights, const float *sh_rgb);

/**
 * Per-surfel sky transfer T (9 floats a surfel, surfel-major: transfer[9 i + k]; count must be the bake's
 * surfel_count) for the SH sky: the bake's (glow_bake_get_sky_transfer, format 1.6) or the CPU host's
 * (glow_host_sky_transfer). Same buffer and binding as glow_gl_lights_set_sky_visibility (S first, then T),
 * read only inside Glow's surfel kernel. NULL removes it. Persists across set().
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL object, count 0 with values, a value not finite or
 * beyond 16: nothing changes); GLOW_ERROR_OUT_OF_MEMORY. \since 0.2
 */
GLOW_API glow_result glow_gl_lights_set_sky_transfer(glow_gl_lights *lights, const float *transfer, uint32_t count);

typedef struct glow_gl_lights_stats {
    uint32_t light_count;       /* lights of the last successful set() */
    uint32_t triangle_count;    /* bake triangles drawn into every map */
    uint32_t map_count;         /* depth maps in use (a cube counts 6) */
    uint64_t map_bytes;         /* GPU memory of the two map arrays (allocated layers, 4 bytes a texel) */
    double set_ms;              /* CPU wall time of the last successful set() (commands issued, GPU not awaited) */
    uint32_t ubo_binding;       /* resolved bindings (see BINDINGS) */
    uint32_t texture_units[2];  /* maps, cube faces */
} glow_gl_lights_stats;

/** Fills `out_stats`. \returns GLOW_ERROR_INVALID_ARGUMENT for NULL. \since 0.1 */
GLOW_API glow_result glow_gl_lights_get_stats(const glow_gl_lights *lights, glow_gl_lights_stats *out_stats);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_GL_LIGHTS_H */
