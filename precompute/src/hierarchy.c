/* hierarchy.c — surfel hierarchy by agglomerative clustering (PIC 4.3).
 *
 * Metric (PIC Eq. in 4.3):
 *     d(a,b) = |xa - xb|^2 / |xmax - xmin|^2 + Cn (1 - <ma, mb>) + Cb |Aa - Ab| / max(Aa, Ab)
 * with Cb = 0.02, x the area-weighted centre, m the normalised area-weighted mean normal (the zero
 * vector when the normals cancel, so the normal term is then Cn) and A the area. Cn = 0.01, not the
 * paper's 0.1 (departure, issue 13): the position term is relative to the scene's extent E, so Cn
 * sets how far apart two surfels may be before their normals matter less than their distance:
 * opposite normals cost as much as E·sqrt(2 Cn), 0.45 E with 0.1 and 0.14 E with 0.01. At 0.1 a
 * Sponza cluster gathered same-facing surfels from 18 m around before it took a neighbour facing
 * another way: wide clusters that most caches see only in part, whose mean radiosity the link then
 * applies (the diagnosed loss and leaks). Mutually hidden neighbours (both sides of a wall or of a
 * pillar) stay apart through the visibility penalty HAC_CV instead. Sponza against the referee
 * (moderate, 8x8 block error with surfel seeds 0-3): 0.187 0.193 0.205 0.179 -> 0.173 0.173 0.187
 * 0.161, mean ratio 0.897 -> 0.925 on average; Cornell 0.0454 -> 0.0453; and more links now help
 * (Sponza 64 / 128 / 256 links: 0.197 / 0.173 / 0.165, was 0.183 / 0.187 / 0.175).
 *
 * Algorithm: the heap-based *locally-ordered* agglomerative clustering of Walter, Bala, Kulkarni,
 * Pingali, "Fast Agglomerative Clustering for Rendering" (IEEE Symposium on Interactive Ray Tracing
 * 2008), instead of PIC's O(n^2)-memory generic HAC (Müllner 2011):
 *   - every live cluster keeps its best partner (nearest neighbour under d) and sits in a min-heap
 *     keyed by (d, cluster index);
 *   - pop A: dead -> skip; partner B dead -> recompute A's nearest neighbour and re-push; otherwise
 *     re-check A's nearest neighbour, because this metric is not reducible (merging two clusters can
 *     bring their union closer to a third than either was, e.g. through the centroid or the balance
 *     term), so a cluster created after A's search may now be nearer than B; if it is still B, merge
 *     A and B into C, find C's nearest neighbour and push it. The re-check keeps every merged pair a
 *     true nearest-neighbour pair at the time of merging; on small inputs the result matched the
 *     exact O(n^3) greedy HAC in the tests (test_hierarchy.c compares the total merge cost).
 * Nearest-neighbour search is branch-and-bound over a dynamic k-d tree on cluster centres whose nodes
 * carry the bounding box of their clusters' centres, the box of their normals, the range of their
 * areas and a live count. A node's lower bound is the sum of the three terms' lower bounds (each term
 * is >= 0; the position term alone is the box distance^2 / extent^2), and subtrees whose bound exceeds
 * the best distance found are pruned. Deletion marks the cluster dead, unlinks it from its leaf and
 * decrements live counts; a merged cluster is inserted into the leaf whose cell contains its centre,
 * growing the bounds on the way down; the whole tree is rebuilt (median splits) once the insertions
 * since the last build exceed half the live count. Bounds only grow between rebuilds, so they stay
 * conservative.
 *
 * Scale of the terms: the balance term is 0.01 for a single surfel joining a pair, as much as the
 * position term of two centres 0.14 scene diagonals apart; so the low levels are shaped mostly by
 * balance, and a few leftover surfels pair with distant ones (64x64 plane in the tests: clusters of
 * <= 16 surfels have a mean radius of 1.1 spacings, 2.6% are wider than 4). That is the paper's metric
 * as published, up to the moderate preset's surfel count; above it the balance term's weight falls
 * with the surfels' squared spacing (hac_balance).
 *
 * Visibility (glow__hierarchy_build_rt, which the pipeline uses): PIC 5.2 traces its light bleeding
 * (Fig. 9c) to this metric merging clusters that cannot see each other — two rooms' coplanar ceiling
 * strips on either side of a 10 cm wall are as close as any two surfels of one ceiling, and every
 * cache that then links the merged cluster receives its mean radiosity, the other room's light
 * included. So a pair whose centres cannot see each other (hac_occluded: a front face between them)
 * pays HAC_CV on top of d. The penalty only raises d, so the k-d tree's bounds stay lower bounds; a
 * ray pair is cast only for a candidate that would otherwise become the best. builtin:two-rooms: 128
 * of 8191 nodes mixed the rooms without it, 1 (the root) with it.
 *
 * Ties are broken by (distance, cluster index) everywhere, the clustering itself is serial and the only
 * parallel step (the initial nearest-neighbour searches) writes per-cluster results, so the hierarchy
 * is identical for any thread count.
 *
 * Output: surfels reordered in depth-first order of the tree (first child first), leaves [0, n) in
 * that order, internal nodes sorted by (level, depth-first order) and numbered n .. 2n-2, so the pull
 * is a sequence of contiguous level sweeps and the root (unique node of maximal level) is last.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_format.h"
#include "hierarchy.h"
#include "pc_internal.h"

#define HAC_CN 0.01 /* the paper has 0.1: see the top of the file */
#define HAC_CB 0.02
/* The balance term's weight for n surfels: HAC_CB up to HAC_CB_FROM surfels (the moderate preset's
 * count: every bake at or below it as published), HAC_CB x HAC_CB_FROM / n above. The position term
 * of two neighbouring surfels falls as 1/n on a given scene (their squared spacing over the squared
 * extent), the balance term does not: at 16x the surfels a 10 % difference in area weighed as much as
 * 2 m on Sponza, the low levels paired surfels of like area across metres, and the loose clusters
 * cost the clustered visibility 3x the rays (docs/linker.md, "Hierarchy"). Scaled, the balance term
 * weighs against the spacing as it does at HAC_CB_FROM. */
#define HAC_CB_FROM 32768u
static double hac_balance(uint32_t n) {
    return n > HAC_CB_FROM ? HAC_CB * (double)HAC_CB_FROM / (double)n : HAC_CB;
}
/* Added to d(a,b) when a and b cannot see each other (visibility-aware builds only, see below):
 * more than the normal and balance terms together (0.22) plus a quarter of the squared diagonal, so
 * an occluded pair merges only after every visible pair within about half a scene diagonal. */
