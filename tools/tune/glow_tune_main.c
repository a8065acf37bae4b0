/* glow-tune — the bounce tuning tool a lighting artist uses (docs/tune.md).
 *
 *   glow-tune BAKE SCENE [--iterations N] [--epsilon E] [--bounce LIST] [--per-update LIST]
 *             [--host exact|shadow-map] [--threads N] [--luma L] [--chroma C] [--out DIR] [--no-chart]
 *             [--json] [-q]
 *
 * Runs the progressive solver (one feedback iteration per update, GLOW_UPDATE_FLAG_RESET_BOUNCE on the
 * first) with the scene's static lights and reports, per update, the total indirect energy, its change
 * from the previous update, the geometric convergence ratio, how many updates it takes to converge
 * within ε, for every bounce intensity of --bounce; then, at the largest of them, how bounce_iterations
 * per update (--per-update) changes the updates needed. Writes DIR/summary.json, DIR/convergence.dat,
 * DIR/convergence.gp and (gnuplot) DIR/convergence.png.
 *
 * TOTAL INDIRECT ENERGY (W): Φ_ind = Σ_surfels A_s · E_ind(s), the indirect flux arriving at the scene's
 * surfaces, sampled at the bake's surfels (A_s their areas, which sum to the scene's area).
 * E_ind(s) = π · max(0, glow_shade_sh(lightmap SH at the surfel, n_s, exponent 1)) per RGB channel: the
 * diffuse indirect irradiance a lightmapped surface shows at the surfel (the lightmap sampled bilinearly at
 * the surfel's lightmap UV, from its triangle's corners in the bake geometry; where the lightmap has no
 * cache there, the grid at the surfel's position). The clamp is the runtime's own (the feedback and the
 * renderers use max(0, E_ind)). Luma = R/4 + G/2 + B/4 (YCoCg Y, the runtime's luma channel).
 * TRANSPORT (the energy check): (E_k - E_{k-1}) / (bounce · Σ ρ_s A_s ΔE_ind,k-1(s)), the share of the light the
 * surfaces reflected of the previous update's new indirect light that arrives at a surface again: 1 in a closed
 * scene, < 1 where light escapes, > 1 only if the solver created energy. Update 1: E_1 / Σ A (ρ E_direct + π L_e).
 * Only the public API is used (glow.h, glow_host.h, glow_scene.h).
 *
 * Exit: 0 ok (a missing or failing gnuplot is a warning: "chart": null), 1 bad input or runtime failure
 * (the message names the file), 2 usage. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "glow_cli.h"
#include "glow/glow.h"
#include "glow/glow_host.h"
#include "glow/glow_scene.h"

#define PI_D 3.14159265358979323846
#define MAX_BOUNCES 16
#define MAX_PER_UPDATE 8
#define NOISE_REL 1e-6 /* relative differences below this are float noise: no ratio from them */

typedef struct options {
    const char *bake, *scene, *out;
    uint32_t iterations, threads, luma, chroma;
    double epsilon;
    float bounce[MAX_BOUNCES];
    uint32_t bounce_count;
    uint32_t per_update[MAX_PER_UPDATE];
    uint32_t per_update_count;
    glow_host_kind host;
    int json, quiet, no_chart;
} options;

/* one measured run: `updates` updates of `per_update` feedback iterations at bounce intensity b */
typedef struct run {
    float bounce;
    uint32_t per_update, updates;
    double *e;       /* [updates][4]: luma, R, G, B (W) after each update */
    double *rel;     /* [updates] |E_k - E_{k-1}| / E_k (luma; E_0 = 0) */
    double *ratio;   /* [updates] (E_k - E_{k-1}) / (E_{k-1} - E_{k-2}), NAN where undefined */
    double *ms;      /* [updates] glow_update_stats.total_ms */
    double median_ms, asymptotic_ratio, limit_luma;
    double *refl;    /* [updates] luma of Σ_s ρ_s A_s (E_k(s) - E_{k-1}(s)): what the surfaces reflect of the
                        update's new indirect light (the next update's increment before bounce intensity) */
    double *transport; /* [updates] (E_k - E_{k-1}) / (bounce · refl_{k-1}), NAN where undefined: the share of
                          reflected light that arrives at a surface again (<= 1 conserves energy) */
    double asymptotic_transport, increment_albedo; /* medians over the last defined updates */
    long converge;        /* updates until the relative change stays below ε; -1 = not within the run */
    long within_eps;      /* updates until |E_k - E_limit| / E_limit stays below ε; -1 = not within */
} run;

/* what the energy evaluation needs of each surfel (copied from the system's surfel view) */
typedef struct surfel_probe {
    float pos[3], nrm[3], area, u, v;
    float albedo[3]; /* the material's, clamped to [0, 0.999] as the runtime does (textures not included) */
    int has_uv;
    uint32_t page; /* its triangle's lightmap page */
} surfel_probe;

typedef struct sampler {
    surfel_probe *s;
    uint32_t count;
    float *coeffs;
    double *prev; /* [count][3] A_s E_ind(s) of the previous update (zero at a run's start) */
    double direct[4], source[4];      /* luma, RGB (W): Σ A E_direct, and Σ A (ρ E_direct + π L_e · emission_scale) */
    int textured;                     /* a material has an albedo texture: ρ here is the material's untextured albedo */
    uint64_t from_lightmap, from_grid, missed; /* of the last evaluation */
} sampler;

static void usage(FILE *f) {
    fprintf(f,
            "usage: glow-tune BAKE SCENE [--iterations N] [--epsilon E] [--bounce LIST] [--per-update LIST]\n"
            "                 [--host exact|shadow-map] [--threads N] [--luma L] [--chroma C] [--out DIR]\n"
            "                 [--no-chart] [--json] [-q]\n"
            "  BAKE   a bake written by glow-bake;  SCENE  its scene description JSON (docs/scene-format.md)\n"
            "  Runs the progressive solver from no indirect light and reports, per update, the total indirect\n"
            "  energy (indirect flux arriving at the surfaces, W), its relative change and the convergence\n"
            "  ratio, and the updates needed to converge within epsilon, for each bounce intensity.\n"
            "  --iterations N   updates per run (default 32; 1..10000), one feedback iteration each\n"
            "  --epsilon E      convergence threshold on the relative change (default 0.01; 0 < E < 1)\n"
            "  --bounce LIST    bounce intensities to compare, comma-separated in [0,1] (default 0,0.25,0.5,0.75,1)\n"
            "  --per-update LIST  bounce_iterations per update to compare at the largest bounce intensity\n"
            "                   (default 1,2,4; each 1..64)\n"
            "  --host           surfel lighting: exact Embree rays (default) or software shadow maps\n"
            "  --threads N      runtime workers (default: one per online CPU)\n"
            "  --luma/--chroma  SH bands (default: the bake's; chroma = luma)\n"
            "  --out DIR        summary.json, convergence.dat/.gp/.png (default ./glow-tune-out)\n"
            "  --no-chart       do not run gnuplot (\"chart\": null)\n"
            "  --json           print summary.json to stdout instead of the tables;  -q  no tables\n"
            "Exit: 0 ok, 1 bad input or runtime failure, 2 bad command line.\n");
}



