/* grid_fine.c — the grid refined near geometry (bake section GFIN, format 1.5; glow-bake --grid-refine R).
 *
 * A uniform grid spends as many points on empty air (a courtyard's middle, the sky over a level's
 * streets) as on the places where dynamic objects meet surfaces and the light changes within a metre.
 * With refine R > 1 the grid is two lattices: the coarse one of caches.c (spacing S, over the whole
 * box) and a fine one of spacing S / R, present only in the coarse cells near geometry: a cell is
 * refined when a triangle comes within one fine spacing of it (an exact triangle-box test on the cell
 * grown by that margin). A refined cell is a "brick" of R³ fine cells whose (R + 1)³ corners are
 * lattice points of the fine lattice; points shared by neighbouring bricks are one cache, and the
 * brick corners that are coarse points are the coarse caches themselves. A fine point inside solid
 * geometry (the coarse grid's test) is no cache; its brick entry is empty (lookups weight it 0). A
 * brick without any cache is dropped.
 *
 * The lattice: a uniform grid's points are cell centres, half a spacing inside the scene's box, so with
 * a coarse spacing the floor may lie half a coarse spacing below the first layer, where lookups clamp.
 * A refined grid's coarse lattice instead spans the box grown by half a fine spacing on every side
 * (at least 2 points an axis): the geometry lies inside its cells, and the fine points nearest a
 * floor lie half a fine spacing above it (and below it, where they are inside or open air).
 *
 * The budget: with no spacing given, S is the smallest spacing whose coarse points plus the fine
 * points of its refined cells (counted exactly, inside ones too) stay within the grid's cache target,
 * found by a scan of spacings 2^(1/8) apart; with --grid-spacing M, M is the fine spacing
 * (the one near geometry) and S = R · M.
 *
 * Fine caches follow the coarse grid caches in the cache array (both are GRID caches: spherical, and
 * linked alike); their `texel` is the coarse cell they lie in. Deterministic: pure functions of the
 * geometry, in cell order; the inside rays run through glow__parallel_for with one result per point. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_format.h"
#include "pc_internal.h"


/* ------------------------------------------------------------------ triangle-box overlap */
/* Akenine-Möller's separating-axis test: does triangle v overlap the box of centre c, half size h? */
static int axis_sep(const double a[3], const double v0[3], const double v1[3], const double v2[3], const double h[3]) {
    const double p0 = a[0] * v0[0] + a[1] * v0[1] + a[2] * v0[2], p1 = a[0] * v1[0] + a[1] * v1[1] + a[2] * v1[2],
                 p2 = a[0] * v2[0] + a[1] * v2[1] + a[2] * v2[2];
    const double r = h[0] * fabs(a[0]) + h[1] * fabs(a[1]) + h[2] * fabs(a[2]);
    const double mn = fmin(p0, fmin(p1, p2)), mx = fmax(p0, fmax(p1, p2));
    return mn > r || mx < -r;
}

static int tri_box(const float (*tri)[3], const double c[3], const double h[3]) {
    double v[3][3], e[3][3];
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) v[k][a] = (double)tri[k][a] - c[a];
    for (int a = 0; a < 3; ++a) { /* the box's own axes */
        const double mn = fmin(v[0][a], fmin(v[1][a], v[2][a])), mx = fmax(v[0][a], fmax(v[1][a], v[2][a]));
        if (mn > h[a] || mx < -h[a]) return 0;
    }
    for (int a = 0; a < 3; ++a) {
        e[0][a] = v[1][a] - v[0][a];
        e[1][a] = v[2][a] - v[1][a];
        e[2][a] = v[0][a] - v[2][a];
    }
    for (int i = 0; i < 3; ++i) /* edge x box axis */
        for (int j = 0; j < 3; ++j) {
            double ax[3] = {0, 0, 0}, u[3] = {0, 0, 0};
            u[j] = 1.0;
            ax[0] = e[i][1] * u[2] - e[i][2] * u[1];
            ax[1] = e[i][2] * u[0] - e[i][0] * u[2];
            ax[2] = e[i][0] * u[1] - e[i][1] * u[0];
            if (axis_sep(ax, v[0], v[1], v[2], h)) return 0;
        }
    double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                   e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    if (axis_sep(n, v[0], v[1], v[2], h)) return 0; /* the triangle's plane */
    return 1;
}

/* ------------------------------------------------------------------ refined cells */
typedef struct lattice {
    double origin[3], s;
    uint32_t dims[3];
} lattice;

/* Marks mark[cell] = 1 for every coarse cell (lowest corner x < dims - 1 on each axis) that a triangle
 * comes within `margin` of. Returns the number marked. */
