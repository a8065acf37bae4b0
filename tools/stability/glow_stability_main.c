/* glow-stability — measurements of the stability suite that are charts, not pass/fail (issue 4):
 *
 *   glow-stability ringing BAKE SCENE.json [--bands-max L] [--dirs N] [--json]
 *   glow-stability flicker BAKE SCENE.json [--frames N] [--iterations K] [--probes P] [--samples S] [--csv FILE]
 *   glow-stability jumps   BAKE SCENE.json [--pairs P] [--samples S] [--csv FILE]
 *
 * SH ringing: for l = 2 .. min(L, the bake's bands) the runtime is converged (luma = chroma = l,
 * multi-bounce, the scene's lights through the exact host) and every cache's radiance is evaluated in
 * N Fibonacci directions (grid caches: the sphere; lightmap caches: the hemisphere above their
 * normal, the only directions a surface can receive from). Reported per l: the share of
 * (cache, direction) pairs whose RGB radiance has a channel below zero, the same with the
 * Lanczos window of glow_sh_window_factor applied to the bands, and the share of lightmap caches
 * whose diffuse-shaded irradiance (what a surface shows) is negative, without and with the window.
 * A pair counts as negative when a channel is below -1e-6 of the cache's mean luma (so exact zeros
 * in unlit caches do not count).
 *
 * Flicker: the scene's first light (point or spot) moves once around a horizontal circle (radius 15 %
 * of the scene's diagonal, centred on its position: keep it clear of walls) in N frames; Glow runs K feedback iterations per
 * frame (progressive, as an engine would; converged before frame 0), the reference estimates the same
 * irradiance at P lightmap caches per frame with glow_render_irradiance and the same random numbers
 * every frame (correlated). Per frame: mean over the probes of |E(f) - E(f-1)| / mean E, for both;
 * the summary compares Glow's frame-to-frame change with the reference's.
 *
 * Jumps (link-cut discontinuities): Glow converged with the scene's lights; P pairs of neighbouring
 * lightmap texels (adjacent in the lightmap, caches within 2.5 texel spacings in space, normals within
 * 25 degrees); per pair the jump |E_a - E_b| (luma) from Glow's caches and from the reference (the pair
 * shares its random numbers). Reports the largest and 99th-percentile jumps relative to the mean
 * irradiance, Glow against the reference.
 *
 * Audit (where the indirect energy goes): P lightmap caches, spread over the cache list; at each, Glow's
 * irradiance along the cache normal against the reference's (glow_render_irradiance, S paths), twice:
 * single bounce (Glow: one update without feedback; reference: paths of one reflection, max depth 3)
 * and converged (multi-bounce against full paths). Reports Glow / reference of the summed irradiance,
 * the relative RMS error over caches, the per-cache ratio's 5th/50th/95th percentiles and the caches
 * off by more than 1.5x either way, and a histogram of the caches' visible solid angle (Σ over
 * their links). The cache gather alone: no lightmap interpolation, no camera. The single-bounce pass
 * matches only for scenes lit by host lights: with emissive surfaces the reference's paths also
 * count the emitters' light after one reflection, which Glow's caches receive one update later.
 *
 * Also the same at area-uniform points (the bake's surfels: Glow's feedback irradiance for the next
 * bounce), and with --radiance-out FILE the surfels' single-bounce radiance (luma, float32, surfel
 * order) for glow-bake --audit-radiance, which splits the gather error into the cut's share and the
 * rest (docs/results.md).
 *
 * Exit 0, 1 on a failure (the message names the file), 2 bad usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glow_cli.h"
#include "glow/glow.h"
#include "glow/glow_backend.h"
#include "glow/glow_host.h"
#include "glow/glow_scene.h"
#include "glow_render.h"
#include "glow_tool_json.h"
#include "bake_format.h" /* the link block layout (audit: visible solid angle), the format seam */

#define PI_D 3.14159265358979323846

static uint32_t g_surfel_samples; /* --surfel-samples: the exact host's footprint points (0 = its default) */

static int usage(FILE *f) {
    fprintf(f, "usage: glow-stability ringing BAKE SCENE.json [--bands-max L] [--dirs N] [--json]\n"
               "       glow-stability flicker BAKE SCENE.json [--frames N] [--iterations K] [--probes P] [--samples S]\n"
               "                              [--budget-caches N]\n"
               "                              [--csv FILE]\n"
               "       glow-stability jumps   BAKE SCENE.json [--pairs P] [--samples S] [--csv FILE]\n"
               "       glow-stability audit   BAKE SCENE.json [--probes P] [--samples S] [--csv FILE] [--json]\n"
               "                              [--radiance-out FILE] [--caches I,J,...]\n"
               "  every command: [--surfel-samples K] the exact host's shadow-ray points per surfel, 1..8 (default 8)\n"
               "  audit --caches: only these lightmap caches (output cache indices, e.g. glow-compare\n"
               "  --texels' blotch report or the B channel of glow-render's PREFIX_texel.exr minus 1)\n"
               "Share of negative radiance in Glow's converged caches for SH bands 2..L, with and without\n"
               "the Lanczos window (glow_sh_window_factor); see docs/results.md.\n");
    return f == stdout ? 0 : 2;
}


typedef struct counts {
    double pairs, neg, neg_w;            /* (cache, direction) pairs */
    double lm, lm_neg_irr, lm_neg_irr_w; /* lightmap caches, diffuse irradiance */
    double worst, worst_w;               /* most negative radiance relative to the cache's mean luma */
} counts;

static void radiance(const float *c, uint32_t L, const float *y, const float *win, float rgb[3]) {
    float ycc[3] = {0, 0, 0};
    const float *co = c + L * L, *cg = co + L * L;
    for (uint32_t l = 0; l < L; ++l)
        for (uint32_t q = l * l; q < (l + 1) * (l + 1); ++q) {
            const float w = win ? win[l] : 1.0f;
            ycc[0] += w * c[q] * y[q];
            ycc[1] += w * co[q] * y[q];
            ycc[2] += w * cg[q] * y[q];
        }
    glow_ycocg_to_rgb(ycc, rgb);
}

