/* caches.c — cache placement (PIC 4.4): where the indirect light is gathered at runtime.
 *
 * Two kinds of cache, grid caches first in the array, then lightmap caches:
 *  - GRID: one spherical cache per cell centre of a regular grid over the scene's AABB (for dynamic
 *    objects). A grid point inside solid geometry is no cache: from inside a wall or a closed block
 *    one sees back faces (walls face into rooms, blocks face out). GRID_RAYS fixed directions (a
 *    spherical Fibonacci set) are cast; the point is inside when more than GRID_INSIDE_FRACTION of
 *    the rays that hit something hit a back face and at least a quarter of all rays do (points that
 *    see mostly sky, outside an open scene, stay: they are air).
 *  - LIGHTMAP: one hemispherical cache per texel of one atlas, UVs from the mesh's second UV set or
 *    from charts.c. Every triangle is rasterised conservatively: a texel its UV triangle overlaps
 *    belongs to the triangle whose UV triangle is nearest to the texel centre (0 when the centre is
 *    inside; ties: lowest triangle index), and the cache sits at that nearest point, lifted by
 *    1e-4 x the scene diagonal along the geometric normal. So every triangle owns or shares every
 *    texel it touches, and tiny triangles still get a texel. A texel whose cache sees back faces
 *    (LM_RAYS hemisphere rays, LM_INVALID_FRACTION of the hits, at least a quarter of the rays: a
 *    floor under a box, a wall poking through a floor) is invalid: counted, not a cache.
 * Maps (grid_map, lm_map): cache index, GLOW_MAP_COPY_BIT | index of a nearby cache for cells that
 * have none of their own, or GLOW_MAP_EMPTY. Copies are made by a breadth-first dilation in layers
 * (each layer reads only earlier layers, neighbours in a fixed order: faces, then edges, then
 * corners), so they do not depend on scan order: the grid dilates GRID_DILATE_PASSES layers; the
 * lightmap first fills invalid texels from the valid ones of their chart (all layers needed), then
 * the gutter LM_GUTTER_PASSES layers out (charts.c keeps charts 2 texels apart: a bilinear lookup
 * inside a chart reads at most one texel beyond its conservative footprint).
 * Texel density and grid spacing come from the settings or from the targets; with generated charts
 * the density is corrected from the covered-texel count (a few packing rounds).
 * All ray work runs through glow__parallel_for with one result per item; the rest is serial, so the
 * result is the same for any thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_format.h"
#include "charts.h"
#include "pc_internal.h"

#define NONE 0xFFFFFFFFu
#define GRID_RAYS GLOW__GRID_RAYS
#define LM_RAYS 16u
#define GRID_INSIDE_FRACTION 0.4
#define LM_INVALID_FRACTION 0.3
#define GRID_DILATE_PASSES 3u
#define LM_GUTTER_PASSES 2u
#define LM_INVALID_WARN 0.2 /* warn when more than this share of the texels see mostly back faces */
#define LM_PADDING 2u
#define MAX_GRID_CELLS (8u << 20)
#define DEFAULT_TARGET_GRID 2000u
#define DEFAULT_TARGET_LIGHTMAP 8000u
#define DENSITY_ROUNDS 4

/* ------------------------------------------------------------------ directions */
void glow__fibonacci_sphere(uint32_t n, float (*out)[3]) {
    const double golden = GLOW__PI * (3.0 - sqrt(5.0));
    for (uint32_t i = 0; i < n; ++i) {
        double z = 1.0 - (2.0 * i + 1.0) / n, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = golden * i;
        out[i][0] = (float)(r * cos(phi));
        out[i][1] = (float)(r * sin(phi));
        out[i][2] = (float)z;
    }
}

/* Local hemisphere directions (z up), cos(theta) in (0.1, 1): no grazing rays. */
static void fibonacci_hemisphere(uint32_t n, double (*out)[3]) {
    const double golden = GLOW__PI * (3.0 - sqrt(5.0));
    for (uint32_t i = 0; i < n; ++i) {
        double z = 1.0 - 0.9 * (i + 0.5) / n, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = golden * i;
        out[i][0] = r * cos(phi);
        out[i][1] = r * sin(phi);
        out[i][2] = z;
    }
}

/* ------------------------------------------------------------------ dilation */
/* Breadth-first layers into cells with eligible[c] != 0 and map[c] == EMPTY, from every non-empty
 * cell, at most max_layers layers. nb/nb_count: neighbour offsets in priority order (dx, dy, dz);
 * dims[2] == 1 for 2-D maps. Returns false on OOM. */
static bool dilate(uint32_t *map, const uint32_t dims[3], const uint8_t *eligible, const int (*nb)[3],
                   uint32_t nb_count, uint32_t max_layers) {
    const size_t nx = dims[0], ny = dims[1], nz = dims[2], n = nx * ny * nz;
    uint16_t *layer = malloc(n * sizeof *layer);
    uint32_t *cur = malloc(n * sizeof *cur), *next = malloc(n * sizeof *next);
    if (!layer || !cur || !next) {
        free(layer);
        free(cur);
        free(next);
        return false;
    }
    size_t cur_len = 0;
    for (size_t i = 0; i < n; ++i) {
        layer[i] = map[i] != GLOW_MAP_EMPTY ? 0 : UINT16_MAX;
        if (map[i] != GLOW_MAP_EMPTY) cur[cur_len++] = (uint32_t)i;
    }
    if (max_layers >= UINT16_MAX) max_layers = UINT16_MAX - 1;
    for (uint32_t pass = 1; pass <= max_layers && cur_len; ++pass) {
        size_t next_len = 0;
        for (size_t f = 0; f < cur_len; ++f) {
            size_t c = cur[f];
            long x = (long)(c % nx), y = (long)((c / nx) % ny), z = (long)(c / (nx * ny));
            for (uint32_t k = 0; k < nb_count; ++k) {
                long qx = x + nb[k][0], qy = y + nb[k][1], qz = z + nb[k][2];
                if (qx < 0 || qy < 0 || qz < 0 || qx >= (long)nx || qy >= (long)ny || qz >= (long)nz) continue;
                size_t q = ((size_t)qz * ny + (size_t)qy) * nx + (size_t)qx;
                if (!eligible[q] || layer[q] != UINT16_MAX || map[q] != GLOW_MAP_EMPTY) continue;
                layer[q] = (uint16_t)pass;
                next[next_len++] = (uint32_t)q;
            }
        }
        for (size_t f = 0; f < next_len; ++f) {
            size_t c = next[f];
            long x = (long)(c % nx), y = (long)((c / nx) % ny), z = (long)(c / (nx * ny));
            for (uint32_t k = 0; k < nb_count; ++k) {
                long qx = x + nb[k][0], qy = y + nb[k][1], qz = z + nb[k][2];
                if (qx < 0 || qy < 0 || qz < 0 || qx >= (long)nx || qy >= (long)ny || qz >= (long)nz) continue;
                size_t q = ((size_t)qz * ny + (size_t)qy) * nx + (size_t)qx;
                if (layer[q] < pass && map[q] != GLOW_MAP_EMPTY) {
                    map[c] = GLOW_MAP_COPY_BIT | (map[q] & GLOW_MAP_INDEX_MASK);
                    break;
                }
            }
        }
        uint32_t *tmp = cur;
        cur = next;
        next = tmp;
        cur_len = next_len;
    }
    free(layer);
    free(cur);
    free(next);
    return true;
}

/* Neighbour offsets sorted by how many axes they step along (faces, edges, corners); dims 2 or 3. */
static uint32_t neighbour_offsets(int dim, int (*out)[3]) {
    uint32_t n = 0;
    for (int steps = 1; steps <= dim; ++steps)
        for (int dz = dim == 3 ? -1 : 0; dz <= (dim == 3 ? 1 : 0); ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if (abs(dx) + abs(dy) + abs(dz) != steps) continue;
                    out[n][0] = dx;
                    out[n][1] = dy;
                    out[n][2] = dz;
                    ++n;
                }
    return n;
}

