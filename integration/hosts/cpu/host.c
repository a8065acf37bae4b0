/* host.c — glow_host (glow_host.h): CPU implementations of the runtime's lighting hook.
 *
 * Both kinds share the light models (point, spot with smoothstep falloff, sun) and the sky term;
 * they differ only in the visibility V of a light: one Embree occlusion ray (exact) or a PCF lookup
 * in a software depth map (shadow_map.c). Embree is used as precompute/src/rt.c uses it: one
 * triangle geometry of unwelded corners, robust build, rtcOccluded1 with a per-call context
 * (thread-safe). */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "glow/glow_host.h"
#include "shadow_map.h"
#include "host_math.h"
#include "host_log.h"

#define HOST_PI 3.14159265358979323846
#define SKY_UNSET 0xFFFFFFFFu
#define SPOT_MAX_SINGLE_MAP_DEG 60.0f

typedef struct host_light {
    glow_scene_light l;       /* direction normalised */
    float cos_outer, cos_inner;
    uint16_t gen;             /* exact kind with footprints: bumped when the light moves (its samples age) */
    glow__depth_map *maps;    /* shadow-map kind: 1 (ortho / persp) or 6 (cube); NULL otherwise */
    uint32_t map_count;
} host_light;

struct glow_host {
    glow_host_kind kind;
    glow_logger logger;
    const glow_bake *bake;
    uint32_t surfel_count, tri_count, own_tri_count; /* tri_count: own + occluders' */
    float *tris; /* tri_count x 9 floats, corners packed */
    float bmin[3], bmax[3], eps, diag;
    RTCDevice device;
    RTCScene scene;
    host_light *lights;
    uint32_t light_count;
    float env[3];
    glow_host_sky sky;
    uint32_t sky_rays;
    float *sky_dirs;             /* sky_rays x 3: cosine-distributed directions around +z */
    uint32_t *sky_order;         /* sky_rays: the rays by azimuth, traced 16 at a time (sky_open) */
    _Atomic uint32_t *sky_cache; /* surfel_count: bits of S, SKY_UNSET = not traced yet */
    /* the sky as SH (glow_host_set_environment_sh; docs/sky.md): when env_sh_on, the sky term is
     * max(0, Σ T_k L_k) with T the bake's transfer (SKYT) or, without it, traced per surfel on first use */
    bool env_sh_on;
    float env_sh[GLOW_SKY_SH_FLOATS];
    const float *bake_T;         /* [surfel_count][9] the bake's SKYT transfer, or NULL */
    float *sky_E;                /* with bake_T (traced sky): [surfel_count][3] max(0, Σ T L) for env_sh, computed by
                                    glow_host_set_environment_sh so the hook reads 3 floats (0.95 -> 0.32 ms a pass
                                    on Sponza) */
    _Atomic uint32_t *t_cache;   /* without bake_T, allocated by the first set_environment_sh: surfel_count x
                                    10, [0] SKY_UNSET until the 9 bits of T in [1..9] are stored */
    _Atomic uint32_t *origin_cache; /* 3 x surfel_count: bits of each surfel's ray origin, [0] SKY_UNSET = not yet */
    uint32_t sm_size, cube_size;
    glow__shadow_params sp;
    double shadow_map_ms;
    bool packets; /* exact kind: 16-ray packets (GLOW_HOST_PACKETS=0 in the environment turns them off) */
    /* footprints (exact kind, samples > 1; glow_host.h FOOTPRINTS) */
    uint32_t samples;
    struct foot_state *foot;  /* light_count x surfel_count (light-major); NULL when samples == 1 */
    _Atomic uint16_t *reach;  /* surfel_count: FOOT_REACH_DONE | bit k when point k is seen from the centre */
    struct { _Atomic uint64_t n; char pad[56]; } rays[64]; /* shadow rays by worker % 64 (glow_host_stats):
                                 one cache line each, one add per batch (a shared counter cost 17 % of the hook) */
    float foot_turn[256][2];  /* cos, sin of a surfel's turn (256 steps, picked by a hash of its index) */
    float foot_step[GLOW_HOST_SURFEL_SAMPLES_MAX][3]; /* point k: cos, sin of k golden angles; sqrt((k + 1/2) / K) */
    float foot_frac[1u << GLOW_HOST_SURFEL_SAMPLES_MAX]; /* popcount(bits) / K: foot_fraction without a division */
};

/* One surfel's footprint samples of one light: bit k of `bits` = point k reached by the light when last
 * traced; `next` = the point the next call re-traces; `fresh` = points traced since the light last
 * moved (gen = the light's gen then); `filled` = all K traced once. */
typedef struct foot_state {
    uint8_t bits, next, fresh, filled;
    uint16_t gen, pad;
} foot_state;
#define FOOT_REACH_DONE 0x8000u

/* ------------------------------------------------------------------------------ helpers */

/* logf_(logger, level, code, fmt, ...): host_log.h with this file's prefix and the caller's line */
#define logf_(lg, level, code, ...) glow__host_log((lg), "glow_host: ", (level), (code), __FILE__, __LINE__, __VA_ARGS__)
#define HOST_FAIL(lg, code, ...) logf_((lg), GLOW_LOG_ERROR, (code), __VA_ARGS__)
#define now_ms glow__host_now_ms

static const float *power_of(const glow_scene_light *l) {
    return l->type == GLOW_SCENE_LIGHT_SUN ? l->irradiance : l->intensity;
}

/* ------------------------------------------------------------------------------ Embree */

static void embree_error(void *user, enum RTCError code, const char *str) {
    logf_(user, GLOW_LOG_ERROR, GLOW_ERROR_UNSUPPORTED, "embree: error %d: %s", (int)code, str ? str : "");
}

static glow_result build_embree(glow_host *h) {
    h->device = rtcNewDevice(NULL);
    if (!h->device)
        return HOST_FAIL(&h->logger, GLOW_ERROR_UNSUPPORTED, "embree: cannot create a device (error %d)",
                         (int)rtcGetDeviceError(NULL));
    rtcSetDeviceErrorFunction(h->device, embree_error, &h->logger);
    h->scene = rtcNewScene(h->device);
    rtcSetSceneBuildQuality(h->scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(h->scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(h->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    uint32_t n = h->tri_count;
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), (size_t)3 * n);
    uint32_t *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), n);
    if (!v || !idx) {
        rtcReleaseGeometry(g);
        return HOST_FAIL(&h->logger, GLOW_ERROR_OUT_OF_MEMORY, "embree: out of memory for %u triangles", n);
    }
    memcpy(v, h->tris, (size_t)n * 9 * sizeof(float));
    for (uint32_t i = 0; i < 3 * n; ++i) idx[i] = i;
    rtcCommitGeometry(g);
    rtcAttachGeometry(h->scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(h->scene);
    if (rtcGetDeviceError(h->device) != RTC_ERROR_NONE) return GLOW_ERROR_UNSUPPORTED;
    return GLOW_OK;
}

static bool occluded(const glow_host *h, const float org[3], const float dir[3], float tfar) {
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay ray;
    memset(&ray, 0, sizeof ray);
    ray.org_x = org[0];
    ray.org_y = org[1];
    ray.org_z = org[2];
    ray.dir_x = dir[0];
    ray.dir_y = dir[1];
    ray.dir_z = dir[2];
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    ray.mask = 0xFFFFFFFFu;
    rtcOccluded1(h->scene, &ctx, &ray);
    return ray.tfar < 0.0f; /* Embree sets tfar = -inf on a hit */
}

/* ------------------------------------------------------------------------- light models */

typedef struct own_query {
    const glow_host *h;
    const float *p, *n;
    uint32_t best;
    float best_d2;
} own_query;

