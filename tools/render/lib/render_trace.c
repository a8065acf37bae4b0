/* render_trace.c — the reference path tracer and Glow's view of the same camera (glow_render.h has
 * the definitions: direct / indirect split, light model, sampling, determinism; docs/render.md).
 *
 * One function renders both: sample() computes the camera ray, the first hit and the direct term
 * (the same code and the same random numbers in both modes), then either continues the path
 * (reference) or reads Glow's caches at the first hit (glow view). Random numbers: per pixel, two
 * PCG32 streams seeded from hash(seed, pixel): stream 0 ("direct": pixel jitter, the first bounce
 * direction) and stream 1 ("path": everything after), so the direct image does not depend on the
 * mode and no pixel depends on the thread that renders it. */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "glow/glow_host.h"
#include "render_internal.h"

#define PI_F 3.14159265358979323846f
#define INV_PI_F 0.31830988618379067154f
#define DEFAULT_SPP 64u
#define DEFAULT_MAX_DEPTH 256u
#define DEFAULT_BOUNCES 192u
#define RR_START 3u /* Russian roulette from this path vertex on (1 = the camera's hit) */

/* ------------------------------------------------------------------------------------- random */
typedef glow__rng rng; /* render_internal.h: shared with render_ddish.c */

static inline uint32_t pcg32(rng *r) {
    uint64_t old = r->state;
    r->state = old * 6364136223846793005ull + r->inc;
    uint32_t xs = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xs >> rot) | (xs << ((32u - rot) & 31u));
}
static inline float rnd(rng *r) { return (float)(pcg32(r) >> 8) * 0x1p-24f; } /* [0, 1) */

static uint64_t splitmix64(uint64_t *x) {
    uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static void rng_init(rng *r, uint64_t seed, uint64_t pixel, uint32_t stream) {
    uint64_t x = seed;
    x = splitmix64(&x) ^ (2u * pixel + stream);
    r->state = splitmix64(&x);
    r->inc = (splitmix64(&x) << 1) | 1u;
    (void)pcg32(r);
}

void glow__rng_seed(glow__rng *r, uint64_t seed, uint64_t index, uint32_t stream) { rng_init(r, seed, index, stream); }
float glow__rng_float(glow__rng *r) { return rnd(r); }

/* ------------------------------------------------------------------------------------- vectors */
static inline void v_madd(float o[3], const float a[3], float s, const float b[3]) {
    for (int k = 0; k < 3; ++k) o[k] = a[k] + s * b[k];
}
static inline float v_norm(float v[3]) {
    float l = sqrtf(glow__dot(v, v));
    if (l > 0.0f)
        for (int k = 0; k < 3; ++k) v[k] /= l;
    return l;
}
/* ------------------------------------------------------------------------------------- setup */
typedef struct render_light {
    glow_scene_light l;
    float cos_outer, cos_inner;
} render_light;


typedef struct worker_stats {
    uint64_t rays, lm, grid, missed, nonfinite;
} worker_stats;

typedef struct render_ctx {
    const glow_render_scene *sc;
    uint32_t w, h, spp, max_depth, threads;
    uint64_t seed;
    float albedo_scale, emission_scale;
    bool emitters_on, env_on;
    float env[3];
    const glow_eval_envmap *map; /* the scene's environment_map (added to env), NULL without one */
    bool map_nee;                /* next-event estimation of the map + MIS (false: BSDF sampling only); its
                                    random numbers are drawn only when true, so scenes without a map keep
                                    their streams (and images) bit for bit */
    render_light *lights;
    uint32_t light_count;
    /* camera */
    float org[3], fwd[3], right[3], up[3], tan_y, tan_x;
    /* glow view (NULL = reference) */
    const glow_view *gv;
    /* accumulators: per pixel RGB */
    float *direct, *indirect;
    float *indirect_near; /* NULL unless settings->near_split > 0 (reference only) */
    float *texel;         /* glow view with a lightmap: glow_render_result.texel's pixels, else NULL */
    float *specular;      /* scenes with a GGX layer: glow_render_result.specular's pixels, else NULL */
    float near_split;
    /* scheduling */
    atomic_uint rows_done;
    pthread_mutex_t progress_lock;
    glow_render_progress_fn progress;
    void *progress_user;
    worker_stats *ws;
} render_ctx;

typedef struct surf {
    float p[3];     /* hit point */
    float o[3];     /* ray origin for rays leaving it: p + eps ng */
    float ng[3];    /* unit geometric normal, facing the arriving ray */
    float ns[3];    /* unit shading normal, facing the arriving ray (ng when it disagrees) */
    float rho[3];   /* albedo (texture, scale, clamp) */
    uint32_t tri;
    float b1, b2;   /* barycentrics of corners 1, 2 */
    bool back;      /* the ray arrived at the back face */
    glow__render_lobe lobe; /* the GGX layer (scene "materials"; docs/glossy.md); lobe.g NULL: Lambertian */
} surf;

static void make_surf(const render_ctx *c, const glow__hit *h, const float wdir[3], surf *s) {
    const glow__scene *m = &c->sc->mesh;
    const uint32_t t = h->tri;
    const float(*p)[3] = m->pos + 3 * (size_t)t;
    const float b1 = h->u, b2 = h->v, b0 = 1.0f - b1 - b2;
    for (int k = 0; k < 3; ++k) s->p[k] = p[0][k] + b1 * (p[1][k] - p[0][k]) + b2 * (p[2][k] - p[0][k]);
    const float(*n)[3] = m->nrm + 3 * (size_t)t;
    float ns[3];
    for (int k = 0; k < 3; ++k) ns[k] = b0 * n[0][k] + b1 * n[1][k] + b2 * n[2][k];
    const float *ng = c->sc->ng[t];
    const float sign = h->back_face ? -1.0f : 1.0f;
    for (int k = 0; k < 3; ++k) {
        s->ng[k] = sign * ng[k];
        ns[k] *= sign;
    }
    if (!(v_norm(ns) > 0.0f) || glow__dot(ns, s->ng) <= 0.0f) memcpy(ns, s->ng, sizeof ns);
    memcpy(s->ns, ns, sizeof ns);
    v_madd(s->o, s->p, c->sc->eps, s->ng);
    s->tri = t;
    s->b1 = b1;
    s->b2 = b2;
    s->back = h->back_face;
    const glow__material *mat = &m->materials[m->tri_material[t]];
    float tex[3] = {1.0f, 1.0f, 1.0f};
    if (mat->texture >= 0 && (uint32_t)mat->texture < m->texture_count && m->uv0) {
        const float(*uv)[2] = m->uv0 + 3 * (size_t)t;
        float u = b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0];
        float v = b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1];
        glow__texture_sample(&m->textures[mat->texture], u, v, 0.0f, tex);
    }
    for (int k = 0; k < 3; ++k) s->rho[k] = fminf(fmaxf(mat->albedo[k] * tex[k] * c->albedo_scale, 0.0f), 0.999f);
    s->lobe.g = NULL;
    if (c->sc->ggx && c->sc->ggx[m->tri_material[t]].alpha > 0.0f) {
        float wo[3] = {-wdir[0], -wdir[1], -wdir[2]};
        glow__render_lobe_setup(&s->lobe, &c->sc->ggx[m->tri_material[t]], s->ns, s->ng, wo, s->rho);
    }
}

/* Emitted radiance of triangle t at barycentrics (b1, b2) towards a ray that hit it (front face only):
 * the material's emission times its emission texture there (map_Ke / emissiveTexture), as the linker
 * folds it into the surfels. Emitters are still chosen for NEE by their material emission and area:
 * the texture only changes the estimator's value, never makes a texel emit where that pdf is 0. */
static bool emission_of(const render_ctx *c, uint32_t t, float b1, float b2, bool back, float le[3]) {
    if (back || !(c->emission_scale > 0.0f)) return false;
    const glow__scene *m = &c->sc->mesh;
    const glow__material *mat = &m->materials[m->tri_material[t]];
    const float *e = mat->emission;
    if (!(e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f)) return false;
    float tex[3] = {1.0f, 1.0f, 1.0f};
    if (mat->emission_texture >= 0 && (uint32_t)mat->emission_texture < m->texture_count && m->uv0) {
        const float *u0 = m->uv0[3 * (size_t)t], *u1 = m->uv0[3 * (size_t)t + 1], *u2 = m->uv0[3 * (size_t)t + 2];
        const float b0 = 1.0f - b1 - b2;
        glow__texture_sample(&m->textures[mat->emission_texture], b0 * u0[0] + b1 * u1[0] + b2 * u2[0],
                             b0 * u0[1] + b1 * u1[1] + b2 * u2[1], 0.0f, tex);
    }
    for (int k = 0; k < 3; ++k) le[k] = e[k] * tex[k] * c->emission_scale;
    return true;
}

