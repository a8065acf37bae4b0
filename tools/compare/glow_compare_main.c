/* glow-compare — the error metrics of glow_eval.h on two image files, for scripts (glow-eval).
 *
 *   glow-compare TEST REF [--exposure E] [--add IMAGE] [--ref-add IMAGE] [--ref-sub IMAGE] [--block N] [--ppd P]
 *                [--flip-map OUT.exr] [--no-flip] [--panels OUT.png [--panel-exposure E]] [--blocks-csv OUT.csv]
 *                [--texels TEXEL.exr [--blotch-threshold T] [--blotch-min-pixels N]] [--json]
 *
 * TEST, REF and the added images may each be OpenEXR or PFM (chosen by the file's magic bytes;
 * PFM is what the independent referee, shared/referee/, writes).
 * --add adds IMAGE to TEST first (same size): glow-eval compares Glow's indirect-only view plus the
 * reference's direct image (which Glow's view reproduces to the bit) with the reference's final.
 * --ref-add adds IMAGE to REF first (same size): the referee (Cycles) files light reflected once
 * from an emitter as 'direct' where Glow files it as indirect, so for a scene lit by emissive
 * meshes (the Cornell box) Glow's indirect compares with referee direct.pfm + indirect.pfm.
 * --panels writes one PNG of three panels side by side, each W x H: TEST and REF shown as
 * glow_eval_write_png shows them (x * E clamped, sRGB; E = --panel-exposure, default --exposure),
 * then a signed error map of the N x N block means (the --block grid, partial blocks at the right
 * and bottom): per block rel = (T - R) / max(R, 1e-3 * the mean reference luma over the image),
 * T and R the block's mean test and reference luma 0.2126 R + 0.7152 G + 0.0722 B, clamped to
 * [-1, 1] (where that denominator is not positive, a reference black or negative on the whole,
 * rel = sign(T - R)); the block is filled red (test brighter) or blue (test darker) with sRGB value
 * round(255 |rel|), black where they are equal.
 * Prints relative RMSE (HDR), display RMSE, PSNR and SSIM after `--exposure` (default 1) and sRGB
 * encoding, both images' mean radiance, the block error of N x N block means (default 8) and the
 * mean ratio, and mean HDR-FLIP (exposure range from REF, --ppd pixels per degree, default 67;
 * 20-30 ms per exposure at 320 x 180, --no-flip skips it); --flip-map writes its per-pixel map
 * as a grey EXR (definitions in tools/eval/glow_eval.h and docs/results.md).
 * --texels TEXEL.exr (glow-render --glow's PREFIX_texel.exr) also finds blotches: texels of the
 * lightmap whose error is beyond ±T (default 0.5) and that touch a texel with an error of the same
 * sign (glow_eval_blotches). Exit status: 0
 * success, 1 an image cannot be read or written or the sizes differ (the message names the file),
 * 2 bad command line. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glow_cli.h"
#include "glow_eval.h"
#include "glow_tool_json.h"

static int usage(FILE *f) {
    fprintf(f, "usage: glow-compare TEST REF [--exposure E] [--add IMAGE] [--ref-add IMAGE] [--ref-sub IMAGE] [--block N] [--ppd P]\n"
               "                    [--flip-map OUT.exr] [--no-flip] [--panels OUT.png [--panel-exposure E]] [--blocks-csv OUT.csv]\n"
               "                    [--texels TEXEL.exr [--blotch-threshold T] [--blotch-min-pixels N]] [--json]\n"
               "Compares TEST with the reference REF (each OpenEXR or PFM): relative RMSE of the HDR\n"
               "values, RMSE and PSNR of the display images (x * exposure, clamped, sRGB-encoded) and their\n"
               "mean SSIM, the block error (relative RMS error of N x N block means, default 8), the mean\n"
               "ratio and the mean HDR-FLIP (exposures from REF, P pixels per degree, default 67;\n"
               "--no-flip skips it).\n"
               "--add IMAGE adds IMAGE to TEST before comparing; --ref-add IMAGE adds IMAGE to REF (e.g.\n"
               "  the referee's direct.pfm to its indirect.pfm for a scene lit by emissive meshes).\n"
               "--flip-map OUT.exr writes the per-pixel HDR-FLIP as a grey EXR.\n"
               "--ref-sub IMAGE subtracts IMAGE from REF (e.g. glow-render --near-split's PREFIX_indirect_near.exr\n"
               "  from PREFIX_indirect.exr: the light of surfaces farther than the split).\n"
               "--blocks-csv OUT.csv writes the N x N block means of TEST and REF (luma and RGB), one row a block.\n"
               "--texels TEXEL.exr (glow-render --glow's PREFIX_texel.exr: the lightmap texel of each pixel)\n"
               "  groups pixels by texel and reports blotches: touching texels whose luma error has one sign\n"
               "  and exceeds --blotch-threshold T (default 0.5) of the reference, in texels seen by at least\n"
               "  --blotch-min-pixels N pixels (default 16). A blotch is two or more such texels.\n"
               "--panels OUT.png writes TEST | REF | error side by side (3W x H): TEST and REF at exposure\n"
               "  --panel-exposure E (default: --exposure) and sRGB; the error map of the N x N blocks'\n"
               "  mean luma, (T - R) / max(R, 1e-3 mean luma of REF) clamped to [-1, 1], red where TEST\n"
               "  is brighter, blue where darker, brightness |error| (black = equal).\n");
    return f == stdout ? 0 : 2;
}


/* Reads `path` and adds it to *dst (read from dst_path), same size. 0 on success, else prints why. */
static int add_image(const char *path, glow_eval_image *dst, const char *dst_path, float sign) {
    glow_eval_image extra = {0};
    char msg[512];
    if (glow_eval_read_image(path, &extra, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-compare: %s\n", msg);
        return 1;
    }
    if (extra.width != dst->width || extra.height != dst->height) {
        fprintf(stderr, "glow-compare: %s is %ux%u but %s is %ux%u\n", path, extra.width, extra.height, dst_path,
                dst->width, dst->height);
        glow_eval_image_free(&extra);
        return 1;
    }
    for (size_t i = 0; i < (size_t)extra.width * extra.height * 3; ++i) dst->rgb[i] += sign * extra.rgb[i];
    glow_eval_image_free(&extra);
    return 0;
}

static double luma(const float *p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

/* The inverse of the sRGB curve (IEC 61966-2-1), for v in [0, 1]. */
static double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4); }

