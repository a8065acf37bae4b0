/*
 * glow.h — Glow runtime, public C11 API.
 *
 * Glow is real-time global-illumination middleware (precomputed illuminance composition,
 * Jendersie et al. 2016). The linker (`glow-bake`, glow_precompute.h) turns a static scene into
 * a bake file; this runtime loads the bake and turns the host's direct light into multi-bounce
 * indirect light every frame.
 *
 * WHAT IT DOES NOT DO: it never includes GL or Embree, never reads files other than the bake, and
 * keeps no global state.
 *
 * USAGE
 *   glow_context *ctx; glow_context_create(&(glow_context_desc){ .api_version = GLOW_VERSION }, &ctx);
 *   glow_bake *bake;   if (glow_bake_load_file(ctx, "scene.glow", &bake) != GLOW_OK) ...
 *   glow_system *sys;  glow_system_create(ctx, &(glow_system_desc){ .bake = bake,
 *                          .lighting = { my_light_surfels, my_engine } }, &sys);
 *   every frame:       glow_system_update(sys, NULL);          (calls my_light_surfels, in batches)
 *                      const glow_cache_outputs *o = glow_system_outputs(sys);   upload o->lightmap_sh...
 *   shading (C reference of the GLSL): glow_sample_grid / glow_sample_lightmap, then glow_shade_sh.
 *   glow_system_destroy(sys); glow_bake_destroy(bake); glow_context_destroy(ctx);
 *
 * THE FRAME (PIC Fig. 2): (1) surfel lighting — the host's hook returns the direct irradiance at each
 * surfel; Glow adds emission and the previous update's indirect light, multiplies by albedo and area:
 * flux per surfel. (2) pull — flux summed up the surfel hierarchy. (3) cache lighting — every cache
 * sums its links into spherical harmonics of incident radiance (runtime projection, PIC 4.6), luma
 * and chroma (YCoCg) with their own band counts. (4) outputs — grid and lightmap textures.
 *
 * UNITS: linear RGB radiometry. Irradiance in W/m², radiance in W/(m²·sr), flux in W, lengths in
 * the scene's unit ("m"). Cache SH hold *incident radiance* L(ω) = Σ c_lm y_lm(ω) in YCoCg.
 *
 * ON MEMORY: every byte goes through the context allocator (zero = malloc/free), at create/load
 * time only. Objects are destroyed with their *_destroy function; destroy(NULL) is a no-op.
 *
 * ON ERRORS: every call that can fail returns a glow_result; detail goes to the context logger
 * with the same code. Bakes are untrusted input: they are fully validated (sizes, CRCs, every
 * index) before anything reads them, in every build.
 *
 * ON THREADS: a glow_context may be used from several threads; a glow_bake is immutable after
 * load and may be read concurrently. A glow_system is used by one thread at a time: its calls
 * (update, setters, getters, destroy) must not overlap, except that its outputs and getters may be
 * read concurrently between updates. Functions without an object (shading helpers, result strings)
 * are pure and run on any thread. Each function's \threadsafety line says where it differs.
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
/* The bake format this runtime reads and glow-bake writes: a bake of another major is refused
 * (GLOW_ERROR_VERSION_MISMATCH); a newer minor loads, its unknown sections skipped. */
#define GLOW_BAKE_FORMAT_VERSION_MAJOR 1u
#define GLOW_BAKE_FORMAT_VERSION_MINOR 8u /* 1.1: material UVs and texture paths (TUV0, TEXP); 1.2: lightmap detail (LDET);
                                            * 1.3: leaf surfels may differ in area (an adapted density);
                                            * 1.4: systems of a world and their links to neighbours (XREF);
                                            * 1.5: the grid refined near geometry (GFIN);
                                            * 1.6: the sky transfer (SKYT);
                                            * 1.7: lightmap pages, a page per triangle (TPAG);
                                            * 1.8: a system's tree as its neighbours link it (PTRE) */
#define GLOW_BAKE_FORMAT_MAJOR 1 /* the bake major this runtime reads */

/* GLOW_API marks the public functions. A shared build (BUILD_SHARED_LIBS) compiles the libraries with
 * hidden visibility and GLOW_BUILDING_SHARED, so that only these are exported (ELF, GCC and Clang;
 * Windows DLLs are not supported yet). Consumers need no definition. */
#ifndef GLOW_API
#if defined(GLOW_BUILDING_SHARED) && defined(__GNUC__)
#define GLOW_API __attribute__((visibility("default")))
#else
#define GLOW_API
#endif
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

/* Work the runtime hands to the host's job system: call fn(task_data, i, worker) for every i in
 * [0, count) and return when all calls are done. `worker` must be < worker_count and no two calls
 * running at the same time may share a worker number (the runtime keeps per-worker scratch).
 * Any order and split give the same results. For speed, give each thread a contiguous run of the
 * indices, the same run for the same thread from call to call (and let idle threads steal): the
 * stages of an update index the same surfels and caches, so each thread then reads what it wrote
 * itself. The built-in pool does this (a stage read another core's lines at about 235 ns each on a
 * 2-core VM; Sponza moderate 0.93x, docs/benchmarks.md). */
typedef void (*glow_task_fn)(void *task_data, uint32_t index, uint32_t worker);
typedef struct glow_task_hooks {
    void (*parallel_for)(void *user, glow_task_fn fn, void *task_data, uint32_t count);
    uint32_t worker_count; /* with parallel_for: the host's worker count (>= 1);
                              without: threads of the built-in pool, 0 = one per online CPU, 1 = serial */
    void *user;
} glow_task_hooks;

typedef struct glow_context_desc {
    uint32_t api_version;     /* must be GLOW_VERSION (major checked) */
    glow_allocator allocator; /* zero = malloc/free */
    glow_logger logger;       /* zero = silent */
    glow_task_hooks tasks;    /* zero = built-in pool, one thread per online CPU */
} glow_context_desc;

typedef struct glow_context glow_context;
typedef struct glow_bake glow_bake;

/** Creates a context. \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for NULL; GLOW_ERROR_VERSION_MISMATCH
 * when desc->api_version has another major. \threadsafety Any thread. \since 0.1 */
GLOW_API glow_result glow_context_create(const glow_context_desc *desc, glow_context **out_context);
/** Destroys a context (NULL is a no-op). All its bakes and systems must be destroyed first: while any
 * is live the call logs GLOW_ERROR_INVALID_OPERATION and returns without destroying anything (the
 * context stays usable; destroy them, then the context). \threadsafety Not while another thread
 * uses the context. \since 0.1 */
GLOW_API void glow_context_destroy(glow_context *context);

typedef struct glow_bake_info {
    uint32_t format_major, format_minor;
    uint32_t surfel_count, node_count, level_count, cache_count;
    uint32_t grid_cache_count, lightmap_cache_count;
    uint32_t links_per_cache, sh_bands, link_kind;
    uint32_t material_count, triangle_count;
    uint32_t grid_dims[3];
    uint32_t lightmap_count, lightmap_width, lightmap_height; /* count: pages of width x height (0 without a
                                                                 lightmap; > 1 since format 1.7) */
    float bounds_min[3], bounds_max[3];
    float surfel_area, grid_spacing, texel_density; /* surfel_area: nominal, scene_area / surfel_count */
    double scene_area;
    uint64_t file_size;
    /* A system of a world (glow-bake --system-area; format 1.4, XREF): its key (the world manifest's
     * "key", 0 for a bake that is no system), how many systems it depends on (their light reaches its
     * caches through proxy nodes, glow_system_set_neighbour) and how many proxy nodes its links read.
     * \since 0.2 */
    uint64_t system_key;
    uint32_t dependency_count, proxy_count;
} glow_bake_info;