/* The host's lights at s (glow_host.h, THE CONTRACT), exact shadow rays: the radiance s reflects
 * back along the arriving ray, ρ/π · E for a Lambertian surface (E the irradiance, W/m²), Σ f(o, l) E_l with a GGX
 * layer. */
static void delta_light(const render_ctx *c, const surf *s, float out[3], uint64_t *rays) {
    float E[3] = {0.0f, 0.0f, 0.0f};
    for (uint32_t i = 0; i < c->light_count; ++i) {
        const render_light *hl = &c->lights[i];
        const glow_scene_light *L = &hl->l;
        const float *pw = L->type == GLOW_SCENE_LIGHT_SUN ? L->irradiance : L->intensity;
        if (pw[0] == 0.0f && pw[1] == 0.0f && pw[2] == 0.0f) continue;
        float l[3], f;
        if (L->type == GLOW_SCENE_LIGHT_SUN) {
            for (int k = 0; k < 3; ++k) l[k] = -L->direction[k];
            f = fmaxf(glow__dot(s->ns, l), 0.0f);
            if (!(f > 0.0f) || glow__dot(s->ng, l) <= 0.0f) continue;
            ++*rays;
            if (glow__rt_occluded(c->sc->rt, s->o, l, 0.0f, INFINITY)) continue;
        } else {
            float d[3];
            glow__sub(L->position, s->p, d);
            float d2 = glow__dot(d, d);
            if (!(d2 > 1e-20f)) continue;
            float dl = sqrtf(d2);
            for (int k = 0; k < 3; ++k) l[k] = d[k] / dl;
            float cs = glow__dot(s->ns, l);
            if (!(cs > 0.0f) || glow__dot(s->ng, l) <= 0.0f) continue;
            f = cs / d2;
            if (L->type == GLOW_SCENE_LIGHT_SPOT) {
                float cos_theta = -glow__dot(l, L->direction), t;
                if (hl->cos_inner > hl->cos_outer) {
                    t = (cos_theta - hl->cos_outer) / (hl->cos_inner - hl->cos_outer);
                    t = fminf(fmaxf(t, 0.0f), 1.0f);
                } else {
                    t = cos_theta >= hl->cos_outer ? 1.0f : 0.0f;
                }
                f *= t * t * (3.0f - 2.0f * t);
                if (!(f > 0.0f)) continue;
            }
            float v[3];
            glow__sub(L->position, s->o, v);
            float vl = sqrtf(glow__dot(v, v)), tfar = vl - c->sc->eps;
            if (tfar > 0.0f) {
                for (int k = 0; k < 3; ++k) v[k] /= vl;
                ++*rays;
                if (glow__rt_occluded(c->sc->rt, s->o, v, 0.0f, tfar)) continue;
            }
        }
        if (s->lobe.g) { /* f = cos θ_l · geometry; bsdf_eval gives f(o, l) cos θ_l */
            float fd[3], fs[3];
            glow__render_lobe_eval(&s->lobe, l, fd, fs);
            const float geom = f / glow__dot(s->ns, l);
            for (int k = 0; k < 3; ++k) E[k] += geom * pw[k] * (fd[k] + fs[k]);
        } else {
            for (int k = 0; k < 3; ++k) E[k] += f * pw[k];
        }
    }
    for (int k = 0; k < 3; ++k) out[k] = s->lobe.g ? E[k] : s->rho[k] * INV_PI_F * E[k];
}

static inline float mis2(float a, float b) { /* power heuristic, weight of a */
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

/* Next-event estimation of the emissive triangles at s: reflected radiance (before the path's
 * throughput), MIS-weighted against BSDF sampling; out_spec (optional) its GGX part. Always draws 3
 * numbers. */
static void emitter_nee(const render_ctx *c, rng *rp, const surf *s, float out[3], float out_spec[3], float *out_dist,
                        uint64_t *rays) {
    out[0] = out[1] = out[2] = 0.0f;
    if (out_spec) out_spec[0] = out_spec[1] = out_spec[2] = 0.0f;
    if (out_dist) *out_dist = INFINITY;
    const glow_render_scene *sc = c->sc;
    float u = rnd(rp), r1 = rnd(rp), r2 = rnd(rp);
    if (!c->emitters_on) return;
    uint32_t lo = 0, hi = sc->emitter_count - 1; /* first i with cdf[i] > u */
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (sc->emitter_cdf[mid] > (double)u) hi = mid;
        else lo = mid + 1;
    }
    const uint32_t t = sc->emitter_tri[lo];
    const float(*p)[3] = sc->mesh.pos + 3 * (size_t)t;
    float su = sqrtf(r1), b1 = su * (1.0f - r2), b2 = su * r2;
    float q[3], d[3];
    for (int k = 0; k < 3; ++k) q[k] = p[0][k] + b1 * (p[1][k] - p[0][k]) + b2 * (p[2][k] - p[0][k]);
    glow__sub(q, s->p, d);
    float d2 = glow__dot(d, d);
    if (!(d2 > 1e-20f)) return;
    float dl = sqrtf(d2), w[3] = {d[0] / dl, d[1] / dl, d[2] / dl};
    if (out_dist) *out_dist = dl;
    float cos_s = glow__dot(s->ns, w);
    if (!(cos_s > 0.0f) || glow__dot(s->ng, w) <= 0.0f) return;
    float cos_l = -glow__dot(sc->ng[t], w);
    if (!(cos_l > 0.0f)) return;
    float le[3];
    if (!emission_of(c, t, b1, b2, false, le)) return;
    float v[3];
    glow__sub(q, s->o, v);
    float vl = sqrtf(glow__dot(v, v)), tfar = vl - sc->eps;
    if (tfar > 0.0f) {
        for (int k = 0; k < 3; ++k) v[k] /= vl;
        ++*rays;
        if (glow__rt_occluded(sc->rt, s->o, v, 0.0f, tfar)) return;
    }
    float pl = sc->light_pdf_area[t] * d2 / cos_l;
    if (!(pl > 0.0f) || !isfinite(pl)) return;
    if (s->lobe.g) {
        float fd[3], fs[3];
        const float pb = glow__render_lobe_eval(&s->lobe, w, fd, fs), m = mis2(pl, pb) / pl;
        for (int k = 0; k < 3; ++k) {
            out[k] = le[k] * (fd[k] + fs[k]) * m;
            if (out_spec) out_spec[k] = le[k] * fs[k] * m;
        }
        return;
    }
    float pb = cos_s * INV_PI_F;
    float g = mis2(pl, pb) * cos_s * INV_PI_F / pl;
    for (int k = 0; k < 3; ++k) out[k] = s->rho[k] * le[k] * g;
}

/* Next-event estimation of the environment map at s from (u1, u2): reflected radiance (before the path's
 * throughput), MIS-weighted (power heuristic) against BSDF sampling; out_spec (optional) its GGX part.
 * The shadow ray goes to infinity: any hit blocks the sky. */
static void envmap_nee(const render_ctx *c, float u1, float u2, const surf *s, float out[3], float out_spec[3],
                       uint64_t *rays) {
    out[0] = out[1] = out[2] = 0.0f;
    if (out_spec) out_spec[0] = out_spec[1] = out_spec[2] = 0.0f;
    float w[3], L[3];
    const float pe = glow_eval_envmap_sample(c->map, u1, u2, w, L);
    if (!(pe > 0.0f)) return;
    const float cos_s = glow__dot(s->ns, w);
    if (!(cos_s > 0.0f) || glow__dot(s->ng, w) <= 0.0f) return;
    ++*rays;
    if (glow__rt_occluded(c->sc->rt, s->o, w, 0.0f, INFINITY)) return;
    if (s->lobe.g) {
        float fd[3], fs[3];
        const float pb = glow__render_lobe_eval(&s->lobe, w, fd, fs), m = mis2(pe, pb) / pe;
        for (int k = 0; k < 3; ++k) {
            out[k] = L[k] * (fd[k] + fs[k]) * m;
            if (out_spec) out_spec[k] = L[k] * fs[k] * m;
        }
        return;
    }
    const float g = mis2(pe, cos_s * INV_PI_F) * cos_s * INV_PI_F / pe;
    for (int k = 0; k < 3; ++k) out[k] = s->rho[k] * L[k] * g;
}

