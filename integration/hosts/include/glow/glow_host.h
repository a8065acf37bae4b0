/*
 * glow_host.h — CPU hosts for the runtime's lighting hook: the direct irradiance of point, spot and
 * sun lights plus a constant sky at the surfels, shadowed either exactly (Embree rays) or the way an
 * engine does it (software-rasterised shadow maps with bias and PCF).
 *
 * Part of glow_host (target glow::host, folder integration/hosts/cpu/; links Embree 3). The lights are the
 * scene description's (glow_scene.h); their units are those of docs/scene-format.md.
 *
 * WHAT IT DOES NOT DO: emission (the runtime adds the bake's material emission; pass the scene's
 * emission_scale to glow_system_set_params), indirect light (the runtime's bounce), or anything on the
 * GPU. It allocates with malloc, not the glow_context allocator (it is host code, not the runtime).
 *
 * THE CONTRACT (glow_lighting_hooks, glow.h): for every surfel, at position p with unit front normal n,
 *   E = Σ_lights V_i · power_i · f_i  +  environment · π · S          (W/m², RGB)
 *     point:  f = max(0, n·l) / d²                   l = (x_light - p)/d, d = |x_light - p|, power = intensity
 *     spot:   f = smoothstep(t) · max(0, n·l) / d²   t = clamp((cos θ - cos outer)/(cos inner - cos outer), 0, 1),
 *             smoothstep(t) = 3t² - 2t³, θ the angle between the axis and p - x_light (inner = outer: a hard edge)
 *     sun:    f = max(0, -n·direction)               power = irradiance
 *   V_i in [0,1] is the light's visibility: exact = one shadow ray towards the light (the sun: along
 *   -direction, unbounded; a point or spot: stopping ε short of it) from p + ε n, nudged up to ε along
 *   the surface into p's own triangle so that surfels lying exactly on an edge where two faces meet
 *   do not start inside the other face's plane (ε = 1e-4 of the scene's bounding-box diagonal);
 *   shadow map = the PCF fraction of depth tests passed. S in [0,1] is the cosine-weighted fraction of
 *   the hemisphere above n from which a ray leaves the scene (the sky is the whole sphere of directions:
 *   a ray that escapes downwards sees sky too), estimated with `sky_rays` deterministic
 *   cosine-distributed rays from the same origin as the shadow rays.
 *
 * COST (Dabrovic Sponza, 66k triangles, 32k surfels, sun + sky, one thread, this repository's 2-core
 * machine): create 24 ms (exact: the BVH) / 86 ms (shadow map: BVH for the sky + one 1024² map, 67 ms);
 * first hook pass 380 ms (S traced, 128 rays per surfel, cached); every later pass 1.9 ms (exact) /
 * 3.3 ms (shadow map). A 2048² sun map renders in 216 ms, 4096² in 814 ms.
 * Footprints (exact kind, 8 points, 2026-11-29, 2 threads): the first pass also traces 8 shadow rays
 * per surfel and light and each footprint's reach; later passes with a moving sun cost about 0.25 ms
 * more than one ray per surfel (the bookkeeping), with a still sun about 0.5 ms less (no rays).
 *
 * USAGE
 *   glow_host_desc hd = glow_host_desc_from_scene(&scene, bake, GLOW_HOST_KIND_SHADOW_MAP);
 *   glow_host *host;   glow_host_create(&hd, &host);
 *   glow_system_create(ctx, &(glow_system_desc){ .bake = bake, .lighting = glow_host_hooks(host) }, &sys);
 *   every frame:       glow_host_set_light(host, 0, &moved_light);   (renders that light's maps now)
 *                      glow_system_update(sys, NULL);                   (the hook runs on the workers)
 *   glow_system_destroy(sys); glow_host_destroy(host);
 *
 * SHADOW MAPS (GLOW_HOST_KIND_SHADOW_MAP): depth maps of every bake triangle, both faces, rendered on
 * the calling thread by glow_host_create, glow_host_set_light and glow_host_set_lights (never inside the
 * hook, so the hook only reads). sun: one orthographic map of shadow_map_size² covering the scene's
 * bounding box; spot: one perspective map of shadow_map_size² covering the outer cone (outer_deg <= 60),
 * or a cube map of cube_map_size² per face for wider spots; point: a cube map. Maps store the distance
 * along the map's view axis; a lookup moves p by normal_offset texels along n, compares against
 * depth - bias with bias = texel · (depth_bias + slope_bias · tan θ) (θ between n and the light,
 * tan clamped to 10, texel = the map's texel footprint at p), and averages pcf_size² texels.
 *
 * FOOTPRINTS (exact kind): a surfel stands for a patch of surface (its area, the fourth float of its
 * position), and a shadow edge that crosses the patch lights part of it. One ray from its centre
 * lights all of it or none; over a sunlit patch a few surfels wide that is the patch's area give or
 * take a surfel (Sponza's sun under the arcades: the indirect block error of surfel seeds 0-3 spread
 * 0.085-0.107 with one ray, 0.090-0.094 with 8 points; docs/results.md). So V of a light is the
 * fraction of K = surfel_samples points of the surfel's disk (radius sqrt(area / pi); K points on a
 * Fibonacci spiral at radii sqrt((k + 1/2) / K), turned by a hash of the surfel's index) that the
 * light reaches. A point that the centre cannot see along the surface (the disk crossing into a wall
 * at a crease) is replaced by the centre, checked once per surfel. The K results are kept per surfel
 * and light, and each hook call re-traces one of them (round robin): a light that keeps still costs
 * no rays once its K points are traced at its place, a moving light one ray per surfel per call, as
 * with K = 1, and its penumbrae follow it over K calls (a box filter over the last K calls; a light
 * switched on, off or recoloured changes at once: the samples hold visibility only). The first call
 * after glow_host_create or glow_host_set_lights traces all K. A host with K > 1 lights the surfels
 * of one system per update (its samples roll per call). glow_host_irradiance (any point) traces one
 * ray from the point.
 *
 * SKY (both kinds): with GLOW_HOST_SKY_TRACED the per-surfel S is traced with Embree on first use (in
 * the hook, by whichever worker lights that surfel first) and cached for the host's life, unless the
 * desc supplies it (sky_visibility). GLOW_HOST_SKY_UNSHADOWED uses S = 1 (no occlusion).
 * glow_host_irradiance (arbitrary points) traces S on every call.
 * An HDR sky (glow_host_set_environment_sh, docs/sky.md) replaces environment · π · S by
 * max(0, Σ_k T_k L_k) per channel: L the sky's radiance SH (l <= 2), T the surfel's sky transfer from the
 * bake (format 1.6, SKYT: no rays at all) or, for an older bake, traced with the same rays as S on first
 * use and cached. For a constant sky the two agree ray for ray.
 *
 * ON ERRORS: functions return a glow_result; the message goes to desc.logger ("glow_host: ..."),
 * with the same code. The hook returns GLOW_ERROR_INVALID_ARGUMENT for a batch outside the bake.
 *
 * ON THREADS: the hook and glow_host_irradiance may run concurrently with each other (any number of
 * threads). glow_host_set_* and glow_host_destroy must not overlap any other call on the host —
 * in particular, not a glow_system_update that uses its hook.
 */
