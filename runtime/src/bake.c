/* bake.c — glow_bake: loads a bake (bake/bake_format.h) into one aligned allocation and
 * validates every byte the runtime will ever read before anything uses it.
 *
 * Order of checks (the first failure is reported, logged with its code and returned):
 *   1. size < 64                                   TRUNCATED
 *   2. magic != "GLOW"                             BAD_MAGIC
 *   3. major != 1                                  VERSION_MISMATCH (before the CRC: a future major
 *                                                  may lay out its header differently)
 *   4. header CRC                                  BAD_CHECKSUM
 *   5. header.file_size vs the bytes present       TRUNCATED when fewer, CORRUPT_DATA when more
 *   6. header_size, section_count, table bounds    CORRUPT_DATA
 *   7. table CRC                                   BAD_CHECKSUM
 *   8. every entry: alignment, inside the file, after the table, no overlap, no duplicate
 *      fourcc                                      CORRUPT_DATA
 *   9. every payload CRC (unknown sections too)    BAD_CHECKSUM
 *  10. known sections: version 1, required ones present, META counts consistent, every size
 *      equal to what META implies (64-bit maths, overflow-checked)           CORRUPT_DATA
 *  11. contents: non-finite / out-of-domain floats CORRUPT_DATA; indices and tree structure
 *      OUT_OF_RANGE (see validate_* below for the full list). Every float the solver reads is
 *      checked against its domain, not only for finiteness (issue 15, D2: checksums are not
 *      authentication, and a resealed bake with a non-unit normal or an 8.8e-43 node area loaded
 *      and then drove the solver to 5e14 and NaN): unit surfel normals (|n|² within 2 %), albedos in
 *      [0, 1], emission in [0, GLOW_MAX_IRRADIANCE], leaf areas within 16x of surfel_area summing to
 *      scene_area (0.1 %; 1.3: they may differ), every
 *      internal area the sum of its children's (0.1 %), factor_scale = 1 / (pi surfel_area) (0.1 %).
 * Unknown fourccs are CRC-checked and otherwise skipped.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdatomic.h>
#include <string.h>

#include "runtime_internal.h"

#define BAKE_HEADER_SIZE ((uint64_t)sizeof(glow_bake_header))
#define BAKE_ENTRY_SIZE ((uint64_t)sizeof(glow_bake_section))
#define MAX_SH_BANDS 16u

enum { S_META, S_MATL, S_SURF, S_NODE, S_LEVL, S_CACH, S_GRID, S_LMAP, S_LINK, S_SHLK, S_GEOM, S_GVIS, S_LSUB, S_TUV0, S_TEXP,
       S_LDET, S_XREF, S_GFIN, S_SKYT, S_TPAG, S_KNOWN_COUNT };

static const uint32_t known_fourcc[S_KNOWN_COUNT] = {
    GLOW_SECTION_META, GLOW_SECTION_MATL, GLOW_SECTION_SURF, GLOW_SECTION_NODE, GLOW_SECTION_LEVL, GLOW_SECTION_CACH,
    GLOW_SECTION_GRID, GLOW_SECTION_LMAP, GLOW_SECTION_LINK, GLOW_SECTION_SHLK, GLOW_SECTION_GEOM, GLOW_SECTION_GVIS,
    GLOW_SECTION_LSUB, GLOW_SECTION_TUV0, GLOW_SECTION_TEXP, GLOW_SECTION_LDET, GLOW_SECTION_XREF, GLOW_SECTION_GFIN,
    GLOW_SECTION_SKYT, GLOW_SECTION_TPAG,
};

typedef struct section_ref {
    int present;
    uint64_t offset, size;
} section_ref;

struct glow_bake {
    glow_context *ctx;
    const unsigned char *data; /* the file image, GLOW_BAKE_ALIGN-aligned, inside this allocation */
    uint64_t size;
    uint32_t section_count;
    const glow_bake_section *table;
    section_ref known[S_KNOWN_COUNT];
    glow_bake_meta meta; /* copy (also readable in place through glow__bake_meta) */
    uint16_t major, minor;
    atomic_uint systems; /* live glow_systems using this bake */
};

static const void *known_ptr(const glow_bake *b, int k); /* a known section's payload, or NULL */

/* Offset of the file image inside the allocation. */
#define BAKE_DATA_OFFSET (((sizeof(struct glow_bake) + GLOW_BAKE_ALIGN - 1u) / GLOW_BAKE_ALIGN) * GLOW_BAKE_ALIGN)

/* --------------------------------------------------------------------------- reporting */
typedef struct vstate {
    glow_context *ctx;
    const char *name; /* file path, or "bake (memory)" */
    const unsigned char *data;
    uint64_t size;
} vstate;

static glow_result failf(const vstate *v, glow_result code, int line, const char *fmt, ...) GLOW__PRINTF(4, 5);
static glow_result failf(const vstate *v, glow_result code, int line, const char *fmt, ...) {
    char msg[896];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    glow__ctx_log(v->ctx, GLOW_LOG_ERROR, code, __FILE__, line, "%s: %s", v->name, msg);
    return code;
}
#define FAIL(code, ...) return failf(v, (code), __LINE__, __VA_ARGS__)

typedef struct fourcc_str {
    char s[5];
} fourcc_str;
static fourcc_str fourcc_name(uint32_t f) {
    fourcc_str r;
    for (int i = 0; i < 4; i++) {
        unsigned char c = (unsigned char)(f >> (8 * i));
        r.s[i] = (c >= 0x20 && c < 0x7F) ? (char)c : '?';
    }
    r.s[4] = 0;
    return r;
}

/* --------------------------------------------------------------------------- bounds-checked reads */
/* true when [offset, offset + len) lies inside the v's bytes (no overflow possible). */
static int in_bounds(const vstate *v, uint64_t offset, uint64_t len) {
    return offset <= v->size && len <= v->size - offset;
}
/* Copies len bytes at offset into dst; 0 when out of bounds (nothing copied). */
static int read_at(const vstate *v, uint64_t offset, void *dst, uint64_t len) {
    if (!in_bounds(v, offset, len)) return 0;
    memcpy(dst, v->data + offset, (size_t)len);
    return 1;
}
static int mul_u64(uint64_t a, uint64_t b, uint64_t *out) {
    if (a != 0 && b > UINT64_MAX / a) return 0;
    *out = a * b;
    return 1;
}
static int host_is_little_endian(void) {
    const uint32_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

static int finite3(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }
/* each component in [lo, hi] (false for NaN) */
static int in_range3(const float *p, float lo, float hi) {
    return p[0] >= lo && p[0] <= hi && p[1] >= lo && p[1] <= hi && p[2] >= lo && p[2] <= hi;
}
/* a within 0.1 % of b (b > 0); false for NaN */
static int near_rel(double a, double b) { return fabs(a - b) <= 1e-3 * b; }

/* --------------------------------------------------------------------------- header + table */
static glow_result check_header(const vstate *v, glow_bake_header *out_hdr) {
    if (v->size < BAKE_HEADER_SIZE)
        FAIL(GLOW_ERROR_TRUNCATED, "%llu bytes, shorter than the %u-byte bake header", (unsigned long long)v->size,
             (unsigned)BAKE_HEADER_SIZE);
    glow_bake_header h;
    read_at(v, 0, &h, sizeof h);
    if (memcmp(h.magic, GLOW_BAKE_MAGIC, 4) != 0)
        FAIL(GLOW_ERROR_BAD_MAGIC, "not a Glow bake (magic %02x %02x %02x %02x, expected \"GLOW\")",
             (unsigned char)h.magic[0], (unsigned char)h.magic[1], (unsigned char)h.magic[2],
             (unsigned char)h.magic[3]);
    if (h.major != GLOW_BAKE_FORMAT_VERSION_MAJOR)
        FAIL(GLOW_ERROR_VERSION_MISMATCH,
             "bake format version %u.%u; this runtime reads format version %u.x (re-bake with a matching glow-bake)",
             (unsigned)h.major, (unsigned)h.minor, (unsigned)GLOW_BAKE_FORMAT_VERSION_MAJOR);
    glow_bake_header z = h;
    z.header_crc32 = 0;
    uint32_t crc = glow__crc32(0, &z, sizeof z);
    if (crc != h.header_crc32)
        FAIL(GLOW_ERROR_BAD_CHECKSUM, "header CRC-32 mismatch (stored 0x%08x, computed 0x%08x)", h.header_crc32, crc);
    if (h.file_size > v->size)
        FAIL(GLOW_ERROR_TRUNCATED, "truncated: header says %llu bytes, only %llu present",
             (unsigned long long)h.file_size, (unsigned long long)v->size);
    if (h.file_size < v->size)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "header says %llu bytes but the data is %llu bytes",
             (unsigned long long)h.file_size, (unsigned long long)v->size);
    if (h.header_size != sizeof(glow_bake_header))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "header_size %u, expected %u", h.header_size, (unsigned)BAKE_HEADER_SIZE);
    if (h.section_count > GLOW_BAKE_MAX_SECTIONS)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section_count %u exceeds the maximum %u", h.section_count,
             GLOW_BAKE_MAX_SECTIONS);
    uint64_t table_size = (uint64_t)h.section_count * BAKE_ENTRY_SIZE;
    if (!in_bounds(v, BAKE_HEADER_SIZE, table_size))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section table (%u entries) extends past the end of the file", h.section_count);
    crc = glow__crc32(0, v->data + BAKE_HEADER_SIZE, (size_t)table_size);
    if (crc != h.table_crc32)
        FAIL(GLOW_ERROR_BAD_CHECKSUM, "section table CRC-32 mismatch (stored 0x%08x, computed 0x%08x)", h.table_crc32,
             crc);
    *out_hdr = h;
    return GLOW_OK;
}

