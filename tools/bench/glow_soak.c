/* glow-soak — the runtime over a long run, the way a game drives it for hours (issue 15, item 4).
 *
 *   glow-soak BAKE [--updates N] [--seed S] [--every K] [--threads T] [--csv FILE] [-q]
 *
 * N updates (default 100000) of one system while its light moves, changes colour and switches off
 * and on, and an "artist" changes a random control every few updates: the bounce intensity, the
 * emission scale, bounce iterations, a material's emission and albedo scales, a bounce reset, a
 * frame that keeps the last lighting, and now and then an invalid value (NaN, negative, above
 * GLOW_MAX_SCALE), which must be refused with GLOW_ERROR_INVALID_ARGUMENT and change nothing.
 * The light is a point light without shadows (as samples/00_minimal_cpu), so the run measures the
 * runtime, not a host.
 *
 * Checked, and printed at the end:
 *   - every output of every update is finite (all caches' SH, every update);
 *   - drift: the converged outputs under one fixed state (light, controls) before the run and again
 *     after it must agree (max |difference| / max |value|, limit 1e-4): nothing accumulates;
 *   - resident memory (VmRSS) after the first K updates and at the end: the runtime allocates nothing
 *     per update, so it must not grow (limit 1 MiB, for the C library's own caches);
 *   - the median update time of each window of K updates (drift in speed).
 * --csv FILE writes one row per window: updates, median ms, RSS KiB, mean luma of the caches, refused
 * invalid calls so far. Exit: 0 all checks passed, 1 a check failed or a call failed, 2 usage. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "glow/glow.h"
#include "glow_cli.h"

typedef struct soak_light {
    float position[3], intensity[3]; /* W/sr, RGB; 0 = off */
} soak_light;

static glow_result light_surfels(void *user, const glow_surfel_batch *b, float *out, uint32_t worker) {
    (void)worker;
    const soak_light *l = user;
    for (uint32_t i = 0; i < b->count; ++i) {
        const float *p = b->positions + 4 * i, *n = b->normals + 4 * i;
        const float d[3] = {l->position[0] - p[0], l->position[1] - p[1], l->position[2] - p[2]};
        const float d2 = fmaxf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1e-4f);
        const float c = fmaxf((n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / sqrtf(d2), 0.0f);
        for (int k = 0; k < 3; ++k) out[3 * i + k] = l->intensity[k] * c / d2;
    }
    return GLOW_OK;
}

static uint64_t rng_state;
static uint32_t rng(void) { /* xorshift64* */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (uint32_t)((rng_state * 2685821657736338717ull) >> 32);
}
static float rngf(void) { return (float)(rng() >> 8) * (1.0f / 16777216.0f); }

static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

static long rss_kib(void) {
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return -1;
    char line[256];
    long kib = -1;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "VmRSS:", 6)) {
            kib = strtol(line + 6, NULL, 10);
            break;
        }
    fclose(f);
    return kib;
}


static void log_stderr(void *user, glow_log_level level, glow_result code, const char *msg, const char *file, int line) {
    (void)code, (void)file, (void)line;
    const int *quiet_invalid = user;
    /* the refused invalid calls are expected: their messages would flood the run */
    if (level <= GLOW_LOG_ERROR && !*quiet_invalid) fprintf(stderr, "glow: %s\n", msg);
}

static int usage(FILE *f, int code) {
    fprintf(f, "usage: glow-soak BAKE [--updates N] [--seed S] [--every K] [--threads T] [--csv FILE] [-q]\n"
               "  --updates N  updates in the run (default 100000)\n"
               "  --seed S     the light's path and the artist's changes (default 1)\n"
               "  --every K    a window of K updates per report and CSV row (default 1000)\n"
               "  --threads T  runtime workers (default: one per online CPU)\n"
               "  --csv FILE   one row per window\n");
    return code;
}