/* "a,b,c" -> floats in [0,1] */
static int parse_bounce_list(const char *s, options *o) {
    char buf[512];
    if (strlen(s) >= sizeof buf) return 0;
    strcpy(buf, s);
    o->bounce_count = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        double v;
        if (o->bounce_count == MAX_BOUNCES || !glow_cli_double(tok, &v) || v < 0.0 || v > 1.0) return 0;
        o->bounce[o->bounce_count++] = (float)v;
    }
    return o->bounce_count > 0 && s[strlen(s) - 1] != ',';
}

static int parse_per_update_list(const char *s, options *o) {
    char buf[256];
    if (strlen(s) >= sizeof buf) return 0;
    strcpy(buf, s);
    o->per_update_count = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        uint32_t v;
        if (o->per_update_count == MAX_PER_UPDATE || !glow_cli_u32(tok, 1, 64, &v)) return 0;
        o->per_update[o->per_update_count++] = v;
    }
    return o->per_update_count > 0 && s[strlen(s) - 1] != ',';
}

/* 0 = ok; 2 = usage error (message printed); 3 = --help printed */
static int parse_args(int argc, char **argv, options *o) {
    memset(o, 0, sizeof *o);
    o->iterations = 32;
    o->epsilon = 0.01;
    o->out = "glow-tune-out";
    o->host = GLOW_HOST_KIND_EXACT;
    parse_bounce_list("0,0.25,0.5,0.75,1", o);
    parse_per_update_list("1,2,4", o);
    int pos = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int ok = 1, takes = 1;
        if (!strcmp(a, "--iterations")) ok = v && glow_cli_u32(v, 1, 10000, &o->iterations);
        else if (!strcmp(a, "--threads")) ok = v && glow_cli_u32(v, 0, 1024, &o->threads);
        else if (!strcmp(a, "--luma")) ok = v && glow_cli_u32(v, 1, GLOW_MAX_SH_BANDS, &o->luma);
        else if (!strcmp(a, "--chroma")) ok = v && glow_cli_u32(v, 1, GLOW_MAX_SH_BANDS, &o->chroma);
        else if (!strcmp(a, "--epsilon")) ok = v && glow_cli_double(v, &o->epsilon) && o->epsilon > 0.0 && o->epsilon < 1.0;
        else if (!strcmp(a, "--bounce")) ok = v && parse_bounce_list(v, o);
        else if (!strcmp(a, "--per-update")) ok = v && parse_per_update_list(v, o);
        else if (!strcmp(a, "--out")) {
            ok = v && *v;
            if (ok) o->out = v;
        }
        else if (!strcmp(a, "--host")) {
            ok = v && (!strcmp(v, "exact") || !strcmp(v, "shadow-map"));
            if (ok) o->host = !strcmp(v, "exact") ? GLOW_HOST_KIND_EXACT : GLOW_HOST_KIND_SHADOW_MAP;
        } else {
            takes = 0;
            if (!strcmp(a, "--json")) o->json = 1;
            else if (!strcmp(a, "-q")) o->quiet = 1;
            else if (!strcmp(a, "--no-chart")) o->no_chart = 1;
            else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
                usage(stdout);
                return 3;
            } else if (a[0] == '-' && a[1] != '\0') {
                fprintf(stderr, "glow-tune: unknown option %s\n", a);
                return 2;
            } else if (pos == 0) o->bake = a, pos++;
            else if (pos == 1) o->scene = a, pos++;
            else {
                fprintf(stderr, "glow-tune: unexpected argument %s\n", a);
                return 2;
            }
        }
        if (!ok) {
            static const char *const why[][2] = {
                {"--iterations", "a whole number in 1..10000"}, {"--threads", "a whole number in 0..1024"},
                {"--luma", "a band count in 1..8"}, {"--chroma", "a band count in 1..8"},
                {"--epsilon", "a number with 0 < E < 1"},
                {"--bounce", "comma-separated numbers in [0, 1] (at most 16)"},
                {"--per-update", "comma-separated whole numbers in 1..64 (at most 8)"},
                {"--out", "a folder"}, {"--host", "exact or shadow-map"}};
            const char *need = "a value";
            for (size_t k = 0; k < sizeof why / sizeof why[0]; ++k)
                if (!strcmp(a, why[k][0])) need = why[k][1];
            fprintf(stderr, "glow-tune: %s needs %s%s%s%s\n", a, need, v ? ", not '" : "", v ? v : "", v ? "'" : "");
            return 2;
        }
        i += takes;
    }
    if (pos != 2) {
        fprintf(stderr, "glow-tune: need BAKE and SCENE\n");
        return 2;
    }
    if (o->luma && o->chroma && o->chroma > o->luma) {
        fprintf(stderr, "glow-tune: --chroma (%u) must not exceed --luma (%u)\n", o->chroma, o->luma);
        return 2;
    }
    return 0;
}



/* median of a copy (v is kept) */
static double median_of(const double *v, uint32_t n) {
    double *t = n ? malloc(sizeof(double) * n) : NULL;
    if (!t) return NAN;
    memcpy(t, v, sizeof(double) * n);
    const double m = glow_cli_median(t, n);
    free(t);
    return m;
}

/* ------------------------------------------------------------------ the energy */

