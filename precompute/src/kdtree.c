/* kdtree.c — static 3-d tree over points for k-nearest-neighbour queries.
 *
 * Built once over a point set (median split on the widest axis of each node's bounding box, leaf
 * buckets of at most LEAF_SIZE points), then queried read-only: any number of threads may call
 * glow__kdtree_knn on the same tree at once. Results are ordered by (squared distance, index), so
 * equal distances are broken by the smaller index and a query's answer does not depend on the tree's
 * traversal order. Used by surfel relaxation (surfels.c) and by other modules (cache placement). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pc_internal.h"

#define LEAF_SIZE 8u
#define NO_CHILD UINT32_MAX
#define MAX_DEPTH 96

typedef struct kd_node {
    float lo[3], hi[3];   /* bounding box of the node's points */
    uint32_t begin, end;  /* range in the permuted point array */
    uint32_t left, right; /* NO_CHILD for leaves */
    uint32_t min_index;   /* smallest original index in the node (ties at equal distance) */
} kd_node;

struct glow__kdtree {
    uint32_t count;
    float (*pts)[3];      /* points in tree order */
    uint32_t *index;      /* original index of each point in tree order */
    kd_node *nodes;
    uint32_t node_count, node_cap;
};

/* (coordinate, index) ordering: a strict total order (NaN sorts as +infinity), so selection is
 * deterministic and the partition scans always stop. */
static int less_on_axis(const float (*points)[3], uint32_t a, uint32_t b, int axis) {
    float ca = points[a][axis], cb = points[b][axis];
    if (isnan(ca)) ca = INFINITY;
    if (isnan(cb)) cb = INFINITY;
    if (ca < cb) return 1;
    if (ca > cb) return 0;
    return a < b;
}

/* Quickselect: afterwards idx[k] is the element of rank k and everything before it ranks lower. */
static void select_kth(const float (*points)[3], uint32_t *idx, uint32_t n, uint32_t k, int axis) {
    uint32_t lo = 0, hi = n - 1;
    while (hi > lo) {
        /* median of three as pivot */
        uint32_t mid = lo + (hi - lo) / 2;
        if (less_on_axis(points, idx[mid], idx[lo], axis)) { uint32_t t = idx[mid]; idx[mid] = idx[lo]; idx[lo] = t; }
        if (less_on_axis(points, idx[hi], idx[lo], axis)) { uint32_t t = idx[hi]; idx[hi] = idx[lo]; idx[lo] = t; }
        if (less_on_axis(points, idx[hi], idx[mid], axis)) { uint32_t t = idx[hi]; idx[hi] = idx[mid]; idx[mid] = t; }
        uint32_t pivot = idx[mid];
        /* Hoare partition around the pivot value */
        uint32_t i = lo, j = hi;
        for (;;) {
            while (less_on_axis(points, idx[i], pivot, axis)) ++i;
            while (less_on_axis(points, pivot, idx[j], axis)) --j;
            if (i >= j) break;
            uint32_t t = idx[i]; idx[i] = idx[j]; idx[j] = t;
            ++i;
            --j;
        }
        /* now [lo, j] <= pivot <= [j+1, hi] */
        if (k <= j) hi = j;
        else lo = j + 1;
    }
}

static uint32_t new_node(glow__kdtree *t) {
    if (t->node_count == t->node_cap) return NO_CHILD; /* capacity is computed up front */
    return t->node_count++;
}

static uint32_t build_rec(glow__kdtree *t, const float (*points)[3], uint32_t begin, uint32_t end, int depth) {
    uint32_t ni = new_node(t);
    if (ni == NO_CHILD) return NO_CHILD;
    kd_node *nd = &t->nodes[ni];
    nd->begin = begin;
    nd->end = end;
    nd->left = nd->right = NO_CHILD;
    nd->min_index = UINT32_MAX;
    for (int a = 0; a < 3; ++a) { nd->lo[a] = FLT_MAX; nd->hi[a] = -FLT_MAX; }
    for (uint32_t i = begin; i < end; ++i) {
        if (t->index[i] < nd->min_index) nd->min_index = t->index[i];
        const float *p = points[t->index[i]];
        for (int a = 0; a < 3; ++a) {
            if (p[a] < nd->lo[a]) nd->lo[a] = p[a];
            if (p[a] > nd->hi[a]) nd->hi[a] = p[a];
        }
    }
    if (end - begin <= LEAF_SIZE || depth >= MAX_DEPTH) return ni;
    int axis = 0;
    float ext = nd->hi[0] - nd->lo[0];
    for (int a = 1; a < 3; ++a)
        if (nd->hi[a] - nd->lo[a] > ext) { ext = nd->hi[a] - nd->lo[a]; axis = a; }
    uint32_t n = end - begin, half = n / 2;
    select_kth(points, t->index + begin, n, half, axis);
    uint32_t l = build_rec(t, points, begin, begin + half, depth + 1);
    uint32_t r = build_rec(t, points, begin + half, end, depth + 1);
    t->nodes[ni].left = l;
    t->nodes[ni].right = r;
    return ni;
}

