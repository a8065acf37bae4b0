/* rt.c — the linker's ray queries over the scene, on Embree 3. Triangles are the scene's own
 * unwelded corners (vertex 3i+k is corner k of triangle i), so Embree's primID is our triangle index.
 * All queries are thread-safe (Embree's rtcIntersect/rtcOccluded are). */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pc_internal.h"
#include "sky_rays.h"

struct glow__rt {
    RTCDevice device;
    RTCScene scene;
    const glow__scene *src;
    const float *foreign; /* glow__rt_create_system: geometry 1's corners (9 floats a triangle), not owned */
    bool ray16;
};

/* Attaches one triangle geometry of n unwelded triangles (9 floats each) as geometry id `id`. */
static bool attach_tris(glow__rt *rt, const float *pos, uint32_t n, unsigned id) {
    RTCGeometry geom = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                       (size_t)3 * n);
    uint32_t *idx = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), n);
    if (!v || !idx) {
        rtcReleaseGeometry(geom);
        return false;
    }
    if (n) memcpy(v, pos, (size_t)n * 9 * sizeof(float));
    for (uint32_t i = 0; i < 3 * n; ++i) idx[i] = i;
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(rt->scene, geom, id);
    rtcReleaseGeometry(geom);
    return true;
}

static void embree_error(void *user, enum RTCError code, const char *str) {
    glow__log *log = user;
    glow__errorf(log, "embree: error %d: %s", (int)code, str ? str : "");
}

