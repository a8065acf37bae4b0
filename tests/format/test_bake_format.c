/* test_bake_format.c — the bake container: writer, reader validation (every error class, exact
 * result and logged code), CRC-32 against zlib, half and octahedral codecs, atomic file writes,
 * and the frozen golden v1 bake (tests/data/golden_v1.glow).
 *
 * The golden file is never regenerated silently: run this test once with
 * GLOW_REGENERATE_GOLDEN=1 to rewrite it (and then update GOLDEN_SIZE / GOLDEN_CRC below). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "bake/bake_format.h"
#include "bake_write.h"
#include "glow/glow.h"
#include "runtime_internal.h"
#include "../fuzz/fuzz_reseal.h"

#define GOLDEN_PATH GLOW_TEST_DATA_DIR "/golden_v1.glow"
/* Frozen properties of tests/data/golden_v1.glow (zlib crc32 of the whole file). */
#define GOLDEN_SIZE 1664u
#define GOLDEN_CRC 0xc3bc1586u

/* ------------------------------------------------------------------------------ helpers */
typedef struct test_log {
    int count;
    glow_result last_code;
    glow_log_level last_level;
    char last_message[1024];
} test_log;

static void test_logger(void *user, glow_log_level level, glow_result code, const char *message, const char *file,
                        int line) {
    test_log *l = user;
    l->count++;
    l->last_code = code;
    l->last_level = level;
    snprintf(l->last_message, sizeof l->last_message, "%s", message);
    assert_non_null(file);
    assert_true(line > 0);
}

static glow_context *make_ctx(test_log *log) {
    memset(log, 0, sizeof *log);
    glow_context_desc d;
    memset(&d, 0, sizeof d);
    d.api_version = GLOW_VERSION;
    d.logger.log = test_logger;
    d.logger.user = log;
    glow_context *ctx = NULL;
    assert_int_equal(glow_context_create(&d, &ctx), GLOW_OK);
    assert_non_null(ctx);
    return ctx;
}

static uint32_t rng_state = 0x12345678u;
static uint32_t rng(void) { /* xorshift32 */
    uint32_t x = rng_state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return rng_state = x;
}
static float rngf(void) { return (float)(rng() >> 8) * (1.0f / 16777216.0f); }

static uint32_t u32_at(const unsigned char *p) { uint32_t v; memcpy(&v, p, 4); return v; }
static uint64_t u64_at(const unsigned char *p) { uint64_t v; memcpy(&v, p, 8); return v; }
static void put_u16(unsigned char *p, uint16_t v) { memcpy(p, &v, 2); }
static void put_u32(unsigned char *p, uint32_t v) { memcpy(p, &v, 4); }
static void put_u64(unsigned char *p, uint64_t v) { memcpy(p, &v, 8); }

/* Recomputes every CRC of an image (payloads, table, header) with zlib, so a patched field is
 * what the reader trips over. Tolerates nonsense (only entries that fit are refreshed). */
static void refresh_crcs(unsigned char *img, size_t size) {
    if (size < 64) return;
    uint32_t n = u32_at(img + 12);
    if (n > GLOW_BAKE_MAX_SECTIONS) n = GLOW_BAKE_MAX_SECTIONS;
    if (64u + 32u * (size_t)n > size) n = (uint32_t)((size - 64) / 32);
    for (uint32_t i = 0; i < n; i++) {
        unsigned char *e = img + 64 + 32 * i;
        uint64_t off = u64_at(e + 8), sz = u64_at(e + 16);
        if (off <= size && sz <= size - off) put_u32(e + 24, (uint32_t)crc32(0L, img + off, (uInt)sz));
    }
    put_u32(img + 28, (uint32_t)crc32(0L, img + 64, (uInt)(32u * u32_at(img + 12) <= size - 64 ? 32u * u32_at(img + 12) : 0)));
    put_u32(img + 32, 0);
    put_u32(img + 32, (uint32_t)crc32(0L, img, 64));
}

/* Index of the table entry with `fourcc`, or -1. */
static int find_entry(const unsigned char *img, uint32_t fourcc) {
    uint32_t n = u32_at(img + 12);
    for (uint32_t i = 0; i < n; i++)
        if (u32_at(img + 64 + 32 * i) == fourcc) return (int)i;
    return -1;
}
static unsigned char *entry_ptr(unsigned char *img, uint32_t fourcc) {
    int i = find_entry(img, fourcc);
    assert_true(i >= 0);
    return img + 64 + 32 * i;
}
static unsigned char *payload_ptr(unsigned char *img, uint32_t fourcc) {
    return img + u64_at(entry_ptr(img, fourcc) + 8);
}

/* Loads and checks the exact result AND the logged code; returns the bake on GLOW_OK. */
#define EXPECT_LOAD(img, size, code) expect_load((img), (size), (code), NULL, __LINE__)
#define EXPECT_LOAD_MSG(img, size, code, needle) expect_load((img), (size), (code), (needle), __LINE__)
static void expect_load(const void *img, size_t size, glow_result code, const char *needle, int line) {
    test_log log;
    glow_context *ctx = make_ctx(&log);
    glow_bake *bake = (glow_bake *)(uintptr_t)1;
    glow_result r = glow_bake_load(ctx, img, size, &bake);
    if (r != code)
        fail_msg("line %d: glow_bake_load returned %s, expected %s (log: %s)", line, glow_result_string(r),
                 glow_result_string(code), log.count ? log.last_message : "-");
    if (code == GLOW_OK) {
        if (log.count != 0) fail_msg("line %d: a valid bake logged: %s", line, log.last_message);
        assert_non_null(bake);
    } else {
        if (bake != NULL) fail_msg("line %d: out_bake not NULL on failure", line);
        if (log.count < 1) fail_msg("line %d: failure was not logged", line);
        if (log.last_code != code)
            fail_msg("line %d: logged code %s, expected %s (%s)", line, glow_result_string(log.last_code),
                     glow_result_string(code), log.last_message);
        if (log.last_level != GLOW_LOG_ERROR) fail_msg("line %d: logged at level %d", line, (int)log.last_level);
        if (needle && !strstr(log.last_message, needle))
            fail_msg("line %d: message \"%s\" does not mention \"%s\"", line, log.last_message, needle);
    }
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
}

/* ------------------------------------------------------------------------------ a hand-built bake */
/* Scene: a 1 x 1 floor quad (y = 0) split into two triangles, one surfel each (area 0.5): a grey
 * floor surfel and an emissive one; a 3-node tree; a 1x1x2 grid with one cache and a 2x2
 * lightmap with one cache; 2 links per cache (1 block each); 2 materials; GEOM. Halves and
 * octahedral values are literals, so the golden file does not depend on the codecs under test.
 * FROZEN: the golden file is this bake. Change a copy in a test, never this function. */
#define SHLK_BANDS 2u
#define SHLK_BLOCK (64u + 32u * SHLK_BANDS * SHLK_BANDS)
typedef struct test_bake {
    glow_bake_meta meta;
    glow_bake_material mat[2];
    glow_bake_surfel surf[2];
    glow_bake_node node[3];
    uint32_t levl[4]; /* level_count + 1 used */
    glow_bake_cache cache[2];
    uint32_t grid[2];
    uint32_t lmap[4];
    glow_bake_link_block link[2];
    unsigned char shlk[2 * SHLK_BLOCK];
    uint16_t lsub[2 * GLOW_LINK_BLOCK];
    glow_bake_triangle tri[2];
    float tuv0[2][6];
    char texp[2][GLOW_BAKE_TEXTURE_PATH];
    struct { /* LDET (1.2): two detail texels of a 4 x 4 detail over the 2 x 2 lightmap, three links */
        glow_bake_detail h;
        uint32_t texel[2], first[3], surfel[3];
        float weight[3];
    } ldet;
} test_bake;

#define OCT_UP 0x7FFF0000u /* (0, 1, 0): u = 0, v = 32767 */

static void set3(float *d, float x, float y, float z) { d[0] = x; d[1] = y; d[2] = z; }

static void build_golden(test_bake *b) {
    memset(b, 0, sizeof *b);
    glow_bake_meta *m = &b->meta;
    m->surfel_count = 2;
    m->node_count = 3;
    m->level_count = 2;
    m->cache_count = 2;
    m->grid_cache_count = 1;
    m->lightmap_cache_count = 1;
    m->links_per_cache = 2;
    m->link_blocks_per_cache = 1;
    m->sh_bands = SHLK_BANDS;
    m->link_kind = GLOW_LINK_KIND_RUNTIME_PROJECTION;
    m->material_count = 2;
    m->triangle_count = 2;
    set3(m->bounds_min, 0.0f, 0.0f, 0.0f);
    set3(m->bounds_max, 1.0f, 0.0f, 1.0f);
    m->surfel_area = 0.5f;
    m->factor_scale = 0.636619772f; /* 1 / (pi * 0.5) */
    set3(m->grid_origin, 0.5f, 0.25f, 0.25f);
    m->grid_spacing = 0.5f;
    m->grid_dims[0] = 1;
    m->grid_dims[1] = 1;
    m->grid_dims[2] = 2;
    m->lightmap_count = 1;
    m->lightmap_width = 2;
    m->lightmap_height = 2;
    m->texel_density = 2.0f;
    m->seed = 7;
    m->scene_area = 1.0;
    m->source_triangles = 3;
    m->skipped_degenerate = 1;
    m->quality = 0;
    m->rays_per_surfel = 1;

    snprintf(b->mat[0].name, sizeof b->mat[0].name, "floor");
    set3(b->mat[0].albedo, 0.5f, 0.5f, 0.5f);
    snprintf(b->mat[1].name, sizeof b->mat[1].name, "lamp");
    set3(b->mat[1].albedo, 0.8f, 0.7f, 0.6f);
    set3(b->mat[1].emission, 2.0f, 1.5f, 1.0f);

    set3(b->surf[0].position, 0.75f, 0.0f, 0.25f);
    set3(b->surf[0].normal, 0.0f, 1.0f, 0.0f);
    set3(b->surf[0].albedo, 0.5f, 0.5f, 0.5f);
    b->surf[0].material = 0;
    b->surf[0].feedback = 1;
    b->surf[0].triangle = 0;
    set3(b->surf[1].position, 0.25f, 0.0f, 0.75f);
    set3(b->surf[1].normal, 0.0f, 1.0f, 0.0f);
    set3(b->surf[1].albedo, 0.8f, 0.7f, 0.6f);
    set3(b->surf[1].emission, 2.0f, 1.5f, 1.0f);
    b->surf[1].material = 1;
    b->surf[1].feedback = 1;
    b->surf[1].triangle = 1;

    for (int i = 0; i < 2; i++) {
        b->node[i].child[0] = b->node[i].child[1] = GLOW_NODE_NONE;
        b->node[i].parent = 2;
        b->node[i].area = 0.5f;
        memcpy(b->node[i].position, b->surf[i].position, sizeof b->node[i].position);
        b->node[i].normal_oct = OCT_UP;
    }
    b->node[2].child[0] = 0;
    b->node[2].child[1] = 1;
    b->node[2].parent = GLOW_NODE_NONE;
    b->node[2].area = 1.0f;
    set3(b->node[2].position, 0.5f, 0.0f, 0.5f);
    b->node[2].normal_oct = OCT_UP;
    b->levl[0] = 0;
    b->levl[1] = 2;
    b->levl[2] = 3;

    set3(b->cache[0].position, 0.5f, 0.25f, 0.75f);
    b->cache[0].kind = GLOW_CACHE_KIND_GRID;
    b->cache[0].texel = 1;
    set3(b->cache[1].position, 0.25f, 0.0f, 0.25f);
    b->cache[1].normal_oct = OCT_UP;
    b->cache[1].kind = GLOW_CACHE_KIND_LIGHTMAP;
    b->cache[1].texel = 0;
    b->grid[0] = 0u | GLOW_MAP_COPY_BIT;
    b->grid[1] = 0u;
    b->lmap[0] = 1u;
    b->lmap[1] = 1u | GLOW_MAP_COPY_BIT;
    b->lmap[2] = GLOW_MAP_EMPTY;
    b->lmap[3] = 1u | GLOW_MAP_COPY_BIT;

    /* cache 0 (grid, above the floor) sees the root and leaf 0; cache 1 sees leaf 1 and leaf 0.
     * Packed by hand (bake_format.h): node_dir = node | (dir_u >> 4) << 24,
     * dir_lo = (dir_u & 15) | dir_v << 4, with dir_u, dir_v 12-bit octahedral (s = q * 2/4095 - 1).
     * Lanes 2..15 stay zero: unused (node 0, one_minus_cos 0, dir 0). */
    b->link[0].node_dir[0] = 0x80000002u;   /* node 2, dir_u 2048 */
    b->link[0].dir_lo[0] = 0x0000;          /* dir_v 0: (u, v) = (2048, 0) ~ (0, -1, 0) */
    b->link[0].one_minus_cos[0] = 0x34CD;   /* ~0.3 */
    b->link[0].node_dir[1] = 0x9F000000u;   /* node 0, dir_u 2559 = 0x9FF */
    b->link[0].dir_lo[1] = 0x200F;          /* dir_v 512: (2559, 512) ~ oct (0.25, -0.75) */
    b->link[0].one_minus_cos[1] = 0x2E66;   /* ~0.1 */
    b->link[1].node_dir[0] = 0x80000001u;   /* node 1, dir_u 2048 */
    b->link[1].dir_lo[0] = 0xFFF0;          /* dir_v 4095: ~ (0, 1, 0) */
    b->link[1].one_minus_cos[0] = 0x3266;   /* ~0.2 */
    b->link[1].node_dir[1] = 0xBF000000u;   /* node 0, dir_u 3071 = 0xBFF */
    b->link[1].dir_lo[1] = 0xC00F;          /* dir_v 3072: ~ oct (0.5, 0.5) = (0.71, 0.71, 0) */
    b->link[1].one_minus_cos[1] = 0x2A66;   /* ~0.05 */

    /* SHLK (only written when a test asks): same cut (plain u32 nodes), coefficients 0.25 */
    static const uint32_t shlk_nodes[2][2] = {{2, 0}, {1, 0}};
    for (int blk = 0; blk < 2; blk++) {
        unsigned char *p = b->shlk + blk * SHLK_BLOCK;
        for (int lane = 0; lane < 2; lane++) put_u32(p + 4 * lane, shlk_nodes[blk][lane]);
        for (uint32_t k = 0; k < SHLK_BANDS * SHLK_BANDS * 16u; k++) put_u16(p + 64 + 2 * k, 0x3400);
    }

    float t0[9] = {0, 0, 0, 1, 0, 0, 1, 0, 1}, t1[9] = {0, 0, 0, 1, 0, 1, 0, 0, 1};
    memcpy(b->tri[0].position, t0, sizeof t0);
    memcpy(b->tri[1].position, t1, sizeof t1);
    uint16_t uv0[6] = {0, 0, 65535, 0, 65535, 65535}, uv1[6] = {0, 0, 65535, 65535, 0, 65535};
    memcpy(b->tri[0].lm_uv, uv0, sizeof uv0);
    memcpy(b->tri[1].lm_uv, uv1, sizeof uv1);
    b->tri[0].material = 0;
    b->tri[0].source = 0;
    b->tri[0].normal_oct = OCT_UP;
    b->tri[1].material = 1;
    b->tri[1].source = 2;
    b->tri[1].normal_oct = OCT_UP;

    b->ldet.h = (glow_bake_detail){.factor = 2, .width = 4, .height = 4, .texel_count = 2, .link_count = 3};
    b->ldet.texel[0] = 1, b->ldet.texel[1] = 6;
    b->ldet.first[0] = 0, b->ldet.first[1] = 2, b->ldet.first[2] = 3;
    b->ldet.surfel[0] = 0, b->ldet.surfel[1] = 1, b->ldet.surfel[2] = 1;
    b->ldet.weight[0] = 0.5f, b->ldet.weight[1] = -0.25f, b->ldet.weight[2] = 0.1f;
}