#define HAC_CV 0.5
/* Added to d(a,b) when exactly one of a and b holds emissive surfels. Emitters are the strongest
 * radiance edge a bake knows about, and a cache receives a node's MEAN radiance: the McGuire Cornell
 * box's lamp (0.18 of 25 units², 230 of 32k surfels) merged with the ceiling or the tall block's top
 * around it, and a floor texel under it, whose 128-link cut ends at about one lamp-sized node, saw
 * the lamp diluted 3x (Glow's indirect light -34 % against the path tracer). With the penalty an
 * emitter forms its own subtree, joined to the rest only after every non-emissive pair within about
 * half a scene diagonal, so a cut reaches a pure emitter node after a few splits. Emission scaled at
 * run time (glow_system_set_material) keeps this split; per-surfel emission set at run time
 * (glow_system_set_surfel_emission) on a surface without material emission does not get it. */
#define HAC_CE 0.5
/* hac_occluded: a segment within HAC_GRAZE (cosine) of both ends' tangent planes is also cast
 * HAC_SIDE ray epsilons (1e-4 of the scene diagonal) to either side */
#define HAC_GRAZE 0.1f
#define HAC_SIDE 4.0f
#define HAC_LEAF_MAX 8u
#define HAC_MAX_DEPTH 96
#define NONE UINT32_MAX

typedef struct cluster {
    double pos[3];   /* area-weighted centre */
    double nsum[3];  /* area-weighted sum of normals */
    double m[3];     /* normalised nsum, or 0 */
    double area;
    double nnd;      /* distance to nn */
    uint32_t child[2];
    uint32_t nn;     /* best partner */
    uint32_t since;  /* clusters created after nn was found have indices from here on */
    uint32_t rec;    /* its record in hac.rec (NONE: inserted since the last rebuild, in its leaf's list) */
    uint32_t leaf;   /* k-d tree leaf holding the cluster (while alive) */
    uint32_t next;   /* next cluster in that leaf's list */
    uint32_t alive;
    uint32_t emissive; /* holds a surfel whose material emits (see HAC_CE) */
} cluster;

typedef struct tnode {
    double lo[3], hi[3];   /* box of the centres */
    double mlo[3], mhi[3]; /* box of the mean normals */
    double alo, ahi;       /* area range */
    double split;
    uint32_t axis;
    uint32_t alive;
    uint32_t parent;
    uint32_t child[2];     /* NONE for leaves */
    uint32_t head;         /* leaves: first cluster inserted since the last rebuild (a list) */
    uint32_t rbegin, rend; /* leaves: their clusters at the last rebuild, hac.rec[rbegin, rend) */
    uint32_t min_id;       /* smallest cluster index ever in the node (exact ties stay cheap) */
    uint32_t max_id;       /* largest cluster index ever in the node (the re-check's search) */
} tnode;

/* What the search reads of a cluster, copied into its leaf's run at each rebuild (a cluster never
 * changes once made): a leaf's clusters were scattered over the cluster array (merged clusters are
 * appended), and their loads were 40 % of the search's samples at 524,288 surfels. One cache line. */
typedef struct crec {
    double pos[3], m[3], area;
    uint32_t id;           /* NONE once dead */
    uint16_t emissive;
    uint16_t leaf;         /* a surfel (hac_occluded) */
} crec;

typedef struct hac {
    cluster *c;
    crec *rec;             /* the leaves' runs (tree_rebuild) */
    uint32_t rcount;
    uint32_t cluster_count;
    double inv_e2;
    double cb;             /* the balance term's weight (hac_balance) */
    const glow__rt *rt;    /* visibility-aware build (NULL: the published metric alone) */
    float ray_eps;         /* ray offsets, 1e-4 x the scene diagonal (as links.c) */
    tnode *t;
    uint32_t tcount, tcap;
    uint32_t *ids;         /* scratch for rebuilds */
    uint32_t live, inserted;
    /* heap */
    double *hkey;
    uint32_t *hid;
    uint32_t hcount;
} hac;

/* ------------------------------------------------------------------ metric */
static inline double hac_metric(const hac *h, const double apos[3], const double am[3], double aarea, uint32_t aem,
                                const double bpos[3], const double bm[3], double barea, uint32_t bem) {
    double dx = apos[0] - bpos[0], dy = apos[1] - bpos[1], dz = apos[2] - bpos[2];
    double p = (dx * dx + dy * dy + dz * dz) * h->inv_e2;
    double dot = am[0] * bm[0] + am[1] * bm[1] + am[2] * bm[2];
    if (dot > 1.0) dot = 1.0;
    double amax = aarea > barea ? aarea : barea;
    return p + HAC_CN * (1.0 - dot) + h->cb * fabs(aarea - barea) / amax + (aem != bem ? HAC_CE : 0.0);
}

/* Visibility of two clusters (visibility-aware builds). Each cluster is represented by its centre
 * lifted 2 ray_eps along its mean normal (a flat cluster's point just in front of its surface). The
 * pair is occluded when the segment between the two points, cast from either end, first hits a
 * FRONT face before it reaches the other end: a surface that faces one of them stands between them
 * (a wall between two rooms, a floor between two storeys, a block between two floor patches). From
 * either end, not both: a surfel that relaxation pushed onto the edge where its floor meets the
 * separating wall lies in the wall's plane, so its own ray starts on that wall, misses it and sees
 * the far room's wall from behind; the ray from the other room's side hits a front face. The price:
 * a convex cluster whose centre lies inside its solid (two faces of a block) looks occluded from
 * outside, so it joins the clusters around it only after the visible pairs: no point outside sees
 * all of a convex solid's faces anyway. Symmetric, deterministic, thread-safe. */
/* A front face across the segment pa -> pb (len, unit d), cast from both ends. */
static bool hac_segment_blocked(const hac *h, const float pa[3], const float pb[3], const float d[3], float len) {
    glow__hit hit = glow__rt_intersect(h->rt, pa, d, h->ray_eps, len - h->ray_eps);
    if (hit.t != INFINITY && !hit.back_face) return true;
    const float nd[3] = {-d[0], -d[1], -d[2]};
    hit = glow__rt_intersect(h->rt, pb, nd, h->ray_eps, len - h->ray_eps);
    return hit.t != INFINITY && !hit.back_face;
}

