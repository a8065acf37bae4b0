/* context.c — glow_context: the host's allocator, logger and task hooks, shared by everything the
 * runtime creates. A context is immutable after creation (except its lazily started worker pool,
 * guarded by a mutex), so any thread may use it. */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime_internal.h"

struct glow_context {
    glow_allocator allocator; /* both hooks set, or both NULL (aligned malloc) */
    glow_logger logger;       /* log NULL = silent */
    glow_task_hooks tasks;    /* parallel_for NULL = the built-in pool below */
    glow__taskpool *pool;     /* built-in pool, started by the first parallel run (NULL with host tasks,
                                 with one worker, or before first use) */
    pthread_mutex_t pool_mutex;
    atomic_bool pool_failed;  /* could not start: run serially */
    uint32_t workers;         /* worker indices handed to task functions are < workers */
    atomic_ullong live;       /* allocations not yet freed */
};

static int is_pow2(size_t v) { return v != 0 && (v & (v - 1)) == 0; }

static void *default_alloc(size_t size, size_t align) {
    /* C11 aligned_alloc wants size to be a multiple of the alignment (ASan checks it). */
    size_t rounded = (size + align - 1) & ~(align - 1);
    if (rounded < size) return NULL; /* overflow */
    return aligned_alloc(align, rounded);
}

void *glow__ctx_alloc(glow_context *ctx, size_t size, size_t align) {
    void *p = glow__ctx_alloc_uncounted(ctx, size, align);
    if (p) atomic_fetch_add_explicit(&ctx->live, 1u, memory_order_relaxed);
    return p;
}

void *glow__ctx_alloc_uncounted(glow_context *ctx, size_t size, size_t align) {
    if (align == 0) align = 16;
    if (!is_pow2(align)) return NULL;
    if (align < sizeof(void *)) align = sizeof(void *);
    if (size == 0) size = 1;
    void *p = ctx->allocator.alloc ? ctx->allocator.alloc(ctx->allocator.user, size, align)
                                   : default_alloc(size, align);
    if (p && ((uintptr_t)p & (align - 1)) != 0) {
        /* A host allocator that ignores the alignment would break every typed view of a bake. */
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_OUT_OF_MEMORY,
                        "host allocator returned %p, not aligned to %zu bytes as requested", p, align);
        if (ctx->allocator.free) ctx->allocator.free(ctx->allocator.user, p);
        return NULL;
    }
    return p;
}

void glow__ctx_free(glow_context *ctx, void *ptr) {
    if (!ptr) return;
    atomic_fetch_sub_explicit(&ctx->live, 1u, memory_order_relaxed);
    glow__ctx_free_uncounted(ctx, ptr);
}

void glow__ctx_free_uncounted(glow_context *ctx, void *ptr) {
    if (!ptr) return;
    if (ctx->allocator.free)
        ctx->allocator.free(ctx->allocator.user, ptr);
    else
        free(ptr);
}

uint64_t glow__ctx_live_allocations(const glow_context *ctx) {
    return ctx ? (uint64_t)atomic_load_explicit(&((glow_context *)ctx)->live, memory_order_relaxed) : 0u;
}

void glow__ctx_logv(glow_context *ctx, glow_log_level level, glow_result code, const char *file, int line,
                    const char *fmt, va_list ap) {
    if (!ctx || !ctx->logger.log) return;
    char buf[1024];
    int n = vsnprintf(buf, sizeof buf, fmt, ap);
    if (n < 0) snprintf(buf, sizeof buf, "(message could not be formatted)");
    ctx->logger.log(ctx->logger.user, level, code, buf, file, line);
}

void glow__ctx_log(glow_context *ctx, glow_log_level level, glow_result code, const char *file, int line,
                   const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    glow__ctx_logv(ctx, level, code, file, line, fmt, ap);
    va_end(ap);
}

