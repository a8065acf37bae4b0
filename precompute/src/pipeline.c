/* pipeline.c — glow_pc_bake: import -> ray-tracing BVH -> surfels -> hierarchy -> caches -> links ->
 * bake file. Owns the presets, option validation, per-stage timing and peak memory, and the
 * serialisation of the in-memory results into the sections of bake_format.h. */
#include <fnmatch.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "bake_format.h"
#include "bake_write.h"
#include "hierarchy.h"
#include "pc_internal.h"
#include "grid_vis.h"

static const char *const stage_names[GLOW_PC_STAGE_COUNT] = {"import", "bvh", "surfels", "hierarchy",
                                                             "caches", "links", "write"};
enum { ST_IMPORT, ST_BVH, ST_SURFELS, ST_HIER, ST_CACHES, ST_LINKS, ST_WRITE };

const char *glow_pc_stage_name(uint32_t stage) { return stage < GLOW_PC_STAGE_COUNT ? stage_names[stage] : "?"; }

/* Clustered link visibility (links.c cluster_nodes; docs/linker.md "Clustered visibility"): the
 * largest a cluster may look from a cache (bounding radius / distance) and the rays it shares */
#define GLOW_PC_CLUSTER_ANGLE 0.3f
#define GLOW_PC_CLUSTER_RAYS 4u
/* The lightmap detail (links.c "Lightmap detail"; docs/results.md): detail texels per lightmap texel
 * side, links per detail texel and the radius (lightmap texels) of the surfels they reach */
#define GLOW_PC_LIGHTMAP_DETAIL 3u
#define GLOW_PC_LIGHTMAP_DETAIL_MAX 4u /* automatic: up to this many where open ground's texels are coarse */
#define GLOW_PC_DETAIL_LINKS 16u
#define GLOW_PC_DETAIL_RADIUS 1.0f

/* Rays per surfel and grid cache of the sky transfer (sky.c): the CPU host's sky_rays default, so that
 * the bake's constant-sky term is the host's S ray for ray (docs/sky.md, measurements) */
#define GLOW_PC_SKY_RAYS 128u
/* ... and this many times as many per grid cache: Sponza's grid V ⊗ L against 1024 rays, 8.4 % RMS at 128
 * rays (one Fibonacci set over the whole sphere, no cosine weighting), where the surfels' E is 0.5 %; the
 * grid has ~20x fewer caches than there are surfels (docs/sky.md) */
#define GLOW_PC_SKY_GRID_RAYS 8u

typedef struct preset {
    uint32_t surfels, links, bands, grid, lightmap, relax;
    float adapt; /* surfel density in concave places against open ground (surfels.c "adaptive
                  * density"); 1 = area-uniform. Sponza against the referee, surfel seeds 0-3: moderate
                  * 0.123 -> 0.102 with 4; low 0.199 -> 0.197 (seeds 0-1); fine 0.081 / 0.088 ->
                  * 0.099 / 0.090 (seeds 0 / 1): at 131k surfels the open ground it thins costs more
                  * than the creases gain, so high and fine stay area-uniform (docs/results.md) */
    float texel_adapt; /* the same for generated charts' texel density (caches.c, "texel density per
                        * chart"), within the same texel budget. Sponza against the referee: moderate
                        * 0.102 -> 0.097 with 4 (surfel seeds 0-3), low 0.197 -> 0.196, high 0.0803 ->
                        * 0.0805 (seed 0), fine 0.0846 / 0.0890 -> 0.0839 / 0.0935 (seeds 0 / 1): high
                        * and fine stay uniform, as their surfels do (docs/results.md) */
    uint32_t grid_refine; /* the grid's refinement near geometry (grid_fine.c) */
} preset;
static const preset presets[5] = {
    /* default = moderate */ {32768, 128, 3, 2000, 8000, 6, 4.0f, 4.0f, 1},
    /* low      */ {8192, 64, 3, 500, 2000, 4, 4.0f, 4.0f, 1},
    /* moderate: PIC's. Half the links on twice the lightmap caches (about the same links per bake)
     * was 4 % better on Sponza's block error averaged over 4 surfel seeds, 7 % worse on Cornell's, at
     * +11.5 % update time: not taken (docs/results.md, "More budget"); --lightmap-caches sets it */
    /* moderate */ {32768, 128, 3, 2000, 8000, 6, 4.0f, 4.0f, 1},
    /* high     */ {131072, 254, 4, 2000, 8000, 6, 1.0f, 1.0f, 1},
    /* fine: moderate's links, bands and lightmap on 4x its surfels (0.24 m apart on Sponza), with the
     * lightmap detail (the default) for the receivers. It resolves light from surfaces a fraction of a
     * metre away (pillar feet next to a sunlit floor, capitals): Sponza's block error 0.124 -> 0.088
     * (surfel seeds 0-3), at about 1.8x moderate's update time and 2.3x its memory. Until 2026-11-27 it
     * also had 4x moderate's lightmap caches (32000: 0.079 without the detail, 0.060 with it on seed 0,
     * at about 4x the update): --lightmap-caches 32000 (docs/results.md, "Near light") */
    /* fine     */ {131072, 128, 3, 2000, 8000, 6, 1.0f, 1.0f, 1},
};

static const preset *preset_of(glow_pc_quality q) {
    return (unsigned)q <= GLOW_PC_QUALITY_FINE ? &presets[q] : &presets[0];
}

glow_pc_settings glow_pc_settings_resolve(const glow_pc_settings *in) {
    glow_pc_settings s = in ? *in : (glow_pc_settings){0};
    const preset *p = preset_of(s.quality);
    if (s.quality == GLOW_PC_QUALITY_DEFAULT) s.quality = GLOW_PC_QUALITY_MODERATE;
    if (!s.surfels) s.surfels = p->surfels;
    if (!s.links) s.links = p->links;
    if (!s.bands) s.bands = p->bands;
    if (!s.relax_iterations) s.relax_iterations = p->relax;
    if (!s.lightmap_caches) s.lightmap_caches = p->lightmap;
    if (!s.rays_per_surfel) s.rays_per_surfel = 1;
    if (s.link_visibility == GLOW_PC_LINK_VISIBILITY_DEFAULT) s.link_visibility = GLOW_PC_LINK_VISIBILITY_CLUSTERED;
    if (s.link_cluster_angle == 0.0f) s.link_cluster_angle = GLOW_PC_CLUSTER_ANGLE;
    if (!s.link_cluster_rays) s.link_cluster_rays = GLOW_PC_CLUSTER_RAYS;
    /* lightmap_detail stays 0 (automatic: GLOW_PC_LIGHTMAP_DETAIL, up to GLOW_PC_LIGHTMAP_DETAIL_MAX where the
     * texels are coarse; caches.c) so that a system's key tells it from an explicit 3 */
    if (!s.detail_links) s.detail_links = GLOW_PC_DETAIL_LINKS;
    if (s.detail_radius == 0.0f) s.detail_radius = GLOW_PC_DETAIL_RADIUS;
    if (s.surfel_adapt == 0.0f) s.surfel_adapt = p->adapt;
    if (s.texel_adapt == 0.0f) s.texel_adapt = p->texel_adapt;
    if (!s.grid_refine) s.grid_refine = p->grid_refine;
    if (!s.sky_rays) s.sky_rays = GLOW_PC_SKY_RAYS;
    return s;
}

glow_result glow_pc_settings_validate(const glow_pc_settings *s, char *msg, size_t n) {
#define BAD(...) do { if (msg && n) snprintf(msg, n, __VA_ARGS__); return GLOW_ERROR_INVALID_ARGUMENT; } while (0)
    if ((unsigned)s->quality > GLOW_PC_QUALITY_FINE) BAD("quality %u is not low, moderate, high or fine", (unsigned)s->quality);
    if (s->surfels && (s->surfels < 16 || s->surfels > (1u << 22)))
        BAD("--surfels %u is out of range (16..4194304)", s->surfels);
    if (s->links && s->links > 4096) BAD("--links %u is out of range (1..4096)", s->links);
    if (s->bands && (s->bands < 2 || s->bands > 8)) BAD("--bands %u is out of range (2..8)", s->bands);
    if (s->grid_spacing != 0.0f && !(isfinite(s->grid_spacing) && s->grid_spacing > 0.0f))
        BAD("--grid-spacing %g must be a positive finite length", (double)s->grid_spacing);
    if (s->texel_density != 0.0f && !(isfinite(s->texel_density) && s->texel_density > 0.0f))
        BAD("--texel-density %g must be a positive finite number of texels per unit", (double)s->texel_density);
    if (s->threads > 1024) BAD("--threads %u is out of range (0..1024)", s->threads);
    if (s->cut_error && s->cut_solid_angle) BAD("cut_error and cut_solid_angle are both set: pick one cut");
    if (s->lightmap_max_size && (s->lightmap_max_size < 4 || s->lightmap_max_size > 4096 || s->lightmap_max_size % 4))
        BAD("--lightmap-max-size %u must be a multiple of 4 in 4..4096", s->lightmap_max_size);
    if (s->lightmap_caches > (1u << 24)) BAD("--lightmap-caches %u is out of range (1..16777216)", s->lightmap_caches);
    if (s->rays_per_surfel > 256) BAD("rays per surfel %u is out of range (1..256)", s->rays_per_surfel);
    if (s->relax_iterations > 1000) BAD("relaxation iterations %u is out of range", s->relax_iterations);
    if ((unsigned)s->link_visibility > GLOW_PC_LINK_VISIBILITY_EXACT)
        BAD("link visibility %u is not clustered or exact", (unsigned)s->link_visibility);
    if (s->link_cluster_angle != 0.0f && !(s->link_cluster_angle > 0.0f && s->link_cluster_angle <= 1.0f))
        BAD("--link-cluster-angle %g is out of range (0..1 radians)", (double)s->link_cluster_angle);
    if (s->link_cluster_rays > 64) BAD("--link-cluster-rays %u is out of range (1..64)", s->link_cluster_rays);
    if (s->lightmap_detail > 4) BAD("--lightmap-detail %u is out of range (1 = none, 2..4)", s->lightmap_detail);
    if (s->detail_links > 256) BAD("--detail-links %u is out of range (1..256)", s->detail_links);
    if (s->detail_radius != 0.0f && !(s->detail_radius > 0.0f && s->detail_radius <= 4.0f))
        BAD("--detail-radius %g is out of range (0..4 lightmap texels)", (double)s->detail_radius);
    if (s->surfel_adapt != 0.0f && !(s->surfel_adapt >= 1.0f && s->surfel_adapt <= 4.0f))
        BAD("--surfel-adapt %g is out of range (1..4)", (double)s->surfel_adapt);
    if (s->texel_adapt != 0.0f && !(s->texel_adapt >= 1.0f && s->texel_adapt <= 8.0f))
        BAD("--texel-adapt %g is out of range (1..8)", (double)s->texel_adapt);
    if (s->sky_rays > 65536) BAD("--sky-rays %u is out of range (1..65536)", s->sky_rays);
    if (s->grid_refine > 4 || s->grid_refine == 3) BAD("--grid-refine %u is not 1, 2 or 4", s->grid_refine);
    if (s->system_group_count && !(s->system_area > 0.0f)) BAD("--system-group needs --system-area");
    if (s->system_group_count > 256) BAD("%u system groups; at most 256", s->system_group_count);
    if (s->system_group_count && !s->system_groups) BAD("system_group_count %u without system_groups", s->system_group_count);
    for (uint32_t g = 0; g < s->system_group_count; ++g) {
        const char *e = s->system_groups[g], *eq = e ? strchr(e, '=') : NULL;
        if (!eq || eq == e || eq - e > 48 || !eq[1])
            BAD("system group '%s': expected NAME=PATTERN[,PATTERN...] with a name of 1..48 characters", e ? e : "(null)");
        for (const char *q = e; q < eq; ++q)
            if (!((*q >= 'A' && *q <= 'Z') || (*q >= 'a' && *q <= 'z') || (*q >= '0' && *q <= '9') || *q == '_' || *q == '-'))
                BAD("system group '%s': the name may hold only A-Z a-z 0-9 _ -", e);
        for (uint32_t h = 0; h < g; ++h)
            if (!strncmp(s->system_groups[h], e, (size_t)(eq - e) + 1u)) BAD("system group '%.*s' is named twice", (int)(eq - e), e);
    }
    for (uint32_t g = 0; s->system_neighbours && g < s->system_group_count; ++g) {
        const char *e = s->system_groups[g], *l = s->system_neighbours[g];
        const int nl = (int)(strchr(e, '=') - e);
        while (l && *l) { /* each declared name: another group's, once */
            const char *c = strchr(l, ',');
            const size_t len = c ? (size_t)(c - l) : strlen(l);
            uint32_t h = 0;
            while (h < s->system_group_count &&
                   !(strncmp(s->system_groups[h], l, len) == 0 && s->system_groups[h][len] == '='))
                ++h;
            if (!len) BAD("system '%.*s': an empty neighbour name in '%s'", nl, e, s->system_neighbours[g]);
            if (h == s->system_group_count)
                BAD("system '%.*s': neighbour '%.*s' is no named system (unknown; the names are the groups')", nl, e,
                    (int)len, l);
            if (h == g) BAD("system '%.*s' names itself as its neighbour (a system's own light needs no dependency)", nl, e);
            for (const char *q = s->system_neighbours[g]; q < l;) {
                const char *qc = strchr(q, ',');
                const size_t ql = qc ? (size_t)(qc - q) : strlen(q);
                if (ql == len && !strncmp(q, l, len)) BAD("system '%.*s': neighbour '%.*s' is named twice", nl, e, (int)len, l);
                q += ql + (qc ? 1 : 0);
            }
            l += len + (c ? 1 : 0);
            if (c && !*l) BAD("system '%.*s': an empty neighbour name in '%s'", nl, e, s->system_neighbours[g]);
        }
    }
    if (s->system_neighbours && !s->system_group_count) BAD("system_neighbours without system_groups");
    if (s->system_reach != 0.0f && !(s->system_reach > 0.0f && s->system_reach <= 4.0f))
        BAD("--system-reach %g is out of range (0..4 system diagonals)", (double)s->system_reach);
    if (s->system_area > 0.0f && s->sh_links)
        BAD("--sh-links with --system-area: full-SH links to neighbouring systems are not supported (the runtime "
            "reads them from node flux, which proxies do not carry)");
    if (s->distribution) {
        const glow_pc_distribution *d = s->distribution;
        if (d->ranks == 0 || d->rank >= d->ranks) BAD("distribution: rank %u of %u ranks", d->rank, d->ranks);
        if (d->ranks > 1 && !d->share) BAD("distribution: %u ranks and no share function", d->ranks);
    }
#undef BAD
    return GLOW_OK;
}

/* ------------------------------------------------------------------ timing and memory */
static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Per-stage peak RSS: reset the kernel's high-water mark (Linux >= 4.0, "5" > clear_refs) before a
 * stage and read VmHWM after it. Where that is not possible the value is the process peak so far. */
static void peak_reset(void) {
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (!f) return;
    fputs("5", f);
    fclose(f);
}
static size_t peak_read(void) {
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return 0;
    char line[256];
    size_t kb = 0;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "VmHWM:", 6) == 0) {
            kb = (size_t)strtoull(line + 6, NULL, 10);
            break;
        }
    fclose(f);
    return kb * 1024u;
}

typedef struct progress_ctx {
    const glow_pc_settings *s;
    uint32_t stage;
} progress_ctx;
static void stage_progress(void *user, double f) {
    progress_ctx *p = user;
    if (p->s->progress) p->s->progress(p->s->progress_user, p->stage, f);
}

/* ------------------------------------------------------------------ serialisation */
static uint16_t unorm16(float x) {
    if (!(x > 0.0f)) return 0;
    if (x >= 1.0f) return 65535;
    return (uint16_t)lrintf(x * 65535.0f);
}

typedef struct sections {
    glow__section_data s[24];
    uint32_t n;
    void *owned[24];
} sections;

static void add_section(sections *ss, uint32_t fourcc, void *data, uint64_t size) {
    ss->owned[ss->n] = data;
    ss->s[ss->n] = (glow__section_data){.fourcc = fourcc, .version = 1, .data = data, .size = size};
    ss->n++;
}