glow__kdtree *glow__kdtree_build(const float (*points)[3], uint32_t count) {
    glow__kdtree *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    t->count = count;
    if (count == 0) return t;
    /* median splits of n > LEAF_SIZE points: leaves hold > LEAF_SIZE/2 points -> < 2n/(LEAF_SIZE/2) + 1 nodes */
    t->node_cap = 2u * (count / (LEAF_SIZE / 2u) + 1u) + 1u;
    t->nodes = malloc((size_t)t->node_cap * sizeof *t->nodes);
    t->index = malloc((size_t)count * sizeof *t->index);
    t->pts = malloc((size_t)count * sizeof *t->pts);
    if (!t->nodes || !t->index || !t->pts) {
        glow__kdtree_free(t);
        return NULL;
    }
    for (uint32_t i = 0; i < count; ++i) t->index[i] = i;
    if (build_rec(t, points, 0, count, 0) == NO_CHILD) { /* cannot happen: capacity bound above */
        glow__kdtree_free(t);
        return NULL;
    }
    for (uint32_t i = 0; i < count; ++i) memcpy(t->pts[i], points[t->index[i]], sizeof t->pts[i]);
    return t;
}

void glow__kdtree_free(glow__kdtree *tree) {
    if (!tree) return;
    free(tree->nodes);
    free(tree->index);
    free(tree->pts);
    free(tree);
}

static float box_dist2(const kd_node *nd, const float q[3]) {
    float d2 = 0.0f;
    for (int a = 0; a < 3; ++a) {
        float d = 0.0f;
        if (q[a] < nd->lo[a]) d = nd->lo[a] - q[a];
        else if (q[a] > nd->hi[a]) d = q[a] - nd->hi[a];
        d2 += d * d;
    }
    return d2;
}

/* (d2, index) lexicographic: true when a ranks before b */
static int before(float da, uint32_t ia, float db, uint32_t ib) { return da < db || (da == db && ia < ib); }

/* a candidate into the sorted list of the k best so far (the tree's and the grid's queries) */
static void offer(float d2, uint32_t id, uint32_t k, uint32_t *found, uint32_t *out_index, float *out_dist2) {
    if (*found == k && !before(d2, id, out_dist2[k - 1], out_index[k - 1])) return;
    uint32_t j = *found < k ? (*found)++ : k - 1;
    while (j > 0 && before(d2, id, out_dist2[j - 1], out_index[j - 1])) {
        out_dist2[j] = out_dist2[j - 1];
        out_index[j] = out_index[j - 1];
        --j;
    }
    out_dist2[j] = d2;
    out_index[j] = id;
}

uint32_t glow__kdtree_knn(const glow__kdtree *tree, const float q[3], uint32_t k, uint32_t exclude,
                          uint32_t *out_index, float *out_dist2) {
    return glow__kdtree_knn_within(tree, q, k, exclude, INFINITY, out_index, out_dist2);
}