/* the surfels, with their lightmap UV (barycentrics of the surfel centre in its triangle) */
static int sampler_init(sampler *sm, const glow_system *sys, const glow_bake *bake, const glow_cache_outputs *o,
                        glow_host *host, float emission_scale) {
    glow_bake_info info;
    if (glow_bake_get_info(bake, &info) != GLOW_OK) return 0;
    memset(sm, 0, sizeof *sm);
    glow_surfel_view view;
    glow_bake_geometry geo;
    if (glow_system_get_surfels(sys, &view) != GLOW_OK || glow_bake_get_geometry(bake, &geo) != GLOW_OK) return 0;
    sm->count = view.count;
    sm->s = calloc(view.count ? view.count : 1, sizeof *sm->s);
    sm->coeffs = calloc(o->coeff_count, sizeof(float));
    sm->prev = calloc((size_t)(view.count ? view.count : 1) * 3, sizeof(double));
    if (!sm->s || !sm->coeffs || !sm->prev) return 0;
    const int lightmap = o->lightmap_sh && geo.triangle_count > 0 && geo.lightmap_uv;
    for (uint32_t i = 0; i < view.count; ++i) {
        surfel_probe *p = &sm->s[i];
        memcpy(p->pos, view.positions + 4 * (size_t)i, sizeof p->pos);
        p->area = view.positions[4 * (size_t)i + 3];
        memcpy(p->nrm, view.normals + 4 * (size_t)i, sizeof p->nrm);
        glow_material_info m;
        if (glow_bake_get_material(bake, view.materials[i], &m) == GLOW_OK) {
            for (int c = 0; c < 3; ++c) {
                p->albedo[c] = m.albedo[c] < 0.0f ? 0.0f : m.albedo[c] > 0.999f ? 0.999f : m.albedo[c];
                sm->source[1 + c] += (double)p->area * PI_D * m.emission[c] * emission_scale;
            }
            sm->textured |= m.has_albedo_texture != 0;
        }
        const uint32_t t = view.triangles[i];
        if (!lightmap || t >= geo.triangle_count) continue;
        float c[9];
        uint16_t uv[6];
        memcpy(c, (const char *)geo.positions + (size_t)t * geo.stride, sizeof c);
        memcpy(uv, (const char *)geo.lightmap_uv + (size_t)t * geo.stride, sizeof uv);
        double e0[3], e1[3], d[3];
        for (int k = 0; k < 3; ++k) {
            e0[k] = (double)c[3 + k] - c[k];
            e1[k] = (double)c[6 + k] - c[k];
            d[k] = (double)p->pos[k] - c[k];
        }
        const double d00 = e0[0] * e0[0] + e0[1] * e0[1] + e0[2] * e0[2];
        const double d01 = e0[0] * e1[0] + e0[1] * e1[1] + e0[2] * e1[2];
        const double d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
        const double d20 = d[0] * e0[0] + d[1] * e0[1] + d[2] * e0[2];
        const double d21 = d[0] * e1[0] + d[1] * e1[1] + d[2] * e1[2];
        const double den = d00 * d11 - d01 * d01;
        if (!(den > 0.0)) continue;
        double b1 = (d11 * d20 - d01 * d21) / den, b2 = (d00 * d21 - d01 * d20) / den;
        b1 = b1 < 0.0 ? 0.0 : b1 > 1.0 ? 1.0 : b1; /* the centre lies in its triangle; guard rounding */
        b2 = b2 < 0.0 ? 0.0 : b2 > 1.0 - b1 ? 1.0 - b1 : b2;
        const double b0 = 1.0 - b1 - b2;
        p->u = (float)((b0 * uv[0] + b1 * uv[2] + b2 * uv[4]) / 65535.0);
        p->v = (float)((b0 * uv[1] + b1 * uv[3] + b2 * uv[5]) / 65535.0);
        p->has_uv = 1;
        p->page = geo.lightmap_page ? geo.lightmap_page[t] : 0u;
    }
    /* the direct light the runtime receives: the host's own hook over all surfels (it ignores `worker`) */
    float *e = malloc(sizeof(float) * 3 * (view.count ? view.count : 1));
    const glow_lighting_hooks hooks = glow_host_hooks(host);
    const glow_surfel_batch batch = {.first = 0, .count = view.count, .positions = view.positions,
                                     .normals = view.normals, .materials = view.materials};
    const int lit = e && hooks.light_surfels && hooks.light_surfels(hooks.user, &batch, e, 0) == GLOW_OK;
    for (uint32_t i = 0; lit && i < view.count; ++i)
        for (int c = 0; c < 3; ++c) {
            const double flux = (double)sm->s[i].area * (e[3 * (size_t)i + c] > 0.0f ? e[3 * (size_t)i + c] : 0.0f);
            sm->direct[1 + c] += flux;
            sm->source[1 + c] += sm->s[i].albedo[c] * flux;
        }
    free(e);
    if (!lit) return 0;
    sm->direct[0] = 0.25 * sm->direct[1] + 0.5 * sm->direct[2] + 0.25 * sm->direct[3];
    sm->source[0] = 0.25 * sm->source[1] + 0.5 * sm->source[2] + 0.25 * sm->source[3];
    return 1;
}

static void sampler_free(sampler *sm) {
    free(sm->s);
    free(sm->coeffs);
    free(sm->prev);
    memset(sm, 0, sizeof *sm);
}

/* Φ_ind = Σ A_s π max(0, shade(cache SH at s, n_s)), per RGB channel; out[0] luma, out[1..3] RGB (W);
 * *out_reflected: the luma of Σ ρ_s A_s (E_ind(s) - previous E_ind(s)), what the surfaces reflect of the
 * indirect light this update added (sm->prev then holds this update's values) */
static void indirect_energy(sampler *sm, const glow_cache_outputs *o, double out[4], double *out_reflected) {
    double sum[3] = {0, 0, 0}, refl[3] = {0, 0, 0};
    sm->from_lightmap = sm->from_grid = sm->missed = 0;
    for (uint32_t i = 0; i < sm->count; ++i) {
        const surfel_probe *p = &sm->s[i];
        int ok = p->has_uv && glow_sample_lightmap_page(o, p->page, p->u, p->v, sm->coeffs) == GLOW_OK;
        if (ok) sm->from_lightmap++;
        else if (o->grid_sh && glow_sample_grid(o, p->pos, sm->coeffs) == GLOW_OK) ok = 1, sm->from_grid++;
        if (!ok) {
            sm->missed++;
            sm->prev[3 * (size_t)i] = sm->prev[3 * (size_t)i + 1] = sm->prev[3 * (size_t)i + 2] = 0.0;
            continue;
        }
        float e[3];
        glow_shade_sh(sm->coeffs, o->sh_bands_luma, o->sh_bands_chroma, p->nrm, 1.0f, e);
        for (int c = 0; c < 3; ++c) {
            const double flux = (double)p->area * PI_D * (e[c] > 0.0f ? e[c] : 0.0f);
            sum[c] += flux;
            refl[c] += p->albedo[c] * (flux - sm->prev[3 * (size_t)i + c]);
            sm->prev[3 * (size_t)i + c] = flux;
        }
    }
    *out_reflected = 0.25 * refl[0] + 0.5 * refl[1] + 0.25 * refl[2];
    out[1] = sum[0];
    out[2] = sum[1];
    out[3] = sum[2];
    out[0] = 0.25 * sum[0] + 0.5 * sum[1] + 0.25 * sum[2];
}

/* ------------------------------------------------------------------ runs */

static void run_free(run *r) {
    free(r->e);
    free(r->rel);
    free(r->ratio);
    free(r->ms);
    free(r->refl);
    free(r->transport);
    memset(r, 0, sizeof *r);
}

