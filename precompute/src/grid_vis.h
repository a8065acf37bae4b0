/* grid_vis.h — per-octant corner visibility of the grid cells (bake section GVIS), grid_vis.c. */
#ifndef GLOW_PC_GRID_VIS_H
#define GLOW_PC_GRID_VIS_H

#include "pc_internal.h"

/* Fills out_mask[dx*dy*dz][8] (cell = grid point index, x fastest; octant o: bit a of o = upper half
 * along axis a; bit k = corner k visible from the octant's centre). */
glow_result glow__grid_visibility(const glow__rt *rt, const glow__caches *ca, float scene_diag, glow__pool *pool,
                                  uint8_t *out_mask);

/* The same for the refined grid's fine cells: out_mask[brick][R³][8] (grid_fine.c, section GFIN). */
glow_result glow__grid_fine_visibility(const glow__rt *rt, const glow__caches *ca, float scene_diag, glow__pool *pool,
                                       uint8_t *out_mask);

#endif /* GLOW_PC_GRID_VIS_H */