/** The key of dependency `index` of a system's bake (glow_bake_info.dependency_count): the
 * "key" of the system in the world manifest whose bake glow_system_set_neighbour must be given.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for NULL or an index out of range.
 * \threadsafety Any thread. \since 0.2 */
GLOW_API glow_result glow_bake_get_dependency(const glow_bake *bake, uint32_t index, uint64_t *out_key);

/** Reads the format version of a bake in memory without a context (cheap: header only).
 * \returns GLOW_OK, GLOW_ERROR_TRUNCATED (< 64 bytes), GLOW_ERROR_BAD_MAGIC. \threadsafety Any thread.
 * \since 0.1 */
GLOW_API glow_result glow_bake_peek_version(const void *data, size_t size, uint32_t *out_major,
                                            uint32_t *out_minor);

/** Validates and loads a bake from memory (copied; `data` may be freed after return).
 * Every check runs before anything is used: header, version, sizes, section CRCs, every index.
 * \returns GLOW_OK; GLOW_ERROR_TRUNCATED, GLOW_ERROR_BAD_MAGIC, GLOW_ERROR_VERSION_MISMATCH,
 * GLOW_ERROR_BAD_CHECKSUM, GLOW_ERROR_OUT_OF_RANGE, GLOW_ERROR_CORRUPT_DATA (other structure
 * errors), GLOW_ERROR_OUT_OF_MEMORY. *out_bake is NULL on failure.
 * \threadsafety Any thread. \since 0.1 */
GLOW_API glow_result glow_bake_load(glow_context *context, const void *data, size_t size, glow_bake **out_bake);
/** glow_bake_load on a file's bytes; GLOW_ERROR_IO when it cannot be read. \threadsafety Any thread.
 * \since 0.1 */
GLOW_API glow_result glow_bake_load_file(glow_context *context, const char *path, glow_bake **out_bake);
/** Fills `out_info`. \threadsafety Any thread (the bake is immutable). \since 0.1 */
GLOW_API glow_result glow_bake_get_info(const glow_bake *bake, glow_bake_info *out_info);
/** Destroys a bake (NULL is a no-op). A bake still used by a system is not destroyed: the call logs
 * GLOW_ERROR_INVALID_OPERATION and returns (destroy the systems first). \threadsafety Not while
 * another thread uses the bake. \since 0.1 */
GLOW_API void glow_bake_destroy(glow_bake *bake);

/* The static geometry the bake was made from (the triangles the linker kept), for hosts that need
 * it: shadow maps, ray-traced reference lighting, lightmap UVs. Views into the bake, valid until
 * it is destroyed. */
typedef struct glow_bake_geometry {
    uint32_t triangle_count;
    uint32_t stride;            /* bytes between consecutive triangles in every array below */
    const float *positions;     /* per triangle: 9 floats, corners p0 p1 p2 (front face counter-clockwise) */
    const uint16_t *lightmap_uv;/* per triangle: 6 unorm16 (u0 v0 u1 v1 u2 v2) of [0,1] */
    const uint32_t *materials;  /* per triangle: material index */
    const float *material_uv;   /* NOT strided: [triangle_count * 6] floats, the mesh's first UV set per
                                   corner (u0 v0 u1 v1 u2 v2; v = 1 is a texture's top row), or NULL
                                   (a mesh without UVs, or a bake before format 1.1) */
    const uint32_t *lightmap_page; /* \since 0.2. NOT strided: [triangle_count] each triangle's lightmap
                                   page (its lightmap_uv are in [0,1] within it; glow_sample_lightmap_page),
                                   or NULL when the lightmap has one page (page 0 for all) */
} glow_bake_geometry;
/** Fills `out_geometry` (triangle_count 0 when the bake carries no geometry). \threadsafety Any
 * thread. \since 0.1 */
GLOW_API glow_result glow_bake_get_geometry(const glow_bake *bake, glow_bake_geometry *out_geometry);

/* The sky transfer (bake format 1.6, section SKYT; docs/sky.md): what a host needs to light the surfels
 * with a sky of any radiance, given as RGB l <= 2 SH (glow_sh_sky_constant, glow_sh_rotate_y), without a
 * re-bake: per surfel (SURF order, the order of glow_surfel_batch) the transfer vector
 *     T_k = ∫ V(ω) max(0, n·ω) y_k(ω) dω        (k < 9, glow_sh_eval's basis)
 * so that its sky irradiance is max(0, Σ_k T_k L_k) (glow_sh_sky_irradiance; W/m² for L in
 * W/(m²·sr)), and per grid cache (the first grid_cache_count caches) the visibility SH
 *     V_k = ∫ V(ω) y_k(ω) dω
 * so that the radiance SH of the sky it sees is V ⊗ L (glow_sh_sky_visible). V(ω) = 1 where a ray escapes
 * the scene. Views into the bake, valid until it is destroyed. \since 0.2 */
#define GLOW_SKY_SH_FLOATS 27 /* a sky's radiance SH: 9 coefficients x RGB, coefficient-major (see "Sky SH" below) */
typedef struct glow_bake_sky_transfer {
    uint32_t surfel_count;          /* the bake's surfels, or 0 when the bake has no SKYT */
    const float *surfel_transfer;   /* [surfel_count][9] T, or NULL */
    uint32_t grid_cache_count;      /* the bake's grid caches (0 without SKYT) */
    const float *grid_visibility;   /* [grid_cache_count][9] V, or NULL */
    uint32_t rays;                  /* rays per surfel the linker traced (0 without SKYT) */
    uint32_t grid_rays;             /* rays per grid cache (0 without SKYT) */
} glow_bake_sky_transfer;
/** Fills `out` (all 0 / NULL for a bake without the sky transfer: glow-bake --no-sky, or before format
 * 1.6). \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for NULL. \threadsafety Any thread. \since 0.2 */
GLOW_API glow_result glow_bake_get_sky_transfer(const glow_bake *bake, glow_bake_sky_transfer *out);

/* glow_bake_info.link_kind bits: how the bake's links are encoded. \since 0.1 */
typedef enum glow_link_kind_bits {
    GLOW_LINK_KIND_RUNTIME_PROJECTION = 1, /* always: cones projected to SH at run time (PIC 4.6) */
    GLOW_LINK_KIND_FULL_SH = 2,            /* also full-SH links (glow-bake --sh-links; GLOW_LINK_MODE_SH) */
    GLOW_LINK_KIND_SUBSETS = 4,            /* links carry their node's visible-part weights (link subsets) */
    GLOW_LINK_KIND_GRADIENT = 8            /* links carry the gradient of their response across their node
                                              (link gradients; LSUB, never with SUBSETS; CPU runtime and GL backend).
                                              \since 0.2 */
} glow_link_kind_bits;

/* What a cache is: a grid point (dynamic objects, the whole sphere) or a lightmap texel's (the
 * hemisphere above its surface). \since 0.1 */
typedef enum glow_cache_kind { GLOW_CACHE_KIND_GRID = 1, GLOW_CACHE_KIND_LIGHTMAP = 2 } glow_cache_kind;
typedef struct glow_cache_info {
    float position[3]; /* m */
    float normal[3];   /* lightmap caches: the surface normal (unit); grid caches: 0 */
    uint32_t kind;     /* glow_cache_kind */
    uint32_t texel;    /* grid: cell index (x fastest); lightmap: page * lightmap_width * lightmap_height +
                          y * lightmap_width + x (page 0 with one page) */
} glow_cache_info;
/** Copies caches [first, first + count) (grid caches first, then lightmap caches; the order of the
 * outputs' cache indices), e.g. for debug views or to place effects at the caches.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for NULL or a range outside the bake's caches.
 * \threadsafety Any thread; the bake is immutable. \since 0.1 */
GLOW_API glow_result glow_bake_get_caches(const glow_bake *bake, uint32_t first, uint32_t count,
                                          glow_cache_info *out_caches);

