/* links.c — link generation (PIC 4.5, 4.6, App. A).
 *
 * For every cache, independently (so the result does not depend on the thread count):
 *  1. every leaf surfel's solid angle seen from the cache. Far surfels (centre farther than
 *     NEAR_RADII surfel radii): the solid angle of the surfel's disc, with visibility from Embree
 *     occlusion rays (rays_per_surfel rays to points on the disc; the fraction that arrives).
 *     Near surfels: the disc approximation is wrong there (a cache beside a wall sees the wall at
 *     angles no disc represents), so their solid angle is measured by rays instead — NEAR_RAYS
 *     directions over the sphere (hemisphere for lightmap caches), each hit closer than the near
 *     radius credits its solid angle to the surfel nearest to the hit point that faces the cache,
 *     stands for the surface hit (NEAR_CREDIT_COS, within a surfel radius of its plane) and that
 *     nothing separates from the hit point (surfel_reaches_hit: not the surfel on the other side of a
 *     thin wall). Back-facing surfels and, for lightmap caches, surfels below the cache's horizon get
 *     zero.
 *     Normalisation: the same rays, continued to unlimited length, measure the solid angle of the
 *     visible geometry (first hits on front faces). The disc approximation of the far field falls a
 *     few % short of it, energy the runtime would lose at every bounce, so every leaf's solid angle
 *     is scaled by measured / Σ leaves (bounded to [NORM_MIN, NORM_MAX]; off with no_normalize);
 *  2. the visible solid angle ω and the ω-weighted direction summed up the hierarchy (one sweep over
 *     the nodes in index order: children always precede parents);
 *  3. the cut refined top-down: start at the root, always split the node with the largest visible
 *     solid angle, drop nodes that are not visible at all, until n_L nodes remain or every node in
 *     the cut is a leaf. The cut therefore covers all of the visible scene (Σ ω is preserved);
 *  4. one link per cut node, runtime-projection encoding (4.6): factor = surfel_area / node_area
 *     (flux -> radiosity, the 1/π and 1/surfel_area are the bake's factor_scale), the cone with the
 *     same visible solid angle (1 - cos α = ω / 2π) and the mean visible direction.
 *  With full_sh, also PIC Eq. 2: c_lm = Σ_visible-leaves ω_i y_lm(dir_i) per cut node, times factor
 *  (the per-leaf sum is the Monte-Carlo estimate with one sample per leaf surfel, App. A).
 */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "bake_format.h"
#include "cone_fit.h"
#include "pc_internal.h"

#define NEAR_RADII 4.0f
#define NEAR_RAYS 1024u /* over the sphere; a hemisphere gets half, so each ray is 4π/1024 sr */
#define NEAR_KNN 8u       /* candidate surfels for a near-field hit */
#define NEAR_KNN_MORE 32u /* ... when none of the first NEAR_KNN may take it (surfel_reaches_hit) */
/* A near-field hit is credited only to a surfel that stands for the surface hit: its normal within
 * 60° of the hit triangle's and its centre within one surfel radius of that triangle's plane. Without
 * these, a hit on a small surface with no surfel of its own went to the nearest surfel facing the
 * cache, which could lie on another surface: caches on Sponza's 45° chamfers under the eaves (dark in
 * the path tracer) credited the sunlit outer wall 0.6 m away and gathered 25-250x their light. Hits
 * nobody may take stay uncredited; the normalisation spreads their solid angle. Sponza, 1174 audited
 * texels (glow-bake --audit-radiance): the exact gather of the darkest quarter went from 2.77x to
 * 1.32x the path tracer's, the brightest 3 % from 0.885x to 0.951x. */
#define NEAR_CREDIT_COS 0.5f
/* Bounds of the normalisation factor. In the closed Cornell box every cache needs 0.975-1.072; in
 * the Dabrovic Sponza (moderate) 99.8 % of the caches need 0.89-2. Beyond 2, more than half of
 * what the rays hit has no surfel within reach of the near-field credit (texels at the inner edge
 * of the arches, whose 8 cm strips hold one 0.23 m² surfel per ~26 triangles): the leaves that
 * are visible are then a poor stand-in for it (other directions, other surfaces), so their share
 * is not stretched further. The lower bound guards the same way against the opposite mismatch. */
/* Clustered visibility: a part of a cluster whose leaves do not all face the cache (or straddle its
 * horizon) sums its leaves' own solid angles in subtrees of at most this many leaves; a larger
 * subtree is read by its parts (mixed_part), so that those that all face the cache take the
 * aggregate. Sponza at 524,288 surfels: summing every such cluster made the leaf arithmetic 11 % of
 * the bake. */
#define CLUSTER_SUM_LEAVES 64u
#define NORM_MIN 0.5
#define NORM_MAX 2.0

/* Clustered visibility's descent reads the hierarchy in preorder (the child with the lower leaves
 * first), one cache line per node: a node it stops at jumps to `skip`, one it opens goes on to the
 * next entry. Nodes in index order (by level) put a node's children megabytes apart at 1M nodes, and
 * the descent, a few thousand nodes per cache, spent most of its time waiting for them. */
typedef struct trav_node {
    float pos[3], radius;  /* bounding sphere */
    float nrm[3], cone;    /* mean normal and the half-angle of a cone about it holding every normal */
    float nsum[3];         /* sum of the leaves' normals */
    uint32_t id;           /* node index; TRAV_EMISSIVE: holds an emissive leaf */
    uint32_t first, end;   /* leaf range */
    uint32_t skip;         /* the preorder index after this subtree */
    uint32_t child0_low;   /* 1: the node's child[0] is its first child here (the lower leaves) */
} trav_node;
#define TRAV_EMISSIVE 0x80000000u

/* A cluster's parts (clustered visibility), which do not depend on the cache: the preorder indices
 * of its K <= 4 subtrees in leaf order, and where their leaf ranges meet. Read with the node, they
 * spare the descent the three child entries it read one after another to split each cluster (the
 * split loop was 45 % of link_cache's samples at 524,288 surfels). */
typedef struct trav_quad {
    uint32_t sub[4];
    uint32_t bnd[3]; /* part k holds leaves [bnd[k - 1], bnd[k]) (the node's first and end outside) */
    uint32_t ns;     /* parts: K, fewer where the node has fewer splittable subtrees */
} trav_quad;

typedef struct link_job {
    const glow_pc_distribution *dist; /* this rank's caches: rank_item (links.c "Ranks") */
    uint32_t cache_total;             /* how many this rank links */
    const glow__scene *scene;
    const glow__rt *rt;
    const glow__surfels *surfels;
    const glow__hierarchy *h;
    const glow__caches *caches;
    const glow__link_settings *settings;
    glow__links *out;
    uint32_t *leaf_first, *leaf_end; /* per node: its leaves are [first, end) (DFS leaf order) */
    double *leaf_area;               /* [leaf_count + 1]: area of leaves [0, i), so leaves [a, b) hold
                                      * leaf_area[b] - leaf_area[a]; a node's radiance is its flux over
                                      * its area, so each leaf weighs by its area, not 1/n (adaptive
                                      * surfel density: areas 0.1-3.4x the nominal) */
    double *leaf_apos;               /* [3 (leaf_count + 1)]: the area-weighted positions of leaves
                                      * [0, i) (link gradients with clustered visibility: a run's share of
                                      * a node's response centroid without reading its leaves) */
    double *grad_frame;              /* per node [4]: its leaves' area centroid and radius sigma
                                      * (link_gradient; sigma 0: the node has no gradient) */
    float ray_eps;                   /* scene-scale offset for ray starts and ends */
    float near_radius;               /* NEAR_RADII surfel radii */
    glow__pointgrid *surfel_grid;    /* over this system's surfel positions: the near-field and detail
                                      * credit's k-nearest (a k-d tree until 2026-11-30: same answers) */
    float sphere_dirs[NEAR_RAYS][3]; /* uniform in solid angle */
    float hemi_dirs[NEAR_RAYS / 2][3]; /* uniform in solid angle, z up */
    /* per-worker scratch */
    uint32_t workers;
    float **omega;                   /* [workers][node_count] */
    float **dirsum;                  /* [workers][node_count*3] */
    float **kappa;                   /* [workers][node_count]: Σ ω_i max(0, d_i·n)/π, lightmap caches */
    float **prio;                    /* [workers][node_count]: split priority of the nodes pushed (cut_priority) */
    uint32_t **heap;                 /* [workers][node_count] */
    struct cl_runs *runs;            /* [workers]: clustered visibility's runs (cl_runs) */
    float *radius;                   /* per node: bounding sphere radius about its centre (leaves: a surfel's) */
    float *cone;                     /* per node: half-angle (rad) of a cone about nrm holding its leaves' normals */
    float *nsum;                     /* per node [3]: the sum of its leaves' normals */
    uint8_t *emissive;               /* per node: holds an emissive surfel (never a cluster) */
    trav_node *trav;                 /* [node_count] the hierarchy in preorder (clustered visibility) */
    trav_quad *quad;                 /* [node_count] per preorder entry, when cluster_samples <= 4 */
    float *lift;                     /* [node_count] per preorder entry: how far its leaves rise above its
                                      * centre along its mean normal (mixed_part's horizon test) */
    float *leaf_soa;                 /* [7][leaf_count]: the leaves' x, y, z, normal x, y, z and area, by
                                      * plane (leaf_batch) */
    double *visible_total;           /* per cache, summed in cache order afterwards */
    float *norm_scale;               /* per cache: the normalisation factor applied (0 = none) */
    uint8_t *norm_clamped;           /* per cache: 1 when it hit NORM_MIN / NORM_MAX */
    atomic_uint done;
    atomic_ullong vis_rays, vis_cluster_rays, vis_units; /* visibility rays cast (all, for clusters), runs or leaves */
    glow__progress_fn progress;
    void *progress_user;
} link_job;

/* max-heap on the split priority, ties broken by the smaller node index, so the cut is deterministic */
static bool heap_less(const float *prio, uint32_t a, uint32_t b) {
    if (prio[a] != prio[b]) return prio[a] < prio[b];
    return a > b;
}
static void heap_push(uint32_t *heap, uint32_t *n, const float *prio, uint32_t v) {
    uint32_t i = (*n)++;
    heap[i] = v;
    while (i > 0) {
        uint32_t p = (i - 1) / 2;
        if (!heap_less(prio, heap[p], heap[i])) break;
        uint32_t t = heap[p]; heap[p] = heap[i]; heap[i] = t;
        i = p;
    }
}
static uint32_t heap_pop(uint32_t *heap, uint32_t *n, const float *prio) {
    uint32_t top = heap[0];
    heap[0] = heap[--(*n)];
    uint32_t i = 0;
    for (;;) {
        uint32_t l = 2 * i + 1, r = l + 1, m = i;
        if (l < *n && heap_less(prio, heap[m], heap[l])) m = l;
        if (r < *n && heap_less(prio, heap[m], heap[r])) m = r;
        if (m == i) break;
        uint32_t t = heap[m]; heap[m] = heap[i]; heap[i] = t;
        i = m;
    }
    return top;
}

/* Solid angle of a disc of area `area` at distance d, tilted by cos_s: exact on-axis disc formula
 * 2π(1 - d/sqrt(d² + R²)) times the tilt; tends to area*cos_s/d² far away, stays ≤ 2π close up. */
static float disc_solid_angle(float area, float d2, float cos_s) {
    float r2 = area / (float)GLOW__PI;
    float d = sqrtf(d2);
    return (float)(2.0 * GLOW__PI) * (1.0f - d / sqrtf(d2 + r2)) * cos_s;
}

/* Unit tangents t, b with (t, b, n) right-handed, for a unit n. */
static void tangent_frame(const float n[3], float t[3], float b[3]) {
    float a[3] = {fabsf(n[0]) < 0.9f ? 1.0f : 0.0f, fabsf(n[0]) < 0.9f ? 0.0f : 1.0f, 0.0f};
    glow__cross(n, a, t);
    float tl = sqrtf(glow__dot(t, t));
    for (int k = 0; k < 3; ++k) t[k] /= tl;
    glow__cross(n, t, b);
}

/* Deterministic per-(cache, surfel, ray) point on the surfel disc (for rays_per_surfel > 1). */
static void disc_point(const glow__surfel *s, float radius, uint32_t k, uint32_t count, float out[3]) {
    /* Fibonacci spiral on the disc: area-uniform, no randomness needed. */
    float t[3], b[3];
    tangent_frame(s->nrm, t, b);
    float rr = radius * sqrtf(((float)k + 0.5f) / (float)count);
    float phi = (float)k * 2.39996323f;
    float c = cosf(phi) * rr, d = sinf(phi) * rr;
    for (int i = 0; i < 3; ++i) out[i] = s->pos[i] + c * t[i] + d * b[i];
}

/* Is the segment from `from` to `to` blocked by geometry other than the surface the start point
 * stands on (the plane through plane_p with unit normal plane_n)? A first hit on that surface itself
 * (parallel and within a few ray offsets of its plane) is the segment cutting across a convex edge of
 * that surface, not an obstacle. */
static bool blocked_elsewhere(const link_job *job, const float from[3], const float to[3], const float plane_p[3],
                              const float plane_n[3]) {
    float d[3];
    glow__sub(to, from, d);
    const float len = sqrtf(glow__dot(d, d));
    if (!(len > 2.0f * job->ray_eps)) return false;
    const float f = job->ray_eps / len;
    glow__hit hit = glow__rt_intersect(job->rt, from, d, f, 1.0f - f);
    if (hit.t == INFINITY) return false;
    if (hit.foreign) return true; /* another system's surface */
    const float(*P)[3] = job->scene->pos + 3 * (size_t)hit.tri;
    float e1[3], e2[3], n[3], h[3], off[3];
    glow__sub(P[1], P[0], e1);
    glow__sub(P[2], P[0], e2);
    glow__cross(e1, e2, n);
    const float nl = sqrtf(glow__dot(n, n));
    for (int k = 0; k < 3; ++k) h[k] = from[k] + hit.t * d[k];
    glow__sub(h, plane_p, off);
    const bool own_surface = nl > 0.0f && fabsf(glow__dot(n, plane_n)) > 0.99f * nl &&
                             fabsf(glow__dot(off, plane_n)) < 4.0f * job->ray_eps;
    return !own_surface;
}

/* Does the surfel stand for the surface at the hit point p (on triangle tri, ray direction dir)?
 * Not when something else lies between them: the nearest facing surfel may lie on the other side
 * of a thin wall. A texel in the corner of one room, where its floor meets the separating wall,
 * credited its near-field rays to the surfels on the other room's edge (0.1 m away, nearer than its
 * own room's) and linked that room's light (tests/unit/test_stability_leak.c). Checked from both
 * ends, from p lifted 2 eps back towards the cache and from the surfel lifted 2 eps along its normal,
 * each ignoring its own surface: a surfel around a convex edge of the hit surface (the next face of
 * a pillar) stays creditable, although the straight segment to it cuts through the pillar. Surfels on
 * the hit triangle itself need no ray. */
static bool surfel_reaches_hit(const link_job *job, const glow__surfel *s, const float p[3], const float dir[3],
                               uint32_t tri) {
    const float lift = 2.0f * job->ray_eps;
    float a[3], b[3], e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = p[k] - lift * dir[k];
        b[k] = s->pos[k] + lift * s->nrm[k];
    }
    const float(*P)[3] = job->scene->pos + 3 * (size_t)tri;
    glow__sub(P[1], P[0], e1);
    glow__sub(P[2], P[0], e2);
    glow__cross(e1, e2, n);
    const float nl = sqrtf(glow__dot(n, n));
    for (int k = 0; k < 3; ++k) n[k] = nl > 0.0f ? n[k] / nl : -dir[k]; /* (the scene has no zero-area triangles) */
    return !blocked_elsewhere(job, a, b, p, n) && !blocked_elsewhere(job, b, a, s->pos, s->nrm);
}

/* Clustered visibility (settings->cluster_tau > 0, docs/linker.md "Clustered visibility").
 *
 * The exact pass gives every leaf its own solid angle and ray: caches x surfels rays and as much
 * arithmetic. The clustered pass descends the hierarchy from the root instead and stops at
 *  - nodes the cache cannot see at all: wholly below a lightmap cache's horizon, or whose normals
 *    (a bounding cone about the mean normal) all face away from it. Their leaves get nothing, as in
 *    the exact pass;
 *  - clusters: nodes wholly beyond the near field that look at most tau radians from the cache
 *    (bounding radius over distance), hold at least 2 x cluster_samples leaves and no emissive one
 *    (an emitter's penumbrae are the sharpest light a bake knows: Cornell's block error went from
 *    0.045 to 0.053 while the lamp clustered). A cluster splits into cluster_samples subtrees (the
 *    one with the most leaves split until there are that many), its parts, and one ray per part
 *    decides whether the part is visible. When every normal of the cluster faces the cache and it is
 *    wholly above the horizon, a part is one run, its solid angle the subtree's area times the cosine
 *    of its normal sum over the squared distance of its centre (the far-field disc sum to second
 *    order in tau; no leaf is visited), its ray to the leaf in its middle. Otherwise (a mixed
 *    cluster, of any size) the part's runs are its stretches of leaves that add to the solid angle
 *    (mixed_part: the leaves' own solid angles, or the aggregate of subtrees that wholly face the
 *    cache), and its ray goes to the adding leaf nearest its middle. Until 2026-11-30 a mixed cluster
 *    of more than CLUSTER_SUM_LEAVES leaves was opened instead, and at 524,288 surfels it was opened
 *    down to 64-leaf clusters with 4 rays each (13,398 rays a cache against 8,594 now);
 *  - single leaves: their own solid angle and ray, as in the exact pass (the near field, and wherever
 *    a cluster would look too large).
 * The result is a list of runs of leaves, each with a solid angle, direction sum and diffuse response
 * spread evenly over its leaves. A node's sums are read from the runs' prefix sums when the cut asks
 * for them (node_vals): the rays per cache grow with the number of clusters (about the hemisphere
 * over tau²) and the leaves near the cache, not with the surfel count. */
