/* pool.c — a small pthread pool for the linker's parallel loops.
 *
 * glow__parallel_for hands out fixed ranges [k*grain, (k+1)*grain) through an atomic counter.
 * Which worker runs a range varies; what a range computes must not depend on it (callers write
 * per-item results, never order-dependent reductions), so results are identical for any thread
 * count. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

#include "pc_internal.h"

typedef struct job {
    glow__range_fn fn;
    void *ctx;
    uint32_t count, grain;
    atomic_uint next;
    atomic_uint done_workers;
} job;

struct glow__pool {
    uint32_t threads;
    pthread_t *workers;
    pthread_mutex_t mutex;
    pthread_cond_t wake, finished;
    job *current;
    uint64_t generation;
    uint32_t active;
    bool quit;
};

static void run_job(job *j, uint32_t worker) {
    for (;;) {
        uint32_t k = atomic_fetch_add(&j->next, 1u);
        uint64_t begin = (uint64_t)k * j->grain;
        if (begin >= j->count) break;
        uint64_t end = begin + j->grain;
        if (end > j->count) end = j->count;
        j->fn(j->ctx, (uint32_t)begin, (uint32_t)end, worker);
    }
}

typedef struct worker_arg {
    glow__pool *pool;
    uint32_t index;
} worker_arg;

static void *worker_main(void *p) {
    worker_arg *arg = p;
    glow__pool *pool = arg->pool;
    uint32_t index = arg->index;
    free(arg);
    uint64_t seen = 0;
    pthread_mutex_lock(&pool->mutex);
    for (;;) {
        while (!pool->quit && pool->generation == seen) pthread_cond_wait(&pool->wake, &pool->mutex);
        if (pool->quit) break;
        seen = pool->generation;
        job *j = pool->current;
        pthread_mutex_unlock(&pool->mutex);
        run_job(j, index);
        pthread_mutex_lock(&pool->mutex);
        if (--pool->active == 0) pthread_cond_signal(&pool->finished);
    }
    pthread_mutex_unlock(&pool->mutex);
    return NULL;
}

glow__pool *glow__pool_create(uint32_t threads) {
    if (threads == 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        threads = n > 0 ? (uint32_t)n : 1u;
    }
    if (threads > 256) threads = 256;
    glow__pool *pool = calloc(1, sizeof *pool);
    if (!pool) return NULL;
    pool->threads = threads;
    pthread_mutex_init(&pool->mutex, NULL);
    pthread_cond_init(&pool->wake, NULL);
    pthread_cond_init(&pool->finished, NULL);
    if (threads > 1) {
        pool->workers = calloc(threads - 1, sizeof *pool->workers);
        if (!pool->workers) {
            glow__pool_destroy(pool);
            return NULL;
        }
        for (uint32_t i = 0; i + 1 < threads; ++i) {
            worker_arg *arg = malloc(sizeof *arg);
            if (!arg) { pool->threads = i + 1; break; }
            arg->pool = pool;
            arg->index = i + 1;
            if (pthread_create(&pool->workers[i], NULL, worker_main, arg) != 0) {
                free(arg);
                pool->threads = i + 1;
                break;
            }
        }
    }
    return pool;
}

void glow__pool_destroy(glow__pool *pool) {
    if (!pool) return;
    pthread_mutex_lock(&pool->mutex);
    pool->quit = true;
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->mutex);
    if (pool->workers)
        for (uint32_t i = 0; i + 1 < pool->threads; ++i) pthread_join(pool->workers[i], NULL);
    free(pool->workers);
    pthread_mutex_destroy(&pool->mutex);
    pthread_cond_destroy(&pool->wake);
    pthread_cond_destroy(&pool->finished);
    free(pool);
}

uint32_t glow__pool_threads(const glow__pool *pool) { return pool ? pool->threads : 1u; }

void glow__parallel_for(glow__pool *pool, uint32_t count, uint32_t grain, glow__range_fn fn, void *ctx) {
    if (count == 0) return;
    uint32_t threads = glow__pool_threads(pool);
    if (grain == 0) {
        grain = count / (threads * 16u);
        if (grain == 0) grain = 1;
    }
    job j = {.fn = fn, .ctx = ctx, .count = count, .grain = grain};
    atomic_init(&j.next, 0u);
    atomic_init(&j.done_workers, 0u);
    if (threads <= 1 || count <= grain) {
        run_job(&j, 0);
        return;
    }
    pthread_mutex_lock(&pool->mutex);
    pool->current = &j;
    pool->active = threads - 1;
    pool->generation++;
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->mutex);
    run_job(&j, 0);
    pthread_mutex_lock(&pool->mutex);
    while (pool->active > 0) pthread_cond_wait(&pool->finished, &pool->mutex);
    pool->current = NULL;
    pthread_mutex_unlock(&pool->mutex);
}
