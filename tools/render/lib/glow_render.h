/*
 * glow_render.h — glow-render as a library: the reference path tracer (Embree) and Glow's view of the
 * same camera, over one scene description file (docs/scene-format.md). Tool code (tools/render/,
 * target glow_render), not part of the runtime. Full documentation: docs/render.md.
 *
 * THE LIGHT MODEL is the runtime's and the host's (glow_host.h "THE CONTRACT", docs/scene-format.md):
 *   - materials are Lambertian, or diffuse under a GGX layer where the scene's "materials" key gives one
 *     (render_bsdf.h, docs/glossy.md): albedo ρ = material albedo × albedo texture (glow__texture_sample at
 *     the interpolated uv0, finest mip level), times settings.albedo_scale, clamped to [0, 0.999] (the
 *     runtime's clamp); emission L_e = material emission × the scene's emission_scale, W/(m²·sr),
 *     emitted by the FRONT face only (counter-clockwise winding, geometric normal (p1-p0)×(p2-p0));
 *   - point: E = I·max(0, n·l)/d²; spot: × smoothstep falloff of the cone; sun: E = irradiance ·
 *     max(0, -n·direction) — delta lights, reached by next-event estimation only (exact shadow rays);
 *   - environment: constant radiance for every ray that leaves the scene, in any direction, plus the
 *     scene's environment_map (an equirectangular HDR sky, tools/eval/glow_envmap.h, docs/envmap.md)
 *     when it has one: radiance = environment + scale × texel(direction), nearest texel.
 * SURFACES reflect on BOTH sides in the reference (the normal is flipped to face the arriving ray);
 * Glow's surfels live on front faces only, so the two differ where back faces receive light (not in
 * closed rooms). Emission is front-face only in both. Lighting cosines use the interpolated shading
 * normal (the normal Glow's surfels carry); a direction below the geometric surface carries nothing.
 *
 * THE IMAGES (radiance W/(m²·sr), linear RGB, top row first):
 *   direct   = what the camera ray sees directly (front-face emission × emission_scale, or the
 *              environment when it leaves the scene) + the first hit's reflection of the host-style
 *              lights: point/spot/sun by next-event estimation with an exact shadow ray, and the
 *              environment reached by the first bounce (a cosine-sampled ray that escapes; with an
 *              environment_map also one map sample + shadow ray, MIS-combined with that ray). These are
 *              exactly the terms Glow's host computes per surfel (the lighting hook's E).
 *   indirect = everything else: light after two or more bounces from lights and environment, and
 *              emissive surfaces' light reflected at the first hit or later. Glow transports emitters
 *              through its surfels and caches (PIC), so their light at the first hit is Glow's
 *              "indirect" too.
 *   final    = direct + indirect (per pixel, in float).
 * Glow's view (glow_render_glow): the same camera rays, random numbers and direct term (same seed and
 * size: a bit-identical direct image); indirect = ρ · glow_shade_sh(SH, n, 1) at the first hit, the SH
 * from the lightmap (bilinear at the hit's lightmap UV, when a texel with a cache is among the four;
 * front-face hits only) else from the grid (trilinear at the hit position), clamped at 0 per channel;
 * with a GGX layer ρ (1 - E(cos θ_o)) · that + E(cos θ_o) · the caches convolved with the GGX lobe's
 * zonal harmonics (glow_render_glow_settings.glossy; E = F0 A + B, the split sum; docs/glossy.md).
 * The difference between the two final images is Glow's error alone.
 *
 * PATH TRACING (reference): cosine-weighted sampling of the Lambertian lobe (GGX layers: a mixture of
 * visible-normal and cosine sampling, render_bsdf.h); next-event estimation of
 * every delta light at every vertex; emissive triangles sampled by area × luminance (a CDF) and
 * combined with BSDF-sampled emitter hits by multiple importance sampling (power heuristic);
 * an environment_map is sampled at every vertex too (its texels ∝ luminance × solid angle, an
 * unoccluded-to-infinity shadow ray) and combined with BSDF-sampled escaping rays by MIS (power
 * heuristic), the first hit's part of it being direct light (the constant `environment` stays BSDF-sampled);
 * Russian roulette from the third vertex on (survival min(0.95, max channel of throughput × ρ)); no
 * depth limit except settings.max_depth (default 256 vertices: the bias left is below ρ^256).
 * Deterministic per seed for any thread count: each pixel has its own PCG32 streams seeded from
 * hash(seed, pixel); rows are shared among threads, each pixel is computed by one thread.
 *
 * ON ERRORS: functions return a glow_result and write one line naming the file and the problem into
 * `message` (may be NULL). Nothing is printed.
 * ON THREADS: a glow_render_scene is read-only after load; renders of it may run concurrently.
 */