enum { WITH_SHLK = 1, NO_GEOM = 2, NO_GRID = 4, NO_LMAP = 8, EXTRA_UNKNOWN = 16, WITH_LSUB = 32, SHORT_LSUB = 64,
       WITH_TEX = 128, SHORT_TUV0 = 256, WITH_LDET = 512, SHORT_LDET = 1024 };

static uint32_t sections_of(const test_bake *b, int flags, glow__section_data *s) {
    static const unsigned char unknown_payload[5] = {1, 2, 3, 4, 5};
    uint32_t n = 0;
#define ADD(fc, ptr, sz) (s[n].fourcc = (fc), s[n].version = 1, s[n].data = (ptr), s[n].size = (sz), n++)
    ADD(GLOW_SECTION_META, &b->meta, sizeof b->meta);
    ADD(GLOW_SECTION_MATL, b->mat, sizeof b->mat);
    ADD(GLOW_SECTION_SURF, b->surf, sizeof b->surf);
    ADD(GLOW_SECTION_NODE, b->node, sizeof b->node);
    ADD(GLOW_SECTION_LEVL, b->levl, (b->meta.level_count + 1u) * sizeof(uint32_t));
    ADD(GLOW_SECTION_CACH, b->cache, sizeof b->cache);
    if (!(flags & NO_GRID)) ADD(GLOW_SECTION_GRID, b->grid, sizeof b->grid);
    if (!(flags & NO_LMAP)) ADD(GLOW_SECTION_LMAP, b->lmap, sizeof b->lmap);
    if (flags & EXTRA_UNKNOWN) ADD(GLOW_FOURCC('Z', 'Z', 'Z', 'Z'), unknown_payload, sizeof unknown_payload);
    ADD(GLOW_SECTION_LINK, b->link, sizeof b->link);
    if (flags & WITH_SHLK) ADD(GLOW_SECTION_SHLK, b->shlk, sizeof b->shlk);
    if (flags & (WITH_LSUB | SHORT_LSUB))
        ADD(GLOW_SECTION_LSUB, b->lsub, (flags & SHORT_LSUB) ? sizeof b->lsub - 2u : sizeof b->lsub);
    if (!(flags & NO_GEOM)) ADD(GLOW_SECTION_GEOM, b->tri, sizeof b->tri);
    if (flags & (WITH_TEX | SHORT_TUV0)) {
        ADD(GLOW_SECTION_TUV0, b->tuv0, (flags & SHORT_TUV0) ? sizeof b->tuv0 - 4u : sizeof b->tuv0);
        ADD(GLOW_SECTION_TEXP, b->texp, sizeof b->texp);
    }
    if (flags & (WITH_LDET | SHORT_LDET)) ADD(GLOW_SECTION_LDET, &b->ldet, (flags & SHORT_LDET) ? sizeof b->ldet - 4u : sizeof b->ldet);
#undef ADD
    return n;
}

static unsigned char *write_bake(const test_bake *b, int flags, size_t *out_size) {
    glow__section_data s[16];
    uint32_t n = sections_of(b, flags, s);
    void *img = NULL;
    uint64_t size = 0;
    assert_int_equal(glow__bake_write_memory(s, n, &img, &size), GLOW_OK);
    assert_non_null(img);
    *out_size = (size_t)size;
    return img;
}

/* Builds the golden bake, lets `patch` change it, writes it and expects `code` on load. */
#define EXPECT_PATCHED(flags, code, needle, ...)                     \
    do {                                                             \
        test_bake tb_;                                               \
        build_golden(&tb_);                                          \
        test_bake *b = &tb_;                                         \
        __VA_ARGS__;                                                 \
        size_t sz_;                                                  \
        unsigned char *img_ = write_bake(b, (flags), &sz_);          \
        expect_load(img_, sz_, (code), (needle), __LINE__);          \
        free(img_);                                                  \
    } while (0)

/* ------------------------------------------------------------------------------ valid loads */
/* minor: the golden file is format 1.0; bakes this writer makes are the current 1.x */
static void check_golden_contents(const glow_bake *bake, uint32_t minor) {
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(bake, &info), GLOW_OK);
    assert_int_equal(info.format_major, 1);
    assert_int_equal(info.format_minor, minor);
    assert_int_equal(info.surfel_count, 2);
    assert_int_equal(info.node_count, 3);
    assert_int_equal(info.level_count, 2);
    assert_int_equal(info.cache_count, 2);
    assert_int_equal(info.grid_cache_count, 1);
    assert_int_equal(info.lightmap_cache_count, 1);
    assert_int_equal(info.links_per_cache, 2);
    assert_int_equal(info.sh_bands, 2);
    assert_int_equal(info.link_kind, GLOW_LINK_KIND_RUNTIME_PROJECTION);
    assert_int_equal(info.material_count, 2);
    assert_int_equal(info.triangle_count, 2);
    assert_int_equal(info.grid_dims[0], 1);
    assert_int_equal(info.grid_dims[1], 1);
    assert_int_equal(info.grid_dims[2], 2);
    assert_int_equal(info.lightmap_count, 1);
    assert_int_equal(info.lightmap_width, 2);
    assert_int_equal(info.lightmap_height, 2);
    assert_true(info.bounds_max[0] == 1.0f && info.bounds_max[1] == 0.0f && info.bounds_max[2] == 1.0f);
    assert_true(info.surfel_area == 0.5f && info.grid_spacing == 0.5f && info.texel_density == 2.0f);
    assert_true(info.scene_area == 1.0);

    const glow_bake_meta *m = glow__bake_meta(bake);
    assert_non_null(m);
    assert_int_equal(m->seed, 7);
    assert_int_equal(m->source_triangles, 3);
    assert_true(((uintptr_t)m % GLOW_BAKE_ALIGN) == 0);
    const glow_bake_surfel *s = glow__bake_surfels(bake);
    assert_true(s[1].position[0] == 0.25f && s[1].position[2] == 0.75f && s[1].emission[1] == 1.5f);
    assert_int_equal(s[1].material, 1);
    const glow_bake_material *mat = glow__bake_materials(bake);
    assert_string_equal(mat[1].name, "lamp");
    const glow_bake_node *nd = glow__bake_nodes(bake);
    assert_int_equal(nd[2].child[1], 1);
    assert_int_equal(nd[0].parent, 2);
    assert_int_equal(glow__bake_level_starts(bake)[1], 2);
    const glow_bake_cache *c = glow__bake_caches(bake);
    assert_int_equal(c[1].kind, GLOW_CACHE_KIND_LIGHTMAP);
    assert_int_equal(glow__bake_grid_map(bake)[0], GLOW_MAP_COPY_BIT);
    assert_int_equal(glow__bake_lightmap_map(bake)[2], GLOW_MAP_EMPTY);
    const glow_bake_link_block *lb = glow__bake_link_blocks(bake);
    assert_int_equal(lb[0].node_dir[0], 0x80000002u);
    assert_int_equal(glow_bake_link_node(&lb[0], 0), 2);
    assert_int_equal(glow_bake_link_node(&lb[1], 0), 1);
    assert_int_equal(lb[1].one_minus_cos[0], 0x3266);
    uint32_t du, dv;
    glow_bake_link_dir12(&lb[0], 1, &du, &dv);
    assert_int_equal(du, 2559);
    assert_int_equal(dv, 512);
    glow_bake_link_dir12(&lb[1], 1, &du, &dv);
    assert_int_equal(du, 3071);
    assert_int_equal(dv, 3072);
    assert_int_equal(lb[1].dir_lo[1], 0xC00F);
    assert_true(((uintptr_t)lb % GLOW_BAKE_ALIGN) == 0);
    assert_null(glow__bake_shlk_blocks(bake));
    const glow_bake_triangle *t = glow__bake_triangles(bake);
    assert_non_null(t);
    assert_int_equal(t[1].source, 2);
    assert_int_equal(t[0].lm_uv[4], 65535);
    uint64_t sz = 0;
    assert_non_null(glow__bake_section(bake, GLOW_SECTION_LEVL, &sz));
    assert_int_equal(sz, 12);
    assert_null(glow__bake_section(bake, GLOW_FOURCC('N', 'O', 'N', 'E'), &sz));
    assert_int_equal(sz, 0);
}

static void test_load_valid(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    size_t size;
    unsigned char *img = write_bake(&tb, 0, &size);
    EXPECT_LOAD(img, size, GLOW_OK);

    test_log log;
    glow_context *ctx = make_ctx(&log);
    glow_bake *bake = NULL;
    assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_OK);
    memset(img, 0xAB, size); /* the bake holds a copy */
    free(img);
    check_golden_contents(bake, GLOW_BAKE_FORMAT_VERSION_MINOR);
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(bake, &info), GLOW_OK);
    assert_int_equal(info.file_size, size);
    assert_int_equal(glow__ctx_live_allocations(ctx), 1);
    assert_ptr_equal(glow__bake_context(bake), ctx);
    glow_bake_destroy(bake);
    assert_int_equal(glow__ctx_live_allocations(ctx), 0);
    glow_bake_destroy(NULL);
    assert_int_equal(log.count, 0);
    glow_context_destroy(ctx);
    glow_context_destroy(NULL);
}