/* a and b by their centres, mean normals and whether they are leaves (surfels) */
static bool hac_occluded(const hac *h, const double apos[3], const double am[3], bool aleaf, const double bpos[3],
                         const double bm[3], bool bleaf) {
    float pa[3], pb[3], d[3];
    const double lift = 2.0 * h->ray_eps;
    for (int k = 0; k < 3; ++k) {
        pa[k] = (float)(apos[k] + lift * am[k]);
        pb[k] = (float)(bpos[k] + lift * bm[k]);
    }
    glow__sub(pb, pa, d);
    float len = sqrtf(glow__dot(d, d));
    if (!(len > 4.0f * h->ray_eps)) return false;
    for (int k = 0; k < 3; ++k) d[k] /= len;
    if (hac_segment_blocked(h, pa, pb, d, len)) return true;
    /* A segment that runs along both ends' surfaces can lie in the edge where they meet another
     * surface: relaxation pushes surfels onto creases, and two rooms' surfels on the top edges of
     * their back walls, either side of a 10 cm partition, are joined by a segment that grazes the
     * partition's top edges and the ceiling without crossing either (builtin:two-rooms). Between two
     * leaves (surfels: child[0] == child[1], both 0 from the allocation), such a segment is also
     * cast HAC_SIDE ray epsilons to either side (across the segment, within the ends' mean tangent
     * plane); a front face across either side counts. Clusters' centres are not on edges. */
    if (!aleaf || !bleaf) return false; /* only between leaves */
    const float fa = (float)(am[0] * d[0] + am[1] * d[1] + am[2] * d[2]);
    const float fb = (float)(bm[0] * d[0] + bm[1] * d[1] + bm[2] * d[2]);
    if (fabsf(fa) > HAC_GRAZE || fabsf(fb) > HAC_GRAZE) return false;
    float m[3] = {(float)(am[0] + bm[0]), (float)(am[1] + bm[1]), (float)(am[2] + bm[2])}, side[3];
    glow__cross(d, m, side);
    const float sl = sqrtf(glow__dot(side, side));
    if (!(sl > 1e-3f)) return false; /* opposite normals or none: no tangent plane */
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        const float off = (float)sgn * HAC_SIDE * h->ray_eps / sl;
        float qa[3], qb[3];
        for (int k = 0; k < 3; ++k) {
            qa[k] = pa[k] + off * side[k];
            qb[k] = pb[k] + off * side[k];
        }
        if (hac_segment_blocked(h, qa, qb, d, len)) return true;
    }
    return false;
}

/* Lower bound of hac_metric(q, x) over all clusters x inside node nd. */
static double node_bound(const hac *h, const tnode *nd, const cluster *q) {
    double p = 0.0, ub = 0.0;
    for (int k = 0; k < 3; ++k) {
        double g = 0.0;
        if (q->pos[k] < nd->lo[k]) g = nd->lo[k] - q->pos[k];
        else if (q->pos[k] > nd->hi[k]) g = q->pos[k] - nd->hi[k];
        p += g * g;
        ub += q->m[k] >= 0.0 ? q->m[k] * nd->mhi[k] : q->m[k] * nd->mlo[k];
    }
    if (ub > 1.0) ub = 1.0;
    double A = q->area, b = 0.0;
    if (A < nd->alo) b = (nd->alo - A) / nd->alo;
    else if (A > nd->ahi) b = (A - nd->ahi) / A;
    return p * h->inv_e2 + HAC_CN * (1.0 - ub) + h->cb * b;
}

/* ------------------------------------------------------------------ dynamic k-d tree */
static void node_reset(tnode *nd, uint32_t parent) {
    for (int k = 0; k < 3; ++k) {
        nd->lo[k] = INFINITY;
        nd->hi[k] = -INFINITY;
        nd->mlo[k] = INFINITY;
        nd->mhi[k] = -INFINITY;
    }
    nd->alo = INFINITY;
    nd->ahi = -INFINITY;
    nd->split = 0.0;
    nd->axis = 0;
    nd->alive = 0;
    nd->parent = parent;
    nd->child[0] = nd->child[1] = NONE;
    nd->head = NONE;
    nd->rbegin = nd->rend = 0;
    nd->min_id = NONE;
    nd->max_id = 0;
}

static void node_grow(tnode *nd, const cluster *c, uint32_t id) {
    if (id < nd->min_id) nd->min_id = id;
    if (id > nd->max_id) nd->max_id = id;
    for (int k = 0; k < 3; ++k) {
        if (c->pos[k] < nd->lo[k]) nd->lo[k] = c->pos[k];
        if (c->pos[k] > nd->hi[k]) nd->hi[k] = c->pos[k];
        if (c->m[k] < nd->mlo[k]) nd->mlo[k] = c->m[k];
        if (c->m[k] > nd->mhi[k]) nd->mhi[k] = c->m[k];
    }
    if (c->area < nd->alo) nd->alo = c->area;
    if (c->area > nd->ahi) nd->ahi = c->area;
}

/* A k-d node splits on a centre coordinate (axis 0-2) or on the area (HAC_AXIS_AREA): see tree_build_rec. */
#define HAC_AXIS_AREA 3u
static double axis_key(const cluster *c, uint32_t axis) { return axis == HAC_AXIS_AREA ? c->area : c->pos[axis]; }

static int less_on_axis(const cluster *c, uint32_t a, uint32_t b, uint32_t axis) {
    double ca = axis_key(&c[a], axis), cb = axis_key(&c[b], axis);
    if (ca < cb) return 1;
    if (ca > cb) return 0;
    return a < b;
}

/* Quickselect by (coordinate, index): afterwards idx[k] has rank k, lower ranks before it. */
static void select_kth(const cluster *c, uint32_t *idx, uint32_t n, uint32_t k, uint32_t axis) {
    uint32_t lo = 0, hi = n - 1;
    while (hi > lo) {
        uint32_t mid = lo + (hi - lo) / 2, t;
        if (less_on_axis(c, idx[mid], idx[lo], axis)) { t = idx[mid]; idx[mid] = idx[lo]; idx[lo] = t; }
        if (less_on_axis(c, idx[hi], idx[lo], axis)) { t = idx[hi]; idx[hi] = idx[lo]; idx[lo] = t; }
        if (less_on_axis(c, idx[hi], idx[mid], axis)) { t = idx[hi]; idx[hi] = idx[mid]; idx[mid] = t; }
        uint32_t pivot = idx[mid];
        uint32_t i = lo, j = hi;
        for (;;) {
            while (less_on_axis(c, idx[i], pivot, axis)) ++i;
            while (less_on_axis(c, pivot, idx[j], axis)) --j;
            if (i >= j) break;
            t = idx[i]; idx[i] = idx[j]; idx[j] = t;
            ++i;
            --j;
        }
        if (k <= j) hi = j;
        else lo = j + 1;
    }
}