/* Point-query callback: the nearest triangle that faces the way the surfel does. */
static bool own_cb(struct RTCPointQueryFunctionArguments *args) {
    own_query *q = args->userPtr;
    if (args->primID >= q->h->tri_count) return false;
    const float *t = q->h->tris + 9 * (size_t)args->primID;
    float e1[3] = {t[3] - t[0], t[4] - t[1], t[5] - t[2]}, e2[3] = {t[6] - t[0], t[7] - t[1], t[8] - t[2]};
    float ng[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    float len = sqrtf(glow__dot3(ng, ng));
    if (!(len > 0.0f) || glow__dot3(ng, q->n) < 0.9f * len) return false;
    float c[3];
    glow__seam_closest_on_tri(q->p, t, t + 3, t + 6, c);
    float d[3] = {c[0] - q->p[0], c[1] - q->p[1], c[2] - q->p[2]}, d2 = glow__dot3(d, d);
    if (d2 >= q->best_d2) return false;
    q->best = args->primID;
    q->best_d2 = d2;
    return false;
}

/* The origin of every ray that leaves surface point p (front normal n): eps along n, against
 * self-hits, then up to eps along the surface towards the centre of the triangle p lies on (the
 * nearest triangle facing along n, found with an Embree point query). The second step matters for
 * surfels that lie exactly on an edge where another surface meets theirs (relaxation puts surfels
 * there: a floor surfel against a wall, a wall surfel at the ceiling's height, a room's corner): from
 * an origin inside the other surface's plane, a ray into that surface hits at t = 0 (not counted:
 * light leaks into a closed room) and a ray away from it may hit at t = +0 (false shadow). */
static void safe_origin(const glow_host *h, const float p[3], const float n[3], float o[3]) {
    for (int i = 0; i < 3; ++i) o[i] = p[i] + h->eps * n[i];
    if (!h->scene) return;
    struct RTCPointQuery pq;
    memset(&pq, 0, sizeof pq);
    pq.x = p[0];
    pq.y = p[1];
    pq.z = p[2];
    pq.radius = 4.0f * h->eps;
    struct RTCPointQueryContext pc;
    rtcInitPointQueryContext(&pc);
    own_query q = {h, p, n, UINT32_MAX, INFINITY};
    rtcPointQuery(h->scene, &pq, &pc, own_cb, &q);
    if (q.best == UINT32_MAX) return;
    const float *t = h->tris + 9 * (size_t)q.best;
    float v[3];
    for (int i = 0; i < 3; ++i) v[i] = (t[i] + t[3 + i] + t[6 + i]) * (1.0f / 3.0f) - p[i];
    float vn = glow__dot3(v, n);
    for (int i = 0; i < 3; ++i) v[i] -= vn * n[i];
    float len = sqrtf(glow__dot3(v, v));
    if (!(len > 1e-12f)) return;
    float step = fminf(h->eps, 0.5f * len) / len;
    for (int i = 0; i < 3; ++i) o[i] += step * v[i];
}

/* safe_origin, cached per surfel (UINT32_MAX = none). Racing workers store identical values. */
static void surfel_origin(const glow_host *h, const float p[3], const float n[3], uint32_t surfel, float o[3]) {
    if (surfel == UINT32_MAX || !h->origin_cache) {
        safe_origin(h, p, n, o);
        return;
    }
    _Atomic uint32_t *c = h->origin_cache + 3 * (size_t)surfel;
    uint32_t b0 = atomic_load_explicit(&c[0], memory_order_acquire);
    if (b0 != SKY_UNSET) {
        uint32_t b[3] = {b0, atomic_load_explicit(&c[1], memory_order_relaxed),
                         atomic_load_explicit(&c[2], memory_order_relaxed)};
        memcpy(o, b, sizeof b);
        return;
    }
    safe_origin(h, p, n, o);
    uint32_t b[3];
    memcpy(b, o, sizeof b);
    atomic_store_explicit(&c[1], b[1], memory_order_relaxed);
    atomic_store_explicit(&c[2], b[2], memory_order_relaxed);
    atomic_store_explicit(&c[0], b[0], memory_order_release);
}

/* Unshadowed geometry term f of the light at p (normal n): E = V * power * f. Also the unit
 * direction to the light and its distance (INFINITY for the sun). Returns 0 when the light cannot
 * reach the front face. */
static float light_term(const host_light *hl, const float p[3], const float n[3], float l[3], float *dist) {
    const glow_scene_light *L = &hl->l;
    if (L->type == GLOW_SCENE_LIGHT_SUN) {
        for (int i = 0; i < 3; ++i) l[i] = -L->direction[i];
        *dist = INFINITY;
        return fmaxf(glow__dot3(n, l), 0.0f);
    }
    float d[3] = {L->position[0] - p[0], L->position[1] - p[1], L->position[2] - p[2]};
    float d2 = glow__dot3(d, d);
    if (!(d2 > 1e-20f)) return 0.0f;
    float dl = sqrtf(d2);
    for (int i = 0; i < 3; ++i) l[i] = d[i] / dl;
    *dist = dl;
    float c = glow__dot3(n, l);
    if (!(c > 0.0f)) return 0.0f;
    float f = c / d2;
    if (L->type == GLOW_SCENE_LIGHT_SPOT) {
        float cos_theta = -glow__dot3(l, L->direction); /* angle between the axis and p - x_light */
        float t;
        if (hl->cos_inner > hl->cos_outer) {
            t = (cos_theta - hl->cos_outer) / (hl->cos_inner - hl->cos_outer);
            t = fminf(fmaxf(t, 0.0f), 1.0f);
        } else {
            t = cos_theta >= hl->cos_outer ? 1.0f : 0.0f;
        }
        f *= t * t * (3.0f - 2.0f * t);
    }
    return f;
}

/* V of one light at p (unit normal n, unit direction to the light l); `o` is the ray origin
 * (safe_origin), read by the exact kind only. */
static float visibility(const glow_host *h, const host_light *hl, const float p[3], const float n[3],
                        const float l[3], const float o[3]) {
    if (h->kind == GLOW_HOST_KIND_EXACT) {
        if (hl->l.type == GLOW_SCENE_LIGHT_SUN) return occluded(h, o, l, INFINITY) ? 0.0f : 1.0f;
        float v[3] = {hl->l.position[0] - o[0], hl->l.position[1] - o[1], hl->l.position[2] - o[2]};
        float dl = sqrtf(glow__dot3(v, v)), tfar = dl - h->eps; /* stop short of geometry at the light itself */
        if (!(tfar > 0.0f)) return 1.0f;
        for (int i = 0; i < 3; ++i) v[i] /= dl;
        return occluded(h, o, v, tfar) ? 0.0f : 1.0f;
    }
    if (!hl->maps) return 1.0f;
    const glow__depth_map *m = hl->maps;
    if (hl->map_count == 6) {
        float d[3] = {p[0] - hl->l.position[0], p[1] - hl->l.position[1], p[2] - hl->l.position[2]};
        m = &hl->maps[glow__dm_cube_face(d)];
    }
    return glow__dm_visibility(m, p, n, l, &h->sp);
}

/* Cosine-weighted visible fraction of the sky over n, traced. */
#define PACKET 16 /* rays a packet (rtcOccluded16): the sky's below, the lights' in the hook path */
static void ray_lane_idle(struct RTCRay16 *ray, uint32_t k) {
    ray->org_x[k] = ray->org_y[k] = ray->org_z[k] = 0.0f;
    ray->dir_x[k] = ray->dir_y[k] = 0.0f;
    ray->dir_z[k] = 1.0f;
    ray->tnear[k] = 0.0f;
    ray->tfar[k] = 0.0f;
    ray->time[k] = 0.0f;
    ray->mask[k] = 0xFFFFFFFFu;
    ray->id[k] = k;
    ray->flags[k] = 0;
}

/* Which of the sky's rays from o over the frame (tx, ty, n) are open: bit k of open[k / 64]. The rays
 * go to Embree 16 at a time in azimuth order (h->sky_order): the seam's directions are Hammersley
 * points with bit-reversed azimuth, so rays next to each other by index point to opposite sides, and
 * a packet of neighbours in azimuth shares most of its BVH walk (the linker's SKYT pass, the same
 * directions: 3.37 -> 2.66 s for 524,288 surfels). Each ray is the one occluded() traces (origin,
 * direction, tnear 0, tfar ∞), so the answers are its answers. */
#define SKY_MAX_RAYS 65536u
static void sky_open(const glow_host *h, const float o[3], const float tx[3], const float ty[3], const float n[3],
                     uint64_t *open) {
    const uint32_t N = h->sky_rays;
    memset(open, 0, ((size_t)N + 63u) / 64u * sizeof *open);
    if (!h->packets) { /* GLOW_HOST_PACKETS=0: one ray at a time, in index order */
        for (uint32_t k = 0; k < N; ++k) {
            const float *sd = h->sky_dirs + 3 * (size_t)k;
            float d[3];
            for (int i = 0; i < 3; ++i) d[i] = sd[0] * tx[i] + sd[1] * ty[i] + sd[2] * n[i];
            if (!occluded(h, o, d, INFINITY)) open[k / 64u] |= (uint64_t)1 << (k % 64u);
        }
        return;
    }
    for (uint32_t k0 = 0; k0 < N; k0 += PACKET) {
        _Alignas(64) struct RTCRay16 ray;
        _Alignas(64) int valid[PACKET];
        for (uint32_t q = 0; q < PACKET; ++q) {
            ray_lane_idle(&ray, q);
            valid[q] = 0;
            if (k0 + q >= N) continue;
            const float *sd = h->sky_dirs + 3 * (size_t)h->sky_order[k0 + q];
            ray.org_x[q] = o[0];
            ray.org_y[q] = o[1];
            ray.org_z[q] = o[2];
            ray.dir_x[q] = sd[0] * tx[0] + sd[1] * ty[0] + sd[2] * n[0];
            ray.dir_y[q] = sd[0] * tx[1] + sd[1] * ty[1] + sd[2] * n[1];
            ray.dir_z[q] = sd[0] * tx[2] + sd[1] * ty[2] + sd[2] * n[2];
            ray.tfar[q] = INFINITY;
            valid[q] = -1;
        }
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        rtcOccluded16(valid, h->scene, &ctx, &ray);
        for (uint32_t q = 0; q < PACKET && k0 + q < N; ++q)
            if (!(ray.tfar[q] < 0.0f)) { /* Embree sets tfar = -inf on a hit */
                const uint32_t k = h->sky_order[k0 + q];
                open[k / 64u] |= (uint64_t)1 << (k % 64u);
            }
    }
}

static float trace_sky(const glow_host *h, const float o[3], const float n[3]) {
    float tx[3], ty[3];
    glow__onb(n, tx, ty);
    uint64_t open[SKY_MAX_RAYS / 64u];
    sky_open(h, o, tx, ty, n, open);
    uint32_t count = 0;
    for (uint32_t w = 0; w < (h->sky_rays + 63u) / 64u; ++w) count += (uint32_t)__builtin_popcountll(open[w]);
    return (float)count / (float)h->sky_rays;
}

/* The sky transfer of one point, traced from origin o over n: T_k = π/N Σ_open y_k over the same
 * cosine-distributed rays as trace_sky, so that with a constant sky Σ T_k L_k = L π S exactly. */
static void trace_sky_T(const glow_host *h, const float o[3], const float n[3], float T[9]) {
    float tx[3], ty[3];
    glow__onb(n, tx, ty);
    double acc[9] = {0};
    uint64_t open[SKY_MAX_RAYS / 64u];
    sky_open(h, o, tx, ty, n, open);
    for (uint32_t k = 0; k < h->sky_rays; ++k) { /* summed in the rays' own order */
        if (!(open[k / 64u] >> (k % 64u) & 1u)) continue;
        const float *s = h->sky_dirs + 3 * (size_t)k;
        float d[3], y[9];
        for (int i = 0; i < 3; ++i) d[i] = s[0] * tx[i] + s[1] * ty[i] + s[2] * n[i];
        glow_sh_eval(3, d, y);
        for (int q = 0; q < 9; ++q) acc[q] += y[q];
    }
    for (int q = 0; q < 9; ++q) T[q] = (float)(acc[q] * HOST_PI / (double)h->sky_rays);
}

static bool sky_on(const glow_host *h) {
    return h->env_sh_on || h->env[0] > 0.0f || h->env[1] > 0.0f || h->env[2] > 0.0f;
}
static void irradiance_sky(const glow_host *h, const float p[3], const float n[3], uint32_t surfel, float out[3]);

/* ------------------------------------------------------------------------- footprints */
static uint32_t foot_hash(uint32_t x) { /* lowbias32 */
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* The tables of foot_offset (no trigonometry per ray: measured 0.94 -> 1.60 ms per hook pass with
 * cosf/sinf per ray on Sponza, 32k surfels, a moving sun). */
static void foot_tables(glow_host *h) {
    for (int i = 0; i < 256; ++i) {
        const double a = 2.0 * HOST_PI * (i + 0.5) / 256.0;
        h->foot_turn[i][0] = (float)cos(a);
        h->foot_turn[i][1] = (float)sin(a);
    }
    for (uint32_t k = 0; k < GLOW_HOST_SURFEL_SAMPLES_MAX; ++k) {
        const double a = 2.399963229728653 * k; /* the golden angle */
        h->foot_step[k][0] = (float)cos(a);
        h->foot_step[k][1] = (float)sin(a);
        h->foot_step[k][2] = k < h->samples ? (float)sqrt((k + 0.5) / h->samples) : 0.0f;
    }
    for (uint32_t b = 0; b < (1u << GLOW_HOST_SURFEL_SAMPLES_MAX); ++b)
        h->foot_frac[b] = (float)__builtin_popcount(b & ((1u << h->samples) - 1u)) / (float)h->samples;
}

/* A surfel's footprint: the ray origin o of its centre, the tangent frame tx, ty of its normal
 * (glow__onb), its turn (one of 256, a hash of its index; foot_turn) and its disk's radius
 * sqrt(area / pi). Worked out once per surfel and call, for all its points and lights (with the
 * branch-free origin in foot_ray, the constant sky read inline in add_sky and no division in
 * foot_record / foot_fraction: the hook alone 2.28 -> 1.72 ms of CPU on Sponza, 32k surfels, a
 * turning sun, one thread, 2026-11-29). */
typedef struct foot_frame {
    float o[3], tx[3], ty[3], radius;
    const float *turn;
} foot_frame;

static void foot_frame_of(const glow_host *h, const float p[3], const float n[3], uint32_t surfel, foot_frame *fr) {
    surfel_origin(h, p, n, surfel, fr->o);
    glow__onb(n, fr->tx, fr->ty);
    fr->turn = h->foot_turn[foot_hash(surfel) >> 24];
    fr->radius = p[3] > 0.0f ? sqrtf(p[3] * (float)(1.0 / HOST_PI)) : 0.0f;
}

/* Point k of a surfel's footprint as an offset from its centre: unit tangent direction dir and length
 * *len (glow_host.h FOOTPRINTS). Point k is k golden angles past the surfel's turn at radius
 * sqrt((k + 1/2) / K) of the disk's. */
static inline void foot_offset(const glow_host *h, const foot_frame *fr, uint32_t k, float dir[3], float *len) {
    const float *t = fr->turn, *st = h->foot_step[k];
    const float c = t[0] * st[0] - t[1] * st[1], sn = t[1] * st[0] + t[0] * st[1];
    for (int i = 0; i < 3; ++i) dir[i] = c * fr->tx[i] + sn * fr->ty[i];
    *len = fr->radius * st[2];
}

/* The points of `surfel`'s footprint that its centre sees along the surface: traced on first use
 * and kept (the same for every light). */
static uint32_t foot_reach(glow_host *h, const foot_frame *fr, uint32_t surfel) {
    uint16_t m = atomic_load_explicit(&h->reach[surfel], memory_order_relaxed);
    if (m & FOOT_REACH_DONE) return m;
    m = FOOT_REACH_DONE;
    for (uint32_t k = 0; k < h->samples; ++k) {
        float d[3], len;
        foot_offset(h, fr, k, d, &len);
        if (!(len > 0.0f) || !occluded(h, fr->o, d, len)) m |= (uint16_t)(1u << k);
    }
    atomic_store_explicit(&h->reach[surfel], m, memory_order_relaxed);
    return m;
}

/* Ray k of a surfel towards light hl: its origin (the footprint point, or the centre when the point
 * is not reached along the surface), direction and tfar. False when the light is at the origin
 * (V = 1 without a ray). l: unit direction from the centre to the light (the sun's direction). */
static inline bool foot_ray(const glow_host *h, const host_light *hl, const foot_frame *fr, uint32_t reach, uint32_t k,
                            const float l[3], float org[3], float dir[3], float *tfar) {
    float d[3], len;
    foot_offset(h, fr, k, d, &len);
    len *= (float)((reach >> k) & 1u); /* 0: the centre (o + 0 d = o); a branch here mispredicts */
    for (int i = 0; i < 3; ++i) org[i] = fr->o[i] + len * d[i];
    if (hl->l.type == GLOW_SCENE_LIGHT_SUN) {
        memcpy(dir, l, 3 * sizeof(float));
        *tfar = INFINITY;
        return true;
    }
    float v[3] = {hl->l.position[0] - org[0], hl->l.position[1] - org[1], hl->l.position[2] - org[2]};
    const float dl = sqrtf(glow__dot3(v, v));
    *tfar = dl - h->eps;
    if (!(*tfar > 0.0f)) return false;
    for (int i = 0; i < 3; ++i) dir[i] = v[i] / dl;
    return true;
}

static float foot_fraction(const glow_host *h, const foot_state *st) { return h->foot_frac[st->bits]; }

/* Which point of st a call traces in round r (rounds 0..K-1): every point while the surfel is not
 * filled, else point `next` in round 0 while fewer than K are fresh; UINT32_MAX = none. */
static uint32_t foot_pick(const glow_host *h, const foot_state *st, uint32_t r) {
    if (!st->filled) return r;
    return r == 0 && st->fresh < h->samples ? st->next : UINT32_MAX;
}

static void foot_record(const glow_host *h, foot_state *st, uint32_t k, bool lit) {
    st->bits = (uint8_t)(lit ? st->bits | (1u << k) : st->bits & ~(1u << k));
    if (st->filled) {
        st->next = (uint8_t)(st->next + 1u < h->samples ? st->next + 1u : 0u); /* no division */
        st->fresh++;
    }
}

/* Before a call's rounds: a light that moved since the surfel's samples were fresh ages them all. */
static void foot_begin(const host_light *hl, foot_state *st) {
    if (st->filled && st->gen != hl->gen) {
        st->fresh = 0;
        st->gen = hl->gen;
    }
}

/* After a call's rounds: a surfel traced in full is filled and fresh. */
static void foot_end(const glow_host *h, const host_light *hl, foot_state *st) {
    if (!st->filled) {
        st->filled = 1;
        st->fresh = (uint8_t)h->samples;
        st->next = 0;
        st->gen = hl->gen;
    }
}

/* V of light li over `surfel`'s footprint, one ray at a time (the hook without packets). */
static float foot_visibility(const glow_host *h, uint32_t li, const float p[3], const float n[3], float area,
                             uint32_t surfel, const float o[3], const float l[3], uint64_t *rays) {
    (void)p;
    glow_host *hm = (glow_host *)h; /* the footprint state: written by the one worker lighting this surfel */
    const host_light *hl = &h->lights[li];
    foot_frame fr;
    glow__onb(n, fr.tx, fr.ty);
    memcpy(fr.o, o, sizeof fr.o);
    fr.turn = h->foot_turn[foot_hash(surfel) >> 24];
    fr.radius = area > 0.0f ? sqrtf(area * (float)(1.0 / HOST_PI)) : 0.0f;
    const uint32_t reach = foot_reach(hm, &fr, surfel);
    foot_state *st = &hm->foot[(size_t)li * h->surfel_count + surfel];
    foot_begin(hl, st);
    for (uint32_t r = 0; r < h->samples; ++r) {
        const uint32_t k = foot_pick(h, st, r);
        if (k == UINT32_MAX) break;
        float org[3], dir[3], tfar;
        bool lit = true;
        if (foot_ray(h, hl, &fr, reach, k, l, org, dir, &tfar)) {
            lit = !occluded(h, org, dir, tfar);
            ++*rays;
        }
        foot_record(h, st, k, lit);
    }
    foot_end(h, hl, st);
    return foot_fraction(h, st);
}

/* E at p, n. `surfel` indexes the sky cache and the footprint samples (its area: the footprint's),
 * UINT32_MAX = none (trace afresh, one ray from p). */
static uint64_t irradiance_at(const glow_host *h, const float p[3], const float n[3], uint32_t surfel, float area,
                              float out[3]) {
    uint64_t rays = 0;
    out[0] = out[1] = out[2] = 0.0f;
    float o[3];
    bool have_o = false;
    for (uint32_t i = 0; i < h->light_count; ++i) {
        const host_light *hl = &h->lights[i];
        const float *pw = power_of(&hl->l);
        if (pw[0] == 0.0f && pw[1] == 0.0f && pw[2] == 0.0f) continue;
        float l[3], dist;
        float f = light_term(hl, p, n, l, &dist);
        if (!(f > 0.0f)) continue;
        if (h->kind == GLOW_HOST_KIND_EXACT && !have_o) {
            surfel_origin(h, p, n, surfel, o);
            have_o = true;
        }
        if (h->foot && surfel != UINT32_MAX) {
            f *= foot_visibility(h, i, p, n, area, surfel, o, l, &rays);
        } else {
            f *= visibility(h, hl, p, n, l, o);
            rays += h->kind == GLOW_HOST_KIND_EXACT;
        }
        for (int c = 0; c < 3; ++c) out[c] += f * pw[c];
    }
    if (!sky_on(h)) return rays;
    float e[3];
    irradiance_sky(h, p, n, surfel, e);
    for (int c = 0; c < 3; ++c) out[c] += e[c];
    return rays;
}

/* The sky term env · π · S at p, n (S cached per surfel, or traced). */
static float sky_S(const glow_host *h, const float p[3], const float n[3], uint32_t surfel) {
    /* S: the cached value (supplied, or traced by an earlier call) wins; else trace it (TRACED) and
     * cache it when this is a surfel; else 1 (UNSHADOWED). Two workers racing on one surfel would
     * both store the same deterministic value; the relaxed atomics keep that well-defined. */
    float S = 1.0f;
    uint32_t bits = SKY_UNSET;
    if (surfel != UINT32_MAX) bits = atomic_load_explicit(&h->sky_cache[surfel], memory_order_relaxed);
    if (bits != SKY_UNSET) {
        memcpy(&S, &bits, sizeof S);
    } else if (h->sky == GLOW_HOST_SKY_TRACED && h->scene) {
        float o[3];
        surfel_origin(h, p, n, surfel, o);
        S = trace_sky(h, o, n);
        if (surfel != UINT32_MAX) {
            memcpy(&bits, &S, sizeof bits);
            atomic_store_explicit(&h->sky_cache[surfel], bits, memory_order_relaxed);
        }
    }
    return S;
}

/* The sky transfer T at p, n: the bake's (SKYT) for a surfel of a bake that has it, else cached per
 * surfel or traced as sky_S does; for GLOW_HOST_SKY_UNSHADOWED the unoccluded cosine lobe
 * T_k = Â_l y_k(n), Â = (π, 2π/3, π/4). Returns T (the bake's row, or `buf`). */
static const float *sky_T(const glow_host *h, const float p[3], const float n[3], uint32_t surfel, float buf[9]) {
    if (h->sky == GLOW_HOST_SKY_UNSHADOWED || !h->scene) {
        glow_sh_eval(3, n, buf);
        for (int q = 0; q < 9; ++q) buf[q] *= q == 0 ? (float)HOST_PI : q < 4 ? (float)(2.0 * HOST_PI / 3.0) : (float)(HOST_PI / 4.0);
        return buf;
    }
    if (surfel != UINT32_MAX && h->bake_T) return h->bake_T + 9 * (size_t)surfel;
    _Atomic uint32_t *c = surfel != UINT32_MAX && h->t_cache ? h->t_cache + 10 * (size_t)surfel : NULL;
    if (c && atomic_load_explicit(&c[0], memory_order_acquire) != SKY_UNSET) {
        for (int q = 0; q < 9; ++q) {
            const uint32_t b = atomic_load_explicit(&c[1 + q], memory_order_relaxed);
            memcpy(&buf[q], &b, sizeof b);
        }
        return buf;
    }
    float o[3];
    surfel_origin(h, p, n, surfel, o);
    trace_sky_T(h, o, n, buf);
    if (c) { /* racing workers store the same values */
        for (int q = 0; q < 9; ++q) {
            uint32_t b;
            memcpy(&b, &buf[q], sizeof b);
            atomic_store_explicit(&c[1 + q], b, memory_order_relaxed);
        }
        atomic_store_explicit(&c[0], 0u, memory_order_release);
    }
    return buf;
}

static void irradiance_sky(const glow_host *h, const float p[3], const float n[3], uint32_t surfel, float out[3]) {
    if (h->env_sh_on && h->sky_E && surfel != UINT32_MAX) {
        memcpy(out, h->sky_E + 3 * (size_t)surfel, 3 * sizeof *out);
        return;
    }
    if (h->env_sh_on) {
        float buf[9];
        glow_sh_sky_irradiance(sky_T(h, p, n, surfel, buf), h->env_sh, out);
        return;
    }
    const float S = sky_S(h, p, n, surfel);
    for (int c = 0; c < 3; ++c) out[c] = h->env[c] * (float)HOST_PI * S;
}

glow_result glow_host_sky_visibility(glow_host *h, const glow_surfel_view *v, float *out, uint32_t count) {
    if (!h || !v || !out || !v->positions || !v->normals) return GLOW_ERROR_INVALID_ARGUMENT;
    if (count != h->surfel_count || v->count != h->surfel_count) {
        HOST_FAIL(&h->logger, GLOW_ERROR_INVALID_ARGUMENT,
                  "glow_host_sky_visibility: %u values / %u surfels given, the bake has %u surfels", count, v->count,
                  h->surfel_count);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    for (uint32_t i = 0; i < count; ++i) out[i] = sky_S(h, v->positions + 4 * (size_t)i, v->normals + 4 * (size_t)i, i);
    return GLOW_OK;
}

/* The exact kind's hook path: the shadow rays of 16 consecutive surfels go to Embree as one
 * packet per light (rtcOccluded16, coherent flag). Consecutive surfels are neighbours (the bake
 * orders them along the hierarchy), so a packet shares most of its BVH walk: measured 1.10 ->
 * 0.74 ms per hook pass on Sponza (32k surfels, sun, 2 threads; alternating runs with
 * GLOW_HOST_PACKETS=0, docs/benchmarks.md). Each ray is the one
 * irradiance_at would trace (same origin, direction, tfar), so the result is the same V; the sky
 * term then goes through irradiance_at's cached path. */

/* Adds the sky term of surfels [i0, i0 + count) of the batch to out (irradiance_at without lights). */
static void add_sky(const glow_host *h, const glow_surfel_batch *batch, uint32_t i0, uint32_t count, float *out) {
    if (!sky_on(h)) return;
    if (!h->env_sh_on) { /* a constant sky: env · π · S with S cached (sky_S's first case), without a call a surfel */
        const float e[3] = {h->env[0] * (float)HOST_PI, h->env[1] * (float)HOST_PI, h->env[2] * (float)HOST_PI};
        for (uint32_t k = 0; k < count; ++k) {
            const uint32_t bits = atomic_load_explicit(&h->sky_cache[batch->first + i0 + k], memory_order_relaxed);
            float S;
            if (bits != SKY_UNSET) {
                memcpy(&S, &bits, sizeof S);
            } else {
                const float *p = batch->positions + 4 * (size_t)(i0 + k), *n = batch->normals + 4 * (size_t)(i0 + k);
                S = sky_S(h, p, n, batch->first + i0 + k);
            }
            for (int c = 0; c < 3; ++c) out[3 * (size_t)(i0 + k) + c] += e[c] * S;
        }
        return;
    }
    for (uint32_t k = 0; k < count; ++k) {
        const float *p = batch->positions + 4 * (size_t)(i0 + k), *n = batch->normals + 4 * (size_t)(i0 + k);
        float e[3];
        irradiance_sky(h, p, n, batch->first + i0 + k, e);
        for (int c = 0; c < 3; ++c) out[3 * (size_t)(i0 + k) + c] += e[c];
    }
}

/* Lane k of a packet as an idle ray (the packet paths fill the lanes they trace over it). */
static uint64_t light_packet(const glow_host *h, const glow_surfel_batch *batch, uint32_t i0, uint32_t count, float *out) {
    uint64_t traced = 0;
    float o[PACKET][3];
    for (uint32_t k = 0; k < count; ++k) {
        const float *p = batch->positions + 4 * (size_t)(i0 + k), *n = batch->normals + 4 * (size_t)(i0 + k);
        surfel_origin(h, p, n, batch->first + i0 + k, o[k]);
        for (int c = 0; c < 3; ++c) out[3 * (size_t)(i0 + k) + c] = 0.0f;
    }
    for (uint32_t li = 0; li < h->light_count; ++li) {
        const host_light *hl = &h->lights[li];
        const float *pw = power_of(&hl->l);
        if (pw[0] == 0.0f && pw[1] == 0.0f && pw[2] == 0.0f) continue;
        struct RTCRay16 ray;
        RTC_ALIGN(64) int valid[PACKET]; /* Embree reads the mask as one vector: 64-byte aligned */
        float f[PACKET];
        bool any = false;
        for (uint32_t k = 0; k < PACKET; ++k) {
            valid[k] = 0;
            f[k] = 0.0f;
            ray_lane_idle(&ray, k);
            if (k >= count) continue;
            const float *p = batch->positions + 4 * (size_t)(i0 + k), *n = batch->normals + 4 * (size_t)(i0 + k);
            float l[3], dist;
            f[k] = light_term(hl, p, n, l, &dist);
            if (!(f[k] > 0.0f)) continue;
            float d[3] = {l[0], l[1], l[2]}, tfar = INFINITY;
            if (hl->l.type != GLOW_SCENE_LIGHT_SUN) { /* as visibility(): from o, stopping eps short */
                float v[3] = {hl->l.position[0] - o[k][0], hl->l.position[1] - o[k][1], hl->l.position[2] - o[k][2]};
                float dl = sqrtf(glow__dot3(v, v));
                tfar = dl - h->eps;
                if (!(tfar > 0.0f)) continue; /* V = 1: f[k] stays, the ray stays invalid */
                for (int c = 0; c < 3; ++c) d[c] = v[c] / dl;
            }
            ray.org_x[k] = o[k][0];
            ray.org_y[k] = o[k][1];
            ray.org_z[k] = o[k][2];
            ray.dir_x[k] = d[0];
            ray.dir_y[k] = d[1];
            ray.dir_z[k] = d[2];
            ray.tfar[k] = tfar;
            valid[k] = -1;
            any = true;
        }
        if (any) {
            struct RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            rtcOccluded16(valid, h->scene, &ctx, &ray);
            for (uint32_t k = 0; k < PACKET; ++k) traced += valid[k] != 0;
        }
        for (uint32_t k = 0; k < count; ++k) {
            if (!(f[k] > 0.0f)) continue;
            if (valid[k] && ray.tfar[k] < 0.0f) continue; /* Embree sets tfar = -inf on a hit */
            for (int c = 0; c < 3; ++c) out[3 * (size_t)(i0 + k) + c] += f[k] * pw[c];
        }
    }
    add_sky(h, batch, i0, count, out);
    return traced;
}

/* All lanes of a packet as idle rays (GCC inlines ray_lane_idle and vectorises the loop). */
static void ray_packet_idle(struct RTCRay16 *ray) {
    for (uint32_t k = 0; k < PACKET; ++k) ray_lane_idle(ray, k);
}

/* light_packet with footprints (h->foot): per light, rounds of up to 16 rays (one per surfel: all K
 * points of surfels not yet filled, else the one point each call re-traces), then V = the fraction of
 * the surfel's K points that the light reaches. Each ray is the one foot_visibility would trace.
 * The surfels the light faces are listed first (lit[]) and every later loop runs over that list: a
 * test of f > 0 per lane and loop mispredicted about half the time on a sunlit scene (about half the
 * surfels face away), and with four such loops the bookkeeping cost more than the rays (Sponza, 32k
 * surfels, a turning sun: see docs/benchmarks.md). Lanes keep their positions in the packet. */
static uint64_t light_packet_foot(glow_host *h, const glow_surfel_batch *batch, uint32_t i0, uint32_t count, float *out) {
    foot_frame fr[PACKET];
    uint32_t reach[PACKET]; /* 0 until a ray of the surfel needs its frame and reach (then FOOT_REACH_DONE | ...) */
    for (uint32_t k = 0; k < count; ++k) {
        reach[k] = 0;
        for (int c = 0; c < 3; ++c) out[3 * (size_t)(i0 + k) + c] = 0.0f;
    }
    uint64_t traced = 0;
    for (uint32_t li = 0; li < h->light_count; ++li) {
        const host_light *hl = &h->lights[li];
        const float *pw = power_of(&hl->l);
        if (pw[0] == 0.0f && pw[1] == 0.0f && pw[2] == 0.0f) continue;
        float f[PACKET], l[PACKET][3];
        uint32_t lit[PACKET], n = 0; /* the lanes the light faces (f > 0), ascending */
        for (uint32_t k = 0; k < count; ++k) {
            const float *p = batch->positions + 4 * (size_t)(i0 + k), *nr = batch->normals + 4 * (size_t)(i0 + k);
            float dist;
            f[k] = light_term(hl, p, nr, l[k], &dist);
            lit[n] = k;
            n += f[k] > 0.0f;
        }
        if (!n) continue;
        foot_state *st[PACKET]; /* of lane lit[j] */
        bool unfilled = false;
        foot_state *const st0 = h->foot + (size_t)li * h->surfel_count + batch->first + i0;
        for (uint32_t j = 0; j < n; ++j) {
            st[j] = st0 + lit[j];
            foot_begin(hl, st[j]);
            unfilled |= !st[j]->filled;
        }
        for (uint32_t r = 0; r < (unfilled ? h->samples : 1u); ++r) {
            struct RTCRay16 ray;
            RTC_ALIGN(64) int valid[PACKET] = {0}; /* Embree reads the mask as one vector: 64-byte aligned */
            uint32_t pick[PACKET];
            bool any = false, picked = false;
            ray_packet_idle(&ray);
            for (uint32_t j = 0; j < n; ++j) {
                const uint32_t k = lit[j];
                pick[j] = foot_pick(h, st[j], r);
                if (pick[j] == UINT32_MAX) continue;
                picked = true;
                if (!reach[k]) {
                    const uint32_t surfel = batch->first + i0 + k;
                    foot_frame_of(h, batch->positions + 4 * (size_t)(i0 + k), batch->normals + 4 * (size_t)(i0 + k),
                                  surfel, &fr[k]);
                    reach[k] = foot_reach(h, &fr[k], surfel);
                }
                float org[3], dir[3], tfar;
                if (!foot_ray(h, hl, &fr[k], reach[k], pick[j], l[k], org, dir, &tfar))
                    continue; /* the light at the point: lit, no ray (the lane stays idle) */
                ray.org_x[k] = org[0];
                ray.org_y[k] = org[1];
                ray.org_z[k] = org[2];
                ray.dir_x[k] = dir[0];
                ray.dir_y[k] = dir[1];
                ray.dir_z[k] = dir[2];
                ray.tfar[k] = tfar;
                valid[k] = -1;
                any = true;
            }
            if (!picked) break;
            if (any) {
                struct RTCIntersectContext ctx;
                rtcInitIntersectContext(&ctx);
                ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
                rtcOccluded16(valid, h->scene, &ctx, &ray);
            }
            for (uint32_t j = 0; j < n; ++j) {
                if (pick[j] == UINT32_MAX) continue;
                const uint32_t k = lit[j];
                traced += valid[k] != 0;
                foot_record(h, st[j], pick[j], !(valid[k] && ray.tfar[k] < 0.0f)); /* Embree: tfar = -inf on a hit */
            }
        }
        for (uint32_t j = 0; j < n; ++j) {
            const uint32_t k = lit[j];
            foot_end(h, hl, st[j]);
            const float v = f[k] * foot_fraction(h, st[j]);
            for (int c = 0; c < 3; ++c) out[3 * (size_t)(i0 + k) + c] += v * pw[c];
        }
    }
    add_sky(h, batch, i0, count, out);
    return traced;
}

static glow_result light_surfels(void *user, const glow_surfel_batch *batch, float *out, uint32_t worker) {
    const glow_host *h = user;
    if (!h || !batch || !out || (batch->count && (!batch->positions || !batch->normals))) return GLOW_ERROR_INVALID_ARGUMENT;
    if ((uint64_t)batch->first + batch->count > h->surfel_count)
        return HOST_FAIL(&h->logger, GLOW_ERROR_INVALID_ARGUMENT,
                         "surfel batch [%u, %u) is outside the bake's %u surfels (a host made for another bake?)",
                         batch->first, batch->first + batch->count, h->surfel_count);
    if (h->kind == GLOW_HOST_KIND_EXACT && h->scene && h->packets) {
        uint64_t traced = 0;
        for (uint32_t i = 0; i < batch->count; i += PACKET) {
            const uint32_t c = batch->count - i < PACKET ? batch->count - i : PACKET;
            traced += h->foot ? light_packet_foot((glow_host *)h, batch, i, c, out) : light_packet(h, batch, i, c, out);
        }
        atomic_fetch_add_explicit(&((glow_host *)h)->rays[worker % 64u].n, traced, memory_order_relaxed);
        return GLOW_OK;
    }
    uint64_t traced = 0;
    for (uint32_t i = 0; i < batch->count; ++i) {
        const float *p = batch->positions + 4 * (size_t)i, *n = batch->normals + 4 * (size_t)i;
        traced += irradiance_at(h, p, n, batch->first + i, p[3], out + 3 * (size_t)i);
    }
    atomic_fetch_add_explicit(&((glow_host *)h)->rays[worker % 64u].n, traced, memory_order_relaxed);
    return GLOW_OK;
}

/* ---------------------------------------------------------------------------- lights */

static void free_maps(host_light *hl) {
    if (!hl->maps) return;
    for (uint32_t m = 0; m < hl->map_count; ++m) glow__dm_free(&hl->maps[m]);
    free(hl->maps);
    hl->maps = NULL;
    hl->map_count = 0;
}

static glow_result render_maps(glow_host *h, host_light *hl) {
    free_maps(hl);
    if (h->kind != GLOW_HOST_KIND_SHADOW_MAP) return GLOW_OK;
    const glow_scene_light *L = &hl->l;
    bool cube = L->type == GLOW_SCENE_LIGHT_POINT ||
                (L->type == GLOW_SCENE_LIGHT_SPOT && L->outer_deg > SPOT_MAX_SINGLE_MAP_DEG);
    uint32_t count = cube ? 6 : 1;
    hl->maps = calloc(count, sizeof *hl->maps);
    if (!hl->maps) return HOST_FAIL(&h->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for shadow maps");
    hl->map_count = count;
    uint32_t margin = (uint32_t)h->sp.pcf_radius + 2;
    float near_z = 1e-3f * h->diag;
    if (L->type == GLOW_SCENE_LIGHT_SUN)
        glow__dm_setup_ortho(&hl->maps[0], L->direction, h->bmin, h->bmax, h->sm_size, margin);
    else if (cube)
        glow__dm_setup_cube(hl->maps, L->position, h->cube_size, margin, near_z);
    else
        glow__dm_setup_persp(&hl->maps[0], L->position, L->direction,
                             tanf(L->outer_deg * (float)(HOST_PI / 180.0)), h->sm_size, margin, near_z);
    for (uint32_t m = 0; m < count; ++m) {
        if (!glow__dm_render(&hl->maps[m], h->tris, h->tri_count)) {
            free_maps(hl);
            return HOST_FAIL(&h->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for a %u² shadow map",
                             cube ? h->cube_size : h->sm_size);
        }
    }
    return GLOW_OK;
}

/* Validates and normalises a light into *out (no maps). */
static glow_result prepare_light(const glow_host *h, const glow_scene_light *in, uint32_t index, host_light *out) {
    char what[48], msg[512];
    snprintf(what, sizeof what, "lights[%u]", index);
    glow_result r = glow_scene_light_validate(in, what, msg, sizeof msg);
    if (r != GLOW_OK) return HOST_FAIL(&h->logger, r, "%s", msg);
    memset(out, 0, sizeof *out);
    out->l = *in;
    if (in->type != GLOW_SCENE_LIGHT_POINT) glow__normalize3(in->direction, out->l.direction);
    if (in->type == GLOW_SCENE_LIGHT_SPOT) {
        out->cos_outer = cosf(in->outer_deg * (float)(HOST_PI / 180.0));
        out->cos_inner = cosf(in->inner_deg * (float)(HOST_PI / 180.0));
    }
    return GLOW_OK;
}

glow_result glow_host_set_light(glow_host *host, uint32_t index, const glow_scene_light *light) {
    if (!host || !light) return GLOW_ERROR_INVALID_ARGUMENT;
    if (index >= host->light_count)
        return HOST_FAIL(&host->logger, GLOW_ERROR_INVALID_ARGUMENT, "light index %u out of range (%u lights)", index,
                         host->light_count);
    host_light nl;
    glow_result r = prepare_light(host, light, index, &nl);
    if (r != GLOW_OK) return r;
    double t0 = now_ms();
    if ((r = render_maps(host, &nl)) != GLOW_OK) return r;
    if (host->kind == GLOW_HOST_KIND_SHADOW_MAP) host->shadow_map_ms = now_ms() - t0;
    free_maps(&host->lights[index]);
    const glow_scene_light *a = &host->lights[index].l, *b = &nl.l;
    const bool moved = a->type != b->type || memcmp(a->position, b->position, sizeof a->position) != 0 ||
                       memcmp(a->direction, b->direction, sizeof a->direction) != 0 || a->outer_deg != b->outer_deg ||
                       a->inner_deg != b->inner_deg;
    nl.gen = (uint16_t)(host->lights[index].gen + (moved ? 1u : 0u)); /* footprint samples age when it moves */
    host->lights[index] = nl;
    return GLOW_OK;
}

glow_result glow_host_set_lights(glow_host *host, const glow_scene_light *lights, uint32_t count) {
    if (!host || (count && !lights)) return GLOW_ERROR_INVALID_ARGUMENT;
    host_light *nl = count ? calloc(count, sizeof *nl) : NULL;
    if (count && !nl) return HOST_FAIL(&host->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u lights", count);
    glow_result r = GLOW_OK;
    for (uint32_t i = 0; i < count && r == GLOW_OK; ++i) r = prepare_light(host, &lights[i], i, &nl[i]);
    double t0 = now_ms();
    for (uint32_t i = 0; i < count && r == GLOW_OK; ++i) r = render_maps(host, &nl[i]);
    if (r != GLOW_OK) {
        for (uint32_t i = 0; i < count; ++i) free_maps(&nl[i]);
        free(nl);
        return r;
    }
    if (host->kind == GLOW_HOST_KIND_SHADOW_MAP) host->shadow_map_ms = now_ms() - t0;
    if (host->samples > 1 && host->surfel_count) { /* footprints: every light starts unfilled */
        foot_state *nf = count ? calloc((size_t)count * host->surfel_count, sizeof *nf) : NULL;
        if (count && !nf) {
            for (uint32_t i = 0; i < count; ++i) free_maps(&nl[i]);
            free(nl);
            return HOST_FAIL(&host->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u lights' surfel samples", count);
        }
        free(host->foot);
        host->foot = nf;
    }
    for (uint32_t i = 0; i < host->light_count; ++i) free_maps(&host->lights[i]);
    free(host->lights);
    host->lights = nl;
    host->light_count = count;
    return GLOW_OK;
}

uint32_t glow_host_light_count(const glow_host *host) { return host ? host->light_count : 0; }

glow_result glow_host_get_light(const glow_host *host, uint32_t index, glow_scene_light *out_light) {
    if (!host || !out_light || index >= host->light_count) return GLOW_ERROR_INVALID_ARGUMENT;
    *out_light = host->lights[index].l;
    return GLOW_OK;
}

glow_result glow_host_set_environment(glow_host *host, const float radiance_rgb[3]) {
    if (!host || !radiance_rgb) return GLOW_ERROR_INVALID_ARGUMENT;
    for (int c = 0; c < 3; ++c)
        if (!isfinite(radiance_rgb[c]) || radiance_rgb[c] < 0.0f)
            return HOST_FAIL(&host->logger, GLOW_ERROR_INVALID_ARGUMENT, "environment[%d] (%g) is negative or not finite",
                             c, (double)radiance_rgb[c]);
    memcpy(host->env, radiance_rgb, sizeof host->env);
    host->env_sh_on = false;
    return GLOW_OK;
}

glow_result glow_host_set_environment_sh(glow_host *host, const float sh_rgb[GLOW_SKY_SH_FLOATS]) {
    if (!host) return GLOW_ERROR_INVALID_ARGUMENT;
    if (!sh_rgb) {
        host->env_sh_on = false;
        return GLOW_OK;
    }
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k)
        if (!isfinite(sh_rgb[k]) || fabsf(sh_rgb[k]) > GLOW_MAX_IRRADIANCE)
            return HOST_FAIL(&host->logger, GLOW_ERROR_INVALID_ARGUMENT,
                             "environment SH coefficient %d channel %d (%g) is not finite or beyond %g", k / 3, k % 3,
                             (double)sh_rgb[k], (double)GLOW_MAX_IRRADIANCE);
    if (!host->bake_T && !host->t_cache && host->surfel_count && host->sky == GLOW_HOST_SKY_TRACED) {
        host->t_cache = malloc((size_t)host->surfel_count * 10 * sizeof *host->t_cache);
        if (!host->t_cache)
            return HOST_FAIL(&host->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for the sky transfer of %u surfels",
                             host->surfel_count);
        for (size_t i = 0; i < (size_t)host->surfel_count * 10; ++i) atomic_init(&host->t_cache[i], SKY_UNSET);
    }
    if (host->bake_T && host->sky == GLOW_HOST_SKY_TRACED && host->scene && host->surfel_count) {
        if (!host->sky_E && !(host->sky_E = malloc((size_t)host->surfel_count * 3 * sizeof *host->sky_E)))
            return HOST_FAIL(&host->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for the sky of %u surfels",
                             host->surfel_count);
        for (uint32_t i = 0; i < host->surfel_count; ++i)
            glow_sh_sky_irradiance(host->bake_T + 9 * (size_t)i, sh_rgb, host->sky_E + 3 * (size_t)i);
    }
    memcpy(host->env_sh, sh_rgb, sizeof host->env_sh);
    host->env_sh_on = true;
    return GLOW_OK;
}

glow_result glow_host_sky_transfer(glow_host *h, const glow_surfel_view *v, float *out, uint32_t count) {
    if (!h || !v || !out || !v->positions || !v->normals) return GLOW_ERROR_INVALID_ARGUMENT;
    if (count != h->surfel_count || v->count != h->surfel_count)
        return HOST_FAIL(&h->logger, GLOW_ERROR_INVALID_ARGUMENT,
                         "glow_host_sky_transfer: %u values / %u surfels given, the bake has %u surfels", count, v->count,
                         h->surfel_count);
    for (uint32_t i = 0; i < count; ++i) {
        float buf[9];
        const float *T = sky_T(h, v->positions + 4 * (size_t)i, v->normals + 4 * (size_t)i, i, buf);
        memcpy(out + 9 * (size_t)i, T, 9 * sizeof *out);
    }
    return GLOW_OK;
}

/* -------------------------------------------------------------------------- lifetime */

glow_host_desc glow_host_desc_from_scene(const glow_scene_desc *scene, const glow_bake *bake, glow_host_kind kind) {
    glow_host_desc d;
    memset(&d, 0, sizeof d);
    d.kind = kind;
    d.bake = bake;
    if (scene) {
        d.lights = scene->lights;
        d.light_count = scene->light_count;
        memcpy(d.environment, scene->environment, sizeof d.environment);
    }
    return d;
}

glow_lighting_hooks glow_host_hooks(glow_host *host) {
    glow_lighting_hooks hk = {NULL, NULL};
    if (host) {
        hk.light_surfels = light_surfels;
        hk.user = host;
    }
    return hk;
}

void glow_host_destroy(glow_host *host) {
    if (!host) return;
    for (uint32_t i = 0; i < host->light_count; ++i) free_maps(&host->lights[i]);
    free(host->lights);
    if (host->scene) rtcReleaseScene(host->scene);
    if (host->device) rtcReleaseDevice(host->device);
    free(host->tris);
    free(host->sky_dirs);
    free(host->sky_order);
    free((void *)host->sky_cache);
    free((void *)host->t_cache);
    free(host->sky_E);
    free((void *)host->origin_cache);
    free(host->foot);
    free((void *)host->reach);
    free(host);
}

/* Deterministic cosine-distributed directions around +z (the seam's, sky_rays.h: the linker's SKYT uses
 * the same). The estimate of S is the fraction of them that escape. */
static void make_sky_dirs(float *dirs, uint32_t n) { glow__seam_sky_dirs(n, dirs); }

static glow_result check_settings(const glow_host_desc *d, const glow_logger *lg) {
    if (d->kind != GLOW_HOST_KIND_DEFAULT && d->kind != GLOW_HOST_KIND_EXACT && d->kind != GLOW_HOST_KIND_SHADOW_MAP)
        return HOST_FAIL(lg, GLOW_ERROR_UNSUPPORTED, "unknown host kind %d", (int)d->kind);
    if (d->sky != GLOW_HOST_SKY_DEFAULT && d->sky != GLOW_HOST_SKY_TRACED && d->sky != GLOW_HOST_SKY_UNSHADOWED)
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "unknown sky mode %d", (int)d->sky);
    if (d->sky_rays > 65536) return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "sky_rays %u > 65536", d->sky_rays);
    if (d->shadow_map_size && (d->shadow_map_size < 16 || d->shadow_map_size > 8192))
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "shadow_map_size %u outside 16..8192", d->shadow_map_size);
    if (d->cube_map_size && (d->cube_map_size < 16 || d->cube_map_size > 8192))
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "cube_map_size %u outside 16..8192", d->cube_map_size);
    if (d->surfel_samples > GLOW_HOST_SURFEL_SAMPLES_MAX)
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "surfel_samples %u outside 1..%u", d->surfel_samples,
                         GLOW_HOST_SURFEL_SAMPLES_MAX);
    if (d->pcf_size && (d->pcf_size > 9 || (d->pcf_size & 1) == 0))
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "pcf_size %u is not odd in 1..9", d->pcf_size);
    const float b[3] = {d->depth_bias, d->slope_bias, d->normal_offset};
    static const char *const names[3] = {"depth_bias", "slope_bias", "normal_offset"};
    for (int i = 0; i < 3; ++i)
        if (!isfinite(b[i]) || b[i] < 0.0f || b[i] > 1000.0f)
            return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "%s (%g) outside [0, 1000]", names[i], (double)b[i]);
    for (int c = 0; c < 3; ++c)
        if (!isfinite(d->environment[c]) || d->environment[c] < 0.0f)
            return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "environment[%d] (%g) is negative or not finite", c,
                             (double)d->environment[c]);
    if (d->light_count && !d->lights)
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "lights is NULL with light_count %u", d->light_count);
    return GLOW_OK;
}

