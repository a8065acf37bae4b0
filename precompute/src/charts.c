/* charts.c — Glow's own lightmap chart packer, for meshes without a second UV set (PIC 4.4 needs a
 * texel per surface element; DESIGN §2.3).
 *
 * Segmentation (glow__charts_segment), all serial and in triangle order, so deterministic:
 *   1. corners are welded by exact position (hash of the float bits, -0 == +0);
 *   2. two triangles are neighbours when they share an edge used in opposite directions (a
 *      consistently oriented manifold edge; non-manifold fans pair their first 8 users);
 *   3. charts grow breadth-first from the lowest unassigned triangle, taking neighbours whose
 *      geometric normal is within GLOW__CHART_MAX_ANGLE_DEG of the seed's; then (up to twice) the
 *      chart is regrown from its member whose normal is nearest the chart's mean normal, so that
 *      the seed sits in the middle of its chart rather than at an edge (fewer, rounder charts);
 *   4. a chart is projected onto the plane of its area-weighted mean normal. Projection may still
 *      fold (a spiral ramp, a triangle turned past 90° from the mean): every triangle is tested
 *      against the chart's earlier ones (separating axes, uniform grid) and a triangle that
 *      overlaps is evicted; it seeds or joins a later chart;
 *   5. the chart is rotated to its minimum-area bounding rectangle (rotating calipers over the
 *      convex hull's edges) and then to landscape (width >= height).
 * Packing (glow__charts_pack): every chart gets a texel footprint of ceil(extent*density + 0.1)
 * texels a side with the chart centred in it (so its conservative rasterisation stays inside the
 * footprint, even after the bake's unorm16 UV rounding); footprints are shelf-packed, tallest first,
 * `padding` texels apart and from the border, for several atlas widths; the smallest roughly
 * square atlas wins. Bilinear lookups inside a chart read at most one texel beyond its footprint,
 * so padding >= 2 keeps a chart's dilated gutter free of its neighbours' texels. Charts narrower than
 * a texel are first merged into shared one-texel footprints (see "small charts" below). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "charts.h"

#define NONE 0xFFFFFFFFu
#define PAIR_CAP 8u /* users of a non-manifold edge that are paired with each other */

/* ------------------------------------------------------------------ welding */
static uint32_t float_key(float f) {
    if (f == 0.0f) f = 0.0f; /* -0 welds with +0 */
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static uint64_t hash3(uint32_t a, uint32_t b, uint32_t c) {
    uint64_t h = (uint64_t)a * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)b * 0xC2B2AE3D27D4EB4Full + (h >> 29);
    h ^= (uint64_t)c * 0x165667B19E3779F9ull + (h >> 32);
    h ^= h >> 31;
    h *= 0x94D049BB133111EBull;
    return h ^ (h >> 29);
}

/* vid[corner] = the lowest corner index at the same position. */
static bool weld(const glow__scene *s, uint32_t *vid) {
    const size_t n3 = 3 * (size_t)s->tri_count;
    size_t cap = 16;
    while (cap < 2 * n3) cap <<= 1;
    uint32_t *table = malloc(cap * sizeof *table);
    if (!table) return false;
    memset(table, 0xFF, cap * sizeof *table);
    for (size_t i = 0; i < n3; ++i) {
        uint32_t k0 = float_key(s->pos[i][0]), k1 = float_key(s->pos[i][1]), k2 = float_key(s->pos[i][2]);
        size_t h = (size_t)hash3(k0, k1, k2) & (cap - 1);
        vid[i] = (uint32_t)i;
        for (;;) {
            uint32_t j = table[h];
            if (j == NONE) {
                table[h] = (uint32_t)i;
                break;
            }
            if (float_key(s->pos[j][0]) == k0 && float_key(s->pos[j][1]) == k1 && float_key(s->pos[j][2]) == k2) {
                vid[i] = vid[j];
                break;
            }
            h = (h + 1) & (cap - 1);
        }
    }
    free(table);
    return true;
}

/* ------------------------------------------------------------------ adjacency */
typedef struct half_edge {
    uint64_t key; /* (min vertex << 32) | max vertex; UINT64_MAX for a degenerate edge */
    uint32_t corner; /* 3*tri + k: the edge from corner k to corner k+1 */
} half_edge;

static int cmp_half_edge(const void *pa, const void *pb) {
    const half_edge *a = pa, *b = pb;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    return a->corner < b->corner ? -1 : (a->corner > b->corner);
}

/* CSR adjacency: neighbours of t are adj[adj_start[t] .. adj_start[t+1]). */
static bool build_adjacency(uint32_t tri_count, const uint32_t *vid, uint32_t **out_start, uint32_t **out_adj) {
    const size_t n3 = 3 * (size_t)tri_count;
    half_edge *he = malloc(n3 * sizeof *he);
    uint32_t *start = calloc((size_t)tri_count + 1, sizeof *start);
    if (!he || !start) {
        free(he);
        free(start);
        return false;
    }
    for (size_t c = 0; c < n3; ++c) {
        size_t t = c / 3, k = c % 3;
        uint32_t a = vid[c], b = vid[3 * t + (k + 1) % 3];
        he[c].corner = (uint32_t)c;
        he[c].key = a == b ? UINT64_MAX : ((uint64_t)(a < b ? a : b) << 32) | (a < b ? b : a);
    }
    qsort(he, n3, sizeof *he, cmp_half_edge);
    /* Two passes over the same pairs: count, then fill. */
    uint32_t *adj = NULL;
    for (int pass = 0; pass < 2; ++pass) {
        uint32_t *fill = NULL;
        if (pass == 1) {
            for (uint32_t t = 0; t < tri_count; ++t) start[t + 1] += start[t];
            adj = malloc(((size_t)start[tri_count] + 1) * sizeof *adj);
            fill = malloc(((size_t)tri_count + 1) * sizeof *fill);
            if (!adj || !fill) {
                free(adj);
                free(fill);
                free(he);
                free(start);
                return false;
            }
            memcpy(fill, start, (size_t)tri_count * sizeof *fill);
        }
        size_t g = 0;
        while (g < n3) {
            size_t e = g + 1;
            while (e < n3 && he[e].key == he[g].key) ++e;
            if (he[g].key != UINT64_MAX) {
                size_t lim = e - g > PAIR_CAP ? g + PAIR_CAP : e;
                for (size_t i = g; i < lim; ++i)
                    for (size_t j = i + 1; j < lim; ++j) {
                        uint32_t ca = he[i].corner, cb = he[j].corner;
                        uint32_t ta = ca / 3, tb = cb / 3;
                        if (ta == tb || vid[ca] == vid[cb]) continue; /* same triangle or same direction */
                        if (pass == 0) {
                            start[ta + 1]++;
                            start[tb + 1]++;
                        } else {
                            adj[fill[ta]++] = tb;
                            adj[fill[tb]++] = ta;
                        }
                    }
            }
            g = e;
        }
        free(fill);
    }
    free(he);
    *out_start = start;
    *out_adj = adj;
    return true;
}