/* A BSDF-sampled ray w (drawn with solid-angle pdf pdf_bsdf; 0 = its origin did no NEE: full weight) left
 * the scene: adds beta × the map's radiance there × the MIS weight against envmap_nee to out. */
static void envmap_escape(const render_ctx *c, const float w[3], float pdf_bsdf, const float beta[3], float out[3]) {
    if (!c->map) return;
    float L[3];
    glow_eval_envmap_eval(c->map, w, L);
    const float wgt = c->map_nee && pdf_bsdf > 0.0f ? mis2(pdf_bsdf, glow_eval_envmap_pdf(c->map, w)) : 1.0f;
    for (int k = 0; k < 3; ++k) out[k] += beta[k] * L[k] * wgt;
}

/* Glow's indirect light at the first hit: ρ · (cosine-lobe mean incident radiance of the caches);
 * with a GGX layer ρ (1 - E(cos θ_o)) · that + the GGX lobe's (glow_view.glossy), which also goes to spec[].
 * When it read the lightmap, texel[] gets the texel whose square holds the lookup (x + 1, y + 1) and
 * that texel's cache + 1 (glow_render_result.texel); otherwise texel[] is left alone. */
static void glow_indirect(const render_ctx *c, const surf *s, float *coeffs, worker_stats *ws, float out[3],
                          float texel[3], float spec[3]) {
    out[0] = out[1] = out[2] = 0.0f;
    float det[3] = {0.0f, 0.0f, 0.0f}; /* the lightmap detail's correction (bakes with LDET) */
    const glow_cache_outputs *o = c->gv->out;
    bool ok = false;
    if (!s->back && c->gv->lm_uv && !c->gv->grid_only) {
        const float *uv = c->gv->lm_uv[s->tri];
        float b0 = 1.0f - s->b1 - s->b2;
        float u = b0 * uv[0] + s->b1 * uv[2] + s->b2 * uv[4];
        float v = b0 * uv[1] + s->b1 * uv[3] + s->b2 * uv[5];
        const uint32_t page = c->gv->lm_page ? c->gv->lm_page[s->tri] : 0u; /* the triangle's atlas */
        ok = glow_sample_lightmap_page(o, page, u, v, coeffs) == GLOW_OK;
        if (ok) {
            ws->lm++;
            const uint32_t W = o->lightmap_width, H = o->lightmap_height;
            const float fx = u * (float)W, fy = v * (float)H; /* the texel square holding (u, v), clamped */
            const uint32_t tx = fx > 0.0f ? (fx < (float)W ? (uint32_t)fx : W - 1u) : 0u;
            /* (rows of the pages stacked: the texel index page * W * H + y * W + x is ty * W + tx) */
            const uint32_t ty = (fy > 0.0f ? (fy < (float)H ? (uint32_t)fy : H - 1u) : 0u) + page * H;
            const uint32_t cache = o->lightmap_map[(size_t)ty * W + tx];
            texel[0] = (float)(tx + 1u);
            texel[1] = (float)(ty + 1u);
            texel[2] = cache == UINT32_MAX ? 0.0f : (float)cache + 1.0f;
        }
        if (ok && o->lightmap_detail && !c->gv->no_detail) glow_sample_lightmap_detail_page(o, page, u, v, det);
    }
    if (!ok && o->grid_sh) { /* as a dynamic object's surface (with grid_only: 0.1 % of the diagonal off it) */
        float p[3];
        const float off = c->gv->grid_only ? 1e-3f * c->sc->diag : 0.0f;
        for (int k = 0; k < 3; ++k) p[k] = s->p[k] + off * s->ns[k];
        ok = glow_sample_grid_oriented(o, p, s->ns, coeffs) == GLOW_OK;
        if (ok) ws->grid++;
    }
    if (!ok) {
        ws->missed++;
        return;
    }
    float e[3];
    glow_shade_sh(coeffs, o->sh_bands_luma, o->sh_bands_chroma, s->ns, 1.0f, e);
    if (!s->lobe.g) {
        for (int k = 0; k < 3; ++k) out[k] = s->rho[k] * fmaxf(e[k] + det[k], 0.0f);
        return;
    }
    /* the diffuse layer: ρ (1 - E(cos θ_o)) · its mean over the cosine lobe, the weight (1 - E(cos θ_i)) /
     * (1 - Ē) of each incident direction taken as its mean, 1 (exact for uniform light) */
    for (int k = 0; k < 3; ++k) out[k] = s->rho[k] * (1.0f - s->lobe.e_o[k]) * fmaxf(e[k] + det[k], 0.0f);
    const glow_view_ggx *vg = &c->gv->ggx[s->lobe.g - c->sc->ggx];
    if (c->gv->glossy == GLOW_RENDER_GLOSSY_NONE || !vg->ok) return;
    /* the split sum: (F0 A + B)(cos θ_o) × the lobe's mean of the caches' radiance about the reflection
     * vector (docs/glossy.md) */
    float r[3], l[3];
    for (int k = 0; k < 3; ++k) r[k] = 2.0f * s->lobe.cos_o * s->ns[k] - s->lobe.wo[k];
    if (c->gv->glossy == GLOW_RENDER_GLOSSY_ZH_GGX_DOMINANT) {
        /* Lagarde & de Rousiers 2014 ("Moving Frostbite to PBR", getSpecularDominantDir): the lobe's
         * dominant direction leans from the reflection vector towards the normal as it widens (the
         * off-specular peak) */
        const float a = s->lobe.g->alpha, sm = 1.0f - a, t = sm * (sqrtf(sm) + a);
        for (int k = 0; k < 3; ++k) r[k] = s->ns[k] + t * (r[k] - s->ns[k]);
    }
    v_norm(r);
    glow_shade_sh_factors(coeffs, o->sh_bands_luma, o->sh_bands_chroma, r,
                          c->gv->glossy == GLOW_RENDER_GLOSSY_PHONG ? vg->phong : vg->zh, l);
    for (int k = 0; k < 3; ++k) {
        const float sp = s->lobe.e_o[k] * fmaxf(l[k], 0.0f); /* E = F0 A + B at cos θ_o */
        out[k] += sp;
        spec[k] += sp;
    }
}

/* The rest of a path from hit h (its vertex 2 onwards), reached from prev_p along wdir with throughput
 * beta: emission found by BSDF sampling (MIS-weighted against the previous vertex's emitter NEE; at
 * full weight when pdf_prev is 0, i.e. the previous vertex did no NEE), NEE of the host's lights and of
 * the emitters at every vertex, Russian roulette, the environment where the path escapes. Adds the
 * radiance it carries to out. Shared by the reference's pixels and its irradiance probes. */