static glow_result check_table(const vstate *v, const glow_bake_header *h, glow_bake_section *entries) {
    uint32_t n = h->section_count;
    uint64_t table_end = BAKE_HEADER_SIZE + (uint64_t)n * BAKE_ENTRY_SIZE;
    for (uint32_t i = 0; i < n; i++) read_at(v, BAKE_HEADER_SIZE + i * BAKE_ENTRY_SIZE, &entries[i], BAKE_ENTRY_SIZE);
    for (uint32_t i = 0; i < n; i++) {
        const glow_bake_section *e = &entries[i];
        fourcc_str fn = fourcc_name(e->fourcc);
        if (e->offset % GLOW_BAKE_ALIGN != 0)
            FAIL(GLOW_ERROR_CORRUPT_DATA, "section '%s' offset %llu is not a multiple of %u", fn.s,
                 (unsigned long long)e->offset, GLOW_BAKE_ALIGN);
        if (e->offset < table_end)
            FAIL(GLOW_ERROR_CORRUPT_DATA, "section '%s' offset %llu overlaps the header or section table", fn.s,
                 (unsigned long long)e->offset);
        if (!in_bounds(v, e->offset, e->size))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "section '%s' [%llu, +%llu) extends past the end of the file (%llu bytes)",
                 fn.s, (unsigned long long)e->offset, (unsigned long long)e->size, (unsigned long long)v->size);
        for (uint32_t j = 0; j < i; j++) {
            const glow_bake_section *o = &entries[j];
            if (o->fourcc == e->fourcc) FAIL(GLOW_ERROR_CORRUPT_DATA, "duplicate section '%s'", fn.s);
            if (e->size && o->size && e->offset < o->offset + o->size && o->offset < e->offset + e->size)
                FAIL(GLOW_ERROR_CORRUPT_DATA, "sections '%s' and '%s' overlap", fourcc_name(o->fourcc).s, fn.s);
        }
    }
    for (uint32_t i = 0; i < n; i++) {
        const glow_bake_section *e = &entries[i];
        uint32_t crc = glow__crc32(0, v->data + e->offset, (size_t)e->size);
        if (crc != e->crc32)
            FAIL(GLOW_ERROR_BAD_CHECKSUM, "section '%s' CRC-32 mismatch (stored 0x%08x, computed 0x%08x)",
                 fourcc_name(e->fourcc).s, e->crc32, crc);
    }
    return GLOW_OK;
}

/* --------------------------------------------------------------------------- META and sizes */
static glow_result check_section_size(const vstate *v, const section_ref *s, uint32_t fourcc, uint64_t count,
                                      uint64_t elem_size, const char *what) {
    uint64_t expect;
    if (!mul_u64(count, elem_size, &expect) || s->size != expect)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section '%s' is %llu bytes; %s needs %llu x %llu bytes", fourcc_name(fourcc).s,
             (unsigned long long)s->size, what, (unsigned long long)count, (unsigned long long)elem_size);
    return GLOW_OK;
}

typedef struct derived {
    uint64_t grid_cells, lm_texels, link_blocks, shlk_block_size;
} derived;