/* ------------------------------------------------------------------ 2-D geometry */
typedef struct vec2 {
    double x, y;
} vec2;

static double cross2(vec2 o, vec2 a, vec2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/* Interiors of two triangles overlap by more than eps (absolute length) along every separating
 * axis candidate (the six edge normals). Triangles that only share an edge or a vertex do not. */
static bool tri_overlap(const double (*a)[2], const double (*b)[2], double eps) {
    for (int s = 0; s < 2; ++s) {
        const double(*t)[2] = s ? b : a;
        for (int k = 0; k < 3; ++k) {
            double ax = t[(k + 1) % 3][1] - t[k][1], ay = t[k][0] - t[(k + 1) % 3][0];
            double len = sqrt(ax * ax + ay * ay);
            if (!(len > 0.0)) continue;
            double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
            for (int i = 0; i < 3; ++i) {
                double pa = a[i][0] * ax + a[i][1] * ay, pb = b[i][0] * ax + b[i][1] * ay;
                amin = fmin(amin, pa);
                amax = fmax(amax, pa);
                bmin = fmin(bmin, pb);
                bmax = fmax(bmax, pb);
            }
            double ov = fmin(amax, bmax) - fmax(amin, bmin);
            if (ov <= eps * len) return false;
        }
    }
    return true;
}

static int cmp_vec2(const void *pa, const void *pb) {
    const vec2 *a = pa, *b = pb;
    if (a->x != b->x) return a->x < b->x ? -1 : 1;
    if (a->y != b->y) return a->y < b->y ? -1 : 1;
    return 0;
}

/* Andrew's monotone chain; pts is sorted in place; hull gets at most n + 1 points (CCW). */
static uint32_t convex_hull(vec2 *pts, uint32_t n, vec2 *hull) {
    qsort(pts, n, sizeof *pts, cmp_vec2);
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; ++i) {
        while (k >= 2 && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0.0) --k;
        hull[k++] = pts[i];
    }
    for (uint32_t i = n - 1, lo = k + 1; i-- > 0;) {
        while (k >= lo && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0.0) --k;
        hull[k++] = pts[i];
    }
    return k > 1 ? k - 1 : k;
}

/* ------------------------------------------------------------------ segmentation */
typedef struct seg_ctx {
    const glow__scene *scene;
    double (*nrm)[3];     /* unit geometric normal per triangle (0 for degenerate) */
    double (*cr)[3];      /* (p1-p0)x(p2-p0) per triangle */
    uint32_t *chart_of;
    /* scratch for the overlap test */
    uint32_t *cell_head;
    size_t cell_cap;
    uint32_t *ent_tri, *ent_next;
    size_t ent_len, ent_cap;
    uint32_t *stamp;
    uint32_t query;
    vec2 *pts, *hull;
} seg_ctx;

static bool ent_push(seg_ctx *c, uint32_t tri, uint32_t next) {
    if (c->ent_len == c->ent_cap) {
        size_t cap = c->ent_cap ? 2 * c->ent_cap : 1024;
        uint32_t *a = realloc(c->ent_tri, cap * sizeof *a);
        if (!a) return false;
        c->ent_tri = a;
        uint32_t *b = realloc(c->ent_next, cap * sizeof *b);
        if (!b) return false;
        c->ent_next = b;
        c->ent_cap = cap;
    }
    c->ent_tri[c->ent_len] = tri;
    c->ent_next[c->ent_len] = next;
    c->ent_len++;
    return true;
}

/* Projects chart members [*m, m + count) onto their mean plane (xy), evicts overlapping triangles
 * (compacting the member list) and rotates to the minimum-area rectangle. Returns false on OOM. */
