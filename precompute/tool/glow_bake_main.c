/* glow-bake — the Glow linker CLI, a thin layer over glow_precompute.h.
 *
 *   glow-bake SCENE -o OUT.glow [options]     bake a scene
 *   glow-bake --info FILE [--json]           describe an existing bake
 *
 * Exit codes: 0 success, 1 the bake or the file failed (message on stderr), 2 bad command line. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "glow/glow.h"
#include "glow/glow_precompute.h"
#ifdef GLOW_HAVE_MPI
#include "bake_mpi.h"
#endif

static const char *usage_text =
    "usage: glow-bake SCENE -o OUT.glow [options]\n"
    "       glow-bake --info FILE.glow [--json]\n"
    "\n"
    "Bakes a static scene into a Glow bake: surfels, HAC hierarchy, caches (grid + lightmap\n"
    "texels) and visibility-aware links for real-time multi-bounce indirect light.\n"
    "\n"
    "SCENE is any file assimp reads (OBJ+MTL, glTF 2.0 / GLB, FBX, ...) or a built-in scene:\n"
    "  builtin:cornell     Cornell box (closed), emissive ceiling light\n"
    "  builtin:furnace     closed box, uniform albedo 0.5, uniformly emissive walls\n"
    "  builtin:two-rooms   two closed rooms sharing one thin wall (light-leak tests)\n"
    "  builtin:pillar-hall a hall with a row of pillars and a bench (partly visible nodes, contacts)\n"
    "  builtin:pillar-court the same without its ceiling (an open shell)\n"
    "  builtin:wall-gap    a room split by a thin partition with a doorway (contact leaks)\n"
    "\n"
    "Options:\n"
    "  -o, --output FILE      bake file to write (required); written atomically\n"
    "  --quality PRESET       low | moderate (default) | high | fine\n"
    "                           low:      n_S=8192,   n_L=64,  l=3, ~2.5k caches\n"
    "                           moderate: n_S=32768,  n_L=128, l=3, ~10k caches (PIC moderate)\n"
    "                           high:     n_S=131072, n_L=254, l=4, ~10k caches (PIC high)\n"
    "                           fine:     n_S=131072, n_L=128, l=3, ~10k caches: resolves light from\n"
    "                                     nearby surfaces; ~1.8x moderate's update time\n"
    "  --surfels N            number of leaf surfels n_S (16..4194304)\n"
    "  --links N              links per cache n_L (1..4096)\n"
    "  --bands L              SH bands l (2..8; l*l coefficients)\n"
    "  --grid-spacing M       grid cache spacing in scene units (default: from the scene size); with\n"
    "                         --grid-refine, the fine spacing near geometry\n"
    "  --grid-refine R        grid R times finer in the cells near geometry than in open space, within\n"
    "                         the same grid budget: 1 = uniform, 2 or 4 (default: 1)\n"
    "  --sky-rays N           rays per surfel for the sky transfer, 8 N per grid cache (default: 128)\n"
    "  --no-sky               no sky transfer (section SKYT): hosts then trace the sky themselves\n"
    "  --texel-density D      lightmap texels per scene unit (default: from the scene area and the\n"
    "                         lightmap budget)\n"
    "  --lightmap-caches N    the lightmap budget: texels that hold a cache (default: the preset's);\n"
    "                         the density is chosen to land within 20 % of it\n"
    "  --lightmap-max-size N  texels a side of a lightmap atlas, a multiple of 4 in 4..4096 (default\n"
    "                         4096); generated charts that need more go onto several such pages\n"
    "  --threads N            worker threads (default: all CPUs); output is identical for any N\n"
    "  --seed S               sampling seed (default 0); same input and seed give the same bytes\n"
    "  --sh-links             also store full-SH links (PIC Eq. 2) next to runtime-projection links\n"
    "  --rays N               visibility rays per (cache, surfel) pair (default 1)\n"
    "  --cut error|solid-angle  how each cache's cut is refined: error (default) splits first the node\n"
    "                         whose link can err most (partly visible nodes, uneven visibility) and links\n"
    "                         a node's visible subtree (see --audit-radiance); solid-angle splits the\n"
    "                         largest visible solid angle first (PIC 4.5)\n"
    "  --link-subsets gradient|on|off  gradient (default): each link reads its node's mean scaled by\n"
    "                         where in the node the light is (its flux centroid) against how the\n"
    "                         cache's response varies across the node (2 bytes per link, LSUB); on: a\n"
    "                         partly visible link reads the part of its node the cache sees (four\n"
    "                         weights per link, the default before 2026-11-29); off: the node's mean, as PIC\n"
    "  --link-visibility clustered|exact  clustered (default): clusters beyond the near field that look\n"
    "                         small from a cache share a few rays (the rays per cache barely grow with\n"
    "                         the surfels); exact: one ray per (cache, surfel)\n"
    "  --link-cluster-angle A clustered: the largest a cluster may look, radius / distance (default 0.3)\n"
    "  --link-cluster-rays K  clustered: rays per cluster, one per run of its leaves (default 4)\n"
    "  --lightmap-detail N    detail texels per lightmap texel side, each correcting its caches' near\n"
    "                         light through a few links to the surfels beside it: 1 = none, 2..4\n"
    "                         (default 3, or 4 where open ground's texels span more than 3 surfels)\n"
    "  --detail-links K       at most K links per detail texel (default 16); beyond K, surfels\n"
    "                         share the link of a small subtree of the hierarchy\n"
    "  --detail-radius R      a detail texel corrects the light of surfels within R lightmap texels of\n"
    "                         it (default 1)\n"
    "  --system-area A        split the scene into systems of at most A units² of surface each (cells\n"
    "                         fixed in space), each baked with its own surfels, hierarchy, caches\n"
    "                         and links and the preset's budgets per A units²; -o then names the\n"
    "                         world manifest (JSON) and the systems are written beside it, named by\n"
    "                         their content keys; a world already there keeps its unchanged systems\n"
    "                         (incremental). Caches link the light of the systems within reach\n"
    "  --system-group NAME=PATTERN[,PATTERN...]  with --system-area: the objects of the file (OBJ o/g,\n"
    "                         glTF nodes) whose names match a pattern (* ? [...]) form system NAME,\n"
    "                         whole; the rest is split by area. Repeat for more groups\n"
    "  --systems FILE.json    with --system-area: systems named by the user and their declared\n"
    "                         neighbours, the systems whose light each links (instead of\n"
    "                         --system-group); see docs/linker.md \"Systems named by the user\"\n"
    "  --system-reach F       with --system-area: other systems within F times a system's bounds\n"
    "                         diagonal occlude its rays and light its caches (default 0.5, up to 4)\n"
    "  --surfel-adapt F       surfels up to F times as dense where surfaces face each other within\n"
    "                         the near field (concave places) as on open ground, same count:\n"
    "                         1 = area-uniform, up to 4 (default: low and moderate 4, high and\n"
    "                         fine 1)\n"
    "  --texel-adapt F        generated lightmap charts up to F times as many texels per area where\n"
    "                         surfaces face each other within the near field as on open walls and\n"
    "                         floors, same budget: 1 = uniform, up to 8 (default: low and\n"
    "                         moderate 4, high and fine 1)\n"
    "  --audit-radiance FILE  audit the cuts under a lighting: FILE holds one float32 radiance per surfel\n"
    "                         (glow-stability audit --radiance-out, for a bake with the same settings);\n"
    "                         logs each cut's gather against the exact gather through visible surfels\n"
    "  --audit-csv FILE       with --audit-radiance: the per-cache figures as CSV\n"
    "  --no-link-normalize    keep each cache's link solid angles as estimated (default: scaled to\n"
    "                         the ray-measured visible geometry, so no energy is lost per bounce)\n"
    "  --mpi                  one bake over the ranks of an MPI job: mpirun -np N glow-bake --mpi\n"
    "                         SCENE -o OUT; the links are split between the ranks, rank 0 writes the\n"
    "                         same bytes as a one-process bake (needs a glow-bake built with MPI)\n"
    "  --json                 print the summary (or --info) as JSON on stdout\n"
    "  -q, --quiet            no progress output\n"
    "  --info FILE            validate and describe an existing bake\n"
    "  -h, --help             this text\n"
    "  --version              print versions\n"
    "\n"
    "Progress goes to stderr (a bar with an ETA on a terminal, plain lines otherwise); the summary\n"
    "to stdout. Exit status: 0 success, 1 failure (message names the file and the problem),\n"
    "2 bad command line.\n";

static int usage_error(const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fputs("glow-bake: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputs("\n(see glow-bake --help)\n", stderr);
    va_end(ap);
    return 2;
}

/* --systems FILE.json: the systems named by the user and their declared neighbours
 * (glow_pc_settings.system_groups and .system_neighbours):
 *   {"glow_systems": 1,
 *    "systems": [{"name": "hall", "objects": ["hall_*", "stairs"], "neighbours": ["tower"]}, ...]}
 * "objects": fnmatch(3) patterns of the scene's object names; "neighbours" (optional; absent =
 * automatic, every system within reach; [] = none): other systems of the file. The strings are kept for
 * the bake (static arrays: the process's lifetime). Returns false with a message naming the file. */
