/* render_internal.h — what the glow_render library's files share (not installed). */
#ifndef GLOW_RENDER_INTERNAL_H
#define GLOW_RENDER_INTERNAL_H

#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>

#include "glow_envmap.h"
#include "glow_render.h"
#include "glow/glow_host.h"
#include "render_bsdf.h"
#include "glow/glow_pc_kit.h" /* the linker's scene kit: scene, rays, pool (not precompute/src) */

struct glow_render_scene {
    char path[512];            /* the scene description file, as given */
    glow_scene_desc desc;
    glow_scene_camera camera;  /* resolved */
    glow__scene mesh;
    glow__rt *rt;
    glow__log log;
    float (*ng)[3];            /* [tri_count] unit geometric normal (p1-p0)x(p2-p0) */
    float *tri_area;           /* [tri_count] */
    /* emitters (material emission > 0, front face), sampled by area x luminance */
    uint32_t emitter_count;
    uint32_t *emitter_tri;     /* [emitter_count] */
    double *emitter_cdf;       /* [emitter_count], last = 1 */
    float *light_pdf_area;     /* [tri_count]: luminance / Σ(area x luminance), the area-measure pdf of
                                  next-event estimation on that triangle (0 for non-emitters) */
    glow__render_ggx *ggx;     /* [material_count]: the material's GGX layer (roughness 0 = none), or NULL
                                  when no material has one */
    uint32_t glossy_count;     /* materials with a GGX layer */
    float eps;                 /* ray offset: 1e-4 x bounds diagonal (glow_host's) */
    float diag;
    bool has_envmap;           /* the scene's "environment_map" (desc.environment_map.path non-empty) */
    glow_eval_envmap envmap;   /* loaded with its rotation and scale (glow_envmap.h); zeroed without one */
};

/* Writes "fmt..." into message (truncated; message may be NULL). Returns `code`. */
glow_result glow__render_fail(char *message, size_t message_size, glow_result code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));


/* ---- shared with render_ddish.c (DDISH-GI on Glow's caches) ---- */

/* PCG32 stream (render_trace.c: rng_init / rnd). */
typedef struct glow__rng {
    uint64_t state, inc;
} glow__rng;
/* The stream `stream` of item `index` under `seed` (the pixels' streams are 0 and 1). */
void glow__rng_seed(glow__rng *r, uint64_t seed, uint64_t index, uint32_t stream);
float glow__rng_float(glow__rng *r); /* [0, 1) */

/* Glow's view of a bake: the runtime, its host and outputs, the bake's lightmap UVs. */
typedef struct capture_log {
    pthread_mutex_t lock;
    char first_error[512];
} capture_log;
typedef struct glow_view_ggx { /* per material with a GGX layer */
    bool ok;
    float zh[GLOW_MAX_SH_BANDS];    /* glow_sh_ggx_lobe_factors */
    float phong[GLOW_MAX_SH_BANDS]; /* glow_sh_lobe_factor of the Phong exponent standing in for it */
} glow_view_ggx;
typedef struct glow_view {
    glow_context *ctx;
    glow_bake *bake;
    glow_host *host;
    glow_system *sys;
    const glow_cache_outputs *out; /* what the view reads: the system's outputs, or another solver's (DDISH) */
    bool indirect_only; /* glow_render_glow_settings.indirect_only */
    bool no_detail;     /* glow_render_glow_settings.no_detail */
    bool grid_only;     /* glow_render_glow_settings.grid_only */
    glow_render_glossy glossy; /* glow_render_glow_settings.glossy */
    glow_view_ggx *ggx; /* [material_count] with the scene's GGX layers, else NULL */
    float (*lm_uv)[6]; /* [tri] the bake's lightmap UV per corner, or NULL without a lightmap */
    const uint32_t *lm_page; /* [tri] each triangle's lightmap page (the bake's view), NULL with one page */
} glow_view;
/* Loads the bake (checked against the scene's mesh), creates the host and the system and runs
 * gs->bounce_iterations (0 = 192) feedback iterations. `cl` (initialised lock) must outlive the view. */
glow_result glow__view_create(const glow_render_scene *sc, const char *bake_path, const glow_render_settings *st,
                              const glow_render_glow_settings *gs, capture_log *cl, glow_view *gv, char *message,
                              size_t message_size);
void glow__view_free(glow_view *gv);
/* Renders the scene's camera with gv's caches (check_settings first). */
glow_result glow__view_render(const glow_render_scene *sc, const glow_render_settings *st, const glow_view *gv,
                              glow_render_result *out, char *message, size_t message_size);

/* Incident radiance along rays, as glow_render_irradiance's probes see it (what Glow's caches hold:
 * emitters seen from the point at full weight and everything reflected by the scene, NEE + MIS after
 * the first hit, not the sky seen directly). */
typedef struct glow__tracer glow__tracer;
/* lights: light_count of them replace the scene's (NULL = the scene's). max_depth: path vertices (the
 * probe is vertex 1, its ray's hit vertex 2); 0 = settings->max_depth or 256. */
glow_result glow__tracer_create(const glow_render_scene *sc, const glow_scene_light *lights, uint32_t light_count,
                                const glow_render_settings *st, uint32_t max_depth, glow__tracer **out, char *message,
                                size_t message_size);
void glow__tracer_destroy(glow__tracer *t);
/* Radiance arriving at o from unit direction w (RGB, W/(m²·sr)). cull_back: the probe ray passes through
 * back faces (DDISH's backface culling), up to 64 of them. Adds its Embree queries to *rays. */
void glow__tracer_incoming(const glow__tracer *t, glow__rng *r, const float o[3], const float w[3], bool cull_back,
                           float out[3], uint64_t *rays);

#endif /* GLOW_RENDER_INTERNAL_H */