glow_result glow_context_create(const glow_context_desc *desc, glow_context **out_context) {
    if (out_context) *out_context = NULL;
    if (!desc || !out_context) return GLOW_ERROR_INVALID_ARGUMENT;

    /* A stand-in so problems with the desc itself reach the host's logger. */
    glow_context tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.logger = desc->logger;

    if (desc->api_version / 10000u != (uint32_t)GLOW_VERSION_MAJOR) {
        GLOW__LOG_ERROR(&tmp, GLOW_ERROR_VERSION_MISMATCH,
                        "glow_context_create: api_version %u is version %u.%u.%u; this runtime is %d.%d.%d "
                        "(major versions must match)",
                        desc->api_version, desc->api_version / 10000u, desc->api_version / 100u % 100u,
                        desc->api_version % 100u, GLOW_VERSION_MAJOR, GLOW_VERSION_MINOR, GLOW_VERSION_PATCH);
        return GLOW_ERROR_VERSION_MISMATCH;
    }
    if ((desc->allocator.alloc == NULL) != (desc->allocator.free == NULL)) {
        GLOW__LOG_ERROR(&tmp, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_context_create: allocator.alloc and allocator.free must both be set or both be NULL");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (desc->tasks.parallel_for && desc->tasks.worker_count == 0) {
        GLOW__LOG_ERROR(&tmp, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_context_create: tasks.parallel_for is set but tasks.worker_count is 0 (must be >= 1)");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (desc->tasks.worker_count > 1024) {
        GLOW__LOG_ERROR(&tmp, GLOW_ERROR_INVALID_ARGUMENT, "glow_context_create: tasks.worker_count %u > 1024",
                        desc->tasks.worker_count);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    tmp.allocator = desc->allocator;
    atomic_init(&tmp.live, 0u);

    glow_context *ctx = glow__ctx_alloc(&tmp, sizeof *ctx, _Alignof(glow_context));
    if (!ctx) {
        GLOW__LOG_ERROR(&tmp, GLOW_ERROR_OUT_OF_MEMORY, "glow_context_create: out of memory (%zu bytes)",
                        sizeof *ctx);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    ctx->allocator = desc->allocator;
    ctx->logger = desc->logger;
    ctx->tasks = desc->tasks;
    ctx->pool = NULL;
    atomic_init(&ctx->live, 0u); /* the context's own block is not counted */
    atomic_init(&ctx->pool_failed, false);
    pthread_mutex_init(&ctx->pool_mutex, NULL);
    /* The built-in pool starts with the first parallel run (a context that only loads bakes never
     * starts threads); its blocks are not counted as live allocations: they are the context's. */
    ctx->workers = desc->tasks.parallel_for ? desc->tasks.worker_count
                                            : (desc->tasks.worker_count ? desc->tasks.worker_count : glow__online_cpus());
    *out_context = ctx;
    return GLOW_OK;
}

uint32_t glow__ctx_workers(const glow_context *ctx) { return ctx->workers; }

void glow__ctx_run(glow_context *ctx, glow_task_fn fn, void *data, uint32_t count) {
    if (count == 0) return;
    if (ctx->tasks.parallel_for) {
        ctx->tasks.parallel_for(ctx->tasks.user, fn, data, count);
        return;
    }
    glow__taskpool *pool = count > 1 ? glow__ctx_start_pool(ctx) : NULL;
    glow__taskpool_run(pool, fn, data, count); /* NULL pool: serial, on this thread */
}

glow__taskpool *glow__ctx_start_pool(glow_context *ctx) {
    if (ctx->tasks.parallel_for || ctx->workers <= 1 || atomic_load(&ctx->pool_failed)) return NULL;
    pthread_mutex_lock(&ctx->pool_mutex);
    if (!ctx->pool && glow__taskpool_create(ctx, ctx->workers, &ctx->pool) != GLOW_OK) {
        atomic_store(&ctx->pool_failed, true);
        GLOW__LOG_WARNING(ctx, GLOW_ERROR_OUT_OF_MEMORY, "could not start the worker pool; running serially");
    }
    glow__taskpool *pool = ctx->pool;
    pthread_mutex_unlock(&ctx->pool_mutex);
    return pool;
}

void glow_context_destroy(glow_context *context) {
    if (!context) return;
    /* Refused, like glow_bake_destroy with live systems: freeing the context under a live bake or
     * system made their next call a use-after-free (issue 15, D6). The context stays usable. */
    uint64_t live = glow__ctx_live_allocations(context);
    if (live != 0) {
        GLOW__LOG_ERROR(context, GLOW_ERROR_INVALID_OPERATION,
                        "glow_context_destroy: %llu allocation(s) still live (a bake or system was not destroyed); "
                        "destroy them first (the context was not destroyed)",
                        (unsigned long long)live);
        return;
    }
    glow__taskpool_destroy(context->pool);
    context->pool = NULL;
    pthread_mutex_destroy(&context->pool_mutex);
    glow_allocator a = context->allocator;
    if (a.free)
        a.free(a.user, context);
    else
        free(context);
}
