/*
 * bake_format.h — the on-disk layout of a Glow bake (.glow), shared by the writer
 * (precompute/src/bake_write.c) and the reader (runtime/src/bake.c). One header, so the two
 * cannot drift; every size and offset is _Static_assert'ed below.
 *
 * File layout (all little-endian, no pointers, loadable with one read or mmap):
 *
 *   [glow_bake_header]           64 bytes at offset 0
 *   [glow_bake_section x N]      32 bytes each, right after the header (the section table)
 *   [section payloads]           each at a 64-byte aligned offset, in table order, zero padding between
 *
 * The header carries its own CRC-32 (computed with header_crc32 = 0) and the CRC-32 of the section
 * table; each section entry carries the CRC-32 of its payload. CRC-32 is the zlib/PNG polynomial
 * (0xEDB88320, reflected), so `crc32()` from zlib reproduces every value.
 *
 * Versioning: `major` changes when any layout below changes (a reader refuses other majors);
 * `minor` grows when sections are added (readers skip unknown fourccs).
 *
 * Units: positions in scene units (the file's own; "m" below means that unit), areas in m²,
 * albedo is linear-RGB reflectance in [0,1], emission is emitted radiance W/(m²·sr) per unit
 * of the scene's emission scale.
 */
#ifndef GLOW_BAKE_FORMAT_H
#define GLOW_BAKE_FORMAT_H

#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h" /* glow_cache_kind, glow_link_kind_bits */

#define GLOW_BAKE_MAGIC "GLOW"
/* GLOW_BAKE_FORMAT_VERSION_MAJOR / _MINOR: glow.h (public: what this runtime reads). */
#define GLOW_BAKE_ALIGN 64u
#define GLOW_BAKE_MAX_SECTIONS 64u

#define GLOW_FOURCC(a, b, c, d) \
    ((uint32_t)(a) | ((uint32_t)(b) << 8) | ((uint32_t)(c) << 16) | ((uint32_t)(d) << 24))

/* Section fourccs (append only). */
#define GLOW_SECTION_META GLOW_FOURCC('M', 'E', 'T', 'A') /* glow_bake_meta, exactly one */
#define GLOW_SECTION_MATL GLOW_FOURCC('M', 'A', 'T', 'L') /* glow_bake_material[material_count] */
#define GLOW_SECTION_SURF GLOW_FOURCC('S', 'U', 'R', 'F') /* glow_bake_surfel[surfel_count] */
#define GLOW_SECTION_NODE GLOW_FOURCC('N', 'O', 'D', 'E') /* glow_bake_node[node_count] */
#define GLOW_SECTION_LEVL GLOW_FOURCC('L', 'E', 'V', 'L') /* uint32_t[level_count + 1] level starts */
#define GLOW_SECTION_CACH GLOW_FOURCC('C', 'A', 'C', 'H') /* glow_bake_cache[cache_count] */
#define GLOW_SECTION_GRID GLOW_FOURCC('G', 'R', 'I', 'D') /* uint32_t[dx*dy*dz] cell -> cache map */
#define GLOW_SECTION_LMAP GLOW_FOURCC('L', 'M', 'A', 'P') /* uint32_t[pages*w*h] texel -> cache map */
#define GLOW_SECTION_LINK GLOW_FOURCC('L', 'I', 'N', 'K') /* glow_bake_link_block[cache_count*blocks] */
#define GLOW_SECTION_SHLK GLOW_FOURCC('S', 'H', 'L', 'K') /* full-SH links (optional), see below */
#define GLOW_SECTION_GEOM GLOW_FOURCC('G', 'E', 'O', 'M') /* glow_bake_triangle[triangle_count] */
#define GLOW_SECTION_LSUB GLOW_FOURCC('L', 'S', 'U', 'B') /* uint16_t[cache_count*blocks][16] link subsets (optional, link_kind bit 2), see below */
/* Since 1.1 (optional; 1.0 readers skip them): what a host needs to draw the scene textured. */
#define GLOW_SECTION_TUV0 GLOW_FOURCC('T', 'U', 'V', '0') /* float[triangle_count][6] material UVs per corner, GEOM order (with GEOM) */
#define GLOW_SECTION_TEXP GLOW_FOURCC('T', 'E', 'X', 'P') /* char[material_count][GLOW_BAKE_TEXTURE_PATH] albedo texture paths */
#define GLOW_BAKE_TEXTURE_PATH 512u /* bytes per TEXP entry: a NUL-terminated path as the linker opened it, "" for none */
#define GLOW_SECTION_GVIS GLOW_FOURCC('G', 'V', 'I', 'S') /* uint8_t[dx*dy*dz][8] grid cell visibility (optional; readers that predate it skip it) */

