/* hierarchy.h — the visibility-aware variant of glow__hierarchy_build (pc_internal.h).
 *
 * glow__hierarchy_build_rt clusters with the PIC metric plus an occlusion term: a pair of clusters
 * that cannot see each other (a front face blocks the segment between their centres from both ends)
 * pays HAC_CV = 0.5 on top of d(a,b), so it is merged only after every visible pair within about half
 * a scene diagonal. Without it the HAC happily merges, say, the strips of two rooms' ceilings on either
 * side of a 10 cm wall (they are close and coplanar), and every cache in one room that links such a
 * cluster receives the other room's light through the cluster's mean radiosity (PIC 5.2, Fig. 9c).
 * rt == NULL is glow__hierarchy_build. Same determinism and thread-count independence. */
#ifndef GLOW_PC_HIERARCHY_H
#define GLOW_PC_HIERARCHY_H

#include "pc_internal.h"

glow_result glow__hierarchy_build_rt(glow__surfels *surfels, const float scene_min[3], const float scene_max[3],
                                     const glow__rt *rt, glow__pool *pool, glow__log *log, glow__hierarchy *out);

/* glow__hierarchy_build_rt with the chunking explicit (hierarchy.c, "chunked clustering"): above
 * chunk_from surfels, spatial chunks of at most `chunk` are clustered in parallel, then their roots.
 * The pipeline uses 131072 and 65536; UINT32_MAX clusters in one piece (tests). */
glow_result glow__hierarchy_build_chunked(glow__surfels *surfels, const float scene_min[3], const float scene_max[3],
                                          const glow__rt *rt, uint32_t chunk_from, uint32_t chunk, glow__pool *pool,
                                          glow__log *log, glow__hierarchy *out);

#endif /* GLOW_PC_HIERARCHY_H */