glow_result glow__rt_create_system(const glow__scene *scene, const float *foreign, uint32_t foreign_count,
                                   glow__log *log, glow__rt **out) {
    *out = NULL;
    glow__rt *rt = calloc(1, sizeof *rt);
    if (!rt) return GLOW_ERROR_OUT_OF_MEMORY;
    rt->src = scene;
    rt->foreign = foreign_count ? foreign : NULL;
    rt->device = rtcNewDevice(NULL);
    if (!rt->device) {
        glow__errorf(log, "embree: cannot create device (error %d)", (int)rtcGetDeviceError(NULL));
        free(rt);
        return GLOW_ERROR_UNSUPPORTED;
    }
    rtcSetDeviceErrorFunction(rt->device, embree_error, log);
    rt->ray16 = rtcGetDeviceProperty(rt->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
    rt->scene = rtcNewScene(rt->device);
    rtcSetSceneBuildQuality(rt->scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(rt->scene, RTC_SCENE_FLAG_ROBUST);
    const uint32_t n = scene->tri_count;
    if (!attach_tris(rt, (const float *)scene->pos, n, 0) ||
        (rt->foreign && !attach_tris(rt, foreign, foreign_count, 1))) {
        glow__rt_destroy(rt);
        glow__errorf(log, "embree: out of memory for %u triangles", n + foreign_count);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    rtcCommitScene(rt->scene);
    if (rtcGetDeviceError(rt->device) != RTC_ERROR_NONE) {
        glow__rt_destroy(rt);
        return GLOW_ERROR_UNSUPPORTED;
    }
    *out = rt;
    return GLOW_OK;
}

glow_result glow__rt_create(const glow__scene *scene, glow__log *log, glow__rt **out) {
    return glow__rt_create_system(scene, NULL, 0, log, out);
}

void glow__rt_destroy(glow__rt *rt) {
    if (!rt) return;
    if (rt->scene) rtcReleaseScene(rt->scene);
    if (rt->device) rtcReleaseDevice(rt->device);
    free(rt);
}

bool glow__rt_occluded(const glow__rt *rt, const float org[3], const float dir[3], float tnear, float tfar) {
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay ray = {0};
    ray.org_x = org[0]; ray.org_y = org[1]; ray.org_z = org[2];
    ray.dir_x = dir[0]; ray.dir_y = dir[1]; ray.dir_z = dir[2];
    ray.tnear = tnear;
    ray.tfar = tfar;
    ray.mask = 0xFFFFFFFFu;
    rtcOccluded1(rt->scene, &ctx, &ray);
    return ray.tfar < 0.0f; /* Embree sets tfar = -inf on a hit */
}

void glow__rt_occluded16(const glow__rt *rt, const float org[3], const float (*dir)[3], const float *tfar, uint32_t n,
                         float tnear, uint8_t *out_occluded) {
    if (n > 16) n = 16;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    _Alignas(64) struct RTCRay16 r;
    _Alignas(64) int valid[16];
    for (uint32_t i = 0; i < 16; ++i) {
        bool on = i < n;
        valid[i] = on ? -1 : 0;
        r.org_x[i] = org[0]; r.org_y[i] = org[1]; r.org_z[i] = org[2];
        r.dir_x[i] = on ? dir[i][0] : 0.0f;
        r.dir_y[i] = on ? dir[i][1] : 0.0f;
        r.dir_z[i] = on ? dir[i][2] : 1.0f;
        r.tnear[i] = tnear;
        r.tfar[i] = on ? tfar[i] : 0.0f;
        r.time[i] = 0.0f;
        r.mask[i] = 0xFFFFFFFFu;
        r.id[i] = i;
        r.flags[i] = 0;
    }
    rtcOccluded16(valid, rt->scene, &ctx, &r);
    for (uint32_t i = 0; i < n; ++i) out_occluded[i] = r.tfar[i] < 0.0f;
}

glow__hit glow__rt_intersect(const glow__rt *rt, const float org[3], const float dir[3], float tnear, float tfar) {
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = org[0]; rh.ray.org_y = org[1]; rh.ray.org_z = org[2];
    rh.ray.dir_x = dir[0]; rh.ray.dir_y = dir[1]; rh.ray.dir_z = dir[2];
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rt->scene, &ctx, &rh);
    glow__hit hit = {.t = INFINITY, .tri = UINT32_MAX};
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.t = rh.ray.tfar;
    hit.tri = rh.hit.primID;
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    /* Our own front-face convention, independent of Embree's Ng sign: (p1-p0) x (p2-p0). */
    const float(*p)[3] = rt->src->pos + 3 * (size_t)hit.tri;
    if (rh.hit.geomID == 1) { /* another system's triangle */
        p = (const float(*)[3])(rt->foreign + 9 * (size_t)hit.tri);
        hit.tri = UINT32_MAX;
        hit.foreign = true;
    }
    float e1[3], e2[3], ng[3];
    glow__sub(p[1], p[0], e1);
    glow__sub(p[2], p[0], e2);
    glow__cross(e1, e2, ng);
    hit.back_face = glow__dot(ng, dir) > 0.0f;
    return hit;
}

/* ------------------------------------------------------------------ nearest facing triangle */
typedef struct facing_query {
    const glow__rt *rt;
    const float *p, *n;
    const float *best_tri; /* 9 floats */
    float best_d2;
} facing_query;

static bool facing_cb(struct RTCPointQueryFunctionArguments *args) {
    facing_query *q = args->userPtr;
    const float *t;
    if (args->geomID == 1 && q->rt->foreign) t = q->rt->foreign + 9 * (size_t)args->primID;
    else if (args->geomID == 0 && args->primID < q->rt->src->tri_count) t = (const float *)(q->rt->src->pos + 3 * (size_t)args->primID);
    else return false;
    const float e1[3] = {t[3] - t[0], t[4] - t[1], t[5] - t[2]}, e2[3] = {t[6] - t[0], t[7] - t[1], t[8] - t[2]};
    float ng[3];
    glow__cross(e1, e2, ng);
    const float len = sqrtf(glow__dot(ng, ng));
    if (!(len > 0.0f) || glow__dot(ng, q->n) < 0.9f * len) return false;
    float c[3];
    glow__seam_closest_on_tri(q->p, t, t + 3, t + 6, c);
    const float d[3] = {c[0] - q->p[0], c[1] - q->p[1], c[2] - q->p[2]}, d2 = glow__dot(d, d);
    if (d2 >= q->best_d2) return false;
    q->best_tri = t;
    q->best_d2 = d2;
    return false;
}

bool glow__rt_nearest_facing(const glow__rt *rt, const float p[3], const float n[3], float radius,
                             float out_centroid[3]) {
    struct RTCPointQuery pq;
    memset(&pq, 0, sizeof pq);
    pq.x = p[0];
    pq.y = p[1];
    pq.z = p[2];
    pq.radius = radius;
    struct RTCPointQueryContext pc;
    rtcInitPointQueryContext(&pc);
    facing_query q = {rt, p, n, NULL, INFINITY};
    rtcPointQuery(rt->scene, &pq, &pc, facing_cb, &q);
    if (!q.best_tri) return false;
    for (int i = 0; i < 3; ++i) out_centroid[i] = (q.best_tri[i] + q.best_tri[3 + i] + q.best_tri[6 + i]) * (1.0f / 3.0f);
    return true;
}