static void continue_path(const render_ctx *c, rng *rp, glow__hit h, const float beta_in[3], const float prev_in[3],
                          const float w_in[3], float pdf_prev, float out[3], uint64_t *rays) {
    const glow_render_scene *sc = c->sc;
    float beta[3], prev_p[3], wdir[3], le[3], E[3], nee[3];
    memcpy(beta, beta_in, sizeof beta);
    memcpy(prev_p, prev_in, sizeof prev_p);
    memcpy(wdir, w_in, sizeof wdir);
    surf s;
    for (uint32_t depth = 2;; ++depth) {
        make_surf(c, &h, wdir, &s);
        if (emission_of(c, s.tri, s.b1, s.b2, s.back, le)) { /* BSDF-sampled emitter hit, MIS against NEE */
            float wgt = 1.0f;
            if (pdf_prev > 0.0f) {
                float d[3];
                glow__sub(s.p, prev_p, d);
                float cos_l = -glow__dot(sc->ng[s.tri], wdir);
                float pl = cos_l > 0.0f ? sc->light_pdf_area[s.tri] * glow__dot(d, d) / cos_l : 0.0f;
                wgt = c->emitters_on && pl > 0.0f && isfinite(pl) ? mis2(pdf_prev, pl) : 1.0f;
            }
            for (int k = 0; k < 3; ++k) out[k] += beta[k] * le[k] * wgt;
        }
        if (depth >= c->max_depth) break;
        delta_light(c, &s, E, rays);
        emitter_nee(c, rp, &s, nee, NULL, NULL, rays);
        for (int k = 0; k < 3; ++k) out[k] += beta[k] * (E[k] + nee[k]);
        if (c->map_nee) {
            const float u1 = rnd(rp), u2 = rnd(rp);
            envmap_nee(c, u1, u2, &s, nee, NULL, rays);
            for (int k = 0; k < 3; ++k) out[k] += beta[k] * nee[k];
        }
        float r = rnd(rp), a = rnd(rp), b = rnd(rp);
        if (s.lobe.g) { /* GGX layer: sample first, then Russian roulette on the new throughput */
            float w[3], wsp[3], pdf;
            if (!glow__render_lobe_sample(&s.lobe, a, b, wdir, w, wsp, &pdf)) break;
            float nb[3] = {beta[0] * w[0], beta[1] * w[1], beta[2] * w[2]};
            if (depth >= RR_START) {
                float q = fminf(0.95f, fmaxf(nb[0], fmaxf(nb[1], nb[2])));
                if (!(r < q)) break;
                for (int k = 0; k < 3; ++k) nb[k] /= q;
            }
            memcpy(beta, nb, sizeof beta);
            pdf_prev = pdf;
        } else {
            float nb[3] = {beta[0] * s.rho[0], beta[1] * s.rho[1], beta[2] * s.rho[2]};
            if (depth >= RR_START) {
                float q = fminf(0.95f, fmaxf(nb[0], fmaxf(nb[1], nb[2])));
                if (!(r < q)) break;
                for (int k = 0; k < 3; ++k) nb[k] /= q;
            }
            float cw = glow__render_sample_cosine(s.ns, a, b, wdir);
            if (!(cw > 0.0f) || glow__dot(wdir, s.ng) <= 0.0f) break;
            memcpy(beta, nb, sizeof beta);
            pdf_prev = cw * INV_PI_F;
        }
        memcpy(prev_p, s.p, sizeof prev_p);
        ++*rays;
        h = glow__rt_intersect(sc->rt, s.o, wdir, 0.0f, INFINITY);
        if (h.tri == UINT32_MAX) {
            for (int k = 0; k < 3; ++k) out[k] += beta[k] * c->env[k];
            envmap_escape(c, wdir, pdf_prev, beta, out);
            break;
        }
    }
}

/* One sample of pixel (x, y): adds to direct[3] and indirect[3]; texel[] as glow_indirect's; spec[3]
 * (scenes with a GGX layer) the part of indirect that the first hit's GGX lobe reflects. */
static void sample(const render_ctx *c, uint32_t x, uint32_t y, rng *rd, rng *rp, float *coeffs, worker_stats *ws,
                   float direct[3], float indirect[3], float near[3], float texel[3], float spec[3]) {
    const glow_render_scene *sc = c->sc;
    /* ---- camera ray (stream rd) */
    float jx = rnd(rd), jy = rnd(rd);
    float sx = (2.0f * ((float)x + jx) / (float)c->w - 1.0f) * c->tan_x;
    float sy = (1.0f - 2.0f * ((float)y + jy) / (float)c->h) * c->tan_y;
    float dir[3];
    for (int k = 0; k < 3; ++k) dir[k] = c->fwd[k] + sx * c->right[k] + sy * c->up[k];
    v_norm(dir);
    ws->rays++;
    glow__hit h = glow__rt_intersect(sc->rt, c->org, dir, 0.0f, INFINITY);
    if (h.tri == UINT32_MAX) {
        if (!(c->gv && c->gv->indirect_only)) {
            for (int k = 0; k < 3; ++k) direct[k] += c->env[k];
            if (c->map) {
                float L[3];
                glow_eval_envmap_eval(c->map, dir, L);
                for (int k = 0; k < 3; ++k) direct[k] += L[k];
            }
        }
        return;
    }
    surf s;
    make_surf(c, &h, dir, &s);
    if (c->gv && c->gv->indirect_only) { /* the caches alone; stream rd advances as below */
        (void)rnd(rd);
        (void)rnd(rd);
        if (c->map_nee) {
            (void)rnd(rd);
            (void)rnd(rd);
        }
        float g[3];
        glow_indirect(c, &s, coeffs, ws, g, texel, spec);
        for (int k = 0; k < 3; ++k) indirect[k] += g[k];
        return;
    }
    float le[3];
    if (emission_of(c, s.tri, s.b1, s.b2, s.back, le))
        for (int k = 0; k < 3; ++k) direct[k] += le[k];
    /* ---- the host's lights at the first hit */
    float E[3];
    delta_light(c, &s, E, &ws->rays);
    for (int k = 0; k < 3; ++k) direct[k] += E[k];
    /* ---- the first bounce (stream rd): the environment it reaches is direct */
    float w1[3];
    float r1 = rnd(rd), r2 = rnd(rd);
    float beta[3] = {s.rho[0], s.rho[1], s.rho[2]}, beta_s[3] = {0.0f, 0.0f, 0.0f}; /* f cos / pdf: ρ for cosine sampling */
    float pdf1;
    bool valid;
    if (s.lobe.g) {
        valid = glow__render_lobe_sample(&s.lobe, r1, r2, w1, beta, beta_s, &pdf1);
    } else {
        float cos1 = glow__render_sample_cosine(s.ns, r1, r2, w1);
        valid = cos1 > 0.0f && glow__dot(w1, s.ng) > 0.0f;
        pdf1 = cos1 * INV_PI_F;
    }
    glow__hit h1 = {.t = INFINITY, .tri = UINT32_MAX};
    if (valid) {
        ws->rays++;
        h1 = glow__rt_intersect(sc->rt, s.o, w1, 0.0f, INFINITY);
        if (h1.tri == UINT32_MAX && c->env_on)
            for (int k = 0; k < 3; ++k) direct[k] += beta[k] * c->env[k];
        if (h1.tri == UINT32_MAX) envmap_escape(c, w1, pdf1, beta, direct);
    }
    if (c->map_nee) { /* the environment map's NEE at the first hit (stream rd): direct light too */
        const float u1 = rnd(rd), u2 = rnd(rd);
        float en[3];
        envmap_nee(c, u1, u2, &s, en, NULL, &ws->rays);
        for (int k = 0; k < 3; ++k) direct[k] += en[k];
    }
    /* ---- Glow's view: the caches at the first hit */
    if (c->gv) {
        float g[3];
        glow_indirect(c, &s, coeffs, ws, g, texel, spec);
        for (int k = 0; k < 3; ++k) indirect[k] += g[k];
        return;
    }
    /* ---- reference: the rest of the path (stream rp). With a near split, each part of the indirect
     * light also goes to near[] when the surface it last left before the first hit (the emitter point
     * of the NEE, the hit of the first bounce) is closer than c->near_split. */
    float nee[3], nee_s[3], nee_dist;
    emitter_nee(c, rp, &s, nee, nee_s, &nee_dist, &ws->rays);
    for (int k = 0; k < 3; ++k) indirect[k] += nee[k];
    if (s.lobe.g)
        for (int k = 0; k < 3; ++k) spec[k] += nee_s[k];
    if (nee_dist < c->near_split)
        for (int k = 0; k < 3; ++k) near[k] += nee[k];
    if (!valid || h1.tri == UINT32_MAX) return;
    float rest[3] = {0.0f, 0.0f, 0.0f};
    if (s.lobe.g) { /* the path after a unit throughput, then split by the lobes' weights */
        const float one[3] = {1.0f, 1.0f, 1.0f};
        continue_path(c, rp, h1, one, s.p, w1, pdf1, rest, &ws->rays);
        for (int k = 0; k < 3; ++k) {
            spec[k] += beta_s[k] * rest[k];
            rest[k] *= beta[k];
        }
    } else {
        continue_path(c, rp, h1, beta, s.p, w1, pdf1, rest, &ws->rays);
    }
    for (int k = 0; k < 3; ++k) indirect[k] += rest[k];
    if (h1.t < c->near_split)
        for (int k = 0; k < 3; ++k) near[k] += rest[k];
}

