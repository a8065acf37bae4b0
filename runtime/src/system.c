/* system.c — glow_system: the per-frame CPU solver (PIC Fig. 2, steps 2-4), DESIGN §1.
 *
 * Buffers (all allocated in glow_system_create; an update allocates nothing):
 *   surfels  pos4/nrm4 (what the hook sees), albedo, emission, direct irradiance (two buffers: the
 *            hook writes the spare one, which becomes current only when every batch was valid),
 *            feedback weights π s_l y_lm(n) and the indirect-albedo cap (see below)
 *   nodes    flux and radiance, planar Y | Co | Cg (the pull and the gather read one plane at a time)
 *   caches   cache_sh [cache][coeffs] (the bounce state), then the planar grid and lightmap outputs
 *
 * One update, per bounce iteration:
 *   surfel flux   B = ρ E_direct + ρ_ind · bounce · max(0, E_indirect) + π L_e · scales;  Φ = B · area
 *                 E_indirect = the surfel's feedback cache convolved with the cosine lobe (the
 *                 previous iteration's caches: progressive multi-bounce, PIC 4.1)
 *   pull          Φ summed up the hierarchy, level by level; node radiance R = Φ / (π area)
 *   cache light   cache_lighting.c
 * then the outputs (planar textures with lightmap gutter/seam copies).
 *
 * Why it cannot diverge: with node radiances bounded by R_max, the indirect irradiance a surfel
 * gathers through its cache's links is at most G_s · R_max, where G_s = Σ_links |w_j(n_s)| is
 * computed once at create from the decoded links (w_j: the link's weight in the cosine-lobe
 * convolution, by the SH addition theorem w_j = π Σ_l s_l k_l(x_j) (2l+1)/(4π) P_l(d_j·n_s)).
 * Capping the albedo used for indirect light at ρ_ind ≤ 0.999 π / G_s makes one bounce a
 * contraction with factor ≤ 0.999 · bounce_intensity in the max norm, whatever the links'
 * discretisation error or SH ringing. In a well-linked closed scene G_s ≈ π, so the cap
 * (≈ 0.999) only bites for albedos the API clamps anyway.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cache_lighting.h"
#include "runtime_internal.h"

#define PI_F 3.14159265358979323846f
#define SURFEL_CHUNK 2048u
#define NODE_CHUNK 2048u
#define CACHE_CHUNK 16u
#define DETAIL_CHUNK 1024u
#define MAX_ITERATIONS 64u
#define ALBEDO_MAX 0.999f

enum { ST_OK = 0, ST_HOOK_FAILED = 1, ST_NONFINITE = 2, ST_SKIPPED = 3 /* a time budget's deadline */ };

struct glow_system {
    atomic_int updating; /* 1 while glow_system_update runs: misuse is refused, not raced (issue 15 D4, D5) */
    glow_context *ctx;
    const glow_bake *bake;
    const glow_bake_meta *meta;
    const glow_bake_node *nodes;
    const uint32_t *level_starts;
    char label[64];
    glow_lighting_hooks hooks;
    uint32_t S, N, C, M, levels, bpc, batch, nbatches;
    uint32_t luma, chroma, coeffs, fbk; /* fbk = luma² feedback weights per surfel */
    glow__cl_isa isa;
    glow_link_mode link_mode;
    unsigned char *xblocks; /* expanded links (GLOW_LINK_MODE_EXPANDED), else NULL */
    const unsigned char *xlinks; /* what the kernel reads as expanded blocks: xblocks, or the bake's
                                    full-SH links (GLOW_LINK_MODE_SH), else NULL */
    size_t xlink_size;           /* bytes per block of xlinks (0 = from luma) */
    float xscale;                /* SH mode: the bake's factor_scale (SHLK is against node flux) */
    const uint16_t *subsets;     /* the bake's LSUB (every link mode), else NULL */
    uint32_t *slots;             /* with subsets: [N][4] glow_bake_link_slots of every node */
    uint16_t *sub_ratio;         /* with subsets: [N][4] Y[slot] / Y[node] as IEEE halves, each update,
                                    for the sub_nodes only (the others stay 1: no weighted link reads them) */
    uint32_t *sub_nodes, sub_count; /* the internal nodes some link reads with LSUB weights, ascending */
    bool gradient;               /* LSUB holds link gradient codes (GLOW_LINK_KIND_GRADIENT): sub_ratio then
                                    holds u_x u_y u_z 0 (signed halves) of each sub_node, 0 elsewhere */
    uint16_t *grad_uz;           /* with gradient and the interleaved radiance (not GLOW_LINK_MODE_SH): u_z of
                                    each node ([N + P + 2], 0 but for the sub_nodes), and u_x u_y in the bits of
                                    rad's fourth float (0 but for the sub_nodes): one gather of the record
                                    brings the radiance and u_x u_y (cache_lighting.h); sub_ratio is unused */
    float *mom;                  /* with gradient: [3][N] luma-flux moments sum Yflux_i p_i, planar, pulled */
    float *grad_cm;              /* with gradient: per sub_node k its area centroid c (3) and
                                    M = sigma (C + 1e-3 trace(C) I)^-1 (9, row-major), from the surfels, in
                                    blocks of four nodes: value q of node k at GRAD_CM(k, q) */
    uint64_t memory_bytes;
    /* surfels */
    float *pos4, *nrm4;
    uint32_t *mat, *tri, *feedback;
    float *albedo, *emis_base, *emis;
    float *direct, *direct_spare;
    float *fb_w;       /* [S][luma²] π s_l(1) y_lm(n_s) */
    float *uv0;        /* [S][2] material UV at each surfel (bakes with TUV0), else NULL */
    float *rho_ind_max;/* [S] 0.999 π / G_s (cap of the albedo applied to indirect light) */
    /* nodes */
    float *flux; /* 3 planes of N */
    float *rad;  /* [N][4]: Y Co Cg 0, interleaved for the gathers (with grad_uz the fourth float holds
                    u_x u_y of the sub_nodes) */
    float *inv_pi_area;
    float *leaf_area;         /* per surfel: its leaf node's area (equal unless the bake adapted the density) */
    /* caches and outputs */
    float *cache_sh;
    /* the visible sky of the grid caches (glow_system_set_sky; docs/sky.md), bakes with SKYT only:
     * sky_grid [grid caches][coeffs] V ⊗ L in cache_sh's layout (YCoCg), added to the grid caches' rows
     * after the bounce iterations; sky_backup holds those rows without it, restored before the next
     * update's surfel flux reads them (feedback: the host already lights the surfels with the sky) */
    const float *sky_V;           /* the bake's [grid caches][9], NULL without SKYT */
    float *sky_grid, *sky_backup;
    bool sky_on, sky_applied;
    uint64_t sky_revision, sky_out_revision;
    glow_output_planes planes; /* the planes' format: grid_sh / lm_sh (F32), grid_h / lm_h (RGBA16F) or none */
    float *grid_sh, *lm_sh;
    uint16_t *grid_h, *lm_h;
    uint32_t *grid_map, *lm_map;
    size_t grid_cells, lm_texels;
    /* the non-empty cells/texels as (index, cache) pairs, for other backends (glow_solver_tables:
     * the GL outputs kernel); the CPU output stage writes whole planes (task_output) */
    uint32_t *out_index, *out_cache;
    size_t grid_used, lm_used;
    /* the same pairs by group of caches (task_output_sel): grp_out[grp_out_off[g] .. grp_out_off[g + 1])
     * are the positions in out_index/out_cache whose cache is in group g */
    uint32_t *grp_out_off, *grp_out;
    /* lightmap detail (LDET): the bake's tables, and the output plane [dh][dw][4] (RGB, coverage) */
    const glow_bake_detail *det;
    const uint32_t *det_texel, *det_first, *det_surfel;
    const float *det_weight;
    float *det_out;
    glow_cache_outputs out;
    /* controls */
    glow_system_params params;
    float *mat_emis_scale, *mat_albedo_scale; /* [M][3] */
    /* per-update bookkeeping */
    uint8_t *batch_status;
    uint32_t *batch_negative;
    glow_update_stats stats;
    /* per-stage task arguments */
    uint32_t pull_first, pull_count;
    uint64_t emission_revision, direct_revision, material_revision;
    uint64_t params_revision, cache_revision; /* glow_system_set_params calls; gathers and bounce resets */
    uint64_t flux_key[5]; /* the five revisions the surfel flux and pull were last computed from */
    bool flux_valid;
    float cl_scale[GLOW__CL_SCALE_FLOATS]; /* glow__cl_coeff_scale(luma, chroma) */
    /* budgets (glow_update_desc): groups of GLOW_BUDGET_GROUP caches, all allocated at create */
    uint32_t groups;
    uint32_t *grp_age;     /* updates since the group was last gathered */
    float *grp_delta;      /* relative luma change of its last gather (INFINITY: never, or reset) */
    double *grp_drift_at;  /* the input drift counter when it was last gathered */
    float *grp_centre;     /* [groups][3] mean cache position */
    uint64_t *grp_pack;    /* scratch: candidates as (~priority bits) << 32 | group: ascending = best first */
    uint32_t *grp_sel;     /* scratch: the selection, in group order */
    uint8_t *grp_skip;     /* scratch: converged groups this update */
    float *grp_busy;       /* scratch: [sel_count] the time of task k of the selection's gather, ms */
    uint32_t sel_count;
    float *rad_prev;       /* [N] node luma at the last update, for the drift */
    float *rad_out;        /* [N][4] the node radiance the outputs were last written with (budgeted updates
                              skip the output stage when it and the caches are unchanged) */
    bool out_written;
    double drift;          /* Σ over updates of the node luma's relative L1 change */
    double ema_other_ms;   /* recent times, for budget_ms (0 = none yet): the stages a budget cannot cut (all
                              but the hook and the cache gathers), */
    glow_budget_cost gather_cost; /* and the cache gathers (glow_budget_cost_learn) */
    double first_other_ms; /* the first budgeted update's other stages (first touches included): the estimate
                              until ema_other_ms has a sample */
    /* a time budget also cuts the host's hook (order_batches): batches of surfels lit by priority, as groups */
    uint32_t *bat_age;     /* [nbatches] updates since the batch was last lit */
    float *bat_centre;     /* [nbatches][3] mean surfel position */
    uint64_t *bat_pack;    /* scratch, as grp_pack */
    uint32_t *bat_sel;     /* [nbatches] the batches in the order this update's hook claims them */
    uint32_t bat_count;    /* how many it lit (nbatches: all) */
    float *bat_ms;         /* [nbatches] the hook's time for the batch when last lit, ms (< 0: never) */
    atomic_uint bat_next;  /* the next of bat_sel to claim */
    uint32_t bat_min;      /* the first bat_min claimed are lit whatever the deadline */
    double bat_deadline;   /* now_ms() by which a batch must end to start (0: none) */
    float bat_mean_ms;     /* a batch never lit counts this (the mean of those lit) */
    double hook_ms;        /* this update's hook time (0: not called) */
    bool hook_uncut;       /* GLOW_HOOK_BUDGET=off (benchmarking): a time budget never cuts the hook */
    bool full_outputs;     /* GLOW_SEL_OUTPUTS=off (benchmarking): budgeted updates write whole planes */
    uint8_t *bat_current;  /* [nbatches] 1: lit since the host's light last changed (since the last call
                              without KEEP_LIGHTING, which may not light it); KEEP_LIGHTING updates light
                              the others (and none when all are current, as before the hook was cut) */
    uint32_t bat_stale;    /* how many are not current */
    uint32_t hook_skipped; /* surfels of this update's candidate batches the deadline left */
    float scene_diag;
    /* a system of a world (XREF): proxy node p (index N + p) reads node proxies[p].node of the system
     * attached as dependency proxies[p].dependency (glow_system_set_neighbour); rad holds N + P nodes */
    uint32_t P, deps;
    const glow_bake_xref_proxy *proxies;
    const uint64_t *dep_keys;
    uint32_t *dep_max_node;         /* [deps] the largest node index its proxies read, + 1 */
    glow_system *nbr[GLOW_BAKE_MAX_DEPENDENCIES];
    atomic_uint attached;           /* how many systems have this one attached as a neighbour */
};

/* ------------------------------------------------------------------------------------------ */
static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static uint32_t div_up(uint32_t a, uint32_t b) { return (a + b - 1u) / b; }

/* ------------------------------------------------------------------------------ stage tasks */
/* surfel lighting: one hook call per batch, into the spare buffer, checked */
static void task_hook(void *data, uint32_t b, uint32_t worker) {
    glow_system *s = data;
    const double t0 = now_ms();
    uint32_t first = b * s->batch, count = s->S - first < s->batch ? s->S - first : s->batch;
    glow_surfel_batch batch = {.first = first,
                               .count = count,
                               .positions = s->pos4 + 4 * (size_t)first,
                               .normals = s->nrm4 + 4 * (size_t)first,
                               .materials = s->mat + first};
    float *out = s->direct_spare + 3 * (size_t)first;
    glow_result r = s->hooks.light_surfels(s->hooks.user, &batch, out, worker);
    if (r != GLOW_OK) {
        s->batch_status[b] = ST_HOOK_FAILED;
        return;
    }
    uint32_t neg = 0;
    uint8_t st = ST_OK;
    for (size_t i = 0; i < 3 * (size_t)count; ++i) {
        float v = out[i];
        if (!isfinite(v) || v > GLOW_MAX_IRRADIANCE) {
            st = ST_NONFINITE;
            break;
        }
        if (v < 0.0f) {
            out[i] = 0.0f;
            neg++;
        }
    }
    s->batch_status[b] = st;
    s->batch_negative[b] = neg;
    s->bat_ms[b] = (float)(now_ms() - t0); /* for a time budget's choice of batches (order_batches) */
}

/* The hook under a time budget: each call claims the next batch in priority order (whatever index the
 * task pool gives it: the pool splits indices into one range a worker) and lights it, unless the
 * deadline would pass before a batch of its last time ends (order_batches). */
static void task_hook_sel(void *data, uint32_t i, uint32_t worker) {
    (void)i;
    glow_system *s = data;
    const uint32_t r = atomic_fetch_add_explicit(&s->bat_next, 1u, memory_order_relaxed), b = s->bat_sel[r];
    if (r >= s->bat_min && s->bat_deadline > 0.0) {
        const double t = s->bat_ms[b] >= 0.0f ? (double)s->bat_ms[b] : (double)s->bat_mean_ms;
        if (now_ms() + t > s->bat_deadline) {
            s->batch_status[b] = ST_SKIPPED;
            return;
        }
    }
    task_hook(data, b, worker);
}

/* surfel flux for surfels [k*SURFEL_CHUNK, ...): leaves of the node arrays.
 * Written for the compiler: every array through a restrict-qualified local (no reloads after the
 * stores), the YCoCg conversions inline, the bounce branch hoisted, no fmaxf call (which GCC keeps
 * as a libm call without -ffinite-math-only). Measured on Sponza moderate, 2 threads: 0.58 -> 0.37 ms
 * (medians of 6 alternating runs on a shared machine). With the leaves' flux moments the rows of
 * the feedback caches (scattered, evicted by the cache lighting since the last update) are fetched
 * FLUX_AHEAD surfels ahead: surfel lighting without the hook 1.13 -> 0.83 ms on one thread (medians of
 * 6 alternating pairs, 2026-11-29). */