/* Since 1.2 (optional; 1.0 and 1.1 readers skip it): the lightmap detail, see glow_bake_detail. */
#define GLOW_SECTION_LDET GLOW_FOURCC('L', 'D', 'E', 'T')

/* Since 1.4 (optional; written for the systems of a world, glow-bake --system-area): the system's key
 * and its dependencies, and the proxy nodes its links may read, see glow_bake_xref. A reader that
 * predates it refuses a bake whose links read proxies (GLOW_ERROR_OUT_OF_RANGE: a link node beyond
 * node_count) and loads one without. */
#define GLOW_SECTION_XREF GLOW_FOURCC('X', 'R', 'E', 'F')

/* Since 1.5 (optional, with GRID and GVIS; glow-bake --grid-refine): the grid refined near geometry,
 * see glow_bake_grid_fine. Readers that predate it skip it and look the coarse grid up alone. */
#define GLOW_SECTION_GFIN GLOW_FOURCC('G', 'F', 'I', 'N')

/* Since 1.6 (optional; glow-bake writes it unless --no-sky): the sky transfer, see glow_bake_sky.
 * Readers that predate it skip it (their hosts trace the sky themselves). */
#define GLOW_SECTION_SKYT GLOW_FOURCC('S', 'K', 'Y', 'T')

/* Since 1.7 (with GEOM, exactly when lightmap_count > 1; glow-bake --lightmap-max-size): the lightmap
 * page of each GEOM triangle, uint32_t[triangle_count], each < lightmap_count. The pages are
 * lightmap_count atlases of lightmap_width x lightmap_height, stacked: a lightmap texel's index (LMAP,
 * CACH) is page * width * height + y * width + x, and a triangle's lm_uv are in [0,1] within its page.
 * Readers that predate it refuse lightmap_count > 1 (GLOW_ERROR_CORRUPT_DATA). */
#define GLOW_SECTION_TPAG GLOW_FOURCC('T', 'P', 'A', 'G')

/* Since 1.8 (optional; written for the systems of a world): the system's tree as its neighbours' links
 * see it, see glow_bake_ptree. The linker's, not the runtime's: a re-bake of a neighbour reads it
 * instead of placing and clustering this system's surfels again. Runtime readers skip it. */
#define GLOW_SECTION_PTRE GLOW_FOURCC('P', 'T', 'R', 'E')

/* Cache-map entries (GRID and LMAP): the low 31 bits index the cache array. */
#define GLOW_MAP_EMPTY 0xFFFFFFFFu   /* no cache here; samples read zero */
#define GLOW_MAP_COPY_BIT 0x80000000u /* not a cache of its own: a dilated copy of cache (v & ~bit) */
#define GLOW_MAP_INDEX_MASK 0x7FFFFFFFu

#define GLOW_NODE_NONE 0xFFFFFFFFu /* child of a leaf, parent of the root */

/* Cache kinds (glow_bake_cache.kind) and link encodings (meta.link_kind bits; LINK is always present,
 * SHLK only with GLOW_LINK_KIND_FULL_SH, LSUB only with GLOW_LINK_KIND_SUBSETS: each link blends its
 * node's four grandchildren) are glow.h's glow_cache_kind and glow_link_kind_bits, whose values are
 * the format's (checked below). */
_Static_assert(GLOW_CACHE_KIND_GRID == 1 && GLOW_CACHE_KIND_LIGHTMAP == 2, "cache kinds are format values");
_Static_assert(GLOW_LINK_KIND_RUNTIME_PROJECTION == 1 && GLOW_LINK_KIND_FULL_SH == 2 && GLOW_LINK_KIND_SUBSETS == 4 &&
                   GLOW_LINK_KIND_GRADIENT == 8,
               "link kinds are format values");

#define GLOW_LINK_BLOCK 16u /* links per SoA block; caches own whole blocks */

/* ------------------------------------------------------------------------------------------ */
typedef struct glow_bake_header {
    /*  0 */ char magic[4];          /* "GLOW" */
    /*  4 */ uint16_t major;         /* GLOW_BAKE_FORMAT_VERSION_MAJOR */
    /*  6 */ uint16_t minor;         /* GLOW_BAKE_FORMAT_VERSION_MINOR */
    /*  8 */ uint32_t header_size;   /* sizeof(glow_bake_header) */
    /* 12 */ uint32_t section_count; /* entries in the section table */
    /* 16 */ uint64_t file_size;     /* total bytes, must equal the file's size */
    /* 24 */ uint32_t flags;         /* 0 */
    /* 28 */ uint32_t table_crc32;   /* CRC-32 of the section table */
    /* 32 */ uint32_t header_crc32;  /* CRC-32 of these 64 bytes with this field zero */
    /* 36 */ uint32_t reserved[7];
} glow_bake_header; /* 64 */

