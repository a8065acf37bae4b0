/*
 * glow_precompute.h — the Glow linker as a library (what `glow-bake` is a thin CLI over).
 *
 * Turns a static scene (any file assimp reads, or `builtin:cornell|furnace|two-rooms`) into a
 * bake file: surfels (PIC 4.2), a HAC hierarchy (4.3), caches (grid + lightmap texels, 4.4) and
 * visibility-aware links (4.5, 4.6, App. A). See runtime/src/bake/bake_format.h for the file.
 *
 * WHAT IT DOES NOT DO: light anything (that is the runtime), or keep global state.
 *
 * ON ERRORS: glow_pc_bake returns a glow_result; the message (naming the file and the problem)
 * goes to settings.log and is copied to stats.error. The output file is written to a temporary
 * name and renamed only when complete: a failed or killed bake leaves no file behind.
 *
 * ON THREADS: glow_pc_bake may run concurrently with itself on different outputs. Its result is
 * byte-identical for any settings.threads.
 */
#ifndef GLOW_GLOW_PRECOMPUTE_H
#define GLOW_GLOW_PRECOMPUTE_H

#include "glow/glow.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum glow_pc_quality {
    GLOW_PC_QUALITY_DEFAULT = 0, /* = moderate */
    GLOW_PC_QUALITY_LOW,
    GLOW_PC_QUALITY_MODERATE,    /* PIC: n_S = 32k, n_L = 128, l = 3, ~10k caches (8000 lightmap) */
    GLOW_PC_QUALITY_HIGH,        /* PIC: n_S = 128k, n_L = 254, l = 4, ~10k caches */
    GLOW_PC_QUALITY_FINE,        /* n_S = 128k, n_L = 128, l = 3, ~34k caches (32000 lightmap): near light */
    GLOW_PC_QUALITY_FORCE_U32 = 0x7FFFFFFF
} glow_pc_quality;

/* Deprecated, removed in 0.2: glow_pc_settings.logger takes glow.h's glow_logger. */
typedef void (*glow_pc_log_fn)(void *user, glow_log_level level, const char *message);
/* stage: 0-based index into glow_pc_stage_names; fraction in [0,1] of that stage. */
typedef void (*glow_pc_progress_fn)(void *user, uint32_t stage, double fraction);

enum { GLOW_PC_STAGE_COUNT = 7 };
/* "import", "surfels", "hierarchy", "caches", "links", "write", ... */
GLOW_API const char *glow_pc_stage_name(uint32_t stage);

/* How the linker decides which surfels a cache sees (docs/linker.md, "Clustered visibility"). */
typedef enum glow_pc_link_visibility {
    GLOW_PC_LINK_VISIBILITY_DEFAULT = 0, /* clustered */
    GLOW_PC_LINK_VISIBILITY_CLUSTERED,   /* far, small clusters share a few sampled rays: rays per cache
                                            about constant in the surfel count (--link-visibility clustered) */
    GLOW_PC_LINK_VISIBILITY_EXACT,       /* one ray per (cache, surfel): caches x surfels rays (exact) */
    GLOW_PC_LINK_VISIBILITY_FORCE_U32 = 0x7FFFFFFF
} glow_pc_link_visibility;

/* A bake split over several processes (glow-bake --mpi, precompute/tool/bake_mpi.c; docs/linker.md
 * "A bake over MPI"). Every process calls glow_pc_bake with the same scene and settings and its own
 * rank. The stages before the links are computed by each (they are a few percent of a bake); the
 * links stage, which grows as caches x links, is split in contiguous index ranges: each rank computes
 * its share of the caches' links and of the lightmap detail texels, and share() exchanges the shares.
 * Only rank 0 writes the bake (the others' out_path is not touched), and its bytes are the
 * one-process bake's for any number of ranks (each cache's links depend on nothing but the cache).
 * A bake split into systems (system_area) gives whole systems to the ranks instead (the k-th system to
 * bake to rank k mod ranks), each rank writes the systems it baked (out_path's folder must be shared),
 * share() exchanges their figures and rank 0 writes the manifest. Every rank's summary (glow_pc_stats)
 * then holds the whole world's figures as a one-process bake's would, but for the stage times and peak
 * memory, which are the rank's own.
 * No MPI in the library: the host supplies the exchange. */