static int ringing(const char *bake_path, const char *scene_path, uint32_t lmax, uint32_t ndirs, int json) {
    cJSON *jrows = NULL; /* --json: one object per band count, printed at the end */
    static glow_cli_log log_state = {"glow-stability", 0};
    glow_logger lg = glow_cli_logger(&log_state);
    glow_scene_desc scene;
    char msg[512];
    if (glow_scene_load(scene_path, &lg, &scene, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s\n", msg);
        return 1;
    }
    glow_context *ctx = NULL;
    glow_bake *bake = NULL;
    glow_host *host = NULL;
    int rc = 1;
    float *dirs = malloc(sizeof(float) * 3 * ndirs);
    if (!dirs) goto done;
    for (uint32_t i = 0; i < ndirs; ++i) { /* Fibonacci sphere */
        double z = 1.0 - (2.0 * i + 1.0) / ndirs, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = i * PI_D * (3.0 - sqrt(5.0));
        dirs[3 * i] = (float)(r * cos(phi));
        dirs[3 * i + 1] = (float)(r * sin(phi));
        dirs[3 * i + 2] = (float)z;
    }
    if (glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION, .logger = lg}, &ctx) != GLOW_OK) goto done;
    if (glow_bake_load_file(ctx, bake_path, &bake) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s: cannot load the bake\n", bake_path);
        goto done;
    }
    glow_bake_info info;
    glow_bake_get_info(bake, &info);
    glow_host_desc hd = glow_host_desc_from_scene(&scene, bake, GLOW_HOST_KIND_EXACT);
    hd.logger = lg;
    hd.surfel_samples = g_surfel_samples;
    if (glow_host_create(&hd, &host) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s: cannot create the host\n", bake_path);
        goto done;
    }
    if (lmax > info.sh_bands) lmax = info.sh_bands;
    if (json) jrows = cJSON_CreateArray();
    else
        printf("%s (%u caches, bake bands %u), %u directions\n"
               "bands  negative radiance (pairs)  windowed   worst (x mean luma)  windowed   lightmap irradiance < 0  windowed\n",
               bake_path, info.cache_count, info.sh_bands, ndirs);
    for (uint32_t L = 2; L <= lmax; ++L) {
        glow_system *sys;
        if (glow_system_create(ctx, &(glow_system_desc){.bake = bake, .lighting = glow_host_hooks(host),
                                                          .sh_bands_luma = L, .sh_bands_chroma = L},
                               &sys) != GLOW_OK)
            goto done;
        glow_system_set_params(sys, &(glow_system_params){.bounce_intensity = 1.0f,
                                                          .emission_scale = scene.emission_scale,
                                                          .bounce_iterations = 64});
        for (int u = 0; u < 3; ++u)
            if (glow_system_update(sys, NULL) != GLOW_OK) {
                glow_system_destroy(sys);
                goto done;
            }
        const glow_cache_outputs *o = glow_system_outputs(sys);
        glow_cache_info *caches = malloc(((size_t)o->cache_count + 1) * sizeof *caches);
        if (!caches || glow_bake_get_caches(bake, 0, o->cache_count, caches) != GLOW_OK) {
            free(caches);
            glow_system_destroy(sys);
            goto done;
        }
        float win[GLOW_MAX_SH_BANDS], y[GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS];
        for (uint32_t l = 0; l < L; ++l) win[l] = glow_sh_window_factor(l, L);
        counts k = {0};
        for (uint32_t c = 0; c < o->cache_count; ++c) {
            const float *sh = o->cache_sh + (size_t)c * o->coeff_count;
            const double mean = sh[0] * 0.28209479177387814;
            if (!(mean > 0.0)) continue;
            const bool lm = c >= o->grid_cache_count;
            const float *nrm = caches[c].normal;
            for (uint32_t d = 0; d < ndirs; ++d) {
                const float *w = dirs + 3 * d;
                if (lm && w[0] * nrm[0] + w[1] * nrm[1] + w[2] * nrm[2] <= 0.0f) continue;
                glow_sh_eval(L, w, y);
                float a[3], b[3];
                radiance(sh, L, y, NULL, a);
                radiance(sh, L, y, win, b);
                const double ma = fmin(a[0], fmin(a[1], a[2])) / mean, mb = fmin(b[0], fmin(b[1], b[2])) / mean;
                k.pairs += 1.0;
                k.neg += ma < -1e-6;
                k.neg_w += mb < -1e-6;
                k.worst = fmin(k.worst, ma);
                k.worst_w = fmin(k.worst_w, mb);
            }
            if (lm) {
                float e[3], ew[3], tmp[3 * GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS];
                glow_shade_sh(sh, L, L, nrm, 1.0f, e);
                memcpy(tmp, sh, sizeof(float) * 3 * L * L);
                for (uint32_t ch = 0; ch < 3; ++ch)
                    for (uint32_t l = 0; l < L; ++l)
                        for (uint32_t q = l * l; q < (l + 1) * (l + 1); ++q) tmp[ch * L * L + q] *= win[l];
                glow_shade_sh(tmp, L, L, nrm, 1.0f, ew);
                k.lm += 1.0;
                k.lm_neg_irr += fmin(e[0], fmin(e[1], e[2])) < -1e-6 * mean;
                k.lm_neg_irr_w += fmin(ew[0], fmin(ew[1], ew[2])) < -1e-6 * mean;
            }
        }
        free(caches);
        glow_system_destroy(sys);
        const double sh_neg = k.pairs ? k.neg / k.pairs : 0.0, sh_neg_w = k.pairs ? k.neg_w / k.pairs : 0.0;
        const double irr = k.lm ? k.lm_neg_irr / k.lm : 0.0, irr_w = k.lm ? k.lm_neg_irr_w / k.lm : 0.0;
        if (json) {
            cJSON *row = cJSON_CreateObject();
            cJSON_AddItemToArray(jrows, row);
            cJSON_AddNumberToObject(row, "bands", L);
            glow_json_num(row, "negative_share", sh_neg);
            glow_json_num(row, "negative_share_windowed", sh_neg_w);
            glow_json_num(row, "worst", k.worst);
            glow_json_num(row, "worst_windowed", k.worst_w);
            glow_json_num(row, "lightmap_irradiance_negative_share", irr);
            glow_json_num(row, "lightmap_irradiance_negative_share_windowed", irr_w);
            glow_json_num(row, "pairs", k.pairs);
        } else
            printf("%5u  %25.2f %%  %8.2f %%  %19.3f  %8.3f  %22.2f %%  %6.2f %%\n", L, 100 * sh_neg, 100 * sh_neg_w, k.worst,
                   k.worst_w, 100 * irr, 100 * irr_w);
        fflush(stdout);
    }
    if (json) {
        const int bad = glow_json_print(jrows);
        jrows = NULL;
        if (bad) goto done;
    }
    rc = 0;