#ifndef GLOW_GLOW_HOST_H
#define GLOW_GLOW_HOST_H

#include "glow/glow.h"
#include "glow/glow_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct glow_host glow_host;

#define GLOW_HOST_SURFEL_SAMPLES_DEFAULT 8u /* glow_host_desc.surfel_samples 0 */
#define GLOW_HOST_SURFEL_SAMPLES_MAX 8u

typedef enum glow_host_kind {
    GLOW_HOST_KIND_DEFAULT = 0, /* = EXACT */
    GLOW_HOST_KIND_EXACT,       /* Embree shadow rays over each surfel's footprint: the reference */
    GLOW_HOST_KIND_SHADOW_MAP,  /* software shadow maps, bias, PCF: what an engine computes */
    GLOW_HOST_KIND_FORCE_U32 = 0x7FFFFFFF
} glow_host_kind;

typedef enum glow_host_sky {
    GLOW_HOST_SKY_DEFAULT = 0,  /* = TRACED */
    GLOW_HOST_SKY_TRACED,       /* cosine-weighted visible-sky fraction per surfel, traced once and cached */
    GLOW_HOST_SKY_UNSHADOWED,   /* E_env = environment · π everywhere (no occlusion) */
    GLOW_HOST_SKY_FORCE_U32 = 0x7FFFFFFF
} glow_host_sky;