typedef struct glow_pc_distribution {
    uint32_t rank, ranks; /* this process's rank, 0 <= rank < ranks */
    /* buf holds one part per rank, part r in bytes [offsets[r], offsets[r + 1]); on entry this rank's
       part is filled, on return every part is. Every rank calls it with the same offsets, in the same
       order. Return GLOW_OK, or an error when the exchange failed (a rank died): the bake then fails
       with that code and writes nothing. */
    glow_result (*share)(void *user, void *buf, const size_t *offsets);
    void *user;
    /* optional, for a world bake (system_area): called on every rank before the first system's bake is
       written, with every file of the new world that any rank may write (the systems baked or
       re-indexed now; the unchanged ones keep their files, which have other names), and on the rank
       that writes the manifest once more with (NULL, 0) just before it writes it. Until then, a
       launcher that stops this rank because another failed can remove those files (and their
       "<path>.tmp.<pid>" temporaries) so that a failed job leaves no part of the new world and the
       old world whole. The list is only valid during the call. \since 0.2 */
    void (*will_write)(void *user, const char *const *paths, uint32_t count);
} glow_pc_distribution;

typedef struct glow_pc_settings {
    glow_pc_quality quality;  /* presets below; 0 = moderate */
    uint32_t surfels;         /* n_S, 0 = preset */
    uint32_t links;           /* n_L per cache, 0 = preset */
    uint32_t bands;           /* SH bands l (2..8), 0 = preset */
    float grid_spacing;       /* m, 0 = from the scene size */
    float texel_density;      /* lightmap texels per m, 0 = from the scene area */
    uint32_t threads;         /* 0 = all online CPUs */
    uint32_t seed;            /* 0 is a valid seed; same seed, same bytes */
    bool sh_links;            /* also write full-SH links (SHLK) */
    uint32_t relax_iterations;/* 0 = preset */
    uint32_t rays_per_surfel; /* 0 = 1 */
    glow_pc_log_fn log;       /* deprecated: use logger (below); removed in 0.2. Used
                                 only when logger.log is NULL, and gets every message as it happens */
    void *log_user;
    glow_pc_progress_fn progress; /* NULL = none */
    void *progress_user;
    bool no_link_normalize;   /* false (default): scale each cache's link solid angles to the
                                 ray-measured visible geometry (energy-conserving); true: leave the
                                 disc/near-field estimates as they are (--no-link-normalize) */
    bool cut_error;           /* kept for source compatibility: the error cut is now the default (see
                                 cut_solid_angle); true asks for it explicitly */
    const char *audit_radiance; /* optional: a file of one float32 radiance per surfel (any lighting;
                                   glow-stability audit --radiance-out); the linker then compares each
                                   cache's gather through its cut with the exact gather through its
                                   visible surfels and logs the summary (--audit-radiance) */
    const char *audit_csv;      /* optional, with audit_radiance: the per-cache figures as CSV (--audit-csv) */
    bool cut_solid_angle;       /* false (default): refine each cache's cut by a bound on each link's
                                   error, which splits partly visible nodes first and links a node's
                                   visible subtree (--cut error); true: by visible solid angle, as PIC
                                   4.5 (--cut solid-angle). Not both with cut_error (docs/linker.md,
                                   "The cut and its audit") */
    uint32_t lightmap_caches;   /* the lightmap's budget: how many texels hold a cache (each costs links
                                   per cache x 8 bytes and a gather per update); the texel density is
                                   searched to land within 20 % of it. 0 = preset; ignored when
                                   texel_density is set (--lightmap-caches) */
    bool no_link_subsets;       /* false (default): links whose node the cache sees unevenly carry four
                                   weights (LSUB, 2 bytes per link) so that they read the light of the
                                   part it sees, not the node's mean; true: no LSUB, PIC's links
                                   (--link-subsets off; docs/linker.md "Link subsets") */
    glow_logger logger;         /* zero = silent. The runtime's logger (glow.h), so that one sink serves
                                   both: warnings and info as they happen (code GLOW_OK), the error
                                   once, when glow_pc_bake returns, with the code it returns (the text
                                   of stats.error); file NULL, line 0. Replaces log. */
    /* new fields go last, so that code built against older headers keeps its layout */
    glow_pc_link_visibility link_visibility; /* 0 = clustered (--link-visibility) */
    float link_cluster_angle;   /* clustered: a cluster looks at most this many radians (bounding radius
                                   over distance) from the cache; 0 = default (--link-cluster-angle) */
    uint32_t link_cluster_rays; /* clustered: sampled rays per cluster; 0 = default (--link-cluster-rays) */
    uint32_t lightmap_detail;   /* detail texels per lightmap texel side (2..4), each correcting its caches'
                                   near light through a few links to the surfels beside it (LDET,
                                   docs/linker.md "Lightmap detail"); 0 = default (3, or 4 where open
                                   ground's texels span more than 3 nominal surfel spacings), 1 = none
                                   (--lightmap-detail) */
    uint32_t detail_links;      /* at most this many links per detail texel; 0 = default (--detail-links) */
    float detail_radius;        /* a detail texel corrects the light of surfels within this many lightmap
                                   texels of it; 0 = default (--detail-radius) */
    float surfel_adapt;         /* surfels up to this many times as dense in concave places (surfaces
                                   facing each other within the links' near field) as on open ground,
                                   at the same count; each surfel carries its own area (format 1.3).
                                   0 = preset (low and moderate 4, high and fine 1), 1 = area-uniform,
                                   at most 4 (--surfel-adapt) */
    const glow_pc_distribution *distribution; /* NULL = this process bakes alone */
    float system_area;          /* > 0: split the scene into systems (issue 16) of at most this much
                                   surface (scene units²) each, cells of a k-d tree anchored at the origin,
                                   and bake each with its own surfels, hierarchy, caches and links, with
                                   the budgets above per system_area of surface (a system of half that
                                   area gets half the surfels and caches). out_path then names the world
                                   manifest (JSON), beside which the systems' bakes are written; a world
                                   already there is re-baked incrementally (unchanged systems kept). The
                                   other systems' geometry within system_reach occludes, and their light
                                   reaches this system's caches through links to their trees (bake
                                   format 1.4, XREF; docs/linker.md "Systems"). 0 = one system
                                   (--system-area) */
    float system_reach;         /* with system_area: how far around a system, as a fraction of its bounds'
                                   diagonal, other systems' triangles occlude its rays and its caches link
                                   their light (its neighbours, the distance limit of its dependencies);
                                   0 = 0.5, at most 4 (--system-reach) */
    float texel_adapt;          /* generated lightmap charts get up to this many times as many texels per
                                   area where their surface faces other surfaces within the links' near
                                   field (an arch, a capital, a pier's foot) as open walls and floors,
                                   within the same lightmap budget (docs/linker.md "Caches"); a mesh's
                                   own second UV set keeps its layout. 0 = preset (low and moderate 4,
                                   high and fine 1), 1 = uniform, at most 8 (--texel-adapt).
                                   \since 0.2 */
    uint32_t grid_refine;       /* the grid is this many times finer in the cells that geometry comes near
                                   (bricks of R³ fine cells, bake format 1.5) than in open space, within
                                   the same grid budget; grid_spacing, when given, is then the fine
                                   spacing (docs/linker.md "Caches"). 0 = preset, 1 = uniform, 2 or 4
                                   (--grid-refine). \since 0.2 */
    /* with system_area: systems named by the user, each "NAME=PATTERN[,PATTERN...]": the triangles of
       the file's objects (a node's name, else its mesh's: OBJ o / g, glTF nodes) whose name matches a
       pattern (fnmatch(3): *, ?, [...]) form system NAME, whole, whatever its area; the first group
       that matches takes an object. The rest is split by system_area as without. NAME: 1..48 of
       [A-Za-z0-9_-]. At most 256 groups (--system-group, repeated). \since 0.2 */
    const char *const *system_groups;
    uint32_t system_group_count;
    bool link_gradients;        /* with link subsets on: each link carries instead the gradient of the
                                   cache's response across its node (LSUB holds a 16-bit code, link_kind
                                   GLOW_LINK_KIND_GRADIENT) and reads its node's radiance times
                                   1 + e . u, u from where in the node the light is (the flux centroid,
                                   each update). The CPU runtime and the GL backend read it
                                   (--link-subsets gradient; docs/linker.md "Link gradients").
                                   \since 0.2 */
    bool no_sky;                /* false (default): the bake carries the sky transfer (section SKYT,
                                   format 1.6): per surfel the SH l <= 2 transfer of the cosine-weighted
                                   visible sky, per grid cache the visible sky's SH, so that a host lights
                                   with an HDR sky map that turns or changes without a re-bake
                                   (docs/sky.md). true: none (--no-sky). \since 0.2 */
    uint32_t sky_rays;          /* rays per surfel for the sky transfer, and 8x as many per grid cache; 0 =
                                   128 (the CPU host's sky_rays default, whose rays they are), at most 65536
                                   (--sky-rays). \since 0.2 */
    uint32_t lightmap_max_size; /* texels a side of a lightmap atlas, a multiple of 4 in 4..4096; 0 = 4096.
                                   Generated charts that do not fit one atlas at the density asked for go
                                   onto several pages of this size (up to 64, bake format 1.7) rather than
                                   to a lower density; a mesh's own second UV set stays one atlas
                                   (--lightmap-max-size). \since 0.2 */
    /* with system_groups: each group's declared neighbours, the named systems whose light its caches
       may link (its dependencies), as "NAME[,NAME...]" of other groups' names, "" for none; NULL (the
       array, or a group's entry) = automatic: every system within its reach, as for the systems split
       by area. A declared neighbour is linked only within the reach (system_reach: the distance
       limit); one beyond it is warned about. Occluders are not declared: every triangle within the
       reach blocks a system's rays. Dependencies may be mutual or form longer cycles (light goes both
       ways; a system's tree never depends on its neighbours); a group naming itself, a name that is no
       group's, or a name given twice is refused (GLOW_ERROR_INVALID_ARGUMENT). glow-bake --systems
       FILE.json fills this and system_groups (docs/linker.md "Systems named by the user").
       \since 0.2 */
    const char *const *system_neighbours;
} glow_pc_settings;