static glow_result check_meta(const vstate *v, const glow_bake_meta *m, section_ref *sec, derived *d) {
    glow_result r;
    /* counts */
    if (m->surfel_count == 0) FAIL(GLOW_ERROR_CORRUPT_DATA, "META: surfel_count is 0");
    if ((uint64_t)m->node_count != 2u * (uint64_t)m->surfel_count - 1u)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: node_count %u, expected 2 * surfel_count - 1 = %llu", m->node_count,
             (unsigned long long)(2u * (uint64_t)m->surfel_count - 1u));
    if (m->node_count > GLOW_LINK_MAX_NODES)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: node_count %u exceeds %u (LINK node indices are 24 bits)", m->node_count,
             GLOW_LINK_MAX_NODES);
    if (m->level_count == 0 || m->level_count > m->node_count)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: level_count %u not in [1, node_count = %u]", m->level_count,
             m->node_count);
    if ((uint64_t)m->grid_cache_count + m->lightmap_cache_count != m->cache_count)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: grid_cache_count %u + lightmap_cache_count %u != cache_count %u",
             m->grid_cache_count, m->lightmap_cache_count, m->cache_count);
    if ((uint64_t)m->link_blocks_per_cache != ((uint64_t)m->links_per_cache + GLOW_LINK_BLOCK - 1u) / GLOW_LINK_BLOCK)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: link_blocks_per_cache %u, expected ceil(links_per_cache %u / %u)",
             m->link_blocks_per_cache, m->links_per_cache, GLOW_LINK_BLOCK);
    if (m->sh_bands == 0 || m->sh_bands > MAX_SH_BANDS)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: sh_bands %u not in [1, %u]", m->sh_bands, MAX_SH_BANDS);
    if (m->lightmap_count > GLOW_BAKE_MAX_LIGHTMAP_PAGES) /* 1.7: pages (TPAG) */
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: lightmap_count %u exceeds %u pages", m->lightmap_count,
             GLOW_BAKE_MAX_LIGHTMAP_PAGES);
    /* floats */
    if (!finite3(m->bounds_min) || !finite3(m->bounds_max))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: non-finite scene bounds");
    /* > 0: links weigh a node's flux by 1 / (pi * node area), so a zero area would make radiance infinite */
    if (!isfinite(m->surfel_area) || !(m->surfel_area > 0.0f) || !isfinite(m->scene_area) || !(m->scene_area > 0.0))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: surfel_area %g / scene_area %g not finite and > 0", (double)m->surfel_area,
             m->scene_area);
    if (!isfinite(m->factor_scale)) FAIL(GLOW_ERROR_CORRUPT_DATA, "META: non-finite factor_scale");
    if (!near_rel(m->factor_scale, 1.0 / (3.14159265358979323846 * m->surfel_area)))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: factor_scale %g is not 1 / (pi x surfel_area %g)", (double)m->factor_scale,
             (double)m->surfel_area);
    if (!finite3(m->grid_origin) || !isfinite(m->grid_spacing) || !isfinite(m->texel_density))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: non-finite grid origin / spacing or texel density");

    /* derived sizes (64-bit, overflow-checked) */
    uint64_t xy;
    if (!mul_u64(m->grid_dims[0], m->grid_dims[1], &xy) || !mul_u64(xy, m->grid_dims[2], &d->grid_cells))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: grid_dims %u x %u x %u overflow", m->grid_dims[0], m->grid_dims[1],
             m->grid_dims[2]);
    if (d->grid_cells > 0 && !(m->grid_spacing > 0.0f))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: grid_spacing %g must be > 0 for a grid of %llu cells",
             (double)m->grid_spacing, (unsigned long long)d->grid_cells);
    /* lightmap_count pages of width x height, stacked (1.7) */
    if (!mul_u64((uint64_t)m->lightmap_width * m->lightmap_height, m->lightmap_count, &d->lm_texels))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "META: lightmap %u x %u x %u pages overflows", m->lightmap_width,
             m->lightmap_height, m->lightmap_count);
    d->link_blocks = (uint64_t)m->cache_count * m->link_blocks_per_cache;
    d->shlk_block_size = glow_bake_shlk_block_size(m->sh_bands);

    /* presence */
    static const int required[] = {S_META, S_SURF, S_NODE, S_LEVL, S_CACH, S_LINK, S_MATL};
    for (size_t i = 0; i < sizeof required / sizeof required[0]; i++)
        if (!sec[required[i]].present)
            FAIL(GLOW_ERROR_CORRUPT_DATA, "missing required section '%s'", fourcc_name(known_fourcc[required[i]]).s);
    if (d->grid_cells > 0 && !sec[S_GRID].present)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "missing section 'GRID' (grid of %llu cells)", (unsigned long long)d->grid_cells);
    if (m->lightmap_count > 0 && !sec[S_LMAP].present)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "missing section 'LMAP' (lightmap_count %u)", m->lightmap_count);
    int full_sh = (m->link_kind & GLOW_LINK_KIND_FULL_SH) != 0;
    if (full_sh && !sec[S_SHLK].present)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "missing section 'SHLK' (link_kind 0x%x has full-SH links)", m->link_kind);
    if (!full_sh && sec[S_SHLK].present)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'SHLK' present but link_kind 0x%x has no full-SH links", m->link_kind);
    if ((m->link_kind & GLOW_LINK_KIND_SUBSETS) && (m->link_kind & GLOW_LINK_KIND_GRADIENT))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "link_kind 0x%x has both link subsets and link gradients", m->link_kind);
    const int subsets = (m->link_kind & (GLOW_LINK_KIND_SUBSETS | GLOW_LINK_KIND_GRADIENT)) != 0;
    if (subsets != sec[S_LSUB].present)
        FAIL(GLOW_ERROR_CORRUPT_DATA, subsets ? "missing section 'LSUB' (link_kind 0x%x has link subsets)"
                                              : "section 'LSUB' present but link_kind 0x%x has no link subsets",
             m->link_kind);

    /* sizes */
    if ((r = check_section_size(v, &sec[S_MATL], GLOW_SECTION_MATL, m->material_count, sizeof(glow_bake_material),
                                "material_count")))
        return r;
    if ((r = check_section_size(v, &sec[S_SURF], GLOW_SECTION_SURF, m->surfel_count, sizeof(glow_bake_surfel),
                                "surfel_count")))
        return r;
    if ((r = check_section_size(v, &sec[S_NODE], GLOW_SECTION_NODE, m->node_count, sizeof(glow_bake_node),
                                "node_count")))
        return r;
    if ((r = check_section_size(v, &sec[S_LEVL], GLOW_SECTION_LEVL, (uint64_t)m->level_count + 1u, sizeof(uint32_t),
                                "level_count + 1")))
        return r;
    if ((r = check_section_size(v, &sec[S_CACH], GLOW_SECTION_CACH, m->cache_count, sizeof(glow_bake_cache),
                                "cache_count")))
        return r;
    if (sec[S_GRID].present &&
        (r = check_section_size(v, &sec[S_GRID], GLOW_SECTION_GRID, d->grid_cells, sizeof(uint32_t), "grid cells")))
        return r;
    if (sec[S_LMAP].present && (r = check_section_size(v, &sec[S_LMAP], GLOW_SECTION_LMAP, d->lm_texels,
                                                       sizeof(uint32_t), "lightmap texels")))
        return r;
    if ((r = check_section_size(v, &sec[S_LINK], GLOW_SECTION_LINK, d->link_blocks, sizeof(glow_bake_link_block),
                                "cache_count * link_blocks_per_cache")))
        return r;
    if (sec[S_SHLK].present && (r = check_section_size(v, &sec[S_SHLK], GLOW_SECTION_SHLK, d->link_blocks,
                                                       d->shlk_block_size, "full-SH link blocks")))
        return r;
    if (sec[S_GEOM].present && (r = check_section_size(v, &sec[S_GEOM], GLOW_SECTION_GEOM, m->triangle_count,
                                                       sizeof(glow_bake_triangle), "triangle_count")))
        return r;
    /* LSUB (optional): one uint16_t of four 4-bit weights per link; any value is valid */
    if (sec[S_LSUB].present && (r = check_section_size(v, &sec[S_LSUB], GLOW_SECTION_LSUB, d->link_blocks,
                                                       GLOW_LINK_BLOCK * sizeof(uint16_t), "link blocks x 16 lanes")))
        return r;
    /* TUV0 (optional, 1.1): 6 floats per GEOM triangle; TEXP (optional, 1.1): one path per material */
    if (sec[S_TUV0].present && !sec[S_GEOM].present)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'TUV0' (material UVs) without 'GEOM' (the triangles they belong to)");
    if (sec[S_TUV0].present && (r = check_section_size(v, &sec[S_TUV0], GLOW_SECTION_TUV0, m->triangle_count,
                                                       6u * sizeof(float), "triangle_count x 6 floats")))
        return r;
    if (sec[S_TEXP].present && (r = check_section_size(v, &sec[S_TEXP], GLOW_SECTION_TEXP, m->material_count,
                                                       GLOW_BAKE_TEXTURE_PATH, "material_count x path")))
        return r;
    /* TPAG (1.7): a page per GEOM triangle, exactly when the lightmap has several pages and GEOM is present */
    if (sec[S_TPAG].present && (!sec[S_GEOM].present || m->lightmap_count < 2))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'TPAG' (lightmap pages) needs 'GEOM' and lightmap_count > 1 (it is %u)",
             m->lightmap_count);
    if (!sec[S_TPAG].present && sec[S_GEOM].present && m->lightmap_count > 1)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "missing section 'TPAG' (lightmap_count %u pages with GEOM)", m->lightmap_count);
    if (sec[S_TPAG].present && (r = check_section_size(v, &sec[S_TPAG], GLOW_SECTION_TPAG, m->triangle_count,
                                                       sizeof(uint32_t), "triangle_count pages")))
        return r;
    /* GVIS (optional): 8 octant masks per grid cell; any byte value is valid */
    if (sec[S_GVIS].present &&
        (r = check_section_size(v, &sec[S_GVIS], GLOW_SECTION_GVIS, d->grid_cells, 8u, "grid cells x 8 octants")))
        return r;
    return GLOW_OK;
}

/* --------------------------------------------------------------------------- contents */
static const void *payload(const vstate *v, const section_ref *s) { return v->data + s->offset; }

static glow_result check_materials(const vstate *v, const glow_bake_meta *m, const glow_bake_material *mat) {
    for (uint32_t i = 0; i < m->material_count; i++) {
        if (mat[i].name[sizeof mat[i].name - 1] != 0)
            FAIL(GLOW_ERROR_CORRUPT_DATA, "material %u: name is not NUL-terminated", i);
        if (!finite3(mat[i].albedo) || !finite3(mat[i].emission))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "material %u: non-finite albedo or emission", i);
        if (!in_range3(mat[i].albedo, 0.0f, 1.0f) || !in_range3(mat[i].emission, 0.0f, GLOW_MAX_IRRADIANCE))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "material %u: albedo outside [0, 1] or emission outside [0, %g]", i,
                 (double)GLOW_MAX_IRRADIANCE);
    }
    return GLOW_OK;
}

static glow_result check_surfels(const vstate *v, const glow_bake_meta *m, const glow_bake_surfel *s, int has_geom) {
    for (uint32_t i = 0; i < m->surfel_count; i++) {
        if (!finite3(s[i].position) || !finite3(s[i].normal) || !finite3(s[i].albedo) || !finite3(s[i].emission))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "surfel %u: non-finite position, normal, albedo or emission", i);
        const float *n = s[i].normal;
        const float n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (!(n2 >= 0.98f && n2 <= 1.02f))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "surfel %u: normal (%g, %g, %g) is not unit length", i, (double)n[0],
                 (double)n[1], (double)n[2]);
        if (!in_range3(s[i].albedo, 0.0f, 1.0f) || !in_range3(s[i].emission, 0.0f, GLOW_MAX_IRRADIANCE))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "surfel %u: albedo outside [0, 1] or emission outside [0, %g]", i,
                 (double)GLOW_MAX_IRRADIANCE);
        if (s[i].material >= m->material_count)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "surfel %u: material %u out of range (material_count %u)", i, s[i].material,
                 m->material_count);
        if (s[i].feedback >= m->cache_count)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "surfel %u: feedback cache %u out of range (cache_count %u)", i,
                 s[i].feedback, m->cache_count);
        if (has_geom && s[i].triangle >= m->triangle_count)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "surfel %u: triangle %u out of range (triangle_count %u)", i, s[i].triangle,
                 m->triangle_count);
    }
    return GLOW_OK;
}