/* the derived figures of a run, from its energies */
static void run_analyse(run *r, double eps, double source_luma) {
    const uint32_t n = r->updates;
    for (uint32_t k = 0; k < n; ++k) {
        const double ek = r->e[4 * k], e1 = k >= 1 ? r->e[4 * (k - 1)] : 0.0, e2 = k >= 2 ? r->e[4 * (k - 2)] : 0.0;
        r->rel[k] = ek > 0.0 ? fabs(ek - e1) / ek : (e1 == 0.0 ? 0.0 : 1.0);
        const double num = ek - e1, den = e1 - e2;
        r->ratio[k] = k >= 1 && fabs(den) > NOISE_REL * fabs(ek) && ek > 0.0 ? num / den : NAN;
    }
    /* the iteration after which the relative change stays below ε (1-based; the last update must qualify) */
    r->converge = -1;
    for (long k = (long)n - 1; k >= 0; --k) {
        if (r->rel[k] >= eps) {
            r->converge = k + 1 < (long)n ? k + 1 : -1;
            break;
        }
        if (k == 0) r->converge = 0; /* below ε from the first update on: only an all-zero run */
    }
    /* the asymptotic ratio: the median of the last (up to) 3 defined ratios whose change is above float noise */
    double last[3];
    uint32_t nl = 0;
    for (long k = (long)n - 1; k >= 1 && nl < 3; --k)
        if (isfinite(r->ratio[k]) && r->rel[k] > 1e-5) last[nl++] = r->ratio[k];
    r->asymptotic_ratio = nl ? median_of(last, nl) : NAN;
    /* the limit: geometric extrapolation E_n + (E_n - E_{n-1}) r/(1-r) when 0 <= r < 1, else E_n */
    const double en = r->e[4 * (n - 1)], en1 = n >= 2 ? r->e[4 * (n - 2)] : 0.0;
    const double q = r->asymptotic_ratio;
    r->limit_luma = isfinite(q) && q >= 0.0 && q < 1.0 ? en + (en - en1) * q / (1.0 - q)
                  : r->converge >= 0 ? en /* converged (to float noise, or bounce 0): E_n is the limit */
                                     : NAN; /* neither converged nor a ratio to extrapolate with: unknown */
    /* the first update from which E stays within ε of the limit (1-based) */
    r->within_eps = -1;
    if (r->limit_luma > 0.0)
        for (long k = (long)n - 1; k >= 0; --k) {
            if (fabs(r->e[4 * k] - r->limit_luma) / r->limit_luma >= eps) {
                r->within_eps = k + 1 < (long)n ? k + 2 : -1;
                break;
            }
            if (k == 0) r->within_eps = 1;
        }
    /* transport: the share of the light the surfaces reflected in update k-1 that arrives again in update k */
    double lt[3], la[3];
    uint32_t nt = 0, na = 0;
    for (uint32_t k = 0; k < n; ++k) {
        const double ek = r->e[4 * k], d = ek - (k ? r->e[4 * (k - 1)] : 0.0);
        const int above_noise = ek > 0.0 && fabs(d) > NOISE_REL * ek && r->rel[k] > 1e-5;
        /* one iteration per update only: with k per update, an update's increment is k bounces' worth */
        r->transport[k] = k >= 1 && r->per_update == 1 && r->bounce > 0.0f && above_noise && r->refl[k - 1] > NOISE_REL * ek
                              ? d / (r->bounce * r->refl[k - 1]) : NAN;
    }
    /* update 1 gathers what the surfaces send out of the direct light and emission: E_1 / source */
    if (n > 0 && r->per_update == 1 && source_luma > 0.0) r->transport[0] = r->e[0] / source_luma;
    for (long k = (long)n - 1; k >= 1 && nt < 3; --k)
        if (isfinite(r->transport[k])) lt[nt++] = r->transport[k];
    for (long k = (long)n - 1; k >= 0 && na < 3; --k) {
        const double d = r->e[4 * k] - (k ? r->e[4 * (k - 1)] : 0.0);
        if (r->e[4 * k] > 0.0 && d > NOISE_REL * r->e[4 * k] && r->rel[k] > 1e-5) la[na++] = r->refl[k] / d;
    }
    r->asymptotic_transport = nt ? median_of(lt, nt) : NAN;
    r->increment_albedo = na ? median_of(la, na) : NAN;
    r->median_ms = median_of(r->ms, n);
}

typedef struct session {
    const options *opt;
    glow_context *ctx;
    glow_bake *bake;
    glow_host *host;
    float emission_scale;
    uint32_t luma, chroma; /* the bands in use (resolved) */
    sampler sm;
} session;

static glow_result do_run(session *s, float bounce, uint32_t per_update, uint32_t updates, run *r) {
    memset(r, 0, sizeof *r);
    r->bounce = bounce;
    r->per_update = per_update;
    r->updates = updates;
    r->e = calloc((size_t)updates * 4, sizeof(double));
    r->rel = calloc(updates, sizeof(double));
    r->ratio = calloc(updates, sizeof(double));
    r->ms = calloc(updates, sizeof(double));
    r->refl = calloc(updates, sizeof(double));
    r->transport = calloc(updates, sizeof(double));
    if (!r->e || !r->rel || !r->ratio || !r->ms || !r->refl || !r->transport) return GLOW_ERROR_OUT_OF_MEMORY;
    glow_system *sys = NULL;
    /* a fresh system per run: nothing carries over between runs (the first update also resets the bounce) */
    glow_result res = glow_system_create(s->ctx,
                                         &(glow_system_desc){.bake = s->bake, .lighting = glow_host_hooks(s->host),
                                                             .sh_bands_luma = s->opt->luma,
                                                             .sh_bands_chroma = s->opt->chroma, .label = s->opt->bake},
                                         &sys);
    if (res != GLOW_OK) return res;
    res = glow_system_set_params(sys, &(glow_system_params){.bounce_intensity = bounce,
                                                            .emission_scale = s->emission_scale,
                                                            .bounce_iterations = per_update});
    if (res == GLOW_OK && !s->sm.s &&
        !sampler_init(&s->sm, sys, s->bake, glow_system_outputs(sys), s->host, s->emission_scale))
        res = GLOW_ERROR_HOST_CALLBACK; /* out of memory, or the host's hook failed on the surfels */
    for (uint32_t k = 0; k < updates && res == GLOW_OK; ++k) {
        res = glow_system_update(sys, &(glow_update_desc){.flags = k == 0 ? GLOW_UPDATE_FLAG_RESET_BOUNCE : 0u});
        if (res != GLOW_OK) break;
        glow_update_stats st;
        glow_system_get_stats(sys, &st);
        r->ms[k] = st.total_ms;
        if (k == 0) memset(s->sm.prev, 0, sizeof(double) * 3 * s->sm.count);
        indirect_energy(&s->sm, glow_system_outputs(sys), r->e + 4 * (size_t)k, &r->refl[k]);
        s->luma = glow_system_outputs(sys)->sh_bands_luma;
        s->chroma = glow_system_outputs(sys)->sh_bands_chroma;
    }
    glow_system_destroy(sys);
    if (res == GLOW_OK) run_analyse(r, s->opt->epsilon, s->sm.source[0]);
    return res;
}

/* ------------------------------------------------------------------ outputs */

static void json_string(FILE *f, const char *s) {
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; ++p) {
        if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
        else if (*p < 0x20) fprintf(f, "\\u%04x", *p);
        else fputc(*p, f);
    }
    fputc('"', f);
}

static void json_num(FILE *f, double v) {
    if (isfinite(v)) fprintf(f, "%.9g", v);
    else fputs("null", f);
}

/* bounce intensities are floats: 6 digits print 0.2 as 0.2, not 0.200000003 */
static void json_float(FILE *f, float v) {
    if (isfinite(v)) fprintf(f, "%.6g", (double)v);
    else fputs("null", f);
}

static void json_count(FILE *f, long v) {
    if (v >= 0) fprintf(f, "%ld", v);
    else fputs("null", f);
}