/* ------------------------------------------------------------------ grid */
typedef struct grid_job {
    const glow__rt *rt;
    float origin[3], spacing;
    uint32_t dims[3];
    float dirs[GRID_RAYS][3];
    uint8_t *inside;
} grid_job;

int glow__grid_point_inside(const glow__rt *rt, const float o[3], const float (*dirs)[3]) {
    uint32_t hits = 0, back = 0;
    for (uint32_t r = 0; r < GRID_RAYS; ++r) {
        glow__hit h = glow__rt_intersect(rt, o, dirs[r], 0.0f, INFINITY);
        if (h.t == INFINITY) continue;
        ++hits;
        back += h.back_face;
    }
    return back > GRID_INSIDE_FRACTION * hits && 4 * back >= GRID_RAYS;
}

static void grid_range(void *p, uint32_t begin, uint32_t end, uint32_t worker) {
    grid_job *j = p;
    (void)worker;
    for (uint32_t c = begin; c < end; ++c) {
        uint32_t x = c % j->dims[0], y = (c / j->dims[0]) % j->dims[1], z = c / (j->dims[0] * j->dims[1]);
        float o[3] = {j->origin[0] + j->spacing * (float)x, j->origin[1] + j->spacing * (float)y,
                      j->origin[2] + j->spacing * (float)z};
        j->inside[c] = (uint8_t)glow__grid_point_inside(j->rt, o, (const float(*)[3])j->dirs);
    }
}

/* Spacing so that the grid over `ext` has about `target` points (flat axes count as one cell). */
static double spacing_for_target(const double ext[3], double target) {
    double big = fmax(ext[0], fmax(ext[1], ext[2]));
    if (!(big > 0.0)) return 1.0;
    double lo = big / (2.0 * target + 2.0), hi = big * 2.0;
    for (int it = 0; it < 100; ++it) {
        double s = sqrt(lo * hi), cnt = 1.0;
        for (int a = 0; a < 3; ++a) cnt *= fmax(1.0, ext[a] / s);
        if (cnt > target)
            lo = s;
        else
            hi = s;
    }
    return sqrt(lo * hi);
}

