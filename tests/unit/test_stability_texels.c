/* test_stability_texels.c — caches behind geometry (PIC Fig. 9a; issue 4, stability suite): no
 * lightmap texel that shading reads may deliver the light of a cache that sits behind geometry.
 *
 * "Used in shading": a texel is used when glow_sample_lightmap, at some point of some triangle's
 * lightmap footprint, reads it with non-zero weight — the union of the 2x2 bilinear footprints over
 * the rasterised UV triangles (stab_used_texels: texel (i, j) is used when the triangle, in texel
 * units, overlaps the open square (i - 0.5, i + 1.5) x (j - 0.5, j + 1.5)). UVs are the bake's own
 * unorm16 GEOM values, what a host samples with.
 *
 * "Invalid" (behind geometry), for the cache a used texel maps to (LMAP entry, copies followed):
 *   (a) the texel reads nothing: EMPTY map entry (glow.h promises that gutter texels hold copies, so
 *       a bilinear lookup inside a chart's footprint never reads an empty texel), or an entry that is
 *       not one of the linker's kept lightmap caches (kind LIGHTMAP, and that cache's own texel maps
 *       back to it: a texel the linker flagged invalid must name a valid neighbour's cache, never a
 *       cache of its own);
 *   (b) the cache position is inside a closed solid or outside the scene's rooms, by the scene's
 *       analytic geometry: builtin:cornell — outside the 2 m room or inside one of the two blocks
 *       (placed as in precompute/src/builtin.c); builtin:two-rooms — in neither room (e.g. in the
 *       0.1 m gap of the separating wall), or in the other room than the triangle that reads it;
 *   (c) a ray from the cache position along its normal first meets a back face (brute force over the
 *       bake's triangles, not the linker's Embree scene): the cache looks at the back of something,
 *       e.g. a ceiling texel above the one-sided Cornell light.
 * Each count must be 0, for builtin:cornell and builtin:two-rooms, and so must the grid caches inside
 * solids (by (b): grid cache points must be air as well). Also reported: the linker's own count of
 * texels it flagged invalid (and filled from neighbours), and used texels whose cache's normal is more
 * than 60 degrees off the reading triangle's (a copy from another surface; 0 in both scenes). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "stability_common.h"

/* ------------------------------------------------------------------------- analytic geometry */
typedef enum { SCENE_CORNELL, SCENE_TWO_ROOMS, SCENE_WALL_GAP } scene_kind;

/* builtin.c add_block: footprint half-size `half` about (cx, cz), turned by `angle` about +Y. */
static bool inside_block(const float p[3], double cx, double cz, double half, double height, double angle) {
    double ca = cos(angle), sa = sin(angle), dx = p[0] - cx, dz = p[2] - cz;
    double u = dx * ca + dz * sa, w = -dx * sa + dz * ca;
    return fabs(u) < half && fabs(w) < half && p[1] > 0.0 && p[1] < height;
}

/* Room of a point: 0 = not in any room's air (outside, inside a solid, in a wall gap), else 1 or 2. */
static int room_of(scene_kind k, const float p[3]) {
    if (k == SCENE_CORNELL) {
        if (!(p[0] > -1.0f && p[0] < 1.0f && p[1] > 0.0f && p[1] < 2.0f && p[2] > -1.0f && p[2] < 1.0f)) return 0;
        if (inside_block(p, 0.33, 0.37, 0.3, 0.6, atan2(0.17, 0.57))) return 0;
        if (inside_block(p, -0.335, -0.29, 0.3, 1.2, atan2(-0.18, 0.57))) return 0;
        return 1;
    }
    if (!(p[1] > 0.0f && p[1] < 2.5f && p[2] > -2.0f && p[2] < 2.0f)) return 0;
    if (k == SCENE_WALL_GAP) { /* one room, the 0.1 m partition at x = 0 for z < 1, the doorway beyond */
        if (!(p[0] > -4.0f && p[0] < 4.0f)) return 0;
        if (p[0] <= -0.05f) return 1;
        if (p[0] >= 0.05f) return 2;
        return p[2] >= 1.0f ? 3 : 0;
    }
    if (p[0] > -4.05f && p[0] < -0.05f) return 1;
    if (p[0] > 0.05f && p[0] < 4.05f) return 2;
    return 0;
}