typedef struct glow_bake_section {
    /*  0 */ uint32_t fourcc;
    /*  4 */ uint32_t version; /* per-section layout version, 1 */
    /*  8 */ uint64_t offset;  /* from file start, multiple of GLOW_BAKE_ALIGN */
    /* 16 */ uint64_t size;    /* payload bytes */
    /* 24 */ uint32_t crc32;   /* CRC-32 of the payload */
    /* 28 */ uint32_t reserved;
} glow_bake_section; /* 32 */

typedef struct glow_bake_meta {
    /*   0 */ uint32_t surfel_count;      /* leaves n_S */
    /*   4 */ uint32_t node_count;        /* all nodes, leaves first: 2*n_S - 1 for a binary HAC */
    /*   8 */ uint32_t level_count;       /* pull levels, level 0 = leaves */
    /*  12 */ uint32_t cache_count;       /* grid caches first, then lightmap caches */
    /*  16 */ uint32_t grid_cache_count;
    /*  20 */ uint32_t lightmap_cache_count;
    /*  24 */ uint32_t links_per_cache;   /* n_L (unused lanes have one_minus_cos 0) */
    /*  28 */ uint32_t link_blocks_per_cache; /* ceil(n_L / GLOW_LINK_BLOCK) */
    /*  32 */ uint32_t sh_bands;          /* l the linker aimed for (full-SH links carry l*l) */
    /*  36 */ uint32_t link_kind;         /* GLOW_LINK_KIND_* bits */
    /*  40 */ uint32_t material_count;
    /*  44 */ uint32_t triangle_count;    /* triangles kept (GEOM entries) */
    /*  48 */ float bounds_min[3];        /* scene AABB, m */
    /*  60 */ float surfel_area;          /* nominal leaf area scene_area / surfel_count, m² (1.3: leaves may differ, NODE) */
    /*  64 */ float bounds_max[3];
    /*  76 */ float factor_scale;         /* 1/(pi * surfel_area): scales SHLK coefficients (LINK needs none) */
    /*  80 */ float grid_origin[3];       /* centre of grid cell (0,0,0), m */
    /*  92 */ float grid_spacing;         /* m */
    /*  96 */ uint32_t grid_dims[3];      /* cells in x, y, z (x fastest in GRID) */
    /* 108 */ uint32_t lightmap_count;    /* atlases (pages) of width x height: 0, 1, or (1.7, TPAG) up to
                                             GLOW_BAKE_MAX_LIGHTMAP_PAGES; LMAP holds them stacked */
    /* 112 */ uint32_t lightmap_width;
    /* 116 */ uint32_t lightmap_height;
    /* 120 */ float texel_density;        /* texels per m */
    /* 124 */ uint32_t seed;
    /* 128 */ double scene_area;          /* m², sum of kept triangle areas == surfel_count*surfel_area == the leaves' areas */
    /* 136 */ uint32_t source_triangles;  /* triangles read from the file */
    /* 140 */ uint32_t skipped_degenerate;/* zero-area / repeated-index triangles */
    /* 144 */ uint32_t skipped_duplicate; /* coincident duplicate faces */
    /* 148 */ uint32_t skipped_nonfinite; /* NaN/Inf vertices */
    /* 152 */ uint32_t chart_count;       /* generated lightmap charts (0 = mesh's own UV set) */
    /* 156 */ uint32_t lightmap_invalid_texels; /* texels seeing back faces, filled from neighbours */
    /* 160 */ uint32_t quality;           /* 0 custom, 1 low, 2 moderate, 3 high */
    /* 164 */ uint32_t rays_per_surfel;   /* visibility rays per (cache, surfel) pair */
    /* 168 */ uint32_t reserved[22];
} glow_bake_meta; /* 256 */

typedef struct glow_bake_material {
    /*  0 */ char name[32];      /* NUL-terminated, truncated */
    /* 32 */ float albedo[3];    /* Kd / baseColorFactor, linear RGB */
    /* 44 */ uint32_t flags;     /* bit 0: has albedo texture (baked into surfel albedo) */
    /* 48 */ float emission[3];  /* emitted radiance W/(m²·sr) (Ke / emissiveFactor) */
    /* 60 */ uint32_t reserved;
} glow_bake_material; /* 64 */

