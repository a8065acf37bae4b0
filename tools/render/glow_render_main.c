/* glow-render — the reference path tracer (Embree) and Glow's view of the same camera, over one scene
 * description file. See docs/render.md and tools/render/lib/glow_render.h for the definitions.
 *
 *   glow-render SCENE.json --out PREFIX [options]              the reference
 *   glow-render SCENE.json --glow BAKE --out PREFIX [options]  Glow's view (bake made from SCENE's mesh)
 *
 * Writes PREFIX.exr (final), PREFIX_direct.exr, PREFIX_indirect.exr (linear radiance, 32-bit float) and
 * PREFIX.png (final, exposure + sRGB), all or nothing; prints a summary on stdout.
 * Exit: 0 ok, 1 failure (input, bake, output), 2 usage. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "glow_cli.h"
#include "glow_render.h"

static void usage(FILE *f) {
    fprintf(f,
            "usage: glow-render SCENE.json --out PREFIX [--spp N] [--seed S] [--threads N] [--width W --height H]\n"
            "                   [--exposure E] [--max-depth D] [--albedo-scale A] [--near-split R] [--envmap-bsdf-only]\n"
            "                   [--glow BAKE [--bounces K] [--sky-rays R] [--surfel-samples K] [--luma L] [--chroma C]\n"
            "                   [--link-mode compact|expanded|sh] [--indirect-only] [--no-detail] [--grid-only]\n"
            "                   [--glossy zh-ggx|zh-ggx-dominant|phong|none]] [--progress | -q]\n"
            "  SCENE.json       scene description (docs/scene-format.md): mesh, camera, lights, environment(_map)\n"
            "  --out PREFIX     writes PREFIX.exr (final), PREFIX_direct.exr, PREFIX_indirect.exr, PREFIX.png;\n"
            "                   Glow's view of a bake with a lightmap also PREFIX_texel.exr, each pixel's texel\n"
            "                   (x + 1, y + 1, cache + 1) for glow-compare --texels; a scene with a GGX material\n"
            "                   (\"materials\", docs/glossy.md) also PREFIX_specular.exr, the indirect light its\n"
            "                   first hit's GGX lobe reflects (part of PREFIX_indirect.exr)\n"
            "  --spp N          samples per pixel (default 64)\n"
            "  --seed S         random seed (default 1); same seed and size: same image for any --threads\n"
            "  --threads N      worker threads (default: one per online CPU)\n"
            "  --width/--height image size (default: the scene camera's); give both\n"
            "  --exposure E     PNG exposure multiplier before sRGB encoding (default 1)\n"
            "  --max-depth D    path vertices at most (default 256; Russian roulette ends paths well before)\n"
            "  --albedo-scale A multiplies every albedo, clamped to 0.999 (default 1; e.g. the furnace at 0.9: 1.8)\n"
            "  --near-split R   reference only: also writes PREFIX_indirect_near.exr, the part of the indirect\n"
            "                   light that reached each first hit from a surface closer than R scene units (the\n"
            "                   scale a cache-based solver must resolve to reproduce it); the rest is far light\n"
            "  --envmap-bsdf-only  the scene's environment_map reached by BSDF sampling only (no next-event\n"
            "                   estimation of the map, no MIS): the same expected image, noisier (docs/envmap.md)\n"
            "  --glow BAKE      render Glow's view: direct light as the reference computes it, indirect light\n"
            "                   from BAKE's caches (lightmap on static surfaces, else the grid)\n"
            "  --bounces K      Glow's feedback iterations in all, run as updates of up to 64 (default 192)\n"
            "  --sky-rays R     the host's rays per surfel for sky visibility (default: glow_host's 128)\n"
            "  --surfel-samples K  the host's shadow-ray points per surfel footprint, 1..8 (default: glow_host's 8;\n"
            "                   1 = one ray from the centre)\n"
            "  --luma L         SH bands of Glow's luma (default: the bake's); --chroma C of its chroma (default L)\n"
            "  --link-mode M    compact (runtime projection, default), expanded, or sh (the bake's full-SH links,\n"
            "                   glow-bake --sh-links)\n"
            "  --indirect-only  Glow's view without the direct term (only camera rays and cache lookups): its\n"
            "                   direct image equals the reference's for the same seed, size and spp\n"
            "  --no-detail      Glow's view without the bake's lightmap detail (glow-bake --lightmap-detail)\n"
            "  --glossy LOBE    Glow's view of GGX materials: zh-ggx (default: the GGX lobe's zonal harmonics and\n"
            "                   the split sum, about the reflection vector), zh-ggx-dominant (the same about the\n"
            "                   lobe's dominant direction, leant towards the normal), phong (the Phong lobe of\n"
            "                   the same width, same split sum), none (no specular from the caches); docs/glossy.md\n"
            "  --grid-only      Glow's view with every surface shaded from the grid, as a dynamic object\n"
            "                   there (0.1 %% of the scene's diagonal off the surface): the grid's accuracy\n"
            "  --glow-move SCENE2.json --glow-move-iterations K  Glow's view after its light changes: converged with\n"
            "                   SCENE's lights, then K feedback iterations (frames) with SCENE2's (same mesh)\n"
            "  --progress       progress bar on stderr even when it is not a terminal; -q: none, no summary\n"
            "DDISH-GI on the bake's caches (docs/ddish.md): --ddish BAKE instead of --glow BAKE, and\n"
            "  --ddish-rays N   rays per cache per frame (default 256, the paper's)\n"
            "  --ddish-frames F frames (default 300)\n"
            "  --ddish-hysteresis A  history weight in [0, 1) (default 0.99, the paper's)\n"
            "  --ddish-ramp     cold start as a running mean (frame f weighs the history min(A, f/(f+1)))\n"
            "  --ddish-bounces B path bounces from a cache (default 32, the paper's)\n"
            "  --ddish-no-cull  probe rays stop at back faces (the paper culls them: rays pass through)\n"
            "  --ddish-move SCENE2.json --ddish-move-frame K  from frame K on, SCENE2's lights (same mesh)\n"
            "  --ddish-eval-every K  after every K-th frame and the last, render the view (indirect only) and\n"
            "                   compare it with --ddish-ref IMG [--ddish-ref-add IMG] (after the move:\n"
            "                   --ddish-ref-moved IMG [--ddish-ref-moved-add IMG]): 8x8 block error, mean ratio\n"
            "  --ddish-csv FILE per frame: frame,moved,update_ms,rays,block_error,mean_ratio,rel_rmse\n");
}



typedef struct options {
    const char *scene, *out, *bake;
    const char *ddish;                  /* --ddish BAKE */
    glow_render_ddish_settings ds;
    const char *move_scene, *ref, *ref_add, *ref_moved, *ref_moved_add, *csv;
    const char *glow_move;              /* --glow-move SCENE2 */
    int have_glow_move_it;
    int ddish_opts;                     /* a --ddish-* option was given */
    glow_render_settings rs;
    glow_render_glow_settings gs;
    float exposure;
    int quiet, progress;
} options;