static bool load_systems(const char *path, const char **groups, const char **neighbours, uint32_t *count, char *err,
                         size_t n) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, n, "%s: cannot read the systems file: %s", path, strerror(errno));
        return false;
    }
    char *text = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len + 4096 + 1 > cap) {
            cap = cap ? 2 * cap : 8192;
            char *t = cap <= ((size_t)64 << 20) ? realloc(text, cap) : NULL;
            if (!t) {
                snprintf(err, n, "%s: the systems file is too large (more than 64 MiB) or memory ran out", path);
                free(text);
                fclose(f);
                return false;
            }
            text = t;
        }
        const size_t r = fread(text + len, 1, 4096, f);
        len += r;
        if (r < 4096) break;
    }
    const bool rerr = ferror(f) != 0;
    fclose(f);
    if (rerr) {
        snprintf(err, n, "%s: cannot read the systems file", path);
        free(text);
        return false;
    }
    text[len] = 0;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    bool ok = false;
#define FAIL(...) do { snprintf(err, n, __VA_ARGS__); goto done; } while (0)
    if (!root) {
        unsigned line = 1;
        for (const char *q = text; end && q < end && *q; ++q) line += *q == '\n';
        FAIL("%s: line %u: not valid JSON", path, line);
    }
    const cJSON *ver = cJSON_GetObjectItemCaseSensitive(root, "glow_systems");
    if (!cJSON_IsNumber(ver) || ver->valuedouble != 1.0)
        FAIL("%s: not a systems file of version 1 (expected \"glow_systems\": 1)", path);
    const cJSON *list = cJSON_GetObjectItemCaseSensitive(root, "systems"), *e;
    if (!cJSON_IsArray(list) || !cJSON_GetArraySize(list)) FAIL("%s: \"systems\" must be a non-empty array", path);
    if (cJSON_GetArraySize(list) > 256) FAIL("%s: %d systems; at most 256", path, cJSON_GetArraySize(list));
    uint32_t i = 0;
    cJSON_ArrayForEach(e, list) {
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(e, "name");
        const cJSON *objs = cJSON_GetObjectItemCaseSensitive(e, "objects");
        const cJSON *nb = cJSON_GetObjectItemCaseSensitive(e, "neighbours"), *x;
        if (!cJSON_IsObject(e) || !cJSON_IsString(name)) FAIL("%s: systems[%u] has no \"name\" string", path, i);
        if (!cJSON_IsArray(objs) || !cJSON_GetArraySize(objs))
            FAIL("%s: system '%s': \"objects\" must be a non-empty array of name patterns", path, name->valuestring);
        if (nb && !cJSON_IsArray(nb))
            FAIL("%s: system '%s': \"neighbours\" must be an array of system names", path, name->valuestring);
        size_t gl = strlen(name->valuestring) + 2, nl = 1;
        cJSON_ArrayForEach(x, objs) {
            if (!cJSON_IsString(x) || !*x->valuestring || strchr(x->valuestring, ','))
                FAIL("%s: system '%s': every object pattern must be a non-empty string without ','", path,
                     name->valuestring);
            gl += strlen(x->valuestring) + 1;
        }
        cJSON_ArrayForEach(x, nb) {
            if (!cJSON_IsString(x)) FAIL("%s: system '%s': every neighbour must be a system's name", path, name->valuestring);
            nl += strlen(x->valuestring) + 1;
        }
        char *g = malloc(gl), *l = nb ? malloc(nl) : NULL;
        if (!g || (nb && !l)) {
            free(g);
            free(l);
            FAIL("%s: out of memory", path);
        }
        int at = snprintf(g, gl, "%s=", name->valuestring);
        cJSON_ArrayForEach(x, objs) at += snprintf(g + at, gl - (size_t)at, "%s%s", x != objs->child ? "," : "", x->valuestring);
        if (l) {
            l[0] = 0;
            at = 0;
            cJSON_ArrayForEach(x, nb) at += snprintf(l + at, nl - (size_t)at, "%s%s", x != nb->child ? "," : "", x->valuestring);
        }
        groups[i] = g;
        neighbours[i] = l;
        *count = ++i;
    }
    ok = true;