static void test_load_variants(void **state) {
    (void)state;
    /* lightmap detail (LDET, 1.2): sizes, ranges, order, finite weights */
    _Static_assert(sizeof(((test_bake *)0)->ldet) == 32 + 4 * (2 + 3 + 3 + 3), "LDET payload without padding");
    EXPECT_PATCHED(WITH_LDET, GLOW_OK, NULL, (void)b);
    EXPECT_PATCHED(SHORT_LDET, GLOW_ERROR_CORRUPT_DATA, "section 'LDET' is", (void)b);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_OUT_OF_RANGE, "LDET link 2: surfel 2", b->ldet.surfel[2] = 2);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_CORRUPT_DATA, "not ascending", b->ldet.texel[1] = 1);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_CORRUPT_DATA, "outside the grid", b->ldet.texel[1] = 16);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_CORRUPT_DATA, "does not fit", b->ldet.h.width = 6);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_CORRUPT_DATA, "does not fit", b->ldet.h.factor = 1; b->ldet.h.width = 2;
                   b->ldet.h.height = 2);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_CORRUPT_DATA, "decreasing", b->ldet.first[1] = 4);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_CORRUPT_DATA, "not 0 to link_count", b->ldet.first[0] = 1);
    EXPECT_PATCHED(WITH_LDET, GLOW_ERROR_CORRUPT_DATA, "weight", b->ldet.weight[1] = NAN);
    {
        test_bake tb;
        build_golden(&tb);
        size_t size;
        unsigned char *img = write_bake(&tb, WITH_LDET, &size);
        test_log log;
        glow_context *ctx = make_ctx(&log);
        glow_bake *bake = NULL;
        assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_OK);
        const uint32_t *texel, *first, *surfel;
        const float *weight;
        const glow_bake_detail *dh = glow__bake_detail(bake, &texel, &first, &surfel, &weight);
        assert_non_null(dh);
        assert_int_equal(dh->texel_count, 2);
        assert_int_equal(texel[1], 6);
        assert_int_equal(first[2], 3);
        assert_int_equal(surfel[1], 1);
        assert_true(weight[1] == -0.25f);
        glow_bake_destroy(bake);
        glow_context_destroy(ctx);
        free(img);
    }
    /* full-SH links */
    EXPECT_PATCHED(WITH_SHLK, GLOW_OK, NULL, b->meta.link_kind |= GLOW_LINK_KIND_FULL_SH);
    {
        test_bake tb;
        build_golden(&tb);
        tb.meta.link_kind |= GLOW_LINK_KIND_FULL_SH;
        size_t size;
        unsigned char *img = write_bake(&tb, WITH_SHLK, &size);
        test_log log;
        glow_context *ctx = make_ctx(&log);
        glow_bake *bake = NULL;
        assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_OK);
        const unsigned char *sh = glow__bake_shlk_blocks(bake);
        assert_non_null(sh);
        assert_int_equal(u32_at(sh + SHLK_BLOCK), 1); /* block 1, lane 0 node */
        glow_bake_destroy(bake);
        glow_context_destroy(ctx);
        free(img);
    }
    /* link subsets (LSUB): any weights; the section and link_kind's bit go together, one uint16 a lane */
    EXPECT_PATCHED(WITH_LSUB, GLOW_OK, NULL, b->meta.link_kind |= GLOW_LINK_KIND_SUBSETS; b->lsub[3] = 0xFFFFu);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "missing section 'LSUB'", b->meta.link_kind |= GLOW_LINK_KIND_SUBSETS);
    EXPECT_PATCHED(WITH_LSUB, GLOW_ERROR_CORRUPT_DATA, "section 'LSUB' present but link_kind", (void)b);
    EXPECT_PATCHED(SHORT_LSUB, GLOW_ERROR_CORRUPT_DATA, "LSUB", b->meta.link_kind |= GLOW_LINK_KIND_SUBSETS);
    /* link gradients (link_kind bit 8): the same section holding gradient codes; never with bit 4 */
    EXPECT_PATCHED(WITH_LSUB, GLOW_OK, NULL, b->meta.link_kind |= GLOW_LINK_KIND_GRADIENT; b->lsub[3] = 0xFFFFu);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "missing section 'LSUB'", b->meta.link_kind |= GLOW_LINK_KIND_GRADIENT);
    EXPECT_PATCHED(WITH_LSUB, GLOW_ERROR_CORRUPT_DATA, "both link subsets and link gradients",
                   b->meta.link_kind |= GLOW_LINK_KIND_SUBSETS | GLOW_LINK_KIND_GRADIENT);
    {
        test_bake tb;
        build_golden(&tb);
        tb.meta.link_kind |= GLOW_LINK_KIND_SUBSETS;
        tb.lsub[GLOW_LINK_BLOCK + 1] = 0x1234u;
        size_t size;
        unsigned char *img = write_bake(&tb, WITH_LSUB, &size);
        test_log log;
        glow_context *ctx = make_ctx(&log);
        glow_bake *bake = NULL;
        assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_OK);
        const uint16_t *ls = glow__bake_link_subsets(bake);
        assert_non_null(ls);
        assert_int_equal(ls[GLOW_LINK_BLOCK + 1], 0x1234u); /* block 1, lane 1 */
        glow_bake_destroy(bake);
        glow_context_destroy(ctx);
        free(img);
    }
    /* format 1.1: material UVs (TUV0, with GEOM, finite) and texture paths (TEXP, NUL-terminated) */
    EXPECT_PATCHED(WITH_TEX, GLOW_OK, NULL, b->tuv0[1][5] = -3.5f; strcpy(b->texp[1], "textures/brick.png"));
    EXPECT_PATCHED(WITH_TEX | NO_GEOM, GLOW_ERROR_CORRUPT_DATA, "'TUV0' (material UVs) without 'GEOM'", (void)b);
    EXPECT_PATCHED(SHORT_TUV0, GLOW_ERROR_CORRUPT_DATA, "TUV0", (void)b);
    EXPECT_PATCHED(WITH_TEX, GLOW_ERROR_CORRUPT_DATA, "TUV0 triangle 1: non-finite", b->tuv0[1][2] = NAN);
    EXPECT_PATCHED(WITH_TEX, GLOW_ERROR_CORRUPT_DATA, "TEXP material 0: the texture path is not NUL-terminated",
                   memset(b->texp[0], 'a', sizeof b->texp[0]));
    {
        test_bake tb;
        build_golden(&tb);
        tb.tuv0[1][3] = 0.25f;
        strcpy(tb.texp[1], "/data/sponza/textures/lion.png");
        size_t size;
        unsigned char *img = write_bake(&tb, WITH_TEX, &size);
        test_log log;
        glow_context *ctx = make_ctx(&log);
        glow_bake *bake = NULL;
        assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_OK);
        glow_bake_geometry g;
        assert_int_equal(glow_bake_get_geometry(bake, &g), GLOW_OK);
        assert_non_null(g.material_uv);
        assert_true(g.material_uv[6 + 3] == 0.25f);
        glow_material_info mi;
        assert_int_equal(glow_bake_get_material(bake, 1, &mi), GLOW_OK);
        assert_string_equal(mi.albedo_texture, "/data/sponza/textures/lion.png");
        assert_int_equal(glow_bake_get_material(bake, 0, &mi), GLOW_OK);
        assert_string_equal(mi.albedo_texture, "");
        glow_bake_destroy(bake);
        /* a bake without them: NULL and "" */
        free(img);
        img = write_bake(&tb, 0, &size);
        assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_OK);
        assert_int_equal(glow_bake_get_geometry(bake, &g), GLOW_OK);
        assert_null(g.material_uv);
        assert_int_equal(glow_bake_get_material(bake, 1, &mi), GLOW_OK);
        assert_string_equal(mi.albedo_texture, "");
        glow_bake_destroy(bake);
        glow_context_destroy(ctx);
        free(img);
    }
    /* without GEOM: triangle indices are not checked */
    EXPECT_PATCHED(NO_GEOM, GLOW_OK, NULL, b->surf[0].triangle = 99);
    /* unknown sections are skipped */
    EXPECT_PATCHED(EXTRA_UNKNOWN, GLOW_OK, NULL, (void)b);
    /* a single surfel: the leaf is the root, one level */
    {
        test_bake tb;
        build_golden(&tb);
        tb.meta.surfel_count = 1;
        tb.meta.node_count = 1;
        tb.meta.level_count = 1;
        tb.meta.scene_area = 0.5; /* the one leaf's area: the leaves' areas sum to scene_area */
        tb.node[0].parent = GLOW_NODE_NONE;
        tb.levl[1] = 1;
        for (int i = 0; i < 2; i++)
            for (int k = 0; k < 2; k++) tb.link[i].node_dir[k] &= ~GLOW_LINK_NODE_MASK; /* node 0, dir kept */
        glow__section_data s[16];
        uint32_t n = sections_of(&tb, 0, s);
        for (uint32_t i = 0; i < n; i++) {
            if (s[i].fourcc == GLOW_SECTION_SURF) s[i].size = sizeof(glow_bake_surfel);
            if (s[i].fourcc == GLOW_SECTION_NODE) s[i].size = sizeof(glow_bake_node);
            if (s[i].fourcc == GLOW_SECTION_LEVL) s[i].size = 2 * sizeof(uint32_t);
        }
        void *img;
        uint64_t size;
        assert_int_equal(glow__bake_write_memory(s, n, &img, &size), GLOW_OK);
        EXPECT_LOAD(img, (size_t)size, GLOW_OK);
        tb.node[0].parent = 0; /* the root must have no parent */
        free(img);
        assert_int_equal(glow__bake_write_memory(s, n, &img, &size), GLOW_OK);
        EXPECT_LOAD_MSG(img, (size_t)size, GLOW_ERROR_OUT_OF_RANGE, "root node 0");
        free(img);
    }
    /* a bake without a lightmap: lightmap caches must go too (cache 1 would point at no texel) */
    EXPECT_PATCHED(NO_LMAP, GLOW_ERROR_OUT_OF_RANGE, "cache 1: texel/cell 0 out of range (0)",
                   b->meta.lightmap_count = 0);
}

/* ------------------------------------------------------------------------------ container errors */
static void test_truncated(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    size_t size;
    unsigned char *img = write_bake(&tb, 0, &size);
    uint32_t n = u32_at(img + 12);
    size_t lens[] = {0, 10, 63, 64, 65, 64 + 32 * (size_t)n - 1, 64 + 32 * (size_t)n, size / 2, size - 64, size - 1};
    for (size_t i = 0; i < sizeof lens / sizeof lens[0]; i++) {
        /* a fresh allocation of exactly that length, so ASan catches any read past it */
        unsigned char *cut = malloc(lens[i] ? lens[i] : 1);
        memcpy(cut, img, lens[i]);
        expect_load(cut, lens[i], GLOW_ERROR_TRUNCATED, lens[i] >= 64 ? "truncated" : "shorter", __LINE__);
        free(cut);
    }
    EXPECT_LOAD(NULL, 0, GLOW_ERROR_TRUNCATED);
    free(img);
}

static void test_magic_version(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    size_t size;
    unsigned char *img = write_bake(&tb, 0, &size);
    unsigned char *p = malloc(size);

    memcpy(p, img, size);
    p[0] = 'X';
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_BAD_MAGIC, "not a Glow bake");
    memcpy(p, img, size);
    memcpy(p, "glow", 4);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_BAD_MAGIC);

    memcpy(p, img, size);
    put_u16(p + 4, 2);
    refresh_crcs(p, size);
    {
        char needle[32];
        snprintf(needle, sizeof needle, "version 2.%u", (unsigned)GLOW_BAKE_FORMAT_VERSION_MINOR);
        EXPECT_LOAD_MSG(p, size, GLOW_ERROR_VERSION_MISMATCH, needle);
    }
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_VERSION_MISMATCH, "reads format version 1");
    put_u16(p + 4, 0);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_VERSION_MISMATCH);
    /* a newer minor loads */
    memcpy(p, img, size);
    put_u16(p + 6, 7);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_OK);

    /* peek_version: header only, no context */
    uint32_t major = 9, minor = 9;
    assert_int_equal(glow_bake_peek_version(img, size, &major, &minor), GLOW_OK);
    assert_int_equal(major, 1);
    assert_int_equal(minor, GLOW_BAKE_FORMAT_VERSION_MINOR);
    assert_int_equal(glow_bake_peek_version(p, 64, &major, &minor), GLOW_OK);
    assert_int_equal(minor, 7);
    put_u16(p + 4, 3);
    assert_int_equal(glow_bake_peek_version(p, 64, &major, &minor), GLOW_OK);
    assert_int_equal(major, 3);
    assert_int_equal(glow_bake_peek_version(img, 63, &major, &minor), GLOW_ERROR_TRUNCATED);
    assert_int_equal(glow_bake_peek_version(NULL, 0, &major, &minor), GLOW_ERROR_TRUNCATED);
    p[1] = 'X';
    assert_int_equal(glow_bake_peek_version(p, size, &major, &minor), GLOW_ERROR_BAD_MAGIC);
    free(p);
    free(img);
}

static void test_checksums(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    size_t size;
    unsigned char *img = write_bake(&tb, 0, &size);
    unsigned char *p = malloc(size);
    /* a flipped bit in every section's payload */
    uint32_t n = u32_at(img + 12);
    for (uint32_t i = 0; i < n; i++) {
        memcpy(p, img, size);
        uint64_t off = u64_at(p + 64 + 32 * i + 8), sz = u64_at(p + 64 + 32 * i + 16);
        p[off + sz / 2] ^= 0x10;
        EXPECT_LOAD_MSG(p, size, GLOW_ERROR_BAD_CHECKSUM, "CRC-32 mismatch");
    }
    memcpy(p, img, size);
    p[24] ^= 1; /* header flags */
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_BAD_CHECKSUM, "header CRC");
    memcpy(p, img, size);
    p[64 + 4] ^= 1; /* section table: META version */
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_BAD_CHECKSUM, "table CRC");
    memcpy(p, img, size);
    p[32] ^= 1; /* the header CRC itself */
    EXPECT_LOAD(p, size, GLOW_ERROR_BAD_CHECKSUM);
    /* padding between payloads is not covered by any CRC and may be anything */
    memcpy(p, img, size);
    uint64_t meta_end = u64_at(entry_ptr(p, GLOW_SECTION_META) + 8) + sizeof(glow_bake_meta);
    uint64_t matl_off = u64_at(entry_ptr(p, GLOW_SECTION_MATL) + 8);
    assert_true(matl_off == meta_end); /* 256 is aligned: no padding there; find one that has */
    uint64_t levl_end = u64_at(entry_ptr(p, GLOW_SECTION_LEVL) + 8) + 12;
    assert_int_equal(p[levl_end], 0);
    p[levl_end] = 0x5A;
    EXPECT_LOAD(p, size, GLOW_OK);
    free(p);
    free(img);
}

static void test_container_structure(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    size_t size;
    unsigned char *img = write_bake(&tb, 0, &size);
    unsigned char *p = malloc(size + 64);

    /* file_size field smaller than the data: trailing bytes */
    memcpy(p, img, size);
    p[size] = 0;
    EXPECT_LOAD_MSG(p, size + 1, GLOW_ERROR_CORRUPT_DATA, "header says");
    memcpy(p, img, size);
    put_u64(p + 16, size - 1);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_CORRUPT_DATA);
    /* file_size larger than the data: truncated */
    memcpy(p, img, size);
    put_u64(p + 16, size + 100);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_TRUNCATED);
    /* header_size */
    memcpy(p, img, size);
    put_u32(p + 8, 128);
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "header_size");
    /* section_count over the maximum, and a table running past the end */
    memcpy(p, img, size);
    put_u32(p + 12, GLOW_BAKE_MAX_SECTIONS + 1);
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "section_count");
    memcpy(p, img, size);
    put_u32(p + 12, 0xFFFFFFFFu);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_CORRUPT_DATA);
    /* unaligned offset */
    memcpy(p, img, size);
    put_u64(entry_ptr(p, GLOW_SECTION_NODE) + 8, u64_at(entry_ptr(p, GLOW_SECTION_NODE) + 8) + 4);
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "multiple of 64");
    /* overlapping sections */
    memcpy(p, img, size);
    put_u64(entry_ptr(p, GLOW_SECTION_NODE) + 8, u64_at(entry_ptr(p, GLOW_SECTION_SURF) + 8));
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "overlap");
    /* a section inside the header / table */
    memcpy(p, img, size);
    put_u64(entry_ptr(p, GLOW_SECTION_NODE) + 8, 64);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_CORRUPT_DATA);
    /* a section past the end (size and offset, including 64-bit wrap-around) */
    memcpy(p, img, size);
    put_u64(entry_ptr(p, GLOW_SECTION_GEOM) + 16, size);
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "past the end");
    memcpy(p, img, size);
    put_u64(entry_ptr(p, GLOW_SECTION_GEOM) + 16, UINT64_MAX - 63);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_CORRUPT_DATA);
    memcpy(p, img, size);
    put_u64(entry_ptr(p, GLOW_SECTION_GEOM) + 8, UINT64_MAX - 63);
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_ERROR_CORRUPT_DATA);
    /* duplicate fourcc */
    memcpy(p, img, size);
    put_u32(entry_ptr(p, GLOW_SECTION_GEOM), GLOW_SECTION_MATL);
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "duplicate section 'MATL'");
    /* section layout version */
    memcpy(p, img, size);
    put_u32(entry_ptr(p, GLOW_SECTION_CACH) + 4, 2);
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "layout version");
    /* missing required sections (renamed to an unknown fourcc, which is otherwise skipped) */
    static const uint32_t required[] = {GLOW_SECTION_META, GLOW_SECTION_SURF, GLOW_SECTION_NODE, GLOW_SECTION_LEVL,
                                        GLOW_SECTION_CACH, GLOW_SECTION_LINK, GLOW_SECTION_MATL, GLOW_SECTION_GRID,
                                        GLOW_SECTION_LMAP};
    for (size_t i = 0; i < sizeof required / sizeof required[0]; i++) {
        memcpy(p, img, size);
        put_u32(entry_ptr(p, required[i]), GLOW_FOURCC('X', 'X', 'X', (int)('0' + i)));
        refresh_crcs(p, size);
        char needle[32];
        snprintf(needle, sizeof needle, "'%.4s'", (const char *)&required[i]);
        EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, needle);
    }
    /* GEOM is optional */
    memcpy(p, img, size);
    put_u32(entry_ptr(p, GLOW_SECTION_GEOM), GLOW_FOURCC('X', 'G', 'E', 'O'));
    refresh_crcs(p, size);
    EXPECT_LOAD(p, size, GLOW_OK);
    /* the META section must be exactly one glow_bake_meta */
    memcpy(p, img, size);
    put_u64(entry_ptr(p, GLOW_SECTION_META) + 16, 128);
    refresh_crcs(p, size);
    EXPECT_LOAD_MSG(p, size, GLOW_ERROR_CORRUPT_DATA, "'META'");
    free(p);
    free(img);
}