/* Rows [begin, end) on the linker's pool (glow__parallel_for: the bake side's one thread pool). */
static void render_rows(void *ctx, uint32_t begin, uint32_t end, uint32_t worker) {
    render_ctx *c = ctx;
    worker_stats local = {0}, *ws = &local; /* counted here, added once: no false sharing between workers */
    float coeffs[GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS * 3];
    for (uint32_t y = begin; y < end; ++y) {
        for (uint32_t x = 0; x < c->w; ++x) {
            const uint64_t pixel = (uint64_t)y * c->w + x;
            rng rd, rp;
            rng_init(&rd, c->seed, pixel, 0);
            rng_init(&rp, c->seed, pixel, 1);
            double sd[3] = {0, 0, 0}, si[3] = {0, 0, 0}, sn[3] = {0, 0, 0}, ss[3] = {0, 0, 0};
            float tex[3] = {0, 0, 0}; /* the first sample's lightmap texel that has one */
            for (uint32_t n = 0; n < c->spp; ++n) {
                float d[3] = {0, 0, 0}, ind[3] = {0, 0, 0}, nr[3] = {0, 0, 0}, tl[3] = {0, 0, 0}, sp[3] = {0, 0, 0};
                sample(c, x, y, &rd, &rp, coeffs, ws, d, ind, nr, tl, sp);
                if (tex[0] == 0.0f) memcpy(tex, tl, sizeof tex);
                if (!(isfinite(d[0]) && isfinite(d[1]) && isfinite(d[2]) && isfinite(ind[0]) && isfinite(ind[1]) &&
                      isfinite(ind[2]))) { /* a bug upstream: counted and reported, kept out of the pixel */
                    ws->nonfinite++;
                    continue;
                }
                for (int k = 0; k < 3; ++k) {
                    sd[k] += d[k];
                    si[k] += ind[k];
                    sn[k] += nr[k];
                    ss[k] += sp[k];
                }
            }
            for (int k = 0; k < 3; ++k) {
                c->direct[3 * pixel + k] = (float)(sd[k] / c->spp);
                c->indirect[3 * pixel + k] = (float)(si[k] / c->spp);
                if (c->indirect_near) c->indirect_near[3 * pixel + k] = (float)(sn[k] / c->spp);
                if (c->texel) c->texel[3 * pixel + k] = tex[k];
                if (c->specular) c->specular[3 * pixel + k] = (float)(ss[k] / c->spp);
            }
        }
        unsigned done = atomic_fetch_add(&c->rows_done, 1u) + 1u;
        if (c->progress) {
            pthread_mutex_lock(&c->progress_lock);
            c->progress(c->progress_user, (double)done / c->h);
            pthread_mutex_unlock(&c->progress_lock);
        }
    }
    worker_stats *w = &c->ws[worker];
    w->rays += local.rays;
    w->lm += local.lm;
    w->grid += local.grid;
    w->missed += local.missed;
    w->nonfinite += local.nonfinite;
}

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void image_mean(const glow_eval_image *img, double out[3]) {
    double s[3] = {0, 0, 0};
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) s[k] += img->rgb[3 * i + k];
    for (int k = 0; k < 3; ++k) out[k] = n ? s[k] / (double)n : 0.0;
}

static uint32_t resolve_threads(uint32_t t) {
    if (t) return t;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (uint32_t)n : 1u;
}

static glow_result check_settings(const glow_render_scene *sc, const glow_render_settings *s, char *message,
                                  size_t message_size) {
    if (!sc || !s) return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: NULL argument");
    if ((s->width == 0) != (s->height == 0))
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: give both width and height, or neither (got %u x %u)", s->width, s->height);
    if (s->width > 16384 || s->height > 16384)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: image size %u x %u is outside 1..16384", s->width, s->height);
    if (s->spp > (1u << 20))
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: spp %u is above 1048576",
                                 s->spp);
    if (s->threads > 1024)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: threads %u is above 1024",
                                 s->threads);
    if (!isfinite(s->albedo_scale) || s->albedo_scale < 0.0f)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: albedo_scale %g must be finite and >= 0", (double)s->albedo_scale);
    if (!(s->near_split >= 0.0f) || isinf(s->near_split))
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: near_split %g must be finite and >= 0", (double)s->near_split);
    return GLOW_OK;
}

/* Renders with `gv` (NULL = reference) into out. */
static glow_result render(const glow_render_scene *sc, const glow_render_settings *st, const glow_view *gv,
                          glow_render_result *out, char *message, size_t message_size) {
    render_ctx c;
    memset(&c, 0, sizeof c);
    c.sc = sc;
    c.w = st->width ? st->width : sc->camera.width;
    c.h = st->height ? st->height : sc->camera.height;
    c.spp = st->spp ? st->spp : DEFAULT_SPP;
    c.max_depth = st->max_depth ? st->max_depth : DEFAULT_MAX_DEPTH;
    c.threads = resolve_threads(st->threads);
    if (c.threads > c.h) c.threads = c.h;
    c.seed = st->seed;
    c.albedo_scale = st->albedo_scale > 0.0f ? st->albedo_scale : 1.0f;
    c.emission_scale = sc->desc.emission_scale;
    c.emitters_on = sc->emitter_count > 0 && c.emission_scale > 0.0f;
    memcpy(c.env, sc->desc.environment, sizeof c.env);
    c.env_on = c.env[0] > 0.0f || c.env[1] > 0.0f || c.env[2] > 0.0f;
    c.map = sc->has_envmap ? &sc->envmap : NULL;
    c.map_nee = c.map && c.map->lum_integral > 0.0 && c.map->scale > 0.0f && !st->envmap_bsdf_only;
    c.gv = gv;
    c.progress = st->progress;
    c.progress_user = st->progress_user;
    /* camera */
    const glow_scene_camera *cam = &sc->camera;
    memcpy(c.org, cam->position, sizeof c.org);
    glow__sub(cam->target, cam->position, c.fwd);
    glow__cross(c.fwd, cam->up, c.right);
    if (!(v_norm(c.fwd) > 0.0f) || !(v_norm(c.right) > 0.0f))
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "%s: camera: target equals position, or up is parallel to the view", sc->path);
    glow__cross(c.right, c.fwd, c.up);
    c.tan_y = tanf(0.5f * cam->vfov_deg * PI_F / 180.0f);
    c.tan_x = c.tan_y * (float)c.w / (float)c.h;

    glow_result r = GLOW_OK;
    c.lights = sc->desc.light_count ? calloc(sc->desc.light_count, sizeof *c.lights) : NULL;
    c.ws = calloc(c.threads, sizeof *c.ws);
    if ((sc->desc.light_count && !c.lights) || !c.ws) {
        r = glow__render_fail(message, message_size, GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", sc->path);
        goto done;
    }
    for (uint32_t i = 0; i < sc->desc.light_count; ++i) {
        c.lights[i].l = sc->desc.lights[i];
        v_norm(c.lights[i].l.direction);
        c.lights[i].cos_outer = cosf(c.lights[i].l.outer_deg * PI_F / 180.0f);
        c.lights[i].cos_inner = cosf(c.lights[i].l.inner_deg * PI_F / 180.0f);
    }
    c.light_count = sc->desc.light_count;
    if ((r = glow_eval_image_alloc(&out->direct, c.w, c.h)) != GLOW_OK ||
        (r = glow_eval_image_alloc(&out->indirect, c.w, c.h)) != GLOW_OK ||
        (r = glow_eval_image_alloc(&out->final, c.w, c.h)) != GLOW_OK ||
        (!gv && st->near_split > 0.0f && (r = glow_eval_image_alloc(&out->indirect_near, c.w, c.h)) != GLOW_OK) ||
        (gv && gv->lm_uv && !gv->grid_only && (r = glow_eval_image_alloc(&out->texel, c.w, c.h)) != GLOW_OK) ||
        (sc->ggx && (r = glow_eval_image_alloc(&out->specular, c.w, c.h)) != GLOW_OK)) {
        r = glow__render_fail(message, message_size, r, "%s: cannot allocate %u x %u images", sc->path, c.w, c.h);
        goto done;
    }
    c.direct = out->direct.rgb;
    c.indirect = out->indirect.rgb;
    c.indirect_near = out->indirect_near.rgb; /* NULL unless allocated above */
    c.texel = out->texel.rgb;                 /* likewise */
    c.specular = out->specular.rgb;           /* likewise */
    c.near_split = c.indirect_near ? st->near_split : 0.0f;
    atomic_init(&c.rows_done, 0u);
    pthread_mutex_init(&c.progress_lock, NULL);
    double t0 = now_s();
    glow__pool *pool = glow__pool_create(c.threads); /* NULL (no memory): glow__parallel_for runs serially */
    const uint32_t ran = pool ? glow__pool_threads(pool) : 1u;
    glow__parallel_for(pool, c.h, 1, render_rows, &c);
    glow__pool_destroy(pool);
    double t1 = now_s();
    pthread_mutex_destroy(&c.progress_lock);
    size_t n = (size_t)c.w * c.h * 3;
    for (size_t i = 0; i < n; ++i) out->final.rgb[i] = c.direct[i] + c.indirect[i];
    out->width = c.w;
    out->height = c.h;
    out->spp = c.spp;
    out->threads = ran;
    out->seconds = t1 - t0;
    for (uint32_t i = 0; i < c.threads; ++i) {
        out->rays += c.ws[i].rays;
        out->lightmap_lookups += c.ws[i].lm;
        out->grid_lookups += c.ws[i].grid;
        out->missed_lookups += c.ws[i].missed;
        out->nonfinite_samples += c.ws[i].nonfinite;
    }
    out->mrays_per_s = out->seconds > 0.0 ? (double)out->rays / out->seconds * 1e-6 : 0.0;
    image_mean(&out->final, out->mean_final);
    image_mean(&out->direct, out->mean_direct);
    image_mean(&out->indirect, out->mean_indirect);
    if (c.indirect_near) image_mean(&out->indirect_near, out->mean_indirect_near);
    if (c.specular) image_mean(&out->specular, out->mean_specular);
done:
    free(c.lights);
    free(c.ws);
    if (r != GLOW_OK) glow_render_result_free(out);
    return r;
}