#undef FAIL
done:
    cJSON_Delete(root);
    free(text);
    return ok;
}

static bool parse_u32(const char *s, uint32_t lo, uint32_t hi, uint32_t *out) {
    if (!s || !*s || *s == '-' || *s == '+') return false;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno || *end || v < lo || v > hi) return false;
    *out = (uint32_t)v;
    return true;
}
static bool parse_pos_float(const char *s, float *out) {
    if (!s || !*s) return false;
    char *end;
    errno = 0;
    float v = strtof(s, &end);
    if (errno || *end || !isfinite(v) || !(v > 0.0f)) return false;
    *out = v;
    return true;
}

/* ---------------------------------------------------------------- progress display */
typedef struct progress_state {
    bool tty, quiet;
    uint32_t stage;
    double stage_start, last_print, bake_start;
} progress_state;

static double mono(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void on_progress(void *user, uint32_t stage, double f) {
    progress_state *p = user;
    if (p->quiet) return;
    double t = mono();
    if (f <= 0.0) {
        p->stage = stage;
        p->stage_start = t;
        p->last_print = 0.0;
        if (!p->tty) fprintf(stderr, "glow-bake: [%u/%d] %s ...\n", stage + 1, GLOW_PC_STAGE_COUNT, glow_pc_stage_name(stage));
        return;
    }
    double el = t - p->stage_start;
    if (f >= 1.0) {
        if (p->tty)
            fprintf(stderr, "\r\033[K[%u/%d] %-9s done in %.2f s\n", stage + 1, GLOW_PC_STAGE_COUNT,
                    glow_pc_stage_name(stage), el);
        else
            fprintf(stderr, "glow-bake: [%u/%d] %s done in %.2f s\n", stage + 1, GLOW_PC_STAGE_COUNT,
                    glow_pc_stage_name(stage), el);
        return;
    }
    if (!p->tty || t - p->last_print < 0.1) return;
    p->last_print = t;
    int width = 30, fill = (int)(f * width);
    char bar[64];
    for (int i = 0; i < width; ++i) bar[i] = i < fill ? '#' : '.';
    bar[width] = 0;
    double eta = f > 0.01 ? el * (1.0 - f) / f : -1.0;
    if (eta >= 0.0)
        fprintf(stderr, "\r\033[K[%u/%d] %-9s %s %5.1f%%  ETA %.0f s", stage + 1, GLOW_PC_STAGE_COUNT,
                glow_pc_stage_name(stage), bar, 100.0 * f, eta);
    else
        fprintf(stderr, "\r\033[K[%u/%d] %-9s %s %5.1f%%", stage + 1, GLOW_PC_STAGE_COUNT, glow_pc_stage_name(stage),
                bar, 100.0 * f);
    fflush(stderr);
}

static void on_log(void *user, glow_log_level level, glow_result code, const char *msg, const char *file, int line) {
    progress_state *p = user;
    (void)code;
    (void)file;
    (void)line;
    if (level == GLOW_LOG_ERROR) return; /* printed once by main, after the bake returns */
    if (level == GLOW_LOG_INFO && p->quiet) return;
    if (level > GLOW_LOG_INFO) return;
    if (p->tty) fputs("\r\033[K", stderr);
    fprintf(stderr, "glow-bake: %s: %s\n", level == GLOW_LOG_WARNING ? "warning" : "info", msg);
}

static void fourcc_str(uint32_t f, char out[5]) {
    for (int i = 0; i < 4; ++i) {
        char c = (char)((f >> (8 * i)) & 0xFF);
        out[i] = (c >= 32 && c < 127) ? c : '?';
    }
    out[4] = 0;
}

/* --json output through cJSON (Debian's libcjson, which the scene loader links too): pretty-printed,
 * strings escaped. Out of memory leaves a short document; it is reported, not printed. */
/* --info: what the bake's LSUB holds (glow-bake --link-subsets) */
static const char *link_lsub_mode(uint32_t link_kind) {
    if (link_kind & GLOW_LINK_KIND_GRADIENT) return "gradient";
    return (link_kind & GLOW_LINK_KIND_SUBSETS) ? "on" : "off";
}

static void print_json(cJSON *o) {
    char *text = o ? cJSON_Print(o) : NULL;
    cJSON_Delete(o);
    if (!text) {
        fprintf(stderr, "glow-bake: out of memory for the JSON output\n");
        return;
    }
    puts(text);
    cJSON_free(text);
}

static void print_summary(const char *scene, const char *out, const glow_pc_stats *s, bool json,
                          const char *lsub_mode) {
    char fc[5];
    if (json) {
        cJSON *o = cJSON_CreateObject(), *a, *x;
        cJSON_AddStringToObject(o, "scene", scene);
        cJSON_AddStringToObject(o, "output", out);
        cJSON_AddNumberToObject(o, "threads", s->threads);
        cJSON_AddNumberToObject(o, "seed", s->seed);
        cJSON_AddNumberToObject(o, "total_seconds", s->total_seconds);
        a = cJSON_AddArrayToObject(o, "stages");
        for (int i = 0; a && i < GLOW_PC_STAGE_COUNT; ++i) {
            cJSON_AddItemToArray(a, x = cJSON_CreateObject());
            cJSON_AddStringToObject(x, "name", glow_pc_stage_name((uint32_t)i));
            cJSON_AddNumberToObject(x, "seconds", s->stage_seconds[i]);
            cJSON_AddNumberToObject(x, "peak_rss_bytes", (double)s->stage_peak_rss[i]);
        }
        x = cJSON_AddObjectToObject(o, "scene_stats");
        cJSON_AddNumberToObject(x, "source_triangles", s->source_triangles);
        cJSON_AddNumberToObject(x, "triangles", s->triangles);
        cJSON_AddNumberToObject(x, "skipped_degenerate", s->skipped_degenerate);
        cJSON_AddNumberToObject(x, "skipped_repeated", s->skipped_repeated);
        cJSON_AddNumberToObject(x, "skipped_collinear", s->skipped_collinear);
        cJSON_AddNumberToObject(x, "skipped_duplicate", s->skipped_duplicate);
        cJSON_AddNumberToObject(x, "skipped_nonfinite", s->skipped_nonfinite);
        cJSON_AddNumberToObject(x, "materials", s->materials);
        cJSON_AddNumberToObject(x, "textures", s->textures);
        cJSON_AddNumberToObject(x, "textures_missing", s->textures_missing);
        cJSON_AddNumberToObject(x, "area", s->scene_area);
        cJSON_AddNumberToObject(o, "systems", s->systems);
        cJSON_AddNumberToObject(o, "systems_reused", s->systems_reused);
        cJSON_AddNumberToObject(o, "systems_trees_read", s->systems_trees_read);
        cJSON_AddNumberToObject(o, "dependencies", s->dependencies);
        cJSON_AddNumberToObject(o, "proxies", (double)s->proxies);
        cJSON_AddNumberToObject(o, "surfels", s->surfels);
        cJSON_AddNumberToObject(o, "nodes", s->nodes);
        cJSON_AddNumberToObject(o, "levels", s->levels);
        x = cJSON_AddObjectToObject(o, "caches");
        cJSON_AddNumberToObject(x, "total", s->caches);
        cJSON_AddNumberToObject(x, "grid", s->grid_caches);
        const int dims[3] = {(int)s->grid_dims[0], (int)s->grid_dims[1], (int)s->grid_dims[2]};
        cJSON_AddItemToObject(x, "grid_dims", cJSON_CreateIntArray(dims, 3));
        cJSON_AddNumberToObject(x, "grid_spacing", s->grid_spacing);
        cJSON_AddNumberToObject(x, "grid_inside_rejected", s->grid_inside);
        cJSON_AddNumberToObject(x, "grid_refine", s->grid_refine);
        cJSON_AddNumberToObject(x, "grid_bricks", s->grid_bricks);
        cJSON_AddNumberToObject(x, "grid_fine", s->grid_fine_caches);
        cJSON_AddNumberToObject(x, "sky_rays", s->sky_rays);
        cJSON_AddNumberToObject(x, "sky_seconds", s->sky_seconds);
        cJSON_AddNumberToObject(x, "lightmap", s->lightmap_caches);
        const int lsz[2] = {(int)s->lightmap_width, (int)s->lightmap_height};
        cJSON_AddItemToObject(x, "lightmap_size", cJSON_CreateIntArray(lsz, 2));
        cJSON_AddNumberToObject(x, "lightmap_pages", s->lightmap_pages);
        cJSON_AddNumberToObject(x, "texel_density", s->texel_density);
        cJSON_AddNumberToObject(x, "lightmap_invalid", s->lightmap_invalid);
        cJSON_AddNumberToObject(x, "lightmap_gutter", s->lightmap_gutter);
        cJSON_AddNumberToObject(x, "lightmap_unused", s->lightmap_unused);
        cJSON_AddNumberToObject(x, "lightmap_coverage", s->lightmap_coverage);
        cJSON_AddNumberToObject(x, "charts", s->charts);
        cJSON_AddNumberToObject(x, "small_charts", s->small_charts);
        cJSON_AddNumberToObject(x, "shared_texels", s->shared_texels);
        cJSON_AddNumberToObject(x, "detail_factor", s->detail_factor);
        cJSON_AddNumberToObject(x, "detail_texels", s->detail_texels);
        cJSON_AddNumberToObject(x, "detail_corrected", s->detail_corrected);
        cJSON_AddNumberToObject(x, "detail_links", (double)s->detail_links);
        x = cJSON_AddObjectToObject(o, "links");
        cJSON_AddNumberToObject(x, "per_cache", s->links_per_cache);
        cJSON_AddNumberToObject(x, "total", (double)s->links);
        cJSON_AddStringToObject(x, "subsets", lsub_mode);
        cJSON_AddNumberToObject(x, "bands", s->bands);
        cJSON_AddNumberToObject(x, "bytes_per_link", s->bytes_per_link);
        cJSON_AddNumberToObject(o, "file_bytes", (double)s->file_size);
        a = cJSON_AddArrayToObject(o, "sections");
        for (uint32_t i = 0; a && i < s->section_count && i < 16; ++i) {
            fourcc_str(s->section_fourcc[i], fc);
            cJSON_AddItemToArray(a, x = cJSON_CreateObject());
            cJSON_AddStringToObject(x, "fourcc", fc);
            cJSON_AddNumberToObject(x, "bytes", (double)s->section_size[i]);
        }
        print_json(o);
        return;
    }
    printf("glow-bake: %s -> %s\n", scene, out);
    if (s->systems > 1)
        printf("  systems   %u, %u of them baked and %u unchanged (%u re-indexed: only their triangles' places in "
               "the file moved) from the previous bake (the world manifest %s names their bakes; the figures below are "
               "sums over the baked ones, the settings the largest's)\n",
               s->systems, s->systems - s->systems_reused, s->systems_reused, s->systems_patched, out);
    printf("  scene     %u triangles kept of %u (skipped: %u degenerate [%u repeated corners, %u collinear], "
           "%u duplicate, %u non-finite), "
           "%u materials, %u textures (%u missing), area %.6g\n",
           s->triangles, s->source_triangles, s->skipped_degenerate, s->skipped_repeated, s->skipped_collinear,
           s->skipped_duplicate, s->skipped_nonfinite, s->materials, s->textures, s->textures_missing, s->scene_area);
    printf("  surfels   %u   nodes %u   levels %u\n", s->surfels, s->nodes, s->levels);
    printf("  caches    %u = grid %u (%ux%ux%u, spacing %.4g, %u inside solids) + lightmap %u (%ux%u, %.4g texels/unit, "
           "%u charts, %u invalid texels)\n",
           s->caches, s->grid_caches, s->grid_dims[0], s->grid_dims[1], s->grid_dims[2], (double)s->grid_spacing,
           s->grid_inside, s->lightmap_caches, s->lightmap_width, s->lightmap_height, (double)s->texel_density,
           s->charts, s->lightmap_invalid);
    if (s->lightmap_pages > 1)
        printf("  lightmap  %u pages of %ux%u texels (--lightmap-max-size)\n", s->lightmap_pages, s->lightmap_width,
               s->lightmap_height);
    if (s->grid_refine)
        printf("  grid      refined %ux near geometry: %u cells of %.4g are bricks of %u³ cells of %.4g, holding %u of the "
               "grid's caches\n",
               s->grid_refine, s->grid_bricks, (double)s->grid_spacing, s->grid_refine,
               (double)s->grid_spacing / s->grid_refine, s->grid_fine_caches);
    if (s->sky_rays)
        printf("  sky       transfer of %u surfels (%u rays each) and %u grid caches (%u rays each), %.2f s\n", s->surfels,
               s->sky_rays, s->grid_caches, 8u * s->sky_rays, s->sky_seconds);
    if (s->lightmap_width)
        printf("  lightmap  %.3g units per texel (%.3g in the most concave charts); the atlas holds %u caches (%.0f %% of their area is surface), %u gutter "
               "copies and %u unused texels (%.0f %%); %u charts narrower than a texel share %u texels\n",
               s->texel_density > 0.0f ? 1.0 / (double)s->texel_density : 0.0,
               s->texel_density_max > 0.0f ? 1.0 / (double)s->texel_density_max
                                           : s->texel_density > 0.0f ? 1.0 / (double)s->texel_density : 0.0,
               s->lightmap_caches,
               100.0 * (double)s->lightmap_coverage, s->lightmap_gutter, s->lightmap_unused,
               100.0 * s->lightmap_unused /
                   (s->systems > 1 ? (double)s->lightmap_caches + s->lightmap_invalid + s->lightmap_gutter + s->lightmap_unused
                                   : (double)s->lightmap_width * s->lightmap_height * (s->lightmap_pages ? s->lightmap_pages : 1u)),
               s->small_charts,
               s->shared_texels);
    printf("  links     %llu (%u per cache, l=%u, link subsets %s), %.2f bytes per link\n",
           (unsigned long long)s->links, s->links_per_cache, s->bands, lsub_mode, s->bytes_per_link);
    if (s->systems > 1 && s->systems > s->systems_reused)
        printf("  across    the caches of the baked systems link the light of %u neighbouring systems through %llu "
               "proxy nodes; %u neighbours' trees read from their bakes (PTRE), not built again\n",
               s->dependencies, (unsigned long long)s->proxies, s->systems_trees_read);
    if (s->detail_factor)
        printf("  detail    %u texels of %.3g units (%u per lightmap texel side) cover a surface; %u of them correct "
               "the near light with %llu links (%.1f each)\n",
               s->detail_texels, s->texel_density > 0.0f ? 1.0 / ((double)s->texel_density * s->detail_factor) : 0.0,
               s->detail_factor, s->detail_corrected, (unsigned long long)s->detail_links,
               s->detail_corrected ? (double)s->detail_links / s->detail_corrected : 0.0);
    printf("  file      %llu bytes:", (unsigned long long)s->file_size);
    for (uint32_t i = 0; i < s->section_count && i < 16; ++i) {
        fourcc_str(s->section_fourcc[i], fc);
        printf(" %s %llu", fc, (unsigned long long)s->section_size[i]);
    }
    printf("\n  time      %.2f s total (%u threads):", s->total_seconds, s->threads);
    for (int i = 0; i < GLOW_PC_STAGE_COUNT; ++i)
        printf(" %s %.2f", glow_pc_stage_name((uint32_t)i), s->stage_seconds[i]);
    printf("\n  peak RSS  ");
    for (int i = 0; i < GLOW_PC_STAGE_COUNT; ++i)
        printf("%s%s %.1f MiB", i ? ", " : "", glow_pc_stage_name((uint32_t)i), (double)s->stage_peak_rss[i] / 1048576.0);
    printf("\n");
}

/* ---------------------------------------------------------------- --info */
static void info_logger(void *user, glow_log_level level, glow_result code, const char *message, const char *file,
                        int line) {
    (void)user; (void)file; (void)line;
    if (level == GLOW_LOG_ERROR) fprintf(stderr, "glow-bake: %s (%s)\n", message, glow_result_string(code));
}

static int run_info(const char *path, bool json) {
    glow_context *ctx = NULL;
    glow_context_desc cd = {.api_version = GLOW_VERSION, .logger = {.log = info_logger}};
    if (glow_context_create(&cd, &ctx) != GLOW_OK) return 1;
    glow_bake *bake = NULL;
    glow_result r = glow_bake_load_file(ctx, path, &bake);
    if (r != GLOW_OK) {
        glow_context_destroy(ctx);
        return 1;
    }
    glow_bake_info in;
    glow_bake_get_info(bake, &in);
    /* the section table, read from the (already validated) file */
    /* the section table (the bake is already validated) */
    glow_bake_section_info sec[64];
    uint32_t nsec = 0;
    glow_bake_get_sections(bake, sec, 64, &nsec);
    if (nsec > 64) nsec = 64;
    double links = (double)in.cache_count * in.links_per_cache;
    if (json) {
        cJSON *o = cJSON_CreateObject(), *a, *x;
        cJSON_AddStringToObject(o, "file", path);
        const int fmt[2] = {(int)in.format_major, (int)in.format_minor};
        cJSON_AddItemToObject(o, "format", cJSON_CreateIntArray(fmt, 2));
        cJSON_AddNumberToObject(o, "file_bytes", (double)in.file_size);
        cJSON_AddNumberToObject(o, "surfels", in.surfel_count);
        cJSON_AddNumberToObject(o, "surfel_area", in.surfel_area);
        cJSON_AddNumberToObject(o, "scene_area", in.scene_area);
        cJSON_AddNumberToObject(o, "nodes", in.node_count);
        cJSON_AddNumberToObject(o, "levels", in.level_count);
        x = cJSON_AddObjectToObject(o, "caches");
        cJSON_AddNumberToObject(x, "total", in.cache_count);
        cJSON_AddNumberToObject(x, "grid", in.grid_cache_count);
        const int dims[3] = {(int)in.grid_dims[0], (int)in.grid_dims[1], (int)in.grid_dims[2]};
        cJSON_AddItemToObject(x, "grid_dims", cJSON_CreateIntArray(dims, 3));
        cJSON_AddNumberToObject(x, "grid_spacing", in.grid_spacing);
        cJSON_AddNumberToObject(x, "lightmap", in.lightmap_cache_count);
        const int lsz[2] = {(int)in.lightmap_width, (int)in.lightmap_height};
        cJSON_AddItemToObject(x, "lightmap_size", cJSON_CreateIntArray(lsz, 2));
        cJSON_AddNumberToObject(x, "texel_density", in.texel_density);
        x = cJSON_AddObjectToObject(o, "links");
        cJSON_AddNumberToObject(x, "per_cache", in.links_per_cache);
        cJSON_AddNumberToObject(x, "total", links);
        cJSON_AddNumberToObject(x, "bands", in.sh_bands);
        cJSON_AddBoolToObject(x, "full_sh", (in.link_kind & GLOW_LINK_KIND_FULL_SH) != 0);
        cJSON_AddStringToObject(x, "subsets", link_lsub_mode(in.link_kind));
        cJSON_AddNumberToObject(o, "materials", in.material_count);
        cJSON_AddNumberToObject(o, "triangles", in.triangle_count);
        a = cJSON_AddArrayToObject(o, "bounds");
        const double bmin[3] = {in.bounds_min[0], in.bounds_min[1], in.bounds_min[2]},
                     bmax[3] = {in.bounds_max[0], in.bounds_max[1], in.bounds_max[2]};
        cJSON_AddItemToArray(a, cJSON_CreateDoubleArray(bmin, 3));
        cJSON_AddItemToArray(a, cJSON_CreateDoubleArray(bmax, 3));
        a = cJSON_AddArrayToObject(o, "sections");
        for (uint32_t i = 0; a && i < nsec; ++i) {
            char crc[9];
            snprintf(crc, sizeof crc, "%08x", sec[i].crc32);
            cJSON_AddItemToArray(a, x = cJSON_CreateObject());
            cJSON_AddStringToObject(x, "fourcc", sec[i].fourcc);
            cJSON_AddNumberToObject(x, "bytes", (double)sec[i].size);
            cJSON_AddStringToObject(x, "crc32", crc);
        }
        print_json(o);
    } else {
        printf("%s: Glow bake format %u.%u, %llu bytes (valid)\n", path, in.format_major, in.format_minor,
               (unsigned long long)in.file_size);
        printf("  surfels   %u (area %.6g each, scene %.6g)   nodes %u   levels %u\n", in.surfel_count,
               (double)in.surfel_area, in.scene_area, in.node_count, in.level_count);
        if (in.lightmap_count > 1) printf("  lightmap  %u pages of %ux%u\n", in.lightmap_count, in.lightmap_width,
                                          in.lightmap_height);
        printf("  caches    %u = grid %u (%ux%ux%u, spacing %.4g) + lightmap %u (%ux%u, %.4g texels/unit)\n",
               in.cache_count, in.grid_cache_count, in.grid_dims[0], in.grid_dims[1], in.grid_dims[2],
               (double)in.grid_spacing, in.lightmap_cache_count, in.lightmap_width, in.lightmap_height,
               (double)in.texel_density);
        printf("  links     %.0f (%u per cache, l=%u%s, link subsets %s)\n", links, in.links_per_cache, in.sh_bands,
               (in.link_kind & GLOW_LINK_KIND_FULL_SH) ? ", with full-SH links" : "", link_lsub_mode(in.link_kind));
        if (in.system_key)
            printf("  system    key %016llx, %u dependencies, %u proxy nodes (its links to their nodes)\n",
                   (unsigned long long)in.system_key, in.dependency_count, in.proxy_count);
        printf("  scene     %u triangles, %u materials, bounds (%.4g %.4g %.4g)-(%.4g %.4g %.4g)\n", in.triangle_count,
               in.material_count, (double)in.bounds_min[0], (double)in.bounds_min[1], (double)in.bounds_min[2],
               (double)in.bounds_max[0], (double)in.bounds_max[1], (double)in.bounds_max[2]);
        printf("  sections ");
        for (uint32_t i = 0; i < nsec; ++i) {
            printf(" %s %llu", sec[i].fourcc, (unsigned long long)sec[i].size);
        }
        printf("\n");
    }
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    return 0;
}

int main(int argc, char **argv) {
    glow_pc_settings s = {0};
    s.link_gradients = true; /* --link-subsets gradient: the CLI's default (docs/linker.md, "Link gradients") */
    static const char *groups[256]; /* --system-group, pointing into argv (or --systems' strings) */
    static const char *neighbours[256]; /* --systems: each group's declared neighbours, NULL = automatic */
    s.system_groups = groups;
    const char *systems_file = NULL;
    const char *scene = NULL, *out = NULL, *info = NULL;
    bool json = false, quiet = false, mpi = false;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
#define NEED_VALUE() do { if (!v) return usage_error("option %s needs a value", a); ++i; } while (0)
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage_text, stdout);
            return 0;
        } else if (!strcmp(a, "--version")) {
#ifdef GLOW_HAVE_MPI
            const char *mpi_state = "on";
#else
            const char *mpi_state = "off";
#endif
            printf("glow-bake %d.%d.%d (bake format %u.%u, --mpi %s)\n", GLOW_VERSION_MAJOR, GLOW_VERSION_MINOR,
                   GLOW_VERSION_PATCH, GLOW_BAKE_FORMAT_VERSION_MAJOR, GLOW_BAKE_FORMAT_VERSION_MINOR, mpi_state);
            return 0;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            NEED_VALUE();
            out = v;
        } else if (!strcmp(a, "--info")) {
            NEED_VALUE();
            info = v;
        } else if (!strcmp(a, "--quality")) {
            NEED_VALUE();
            if (!strcmp(v, "low")) s.quality = GLOW_PC_QUALITY_LOW;
            else if (!strcmp(v, "moderate")) s.quality = GLOW_PC_QUALITY_MODERATE;
            else if (!strcmp(v, "high")) s.quality = GLOW_PC_QUALITY_HIGH;
            else if (!strcmp(v, "fine")) s.quality = GLOW_PC_QUALITY_FINE;
            else return usage_error("--quality '%s': expected low, moderate, high or fine", v);
        } else if (!strcmp(a, "--surfels")) {
            NEED_VALUE();
            if (!parse_u32(v, 16, 1u << 22, &s.surfels)) return usage_error("--surfels '%s': expected an integer in 16..4194304", v);
        } else if (!strcmp(a, "--links")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 4096, &s.links)) return usage_error("--links '%s': expected an integer in 1..4096", v);
        } else if (!strcmp(a, "--bands")) {
            NEED_VALUE();
            if (!parse_u32(v, 2, 8, &s.bands)) return usage_error("--bands '%s': expected an integer in 2..8", v);
        } else if (!strcmp(a, "--grid-spacing")) {
            NEED_VALUE();
            if (!parse_pos_float(v, &s.grid_spacing)) return usage_error("--grid-spacing '%s': expected a positive length", v);
        } else if (!strcmp(a, "--texel-density")) {
            NEED_VALUE();
            if (!parse_pos_float(v, &s.texel_density)) return usage_error("--texel-density '%s': expected a positive number", v);
        } else if (!strcmp(a, "--lightmap-caches")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 1u << 24, &s.lightmap_caches))
                return usage_error("--lightmap-caches '%s': expected an integer in 1..16777216", v);
        } else if (!strcmp(a, "--lightmap-max-size")) {
            NEED_VALUE();
            if (!parse_u32(v, 4, 4096, &s.lightmap_max_size) || s.lightmap_max_size % 4)
                return usage_error("--lightmap-max-size '%s': expected a multiple of 4 in 4..4096", v);
        } else if (!strcmp(a, "--threads")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 1024, &s.threads)) return usage_error("--threads '%s': expected an integer in 1..1024", v);
        } else if (!strcmp(a, "--seed")) {
            NEED_VALUE();
            if (!parse_u32(v, 0, UINT32_MAX, &s.seed)) return usage_error("--seed '%s': expected an integer in 0..4294967295", v);
        } else if (!strcmp(a, "--rays")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 256, &s.rays_per_surfel)) return usage_error("--rays '%s': expected an integer in 1..256", v);
        } else if (!strcmp(a, "--cut")) {
            NEED_VALUE();
            if (!strcmp(v, "solid-angle")) s.cut_solid_angle = true;
            else if (!strcmp(v, "error")) s.cut_solid_angle = false;
            else return usage_error("--cut '%s': expected error or solid-angle", v);
        } else if (!strcmp(a, "--audit-radiance")) {
            NEED_VALUE();
            s.audit_radiance = v;
        } else if (!strcmp(a, "--audit-csv")) {
            NEED_VALUE();
            s.audit_csv = v;
        } else if (!strcmp(a, "--link-subsets")) {
            NEED_VALUE();
            if (!strcmp(v, "off")) s.no_link_subsets = true, s.link_gradients = false;
            else if (!strcmp(v, "on")) s.no_link_subsets = false, s.link_gradients = false;
            else if (!strcmp(v, "gradient")) s.no_link_subsets = false, s.link_gradients = true;
            else return usage_error("--link-subsets '%s': expected on, off or gradient", v);
        } else if (!strcmp(a, "--link-visibility")) {
            NEED_VALUE();
            if (!strcmp(v, "clustered")) s.link_visibility = GLOW_PC_LINK_VISIBILITY_CLUSTERED;
            else if (!strcmp(v, "exact")) s.link_visibility = GLOW_PC_LINK_VISIBILITY_EXACT;
            else return usage_error("--link-visibility '%s': expected clustered or exact", v);
        } else if (!strcmp(a, "--link-cluster-angle")) {
            NEED_VALUE();
            char *end = NULL;
            double x = strtod(v, &end);
            if (!end || *end || !(x > 0.0 && x <= 1.0))
                return usage_error("--link-cluster-angle '%s': expected radians in (0, 1]", v);
            s.link_cluster_angle = (float)x;
        } else if (!strcmp(a, "--link-cluster-rays")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 64, &s.link_cluster_rays)) return usage_error("--link-cluster-rays '%s': expected an integer in 1..64", v);
        } else if (!strcmp(a, "--lightmap-detail")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 4, &s.lightmap_detail))
                return usage_error("--lightmap-detail '%s': expected 1 (none) or 2..4 detail texels per texel side", v);
        } else if (!strcmp(a, "--detail-radius")) {
            NEED_VALUE();
            char *end = NULL;
            double x = strtod(v, &end);
            if (!end || *end || !(x > 0.0 && x <= 4.0))
                return usage_error("--detail-radius '%s': expected lightmap texels in (0, 4]", v);
            s.detail_radius = (float)x;
        } else if (!strcmp(a, "--system-area")) {
            NEED_VALUE();
            char *end = NULL;
            double x = strtod(v, &end);
            if (!end || *end || !(x > 0.0 && x < 1e30))
                return usage_error("--system-area '%s': expected a positive area in scene units squared", v);
            s.system_area = (float)x;
        } else if (!strcmp(a, "--system-group")) {
            NEED_VALUE();
            if (s.system_group_count == 256) return usage_error("--system-group: at most 256 groups");
            groups[s.system_group_count++] = v;
        } else if (!strcmp(a, "--systems")) {
            NEED_VALUE();
            if (systems_file) return usage_error("--systems is given twice");
            systems_file = v;
        } else if (!strcmp(a, "--system-reach")) {
            NEED_VALUE();
            char *end = NULL;
            double x = strtod(v, &end);
            if (!end || *end || !(x > 0.0 && x <= 4.0))
                return usage_error("--system-reach '%s': expected a fraction of a system's diagonal in (0, 4]", v);
            s.system_reach = (float)x;
        } else if (!strcmp(a, "--surfel-adapt")) {
            NEED_VALUE();
            char *end = NULL;
            double x = strtod(v, &end);
            if (!end || *end || !(x >= 1.0 && x <= 4.0))
                return usage_error("--surfel-adapt '%s': expected a density ratio in [1, 4] (1 = area-uniform)", v);
            s.surfel_adapt = (float)x;
        } else if (!strcmp(a, "--grid-refine")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 4, &s.grid_refine) || s.grid_refine == 3)
                return usage_error("--grid-refine '%s': expected 1 (uniform), 2 or 4", v);
        } else if (!strcmp(a, "--texel-adapt")) {
            NEED_VALUE();
            char *end = NULL;
            double x = strtod(v, &end);
            if (!end || *end || !(x >= 1.0 && x <= 8.0))
                return usage_error("--texel-adapt '%s': expected a density ratio in [1, 8] (1 = uniform)", v);
            s.texel_adapt = (float)x;
        } else if (!strcmp(a, "--detail-links")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 256, &s.detail_links)) return usage_error("--detail-links '%s': expected an integer in 1..256", v);
        } else if (!strcmp(a, "--sky-rays")) {
            NEED_VALUE();
            if (!parse_u32(v, 1, 65536, &s.sky_rays)) return usage_error("--sky-rays '%s': expected an integer in 1..65536", v);
        } else if (!strcmp(a, "--no-sky")) {
            s.no_sky = true;
        } else if (!strcmp(a, "--no-link-normalize")) {
            s.no_link_normalize = true;
        } else if (!strcmp(a, "--sh-links")) {
            s.sh_links = true;
        } else if (!strcmp(a, "--mpi")) {
            mpi = true;
        } else if (!strcmp(a, "--json")) {
            json = true;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            quiet = true;
        } else if (a[0] == '-' && a[1] != 0) {
            return usage_error("unknown option '%s'", a);
        } else {
            if (scene) return usage_error("more than one scene given ('%s' and '%s')", scene, a);
            scene = a;
        }
