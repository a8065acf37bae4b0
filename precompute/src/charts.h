/* charts.h — the two halves of Glow's lightmap chart packer (charts.c), exposed so that caches.c can
 * segment a scene once and pack it at several texel densities while it searches for the density
 * that meets its texel budget. glow__charts_build (pc_internal.h) is segment + pack + free. */
#ifndef GLOW_CHARTS_H
#define GLOW_CHARTS_H

#include "pc_internal.h"

typedef struct glow__chart_set {
    uint32_t tri_count, chart_count;
    uint32_t *chart_start;   /* [chart_count + 1] */
    uint32_t *chart_tris;    /* [tri_count]: chart c holds chart_tris[chart_start[c] .. chart_start[c+1]) */
    double (*xy)[2];         /* [3*tri_count] corner positions in the chart's plane (m), chart min at 0,0 */
    double (*extent)[2];     /* [chart_count] chart width >= height (m), after the min-area rotation */
    uint32_t evicted;        /* triangles moved to a later chart because their projection overlapped */
    uint32_t blocked;        /* shared edges not crossed because geometry stands on the surface there */
    double (*normal)[3];     /* [chart_count] area-weighted mean geometric normal (unit; 0 when none) */
    double (*centre)[3];     /* [chart_count] area-weighted centroid */
    float *scale;            /* [chart_count] texel density multiplier (texels per m = density x
                                scale), or NULL for 1 everywhere; freed with the set */
} glow__chart_set;

/* What one packing did with the small charts (glow__charts_pack). */
typedef struct glow__chart_pack_stats {
    uint32_t small;   /* charts no wider than GLOW__CHART_SMALL texels at the density used */
    uint32_t shared;  /* texels they were merged into (a chart alone in its group keeps its own) */
    uint32_t slots;   /* footprints packed: the large charts plus the shared texels */
    uint32_t *unit_of; /* in: NULL, or [chart_count] to receive each chart's footprint index (merged
                          charts share one) */
} glow__chart_pack_stats;

/* Welds corners by exact position, grows planar-ish charts over shared edges (normals within
 * GLOW__CHART_MAX_ANGLE_DEG of the seed's), projects each onto its mean plane, evicts triangles
 * whose projection overlaps the chart, and rotates each chart to its minimum-area rectangle.
 * With a ray tracer (rt may be NULL), a chart does not grow across an edge between coplanar
 * triangles where other geometry stands on the surface between them (a wall on a floor): the
 * segment between their centroids, lifted off the surface, must be clear. */
glow_result glow__charts_segment(const glow__scene *scene, const glow__rt *rt, glow__log *log, glow__chart_set *out);

/* Packs the charts at `texel_density` texels per m into one atlas (shelf packing, charts' texel
 * footprints `padding` texels apart and from the border; width and height multiples of 4). When
 * the atlas would exceed GLOW__CHART_MAX_ATLAS texels a side the density is lowered (warning).
 * Charts no wider than GLOW__CHART_SMALL texels are merged: those whose centres share a cell of one
 * texel and whose normals lie within GLOW__CHART_MERGE_ANGLE_DEG of the group's first share one
 * texel, projected together onto their mean plane (shrunk when the group is wider than a texel).
 * out_uv: [3*tri_count] per-corner UV in [0,1]; out_density: the density used; stats may be NULL. */
glow_result glow__charts_pack(const glow__chart_set *cs, float texel_density, uint32_t padding, glow__log *log,
                              float (*out_uv)[2], uint32_t *out_width, uint32_t *out_height, float *out_density,
                              glow__chart_pack_stats *stats);

/* As glow__charts_pack with at most `max_side` texels a side (a multiple of 4, at most
 * GLOW__CHART_MAX_ATLAS), and when the charts at `texel_density` do not fit one atlas, pages (issue 16
 * item 5): up to `max_pages` atlases of max_side x max_side each (out_page != NULL needed), shelf
 * packing continuing on the next page, at the same density; beyond max_pages the density is lowered
 * (warning). Charts that fit one atlas are packed exactly as glow__charts_pack packs them.
 * out_page: [tri_count] each triangle's page (its UVs are in [0,1] within that page); out_pages: the
 * page count (1 when one atlas holds them; 0 without charts). */
glow_result glow__charts_pack_pages(const glow__chart_set *cs, float texel_density, uint32_t padding,
                                    uint32_t max_side, uint32_t max_pages, glow__log *log, float (*out_uv)[2],
                                    uint32_t *out_page, uint32_t *out_pages, uint32_t *out_width,
                                    uint32_t *out_height, float *out_density, glow__chart_pack_stats *stats);

void glow__charts_free(glow__chart_set *cs);

#define GLOW__CHART_MAX_ANGLE_DEG 40.0
#define GLOW__CHART_MAX_ATLAS 4096u   /* the largest atlas side (glow-bake --lightmap-max-size's default) */
#define GLOW__CHART_MAX_PAGES 64u     /* atlases before the density is lowered */
#define GLOW__CHART_SMALL 1.0          /* texels: charts no wider than this may share a texel */
#define GLOW__CHART_MERGE_ANGLE_DEG 30.0

#endif /* GLOW_CHARTS_H */