typedef struct cl_runs {
    bool active;
    uint32_t count;
    uint32_t *a, *b;      /* [leaf_count] leaf ranges [a, b), ascending and disjoint */
    float *w, *d, *k;     /* solid angle, solid-angle-weighted direction [3], diffuse response */
    double *pw, *pd, *pk; /* prefix sums [count + 1] (pd: 3 per) */
    uint32_t *stamp;      /* [node_count] omega/dirsum/kappa[v] are this cache's when stamp[v] == tag */
    uint32_t tag;
} cl_runs;

/* first run whose end is beyond leaf x, and first run that starts at or after x */
static uint32_t runs_end_after(const cl_runs *r, uint32_t x) {
    uint32_t lo = 0, hi = r->count;
    while (lo < hi) { uint32_t m = (lo + hi) / 2; if (r->b[m] > x) hi = m; else lo = m + 1; }
    return lo;
}
static uint32_t runs_start_from(const cl_runs *r, uint32_t x) {
    uint32_t lo = 0, hi = r->count;
    while (lo < hi) { uint32_t m = (lo + hi) / 2; if (r->a[m] >= x) hi = m; else lo = m + 1; }
    return lo;
}

/* The surfel a near-field hit is credited to (near_field; the lightmap detail): the nearest surfel to
 * the hit point, among NEAR_KNN (then NEAR_KNN_MORE) candidates, whose centre lies within R of the
 * ray's origin, that faces the ray, stands for the surface hit (NEAR_CREDIT_COS, within a surfel
 * radius of its plane), is not below the origin's horizon (hemi_nrm, NULL for the whole sphere) and
 * that nothing separates from the hit point (surfel_reaches_hit). With active runs (clustered
 * visibility), only a leaf that is a run of its own, and the run's index is returned. CREDIT_NONE
 * when nobody may take it. */
#define CREDIT_NONE 0xFFFFFFFFu
static uint32_t credit_hit(const link_job *job, const float origin[3], const float *hemi_nrm, float R, const float dir[3],
                           const glow__hit *hit, const cl_runs *runs, float max_d2) {
    const glow__surfels *S = job->surfels;
    const float eps = job->ray_eps, plane_tol = job->near_radius / NEAR_RADII; /* one surfel radius */
    if (hit->foreign) return CREDIT_NONE; /* another system's surface: its surfels are not this system's */
    float p[3], hn[3];
    for (int k = 0; k < 3; ++k) p[k] = origin[k] + hit->t * dir[k];
    {
        const float(*P)[3] = job->scene->pos + 3 * (size_t)hit->tri;
        float e1[3], e2[3];
        glow__sub(P[1], P[0], e1);
        glow__sub(P[2], P[0], e2);
        glow__cross(e1, e2, hn);
        const float hl = sqrtf(glow__dot(hn, hn));
        for (int k = 0; k < 3; ++k) hn[k] = hl > 0.0f ? hn[k] / hl : -dir[k];
        if (glow__dot(hn, dir) > 0.0f) for (int k = 0; k < 3; ++k) hn[k] = -hn[k];
    }
    /* the NEAR_KNN surfels nearest to the hit point; when none of them may take the credit, the next ones */
    uint32_t idx[NEAR_KNN_MORE];
    float dist2[NEAR_KNN_MORE];
    uint32_t found = glow__pointgrid_knn_within(job->surfel_grid, p, NEAR_KNN, UINT32_MAX, max_d2, idx, dist2);
    for (uint32_t q = 0, round = 0; q < found; ++q) {
        const glow__surfel *s = &S->s[idx[q]];
        float d[3];
        glow__sub(s->pos, origin, d);
        float off[3];
        glow__sub(s->pos, p, off);
        if (!(dist2[q] <= max_d2)) break; /* the kNN are nearest first: the rest are farther */
        bool ok = glow__dot(d, d) < R * R                         /* else a far surfel: the disc pass has it */
                  && glow__dot(s->nrm, dir) < 0.0f                /* else it faces away: another surface */
                  && glow__dot(s->nrm, hn) >= NEAR_CREDIT_COS     /* else it stands for another surface */
                  && fabsf(glow__dot(off, hn)) <= plane_tol       /* ... or for one off the hit's plane */
                  && !(hemi_nrm && glow__dot(hemi_nrm, d) <= -0.5f * eps)
                  && (s->tri == hit->tri || surfel_reaches_hit(job, s, p, dir, hit->tri));
        uint32_t unit = idx[q]; /* clustered: its run (every leaf in the near field has one of its own) */
        if (ok && runs && runs->active) {
            unit = runs_start_from(runs, idx[q]);
            ok = unit < runs->count && runs->a[unit] == idx[q] && runs->b[unit] == idx[q] + 1;
        }
        if (ok) return unit;
        if (q + 1 == found && round == 0 && found == NEAR_KNN) {
            round = 1;
            found = glow__pointgrid_knn_within(job->surfel_grid, p, NEAR_KNN_MORE, UINT32_MAX, max_d2, idx, dist2);
        }
    }
    return CREDIT_NONE;
}

/* Near field: rays from the cache, each hit within the near radius credits its solid angle (and its
 * direction) to the nearest surfel that faces the cache on the hit surface. Only surfels whose
 * centre lies within the near radius are credited, the same surfels the disc pass skipped.
 * The rays go on to unlimited length (the first hit within R is the same either way): the return
 * value counts the rays whose first hit is a front face anywhere, the visible geometry for the
 * normalisation in link_cache. Back faces (no surfels there) and rays into the sky count nothing. */
static uint32_t near_field(const link_job *job, const glow__cache *cache, const cl_runs *runs, float *omega,
                           float *dirsum, double *out_kappa_geom) {
    const bool hemi = cache->kind == GLOW_CACHE_KIND_LIGHTMAP;
    const uint32_t count = hemi ? NEAR_RAYS / 2 : NEAR_RAYS;
    const float dw = (float)(4.0 * GLOW__PI / NEAR_RAYS);
    const float R = job->near_radius, eps = job->ray_eps;
    float t[3] = {0}, b[3] = {0};
    uint32_t front_hits = 0;
    /* lightmap caches: the cosine response of the front-face hits as a share of every ray's, so a
     * closed scene gives exactly the full hemisphere's 1 (E/π per unit radiance; the rays' own sum of
     * dw cos/π is 1 only to the direction set's quadrature, 2.7e-4 off here) */
    double k_hit = 0.0, k_all = 0.0;
    if (hemi) tangent_frame(cache->nrm, t, b);
    for (uint32_t r = 0; r < count; ++r) {
        float dir[3];
        if (hemi) {
            const float *l = job->hemi_dirs[r];
            for (int k = 0; k < 3; ++k) dir[k] = l[0] * t[k] + l[1] * b[k] + l[2] * cache->nrm[k];
        } else {
            memcpy(dir, job->sphere_dirs[r], sizeof dir);
        }
        glow__hit hit = glow__rt_intersect(job->rt, cache->pos, dir, eps, INFINITY);
        const double kr = hemi ? glow__cos_kernel(glow__dot(dir, cache->nrm)) : 0.0;
        k_all += kr;
        /* another system's surface (a bake split into systems) counts as the sky does: this system
         * links none of its light */
        if (hit.t == INFINITY || hit.back_face || hit.foreign) continue;
        front_hits++;
        k_hit += kr;
        if (!(hit.t < R)) continue; /* beyond the near field: counted, not credited */
        /* a surfel more than 2R from the hit (hit.t < R) is more than R from the cache: never credited */
        const uint32_t unit = credit_hit(job, cache->pos, hemi ? cache->nrm : NULL, R, dir, &hit, runs, 4.04f * R * R);
        if (unit != CREDIT_NONE) {
            omega[unit] += dw;
            for (int k = 0; k < 3; ++k) dirsum[3 * unit + k] += dw * dir[k];
        }
    }
    if (hemi && k_all > 0.0) *out_kappa_geom += k_hit / k_all;
    return front_hits;
}

/* Node v's solid angle, direction sum and diffuse response from the runs (the part of each run that
 * overlaps its leaves), into omega/dirsum/kappa[v]; a no-op in the exact pass, whose arrays are full. */
static void node_vals(const link_job *job, cl_runs *r, uint32_t v, float *omega, float *dirsum, float *kappa) {
    if (!r->active || r->stamp[v] == r->tag) return;
    r->stamp[v] = r->tag;
    const uint32_t a = job->leaf_first[v], b = job->leaf_end[v];
    const uint32_t j0 = runs_end_after(r, a), j1 = runs_start_from(r, b);
    double w = 0.0, d[3] = {0.0, 0.0, 0.0}, k = 0.0;
    if (j0 + 1 < j1) { /* whole runs between the end runs */
        w = r->pw[j1 - 1] - r->pw[j0 + 1];
        k = r->pk[j1 - 1] - r->pk[j0 + 1];
        for (int q = 0; q < 3; ++q) d[q] = r->pd[3 * (j1 - 1) + q] - r->pd[3 * (j0 + 1) + q];
    }
    for (uint32_t j = j0; j < j1; j = (j == j0 && j1 - 1 > j0) ? j1 - 1 : j1) {
        const uint32_t lo = r->a[j] > a ? r->a[j] : a, hi = r->b[j] < b ? r->b[j] : b;
        const double *A = job->leaf_area;
        const double f = (A[hi] - A[lo]) / (A[r->b[j]] - A[r->a[j]]);
        w += f * r->w[j];
        k += f * r->k[j];
        for (int q = 0; q < 3; ++q) d[q] += f * r->d[3 * j + q];
    }
    omega[v] = (float)w;
    kappa[v] = (float)k;
    for (int q = 0; q < 3; ++q) dirsum[3 * v + q] = (float)d[q];
}

/* The total variation of cut_priority over the runs: leaves of a run share its solid angle by their
 * areas, leaves in no run have none. */
static double runs_tv(const link_job *job, const cl_runs *r, uint32_t v, double om, bool resp_k) {
    const float *rw = resp_k ? r->k : r->w;
    const uint32_t a = job->leaf_first[v], b = job->leaf_end[v];
    const double *A = job->leaf_area;
    const double inv_om = 1.0 / om, inv_area = 1.0 / (A[b] - A[a]);
    double tv = 0.0, covered = 0.0;
    for (uint32_t j = runs_end_after(r, a); j < r->count && r->a[j] < b; ++j) {
        const uint32_t lo = r->a[j] > a ? r->a[j] : a, hi = r->b[j] < b ? r->b[j] : b;
        const double part = A[hi] - A[lo];
        tv += fabs(rw[j] * part / (A[r->b[j]] - A[r->a[j]]) * inv_om - part * inv_area);
        covered += part;
    }
    tv += ((A[b] - A[a]) - covered) * inv_area;
    return 0.5 * tv;
}

/* A node one of whose children is invisible from the cache links exactly what its visible child
 * links, less the invisible child's flux that the node's mean radiosity would dilute it with: descend
 * to the smallest subtree that holds all the node's visible leaves. Free: the cut keeps its size. */
static uint32_t cut_descend(const link_job *job, cl_runs *r, float *omega, float *dirsum, float *kappa, uint32_t v) {
    if (!job->settings->cut_error) return v; /* the published cut */
    const glow__hierarchy *h = job->h;
    for (;;) {
        const glow__node *nd = &h->nodes[v];
        if (nd->child[0] == GLOW_NODE_NONE) return v;
        node_vals(job, r, nd->child[0], omega, dirsum, kappa);
        node_vals(job, r, nd->child[1], omega, dirsum, kappa);
        const bool a = omega[nd->child[0]] > 0.0f, b = omega[nd->child[1]] > 0.0f;
        if (a && b) return v;
        v = a ? nd->child[0] : nd->child[1];
    }
}

/* Split priority of a cut node v: a bound on the error its link can make, in units of
 * (visible solid angle x radiosity contrast). The link applies the node's mean radiosity (its flux
 * over its area), i.e. weight a_i = A_i/A_v to each leaf, where the exact gather weights leaf i by
 * ω_i/ω_v (hidden leaves by 0). The gather error is Σ_i (ω_i/ω_v − a_i) B_i, at most
 * ω_v · D_v · (B_max − B_min) with D_v the total variation distance ½ Σ_i |ω_i/ω_v − a_i| between the
 * two weightings (a_i = 1/n before surfel areas varied, docs/linker.md): D_v is at least the node's
 * hidden fraction (the cause of the energy loss and of contact leaks, docs/linker.md) and also counts
 * visible leaves seen at very different solid angles. A node that is fully and evenly visible still
 * errs in direction (one cone for a spread of directions): its spread 1 − |Σ ω_i d_i| / ω_v, which is
 * (1 − cos α)/2 for a cap of half-angle α, so for such nodes the order is that of the solid angle, the
 * published priority (PIC 4.5).
 * Lightmap caches (kappa non-NULL) gather each leaf by its diffuse response κ_i = ω_i max(0, d_i · n)/π, not
 * its solid angle, so both the scale and D_v are taken in κ: a node seen at grazing incidence (the
 * ceiling above a wall texel) has a large ω but adds little to the texel's light, and splitting it
 * spent links the nodes the texel does gather from needed (CornellBox-Sphere under a point light near
 * its ceiling: block error 0.119 → 0.099 over surfel seeds 0-3, Sponza 0.0919 → 0.0909,
 * docs/linker.md "The cut and its audit"). Grid caches keep ω (they gather the whole sphere). */
static float cut_priority(const link_job *job, const cl_runs *r, const float *omega, const float *dirsum,
                          const float *kappa, uint32_t v) {
    if (job->settings->join && job->settings->join[v]) return INFINITY; /* joins trees: never a link */
    if (!job->settings->cut_error || !(omega[v] > 0.0f)) return omega[v]; /* the published priority (PIC 4.5) */
    const float *ds = &dirsum[3 * v];
    float spread = 1.0f - sqrtf(glow__dot(ds, ds)) / omega[v];
    spread = spread < 0.0f ? 0.0f : spread;
    const bool resp_k = kappa != NULL;
    const float *resp = resp_k ? kappa : omega;
    const float om = resp[v];
    if (!(om > 0.0f)) return 0.0f;
    const uint32_t a = job->leaf_first[v], b = job->leaf_end[v];
    double tv = 0.0;
    if (r->active) {
        if (b - a > 1) tv = runs_tv(job, r, v, om, resp_k);
    } else if (b - a > 1) {
        const double *A = job->leaf_area;
        const double inv_om = 1.0 / om, inv_area = 1.0 / (A[b] - A[a]);
        for (uint32_t i = a; i < b; ++i) tv += fabs(resp[i] * inv_om - (A[i + 1] - A[i]) * inv_area);
        tv *= 0.5;
    }
    return om * (float)(tv + spread);
}

/* Audit: link v's gather if it read its node's mean radiance times 1 + γ·(p_B − c): c the node's area
 * centroid, p_B its flux-weighted centroid (known at run time from the pull), γ = C⁻¹ (p_w − c) the
 * area-weighted least-squares gradient of the cache's response per unit area across the node (C the
 * leaves' position covariance, p_w the response-weighted centroid; fixed at bake time). Exact when the
 * response per unit area is linear in position over the node. */
static double audit_gradient_q(const link_job *job, const float *wt, const float *B, uint32_t v, bool quantised,
                               uint16_t code);
static double audit_gradient(const link_job *job, const float *wt, const float *B, uint32_t v) {
    return audit_gradient_q(job, wt, B, v, false, 0);
}
/* The same with the link's LSUB gradient code (quantised: the runtime's 1 + (k / 15) . u, u = sigma
 * (C + eps I)^-1 (p_B - c); code 0 reads the node's mean), or the exact gamma (!quantised) */