typedef struct progress_state {
    int last;
} progress_state;

static void progress_bar(void *user, double fraction) {
    progress_state *p = user;
    int pct = (int)(fraction * 100.0 + 1e-9);
    if (pct == p->last) return;
    p->last = pct;
    char bar[41];
    int fill = pct * 40 / 100;
    for (int i = 0; i < 40; ++i) bar[i] = i < fill ? '#' : '.';
    bar[40] = 0;
    fprintf(stderr, "\rglow-render [%s] %3d%%", bar, pct);
    if (pct >= 100) fputc('\n', stderr);
    fflush(stderr);
}

static int parse_args(int argc, char **argv, options *o) {
    memset(o, 0, sizeof *o);
    o->exposure = 1.0f;
    o->rs.seed = 1;
    o->rs.spp = 64;
    int have_w = 0, have_h = 0, have_glossy = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        uint64_t u;
#define NEED_U(min, max, dst, what)                                                               \
    do {                                                                                          \
        if (!glow_cli_u64(v, 0, max, &u) || u < (min)) {                                                \
            fprintf(stderr, "glow-render: %s needs %s, not \"%s\"\n", a, what, v ? v : "nothing"); \
            return 0;                                                                             \
        }                                                                                         \
        dst = u;                                                                                  \
        ++i;                                                                                      \
    } while (0)
        if (!strcmp(a, "--out")) {
            if (!v || !*v) { fprintf(stderr, "glow-render: --out needs a PREFIX\n"); return 0; }
            o->out = v;
            ++i;
        } else if (!strcmp(a, "--glow")) {
            if (!v || !*v) { fprintf(stderr, "glow-render: --glow needs a BAKE file\n"); return 0; }
            o->bake = v;
            ++i;
        } else if (!strcmp(a, "--ddish")) {
            if (!v || !*v) { fprintf(stderr, "glow-render: --ddish needs a BAKE file\n"); return 0; }
            o->ddish = v;
            ++i;
        } else if (!strcmp(a, "--glow-move")) {
            if (!v || !*v) { fprintf(stderr, "glow-render: --glow-move needs a SCENE2.json\n"); return 0; }
            o->glow_move = v;
            ++i;
        } else if (!strcmp(a, "--glow-move-iterations")) {
            NEED_U(1, 100000, o->gs.moved_iterations, "a number of iterations in 1..100000");
            o->have_glow_move_it = 1;
        } else if (!strcmp(a, "--ddish-rays")) { NEED_U(1, 65536, o->ds.rays, "a number of rays in 1..65536"); o->ddish_opts = 1; }
        else if (!strcmp(a, "--ddish-frames")) { NEED_U(1, 1000000, o->ds.frames, "a number of frames in 1..1000000"); o->ddish_opts = 1; }
        else if (!strcmp(a, "--ddish-bounces")) { NEED_U(1, 1024, o->ds.bounces, "a number of bounces in 1..1024"); o->ddish_opts = 1; }
        else if (!strcmp(a, "--ddish-move-frame")) { NEED_U(1, 999999, o->ds.move_frame, "a frame in 1..999999"); o->ddish_opts = 1; }
        else if (!strcmp(a, "--ddish-eval-every")) { NEED_U(1, 1000000, o->ds.eval_every, "a number of frames in 1..1000000"); o->ddish_opts = 1; }
        else if (!strcmp(a, "--ddish-ramp")) { o->ds.ramp = true; o->ddish_opts = 1; }
        else if (!strcmp(a, "--ddish-no-cull")) { o->ds.no_cull = true; o->ddish_opts = 1; }
        else if (!strcmp(a, "--ddish-hysteresis")) {
            if (!glow_cli_float(v, &o->ds.hysteresis) || !(o->ds.hysteresis >= 0.0f && o->ds.hysteresis < 1.0f)) {
                fprintf(stderr, "glow-render: --ddish-hysteresis needs a number in [0, 1), not \"%s\"\n", v ? v : "nothing");
                return 0;
            }
            o->ds.hysteresis_set = true;
            o->ddish_opts = 1;
            ++i;
        } else if (!strcmp(a, "--ddish-move") || !strcmp(a, "--ddish-ref") || !strcmp(a, "--ddish-ref-add") ||
                   !strcmp(a, "--ddish-ref-moved") || !strcmp(a, "--ddish-ref-moved-add") || !strcmp(a, "--ddish-csv")) {
            if (!v || !*v) { fprintf(stderr, "glow-render: %s needs a file\n", a); return 0; }
            const char **dst = !strcmp(a, "--ddish-move") ? &o->move_scene : !strcmp(a, "--ddish-ref") ? &o->ref
                             : !strcmp(a, "--ddish-ref-add") ? &o->ref_add : !strcmp(a, "--ddish-ref-moved") ? &o->ref_moved
                             : !strcmp(a, "--ddish-ref-moved-add") ? &o->ref_moved_add : &o->csv;
            *dst = v;
            o->ddish_opts = 1;
            ++i;
        } else if (!strcmp(a, "--spp")) NEED_U(1, 1u << 20, o->rs.spp, "a number of samples in 1..1048576");
        else if (!strcmp(a, "--seed")) {
            if (!glow_cli_u64(v, 0, UINT64_MAX, &o->rs.seed)) {
                fprintf(stderr, "glow-render: --seed needs a whole number >= 0, not \"%s\"\n", v ? v : "nothing");
                return 0;
            }
            ++i;
        }
        else if (!strcmp(a, "--threads")) NEED_U(1, 1024, o->rs.threads, "a number of threads in 1..1024");
        else if (!strcmp(a, "--width")) { NEED_U(1, 16384, o->rs.width, "a width in 1..16384"); have_w = 1; }
        else if (!strcmp(a, "--height")) { NEED_U(1, 16384, o->rs.height, "a height in 1..16384"); have_h = 1; }
        else if (!strcmp(a, "--max-depth")) NEED_U(1, 1u << 16, o->rs.max_depth, "a depth in 1..65536");
        else if (!strcmp(a, "--bounces")) NEED_U(1, 100000, o->gs.bounce_iterations, "a number of iterations in 1..100000");
        else if (!strcmp(a, "--sky-rays")) NEED_U(1, 65536, o->gs.sky_rays, "a number of rays in 1..65536");
        else if (!strcmp(a, "--surfel-samples")) NEED_U(1, 8, o->gs.surfel_samples, "a number of points in 1..8");
        else if (!strcmp(a, "--luma")) NEED_U(1, GLOW_MAX_SH_BANDS, o->gs.sh_bands_luma, "a band count in 1..8");
        else if (!strcmp(a, "--chroma")) NEED_U(1, GLOW_MAX_SH_BANDS, o->gs.sh_bands_chroma, "a band count in 1..8");
        else if (!strcmp(a, "--indirect-only")) o->gs.indirect_only = true;
        else if (!strcmp(a, "--envmap-bsdf-only")) o->rs.envmap_bsdf_only = true;
        else if (!strcmp(a, "--no-detail")) o->gs.no_detail = true;
        else if (!strcmp(a, "--grid-only")) o->gs.grid_only = true;
        else if (!strcmp(a, "--glossy")) {
            if (!v || (strcmp(v, "zh-ggx") && strcmp(v, "zh-ggx-dominant") && strcmp(v, "phong") && strcmp(v, "none"))) {
                fprintf(stderr, "glow-render: --glossy needs zh-ggx, zh-ggx-dominant, phong or none\n");
                return 0;
            }
            o->gs.glossy = !strcmp(v, "phong")             ? GLOW_RENDER_GLOSSY_PHONG
                           : !strcmp(v, "none")            ? GLOW_RENDER_GLOSSY_NONE
                           : !strcmp(v, "zh-ggx-dominant") ? GLOW_RENDER_GLOSSY_ZH_GGX_DOMINANT
                                                           : GLOW_RENDER_GLOSSY_ZH_GGX;
            have_glossy = 1;
            ++i;
        }
        else if (!strcmp(a, "--link-mode")) {
            if (!v || (strcmp(v, "compact") && strcmp(v, "expanded") && strcmp(v, "sh"))) {
                fprintf(stderr, "glow-render: --link-mode must be compact, expanded or sh, not \"%s\"\n", v ? v : "nothing");
                return 0;
            }
            o->gs.link_mode = !strcmp(v, "sh") ? GLOW_LINK_MODE_SH : !strcmp(v, "expanded") ? GLOW_LINK_MODE_EXPANDED
                                                                                           : GLOW_LINK_MODE_COMPACT;
            ++i;
        }
        else if (!strcmp(a, "--exposure")) {
            if (!glow_cli_float(v, &o->exposure) || o->exposure < 0.0f) {
                fprintf(stderr, "glow-render: --exposure needs a finite number >= 0, not \"%s\"\n", v ? v : "nothing");
                return 0;
            }
            ++i;
        } else if (!strcmp(a, "--albedo-scale")) {
            if (!glow_cli_float(v, &o->rs.albedo_scale) || !(o->rs.albedo_scale > 0.0f)) {
                fprintf(stderr, "glow-render: --albedo-scale needs a finite number > 0, not \"%s\"\n", v ? v : "nothing");
                return 0;
            }
            ++i;
        } else if (!strcmp(a, "--near-split")) {
            if (!glow_cli_float(v, &o->rs.near_split) || !(o->rs.near_split > 0.0f)) {
                fprintf(stderr, "glow-render: --near-split needs a finite distance > 0, not \"%s\"\n", v ? v : "nothing");
                return 0;
            }
            ++i;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) o->quiet = 1;
        else if (!strcmp(a, "--progress")) o->progress = 1;
        else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            exit(0);
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "glow-render: unknown option %s\n", a);
            return 0;
        } else if (!o->scene) o->scene = a;
        else {
            fprintf(stderr, "glow-render: unexpected argument %s (one SCENE.json only)\n", a);
            return 0;
        }
