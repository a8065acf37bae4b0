/* grid_vis.c — which corners of a grid cell a lookup may blend (bake section GVIS).
 *
 * Trilinear interpolation between grid caches leaks light through walls thinner than the grid
 * spacing: a lookup just inside room B blends the grid points on room A's side (and the point inside
 * the wall, which holds a copy of A's cache). PIC 5.2 names this bleeding; the two-rooms test
 * measured 20 % (single bounce) to 35 % (multi-bounce) of room A's grid radiance read at B's wall.
 * For every cell (the cube whose lowest corner is grid point (x, y, z); corners past the last point
 * are clamped to it, as glow_sample_grid clamps) and each of its 8 octants, bit k of byte
 * mask[cell][octant] says whether corner k (x + (k & 1), y + (k >> 1 & 1), z + (k >> 2)) is visible
 * from the octant's centre: the segment between them hits nothing. A lookup then blends only the
 * visible corners of its octant (glow_sample_grid). An octant whose centre sees no corner (inside a
 * solid) keeps all 8, as before. Deterministic: every mask is a pure function of the geometry. */
#include <stdlib.h>
#include <string.h>

#include "grid_vis.h"
#include "bake_format.h"

/* The 8 octant masks of one cell from its corners (k: x + (k & 1), y + (k >> 1 & 1), z + (k >> 2));
 * the octant centres lie between corner 0 and corner 7 (which may be clamped onto corner 0). */
static void cell_masks(const glow__rt *rt, const float (*corner)[3], float eps, uint8_t *mask) {
    for (uint32_t o = 0; o < 8; ++o) {
        float c[3];
        for (int a = 0; a < 3; ++a) {
            const float lo = corner[0][a], hi = corner[7][a];
            c[a] = lo + (hi - lo) * ((o >> a) & 1u ? 0.75f : 0.25f);
        }
        uint8_t m = 0;
        for (uint32_t k = 0; k < 8; ++k) {
            float d[3];
            glow__sub(corner[k], c, d);
            const float len2 = glow__dot(d, d);
            if (!(len2 > 0.0f) || !glow__rt_occluded(rt, c, d, 0.0f, 1.0f - eps)) m |= (uint8_t)(1u << k);
        }
        mask[o] = m ? m : 0xFFu;
    }
}

typedef struct gv_job {
    const glow__rt *rt;
    const glow__caches *ca;
    float eps;
    uint8_t *mask;
} gv_job;

static void gv_range(void *user, uint32_t first, uint32_t end, uint32_t worker) {
    (void)worker;
    const gv_job *j = user;
    const glow__caches *ca = j->ca;
    const uint32_t dx = ca->grid_dims[0], dy = ca->grid_dims[1], dz = ca->grid_dims[2];
    const float s = ca->grid_spacing;
    for (uint32_t cell = first; cell < end; ++cell) {
        const uint32_t x = cell % dx, y = (cell / dx) % dy, z = cell / (dx * dy);
        float corner[8][3];
        for (uint32_t k = 0; k < 8; ++k) {
            const uint32_t cx = (k & 1u) && x + 1 < dx ? x + 1 : x, cy = (k & 2u) && y + 1 < dy ? y + 1 : y,
                           cz = (k & 4u) && z + 1 < dz ? z + 1 : z;
            corner[k][0] = ca->grid_origin[0] + s * (float)cx;
            corner[k][1] = ca->grid_origin[1] + s * (float)cy;
            corner[k][2] = ca->grid_origin[2] + s * (float)cz;
        }
        cell_masks(j->rt, (const float(*)[3])corner, j->eps, j->mask + (size_t)cell * 8);
    }
}

glow_result glow__grid_visibility(const glow__rt *rt, const glow__caches *ca, const float scene_diag, glow__pool *pool,
                                  uint8_t *out_mask) {
    if (!rt || !ca || !out_mask) return GLOW_ERROR_INVALID_ARGUMENT;
    const uint64_t cells = (uint64_t)ca->grid_dims[0] * ca->grid_dims[1] * ca->grid_dims[2];
    if (cells == 0) return GLOW_OK;
    /* stop 1e-4 of the scene diagonal short of the corner, in units of the segment (<= 1 spacing long) */
    gv_job j = {.rt = rt, .ca = ca, .eps = ca->grid_spacing > 0.0f ? 1e-4f * scene_diag / ca->grid_spacing : 0.0f,
                .mask = out_mask};
    if (j.eps > 0.01f) j.eps = 0.01f;
    glow__parallel_for(pool, (uint32_t)cells, 64, gv_range, &j);
    return GLOW_OK;
}

/* The same masks for the fine cells of the refined grid's bricks (grid_fine.c; GFIN): out_mask
 * [brick][R³ fine cells, x fastest][8 octants]. A fine cell's corners are lattice points of the fine
 * lattice (spacing grid_spacing / R), never clamped: a brick's cells lie inside the grid. */
typedef struct gvf_job {
    const glow__rt *rt;
    const glow__caches *ca;
    const uint32_t *brick_cell; /* [brick] the coarse cell it refines */
    float eps;
    uint8_t *mask;
} gvf_job;

static void gvf_range(void *user, uint32_t first, uint32_t end, uint32_t worker) {
    (void)worker;
    const gvf_job *j = user;
    const glow__caches *ca = j->ca;
    const uint32_t R = ca->grid_refine, per = R * R * R, dx = ca->grid_dims[0], dy = ca->grid_dims[1];
    const float fs = ca->grid_spacing / (float)R;
    for (uint32_t item = first; item < end; ++item) { /* one fine cell */
        const uint32_t b = item / per, l = item % per, c = j->brick_cell[b];
        const uint32_t base[3] = {(c % dx) * R + l % R, ((c / dx) % dy) * R + (l / R) % R, (c / (dx * dy)) * R + l / (R * R)};
        float corner[8][3];
        for (uint32_t k = 0; k < 8; ++k)
            for (int a = 0; a < 3; ++a) corner[k][a] = ca->grid_origin[a] + fs * (float)(base[a] + ((k >> a) & 1u));
        cell_masks(j->rt, (const float(*)[3])corner, j->eps, j->mask + (size_t)item * 8);
    }
}

glow_result glow__grid_fine_visibility(const glow__rt *rt, const glow__caches *ca, const float scene_diag,
                                       glow__pool *pool, uint8_t *out_mask) {
    if (!rt || !ca || !out_mask) return GLOW_ERROR_INVALID_ARGUMENT;
    if (!ca->grid_refine || !ca->grid_brick_count) return GLOW_OK;
    const size_t cells = (size_t)ca->grid_dims[0] * ca->grid_dims[1] * ca->grid_dims[2];
    uint32_t *brick_cell = malloc((size_t)ca->grid_brick_count * sizeof *brick_cell);
    if (!brick_cell) return GLOW_ERROR_OUT_OF_MEMORY;
    for (size_t c = 0; c < cells; ++c)
        if (ca->grid_brick_of_cell[c] != GLOW_MAP_EMPTY) brick_cell[ca->grid_brick_of_cell[c]] = (uint32_t)c;
    const float fs = ca->grid_spacing / (float)ca->grid_refine;
    gvf_job j = {.rt = rt, .ca = ca, .brick_cell = brick_cell, .eps = fs > 0.0f ? 1e-4f * scene_diag / fs : 0.0f,
                 .mask = out_mask};
    if (j.eps > 0.01f) j.eps = 0.01f;
    const uint32_t R = ca->grid_refine;
    glow__parallel_for(pool, ca->grid_brick_count * R * R * R, 16, gvf_range, &j);
    free(brick_cell);
    return GLOW_OK;
}