/* A leaf node's area lies within this factor of META surfel_area either way (format 1.3: the linker
 * may adapt the surfel density; before, every leaf's area was surfel_area). */
#define GLOW_BAKE_LEAF_AREA_RANGE 16.0f

typedef struct glow_bake_surfel {
    /*  0 */ float position[3];  /* m */
    /* 12 */ float normal[3];    /* unit */
    /* 24 */ float albedo[3];    /* linear RGB reflectance, texture folded in */
    /* 36 */ float emission[3];  /* emitted radiance W/(m²·sr) at this surfel */
    /* 48 */ uint32_t material;  /* index into MATL */
    /* 52 */ uint32_t feedback;  /* cache index whose light the surfel re-emits (multi-bounce) */
    /* 56 */ uint32_t triangle;  /* GEOM index it lies on */
    /* 60 */ uint32_t reserved;
} glow_bake_surfel; /* 64 */

/* Nodes: leaves [0, surfel_count) are the surfels in SURF order; internal nodes follow,
 * sorted by level (height above the leaves), so the pull is a sweep over LEVL ranges
 * 1..level_count-1, each node reading two nodes of lower levels. Root = node_count - 1. */
typedef struct glow_bake_node {
    /*  0 */ uint32_t child[2];   /* GLOW_NODE_NONE for leaves */
    /*  8 */ uint32_t parent;     /* GLOW_NODE_NONE for the root */
    /* 12 */ float area;          /* m², sum of the leaves below */
    /* 16 */ float position[3];   /* area-weighted centre, m */
    /* 28 */ uint32_t normal_oct; /* area-weighted mean normal, octahedral snorm16x2 (x low) */
} glow_bake_node; /* 32 */

typedef struct glow_bake_cache {
    /*  0 */ float position[3];   /* m */
    /* 12 */ uint32_t normal_oct; /* lightmap: surface normal; grid: 0 */
    /* 16 */ uint32_t kind;       /* GLOW_CACHE_KIND_* */
    /* 20 */ uint32_t texel;      /* grid: cell index (x fastest); lightmap: y*width + x */
    /* 24 */ uint32_t reserved[2];
} glow_bake_cache; /* 32 */

/* Runtime-projection links (PIC 4.6), SoA blocks of 16 so the solver vectorises across links.
 * Link j of cache c is block c*link_blocks_per_cache + j/16, lane j%16. 8 bytes per link:
 *   node     24 bits  hierarchy node (the sender), so node_count <= GLOW_LINK_MAX_NODES
 *   dir_u    12 bits  octahedral direction, unsigned: q in [0, 4095] <-> s = q * (2/4095) - 1
 *   dir_v    12 bits  (glow__oct_decode12; worst-case angular error ~0.04 degrees)
 *   one_minus_cos     IEEE half, 1 - cos(alpha), alpha the half-angle of the cone whose solid
 *                     angle equals the node's solid angle visible from the cache (occlusion
 *                     included): omega = 2 pi (1 - cos alpha)
 * Its contribution to the cache's radiance SH (band l, order m) is
 *     L_lm += flux[node] / (pi * node.area) * k_l(1 - one_minus_cos) * y_lm(oct_decode12(dir_u, dir_v))
 * with k_l the cone factors of DESIGN §3: flux / (pi * area) is the node's radiosity turned into
 * radiance, which the solver computes once per node per frame (after the pull) rather than per link.
 * No factor is stored: the linker's factor is always surfel_area / node.area (1 / the node's leaf
 * count), so the former flux * meta.factor_scale * factor is flux / (pi * node.area), which NODE
 * already holds. (meta.factor_scale stays: SHLK coefficients are scaled by it.)
 * Unused lanes (j >= links_per_cache) must have one_minus_cos 0 (the writer also sets node 0 and
 * dir 0 there, and in cut slots the linker left empty). Every lane's node must be < node_count, so
 * the solver may read all 16; a lane with one_minus_cos 0 contributes nothing (k_l(1) = 0). */
#define GLOW_LINK_MAX_NODES (1u << 24)     /* node indices are 24 bits */
#define GLOW_LINK_NODE_MASK 0x00FFFFFFu
#define GLOW_LINK_DIR_MAX 4095u            /* 12-bit octahedral coordinates */

typedef struct glow_bake_link_block {
    /*   0 */ uint32_t node_dir[GLOW_LINK_BLOCK];      /* bits 0-23: node index; bits 24-31: bits 4-11 of dir_u */
    /*  64 */ uint16_t one_minus_cos[GLOW_LINK_BLOCK]; /* IEEE half in [0, 2]; 0 for unused lanes (they contribute nothing) */
    /*  96 */ uint16_t dir_lo[GLOW_LINK_BLOCK];        /* bits 0-3: bits 0-3 of dir_u; bits 4-15: dir_v */
} glow_bake_link_block; /* 128 = 8 bytes per link */