#define FLUX_AHEAD 8u
static void task_flux(void *data, uint32_t k, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    const uint32_t first = k * SURFEL_CHUNK, end = first + SURFEL_CHUNK < s->S ? first + SURFEL_CHUNK : s->S;
    const uint32_t L2 = s->luma * s->luma, C2 = s->chroma * s->chroma, nc = s->coeffs, fbk = s->fbk;
    const float bounce = s->params.bounce_intensity, es = s->params.emission_scale;
    const size_t N = s->N;
    const uint32_t *restrict mat = s->mat, *restrict feedback = s->feedback;
    const float *restrict mas = s->mat_albedo_scale, *restrict mes = s->mat_emis_scale;
    const float *restrict cache_sh = s->cache_sh, *restrict fb_w = s->fb_w, *restrict albedo = s->albedo;
    const float *restrict rho_max = s->rho_ind_max, *restrict direct = s->direct, *restrict emis = s->emis;
    const float *restrict inv_pi_area = s->inv_pi_area, *restrict leaf_area = s->leaf_area;
    float *restrict fy_out = s->flux, *restrict fco_out = s->flux + N, *restrict fcg_out = s->flux + 2 * N;
    float *restrict rad = s->rad;
    float *restrict mom = s->mom;
    const float *restrict pos4 = s->pos4;
    const bool fb = bounce > 0.0f;
    for (uint32_t i = first; i < end; ++i) {
        const uint32_t m = mat[i];
        const float *ms = mas + 3 * (size_t)m, *me = mes + 3 * (size_t)m;
        float ind[3] = {0.0f, 0.0f, 0.0f};
        if (fb) {
            if (i + FLUX_AHEAD < end) { /* the feedback caches' rows are scattered: fetch them a few surfels ahead */
                const float *ahead = cache_sh + (size_t)feedback[i + FLUX_AHEAD] * nc;
                for (uint32_t q = 0; q < nc; q += 16) __builtin_prefetch(ahead + q); /* its lines, 64 B apart */
                __builtin_prefetch(ahead + nc - 1);
            }
            const float *sh = cache_sh + (size_t)feedback[i] * nc, *w = fb_w + (size_t)i * fbk;
            float y = 0.0f, co = 0.0f, cg = 0.0f;
            for (uint32_t q = 0; q < L2; ++q) y += w[q] * sh[q];
            for (uint32_t q = 0; q < C2; ++q) {
                co += w[q] * sh[L2 + q];
                cg += w[q] * sh[L2 + C2 + q];
            }
            ind[0] = y + co - cg; /* glow_ycocg_to_rgb */
            ind[1] = y + cg;
            ind[2] = y - co - cg;
        }
        const float rmax = rho_max[i];
        float B[3];
        for (int c = 0; c < 3; ++c) {
            float rho = albedo[3 * (size_t)i + c] * ms[c];
            rho = rho < 0.0f ? 0.0f : (rho > ALBEDO_MAX ? ALBEDO_MAX : rho);
            const float rho_ind = rho < rmax ? rho : rmax;
            const float e_ind = ind[c] > 0.0f ? ind[c] * bounce : 0.0f;
            B[c] = rho * direct[3 * (size_t)i + c] + rho_ind * e_ind + PI_F * emis[3 * (size_t)i + c] * es * me[c];
        }
        const float ipa = inv_pi_area[i], area = leaf_area[i];
        const float fy = (0.25f * B[0] + 0.5f * B[1] + 0.25f * B[2]) * area; /* RGB -> YCoCg */
        const float fco = (0.5f * B[0] - 0.5f * B[2]) * area;
        const float fcg = (-0.25f * B[0] + 0.5f * B[1] - 0.25f * B[2]) * area;
        fy_out[i] = fy;
        fco_out[i] = fco;
        fcg_out[i] = fcg;
        if (mom) { /* link gradients: the leaf's luma flux moment Yflux p */
            const float *p = pos4 + 4 * (size_t)i;
            mom[i] = fy * p[0];
            mom[N + i] = fy * p[1];
            mom[2 * N + i] = fy * p[2];
        }
        float *r = rad + 4 * (size_t)i;
        r[0] = fy * ipa;
        r[1] = fco * ipa;
        r[2] = fcg * ipa;
        r[3] = 0.0f;
    }
}

/* Where value q (0..11: c, then M row-major) of sub_node k sits in grad_cm: blocks of four nodes, each
 * value's four in a row, so that gradient_u_range reads a value of four nodes with one 16-byte load
 * (glow_backend.h glow_solver_tables.gradient_cm) */
#define GRAD_CM(k, q) (48u * ((size_t)(k) / 4u) + 4u * (size_t)(q) + (size_t)(k) % 4u)

/* A ratio Y[slot] / Y[node] as an IEEE half, rounded to nearest: values below the smallest normal
 * half (6.1e-5) become 0, above the largest (65504) 65504, NaN 0. The kernel decodes normals only. */
static inline uint16_t ratio_half(float x) {
    if (!(x >= 6.103515625e-05f)) return 0u;
    if (x >= 65504.0f) return 0x7BFFu;
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    return (uint16_t)(((b + 0x1000u) >> 13) - (112u << 10));
}

/* A signed IEEE half of x, rounded to nearest: |x| below the smallest normal half 0, above the
 * largest 65504 (cache_kernel.inc's gradient_scale_r decodes normals only), NaN 0. */
static inline uint16_t signed_half(float x) {
    /* without branches: the signs of u are a coin toss per node, and ratio_half's branches cost Sponza's
     * pull 0.4 ms in mispredictions */
    const uint32_t sign = x < 0.0f ? 0x8000u : 0u;
    float a = fabsf(x);
    a = a < 65504.0f ? a : 65504.0f;
    uint32_t b;
    memcpy(&b, &a, sizeof b);
    const uint32_t h = (((b + 0x1000u) >> 13) - (112u << 10)) | sign;
    return (uint16_t)(a >= 6.103515625e-05f ? h : 0u);
}

/* Link gradients: u = M (p_B - c) of sub_node k (node n), p_B = the node's luma flux moments (mx my mz)
 * over its luma flux y; into the radiance record's fourth float and grad_uz, or sub_ratio */
static inline __attribute__((always_inline)) void gradient_u(glow_system *s, uint32_t k, uint32_t n, float y, float mx,
                                                             float my, float mz) {
    const float *cm = s->grad_cm;
    uint16_t out[4] = {0u, 0u, 0u, 0u};
    if (y > 0.0f) {
        const float inv = 1.0f / y;
        const float d[3] = {mx * inv - cm[GRAD_CM(k, 0)], my * inv - cm[GRAD_CM(k, 1)], mz * inv - cm[GRAD_CM(k, 2)]};
        for (int i = 0; i < 3; ++i)
            out[i] = signed_half(cm[GRAD_CM(k, 3 + 3 * i)] * d[0] + cm[GRAD_CM(k, 4 + 3 * i)] * d[1] +
                                 cm[GRAD_CM(k, 5 + 3 * i)] * d[2]);
    }
    if (s->grad_uz) { /* u_x u_y into the radiance record's fourth float, u_z beside */
        const uint32_t xy = (uint32_t)out[0] | (uint32_t)out[1] << 16;
        memcpy(s->rad + 4 * (size_t)n + 3, &xy, sizeof xy);
        s->grad_uz[n] = out[2];
    } else {
        memcpy(s->sub_ratio + 4 * (size_t)n, out, sizeof out);
    }
}

/* gradient_u of sub_nodes [k0, k1), four at a time (GCC vector extensions of 16 bytes: native SSE on
 * x86-64's baseline, NEON on ARM; the same IEEE single operations in the same order as the scalar form,
 * so the same bits), the rest one by one. Eight-wide vectors were emulated on the baseline ISA, their
 * comparisons lowered to a scalar compare and set per lane: Sponza moderate's pull spent about half its
 * time here. */
typedef float glow__g4f __attribute__((vector_size(16)));
typedef uint32_t glow__g4u __attribute__((vector_size(16)));
static inline __attribute__((always_inline)) glow__g4u signed_half4(glow__g4f x) { /* signed_half, lane-wise */
    const glow__g4u sign = (glow__g4u)(x < 0.0f) & 0x8000u;
    glow__g4f a = (glow__g4f)((glow__g4u)x & 0x7FFFFFFFu);
    const glow__g4u lt = (glow__g4u)(a < 65504.0f); /* NaN: 65504, as the scalar form */
    a = (glow__g4f)(((glow__g4u)a & lt) | (~lt & 0x477FE000u));
    const glow__g4u h = ((((glow__g4u)a + 0x1000u) >> 13) - (112u << 10)) | sign;
    return h & (glow__g4u)(a >= 6.103515625e-05f);
}
static void gradient_u_range(glow_system *s, uint32_t k0, uint32_t k1) {
    const size_t N = s->N;
    const float *restrict fy = s->flux, *restrict mo = s->mom, *restrict gcm = s->grad_cm;
    const uint32_t *restrict sub = s->sub_nodes;
    uint32_t k = k0;
    for (; k < k1 && k % 4u; ++k) { /* to the first whole block of grad_cm */
        const uint32_t n = sub[k];
        gradient_u(s, k, n, fy[n], mo[n], mo[N + n], mo[2 * N + n]);
    }
    if (s->grad_uz)
        for (; k + 4u <= k1; k += 4u) {
            const uint32_t n0 = sub[k], n1 = sub[k + 1u], n2 = sub[k + 2u], n3 = sub[k + 3u];
            const glow__g4f y = {fy[n0], fy[n1], fy[n2], fy[n3]};
            const glow__g4f m0 = {mo[n0], mo[n1], mo[n2], mo[n3]};
            const glow__g4f m1 = {mo[N + n0], mo[N + n1], mo[N + n2], mo[N + n3]};
            const glow__g4f m2 = {mo[2 * N + n0], mo[2 * N + n1], mo[2 * N + n2], mo[2 * N + n3]};
            const float *c = gcm + GRAD_CM(k, 0);
            glow__g4f cm[12];
            for (int q = 0; q < 12; ++q) memcpy(&cm[q], c + 4 * q, sizeof cm[q]); /* the four nodes' value q */
            const glow__g4u pos = (glow__g4u)(y > 0.0f); /* else u = 0 */
            const glow__g4f inv = 1.0f / y;
            const glow__g4f d0 = m0 * inv - cm[0], d1 = m1 * inv - cm[1], d2 = m2 * inv - cm[2];
            const glow__g4u ox = signed_half4(cm[3] * d0 + cm[4] * d1 + cm[5] * d2) & pos;
            const glow__g4u oy = signed_half4(cm[6] * d0 + cm[7] * d1 + cm[8] * d2) & pos;
            const glow__g4u oz = signed_half4(cm[9] * d0 + cm[10] * d1 + cm[11] * d2) & pos;
            const glow__g4u xy = ox | oy << 16;
            const uint32_t n[4] = {n0, n1, n2, n3};
            for (int i = 0; i < 4; ++i) {
                const uint32_t v = xy[i];
                memcpy(s->rad + 4 * (size_t)n[i] + 3, &v, sizeof v);
                s->grad_uz[n[i]] = (uint16_t)oz[i];
            }
        }
    for (; k < k1; ++k) {
        const uint32_t n = sub[k];
        gradient_u(s, k, n, fy[n], mo[n], mo[N + n], mo[2 * N + n]);
    }
}

/* the first of the ascending sub_nodes >= n */
static uint32_t sub_lower_bound(const glow_system *s, uint32_t n) {
    uint32_t k = 0, hi = s->sub_count;
    while (k < hi) {
        const uint32_t mid = k + (hi - k) / 2u;
        if (s->sub_nodes[mid] < n) k = mid + 1u;
        else hi = mid;
    }
    return k;
}

/* One level's nodes [first, end): flux and radiance from the children, and with link gradients the
 * luma-flux moments in the same pass and then the u of the sub_nodes among them, while their values
 * are in L1 (`mom` is a constant at each call: two specialised loops). A separate pass over the
 * sub_nodes after the pull, one at a time, cost 0.30-0.37 ms of the pull's 0.54-0.65 on Sponza
 * moderate (one thread, 21305 sub_nodes). */
static inline __attribute__((always_inline)) void pull_nodes(glow_system *s, uint32_t first, uint32_t end, bool mom) {
    const size_t N = s->N;
    float *restrict fy = s->flux, *restrict fco = s->flux + N, *restrict fcg = s->flux + 2 * N;
    float *restrict mx = s->mom, *restrict my = mom ? s->mom + N : NULL, *restrict mz = mom ? s->mom + 2 * N : NULL;
    float *restrict r = s->rad;
    const glow_bake_node *restrict nodes = s->nodes;
    const float *restrict inv_pi_area = s->inv_pi_area;
    for (uint32_t n = first; n < end; ++n) {
        const uint32_t a = nodes[n].child[0], b = nodes[n].child[1];
        const float ipa = inv_pi_area[n];
        const float y = fy[a] + fy[b], co = fco[a] + fco[b], cg = fcg[a] + fcg[b];
        fy[n] = y;
        fco[n] = co;
        fcg[n] = cg;
        float *restrict rn = r + 4 * (size_t)n;
        rn[0] = y * ipa;
        rn[1] = co * ipa;
        rn[2] = cg * ipa;
        rn[3] = 0.0f;
        if (mom) {
            const float x = mx[a] + mx[b], yy = my[a] + my[b], z = mz[a] + mz[b];
            mx[n] = x;
            my[n] = yy;
            mz[n] = z;
        }
    }
    if (mom && s->sub_count) gradient_u_range(s, sub_lower_bound(s, first), sub_lower_bound(s, end));
}

static void pull_range(glow_system *s, uint32_t first, uint32_t end) {
    if (s->mom) pull_nodes(s, first, end, true); /* link gradients */
    else pull_nodes(s, first, end, false);
}

/* LSUB ratios (not gradients) of sub_nodes [first, end), after the pull (their slots, grandchildren,
 * are final) */
static void sub_ratio_range(glow_system *s, uint32_t first, uint32_t end) {
    const float *restrict r = s->rad;
    for (uint32_t k = first; k < end; ++k) {
        const uint32_t n = s->sub_nodes[k];
        const uint32_t *sl = s->slots + 4 * (size_t)n;
        const float yn = r[4 * (size_t)n];
        const float inv = yn > 0.0f ? 1.0f / yn : 0.0f;
        for (int i = 0; i < 4; ++i)
            s->sub_ratio[4 * (size_t)n + (size_t)i] = inv > 0.0f ? ratio_half(r[4 * (size_t)sl[i]] * inv) : 0x3C00u;
    }
}

static void task_sub_ratio(void *data, uint32_t k, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    const uint32_t first = k * NODE_CHUNK, end = first + NODE_CHUNK < s->sub_count ? first + NODE_CHUNK : s->sub_count;
    sub_ratio_range(s, first, end);
}