static bool finish_chart(seg_ctx *c, uint32_t *m, uint32_t *count, const double seed_nrm[3], double (*xy)[2],
                         double ext[2], uint32_t *evicted) {
    const glow__scene *s = c->scene;
    uint32_t n = *count;
    /* mean plane */
    double N[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) N[k] += c->cr[m[i]][k];
    double len = sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2]);
    if (len > 0.0) {
        for (int k = 0; k < 3; ++k) N[k] /= len;
    } else {
        memcpy(N, seed_nrm, sizeof N);
        if (!(fabs(N[0]) + fabs(N[1]) + fabs(N[2]) > 0.0)) N[2] = 1.0;
    }
    double T[3], B[3];
    glow__tangent_frame(N, T, B);
    const float *o = s->pos[3 * (size_t)m[0]];
    double bx0 = INFINITY, by0 = INFINITY, bx1 = -INFINITY, by1 = -INFINITY;
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const float *p = s->pos[3 * (size_t)m[i] + (size_t)k];
            double d[3] = {(double)p[0] - o[0], (double)p[1] - o[1], (double)p[2] - o[2]};
            double x = d[0] * T[0] + d[1] * T[1] + d[2] * T[2];
            double y = d[0] * B[0] + d[1] * B[1] + d[2] * B[2];
            xy[3 * (size_t)m[i] + (size_t)k][0] = x;
            xy[3 * (size_t)m[i] + (size_t)k][1] = y;
            bx0 = fmin(bx0, x);
            by0 = fmin(by0, y);
            bx1 = fmax(bx1, x);
            by1 = fmax(by1, y);
        }
    /* overlap test in a uniform grid over the chart, in member (BFS) order */
    double ex = bx1 - bx0, ey = by1 - by0, big = fmax(ex, ey);
    if (n > 1 && big > 0.0) {
        double eps = 1e-6 * big;
        double cs = sqrt(fmax(ex * ey, big * big * 1e-6) / n);
        if (cs < big / 1024.0) cs = big / 1024.0;
        size_t nx = (size_t)(ex / cs) + 1, ny = (size_t)(ey / cs) + 1;
        if (nx * ny > c->cell_cap) {
            free(c->cell_head);
            c->cell_cap = nx * ny;
            c->cell_head = malloc(c->cell_cap * sizeof *c->cell_head);
            if (!c->cell_head) return false;
        }
        memset(c->cell_head, 0xFF, nx * ny * sizeof *c->cell_head);
        c->ent_len = 0;
        uint32_t kept = 0;
        for (uint32_t i = 0; i < n; ++i) {
            uint32_t t = m[i];
            const double(*tp)[2] = (const double(*)[2])(xy + 3 * (size_t)t);
            double tx0 = fmin(fmin(tp[0][0], tp[1][0]), tp[2][0]), tx1 = fmax(fmax(tp[0][0], tp[1][0]), tp[2][0]);
            double ty0 = fmin(fmin(tp[0][1], tp[1][1]), tp[2][1]), ty1 = fmax(fmax(tp[0][1], tp[1][1]), tp[2][1]);
            size_t cx0 = (size_t)((tx0 - bx0) / cs), cx1 = (size_t)((tx1 - bx0) / cs);
            size_t cy0 = (size_t)((ty0 - by0) / cs), cy1 = (size_t)((ty1 - by0) / cs);
            if (cx1 >= nx) cx1 = nx - 1;
            if (cy1 >= ny) cy1 = ny - 1;
            if (cx0 > cx1) cx0 = cx1;
            if (cy0 > cy1) cy0 = cy1;
            bool overlap = false;
            uint32_t q = ++c->query;
            for (size_t cy = cy0; cy <= cy1 && !overlap; ++cy)
                for (size_t cx = cx0; cx <= cx1 && !overlap; ++cx)
                    for (uint32_t e = c->cell_head[cy * nx + cx]; e != NONE; e = c->ent_next[e]) {
                        uint32_t u = c->ent_tri[e];
                        if (c->stamp[u] == q) continue;
                        c->stamp[u] = q;
                        if (tri_overlap(tp, (const double(*)[2])(xy + 3 * (size_t)u), eps)) {
                            overlap = true;
                            break;
                        }
                    }
            if (overlap) {
                c->chart_of[t] = NONE;
                ++*evicted;
                continue;
            }
            for (size_t cy = cy0; cy <= cy1; ++cy)
                for (size_t cx = cx0; cx <= cx1; ++cx) {
                    if (!ent_push(c, t, c->cell_head[cy * nx + cx])) return false;
                    c->cell_head[cy * nx + cx] = (uint32_t)(c->ent_len - 1);
                }
            m[kept++] = t;
        }
        n = kept;
        *count = kept;
    }
    /* minimum-area rectangle over the hull edges */
    uint32_t np = 3 * n;
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            c->pts[3 * i + (uint32_t)k].x = xy[3 * (size_t)m[i] + (size_t)k][0];
            c->pts[3 * i + (uint32_t)k].y = xy[3 * (size_t)m[i] + (size_t)k][1];
        }
    uint32_t nh = convex_hull(c->pts, np, c->hull);
    double ux = 1.0, uy = 0.0, best = INFINITY;
    for (uint32_t i = 0; i + 1 < nh || (nh > 2 && i < nh); ++i) {
        vec2 p0 = c->hull[i], p1 = c->hull[(i + 1) % nh];
        double dx = p1.x - p0.x, dy = p1.y - p0.y, l = sqrt(dx * dx + dy * dy);
        if (!(l > 0.0)) continue;
        dx /= l;
        dy /= l;
        double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
        for (uint32_t j = 0; j < nh; ++j) {
            double pu = c->hull[j].x * dx + c->hull[j].y * dy, pv = -c->hull[j].x * dy + c->hull[j].y * dx;
            u0 = fmin(u0, pu);
            u1 = fmax(u1, pu);
            v0 = fmin(v0, pv);
            v1 = fmax(v1, pv);
        }
        double area = (u1 - u0) * (v1 - v0);
        if (area < best * (1.0 - 1e-9)) {
            best = area;
            ux = dx;
            uy = dy;
        }
    }
    double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            double *p = xy[3 * (size_t)m[i] + (size_t)k];
            double pu = p[0] * ux + p[1] * uy, pv = -p[0] * uy + p[1] * ux;
            p[0] = pu;
            p[1] = pv;
            u0 = fmin(u0, pu);
            u1 = fmax(u1, pu);
            v0 = fmin(v0, pv);
            v1 = fmax(v1, pv);
        }
    double w = u1 - u0, h = v1 - v0;
    bool turn = h > w;
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            double *p = xy[3 * (size_t)m[i] + (size_t)k];
            double x = p[0] - u0, y = p[1] - v0;
            if (turn) { /* rotate by -90 degrees: (x, y) -> (y, w - x) */
                p[0] = y;
                p[1] = w - x;
            } else {
                p[0] = x;
                p[1] = y;
            }
        }
    ext[0] = turn ? h : w;
    ext[1] = turn ? w : h;
    return true;
}

void glow__charts_free(glow__chart_set *cs) {
    if (!cs) return;
    free(cs->chart_start);
    free(cs->chart_tris);
    free(cs->xy);
    free(cs->extent);
    free(cs->normal);
    free(cs->centre);
    free(cs->scale);
    memset(cs, 0, sizeof *cs);
}

/* A wall standing on a chart's surface, seen from one blocked step t -> q: triangles whose centroid
 * lies on q's side of the midpoint (along s = t - q) and within `r2` of it are beyond it. */
typedef struct barrier {
    double m[3], s[3], r2;
} barrier;

static void tri_centroid(const glow__scene *sc, uint32_t t, double out[3]) {
    const float(*P)[3] = sc->pos + 3 * (size_t)t;
    for (int k = 0; k < 3; ++k) out[k] = ((double)P[0][k] + P[1][k] + P[2][k]) / 3.0;
}

static bool add_barrier(const seg_ctx *c, barrier **bar, uint32_t *nbar, uint32_t *cap, uint32_t t, uint32_t q) {
    if (*nbar == *cap) {
        uint32_t nc = *cap ? 2 * *cap : 16;
        barrier *nb = realloc(*bar, (size_t)nc * sizeof *nb);
        if (!nb) return false;
        *bar = nb;
        *cap = nc;
    }
    double a[3], b[3], d2 = 0.0;
    tri_centroid(c->scene, t, a);
    tri_centroid(c->scene, q, b);
    barrier *r = &(*bar)[(*nbar)++];
    for (int k = 0; k < 3; ++k) {
        r->m[k] = 0.5 * (a[k] + b[k]);
        r->s[k] = a[k] - b[k];
        d2 += r->s[k] * r->s[k];
    }
    r->r2 = 6.25 * d2; /* reach: 2.5 centroid spacings */
    return true;
}

static bool beyond_barrier(const seg_ctx *c, const barrier *bar, uint32_t nbar, uint32_t u) {
    if (!nbar) return false;
    double p[3];
    tri_centroid(c->scene, u, p);
    for (uint32_t i = 0; i < nbar; ++i) {
        const barrier *b = &bar[i];
        const double d[3] = {p[0] - b->m[0], p[1] - b->m[1], p[2] - b->m[2]};
        if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < b->r2 && d[0] * b->s[0] + d[1] * b->s[1] + d[2] * b->s[2] < 0.0)
            return true;
    }
    return false;
}

/* Is the step from triangle t to its coplanar neighbour u blocked by geometry standing on the surface
 * between them (a wall on a floor, a partition under a ceiling)? The segment between their centroids,
 * lifted `lift` along the normal, must reach u without hitting anything but t and u. */