typedef struct glow_host_desc {
    glow_host_kind kind;
    const glow_bake *bake;          /* required; borrowed: must outlive the host. Its geometry
                                       (glow_bake_get_geometry) is what shadows */
    const glow_scene_light *lights; /* copied (directions normalised); NULL when light_count is 0 */
    uint32_t light_count;
    float environment[3];           /* constant sky radiance W/(m²·sr); zero = no sky */
    glow_host_sky sky;
    uint32_t sky_rays;              /* rays per surfel for S, 1..65536; 0 = 128. Measured 0.5 m from a 2 x 2 m
                                       wall: S = 0.195 (128 rays), 0.164 (1024), 0.1686 (65536); exact 0.1690 */
    const float *sky_visibility;    /* optional, copied: S for each of the bake's surfels (surfel_count
                                       values in [0,1]); replaces tracing. NULL = trace (or unshadowed) */
    uint32_t sky_visibility_count;  /* must equal the bake's surfel_count when sky_visibility is set */
    /* shadow maps (GLOW_HOST_KIND_SHADOW_MAP only) */
    uint32_t shadow_map_size;       /* sun and spot maps, texels per side, 16..8192; 0 = 1024 */
    uint32_t cube_map_size;         /* point lights and spots wider than 60°, per face, 16..8192; 0 = 512 */
    float depth_bias;               /* constant bias in texels; 0 = 1.0 (pass a tiny value for none) */
    float slope_bias;               /* texels per unit of tan θ; 0 = 2.0 */
    float normal_offset;            /* texels along the normal; 0 = 1.0 */
    uint32_t pcf_size;              /* PCF kernel width in texels: odd, 1..9; 0 = 3 */
    /* \since 0.2, exact kind: points of each surfel's footprint whose shadow rays it averages, 1..8;
     * 0 = GLOW_HOST_SURFEL_SAMPLES_DEFAULT. See FOOTPRINTS above; 1 = one ray from the surfel's centre */
    uint32_t surfel_samples;
    glow_logger logger;             /* zero = silent; must be reentrant */
    /* \since 0.2: other bakes whose geometry also casts shadows here (borrowed, must outlive the host):
     * for a system of a world (glow-bake --system-area), its neighbours, so that the buildings of the
     * systems around it shadow it. Their surfels are not lit. NULL / 0 = none. The epsilon and the
     * stats' triangle_count stay those of `bake`'s own geometry; shadow maps cover all of it. */
    const glow_bake *const *occluders;
    uint32_t occluder_count;
} glow_host_desc;

/**
 * A desc that lights `bake` with `scene`'s lights and environment; everything else zero (defaults).
 * The result borrows scene->lights until glow_host_create has copied them.
 * \threadsafety Any thread. \since 0.1
 */
GLOW_API glow_host_desc glow_host_desc_from_scene(const glow_scene_desc *scene, const glow_bake *bake,
                                                  glow_host_kind kind);