static glow_result build_grid(const glow__scene *scene, const glow__rt *rt, const glow__cache_settings *set,
                              glow__pool *pool, glow__log *log, glow__caches *out, uint8_t **out_inside) {
    double ext[3], centre[3];
    for (int a = 0; a < 3; ++a) {
        ext[a] = fmax(0.0, (double)scene->bounds_max[a] - scene->bounds_min[a]);
        centre[a] = 0.5 * ((double)scene->bounds_max[a] + scene->bounds_min[a]);
    }
    double s;
    const uint32_t R = set->grid_refine >= 2 ? set->grid_refine : 1u;
    out->grid_refine = R > 1 ? R : 0u; /* to be refined (caches_build), unless no refined grid fits */
    if (set->grid_spacing > 0.0f) {
        s = (double)set->grid_spacing * R; /* refined: the given spacing is the fine one */
    } else {
        uint32_t target = set->target_grid ? set->target_grid : DEFAULT_TARGET_GRID;
        s = R > 1 ? glow__grid_refined_spacing(scene, R, target, MAX_GRID_CELLS) : 0.0;
        if (!(s > 0.0)) {
            if (R > 1)
                glow__infof(log, "%s: caches: no grid refined %ux fits %u points; the grid stays uniform", scene->source,
                            R, target);
            out->grid_refine = 0;
            s = spacing_for_target(ext, target);
        }
    }
    double dims[3], cells = 1.0;
    uint32_t rdims[3] = {0, 0, 0};
    float rorigin[3] = {0, 0, 0};
    for (int it = 0; it < 8; ++it) {
        cells = 1.0;
        if (out->grid_refine) glow__grid_refined_lattice(scene, s, out->grid_refine, rdims, rorigin);
        for (int a = 0; a < 3; ++a) {
            dims[a] = out->grid_refine ? (double)rdims[a] : fmax(1.0, ceil(ext[a] / s - 1e-6));
            cells *= dims[a];
        }
        if (cells <= MAX_GRID_CELLS) break;
        double grown = s * cbrt(cells / MAX_GRID_CELLS) * 1.01;
        if (it == 0)
            glow__warnf(log, "%s: caches: grid spacing %g gives %.0f grid points; using %g (at most %u points)",
                        scene->source, s, cells, grown, MAX_GRID_CELLS);
        s = grown;
    }
    out->grid_spacing = (float)s;
    for (int a = 0; a < 3; ++a) {
        out->grid_dims[a] = (uint32_t)dims[a];
        out->grid_origin[a] = out->grid_refine ? rorigin[a] : (float)(centre[a] - 0.5 * dims[a] * s + 0.5 * s);
    }
    const uint32_t n = (uint32_t)cells;
    uint8_t *inside = malloc(n);
    out->grid_map = malloc((size_t)n * sizeof *out->grid_map);
    if (!inside || !out->grid_map) {
        free(inside);
        glow__errorf(log, "%s: caches: out of memory for %u grid points", scene->source, n);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    grid_job j = {.rt = rt, .spacing = out->grid_spacing, .inside = inside};
    memcpy(j.origin, out->grid_origin, sizeof j.origin);
    memcpy(j.dims, out->grid_dims, sizeof j.dims);
    glow__fibonacci_sphere(GRID_RAYS, j.dirs);
    glow__parallel_for(pool, n, 64, grid_range, &j);
    uint32_t count = 0;
    for (uint32_t c = 0; c < n; ++c) {
        out->grid_map[c] = inside[c] ? GLOW_MAP_EMPTY : count;
        count += !inside[c];
    }
    out->grid_cache_count = count;
    out->grid_inside = n - count;
    *out_inside = inside;
    return GLOW_OK;
}

/* ------------------------------------------------------------------ lightmap rasterisation */
static double cross2(const double o[2], const double a[2], const double b[2]) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/* Squared distance from p to triangle t (2-D) and the barycentrics of the nearest point. */
static double closest_bary(const double p[2], const double t[3][2], double bary[3]) {
    double area = cross2(t[0], t[1], t[2]);
    if (area != 0.0) {
        double w0 = cross2(p, t[1], t[2]) / area, w1 = cross2(p, t[2], t[0]) / area, w2 = 1.0 - w0 - w1;
        if (w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0) {
            bary[0] = w0;
            bary[1] = w1;
            bary[2] = w2;
            return 0.0;
        }
    }
    double best = INFINITY;
    for (int k = 0; k < 3; ++k) {
        const double *a = t[k], *b = t[(k + 1) % 3];
        double ex = b[0] - a[0], ey = b[1] - a[1], l2 = ex * ex + ey * ey;
        double s = l2 > 0.0 ? ((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / l2 : 0.0;
        s = fmin(fmax(s, 0.0), 1.0);
        double dx = a[0] + s * ex - p[0], dy = a[1] + s * ey - p[1], d2 = dx * dx + dy * dy;
        if (d2 < best) {
            best = d2;
            bary[k] = 1.0 - s;
            bary[(k + 1) % 3] = s;
            bary[(k + 2) % 3] = 0.0;
        }
    }
    return best;
}

/* Does triangle t overlap the unit square at (x0, y0) by more than eps (texels)? Separating axes. */
static bool tri_box(const double t[3][2], double x0, double y0, double eps) {
    double mnx = fmin(fmin(t[0][0], t[1][0]), t[2][0]), mxx = fmax(fmax(t[0][0], t[1][0]), t[2][0]);
    double mny = fmin(fmin(t[0][1], t[1][1]), t[2][1]), mxy = fmax(fmax(t[0][1], t[1][1]), t[2][1]);
    if (mxx <= x0 + eps || mnx >= x0 + 1.0 - eps || mxy <= y0 + eps || mny >= y0 + 1.0 - eps) return false;
    for (int k = 0; k < 3; ++k) {
        double ax = t[(k + 1) % 3][1] - t[k][1], ay = t[k][0] - t[(k + 1) % 3][0];
        double len = sqrt(ax * ax + ay * ay);
        if (!(len > 0.0)) continue;
        double lo = INFINITY, hi = -INFINITY;
        for (int i = 0; i < 3; ++i) {
            double p = t[i][0] * ax + t[i][1] * ay;
            lo = fmin(lo, p);
            hi = fmax(hi, p);
        }
        double c = (x0 + 0.5) * ax + (y0 + 0.5) * ay, r = 0.5 * (fabs(ax) + fabs(ay));
        if (hi <= c - r + eps * len || lo >= c + r - eps * len) return false;
    }
    return true;
}

/* Triangle t's corners in texel units of the stacked pages (page p's rows start at p * h: the texel
 * index page*w*h + y*w + x is then y'*w + x). page may be NULL (one page). */
static void tri_texels(const float (*uv)[2], const uint32_t *page, size_t t, uint32_t w, uint32_t h,
                       double out[3][2]) {
    const double y0 = page ? (double)page[t] * h : 0.0;
    for (int k = 0; k < 3; ++k) {
        out[k][0] = (double)uv[3 * t + (size_t)k][0] * w;
        out[k][1] = (double)uv[3 * t + (size_t)k][1] * h + y0;
    }
}

/* Area and centroid of the part of triangle t (texel units) inside the texel square at (x0, y0):
 * Sutherland-Hodgman against the square's four sides. */
static double clip_tri_box(const double t[3][2], double x0, double y0, double centroid[2]) {
    double a[9][2], b[9][2];
    int n = 3;
    memcpy(a, t, sizeof(double[3][2]));
    for (int side = 0; side < 4 && n > 0; ++side) {
        const int axis = side & 1;
        const double lim = side < 2 ? (axis ? y0 : x0) : (axis ? y0 + 1.0 : x0 + 1.0), sgn = side < 2 ? 1.0 : -1.0;
        int m = 0;
        for (int i = 0; i < n; ++i) {
            const double *p = a[i], *q = a[(i + 1) % n];
            const double dp = sgn * (p[axis] - lim), dq = sgn * (q[axis] - lim);
            if (dp >= 0.0) memcpy(b[m++], p, sizeof b[0]);
            if ((dp >= 0.0) != (dq >= 0.0) && m < 9) {
                const double f = dp / (dp - dq);
                b[m][0] = p[0] + f * (q[0] - p[0]);
                b[m][1] = p[1] + f * (q[1] - p[1]);
                m++;
            }
        }
        n = m;
        memcpy(a, b, (size_t)m * sizeof a[0]);
    }
    double area = 0.0, cx = 0.0, cy = 0.0;
    for (int i = 0; i < n; ++i) {
        const double *p = a[i], *q = a[(i + 1) % n];
        const double c = p[0] * q[1] - q[0] * p[1];
        area += c;
        cx += (p[0] + q[0]) * c;
        cy += (p[1] + q[1]) * c;
    }
    area *= 0.5;
    if (!(fabs(area) > 0.0)) return 0.0;
    centroid[0] = cx / (6.0 * area);
    centroid[1] = cy / (6.0 * area);
    return fabs(area);
}

/* owner[texel] = triangle whose UV triangle overlaps the texel and is nearest to the texel's reference
 * point: ref[texel] (texel units) when given, else the texel centre. Returns the number of owned
 * texels. With `foot` (3 doubles per texel, zeroed here), also sums the texel's footprint: the area of
 * every overlapping triangle inside the texel and its area-weighted centroid. */
static uint32_t rasterise(uint32_t tri_count, const float (*uv)[2], const uint32_t *page, uint32_t w, uint32_t h,
                          uint32_t pages, const double (*ref)[2], uint32_t *owner, float *dist, double (*foot)[3]) {
    const size_t n = (size_t)w * h * pages;
    for (size_t i = 0; i < n; ++i) {
        owner[i] = NONE;
        dist[i] = INFINITY;
        if (foot) foot[i][0] = foot[i][1] = foot[i][2] = 0.0;
    }
    uint32_t covered = 0;
    for (uint32_t t = 0; t < tri_count; ++t) {
        double tc[3][2];
        tri_texels(uv, page, t, w, h, tc);
        const long ylo = page ? (long)page[t] * (long)h : 0, yhi = ylo + (long)h - 1; /* its page's rows */
        double mnx = fmin(fmin(tc[0][0], tc[1][0]), tc[2][0]), mxx = fmax(fmax(tc[0][0], tc[1][0]), tc[2][0]);
        double mny = fmin(fmin(tc[0][1], tc[1][1]), tc[2][1]), mxy = fmax(fmax(tc[0][1], tc[1][1]), tc[2][1]);
        long x0 = (long)floor(mnx), x1 = (long)floor(mxx), y0 = (long)floor(mny), y1 = (long)floor(mxy);
        if (x0 < 0) x0 = 0;
        if (y0 < ylo) y0 = ylo;
        if (x1 > (long)w - 1) x1 = (long)w - 1;
        if (y1 > yhi) y1 = yhi;
        for (long y = y0; y <= y1; ++y)
            for (long x = x0; x <= x1; ++x) {
                if (!tri_box((const double(*)[2])tc, (double)x, (double)y, 1e-4)) continue;
                size_t i = (size_t)y * w + (size_t)x;
                double p[2] = {x + 0.5, y + 0.5}, bary[3];
                if (ref) memcpy(p, ref[i], sizeof p);
                float d2 = (float)closest_bary(p, (const double(*)[2])tc, bary);
                if (d2 < dist[i]) {
                    covered += owner[i] == NONE;
                    dist[i] = d2;
                    owner[i] = t;
                }
                if (foot) {
                    double c[2] = {0.0, 0.0};
                    const double a = clip_tri_box((const double(*)[2])tc, (double)x, (double)y, c);
                    foot[i][0] += a;
                    foot[i][1] += a * c[0];
                    foot[i][2] += a * c[1];
                }
            }
    }
    return covered;
}

/* A texel's cache (or detail point) stands for the surface the texel covers: rasterise once to sum
 * each texel's footprint (foot, scratch of w*h), take its area-weighted centroid as the texel's
 * reference point (texels with no footprint area keep their centre), and rasterise again to find the
 * triangle nearest to it. Returns the covered texel count; *footprint = the covered surface area in
 * texels (overlapping charts' triangles count once). */
static uint32_t place_texels(uint32_t tri_count, const float (*uv)[2], const uint32_t *page, uint32_t w, uint32_t h,
                             uint32_t pages, uint32_t *owner, float *dist, double (*ref)[2], double (*foot)[3],
                             double *footprint) {
    rasterise(tri_count, uv, page, w, h, pages, NULL, owner, dist, foot);
    *footprint = 0.0;
    for (size_t i = 0; i < (size_t)w * h * pages; ++i) {
        *footprint += foot[i][0] < 1.0 ? foot[i][0] : 1.0;
        if (foot[i][0] > 0.0) {
            ref[i][0] = foot[i][1] / foot[i][0];
            ref[i][1] = foot[i][2] / foot[i][0];
        } else {
            ref[i][0] = (double)(i % w) + 0.5;
            ref[i][1] = (double)(i / w) + 0.5;
        }
    }
    return rasterise(tri_count, uv, page, w, h, pages, (const double(*)[2])ref, owner, dist, NULL);
}

/* Unorm16 rounding, as the bake stores lightmap UVs: rasterise what the host will sample. */
static float quantise(float x) {
    if (!(x > 0.0f)) return 0.0f;
    if (x >= 1.0f) return 1.0f;
    return (float)lrintf(x * 65535.0f) / 65535.0f;
}

typedef struct lm_job {
    const glow__scene *scene;
    const glow__rt *rt;
    const float (*uv)[2];
    const uint32_t *page;   /* per triangle, or NULL */
    uint32_t w, h;          /* a page's */
    const uint32_t *texel;  /* candidate texels */
    const uint32_t *owner;
    const double (*ref)[2]; /* per texel: where its cache goes (texel units), see lm_try */
    float offset;
    double dirs[LM_RAYS][3];
    float (*pos)[3], (*nrm)[3];
    uint8_t *valid;
} lm_job;

static void lm_range(void *p, uint32_t begin, uint32_t end, uint32_t worker) {
    lm_job *j = p;
    (void)worker;
    for (uint32_t i = begin; i < end; ++i) {
        uint32_t texel = j->texel[i], t = j->owner[texel];
        double tc[3][2], bary[3];
        tri_texels(j->uv, j->page, t, j->w, j->h, tc);
        closest_bary(j->ref[texel], (const double(*)[2])tc, bary);
        const float(*P)[3] = j->scene->pos + 3 * (size_t)t;
        double pos[3], cen[3], e1[3], e2[3], n[3], dc = 0.0;
        for (int k = 0; k < 3; ++k) {
            pos[k] = bary[0] * P[0][k] + bary[1] * P[1][k] + bary[2] * P[2][k];
            cen[k] = ((double)P[0][k] + P[1][k] + P[2][k]) / 3.0;
            dc += (cen[k] - pos[k]) * (cen[k] - pos[k]);
            e1[k] = (double)P[1][k] - P[0][k];
            e2[k] = (double)P[2][k] - P[0][k];
        }
        /* Off the triangle's edges by ~2 offsets (towards the centroid): a point on an edge where
         * two walls meet lies in the other wall's plane and sees half the room from behind. */
        dc = sqrt(dc);
        if (dc > 0.0) {
            double lambda = fmin(0.5, 2.0 * j->offset / dc);
            for (int k = 0; k < 3; ++k) pos[k] += lambda * (cen[k] - pos[k]);
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0.0) && j->scene->nrm) { /* no geometric normal: the shading normals' mean */
            for (int k = 0; k < 3; ++k) {
                const float(*N)[3] = j->scene->nrm + 3 * (size_t)t;
                n[k] = (double)N[0][k] + N[1][k] + N[2][k];
            }
            l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        }
        if (l > 0.0) {
            for (int k = 0; k < 3; ++k) n[k] /= l;
        } else {
            n[0] = 0.0;
            n[1] = 1.0;
            n[2] = 0.0;
        }
        float o[3];
        for (int k = 0; k < 3; ++k) {
            o[k] = (float)(pos[k] + j->offset * n[k]);
            j->pos[i][k] = o[k];
            j->nrm[i][k] = (float)n[k];
        }
        double tb[3], bb[3];
        glow__tangent_frame(n, tb, bb);
        uint32_t hits = 0, back = 0;
        for (uint32_t r = 0; r < LM_RAYS; ++r) {
            const double *d = j->dirs[r];
            float dir[3];
            for (int k = 0; k < 3; ++k) dir[k] = (float)(d[0] * tb[k] + d[1] * bb[k] + d[2] * n[k]);
            glow__hit hit = glow__rt_intersect(j->rt, o, dir, 0.0f, INFINITY);
            if (hit.t == INFINITY) continue;
            ++hits;
            back += hit.back_face;
        }
        j->valid[i] = !(back > LM_INVALID_FRACTION * hits && 4 * back >= LM_RAYS);
    }
}

/* ------------------------------------------------------------------ surfel feedback */
typedef struct fb_job {
    const glow__scene *scene;
    const glow__surfels *surfels;
    const glow__caches *c;
} fb_job;

static uint32_t nearest_grid_cache(const glow__caches *c, const float p[3]) {
    const uint32_t *d = c->grid_dims;
    long cc[3];
    for (int a = 0; a < 3; ++a) {
        double f = floor(((double)p[a] - c->grid_origin[a]) / c->grid_spacing + 0.5);
        cc[a] = f < 0.0 ? 0 : f > d[a] - 1.0 ? (long)d[a] - 1 : (long)f;
    }
    long rmax = (long)(d[0] > d[1] ? (d[0] > d[2] ? d[0] : d[2]) : (d[1] > d[2] ? d[1] : d[2]));
    uint32_t best = NONE;
    double best_d2 = INFINITY;
    for (long r = 0; r <= rmax; ++r) {
        for (long z = cc[2] - r; z <= cc[2] + r; ++z) {
            if (z < 0 || z >= (long)d[2]) continue;
            for (long y = cc[1] - r; y <= cc[1] + r; ++y) {
                if (y < 0 || y >= (long)d[1]) continue;
                bool shell_yz = labs(z - cc[2]) == r || labs(y - cc[1]) == r;
                for (long x = cc[0] - r; x <= cc[0] + r; x += (shell_yz || r == 0) ? 1 : 2 * r) {
                    if (x < 0 || x >= (long)d[0]) continue;
                    uint32_t v = c->grid_map[((size_t)z * d[1] + (size_t)y) * d[0] + (size_t)x];
                    if (v == GLOW_MAP_EMPTY || (v & GLOW_MAP_COPY_BIT)) continue;
                    const float *q = c->caches[v].pos;
                    double dx = (double)q[0] - p[0], dy = (double)q[1] - p[1], dz = (double)q[2] - p[2];
                    double d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 < best_d2 || (d2 == best_d2 && v < best)) {
                        best_d2 = d2;
                        best = v;
                    }
                }
            }
        }
        double reach = (r + 0.5) * c->grid_spacing;
        if (best != NONE && best_d2 <= reach * reach) break;
    }
    return best;
}

static void fb_range(void *p, uint32_t begin, uint32_t end, uint32_t worker) {
    fb_job *j = p;
    const glow__caches *c = j->c;
    (void)worker;
    for (uint32_t i = begin; i < end; ++i) {
        const glow__surfel *s = &j->surfels->s[i];
        uint32_t fb = NONE;
        if (c->lm_map && s->tri < j->scene->tri_count) {
            const float(*uv)[2] = c->lm_uv + 3 * (size_t)s->tri;
            double b1 = s->bary[0], b2 = s->bary[1], b0 = 1.0 - b1 - b2;
            double u = b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0];
            double v = b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1];
            double fx = floor(u * c->lm_width), fy = floor(v * c->lm_height);
            uint32_t x = fx < 0.0 ? 0 : fx >= c->lm_width ? c->lm_width - 1 : (uint32_t)fx;
            uint32_t y = fy < 0.0 ? 0 : fy >= c->lm_height ? c->lm_height - 1 : (uint32_t)fy;
            const size_t pg = c->lm_page ? c->lm_page[s->tri] : 0u;
            uint32_t m = c->lm_map[(pg * c->lm_height + y) * c->lm_width + x];
            if (m != GLOW_MAP_EMPTY) fb = m & GLOW_MAP_INDEX_MASK;
        }
        if (fb == NONE && c->grid_cache_count) fb = nearest_grid_cache(c, s->pos);
        if (fb == NONE) { /* no grid cache at all: the nearest lightmap cache */
            double best = INFINITY;
            for (uint32_t k = c->grid_cache_count; k < c->count; ++k) {
                const float *q = c->caches[k].pos;
                double dx = (double)q[0] - s->pos[0], dy = (double)q[1] - s->pos[1], dz = (double)q[2] - s->pos[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                if (d2 < best) {
                    best = d2;
                    fb = k;
                }
            }
        }
        j->c->surfel_feedback[i] = fb == NONE ? 0u : fb;
    }
}