static bool step_blocked(const seg_ctx *c, const glow__rt *rt, uint32_t t, uint32_t u, double lift) {
    const float(*P)[3] = c->scene->pos + 3 * (size_t)t, (*Q)[3] = c->scene->pos + 3 * (size_t)u;
    float a[3], dir[3];
    for (int k = 0; k < 3; ++k) {
        const double ca = ((double)P[0][k] + P[1][k] + P[2][k]) / 3.0, cb = ((double)Q[0][k] + Q[1][k] + Q[2][k]) / 3.0;
        a[k] = (float)(ca + lift * c->nrm[t][k]);
        dir[k] = (float)(cb + lift * c->nrm[u][k]) - a[k];
    }
    const float len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    if (!(len > 0.0f)) return false;
    for (int k = 0; k < 3; ++k) dir[k] /= len;
    const glow__hit h = glow__rt_intersect(rt, a, dir, 0.0f, len);
    return h.t < len && h.tri != t && h.tri != u;
}

glow_result glow__charts_segment(const glow__scene *scene, const glow__rt *rt, glow__log *log, glow__chart_set *out) {
    memset(out, 0, sizeof *out);
    const uint32_t n = scene->tri_count;
    if (n == 0) {
        out->chart_start = calloc(1, sizeof *out->chart_start);
        if (!out->chart_start) goto oom;
        return GLOW_OK;
    }
    const size_t n3 = 3 * (size_t)n;
    seg_ctx c = {.scene = scene};
    uint32_t *vid = malloc(n3 * sizeof *vid);
    uint32_t *adj_start = NULL, *adj = NULL;
    uint32_t *blk_start = NULL, *blk = NULL; /* blocked partners (rt only) */
    uint32_t *bar_stamp = NULL;              /* chart id + 1 whose barriers hold this triangle's */
    barrier *bar = NULL;
    uint32_t nbar = 0, bar_cap = 0;
    uint32_t *chart_start_tmp = malloc(((size_t)n + 1) * sizeof *chart_start_tmp);
    double(*ext_tmp)[2] = malloc((size_t)n * sizeof *ext_tmp);
    double(*nrm_tmp)[3] = malloc((size_t)n * sizeof *nrm_tmp);
    double(*cen_tmp)[3] = malloc((size_t)n * sizeof *cen_tmp);
    c.nrm = malloc((size_t)n * sizeof *c.nrm);
    c.cr = malloc((size_t)n * sizeof *c.cr);
    c.chart_of = malloc((size_t)n * sizeof *c.chart_of);
    c.stamp = calloc(n, sizeof *c.stamp);
    c.pts = malloc(n3 * sizeof *c.pts);
    c.hull = malloc((2 * n3 + 2) * sizeof *c.hull);
    out->chart_tris = malloc((size_t)n * sizeof *out->chart_tris);
    out->xy = calloc(n3, sizeof *out->xy);
    bool ok = vid && chart_start_tmp && ext_tmp && nrm_tmp && cen_tmp && c.nrm && c.cr && c.chart_of && c.stamp && c.pts && c.hull &&
              out->chart_tris && out->xy;
    ok = ok && weld(scene, vid) && build_adjacency(n, vid, &adj_start, &adj);
    if (!ok) goto fail;

    for (uint32_t t = 0; t < n; ++t) {
        const float(*p)[3] = scene->pos + 3 * (size_t)t;
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)p[1][k] - p[0][k];
            e2[k] = (double)p[2][k] - p[0][k];
        }
        double *cr = c.cr[t];
        cr[0] = e1[1] * e2[2] - e1[2] * e2[1];
        cr[1] = e1[2] * e2[0] - e1[0] * e2[2];
        cr[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        for (int k = 0; k < 3; ++k) c.nrm[t][k] = l > 0.0 ? cr[k] / l : 0.0;
        c.chart_of[t] = NONE;
    }

    const double cos_max = cos(GLOW__CHART_MAX_ANGLE_DEG * GLOW__PI / 180.0);
    double diag = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double e = (double)scene->bounds_max[a] - scene->bounds_min[a];
        diag += e * e;
    }
    const double lift = diag > 0.0 ? 1e-4 * sqrt(diag) : 1e-6; /* caches.c lifts texels as much */
    /* blocked partners: coplanar neighbours with geometry standing on the surface between them */
    if (rt) {
        blk_start = calloc((size_t)n + 1, sizeof *blk_start);
        blk = malloc(((size_t)adj_start[n] + 1) * sizeof *blk);
        bar_stamp = calloc((size_t)n + 1, sizeof *bar_stamp);
        if (!blk_start || !blk || !bar_stamp) goto fail;
        uint32_t nb = 0;
        for (uint32_t t = 0; t < n; ++t) {
            blk_start[t] = nb;
            const double *tn = c.nrm[t];
            for (uint32_t a = adj_start[t]; a < adj_start[t + 1]; ++a) {
                const uint32_t u = adj[a];
                const double *un = c.nrm[u];
                if (tn[0] * un[0] + tn[1] * un[1] + tn[2] * un[2] > 0.99 && step_blocked(&c, rt, t, u, lift)) {
                    blk[nb++] = u;
                    out->blocked += t < u;
                }
            }
        }
        blk_start[n] = nb;
    }
    uint32_t *members = out->chart_tris;
    uint32_t len = 0, charts = 0;
    for (uint32_t seed = 0; seed < n;) {
        if (c.chart_of[seed] != NONE) {
            ++seed;
            continue;
        }
        uint32_t id = charts++;
        uint32_t first = len;
        chart_start_tmp[id] = first;
        /* Grow from the seed, then regrow from the member whose normal is nearest the chart's mean
         * (a seed in the middle reaches GLOW__CHART_MAX_ANGLE_DEG to every side, one at the edge
         * only to one). The loop then looks at `seed` again: it may not be in the regrown chart. */
        uint32_t s0 = seed;
        for (int grow = 0; grow < 3; ++grow) {
            len = first;
            c.chart_of[s0] = id;
            members[len++] = s0;
            const double *sn = c.nrm[s0];
            bool zero_seed = sn[0] == 0.0 && sn[1] == 0.0 && sn[2] == 0.0;
            for (uint32_t head = first; head < len; ++head) {
                uint32_t t = members[head];
                for (uint32_t a = adj_start[t]; a < adj_start[t + 1]; ++a) {
                    uint32_t u = adj[a];
                    if (c.chart_of[u] != NONE) continue;
                    const double *un = c.nrm[u];
                    bool zero_u = un[0] == 0.0 && un[1] == 0.0 && un[2] == 0.0;
                    bool accept =
                        zero_seed ? zero_u : (zero_u || un[0] * sn[0] + un[1] * sn[1] + un[2] * sn[2] >= cos_max);
                    if (!accept) continue;
                    /* never both sides of a wall standing on the surface: u stays out when a member of
                     * this chart is one of its blocked partners, or lies beyond a barrier of it */
                    bool barred = false;
                    for (uint32_t q = blk_start ? blk_start[u] : 0; blk_start && q < blk_start[u + 1] && !barred; ++q)
                        barred = c.chart_of[blk[q]] == id;
                    if (barred || beyond_barrier(&c, bar, nbar, u)) continue;
                    c.chart_of[u] = id;
                    members[len++] = u;
                }
                /* t's blocked partners mark where a wall stands on the chart: a barrier */
                if (blk_start && blk_start[t + 1] > blk_start[t] && bar_stamp[t] != id + 1u) {
                    bar_stamp[t] = id + 1u;
                    for (uint32_t q = blk_start[t]; q < blk_start[t + 1]; ++q)
                        if (!add_barrier(&c, &bar, &nbar, &bar_cap, t, blk[q])) goto fail;
                }
            }
            if (grow == 2 || zero_seed || len - first < 3) break;
            double N[3] = {0, 0, 0};
            for (uint32_t i = first; i < len; ++i)
                for (int k = 0; k < 3; ++k) N[k] += c.cr[members[i]][k];
            uint32_t best = s0;
            double best_dot = -INFINITY;
            for (uint32_t i = first; i < len; ++i) {
                const double *un = c.nrm[members[i]];
                double d = un[0] * N[0] + un[1] * N[1] + un[2] * N[2];
                if (d > best_dot) {
                    best_dot = d;
                    best = members[i];
                }
            }
            if (best == s0) break;
            for (uint32_t i = first; i < len; ++i) c.chart_of[members[i]] = NONE;
            s0 = best;
        }
        /* members accepted before a barrier was found may lie beyond it: they leave for a later chart */
        if (nbar) {
            uint32_t kept = first;
            for (uint32_t i = first; i < len; ++i) {
                const uint32_t t = members[i];
                if (t != s0 && beyond_barrier(&c, bar, nbar, t)) {
                    c.chart_of[t] = NONE;
                    continue;
                }
                members[kept++] = t;
            }
            len = kept;
        }
        nbar = 0;
        uint32_t count = len - first;
        if (!finish_chart(&c, members + first, &count, c.nrm[s0], out->xy, ext_tmp[id], &out->evicted)) goto fail;
        len = first + count;
        /* mean normal and centroid, for merging small charts at pack time */
        double N[3] = {0, 0, 0}, C[3] = {0, 0, 0}, wsum = 0.0;
        for (uint32_t i = first; i < len; ++i) {
            const double *cr = c.cr[members[i]];
            const double a = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
            const float(*p)[3] = scene->pos + 3 * (size_t)members[i];
            for (int k = 0; k < 3; ++k) {
                N[k] += cr[k];
                C[k] += (a > 0.0 ? a : 1e-300) * ((double)p[0][k] + p[1][k] + p[2][k]) / 3.0;
            }
            wsum += a > 0.0 ? a : 1e-300;
        }
        const double nl = sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2]);
        for (int k = 0; k < 3; ++k) {
            nrm_tmp[id][k] = nl > 0.0 ? N[k] / nl : 0.0;
            cen_tmp[id][k] = wsum > 0.0 ? C[k] / wsum : 0.0;
        }
    }
    out->tri_count = n;
    out->chart_count = charts;
    chart_start_tmp[charts] = len;
    uint32_t *shrunk = realloc(chart_start_tmp, ((size_t)charts + 1) * sizeof *chart_start_tmp);
    if (shrunk) chart_start_tmp = shrunk; /* a failed shrink keeps the larger block */
    out->chart_start = chart_start_tmp;
    chart_start_tmp = NULL;
    out->extent = malloc(((size_t)charts + 1) * sizeof *out->extent);
    if (!out->extent) goto fail;
    memcpy(out->extent, ext_tmp, (size_t)charts * sizeof *out->extent);
    out->normal = malloc(((size_t)charts + 1) * sizeof *out->normal);
    out->centre = malloc(((size_t)charts + 1) * sizeof *out->centre);
    if (!out->normal || !out->centre) goto fail;
    memcpy(out->normal, nrm_tmp, (size_t)charts * sizeof *out->normal);
    memcpy(out->centre, cen_tmp, (size_t)charts * sizeof *out->centre);

    free(vid);
    free(adj_start);
    free(adj);
    free(blk_start);
    free(blk);
    free(bar_stamp);
    free(bar);
    free(ext_tmp);
    free(nrm_tmp);
    free(cen_tmp);
    free(c.nrm);
    free(c.cr);
    free(c.chart_of);
    free(c.stamp);
    free(c.pts);
    free(c.hull);
    free(c.cell_head);
    free(c.ent_tri);
    free(c.ent_next);
    if (out->evicted)
        glow__infof(log, "%s: charts: %u triangles overlapped their chart's projection and moved to another chart",
                    scene->source, out->evicted);
    if (out->blocked)
        glow__infof(log, "%s: charts: %u shared edges not crossed where geometry stands on the surface", scene->source,
                    out->blocked);
    return GLOW_OK;