/* ------------------------------------------------------------------------------ META and sizes */
static void test_meta_counts(void **state) {
    (void)state;
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "node_count", b->meta.surfel_count = 3);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "surfel_count is 0", b->meta.surfel_count = 0);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "node_count", b->meta.node_count = 5);
    /* LINK node indices are 24 bits: node_count <= 2^24 (it is odd, so 2^24 - 1 at most in practice) */
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "node_count 16777217 exceeds 16777216",
                   b->meta.surfel_count = (1u << 23) + 1u; b->meta.node_count = (1u << 24) + 1u);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'SURF'", /* within the limit: fails later, on sizes */
                   b->meta.surfel_count = 1u << 23; b->meta.node_count = (1u << 24) - 1u);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "level_count", b->meta.level_count = 0);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "level_count", b->meta.level_count = 4);
    {   /* LEVL size disagreeing with META.level_count (patched in the image, CRCs refreshed) */
        test_bake tb;
        build_golden(&tb);
        size_t size;
        unsigned char *img = write_bake(&tb, 0, &size);
        put_u32(payload_ptr(img, GLOW_SECTION_META) + offsetof(glow_bake_meta, level_count), 3);
        refresh_crcs(img, size);
        EXPECT_LOAD_MSG(img, size, GLOW_ERROR_CORRUPT_DATA, "'LEVL'");
        free(img);
    }
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "cache_count", b->meta.cache_count = 3);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'CACH'", b->meta.cache_count = 3; b->meta.grid_cache_count = 2);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "link_blocks_per_cache", b->meta.links_per_cache = 17);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'LINK'", b->meta.links_per_cache = 17;
                   b->meta.link_blocks_per_cache = 2);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'MATL'", b->meta.material_count = 3);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'GEOM'", b->meta.triangle_count = 1);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'GRID'", b->meta.grid_dims[0] = 2);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "overflow", b->meta.grid_dims[0] = 0xFFFFFFFFu;
                   b->meta.grid_dims[1] = 0xFFFFFFFFu; b->meta.grid_dims[2] = 0xFFFFFFFFu);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'LMAP'", b->meta.lightmap_width = 0x80000000u;
                   b->meta.lightmap_height = 0x80000000u);
    /* 1.7: pages; LMAP then holds lightmap_count pages, and more than GLOW_BAKE_MAX_LIGHTMAP_PAGES are refused */
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'LMAP'", b->meta.lightmap_count = 2);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "lightmap_count", b->meta.lightmap_count = GLOW_BAKE_MAX_LIGHTMAP_PAGES + 1u);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "sh_bands", b->meta.sh_bands = 0);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "sh_bands", b->meta.sh_bands = 0x10000u);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "grid_spacing", b->meta.grid_spacing = 0.0f);
    /* conditional sections */
    EXPECT_PATCHED(NO_GRID, GLOW_ERROR_CORRUPT_DATA, "'GRID'", (void)b);
    EXPECT_PATCHED(NO_LMAP, GLOW_ERROR_CORRUPT_DATA, "'LMAP'", (void)b);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "'SHLK'", b->meta.link_kind |= GLOW_LINK_KIND_FULL_SH);
    EXPECT_PATCHED(WITH_SHLK, GLOW_ERROR_CORRUPT_DATA, "'SHLK'", (void)b);
    EXPECT_PATCHED(WITH_SHLK, GLOW_ERROR_CORRUPT_DATA, "'SHLK'", b->meta.link_kind |= GLOW_LINK_KIND_FULL_SH;
                   b->meta.sh_bands = 3);
    /* non-finite META floats */
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "bounds", b->meta.bounds_min[1] = NAN);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "bounds", b->meta.bounds_max[2] = INFINITY);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "surfel_area", b->meta.surfel_area = NAN);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "scene_area", b->meta.scene_area = -1.0);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "surfel_area", b->meta.surfel_area = 0.0f);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "factor_scale", b->meta.factor_scale = INFINITY);
    EXPECT_PATCHED(0, GLOW_ERROR_CORRUPT_DATA, "grid origin", b->meta.grid_origin[0] = NAN);
}

/* ------------------------------------------------------------------------------ indices */
static void test_out_of_range(void **state) {
    (void)state;
    const glow_result R = GLOW_ERROR_OUT_OF_RANGE;
    /* nodes */
    EXPECT_PATCHED(0, R, "node 2: child 3 out of range", b->node[2].child[0] = 3);
    EXPECT_PATCHED(0, R, "parent 7 out of range", b->node[1].parent = 7);
    EXPECT_PATCHED(0, R, "not in a lower level", b->node[2].child[1] = 2);
    EXPECT_PATCHED(0, R, "two distinct children", b->node[2].child[1] = 0);
    EXPECT_PATCHED(0, R, "two distinct children", b->node[2].child[1] = GLOW_NODE_NONE);
    EXPECT_PATCHED(0, R, "is a leaf", b->node[0].child[0] = 1);
    EXPECT_PATCHED(0, R, "root node", b->node[2].parent = 0);
    EXPECT_PATCHED(0, R, "node 2: child 1 names parent", b->node[1].parent = GLOW_NODE_NONE);
    EXPECT_PATCHED(0, R, "names parent", b->node[1].parent = 1);
    EXPECT_PATCHED(0, R, "LEVL", b->levl[1] = 1);
    EXPECT_PATCHED(0, R, "LEVL", b->levl[0] = 1);
    EXPECT_PATCHED(0, R, "LEVL", b->levl[2] = 2);
    EXPECT_PATCHED(0, R, "LEVL: level start 3 (3) < level start 2 (4)", b->meta.level_count = 3; b->levl[2] = 4;
                   b->levl[3] = 3);
    EXPECT_PATCHED(0, GLOW_OK, NULL, b->meta.level_count = 3; b->levl[2] = 2; b->levl[3] = 3); /* an empty level */
    /* surfels */
    EXPECT_PATCHED(0, R, "surfel 1: material 2", b->surf[1].material = 2);
    EXPECT_PATCHED(0, R, "feedback cache 2", b->surf[0].feedback = 2);
    EXPECT_PATCHED(0, R, "triangle 2", b->surf[1].triangle = 2);
    /* caches */
    EXPECT_PATCHED(0, R, "unknown kind 3", b->cache[1].kind = 3);
    EXPECT_PATCHED(0, R, "kind 2", b->cache[0].kind = GLOW_CACHE_KIND_LIGHTMAP);
    EXPECT_PATCHED(0, R, "texel/cell 2", b->cache[0].texel = 2);
    EXPECT_PATCHED(0, R, "texel/cell 4", b->cache[1].texel = 4);
    /* maps */
    EXPECT_PATCHED(0, R, "GRID entry 1", b->grid[1] = 2);
    EXPECT_PATCHED(0, R, "GRID entry 0", b->grid[0] = 1u | GLOW_MAP_COPY_BIT); /* a lightmap cache */
    EXPECT_PATCHED(0, R, "LMAP entry 2", b->lmap[2] = 0x7FFFFFFFu);
    EXPECT_PATCHED(0, R, "LMAP entry 0", b->lmap[0] = 0); /* a grid cache */
    /* links */
    EXPECT_PATCHED(0, R, "LINK cache 1 link 1: node 3 out of range", b->link[1].node_dir[1] = 0xBF000003u);
    EXPECT_PATCHED(0, R, "link 15: node 16777215 out of range", b->link[0].node_dir[15] = 0xFFFFFFFFu);
    /* a bad index under direction bits: only the low 24 bits are the node */
    EXPECT_PATCHED(0, R, "LINK cache 0 link 0: node 3 out of range", b->link[0].node_dir[0] = 0xFF000003u);
    EXPECT_PATCHED(0, R, "LINK cache 1 link 0: node 65538 out of range", b->link[1].node_dir[0] = 0x80010002u);
    /* ...and high bits alone are direction, not an index: valid (also in unused lanes) */
    EXPECT_PATCHED(0, GLOW_OK, NULL, b->link[0].node_dir[0] = 0xFF000002u; b->link[0].node_dir[9] = 0xFF000000u;
                   b->link[1].dir_lo[9] = 0xFFFF);
    EXPECT_PATCHED(WITH_SHLK, R, "SHLK block 1", b->meta.link_kind |= GLOW_LINK_KIND_FULL_SH;
                   put_u32(b->shlk + SHLK_BLOCK + 8, 3));
    /* geometry */
    EXPECT_PATCHED(0, R, "GEOM triangle 1: material 2", b->tri[1].material = 2);
}

static void test_non_finite(void **state) {
    (void)state;
    const glow_result C = GLOW_ERROR_CORRUPT_DATA;
    EXPECT_PATCHED(0, C, "surfel 1", b->surf[1].position[0] = NAN);
    EXPECT_PATCHED(0, C, "surfel 0", b->surf[0].normal[2] = -INFINITY);
    EXPECT_PATCHED(0, C, "surfel 1", b->surf[1].albedo[1] = NAN);
    EXPECT_PATCHED(0, C, "surfel 1", b->surf[1].emission[2] = INFINITY);
    EXPECT_PATCHED(0, C, "node 2", b->node[2].area = NAN);
    EXPECT_PATCHED(0, C, "node 0", b->node[0].area = -1.0f);
    EXPECT_PATCHED(0, C, "node 1", b->node[1].area = 0.0f); /* 1/(pi*area) must stay finite */
    EXPECT_PATCHED(0, C, "cache 1", b->cache[1].position[1] = NAN);
    EXPECT_PATCHED(0, C, "material 1", b->mat[1].emission[0] = INFINITY);
    EXPECT_PATCHED(0, C, "material 0: name", memset(b->mat[0].name, 'a', sizeof b->mat[0].name));
    EXPECT_PATCHED(0, C, "GEOM triangle 0", b->tri[0].position[7] = NAN);
    /* link halves: one_minus_cos finite in [0, 2]; unused lanes (j >= links_per_cache) exactly 0 */
    EXPECT_PATCHED(0, C, "LINK cache 0 link 0: one_minus_cos", b->link[0].one_minus_cos[0] = 0x4001); /* > 2 */
    EXPECT_PATCHED(0, C, "LINK cache 0 link 0", b->link[0].one_minus_cos[0] = 0xB800); /* -0.5 */
    EXPECT_PATCHED(0, C, "LINK cache 0 link 0", b->link[0].one_minus_cos[0] = 0x8001); /* tiny negative */
    EXPECT_PATCHED(0, C, "LINK cache 0 link 1", b->link[0].one_minus_cos[1] = 0x7E00); /* NaN */
    EXPECT_PATCHED(0, C, "LINK cache 1 link 0", b->link[1].one_minus_cos[0] = 0x7C00); /* Inf */
    EXPECT_PATCHED(0, C, "LINK cache 1 link 1", b->link[1].one_minus_cos[1] = 0xFC00); /* -Inf */
    EXPECT_PATCHED(0, C, "LINK cache 1: unused lane 5 has one_minus_cos 1", b->link[1].one_minus_cos[5] = 0x3C00);
    EXPECT_PATCHED(0, C, "LINK cache 0: unused lane 15", b->link[0].one_minus_cos[15] = 0x0001); /* subnormal */
    /* links_per_cache 1: lane 1 becomes unused, and it carries a cone */
    EXPECT_PATCHED(0, C, "LINK cache 0: unused lane 1", b->meta.links_per_cache = 1);
    /* valid: the full sphere (2), a used lane that contributes nothing (0), -0 in an unused lane */
    EXPECT_PATCHED(0, GLOW_OK, NULL, b->link[0].one_minus_cos[0] = 0x4000; b->link[0].one_minus_cos[1] = 0;
                   b->link[1].one_minus_cos[3] = 0x8000);
    EXPECT_PATCHED(WITH_SHLK, C, "SHLK block 0: non-finite", b->meta.link_kind |= GLOW_LINK_KIND_FULL_SH;
                   put_u16(b->shlk + 64 + 2 * 37, 0xFC00));
    /* finite but outside the domain the solver assumes (issue 15, D2: such bakes loaded, with their
     * checksums resealed, and drove updates to 5e14 W/m² and then NaN) */
    EXPECT_PATCHED(0, C, "surfel 0: normal", b->surf[0].normal[1] = 2.0f);
    EXPECT_PATCHED(0, C, "surfel 1: normal", b->surf[1].normal[1] = 0.5f);
    EXPECT_PATCHED(0, C, "surfel 0: albedo", b->surf[0].albedo[0] = 1.5f);
    EXPECT_PATCHED(0, C, "surfel 1: albedo", b->surf[1].albedo[2] = -0.1f);
    EXPECT_PATCHED(0, C, "surfel 1: albedo", b->surf[1].emission[0] = -1.0f);
    EXPECT_PATCHED(0, C, "surfel 1: albedo", b->surf[1].emission[1] = 3e38f);
    EXPECT_PATCHED(0, C, "material 1: albedo", b->mat[1].albedo[0] = 2.0f);
    EXPECT_PATCHED(0, C, "node 0: area", b->node[0].area = 8.8e-43f);
    EXPECT_PATCHED(0, C, "node 2: area", b->node[2].area = 5.0f);
    /* 1.3: leaves may differ in area (an adapted surfel density), within 16x of surfel_area either
     * way and summing to scene_area */
    EXPECT_PATCHED(0, GLOW_OK, NULL, b->node[0].area = 0.3f; b->node[1].area = 0.7f);
    EXPECT_PATCHED(0, C, "leaves' areas sum to 0.8", b->node[0].area = 0.3f; b->node[1].area = 0.5f; b->node[2].area = 0.8f);
    EXPECT_PATCHED(0, C, "node 1: area 9 of a leaf is not within 16x", b->node[1].area = 9.0f);
    EXPECT_PATCHED(0, C, "node 0: area 0.03 of a leaf is not within 16x", b->node[0].area = 0.03f);
    EXPECT_PATCHED(0, C, "factor_scale", b->meta.factor_scale = 1.0f);
    /* the edges of the domain stay valid */
    EXPECT_PATCHED(0, GLOW_OK, NULL, b->surf[0].albedo[0] = 1.0f; b->surf[1].albedo[2] = 0.0f;
                   b->surf[0].normal[1] = 1.005f);
}