typedef struct glow_pc_stats {
    double stage_seconds[GLOW_PC_STAGE_COUNT];
    size_t stage_peak_rss[GLOW_PC_STAGE_COUNT]; /* bytes, process peak RSS at the stage's end */
    double total_seconds;
    /* resolved settings */
    uint32_t surfels, links_per_cache, bands, threads, seed;
    float grid_spacing, texel_density;
    /* counts */
    uint32_t source_triangles, triangles, materials, textures, textures_missing;
    uint32_t skipped_degenerate, skipped_duplicate, skipped_nonfinite;
    uint32_t skipped_repeated, skipped_collinear; /* the degenerate ones by reason (sum: skipped_degenerate):
                                                     repeated corners; corners collinear relative to the
                                                     triangle's own size (never: small in scene units) */
    uint32_t nodes, levels;
    uint32_t grid_dims[3], grid_caches, grid_inside;
    uint32_t lightmap_width, lightmap_height, lightmap_caches, lightmap_invalid, charts;
    uint32_t small_charts, shared_texels; /* charts narrower than a texel, and the texels they share
                                             (merged by position and facing; a lone one keeps its own) */
    uint32_t lightmap_gutter, lightmap_unused; /* atlas texels holding a gutter copy / nothing */
    float lightmap_coverage;  /* mean share of a covered texel's area that is surface (the rest
                                 overhangs its chart's border: budget spent on no surface) */
    uint32_t caches;
    uint64_t links;
    double scene_area;
    /* file */
    uint64_t file_size;
    uint32_t section_count;
    uint32_t section_fourcc[16];
    uint64_t section_size[16];
    double bytes_per_link;    /* LINK section bytes / links */
    char error[1024];         /* last error message, "" on success */
    /* new fields go last. The lightmap detail (glow_pc_settings.lightmap_detail): */
    uint32_t detail_factor;   /* detail texels per lightmap texel side, 0 = none */
    uint32_t detail_texels;   /* detail texels that cover a surface */
    uint32_t detail_corrected;/* ... of which correct their caches' near light (have links) */
    uint64_t detail_links;
    /* systems (glow_pc_settings.system_area): how many; 1 for a bake of one. With several, the counts
     * and sizes above are sums over the systems, the resolved settings those of the largest, and
     * stage_peak_rss the largest over the systems */
    uint32_t systems;
    uint32_t systems_reused;  /* ... of which an incremental re-bake kept unchanged (their figures above
                                 are only those the manifest records: surfels, caches, bytes) */
    uint32_t systems_patched; /* \since 0.2: ... of those, unchanged but for their triangles' indices in the
                                 file (triangles added or removed before them): the old file re-indexed */
    /* light across systems: the systems whose trees the caches link (summed over the systems baked) and
     * the proxy nodes those links read (bake format 1.4, XREF) */
    uint32_t dependencies;
    uint64_t proxies;
    float texel_density_max;  /* texels per m of the most concave generated chart (texel_adapt; equal to
                                 texel_density when uniform) \since 0.2 */
    uint32_t grid_refine;     /* the grid's refinement near geometry (grid_refine; 0 = uniform) ... */
    uint32_t grid_bricks;     /* ... the coarse cells refined ... */
    uint32_t grid_fine_caches;/* ... and the fine caches among grid_caches (grid_dims and grid_spacing are
                                 the coarse lattice's) \since 0.2 */
    double sky_seconds;       /* the sky transfer's share of the caches stage (0 with no_sky) \since 0.2 */
    uint32_t sky_rays;        /* its rays per surfel (8x per grid cache), 0 = none written \since 0.2 */
    uint32_t lightmap_pages;  /* atlases of lightmap_width x lightmap_height (1 with a lightmap that fits
                                 one; lightmap_max_size) \since 0.2 */
    uint32_t systems_trees_read; /* neighbours' trees an incremental re-bake read from their previous bakes
                                 (bake format 1.8, PTRE) instead of placing and clustering their surfels
                                 again \since 0.2 */
} glow_pc_stats;