fail:
    free(vid);
    free(adj_start);
    free(adj);
    free(blk_start);
    free(blk);
    free(bar_stamp);
    free(bar);
    free(chart_start_tmp);
    free(ext_tmp);
    free(nrm_tmp);
    free(cen_tmp);
    free(c.nrm);
    free(c.cr);
    free(c.chart_of);
    free(c.stamp);
    free(c.pts);
    free(c.hull);
    free(c.cell_head);
    free(c.ent_tri);
    free(c.ent_next);
    glow__charts_free(out);
oom:
    glow__errorf(log, "%s: charts: out of memory for %u triangles", scene->source, n);
    return GLOW_ERROR_OUT_OF_MEMORY;
}

/* ------------------------------------------------------------------ packing */
typedef struct slot {
    uint32_t chart, w, h;
} slot;

static int cmp_slot(const void *pa, const void *pb) {
    const slot *a = pa, *b = pb;
    if (a->h != b->h) return a->h > b->h ? -1 : 1;
    if (a->w != b->w) return a->w > b->w ? -1 : 1;
    return a->chart < b->chart ? -1 : (a->chart > b->chart);
}

static uint64_t round4(uint64_t v) { return (v + 3u) & ~(uint64_t)3u; }

/* Shelf packing (next fit over slots sorted tallest first) into `width`; returns the atlas height
 * (multiple of 4, at least 4) and, when pos != NULL, each slot's footprint origin. */
static uint64_t shelf_pack(const slot *sl, uint32_t count, uint64_t width, uint32_t pad, uint32_t (*pos)[2]) {
    uint64_t x = pad, y = pad, shelf = 0;
    for (uint32_t i = 0; i < count; ++i) {
        if (x > pad && x + sl[i].w + pad > width) {
            y += shelf + pad;
            x = pad;
            shelf = 0;
        }
        if (pos) {
            pos[i][0] = (uint32_t)x;
            pos[i][1] = (uint32_t)y;
        }
        x += sl[i].w + pad;
        if (sl[i].h > shelf) shelf = sl[i].h;
    }
    uint64_t h = round4(y + shelf + pad);
    return h < 4 ? 4 : h;
}

