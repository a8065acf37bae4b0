/* test_world.c — light across the systems of a world (issue 16 item 2, issue 17 item 1; bake format
 * 1.4 XREF, glow_system_set_neighbour). The built-in pillar hall (a closed hall lit by one point light)
 * is baked as a world of systems of at most 100 m² (6 of them) and as one system with the same surfel and
 * texel density. Each system is lit by the exact host from its own geometry, and updated in turn.
 *  - every system's dependencies are systems of the same world (by key), and the keys find them;
 *  - with the neighbours attached the caches gather the light of the systems around them: the mean
 *    indirect light of all lightmap caches rises and comes at least half way back from the detached
 *    world's to the one-system bake's (where no border exists);
 *  - a detached neighbour's proxies keep its last radiance (the documented fallback): detaching and
 *    updating again changes nothing;
 *  - the errors: a dependency out of range, a neighbour with another key, the system itself, destroying
 *    a system that another still reads;
 *  - a resealed bake whose XREF names a dependency out of range (GLOW_ERROR_OUT_OF_RANGE), whose counts do
 *    not match its size or that has more than 64 dependencies (GLOW_ERROR_CORRUPT_DATA) is refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "glow/glow.h"
#include "glow/glow_host.h"
#include "glow/glow_precompute.h"
#include "glow/glow_scene.h"
#include "bake/bake_format.h"

#define MAXS 16

typedef struct world {
    uint32_t n;
    glow_bake *bake[MAXS];
    glow_host *host[MAXS];
    glow_system *sys[MAXS];
    char path[MAXS][600];
} world;

static char dir[256];
static glow_context *ctx;
static glow_scene_desc scene;
static const char *scene_json = GLOW_TEST_DATA_DIR "/../../scenes/pillar-hall.json";

static glow_pc_settings settings(float system_area) {
    glow_pc_settings s = {0};
    s.surfels = 1024; /* per 100 m² with systems; the one-system bake gets the same density below */
    s.links = 32;
    s.lightmap_caches = 300;
    s.lightmap_detail = 1;
    s.threads = 2;
    s.system_area = system_area;
    return s;
}

static void open_system(world *w, const char *path) {
    assert_true(w->n < MAXS);
    const uint32_t i = w->n++;
    snprintf(w->path[i], sizeof w->path[i], "%s", path);
    assert_int_equal(glow_bake_load_file(ctx, path, &w->bake[i]), GLOW_OK);
    glow_host_desc hd = glow_host_desc_from_scene(&scene, w->bake[i], GLOW_HOST_KIND_EXACT);
    assert_int_equal(glow_host_create(&hd, &w->host[i]), GLOW_OK);
    assert_int_equal(glow_system_create(ctx,
                                        &(glow_system_desc){.bake = w->bake[i], .lighting = glow_host_hooks(w->host[i]),
                                                            .label = path},
                                        &w->sys[i]),
                     GLOW_OK);
    glow_system_params p = GLOW_SYSTEM_PARAMS_INIT;
    p.bounce_iterations = 4;
    assert_int_equal(glow_system_set_params(w->sys[i], &p), GLOW_OK);
}

static void close_world(world *w) {
    for (uint32_t i = 0; i < w->n; ++i) { /* detach everything first: a system others read is not destroyed */
        glow_bake_info bi;
        glow_bake_get_info(w->bake[i], &bi);
        for (uint32_t d = 0; d < bi.dependency_count; ++d) assert_int_equal(glow_system_set_neighbour(w->sys[i], d, NULL), GLOW_OK);
    }
    for (uint32_t i = 0; i < w->n; ++i) {
        glow_system_destroy(w->sys[i]);
        glow_host_destroy(w->host[i]);
        glow_bake_destroy(w->bake[i]);
    }
    memset(w, 0, sizeof *w);
}

/* the world's systems, as a host finds them without the manifest: every bake beside it whose name
 * starts with prefix (a manifest M.json names its systems M.s*) */