static uint32_t tree_build_rec(hac *h, uint32_t *ids, uint32_t count, uint32_t parent, int depth) {
    uint32_t ni = h->tcount++; /* tcap bounds the node count of median splits (see hac_init) */
    tnode *nd = &h->t[ni];
    node_reset(nd, parent);
    for (uint32_t i = 0; i < count; ++i) node_grow(nd, &h->c[ids[i]], ids[i]);
    nd->alive = count;
    if (count <= HAC_LEAF_MAX || depth >= HAC_MAX_DEPTH) {
        nd->rbegin = h->rcount;
        for (uint32_t i = 0; i < count; ++i) {
            cluster *c = &h->c[ids[i]];
            crec *r = &h->rec[h->rcount];
            memcpy(r->pos, c->pos, sizeof r->pos);
            memcpy(r->m, c->m, sizeof r->m);
            r->area = c->area;
            r->id = ids[i];
            r->emissive = (uint16_t)c->emissive;
            r->leaf = c->child[0] == c->child[1];
            c->rec = h->rcount++;
            c->leaf = ni;
        }
        nd->rend = h->rcount;
        return ni;
    }
    /* The axis along which the node's clusters differ most in the metric: a centre coordinate's
     * extent squared over the scene's, or the balance term across the node's area range. The low
     * levels are shaped by balance (top of the file): a surfel's nearest partner is the one of most
     * similar area within about 2 m on Sponza, so a tree of positions alone left every cluster
     * there to be weighed (about 100 a query at 524,288 surfels); splitting on the area as well
     * lets node_bound's balance term prune. The search is exact whatever the tree, so the
     * hierarchy does not change. */
    uint32_t axis = 0;
    double spread = -1.0;
    for (uint32_t k = 0; k < 3; ++k) {
        const double e = nd->hi[k] - nd->lo[k], sk = e * e * h->inv_e2;
        if (sk > spread) { spread = sk; axis = k; }
    }
    if (nd->ahi > 0.0 && h->cb * (1.0 - nd->alo / nd->ahi) > spread) axis = HAC_AXIS_AREA;
    uint32_t half = count / 2;
    select_kth(h->c, ids, count, half, axis);
    nd->axis = axis;
    nd->split = axis_key(&h->c[ids[half]], axis);
    uint32_t l = tree_build_rec(h, ids, half, ni, depth + 1);
    uint32_t r = tree_build_rec(h, ids + half, count - half, ni, depth + 1);
    h->t[ni].child[0] = l;
    h->t[ni].child[1] = r;
    return ni;
}

static void tree_rebuild(hac *h) {
    uint32_t n = 0;
    for (uint32_t i = 0; i < h->cluster_count; ++i)
        if (h->c[i].alive) h->ids[n++] = i;
    h->tcount = 0;
    h->rcount = 0;
    tree_build_rec(h, h->ids, n, NONE, 0);
    h->inserted = 0;
}

static void tree_remove(hac *h, uint32_t id) {
    cluster *c = &h->c[id];
    c->alive = 0;
    tnode *leaf = &h->t[c->leaf];
    if (c->rec != NONE) {
        h->rec[c->rec].id = NONE;
    } else if (leaf->head == id) {
        leaf->head = c->next;
    } else {
        uint32_t p = leaf->head;
        while (h->c[p].next != id) p = h->c[p].next;
        h->c[p].next = c->next;
    }
    for (uint32_t ni = c->leaf; ni != NONE; ni = h->t[ni].parent) h->t[ni].alive--;
}

static void tree_insert(hac *h, uint32_t id) {
    cluster *c = &h->c[id];
    uint32_t ni = 0;
    for (;;) {
        tnode *nd = &h->t[ni];
        node_grow(nd, c, id);
        nd->alive++;
        if (nd->child[0] == NONE) break;
        ni = axis_key(c, nd->axis) < nd->split ? nd->child[0] : nd->child[1];
    }
    c->leaf = ni;
    c->rec = NONE;
    c->next = h->t[ni].head;
    h->t[ni].head = id;
    h->inserted++;
}

/* (d, id) lexicographic order: true when (da, ia) ranks before (db, ib). */
static int ranks_before(double da, uint32_t ia, double db, uint32_t ib) { return da < db || (da == db && ia < ib); }

/* Candidate ci (its centre, mean normal, area, emitter flag, whether it is a leaf) against the best so
 * far (*bi, *bd) of the search for q. The occlusion penalty only ever raises d, so the bounds stay
 * lower bounds and rays are cast only for candidates that would otherwise win. */
static inline void hac_consider(const hac *h, const cluster *q, bool qleaf, uint32_t ci, const double pos[3],
                                const double m[3], double area, uint32_t emissive, bool leaf, uint32_t *bi, double *bd) {
    double d = hac_metric(h, q->pos, q->m, q->area, q->emissive, pos, m, area, emissive);
    if (*bi != NONE && !ranks_before(d, ci, *bd, *bi)) return;
    if (h->rt && hac_occluded(h, q->pos, q->m, qleaf, pos, m, leaf)) {
        d += HAC_CV;
        if (*bi != NONE && !ranks_before(d, ci, *bd, *bi)) return;
    }
    *bd = d;
    *bi = ci;
}

/* Nearest live cluster to q under hac_metric among those of index `since` or more, and (bd, best) on
 * entry (NONE, INFINITY: none yet), ties to the smaller index. A subtree is searched only when (its
 * lower bound, its smallest index) ranks before the best so far and it has held an index from
 * `since` on. */
static uint32_t tree_nearest_since(const hac *h, uint32_t qid, uint32_t since, uint32_t best, double bd,
                                   double *out_d) {
    const cluster *q = &h->c[qid];
    const bool qleaf = q->child[0] == q->child[1];
    struct { uint32_t node; double bound; } stack[HAC_MAX_DEPTH + 4];
    int sp = 0;
    if (h->tcount == 0 || h->t[0].alive == 0 || h->t[0].max_id < since) { *out_d = bd; return best; }
    stack[0].node = 0;
    stack[0].bound = node_bound(h, &h->t[0], q);
    sp = 1;
    while (sp > 0) {
        --sp;
        const tnode *nd = &h->t[stack[sp].node];
        if (best != NONE && !ranks_before(stack[sp].bound, nd->min_id, bd, best)) continue;
        if (nd->child[0] == NONE) {
            for (uint32_t ri = nd->rbegin; ri < nd->rend; ++ri) { /* the leaf's records */
                const crec *r = &h->rec[ri];
                if (r->id == NONE || r->id == qid || r->id < since) continue;
                hac_consider(h, q, qleaf, r->id, r->pos, r->m, r->area, r->emissive, r->leaf, &best, &bd);
            }
            for (uint32_t ci = nd->head; ci != NONE; ci = h->c[ci].next) { /* inserted since the rebuild */
                if (ci == qid || ci < since) continue;
                const cluster *x = &h->c[ci];
                hac_consider(h, q, qleaf, ci, x->pos, x->m, x->area, x->emissive, x->child[0] == x->child[1], &best, &bd);
            }
            continue;
        }
        uint32_t li = nd->child[0], ri = nd->child[1];
        const tnode *l = &h->t[li], *r = &h->t[ri];
        double bl = l->alive ? node_bound(h, l, q) : INFINITY;
        double br = r->alive ? node_bound(h, r, q) : INFINITY;
        int lgo = l->alive && l->max_id >= since && (best == NONE || ranks_before(bl, l->min_id, bd, best));
        int rgo = r->alive && r->max_id >= since && (best == NONE || ranks_before(br, r->min_id, bd, best));
        /* farther first, so the nearer child is searched first */
        if (bl <= br) {
            if (rgo) { stack[sp].node = ri; stack[sp].bound = br; ++sp; }
            if (lgo) { stack[sp].node = li; stack[sp].bound = bl; ++sp; }
        } else {
            if (lgo) { stack[sp].node = li; stack[sp].bound = bl; ++sp; }
            if (rgo) { stack[sp].node = ri; stack[sp].bound = br; ++sp; }
        }
    }
    *out_d = bd;
    return best;
}