static glow_result check_tree(const vstate *v, const glow_bake_meta *m, const glow_bake_node *nd,
                              const uint32_t *ls) {
    const uint32_t nn = m->node_count, ns = m->surfel_count, nl = m->level_count;
    /* level starts: 0 = ls[0], ls[1] = surfel_count, non-decreasing, ls[level_count] = node_count */
    if (ls[0] != 0 || ls[1] != ns || ls[nl] != nn)
        FAIL(GLOW_ERROR_OUT_OF_RANGE,
             "LEVL: level starts must run from 0 (got %u) to node_count %u (got %u) with level 1 at surfel_count %u "
             "(got %u)",
             ls[0], nn, ls[nl], ns, ls[1]);
    for (uint32_t k = 0; k < nl; k++)
        if (ls[k + 1] < ls[k]) FAIL(GLOW_ERROR_OUT_OF_RANGE, "LEVL: level start %u (%u) < level start %u (%u)", k + 1, ls[k + 1], k, ls[k]);
    for (uint32_t i = 0; i < nn; i++) {
        const glow_bake_node *n = &nd[i];
        for (int c = 0; c < 2; c++)
            if (n->child[c] != GLOW_NODE_NONE && n->child[c] >= nn)
                FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u: child %u out of range (node_count %u)", i, n->child[c], nn);
        if (n->parent != GLOW_NODE_NONE && n->parent >= nn)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u: parent %u out of range (node_count %u)", i, n->parent, nn);
        if (!isfinite(n->area) || !(n->area > 0.0f) || !finite3(n->position))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "node %u: area must be finite and > 0, position finite", i);
    }
    /* leaves: no children */
    for (uint32_t i = 0; i < ns; i++)
        if (nd[i].child[0] != GLOW_NODE_NONE || nd[i].child[1] != GLOW_NODE_NONE)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u is a leaf (< surfel_count %u) but has children %u, %u", i, ns,
                 nd[i].child[0], nd[i].child[1]);
    /* internal nodes of level k: two distinct children from lower levels whose parent is this node */
    for (uint32_t k = 1; k < nl; k++) {
        for (uint32_t i = ls[k]; i < ls[k + 1]; i++) {
            const glow_bake_node *n = &nd[i];
            if (n->child[0] == GLOW_NODE_NONE || n->child[1] == GLOW_NODE_NONE || n->child[0] == n->child[1])
                FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u (level %u): needs two distinct children, has %u, %u", i, k,
                     n->child[0], n->child[1]);
            for (int c = 0; c < 2; c++) {
                if (n->child[c] >= ls[k])
                    FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u (level %u): child %u is not in a lower level (< %u)", i, k,
                         n->child[c], ls[k]);
                if (nd[n->child[c]].parent != i)
                    FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u: child %u names parent %u", i, n->child[c],
                         nd[n->child[c]].parent);
            }
        }
    }
    /* areas: a leaf's is its surfel's share of the surface, surfel_area (the nominal scene_area /
     * surfel_count) unless the linker adapted the density (format 1.3), and then within
     * [surfel_area / GLOW_BAKE_LEAF_AREA_RANGE, surfel_area x GLOW_BAKE_LEAF_AREA_RANGE], all of them
     * summing to scene_area (0.1 %); an internal node's the sum of its children's (the links turn a
     * node's flux into radiosity with 1 / its area) */
    {
        double leaf_sum = 0.0;
        for (uint32_t i = 0; i < ns; i++) {
            const float a = nd[i].area;
            if (!(a >= m->surfel_area / GLOW_BAKE_LEAF_AREA_RANGE && a <= m->surfel_area * GLOW_BAKE_LEAF_AREA_RANGE))
                FAIL(GLOW_ERROR_CORRUPT_DATA, "node %u: area %g of a leaf is not within %gx of surfel_area %g", i,
                     (double)a, (double)GLOW_BAKE_LEAF_AREA_RANGE, (double)m->surfel_area);
            leaf_sum += a;
        }
        if (!near_rel(leaf_sum, m->scene_area))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "NODE: the leaves' areas sum to %g, not scene_area %g", leaf_sum,
                 m->scene_area);
    }
    for (uint32_t i = ns; i < nn; i++) {
        const double sum = (double)nd[nd[i].child[0]].area + nd[nd[i].child[1]].area;
        if (!near_rel(nd[i].area, sum))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "node %u: area %g is not the sum of its children's (%g)", i,
                 (double)nd[i].area, sum);
    }
    /* parents: only the root (node_count - 1) has none; every parent lists its child */
    for (uint32_t i = 0; i < nn; i++) {
        uint32_t p = nd[i].parent;
        if (i == nn - 1) {
            if (p != GLOW_NODE_NONE) FAIL(GLOW_ERROR_OUT_OF_RANGE, "root node %u has parent %u", i, p);
        } else if (p == GLOW_NODE_NONE) {
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u has no parent but is not the root (%u)", i, nn - 1);
        } else if (nd[p].child[0] != i && nd[p].child[1] != i) {
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "node %u names parent %u, which does not list it as a child", i, p);
        }
    }
    return GLOW_OK;
}

static glow_result check_caches(const vstate *v, const glow_bake_meta *m, const derived *d,
                                const glow_bake_cache *c) {
    for (uint32_t i = 0; i < m->cache_count; i++) {
        uint32_t want = i < m->grid_cache_count ? GLOW_CACHE_KIND_GRID : GLOW_CACHE_KIND_LIGHTMAP;
        if (c[i].kind != GLOW_CACHE_KIND_GRID && c[i].kind != GLOW_CACHE_KIND_LIGHTMAP)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "cache %u: unknown kind %u", i, c[i].kind);
        if (c[i].kind != want)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "cache %u: kind %u, but caches [0, %u) are grid caches and the rest lightmap",
                 i, c[i].kind, m->grid_cache_count);
        uint64_t limit = want == GLOW_CACHE_KIND_GRID ? d->grid_cells : d->lm_texels;
        if (c[i].texel >= limit)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "cache %u: texel/cell %u out of range (%llu)", i, c[i].texel,
                 (unsigned long long)limit);
        if (!finite3(c[i].position)) FAIL(GLOW_ERROR_CORRUPT_DATA, "cache %u: non-finite position", i);
    }
    return GLOW_OK;
}

/* Map entries: GLOW_MAP_EMPTY, or (index | optional copy bit) with index in [lo, hi). */
static glow_result check_map(const vstate *v, const char *what, const uint32_t *map, uint64_t count, uint32_t lo,
                             uint32_t hi) {
    for (uint64_t i = 0; i < count; i++) {
        uint32_t e = map[i];
        if (e == GLOW_MAP_EMPTY) continue;
        uint32_t idx = e & GLOW_MAP_INDEX_MASK;
        if (idx < lo || idx >= hi)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "%s entry %llu: cache %u out of range [%u, %u)", what, (unsigned long long)i,
                 idx, lo, hi);
    }
    return GLOW_OK;
}

/* Every lane is read by the solver, so every lane's node must exist; the direction bits need no
 * check (all 12-bit values decode to unit vectors). */
static glow_result check_links(const vstate *v, const glow_bake_meta *m, const derived *d,
                               const glow_bake_link_block *b, uint32_t proxies, const uint16_t *subsets) {
    const uint32_t bpc = m->link_blocks_per_cache;
    const uint64_t nodes = (uint64_t)m->node_count + proxies; /* proxy p is node node_count + p (XREF) */
    for (uint64_t i = 0; i < d->link_blocks; i++) {
        const glow_bake_link_block *blk = &b[i];
        uint64_t first = (i % bpc) * GLOW_LINK_BLOCK; /* link index of lane 0 within its cache */
        for (uint32_t j = 0; j < GLOW_LINK_BLOCK; j++) {
            uint32_t node = glow_bake_link_node(blk, j);
            if (node >= nodes)
                FAIL(GLOW_ERROR_OUT_OF_RANGE, "LINK cache %llu link %llu: node %u out of range (node_count %u%s)",
                     (unsigned long long)(i / bpc), (unsigned long long)(first + j), node, m->node_count,
                     proxies ? " and the XREF proxies" : "");
            if (node >= m->node_count && subsets && subsets[i * GLOW_LINK_BLOCK + j])
                FAIL(GLOW_ERROR_CORRUPT_DATA, "LINK cache %llu link %llu: a link to proxy node %u has LSUB weights",
                     (unsigned long long)(i / bpc), (unsigned long long)(first + j), node);
            uint16_t omc = blk->one_minus_cos[j];
            if (!(omc <= 0x4000u || omc == 0x8000u)) /* [+0, 2.0] or -0: excludes negatives, Inf, NaN */
                FAIL(GLOW_ERROR_CORRUPT_DATA, "LINK cache %llu link %llu: one_minus_cos %g must be finite and in [0, 2]",
                     (unsigned long long)(i / bpc), (unsigned long long)(first + j), (double)glow__half_to_float(omc));
            if (first + j >= m->links_per_cache && (omc & 0x7FFFu) != 0)
                FAIL(GLOW_ERROR_CORRUPT_DATA, "LINK cache %llu: unused lane %llu has one_minus_cos %g (must be 0)",
                     (unsigned long long)(i / bpc), (unsigned long long)(first + j), (double)glow__half_to_float(omc));
        }
    }
    return GLOW_OK;
}

static glow_result check_shlk(const vstate *v, const glow_bake_meta *m, const derived *d, const unsigned char *p) {
    const uint64_t coeffs = (uint64_t)m->sh_bands * m->sh_bands * GLOW_LINK_BLOCK;
    for (uint64_t i = 0; i < d->link_blocks; i++) {
        const unsigned char *blk = p + i * d->shlk_block_size;
        const uint32_t *node = (const uint32_t *)blk;
        const uint16_t *coeff = (const uint16_t *)(blk + 64);
        for (uint32_t j = 0; j < GLOW_LINK_BLOCK; j++)
            if (node[j] >= m->node_count)
                FAIL(GLOW_ERROR_OUT_OF_RANGE, "SHLK block %llu lane %u: node %u out of range (node_count %u)",
                     (unsigned long long)i, j, node[j], m->node_count);
        for (uint64_t k = 0; k < coeffs; k++)
            if ((coeff[k] & 0x7C00u) == 0x7C00u)
                FAIL(GLOW_ERROR_CORRUPT_DATA, "SHLK block %llu: non-finite coefficient %llu", (unsigned long long)i,
                     (unsigned long long)k);
    }
    return GLOW_OK;
}