static uint64_t mark_cells(const glow__scene *scene, const lattice *L, double margin, uint8_t *mark) {
    const size_t n = (size_t)L->dims[0] * L->dims[1] * L->dims[2];
    memset(mark, 0, n);
    uint64_t count = 0;
    const double h[3] = {0.5 * L->s + margin, 0.5 * L->s + margin, 0.5 * L->s + margin};
    for (uint32_t t = 0; t < scene->tri_count; ++t) {
        const float(*p)[3] = scene->pos + 3 * (size_t)t;
        long lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const double mn = fmin(p[0][a], fmin(p[1][a], p[2][a])) - margin,
                         mx = fmax(p[0][a], fmax(p[1][a], p[2][a])) + margin;
            const long last = (long)L->dims[a] - 2;
            lo[a] = (long)floor((mn - L->origin[a]) / L->s);
            hi[a] = (long)floor((mx - L->origin[a]) / L->s);
            if (lo[a] < 0) lo[a] = 0;
            if (hi[a] > last) hi[a] = last;
        }
        for (long z = lo[2]; z <= hi[2]; ++z)
            for (long y = lo[1]; y <= hi[1]; ++y)
                for (long x = lo[0]; x <= hi[0]; ++x) {
                    const size_t c = ((size_t)z * L->dims[1] + (size_t)y) * L->dims[0] + (size_t)x;
                    if (mark[c]) continue;
                    const double ctr[3] = {L->origin[0] + L->s * ((double)x + 0.5),
                                           L->origin[1] + L->s * ((double)y + 0.5),
                                           L->origin[2] + L->s * ((double)z + 0.5)};
                    if (tri_box(p, ctr, h)) {
                        mark[c] = 1;
                        ++count;
                    }
                }
    }
    return count;
}

/* The fine points (not coarse ones) on the marked cells' corners, each counted once: by the marked
 * cell of lowest index among those it is a corner of. */
static uint64_t count_fine(const lattice *L, const uint8_t *mark, uint32_t R) {
    const uint32_t *d = L->dims, side = R + 1;
    const size_t cells = (size_t)d[0] * d[1] * d[2];
    uint64_t n = 0;
    for (size_t c = 0; c < cells; ++c) {
        if (!mark[c]) continue;
        const uint32_t cc[3] = {(uint32_t)(c % d[0]), (uint32_t)((c / d[0]) % d[1]), (uint32_t)(c / ((size_t)d[0] * d[1]))};
        for (uint32_t k = 0; k < side * side * side; ++k) {
            const uint32_t l[3] = {k % side, (k / side) % side, k / (side * side)};
            if (l[0] % R == 0 && l[1] % R == 0 && l[2] % R == 0) continue; /* a coarse point */
            size_t owner = c; /* the lowest-index marked cell with this point as a corner */
            for (uint32_t m = 1; m < 8; ++m) { /* the neighbours: -1 along an axis where the point is on the
                                                  cell's lower face, +1 where on its upper face */
                long q[3];
                int ok = 1;
                for (int a = 0; a < 3; ++a) {
                    q[a] = (long)cc[a];
                    if ((m >> a) & 1u) {
                        if (l[a] == 0) q[a] -= 1;
                        else if (l[a] == R) q[a] += 1;
                        else ok = 0;
                    }
                    if (q[a] < 0 || q[a] + 1 >= (long)d[a]) ok = 0;
                }
                if (!ok) continue;
                const size_t qc = ((size_t)q[2] * d[1] + (size_t)q[1]) * d[0] + (size_t)q[0];
                if (mark[qc] && qc < owner) owner = qc;
            }
            n += owner == c;
        }
    }
    return n;
}

/* The coarse lattice of a refined grid of coarse spacing s (see glow__grid_refined_lattice). */
static void lattice_for(const glow__scene *scene, double s, uint32_t R, lattice *L) {
    L->s = s;
    for (int a = 0; a < 3; ++a) {
        const double ext = fmax(0.0, (double)scene->bounds_max[a] - scene->bounds_min[a]);
        const double centre = 0.5 * ((double)scene->bounds_max[a] + scene->bounds_min[a]);
        const double d = ceil((ext + s / R) / s - 1e-9) + 1.0;
        L->dims[a] = d > 4e9 ? 4000000000u : (uint32_t)d;
        L->origin[a] = centre - 0.5 * (d - 1.0) * s;
    }
}

void glow__grid_refined_lattice(const glow__scene *scene, double s, uint32_t refine, uint32_t dims[3], float origin[3]) {
    lattice L;
    lattice_for(scene, s, refine, &L);
    for (int a = 0; a < 3; ++a) {
        dims[a] = L.dims[a];
        origin[a] = (float)L.origin[a];
    }
}