static glow_result serialise(const glow_pc_settings *set, const glow__scene *sc, const glow__surfels *sf,
                             const glow__hierarchy *h, const glow__caches *ca, const glow__links *lk, uint8_t *gvis,
                             void *xref, uint64_t xref_size, void *ptre, uint64_t ptre_size, const float *sky_surfel,
                             const float *sky_grid, sections *ss, glow__log *log) {
    const uint32_t nl = lk->per_cache;
    const uint32_t blocks = (nl + GLOW_LINK_BLOCK - 1) / GLOW_LINK_BLOCK;
    /* LINK stores 24-bit node indices. --surfels <= 2^22 keeps node_count < 2^23; this guards the
     * format's limit itself. */
    if (h->node_count > GLOW_LINK_MAX_NODES) {
        glow__errorf(log, "write: %u hierarchy nodes exceed the bake format's limit of %u (24-bit link node index)",
                     h->node_count, GLOW_LINK_MAX_NODES);
        free(gvis);
        return GLOW_ERROR_UNSUPPORTED;
    }
    /* META */
    glow_bake_meta *m = calloc(1, sizeof *m);
    glow_bake_material *mat = calloc(sc->material_count ? sc->material_count : 1, sizeof *mat);
    glow_bake_surfel *su = calloc(sf->count, sizeof *su);
    glow_bake_node *no = calloc(h->node_count, sizeof *no);
    uint32_t *lv = calloc((size_t)h->level_count + 1, sizeof *lv);
    glow_bake_cache *cc = calloc(ca->count ? ca->count : 1, sizeof *cc);
    size_t grid_cells = (size_t)ca->grid_dims[0] * ca->grid_dims[1] * ca->grid_dims[2];
    uint32_t *gm = grid_cells ? malloc(grid_cells * sizeof *gm) : NULL;
    size_t lm_texels = (size_t)ca->lm_width * ca->lm_height * ca->lm_pages; /* pages stacked: [page][h][w] */
    uint32_t *lmm = lm_texels ? malloc(lm_texels * sizeof *lmm) : NULL;
    glow_bake_link_block *lb = calloc((size_t)ca->count * blocks + 1, sizeof *lb);
    size_t shlk_block = glow_bake_shlk_block_size(lk->sh_bands);
    uint8_t *sh = lk->sh ? calloc((size_t)ca->count * blocks + 1, shlk_block) : NULL;
    size_t n_sub = 0, n_used = 0;
    for (size_t i = 0; i < (size_t)ca->count * nl; ++i) {
        n_sub += lk->links[i].subsets != 0;
        n_used += lk->links[i].factor != 0.0f;
    }
    const bool any_sub = n_sub > 0;
    if (any_sub && lk->gradients)
        glow__infof(log, "link gradients: %zu of %zu links (%.1f %%) read their node's light where the cache sees it "
                    "(CPU runtime only)", n_sub, n_used, n_used ? 100.0 * (double)n_sub / (double)n_used : 0.0);
    else if (any_sub)
        glow__infof(log, "link subsets: %zu of %zu links (%.1f %%) read the part of their node the cache sees", n_sub,
                    n_used, n_used ? 100.0 * (double)n_sub / (double)n_used : 0.0);
    uint16_t *lsub = any_sub ? calloc((size_t)ca->count * blocks * GLOW_LINK_BLOCK + 1, sizeof *lsub) : NULL;
    glow_bake_triangle *tr = calloc(sc->tri_count, sizeof *tr);
    if (!m || !mat || !su || !no || !lv || !cc || (grid_cells && !gm) || (lm_texels && !lmm) || !lb ||
        (lk->sh && !sh) || (any_sub && !lsub) || !tr) {
        free(m); free(mat); free(su); free(no); free(lv); free(cc); free(gm); free(lmm); free(lb); free(sh); free(tr);
        free(lsub);
        free(gvis);
        glow__errorf(log, "write: out of memory while serialising the bake");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }

    m->surfel_count = sf->count;
    m->node_count = h->node_count;
    m->level_count = h->level_count;
    m->cache_count = ca->count;
    m->grid_cache_count = ca->grid_cache_count;
    m->lightmap_cache_count = ca->lm_cache_count;
    m->links_per_cache = nl;
    m->link_blocks_per_cache = blocks;
    m->sh_bands = set->bands;
    m->link_kind = GLOW_LINK_KIND_RUNTIME_PROJECTION | (lk->sh ? GLOW_LINK_KIND_FULL_SH : 0u) |
                   (lsub ? (lk->gradients ? GLOW_LINK_KIND_GRADIENT : GLOW_LINK_KIND_SUBSETS) : 0u);
    m->material_count = sc->material_count;
    m->triangle_count = sc->tri_count;
    memcpy(m->bounds_min, sc->bounds_min, sizeof m->bounds_min);
    memcpy(m->bounds_max, sc->bounds_max, sizeof m->bounds_max);
    m->surfel_area = sf->area;
    m->factor_scale = (float)(1.0 / (GLOW__PI * (double)sf->area));
    memcpy(m->grid_origin, ca->grid_origin, sizeof m->grid_origin);
    m->grid_spacing = ca->grid_spacing;
    memcpy(m->grid_dims, ca->grid_dims, sizeof m->grid_dims);
    m->lightmap_count = lm_texels ? ca->lm_pages : 0u;
    m->lightmap_width = ca->lm_width;
    m->lightmap_height = ca->lm_height;
    m->texel_density = ca->texel_density;
    m->seed = set->seed;
    m->scene_area = sc->area;
    m->source_triangles = sc->source_tri_count;
    m->skipped_degenerate = sc->skipped_degenerate;
    m->skipped_duplicate = sc->skipped_duplicate;
    m->skipped_nonfinite = sc->skipped_nonfinite;
    m->chart_count = ca->chart_count;
    m->lightmap_invalid_texels = ca->lm_invalid;
    m->quality = (uint32_t)set->quality;
    m->rays_per_surfel = set->rays_per_surfel;

    for (uint32_t i = 0; i < sc->material_count; ++i) {
        const glow__material *src = &sc->materials[i];
        size_t len = strnlen(src->name, sizeof mat[i].name - 1); /* truncate, keep NUL */
        memcpy(mat[i].name, src->name, len);
        memcpy(mat[i].albedo, src->albedo, sizeof mat[i].albedo);
        memcpy(mat[i].emission, src->emission, sizeof mat[i].emission);
        mat[i].flags = src->texture >= 0 ? 1u : 0u;
    }
    for (uint32_t i = 0; i < sf->count; ++i) {
        const glow__surfel *s = &sf->s[i];
        memcpy(su[i].position, s->pos, 12);
        memcpy(su[i].normal, s->nrm, 12);
        memcpy(su[i].albedo, s->albedo, 12);
        memcpy(su[i].emission, s->emission, 12);
        su[i].material = s->material;
        su[i].feedback = ca->surfel_feedback[i];
        su[i].triangle = s->tri;
    }
    for (uint32_t i = 0; i < h->node_count; ++i) {
        const glow__node *n = &h->nodes[i];
        no[i].child[0] = n->child[0];
        no[i].child[1] = n->child[1];
        no[i].parent = n->parent;
        no[i].area = n->area;
        memcpy(no[i].position, n->pos, 12);
        no[i].normal_oct = glow__oct_encode(n->nrm);
    }
    memcpy(lv, h->level_start, ((size_t)h->level_count + 1) * sizeof *lv);
    for (uint32_t i = 0; i < ca->count; ++i) {
        const glow__cache *c = &ca->caches[i];
        memcpy(cc[i].position, c->pos, 12);
        cc[i].normal_oct = c->kind == GLOW_CACHE_KIND_LIGHTMAP ? glow__oct_encode(c->nrm) : 0u;
        cc[i].kind = c->kind;
        cc[i].texel = c->texel;
    }
    if (gm) memcpy(gm, ca->grid_map, grid_cells * sizeof *gm);
    if (lmm) memcpy(lmm, ca->lm_map, lm_texels * sizeof *lmm);
    /* LINK: 8 bytes per link (bake_format.h). The linker's factor is surfel_area / node area, which
     * the runtime derives from NODE.area, so only node, one_minus_cos and dir are stored. Padding
     * lanes (j >= nl, left zero by calloc) and empty cut slots (factor 0) are node 0,
     * one_minus_cos 0, dir 0. */
    for (uint32_t c = 0; c < ca->count; ++c)
        for (uint32_t j = 0; j < nl; ++j) {
            glow_bake_link_block *b = &lb[(size_t)c * blocks + j / GLOW_LINK_BLOCK];
            uint32_t lane = j % GLOW_LINK_BLOCK;
            const glow__link *L = &lk->links[(size_t)c * nl + j];
            if (L->factor == 0.0f) {
                glow_bake_link_pack(b, lane, 0u, 0u, 0u, 0u);
            } else {
                uint32_t u, v;
                glow__oct_encode12(L->dir, &u, &v);
                glow_bake_link_pack(b, lane, L->node, glow__half_from_float(L->one_minus_cos), u, v);
            }
            if (lsub && L->factor != 0.0f) lsub[(size_t)c * blocks * GLOW_LINK_BLOCK + j] = L->subsets;
            if (sh) {
                uint8_t *blk = sh + ((size_t)c * blocks + j / GLOW_LINK_BLOCK) * shlk_block;
                uint32_t *node = (uint32_t *)blk;
                uint16_t *coef = (uint16_t *)(blk + 64);
                node[lane] = L->node;
                const float *src = lk->sh + ((size_t)c * nl + j) * lk->sh_bands * lk->sh_bands;
                for (uint32_t q = 0; q < lk->sh_bands * lk->sh_bands; ++q)
                    coef[q * GLOW_LINK_BLOCK + lane] = glow__half_from_float(src[q]);
            }
        }
    for (uint32_t t = 0; t < sc->tri_count; ++t) {
        const float(*p)[3] = sc->pos + 3 * (size_t)t;
        memcpy(tr[t].position, p, 36);
        for (int k = 0; k < 3; ++k) {
            tr[t].lm_uv[2 * k] = unorm16(ca->lm_uv[3 * (size_t)t + k][0]);
            tr[t].lm_uv[2 * k + 1] = unorm16(ca->lm_uv[3 * (size_t)t + k][1]);
        }
        tr[t].material = sc->tri_material[t];
        tr[t].source = sc->tri_source[t];
        float e1[3], e2[3], ng[3];
        glow__sub(p[1], p[0], e1);
        glow__sub(p[2], p[0], e2);
        glow__cross(e1, e2, ng);
        float l = sqrtf(glow__dot(ng, ng));
        for (int k = 0; k < 3; ++k) ng[k] = l > 0.0f ? ng[k] / l : 0.0f;
        tr[t].normal_oct = glow__oct_encode(ng);
    }

    add_section(ss, GLOW_SECTION_META, m, sizeof *m);
    add_section(ss, GLOW_SECTION_MATL, mat, (uint64_t)sc->material_count * sizeof *mat);
    add_section(ss, GLOW_SECTION_SURF, su, (uint64_t)sf->count * sizeof *su);
    add_section(ss, GLOW_SECTION_NODE, no, (uint64_t)h->node_count * sizeof *no);
    add_section(ss, GLOW_SECTION_LEVL, lv, ((uint64_t)h->level_count + 1) * sizeof *lv);
    add_section(ss, GLOW_SECTION_CACH, cc, (uint64_t)ca->count * sizeof *cc);
    if (gm) add_section(ss, GLOW_SECTION_GRID, gm, grid_cells * sizeof *gm);
    else free(gm);
    if (gvis && gm && ca->grid_refine && ca->grid_brick_count) { /* 1.5: GFIN (bake_format.h) */
        const uint64_t R = ca->grid_refine, per = (R + 1) * (R + 1) * (R + 1), nb = ca->grid_brick_count;
        const uint64_t size = sizeof(glow_bake_grid_fine) + 4u * grid_cells + 4u * nb * per + 8u * nb * R * R * R;
        uint8_t *buf = calloc(1, (size_t)size);
        if (!buf) {
            free(gvis);
            glow__errorf(log, "write: out of memory for the refined grid");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        glow_bake_grid_fine *gh = (glow_bake_grid_fine *)(void *)buf;
        gh->refine = (uint32_t)R;
        gh->brick_count = (uint32_t)nb;
        uint8_t *q = buf + sizeof *gh;
        memcpy(q, ca->grid_brick_of_cell, 4u * grid_cells);
        memcpy(q + 4u * grid_cells, ca->grid_bricks, 4u * nb * per);
        memcpy(q + 4u * grid_cells + 4u * nb * per, gvis + 8u * grid_cells, 8u * nb * R * R * R);
        add_section(ss, GLOW_SECTION_GFIN, buf, size);
    }
    if (gvis && gm) add_section(ss, GLOW_SECTION_GVIS, gvis, grid_cells * 8u);
    else free(gvis);
    if (lmm) add_section(ss, GLOW_SECTION_LMAP, lmm, lm_texels * sizeof *lmm);
    else free(lmm);
    add_section(ss, GLOW_SECTION_LINK, lb, (uint64_t)ca->count * blocks * sizeof *lb);
    if (sh) add_section(ss, GLOW_SECTION_SHLK, sh, (uint64_t)ca->count * blocks * shlk_block);
    if (lsub) add_section(ss, GLOW_SECTION_LSUB, lsub, (uint64_t)ca->count * blocks * GLOW_LINK_BLOCK * sizeof *lsub);
    add_section(ss, GLOW_SECTION_GEOM, tr, (uint64_t)sc->tri_count * sizeof *tr);
    if (lm_texels && ca->lm_pages > 1 && sc->tri_count) { /* 1.7: TPAG, each triangle's lightmap page */
        uint32_t *pg = malloc((size_t)sc->tri_count * sizeof *pg);
        if (!pg) {
            glow__errorf(log, "write: out of memory for the lightmap pages");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        memcpy(pg, ca->lm_page, (size_t)sc->tri_count * sizeof *pg);
        add_section(ss, GLOW_SECTION_TPAG, pg, (uint64_t)sc->tri_count * sizeof *pg);
    }
    if (lk->detail_count && ca->detail_count == lk->detail_count) { /* 1.2: LDET (bake_format.h) */
        const uint32_t T = lk->detail_count, nlk = lk->detail_first[T];
        const uint64_t size = sizeof(glow_bake_detail) + 4ull * T + 4ull * (T + 1ull) + 8ull * nlk;
        uint8_t *buf = calloc(1, (size_t)size);
        if (!buf) {
            glow__errorf(log, "write: out of memory for the lightmap detail");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        glow_bake_detail *dh = (glow_bake_detail *)(void *)buf;
        dh->factor = ca->detail_factor;
        dh->width = ca->detail_width;
        dh->height = ca->detail_height;
        dh->texel_count = T;
        dh->link_count = nlk;
        uint8_t *q = buf + sizeof *dh;
        memcpy(q, ca->detail_texel, 4ull * T);
        q += 4ull * T;
        memcpy(q, lk->detail_first, 4ull * (T + 1ull));
        q += 4ull * (T + 1ull);
        memcpy(q, lk->detail_surfel, 4ull * nlk);
        q += 4ull * nlk;
        memcpy(q, lk->detail_weight, 4ull * nlk);
        add_section(ss, GLOW_SECTION_LDET, buf, size);
    }
    /* 1.1: material UVs and albedo texture paths, for hosts that draw the scene textured */
    if (sc->uv0 && sc->tri_count) {
        float *uv = malloc((size_t)sc->tri_count * 6u * sizeof *uv);
        if (!uv) {
            glow__errorf(log, "write: out of memory for the material UVs");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        for (uint32_t t = 0; t < sc->tri_count; ++t)
            for (int k = 0; k < 3; ++k) {
                const float u = sc->uv0[3 * (size_t)t + k][0], w = sc->uv0[3 * (size_t)t + k][1];
                uv[6 * (size_t)t + 2 * k] = isfinite(u) ? u : 0.0f;
                uv[6 * (size_t)t + 2 * k + 1] = isfinite(w) ? w : 0.0f;
            }
        add_section(ss, GLOW_SECTION_TUV0, uv, (uint64_t)sc->tri_count * 6u * sizeof *uv);
    }
    bool any_texture = false;
    for (uint32_t i = 0; i < sc->material_count; ++i) any_texture |= sc->materials[i].texture >= 0;
    if (any_texture) {
        char *paths = calloc(sc->material_count, GLOW_BAKE_TEXTURE_PATH);
        if (!paths) {
            glow__errorf(log, "write: out of memory for the texture paths");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        for (uint32_t i = 0; i < sc->material_count; ++i) {
            const int tx = sc->materials[i].texture;
            if (tx < 0 || (uint32_t)tx >= sc->texture_count) continue;
            const char *path = sc->textures[tx].path;
            const size_t len = strnlen(path, sizeof sc->textures[tx].path);
            if (len < GLOW_BAKE_TEXTURE_PATH) memcpy(paths + (size_t)i * GLOW_BAKE_TEXTURE_PATH, path, len); /* else "" */
        }
        add_section(ss, GLOW_SECTION_TEXP, paths, (uint64_t)sc->material_count * GLOW_BAKE_TEXTURE_PATH);
    }
    if (sky_surfel) { /* 1.6: SKYT (bake_format.h glow_bake_sky): header, surfels' T, grid caches' V */
        const uint64_t ns = (uint64_t)sf->count * GLOW_BAKE_SKY_COEFFS, ng = (uint64_t)ca->grid_cache_count * GLOW_BAKE_SKY_COEFFS;
        const uint64_t size = sizeof(glow_bake_sky) + 4u * (ns + ng);
        uint8_t *buf = calloc(1, (size_t)size);
        if (!buf) {
            if (xref) add_section(ss, GLOW_SECTION_XREF, xref, xref_size); /* freed with the sections */
            if (ptre) add_section(ss, GLOW_SECTION_PTRE, ptre, ptre_size);
            glow__errorf(log, "write: out of memory for the sky transfer");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        glow_bake_sky *kh = (glow_bake_sky *)(void *)buf;
        kh->coeffs = GLOW_BAKE_SKY_COEFFS;
        kh->surfel_count = sf->count;
        kh->grid_count = ca->grid_cache_count;
        kh->rays = set->sky_rays;
        kh->grid_rays = set->sky_rays * GLOW_PC_SKY_GRID_RAYS;
        memcpy(buf + sizeof *kh, sky_surfel, 4u * ns);
        if (ng) memcpy(buf + sizeof *kh + 4u * ns, sky_grid, 4u * ng);
        add_section(ss, GLOW_SECTION_SKYT, buf, size);
    }
    if (xref) add_section(ss, GLOW_SECTION_XREF, xref, xref_size); /* the sections own it now */
    if (ptre) add_section(ss, GLOW_SECTION_PTRE, ptre, ptre_size); /* 1.8: PTRE, likewise */
    return GLOW_OK;
}

/* ------------------------------------------------------------------ the bake */
/* Messages go to settings.logger (glow.h's logger type): warnings and info as they happen with code
 * GLOW_OK, the error once, when glow_pc_bake returns, with the code it returns (glow_pc_bake below).
 * The deprecated settings.log callback gets everything as it happens, as in 0.1. */
static void log_adapter(void *user, glow_log_level level, const char *msg) {
    const glow_pc_settings *s = user;
    if (s->logger.log) {
        if (level != GLOW_LOG_ERROR) s->logger.log(s->logger.user, level, GLOW_OK, msg, NULL, 0);
    } else if (s->log) {
        s->log(s->log_user, level, msg);
    }
}

/* --audit-radiance: one little-endian float32 per surfel, in the bake's surfel order (what
 * glow-stability audit --radiance-out writes for a bake of the same scene and settings). */
static glow_result read_audit_radiance(const char *path, uint32_t count, glow__log *log, float **out) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        glow__errorf(log, "%s: cannot open the audit radiance file", path);
        return GLOW_ERROR_IO;
    }
    float *b = malloc(((size_t)count + 1) * sizeof *b);
    size_t got = b ? fread(b, sizeof *b, (size_t)count + 1, f) : 0;
    fclose(f);
    if (!b) {
        glow__errorf(log, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    if (got != count) {
        glow__errorf(log, "%s: holds %s%zu radiances, the bake has %u surfels (baked with other settings?)", path,
                     got > count ? "more than " : "", got > count ? (size_t)count : got, count);
        free(b);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    for (uint32_t i = 0; i < count; ++i)
        if (!isfinite(b[i]) || b[i] < 0.0f) {
            glow__errorf(log, "%s: radiance %u is %g (must be finite and >= 0)", path, i, (double)b[i]);
            free(b);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    *out = b;
    return GLOW_OK;
}

static int cmp_float(const void *a, const void *b) {
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The audit's summary (log) and per-cache CSV. Caches whose exact gather is below 5 % of the mean are
 * left out of the ratio percentiles (their ratios are noise of near-black values). */
static void report_audit(const glow__caches *c, const glow__links *l, FILE *csv, const char *csv_path, glow__log *log) {
    double exact = 0, linked = 0, vis = 0, e2 = 0, r2 = 0, fsum = 0, fw = 0;
    for (uint32_t i = 0; i < c->count; ++i) {
        const float *a = l->audit + (size_t)i * GLOW__AUDIT_FIELDS;
        exact += a[0];
        linked += a[1];
        vis += a[2];
        e2 += ((double)a[1] - a[0]) * ((double)a[1] - a[0]);
        r2 += (double)a[0] * a[0];
        fsum += (double)a[3] * a[4];
        fw += a[4];
    }
    const double mean = c->count ? exact / c->count : 0.0;
    float *ratio = malloc(((size_t)c->count + 1) * sizeof *ratio);
    uint32_t nr = 0, bright = 0, dark = 0;
    for (uint32_t i = 0; ratio && i < c->count; ++i) {
        const float *a = l->audit + (size_t)i * GLOW__AUDIT_FIELDS;
        if (!(a[0] > 0.05 * mean)) continue;
        ratio[nr] = a[1] / a[0];
        bright += ratio[nr] > 1.5f;
        dark += ratio[nr] < 1.0f / 1.5f;
        nr++;
    }
    if (ratio && nr) {
        qsort(ratio, nr, sizeof *ratio, cmp_float);
        glow__infof(log,
                    "links audit: gather through the cut / exact %.4f (with visible-part means %.4f), rel. RMS error %.4f; "
                    "per cache (%u rated) p05 %.3f median %.3f p95 %.3f, %u above 1.5x, %u below 1/1.5x; linked nodes "
                    "%.1f %% visible (solid-angle weighted)",
                    exact > 0 ? linked / exact : 0.0, exact > 0 ? vis / exact : 0.0, r2 > 0 ? sqrt(e2 / r2) : 0.0, nr,
                    (double)ratio[(size_t)(0.05 * (nr - 1))], (double)ratio[nr / 2], (double)ratio[(size_t)(0.95 * (nr - 1))],
                    bright, dark, fw > 0 ? 100.0 * fsum / fw : 100.0);
    }
    /* what a link could read instead of its node's mean (links.c): per variant the total, the relative
     * RMS error over caches and the per-cache ratio's p05 / p95 */
    const char *const variant[5] = {"its visible leaves' mean", "its visible children's means",
                                    "its visible grandchildren's means",
                                    l->gradients ? "its link gradient codes (what this bake's runtime reads)"
                                                 : "its link subsets (what this bake's runtime reads)",
                                    "its node's mean moved by the response gradient to the flux centroid"};
    char line[768];
    int len = snprintf(line, sizeof line, "link alternatives audit: if each link read, instead of its node's mean,");
    for (int f = 5; f < GLOW__AUDIT_FIELDS && ratio; ++f) {
        double t = 0.0, ee = 0.0, rr = 0.0;
        nr = 0;
        for (uint32_t i = 0; i < c->count; ++i) {
            const float *a = l->audit + (size_t)i * GLOW__AUDIT_FIELDS;
            t += a[f];
            ee += ((double)a[f] - a[0]) * ((double)a[f] - a[0]);
            rr += (double)a[0] * a[0];
            if (a[0] > 0.05 * mean) ratio[nr++] = a[f] / a[0];
        }
        if (!nr) break;
        qsort(ratio, nr, sizeof *ratio, cmp_float);
        if (len > 0 && (size_t)len < sizeof line)
            len += snprintf(line + len, sizeof line - (size_t)len, "%s %s: / exact %.4f, rel. RMS error %.4f, p05 %.3f p95 %.3f",
                            f > 5 ? ";" : "", variant[f - 5], exact > 0 ? t / exact : 0.0, rr > 0 ? sqrt(ee / rr) : 0.0,
                            (double)ratio[(size_t)(0.05 * (nr - 1))], (double)ratio[(size_t)(0.95 * (nr - 1))]);
    }
    if (ratio && nr) glow__infof(log, "%s", line);
    free(ratio);
    if (!csv) return;
    fprintf(csv, "cache,kind,x,y,z,nx,ny,nz,visible_solid_angle,visible_fraction,exact,link,link_visible_mean,"
                 "link_visible_uniform_mean,link_children,link_grandchildren,link_subsets,link_gradient\n");
    for (uint32_t i = 0; i < c->count; ++i) {
        const glow__cache *k = &c->caches[i];
        const float *a = l->audit + (size_t)i * GLOW__AUDIT_FIELDS;
        fprintf(csv, "%u,%s,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g\n", i,
                k->kind == GLOW_CACHE_KIND_LIGHTMAP ? "lightmap" : "grid", k->pos[0], k->pos[1], k->pos[2], k->nrm[0],
                k->nrm[1], k->nrm[2], a[4], a[3], a[0], a[1], a[2], a[5], a[6], a[7], a[8], a[9]);
    }
    if (ferror(csv)) glow__warnf(log, "%s: writing the audit CSV failed", csv_path);
}

#define STAGE_BEGIN(k) do { pc.stage = (k); peak_reset(); t0 = now_seconds(); stage_progress(&pc, 0.0); } while (0)
#define STAGE_END(k) do { stats->stage_seconds[k] = now_seconds() - t0; stats->stage_peak_rss[k] = peak_read(); \
                          stage_progress(&pc, 1.0); } while (0)

/* Light across systems (bake_systems): a system's surfels and hierarchy, placed once and shared by its
 * own bake and the bakes of the systems that link it. */
typedef struct sys_base {
    bool done;
    glow__surfels surfels;
    glow__hierarchy hier;
    double seconds[2]; /* surfels, hierarchy */
} sys_base;

/* A tree as a system's links see it (a neighbour's coarsened, PTRE; or a system's own, whole): leaves
 * [0, leaf_count) with their surfels, then internal nodes, children before parents; source: the node
 * of the full tree each stands for. */
typedef struct sys_tree {
    uint32_t leaf_count, node_count, root;
    glow__node *nodes;
    glow__surfel *leaves;
    uint32_t *source;
} sys_tree;

static void *sys_tree_pack(const sys_tree *t, uint64_t key, uint64_t *size); /* PTRE's payload, below */

#define SYS_DEP_JOIN 0xFFFFFFFEu /* map_dep of a join */
#define SYS_DEP_OWN 0xFFFFFFFFu  /* map_dep of the system's own nodes */

/* What a system's links see: its tree and its neighbours' whole trees under a chain of joins (own
 * leaves first, then each neighbour's; internal nodes likewise; the joins last), and how each node of
 * that tree maps to the bake: its own node, or node map_node of dependency map_dep (a proxy, XREF). */
typedef struct sys_links_in {
    glow__surfels surfels;
    glow__hierarchy hier;
    uint8_t *join;
    uint32_t *map_dep, *map_node;
    uint32_t own_leaves, own_nodes;
    float trace_lo[3], trace_hi[3];
    uint64_t key;           /* the system's own key (XREF system_key) */
    const sys_tree *proxy;  /* its tree as its neighbours see it (PTRE) */
    uint32_t deps;
    const uint64_t *dep_keys; /* the dependencies' own keys */
} sys_links_in;

/* One system (the whole scene when the bake is not split): surfels -> hierarchy -> caches -> links ->
 * file, from its triangles and its rays. grid_target: the grid's cache budget. Fills the stats of these
 * stages; a rank other than the writer (`writer` false) stops before the file. */
static glow_result bake_system(const glow_pc_settings *setp, uint32_t grid_target, const glow__scene *sc,
                               const glow__rt *rt, const char *out_path, bool writer, glow__pool *pool,
                               glow__log *log, FILE *audit_csv, glow_pc_stats *stats, const sys_base *base,
                               const sys_links_in *w) {
    glow_pc_settings set = *setp;
    const char *scene_path = sc->source;
    glow__surfels surfels = {0};
    glow__hierarchy hier = {0};
    glow__caches caches = {0};
    uint8_t *gvis = NULL; /* GVIS, until serialise takes it */
    float *sky_surfel = NULL, *sky_grid = NULL; /* SKYT, until serialise takes them */
    glow__links links = {0};
    sections ss = {0};
    float *audit_radiance = NULL;
    glow_result res = GLOW_OK;
    double t0;
    void *xref = NULL, *ptre = NULL; /* XREF and PTRE, for a system of a world */
    uint64_t ptre_size = 0;
    uint32_t *proxy_of = NULL;
    progress_ctx pc = {.s = setp};
    const glow__surfels *SF = &surfels;
    const glow__hierarchy *H = &hier;
    if (base) { /* placed before (bake_systems: shared with the systems that link this one) */
        SF = &base->surfels;
        H = &base->hier;
        stats->stage_seconds[ST_SURFELS] = base->seconds[0];
        stats->stage_seconds[ST_HIER] = base->seconds[1];
    } else {
        STAGE_BEGIN(ST_SURFELS);
        glow__surfel_settings ssurf = {.count = set.surfels, .seed = set.seed, .relax_iterations = set.relax_iterations,
                                       .adapt = set.surfel_adapt, .rt = rt};
        res = glow__surfels_place(sc, &ssurf, pool, log, &surfels);
        STAGE_END(ST_SURFELS);
        if (res != GLOW_OK) goto done;

        STAGE_BEGIN(ST_HIER);
        res = glow__hierarchy_build_rt(&surfels, sc->bounds_min, sc->bounds_max, rt, pool, log, &hier);
        STAGE_END(ST_HIER);
        if (res != GLOW_OK) goto done;
    }
    stats->surfels = SF->count;
    stats->nodes = H->node_count;
    stats->levels = H->level_count;

    STAGE_BEGIN(ST_CACHES);
    glow__cache_settings scache = {.grid_spacing = set.grid_spacing, .texel_density = set.texel_density,
                                   .target_grid = grid_target, .target_lightmap = set.lightmap_caches, .seed = set.seed,
                                   .detail_factor = !set.lightmap_detail       ? GLOW_PC_LIGHTMAP_DETAIL
                                                    : set.lightmap_detail >= 2 ? set.lightmap_detail
                                                                               : 0u,
                                   .detail_factor_max = set.lightmap_detail ? 0u : GLOW_PC_LIGHTMAP_DETAIL_MAX,
                                   .detail_spacing = sqrtf(SF->area),
                                   .texel_adapt = set.texel_adapt, .grid_refine = set.grid_refine,
                                   .lightmap_max_size = set.lightmap_max_size,
                                   .adapt_reach = 4.0f * sqrtf(SF->area / (float)GLOW__PI)};
    res = glow__caches_build(sc, rt, SF, &scache, pool, log, &caches);
    if (res == GLOW_OK && caches.grid_dims[0] && caches.grid_dims[1] && caches.grid_dims[2]) {
        /* which corners of each grid cell a lookup may blend (grid_vis.c) */
        const size_t cells = (size_t)caches.grid_dims[0] * caches.grid_dims[1] * caches.grid_dims[2];
        float ext[3];
        glow__sub(sc->bounds_max, sc->bounds_min, ext);
        /* ... and of each fine cell of the refined grid's bricks, after them (serialise splits it) */
        const size_t R = caches.grid_refine, fine = (size_t)caches.grid_brick_count * R * R * R;
        gvis = malloc(cells * 8 + fine * 8);
        if (!gvis) {
            glow__errorf(log, "%s: out of memory for the grid visibility", scene_path);
            res = GLOW_ERROR_OUT_OF_MEMORY;
        } else {
            res = glow__grid_visibility(rt, &caches, sqrtf(glow__dot(ext, ext)), pool, gvis);
            if (res == GLOW_OK && fine)
                res = glow__grid_fine_visibility(rt, &caches, sqrtf(glow__dot(ext, ext)), pool, gvis + cells * 8);
        }
    }
    if (res == GLOW_OK && writer && !set.no_sky) { /* 1.6: SKYT (sky.c), on the final surfel order */
        const double ts = now_seconds();
        sky_surfel = malloc((size_t)SF->count * GLOW_BAKE_SKY_COEFFS * sizeof *sky_surfel);
        sky_grid = malloc(((size_t)caches.grid_cache_count + 1u) * GLOW_BAKE_SKY_COEFFS * sizeof *sky_grid);
        if (!sky_surfel || !sky_grid) {
            glow__errorf(log, "%s: out of memory for the sky transfer", scene_path);
            res = GLOW_ERROR_OUT_OF_MEMORY;
        } else {
            res = glow__sky_transfer(rt, sc, SF, &caches, set.sky_rays, set.sky_rays * GLOW_PC_SKY_GRID_RAYS, pool,
                                     sky_surfel, sky_grid);
        }
        stats->sky_seconds = now_seconds() - ts;
        stats->sky_rays = set.sky_rays;
        if (res == GLOW_OK)
            glow__infof(log, "sky transfer: %u surfels (%u rays each) and %u grid caches (%u rays each), %.2f s",
                        SF->count, set.sky_rays, caches.grid_cache_count, set.sky_rays * GLOW_PC_SKY_GRID_RAYS,
                        stats->sky_seconds);
    }
    STAGE_END(ST_CACHES);
    if (res != GLOW_OK) goto done;
    stats->grid_spacing = caches.grid_spacing;
    stats->texel_density = caches.texel_density;
    stats->texel_density_max = caches.texel_density_max;
    memcpy(stats->grid_dims, caches.grid_dims, sizeof stats->grid_dims);
    stats->grid_caches = caches.grid_cache_count;
    stats->grid_inside = caches.grid_inside;
    stats->grid_refine = caches.grid_refine;
    stats->grid_bricks = caches.grid_brick_count;
    stats->grid_fine_caches = caches.grid_fine_count;
    stats->lightmap_width = caches.lm_width;
    stats->lightmap_height = caches.lm_height;
    stats->lightmap_pages = caches.lm_pages;
    stats->lightmap_caches = caches.lm_cache_count;
    stats->lightmap_invalid = caches.lm_invalid;
    stats->lightmap_gutter = caches.lm_gutter;
    stats->lightmap_unused = caches.lm_unused;
    {
        const uint64_t covered = (uint64_t)caches.lm_cache_count + caches.lm_invalid;
        stats->lightmap_coverage = covered ? (float)(caches.lm_footprint / (double)covered) : 0.0f;
    }
    stats->charts = caches.chart_count;
    stats->small_charts = caches.small_charts;
    stats->shared_texels = caches.shared_texels;
    stats->caches = caches.count;

    {   /* refuse link tables that cannot fit before trying (each link costs ~28 B while baking) */
        double bytes = (double)caches.count * set.links * (sizeof(glow__link) + (set.sh_links ? 4.0 * set.bands * set.bands : 0.0));
        if (bytes > 64.0 * 1024 * 1024 * 1024) {
            glow__errorf(log, "%s: %u caches x %u links would need %.1f GiB; lower --links or the cache density",
                         scene_path, caches.count, set.links, bytes / (1024.0 * 1024 * 1024));
            res = GLOW_ERROR_INVALID_ARGUMENT;
            goto done;
        }
    }
    if (set.audit_radiance) {
        res = read_audit_radiance(set.audit_radiance, SF->count, log, &audit_radiance);
        if (res != GLOW_OK) goto done;
    }
    STAGE_BEGIN(ST_LINKS);
    glow__link_settings slink = {.links_per_cache = set.links, .sh_bands = set.bands, .full_sh = set.sh_links,
                                 .rays_per_surfel = set.rays_per_surfel, .seed = set.seed,
                                 .no_normalize = set.no_link_normalize, .cut_error = !set.cut_solid_angle,
                                 .audit_radiance = audit_radiance, .link_subsets = !set.no_link_subsets,
                                 .link_gradients = set.link_gradients,
                                 .cluster_tau = set.link_visibility == GLOW_PC_LINK_VISIBILITY_CLUSTERED ? set.link_cluster_angle : 0.0f,
                                 .cluster_samples = set.link_cluster_rays,
                                 .detail_radius = set.detail_radius, .detail_links = set.detail_links,
                                 .dist = set.distribution && set.distribution->ranks > 1 ? set.distribution : NULL};
    if (w) {
        slink.own_leaves = w->own_leaves;
        slink.join = w->join;
        memcpy(slink.trace_lo, w->trace_lo, sizeof slink.trace_lo);
        memcpy(slink.trace_hi, w->trace_hi, sizeof slink.trace_hi);
    }
    res = glow__links_build(sc, rt, w ? &w->surfels : SF, w ? &w->hier : H, &caches, &slink, pool, log, stage_progress,
                            &pc, &links);
    STAGE_END(ST_LINKS);
    if (res != GLOW_OK) goto done;
    uint64_t xref_size = 0;
    if (w) { /* links into the neighbours' trees become proxies (XREF), the rest this system's nodes */
        const uint32_t MN = w->hier.node_count;
        const size_t nlinks = (size_t)caches.count * links.per_cache;
        uint32_t P = 0;
        if (!(proxy_of = malloc(((size_t)MN + 1) * sizeof *proxy_of))) {
            res = GLOW_ERROR_OUT_OF_MEMORY;
            goto done;
        }
        memset(proxy_of, 0xFF, ((size_t)MN + 1) * sizeof *proxy_of);
        for (size_t j = 0; j < nlinks; ++j) {
            const uint32_t v = links.links[j].node;
            if (v >= MN || w->map_dep[v] == SYS_DEP_JOIN) {
                glow__errorf(log, "%s: link %zu reads node %u, which joins the systems' trees (a linker bug)", scene_path, j, v);
                res = GLOW_ERROR_INVALID_ARGUMENT;
                goto done;
            }
            if (w->map_dep[v] != SYS_DEP_OWN && proxy_of[v] == 0xFFFFFFFFu) proxy_of[v] = P++;
        }
        if ((uint64_t)w->own_nodes + P > GLOW_LINK_MAX_NODES) {
            glow__errorf(log, "%s: %u nodes and %u proxy nodes exceed %u; lower the system area", scene_path, w->own_nodes, P,
                         GLOW_LINK_MAX_NODES);
            res = GLOW_ERROR_INVALID_ARGUMENT;
            goto done;
        }
        xref_size = sizeof(glow_bake_xref) + 8u * (uint64_t)w->deps + sizeof(glow_bake_xref_proxy) * (uint64_t)P;
        if (!(xref = calloc(1, (size_t)xref_size))) {
            res = GLOW_ERROR_OUT_OF_MEMORY;
            goto done;
        }
        glow_bake_xref *xh = xref;
        xh->system_key = w->key;
        xh->dependency_count = w->deps;
        xh->proxy_count = P;
        uint64_t *dk = (uint64_t *)(xh + 1);
        if (w->deps) memcpy(dk, w->dep_keys, 8u * (size_t)w->deps);
        glow_bake_xref_proxy *px = (glow_bake_xref_proxy *)(dk + w->deps);
        for (uint32_t v = 0; v < MN; ++v)
            if (proxy_of[v] != 0xFFFFFFFFu) px[proxy_of[v]] = (glow_bake_xref_proxy){w->map_dep[v], w->map_node[v]};
        for (size_t j = 0; j < nlinks; ++j) {
            const uint32_t v = links.links[j].node;
            links.links[j].node = w->map_dep[v] == SYS_DEP_OWN ? w->map_node[v] : w->own_nodes + proxy_of[v];
        }
        stats->proxies = P;
        stats->dependencies = w->deps;
    }
    if (links.audit) report_audit(&caches, &links, audit_csv, set.audit_csv, log);
    stats->links = (uint64_t)caches.count * set.links;
    if (links.detail_count) {
        stats->detail_factor = caches.detail_factor;
        stats->detail_texels = links.detail_count;
        stats->detail_links = links.detail_first[links.detail_count];
        for (uint32_t d = 0; d < links.detail_count; ++d)
            stats->detail_corrected += links.detail_first[d + 1] > links.detail_first[d];
    }
    stats->links_per_cache = set.links;
    stats->bands = set.bands;
    stats->seed = set.seed;
    if (!writer) goto done; /* every rank holds the whole link table now; rank 0 writes it */

    STAGE_BEGIN(ST_WRITE);
    if (w && w->proxy && !(ptre = sys_tree_pack(w->proxy, w->key, &ptre_size))) {
        glow__errorf(log, "write: out of memory for the system's tree (PTRE)");
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    res = serialise(&set, sc, SF, H, &caches, &links, gvis, xref, xref_size, ptre, ptre_size, sky_surfel, sky_grid, &ss,
                    log);
    gvis = NULL; /* the sections own it now */
    for (uint32_t i = 0; i < ss.n; ++i) {
        if (ss.owned[i] == xref) xref = NULL; /* ... and these, once serialise got that far */
        if (ss.owned[i] == ptre) ptre = NULL;
    }
    if (res == GLOW_OK) res = glow__bake_write_file(out_path, ss.s, ss.n, log, &stats->file_size);
    STAGE_END(ST_WRITE);
    if (res != GLOW_OK) goto done;
    stats->section_count = ss.n;
    for (uint32_t i = 0; i < ss.n && i < 16; ++i) {
        stats->section_fourcc[i] = ss.s[i].fourcc;
        stats->section_size[i] = ss.s[i].size;
        if (ss.s[i].fourcc == GLOW_SECTION_LINK && stats->links)
            stats->bytes_per_link = (double)ss.s[i].size / (double)stats->links;
    }
done:
    free(audit_radiance);
    free(gvis);
    free(sky_surfel);
    free(sky_grid);
    free(xref);
    free(ptre);
    free(proxy_of);
    for (uint32_t i = 0; i < ss.n; ++i) free(ss.owned[i]);
    glow__links_free(&links);
    glow__caches_free(&caches);
    glow__hierarchy_free(&hier);
    glow__surfels_free(&surfels);
    return res;
}

/* ------------------------------------------------------------------ systems (issue 16) */
/* A scene split into systems (glow_pc_settings.system_area). Triangles go by their centroid. The cells
 * are fixed in space, so that an edit changes only the systems it touches (incremental re-bakes): the
 * root is the cube [-2^k, 2^k]^3 around the origin, k the smallest that holds every centroid; a cell
 * holding more than the target area is halved at its middle, along x, y, z in turn with its depth,
 * and each half again, down to cells of at most the target area (a single triangle larger than that
 * stays whole, in a cell of its own). Empty cells are no systems. A system is named by its cell:
 * depth and the path of halves (bit i: upper half at depth i). Centroids on a halving plane go up. */
/* Other systems' triangles within this fraction of a system's bounds diagonal occlude its rays, and
 * its caches link their light (glow_pc_settings.system_reach's default). */
#define SYS_REACH_DEFAULT 0.5f

typedef struct sys_part {
    uint32_t first, count; /* range of the partition's triangle order */
    double area;
    uint32_t depth;        /* SYS_NAMED for a system named by the user (path: its name's hash) */
    uint64_t path;
    int group;             /* its --system-group, or -1 */
} sys_part;
#define SYS_NAMED 0xFFFFFFFFu

#define SYS_SPLIT_BINS 1024u

typedef struct sys_split {
    const glow__scene *sc;
    const double *tri_area;
    const float (*cent)[3];
    uint32_t *order, *tmp;
    double target;
    sys_part *parts;
    uint32_t n, cap;
    double cross[SYS_SPLIT_BINS + 2]; /* scratch: surface crossing each candidate plane */
} sys_split;

#define SYS_MAX_DEPTH 60u

static bool split_systems(sys_split *sp, uint32_t first, uint32_t count, const double lo[3], const double hi[3],
                          uint32_t depth, uint64_t path) {
    if (count == 0) return true;
    double area = 0.0;
    for (uint32_t i = first; i < first + count; ++i) area += sp->tri_area[sp->order[i]];
    if (area <= sp->target || count < 2 || depth >= SYS_MAX_DEPTH) {
        if (sp->n == sp->cap) {
            const uint32_t cap = sp->cap ? 2 * sp->cap : 16;
            sys_part *np = realloc(sp->parts, cap * sizeof *np);
            if (!np) return false;
            sp->parts = np;
            sp->cap = cap;
        }
        sp->parts[sp->n++] = (sys_part){first, count, area, depth, path, -1};
        return true;
    }
    /* The axis: the longest extent of the cell's triangles' centroids (ties: x, y, z). A level is wide
     * and low: halving y in turn with x and z cut floors from the walls that stand on them (the 4x4
     * level's floor cells, up to 146 m long, were neighbours of every building along them). Extents
     * are quantised to 1/64 of the cell, so that an edit of a few centimetres does not flip the choice
     * where two are about equal. */
    double cmin[3] = {INFINITY, INFINITY, INFINITY}, cmax[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = first; i < first + count; ++i)
        for (int k = 0; k < 3; ++k) {
            const double c = (double)sp->cent[sp->order[i]][k];
            cmin[k] = c < cmin[k] ? c : cmin[k];
            cmax[k] = c > cmax[k] ? c : cmax[k];
        }
    int axis = 0;
    double best = -1.0;
    const double quantum = fmax(fmax(hi[0] - lo[0], hi[1] - lo[1]), hi[2] - lo[2]) / 64.0;
    for (int k = 0; k < 3; ++k) {
        const double q = quantum > 0.0 ? floor((cmax[k] - cmin[k]) / quantum) : cmax[k] - cmin[k];
        if (q > best) {
            best = q;
            axis = k;
        }
    }
    /* The plane: of the cell's SYS_SPLIT_BINS - 1 evenly spaced planes (fixed in the world) within the
     * middle half of the centroids' range, the one that the least surface crosses (triangles whose
     * extent along the axis contains it), ties to the nearest the middle: a street between two
     * buildings, a gap between rooms, rather than through a building, so that one building is one
     * system or a few and an edit to it changes few systems' trees. Only an edit that adds surface
     * where a plane was chosen, or moves the centroids' range, moves a border. */
    /* The middle half is of the cell's surface, not of its centroids' range: planes with at least a
     * quarter of the cell's area (by centroid) on either side. By the range, the 4x4 Sponza level
     * with a ground of streets (none under the buildings) was cut at a gap 10 m into a building,
     * 1,564 m² against 6,353 m² around a 7,506 m² target, and the large halves, 42 m across, had 17-23
     * neighbours (12.2 a system on average, against 8.7 with this window). */
    const double w = (hi[axis] - lo[axis]) / SYS_SPLIT_BINS;
    double mid_c = 0.5 * (cmin[axis] + cmax[axis]);
    double a_lo = 1.0, a_hi = 0.0;
    if (w > 0.0) { /* the area by centroid bin; plane j lies between bins j - 1 and j */
        memset(sp->cross, 0, sizeof sp->cross);
        for (uint32_t i = first; i < first + count; ++i) {
            const uint32_t t = sp->order[i];
            double b = floor(((double)sp->cent[t][axis] - lo[axis]) / w);
            b = fmin(fmax(b, 0.0), (double)SYS_SPLIT_BINS - 1.0);
            sp->cross[(uint32_t)b] += sp->tri_area[t];
        }
        double below = 0.0, best_half = INFINITY;
        bool lo_set = false;
        for (uint32_t j = 1; j < SYS_SPLIT_BINS; ++j) {
            below += sp->cross[j - 1];
            if (below >= 0.25 * area && below <= 0.75 * area) {
                if (!lo_set) a_lo = j, lo_set = true;
                a_hi = j;
            }
            if (fabs(below - 0.5 * area) < best_half) { /* ties: the plane nearest the area's median */
                best_half = fabs(below - 0.5 * area);
                mid_c = lo[axis] + j * w;
            }
        }
    }
    double mid;
    if (!(w > 0.0) || !(a_lo <= a_hi)) {
        mid = 0.5 * (lo[axis] + hi[axis]);
    } else {
        const uint32_t b0 = (uint32_t)a_lo, b1 = (uint32_t)a_hi;
        memset(sp->cross, 0, sizeof sp->cross);
        for (uint32_t i = first; i < first + count; ++i) { /* difference array over the planes */
            const uint32_t t = sp->order[i];
            double e0 = INFINITY, e1 = -INFINITY;
            for (int c = 0; c < 3; ++c) {
                const double v = (double)sp->sc->pos[3 * (size_t)t + (size_t)c][axis];
                e0 = v < e0 ? v : e0;
                e1 = v > e1 ? v : e1;
            }
            /* planes j with lo + j w strictly inside (e0, e1) */
            double j0 = floor((e0 - lo[axis]) / w) + 1.0, j1 = ceil((e1 - lo[axis]) / w) - 1.0;
            j0 = fmax(j0, (double)b0);
            j1 = fmin(j1, (double)b1);
            if (!(j0 <= j1)) continue;
            sp->cross[(uint32_t)j0] += sp->tri_area[t];
            sp->cross[(uint32_t)j1 + 1] -= sp->tri_area[t];
        }
        double run = 0.0, best_cross = INFINITY, best_dist = INFINITY;
        uint32_t pick = b0;
        for (uint32_t j = b0; j <= b1; ++j) {
            run += sp->cross[j];
            const double c = run > 0.0 ? run : 0.0, pos = lo[axis] + j * w, dist = fabs(pos - mid_c);
            if (c < best_cross * (1.0 - 1e-9) || (c <= best_cross * (1.0 + 1e-9) && dist < best_dist)) {
                best_cross = c;
                best_dist = dist;
                pick = j;
            }
        }
        mid = lo[axis] + pick * w;
    }
    /* stable: the lower half keeps its order, then the upper half */
    uint32_t nl = 0, nu = 0;
    for (uint32_t i = first; i < first + count; ++i) {
        const uint32_t t = sp->order[i];
        if ((double)sp->cent[t][axis] < mid) sp->order[first + nl++] = t;
        else sp->tmp[nu++] = t;
    }
    memcpy(sp->order + first + nl, sp->tmp, nu * sizeof *sp->tmp);
    double lo_u[3], hi_l[3];
    memcpy(lo_u, lo, sizeof lo_u);
    memcpy(hi_l, hi, sizeof hi_l);
    lo_u[axis] = hi_l[axis] = mid;
    return split_systems(sp, first, nl, lo, hi_l, depth + 1, path) &&
           split_systems(sp, first + nl, nu, lo_u, hi, depth + 1, path | (1ull << depth));
}

/* Systems named by the user (glow_pc_settings.system_groups): each group's triangles, in their order,
 * one whole system each at the front of sp->order (groups in their given order, empty ones left out
 * with a warning); *rest = how many. A triangle's object is its source triangle's (a cut piece keeps
 * its triangle's). */
static uint64_t fnv64(uint64_t h, const void *data, size_t n);
static glow_result named_systems(const glow_pc_settings *set, const glow__scene *w, sys_split *sp, uint32_t *rest,
                                 glow__log *log) {
    *rest = 0;
    if (!w->object_count || !w->source_object) {
        glow__errorf(log, "%s: --system-group: the scene names no objects (a built-in scene)", w->source);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t G = set->system_group_count, n = w->tri_count;
    int *obj_group = malloc(((size_t)w->object_count + 1) * sizeof *obj_group);
    uint32_t *count = calloc((size_t)G + 2, sizeof *count);
    if (!obj_group || !count) {
        free(obj_group);
        free(count);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    for (uint32_t o = 0; o < w->object_count; ++o) { /* the first group with a pattern that matches */
        obj_group[o] = -1;
        for (uint32_t g = 0; g < G && obj_group[o] < 0; ++g) {
            const char *p = strchr(set->system_groups[g], '=') + 1;
            while (*p && obj_group[o] < 0) {
                const char *e = strchr(p, ',');
                const size_t len = e ? (size_t)(e - p) : strlen(p);
                char pat[256];
                if (len && len < sizeof pat) {
                    memcpy(pat, p, len);
                    pat[len] = 0;
                    if (fnmatch(pat, w->object_name[o], 0) == 0) obj_group[o] = (int)g;
                }
                p += len + (e ? 1 : 0);
            }
        }
    }
    for (uint32_t t = 0; t < n; ++t) {
        const uint32_t src = w->tri_source[t];
        const int g = src < w->source_tri_count ? obj_group[w->source_object[src]] : -1;
        count[g < 0 ? G : (uint32_t)g]++;
    }
    uint32_t start[257 + 1], at = 0;
    for (uint32_t g = 0; g <= G; ++g) {
        start[g] = at;
        at += count[g];
    }
    for (uint32_t t = 0; t < n; ++t) { /* stable: by group, the rest last */
        const uint32_t src = w->tri_source[t];
        const int g = src < w->source_tri_count ? obj_group[w->source_object[src]] : -1;
        sp->order[start[g < 0 ? G : (uint32_t)g]++] = t;
    }
    glow_result r = GLOW_OK;
    for (uint32_t g = 0, first = 0; g < G; ++g) {
        const char *e = set->system_groups[g];
        const int nl = (int)(strchr(e, '=') - e);
        if (!count[g]) {
            glow__warnf(log, "%s: --system-group %s: no object of the scene matches; no such system", w->source, e);
            continue;
        }
        if (sp->n == sp->cap) {
            const uint32_t cap = sp->cap ? 2 * sp->cap : 16;
            sys_part *np = realloc(sp->parts, cap * sizeof *np);
            if (!np) {
                r = GLOW_ERROR_OUT_OF_MEMORY;
                break;
            }
            sp->parts = np;
            sp->cap = cap;
        }
        double area = 0.0;
        for (uint32_t i = first; i < first + count[g]; ++i) area += sp->tri_area[sp->order[i]];
        sp->parts[sp->n++] = (sys_part){first, count[g], area, SYS_NAMED, fnv64(0xcbf29ce484222325ull, e, (size_t)nl), (int)g};
        glow__infof(log, "%s: system %.*s: %u triangles, area %.6g (named)", w->source, nl, e, count[g], area);
        first += count[g];
        *rest = first;
    }
    free(obj_group);
    free(count);
    return r;
}

/* Group g's declared neighbours (glow_pc_settings.system_neighbours: "" none), or NULL: automatic */
static const char *sys_declared(const glow_pc_settings *set, int g) {
    return g >= 0 && set->system_neighbours ? set->system_neighbours[g] : NULL;
}

/* Whether the list "NAME[,NAME...]" holds the name of `group` ("NAME=PATTERNS") */
static bool sys_lists(const char *list, const char *group) {
    const size_t nl = (size_t)(strchr(group, '=') - group);
    while (*list) {
        const char *c = strchr(list, ',');
        const size_t len = c ? (size_t)(c - list) : strlen(list);
        if (len == nl && !strncmp(list, group, nl)) return true;
        list += len + (c ? 1 : 0);
    }
    return false;
}

/* The triangles order[first, first + count) of `world` as a scene of their own: copies of the per-corner
 * arrays, the world's materials and textures shared (sys_scene_free frees only the copies). */
static bool sys_scene(const glow__scene *w, const double *tri_area_w, const uint32_t *order, uint32_t count, uint32_t index,
                      glow__scene *out) {
    memset(out, 0, sizeof *out);
    out->tri_count = count;
    out->pos = malloc((size_t)count * 3 * sizeof *out->pos);
    out->nrm = malloc((size_t)count * 3 * sizeof *out->nrm);
    out->uv0 = w->uv0 ? malloc((size_t)count * 3 * sizeof *out->uv0) : NULL;
    out->uv1 = w->uv1 ? malloc((size_t)count * 3 * sizeof *out->uv1) : NULL;
    out->tri_material = malloc((size_t)count * sizeof *out->tri_material);
    out->tri_source = malloc((size_t)count * sizeof *out->tri_source);
    if (!out->pos || !out->nrm || (w->uv0 && !out->uv0) || (w->uv1 && !out->uv1) || !out->tri_material ||
        !out->tri_source)
        return false;
    for (int k = 0; k < 3; ++k) {
        out->bounds_min[k] = INFINITY;
        out->bounds_max[k] = -INFINITY;
    }
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t t = order[i];
        memcpy(out->pos[3 * (size_t)i], w->pos[3 * (size_t)t], sizeof(float[3][3]));
        memcpy(out->nrm[3 * (size_t)i], w->nrm[3 * (size_t)t], sizeof(float[3][3]));
        if (out->uv0) memcpy(out->uv0[3 * (size_t)i], w->uv0[3 * (size_t)t], sizeof(float[3][2]));
        if (out->uv1) memcpy(out->uv1[3 * (size_t)i], w->uv1[3 * (size_t)t], sizeof(float[3][2]));
        out->tri_material[i] = w->tri_material[t];
        out->tri_source[i] = w->tri_source ? w->tri_source[t] : t;
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) {
                const float v = out->pos[3 * (size_t)i + c][k];
                out->bounds_min[k] = v < out->bounds_min[k] ? v : out->bounds_min[k];
                out->bounds_max[k] = v > out->bounds_max[k] ? v : out->bounds_max[k];
            }
        out->area += tri_area_w[t];
    }
    out->material_count = w->material_count;
    out->materials = w->materials;
    out->texture_count = w->texture_count;
    out->textures = w->textures;
    out->source_tri_count = count;
    out->normals_generated = w->normals_generated;
    snprintf(out->source, sizeof out->source, "%.480s (system %u)", w->source, index);
    return true;
}

static void sys_scene_free(glow__scene *s) {
    free(s->pos);
    free(s->nrm);
    free(s->uv0);
    free(s->uv1);
    free(s->tri_material);
    free(s->tri_source);
    memset(s, 0, sizeof *s);
}

static void add_vec3(cJSON *o, const char *name, const float v[3]) {
    const double d[3] = {v[0], v[1], v[2]};
    cJSON_AddItemToObject(o, name, cJSON_CreateDoubleArray(d, 3));
}

/* Sums one system's stats into the world's (see glow_pc_stats.systems). */
static void sys_stats_add(glow_pc_stats *w, const glow_pc_stats *s, bool largest) {
    w->dependencies += s->dependencies;
    w->proxies += s->proxies;
    for (int k = ST_SURFELS; k < GLOW_PC_STAGE_COUNT; ++k) {
        w->stage_seconds[k] += s->stage_seconds[k];
        if (s->stage_peak_rss[k] > w->stage_peak_rss[k]) w->stage_peak_rss[k] = s->stage_peak_rss[k];
    }
    if (largest) { /* the resolved settings of the largest system */
        w->links_per_cache = s->links_per_cache;
        w->bands = s->bands;
        w->seed = s->seed;
        w->grid_spacing = s->grid_spacing;
        w->texel_density = s->texel_density;
        w->texel_density_max = s->texel_density_max;
        memcpy(w->grid_dims, s->grid_dims, sizeof w->grid_dims);
        w->lightmap_width = s->lightmap_width;
        w->lightmap_height = s->lightmap_height;
        w->lightmap_pages = s->lightmap_pages;
        w->detail_factor = s->detail_factor;
        w->levels = s->levels;
    }
    const double cov = (double)w->lightmap_coverage * ((double)w->lightmap_caches + w->lightmap_invalid) +
                       (double)s->lightmap_coverage * ((double)s->lightmap_caches + s->lightmap_invalid);
    w->surfels += s->surfels;
    w->nodes += s->nodes;
    w->grid_caches += s->grid_caches;
    w->grid_inside += s->grid_inside;
    w->grid_bricks += s->grid_bricks;
    w->grid_fine_caches += s->grid_fine_caches;
    w->sky_seconds += s->sky_seconds;
    if (s->sky_rays) w->sky_rays = s->sky_rays;
    if (s->grid_refine > w->grid_refine) w->grid_refine = s->grid_refine;
    w->lightmap_caches += s->lightmap_caches;
    w->lightmap_invalid += s->lightmap_invalid;
    w->lightmap_gutter += s->lightmap_gutter;
    w->lightmap_unused += s->lightmap_unused;
    const double covered = (double)w->lightmap_caches + w->lightmap_invalid;
    w->lightmap_coverage = covered > 0.0 ? (float)(cov / covered) : 0.0f;
    w->charts += s->charts;
    w->small_charts += s->small_charts;
    w->shared_texels += s->shared_texels;
    w->caches += s->caches;
    w->links += s->links;
    w->file_size += s->file_size;
    w->detail_texels += s->detail_texels;
    w->detail_corrected += s->detail_corrected;
    w->detail_links += s->detail_links;
    for (uint32_t i = 0; i < s->section_count && i < 16; ++i) { /* sums by section (some are optional) */
        uint32_t k = 0;
        while (k < w->section_count && w->section_fourcc[k] != s->section_fourcc[i]) ++k;
        if (k == 16) continue;
        if (k == w->section_count) {
            w->section_fourcc[k] = s->section_fourcc[i];
            w->section_count++;
        }
        w->section_size[k] += s->section_size[i];
    }
}

/* Writes the world manifest (JSON) atomically: temp file + rename. */
static glow_result write_manifest(const char *path, const char *text, glow__log *log) {
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%.4000s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        glow__errorf(log, "%s: cannot write the world manifest", path);
        return GLOW_ERROR_IO;
    }
    const size_t len = strlen(text);
    bool ok = fwrite(text, 1, len, f) == len && fputc('\n', f) != EOF;
    ok = (fclose(f) == 0) && ok;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        glow__errorf(log, "%s: writing the world manifest failed (disk full?)", path);
        return GLOW_ERROR_IO;
    }
    return GLOW_OK;
}

/* Incremental re-bakes key each system by a hash of everything its bytes follow from. FNV-1a (64 bit):
 * a change detector, not a defence against forged inputs; zlib's CRC-32 is too short for a key. */
static uint64_t fnv64(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    while (n--) {
        h ^= *p++;
        h *= 0x100000001b3ull;
    }
    return h;
}
#define FNV_INIT 0xcbf29ce484222325ull
#define HASH_VAL(h, v) ((h) = fnv64((h), &(v), sizeof(v)))

/* The settings a system's bytes follow from, the bake format and the world's materials and textures
 * (contents and names): the part of every system's key that is not its own geometry. */
static uint64_t world_key(const glow_pc_settings *s, const glow__scene *w) {
    uint64_t h = FNV_INIT;
    const uint32_t v[] = {GLOW_BAKE_FORMAT_VERSION_MAJOR, GLOW_BAKE_FORMAT_VERSION_MINOR, GLOW_VERSION,
                          (uint32_t)s->quality, s->surfels, s->links, s->bands, s->seed, s->sh_links,
                          s->relax_iterations, s->rays_per_surfel, s->no_link_normalize, s->cut_solid_angle,
                          s->lightmap_caches, s->no_link_subsets, (uint32_t)s->link_visibility, s->link_cluster_rays,
                          s->lightmap_detail, s->detail_links, w->material_count, w->texture_count, s->grid_refine,
                          s->link_gradients, s->no_sky, s->no_sky ? 0u : s->sky_rays};
    const float f[] = {s->grid_spacing, s->texel_density, s->link_cluster_angle, s->detail_radius, s->surfel_adapt,
                       s->system_area, s->system_reach > 0.0f ? s->system_reach : SYS_REACH_DEFAULT, s->texel_adapt};
    h = fnv64(h, v, sizeof v);
    h = fnv64(h, f, sizeof f);
    if (s->lightmap_max_size && s->lightmap_max_size != 4096u) HASH_VAL(h, s->lightmap_max_size); /* (keys unchanged without) */
    for (uint32_t m = 0; m < w->material_count; ++m) {
        const glow__material *mt = &w->materials[m];
        h = fnv64(h, mt->name, strnlen(mt->name, sizeof mt->name));
        h = fnv64(h, mt->albedo, sizeof mt->albedo);
        h = fnv64(h, mt->emission, sizeof mt->emission);
        HASH_VAL(h, mt->texture);
        HASH_VAL(h, mt->emission_texture);
    }
    for (uint32_t t = 0; t < w->texture_count; ++t) {
        const glow__texture *tx = &w->textures[t];
        h = fnv64(h, tx->path, strnlen(tx->path, sizeof tx->path));
        HASH_VAL(h, tx->width);
        HASH_VAL(h, tx->height);
        if (tx->levels[0]) h = fnv64(h, tx->levels[0], (size_t)tx->width * tx->height * 3 * sizeof(float));
    }
    return h;
}

/* A system's key: the world's part, its cell, its triangles and the occluders it traces. Not the
 * triangles' indices in the file (tri_source): only GEOM's `source` fields follow from those, so a
 * system whose triangles merely moved in the file keeps its key, and its file is patched, not baked
 * (patch_sources; the file's name adds a hash of the indices, sources_key). */
static uint64_t system_key(uint64_t world, const sys_part *part, const glow__scene *sub, const float *occ, uint32_t nocc) {
    uint64_t h = world;
    HASH_VAL(h, part->depth);
    HASH_VAL(h, part->path);
    const size_t n = sub->tri_count;
    h = fnv64(h, sub->pos, n * 3 * sizeof *sub->pos);
    h = fnv64(h, sub->nrm, n * 3 * sizeof *sub->nrm);
    if (sub->uv0) h = fnv64(h, sub->uv0, n * 3 * sizeof *sub->uv0);
    if (sub->uv1) h = fnv64(h, sub->uv1, n * 3 * sizeof *sub->uv1);
    h = fnv64(h, sub->tri_material, n * sizeof *sub->tri_material);
    HASH_VAL(h, nocc);
    return fnv64(h, occ, (size_t)nocc * 9 * sizeof *occ);
}

static void beside(const char *out_path, const char *file, char *buf, size_t n);

/* Whether the file at `path` is there with `bytes` bytes (what a manifest recorded of it). */
static bool file_has_size(const char *path, double bytes) {
    FILE *f = fopen(path, "rb");
    if (!f) return false;
    long len = -1;
    if (fseek(f, 0, SEEK_END) == 0) len = ftell(f);
    fclose(f);
    return len >= 0 && (double)len == bytes;
}

/* The hash of a system's triangles' indices in the imported file: with the content key, its file key. */
static uint64_t sources_key(const glow__scene *sub) {
    return fnv64(FNV_INIT ^ 0x736f7572636573ull, sub->tri_source, (size_t)sub->tri_count * sizeof *sub->tri_source);
}

/* An incremental re-bake where a system's content is unchanged but its triangles' indices in the file
 * moved (triangles added or removed before them): the previous file `from` is copied to `to` with
 * GEOM's `source` fields from sub->tri_source (the same triangles in the same order) and its CRCs
 * redone. Nothing else in a system's bytes follows from the indices, so the result is what a bake
 * would write. Written under TO.tmp and renamed; GLOW_ERROR_IO / CORRUPT_DATA (the old file is not
 * the bake its manifest entry says: the caller bakes instead) / OUT_OF_MEMORY. */
static glow_result patch_sources(const char *from, const char *to, const glow__scene *sub) {
    FILE *f = fopen(from, "rb");
    if (!f) return GLOW_ERROR_IO;
    long len = -1;
    if (fseek(f, 0, SEEK_END) == 0) len = ftell(f);
    unsigned char *img = len > (long)sizeof(glow_bake_header) && fseek(f, 0, SEEK_SET) == 0 ? malloc((size_t)len) : NULL;
    const bool read = img && fread(img, 1, (size_t)len, f) == (size_t)len;
    fclose(f);
    if (!read) {
        free(img);
        return img || len <= (long)sizeof(glow_bake_header) ? GLOW_ERROR_IO : GLOW_ERROR_OUT_OF_MEMORY;
    }
    glow_bake_header h;
    memcpy(&h, img, sizeof h);
    const uint64_t table_end = sizeof h + (uint64_t)h.section_count * sizeof(glow_bake_section);
    glow_result r = GLOW_ERROR_CORRUPT_DATA;
    if (memcmp(h.magic, "GLOW", 4) != 0 || h.file_size != (uint64_t)len || table_end > (uint64_t)len) goto out;
    for (uint32_t i = 0; i < h.section_count; ++i) {
        glow_bake_section sec;
        memcpy(&sec, img + sizeof h + (size_t)i * sizeof sec, sizeof sec);
        if (sec.fourcc != GLOW_SECTION_GEOM) continue;
        if (sec.size != (uint64_t)sub->tri_count * sizeof(glow_bake_triangle) || sec.offset > (uint64_t)len ||
            sec.size > (uint64_t)len - sec.offset)
            goto out;
        unsigned char *tri = img + sec.offset;
        for (uint32_t t = 0; t < sub->tri_count; ++t)
            memcpy(tri + (size_t)t * sizeof(glow_bake_triangle) + offsetof(glow_bake_triangle, source), &sub->tri_source[t],
                   sizeof(uint32_t));
        sec.crc32 = glow__crc32(0, tri, (size_t)sec.size);
        memcpy(img + sizeof h + (size_t)i * sizeof sec, &sec, sizeof sec);
        h.table_crc32 = glow__crc32(0, img + sizeof h, (size_t)h.section_count * sizeof sec);
        h.header_crc32 = 0;
        h.header_crc32 = glow__crc32(0, &h, sizeof h);
        memcpy(img, &h, sizeof h);
        char tmp[4300];
        snprintf(tmp, sizeof tmp, "%s.tmp", to);
        FILE *o = fopen(tmp, "wb");
        bool ok = o && fwrite(img, 1, (size_t)len, o) == (size_t)len;
        if (o && fclose(o) != 0) ok = false;
        if (!ok || rename(tmp, to) != 0) {
            remove(tmp);
            r = GLOW_ERROR_IO;
        } else {
            r = GLOW_OK;
        }
        break;
    }
out:
    free(img);
    return r;
}

/* The previous manifest's next system entry after `from` (NULL: from the first) whose string `field`
 * is `value` and whose file is still there at the size it recorded, or NULL; *path gets that file's
 * path. */
static const cJSON *previous_with(const cJSON *prev, const char *field, const char *value, const cJSON *from,
                                  const char *out_path, char *path, size_t n) {
    const cJSON *list = cJSON_GetObjectItem(prev, "systems");
    for (const cJSON *e = from ? from->next : list ? list->child : NULL; e; e = e->next) {
        const cJSON *ve = cJSON_GetObjectItem(e, field), *fe = cJSON_GetObjectItem(e, "file"),
                    *be = cJSON_GetObjectItem(e, "bytes");
        if (!cJSON_IsString(ve) || strcmp(ve->valuestring, value) != 0 || !cJSON_IsString(fe) || !cJSON_IsNumber(be) ||
            strchr(fe->valuestring, '/'))
            continue;
        beside(out_path, fe->valuestring, path, n);
        if (file_has_size(path, be->valuedouble)) return e;
    }
    return NULL;
}

/* The previous manifest's entry with this content key (the file key less the triangles' indices) whose
 * file is still there at the size it recorded, or NULL; *old_path gets that file's path. */
static const cJSON *previous_content(const cJSON *prev, const char *content, const char *out_path, char *old_path,
                                     size_t n) {
    return previous_with(prev, "content_key", content, NULL, out_path, old_path, n);
}

/* The previous manifest at out_path, when it is one of ours (else NULL: everything is baked). */
static cJSON *read_previous(const char *out_path) {
    FILE *f = fopen(out_path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    long len = -1;
    if (fseek(f, 0, SEEK_END) == 0 && (len = ftell(f)) > 0 && len < (64l << 20) && fseek(f, 0, SEEK_SET) == 0 &&
        (buf = malloc((size_t)len + 1)) && fread(buf, 1, (size_t)len, f) == (size_t)len)
        buf[len] = 0;
    else {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    cJSON *j = buf ? cJSON_Parse(buf) : NULL;
    free(buf);
    if (j && !(cJSON_IsNumber(cJSON_GetObjectItem(j, "glow_world")) && cJSON_IsArray(cJSON_GetObjectItem(j, "systems")))) {
        cJSON_Delete(j);
        j = NULL;
    }
    return j;
}

/* The previous manifest's entry for a system file of this name whose file is still there at the size
 * it recorded, or NULL. */
static const cJSON *previous_entry(const cJSON *prev, const char *file, const char *path) {
    const cJSON *e;
    cJSON_ArrayForEach(e, cJSON_GetObjectItem(prev, "systems")) {
        const cJSON *fe = cJSON_GetObjectItem(e, "file"), *be = cJSON_GetObjectItem(e, "bytes");
        if (!cJSON_IsString(fe) || strcmp(fe->valuestring, file) != 0 || !cJSON_IsNumber(be)) continue;
        return file_has_size(path, be->valuedouble) ? e : NULL;
    }
    return NULL;
}

static double json_num(const cJSON *o, const char *name) {
    const cJSON *x = cJSON_GetObjectItem(o, name);
    return cJSON_IsNumber(x) ? x->valuedouble : 0.0;
}

/* The path of a file named in the manifest: beside it. */
static void beside(const char *out_path, const char *file, char *buf, size_t n) {
    const char *slash = strrchr(out_path, '/');
    const int dir = slash ? (int)(slash - out_path + 1) : 0;
    if ((size_t)snprintf(buf, n, "%.*s%s", dir < 4000 ? dir : 4000, out_path, file) >= n) buf[0] = 0; /* never: names are short */
}

/* A baked system's figures in the manifest: surfels, caches, grid caches, lightmap caches, texel
 * density, bytes, proxy nodes. */
#define SYS_REC 7

/* A system's manifest entry up to what its bake reports (bake_systems adds that, in SYS_REC's order). */
static cJSON *sys_entry(uint32_t index, const char *file, const char *key, const glow__scene *sub, uint32_t occluders) {
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "index", index);
    cJSON_AddStringToObject(o, "file", file);
    cJSON_AddStringToObject(o, "key", key);
    add_vec3(o, "bounds_min", sub->bounds_min);
    add_vec3(o, "bounds_max", sub->bounds_max);
    cJSON_AddNumberToObject(o, "area", sub->area);
    cJSON_AddNumberToObject(o, "triangles", sub->tri_count);
    cJSON_AddNumberToObject(o, "occluders", occluders);
    return o;
}

/* ------------------------------------------------------------ light across systems */
/* The systems of a world link their neighbours' trees. A system's neighbours are the systems whose
 * triangles it traces as occluders (within the reach of its bounds): where its rays see
 * every surface, so where a link's visibility is exact. At most SYS_MAX_DEPS (and a quarter of the
 * links per cache, so that the cut always has room for its roots), those with the most occluders. */
#define SYS_MAX_DEPS GLOW_BAKE_MAX_DEPENDENCIES

typedef struct sys_world {
    const glow__scene *w;
    const glow_pc_settings *set;
    const preset *p;
    const double *tri_area;
    const sys_split *sp;
    float reach; /* glow_pc_settings.system_reach, resolved */
    float *foreign; /* scratch: the occluders of the system being prepared (its rays keep a pointer) */
    const float (*tb)[6]; /* the bounds (lo x y z, hi x y z) of the triangle at each place of sp->order */
    glow__pool *pool;
    glow__log *log;
} sys_world;

/* System s's budgets: the preset's per system_area of surface */
static void sys_budget(const sys_world *W, uint32_t s, glow_pc_settings *sset, uint32_t *grid_target) {
    const glow_pc_settings *set = W->set;
    const double f = W->sp->parts[s].area / set->system_area;
    *sset = *set;
    const double sv = (double)set->surfels * f;
    sset->surfels = sv < 16.0 ? 16u : (sv > (double)(1u << 22) ? (1u << 22) : (uint32_t)lround(sv));
    const double lv = (double)set->lightmap_caches * f;
    sset->lightmap_caches = lv < 1.0 ? 1u : (uint32_t)lround(lv);
    const double gv = (double)W->p->grid * f;
    *grid_target = gv < 8.0 ? 8u : (uint32_t)lround(gv);
    sset->distribution = NULL; /* a system is baked by one rank, whole */
}

/* System s's scene, its occluders (into W->foreign; *nf of them), the box they fill (bounds grown by
 * the margin) and, when owner_count is given, how many occluders each other system owns. */
static bool sys_prepare(const sys_world *W, uint32_t s, glow__scene *sub, uint32_t *nf, float olo[3], float ohi[3],
                        const uint32_t *sys_of, uint32_t *owner_count) {
    const sys_part *part = &W->sp->parts[s];
    const uint32_t n = W->w->tri_count;
    if (!sys_scene(W->w, W->tri_area, W->sp->order + part->first, part->count, s, sub)) return false;
    /* The rest of the world occludes within the reach: the box of the system's bounds grown by a
     * fraction of their diagonal (system_reach). Every ray whose hits this system uses runs between its
     * own caches and surfels, within their near field, or to a neighbour's surfel inside that box (the
     * links skip those beyond it), so inside the box, where every occluder is traced; a ray that would
     * have hit another system beyond counts as sky either way. */
    float e[3];
    glow__sub(sub->bounds_max, sub->bounds_min, e);
    const float m = W->reach * sqrtf(glow__dot(e, e));
    for (int k = 0; k < 3; ++k) {
        olo[k] = sub->bounds_min[k] - m;
        ohi[k] = sub->bounds_max[k] + m;
    }
    *nf = 0;
    /* every system scans every triangle (systems x triangles: 128 x 4.3M on the 8x8 level), so the
     * triangles' bounds are worked out once (tb), in the order scanned */
    for (uint32_t i = 0; i < n; ++i) {
        if (i == part->first) i += part->count;
        if (i >= n) break;
        const float *b = W->tb[i];
        if (!(b[3] >= olo[0] && b[0] <= ohi[0] && b[4] >= olo[1] && b[1] <= ohi[1] && b[5] >= olo[2] && b[2] <= ohi[2]))
            continue;
        const float(*P)[3] = W->w->pos + 3 * (size_t)W->sp->order[i];
        memcpy(W->foreign + 9 * (size_t)*nf, P, 9 * sizeof(float));
        (*nf)++;
        if (owner_count) owner_count[sys_of[i]]++;
    }
    return true;
}

/* System s's surfels and hierarchy (once), from its scene and rays as its own bake would place them */
static glow_result sys_base_build(const sys_world *W, uint32_t s, const glow__scene *sub, const glow__rt *rt,
                                  sys_base *b) {
    if (b->done) return GLOW_OK;
    glow_pc_settings sset;
    uint32_t gt;
    sys_budget(W, s, &sset, &gt);
    double t0 = now_seconds();
    glow__surfel_settings ssurf = {.count = sset.surfels, .seed = sset.seed, .relax_iterations = sset.relax_iterations,
                                   .adapt = sset.surfel_adapt, .rt = rt};
    glow_result res = glow__surfels_place(sub, &ssurf, W->pool, W->log, &b->surfels);
    double t1 = now_seconds();
    if (res == GLOW_OK)
        res = glow__hierarchy_build_rt(&b->surfels, sub->bounds_min, sub->bounds_max, rt, W->pool, W->log, &b->hier);
    b->seconds[0] = t1 - t0;
    b->seconds[1] = now_seconds() - t1;
    b->done = res == GLOW_OK;
    return res;
}

/* sys_base_build for a neighbour: its scene and rays made, used and dropped here */
static glow_result sys_base_of(const sys_world *W, uint32_t s, sys_base *b) {
    if (b->done) return GLOW_OK;
    glow__scene sub;
    uint32_t nf = 0;
    float olo[3], ohi[3];
    glow__rt *rt = NULL;
    glow_result res = GLOW_ERROR_OUT_OF_MEMORY;
    if (sys_prepare(W, s, &sub, &nf, olo, ohi, NULL, NULL)) {
        res = glow__rt_create_system(&sub, W->foreign, nf, W->log, &rt);
        if (res == GLOW_OK) res = sys_base_build(W, s, &sub, rt, b);
    } else {
        glow__errorf(W->log, "%s: out of memory for system %u", W->w->source, s);
    }
    glow__rt_destroy(rt);
    sys_scene_free(&sub);
    return res;
}

static void sys_base_free(sys_base *b) {
    glow__surfels_free(&b->surfels);
    glow__hierarchy_free(&b->hier);
    memset(b, 0, sizeof *b);
}

/* The path of system `part`'s bake of file key `key`: STEM.sDEPTH-PATH-KEY.glow (or STEM.GROUP-KEY.glow)
 * beside the manifest, STEM: out_path less a ".json" or ".glow" ending */
static void sys_file_path(const char *out_path, const glow_pc_settings *set, const sys_part *part, uint64_t key,
                          char *path, size_t n) {
    char keyhex[20], name[4200];
    snprintf(keyhex, sizeof keyhex, "%016llx", (unsigned long long)key);
    size_t len = strlen(out_path), st = 0;
    if (len > 5 && (strcmp(out_path + len - 5, ".json") == 0 || strcmp(out_path + len - 5, ".glow") == 0)) len -= 5;
    for (size_t i = 0; i < len; ++i)
        if (out_path[i] == '/') st = i + 1;
    const int sl = (int)(len - st);
    if (part->group >= 0) {
        const char *g = set->system_groups[part->group];
        snprintf(name, sizeof name, "%.*s.%.*s-%s.glow", sl < 4000 ? sl : 4000, out_path + st, (int)(strchr(g, '=') - g), g,
                 keyhex);
    } else {
        snprintf(name, sizeof name, "%.*s.s%u-%llx-%s.glow", sl < 4000 ? sl : 4000, out_path + st, part->depth,
                 (unsigned long long)part->path, keyhex);
    }
    beside(out_path, name, path, n);
}

/* A system's file key: its content key and its triangles' indices in the file (the key in its file's
 * name; the files a distributed bake may write are listed by it before they are baked) */
static uint64_t sys_file_key(uint64_t content, uint64_t sources) {
    HASH_VAL(content, sources);
    return content;
}

/* forward: sys_tree_make and sys_tree_read are below, with the trees' merge */
static bool sys_tree_make(const sys_base *b, bool coarsen, sys_tree *t);
static bool sys_tree_read(const char *path, uint64_t key, sys_tree *t);

/* Neighbour d's tree as the links see it (tree key `key`), once: from the PTRE of a previous bake of
 * the same tree when the previous world (prev) has one (counted in *read), else placed and clustered
 * (sys_base_of) and coarsened. An edit re-bakes the systems around it; their unchanged neighbours'
 * trees are read, not built again. */
static glow_result sys_tree_of(const sys_world *W, uint32_t d, uint64_t key, const cJSON *prev, const char *out_path,
                               sys_base *b, sys_tree *t, uint32_t *read) {
    if (t->nodes) return GLOW_OK;
    if (prev && !b->done) {
        char hex[20], path[4200];
        snprintf(hex, sizeof hex, "%016llx", (unsigned long long)key);
        for (const cJSON *e = previous_with(prev, "system_key", hex, NULL, out_path, path, sizeof path); e;
             e = previous_with(prev, "system_key", hex, e, out_path, path, sizeof path))
            if (sys_tree_read(path, key, t)) {
                (*read)++;
                return GLOW_OK;
            }
    }
    glow_result res = sys_base_of(W, d, b);
    if (res == GLOW_OK && !sys_tree_make(b, true, t)) {
        glow__errorf(W->log, "%s: out of memory for system %u's tree", W->w->source, d);
        res = GLOW_ERROR_OUT_OF_MEMORY;
    }
    return res;
}

static void sys_links_free(sys_links_in *x) {
    free(x->surfels.s);
    free(x->hier.nodes);
    free(x->join);
    free(x->map_dep);
    free(x->map_node);
    memset(x, 0, sizeof *x);
}

/* A neighbour's tree as the links see it: its nodes of at most SYS_PROXY_LEAVES leaves whose parent has
 * more become leaves (a disc of the node's area, centre and mean normal), the nodes below them go.
 * The links' cost grows with the leaves they see; a neighbour seen through a border is linked at
 * this coarser grain, at a sixteenth of the work its full tree would take. */
#define SYS_PROXY_LEAVES 16u

/* per node of h: its leaf count (children precede parents) */
static uint32_t *leaf_counts(const glow__hierarchy *h) {
    uint32_t *c = malloc(((size_t)h->node_count + 1) * sizeof *c);
    if (!c) return NULL;
    for (uint32_t v = 0; v < h->node_count; ++v)
        c[v] = v < h->leaf_count ? 1u : c[h->nodes[v].child[0]] + c[h->nodes[v].child[1]];
    return c;
}

static void sys_tree_free(sys_tree *t) {
    free(t->nodes);
    free(t->leaves);
    free(t->source);
    memset(t, 0, sizeof *t);
}

/* A system's tree as the links see it: whole (coarsen false: its own) or as a neighbour's links see it
 * (nodes of at most SYS_PROXY_LEAVES leaves whose parent has more become leaves). */
static bool sys_tree_make(const sys_base *b, bool coarsen, sys_tree *t) {
    const glow__hierarchy *h = &b->hier;
    const uint32_t N = h->node_count;
    memset(t, 0, sizeof *t);
    uint32_t *cnt = leaf_counts(h), *idx = malloc(((size_t)N + 1) * sizeof *idx);
    uint32_t *first = malloc(((size_t)N + 1) * sizeof *first), *at = calloc((size_t)h->leaf_count + 1, sizeof *at);
    bool ok = cnt && idx && first && at && N > 0;
    uint32_t nL = 0, nI = 0;
    if (ok) {
        /* the leaves in depth-first order (each subtree's leaves contiguous, as links.c needs): a
         * coarsened leaf's place is that of its first original leaf, which the tree's leaf order gives */
        for (uint32_t v = 0; v < N; ++v) {
            if (v < h->leaf_count) { first[v] = v; continue; }
            const uint32_t a = first[h->nodes[v].child[0]], c = first[h->nodes[v].child[1]];
            first[v] = a < c ? a : c;
        }
        for (uint32_t v = 0; v < N; ++v) {
            const uint32_t par = h->nodes[v].parent;
            const bool leaf = !coarsen ? v < h->leaf_count
                                       : cnt[v] <= SYS_PROXY_LEAVES && (par == GLOW_NODE_NONE || cnt[par] > SYS_PROXY_LEAVES);
            const bool kept = !coarsen || leaf || cnt[v] > SYS_PROXY_LEAVES;
            idx[v] = !kept ? GLOW_NODE_NONE : leaf ? 0x80000000u : nI++;
            if (leaf) at[first[v]] = v + 1;
        }
        for (uint32_t i = 0; i < h->leaf_count; ++i)
            if (at[i]) idx[at[i] - 1] = nL++ | 0x80000000u;
        const uint32_t M = nL + nI;
        t->nodes = malloc((size_t)M * sizeof *t->nodes);
        t->leaves = calloc(nL, sizeof *t->leaves);
        t->source = malloc((size_t)M * sizeof *t->source);
        ok = t->nodes && t->leaves && t->source;
    }
    if (ok) {
        t->leaf_count = nL;
        t->node_count = nL + nI;
#define SYS_MAP(u) ((idx[u] & 0x80000000u) ? (idx[u] & 0x7FFFFFFFu) : nL + idx[u])
        for (uint32_t u = 0; u < N; ++u) {
            if (idx[u] == GLOW_NODE_NONE) continue;
            const uint32_t m = SYS_MAP(u);
            glow__node nd = h->nodes[u];
            if (idx[u] & 0x80000000u) { /* a leaf: the surfel, or a node as one disc */
                glow__surfel *sf = &t->leaves[m];
                if (u < h->leaf_count) {
                    *sf = b->surfels.s[u];
                } else {
                    memcpy(sf->pos, nd.pos, sizeof sf->pos);
                    memcpy(sf->nrm, nd.nrm, sizeof sf->nrm);
                    sf->area = nd.area;
                }
                nd.child[0] = nd.child[1] = GLOW_NODE_NONE;
                nd.level = 0;
            } else {
                for (int c = 0; c < 2; ++c) nd.child[c] = SYS_MAP(nd.child[c]);
            }
            if (nd.parent != GLOW_NODE_NONE) nd.parent = SYS_MAP(nd.parent);
            t->nodes[m] = nd;
            t->source[m] = u;
        }
        t->root = SYS_MAP(N - 1);
#undef SYS_MAP
        /* levels above the coarsened leaves: 1 + the children's */
        for (uint32_t m = nL; m < t->node_count; ++m) {
            const glow__node *a = &t->nodes[t->nodes[m].child[0]], *c = &t->nodes[t->nodes[m].child[1]];
            t->nodes[m].level = 1 + (a->level > c->level ? a->level : c->level);
        }
    } else {
        sys_tree_free(t);
    }
    free(cnt);
    free(idx);
    free(first);
    free(at);
    return ok;
}

/* PTRE's payload for tree t of key `key` (bake_format.h glow_bake_ptree), or NULL (out of memory) */
static void *sys_tree_pack(const sys_tree *t, uint64_t key, uint64_t *size) {
    *size = sizeof(glow_bake_ptree) + (uint64_t)t->node_count * sizeof(glow_bake_ptree_node) +
            (uint64_t)t->leaf_count * sizeof(glow_bake_ptree_leaf);
    uint8_t *buf = calloc(1, (size_t)*size);
    if (!buf) return NULL;
    const glow_bake_ptree ph = {.tree_key = key, .node_count = t->node_count, .leaf_count = t->leaf_count, .root = t->root};
    memcpy(buf, &ph, sizeof ph);
    uint8_t *q = buf + sizeof ph;
    for (uint32_t i = 0; i < t->node_count; ++i, q += sizeof(glow_bake_ptree_node)) {
        const glow__node *n = &t->nodes[i];
        glow_bake_ptree_node o = {.child = {n->child[0], n->child[1]}, .parent = n->parent, .level = n->level,
                                  .source = t->source[i], .area = n->area};
        memcpy(o.pos, n->pos, sizeof o.pos);
        memcpy(o.nrm, n->nrm, sizeof o.nrm);
        memcpy(q, &o, sizeof o);
    }
    for (uint32_t i = 0; i < t->leaf_count; ++i, q += sizeof(glow_bake_ptree_leaf)) {
        const glow__surfel *f = &t->leaves[i];
        glow_bake_ptree_leaf o = {.triangle = f->tri, .material = f->material, .area = f->area};
        memcpy(o.pos, f->pos, sizeof o.pos);
        memcpy(o.nrm, f->nrm, sizeof o.nrm);
        memcpy(o.albedo, f->albedo, sizeof o.albedo);
        memcpy(o.emission, f->emission, sizeof o.emission);
        memcpy(o.bary, f->bary, sizeof o.bary);
        memcpy(q, &o, sizeof o);
    }
    return buf;
}

/* The tree of key `key` from the PTRE of the bake at `path` (a previous bake of a system whose tree is
 * that key's): false when the file, its section or its key is not that, or it is not a tree as
 * sys_tree_make makes them (the caller builds the tree instead). */
static bool sys_tree_read(const char *path, uint64_t key, sys_tree *t) {
    memset(t, 0, sizeof *t);
    FILE *f = fopen(path, "rb");
    if (!f) return false;
    glow_bake_header h;
    glow_bake_section sec = {0};
    bool found = false;
    uint8_t *buf = NULL;
    if (fread(&h, sizeof h, 1, f) == 1 && memcmp(h.magic, "GLOW", 4) == 0 && h.major == GLOW_BAKE_FORMAT_VERSION_MAJOR &&
        h.section_count < 4096u) {
        for (uint32_t i = 0; i < h.section_count && !found; ++i)
            found = fread(&sec, sizeof sec, 1, f) == 1 && sec.fourcc == GLOW_SECTION_PTRE;
    }
    found = found && sec.size >= sizeof(glow_bake_ptree) && sec.size <= (1ull << 32) &&
            fseek(f, (long)sec.offset, SEEK_SET) == 0 && (buf = malloc((size_t)sec.size)) &&
            fread(buf, 1, (size_t)sec.size, f) == (size_t)sec.size && glow__crc32(0, buf, (size_t)sec.size) == sec.crc32;
    fclose(f);
    glow_bake_ptree ph;
    if (found) memcpy(&ph, buf, sizeof ph);
    bool ok = found && ph.tree_key == key && ph.leaf_count >= 1 && ph.leaf_count <= ph.node_count &&
              ph.root < ph.node_count &&
              sec.size == sizeof ph + (uint64_t)ph.node_count * sizeof(glow_bake_ptree_node) +
                              (uint64_t)ph.leaf_count * sizeof(glow_bake_ptree_leaf);
    if (ok) {
        t->nodes = malloc((size_t)ph.node_count * sizeof *t->nodes);
        t->leaves = calloc(ph.leaf_count, sizeof *t->leaves);
        t->source = malloc((size_t)ph.node_count * sizeof *t->source);
        ok = t->nodes && t->leaves && t->source;
    }
    if (ok) {
        t->node_count = ph.node_count;
        t->leaf_count = ph.leaf_count;
        t->root = ph.root;
        const uint8_t *q = buf + sizeof ph;
        for (uint32_t i = 0; i < ph.node_count && ok; ++i, q += sizeof(glow_bake_ptree_node)) {
            glow_bake_ptree_node o;
            memcpy(&o, q, sizeof o);
            glow__node *n = &t->nodes[i];
            const bool leaf = i < ph.leaf_count;
            /* children before parents, leaves childless, one root: what the links' walks rely on */
            ok = (leaf ? o.child[0] == GLOW_NODE_NONE && o.child[1] == GLOW_NODE_NONE && o.level == 0
                       : o.child[0] < i && o.child[1] < i && o.child[0] != o.child[1] &&
                             o.level == 1 + (t->nodes[o.child[0]].level > t->nodes[o.child[1]].level
                                                 ? t->nodes[o.child[0]].level
                                                 : t->nodes[o.child[1]].level)) &&
                 (i == ph.root ? o.parent == GLOW_NODE_NONE : o.parent > i && o.parent < ph.node_count) &&
                 isfinite(o.area);
            n->child[0] = o.child[0];
            n->child[1] = o.child[1];
            n->parent = o.parent;
            n->level = o.level;
            memcpy(n->pos, o.pos, sizeof n->pos);
            memcpy(n->nrm, o.nrm, sizeof n->nrm);
            n->area = o.area;
            t->source[i] = o.source;
        }
        for (uint32_t i = 0; i < ph.leaf_count && ok; ++i, q += sizeof(glow_bake_ptree_leaf)) {
            glow_bake_ptree_leaf o;
            memcpy(&o, q, sizeof o);
            glow__surfel *sf = &t->leaves[i];
            memcpy(sf->pos, o.pos, sizeof sf->pos);
            memcpy(sf->nrm, o.nrm, sizeof sf->nrm);
            memcpy(sf->albedo, o.albedo, sizeof sf->albedo);
            memcpy(sf->emission, o.emission, sizeof sf->emission);
            memcpy(sf->bary, o.bary, sizeof sf->bary);
            sf->tri = o.triangle;
            sf->material = o.material;
            sf->area = o.area;
        }
        ok = ok && (ph.root == ph.node_count - 1 || (ph.node_count == 1 && ph.root == 0));
    }
    free(buf);
    if (!ok) sys_tree_free(t);
    return ok;
}

/* The tree a system's links see: its own (t[0]) whole and its neighbours' (t[1..nb]) coarsened,
 * joined. Merged order: leaves (own, then each neighbour's), internal nodes (likewise), the joins. */
static bool sys_links_merge(const sys_tree *const *t, uint32_t nb, const sys_base *own, sys_links_in *x) {
    uint32_t nL = 0, nI = 0;
    for (uint32_t k = 0; k <= nb; ++k) {
        nL += t[k]->leaf_count;
        nI += t[k]->node_count - t[k]->leaf_count;
    }
    const uint32_t N = nL + nI + nb;
    x->surfels.s = calloc((size_t)nL + 1, sizeof *x->surfels.s);
    x->hier.nodes = malloc(((size_t)N + 1) * sizeof *x->hier.nodes);
    x->join = calloc((size_t)N + 1, 1);
    x->map_dep = malloc(((size_t)N + 1) * sizeof *x->map_dep);
    x->map_node = malloc(((size_t)N + 1) * sizeof *x->map_node);
    if (!(x->surfels.s && x->hier.nodes && x->join && x->map_dep && x->map_node)) return false;
    x->surfels.count = nL;
    x->surfels.area = own->surfels.area;
    x->surfels.adapted = own->surfels.adapted;
    x->hier.leaf_count = nL;
    x->hier.node_count = N;
    x->own_leaves = own->hier.leaf_count;
    x->own_nodes = own->hier.node_count;
    uint32_t bL = 0, bI = nL, prev = 0;
    for (uint32_t k = 0; k <= nb; ++k) {
        const sys_tree *T = t[k];
        const uint32_t tl = T->leaf_count;
#define SYS_MAP(u) ((u) < tl ? bL + (u) : bI + (u) - tl)
        for (uint32_t u = 0; u < T->node_count; ++u) {
            const uint32_t m = SYS_MAP(u);
            glow__node nd = T->nodes[u];
            if (u < tl) x->surfels.s[m] = T->leaves[u];
            else
                for (int c = 0; c < 2; ++c) nd.child[c] = SYS_MAP(nd.child[c]);
            if (nd.parent != GLOW_NODE_NONE) nd.parent = SYS_MAP(nd.parent);
            x->hier.nodes[m] = nd;
            x->map_dep[m] = k == 0 ? SYS_DEP_OWN : k - 1;
            x->map_node[m] = T->source[u];
        }
        const uint32_t root = SYS_MAP(T->root);
#undef SYS_MAP
        if (k == 0) {
            prev = root;
        } else { /* join the trees so far with this one */
            const uint32_t j = nL + nI + k - 1;
            glow__node *a = &x->hier.nodes[prev], *c = &x->hier.nodes[root], *J = &x->hier.nodes[j];
            J->child[0] = prev;
            J->child[1] = root;
            J->parent = GLOW_NODE_NONE;
            a->parent = c->parent = j;
            J->level = 1 + (a->level > c->level ? a->level : c->level);
            J->area = a->area + c->area;
            float nrm[3];
            for (int q = 0; q < 3; ++q) {
                J->pos[q] = J->area > 0.0f ? (a->pos[q] * a->area + c->pos[q] * c->area) / J->area : 0.5f * (a->pos[q] + c->pos[q]);
                nrm[q] = a->nrm[q] * a->area + c->nrm[q] * c->area;
            }
            const float nl = sqrtf(glow__dot(nrm, nrm));
            for (int q = 0; q < 3; ++q) J->nrm[q] = nl > 0.0f ? nrm[q] / nl : 0.0f;
            x->join[j] = 1;
            x->map_dep[j] = SYS_DEP_JOIN;
            x->map_node[j] = 0;
            prev = j;
        }
        bL += tl;
        bI += T->node_count - tl;
    }
    x->hier.level_count = x->hier.nodes[N - 1].level + 1;
    x->hier.level_start = NULL; /* the links read no level table */
    return true;
}

/* Triangles larger than a sixteenth of the system area, or with an edge longer than a quarter of its
 * square root, are cut into 4^k similar pieces (midpoint subdivision, corner attributes
 * interpolated), so that the partition can place them: a level's ground quad of two 7,821 m²
 * triangles was two systems of its own whose reach took in every system of the level, so that an
 * edit anywhere re-baked all of them, and whose caches saw little of their own. Long thin triangles
 * are cut too (a street along a row of buildings, 169 m by 6 m, is two triangles of 507 m²): whole,
 * or in four 84 m slivers, they stretched the bounds of the systems that took them across the level,
 * and with them each system's reach (its occluders and neighbours: the 4x4 Sponza level with a
 * ground of streets had 17.5 neighbours a system and 432k occluder triangles; with long triangles
 * cut and the balanced cells of split_systems, 8.7 and 191k). Pieces keep their source triangle
 * (tri_source). NULL out: nothing to cut. */
#define SYS_PIECE_FRACTION (1.0 / 16.0)
#define SYS_PIECE_EDGE 0.25 /* of sqrt(system area) */
#define SYS_PIECE_MAX_LEVELS 8u

static void piece_emit(const glow__scene *w, uint32_t t, const float P[3][3], const float N[3][3], const float U0[3][2],
                       const float U1[3][2], uint32_t levels, glow__scene *o) {
    if (levels == 0) {
        const uint32_t i = o->tri_count++;
        memcpy(o->pos[3 * (size_t)i], P, sizeof(float[3][3]));
        memcpy(o->nrm[3 * (size_t)i], N, sizeof(float[3][3]));
        if (o->uv0) memcpy(o->uv0[3 * (size_t)i], U0, sizeof(float[3][2]));
        if (o->uv1) memcpy(o->uv1[3 * (size_t)i], U1, sizeof(float[3][2]));
        o->tri_material[i] = w->tri_material[t];
        o->tri_source[i] = w->tri_source ? w->tri_source[t] : t;
        return;
    }
    float mp[3][3], mn[3][3], m0[3][2], m1[3][2]; /* midpoints of edges 01, 12, 20 */
    for (int e = 0; e < 3; ++e) {
        const int a = e, b = (e + 1) % 3;
        float len = 0.0f;
        for (int k = 0; k < 3; ++k) {
            mp[e][k] = 0.5f * (P[a][k] + P[b][k]);
            mn[e][k] = 0.5f * (N[a][k] + N[b][k]);
            len += mn[e][k] * mn[e][k];
        }
        len = sqrtf(len);
        for (int k = 0; k < 3; ++k) mn[e][k] = len > 0.0f ? mn[e][k] / len : N[a][k];
        for (int k = 0; k < 2; ++k) {
            m0[e][k] = U0 ? 0.5f * (U0[a][k] + U0[b][k]) : 0.0f;
            m1[e][k] = U1 ? 0.5f * (U1[a][k] + U1[b][k]) : 0.0f;
        }
    }
    /* corner c with the midpoints of its two edges, then the middle triangle (same winding) */
    for (int c = 0; c < 4; ++c) {
        float q[3][3], n[3][3], u0[3][2], u1[3][2];
        for (int j = 0; j < 3; ++j) {
            int src_corner = -1, src_mid = -1;
            if (c < 3) {
                if (j == 0) src_corner = c;
                else src_mid = j == 1 ? c : (c + 2) % 3;
            } else {
                src_mid = j;
            }
            memcpy(q[j], src_corner >= 0 ? P[src_corner] : mp[src_mid], sizeof q[j]);
            memcpy(n[j], src_corner >= 0 ? N[src_corner] : mn[src_mid], sizeof n[j]);
            if (U0) memcpy(u0[j], src_corner >= 0 ? U0[src_corner] : m0[src_mid], sizeof u0[j]);
            if (U1) memcpy(u1[j], src_corner >= 0 ? U1[src_corner] : m1[src_mid], sizeof u1[j]);
        }
        piece_emit(w, t, (const float(*)[3])q, (const float(*)[3])n, U0 ? (const float(*)[2])u0 : NULL,
                   U1 ? (const float(*)[2])u1 : NULL, levels - 1, o);
    }
}

/* how many times triangle t is cut in four for its pieces to be at most `limit` in area and `edge`
 * in their longest edge (each cut halves the edges) */
static uint32_t piece_levels(const glow__scene *w, uint32_t t, double limit, double edge) {
    const float(*P)[3] = w->pos + 3 * (size_t)t;
    double e2 = 0.0;
    for (int e = 0; e < 3; ++e) {
        double l2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double d = (double)P[(e + 1) % 3][k] - P[e][k];
            l2 += d * d;
        }
        if (l2 > e2) e2 = l2;
    }
    const double edge2 = edge * edge;
    uint32_t k = 0;
    for (double a = glow__tri_area(w, t); (a > limit || e2 > edge2) && k < SYS_PIECE_MAX_LEVELS; a *= 0.25, e2 *= 0.25) k++;
    return k;
}

static bool split_large_triangles(const glow__scene *w, double target, glow__scene *o, uint32_t *cut) {
    memset(o, 0, sizeof *o);
    *cut = 0;
    const double limit = target * SYS_PIECE_FRACTION, edge = sqrt(target) * SYS_PIECE_EDGE;
    size_t total = 0;
    for (uint32_t t = 0; t < w->tri_count; ++t) {
        const uint32_t k = piece_levels(w, t, limit, edge);
        total += (size_t)1 << (2 * k);
        *cut += k > 0;
    }
    if (!*cut) return true;
    if (total > UINT32_MAX / 4) return false;
    *o = *w; /* materials, textures, bounds, statistics, source: the world's (shared, not owned) */
    o->tri_count = 0;
    o->pos = malloc(total * 3 * sizeof *o->pos);
    o->nrm = malloc(total * 3 * sizeof *o->nrm);
    o->uv0 = w->uv0 ? malloc(total * 3 * sizeof *o->uv0) : NULL;
    o->uv1 = w->uv1 ? malloc(total * 3 * sizeof *o->uv1) : NULL;
    o->tri_material = malloc(total * sizeof *o->tri_material);
    o->tri_source = malloc(total * sizeof *o->tri_source);
    if (!o->pos || !o->nrm || (w->uv0 && !o->uv0) || (w->uv1 && !o->uv1) || !o->tri_material || !o->tri_source) return false;
    for (uint32_t t = 0; t < w->tri_count; ++t) {
        const uint32_t k = piece_levels(w, t, limit, edge);
        piece_emit(w, t, (const float(*)[3])w->pos[3 * (size_t)t], (const float(*)[3])w->nrm[3 * (size_t)t],
                   w->uv0 ? (const float(*)[2])w->uv0[3 * (size_t)t] : NULL,
                   w->uv1 ? (const float(*)[2])w->uv1[3 * (size_t)t] : NULL, k, o);
    }
    return true;
}

/* The systems of a split bake, one after the other (each with every thread, and over the ranks of a
 * distributed bake), then the manifest. A system whose key (system_key) and file the previous manifest
 * at out_path already has is kept as it is (an incremental re-bake): its bytes are what a bake would
 * write again. Each file's name holds its key, so the previous world stays whole until the new manifest
 * replaces it; then the files only the previous manifest named are removed. On failure the files
 * written by this bake are removed and the previous world is left as it was. */
static glow_result bake_systems(const glow_pc_settings *set, const preset *p, const glow__scene *world_in,
                                const char *out_path, bool writer, glow__pool *pool, glow__log *log,
                                glow_pc_stats *stats) {
    glow__scene pieces;
    uint32_t cut = 0;
    if (!split_large_triangles(world_in, set->system_area, &pieces, &cut)) {
        glow__errorf(log, "%s: out of memory cutting large triangles into pieces", world_in->source);
        if (cut) sys_scene_free(&pieces);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    const glow__scene *world = cut ? &pieces : world_in;
    if (cut)
        glow__infof(log, "systems: %u triangles larger than %g units² or longer than %g cut into %u pieces", cut,
                    set->system_area * SYS_PIECE_FRACTION, sqrt(set->system_area) * SYS_PIECE_EDGE,
                    world->tri_count - (world_in->tri_count - cut));
    const uint32_t n = world->tri_count;
    double *tri_area_v = malloc(((size_t)n + 1) * sizeof *tri_area_v);
    float(*cent)[3] = malloc(((size_t)n + 1) * sizeof *cent);
    sys_split sp = {.sc = world, .tri_area = tri_area_v, .cent = (const float(*)[3])cent, .target = set->system_area};
    sp.order = malloc(((size_t)n + 1) * sizeof *sp.order);
    sp.tmp = malloc(((size_t)n + 1) * sizeof *sp.tmp);
    float *foreign = malloc(((size_t)n + 1) * 9 * sizeof *foreign);
    float (*tri_bounds)[6] = NULL; /* sys_world.tb */
    char **made = NULL; /* files this bake wrote */
    cJSON **objs = NULL; /* the manifest entries of the systems baked now, completed after the bakes */
    double *rec = NULL;  /* per system: what its bake reports (SYS_REC numbers), exchanged between ranks */
    glow_pc_stats *sst = NULL; /* distributed: each baked system's summary, exchanged with rec and added to the
                                  world's in index order, so the summary is a one-process bake's for any ranks */
    const glow_pc_distribution *dist = set->distribution && set->distribution->ranks > 1 ? set->distribution : NULL;
    uint32_t to_bake = 0;
    cJSON *root = cJSON_CreateObject(), *list = NULL, *prev = read_previous(out_path);
    glow_result res = GLOW_OK;
    uint32_t nmade = 0, largest = 0, reused = 0;
    uint64_t nf_total = 0, dep_total = 0;
    uint64_t *own_key = NULL, *full_key = NULL, *tree_key = NULL, *src_key = NULL;
    uint32_t *dep_count = NULL, *deps = NULL, *occ_count = NULL, *sys_of = NULL, *last_use = NULL;
    sys_base *bases = NULL;
    sys_tree *trees = NULL; /* each system's tree as its neighbours see it, kept until the last that links it */
    uint32_t trees_read = 0;
    if (!tri_area_v || !cent || !sp.order || !sp.tmp || !foreign || !root) {
        glow__errorf(log, "%s: out of memory for the systems", world->source);
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    double ext = 0.0;
    for (uint32_t t = 0; t < n; ++t) {
        tri_area_v[t] = glow__tri_area(world, t);
        sp.order[t] = t;
        for (int k = 0; k < 3; ++k) {
            cent[t][k] = (world->pos[3 * (size_t)t][k] + world->pos[3 * (size_t)t + 1][k] + world->pos[3 * (size_t)t + 2][k]) *
                         (1.0f / 3.0f);
            ext = fmax(ext, fabs((double)cent[t][k]));
        }
    }
    double half = 1.0; /* the root cell: [-half, half]^3, half a power of two */
    while (half <= ext && half < 1e30) half *= 2.0;
    while (half > 2.0 * ext && half > 0x1p-30) half *= 0.5;
    if (!(half > ext)) half *= 2.0;
    const double lo[3] = {-half, -half, -half}, hi[3] = {half, half, half};
    uint32_t rest = 0; /* the triangles before it are the named systems' */
    if (set->system_group_count && (res = named_systems(set, world, &sp, &rest, log)) != GLOW_OK) goto done;
    if (!split_systems(&sp, rest, n - rest, lo, hi, 0, 0)) {
        glow__errorf(log, "%s: out of memory for the systems", world->source);
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    if (sp.n > 1000) {
        glow__errorf(log, "%s: --system-area %g splits the scene (area %.6g) into %u systems; at most 1000", world->source,
                     (double)set->system_area, world->area, sp.n);
        res = GLOW_ERROR_INVALID_ARGUMENT;
        goto done;
    }
    if (!(made = calloc(sp.n + 1, sizeof *made)) || !(objs = calloc(sp.n + 1, sizeof *objs)) ||
        (dist && !(sst = calloc(sp.n + 1, sizeof *sst))) ||
        !(rec = calloc(((size_t)sp.n + 1) * SYS_REC, sizeof *rec))) {
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    glow__infof(log, "systems: %u of at most %g units² each (scene area %.6g)%s", sp.n, (double)set->system_area,
                world->area, prev ? "; a previous world is there: unchanged systems are kept" : "");
    const uint64_t wkey = world_key(set, world);
    cJSON_AddNumberToObject(root, "glow_world", 1);
    cJSON_AddStringToObject(root, "source", world->source);
    cJSON_AddNumberToObject(root, "system_area", set->system_area);
    cJSON_AddNumberToObject(root, "seed", set->seed);
    cJSON_AddStringToObject(root, "cross_system_light", "links");
    if (!(list = cJSON_AddArrayToObject(root, "systems"))) {
        glow__errorf(log, "%s: out of memory for the world manifest", out_path);
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    /* Pass 1: every system's inputs key (own_key: its triangles and every occluder it traces), its
     * tree key (what its surfels and tree follow from) and its neighbours (the systems whose triangles
     * it traces); its file key adds the neighbours' tree keys, whose trees it links. */
    tri_bounds = malloc(((size_t)n + 1) * sizeof *tri_bounds);
    if (!tri_bounds) {
        glow__errorf(log, "%s: out of memory for the triangles' bounds", world->source);
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    for (uint32_t i = 0; i < n; ++i) {
        const float(*P)[3] = world->pos + 3 * (size_t)sp.order[i];
        for (int k = 0; k < 3; ++k) {
            tri_bounds[i][k] = fminf(P[0][k], fminf(P[1][k], P[2][k]));
            tri_bounds[i][3 + k] = fmaxf(P[0][k], fmaxf(P[1][k], P[2][k]));
        }
    }
    sys_world W = {.w = world, .set = set, .p = p, .tri_area = tri_area_v, .sp = &sp, .foreign = foreign, .pool = pool,
                   .tb = (const float(*)[6])tri_bounds, .log = log,
                   .reach = set->system_reach > 0.0f ? set->system_reach : SYS_REACH_DEFAULT};
    const uint32_t dep_cap = set->links / 4u < SYS_MAX_DEPS ? (set->links / 4u ? set->links / 4u : 1u) : SYS_MAX_DEPS;
    own_key = calloc(sp.n + 1, sizeof *own_key);
    full_key = calloc(sp.n + 1, sizeof *full_key);
    tree_key = calloc(sp.n + 1, sizeof *tree_key);
    src_key = calloc(sp.n + 1, sizeof *src_key);
    dep_count = calloc(sp.n + 1, sizeof *dep_count);
    deps = malloc(((size_t)sp.n * dep_cap + 1) * sizeof *deps);
    occ_count = calloc(sp.n + 1, sizeof *occ_count);
    sys_of = malloc(((size_t)n + 1) * sizeof *sys_of);
    bases = calloc(sp.n + 1, sizeof *bases);
    trees = calloc(sp.n + 1, sizeof *trees);
    last_use = calloc(sp.n + 1, sizeof *last_use);
    if (!own_key || !full_key || !tree_key || !src_key || !dep_count || !deps || !occ_count || !sys_of || !bases || !trees || !last_use) {
        glow__errorf(log, "%s: out of memory for the systems", world->source);
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    for (uint32_t s = 0; s < sp.n; ++s)
        for (uint32_t i = sp.parts[s].first; i < sp.parts[s].first + sp.parts[s].count; ++i) sys_of[i] = s;
    for (uint32_t s = 0; s < sp.n && res == GLOW_OK; ++s) {
        glow__scene sub;
        uint32_t nf = 0;
        float olo[3], ohi[3];
        memset(occ_count, 0, sp.n * sizeof *occ_count);
        if (!sys_prepare(&W, s, &sub, &nf, olo, ohi, sys_of, occ_count)) {
            glow__errorf(log, "%s: out of memory for system %u", world->source, s);
            res = GLOW_ERROR_OUT_OF_MEMORY;
        } else {
            own_key[s] = system_key(wkey, &sp.parts[s], &sub, foreign, nf);
            src_key[s] = sources_key(&sub);
            nf_total += nf;
            /* The key of its surfels and tree (what its dependents' proxies index): every ray that
             * places and clusters them stays within its bounds grown by the concavity rays' reach (4
             * nominal surfel radii, here 8) and a few ray offsets, so only the occluders there count. */
            glow_pc_settings sset;
            uint32_t gt;
            sys_budget(&W, s, &sset, &gt);
            float e[3];
            glow__sub(sub.bounds_max, sub.bounds_min, e);
            const float tm = 8.0f * sqrtf((float)(sub.area / sset.surfels / GLOW__PI)) + 1e-3f * sqrtf(glow__dot(e, e));
            uint32_t nt = 0;
            for (uint32_t i = 0; i < nf; ++i) {
                const float *P = foreign + 9 * (size_t)i;
                bool near = true;
                for (int k = 0; k < 3 && near; ++k) {
                    const float a = fminf(P[k], fminf(P[3 + k], P[6 + k])), b = fmaxf(P[k], fmaxf(P[3 + k], P[6 + k]));
                    near = b >= sub.bounds_min[k] - tm && a <= sub.bounds_max[k] + tm;
                }
                if (near) memmove(foreign + 9 * (size_t)nt++, P, 9 * sizeof(float));
            }
            tree_key[s] = system_key(wkey ^ 0x7472656565ull, &sp.parts[s], &sub, foreign, nt);
        }
        sys_scene_free(&sub);
        /* the neighbours: the most occluders first (ties: the lower index), at most dep_cap, by index;
         * of a system that declares its neighbours, only those */
        uint32_t *d = deps + (size_t)s * dep_cap, nd = 0;
        const char *decl = sys_declared(set, sp.parts[s].group);
        for (uint32_t k = 0; k < sp.n; ++k) {
            if (!occ_count[k]) continue;
            if (decl && !(sp.parts[k].group >= 0 && sys_lists(decl, set->system_groups[sp.parts[k].group]))) continue;
            uint32_t at = nd < dep_cap ? nd++ : dep_cap;
            if (at == dep_cap) { /* full: replace the weakest if this one beats it */
                if (occ_count[k] <= occ_count[d[dep_cap - 1]]) continue;
                at = dep_cap - 1;
            }
            while (at > 0 && occ_count[d[at - 1]] < occ_count[k]) { d[at] = d[at - 1]; at--; }
            d[at] = k;
        }
        for (uint32_t q = 1; q < nd; ++q)
            for (uint32_t y = q; y > 0 && d[y - 1] > d[y]; --y) { const uint32_t t = d[y]; d[y] = d[y - 1]; d[y - 1] = t; }
        dep_count[s] = nd;
        dep_total += nd;
        if (decl) { /* a declared neighbour not linked: say why (one that is no system: refused) */
            const char *e = set->system_groups[sp.parts[s].group];
            const int el = (int)(strchr(e, '=') - e);
            for (uint32_t g = 0; g < set->system_group_count; ++g) {
                if (!sys_lists(decl, set->system_groups[g])) continue;
                const char *gn = set->system_groups[g];
                const int gl = (int)(strchr(gn, '=') - gn);
                uint32_t k = 0;
                while (k < sp.n && sp.parts[k].group != (int)g) ++k;
                bool linked = false;
                for (uint32_t q = 0; q < nd; ++q) linked |= d[q] == k;
                if (k == sp.n) {
                    glow__errorf(log, "%s: system %.*s: declared neighbour %.*s is missing: its patterns match no "
                                 "object of the scene", world->source, el, e, gl, gn);
                    res = GLOW_ERROR_INVALID_ARGUMENT;
                } else if (!writer) {
                } else if (!occ_count[k])
                    glow__warnf(log, "%s: system %.*s: declared neighbour %.*s is beyond its reach (--system-reach "
                                "%g of its diagonal); no light from it", world->source, el, e, gl, gn, (double)W.reach);
                else if (!linked)
                    glow__warnf(log, "%s: system %.*s: declared neighbour %.*s is not linked: at most %u neighbours a "
                                "system, those with the most triangles within its reach", world->source, el, e, gl, gn,
                                dep_cap);
            }
        }
    }
    for (uint32_t s = 0; s < sp.n && res == GLOW_OK; ++s) {
        uint64_t h = own_key[s];
        HASH_VAL(h, dep_count[s]);
        for (uint32_t q = 0; q < dep_count[s]; ++q) HASH_VAL(h, tree_key[deps[(size_t)s * dep_cap + q]]);
        const char *decl = sys_declared(set, sp.parts[s].group);
        if (decl) { /* the declaration, which its manifest entry names: in the groups' order */
            h = fnv64(h, "declared", 8);
            for (uint32_t g = 0; g < set->system_group_count; ++g)
                if (sys_lists(decl, set->system_groups[g]))
                    h = fnv64(h, set->system_groups[g], (size_t)(strchr(set->system_groups[g], '=') - set->system_groups[g]) + 1u);
        }
        full_key[s] = h;
    }
    if (res == GLOW_OK && dist && dist->will_write) { /* the files any rank may write: the systems not kept */
        char **wl = calloc(sp.n + 1, sizeof *wl);
        uint32_t nw = 0;
        for (uint32_t s = 0; wl && s < sp.n; ++s) {
            const uint64_t key = sys_file_key(full_key[s], src_key[s]);
            char path[4200];
            sys_file_path(out_path, set, &sp.parts[s], key, path, sizeof path);
            const char *base = strrchr(path, '/');
            if (prev && previous_entry(prev, base ? base + 1 : path, path)) continue; /* kept as it is */
            if (!(wl[nw++] = strdup(path))) break;
        }
        if (!wl || (nw && !wl[nw - 1])) {
            glow__errorf(log, "%s: out of memory for the list of the world's files", out_path);
            res = GLOW_ERROR_OUT_OF_MEMORY;
        } else {
            dist->will_write(dist->user, (const char *const *)wl, nw);
        }
        for (uint32_t i = 0; wl && i < nw; ++i) free(wl[i]);
        free(wl);
    }
    /* Pass 2: the systems, each with its neighbours' trees (placed once, kept until the last system
     * that links them) */
    for (uint32_t s = 0; s < sp.n; ++s) {
        last_use[s] = s;
        for (uint32_t q = 0; q < dep_count[s]; ++q) {
            const uint32_t k = deps[(size_t)s * dep_cap + q];
            if (s > last_use[k]) last_use[k] = s;
        }
    }
    for (uint32_t s = 0; s < sp.n && res == GLOW_OK; ++s) {
        const sys_part *part = &sp.parts[s];
        const uint32_t *d = deps + (size_t)s * dep_cap, nd = dep_count[s];
        /* the file key: its content (full_key) and its triangles' indices in the file */
        const uint64_t key = sys_file_key(full_key[s], src_key[s]);
        /* STEM.sDEPTH-PATH-KEY.glow beside the manifest, STEM: out_path less a ".json" or ".glow" ending */
        char path[4200], keyhex[20], ownhex[20], contenthex[20];
        snprintf(keyhex, sizeof keyhex, "%016llx", (unsigned long long)key);
        snprintf(contenthex, sizeof contenthex, "%016llx", (unsigned long long)full_key[s]);
        snprintf(ownhex, sizeof ownhex, "%016llx", (unsigned long long)tree_key[s]);
        sys_file_path(out_path, set, part, key, path, sizeof path);
        const char *base = strrchr(path, '/');
        base = base ? base + 1 : path;
        const cJSON *old = prev ? previous_entry(prev, base, path) : NULL;
        cJSON *o = NULL;
        bool patched = false;
        if (!old && prev) { /* the same content, its triangles elsewhere in the file: the old file, re-indexed */
            char old_path[4200];
            const cJSON *same = previous_content(prev, contenthex, out_path, old_path, sizeof old_path);
            if (same) {
                glow__scene sub;
                uint32_t nf = 0;
                float olo[3], ohi[3];
                glow_result pr = GLOW_ERROR_OUT_OF_MEMORY;
                if (sys_prepare(&W, s, &sub, &nf, olo, ohi, NULL, NULL)) {
                    pr = writer ? patch_sources(old_path, path, &sub) : GLOW_OK;
                    sys_scene_free(&sub);
                }
                if (pr == GLOW_OK && writer && !(made[nmade++] = strdup(path))) pr = GLOW_ERROR_OUT_OF_MEMORY;
                if (pr == GLOW_OK) {
                    old = same;
                    patched = true;
                    stats->systems_patched++;
                } else if (pr == GLOW_ERROR_OUT_OF_MEMORY) {
                    glow__errorf(log, "%s: out of memory re-indexing system %u", world->source, s);
                    res = pr;
                } else {
                    glow__warnf(log, "system %u: %s could not be re-indexed (%s): baking it", s, old_path, glow_result_string(pr));
                }
            }
        }
        if (res != GLOW_OK) {
        } else if (old) { /* unchanged: keep the file (re-indexed: patched) and what the manifest said of it */
            o = cJSON_Duplicate(old, 1);
            cJSON_ReplaceItemInObject(o, "index", cJSON_CreateNumber(s));
            if (patched) {
                cJSON_ReplaceItemInObject(o, "file", cJSON_CreateString(base));
                cJSON_ReplaceItemInObject(o, "key", cJSON_CreateString(keyhex));
            }
            reused++;
            stats->surfels += (uint32_t)json_num(old, "surfels");
            stats->caches += (uint32_t)json_num(old, "caches");
            stats->grid_caches += (uint32_t)json_num(old, "grid_caches");
            stats->lightmap_caches += (uint32_t)json_num(old, "lightmap_caches");
            stats->file_size += (uint64_t)json_num(old, "bytes");
            glow__infof(log, "system %u: unchanged%s (key %s) -> %s", s,
                        patched ? " but for its triangles' indices in the file (re-indexed)" : "", keyhex, path);
        } else {
            const bool other = dist && (to_bake++ % dist->ranks) != dist->rank;
            glow__scene sub;
            uint32_t nf = 0;
            float olo[3], ohi[3];
            glow__rt *rt = NULL;
            sys_links_in win = {0};
            uint64_t dkeys[SYS_MAX_DEPS];
            const sys_tree *tl[SYS_MAX_DEPS + 1];
            sys_tree own = {0};
            /* the neighbours' trees first: each read from a previous bake of it, or placed with its own
             * rays, made and dropped in turn */
            for (uint32_t q = 0; !other && q < nd && res == GLOW_OK; ++q)
                res = sys_tree_of(&W, d[q], tree_key[d[q]], prev, out_path, &bases[d[q]], &trees[d[q]], &trees_read);
            if (!sys_prepare(&W, s, &sub, &nf, olo, ohi, NULL, NULL)) {
                glow__errorf(log, "%s: out of memory for system %u", world->source, s);
                if (res == GLOW_OK) res = GLOW_ERROR_OUT_OF_MEMORY;
            }
            if (other) {
                /* another rank bakes this system (whole systems per rank): its entry waits for its figures */
            } else if (res == GLOW_OK) {
                res = glow__rt_create_system(&sub, foreign, nf, log, &rt);
                if (res == GLOW_OK) res = sys_base_build(&W, s, &sub, rt, &bases[s]);
                tl[0] = &own;
                for (uint32_t q = 0; q < nd; ++q) {
                    tl[q + 1] = &trees[d[q]];
                    dkeys[q] = tree_key[d[q]];
                }
                if (res == GLOW_OK &&
                    (!sys_tree_make(&bases[s], false, &own) || (!trees[s].nodes && !sys_tree_make(&bases[s], true, &trees[s])) ||
                     !sys_links_merge(tl, nd, &bases[s], &win))) {
                    glow__errorf(log, "%s: out of memory for system %u's links to its neighbours", world->source, s);
                    res = GLOW_ERROR_OUT_OF_MEMORY;
                }
                sys_tree_free(&own);
                win.key = tree_key[s];
                win.proxy = &trees[s];
                win.deps = nd;
                win.dep_keys = dkeys;
                memcpy(win.trace_lo, olo, sizeof olo);
                memcpy(win.trace_hi, ohi, sizeof ohi);
                glow_pc_settings sset;
                uint32_t grid_target;
                sys_budget(&W, s, &sset, &grid_target);
                glow_pc_stats ss = {0};
                /* every rank writes the systems it bakes (a distributed bake needs a shared folder) */
                const bool mine = dist || writer;
                if (res == GLOW_OK)
                    res = bake_system(&sset, grid_target, &sub, rt, path, mine, pool, log, NULL, &ss, &bases[s], &win);
                sys_base_free(&bases[s]); /* the systems that link it read trees[s] */
                if (res == GLOW_OK) {
                    if (mine && !(made[nmade++] = strdup(path))) res = GLOW_ERROR_OUT_OF_MEMORY;
                    if (dist) {
                        sst[s] = ss;
                    } else {
                        const bool big = ss.surfels > largest;
                        if (big) largest = ss.surfels;
                        sys_stats_add(stats, &ss, big);
                    }
                    glow__infof(log, "system %u: %u triangles, area %.6g, %u surfels, %u caches (%u grid, %u lightmap), "
                                "%.3g texels/unit, %u neighbours, %llu proxy nodes -> %s", s, sub.tri_count, sub.area,
                                ss.surfels, ss.caches, ss.grid_caches, ss.lightmap_caches, (double)ss.texel_density, nd,
                                (unsigned long long)ss.proxies, path);
                    double *r = rec + (size_t)s * SYS_REC;
                    r[0] = ss.surfels;
                    r[1] = ss.caches;
                    r[2] = ss.grid_caches;
                    r[3] = ss.lightmap_caches;
                    r[4] = ss.texel_density;
                    r[5] = (double)ss.file_size;
                    r[6] = (double)ss.proxies;
                }
            }
            if (res == GLOW_OK) {
                o = objs[s] = sys_entry(s, base, keyhex, &sub, nf);
                if (part->group >= 0) {
                    const char *g = set->system_groups[part->group];
                    char nm[64];
                    snprintf(nm, sizeof nm, "%.*s", (int)(strchr(g, '=') - g), g);
                    cJSON_AddStringToObject(o, "name", nm);
                    const char *decl = sys_declared(set, part->group);
                    cJSON *dn = decl ? cJSON_AddArrayToObject(o, "declared_neighbours") : NULL;
                    for (uint32_t h = 0; dn && h < set->system_group_count; ++h) /* in the groups' order */
                        if (sys_lists(decl, set->system_groups[h])) {
                            const char *gn = set->system_groups[h];
                            snprintf(nm, sizeof nm, "%.*s", (int)(strchr(gn, '=') - gn), gn);
                            cJSON_AddItemToArray(dn, cJSON_CreateString(nm));
                        }
                }
                cJSON_AddStringToObject(o, "system_key", ownhex);
                cJSON_AddStringToObject(o, "content_key", contenthex);
                char inhex[20];
                snprintf(inhex, sizeof inhex, "%016llx", (unsigned long long)own_key[s]);
                cJSON_AddStringToObject(o, "inputs_key", inhex);
                cJSON *da = cJSON_AddArrayToObject(o, "dependencies");
                for (uint32_t q = 0; q < nd; ++q) {
                    char dh[20];
                    snprintf(dh, sizeof dh, "%016llx", (unsigned long long)tree_key[d[q]]);
                    cJSON_AddItemToArray(da, cJSON_CreateString(dh));
                }
            }
            sys_links_free(&win);
            glow__rt_destroy(rt);
            sys_scene_free(&sub);
        }
        for (uint32_t k = 0; k < sp.n; ++k) /* the trees no later system links */
            if (last_use[k] == s) {
                if (bases[k].done) sys_base_free(&bases[k]);
                sys_tree_free(&trees[k]);
            }
        if (o) cJSON_AddItemToArray(list, o);
    }
    if (res == GLOW_OK && dist && to_bake) { /* every rank's figures for the systems it baked */
        /* one item a system: its SYS_REC numbers, then its whole summary (the ranks run one binary) */
        const size_t item = SYS_REC * sizeof(double) + (sizeof(glow_pc_stats) + 7u) / 8u * 8u;
        size_t *off = calloc((size_t)dist->ranks + 1, sizeof *off);
        unsigned char *buf = malloc(((size_t)to_bake + 1) * item);
        uint32_t *order = malloc(((size_t)to_bake + 1) * sizeof *order); /* systems by rank, then index */
        if (!off || !buf || !order) {
            res = GLOW_ERROR_OUT_OF_MEMORY;
        } else {
            uint32_t k = 0;
            for (uint32_t r = 0; r < dist->ranks; ++r) {
                off[r] = (size_t)k * item;
                for (uint32_t s2 = 0, b = 0; s2 < sp.n; ++s2)
                    if (objs[s2] && (b++ % dist->ranks) == r) order[k++] = s2;
            }
            off[dist->ranks] = (size_t)k * item;
            for (uint32_t i = 0; i < k; ++i) {
                memcpy(buf + (size_t)i * item, rec + (size_t)order[i] * SYS_REC, SYS_REC * sizeof(double));
                memcpy(buf + (size_t)i * item + SYS_REC * sizeof(double), &sst[order[i]], sizeof *sst);
            }
            res = dist->share(dist->user, buf, off);
            if (res != GLOW_OK) glow__errorf(log, "%s: the systems' figures could not be exchanged between the ranks", out_path);
            for (uint32_t i = 0; res == GLOW_OK && i < k; ++i) {
                glow_pc_stats *x = &sst[order[i]];
                memcpy(rec + (size_t)order[i] * SYS_REC, buf + (size_t)i * item, SYS_REC * sizeof(double));
                memcpy(x, buf + (size_t)i * item + SYS_REC * sizeof(double), sizeof *x);
                if ((size_t)i * item < off[dist->rank] || (size_t)i * item >= off[dist->rank + 1]) {
                    /* the stage times and peak memory stay this process's own */
                    memset(x->stage_seconds, 0, sizeof x->stage_seconds);
                    memset(x->stage_peak_rss, 0, sizeof x->stage_peak_rss);
                }
            }
            for (uint32_t s2 = 0; res == GLOW_OK && s2 < sp.n; ++s2) { /* in index order, as one process adds them */
                if (!objs[s2]) continue;
                const bool big = sst[s2].surfels > largest;
                if (big) largest = sst[s2].surfels;
                sys_stats_add(stats, &sst[s2], big);
            }
        }
        free(order);
        free(buf);
        free(off);
    }
    for (uint32_t s2 = 0; res == GLOW_OK && s2 < sp.n; ++s2) { /* the baked systems' figures, in entry order */
        if (!objs[s2]) continue;
        const double *r = rec + (size_t)s2 * SYS_REC;
        cJSON_AddNumberToObject(objs[s2], "surfels", r[0]);
        cJSON_AddNumberToObject(objs[s2], "caches", r[1]);
        cJSON_AddNumberToObject(objs[s2], "grid_caches", r[2]);
        cJSON_AddNumberToObject(objs[s2], "lightmap_caches", r[3]);
        cJSON_AddNumberToObject(objs[s2], "texel_density", (float)r[4]);
        cJSON_AddNumberToObject(objs[s2], "bytes", r[5]);
        cJSON_AddNumberToObject(objs[s2], "proxies", r[6]);
    }
    stats->systems = sp.n;
    stats->systems_reused = reused;
    stats->systems_trees_read = trees_read;
    if (res == GLOW_OK)
        glow__infof(log, "systems: %u baked, %u unchanged (%u of them re-indexed); %.1f other systems' triangles per "
                    "system traced as occluders (within %.0f %% of its diagonal), whose %.1f systems on average its caches "
                    "link (light across systems)", sp.n - reused, reused, stats->systems_patched,
                    sp.n ? (double)nf_total / sp.n : 0.0, 100.0 * W.reach,
                    sp.n ? (double)dep_total / sp.n : 0.0);
    if (res == GLOW_OK && trees_read)
        glow__infof(log, "systems: %u neighbours' trees read from their bakes (PTRE), not built again", trees_read);
    for (uint32_t i = 0; i < stats->section_count && i < 16; ++i)
        if (stats->section_fourcc[i] == GLOW_SECTION_LINK && stats->links)
            stats->bytes_per_link = (double)stats->section_size[i] / (double)stats->links;
    if (res == GLOW_OK && writer) {
        char *text = cJSON_Print(root);
        if (!text) {
            glow__errorf(log, "%s: out of memory for the world manifest", out_path);
            res = GLOW_ERROR_OUT_OF_MEMORY;
        } else {
            if (dist && dist->will_write) dist->will_write(dist->user, NULL, 0); /* every system is written */
            res = write_manifest(out_path, text, log);
            cJSON_free(text);
        }
        if (res == GLOW_OK && prev) { /* the files only the previous world named */
            const cJSON *e;
            cJSON_ArrayForEach(e, cJSON_GetObjectItem(prev, "systems")) {
                const cJSON *fe = cJSON_GetObjectItem(e, "file");
                if (!cJSON_IsString(fe) || strchr(fe->valuestring, '/')) continue;
                bool kept = false;
                const cJSON *x;
                cJSON_ArrayForEach(x, list) {
                    const cJSON *fx = cJSON_GetObjectItem(x, "file");
                    kept = kept || (cJSON_IsString(fx) && strcmp(fx->valuestring, fe->valuestring) == 0);
                }
                if (kept) continue;
                char path[4200];
                beside(out_path, fe->valuestring, path, sizeof path);
                remove(path);
            }
        }
    }
done:
    for (uint32_t i = 0; i < nmade; ++i) {
        if (res != GLOW_OK && made[i]) remove(made[i]); /* no partial output */
        free(made[i]);
    }
    free(made);
    free(objs);
    free(rec);
    free(sst);
    for (uint32_t s = 0; bases && s < sp.n; ++s) sys_base_free(&bases[s]);
    free(bases);
    for (uint32_t s = 0; trees && s < sp.n; ++s) sys_tree_free(&trees[s]);
    free(trees);
    free(own_key);
    free(full_key);
    free(tree_key);
    free(src_key);
    free(dep_count);
    free(deps);
    free(occ_count);
    free(sys_of);
    free(last_use);
    cJSON_Delete(prev);
    cJSON_Delete(root);
    free(foreign);
    free(tri_bounds);
    free(sp.parts);
    free(sp.tmp);
    free(sp.order);
    free(cent);
    free(tri_area_v);
    if (cut) sys_scene_free(&pieces); /* its own arrays; materials and textures are the world's */
    return res;
}

static glow_result bake(const char *scene_path, const char *out_path, const glow_pc_settings *settings_in,
                        glow_pc_stats *stats) {
    memset(stats, 0, sizeof *stats);
    glow_pc_settings zero = {0};
    glow_pc_settings set = glow_pc_settings_resolve(settings_in ? settings_in : &zero);
    glow__log log = {.fn = log_adapter, .user = &set};
    if (!scene_path || !out_path) {
        glow__errorf(&log, "glow_pc_bake: scene and output paths are required");
        snprintf(stats->error, sizeof stats->error, "%s", log.last_error);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    char msg[512];
    glow_result res = glow_pc_settings_validate(&set, msg, sizeof msg);
    if (res != GLOW_OK) {
        glow__errorf(&log, "%s", msg);
        snprintf(stats->error, sizeof stats->error, "%s", log.last_error);
        return res;
    }
    const preset *p = preset_of(set.quality);
    glow__scene scene = {0};
    glow__rt *rt = NULL;
    FILE *audit_csv = NULL; /* opened first: a bad path fails before the work */
    /* the output must be writable and must not be the input, checked before the work (D7, D8) */
    /* a distributed bake (glow_pc_distribution): rank 0 alone writes, so it alone checks the output */
    const bool writer = !set.distribution || set.distribution->rank == 0;
    if (!writer) set.audit_csv = NULL;
    if (writer &&
        (res = glow__bake_write_check(out_path, strncmp(scene_path, "builtin:", 8) ? scene_path : NULL, &log)) != GLOW_OK) {
        snprintf(stats->error, sizeof stats->error, "%s", log.last_error);
        return res;
    }
    if (set.audit_csv && !(audit_csv = fopen(set.audit_csv, "w"))) {
        glow__errorf(&log, "%s: cannot write the audit CSV", set.audit_csv);
        return GLOW_ERROR_IO;
    }
    glow__pool *pool = glow__pool_create(set.threads);
    if (!pool) {
        glow__errorf(&log, "cannot start %u threads", set.threads);
        res = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    stats->threads = glow__pool_threads(pool);
    double t_all = now_seconds(), t0;
    progress_ctx pc = {.s = &set};

    STAGE_BEGIN(ST_IMPORT);
    res = glow__scene_load(scene_path, &log, &scene);
    STAGE_END(ST_IMPORT);
    if (res != GLOW_OK) goto done;
    stats->source_triangles = scene.source_tri_count;
    stats->triangles = scene.tri_count;
    stats->materials = scene.material_count;
    stats->textures = scene.texture_count;
    stats->textures_missing = scene.textures_missing;
    stats->skipped_degenerate = scene.skipped_degenerate;
    stats->skipped_repeated = scene.skipped_repeated;
    stats->skipped_collinear = scene.skipped_collinear;
    stats->skipped_duplicate = scene.skipped_duplicate;
    stats->skipped_nonfinite = scene.skipped_nonfinite;
    stats->scene_area = scene.area;

    if (set.system_area > 0.0f) { /* each system builds its own rays */
        res = bake_systems(&set, p, &scene, out_path, writer, pool, &log, stats);
    } else {
        stats->systems = 1;
        STAGE_BEGIN(ST_BVH);
        res = glow__rt_create(&scene, &log, &rt);
        STAGE_END(ST_BVH);
        if (res == GLOW_OK)
            res = bake_system(&set, p->grid, &scene, rt, out_path, writer, pool, &log, audit_csv, stats, NULL, NULL);
    }
    stats->total_seconds = now_seconds() - t_all;
done:
    if (audit_csv) {
        fclose(audit_csv);
        if (res != GLOW_OK) remove(set.audit_csv);
    }
    glow__rt_destroy(rt);
    glow__scene_free(&scene);
    glow__pool_destroy(pool);
    if (res != GLOW_OK) snprintf(stats->error, sizeof stats->error, "%s", log.last_error);
    return res;
}
#undef STAGE_BEGIN
#undef STAGE_END


glow_result glow_pc_bake(const char *scene_path, const char *out_path, const glow_pc_settings *settings_in,
                         glow_pc_stats *stats) {
    glow_pc_stats local_stats;
    if (!stats) stats = &local_stats;
    const glow_result r = bake(scene_path, out_path, settings_in, stats);
    if (r != GLOW_OK && settings_in && settings_in->logger.log)
        settings_in->logger.log(settings_in->logger.user, GLOW_LOG_ERROR, r,
                                stats->error[0] ? stats->error : glow_result_string(r), NULL, 0);
    return r;
}