/* Nearest live cluster to q under hac_metric, ties to the smaller index. */
static uint32_t tree_nearest(const hac *h, uint32_t qid, double *out_d) {
    return tree_nearest_since(h, qid, 0, NONE, INFINITY, out_d);
}

/* ------------------------------------------------------------------ heap of (distance, cluster) */
static int heap_less(const hac *h, uint32_t i, uint32_t j) {
    return h->hkey[i] < h->hkey[j] || (h->hkey[i] == h->hkey[j] && h->hid[i] < h->hid[j]);
}

static void heap_swap(hac *h, uint32_t i, uint32_t j) {
    double k = h->hkey[i];
    h->hkey[i] = h->hkey[j];
    h->hkey[j] = k;
    uint32_t t = h->hid[i];
    h->hid[i] = h->hid[j];
    h->hid[j] = t;
}

static void heap_down(hac *h, uint32_t i) {
    for (;;) {
        uint32_t l = 2 * i + 1, r = l + 1, m = i;
        if (l < h->hcount && heap_less(h, l, m)) m = l;
        if (r < h->hcount && heap_less(h, r, m)) m = r;
        if (m == i) return;
        heap_swap(h, i, m);
        i = m;
    }
}

static void heap_push(hac *h, double key, uint32_t id) {
    uint32_t i = h->hcount++;
    h->hkey[i] = key;
    h->hid[i] = id;
    while (i > 0) {
        uint32_t p = (i - 1) / 2;
        if (!heap_less(h, i, p)) break;
        heap_swap(h, i, p);
        i = p;
    }
}

static void heap_pop(hac *h) {
    h->hcount--;
    if (h->hcount == 0) return;
    h->hkey[0] = h->hkey[h->hcount];
    h->hid[0] = h->hid[h->hcount];
    heap_down(h, 0);
}

/* ------------------------------------------------------------------ clustering */
static void set_mean_normal(cluster *c) {
    double len = sqrt(c->nsum[0] * c->nsum[0] + c->nsum[1] * c->nsum[1] + c->nsum[2] * c->nsum[2]);
    if (len > 1e-6 * c->area) {
        for (int k = 0; k < 3; ++k) c->m[k] = c->nsum[k] / len;
    } else {
        c->m[0] = c->m[1] = c->m[2] = 0.0;
    }
}

typedef struct nn_ctx {
    hac *h;
} nn_ctx;

static void initial_nn_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    hac *h = ((nn_ctx *)vctx)->h;
    for (uint32_t i = begin; i < end; ++i) {
        h->c[i].nn = tree_nearest(h, i, &h->c[i].nnd);
        h->c[i].since = h->cluster_count;
    }
}

static void hac_free(hac *h) {
    free(h->c);
    free(h->t);
    free(h->ids);
    free(h->rec);
    free(h->hkey);
    free(h->hid);
    memset(h, 0, sizeof *h);
}

/* Runs the clustering; clusters [0, n) are the surfels, the root is cluster 2n-2. */
static glow_result hac_cluster(hac *h, uint32_t n, double inv_e2, double cb, const glow__rt *rt, float ray_eps,
                               glow__pool *pool);

static glow_result hac_run(hac *h, const glow__surfels *surfels, double inv_e2, double cb, const glow__rt *rt,
                           float ray_eps, glow__pool *pool) {
    const uint32_t n = surfels->count;
    const uint32_t total = 2 * n - 1;
    h->c = calloc(total, sizeof *h->c);
    if (!h->c) return GLOW_ERROR_OUT_OF_MEMORY;
    for (uint32_t i = 0; i < n; ++i) {
        cluster *c = &h->c[i];
        const glow__surfel *s = &surfels->s[i];
        const double a = s->area;
        for (int k = 0; k < 3; ++k) {
            c->pos[k] = s->pos[k];
            c->nsum[k] = a * s->nrm[k];
        }
        c->area = a;
        c->emissive = s->emission[0] > 0.0f || s->emission[1] > 0.0f || s->emission[2] > 0.0f;
    }
    return hac_cluster(h, n, inv_e2, cb, rt, ray_eps, pool);
}

/* Clusters h->c[0, n) (allocated for 2n - 1, with pos, nsum, area and emissive set) into one tree:
 * clusters [0, n) are the leaves, the root is cluster 2n-2. */