static void open_world_named(world *w, const char *prefix) {
    memset(w, 0, sizeof *w);
    DIR *d = opendir(dir);
    assert_non_null(d);
    char names[MAXS][200];
    uint32_t n = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0 && strstr(e->d_name, ".glow") && n < MAXS &&
            strlen(e->d_name) < 200)
            memcpy(names[n++], e->d_name, strlen(e->d_name) + 1);
    closedir(d);
    qsort(names, n, sizeof names[0], (int (*)(const void *, const void *))strcmp);
    for (uint32_t i = 0; i < n; ++i) {
        char p[600];
        snprintf(p, sizeof p, "%s/%.199s", dir, names[i]);
        open_system(w, p);
    }
}

static void open_world(world *w) { open_world_named(w, "w.s"); }

/* attach (or detach) every dependency by key; returns how many links were made */
static uint32_t attach_all(world *w, bool on) {
    uint32_t made = 0;
    for (uint32_t i = 0; i < w->n; ++i) {
        glow_bake_info bi;
        assert_int_equal(glow_bake_get_info(w->bake[i], &bi), GLOW_OK);
        for (uint32_t d = 0; d < bi.dependency_count; ++d) {
            uint64_t key = 0;
            assert_int_equal(glow_bake_get_dependency(w->bake[i], d, &key), GLOW_OK);
            glow_system *nb = NULL;
            for (uint32_t j = 0; j < w->n; ++j) {
                glow_bake_info bj;
                glow_bake_get_info(w->bake[j], &bj);
                if (bj.system_key == key) nb = w->sys[j];
            }
            assert_non_null(nb); /* every dependency is a system of this world */
            assert_int_equal(glow_system_set_neighbour(w->sys[i], d, on ? nb : NULL), GLOW_OK);
            made++;
        }
    }
    return made;
}

/* mean Y (SH DC) of every lightmap cache of the world after `rounds` updates of each system in turn */
static double run(world *w, uint32_t rounds) {
    for (uint32_t r = 0; r < rounds; ++r)
        for (uint32_t i = 0; i < w->n; ++i) assert_int_equal(glow_system_update(w->sys[i], NULL), GLOW_OK);
    double sum = 0.0;
    uint64_t count = 0;
    for (uint32_t i = 0; i < w->n; ++i) {
        const glow_cache_outputs *o = glow_system_outputs(w->sys[i]);
        for (uint32_t c = o->grid_cache_count; c < o->cache_count; ++c) {
            const float y = o->cache_sh[(size_t)c * o->coeff_count];
            assert_true(isfinite(y));
            sum += y;
            count++;
        }
    }
    assert_true(count > 0);
    return sum / (double)count;
}

