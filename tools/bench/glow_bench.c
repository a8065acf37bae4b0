/* glow-bench — the runtime's speed on a real bake, the way an engine drives it.
 *
 *   glow-bench BAKE SCENE [options]       (SCENE: a scene description JSON, docs/scene-format.md)
 *
 * Runs --frames updates while the scene's first light moves along a path (a point/spot light circles
 * its position; a sun turns about the vertical; a scene without lights has its emission pulse), the
 * host lighting the surfels every frame (exact Embree rays or software shadow maps), and prints the
 * median milliseconds per stage, the cache-lighting kernel's achieved memory bandwidth and FLOP rate,
 * and — measured in the same run, with the same thread count — this machine's STREAM-triad bandwidth
 * and fp32 FMA peak, so the fractions mean something. --probe X,Y,Z (repeatable) prints the indirect
 * light at points (grid caches, diffuse, normal +Y), as does the default probe set.
 *
 * Exit: 0 ok, 1 runtime/IO failure, 2 usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/resource.h>
#include <unistd.h>

#include "glow_cli.h"
#include "glow_tool_json.h"
#include "glow/glow.h"
#include "glow/glow_host.h"
#include "glow/glow_scene.h"
#include "machine_probe.h"
#ifdef GLOW_BENCH_HAVE_GL
#include "glow/glow_gl.h"
#include "glow/glow_gl_lights.h"
#include "glow/glow_glctx.h"
#endif

#define MAX_PROBES 16

typedef struct options {
    const char *bake, *scene;
    uint32_t frames, warmup, threads, luma, chroma, iterations;
    glow_host_kind host;
    uint32_t surfel_samples; /* the exact host's footprint points (glow_host_desc); 0 = its default */
    glow_link_mode link_mode;
    glow_output_planes planes;
    int json, quiet, no_probe_machine, gl, gl_finish;
    uint32_t probe_count;
    float probes[MAX_PROBES][3];
    /* budgets (glow_update_desc): 0 = none */
    float budget_ms, converge;
    uint32_t budget_caches;
    int has_focus, still, walk, keep_lighting;
    float focus[3];
    float stream; /* worlds, with --walk: only the systems within this distance of the focus are loaded */
} options;

static const char *link_mode_name(uint32_t mode) {
    return mode == GLOW_LINK_MODE_EXPANDED ? "expanded" : mode == GLOW_LINK_MODE_SH ? "sh" : "compact";
}

static const char *planes_name(glow_output_planes p) {
    return p == GLOW_OUTPUT_PLANES_RGBA16F ? "rgba16f" : p == GLOW_OUTPUT_PLANES_NONE ? "none" : "f32";
}

static void usage(FILE *f) {
    fprintf(f,
            "usage: glow-bench BAKE SCENE [--frames N] [--warmup N] [--threads N] [--luma L] [--chroma C]\n"
            "                  [--iterations K] [--host exact|shadow-map] [--surfel-samples K] [--link-mode compact|expanded|sh]\n"
            "                  [--probe X,Y,Z]... [--no-machine] [--backend cpu|gl] [--planes f32|rgba16f|none]\n"
            "                  [--budget-ms MS] [--budget-caches N] [--converge EPS] [--focus X,Y,Z] [--still [--keep-lighting]]\n"
            "                  [--walk [--stream R]]\n"
            "                  [--json] [-q]\n"
            "  BAKE   a bake written by glow-bake, or a world manifest (glow-bake --system-area: every system in one\n"
            "         glow_world, one host each shadowed by its neighbours too, CPU backend);  SCENE  its scene description JSON (docs/scene-format.md)\n"
            "  --frames N      timed updates (default 60); --warmup N untimed first (default 5)\n"
            "  --threads N     runtime workers (default: one per online CPU); the machine probes use the same\n"
            "  --luma/--chroma SH bands (default: the bake's; chroma = luma)\n"
            "  --iterations K  bounce iterations per update (default 1)\n"
            "  --host          surfel lighting: exact Embree rays (default) or software shadow maps\n"
            "  --surfel-samples K  the exact host's shadow-ray points per surfel footprint, 1..8 (default 8;\n"
            "                  a moving light costs one ray per surfel per update, a still one none)\n"
            "  --link-mode     links projected every update (compact, default), expanded at create (more memory),\n"
            "                  or the bake's full-SH links (sh: needs glow-bake --sh-links)\n"
            "  --planes        the grid and lightmap output planes as floats (f32, default), IEEE halves packed for\n"
            "                  RGBA16F textures (rgba16f) or none (hosts that read the cache rows;\n"
            "                  glow_system_desc.output_planes)\n"
            "  --probe X,Y,Z   print the indirect light at this point (repeatable; default: 3 points)\n"
            "  --no-machine    skip the STREAM-triad, FMA-peak and cache-line round-trip probes\n"
            "  --backend gl    the GL 4.5 solver (glow_gl.h) on a headless context (EGL, else OSMesa; GLOW_GLCTX=egl|osmesa),\n"
            "                  surfels lit by the GPU shadow-map hook (glow_gl_lights.h); per-stage GPU times from timer\n"
            "                  queries (--threads, --host and --link-mode do not apply)\n"
            "  --gl-timing finish  time GL stages with glFinish + the CPU clock (for llvmpipe, whose timestamps\n"
            "                  are not ordered with compute work); default: timer queries\n"
            "  --budget-ms MS  aim each update at MS ms (glow_update_desc.budget_ms; CPU backend); with any budget\n"
            "                  an unbudgeted twin system runs the same frames (untimed) and the report gives the\n"
            "                  budget's cost: the caches' luma error against the twin, per frame\n"
            "  --budget-caches N  at most N caches gathered per update (max_caches)\n"
            "  --converge EPS  skip converged caches (converged_epsilon)\n"
            "  --focus X,Y,Z   caches near this point first (default: the scene's camera, when it has one)\n"
            "  --still         keep the lights still (default: the first light moves every update)\n"
            "  --keep-lighting with --still: after the first update, tell Glow the lights did not move\n"
            "                  (GLOW_UPDATE_FLAG_KEEP_LIGHTING: the host hook is not called, but for the\n"
            "                  batches a time budget left)\n"
            "  --walk          with a budget: the focus walks across the scene's longest horizontal extent\n"
            "                  over the run (at the scene camera's height), and the report adds the error of\n"
            "                  the caches within a tenth of the scene's diagonal of it (the camera's view);\n"
            "                  for a world, also their flicker: change per update against the twin's\n"
            "  --stream R      a world, with --walk and --budget-ms: only the systems whose bounds lie within R\n"
            "                  of the focus are loaded; as it walks, the others are streamed in (a new system from\n"
            "                  its bake, added; untimed, as an engine's loader would) and out (removed, destroyed)\n"
            "                  between updates, and the report adds the updates that followed a stream-in\n");
}