static glow_result hac_cluster(hac *h, uint32_t n, double inv_e2, double c_b, const glow__rt *rt, float ray_eps,
                               glow__pool *pool) {
    const uint32_t total = 2 * n - 1;
    h->inv_e2 = inv_e2;
    h->cb = c_b;
    h->rt = rt;
    h->ray_eps = ray_eps;
    /* median splits: leaves hold > HAC_LEAF_MAX/2 clusters when split, so < 2*(n/(LEAF/2)+1) nodes */
    h->tcap = 2u * (n / (HAC_LEAF_MAX / 2u) + 1u) + 1u;
    h->t = malloc((size_t)h->tcap * sizeof *h->t);
    h->ids = malloc((size_t)n * sizeof *h->ids);
    h->rec = malloc((size_t)n * sizeof *h->rec);
    h->hkey = malloc((size_t)n * sizeof *h->hkey);
    h->hid = malloc((size_t)n * sizeof *h->hid);
    if (!h->c || !h->t || !h->ids || !h->rec || !h->hkey || !h->hid) return GLOW_ERROR_OUT_OF_MEMORY;
    for (uint32_t i = 0; i < n; ++i) {
        cluster *c = &h->c[i];
        c->child[0] = c->child[1] = NONE;
        c->alive = 1;
        set_mean_normal(c);
    }
    h->cluster_count = n;
    h->live = n;
    tree_rebuild(h);

    nn_ctx ctx = {h};
    glow__parallel_for(pool, n, 256, initial_nn_range, &ctx);
    for (uint32_t i = 0; i < n; ++i) heap_push(h, h->c[i].nnd, i);

    while (h->live > 1 && h->hcount > 0) {
        uint32_t A = h->hid[0];
        heap_pop(h);
        cluster *ca = &h->c[A];
        if (!ca->alive) continue;
        uint32_t B = ca->nn;
        if (B == NONE || !h->c[B].alive) {
            ca->nn = tree_nearest(h, A, &ca->nnd);
            ca->since = h->cluster_count;
            heap_push(h, ca->nnd, A);
            continue;
        }
        /* re-check: a newer cluster may be nearer than B (the metric is not reducible). Only a newer
         * one: every cluster alive when B was found, and alive still, is as far from A as it was, so
         * it still ranks after B; the search weighs the clusters created since, against B (about
         * a quarter of the bake's searches, each of them until 2026-11-30 over every live cluster;
         * the same tree). */
        double d;
        uint32_t best = tree_nearest_since(h, A, ca->since, B, ca->nnd, &d);
        if (best != B) {
            ca->nn = best;
            ca->nnd = d;
            ca->since = h->cluster_count;
            heap_push(h, d, A);
            continue;
        }
        /* merge A and B into C */
        uint32_t C = h->cluster_count++;
        cluster *cc = &h->c[C];
        const cluster *cb = &h->c[B];
        cc->area = ca->area + cb->area;
        for (int k = 0; k < 3; ++k) {
            cc->pos[k] = (ca->area * ca->pos[k] + cb->area * cb->pos[k]) / cc->area;
            cc->nsum[k] = ca->nsum[k] + cb->nsum[k];
        }
        set_mean_normal(cc);
        cc->child[0] = A < B ? A : B;
        cc->child[1] = A < B ? B : A;
        cc->alive = 1;
        cc->emissive = ca->emissive | cb->emissive;
        tree_remove(h, A);
        tree_remove(h, B);
        tree_insert(h, C);
        h->live--;
        if (h->live > 1) {
            if (h->inserted > h->live / 2) tree_rebuild(h);
            cc->nn = tree_nearest(h, C, &cc->nnd);
            cc->since = h->cluster_count;
            heap_push(h, cc->nnd, C);
        }
    }
    return h->cluster_count == total ? GLOW_OK : GLOW_ERROR_INVALID_OPERATION;
}

/* ------------------------------------------------------------------ chunked clustering
 * The clustering above is serial: 23 s of Sponza's 68 s bake at 524,288 surfels (2 threads), as much
 * as the links once they stopped costing caches x surfels. Above HAC_CHUNK_FROM surfels the surfels
 * are split in space (median cuts across the longest axis of their centres, ties by index) into
 * chunks of at most HAC_CHUNK, each chunk is clustered on its own, in parallel, with the same metric
 * (the scene's extent, the visibility and emitter terms), and the chunks' roots are then clustered
 * into one tree. No cluster spans two chunks below the top, which a cut (128 links of a tree with
 * thousands of nodes above the chunks' roots) always opens. Same bytes for any thread count (each
 * chunk is serial and writes only its own result). Bakes of at most HAC_CHUNK_FROM surfels (every
 * preset) do not change. */
#define HAC_CHUNK 65536u
#define HAC_CHUNK_FROM 131072u

typedef struct chunk_job {
    const glow__surfels *surfels;
    uint32_t chunk;        /* at most this many surfels a chunk */
    const uint32_t *idx;   /* surfel indices, chunk c is idx[start[c], start[c + 1]) */
    const uint32_t *start;
    hac *sub;              /* per chunk */
    glow_result *res;      /* per chunk */
    double inv_e2, cb;
    const glow__rt *rt;
    float ray_eps;
} chunk_job;

static void chunk_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    chunk_job *j = vctx;
    for (uint32_t c = begin; c < end; ++c) {
        const uint32_t m = j->start[c + 1] - j->start[c];
        hac *h = &j->sub[c];
        h->c = calloc(2u * m - 1u, sizeof *h->c);
        if (!h->c) { j->res[c] = GLOW_ERROR_OUT_OF_MEMORY; continue; }
        for (uint32_t l = 0; l < m; ++l) {
            const glow__surfel *s = &j->surfels->s[j->idx[j->start[c] + l]];
            const double a = s->area;
            cluster *cl = &h->c[l];
            for (int k = 0; k < 3; ++k) {
                cl->pos[k] = s->pos[k];
                cl->nsum[k] = a * s->nrm[k];
            }
            cl->area = a;
            cl->emissive = s->emission[0] > 0.0f || s->emission[1] > 0.0f || s->emission[2] > 0.0f;
        }
        j->res[c] = hac_cluster(h, m, j->inv_e2, j->cb, j->rt, j->ray_eps, NULL);
        /* keep the clusters, free the search structures now (the other chunks still run) */
        free(h->t);
        free(h->ids);
        free(h->rec);
        free(h->hkey);
        free(h->hid);
        h->t = NULL;
        h->rec = NULL;
        h->ids = h->hid = NULL;
        h->hkey = NULL;
    }
}

typedef struct key_index {
    float x;
    uint32_t i;
} key_index;
static int cmp_key_index(const void *pa, const void *pb) {
    const key_index *a = pa, *b = pb;
    return a->x < b->x ? -1 : (a->x > b->x ? 1 : (a->i < b->i ? -1 : (a->i > b->i)));
}

/* idx[lo, hi) split into chunks of at most HAC_CHUNK; their starts appended to start[*count] */
static void chunk_split(const glow__surfels *S, uint32_t *idx, key_index *keys, uint32_t lo, uint32_t hi, uint32_t chunk,
                        uint32_t *start, uint32_t *count) {
    if (hi - lo <= chunk) {
        start[(*count)++] = lo;
        return;
    }
    float bl[3] = {INFINITY, INFINITY, INFINITY}, bh[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = lo; i < hi; ++i)
        for (int k = 0; k < 3; ++k) {
            const float x = S->s[idx[i]].pos[k];
            bl[k] = x < bl[k] ? x : bl[k];
            bh[k] = x > bh[k] ? x : bh[k];
        }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (bh[k] - bl[k] > bh[axis] - bl[axis]) axis = k;
    for (uint32_t i = lo; i < hi; ++i) keys[i] = (key_index){S->s[idx[i]].pos[axis], idx[i]};
    qsort(keys + lo, hi - lo, sizeof *keys, cmp_key_index);
    for (uint32_t i = lo; i < hi; ++i) idx[i] = keys[i].i;
    const uint32_t mid = lo + (hi - lo) / 2;
    chunk_split(S, idx, keys, lo, mid, chunk, start, count);
    chunk_split(S, idx, keys, mid, hi, chunk, start, count);
}

/* The chunked clustering into out->c (2n - 1 clusters: the surfels, then internal clusters children
 * first, the root last), as hac_run leaves it. */