/* Shelf packing onto pages of width x height (issue 16 item 5): the same next fit, and a shelf that
 * does not fit below the page's last starts the next page. Returns the page count, or 0 when a
 * footprint does not fit a page or more than max_pages would be needed; pos and page (when not NULL)
 * receive each slot's origin in its page and its page. */
static uint32_t shelf_pack_pages(const slot *sl, uint32_t count, uint64_t width, uint64_t height, uint32_t pad,
                                 uint32_t max_pages, uint32_t (*pos)[2], uint32_t *page) {
    uint64_t x = pad, y = pad, shelf = 0;
    uint32_t p = 0;
    for (uint32_t i = 0; i < count; ++i) {
        if ((uint64_t)sl[i].w + 2u * pad > width || (uint64_t)sl[i].h + 2u * pad > height) return 0;
        if (x > pad && x + sl[i].w + pad > width) {
            y += shelf + pad;
            x = pad;
            shelf = 0;
        }
        if (y + sl[i].h + pad > height) { /* (slots come tallest first: only a shelf's first can overflow) */
            if (++p >= max_pages) return 0;
            x = pad;
            y = pad;
            shelf = 0;
        }
        if (pos) {
            pos[i][0] = (uint32_t)x;
            pos[i][1] = (uint32_t)y;
        }
        if (page) page[i] = p;
        x += sl[i].w + pad;
        if (sl[i].h > shelf) shelf = sl[i].h;
    }
    return p + 1;
}

/* ------------------------------------------------------------------ small charts
 * A chart narrower than a texel still took a texel of its own (plus its padding): in the Dabrovic
 * Sponza 4023 of 4757 charts were narrower than one texel at the default budget and held 3.8 % of
 * the surface, but about half of the lightmap caches. Such charts are merged: those whose centres
 * fall in the same cell of one texel (world units) and face within GLOW__CHART_MERGE_ANGLE_DEG of the
 * group's first member share one texel, laid out as their orthographic projection onto the group's
 * mean plane. The texel's cache then stands at the footprint centroid of the whole group (caches.c).
 * A lightmap texel's cache sees one hemisphere, hence the angle limit: a member facing further away
 * keeps its own texel, as do charts wider than GLOW__CHART_SMALL texels. */
typedef struct unit_plan {
    uint32_t count;   /* units: large charts, then groups of small charts */
    uint32_t *first;  /* [count + 1] into charts */
    uint32_t *charts; /* [chart_count] chart ids, unit by unit */
    uint32_t small, shared;
} unit_plan;

static void unit_plan_free(unit_plan *u) {
    free(u->first);
    free(u->charts);
    memset(u, 0, sizeof *u);
}

typedef struct cell_key {
    int64_t x, y, z;
    uint32_t chart;
} cell_key;

static int cmp_cell_key(const void *pa, const void *pb) {
    const cell_key *a = pa, *b = pb;
    if (a->x != b->x) return a->x < b->x ? -1 : 1;
    if (a->y != b->y) return a->y < b->y ? -1 : 1;
    if (a->z != b->z) return a->z < b->z ? -1 : 1;
    return a->chart < b->chart ? -1 : (a->chart > b->chart);
}

static double chart_scale(const glow__chart_set *cs, uint32_t i) {
    return cs->scale ? (double)cs->scale[i] : 1.0;
}

/* Small at the base density, whatever the chart's scale: a concave chart narrower than a texel still
 * shares one, so that a budget too coarse for the features is not spent on them (Sponza at the low
 * preset, 2000 texels: scaled small charts taking texels of their own made its block error 0.197 ->
 * 0.227; so: 0.196). */
static bool is_small(const glow__chart_set *cs, uint32_t i, double d) {
    return cs->normal && cs->extent[i][0] * d <= GLOW__CHART_SMALL;
}

static int64_t cell_of(double x, double d) {
    double f = floor(x * d);
    return f < -4e18 ? INT64_MIN / 2 : f > 4e18 ? INT64_MAX / 2 : (int64_t)f;
}

/* Groups the small charts at density d. Deterministic: cells in coordinate order, charts in index
 * order within a cell. */
static bool plan_units(const glow__chart_set *cs, double d, unit_plan *u) {
    const uint32_t n = cs->chart_count;
    memset(u, 0, sizeof *u);
    u->first = malloc(((size_t)n + 1) * sizeof *u->first);
    u->charts = malloc(((size_t)n + 1) * sizeof *u->charts);
    uint32_t *unit_of = malloc(((size_t)n + 1) * sizeof *unit_of);
    uint32_t *seed = malloc(((size_t)n + 1) * sizeof *seed);
    cell_key *keys = malloc(((size_t)n + 1) * sizeof *keys);
    if (!u->first || !u->charts || !unit_of || !seed || !keys) {
        free(unit_of);
        free(seed);
        free(keys);
        unit_plan_free(u);
        return false;
    }
    uint32_t units = 0, ns = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (!is_small(cs, i, d)) {
            unit_of[i] = units++;
            continue;
        }
        keys[ns].x = cell_of(cs->centre[i][0], d);
        keys[ns].y = cell_of(cs->centre[i][1], d);
        keys[ns].z = cell_of(cs->centre[i][2], d);
        keys[ns++].chart = i;
    }
    qsort(keys, ns, sizeof *keys, cmp_cell_key);
    const double cos_max = cos(GLOW__CHART_MERGE_ANGLE_DEG * GLOW__PI / 180.0);
    for (uint32_t a = 0; a < ns;) {
        uint32_t b = a + 1;
        while (b < ns && keys[b].x == keys[a].x && keys[b].y == keys[a].y && keys[b].z == keys[a].z) ++b;
        const uint32_t cell_first_unit = units;
        for (uint32_t k = a; k < b; ++k) {
            const uint32_t i = keys[k].chart;
            const double *ni = cs->normal[i];
            const bool zero = ni[0] == 0.0 && ni[1] == 0.0 && ni[2] == 0.0;
            uint32_t g = NONE;
            for (uint32_t v = cell_first_unit; v < units && !zero; ++v) {
                const double *ns0 = cs->normal[seed[v]];
                if (ni[0] * ns0[0] + ni[1] * ns0[1] + ni[2] * ns0[2] >= cos_max) {
                    g = v;
                    break;
                }
            }
            if (g == NONE) {
                g = units++;
                seed[g] = i;
                u->shared += 1;
            }
            unit_of[i] = g;
        }
        a = b;
    }
    u->small = ns;
    u->count = units;
    /* counting sort of the charts by unit, charts in index order within a unit */
    memset(u->first, 0, ((size_t)units + 1) * sizeof *u->first);
    for (uint32_t i = 0; i < n; ++i) u->first[unit_of[i] + 1]++;
    for (uint32_t v = 0; v < units; ++v) u->first[v + 1] += u->first[v];
    memcpy(seed, u->first, ((size_t)units + 1) * sizeof *seed);
    for (uint32_t i = 0; i < n; ++i) u->charts[seed[unit_of[i]]++] = i;
    free(unit_of);
    free(seed);
    free(keys);
    return true;
}