/**
 * Creates a host: reads the bake's geometry, builds the Embree scene (exact kind, and the traced sky)
 * and renders the shadow maps (shadow-map kind).
 *
 * \param desc      see glow_host_desc; must not be NULL.
 * \param out_host  receives the host; NULL on failure.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, a light breaking the schema rules, settings out
 * of range, sky_visibility of the wrong count or with values outside [0,1]); GLOW_ERROR_UNSUPPORTED
 * (unknown light type or kind, Embree failed); GLOW_ERROR_EMPTY_SCENE (the bake carries no
 * triangles); GLOW_ERROR_OUT_OF_MEMORY.
 * \threadsafety Any thread. \ownership Borrows desc->bake for the host's life; copies the rest.
 * \since 0.1
 */
GLOW_API glow_result glow_host_create(const glow_host_desc *desc, glow_host **out_host);

/** Destroys a host (NULL is a no-op). Destroy the systems that use its hook first. \since 0.1 */
GLOW_API void glow_host_destroy(glow_host *host);

/**
 * The hook table for glow_system_desc.lighting: { light_surfels, host }. The batch's surfels must be
 * the bake's (the sky cache is indexed by surfel number). NULL host gives a zero table.
 * \threadsafety Any thread; the hook itself runs concurrently (see ON THREADS). \since 0.1
 */
GLOW_API glow_lighting_hooks glow_host_hooks(glow_host *host);

/**
 * Replaces light `index` (< glow_host_light_count) — move it, recolour it, change its type.
 * Shadow-map hosts re-render that light's maps before returning.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, bad index, a light breaking the rules: the
 * host keeps the old light); GLOW_ERROR_UNSUPPORTED (unknown type); GLOW_ERROR_OUT_OF_MEMORY.
 * \threadsafety Not during an update that uses the hook, nor with other calls on the host.
 * \since 0.1
 */
GLOW_API glow_result glow_host_set_light(glow_host *host, uint32_t index, const glow_scene_light *light);

/**
 * Replaces all lights (count may differ; 0 = none; copied). Validated first: on failure the old set stays.
 * \returns as glow_host_set_light. \threadsafety As glow_host_set_light. \since 0.1
 */
GLOW_API glow_result glow_host_set_lights(glow_host *host, const glow_scene_light *lights, uint32_t count);

/** The number of lights (0 for NULL). \since 0.1 */
GLOW_API uint32_t glow_host_light_count(const glow_host *host);

/** Copies light `index` (direction normalised). \returns GLOW_ERROR_INVALID_ARGUMENT for NULL or a bad
 * index. \since 0.1 */
GLOW_API glow_result glow_host_get_light(const glow_host *host, uint32_t index, glow_scene_light *out_light);

/**
 * Sets the constant sky radiance W/(m²·sr). Cached sky visibility stays valid (it is geometry only).
 * \returns GLOW_ERROR_INVALID_ARGUMENT for NULL, NaN or negative values.
 * \threadsafety As glow_host_set_light. \since 0.1
 */
GLOW_API glow_result glow_host_set_environment(glow_host *host, const float radiance_rgb[3]);

/**
 * Lights the surfels with a sky of any radiance instead of the constant one (docs/sky.md): `sh_rgb` is
 * its radiance W/(m²·sr) as real SH l <= 2, 9 coefficients x RGB, COEFFICIENT-MAJOR (sh_rgb[3 k + c],
 * glow.h GLOW_SKY_SH_FLOATS; glow_sh_sky_constant, glow_sh_rotate_y). The sky term of a surfel is then
 *   E_sky = max(0, Σ_k T_k L_k)        per channel
 * with T its sky transfer: the bake's (format 1.6, SKYT: glow_bake_get_sky_transfer), or, for a bake
 * without it, traced with the same rays as S on first use and cached (the first hook pass costs about
 * what S costs). GLOW_HOST_SKY_UNSHADOWED uses the unoccluded cosine lobe. For a constant sky
 * (glow_sh_sky_constant) this equals environment · π · S within the rays' noise (exactly, ray for ray,
 * when T is traced here or the bake's sky rays are the host's: glow-bake's default 128 = sky_rays'). L2
 * holds no sun: give a sun as a separate shadowed GLOW_SCENE_LIGHT_SUN. With the bake's T (and the traced
 * sky) this call computes every surfel's sky term once (~1 ms for 32k surfels), so the hook only reads
 * it and a turning sky costs one call per change. NULL returns to the constant
 * environment; glow_host_set_environment does too. Lights stay as they are.
 * \returns GLOW_ERROR_INVALID_ARGUMENT for a NULL host or a non-finite coefficient (or one beyond
 * GLOW_MAX_IRRADIANCE); GLOW_ERROR_OUT_OF_MEMORY. \threadsafety As glow_host_set_light. \since 0.2
 */
