/* fuzz_bake_solver.c — libFuzzer target: "load + 3 updates" (issue 15, D10).
 *
 * The input is loaded with every CRC recomputed (as fuzz_bake_reader's second pass does, so the
 * mutations reach the content checks). When the reader accepts it, a system is created on it, lit
 * by a hook whose irradiance comes from the input's last bytes (finite and within
 * GLOW_MAX_IRRADIANCE, as the runtime demands), updated three times, and every published output
 * must be finite: abort() otherwise. A bake the reader accepts may not make the solver produce NaN
 * or Inf (the reader checks every float's domain for exactly this).
 * The solver (system.c, cache_lighting.c) is compiled without the fuzzer's instrumentation
 * (tests/fuzz/CMakeLists.txt: its unrolled kernels take minutes to build instrumented); the reader
 * is instrumented and guides the search. Seed corpus: the bakes in tests/data. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/bake_format.h"
#include "glow/glow.h"
#include "runtime_internal.h"
#include "fuzz_reseal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);


typedef struct light {
    float e[3]; /* W/m², from the input */
} light;

static glow_result hook(void *user, const glow_surfel_batch *b, float *out, uint32_t worker) {
    (void)worker;
    const light *l = user;
    for (uint32_t i = 0; i < b->count; i++)
        for (int k = 0; k < 3; k++) out[3 * (size_t)i + k] = l->e[k] * (0.5f + 0.5f * b->normals[4 * (size_t)i + 1]);
    return GLOW_OK;
}

/* GLOW_FUZZ_LOG=1: the runtime's messages on stderr (to see why an accepted bake did not update) */
static void log_stderr(void *user, glow_log_level level, glow_result code, const char *message, const char *file,
                       int line) {
    (void)user;
    (void)level;
    (void)file;
    (void)line;
    fprintf(stderr, "glow (%d): %s\n", (int)code, message);
}

static void check_finite(const float *p, uint64_t n) {
    if (!p) return;
    for (uint64_t i = 0; i < n; i++)
        if (!isfinite(p[i])) abort();
}

/* inputs the reader accepted and that got three updates: printed at exit, so a run shows it reached
 * the solver at all */
static uint64_t solved, loaded;
static void report(void) { fprintf(stderr, "fuzz_bake_solver: %llu inputs loaded, %llu of them updated 3 times\n",
                                   (unsigned long long)loaded, (unsigned long long)solved); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static int once;
    if (!once) {
        once = 1;
        atexit(report);
    }
    if (size < 64 || size > (64u << 20)) return 0;
    uint8_t *img = malloc(size);
    if (!img) return 0;
    memcpy(img, data, size);
    fuzz_fix_crcs(img, size);
    glow_context_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.api_version = GLOW_VERSION;
    desc.tasks.worker_count = 1;
    if (getenv("GLOW_FUZZ_LOG")) desc.logger.log = log_stderr;
    glow_context *ctx = NULL;
    if (glow_context_create(&desc, &ctx) != GLOW_OK) abort();
    glow_bake *bake = NULL;
    if (glow_bake_load(ctx, img, size, &bake) == GLOW_OK) {
        loaded++;
        light l;
        for (int k = 0; k < 3; k++) { /* 0 .. 2e4 W/m² from the last bytes */
            uint8_t v = data[size - 1 - (size_t)k];
            l.e[k] = (float)v * (2e4f / 255.0f);
        }
        glow_system *sys = NULL;
        glow_system_desc sd = {.bake = bake, .lighting = {.light_surfels = hook, .user = &l}};
        if (glow_system_create(ctx, &sd, &sys) == GLOW_OK) {
            glow_system_params p = GLOW_SYSTEM_PARAMS_INIT;
            glow_system_set_params(sys, &p);
            int u = 0;
            for (; u < 3; u++) {
                if (glow_system_update(sys, NULL) != GLOW_OK) break;
                const glow_cache_outputs *o = glow_system_outputs(sys);
                check_finite(o->cache_sh, (uint64_t)o->cache_count * o->coeff_count);
                check_finite(o->grid_sh,
                             (uint64_t)o->coeff_count * o->grid_dims[0] * o->grid_dims[1] * o->grid_dims[2]);
                check_finite(o->lightmap_sh,
                             (uint64_t)o->coeff_count * o->lightmap_width * o->lightmap_height * o->lightmap_pages);
            }
            solved += u == 3;
            glow_system_destroy(sys);
        }
        glow_bake_destroy(bake);
    }
    glow_context_destroy(ctx);
    free(img);
    return 0;
}