uint32_t glow__kdtree_knn_within(const glow__kdtree *tree, const float q[3], uint32_t k, uint32_t exclude,
                                 float max_dist2, uint32_t *out_index, float *out_dist2) {
    if (!tree || tree->count == 0 || k == 0) return 0;
    uint32_t found = 0;
    struct { uint32_t node; float d2; } stack[MAX_DEPTH + 4];
    int sp = 0;
    stack[sp].node = 0;
    stack[sp].d2 = box_dist2(&tree->nodes[0], q);
    ++sp;
    while (sp > 0) {
        --sp;
        uint32_t ni = stack[sp].node;
        const kd_node *nd = &tree->nodes[ni];
        if (stack[sp].d2 > max_dist2) continue; /* wholly beyond the radius */
        /* prune: a box that cannot hold a point ranking before the current k-th candidate (equal
         * distance still wins on a smaller index; min_index keeps masses of coincident points cheap) */
        if (found == k && !before(stack[sp].d2, nd->min_index, out_dist2[k - 1], out_index[k - 1])) continue;
        if (nd->left == NO_CHILD) {
            for (uint32_t i = nd->begin; i < nd->end; ++i) {
                uint32_t id = tree->index[i];
                if (id == exclude) continue;
                const float *p = tree->pts[i];
                float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
                float d2 = dx * dx + dy * dy + dz * dz;
                if (d2 > max_dist2) continue;
                offer(d2, id, k, &found, out_index, out_dist2);
            }
            continue;
        }
        float dl = box_dist2(&tree->nodes[nd->left], q);
        float dr = box_dist2(&tree->nodes[nd->right], q);
        /* push the farther child first so the nearer one is searched first */
        if (dl <= dr) {
            stack[sp].node = nd->right; stack[sp].d2 = dr; ++sp;
            stack[sp].node = nd->left; stack[sp].d2 = dl; ++sp;
        } else {
            stack[sp].node = nd->left; stack[sp].d2 = dl; ++sp;
            stack[sp].node = nd->right; stack[sp].d2 = dr; ++sp;
        }
    }
    return found;
}

/* ------------------------------------------------------------------ uniform grid (glow__pointgrid)
 * Points binned into cubic cells of side h over a box that holds every point and every query; a
 * query scans rings of cells (Chebyshev distance r = 0, 1, 2, ... from its own cell) and stops once
 * k candidates are held and the k-th lies nearer than any cell not yet scanned can be, (r - margin) h.
 * Candidates are ranked by (squared distance, index) exactly as the tree ranks them, from the same
 * float arithmetic, so both give the same answer. For queries that come by the million (the surfels'
 * Voronoi areas): on surface points with h about two spacings a query reads ~27 cells and ~52
 * points instead of descending a tree (Sponza's 524,288 surfels, 32 queries each, k = 8). Rings 0
 * and 1 go first as 9 rows of 3 cells, each row's points one run (a row's cells are consecutive),
 * the rows nearest the query first, and a point is offered only when it beats the k-th: 25 % less
 * time than cell by cell in grid order (9.4 s to 7.0 s a thread for those 16.8M queries). */
struct glow__pointgrid {
    float lo[3], h, inv_h;
    int32_t dim[3];
    uint32_t *start;  /* [cells + 1] first point of each cell (x fastest) */
    uint32_t *index;  /* original index of each point, by cell */
    float (*pts)[3];  /* the points, by cell */
};

static int32_t grid_coord(const glow__pointgrid *g, const float p[3], int a) {
    const float f = floorf((p[a] - g->lo[a]) * g->inv_h);
    if (!(f >= 0.0f)) return 0; /* below, or NaN */
    return f >= (float)g->dim[a] ? g->dim[a] - 1 : (int32_t)f;
}

/* cells of side h over [lo, hi] plus one spare a side (at most 65536 an axis, clamped into the last);
 * returns how many */
static double grid_dims(glow__pointgrid *g, const float lo[3], const float hi[3], float h) {
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) {
        const double ext = (double)hi[a] - lo[a];
        const double d = ext > 0.0 ? ceil(ext / h) + 1.0 : 1.0;
        g->dim[a] = !(d >= 1.0) ? 1 : (d > 65536.0 ? 65536 : (int32_t)d);
        cells *= g->dim[a];
    }
    return cells;
}