/* ------------------------------------------------------------------------------ context, results */
typedef struct count_alloc {
    int allocs, frees, fail_after;
} count_alloc;
static void *ca_alloc(void *user, size_t size, size_t align) {
    count_alloc *c = user;
    if (c->fail_after >= 0 && c->allocs >= c->fail_after) return NULL;
    c->allocs++;
    size_t rounded = (size + align - 1) / align * align;
    return aligned_alloc(align, rounded);
}
static void ca_free(void *user, void *p) {
    count_alloc *c = user;
    c->frees++;
    free(p);
}

static void test_context_and_results(void **state) {
    (void)state;
    test_log log;
    memset(&log, 0, sizeof log);
    glow_context_desc d;
    memset(&d, 0, sizeof d);
    glow_context *ctx = (glow_context *)(uintptr_t)1;
    assert_int_equal(glow_context_create(NULL, &ctx), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(ctx);
    assert_int_equal(glow_context_create(&d, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    d.logger.log = test_logger;
    d.logger.user = &log;
    d.api_version = 10000u; /* 1.0.0 */
    assert_int_equal(glow_context_create(&d, &ctx), GLOW_ERROR_VERSION_MISMATCH);
    assert_int_equal(log.last_code, GLOW_ERROR_VERSION_MISMATCH);
    assert_null(ctx);
    d.api_version = GLOW_VERSION;
    count_alloc ca = {0, 0, -1};
    d.allocator.alloc = ca_alloc;
    d.allocator.user = &ca;
    assert_int_equal(glow_context_create(&d, &ctx), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(log.last_code, GLOW_ERROR_INVALID_ARGUMENT);
    d.allocator.free = ca_free;
    assert_int_equal(glow_context_create(&d, &ctx), GLOW_OK);

    test_bake tb;
    build_golden(&tb);
    size_t size;
    unsigned char *img = write_bake(&tb, 0, &size);
    glow_bake *bake = NULL;
    assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_OK);
    assert_int_equal(ca.allocs, 2);
    glow_bake_destroy(bake);
    assert_int_equal(ca.frees, 1);
    /* out of memory while loading */
    ca.fail_after = ca.allocs;
    log.count = 0;
    assert_int_equal(glow_bake_load(ctx, img, size, &bake), GLOW_ERROR_OUT_OF_MEMORY);
    assert_null(bake);
    assert_int_equal(log.last_code, GLOW_ERROR_OUT_OF_MEMORY);
    /* NULL arguments */
    assert_int_equal(glow_bake_load(ctx, NULL, size, &bake), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(log.last_code, GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_bake_load(NULL, img, size, &bake), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_bake_load(ctx, img, size, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_bake_load_file(ctx, NULL, &bake), GLOW_ERROR_INVALID_ARGUMENT);
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(NULL, &info), GLOW_ERROR_INVALID_ARGUMENT);
    glow_context_destroy(ctx);
    assert_int_equal(ca.allocs, ca.frees);
    free(img);

    /* a context with live allocations refuses to be destroyed (logged as an error), then goes */
    glow_context *c2 = make_ctx(&log);
    void *leak = glow__ctx_alloc(c2, 100, 64);
    assert_non_null(leak);
    assert_true(((uintptr_t)leak % 64) == 0);
    assert_null(glow__ctx_alloc(c2, 100, 48)); /* not a power of two */
    glow__ctx_free(c2, leak);
    leak = glow__ctx_alloc(c2, 1, 0);
    log.count = 0;
    glow_context_destroy(c2); /* refused: the block is live */
    assert_int_equal(log.count, 1);
    assert_int_equal(log.last_level, GLOW_LOG_ERROR);
    assert_int_equal(log.last_code, GLOW_ERROR_INVALID_OPERATION);
    glow__ctx_free(c2, leak); /* the context still works */
    log.count = 0;
    glow_context_destroy(c2);
    assert_int_equal(log.count, 0);

    /* result strings name their code */
    static const struct { glow_result r; const char *name; } codes[] = {
        {GLOW_OK, "GLOW_OK"},
        {GLOW_ERROR_INVALID_ARGUMENT, "GLOW_ERROR_INVALID_ARGUMENT"},
        {GLOW_ERROR_INVALID_OPERATION, "GLOW_ERROR_INVALID_OPERATION"},
        {GLOW_ERROR_OUT_OF_MEMORY, "GLOW_ERROR_OUT_OF_MEMORY"},
        {GLOW_ERROR_IO, "GLOW_ERROR_IO"},
        {GLOW_ERROR_CORRUPT_DATA, "GLOW_ERROR_CORRUPT_DATA"},
        {GLOW_ERROR_VERSION_MISMATCH, "GLOW_ERROR_VERSION_MISMATCH"},
        {GLOW_ERROR_UNSUPPORTED, "GLOW_ERROR_UNSUPPORTED"},
        {GLOW_ERROR_HOST_CALLBACK, "GLOW_ERROR_HOST_CALLBACK"},
        {GLOW_ERROR_TRUNCATED, "GLOW_ERROR_TRUNCATED"},
        {GLOW_ERROR_BAD_MAGIC, "GLOW_ERROR_BAD_MAGIC"},
        {GLOW_ERROR_BAD_CHECKSUM, "GLOW_ERROR_BAD_CHECKSUM"},
        {GLOW_ERROR_OUT_OF_RANGE, "GLOW_ERROR_OUT_OF_RANGE"},
        {GLOW_ERROR_EMPTY_SCENE, "GLOW_ERROR_EMPTY_SCENE"},
    };
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        const char *s = glow_result_string(codes[i].r);
        size_t n = strlen(codes[i].name);
        assert_int_equal(strncmp(s, codes[i].name, n), 0);
        assert_int_equal(s[n], ':');
    }
    assert_non_null(glow_result_string((glow_result)999));
}

/* ------------------------------------------------------------------------------ codecs */
static void test_crc32_vs_zlib(void **state) {
    (void)state;
    enum { N = 1 << 16 };
    unsigned char *buf = malloc(N + 16);
    for (int i = 0; i < N + 16; i++) buf[i] = (unsigned char)rng();
    assert_int_equal(glow__crc32(0, "123456789", 9), 0xCBF43926u); /* the CRC-32 check value */
    assert_int_equal(glow__crc32(0, buf, 0), 0);
    for (int t = 0; t < 300; t++) {
        size_t len = t < 40 ? (size_t)t : (size_t)(rng() % N);
        size_t off = rng() % 16; /* misaligned starts */
        uint32_t seed = t % 3 == 0 ? 0u : rng();
        uLong ref = crc32((uLong)seed, buf + off, (uInt)len);
        assert_int_equal(glow__crc32(seed, buf + off, len), (uint32_t)ref);
    }
    /* chaining = one call */
    uint32_t a = glow__crc32(0, buf, 1000);
    a = glow__crc32(a, buf + 1000, 3333);
    assert_int_equal(a, (uint32_t)crc32(0L, buf, 4333));
    free(buf);
}

static float bits_to_float(uint32_t x) { float f; memcpy(&f, &x, 4); return f; }
static uint32_t float_to_bits(float f) { uint32_t x; memcpy(&x, &f, 4); return x; }

static void test_half(void **state) {
    (void)state;
    /* every non-NaN pattern survives half -> float -> half */
    int nan_count = 0;
    for (uint32_t h = 0; h < 65536u; h++) {
        float f = glow__half_to_float((uint16_t)h);
        if ((h & 0x7C00u) == 0x7C00u && (h & 0x3FFu)) {
            assert_true(isnan(f));
            assert_true(isnan(glow__half_to_float(glow__half_from_float(f))));
            nan_count++;
            continue;
        }
        if (glow__half_from_float(f) != h) fail_msg("half 0x%04x -> %a -> 0x%04x", h, (double)f, glow__half_from_float(f));
    }
    assert_int_equal(nan_count, 2 * 1023);
    /* values computed by hand */
    assert_true(glow__half_to_float(0x3C00) == 1.0f);
    assert_true(glow__half_to_float(0xC000) == -2.0f);
    assert_true(glow__half_to_float(0x7BFF) == 65504.0f);
    assert_true(glow__half_to_float(0x0001) == ldexpf(1.0f, -24));
    assert_true(glow__half_to_float(0x03FF) == ldexpf(1023.0f, -24));
    assert_true(isinf(glow__half_to_float(0xFC00)) && glow__half_to_float(0xFC00) < 0);
    assert_int_equal(glow__half_from_float(65519.0f), 0x7BFF);
    assert_int_equal(glow__half_from_float(65520.0f), 0x7C00); /* tie -> even -> overflow */
    assert_int_equal(glow__half_from_float(1e10f), 0x7C00);
    assert_int_equal(glow__half_from_float(-INFINITY), 0xFC00);
    assert_int_equal(glow__half_from_float(ldexpf(1.0f, -25)), 0x0000);           /* tie -> even 0 */
    assert_int_equal(glow__half_from_float(ldexpf(1.0f, -25) * 1.0000001f), 0x0001);
    assert_int_equal(glow__half_from_float(ldexpf(3.0f, -25)), 0x0002);           /* 1.5 ulp -> 2 */
    assert_int_equal(glow__half_from_float(ldexpf(1.0f, -26)), 0x0000);
    assert_int_equal(glow__half_from_float(-0.0f), 0x8000);
    assert_int_equal(glow__half_from_float(1.0f + ldexpf(1.0f, -11)), 0x3C00);   /* tie -> even */
    assert_int_equal(glow__half_from_float(1.0f + ldexpf(3.0f, -11)), 0x3C02);   /* tie -> even (up) */
    assert_int_equal(glow__half_from_float(ldexpf(2047.0f, -25)), 0x0400);       /* rounds up into normals */
    assert_true(isnan(glow__half_to_float(glow__half_from_float(NAN))));
    /* round to nearest: no other half is closer (ties to even), on random floats of all ranges */
    for (int t = 0; t < 200000; t++) {
        float f = bits_to_float(rng());
        if (isnan(f)) continue;
        if (t & 1) f = ldexpf(rngf(), (int)(rng() % 50) - 30) * ((rng() & 1) ? 1.0f : -1.0f);
        uint16_t h = glow__half_from_float(f);
        double got = glow__half_to_float(h);
        double af = fabs((double)f);
        if (af >= 65520.0) {
            assert_true(isinf(got));
            continue;
        }
        double err = fabs(got - f);
        /* neighbours in magnitude */
        uint16_t mag = h & 0x7FFFu;
        for (int dn = -1; dn <= 1; dn += 2) {
            int nb = (int)mag + dn;
            if (nb < 0 || nb > 0x7BFF) continue;
            double alt = glow__half_to_float((uint16_t)nb);
            double aerr = fabs(alt - af);
            if (aerr < err) fail_msg("%a -> 0x%04x, but 0x%04x is closer", (double)f, h, nb);
            if (aerr == err && (mag & 1u)) fail_msg("%a -> odd 0x%04x on a tie", (double)f, h);
        }
        if (f != 0.0f) assert_int_equal(h & 0x8000u, (float_to_bits(f) >> 16) & 0x8000u);
    }
}

static double angle_deg(const float a[3], const double b[3]) {
    double la = sqrt((double)a[0] * a[0] + (double)a[1] * a[1] + (double)a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    double s = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    (void)la;
    (void)lb;
    return atan2(s, d) * (180.0 / 3.14159265358979323846);
}

static void test_oct(void **state) {
    (void)state;
    double max_err = 0.0;
    for (int t = 0; t < 200000; t++) {
        double v[3];
        if (t < 26) { /* axes, edge and corner diagonals */
            int a = t < 13 ? t : t + 1; /* skip (0,0,0) */
            v[0] = a % 3 - 1;
            v[1] = a / 3 % 3 - 1;
            v[2] = a / 9 - 1;
        } else { /* uniform on the sphere */
            double z = 2.0 * rngf() - 1.0, phi = 2.0 * 3.14159265358979323846 * rngf(), r = sqrt(1.0 - z * z);
            v[0] = r * cos(phi);
            v[1] = r * sin(phi);
            v[2] = z;
        }
        double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; k++) v[k] /= l;
        float vf[3] = {(float)v[0], (float)v[1], (float)v[2]};
        float out[3], out2[3];
        uint32_t packed = glow__oct_encode(vf);
        glow__oct_decode(packed, out);
        int16_t u, w;
        glow__oct_encode2(vf, &u, &w);
        assert_int_equal((uint16_t)u, packed & 0xFFFFu);
        assert_int_equal((uint16_t)w, packed >> 16);
        glow__oct_decode2(u, w, out2);
        assert_memory_equal(out, out2, sizeof out);
        double len = sqrt((double)out[0] * out[0] + (double)out[1] * out[1] + (double)out[2] * out[2]);
        assert_true(fabs(len - 1.0) < 1e-5);
        double e = angle_deg(out, v);
        if (e > max_err) max_err = e;
    }
    print_message("oct max angular error %.5f deg\n", max_err);
    assert_true(max_err < 0.01);  /* the requirement */
    assert_true(max_err < 0.003); /* the "precise" encoder: plain rounding gives ~0.004, floor ~0.007 */
    /* x in the low 16 bits */
    float px[3] = {1, 0, 0}, py[3] = {0, 1, 0}, nz[3] = {0, 0, -1}, zero[3] = {0, 0, 0}, bad[3] = {NAN, 0, 1};
    assert_int_equal(glow__oct_encode(px), 0x00007FFFu);
    assert_int_equal(glow__oct_encode(py), OCT_UP);
    assert_int_equal(glow__oct_encode(zero), 0u);
    assert_int_equal(glow__oct_encode(bad), 0u);
    float out[3];
    glow__oct_decode(glow__oct_encode(nz), out);
    assert_true(out[2] < -0.99999f);
    glow__oct_decode(0x80000000u, out); /* v = -32768 reads as -1 */
    assert_true(out[0] == 0.0f && out[1] == -1.0f && out[2] == 0.0f);
    glow__oct_decode(0x00008000u, out); /* u = -32768 */
    assert_true(out[0] == -1.0f && out[1] == 0.0f && out[2] == 0.0f);
    glow__oct_decode(0u, out);
    assert_true(out[2] == 1.0f);
}

/* Direction of 12-bit oct (u, v), computed here in double from the definition, independently of
 * the codec: s = q * 2/4095 - 1, fold the lower hemisphere, normalise. */
static void oct12_ref(uint32_t u, uint32_t v, double out[3]) {
    double x = u * (2.0 / 4095.0) - 1.0, y = v * (2.0 / 4095.0) - 1.0, z = 1.0 - fabs(x) - fabs(y);
    if (z < 0.0) {
        double t = x;
        x = (1.0 - fabs(y)) * (t >= 0.0 ? 1.0 : -1.0);
        y = (1.0 - fabs(t)) * (y >= 0.0 ? 1.0 : -1.0);
    }
    double l = sqrt(x * x + y * y + z * z);
    out[0] = x / l;
    out[1] = y / l;
    out[2] = z / l;
}

static double angle_dd(const double a[3], const double b[3]) {
    double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    double s = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    return atan2(s, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * (180.0 / 3.14159265358979323846);
}

static void test_oct12(void **state) {
    (void)state;
    double max_err = 0.0, max_round_err = 0.0;
    for (int t = 0; t < 200000; t++) {
        double v[3];
        if (t < 26) { /* axes, edge and corner diagonals */
            int a = t < 13 ? t : t + 1;
            v[0] = a % 3 - 1;
            v[1] = a / 3 % 3 - 1;
            v[2] = a / 9 - 1;
        } else {
            double z = 2.0 * rngf() - 1.0, phi = 2.0 * 3.14159265358979323846 * rngf(), r = sqrt(1.0 - z * z);
            v[0] = r * cos(phi);
            v[1] = r * sin(phi);
            v[2] = z;
        }
        /* The encoder's input is vf; errors are measured against vf itself (in double). vf is
         * normalised in float arithmetic on purpose: GCC 12.2 -O2 (SLP vectorizer) was seen to
         * read (double)vf[k] as the unrounded double when vf[k] = (float)(double expr). */
        float vf[3] = {(float)v[0], (float)v[1], (float)v[2]};
        float lf = sqrtf(vf[0] * vf[0] + vf[1] * vf[1] + vf[2] * vf[2]);
        for (int k = 0; k < 3; k++) vf[k] /= lf;
        double l = sqrt((double)vf[0] * vf[0] + (double)vf[1] * vf[1] + (double)vf[2] * vf[2]);
        for (int k = 0; k < 3; k++) v[k] = vf[k] / l;
        uint32_t u, w;
        glow__oct_encode12(vf, &u, &w);
        assert_true(u <= GLOW_LINK_DIR_MAX && w <= GLOW_LINK_DIR_MAX);
        float out[3];
        glow__oct_decode12(u, w, out);
        double len = sqrt((double)out[0] * out[0] + (double)out[1] * out[1] + (double)out[2] * out[2]);
        assert_true(fabs(len - 1.0) < 1e-5);
        double ref[3];
        oct12_ref(u, w, ref);
        double outd[3] = {out[0], out[1], out[2]};
        assert_true(angle_dd(outd, ref) < 1e-3); /* the float decoder agrees with the definition */
        double e = angle_deg(out, v);
        if (e > max_err) max_err = e;
        /* never worse than rounding each coordinate to the nearest step */
        double px = v[0], py = v[1], pz = v[2], l1 = fabs(px) + fabs(py) + fabs(pz);
        px /= l1;
        py /= l1;
        if (pz < 0.0) {
            double tx = (1.0 - fabs(py)) * (px >= 0.0 ? 1.0 : -1.0), ty = (1.0 - fabs(px)) * (py >= 0.0 ? 1.0 : -1.0);
            px = tx;
            py = ty;
        }
        double ru = floor((px + 1.0) * 2047.5 + 0.5), rv = floor((py + 1.0) * 2047.5 + 0.5);
        if (ru > 4095.0) ru = 4095.0;
        if (rv > 4095.0) rv = 4095.0;
        double rd[3];
        oct12_ref((uint32_t)ru, (uint32_t)rv, rd);
        double er = angle_dd(rd, v);
        if (er > max_round_err) max_round_err = er;
        oct12_ref(u, w, ref);
        if (!(angle_dd(ref, v) <= er + 1e-9))
            fail_msg("oct12 of (%a, %a, %a): (%u, %u) is %.9g deg off, plain rounding (%g, %g) only %.9g deg",
                     (double)vf[0], (double)vf[1], (double)vf[2], u, w, angle_dd(ref, v), ru, rv, er);
    }
    print_message("oct12 max angular error %.5f deg (plain rounding: %.5f deg)\n", max_err, max_round_err);
    assert_true(max_err < 0.06);
    assert_true(max_err < max_round_err);
    /* hand-computed codes */
    float px[3] = {1, 0, 0}, pz[3] = {0, 0, 1}, nz[3] = {0, 0, -1}, zero[3] = {0, 0, 0}, bad[3] = {NAN, 0, 1};
    uint32_t u, w;
    glow__oct_encode12(px, &u, &w);
    assert_int_equal(u, 4095);
    assert_true(w == 2047 || w == 2048); /* y = -+1/4095: both half a step from 0 */
    glow__oct_encode12(pz, &u, &w);
    assert_true((u == 2047 || u == 2048) && (w == 2047 || w == 2048));
    uint32_t zu, zw;
    glow__oct_encode12(zero, &zu, &zw); /* degenerate input: +z */
    assert_int_equal(zu, u);
    assert_int_equal(zw, w);
    glow__oct_encode12(bad, &zu, &zw);
    assert_int_equal(zu, u);
    assert_int_equal(zw, w);
    glow__oct_encode12(nz, &u, &w); /* the lower pole is any corner */
    assert_true((u == 0 || u == 4095) && (w == 0 || w == 4095));
    float out[3];
    glow__oct_decode12(0, 0, out);
    assert_true(out[0] == 0.0f && out[1] == 0.0f && out[2] == -1.0f);
    glow__oct_decode12(4095, 4095, out);
    assert_true(out[2] == -1.0f);
    glow__oct_decode12(2048, 4095, out); /* (1/4095, 1): ~ +y */
    assert_true(out[1] > 0.9999999f && fabsf(out[0]) < 1e-6f && fabsf(out[2]) < 2.5e-4f);
    glow__oct_decode12(0x1000u | 2048u, 0xF000u | 4095u, out); /* bits above 12 are ignored */
    assert_true(out[1] > 0.9999999f);
    /* every code decodes to a unit vector (all u, every 5th v and both ends) */
    for (uint32_t a = 0; a <= 4095; a++)
        for (uint32_t c = 0; c <= 4095; c = c == 4095 ? 4096 : (c + 5 > 4095 ? 4095 : c + 5)) {
            glow__oct_decode12(a, c, out);
            float l2 = out[0] * out[0] + out[1] * out[1] + out[2] * out[2];
            if (!(fabsf(l2 - 1.0f) < 1e-5f)) fail_msg("oct12 (%u, %u) decodes to length^2 %g", a, c, (double)l2);
        }
}

/* The link packing helpers against hand-computed bit patterns. */
static void test_link_pack(void **state) {
    (void)state;
    glow_bake_link_block b;
    memset(&b, 0xAA, sizeof b);
    glow_bake_link_pack(&b, 3, 0x123456u, 0x3C00, 0xABCu, 0xDEFu);
    assert_int_equal(b.node_dir[3], 0xAB123456u);
    assert_int_equal(b.dir_lo[3], 0xDEFCu);
    assert_int_equal(b.one_minus_cos[3], 0x3C00);
    assert_int_equal(b.node_dir[2], 0xAAAAAAAAu); /* neighbours untouched */
    assert_int_equal(b.dir_lo[4], 0xAAAAu);
    uint32_t u, v;
    glow_bake_link_dir12(&b, 3, &u, &v);
    assert_int_equal(u, 0xABC);
    assert_int_equal(v, 0xDEF);
    assert_int_equal(glow_bake_link_node(&b, 3), 0x123456u);
    glow_bake_link_pack(&b, 15, GLOW_LINK_MAX_NODES - 1u, 0x4000, GLOW_LINK_DIR_MAX, 0);
    assert_int_equal(b.node_dir[15], 0xFFFFFFFFu);
    assert_int_equal(b.dir_lo[15], 0x000Fu);
    glow_bake_link_pack(&b, 0, 0, 0, 0, GLOW_LINK_DIR_MAX);
    assert_int_equal(b.node_dir[0], 0u);
    assert_int_equal(b.dir_lo[0], 0xFFF0u);
    /* random round trips */
    for (int t = 0; t < 100000; t++) {
        uint32_t lane = rng() % GLOW_LINK_BLOCK, node = rng() & GLOW_LINK_NODE_MASK;
        uint32_t du = rng() & 0xFFFu, dv = rng() & 0xFFFu;
        uint16_t omc = (uint16_t)(rng() & 0x7FFFu);
        glow_bake_link_pack(&b, lane, node, omc, du, dv);
        assert_int_equal(glow_bake_link_node(&b, lane), node);
        glow_bake_link_dir12(&b, lane, &u, &v);
        assert_int_equal(u, du);
        assert_int_equal(v, dv);
        assert_int_equal(b.one_minus_cos[lane], omc);
    }
    /* layout: 8 bytes per link */
    assert_int_equal(sizeof(glow_bake_link_block), 8 * GLOW_LINK_BLOCK);
}

/* ------------------------------------------------------------------------------ writer */
static void test_writer(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    size_t s1, s2;
    unsigned char *a = write_bake(&tb, WITH_SHLK | EXTRA_UNKNOWN, &s1);
    unsigned char *b = write_bake(&tb, WITH_SHLK | EXTRA_UNKNOWN, &s2);
    assert_int_equal(s1, s2);
    assert_memory_equal(a, b, s1); /* deterministic */

    /* layout, checked independently of the reader */
    assert_memory_equal(a, "GLOW", 4);
    uint32_t n = u32_at(a + 12);
    assert_int_equal(n, 12);
    assert_int_equal(u64_at(a + 16), s1);
    assert_int_equal(u32_at(a + 8), 64);
    assert_int_equal(u32_at(a + 28), (uint32_t)crc32(0L, a + 64, 32 * n));
    unsigned char h[64];
    memcpy(h, a, 64);
    put_u32(h + 32, 0);
    assert_int_equal(u32_at(a + 32), (uint32_t)crc32(0L, h, 64));
    for (int i = 0; i < 64; i++)
        if (i >= 36) assert_int_equal(a[i], 0); /* reserved */
    uint64_t prev_end = 64 + 32 * (uint64_t)n;
    for (uint32_t i = 0; i < n; i++) {
        const unsigned char *e = a + 64 + 32 * i;
        uint64_t off = u64_at(e + 8), sz = u64_at(e + 16);
        assert_int_equal(off % 64, 0);
        assert_true(off >= prev_end && off - prev_end < 64); /* table order, tightly packed */
        for (uint64_t k = prev_end; k < off; k++) assert_int_equal(a[k], 0);
        assert_int_equal(u32_at(e + 24), (uint32_t)crc32(0L, a + off, (uInt)sz));
        assert_int_equal(u32_at(e + 4), 1);
        assert_int_equal(u32_at(e + 28), 0);
        prev_end = off + sz;
    }
    assert_int_equal(prev_end, s1);
    assert_int_equal(find_entry(a, GLOW_FOURCC('Z', 'Z', 'Z', 'Z')), 8);
    assert_memory_equal(payload_ptr(a, GLOW_SECTION_SURF), tb.surf, sizeof tb.surf);
    free(a);
    free(b);

    /* bad arguments */
    glow__section_data s[70];
    uint32_t cnt = sections_of(&tb, 0, s);
    void *img = (void *)1;
    uint64_t size = 1;
    s[cnt] = s[1]; /* duplicate MATL */
    assert_int_equal(glow__bake_write_memory(s, cnt + 1, &img, &size), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(img);
    assert_int_equal(size, 0);
    for (uint32_t i = 0; i < 70; i++) s[i] = (glow__section_data){GLOW_FOURCC('A', 'A', i / 10, i % 10), 1, NULL, 0};
    assert_int_equal(glow__bake_write_memory(s, 65, &img, &size), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow__bake_write_memory(s, 64, &img, &size), GLOW_OK); /* 64 empty sections is fine */
    assert_int_equal(size, 64 + 64 * 32);
    free(img);
    s[3].size = 10; /* NULL data with a size */
    assert_int_equal(glow__bake_write_memory(s, 4, &img, &size), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow__bake_write_memory(s, 4, NULL, &size), GLOW_ERROR_INVALID_ARGUMENT);
}

/* ------------------------------------------------------------------------------ files */
static char tmpdir[256];

static int count_tmp_files(const char *dir) {
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, ".tmp.")) n++;
    closedir(d);
    return n;
}

static long file_size_of(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

typedef struct pc_log_capture {
    int count;
    char last[1024];
} pc_log_capture;
static void pc_log(void *user, glow_log_level level, const char *message) {
    pc_log_capture *c = user;
    (void)level;
    c->count++;
    snprintf(c->last, sizeof c->last, "%s", message);
}

static void test_file_round_trip(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    glow__section_data s[16];
    uint32_t n = sections_of(&tb, 0, s);
    char path[512];
    snprintf(path, sizeof path, "%s/scene.glow", tmpdir);
    pc_log_capture cap = {0, ""};
    glow__log log = {pc_log, &cap, "", 0};
    uint64_t written = 0;
    assert_int_equal(glow__bake_write_file(path, s, n, &log, &written), GLOW_OK);
    assert_int_equal(cap.count, 0);
    assert_int_equal(file_size_of(path), (long)written);
    assert_int_equal(count_tmp_files(tmpdir), 0);

    test_log tl;
    glow_context *ctx = make_ctx(&tl);
    glow_bake *bake = NULL;
    assert_int_equal(glow_bake_load_file(ctx, path, &bake), GLOW_OK);
    check_golden_contents(bake, GLOW_BAKE_FORMAT_VERSION_MINOR);
    glow_bake_destroy(bake);

    /* same bytes as the in-memory writer */
    void *img;
    uint64_t size;
    assert_int_equal(glow__bake_write_memory(s, n, &img, &size), GLOW_OK);
    FILE *f = fopen(path, "rb");
    unsigned char *disk = malloc(size);
    assert_int_equal(fread(disk, 1, size, f), size);
    fclose(f);
    assert_memory_equal(disk, img, size);
    free(disk);

    /* load_file failures carry the path */
    char missing[512];
    snprintf(missing, sizeof missing, "%s/missing.glow", tmpdir);
    assert_int_equal(glow_bake_load_file(ctx, missing, &bake), GLOW_ERROR_IO);
    assert_null(bake);
    assert_int_equal(tl.last_code, GLOW_ERROR_IO);
    assert_non_null(strstr(tl.last_message, missing));
    assert_int_equal(glow_bake_load_file(ctx, tmpdir, &bake), GLOW_ERROR_IO); /* a directory */
    assert_int_equal(tl.last_code, GLOW_ERROR_IO);
    /* a truncated file: TRUNCATED, named */
    char cut[512];
    snprintf(cut, sizeof cut, "%s/cut.glow", tmpdir);
    f = fopen(cut, "wb");
    fwrite(img, 1, (size_t)size - 1, f);
    fclose(f);
    assert_int_equal(glow_bake_load_file(ctx, cut, &bake), GLOW_ERROR_TRUNCATED);
    assert_int_equal(tl.last_code, GLOW_ERROR_TRUNCATED);
    assert_non_null(strstr(tl.last_message, cut));
    f = fopen(cut, "wb");
    fwrite(img, 1, 20, f);
    fclose(f);
    assert_int_equal(glow_bake_load_file(ctx, cut, &bake), GLOW_ERROR_TRUNCATED);
    assert_non_null(strstr(tl.last_message, cut));
    /* a damaged file: BAD_CHECKSUM, named */
    ((unsigned char *)img)[size - 3] ^= 0xFF;
    f = fopen(cut, "wb");
    fwrite(img, 1, (size_t)size, f);
    fclose(f);
    assert_int_equal(glow_bake_load_file(ctx, cut, &bake), GLOW_ERROR_BAD_CHECKSUM);
    assert_int_equal(tl.last_code, GLOW_ERROR_BAD_CHECKSUM);
    assert_non_null(strstr(tl.last_message, cut));
    unlink(cut);
    free(img);
    glow_context_destroy(ctx);
    unlink(path);
}

static void test_atomic_write_failures(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    glow__section_data s[16];
    uint32_t n = sections_of(&tb, 0, s);
    pc_log_capture cap = {0, ""};
    glow__log log = {pc_log, &cap, "", 0};

    /* nonexistent directory: IO error, nothing created */
    char path[512];
    snprintf(path, sizeof path, "%s/no/such/dir/out.glow", tmpdir);
    assert_int_equal(glow__bake_write_file(path, s, n, &log, NULL), GLOW_ERROR_IO);
    assert_int_equal(cap.count, 1);
    assert_non_null(strstr(cap.last, path));
    assert_non_null(strstr(log.last_error, path));
    assert_int_equal(file_size_of(path), -1);

    /* disk full after 100 bytes (test hook): the existing file survives, no temp is left */
    snprintf(path, sizeof path, "%s/keep.glow", tmpdir);
    FILE *f = fopen(path, "wb");
    fputs("previous bake", f);
    fclose(f);
    assert_int_equal(setenv("GLOW_TEST_WRITE_FAIL_AFTER", "100", 1), 0);
    cap.count = 0;
    assert_int_equal(glow__bake_write_file(path, s, n, &log, NULL), GLOW_ERROR_IO);
    unsetenv("GLOW_TEST_WRITE_FAIL_AFTER");
    assert_int_equal(cap.count, 1);
    char expect[700];
    snprintf(expect, sizeof expect, "%s: write failed: %s", path, strerror(ENOSPC));
    assert_string_equal(cap.last, expect);
    assert_int_equal(file_size_of(path), 13);
    assert_int_equal(count_tmp_files(tmpdir), 0);
    /* fails at 0 bytes too */
    assert_int_equal(setenv("GLOW_TEST_WRITE_FAIL_AFTER", "0", 1), 0);
    assert_int_equal(glow__bake_write_file(path, s, n, &log, NULL), GLOW_ERROR_IO);
    unsetenv("GLOW_TEST_WRITE_FAIL_AFTER");
    assert_int_equal(file_size_of(path), 13);
    assert_int_equal(count_tmp_files(tmpdir), 0);

    /* a real ENOSPC: the temporary name is a symlink to /dev/full */
    struct stat st;
    if (stat("/dev/full", &st) == 0) {
        char tmp[600];
        snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid());
        assert_int_equal(symlink("/dev/full", tmp), 0);
        cap.count = 0;
        assert_int_equal(glow__bake_write_file(path, s, n, &log, NULL), GLOW_ERROR_IO);
        assert_string_equal(cap.last, expect);
        assert_int_equal(file_size_of(path), 13);
        assert_int_equal(count_tmp_files(tmpdir), 0); /* the link is gone, /dev/full is not */
        assert_int_equal(stat("/dev/full", &st), 0);
    }

    /* the target is a directory: rename fails, the temp is removed */
    snprintf(path, sizeof path, "%s/adir", tmpdir);
    assert_int_equal(mkdir(path, 0700), 0);
    char inner[600];
    snprintf(inner, sizeof inner, "%s/x", path);
    f = fopen(inner, "wb");
    fclose(f);
    assert_int_equal(glow__bake_write_file(path, s, n, &log, NULL), GLOW_ERROR_IO);
    assert_non_null(strstr(cap.last, "rename failed"));
    assert_int_equal(count_tmp_files(tmpdir), 0);
    unlink(inner);
    rmdir(path);

    /* a successful write replaces the old file */
    snprintf(path, sizeof path, "%s/keep.glow", tmpdir);
    uint64_t written = 0;
    assert_int_equal(glow__bake_write_file(path, s, n, &log, &written), GLOW_OK);
    assert_int_equal(file_size_of(path), (long)written);
    unlink(path);
    /* builder errors pass through */
    s[n] = s[0];
    assert_int_equal(glow__bake_write_file(path, s, n + 1, &log, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(file_size_of(path), -1);
}

/* ------------------------------------------------------------------------------ golden v1 */
/* A real format-1.2 bake with a lightmap detail (glow-bake builtin:cornell --surfels 16 --links 4
 * --grid-spacing 2 --texel-density 0.5, 2026-11-27; also a fuzz seed): this reader loads it, finds
 * the LDET section and the solver runs it. Never regenerated silently: a reader that stops loading
 * it broke 1.2 files. */
static void test_real_v1_2_detail(void **state) {
    (void)state;
    test_log log;
    glow_context *ctx = make_ctx(&log);
    glow_bake *bake = NULL;
    assert_int_equal(glow_bake_load_file(ctx, GLOW_TEST_DATA_DIR "/seed_cornell_tiny_ldet.glow", &bake), GLOW_OK);
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(bake, &info), GLOW_OK);
    assert_int_equal(info.format_major, 1);
    assert_int_equal(info.format_minor, 2);
    const uint32_t *texel, *first, *node;
    const float *weight;
    const glow_bake_detail *dh = glow__bake_detail(bake, &texel, &first, &node, &weight);
    assert_non_null(dh);
    assert_int_equal(dh->factor, 3);
    assert_int_equal(dh->texel_count, 69);
    assert_int_equal(dh->link_count, 396);
    glow_system *sys = NULL;
    assert_int_equal(glow_system_create(ctx, &(glow_system_desc){.bake = bake}, &sys), GLOW_OK);
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(sys);
    assert_non_null(o->lightmap_detail);
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)o->detail_width * o->detail_height * 4u; ++i) {
        assert_true(isfinite(o->lightmap_detail[i]));
        sum += fabs(o->lightmap_detail[i]);
    }
    assert_true(sum > 69.0); /* the coverage alone is 69; the lamp lights the box, so some RGB is not 0 */
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
}

/* A real format-1.5 bake with a refined grid (glow-bake builtin:cornell --surfels 16 --links 4
 * --grid-spacing 0.9 --grid-refine 2 --texel-density 0.5, 2026-11-29; also a fuzz seed): it loads, its
 * GFIN reaches the outputs, the solver runs it and lookups in the bricks are finite; GFIN's checks
 * refuse a bad refine, a brick on the grid's last layer, a corner that is no grid cache and a short
 * section (each patched in memory, CRCs resealed). */
static unsigned char *read_file_all(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)n);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return buf;
}