static void json_run(FILE *f, const run *r, const char *indent) {
    const uint32_t n = r->updates;
    const double *last = r->e + 4 * (size_t)(n - 1);
    fprintf(f, "%s{\"bounce_intensity\": ", indent);
    json_float(f, r->bounce);
    fprintf(f, ", \"iterations_per_update\": %u, \"updates\": %u,\n%s \"energy_luma\": [", r->per_update, n, indent);
    for (uint32_t k = 0; k < n; ++k) fputs(k ? ", " : "", f), json_num(f, r->e[4 * k]);
    fprintf(f, "],\n%s \"energy_rgb\": [", indent);
    for (uint32_t k = 0; k < n; ++k) {
        fputs(k ? ", [" : "[", f);
        for (int c = 1; c < 4; ++c) fputs(c > 1 ? ", " : "", f), json_num(f, r->e[4 * k + c]);
        fputc(']', f);
    }
    fprintf(f, "],\n%s \"relative_change\": [", indent);
    for (uint32_t k = 0; k < n; ++k) fputs(k ? ", " : "", f), json_num(f, r->rel[k]);
    fprintf(f, "],\n%s \"ratio\": [", indent);
    for (uint32_t k = 0; k < n; ++k) fputs(k ? ", " : "", f), json_num(f, r->ratio[k]);
    fprintf(f, "],\n%s \"reflected_increment\": [", indent);
    for (uint32_t k = 0; k < n; ++k) fputs(k ? ", " : "", f), json_num(f, r->refl[k]);
    fprintf(f, "],\n%s \"transport\": [", indent);
    for (uint32_t k = 0; k < n; ++k) fputs(k ? ", " : "", f), json_num(f, r->transport[k]);
    fprintf(f, "],\n%s \"update_ms\": [", indent);
    for (uint32_t k = 0; k < n; ++k) fprintf(f, "%s%.4f", k ? ", " : "", r->ms[k]);
    fprintf(f, "],\n%s \"converged_energy_luma\": ", indent);
    json_num(f, last[0]);
    fputs(", \"converged_energy_rgb\": [", f);
    json_num(f, last[1]), fputs(", ", f), json_num(f, last[2]), fputs(", ", f), json_num(f, last[3]);
    fputs("], \"limit_energy_luma\": ", f);
    json_num(f, r->limit_luma);
    fprintf(f, ",\n%s \"updates_to_converge\": ", indent);
    json_count(f, r->converge);
    fputs(", \"updates_within_epsilon_of_limit\": ", f);
    json_count(f, r->within_eps);
    fputs(", \"asymptotic_ratio\": ", f);
    json_num(f, r->asymptotic_ratio);
    fputs(", \"asymptotic_transport\": ", f);
    json_num(f, r->asymptotic_transport);
    fputs(", \"increment_albedo\": ", f);
    json_num(f, r->increment_albedo);
    fputs(", \"median_update_ms\": ", f);
    json_num(f, r->median_ms);
    fputc('}', f);
}

typedef struct report {
    const options *o;
    const glow_scene_desc *scene;
    glow_bake_info info;
    uint32_t luma, chroma, threads;
    const run *sweep;        /* o->bounce_count runs */
    const run *const *per;   /* o->per_update_count runs (pointers: k = 1 reuses the sweep's run) */
    float per_bounce;
    double median_ms;
    uint64_t from_lightmap, from_grid, missed;
    const double *direct, *source; /* luma, RGB (W): the sampler's */
    double light_power;            /* luma (W) the point and spot lights emit at most; NAN with a sun or sky */
    int textured;
    const char *chart;       /* NULL = none */
    const char *data_path;
} report;

static void json_summary(FILE *f, const report *p) {
    const options *o = p->o;
    fputs("{\"tool\": \"glow-tune\", \"scene\": ", f);
    json_string(f, o->scene);
    fputs(", \"bake\": ", f);
    json_string(f, o->bake);
    fputs(", \"mesh\": ", f);
    json_string(f, p->scene->mesh ? p->scene->mesh : "");
    fprintf(f, ",\n \"settings\": {\"iterations\": %u, \"epsilon\": ", o->iterations);
    json_num(f, o->epsilon);
    fprintf(f, ", \"host\": \"%s\", \"threads\": %u, \"luma\": %u, \"chroma\": %u, \"emission_scale\": ",
            o->host == GLOW_HOST_KIND_EXACT ? "exact" : "shadow-map", p->threads, p->luma, p->chroma);
    json_num(f, p->scene->emission_scale);
    fputs(", \"bounce\": [", f);
    for (uint32_t b = 0; b < o->bounce_count; ++b) fputs(b ? ", " : "", f), json_float(f, o->bounce[b]);
    fputs("], \"per_update\": [", f);
    for (uint32_t k = 0; k < o->per_update_count; ++k) fprintf(f, "%s%u", k ? ", " : "", o->per_update[k]);
    fprintf(f, "]},\n \"bake_info\": {\"surfels\": %u, \"caches\": %u, \"grid_caches\": %u, \"lightmap_caches\": %u, "
               "\"links_per_cache\": %u, \"sh_bands\": %u, \"scene_area\": ",
            p->info.surfel_count, p->info.cache_count, p->info.grid_cache_count, p->info.lightmap_cache_count,
            p->info.links_per_cache, p->info.sh_bands);
    json_num(f, p->info.scene_area);
    fputs("},\n \"energy\": {\"definition\": \"sum over the bake's surfels of area x pi x max(0, glow_shade_sh(cache SH "
          "sampled at the surfel: lightmap at its UV, else grid; surfel normal; exponent 1)) per RGB channel: the indirect "
          "flux arriving at the surfaces\", \"unit\": \"W\", \"luma\": \"R/4 + G/2 + B/4\", ",
          f);
    fprintf(f, "\"surfels_from_lightmap\": %llu, \"surfels_from_grid\": %llu, \"surfels_missed\": %llu},\n",
            (unsigned long long)p->from_lightmap, (unsigned long long)p->from_grid, (unsigned long long)p->missed);
    fputs(" \"sources\": {\"direct_flux_luma\": ", f);
    json_num(f, p->direct[0]);
    fputs(", \"direct_flux_rgb\": [", f);
    json_num(f, p->direct[1]), fputs(", ", f), json_num(f, p->direct[2]), fputs(", ", f), json_num(f, p->direct[3]);
    fputs("], \"source_flux_luma\": ", f);
    json_num(f, p->source[0]);
    fputs(", \"source_flux_rgb\": [", f);
    json_num(f, p->source[1]), fputs(", ", f), json_num(f, p->source[2]), fputs(", ", f), json_num(f, p->source[3]);
    fputs("], \"light_power_bound_luma\": ", f);
    json_num(f, p->light_power);
    fprintf(f, ", \"albedo_textures_ignored\": %s},\n", p->textured ? "true" : "false");
    fputs(" \"median_update_ms\": ", f);
    json_num(f, p->median_ms);
    fputs(",\n \"bounce_sweep\": [\n", f);
    for (uint32_t b = 0; b < o->bounce_count; ++b) {
        json_run(f, &p->sweep[b], "  ");
        fputs(b + 1 < o->bounce_count ? ",\n" : "\n", f);
    }
    fputs(" ],\n \"per_update_bounce_intensity\": ", f);
    json_float(f, p->per_bounce);
    fputs(",\n \"per_update_sweep\": [\n", f);
    for (uint32_t k = 0; k < o->per_update_count; ++k) {
        json_run(f, p->per[k], "  ");
        fputs(k + 1 < o->per_update_count ? ",\n" : "\n", f);
    }
    fputs(" ],\n \"data\": ", f);
    json_string(f, p->data_path);
    fputs(", \"chart\": ", f);
    if (p->chart) json_string(f, p->chart);
    else fputs("null", f);
    fputs("}\n", f);
}