glow_result glow_render_reference(const glow_render_scene *sc, const glow_render_settings *st, glow_render_result *out,
                                  char *message, size_t message_size) {
    if (message && message_size) message[0] = 0;
    if (out) memset(out, 0, sizeof *out);
    if (!out) return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: NULL argument");
    glow_result r = check_settings(sc, st, message, message_size);
    if (r != GLOW_OK) return r;
    return render(sc, st, NULL, out, message, message_size);
}

/* ------------------------------------------------------------------------------------- glow view */
float glow_render_phong_exponent(float roughness) {
    const float a = roughness * roughness, nb = 2.0f / (a * a) - 2.0f; /* Walter et al. 2007's Blinn-Phong */
    return fmaxf(1.0f, 0.25f * nb); /* about the reflection vector θ_i = 2 θ_h: cos^(nb/4) θ_i ≈ cos^nb θ_h */
}

static void capture(void *user, glow_log_level level, glow_result code, const char *msg, const char *file, int line) {
    (void)code; (void)file; (void)line;
    capture_log *cl = user;
    if (level != GLOW_LOG_ERROR || !msg) return;
    pthread_mutex_lock(&cl->lock);
    if (!cl->first_error[0]) snprintf(cl->first_error, sizeof cl->first_error, "%s", msg);
    pthread_mutex_unlock(&cl->lock);
}

void glow__view_free(glow_view *gv) {
    glow_system_destroy(gv->sys);
    glow_host_destroy(gv->host);
    glow_bake_destroy(gv->bake);
    glow_context_destroy(gv->ctx);
    free(gv->lm_uv);
    free(gv->ggx);
    memset(gv, 0, sizeof *gv);
}

/* The scene's environment_map as the host's light (docs/envmap.md, docs/sky.md): its sun (the texels that
 * stand out, glow_eval_envmap_sky_sh's RULE) as one more sun light, shadowed by the host like any other,
 * and the rest as l <= 2 SH through each surfel's baked sky transfer, plus the constant `environment`.
 * Without a map the host keeps the constant sky. The grid is not given the sky (glow_system_set_sky):
 * this view adds the sky reached by the first bounce itself, as direct light. */
static glow_result view_sky(const glow_render_scene *sc, glow_host *host, char *message, size_t message_size) {
    if (!sc->has_envmap) return GLOW_OK;
    float sh[GLOW_SKY_SH_FLOATS];
    glow_eval_envmap_sun sun;
    glow_result r = glow_eval_envmap_sky_sh(&sc->envmap, true, NULL, sh, &sun, message, message_size);
    if (r != GLOW_OK) return r;
    float constant[GLOW_SKY_SH_FLOATS]; /* the constant `environment` adds */
    glow_sh_sky_constant(sc->desc.environment, constant);
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k) sh[k] += constant[k];
    if ((r = glow_host_set_environment_sh(host, sh)) != GLOW_OK)
        return glow__render_fail(message, message_size, r, "%s: the host refused the environment map's SH sky: %s",
                                 sc->path, glow_result_string(r));
    if (!sun.found) return GLOW_OK;
    const uint32_t n = sc->desc.light_count;
    glow_scene_light *lights = calloc((size_t)n + 1, sizeof *lights);
    if (!lights) return glow__render_fail(message, message_size, GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", sc->path);
    if (n) memcpy(lights, sc->desc.lights, (size_t)n * sizeof *lights);
    lights[n].type = GLOW_SCENE_LIGHT_SUN;
    for (int k = 0; k < 3; ++k) {
        lights[n].direction[k] = -sun.to_sun[k];
        lights[n].irradiance[k] = sun.irradiance[k];
    }
    r = glow_host_set_lights(host, lights, n + 1);
    free(lights);
    if (r != GLOW_OK)
        return glow__render_fail(message, message_size, r, "%s: the host refused the environment map's sun: %s", sc->path,
                                 glow_result_string(r));
    return GLOW_OK;
}