/* The node a lane links to (the low 24 bits of node_dir). */
static inline uint32_t glow_bake_link_node(const glow_bake_link_block *b, uint32_t lane) {
    return b->node_dir[lane] & GLOW_LINK_NODE_MASK;
}

/* The lane's 12-bit octahedral direction (decode with glow__oct_decode12). */
static inline void glow_bake_link_dir12(const glow_bake_link_block *b, uint32_t lane, uint32_t *out_u,
                                        uint32_t *out_v) {
    *out_u = ((b->node_dir[lane] >> 24) << 4) | (b->dir_lo[lane] & 0xFu);
    *out_v = (uint32_t)b->dir_lo[lane] >> 4;
}

/* Writer side: packs one lane. node < GLOW_LINK_MAX_NODES and u, v <= GLOW_LINK_DIR_MAX (higher bits
 * are dropped); one_minus_cos is already an IEEE half. */
static inline void glow_bake_link_pack(glow_bake_link_block *b, uint32_t lane, uint32_t node, uint16_t one_minus_cos,
                                       uint32_t u, uint32_t v) {
    b->node_dir[lane] = (node & GLOW_LINK_NODE_MASK) | (((u >> 4) & 0xFFu) << 24);
    b->one_minus_cos[lane] = one_minus_cos;
    b->dir_lo[lane] = (uint16_t)((u & 0xFu) | ((v & 0xFFFu) << 4));
}

/* Link subsets (LSUB, link_kind bit GLOW_LINK_KIND_SUBSETS): one uint16_t per link, in LINK's order
 * (block c*link_blocks_per_cache + j/16, lane j%16). A link's node v has four slots below it
 * (glow_bake_link_slots: its grandchildren, or a child twice where that child is a leaf, or v four
 * times where v is a leaf), and nibble i (bits 4i..4i+3) is slot i's weight q_i in [0, 15]: the
 * share of the link's visible response that slot i gives, scaled so the largest is 15. The link then
 * reads the radiance
 *     R = sum_i q_i R[slot_i] / sum_i q_i          (R[node] = flux / (pi area), as for LINK)
 * instead of R[v]: the mean of the part of the node the cache sees, where R[v] is the mean of all of
 * it (the energy of partly visible nodes; docs/linker.md). A link whose four weights are 0 reads
 * R[v]. Direction and cone are LINK's. */
/* Link gradients (LSUB with link_kind bit GLOW_LINK_KIND_GRADIENT, never with GLOW_LINK_KIND_SUBSETS;
 * glow-bake --link-subsets gradient; an older runtime refuses the bake): the same uint16_t per link,
 * holding instead a gradient code. Code 0: the link reads R[v]. Otherwise bit 15 is 1 and bits 0-4,
 * 5-9, 10-14 hold k_x + 15, k_y + 15, k_z + 15 with k in [-15, 15]: e = k / 15 approximates
 * (p_w - c) / sigma, clamped to [-1, 1] per component, where c is the area centroid of v's leaves,
 * C their area-weighted position covariance, sigma = sqrt(trace C) and p_w the centroid of the
 * leaves weighted by the cache's response (diffuse response for lightmap caches, solid angle for
 * grid caches, 0 where hidden). The link reads
 *     R = R[v] * max(0, 1 + e . u),   u = sigma C'^-1 (p_B - c),   C' = C + 1e-3 trace(C) I
 * with p_B the luma-flux-weighted centroid of v's leaves (u = 0 where v has no flux): exact where the
 * response per unit area is linear in position over v (docs/linker.md "Link gradients"). Links with
 * a code follow those without in each cache, as with subsets. The runtime derives c, C and sigma from
 * the surfels' positions and areas (SURF, NODE); nothing else is stored. */
static inline void glow_bake_link_slots(uint32_t v, const uint32_t child[2], const uint32_t child0_child[2],
                                        const uint32_t child1_child[2], uint32_t slot[4]) {
    if (child[0] == 0xFFFFFFFFu) {
        slot[0] = slot[1] = slot[2] = slot[3] = v;
        return;
    }
    for (int k = 0; k < 2; ++k) {
        const uint32_t *cc = k ? child1_child : child0_child;
        if (cc[0] == 0xFFFFFFFFu) slot[2 * k] = slot[2 * k + 1] = child[k];
        else {
            slot[2 * k] = cc[0];
            slot[2 * k + 1] = cc[1];
        }
    }
}