done:
    cJSON_Delete(jrows);
    glow_host_destroy(host);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    glow_scene_free(&scene);
    free(dirs);
    return rc;
}

/* ------------------------------------------------------------------ shared: Glow and the reference */
typedef struct session {
    glow_scene_desc scene;
    glow_render_scene *rs;
    glow_context *ctx;
    glow_bake *bake;
    glow_host *host;
    glow_system *sys;
    glow_cache_info *caches;   /* [info.cache_count] */
    glow_surfel_view surfels;  /* positions, normals */
    const uint32_t *feedback;  /* [surfels] each surfel's feedback cache (glow_backend.h) */
    glow_bake_info info;
    uint32_t iterations;       /* feedback iterations per update after session_converge */
} session;

static void session_free(session *s) {
    glow_system_destroy(s->sys);
    free(s->caches);
    glow_host_destroy(s->host);
    glow_bake_destroy(s->bake);
    glow_context_destroy(s->ctx);
    glow_render_scene_destroy(s->rs);
    glow_scene_free(&s->scene);
}

/* moving_light: the measurement moves the scene's first light, refused (before the bake is loaded and
 * the bounce converged) unless it is a point or spot light */
static int session_open(session *s, const char *bake_path, const char *scene_path, uint32_t iterations,
                        bool moving_light) {
    memset(s, 0, sizeof *s);
    static glow_cli_log log_state = {"glow-stability", 0};
    glow_logger lg = glow_cli_logger(&log_state);
    char msg[512];
    if (glow_scene_load(scene_path, &lg, &s->scene, msg, sizeof msg) != GLOW_OK ||
        glow_render_scene_load(scene_path, &s->rs, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s\n", msg);
        return 0;
    }
    if (moving_light && (s->scene.light_count == 0 || s->scene.lights[0].type == GLOW_SCENE_LIGHT_SUN)) {
        fprintf(stderr, "glow-stability: %s: flicker moves the first light, which must be a point or spot light\n",
                scene_path);
        return 0;
    }
    if (glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION, .logger = lg}, &s->ctx) != GLOW_OK) return 0;
    if (glow_bake_load_file(s->ctx, bake_path, &s->bake) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s: cannot load the bake\n", bake_path);
        return 0;
    }
    glow_bake_get_info(s->bake, &s->info);
    s->caches = malloc(((size_t)s->info.cache_count + 1) * sizeof *s->caches);
    if (!s->caches || glow_bake_get_caches(s->bake, 0, s->info.cache_count, s->caches) != GLOW_OK) return 0;
    glow_host_desc hd = glow_host_desc_from_scene(&s->scene, s->bake, GLOW_HOST_KIND_EXACT);
    hd.logger = lg;
    hd.surfel_samples = g_surfel_samples;
    if (glow_host_create(&hd, &s->host) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s: cannot create the host\n", bake_path);
        return 0;
    }
    if (glow_system_create(s->ctx, &(glow_system_desc){.bake = s->bake, .lighting = glow_host_hooks(s->host)}, &s->sys) !=
        GLOW_OK)
        return 0;
    glow_solver_tables tab;
    if (glow_system_get_surfels(s->sys, &s->surfels) != GLOW_OK || glow_system_get_solver_tables(s->sys, &tab) != GLOW_OK)
        return 0;
    s->feedback = tab.feedback;
    s->iterations = iterations;
    return 1;
}

/* the bounce converged (3 updates of 64 feedback iterations), then `iterations` per update */
static int session_converge(session *s) {
    glow_system_set_params(s->sys, &(glow_system_params){.bounce_intensity = 1.0f, .emission_scale = s->scene.emission_scale,
                                                         .bounce_iterations = 64});
    for (int u = 0; u < 3; ++u)
        if (glow_system_update(s->sys, NULL) != GLOW_OK) return 0;
    glow_system_set_params(s->sys, &(glow_system_params){.bounce_intensity = 1.0f, .emission_scale = s->scene.emission_scale,
                                                         .bounce_iterations = s->iterations});
    return 1;
}

/* Glow's irradiance E (W/m², RGB) at lightmap cache c: π x the diffuse-shaded cache along its normal */
static void glow_irradiance(const session *s, uint32_t c, float out[3]) {
    const glow_cache_outputs *o = glow_system_outputs(s->sys);
    glow_shade_sh(o->cache_sh + (size_t)c * o->coeff_count, o->sh_bands_luma, o->sh_bands_chroma, s->caches[c].normal, 1.0f,
                  out);
    for (int k = 0; k < 3; ++k) out[k] *= (float)PI_D;
}

/* Glow's irradiance E (W/m², RGB) for surfel u's next bounce: π x its feedback cache, diffuse-shaded
 * along the surfel's normal */
static void surfel_irradiance(const session *s, uint32_t u, float out[3]) {
    const glow_cache_outputs *o = glow_system_outputs(s->sys);
    glow_shade_sh(o->cache_sh + (size_t)s->feedback[u] * o->coeff_count, o->sh_bands_luma, o->sh_bands_chroma,
                  s->surfels.normals + 4 * (size_t)u, 1.0f, out);
    for (int k = 0; k < 3; ++k) out[k] *= (float)PI_D;
}

static float luma(const float *rgb) { return 0.25f * rgb[0] + 0.5f * rgb[1] + 0.25f * rgb[2]; }

static void cache_point(const session *s, uint32_t c, float *pt) {
    memcpy(pt, s->caches[c].position, 3 * sizeof(float));
    memcpy(pt + 3, s->caches[c].normal, 3 * sizeof(float));
}

