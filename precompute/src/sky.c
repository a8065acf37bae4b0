/* sky.c — the sky transfer (bake section SKYT, format 1.6; docs/sky.md).
 *
 * Per leaf surfel (position p, unit normal n) the transfer vector of the cosine-weighted visible sky
 *     T_k = ∫ V(ω) max(0, n·ω) y_k(ω) dω,  k < 9 (real SH l <= 2, the runtime's glow_sh_eval)
 * and per grid cache the visibility SH
 *     V_k = ∫ V(ω) y_k(ω) dω
 * with V(ω) = 1 where a ray escapes the scene (every direction counts, also below the horizon, as the
 * CPU host's sky fraction S does). A host lights a surfel with a sky of radiance SH L by
 * max(0, Σ_k T_k L_k), for any rotation or change of the sky, without re-baking.
 *
 * The surfel rays are exactly the CPU host's (integration/hosts/cpu/host.c, trace_sky): the same
 * Hammersley set lifted onto the cosine lobe (make_sky_dirs), the same tangent frame (glow__onb of
 * host_math.h), the same origin (safe_origin: eps = 1e-4 of the scene's diagonal along n, then up to eps
 * along the surface towards the centre of the nearest triangle facing along n) and rays from t = 0 to
 * infinity. With cosine-distributed directions the estimate is T_k = π/N Σ_open y_k(ω), so for a
 * constant sky (L_0 = L √(4π), the rest 0) Σ T_k L_k = L π (open / N) = L π S: the host's constant sky,
 * ray for ray. Grid caches use M directions of a spherical Fibonacci set: V_k = 4π/M Σ_open y_k(ω).
 *
 * Threaded over surfels and caches with glow__parallel_for; every value depends only on its own rays,
 * so the result is the same for any thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pc_internal.h"
#include "bake_format.h"
#include "sky_rays.h"

/* the CPU host's cosine-distributed sky directions around +z (the seam: sky_rays.h) */
void glow__sky_dirs(uint32_t n, float (*dirs)[3]) { glow__seam_sky_dirs(n, &dirs[0][0]); }

typedef struct sky_job {
    const glow__rt *rt;
    const glow__surfels *sf;
    const glow__caches *ca;
    const float (*hemi)[3], (*sphere)[3];
    const uint32_t *order; /* the hemisphere's rays by azimuth: packets of 16 that look the same way */
    uint8_t *occ;          /* [worker][rays]: which rays of the surfel are blocked */
    uint32_t rays, grid_rays;
    float eps;
    float *surfel_out, *grid_out;
} sky_job;

/* host.c's safe_origin */
static void sky_origin(const sky_job *j, const float p[3], const float n[3], float o[3]) {
    for (int i = 0; i < 3; ++i) o[i] = p[i] + j->eps * n[i];
    float c[3];
    if (!glow__rt_nearest_facing(j->rt, p, n, 4.0f * j->eps, c)) return;
    float v[3];
    for (int i = 0; i < 3; ++i) v[i] = c[i] - p[i];
    const float vn = glow__dot(v, n);
    for (int i = 0; i < 3; ++i) v[i] -= vn * n[i];
    const float len = sqrtf(glow__dot(v, v));
    if (!(len > 1e-12f)) return;
    const float step = fminf(j->eps, 0.5f * len) / len;
    for (int i = 0; i < 3; ++i) o[i] += step * v[i];
}


