/* machine_probe.c — STREAM triad, FMA peak and core-to-core latency (see machine_probe.h). */
#include "machine_probe.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* ------------------------------------------------------------------------- triad */
typedef struct triad_arg {
    double *a, *b, *c;
    size_t begin, end;
    pthread_barrier_t *barrier;
    uint32_t reps;
    double *best; /* thread 0 only */
} triad_arg;

static void *triad_thread(void *p) {
    triad_arg *t = p;
    for (size_t i = t->begin; i < t->end; ++i) { /* first touch by the thread that uses it */
        t->a[i] = 0.0;
        t->b[i] = 1.0;
        t->c[i] = 2.0;
    }
    for (uint32_t r = 0; r < t->reps; ++r) {
        pthread_barrier_wait(t->barrier);
        double t0 = now_s();
        const double s = 3.0;
        double *restrict a = t->a;
        const double *restrict b = t->b, *restrict c = t->c;
        for (size_t i = t->begin; i < t->end; ++i) a[i] = b[i] + s * c[i];
        pthread_barrier_wait(t->barrier);
        double dt = now_s() - t0;
        if (t->best && (r == 0 || dt < *t->best)) *t->best = dt;
    }
    return NULL;
}

double glow_probe_stream_triad(uint32_t threads, size_t n, uint32_t reps) {
    if (threads < 1) threads = 1;
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
    triad_arg *args = calloc(threads, sizeof *args);
    pthread_t *th = calloc(threads, sizeof *th);
    if (!a || !b || !c || !args || !th) {
        free(a); free(b); free(c); free(args); free(th);
        return -1.0;
    }
    pthread_barrier_t barrier;
    pthread_barrier_init(&barrier, NULL, threads);
    double best = 0.0;
    for (uint32_t t = 0; t < threads; ++t) {
        args[t] = (triad_arg){a, b, c, n * t / threads, n * (t + 1) / threads, &barrier, reps, t == 0 ? &best : NULL};
        if (t > 0) pthread_create(&th[t], NULL, triad_thread, &args[t]);
    }
    triad_thread(&args[0]);
    for (uint32_t t = 1; t < threads; ++t) pthread_join(th[t], NULL);
    pthread_barrier_destroy(&barrier);
    volatile double sink = a[n / 2];
    (void)sink;
    free(a); free(b); free(c); free(args); free(th);
    return best > 0.0 ? 3.0 * 8.0 * (double)n / best * 1e-9 : -1.0;
}

/* ------------------------------------------------------------------------- FMA */
typedef float v8f __attribute__((vector_size(32)));

#define FMA_CHAINS 12
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
__attribute__((target("avx2,fma"))) static uint64_t fma_loop_avx2(uint64_t iters, float *out) {
    __m256 acc[FMA_CHAINS];
    const __m256 m = _mm256_set1_ps(0.999999f), add = _mm256_set1_ps(1e-7f);
    for (int k = 0; k < FMA_CHAINS; ++k) acc[k] = _mm256_set1_ps((float)k);
    for (uint64_t i = 0; i < iters; ++i)
        for (int k = 0; k < FMA_CHAINS; ++k) acc[k] = _mm256_fmadd_ps(acc[k], m, add);
    __m256 s = acc[0];
    for (int k = 1; k < FMA_CHAINS; ++k) s = _mm256_add_ps(s, acc[k]);
    float tmp[8];
    _mm256_storeu_ps(tmp, s);
    *out = tmp[0];
    return iters * FMA_CHAINS * 8u;
}
__attribute__((target("avx512f"))) static uint64_t fma_loop_avx512(uint64_t iters, float *out) {
    __m512 acc[FMA_CHAINS];
    const __m512 m = _mm512_set1_ps(0.999999f), add = _mm512_set1_ps(1e-7f);
    for (int k = 0; k < FMA_CHAINS; ++k) acc[k] = _mm512_set1_ps((float)k);
    for (uint64_t i = 0; i < iters; ++i)
        for (int k = 0; k < FMA_CHAINS; ++k) acc[k] = _mm512_fmadd_ps(acc[k], m, add);
    __m512 s = acc[0];
    for (int k = 1; k < FMA_CHAINS; ++k) s = _mm512_add_ps(s, acc[k]);
    *out = _mm512_reduce_add_ps(s);
    return iters * FMA_CHAINS * 16u;
}
#endif

static uint64_t fma_loop_generic(uint64_t iters, float *out) {
    float acc[FMA_CHAINS][8];
    for (int k = 0; k < FMA_CHAINS; ++k)
        for (int j = 0; j < 8; ++j) acc[k][j] = (float)k;
    for (uint64_t i = 0; i < iters; ++i)
        for (int k = 0; k < FMA_CHAINS; ++k)
            for (int j = 0; j < 8; ++j) acc[k][j] = acc[k][j] * 0.999999f + 1e-7f;
    *out = acc[0][0];
    return iters * FMA_CHAINS * 8u;
}