/* One section of a bake file (docs/bake-format.md). */
typedef struct glow_bake_section_info {
    char fourcc[5];   /* NUL-terminated, e.g. "LINK"; non-printable bytes as '?' */
    uint32_t version; /* the section's layout version */
    uint64_t offset;  /* from the start of the file */
    uint64_t size;    /* payload bytes */
    uint32_t crc32;   /* CRC-32 (zlib's) of the payload, as the file states it (verified at load) */
} glow_bake_section_info;
/** The bake's section table in file order (unknown sections included). Writes at most `capacity`
 * entries to out_sections (may be NULL with capacity 0) and the table's length to *out_count.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for a NULL bake or out_count.
 * \threadsafety Any thread. \since 0.1 */
GLOW_API glow_result glow_bake_get_sections(const glow_bake *bake, glow_bake_section_info *out_sections,
                                            uint32_t capacity, uint32_t *out_count);

typedef struct glow_material_info {
    char name[32];
    float albedo[3];   /* linear RGB (a texture, when flagged, is folded into the surfels) */
    float emission[3]; /* emitted radiance W/(m²·sr), front face only */
    uint32_t has_albedo_texture;
    char albedo_texture[512]; /* the albedo texture's path as the linker opened it (for drawing the scene
                                 textured: sample it at glow_bake_geometry.material_uv); "" when there is
                                 none, it was embedded in the mesh, or the bake predates format 1.1 */
} glow_material_info;
/** Material `index` of the bake. \returns GLOW_ERROR_INVALID_ARGUMENT for NULL or a bad index.
 * \threadsafety Any thread. \since 0.1 */
GLOW_API glow_result glow_bake_get_material(const glow_bake *bake, uint32_t index, glow_material_info *out_material);


/* =============================================================================== system
 * A glow_system is the per-bake solver state: surfel flux, node radiance, cache SH, outputs.
 * Everything it needs is allocated in glow_system_create; glow_system_update allocates nothing. */
typedef struct glow_system glow_system;

#define GLOW_MAX_SH_BANDS 8u /* l = 1..8 bands, l*l coefficients */
/* Input limits. Finite values this large would overflow float sums inside an update that returns
 * GLOW_OK; they are refused like NaN. The sun at noon gives ~1e3 W/m², so the limits are
 * far from any lighting a scene needs. */
#define GLOW_MAX_IRRADIANCE 1e12f  /* per channel: light_surfels and glow_system_set_surfel_irradiance (W/m²),
                                      glow_system_set_surfel_emission (W/(m²·sr)) */
#define GLOW_MAX_SCALE 1e6f        /* emission_scale (params and materials), albedo_scale */

/* What the host's CPU hook sees: a contiguous range of the bake's surfels. */
typedef struct glow_surfel_batch {
    uint32_t first, count;  /* surfels [first, first + count) */
    const float *positions; /* count x {x, y, z, area}: centre in m, area in m² (stride 16 bytes) */
    const float *normals;   /* count x {x, y, z, 0}: unit front-face normal (stride 16 bytes) */
    const uint32_t *materials; /* count: the bake's material index of each surfel */
} glow_surfel_batch;

/* The host's CPU lighting hook (PIC step 2).
 * light_surfels writes, for each surfel of the batch, the DIRECT IRRADIANCE E (W/m², RGB, 3 floats
 * per surfel, out_irradiance_rgb[3*i + c]) arriving at the surfel's front face from the host's lights,
 * shadowed the way the host shadows (shadow maps, rays...): E = Σ_lights L_i cos θ_i dω_i. Not radiance,
 * not multiplied by albedo, without emission and without indirect light: Glow adds those.
 * Return GLOW_OK, or any other code to abort the update (glow_system_update then returns
 * GLOW_ERROR_HOST_CALLBACK and keeps the previous outputs). NaN, Inf or values above
 * GLOW_MAX_IRRADIANCE abort the update the same way; negative values are clamped to 0 with a warning.
 * \threadsafety Called from the runtime's workers (or the host's parallel_for), several batches at
 * once; `worker` is the calling worker's index (< worker_count), for per-worker scratch. */
typedef struct glow_lighting_hooks {
    glow_result (*light_surfels)(void *user, const glow_surfel_batch *batch, float *out_irradiance_rgb,
                                 uint32_t worker);
    void *user; /* borrowed: must outlive the system */
} glow_lighting_hooks;

/* How the solver holds the bake's links (a speed / memory trade; both give the same results within
 * the half-float precision of the expanded weights, about 1e-3 relative per link). */
typedef enum glow_link_mode {
    GLOW_LINK_MODE_DEFAULT = 0,  /* = COMPACT */
    GLOW_LINK_MODE_COMPACT,      /* read the bake's 8-byte links and project them every update (runtime
                                    projection, PIC 4.6): no extra memory */
    GLOW_LINK_MODE_EXPANDED,     /* at create, each link's cone factors x SH basis (k_l(cos a) y_lm(dir),
                                    luma² IEEE halves) are computed once, so an update does luma² + 2
                                    chroma² multiply-adds per link and no decoding. Memory: (4 + 2 luma²)
                                    bytes per link (22 at l = 3: +29 MB for 1.37 M links). Not faster
                                    where the node-radiance gathers bound the update (docs/benchmarks.md);
                                    for CPUs with slow FMA and fast gathers */
    GLOW_LINK_MODE_SH,           /* the bake's full-SH links (glow-bake --sh-links, PIC Eq. 2): each link's
                                    SH coefficients were projected at bake time from the visible leaf
                                    surfels (one sample per leaf) instead of a cone, read in place (no
                                    extra memory here; the bake is larger by 2 l² bytes per link). The
                                    comparison point for runtime projection ("RTP vs SH links" in
                                    docs/results.md). Needs sh_bands_luma <= the bake's bands (else
                                    GLOW_ERROR_INVALID_ARGUMENT) and a bake with them (else
                                    GLOW_ERROR_UNSUPPORTED). The non-divergence cap is still computed from
                                    the cone links */
    GLOW_LINK_MODE_FORCE_U32 = 0x7FFFFFFF
} glow_link_mode;

/* The format of a system's output planes (glow_cache_outputs' grid and lightmap planes), which a host
 * uploads to textures. The cache rows (cache_sh), the maps and every glow_sample_* function are the same
 * in each: they read cache_sh, not the planes. \since 0.2 */
typedef enum glow_output_planes {
    GLOW_OUTPUT_PLANES_F32 = 0,  /* 32-bit floats, one plane per coefficient: grid_sh and lightmap_sh */
    GLOW_OUTPUT_PLANES_RGBA16F,  /* IEEE halves packed 4 coefficients a texel, in the layout of the textures
                                    glow_shading.glsl reads (grid_rgba16f, lightmap_rgba16f, below): one
                                    glTextureSubImage3D(..., GL_RGBA, GL_HALF_FLOAT, ...) each into an RGBA16F
                                    3D texture and 2D array, no conversion or repacking. Rounded to nearest
                                    even, values beyond +-65504 clamped to it; grid_sh and lightmap_sh are
                                    NULL. About half the float planes' bytes (27 coefficients: 28 halves,
                                    56 bytes a texel, against 108); 2^-11 relative rounding, far below the
                                    solver's error against the referee */
    GLOW_OUTPUT_PLANES_NONE,     /* no grid or lightmap planes (their pointers NULL): for hosts that read
                                    cache_sh through the maps (glow_sample_*) or upload the cache rows and
                                    maps themselves; the output stage then writes only the lightmap detail */
    GLOW_OUTPUT_PLANES_FORCE_U32 = 0x7FFFFFFF
} glow_output_planes;