static double audit_gradient_q(const link_job *job, const float *wt, const float *B, uint32_t v, bool quantised,
                               uint16_t code) {
    const glow__surfels *S = job->surfels;
    const uint32_t a = job->leaf_first[v], b = job->leaf_end[v];
    double A = 0, W = 0, F = 0, c[3] = {0, 0, 0}, pw[3] = {0, 0, 0}, pb[3] = {0, 0, 0}, C[6] = {0, 0, 0, 0, 0, 0};
    for (uint32_t i = a; i < b; ++i) {
        const double ai = S->s[i].area, wi = wt[i] > 0.0f ? wt[i] : 0.0, fi = ai * B[i];
        A += ai, W += wi, F += fi;
        for (int k = 0; k < 3; ++k) c[k] += ai * S->s[i].pos[k], pw[k] += wi * S->s[i].pos[k], pb[k] += fi * S->s[i].pos[k];
    }
    if (!(A > 0.0) || !(W > 0.0) || !(F > 0.0)) return 0.0;
    for (int k = 0; k < 3; ++k) c[k] /= A, pw[k] = pw[k] / W - c[k], pb[k] = pb[k] / F - c[k];
    for (uint32_t i = a; i < b; ++i) {
        const double ai = S->s[i].area / A, d[3] = {S->s[i].pos[0] - c[0], S->s[i].pos[1] - c[1], S->s[i].pos[2] - c[2]};
        C[0] += ai * d[0] * d[0], C[1] += ai * d[0] * d[1], C[2] += ai * d[0] * d[2];
        C[3] += ai * d[1] * d[1], C[4] += ai * d[1] * d[2], C[5] += ai * d[2] * d[2];
    }
    const double eps = 1e-3 * (C[0] + C[3] + C[5]) + 1e-30;
    const double m00 = C[0] + eps, m01 = C[1], m02 = C[2], m11 = C[3] + eps, m12 = C[4], m22 = C[5] + eps;
    const double i00 = m11 * m22 - m12 * m12, i01 = m02 * m12 - m01 * m22, i02 = m01 * m12 - m02 * m11;
    const double i11 = m00 * m22 - m02 * m02, i12 = m01 * m02 - m00 * m12, i22 = m00 * m11 - m01 * m01;
    const double det = m00 * i00 + m01 * i01 + m02 * i02;
    if (!(fabs(det) > 0.0)) return W * F / A;
    if (quantised) {
        if (!code) return W * F / A;
        const double sigma = sqrt(C[0] + C[3] + C[5]);
        const double u[3] = {sigma * (i00 * pb[0] + i01 * pb[1] + i02 * pb[2]) / det,
                             sigma * (i01 * pb[0] + i11 * pb[1] + i12 * pb[2]) / det,
                             sigma * (i02 * pb[0] + i12 * pb[1] + i22 * pb[2]) / det};
        double sc = 1.0;
        for (int k = 0; k < 3; ++k) sc += ((double)((code >> (5 * k)) & 31u) - 15.0) / 15.0 * u[k];
        return W * F / A * (sc > 0.0 ? sc : 0.0);
    }
    const double g[3] = {(i00 * pw[0] + i01 * pw[1] + i02 * pw[2]) / det, (i01 * pw[0] + i11 * pw[1] + i12 * pw[2]) / det,
                         (i02 * pw[0] + i12 * pw[1] + i22 * pw[2]) / det};
    const double sc = 1.0 + g[0] * pb[0] + g[1] * pb[1] + g[2] * pb[2];
    return W * F / A * (sc > 0.0 ? sc : 0.0); /* a clamp at 2 or 4 above changed nothing measurable */
}

/* Node v's radiance as the runtime pulls it: its leaves' flux over its area (B: one radiance per leaf) */
static double leaf_mean(const link_job *job, const float *B, uint32_t v) {
    const uint32_t a = job->leaf_first[v], b = job->leaf_end[v];
    const double *A = job->leaf_area;
    double sum = 0.0;
    for (uint32_t i = a; i < b; ++i) sum += (A[i + 1] - A[i]) * B[i];
    return sum / (A[b] - A[a]);
}

/* Audit: the gather of one link if it read, instead of its node's mean, the means of the node's
 * visible descendants `levels` levels down (or leaves), each weighted by its own visible share wt. */
static double audit_descendants(const link_job *job, const float *wt, const float *omega, const float *B, uint32_t v,
                                uint32_t levels) {
    uint32_t stack[64], depth[64], sp = 0;
    double g = 0.0;
    stack[sp] = v;
    depth[sp++] = 0;
    while (sp) {
        --sp;
        const uint32_t u = stack[sp], dd = depth[sp];
        const glow__node *nu = &job->h->nodes[u];
        if (nu->child[0] == GLOW_NODE_NONE || dd == levels) {
            g += wt[u] * leaf_mean(job, B, u);
            continue;
        }
        for (int c = 0; c < 2; ++c)
            if (omega[nu->child[c]] > 0.0f && sp < 64) {
                stack[sp] = nu->child[c];
                depth[sp++] = dd + 1;
            }
    }
    return g;
}

/* Below this total variation between a link's slot weights and the slots' shares of its node's area
 * the link stores no weights (it reads the node's mean). Sponza, seeds 0-1 (docs/results.md): 0 puts
 * weights on 76 % of the links, 0.1 on 60 % for the same image error (0.1511/0.1400 against
 * 0.1520/0.1397), 0.2 on 38 % and loses a third of the gain. The kernel's cost follows the share of
 * 8-link groups with weights. */
#define GLOW__SUBSET_MIN_TV 0.1

/* LSUB weights of node v's four slots (bake_format.h): each slot's share of the link's response wt
 * (the diffuse response for lightmap caches, the solid angle for grid caches), the largest scaled to
 * 15. A slot that repeats the one before it (a leaf child) gets 0. 0 (the link reads the node's mean)
 * where nothing below v is seen. */
static void link_slots(const glow__hierarchy *h, uint32_t v, uint32_t slot[4]) {
    const glow__node *nv = &h->nodes[v];
    const uint32_t none[2] = {GLOW_NODE_NONE, GLOW_NODE_NONE};
    glow_bake_link_slots(v, nv->child, nv->child[0] != GLOW_NODE_NONE ? h->nodes[nv->child[0]].child : none,
                         nv->child[1] != GLOW_NODE_NONE ? h->nodes[nv->child[1]].child : none, slot);
}

static uint16_t link_subsets(const glow__hierarchy *h, const float *wt, uint32_t v) {
    const glow__node *nv = &h->nodes[v];
    uint32_t slot[4];
    link_slots(h, v, slot);
    float w[4], wmax = 0.0f;
    for (int i = 0; i < 4; ++i) {
        w[i] = (i > 0 && slot[i] == slot[i - 1]) ? 0.0f : wt[slot[i]];
        if (!(w[i] > 0.0f)) w[i] = 0.0f;
        if (w[i] > wmax) wmax = w[i];
    }
    if (!(wmax > 0.0f)) return 0;
    uint16_t q = 0;
    uint32_t qi[4], qs = 0;
    for (int i = 0; i < 4; ++i) {
        qi[i] = (uint32_t)lrintf(15.0f * (w[i] / wmax));
        qs += qi[i];
        q |= (uint16_t)(qi[i] << (4 * i));
    }
    /* weights that give the slots their shares of the node's area read the node's mean anyway:
     * below a total variation of GLOW__SUBSET_MIN_TV from those shares, store none (the kernel
     * skips lanes without weights) */
    double tv = 0.0;
    for (int i = 0; i < 4; ++i) {
        const double ai = (i > 0 && slot[i] == slot[i - 1]) ? 0.0 : (double)h->nodes[slot[i]].area / nv->area;
        tv += fabs((double)qi[i] / qs - ai);
    }
    if (0.5 * tv < GLOW__SUBSET_MIN_TV) return 0;
    return q;
}

/* link_subsets with the slots' sums read first (clustered visibility fills them on demand) */
static uint16_t link_subsets_of(const link_job *job, cl_runs *r, bool hemi, float *omega, float *dirsum, float *kappa,
                                uint32_t v) {
    /* a neighbour's node is a proxy at run time, which carries no grandchildren (bake_format.h XREF) */
    if (job->settings->own_leaves && job->leaf_first[v] >= job->settings->own_leaves) return 0;
    uint32_t slot[4];
    link_slots(job->h, v, slot);
    for (int i = 0; i < 4; ++i) node_vals(job, r, slot[i], omega, dirsum, kappa);
    return link_subsets(job->h, hemi ? kappa : omega, v);
}

/* Link gradients (GLOW_LINK_KIND_GRADIENT, bake_format.h): the LSUB code of link v, the offset of the
 * cache's response-weighted centroid p_w from the node's area centroid c in units of the node's
 * radius sigma = sqrt(trace C) (C the leaves' area-weighted position covariance), each component
 * clamped to [-1, 1] and quantised to k in [-15, 15]. The runtime reads the node's radiance times
 * 1 + (k / 15) . u, u = sigma C^-1 (p_B - c) from the node's flux centroid p_B: audit_gradient's
 * 1 + gamma . (p_B - c) with gamma = C^-1 (p_w - c). 0 (the node's mean) for a leaf, a node seen by
 * none of its leaves, a neighbour's node (a proxy at run time) or an offset that rounds to 0.
 * The response per leaf is the cache's (kappa for lightmap caches, omega for grid caches): with
 * active runs (clustered visibility) each run's spread over its leaves by area, as node_vals does. */
static uint16_t link_gradient(const link_job *job, const cl_runs *r, bool hemi, const float *omega, const float *kappa,
                              uint32_t v) {
    if (job->settings->own_leaves && job->leaf_first[v] >= job->settings->own_leaves) return 0;
    const uint32_t a = job->leaf_first[v], b = job->leaf_end[v];
    if (b - a < 2) return 0;
    const double *gf = &job->grad_frame[4 * (size_t)v], sigma = gf[3];
    if (!(sigma > 0.0)) return 0;
    const double *LA = job->leaf_area;
    double W = 0.0, pw[3] = {0, 0, 0};
    if (r->active) {
        /* each run spreads its response over its leaves by area: its share of [a, b) from the prefix
         * sums (runs and v are subtrees, so a run holds v, lies in it or misses it). Per cache this
         * reads the runs, not the leaves: at 524,288 surfels the leaf loop was 15 % of the bake. */
        const float *rw = hemi ? r->k : r->w;
        const double *LP = job->leaf_apos;
        for (uint32_t j = runs_end_after(r, a); j < r->count && r->a[j] < b; ++j) {
            const double ar = LA[r->b[j]] - LA[r->a[j]];
            if (!(ar > 0.0)) continue;
            const double f = rw[j] / ar;
            if (!(f > 0.0)) continue;
            const uint32_t lo = r->a[j] > a ? r->a[j] : a, hi = r->b[j] < b ? r->b[j] : b;
            W += f * (LA[hi] - LA[lo]);
            for (int k = 0; k < 3; ++k) pw[k] += f * (LP[3 * (size_t)hi + k] - LP[3 * (size_t)lo + k]);
        }
    } else {
        const glow__surfels *S = job->surfels;
        const float *resp = hemi ? kappa : omega;
        for (uint32_t i = a; i < b; ++i) {
            double wi = resp[i];
            if (!(wi > 0.0)) wi = 0.0;
            W += wi;
            for (int k = 0; k < 3; ++k) pw[k] += wi * S->s[i].pos[k];
        }
    }
    if (!(W > 0.0)) return 0;
    uint16_t code = 0x8000u;
    bool any = false;
    for (int k = 0; k < 3; ++k) {
        double e = (pw[k] / W - gf[k]) / sigma;
        e = e < -1.0 ? -1.0 : (e > 1.0 ? 1.0 : e);
        const long q = lrint(15.0 * e);
        any |= q != 0;
        code |= (uint16_t)((uint32_t)(q + 15) << (5 * k));
    }
    return any ? code : 0u;
}

/* link_gradient's cache-independent half, per node: the leaves' area centroid c and radius
 * sigma = sqrt(trace C), C their area-weighted position covariance (sigma 0: no gradient) */
static void gradient_frames(link_job *job) {
    const glow__surfels *S = job->surfels;
    const double *LA = job->leaf_area;
    for (uint32_t v = 0; v < job->h->node_count; ++v) {
        double *gf = &job->grad_frame[4 * (size_t)v];
        gf[0] = gf[1] = gf[2] = gf[3] = 0.0;
        const uint32_t a = job->leaf_first[v], b = job->leaf_end[v];
        if (b - a < 2) continue;
        double A = 0.0, c[3] = {0, 0, 0};
        for (uint32_t i = a; i < b; ++i) {
            const double ai = LA[i + 1] - LA[i];
            A += ai;
            for (int k = 0; k < 3; ++k) c[k] += ai * S->s[i].pos[k];
        }
        if (!(A > 0.0)) continue;
        for (int k = 0; k < 3; ++k) c[k] /= A;
        double tr = 0.0;
        for (uint32_t i = a; i < b; ++i) {
            const double ai = (LA[i + 1] - LA[i]) / A;
            for (int k = 0; k < 3; ++k) tr += ai * (S->s[i].pos[k] - c[k]) * (S->s[i].pos[k] - c[k]);
        }
        if (!(tr > 0.0)) continue;
        for (int k = 0; k < 3; ++k) gf[k] = c[k];
        gf[3] = sqrt(tr);
    }
}

/* A link's LSUB entry: its gradient code or its slot weights, whichever the bake stores */
static uint16_t link_lsub(const link_job *job, cl_runs *r, bool hemi, float *omega, float *dirsum, float *kappa,
                          uint32_t v) {
    if (job->settings->link_gradients) return link_gradient(job, r, hemi, omega, kappa, v);
    return link_subsets_of(job, r, hemi, omega, dirsum, kappa, v);
}

/* Is the point inside the box in which a system's rays see every occluder (trace_lo/hi, inclusive;
 * false for NaN)? */
static inline bool in_trace_box(const glow__link_settings *set, float x, float y, float z) {
    return x >= set->trace_lo[0] && x <= set->trace_hi[0] && y >= set->trace_lo[1] && y <= set->trace_hi[1] &&
           z >= set->trace_lo[2] && z <= set->trace_hi[2];
}

/* A leaf's solid angle seen from the cache before visibility (0: back-facing, below a lightmap
 * cache's horizon, in the near field or degenerate), with its unit direction and distance. */
static float leaf_solid_angle(const link_job *job, const glow__cache *cache, const glow__surfel *s, float dir[3],
                              float *dist) {
    const bool hemi = cache->kind == GLOW_CACHE_KIND_LIGHTMAP;
    const float eps = job->ray_eps;
    const glow__link_settings *set = job->settings;
    if (set->own_leaves && (uint32_t)(s - job->surfels->s) >= set->own_leaves &&
        !in_trace_box(set, s->pos[0], s->pos[1], s->pos[2]))
        return 0.0f; /* a neighbour's leaf beyond the occluders this system traces */
    float d[3];
    glow__sub(s->pos, cache->pos, d);
    float d2 = glow__dot(d, d);
    if (!(d2 > 0.0f)) return 0.0f;
    float inv = 1.0f / sqrtf(d2);
    float cos_s = -glow__dot(s->nrm, d) * inv;
    if (cos_s <= 0.0f) return 0.0f;
    /* Horizon of a lightmap cache: the plane of its surface, which lies `eps` below it (caches.c
     * lifts texels by 1e-4 x diagonal, the same as eps). Half of that keeps its own surface out.
     * Surfels of another surface that meets this one lie in that plane too where relaxation
     * pushed them onto the shared edge (2.6x the mean density there in the furnace box); they
     * stand for the strip of their surface above the edge, so they stay in when their normal
     * differs from the cache's by more than ~25°. Dropping them cost a floor texel 12 % of its
     * solid angle within 7° of the horizon, which the normalisation below would have spread
     * over the whole hemisphere (+2 % cosine-weighted irradiance per bounce). */
    if (hemi) {
        float up = glow__dot(cache->nrm, d);
        if (up <= -0.5f * eps && !(up > -1.5f * eps && glow__dot(s->nrm, cache->nrm) < 0.9f)) return 0.0f;
    }
    if (d2 < job->near_radius * job->near_radius) return 0.0f; /* measured by the near-field rays */
    float w = disc_solid_angle(s->area, d2, cos_s);
    if (!(w > 0.0f)) return 0.0f;
    for (int k = 0; k < 3; ++k) dir[k] = d[k] * inv;
    *dist = sqrtf(d2);
    return w;
}

/* Queue one visibility ray for run j; a full packet is traced and its blocked runs see nothing. */
typedef struct ray_packet {
    uint32_t n, run[16], run_end[16]; /* a ray decides runs [run, run_end) */
    float dir[16][3], tfar[16];
} ray_packet;
static void packet_flush(const link_job *job, const glow__cache *cache, ray_packet *p, cl_runs *r) {
    if (!p->n) return;
    uint8_t occ[16];
    glow__rt_occluded16(job->rt, cache->pos, (const float(*)[3])p->dir, p->tfar, p->n, job->ray_eps, occ);
    for (uint32_t q = 0; q < p->n; ++q)
        if (occ[q])
            for (uint32_t j = p->run[q]; j < p->run_end[q]; ++j) r->w[j] = 0.0f;
    p->n = 0;
}
static void packet_add(const link_job *job, const glow__cache *cache, ray_packet *p, cl_runs *r, uint32_t j,
                       uint32_t j_end, const float dir[3], float dist) {
    p->run[p->n] = j;
    p->run_end[p->n] = j_end;
    memcpy(p->dir[p->n], dir, 3 * sizeof(float));
    p->tfar[p->n] = dist - job->ray_eps;
    if (++p->n == 16) packet_flush(job, cache, p, r);
}

/* The K subtrees of preorder entry t that a cluster's rays go to: split the one with the most leaves
 * until there are K (or none splits), in leaf order. sub[] holds preorder indices: a node's children
 * are the next entry and the one after its subtree, and preorder is leaf order, so no node array is
 * read. Returns how many. */