static void test_light_crosses_systems(void **state) {
    (void)state;
    char out[300];
    glow_pc_stats st;
    snprintf(out, sizeof out, "%s/w.json", dir);
    glow_pc_settings s = settings(100.0f);
    assert_int_equal(glow_pc_bake("builtin:pillar-hall", out, &s, &st), GLOW_OK);
    assert_true(st.systems >= 4);
    assert_true(st.dependencies >= 4); /* each system links at least one neighbour */
    assert_true(st.proxies > 0);

    /* the one-system bake at the same density: 1024 surfels and 300 texels per 100 m² */
    char one[300];
    snprintf(one, sizeof one, "%s/one.glow", dir);
    glow_pc_settings s1 = settings(0.0f);
    s1.surfels = (uint32_t)lround(1024.0 * st.scene_area / 100.0);
    s1.lightmap_caches = (uint32_t)lround(300.0 * st.scene_area / 100.0);
    glow_pc_stats st1;
    assert_int_equal(glow_pc_bake("builtin:pillar-hall", one, &s1, &st1), GLOW_OK);
    world single;
    memset(&single, 0, sizeof single);
    open_system(&single, one);
    glow_bake_info b1;
    glow_bake_get_info(single.bake[0], &b1);
    assert_true(b1.system_key == 0 && b1.dependency_count == 0 && b1.proxy_count == 0); /* no world, no XREF */
    const double e_one = run(&single, 3);
    close_world(&single);

    world w;
    open_world(&w);
    assert_int_equal(w.n, st.systems);
    for (uint32_t i = 0; i < w.n; ++i) {
        glow_bake_info bi;
        glow_bake_get_info(w.bake[i], &bi);
        assert_int_equal(bi.format_major, 1);
        assert_int_equal(bi.format_minor, GLOW_BAKE_FORMAT_VERSION_MINOR); /* 1.4 XREF or later */
        assert_true(bi.system_key != 0);
    }
    const double e_alone = run(&w, 3); /* nothing attached: each system alone, its neighbours dark */
    close_world(&w);
    open_world(&w);
    assert_true(attach_all(&w, true) >= 4);
    const double e_world = run(&w, 3);
    print_message("mean lightmap-cache luma: one system %.5f, world of %u alone %.5f, with neighbours %.5f\n", e_one,
                  w.n, e_alone, e_world);
    assert_true(e_alone < e_one);                                   /* the borders lose light ... */
    assert_true(e_world > e_alone);                                 /* ... which the neighbours bring back */
    assert_true(fabs(e_world - e_one) < 0.5 * fabs(e_alone - e_one)); /* at least half of it */

    /* Clustered visibility against one ray per leaf, the same world: a neighbour's subtree across the
     * box in which a system's rays see every occluder is a cluster whose leaves beyond the box add
     * nothing (links.c, trace_box); crediting them (the part's ray decides them) read 2.6 % high here. */
    {
        world x;
        char xout[300];
        snprintf(xout, sizeof xout, "%s/x.json", dir);
        glow_pc_settings sx = settings(100.0f);
        sx.link_visibility = GLOW_PC_LINK_VISIBILITY_EXACT;
        glow_pc_stats stx;
        assert_int_equal(glow_pc_bake("builtin:pillar-hall", xout, &sx, &stx), GLOW_OK);
        open_world_named(&x, "x.s");
        assert_int_equal(x.n, stx.systems);
        assert_true(attach_all(&x, true) >= 4);
        const double e_exact = run(&x, 3);
        close_world(&x);
        print_message("with neighbours, exact visibility %.5f, clustered %.5f (%+.2f %%)\n", e_exact, e_world,
                      100.0 * (e_world - e_exact) / e_exact);
        assert_true(fabs(e_world - e_exact) < 0.01 * e_exact);
    }

    /* the fallback: detached neighbours' proxies keep their last radiance */
    world *W = &w;
    const double before = run(W, 1);
    attach_all(W, false);
    const double after = run(W, 1);
    print_message("converged %.6f, after detaching %.6f\n", before, after);
    assert_true(fabs(after - before) <= 1e-3 * before);

    /* errors */
    glow_bake_info b0;
    glow_bake_get_info(W->bake[0], &b0);
    assert_int_equal(glow_system_set_neighbour(W->sys[0], b0.dependency_count, W->sys[1]), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_system_set_neighbour(W->sys[0], 0, W->sys[0]), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_system_set_neighbour(NULL, 0, W->sys[0]), GLOW_ERROR_INVALID_ARGUMENT);
    uint64_t k0 = 0;
    assert_int_equal(glow_bake_get_dependency(W->bake[0], 0, &k0), GLOW_OK);
    assert_int_equal(glow_bake_get_dependency(W->bake[0], b0.dependency_count, &k0), GLOW_ERROR_INVALID_ARGUMENT);
    uint32_t wrong = UINT32_MAX, right = UINT32_MAX;
    for (uint32_t j = 1; j < W->n; ++j) {
        glow_bake_info bj;
        glow_bake_get_info(W->bake[j], &bj);
        if (bj.system_key == k0) right = j;
        else wrong = j;
    }
    assert_true(right != UINT32_MAX);
    if (wrong != UINT32_MAX) assert_int_equal(glow_system_set_neighbour(W->sys[0], 0, W->sys[wrong]), GLOW_ERROR_INVALID_ARGUMENT);
    /* a system another reads is not destroyed; once detached it is */
    assert_int_equal(glow_system_set_neighbour(W->sys[0], 0, W->sys[right]), GLOW_OK);
    glow_system_destroy(W->sys[right]);
    glow_update_stats us;
    assert_int_equal(glow_system_get_stats(W->sys[right], &us), GLOW_OK); /* still alive */
    close_world(W);
}

/* glow_world: the same systems added to a world attach themselves by key and update in the order they
 * were added, as attach_all + run do by hand (the same light); a system streamed out leaves its
 * dependents its last radiance and may be destroyed; streamed in again, it is attached again. */