/* ------------------------------------------------------------------ build */
void glow__caches_free(glow__caches *c) {
    if (!c) return;
    free(c->caches);
    free(c->grid_map);
    free(c->grid_brick_of_cell);
    free(c->grid_bricks);
    free(c->grid_fine_pos);
    free(c->grid_fine_cell);
    free(c->lm_map);
    free(c->lm_uv);
    free(c->lm_page);
    free(c->surfel_feedback);
    free(c->detail_texel);
    free(c->detail_pos);
    free(c->detail_nrm);
    memset(c, 0, sizeof *c);
}

typedef struct lm_state {
    float (*uv)[2];
    uint32_t *page;   /* [tri_count] */
    uint32_t w, h, pages;
    uint32_t max_side;
    float density;
    uint32_t *owner;
    float *dist;
    double (*ref)[2]; /* per texel: the centroid of its footprint (texel units), where its cache goes */
    double footprint; /* Σ over covered texels of the surface area inside them (texel units) */
    uint32_t covered;
    glow__chart_pack_stats pack; /* small charts merged at the density used */
} lm_state;

static void lm_state_free(lm_state *s) {
    free(s->uv);
    free(s->page);
    free(s->owner);
    free(s->dist);
    free(s->ref);
    memset(s, 0, sizeof *s);
}