/* Writes the N x N block means (the block error's inputs) as CSV: x0, y0 (the block's first pixel),
 * pixel count, then TEST's and REF's mean luma and RGB. For looking at where an error lives (by region,
 * by brightness) without re-reading the images. Written under FILE.tmp and renamed when complete. */
static glow_result write_blocks_csv(const glow_eval_image *test, const glow_eval_image *ref, uint32_t block,
                                    const char *path, char *msg, size_t msg_size) {
    const uint32_t W = ref->width, H = ref->height;
    char tmp[4096];
    if (snprintf(tmp, sizeof tmp, "%s.tmp", path) >= (int)sizeof tmp) {
        snprintf(msg, msg_size, "%s: path too long", path);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    FILE *f = fopen(tmp, "w");
    if (!f) {
        snprintf(msg, msg_size, "%.400s: cannot write", tmp);
        return GLOW_ERROR_IO;
    }
    int ok = fprintf(f, "x0,y0,pixels,test_luma,ref_luma,test_r,test_g,test_b,ref_r,ref_g,ref_b\n") > 0;
    for (uint32_t by = 0; ok && by < H; by += block)
        for (uint32_t bx = 0; ok && bx < W; bx += block) {
            const uint32_t ey = H - by < block ? H : by + block, ex = W - bx < block ? W : bx + block;
            double t[3] = {0, 0, 0}, rf[3] = {0, 0, 0};
            for (uint32_t y = by; y < ey; y++)
                for (uint32_t x = bx; x < ex; x++) {
                    const size_t i = ((size_t)y * W + x) * 3;
                    for (int k = 0; k < 3; k++) {
                        t[k] += test->rgb[i + k];
                        rf[k] += ref->rgb[i + k];
                    }
                }
            const double n = (double)(ey - by) * (ex - bx);
            for (int k = 0; k < 3; k++) {
                t[k] /= n;
                rf[k] /= n;
            }
            ok = fprintf(f, "%u,%u,%.0f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", bx, by, n,
                         0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2], 0.2126 * rf[0] + 0.7152 * rf[1] + 0.0722 * rf[2],
                         t[0], t[1], t[2], rf[0], rf[1], rf[2]) > 0;
        }
    if (fclose(f) != 0) ok = 0;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        snprintf(msg, msg_size, "%s: cannot write", path);
        return GLOW_ERROR_IO;
    }
    return GLOW_OK;
}