double glow__grid_refined_spacing(const glow__scene *scene, uint32_t refine, double target, double max_cells) {
    double ext[3], big = 0.0;
    for (int a = 0; a < 3; ++a) {
        ext[a] = fmax(0.0, (double)scene->bounds_max[a] - scene->bounds_min[a]);
        big = fmax(big, ext[a]);
    }
    if (!(big > 0.0) || refine < 2 || !scene->tri_count) return 0.0;
    for (int a = 0; a < 3; ++a)
        if (!(ext[a] > 1e-3 * big)) return 0.0; /* a flat scene: the uniform grid */
    /* The count is not monotonic in s (a layer of cells moves past a floor), so scan 96 spacings a
     * factor 2^(1/8) apart, coarse to fine, and keep the finest that fits. */
    const double hi = big * 2.0;
    double best = 0.0;
    uint8_t *mark = NULL;
    for (int it = 0; it < 96; ++it) {
        const double s = hi * pow(2.0, -it / 8.0);
        lattice L;
        lattice_for(scene, s, refine, &L);
        const double cells = (double)L.dims[0] * L.dims[1] * L.dims[2];
        if (cells > target || cells > max_cells) break; /* every finer one has more coarse points alone */
        free(mark);
        mark = malloc((size_t)cells);
        if (!mark) return 0.0;
        mark_cells(scene, &L, s / refine, mark);
        if (cells + (double)count_fine(&L, mark, refine) <= target) best = s;
    }
    free(mark);
    return best; /* 0: no refined grid fits the target, the uniform one */
}

/* ------------------------------------------------------------------ inside test of the fine points */
typedef struct fine_job {
    const glow__rt *rt;
    const float (*pos)[3];
    float dirs[GLOW__GRID_RAYS][3];
    uint8_t *inside;
} fine_job;

static void fine_range(void *p, uint32_t begin, uint32_t end, uint32_t worker) {
    fine_job *j = p;
    (void)worker;
    for (uint32_t i = begin; i < end; ++i)
        j->inside[i] = (uint8_t)glow__grid_point_inside(j->rt, j->pos[i], (const float(*)[3])j->dirs);
}