/* Lays out the lightmap at density d (charts: packed; uv1: atlas side d/sqrt(uv area per m²)) and
 * rasterises it. */
static glow_result lm_try(const glow__scene *scene, const glow__chart_set *cs, double uv_ratio, double d,
                          glow__log *log, lm_state *st) {
    const uint32_t n = scene->tri_count;
    glow_result r = GLOW_OK;
    if (cs) {
        float used = 0.0f;
        r = glow__charts_pack_pages(cs, (float)d, LM_PADDING, st->max_side, GLOW__CHART_MAX_PAGES, log, st->uv, st->page,
                                    &st->pages, &st->w, &st->h, &used, &st->pack);
        if (r != GLOW_OK) return r;
        st->density = used;
    } else {
        double side = d / sqrt(uv_ratio);
        double s4 = ceil(side / 4.0 - 1e-9) * 4.0;
        if (!(s4 >= 4.0)) s4 = 4.0;
        if (s4 > st->max_side) { /* (a mesh's own UV set is one atlas) */
            glow__warnf(log, "%s: caches: the lightmap at %g texels per unit would be %.0f texels a side; using %u",
                        scene->source, d, s4, st->max_side);
            s4 = st->max_side;
        }
        st->w = st->h = (uint32_t)s4;
        st->pages = 1;
        memset(st->page, 0, (size_t)n * sizeof *st->page);
        st->density = (float)(s4 * sqrt(uv_ratio));
        memcpy(st->uv, scene->uv1, 3 * (size_t)n * sizeof *st->uv);
    }
    for (size_t i = 0; i < 3 * (size_t)n; ++i) {
        st->uv[i][0] = quantise(st->uv[i][0]);
        st->uv[i][1] = quantise(st->uv[i][1]);
    }
    free(st->owner);
    free(st->dist);
    free(st->ref);
    st->ref = NULL;
    size_t texels = (size_t)st->w * st->h * st->pages;
    st->owner = malloc(texels * sizeof *st->owner);
    st->dist = malloc(texels * sizeof *st->dist);
    st->ref = malloc(texels * sizeof *st->ref);
    double(*foot)[3] = malloc(texels * sizeof *foot);
    if (!st->owner || !st->dist || !st->ref || !foot) {
        free(foot);
        glow__errorf(log, "%s: caches: out of memory for a %ux%u lightmap (%u pages)", scene->source, st->w, st->h,
                     st->pages);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    /* A texel's cache stands for the surface the texel covers, so it goes to the centroid of that
     * footprint (on the triangle nearest to it), not to the point nearest to the texel centre: with
     * 4757 charts for 9245 texels in the Dabrovic Sponza most texels overhang their chart, and the
     * centre-nearest point lay on the chart's border, often a crease, whose irradiance is not the
     * texel's. Texels with no footprint area (slivers) keep their centre. */
    st->covered = place_texels(n, (const float(*)[2])st->uv, st->page, st->w, st->h, st->pages, st->owner, st->dist,
                               st->ref, foot, &st->footprint);
    free(foot);
    return GLOW_OK;
}

/* ------------------------------------------------------------------ texel density per chart */
/* A lightmap cache stands for its whole texel; where surfaces face each other within the near field
 * (an arch's soffit and springing, a capital, a pier's foot) light changes within a texel, and there
 * the texels should be finer than on open walls and floors, as the surfels are (surfels.c, adaptive
 * density). Each generated chart gets the fraction f of CONC_RAYS cosine-distributed rays, cast from
 * area-proportional points on its surface (CONC_POINTS_PER_TEXEL per texel of the budget), that meet
 * a surface within the reach, and its texels' area density is scaled by 1 + (F - 1) f (the linear
 * density by the square root); the density search then meets the texel budget at a lower base
 * density, which open ground gets. */
#define CONC_RAYS GLOW__NEAR_RAYS
#define CONC_POINTS_PER_TEXEL 16.0

typedef struct conc_ctx {
    const glow__scene *scene;
    const glow__rt *rt;
    const uint32_t *pt_tri;
    uint32_t *hits;
    float reach, eps;
} conc_ctx;

static uint32_t conc_hash(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    return x ^ (x >> 16);
}

static void conc_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    conc_ctx *c = vctx;
    for (uint32_t i = begin; i < end; ++i) {
        const uint32_t t = c->pt_tri[i];
        const float(*p)[3] = c->scene->pos + 3 * (size_t)t;
        double u = (conc_hash(2 * i + 1) + 0.5) / 4294967296.0, v = (conc_hash(2 * i + 2) + 0.5) / 4294967296.0;
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        float org[3];
        double e1[3], e2[3], n[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)p[1][k] - p[0][k];
            e2[k] = (double)p[2][k] - p[0][k];
            org[k] = (float)(p[0][k] + u * e1[k] + v * e2[k]);
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        const double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0.0)) {
            c->hits[i] = 0;
            continue;
        }
        for (int k = 0; k < 3; ++k) n[k] /= l;
        const double phi0 = conc_hash(i ^ 0x9e3779b9u) * (2.0 * GLOW__PI / 4294967296.0);
        c->hits[i] = glow__near_hits(c->rt, org, n, phi0, c->reach, c->eps);
    }
}