/* Full-SH links (PIC Eq. 2, Monte-Carlo projection), SHLK: the same cut as LINK, per block of
 * 16 links: uint32_t node[16] followed by IEEE-half coeff[sh_bands*sh_bands][16] (coefficient-major),
 * each the SH projection of the visible sender divided by (pi * node.area) and by factor_scale,
 * i.e. times surfel_area / node.area: the runtime multiplies them by meta.factor_scale. SHLK node
 * indices are full uint32_t (no packed direction); lanes match LINK's glow_bake_link_node.
 * Block size = 64 + 32 * sh_bands². */
static inline size_t glow_bake_shlk_block_size(uint32_t sh_bands) {
    return (size_t)64u + (size_t)32u * sh_bands * sh_bands;
}

/* Geometry the host needs to sample the lightmap (Glow may have generated the lightmap UVs). */
typedef struct glow_bake_triangle {
    /*  0 */ float position[9];   /* three corners, m */
    /* 36 */ uint16_t lm_uv[6];   /* lightmap UV per corner, unorm16 of [0,1] */
    /* 48 */ uint32_t material;
    /* 52 */ uint32_t source;     /* index of the triangle in the imported file's order */
    /* 56 */ uint32_t normal_oct; /* geometric normal */
    /* 60 */ uint32_t reserved;
} glow_bake_triangle; /* 64 */

/* Lightmap detail (LDET, optional): a grid `factor` times finer than the lightmap over the same atlas
 * (width = factor x lightmap_width, height likewise). Each detail texel that covers a surface
 * corrects the near light the bilinear lightmap lookup at its centre misses (docs/linker.md
 * "Lightmap detail"):
 *     correction = sum_k weight[k] * R[surfel[k]]      k in [first[i], first[i + 1])
 * with R a leaf's radiance (flux / (pi area), as for LINK), in the units of glow_shade_sh's result
 * (cosine-lobe mean radiance about the texel's normal); weights are signed. Payload:
 *     glow_bake_detail; uint32_t texel[texel_count] (page * width * height + y * width + x, ascending;
 *     width x height a page, lightmap_count pages);
 *     uint32_t first[texel_count + 1] (first[0] = 0, non-decreasing, first[texel_count] = link_count);
 *     uint32_t surfel[link_count] (< surfel_count); float weight[link_count] (finite). */
typedef struct glow_bake_detail {
    /*  0 */ uint32_t factor;      /* 2..8 */
    /*  4 */ uint32_t width, height;
    /* 12 */ uint32_t texel_count; /* detail texels that cover a surface (the rest read nothing) */
    /* 16 */ uint32_t link_count;
    /* 20 */ uint32_t reserved[3];
} glow_bake_detail; /* 32 */
#define GLOW_BAKE_DETAIL_MAX_FACTOR 8u
#define GLOW_BAKE_MAX_LIGHTMAP_PAGES 256u /* lightmap_count (glow-bake writes at most 64) */

/* XREF (since 1.4): light across systems. A world (glow-bake --system-area) is split into systems, each
 * an ordinary bake; a system's links may also read nodes of its dependencies (neighbouring systems
 * within reach). Such a link names a proxy node: index node_count + p for proxy p, whose radiance the
 * runtime copies from node `node` of dependency `dependency` (glow_system_set_neighbour) before it
 * gathers. Payload:
 *     glow_bake_xref; uint64_t dependency_key[dependency_count] (each dependency's system_key);
 *     glow_bake_xref_proxy proxy[proxy_count] (dependency < dependency_count). */
typedef struct glow_bake_xref {
    /*  0 */ uint64_t system_key;       /* this system's key, the world manifest's "key" */
    /*  8 */ uint32_t dependency_count; /* at most GLOW_BAKE_MAX_DEPENDENCIES */
    /* 12 */ uint32_t proxy_count;      /* node_count + proxy_count <= GLOW_LINK_MAX_NODES */
    /* 16 */ uint32_t reserved[4];
} glow_bake_xref; /* 32 */
/* GFIN: a coarse cell (the one whose lowest corner is grid point (x, y, z), x < dx - 1, y < dy - 1,
 * z < dz - 1) may be a brick of R³ fine cells of spacing grid_spacing / R, whose (R + 1)³ corners
 * are points of the fine lattice origin + (grid_spacing / R) · (gx, gy, gz). Payload:
 *     glow_bake_grid_fine;
 *     uint32_t brick_of_cell[dx·dy·dz]  (brick index, or GLOW_MAP_EMPTY);
 *     uint32_t brick[brick_count][(R+1)³] (cache index of each corner, x fastest, a grid cache without
 *              the copy bit, or GLOW_MAP_EMPTY: inside geometry);
 *     uint8_t  visibility[brick_count][R³][8] (per fine cell, x fastest, and octant: GVIS's masks). */