static int parse_args(int argc, char **argv, options *o) {
    memset(o, 0, sizeof *o);
    o->frames = 60;
    o->warmup = 5;
    o->iterations = 1;
    o->host = GLOW_HOST_KIND_EXACT;
    int pos = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
#define NEED_U32(field) \
    do { if (!v || !glow_cli_u32(v, 0, 1000000000u, &o->field)) { fprintf(stderr, "glow-bench: %s needs a number\n", a); return 0; } ++i; } while (0)
        if (!strcmp(a, "--frames")) NEED_U32(frames);
        else if (!strcmp(a, "--warmup")) NEED_U32(warmup);
        else if (!strcmp(a, "--threads")) NEED_U32(threads);
        else if (!strcmp(a, "--luma")) NEED_U32(luma);
        else if (!strcmp(a, "--chroma")) NEED_U32(chroma);
        else if (!strcmp(a, "--iterations")) NEED_U32(iterations);
        else if (!strcmp(a, "--surfel-samples")) {
            if (!v || !glow_cli_u32(v, 1, GLOW_HOST_SURFEL_SAMPLES_MAX, &o->surfel_samples)) {
                fprintf(stderr, "glow-bench: --surfel-samples needs a number in 1..%u\n", GLOW_HOST_SURFEL_SAMPLES_MAX);
                return 0;
            }
            ++i;
        }
        else if (!strcmp(a, "--host")) {
            if (!v || (strcmp(v, "exact") && strcmp(v, "shadow-map"))) {
                fprintf(stderr, "glow-bench: --host must be exact or shadow-map\n");
                return 0;
            }
            o->host = strcmp(v, "exact") ? GLOW_HOST_KIND_SHADOW_MAP : GLOW_HOST_KIND_EXACT;
            ++i;
        } else if (!strcmp(a, "--link-mode")) {
            if (!v || (strcmp(v, "expanded") && strcmp(v, "compact") && strcmp(v, "sh"))) {
                fprintf(stderr, "glow-bench: --link-mode must be compact, expanded or sh\n");
                return 0;
            }
            o->link_mode = !strcmp(v, "expanded") ? GLOW_LINK_MODE_EXPANDED
                         : !strcmp(v, "sh")       ? GLOW_LINK_MODE_SH
                                                  : GLOW_LINK_MODE_COMPACT;
            ++i;
        } else if (!strcmp(a, "--planes")) {
            if (!v || (strcmp(v, "f32") && strcmp(v, "rgba16f") && strcmp(v, "none"))) {
                fprintf(stderr, "glow-bench: --planes must be f32, rgba16f or none\n");
                return 0;
            }
            o->planes = !strcmp(v, "rgba16f") ? GLOW_OUTPUT_PLANES_RGBA16F
                      : !strcmp(v, "none")    ? GLOW_OUTPUT_PLANES_NONE
                                              : GLOW_OUTPUT_PLANES_F32;
            ++i;
        } else if (!strcmp(a, "--probe")) {
            float p[3];
            if (!v || sscanf(v, "%f,%f,%f", &p[0], &p[1], &p[2]) != 3 || !isfinite(p[0]) || !isfinite(p[1]) ||
                !isfinite(p[2]) || o->probe_count == MAX_PROBES) {
                fprintf(stderr, "glow-bench: --probe needs X,Y,Z (at most %d probes)\n", MAX_PROBES);
                return 0;
            }
            memcpy(o->probes[o->probe_count++], p, sizeof p);
            ++i;
        } else if (!strcmp(a, "--backend")) {
            if (!v || (strcmp(v, "cpu") && strcmp(v, "gl"))) {
                fprintf(stderr, "glow-bench: --backend must be cpu or gl\n");
                return 0;
            }
            o->gl = !strcmp(v, "gl");
            ++i;
        } else if (!strcmp(a, "--gl-timing")) {
            if (!v || (strcmp(v, "finish") && strcmp(v, "queries"))) {
                fprintf(stderr, "glow-bench: --gl-timing must be queries or finish\n");
                return 0;
            }
            o->gl_finish = !strcmp(v, "finish");
            ++i;
        } else if (!strcmp(a, "--budget-ms") || !strcmp(a, "--converge") || !strcmp(a, "--stream")) {
            float x;
            if (!v || !glow_cli_float(v, &x) || !(x > 0.0f)) {
                fprintf(stderr, "glow-bench: %s needs a positive number\n", a);
                return 0;
            }
            if (!strcmp(a, "--budget-ms")) o->budget_ms = x;
            else if (!strcmp(a, "--stream")) o->stream = x;
            else o->converge = x;
            ++i;
        } else if (!strcmp(a, "--budget-caches")) {
            if (!v || !glow_cli_u32(v, 1, 1u << 30, &o->budget_caches)) {
                fprintf(stderr, "glow-bench: --budget-caches needs a whole number >= 1\n");
                return 0;
            }
            ++i;
        } else if (!strcmp(a, "--focus")) {
            if (!v || sscanf(v, "%f,%f,%f", &o->focus[0], &o->focus[1], &o->focus[2]) != 3 || !isfinite(o->focus[0]) ||
                !isfinite(o->focus[1]) || !isfinite(o->focus[2])) {
                fprintf(stderr, "glow-bench: --focus needs X,Y,Z\n");
                return 0;
            }
            o->has_focus = 1;
            ++i;
        } else if (!strcmp(a, "--still")) o->still = 1;
        else if (!strcmp(a, "--keep-lighting")) o->keep_lighting = 1;
        else if (!strcmp(a, "--walk")) o->walk = 1;
        else if (!strcmp(a, "--no-machine")) o->no_probe_machine = 1;
        else if (!strcmp(a, "--json")) o->json = 1;
        else if (!strcmp(a, "-q")) o->quiet = 1;
        else if (!strcmp(a, "-h") || !strcmp(a, "--help")) { usage(stdout); exit(0); }
        else if (a[0] == '-') { fprintf(stderr, "glow-bench: unknown option %s\n", a); return 0; }
        else if (pos == 0) { o->bake = a; pos++; }
        else if (pos == 1) { o->scene = a; pos++; }
        else { fprintf(stderr, "glow-bench: unexpected argument %s\n", a); return 0; }
#undef NEED_U32
    }
    if (pos != 2) {
        fprintf(stderr, "glow-bench: need BAKE and SCENE\n");
        return 0;
    }
    if (o->keep_lighting && !o->still) {
        fprintf(stderr, "glow-bench: --keep-lighting goes with --still (a moving light must be relit)\n");
        return 0;
    }
    if (o->stream > 0.0f && !(o->walk && o->budget_ms > 0.0f)) {
        fprintf(stderr, "glow-bench: --stream measures a walk under a time budget: give --walk and --budget-ms\n");
        return 0;
    }
    if (o->walk && !(o->budget_ms > 0.0f || o->budget_caches || o->converge > 0.0f)) {
        fprintf(stderr, "glow-bench: --walk measures a budget: give --budget-ms, --budget-caches or --converge\n");
        return 0;
    }
#ifndef GLOW_BENCH_HAVE_GL
    if (o->gl) {
        fprintf(stderr, "glow-bench: --backend gl: this build has no GL backend (GLOW_WITH_GL=OFF)\n");
        return 0;
    }
#endif
    if (o->frames == 0) {
        fprintf(stderr, "glow-bench: --frames must be >= 1\n");
        return 0;
    }
    return 1;
}


static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* FLOPs the cache-lighting kernel spends per link (cache_kernel.inc, sh_kernel.h's scaled basis),
 * counted per floating-point operation of the source (an FMA = 2): octahedral decode 5 (the fold;
 * the scale by 4095 is integer work), normalise 14 (length², rsqrt + one Newton step, 3 scales),
 * cone factors 3 + 1 for l = 2 + 3 per band above, the scaled basis (sh_eval_scaled_flops), band
 * weights (luma, plus 2 per chroma band, from l = 1; l = 0 multiplies straight into its sums),
 * accumulation 2 per coefficient. l = 3/3: 93 (the kernel before 2026-11-22 took 138). */
static double sh_eval_scaled_flops(uint32_t L) {
    double f = 0.0;
    for (uint32_t m = 0; m < L; ++m) {
        if (m >= 2) f += 6.0; /* (c, s) <- (c x - s y, s x + c y) */
        for (uint32_t l = m + 1; l < L; ++l) {
            if (l == m + 2) f += 2.0;      /* z q - beta: one FMA */
            else if (l > m + 2) f += 3.0;  /* z q - beta q': mul + FMA */
            if (m > 0) f += 2.0;           /* q c, q s */
        }
    }
    return f;
}
static double flops_per_link(uint32_t L, uint32_t C) {
    const double cone = 3.0 + (L >= 3 ? 1.0 + 3.0 * (L - 3) : 0.0);
    const double weights = (L - 1.0) + 2.0 * (C - 1.0);
    return 5.0 + 14.0 + cone + sh_eval_scaled_flops(L) + weights + 2.0 * (L * L + 2.0 * C * C);
}

/* the light path: frame f of n */
static void animate(const glow_scene_light *base, glow_scene_light *out, uint32_t f, uint32_t n, float radius) {
    *out = *base;
    double phi = 2.0 * 3.14159265358979323846 * (double)f / (double)n;
    if (base->type == GLOW_SCENE_LIGHT_SUN) {
        double c = cos(phi), s = sin(phi);
        out->direction[0] = (float)(c * base->direction[0] - s * base->direction[2]);
        out->direction[2] = (float)(s * base->direction[0] + c * base->direction[2]);
    } else {
        out->position[0] = base->position[0] + radius * (float)cos(phi);
        out->position[2] = base->position[2] + radius * (float)sin(phi);
    }
}

/* --walk: from 5 % in at one end of the longest horizontal extent of [lo, hi] to 5 % in at the other, at
 * the camera's height (else the middle's) */
static void walk_ends(const float lo[3], const float hi[3], const glow_scene_desc *scene, float a[3], float b[3]) {
    const int ax = hi[0] - lo[0] >= hi[2] - lo[2] ? 0 : 2;
    for (int k = 0; k < 3; ++k) a[k] = b[k] = 0.5f * (lo[k] + hi[k]);
    if (scene->has_camera) a[1] = b[1] = scene->camera.position[1];
    const float ext = hi[ax] - lo[ax];
    a[ax] = lo[ax] + 0.05f * ext;
    b[ax] = hi[ax] - 0.05f * ext;
}

/* ------------------------------------------------------------------------------------ worlds */
/* BAKE a world manifest (glow-bake --system-area): every system loaded, one host each (shadows from
 * its own and its neighbours' geometry: glow_host_desc.occluders), all in a glow_world, updated as one
 * (glow_world_update). With a budget an unbudgeted twin world runs the same frames (untimed) and the
 * report gives the budget's cost as for one system; --walk walks the focus across the world's bounds. */
#define WORLD_MAX 1024u

typedef struct world_set {
    uint32_t n;
    glow_bake *bake[WORLD_MAX];
    glow_host *host[WORLD_MAX], *twin_host[WORLD_MAX]; /* the twins' own hosts: footprint samples roll per host */
    glow_system *sys[WORLD_MAX], *twin[WORLD_MAX];
    glow_cache_info *cinfo[WORLD_MAX];
    float *prev[WORLD_MAX];       /* --walk with a twin: each cache's luma at the last measured update, and
                                     the twin's ([2 x caches]) */
    uint32_t prev_fr[WORLD_MAX];  /* the update they are from + 1 (0: none) */
} world_set;

/* The loader's share of the host, which it would otherwise do on its first calls, inside the budgeted
 * updates: each surfel's sky visibility (a constant sky's S, 128 rays a surfel) and the exact host's
 * footprint samples for the current light (all K points of every lit surfel; later calls re-trace
 * one). Half-tile systems of the 4x4 Sponza level: 130 ms, then 5-6.5 ms of a 2 ms budget's first
 * update without it; and since a time budget lights the hook's batches a few at a time (2026-11-30),
 * 10-27 ms in each of the first 30 updates of a walk whose systems loaded at the start were not
 * prepared. So every system of a budgeted run is prepared, untimed, as an engine's loader would. */
static glow_result prepare_host(glow_system *sys, glow_host *host) {
    glow_surfel_view sv;
    float *S = NULL;
    glow_result r;
    if ((r = glow_system_get_surfels(sys, &sv)) != GLOW_OK || !(S = malloc(((size_t)sv.count + 1) * 3 * sizeof *S)) ||
        (r = glow_host_sky_visibility(host, &sv, S, sv.count)) != GLOW_OK) {
        free(S);
        return r == GLOW_OK ? GLOW_ERROR_OUT_OF_MEMORY : r;
    }
    const glow_lighting_hooks hk = glow_host_hooks(host);
    for (uint32_t b = 0; b < sv.count && r == GLOW_OK; b += 256) {
        const glow_surfel_batch batch = {.first = b, .count = sv.count - b < 256 ? sv.count - b : 256,
                                         .positions = sv.positions + 4 * (size_t)b,
                                         .normals = sv.normals + 4 * (size_t)b,
                                         .materials = sv.materials ? sv.materials + b : NULL};
        r = hk.light_surfels(hk.user, &batch, S, 0);
    }
    free(S);
    return r;
}

/* Against a time budget: of the updates, the 95th percentile, the largest and how many took more than
 * 1.25x the budget (issue 17's limit for streaming); with --stream the same of the updates that gave a
 * streamed-in system its first update (in[i] > 0) */
typedef struct stream_figs {
    uint32_t frames, over, in_frames, in_over;
    uint32_t over_descheduled, over_faulted; /* of `over`, those with an involuntary context switch, a page fault */
    double p95, max, in_median, in_max;
} stream_figs;

static bool stream_figures(const double *wall, const double *in, const double *csw, const double *flt, uint32_t n,
                           double budget_ms, stream_figs *out) {
    stream_figs f = {0};
    double *scratch = malloc(((size_t)n + 1) * sizeof *scratch);
    if (!scratch) return false;
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
        f.over += wall[i] > 1.25 * budget_ms;
        f.over_descheduled += wall[i] > 1.25 * budget_ms && csw[i] > 0.0;
        f.over_faulted += wall[i] > 1.25 * budget_ms && flt[i] > 0.0;
        f.max = fmax(f.max, wall[i]);
        if (in[i] > 0.0) {
            f.in_frames++;
            f.in_over += wall[i] > 1.25 * budget_ms;
            f.in_max = fmax(f.in_max, wall[i]);
            scratch[m++] = wall[i];
        }
    }
    f.frames = n;
    f.in_median = m ? glow_cli_median(scratch, m) : 0.0;
    memcpy(scratch, wall, n * sizeof *scratch);
    qsort(scratch, n, sizeof *scratch, glow_cli_cmp_double);
    f.p95 = n ? scratch[(uint32_t)fmin((double)n - 1.0, ceil(0.95 * n) - 1.0)] : 0.0;
    free(scratch);
    *out = f;
    return true;
}

