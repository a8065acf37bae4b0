/*
 * pc_internal.h — internal data structures of the linker (precompute). Not installed.
 *
 * Pipeline (glow_pc_bake in pipeline.c):
 *   import.c / builtin.c   -> glow__scene        triangles, materials, textures (cleaned)
 *   rt.c                   -> glow__rt           Embree scene over the triangles
 *   surfels.c              -> glow__surfels      PIC 4.2: Halton placement + tangential relaxation
 *   hierarchy.c            -> glow__hierarchy    PIC 4.3: HAC with k-d tree NN search; REORDERS surfels
 *   caches.c, charts.c     -> glow__caches       PIC 4.4: grid + lightmap texels, surfel feedback
 *   links.c                -> glow__links        PIC 4.5/4.6/App. A
 *   bake_write.c           -> file               runtime/src/bake/bake_format.h
 *
 * Conventions: every array is allocated with malloc/calloc and freed by the matching *_free();
 * functions return glow_result and report problems through glow__log (one message naming the
 * file and the problem). Work that takes time runs through glow__parallel_for and must give
 * identical results for any thread count (no reductions whose order depends on scheduling).
 */
#ifndef GLOW_PC_INTERNAL_H
#define GLOW_PC_INTERNAL_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h"
#include "glow/glow_precompute.h"

#include "glow/glow_pc_kit.h" /* the scene kit shared with this repository's tools: scene, rays, pool, log */

/* ---------------------------------------------------------------- surfels (surfels.c) */
typedef struct glow__surfel {
    float pos[3];
    float nrm[3];             /* unit; the triangle's shading normal at the surfel */
    float albedo[3];          /* material albedo x texture, linear */
    float emission[3];        /* W/(m²·sr) */
    uint32_t tri;             /* scene triangle it lies on */
    float bary[2];            /* barycentrics (of corners 1, 2) on tri */
    uint32_t material;
    float area;               /* m²: its share of the surface (all equal unless the density adapts) */
} glow__surfel;

typedef struct glow__surfels {
    uint32_t count;
    glow__surfel *s;
    float area;               /* the nominal area, scene area / count (META surfel_area); each
                               * surfel's own is s[i].area, equal to it unless the density adapts */
    uint32_t adapted;         /* 1 when the density followed the surface's concavity */
} glow__surfels;

typedef struct glow__surfel_settings {
    uint32_t count;           /* target n_S (exact: placement yields exactly this many) */
    uint32_t seed;            /* scrambles the Halton sequence */
    uint32_t relax_iterations;/* 0 = none */
    float adapt;              /* > 1: the density in concave places may be up to this many times the
                               * density on open flat ground (needs rt); <= 1: area-uniform */
    const glow__rt *rt;       /* for the concavity rays (adapt > 1) */
} glow__surfel_settings;

/* The area of scene triangle t, in double precision (surfels.c). */
double glow__tri_area(const glow__scene *scene, uint32_t t);
/* Concavity (surfels.c; the surfels' adaptive density and caches.c's texel density per chart): how
 * many of GLOW__NEAR_RAYS cosine-distributed rays (a Fibonacci spiral about unit normal n, turned by
 * phi0 radians) from org meet any surface within reach (tnear eps). */
/* Area-proportional points (surfels.c): out_tri[0, count) the triangle of each, from a running
 * cumulative area over the triangles in order (units of `total`, their summed area), so that small
 * triangles accumulate area until one gets a point. */
void glow__spawn_tris(const glow__scene *scene, double total, uint32_t count, uint32_t *out_tri);
#define GLOW__NEAR_RAYS 16u
uint32_t glow__near_hits(const glow__rt *rt, const float org[3], const double n[3], double phi0, float reach, float eps);
glow_result glow__surfels_place(const glow__scene *scene, const glow__surfel_settings *settings,
                                glow__pool *pool, glow__log *log, glow__surfels *out);
void glow__surfels_free(glow__surfels *s);

/* ---------------------------------------------------------------- k-d tree (kdtree.c) */
/* Static 3-d tree over points for k-nearest-neighbour queries (relaxation, cache placement). */
typedef struct glow__kdtree glow__kdtree;
glow__kdtree *glow__kdtree_build(const float (*points)[3], uint32_t count);
void glow__kdtree_free(glow__kdtree *tree);
/* Up to k nearest points to q (excluding index `exclude`, pass UINT32_MAX for none), sorted by
 * distance; returns how many were found. */
