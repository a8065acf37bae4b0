/* 04_hdr_sky — an HDR environment map as the sky, turning every frame: CPU only (glow.h, glow_host.h).
 *   1. read an equirectangular (lat-long) RGB OpenEXR sky with OpenEXR's C core,
 *   2. split off its sun, the way an engine does: the sun becomes a directional light (shadowed), the
 *      smooth rest 27 floats of SH (l <= 2, RGB) — nine coefficients cannot hold a 0.5° sun,
 *   3. light the bake's surfels with both through the CPU host (exact shadow rays for the sun; the
 *      bake's per-surfel sky transfer for the SH sky: no rays) and add the sky the grid caches see
 *      (glow_system_set_sky), so that dynamic objects receive it too,
 *   4. every frame turn the sky about +Y, hand the turned SH and sun to the host and the system, update,
 *      and print how the indirect light follows the sun round.
 * Usage: sample-04_hdr_sky BAKE --sky SKY.exr [--frames N] [--turn DEG_PER_FRAME] [--scale S] [--no-grid-sky]
 *   BAKE   a bake with the sky transfer (format 1.6, glow-bake's default), e.g.
 *            glow-bake builtin:pillar-court -o court.glow --quality low
 *   SKY    a W x W/2 lat-long RGB EXR, radiance W/(m²·sr) (docs/envmap.md); make one with
 *            glow-envmap sky --out sky.exr [--width 512] [--sun-elevation 35] [--sun-azimuth 30]
 *   --frames N (default 8), --turn degrees about +Y per frame (default 45; +Z turns towards +X),
 *   --scale S multiplies the map's radiance (default 1), --no-grid-sky leaves glow_system_set_sky out
 *   (dynamic objects then get the sky's bounce but not the sky itself: compare the probe's numbers).
 * Each frame prints the sky's turn, the direction towards the sun, the mean indirect irradiance
 * (W/m², luminance) of the lightmap caches facing +X and -X, that of a probe in the middle of the bake
 * (a dynamic object's faces towards +X and -X: bounce plus the sky it sees), and the time of the sky
 * hand-over and of the update. Exit 0 ok, 1 error (the message names the file), 2 usage. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <glow/glow.h>
#include <glow/glow_host.h>
#include <openexr.h>

#include "sample_args.h" /* samples/common: the command line every sample shares */

#define PI 3.14159265358979323846

/* ---------------------------------------------------------------------------------- the sky map */
typedef struct sky_map { uint32_t width, height; float *rgb; } sky_map; /* rows top (+Y) down, RGB */

static void exr_quiet(exr_const_context_t ctx, exr_result_t code, const char *msg) {
    (void)ctx, (void)code, (void)msg; /* we say what failed ourselves, naming the file */
}

/* Decodes one chunk (scanlines or a tile) whose top-left texel is (x0, y0) into the map's R, G, B. */
static exr_result_t decode_chunk(exr_context_t ctx, const exr_chunk_info_t *ci, sky_map *m, int64_t x0, int64_t y0,
                                 unsigned *seen) {
    if (x0 < 0 || y0 < 0 || x0 + ci->width > m->width || y0 + ci->height > m->height) return EXR_ERR_CORRUPT_CHUNK;
    exr_decode_pipeline_t dec;
    memset(&dec, 0, sizeof dec);
    exr_result_t rv = exr_decoding_initialize(ctx, 0, ci, &dec);
    for (int c = 0; rv == EXR_ERR_SUCCESS && c < dec.channel_count; c++) {
        exr_coding_channel_info_t *ch = &dec.channels[c];
        const char *n = ch->channel_name ? ch->channel_name : "";
        int k = !strcmp(n, "R") ? 0 : !strcmp(n, "G") ? 1 : !strcmp(n, "B") ? 2 : -1;
        ch->decode_to_ptr = NULL; /* A and anything else: skipped */
        if (k < 0) continue;
        if (ch->width != ci->width || ch->height != ci->height) rv = EXR_ERR_CORRUPT_CHUNK; /* subsampled */
        ch->user_pixel_stride = 3 * sizeof(float);
        ch->user_line_stride = (int32_t)(3 * sizeof(float) * m->width);
        ch->user_data_type = EXR_PIXEL_FLOAT; /* half or float in the file: float here */
        ch->user_bytes_per_element = sizeof(float);
        ch->decode_to_ptr = (uint8_t *)(m->rgb + 3 * ((size_t)y0 * m->width + (size_t)x0) + k);
        *seen |= 1u << k;
    }
    if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
    if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(ctx, 0, &dec);
    exr_decoding_destroy(ctx, &dec);
    return rv;
}