GLOW_API glow_result glow_host_set_environment_sh(glow_host *host, const float sh_rgb[GLOW_SKY_SH_FLOATS]);

/**
 * The sky transfer T (9 per surfel, out[count * 9]) the hook uses with glow_host_set_environment_sh:
 * the bake's, cached or traced now (as glow_host_sky_visibility). For GPU hooks that light the sky the
 * same way. \returns as glow_host_sky_visibility. \since 0.2
 */
GLOW_API glow_result glow_host_sky_transfer(glow_host *host, const glow_surfel_view *surfels, float *out, uint32_t count);

/**
 * The direct irradiance E (W/m², RGB) the hook would compute at one point: for tests and tools.
 * Traces the sky visibility S afresh (GLOW_HOST_SKY_TRACED) rather than using the per-surfel cache.
 *
 * \param position  m; \param normal  front-face normal (normalised here; must be non-zero).
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, non-finite or zero-length input).
 * \threadsafety Concurrently with the hook and itself. \since 0.1
 */
GLOW_API glow_result glow_host_irradiance(const glow_host *host, const float position[3], const float normal[3],
                                          float out_rgb[3]);

/**
 * The sky visibility S of every surfel: the value the hook uses (cached, supplied in the desc, or traced now
 * for GLOW_HOST_SKY_TRACED and cached; 1 for GLOW_HOST_SKY_UNSHADOWED). For GPU hooks that must light the
 * sky the same way (glow_gl_lights_set_sky_visibility). `surfels` is the system's view
 * (glow_system_get_surfels) of the host's bake; out[surfels->count]. Traces on the calling thread:
 * ~0.4 s for 32k surfels at 128 rays on this repository's machine.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, a count other than the bake's surfel_count).
 * \threadsafety Not concurrently with glow_host_set_* or destroy. \since 0.1
 */
GLOW_API glow_result glow_host_sky_visibility(glow_host *host, const glow_surfel_view *surfels, float *out, uint32_t count);

typedef struct glow_host_stats {
    glow_host_kind kind;           /* resolved (never DEFAULT) */
    uint32_t triangle_count;       /* bake triangles that cast shadows */
    float epsilon;                 /* shadow/sky ray offset along the normal, m */
    uint32_t shadow_map_count;     /* depth maps held (a cube counts 6) */
    uint64_t shadow_map_bytes;
    double shadow_map_ms;          /* wall time of the last map rendering (create / set_light / set_lights) */
    uint32_t sky_cached;           /* surfels whose S is cached (traced or supplied) */
    uint32_t surfel_samples;       /* \since 0.2: footprint points per surfel (exact kind; 1 otherwise) */
    uint64_t shadow_rays;          /* \since 0.2: shadow rays the hook traced for lights (exact kind), in all */
    uint32_t sky_sh;               /* \since 0.2: 1 while the sky is an SH sky (glow_host_set_environment_sh) */
    uint32_t sky_transfer_baked;   /* \since 0.2: 1 when the bake carries the surfels' sky transfer (SKYT) */
} glow_host_stats;

/** Fills `out_stats`. \returns GLOW_ERROR_INVALID_ARGUMENT for NULL. \threadsafety As glow_host_irradiance.
 * \since 0.1 */
GLOW_API glow_result glow_host_get_stats(const glow_host *host, glow_host_stats *out_stats);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_HOST_H */