static void task_pull(void *data, uint32_t k, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    uint32_t first = s->pull_first + k * NODE_CHUNK, end = s->pull_first + s->pull_count;
    if (first + NODE_CHUNK < end) end = first + NODE_CHUNK;
    pull_range(s, first, end);
}

static void task_caches(void *data, uint32_t k, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    const bool sh = s->link_mode == GLOW_LINK_MODE_SH; /* SHLK weights multiply node flux (planar) */
    glow__cl_args a = {.blocks = glow__bake_link_blocks(s->bake),
                       .blocks_per_cache = s->bpc,
                       .rad_y = sh ? s->flux : s->rad,
                       .rad_co = sh ? s->flux + s->N : s->rad + 1,
                       .rad_cg = sh ? s->flux + 2 * s->N : s->rad + 2,
                       .rad_stride = sh ? 1 : 4,
                       .luma = s->luma,
                       .chroma = s->chroma,
                       .coeffs = s->coeffs,
                       .cache_sh = s->cache_sh,
                       .isa = s->isa,
                       .xblocks = s->xlinks,
                       .xblock_size = s->xlink_size,
                       .coeff_scale = s->cl_scale,
                       .xscale = s->xscale,
                       .subsets = s->subsets,
                       .sub_ratio = (const uint32_t *)(const void *)s->sub_ratio,
                       .grad_uz = sh ? NULL : s->grad_uz,
                       .link_gradient = s->gradient};
    uint32_t first = k * CACHE_CHUNK, count = s->C - first < CACHE_CHUNK ? s->C - first : CACHE_CHUNK;
    glow__cl_light_caches(&a, first, count);
}

/* cache lighting of the budget's selection: task k gathers group grp_sel[k] and records how much it
 * changed the caches' luma (DC): the convergence test of later updates */
static void task_caches_sel(void *data, uint32_t k, uint32_t worker) {
    glow_system *s = data;
    const double t0 = now_ms();
    const uint32_t g = s->grp_sel[k], first = g * GLOW_BUDGET_GROUP;
    const uint32_t count = s->C - first < GLOW_BUDGET_GROUP ? s->C - first : GLOW_BUDGET_GROUP;
    float before[GLOW_BUDGET_GROUP];
    for (uint32_t i = 0; i < count; ++i) before[i] = s->cache_sh[(size_t)(first + i) * s->coeffs];
    _Static_assert(GLOW_BUDGET_GROUP == CACHE_CHUNK, "a group is one cache-lighting task");
    task_caches(data, g, worker);
    double d = 0.0, v = 0.0;
    for (uint32_t i = 0; i < count; ++i) {
        const float now = s->cache_sh[(size_t)(first + i) * s->coeffs];
        d += fabs((double)now - before[i]);
        v += fabs((double)now);
    }
    s->grp_delta[g] = v > 0.0 ? (float)(d / v) : (d > 0.0 ? INFINITY : 0.0f);
    s->grp_busy[k] = (float)(now_ms() - t0); /* the time budget's cost model (glow_budget_cost_learn) */
}

/* outputs: tasks of PLANE_CHUNK cells (the grid's, then the lightmap's texels), each writing all the
 * planes of its cells, empty cells/texels as 0 (glow__cl_write_planes: every cache row read once),
 * then the lightmap detail, DETAIL_CHUNK texels a task. */
#define PLANE_CHUNK 2048u
_Static_assert(GLOW__CL_EMPTY == GLOW_MAP_EMPTY, "one empty marker");
static void detail_range(glow_system *s, uint32_t first, uint32_t end) {
    const float *restrict rad = s->rad, *restrict w = s->det_weight;
    const uint32_t *restrict fi = s->det_first, *restrict sf = s->det_surfel, *restrict tx = s->det_texel;
    float *restrict out = s->det_out;
    typedef float v4f __attribute__((vector_size(16))); /* Y Co Cg pad: one vector multiply-add a link */
    for (uint32_t i = first; i < end; ++i) {
        v4f acc = {0.0f, 0.0f, 0.0f, 0.0f};
        for (uint32_t k = fi[i]; k < fi[i + 1]; ++k) {
            v4f r;
            memcpy(&r, rad + 4 * (size_t)sf[k], sizeof r);
            acc += w[k] * r;
        }
        const float y = acc[0], co = acc[1], cg = acc[2];
        float *o = out + 4 * (size_t)tx[i];
        o[0] = y + co - cg; /* glow_ycocg_to_rgb */
        o[1] = y + cg;
        o[2] = y - co - cg;
    }
}

/* the detail's chunk c: DETAIL_CHUNK texels (task_output, task_output_sel) */
static void detail_chunk(glow_system *s, uint32_t c) {
    const uint32_t first = c * DETAIL_CHUNK, T = s->det->texel_count;
    detail_range(s, first, T - first < DETAIL_CHUNK ? T : first + DETAIL_CHUNK);
}

static uint32_t output_tasks(const glow_system *s, uint32_t *grid_tasks, uint32_t *plane_tasks) {
    const bool none = s->planes == GLOW_OUTPUT_PLANES_NONE;
    const uint32_t g = none ? 0u : div_up(s->grid_cells, PLANE_CHUNK), p = g + (none ? 0u : div_up(s->lm_texels, PLANE_CHUNK));
    if (grid_tasks) *grid_tasks = g;
    if (plane_tasks) *plane_tasks = p;
    return p + (s->det ? div_up(s->det->texel_count, DETAIL_CHUNK) : 0u);
}

static void task_output(void *data, uint32_t q, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    uint32_t g, planes;
    output_tasks(s, &g, &planes);
    if (q >= planes) { /* the lightmap detail */
        detail_chunk(s, q - planes);
        return;
    }
    const bool grid = q < g;
    const size_t n = grid ? s->grid_cells : s->lm_texels, first = (size_t)(grid ? q : q - g) * PLANE_CHUNK;
    const size_t end = n - first < PLANE_CHUNK ? n : first + PLANE_CHUNK;
    if (s->planes == GLOW_OUTPUT_PLANES_RGBA16F)
        glow__cl_write_rgba16f(s->isa, grid ? s->grid_h : s->lm_h, n, grid ? 1u : s->out.lightmap_pages,
                               grid ? s->grid_map : s->lm_map, first, end, s->cache_sh, s->coeffs);
    else
        glow__cl_write_planes(s->isa, grid ? s->grid_sh : s->lm_sh, n, grid ? s->grid_map : s->lm_map, first, end,
                              s->cache_sh, s->coeffs);
}

/* outputs of a budgeted update whose outputs were written last from the same caches but the gathered
 * ones (output_sel): task q < sel_count writes the cells and texels of group grp_sel[q], one float to
 * each plane (the same bytes as glow__cl_write_planes: copies, no arithmetic); the tasks after them
 * are the detail's, as task_output's. */
static void task_output_sel(void *data, uint32_t q, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    if (q >= s->sel_count) {
        detail_chunk(s, q - s->sel_count);
        return;
    }
    const uint32_t g = s->grp_sel[q], nc = s->coeffs;
    if (s->planes == GLOW_OUTPUT_PLANES_NONE) return;
    const bool f16 = s->planes == GLOW_OUTPUT_PLANES_RGBA16F;
    for (uint32_t i = s->grp_out_off[g]; i < s->grp_out_off[g + 1u]; ++i) {
        const uint32_t p = s->grp_out[i];
        const bool grid = p < s->grid_used;
        const size_t n = grid ? s->grid_cells : s->lm_texels, t = s->out_index[p];
        const float *restrict src = s->cache_sh + (size_t)s->out_cache[p] * nc;
        if (f16) {
            const size_t ps = grid ? n : n / s->out.lightmap_pages;
            glow__rgba16f_put((grid ? s->grid_h : s->lm_h) + glow__rgba16f_at(ps, nc, t), ps, nc, src);
        } else {
            float *restrict dst = (grid ? s->grid_sh : s->lm_sh) + t;
            for (uint32_t k = 0; k < nc; ++k) dst[k * n] = src[k];
        }
    }
}

/* create-time: expanded links for caches [k*EXPAND_CHUNK, ...) */
#define EXPAND_CHUNK 64u
static void task_expand(void *data, uint32_t k, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    uint32_t first = k * EXPAND_CHUNK, count = s->C - first < EXPAND_CHUNK ? s->C - first : EXPAND_CHUNK;
    glow__cl_expand(glow__bake_link_blocks(s->bake), s->bpc, s->luma, s->xblocks, first, count);
}

/* create-time: feedback weights and the indirect-albedo cap, per surfel */
static void task_feedback_setup(void *data, uint32_t k, uint32_t worker) {
    (void)worker;
    glow_system *s = data;
    const uint32_t first = k * SURFEL_CHUNK, end = first + SURFEL_CHUNK < s->S ? first + SURFEL_CHUNK : s->S;
    const uint32_t L = s->luma;
    float sl[GLOW__MAX_BANDS];
    for (uint32_t l = 0; l < L; ++l) sl[l] = glow_sh_lobe_factor(l, 1.0f);
    const glow_bake_link_block *blocks = glow__bake_link_blocks(s->bake);
    const uint32_t nl = s->meta->links_per_cache;
    for (uint32_t i = first; i < end; ++i) {
        const float *n = s->nrm4 + 4 * (size_t)i;
        float y[GLOW__MAX_BANDS * GLOW__MAX_BANDS];
        glow_sh_eval(L, n, y);
        for (uint32_t l = 0; l < L; ++l)
            for (uint32_t q = l * l; q < (l + 1) * (l + 1); ++q) s->fb_w[(size_t)i * s->fbk + q] = PI_F * sl[l] * y[q];
        /* G_s */
        double G = 0.0;
        const glow_bake_link_block *b = blocks + (size_t)s->feedback[i] * s->bpc;
        for (uint32_t j = 0; j < nl; ++j) {
            const glow_bake_link_block *bb = b + j / GLOW_LINK_BLOCK;
            uint32_t lane = j % GLOW_LINK_BLOCK;
            float omc = glow__half_to_float(bb->one_minus_cos[lane]);
            if (!(omc > 0.0f)) continue;
            uint32_t du, dv;
            glow_bake_link_dir12(bb, lane, &du, &dv);
            float d[3];
            glow__oct_decode12(du, dv, d);
            double x = 1.0 - omc, t = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
            /* Legendre in x (cone) up to L, and in t (angle to the normal) up to L-1 */
            double Px[GLOW__MAX_BANDS + 2], Pt[GLOW__MAX_BANDS + 2];
            glow__legendre_all(L + 1, x, Px);
            glow__legendre_all(L, t, Pt);
            double w = 0.0;
            for (uint32_t l = 0; l < L; ++l) {
                double kl = l == 0 ? 2.0 * 3.14159265358979323846 * omc
                                   : 2.0 * 3.14159265358979323846 / (2.0 * l + 1.0) * (Px[l - 1] - Px[l + 1]);
                w += sl[l] * kl * (2.0 * l + 1.0) / (4.0 * 3.14159265358979323846) * Pt[l];
            }
            G += fabs(w) * 3.14159265358979323846;
        }
        s->rho_ind_max[i] = G > 0.0 ? (float)(ALBEDO_MAX * 3.14159265358979323846 / G) : ALBEDO_MAX;
    }
}

/* ------------------------------------------------------------------------------ create */
static void *alloc_array(glow_system *s, size_t count, size_t elem, bool *ok) {
    if (!*ok) return NULL;
    if (count != 0 && elem > SIZE_MAX / count) {
        *ok = false;
        return NULL;
    }
    void *p = glow__ctx_alloc(s->ctx, count * elem, 64);
    if (!p) {
        *ok = false;
        return NULL;
    }
    /* Zeroed: every page touched here, at create (the loader's time), not in the first updates (and
     * create relies on the zeros: caches, light and outputs start dark). A buffer that
     * create leaves for the update to fill (rad_out, the scratch) otherwise takes its pages' first-touch
     * faults inside a budgeted update. On this 2-core VM a streamed-in system's first update took 135
     * minor faults in its output stage, 2.5 ms against 0.35 (the 4x4 level under 2 ms, --stream 20). */
    memset(p, 0, count * elem);
    s->memory_bytes += count * elem;
    return p;
}

static void free_system(glow_system *s) {
    glow_context *ctx = s->ctx;
    void *bufs[] = {s->pos4, s->nrm4, s->mat, s->tri, s->feedback, s->albedo, s->emis_base, s->emis,
                    s->direct, s->direct_spare, s->fb_w, s->rho_ind_max, s->flux, s->rad, s->inv_pi_area, s->leaf_area,
                    s->cache_sh, s->grid_sh, s->lm_sh, s->grid_h, s->lm_h, s->grid_map, s->lm_map, s->mat_emis_scale,
                    s->mat_albedo_scale, s->batch_status, s->batch_negative, s->out_index, s->out_cache,
                    s->grp_out, s->grp_out_off, s->xblocks, s->slots, s->sub_ratio, s->grad_uz, s->sub_nodes, s->mom, s->grad_cm, s->grp_age, s->grp_delta,
                    s->grp_drift_at, s->grp_centre,
                    s->grp_pack, s->grp_sel, s->grp_skip, s->grp_busy, s->rad_prev, s->uv0, s->det_out, s->rad_out, s->dep_max_node,
                    s->sky_grid, s->sky_backup, s->bat_age, s->bat_centre, s->bat_pack, s->bat_sel, s->bat_ms, s->bat_current};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; ++i) glow__ctx_free(ctx, bufs[i]);
    glow__ctx_free(ctx, s);
}

/* c and M (gradient_moments) of a node from its area moments o (A, A p, A p p^T); left 0 where
 * there are none */
static void gradient_cm_of(const double *o, float cm[12]) {
    if (!(o[0] > 0.0)) return;
    const double c[3] = {o[1] / o[0], o[2] / o[0], o[3] / o[0]};
    const double C[6] = {o[4] / o[0] - c[0] * c[0], o[5] / o[0] - c[0] * c[1], o[6] / o[0] - c[0] * c[2],
                         o[7] / o[0] - c[1] * c[1], o[8] / o[0] - c[1] * c[2], o[9] / o[0] - c[2] * c[2]};
    for (int q = 0; q < 3; ++q) cm[q] = (float)c[q];
    const double tr = C[0] + C[3] + C[5];
    if (!(tr > 0.0)) return; /* M = 0: u = 0 */
    const double eps = 1e-3 * tr + 1e-30;
    const double m00 = C[0] + eps, m01 = C[1], m02 = C[2], m11 = C[3] + eps, m12 = C[4], m22 = C[5] + eps;
    const double i00 = m11 * m22 - m12 * m12, i01 = m02 * m12 - m01 * m22, i02 = m01 * m12 - m02 * m11;
    const double i11 = m00 * m22 - m02 * m02, i12 = m01 * m02 - m00 * m12, i22 = m00 * m11 - m01 * m01;
    const double det = m00 * i00 + m01 * i01 + m02 * i02;
    if (!(fabs(det) > 0.0)) return;
    const double f = sqrt(tr) / det;
    const double M[9] = {i00, i01, i02, i01, i11, i12, i02, i12, i22};
    for (int q = 0; q < 9; ++q) cm[3 + q] = (float)(f * M[q]);
}

