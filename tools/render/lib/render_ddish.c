/* render_ddish.c — DDISH-GI (Ikkala et al.; ../shared/seeds/ikkala-ddish-gi-*) as a comparator on
 * Glow's own caches (glow_render.h, "DDISH"; docs/ddish.md).
 *
 * Per frame, for every cache of the bake (grid points, lightmap texels): N rays of incident radiance
 * from the reference path tracer (glow__tracer_incoming: what Glow's caches hold), projected to Glow's
 * output SH (YCoCg, luma and chroma bands of the view's system) and blended into the history with
 * hysteresis α. The probe directions are N spherical-Fibonacci points (z stratified with a random
 * offset u, azimuth 2π frac(s / φ + v)) with (u, v) random per cache and frame: each direction is
 * uniform on the sphere (grid) or the hemisphere above the surface (lightmap caches), so the estimate
 * c_k = Σ_s L(ω_s) y_k(ω_s) · |Ω| / N is unbiased, and stratified.
 *
 * The view then reads these caches through a copy of the system's glow_cache_outputs whose SH arrays
 * are DDISH's (cache_sh and the grid and lightmap planes, scattered through grid_map / lightmap_map as
 * the runtime's output stage does), without the lightmap detail (Glow's own). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render_internal.h"

#define DDISH_PI 3.14159265358979323846f
#define DDISH_DEFAULT_RAYS 256u   /* the paper: 256 path-traced samples per probe per frame */
#define DDISH_DEFAULT_FRAMES 300u
#define DDISH_DEFAULT_ALPHA 0.99f /* the paper's hysteresis */
#define DDISH_DEFAULT_BOUNCES 32u /* the paper: 32 bounces, Russian roulette */

void glow_render_ddish_blend(float *history, const float *fresh, size_t count, float a) {
    const float b = 1.0f - a;
    for (size_t i = 0; i < count; ++i) history[i] = a * history[i] + b * fresh[i];
}

static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Orthonormal basis around unit n (Duff et al. 2017). */
static void basis(const float n[3], float t[3], float b[3]) {
    const float sign = copysignf(1.0f, n[2]);
    const float a = -1.0f / (sign + n[2]);
    const float c = n[0] * n[1] * a;
    t[0] = 1.0f + sign * n[0] * n[0] * a; t[1] = sign * c; t[2] = -sign * n[0];
    b[0] = c; b[1] = sign + n[1] * n[1] * a; b[2] = -n[1];
}

typedef struct ddish_job {
    const glow__tracer *tracer;
    const glow_cache_info *caches;
    float eps;
    uint32_t rays, luma2, chroma2, cc, bands;
    uint64_t seed;  /* this frame's */
    float alpha;    /* this frame's */
    bool cull;
    float *sh;      /* [cache][cc] history */
    uint64_t worker_rays[256];
} ddish_job;

