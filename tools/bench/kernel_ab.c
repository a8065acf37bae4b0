/* kernel_ab.c — paired A/B timing of cache-lighting kernel versions (driven by tools/kernel_ab.sh).
 *
 * A shared VM's speed changes by up to 1.6x between windows of seconds, so two separate benchmark
 * runs of two kernels compare the windows more than the kernels. This harness links several
 * versions of runtime/src/cache_lighting.c into one process (each compiled in its own translation
 * unit with renamed symbols, see kernel_ab.sh), lights every cache of a bake with each version in
 * turn, alternating the order every iteration, and reports per version the min / p10 / median time
 * and the median of the per-iteration ratio to version 0 (both ran within a few ms of each other).
 * Node radiance is random (interleaved Y Co Cg pad, as the system lays it out); the outputs are
 * compared with version 0 (largest difference relative to |value| + 1e-3). With KAB_SUBSETS=1 in the
 * environment the links carry the bake's LSUB weights and random per-node ratios (the system's
 * case; versions older than link subsets ignore them, so compare such versions without it).
 *
 *   kernel_ab BAKE [ITERS=200] [THREADS=1] [LUMA=3] [CHROMA=LUMA]
 */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake/bake_format.h"
#include "glow/glow.h"
#include "runtime_internal.h"

typedef void (*run_fn)(const glow_bake_link_block *blocks, uint32_t bpc, const float *rad, uint32_t L, uint32_t C,
                       float *out, uint32_t first, uint32_t count);
#define X(n) void V##n##_run(const glow_bake_link_block *, uint32_t, const float *, uint32_t, uint32_t, float *, uint32_t, uint32_t);
VLIST
#undef X
/* VRUNS, when given, lists the functions to time instead (CMake's prebuilt harness times its one
 * compiled version twice: compiling the kernel once more took 1-2 min of each build) */
static const run_fn fns[] = {
#ifdef VRUNS
    VRUNS
#else
#define X(n) V##n##_run,
    VLIST
#undef X
#endif
};
enum { NV = sizeof fns / sizeof fns[0], MAXIT = 10000 };
const uint16_t *kab_subsets; /* read by the versions (tools/kernel_ab.sh's variant text) */
const uint32_t *kab_ratio;

typedef struct job {
    run_fn f;
    const glow_bake_link_block *blocks;
    uint32_t bpc, L, C, first, count;
    const float *rad;
    float *out;
} job;