static glow_result check_geom(const vstate *v, const glow_bake_meta *m, const glow_bake_triangle *t) {
    for (uint32_t i = 0; i < m->triangle_count; i++) {
        if (!finite3(t[i].position) || !finite3(t[i].position + 3) || !finite3(t[i].position + 6))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "GEOM triangle %u: non-finite position", i);
        if (t[i].material >= m->material_count)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "GEOM triangle %u: material %u out of range (material_count %u)", i,
                 t[i].material, m->material_count);
    }
    return GLOW_OK;
}

/* TPAG: every triangle's page below lightmap_count. */
static glow_result check_pages(const vstate *v, const glow_bake_meta *m, const uint32_t *page) {
    for (uint32_t i = 0; i < m->triangle_count; i++)
        if (page[i] >= m->lightmap_count)
            FAIL(GLOW_ERROR_CORRUPT_DATA, "TPAG triangle %u: lightmap page %u not below lightmap_count %u", i, page[i],
                 m->lightmap_count);
    return GLOW_OK;
}

/* TUV0: finite UVs (a host samples textures with them); TEXP: every path NUL-terminated in its slot. */
static glow_result check_textures(const vstate *v, const glow_bake_meta *m, const float *uv, const char *paths) {
    for (uint64_t i = 0; uv && i < 6ull * m->triangle_count; i++)
        if (!isfinite(uv[i])) FAIL(GLOW_ERROR_CORRUPT_DATA, "TUV0 triangle %u: non-finite material UV", (uint32_t)(i / 6));
    for (uint32_t k = 0; paths && k < m->material_count; k++)
        if (!memchr(paths + (size_t)k * GLOW_BAKE_TEXTURE_PATH, 0, GLOW_BAKE_TEXTURE_PATH))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "TEXP material %u: the texture path is not NUL-terminated", k);
    return GLOW_OK;
}

/* GFIN (optional, 1.5; bake_format.h glow_bake_grid_fine): with GRID and GVIS; R and the size; bricks
 * only in cells with a +1 neighbour on every axis, each brick named once; brick corners EMPTY or a grid
 * cache without the copy bit. The masks take any value. */
static glow_result check_grid_fine(const vstate *v, const glow_bake_meta *m, const derived *d, const section_ref *s,
                                   int have_gvis) {
    glow_bake_grid_fine gh;
    if (s->size < sizeof gh) FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'GFIN' is %llu bytes, shorter than its header",
                                  (unsigned long long)s->size);
    read_at(v, s->offset, &gh, sizeof gh);
    if (!d->grid_cells || !have_gvis) FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'GFIN' (refined grid) without a grid and its GVIS");
    if (gh.refine < 2 || gh.refine > 8 || gh.brick_count == 0 || gh.brick_count > d->grid_cells)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "GFIN: refine %u (2..8) or %u bricks (1..%llu) out of range", gh.refine,
             gh.brick_count, (unsigned long long)d->grid_cells);
    for (int a = 0; a < 3; a++)
        if (m->grid_dims[a] < 2) FAIL(GLOW_ERROR_CORRUPT_DATA, "GFIN: a refined grid needs 2 points an axis, not %u", m->grid_dims[a]);
    const uint64_t R = gh.refine, per = (R + 1) * (R + 1) * (R + 1), nb = gh.brick_count;
    const uint64_t expect = sizeof gh + 4u * d->grid_cells + 4u * nb * per + 8u * nb * R * R * R;
    if (s->size != expect)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'GFIN' is %llu bytes; %llu cells and %u bricks of %u need %llu",
             (unsigned long long)s->size, (unsigned long long)d->grid_cells, gh.brick_count, gh.refine,
             (unsigned long long)expect);
    const uint32_t *of = (const uint32_t *)(const void *)(v->data + s->offset + sizeof gh), *br = of + d->grid_cells;
    uint64_t named = 0;
    for (uint64_t c = 0; c < d->grid_cells; c++) {
        if (of[c] == GLOW_MAP_EMPTY) continue;
        const uint64_t x = c % m->grid_dims[0], y = (c / m->grid_dims[0]) % m->grid_dims[1],
                       z = c / ((uint64_t)m->grid_dims[0] * m->grid_dims[1]);
        if (of[c] >= nb || x + 1 >= m->grid_dims[0] || y + 1 >= m->grid_dims[1] || z + 1 >= m->grid_dims[2])
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "GFIN cell %llu: brick %u out of range or the cell on the grid's last layer",
                 (unsigned long long)c, of[c]);
        named++;
    }
    if (named != nb) FAIL(GLOW_ERROR_CORRUPT_DATA, "GFIN: %llu cells name bricks, not brick_count %u", (unsigned long long)named, gh.brick_count);
    for (uint64_t i = 0; i < nb * per; i++)
        if (br[i] != GLOW_MAP_EMPTY && br[i] >= m->grid_cache_count)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "GFIN brick %llu corner %llu: cache %u is not a grid cache (%u)",
                 (unsigned long long)(i / per), (unsigned long long)(i % per), br[i], m->grid_cache_count);
    return GLOW_OK;
}

/* SKYT (optional, 1.6; bake_format.h glow_bake_sky): 9 coefficients, the bake's surfel and grid cache
 * counts, rays >= 1, the size from them, every value finite and within GLOW_BAKE_SKY_MAX. */
static glow_result check_sky(const vstate *v, const glow_bake_meta *m, const section_ref *s) {
    glow_bake_sky kh;
    if (s->size < sizeof kh) FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'SKYT' is %llu bytes, shorter than its header",
                                  (unsigned long long)s->size);
    read_at(v, s->offset, &kh, sizeof kh);
    if (kh.coeffs != GLOW_BAKE_SKY_COEFFS || kh.surfel_count != m->surfel_count || kh.grid_count != m->grid_cache_count ||
        kh.rays == 0 || (kh.grid_count && kh.grid_rays == 0))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "SKYT: %u coefficients (9), %u surfels (%u), %u grid caches (%u) or %u / %u rays "
             "(>= 1) do not fit the bake", kh.coeffs, kh.surfel_count, m->surfel_count, kh.grid_count, m->grid_cache_count,
             kh.rays, kh.grid_rays);
    const uint64_t n = ((uint64_t)kh.surfel_count + kh.grid_count) * GLOW_BAKE_SKY_COEFFS;
    if (s->size != sizeof kh + 4u * n)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'SKYT' is %llu bytes; %u surfels and %u grid caches need %llu",
             (unsigned long long)s->size, kh.surfel_count, kh.grid_count, (unsigned long long)(sizeof kh + 4u * n));
    const float *x = (const float *)(const void *)(v->data + s->offset + sizeof kh);
    for (uint64_t i = 0; i < n; i++)
        if (!(fabsf(x[i]) <= GLOW_BAKE_SKY_MAX)) { /* also NaN */
            const uint64_t e = i / GLOW_BAKE_SKY_COEFFS;
            const int surf = e < kh.surfel_count;
            FAIL(GLOW_ERROR_CORRUPT_DATA, "SKYT %s %llu coefficient %u: %g is not finite or beyond %g",
                 surf ? "surfel" : "grid cache", (unsigned long long)(surf ? e : e - kh.surfel_count),
                 (unsigned)(i % GLOW_BAKE_SKY_COEFFS), (double)x[i], (double)GLOW_BAKE_SKY_MAX);
        }
    return GLOW_OK;
}

/* LDET (optional, 1.2; bake_format.h glow_bake_detail): sizes, ascending texels inside the detail grid,
 * link ranges, surfels in range, finite weights. */