static void ddish_range(void *ctx, uint32_t first, uint32_t end, uint32_t worker) {
    ddish_job *j = ctx;
    float y[GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS];
    float fresh[3 * GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS];
    uint64_t rays = 0;
    const float inv_phi = 0.61803398874989485f;
    for (uint32_t i = first; i < end; ++i) {
        const glow_cache_info *ci = &j->caches[i];
        const bool hemi = ci->kind == GLOW_CACHE_KIND_LIGHTMAP;
        float n[3] = {0.0f, 0.0f, 1.0f}, t[3] = {1.0f, 0.0f, 0.0f}, b[3] = {0.0f, 1.0f, 0.0f}, o[3];
        memcpy(o, ci->position, sizeof o);
        if (hemi) {
            const float l = sqrtf(ci->normal[0] * ci->normal[0] + ci->normal[1] * ci->normal[1] + ci->normal[2] * ci->normal[2]);
            if (l > 0.0f) {
                for (int k = 0; k < 3; ++k) n[k] = ci->normal[k] / l;
                basis(n, t, b);
            }
            for (int k = 0; k < 3; ++k) o[k] += j->eps * n[k];
        }
        glow__rng r;
        glow__rng_seed(&r, j->seed, i, 0);
        const float u = glow__rng_float(&r), v = glow__rng_float(&r);
        memset(fresh, 0, j->cc * sizeof *fresh);
        const float weight = (hemi ? 2.0f * DDISH_PI : 4.0f * DDISH_PI) / (float)j->rays; /* 1 / (pdf N) */
        for (uint32_t s = 0; s < j->rays; ++s) {
            const float f = ((float)s + u) / (float)j->rays;
            const float z = hemi ? 1.0f - f : 1.0f - 2.0f * f;
            const float rr = sqrtf(fmaxf(0.0f, 1.0f - z * z));
            float ph = (float)s * inv_phi + v;
            ph = 2.0f * DDISH_PI * (ph - floorf(ph));
            const float x = rr * cosf(ph), yy = rr * sinf(ph);
            float w[3];
            for (int k = 0; k < 3; ++k) w[k] = x * t[k] + yy * b[k] + z * n[k];
            const float wl = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            for (int k = 0; k < 3; ++k) w[k] /= wl;
            float L[3], c[3];
            glow__tracer_incoming(j->tracer, &r, o, w, j->cull, L, &rays);
            if (!(isfinite(L[0]) && isfinite(L[1]) && isfinite(L[2]))) continue; /* a bug upstream: left out */
            glow_rgb_to_ycocg(L, c);
            glow_sh_eval(j->bands, w, y);
            for (uint32_t k = 0; k < j->luma2; ++k) fresh[k] += weight * c[0] * y[k];
            for (uint32_t k = 0; k < j->chroma2; ++k) {
                fresh[j->luma2 + k] += weight * c[1] * y[k];
                fresh[j->luma2 + j->chroma2 + k] += weight * c[2] * y[k];
            }
        }
        glow_render_ddish_blend(j->sh + (size_t)i * j->cc, fresh, j->cc, j->alpha);
    }
    j->worker_rays[worker % 256] += rays;
}

/* The output planes from cache_sh, as the runtime's output stage lays them out: plane k of cell c
 * holds coefficient k of map[c]'s cache, 0 where the map is empty. */
typedef struct scatter_job {
    const float *sh;
    uint32_t cc;
    const uint32_t *map;
    size_t cells;
    float *planes;
} scatter_job;

static void scatter_range(void *ctx, uint32_t first, uint32_t end, uint32_t worker) {
    (void)worker;
    scatter_job *j = ctx;
    for (uint32_t k = first; k < end; ++k) {
        float *plane = j->planes + (size_t)k * j->cells;
        for (size_t c = 0; c < j->cells; ++c)
            plane[c] = j->map[c] == UINT32_MAX ? 0.0f : j->sh[(size_t)j->map[c] * j->cc + k];
    }
}

static bool same_mesh(const glow_render_scene *a, const glow_render_scene *b) {
    if (a->mesh.tri_count != b->mesh.tri_count) return false;
    return memcmp(a->mesh.pos, b->mesh.pos, (size_t)a->mesh.tri_count * 3 * sizeof a->mesh.pos[0]) == 0;
}