/* Link gradients: each sub_node's area centroid c and M = sigma (C + 1e-3 trace(C) I)^-1 (C the
 * area-weighted covariance of its leaves' positions, sigma = sqrt(trace C)), as the bake's
 * link_gradient and audit_gradient (precompute/src/links.c) take them: area moments of the surfels
 * summed up the hierarchy in double. False when out of memory. */
static bool gradient_moments(glow_system *s) {
    const size_t S = s->S, N = s->N;
    double *mo = glow__ctx_alloc(s->ctx, N * 10 * sizeof(double), 64); /* A, A p (3), A p p^T (6) */
    if (!mo) return false;
    for (size_t i = 0; i < S; ++i) {
        const double a = s->nodes[i].area;
        const double p[3] = {s->pos4[4 * i], s->pos4[4 * i + 1], s->pos4[4 * i + 2]};
        double *o = mo + 10 * i;
        o[0] = a;
        for (int k = 0; k < 3; ++k) o[1 + k] = a * p[k];
        o[4] = a * p[0] * p[0], o[5] = a * p[0] * p[1], o[6] = a * p[0] * p[2];
        o[7] = a * p[1] * p[1], o[8] = a * p[1] * p[2], o[9] = a * p[2] * p[2];
    }
    for (uint32_t lv = 1; lv < s->levels; ++lv) /* children precede parents level by level, as the pull */
        for (uint32_t n = s->level_starts[lv]; n < s->level_starts[lv + 1]; ++n) {
            const double *a = mo + 10 * (size_t)s->nodes[n].child[0], *b = mo + 10 * (size_t)s->nodes[n].child[1];
            for (int k = 0; k < 10; ++k) mo[10 * (size_t)n + k] = a[k] + b[k];
        }
    /* grad_cm starts zeroed (alloc_array), a last block's padding too */
    for (uint32_t k = 0; k < s->sub_count; ++k) {
        float cm[12] = {0}; /* 0 where the moments give none */
        gradient_cm_of(mo + 10 * (size_t)s->sub_nodes[k], cm);
        for (uint32_t q = 0; q < 12u; ++q) s->grad_cm[GRAD_CM(k, q)] = cm[q];
    }
    glow__ctx_free(s->ctx, mo);
    return true;
}