/* Is unit v laid out into one shared texel? */
static bool unit_shared(const glow__chart_set *cs, const unit_plan *u, uint32_t v, double d) {
    return is_small(cs, u->charts[u->first[v]], d);
}

/* Projection frame of a merged group: the members' mean normal and two tangents. */
static void group_frame(const glow__chart_set *cs, const unit_plan *u, uint32_t v, double T[3], double B[3]) {
    double N[3] = {0, 0, 0};
    for (uint32_t j = u->first[v]; j < u->first[v + 1]; ++j)
        for (int k = 0; k < 3; ++k) N[k] += cs->normal[u->charts[j]][k];
    double l = sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2]);
    if (l > 0.0) {
        for (int k = 0; k < 3; ++k) N[k] /= l;
    } else {
        N[0] = N[1] = 0.0;
        N[2] = 1.0;
    }
    glow__tangent_frame(N, T, B);
}

/* Footprints at density d; returns the best atlas size for them. */
static void layout(const glow__chart_set *cs, const unit_plan *u, double d, uint32_t pad, slot *sl, uint64_t *out_w,
                   uint64_t *out_h) {
    double total = 0.0;
    uint64_t maxw = 1;
    for (uint32_t v = 0; v < u->count; ++v) {
        const uint32_t i = u->charts[u->first[v]];
        double fw = 1.0, fh = 1.0;
        if (!unit_shared(cs, u, v, d)) {
            fw = ceil(cs->extent[i][0] * d * chart_scale(cs, i) + 0.1);
            fh = ceil(cs->extent[i][1] * d * chart_scale(cs, i) + 0.1);
        }
        if (!(fw >= 1.0)) fw = 1.0;
        if (!(fh >= 1.0)) fh = 1.0;
        if (fw > 1e7) fw = 1e7;
        if (fh > 1e7) fh = 1e7;
        sl[v].chart = v;
        sl[v].w = (uint32_t)fw;
        sl[v].h = (uint32_t)fh;
        total += (fw + pad) * (fh + pad);
        if (sl[v].w > maxw) maxw = sl[v].w;
    }
    qsort(sl, u->count, sizeof *sl, cmp_slot);
    double base = fmax(sqrt(total), (double)(maxw + 2 * pad));
    /* Candidate widths from sqrt(area) up; the shortest longer side wins (roughly square), then
     * the smallest area. */
    uint64_t best_w = 0, best_h = 0;
    for (int k = 0; k < 24; ++k) {
        uint64_t w = round4((uint64_t)ceil(base * (1.0 + 0.03 * k)));
        if (w < maxw + 2 * (uint64_t)pad) w = round4(maxw + 2 * (uint64_t)pad);
        if (w < 4) w = 4;
        uint64_t h = shelf_pack(sl, u->count, w, pad, NULL);
        uint64_t side = w > h ? w : h, best_side = best_w > best_h ? best_w : best_h;
        if (best_w == 0 || side < best_side || (side == best_side && w * h < best_w * best_h)) {
            best_w = w;
            best_h = h;
        }
        if (h < w) break; /* wider only makes it flatter */
    }
    *out_w = best_w;
    *out_h = best_h;
}

static void put_uv(float (*out_uv)[2], size_t corner, double x, double y, uint64_t w, uint64_t h) {
    out_uv[corner][0] = (float)fmin(fmax(x / (double)w, 0.0), 1.0);
    out_uv[corner][1] = (float)fmin(fmax(y / (double)h, 0.0), 1.0);
}

/* Writes the UVs of unit v, whose footprint starts at texel (px, py). */
static void place_unit(const glow__chart_set *cs, const unit_plan *u, uint32_t v, const slot *sl, uint32_t px,
                       uint32_t py, double d, uint64_t w, uint64_t h, float (*out_uv)[2]) {
    const uint32_t c0 = u->charts[u->first[v]];
    const bool shared = unit_shared(cs, u, v, d);
    if (u->first[v + 1] - u->first[v] == 1) { /* one chart: its own plane, scaled to fit */
        double s = shared ? d : d * chart_scale(cs, c0);
        if (shared && cs->extent[c0][0] * d > 0.9) s = 0.9 / cs->extent[c0][0];
        const double ox = px + 0.5 * (sl->w - cs->extent[c0][0] * s), oy = py + 0.5 * (sl->h - cs->extent[c0][1] * s);
        for (uint32_t j = cs->chart_start[c0]; j < cs->chart_start[c0 + 1]; ++j) {
            const uint32_t t = cs->chart_tris[j];
            for (uint32_t k = 0; k < 3; ++k) {
                const double *p = cs->xy[3 * (size_t)t + k];
                put_uv(out_uv, 3 * (size_t)t + k, ox + p[0] * s, oy + p[1] * s, w, h);
            }
        }
        return;
    }
    /* A merged group: each member keeps its own chart's layout (never flipped or stretched), placed
     * where its centre projects onto the group's mean plane; the whole scaled to fit the texel. */
    double T[3], B[3];
    group_frame(cs, u, v, T, B);
    const double *o = cs->centre[c0];
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY, s = d;
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1) {
            const double ext = fmax(x1 - x0, y1 - y0);
            if (ext * d > 0.9) s = 0.9 / ext;
        }
        const double ox = px + 0.5 * (1.0 - (x1 - x0) * s) - x0 * s, oy = py + 0.5 * (1.0 - (y1 - y0) * s) - y0 * s;
        for (uint32_t jc = u->first[v]; jc < u->first[v + 1]; ++jc) {
            const uint32_t ch = u->charts[jc];
            const double q[3] = {cs->centre[ch][0] - o[0], cs->centre[ch][1] - o[1], cs->centre[ch][2] - o[2]};
            const double cx = q[0] * T[0] + q[1] * T[1] + q[2] * T[2] - 0.5 * cs->extent[ch][0];
            const double cy = q[0] * B[0] + q[1] * B[1] + q[2] * B[2] - 0.5 * cs->extent[ch][1];
            if (pass == 0) {
                x0 = fmin(x0, cx);
                y0 = fmin(y0, cy);
                x1 = fmax(x1, cx + cs->extent[ch][0]);
                y1 = fmax(y1, cy + cs->extent[ch][1]);
                continue;
            }
            for (uint32_t j = cs->chart_start[ch]; j < cs->chart_start[ch + 1]; ++j) {
                const uint32_t t = cs->chart_tris[j];
                for (uint32_t k = 0; k < 3; ++k) {
                    const double *p = cs->xy[3 * (size_t)t + k];
                    put_uv(out_uv, 3 * (size_t)t + k, ox + (cx + p[0]) * s, oy + (cy + p[1]) * s, w, h);
                }
            }
        }
    }
}