/* Writes TEST | REF | block error map (see the file comment) as one PNG through glow_eval_write_png:
 * the error panel holds linear values that its display transform (x * exposure, sRGB, round(255 v))
 * turns into exactly round(255 |rel|) in the red or blue channel. test and ref: same size, finite. */
static glow_result write_panels(const glow_eval_image *test, const glow_eval_image *ref, uint32_t block,
                                float exposure, const char *path, char *msg, size_t msg_size) {
    const uint32_t W = ref->width, H = ref->height;
    if (W > UINT32_MAX / 3) {
        snprintf(msg, msg_size, "%s: image %ux%u is too wide for three panels", path, W, H);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_eval_image out = {0};
    glow_result r = glow_eval_image_alloc(&out, 3 * W, H);
    if (r != GLOW_OK) {
        snprintf(msg, msg_size, "%s: out of memory", path);
        return r;
    }
    double ref_sum = 0.0;
    for (uint32_t y = 0; y < H; y++) {
        const size_t src = (size_t)y * W * 3, dst = (size_t)y * 3 * W * 3;
        memcpy(out.rgb + dst, test->rgb + src, (size_t)W * 3 * sizeof(float));
        memcpy(out.rgb + dst + (size_t)W * 3, ref->rgb + src, (size_t)W * 3 * sizeof(float));
        for (uint32_t x = 0; x < W; x++) ref_sum += luma(ref->rgb + src + 3 * (size_t)x);
    }
    const double floor_luma = 1e-3 * ref_sum / ((double)W * H);
    for (uint32_t by = 0; by < H; by += block)
        for (uint32_t bx = 0; bx < W; bx += block) {
            const uint32_t ey = H - by < block ? H : by + block, ex = W - bx < block ? W : bx + block;
            double t = 0.0, rf = 0.0;
            for (uint32_t y = by; y < ey; y++)
                for (uint32_t x = bx; x < ex; x++) {
                    const size_t i = ((size_t)y * W + x) * 3;
                    t += luma(test->rgb + i);
                    rf += luma(ref->rgb + i);
                }
            const double n = (double)(ey - by) * (ex - bx), diff = (t - rf) / n, den = fmax(rf / n, floor_luma);
            double rel = den > 0.0 ? diff / den : (diff > 0.0 ? 1.0 : diff < 0.0 ? -1.0 : 0.0);
            rel = rel > 1.0 ? 1.0 : rel < -1.0 ? -1.0 : rel;
            const float v = (float)(srgb_decode(round(255.0 * fabs(rel)) / 255.0) / exposure);
            for (uint32_t y = by; y < ey; y++)
                for (uint32_t x = bx; x < ex; x++) {
                    float *p = out.rgb + ((size_t)y * 3 * W + 2 * (size_t)W + x) * 3;
                    p[0] = rel > 0.0 ? v : 0.0f;
                    p[1] = 0.0f;
                    p[2] = rel < 0.0 ? v : 0.0f;
                }
        }
    r = glow_eval_write_png(&out, exposure, path, msg, msg_size);
    glow_eval_image_free(&out);
    return r;
}

int main(int argc, char **argv) {
    const char *paths[2] = {NULL, NULL}, *add = NULL, *ref_add = NULL, *flip_map = NULL, *panels = NULL,
               *blocks_csv = NULL, *ref_sub = NULL, *texels = NULL;
    glow_eval_blotch_params bp = {0};
    int blotch_opts = 0;
    int np = 0, json = 0, flip = 1;
    float exposure = 1.0f, panel_exposure = 0.0f; /* 0: --exposure */
    unsigned long block = GLOW_EVAL_BLOCK_SIZE;
    double ppd = 0.0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) return usage(stdout);
        if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--add")) {
            if (i + 1 >= argc) return usage(stderr);
            add = argv[++i];
        } else if (!strcmp(a, "--ref-add")) {
            if (i + 1 >= argc) return usage(stderr);
            ref_add = argv[++i];
        } else if (!strcmp(a, "--panels")) {
            if (i + 1 >= argc) return usage(stderr);
            panels = argv[++i];
        } else if (!strcmp(a, "--ref-sub")) {
            if (i + 1 >= argc) return usage(stderr);
            ref_sub = argv[++i];
        } else if (!strcmp(a, "--texels")) {
            if (i + 1 >= argc) return usage(stderr);
            texels = argv[++i];
        } else if (!strcmp(a, "--blotch-threshold")) {
            if (i + 1 >= argc) return usage(stderr);
            if (!glow_cli_double(argv[++i], &bp.threshold) || !(bp.threshold > 0.0) || bp.threshold > 1e6) {
                fprintf(stderr, "glow-compare: --blotch-threshold needs a positive number, got '%s'\n", argv[i]);
                return 2;
            }
            blotch_opts = 1;
        } else if (!strcmp(a, "--blotch-min-pixels")) {
            if (i + 1 >= argc) return usage(stderr);
            if (!glow_cli_u32(argv[++i], 1, 1u << 30, &bp.min_pixels)) {
                fprintf(stderr, "glow-compare: --blotch-min-pixels needs a whole number >= 1, got '%s'\n", argv[i]);
                return 2;
            }
            blotch_opts = 1;
        } else if (!strcmp(a, "--blocks-csv")) {
            if (i + 1 >= argc) return usage(stderr);
            blocks_csv = argv[++i];
        } else if (!strcmp(a, "--panel-exposure")) {
            if (i + 1 >= argc) return usage(stderr);
            if (!glow_cli_float(argv[++i], &panel_exposure) || panel_exposure <= 0.0f) {
                fprintf(stderr, "glow-compare: --panel-exposure needs a positive number, got '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--no-flip")) {
            flip = 0;
        } else if (!strcmp(a, "--flip-map")) {
            if (i + 1 >= argc) return usage(stderr);
            flip_map = argv[++i];
        } else if (!strcmp(a, "--block")) {
            if (i + 1 >= argc) return usage(stderr);
            uint32_t b32 = 0;
            if (!glow_cli_u32(argv[++i], 1, 65536, &b32)) {
                fprintf(stderr, "glow-compare: --block needs a whole number in [1, 65536], got '%s'\n", argv[i]);
                return 2;
            }
            block = b32;
        } else if (!strcmp(a, "--ppd")) {
            if (i + 1 >= argc) return usage(stderr);
            if (!glow_cli_double(argv[++i], &ppd) || ppd <= 0.0 || ppd > 10000.0) {
                fprintf(stderr, "glow-compare: --ppd needs a number in (0, 10000], got '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--exposure")) {
            if (i + 1 >= argc) return usage(stderr);
            if (!glow_cli_float(argv[++i], &exposure) || exposure <= 0.0f) {
                fprintf(stderr, "glow-compare: --exposure needs a positive number, got '%s'\n", argv[i]);
                return 2;
            }
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "glow-compare: unknown option '%s'\n", a);
            return usage(stderr);
        } else if (np < 2) {
            paths[np++] = a;
        } else {
            return usage(stderr);
        }
    }
    if (np != 2) return usage(stderr);
    if (flip_map && !flip) {
        fprintf(stderr, "glow-compare: --flip-map and --no-flip exclude each other\n");
        return 2;
    }
    if (panel_exposure > 0.0f && !panels) {
        fprintf(stderr, "glow-compare: --panel-exposure needs --panels\n");
        return 2;
    }
    if (blotch_opts && !texels) {
        fprintf(stderr, "glow-compare: --blotch-threshold and --blotch-min-pixels need --texels\n");
        return 2;
    }
    if (panel_exposure <= 0.0f) panel_exposure = exposure;
    glow_eval_image img[2] = {{0}, {0}};
    char msg[512];
    for (int k = 0; k < 2; ++k)
        if (glow_eval_read_image(paths[k], &img[k], msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-compare: %s\n", msg);
            glow_eval_image_free(&img[0]);
            return 1;
        }
    if ((add && add_image(add, &img[0], paths[0], 1.0f)) || (ref_add && add_image(ref_add, &img[1], paths[1], 1.0f)) ||
        (ref_sub && add_image(ref_sub, &img[1], paths[1], -1.0f))) {
        glow_eval_image_free(&img[0]);
        glow_eval_image_free(&img[1]);
        return 1;
    }
    glow_eval_metrics m;
    glow_eval_flip_result fr = {0};
    glow_eval_image map = {0};
    glow_result r = glow_eval_compare(&img[0], &img[1], NULL, exposure, &m, msg, sizeof msg);
    if (r == GLOW_OK && block != m.block_size) {
        m.block_error = glow_eval_block_error(&img[0], &img[1], NULL, (uint32_t)block);
        m.block_size = (uint32_t)block;
    }
    if (r == GLOW_OK && panels && write_panels(&img[0], &img[1], (uint32_t)block, panel_exposure, panels, msg,
                                               sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-compare: %s\n", msg);
        glow_eval_image_free(&img[0]);
        glow_eval_image_free(&img[1]);
        return 1;
    }
    if (r == GLOW_OK && blocks_csv && write_blocks_csv(&img[0], &img[1], (uint32_t)block, blocks_csv, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "glow-compare: %s\n", msg);
        glow_eval_image_free(&img[0]);
        glow_eval_image_free(&img[1]);
        return 1;
    }
    glow_eval_blotch_result br = {0};
    if (r == GLOW_OK && texels) {
        glow_eval_image tx = {0};
        if (glow_eval_read_image(texels, &tx, msg, sizeof msg) != GLOW_OK ||
            glow_eval_blotches(&img[0], &img[1], &tx, &bp, &br, msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-compare: %s: %s\n", texels, msg);
            glow_eval_image_free(&tx);
            glow_eval_image_free(&img[0]);
            glow_eval_image_free(&img[1]);
            return 1;
        }
        glow_eval_image_free(&tx);
    }
    if (r == GLOW_OK && flip) {
        float *fm = NULL;
        if (flip_map && (r = glow_eval_image_alloc(&map, img[1].width, img[1].height)) == GLOW_OK)
            fm = malloc(sizeof(float) * img[1].width * img[1].height);
        if (r == GLOW_OK && flip_map && !fm) r = GLOW_ERROR_OUT_OF_MEMORY;
        if (r == GLOW_OK)
            r = glow_eval_flip(&img[0], &img[1], NULL, &(glow_eval_flip_params){.ppd = ppd}, fm, &fr, msg, sizeof msg);
        else
            snprintf(msg, sizeof msg, "out of memory");
        if (r == GLOW_OK && fm)
            for (size_t i = 0; i < (size_t)map.width * map.height; i++)
                map.rgb[3 * i] = map.rgb[3 * i + 1] = map.rgb[3 * i + 2] = fm[i];
        free(fm);
    }
    glow_eval_image_free(&img[0]);
    glow_eval_image_free(&img[1]);
    if (r != GLOW_OK) {
        fprintf(stderr, "glow-compare: %s vs %s: %s\n", paths[0], paths[1], msg);
        glow_eval_image_free(&map);
        return 1;
    }
    if (flip_map) {
        r = glow_eval_write_exr(&map, flip_map, msg, sizeof msg);
        glow_eval_image_free(&map);
        if (r != GLOW_OK) {
            fprintf(stderr, "glow-compare: %s\n", msg);
            return 1;
        }
    }
    if (json) {
        cJSON *o = cJSON_CreateObject();
        glow_json_num(o, "rel_rmse", m.rel_rmse);
        glow_json_num(o, "rmse_display", m.rmse_display);
        glow_json_num(o, "psnr_db", m.psnr_db);
        glow_json_num(o, "ssim", m.ssim);
        glow_json_num(o, "block_error", m.block_error);
        cJSON_AddNumberToObject(o, "block_size", m.block_size);
        glow_json_num(o, "mean_ratio", m.mean_ratio);
        if (flip) {
            glow_json_num(o, "hdr_flip", fr.mean);
            glow_json_num(o, "flip_ppd", fr.ppd);
            glow_json_num(o, "flip_start_exposure", fr.start_exposure);
            glow_json_num(o, "flip_stop_exposure", fr.stop_exposure);
            cJSON_AddNumberToObject(o, "flip_exposures", fr.num_exposures);
        }
        if (texels) {
            cJSON *b = cJSON_AddObjectToObject(o, "blotches");
            cJSON_AddNumberToObject(b, "threshold", bp.threshold > 0.0 ? bp.threshold : 0.5);
            cJSON_AddNumberToObject(b, "min_pixels", bp.min_pixels ? bp.min_pixels : 16);
            cJSON_AddNumberToObject(b, "texels", br.texels);
            cJSON_AddNumberToObject(b, "judged", br.judged);
            cJSON_AddNumberToObject(b, "bad", br.bad);
            cJSON_AddNumberToObject(b, "blotches", br.blotches);
            cJSON_AddNumberToObject(b, "judged_pixels", (double)br.judged_pixels);
            cJSON_AddNumberToObject(b, "bad_pixels", (double)br.bad_pixels);
            cJSON_AddNumberToObject(b, "blotch_pixels", (double)br.blotch_pixels);
            cJSON_AddNumberToObject(b, "largest_texels", br.largest_texels);
            cJSON_AddNumberToObject(b, "largest_pixels", (double)br.largest_pixels);
            glow_json_num(b, "largest_rel", br.largest_rel);
            cJSON *box = cJSON_AddArrayToObject(b, "largest_box");
            for (int k = 0; k < 4; k++) cJSON_AddItemToArray(box, cJSON_CreateNumber(br.largest_box[k]));
            glow_json_num(b, "worst_rel", br.worst_rel);
            cJSON *lc = cJSON_AddArrayToObject(b, "largest_caches");
            for (uint32_t k = 0; k < br.largest_cache_count; k++) cJSON_AddItemToArray(lc, cJSON_CreateNumber(br.largest_caches[k]));
        }
        glow_json_num(o, "exposure", exposure);
        cJSON_AddNumberToObject(o, "pixels", (double)m.pixels);
        glow_json_array3(o, "mean_test", m.mean_test);
        glow_json_array3(o, "mean_ref", m.mean_ref);
        if (glow_json_print(o) != 0) return 1;
    } else {
        printf("%s%s%s vs %s%s%s (exposure %g, %llu pixels)\n", paths[0], add ? " + " : "", add ? add : "", paths[1],
               ref_add ? " + " : "", ref_add ? ref_add : "", (double)exposure, (unsigned long long)m.pixels);
        printf("  relative RMSE (HDR)  %.4f\n  display RMSE         %.5f\n  PSNR                 %.2f dB\n"
               "  SSIM                 %.4f\n",
               m.rel_rmse, m.rmse_display, m.psnr_db, m.ssim);
        printf("  mean radiance        test %.5g %.5g %.5g, reference %.5g %.5g %.5g W/(m^2 sr)\n", m.mean_test[0],
               m.mean_test[1], m.mean_test[2], m.mean_ref[0], m.mean_ref[1], m.mean_ref[2]);
        char label[48];
        snprintf(label, sizeof label, "block error (%ux%u)", (unsigned)m.block_size, (unsigned)m.block_size);
        printf("  %-21s%.4f\n  mean ratio           %.4f\n", label, m.block_error, m.mean_ratio);
        if (texels) {
            const double jp = br.judged_pixels ? (double)br.judged_pixels : 1.0;
            printf("  blotches (> %.2g)     %u larger than a texel (%.1f %% of judged pixels); %u bad of %u judged "
                   "texels (%.1f %%), %u seen\n",
                   bp.threshold > 0.0 ? bp.threshold : 0.5, br.blotches, 100.0 * (double)br.blotch_pixels / jp, br.bad,
                   br.judged, 100.0 * (double)br.bad_pixels / jp, br.texels);
            if (br.largest_texels)
                printf("  largest bad set      %u texel%s, %llu pixels, error %+.2f, pixels (%u, %u)-(%u, %u); worst "
                       "texel %+.2f\n",
                       br.largest_texels, br.largest_texels == 1 ? "" : "s", (unsigned long long)br.largest_pixels,
                       br.largest_rel, br.largest_box[0], br.largest_box[1], br.largest_box[2], br.largest_box[3],
                       br.worst_rel);
            if (br.largest_cache_count) {
                printf("  its caches           ");
                for (uint32_t k = 0; k < br.largest_cache_count; k++)
                    printf("%s%u", k ? "," : "", br.largest_caches[k]);
                printf(" (glow-stability audit BAKE SCENE --caches ...)\n");
            }
        }
        if (flip)
            printf("  HDR-FLIP (mean)      %.4f (%d exposures %.2f .. %.2f, %.1f pixels/degree)\n", fr.mean,
                   fr.num_exposures, fr.start_exposure, fr.stop_exposure, fr.ppd);
    }
    return 0;
}
