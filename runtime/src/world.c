/* world.c — glow_world: the systems of a world (glow-bake --system-area) that a host has loaded,
 * attached to each other by key as they come and go, and updated together (issue 17, item 1).
 *
 * A world holds borrowed systems (the host creates and destroys them) in a fixed-capacity array
 * allocated at create, so adding, removing and updating allocate nothing: a host streams systems in
 * and out between frames. Adding a system attaches it to every member it depends on and every member
 * that depends on it (glow_system_set_neighbour, checked by key); removing one detaches both ways, so
 * its dependents keep its last radiance (the documented fallback) and the host may destroy it. An
 * update updates the members one after another in the order they were added, each with every worker
 * of the context: light crosses a border with one update of lag, as between two systems attached by
 * hand. A caches budget (max_caches) is shared between the members in proportion to their caches; a
 * time budget (budget_ms) goes to the members by priority (schedule, below); the focus points go to
 * every member. */
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "runtime_internal.h"

typedef struct member_state {
    uint32_t stale;  /* world updates since it was last updated */
    double est_ms;   /* what a budget cannot cut of its last update (glow__system_uncut_ms: all but the
                        cache gathers and the hook's batches beyond its fewest); 0 = never updated */
    float lo[3], hi[3]; /* its bake's bounds */
} member_state;

struct glow_world {
    glow_context *ctx;
    uint32_t capacity, count;
    glow_system **sys;  /* [capacity], in the order they were added */
    uint64_t *key;      /* [capacity] each member's bake system_key (0: not a system of a world) */
    member_state *ms;   /* [capacity] */
    uint32_t *order;    /* [capacity] scratch: the members by priority */
    double *prio;       /* [capacity] scratch */
    glow_update_stats stats;
    uint32_t attached;  /* dependencies currently attached over all members */
    uint32_t missing;   /* dependencies whose system is not a member */
    uint32_t updated;   /* members the last update updated */
    double diag;        /* the diagonal of the members' bounds (recount) */
};

static void free_world(glow_world *w) {
    glow_context *ctx = w->ctx;
    glow__ctx_free(ctx, w->sys);
    glow__ctx_free(ctx, w->key);
    glow__ctx_free(ctx, w->ms);
    glow__ctx_free(ctx, w->order);
    glow__ctx_free(ctx, w->prio);
    glow__ctx_free(ctx, w);
}

glow_result glow_world_create(glow_context *ctx, uint32_t capacity, glow_world **out) {
    if (out) *out = NULL;
    if (!ctx || !out || capacity == 0 || capacity > (1u << 20)) {
        GLOW__LOG_ERROR(ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_world_create: %s",
                        !out ? "NULL out" : "capacity must be 1..1048576 systems");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_world *w = glow__ctx_alloc(ctx, sizeof *w, 0);
    if (!w) goto oom;
    memset(w, 0, sizeof *w);
    w->ctx = ctx;
    w->capacity = capacity;
    w->sys = glow__ctx_alloc(ctx, (size_t)capacity * sizeof *w->sys, 0);
    w->key = glow__ctx_alloc(ctx, (size_t)capacity * sizeof *w->key, 0);
    w->ms = glow__ctx_alloc(ctx, (size_t)capacity * sizeof *w->ms, 0);
    w->order = glow__ctx_alloc(ctx, (size_t)capacity * sizeof *w->order, 0);
    w->prio = glow__ctx_alloc(ctx, (size_t)capacity * sizeof *w->prio, 0);
    if (!w->sys || !w->key || !w->ms || !w->order || !w->prio) {
        free_world(w);
        goto oom;
    }
    *out = w;
    return GLOW_OK;
oom:
    GLOW__LOG_ERROR(ctx, GLOW_ERROR_OUT_OF_MEMORY, "glow_world_create: out of memory for %u systems", capacity);
    return GLOW_ERROR_OUT_OF_MEMORY;
}

static uint32_t find(const glow_world *w, const glow_system *s) {
    for (uint32_t i = 0; i < w->count; ++i)
        if (w->sys[i] == s) return i;
    return UINT32_MAX;
}

/* Counts the members' dependencies that are attached and those whose system is absent, and measures
 * the members' bounds (the focus radius's default). After every add and remove. */
static void recount(glow_world *w) {
    w->attached = w->missing = 0;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < w->count; ++i)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fminf(lo[k], w->ms[i].lo[k]);
            hi[k] = fmaxf(hi[k], w->ms[i].hi[k]);
        }
    double diag2 = 0.0;
    for (int k = 0; w->count && k < 3; ++k) diag2 += (double)(hi[k] - lo[k]) * (hi[k] - lo[k]);
    w->diag = sqrt(diag2);
    for (uint32_t i = 0; i < w->count; ++i) {
        const glow_bake *b = glow__system_bake(w->sys[i]);
        glow_bake_info bi;
        glow_bake_get_info(b, &bi);
        for (uint32_t d = 0; d < bi.dependency_count; ++d) {
            uint64_t k = 0;
            glow_bake_get_dependency(b, d, &k);
            bool present = false;
            for (uint32_t j = 0; j < w->count && !present; ++j) present = j != i && w->key[j] == k;
            if (present) w->attached++;
            else w->missing++;
        }
    }
}