static uint32_t cluster_split(const trav_node *T, uint32_t t, uint32_t K, uint32_t sub[64]) {
    uint32_t ns = 1;
    sub[0] = t;
    while (ns < K) {
        uint32_t best = UINT32_MAX, bm = 1;
        for (uint32_t q = 0; q < ns; ++q) {
            const uint32_t mq = T[sub[q]].end - T[sub[q]].first;
            if (mq > bm) { bm = mq; best = q; }
        }
        if (best == UINT32_MAX) break;
        const uint32_t lo = sub[best] + 1, hi = T[lo].skip; /* lower and higher leaves */
        const bool c0_low = T[sub[best]].child0_low != 0; /* keep the node's child order */
        sub[best] = c0_low ? lo : hi;
        sub[ns++] = c0_low ? hi : lo;
    }
    for (uint32_t q = 1; q < ns; ++q)
        for (uint32_t y = q; y > 0 && sub[y - 1] > sub[y]; --y) {
            const uint32_t x = sub[y]; sub[y] = sub[y - 1]; sub[y - 1] = x;
        }
    return ns;
}

/* How a node beyond the near field looks from the cache (the descent's tests, clustered_runs and
 * mixed_part), with dv = its centre minus the cache's position and dist = |dv|: NODE_HIDDEN when it
 * lies wholly below a lightmap cache's horizon or every normal of its cone faces away; NODE_WHOLE
 * when every normal faces the cache and all of it is above the horizon; else NODE_MIXED. *up: how
 * far its centre lies above the horizon (INFINITY for grid caches). */
enum { NODE_HIDDEN, NODE_WHOLE, NODE_MIXED };
static inline int node_view(const trav_node *tn, const glow__cache *cache, float eps, const float dv[3], float dist,
                            float *up) {
    const float half_pi = (float)(0.5 * GLOW__PI), rad = tn->radius;
    *up = cache->kind == GLOW_CACHE_KIND_LIGHTMAP ? glow__dot(cache->nrm, dv) : INFINITY;
    if (*up + rad < -1.5f * eps) return NODE_HIDDEN; /* wholly below the horizon */
    const float facing = -glow__dot(tn->nrm, dv) / dist; /* cos of the axis against the way back */
    const float th = acosf(facing < -1.0f ? -1.0f : (facing > 1.0f ? 1.0f : facing));
    const float rho = asinf(rad < dist ? rad / dist : 1.0f), cone = tn->cone;
    if (th - cone - rho > half_pi) return NODE_HIDDEN; /* every normal faces away */
    return th + cone + rho < half_pi && *up - rad > 0.5f * eps ? NODE_WHOLE : NODE_MIXED;
}

/* leaf_solid_angle for leaves [a, a + n) of a cluster that lies wholly where the system's rays see
 * every occluder (so its leaves pass the own_leaves test), by plane from job->leaf_soa: w[j] the
 * solid angle (0 where leaf_solid_angle gives 0) and (x, y, z)[j] the unit direction. The same
 * float operations in the same order, so the same values to the bit (no contraction: ISO C mode
 * keeps -ffp-contract=off), in a loop the compiler vectorises; on x86-64, one clone per vector
 * width, chosen at load time. Sums of mixed clusters' leaves were 15 % of the 524k Sponza bake. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define LEAF_BATCH_ATTR __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"), optimize("tree-vectorize", "vect-cost-model=dynamic")))
#else
#define LEAF_BATCH_ATTR
#endif
LEAF_BATCH_ATTR static void leaf_batch(const float *soa, uint32_t count, uint32_t a, uint32_t n, const float c[3],
                                       const float cn[3], int hemi, float eps, float near2, float *restrict w,
                                       float *restrict x, float *restrict y, float *restrict z) {
    const float *restrict px = soa + a, *restrict py = px + count, *restrict pz = py + count;
    const float *restrict nx = pz + count, *restrict ny = nx + count, *restrict nz = ny + count;
    const float *restrict ar = nz + count;
    const float c0 = c[0], c1 = c[1], c2 = c[2], n0 = cn[0], n1 = cn[1], n2 = cn[2];
    for (uint32_t j = 0; j < n; ++j) {
        const float dx = px[j] - c0, dy = py[j] - c1, dz = pz[j] - c2;
        const float d2 = dx * dx + dy * dy + dz * dz;
        const float inv = 1.0f / sqrtf(d2);
        const float cs = -(nx[j] * dx + ny[j] * dy + nz[j] * dz) * inv;
        const float up = n0 * dx + n1 * dy + n2 * dz;
        const float nn = nx[j] * n0 + ny[j] * n1 + nz[j] * n2;
        const float r2 = ar[j] / (float)GLOW__PI;
        const float v = (float)(2.0 * GLOW__PI) * (1.0f - sqrtf(d2) / sqrtf(d2 + r2)) * cs;
        const int below = hemi && up <= -0.5f * eps && !(up > -1.5f * eps && nn < 0.9f);
        const int ok = d2 > 0.0f && cs > 0.0f && !below && !(d2 < near2) && v > 0.0f;
        w[j] = ok ? v : 0.0f;
        x[j] = dx * inv;
        y[j] = dy * inv;
        z[j] = dz * inv;
    }
}

/* Where a neighbour's node lies against the box in which a system's rays see every occluder
 * (glow__link_settings trace_lo/hi; bounded by its centre and radius): wholly beyond it, wholly inside
 * or across its border. A system's own nodes are always inside. */
enum { TRACE_OUT, TRACE_IN, TRACE_ACROSS };
static int trace_box(const link_job *job, const trav_node *tn) {
    const glow__link_settings *set = job->settings;
    if (!set->own_leaves || tn->first < set->own_leaves) return TRACE_IN;
    bool out = false, in = true;
    for (int k = 0; k < 3; ++k) {
        out = out || tn->pos[k] + tn->radius < set->trace_lo[k] || tn->pos[k] - tn->radius > set->trace_hi[k];
        in = in && tn->pos[k] - tn->radius >= set->trace_lo[k] && tn->pos[k] + tn->radius <= set->trace_hi[k];
    }
    return out ? TRACE_OUT : in ? TRACE_IN : TRACE_ACROSS;
}

/* A mixed cluster's part (not every normal faces the cache, or it straddles the horizon): the
 * stretches of its leaves (preorder subtree t) that add to the solid angle, each appended to r as a
 * run with its solid angle and direction, and the leaf the part's one ray goes to (pick: the one that
 * adds nearest the middle of the part's leaf range, mid). A subtree of at most CLUSTER_SUM_LEAVES
 * leaves sums its leaves' own solid angles; a larger one is read as the descent reads clusters:
 * wholly below the horizon, in the plane of the cache's own surface or facing away, nothing; wholly
 * facing and above the horizon, its aggregate (area x cosine of its normal sum over its centre's
 * squared distance); otherwise its two children in turn. Leaves that add nothing (facing away, below
 * the horizon) end a run, so they take no share of the part's solid angle: a wall's far face in
 * the same cluster as its near face is not linked (test_stability_leak). boxed (a neighbour's
 * cluster across the traced box, trace_box): leaves beyond the box add nothing either, and only a
 * subtree wholly inside it gives its aggregate. */
typedef struct mix_run {
    uint32_t a, b; /* the open stretch [a, b), none while a == b */
    float w, d[3];
} mix_run;
static void mix_close(mix_run *m, cl_runs *r, uint32_t *R) {
    if (m->a == m->b) return;
    const float dl = sqrtf(glow__dot(m->d, m->d));
    if (m->w > 0.0f && dl > 0.0f) {
        r->a[*R] = m->a;
        r->b[*R] = m->b;
        r->w[*R] = m->w;
        for (int q = 0; q < 3; ++q) r->d[3 * *R + q] = m->d[q] / dl;
        (*R)++;
    }
    m->a = m->b = 0;
    m->w = m->d[0] = m->d[1] = m->d[2] = 0.0f;
}
static void mix_add(mix_run *m, cl_runs *r, uint32_t *R, uint32_t a, uint32_t b, float w, float dx, float dy,
                    float dz) {
    if (m->a == m->b || m->b != a) {
        mix_close(m, r, R);
        m->a = a;
    }
    m->b = b;
    m->w += w;
    m->d[0] += w * dx;
    m->d[1] += w * dy;
    m->d[2] += w * dz;
}
static void mixed_part(const link_job *job, const glow__cache *cache, uint32_t t, float mid, uint32_t *pick,
                       cl_runs *r, uint32_t *R, bool boxed) {
    const trav_node *T = job->trav;
    const glow__surfels *S = job->surfels;
    const bool hemi = cache->kind == GLOW_CACHE_KIND_LIGHTMAP;
    const float eps = job->ray_eps;
    float best = INFINITY;
    mix_run m = {0};
    const uint32_t stop = T[t].skip;
    for (uint32_t u = t, nx; u < stop; u = nx) {
        const trav_node *tu = &T[u];
        nx = tu->skip;
        const int where = boxed ? trace_box(job, tu) : TRACE_IN;
        if (where == TRACE_OUT) continue; /* beyond the traced box: hidden, as its leaves */
        if (tu->end - tu->first <= CLUSTER_SUM_LEAVES) {
            float lw[CLUSTER_SUM_LEAVES], lx[CLUSTER_SUM_LEAVES], ly[CLUSTER_SUM_LEAVES], lz[CLUSTER_SUM_LEAVES];
            const uint32_t n = tu->end - tu->first;
            leaf_batch(job->leaf_soa, S->count, tu->first, n, cache->pos, cache->nrm, hemi, eps,
                       job->near_radius * job->near_radius, lw, lx, ly, lz);
            if (where == TRACE_ACROSS) { /* leaf_solid_angle's test, leaf by leaf */
                const glow__link_settings *set = job->settings;
                const float *px = job->leaf_soa + tu->first, *py = px + S->count, *pz = py + S->count;
                for (uint32_t j = 0; j < n; ++j)
                    if (!in_trace_box(set, px[j], py[j], pz[j])) lw[j] = 0.0f;
            }
            for (uint32_t j = 0; j < n; ++j) { /* in leaf order */
                const float wi = lw[j];
                if (!(wi > 0.0f)) continue;
                const uint32_t i = tu->first + j;
                mix_add(&m, r, R, i, i + 1, wi, lx[j], ly[j], lz[j]);
                const float off = fabsf((float)i - mid);
                if (off < best) { best = off; *pick = i; }
            }
            continue;
        }
        float dv[3];
        glow__sub(tu->pos, cache->pos, dv);
        const float dist = sqrtf(glow__dot(dv, dv)), rad = tu->radius;
        float up;
        const int view = node_view(tu, cache, eps, dv, dist, &up);
        if (view == NODE_HIDDEN) continue;
        if (hemi) { /* in the plane of the cache's own surface, facing as it does: leaf_solid_angle
                     * gives every leaf 0 (up to 0.5 eps below the horizon, normals within ~25°) */
            const float ca = glow__dot(tu->nrm, cache->nrm), cc = cosf(tu->cone);
            const float sa = sqrtf(fmaxf(0.0f, 1.0f - ca * ca)), sc = sqrtf(fmaxf(0.0f, 1.0f - cc * cc));
            /* up_i <= up + cos a lift + sin a rad for every leaf, a the angle between the normals */
            if (ca > 0.0f && ca * cc - sa * sc >= 0.9f && up + ca * job->lift[u] + sa * rad <= -0.75f * eps) continue;
        }
        if (view == NODE_WHOLE && where == TRACE_IN) { /* wholly facing: the aggregate */
            const float wu = S->area * -glow__dot(tu->nsum, dv) / (dist * dist * dist);
            if (!(wu > 0.0f)) continue;
            mix_add(&m, r, R, tu->first, tu->end, wu, dv[0] / dist, dv[1] / dist, dv[2] / dist);
            const uint32_t i = tu->first + (tu->end - tu->first) / 2;
            const float off = fabsf((float)i - mid);
            if (off < best) { best = off; *pick = i; }
            continue;
        }
        nx = u + 1; /* open it */
    }
    mix_close(&m, r, R);
}

/* Clustered visibility's pass 1 (see cl_runs): the runs, in leaf order, with their solid angles
 * after visibility and ω-weighted directions. Returns the run count. */
static uint32_t clustered_runs(link_job *job, const glow__cache *cache, uint32_t worker, cl_runs *r) {
    const glow__hierarchy *h = job->h;
    const glow__surfels *S = job->surfels;
    const float eps = job->ray_eps, tau = job->settings->cluster_tau;
    const uint32_t K = job->settings->cluster_samples;
    uint32_t R = 0;
    uint64_t nrays = 0, ncl = 0; /* visibility rays, and those for clusters */
    ray_packet pk = {0};
    for (uint32_t t = 0, next; t < h->node_count; t = next) {
        const trav_node *tn = &job->trav[t];
        const uint32_t v = tn->id & ~TRAV_EMISSIVE;
        next = tn->skip;
        /* where the descent goes if it stops here: fetch it while this node is decided */
#if defined(__GNUC__) || defined(__clang__)
        if (next < h->node_count) __builtin_prefetch(&job->trav[next]); /* 524k surfels: links -9 % */
        if (job->quad) __builtin_prefetch(&job->quad[t]);
#endif
        if (v < h->leaf_count) { /* a single leaf: the exact pass's solid angle and ray */
            float dir[3] = {0.0f, 0.0f, 0.0f}, dist = 0.0f;
            const float w = leaf_solid_angle(job, cache, &S->s[v], dir, &dist);
            r->a[R] = v;
            r->b[R] = v + 1;
            r->w[R] = w > 0.0f ? w : 0.0f;
            memcpy(&r->d[3 * R], dir, sizeof dir);
            if (w > 0.0f) {
                packet_add(job, cache, &pk, r, R, R + 1, dir, dist);
                nrays++;
            }
            R++;
            continue;
        }
        /* where the system's rays see every occluder: a neighbour's subtree wholly beyond them is hidden,
         * as its leaves; one across their border is read as a mixed cluster whose leaves beyond add
         * nothing (before 2026-11-30 it was opened down to single leaves: 500-900 of a level system's
         * rays a cache went to its neighbours' leaves along the border) */
        const int where = trace_box(job, tn);
        if (where == TRACE_OUT) continue;
        float dv[3];
        glow__sub(tn->pos, cache->pos, dv);
        const float dist = sqrtf(glow__dot(dv, dv)), rad = tn->radius;
        if (dist - rad > job->near_radius) { /* wholly beyond the near field: cull or cluster */
            float up;
            const int view = node_view(tn, cache, eps, dv, dist, &up);
            if (view == NODE_HIDDEN) continue;
            const uint32_t m = tn->end - tn->first;
            /* every normal faces the cache and all of it is above the horizon: the aggregate; else
             * each part's stretches of leaves that add (mixed_part) */
            const bool whole = view == NODE_WHOLE && where == TRACE_IN;
            if (m >= 2u * K && rad <= tau * dist && !(tn->id & TRAV_EMISSIVE)) {
                /* the runs: K subtrees of v (split the one with the most leaves until there are K),
                 * in leaf order */
                const trav_node *T = job->trav;
                uint32_t sub[64], ns, bnd[65];
                if (job->quad) {
                    const trav_quad *qd = &job->quad[t];
                    ns = qd->ns;
                    bnd[0] = tn->first;
                    for (uint32_t k = 0; k < ns; ++k) {
                        sub[k] = qd->sub[k];
                        bnd[k + 1] = k + 1 < ns ? qd->bnd[k] : tn->end;
                    }
                } else {
                    ns = cluster_split(T, t, K, sub);
                    for (uint32_t k = 0; k < ns; ++k) bnd[k] = T[sub[k]].first;
                    bnd[ns] = tn->end;
                }
#if defined(__GNUC__) || defined(__clang__)
                /* the parts' own entries (centres and normal sums, or where a mixed part's descent
                 * starts): fetch them together */
                for (uint32_t k = 0; k < ns; ++k) __builtin_prefetch(&T[sub[k]]);
#endif
                for (uint32_t k = 0; k < ns; ++k) {
                    const uint32_t sa = bnd[k], sb = bnd[k + 1], R0 = R;
                    uint32_t pick = sa + (sb - sa) / 2;
                    if (whole) { /* the subtree's aggregate from its own centre */
                        float dk[3], dsum[3];
                        glow__sub(T[sub[k]].pos, cache->pos, dk);
                        const float lk = sqrtf(glow__dot(dk, dk));
                        for (int q = 0; q < 3; ++q) dsum[q] = dk[q] / lk;
                        const float w = S->area * -glow__dot(T[sub[k]].nsum, dsum) / (lk * lk);
                        if (!(w > 0.0f)) continue;
                        r->a[R] = sa;
                        r->b[R] = sb;
                        r->w[R] = w;
                        memcpy(&r->d[3 * R], dsum, sizeof dsum);
                        R++;
                    } else { /* its stretches of leaves that add to the solid angle, one run each */
                        mixed_part(job, cache, sub[k], 0.5f * (float)(sa + sb - 1), &pick, r, &R, where == TRACE_ACROSS);
                        if (R == R0) continue;
                    }
                    const glow__surfel *mid = &S->s[pick];
                    float dm[3];
                    glow__sub(mid->pos, cache->pos, dm);
                    const float lm = sqrtf(glow__dot(dm, dm));
                    for (int q = 0; q < 3; ++q) dm[q] /= lm;
                    packet_add(job, cache, &pk, r, R0, R, dm, lm);
                    nrays++;
                    ncl++;
                }
                continue;
            }
        }
        next = t + 1; /* open it: its first child (the lower leaves, so the runs come in leaf order) */
    }
    packet_flush(job, cache, &pk, r);
    atomic_fetch_add(&job->vis_rays, nrays);
    atomic_fetch_add(&job->vis_cluster_rays, ncl);
    atomic_fetch_add(&job->vis_units, R);
    for (uint32_t j = 0; j < R; ++j)
        for (int q = 0; q < 3; ++q) r->d[3 * j + q] *= r->w[j];
    r->count = R;
    return R;
}

