/*
 * runtime_internal.h — what the runtime's source files share with each other (and with tests).
 * Not installed; only runtime/src/ and tests/ include it.
 *
 *   context.c  glow_context: allocator + logger hooks, and the glow__ctx_* helpers below
 *   result.c   glow_result_string
 *   bake.c     glow_bake: load + full validation, and the typed section accessors below
 *   bake/format_util.c  CRC-32, octahedral and half conversions (declared in bake/bake_format.h)
 *   system.c   glow_system: the solver; world.c  glow_world: systems attached to each other by key
 */
#ifndef GLOW_RUNTIME_INTERNAL_H
#define GLOW_RUNTIME_INTERNAL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "bake/bake_format.h"
#include "glow/glow.h"
#include "glow/glow_backend.h" /* glow_solver_tables (system.c) */

#if defined(__GNUC__) || defined(__clang__)
#define GLOW__PRINTF(fmt_index, first_arg) __attribute__((format(printf, fmt_index, first_arg)))
#else
#define GLOW__PRINTF(fmt_index, first_arg)
#endif

/* ---------------------------------------------------------------- context (context.c) */

/* Allocates `size` bytes aligned to `align` (a power of two; 0 = 16) through the context's
 * allocator. size 0 is treated as 1. Returns NULL on failure (logs nothing: the caller knows
 * what it was allocating and reports GLOW_ERROR_OUT_OF_MEMORY with that). ctx must not be NULL. */
void *glow__ctx_alloc(glow_context *ctx, size_t size, size_t align);
/* Frees what glow__ctx_alloc returned (NULL is a no-op). */
void glow__ctx_free(glow_context *ctx, void *ptr);
/* The same without the live-allocation count (the context's own worker pool). */
void *glow__ctx_alloc_uncounted(glow_context *ctx, size_t size, size_t align);
void glow__ctx_free_uncounted(glow_context *ctx, void *ptr);

/* Formats one message and hands it to the context's logger with `level` and `code`; `file` and
 * `line` name the runtime source location (use the GLOW__LOG* macros). ctx may be NULL (silent).
 * Messages longer than 1023 bytes are truncated. Reentrant. */
void glow__ctx_log(glow_context *ctx, glow_log_level level, glow_result code, const char *file, int line,
                   const char *fmt, ...) GLOW__PRINTF(6, 7);
void glow__ctx_logv(glow_context *ctx, glow_log_level level, glow_result code, const char *file, int line,
                    const char *fmt, va_list ap);

#define GLOW__LOG_ERROR(ctx, code, ...) glow__ctx_log((ctx), GLOW_LOG_ERROR, (code), __FILE__, __LINE__, __VA_ARGS__)
#define GLOW__LOG_WARNING(ctx, code, ...) \
    glow__ctx_log((ctx), GLOW_LOG_WARNING, (code), __FILE__, __LINE__, __VA_ARGS__)

/* Workers task functions may see (worker index < this), >= 1. */
uint32_t glow__ctx_workers(const glow_context *ctx);
/* Runs fn(data, i, worker) for i in [0, count) on the host's parallel_for or the built-in pool and
 * returns when all are done. Not reentrant (a task must not call it). */
void glow__ctx_run(glow_context *ctx, glow_task_fn fn, void *data, uint32_t count);
/* Starts the built-in pool now if the context uses one (systems call it at create, so no update
 * ever allocates); returns it, or NULL when work runs on the host's tasks or serially. */
struct glow__taskpool *glow__ctx_start_pool(glow_context *ctx);

/* ---------------------------------------------------------------- SH helpers (sh.c) */
#include "bake/sh_seam.h" /* glow__legendre_all, glow__cone_factor_omc: shared with the linker */

/* ---------------------------------------------------------------- built-in pool (pool.c) */
typedef struct glow__taskpool glow__taskpool;
glow_result glow__taskpool_create(glow_context *ctx, uint32_t threads, glow__taskpool **out); /* 0 = online CPUs */
void glow__taskpool_destroy(glow__taskpool *pool);
uint32_t glow__taskpool_threads(const glow__taskpool *pool);
void glow__taskpool_run(glow__taskpool *pool, glow_task_fn fn, void *data, uint32_t count);
uint32_t glow__online_cpus(void);

/* Live allocations made through glow__ctx_alloc and not yet freed (leak checks in tests). */
uint64_t glow__ctx_live_allocations(const glow_context *ctx);