typedef struct glow_system_desc {
    const glow_bake *bake;        /* required; borrowed: must outlive the system */
    glow_lighting_hooks lighting; /* NULL light_surfels = the host pushes irradiance with
                                     glow_system_set_surfel_irradiance (zero until it does) */
    uint32_t sh_bands_luma;       /* 1..GLOW_MAX_SH_BANDS; 0 = the bake's sh_bands */
    uint32_t sh_bands_chroma;     /* 1..sh_bands_luma; 0 = same as luma */
    uint32_t surfel_batch_size;   /* surfels per hook call; 0 = 1024 */
    const char *label;            /* copied; names the system in log messages; NULL = "system" */
    glow_link_mode link_mode;     /* 0 = GLOW_LINK_MODE_COMPACT */
    glow_output_planes output_planes; /* 0 = GLOW_OUTPUT_PLANES_F32 \since 0.2 */
} glow_system_desc;

/** Creates a solver for `desc->bake`: allocates every buffer, decodes nothing per frame.
 * Outputs start at zero (no light) until the first update.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, band counts out of range, a bake without
 * runtime-projection links, an unknown link_mode or output_planes); GLOW_ERROR_UNSUPPORTED (GLOW_LINK_MODE_SH with a
 * bake without full-SH links); GLOW_ERROR_OUT_OF_MEMORY. *out_system is NULL on failure.
 * \threadsafety Any thread; several systems may share one bake. \since 0.1 */
GLOW_API glow_result glow_system_create(glow_context *context, const glow_system_desc *desc,
                                        glow_system **out_system);
/** Destroys a system (NULL is a no-op). \threadsafety Not during an update of the system (refused
 * and logged, as the setters). \since 0.1 */
GLOW_API void glow_system_destroy(glow_system *system);

/** Pushes direct irradiance (W/m², RGB, as the hook would return it) for surfels
 * [first, first + count); kept until pushed again. For hosts that compute surfel lighting elsewhere
 * (for example on the GPU, read back). Used by updates when the system has no light_surfels hook.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, range outside the bake's surfels);
 * GLOW_ERROR_HOST_CALLBACK when a value is NaN, Inf or above GLOW_MAX_IRRADIANCE (nothing is
 * stored); negative values are
 * clamped to 0 with a warning. \threadsafety Not concurrently with other calls on the system. \since 0.1 */
GLOW_API glow_result glow_system_set_surfel_irradiance(glow_system *system, uint32_t first, uint32_t count,
                                                       const float *irradiance_rgb);

/** Overrides the emitted radiance (W/(m²·sr), RGB, before the emission scales) of surfels
 * [first, first + count), e.g. from an animated emissive texture the host samples at the surfels
 * (glow_system_get_surfels gives their positions and triangles). NULL restores the bake's emission for
 * the range. \returns as glow_system_set_surfel_irradiance. \threadsafety As
 * glow_system_set_surfel_irradiance. \since 0.1 */
GLOW_API glow_result glow_system_set_surfel_emission(glow_system *system, uint32_t first, uint32_t count,
                                                     const float *radiance_rgb);

/** Sets the emitted radiance of every surfel of `material` from an RGB texture the host owns and
 * animates (a video screen, a flickering sign): W/(m²·sr) = scale x the texture, sampled bilinearly
 * (wrapping) at each surfel's material UV (glow_surfel_view.uv0). `rgb` is width x height x 3 floats,
 * rows from the top. The sample is one point per surfel, so detail finer than the surfels averages out
 * only by chance: filter the texture to about the surfel spacing first (sqrt of the bake's surfel area)
 * for a steady result. NULL rgb restores the bake's emission for the material's surfels.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL system, a bad material, width or height 0,
 * scale negative or not finite); GLOW_ERROR_UNSUPPORTED when the bake has no material UVs;
 * GLOW_ERROR_HOST_CALLBACK when a sampled value is NaN, Inf or above GLOW_MAX_IRRADIANCE (nothing is
 * stored). Allocates nothing. \threadsafety As glow_system_set_surfel_emission. \since 0.1 */
GLOW_API glow_result glow_system_set_emission_texture(glow_system *system, uint32_t material, const float *rgb,
                                                      uint32_t width, uint32_t height, float scale);

/** Read-only view of the bake's surfels in the layout the hook receives (for hosts that push). */
typedef struct glow_surfel_view {
    uint32_t count;
    const float *positions;    /* count x {x, y, z, area} */
    const float *normals;      /* count x {x, y, z, 0} */
    const uint32_t *materials; /* count */
    const uint32_t *triangles; /* count: the bake triangle (GEOM) each surfel lies on */
    const float *uv0;          /* count x {u, v}: the material UV at each surfel (interpolated on its
                                  triangle; v = 1 is a texture's top row), or NULL when the bake has no
                                  material UVs (format 1.0, or a mesh without UVs). \since 0.1 */
} glow_surfel_view;
/** Fills `out_view`; valid until the system is destroyed. \threadsafety Any thread; the view is
 * immutable. \since 0.1 */
GLOW_API glow_result glow_system_get_surfels(const glow_system *system, glow_surfel_view *out_view);

/* Lighting-artist controls. All take effect at the next update and persist.
 * Departure from zero-is-default (STYLE.md): the two scales keep 0 as a setting, because artists use
 * it (bounce off, emission off) and reading 0 as 1 would silently change valid code; counts take 0 as
 * their default. GLOW_SYSTEM_PARAMS_INIT is the defaults, for C and C++ initialisers:
 *     glow_system_params p = GLOW_SYSTEM_PARAMS_INIT;  p.emission_scale = 2.0f; */
typedef struct glow_system_params {
    float bounce_intensity;  /* indirect light fed back into surfel lighting: 0 = single bounce,
                                1 = physical (default); clamped to [0, 1] */
    float emission_scale;    /* multiplies all emission (default 1); 0 .. GLOW_MAX_SCALE */
    uint32_t bounce_iterations; /* feedback iterations per update, 0 = the default, 1: each one lights
                                   the surfels again with the previous iteration's caches */
} glow_system_params;
/** The defaults of glow_system_params (what a new system starts with). \since 0.1 */
#define GLOW_SYSTEM_PARAMS_INIT {1.0f, 1.0f, 1u}
/** Sets the artist controls. \returns GLOW_ERROR_INVALID_ARGUMENT for NaN, negative values, an
 * emission_scale above GLOW_MAX_SCALE or bounce_iterations above 64 (nothing changes).
 * \threadsafety Not concurrently with other calls on the system. \since 0.1 */
GLOW_API glow_result glow_system_set_params(glow_system *system, const glow_system_params *params);
/** Adds a sky to the grid caches (dynamic objects receive it; docs/sky.md): from the next update on,
 * each grid cache's radiance SH (cache_sh and grid_sh, in YCoCg) also holds V ⊗ L, the part of the sky
 * `sh_rgb` (RGB l <= 2 SH, coefficient-major, glow.h GLOW_SKY_SH_FLOATS) that the cache sees
 * (glow_sh_sky_visible with the bake's grid visibility SH; bands above 2 get nothing, chroma only up to
 * sh_bands_chroma). Lightmap caches are not changed (the surfels, and through them the static surfaces,
 * get the sky from the host: glow_host_set_environment_sh), and the sky is not fed back into the
 * surfels' bounce (the host lights them with it already). Computed here (9 x 27 multiply-adds per grid
 * cache); an update then costs two copies of the grid caches' rows. The first call allocates two copies
 * of the grid caches' SH (8 · grid caches · coeff_count bytes). NULL removes it. Needs a bake with
 * the sky transfer (format 1.6 SKYT). For a sky with a sun, give the sun as a light as well: L2 holds
 * no peak. The CPU solver's outputs only: the GL backend has its own, glow_gl_system_set_sky (glow_gl.h).
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL system, a non-finite coefficient or one beyond
 * GLOW_MAX_IRRADIANCE); GLOW_ERROR_UNSUPPORTED (a bake without SKYT); GLOW_ERROR_OUT_OF_MEMORY;
 * GLOW_ERROR_INVALID_OPERATION during an update. \threadsafety As glow_system_set_params. \since 0.2 */