uint32_t glow__kdtree_knn(const glow__kdtree *tree, const float q[3], uint32_t k, uint32_t exclude,
                          uint32_t *out_index, float *out_dist2);
/* The same among the points within max_dist2 (squared distance, inclusive) of q only: the k nearest of
 * them, so a caller that stops at the first point beyond the radius sees what glow__kdtree_knn gives,
 * while boxes beyond it are never visited. */
uint32_t glow__kdtree_knn_within(const glow__kdtree *tree, const float q[3], uint32_t k, uint32_t exclude,
                                 float max_dist2, uint32_t *out_index, float *out_dist2);

/* A uniform grid over points for the same k-nearest queries (kdtree.c), faster where they come by the
 * million over a surface: cells of side `cell` over [lo, hi] (coarser when that would make more than
 * 8 cells a point), which should hold every query and point. glow__pointgrid_knn gives exactly what
 * glow__kdtree_knn gives for the same points (ties by the smaller index). */
typedef struct glow__pointgrid glow__pointgrid;
glow__pointgrid *glow__pointgrid_build(const float (*points)[3], uint32_t count, const float lo[3], const float hi[3],
                                       float cell);
void glow__pointgrid_free(glow__pointgrid *grid);
uint32_t glow__pointgrid_knn(const glow__pointgrid *grid, const float q[3], uint32_t k, uint32_t exclude,
                             uint32_t *out_index, float *out_dist2);
/* The same among the points within max_dist2 of q only (squared, inclusive), as glow__kdtree_knn_within:
 * the rings stop at the radius. */
uint32_t glow__pointgrid_knn_within(const glow__pointgrid *grid, const float q[3], uint32_t k, uint32_t exclude,
                                    float max_dist2, uint32_t *out_index, float *out_dist2);
/* The nearest point alone (what glow__pointgrid_knn gives with k = 1, the same index), or UINT32_MAX
 * for an empty grid; *out_dist2 its squared distance. Cheaper: no list, q's own row of cells first. */
uint32_t glow__pointgrid_nearest(const glow__pointgrid *grid, const float q[3], float *out_dist2);

/* ---------------------------------------------------------------- hierarchy (hierarchy.c) */
typedef struct glow__node {
    uint32_t child[2];        /* GLOW_NODE_NONE for leaves */
    uint32_t parent;          /* GLOW_NODE_NONE for the root */
    uint32_t level;           /* 0 for leaves, 1 + max(children) otherwise */
    float pos[3];             /* area-weighted centre */
    float nrm[3];             /* normalised area-weighted mean normal (may be 0 if they cancel) */
    float area;               /* sum of leaf areas */
} glow__node;

typedef struct glow__hierarchy {
    uint32_t leaf_count, node_count;  /* node_count = 2*leaf_count - 1 */
    glow__node *nodes;                /* leaves [0, leaf_count) = surfels in order; then internal
                                         nodes sorted by level; root = node_count - 1 */
    uint32_t level_count;             /* max level + 1 */
    uint32_t *level_start;            /* [level_count + 1] */
} glow__hierarchy;

/* HAC with the PIC metric (Cn = 0.1, Cb = 0.02). Reorders surfels->s in place (depth-first leaf
 * order, so siblings are neighbours in memory). */
glow_result glow__hierarchy_build(glow__surfels *surfels, const float scene_min[3], const float scene_max[3],
                                  glow__pool *pool, glow__log *log, glow__hierarchy *out);
void glow__hierarchy_free(glow__hierarchy *h);

/* ---------------------------------------------------------------- caches (caches.c, charts.c) */
typedef struct glow__cache {
    float pos[3];
    float nrm[3];             /* lightmap: surface normal; grid: 0,0,0 (spherical) */
    uint32_t kind;            /* GLOW_CACHE_KIND_GRID / _LIGHTMAP (bake_format.h) */
    uint32_t texel;           /* grid cell index or lightmap texel index (page*w*h + y*w + x) */
} glow__cache;