/* ---------------------------------------------------------------- bake (bake.c) */
/* Typed views of a loaded (fully validated) bake. The bake's bytes live in one allocation aligned
 * to GLOW_BAKE_ALIGN, so every pointer below is 64-byte aligned. Counts are in glow__bake_meta().
 * Pointers are valid until glow_bake_destroy. None is NULL for a loaded bake except where noted
 * (a section of size 0 still yields a valid, non-dereferenceable pointer). */
const glow_bake_meta *glow__bake_meta(const glow_bake *bake);
const glow_bake_material *glow__bake_materials(const glow_bake *bake); /* [material_count] */
const glow_bake_surfel *glow__bake_surfels(const glow_bake *bake);     /* [surfel_count] */
const glow_bake_node *glow__bake_nodes(const glow_bake *bake);         /* [node_count] */
const uint32_t *glow__bake_level_starts(const glow_bake *bake);        /* [level_count + 1] */
const glow_bake_cache *glow__bake_caches(const glow_bake *bake);       /* [cache_count] */
/* [grid_dims[0]*grid_dims[1]*grid_dims[2]]; NULL when the grid has no cells. */
const uint32_t *glow__bake_grid_map(const glow_bake *bake);
/* [grid cells][8]: per octant of each grid cell, the corners a lookup may blend (GVIS, optional,
 * see bake_format.h); NULL when the bake has no grid or was baked before it existed. */
const uint8_t *glow__bake_grid_visibility(const glow_bake *bake);
/* GFIN's header or NULL; brick_of_cell, the bricks and their masks follow it (bake_format.h) */
const glow_bake_grid_fine *glow__bake_grid_fine(const glow_bake *bake);
/* [lightmap_count pages][lightmap_height][lightmap_width]; NULL when lightmap_count == 0. */
const uint32_t *glow__bake_lightmap_map(const glow_bake *bake);
/* [cache_count * link_blocks_per_cache] */
const glow_bake_link_block *glow__bake_link_blocks(const glow_bake *bake);
/* Full-SH link blocks, glow_bake_shlk_block_size(sh_bands) bytes each, same count as the LINK
 * blocks; NULL unless link_kind has GLOW_LINK_KIND_FULL_SH. */
const void *glow__bake_shlk_blocks(const glow_bake *bake);
const uint16_t *glow__bake_link_subsets(const glow_bake *bake); /* LSUB, or NULL */
/* XREF (a system of a world), or NULL; its dependency keys and proxies through the pointers */
const glow_bake_xref *glow__bake_xref(const glow_bake *bake, const uint64_t **dependency_key,
                                      const glow_bake_xref_proxy **proxies);
/* LDET (bake_format.h glow_bake_detail), or NULL; the arrays follow its header */
const glow_bake_detail *glow__bake_detail(const glow_bake *bake, const uint32_t **texel, const uint32_t **first,
                                          const uint32_t **surfel, const float **weight);
/* [triangle_count]; NULL when the bake has no GEOM section. */
const glow_bake_triangle *glow__bake_triangles(const glow_bake *bake);
/* Any section by fourcc (also ones this runtime does not know); NULL when absent. */
const void *glow__bake_section(const glow_bake *bake, uint32_t fourcc, uint64_t *out_size);
/* The whole file image (header first) and its size. */
const void *glow__bake_data(const glow_bake *bake, uint64_t *out_size);
/* Systems using the bake (glow_bake_destroy refuses while any is live). */
void glow__bake_retain(const glow_bake *bake);
void glow__bake_release(const glow_bake *bake);

/* ---------------------------------------------------------------- systems (system.c, for world.c) */
/* The bake a system was created from, and its label (never NULL for a valid system). */
const glow_bake *glow__system_bake(const glow_system *system);
const char *glow__system_label(const glow_system *system);
uint32_t glow__system_cache_count(const glow_system *system);
uint32_t glow__system_surfel_count(const glow_system *system);
/* The part of the system's last update that a time budget cannot cut: all but the cache gathers and
 * the hook's batches beyond its fewest (system.c, order_batches). */
double glow__system_uncut_ms(const glow_system *system);
/* The context the bake was loaded with. */
glow_context *glow__bake_context(const glow_bake *bake);

#endif /* GLOW_RUNTIME_INTERNAL_H */