static glow_result check_detail(const vstate *v, const glow_bake_meta *m, const section_ref *s) {
    glow_bake_detail dh;
    if (s->size < sizeof dh) FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'LDET' is %llu bytes, shorter than its header",
                                  (unsigned long long)s->size);
    read_at(v, s->offset, &dh, sizeof dh);
    if (!m->lightmap_count) FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'LDET' (lightmap detail) in a bake without a lightmap");
    if (dh.factor < 2 || dh.factor > GLOW_BAKE_DETAIL_MAX_FACTOR || dh.width != (uint64_t)dh.factor * m->lightmap_width ||
        dh.height != (uint64_t)dh.factor * m->lightmap_height)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "LDET: detail %ux%u at factor %u does not fit the %ux%u lightmap (factor 2..%u)",
             dh.width, dh.height, dh.factor, m->lightmap_width, m->lightmap_height, GLOW_BAKE_DETAIL_MAX_FACTOR);
    const uint64_t T = dh.texel_count, Lk = dh.link_count;
    const uint64_t grid = (uint64_t)dh.width * dh.height * m->lightmap_count; /* every page's (1.7) */
    if (T > grid)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "LDET: %u detail texels in a %ux%u grid", dh.texel_count, dh.width, dh.height);
    const uint64_t expect = sizeof dh + 4u * T + 4u * (T + 1u) + 8u * Lk;
    if (s->size != expect)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'LDET' is %llu bytes; %u texels and %u links need %llu",
             (unsigned long long)s->size, dh.texel_count, dh.link_count, (unsigned long long)expect);
    const uint32_t *texel = (const uint32_t *)(const void *)(v->data + s->offset + sizeof dh);
    const uint32_t *first = texel + T, *surfel = first + T + 1u;
    const float *weight = (const float *)(const void *)(surfel + Lk);
    for (uint64_t i = 0; i < T; i++) {
        if (texel[i] >= grid || (i && texel[i] <= texel[i - 1]))
            FAIL(GLOW_ERROR_CORRUPT_DATA, "LDET texel %llu: %u is outside the grid or not ascending", (unsigned long long)i,
                 texel[i]);
        if (first[i] > first[i + 1])
            FAIL(GLOW_ERROR_CORRUPT_DATA, "LDET texel %llu: link range [%u, %u) is decreasing", (unsigned long long)i,
                 first[i], first[i + 1]);
    }
    if (first[0] != 0 || first[T] != Lk)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "LDET: link ranges run from %u to %u, not 0 to link_count %u", first[0], first[T],
             dh.link_count);
    for (uint64_t k = 0; k < Lk; k++) {
        if (surfel[k] >= m->surfel_count)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "LDET link %llu: surfel %u out of range (surfel_count %u)", (unsigned long long)k,
                 surfel[k], m->surfel_count);
        if (!isfinite(weight[k]) || fabsf(weight[k]) > 16.0f)
            FAIL(GLOW_ERROR_CORRUPT_DATA, "LDET link %llu: weight %g is not finite or beyond +-16", (unsigned long long)k,
                 (double)weight[k]);
    }
    return GLOW_OK;
}

/* XREF (optional, 1.4; bake_format.h glow_bake_xref): sizes, dependency indices, the node budget. The
 * dependencies' node indices are checked when a neighbour is attached (glow_system_set_neighbour). */
static glow_result check_xref(const vstate *v, const glow_bake_meta *m, const section_ref *s, uint32_t *out_proxies) {
    glow_bake_xref xh;
    if (s->size < sizeof xh) FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'XREF' is %llu bytes, shorter than its header",
                                  (unsigned long long)s->size);
    read_at(v, s->offset, &xh, sizeof xh);
    if (xh.dependency_count > GLOW_BAKE_MAX_DEPENDENCIES)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "XREF: %u dependencies (at most %u)", xh.dependency_count, GLOW_BAKE_MAX_DEPENDENCIES);
    if ((uint64_t)m->node_count + xh.proxy_count > GLOW_LINK_MAX_NODES)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "XREF: %u nodes and %u proxies exceed %u (LINK node indices are 24 bits)",
             m->node_count, xh.proxy_count, GLOW_LINK_MAX_NODES);
    if (xh.proxy_count && !xh.dependency_count)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "XREF: %u proxies but no dependency", xh.proxy_count);
    const uint64_t want = sizeof xh + 8u * (uint64_t)xh.dependency_count + sizeof(glow_bake_xref_proxy) * (uint64_t)xh.proxy_count;
    if (s->size != want)
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'XREF' is %llu bytes; %u dependencies and %u proxies need %llu",
             (unsigned long long)s->size, xh.dependency_count, xh.proxy_count, (unsigned long long)want);
    const glow_bake_xref_proxy *px =
        (const glow_bake_xref_proxy *)(const void *)(v->data + s->offset + sizeof xh + 8u * (uint64_t)xh.dependency_count);
    for (uint32_t p = 0; p < xh.proxy_count; ++p)
        if (px[p].dependency >= xh.dependency_count)
            FAIL(GLOW_ERROR_OUT_OF_RANGE, "XREF proxy %u: dependency %u out of range (dependency_count %u)", p,
                 px[p].dependency, xh.dependency_count);
    *out_proxies = xh.proxy_count;
    return GLOW_OK;
}

/* Validates v's bytes (which must be GLOW_BAKE_ALIGN-aligned) and fills the bake's views. */
static glow_result validate(const vstate *v, struct glow_bake *b) {
    glow_result r;
    glow_bake_header h;
    if ((r = check_header(v, &h))) return r;
    glow_bake_section entries[GLOW_BAKE_MAX_SECTIONS];
    if ((r = check_table(v, &h, entries))) return r;

    section_ref sec[S_KNOWN_COUNT];
    memset(sec, 0, sizeof sec);
    for (uint32_t i = 0; i < h.section_count; i++) {
        for (int k = 0; k < S_KNOWN_COUNT; k++) {
            if (entries[i].fourcc != known_fourcc[k]) continue;
            if (entries[i].version != 1)
                FAIL(GLOW_ERROR_CORRUPT_DATA, "section '%s' has layout version %u; format %u.x defines version 1",
                     fourcc_name(entries[i].fourcc).s, entries[i].version, (unsigned)GLOW_BAKE_FORMAT_VERSION_MAJOR);
            sec[k].present = 1;
            sec[k].offset = entries[i].offset;
            sec[k].size = entries[i].size;
        }
    }
    if (!sec[S_META].present) FAIL(GLOW_ERROR_CORRUPT_DATA, "missing required section 'META'");
    if (sec[S_META].size != sizeof(glow_bake_meta))
        FAIL(GLOW_ERROR_CORRUPT_DATA, "section 'META' is %llu bytes, expected %u", (unsigned long long)sec[S_META].size,
             (unsigned)sizeof(glow_bake_meta));
    glow_bake_meta m;
    read_at(v, sec[S_META].offset, &m, sizeof m);
    derived d = {0, 0, 0, 0};
    if ((r = check_meta(v, &m, sec, &d))) return r;

    /* From here every section is inside the buffer, aligned and exactly as large as META says. */
    if ((r = check_materials(v, &m, payload(v, &sec[S_MATL])))) return r;
    if ((r = check_surfels(v, &m, payload(v, &sec[S_SURF]), sec[S_GEOM].present))) return r;
    if ((r = check_tree(v, &m, payload(v, &sec[S_NODE]), payload(v, &sec[S_LEVL])))) return r;
    if ((r = check_caches(v, &m, &d, payload(v, &sec[S_CACH])))) return r;
    if (sec[S_GRID].present &&
        (r = check_map(v, "GRID", payload(v, &sec[S_GRID]), d.grid_cells, 0u, m.grid_cache_count)))
        return r;
    if (sec[S_LMAP].present && (r = check_map(v, "LMAP", payload(v, &sec[S_LMAP]), d.lm_texels, m.grid_cache_count,
                                              m.cache_count)))
        return r;
    uint32_t proxies = 0;
    if (sec[S_XREF].present && (r = check_xref(v, &m, &sec[S_XREF], &proxies))) return r;
    if ((r = check_links(v, &m, &d, payload(v, &sec[S_LINK]), proxies,
                         sec[S_LSUB].present ? (const uint16_t *)payload(v, &sec[S_LSUB]) : NULL)))
        return r;
    if (sec[S_SHLK].present && (r = check_shlk(v, &m, &d, payload(v, &sec[S_SHLK])))) return r;
    if (sec[S_GEOM].present && (r = check_geom(v, &m, payload(v, &sec[S_GEOM])))) return r;
    if (sec[S_TPAG].present && (r = check_pages(v, &m, payload(v, &sec[S_TPAG])))) return r;
    if ((sec[S_TUV0].present || sec[S_TEXP].present) &&
        (r = check_textures(v, &m, sec[S_TUV0].present ? (const float *)payload(v, &sec[S_TUV0]) : NULL,
                            sec[S_TEXP].present ? (const char *)payload(v, &sec[S_TEXP]) : NULL)))
        return r;
    if (sec[S_LDET].present && (r = check_detail(v, &m, &sec[S_LDET]))) return r;
    if (sec[S_GFIN].present && (r = check_grid_fine(v, &m, &d, &sec[S_GFIN], sec[S_GVIS].present))) return r;
    if (sec[S_SKYT].present && (r = check_sky(v, &m, &sec[S_SKYT]))) return r;

    b->data = v->data;
    b->size = v->size;
    b->section_count = h.section_count;
    b->table = (const glow_bake_section *)(v->data + BAKE_HEADER_SIZE);
    memcpy(b->known, sec, sizeof sec);
    b->meta = m;
    b->major = h.major;
    b->minor = h.minor;
    return GLOW_OK;
}