glow_result glow_host_create(const glow_host_desc *desc, glow_host **out_host) {
    if (out_host) *out_host = NULL;
    if (!desc || !out_host) return GLOW_ERROR_INVALID_ARGUMENT;
    const glow_logger *lg = &desc->logger;
    if (!desc->bake) return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "desc.bake is NULL");
    glow_result r = check_settings(desc, lg);
    if (r != GLOW_OK) return r;
    glow_bake_info info;
    glow_bake_geometry geo;
    if ((r = glow_bake_get_info(desc->bake, &info)) != GLOW_OK) return HOST_FAIL(lg, r, "cannot read the bake's info");
    if ((r = glow_bake_get_geometry(desc->bake, &geo)) != GLOW_OK)
        return HOST_FAIL(lg, r, "cannot read the bake's geometry");
    if (geo.triangle_count == 0 || !geo.positions)
        return HOST_FAIL(lg, GLOW_ERROR_EMPTY_SCENE, "the bake carries no triangles to cast shadows");
    if (desc->sky_visibility && desc->sky_visibility_count != info.surfel_count)
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "sky_visibility has %u values, the bake has %u surfels",
                         desc->sky_visibility_count, info.surfel_count);

    glow_host *h = calloc(1, sizeof *h);
    if (!h) return GLOW_ERROR_OUT_OF_MEMORY;
    h->kind = desc->kind == GLOW_HOST_KIND_SHADOW_MAP ? GLOW_HOST_KIND_SHADOW_MAP : GLOW_HOST_KIND_EXACT;
    { /* a benchmarking knob, undocumented in the header: GLOW_HOST_PACKETS=0 traces one ray at a time */
        const char *env = getenv("GLOW_HOST_PACKETS");
        h->packets = !(env && strcmp(env, "0") == 0);
    }
    h->logger = desc->logger;
    h->bake = desc->bake;
    h->surfel_count = info.surfel_count;
    h->tri_count = geo.triangle_count;
    h->own_tri_count = geo.triangle_count;
    if (desc->occluder_count && !desc->occluders) {
        free(h);
        return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "occluders is NULL with occluder_count %u", desc->occluder_count);
    }
    for (uint32_t b = 0; b < desc->occluder_count; ++b) {
        glow_bake_geometry og;
        if (!desc->occluders[b] || glow_bake_get_geometry(desc->occluders[b], &og) != GLOW_OK || !og.positions ||
            og.triangle_count > UINT32_MAX / 9u - h->tri_count) {
            free(h);
            return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "occluder bake %u is NULL or has no readable geometry", b);
        }
        h->tri_count += og.triangle_count;
    }
    h->sky = desc->sky == GLOW_HOST_SKY_UNSHADOWED ? GLOW_HOST_SKY_UNSHADOWED : GLOW_HOST_SKY_TRACED;
    h->sky_rays = desc->sky_rays ? desc->sky_rays : 128;
    h->sm_size = desc->shadow_map_size ? desc->shadow_map_size : 1024;
    h->cube_size = desc->cube_map_size ? desc->cube_map_size : 512;
    h->sp.depth_bias = desc->depth_bias > 0.0f ? desc->depth_bias : 1.0f;
    h->sp.slope_bias = desc->slope_bias > 0.0f ? desc->slope_bias : 2.0f;
    h->sp.normal_offset = desc->normal_offset > 0.0f ? desc->normal_offset : 1.0f;
    h->sp.pcf_radius = desc->pcf_size ? (int)desc->pcf_size / 2 : 1;
    memcpy(h->env, desc->environment, sizeof h->env);
    {
        glow_bake_sky_transfer st;
        if (glow_bake_get_sky_transfer(desc->bake, &st) == GLOW_OK && st.surfel_transfer && st.surfel_count == info.surfel_count)
            h->bake_T = st.surfel_transfer;
    }

    h->tris = malloc((size_t)h->tri_count * 9 * sizeof(float));
    h->sky_dirs = malloc((size_t)h->sky_rays * 3 * sizeof(float));
    h->sky_order = malloc((size_t)h->sky_rays * sizeof *h->sky_order);
    h->sky_cache = h->surfel_count ? malloc((size_t)h->surfel_count * sizeof *h->sky_cache) : NULL;
    if (!h->tris || !h->sky_dirs || !h->sky_order || (h->surfel_count && !h->sky_cache)) {
        glow_host_destroy(h);
        return HOST_FAIL(lg, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u triangles", geo.triangle_count);
    }
    for (int i = 0; i < 3; ++i) {
        h->bmin[i] = INFINITY;
        h->bmax[i] = -INFINITY;
    }
    uint32_t t = 0;
    for (uint32_t b = 0; b <= desc->occluder_count; ++b) { /* the bake's own triangles, then the occluders' */
        glow_bake_geometry g = geo;
        if (b > 0) glow_bake_get_geometry(desc->occluders[b - 1], &g);
        for (uint32_t j = 0; j < g.triangle_count; ++j, ++t) {
            const float *src = (const float *)((const char *)g.positions + (size_t)j * g.stride);
            for (int k = 0; k < 9; ++k) {
                float v = src[k];
                if (!isfinite(v)) {
                    glow_host_destroy(h);
                    return HOST_FAIL(lg, GLOW_ERROR_CORRUPT_DATA, "%s triangle %u has a non-finite corner",
                                     b ? "occluder bake" : "bake", j);
                }
                h->tris[9 * (size_t)t + k] = v;
                h->bmin[k % 3] = fminf(h->bmin[k % 3], v);
                h->bmax[k % 3] = fmaxf(h->bmax[k % 3], v);
            }
        }
        if (b == 0) { /* the epsilon from the bake's own extent, as without occluders */
            float ext[3] = {h->bmax[0] - h->bmin[0], h->bmax[1] - h->bmin[1], h->bmax[2] - h->bmin[2]};
            h->diag = sqrtf(glow__dot3(ext, ext));
            if (!(h->diag > 0.0f)) h->diag = 1.0f;
            h->eps = 1e-4f * h->diag;
        }
    }
    make_sky_dirs(h->sky_dirs, h->sky_rays);
    {
        uint64_t *keys = malloc((size_t)h->sky_rays * sizeof *keys);
        if (!keys) {
            const uint32_t rays = h->sky_rays;
            glow_host_destroy(h);
            return HOST_FAIL(lg, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u sky rays", rays);
        }
        glow__seam_sky_order(h->sky_rays, keys, h->sky_order);
        free(keys);
    }
    for (uint32_t i = 0; i < h->surfel_count; ++i) {
        uint32_t bits = SKY_UNSET;
        if (desc->sky_visibility) {
            float s = desc->sky_visibility[i];
            if (!(s >= 0.0f && s <= 1.0f)) {
                glow_host_destroy(h);
                return HOST_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "sky_visibility[%u] (%g) is outside [0, 1]", i,
                                 (double)s);
            }
            memcpy(&bits, &s, sizeof bits);
        }
        atomic_init(&h->sky_cache[i], bits);
    }

    bool need_rays = h->kind == GLOW_HOST_KIND_EXACT || h->sky == GLOW_HOST_SKY_TRACED;
    if (need_rays && (r = build_embree(h)) != GLOW_OK) {
        glow_host_destroy(h);
        return r;
    }
    if (need_rays && h->surfel_count) {
        h->origin_cache = malloc((size_t)h->surfel_count * 3 * sizeof *h->origin_cache);
        if (!h->origin_cache) {
            glow_host_destroy(h);
            return HOST_FAIL(lg, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u surfels", h->surfel_count);
        }
        for (size_t i = 0; i < (size_t)h->surfel_count * 3; ++i) atomic_init(&h->origin_cache[i], SKY_UNSET);
    }
    h->samples = h->kind == GLOW_HOST_KIND_EXACT
                     ? (desc->surfel_samples ? desc->surfel_samples : GLOW_HOST_SURFEL_SAMPLES_DEFAULT)
                     : 1u;
    for (int w = 0; w < 64; ++w) atomic_init(&h->rays[w].n, 0);
    foot_tables(h);
    if (h->samples > 1 && h->surfel_count) { /* footprints; glow_host_set_lights allocates h->foot */
        h->reach = malloc((size_t)h->surfel_count * sizeof *h->reach);
        if (!h->reach) {
            glow_host_destroy(h);
            return HOST_FAIL(lg, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u surfels", h->surfel_count);
        }
        for (uint32_t i = 0; i < h->surfel_count; ++i) atomic_init(&h->reach[i], 0);
    }
    if ((r = glow_host_set_lights(h, desc->lights, desc->light_count)) != GLOW_OK) {
        glow_host_destroy(h);
        return r;
    }
    *out_host = h;
    return GLOW_OK;
}

glow_result glow_host_irradiance(const glow_host *host, const float position[3], const float normal[3],
                                 float out_rgb[3]) {
    if (out_rgb) out_rgb[0] = out_rgb[1] = out_rgb[2] = 0.0f;
    if (!host || !position || !normal || !out_rgb) return GLOW_ERROR_INVALID_ARGUMENT;
    float n[3];
    if (!isfinite(position[0]) || !isfinite(position[1]) || !isfinite(position[2]) || !glow__normalize3(normal, n))
        return HOST_FAIL(&host->logger, GLOW_ERROR_INVALID_ARGUMENT, "irradiance: non-finite position or bad normal");
    irradiance_at(host, position, n, UINT32_MAX, 0.0f, out_rgb);
    return GLOW_OK;
}

glow_result glow_host_get_stats(const glow_host *host, glow_host_stats *out_stats) {
    if (!host || !out_stats) return GLOW_ERROR_INVALID_ARGUMENT;
    memset(out_stats, 0, sizeof *out_stats);
    out_stats->kind = host->kind;
    out_stats->triangle_count = host->own_tri_count;
    out_stats->epsilon = host->eps;
    for (uint32_t i = 0; i < host->light_count; ++i) {
        const host_light *hl = &host->lights[i];
        for (uint32_t m = 0; m < hl->map_count; ++m) {
            if (!hl->maps[m].depth) continue;
            out_stats->shadow_map_count++;
            out_stats->shadow_map_bytes += (uint64_t)hl->maps[m].res * hl->maps[m].res * sizeof(float);
        }
    }
    out_stats->shadow_map_ms = host->shadow_map_ms;
    for (uint32_t i = 0; i < host->surfel_count; ++i)
        out_stats->sky_cached += atomic_load_explicit(&host->sky_cache[i], memory_order_relaxed) != SKY_UNSET;
    out_stats->surfel_samples = host->samples;
    out_stats->sky_sh = host->env_sh_on;
    out_stats->sky_transfer_baked = host->bake_T != NULL;
    for (int w = 0; w < 64; ++w) out_stats->shadow_rays += atomic_load_explicit(&host->rays[w].n, memory_order_relaxed);
    return GLOW_OK;
}