/** Resolves presets: fills every zero field of `settings` from its quality. \since 0.1 */
GLOW_API glow_pc_settings glow_pc_settings_resolve(const glow_pc_settings *settings);

/** Validates settings: returns GLOW_ERROR_INVALID_ARGUMENT and writes a message for absurd values
 * (e.g. bands outside 2..8, surfels < 16 or > 4M, links outside 1..4096). \since 0.1 */
GLOW_API glow_result glow_pc_settings_validate(const glow_pc_settings *settings, char *message, size_t message_size);

/** Bakes `scene_path` into `out_path` (atomic: temp file + rename). `stats` may be NULL. With
 * settings->system_area, out_path names the world manifest and the systems' bakes are written beside
 * it as STEM.sDEPTH-PATH-KEY.glow (STEM: out_path less a ".json" or ".glow" ending); a world already at
 * out_path keeps its unchanged systems; on failure the files this call wrote are removed.
 * \returns GLOW_OK; GLOW_ERROR_IO (missing/unreadable input, unwritable output, disk full),
 * GLOW_ERROR_UNSUPPORTED (unknown format), GLOW_ERROR_EMPTY_SCENE, GLOW_ERROR_CORRUPT_DATA,
 * GLOW_ERROR_INVALID_ARGUMENT, GLOW_ERROR_OUT_OF_MEMORY. \since 0.1 */
GLOW_API glow_result glow_pc_bake(const char *scene_path, const char *out_path, const glow_pc_settings *settings,
                                  glow_pc_stats *stats);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_PRECOMPUTE_H */