static void dat_run(FILE *f, const run *r, const char *what) {
    fprintf(f, "# %s: bounce_intensity %g, bounce_iterations per update %u\n", what, r->bounce, r->per_update);
    fprintf(f, "# update  energy_luma_W  energy_r_W  energy_g_W  energy_b_W  relative_change  ratio  update_ms\n");
    for (uint32_t k = 0; k < r->updates; ++k) {
        const double *e = r->e + 4 * (size_t)k;
        fprintf(f, "%u %.9g %.9g %.9g %.9g %.6g ", k + 1, e[0], e[1], e[2], e[3], r->rel[k]);
        if (isfinite(r->ratio[k])) fprintf(f, "%.6g", r->ratio[k]);
        else fputs("nan", f);
        fprintf(f, " %.4f\n", r->ms[k]);
    }
    fputs("\n\n", f); /* gnuplot: next index */
}

/* a string safe inside gnuplot single quotes (and readable) */
static void gp_text(FILE *f, const char *s) {
    for (; *s; ++s) fputs(*s == '\'' ? "''" : (char[2]){*s, 0}, f);
}

static const char *base_name(const char *p) {
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

static int write_gp(const char *path, const options *o, const run *sweep, const run *const *per, float per_bounce) {
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fputs("# glow-tune chart: gnuplot convergence.gp (in this folder) writes convergence.png\n"
          "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) { set terminal pngcairo size 900,1100 font ',10' } "
          "else { set terminal png size 900,1100 }\n"
          "set termoption noenhanced\nset output 'convergence.png'\nset datafile missing 'nan'\n"
          "set grid\nset key outside right top\nset lmargin 12\nset rmargin 26\n",
          f);
    fprintf(f, "set xrange [0:%u]\n", o->iterations + 1);
    fputs("set multiplot layout 3,1 title 'glow-tune: ", f);
    gp_text(f, base_name(o->scene));
    fputs(" + ", f);
    gp_text(f, base_name(o->bake));
    fputs("'\n", f);
    fputs("set title 'total indirect energy (flux arriving at the surfaces), 1 bounce iteration per update'\n"
          "set xlabel 'update'\nset ylabel 'indirect energy, luma (W)'\nset yrange [0:*]\nplot ",
          f);
    for (uint32_t b = 0; b < o->bounce_count; ++b)
        fprintf(f, "%s'convergence.dat' index %u using 1:2 with linespoints pt 7 ps 0.5 title 'bounce %g'",
                b ? ", \\\n     " : "", b, sweep[b].bounce);
    fprintf(f, "\nset title 'relative change |E_k - E_k-1| / E_k (log scale); converged below epsilon'\n"
               "set ylabel 'relative change'\nset logscale y\nset yrange [*:*]\nset format y '%%.0e'\nplot ");
    for (uint32_t b = 0; b < o->bounce_count; ++b)
        fprintf(f, "'convergence.dat' index %u using 1:($6 > 0 ? $6 : 1/0) with linespoints pt 7 ps 0.5 title 'bounce %g', \\\n     ",
                b, sweep[b].bounce);
    fprintf(f, "%.9g with lines dt 2 lc rgb 'black' title 'epsilon %g'\n", o->epsilon, o->epsilon);
    fprintf(f, "unset logscale y\nset format y '%%g'\nset yrange [0:*]\n"
               "set title 'bounce intensity %g: total indirect energy with bounce_iterations per update'\n"
               "set ylabel 'indirect energy, luma (W)'\nplot ",
            per_bounce);
    for (uint32_t k = 0; k < o->per_update_count; ++k) {
        /* index of the run in the .dat: the sweep's runs first, then the per-update runs in order */
        fprintf(f, "%s'convergence.dat' index %u using 1:2 with linespoints pt 7 ps 0.5 title '%u per update'",
                k ? ", \\\n     " : "", o->bounce_count + k, per[k]->per_update);
    }
    fputs("\nunset multiplot\n", f);
    return fclose(f) == 0;
}

/* runs gnuplot on DIR/convergence.gp with DIR as its working folder; 1 when the PNG was written */
static int run_gnuplot(const char *dir, const char *png, const char *log_path) {
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        fprintf(stderr, "glow-tune: warning: cannot start gnuplot: %s; no chart\n", strerror(errno));
        return 0;
    }
    if (pid == 0) {
        int fd = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
            close(fd);
        }
        if (chdir(dir) != 0) _exit(126);
        execlp("gnuplot", "gnuplot", "convergence.gp", (char *)NULL);
        _exit(127);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return 0;
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code == 127) {
        fprintf(stderr, "glow-tune: warning: gnuplot not found; no chart (summary.json says \"chart\": null)\n");
        remove(png);
        remove(log_path);
        return 0;
    }
    unsigned char sig[8] = {0};
    FILE *f = fopen(png, "rb");
    const int good = f && fread(sig, 1, 8, f) == 8 && !memcmp(sig, "\x89PNG\r\n\x1a\n", 8);
    if (f) fclose(f);
    if (code != 0 || !good) {
        fprintf(stderr, "glow-tune: warning: gnuplot failed (exit %d, see %s); no chart\n", code, log_path);
        remove(png);
        return 0;
    }
    struct stat st; /* keep the log only when gnuplot said something */
    if (stat(log_path, &st) == 0 && st.st_size == 0) remove(log_path);
    return 1;
}

static int make_dirs(const char *path) {
    char buf[4096];
    if (strlen(path) >= sizeof buf) return 0;
    strcpy(buf, path);
    for (char *p = buf + 1; *p; ++p)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(buf, 0755) != 0 && errno != EEXIST) return 0;
            *p = '/';
        }
    if (mkdir(buf, 0755) != 0 && errno != EEXIST) return 0;
    struct stat st;
    return stat(buf, &st) == 0 && S_ISDIR(st.st_mode);
}

static char *join(const char *dir, const char *name) {
    size_t n = strlen(dir) + strlen(name) + 2;
    char *s = malloc(n);
    if (s) snprintf(s, n, "%s/%s", dir, name);
    return s;
}

/* "12", or ">N" when a run did not get there */
static const char *fmt_count(char *buf, size_t size, long k, uint32_t n) {
    if (k >= 0) snprintf(buf, size, "%ld", k);
    else snprintf(buf, size, ">%u", n);
    return buf;
}

static const char *fmt_num(char *buf, size_t size, const char *fmt, double v) {
    if (isfinite(v)) snprintf(buf, size, fmt, v);
    else snprintf(buf, size, "-");
    return buf;
}