GLOW_API glow_result glow_system_set_sky(glow_system *system, const float sh_rgb[GLOW_SKY_SH_FLOATS]);
/** The artist controls in effect. \threadsafety Between updates, from any thread. \since 0.1 */
GLOW_API glow_result glow_system_get_params(const glow_system *system, glow_system_params *out_params);

/** Per-material scales (index into the bake's materials): emission_scale multiplies the material's
 * emission (runtime-switchable area lights), albedo_scale its albedo (RGB). The effective albedo is
 * clamped to [0, 0.999] so multi-bounce stays convergent. Defaults 1.
 * \returns GLOW_ERROR_INVALID_ARGUMENT for a bad index, NaN, negative values or values above
 * GLOW_MAX_SCALE. \threadsafety Not concurrently with other calls on the system. \since 0.1 */
GLOW_API glow_result glow_system_set_material(glow_system *system, uint32_t material, const float emission_scale[3],
                                              const float albedo_scale[3]);

/* Update flags, OR-ed into glow_update_desc.flags (a uint32_t, so that C++ needs no casts). They were
 * macros before 0.1's release; the names and values are unchanged. */
typedef enum glow_update_flags {
    GLOW_UPDATE_FLAG_NONE = 0,
    GLOW_UPDATE_FLAG_RESET_BOUNCE = 1,  /* forget the indirect light of previous updates first */
    GLOW_UPDATE_FLAG_KEEP_LIGHTING = 2, /* the host's lights did not change since the last call: reuse the
                                           last direct irradiance (do not call the hook), except for the
                                           batches a time budget left unlit since that call, which are
                                           still lit (under the budget) */
    GLOW_UPDATE_FLAGS_FORCE_U32 = 0x7FFFFFFF
} glow_update_flags;

/* Caches are scheduled in groups of this many neighbours (bake order), the unit of a budget. */
#define GLOW_BUDGET_GROUP 16u

/* Zero everywhere = no budget: every cache is gathered every update (bit-identical to 0.1).
 * A budget gathers some groups of GLOW_BUDGET_GROUP caches and keeps the others' last values (the
 * outputs always show every cache). Which: the stalest first, each group's staleness (updates since it
 * was last gathered, + 1) weighted by 1 + 4 f, f = max over the focus points of 1 / (1 + d² / r²), d
 * the distance to the group's centre; ties by group index, so a caches budget is deterministic
 * (a time budget depends on the measured times). See docs/runtime.md, "Budgets". */
typedef struct glow_update_desc {
    uint32_t flags;          /* glow_update_flags, OR-ed; 0 = none */
    uint32_t max_caches;     /* at most this many caches gathered (rounded up to whole groups); 0 = no cap */
    float budget_ms;         /* aim the whole update at this many ms: the caches that fit after the other
                                stages, from the last updates' times (the first update gathers all); and
                                when lighting every surfel would take more than half of what the budget
                                leaves, the host hook's batches that fit in that half, by the same priority
                                (the others keep their last direct light: surfels_skipped_budget); 0 = none.
                                With max_caches too, the smaller wins */
    const float *focus;      /* focus_count points (x, y, z: the camera, points of interest), or NULL */
    uint32_t focus_count;
    float focus_radius;      /* r above, m; 0 = a tenth of the bake's bounds diagonal */
    float converged_epsilon; /* > 0: skip groups whose last gather changed their caches by less than this
                                (relative, luma) while the node radiance they read drifted by less than this
                                since (relative, summed over updates): converged light costs nothing until
                                it changes. 0 = off */
} glow_update_desc;

/* Wall-clock milliseconds of the last successful update, per stage (summed over bounce iterations). */
typedef struct glow_update_stats {
    double surfel_lighting_ms; /* host hook (or pushed values) + emission + feedback -> flux */
    double host_ms;            /* the part of surfel_lighting_ms spent in the host's hook */
    double pull_ms;
    double cache_lighting_ms;
    double output_ms;          /* grid and lightmap textures, seam/gutter copies, the lightmap detail */
    double total_ms;
    uint64_t links;            /* links gathered (caches gathered * links_per_cache * iterations) */
    uint32_t caches_gathered;  /* caches gathered in the last update (per bounce iteration) */
    uint32_t caches_skipped_budget;    /* ... left at their last value by the budget */
    uint32_t caches_skipped_converged; /* ... skipped as converged (converged_epsilon) */
    uint64_t updates;          /* successful updates since create */
    uint64_t memory_bytes;     /* everything the system allocated (the bake not included) */
    uint32_t link_mode;        /* the glow_link_mode in use (resolved, never DEFAULT) */
    const char *kernel;        /* the cache-lighting kernel's instruction set: "avx512f", "avx2+fma+f16c", "generic" */
    /* \since 0.2: 1 when the last update skipped its output stage because nothing the outputs read had
     * changed since they were last written (a budgeted update that gathered no cache, with the node
     * radiance bit for bit the same): the outputs are those of the update before, and output_ms 0 */
    uint32_t outputs_skipped;
    /* \since 0.2: surfels whose direct light the last update did not ask the hook for (a time budget
     * lights the hook's batches by priority when lighting them all would take more than half of what the
     * budget leaves: docs/runtime.md, "Budgets"); they keep the light of their last call */
    uint32_t surfels_skipped_budget;
} glow_update_stats;

/** Attaches `neighbour` as dependency `dependency` of `system` (glow_bake_info.dependency_count; a
 * system of a world, glow-bake --system-area): the links of `system` that read its neighbours' nodes
 * (proxy nodes) read that system's node radiance as its last update left it, at each of this
 * system's bounce iterations. So light crosses systems with one update of lag per crossing, and
 * updating the world's systems one after another each frame converges like the bounces within a
 * system. NULL detaches: the proxies keep the radiance they last read (the fallback for a neighbour
 * that is streamed out: its last known radiance; zero for one never attached).
 * `neighbour` must be the system baked as that dependency: its bake's system_key must equal
 * glow_bake_get_dependency(bake of `system`, dependency). A system attached as a neighbour is not
 * destroyed (glow_system_destroy logs GLOW_ERROR_INVALID_OPERATION) until every system that reads it
 * has detached it or is destroyed.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL system, dependency out of range, a neighbour
 * with another key or the system itself); GLOW_ERROR_OUT_OF_RANGE (a neighbour with fewer nodes than
 * the proxies read: a forged bake); GLOW_ERROR_INVALID_OPERATION during an update of `system`.
 * \threadsafety Not while `system` or `neighbour` updates: update the systems of a world one after
 * another (each update uses every worker of the context). \since 0.2 */
GLOW_API glow_result glow_system_set_neighbour(glow_system *system, uint32_t dependency, glow_system *neighbour);

/** One frame: surfel lighting -> pull -> cache lighting -> outputs (x bounce_iterations).
 * `desc` may be NULL. Allocates nothing.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL system, unknown flags);
 * GLOW_ERROR_HOST_CALLBACK when the hook failed or returned NaN/Inf: the outputs and the bounce
 * state stay those of the last good update, and the system remains usable;
 * GLOW_ERROR_INVALID_OPERATION when an update of this system is already running (called from its
 * own lighting hook, or from a second thread): refused and logged, the running update unharmed.
 * The setters (glow_system_set_*) and glow_system_destroy refuse the same way while an update runs.
 * \threadsafety One thread at a time per system (different systems may update concurrently);
 * overlapping calls are detected on a best-effort basis, not serialised.
 * \since 0.1 */