static void link_cache(link_job *job, uint32_t ci, uint32_t worker) {
    const glow__hierarchy *h = job->h;
    const glow__surfels *S = job->surfels;
    const glow__cache *cache = &job->caches->caches[ci];
    const glow__link_settings *set = job->settings;
    float *omega = job->omega[worker];
    float *dirsum = job->dirsum[worker];
    uint32_t *heap = job->heap[worker];
    const uint32_t n = S->count;
    const bool hemi = cache->kind == GLOW_CACHE_KIND_LIGHTMAP;
    const uint32_t rays = set->rays_per_surfel ? set->rays_per_surfel : 1u;
    const float eps = job->ray_eps;

    /* 1. leaves (exact) or runs of leaves (clustered): solid angles, then visibility in packets of 16
     * rays from the cache. "Units" below are the leaves or the runs. */
    cl_runs *cr = &job->runs[worker];
    cr->active = set->cluster_tau > 0.0f && rays == 1;
    float *kappa = job->kappa[worker];
    const uint32_t fit_bands = job->out->sh_bands;
    float *uw = omega, *ud = dirsum, *uk = kappa;
    uint32_t un = n;
    if (cr->active) {
        un = clustered_runs(job, cache, worker, cr);
        uw = cr->w;
        ud = cr->d;
        uk = cr->k;
    } else {
        uint32_t pending_idx[16];
        float pending_dir[16][3], pending_tfar[16];
        uint8_t occ[16];
        uint32_t pending = 0;
        uint64_t exact_rays = 0;
        for (uint32_t i = 0; i < n; ++i) {
            const glow__surfel *s = &S->s[i];
            float dir[3], len = 0.0f;
            const float w = leaf_solid_angle(job, cache, s, dir, &len);
            omega[i] = 0.0f;
            for (int k = 0; k < 3; ++k) dirsum[3 * i + k] = w > 0.0f ? dir[k] : 0.0f;
            if (!(w > 0.0f)) continue;
            exact_rays += rays;
            if (rays == 1) {
                omega[i] = w; /* tentatively visible; the packet below clears it when blocked */
                pending_idx[pending] = i;
                memcpy(pending_dir[pending], dir, sizeof dir);
                pending_tfar[pending] = len - eps;
                if (++pending == 16) {
                    glow__rt_occluded16(job->rt, cache->pos, (const float(*)[3])pending_dir, pending_tfar, 16, eps, occ);
                    for (uint32_t q = 0; q < 16; ++q)
                        if (occ[q]) omega[pending_idx[q]] = 0.0f;
                    pending = 0;
                }
            } else {
                uint32_t seen = 0;
                for (uint32_t k = 0; k < rays; ++k) {
                    float p[3], dd[3];
                    disc_point(s, sqrtf(s->area / (float)GLOW__PI), k, rays, p);
                    glow__sub(p, cache->pos, dd);
                    float dl = sqrtf(glow__dot(dd, dd));
                    if (!(dl > 2.0f * eps)) { seen++; continue; }
                    if (!glow__rt_occluded(job->rt, cache->pos, dd, eps / dl, 1.0f - eps / dl)) seen++;
                }
                omega[i] = w * (float)seen / (float)rays;
            }
        }
        if (pending) {
            glow__rt_occluded16(job->rt, cache->pos, (const float(*)[3])pending_dir, pending_tfar, pending, eps, occ);
            for (uint32_t q = 0; q < pending; ++q)
                if (occ[q]) omega[pending_idx[q]] = 0.0f;
        }
        for (uint32_t i = 0; i < n; ++i)
            for (int k = 0; k < 3; ++k) dirsum[3 * i + k] *= omega[i];
        atomic_fetch_add(&job->vis_rays, exact_rays);
    }
    double kappa_geom = 0.0; /* lightmap caches: the rays' estimate of the diffuse response of all visible geometry */
    const uint32_t front_hits = near_field(job, cache, cr, uw, ud, &kappa_geom);
    /* a system of a world: its own units come first (runs in leaf order); the near field's rays count
     * only its own surfaces, so only they are normalised (the neighbours' keep their solid angles) */
    uint32_t un_own = un;
    if (set->own_leaves) {
        un_own = 0;
        while (un_own < un && (cr->active ? cr->a[un_own] : un_own) < set->own_leaves) un_own++;
    }
    double leaf_total = 0.0, other_total = 0.0;
    for (uint32_t i = 0; i < un_own; ++i) leaf_total += uw[i];
    for (uint32_t i = un_own; i < un; ++i) other_total += uw[i];
    /* Normalisation (before the sums up the tree): scale every unit's ω, and its ω-weighted
     * direction, so that they add up to the ray-measured solid angle of visible geometry.
     * Nothing to scale towards when no ray hit a front face, nothing to scale when no leaf is
     * visible: those caches stay as they are. */
    job->norm_scale[ci] = 0.0f;
    job->norm_clamped[ci] = 0;
    if (!set->no_normalize && front_hits > 0 && leaf_total > 0.0) {
        double sc = (double)front_hits * (4.0 * GLOW__PI / NEAR_RAYS) / leaf_total;
        if (sc < NORM_MIN || sc > NORM_MAX) {
            sc = sc < NORM_MIN ? NORM_MIN : NORM_MAX;
            job->norm_clamped[ci] = 1;
        }
        const float fs = (float)sc;
        leaf_total = 0.0;
        for (uint32_t i = 0; i < un_own; ++i) {
            if (uw[i] == 0.0f) continue;
            uw[i] *= fs;
            for (int k = 0; k < 3; ++k) ud[3 * i + k] *= fs;
            leaf_total += uw[i];
        }
        job->norm_scale[ci] = fs;
    }
    leaf_total += other_total;
    job->visible_total[ci] = leaf_total;

    /* 2. sums up the tree: children precede parents in node order (clustered: prefix sums over the
     * runs, read per node by node_vals). Lightmap caches also sum each unit's diffuse response
     * ω max(0, d·n)/π, the exact cosine response, for the cone fit in step 4 (cone_fit.c). */
    if (hemi)
        for (uint32_t i = 0; i < un; ++i) {
            uk[i] = 0.0f;
            if (!(uw[i] > 0.0f)) continue;
            const float *ds = &ud[3 * i];
            float len = sqrtf(glow__dot(ds, ds));
            if (!(len > 0.0f)) continue;
            uk[i] = (float)((double)uw[i] * glow__cos_kernel(glow__dot(ds, cache->nrm) / len));
        }
    else if (cr->active)
        memset(uk, 0, un * sizeof *uk);
    if (hemi && !set->no_normalize) {
        /* The leaves' directions are not spread like the geometry they stand for (what the disc and
         * near-field passes lose is mostly grazing, and the solid-angle normalisation above spreads
         * that loss over every direction), so their total response is normalised too, to the rays'
         * Σ dw max(0, t)/π over the same first hits. */
        double ksum = 0.0;
        for (uint32_t i = 0; i < un_own; ++i) ksum += uk[i];
        if (kappa_geom > 0.0 && ksum > 0.0) {
            double r = kappa_geom / ksum;
            r = r < NORM_MIN ? NORM_MIN : (r > NORM_MAX ? NORM_MAX : r);
            for (uint32_t i = 0; i < un_own; ++i) uk[i] = (float)(uk[i] * r);
        }
    }
    if (cr->active) {
        cr->pw[0] = cr->pk[0] = 0.0;
        cr->pd[0] = cr->pd[1] = cr->pd[2] = 0.0;
        for (uint32_t j = 0; j < un; ++j) {
            cr->pw[j + 1] = cr->pw[j] + cr->w[j];
            cr->pk[j + 1] = cr->pk[j] + cr->k[j];
            for (int q = 0; q < 3; ++q) cr->pd[3 * (j + 1) + q] = cr->pd[3 * j + q] + cr->d[3 * j + q];
        }
        if (++cr->tag == 0) { /* wrapped: forget every stamp */
            memset(cr->stamp, 0, (size_t)h->node_count * sizeof *cr->stamp);
            cr->tag = 1;
        }
        /* the audit and full-SH links read every leaf (and the audit nodes below the cut): fill them
         * all from the runs, the same values the cut reads */
        if (set->audit_radiance || job->out->sh)
            for (uint32_t v = 0; v < h->node_count; ++v) node_vals(job, cr, v, omega, dirsum, kappa);
    } else {
        for (uint32_t v = n; v < h->node_count; ++v) {
            const glow__node *nd = &h->nodes[v];
            uint32_t a = nd->child[0], b = nd->child[1];
            omega[v] = omega[a] + omega[b];
            for (int k = 0; k < 3; ++k) dirsum[3 * v + k] = dirsum[3 * a + k] + dirsum[3 * b + k];
            if (hemi) kappa[v] = kappa[a] + kappa[b];
        }
    }

    /* 3. cut refinement. The heap holds the current cut; split the node of highest priority. */
    uint32_t nl = set->links_per_cache;
    uint32_t hn = 0, leaves_in_cut = 0;
    uint32_t root = h->node_count - 1;
    float *prio = job->prio[worker];
    const float *prio_k = hemi && !set->cut_error_omega ? kappa : NULL; /* cut_priority: the response the cache gathers */
    node_vals(job, cr, root, omega, dirsum, kappa);
    if (omega[root] > 0.0f) {
        root = cut_descend(job, cr, omega, dirsum, kappa, root);
        node_vals(job, cr, root, omega, dirsum, kappa);
        prio[root] = cut_priority(job, cr, omega, dirsum, prio_k, root);
        heap_push(heap, &hn, prio, root);
    }
    /* Leaves cannot be split: they move from the heap to `leafcut`. The heap never holds more
     * than nl + 1 nodes (each split adds at most one to the cut, which stops at nl). */
    uint32_t *leafcut = heap + nl + 2;
    while (hn > 0 && hn + leaves_in_cut < nl) {
        uint32_t v = heap_pop(heap, &hn, prio);
        const glow__node *nd = &h->nodes[v];
        if (nd->child[0] == GLOW_NODE_NONE) {
            leafcut[leaves_in_cut++] = v;
            continue;
        }
        for (int c = 0; c < 2; ++c) {
            node_vals(job, cr, nd->child[c], omega, dirsum, kappa);
            if (omega[nd->child[c]] > 0.0f) {
                uint32_t u = cut_descend(job, cr, omega, dirsum, kappa, nd->child[c]);
                node_vals(job, cr, u, omega, dirsum, kappa);
                prio[u] = cut_priority(job, cr, omega, dirsum, prio_k, u);
                heap_push(heap, &hn, prio, u);
            }
        }
    }
    /* Cut = heap contents + leafcut. Sort by node index for a stable, cache-friendly order. */
    uint32_t cut_n = 0;
    glow__link *L = job->out->links + (size_t)ci * nl;
    uint32_t *cut = leafcut + leaves_in_cut; /* room after leafcut */
    memcpy(cut, leafcut, leaves_in_cut * sizeof *cut);
    memcpy(cut + leaves_in_cut, heap, hn * sizeof *cut);
    cut_n = leaves_in_cut + hn;
    /* insertion sort would be O(n_L²); n_L <= 4096 so use qsort-free shell sort */
    for (uint32_t gap = cut_n / 2; gap > 0; gap /= 2)
        for (uint32_t i = gap; i < cut_n; ++i) {
            uint32_t t = cut[i], j = i;
            while (j >= gap && cut[j - gap] > t) { cut[j] = cut[j - gap]; j -= gap; }
            cut[j] = t;
        }

    /* Links with LSUB weights after those without (each group still by node index), so that the
     * kernel's blocks of links without weights skip the subset work */
    if (set->link_subsets && cut_n > 1) {
        uint32_t tmp[4096], nt = 0, k = 0;
        for (uint32_t j = 0; j < cut_n && nt < 4096; ++j) {
            if (link_lsub(job, cr, hemi, omega, dirsum, kappa, cut[j])) tmp[nt++] = cut[j];
            else cut[k++] = cut[j];
        }
        memcpy(cut + k, tmp, nt * sizeof *cut);
    }
    /* Audit (settings->audit_radiance, glow-bake --audit-radiance): with one radiance per surfel from any
     * lighting, the gather as the exact sum over the visible leaves against the gather through the cut:
     * a node's link applies the mean over all its leaves, where the exact sum weighs each visible leaf by
     * its own solid angle; the difference is the error of the cut alone (PIC's Fig. 9c bleeding, the
     * energy of partly visible nodes). Lightmap caches weigh by the diffuse response (the leaves' ω cos/π),
     * grid caches by the solid angle. Also what a link could read instead of its node's mean: the
     * visible part's mean (ω-weighted: what a link could give at best; uniform over the visible leaves:
     * what a link to its node's visible leaves could give), and its visible children's or grandchildren's
     * means weighted by their own shares (a link that blends a few nodes below its own). */
    if (set->audit_radiance) {
        const float *B = set->audit_radiance;
        const float *wt = hemi ? kappa : omega;
        double exact = 0.0, linked = 0.0, linked_vis = 0.0, fvis = 0.0, om = 0.0, linked_uvis = 0.0;
        double linked_d1 = 0.0, linked_d2 = 0.0, linked_sub = 0.0, linked_grad = 0.0;
        for (uint32_t i = 0; i < n; ++i) exact += (double)wt[i] * B[i];
        for (uint32_t j = 0; j < cut_n; ++j) {
            const uint32_t v = cut[j], a = job->leaf_first[v], b = job->leaf_end[v];
            double sum_vis = 0.0, w_vis = 0.0, n_vis = 0.0, sum_uvis = 0.0;
            const double mean = leaf_mean(job, B, v);
            for (uint32_t i = a; i < b; ++i) {
                if (omega[i] > 0.0f) {
                    const double ai = job->leaf_area[i + 1] - job->leaf_area[i];
                    sum_vis += (double)omega[i] * B[i];
                    sum_uvis += ai * B[i];
                    w_vis += omega[i];
                    n_vis += ai;
                }
            }
            linked += wt[v] * mean;
            linked_vis += w_vis > 0.0 ? wt[v] * sum_vis / w_vis : 0.0;
            linked_uvis += n_vis > 0.0 ? wt[v] * sum_uvis / n_vis : 0.0;
            linked_d1 += audit_descendants(job, wt, omega, B, v, 1);
            linked_d2 += audit_descendants(job, wt, omega, B, v, 2);
            linked_grad += audit_gradient(job, wt, B, v);
            /* what the runtime gathers: with LSUB weights, the weighted mean of the slots' means */
            const uint16_t q = set->link_subsets && !set->link_gradients ? link_subsets(h, wt, v) : 0u;
            if (set->link_subsets && set->link_gradients) { /* the gradient codes, as the runtime reads them */
                linked_sub += audit_gradient_q(job, wt, B, v, true, link_gradient(job, cr, hemi, omega, kappa, v));
            } else if (q) {
                uint32_t slot[4];
                link_slots(h, v, slot);
                double num = 0.0, den = 0.0;
                for (int k = 0; k < 4; ++k) {
                    const uint32_t qk = (q >> (4 * k)) & 15u;
                    num += qk * leaf_mean(job, B, slot[k]);
                    den += qk;
                }
                linked_sub += wt[v] * num / den;
            } else {
                linked_sub += wt[v] * mean;
            }
            fvis += omega[v] * n_vis / (job->leaf_area[b] - job->leaf_area[a]);
            om += omega[v];
        }
        float *row = job->out->audit + (size_t)ci * GLOW__AUDIT_FIELDS;
        row[0] = (float)exact;
        row[1] = (float)linked;
        row[2] = (float)linked_vis;
        row[3] = om > 0.0 ? (float)(fvis / om) : 1.0f;
        row[4] = (float)om;
        row[5] = (float)linked_uvis;
        row[6] = (float)linked_d1;
        row[7] = (float)linked_d2;
        row[8] = (float)linked_sub;
        row[9] = (float)linked_grad;
    }
    /* 4. links */
    const uint32_t bands = job->out->sh_bands;
    const uint32_t nc = bands * bands;
    float *shout = job->out->sh ? job->out->sh + (size_t)ci * nl * nc : NULL;
    if (shout) memset(shout, 0, (size_t)nl * nc * sizeof(float));
    for (uint32_t j = 0; j < nl; ++j) {
        glow__link *lk = &L[j];
        if (j >= cut_n) {
            memset(lk, 0, sizeof *lk);
            lk->dir[2] = 1.0f;
            continue;
        }
        uint32_t v = cut[j];
        const glow__node *nd = &h->nodes[v];
        lk->node = v;
        lk->factor = S->area / nd->area;
        float om = omega[v];
        float omc = om / (float)(2.0 * GLOW__PI);
        lk->one_minus_cos = omc > 2.0f ? 2.0f : omc;
        float *ds = &dirsum[3 * v];
        float len = sqrtf(glow__dot(ds, ds));
        if (len > 1e-12f * om && len > 0.0f) {
            for (int k = 0; k < 3; ++k) lk->dir[k] = ds[k] / len;
        } else {
            float d[3];
            glow__sub(nd->pos, cache->pos, d);
            float dl = sqrtf(glow__dot(d, d));
            if (dl > 0.0f) for (int k = 0; k < 3; ++k) lk->dir[k] = d[k] / dl;
            else { lk->dir[0] = lk->dir[1] = 0.0f; lk->dir[2] = 1.0f; }
        }
        /* Lightmap caches: the cone's size is fitted so its diffuse response at the cache normal
         * equals the cluster's (cone_fit.c); grid caches keep the solid angle. */
        if (hemi && !set->no_cone_fit) lk->one_minus_cos = glow__cone_fit_omc(fit_bands, lk->one_minus_cos, glow__dot(lk->dir, cache->nrm), kappa[v]);
        if (set->link_subsets) lk->subsets = link_lsub(job, cr, hemi, omega, dirsum, kappa, v);
        if (shout) {
            /* PIC Eq. 2 over this node's visible leaves: Σ ω_i y(dir_i), in units of the runtime
             * projection (multiplied by factor; factor_scale applied at runtime). */
            float y[64];
            float *c = shout + (size_t)j * nc;
            for (uint32_t i = job->leaf_first[v]; i < job->leaf_end[v]; ++i) {
                if (!(omega[i] > 0.0f)) continue;
                float dir[3];
                float *dd = &dirsum[3 * i];
                for (int k = 0; k < 3; ++k) dir[k] = dd[k] / omega[i];
                glow__sh_eval(bands, dir, y);
                for (uint32_t q = 0; q < nc; ++q) c[q] += omega[i] * y[q];
            }
            for (uint32_t q = 0; q < nc; ++q) c[q] *= lk->factor;
        }
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Ranks (glow_pc_distribution): a bake split over processes. Items (caches, or lightmap detail
 * texels) go to the ranks in blocks of RANK_BLOCK, round robin (block b to rank b mod R), so that
 * every rank gets its share of grid caches, of lightmap caches and of each region of the atlas (the
 * cost per cache varies by kind and place: contiguous ranges left one rank 15 % longer on Sponza).
 * After computing its items a rank packs them in order, share() hands every rank every packed part,
 * and each unpacks them to their places; since each item's result depends on that item alone (as for
 * any thread count), the table is the one-process table byte for byte. */
#define RANK_BLOCK 16u
/* how many of n items rank r owns */
static uint32_t rank_count(const glow_pc_distribution *d, uint32_t r, uint32_t n) {
    if (!d) return n;
    const uint32_t R = d->ranks, blocks = (n + RANK_BLOCK - 1u) / RANK_BLOCK;
    if (r >= blocks) return 0;
    const uint32_t mine = (blocks - 1u - r) / R + 1u; /* blocks r, r + R, ... < blocks */
    const uint32_t last = r + (mine - 1u) * R;        /* the last may be partial */
    return (mine - 1u) * RANK_BLOCK + (last == blocks - 1u ? n - last * RANK_BLOCK : RANK_BLOCK);
}
/* the global index of this rank's k-th item */
static inline uint32_t rank_item(const glow_pc_distribution *d, uint32_t k) {
    if (!d) return k;
    return ((k / RANK_BLOCK) * d->ranks + d->rank) * RANK_BLOCK + k % RANK_BLOCK;
}

/* Every rank's items of base[n items of elem bytes]; a no-op for one process. */
static glow_result rank_share(const glow_pc_distribution *d, void *base, uint32_t n, size_t elem, glow__log *log,
                              const char *what) {
    if (!d || d->ranks < 2 || n == 0) return GLOW_OK;
    const uint32_t R = d->ranks;
    size_t *off = malloc(((size_t)R + 1) * sizeof *off);
    unsigned char *buf = malloc((size_t)n * elem + 1);
    if (!off || !buf) {
        free(off);
        free(buf);
        glow__errorf(log, "links: out of memory sharing %s between ranks", what);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    off[0] = 0;
    for (uint32_t r = 0; r < R; ++r) off[r + 1] = off[r] + (size_t)rank_count(d, r, n) * elem;
    unsigned char *b = base;
    /* pack this rank's blocks; after the exchange, unpack every rank's */
    for (uint32_t r = 0; r < R; ++r) {
        const bool mine = r == d->rank;
        size_t o = off[r];
        for (uint32_t blk = r; (size_t)blk * RANK_BLOCK < n; blk += R) {
            const uint32_t first = blk * RANK_BLOCK, cnt = n - first < RANK_BLOCK ? n - first : RANK_BLOCK;
            if (mine) memcpy(buf + o, b + (size_t)first * elem, (size_t)cnt * elem);
            o += (size_t)cnt * elem;
        }
    }
    const glow_result res = d->share(d->user, buf, off);
    if (res == GLOW_OK)
        for (uint32_t r = 0; r < R; ++r) {
            size_t o = off[r];
            for (uint32_t blk = r; (size_t)blk * RANK_BLOCK < n; blk += R) {
                const uint32_t first = blk * RANK_BLOCK, cnt = n - first < RANK_BLOCK ? n - first : RANK_BLOCK;
                memcpy(b + (size_t)first * elem, buf + o, (size_t)cnt * elem);
                o += (size_t)cnt * elem;
            }
        }
    free(off);
    free(buf);
    if (res != GLOW_OK)
        glow__errorf(log, "links: rank %u of %u: exchanging %s with the other ranks failed: %s", d->rank, d->ranks, what,
                     glow_result_string(res));
    return res;
}

static void link_range(void *ctx, uint32_t begin, uint32_t end, uint32_t worker) {
    link_job *job = ctx;
    for (uint32_t c = begin; c < end; ++c) {
        link_cache(job, rank_item(job->dist, c), worker);
        unsigned done = atomic_fetch_add(&job->done, 1u) + 1u;
        if (worker == 0 && job->progress) /* < 1: the pipeline reports the stage end itself */
            job->progress(job->progress_user, 0.999 * (double)done / job->cache_total);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Lightmap detail (docs/linker.md "Lightmap detail").
 *
 * A lightmap cache stands for its whole texel (1.4 m on Sponza's default), so light that changes
 * within a texel is lost: most of all light from surfaces a few decimetres away across a concave
 * corner (the foot of a sunlit pillar, a capital's sunlit face), which the referee puts at most of
 * Sponza's remaining block error (docs/results.md "Near light"). The detail texels (caches.c, a
 * finer grid over the same atlas) each add what their own point receives from the surfels near it
 * and remove what the interpolated caches already gather from those surfels:
 *     correction(d) = sum_s [F_d(s) - sum_i b_i F_ci(s)] R(s)        s: surfels within rho of d
 * F_x(s) = (1/pi) * the cosine-weighted solid angle of s seen from x about d's normal (the weight
 * glow_shade_sh gives a source of radiance R in the cosine-lobe mean radiance), measured by rays
 * with near_field's credit (credit_hit); b_i the bilinear weights with which a lookup at d's centre
 * reads caches c_i (glow_sample_lightmap's, empty texels dropped and the rest renormalised). Where
 * the caches see the near surfels as d does (a flat open floor) the two terms cancel and no link is
 * kept. A cache's rays are cast once (phase A) and shared by the detail texels around it (phase B).
 * The result is linear in the surfels' radiance, so the runtime evaluates it every update (a few
 * signed weights per detail texel) and light that moves or changes stays right. */
/* A detail hit is credited only to a surfel whose centre lies within this many surfel radii of the
 * hit point. A point in a narrow gap (under a moulding, between a pier's base and the floor) sends
 * most of its rays into the gap's walls; without the bound they went to a surfel whose centre stands
 * outside the gap, in the sun, and single links carried up to 0.9 of the texel's response (Sponza,
 * seed 0, 3 detail texels a side: block error 0.171 with no bound, 0.127 at 1.5, 0.129 at 2, 0.136
 * at 1). */
#define DETAIL_CREDIT_RADII 1.5f
/* Rays over a cache's and a detail texel's hemisphere. Sponza (seed 0, 3 detail texels a side), block
 * error against the referee: 0.1266 with 512 / 256, 0.1252 with 256 / 128 (seed 1: 0.1138 / 0.1143),
 * and 0.1328 against 0.1333 with 2048 / 1024 before the credit bound: the difference of two estimates
 * is not what limits it. 256 / 128 costs 2.6 s of a 2-thread bake there (5.1 s at 512 / 256). */
#define DETAIL_CACHE_RAYS 256u
#define DETAIL_RAYS 128u
#define DETAIL_MAX_LINKS 256u /* --detail-links' range (pipeline.c) */

typedef struct detail_hit {
    uint32_t surfel;
    float d[3]; /* sum over the rays credited to the surfel of (2 / rays) x direction */
} detail_hit;

typedef struct detail_job {
    const link_job *lj;
    const glow_pc_distribution *dist; /* this rank's detail texels: rank_item (links.c "Ranks") */
    float rho, reach;              /* detail radius (m); a cache's credit radius: rho + its texels' reach */
    float credit_d2;               /* a hit is credited only to a surfel within this squared distance */
    float dirs[DETAIL_RAYS][3];    /* uniform hemisphere, z up */
    float cdirs[DETAIL_CACHE_RAYS][3];
    detail_hit **hits;             /* [lightmap caches] phase A */
    uint32_t *hit_count;
    float **acc_f, **acc_c;        /* [workers][surfels] */
    uint32_t **touched;            /* [workers][surfels] */
    uint8_t **mark;                /* [workers][surfels] */
    uint8_t *relief;               /* [detail texels] detail_sees_relief: the texel has its rays cast */
    uint8_t *need;                 /* [lightmap caches] read by a detail texel with relief: phase A casts */
    uint32_t *out_s;               /* [detail_count][K] */
    float *out_w;
    uint32_t *out_n;               /* [detail_count] */
    double *merged, *total;        /* [detail_count]: |weight| given to a group's member, and all of it */
    uint32_t K;
    bool oom;
} detail_job;

static void detail_cache_range(void *p, uint32_t begin, uint32_t end, uint32_t worker) {
    detail_job *dj = p;
    const link_job *job = dj->lj;
    const glow__caches *ca = job->caches;
    float *acc = dj->acc_f[worker];  /* [surfels][3]: here the direction sums */
    uint32_t *touched = dj->touched[worker];
    uint8_t *mark = dj->mark[worker];
    const float wr = 2.0f / (float)DETAIL_CACHE_RAYS;
    for (uint32_t li = begin; li < end; ++li) {
        dj->hits[li] = NULL;
        dj->hit_count[li] = 0;
        if (!dj->need[li]) continue; /* no detail texel that corrects anything reads it */
        const glow__cache *c = &ca->caches[ca->grid_cache_count + li];
        float t[3], b[3];
        tangent_frame(c->nrm, t, b);
        uint32_t n = 0;
        for (uint32_t r = 0; r < DETAIL_CACHE_RAYS; ++r) {
            const float *l = dj->cdirs[r];
            float dir[3];
            for (int k = 0; k < 3; ++k) dir[k] = l[0] * t[k] + l[1] * b[k] + l[2] * c->nrm[k];
            glow__hit hit = glow__rt_intersect(job->rt, c->pos, dir, job->ray_eps, dj->reach);
            if (hit.t == INFINITY || hit.back_face) continue;
            const uint32_t s = credit_hit(job, c->pos, c->nrm, dj->reach, dir, &hit, NULL, dj->credit_d2);
            if (s == CREDIT_NONE) continue;
            if (!mark[s]) {
                mark[s] = 1;
                touched[n++] = s;
                acc[3 * (size_t)s] = acc[3 * (size_t)s + 1] = acc[3 * (size_t)s + 2] = 0.0f;
            }
            for (int k = 0; k < 3; ++k) acc[3 * (size_t)s + k] += wr * dir[k];
        }
        detail_hit *h = malloc(((size_t)n + 1) * sizeof *h);
        if (!h) dj->oom = true;
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t s = touched[i];
            mark[s] = 0;
            if (!h) continue;
            h[i].surfel = s;
            memcpy(h[i].d, &acc[3 * (size_t)s], sizeof h[i].d);
        }
        dj->hits[li] = h;
        dj->hit_count[li] = h ? n : 0;
    }
}

static int cmp_u32(const void *a, const void *b) {
    const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : (x > y);
}

/* Does a surfel within the detail radius stand off the detail texel's plane (a wall beside a floor, a
 * step, a moulding)? If every surfel near it lies in its own plane, its rays meet none of them and the
 * caches' rays see them edge-on: the correction is zero, and the texel's rays are not cast (most of an
 * open floor; 88 % of the Cornell box's detail texels). The DETAIL_RELIEF_KNN nearest surfels are
 * looked at; a disc of the detail radius holds about 29 at Sponza's default. */
#define DETAIL_RELIEF_KNN 64u
static bool detail_sees_relief(const detail_job *dj, const float pd[3], const float nd[3]) {
    const link_job *job = dj->lj;
    uint32_t idx[DETAIL_RELIEF_KNN];
    float dist2[DETAIL_RELIEF_KNN];
    const float rho2 = dj->rho * dj->rho, tol = job->near_radius / NEAR_RADII; /* a surfel's radius */
    const uint32_t found = glow__pointgrid_knn_within(job->surfel_grid, pd, DETAIL_RELIEF_KNN, UINT32_MAX, rho2, idx, dist2);
    for (uint32_t q = 0; q < found; ++q) {
        if (dist2[q] >= rho2) return false; /* nearest first: the rest are beyond the radius */
        const glow__surfel *s = &job->surfels->s[idx[q]];
        float off[3];
        glow__sub(s->pos, pd, off);
        if (fabsf(glow__dot(off, nd)) > 0.25f * tol || glow__dot(s->nrm, nd) < 0.97f) return true;
    }
    return found == DETAIL_RELIEF_KNN; /* more surfels within the radius than looked at: cast the rays */
}

/* The caches a lightmap lookup at detail texel d's centre reads (lm_map entries, GLOW_MAP_EMPTY for
 * none) and their weights, renormalised over the non-empty ones as glow_sample_lightmap does; false
 * when all four are empty. */
static bool detail_lookup(const glow__caches *ca, uint32_t d, uint32_t m4[4], float b4[4]) {
    const uint32_t D = ca->detail_factor, W = ca->lm_width, H = ca->lm_height;
    const size_t dpage = (size_t)ca->detail_width * ca->detail_height; /* a page's detail texels */
    const uint32_t dt = (uint32_t)(ca->detail_texel[d] % dpage);
    const uint32_t *lm_map = ca->lm_map + (size_t)(ca->detail_texel[d] / dpage) * W * H; /* its page's */
    const uint32_t tx = dt % ca->detail_width, ty = dt / ca->detail_width;
    const float fx = ((float)tx + 0.5f) / (float)D - 0.5f, fy = ((float)ty + 0.5f) / (float)D - 0.5f;
    float f = fx < 0.0f ? 0.0f : (fx > (float)(W - 1) ? (float)(W - 1) : fx), fl = floorf(f);
    const uint32_t x0 = (uint32_t)fl, x1 = x0 + 1 < W ? x0 + 1 : x0;
    const float ax = f - fl;
    f = fy < 0.0f ? 0.0f : (fy > (float)(H - 1) ? (float)(H - 1) : fy);
    fl = floorf(f);
    const uint32_t y0 = (uint32_t)fl, y1 = y0 + 1 < H ? y0 + 1 : y0;
    const float ay = f - fl;
    m4[0] = lm_map[(size_t)y0 * W + x0], m4[1] = lm_map[(size_t)y0 * W + x1];
    m4[2] = lm_map[(size_t)y1 * W + x0], m4[3] = lm_map[(size_t)y1 * W + x1];
    b4[0] = (1 - ax) * (1 - ay), b4[1] = ax * (1 - ay), b4[2] = (1 - ax) * ay, b4[3] = ax * ay;
    float bs = 0.0f;
    for (int i = 0; i < 4; ++i) {
        if (m4[i] == GLOW_MAP_EMPTY || !(b4[i] > 0.0f) || (m4[i] & GLOW_MAP_INDEX_MASK) < ca->grid_cache_count) {
            m4[i] = GLOW_MAP_EMPTY; /* (the lightmap's map names lightmap caches only) */
            b4[i] = 0.0f;
        }
        bs += b4[i];
    }
    for (int i = 0; i < 4; ++i) b4[i] = bs > 0.0f ? b4[i] / bs : 0.0f;
    return bs > 0.0f;
}

static void detail_relief_range(void *p, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    detail_job *dj = p;
    const glow__caches *ca = dj->lj->caches;
    for (uint32_t d = begin; d < end; ++d) dj->relief[d] = detail_sees_relief(dj, ca->detail_pos[d], ca->detail_nrm[d]);
}

static void detail_texel_range(void *p, uint32_t begin, uint32_t end, uint32_t worker) {
    detail_job *dj = p;
    const link_job *job = dj->lj;
    const glow__caches *ca = job->caches;
    const glow__surfels *S = job->surfels;
    float *accf = dj->acc_f[worker], *accc = dj->acc_c[worker];
    uint32_t *touched = dj->touched[worker];
    uint8_t *mark = dj->mark[worker];
    const float rho2 = dj->rho * dj->rho, wr = 2.0f / (float)DETAIL_RAYS;
    for (uint32_t item = begin; item < end; ++item) {
        const uint32_t d = rank_item(dj->dist, item);
        const float *pd = ca->detail_pos[d], *nd = ca->detail_nrm[d];
        uint32_t n = 0;
        dj->out_n[d] = 0;
        dj->total[d] = dj->merged[d] = 0.0;
        if (!dj->relief[d]) continue; /* only its own plane near it: nothing to correct */
#define DETAIL_TOUCH(s)                                      \
    do {                                                     \
        if (!mark[s]) {                                      \
            mark[s] = 1;                                     \
            touched[n++] = (s);                              \
            accf[s] = accc[s] = 0.0f;                        \
        }                                                    \
    } while (0)
        /* what the interpolated caches gather from the surfels near d */
        uint32_t m4[4];
        float b4[4];
        const bool any = detail_lookup(ca, d, m4, b4);
        for (int i = 0; any && i < 4; ++i) {
            if (m4[i] == GLOW_MAP_EMPTY) continue;
            const uint32_t li = (m4[i] & GLOW_MAP_INDEX_MASK) - ca->grid_cache_count;
            const float bw = b4[i];
            for (uint32_t q = 0; q < dj->hit_count[li]; ++q) {
                const detail_hit *h = &dj->hits[li][q];
                float off[3];
                glow__sub(S->s[h->surfel].pos, pd, off);
                if (glow__dot(off, off) >= rho2) continue;
                const float c = glow__dot(h->d, nd);
                if (!(c > 0.0f)) continue;
                DETAIL_TOUCH(h->surfel);
                accc[h->surfel] += bw * c;
            }
        }
        /* what d's own point receives from them */
        float t[3], b[3];
        tangent_frame(nd, t, b);
        for (uint32_t r = 0; r < DETAIL_RAYS; ++r) {
            const float *l = dj->dirs[r];
            float dir[3];
            for (int k = 0; k < 3; ++k) dir[k] = l[0] * t[k] + l[1] * b[k] + l[2] * nd[k];
            glow__hit hit = glow__rt_intersect(job->rt, pd, dir, job->ray_eps, dj->rho + job->near_radius);
            if (hit.t == INFINITY || hit.back_face) continue;
            const uint32_t s = credit_hit(job, pd, nd, dj->rho, dir, &hit, NULL, dj->credit_d2);
            if (s == CREDIT_NONE) continue;
            DETAIL_TOUCH(s);
            accf[s] += wr * l[2];
        }
#undef DETAIL_TOUCH
        /* the difference, by surfel */
        uint32_t m = 0;
        double all = 0.0, merged = 0.0;
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t s = touched[i];
            mark[s] = 0;
            const float v = accf[s] - accc[s];
            accf[s] = v;
            all += fabs((double)v);
            if (fabsf(v) > 1e-6f) touched[m++] = s;
        }
        qsort(touched, m, sizeof *touched, cmp_u32);
        if (m > dj->K) {
            /* More surfels than links (a dense bake puts many surfels where the rays of a moderate one
             * meet a few): group them by the hierarchy's subtrees of at most T leaves, for the least
             * power of two T that leaves at most K groups, and give each group's summed weight to its
             * member of the largest |weight| (ties: the lower index). A small subtree is a compact
             * cluster of like-facing surfels, so its members' radiance is alike. Subtrees own
             * contiguous leaf ranges, so in index order a group's members are consecutive. Before
             * (2026-11-30: the K largest kept, the rest dropped), Sponza at 524,288 surfels left 37 %
             * of the weight out, and its block error against the referee was 0.096 instead of 0.080. */
            const glow__node *nodes = job->h->nodes;
            uint32_t grp[DETAIL_RAYS + 4u * DETAIL_CACHE_RAYS];
            for (uint32_t i = 0; i < m; ++i) grp[i] = touched[i];
            uint32_t groups = m;
            for (uint32_t T = 2; groups > dj->K; T *= 2) {
                groups = 0;
                for (uint32_t i = 0; i < m; ++i) {
                    uint32_t g = grp[i], up;
                    while ((up = nodes[g].parent) != GLOW_NODE_NONE && job->leaf_end[up] - job->leaf_first[up] <= T) g = up;
                    grp[i] = g;
                    groups += i == 0 || g != grp[i - 1];
                }
            }
            uint32_t k = 0;
            for (uint32_t i = 0; i < m;) {
                uint32_t rep = touched[i], j = i;
                double sum = 0.0, mag = 0.0;
                for (; j < m && grp[j] == grp[i]; ++j) {
                    const float v = accf[touched[j]];
                    sum += (double)v;
                    mag += fabs((double)v);
                    if (fabsf(v) > fabsf(accf[rep])) rep = touched[j];
                }
                merged += mag - fabs((double)accf[rep]);
                accf[rep] = (float)sum;
                touched[k++] = rep;
                i = j;
            }
            m = k;
        }
        for (uint32_t i = 0; i < m; ++i) {
            dj->out_s[(size_t)d * dj->K + i] = touched[i];
            dj->out_w[(size_t)d * dj->K + i] = accf[touched[i]];
        }
        dj->out_n[d] = m;
        dj->total[d] = all;
        dj->merged[d] = merged;
    }
}

static glow_result detail_build(const link_job *job, glow__pool *pool, glow__log *log, glow__links *out) {
    const glow__caches *ca = job->caches;
    const glow__link_settings *set = job->settings;
    const uint32_t S = set->own_leaves ? set->own_leaves : job->surfels->count, Dn = ca->detail_count,
                   L = ca->lm_cache_count;
    detail_job dj = {.lj = job, .K = !set->detail_links ? 16u : set->detail_links < DETAIL_MAX_LINKS ? set->detail_links : DETAIL_MAX_LINKS};
    dj.rho = set->detail_radius / ca->texel_density;
    /* a detail texel reads caches up to about 1.5 texels away on its chart */
    dj.reach = dj.rho + 2.0f / ca->texel_density + job->near_radius;
    {
        const float rs = job->near_radius / NEAR_RADII; /* a surfel's radius */
        dj.credit_d2 = DETAIL_CREDIT_RADII * rs * DETAIL_CREDIT_RADII * rs;
    }
    {
        const double golden = GLOW__PI * (3.0 - sqrt(5.0));
        for (uint32_t i = 0; i < DETAIL_RAYS; ++i) {
            double z = 1.0 - (i + 0.5) / DETAIL_RAYS, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = golden * i;
            dj.dirs[i][0] = (float)(r * cos(phi));
            dj.dirs[i][1] = (float)(r * sin(phi));
            dj.dirs[i][2] = (float)z;
        }
        for (uint32_t i = 0; i < DETAIL_CACHE_RAYS; ++i) {
            double z = 1.0 - (i + 0.5) / DETAIL_CACHE_RAYS, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = golden * i;
            dj.cdirs[i][0] = (float)(r * cos(phi));
            dj.cdirs[i][1] = (float)(r * sin(phi));
            dj.cdirs[i][2] = (float)z;
        }
    }
    const uint32_t W = job->workers;
    glow_result res = GLOW_OK;
    dj.hits = calloc((size_t)L + 1, sizeof *dj.hits);
    dj.hit_count = calloc((size_t)L + 1, sizeof *dj.hit_count);
    dj.acc_f = calloc(W, sizeof *dj.acc_f);
    dj.acc_c = calloc(W, sizeof *dj.acc_c);
    dj.touched = calloc(W, sizeof *dj.touched);
    dj.mark = calloc(W, sizeof *dj.mark);
    dj.out_s = malloc(((size_t)Dn * dj.K + 1) * sizeof *dj.out_s);
    dj.out_w = malloc(((size_t)Dn * dj.K + 1) * sizeof *dj.out_w);
    dj.out_n = calloc((size_t)Dn + 1, sizeof *dj.out_n);
    dj.merged = calloc((size_t)Dn + 1, sizeof *dj.merged);
    dj.total = calloc((size_t)Dn + 1, sizeof *dj.total);
    bool ok = dj.hits && dj.hit_count && dj.acc_f && dj.acc_c && dj.touched && dj.mark && dj.out_s && dj.out_w &&
              dj.out_n && dj.merged && dj.total;
    for (uint32_t w = 0; ok && w < W; ++w) {
        dj.acc_f[w] = malloc(((size_t)S + 1) * 3 * sizeof(float));
        dj.acc_c[w] = malloc(((size_t)S + 1) * sizeof(float));
        dj.touched[w] = malloc(((size_t)S + 1) * sizeof(uint32_t));
        dj.mark[w] = calloc((size_t)S + 1, 1);
        ok = dj.acc_f[w] && dj.acc_c[w] && dj.touched[w] && dj.mark[w];
    }
    dj.relief = calloc((size_t)Dn + 1, 1);
    dj.need = calloc((size_t)L + 1, 1);
    ok = ok && dj.relief && dj.need;
    if (ok) { /* which detail texels correct anything, and which caches they read */
        glow__parallel_for(pool, Dn, 64, detail_relief_range, &dj);
        for (uint32_t d = 0; d < Dn; ++d) {
            uint32_t m4[4];
            float b4[4];
            if (!dj.relief[d] || !detail_lookup(ca, d, m4, b4)) continue;
            for (int i = 0; i < 4; ++i)
                if (m4[i] != GLOW_MAP_EMPTY) dj.need[(m4[i] & GLOW_MAP_INDEX_MASK) - ca->grid_cache_count] = 1;
        }
        glow__parallel_for(pool, L, 16, detail_cache_range, &dj);
        ok = !dj.oom;
    }
    if (ok) { /* this rank's texels, then every rank's (links.c "Ranks") */
        const glow_pc_distribution *dist = set->dist;
        dj.dist = dist;
        glow__parallel_for(pool, rank_count(dist, dist ? dist->rank : 0u, Dn), 16, detail_texel_range, &dj);
        if ((res = rank_share(dist, dj.out_s, Dn, dj.K * sizeof *dj.out_s, log, "the detail links")) != GLOW_OK ||
            (res = rank_share(dist, dj.out_w, Dn, dj.K * sizeof *dj.out_w, log, "the detail weights")) != GLOW_OK ||
            (res = rank_share(dist, dj.out_n, Dn, sizeof *dj.out_n, log, "the detail link counts")) != GLOW_OK ||
            (res = rank_share(dist, dj.merged, Dn, sizeof *dj.merged, log, "the detail weight sums")) != GLOW_OK ||
            (res = rank_share(dist, dj.total, Dn, sizeof *dj.total, log, "the detail weight sums")) != GLOW_OK)
            ok = false;
    }
    if (ok) {
        size_t total = 0;
        for (uint32_t d = 0; d < Dn; ++d) total += dj.out_n[d];
        out->detail_first = malloc(((size_t)Dn + 1) * sizeof *out->detail_first);
        out->detail_surfel = malloc((total + 1) * sizeof *out->detail_surfel);
        out->detail_weight = malloc((total + 1) * sizeof *out->detail_weight);
        ok = out->detail_first && out->detail_surfel && out->detail_weight && total < UINT32_MAX;
        if (ok) {
            uint32_t k = 0, with = 0;
            for (uint32_t d = 0; d < Dn; ++d) {
                out->detail_first[d] = k;
                memcpy(out->detail_surfel + k, dj.out_s + (size_t)d * dj.K, dj.out_n[d] * sizeof(uint32_t));
                memcpy(out->detail_weight + k, dj.out_w + (size_t)d * dj.K, dj.out_n[d] * sizeof(float));
                k += dj.out_n[d];
                with += dj.out_n[d] > 0;
                out->detail_total += dj.total[d];
                out->detail_merged += dj.merged[d];
            }
            out->detail_first[Dn] = k;
            out->detail_count = Dn;
            glow__infof(log, "%s: links: lightmap detail: %u of %u detail texels correct their caches' near light "
                        "(surfels within %.3g units), %.1f links each (at most %u; %.1f %% of the weight given to a "
                        "neighbour in its subtree)",
                        job->scene->source, with, Dn, (double)dj.rho, with ? (double)k / with : 0.0, dj.K,
                        out->detail_total > 0.0 ? 100.0 * out->detail_merged / out->detail_total : 0.0);
        }
    }
    if (!ok && res == GLOW_OK) {
        glow__errorf(log, "links: out of memory for the lightmap detail");
        res = GLOW_ERROR_OUT_OF_MEMORY;
    }
    for (uint32_t i = 0; dj.hits && i < L; ++i) free(dj.hits[i]);
    for (uint32_t w = 0; w < W; ++w) {
        if (dj.acc_f) free(dj.acc_f[w]);
        if (dj.acc_c) free(dj.acc_c[w]);
        if (dj.touched) free(dj.touched[w]);
        if (dj.mark) free(dj.mark[w]);
    }
    free(dj.hits); free(dj.hit_count); free(dj.acc_f); free(dj.acc_c); free(dj.touched); free(dj.mark);
    free(dj.out_s); free(dj.out_w); free(dj.out_n); free(dj.merged); free(dj.total); free(dj.relief); free(dj.need);
    return res;
}

glow_result glow__links_build(const glow__scene *scene, const glow__rt *rt, const glow__surfels *surfels,
                              const glow__hierarchy *h, const glow__caches *caches,
                              const glow__link_settings *settings, glow__pool *pool, glow__log *log,
                              glow__progress_fn progress, void *progress_user, glow__links *out) {
    memset(out, 0, sizeof *out);
    uint32_t nl = settings->links_per_cache;
    if (nl == 0 || settings->sh_bands < 1 || settings->sh_bands > 8) {
        glow__errorf(log, "links: invalid settings (links %u, bands %u)", nl, settings->sh_bands);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    out->cache_count = caches->count;
    out->per_cache = nl;
    out->sh_bands = settings->sh_bands;
    out->gradients = settings->link_subsets && settings->link_gradients;
    out->links = calloc((size_t)caches->count * nl + 1, sizeof *out->links);
    if (settings->audit_radiance) out->audit = calloc((size_t)caches->count * GLOW__AUDIT_FIELDS + 1, sizeof(float));
    if (settings->full_sh)
        out->sh = calloc((size_t)caches->count * nl * settings->sh_bands * settings->sh_bands + 1, sizeof(float));
    link_job job = {.scene = scene, .rt = rt, .surfels = surfels, .h = h, .caches = caches, .settings = settings,
                    .out = out, .progress = progress, .progress_user = progress_user};
    atomic_init(&job.done, 0u);
    atomic_init(&job.vis_rays, 0ull);
    atomic_init(&job.vis_cluster_rays, 0ull);
    atomic_init(&job.vis_units, 0ull);
    job.workers = glow__pool_threads(pool);
    job.omega = calloc(job.workers, sizeof *job.omega);
    job.dirsum = calloc(job.workers, sizeof *job.dirsum);
    job.kappa = calloc(job.workers, sizeof *job.kappa);
    job.prio = calloc(job.workers, sizeof *job.prio);
    job.heap = calloc(job.workers, sizeof *job.heap);
    job.runs = calloc(job.workers, sizeof *job.runs);
    job.radius = malloc((size_t)h->node_count * sizeof(float));
    job.cone = malloc((size_t)h->node_count * sizeof(float));
    job.nsum = malloc((size_t)h->node_count * 3 * sizeof(float));
    job.emissive = malloc((size_t)h->node_count + 1);
    job.trav = settings->cluster_tau > 0.0f ? malloc((size_t)h->node_count * sizeof *job.trav) : NULL;
    job.visible_total = calloc((size_t)caches->count + 1, sizeof(double));
    job.norm_scale = calloc((size_t)caches->count + 1, sizeof(float));
    job.norm_clamped = calloc((size_t)caches->count + 1, 1);
    job.leaf_first = malloc((size_t)h->node_count * sizeof(uint32_t));
    job.leaf_end = malloc((size_t)h->node_count * sizeof(uint32_t));
    job.leaf_area = malloc(((size_t)h->leaf_count + 1) * sizeof(double));
    if (settings->link_gradients) {
        job.grad_frame = malloc(4 * (size_t)h->node_count * sizeof(double));
        if (settings->cluster_tau > 0.0f) job.leaf_apos = malloc(3 * ((size_t)h->leaf_count + 1) * sizeof(double));
    }
    bool ok = (!settings->link_gradients || (job.grad_frame && (settings->cluster_tau <= 0.0f || job.leaf_apos))) && out->links && (!settings->full_sh || out->sh) && (!settings->audit_radiance || out->audit) && job.omega && job.dirsum && job.kappa && job.prio && job.heap &&
              job.runs && job.radius && job.cone && job.nsum && job.emissive &&
              (settings->cluster_tau <= 0.0f || job.trav) &&
              job.visible_total && job.norm_scale && job.norm_clamped && job.leaf_first && job.leaf_end && job.leaf_area;
    for (uint32_t w = 0; ok && w < job.workers; ++w) {
        job.omega[w] = malloc((size_t)h->node_count * sizeof(float));
        job.dirsum[w] = malloc((size_t)h->node_count * 3 * sizeof(float));
        job.kappa[w] = malloc((size_t)h->node_count * sizeof(float));
        job.prio[w] = malloc((size_t)h->node_count * sizeof(float));
        /* heap (nl + 2) + leaf cut (nl) + sorted cut (<= nl + 2) */
        job.heap[w] = malloc(((size_t)3u * nl + 8u) * sizeof(uint32_t));
        ok = job.omega[w] && job.dirsum[w] && job.kappa[w] && job.prio[w] && job.heap[w];
        if (ok && settings->cluster_tau > 0.0f) {
            cl_runs *r = &job.runs[w];
            const size_t nr = (size_t)h->leaf_count + 1;
            r->a = malloc(nr * sizeof *r->a);
            r->b = malloc(nr * sizeof *r->b);
            r->w = malloc(nr * sizeof *r->w);
            r->k = malloc(nr * sizeof *r->k);
            r->d = malloc(3 * nr * sizeof *r->d);
            r->pw = malloc((nr + 1) * sizeof *r->pw);
            r->pk = malloc((nr + 1) * sizeof *r->pk);
            r->pd = malloc(3 * (nr + 1) * sizeof *r->pd);
            r->stamp = calloc((size_t)h->node_count, sizeof *r->stamp);
            ok = r->a && r->b && r->w && r->k && r->d && r->pw && r->pk && r->pd && r->stamp;
        }
    }
    glow_result res = GLOW_OK;
    if (!ok) {
        glow__errorf(log, "links: out of memory for %u caches x %u links", caches->count, nl);
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    /* leaf ranges: leaves are in DFS order, so every subtree owns a contiguous range */
    job.leaf_area[0] = 0.0;
    for (uint32_t i = 0; i < h->leaf_count; ++i) job.leaf_area[i + 1] = job.leaf_area[i] + surfels->s[i].area;
    for (uint32_t v = 0; v < h->node_count; ++v) {
        if (v < h->leaf_count) {
            job.leaf_first[v] = v;
            job.leaf_end[v] = v + 1;
        } else {
            uint32_t a = h->nodes[v].child[0], b = h->nodes[v].child[1];
            job.leaf_first[v] = job.leaf_first[a] < job.leaf_first[b] ? job.leaf_first[a] : job.leaf_first[b];
            job.leaf_end[v] = job.leaf_end[a] > job.leaf_end[b] ? job.leaf_end[a] : job.leaf_end[b];
        }
    }
    if (job.leaf_apos) {
        for (int k = 0; k < 3; ++k) job.leaf_apos[k] = 0.0;
        for (uint32_t i = 0; i < h->leaf_count; ++i)
            for (int k = 0; k < 3; ++k)
                job.leaf_apos[3 * ((size_t)i + 1) + k] = job.leaf_apos[3 * (size_t)i + k] + (double)surfels->s[i].area * surfels->s[i].pos[k];
    }
    if (job.grad_frame) gradient_frames(&job);
    /* Per node, children first (they precede their parents): a bounding sphere about its centre, a
     * cone about its mean normal that holds its leaves' normals, and its leaves' normal sum
     * (clustered visibility) */
    for (uint32_t v = 0; v < h->node_count; ++v) {
        const glow__node *nd = &h->nodes[v];
        if (v < h->leaf_count) {
            job.radius[v] = sqrtf(surfels->s[v].area / (float)GLOW__PI);
            job.cone[v] = 0.0f;
            /* in units of the nominal area (1 each unless the density adapts), so that the
             * clustered pass's S->area x nsum is the area-weighted normal sum */
            const float rel = surfels->s[v].area / surfels->area;
            for (int k = 0; k < 3; ++k) job.nsum[3 * v + k] = rel * surfels->s[v].nrm[k];
            const float *e = surfels->s[v].emission;
            job.emissive[v] = e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f;
            continue;
        }
        float r = 0.0f, cone = 0.0f;
        const bool axis = glow__dot(nd->nrm, nd->nrm) > 0.5f;
        for (int c = 0; c < 2; ++c) {
            const uint32_t u = nd->child[c];
            float d[3];
            glow__sub(h->nodes[u].pos, nd->pos, d);
            const float rc = sqrtf(glow__dot(d, d)) + job.radius[u];
            r = rc > r ? rc : r;
            /* a child's own cone axis is its mean normal, the node's leaf normals for a leaf */
            const float *ax = u < h->leaf_count ? surfels->s[u].nrm : h->nodes[u].nrm;
            const float cu = glow__dot(nd->nrm, ax);
            const float ang = (axis && glow__dot(ax, ax) > 0.5f ? acosf(cu < -1.0f ? -1.0f : (cu > 1.0f ? 1.0f : cu))
                                                                : (float)GLOW__PI) + job.cone[u];
            cone = ang > cone ? ang : cone;
        }
        job.emissive[v] = job.emissive[nd->child[0]] | job.emissive[nd->child[1]] |
                          (settings->join && settings->join[v]); /* a join spans systems: never one cluster */
        job.radius[v] = r; /* a bound from the children's spheres; tightened by the leaves below */
        job.cone[v] = cone < (float)GLOW__PI ? cone : (float)GLOW__PI;
        for (int k = 0; k < 3; ++k) job.nsum[3 * v + k] = job.nsum[3 * nd->child[0] + k] + job.nsum[3 * nd->child[1] + k];
    }
    /* The spheres from the children's spheres grow loose up the tree (each level adds the offset of
     * its children's centres): take the farthest leaf instead, walking each leaf's ancestors
     * (leaves x depth). */
    {
        float rs = 0.0f; /* the largest leaf's radius */
        for (uint32_t i = 0; i < h->leaf_count; ++i) rs = job.radius[i] > rs ? job.radius[i] : rs;
        for (uint32_t v = h->leaf_count; v < h->node_count; ++v) job.radius[v] = rs;
        for (uint32_t i = 0; i < h->leaf_count; ++i)
            for (uint32_t v = h->nodes[i].parent; v != GLOW_NODE_NONE; v = h->nodes[v].parent) {
                float d[3];
                glow__sub(surfels->s[i].pos, h->nodes[v].pos, d);
                const float ri = sqrtf(glow__dot(d, d)) + job.radius[i];
                if (ri > job.radius[v]) job.radius[v] = ri;
            }
    }
    if (settings->cluster_tau > 0.0f) { /* the preorder copy (trav_node) */
        uint32_t *stack = malloc(((size_t)h->level_count + 4u) * sizeof *stack), sp = 0, t = 0;
        if (!stack) {
            glow__errorf(log, "links: out of memory for the hierarchy's preorder");
            res = GLOW_ERROR_OUT_OF_MEMORY;
            goto done;
        }
        stack[sp++] = h->node_count - 1;
        while (sp) {
            const uint32_t v = stack[--sp];
            trav_node *tn = &job.trav[t];
            const bool leaf = v < h->leaf_count;
            memcpy(tn->pos, leaf ? surfels->s[v].pos : h->nodes[v].pos, sizeof tn->pos);
            memcpy(tn->nrm, leaf ? surfels->s[v].nrm : h->nodes[v].nrm, sizeof tn->nrm);
            memcpy(tn->nsum, &job.nsum[3 * v], sizeof tn->nsum);
            tn->radius = job.radius[v];
            tn->cone = job.cone[v];
            tn->id = v | (job.emissive[v] ? TRAV_EMISSIVE : 0u);
            tn->first = job.leaf_first[v];
            tn->end = job.leaf_end[v];
            tn->skip = t + 2u * (tn->end - tn->first) - 1u; /* a full binary tree: 2 m - 1 nodes */
            tn->child0_low = 0;
            t++;
            if (leaf) continue;
            uint32_t c0 = h->nodes[v].child[0], c1 = h->nodes[v].child[1];
            tn->child0_low = job.leaf_first[c0] < job.leaf_first[c1];
            if (job.leaf_first[c0] < job.leaf_first[c1]) { const uint32_t x = c0; c0 = c1; c1 = x; }
            stack[sp++] = c0; /* the higher leaves, popped after the lower ones' subtree */
            stack[sp++] = c1;
        }
        free(stack);
        job.lift = malloc((size_t)h->node_count * sizeof *job.lift);
        job.leaf_soa = malloc((size_t)surfels->count * 7u * sizeof *job.leaf_soa);
        if (!job.lift || !job.leaf_soa) {
            glow__errorf(log, "links: out of memory for the hierarchy's preorder");
            res = GLOW_ERROR_OUT_OF_MEMORY;
            goto done;
        }
        for (uint32_t i = 0, lc = surfels->count; i < lc; ++i) {
            const glow__surfel *sf = &surfels->s[i];
            for (int k = 0; k < 3; ++k) {
                job.leaf_soa[(size_t)k * lc + i] = sf->pos[k];
                job.leaf_soa[(size_t)(3 + k) * lc + i] = sf->nrm[k];
            }
            job.leaf_soa[(size_t)6 * lc + i] = sf->area;
        }
        for (uint32_t u = 0; u < h->node_count; ++u) {
            const trav_node *tn = &job.trav[u];
            float top = -INFINITY;
            for (uint32_t i = tn->first; i < tn->end; ++i) {
                float d[3];
                glow__sub(surfels->s[i].pos, tn->pos, d);
                const float x = glow__dot(tn->nrm, d);
                if (x > top) top = x;
            }
            job.lift[u] = top;
        }
        if (settings->cluster_samples <= 4u) {
            job.quad = malloc((size_t)h->node_count * sizeof *job.quad);
            if (!job.quad) {
                glow__errorf(log, "links: out of memory for the clusters' parts");
                res = GLOW_ERROR_OUT_OF_MEMORY;
                goto done;
            }
            for (uint32_t u = 0; u < h->node_count; ++u) {
                trav_quad *qd = &job.quad[u];
                memset(qd, 0, sizeof *qd);
                if (job.trav[u].end - job.trav[u].first < 2u * settings->cluster_samples) continue; /* never a cluster */
                uint32_t sub[64];
                qd->ns = cluster_split(job.trav, u, settings->cluster_samples, sub);
                for (uint32_t k = 0; k < qd->ns; ++k) {
                    qd->sub[k] = sub[k];
                    if (k) qd->bnd[k - 1] = job.trav[sub[k]].first;
                }
            }
        }
    }
    {
        float ext[3];
        glow__sub(scene->bounds_max, scene->bounds_min, ext);
        float diag = sqrtf(glow__dot(ext, ext));
        job.ray_eps = 1e-4f * (diag > 0.0f ? diag : 1.0f);
    }
    job.near_radius = NEAR_RADII * sqrtf(surfels->area / (float)GLOW__PI);
    {
        const double golden = GLOW__PI * (3.0 - sqrt(5.0));
        for (uint32_t i = 0; i < NEAR_RAYS; ++i) { /* spherical Fibonacci: equal solid angle each */
            double z = 1.0 - (2.0 * i + 1.0) / NEAR_RAYS, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = golden * i;
            job.sphere_dirs[i][0] = (float)(r * cos(phi));
            job.sphere_dirs[i][1] = (float)(r * sin(phi));
            job.sphere_dirs[i][2] = (float)z;
        }
        for (uint32_t i = 0; i < NEAR_RAYS / 2; ++i) {
            double z = 1.0 - (i + 0.5) / (NEAR_RAYS / 2), r = sqrt(fmax(0.0, 1.0 - z * z)), phi = golden * i;
            job.hemi_dirs[i][0] = (float)(r * cos(phi));
            job.hemi_dirs[i][1] = (float)(r * sin(phi));
            job.hemi_dirs[i][2] = (float)z;
        }
    }
    {
        float(*pts)[3] = malloc(((size_t)surfels->count + 1) * sizeof *pts);
        if (pts) {
            /* this system's surfels only: the near field and the detail credit no neighbour's */
            const uint32_t own = settings->own_leaves ? settings->own_leaves : surfels->count;
            for (uint32_t i = 0; i < own; ++i) memcpy(pts[i], surfels->s[i].pos, sizeof pts[i]);
            /* cells of two spacings: a credit's 8 nearest lie within one ring */
            job.surfel_grid = glow__pointgrid_build((const float(*)[3])pts, own, scene->bounds_min, scene->bounds_max,
                                                    2.0f * sqrtf(surfels->area));
            free(pts);
        }
        if (!job.surfel_grid) {
            glow__errorf(log, "links: out of memory for the surfel search tree");
            res = GLOW_ERROR_OUT_OF_MEMORY;
            goto done;
        }
    }
    { /* this rank's caches, then every rank's (links.c "Ranks") */
        const glow_pc_distribution *dist = settings->dist;
        job.dist = dist;
        job.cache_total = rank_count(dist, dist ? dist->rank : 0u, caches->count);
        glow__parallel_for(pool, job.cache_total, 4, link_range, &job);
        if (dist) {
            const uint32_t R = dist->ranks;
            /* one block per rank, its counts first (block r is rank r's), the rest zero */
            uint64_t *counts = calloc((size_t)R * RANK_BLOCK * 3u, sizeof *counts);
            if (!counts) {
                glow__errorf(log, "links: out of memory sharing the ray counts between ranks");
                res = GLOW_ERROR_OUT_OF_MEMORY;
                goto done;
            }
            uint64_t *mine = counts + (size_t)3u * RANK_BLOCK * dist->rank;
            mine[0] = atomic_load(&job.vis_rays);
            mine[1] = atomic_load(&job.vis_cluster_rays);
            mine[2] = atomic_load(&job.vis_units);
            if ((res = rank_share(dist, out->links, caches->count, (size_t)nl * sizeof *out->links, log, "the links")) != GLOW_OK ||
                (out->sh && (res = rank_share(dist, out->sh, caches->count,
                                              (size_t)nl * settings->sh_bands * settings->sh_bands * sizeof *out->sh, log,
                                              "the full-SH links")) != GLOW_OK) ||
                (out->audit && (res = rank_share(dist, out->audit, caches->count, GLOW__AUDIT_FIELDS * sizeof *out->audit,
                                                 log, "the audit")) != GLOW_OK) ||
                (res = rank_share(dist, job.visible_total, caches->count, sizeof *job.visible_total, log,
                                  "the visible solid angles")) != GLOW_OK ||
                (res = rank_share(dist, job.norm_scale, caches->count, sizeof *job.norm_scale, log,
                                  "the normalisation")) != GLOW_OK ||
                (res = rank_share(dist, job.norm_clamped, caches->count, sizeof *job.norm_clamped, log,
                                  "the normalisation")) != GLOW_OK ||
                (res = rank_share(dist, counts, R * RANK_BLOCK, 3 * sizeof *counts, log, "the ray counts")) != GLOW_OK) {
                free(counts);
                goto done;
            }
            uint64_t sum[3] = {0, 0, 0};
            for (size_t i = 0; i < (size_t)R * RANK_BLOCK; ++i)
                for (int k = 0; k < 3; ++k) sum[k] += counts[3 * i + (size_t)k];
            free(counts);
            atomic_store(&job.vis_rays, (unsigned long long)sum[0]);
            atomic_store(&job.vis_cluster_rays, (unsigned long long)sum[1]);
            atomic_store(&job.vis_units, (unsigned long long)sum[2]);
        }
    }
    if (settings->detail_radius > 0.0f && caches->detail_count && caches->texel_density > 0.0f &&
        (res = detail_build(&job, pool, log, out)) != GLOW_OK)
        goto done;
    {
        uint32_t scaled = 0, clamped = 0;
        float lo = INFINITY, hi = 0.0f;
        for (uint32_t c = 0; c < caches->count; ++c) {
            out->visible_solid_angle_total += job.visible_total[c];
            if (job.norm_scale[c] == 0.0f) continue;
            scaled++;
            clamped += job.norm_clamped[c];
            if (!job.norm_clamped[c]) {
                lo = job.norm_scale[c] < lo ? job.norm_scale[c] : lo;
                hi = job.norm_scale[c] > hi ? job.norm_scale[c] : hi;
            }
        }
        const unsigned long long vr = atomic_load(&job.vis_rays), vc = atomic_load(&job.vis_cluster_rays),
                                 vu = atomic_load(&job.vis_units);
        out->visibility_rays = vr;
        if (settings->cluster_tau > 0.0f && caches->count && vu)
            glow__infof(log, "%s: links: clustered visibility: %.0f visibility rays per cache (%.0f of them for clusters) "
                        "against %u surfels, %.0f runs of leaves per cache", scene->source, (double)vr / caches->count,
                        (double)vc / caches->count, surfels->count, (double)vu / caches->count);
        else if (caches->count)
            glow__infof(log, "%s: links: exact visibility: %.0f visibility rays per cache against %u surfels", scene->source,
                        (double)vr / caches->count, surfels->count);
        if (scaled > clamped)
            glow__infof(log, "%s: links: solid angles of %u of %u caches normalised to the ray-measured visible "
                        "geometry (factor %.3f-%.3f, and %u caches bounded to [%.1f, %.1f])",
                        scene->source, scaled, caches->count, (double)lo, (double)hi, clamped, NORM_MIN, NORM_MAX);
    }
done:
    glow__pointgrid_free(job.surfel_grid);
    for (uint32_t w = 0; w < job.workers; ++w) {
        if (job.omega) free(job.omega[w]);
        if (job.dirsum) free(job.dirsum[w]);
        if (job.kappa) free(job.kappa[w]);
        if (job.prio) free(job.prio[w]);
        if (job.heap) free(job.heap[w]);
        if (job.runs) {
            cl_runs *r = &job.runs[w];
            free(r->a); free(r->b); free(r->w); free(r->k); free(r->d);
            free(r->pw); free(r->pk); free(r->pd); free(r->stamp);
        }
    }
    free(job.runs);
    free(job.radius);
    free(job.cone);
    free(job.nsum);
    free(job.emissive);
    free(job.trav);
    free(job.lift);
    free(job.leaf_soa);
    free(job.omega);
    free(job.dirsum);
    free(job.kappa);
    free(job.prio);
    free(job.heap);
    free(job.visible_total);
    free(job.norm_scale);
    free(job.norm_clamped);
    free(job.leaf_first);
    free(job.leaf_end);
    free(job.leaf_area);
    free(job.quad);
    free(job.leaf_apos);
    free(job.grad_frame);
    if (res != GLOW_OK) glow__links_free(out);
    return res;
}

void glow__links_free(glow__links *l) {
    if (!l) return;
    free(l->links);
    free(l->sh);
    free(l->audit);
    free(l->detail_first);
    free(l->detail_surfel);
    free(l->detail_weight);
    memset(l, 0, sizeof *l);
}