/* -------------------------------------------------------------------------------------- check */
typedef struct texel_counts {
    uint32_t used, copies, empty, not_kept, behind_solid, other_room, faces_back, normal_off;
    uint32_t linker_invalid, grid_inside_solid;
} texel_counts;

static void count_texels(const stab_bake *b, scene_kind kind, texel_counts *tc) {
    memset(tc, 0, sizeof *tc);
    const glow_bake_meta *m = glow__bake_meta(b->bake);
    const glow_bake_cache *caches = glow__bake_caches(b->bake);
    const uint32_t *lmap = glow__bake_lightmap_map(b->bake);
    glow_bake_geometry g;
    assert_int_equal(glow_bake_get_geometry(b->bake, &g), GLOW_OK);
    assert_true(g.triangle_count > 0 && lmap && m->lightmap_width > 0);
    const uint32_t W = m->lightmap_width, H = m->lightmap_height;
    tc->linker_invalid = m->lightmap_invalid_texels;
    /* seen[texel]: bit 0 counted, bit 1 read by a triangle of another room than its cache's, bit 2
     * read by a triangle whose normal is > 60 deg off its cache's (every triangle that reads a texel
     * is checked; the texel is counted once) */
    uint8_t *seen = calloc((size_t)W * H, 1);
    uint8_t *cache_checked = calloc(m->cache_count, 1), *cache_faces_back = calloc(m->cache_count, 1);
    uint32_t *texels = malloc((size_t)W * H * sizeof *texels);
    assert_non_null(seen);
    assert_non_null(cache_checked);
    assert_non_null(cache_faces_back);
    assert_non_null(texels);
    for (uint32_t t = 0; t < g.triangle_count; ++t) {
        double p[3][3], uv[3][2], n[3];
        stab_triangle(&g, t, p, uv);
        stab_normal(p, n);
        /* the triangle's room: its centroid lifted 1 cm along its normal */
        const float lifted[3] = {(float)((p[0][0] + p[1][0] + p[2][0]) / 3.0 + 0.01 * n[0]),
                                 (float)((p[0][1] + p[1][1] + p[2][1]) / 3.0 + 0.01 * n[1]),
                                 (float)((p[0][2] + p[1][2] + p[2][2]) / 3.0 + 0.01 * n[2])};
        const int tri_room = room_of(kind, lifted);
        assert_true(tri_room != 0); /* every surface faces into a room's air */
        const uint32_t count = stab_used_texels((const double(*)[2])uv, W, H, texels, W * H);
        for (uint32_t k = 0; k < count; ++k) {
            const uint32_t tx = texels[k];
            const bool first = !(seen[tx] & 1u);
            seen[tx] |= 1u;
            tc->used += first;
            const uint32_t e = lmap[tx];
            if (e == GLOW_MAP_EMPTY) {
                tc->empty += first;
                continue;
            }
            tc->copies += first && (e & GLOW_MAP_COPY_BIT) != 0;
            const uint32_t c = e & GLOW_MAP_INDEX_MASK;
            if (c < m->grid_cache_count || c >= m->cache_count || caches[c].kind != GLOW_CACHE_KIND_LIGHTMAP ||
                caches[c].texel >= W * H || lmap[caches[c].texel] != c) {
                tc->not_kept += first;
                continue;
            }
            const int room = room_of(kind, caches[c].position);
            if (room == 0) {
                tc->behind_solid += first;
            } else if (room != tri_room && !(seen[tx] & 2u) &&
                       !(kind == SCENE_WALL_GAP && (room == 3 || tri_room == 3 || caches[c].position[2] > 0.9f))) {
                /* wall-gap: only caches beside the partition (not at the doorway, where both halves
                 * meet and see each other) belong to one half */
                seen[tx] |= 2u;
                tc->other_room++;
            }
            float cn[3];
            glow__oct_decode(caches[c].normal_oct, cn);
            if (cn[0] * n[0] + cn[1] * n[1] + cn[2] * n[2] < 0.5 && !(seen[tx] & 4u)) {
                seen[tx] |= 4u;
                tc->normal_off++;
            }
            if (!cache_checked[c]) {
                cache_checked[c] = 1;
                const double o[3] = {caches[c].position[0], caches[c].position[1], caches[c].position[2]};
                const double d[3] = {cn[0], cn[1], cn[2]};
                bool back;
                if (stab_ray_first_hit(&g, o, d, 1e-6, &back) < INFINITY && back) cache_faces_back[c] = 1;
            }
            if (first) tc->faces_back += cache_faces_back[c];
        }
    }
    for (uint32_t c = 0; c < m->grid_cache_count; ++c) tc->grid_inside_solid += room_of(kind, caches[c].position) == 0;
    free(seen);
    free(cache_checked);
    free(cache_faces_back);
    free(texels);
}