#ifndef GLOW_RENDER_H
#define GLOW_RENDER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h"
#include "glow/glow_scene.h"
#include "glow_eval.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct glow_render_scene glow_render_scene;

/* Loads the scene description `scene_json`, the mesh it names (glow-bake's importer: the same
 * triangles, materials and textures) and builds the Embree scene. */
glow_result glow_render_scene_load(const char *scene_json, glow_render_scene **out_scene, char *message,
                                   size_t message_size);
void glow_render_scene_destroy(glow_render_scene *scene);

typedef struct glow_render_scene_info {
    uint32_t triangle_count, material_count, texture_count;
    uint32_t emissive_triangle_count; /* with emission > 0 (before emission_scale) */
    uint32_t light_count;
    float environment[3], emission_scale;
    glow_scene_camera camera;          /* resolved (glow_scene_camera_default when the file had none) */
    float bounds_min[3], bounds_max[3];
    const char *mesh;                  /* as the scene file resolved it */
    const char *environment_map;       /* the resolved environment_map path, NULL without one */
    uint32_t environment_map_width, environment_map_height;
    float environment_map_rotation_deg, environment_map_scale;
} glow_render_scene_info;
glow_result glow_render_scene_get_info(const glow_render_scene *scene, glow_render_scene_info *out_info);

typedef void (*glow_render_progress_fn)(void *user, double fraction);

typedef struct glow_render_settings {
    uint32_t width, height;   /* 0 = the scene camera's */
    uint32_t spp;             /* samples per pixel; 0 = 64 */
    uint64_t seed;            /* same seed, same size: same image, bit for bit, any thread count */
    uint32_t threads;         /* 0 = one per online CPU */
    uint32_t max_depth;       /* path vertices; 0 = 256 (reference only) */
    float albedo_scale;       /* multiplies every albedo (clamped to 0.999); 0 = 1 */
    float near_split;         /* reference only, m: > 0 also returns indirect_near, the part of the indirect
                                 light that reached the first hit from a surface closer than this (the
                                 first bounce's hit, or the emitter point of its NEE): light a cache-based
                                 solver can only resolve at that scale. 0 = no split */
    glow_render_progress_fn progress; /* optional: called with the fraction of rows done (serialised) */
    void *progress_user;
    bool envmap_bsdf_only;    /* the scene's environment_map reached by BSDF sampling only, no next-event
                                 estimation of the map (for measuring what the map's importance sampling +
                                 MIS gains: the same expected image, more noise). false = NEE + MIS */
} glow_render_settings;

/* How Glow's view shades a GGX layer (scene "materials") from the caches (docs/glossy.md). */
typedef enum glow_render_glossy {
    GLOW_RENDER_GLOSSY_ZH_GGX = 0, /* the GGX lobe's zonal harmonics (glow_sh_ggx_lobe_factors) x the split sum */
    GLOW_RENDER_GLOSSY_PHONG,      /* the Phong lobe of glow_render_phong_exponent(roughness) x the same split sum */
    GLOW_RENDER_GLOSSY_NONE,       /* no specular from the caches (the diffuse layer only) */
    GLOW_RENDER_GLOSSY_ZH_GGX_DOMINANT /* ZH-GGX about the lobe's dominant direction (Lagarde & de Rousiers
                                          2014: the reflection vector leant towards the normal) */
} glow_render_glossy;

/* The Phong exponent standing in for GGX roughness r: Walter et al. 2007's Blinn-Phong exponent
 * 2/α² - 2 (α = r²) about the half vector, divided by 4 about the reflection vector; at least 1. */
float glow_render_phong_exponent(float roughness);

typedef struct glow_render_glow_settings {
    uint32_t bounce_iterations; /* runtime feedback iterations in all (updates of up to 64); 0 = 192 */
    uint32_t sky_rays;          /* the host's rays per surfel for the sky visibility; 0 = its default */
    uint32_t surfel_samples;    /* the host's footprint points per surfel (glow_host_desc); 0 = its default */
    uint32_t sh_bands_luma;     /* glow_system_desc's: 0 = the bake's bands */
    uint32_t sh_bands_chroma;   /* 0 = luma */
    glow_link_mode link_mode;   /* 0 = compact (runtime projection) */
    bool indirect_only;         /* skip the direct term (its image stays 0): the camera rays, their jitter
                                   and the cache lookups only. Glow's direct image equals the reference's
                                   for the same seed, size and spp, so final = reference direct + this
                                   indirect (glow-compare --add): the sweeps of glow-eval run this way */
    bool no_detail;             /* ignore the bake's lightmap detail (LDET): the lightmap alone */
    glow_render_glossy glossy;  /* GGX layers: 0 = ZH-GGX */
    bool grid_only;             /* shade every surface from the grid, as a dynamic object there would be
                                   (glow_sample_grid 0.1 % of the scene's diagonal off the surface along
                                   its shading normal): measures the light dynamic objects receive */
    const struct glow_render_scene *moved; /* optional, the same mesh: after converging, the light changes to
                                   this scene's lights, environment and emission_scale, the runtime runs
                                   moved_iterations more feedback iterations (one per update by default: as
                                   many frames) and the view shows `moved` (the lag after a light change) */
    uint32_t moved_iterations;
} glow_render_glow_settings;