static int cmp_u64(const void *a, const void *b) {
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

glow_result glow__grid_refine(const glow__scene *scene, const glow__rt *rt, uint32_t refine, glow__pool *pool,
                              glow__log *log, glow__caches *ca) {
    ca->grid_refine = 0;
    const uint32_t *d = ca->grid_dims, R = refine;
    if (R < 2 || !scene->tri_count) return GLOW_OK;
    if (d[0] < 2 || d[1] < 2 || d[2] < 2) {
        glow__infof(log, "%s: caches: grid %ux%ux%u is flat; not refined", scene->source, d[0], d[1], d[2]);
        return GLOW_OK;
    }
    const size_t cells = (size_t)d[0] * d[1] * d[2];
    const uint32_t side = R + 1, per = side * side * side;
    lattice L = {.s = ca->grid_spacing, .dims = {d[0], d[1], d[2]}};
    for (int a = 0; a < 3; ++a) L.origin[a] = ca->grid_origin[a];
    uint8_t *mark = malloc(cells);
    uint32_t *brick_of = malloc(cells * sizeof *brick_of);
    uint64_t *keys = NULL;
    uint32_t *bricks = NULL, *cell_of = NULL;
    float(*pos)[3] = NULL;
    uint8_t *inside = NULL;
    glow_result r = GLOW_ERROR_OUT_OF_MEMORY;
    if (!mark || !brick_of) goto fail;
    const uint64_t marked = mark_cells(scene, &L, ca->grid_spacing / (double)R, mark);
    if (marked * per > (uint64_t)(64u << 20)) {
        glow__errorf(log, "%s: caches: %llu refined grid cells are too many (a coarser grid spacing, or a smaller "
                     "--grid-refine)", scene->source, (unsigned long long)marked);
        r = GLOW_ERROR_OUT_OF_RANGE;
        goto fail;
    }
    /* fine lattice coordinates g = cell * R + local; fine dims (d - 1) * R + 1 */
    const uint64_t fx = (uint64_t)(d[0] - 1) * R + 1, fy = (uint64_t)(d[1] - 1) * R + 1;
    keys = malloc((size_t)(marked * per + 1) * sizeof *keys);
    bricks = malloc((size_t)(marked * per + 1) * sizeof *bricks);
    if (!keys || !bricks) goto fail;
    size_t nk = 0;
    uint32_t nb = 0;
    for (size_t c = 0; c < cells; ++c) {
        brick_of[c] = GLOW_MAP_EMPTY;
        if (!mark[c]) continue;
        const uint64_t cx = c % d[0], cy = (c / d[0]) % d[1], cz = c / ((size_t)d[0] * d[1]);
        for (uint32_t k = 0; k < per; ++k) {
            const uint64_t gx = cx * R + k % side, gy = cy * R + (k / side) % side, gz = cz * R + k / (side * side);
            if (gx % R || gy % R || gz % R) keys[nk++] = (gz * fy + gy) * fx + gx;
        }
        brick_of[c] = nb++;
    }
    qsort(keys, nk, sizeof *keys, cmp_u64);
    size_t nu = 0;
    for (size_t i = 0; i < nk; ++i)
        if (!nu || keys[i] != keys[nu - 1]) keys[nu++] = keys[i];
    pos = malloc((nu + 1) * sizeof *pos);
    inside = malloc(nu + 1);
    if (!pos || !inside) goto fail;
    const double fs = ca->grid_spacing / (double)R;
    for (size_t i = 0; i < nu; ++i) {
        const uint64_t g = keys[i], gx = g % fx, gy = (g / fx) % fy, gz = g / (fx * fy);
        pos[i][0] = (float)(ca->grid_origin[0] + fs * (double)gx);
        pos[i][1] = (float)(ca->grid_origin[1] + fs * (double)gy);
        pos[i][2] = (float)(ca->grid_origin[2] + fs * (double)gz);
    }
    fine_job j = {.rt = rt, .pos = (const float(*)[3])pos, .inside = inside};
    glow__fibonacci_sphere(GLOW__GRID_RAYS, j.dirs);
    glow__parallel_for(pool, (uint32_t)nu, 64, fine_range, &j);
    /* fine caches: the points outside solids, in key order, after the coarse grid caches */
    uint32_t *index = malloc((nu + 1) * sizeof *index);
    if (!index) goto fail;
    uint32_t fine = 0;
    for (size_t i = 0; i < nu; ++i) index[i] = inside[i] ? GLOW_MAP_EMPTY : ca->grid_cache_count + fine++;
    /* bricks: (R + 1)³ entries each, x fastest; drop those without a cache */
    uint32_t kept = 0;
    for (size_t c = 0; c < cells; ++c) {
        if (brick_of[c] == GLOW_MAP_EMPTY) continue;
        const uint64_t cx = c % d[0], cy = (c / d[0]) % d[1], cz = c / ((size_t)d[0] * d[1]);
        uint32_t *e = bricks + (size_t)kept * per, any = 0;
        for (uint32_t k = 0; k < per; ++k) {
            const uint64_t gx = cx * R + k % side, gy = cy * R + (k / side) % side, gz = cz * R + k / (side * side);
            if (!(gx % R || gy % R || gz % R)) { /* a coarse point: its own cache, not a dilated copy */
                const uint32_t m = ca->grid_map[((size_t)(gz / R) * d[1] + (size_t)(gy / R)) * d[0] + (size_t)(gx / R)];
                e[k] = (m == GLOW_MAP_EMPTY || (m & GLOW_MAP_COPY_BIT)) ? GLOW_MAP_EMPTY : m;
            } else {
                const uint64_t key = (gz * fy + gy) * fx + gx;
                const uint64_t *f = bsearch(&key, keys, nu, sizeof *keys, cmp_u64);
                e[k] = index[f - keys];
            }
            any |= e[k] != GLOW_MAP_EMPTY;
        }
        brick_of[c] = any ? kept++ : GLOW_MAP_EMPTY;
    }
    /* the fine caches' positions and cells, for caches.c to append */
    cell_of = malloc(((size_t)fine + 1) * sizeof *cell_of);
    float(*fpos)[3] = malloc(((size_t)fine + 1) * sizeof *fpos);
    if (!cell_of || !fpos) {
        free(fpos);
        free(index);
        goto fail;
    }
    for (size_t i = 0, k = 0; i < nu; ++i) {
        if (inside[i]) continue;
        memcpy(fpos[k], pos[i], sizeof fpos[k]);
        const uint64_t g = keys[i], gx = g % fx, gy = (g / fx) % fy, gz = g / (fx * fy);
        uint64_t cx = gx / R, cy = gy / R, cz = gz / R;
        if (cx >= d[0]) cx = d[0] - 1;
        if (cy >= d[1]) cy = d[1] - 1;
        if (cz >= d[2]) cz = d[2] - 1;
        cell_of[k++] = (uint32_t)((cz * d[1] + cy) * d[0] + cx);
    }
    free(index);
    ca->grid_refine = R;
    ca->grid_brick_count = kept;
    ca->grid_brick_of_cell = brick_of;
    ca->grid_bricks = bricks;
    ca->grid_fine_count = fine;
    ca->grid_fine_inside = (uint32_t)(nu - fine);
    ca->grid_fine_pos = fpos;
    ca->grid_fine_cell = cell_of;
    free(mark);
    free(keys);
    free(pos);
    free(inside);
    return GLOW_OK;
fail:
    if (r == GLOW_ERROR_OUT_OF_MEMORY) glow__errorf(log, "%s: caches: out of memory for the refined grid", scene->source);
    free(mark);
    free(brick_of);
    free(keys);
    free(bricks);
    free(cell_of);
    free(pos);
    free(inside);
    return r;
}