glow_result glow_system_create(glow_context *ctx, const glow_system_desc *desc, glow_system **out) {
    if (out) *out = NULL;
    if (!ctx || !desc || !out) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_system_create: context, desc and out_system must not be NULL");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const char *label = desc->label ? desc->label : "system";
    if (!desc->bake) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_system_create(%s): desc->bake is NULL", label);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (glow__bake_context(desc->bake) != ctx) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_system_create(%s): the bake was loaded with another context", label);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const glow_bake_meta *m = glow__bake_meta(desc->bake);
    if (!(m->link_kind & GLOW_LINK_KIND_RUNTIME_PROJECTION) || m->cache_count == 0 || m->links_per_cache == 0) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_system_create(%s): the bake has no runtime-projection links (%u caches, %u links each)",
                        label, m->cache_count, m->links_per_cache);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    uint32_t luma = desc->sh_bands_luma ? desc->sh_bands_luma : m->sh_bands;
    if (luma == 0) luma = 3;
    uint32_t chroma = desc->sh_bands_chroma ? desc->sh_bands_chroma : luma;
    if (luma > GLOW_MAX_SH_BANDS || chroma > luma) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_system_create(%s): sh_bands_luma %u / sh_bands_chroma %u out of range "
                        "(need 1 <= chroma <= luma <= %u)",
                        label, luma, chroma, GLOW_MAX_SH_BANDS);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    uint32_t batch = desc->surfel_batch_size ? desc->surfel_batch_size : 1024u;
    glow_link_mode link_mode = desc->link_mode == GLOW_LINK_MODE_DEFAULT ? GLOW_LINK_MODE_COMPACT : desc->link_mode;
    if (link_mode != GLOW_LINK_MODE_EXPANDED && link_mode != GLOW_LINK_MODE_COMPACT && link_mode != GLOW_LINK_MODE_SH) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_system_create(%s): unknown link_mode %u", label,
                        (unsigned)desc->link_mode);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (desc->output_planes != GLOW_OUTPUT_PLANES_F32 && desc->output_planes != GLOW_OUTPUT_PLANES_RGBA16F &&
        desc->output_planes != GLOW_OUTPUT_PLANES_NONE) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_system_create(%s): unknown output_planes %u", label,
                        (unsigned)desc->output_planes);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (link_mode == GLOW_LINK_MODE_SH && (!(m->link_kind & GLOW_LINK_KIND_FULL_SH) || !glow__bake_shlk_blocks(desc->bake))) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_UNSUPPORTED,
                        "glow_system_create(%s): GLOW_LINK_MODE_SH needs full-SH links, and this bake has none "
                        "(bake it with glow-bake --sh-links)",
                        label);
        return GLOW_ERROR_UNSUPPORTED;
    }
    const glow_bake_xref *xref = glow__bake_xref(desc->bake, NULL, NULL);
    if (link_mode == GLOW_LINK_MODE_SH && xref && xref->proxy_count) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_UNSUPPORTED,
                        "glow_system_create(%s): GLOW_LINK_MODE_SH reads node flux, which proxy nodes (links to "
                        "neighbouring systems) do not carry; use the compact or expanded link mode",
                        label);
        return GLOW_ERROR_UNSUPPORTED;
    }
    if (link_mode == GLOW_LINK_MODE_SH && luma > m->sh_bands) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_system_create(%s): sh_bands_luma %u > the bake's %u: full-SH links carry only %u bands",
                        label, luma, m->sh_bands, m->sh_bands);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }

    glow_system *s = glow__ctx_alloc(ctx, sizeof *s, 64);
    if (!s) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_OUT_OF_MEMORY, "glow_system_create(%s): out of memory", label);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    memset(s, 0, sizeof *s);
    atomic_init(&s->updating, 0);
    s->ctx = ctx;
    s->bake = desc->bake;
    s->meta = m;
    s->nodes = glow__bake_nodes(desc->bake);
    s->level_starts = glow__bake_level_starts(desc->bake);
    snprintf(s->label, sizeof s->label, "%s", label);
    s->hooks = desc->lighting;
    s->S = m->surfel_count;
    s->N = m->node_count;
    s->C = m->cache_count;
    s->M = m->material_count;
    s->levels = m->level_count;
    s->bpc = m->link_blocks_per_cache;
    {
        const glow_bake_xref *xh = glow__bake_xref(desc->bake, &s->dep_keys, &s->proxies);
        s->P = xh ? xh->proxy_count : 0u;
        s->deps = xh ? xh->dependency_count : 0u;
    }
    atomic_init(&s->attached, 0);
    atomic_init(&s->bat_next, 0);
    s->batch = batch;
    s->nbatches = div_up(s->S, batch);
    s->luma = luma;
    s->chroma = chroma;
    glow__cl_coeff_scale(luma, chroma, s->cl_scale);
    s->coeffs = luma * luma + 2 * chroma * chroma;
    s->fbk = luma * luma;
    s->isa = glow__cl_best_isa();
    s->link_mode = link_mode;
    { /* benchmarking knob (documented in docs/runtime.md): GLOW_CACHE_KERNEL=generic|avx2|avx512 */
        const char *hb = getenv("GLOW_HOOK_BUDGET"); /* benchmarking knob, docs/runtime.md "Budgets" */
        s->hook_uncut = hb && !strcmp(hb, "off");
        const char *so = getenv("GLOW_SEL_OUTPUTS"); /* the same: off = whole planes in budgeted updates */
        s->full_outputs = so && !strcmp(so, "off");
        const char *k = getenv("GLOW_CACHE_KERNEL");
        glow__cl_isa want = s->isa;
        if (k && !strcmp(k, "generic")) want = GLOW__CL_GENERIC;
        else if (k && !strcmp(k, "avx2")) want = GLOW__CL_AVX2;
        else if (k && !strcmp(k, "avx512")) want = GLOW__CL_AVX512;
        if (glow__cl_isa_supported(want)) s->isa = want;
    }
    s->params = (glow_system_params)GLOW_SYSTEM_PARAMS_INIT;
    const uint32_t *gmap = glow__bake_grid_map(desc->bake), *lmap = glow__bake_lightmap_map(desc->bake);
    s->grid_cells = gmap ? (size_t)m->grid_dims[0] * m->grid_dims[1] * m->grid_dims[2] : 0;
    s->lm_texels = lmap && m->lightmap_count ? (size_t)m->lightmap_width * m->lightmap_height * m->lightmap_count : 0;

    bool ok = true;
    const size_t S = s->S, N = s->N;
    s->pos4 = alloc_array(s, S, 4 * sizeof(float), &ok);
    s->nrm4 = alloc_array(s, S, 4 * sizeof(float), &ok);
    s->mat = alloc_array(s, S, sizeof(uint32_t), &ok);
    s->tri = alloc_array(s, S, sizeof(uint32_t), &ok);
    s->feedback = alloc_array(s, S, sizeof(uint32_t), &ok);
    s->albedo = alloc_array(s, S, 3 * sizeof(float), &ok);
    s->emis_base = alloc_array(s, S, 3 * sizeof(float), &ok);
    s->emis = alloc_array(s, S, 3 * sizeof(float), &ok);
    s->direct = alloc_array(s, S, 3 * sizeof(float), &ok);
    s->direct_spare = alloc_array(s, S, 3 * sizeof(float), &ok);
    s->fb_w = alloc_array(s, S, (size_t)s->fbk * sizeof(float), &ok);
    s->rho_ind_max = alloc_array(s, S, sizeof(float), &ok);
    s->flux = alloc_array(s, N, 3 * sizeof(float), &ok);
    s->rad = alloc_array(s, N + s->P, 4 * sizeof(float), &ok); /* interleaved Y Co Cg pad; then the proxies */
    s->inv_pi_area = alloc_array(s, N, sizeof(float), &ok);
    s->leaf_area = alloc_array(s, S, sizeof(float), &ok);
    s->cache_sh = alloc_array(s, s->C, (size_t)s->coeffs * sizeof(float), &ok);
    {
        glow_bake_sky_transfer sky;
        if (glow_bake_get_sky_transfer(s->bake, &sky) == GLOW_OK && sky.grid_visibility && sky.grid_cache_count)
            s->sky_V = sky.grid_visibility; /* sky_grid and sky_backup: the first glow_system_set_sky */
    }
    s->planes = desc->output_planes;
    if (s->planes == GLOW_OUTPUT_PLANES_F32) {
        s->grid_sh = alloc_array(s, s->grid_cells, (size_t)s->coeffs * sizeof(float), &ok);
        s->lm_sh = alloc_array(s, s->lm_texels, (size_t)s->coeffs * sizeof(float), &ok);
    } else if (s->planes == GLOW_OUTPUT_PLANES_RGBA16F) { /* Q planes of 4 halves */
        const size_t q4 = (size_t)(s->coeffs + 3u) / 4u * 4u;
        s->grid_h = alloc_array(s, s->grid_cells, q4 * sizeof(uint16_t), &ok);
        s->lm_h = alloc_array(s, s->lm_texels, q4 * sizeof(uint16_t), &ok);
    }
    s->grid_map = alloc_array(s, s->grid_cells, sizeof(uint32_t), &ok);
    s->lm_map = alloc_array(s, s->lm_texels, sizeof(uint32_t), &ok);
    s->mat_emis_scale = alloc_array(s, s->M ? s->M : 1u, 3 * sizeof(float), &ok);
    s->mat_albedo_scale = alloc_array(s, s->M ? s->M : 1u, 3 * sizeof(float), &ok);
    s->batch_status = alloc_array(s, s->nbatches, 1, &ok);
    s->batch_negative = alloc_array(s, s->nbatches, sizeof(uint32_t), &ok);
    const size_t NB = s->nbatches ? s->nbatches : 1u;
    s->bat_age = alloc_array(s, NB, sizeof(uint32_t), &ok);
    s->bat_centre = alloc_array(s, NB, 3 * sizeof(float), &ok);
    s->bat_pack = alloc_array(s, NB, sizeof(uint64_t), &ok);
    s->bat_sel = alloc_array(s, NB, sizeof(uint32_t), &ok);
    s->bat_ms = alloc_array(s, NB, sizeof(float), &ok);
    s->bat_current = alloc_array(s, NB, 1, &ok);
    size_t used = 0;
    for (size_t i = 0; i < s->grid_cells; ++i) used += gmap[i] != GLOW_MAP_EMPTY;
    for (size_t i = 0; i < s->lm_texels; ++i) used += lmap[i] != GLOW_MAP_EMPTY;
    s->out_index = alloc_array(s, used, sizeof(uint32_t), &ok);
    s->out_cache = alloc_array(s, used, sizeof(uint32_t), &ok);
    s->grp_out = alloc_array(s, used ? used : 1u, sizeof(uint32_t), &ok);
    s->grp_out_off = alloc_array(s, (size_t)div_up(s->C, GLOW_BUDGET_GROUP) + 1u, sizeof(uint32_t), &ok);
    if (link_mode == GLOW_LINK_MODE_EXPANDED)
        s->xblocks = alloc_array(s, (size_t)s->C * s->bpc, glow__cl_xblock_size(luma), &ok);
    const bool lsub = glow__bake_link_subsets(desc->bake) != NULL;
    s->gradient = lsub && (m->link_kind & GLOW_LINK_KIND_GRADIENT);
    if (lsub && !s->gradient)
        s->slots = alloc_array(s, N, 4 * sizeof(uint32_t), &ok);
    const bool grad_fold = s->gradient && link_mode != GLOW_LINK_MODE_SH; /* SH mode reads planar flux */
    if (lsub && !grad_fold) s->sub_ratio = alloc_array(s, N + s->P, 4 * sizeof(uint16_t), &ok); /* proxies: ratio 1 (u 0) */
    if (grad_fold) s->grad_uz = alloc_array(s, N + s->P + 2u, sizeof(uint16_t), &ok); /* proxies: u 0 */
    if (s->gradient) s->mom = alloc_array(s, N, 3 * sizeof(float), &ok);
    if (lsub && ok) { /* which internal nodes a weighted link reads (their ratios are computed each update) */
        const uint16_t *sub = glow__bake_link_subsets(desc->bake);
        const glow_bake_link_block *lb = glow__bake_link_blocks(desc->bake);
        uint8_t *mark = glow__ctx_alloc(ctx, N + 1, 64);
        if (!mark) ok = false;
        else {
            memset(mark, 0, N + 1);
            const size_t links = (size_t)s->C * s->bpc * GLOW_LINK_BLOCK;
            for (size_t j = 0; j < links; ++j)
                if (sub[j]) {
                    const uint32_t n = glow_bake_link_node(lb + j / GLOW_LINK_BLOCK, (uint32_t)(j % GLOW_LINK_BLOCK));
                    if (n < N) mark[n] = 1;
                }
            uint32_t marked = 0;
            for (size_t n = S; n < N; ++n) marked += mark[n]; /* leaves (n < S) keep ratio 1 */
            s->sub_count = marked;
            s->sub_nodes = alloc_array(s, marked ? marked : 1u, sizeof(uint32_t), &ok);
            if (ok) {
                marked = 0;
                for (size_t n = S; n < N; ++n)
                    if (mark[n]) s->sub_nodes[marked++] = (uint32_t)n;
            }
            if (s->gradient) /* whole blocks of four (GRAD_CM) */
                s->grad_cm = alloc_array(s, ((marked ? marked : 1u) + 3u) / 4u * 4u, 12 * sizeof(float), &ok);
            glow__ctx_free(ctx, mark);
        }
    }
    s->groups = div_up(s->C, GLOW_BUDGET_GROUP);
    const size_t G = s->groups ? s->groups : 1u;
    s->grp_age = alloc_array(s, G, sizeof(uint32_t), &ok);
    s->grp_delta = alloc_array(s, G, sizeof(float), &ok);
    s->grp_drift_at = alloc_array(s, G, sizeof(double), &ok);
    s->grp_centre = alloc_array(s, G, 3 * sizeof(float), &ok);
    s->grp_pack = alloc_array(s, G, sizeof(uint64_t), &ok);
    s->grp_sel = alloc_array(s, G, sizeof(uint32_t), &ok);
    s->grp_skip = alloc_array(s, G, 1, &ok);
    s->grp_busy = alloc_array(s, G, sizeof(float), &ok);
    s->rad_prev = alloc_array(s, N + s->P ? N + s->P : 1u, sizeof(float), &ok);
    if (s->deps) s->dep_max_node = alloc_array(s, s->deps, sizeof(uint32_t), &ok);
    s->rad_out = alloc_array(s, N ? N : 1u, 4 * sizeof(float), &ok);
    glow_bake_geometry geo;
    glow_bake_get_geometry(desc->bake, &geo);
    if (geo.material_uv) s->uv0 = alloc_array(s, S, 2 * sizeof(float), &ok);
    s->det = s->lm_texels ? glow__bake_detail(desc->bake, &s->det_texel, &s->det_first, &s->det_surfel, &s->det_weight)
                          : NULL;
    if (s->det) /* every page's (format 1.7) */
        s->det_out = alloc_array(s, (size_t)s->det->width * s->det->height * m->lightmap_count, 4 * sizeof(float), &ok);
    if (!ok) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_OUT_OF_MEMORY, "glow_system_create(%s): out of memory (%u surfels, %u caches)",
                        label, s->S, s->C);
        free_system(s);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }

    const glow_bake_surfel *sf = glow__bake_surfels(desc->bake);
    for (size_t i = 0; i < S; ++i) {
        memcpy(s->pos4 + 4 * i, sf[i].position, 3 * sizeof(float));
        s->pos4[4 * i + 3] = s->leaf_area[i] = s->nodes[i].area;
        memcpy(s->nrm4 + 4 * i, sf[i].normal, 3 * sizeof(float));
        s->nrm4[4 * i + 3] = 0.0f;
        s->mat[i] = sf[i].material;
        s->tri[i] = sf[i].triangle;
        s->feedback[i] = sf[i].feedback;
        memcpy(s->albedo + 3 * i, sf[i].albedo, 3 * sizeof(float));
        memcpy(s->emis_base + 3 * i, sf[i].emission, 3 * sizeof(float));
    }
    memcpy(s->emis, s->emis_base, S * 3 * sizeof(float));
    if (s->uv0) { /* each surfel's material UV: its position's barycentrics on its triangle, clamped into it */
        for (size_t i = 0; i < S; ++i) {
            const uint32_t t = s->tri[i] < geo.triangle_count ? s->tri[i] : 0u;
            const float *p = (const float *)((const unsigned char *)geo.positions + (size_t)t * geo.stride);
            const float *q = s->pos4 + 4 * i, *uv = geo.material_uv + 6 * (size_t)t;
            double e1[3], e2[3], w[3];
            for (int k = 0; k < 3; ++k) {
                e1[k] = (double)p[3 + k] - p[k];
                e2[k] = (double)p[6 + k] - p[k];
                w[k] = (double)q[k] - p[k];
            }
            const double d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2], d12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2],
                         d22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2], w1 = w[0] * e1[0] + w[1] * e1[1] + w[2] * e1[2],
                         w2 = w[0] * e2[0] + w[1] * e2[1] + w[2] * e2[2], det = d11 * d22 - d12 * d12;
            double b1 = det > 0.0 ? (d22 * w1 - d12 * w2) / det : 1.0 / 3.0, b2 = det > 0.0 ? (d11 * w2 - d12 * w1) / det : 1.0 / 3.0;
            b1 = b1 < 0.0 ? 0.0 : b1 > 1.0 ? 1.0 : b1;
            b2 = b2 < 0.0 ? 0.0 : b2 > 1.0 - b1 ? 1.0 - b1 : b2;
            const double b0 = 1.0 - b1 - b2;
            s->uv0[2 * i] = (float)(b0 * uv[0] + b1 * uv[2] + b2 * uv[4]);
            s->uv0[2 * i + 1] = (float)(b0 * uv[1] + b1 * uv[3] + b2 * uv[5]);
        }
    }
    /* direct, flux, rad, dep_max_node and every other buffer start zeroed (alloc_array) */
    for (uint32_t p = 0; p < s->P; ++p) {
        uint32_t *mx = &s->dep_max_node[s->proxies[p].dependency];
        if (s->proxies[p].node + 1u > *mx) *mx = s->proxies[p].node + 1u;
    }
    for (size_t n = 0; n < N; ++n) s->inv_pi_area[n] = 1.0f / (PI_F * s->nodes[n].area);
    if (s->gradient) {
        s->subsets = glow__bake_link_subsets(desc->bake);
        /* sub_ratio, grad_uz and mom start zeroed (sub_ratio's u = 0: scale 1) */
        if (!gradient_moments(s)) {
            GLOW__LOG_ERROR(ctx, GLOW_ERROR_OUT_OF_MEMORY, "glow_system_create(%s): out of memory (link gradients)",
                            label);
            free_system(s);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
    }
    if (s->slots) {
        s->subsets = glow__bake_link_subsets(desc->bake);
        const uint32_t none[2] = {GLOW_NODE_NONE, GLOW_NODE_NONE};
        for (size_t n = 0; n < N; ++n) {
            const uint32_t *ch = s->nodes[n].child;
            glow_bake_link_slots((uint32_t)n, ch, ch[0] != GLOW_NODE_NONE ? s->nodes[ch[0]].child : none,
                                 ch[1] != GLOW_NODE_NONE ? s->nodes[ch[1]].child : none, s->slots + 4 * n);
            for (int i = 0; i < 4; ++i) s->sub_ratio[4 * n + (size_t)i] = 0x3C00u; /* 1: leaves keep it */
        }
        for (size_t n = N; n < N + s->P; ++n)
            for (int i = 0; i < 4; ++i) s->sub_ratio[4 * n + (size_t)i] = 0x3C00u;
    }
    { /* budget state: every group stale and unconverged; centres for the focus (cache_sh, rad_prev start zeroed) */
        const glow_bake_cache *cc = glow__bake_caches(desc->bake);
        for (uint32_t g = 0; g < s->groups; ++g) {
            const uint32_t first = g * GLOW_BUDGET_GROUP, end = first + GLOW_BUDGET_GROUP < s->C ? first + GLOW_BUDGET_GROUP : s->C;
            double c[3] = {0, 0, 0};
            for (uint32_t i = first; i < end; ++i)
                for (int k = 0; k < 3; ++k) c[k] += cc[i].position[k];
            for (int k = 0; k < 3; ++k) s->grp_centre[3 * (size_t)g + (size_t)k] = (float)(c[k] / (double)(end - first));
            s->grp_age[g] = 0;
            s->grp_delta[g] = INFINITY;
            s->grp_drift_at[g] = 0.0;
        }
        for (uint32_t b = 0; b < s->nbatches; ++b) { /* the hook's batches, for a time budget */
            const uint32_t first = b * s->batch, end = first + s->batch < s->S ? first + s->batch : s->S;
            double c[3] = {0, 0, 0};
            for (uint32_t i = first; i < end; ++i)
                for (int k = 0; k < 3; ++k) c[k] += s->pos4[4 * (size_t)i + (size_t)k];
            for (int k = 0; k < 3; ++k) s->bat_centre[3 * (size_t)b + (size_t)k] = (float)(c[k] / (double)(end - first));
            s->bat_age[b] = 0;
            s->bat_ms[b] = -1.0f;
            s->bat_current[b] = 1; /* a first update with KEEP_LIGHTING calls no hook, as before */
        }
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) d2 += (double)(m->bounds_max[k] - m->bounds_min[k]) * (m->bounds_max[k] - m->bounds_min[k]);
        s->scene_diag = (float)sqrt(d2);
    }
    for (size_t i = 0; i < 3 * (size_t)(s->M ? s->M : 1u); ++i) s->mat_emis_scale[i] = s->mat_albedo_scale[i] = 1.0f;
    for (size_t i = 0; i < s->grid_cells; ++i) s->grid_map[i] = gmap[i] == GLOW_MAP_EMPTY ? GLOW_MAP_EMPTY : (gmap[i] & GLOW_MAP_INDEX_MASK);
    for (size_t i = 0; i < s->lm_texels; ++i) s->lm_map[i] = lmap[i] == GLOW_MAP_EMPTY ? GLOW_MAP_EMPTY : (lmap[i] & GLOW_MAP_INDEX_MASK);
    for (size_t i = 0; i < s->grid_cells; ++i)
        if (s->grid_map[i] != GLOW_MAP_EMPTY) {
            s->out_index[s->grid_used] = (uint32_t)i;
            s->out_cache[s->grid_used++] = s->grid_map[i];
        }
    for (size_t i = 0; i < s->lm_texels; ++i)
        if (s->lm_map[i] != GLOW_MAP_EMPTY) {
            s->out_index[s->grid_used + s->lm_used] = (uint32_t)i;
            s->out_cache[s->grid_used + s->lm_used++] = s->lm_map[i];
        }
    { /* the pairs by group (a counting sort; grp_sel is scratch until the first update) */
        const size_t pairs = s->grid_used + s->lm_used;
        for (size_t p = 0; p < pairs; ++p) s->grp_out_off[s->out_cache[p] / GLOW_BUDGET_GROUP + 1u]++;
        for (uint32_t g = 0; g < s->groups; ++g) {
            s->grp_out_off[g + 1u] += s->grp_out_off[g];
            s->grp_sel[g] = s->grp_out_off[g];
        }
        for (size_t p = 0; p < pairs; ++p) s->grp_out[s->grp_sel[s->out_cache[p] / GLOW_BUDGET_GROUP]++] = (uint32_t)p;
    }
    if (s->det) { /* planes 0 until the first update; the detail's RGB too, A = 1 where it covers a surface */
        for (uint32_t i = 0; i < s->det->texel_count; ++i) s->det_out[4 * (size_t)s->det_texel[i] + 3] = 1.0f;
    }
    glow__ctx_start_pool(ctx); /* threads start here, never in an update */
    glow__ctx_run(ctx, task_feedback_setup, s, div_up(s->S, SURFEL_CHUNK));
    if (s->xblocks) glow__ctx_run(ctx, task_expand, s, div_up(s->C, EXPAND_CHUNK));
    s->xlinks = s->xblocks;
    if (link_mode == GLOW_LINK_MODE_SH) { /* read in place: no copy, no extra memory */
        s->xlinks = glow__bake_shlk_blocks(desc->bake);
        s->xlink_size = glow_bake_shlk_block_size(m->sh_bands);
        s->xscale = m->factor_scale;
    }

    s->out = (glow_cache_outputs){.sh_bands_luma = luma,
                                  .sh_bands_chroma = chroma,
                                  .coeff_count = s->coeffs,
                                  .cache_count = s->C,
                                  .grid_cache_count = m->grid_cache_count,
                                  .lightmap_cache_count = m->lightmap_cache_count,
                                  .cache_sh = s->cache_sh,
                                  .grid_spacing = m->grid_spacing,
                                  .grid_sh = s->grid_cells ? s->grid_sh : NULL,
                                  .lightmap_sh = s->lm_texels ? s->lm_sh : NULL,
                                  .output_planes = s->planes,
                                  .grid_rgba16f = s->grid_cells ? s->grid_h : NULL,
                                  .lightmap_rgba16f = s->lm_texels ? s->lm_h : NULL,
                                  .grid_map = s->grid_cells ? s->grid_map : NULL,
                                  .grid_visibility = s->grid_cells ? glow__bake_grid_visibility(desc->bake) : NULL,
                                  .lightmap_map = s->lm_texels ? s->lm_map : NULL};
    if (s->grid_cells) {
        memcpy(s->out.grid_dims, m->grid_dims, sizeof s->out.grid_dims);
        memcpy(s->out.grid_origin, m->grid_origin, sizeof s->out.grid_origin);
    }
    if (s->lm_texels) {
        s->out.lightmap_width = m->lightmap_width;
        s->out.lightmap_height = m->lightmap_height;
        s->out.lightmap_pages = m->lightmap_count;
    }
    const glow_bake_grid_fine *gf = s->grid_cells ? glow__bake_grid_fine(desc->bake) : NULL;
    if (gf) { /* the refined grid (GFIN), read in place: validated at load */
        const uint64_t R = gf->refine, per = (R + 1) * (R + 1) * (R + 1);
        s->out.grid_refine = gf->refine;
        s->out.grid_brick_count = gf->brick_count;
        s->out.grid_brick_of_cell = (const uint32_t *)(const void *)(gf + 1);
        s->out.grid_bricks = s->out.grid_brick_of_cell + s->grid_cells;
        s->out.grid_brick_visibility = (const uint8_t *)(const void *)(s->out.grid_bricks + (size_t)gf->brick_count * per);
    }
    if (s->det) {
        s->out.detail_width = s->det->width;
        s->out.detail_height = s->det->height;
        s->out.lightmap_detail = s->det_out;
    }
    glow__bake_retain(desc->bake);
    *out = s;
    return GLOW_OK;
}

/* A call that changes the system while its update runs (from the system's own lighting hook, or
 * from another thread) is refused: re-entering the update deadlocked, and concurrent calls raced.
 * Detection, not locking: a call that starts just before an update is not seen. */
static bool busy(glow_system *s, const char *fn) {
    if (!atomic_load(&s->updating)) return false;
    GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_OPERATION,
                    "%s(%s): called while an update of this system runs (from its own lighting hook, or from "
                    "another thread); refused",
                    fn, s->label);
    return true;
}