#undef NEED_U
    }
    if (!o->scene) { fprintf(stderr, "glow-render: need a SCENE.json\n"); return 0; }
    if (!o->out) { fprintf(stderr, "glow-render: need --out PREFIX\n"); return 0; }
    if (have_w != have_h) { fprintf(stderr, "glow-render: give both --width and --height\n"); return 0; }
    if (o->bake && o->ddish) { fprintf(stderr, "glow-render: --glow and --ddish: one view at a time\n"); return 0; }
    if (o->ddish_opts && !o->ddish) { fprintf(stderr, "glow-render: the --ddish-* options go with --ddish BAKE\n"); return 0; }
    if (o->ddish && o->rs.near_split > 0.0f) {
        fprintf(stderr, "glow-render: --near-split splits the reference's light; it does not go with --ddish\n");
        return 0;
    }
    if ((o->ref_add && !o->ref) || (o->ref_moved_add && !o->ref_moved) || (o->ref_moved && !o->move_scene)) {
        fprintf(stderr, "glow-render: --ddish-ref-add needs --ddish-ref, --ddish-ref-moved-add --ddish-ref-moved, "
                        "and --ddish-ref-moved --ddish-move\n");
        return 0;
    }
    if ((o->glow_move || o->have_glow_move_it) && (!o->bake || !o->glow_move || !o->have_glow_move_it)) {
        fprintf(stderr, "glow-render: --glow-move SCENE2 and --glow-move-iterations K go together, with --glow BAKE\n");
        return 0;
    }
    if (o->ds.move_frame && !o->move_scene) { fprintf(stderr, "glow-render: --ddish-move-frame goes with --ddish-move\n"); return 0; }
    if (o->ref && !o->ds.eval_every) o->ds.eval_every = 1;
    if (o->bake && o->rs.near_split > 0.0f) {
        fprintf(stderr, "glow-render: --near-split splits the reference's light; it does not go with --glow\n");
        return 0;
    }
    if (!o->bake && !o->ddish && (o->gs.bounce_iterations || o->gs.sky_rays || o->gs.surfel_samples || o->gs.sh_bands_luma ||
                                  o->gs.sh_bands_chroma || o->gs.link_mode || o->gs.indirect_only || o->gs.no_detail ||
                                  o->gs.grid_only || have_glossy)) {
        fprintf(stderr, "glow-render: --bounces, --sky-rays, --surfel-samples, --luma, --chroma, --link-mode, --indirect-only, "
                        "--no-detail, --grid-only and --glossy go with --glow BAKE (or --ddish BAKE)\n");
        return 0;
    }
    return 1;
}