glow__pointgrid *glow__pointgrid_build(const float (*points)[3], uint32_t count, const float lo[3], const float hi[3],
                                       float cell) {
    glow__pointgrid *g = calloc(1, sizeof *g);
    if (!g) return NULL;
    /* no more than 8 cells a point (plus a floor for tiny sets): a coarser cell keeps it exact */
    float h = cell > 0.0f ? cell : 1.0f;
    const double cap = 8.0 * (double)count + 4096.0;
    double cells = grid_dims(g, lo, hi, h);
    while (cells > cap) {
        h *= 1.25f;
        cells = grid_dims(g, lo, hi, h);
    }
    memcpy(g->lo, lo, sizeof g->lo);
    g->h = h;
    g->inv_h = 1.0f / h;
    const size_t nc = (size_t)cells;
    g->start = calloc(nc + 1, sizeof *g->start);
    g->index = malloc(((size_t)count + 1) * sizeof *g->index);
    g->pts = malloc(((size_t)count + 1) * sizeof *g->pts);
    uint32_t *cell_of = malloc(((size_t)count + 1) * sizeof *cell_of);
    if (!g->start || !g->index || !g->pts || !cell_of) {
        free(cell_of);
        glow__pointgrid_free(g);
        return NULL;
    }
    for (uint32_t i = 0; i < count; ++i) {
        const int32_t x = grid_coord(g, points[i], 0), y = grid_coord(g, points[i], 1), z = grid_coord(g, points[i], 2);
        cell_of[i] = (uint32_t)(((size_t)z * g->dim[1] + y) * g->dim[0] + x);
        g->start[cell_of[i] + 1]++;
    }
    for (size_t c = 0; c < nc; ++c) g->start[c + 1] += g->start[c];
    for (uint32_t i = 0; i < count; ++i) { /* in index order within a cell */
        const uint32_t at = g->start[cell_of[i]]++;
        g->index[at] = i;
        memcpy(g->pts[at], points[i], sizeof g->pts[at]);
    }
    for (size_t c = nc; c > 0; --c) g->start[c] = g->start[c - 1]; /* undo the advance */
    g->start[0] = 0;
    free(cell_of);
    return g;
}

void glow__pointgrid_free(glow__pointgrid *g) {
    if (!g) return;
    free(g->start);
    free(g->index);
    free(g->pts);
    free(g);
}

/* how far q (on axis a) lies from slab i of the cells on that axis, the slab grown by a tenth of a side
 * against binning's rounding; 0 beyond a border slab, which holds the points outside the box */
static inline float axis_gap(const glow__pointgrid *g, int a, int32_t i, float q) {
    const float lo = g->lo[a] + ((float)i - 0.1f) * g->h, hi = g->lo[a] + ((float)i + 1.1f) * g->h;
    if (q < lo) return i > 0 ? lo - q : 0.0f;
    if (q > hi) return i < g->dim[a] - 1 ? q - hi : 0.0f;
    return 0.0f;
}

/* the points [i0, i1) of the grid's order (a row's consecutive cells are consecutive) */
static void grid_span(const glow__pointgrid *g, uint32_t i0, uint32_t i1, const float q[3], uint32_t k,
                      uint32_t exclude, float limit, uint32_t *found, uint32_t *out_index, float *out_dist2) {
    float worst = *found == k ? out_dist2[k - 1] : limit; /* nothing beyond the limit is offered */
    for (uint32_t i = i0; i < i1; ++i) {
        const float *p = g->pts[i];
        const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
        const float d2 = dx * dx + dy * dy + dz * dz;
        if (d2 > worst) continue;
        const uint32_t id = g->index[i];
        if (id == exclude) continue;
        offer(d2, id, k, found, out_index, out_dist2);
        if (*found == k) worst = out_dist2[k - 1];
    }
}

/* How far q lies inside the block of rings 0 .. r - 1 around its cell c: every point outside that block
 * is at least this far away (a point outside the box is binned into a border cell, which only brings
 * it nearer), less a tenth of a cell for binning's rounding. INFINITY when the block reaches every
 * cell. */
static float block_bound(const glow__pointgrid *g, const int32_t c[3], const float q[3], int32_t r) {
    float bound = INFINITY;
    for (int a = 0; a < 3; ++a) {
        if (c[a] - (r - 1) > 0) {
            const float d = q[a] - (g->lo[a] + (float)(c[a] - (r - 1)) * g->h);
            bound = d < bound ? d : bound;
        }
        if (c[a] + (r - 1) < g->dim[a] - 1) {
            const float d = g->lo[a] + (float)(c[a] + r) * g->h - q[a];
            bound = d < bound ? d : bound;
        }
    }
    return bound == INFINITY ? bound : bound - 0.1f * g->h;
}

/* The smallest (d2, index) among the points [i0, i1) and (*bd, *bi): the squared distances of up to 64
 * points at a time first (a running minimum without branches), then the smallest index among those at
 * the minimum, from the same stored values. */