static stab_bake g_b; /* the running test's bake: teardown_bake frees it after a failed assertion too */

static int teardown_bake(void **state) {
    (void)state;
    stab_bake_free(&g_b);
    return 0;
}

static void check_scene(const char *scene, scene_kind kind) {
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 64, .bands = 3, .threads = 2, .seed = 3};
    stab_bake *bp = &g_b;
    assert_int_equal(stab_bake_load(scene, kind == SCENE_CORNELL ? "texels_cornell" : kind == SCENE_TWO_ROOMS ? "texels_two_rooms" : "texels_wall_gap", &s, bp), 0);
    const stab_bake b = *bp;
    texel_counts tc;
    count_texels(&b, kind, &tc);
    const glow_bake_meta *m = glow__bake_meta(b.bake);
    printf("%s: %ux%u lightmap, %u lightmap caches, %u texels the linker flagged invalid (filled from neighbours); "
           "%u texels used in shading (%u copies): empty %u, not a kept cache %u, cache inside a solid / outside the "
           "rooms %u, cache in the other room %u, cache's normal ray meets a back face %u (cache normal > 60 deg off "
           "the triangle's: %u); grid caches inside solids %u of %u\n",
           scene, m->lightmap_width, m->lightmap_height, m->lightmap_cache_count, tc.linker_invalid, tc.used, tc.copies,
           tc.empty, tc.not_kept, tc.behind_solid, tc.other_room, tc.faces_back, tc.normal_off, tc.grid_inside_solid,
           m->grid_cache_count);
    assert_true(tc.used > m->lightmap_cache_count / 2); /* the enumeration found the charts */
    assert_int_equal(tc.empty, 0);
    assert_int_equal(tc.not_kept, 0);
    assert_int_equal(tc.behind_solid, 0);
    assert_int_equal(tc.other_room, 0);
    assert_int_equal(tc.faces_back, 0);
    assert_int_equal(tc.grid_inside_solid, 0);
    teardown_bake(NULL);
}

static void test_texels_cornell(void **state) {
    (void)state;
    check_scene("builtin:cornell", SCENE_CORNELL);
}

static void test_texels_two_rooms(void **state) {
    (void)state;
    check_scene("builtin:two-rooms", SCENE_TWO_ROOMS);
}

/* A partition standing on a floor and meeting a ceiling that run on under it (issue 13, contact
 * leaks): texels beside it on one side must not read caches of the other side. Before charts
 * stopped at such contacts, floor and ceiling were one chart each and the texels along the partition
 * read the lit side's caches (a bright line at the foot of the wall in Glow's view). */
static void test_texels_wall_gap(void **state) {
    (void)state;
    check_scene("builtin:wall-gap", SCENE_WALL_GAP);
}