/* Converges the system under the fixed reference state and copies its caches' SH into `snap`. */
static glow_result converge(glow_system *sys, soak_light *light, const float ref_pos[3], uint32_t M, float *snap,
                            size_t n) {
    memcpy(light->position, ref_pos, sizeof light->position);
    light->intensity[0] = 20.0f, light->intensity[1] = 16.0f, light->intensity[2] = 12.0f;
    glow_system_params p = {.bounce_intensity = 1.0f, .emission_scale = 1.0f, .bounce_iterations = 1};
    glow_result r = glow_system_set_params(sys, &p);
    const float one[3] = {1, 1, 1};
    for (uint32_t m = 0; m < M && r == GLOW_OK; ++m) r = glow_system_set_material(sys, m, one, one);
    glow_update_desc reset = {.flags = GLOW_UPDATE_FLAG_RESET_BOUNCE};
    if (r == GLOW_OK) r = glow_system_update(sys, &reset);
    for (int i = 0; i < 200 && r == GLOW_OK; ++i) r = glow_system_update(sys, NULL);
    if (r == GLOW_OK) memcpy(snap, glow_system_outputs(sys)->cache_sh, n * sizeof *snap);
    return r;
}

int main(int argc, char **argv) {
    const char *bake_path = NULL, *csv_path = NULL;
    uint32_t updates = 100000, seed = 1, every = 1000, threads = 0;
    int quiet = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) return usage(stdout, 0);
        if (!strcmp(a, "-q")) quiet = 1;
        else if (a[0] == '-' && i + 1 >= argc) {
            fprintf(stderr, "glow-soak: %s needs a value\n", a);
            return usage(stderr, 2);
        } else if (!strcmp(a, "--updates")) {
            if (!glow_cli_u32(argv[++i], 1, 100000000, &updates)) return usage(stderr, 2);
        } else if (!strcmp(a, "--seed")) {
            if (!glow_cli_u32(argv[++i], 0, UINT32_MAX, &seed)) return usage(stderr, 2);
        } else if (!strcmp(a, "--every")) {
            if (!glow_cli_u32(argv[++i], 1, 1000000, &every)) return usage(stderr, 2);
        } else if (!strcmp(a, "--threads")) {
            if (!glow_cli_u32(argv[++i], 1, 256, &threads)) return usage(stderr, 2);
        } else if (!strcmp(a, "--csv")) {
            csv_path = argv[++i];
        } else if (a[0] == '-') {
            fprintf(stderr, "glow-soak: unknown option %s\n", a);
            return usage(stderr, 2);
        } else if (!bake_path) {
            bake_path = a;
        } else {
            return usage(stderr, 2);
        }
    }
    if (!bake_path) return usage(stderr, 2);
    rng_state = 0x9E3779B97F4A7C15ull ^ ((uint64_t)seed << 1 | 1u);

    int quiet_invalid = 0;
    glow_context *ctx = NULL;
    glow_bake *bake = NULL;
    glow_system *sys = NULL;
    glow_bake_info info;
    soak_light light = {{0, 0, 0}, {0, 0, 0}};
    glow_context_desc cd = {.api_version = GLOW_VERSION, .logger = {log_stderr, &quiet_invalid},
                            .tasks = {.worker_count = threads}};
    glow_result r = glow_context_create(&cd, &ctx);
    if (r == GLOW_OK) r = glow_bake_load_file(ctx, bake_path, &bake);
    if (r == GLOW_OK) r = glow_bake_get_info(bake, &info);
    glow_system_desc sd = {.bake = bake, .lighting = {light_surfels, &light}, .label = "soak"};
    if (r == GLOW_OK) r = glow_system_create(ctx, &sd, &sys);
    if (r != GLOW_OK) {
        fprintf(stderr, "glow-soak: %s: %s\n", bake_path, glow_result_string(r));
        glow_system_destroy(sys), glow_bake_destroy(bake), glow_context_destroy(ctx);
        return 1;
    }
    const glow_cache_outputs *o = glow_system_outputs(sys);
    const size_t n = (size_t)o->cache_count * o->coeff_count;
    const uint32_t M = info.material_count;
    float centre[3], ext[3];
    for (int k = 0; k < 3; ++k) {
        centre[k] = 0.5f * (info.bounds_min[k] + info.bounds_max[k]);
        ext[k] = 0.5f * (info.bounds_max[k] - info.bounds_min[k]);
    }
    const float ref_pos[3] = {centre[0] + 0.3f * ext[0], centre[1] + 0.5f * ext[1], centre[2] - 0.2f * ext[2]};
    float *before = malloc(n * sizeof *before), *after = malloc(n * sizeof *after);
    double *win = malloc((size_t)every * sizeof *win);
    FILE *csv = csv_path ? fopen(csv_path, "w") : NULL;
    if (!before || !after || !win || (csv_path && !csv)) {
        fprintf(stderr, "glow-soak: %s\n", csv_path && !csv ? "cannot write the CSV" : "out of memory");
        return 1;
    }
    if (csv) fprintf(csv, "updates,median_ms,rss_kib,mean_luma,refused\n");
    if ((r = converge(sys, &light, ref_pos, M, before, n)) != GLOW_OK) {
        fprintf(stderr, "glow-soak: converging before the run: %s\n", glow_result_string(r));
        return 1;
    }

    uint64_t nonfinite = 0, refused = 0, wrongly_accepted = 0, failed_calls = 0;
    long rss_first = -1, rss_max = 0, rss_last = 0;
    double med_first = 0.0, med_last = 0.0;
    uint32_t iters_last = 1;
    uint32_t on = 1;
    float colour[3] = {1, 1, 1};
    for (uint32_t u = 0; u < updates; ++u) {
        /* the light: an orbit around the scene's centre at a changing height; colour drifts; off now and then */
        const float t = (float)u * 0.013f;
        light.position[0] = centre[0] + 0.6f * ext[0] * cosf(t);
        light.position[1] = centre[1] + 0.6f * ext[1] * sinf(0.37f * t);
        light.position[2] = centre[2] + 0.6f * ext[2] * sinf(t);
        if (rng() % 500 == 0) on = !on;
        if (rng() % 50 == 0)
            for (int k = 0; k < 3; ++k) colour[k] = 0.2f + rngf();
        for (int k = 0; k < 3; ++k) light.intensity[k] = on ? 20.0f * colour[k] : 0.0f;
        /* the artist */
        uint32_t flags = 0;
        switch (rng() % 16) {
        case 0: {
            glow_system_params p = {.bounce_intensity = rngf(), .emission_scale = 2.0f * rngf(),
                                    .bounce_iterations = 1 + rng() % 3};
            failed_calls += glow_system_set_params(sys, &p) != GLOW_OK;
            break;
        }
        case 1:
            if (M) {
                const float e[3] = {2.0f * rngf(), 2.0f * rngf(), 2.0f * rngf()}, a[3] = {rngf() * 1.5f, rngf() * 1.5f, rngf() * 1.5f};
                failed_calls += glow_system_set_material(sys, rng() % M, e, a) != GLOW_OK;
            }
            break;
        case 2: { /* invalid: must be refused and change nothing */
            glow_system_params before_p, after_p;
            glow_system_get_params(sys, &before_p);
            glow_system_params bad = before_p;
            const uint32_t which = rng() % 4;
            if (which == 0) bad.emission_scale = NAN;
            else if (which == 1) bad.bounce_intensity = -1.0f;
            else if (which == 2) bad.emission_scale = 2.0f * GLOW_MAX_SCALE;
            else bad.bounce_iterations = 65; /* above the 64 limit (0 is the default, 1) */
            quiet_invalid = 1;
            const glow_result br = glow_system_set_params(sys, &bad);
            quiet_invalid = 0;
            glow_system_get_params(sys, &after_p);
            if (br == GLOW_ERROR_INVALID_ARGUMENT && !memcmp(&before_p, &after_p, sizeof before_p)) refused++;
            else wrongly_accepted++;
            break;
        }
        case 3:
            if (M) {
                const float bad[3] = {1.0f, NAN, 1.0f}, ok[3] = {1, 1, 1};
                quiet_invalid = 1;
                const int which = (int)(rng() % 2); /* one of the two scales is bad */
                const glow_result br = glow_system_set_material(sys, rng() % M, which ? bad : ok, which ? ok : bad);
                const glow_result br2 = glow_system_set_material(sys, M, ok, ok); /* out of range */
                quiet_invalid = 0;
                if (br == GLOW_ERROR_INVALID_ARGUMENT && br2 == GLOW_ERROR_INVALID_ARGUMENT) refused++;
                else wrongly_accepted++;
            }
            break;
        case 4:
            if (rng() % 8 == 0) flags |= GLOW_UPDATE_FLAG_RESET_BOUNCE;
            break;
        case 5:
            flags |= GLOW_UPDATE_FLAG_KEEP_LIGHTING;
            break;
        default:
            break;
        }
        glow_update_desc ud = {.flags = flags};
        const double t0 = now_ms();
        r = glow_system_update(sys, &ud);
        win[u % every] = now_ms() - t0;
        if (r != GLOW_OK) {
            fprintf(stderr, "glow-soak: update %u: %s\n", u, glow_result_string(r));
            failed_calls++;
            break;
        }
        const float *sh = o->cache_sh;
        uint64_t bad_here = 0;
        for (size_t i = 0; i < n; ++i) bad_here += !isfinite(sh[i]);
        nonfinite += bad_here;
        if ((u + 1) % every == 0 || u + 1 == updates) {
            const uint32_t w = (u % every) + 1;
            qsort(win, w, sizeof *win, glow_cli_cmp_double);
            const double med = win[w / 2];
            const long rss = rss_kib();
            double luma = 0.0;
            for (uint32_t c = 0; c < o->cache_count; ++c) luma += sh[(size_t)c * o->coeff_count];
            luma /= o->cache_count ? o->cache_count : 1u;
            if (rss_first < 0) rss_first = rss, med_first = med;
            if (rss > rss_max) rss_max = rss;
            rss_last = rss;
            med_last = med;
            glow_system_params pp;
            glow_system_get_params(sys, &pp);
            iters_last = pp.bounce_iterations;
            if (csv) fprintf(csv, "%u,%.4f,%ld,%.6g,%llu\n", u + 1, med, rss, luma, (unsigned long long)refused);
            if (!quiet && ((u + 1) % (every * 10) == 0 || u + 1 == updates))
                printf("  %9u updates: median %.3f ms, RSS %ld KiB, mean luma %.4g, non-finite %llu\n", u + 1, med,
                       rss, luma, (unsigned long long)nonfinite);
        }
    }
    if (r == GLOW_OK && (r = converge(sys, &light, ref_pos, M, after, n)) != GLOW_OK)
        fprintf(stderr, "glow-soak: converging after the run: %s\n", glow_result_string(r));
    double dmax = 0.0, vmax = 0.0;
    for (size_t i = 0; i < n; ++i) {
        dmax = fmax(dmax, fabs((double)after[i] - before[i]));
        vmax = fmax(vmax, fabs((double)before[i]));
    }
    const double drift = vmax > 0.0 ? dmax / vmax : dmax;
    const long growth = rss_last - rss_first;
    const int ok = r == GLOW_OK && nonfinite == 0 && wrongly_accepted == 0 && failed_calls == 0 && drift <= 1e-4 &&
                   growth <= 1024;
    printf("glow-soak %s: %u updates, %u caches x %u coeffs, %u materials\n", bake_path, updates, o->cache_count,
           o->coeff_count, M);
    printf("  non-finite outputs      %llu\n", (unsigned long long)nonfinite);
    printf("  invalid calls refused   %llu (accepted or changed state: %llu); failed valid calls %llu\n",
           (unsigned long long)refused, (unsigned long long)wrongly_accepted, (unsigned long long)failed_calls);
    printf("  drift                   %.3g (max |converged after - before| / max |before|, limit 1e-4)\n", drift);
    printf("  RSS                     %ld KiB after the first window, %ld at the end, max %ld (growth %ld KiB, limit 1024)\n",
           rss_first, rss_last, rss_max, growth);
    printf("  update median           %.3f ms in the first window, %.3f in the last (the artist sets 1 to 3 bounce\n"
           "                          iterations per update; %u at the end of the last window)\n",
           med_first, med_last, iters_last);
    printf("glow-soak: %s\n", ok ? "all checks passed" : "FAILED");
    if (csv) fclose(csv);
    free(before), free(after), free(win);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    return ok ? 0 : 1;
}