static int is_world(const char *path) {
    const size_t n = strlen(path);
    return n > 5 && strcmp(path + n - 5, ".json") == 0;
}

/* System i of the world (its bake loaded), lit by `host`, with the run's params */
static glow_result world_system(const options *o, glow_context *ctx, const world_set *ws, const cJSON *systems, uint32_t i,
                                glow_host *host, const glow_system_params *params, glow_system **out) {
    const cJSON *file = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(systems, (int)i), "file");
    const glow_system_desc sd = {.bake = ws->bake[i], .lighting = glow_host_hooks(host), .sh_bands_luma = o->luma,
                                 .sh_bands_chroma = o->chroma, .label = file->valuestring, .link_mode = o->link_mode,
                                 .output_planes = o->planes};
    glow_result r = glow_system_create(ctx, &sd, out);
    return r == GLOW_OK ? glow_system_set_params(*out, params) : r;
}

static int run_world(options *o, glow_scene_desc *scene, glow_logger logger) {
    int rc = 1;
    glow_result r = GLOW_OK;
    world_set *ws = calloc(1, sizeof *ws);
    char *text = NULL;
    cJSON *man = NULL;
    glow_context *ctx = NULL;
    glow_world *W = NULL, *T = NULL;
    double *v_total = NULL, *v_wall = NULL, *v_upd = NULL, *v_err = NULL, *v_errn = NULL, *v_gath = NULL, *v_skip = NULL;
    double *v_in = NULL, *v_loaded = NULL; /* --stream: systems streamed in before each update, loaded */
    double *v_csw = NULL, *v_flt = NULL;   /* the process's involuntary context switches and page faults in it */
    if (!ws) goto done;
    FILE *f = fopen(o->bake, "rb");
    if (!f) {
        fprintf(stderr, "glow-bench: %s: cannot open the world manifest\n", o->bake);
        goto done;
    }
    fseek(f, 0, SEEK_END);
    const long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    text = size > 0 ? malloc((size_t)size + 1) : NULL;
    if (!text || fread(text, 1, (size_t)size, f) != (size_t)size) {
        fclose(f);
        fprintf(stderr, "glow-bench: %s: cannot read the world manifest\n", o->bake);
        goto done;
    }
    fclose(f);
    text[size] = 0;
    man = cJSON_Parse(text);
    const cJSON *systems = man ? cJSON_GetObjectItemCaseSensitive(man, "systems") : NULL;
    if (!man || !cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(man, "glow_world")) || !cJSON_IsArray(systems) ||
        cJSON_GetArraySize(systems) < 1 || cJSON_GetArraySize(systems) > (int)WORLD_MAX) {
        fprintf(stderr, "glow-bench: %s: not a world manifest (glow_world, systems[1..%u]; glow-bake --system-area)\n",
                o->bake, WORLD_MAX);
        goto done;
    }
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", o->bake);
    char *slash = strrchr(dir, '/');
    if (slash) slash[1] = 0;
    else dir[0] = 0;
    r = glow_context_create(
        &(glow_context_desc){.api_version = GLOW_VERSION, .logger = logger, .tasks = {.worker_count = o->threads}}, &ctx);
    if (r != GLOW_OK) goto done;
    const bool budget = o->budget_ms > 0.0f || o->budget_caches || o->converge > 0.0f;
    const glow_system_params params = {.bounce_intensity = 1.0f, .emission_scale = scene->emission_scale,
                                       .bounce_iterations = o->iterations};
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    uint64_t caches = 0, surfels = 0;
    const cJSON *it;
    cJSON_ArrayForEach(it, systems) {
        const cJSON *file = cJSON_GetObjectItemCaseSensitive(it, "file");
        if (!cJSON_IsString(file)) {
            fprintf(stderr, "glow-bench: %s: a system without a \"file\"\n", o->bake);
            goto done;
        }
        char path[8192];
        snprintf(path, sizeof path, "%s%s", dir, file->valuestring);
        const uint32_t i = ws->n++;
        if ((r = glow_bake_load_file(ctx, path, &ws->bake[i])) != GLOW_OK) goto done;
        glow_bake_info bi;
        glow_bake_get_info(ws->bake[i], &bi);
        for (int k = 0; k < 3; ++k) {
            lo[k] = fminf(lo[k], bi.bounds_min[k]);
            hi[k] = fmaxf(hi[k], bi.bounds_max[k]);
        }
        caches += bi.cache_count;
        surfels += bi.surfel_count;
    }
    for (uint32_t i = 0; i < ws->n; ++i) { /* hosts: each system shadowed by its own and its neighbours' geometry */
        glow_bake_info bi;
        glow_bake_get_info(ws->bake[i], &bi);
        const glow_bake *occ[64];
        uint32_t nocc = 0;
        for (uint32_t d = 0; d < bi.dependency_count && nocc < 64; ++d) {
            uint64_t key = 0;
            glow_bake_get_dependency(ws->bake[i], d, &key);
            for (uint32_t j = 0; j < ws->n; ++j) {
                glow_bake_info bj;
                glow_bake_get_info(ws->bake[j], &bj);
                if (j != i && bj.system_key == key) {
                    occ[nocc++] = ws->bake[j];
                    break;
                }
            }
        }
        glow_host_desc hd = glow_host_desc_from_scene(scene, ws->bake[i], o->host);
        hd.logger = logger;
        hd.occluders = occ;
        hd.occluder_count = nocc;
        hd.surfel_samples = o->surfel_samples;
        if ((r = glow_host_create(&hd, &ws->host[i])) != GLOW_OK) goto done;
        if (budget && (r = glow_host_create(&hd, &ws->twin_host[i])) != GLOW_OK) goto done;
        if ((r = world_system(o, ctx, ws, systems, i, ws->host[i], &params, &ws->sys[i])) != GLOW_OK ||
            (budget && (r = world_system(o, ctx, ws, systems, i, ws->twin_host[i], &params, &ws->twin[i])) != GLOW_OK))
            goto done;
        ws->cinfo[i] = malloc(((size_t)bi.cache_count + 1) * sizeof *ws->cinfo[i]);
        if (!ws->cinfo[i] || (r = glow_bake_get_caches(ws->bake[i], 0, bi.cache_count, ws->cinfo[i])) != GLOW_OK) goto done;
        if (budget && !(ws->prev[i] = malloc(((size_t)bi.cache_count + 1) * 2 * sizeof *ws->prev[i]))) goto done;
    }
    if ((r = glow_world_create(ctx, ws->n, &W)) != GLOW_OK || (budget && (r = glow_world_create(ctx, ws->n, &T)) != GLOW_OK))
        goto done;
    const bool stream = o->stream > 0.0f; /* the walk's start decides who is loaded first (below) */
    for (uint32_t i = 0; i < ws->n; ++i)
        if ((!stream && (r = glow_world_add(W, ws->sys[i])) != GLOW_OK) || (T && (r = glow_world_add(T, ws->twin[i])) != GLOW_OK))
            goto done;
    if (budget) /* the systems loaded at the start, as those streamed in later (prepare_host), and the twins */
        for (uint32_t i = 0; i < ws->n; ++i)
            if ((r = prepare_host(ws->sys[i], ws->host[i])) != GLOW_OK || (r = prepare_host(ws->twin[i], ws->twin_host[i])) != GLOW_OK)
                goto done;
    glow_world_stats wst;
    glow_world_get_stats(W, &wst);
    float diag = 0.0f;
    for (int k = 0; k < 3; ++k) diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    diag = sqrtf(diag);
    const uint32_t n = o->frames, total = o->warmup + o->frames;
    v_total = calloc(n, sizeof(double)); v_wall = calloc(n, sizeof(double)); v_upd = calloc(n, sizeof(double));
    v_err = calloc(n, sizeof(double)); v_errn = calloc(n, sizeof(double)); v_gath = calloc(n, sizeof(double));
    v_skip = calloc(n, sizeof(double));
    v_in = calloc(n, sizeof(double)); v_loaded = calloc(n, sizeof(double));
    v_csw = calloc(n, sizeof(double)); v_flt = calloc(n, sizeof(double));
    if (!v_total || !v_wall || !v_upd || !v_err || !v_errn || !v_gath || !v_skip || !v_in || !v_loaded || !v_csw || !v_flt)
        goto done;
    glow_update_desc ud = {0};
    if (!o->has_focus && scene->has_camera) {
        memcpy(o->focus, scene->camera.position, sizeof o->focus);
        o->has_focus = 1;
    }
    if (budget)
        ud = (glow_update_desc){.max_caches = o->budget_caches, .budget_ms = o->budget_ms, .converged_epsilon = o->converge,
                                .focus = o->has_focus ? o->focus : NULL, .focus_count = o->has_focus ? 1u : 0u};
    const bool walk = o->walk && budget;
    float walk_a[3], walk_b[3];
    if (walk) {
        walk_ends(lo, hi, scene, walk_a, walk_b);
        ud.focus = o->focus;
        ud.focus_count = 1;
    }
    const float near_r = 0.1f * diag;
    /* the caches near the focus: walking, or standing at the scene camera (or --focus) */
    const bool near = budget && (walk || ud.focus_count > 0);
    bool member[WORLD_MAX] = {false}, pending[WORLD_MAX] = {false}; /* pending: streamed in, not updated yet */
    uint32_t n_in = 0, n_out = 0;
    double f_chg = 0.0, f_twin = 0.0, f_beyond = 0.0, f_max = 0.0; /* --walk: flicker near the focus */
    uint32_t f_n = 0;
    for (uint32_t fr = 0; fr < total; ++fr) {
        if (walk) {
            const float u = total > 1 ? (float)fr / (float)(total - 1) : 0.0f;
            for (int k = 0; k < 3; ++k) o->focus[k] = walk_a[k] + u * (walk_b[k] - walk_a[k]);
        }
        uint32_t in_now = 0;
        for (uint32_t i = 0; stream && i < ws->n; ++i) { /* --stream: load what is near the focus, unload the rest */
            glow_bake_info bi;
            glow_bake_get_info(ws->bake[i], &bi);
            float d2 = 0.0f;
            for (int k = 0; k < 3; ++k) {
                const float x = o->focus[k], e = x < bi.bounds_min[k] ? bi.bounds_min[k] - x : x > bi.bounds_max[k] ? x - bi.bounds_max[k] : 0.0f;
                d2 += e * e;
            }
            const bool want = d2 <= o->stream * o->stream;
            if (member[i] && !want) { /* out: detached both ways, then freed, as an engine unloads it */
                if ((r = glow_world_remove(W, ws->sys[i])) != GLOW_OK) goto done;
                glow_system_destroy(ws->sys[i]);
                ws->sys[i] = NULL;
                member[i] = false;
                n_out += fr > 0;
            } else if (!member[i] && want) { /* in: a new system from its bake (the first frame's are loaded already) */
                if (!ws->sys[i]) {
                    if ((r = world_system(o, ctx, ws, systems, i, ws->host[i], &params, &ws->sys[i])) != GLOW_OK ||
                        (r = prepare_host(ws->sys[i], ws->host[i])) != GLOW_OK)
                        goto done;
                }
                if ((r = glow_world_add(W, ws->sys[i])) != GLOW_OK) goto done;
                member[i] = true;
                if (fr > 0) {
                    n_in++;
                    pending[i] = true;
                }
            }
        }
        if (stream && fr == 0)
            for (uint32_t i = 0; i < ws->n; ++i)
                if (!member[i]) { /* not loaded at the start */
                    glow_system_destroy(ws->sys[i]);
                    ws->sys[i] = NULL;
                }
        if (!o->still && scene->light_count > 0) {
            glow_scene_light l;
            animate(&scene->lights[0], &l, fr, total, 0.05f * diag);
            for (uint32_t i = 0; i < ws->n; ++i)
                if ((r = glow_host_set_light(ws->host[i], 0, &l)) != GLOW_OK ||
                    (ws->twin_host[i] && (r = glow_host_set_light(ws->twin_host[i], 0, &l)) != GLOW_OK))
                    goto done;
        }
        glow_update_desc u = ud; /* --keep-lighting (with --still): the hosts are not called after the first */
        if (o->keep_lighting && fr > 0) u.flags |= GLOW_UPDATE_FLAG_KEEP_LIGHTING;
        /* an update over its budget: was a thread descheduled (another process on these cores), or a page
         * touched for the first time? getrusage counts the process's threads together */
        struct rusage ru0, ru1;
        getrusage(RUSAGE_SELF, &ru0);
        const double t0 = now_ms();
        if ((r = glow_world_update(W, &u)) != GLOW_OK) goto done;
        const double t1 = now_ms();
        getrusage(RUSAGE_SELF, &ru1);
        if (T && (r = glow_world_update(T, NULL)) != GLOW_OK) goto done; /* untimed reference */
        glow_world_get_stats(W, &wst);
        for (uint32_t s = 0; stream && s < ws->n; ++s) { /* a system streamed in had its first update now */
            glow_update_stats us;
            if (pending[s] && ws->sys[s] && glow_system_get_stats(ws->sys[s], &us) == GLOW_OK && us.updates > 0) {
                pending[s] = false;
                in_now++;
            }
        }
        if (fr < o->warmup) continue;
        const uint32_t i = fr - o->warmup;
        v_wall[i] = t1 - t0;
        v_in[i] = in_now;
        v_csw[i] = (double)(ru1.ru_nivcsw - ru0.ru_nivcsw);
        v_flt[i] = (double)(ru1.ru_minflt - ru0.ru_minflt + ru1.ru_majflt - ru0.ru_majflt);
        v_loaded[i] = wst.systems;
        v_total[i] = wst.last_update.total_ms;
        v_upd[i] = wst.systems_updated;
        v_gath[i] = wst.last_update.caches_gathered;
        v_skip[i] = wst.last_update.surfels_skipped_budget;
        if (!T) continue;
        double num = 0.0, den = 0.0, numn = 0.0, denn = 0.0, ca = 0.0, cb = 0.0, cd = 0.0, cden = 0.0;
        for (uint32_t s = 0; s < ws->n; ++s) {
            if (!ws->sys[s]) continue; /* streamed out */
            const glow_cache_outputs *a = glow_system_outputs(ws->sys[s]), *b = glow_system_outputs(ws->twin[s]);
            const bool had = fr > 0 && ws->prev_fr[s] == fr; /* loaded and measured at the update before */
            float *pa = ws->prev[s], *pb = ws->prev[s] + a->cache_count;
            for (uint32_t c = 0; c < a->cache_count; ++c) {
                const double x = a->cache_sh[(size_t)c * a->coeff_count], y = b->cache_sh[(size_t)c * b->coeff_count];
                num += fabs(x - y);
                den += fabs(y);
                float d[3];
                for (int k = 0; k < 3; ++k) d[k] = ws->cinfo[s][c].position[k] - o->focus[k];
                if (near && d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= near_r * near_r) {
                    numn += fabs(x - y);
                    denn += fabs(y);
                    if (had) { /* the stability suite's flicker metrics, the twin as the reference */
                        const double dx = x - pa[c], dy = y - pb[c];
                        ca += fabs(dx);
                        cb += fabs(dy);
                        cd += fmax(0.0, fabs(dx) - fabs(dy)); /* as glow-stability flicker */
                        cden += fabs(y);
                    }
                }
                pa[c] = (float)x;
                pb[c] = (float)y;
            }
            ws->prev_fr[s] = fr + 1;
        }
        v_err[i] = den > 0.0 ? num / den : 0.0;
        v_errn[i] = denn > 0.0 ? numn / denn : 0.0;
        if (cden > 0.0) {
            f_chg += ca / cden;
            f_twin += cb / cden;
            f_beyond += cd / cden;
            f_max = fmax(f_max, cd / cden);
            f_n++;
        }
    }
    if (f_n) {
        f_chg /= f_n;
        f_twin /= f_n;
        f_beyond /= f_n;
    }
    double e_mean = 0.0, en_mean = 0.0, en_last = 0.0;
    const uint32_t q0 = n - n / 4;
    for (uint32_t i = 0; i < n; ++i) {
        e_mean += v_err[i] / n;
        en_mean += v_errn[i] / n;
        if (i >= q0) en_last += v_errn[i] / (double)(n - q0);
    }
    stream_figs sf = {0}; /* before the medians, which sort v_wall in place */
    if (o->budget_ms > 0.0f && !stream_figures(v_wall, v_in, v_csw, v_flt, n, o->budget_ms, &sf)) goto done;
    const double m_loaded = glow_cli_median(v_loaded, n);
    const double m_wall = glow_cli_median(v_wall, n), m_total = glow_cli_median(v_total, n),
                 m_upd = glow_cli_median(v_upd, n), m_gath = glow_cli_median(v_gath, n),
                 m_skip = glow_cli_median(v_skip, n);
    const double e_med = glow_cli_median(v_err, n), en_med = glow_cli_median(v_errn, n);
    if (o->json) {
        cJSON *jo = cJSON_CreateObject();
        if (!jo) goto done;
        cJSON_AddStringToObject(jo, "world", o->bake);
        cJSON_AddNumberToObject(jo, "systems", ws->n);
        cJSON_AddNumberToObject(jo, "surfels", (double)surfels);
        cJSON_AddNumberToObject(jo, "caches", (double)caches);
        cJSON_AddNumberToObject(jo, "dependencies_attached", wst.dependencies_attached);
        cJSON_AddNumberToObject(jo, "frames", n);
        glow_json_num(jo, "median_update_ms", m_wall);
        glow_json_num(jo, "median_systems_ms", m_total);
        glow_json_num(jo, "median_systems_updated", m_upd);
        glow_json_num(jo, "median_caches_gathered", m_gath);
        glow_json_num(jo, "median_surfels_skipped_budget", m_skip);
        glow_json_num(jo, "memory_mib", (double)wst.last_update.memory_bytes / (1024.0 * 1024.0));
        if (budget) {
            cJSON *jb = cJSON_AddObjectToObject(jo, "budget");
            glow_json_num(jb, "budget_ms", o->budget_ms);
            cJSON_AddNumberToObject(jb, "budget_caches", o->budget_caches);
            glow_json_num(jb, "luma_error_mean", e_mean);
            glow_json_num(jb, "luma_error_median", e_med);
            if (o->budget_ms > 0.0f) {
                glow_json_num(jb, "p95_update_ms", sf.p95);
                glow_json_num(jb, "max_update_ms", sf.max);
                cJSON_AddNumberToObject(jb, "updates_over_1_25x_budget", sf.over);
                cJSON_AddNumberToObject(jb, "updates_over_descheduled", sf.over_descheduled);
                cJSON_AddNumberToObject(jb, "updates_over_page_faults", sf.over_faulted);
            }
            if (stream) {
                cJSON *js = cJSON_AddObjectToObject(jb, "stream");
                glow_json_num(js, "radius", o->stream);
                cJSON_AddNumberToObject(js, "streamed_in", n_in);
                cJSON_AddNumberToObject(js, "streamed_out", n_out);
                glow_json_num(js, "median_systems_loaded", m_loaded);
                cJSON_AddNumberToObject(js, "first_updates", sf.in_frames);
                glow_json_num(js, "first_updates_median_ms", sf.in_median);
                glow_json_num(js, "first_updates_max_ms", sf.in_max);
                cJSON_AddNumberToObject(js, "first_updates_over_1_25x_budget", sf.in_over);
            }
            if (near) { /* "walk_" also for a focus that stands still (the names predate it) */
                glow_json_num(jb, "walk_near_radius", near_r);
                glow_json_num(jb, "walk_near_error_mean", en_mean);
                glow_json_num(jb, "walk_near_error_median", en_med);
                glow_json_num(jb, "walk_near_error_last_quarter", en_last);
                glow_json_num(jb, "walk_near_change_per_update", f_chg);
                glow_json_num(jb, "walk_near_twin_change_per_update", f_twin);
                glow_json_num(jb, "walk_near_change_beyond_twin", f_beyond);
                glow_json_num(jb, "walk_near_change_beyond_twin_max", f_max);
            }
        }
        if (glow_json_print(jo) != 0) goto done;
    } else {
        printf("glow-bench %s + %s: a world of %u systems (%u dependencies attached), %llu surfels, %llu caches, "
               "%s host per system\n",
               o->bake, o->scene, ws->n, wst.dependencies_attached, (unsigned long long)surfels,
               (unsigned long long)caches, o->host == GLOW_HOST_KIND_EXACT ? "exact" : "shadow-map");
        printf("memory %.1f MiB; median of %u world updates: %.3f ms (the systems' own totals %.3f ms), %.0f of %u "
               "systems updated, %.0f caches gathered, %.0f surfels not relit (the hook's budget)\n",
               (double)wst.last_update.memory_bytes / (1024.0 * 1024.0), n, m_wall, m_total, m_upd, ws->n, m_gath, m_skip);
        if (budget)
            printf("budget (%.3g ms, %u caches): the caches' luma against an unbudgeted twin world: error mean %.4f, "
                   "median %.4f (relative L1)\n",
                   (double)o->budget_ms, o->budget_caches, e_mean, e_med);
        if (walk)
            printf("walk: the focus crosses the world (%.3g, %.3g, %.3g) -> (%.3g, %.3g, %.3g); caches within %.3g of it: "
                   "error mean %.4f, median %.4f, last quarter of the walk %.4f\n",
                   walk_a[0], walk_a[1], walk_a[2], walk_b[0], walk_b[1], walk_b[2], (double)near_r, en_mean, en_med, en_last);
        if (!walk && near)
            printf("focus (%.3g, %.3g, %.3g), still: caches within %.3g of it: error mean %.4f, median %.4f, last quarter "
                   "of the run %.4f\n",
                   (double)o->focus[0], (double)o->focus[1], (double)o->focus[2], (double)near_r, en_mean, en_med, en_last);
        if (near && f_n)
            printf("flicker near the focus (the stability suite's metrics, the twin as the reference): change per update "
                   "%.2f %% of the mean (the twin's %.2f %%), beyond the twin's change %.2f %% (largest %.2f %%), over %u "
                   "updates\n",
                   100.0 * f_chg, 100.0 * f_twin, 100.0 * f_beyond, 100.0 * f_max, f_n);
        if (o->budget_ms > 0.0f)
            printf("updates against the %.3g ms budget: p95 %.3f ms, largest %.3f ms, %u of %u over 1.25x (of them %u with "
                   "a thread descheduled, %u with page faults)\n",
                   (double)o->budget_ms, sf.p95, sf.max, sf.over, sf.frames, sf.over_descheduled, sf.over_faulted);
        if (stream)
            printf("stream: systems within %.3g of the focus loaded (median %.0f of %u); %u streamed in, %u out; the %u "
                   "world updates that gave a streamed-in system its first update: median %.3f ms, largest %.3f ms, %u "
                   "over 1.25x the budget\n",
                   (double)o->stream, m_loaded, ws->n, n_in, n_out, sf.in_frames, sf.in_median, sf.in_max, sf.in_over);
    }
    rc = 0;
