/*
 * glow.h — Glow runtime, public C11 API.
 *
 * Glow is real-time global-illumination middleware (precomputed illuminance composition,
 * Jendersie et al. 2016). The linker (`glow-bake`, glow_precompute.h) turns a static scene into
 * a bake file; this runtime loads the bake and (in a later version) turns the host's direct light
 * into multi-bounce indirect light every frame.
 *
 * WHAT IT DOES NOT DO: it never includes GL or Embree, never reads files other than the bake, and
 * keeps no global state.
 *
 * USAGE (this version: bake loading and inspection)
 *   glow_context *ctx; glow_context_create(&(glow_context_desc){ .api_version = GLOW_VERSION }, &ctx);
 *   glow_bake *bake;   if (glow_bake_load_file(ctx, "scene.glow", &bake) != GLOW_OK) ...
 *   glow_bake_info info; glow_bake_get_info(bake, &info);
 *   glow_bake_destroy(bake); glow_context_destroy(ctx);
 *
 * ON MEMORY: every byte goes through the context allocator (zero = malloc/free), at create/load
 * time only. Objects are destroyed with their *_destroy function; destroy(NULL) is a no-op.
 *
 * ON ERRORS: every call that can fail returns a glow_result; detail goes to the context logger
 * with the same code. Bakes are untrusted input: they are fully validated (sizes, CRCs, every
 * index) before anything reads them, in every build.
 *
 * ON THREADS: a glow_context may be used from several threads; a glow_bake is immutable after
 * load and may be read concurrently.
 */
#ifndef GLOW_GLOW_H
#define GLOW_GLOW_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define GLOW_VERSION_MAJOR 0
#define GLOW_VERSION_MINOR 1
#define GLOW_VERSION_PATCH 0
#define GLOW_VERSION (GLOW_VERSION_MAJOR * 10000 + GLOW_VERSION_MINOR * 100 + GLOW_VERSION_PATCH)
#define GLOW_BAKE_FORMAT_MAJOR 1 /* the bake major this runtime reads */

#ifndef GLOW_API
#define GLOW_API
#endif

typedef enum glow_result {
    GLOW_OK = 0,
    GLOW_ERROR_INVALID_ARGUMENT,  /* bad desc / NULL / out of range */
    GLOW_ERROR_INVALID_OPERATION, /* call order or object state */
    GLOW_ERROR_OUT_OF_MEMORY,
    GLOW_ERROR_IO,                /* a file could not be opened, read or written */
    GLOW_ERROR_CORRUPT_DATA,      /* input failed structure checks (generic) */
    GLOW_ERROR_VERSION_MISMATCH,  /* bake major (or API version) not supported */
    GLOW_ERROR_UNSUPPORTED,       /* feature or file format not available */
    GLOW_ERROR_HOST_CALLBACK,     /* a host hook reported failure or returned NaN/Inf */
    GLOW_ERROR_TRUNCATED,         /* bake shorter than its header / sections say */
    GLOW_ERROR_BAD_MAGIC,         /* not a Glow bake */
    GLOW_ERROR_BAD_CHECKSUM,      /* a CRC-32 does not match */
    GLOW_ERROR_OUT_OF_RANGE,      /* an index in the bake points outside its array */
    GLOW_ERROR_EMPTY_SCENE,       /* scene has no usable triangles */
    GLOW_RESULT_FORCE_U32 = 0x7FFFFFFF
} glow_result;

/** Short English description of `result` ("GLOW_ERROR_TRUNCATED: ..."); never NULL.
 * \threadsafety Any thread. \since 0.1 */
GLOW_API const char *glow_result_string(glow_result result);

typedef enum glow_log_level {
    GLOW_LOG_ERROR = 1,
    GLOW_LOG_WARNING,
    GLOW_LOG_INFO,
    GLOW_LOG_DEBUG,
    GLOW_LOG_LEVEL_FORCE_U32 = 0x7FFFFFFF
} glow_log_level;

typedef struct glow_allocator {
    void *(*alloc)(void *user, size_t size, size_t align); /* NULL = aligned malloc */
    void (*free)(void *user, void *ptr);
    void *user;
} glow_allocator;

typedef struct glow_logger {
    void (*log)(void *user, glow_log_level level, glow_result code, const char *message, const char *file,
                int line); /* must be reentrant */
    void *user;
} glow_logger;

typedef struct glow_context_desc {
    uint32_t api_version;     /* must be GLOW_VERSION (major checked) */
    glow_allocator allocator; /* zero = malloc/free */
    glow_logger logger;       /* zero = silent */
} glow_context_desc;

typedef struct glow_context glow_context;
typedef struct glow_bake glow_bake;

/** Creates a context. \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for NULL; GLOW_ERROR_VERSION_MISMATCH
 * when desc->api_version has another major. \threadsafety Any thread. \since 0.1 */
GLOW_API glow_result glow_context_create(const glow_context_desc *desc, glow_context **out_context);
/** Destroys a context (NULL is a no-op). All its bakes must be destroyed first. \since 0.1 */
GLOW_API void glow_context_destroy(glow_context *context);

typedef struct glow_bake_info {
    uint32_t format_major, format_minor;
    uint32_t surfel_count, node_count, level_count, cache_count;
    uint32_t grid_cache_count, lightmap_cache_count;
    uint32_t links_per_cache, sh_bands, link_kind;
    uint32_t material_count, triangle_count;
    uint32_t grid_dims[3];
    uint32_t lightmap_count, lightmap_width, lightmap_height;
    float bounds_min[3], bounds_max[3];
    float surfel_area, grid_spacing, texel_density;
    double scene_area;
    uint64_t file_size;
} glow_bake_info;

/** Reads the format version of a bake in memory without a context (cheap: header only).
 * \returns GLOW_OK, GLOW_ERROR_TRUNCATED (< 64 bytes), GLOW_ERROR_BAD_MAGIC. \since 0.1 */
GLOW_API glow_result glow_bake_peek_version(const void *data, size_t size, uint32_t *out_major,
                                            uint32_t *out_minor);

/** Validates and loads a bake from memory (copied; `data` may be freed after return).
 * Every check runs before anything is used: header, version, sizes, section CRCs, every index.
 * \returns GLOW_OK; GLOW_ERROR_TRUNCATED, GLOW_ERROR_BAD_MAGIC, GLOW_ERROR_VERSION_MISMATCH,
 * GLOW_ERROR_BAD_CHECKSUM, GLOW_ERROR_OUT_OF_RANGE, GLOW_ERROR_CORRUPT_DATA (other structure
 * errors), GLOW_ERROR_OUT_OF_MEMORY. *out_bake is NULL on failure.
 * \threadsafety Any thread. \since 0.1 */
GLOW_API glow_result glow_bake_load(glow_context *context, const void *data, size_t size, glow_bake **out_bake);
/** glow_bake_load on a file's bytes; GLOW_ERROR_IO when it cannot be read. \since 0.1 */
GLOW_API glow_result glow_bake_load_file(glow_context *context, const char *path, glow_bake **out_bake);
/** Fills `out_info`. \since 0.1 */
GLOW_API glow_result glow_bake_get_info(const glow_bake *bake, glow_bake_info *out_info);
/** Destroys a bake (NULL is a no-op). \since 0.1 */
GLOW_API void glow_bake_destroy(glow_bake *bake);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_H */