glow_result glow_render_ddish(const glow_render_scene *sc, const char *bake_path, const glow_render_settings *st,
                              const glow_render_glow_settings *gs, const glow_render_ddish_settings *ds,
                              glow_render_result *out, glow_render_ddish_stats *stats, char *message,
                              size_t message_size) {
    if (message && message_size) message[0] = 0;
    if (out) memset(out, 0, sizeof *out);
    if (stats) memset(stats, 0, sizeof *stats);
    if (!sc || !bake_path || !st || !ds || !out)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render_ddish: NULL argument");
    const uint32_t rays = ds->rays ? ds->rays : DDISH_DEFAULT_RAYS;
    const uint32_t frames = ds->frames ? ds->frames : DDISH_DEFAULT_FRAMES;
    const float alpha = ds->hysteresis_set ? ds->hysteresis : DDISH_DEFAULT_ALPHA;
    const uint32_t bounces = ds->bounces ? ds->bounces : DDISH_DEFAULT_BOUNCES;
    if (rays > 65536)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "ddish: %u rays per cache is above 65536", rays);
    if (frames > 1000000)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "ddish: %u frames is above 1000000", frames);
    if (!(alpha >= 0.0f && alpha < 1.0f))
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "ddish: hysteresis %g is outside [0, 1)", (double)alpha);
    if (bounces > 1024)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "ddish: %u bounces is above 1024", bounces);
    if (ds->moved && ds->move_frame >= frames)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "ddish: the light moves at frame %u but only %u frames run", ds->move_frame, frames);
    if (ds->moved && !same_mesh(sc, ds->moved))
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "ddish: %s and %s do not describe the same mesh (%s, %s): the light can move, the geometry not",
                                 sc->path, ds->moved->path, sc->desc.mesh, ds->moved->desc.mesh);
    glow_render_glow_settings g = gs ? *gs : (glow_render_glow_settings){0};
    g.bounce_iterations = 1; /* the system only provides the outputs' layout and maps */
    capture_log cl;
    memset(&cl, 0, sizeof cl);
    pthread_mutex_init(&cl.lock, NULL);
    glow_view gv;
    glow_result r = glow__view_create(sc, bake_path, st, &g, &cl, &gv, message, message_size);
    if (r != GLOW_OK) {
        pthread_mutex_destroy(&cl.lock);
        return r;
    }
    glow_cache_outputs o = *gv.out; /* the layout, maps and visibility of Glow's outputs; DDISH's SH */
    const uint32_t cc = o.coeff_count, n = o.cache_count;
    glow_cache_info *caches = malloc((size_t)(n ? n : 1) * sizeof *caches);
    float *sh = calloc((size_t)(n ? n : 1) * cc, sizeof *sh);
    const size_t grid_cells = o.grid_sh ? (size_t)o.grid_dims[0] * o.grid_dims[1] * o.grid_dims[2] : 0;
    const size_t lm_texels = o.lightmap_sh ? (size_t)o.lightmap_width * o.lightmap_height * o.lightmap_pages : 0;
    float *grid = grid_cells ? calloc(grid_cells * cc, sizeof *grid) : NULL;
    float *lm = lm_texels ? calloc(lm_texels * cc, sizeof *lm) : NULL;
    double *ms = calloc(frames, sizeof *ms);
    glow__tracer *tr[2] = {NULL, NULL};
    glow__pool *pool = NULL;
    glow_render_result view;
    memset(&view, 0, sizeof view);