/* Attaches (nb != NULL) or detaches every dependency of `s` whose key is `key`. */
static glow_result link_key(glow_system *s, uint64_t key, glow_system *nb) {
    const glow_bake *b = glow__system_bake(s);
    glow_bake_info bi;
    glow_bake_get_info(b, &bi);
    for (uint32_t d = 0; d < bi.dependency_count; ++d) {
        uint64_t k = 0;
        glow_bake_get_dependency(b, d, &k);
        if (k != key) continue;
        glow_result r = glow_system_set_neighbour(s, d, nb);
        if (r != GLOW_OK) return r;
    }
    return GLOW_OK;
}

glow_result glow_world_add(glow_world *w, glow_system *s) {
    if (!w || !s) {
        if (w) GLOW__LOG_ERROR(w->ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_world_add: NULL system");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (find(w, s) != UINT32_MAX) {
        GLOW__LOG_ERROR(w->ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_world_add(%s): already in the world",
                        glow__system_label(s));
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (w->count == w->capacity) {
        GLOW__LOG_ERROR(w->ctx, GLOW_ERROR_INVALID_OPERATION,
                        "glow_world_add(%s): the world is full (%u systems; glow_world_create's capacity)",
                        glow__system_label(s), w->capacity);
        return GLOW_ERROR_INVALID_OPERATION;
    }
    glow_bake_info bi;
    glow_bake_get_info(glow__system_bake(s), &bi);
    for (uint32_t j = 0; bi.system_key && j < w->count; ++j)
        if (w->key[j] == bi.system_key) {
            GLOW__LOG_ERROR(w->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                            "glow_world_add(%s): %s is the same system (key %016llx): one system per key",
                            glow__system_label(s), glow__system_label(w->sys[j]), (unsigned long long)bi.system_key);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    /* both ways: its dependencies among the members, and the members that depend on it */
    glow_result r = GLOW_OK;
    for (uint32_t j = 0; j < w->count && r == GLOW_OK; ++j) {
        if (w->key[j]) r = link_key(s, w->key[j], w->sys[j]);
        if (r == GLOW_OK && bi.system_key) r = link_key(w->sys[j], bi.system_key, s);
    }
    if (r != GLOW_OK) { /* undo what was attached (a busy system or a forged bake) */
        for (uint32_t j = 0; j < w->count; ++j) {
            if (w->key[j]) (void)link_key(s, w->key[j], NULL);
            if (bi.system_key) (void)link_key(w->sys[j], bi.system_key, NULL);
        }
        return r;
    }
    w->sys[w->count] = s;
    w->key[w->count] = bi.system_key;
    w->ms[w->count] = (member_state){.stale = 0, .est_ms = 0.0};
    memcpy(w->ms[w->count].lo, bi.bounds_min, sizeof w->ms[w->count].lo);
    memcpy(w->ms[w->count].hi, bi.bounds_max, sizeof w->ms[w->count].hi);
    w->count++;
    recount(w);
    return GLOW_OK;
}

glow_result glow_world_remove(glow_world *w, glow_system *s) {
    if (!w || !s) {
        if (w) GLOW__LOG_ERROR(w->ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_world_remove: NULL system");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t i = find(w, s);
    if (i == UINT32_MAX) {
        GLOW__LOG_ERROR(w->ctx, GLOW_ERROR_INVALID_ARGUMENT, "glow_world_remove(%s): not in the world",
                        glow__system_label(s));
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_result r = GLOW_OK;
    for (uint32_t j = 0; j < w->count && r == GLOW_OK; ++j) {
        if (j == i) continue;
        if (w->key[i]) r = link_key(w->sys[j], w->key[i], NULL); /* they keep its last radiance */
        if (r == GLOW_OK && w->key[j]) r = link_key(s, w->key[j], NULL);
    }
    if (r != GLOW_OK) return r; /* only while a member updates: nothing else can fail to detach */
    memmove(w->sys + i, w->sys + i + 1, (size_t)(w->count - i - 1) * sizeof *w->sys);
    memmove(w->key + i, w->key + i + 1, (size_t)(w->count - i - 1) * sizeof *w->key);
    memmove(w->ms + i, w->ms + i + 1, (size_t)(w->count - i - 1) * sizeof *w->ms);
    w->count--;
    recount(w);
    return GLOW_OK;
}

void glow_world_destroy(glow_world *w) {
    if (!w) return;
    while (w->count) (void)glow_world_remove(w, w->sys[w->count - 1]);
    free_world(w);
}

uint32_t glow_world_system_count(const glow_world *w) { return w ? w->count : 0u; }

glow_system *glow_world_system(const glow_world *w, uint32_t index) {
    return w && index < w->count ? w->sys[index] : NULL;
}

static void add_stats(glow_update_stats *sum, const glow_update_stats *st) {
    sum->surfel_lighting_ms += st->surfel_lighting_ms;
    sum->host_ms += st->host_ms;
    sum->pull_ms += st->pull_ms;
    sum->cache_lighting_ms += st->cache_lighting_ms;
    sum->output_ms += st->output_ms;
    sum->total_ms += st->total_ms;
    sum->links += st->links;
    sum->caches_gathered += st->caches_gathered;
    sum->caches_skipped_budget += st->caches_skipped_budget;
    sum->caches_skipped_converged += st->caches_skipped_converged;
    sum->outputs_skipped += st->outputs_skipped;
    sum->surfels_skipped_budget += st->surfels_skipped_budget;
    sum->link_mode = st->link_mode;
    sum->kernel = st->kernel;
}

/* A time budget (budget_ms): the members by priority, each (staleness + 1) x (1 + 4 f), f the largest
 * over the focus points of 1 / (1 + d^2 / r^2), d the distance from the point to the member's bounds
 * (0 inside), r the focus radius (0: a tenth of the members' bounds diagonal), as the groups of caches
 * within a system (glow_update_desc); ties by order added. The first always updates, with the whole
 * budget as its own; each next one only when the part of its last update that a budget cannot cut
 * (all but the cache gathers and the hook's batches beyond its fewest) fits what is left, with what
 * is left as its budget (its gathers take the rest). A member never updated (just streamed in: no light yet) comes first, before any
 * priority, and is held to the same rule with its time estimated from the members that have one (the
 * mean of their times per cache, times its caches); while no member has a time (the world's first
 * update) every member updates. Before 2026-11-30 a member never updated always updated wherever it
 * stood, so a system streamed in under a time budget added its whole fixed part to a budget already
 * spent. The others keep their outputs and count as skipped (their caches in caches_skipped_budget). */
static void schedule(glow_world *w, const glow_update_desc *desc) {
    double r = desc->focus_radius > 0.0f ? desc->focus_radius : 0.1 * w->diag;
    if (!(r > 0.0)) r = 1.0;
    for (uint32_t i = 0; i < w->count; ++i) {
        double f = 0.0;
        for (uint32_t p = 0; p < desc->focus_count; ++p) {
            double d2 = 0.0;
            for (int k = 0; k < 3; ++k) {
                const double x = desc->focus[3 * p + k];
                const double e = x < w->ms[i].lo[k] ? w->ms[i].lo[k] - x : x > w->ms[i].hi[k] ? x - w->ms[i].hi[k] : 0.0;
                d2 += e * e;
            }
            f = fmax(f, 1.0 / (1.0 + d2 / (r * r)));
        }
        w->prio[i] = w->ms[i].est_ms == 0.0 ? INFINITY : (w->ms[i].stale + 1.0) * (1.0 + 4.0 * f);
        w->order[i] = i;
    }
    for (uint32_t i = 1; i < w->count; ++i) { /* insertion sort: stable, no allocation */
        const uint32_t v = w->order[i];
        uint32_t j = i;
        while (j > 0 && w->prio[w->order[j - 1]] < w->prio[v]) {
            w->order[j] = w->order[j - 1];
            --j;
        }
        w->order[j] = v;
    }
}

glow_result glow_world_update(glow_world *w, const glow_update_desc *desc) {
    if (!w) return GLOW_ERROR_INVALID_ARGUMENT;
    if (desc && (!(desc->budget_ms >= 0.0f) || !isfinite(desc->budget_ms) || !(desc->focus_radius >= 0.0f) ||
                 (desc->focus_count && !desc->focus))) {
        GLOW__LOG_ERROR(w->ctx, GLOW_ERROR_INVALID_ARGUMENT,
                        "glow_world_update: budget_ms and focus_radius must be finite and >= 0, focus given with focus_count");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    uint64_t caches = 0;
    for (uint32_t i = 0; i < w->count; ++i) caches += glow__system_cache_count(w->sys[i]);
    glow_update_stats sum;
    memset(&sum, 0, sizeof sum);
    glow_result first = GLOW_OK;
    const bool timed = desc && desc->budget_ms > 0.0f;
    if (timed) schedule(w, desc);
    double left = timed ? desc->budget_ms : 0.0;
    double known_ms = 0.0, known_caches = 0.0; /* the members with a time: a fresh member's estimate */
    for (uint32_t i = 0; timed && i < w->count; ++i)
        if (w->ms[i].est_ms > 0.0) {
            known_ms += w->ms[i].est_ms;
            known_caches += glow__system_cache_count(w->sys[i]);
        }
    w->updated = 0;
    for (uint32_t n = 0; n < w->count; ++n) {
        const uint32_t i = timed ? w->order[n] : n;
        glow_update_desc d = desc ? *desc : (glow_update_desc){0};
        if (timed) {
            double est = w->ms[i].est_ms;
            if (est == 0.0) /* never updated: no time yet (and no light), estimated from the others' */
                est = known_ms > 0.0 ? known_ms / fmax(known_caches, 1.0) * glow__system_cache_count(w->sys[i]) : 0.0;
            if (n > 0 && est > 0.0 && (left <= 0.0 || est > left)) { /* does not fit: keeps its outputs */
                w->ms[i].stale++;
                sum.caches_skipped_budget += glow__system_cache_count(w->sys[i]);
                sum.surfels_skipped_budget += glow__system_surfel_count(w->sys[i]);
                continue;
            }
            d.budget_ms = (float)fmax(left, 1e-3);
        }
        if (desc && desc->max_caches) { /* a caches budget: shared by caches */
            const double m = caches ? (double)desc->max_caches * glow__system_cache_count(w->sys[i]) / (double)caches : 0.0;
            d.max_caches = m < 1.0 ? 1u : (uint32_t)m;
        }
        const glow_result r = glow_system_update(w->sys[i], &d);
        if (r != GLOW_OK) { /* the others still update: one system's failed hook stops no one */
            if (first == GLOW_OK) first = r;
            w->ms[i].stale++;
            continue;
        }
        glow_update_stats st;
        glow_system_get_stats(w->sys[i], &st);
        add_stats(&sum, &st);
        w->ms[i].stale = 0;
        w->ms[i].est_ms = fmax(glow__system_uncut_ms(w->sys[i]), 1e-3);
        left -= st.total_ms;
        w->updated++;
    }
    for (uint32_t i = 0; i < w->count; ++i) { /* memory of every member, updated or not */
        glow_update_stats st;
        glow_system_get_stats(w->sys[i], &st);
        sum.memory_bytes += st.memory_bytes;
    }
    sum.updates = w->stats.updates + (first == GLOW_OK ? 1u : 0u);
    w->stats = sum;
    return first;
}

glow_result glow_world_get_stats(const glow_world *w, glow_world_stats *out) {
    if (!w || !out) return GLOW_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    out->systems = w->count;
    out->dependencies_attached = w->attached;
    out->dependencies_missing = w->missing;
    out->last_update = w->stats;
    out->systems_updated = w->updated;
    return GLOW_OK;
}