#undef NEED_VALUE
    }
    if (info) {
        if (scene || out) return usage_error("--info takes only a bake file (and --json)");
        return run_info(info, json);
    }
    if (!scene) return usage_error("no scene given");
    if (s.audit_csv && !s.audit_radiance) return usage_error("--audit-csv needs --audit-radiance");
    if (s.audit_radiance && s.system_area > 0.0f) return usage_error("--audit-radiance audits a bake of one system (no --system-area)");
    if (s.system_reach > 0.0f && !(s.system_area > 0.0f)) return usage_error("--system-reach needs --system-area");
    if (s.sh_links && s.system_area > 0.0f)
        return usage_error("--sh-links with --system-area: full-SH links to neighbouring systems are not supported");
    if (!out) return usage_error("no output file given (-o OUT.glow)");
    char msg[512];
    if (systems_file) {
        if (s.system_group_count) return usage_error("--systems and --system-group: name the systems in one place");
        if (!(s.system_area > 0.0f)) return usage_error("--systems needs --system-area");
        if (!load_systems(systems_file, groups, neighbours, &s.system_group_count, msg, sizeof msg)) {
            fprintf(stderr, "glow-bake: error: %s\n", msg);
            return 1;
        }
        s.system_neighbours = neighbours;
        if (glow_pc_settings_validate(&s, msg, sizeof msg) != GLOW_OK) { /* names, unknown or repeated ones */
            fprintf(stderr, "glow-bake: error: %s: %s\n", systems_file, msg);
            return 1;
        }
    }
    if (glow_pc_settings_validate(&s, msg, sizeof msg) != GLOW_OK) return usage_error("%s", msg);

    if (mpi && info) return usage_error("--mpi bakes; --info reads one bake file");