glow_result glow__charts_pack(const glow__chart_set *cs, float texel_density, uint32_t padding, glow__log *log,
                              float (*out_uv)[2], uint32_t *out_width, uint32_t *out_height, float *out_density,
                              glow__chart_pack_stats *stats) {
    uint32_t pages = 0;
    return glow__charts_pack_pages(cs, texel_density, padding, GLOW__CHART_MAX_ATLAS, 1u, log, out_uv, NULL, &pages,
                                   out_width, out_height, out_density, stats);
}

/* Marks every triangle of unit v as lying on page p. */
static void unit_page(const glow__chart_set *cs, const unit_plan *u, uint32_t v, uint32_t p, uint32_t *out_page) {
    for (uint32_t jc = u->first[v]; jc < u->first[v + 1]; ++jc) {
        const uint32_t ch = u->charts[jc];
        for (uint32_t j = cs->chart_start[ch]; j < cs->chart_start[ch + 1]; ++j) out_page[cs->chart_tris[j]] = p;
    }
}

glow_result glow__charts_pack_pages(const glow__chart_set *cs, float texel_density, uint32_t padding,
                                    uint32_t max_side, uint32_t max_pages, glow__log *log, float (*out_uv)[2],
                                    uint32_t *out_page, uint32_t *out_pages, uint32_t *out_width,
                                    uint32_t *out_height, float *out_density, glow__chart_pack_stats *stats) {
    *out_width = *out_height = 0;
    *out_pages = 0;
    if (out_density) *out_density = texel_density;
    if (stats) {
        uint32_t *keep = stats->unit_of;
        memset(stats, 0, sizeof *stats);
        stats->unit_of = keep;
    }
    if (!(texel_density > 0.0f) || !isfinite(texel_density)) {
        glow__errorf(log, "charts: texel density %g must be a positive finite number", (double)texel_density);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (max_side < 4 || max_side % 4 || max_side > GLOW__CHART_MAX_ATLAS || max_pages < 1 || max_side <= 2u * padding) {
        glow__errorf(log, "charts: atlas side %u must be a multiple of 4 in [4, %u] wider than twice the padding %u, and "
                     "pages %u at least 1", max_side, GLOW__CHART_MAX_ATLAS, padding, max_pages);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (out_page) memset(out_page, 0, (size_t)cs->tri_count * sizeof *out_page);
    if (cs->tri_count == 0 || cs->chart_count == 0) return GLOW_OK;
    slot *sl = malloc((size_t)cs->chart_count * sizeof *sl);
    uint32_t(*pos)[2] = malloc((size_t)cs->chart_count * sizeof *pos);
    uint32_t *pg = malloc((size_t)cs->chart_count * sizeof *pg);
    unit_plan u = {0};
    if (!sl || !pos || !pg) goto oom;
    double d = texel_density;
    uint64_t w = 0, h = 0;
    uint32_t pages = 0;
    for (int iter = 0; iter < 60; ++iter) {
        unit_plan_free(&u);
        if (!plan_units(cs, d, &u)) goto oom;
        layout(cs, &u, d, padding, sl, &w, &h);
        uint64_t side = w > h ? w : h;
        if (side <= max_side) { /* one atlas: exactly as before pages */
            pages = 1;
            break;
        }
        /* Too large for one atlas: pages of max_side x max_side (the slots are sorted tallest first),
         * at the same density, up to max_pages; beyond that (or a footprint wider than a page) the
         * density is lowered as with one page. */
        if (max_pages > 1 && out_page) {
            uint64_t big = 1;
            for (uint32_t i = 0; i < u.count; ++i) {
                if (sl[i].w > big) big = sl[i].w;
                if (sl[i].h > big) big = sl[i].h;
            }
            if (big + 2u * padding > max_side) { /* a footprint wider than a page: shrink it to fit one */
                d *= fmin(0.98 * (double)(max_side - 2u * padding) / (double)big, 0.98);
                continue;
            }
            const uint32_t need = shelf_pack_pages(sl, u.count, max_side, max_side, padding, UINT32_MAX, NULL, NULL);
            if (need && need <= max_pages) {
                pages = need;
                w = h = max_side;
                break;
            }
            d *= fmin(0.98 * sqrt((double)max_pages / (double)(need ? need : 2u * max_pages)), 0.98);
            continue;
        }
        d *= fmin(0.98 * max_side / (double)side, 0.98);
    }
    if (!pages) {
        free(sl);
        free(pos);
        free(pg);
        unit_plan_free(&u);
        glow__errorf(log, "charts: %u charts do not fit %u atlas(es) of %ux%u at any texel density", cs->chart_count,
                     max_pages, max_side, max_side);
        return GLOW_ERROR_UNSUPPORTED;
    }
    if (d < texel_density)
        glow__warnf(log, "charts: the atlas at %g texels per unit would exceed %u page(s) of %u texels a side (or a "
                    "chart a page); using %g", (double)texel_density, max_pages, max_side, d);
    if (pages == 1) {
        shelf_pack(sl, u.count, w, padding, pos);
        memset(pg, 0, (size_t)u.count * sizeof *pg);
    } else {
        shelf_pack_pages(sl, u.count, w, h, padding, pages, pos, pg);
    }
    for (uint32_t i = 0; i < u.count; ++i) {
        place_unit(cs, &u, sl[i].chart, &sl[i], pos[i][0], pos[i][1], d, w, h, out_uv);
        if (out_page && pg[i]) unit_page(cs, &u, sl[i].chart, pg[i], out_page);
    }
    if (stats) {
        stats->small = u.small;
        stats->shared = u.shared;
        stats->slots = u.count;
        if (stats->unit_of)
            for (uint32_t v = 0; v < u.count; ++v)
                for (uint32_t j = u.first[v]; j < u.first[v + 1]; ++j) stats->unit_of[u.charts[j]] = v;
    }
    free(sl);
    free(pos);
    free(pg);
    unit_plan_free(&u);
    *out_width = (uint32_t)w;
    *out_height = (uint32_t)h;
    *out_pages = pages;
    if (out_density) *out_density = (float)d;
    return GLOW_OK;
oom:
    free(sl);
    free(pos);
    free(pg);
    unit_plan_free(&u);
    glow__errorf(log, "charts: out of memory packing %u charts", cs->chart_count);
    return GLOW_ERROR_OUT_OF_MEMORY;
}

glow_result glow__charts_build(const glow__scene *scene, float texel_density, uint32_t padding, glow__log *log,
                               float (*out_uv)[2], uint32_t *out_width, uint32_t *out_height,
                               uint32_t *out_chart_count) {
    *out_width = *out_height = 0;
    if (out_chart_count) *out_chart_count = 0;
    glow__chart_set cs;
    glow_result r = glow__charts_segment(scene, NULL, log, &cs);
    if (r != GLOW_OK) return r;
    r = glow__charts_pack(&cs, texel_density, padding, log, out_uv, out_width, out_height, NULL, NULL);
    if (r == GLOW_OK && out_chart_count) *out_chart_count = cs.chart_count;
    glow__charts_free(&cs);
    return r;
}