glow_result glow__view_create(const glow_render_scene *sc, const char *bake_path, const glow_render_settings *st,
                              const glow_render_glow_settings *gs, capture_log *cl, glow_view *gv, char *message,
                              size_t message_size) {
    memset(gv, 0, sizeof *gv);
    glow_logger logger = {capture, cl};
    const uint32_t threads = resolve_threads(st->threads);
    glow_result r = glow_context_create(
        &(glow_context_desc){.api_version = GLOW_VERSION, .logger = logger, .tasks = {.worker_count = threads}}, &gv->ctx);
    if (r != GLOW_OK) return glow__render_fail(message, message_size, r, "glow_render: cannot create a context: %s", glow_result_string(r));
#define FAIL(code, ...)                                                   \
    do {                                                                  \
        r = glow__render_fail(message, message_size, code, __VA_ARGS__); \
        goto fail;                                                        \
    } while (0)
    if ((r = glow_bake_load_file(gv->ctx, bake_path, &gv->bake)) != GLOW_OK)
        FAIL(r, "%s: cannot load the bake: %s%s%s", bake_path, glow_result_string(r), cl->first_error[0] ? ": " : "",
             cl->first_error);
    glow_bake_info info;
    glow_bake_get_info(gv->bake, &info);
    glow_bake_geometry geo;
    glow_bake_get_geometry(gv->bake, &geo);
    const glow__scene *m = &sc->mesh;
    if (geo.triangle_count == 0) FAIL(GLOW_ERROR_CORRUPT_DATA, "%s: the bake carries no geometry", bake_path);
    if (geo.triangle_count != m->tri_count)
        FAIL(GLOW_ERROR_INVALID_ARGUMENT, "%s: the bake has %u triangles but the scene's mesh %s has %u: it was baked from another mesh",
             bake_path, geo.triangle_count, sc->desc.mesh, m->tri_count);
    if (info.material_count != m->material_count)
        FAIL(GLOW_ERROR_INVALID_ARGUMENT, "%s: the bake has %u materials but the scene's mesh %s has %u: it was baked from another mesh",
             bake_path, info.material_count, sc->desc.mesh, m->material_count);
    const unsigned char *base = (const unsigned char *)geo.positions;
    const unsigned char *lmb = (const unsigned char *)geo.lightmap_uv;
    const bool has_lm = info.lightmap_width > 0 && info.lightmap_cache_count > 0;
    gv->lm_page = has_lm ? geo.lightmap_page : NULL; /* (a view into the bake, which the view keeps) */
    if (has_lm && !(gv->lm_uv = malloc((size_t)m->tri_count * sizeof *gv->lm_uv)))
        FAIL(GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", bake_path);
    for (uint32_t t = 0; t < m->tri_count; ++t) {
        float p[9];
        uint16_t uv[6];
        memcpy(p, base + (size_t)t * geo.stride, sizeof p);
        if (memcmp(p, m->pos[3 * (size_t)t], sizeof p) != 0)
            FAIL(GLOW_ERROR_INVALID_ARGUMENT,
                 "%s: triangle %u is (%g %g %g) (%g %g %g) (%g %g %g) in the bake but (%g %g %g) (%g %g %g) (%g %g %g) in the "
                 "scene's mesh %s: it was baked from another mesh",
                 bake_path, t, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], m->pos[3 * (size_t)t][0],
                 m->pos[3 * (size_t)t][1], m->pos[3 * (size_t)t][2], m->pos[3 * (size_t)t + 1][0],
                 m->pos[3 * (size_t)t + 1][1], m->pos[3 * (size_t)t + 1][2], m->pos[3 * (size_t)t + 2][0],
                 m->pos[3 * (size_t)t + 2][1], m->pos[3 * (size_t)t + 2][2], sc->desc.mesh);
        if (has_lm) {
            memcpy(uv, lmb + (size_t)t * geo.stride, sizeof uv);
            for (int k = 0; k < 6; ++k) gv->lm_uv[t][k] = (float)uv[k] / 65535.0f;
        }
    }
    glow_host_desc hd = glow_host_desc_from_scene(&sc->desc, gv->bake, GLOW_HOST_KIND_EXACT);
    hd.sky_rays = gs->sky_rays;
    hd.surfel_samples = gs->surfel_samples;
    hd.logger = logger;
    if ((r = glow_host_create(&hd, &gv->host)) != GLOW_OK)
        FAIL(r, "%s: cannot create the host: %s%s%s", bake_path, glow_result_string(r), cl->first_error[0] ? ": " : "",
             cl->first_error);
    if ((r = view_sky(sc, gv->host, message, message_size)) != GLOW_OK) goto fail;
    if ((r = glow_system_create(gv->ctx,
                                &(glow_system_desc){.bake = gv->bake, .lighting = glow_host_hooks(gv->host),
                                                    .sh_bands_luma = gs->sh_bands_luma, .sh_bands_chroma = gs->sh_bands_chroma,
                                                    .link_mode = gs->link_mode,
                                                    .label = bake_path},
                                &gv->sys)) != GLOW_OK)
        FAIL(r, "%s: cannot create the system: %s%s%s", bake_path, glow_result_string(r), cl->first_error[0] ? ": " : "",
             cl->first_error);
    const float as = st->albedo_scale > 0.0f ? st->albedo_scale : 1.0f;
    for (uint32_t i = 0; i < info.material_count; ++i) {
        /* a GGX layer's surfels reflect its diffuse layer only, whose albedo under uniform light is
         * ρ (1 - Ē) (docs/glossy.md): PIC's surfels are Lambertian */
        float k[3] = {as, as, as};
        if (sc->ggx && sc->ggx[i].alpha > 0.0f)
            for (int c = 0; c < 3; ++c) k[c] *= 1.0f - sc->ggx[i].e_mean[c];
        if ((k[0] != 1.0f || k[1] != 1.0f || k[2] != 1.0f) && (r = glow_system_set_material(gv->sys, i, NULL, k)) != GLOW_OK)
            FAIL(r, "%s: albedo scale %g %g %g: %s", bake_path, (double)k[0], (double)k[1], (double)k[2], cl->first_error);
    }
    if (sc->ggx) { /* per GGX material: its ZH lobe, the Phong lobe standing in for it, the split sum's table */
        if (!(gv->ggx = calloc(m->material_count, sizeof *gv->ggx))) FAIL(GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", bake_path);
        for (uint32_t i = 0; i < m->material_count; ++i) {
            const glow__render_ggx *g = &sc->ggx[i];
            if (!(g->alpha > 0.0f)) continue;
            glow_view_ggx *vg = &gv->ggx[i];
            glow_sh_ggx_lobe_factors(g->roughness, GLOW_MAX_SH_BANDS, vg->zh);
            const float n = glow_render_phong_exponent(g->roughness);
            for (uint32_t l = 0; l < GLOW_MAX_SH_BANDS; ++l) vg->phong[l] = glow_sh_lobe_factor(l, n);
            vg->ok = true;
        }
    }
    uint32_t left = gs->bounce_iterations ? gs->bounce_iterations : DEFAULT_BOUNCES;
    while (left > 0) {
        uint32_t it = left > 64 ? 64 : left;
        left -= it;
        if ((r = glow_system_set_params(gv->sys, &(glow_system_params){.bounce_intensity = 1.0f,
                                                                        .emission_scale = sc->desc.emission_scale,
                                                                        .bounce_iterations = it})) != GLOW_OK)
            FAIL(r, "%s: glow_system_set_params: %s", bake_path, cl->first_error);
        if ((r = glow_system_update(gv->sys, NULL)) != GLOW_OK)
            FAIL(r, "%s: glow_system_update: %s%s%s", bake_path, glow_result_string(r), cl->first_error[0] ? ": " : "",
                 cl->first_error);
    }
    gv->out = glow_system_outputs(gv->sys);
    if (!gv->out || (!gv->out->grid_sh && !gv->out->lightmap_sh))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "%s: the bake has neither a grid nor a lightmap", bake_path);
    if (!gv->out->lightmap_sh) {
        free(gv->lm_uv);
        gv->lm_uv = NULL;
    }
#undef FAIL
    return GLOW_OK;
fail:
    glow__view_free(gv);
    return r;
}

glow_result glow_render_glow(const glow_render_scene *sc, const char *bake_path, const glow_render_settings *st,
                             const glow_render_glow_settings *gs, glow_render_result *out, char *message,
                             size_t message_size) {
    if (message && message_size) message[0] = 0;
    if (out) memset(out, 0, sizeof *out);
    if (!out || !bake_path)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: NULL argument");
    glow_result r = check_settings(sc, st, message, message_size);
    if (r != GLOW_OK) return r;
    glow_render_glow_settings g = gs ? *gs : (glow_render_glow_settings){0};
    if (g.bounce_iterations > 100000)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: %u bounce iterations is above 100000", g.bounce_iterations);
    if (g.surfel_samples > GLOW_HOST_SURFEL_SAMPLES_MAX)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: surfel_samples %u is above %u", g.surfel_samples, GLOW_HOST_SURFEL_SAMPLES_MAX);
    if ((uint32_t)g.glossy > (uint32_t)GLOW_RENDER_GLOSSY_ZH_GGX_DOMINANT)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: glossy lobe %u is unknown",
                                 (unsigned)g.glossy);
    if (g.sky_rays > 65536)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: sky_rays %u is above 65536",
                                 g.sky_rays);
    const glow_render_scene *moved = g.moved;
    if (moved && (moved->mesh.tri_count != sc->mesh.tri_count ||
                  memcmp(moved->mesh.pos, sc->mesh.pos, (size_t)sc->mesh.tri_count * 3 * sizeof sc->mesh.pos[0]) != 0))
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: %s and %s do not describe the same mesh (%s, %s): the light can move, the "
                                 "geometry not", sc->path, moved->path, sc->desc.mesh, moved->desc.mesh);
    if (g.moved_iterations > 100000)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render: %u iterations after the move is above 100000", g.moved_iterations);
    capture_log cl;
    memset(&cl, 0, sizeof cl);
    pthread_mutex_init(&cl.lock, NULL);
    glow_view gv;
    double t0 = now_s();
    r = glow__view_create(sc, bake_path, st, &g, &cl, &gv, message, message_size);
    if (r == GLOW_OK && moved) { /* the light changes: the moved scene's lights, sky and emission, K more iterations */
        if ((r = glow_host_set_lights(gv.host, moved->desc.lights, moved->desc.light_count)) != GLOW_OK ||
            (r = glow_host_set_environment(gv.host, moved->desc.environment)) != GLOW_OK ||
            (r = view_sky(moved, gv.host, message, message_size)) != GLOW_OK)
            r = glow__render_fail(message, message_size, r, "%s: cannot give the host its lights: %s%s%s", moved->path,
                                  glow_result_string(r), cl.first_error[0] ? ": " : "", cl.first_error);
        for (uint32_t left = g.moved_iterations; r == GLOW_OK && left > 0;) {
            const uint32_t it = left > 64 ? 64 : left;
            left -= it;
            if ((r = glow_system_set_params(gv.sys, &(glow_system_params){.bounce_intensity = 1.0f,
                                                                          .emission_scale = moved->desc.emission_scale,
                                                                          .bounce_iterations = it})) != GLOW_OK ||
                (r = glow_system_update(gv.sys, NULL)) != GLOW_OK)
                r = glow__render_fail(message, message_size, r, "%s: update after the move: %s%s%s", moved->path,
                                      glow_result_string(r), cl.first_error[0] ? ": " : "", cl.first_error);
        }
        if (r == GLOW_OK) gv.out = glow_system_outputs(gv.sys);
        else glow__view_free(&gv);
    }
    double t1 = now_s();
    if (r == GLOW_OK) {
        gv.indirect_only = g.indirect_only;
        gv.no_detail = g.no_detail;
        gv.grid_only = g.grid_only;
        gv.glossy = g.glossy;
        r = render(moved ? moved : sc, st, &gv, out, message, message_size);
        if (r == GLOW_OK) out->solve_seconds = t1 - t0;
        glow__view_free(&gv);
    }
    pthread_mutex_destroy(&cl.lock);
    return r;
}