/* Reads part 0 of an RGB EXR (scanlines or tiles, level 0, half or float). 0, or -1 after a message. */
static int read_sky(const char *path, sky_map *m) {
    *m = (sky_map){0};
    FILE *f = fopen(path, "rb"); /* first, for errno's words on a missing or unreadable file */
    if (!f) return fprintf(stderr, "%s: cannot open (%s)\n", path, strerror(errno)), -1;
    fclose(f);
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_quiet;
    exr_context_t ctx = NULL;
    exr_storage_t storage = EXR_STORAGE_SCANLINE;
    exr_attr_box2i_t dw;
    memset(&dw, 0, sizeof dw);
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_storage(ctx, 0, &storage);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_data_window(ctx, 0, &dw);
    if (rv != EXR_ERR_SUCCESS) {
        fprintf(stderr, "%s: not a readable OpenEXR image (%s)\n", path, exr_get_default_error_message(rv));
        return exr_finish(&ctx), -1;
    }
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w < 4 || h < 2 || w != 2 * h || w > 32768 || (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)) {
        fprintf(stderr, "%s: %lld x %lld: wants a lat-long map, width = 2 x height (4 x 2 .. 32768 x 16384), "
                        "scanlines or tiles\n", path, (long long)w, (long long)h);
        return exr_finish(&ctx), -1;
    }
    m->width = (uint32_t)w, m->height = (uint32_t)h;
    m->rgb = calloc((size_t)w * (size_t)h * 3, sizeof(float));
    if (!m->rgb) return fprintf(stderr, "%s: out of memory\n", path), exr_finish(&ctx), -1;
    unsigned seen = 0;
    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lines = 0;
        rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
        for (int64_t y = dw.min.y; rv == EXR_ERR_SUCCESS && lines > 0 && y <= dw.max.y; y += lines) {
            exr_chunk_info_t ci;
            rv = exr_read_scanline_chunk_info(ctx, 0, (int)y, &ci);
            if (rv == EXR_ERR_SUCCESS) rv = decode_chunk(ctx, &ci, m, ci.start_x - dw.min.x, ci.start_y - dw.min.y, &seen);
        }
    } else {
        int32_t tw = 0, th = 0;
        rv = exr_get_tile_sizes(ctx, 0, 0, 0, &tw, &th);
        for (int64_t y = 0, ty = 0; rv == EXR_ERR_SUCCESS && th > 0 && y < h; y += th, ty++)
            for (int64_t x = 0, tx = 0; rv == EXR_ERR_SUCCESS && tw > 0 && x < w; x += tw, tx++) {
                exr_chunk_info_t ci;
                rv = exr_read_tile_chunk_info(ctx, 0, (int)tx, (int)ty, 0, 0, &ci);
                if (rv == EXR_ERR_SUCCESS) rv = decode_chunk(ctx, &ci, m, x, y, &seen);
            }
    }
    exr_finish(&ctx);
    const char *problem = rv != EXR_ERR_SUCCESS ? exr_get_default_error_message(rv)
                          : seen != 7           ? "no R, G and B channels"
                                                : NULL;
    for (size_t i = 0, n = (size_t)w * (size_t)h * 3; !problem && i < n; i++)
        if (!(m->rgb[i] >= 0 && m->rgb[i] < 1e30f)) { /* NaN fails this too */
            fprintf(stderr, "%s: texel (%zu, %zu) channel %c is %g (wants finite, >= 0)\n", path, i / 3 % m->width,
                    i / 3 / m->width, "RGB"[i % 3], m->rgb[i]);
            problem = "";
        }
    if (!problem) return 0;
    if (*problem) fprintf(stderr, "%s: %s\n", path, problem);
    free(m->rgb);
    return -1;
}