static void nearest_span(const glow__pointgrid *g, uint32_t i0, uint32_t i1, const float q[3], float *bd,
                         uint32_t *bi) {
    float d2[64];
    for (uint32_t b = i0; b < i1; b += 64) {
        const uint32_t e = i1 - b < 64 ? i1 - b : 64;
        float m = INFINITY;
        for (uint32_t i = 0; i < e; ++i) {
            const float *p = g->pts[b + i];
            const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
            d2[i] = dx * dx + dy * dy + dz * dz;
            m = d2[i] < m ? d2[i] : m;
        }
        if (!(m <= *bd)) continue;
        uint32_t best = m == *bd ? *bi : UINT32_MAX;
        for (uint32_t i = 0; i < e; ++i)
            if (d2[i] == m && g->index[b + i] < best) best = g->index[b + i];
        *bd = m;
        *bi = best;
    }
}

uint32_t glow__pointgrid_nearest(const glow__pointgrid *g, const float q[3], float *out_dist2) {
    *out_dist2 = INFINITY;
    if (!g) return UINT32_MAX;
    const int32_t c[3] = {grid_coord(g, q, 0), grid_coord(g, q, 1), grid_coord(g, q, 2)};
    const int32_t z0 = c[2] - 1 < 0 ? 0 : c[2] - 1, z1 = c[2] + 1 >= g->dim[2] ? g->dim[2] - 1 : c[2] + 1;
    const int32_t y0 = c[1] - 1 < 0 ? 0 : c[1] - 1, y1 = c[1] + 1 >= g->dim[1] ? g->dim[1] - 1 : c[1] + 1;
    const int32_t x0 = c[0] - 1 < 0 ? 0 : c[0] - 1, x1 = c[0] + 1 >= g->dim[0] ? g->dim[0] - 1 : c[0] + 1;
    float bd = INFINITY;
    uint32_t bi = UINT32_MAX;
    /* rings 0 and 1: q's own row of 3 cells, then the 8 rows around it that can hold a nearer point */
    size_t row = ((size_t)c[2] * g->dim[1] + c[1]) * g->dim[0];
    nearest_span(g, g->start[row + x0], g->start[row + x1 + 1], q, &bd, &bi);
    float gy[3];
    for (int32_t y = y0; y <= y1; ++y) gy[y - y0] = axis_gap(g, 1, y, q[1]);
    for (int32_t z = z0; z <= z1; ++z) {
        const float dz = axis_gap(g, 2, z, q[2]);
        for (int32_t y = y0; y <= y1; ++y) {
            if (z == c[2] && y == c[1]) continue;
            const float dy = gy[y - y0];
            if (dz * dz + dy * dy > bd) continue;
            row = ((size_t)z * g->dim[1] + y) * g->dim[0];
            nearest_span(g, g->start[row + x0], g->start[row + x1 + 1], q, &bd, &bi);
        }
    }
    /* every other point lies beyond a face of that block */
    const float bound = block_bound(g, c, q, 2);
    if (bound == INFINITY || (bi != UINT32_MAX && bound > 0.0f && bd < bound * bound)) {
        *out_dist2 = bd;
        return bi;
    }
    /* a point farther out may be nearer: the rings' search */
    uint32_t id = UINT32_MAX;
    return glow__pointgrid_knn_within(g, q, 1, UINT32_MAX, INFINITY, &id, out_dist2) ? id : UINT32_MAX;
}

uint32_t glow__pointgrid_knn(const glow__pointgrid *g, const float q[3], uint32_t k, uint32_t exclude,
                             uint32_t *out_index, float *out_dist2) {
    return glow__pointgrid_knn_within(g, q, k, exclude, INFINITY, out_index, out_dist2);
}