static glow_result hac_run_chunked(hac *out, const glow__surfels *surfels, double inv_e2, double cb, const glow__rt *rt,
                                   float ray_eps, uint32_t chunk, glow__pool *pool, glow__log *log) {
    const uint32_t n = surfels->count, total = 2u * n - 1u;
    const uint32_t max_chunks = 2u * (n / (chunk / 2u) + 1u);
    key_index *keys = malloc((size_t)n * sizeof *keys);
    uint32_t *idx = malloc((size_t)n * sizeof *idx), *start = malloc(((size_t)max_chunks + 1u) * sizeof *start);
    uint32_t *roots = malloc((size_t)max_chunks * sizeof *roots);
    hac *sub = calloc(max_chunks, sizeof *sub);
    glow_result *res = calloc(max_chunks, sizeof *res);
    hac top;
    memset(&top, 0, sizeof top);
    glow_result r = GLOW_OK;
    uint32_t P = 0;
    out->c = calloc(total, sizeof *out->c);
    if (!keys || !idx || !start || !roots || !sub || !res || !out->c) { r = GLOW_ERROR_OUT_OF_MEMORY; goto done; }
    for (uint32_t i = 0; i < n; ++i) idx[i] = i;
    chunk_split(surfels, idx, keys, 0, n, chunk, start, &P);
    free(keys);
    keys = NULL;
    start[P] = n;
    chunk_job job = {.surfels = surfels, .chunk = chunk, .idx = idx, .start = start, .sub = sub, .res = res, .inv_e2 = inv_e2,
                     .cb = cb, .rt = rt, .ray_eps = ray_eps};
    glow__parallel_for(pool, P, 1, chunk_range, &job);
    for (uint32_t c = 0; c < P; ++c)
        if (res[c] != GLOW_OK) { r = res[c]; goto done; }
    /* the chunks' clusters into the global numbering: leaves are their surfels, internal clusters
     * chunk by chunk in creation order */
    uint32_t base = n;
    for (uint32_t c = 0; c < P; ++c) {
        const uint32_t m = start[c + 1] - start[c], first = start[c];
#define CHUNK_GLOBAL(l) ((l) < m ? idx[first + (l)] : base + ((l) - m))
        for (uint32_t l = 0; l < 2u * m - 1u; ++l) {
            cluster x = sub[c].c[l];
            if (l >= m) {
                x.child[0] = CHUNK_GLOBAL(x.child[0]);
                x.child[1] = CHUNK_GLOBAL(x.child[1]);
            }
            x.nn = NONE;
            out->c[CHUNK_GLOBAL(l)] = x;
        }
        roots[c] = CHUNK_GLOBAL(2u * m - 2u);
#undef CHUNK_GLOBAL
        base += m - 1u;
        free(sub[c].c);
        sub[c].c = NULL;
    }
    /* the roots into one tree */
    top.c = calloc(2u * P - 1u, sizeof *top.c);
    if (!top.c) { r = GLOW_ERROR_OUT_OF_MEMORY; goto done; }
    for (uint32_t c = 0; c < P; ++c) {
        const cluster *x = &out->c[roots[c]];
        memcpy(top.c[c].pos, x->pos, sizeof x->pos);
        memcpy(top.c[c].nsum, x->nsum, sizeof x->nsum);
        top.c[c].area = x->area;
        top.c[c].emissive = x->emissive;
    }
    r = hac_cluster(&top, P, inv_e2, cb, rt, ray_eps, pool);
    if (r != GLOW_OK) goto done;
    for (uint32_t l = P; l < 2u * P - 1u; ++l) {
        cluster x = top.c[l];
        for (int k = 0; k < 2; ++k) x.child[k] = x.child[k] < P ? roots[x.child[k]] : base + (x.child[k] - P);
        x.nn = NONE;
        out->c[base + (l - P)] = x;
    }
    out->cluster_count = total;
    glow__infof(log, "hierarchy: %u surfels clustered in %u spatial chunks of at most %u (in parallel), then their roots",
                n, P, chunk);
done:
    for (uint32_t c = 0; sub && c < P; ++c) hac_free(&sub[c]);
    hac_free(&top);
    free(keys);
    free(idx);
    free(start);
    free(roots);
    free(sub);
    free(res);
    return r;
}

/* ------------------------------------------------------------------ output */
glow_result glow__hierarchy_build(glow__surfels *surfels, const float scene_min[3], const float scene_max[3],
                                  glow__pool *pool, glow__log *log, glow__hierarchy *out) {
    return glow__hierarchy_build_rt(surfels, scene_min, scene_max, NULL, pool, log, out);
}

glow_result glow__hierarchy_build_rt(glow__surfels *surfels, const float scene_min[3], const float scene_max[3],
                                     const glow__rt *rt, glow__pool *pool, glow__log *log, glow__hierarchy *out) {
    return glow__hierarchy_build_chunked(surfels, scene_min, scene_max, rt, HAC_CHUNK_FROM, HAC_CHUNK, pool, log, out);
}