typedef struct glow_render_result {
    glow_eval_image final, direct, indirect;
    glow_eval_image indirect_near; /* reference with settings->near_split > 0 only (else empty): part of indirect */
    glow_eval_image texel;         /* glow view with a lightmap (not grid_only; else empty): per pixel, the
                                      lightmap texel its first sample that read the lightmap looked up, the
                                      one whose square holds the lookup's UV: R = x + 1, G = y + 1, B = that
                                      texel's cache + 1 (exact in float up to 2^24); 0 0 0 = none (sky, grid,
                                      back faces). glow-compare --texels groups pixels by it (blotches) */
    glow_eval_image specular;      /* scenes with a GGX material only (else empty): part of indirect, the
                                      indirect light the first hit's GGX lobe reflects (reference: the
                                      specular share of its emitter NEE and first bounce; glow view: the
                                      lobe convolved with the caches). docs/glossy.md */
    uint32_t width, height, spp, threads;
    double seconds;           /* the rendering itself (glow: not the solve) */
    uint64_t rays;            /* Embree queries: camera, bounce and shadow rays */
    double mrays_per_s;
    double mean_final[3], mean_direct[3], mean_indirect[3];
    double mean_indirect_near[3]; /* with indirect_near */
    double mean_specular[3];      /* with specular */
    uint64_t nonfinite_samples; /* samples whose direct or indirect radiance was NaN or infinite: left out
                                   of their pixel (counted as 0) so that one cannot poison an image.
                                   0 unless something is wrong; glow-render warns when it is not */
    /* glow view only */
    double solve_seconds;     /* bake load, host, system, updates */
    uint64_t lightmap_lookups, grid_lookups, missed_lookups; /* first hits (per sample) */
} glow_render_result;

/* The reference path tracer. `out` is zeroed first and owns its images (glow_render_result_free). */
glow_result glow_render_reference(const glow_render_scene *scene, const glow_render_settings *settings,
                                  glow_render_result *out, char *message, size_t message_size);

/* Glow's view: loads `bake_path` (which must have been baked from the scene's mesh: the triangle
 * count and every position are checked), lights it with glow_host (exact kind) and the scene's
 * lights, environment and emission_scale, runs glow->bounce_iterations feedback iterations, then
 * renders. `glow` may be NULL (defaults). */
glow_result glow_render_glow(const glow_render_scene *scene, const char *bake_path, const glow_render_settings *settings,
                             const glow_render_glow_settings *glow, glow_render_result *out, char *message,
                             size_t message_size);


/* ---------------------------------------------------------------------------------------- DDISH
 * DDISH-GI (Ikkala et al., "Dynamic Distributed Spherical Harmonics Global Illumination") as a
 * comparator on Glow's own caches (docs/ddish.md): every frame, each of the bake's caches (grid points
 * and lightmap texels, exactly the ones Glow's view reads) path traces `rays` rays of incident radiance
 * (what Glow's caches hold: glow_render_irradiance's estimator, NEE + MIS, Russian roulette, at most
 * `bounces` bounces), projects them to the SH of Glow's outputs (same bands, YCoCg, real orthonormal
 * basis: c_k = Σ L(ω_i) y_k(ω_i) / (pdf N)) and blends them with the history by hysteresis
 * c ← α c + (1 - α) c_new. Grid caches sample the sphere, lightmap caches the hemisphere above their
 * surface (Glow's lightmap caches hold no light from below): stratified in z with a random offset and
 * a golden-ratio azimuth with a random rotation per cache and frame (spherical Fibonacci points, an
 * unbiased stratified estimator). The view then reads these caches exactly as Glow's view reads
 * Glow's (glow_render_glow; the lightmap detail is Glow's own and is left out). */
