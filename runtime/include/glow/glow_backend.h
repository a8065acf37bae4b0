/*
 * glow_backend.h — the seam between Glow's runtime and Glow's other backends of the same solver.
 *
 * NOT PUBLIC API. The GL backend (glow_gl, integration/gpu/), this repository's tools and the samples'
 * debug views read the runtime's tables through it: the bake's link bit layout, per-surfel arrays,
 * the hierarchy. Its layouts follow the bake format and may change in any version; it is not
 * installed with the SDK. glow_system_get_solver_tables is exported from libglow_runtime.so only
 * because libglow_gl.so calls it. An engine uses glow.h (and glow_gl.h) instead.
 */
#ifndef GLOW_GLOW_BACKEND_H
#define GLOW_GLOW_BACKEND_H

#include "glow/glow.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Solver tables: everything an update reads besides the host's light, in the layouts the CPU solver
 * uses, for other backends of the same solver (the GL backend, glow_gl.h, uploads them once and
 * re-uploads the parts whose revision changed). Views owned by the system (or its bake), valid until
 * it is destroyed; the values a setter changes are visible at once; the revisions say which changed,
 * so a backend re-uploads only those (no comparison of the arrays). */
typedef struct glow_solver_tables {
    uint32_t surfel_count, node_count, level_count, cache_count, material_count;
    uint32_t links_per_cache, link_blocks_per_cache; /* link blocks: 16 links each, see link_blocks */
    uint32_t sh_bands_luma, sh_bands_chroma, coeff_count;
    float surfel_area;                 /* m², the nominal leaf area (META); each surfel's own is the w of
                                          glow_system_get_surfels' positions (differs when the linker
                                          adapted the density, bake format 1.3) */
    const float *albedo;               /* [S][3] linear RGB (texture folded in), before material scales */
    const float *emission;             /* [S][3] W/(m²·sr) before scales (the bake's, or the host's override) */
    const uint32_t *materials;         /* [S] */
    const uint32_t *feedback;          /* [S] the cache each surfel re-emits (multi-bounce) */
    const float *feedback_weights;     /* [S][luma²] π s_l(1) y_lm(n): E_indirect = Σ w · cache SH (YCoCg) */
    const float *indirect_albedo_max;  /* [S] cap of the albedo applied to indirect light (non-divergence) */
    const uint32_t *node_children;     /* node n's children at node_children[n * node_stride + 0/1] (leaves: none) */
    uint32_t node_stride;              /* uint32 between nodes */
    const float *node_inv_pi_area;     /* [N] 1 / (π area): node radiance = flux · this */
    const float *node_positions;       /* node n's area-weighted centre (m) at node_positions[n * node_stride + 0..2]
                                          (debug views: clusters, a cache's links) */
    const float *cache_positions;      /* cache c's position (m) at cache_positions[c * cache_stride + 0..2] */
    uint32_t cache_stride;             /* floats between caches */
    const uint32_t *level_starts;      /* [level_count + 1]: level v's nodes are [starts[v], starts[v+1]); 0 = leaves */
    const void *link_blocks;           /* [cache_count * link_blocks_per_cache] blocks of 128 bytes, 16 links:
                                          uint32 node_dir[16] (bits 0-23 node, 24-31 bits 4-11 of the 12-bit
                                          octahedral u), half one_minus_cos[16], uint16 dir_lo[16] (bits 0-3:
                                          u bits 0-3, 4-15: v); docs/bake-format.md "LINK" */
    const uint32_t *output_index;      /* [grid_used + lightmap_used] the non-empty grid cells, then texels */
    const uint32_t *output_cache;      /* [same] the cache each of them shows */
    uint32_t grid_used, lightmap_used;
    const float *material_emission_scale, *material_albedo_scale; /* [M][3] (glow_system_set_material) */
    uint64_t emission_revision;        /* grows whenever `emission` changes */
    uint64_t material_revision;        /* grows whenever a material scale changes (glow_system_set_material) */
    const float *direct_irradiance;    /* [S][3] W/m²: the direct light the next update uses (pushed with
                                          glow_system_set_surfel_irradiance, or the hook's last); valid until
                                          the next update */
    uint64_t direct_revision;          /* grows whenever `direct_irradiance` changes */
    const uint16_t *link_subsets;      /* the bake's link subsets (LSUB), one per link in link_blocks' order,
                                          or NULL: link j reads its node's radiance times
                                          s = sum_i q_i Y[slot_i] / (sum_i q_i Y[node]), q_i = bits 4i..4i+3,
                                          slot_i the node's grandchildren (children's children; a leaf
                                          child twice; a leaf itself four times), s = 1 where all q_i
                                          are 0 or Y[node] is 0; docs/bake-format.md "LSUB" */
    /* the lightmap detail (the bake's LDET; all 0 / NULL without): texel i (detail_texel[i] = y *
     * detail_width + x) holds sum over k in [detail_first[i], detail_first[i + 1]) of detail_weight[k]
     * times the radiance of leaf detail_surfel[k], as RGB (glow_cache_outputs.lightmap_detail) */
    uint32_t detail_width, detail_height, detail_texels, detail_links;
    const uint32_t *detail_texel, *detail_first, *detail_surfel;
    const float *detail_weight;
    /* \since 0.2: proxy nodes (a system of a world, bake format 1.4 XREF): links may name node
     * node_count + p, whose radiance the CPU solver copies from a neighbouring system (the GL backend:
     * glow_gl_system_set_neighbour); a backend that does not carry them must refuse a bake with
     * proxy_count > 0 */
    uint32_t proxy_count;
    /* \since 0.2: proxy p reads node proxy_pairs[2p + 1] of the system attached as dependency
     * proxy_pairs[2p] (< dependency_count; glow_system_set_neighbour) */
    uint32_t dependency_count;
    const uint32_t *proxy_pairs;
    /* \since 0.2: the bake's bounds diagonal (m): a budget's default focus radius is 0.1 of it */
    float scene_diag;
    /* \since 0.2: the bake's glow_link_kind_bits. With GLOW_LINK_KIND_GRADIENT (link gradients,
     * glow-bake --link-subsets gradient) link_subsets is NULL and the links' gradient codes are in
     * the fields below (since 0.2; the GL backend reads them): a backend that does not implement them
     * must refuse the system */
    uint32_t link_kind;
    /* \since 0.2, link gradients (link_kind & GLOW_LINK_KIND_GRADIENT; all 0 / NULL without): the
     * links' gradient codes (LSUB, one per link in link_blocks' order: 0 = none, else bit 15 and
     * k_x + 15, k_y + 15, k_z + 15 in bits 0-4, 5-9, 10-14; docs/bake-format.md "LSUB"); the
     * gradient_node_count internal nodes some coded link reads (ascending); per such node k,
     * its area centroid c (3) and M = sigma (C + 1e-3 trace(C) I)^-1 (9, row-major), computed once
     * at load, as values q = 0..11 in blocks of four nodes: value q of node k at
     * gradient_cm[48 (k / 4) + 4 q + k % 4], the node count rounded up to 4 (the CPU solver reads a
     * value of four nodes at once). Each update the CPU solver pulls the luma-flux moments
     * m = sum of the leaves' Yflux p (p the surfel position) and sets u = M (m / Yflux - c) (0 where
     * Yflux <= 0), rounded to IEEE halves (|u| < 2^-14: 0, above 65504: 65504); a coded link reads
     * its node's radiance times max(0, 1 + ((k_x u_x + k_y u_y) + k_z u_z) / 15) */
    const uint16_t *link_gradients;
    uint32_t gradient_node_count;
    const uint32_t *gradient_nodes;
    const float *gradient_cm;
    /* \since 0.2: the grid caches are the first grid_cache_count caches; for bakes with the sky transfer
     * (format 1.6 SKYT) sky_grid_visibility is each one's visibility SH V ([grid_cache_count][9],
     * glow_bake_sky_transfer.grid_visibility), NULL without: a backend's glow_system_set_sky
     * (glow_gl_system_set_sky) */
    uint32_t grid_cache_count;
    const float *sky_grid_visibility;
} glow_solver_tables;
/** Fills `out_tables`. \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT for NULL. \threadsafety Between
 * updates; the views change only through the setters and updates. \since 0.1 */