#ifndef GLOW_HAVE_MPI
    if (mpi)
        return usage_error("--mpi: this glow-bake was built without MPI (install libopenmpi-dev and rebuild; "
                           "tools/setup.sh does)");
#endif
    glow_pc_distribution dist = {.rank = 0, .ranks = 1};
#ifdef GLOW_HAVE_MPI
    if (mpi) {
        char err[256];
        if (!glow_bake_mpi_begin(&argc, &argv, &dist, err, sizeof err)) {
            fprintf(stderr, "glow-bake: error: --mpi: %s\n", err);
            return 1;
        }
        s.distribution = &dist;
        glow_bake_mpi_output(out);
        if (dist.rank != 0) quiet = true; /* rank 0 reports progress and the summary */
    }
#endif
    progress_state ps = {.tty = isatty(2) != 0, .quiet = quiet};
    s.progress = on_progress;
    s.progress_user = &ps;
    s.logger = (glow_logger){.log = on_log, .user = &ps};
    glow_pc_stats stats;
    glow_result r = glow_pc_bake(scene, out, &s, &stats);
    if (r != GLOW_OK) {
        if (ps.tty) fputs("\r\033[K", stderr);
        if (mpi)
            fprintf(stderr, "glow-bake: rank %u of %u: error: %s\n", dist.rank, dist.ranks,
                    stats.error[0] ? stats.error : glow_result_string(r));
        else
            fprintf(stderr, "glow-bake: error: %s\n", stats.error[0] ? stats.error : glow_result_string(r));
        if (systems_file && r == GLOW_ERROR_INVALID_ARGUMENT)
            fprintf(stderr, "glow-bake: (the systems and their neighbours are declared in %s)\n", systems_file);
#ifdef GLOW_HAVE_MPI
        if (mpi) glow_bake_mpi_end(1);
#endif
        return 1;
    }
    if (dist.rank == 0)
        print_summary(scene, out, &stats, json, s.no_link_subsets ? "off" : (s.link_gradients ? "gradient" : "on"));
#ifdef GLOW_HAVE_MPI
    if (mpi) glow_bake_mpi_end(0);
#endif
    return 0;
}
