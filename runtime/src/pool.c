/* pool.c — the built-in worker pool behind glow_task_hooks, used when the host gives no
 * parallel_for of its own (DESIGN §4: "the host's job system runs Glow's work if it wants to").
 *
 * One pool per context. glow__taskpool_run gives each worker a contiguous share of the task indices
 * (worker w: [w count / T, (w + 1) count / T)), claimed through an atomic counter per share; a worker
 * that finishes its share takes indices from the others' (work stealing, so a descheduled worker
 * costs little). The shares keep the same data on the same core from stage to stage and update to
 * update when the workers keep pace: surfel batch b of the lighting hook and surfel chunk b of the
 * flux, and the cache rows a worker gathered last update. On the 2-core VMs this project measures
 * on, a cache line written by one core costs the other about 235 ns to read (a 470 ns ping-pong
 * round trip), and a single shared counter scattered every stage's work over both. Which worker
 * runs an index still varies from run to run, so callers must make every index compute the same
 * bytes whoever runs it (they write disjoint outputs and never reduce across indices in completion
 * order): results are bit-identical for any worker count (tested).
 *
 * Wake-up latency matters at a 3 ms frame budget: workers spin briefly on the job generation
 * before they sleep on the condition variable, so back-to-back stages of one update do not pay a
 * futex round trip each. Concurrent callers (two systems updating on two threads) are serialised
 * by `submit`: correct, not maximally parallel; hosts that want more pass their own scheduler. */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <unistd.h>

#include "runtime_internal.h"

/* one worker's share of a job's indices: next claimed index and end, a cache line of its own */
typedef struct pool_share {
    _Alignas(64) atomic_uint next;
    uint32_t end;
} pool_share;

typedef struct pool_job {
    glow_task_fn fn;
    void *data;
    uint32_t shares;     /* the pool's threads (1: the serial path) */
    pool_share *share;   /* [shares] */
} pool_job;

struct glow__taskpool {
    glow_context *ctx;
    uint32_t threads; /* including the calling thread (worker 0) */
    pthread_t *workers;
    pthread_mutex_t submit; /* one job at a time */
    pthread_mutex_t mutex;
    pthread_cond_t wake, finished;
    pool_job *current;
    pool_share *share; /* [threads], reused by every job (one job at a time) */
    atomic_ulong generation;
    atomic_uint active; /* workers still inside the current job */
    atomic_bool quit;
};

typedef struct worker_arg {
    struct glow__taskpool *pool;
    uint32_t index;
} worker_arg;

/* the worker's own share first, then the others' in turn */
static void run_job(pool_job *j, uint32_t worker) {
    for (uint32_t i = 0; i < j->shares; ++i) {
        pool_share *sh = &j->share[(worker + i) % j->shares];
        for (;;) {
            const uint32_t k = atomic_fetch_add_explicit(&sh->next, 1u, memory_order_relaxed);
            if (k >= sh->end) break;
            j->fn(j->data, k, worker);
        }
    }
}

static void *worker_main(void *p) {
    worker_arg *a = p;
    struct glow__taskpool *pool = a->pool;
    uint32_t index = a->index;
    unsigned long seen = 0;
    for (;;) {
        /* spin a little, then sleep */
        unsigned long g = atomic_load_explicit(&pool->generation, memory_order_acquire);
        for (int spin = 0; g == seen && spin < 20000 && !atomic_load(&pool->quit); ++spin)
            g = atomic_load_explicit(&pool->generation, memory_order_acquire);
        if (g == seen) {
            pthread_mutex_lock(&pool->mutex);
            while ((g = atomic_load(&pool->generation)) == seen && !atomic_load(&pool->quit))
                pthread_cond_wait(&pool->wake, &pool->mutex);
            pthread_mutex_unlock(&pool->mutex);
        }
        if (atomic_load(&pool->quit)) break;
        seen = g;
        pool_job *j = pool->current; /* published before generation (release) */
        if (j) run_job(j, index);
        if (atomic_fetch_sub_explicit(&pool->active, 1u, memory_order_acq_rel) == 1u) {
            pthread_mutex_lock(&pool->mutex);
            pthread_cond_signal(&pool->finished);
            pthread_mutex_unlock(&pool->mutex);
        }
    }
    return NULL;
}

uint32_t glow__online_cpus(void) {
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1u : (n > 256 ? 256u : (uint32_t)n);
}