#define FAIL(code, ...)                                                   \
    do {                                                                  \
        r = glow__render_fail(message, message_size, code, __VA_ARGS__); \
        goto done;                                                        \
    } while (0)
    if (!caches || !sh || (grid_cells && !grid) || (lm_texels && !lm) || !ms)
        FAIL(GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory for %u caches", bake_path, n);
    if (n == 0) FAIL(GLOW_ERROR_CORRUPT_DATA, "%s: the bake has no caches", bake_path);
    if ((r = glow_bake_get_caches(gv.bake, 0, n, caches)) != GLOW_OK)
        FAIL(r, "%s: cannot read the caches: %s", bake_path, glow_result_string(r));
    o.cache_sh = sh;
    o.grid_sh = grid;
    o.lightmap_sh = lm;
    o.detail_width = o.detail_height = 0;
    o.lightmap_detail = NULL;
    gv.out = &o;
    gv.no_detail = true;
    gv.grid_only = g.grid_only;
    gv.glossy = g.glossy;
    /* path vertices: the cache is 1, its ray's hit 2, so `bounces` bounces end at vertex bounces + 1 */
    if ((r = glow__tracer_create(sc, NULL, 0, st, bounces + 1, &tr[0], message, message_size)) != GLOW_OK) goto done;
    if (ds->moved && (r = glow__tracer_create(ds->moved, NULL, 0, st, bounces + 1, &tr[1], message, message_size)) != GLOW_OK)
        goto done;
    uint32_t threads = st->threads;
    pool = glow__pool_create(threads); /* 0 = one per online CPU, as glow-render; NULL: serial */
    threads = pool ? glow__pool_threads(pool) : 1u;
    const uint32_t luma = o.sh_bands_luma, chroma = o.sh_bands_chroma;
    ddish_job job = {.caches = caches, .eps = sc->eps, .rays = rays, .luma2 = luma * luma, .chroma2 = chroma * chroma,
                     .cc = cc, .bands = luma > chroma ? luma : chroma, .cull = !ds->no_cull, .sh = sh};
    scatter_job gj = {.sh = sh, .cc = cc, .map = o.grid_map, .cells = grid_cells, .planes = grid};
    scatter_job lj = {.sh = sh, .cc = cc, .map = o.lightmap_map, .cells = lm_texels, .planes = lm};
    uint64_t all_rays = 0;
    glow_render_settings vst = *st; /* the views the callback gets: indirect only */
    for (uint32_t f = 0; f < frames; ++f) {
        const bool moved = ds->moved && f >= ds->move_frame;
        job.tracer = tr[moved ? 1 : 0];
        uint64_t x = st->seed ^ (0xDD15Eull << 32);
        job.seed = x + 0x9E3779B97F4A7C15ull * (uint64_t)(f + 1);
        job.alpha = ds->ramp && (float)f / (float)(f + 1) < alpha ? (float)f / (float)(f + 1) : alpha;
        memset(job.worker_rays, 0, sizeof job.worker_rays);
        const double t0 = now_ms();
        glow__parallel_for(pool, n, 4, ddish_range, &job);
        if (grid_cells) glow__parallel_for(pool, cc, 1, scatter_range, &gj);
        if (lm_texels) glow__parallel_for(pool, cc, 1, scatter_range, &lj);
        ms[f] = now_ms() - t0;
        uint64_t fr = 0;
        for (int w = 0; w < 256; ++w) fr += job.worker_rays[w];
        all_rays += fr;
        glow_render_ddish_frame fi = {.frame = f, .moved = moved, .update_ms = ms[f], .rays = fr};
        const bool eval = ds->eval_every && ((f + 1) % ds->eval_every == 0 || f + 1 == frames);
        if (eval && ds->on_frame) {
            gv.indirect_only = true;
            if ((r = glow__view_render(moved ? ds->moved : sc, &vst, &gv, &view, message, message_size)) != GLOW_OK) goto done;
            fi.view = &view;
        }
        if (ds->on_frame && (r = ds->on_frame(ds->user, &fi)) != GLOW_OK)
            FAIL(r, "ddish: stopped at frame %u by the caller", f);
        glow_render_result_free(&view);
    }
    gv.indirect_only = g.indirect_only;
    {
        const bool moved = ds->moved != NULL;
        if ((r = glow__view_render(moved ? ds->moved : sc, st, &gv, out, message, message_size)) != GLOW_OK) goto done;
    }
    double total = 0.0;
    for (uint32_t f = 0; f < frames; ++f) total += ms[f];
    out->solve_seconds = total * 1e-3;
    if (stats) {
        stats->caches = n;
        stats->grid_caches = o.grid_cache_count;
        stats->lightmap_caches = o.lightmap_cache_count;
        stats->frames = frames;
        stats->coeff_count = cc;
        stats->rays = all_rays;
        stats->threads = threads;
        stats->mean_ms = total / frames;
        qsort(ms, frames, sizeof *ms, cmp_double);
        stats->min_ms = ms[0];
        stats->median_ms = frames % 2 ? ms[frames / 2] : 0.5 * (ms[frames / 2 - 1] + ms[frames / 2]);
    }
#undef FAIL
done:
    glow_render_result_free(&view);
    glow__pool_destroy(pool);
    glow__tracer_destroy(tr[0]);
    glow__tracer_destroy(tr[1]);
    gv.out = NULL;
    glow__view_free(&gv);
    pthread_mutex_destroy(&cl.lock);
    free(caches);
    free(sh);
    free(grid);
    free(lm);
    free(ms);
    if (r != GLOW_OK) glow_render_result_free(out);
    return r;
}