void glow_system_destroy(glow_system *s) {
    if (!s) return;
    if (busy(s, "glow_system_destroy")) return;
    if (atomic_load(&s->attached)) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_OPERATION,
                        "glow_system_destroy(%s): %u system(s) still read its light as a neighbour; detach it first "
                        "(glow_system_set_neighbour with NULL); not destroyed",
                        s->label, atomic_load(&s->attached));
        return;
    }
    for (uint32_t i = 0; i < s->deps; ++i)
        if (s->nbr[i]) atomic_fetch_sub(&s->nbr[i]->attached, 1u);
    glow__bake_release(s->bake);
    free_system(s);
}

const glow_bake *glow__system_bake(const glow_system *s) { return s->bake; }
const char *glow__system_label(const glow_system *s) { return s->label; }
uint32_t glow__system_cache_count(const glow_system *s) { return s->C; }
uint32_t glow__system_surfel_count(const glow_system *s) { return s->S; }

/* ------------------------------------------------------------------------------ neighbours */
/* The proxies' radiance from the attached neighbours' nodes, as their last updates left it; a proxy
 * whose neighbour is not attached keeps what it last read (zero until one was): the documented
 * fallback, its last known radiance. */
static void fill_proxies(glow_system *s) {
    for (uint32_t p = 0; p < s->P; ++p) {
        const glow_system *nb = s->nbr[s->proxies[p].dependency];
        if (nb) /* Y Co Cg: the fourth float stays 0 (the neighbour's may hold its node's u_x u_y) */
            memcpy(s->rad + 4 * ((size_t)s->N + p), nb->rad + 4 * (size_t)s->proxies[p].node, 3 * sizeof(float));
    }
}

glow_result glow_system_set_neighbour(glow_system *s, uint32_t dependency, glow_system *nb) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    if (busy(s, "glow_system_set_neighbour")) return GLOW_ERROR_INVALID_OPERATION;
    if (dependency >= s->deps) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_system_set_neighbour(%s): dependency %u out of range (its bake has %u)", s->label,
                        dependency, s->deps);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (nb) {
        glow_bake_info bi;
        glow_bake_get_info(nb->bake, &bi);
        uint64_t want;
        memcpy(&want, s->dep_keys + dependency, sizeof want);
        if (nb == s || bi.system_key != want) {
            GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                            "glow_system_set_neighbour(%s): dependency %u is the system with key %016llx; %s has key "
                            "%016llx (a bake from another world or an older bake of it)",
                            s->label, dependency, (unsigned long long)want, nb->label, (unsigned long long)bi.system_key);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
        if (s->dep_max_node[dependency] > nb->N) { /* the key matched, so only a forged bake gets here */
            GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_OUT_OF_RANGE,
                            "glow_system_set_neighbour(%s): its proxies read node %u of %s, which has %u nodes",
                            s->label, s->dep_max_node[dependency] - 1u, nb->label, nb->N);
            return GLOW_ERROR_OUT_OF_RANGE;
        }
        atomic_fetch_add(&nb->attached, 1u);
    }
    if (s->nbr[dependency]) atomic_fetch_sub(&s->nbr[dependency]->attached, 1u);
    s->nbr[dependency] = nb;
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------ inputs */
static glow_result check_range(glow_system *s, const char *fn, uint32_t first, uint32_t count, const void *p,
                               bool p_required) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    if (busy(s, fn)) return GLOW_ERROR_INVALID_OPERATION;
    if ((p_required && !p) || first > s->S || count > s->S - first) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT, "%s(%s): surfels [%u, %u + %u) outside [0, %u) or NULL data",
                        fn, s->label, first, first, count, s->S);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    return GLOW_OK;
}

/* Checks 3*count values; NaN/Inf -> GLOW_ERROR_HOST_CALLBACK (nothing stored), else copies with
 * negatives clamped to 0. */
static glow_result store_checked(glow_system *s, const char *fn, float *dst, const float *src, uint32_t first,
                                 uint32_t count) {
    for (size_t i = 0; i < 3 * (size_t)count; ++i)
        if (!isfinite(src[i]) || src[i] > GLOW_MAX_IRRADIANCE) {
            GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_HOST_CALLBACK,
                            "%s(%s): surfel %u has a non-finite value or one above GLOW_MAX_IRRADIANCE (%g); nothing stored",
                            fn, s->label, first + (uint32_t)(i / 3), (double)src[i]);
            return GLOW_ERROR_HOST_CALLBACK;
        }
    uint32_t neg = 0;
    for (size_t i = 0; i < 3 * (size_t)count; ++i) {
        float v = src[i];
        if (v < 0.0f) {
            v = 0.0f;
            neg++;
        }
        dst[3 * (size_t)first + i] = v;
    }
    if (neg)
        GLOW__LOG_WARNING(s->ctx, GLOW_ERROR_HOST_CALLBACK, "%s(%s): %u negative value(s) clamped to 0", fn, s->label, neg);
    return GLOW_OK;
}

glow_result glow_system_set_surfel_irradiance(glow_system *s, uint32_t first, uint32_t count, const float *rgb) {
    glow_result r = check_range(s, "glow_system_set_surfel_irradiance", first, count, rgb, true);
    if (r != GLOW_OK) return r;
    r = store_checked(s, "glow_system_set_surfel_irradiance", s->direct, rgb, first, count);
    if (r == GLOW_OK) s->direct_revision++;
    return r;
}

glow_result glow_system_set_surfel_emission(glow_system *s, uint32_t first, uint32_t count, const float *rgb) {
    glow_result r = check_range(s, "glow_system_set_surfel_emission", first, count, rgb, false);
    if (r != GLOW_OK) return r;
    if (!rgb) {
        memcpy(s->emis + 3 * (size_t)first, s->emis_base + 3 * (size_t)first, 3 * (size_t)count * sizeof(float));
        s->emission_revision++;
        return GLOW_OK;
    }
    r = store_checked(s, "glow_system_set_surfel_emission", s->emis, rgb, first, count);
    if (r == GLOW_OK) s->emission_revision++;
    return r;
}

/* Bilinear, wrapped, rows from the top: v = 1 is row 0 (the linker's and the samples' convention). */
static void sample_rgb(const float *rgb, uint32_t w, uint32_t h, float u, float v, float out[3]) {
    u -= floorf(u);
    v -= floorf(v);
    const float x = u * (float)w - 0.5f, y = (1.0f - v) * (float)h - 0.5f;
    const float fx0 = floorf(x), fy0 = floorf(y), fx = x - fx0, fy = y - fy0;
    int64_t x0 = (int64_t)fx0 % (int64_t)w, y0 = (int64_t)fy0 % (int64_t)h;
    if (x0 < 0) x0 += w;
    if (y0 < 0) y0 += h;
    const int64_t x1 = x0 + 1 == (int64_t)w ? 0 : x0 + 1, y1 = y0 + 1 == (int64_t)h ? 0 : y0 + 1;
    const float *a = rgb + 3 * ((size_t)y0 * w + (size_t)x0), *b = rgb + 3 * ((size_t)y0 * w + (size_t)x1);
    const float *c = rgb + 3 * ((size_t)y1 * w + (size_t)x0), *d = rgb + 3 * ((size_t)y1 * w + (size_t)x1);
    for (int k = 0; k < 3; ++k) {
        const float top = a[k] + (b[k] - a[k]) * fx, bottom = c[k] + (d[k] - c[k]) * fx;
        out[k] = top + (bottom - top) * fy;
    }
}

glow_result glow_system_set_emission_texture(glow_system *s, uint32_t material, const float *rgb, uint32_t width,
                                             uint32_t height, float scale) {
    const char *fn = "glow_system_set_emission_texture";
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    if (busy(s, fn)) return GLOW_ERROR_INVALID_OPERATION;
    if (material >= s->M || (rgb && (width == 0 || height == 0)) || !(scale >= 0.0f) || !isfinite(scale)) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "%s(%s): material %u (of %u), a %ux%u texture and scale %g: the material must exist, the "
                        "texture be at least 1x1 and the scale finite and >= 0",
                        fn, s->label, material, s->M, width, height, (double)scale);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!s->uv0) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_UNSUPPORTED,
                        "%s(%s): the bake has no material UVs (bake format 1.1 with a textured mesh)", fn, s->label);
        return GLOW_ERROR_UNSUPPORTED;
    }
    if (rgb) /* check every value this call would store before storing any */
        for (uint32_t i = 0; i < s->S; ++i) {
            if (s->mat[i] != material) continue;
            float e[3];
            sample_rgb(rgb, width, height, s->uv0[2 * (size_t)i], s->uv0[2 * (size_t)i + 1], e);
            for (int k = 0; k < 3; ++k)
                if (!isfinite(e[k] * scale) || e[k] * scale > GLOW_MAX_IRRADIANCE) {
                    GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_HOST_CALLBACK,
                                    "%s(%s): surfel %u samples a non-finite value or one above GLOW_MAX_IRRADIANCE; nothing "
                                    "stored",
                                    fn, s->label, i);
                    return GLOW_ERROR_HOST_CALLBACK;
                }
        }
    for (uint32_t i = 0; i < s->S; ++i) {
        if (s->mat[i] != material) continue;
        float *e = s->emis + 3 * (size_t)i;
        if (!rgb) {
            memcpy(e, s->emis_base + 3 * (size_t)i, 3 * sizeof(float));
            continue;
        }
        sample_rgb(rgb, width, height, s->uv0[2 * (size_t)i], s->uv0[2 * (size_t)i + 1], e);
        for (int k = 0; k < 3; ++k) e[k] = e[k] > 0.0f ? e[k] * scale : 0.0f;
    }
    s->emission_revision++;
    return GLOW_OK;
}

static glow_result null_arg(const glow_system *s, const char *fn) {
    if (s) GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT, "%s(%s): NULL argument", fn, s->label);
    return GLOW_ERROR_INVALID_ARGUMENT;
}

glow_result glow_system_get_surfels(const glow_system *s, glow_surfel_view *v) {
    if (!s || !v) return null_arg(s, "glow_system_get_surfels");
    *v = (glow_surfel_view){.count = s->S, .positions = s->pos4, .normals = s->nrm4, .materials = s->mat, .triangles = s->tri,
                            .uv0 = s->uv0};
    return GLOW_OK;
}

glow_result glow_system_set_params(glow_system *s, const glow_system_params *p) {
    if (!s || !p) return null_arg(s, "glow_system_set_params");
    if (busy(s, "glow_system_set_params")) return GLOW_ERROR_INVALID_OPERATION;
    if (!(p->bounce_intensity >= 0.0f) || !isfinite(p->bounce_intensity) || !(p->emission_scale >= 0.0f) ||
        !(p->emission_scale <= GLOW_MAX_SCALE) || p->bounce_iterations > MAX_ITERATIONS) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_system_set_params(%s): bounce_intensity %g must be finite and >= 0, emission_scale %g "
                        "in [0, GLOW_MAX_SCALE], bounce_iterations %u in [0 (= 1), %u]",
                        s->label, (double)p->bounce_intensity, (double)p->emission_scale, p->bounce_iterations,
                        MAX_ITERATIONS);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    s->params = *p;
    s->params_revision++;
    if (s->params.bounce_intensity > 1.0f) s->params.bounce_intensity = 1.0f;
    if (s->params.bounce_iterations == 0) s->params.bounce_iterations = 1; /* zero is the default */
    return GLOW_OK;
}

glow_result glow_system_set_sky(glow_system *s, const float sh_rgb[GLOW_SKY_SH_FLOATS]) {
    if (!s) return null_arg(s, "glow_system_set_sky");
    if (busy(s, "glow_system_set_sky")) return GLOW_ERROR_INVALID_OPERATION;
    if (!sh_rgb) {
        s->sky_revision += s->sky_on;
        s->sky_on = false;
        return GLOW_OK;
    }
    if (!s->sky_V) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_UNSUPPORTED,
                        "glow_system_set_sky(%s): the bake carries no sky visibility of its grid caches (format 1.6 "
                        "SKYT; baked with --no-sky, before 1.6, or without a grid)", s->label);
        return GLOW_ERROR_UNSUPPORTED;
    }
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k)
        if (!isfinite(sh_rgb[k]) || fabsf(sh_rgb[k]) > GLOW_MAX_IRRADIANCE) {
            GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                            "glow_system_set_sky(%s): coefficient %d channel %d (%g) is not finite or beyond %g", s->label,
                            k / 3, k % 3, (double)sh_rgb[k], (double)GLOW_MAX_IRRADIANCE);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    const uint32_t G = s->meta->grid_cache_count;
    if (!s->sky_grid) { /* once: a system that never gets a sky holds none */
        bool ok = true;
        s->sky_grid = alloc_array(s, G, (size_t)s->coeffs * sizeof(float), &ok);
        s->sky_backup = alloc_array(s, G, (size_t)s->coeffs * sizeof(float), &ok);
        if (!ok) {
            glow__ctx_free(s->ctx, s->sky_grid);
            glow__ctx_free(s->ctx, s->sky_backup);
            s->sky_grid = s->sky_backup = NULL;
            GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_OUT_OF_MEMORY, "glow_system_set_sky(%s): out of memory for %u grid caches",
                            s->label, G);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
    }
    glow_sky_grid_rows(s->sky_V, G, sh_rgb, s->luma, s->chroma, s->sky_grid);
    s->sky_on = true;
    s->sky_revision++;
    return GLOW_OK;
}

glow_result glow_system_get_params(const glow_system *s, glow_system_params *p) {
    if (!s || !p) return null_arg(s, "glow_system_get_params");
    *p = s->params;
    return GLOW_OK;
}

glow_result glow_system_set_material(glow_system *s, uint32_t material, const float emission_scale[3],
                                     const float albedo_scale[3]) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    if (busy(s, "glow_system_set_material")) return GLOW_ERROR_INVALID_OPERATION;
    if (material >= s->M) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_system_set_material(%s): material %u >= material_count %u",
                        s->label, material, s->M);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    for (int c = 0; c < 3; ++c)
        if ((emission_scale && !(emission_scale[c] >= 0.0f && emission_scale[c] <= GLOW_MAX_SCALE)) ||
            (albedo_scale && !(albedo_scale[c] >= 0.0f && albedo_scale[c] <= GLOW_MAX_SCALE))) {
            GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                            "glow_system_set_material(%s): material %u: scales must be in [0, GLOW_MAX_SCALE]", s->label,
                            material);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    if (emission_scale) memcpy(s->mat_emis_scale + 3 * (size_t)material, emission_scale, 3 * sizeof(float));
    if (albedo_scale) memcpy(s->mat_albedo_scale + 3 * (size_t)material, albedo_scale, 3 * sizeof(float));
    if (emission_scale || albedo_scale) s->material_revision++;
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------ update */
static void pull(glow_system *s) {
    for (uint32_t lv = 1; lv < s->levels; ++lv) {
        uint32_t first = s->level_starts[lv], end = s->level_starts[lv + 1];
        if (end - first >= 2u * NODE_CHUNK) { /* wide levels in parallel; the narrow top serially */
            s->pull_first = first;
            s->pull_count = end - first;
            glow__ctx_run(s->ctx, task_pull, s, div_up(end - first, NODE_CHUNK));
        } else {
            pull_range(s, first, end);
        }
    }
    if (s->sub_count && !s->gradient) /* link gradients: u in the pull (pull_nodes) */
        glow__ctx_run(s->ctx, task_sub_ratio, s, div_up(s->sub_count, NODE_CHUNK));
}