glow_result glow__taskpool_create(glow_context *ctx, uint32_t threads, glow__taskpool **out) {
    *out = NULL;
    if (threads == 0) threads = glow__online_cpus();
    struct glow__taskpool *pool = glow__ctx_alloc_uncounted(ctx, sizeof *pool, 0);
    if (!pool) return GLOW_ERROR_OUT_OF_MEMORY;
    *pool = (struct glow__taskpool){.ctx = ctx, .threads = threads};
    atomic_init(&pool->generation, 0u);
    atomic_init(&pool->active, 0u);
    atomic_init(&pool->quit, false);
    pthread_mutex_init(&pool->submit, NULL);
    pthread_mutex_init(&pool->mutex, NULL);
    pthread_cond_init(&pool->wake, NULL);
    pthread_cond_init(&pool->finished, NULL);
    if (threads > 1) {
        pool->workers = glow__ctx_alloc_uncounted(ctx, (threads - 1) * (sizeof(pthread_t) + sizeof(worker_arg)), 0);
        pool->share = glow__ctx_alloc_uncounted(ctx, threads * sizeof(pool_share), _Alignof(pool_share));
        if (!pool->workers || !pool->share) {
            glow__taskpool_destroy(pool);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        worker_arg *args = (worker_arg *)(pool->workers + (threads - 1));
        for (uint32_t i = 0; i + 1 < threads; ++i) {
            args[i] = (worker_arg){pool, i + 1};
            if (pthread_create(&pool->workers[i], NULL, worker_main, &args[i]) != 0) {
                pool->threads = i + 1; /* the ones that started */
                GLOW__LOG_WARNING(ctx, GLOW_ERROR_OUT_OF_MEMORY,
                                  "thread pool: could not start thread %u of %u; running with %u", i + 2, threads,
                                  i + 1);
                break;
            }
        }
    }
    *out = pool;
    return GLOW_OK;
}

void glow__taskpool_destroy(glow__taskpool *pool) {
    if (!pool) return;
    if (pool->workers) {
        pthread_mutex_lock(&pool->mutex);
        atomic_store(&pool->quit, true);
        pthread_cond_broadcast(&pool->wake);
        pthread_mutex_unlock(&pool->mutex);
        for (uint32_t i = 0; i + 1 < pool->threads; ++i) pthread_join(pool->workers[i], NULL);
        glow__ctx_free_uncounted(pool->ctx, pool->workers);
    }
    if (pool->share) glow__ctx_free_uncounted(pool->ctx, pool->share);
    pthread_cond_destroy(&pool->finished);
    pthread_cond_destroy(&pool->wake);
    pthread_mutex_destroy(&pool->mutex);
    pthread_mutex_destroy(&pool->submit);
    glow__ctx_free_uncounted(pool->ctx, pool);
}

uint32_t glow__taskpool_threads(const glow__taskpool *pool) { return pool ? pool->threads : 1u; }

void glow__taskpool_run(glow__taskpool *pool, glow_task_fn fn, void *data, uint32_t count) {
    if (count == 0) return;
    if (!pool || pool->threads <= 1 || count == 1) {
        for (uint32_t k = 0; k < count; ++k) fn(data, k, 0);
        return;
    }
    pthread_mutex_lock(&pool->submit);
    pool_job j = {.fn = fn, .data = data, .shares = pool->threads, .share = pool->share};
    for (uint32_t w = 0; w < pool->threads; ++w) { /* the workers wait on generation: not yet reading */
        atomic_store_explicit(&pool->share[w].next, (uint32_t)((uint64_t)count * w / pool->threads), memory_order_relaxed);
        pool->share[w].end = (uint32_t)((uint64_t)count * (w + 1u) / pool->threads);
    }
    atomic_store(&pool->active, pool->threads - 1);
    pool->current = &j;
    pthread_mutex_lock(&pool->mutex);
    atomic_fetch_add_explicit(&pool->generation, 1u, memory_order_release);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->mutex);
    run_job(&j, 0);
    /* wait for the workers to leave the job (they may still be claiming past the end) */
    for (int spin = 0; atomic_load_explicit(&pool->active, memory_order_acquire) != 0 && spin < 200000; ++spin) {
    }
    if (atomic_load_explicit(&pool->active, memory_order_acquire) != 0) {
        pthread_mutex_lock(&pool->mutex);
        while (atomic_load(&pool->active) != 0) pthread_cond_wait(&pool->finished, &pool->mutex);
        pthread_mutex_unlock(&pool->mutex);
    }
    pool->current = NULL;
    pthread_mutex_unlock(&pool->submit);
}