/* The checks themselves can fail: the analytic predicates and the brute-force ray on known points. */
static void test_texel_checks_can_fail(void **state) {
    (void)state;
    assert_int_equal(room_of(SCENE_CORNELL, (const float[3]){0.0f, 1.0f, 0.0f}), 1);
    assert_int_equal(room_of(SCENE_CORNELL, (const float[3]){0.33f, 0.3f, 0.37f}), 0);    /* in the short block */
    assert_int_equal(room_of(SCENE_CORNELL, (const float[3]){-0.335f, 1.1f, -0.29f}), 0); /* in the tall block */
    assert_int_equal(room_of(SCENE_CORNELL, (const float[3]){0.0f, 2.01f, 0.0f}), 0);     /* above the ceiling */
    assert_int_equal(room_of(SCENE_TWO_ROOMS, (const float[3]){0.0f, 1.0f, 0.0f}), 0);    /* in the wall gap */
    assert_int_equal(room_of(SCENE_TWO_ROOMS, (const float[3]){-1.0f, 1.0f, 0.0f}), 1);
    assert_int_equal(room_of(SCENE_TWO_ROOMS, (const float[3]){1.0f, 1.0f, 0.0f}), 2);
    assert_int_equal(room_of(SCENE_WALL_GAP, (const float[3]){0.0f, 1.0f, 0.0f}), 0);     /* in the partition */
    assert_int_equal(room_of(SCENE_WALL_GAP, (const float[3]){0.0f, 1.0f, 1.5f}), 3);     /* in the doorway */
    assert_int_equal(room_of(SCENE_WALL_GAP, (const float[3]){0.2f, 0.01f, -1.0f}), 2);
    /* one quad facing +y at y = 0 (the bake's GEOM layout): from above a front face, from below a back face */
    const glow_bake_triangle quad[2] = {{.position = {-1, 0, -1, -1, 0, 1, 1, 0, 1}}, {.position = {-1, 0, -1, 1, 0, 1, 1, 0, -1}}};
    const glow_bake_geometry g = {.triangle_count = 2, .stride = sizeof quad[0], .positions = quad[0].position,
                                  .lightmap_uv = quad[0].lm_uv, .materials = &quad[0].material};
    bool back;
    double t = stab_ray_first_hit(&g, (const double[3]){0.2, 1.0, 0.1}, (const double[3]){0, -1, 0}, 1e-6, &back);
    assert_true(fabs(t - 1.0) < 1e-9);
    assert_false(back);
    t = stab_ray_first_hit(&g, (const double[3]){0.2, -1.0, 0.1}, (const double[3]){0, 1, 0}, 1e-6, &back);
    assert_true(fabs(t - 1.0) < 1e-9);
    assert_true(back);
    /* used texels: a triangle inside texel (4, 4) of a 16x16 map reads the 3x3 block around it
     * whose footprints reach it (its corners lie in the texel's 4 quadrants) */
    uint32_t out[64];
    const double tri[3][2] = {{4.2 / 16, 4.2 / 16}, {4.8 / 16, 4.2 / 16}, {4.5 / 16, 4.8 / 16}};
    uint32_t n = stab_used_texels(tri, 16, 16, out, 64);
    assert_int_equal(n, 9);
    for (uint32_t k = 0; k < n; ++k) {
        uint32_t x = out[k] % 16, y = out[k] / 16;
        assert_true(x >= 3 && x <= 5 && y >= 3 && y <= 5);
    }
    /* a tiny triangle with its corner at the centre of texel (4, 4), reaching up and right: texels
     * 3 are read with weight 0 there (|X - 3.5| = 1), texels 5 with a small positive one: 2x2 used */
    const double dot[3][2] = {{4.5 / 16, 4.5 / 16}, {4.5001 / 16, 4.5 / 16}, {4.5 / 16, 4.5001 / 16}};
    n = stab_used_texels(dot, 16, 16, out, 64);
    assert_int_equal(n, 4);
    for (uint32_t k = 0; k < n; ++k) assert_true(out[k] % 16 >= 4 && out[k] % 16 <= 5 && out[k] / 16 >= 4 && out[k] / 16 <= 5);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_texel_checks_can_fail),
                                       cmocka_unit_test_teardown(test_texels_cornell, teardown_bake),
                                       cmocka_unit_test_teardown(test_texels_two_rooms, teardown_bake),
                                       cmocka_unit_test_teardown(test_texels_wall_gap, teardown_bake)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