uint32_t glow__pointgrid_knn_within(const glow__pointgrid *g, const float q[3], uint32_t k, uint32_t exclude,
                                    float max_dist2, uint32_t *out_index, float *out_dist2) {
    if (!g || k == 0) return 0;
    const int32_t c[3] = {grid_coord(g, q, 0), grid_coord(g, q, 1), grid_coord(g, q, 2)};
    int32_t rmax = 0; /* the ring that reaches every cell */
    for (int a = 0; a < 3; ++a) {
        const int32_t far = c[a] > g->dim[a] - 1 - c[a] ? c[a] : g->dim[a] - 1 - c[a];
        rmax = far > rmax ? far : rmax;
    }
    uint32_t found = 0;
    { /* rings 0 and 1 first, as one block of up to 9 rows of 3 cells (consecutive in the grid's order), the
       * rows nearest q first: their points set the k-th distance early, so that fewer of the others' are
       * offered, and a row farther than the k-th is not read */
        const int32_t z0 = c[2] - 1 < 0 ? 0 : c[2] - 1, z1 = c[2] + 1 >= g->dim[2] ? g->dim[2] - 1 : c[2] + 1;
        const int32_t y0 = c[1] - 1 < 0 ? 0 : c[1] - 1, y1 = c[1] + 1 >= g->dim[1] ? g->dim[1] - 1 : c[1] + 1;
        const int32_t x0 = c[0] - 1 < 0 ? 0 : c[0] - 1, x1 = c[0] + 1 >= g->dim[0] ? g->dim[0] - 1 : c[0] + 1;
        struct { float d2; uint32_t i0, i1; } rows[9];
        int nr = 0;
        for (int32_t z = z0; z <= z1; ++z) {
            const float dz = axis_gap(g, 2, z, q[2]);
            for (int32_t y = y0; y <= y1; ++y) {
                const float dy = axis_gap(g, 1, y, q[1]), d2 = dz * dz + dy * dy;
                const size_t row = ((size_t)z * g->dim[1] + y) * g->dim[0];
                int j = nr++;
                for (; j > 0 && rows[j - 1].d2 > d2; --j) rows[j] = rows[j - 1];
                rows[j].d2 = d2;
                rows[j].i0 = g->start[row + x0];
                rows[j].i1 = g->start[row + x1 + 1];
            }
        }
        for (int j = 0; j < nr; ++j) {
            if ((found == k && rows[j].d2 > out_dist2[k - 1]) || rows[j].d2 > max_dist2) break;
            grid_span(g, rows[j].i0, rows[j].i1, q, k, exclude, max_dist2, &found, out_index, out_dist2);
        }
    }
    for (int32_t r = 2; r <= rmax; ++r) {
        /* rings 0 .. r - 1 are scanned, a block of cells around q's: every other point lies beyond
         * one of its faces (or in no cell: a point outside the box is binned into a border cell, which
         * only brings it nearer). A tenth of a cell covers binning's rounding. Done when the k-th
         * found, or the radius, is nearer than that. */
        if (found == k || max_dist2 < INFINITY) {
            const float bound = block_bound(g, c, q, r);
            if (bound > 0.0f && found == k && out_dist2[k - 1] < bound * bound) break;
            if (bound > 0.0f && max_dist2 < bound * bound) break;
        }
        const int32_t z0 = c[2] - r < 0 ? 0 : c[2] - r, z1 = c[2] + r >= g->dim[2] ? g->dim[2] - 1 : c[2] + r;
        const int32_t y0 = c[1] - r < 0 ? 0 : c[1] - r, y1 = c[1] + r >= g->dim[1] ? g->dim[1] - 1 : c[1] + r;
        const int32_t x0 = c[0] - r < 0 ? 0 : c[0] - r, x1 = c[0] + r >= g->dim[0] ? g->dim[0] - 1 : c[0] + r;
        for (int32_t z = z0; z <= z1; ++z)
            for (int32_t y = y0; y <= y1; ++y) {
                const size_t row = ((size_t)z * g->dim[1] + y) * g->dim[0];
                if (z == c[2] - r || z == c[2] + r || y == c[1] - r || y == c[1] + r) {
                    grid_span(g, g->start[row + x0], g->start[row + x1 + 1], q, k, exclude, max_dist2, &found, out_index, out_dist2);
                } else { /* inside the ring's y-z cross only its two x ends belong to it */
                    const size_t lo = row + (size_t)(c[0] - r), hi = row + (size_t)(c[0] + r);
                    if (c[0] - r >= 0) grid_span(g, g->start[lo], g->start[lo + 1], q, k, exclude, max_dist2, &found, out_index, out_dist2);
                    if (c[0] + r < g->dim[0])
                        grid_span(g, g->start[hi], g->start[hi + 1], q, k, exclude, max_dist2, &found, out_index, out_dist2);
                }
            }
    }
    return found;
}