done:
    if (rc != 0 && r != GLOW_OK) fprintf(stderr, "glow-bench: failed: %s\n", glow_result_string(r));
    glow_world_destroy(W);
    glow_world_destroy(T);
    for (uint32_t i = 0; ws && i < ws->n; ++i) {
        glow_system_destroy(ws->twin[i]);
        glow_system_destroy(ws->sys[i]);
        glow_host_destroy(ws->host[i]);
        glow_host_destroy(ws->twin_host[i]);
        free(ws->cinfo[i]);
        free(ws->prev[i]);
    }
    for (uint32_t i = 0; ws && i < ws->n; ++i) glow_bake_destroy(ws->bake[i]);
    free(v_total); free(v_wall); free(v_upd); free(v_err); free(v_errn); free(v_gath); free(v_skip); free(v_in); free(v_loaded);
    free(v_csw); free(v_flt);
    glow_context_destroy(ctx);
    cJSON_Delete(man);
    free(text);
    free(ws);
    glow_scene_free(scene);
    return rc;
}

int main(int argc, char **argv) {
    options o;
    if (!parse_args(argc, argv, &o)) {
        usage(stderr);
        return 2;
    }
    glow_cli_log log_state = {"glow-bench", o.quiet};
    glow_logger logger = glow_cli_logger(&log_state);
    char msg[1024];
    glow_scene_desc scene;
    if (glow_scene_load(o.scene, &logger, &scene, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-bench: %s\n", msg);
        return 1;
    }
    if (is_world(o.bake)) {
        if (o.gl) {
            fprintf(stderr, "glow-bench: --backend gl: worlds run on the CPU backend only (glow_world drives CPU "
                            "systems; GL systems of a world attach with glow_gl_system_set_neighbour)\n");
            glow_scene_free(&scene);
            return 2;
        }
        return run_world(&o, &scene, logger);
    }
    glow_context *ctx = NULL;
    glow_bake *bake = NULL;
    glow_host *host = NULL, *twin_host = NULL;
    glow_system *sys = NULL, *twin = NULL; /* twin: unbudgeted, the reference of a budgeted run */
    double *v_err = NULL, *v_gath = NULL, *v_errn = NULL, *v_skip = NULL;
    glow_cache_info *cinfo = NULL; /* --walk: cache positions */
    float walk_a[3] = {0, 0, 0}, walk_b[3] = {0, 0, 0};
#ifdef GLOW_BENCH_HAVE_GL
    glow_glctx *glc = NULL;
    glow_gl_lights *gll = NULL;
    glow_gl_system *gls = NULL, *glt = NULL; /* glt: the unbudgeted GL twin of a budgeted GL run */
    glow_scene_light *lights = NULL;
    char gl_renderer[96] = "";
#endif
    float *gpu_sh = NULL;
    float *sh_a = NULL, *sh_b = NULL; /* GL budgets: both GL systems' caches read back, for the error */
    glow_cache_outputs gpu_out;
    double *v_host = NULL, *v_light = NULL, *v_pull = NULL, *v_cache = NULL, *v_out = NULL, *v_total = NULL, *v_move = NULL;
    int rc = 1;
    glow_result r = glow_context_create(
        &(glow_context_desc){.api_version = GLOW_VERSION, .logger = logger, .tasks = {.worker_count = o.threads}}, &ctx);
    if (r != GLOW_OK) goto done;
    if ((r = glow_bake_load_file(ctx, o.bake, &bake)) != GLOW_OK) goto done;
    glow_bake_info info;
    glow_bake_get_info(bake, &info);
    glow_host_desc hd = glow_host_desc_from_scene(&scene, bake, o.host);
    hd.logger = logger;
    hd.surfel_samples = o.surfel_samples;
    if (!o.gl && (r = glow_host_create(&hd, &host)) != GLOW_OK) goto done;
    glow_system_desc sd = {.bake = bake, .lighting = o.gl ? (glow_lighting_hooks){0} : glow_host_hooks(host), .sh_bands_luma = o.luma,
                           .sh_bands_chroma = o.chroma, .label = o.bake, .link_mode = o.link_mode,
                           .output_planes = o.planes};
    if ((r = glow_system_create(ctx, &sd, &sys)) != GLOW_OK) goto done;
    if ((r = glow_system_set_params(sys, &(glow_system_params){.bounce_intensity = 1.0f,
                                                                .emission_scale = scene.emission_scale,
                                                                .bounce_iterations = o.iterations})) != GLOW_OK)
        goto done;
    const glow_cache_outputs *out = glow_system_outputs(sys);
    const bool budget = o.budget_ms > 0.0f || o.budget_caches || o.converge > 0.0f;
    glow_update_desc ud = {0};
    if (budget) {
        /* the loader's share of the host, untimed (prepare_host): under a time budget the hook's first
         * calls, 5-7 ms a batch of 1,024 Sponza surfels unprepared, would otherwise land in the budgeted
         * updates a few batches at a time (the first 17 of a 4 ms run on Sponza moderate took 10-17 ms) */
        if (!o.gl && o.budget_ms > 0.0f && (r = prepare_host(sys, host)) != GLOW_OK) goto done;
        sd.label = "twin";
        if (!o.gl) { /* its own host: footprint samples roll per host, once per update; GL: a GL twin below */
            if ((r = glow_host_create(&hd, &twin_host)) != GLOW_OK) goto done;
            sd.lighting = glow_host_hooks(twin_host);
            if ((r = glow_system_create(ctx, &sd, &twin)) != GLOW_OK) goto done;
            if (o.budget_ms > 0.0f && (r = prepare_host(twin, twin_host)) != GLOW_OK) goto done; /* as sys's */
            if ((r = glow_system_set_params(twin, &(glow_system_params){.bounce_intensity = 1.0f,
                                                                         .emission_scale = scene.emission_scale,
                                                                         .bounce_iterations = o.iterations})) != GLOW_OK)
                goto done;
        }
        if (!o.has_focus && scene.has_camera) {
            memcpy(o.focus, scene.camera.position, sizeof o.focus);
            o.has_focus = 1;
        }
        ud = (glow_update_desc){.max_caches = o.budget_caches, .budget_ms = o.budget_ms,
                                .converged_epsilon = o.converge, .focus = o.has_focus ? o.focus : NULL,
                                .focus_count = o.has_focus ? 1u : 0u};
    }
#ifdef GLOW_BENCH_HAVE_GL
    if (o.gl) {
        if ((r = glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_HEADLESS}, &glc, msg, sizeof msg)) != GLOW_OK) {
            fprintf(stderr, "glow-bench: --backend gl: no OpenGL 4.5 context: %s\n", msg);
            goto done;
        }
        snprintf(gl_renderer, sizeof gl_renderer, "%s", glow_glctx_renderer(glc));
        glow_gl_lights_desc ld = {.loader = glow_glctx_get_proc_address(glc), .bake = bake, .logger = logger};
        if ((r = glow_gl_lights_create(&ld, &gll)) != GLOW_OK) goto done;
        if ((r = glow_gl_lights_set(gll, scene.lights, scene.light_count, scene.environment)) != GLOW_OK) goto done;
        if (scene.environment[0] > 0.0f || scene.environment[1] > 0.0f || scene.environment[2] > 0.0f) {
            /* the sky as the CPU hosts light it: each surfel's traced visibility S (glow_host), on the GPU too */
            glow_host_desc skd = glow_host_desc_from_scene(&scene, bake, GLOW_HOST_KIND_EXACT);
            skd.logger = logger;
            glow_surfel_view sv;
            glow_system_get_surfels(sys, &sv);
            float *S = malloc((size_t)sv.count * sizeof *S);
            if (!S) goto done;
            if ((r = glow_host_create(&skd, &host)) == GLOW_OK && (r = glow_host_sky_visibility(host, &sv, S, sv.count)) == GLOW_OK)
                r = glow_gl_lights_set_sky_visibility(gll, S, sv.count);
            free(S);
            glow_host_destroy(host);
            host = NULL;
            if (r != GLOW_OK) goto done;
        }
        glow_gl_desc gd = {.system = sys, .get_proc_address = glow_glctx_get_proc_address(glc),
                           .hook_glsl = glow_gl_lights_hook_source(gll), .label = o.bake, .logger = logger,
                           .flags = o.gl_finish ? GLOW_GL_FLAG_FINISH_TIMERS : 0u};
        if ((r = glow_gl_system_create(&gd, &gls)) != GLOW_OK) goto done;
        if (budget) { /* the unbudgeted reference: a second GL system on the same tables and lights */
            gd.label = "twin";
            if ((r = glow_gl_system_create(&gd, &glt)) != GLOW_OK) goto done;
            const size_t ncs = (size_t)out->cache_count * out->coeff_count;
            sh_a = malloc((ncs + 1) * sizeof *sh_a);
            sh_b = malloc((ncs + 1) * sizeof *sh_b);
            if (!sh_a || !sh_b) goto done;
        }
        lights = calloc(scene.light_count ? scene.light_count : 1u, sizeof *lights);
        if (!lights) goto done;
        if (scene.light_count) memcpy(lights, scene.lights, scene.light_count * sizeof *lights);
    }
