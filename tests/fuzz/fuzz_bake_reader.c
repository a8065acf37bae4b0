/* fuzz_bake_reader.c — libFuzzer target for the bake reader (glow_bake_load).
 *
 * Each input is loaded twice with a silent context:
 *   1. as is — exercises the container checks (sizes, magic, version, CRCs, table);
 *   2. with every CRC recomputed (when the header and table are readable) — otherwise almost every
 *      mutation dies at a checksum and the fuzzer never reaches the META / index / float checks.
 * A successful load is walked through the public and internal accessors so ASan sees every byte
 * the runtime may read. Seed corpus: tests/data/golden_v1.glow.
 * Build: -DGLOW_FUZZ=ON with CC=clang (tests/fuzz/CMakeLists.txt), or tools/fuzz-smoke.sh. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bake/bake_format.h"
#include "glow/glow.h"
#include "runtime_internal.h"
#include "fuzz_reseal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);


static volatile uint64_t sink;

static void touch(const glow_bake *bake) {
    glow_bake_info info;
    if (glow_bake_get_info(bake, &info) != GLOW_OK) abort();
    const glow_bake_meta *m = glow__bake_meta(bake);
    uint64_t acc = 0;
    const glow_bake_node *nodes = glow__bake_nodes(bake);
    const glow_bake_surfel *surf = glow__bake_surfels(bake);
    const uint32_t *ls = glow__bake_level_starts(bake);
    for (uint32_t i = 0; i <= m->level_count; i++) acc += ls[i];
    /* what a pull sweep reads: every internal node's children */
    for (uint32_t k = 1; k < m->level_count; k++)
        for (uint32_t i = ls[k]; i < ls[k + 1]; i++) acc += nodes[nodes[i].child[0]].parent + nodes[nodes[i].child[1]].parent;
    for (uint32_t i = 0; i < m->surfel_count; i++) {
        acc += glow__bake_materials(bake)[surf[i].material].flags;
        acc += glow__bake_caches(bake)[surf[i].feedback].kind;
        if (glow__bake_triangles(bake)) acc += glow__bake_triangles(bake)[surf[i].triangle].material;
    }
    const glow_bake_link_block *lb = glow__bake_link_blocks(bake);
    uint64_t blocks = (uint64_t)m->cache_count * m->link_blocks_per_cache;
    /* what the solver reads per link: the node's radiance (from its area), cone and direction */
    for (uint64_t b = 0; b < blocks; b++)
        for (uint32_t j = 0; j < GLOW_LINK_BLOCK; j++) {
            const glow_bake_node *n = &nodes[glow_bake_link_node(&lb[b], j)];
            uint32_t u, v;
            glow_bake_link_dir12(&lb[b], j, &u, &v);
            if (u > GLOW_LINK_DIR_MAX || v > GLOW_LINK_DIR_MAX) abort();
            float dir[3];
            glow__oct_decode12(u, v, dir);
            float omc = glow__half_to_float(lb[b].one_minus_cos[j]);
            if (!(omc >= 0.0f && omc <= 2.0f)) abort(); /* the reader guarantees this */
            float s = omc * dir[0] * n->area;
            uint32_t bits;
            memcpy(&bits, &s, sizeof bits);
            acc += n->normal_oct + bits;
        }
    const uint32_t *maps[2] = {glow__bake_grid_map(bake), glow__bake_lightmap_map(bake)};
    uint64_t counts[2] = {(uint64_t)m->grid_dims[0] * m->grid_dims[1] * m->grid_dims[2],
                          (uint64_t)m->lightmap_width * m->lightmap_height * m->lightmap_count};
    for (int k = 0; k < 2; k++)
        if (maps[k])
            for (uint64_t i = 0; i < counts[k]; i++)
                if (maps[k][i] != GLOW_MAP_EMPTY) acc += glow__bake_caches(bake)[maps[k][i] & GLOW_MAP_INDEX_MASK].texel;
    glow_bake_geometry geo; /* TPAG (1.7): the reader guarantees every page below lightmap_count */
    if (glow_bake_get_geometry(bake, &geo) == GLOW_OK && geo.lightmap_page)
        for (uint32_t t = 0; t < geo.triangle_count; t++) {
            if (geo.lightmap_page[t] >= m->lightmap_count) abort();
            acc += geo.lightmap_page[t];
        }
    const uint8_t *sh = glow__bake_shlk_blocks(bake);
    if (sh) {
        size_t bs = glow_bake_shlk_block_size(m->sh_bands);
        for (uint64_t b = 0; b < blocks; b++)
            for (int j = 0; j < (int)GLOW_LINK_BLOCK; j++) acc += nodes[fuzz_rd32(sh + b * bs + 4 * j)].parent;
    }
    sink = acc;
}

static void load_once(const uint8_t *data, size_t size) {
    glow_context_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.api_version = GLOW_VERSION;
    glow_context *ctx = NULL;
    if (glow_context_create(&desc, &ctx) != GLOW_OK) abort();
    glow_bake *bake = NULL;
    glow_result r = glow_bake_load(ctx, data, size, &bake);
    if ((r == GLOW_OK) != (bake != NULL)) abort();
    if (bake) touch(bake);
    glow_bake_destroy(bake);
    if (glow__ctx_live_allocations(ctx) != 0) abort();
    glow_context_destroy(ctx);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    uint32_t major, minor;
    (void)glow_bake_peek_version(data, size, &major, &minor);
    load_once(data, size);
    if (size >= 64 && size <= ((size_t)64 << 20)) {
        uint8_t *copy = malloc(size);
        if (!copy) return 0;
        memcpy(copy, data, size);
        fuzz_fix_crcs(copy, size);
        load_once(copy, size);
        free(copy);
    }
    return 0;
}