/* Fills cs->scale (see above) from `points` area-proportional points over the whole scene. */
static glow_result chart_concavity(const glow__scene *scene, const glow__rt *rt, glow__chart_set *cs, double area,
                                   uint32_t points, float adapt, float reach, glow__pool *pool, glow__log *log) {
    const uint32_t n = scene->tri_count;
    uint32_t *pt_tri = malloc(((size_t)points + 1) * sizeof *pt_tri);
    uint32_t *hits = malloc(((size_t)points + 1) * sizeof *hits);
    uint32_t *chart_of = malloc(((size_t)n + 1) * sizeof *chart_of);
    double *sum = calloc((size_t)cs->chart_count + 1, sizeof *sum);
    double *cnt = calloc((size_t)cs->chart_count + 1, sizeof *cnt);
    cs->scale = malloc(((size_t)cs->chart_count + 1) * sizeof *cs->scale);
    if (!pt_tri || !hits || !chart_of || !sum || !cnt || !cs->scale) {
        free(pt_tri);
        free(hits);
        free(chart_of);
        free(sum);
        free(cnt);
        glow__errorf(log, "%s: caches: out of memory for the charts' concavity", scene->source);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    for (uint32_t c = 0; c < cs->chart_count; ++c)
        for (uint32_t j = cs->chart_start[c]; j < cs->chart_start[c + 1]; ++j) chart_of[cs->chart_tris[j]] = c;
    glow__spawn_tris(scene, area, points, pt_tri);
    float ext[3];
    glow__sub(scene->bounds_max, scene->bounds_min, ext);
    const float diag = sqrtf(glow__dot(ext, ext));
    conc_ctx cc = {.scene = scene, .rt = rt, .pt_tri = pt_tri, .hits = hits, .reach = reach,
                   .eps = 1e-4f * (diag > 0.0f ? diag : 1.0f)};
    glow__parallel_for(pool, points, 0, conc_range, &cc);
    for (uint32_t i = 0; i < points; ++i) {
        const uint32_t c = chart_of[pt_tri[i]];
        sum[c] += hits[i];
        cnt[c] += CONC_RAYS;
    }
    double fsum = 0.0, ssum = 0.0;
    for (uint32_t c = 0; c < cs->chart_count; ++c) {
        const double f = cnt[c] > 0.0 ? sum[c] / cnt[c] : 0.0;
        cs->scale[c] = (float)sqrt(1.0 + (adapt - 1.0) * f);
        fsum += sum[c];
        ssum += cnt[c];
    }
    glow__infof(log, "%s: caches: texel density follows the charts' concavity (up to %gx the area density; "
                "%.1f %% of %u points' rays meet a surface within %.3g)", scene->source, (double)adapt,
                ssum > 0.0 ? 100.0 * fsum / ssum : 0.0, points, (double)reach);
    free(pt_tri);
    free(hits);
    free(chart_of);
    free(sum);
    free(cnt);
    return GLOW_OK;
}

static glow_result build_lightmap_layout(const glow__scene *scene, const glow__rt *rt, const glow__cache_settings *set,
                                         glow__pool *pool, glow__log *log, glow__caches *out, lm_state *st) {
    const uint32_t n = scene->tri_count;
    st->uv = malloc(3 * (size_t)n * sizeof *st->uv);
    st->page = calloc((size_t)n + 1, sizeof *st->page);
    st->max_side = set->lightmap_max_size ? set->lightmap_max_size : GLOW__CHART_MAX_ATLAS;
    if (!st->uv || !st->page) {
        glow__errorf(log, "%s: caches: out of memory for lightmap UVs", scene->source);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    double area = 0.0, uv_area = 0.0;
    for (uint32_t t = 0; t < n; ++t) {
        const float(*p)[3] = scene->pos + 3 * (size_t)t;
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)p[1][k] - p[0][k];
            e2[k] = (double)p[2][k] - p[0][k];
        }
        double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
               cz = e1[0] * e2[1] - e1[1] * e2[0];
        area += 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
        if (scene->uv1) {
            const float(*q)[2] = scene->uv1 + 3 * (size_t)t;
            uv_area += 0.5 * fabs(((double)q[1][0] - q[0][0]) * ((double)q[2][1] - q[0][1]) -
                                  ((double)q[1][1] - q[0][1]) * ((double)q[2][0] - q[0][0]));
        }
    }
    if (!(area > 0.0)) area = 1.0;
    glow__chart_set cs = {0};
    double uv_ratio = 0.0;
    bool use_uv1 = scene->uv1 != NULL;
    if (use_uv1) {
        uint32_t outside = 0;
        for (size_t i = 0; i < 3 * (size_t)n; ++i)
            for (int k = 0; k < 2; ++k) {
                float v = scene->uv1[i][k];
                outside += !(v >= -1e-4f && v <= 1.0f + 1e-4f);
            }
        if (outside)
            glow__warnf(log, "%s: caches: %u lightmap UV coordinates lie outside [0,1]; clamped", scene->source,
                        outside);
        uv_ratio = uv_area / area;
        if (!(uv_ratio > 0.0)) {
            glow__warnf(log, "%s: caches: the second UV set covers no area; generating lightmap charts",
                        scene->source);
            use_uv1 = false;
        }
    }
    if (!use_uv1) {
        glow_result r = glow__charts_segment(scene, rt, log, &cs);
        if (r != GLOW_OK) return r;
        out->chart_count = cs.chart_count;
        if (set->texel_adapt > 1.0f && set->adapt_reach > 0.0f && cs.chart_count) {
            const double target = set->target_lightmap ? set->target_lightmap : DEFAULT_TARGET_LIGHTMAP;
            const double pts = fmin(fmax(CONC_POINTS_PER_TEXEL * target, 1.0), 4.0e6);
            r = chart_concavity(scene, rt, &cs, area, (uint32_t)pts, set->texel_adapt, set->adapt_reach, pool, log);
            if (r != GLOW_OK) {
                glow__charts_free(&cs);
                return r;
            }
        }
    }
    const glow__chart_set *csp = use_uv1 ? NULL : &cs;
    glow_result r;
    if (set->texel_density > 0.0f) {
        r = lm_try(scene, csp, uv_ratio, set->texel_density, log, st);
    } else {
        const double target = set->target_lightmap ? set->target_lightmap : DEFAULT_TARGET_LIGHTMAP;
        double d = sqrt(target / area), best_d = d, best_err = INFINITY, last_d = d;
        r = GLOW_OK;
        for (int round = 0; round < DENSITY_ROUNDS; ++round) {
            r = lm_try(scene, csp, uv_ratio, d, log, st);
            if (r != GLOW_OK) break;
            last_d = d;
            double q = (st->covered + 1.0) / target, err = q > 1.0 ? q : 1.0 / q;
            if (err < best_err) {
                best_err = err;
                best_d = d;
            }
            if (err < 1.2) break;
            d *= fmin(fmax(sqrt(1.0 / q), 0.25), 4.0);
        }
        if (r == GLOW_OK && best_d != last_d) r = lm_try(scene, csp, uv_ratio, best_d, log, st);
        if (r == GLOW_OK && st->covered > 1.2 * target) /* the budget is exceeded: say so (issue 16, item 5) */
            glow__warnf(log,
                        "%s: caches: the lightmap holds %u caches, %.1fx its budget of %.0f (--lightmap-caches): "
                        "%u chart footprints take a texel or more each even at %.3g texels per unit; raise the budget",
                        scene->source, st->covered, st->covered / target, target, csp ? st->pack.slots : 0u,
                        (double)st->density);
    }
    double smax = 1.0;
    for (uint32_t c = 0; cs.scale && c < cs.chart_count; ++c) smax = fmax(smax, cs.scale[c]);
    glow__charts_free(&cs);
    if (r != GLOW_OK) return r;
    out->lm_width = st->w;
    out->lm_height = st->h;
    out->lm_pages = st->pages;
    out->texel_density = st->density;
    out->texel_density_max = (float)(st->density * smax);
    return GLOW_OK;
}

/* Lightmap detail texels (links.c "Lightmap detail"): the atlas rasterised again at factor x its
 * resolution, each covered texel's point placed as a lightmap cache's (the centroid of its
 * footprint, off the edges, lifted) and kept when it sees no back faces. They are no caches: the
 * linker gives each a few links to the surfels near it. Returns GLOW_OK with no detail texels when
 * the fine grid would exceed MAX_DETAIL_TEXELS even at 2 a side (warned). The runtime keeps the whole
 * grid as one RGBA32F plane (16 bytes a texel, a texture on the GPU): 4M texels are 64 MB; Sponza's
 * default is 0.35M. A larger grid takes fewer detail texels a side first. */
