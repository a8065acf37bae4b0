/*
 * glow_pc_kit.h — the linker's scene kit: the imported and cleaned scene (triangles, materials,
 * textures), ray queries over it (Embree), texture lookups, the bake side's thread pool and its log.
 *
 * For this repository's tools (glow-render's path tracer and Glow view, glow-stability), which must
 * read a mesh exactly as glow-bake does: the same import, the same cleaning, the same triangles.
 * NOT part of the SDK and not installed (the linker is an offline tool); a documented seam, so that
 * the tools include this header of glow_precompute's include folder and nothing of precompute/src
 * (docs/architecture.md). Everything else of the linker stays in precompute/src/pc_internal.h.
 */
#ifndef GLOW_PC_KIT_H
#define GLOW_PC_KIT_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h"
#include "glow/glow_precompute.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GLOW__PI 3.14159265358979323846

/* ---------------------------------------------------------------- logging (log.c) */
typedef struct glow__log {
    glow_pc_log_fn fn;    /* may be NULL: silent */
    void *user;
    char last_error[1024]; /* the last error message, also passed to fn */
    uint32_t warning_count;
} glow__log;

void glow__errorf(glow__log *log, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void glow__warnf(glow__log *log, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void glow__infof(glow__log *log, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* ---------------------------------------------------------------- threads (pool.c) */
typedef struct glow__pool glow__pool;
/* fn is called with disjoint ranges [begin, end) covering [0, count); worker < thread count. */
typedef void (*glow__range_fn)(void *ctx, uint32_t begin, uint32_t end, uint32_t worker);
glow__pool *glow__pool_create(uint32_t threads); /* 0 = number of online CPUs */
void glow__pool_destroy(glow__pool *pool);
uint32_t glow__pool_threads(const glow__pool *pool);
/* Blocks until done. grain = items per task (0 = automatic). Safe with pool == NULL (serial). */
void glow__parallel_for(glow__pool *pool, uint32_t count, uint32_t grain, glow__range_fn fn, void *ctx);

/* ---------------------------------------------------------------- scene (import.c, builtin.c) */
typedef struct glow__texture {
    int width, height;
    int level_count;          /* box-filtered mip chain, level 0 = full size */
    float *levels[16];        /* linear RGB, width>>k * height>>k * 3 floats each */
    char path[512];
} glow__texture;

typedef struct glow__material {
    char name[64];
    float albedo[3];          /* linear RGB reflectance (Kd / baseColorFactor), clamped to [0,1) */
    float emission[3];        /* emitted radiance W/(m²·sr) (Ke / emissiveFactor*strength) */
    int texture;              /* index into scene->textures, or -1 */
    int emission_texture;     /* emission = emission x this texture (map_Ke / emissiveTexture), or -1 */
} glow__material;

typedef struct glow__scene {
    uint32_t tri_count;
    float (*pos)[3];          /* [3*tri_count] corner positions (unwelded) */
    float (*nrm)[3];          /* [3*tri_count] corner shading normals, unit (generated when absent) */
    float (*uv0)[2];          /* [3*tri_count] material UVs, or NULL */
    float (*uv1)[2];          /* [3*tri_count] lightmap UVs (the mesh's second UV set), or NULL */
    uint32_t *tri_material;   /* [tri_count] */
    uint32_t *tri_source;     /* [tri_count] index of the triangle in the file's order */
    uint32_t material_count;
    glow__material *materials;
    uint32_t texture_count;
    glow__texture *textures;
    float bounds_min[3], bounds_max[3];
    double area;              /* sum of triangle areas */
    /* import statistics */
    uint32_t source_tri_count;
    uint32_t skipped_degenerate;  /* skipped_repeated + skipped_collinear */
    uint32_t skipped_repeated;    /* two corners at the same point (or a repeated index) */
    uint32_t skipped_collinear;   /* height below 2^-20 of the longest edge (import.c) */
    uint32_t skipped_nonfinite;   /* NaN/Inf in a vertex */
    uint32_t skipped_duplicate;   /* coincident duplicate faces (same three positions) */
    uint32_t turned_triangles;    /* turned to agree with their neighbours' winding (no file normals) or
                                     with their vertex normals (file normals) */
    uint32_t textures_missing;
    bool normals_generated;
    char source[512];             /* file path or builtin:NAME */
    /* the file's named objects (a node's name, else its mesh's: OBJ o / g, glTF nodes), for systems
     * named by the user (glow_pc_settings.system_groups); 0 / NULL for builtin scenes */
    uint32_t object_count;
    char (*object_name)[64];      /* [object_count], NUL-terminated (longer names are cut) */
    uint32_t *source_object;      /* [source_tri_count] the object of each triangle of the file */
} glow__scene;

/* Loads `path` (any assimp format) or `builtin:NAME`. On failure logs "PATH: problem". */
glow_result glow__scene_load(const char *path, glow__log *log, glow__scene *out);
glow_result glow__scene_builtin(const char *name, glow__log *log, glow__scene *out);
/* Shared cleaning step used by both: drops degenerate / non-finite / duplicate triangles (counting
 * them), fills bounds and area, generates normals when nrm == NULL. Exposed for tests. */
glow_result glow__scene_finalize(glow__scene *scene, glow__log *log);
void glow__scene_free(glow__scene *scene);
/* Linear RGB albedo texture lookup: bilinear, wrapped, from the mip level matching footprint
 * (the sample's footprint width in UV units, 0 = finest). */
void glow__texture_sample(const glow__texture *tex, float u, float v, float footprint, float out_rgb[3]);

/* ---------------------------------------------------------------- ray tracing (rt.c) */
typedef struct glow__rt glow__rt;
glow_result glow__rt_create(const glow__scene *scene, glow__log *log, glow__rt **out);
/* The rays of one system of a bake split into systems: `scene` is the system's own triangles (hits on
 * them report their index in it), `foreign` (foreign_count x 9 floats, corners packed) the rest of the
 * world's, which occlude every query and report foreign hits (glow__hit.foreign). */
glow_result glow__rt_create_system(const glow__scene *scene, const float *foreign, uint32_t foreign_count,
                                   glow__log *log, glow__rt **out);
void glow__rt_destroy(glow__rt *rt);
/* true when anything blocks the segment org + t*dir, t in (tnear, tfar). dir need not be unit. */
bool glow__rt_occluded(const glow__rt *rt, const float org[3], const float dir[3], float tnear, float tfar);
/* Occlusion for n <= 16 rays sharing an origin; out_occluded[i] = 1 when blocked. */
void glow__rt_occluded16(const glow__rt *rt, const float org[3], const float (*dir)[3], const float *tfar,
                         uint32_t n, float tnear, uint8_t *out_occluded);
typedef struct glow__hit {
    float t;                  /* INFINITY when nothing was hit */
    uint32_t tri;             /* scene triangle index */
    float u, v;               /* barycentrics of corners 1 and 2 */
    bool back_face;           /* ray hit the side opposite the triangle's geometric normal
                                 (geometric normal = (p1-p0)x(p2-p0), CCW front) */
    bool foreign;             /* the hit is on another system's triangle (glow__rt_create_system):
                                 tri is UINT32_MAX, t and back_face are set; it occludes, nothing more */
} glow__hit;
glow__hit glow__rt_intersect(const glow__rt *rt, const float org[3], const float dir[3], float tnear, float tfar);
/* The triangle nearest to p within `radius` whose geometric normal faces along unit n (cosine >= 0.9),
 * among the scene's and the foreign ones (an Embree point query, as the CPU host's safe origin does);
 * false when there is none. out_centroid: its centroid. */
bool glow__rt_nearest_facing(const glow__rt *rt, const float p[3], const float n[3], float radius,
                             float out_centroid[3]);

/* ---------------------------------------------------------------- small vector helpers */
static inline float glow__dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
/* Two unit tangents t, b of the plane with unit normal n (t from n's smallest axis, b = n x t): the
 * frame of lightmap texels' hemisphere rays (caches.c) and of chart projections (charts.c). */
static inline void glow__tangent_frame(const double n[3], double t[3], double b[3]) {
    int ax = 0;
    if (fabs(n[1]) < fabs(n[ax])) ax = 1;
    if (fabs(n[2]) < fabs(n[ax])) ax = 2;
    double a[3] = {0, 0, 0};
    a[ax] = 1.0;
    t[0] = a[1] * n[2] - a[2] * n[1];
    t[1] = a[2] * n[0] - a[0] * n[2];
    t[2] = a[0] * n[1] - a[1] * n[0];
    const double l = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int k = 0; k < 3; ++k) t[k] /= l;
    b[0] = n[1] * t[2] - n[2] * t[1];
    b[1] = n[2] * t[0] - n[0] * t[2];
    b[2] = n[0] * t[1] - n[1] * t[0];
}
static inline void glow__sub(const float a[3], const float b[3], float o[3]) { o[0] = a[0] - b[0]; o[1] = a[1] - b[1]; o[2] = a[2] - b[2]; }
static inline void glow__cross(const float a[3], const float b[3], float o[3]) {
    o[0] = a[1] * b[2] - a[2] * b[1]; o[1] = a[2] * b[0] - a[0] * b[2]; o[2] = a[0] * b[1] - a[1] * b[0];
}


#ifdef __cplusplus
}
#endif
#endif /* GLOW_PC_KIT_H */