#endif
    uint32_t threads = o.threads;
    if (threads == 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        threads = n > 0 ? (uint32_t)n : 1u;
    }

    float diag = 0.0f;
    for (int k = 0; k < 3; ++k) diag += (info.bounds_max[k] - info.bounds_min[k]) * (info.bounds_max[k] - info.bounds_min[k]);
    diag = sqrtf(diag);
    const uint32_t n = o.frames, total = o.warmup + o.frames;
    v_host = calloc(n, sizeof(double)); v_light = calloc(n, sizeof(double)); v_pull = calloc(n, sizeof(double));
    v_cache = calloc(n, sizeof(double)); v_out = calloc(n, sizeof(double)); v_total = calloc(n, sizeof(double));
    v_move = calloc(n, sizeof(double));
    v_err = calloc(n, sizeof(double));
    v_gath = calloc(n, sizeof(double));
    v_skip = calloc(n, sizeof(double));
    v_errn = calloc(n, sizeof(double));
    if (!v_host || !v_light || !v_pull || !v_cache || !v_out || !v_total || !v_move || !v_err || !v_gath || !v_skip || !v_errn) goto done;
    bool has_twin = twin != NULL;
#ifdef GLOW_BENCH_HAVE_GL
    has_twin = has_twin || glt != NULL;