static glow_result system_update(glow_system *s, const glow_update_desc *desc);

glow_result glow_system_update(glow_system *s, const glow_update_desc *desc) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    if (atomic_exchange(&s->updating, 1)) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_OPERATION,
                        "glow_system_update(%s): called while an update of this system runs (from its own lighting "
                        "hook, or from another thread); refused",
                        s->label);
        return GLOW_ERROR_INVALID_OPERATION;
    }
    glow_result r = system_update(s, desc);
    atomic_store(&s->updating, 0);
    return r;
}

static int cmp_u64(const void *a, const void *b) {
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}
static int cmp_u32(const void *a, const void *b) {
    const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

void glow_sky_grid_rows(const float *visibility, uint32_t grid_caches, const float sh_rgb[GLOW_SKY_SH_FLOATS],
                        uint32_t luma_bands, uint32_t chroma_bands, float *out_rows) {
    const uint32_t L2 = luma_bands * luma_bands, C2 = chroma_bands * chroma_bands, nc = L2 + 2u * C2;
    for (uint32_t c = 0; c < grid_caches; ++c) {
        float vis[GLOW_SKY_SH_FLOATS], *row = out_rows + (size_t)c * nc;
        glow_sh_sky_visible(visibility + 9 * (size_t)c, sh_rgb, vis);
        memset(row, 0, nc * sizeof *row);
        for (uint32_t k = 0; k < 9; ++k) {
            float ycc[3];
            glow_rgb_to_ycocg(vis + 3 * k, ycc);
            if (k < L2) row[k] = ycc[0];
            if (k < C2) {
                row[L2 + k] = ycc[1];
                row[L2 + C2 + k] = ycc[2];
            }
        }
    }
}

/* The candidates of a budget (groups of caches, or the hook's batches) by priority, into `out` as
 * (~priority bits) << 32 | index: ascending = first. Returns how many (those not skipped). */
static uint32_t budget_keys(const float *centre, const uint32_t *age, const uint8_t *skip, uint32_t groups,
                            const float *focus, uint32_t focus_count, float focus_radius, uint64_t *out) {
    const float inv_r2 = focus_radius > 0.0f ? 1.0f / (focus_radius * focus_radius) : 0.0f;
    uint32_t n = 0;
    for (uint32_t g = 0; g < groups; ++g) {
        if (skip && skip[g]) continue;
        float f = 0.0f;
        for (uint32_t p = 0; p < focus_count; ++p) {
            const float *c = centre + 3 * (size_t)g, *q = focus + 3 * (size_t)p;
            const float dx = c[0] - q[0], dy = c[1] - q[1], dz = c[2] - q[2];
            const float w = 1.0f / (1.0f + (dx * dx + dy * dy + dz * dz) * inv_r2);
            if (w > f) f = w;
        }
        const float key = ((float)age[g] + 1.0f) * (1.0f + 4.0f * f); /* >= 1: its bits order as it does */
        uint32_t bits;
        memcpy(&bits, &key, sizeof bits);
        out[n++] = ((uint64_t)(0xFFFFFFFFu - bits) << 32) | g; /* highest priority, then lowest index, first */
    }
    return n;
}

uint32_t glow_budget_choose(const float *centre, uint32_t *age, const uint8_t *skip, uint32_t groups, const float *focus,
                            uint32_t focus_count, float focus_radius, uint32_t max_groups, uint64_t *scratch,
                            uint32_t *out_sel) {
    if (!centre || !age || !scratch || !out_sel || (focus_count && !focus)) return 0;
    const uint32_t n = budget_keys(centre, age, skip, groups, focus, focus_count, focus_radius, scratch);
    const uint32_t k = max_groups < n ? max_groups : n;
    if (k < n) qsort(scratch, n, sizeof *scratch, cmp_u64);
    for (uint32_t i = 0; i < k; ++i) out_sel[i] = (uint32_t)(scratch[i] & 0xFFFFFFFFu);
    qsort(out_sel, k, sizeof *out_sel, cmp_u32); /* memory order for the gather */
    for (uint32_t g = 0; g < groups; ++g) age[g]++;
    for (uint32_t i = 0; i < k; ++i) age[out_sel[i]] = 0;
    return k;
}

/* A system's first budgeted update (no gather cost known yet) gathers an eighth of its groups, at
 * least 32 (or all, when fewer): enough to measure. */
static uint32_t teach_groups(const glow_system *s) {
    return s->groups / 8u > 32u ? s->groups / 8u : (s->groups < 32u ? s->groups : 32u);
}

/* The gather's cost under a time budget (glow_budget_cost, glow_backend.h). Every budgeted update
 * that gathered teaches it, from its wall time and the groups' own times (task_caches_sel): a group's
 * time is their sum over k, the dispatch what the wall time has beyond that sum spread over the
 * workers. Before 2026-11-30 one figure, the wall time over k, was learnt, and only from selections of
 * at least teach_groups (from a few groups it is mostly the workers' wake-up: 66 ns a link for one
 * group of Sponza moderate against 3.8 for all, and learning it would shrink the next selection and
 * collapse the budget). Once that figure was high (a cold first sample), a system chose fewer groups
 * than teach_groups and never learnt again: on the 4x4 Sponza level under 2 ms, with a still camera,
 * the system beside it kept 0.042-0.051 ms a group against the others' 0.004-0.006, gathered 17-21
 * groups a turn against their 95-160, and some runs ended 2-17 % off the unbudgeted solver near the
 * camera. A few groups cost more each than many (the first touches of the node radiance they share),
 * so as an estimate for any selection their time per group is an upper bound: a sample teaches fully
 * downwards, and upwards in proportion to k / teach (all from teach groups on). A sample above twice
 * the estimate counts as twice (a descheduled worker). */
void glow_budget_cost_learn(glow_budget_cost *c, uint32_t k, uint32_t teach, uint32_t workers, uint32_t iters,
                            double wall_ms, double busy_ms) {
    const uint32_t par = workers ? (k < workers ? k : workers) : 1u;
    if (!c || !k || !iters || !(wall_ms > 0.0) || !(busy_ms > 0.0) || !isfinite(wall_ms) || !isfinite(busy_ms)) return;
    const double group = busy_ms / iters / k, dispatch = fmax(wall_ms / iters - busy_ms / iters / par, 0.0);
    if (!(c->group_ms > 0.0)) {
        c->group_ms = group;
        c->dispatch_ms = dispatch;
        return;
    }
    const double up = 0.2 * fmin(1.0, (double)k / (teach ? teach : 1u));
    const double ag = group < c->group_ms ? 0.2 : up, ad = dispatch < c->dispatch_ms ? 0.2 : up;
    c->group_ms = (1.0 - ag) * c->group_ms + ag * fmin(group, 2.0 * c->group_ms);
    c->dispatch_ms = (1.0 - ad) * c->dispatch_ms + ad * fmin(dispatch, 2.0 * c->dispatch_ms + 0.01);
}

uint32_t glow_budget_cost_fit(const glow_budget_cost *c, double ms, uint32_t workers, uint32_t iters) {
    if (!c) return 1u;
    const double it_ms = ms / (iters ? iters : 1u) - c->dispatch_ms;
    const double k = it_ms > 0.0 && c->group_ms > 0.0 ? floor(it_ms * (workers ? workers : 1u) / c->group_ms) : 0.0;
    return k < 1.0 ? 1u : (k > 4e9 ? 4000000000u : (uint32_t)k); /* always some progress */
}

/* Chooses the groups this update gathers (s->grp_sel[0..sel_count), in index order). No allocation. */
static void schedule(glow_system *s, const glow_update_desc *d, glow_update_stats *st) {
    const uint32_t G = s->groups;
    /* the input drift: relative L1 change of the node luma since the last update */
    double dn = 0.0, dv = 0.0;
    for (uint32_t n = 0; n < s->N + s->P; ++n) { /* the proxies too: a neighbour's light changes the caches */
        const float y = s->rad[4 * (size_t)n];
        dn += fabs((double)y - s->rad_prev[n]);
        dv += fabs((double)y);
        s->rad_prev[n] = y;
    }
    s->drift += dv > 0.0 ? dn / dv : (dn > 0.0 ? 1.0 : 0.0);
    const double eps = d->converged_epsilon;
    const float r = d->focus_radius > 0.0f ? d->focus_radius : 0.1f * s->scene_diag;
    uint32_t n = 0;
    for (uint32_t g = 0; g < G; ++g) {
        s->grp_skip[g] = eps > 0.0 && s->grp_delta[g] < eps && s->drift - s->grp_drift_at[g] < eps; /* converged */
        n += !s->grp_skip[g];
    }
    uint32_t k = n;
    if (d->max_caches) {
        const uint32_t kc = div_up(d->max_caches, GLOW_BUDGET_GROUP);
        if (kc < k) k = kc;
    }
    if (d->budget_ms > 0.0f && !(s->gather_cost.group_ms > 0.0)) {
        /* No cost per group yet (the system's first budgeted update, e.g. just streamed into a world):
         * the fewest groups that teach it (teach_groups), not all of them. Gathering every cache here
         * made a system streamed in under a 2 ms budget cost 2.4-3.4 ms (half-tile systems of the 4x4
         * Sponza level, 5,500 caches: 1.1-1.8 ms of gathers). */
        if (teach_groups(s) < k) k = teach_groups(s);
    } else if (d->budget_ms > 0.0f) {
        const double left = (double)d->budget_ms - (s->ema_other_ms > 0.0 ? s->ema_other_ms : s->first_other_ms) -
                            s->hook_ms; /* the hook has run: its time this update */
        const uint32_t kt = glow_budget_cost_fit(&s->gather_cost, left, glow__ctx_workers(s->ctx),
                                                  s->params.bounce_iterations);
        if (kt < k) k = kt;
    }
    k = glow_budget_choose(s->grp_centre, s->grp_age, s->grp_skip, G, d->focus, d->focus_count, r, k, s->grp_pack,
                           s->grp_sel);
    s->sel_count = k;
    for (uint32_t i = 0; i < k; ++i) s->grp_drift_at[s->grp_sel[i]] = s->drift;
    uint32_t gathered = 0;
    for (uint32_t i = 0; i < k; ++i) {
        const uint32_t first = s->grp_sel[i] * GLOW_BUDGET_GROUP;
        gathered += s->C - first < GLOW_BUDGET_GROUP ? s->C - first : GLOW_BUDGET_GROUP;
    }
    uint32_t conv_caches = 0;
    for (uint32_t g = 0; g < G && eps > 0.0; ++g)
        if (s->grp_delta[g] < eps && s->drift - s->grp_drift_at[g] < eps && s->grp_age[g] > 0) {
            const uint32_t first = g * GLOW_BUDGET_GROUP;
            conv_caches += s->C - first < GLOW_BUDGET_GROUP ? s->C - first : GLOW_BUDGET_GROUP;
        }
    st->caches_gathered = gathered;
    st->caches_skipped_converged = conv_caches;
    st->caches_skipped_budget = s->C - gathered - conv_caches;
}

/* The host's hook under a time budget (budget_ms): fewer batches than one a worker would leave workers
 * idle, so at least that many (or all). */
static uint32_t hook_min_batches(const glow_system *s) {
    const uint32_t w = glow__ctx_workers(s->ctx);
    return w < s->nbatches ? (w ? w : 1u) : s->nbatches;
}

/* The order in which this update's hook claims its batches (s->bat_sel) and its deadline. Without a
 * time budget, all, in index order, no deadline. With one, by priority (the stalest and those nearest
 * the focus first, as the groups of caches: budget_keys), and a batch starts only if it would end,
 * at the time it took when last lit, within half of what the budget leaves after the stages it
 * cannot cut (surfel flux, pull, outputs: the last updates' times), counted from the hook's start;
 * the first hook_min_batches always start. So the hook lights every surfel when that fits, and
 * otherwise the batches of highest priority that fit; the others keep their last direct light, and
 * the gathers get the rest. A deadline, not a count from estimated times: the host's cost varies by
 * batch (lit surfels trace rays, unlit ones do not: 0.016 to 0.25 ms a batch of 1,024 on the 4x4
 * Sponza level) and by update (a batch's time doubles when another system's loading has evicted the
 * host's scene from the caches), and choosing by the last times chose 17 batches for 0.6 ms that
 * took 2.1 ms. Before 2026-11-30 the hook always lit every surfel, and its time alone could exceed the
 * budget: the exact host, with 8 footprint points a surfel, took 1.5-2.2 ms of a half-tile system of
 * that level under a 2 ms budget. */
/* With `keep` (GLOW_UPDATE_FLAG_KEEP_LIGHTING) the candidates are the batches not current (bat_current)
 * only. Returns how many candidates (s->bat_sel[0..n)). */
static uint32_t order_batches(glow_system *s, const glow_update_desc *d, bool keep) {
    const uint32_t B = s->nbatches, kmin = hook_min_batches(s);
    atomic_store_explicit(&s->bat_next, 0u, memory_order_relaxed);
    s->bat_deadline = 0.0;
    s->bat_min = B;
    if (!(d->budget_ms > 0.0f) || B <= kmin || s->hook_uncut) {
        uint32_t n = 0;
        for (uint32_t b = 0; b < B; ++b)
            if (!keep || !s->bat_current[b]) s->bat_sel[n++] = b;
        return n;
    }
    double sum = 0.0;
    uint32_t seen = 0;
    for (uint32_t b = 0; b < B; ++b)
        if (s->bat_ms[b] >= 0.0f) {
            sum += s->bat_ms[b];
            ++seen;
        }
    s->bat_mean_ms = seen ? (float)(sum / seen) : 0.0f;
    const float r = d->focus_radius > 0.0f ? d->focus_radius : 0.1f * s->scene_diag;
    const uint32_t n = budget_keys(s->bat_centre, s->bat_age, keep ? s->bat_current : NULL, B, d->focus,
                                   d->focus_count, r, s->bat_pack);
    qsort(s->bat_pack, n, sizeof *s->bat_pack, cmp_u64);
    for (uint32_t i = 0; i < n; ++i) s->bat_sel[i] = (uint32_t)(s->bat_pack[i] & 0xFFFFFFFFu);
    /* the other stages' time: until an update has measured it (a system just streamed in), half the
     * budget, a guess (the 4x4 level's half-tile systems: 0.9-1.2 ms of a 2 ms budget in their first) */
    double other = s->ema_other_ms > 0.0 ? s->ema_other_ms : s->first_other_ms;
    if (!(other > 0.0)) other = 0.5 * (double)d->budget_ms;
    const double half = 0.5 * ((double)d->budget_ms - other);
    s->bat_min = kmin;
    s->bat_deadline = now_ms() + (half > 0.0 ? half : 0.0);
    return n;
}

double glow__system_uncut_ms(const glow_system *s) {
    const glow_update_stats *st = &s->stats;
    double ms = st->total_ms - st->cache_lighting_ms;
    if (s->bat_count > 0) /* the hook's cut: all but its fewest batches */
        ms -= s->hook_ms * (1.0 - fmin(1.0, (double)hook_min_batches(s) / (double)s->bat_count));
    return ms;
}

static glow_result system_update(glow_system *s, const glow_update_desc *desc) {
    const uint32_t flags = desc ? desc->flags : 0u;
    if (flags & ~(GLOW_UPDATE_FLAG_RESET_BOUNCE | GLOW_UPDATE_FLAG_KEEP_LIGHTING)) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_system_update(%s): unknown flags 0x%x", s->label,
                        flags);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const glow_update_desc none = {0};
    const glow_update_desc *d = desc ? desc : &none;
    if (!(d->budget_ms >= 0.0f) || !isfinite(d->budget_ms) || !(d->focus_radius >= 0.0f) || !isfinite(d->focus_radius) ||
        !(d->converged_epsilon >= 0.0f) || !isfinite(d->converged_epsilon) || (d->focus_count && !d->focus)) {
        GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_system_update(%s): budget_ms %g, focus_radius %g and converged_epsilon %g must be finite "
                        "and >= 0, and focus_count %u needs focus points",
                        s->label, (double)d->budget_ms, (double)d->focus_radius, (double)d->converged_epsilon,
                        d->focus_count);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    for (uint32_t i = 0; i < 3 * d->focus_count; ++i)
        if (!isfinite(d->focus[i])) {
            GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_system_update(%s): focus point %u is not finite",
                            s->label, i / 3);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    const bool budgeted = d->max_caches || d->budget_ms > 0.0f || d->converged_epsilon > 0.0f;
    glow_update_stats st = s->stats;
    st.surfel_lighting_ms = st.host_ms = st.pull_ms = st.cache_lighting_ms = st.output_ms = 0.0;
    st.links = 0;
    const double t_begin = now_ms();

    /* 1. direct light from the host, into the spare buffer, checked before it is used; under a time
     * budget maybe only some batches (order_batches), the others keeping their last light */
    double hook_ms = 0.0;
    s->bat_count = 0;
    s->hook_skipped = 0;
    const bool keep = (flags & GLOW_UPDATE_FLAG_KEEP_LIGHTING) != 0;
    if (s->hooks.light_surfels && (!keep || s->bat_stale)) { /* KEEP_LIGHTING: the batches not current */
        const uint32_t B = s->nbatches;
        const double th = now_ms();
        const uint32_t n = order_batches(s, d, keep);
        glow__ctx_run(s->ctx, task_hook_sel, s, n);
        uint32_t neg = 0, k = 0;
        for (uint32_t i = 0; i < n; ++i) { /* the batches lit first, in claim order */
            const uint32_t b = s->bat_sel[i];
            if (s->batch_status[b] == ST_SKIPPED) {
                const uint32_t first = b * s->batch;
                s->hook_skipped += s->S - first < s->batch ? s->S - first : s->batch;
                continue;
            }
            s->bat_sel[k++] = b;
            if (s->batch_status[b] != ST_OK) {
                uint32_t first = b * s->batch;
                GLOW__LOG_ERROR(s->ctx, GLOW_ERROR_HOST_CALLBACK,
                                "glow_system_update(%s): light_surfels %s for surfels [%u, %u); the update was "
                                "abandoned and the previous outputs kept",
                                s->label, s->batch_status[b] == ST_HOOK_FAILED ? "failed"
                                                                        : "returned NaN/Inf or a value above "
                                                                          "GLOW_MAX_IRRADIANCE",
                                first, first + (s->S - first < s->batch ? s->S - first : s->batch));
                return GLOW_ERROR_HOST_CALLBACK;
            }
            neg += s->batch_negative[b];
        }
        if (neg)
            GLOW__LOG_WARNING(s->ctx, GLOW_ERROR_HOST_CALLBACK,
                              "glow_system_update(%s): light_surfels returned %u negative value(s); clamped to 0",
                              s->label, neg);
        if (k == B) {
            float *t = s->direct;
            s->direct = s->direct_spare;
            s->direct_spare = t;
        } else { /* the batches lit; the others keep their last light */
            for (uint32_t i = 0; i < k; ++i) {
                const size_t first = (size_t)s->bat_sel[i] * s->batch;
                const size_t count = s->S - first < s->batch ? s->S - first : s->batch;
                memcpy(s->direct + 3 * first, s->direct_spare + 3 * first, 3 * count * sizeof(float));
            }
        }
        s->direct_revision++;
        for (uint32_t b = 0; b < B; ++b) s->bat_age[b]++;
        if (!keep) memset(s->bat_current, 0, B); /* the host's light may have changed */
        for (uint32_t i = 0; i < k; ++i) {
            s->bat_age[s->bat_sel[i]] = 0;
            s->bat_current[s->bat_sel[i]] = 1;
        }
        s->bat_stale = 0;
        for (uint32_t b = 0; b < B; ++b) s->bat_stale += !s->bat_current[b];
        s->bat_count = k;
        hook_ms = now_ms() - th;
    }
    s->hook_ms = hook_ms;
    if (s->sky_applied) { /* the grid caches' rows without the sky, bit for bit (set_sky) */
        memcpy(s->cache_sh, s->sky_backup, (size_t)s->meta->grid_cache_count * s->coeffs * sizeof(float));
        s->sky_applied = false;
    }
    if (flags & GLOW_UPDATE_FLAG_RESET_BOUNCE) {
        s->cache_revision++;
        memset(s->cache_sh, 0, (size_t)s->C * s->coeffs * sizeof(float));
        for (uint32_t g = 0; g < s->groups; ++g) s->grp_delta[g] = INFINITY; /* nothing is converged now */
    }
    double t = now_ms();
    st.surfel_lighting_ms += t - t_begin;
    st.host_ms = t - t_begin;

    double busy_ms = 0.0; /* the gathered groups' own times (glow_budget_cost_learn) */
    for (uint32_t it = 0; it < s->params.bounce_iterations; ++it) {
        double t0 = now_ms();
        /* Skip-if-unchanged: the surfel flux and the pull read the direct light, the emission, the
         * materials, the params and the caches (feedback). When none of them changed since they last
         * ran (GLOW_UPDATE_FLAG_KEEP_LIGHTING, and no cache gathered since: a still, converged scene),
         * their results are still in place, bit for bit. */
        const uint64_t key[5] = {s->direct_revision, s->emission_revision, s->material_revision, s->params_revision,
                                 s->cache_revision};
        const bool same = s->flux_valid && memcmp(key, s->flux_key, sizeof key) == 0;
        if (!same) glow__ctx_run(s->ctx, task_flux, s, div_up(s->S, SURFEL_CHUNK));
        double t1 = now_ms();
        if (!same) pull(s);
        memcpy(s->flux_key, key, sizeof key);
        s->flux_valid = true;
        fill_proxies(s);
        double ts = now_ms(); /* the schedule counts among the stages a budget cannot cut, not the gathers */
        if (budgeted && it == 0) schedule(s, d, &st); /* after the first pull: the drift of this update's light */
        double t2 = now_ms();
        if (!budgeted) {
            glow__ctx_run(s->ctx, task_caches, s, div_up(s->C, CACHE_CHUNK));
            s->cache_revision++;
        } else {
            glow__ctx_run(s->ctx, task_caches_sel, s, s->sel_count);
            for (uint32_t i = 0; i < s->sel_count; ++i) busy_ms += s->grp_busy[i];
            if (s->sel_count) s->cache_revision++;
        }
        double t3 = now_ms();
        st.surfel_lighting_ms += t1 - t0;
        st.pull_ms += ts - t1;
        st.cache_lighting_ms += t3 - t2;
        st.links += (uint64_t)(budgeted ? st.caches_gathered : s->C) * s->meta->links_per_cache;
    }
    if (!budgeted) {
        st.caches_gathered = s->C;
        st.caches_skipped_budget = st.caches_skipped_converged = 0;
    }
    double t4 = now_ms();
    if (s->sky_on) { /* the visible sky into the grid caches, after the bounce (it is not fed back) */
        const size_t n = (size_t)s->meta->grid_cache_count * s->coeffs;
        memcpy(s->sky_backup, s->cache_sh, n * sizeof(float));
        for (size_t i = 0; i < n; ++i) s->cache_sh[i] += s->sky_grid[i];
        s->sky_applied = true;
    }
    /* Skip-if-unchanged: the outputs are a function of the caches and the node radiance alone. A
     * budgeted update that gathered no cache (all converged) and whose node radiance is bit for bit
     * the last output's leaves them as they are (a still, converged scene: the output stage was 1.0 of
     * its 2.6 ms on Sponza moderate, the detail's included). */
    const size_t rad_bytes = (size_t)s->N * 4u * sizeof(float);
    st.outputs_skipped = budgeted && s->sel_count == 0 && s->out_written && !(flags & GLOW_UPDATE_FLAG_RESET_BOUNCE) &&
                         memcmp(s->rad, s->rad_out, rad_bytes) == 0 && s->sky_out_revision == s->sky_revision;
    /* Only the gathered groups' cells and texels when the planes hold the rest already: the last
     * outputs were a budgeted update's (out_written), from the same sky, and no reset since. Before
     * 2026-11-30 every budgeted update wrote whole planes: 0.71 of a 1.98 ms update on Sponza moderate
     * under a 2 ms budget that gathered 336 of its 9,818 caches. */
    const bool sel_out = budgeted && s->out_written && !(flags & GLOW_UPDATE_FLAG_RESET_BOUNCE) &&
                         s->sky_out_revision == s->sky_revision && !s->full_outputs;
    if (!st.outputs_skipped && sel_out) {
        glow__ctx_run(s->ctx, task_output_sel, s, s->sel_count + (s->det ? div_up(s->det->texel_count, DETAIL_CHUNK) : 0u));
        memcpy(s->rad_out, s->rad, rad_bytes);
    } else if (!st.outputs_skipped) {
        glow__ctx_run(s->ctx, task_output, s, output_tasks(s, NULL, NULL));
        /* only a budgeted update can skip, so only a budgeted one keeps the radiance it wrote with (a
         * megabyte on Sponza moderate: 1.0 MB copied per update was 0.05-0.1 ms); after an unbudgeted
         * one the next budgeted update writes its outputs (the same bytes, when nothing changed) */
        if (budgeted) memcpy(s->rad_out, s->rad, rad_bytes);
        s->out_written = budgeted;
        s->sky_out_revision = s->sky_revision;
    }
    double t5 = now_ms();
    st.output_ms = t5 - t4;
    st.total_ms = t5 - t_begin;
    st.updates++;
    st.surfels_skipped_budget = s->hook_skipped;
    if (budgeted) { /* recent times, for the next budget_ms: the other stages, and cache lighting per group */
        const double other = fmax(st.total_ms - st.cache_lighting_ms - hook_ms, 0.0);
        /* the system's first update pays first touches (the host's, the pages'): not a sample; later
         * outliers (a descheduled thread) count at most twice the average */
        if (st.updates > 1)
            s->ema_other_ms = s->ema_other_ms > 0.0 ? 0.8 * s->ema_other_ms + 0.2 * fmin(other, 2.0 * s->ema_other_ms) : other;
        else
            s->first_other_ms = other; /* an over-estimate until then: the second update keeps within the budget */
        glow_budget_cost_learn(&s->gather_cost, s->sel_count, teach_groups(s), glow__ctx_workers(s->ctx),
                                s->params.bounce_iterations, st.cache_lighting_ms, busy_ms);
    }
    s->stats = st;
    s->out.update_index = st.updates;
    return GLOW_OK;
}