/* ---- --ddish: the per-frame error against a reference image */
typedef struct ddish_eval {
    glow_eval_image ref, ref_moved; /* with their --*-add images added */
    FILE *csv;
    int quiet;
} ddish_eval;

static int load_ref(const char *path, const char *add, glow_eval_image *out, uint32_t w, uint32_t h) {
    char msg[1024];
    if (glow_eval_read_image(path, out, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-render: %s\n", msg);
        return 0;
    }
    if (out->width != w || out->height != h) {
        fprintf(stderr, "glow-render: %s is %u x %u but the view is %u x %u (pass --width %u --height %u)\n", path,
                out->width, out->height, w, h, out->width, out->height);
        return 0;
    }
    if (add) {
        glow_eval_image a;
        if (glow_eval_read_image(add, &a, msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-render: %s\n", msg);
            return 0;
        }
        if (a.width != w || a.height != h) {
            fprintf(stderr, "glow-render: %s is %u x %u but the view is %u x %u\n", add, a.width, a.height, w, h);
            glow_eval_image_free(&a);
            return 0;
        }
        for (size_t i = 0; i < (size_t)w * h * 3; ++i) out->rgb[i] += a.rgb[i];
        glow_eval_image_free(&a);
    }
    return 1;
}

static glow_result ddish_frame(void *user, const glow_render_ddish_frame *f) {
    ddish_eval *e = user;
    double be = NAN, mr = NAN, rr = NAN;
    const glow_eval_image *ref = f->moved ? &e->ref_moved : &e->ref;
    if (f->view && ref->rgb) {
        be = glow_eval_block_error(&f->view->indirect, ref, NULL, 0);
        mr = glow_eval_mean_ratio(&f->view->indirect, ref, NULL);
        rr = glow_eval_rel_rmse(&f->view->indirect, ref, NULL);
    }
    if (e->csv)
        fprintf(e->csv, "%u,%d,%.4f,%llu,%.6g,%.6g,%.6g\n", f->frame, f->moved ? 1 : 0, f->update_ms,
                (unsigned long long)f->rays, be, mr, rr);
    if (!e->quiet && f->view)
        fprintf(stderr, "glow-render: ddish frame %u%s: update %.1f ms, block error %.4f, mean ratio %.4f\n", f->frame,
                f->moved ? " (moved)" : "", f->update_ms, be, mr);
    return GLOW_OK;
}

int main(int argc, char **argv) {
    options o;
    if (!parse_args(argc, argv, &o)) {
        fprintf(stderr, "(glow-render --help for the options)\n");
        return 2;
    }
    /* fail before rendering, not after, when the output folder is missing or read-only */
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", o.out);
    char *slash = strrchr(dir, '/');
    if (slash) slash[slash == dir ? 1 : 0] = 0;
    else snprintf(dir, sizeof dir, ".");
    if (access(dir, W_OK | X_OK) != 0) {
        fprintf(stderr, "glow-render: --out %s: the folder %s does not exist or is not writable\n", o.out, dir);
        return 1;
    }
    char msg[2048];
    glow_render_scene *scene = NULL;
    glow_result r = glow_render_scene_load(o.scene, &scene, msg, sizeof msg);
    if (r != GLOW_OK) {
        fprintf(stderr, "glow-render: %s\n", msg);
        return 1;
    }
    progress_state ps = {-1};
    if (!o.quiet && (o.progress || isatty(STDERR_FILENO))) {
        o.rs.progress = progress_bar;
        o.rs.progress_user = &ps;
    }
    glow_render_result res;
    glow_render_ddish_stats dst;
    memset(&dst, 0, sizeof dst);
    if (o.ddish) {
        glow_render_scene *moved = NULL;
        ddish_eval ev;
        memset(&ev, 0, sizeof ev);
        ev.quiet = o.quiet;
        glow_render_scene_info si;
        glow_render_scene_get_info(scene, &si);
        const uint32_t w = o.rs.width ? o.rs.width : si.camera.width, h = o.rs.height ? o.rs.height : si.camera.height;
        int ok = 1;
        if (o.move_scene && glow_render_scene_load(o.move_scene, &moved, msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-render: %s\n", msg);
            ok = 0;
        }
        if (ok && o.ref) ok = load_ref(o.ref, o.ref_add, &ev.ref, w, h);
        if (ok && o.ref_moved) ok = load_ref(o.ref_moved, o.ref_moved_add, &ev.ref_moved, w, h);
        if (ok && o.csv) {
            if (!(ev.csv = fopen(o.csv, "w"))) {
                fprintf(stderr, "glow-render: --ddish-csv %s: %s\n", o.csv, strerror(errno));
                ok = 0;
            } else {
                fprintf(ev.csv, "frame,moved,update_ms,rays,block_error,mean_ratio,rel_rmse\n");
            }
        }
        if (ok) {
            o.ds.moved = moved;
            o.ds.on_frame = ddish_frame;
            o.ds.user = &ev;
            r = glow_render_ddish(scene, o.ddish, &o.rs, &o.gs, &o.ds, &res, &dst, msg, sizeof msg);
        }
        if (ev.csv && fclose(ev.csv) != 0 && ok && r == GLOW_OK) {
            snprintf(msg, sizeof msg, "--ddish-csv %s: %s", o.csv, strerror(errno));
            r = GLOW_ERROR_IO;
        }
        glow_eval_image_free(&ev.ref);
        glow_eval_image_free(&ev.ref_moved);
        glow_render_scene_destroy(moved);
        if (!ok) {
            glow_render_scene_destroy(scene);
            return 1;
        }
    } else if (o.bake) {
        glow_render_scene *moved = NULL;
        if (o.glow_move && glow_render_scene_load(o.glow_move, &moved, msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-render: %s\n", msg);
            glow_render_scene_destroy(scene);
            return 1;
        }
        o.gs.moved = moved;
        r = glow_render_glow(scene, o.bake, &o.rs, &o.gs, &res, msg, sizeof msg);
        glow_render_scene_destroy(moved);
    }
    else r = glow_render_reference(scene, &o.rs, &res, msg, sizeof msg);
    if (r != GLOW_OK) {
        fprintf(stderr, "glow-render: %s\n", msg);
        glow_render_scene_destroy(scene);
        return 1;
    }
    r = glow_render_write(&res, o.out, o.exposure, msg, sizeof msg);
    if (r != GLOW_OK) {
        fprintf(stderr, "glow-render: %s\n", msg);
        glow_render_result_free(&res);
        glow_render_scene_destroy(scene);
        return 1;
    }
    if (res.nonfinite_samples)
        fprintf(stderr,
                "glow-render: warning: %llu samples had a NaN or infinite radiance and were left out of their pixels "
                "(a bug: please report it with the scene, size, spp and seed)\n",
                (unsigned long long)res.nonfinite_samples);
    if (!o.quiet) {
        glow_render_scene_info info;
        glow_render_scene_get_info(scene, &info);
        printf("glow-render %s: %s (%u triangles, %u emissive, %u lights)%s%s\n", o.scene, info.mesh, info.triangle_count,
               info.emissive_triangle_count, info.light_count, o.bake ? ", Glow's view of " : o.ddish ? ", DDISH's view of " : ", reference",
               o.bake ? o.bake : o.ddish ? o.ddish : "");
        if (info.environment_map)
            printf("  environment map %s (%ux%u, rotation %g deg, scale %g)%s\n", info.environment_map,
                   info.environment_map_width, info.environment_map_height,
                   (double)info.environment_map_rotation_deg, (double)info.environment_map_scale,
                   o.rs.envmap_bsdf_only ? ", BSDF sampling only" : ", importance-sampled + MIS");
        if (o.ddish)
            printf("  ddish: %u caches (%u grid, %u lightmap), %u coefficients (%u B as float), %u frames x %u rays, "
                   "hysteresis %g%s, %u threads: update median %.2f ms (mean %.2f, min %.2f), %.2f M rays per frame\n",
                   dst.caches, dst.grid_caches, dst.lightmap_caches, dst.coeff_count, 4u * dst.coeff_count, dst.frames,
                   o.ds.rays ? o.ds.rays : 256u, o.ds.hysteresis_set ? (double)o.ds.hysteresis : 0.99,
                   o.ds.ramp ? " (ramp)" : "", dst.threads, dst.median_ms, dst.mean_ms, dst.min_ms,
                   dst.frames ? (double)dst.rays * 1e-6 / dst.frames : 0.0);
        if (o.bake)
            printf("  glow: solve %.2f s (%u bounce iterations); first hits from the lightmap %llu, grid %llu, none %llu\n",
                   res.solve_seconds, o.gs.bounce_iterations ? o.gs.bounce_iterations : 192u,
                   (unsigned long long)res.lightmap_lookups, (unsigned long long)res.grid_lookups,
                   (unsigned long long)res.missed_lookups);
        printf("  %u x %u, %u spp, seed %llu, %u threads: %.2f s, %.1f M rays, %.2f Mrays/s\n", res.width, res.height,
               res.spp, (unsigned long long)o.rs.seed, res.threads, res.seconds, (double)res.rays * 1e-6, res.mrays_per_s);
        printf("  mean radiance W/(m^2 sr) (R G B): final %.5g %.5g %.5g | direct %.5g %.5g %.5g | indirect %.5g %.5g %.5g\n",
               res.mean_final[0], res.mean_final[1], res.mean_final[2], res.mean_direct[0], res.mean_direct[1],
               res.mean_direct[2], res.mean_indirect[0], res.mean_indirect[1], res.mean_indirect[2]);
        if (res.indirect_near.rgb) {
            const double ln = 0.2126 * res.mean_indirect_near[0] + 0.7152 * res.mean_indirect_near[1] +
                              0.0722 * res.mean_indirect_near[2],
                         li = 0.2126 * res.mean_indirect[0] + 0.7152 * res.mean_indirect[1] + 0.0722 * res.mean_indirect[2];
            printf("  near light (from surfaces closer than %g): %.5g %.5g %.5g, %.1f %% of the indirect luma\n",
                   (double)o.rs.near_split, res.mean_indirect_near[0], res.mean_indirect_near[1], res.mean_indirect_near[2],
                   li > 0.0 ? 100.0 * ln / li : 0.0);
        }
        if (res.specular.rgb)
            printf("  specular (GGX lobes' indirect light, part of indirect): %.5g %.5g %.5g\n", res.mean_specular[0],
                   res.mean_specular[1], res.mean_specular[2]);
        printf("  wrote %s.exr %s_direct.exr %s_indirect.exr %s.png%s%s%s\n", o.out, o.out, o.out, o.out,
               res.indirect_near.rgb ? " " : "", res.indirect_near.rgb ? o.out : "", res.indirect_near.rgb ? "_indirect_near.exr" : "");
        if (res.specular.rgb) printf("  wrote %s_specular.exr\n", o.out);
    }
    glow_render_result_free(&res);
    glow_render_scene_destroy(scene);
    return 0;
}