#endif
    const bool walk = o.walk && has_twin;
    const float near_r = 0.1f * diag;
    if (walk) { /* from 5 % in at one end of the longest horizontal extent to 5 % in at the other */
        cinfo = malloc(((size_t)info.cache_count + 1) * sizeof *cinfo);
        if (!cinfo || (r = glow_bake_get_caches(bake, 0, info.cache_count, cinfo)) != GLOW_OK) goto done;
        walk_ends(info.bounds_min, info.bounds_max, &scene, walk_a, walk_b);
        o.has_focus = 1;
        ud.focus = o.focus;
        ud.focus_count = 1;
    }
    glow_update_stats st = {0};
    for (uint32_t f = 0; f < total; ++f) {
        if (walk) {
            const float u = total > 1 ? (float)f / (float)(total - 1) : 0.0f;
            for (int k = 0; k < 3; ++k) o.focus[k] = walk_a[k] + u * (walk_b[k] - walk_a[k]);
        }
        double t0 = now_ms();
        /* move the first light (or pulse the emission) */
        if (o.still) {
        } else if (scene.light_count > 0) {
            glow_scene_light l;
            animate(&scene.lights[0], &l, f, total, 0.05f * diag);
#ifdef GLOW_BENCH_HAVE_GL
            if (o.gl) {
                lights[0] = l;
                if ((r = glow_gl_lights_set(gll, lights, scene.light_count, scene.environment)) != GLOW_OK) goto done;
            } else
#endif
            if ((r = glow_host_set_light(host, 0, &l)) != GLOW_OK ||
                (twin_host && (r = glow_host_set_light(twin_host, 0, &l)) != GLOW_OK))
                goto done;
        } else {
            float pulse = scene.emission_scale * (0.75f + 0.25f * (float)cos(6.283185307 * f / total));
            glow_system_set_params(sys, &(glow_system_params){1.0f, pulse, o.iterations});
            if (twin) glow_system_set_params(twin, &(glow_system_params){1.0f, pulse, o.iterations});
        }
        double t1 = now_ms();
        /* one update; the GL backend's stage times go into the CPU stats' fields */
#ifdef GLOW_BENCH_HAVE_GL
        if (o.gl) {
            glow_gl_lights_bind(gll);
            glow_update_desc u = budget ? ud : (glow_update_desc){0};
            if (o.keep_lighting && f > 0) u.flags |= GLOW_UPDATE_FLAG_KEEP_LIGHTING;
            if ((r = glow_gl_system_update(gls, &u)) != GLOW_OK) goto done;
            glow_gl_stats gs;
            glow_gl_system_get_stats(gls, &gs); /* waits for this update's timer queries */
            st.caches_gathered = gs.caches_gathered;
            if (glt) { /* untimed reference, then both read back for the budget's error below */
                glow_gl_lights_bind(gll);
                if ((r = glow_gl_system_update(glt, NULL)) != GLOW_OK) goto done;
                const size_t ncs = (size_t)out->cache_count * out->coeff_count;
                if (f >= o.warmup && ((r = glow_gl_system_read_cache_sh(gls, sh_a, ncs)) != GLOW_OK ||
                                      (r = glow_gl_system_read_cache_sh(glt, sh_b, ncs)) != GLOW_OK))
                    goto done;
            }
            st.host_ms = gs.host_ms;
            st.surfel_lighting_ms = gs.surfel_lighting_ms;
            st.pull_ms = gs.pull_ms;
            st.cache_lighting_ms = gs.cache_lighting_ms;
            st.output_ms = gs.output_ms;
            st.total_ms = gs.total_ms;
            st.memory_bytes = gs.gpu_memory_bytes;
        } else
#endif
        {
            glow_update_desc u = budget ? ud : (glow_update_desc){0};
            if (o.keep_lighting && f > 0) u.flags |= GLOW_UPDATE_FLAG_KEEP_LIGHTING;
            if ((r = glow_system_update(sys, &u)) != GLOW_OK) goto done;
            glow_system_get_stats(sys, &st);
            if (twin && (r = glow_system_update(twin, NULL)) != GLOW_OK) goto done; /* untimed reference */
        }
        if (f >= o.warmup) {
            uint32_t i = f - o.warmup;
            v_move[i] = t1 - t0;
            v_host[i] = st.host_ms;
            v_light[i] = st.surfel_lighting_ms;
            v_pull[i] = st.pull_ms;
            v_cache[i] = st.cache_lighting_ms;
            v_out[i] = st.output_ms;
            v_total[i] = st.total_ms;
            v_gath[i] = st.caches_gathered;
            v_skip[i] = st.surfels_skipped_budget;
            if (has_twin) { /* the budget's cost this frame: the caches' luma (DC) against the unbudgeted twin */
                const uint32_t cc = out->coeff_count;
                const float *A = twin ? glow_system_outputs(sys)->cache_sh : sh_a;
                const float *B = twin ? glow_system_outputs(twin)->cache_sh : sh_b;
                double num = 0.0, den = 0.0, numn = 0.0, denn = 0.0;
                for (uint32_t c = 0; c < out->cache_count; ++c) {
                    const double x = A[(size_t)c * cc], y = B[(size_t)c * cc];
                    num += fabs(x - y);
                    den += fabs(y);
                    if (walk) {
                        float d[3];
                        for (int k = 0; k < 3; ++k) d[k] = cinfo[c].position[k] - o.focus[k];
                        if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= near_r * near_r) {
                            numn += fabs(x - y);
                            denn += fabs(y);
                        }
                    }
                }
                v_err[i] = den > 0.0 ? num / den : 0.0;
                v_errn[i] = denn > 0.0 ? numn / denn : 0.0;
            }
        }
    }
    const double m_move = glow_cli_median(v_move, n), m_host = glow_cli_median(v_host, n), m_light = glow_cli_median(v_light, n),
                 m_pull = glow_cli_median(v_pull, n), m_cache = glow_cli_median(v_cache, n), m_out = glow_cli_median(v_out, n),
                 m_total = glow_cli_median(v_total, n);
    double e_mean = 0.0, e_max = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
        e_mean += v_err[i] / n;
        if (v_err[i] > e_max) e_max = v_err[i];
    }
    const double e_med = glow_cli_median(v_err, n), m_gath = glow_cli_median(v_gath, n), m_skip = glow_cli_median(v_skip, n);
    double en_mean = 0.0, en_max = 0.0, en_last = 0.0; /* --walk: near the focus; the last quarter of the walk */
    const uint32_t q0 = n - n / 4;
    for (uint32_t i = 0; i < n; ++i) {
        en_mean += v_errn[i] / n;
        if (v_errn[i] > en_max) en_max = v_errn[i];
        if (i >= q0 && n / 4) en_last += v_errn[i] / (n / 4);
    }
    const double en_med = glow_cli_median(v_errn, n);
    const uint64_t links = (uint64_t)(budget ? m_gath : (double)info.cache_count) * info.links_per_cache * o.iterations;
    const double link_bytes = (double)links * 8.0;
    const double gbs = links ? link_bytes / (m_cache * 1e-3) * 1e-9 : 0.0; /* links 0: a converged budget */
    const double fpl = flops_per_link(out->sh_bands_luma, out->sh_bands_chroma);
    const double gflops = links ? (double)links * fpl / (m_cache * 1e-3) * 1e-9 : 0.0;
    double triad = -1.0, peak = -1.0, line_rt = -1.0;
    const char *fma_isa = "-";
    if (!o.no_probe_machine && !o.gl) { /* the CPU's limits say nothing about a GPU */
        triad = glow_probe_stream_triad(threads, (size_t)1 << 23, 8); /* 3 x 64 MiB */
        peak = glow_probe_fma_peak(threads, 300.0, &fma_isa);
        if (threads > 1) line_rt = glow_probe_line_round_trip(200000u); /* ~0.1 s on this VM */
    }
    /* probes: indirect light (diffuse, normal +Y) from the grid */
    if (o.probe_count == 0 && out->grid_map) {
        for (int k = 0; k < 3; ++k) {
            float t = (float)(k + 1) / 4.0f;
            for (int a = 0; a < 3; ++a)
                o.probes[k][a] = info.bounds_min[a] + t * (info.bounds_max[a] - info.bounds_min[a]);
        }
        o.probe_count = 3;
    }