#define MAX_DETAIL_TEXELS (4u << 20)
static glow_result build_detail(const glow__scene *scene, const glow__rt *rt, glow__pool *pool, glow__log *log,
                                uint32_t factor, float offset, glow__caches *out) {
    const uint32_t asked = factor;
    const uint64_t P = out->lm_pages ? out->lm_pages : 1u;
    while (factor > 2 && (uint64_t)out->lm_width * factor * out->lm_height * factor * P > MAX_DETAIL_TEXELS) factor--;
    const uint64_t fw = (uint64_t)out->lm_width * factor, fh = (uint64_t)out->lm_height * factor;
    if (fw * fh * P > MAX_DETAIL_TEXELS) {
        glow__warnf(log, "%s: caches: a lightmap detail of %llux%llu texels would exceed %u; no detail", scene->source,
                    (unsigned long long)fw, (unsigned long long)fh, MAX_DETAIL_TEXELS);
        return GLOW_OK;
    }
    if (factor != asked)
        glow__warnf(log, "%s: caches: the %ux%u lightmap takes %u detail texels a side, not %u (at most %u detail texels)",
                    scene->source, out->lm_width, out->lm_height, factor, asked, MAX_DETAIL_TEXELS);
    const size_t n = (size_t)(fw * fh * P);
    const uint32_t tris = scene->tri_count;
    uint32_t *owner = malloc(n * sizeof *owner), *cand = NULL;
    float *dist = malloc(n * sizeof *dist);
    double(*ref)[2] = malloc(n * sizeof *ref), (*foot)[3] = malloc(n * sizeof *foot);
    lm_job j = {0};
    glow_result r = GLOW_OK;
    if (!owner || !dist || !ref || !foot) goto oom;
    double unused_footprint;
    const uint32_t covered = place_texels(tris, (const float(*)[2])out->lm_uv, out->lm_page, (uint32_t)fw, (uint32_t)fh,
                                          (uint32_t)P, owner, dist, ref, foot, &unused_footprint);
    cand = malloc(((size_t)covered + 1) * sizeof *cand);
    j.pos = malloc(((size_t)covered + 1) * sizeof *j.pos);
    j.nrm = malloc(((size_t)covered + 1) * sizeof *j.nrm);
    j.valid = malloc((size_t)covered + 1);
    if (!cand || !j.pos || !j.nrm || !j.valid) goto oom;
    uint32_t m = 0;
    for (size_t i = 0; i < n; ++i)
        if (owner[i] != NONE) cand[m++] = (uint32_t)i;
    j.scene = scene;
    j.rt = rt;
    j.uv = (const float(*)[2])out->lm_uv;
    j.page = out->lm_page;
    j.w = (uint32_t)fw;
    j.h = (uint32_t)fh;
    j.texel = cand;
    j.owner = owner;
    j.ref = (const double(*)[2])ref;
    j.offset = offset;
    fibonacci_hemisphere(LM_RAYS, j.dirs);
    glow__parallel_for(pool, m, 64, lm_range, &j);
    uint32_t k = 0;
    for (uint32_t i = 0; i < m; ++i) k += j.valid[i];
    out->detail_texel = malloc(((size_t)k + 1) * sizeof *out->detail_texel);
    out->detail_pos = malloc(((size_t)k + 1) * sizeof *out->detail_pos);
    out->detail_nrm = malloc(((size_t)k + 1) * sizeof *out->detail_nrm);
    if (!out->detail_texel || !out->detail_pos || !out->detail_nrm) goto oom;
    for (uint32_t i = 0, q = 0; i < m; ++i) {
        if (!j.valid[i]) continue;
        out->detail_texel[q] = cand[i];
        memcpy(out->detail_pos[q], j.pos[i], sizeof out->detail_pos[q]);
        memcpy(out->detail_nrm[q], j.nrm[i], sizeof out->detail_nrm[q]);
        q++;
    }
    out->detail_factor = factor;
    out->detail_width = (uint32_t)fw;
    out->detail_height = (uint32_t)fh;
    out->detail_count = k;
    glow__infof(log, "%s: caches: lightmap detail %ux%u (%u per texel side): %u texels cover a surface, %u invalid",
                scene->source, out->detail_width, out->detail_height, factor, k, m - k);
    goto done;
oom:
    glow__errorf(log, "%s: caches: out of memory for the lightmap detail", scene->source);
    r = GLOW_ERROR_OUT_OF_MEMORY;
done:
    free(owner);
    free(dist);
    free(ref);
    free(foot);
    free(cand);
    free(j.pos);
    free(j.nrm);
    free(j.valid);
    return r;
}