glow_result glow__hierarchy_build_chunked(glow__surfels *surfels, const float scene_min[3], const float scene_max[3],
                                          const glow__rt *rt, uint32_t chunk_from, uint32_t chunk, glow__pool *pool,
                                          glow__log *log, glow__hierarchy *out) {
    if (!out) return GLOW_ERROR_INVALID_ARGUMENT;
    if (chunk < 2u) chunk = 2u;
    memset(out, 0, sizeof *out);
    if (!surfels || surfels->count == 0 || !surfels->s) {
        glow__errorf(log, "hierarchy: no surfels to cluster");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!(surfels->area > 0.0f) || !isfinite(surfels->area)) {
        glow__errorf(log, "hierarchy: surfel area %g is not positive and finite", (double)surfels->area);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t n = surfels->count;
    if (n > 0x7FFFFFFFu) {
        glow__errorf(log, "hierarchy: %u surfels are too many (at most 2^31 - 1)", n);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    for (uint32_t i = 0; i < n; ++i) {
        const glow__surfel *s = &surfels->s[i];
        if (!isfinite(s->pos[0]) || !isfinite(s->pos[1]) || !isfinite(s->pos[2]) || !isfinite(s->nrm[0]) ||
            !isfinite(s->nrm[1]) || !isfinite(s->nrm[2])) {
            glow__errorf(log, "hierarchy: surfel %u has a non-finite position or normal", i);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
        if (!(s->area > 0.0f) || !isfinite(s->area)) {
            glow__errorf(log, "hierarchy: surfel %u has area %g, not positive and finite", i, (double)s->area);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    }

    /* normalisation: squared scene extent (from the surfels when the given bounds are unusable) */
    double e2 = 0.0;
    if (scene_min && scene_max) {
        for (int k = 0; k < 3; ++k) {
            double e = (double)scene_max[k] - scene_min[k];
            e2 += e * e;
        }
    }
    if (!(e2 > 0.0) || !isfinite(e2)) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t i = 0; i < n; ++i)
            for (int k = 0; k < 3; ++k) {
                if (surfels->s[i].pos[k] < lo[k]) lo[k] = surfels->s[i].pos[k];
                if (surfels->s[i].pos[k] > hi[k]) hi[k] = surfels->s[i].pos[k];
            }
        e2 = 0.0;
        for (int k = 0; k < 3; ++k) e2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
        if (!(e2 > 0.0) || !isfinite(e2)) e2 = 1.0;
    }

    const uint32_t total = 2 * n - 1;
    hac h;
    memset(&h, 0, sizeof h);
    glow__node *nodes = NULL;
    uint32_t *map = NULL, *stack = NULL, *dfs_internal = NULL, *level = NULL, *level_start = NULL;
    glow__surfel *sorted = NULL;
    glow_result res = GLOW_OK;

    if (n > 1) {
        const double cb = hac_balance(n);
        res = n > chunk_from && n > chunk
                  ? hac_run_chunked(&h, surfels, 1.0 / e2, cb, rt, (float)(1e-4 * sqrt(e2)), chunk, pool, log)
                  : hac_run(&h, surfels, 1.0 / e2, cb, rt, (float)(1e-4 * sqrt(e2)), pool);
        if (res != GLOW_OK) {
            if (res == GLOW_ERROR_OUT_OF_MEMORY) glow__errorf(log, "hierarchy: out of memory clustering %u surfels", n);
            else glow__errorf(log, "hierarchy: clustering of %u surfels stopped early", n);
            goto fail;
        }
    } else {
        h.c = calloc(1, sizeof *h.c);
        if (!h.c) { res = GLOW_ERROR_OUT_OF_MEMORY; glow__errorf(log, "hierarchy: out of memory"); goto fail; }
        h.c[0].child[0] = h.c[0].child[1] = NONE;
        h.c[0].area = surfels->s[0].area;
        for (int k = 0; k < 3; ++k) {
            h.c[0].pos[k] = surfels->s[0].pos[k];
            h.c[0].nsum[k] = surfels->s[0].area * surfels->s[0].nrm[k];
        }
        set_mean_normal(&h.c[0]);
        h.cluster_count = 1;
    }

    nodes = calloc(total, sizeof *nodes);
    map = malloc((size_t)total * sizeof *map);
    stack = malloc((size_t)total * sizeof *stack);
    dfs_internal = malloc((size_t)n * sizeof *dfs_internal);
    level = calloc(total, sizeof *level);
    sorted = malloc((size_t)n * sizeof *sorted);
    if (!nodes || !map || !stack || !dfs_internal || !level || !sorted) {
        res = GLOW_ERROR_OUT_OF_MEMORY;
        glow__errorf(log, "hierarchy: out of memory for %u nodes", total);
        goto fail;
    }

    /* levels: children are created before parents, so one pass in creation order */
    uint32_t max_level = 0;
    for (uint32_t i = n; i < total; ++i) {
        uint32_t l0 = level[h.c[i].child[0]], l1 = level[h.c[i].child[1]];
        level[i] = 1 + (l0 > l1 ? l0 : l1);
        if (level[i] > max_level) max_level = level[i];
    }
    level_start = calloc((size_t)max_level + 2, sizeof *level_start);
    if (!level_start) {
        res = GLOW_ERROR_OUT_OF_MEMORY;
        glow__errorf(log, "hierarchy: out of memory for %u levels", max_level + 1);
        goto fail;
    }

    /* depth-first traversal from the root, first child first: leaf order and internal DFS order */
    uint32_t sp = 0, leaf_pos = 0, internal_pos = 0;
    stack[sp++] = total - 1;
    while (sp > 0) {
        uint32_t ci = stack[--sp];
        if (ci < n) {
            map[ci] = leaf_pos++;
            continue;
        }
        dfs_internal[internal_pos++] = ci;
        stack[sp++] = h.c[ci].child[1];
        stack[sp++] = h.c[ci].child[0];
    }
    /* internal nodes by (level, DFS order): counting sort, stable in DFS order */
    uint32_t *count = level_start; /* level_start[k + 1] counts level k first */
    for (uint32_t k = 0; k < internal_pos; ++k) count[level[dfs_internal[k]] + 1]++;
    count[1] = n; /* level 0: the leaves */
    level_start[0] = 0;
    for (uint32_t k = 1; k <= max_level + 1; ++k) level_start[k] += level_start[k - 1];
    /* level_start[k] now = first node of level k; use a running cursor per level */
    {
        uint32_t *cursor = stack; /* reuse: max_level + 1 <= total entries */
        for (uint32_t k = 0; k <= max_level; ++k) cursor[k] = level_start[k];
        for (uint32_t k = 0; k < internal_pos; ++k) {
            uint32_t ci = dfs_internal[k];
            map[ci] = cursor[level[ci]]++;
        }
    }

    /* fill the nodes */
    for (uint32_t ci = 0; ci < total; ++ci) {
        glow__node *nd = &nodes[map[ci]];
        nd->level = level[ci];
        nd->parent = GLOW_NODE_NONE;
        if (ci < n) {
            const glow__surfel *s = &surfels->s[ci];
            nd->child[0] = nd->child[1] = GLOW_NODE_NONE;
            memcpy(nd->pos, s->pos, sizeof nd->pos);
            memcpy(nd->nrm, s->nrm, sizeof nd->nrm);
            nd->area = s->area;
        } else {
            const cluster *c = &h.c[ci];
            nd->child[0] = map[c->child[0]];
            nd->child[1] = map[c->child[1]];
            for (int k = 0; k < 3; ++k) {
                nd->pos[k] = (float)c->pos[k];
                nd->nrm[k] = (float)c->m[k];
            }
            nd->area = (float)c->area;
        }
    }
    for (uint32_t ni = n; ni < total; ++ni) {
        nodes[nodes[ni].child[0]].parent = ni;
        nodes[nodes[ni].child[1]].parent = ni;
    }

    /* reorder the surfels into leaf order */
    for (uint32_t i = 0; i < n; ++i) sorted[map[i]] = surfels->s[i];
    memcpy(surfels->s, sorted, (size_t)n * sizeof *sorted);

    out->leaf_count = n;
    out->node_count = total;
    out->nodes = nodes;
    out->level_count = max_level + 1;
    out->level_start = level_start;
    nodes = NULL;
    level_start = NULL;

fail:
    hac_free(&h);
    free(nodes);
    free(map);
    free(stack);
    free(dfs_internal);
    free(level);
    free(level_start);
    free(sorted);
    return res;
}

void glow__hierarchy_free(glow__hierarchy *h) {
    if (!h) return;
    free(h->nodes);
    free(h->level_start);
    memset(h, 0, sizeof *h);
}