GLOW_API glow_result glow_system_get_solver_tables(const glow_system *system, glow_solver_tables *out_tables);

/** The budget's choice of cache groups (glow_update_desc: max_caches, focus), for backends that gather
 * on their own; the CPU solver makes its choice with it. Groups are GLOW_BUDGET_GROUP caches in cache
 * order, `centre` [groups][3] their mean positions, `age` [groups] the updates since each was last
 * gathered (updated: +1, and 0 for the chosen), `skip` [groups] (or NULL) groups not to gather (the CPU
 * solver's converged ones). Priority (age + 1)(1 + 4 f), f = max over the focus points of
 * 1 / (1 + d² / focus_radius²); ties to the lower index. The best min(max_groups, candidates) go to
 * out_sel in index order; scratch holds `groups` uint64s. No allocation. \returns how many. \since 0.2 */
GLOW_API uint32_t glow_budget_choose(const float *centre, uint32_t *age, const uint8_t *skip, uint32_t groups,
                                     const float *focus, uint32_t focus_count, float focus_radius, uint32_t max_groups,
                                     uint64_t *scratch, uint32_t *out_sel);

/** A time budget's model of the cache gathers, for backends that gather on their own; the CPU solver
 * keeps one per system. One bounce iteration that gathers k groups on `workers` parallel workers takes
 * dispatch_ms + group_ms * k / min(k, workers). Both 0 until the first sample. \since 0.2 */