GLOW_API glow_result glow_system_update(glow_system *system, const glow_update_desc *desc);
/* (glow_update_desc budgets: \since 0.1; GLOW_ERROR_INVALID_ARGUMENT for a negative or non-finite
 * budget_ms, focus_radius or converged_epsilon, or focus_count > 0 with a NULL or non-finite focus.) */
/** The last successful update's timings and counters. \threadsafety Between updates, from any thread.
 * \since 0.1 */
GLOW_API glow_result glow_system_get_stats(const glow_system *system, glow_update_stats *out_stats);

/* Outputs: incident-radiance SH, YCoCg, in planar layout (one plane per coefficient) so each plane
 * uploads as one layer of a float texture array (lightmap) or one 3D float texture (grid).
 * Coefficient planes: k in [0, luma²) are Y's SH; then chroma² planes of Co, then chroma² of Cg.
 * Y = R/4 + G/2 + B/4, Co = R/2 - B/2, Cg = -R/4 + G/2 - B/4 (PIC Eq. 7); glow_ycocg_to_rgb inverts.
 * Empty grid cells and lightmap texels hold 0; lightmap gutter/seam texels hold a copy of their
 * source texel's SH, so bilinear filtering never reads an empty texel inside a chart's footprint. */
typedef struct glow_cache_outputs {
    uint32_t sh_bands_luma, sh_bands_chroma;
    uint32_t coeff_count;        /* luma² + 2 chroma²: planes per texel/cell, and floats per cache */
    uint32_t cache_count, grid_cache_count, lightmap_cache_count;
    const float *cache_sh;       /* [cache_count][coeff_count], the bake's cache order */
    uint32_t grid_dims[3];       /* 0 when the bake has no grid */
    float grid_origin[3];        /* centre of cell (0,0,0), m */
    float grid_spacing;          /* m */
    const float *grid_sh;        /* [coeff_count][dz][dy][dx], x fastest; NULL without a grid (or with
                                    output planes other than F32: output_planes, below) */
    uint32_t lightmap_width, lightmap_height; /* 0 without a lightmap */
    const float *lightmap_sh;    /* [coeff_count][height][width], row-major; NULL without a lightmap
                                    (or with output planes other than F32) */
    const uint32_t *grid_map;    /* [dz][dy][dx]: cache index of each cell, 0xFFFFFFFF = empty */
    const uint32_t *lightmap_map;/* [height][width]: cache index of each texel (gutter and seam texels
                                    name the cache they copy), 0xFFFFFFFF = empty */
    const uint8_t *grid_visibility; /* [dz][dy][dx][8] or NULL (bakes made before GVIS): for the grid cell
                                    whose lowest corner is point (x, y, z) and each octant o of it (bit a
                                    of o: the upper half along axis a), bit k set when corner k (x + (k&1),
                                    y + (k>>1&1), z + (k>>2), clamped to the grid) is visible from the
                                    octant's centre. glow_sample_grid blends only those corners, so a
                                    lookup does not read light through a wall thinner than the spacing */
    uint64_t update_index;       /* successful updates so far */
    /* \since 0.2, bakes with a lightmap detail (glow-bake --lightmap-detail; 0 / NULL otherwise): a grid
     * detail_width / lightmap_width times finer over the same atlas, sampled with the same UVs
     * (glow_sample_lightmap_detail). RGB: the light from surfaces beside the texel (a few decimetres
     * across a concave corner) that the lightmap's texels are too coarse to hold, as a correction to
     * add to glow_shade_sh's diffuse result (cosine-lobe mean radiance about the surface normal; it may
     * be negative, the sum is not); A: 1 where a detail texel covers a surface, else 0 (RGB 0). */
    uint32_t detail_width, detail_height;
    const float *lightmap_detail; /* [detail_height][detail_width][4] RGBA, row-major */
    /* \since 0.2, bakes with a refined grid (glow-bake --grid-refine R, bake format 1.5; 0 / NULL
     * otherwise): near geometry a coarse cell (the one whose lowest corner is grid point (x, y, z)) may
     * be a brick of R³ fine cells of spacing grid_spacing / R. glow_sample_grid and
     * glow_sample_grid_oriented look a point up in its brick's fine cell when it has one (and fall back
     * to the coarse cell when none of the fine corners they may blend holds a cache). The fine caches
     * are grid caches (rows of cache_sh) with no cell in grid_sh; on the GPU they are in the GL
     * backend's brick atlas, read by glow_sample_grid_refined (glow_shading.glsl, docs/gpu.md). */
    uint32_t grid_refine;        /* R (0: not refined) */
    uint32_t grid_brick_count;
    const uint32_t *grid_brick_of_cell; /* [dz][dy][dx]: brick of the cell, 0xFFFFFFFF = none */
    const uint32_t *grid_bricks; /* [brick][(R+1)³]: cache index of each corner of the brick's fine
                                    lattice, x fastest, 0xFFFFFFFF = none (inside geometry) */
    const uint8_t *grid_brick_visibility; /* [brick][R³ fine cells, x fastest][8 octants]: as
                                    grid_visibility, for the fine cells */
    /* \since 0.2 (bake format 1.7): the lightmap's pages, atlases of lightmap_width x lightmap_height
     * (1 when it fits one; 0 without a lightmap). With P pages lightmap_sh is [coeff_count][P][height]
     * [width], lightmap_map [P][height][width] and lightmap_detail [P][detail_height][detail_width][4]:
     * each coefficient plane holds the pages one after the other, so with P = 1 every field reads as
     * before. A triangle's page: glow_bake_geometry.lightmap_page; lookups: glow_sample_lightmap_page,
     * glow_sample_lightmap_detail_page. Gutter and seam copies stay within their page. */
    uint32_t lightmap_pages;
    /* \since 0.2: the planes' format (glow_system_desc.output_planes). With GLOW_OUTPUT_PLANES_RGBA16F
     * these two hold the planes (grid_sh and lightmap_sh are NULL) as IEEE halves, coefficient k of a
     * cell or texel at component k % 4 of RGBA texel plane q = k / 4 (Q = (coeff_count + 3) / 4 planes;
     * the last plane's components past coeff_count are 0), as glow_shading.glsl reads them; with
     * GLOW_OUTPUT_PLANES_NONE all four are NULL. */
    glow_output_planes output_planes;
    const uint16_t *grid_rgba16f;     /* [Q][dz][dy][dx][4]: a 3D texture dx x dy x (dz Q), plane q at
                                         z + q dz; or NULL */
    const uint16_t *lightmap_rgba16f; /* [pages][Q][height][width][4]: a 2D array texture of pages x Q
                                         layers, plane q of page g at layer g Q + q; or NULL */
} glow_cache_outputs;
/** The outputs, owned by the system, valid (and unchanged) until the next update or destroy.
 * NULL for a NULL system. \threadsafety Read concurrently, but not during an update. \since 0.1 */
GLOW_API const glow_cache_outputs *glow_system_outputs(const glow_system *system);

/* ------------------------------------------------------------------------------------ worlds */
/* A world: the systems of a level baked in systems (glow-bake --system-area) that the host has loaded
 * now. Adding a system attaches it to the members it depends on and the members that depend on it
 * (glow_system_set_neighbour, by key); removing it detaches both ways, so its dependents keep its last
 * radiance and the host may destroy it: systems stream in and out between updates. The world borrows
 * its systems (the host creates and destroys them, and their bakes) and allocates only at create, so
 * adding, removing and updating allocate nothing. See docs/runtime.md, "A world of systems". */
typedef struct glow_world glow_world;