static void print_tables(const report *p) {
    const options *o = p->o;
    const run *main_run = NULL;
    char b1[32], b2[32], b3[32], b4[32], b5[32];
    for (uint32_t b = 0; b < o->bounce_count; ++b)
        if (p->sweep[b].bounce == p->per_bounce) main_run = &p->sweep[b];
    printf("glow-tune %s + %s: %u surfels, %u caches x %u links, SH luma %u chroma %u, %s host, %u thread(s)\n",
           o->bake, o->scene, p->info.surfel_count, p->info.cache_count, p->info.links_per_cache, p->luma, p->chroma,
           o->host == GLOW_HOST_KIND_EXACT ? "exact" : "shadow-map", p->threads);
    printf("E = total indirect energy: the indirect flux arriving at the surfaces, W (luma = R/4 + G/2 + B/4),\n"
           "    summed over %u surfels (%llu read the lightmap, %llu the grid, %llu no cache)\n",
           p->info.surfel_count, (unsigned long long)p->from_lightmap, (unsigned long long)p->from_grid,
           (unsigned long long)p->missed);
    printf("sources: direct light arriving at the surfaces %.6g W; the surfaces reflect and emit %.6g W of it\n"
           "    (Σ A (ρ E_direct + π L_e)): what update 1 gathers; transport at update 1 = E_1 / that%s\n",
           p->direct[0], p->source[0], p->textured ? " (albedo textures ignored)" : "");
    if (isfinite(p->light_power))
        printf("    the lights emit at most %.6g W (point 4πI, spot 2π(1 - cos outer)·I)\n", p->light_power);
    if (main_run) {
        printf("\nbounce intensity %g, 1 bounce iteration per update\n"
               "update   E luma (W)    E R (W)    E G (W)    E B (W)  rel. change   ratio  transport\n",
               main_run->bounce);
        for (uint32_t k = 0; k < main_run->updates; ++k) {
            const double *e = main_run->e + 4 * (size_t)k;
            printf("%6u %12.6g %10.5g %10.5g %10.5g %12.3e %7s %10s\n", k + 1, e[0], e[1], e[2], e[3], main_run->rel[k],
                   fmt_num(b1, sizeof b1, "%.4f", main_run->ratio[k]), fmt_num(b2, sizeof b2, "%.4f", main_run->transport[k]));
        }
        printf("ratio = (E_k - E_k-1) / (E_k-1 - E_k-2); transport = (E_k - E_k-1) / (bounce x light the surfaces reflected\n"
               "of update k-1's increment): the share of reflected light that reaches a surface again (<= 1)\n");
    }
    int have_zero = 0;
    double single = 0.0;
    for (uint32_t b = 0; b < o->bounce_count; ++b)
        if (p->sweep[b].bounce == 0.0f) have_zero = 1, single = p->sweep[b].e[4 * (size_t)(p->sweep[b].updates - 1)];
    printf("\nbounce intensity sweep (1 bounce iteration per update, epsilon %g)\n"
           "bounce  E after %4u (W)  x single bounce  converged after  within eps from   ratio  transport  ms/update\n",
           o->epsilon, o->iterations);
    for (uint32_t b = 0; b < o->bounce_count; ++b) {
        const run *r = &p->sweep[b];
        const double en = r->e[4 * (size_t)(r->updates - 1)];
        printf("%6.3g  %15.6g  %15s  %15s  %15s  %6s  %9s  %9.3f\n", r->bounce, en,
               have_zero ? fmt_num(b1, sizeof b1, "%.4f", single > 0.0 ? en / single : NAN) : "-",
               fmt_count(b2, sizeof b2, r->converge, r->updates), fmt_count(b3, sizeof b3, r->within_eps, r->updates),
               fmt_num(b4, sizeof b4, "%.4f", r->asymptotic_ratio),
               fmt_num(b5, sizeof b5, "%.4f", r->asymptotic_transport), r->median_ms);
    }
    printf("converged after k: from update k+1 on, each update changes E by less than epsilon (relative);\n"
           "within eps from k: from update k on, E is within epsilon of its extrapolated limit\n");
    if (main_run && isfinite(main_run->increment_albedo) && isfinite(main_run->asymptotic_ratio) &&
        isfinite(main_run->asymptotic_transport))
        printf("(bounce %g: ratio %.4f = bounce x albedo of the new light %.4f x transport %.4f)\n", main_run->bounce,
               main_run->asymptotic_ratio, main_run->increment_albedo, main_run->asymptotic_transport);
    printf("\nbounce intensity %g: bounce_iterations per update\n"
           "per update  converged after  within eps from  E after %4u updates (W)  ms/update\n",
           p->per_bounce, o->iterations);
    for (uint32_t k = 0; k < o->per_update_count; ++k) {
        const run *r = p->per[k];
        printf("%10u  %15s  %15s  %24.6g  %9.3f\n", r->per_update, fmt_count(b1, sizeof b1, r->converge, r->updates),
               fmt_count(b2, sizeof b2, r->within_eps, r->updates), r->e[4 * (size_t)(r->updates - 1)], r->median_ms);
    }
    printf("\nmedian update time %.3f ms (1 bounce iteration; glow_update_stats.total_ms over the bounce sweep)\n",
           p->median_ms);
}