/* A stored seed bake of format 1.MINOR: read, loaded in a fresh context, its info checked for the minor. */
static glow_bake *load_seed(const char *name, uint32_t minor, test_log *log, glow_context **ctx, unsigned char **img,
                            size_t *size, glow_bake_info *info) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s", GLOW_TEST_DATA_DIR, name);
    *img = read_file_all(path, size);
    *ctx = make_ctx(log);
    glow_bake *bake = NULL;
    assert_int_equal(glow_bake_load(*ctx, *img, *size, &bake), GLOW_OK);
    assert_int_equal(glow_bake_get_info(bake, info), GLOW_OK);
    assert_int_equal(info->format_minor, minor);
    return bake;
}

static void test_real_v1_5_grid_fine(void **state) {
    (void)state;
    size_t size = 0;
    unsigned char *img = NULL;
    test_log log;
    glow_context *ctx = NULL;
    glow_bake_info info;
    glow_bake *bake = load_seed("seed_cornell_tiny_gfin.glow", 5, &log, &ctx, &img, &size, &info);
    const glow_bake_grid_fine *gf = glow__bake_grid_fine(bake);
    assert_non_null(gf);
    assert_int_equal(gf->refine, 2);
    assert_int_equal(gf->brick_count, 8);
    glow_system *sys = NULL;
    assert_int_equal(glow_system_create(ctx, &(glow_system_desc){.bake = bake}, &sys), GLOW_OK);
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(sys);
    assert_int_equal(o->grid_refine, 2);
    assert_int_equal(o->grid_brick_count, 8);
    assert_non_null(o->grid_bricks);
    assert_non_null(o->grid_brick_visibility);
    float coeffs[27];
    uint32_t hits = 0;
    for (int i = 0; i < 64; ++i) { /* points through the room */
        const float p[3] = {-0.9f + 0.6f * (float)(i % 4), 0.1f + 0.6f * (float)((i / 4) % 4), -0.9f + 0.6f * (float)(i / 16)};
        const float n[3] = {0.0f, 1.0f, 0.0f};
        if (glow_sample_grid_oriented(o, p, n, coeffs) != GLOW_OK) continue;
        ++hits;
        for (uint32_t k = 0; k < o->coeff_count; ++k) assert_true(isfinite(coeffs[k]));
    }
    assert_true(hits > 32);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    /* patched copies */
    unsigned char *bad = malloc(size);
    const size_t off = (size_t)u64_at(entry_ptr(img, GLOW_SECTION_GFIN) + 8);
    const glow_bake_meta *m = (const glow_bake_meta *)(const void *)payload_ptr(img, GLOW_SECTION_META);
    const size_t cells = (size_t)m->grid_dims[0] * m->grid_dims[1] * m->grid_dims[2];
    uint32_t v;
#define PATCH_GFIN(at, value, code, needle)                                                                            \
    do {                                                                                                               \
        memcpy(bad, img, size);                                                                                        \
        v = (value);                                                                                                   \
        memcpy(bad + off + (at), &v, 4);                                                                               \
        fuzz_fix_crcs(bad, size);                                                                                      \
        EXPECT_LOAD_MSG(bad, size, code, needle);                                                                      \
    } while (0)
    PATCH_GFIN(0, 9u, GLOW_ERROR_CORRUPT_DATA, "GFIN: refine 9");
    PATCH_GFIN(0, 1u, GLOW_ERROR_CORRUPT_DATA, "GFIN: refine 1");
    PATCH_GFIN(4, 7u, GLOW_ERROR_CORRUPT_DATA, "section 'GFIN' is");
    /* the cell whose lowest corner is the last grid point names brick 0 */
    PATCH_GFIN(32 + 4 * (cells - 1), 0u, GLOW_ERROR_OUT_OF_RANGE, "the grid's last layer");
    /* brick 0's first corner: the first lightmap cache */
    PATCH_GFIN(32 + 4 * cells, m->grid_cache_count, GLOW_ERROR_OUT_OF_RANGE, "is not a grid cache");
    PATCH_GFIN(32 + 4 * cells, 0x80000000u | 1u, GLOW_ERROR_OUT_OF_RANGE, "is not a grid cache");
#undef PATCH_GFIN
    /* a short GFIN: the section entry's size one word less */
    memcpy(bad, img, size);
    unsigned char *e = entry_ptr(bad, GLOW_SECTION_GFIN);
    const uint64_t short_size = u64_at(e + 16) - 4u;
    memcpy(e + 16, &short_size, 8);
    fuzz_fix_crcs(bad, size);
    EXPECT_LOAD_MSG(bad, size, GLOW_ERROR_CORRUPT_DATA, "section 'GFIN' is");
    free(bad);
    free(img);
}