static void surfel_range(void *user, uint32_t first, uint32_t end, uint32_t worker) {
    const sky_job *j = user;
    uint8_t *occ = j->occ + (size_t)worker * j->rays;
    for (uint32_t s = first; s < end; ++s) {
        const glow__surfel *sv = &j->sf->s[s];
        float tx[3], ty[3], o[3];
        double acc[GLOW_BAKE_SKY_COEFFS] = {0};
        glow__seam_onb(sv->nrm, tx, ty);
        sky_origin(j, sv->pos, sv->nrm, o);
        /* traced in packets of 16 neighbouring directions, summed in the rays' own order */
        for (uint32_t k0 = 0; k0 < j->rays; k0 += 16) {
            const uint32_t m = j->rays - k0 < 16 ? j->rays - k0 : 16;
            float d[16][3], tfar[16];
            uint8_t o16[16];
            for (uint32_t q = 0; q < m; ++q) {
                const float *h = j->hemi[j->order[k0 + q]];
                for (int i = 0; i < 3; ++i) d[q][i] = h[0] * tx[i] + h[1] * ty[i] + h[2] * sv->nrm[i];
                tfar[q] = INFINITY;
            }
            glow__rt_occluded16(j->rt, o, (const float(*)[3])d, tfar, m, 0.0f, o16);
            for (uint32_t q = 0; q < m; ++q) occ[j->order[k0 + q]] = o16[q];
        }
        for (uint32_t k = 0; k < j->rays; ++k) {
            if (occ[k]) continue;
            const float *h = j->hemi[k];
            float d[3], y[GLOW_BAKE_SKY_COEFFS];
            for (int i = 0; i < 3; ++i) d[i] = h[0] * tx[i] + h[1] * ty[i] + h[2] * sv->nrm[i];
            glow__sh_eval(3, d, y);
            for (uint32_t q = 0; q < GLOW_BAKE_SKY_COEFFS; ++q) acc[q] += y[q];
        }
        const double w = GLOW__PI / (double)j->rays;
        for (uint32_t q = 0; q < GLOW_BAKE_SKY_COEFFS; ++q)
            j->surfel_out[(size_t)s * GLOW_BAKE_SKY_COEFFS + q] = (float)(acc[q] * w);
    }
}

static void grid_range(void *user, uint32_t first, uint32_t end, uint32_t worker) {
    (void)worker;
    const sky_job *j = user;
    for (uint32_t c = first; c < end; ++c) {
        const float *o = j->ca->caches[c].pos;
        double acc[GLOW_BAKE_SKY_COEFFS] = {0};
        for (uint32_t k = 0; k < j->grid_rays; ++k) {
            float y[GLOW_BAKE_SKY_COEFFS];
            if (glow__rt_occluded(j->rt, o, j->sphere[k], j->eps, INFINITY)) continue;
            glow__sh_eval(3, j->sphere[k], y);
            for (uint32_t q = 0; q < GLOW_BAKE_SKY_COEFFS; ++q) acc[q] += y[q];
        }
        const double w = 4.0 * GLOW__PI / (double)j->grid_rays;
        for (uint32_t q = 0; q < GLOW_BAKE_SKY_COEFFS; ++q)
            j->grid_out[(size_t)c * GLOW_BAKE_SKY_COEFFS + q] = (float)(acc[q] * w);
    }
}

glow_result glow__sky_transfer(const glow__rt *rt, const glow__scene *sc, const glow__surfels *sf,
                               const glow__caches *ca, uint32_t rays, uint32_t grid_rays, glow__pool *pool,
                               float *out_surfel, float *out_grid) {
    if (!rt || !sc || !sf || !ca || !out_surfel || (ca->grid_cache_count && !out_grid) || rays == 0 || grid_rays == 0)
        return GLOW_ERROR_INVALID_ARGUMENT;
    float(*hemi)[3] = malloc((size_t)rays * sizeof *hemi), (*sphere)[3] = malloc((size_t)grid_rays * sizeof *sphere);
    uint32_t *order = malloc((size_t)rays * sizeof *order);
    uint64_t *keys = malloc((size_t)rays * sizeof *keys);
    uint8_t *occ = malloc((size_t)glow__pool_threads(pool) * rays);
    if (!hemi || !sphere || !order || !keys || !occ) {
        free(hemi);
        free(sphere);
        free(order);
        free(keys);
        free(occ);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    glow__sky_dirs(rays, hemi);
    glow__seam_sky_order(rays, keys, order); /* packets of 16 that look the same way */
    free(keys);
    glow__fibonacci_sphere(grid_rays, sphere);
    float ext[3];
    glow__sub(sc->bounds_max, sc->bounds_min, ext);
    float diag = sqrtf(glow__dot(ext, ext));
    if (!(diag > 0.0f)) diag = 1.0f;
    sky_job j = {.rt = rt, .sf = sf, .ca = ca, .hemi = (const float(*)[3])hemi, .sphere = (const float(*)[3])sphere,
 .order = order, .occ = occ, .rays = rays, .grid_rays = grid_rays, .eps = 1e-4f * diag, .surfel_out = out_surfel, .grid_out = out_grid};
    glow__parallel_for(pool, sf->count, 64, surfel_range, &j);
    if (ca->grid_cache_count) glow__parallel_for(pool, ca->grid_cache_count, 16, grid_range, &j);
    free(hemi);
    free(sphere);
    free(order);
    free(occ);
    return GLOW_OK;
}