/* --------------------------------------------------------------------------- public API */
glow_result glow_bake_peek_version(const void *data, size_t size, uint32_t *out_major, uint32_t *out_minor) {
    if (out_major) *out_major = 0;
    if (out_minor) *out_minor = 0;
    if (!data && size) return GLOW_ERROR_INVALID_ARGUMENT;
    if (size < sizeof(glow_bake_header)) return GLOW_ERROR_TRUNCATED;
    glow_bake_header h;
    memcpy(&h, data, sizeof h);
    if (memcmp(h.magic, GLOW_BAKE_MAGIC, 4) != 0) return GLOW_ERROR_BAD_MAGIC;
    if (out_major) *out_major = h.major;
    if (out_minor) *out_minor = h.minor;
    return GLOW_OK;
}

/* Allocates the bake block with room for `size` file bytes after the struct. */
static struct glow_bake *bake_alloc(glow_context *ctx, const char *name, uint64_t size) {
    if (size > (uint64_t)SIZE_MAX - BAKE_DATA_OFFSET) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_OUT_OF_MEMORY, "%s: %llu bytes do not fit in memory", name,
                        (unsigned long long)size);
        return NULL;
    }
    struct glow_bake *b = glow__ctx_alloc(ctx, BAKE_DATA_OFFSET + (size_t)size, GLOW_BAKE_ALIGN);
    if (!b) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory allocating %llu bytes", name,
                        (unsigned long long)(BAKE_DATA_OFFSET + size));
        return NULL;
    }
    memset(b, 0, sizeof *b);
    atomic_init(&b->systems, 0u);
    b->ctx = ctx;
    return b;
}

static unsigned char *bake_bytes(struct glow_bake *b) { return (unsigned char *)b + BAKE_DATA_OFFSET; }

/* Validates the bytes already copied into b; frees b on failure. */
static glow_result bake_finish(struct glow_bake *b, const char *name, uint64_t size, glow_bake **out_bake) {
    vstate v = {b->ctx, name, bake_bytes(b), size};
    glow_result r = validate(&v, b);
    if (r != GLOW_OK) {
        glow__ctx_free(b->ctx, b);
        return r;
    }
    *out_bake = b;
    return GLOW_OK;
}

static glow_result check_load_args(glow_context *context, const char *fn, const void *p, glow_bake **out_bake) {
    if (out_bake) *out_bake = NULL;
    if (!context || !out_bake || !p) {
        GLOW__LOG_ERROR(context, GLOW_ERROR_INVALID_ARGUMENT, "%s: context, data/path and out_bake must not be NULL",
                        fn);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!host_is_little_endian()) {
        GLOW__LOG_ERROR(context, GLOW_ERROR_UNSUPPORTED, "%s: bakes are little-endian; this host is not", fn);
        return GLOW_ERROR_UNSUPPORTED;
    }
    return GLOW_OK;
}

glow_result glow_bake_load(glow_context *context, const void *data, size_t size, glow_bake **out_bake) {
    static const char name[] = "bake (memory)";
    glow_result r = check_load_args(context, "glow_bake_load", size ? data : (const void *)name, out_bake);
    if (r != GLOW_OK) return r;
    if (size < sizeof(glow_bake_header)) { /* nothing worth copying */
        vstate v = {context, name, (const unsigned char *)data, size};
        glow_bake_header h;
        return check_header(&v, &h);
    }
    struct glow_bake *b = bake_alloc(context, name, size);
    if (!b) return GLOW_ERROR_OUT_OF_MEMORY;
    memcpy(bake_bytes(b), data, size); /* validate the copy: the caller's buffer may change under us */
    return bake_finish(b, name, size, out_bake);
}