int main(int argc, char **argv) {
    options o;
    const int pr = parse_args(argc, argv, &o);
    if (pr == 3) return 0;
    if (pr != 0) {
        fprintf(stderr, "run 'glow-tune --help' for the options\n");
        return 2;
    }
    glow_cli_log log_state = {"glow-tune", o.quiet};
    glow_logger logger = glow_cli_logger(&log_state);
    char msg[1024];
    glow_scene_desc scene;
    if (glow_scene_load(o.scene, NULL, &scene, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-tune: %s\n", msg);
        return 1;
    }
    session s = {.opt = &o, .emission_scale = scene.emission_scale};
    run *sweep = calloc(o.bounce_count, sizeof *sweep);
    run *extra = calloc(o.per_update_count, sizeof *extra);
    const run **per = calloc(o.per_update_count, sizeof *per);
    char *dat_path = join(o.out, "convergence.dat"), *gp_path = join(o.out, "convergence.gp"),
         *png_path = join(o.out, "convergence.png"), *json_path = join(o.out, "summary.json"),
         *log_path = join(o.out, "gnuplot.log");
    int rc = 1;
    glow_result r = GLOW_OK;
    if (!sweep || !extra || !per || !dat_path || !gp_path || !png_path || !json_path || !log_path) {
        fprintf(stderr, "glow-tune: out of memory\n");
        goto done;
    }
    if ((r = glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION, .logger = logger,
                                                      .tasks = {.worker_count = o.threads}},
                                 &s.ctx)) != GLOW_OK) {
        fprintf(stderr, "glow-tune: cannot create the runtime context: %s\n", glow_result_string(r));
        goto done;
    }
    if ((r = glow_bake_load_file(s.ctx, o.bake, &s.bake)) != GLOW_OK) {
        fprintf(stderr, "glow-tune: %s: cannot load the bake: %s\n", o.bake, glow_result_string(r));
        goto done;
    }
    glow_bake_info info;
    glow_bake_get_info(s.bake, &info);
    /* the bake is not compared with the scene's mesh (that needs the importer: glow-render does it), but a
     * light far outside the bake's bounds usually means a bake of another mesh */
    for (uint32_t l = 0; l < scene.light_count; ++l) {
        const glow_scene_light *lt = &scene.lights[l];
        if (lt->type == GLOW_SCENE_LIGHT_SUN) continue;
        int outside = 0;
        for (int k = 0; k < 3; ++k) {
            const float pad = 0.05f * (info.bounds_max[k] - info.bounds_min[k]);
            outside |= lt->position[k] < info.bounds_min[k] - pad || lt->position[k] > info.bounds_max[k] + pad;
        }
        if (outside)
            fprintf(stderr, "glow-tune: warning: %s: lights[%u] at (%g, %g, %g) is outside the bounds of %s: "
                            "is the bake of the scene's mesh (%s)?\n",
                    o.scene, l, lt->position[0], lt->position[1], lt->position[2], o.bake, scene.mesh ? scene.mesh : "?");
    }
    glow_host_desc hd = glow_host_desc_from_scene(&scene, s.bake, o.host);
    hd.logger = logger;
    if ((r = glow_host_create(&hd, &s.host)) != GLOW_OK) {
        fprintf(stderr, "glow-tune: %s + %s: cannot create the host: %s\n", o.bake, o.scene, glow_result_string(r));
        goto done;
    }
    if (!make_dirs(o.out)) {
        fprintf(stderr, "glow-tune: %s: cannot create the output folder: %s\n", o.out, strerror(errno));
        goto done;
    }
    /* the bounce sweep, one feedback iteration per update */
    float per_bounce = 0.0f;
    for (uint32_t b = 0; b < o.bounce_count; ++b) {
        if (o.bounce[b] > per_bounce) per_bounce = o.bounce[b];
        if ((r = do_run(&s, o.bounce[b], 1, o.iterations, &sweep[b])) != GLOW_OK) {
            fprintf(stderr, "glow-tune: %s: the solver failed (bounce %g): %s\n", o.bake, o.bounce[b],
                    glow_result_string(r));
            goto done;
        }
    }
    /* bounce_iterations per update, at the largest bounce intensity (k = 1 is the sweep's run) */
    for (uint32_t k = 0; k < o.per_update_count; ++k) {
        per[k] = NULL;
        if (o.per_update[k] == 1)
            for (uint32_t b = 0; b < o.bounce_count && !per[k]; ++b)
                if (sweep[b].bounce == per_bounce) per[k] = &sweep[b];
        if (per[k]) continue;
        if ((r = do_run(&s, per_bounce, o.per_update[k], o.iterations, &extra[k])) != GLOW_OK) {
            fprintf(stderr, "glow-tune: %s: the solver failed (bounce %g, %u per update): %s\n", o.bake, per_bounce,
                    o.per_update[k], glow_result_string(r));
            goto done;
        }
        per[k] = &extra[k];
    }
    /* what the lights can emit at most (luma): a bound the sampled direct flux must respect */
    double light_power = 0.0;
    for (uint32_t l = 0; l < scene.light_count; ++l) {
        const glow_scene_light *lt = &scene.lights[l];
        const double i = 0.25 * lt->intensity[0] + 0.5 * lt->intensity[1] + 0.25 * lt->intensity[2];
        if (lt->type == GLOW_SCENE_LIGHT_POINT) light_power += 4.0 * PI_D * i;
        else if (lt->type == GLOW_SCENE_LIGHT_SPOT) light_power += 2.0 * PI_D * (1.0 - cos(lt->outer_deg * PI_D / 180.0)) * i;
        else light_power = NAN; /* a sun: no bound without the scene's extent */
    }
    if (scene.environment[0] > 0.0f || scene.environment[1] > 0.0f || scene.environment[2] > 0.0f) light_power = NAN;
    if (isfinite(light_power) && s.sm.direct[0] > 1.02 * light_power)
        fprintf(stderr, "glow-tune: warning: %s: the direct light the surfels receive (%.4g W) exceeds what the lights emit "
                        "(at most %.4g W): the surfels undersample a light close to a surface, and every bounce inherits it\n",
                o.scene, s.sm.direct[0], light_power);
    report rep = {.o = &o, .light_power = light_power, .scene = &scene, .info = info, .sweep = sweep, .per = per, .per_bounce = per_bounce,
                  .from_lightmap = s.sm.from_lightmap, .from_grid = s.sm.from_grid, .missed = s.sm.missed,
                  .direct = s.sm.direct, .source = s.sm.source, .textured = s.sm.textured,
                  .data_path = dat_path};
    {
        rep.luma = s.luma;
        rep.chroma = s.chroma;
        long cpus = sysconf(_SC_NPROCESSORS_ONLN);
        rep.threads = o.threads ? o.threads : cpus > 0 ? (uint32_t)cpus : 1u;
        double *all = malloc(sizeof(double) * (size_t)o.bounce_count * o.iterations);
        if (all) {
            for (uint32_t b = 0; b < o.bounce_count; ++b) memcpy(all + (size_t)b * o.iterations, sweep[b].ms, sizeof(double) * o.iterations);
            rep.median_ms = median_of(all, o.bounce_count * o.iterations);
            free(all);
        }
    }
    if (rep.missed == info.surfel_count) {
        fprintf(stderr, "glow-tune: %s: no surfel finds a lightmap or grid cache: nothing to measure\n", o.bake);
        goto done;
    }
    /* convergence.dat: the sweep's runs (index 0..B-1), then the per-update runs */
    FILE *f = fopen(dat_path, "w");
    if (!f) {
        fprintf(stderr, "glow-tune: %s: cannot write: %s\n", dat_path, strerror(errno));
        goto done;
    }
    fprintf(f, "# glow-tune %s + %s: total indirect energy (indirect flux arriving at the surfaces, W) per update\n",
            o.bake, o.scene);
    for (uint32_t b = 0; b < o.bounce_count; ++b) dat_run(f, &sweep[b], "bounce sweep");
    for (uint32_t k = 0; k < o.per_update_count; ++k) dat_run(f, per[k], "per-update sweep");
    if (fclose(f) != 0) {
        fprintf(stderr, "glow-tune: %s: cannot write\n", dat_path);
        goto done;
    }
    if (!write_gp(gp_path, &o, sweep, per, per_bounce)) {
        fprintf(stderr, "glow-tune: %s: cannot write\n", gp_path);
        goto done;
    }
    remove(png_path); /* a chart from an earlier run must not pass for this one's */
    if (!o.no_chart && run_gnuplot(o.out, png_path, log_path)) rep.chart = png_path;
    f = fopen(json_path, "w");
    if (!f) {
        fprintf(stderr, "glow-tune: %s: cannot write: %s\n", json_path, strerror(errno));
        goto done;
    }
    json_summary(f, &rep);
    if (fclose(f) != 0) {
        fprintf(stderr, "glow-tune: %s: cannot write\n", json_path);
        goto done;
    }
    if (o.json) json_summary(stdout, &rep);
    else if (!o.quiet) {
        print_tables(&rep);
        printf("wrote %s, %s%s%s\n", json_path, dat_path, rep.chart ? ", " : "", rep.chart ? rep.chart : "");
    }
    rc = 0;
done:
    for (uint32_t b = 0; sweep && b < o.bounce_count; ++b) run_free(&sweep[b]);
    for (uint32_t k = 0; extra && k < o.per_update_count; ++k) run_free(&extra[k]);
    free(sweep);
    free(extra);
    free(per);
    free(dat_path);
    free(gp_path);
    free(png_path);
    free(json_path);
    free(log_path);
    sampler_free(&s.sm);
    glow_host_destroy(s.host);
    glow_bake_destroy(s.bake);
    glow_context_destroy(s.ctx);
    glow_scene_free(&scene);
    return rc;
}