typedef struct glow_bake_grid_fine {
    /*  0 */ uint32_t refine;      /* R, 2..8 */
    /*  4 */ uint32_t brick_count; /* >= 1 */
    /*  8 */ uint32_t reserved[6];
} glow_bake_grid_fine; /* 32 */

/* SKYT (since 1.6): per leaf surfel the sky transfer vector
 *     T_k = ∫ V(ω) max(0, n·ω) y_k(ω) dω          (k < 9: real SH l <= 2, glow_sh_eval's basis)
 * and per grid cache (the first grid_cache_count caches, fine ones included) the sky visibility SH
 *     V_k = ∫ V(ω) y_k(ω) dω
 * with V(ω) = 1 where a ray from the surfel (or the cache) escapes the scene. For a sky of radiance SH
 * L (RGB, l <= 2) a surfel's sky irradiance is max(0, Σ_k T_k L_k) and a grid cache's visible sky the
 * product projection V ⊗ L (docs/sky.md). Payload:
 *     glow_bake_sky; float surfel[surfel_count][9] (SURF order); float grid[grid_count][9] (CACH order).
 * Every value finite and |x| <= GLOW_BAKE_SKY_MAX (|T_k| <= π max|y_k| < 3.5, |V_k| < 14). */
typedef struct glow_bake_sky {
    /*  0 */ uint32_t coeffs;       /* 9 (l <= 2) */
    /*  4 */ uint32_t surfel_count; /* meta.surfel_count */
    /*  8 */ uint32_t grid_count;   /* meta.grid_cache_count */
    /* 12 */ uint32_t rays;         /* rays per surfel the linker traced (informative, >= 1) */
    /* 16 */ uint32_t grid_rays;    /* rays per grid cache (informative, >= 1 when grid_count > 0) */
    /* 20 */ uint32_t reserved[3];
} glow_bake_sky; /* 32 */
#define GLOW_BAKE_SKY_COEFFS 9u
#define GLOW_BAKE_SKY_MAX 16.0f
_Static_assert(sizeof(glow_bake_sky) == 32, "sky header is 32 bytes");

/* PTRE: the system's hierarchy as a neighbour's links see it: each node of at most 16 leaves whose
 * parent has more becomes a leaf (a disc of the node's area, centre and mean normal; a node that is a
 * surfel keeps the surfel's fields), the nodes below it go. Leaves first, in the order of the full
 * tree's leaves, then the kept internal nodes in the full tree's order (children before parents).
 * Payload: glow_bake_ptree; glow_bake_ptree_node node[node_count]; glow_bake_ptree_leaf
 * leaf[leaf_count]. The floats are the linker's own, bit for bit (not quantised like NODE). */
typedef struct glow_bake_ptree {
    /*  0 */ uint64_t tree_key;   /* XREF system_key: what the surfels and tree follow from */
    /*  8 */ uint32_t node_count; /* >= 1 */
    /* 12 */ uint32_t leaf_count; /* >= 1; nodes [0, leaf_count) are leaves */
    /* 16 */ uint32_t root;       /* < node_count: node_count - 1, or 0 when it is the one leaf */
    /* 20 */ uint32_t reserved[3];
} glow_bake_ptree; /* 32 */
typedef struct glow_bake_ptree_node {
    /*  0 */ uint32_t child[2]; /* GLOW_NODE_NONE for leaves; else < this node's index */
    /*  8 */ uint32_t parent;   /* GLOW_NODE_NONE for the root; else > this node's index */
    /* 12 */ uint32_t level;    /* 0 for leaves, 1 + the children's highest */
    /* 16 */ uint32_t source;   /* the node of NODE it stands for */
    /* 20 */ float pos[3];
    /* 32 */ float nrm[3];
    /* 44 */ float area;
} glow_bake_ptree_node; /* 48 */
typedef struct glow_bake_ptree_leaf {
    /*  0 */ float pos[3];
    /* 12 */ float nrm[3];
    /* 24 */ float albedo[3];   /* 0 for a node's disc */
    /* 36 */ float emission[3]; /* 0 for a node's disc */
    /* 48 */ uint32_t triangle; /* GEOM triangle of a surfel; 0 for a node's disc */
    /* 52 */ float bary[2];
    /* 60 */ uint32_t material;
    /* 64 */ float area;
} glow_bake_ptree_leaf; /* 68 */
_Static_assert(sizeof(glow_bake_ptree) == 32, "ptree header is 32 bytes");
_Static_assert(sizeof(glow_bake_ptree_node) == 48, "ptree node is 48 bytes");
_Static_assert(sizeof(glow_bake_ptree_leaf) == 68, "ptree leaf is 68 bytes");