/* ------------------------------------------------------------------ flicker */
static int flicker(const char *bake_path, const char *scene_path, uint32_t frames, uint32_t iterations, uint32_t nprobes,
                   uint32_t samples, const char *csv_path, uint32_t budget_caches) {
    /* --budget-caches: every update after the converged first frame gathers at most that many caches
     * (glow_update_desc.max_caches), to measure a budget's lag and flicker against the reference */
    const glow_update_desc budget = {.max_caches = budget_caches};
    session s;
    int rc = 1;
    float *pts = NULL, *eg = NULL, *er = NULL, *pg = NULL, *pr = NULL;
    FILE *csv = NULL;
    if (!session_open(&s, bake_path, scene_path, iterations, true) || !session_converge(&s)) goto done;
    const uint32_t lm = s.info.lightmap_cache_count, first = s.info.grid_cache_count;
    if (nprobes > lm) nprobes = lm;
    pts = malloc(sizeof(float) * 6 * nprobes);
    eg = malloc(sizeof(float) * 3 * nprobes);
    er = malloc(sizeof(float) * 3 * nprobes);
    pg = malloc(sizeof(float) * 3 * nprobes);
    pr = malloc(sizeof(float) * 3 * nprobes);
    if (!pts || !eg || !er || !pg || !pr || nprobes == 0) goto done;
    for (uint32_t i = 0; i < nprobes; ++i) cache_point(&s, first + (uint32_t)((uint64_t)i * lm / nprobes), pts + 6 * i);
    if (csv_path && !(csv = fopen(csv_path, "w"))) {
        fprintf(stderr, "glow-stability: %s: cannot write\n", csv_path);
        goto done;
    }
    if (csv) fprintf(csv, "frame,mean_glow,mean_ref,change_glow,change_ref,rel_error\n");
    const float diag = sqrtf((s.info.bounds_max[0] - s.info.bounds_min[0]) * (s.info.bounds_max[0] - s.info.bounds_min[0]) +
                             (s.info.bounds_max[1] - s.info.bounds_min[1]) * (s.info.bounds_max[1] - s.info.bounds_min[1]) +
                             (s.info.bounds_max[2] - s.info.bounds_min[2]) * (s.info.bounds_max[2] - s.info.bounds_min[2]));
    const glow_scene_light base = s.scene.lights[0];
    glow_scene_light *lights = s.scene.lights;
    glow_render_settings st = {.seed = 11};
    double sum_cg = 0, sum_cr = 0, max_cg = 0, max_cr = 0, sum_err = 0, sum_excess = 0;
    char msg[512];
    /* The light's path: a circle of 0.15 scene diagonals about its position in the scene, squeezed
     * into an ellipse that stays 2 % of a diagonal inside the bounds. A circle through the wall of a
     * closed room (the pillar hall's light stands 0.6 m from its -z wall) left the room for half the
     * frames: the reference went dark, and every figure, relative to its mean, blew up (> 100 %). */
    double rad[2] = {0.15 * diag, 0.15 * diag};
    for (int k = 0; k < 2; ++k) {
        const int ax = k ? 2 : 0;
        const double m = 0.02 * diag, lo = base.position[ax] - (s.info.bounds_min[ax] + m),
                     hi = (s.info.bounds_max[ax] - m) - base.position[ax];
        rad[k] = fmax(0.0, fmin(rad[k], fmin(lo, hi)));
    }
    for (uint32_t f = 0; f <= frames; ++f) {
        const double a = 2.0 * PI_D * f / frames;
        lights[0] = base;
        lights[0].position[0] = base.position[0] + (float)(rad[0] * cos(a));
        lights[0].position[2] = base.position[2] + (float)(rad[1] * sin(a));
        if (glow_host_set_light(s.host, 0, &lights[0]) != GLOW_OK) goto done;
        if (f == 0) { /* frame 0: converged at the path's first position, as the engine's first frame would be */
            glow_system_set_params(s.sys, &(glow_system_params){.bounce_intensity = 1.0f,
                                                                .emission_scale = s.scene.emission_scale,
                                                                .bounce_iterations = 64});
            for (int u = 0; u < 3; ++u)
                if (glow_system_update(s.sys, NULL) != GLOW_OK) goto done;
            glow_system_set_params(s.sys, &(glow_system_params){.bounce_intensity = 1.0f,
                                                                .emission_scale = s.scene.emission_scale,
                                                                .bounce_iterations = iterations});
        } else if (glow_system_update(s.sys, budget_caches ? &budget : NULL) != GLOW_OK) {
            goto done;
        }
        for (uint32_t i = 0; i < nprobes; ++i) glow_irradiance(&s, first + (uint32_t)((uint64_t)i * lm / nprobes), eg + 3 * i);
        if (glow_render_irradiance(s.rs, lights, s.scene.light_count, &st, pts, nprobes, samples, 0, er, NULL, msg,
                                   sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-stability: %s\n", msg);
            goto done;
        }
        double mg = 0, mr = 0, cg = 0, cr = 0, err = 0, ex = 0;
        for (uint32_t i = 0; i < nprobes; ++i) {
            const double g = luma(eg + 3 * i), rr = luma(er + 3 * i);
            mg += g;
            mr += rr;
            err += fabs(g - rr);
            if (f > 0) {
                const double dg = fabs(g - luma(pg + 3 * i)), dr = fabs(rr - luma(pr + 3 * i));
                cg += dg;
                cr += dr;
                ex += fmax(0.0, dg - dr);
            }
        }
        const double norm = mr > 0 ? mr : 1.0;
        cg /= norm;
        cr /= norm;
        ex /= norm;
        err /= norm;
        mg /= nprobes;
        mr /= nprobes;
        if (f > 0) {
            sum_cg += cg;
            sum_cr += cr;
            sum_excess += ex;
            max_cg = fmax(max_cg, cg);
            max_cr = fmax(max_cr, cr);
        }
        sum_err += err;
        if (csv) fprintf(csv, "%u,%.6g,%.6g,%.6g,%.6g,%.6g\n", f, mg, mr, f ? cg : 0.0, f ? cr : 0.0, err);
        memcpy(pg, eg, sizeof(float) * 3 * nprobes);
        memcpy(pr, er, sizeof(float) * 3 * nprobes);
    }
    if (budget_caches) printf("budget: at most %u of %u caches gathered per update\n", budget_caches, s.info.cache_count);
    printf("flicker: the light circles its position in an ellipse of %.3g x %.3g (x, z)\n", rad[0], rad[1]);
    printf("flicker: %s, %u frames, %u iteration(s) per frame, %u probes x %u paths\n"
           "  mean frame-to-frame change: Glow %.4f, reference %.4f (ratio %.2f); largest: Glow %.4f, reference %.4f\n"
           "  change of Glow beyond the reference's (per frame, mean): %.4f; mean |Glow - reference| %.4f (all relative to "
           "the mean irradiance)\n",
           scene_path, frames, iterations, nprobes, samples, sum_cg / frames, sum_cr / frames,
           sum_cr > 0 ? sum_cg / sum_cr : 0.0, max_cg, max_cr, sum_excess / frames, sum_err / (frames + 1));
    rc = 0;
done:
    if (csv) fclose(csv);
    free(pts);
    free(eg);
    free(er);
    free(pg);
    free(pr);
    session_free(&s);
    return rc;
}

/* ------------------------------------------------------------------ link-cut jumps */

static int jumps(const char *bake_path, const char *scene_path, uint32_t max_pairs, uint32_t samples, const char *csv_path) {
    session s;
    int rc = 1;
    uint32_t *pa = NULL, *pb = NULL;
    float *pts = NULL, *er = NULL;
    double *jg = NULL, *jr = NULL;
    FILE *csv = NULL;
    if (!session_open(&s, bake_path, scene_path, 64, false) || !session_converge(&s)) goto done;
    const glow_cache_outputs *o = glow_system_outputs(s.sys);
    const uint32_t W = o->lightmap_width, H = o->lightmap_height;
    if (!W || !H) {
        fprintf(stderr, "glow-stability: %s: the bake has no lightmap\n", bake_path);
        goto done;
    }
    const float spacing = 1.0f / s.info.texel_density;
    uint32_t cand = 0;
    const uint32_t P = o->lightmap_pages ? o->lightmap_pages : 1u; /* neighbours within a page (format 1.7) */
    pa = malloc(sizeof(uint32_t) * 2 * (size_t)W * H * P);
    pb = malloc(sizeof(uint32_t) * 2 * (size_t)W * H * P);
    if (!pa || !pb) goto done;
    for (uint32_t pg = 0; pg < P; ++pg)
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x)
            for (int d = 0; d < 2; ++d) {
                uint32_t x2 = x + (d == 0), y2 = y + (d == 1);
                if (x2 >= W || y2 >= H) continue;
                const uint32_t *map = o->lightmap_map + (size_t)pg * W * H;
                uint32_t a = map[y * W + x], b = map[y2 * W + x2];
                if (a == GLOW_MAP_EMPTY || b == GLOW_MAP_EMPTY || a == b) continue;
                const float *na = s.caches[a].normal, *nb = s.caches[b].normal;
                float dx = 0, dot = na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2];
                for (int k = 0; k < 3; ++k) dx += (s.caches[a].position[k] - s.caches[b].position[k]) * (s.caches[a].position[k] - s.caches[b].position[k]);
                if (dot < 0.906f || dx > (2.5f * spacing) * (2.5f * spacing)) continue;
                pa[cand] = a;
                pb[cand] = b;
                cand++;
            }
    uint32_t n = cand < max_pairs ? cand : max_pairs;
    if (n == 0) {
        fprintf(stderr, "glow-stability: %s: no neighbouring lightmap caches\n", bake_path);
        goto done;
    }
    pts = malloc(sizeof(float) * 12 * n);
    er = malloc(sizeof(float) * 6 * n);
    jg = malloc(sizeof(double) * n);
    jr = malloc(sizeof(double) * n);
    if (!pts || !er || !jg || !jr) goto done;
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t k = (uint32_t)((uint64_t)i * cand / n);
        cache_point(&s, pa[k], pts + 12 * i);
        cache_point(&s, pb[k], pts + 12 * i + 6);
        pa[i] = pa[k];
        pb[i] = pb[k];
    }
    glow_render_settings st = {.seed = 5};
    char msg[512];
    if (glow_render_irradiance(s.rs, NULL, 0, &st, pts, 2 * n, samples, 2, er, NULL, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s\n", msg);
        goto done;
    }
    if (csv_path && !(csv = fopen(csv_path, "w"))) {
        fprintf(stderr, "glow-stability: %s: cannot write\n", csv_path);
        goto done;
    }
    if (csv) fprintf(csv, "x,y,z,glow_a,glow_b,ref_a,ref_b\n");
    double mean = 0;
    for (uint32_t i = 0; i < n; ++i) {
        float ga[3], gb[3];
        glow_irradiance(&s, pa[i], ga);
        glow_irradiance(&s, pb[i], gb);
        jg[i] = fabs((double)luma(ga) - luma(gb));
        jr[i] = fabs((double)luma(er + 6 * i) - luma(er + 6 * i + 3));
        mean += 0.5 * (luma(er + 6 * i) + luma(er + 6 * i + 3));
        if (csv)
            fprintf(csv, "%g,%g,%g,%g,%g,%g,%g\n", pts[12 * i], pts[12 * i + 1], pts[12 * i + 2], luma(ga), luma(gb),
                    luma(er + 6 * i), luma(er + 6 * i + 3));
    }
    mean /= n;
    qsort(jg, n, sizeof *jg, glow_cli_cmp_double);
    qsort(jr, n, sizeof *jr, glow_cli_cmp_double);
    const uint32_t p99 = (uint32_t)(0.99 * (n - 1));
    printf("jumps: %s, %u neighbouring cache pairs (of %u), %u paths per cache, mean irradiance %.4g W/m^2\n"
           "  largest jump / mean: Glow %.4f, reference %.4f; 99th percentile: Glow %.4f, reference %.4f; median: Glow %.4f, "
           "reference %.4f\n",
           scene_path, n, cand, samples, mean, jg[n - 1] / mean, jr[n - 1] / mean, jg[p99] / mean, jr[p99] / mean,
           jg[n / 2] / mean, jr[n / 2] / mean);
    rc = 0;
done:
    if (csv) fclose(csv);
    free(pa);
    free(pb);
    free(pts);
    free(er);
    free(jg);
    free(jr);
    session_free(&s);
    return rc;
}