#ifdef GLOW_BENCH_HAVE_GL
    if (o.gl) { /* probes read the GPU's caches (read back) through the C sampler */
        const size_t ncs = (size_t)out->cache_count * out->coeff_count;
        gpu_sh = malloc(ncs * sizeof *gpu_sh);
        if (!gpu_sh || (r = glow_gl_system_read_cache_sh(gls, gpu_sh, ncs)) != GLOW_OK) goto done;
        gpu_out = *out;
        gpu_out.cache_sh = gpu_sh;
        out = &gpu_out;
    }
#endif
    float probe_rgb[MAX_PROBES][3];
    int probe_ok[MAX_PROBES];
    float *coeffs = calloc(out->coeff_count, sizeof(float));
    if (!coeffs) goto done;
    for (uint32_t k = 0; k < o.probe_count; ++k) {
        probe_ok[k] = out->grid_map && glow_sample_grid(out, o.probes[k], coeffs) == GLOW_OK;
        const float up[3] = {0, 1, 0};
        if (probe_ok[k]) glow_shade_sh(coeffs, out->sh_bands_luma, out->sh_bands_chroma, up, 1.0f, probe_rgb[k]);
        else probe_rgb[k][0] = probe_rgb[k][1] = probe_rgb[k][2] = 0.0f;
    }
    free(coeffs);
    const char *bound = "-";
    double frac_bw = triad > 0 ? gbs / triad : -1.0, frac_fma = peak > 0 ? gflops / peak : -1.0;
    if (triad > 0 && peak > 0) {
        /* the floor each resource sets: link bytes / triad vs FLOPs / peak; the larger one bounds */
        double t_bw = link_bytes / (triad * 1e9), t_fl = (double)links * fpl / (peak * 1e9);
        bound = t_bw > t_fl ? "memory bandwidth" : "FMA throughput";
    }
    if (o.json) {
        cJSON *jo = cJSON_CreateObject(), *jm, *jc, *jmach, *jp;
        cJSON_AddStringToObject(jo, "bake", o.bake);
        cJSON_AddStringToObject(jo, "scene", o.scene);
        cJSON_AddStringToObject(jo, "host", o.host == GLOW_HOST_KIND_EXACT ? "exact" : "shadow-map");
        cJSON_AddNumberToObject(jo, "threads", threads);
        cJSON_AddNumberToObject(jo, "frames", n);
#ifdef GLOW_BENCH_HAVE_GL
        if (o.gl) {
            cJSON_AddStringToObject(jo, "backend", "gl");
            cJSON_AddStringToObject(jo, "renderer", gl_renderer);
            cJSON_AddStringToObject(jo, "gl_timing", o.gl_finish ? "finish" : "queries");
            cJSON_AddNumberToObject(jo, "gpu_memory_bytes", (double)st.memory_bytes);
        } else
#endif
        {
            cJSON_AddStringToObject(jo, "backend", "cpu");
            cJSON_AddStringToObject(jo, "link_mode", link_mode_name(st.link_mode));
            cJSON_AddStringToObject(jo, "output_planes", planes_name(o.planes));
            cJSON_AddStringToObject(jo, "kernel", st.kernel ? st.kernel : "-");
            cJSON_AddNumberToObject(jo, "system_memory_bytes", (double)st.memory_bytes);
        }
        cJSON_AddNumberToObject(jo, "surfels", info.surfel_count);
        cJSON_AddNumberToObject(jo, "caches", info.cache_count);
        cJSON_AddNumberToObject(jo, "links_per_cache", info.links_per_cache);
        cJSON_AddNumberToObject(jo, "luma", out->sh_bands_luma);
        cJSON_AddNumberToObject(jo, "chroma", out->sh_bands_chroma);
        cJSON_AddNumberToObject(jo, "iterations", o.iterations);
        jm = cJSON_AddObjectToObject(jo, "median_ms");
        glow_json_num(jm, "light_move", m_move);
        glow_json_num(jm, "host_hook", m_host);
        glow_json_num(jm, "surfel_lighting", m_light);
        glow_json_num(jm, "pull", m_pull);
        glow_json_num(jm, "cache_lighting", m_cache);
        glow_json_num(jm, "output", m_out);
        glow_json_num(jm, "total", m_total);
        jc = cJSON_AddObjectToObject(jo, "cache_lighting");
        cJSON_AddNumberToObject(jc, "links", (double)links);
        glow_json_num(jc, "link_bytes", link_bytes);
        glow_json_num(jc, "gb_per_s", gbs);
        glow_json_num(jc, "flops_per_link", fpl);
        glow_json_num(jc, "gflop_per_s", gflops);
        glow_json_num(jc, "ns_per_link", links ? m_cache * 1e6 / (double)links : 0.0);
        jmach = cJSON_AddObjectToObject(jo, "machine");
        glow_json_num(jmach, "stream_triad_gb_per_s", triad);
        glow_json_num(jmach, "fma_peak_gflop_per_s", peak);
        glow_json_num(jmach, "line_round_trip_ns", line_rt);
        cJSON_AddStringToObject(jmach, "fma_isa", fma_isa);
        glow_json_num(jmach, "fraction_of_triad", frac_bw);
        glow_json_num(jmach, "fraction_of_fma_peak", frac_fma);
        cJSON_AddStringToObject(jmach, "bound", bound);
        jp = cJSON_AddArrayToObject(jo, "probes");
        for (uint32_t k = 0; jp && k < o.probe_count; ++k) {
            cJSON *pr = cJSON_CreateObject();
            cJSON_AddItemToArray(jp, pr);
            const double pos[3] = {o.probes[k][0], o.probes[k][1], o.probes[k][2]};
            const double rgb[3] = {probe_rgb[k][0], probe_rgb[k][1], probe_rgb[k][2]};
            glow_json_array3(pr, "position", pos);
            cJSON_AddBoolToObject(pr, "ok", probe_ok[k]);
            glow_json_array3(pr, "diffuse_up_rgb", rgb);
        }
        if (budget) {
            cJSON *jb = cJSON_AddObjectToObject(jo, "budget");
            glow_json_num(jb, "budget_ms", o.budget_ms);
            cJSON_AddNumberToObject(jb, "budget_caches", o.budget_caches);
            glow_json_num(jb, "converge", o.converge);
            glow_json_num(jb, "median_caches_gathered", m_gath);
            glow_json_num(jb, "median_surfels_skipped_budget", m_skip);
            glow_json_num(jb, "luma_error_mean", e_mean);
            glow_json_num(jb, "luma_error_median", e_med);
            glow_json_num(jb, "luma_error_max", e_max);
            if (walk) {
                glow_json_num(jb, "walk_near_radius", near_r);
                glow_json_num(jb, "walk_near_error_mean", en_mean);
                glow_json_num(jb, "walk_near_error_median", en_med);
                glow_json_num(jb, "walk_near_error_max", en_max);
                glow_json_num(jb, "walk_near_error_last_quarter", en_last);
            }
        }
        if (glow_json_print(jo) != 0) goto done;
    } else {
        printf("glow-bench %s + %s: %u surfels, %u caches x %u links, SH luma %u chroma %u, %u thread(s), %s host\n",
               o.bake, o.scene, info.surfel_count, info.cache_count, info.links_per_cache, out->sh_bands_luma,
               out->sh_bands_chroma, threads, o.host == GLOW_HOST_KIND_EXACT ? "exact" : "shadow-map");
#ifdef GLOW_BENCH_HAVE_GL
        if (o.gl)
            printf("backend gl: %s, GPU memory %.1f MiB (GPU times from %s)\n", gl_renderer,
                   (double)st.memory_bytes / (1024.0 * 1024.0), o.gl_finish ? "glFinish + CPU clock" : "timer queries");
        else
#endif
        printf("links %s, kernel %s, output planes %s, system memory %.1f MiB\n", link_mode_name(st.link_mode),
               st.kernel ? st.kernel : "-", planes_name(o.planes),
               (double)st.memory_bytes / (1024.0 * 1024.0));
        printf("median of %u updates (ms):\n", n);
        printf("  light move (host, outside update) %8.3f%s\n", m_move, o.gl ? "  (GPU shadow maps: CPU time to submit)" : "");
        printf("  surfel lighting                   %8.3f  (host hook %.3f)\n", m_light, m_host);
        printf("  pull                              %8.3f\n", m_pull);
        printf("  cache lighting                    %8.3f  (%.2f ns/link)\n", m_cache, links ? m_cache * 1e6 / (double)links : 0.0);
        printf("  outputs                           %8.3f\n", m_out);
        printf("  total update                      %8.3f  (without host hook %.3f)\n", m_total, m_total - m_host);
        if (budget)
            printf("budget (%.3g ms, %u caches, converge %.3g): median %.0f of %u caches gathered and %.0f of %u surfels "
                   "not relit per update; their luma against an unbudgeted twin: error mean %.4f, median %.4f, max %.4f "
                   "(relative L1)\n",
                   (double)o.budget_ms, o.budget_caches, (double)o.converge, m_gath, info.cache_count, m_skip,
                   info.surfel_count, e_mean, e_med, e_max);
        if (walk)
            printf("walk: the focus crosses the scene (%.3g, %.3g, %.3g) -> (%.3g, %.3g, %.3g); caches within %.3g of it: "
                   "error mean %.4f, median %.4f, max %.4f, last quarter of the walk %.4f\n",
                   walk_a[0], walk_a[1], walk_a[2], walk_b[0], walk_b[1], walk_b[2], (double)near_r, en_mean, en_med, en_max,
                   en_last);
        printf("cache lighting: %.2f GB/s of links (8 B each), %.1f GFLOP/s (%.0f FLOPs per link)\n", gbs, gflops, fpl);
        if (triad > 0)
            printf("machine (%u threads): STREAM triad %.2f GB/s, fp32 FMA peak %.1f GFLOP/s [%s]\n"
                   "  cache lighting reaches %.1f %% of triad and %.1f %% of FMA peak; %s sets the floor\n",
                   threads, triad, peak, fma_isa, 100.0 * frac_bw, 100.0 * frac_fma, bound);
        if (line_rt > 0)
            printf("machine: a cache line between two threads %.0f ns there and back (the other core's writes "
                   "cost about half that per line)\n",
                   line_rt);
        for (uint32_t k = 0; k < o.probe_count; ++k)
            printf("indirect light at (%.3g, %.3g, %.3g), diffuse facing +Y: %s%.4g %.4g %.4g W/(m^2 sr)\n",
                   o.probes[k][0], o.probes[k][1], o.probes[k][2], probe_ok[k] ? "" : "(no grid cache near) ",
                   probe_rgb[k][0], probe_rgb[k][1], probe_rgb[k][2]);
    }
    rc = 0;
done:
    if (rc != 0 && r != GLOW_OK) fprintf(stderr, "glow-bench: failed: %s\n", glow_result_string(r));
    free(gpu_sh);
    free(sh_a);
    free(sh_b);
#ifdef GLOW_BENCH_HAVE_GL
    free(lights);
    glow_gl_system_destroy(glt);
    glow_gl_system_destroy(gls);
    glow_gl_lights_destroy(gll);
    glow_glctx_destroy(glc);
#endif
    free(v_host); free(v_light); free(v_pull); free(v_cache); free(v_out); free(v_total); free(v_move);
    glow_system_destroy(twin);
    glow_system_destroy(sys);
    free(v_err);
    free(v_gath);
    free(v_skip);
    free(v_errn);
    free(cinfo);
    glow_host_destroy(host);
    glow_host_destroy(twin_host);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    glow_scene_free(&scene);
    return rc;
}