typedef struct glow__cache_settings {
    float grid_spacing;       /* m; 0 = from the scene size (target_grid caches) */
    float texel_density;      /* texels per m; 0 = from the scene area (target_lightmap texels) */
    uint32_t target_grid;     /* used when grid_spacing == 0 */
    uint32_t target_lightmap; /* used when texel_density == 0 */
    uint32_t seed;
    uint32_t detail_factor;   /* >= 2: also place the lightmap's detail texels, this many a texel side
                                 (links.c "Lightmap detail"); 0 = none */
    float texel_adapt;        /* > 1: generated charts' texel density follows their concavity, up to
                                 this many times the area density of open flat charts; <= 1: uniform */
    float adapt_reach;        /* m: how far the concavity rays look (the links' near field) */
    uint32_t grid_refine;     /* >= 2: the grid is refined this many times near geometry (grid_fine.c);
                                 grid_spacing is then the fine spacing */
    uint32_t detail_factor_max; /* > detail_factor: raise the detail factor, up to this, until open ground's
                                   detail texels (the coarsest) are no wider than detail_spacing */
    float detail_spacing;       /* m: the surfels' nominal spacing, sqrt(nominal area) */
    uint32_t lightmap_max_size; /* texels a side of an atlas page (a multiple of 4); 0 = GLOW__CHART_MAX_ATLAS.
                                   Generated charts that do not fit one page go onto several (issue 16 item 5) */
} glow__cache_settings;

typedef struct glow__caches {
    uint32_t count;
    glow__cache *caches;      /* grid caches first, then lightmap caches */
    uint32_t grid_cache_count, lm_cache_count;
    /* grid */
    float grid_origin[3], grid_spacing;
    uint32_t grid_dims[3];
    uint32_t *grid_map;       /* [dims product]: cache index | GLOW_MAP_COPY_BIT | GLOW_MAP_EMPTY */
    uint32_t grid_inside;     /* grid points rejected as inside solid geometry */
    /* the grid refined near geometry (grid_fine.c; bake section GFIN): grid_refine 0 = not refined */
    uint32_t grid_refine, grid_brick_count;
    uint32_t *grid_brick_of_cell; /* [dims product]: brick of the cell whose lowest corner is that point, or GLOW_MAP_EMPTY */
    uint32_t *grid_bricks;    /* [brick][(R+1)³]: cache index of each fine lattice point (x fastest) or GLOW_MAP_EMPTY */
    uint32_t grid_fine_count; /* fine caches, after the coarse grid caches (grid_cache_count counts both) */
    uint32_t grid_fine_inside;/* fine points rejected as inside solid geometry */
    float (*grid_fine_pos)[3];/* [grid_fine_count], until caches.c appends them */
    uint32_t *grid_fine_cell; /* [grid_fine_count] the coarse cell each lies in */
    /* lightmap: lm_pages atlases of lm_width x lm_height, stacked (texel page*w*h + y*w + x) */
    uint32_t lm_width, lm_height, lm_pages;
    uint32_t *lm_page;        /* [tri_count] each triangle's page (all 0 with one page) */
    float texel_density;
    float texel_density_max;  /* the finest chart's (caches.c, texel density per chart) */
    uint32_t *lm_map;         /* [pages*w*h], same encoding as grid_map */
    uint32_t lm_invalid;      /* texels that saw back faces (filled from neighbours) */
    uint32_t lm_gutter;       /* atlas texels outside every footprint that hold a copy (gutters) */
    uint32_t lm_unused;       /* atlas texels that hold nothing */
    double lm_footprint;      /* Σ over covered texels of the surface area inside them, in texels */
    float (*lm_uv)[2];        /* [3*tri_count] lightmap UV per triangle corner, in [0,1] of its page */
    uint32_t chart_count;     /* 0 when the mesh's own second UV set was used */
    uint32_t small_charts;    /* charts narrower than a texel (charts.h GLOW__CHART_SMALL) ... */
    uint32_t shared_texels;   /* ... and the texels they share (a lone one keeps its own) */
    /* per surfel (in the hierarchy's surfel order): cache whose light it re-emits */
    uint32_t *surfel_feedback;
    /* lightmap detail (cache settings' detail_factor): the texels of a detail_factor-times finer grid
     * over the same atlas that cover a surface, each with a point and normal as a lightmap cache's */
    uint32_t detail_factor, detail_width, detail_height, detail_count;
    uint32_t *detail_texel;   /* [detail_count] page * detail_width * detail_height + y * detail_width + x,
                                 ascending (detail_width x detail_height a page) */
    float (*detail_pos)[3], (*detail_nrm)[3];
} glow__caches;