static int use_avx2(void) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    return 0;
#endif
}

typedef struct fma_arg {
    int avx512;
    uint64_t iters, fmas;
    float sink;
    pthread_barrier_t *barrier;
} fma_arg;

static void *fma_thread(void *p) {
    fma_arg *f = p;
    pthread_barrier_wait(f->barrier);
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (f->avx512) {
        f->fmas = fma_loop_avx512(f->iters, &f->sink);
        return NULL;
    }
    if (use_avx2()) {
        f->fmas = fma_loop_avx2(f->iters, &f->sink);
        return NULL;
    }
#endif
    f->fmas = fma_loop_generic(f->iters, &f->sink);
    return NULL;
}

static double fma_run(uint32_t threads, double ms, int avx512) {
    /* calibrate on one thread */
    fma_arg cal = {.avx512 = avx512, .iters = 100000};
    pthread_barrier_t one;
    pthread_barrier_init(&one, NULL, 1);
    cal.barrier = &one;
    double t0 = now_s();
    fma_thread(&cal);
    double dt = now_s() - t0;
    pthread_barrier_destroy(&one);
    uint64_t iters = (uint64_t)((double)cal.iters * (ms * 1e-3) / (dt > 1e-6 ? dt : 1e-6));
    if (iters < 1000) iters = 1000;
    fma_arg *args = calloc(threads, sizeof *args);
    pthread_t *th = calloc(threads, sizeof *th);
    if (!args || !th) {
        free(args); free(th);
        return -1.0;
    }
    pthread_barrier_t barrier;
    pthread_barrier_init(&barrier, NULL, threads + 1);
    for (uint32_t t = 0; t < threads; ++t) {
        args[t] = (fma_arg){.avx512 = avx512, .iters = iters, .barrier = &barrier};
        pthread_create(&th[t], NULL, fma_thread, &args[t]);
    }
    pthread_barrier_wait(&barrier);
    t0 = now_s();
    for (uint32_t t = 0; t < threads; ++t) pthread_join(th[t], NULL);
    dt = now_s() - t0;
    uint64_t fmas = 0;
    for (uint32_t t = 0; t < threads; ++t) fmas += args[t].fmas;
    pthread_barrier_destroy(&barrier);
    free(args); free(th);
    return 2.0 * (double)fmas / dt * 1e-9;
}

/* The best of the 8-lane (AVX2) and, where the CPU has it, 16-lane (AVX-512) FMA loops: the
 * cache-lighting kernel uses the widest the CPU has, so the peak it is measured against must too. */
double glow_probe_fma_peak(uint32_t threads, double ms, const char **isa) {
    if (threads < 1) threads = 1;
    double best = fma_run(threads, ms, 0);
    *isa = use_avx2() ? "avx2+fma (8 lanes, 12 chains)" : "generic";
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (__builtin_cpu_supports("avx512f")) {
        double w = fma_run(threads, ms, 1);
        if (w > best) {
            best = w;
            *isa = "avx512f (16 lanes, 12 chains)";
        }
    }
#endif
    return best;
}

/* ---------------------------------------------------------------------- line round trip */
typedef struct pingpong {
    _Alignas(64) atomic_uint turn; /* odd: the other thread's move */
    uint32_t rounds;
} pingpong;

static void *pong_thread(void *p) {
    pingpong *g = p;
    for (uint32_t i = 0; i < g->rounds; ++i) {
        while (atomic_load_explicit(&g->turn, memory_order_acquire) != 2u * i + 1u) {
        }
        atomic_store_explicit(&g->turn, 2u * i + 2u, memory_order_release);
    }
    return NULL;
}

double glow_probe_line_round_trip(uint32_t rounds) {
    double best = -1.0;
    for (int run = 0; run < 3; ++run) {
        pingpong g;
        atomic_init(&g.turn, 0u);
        g.rounds = rounds;
        pthread_t th;
        if (pthread_create(&th, NULL, pong_thread, &g) != 0) return -1.0;
        const double t0 = now_s();
        for (uint32_t i = 0; i < rounds; ++i) {
            atomic_store_explicit(&g.turn, 2u * i + 1u, memory_order_release);
            while (atomic_load_explicit(&g.turn, memory_order_acquire) != 2u * i + 2u) {
            }
        }
        const double dt = now_s() - t0;
        pthread_join(th, NULL);
        const double ns = dt / rounds * 1e9;
        if (best < 0.0 || ns < best) best = ns;
    }
    return best;
}