glow_result glow_system_get_stats(const glow_system *s, glow_update_stats *out) {
    if (!s || !out) return null_arg(s, "glow_system_get_stats");
    *out = s->stats;
    out->memory_bytes = s->memory_bytes + sizeof *s;
    out->link_mode = (uint32_t)s->link_mode;
    out->kernel = glow__cl_isa_name(s->isa);
    return GLOW_OK;
}

const glow_cache_outputs *glow_system_outputs(const glow_system *s) { return s ? &s->out : NULL; }

glow_result glow_system_get_solver_tables(const glow_system *s, glow_solver_tables *t) {
    if (!s || !t) return null_arg(s, "glow_system_get_solver_tables");
    *t = (glow_solver_tables){.surfel_count = s->S,
                              .node_count = s->N,
                              .proxy_count = s->P,
                              .dependency_count = s->deps,
                              .proxy_pairs = (const uint32_t *)(const void *)s->proxies, /* {dependency, node}: 8 bytes */
                              .scene_diag = s->scene_diag,
                              .level_count = s->levels,
                              .cache_count = s->C,
                              .material_count = s->M,
                              .links_per_cache = s->meta->links_per_cache,
                              .link_blocks_per_cache = s->bpc,
                              .sh_bands_luma = s->luma,
                              .sh_bands_chroma = s->chroma,
                              .coeff_count = s->coeffs,
                              .surfel_area = s->meta->surfel_area,
                              .albedo = s->albedo,
                              .emission = s->emis,
                              .materials = s->mat,
                              .feedback = s->feedback,
                              .feedback_weights = s->fb_w,
                              .indirect_albedo_max = s->rho_ind_max,
                              .node_children = s->nodes[0].child,
                              .node_stride = (uint32_t)(sizeof(glow_bake_node) / sizeof(uint32_t)),
                              .node_inv_pi_area = s->inv_pi_area,
                              .node_positions = s->nodes[0].position,
                              .cache_positions = glow__bake_caches(s->bake)[0].position,
                              .cache_stride = (uint32_t)(sizeof(glow_bake_cache) / sizeof(float)),
                              .level_starts = s->level_starts,
                              .link_blocks = glow__bake_link_blocks(s->bake),
                              .link_subsets = s->gradient ? NULL : glow__bake_link_subsets(s->bake),
                              .link_kind = s->meta->link_kind,
                              .link_gradients = s->gradient ? s->subsets : NULL,
                              .gradient_node_count = s->gradient ? s->sub_count : 0u,
                              .gradient_nodes = s->gradient ? s->sub_nodes : NULL,
                              .gradient_cm = s->gradient ? s->grad_cm : NULL,
                              .output_index = s->out_index,
                              .output_cache = s->out_cache,
                              .grid_used = (uint32_t)s->grid_used,
                              .lightmap_used = (uint32_t)s->lm_used,
                              .material_emission_scale = s->mat_emis_scale,
                              .material_albedo_scale = s->mat_albedo_scale,
                              .emission_revision = s->emission_revision,
                              .material_revision = s->material_revision,
                              .direct_irradiance = s->direct,
                              .direct_revision = s->direct_revision,
                              .grid_cache_count = s->meta->grid_cache_count,
                              .sky_grid_visibility = s->sky_V};
    if (s->det) {
        t->detail_width = s->det->width;
        t->detail_height = s->det->height;
        t->detail_texels = s->det->texel_count;
        t->detail_links = s->det->link_count;
        t->detail_texel = s->det_texel;
        t->detail_first = s->det_first;
        t->detail_surfel = s->det_surfel;
        t->detail_weight = s->det_weight;
    }
    return GLOW_OK;
}
