/* glow-compare — the error metrics of glow_eval.h on two image files, for scripts (glow-eval).
 *
 *   glow-compare TEST.exr REF.exr [--exposure E] [--add IMAGE.exr] [--block N] [--ppd P]
 *                [--flip-map OUT.exr] [--no-flip] [--json]
 *
 * --add adds IMAGE to TEST first (same size): glow-eval compares Glow's indirect-only view plus the
 * reference's direct image (which Glow's view reproduces to the bit) with the reference's final.
 * Prints relative RMSE (HDR), display RMSE, PSNR and SSIM after `--exposure` (default 1) and sRGB
 * encoding, both images' mean radiance, the block error of N x N block means (default 8) and the
 * mean ratio, and mean HDR-FLIP (exposure range from REF, --ppd pixels per degree, default 67;
 * 20-30 ms per exposure at 320 x 180, --no-flip skips it); --flip-map writes its per-pixel map
 * as a grey EXR (definitions in tools/eval/glow_eval.h and docs/results.md). Exit status: 0
 * success, 1 an image cannot be read or written or the sizes differ (the message names the file),
 * 2 bad command line. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glow_eval.h"

static int usage(FILE *f) {
    fprintf(f, "usage: glow-compare TEST.exr REF.exr [--exposure E] [--add IMAGE.exr] [--block N] [--ppd P]\n"
               "                    [--flip-map OUT.exr] [--no-flip] [--json]\n"
               "Compares TEST with the reference REF: relative RMSE of the HDR values, RMSE and PSNR of\n"
               "the display images (x * exposure, clamped, sRGB-encoded) and their mean SSIM, the block\n"
               "error (relative RMS error of N x N block means, default 8), the mean ratio and the mean\n"
               "HDR-FLIP (exposures from REF, P pixels per degree, default 67; --no-flip skips it).\n"
               "--add IMAGE.exr adds IMAGE to TEST before comparing.\n"
               "--flip-map OUT.exr writes the per-pixel HDR-FLIP as a grey EXR.\n");
    return f == stdout ? 0 : 2;
}

static void print_num(const char *key, double v, const char *sep) {
    if (isfinite(v)) printf("\"%s\": %.9g%s", key, v, sep);
    else printf("\"%s\": %s%s", key, isnan(v) ? "null" : (v > 0 ? "1e999" : "-1e999"), sep);
}

int main(int argc, char **argv) {
    const char *paths[2] = {NULL, NULL}, *add = NULL, *flip_map = NULL;
    int np = 0, json = 0, flip = 1;
    float exposure = 1.0f;
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
        } else if (!strcmp(a, "--no-flip")) {
            flip = 0;
        } else if (!strcmp(a, "--flip-map")) {
            if (i + 1 >= argc) return usage(stderr);
            flip_map = argv[++i];
        } else if (!strcmp(a, "--block")) {
            char *end = NULL;
            if (i + 1 >= argc) return usage(stderr);
            block = strtoul(argv[++i], &end, 10);
            if (!end || *end || argv[i][0] == '-' || block == 0 || block > 65536) {
                fprintf(stderr, "glow-compare: --block needs a whole number in [1, 65536], got '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--ppd")) {
            char *end = NULL;
            if (i + 1 >= argc) return usage(stderr);
            ppd = strtod(argv[++i], &end);
            if (!end || *end || !isfinite(ppd) || ppd <= 0.0 || ppd > 10000.0) {
                fprintf(stderr, "glow-compare: --ppd needs a number in (0, 10000], got '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--exposure")) {
            char *end = NULL;
            if (i + 1 >= argc) return usage(stderr);
            exposure = strtof(argv[++i], &end);
            if (!end || *end || !isfinite(exposure) || exposure <= 0.0f) {
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
    glow_eval_image img[2] = {{0}, {0}};
    char msg[512];
    for (int k = 0; k < 2; ++k)
        if (glow_eval_read_exr(paths[k], &img[k], msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-compare: %s\n", msg);
            glow_eval_image_free(&img[0]);
            return 1;
        }
    if (add) {
        glow_eval_image extra = {0};
        if (glow_eval_read_exr(add, &extra, msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, "glow-compare: %s\n", msg);
            glow_eval_image_free(&img[0]);
            glow_eval_image_free(&img[1]);
            return 1;
        }
        if (extra.width != img[0].width || extra.height != img[0].height) {
            fprintf(stderr, "glow-compare: %s is %ux%u but %s is %ux%u\n", add, extra.width, extra.height, paths[0],
                    img[0].width, img[0].height);
            glow_eval_image_free(&extra);
            glow_eval_image_free(&img[0]);
            glow_eval_image_free(&img[1]);
            return 1;
        }
        for (size_t i = 0; i < (size_t)extra.width * extra.height * 3; ++i) img[0].rgb[i] += extra.rgb[i];
        glow_eval_image_free(&extra);
    }
    glow_eval_metrics m;
    glow_eval_flip_result fr = {0};
    glow_eval_image map = {0};
    glow_result r = glow_eval_compare(&img[0], &img[1], NULL, exposure, &m, msg, sizeof msg);
    if (r == GLOW_OK && block != m.block_size) {
        m.block_error = glow_eval_block_error(&img[0], &img[1], NULL, (uint32_t)block);
        m.block_size = (uint32_t)block;
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
        printf("{");
        print_num("rel_rmse", m.rel_rmse, ", ");
        print_num("rmse_display", m.rmse_display, ", ");
        print_num("psnr_db", m.psnr_db, ", ");
        print_num("ssim", m.ssim, ", ");
        print_num("block_error", m.block_error, ", ");
        printf("\"block_size\": %u, ", (unsigned)m.block_size);
        print_num("mean_ratio", m.mean_ratio, ", ");
        if (flip) {
            print_num("hdr_flip", fr.mean, ", ");
            printf("\"flip_ppd\": %.9g, \"flip_start_exposure\": %.9g, \"flip_stop_exposure\": %.9g, "
                   "\"flip_exposures\": %d, ",
                   fr.ppd, fr.start_exposure, fr.stop_exposure, fr.num_exposures);
        }
        printf("\"exposure\": %.9g, \"pixels\": %llu, ", (double)exposure, (unsigned long long)m.pixels);
        printf("\"mean_test\": [%.9g, %.9g, %.9g], \"mean_ref\": [%.9g, %.9g, %.9g]}\n", m.mean_test[0], m.mean_test[1],
               m.mean_test[2], m.mean_ref[0], m.mean_ref[1], m.mean_ref[2]);
    } else {
        printf("%s vs %s (exposure %g, %llu pixels)\n", paths[0], paths[1], (double)exposure,
               (unsigned long long)m.pixels);
        printf("  relative RMSE (HDR)  %.4f\n  display RMSE         %.5f\n  PSNR                 %.2f dB\n"
               "  SSIM                 %.4f\n",
               m.rel_rmse, m.rmse_display, m.psnr_db, m.ssim);
        printf("  mean radiance        test %.5g %.5g %.5g, reference %.5g %.5g %.5g W/(m^2 sr)\n", m.mean_test[0],
               m.mean_test[1], m.mean_test[2], m.mean_ref[0], m.mean_ref[1], m.mean_ref[2]);
        char label[48];
        snprintf(label, sizeof label, "block error (%ux%u)", (unsigned)m.block_size, (unsigned)m.block_size);
        printf("  %-21s%.4f\n  mean ratio           %.4f\n", label, m.block_error, m.mean_ratio);
        if (flip)
            printf("  HDR-FLIP (mean)      %.4f (%d exposures %.2f .. %.2f, %.1f pixels/degree)\n", fr.mean,
                   fr.num_exposures, fr.start_exposure, fr.stop_exposure, fr.ppd);
    }
    return 0;
}