/* A real format 1.6 bake with the sky transfer (SKYT): builtin:pillar-court, an open court, baked with
 *   glow-bake builtin:pillar-court -o seed_court_tiny_skyt.glow --surfels 32 --links 4 --grid-spacing 4
 *     --texel-density 0.25 --lightmap-detail 1 --link-subsets off -q --seed 1 --sky-rays 16
 * It loads, its transfer reads back with the counts of the bake, the grid takes a sky, and the section's
 * checks name what they refuse (docs/bake-format.md "Sky transfer"). */
static void test_real_v1_6_sky(void **state) {
    (void)state;
    size_t size = 0;
    unsigned char *img = NULL;
    test_log log;
    glow_context *ctx = NULL;
    glow_bake_info info;
    glow_bake *bake = load_seed("seed_court_tiny_skyt.glow", 6, &log, &ctx, &img, &size, &info);
    glow_bake_sky_transfer st;
    assert_int_equal(glow_bake_get_sky_transfer(bake, &st), GLOW_OK);
    assert_int_equal(st.surfel_count, info.surfel_count);
    assert_int_equal(st.grid_cache_count, info.grid_cache_count);
    assert_int_equal(st.rays, 16);
    assert_int_equal(st.grid_rays, 128);
    uint32_t open = 0;
    for (uint32_t i = 0; i < st.surfel_count; ++i) { /* T_0 = π y_0 S, S in [0, 1] */
        const float t0 = st.surfel_transfer[9 * i];
        assert_true(t0 >= 0.0f && t0 <= 3.14159265f * 0.28209479f + 1e-5f);
        open += t0 > 0.0f;
    }
    assert_true(open > st.surfel_count / 2);
    glow_system *sys = NULL;
    assert_int_equal(glow_system_create(ctx, &(glow_system_desc){.bake = bake}, &sys), GLOW_OK);
    float L[GLOW_SKY_SH_FLOATS];
    const float one[3] = {1, 1, 1};
    glow_sh_sky_constant(one, L);
    assert_int_equal(glow_system_set_sky(sys, L), GLOW_OK);
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(sys);
    for (uint32_t c = 0; c < o->grid_cache_count; ++c) assert_true(o->cache_sh[(size_t)c * o->coeff_count] > 0.0f);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    /* patched copies */
    unsigned char *bad = malloc(size);
    const size_t off = (size_t)u64_at(entry_ptr(img, GLOW_SECTION_SKYT) + 8);
    uint32_t v;
#define PATCH_SKYT(at, value, code, needle)                                                                            \
    do {                                                                                                               \
        memcpy(bad, img, size);                                                                                        \
        v = (value);                                                                                                   \
        memcpy(bad + off + (at), &v, 4);                                                                               \
        fuzz_fix_crcs(bad, size);                                                                                      \
        EXPECT_LOAD_MSG(bad, size, code, needle);                                                                      \
    } while (0)
    PATCH_SKYT(0, 4u, GLOW_ERROR_CORRUPT_DATA, "SKYT: 4 coefficients");
    PATCH_SKYT(4, info.surfel_count + 1u, GLOW_ERROR_CORRUPT_DATA, "do not fit the bake");
    PATCH_SKYT(12, 0u, GLOW_ERROR_CORRUPT_DATA, "do not fit the bake");
    PATCH_SKYT(16, 0u, GLOW_ERROR_CORRUPT_DATA, "do not fit the bake");
    PATCH_SKYT(32 + 4 * 5, 0x7FC00000u, GLOW_ERROR_CORRUPT_DATA, "SKYT surfel 0 coefficient 5");
    PATCH_SKYT(32 + 36 * info.surfel_count, 0x41900000u /* 18 */, GLOW_ERROR_CORRUPT_DATA, "SKYT grid cache 0 coefficient 0");
#undef PATCH_SKYT
    memcpy(bad, img, size);
    unsigned char *e = entry_ptr(bad, GLOW_SECTION_SKYT);
    const uint64_t short_size = u64_at(e + 16) - 4u;
    memcpy(e + 16, &short_size, 8);
    fuzz_fix_crcs(bad, size);
    EXPECT_LOAD_MSG(bad, size, GLOW_ERROR_CORRUPT_DATA, "section 'SKYT' is");
    free(bad);
    free(img);
}