typedef struct glow_world_stats {
    uint32_t systems;               /* members */
    uint32_t dependencies_attached; /* the members' dependencies whose system is a member (attached) */
    uint32_t dependencies_missing;  /* ... whose system is not: their proxies keep their last radiance,
                                       or zero for a neighbour never attached */
    glow_update_stats last_update;  /* the last glow_world_update, summed over the members it updated
                                       (times, links, caches; a member a time budget skipped adds its
                                       caches to caches_skipped_budget), memory over all members;
                                       updates counts the world's successful updates */
    uint32_t systems_updated;       /* members the last glow_world_update updated (a time budget may
                                       skip some: they keep their outputs) */
} glow_world_stats;

/** Creates an empty world that holds at most `capacity` systems (1..1048576).
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT; GLOW_ERROR_OUT_OF_MEMORY. \since 0.2 */
GLOW_API glow_result glow_world_create(glow_context *context, uint32_t capacity, glow_world **out_world);
/** Removes every member (detaching them from each other) and frees the world; the systems stay the
 * host's. NULL is a no-op. \since 0.2 */
GLOW_API void glow_world_destroy(glow_world *world);
/** Adds `system` and attaches it both ways to the members of the same world. A system whose bake is not
 * part of a world (system_key 0) may be added: it links nothing.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, already a member, or another member with the
 * same system_key); GLOW_ERROR_INVALID_OPERATION (the world is full, or a member is updating: nothing
 * attached); GLOW_ERROR_OUT_OF_RANGE (a forged bake, as glow_system_set_neighbour).
 * \threadsafety Not during glow_world_update or an update of a member. \since 0.2 */
GLOW_API glow_result glow_world_add(glow_world *world, glow_system *system);
/** Removes `system` and detaches it both ways: the members that read it keep its last radiance.
 * The system may then be destroyed. \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, not a
 * member); GLOW_ERROR_INVALID_OPERATION (a member is updating). \since 0.2 */
GLOW_API glow_result glow_world_remove(glow_world *world, glow_system *system);
/** The members, in the order they were added (the order glow_world_update updates them). \since 0.2 */
GLOW_API uint32_t glow_world_system_count(const glow_world *world);
GLOW_API glow_system *glow_world_system(const glow_world *world, uint32_t index);
/** Updates the members once, one after another, each with every worker of the context: light crosses
 * a border with one update of lag. Without a time budget every member updates, in the order added; a
 * caches budget (max_caches) is shared between them in proportion to their caches. With budget_ms the
 * members go by priority, the stalest and those nearest the focus points first (as the groups of
 * caches within a system; docs/runtime.md "A world of systems"): the first updates with the whole
 * budget as its own, each next one only if the part of its last update that a budget cannot cut (all
 * but the cache gathers and the hook's batches beyond one a worker) fits what is left, with what is
 * left as its budget; the others keep their outputs (glow_world_stats.systems_updated). Flags, focus
 * points and converged_epsilon go to each. A member whose update fails (its hook,
 * GLOW_ERROR_HOST_CALLBACK) keeps its last good outputs and the others still update. Allocates nothing.
 * \returns GLOW_OK, or the first member's error; GLOW_ERROR_INVALID_ARGUMENT for a NULL world, a
 * negative or non-finite budget_ms or focus_radius, or focus_count with NULL focus. \since 0.2 */
GLOW_API glow_result glow_world_update(glow_world *world, const glow_update_desc *desc);
/** \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for NULL. \since 0.2 */
GLOW_API glow_result glow_world_get_stats(const glow_world *world, glow_world_stats *out_stats);

/* The solver's tables for other backends (the link bit layout, per-surfel arrays) are not part of this
 * API: glow/glow_backend.h, for Glow's own GL backend, tools and the samples' debug views. */

/* ============================================================================ shading
 * The C reference of the GLSL shading includes (PIC 3.2, App. B). Pure functions, any thread. */

/** Real orthonormal SH basis (DESIGN §3): l bands -> l² values, index k² + k + m,
 * y_1 = sqrt(3/4π) (y, z, x). `dir` must be unit length. bands 1..GLOW_MAX_SH_BANDS. \since 0.1 */
GLOW_API void glow_sh_eval(uint32_t bands, const float dir[3], float *out);
/** Cone projection factor k_l(x), x = cos of the cone half-angle (DESIGN §3):
 * k_0 = 2π(1 - x), k_l = 2π/(2l+1) (P_{l-1}(x) - P_{l+1}(x)). \since 0.1 */
GLOW_API float glow_sh_cone_factor(uint32_t l, float cos_half_angle);
/** Lobe factor s_l of the normalised Phong lobe (n+1)/(2π) cos^n (PIC App. B): s_0 = 1,
 * s_1 = (n+1)/(n+2), s_l = s_{l-2} (n+2-l)/(n+1+l). n = 1 is the diffuse cosine lobe. \since 0.1 */
GLOW_API float glow_sh_lobe_factor(uint32_t l, float exponent);
/** Ringing window σ_l for band l of an SH signal truncated to `bands` bands (Lanczos sigma factors):
 * σ_0 = 1, σ_l = sin(π l / bands) / (π l / bands). Multiplying band l of a cache (or a lobe factor)
 * by σ_l trades sharpness for less ringing (negative lobes opposite bright sources); measured in
 * docs/results.md ("SH ringing"). 0 for l >= bands. \since 0.1 */
GLOW_API float glow_sh_window_factor(uint32_t l, uint32_t bands);
/** RGB -> YCoCg and back (PIC Eq. 7, see glow_cache_outputs). \since 0.1 */
GLOW_API void glow_rgb_to_ycocg(const float rgb[3], float out_ycocg[3]);
/** \since 0.1 */
GLOW_API void glow_ycocg_to_rgb(const float ycocg[3], float out_rgb[3]);

/** Convolves one cache's SH (`coeffs` in the output layout: luma² Y, chroma² Co, chroma² Cg) with
 * the normalised Phong lobe of `exponent` around unit `axis`: the lobe-weighted mean incident
 * radiance, RGB, W/(m²·sr). With exponent 1 and axis = the surface normal this is E/π, so a
 * Lambertian surface of albedo ρ reflects radiance ρ·result; for a specular lobe pass the
 * reflection vector. \since 0.1 */
GLOW_API void glow_shade_sh(const float *coeffs, uint32_t sh_bands_luma, uint32_t sh_bands_chroma,
                            const float axis[3], float exponent, float out_rgb[3]);

/** glow_shade_sh with any zonal lobe: factors[l] (l < sh_bands_luma) multiplies band l, the lobe's
 * Funk-Hecke factor 2π ∫ p(θ) P_l(cos θ) sin θ dθ for a lobe p normalised to ∫ p = 1 (factors[0] = 1),
 * e.g. glow_sh_ggx_lobe_factors. glow_shade_sh(.., exponent, ..) is this with glow_sh_lobe_factor(l,
 * exponent). \since 0.2 */
GLOW_API void glow_shade_sh_factors(const float *coeffs, uint32_t sh_bands_luma, uint32_t sh_bands_chroma,
                                    const float axis[3], const float *factors, float out_rgb[3]);
/** Zonal-harmonic lobe factors of a GGX specular lobe about the reflection vector (DDISH-GI App. A,
 * derived in docs/glossy.md): out[l] for l < bands (1..GLOW_MAX_SH_BANDS), the band factors of
 * f_s(o, i) cos θ_i at normal incidence (o = n, G = Smith G1(o) G1(i), no Fresnel), normalised so that
 * out[0] = 1. `roughness` is glTF's perceptual roughness in (0, 1], α = roughness² (clamped to
 * [10⁻³, 1]). Deterministic quadrature (16-node Gauss-Legendre panels), about 3 µs for 8 bands:
 * compute it per material. The specular radiance of a GGX surface is then ≈ (F0·A + B) ·
 * glow_shade_sh_factors(SH, reflect(-o, n), out) with A, B from glow_ggx_specular_albedo (the split sum).
 * \since 0.2 */