glow_result glow_bake_load_file(glow_context *context, const char *path, glow_bake **out_bake) {
    glow_result r = check_load_args(context, "glow_bake_load_file", path, out_bake);
    if (r != GLOW_OK) return r;
    FILE *f = fopen(path, "rb");
    if (!f) {
        int e = errno;
        GLOW__LOG_ERROR(context, GLOW_ERROR_IO, "%s: cannot open: %s", path, e ? strerror(e) : "unknown error");
        return GLOW_ERROR_IO;
    }
    int c = fgetc(f); /* catches directories and unreadable files before seeking */
    if (c == EOF && ferror(f)) {
        int e = errno;
        fclose(f);
        GLOW__LOG_ERROR(context, GLOW_ERROR_IO, "%s: read failed: %s", path, e ? strerror(e) : "unknown error");
        return GLOW_ERROR_IO;
    }
    long end = -1;
    if (fseek(f, 0, SEEK_END) == 0) end = ftell(f);
    if (end < 0 || fseek(f, 0, SEEK_SET) != 0) {
        int e = errno;
        fclose(f);
        GLOW__LOG_ERROR(context, GLOW_ERROR_IO, "%s: cannot determine the file size: %s", path,
                        e ? strerror(e) : "not seekable");
        return GLOW_ERROR_IO;
    }
    uint64_t size = (uint64_t)end;
    if (size < sizeof(glow_bake_header)) {
        unsigned char small[sizeof(glow_bake_header)];
        size_t got = fread(small, 1, (size_t)size, f);
        fclose(f);
        vstate v = {context, path, small, got};
        glow_bake_header h;
        return check_header(&v, &h);
    }
    struct glow_bake *b = bake_alloc(context, path, size);
    if (!b) {
        fclose(f);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    size_t got = fread(bake_bytes(b), 1, (size_t)size, f);
    int read_error = ferror(f);
    int e = errno;
    fclose(f);
    if (read_error) {
        glow__ctx_free(context, b);
        GLOW__LOG_ERROR(context, GLOW_ERROR_IO, "%s: read failed: %s", path, e ? strerror(e) : "unknown error");
        return GLOW_ERROR_IO;
    }
    /* A file that shrank since ftell: validate what arrived (reports TRUNCATED). */
    return bake_finish(b, path, got, out_bake);
}

glow_result glow_bake_get_info(const glow_bake *bake, glow_bake_info *out_info) {
    if (!bake || !out_info) return GLOW_ERROR_INVALID_ARGUMENT;
    const glow_bake_meta *m = &bake->meta;
    glow_bake_info i;
    memset(&i, 0, sizeof i);
    i.format_major = bake->major;
    i.format_minor = bake->minor;
    i.surfel_count = m->surfel_count;
    i.node_count = m->node_count;
    i.level_count = m->level_count;
    i.cache_count = m->cache_count;
    i.grid_cache_count = m->grid_cache_count;
    i.lightmap_cache_count = m->lightmap_cache_count;
    i.links_per_cache = m->links_per_cache;
    i.sh_bands = m->sh_bands;
    i.link_kind = m->link_kind;
    i.material_count = m->material_count;
    i.triangle_count = m->triangle_count; /* as META says, also when GEOM is absent */
    for (int k = 0; k < 3; k++) {
        i.grid_dims[k] = m->grid_dims[k];
        i.bounds_min[k] = m->bounds_min[k];
        i.bounds_max[k] = m->bounds_max[k];
    }
    i.lightmap_count = m->lightmap_count;
    i.lightmap_width = m->lightmap_width;
    i.lightmap_height = m->lightmap_height;
    i.surfel_area = m->surfel_area;
    i.grid_spacing = m->grid_spacing;
    i.texel_density = m->texel_density;
    i.scene_area = m->scene_area;
    i.file_size = bake->size;
    const glow_bake_xref *xh = glow__bake_xref(bake, NULL, NULL);
    if (xh) {
        i.system_key = xh->system_key;
        i.dependency_count = xh->dependency_count;
        i.proxy_count = xh->proxy_count;
    }
    *out_info = i;
    return GLOW_OK;
}

glow_result glow_bake_get_caches(const glow_bake *bake, uint32_t first, uint32_t count, glow_cache_info *out) {
    if (!bake || (!out && count)) return GLOW_ERROR_INVALID_ARGUMENT;
    const uint32_t n = bake->meta.cache_count;
    if (first > n || count > n - first) {
        GLOW__LOG_ERROR(bake->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_bake_get_caches: caches [%u, %u + %u) lie outside the bake's %u", first, first, count, n);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const glow_bake_cache *c = glow__bake_caches(bake);
    for (uint32_t i = 0; i < count; ++i) {
        const glow_bake_cache *src = &c[first + i];
        glow_cache_info *d = &out[i];
        memcpy(d->position, src->position, sizeof d->position);
        d->normal[0] = d->normal[1] = d->normal[2] = 0.0f;
        if (src->kind == GLOW_CACHE_KIND_LIGHTMAP) glow__oct_decode(src->normal_oct, d->normal);
        d->kind = src->kind;
        d->texel = src->texel;
    }
    return GLOW_OK;
}

glow_result glow_bake_get_sections(const glow_bake *bake, glow_bake_section_info *out, uint32_t capacity,
                                   uint32_t *out_count) {
    if (!bake || !out_count || (!out && capacity)) return GLOW_ERROR_INVALID_ARGUMENT;
    *out_count = bake->section_count;
    for (uint32_t i = 0; i < bake->section_count && i < capacity; ++i) {
        const glow_bake_section *e = &bake->table[i];
        for (int k = 0; k < 4; ++k) {
            const char ch = (char)((e->fourcc >> (8 * k)) & 0xFFu);
            out[i].fourcc[k] = (ch >= 32 && ch < 127) ? ch : '?';
        }
        out[i].fourcc[4] = '\0';
        out[i].version = e->version;
        out[i].offset = e->offset;
        out[i].size = e->size;
        out[i].crc32 = e->crc32;
    }
    return GLOW_OK;
}

void glow__bake_retain(const glow_bake *bake) { atomic_fetch_add(&((glow_bake *)bake)->systems, 1u); }
void glow__bake_release(const glow_bake *bake) { atomic_fetch_sub(&((glow_bake *)bake)->systems, 1u); }

glow_result glow_bake_get_geometry(const glow_bake *bake, glow_bake_geometry *out) {
    if (out) memset(out, 0, sizeof *out);
    if (!bake || !out) return GLOW_ERROR_INVALID_ARGUMENT;
    const glow_bake_triangle *t = glow__bake_triangles(bake);
    out->stride = (uint32_t)sizeof(glow_bake_triangle);
    if (!t) return GLOW_OK;
    out->triangle_count = bake->meta.triangle_count;
    out->positions = t[0].position;
    out->lightmap_uv = t[0].lm_uv;
    out->materials = &t[0].material;
    out->material_uv = known_ptr(bake, S_TUV0);
    out->lightmap_page = known_ptr(bake, S_TPAG);
    return GLOW_OK;
}

glow_result glow_bake_get_sky_transfer(const glow_bake *bake, glow_bake_sky_transfer *out) {
    if (out) memset(out, 0, sizeof *out);
    if (!bake || !out) return GLOW_ERROR_INVALID_ARGUMENT;
    const glow_bake_sky *kh = known_ptr(bake, S_SKYT);
    if (!kh) return GLOW_OK;
    const float *x = (const float *)(const void *)(kh + 1);
    out->rays = kh->rays;
    out->grid_rays = kh->grid_rays;
    out->surfel_count = kh->surfel_count;
    out->surfel_transfer = x;
    out->grid_cache_count = kh->grid_count;
    out->grid_visibility = kh->grid_count ? x + (size_t)kh->surfel_count * GLOW_BAKE_SKY_COEFFS : NULL;
    return GLOW_OK;
}

glow_result glow_bake_get_material(const glow_bake *bake, uint32_t index, glow_material_info *out) {
    if (out) memset(out, 0, sizeof *out);
    if (!bake || !out || index >= bake->meta.material_count) return GLOW_ERROR_INVALID_ARGUMENT;
    const glow_bake_material *m = glow__bake_materials(bake) + index;
    memcpy(out->name, m->name, sizeof out->name);
    out->name[sizeof out->name - 1] = 0;
    memcpy(out->albedo, m->albedo, sizeof out->albedo);
    memcpy(out->emission, m->emission, sizeof out->emission);
    out->has_albedo_texture = m->flags & 1u;
    const char *paths = known_ptr(bake, S_TEXP);
    if (paths) snprintf(out->albedo_texture, sizeof out->albedo_texture, "%s", paths + (size_t)index * GLOW_BAKE_TEXTURE_PATH);
    return GLOW_OK;
}

void glow_bake_destroy(glow_bake *bake) {
    if (!bake) return;
    unsigned live = atomic_load(&bake->systems);
    if (live) {
        GLOW__LOG_ERROR(bake->ctx, GLOW_ERROR_INVALID_OPERATION,
                        "glow_bake_destroy: %u system(s) still use this bake; destroy them first (the bake was not "
                        "destroyed)",
                        live);
        return;
    }
    glow__ctx_free(bake->ctx, bake);
}

/* --------------------------------------------------------------------------- internal views */
static const void *known_ptr(const glow_bake *b, int k) {
    return b->known[k].present ? (const void *)(b->data + b->known[k].offset) : NULL;
}
const glow_bake_meta *glow__bake_meta(const glow_bake *b) { return known_ptr(b, S_META); }
const glow_bake_material *glow__bake_materials(const glow_bake *b) { return known_ptr(b, S_MATL); }
const glow_bake_surfel *glow__bake_surfels(const glow_bake *b) { return known_ptr(b, S_SURF); }
const glow_bake_node *glow__bake_nodes(const glow_bake *b) { return known_ptr(b, S_NODE); }
const uint32_t *glow__bake_level_starts(const glow_bake *b) { return known_ptr(b, S_LEVL); }
const glow_bake_cache *glow__bake_caches(const glow_bake *b) { return known_ptr(b, S_CACH); }
const uint32_t *glow__bake_grid_map(const glow_bake *b) {
    uint64_t cells = (uint64_t)b->meta.grid_dims[0] * b->meta.grid_dims[1] * b->meta.grid_dims[2];
    return cells ? known_ptr(b, S_GRID) : NULL;
}
const uint8_t *glow__bake_grid_visibility(const glow_bake *b) {
    uint64_t cells = (uint64_t)b->meta.grid_dims[0] * b->meta.grid_dims[1] * b->meta.grid_dims[2];
    return cells && b->known[S_GVIS].present ? known_ptr(b, S_GVIS) : NULL;
}
const glow_bake_grid_fine *glow__bake_grid_fine(const glow_bake *b) {
    return b->known[S_GFIN].present ? known_ptr(b, S_GFIN) : NULL;
}
const uint32_t *glow__bake_lightmap_map(const glow_bake *b) {
    return b->meta.lightmap_count ? known_ptr(b, S_LMAP) : NULL;
}
const glow_bake_link_block *glow__bake_link_blocks(const glow_bake *b) { return known_ptr(b, S_LINK); }
const void *glow__bake_shlk_blocks(const glow_bake *b) { return known_ptr(b, S_SHLK); }
const uint16_t *glow__bake_link_subsets(const glow_bake *b) { return known_ptr(b, S_LSUB); }
const glow_bake_triangle *glow__bake_triangles(const glow_bake *b) { return known_ptr(b, S_GEOM); }
const glow_bake_detail *glow__bake_detail(const glow_bake *b, const uint32_t **texel, const uint32_t **first,
                                          const uint32_t **surfel, const float **weight) {
    const glow_bake_detail *dh = b->known[S_LDET].present ? known_ptr(b, S_LDET) : NULL;
    if (!dh) return NULL;
    const uint32_t *t = (const uint32_t *)(const void *)(dh + 1);
    if (texel) *texel = t;
    if (first) *first = t + dh->texel_count;
    if (surfel) *surfel = t + 2u * (size_t)dh->texel_count + 1u;
    if (weight) *weight = (const float *)(const void *)(t + 2u * (size_t)dh->texel_count + 1u + dh->link_count);
    return dh;
}

const glow_bake_xref *glow__bake_xref(const glow_bake *b, const uint64_t **dependency_key,
                                      const glow_bake_xref_proxy **proxies) {
    const glow_bake_xref *xh = b->known[S_XREF].present ? known_ptr(b, S_XREF) : NULL;
    if (!xh) return NULL;
    const uint64_t *k = (const uint64_t *)(const void *)(xh + 1);
    if (dependency_key) *dependency_key = k;
    if (proxies) *proxies = (const glow_bake_xref_proxy *)(const void *)(k + xh->dependency_count);
    return xh;
}

glow_result glow_bake_get_dependency(const glow_bake *bake, uint32_t index, uint64_t *out_key) {
    if (!bake || !out_key) return GLOW_ERROR_INVALID_ARGUMENT;
    const uint64_t *keys = NULL;
    const glow_bake_xref *xh = glow__bake_xref(bake, &keys, NULL);
    if (!xh || index >= xh->dependency_count) return GLOW_ERROR_INVALID_ARGUMENT;
    memcpy(out_key, keys + index, sizeof *out_key);
    return GLOW_OK;
}

const void *glow__bake_section(const glow_bake *b, uint32_t fourcc, uint64_t *out_size) {
    if (out_size) *out_size = 0;
    for (uint32_t i = 0; i < b->section_count; i++) {
        if (b->table[i].fourcc != fourcc) continue;
        if (out_size) *out_size = b->table[i].size;
        return b->data + b->table[i].offset;
    }
    return NULL;
}

const void *glow__bake_data(const glow_bake *b, uint64_t *out_size) {
    if (out_size) *out_size = b->size;
    return b->data;
}

glow_context *glow__bake_context(const glow_bake *b) { return b->ctx; }