static void test_world_api(void **state) {
    (void)state;
    world ref, w;
    open_world(&ref);
    assert_true(attach_all(&ref, true) > 0);
    const double e_ref = run(&ref, 3);
    close_world(&ref);

    open_world(&w);
    uint32_t deps = 0;
    for (uint32_t i = 0; i < w.n; ++i) {
        glow_bake_info bi;
        glow_bake_get_info(w.bake[i], &bi);
        deps += bi.dependency_count;
    }
    glow_world *W = NULL;
    assert_int_equal(glow_world_create(ctx, 0, &W), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(W);
    assert_int_equal(glow_world_create(ctx, w.n, &W), GLOW_OK);
    glow_world_stats ws;
    for (uint32_t i = 0; i < w.n; ++i) {
        assert_int_equal(glow_world_add(W, w.sys[i]), GLOW_OK);
        assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
        assert_int_equal(ws.systems, i + 1);
    }
    assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
    assert_int_equal(ws.dependencies_attached, deps); /* every dependency is a member */
    assert_int_equal(ws.dependencies_missing, 0);
    assert_int_equal(glow_world_system_count(W), w.n);
    assert_ptr_equal(glow_world_system(W, 1), w.sys[1]);
    assert_null(glow_world_system(W, w.n));
    /* refused: a second add, NULL, a full world */
    assert_int_equal(glow_world_add(W, w.sys[0]), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_world_add(W, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_world_remove(W, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_world_update(NULL, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    glow_world *one = NULL;
    assert_int_equal(glow_world_create(ctx, 1, &one), GLOW_OK);
    assert_int_equal(glow_world_add(one, w.sys[2]), GLOW_OK);
    assert_int_equal(glow_world_add(one, w.sys[3]), GLOW_ERROR_INVALID_OPERATION); /* full */
    glow_world_destroy(one);
    for (uint32_t r = 0; r < 3; ++r) assert_int_equal(glow_world_update(W, NULL), GLOW_OK);
    const double e_api = run(&w, 0);
    print_message("glow_world: %u systems, %u dependencies; mean lightmap-cache luma %.6f (by hand %.6f)\n", w.n,
                  deps, e_api, e_ref);
    assert_true(fabs(e_api - e_ref) <= 1e-6 * e_ref);
    assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
    assert_int_equal(ws.last_update.updates, 3);
    assert_true(ws.last_update.caches_gathered > 0 && ws.last_update.total_ms > 0.0);

    /* stream system 1 out: detached both ways, then destroyed (a system another reads would not be) */
    glow_bake_info b1;
    glow_bake_get_info(w.bake[1], &b1);
    assert_int_equal(glow_world_remove(W, w.sys[1]), GLOW_OK);
    assert_int_equal(glow_world_remove(W, w.sys[1]), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
    assert_int_equal(ws.systems, w.n - 1);
    assert_int_equal(ws.dependencies_attached + b1.dependency_count + ws.dependencies_missing, deps);
    assert_true(ws.dependencies_missing > 0); /* the pillar hall's systems all see each other */
    glow_system_destroy(w.sys[1]);
    w.sys[1] = NULL;
    for (uint32_t r = 0; r < 2; ++r) assert_int_equal(glow_world_update(W, NULL), GLOW_OK); /* reads no freed memory */
    /* and in again, as a new system from the same bake */
    assert_int_equal(glow_system_create(ctx,
                                        &(glow_system_desc){.bake = w.bake[1], .lighting = glow_host_hooks(w.host[1]),
                                                            .label = w.path[1]},
                                        &w.sys[1]),
                     GLOW_OK);
    glow_system_params p = GLOW_SYSTEM_PARAMS_INIT;
    p.bounce_iterations = 4;
    assert_int_equal(glow_system_set_params(w.sys[1], &p), GLOW_OK);
    assert_int_equal(glow_world_add(W, w.sys[1]), GLOW_OK);
    assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
    assert_int_equal(ws.dependencies_attached, deps);
    assert_int_equal(ws.dependencies_missing, 0);
    /* a system never updated updates under any time budget (it has no light yet), first, and under a
     * budget that it spends alone, alone (until 2026-11-30 it updated besides the members' first) */
    assert_int_equal(glow_world_update(W, &(glow_update_desc){.budget_ms = 1e-3f}), GLOW_OK);
    glow_update_stats fresh;
    glow_system_get_stats(w.sys[1], &fresh);
    assert_int_equal(fresh.updates, 1);
    assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
    assert_int_equal(ws.systems_updated, 1);
    for (uint32_t r = 0; r < 3; ++r) assert_int_equal(glow_world_update(W, NULL), GLOW_OK);
    const double e_back = run(&w, 0);
    print_message("streamed out and in again: %.6f\n", e_back);
    assert_true(fabs(e_back - e_ref) <= 0.02 * e_ref);
    /* a caches budget shared between the members */
    assert_int_equal(glow_world_update(W, &(glow_update_desc){.max_caches = 64}), GLOW_OK);
    assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
    assert_true(ws.last_update.caches_skipped_budget > 0);
    /* a time budget far too small for one member: one member a frame, the one nearest the focus first,
     * then the stalest in turn: a member far from it waits at most about 5x as long as one beside it
     * (priority (staleness + 1) x (1 + 4 f)), so none starves */
    uint64_t seen[MAXS];
    glow_bake_info bf;
    glow_bake_get_info(w.bake[2], &bf);
    float focus[3];
    for (int k = 0; k < 3; ++k) focus[k] = 0.5f * (bf.bounds_min[k] + bf.bounds_max[k]);
    for (uint32_t i = 0; i < w.n; ++i) {
        glow_update_stats us;
        glow_system_get_stats(w.sys[i], &us);
        seen[i] = us.updates;
    }
    const glow_update_desc tiny = {.budget_ms = 1e-3f, .focus = focus, .focus_count = 1};
    assert_int_equal(glow_world_update(W, &tiny), GLOW_OK);
    assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
    assert_int_equal(ws.systems_updated, 1);
    assert_true(ws.last_update.caches_skipped_budget > 0);
    for (uint32_t i = 0; i < w.n; ++i) {
        glow_update_stats us;
        glow_system_get_stats(w.sys[i], &us);
        assert_int_equal(us.updates, seen[i] + (i == 2 ? 1u : 0u)); /* the focus's system */
    }
    for (uint32_t f = 0; f < 6 * w.n; ++f) assert_int_equal(glow_world_update(W, &tiny), GLOW_OK);
    for (uint32_t i = 0; i < w.n; ++i) {
        glow_update_stats us;
        glow_system_get_stats(w.sys[i], &us);
        assert_true(us.updates > seen[i]); /* every member got its turn */
    }
    /* two systems streamed in at once under that budget: one a frame, in the order added, each before
     * any member that has light; so a stream-in never adds a second system's fixed cost to a frame */
    assert_int_equal(glow_world_remove(W, w.sys[3]), GLOW_OK);
    assert_int_equal(glow_world_remove(W, w.sys[0]), GLOW_OK);
    assert_int_equal(glow_world_add(W, w.sys[3]), GLOW_OK);
    assert_int_equal(glow_world_add(W, w.sys[0]), GLOW_OK);
    for (uint32_t i = 0; i < w.n; ++i) {
        glow_update_stats us;
        glow_system_get_stats(w.sys[i], &us);
        seen[i] = us.updates;
    }
    for (uint32_t f = 0; f < 2; ++f) {
        assert_int_equal(glow_world_update(W, &tiny), GLOW_OK);
        assert_int_equal(glow_world_get_stats(W, &ws), GLOW_OK);
        assert_int_equal(ws.systems_updated, 1);
        for (uint32_t i = 0; i < w.n; ++i) {
            glow_update_stats us;
            glow_system_get_stats(w.sys[i], &us);
            assert_int_equal(us.updates, seen[i] + ((i == 3) || (f == 1 && i == 0) ? 1u : 0u));
        }
    }
    assert_int_equal(glow_world_update(W, &(glow_update_desc){.budget_ms = -1.0f}), GLOW_ERROR_INVALID_ARGUMENT);
    glow_world_destroy(W); /* detaches everything: the systems can go */
    close_world(&w);
}

/* glow_host_desc.occluders: a system's host shadowed by its neighbours' geometry too. The hall's point
 * light reaches a system's surfels past pillars and walls that are other systems': with the neighbours
 * as occluders no surfel gets more direct light than without, and some get less. */
static void test_host_occluders(void **state) {
    (void)state;
    world w;
    open_world(&w);
    uint32_t darker_systems = 0;
    for (uint32_t i = 0; i < w.n; ++i) {
        glow_bake_info bi;
        glow_bake_get_info(w.bake[i], &bi);
        const glow_bake *occ[MAXS];
        uint32_t nocc = 0;
        for (uint32_t d = 0; d < bi.dependency_count; ++d) {
            uint64_t key = 0;
            assert_int_equal(glow_bake_get_dependency(w.bake[i], d, &key), GLOW_OK);
            for (uint32_t j = 0; j < w.n; ++j) {
                glow_bake_info bj;
                glow_bake_get_info(w.bake[j], &bj);
                if (bj.system_key == key) occ[nocc++] = w.bake[j];
            }
        }
        assert_true(nocc == bi.dependency_count);
        /* one ray per surfel on both sides: footprint points are chosen with the occluders' walls too,
         * so with footprints the two hosts would sample different points (glow_host.h FOOTPRINTS) */
        glow_host_desc hd = glow_host_desc_from_scene(&scene, w.bake[i], GLOW_HOST_KIND_EXACT);
        hd.surfel_samples = 1;
        glow_host *h_alone = NULL;
        assert_int_equal(glow_host_create(&hd, &h_alone), GLOW_OK);
        hd.occluders = occ;
        hd.occluder_count = nocc;
        glow_host *h = NULL;
        assert_int_equal(glow_host_create(&hd, &h), GLOW_OK);
        glow_host_stats hs0, hs1;
        glow_host_get_stats(h_alone, &hs0);
        glow_host_get_stats(h, &hs1);
        assert_int_equal(hs1.triangle_count, hs0.triangle_count); /* its own geometry's */
        assert_true(hs1.epsilon == hs0.epsilon);
        glow_surfel_view sv;
        assert_int_equal(glow_system_get_surfels(w.sys[i], &sv), GLOW_OK);
        float *a = malloc((size_t)sv.count * 3 * sizeof *a), *b = malloc((size_t)sv.count * 3 * sizeof *b);
        assert_non_null(a);
        assert_non_null(b);
        const glow_surfel_batch batch = {0, sv.count, sv.positions, sv.normals, sv.materials};
        const glow_lighting_hooks alone = glow_host_hooks(h_alone), with = glow_host_hooks(h);
        assert_int_equal(alone.light_surfels(alone.user, &batch, a, 0), GLOW_OK);
        assert_int_equal(with.light_surfels(with.user, &batch, b, 0), GLOW_OK);
        uint32_t darker = 0;
        for (size_t k = 0; k < 3 * (size_t)sv.count; ++k) {
            assert_true(b[k] <= a[k] * (1.0f + 1e-5f) + 1e-6f);
            darker += b[k] < 0.5f * a[k];
        }
        darker_systems += darker > 0;
        print_message("system %u: %u neighbours as occluders; %u of %u surfel channels at least halved\n", i, nocc,
                      darker, 3 * sv.count);
        free(a);
        free(b);
        glow_host_destroy(h);
        glow_host_destroy(h_alone);
    }
    assert_true(darker_systems > 0);
    glow_host_desc bad = glow_host_desc_from_scene(&scene, w.bake[0], GLOW_HOST_KIND_EXACT);
    bad.occluder_count = 2; /* and no array */
    glow_host *h = NULL;
    assert_int_equal(glow_host_create(&bad, &h), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(h);
    close_world(&w);
}

/* Resealed bakes (zlib's CRC-32 is the format's) with a bad XREF are refused at load */
static uint32_t crc32_of(const unsigned char *p, size_t n) { return (uint32_t)crc32(0L, p, (uInt)n); }

static void test_xref_validated(void **state) {
    (void)state;
    DIR *d = opendir(dir);
    assert_non_null(d);
    char path[600] = "";
    for (struct dirent *e; (e = readdir(d));)
        if (strncmp(e->d_name, "w.s", 3) == 0 && strstr(e->d_name, ".glow")) snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    closedir(d);
    assert_true(path[0]);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    const long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)size);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)size, f), (size_t)size);
    fclose(f);
    glow_bake_header h;
    memcpy(&h, buf, sizeof h);
    glow_bake_section *tab = (glow_bake_section *)(void *)(buf + sizeof h);
    uint32_t x = UINT32_MAX;
    for (uint32_t i = 0; i < h.section_count; ++i)
        if (tab[i].fourcc == GLOW_SECTION_XREF) x = i;
    assert_true(x != UINT32_MAX);
    glow_bake_xref xh;
    memcpy(&xh, buf + tab[x].offset, sizeof xh);
    assert_true(xh.proxy_count > 0);
    glow_bake_xref_proxy *px = (glow_bake_xref_proxy *)(void *)(buf + tab[x].offset + sizeof xh + 8u * xh.dependency_count);
    unsigned char *orig = malloc((size_t)size);
    assert_non_null(orig);
    memcpy(orig, buf, (size_t)size);
    /* reseal: the section's CRC, the table's and the header's */
#define RESEAL()                                                                                  \
    do {                                                                                          \
        tab[x].crc32 = crc32_of(buf + tab[x].offset, (size_t)tab[x].size);                         \
        h.table_crc32 = crc32_of((const unsigned char *)tab, (size_t)h.section_count * sizeof *tab); \
        h.header_crc32 = 0;                                                                       \
        memcpy(buf, &h, sizeof h);                                                                \
        h.header_crc32 = crc32_of(buf, sizeof h);                                                 \
        memcpy(buf, &h, sizeof h);                                                                \
    } while (0)
    glow_bake *b = NULL;
    RESEAL(); /* unchanged: loads */
    assert_int_equal(glow_bake_load(ctx, buf, (size_t)size, &b), GLOW_OK);
    glow_bake_destroy(b);
    b = NULL;
    px[0].dependency = xh.dependency_count; /* a dependency out of range */
    RESEAL();
    assert_int_equal(glow_bake_load(ctx, buf, (size_t)size, &b), GLOW_ERROR_OUT_OF_RANGE);
    assert_null(b);
    memcpy(buf, orig, (size_t)size);
    memcpy(&h, buf, sizeof h);
    glow_bake_xref bad = xh;
    bad.proxy_count = xh.proxy_count - 1; /* counts that do not match the section's size */
    memcpy(buf + tab[x].offset, &bad, sizeof bad);
    RESEAL();
    assert_int_equal(glow_bake_load(ctx, buf, (size_t)size, &b), GLOW_ERROR_CORRUPT_DATA);
    assert_null(b);
    memcpy(buf, orig, (size_t)size);
    memcpy(&h, buf, sizeof h);
    bad = xh;
    bad.dependency_count = GLOW_BAKE_MAX_DEPENDENCIES + 1; /* too many dependencies */
    memcpy(buf + tab[x].offset, &bad, sizeof bad);
    RESEAL();
    assert_int_equal(glow_bake_load(ctx, buf, (size_t)size, &b), GLOW_ERROR_CORRUPT_DATA);
    assert_null(b);
#undef RESEAL
    free(orig);
    free(buf);
}

static int setup(void **state) {
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/glow_test_world_XXXXXX");
    if (!mkdtemp(dir)) return -1;
    if (glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION}, &ctx) != GLOW_OK) return -1;
    return glow_scene_load(scene_json, NULL, &scene, NULL, 0) == GLOW_OK ? 0 : -1;
}

static int teardown(void **state) {
    (void)state;
    glow_scene_free(&scene);
    glow_context_destroy(ctx);
    DIR *d = opendir(dir);
    if (d) {
        for (struct dirent *e; (e = readdir(d));) {
            if (e->d_name[0] == '.') continue;
            char p[600];
            snprintf(p, sizeof p, "%s/%.200s", dir, e->d_name);
            remove(p);
        }
        closedir(d);
    }
    rmdir(dir);
    return 0;
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_light_crosses_systems),
        cmocka_unit_test(test_world_api),
        cmocka_unit_test(test_host_occluders),
        cmocka_unit_test(test_xref_validated),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