glow_result glow__caches_build(const glow__scene *scene, const glow__rt *rt, const glow__surfels *surfels,
                               const glow__cache_settings *settings, glow__pool *pool, glow__log *log,
                               glow__caches *out) {
    memset(out, 0, sizeof *out);
    if (!scene || !rt || !settings) {
        glow__errorf(log, "caches: scene, ray tracer and settings are required");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!(settings->grid_spacing >= 0.0f) || !isfinite(settings->grid_spacing) ||
        !(settings->texel_density >= 0.0f) || !isfinite(settings->texel_density)) {
        glow__errorf(log, "%s: caches: grid spacing %g and texel density %g must be finite and >= 0", scene->source,
                     (double)settings->grid_spacing, (double)settings->texel_density);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_result r;
    uint8_t *inside = NULL;
    lm_state st = {0};
    uint32_t *cand = NULL;
    uint8_t *eligible = NULL;
    lm_job lj = {0};

    r = build_grid(scene, rt, settings, pool, log, out, &inside);
    if (r != GLOW_OK) goto fail;
    const uint32_t coarse_count = out->grid_cache_count;
    if (out->grid_refine >= 2) {
        r = glow__grid_refine(scene, rt, out->grid_refine, pool, log, out);
        if (r != GLOW_OK) goto fail;
        out->grid_cache_count += out->grid_fine_count;
    }

    uint32_t lm_candidates = 0;
    if (scene->tri_count) {
        r = build_lightmap_layout(scene, rt, settings, pool, log, out, &st);
        if (r != GLOW_OK) goto fail;
        const size_t texels = (size_t)st.w * st.h * st.pages;
        cand = malloc(((size_t)st.covered + 1) * sizeof *cand);
        lj.pos = malloc(((size_t)st.covered + 1) * sizeof *lj.pos);
        lj.nrm = malloc(((size_t)st.covered + 1) * sizeof *lj.nrm);
        lj.valid = malloc((size_t)st.covered + 1);
        if (!cand || !lj.pos || !lj.nrm || !lj.valid) goto oom;
        for (size_t i = 0; i < texels; ++i)
            if (st.owner[i] != NONE) cand[lm_candidates++] = (uint32_t)i;
        double diag = 0.0;
        for (int a = 0; a < 3; ++a) {
            double e = (double)scene->bounds_max[a] - scene->bounds_min[a];
            diag += e * e;
        }
        diag = sqrt(diag);
        lj.scene = scene;
        lj.rt = rt;
        lj.uv = (const float(*)[2])st.uv;
        lj.page = st.page;
        lj.w = st.w;
        lj.h = st.h;
        lj.texel = cand;
        lj.owner = st.owner;
        lj.ref = (const double(*)[2])st.ref;
        lj.offset = (float)(diag > 0.0 ? 1e-4 * diag : 1e-6);
        fibonacci_hemisphere(LM_RAYS, lj.dirs);
        glow__parallel_for(pool, lm_candidates, 64, lm_range, &lj);
    }

    /* caches: grid first, then valid texels in texel order */
    uint32_t lm_count = 0;
    for (uint32_t i = 0; i < lm_candidates; ++i) lm_count += lj.valid[i];
    out->lm_invalid = lm_candidates - lm_count;
    out->lm_cache_count = lm_count;
    out->count = out->grid_cache_count + lm_count;
    out->caches = calloc((size_t)out->count + 1, sizeof *out->caches);
    if (!out->caches) goto oom;
    {
        const uint32_t *d = out->grid_dims;
        for (uint32_t c = 0, k = 0; c < d[0] * d[1] * d[2]; ++c) {
            if (inside[c]) continue;
            glow__cache *ca = &out->caches[k++];
            uint32_t x = c % d[0], y = (c / d[0]) % d[1], z = c / (d[0] * d[1]);
            ca->pos[0] = out->grid_origin[0] + out->grid_spacing * (float)x;
            ca->pos[1] = out->grid_origin[1] + out->grid_spacing * (float)y;
            ca->pos[2] = out->grid_origin[2] + out->grid_spacing * (float)z;
            ca->kind = GLOW_CACHE_KIND_GRID;
            ca->texel = c;
        }
        for (uint32_t i = 0; i < out->grid_fine_count; ++i) { /* the refined grid's own points */
            glow__cache *ca = &out->caches[coarse_count + i];
            memcpy(ca->pos, out->grid_fine_pos[i], sizeof ca->pos);
            ca->kind = GLOW_CACHE_KIND_GRID;
            ca->texel = out->grid_fine_cell[i];
        }
        free(out->grid_fine_pos);
        free(out->grid_fine_cell);
        out->grid_fine_pos = NULL;
        out->grid_fine_cell = NULL;
        int nb[26][3];
        uint32_t nbn = neighbour_offsets(3, nb);
        if (!dilate(out->grid_map, d, inside, (const int(*)[3])nb, nbn, GRID_DILATE_PASSES)) goto oom;
    }
    if (scene->tri_count) {
        const size_t texels = (size_t)st.w * st.h * st.pages;
        out->lm_map = malloc(texels * sizeof *out->lm_map);
        eligible = calloc(texels, 1);
        if (!out->lm_map || !eligible) goto oom;
        for (size_t i = 0; i < texels; ++i) out->lm_map[i] = GLOW_MAP_EMPTY;
        for (uint32_t i = 0, k = out->grid_cache_count; i < lm_candidates; ++i) {
            if (!lj.valid[i]) continue;
            glow__cache *ca = &out->caches[k];
            memcpy(ca->pos, lj.pos[i], sizeof ca->pos);
            memcpy(ca->nrm, lj.nrm[i], sizeof ca->nrm);
            ca->kind = GLOW_CACHE_KIND_LIGHTMAP;
            ca->texel = cand[i];
            out->lm_map[cand[i]] = k++;
        }
        int nb[26][3];
        uint32_t nbn = neighbour_offsets(2, nb);
        const uint32_t dims[3] = {st.w, st.h, st.pages}; /* 2-D neighbours: copies stay within their page */
        /* invalid texels from the valid ones around them (as far as it takes), then the gutter */
        for (size_t i = 0; i < texels; ++i) eligible[i] = st.owner[i] != NONE;
        if (!dilate(out->lm_map, dims, eligible, (const int(*)[3])nb, nbn, UINT32_MAX)) goto oom;
        for (size_t i = 0; i < texels; ++i) eligible[i] = st.owner[i] == NONE;
        if (!dilate(out->lm_map, dims, eligible, (const int(*)[3])nb, nbn, LM_GUTTER_PASSES)) goto oom;
        /* what the atlas holds besides caches: gutter copies and nothing */
        for (size_t i = 0; i < texels; ++i) {
            out->lm_unused += out->lm_map[i] == GLOW_MAP_EMPTY;
            out->lm_gutter += out->lm_map[i] != GLOW_MAP_EMPTY && st.owner[i] == NONE;
        }
        out->lm_footprint = st.footprint;
        out->small_charts = st.pack.small;
        out->shared_texels = st.pack.shared;
        out->lm_uv = st.uv;
        st.uv = NULL;
        out->lm_page = st.page;
        st.page = NULL;
        if (settings->detail_factor >= 2 && out->lm_cache_count) {
            /* The detail corrects near light surfel by surfel (links.c), so its texels should resolve the
             * surfels' spacing: where open ground's texels (1 / density, the coarsest) span more than
             * detail_factor surfels, the automatic setting takes more detail texels a side, up to its cap
             * (Sponza moderate: 1.6 m texels, 0.48 m surfels: 3 -> 4, 0.53 -> 0.40 m; docs/linker.md). */
            uint32_t factor = settings->detail_factor;
            if (settings->detail_factor_max > factor && settings->detail_spacing > 0.0f && out->texel_density > 0.0f) {
                const double want = ceil(1.0 / ((double)out->texel_density * settings->detail_spacing) - 1e-6);
                if (want > factor) factor = want < settings->detail_factor_max ? (uint32_t)want : settings->detail_factor_max;
            }
            r = build_detail(scene, rt, pool, log, factor, lj.offset, out);
            if (r != GLOW_OK) goto fail;
        }
    }

    if (surfels && surfels->count) {
        if (out->count == 0) {
            glow__errorf(log, "%s: caches: no cache left (every grid point inside geometry, every texel invalid)",
                         scene->source);
            r = GLOW_ERROR_EMPTY_SCENE;
            goto fail;
        }
        out->surfel_feedback = malloc((size_t)surfels->count * sizeof *out->surfel_feedback);
        if (!out->surfel_feedback) goto oom;
        fb_job fj = {.scene = scene, .surfels = surfels, .c = out};
        glow__parallel_for(pool, surfels->count, 256, fb_range, &fj);
    }

    if (out->lm_width)
        glow__infof(log,
                    "%s: lightmap budget: %u of %u atlas texels hold a cache (%.0f %% of their area is surface, the "
                    "rest overhangs a chart's border), %u invalid (filled), %u gutter copies, %u unused (%.0f %%); "
                    "%.3g units per texel",
                    scene->source, out->lm_cache_count, out->lm_width * out->lm_height * out->lm_pages,
                    st.covered ? 100.0 * out->lm_footprint / st.covered : 0.0, out->lm_invalid, out->lm_gutter,
                    out->lm_unused, 100.0 * out->lm_unused / ((double)out->lm_width * out->lm_height * out->lm_pages),
                    out->texel_density > 0.0f ? 1.0 / out->texel_density : 0.0);
    /* Texels whose hemisphere meets mostly back faces are invalid: a few along creases and inside solids
     * (Sponza 3.6 %, Cornell 3.7 %, a window room 4.7 %), but about half when surfaces face away from where
     * they are seen. Glow's surfels and texels live on front faces only while a path tracer reflects on
     * both sides, so such a mesh reads dark (the window room wound outwards: mean ratio 0.73 against
     * glow-render; docs/results.md): say so. */
    if (out->lm_invalid && (double)out->lm_invalid > LM_INVALID_WARN * (double)(out->lm_invalid + out->lm_cache_count))
        glow__warnf(log,
                    "%s: %u of %u lightmap texels (%.0f %%) see mostly back faces: surfaces facing away from where they "
                    "are seen (inconsistent winding, single-sided walls wound outwards)? Glow lights front faces only, "
                    "so their back faces will read dark: fix the winding or the normals",
                    scene->source, out->lm_invalid, out->lm_invalid + out->lm_cache_count,
                    100.0 * out->lm_invalid / (double)(out->lm_invalid + out->lm_cache_count));
    glow__infof(log,
                "%s: caches: grid %ux%ux%u at %g: %u caches, %u inside geometry; lightmap %ux%u at %g texels/unit "
                "(%u charts, %u of them narrower than a texel sharing %u texels): %u caches, %u invalid texels",
                scene->source, out->grid_dims[0], out->grid_dims[1], out->grid_dims[2], (double)out->grid_spacing,
                out->grid_cache_count, out->grid_inside, out->lm_width, out->lm_height, (double)out->texel_density,
                out->chart_count, out->small_charts, out->shared_texels, out->lm_cache_count, out->lm_invalid);
    if (out->lm_pages > 1)
        glow__infof(log, "%s: caches: the lightmap is %u pages of %ux%u (--lightmap-max-size) at %g texels/unit",
                    scene->source, out->lm_pages, out->lm_width, out->lm_height, (double)out->texel_density);
    if (out->grid_refine)
        glow__infof(log,
                    "%s: caches: grid refined %ux near geometry: %u of %u cells are bricks of %u³ cells at %g; %u coarse "
                    "and %u fine grid caches (%u fine points inside geometry)",
                    scene->source, out->grid_refine, out->grid_brick_count,
                    (out->grid_dims[0] - 1) * (out->grid_dims[1] - 1) * (out->grid_dims[2] - 1), out->grid_refine,
                    (double)out->grid_spacing / out->grid_refine, coarse_count, out->grid_fine_count,
                    out->grid_fine_inside);
    free(inside);
    lm_state_free(&st);
    free(cand);
    free(eligible);
    free(lj.pos);
    free(lj.nrm);
    free(lj.valid);
    return GLOW_OK;

oom:
    glow__errorf(log, "%s: caches: out of memory", scene->source);
    r = GLOW_ERROR_OUT_OF_MEMORY;
fail:
    free(inside);
    lm_state_free(&st);
    free(cand);
    free(eligible);
    free(lj.pos);
    free(lj.nrm);
    free(lj.valid);
    glow__caches_free(out);
    return r;
}