/* Texel (i, j)'s centre direction and solid angle (docs/envmap.md): φ = 2π u, θ = π v from +Y,
 * d = (−sin θ sin φ, cos θ, sin θ cos φ): the image's centre column faces −Z, u = 0 faces +Z, u = 0.75 +X. */
static void texel_dir(const sky_map *m, uint32_t i, uint32_t j, float d[3]) {
    double phi = 2 * PI * (i + 0.5) / m->width, theta = PI * (j + 0.5) / m->height;
    d[0] = (float)(-sin(theta) * sin(phi)), d[1] = (float)cos(theta), d[2] = (float)(sin(theta) * cos(phi));
}
static double texel_solid_angle(const sky_map *m, uint32_t j) {
    return 2 * PI / m->width * (cos(PI * j / m->height) - cos(PI * (j + 1) / m->height));
}
static float luminance(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* ------------------------------------------------------------------------------- the sun split */
typedef struct sky_sun {
    int found;
    uint32_t texels;
    float to_sun[3];     /* unit, world frame of the unturned map */
    float irradiance[3]; /* W/m² on a surface facing it (before --scale) */
} sky_sun;

/* Takes the sun out of the map (docs/envmap.md, "Sun split"): the brightest texel; the mean radiance
 * L_bg of the texels between R and 2R from it (R = 5°, or two texel heights on a coarse map); the texels
 * within R more than 8 x L_bg's luminance are the sun. Each keeps min(L, L_bg) (the sky behind the sun)
 * and gives the rest to the sun's irradiance; the sun's direction is the luminance centroid. */
static void split_sun(sky_map *m, sky_sun *sun) {
    const uint32_t W = m->width, H = m->height;
    *sun = (sky_sun){0};
    size_t best = 0;
    for (size_t t = 1; t < (size_t)W * H; t++)
        if (luminance(m->rgb + 3 * t) > luminance(m->rgb + 3 * best)) best = t;
    float d0[3], d[3];
    texel_dir(m, (uint32_t)(best % W), (uint32_t)(best / W), d0);
    const double R = fmax(5.0, 2 * 180.0 / H) * PI / 180, cos_r = cos(R), cos_2r = cos(2 * R);
    double bg[3] = {0, 0, 0}, bg_omega = 0;
    for (uint32_t j = 0; j < H; j++)
        for (uint32_t i = 0; i < W; i++) {
            texel_dir(m, i, j, d);
            double c = d[0] * d0[0] + d[1] * d0[1] + d[2] * d0[2], omega = texel_solid_angle(m, j);
            if (c >= cos_r || c < cos_2r) continue;
            for (int k = 0; k < 3; k++) bg[k] += m->rgb[3 * ((size_t)j * W + i) + k] * omega;
            bg_omega += omega;
        }
    float l_bg[3];
    for (int k = 0; k < 3; k++) l_bg[k] = bg_omega > 0 ? (float)(bg[k] / bg_omega) : 0.0f;
    const float limit = 8.0f * luminance(l_bg);
    if (!(luminance(m->rgb + 3 * best) > limit)) return; /* overcast: no sun */
    double centroid[3] = {0, 0, 0}, irr[3] = {0, 0, 0};
    for (uint32_t j = 0; j < H; j++)
        for (uint32_t i = 0; i < W; i++) {
            float *L = m->rgb + 3 * ((size_t)j * W + i), excess[3];
            texel_dir(m, i, j, d);
            if (d[0] * d0[0] + d[1] * d0[1] + d[2] * d0[2] < cos_r || !(luminance(L) > limit)) continue;
            double omega = texel_solid_angle(m, j);
            for (int k = 0; k < 3; k++) {
                excess[k] = L[k] - fminf(L[k], l_bg[k]);
                irr[k] += excess[k] * omega;
                L[k] -= excess[k]; /* the residual: the sky behind the sun */
            }
            for (int k = 0; k < 3; k++) centroid[k] += luminance(excess) * omega * d[k];
            sun->texels++;
        }
    double len = sqrt(centroid[0] * centroid[0] + centroid[1] * centroid[1] + centroid[2] * centroid[2]);
    sun->found = len > 0;
    for (int k = 0; k < 3; k++) {
        sun->to_sun[k] = len > 0 ? (float)(centroid[k] / len) : 0.0f;
        sun->irradiance[k] = (float)irr[k];
    }
}

/* The map's radiance as l <= 2 SH in the runtime's basis (glow_sh_eval), coefficient-major sh[3k + c]:
 * c_k = ∫ L y_k dω, one centre sample per texel times its solid angle. */
static void project_sh(const sky_map *m, float scale, float sh[GLOW_SKY_SH_FLOATS]) {
    double acc[GLOW_SKY_SH_FLOATS] = {0};
    for (uint32_t j = 0; j < m->height; j++) {
        const double omega = texel_solid_angle(m, j);
        for (uint32_t i = 0; i < m->width; i++) {
            float d[3], y[9];
            texel_dir(m, i, j, d);
            glow_sh_eval(3, d, y);
            const float *L = m->rgb + 3 * ((size_t)j * m->width + i);
            for (int k = 0; k < 9; k++)
                for (int c = 0; c < 3; c++) acc[3 * k + c] += (double)L[c] * y[k] * omega;
        }
    }
    for (int i = 0; i < GLOW_SKY_SH_FLOATS; i++) sh[i] = (float)(acc[i] * scale);
}

/* ---------------------------------------------------------------------------------- the frames */
/* The mean indirect irradiance E = π · glow_shade_sh (W/m², luminance) of the lightmap caches in `list`. */
static float mean_lightmap_e(const glow_cache_outputs *out, const glow_cache_info *caches, const uint32_t *list,
                             uint32_t n) {
    double sum = 0;
    for (uint32_t i = 0; i < n; i++) {
        float rgb[3];
        glow_shade_sh(out->cache_sh + (size_t)list[i] * out->coeff_count, out->sh_bands_luma, out->sh_bands_chroma,
                      caches[list[i]].normal, 1.0f, rgb);
        sum += PI * luminance(rgb);
    }
    return n ? (float)(sum / n) : 0.0f;
}

static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

static void log_to_stderr(void *user, glow_log_level level, glow_result code, const char *msg, const char *file,
                          int line) {
    (void)user, (void)code, (void)file, (void)line;
    if (level <= GLOW_LOG_WARNING) fprintf(stderr, "glow: %s\n", msg);
}

static int usage(FILE *f, const char *argv0) {
    fprintf(f, "usage: %s BAKE --sky SKY.exr [--frames N] [--turn DEG_PER_FRAME] [--scale S] [--no-grid-sky]\n"
               "  a sky: glow-envmap sky --out SKY.exr [--width W] [--sun-elevation DEG] [--sun-azimuth DEG]\n",
            argv0);
    return f == stdout ? 0 : 2;
}

static int parse_float(const char *argv0, const char *opt, const char *v, float lo, float hi, float *out) {
    char *end;
    double x = v ? strtod(v, &end) : 0;
    if (!v || end == v || *end || !(x >= lo && x <= hi))
        return fprintf(stderr, "%s: %s '%s': wants a number in [%g, %g]\n", argv0, opt, v ? v : "", lo, hi), -1;
    return *out = (float)x, 0;
}

int main(int argc, char **argv) {
    sample_args args = {.frames = 8};
    const char *sky_path = NULL;
    float turn_deg = 45.0f, scale = 1.0f;
    int grid_sky = 1;
    for (int i = 1; i < argc; i++) {
        int took = sample_arg_common(argc, argv, &i, &args); /* --frames, --headless (ignored), --out */
        if (took == 2) return usage(stderr, argv[0]);
        if (took) continue;
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return usage(stdout, argv[0]);
        if (!strcmp(a, "--sky") && v) sky_path = v, i++;
        else if (!strcmp(a, "--turn")) {
            if (parse_float(argv[0], a, v, -360, 360, &turn_deg)) return usage(stderr, argv[0]);
            i++;
        } else if (!strcmp(a, "--no-grid-sky")) grid_sky = 0;
        else if (!strcmp(a, "--scale")) {
            if (parse_float(argv[0], a, v, 0, 1e6f, &scale)) return usage(stderr, argv[0]);
            i++;
        } else if (a[0] == '-' || args.input) {
            fprintf(stderr, "%s: unexpected argument '%s'%s\n", argv[0], a, !strcmp(a, "--sky") ? " (needs a value)" : "");
            return usage(stderr, argv[0]);
        } else args.input = a;
    }
    if (!args.input || !sky_path || args.out_dir) {
        fprintf(stderr, "%s: %s\n", argv[0], args.out_dir ? "--out: this sample writes no pictures"
                                              : !args.input ? "no BAKE given" : "no --sky SKY.exr given");
        return usage(stderr, argv[0]);
    }

    /* 1-2. The sky: read, split off the sun, project the rest. Once, at load: the frames only turn it. */
    sky_map map;
    if (read_sky(sky_path, &map) != 0) return 1;
    sky_sun sun;
    split_sun(&map, &sun);
    float sky_sh[GLOW_SKY_SH_FLOATS];
    project_sh(&map, scale, sky_sh);
    free(map.rgb);
    for (int k = 0; k < 3; k++) sun.irradiance[k] *= scale;
    printf("%s: %u x %u", sky_path, map.width, map.height);
    if (sun.found)
        printf(", sun in %u texels towards (%.3f %.3f %.3f), %.3f %.3f %.3f W/m2", sun.texels, sun.to_sun[0],
               sun.to_sun[1], sun.to_sun[2], sun.irradiance[0], sun.irradiance[1], sun.irradiance[2]);
    else printf(", no sun");
    const float c0 = 0.2820948f; /* y_0: the residual's mean radiance is L_0 · y_0 */
    printf(", the rest's mean radiance %.4f %.4f %.4f W/(m2 sr)\n", sky_sh[0] * c0, sky_sh[1] * c0, sky_sh[2] * c0);

    /* 3. The bake, the CPU host (exact shadow rays; lit by the sun and the SH sky, set per frame), the
     * system with the host's hook. */
    glow_context *ctx = NULL;
    glow_bake *bake = NULL;
    glow_host *host = NULL;
    glow_system *sys = NULL;
    glow_bake_info info = {0};
    glow_cache_info *caches = NULL;
    int said = 0; /* the error is explained already */
    uint32_t *facing = NULL, n_px = 0, n_nx = 0; /* lightmap caches facing +X, then those facing -X */
    const glow_logger logger = {log_to_stderr, NULL};
    glow_result r = glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION, .logger = logger}, &ctx);
    if (r == GLOW_OK) r = glow_bake_load_file(ctx, args.input, &bake);
    if (r == GLOW_OK) r = glow_bake_get_info(bake, &info);
    glow_bake_sky_transfer transfer = {0}; /* the per-surfel T and per-grid-cache V the sky needs */
    if (r == GLOW_OK && (r = glow_bake_get_sky_transfer(bake, &transfer)) == GLOW_OK && !transfer.grid_visibility) {
        fprintf(stderr, "%s: the bake has no sky transfer (SKYT; baked with --no-sky or before format 1.6): "
                        "bake it again with glow-bake\n", args.input);
        r = GLOW_ERROR_UNSUPPORTED, said = 1;
    }
    if (r == GLOW_OK)
        r = glow_host_create(&(glow_host_desc){.kind = GLOW_HOST_KIND_EXACT, .bake = bake, .logger = logger}, &host);
    if (r == GLOW_OK) r = glow_system_create(ctx, &(glow_system_desc){.bake = bake, .lighting = glow_host_hooks(host)}, &sys);
    if (r == GLOW_OK) {
        caches = malloc(((size_t)info.cache_count + 1) * sizeof *caches);
        facing = malloc(((size_t)info.cache_count + 1) * sizeof *facing);
        if (!caches || !facing) r = GLOW_ERROR_OUT_OF_MEMORY;
    }
    if (r == GLOW_OK) r = glow_bake_get_caches(bake, 0, info.cache_count, caches);
    for (uint32_t i = info.grid_cache_count; r == GLOW_OK && i < info.cache_count; i++)
        if (caches[i].normal[0] > 0.9f) facing[n_px++] = i;
    for (uint32_t i = info.grid_cache_count; r == GLOW_OK && i < info.cache_count; i++)
        if (caches[i].normal[0] < -0.9f) facing[n_px + n_nx++] = i;
    if (r != GLOW_OK && !said) fprintf(stderr, "%s: %s\n", args.input, glow_result_string(r));
    else if (r == GLOW_OK)
        printf("%s: %u surfels, %u grid caches, %u lightmap caches (%u facing +X, %u facing -X)\n", args.input,
               info.surfel_count, info.grid_cache_count, info.lightmap_cache_count, n_px, n_nx);
    /* The probe: a dynamic object at the middle of the bake, a quarter of its height up. */
    float probe[3];
    for (int a = 0; a < 3; a++) probe[a] = 0.5f * (info.bounds_min[a] + info.bounds_max[a]);
    probe[1] = info.bounds_min[1] + 0.25f * (info.bounds_max[1] - info.bounds_min[1]);

    for (long f = 0; r == GLOW_OK && f < args.frames; f++) {
        /* 4. Turn the sky by f · turn about +Y (+Z towards +X): the SH with the runtime's rotation, the
         * sun's direction with the same matrix R = [[c, 0, s], [0, 1, 0], [-s, 0, c]]. */
        const double deg = fmod((double)f * turn_deg, 360.0), a = deg * PI / 180;
        const float c = (float)cos(a), s = (float)sin(a);
        float sh[GLOW_SKY_SH_FLOATS], to_sun[3] = {c * sun.to_sun[0] + s * sun.to_sun[2], sun.to_sun[1],
                                                   -s * sun.to_sun[0] + c * sun.to_sun[2]};
        glow_sh_rotate_y(sky_sh, (float)a, sh);
        glow_scene_light light = {.type = GLOW_SCENE_LIGHT_SUN, .direction = {-to_sun[0], -to_sun[1], -to_sun[2]},
                                  .irradiance = {sun.irradiance[0], sun.irradiance[1], sun.irradiance[2]}};
        /* Hand the turned sky over between updates: the host's SH sky (each surfel's max(0, Σ T L), once
         * per change), its sun, and the visible sky of the grid caches (for dynamic objects). */
        const double t0 = now_ms();
        r = glow_host_set_environment_sh(host, sh);
        if (r == GLOW_OK) r = glow_host_set_lights(host, &light, sun.found ? 1 : 0);
        if (r == GLOW_OK && grid_sky) r = glow_system_set_sky(sys, sh);
        const double sky_ms = now_ms() - t0;
        if (r == GLOW_OK) r = glow_system_update(sys, NULL);
        if (r != GLOW_OK) {
            fprintf(stderr, "%s: frame %ld: %s\n", args.input, f, glow_result_string(r));
            break;
        }
        glow_update_stats stats;
        glow_system_get_stats(sys, &stats);

        /* Read the caches: the lightmap's indirect light on the walls facing +X and -X (what a shader
         * gets from lightmap_sh), and the grid at the probe shaded towards +X and -X (a dynamic object's
         * two sides: bounce plus the sky the grid caches see, glow_system_set_sky). */
        const glow_cache_outputs *out = glow_system_outputs(sys);
        float coeffs[3 * GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS], e_probe[2] = {0, 0};
        const float axes[2][3] = {{1, 0, 0}, {-1, 0, 0}};
        if (glow_sample_grid(out, probe, coeffs) == GLOW_OK) /* fails where no cache is near (inside solids) */
            for (int k = 0; k < 2; k++) {
                float rgb[3];
                glow_shade_sh(coeffs, out->sh_bands_luma, out->sh_bands_chroma, axes[k], 1.0f, rgb);
                e_probe[k] = (float)PI * luminance(rgb);
            }
        printf("frame %ld  turn %.1f  sun (%.3f %.3f %.3f)  lightmap +X %.4f -X %.4f  probe +X %.4f -X %.4f  "
               "sky %.2f ms  update %.2f ms\n",
               f, deg, to_sun[0], to_sun[1], to_sun[2], mean_lightmap_e(out, caches, facing, n_px),
               mean_lightmap_e(out, caches, facing + n_px, n_nx), e_probe[0], e_probe[1], sky_ms, stats.total_ms);
    }
    free(caches);
    free(facing);
    glow_system_destroy(sys); /* systems first, then the host whose hook they call, the bake, the context */
    glow_host_destroy(host);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    return r == GLOW_OK ? 0 : 1;
}