GLOW_API void glow_sh_ggx_lobe_factors(float roughness, uint32_t bands, float *out);
/** Directional albedo of the GGX specular lobe above, split for Schlick's Fresnel:
 * ∫ f_s cos θ_i dω_i = F0 · out_ab[0] + out_ab[1] at cos θ_o = cos_view (0 at or below 0). Deterministic
 * quadrature over the half vector (about 0.4 ms a call: tabulate it over cos_view). \since 0.2 */
GLOW_API void glow_ggx_specular_albedo(float cos_view, float roughness, float out_ab[2]);

/* Sky SH (docs/sky.md): a sky's radiance as real SH l <= 2 (9 coefficients, glow_sh_eval's basis) per
 * RGB channel, COEFFICIENT-MAJOR: sh_rgb[3 k + c] is coefficient k of channel c (R, G, B), W/(m²·sr).
 * Scenes are Y-up. Pure functions, any thread; an output may alias the input. \since 0.2 */
/** The SH of a constant sky of radiance `radiance_rgb`: L_0 = L √(4π), the rest 0. \since 0.2 */
GLOW_API void glow_sh_sky_constant(const float radiance_rgb[3], float out_rgb[GLOW_SKY_SH_FLOATS]);
/** Rotates a sky: out(ω) = in(Rᵀω), so light that came from direction d comes from R d. `rotation` is a
 * row-major orthonormal 3x3 matrix. Exact for l <= 2. \since 0.2 */
GLOW_API void glow_sh_rotate_l2(const float rotation[9], const float in_rgb[GLOW_SKY_SH_FLOATS],
                                float out_rgb[GLOW_SKY_SH_FLOATS]);
/** glow_sh_rotate_l2 about +Y by `angle_radians`, right-handed: a positive angle turns +Z towards +X
 * (and +X towards -Z), R = [[cos, 0, sin], [0, 1, 0], [-sin, 0, cos]]. A sky map turned by
 * rotation_deg is glow_sh_rotate_y(sh, rotation_deg · π/180, out). \since 0.2 */
GLOW_API void glow_sh_rotate_y(const float in_rgb[GLOW_SKY_SH_FLOATS], float angle_radians,
                               float out_rgb[GLOW_SKY_SH_FLOATS]);
/** A surfel's sky irradiance max(0, Σ_k transfer[k] · sky[k]) per channel (W/m²), `transfer` one
 * surfel's 9 values of glow_bake_sky_transfer.surfel_transfer. NaN gives 0. \since 0.2 */
GLOW_API void glow_sh_sky_irradiance(const float transfer[9], const float sky_rgb[GLOW_SKY_SH_FLOATS], float out_rgb[3]);
/** The radiance SH of the part of a sky a grid cache sees: the product projection of its visibility
 * SH `visibility` (glow_bake_sky_transfer.grid_visibility) and the sky, truncated to l <= 2,
 * out_k = Σ_ij G_ijk V_i L_j with G the triple products ∫ y_i y_j y_k (glow_sh_gaunt_l2). A host adds it
 * (in YCoCg, glow_rgb_to_ycocg per coefficient) to the grid cache's radiance SH. \since 0.2 */
GLOW_API void glow_sh_sky_visible(const float visibility[9], const float sky_rgb[GLOW_SKY_SH_FLOATS],
                                  float out_rgb[GLOW_SKY_SH_FLOATS]);
/** The triple product ∫ y_i y_j y_k dω of three basis functions, i, j, k < 9 (0 otherwise). \since 0.2 */
GLOW_API float glow_sh_gaunt_l2(uint32_t i, uint32_t j, uint32_t k);

/** Trilinear sample of the grid at `position` (m) into out_coeffs[coeff_count]. Cells without a
 * cache get weight 0, and so do corners that outputs->grid_visibility marks as hidden from the
 * lookup's octant of the cell; the rest are renormalised. Outside the grid the position is clamped.
 * In a refined grid (outputs->grid_refine) a position inside a brick is looked up in its fine cell
 * the same way (grid_brick_visibility), and in the coarse cell when none of the fine corners it may
 * blend holds a cache.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, no grid); GLOW_ERROR_OUT_OF_RANGE when no
 * cache is among the 8 neighbours (out_coeffs zeroed). \since 0.1 */
GLOW_API glow_result glow_sample_grid(const glow_cache_outputs *outputs, const float position[3], float *out_coeffs);

/* glow_sample_grid_oriented's two constants (DDGI's normal bias and "smooth backface" weight,
 * Majercik et al. 2019; measured in docs/results.md, "the grid at surfaces"). */
#define GLOW_GRID_NORMAL_BIAS 0.25f   /* of a grid spacing, along the normal */
#define GLOW_GRID_BACKFACE_FLOOR 0.2f /* the least backface weight */
/** The grid's light for a surface point: glow_sample_grid at position + GLOW_GRID_NORMAL_BIAS ·
 * spacing · normal (the fine spacing in a refined grid) (so that the cell and its GVIS octant are taken on the side the surface faces),
 * with each corner's trilinear weight also multiplied by ((1 + cos θ) / 2)² + GLOW_GRID_BACKFACE_FLOOR,
 * θ between `normal` and the direction from `position` to the corner: corners behind the surface
 * count about 6x less than those in front. Use it to shade a dynamic object's surface (its
 * world-space normal; it need not be unit length) and glow_sample_grid for a point without a surface
 * (a particle, a volume). On Sponza, shading every surface from the grid this way is within 0.19 of
 * the referee (8x8 block error) against 0.25 with glow_sample_grid, and a finer grid is better where
 * glow_sample_grid's lookups got worse (docs/results.md).
 * \returns as glow_sample_grid; GLOW_ERROR_INVALID_ARGUMENT also for a NULL, zero or non-finite
 * normal. \since 0.2 */
GLOW_API glow_result glow_sample_grid_oriented(const glow_cache_outputs *outputs, const float position[3],
                                               const float normal[3], float *out_coeffs);
/** Bilinear sample of the lightmap at (u, v) in [0,1]² (texel centres at (i + 0.5)/width; v = 0 is
 * row 0), clamped to the edge, empty texels weighted 0 and the rest renormalised.
 * \returns as glow_sample_grid. \since 0.1 */
GLOW_API glow_result glow_sample_lightmap(const glow_cache_outputs *outputs, float u, float v, float *out_coeffs);
/** Bilinear sample of the lightmap detail at (u, v) (the lightmap's UVs; texel centres at
 * (i + 0.5)/detail_width), clamped to the edge, weighted by the coverage (A) and renormalised: RGB to
 * add to glow_shade_sh(lightmap sample, normal, exponent 1) before clamping the sum at 0 and
 * multiplying by the albedo. What a GPU gets from a filtered RGBA texture fetch as rgb / a.
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL, no detail); GLOW_ERROR_OUT_OF_RANGE when
 * none of the 4 texels covers a surface (out_rgb zeroed). \since 0.1 */
GLOW_API glow_result glow_sample_lightmap_detail(const glow_cache_outputs *outputs, float u, float v, float out_rgb[3]);
/** glow_sample_lightmap on page `page` of the lightmap (outputs->lightmap_pages; (u, v) in [0,1]² of
 * that page, which bounds the lookup: it clamps to the page's edge). Page 0 is glow_sample_lightmap.
 * \returns as glow_sample_lightmap; GLOW_ERROR_INVALID_ARGUMENT also for page >= lightmap_pages.
 * \since 0.2 */
GLOW_API glow_result glow_sample_lightmap_page(const glow_cache_outputs *outputs, uint32_t page, float u, float v,
                                               float *out_coeffs);
/** glow_sample_lightmap_detail on page `page` (as glow_sample_lightmap_page). \since 0.2 */
GLOW_API glow_result glow_sample_lightmap_detail_page(const glow_cache_outputs *outputs, uint32_t page, float u,
                                                      float v, float out_rgb[3]);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_H */