/* ------------------------------------------------------------------ audit: where the indirect energy goes */
typedef struct audit_row {
    double g, r; /* luma irradiance: Glow, reference */
} audit_row;

static int cmp_ratio(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Per lightmap cache, Glow's irradiance against the reference's at the cache (position and normal),
 * single bounce (Glow without feedback against paths of one reflection) and converged (multi-bounce
 * against full paths): the gather through the links and the cut, without the lightmap's interpolation
 * and the camera. Also each cache's visible solid angle (Σ over its links, from the bake) as a
 * histogram: what the cut covers. */
static int audit(const char *bake_path, const char *scene_path, uint32_t nprobes, uint32_t samples, const char *csv_path,
                 const char *radiance_out, const uint32_t *only, uint32_t only_count, int json) {
    cJSON *jroot = NULL; /* --json: built as the figures come, printed at the end */
    session s;
    int rc = 1;
    float *pts = NULL, *er1 = NULL, *erc = NULL, *eg1 = NULL, *egc = NULL, *sg1 = NULL, *sgc = NULL;
    double *ratio = NULL;
    uint32_t *pick = NULL;
    FILE *csv = NULL;
    if (!session_open(&s, bake_path, scene_path, 64, false)) goto done; /* converged once --caches is checked */
    const uint32_t lm = s.info.lightmap_cache_count, first = s.info.grid_cache_count;
    if (nprobes > lm) nprobes = lm;
    for (uint32_t i = 0; i < only_count; ++i)
        if (only[i] < first || only[i] - first >= lm) {
            fprintf(stderr, "glow-stability: %s: --caches: %u is not a lightmap cache (those are %u..%u)\n", bake_path,
                    only[i], first, first + lm - 1);
            goto done;
        }
    if (only_count) nprobes = only_count;
    if (nprobes == 0) {
        fprintf(stderr, "glow-stability: %s: the bake has no lightmap caches to audit\n", bake_path);
        goto done;
    }
    if (!session_converge(&s)) goto done;
    pts = malloc(sizeof(float) * 6 * nprobes);
    er1 = malloc(sizeof(float) * 3 * nprobes);
    erc = malloc(sizeof(float) * 3 * nprobes);
    eg1 = malloc(sizeof(float) * 3 * nprobes);
    egc = malloc(sizeof(float) * 3 * nprobes);
    ratio = malloc(sizeof(double) * 2 * nprobes);
    pick = malloc(sizeof(uint32_t) * nprobes);
    /* the area-uniform points (below): every (ns / np)-th surfel */
    const uint32_t ns = s.info.surfel_count, np = nprobes < ns ? nprobes : ns;
    sg1 = malloc(sizeof(float) * 3 * (np + 1));
    sgc = malloc(sizeof(float) * 3 * (np + 1));
    if (!pts || !er1 || !erc || !eg1 || !egc || !ratio || !pick || !sg1 || !sgc) goto done;
    for (uint32_t i = 0; i < nprobes; ++i) {
        pick[i] = only_count ? only[i] : first + (uint32_t)((uint64_t)i * lm / nprobes);
        cache_point(&s, pick[i], pts + 6 * i);
    }
    /* Glow converged (session_open ran 3 x 64 feedback iterations), then single bounce: no feedback */
    for (uint32_t i = 0; i < nprobes; ++i) glow_irradiance(&s, pick[i], egc + 3 * i);
    for (uint32_t i = 0; i < np; ++i) surfel_irradiance(&s, (uint32_t)((uint64_t)i * ns / np), sgc + 3 * i);
    glow_system_set_params(s.sys, &(glow_system_params){.bounce_intensity = 0.0f, .emission_scale = s.scene.emission_scale,
                                                        .bounce_iterations = 1});
    if (glow_system_update(s.sys, NULL) != GLOW_OK) goto done;
    for (uint32_t i = 0; i < nprobes; ++i) glow_irradiance(&s, pick[i], eg1 + 3 * i);
    for (uint32_t i = 0; i < np; ++i) surfel_irradiance(&s, (uint32_t)((uint64_t)i * ns / np), sg1 + 3 * i);
    if (radiance_out) { /* the surfels' single-bounce radiance (luma), for glow-bake --audit-radiance */
        glow_solver_tables t;
        FILE *f = glow_system_get_solver_tables(s.sys, &t) == GLOW_OK ? fopen(radiance_out, "wb") : NULL;
        int wok = f != NULL;
        for (uint32_t i = 0; wok && i < t.surfel_count; ++i) {
            float b[3];
            for (int k = 0; k < 3; ++k)
                b[k] = t.albedo[3 * i + k] * t.material_albedo_scale[3 * t.materials[i] + k] * t.direct_irradiance[3 * i + k] /
                           (float)PI_D +
                       t.emission[3 * i + k] * t.material_emission_scale[3 * t.materials[i] + k] * s.scene.emission_scale;
            const float l = luma(b);
            wok = fwrite(&l, sizeof l, 1, f) == 1;
        }
        if (f && fclose(f) != 0) wok = 0;
        if (!wok) {
            fprintf(stderr, "glow-stability: %s: cannot write the surfel radiance\n", radiance_out);
            if (f) remove(radiance_out);
            goto done;
        }
    }
    char msg[512];
    glow_render_settings st1 = {.seed = 3, .max_depth = 3}, stc = {.seed = 3};
    if (glow_render_irradiance(s.rs, NULL, 0, &st1, pts, nprobes, samples, 0, er1, NULL, msg, sizeof msg) != GLOW_OK ||
        glow_render_irradiance(s.rs, NULL, 0, &stc, pts, nprobes, samples, 0, erc, NULL, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-stability: %s\n", msg);
        goto done;
    }
    if (csv_path && !(csv = fopen(csv_path, "w"))) {
        fprintf(stderr, "glow-stability: %s: cannot write\n", csv_path);
        goto done;
    }
    if (csv) fprintf(csv, "cache,x,y,z,nx,ny,nz,glow_1b,ref_1b,glow,ref\n");
    const char *names[2] = {"single_bounce", "converged"};
    const float *G[2] = {eg1, egc}, *R[2] = {er1, erc};
    if (json) {
        jroot = cJSON_CreateObject();
        cJSON_AddStringToObject(jroot, "scene", scene_path);
        cJSON_AddStringToObject(jroot, "bake", bake_path);
        cJSON_AddNumberToObject(jroot, "probes", nprobes);
        cJSON_AddNumberToObject(jroot, "samples", samples);
    }
    for (int pass = 0; pass < 2; ++pass) {
        double sg = 0, sr = 0, se2 = 0, sr2 = 0, mean_r = 0;
        for (uint32_t i = 0; i < nprobes; ++i) mean_r += luma(R[pass] + 3 * i);
        mean_r /= nprobes;
        uint32_t nr = 0, bright = 0, dark = 0;
        for (uint32_t i = 0; i < nprobes; ++i) {
            const double g = luma(G[pass] + 3 * i), r = luma(R[pass] + 3 * i);
            sg += g;
            sr += r;
            se2 += (g - r) * (g - r);
            sr2 += r * r;
            /* ratios only where the reference is not noise-dominated (above 5 % of the mean) */
            if (r > 0.05 * mean_r) {
                ratio[nr++] = g / r;
                bright += g > 1.5 * r;
                dark += g < r / 1.5;
            }
        }
        qsort(ratio, nr, sizeof *ratio, cmp_ratio);
        const double q05 = nr ? ratio[(size_t)(0.05 * (nr - 1))] : NAN, q50 = nr ? ratio[nr / 2] : NAN,
                     q95 = nr ? ratio[(size_t)(0.95 * (nr - 1))] : NAN;
        if (json) {
            cJSON *o = cJSON_AddObjectToObject(jroot, names[pass]);
            glow_json_num(o, "mean_ratio", sg / sr);
            glow_json_num(o, "rel_rms_error", sqrt(se2 / sr2));
            glow_json_num(o, "ratio_p05", q05);
            glow_json_num(o, "ratio_median", q50);
            glow_json_num(o, "ratio_p95", q95);
            cJSON_AddNumberToObject(o, "caches_rated", nr);
            cJSON_AddNumberToObject(o, "over_1_5x", bright);
            cJSON_AddNumberToObject(o, "under_1_5x", dark);
        } else
            printf("audit %-13s Glow/reference mean %.4f, rel. RMS error %.4f; per cache (%u with ref > 5%% of the mean): "
                   "p05 %.3f median %.3f p95 %.3f, %u above 1.5x, %u below 1/1.5x\n",
                   names[pass], sg / sr, sqrt(se2 / sr2), nr, q05, q50, q95, bright, dark);
    }
    /* Area-uniform points: the bake's surfels (equal areas), each with the irradiance Glow gives it for
     * the next bounce (its feedback cache along the surfel's normal) against the reference's at the
     * surfel. Unlike the caches above (one per texel, however little surface a texel covers), this
     * weighs the scene by area, as the camera and the multi-bounce feedback do; where the two audits
     * disagree, the loss lies between the caches and the surfaces that read them. */
    {
        float *sp = malloc(sizeof(float) * 6 * np), *sr = malloc(sizeof(float) * 3 * np), *sr1 = malloc(sizeof(float) * 3 * np);
        double sg = 0, srr = 0, se2 = 0, sr2 = 0;
        int ok = sp && sr && sr1;
        const float lift = 1e-4f * sqrtf((s.info.bounds_max[0] - s.info.bounds_min[0]) * (s.info.bounds_max[0] - s.info.bounds_min[0]) +
                                         (s.info.bounds_max[1] - s.info.bounds_min[1]) * (s.info.bounds_max[1] - s.info.bounds_min[1]) +
                                         (s.info.bounds_max[2] - s.info.bounds_min[2]) * (s.info.bounds_max[2] - s.info.bounds_min[2]));
        for (uint32_t i = 0; ok && i < np; ++i) {
            const size_t u = (size_t)((uint64_t)i * ns / np);
            const float *up = s.surfels.positions + 4 * u, *un = s.surfels.normals + 4 * u;
            for (int k = 0; k < 3; ++k) {
                sp[6 * i + k] = up[k] + lift * un[k];
                sp[6 * i + 3 + k] = un[k];
            }
        }
        /* Glow's values were read with the caches' (sg1, sgc); the reference's here */
        ok = ok && glow_render_irradiance(s.rs, NULL, 0, &st1, sp, np, samples, 0, sr1, NULL, msg, sizeof msg) == GLOW_OK;
        ok = ok && glow_render_irradiance(s.rs, NULL, 0, &stc, sp, np, samples, 0, sr, NULL, msg, sizeof msg) == GLOW_OK;
        FILE *scsv = NULL;
        if (ok && csv_path) {
            char name[1024];
            snprintf(name, sizeof name, "%s.surfels.csv", csv_path);
            if (!(scsv = fopen(name, "w"))) fprintf(stderr, "glow-stability: %s: cannot write\n", name);
            else fprintf(scsv, "surfel,x,y,z,nx,ny,nz,feedback_cache,glow_1b,ref_1b,glow,ref\n");
        }
        double sg1s = 0, sr1s = 0;
        for (uint32_t i = 0; ok && i < np; ++i) {
            const size_t u = (size_t)((uint64_t)i * ns / np);
            const float *up = s.surfels.positions + 4 * u, *un = s.surfels.normals + 4 * u;
            const double g = luma(sgc + 3 * i), r = luma(sr + 3 * i);
            sg1s += luma(sg1 + 3 * i);
            sr1s += luma(sr1 + 3 * i);
            if (scsv)
                fprintf(scsv, "%u,%g,%g,%g,%g,%g,%g,%u,%g,%g,%g,%g\n", (uint32_t)u, up[0], up[1], up[2], un[0], un[1],
                        un[2], s.feedback[u],
                        luma(sg1 + 3 * i), luma(sr1 + 3 * i), g, r);
            sg += g;
            srr += r;
            se2 += (g - r) * (g - r);
            sr2 += r * r;
        }
        free(sr1);
        if (ok && json) {
            cJSON *o = cJSON_AddObjectToObject(jroot, "surfels");
            glow_json_num(o, "single_bounce_mean_ratio", sg1s / sr1s);
            glow_json_num(o, "mean_ratio", sg / srr);
            glow_json_num(o, "rel_rms_error", sqrt(se2 / sr2));
            cJSON_AddNumberToObject(o, "points", np);
        } else if (ok)
            printf("audit surfels (area-uniform, %u): Glow's feedback irradiance / reference: single bounce %.4f, converged %.4f "
                   "(rel. RMS error %.4f)\n", np, sg1s / sr1s, sg / srr, sqrt(se2 / sr2));
        if (scsv) fclose(scsv);
        free(sp);
        free(sr);
        if (!ok) {
            fprintf(stderr, "glow-stability: %s: surfel audit failed\n", bake_path);
            goto done;
        }
    }
    /* visible solid angle of each cache, from its decoded links */
    {
        uint32_t hist[9] = {0};
        const uint32_t bpc = (s.info.links_per_cache + GLOW_LINK_BLOCK - 1) / GLOW_LINK_BLOCK;
        glow_solver_tables tab;
        const glow_bake_link_block *blocks =
            glow_system_get_solver_tables(s.sys, &tab) == GLOW_OK ? (const glow_bake_link_block *)tab.link_blocks : NULL;
        for (uint32_t i = 0; i < nprobes; ++i) {
            double om = 0; /* unused lanes hold 0 */
            for (uint32_t j = 0; blocks && j < bpc * GLOW_LINK_BLOCK; ++j)
                om += 2.0 * PI_D * glow__half_to_float(blocks[(size_t)pick[i] * bpc + j / GLOW_LINK_BLOCK].one_minus_cos[j % GLOW_LINK_BLOCK]);
            int b = (int)(om / (2.0 * PI_D) * 8.0);
            hist[b < 0 ? 0 : b > 8 ? 8 : b]++;
        }
        if (json) {
            cJSON *a = cJSON_AddArrayToObject(jroot, "visible_solid_angle_hist_2pi_eighths");
            for (int b = 0; a && b < 9; ++b) cJSON_AddItemToArray(a, cJSON_CreateNumber(hist[b]));
            const int bad = glow_json_print(jroot);
            jroot = NULL;
            if (bad) goto done;
        } else {
            printf("audit visible solid angle of the caches' links (x 2 pi sr, in eighths; the last bin: >= 1):");
            for (int b = 0; b < 9; ++b) printf(" %u", hist[b]);
            printf("\n");
        }
    }
    for (uint32_t i = 0; csv && i < nprobes; ++i)
        fprintf(csv, "%u,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g\n", pick[i], pts[6 * i], pts[6 * i + 1], pts[6 * i + 2], pts[6 * i + 3],
                pts[6 * i + 4], pts[6 * i + 5], luma(eg1 + 3 * i), luma(er1 + 3 * i), luma(egc + 3 * i), luma(erc + 3 * i));
    rc = 0;
done:
    cJSON_Delete(jroot);
    if (csv) fclose(csv);
    free(pts);
    free(er1);
    free(erc);
    free(eg1);
    free(egc);
    free(ratio);
    free(pick);
    free(sg1);
    free(sgc);
    session_free(&s);
    return rc;
}

int main(int argc, char **argv) {
    if (argc >= 2 && (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help"))) return usage(stdout);
    if (argc < 4 || (strcmp(argv[1], "ringing") && strcmp(argv[1], "flicker") && strcmp(argv[1], "jumps") &&
                      strcmp(argv[1], "audit")))
        return usage(stderr);
    uint32_t lmax = GLOW_MAX_SH_BANDS, ndirs = 256, frames = 240, iterations = 1, probes = 96, samples = 1024, pairs = 3000,
             budget_caches = 0;
    const char *csv = NULL, *radiance_out = NULL;
    int json = 0;
    uint32_t only[4096], only_count = 0; /* audit --caches */
    for (int i = 4; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        uint32_t *dst = !strcmp(a, "--bands-max") ? &lmax : !strcmp(a, "--dirs") ? &ndirs : !strcmp(a, "--frames") ? &frames
                      : !strcmp(a, "--iterations") ? &iterations : !strcmp(a, "--probes") ? &probes
                      : !strcmp(a, "--samples") ? &samples : !strcmp(a, "--pairs") ? &pairs
                      : !strcmp(a, "--budget-caches") ? &budget_caches : NULL;
        if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--csv") && v) {
            csv = v;
            ++i;
        } else if (!strcmp(a, "--surfel-samples") && v) {
            if (!glow_cli_u32(v, 1, GLOW_HOST_SURFEL_SAMPLES_MAX, &g_surfel_samples)) {
                fprintf(stderr, "glow-stability: --surfel-samples needs a number in 1..%u, not '%s'\n",
                        GLOW_HOST_SURFEL_SAMPLES_MAX, v);
                return 2;
            }
            ++i;
        } else if (!strcmp(a, "--caches") && v) {
            for (const char *q = v; *q;) {
                char item[32];
                size_t len = strcspn(q, ",");
                if (len == 0 || len >= sizeof item || only_count == 4096) {
                    fprintf(stderr, "glow-stability: --caches needs 1 to 4096 cache indices separated by commas, not '%s'\n", v);
                    return 2;
                }
                memcpy(item, q, len);
                item[len] = 0;
                if (!glow_cli_u32(item, 0, UINT32_MAX - 1, &only[only_count++])) {
                    fprintf(stderr, "glow-stability: --caches: '%s' is not a cache index\n", item);
                    return 2;
                }
                q += len + (q[len] == ',');
            }
            ++i;
        } else if (!strcmp(a, "--radiance-out") && v) {
            radiance_out = v;
            ++i;
        } else if (dst && v) {
            if (!glow_cli_u32(v, 1, 1000000, dst)) {
                fprintf(stderr, "glow-stability: %s needs a whole number in 1..1000000, not '%s'\n", a, v);
                return 2;
            }
            ++i;
        } else {
            fprintf(stderr, "glow-stability: unknown option '%s'\n", a);
            return usage(stderr);
        }
    }
    if (lmax < 2 || lmax > GLOW_MAX_SH_BANDS || ndirs < 8 || ndirs > 65536 || iterations > 64) {
        fprintf(stderr, "glow-stability: --bands-max must be 2..8, --dirs 8..65536, --iterations 1..64\n");
        return 2;
    }
    if (only_count && strcmp(argv[1], "audit")) {
        fprintf(stderr, "glow-stability: --caches is an audit option\n");
        return 2;
    }
    if (!strcmp(argv[1], "ringing")) return ringing(argv[2], argv[3], lmax, ndirs, json);
    if (!strcmp(argv[1], "audit")) return audit(argv[2], argv[3], probes, samples, csv, radiance_out, only, only_count, json);
    if (!strcmp(argv[1], "flicker")) return flicker(argv[2], argv[3], frames, iterations, probes, samples, csv, budget_caches);
    return jumps(argv[2], argv[3], pairs, samples, csv);
}