typedef struct glow_bake_xref_proxy {
    uint32_t dependency;
    uint32_t node; /* a node of the dependency's bake (checked when it is attached) */
} glow_bake_xref_proxy;
#define GLOW_BAKE_MAX_DEPENDENCIES 64u
_Static_assert(sizeof(glow_bake_xref) == 32, "xref header is 32 bytes");
_Static_assert(sizeof(glow_bake_grid_fine) == 32, "grid fine header is 32 bytes");
_Static_assert(sizeof(glow_bake_xref_proxy) == 8, "xref proxy is 8 bytes");

_Static_assert(sizeof(glow_bake_detail) == 32, "detail header is 32 bytes");
_Static_assert(sizeof(glow_bake_header) == 64, "header is 64 bytes");
_Static_assert(offsetof(glow_bake_header, file_size) == 16, "header layout");
_Static_assert(offsetof(glow_bake_header, header_crc32) == 32, "header layout");
_Static_assert(sizeof(glow_bake_section) == 32, "section entry is 32 bytes");
_Static_assert(offsetof(glow_bake_section, offset) == 8, "section layout");
_Static_assert(offsetof(glow_bake_section, crc32) == 24, "section layout");
_Static_assert(sizeof(glow_bake_meta) == 256, "meta is 256 bytes");
_Static_assert(offsetof(glow_bake_meta, bounds_min) == 48, "meta layout");
_Static_assert(offsetof(glow_bake_meta, grid_origin) == 80, "meta layout");
_Static_assert(offsetof(glow_bake_meta, scene_area) == 128, "meta layout");
_Static_assert(offsetof(glow_bake_meta, reserved) == 168, "meta layout");
_Static_assert(sizeof(glow_bake_material) == 64, "material is 64 bytes");
_Static_assert(offsetof(glow_bake_material, emission) == 48, "material layout");
_Static_assert(sizeof(glow_bake_surfel) == 64, "surfel is 64 bytes");
_Static_assert(offsetof(glow_bake_surfel, material) == 48, "surfel layout");
_Static_assert(sizeof(glow_bake_node) == 32, "node is 32 bytes");
_Static_assert(offsetof(glow_bake_node, position) == 16, "node layout");
_Static_assert(sizeof(glow_bake_cache) == 32, "cache is 32 bytes");
_Static_assert(offsetof(glow_bake_cache, kind) == 16, "cache layout");
_Static_assert(sizeof(glow_bake_link_block) == 128, "link block is 8 bytes per link");
_Static_assert(offsetof(glow_bake_link_block, one_minus_cos) == 64, "link block layout");
_Static_assert(offsetof(glow_bake_link_block, dir_lo) == 96, "link block layout");
_Static_assert(sizeof(glow_bake_triangle) == 64, "triangle is 64 bytes");
_Static_assert(offsetof(glow_bake_triangle, material) == 48, "triangle layout");

/* CRC-32 (zlib polynomial). The runtime may only depend on libc (DESIGN §2), so it carries this
 * small table-driven version instead of linking zlib; tests/format checks it against zlib. */
uint32_t glow__crc32(uint32_t crc, const void *data, size_t size);

/* Octahedral unit-vector encoding, snorm16 x2 packed (x in the low 16 bits). Shared by writer
 * and reader. */
uint32_t glow__oct_encode(const float n[3]);
void glow__oct_decode(uint32_t packed, float out_n[3]);
void glow__oct_encode2(const float n[3], int16_t *out_u, int16_t *out_v);
void glow__oct_decode2(int16_t u, int16_t v, float out_n[3]);
/* The links' 12-bit unsigned variant: q in [0, 4095] <-> s = q * (2/4095) - 1. The encoder keeps
 * the nearest of the 4 quantised candidates (worst case ~0.04 degrees); zero-length or non-finite
 * input encodes as (approximately) +z. */
void glow__oct_encode12(const float n[3], uint32_t *out_u, uint32_t *out_v);
void glow__oct_decode12(uint32_t u, uint32_t v, float out_n[3]);

/* IEEE half conversions (round to nearest even; no F16C dependency). */
uint16_t glow__half_from_float(float f);
float glow__half_to_float(uint16_t h);

#endif /* GLOW_BAKE_FORMAT_H */