static void *run_job(void *p) {
    const job *j = p;
    for (uint32_t c = j->first; c < j->first + j->count; c += 16u) /* the system's task size */
        j->f(j->blocks, j->bpc, j->rad, j->L, j->C, j->out, c, j->first + j->count - c < 16u ? j->first + j->count - c : 16u);
    return NULL;
}
static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}
static int cmp(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: kernel_ab BAKE [ITERS] [THREADS] [LUMA] [CHROMA]\n");
        return 2;
    }
    const int iters = argc > 2 ? atoi(argv[2]) : 200, threads = argc > 3 ? atoi(argv[3]) : 1;
    const uint32_t L = argc > 4 ? (uint32_t)atoi(argv[4]) : 3u, C = argc > 5 ? (uint32_t)atoi(argv[5]) : L;
    if (iters < 1 || iters > MAXIT || threads < 1 || threads > 64 || L < 1 || L > 8 || C < 1 || C > L) {
        fprintf(stderr, "kernel_ab: ITERS 1..%d, THREADS 1..64, 1 <= CHROMA <= LUMA <= 8\n", MAXIT);
        return 2;
    }
    glow_context *ctx;
    glow_bake *bake;
    glow_context_desc cd = {.api_version = GLOW_VERSION, .tasks = {.worker_count = 1}};
    if (glow_context_create(&cd, &ctx) != GLOW_OK || glow_bake_load_file(ctx, argv[1], &bake) != GLOW_OK) {
        fprintf(stderr, "kernel_ab: cannot load %s\n", argv[1]);
        return 1;
    }
    const glow_bake_meta *m = glow__bake_meta(bake);
    const uint32_t N = m->node_count, nc = L * L + 2 * C * C, caches = m->cache_count;
    float *rad = malloc((size_t)N * 4 * sizeof *rad), *out[NV];
    double *t = malloc(sizeof(double) * (size_t)iters * NV), *col = malloc(sizeof(double) * (size_t)iters),
           *ratio = malloc(sizeof(double) * (size_t)iters);
    if (!rad || !t || !col || !ratio) return 1;
    srand(1);
    for (uint32_t i = 0; i < N; ++i) {
        rad[4 * i] = (float)rand() / (float)RAND_MAX;
        rad[4 * i + 1] = rad[4 * i] * ((float)rand() / (float)RAND_MAX - 0.5f) * 0.4f;
        rad[4 * i + 2] = rad[4 * i] * ((float)rand() / (float)RAND_MAX - 0.5f) * 0.4f;
        rad[4 * i + 3] = 0.0f;
    }
    uint16_t *ratio_h = NULL;
    const char *ks = getenv("KAB_SUBSETS");
    if (ks && atoi(ks) == 1) {
        kab_subsets = glow__bake_link_subsets(bake);
        if (!kab_subsets) {
            fprintf(stderr, "kernel_ab: KAB_SUBSETS=1 but %s has no link subsets (LSUB)\n", argv[1]);
            return 1;
        }
        if (!(ratio_h = malloc((size_t)N * 4 * sizeof *ratio_h))) return 1;
        for (size_t i = 0; i < (size_t)N * 4; ++i) /* halves in [0.25, 2): normal, as the pull leaves them */
            ratio_h[i] = (uint16_t)(0x3400u + (uint32_t)(rand() % 0x0C00));
        kab_ratio = (const uint32_t *)(const void *)ratio_h;
    }
    for (int v = 0; v < NV; ++v)
        if (!(out[v] = calloc((size_t)caches * nc, sizeof(float)))) return 1;
    for (int it = 0; it < iters; ++it)
        for (int k = 0; k < NV; ++k) {
            const int v = (it & 1) ? NV - 1 - k : k;
            job j[64];
            pthread_t th[64];
            const double t0 = now_ms();
            for (int q = 0; q < threads; ++q) {
                const uint32_t a = (uint32_t)((uint64_t)caches * q / threads), b = (uint32_t)((uint64_t)caches * (q + 1) / threads);
                j[q] = (job){fns[v], glow__bake_link_blocks(bake), m->link_blocks_per_cache, L, C, a, b - a, rad, out[v]};
                if (q > 0 && pthread_create(&th[q], NULL, run_job, &j[q]) != 0) return 1;
            }
            run_job(&j[0]);
            for (int q = 1; q < threads; ++q) pthread_join(th[q], NULL);
            t[(size_t)it * NV + v] = now_ms() - t0;
        }
    printf("%u caches x %u links, l = %u/%u, %d thread(s), %d iterations%s\n", caches, m->links_per_cache, L, C, threads, iters,
           kab_subsets ? ", link subsets" : "");
    for (int v = 0; v < NV; ++v) {
        double worst = 0.0;
        for (size_t i = 0; i < (size_t)caches * nc; ++i) {
            const double d = out[v][i] - out[0][i], s = out[0][i] < 0.0f ? -out[0][i] : out[0][i];
            const double r = (d < 0 ? -d : d) / (s + 1e-3);
            if (r > worst) worst = r;
        }
        for (int it = 0; it < iters; ++it) {
            col[it] = t[(size_t)it * NV + v];
            ratio[it] = t[(size_t)it * NV + v] / t[(size_t)it * NV];
        }
        qsort(col, (size_t)iters, sizeof *col, cmp);
        qsort(ratio, (size_t)iters, sizeof *ratio, cmp);
        printf("version %d: min %.3f ms, p10 %.3f, median %.3f; ratio to version 0: median %.3f (p25 %.3f, p75 %.3f); "
               "max difference to version 0: %.2e\n",
               v, col[0], col[iters / 10], col[iters / 2], ratio[iters / 2], ratio[iters / 4], ratio[3 * iters / 4], worst);
    }
    for (int v = 0; v < NV; ++v) free(out[v]);
    free(ratio_h);
    free(rad);
    free(t);
    free(col);
    free(ratio);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    return 0;
}