glow_result glow__caches_build(const glow__scene *scene, const glow__rt *rt, const glow__surfels *surfels,
                               const glow__cache_settings *settings, glow__pool *pool, glow__log *log,
                               glow__caches *out);
void glow__caches_free(glow__caches *c);

/* grid_fine.c: the coarse spacing whose points plus the fine points of its refined cells fit `target`
 * (0 when the scene gives no answer: no triangles, no extent, refine < 2) ... */
double glow__grid_refined_spacing(const glow__scene *scene, uint32_t refine, double target, double max_cells);
/* ... the coarse lattice of a refined grid of coarse spacing s (the box grown by half a fine spacing) ... */
void glow__grid_refined_lattice(const glow__scene *scene, double s, uint32_t refine, uint32_t dims[3], float origin[3]);
/* ... and the refinement of the coarse grid in `ca` (grid_map without dilated copies yet; fine caches
 * numbered from ca->grid_cache_count): fills the grid_refine ... grid_fine_cell fields. */
glow_result glow__grid_refine(const glow__scene *scene, const glow__rt *rt, uint32_t refine, glow__pool *pool,
                              glow__log *log, glow__caches *ca);
/* n directions of a spherical Fibonacci set (caches.c) */
void glow__fibonacci_sphere(uint32_t n, float (*out)[3]);
/* Whether a grid point is inside solid geometry (caches.c, the header's "GRID" rule), from
 * GLOW__GRID_RAYS directions of glow__fibonacci_sphere */
#define GLOW__GRID_RAYS 26u
int glow__grid_point_inside(const glow__rt *rt, const float o[3], const float (*dirs)[3]);

/* Glow's own chart packer (charts.c): per-corner UVs in [0,1] for a w x h atlas at `texel_density`
 * texels per m with `padding` texels between charts. Chooses w, h (multiples of 4). */
glow_result glow__charts_build(const glow__scene *scene, float texel_density, uint32_t padding, glow__log *log,
                               float (*out_uv)[2], uint32_t *out_width, uint32_t *out_height,
                               uint32_t *out_chart_count);

/* ---------------------------------------------------------------- SH maths (sh_math.c) */
/* Real orthonormal SH basis, l bands -> l*l values, index = k*k + k + m (m in [-k, k]).
 * Same convention as runtime/src/sh.c. dir must be unit. */
void glow__sh_eval(uint32_t bands, const float dir[3], float *out);
/* Cone factor k_l(x) (DESIGN §3): SH projection of a cone's indicator, x = cos(half-angle). */
double glow__cone_factor(uint32_t l, double x);

/* ---------------------------------------------------------------- sky transfer (sky.c) */
/* The CPU host's cosine-distributed sky directions around +z (host.c make_sky_dirs), n of them. */
void glow__sky_dirs(uint32_t n, float (*dirs)[3]);
/* SKYT (bake_format.h glow_bake_sky): out_surfel[sf->count][9] the surfels' sky transfer (`rays` rays
 * each), out_grid [ca->grid_cache_count][9] the grid caches' sky visibility SH (`grid_rays` each).
 * Deterministic for any thread count. */
glow_result glow__sky_transfer(const glow__rt *rt, const glow__scene *sc, const glow__surfels *sf,
                               const glow__caches *ca, uint32_t rays, uint32_t grid_rays, glow__pool *pool,
                               float *out_surfel, float *out_grid);