typedef struct glow_budget_cost {
    double group_ms;    /* one group's gather on one worker, ms */
    double dispatch_ms; /* a gather's time beyond its groups' (wake-up and join), ms */
} glow_budget_cost;
/** Teaches `cost` from one update that gathered `k` groups in `iters` bounce iterations: `wall_ms` all
 * of them, `busy_ms` the groups' own times summed (a backend that cannot time its groups passes
 * wall_ms and workers 1). A sample lowers the estimate fully (EMA 0.2) and raises it in proportion to
 * min(1, k / teach): a few groups cost more each than many, so their figure bounds a larger selection's
 * from above; a sample above twice the estimate counts as twice. Samples with k, iters or a time of 0
 * (or not finite) change nothing. \since 0.2 */
GLOW_API void glow_budget_cost_learn(glow_budget_cost *cost, uint32_t k, uint32_t teach, uint32_t workers,
                                     uint32_t iters, double wall_ms, double busy_ms);
/** How many groups fit `ms` (all `iters` iterations) by `cost`: at least 1. \since 0.2 */
GLOW_API uint32_t glow_budget_cost_fit(const glow_budget_cost *cost, double ms, uint32_t workers, uint32_t iters);

/** The visible sky of the grid caches as cache rows (cache_sh's layout: luma² Y, chroma² Co, chroma²
 * Cg per cache): per grid cache c, V_c ⊗ L (glow_sh_sky_visible of `visibility` [grid_caches][9] with
 * the sky `sh_rgb`) in YCoCg, coefficients past the bands dropped. glow_system_set_sky adds these rows
 * to the grid caches; a backend's (glow_gl_system_set_sky) uploads them, so both add the same floats.
 * out_rows: [grid_caches][luma² + 2 chroma²]. No allocation. \since 0.2 */
GLOW_API void glow_sky_grid_rows(const float *visibility, uint32_t grid_caches, const float sh_rgb[GLOW_SKY_SH_FLOATS],
                                 uint32_t luma_bands, uint32_t chroma_bands, float *out_rows);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_BACKEND_H */