/* Format 1.7, lightmap pages: tests/data/seed_cornell_tiny_pages.glow is glow-bake builtin:cornell --surfels 64
 * --links 16 --grid-spacing 1 --lightmap-caches 200 --no-sky --lightmap-detail 2 --link-subsets off
 * --lightmap-max-size 16: 3 pages of 16x16 at the one-page density (1.299 texels/unit, 185 lightmap caches).
 * It loads, every triangle's page is below 3 and every page holds triangles and caches, every LMAP entry
 * (copies included) names a cache of its own page, a system updates
 * and its outputs hold the 3 pages, the page lookups read them; a page index out of range, a missing
 * TPAG and a short TPAG are refused, naming the section. */
static void test_real_v1_7_pages(void **state) {
    (void)state;
    size_t size = 0;
    unsigned char *img = NULL;
    test_log log;
    glow_context *ctx = NULL;
    glow_bake_info info;
    glow_bake *bake = load_seed("seed_cornell_tiny_pages.glow", 7, &log, &ctx, &img, &size, &info);
    assert_int_equal(info.lightmap_count, 3);
    assert_int_equal(info.lightmap_width, 16);
    assert_int_equal(info.lightmap_height, 16);
    glow_bake_geometry geo;
    assert_int_equal(glow_bake_get_geometry(bake, &geo), GLOW_OK);
    assert_non_null(geo.lightmap_page);
    uint32_t tris_on[3] = {0, 0, 0}, caches_on[3] = {0, 0, 0};
    for (uint32_t t = 0; t < geo.triangle_count; ++t) {
        assert_true(geo.lightmap_page[t] < 3);
        tris_on[geo.lightmap_page[t]]++;
    }
    glow_cache_info *ci = malloc((size_t)info.cache_count * sizeof *ci);
    assert_int_equal(glow_bake_get_caches(bake, 0, info.cache_count, ci), GLOW_OK);
    for (uint32_t c = info.grid_cache_count; c < info.cache_count; ++c) {
        assert_true(ci[c].texel < 3u * 16u * 16u);
        caches_on[ci[c].texel / 256u]++;
    }
    for (int p = 0; p < 3; ++p) assert_true(tris_on[p] > 0 && caches_on[p] > 0);
    const uint32_t *lmap = glow__bake_lightmap_map(bake); /* gutter and invalid-texel copies stay in their page */
    assert_non_null(lmap);
    uint32_t copies = 0;
    for (uint32_t i = 0; i < 3u * 256u; ++i) {
        if (lmap[i] == GLOW_MAP_EMPTY) continue;
        const uint32_t c = lmap[i] & GLOW_MAP_INDEX_MASK;
        copies += (lmap[i] & GLOW_MAP_COPY_BIT) != 0;
        assert_true(c >= info.grid_cache_count && c < info.cache_count);
        assert_int_equal(ci[c].texel / 256u, i / 256u);
    }
    assert_true(copies > 0);
    free(ci);
    glow_system *sys = NULL;
    assert_int_equal(glow_system_create(ctx, &(glow_system_desc){.bake = bake}, &sys), GLOW_OK);
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(sys);
    assert_int_equal(o->lightmap_pages, 3);
    assert_non_null(o->lightmap_detail);
    float *coeffs = malloc(o->coeff_count * sizeof *coeffs), rgb[3];
    uint32_t hits = 0;
    for (uint32_t t = 0; t < geo.triangle_count; ++t) { /* each triangle's UV centroid on its page */
        const uint16_t *q = (const uint16_t *)(const void *)((const char *)geo.lightmap_uv + (size_t)t * geo.stride);
        const float u = (q[0] + q[2] + q[4]) / (3.0f * 65535.0f), v = (q[1] + q[3] + q[5]) / (3.0f * 65535.0f);
        hits += glow_sample_lightmap_page(o, geo.lightmap_page[t], u, v, coeffs) == GLOW_OK;
        const glow_result rd = glow_sample_lightmap_detail_page(o, geo.lightmap_page[t], u, v, rgb);
        assert_true(rd == GLOW_OK || rd == GLOW_ERROR_OUT_OF_RANGE);
    }
    assert_true(hits > geo.triangle_count / 2);
    assert_int_equal(glow_sample_lightmap_page(o, 3, 0.5f, 0.5f, coeffs), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_lightmap_detail_page(o, 3, 0.5f, 0.5f, rgb), GLOW_ERROR_INVALID_ARGUMENT);
    free(coeffs);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    /* patched copies */
    unsigned char *bad = malloc(size);
    memcpy(bad, img, size);
    const uint32_t three = 3u;
    memcpy(bad + u64_at(entry_ptr(bad, GLOW_SECTION_TPAG) + 8) + 4u * 5u, &three, 4);
    fuzz_fix_crcs(bad, size);
    EXPECT_LOAD_MSG(bad, size, GLOW_ERROR_CORRUPT_DATA, "TPAG triangle 5: lightmap page 3 not below lightmap_count 3");
    memcpy(bad, img, size);
    memcpy(entry_ptr(bad, GLOW_SECTION_TPAG), "XPAG", 4); /* an unknown section, skipped: no pages */
    fuzz_fix_crcs(bad, size);
    EXPECT_LOAD_MSG(bad, size, GLOW_ERROR_CORRUPT_DATA, "missing section 'TPAG'");
    memcpy(bad, img, size);
    unsigned char *e = entry_ptr(bad, GLOW_SECTION_TPAG);
    const uint64_t short_size = u64_at(e + 16) - 4u;
    memcpy(e + 16, &short_size, 8);
    fuzz_fix_crcs(bad, size);
    EXPECT_LOAD_MSG(bad, size, GLOW_ERROR_CORRUPT_DATA, "section 'TPAG' is");
    free(bad);
    free(img);
}

/* A 1.8 bake: one system of a world of two boxes 0.5 m apart (glow-bake two.obj --system-area 6 --surfels 48
 * --links 8 --lightmap-caches 24 --lightmap-detail 1 --grid-spacing 1 --sky-rays 8), with XREF and PTRE.
 * The runtime skips PTRE (the linker's); its contract is checked here from the bytes: the key is XREF's,
 * children precede parents, the root is last, the leaves hold the system's whole surface. */
static void test_real_v1_8_ptre(void **state) {
    (void)state;
    size_t size = 0;
    unsigned char *img = NULL;
    test_log log;
    glow_context *ctx = NULL;
    glow_bake_info info;
    glow_bake *bake = load_seed("seed_two_boxes_system_ptre.glow", 8, &log, &ctx, &img, &size, &info);
    const unsigned char *xe = entry_ptr(img, GLOW_SECTION_XREF), *pe = entry_ptr(img, GLOW_SECTION_PTRE);
    assert_non_null(xe);
    assert_non_null(pe);
    glow_bake_xref xh;
    glow_bake_ptree ph;
    memcpy(&xh, img + u64_at(xe + 8), sizeof xh);
    memcpy(&ph, img + u64_at(pe + 8), sizeof ph);
    assert_true(xh.system_key == ph.tree_key && ph.tree_key != 0);
    assert_int_equal(xh.dependency_count, 1);
    assert_true(ph.leaf_count >= 1 && ph.leaf_count < ph.node_count && ph.root == ph.node_count - 1);
    assert_true(ph.leaf_count < info.surfel_count); /* coarsened: 24 surfels, nodes of <= 16 leaves */
    assert_int_equal(u64_at(pe + 16), sizeof ph + (uint64_t)ph.node_count * sizeof(glow_bake_ptree_node) +
                                          (uint64_t)ph.leaf_count * sizeof(glow_bake_ptree_leaf));
    const unsigned char *q = img + u64_at(pe + 8) + sizeof ph;
    double leaf_area = 0.0;
    uint32_t *lv = calloc(ph.node_count, sizeof *lv);
    for (uint32_t i = 0; i < ph.node_count; ++i) {
        glow_bake_ptree_node n;
        memcpy(&n, q + (size_t)i * sizeof n, sizeof n);
        assert_true(n.source < info.node_count);
        if (i < ph.leaf_count) {
            assert_true(n.child[0] == GLOW_NODE_NONE && n.child[1] == GLOW_NODE_NONE && n.level == 0);
        } else {
            assert_true(n.child[0] < i && n.child[1] < i);
            lv[i] = 1 + (lv[n.child[0]] > lv[n.child[1]] ? lv[n.child[0]] : lv[n.child[1]]);
            assert_int_equal(n.level, lv[i]);
        }
        assert_true(i == ph.root ? n.parent == GLOW_NODE_NONE : (n.parent > i && n.parent < ph.node_count));
    }
    free(lv);
    q += (size_t)ph.node_count * sizeof(glow_bake_ptree_node);
    for (uint32_t i = 0; i < ph.leaf_count; ++i) {
        glow_bake_ptree_leaf f;
        memcpy(&f, q + (size_t)i * sizeof f, sizeof f);
        leaf_area += f.area;
    }
    assert_true(fabs(leaf_area - info.scene_area) <= 1e-3 * info.scene_area);
    glow_system *sys = NULL;
    assert_int_equal(glow_system_create(ctx, &(glow_system_desc){.bake = bake}, &sys), GLOW_OK);
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    free(img);
}

static void test_golden_v1(void **state) {
    (void)state;
    test_bake tb;
    build_golden(&tb);
    glow__section_data s[16];
    uint32_t n = sections_of(&tb, 0, s);
    const char *regen = getenv("GLOW_REGENERATE_GOLDEN");
    if (regen && strcmp(regen, "1") == 0) {
        uint64_t written = 0;
        assert_int_equal(glow__bake_write_file(GOLDEN_PATH, s, n, NULL, &written), GLOW_OK);
        FILE *f = fopen(GOLDEN_PATH, "rb");
        unsigned char *buf = malloc(written);
        assert_int_equal(fread(buf, 1, written, f), written);
        fclose(f);
        print_message("regenerated %s: GOLDEN_SIZE %lluu, GOLDEN_CRC 0x%08xu\n", GOLDEN_PATH,
                      (unsigned long long)written, (unsigned)crc32(0L, buf, (uInt)written));
        free(buf);
    }
    FILE *f = fopen(GOLDEN_PATH, "rb");
    if (!f) fail_msg("%s is missing (regenerate with GLOW_REGENERATE_GOLDEN=1)", GOLDEN_PATH);
    unsigned char *buf = malloc(GOLDEN_SIZE + 1);
    size_t got = fread(buf, 1, GOLDEN_SIZE + 1, f);
    fclose(f);
    assert_int_equal(got, GOLDEN_SIZE);
    assert_int_equal((uint32_t)crc32(0L, buf, (uInt)got), GOLDEN_CRC);

    test_log log;
    glow_context *ctx = make_ctx(&log);
    glow_bake *bake = NULL;
    assert_int_equal(glow_bake_load_file(ctx, GOLDEN_PATH, &bake), GLOW_OK);
    check_golden_contents(bake, 0); /* the frozen file has no GVIS: plain trilinear grid lookups */
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);

    /* today's writer still produces the frozen bytes, but for the header's minor version (the writer
     * stamps the current 1.x; sections added since are optional and absent here) and so its CRC */
    void *img;
    uint64_t size;
    assert_int_equal(glow__bake_write_memory(s, n, &img, &size), GLOW_OK);
    assert_int_equal(size, GOLDEN_SIZE);
    glow_bake_header hdr;
    memcpy(&hdr, img, sizeof hdr);
    assert_int_equal(hdr.minor, GLOW_BAKE_FORMAT_VERSION_MINOR);
    hdr.minor = 0;
    hdr.header_crc32 = 0;
    hdr.header_crc32 = (uint32_t)crc32(0L, (const Bytef *)&hdr, (uInt)sizeof hdr);
    memcpy(img, &hdr, sizeof hdr);
    assert_memory_equal(img, buf, GOLDEN_SIZE);
    free(img);
    free(buf);
}

static int setup_tmpdir(void **state) {
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/glow_format_XXXXXX");
    return mkdtemp(tmpdir) ? 0 : -1;
}
static int teardown_tmpdir(void **state) {
    (void)state;
    return rmdir(tmpdir);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_load_valid),
        cmocka_unit_test(test_load_variants),
        cmocka_unit_test(test_truncated),
        cmocka_unit_test(test_magic_version),
        cmocka_unit_test(test_checksums),
        cmocka_unit_test(test_container_structure),
        cmocka_unit_test(test_meta_counts),
        cmocka_unit_test(test_out_of_range),
        cmocka_unit_test(test_non_finite),
        cmocka_unit_test(test_context_and_results),
        cmocka_unit_test(test_crc32_vs_zlib),
        cmocka_unit_test(test_half),
        cmocka_unit_test(test_oct),
        cmocka_unit_test(test_oct12),
        cmocka_unit_test(test_link_pack),
        cmocka_unit_test(test_writer),
        cmocka_unit_test(test_file_round_trip),
        cmocka_unit_test(test_atomic_write_failures),
        cmocka_unit_test(test_golden_v1),
        cmocka_unit_test(test_real_v1_2_detail),
        cmocka_unit_test(test_real_v1_5_grid_fine),
        cmocka_unit_test(test_real_v1_6_sky), cmocka_unit_test(test_real_v1_7_pages),
        cmocka_unit_test(test_real_v1_8_ptre),
    };
    return cmocka_run_group_tests(tests, setup_tmpdir, teardown_tmpdir);
}