/* ---------------------------------------------------------------- links (links.c) */
typedef struct glow__link_settings {
    uint32_t links_per_cache; /* n_L */
    uint32_t sh_bands;        /* l */
    bool full_sh;             /* also project full-SH links (PIC Eq. 2) */
    uint32_t rays_per_surfel; /* visibility rays per (cache, surfel) */
    uint32_t seed;
    bool no_normalize;        /* false (default): normalise each cache's leaf solid angles (links.c) */
    bool no_cone_fit;          /* keep lightmap links' solid angles (tests of the raw cut); default: fit */
    bool cut_error;            /* false: split by visible solid angle (PIC 4.5, --cut solid-angle); true:
                                  links.c cut_priority and cut_descend (--cut error, the pipeline's default) */
    bool cut_error_omega;      /* with cut_error: rate lightmap caches' nodes by solid angle as grid caches
                                  (before 2026-11-29; tests and A/B), not by the diffuse response */
    const float *audit_radiance; /* optional [surfel count]: a radiance per surfel (any lighting); the
                                    links then also fill glow__links.audit (links.c, "Audit") */
    bool link_subsets;         /* fill glow__link.subsets (LSUB, bake_format.h) */
    bool link_gradients;       /* with link_subsets: LSUB holds link gradient codes instead of slot
                                  weights (GLOW_LINK_KIND_GRADIENT, links.c link_gradient) */
    float cluster_tau;         /* > 0: clustered visibility (links.c cluster_nodes): nodes smaller than
                                  this many radians seen from the cache share cluster_samples rays */
    uint32_t cluster_samples;
    float detail_radius;       /* > 0 with the caches' detail texels: their near light from surfels
                                  within this many lightmap texels (links.c "Lightmap detail") */
    uint32_t detail_links;     /* at most this many per detail texel */
    const glow_pc_distribution *dist; /* several ranks: this one computes its share (links.c "Ranks") */
    /* A system of a world (pipeline.c, "Light across systems"): the hierarchy joins this system's tree
     * and its neighbours' whole trees. Leaves [0, own_leaves) are this system's (0: every leaf is);
     * nodes with join[v] set only join the trees, are split first and never linked; a neighbour leaf
     * outside [trace_lo, trace_hi] (where the system's ray scene holds every occluder) is not traced
     * and counts as hidden. Only own leaves are credited by the near field and normalised. */
    uint32_t own_leaves;
    const uint8_t *join;
    float trace_lo[3], trace_hi[3];
} glow__link_settings;

typedef struct glow__link {
    uint32_t node;
    float factor;             /* surfel_area / node area (times factor_scale at runtime) */
    float one_minus_cos;      /* 1 - cos(alpha) of the equal-visible-solid-angle cone */
    float dir[3];             /* mean visible direction, unit */
    uint16_t subsets;         /* LSUB weights of the node's four slots (bake_format.h), or with
                                 link_gradients its gradient code; 0 = none */
} glow__link;

typedef struct glow__links {
    uint32_t cache_count, per_cache;   /* links[c * per_cache + j] */
    glow__link *links;
    float *sh;                /* full-SH: [cache_count * per_cache * bands²] or NULL */
    uint32_t sh_bands;
    bool gradients;           /* links' subsets are gradient codes (settings link_gradients) */
    double visible_solid_angle_total;  /* sum over caches of visible solid angle (diagnostic) */
    uint64_t visibility_rays;          /* leaf and cluster visibility rays cast, all caches (diagnostic) */
    /* with audit_radiance: per cache [GLOW__AUDIT_FIELDS] = the exact gather through the visible leaves,
     * the gather through the cut, the gather through the cut with each node's visible part's mean, the
     * linked nodes' visible fraction (ω-weighted), the visible solid angle, the gather with each link
     * reading its node's visible leaves' uniform mean, its visible children's means (weighted by their
     * own shares), its visible grandchildren's, and through its LSUB weights (what the runtime reads) */
    float *audit;
    /* lightmap detail (links.c "Lightmap detail"): per detail texel d (the caches' detail_texel order),
     * links [detail_first[d], detail_first[d + 1]) of (surfel, weight): the texel's near-light correction
     * is sum weight * radiance(surfel), cosine-lobe mean radiance like glow_shade_sh's */
    uint32_t detail_count;
    uint32_t *detail_first;   /* [detail_count + 1] */
    uint32_t *detail_surfel;
    float *detail_weight;
    double detail_merged;     /* sum of |weight| the detail_links cap gave to a neighbour, over all texels */
    double detail_total;      /* sum of |weight| before the cap */
} glow__links;
enum { GLOW__AUDIT_FIELDS = 10 };

typedef void (*glow__progress_fn)(void *user, double fraction);
glow_result glow__links_build(const glow__scene *scene, const glow__rt *rt, const glow__surfels *surfels,
                              const glow__hierarchy *h, const glow__caches *caches,
                              const glow__link_settings *settings, glow__pool *pool, glow__log *log,
                              glow__progress_fn progress, void *progress_user, glow__links *out);
void glow__links_free(glow__links *l);

#endif /* GLOW_PC_INTERNAL_H */