typedef struct glow_render_ddish_frame {
    uint32_t frame;         /* 0-based */
    bool moved;             /* traced with the moved scene's light (frame >= move_frame) */
    double update_ms;       /* this frame's probe update: tracing, projection, hysteresis, output planes */
    uint64_t rays;          /* Embree queries of this frame's update */
    const glow_render_result *view; /* frames the callback asked for (eval_every): Glow's view of the DDISH
                                       caches as they are after this frame (indirect only), else NULL */
} glow_render_ddish_frame;
typedef glow_result (*glow_render_ddish_frame_fn)(void *user, const glow_render_ddish_frame *frame);

typedef struct glow_render_ddish_settings {
    uint32_t rays;          /* per cache per frame; 0 = 256 (the paper's) */
    uint32_t frames;        /* frames in all; 0 = 300 */
    float hysteresis;       /* α in [0, 1); the paper's 0.99 when `hysteresis_set` is false */
    bool hysteresis_set;
    bool ramp;              /* cold start: frame f (from 0) blends with min(α, f / (f + 1)), a running mean until
                               the history is as long as α's; off (the paper): the history starts at 0 */
    uint32_t bounces;       /* path bounces from the cache at most; 0 = 32 (the paper's) */
    bool no_cull;           /* the paper culls back faces in probe updates (a probe ray passes through them);
                               true: probe rays stop at back faces, which reflect as in the reference */
    const glow_render_scene *moved; /* optional: the same mesh lit by another scene file's lights, environment
                                       and emission from frame move_frame on (the light moves; the lag) */
    uint32_t move_frame;
    uint32_t eval_every;    /* > 0: the callback gets a view after every eval_every-th frame and the last */
    glow_render_ddish_frame_fn on_frame; /* optional, called after every frame; a non-OK return stops the run */
    void *user;
} glow_render_ddish_settings;

typedef struct glow_render_ddish_stats {
    uint32_t caches, grid_caches, lightmap_caches, frames, coeff_count;
    double median_ms, mean_ms, min_ms;  /* per frame update */
    uint64_t rays;                      /* all frames' Embree queries */
    uint32_t threads;
} glow_render_ddish_stats;

/* Runs DDISH on bake_path's caches (the bake checked against the scene's mesh as glow_render_glow does)
 * for ds->frames frames, then renders the view after the last frame into `out` (glow->indirect_only
 * etc. as for glow_render_glow; glow->bounce_iterations is ignored: Glow's solver only provides the
 * outputs' layout). `moved` must be a scene of the same mesh. stats may be NULL. */
glow_result glow_render_ddish(const glow_render_scene *scene, const char *bake_path, const glow_render_settings *settings,
                              const glow_render_glow_settings *glow, const glow_render_ddish_settings *ddish,
                              glow_render_result *out, glow_render_ddish_stats *stats, char *message,
                              size_t message_size);

/* Hysteresis blend of one coefficient array (exposed for the tests): history[i] = a history[i] +
 * (1 - a) fresh[i]. */
void glow_render_ddish_blend(float *history, const float *fresh, size_t count, float a);

void glow_render_result_free(glow_render_result *result);

/* The reference's irradiance at points, for comparisons with Glow's caches (glow-stability): for each
 * point (6 floats: position, normal) E = ∫ L_in cos over the hemisphere of the normal, W/m², RGB, from
 * everything Glow's caches hold: emitters seen from the point and all light reflected by the scene
 * (host lights and sky after at least one reflection), not the host's lights or the sky reaching the
 * point directly. `samples` cosine-distributed paths per point, NEE + MIS as the reference;
 * deterministic per (settings->seed, point index) whatever the threads, so the same seed with the
 * light moved reuses the same random numbers (correlated estimates: frame-to-frame differences carry
 * far less noise than each estimate). `lights` (light_count of them) replace the scene's; NULL = the
 * scene's. `group` > 1: points i and j with i / group == j / group use the same random numbers (pairs
 * of neighbours whose difference is wanted); 0 or 1: every point its own. Uses settings->seed, threads,
 * albedo_scale and max_depth. out_rays (optional): Embree rays. */
glow_result glow_render_irradiance(const glow_render_scene *scene, const glow_scene_light *lights, uint32_t light_count,
                                   const glow_render_settings *settings, const float *points, uint32_t count,
                                   uint32_t samples, uint32_t group, float *out_rgb, uint64_t *out_rays, char *message,
                                   size_t message_size);

/* Writes PREFIX.exr (final), PREFIX_direct.exr, PREFIX_indirect.exr and PREFIX.png (final, display
 * transform of glow_eval_write_png at `exposure`). All or nothing: every file is written under a
 * temporary name first and renamed only when all were written. */
glow_result glow_render_write(const glow_render_result *result, const char *prefix, float exposure, char *message,
                              size_t message_size);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_RENDER_H */