/* ------------------------------------------------------------------------------ irradiance probes */
/* Radiance arriving at a point from direction w: the first surface's emission at full weight (there
 * is no emitter NEE at the probe point) and everything reflected there and after, with NEE + MIS as in
 * sample(); the environment counts only after a reflection (Glow's caches hold no sky seen directly,
 * the host lights surfels with it). */
static void trace_incoming(const render_ctx *c, rng *rp, const float o[3], const float w[3], float out[3],
                           uint64_t *rays) {
    out[0] = out[1] = out[2] = 0.0f;
    ++*rays;
    glow__hit h = glow__rt_intersect(c->sc->rt, o, w, 0.0f, INFINITY);
    if (h.tri == UINT32_MAX) return;
    const float one[3] = {1.0f, 1.0f, 1.0f};
    continue_path(c, rp, h, one, o, w, 0.0f, out, rays); /* pdf 0: no emitter NEE at the probe point */
}

typedef struct probe_job {
    const render_ctx *c;
    const float *points;
    uint32_t count, samples, group;
    float *out;
    uint64_t rays[256]; /* per worker (the pool has at most 256) */
} probe_job;

/* points [first, end): each from its own random stream (per point, or per group), so the result does
 * not depend on which worker runs it */
static void probe_range(void *ctx, uint32_t first, uint32_t end, uint32_t worker) {
    probe_job *j = ctx;
    const render_ctx *c = j->c;
    uint64_t rays = 0;
    for (uint32_t i = first; i < end; ++i) {
        const float *pt = j->points + 6 * (size_t)i;
        float n[3] = {pt[3], pt[4], pt[5]}, o[3];
        v_norm(n);
        v_madd(o, pt, c->sc->eps, n);
        rng rp;
        rng_init(&rp, c->seed, j->group > 1 ? i / j->group : i, 1);
        double acc[3] = {0, 0, 0};
        for (uint32_t s = 0; s < j->samples; ++s) {
            float w[3], L[3];
            float r1 = rnd(&rp), r2 = rnd(&rp);
            if (!(glow__render_sample_cosine(n, r1, r2, w) > 0.0f)) continue;
            trace_incoming(c, &rp, o, w, L, &rays);
            for (int k = 0; k < 3; ++k) acc[k] += L[k];
        }
        for (int k = 0; k < 3; ++k) j->out[3 * (size_t)i + k] = (float)(PI_F * acc[k] / j->samples);
    }
    j->rays[worker % 256] += rays;
}

/* The render_ctx of probe queries (glow_render_irradiance, the DDISH tracer): lights (NULL = the
 * scene's), settings; no camera, no images. c->lights is malloc'ed (free it). */
static glow_result probe_ctx_init(render_ctx *c, const glow_render_scene *sc, const glow_scene_light *lights,
                                  uint32_t light_count, const glow_render_settings *st, char *message,
                                  size_t message_size) {
    memset(c, 0, sizeof *c);
    c->sc = sc;
    c->max_depth = st->max_depth ? st->max_depth : DEFAULT_MAX_DEPTH;
    c->threads = resolve_threads(st->threads);
    c->seed = st->seed;
    c->albedo_scale = st->albedo_scale > 0.0f ? st->albedo_scale : 1.0f;
    c->emission_scale = sc->desc.emission_scale;
    c->emitters_on = sc->emitter_count > 0 && c->emission_scale > 0.0f;
    memcpy(c->env, sc->desc.environment, sizeof c->env);
    c->map = sc->has_envmap ? &sc->envmap : NULL;
    c->map_nee = c->map && c->map->lum_integral > 0.0 && c->map->scale > 0.0f && !st->envmap_bsdf_only;
    if (!lights) {
        lights = sc->desc.lights;
        light_count = sc->desc.light_count;
    }
    c->lights = light_count ? calloc(light_count, sizeof *c->lights) : NULL;
    if (light_count && !c->lights)
        return glow__render_fail(message, message_size, GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", sc->path);
    for (uint32_t i = 0; i < light_count; ++i) {
        c->lights[i].l = lights[i];
        v_norm(c->lights[i].l.direction);
        c->lights[i].cos_outer = cosf(c->lights[i].l.outer_deg * PI_F / 180.0f);
        c->lights[i].cos_inner = cosf(c->lights[i].l.inner_deg * PI_F / 180.0f);
    }
    c->light_count = light_count;
    return GLOW_OK;
}

glow_result glow_render_irradiance(const glow_render_scene *sc, const glow_scene_light *lights, uint32_t light_count,
                                   const glow_render_settings *st, const float *points, uint32_t count, uint32_t samples,
                                   uint32_t group, float *out_rgb, uint64_t *out_rays, char *message,
                                   size_t message_size) {
    if (message && message_size) message[0] = 0;
    if (!sc || !st || (count && (!points || !out_rgb)) || (light_count && !lights) || samples == 0)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render_irradiance: bad arguments");
    render_ctx c;
    glow_result r = probe_ctx_init(&c, sc, lights, light_count, st, message, message_size);
    if (r != GLOW_OK) return r;
    probe_job j = {.c = &c, .points = points, .count = count, .samples = samples, .group = group, .out = out_rgb};
    glow__pool *pool = glow__pool_create(c.threads); /* NULL (no memory): glow__parallel_for runs serially */
    glow__parallel_for(pool, count, 1, probe_range, &j);
    glow__pool_destroy(pool);
    if (out_rays) {
        *out_rays = 0;
        for (int i = 0; i < 256; ++i) *out_rays += j.rays[i];
    }
    free(c.lights);
    return GLOW_OK;
}

/* ------------------------------------------------------------------------ DDISH (render_ddish.c) */
struct glow__tracer {
    render_ctx c;
};

glow_result glow__tracer_create(const glow_render_scene *sc, const glow_scene_light *lights, uint32_t light_count,
                                const glow_render_settings *st, uint32_t max_depth, glow__tracer **out, char *message,
                                size_t message_size) {
    *out = NULL;
    glow__tracer *t = calloc(1, sizeof *t);
    if (!t) return glow__render_fail(message, message_size, GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", sc->path);
    glow_result r = probe_ctx_init(&t->c, sc, lights, light_count, st, message, message_size);
    if (r != GLOW_OK) {
        free(t);
        return r;
    }
    if (max_depth) t->c.max_depth = max_depth;
    *out = t;
    return GLOW_OK;
}

void glow__tracer_destroy(glow__tracer *t) {
    if (!t) return;
    free(t->c.lights);
    free(t);
}

void glow__tracer_incoming(const glow__tracer *t, glow__rng *r, const float o[3], const float w[3], bool cull_back,
                           float out[3], uint64_t *rays) {
    const render_ctx *c = &t->c;
    out[0] = out[1] = out[2] = 0.0f;
    float tnear = 0.0f;
    for (int passes = 0;; ++passes) {
        ++*rays;
        glow__hit h = glow__rt_intersect(c->sc->rt, o, w, tnear, INFINITY);
        if (h.tri == UINT32_MAX) return;
        if (cull_back && h.back_face) { /* culled: the ray goes on behind the face */
            if (passes >= 64) return;
            tnear = h.t + c->sc->eps;
            continue;
        }
        const float one[3] = {1.0f, 1.0f, 1.0f};
        continue_path(c, r, h, one, o, w, 0.0f, out, rays); /* pdf 0: no emitter NEE at the probe point */
        return;
    }
}

glow_result glow__view_render(const glow_render_scene *sc, const glow_render_settings *st, const glow_view *gv,
                              glow_render_result *out, char *message, size_t message_size) {
    if (message && message_size) message[0] = 0;
    if (out) memset(out, 0, sizeof *out);
    if (!out || !gv) return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render: NULL argument");
    glow_result r = check_settings(sc, st, message, message_size);
    if (r != GLOW_OK) return r;
    return render(sc, st, gv, out, message, message_size);
}
