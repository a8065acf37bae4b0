/*
 * glow_eval.h — the evaluation library shared by glow-render, glow-eval and their tests: linear HDR
 * images, their files (OpenEXR through OpenEXR's C core library, PNG through stb_image_write) and
 * the error metrics Glow is judged by (relative RMSE, PSNR, SSIM, block error, mean ratio, FLIP).
 * Tool code (tools/eval/, target glow_eval), not part of the runtime: it allocates with malloc and
 * does no threading of its own.
 *
 * IMAGES: glow_eval_image is linear RGB float, row-major, top row first (as image files store it),
 * 3 floats per pixel. Radiance in W/(m²·sr) when it comes from glow-render.
 *
 * METRICS (definitions also in docs/results.md):
 *   rel_rmse(test, ref)  = sqrt( Σ (t - r)² / Σ r² ) over every pixel and channel of the HDR images
 *                          (the RMS error relative to the reference's RMS; 0 = identical). Pixels with
 *                          a zero mask value are left out of both sums.
 *   display(x)           = srgb_encode( clamp(x · exposure, 0, 1) ) per channel (IEC 61966-2-1 curve),
 *                          the "fixed exposure and sRGB encoding" of the final image.
 *   rmse_display         = sqrt( mean over pixels and channels of (display(t) - display(r))² ), in [0,1].
 *   psnr                 = 20 · log10(1 / rmse_display) dB (+INFINITY when identical).
 *   ssim                 = mean SSIM (Wang et al. 2004) of the display images' luma
 *                          Y' = 0.2126 R' + 0.7152 G' + 0.0722 B' (on the encoded values), 11 x 11 Gaussian
 *                          window σ = 1.5, K1 = 0.01, K2 = 0.03, L = 1; windows are clipped at the image
 *                          border (weights renormalised), every pixel is a window centre.
 *
 *   block_error(b)       = the relative RMS error of the b x b block means (b = 8 by default): the
 *                          image is cut into blocks from the top-left corner; blocks at the right and
 *                          bottom border keep the pixels they have (partial blocks, e.g. 320 x 180 in
 *                          8 x 8 gives 40 x 23 blocks, the last row 4 pixels high). For block B with
 *                          n_B unmasked pixels and channel c, T_Bc and R_Bc are the means of the test
 *                          and reference over those pixels (blocks with n_B = 0 are skipped), and
 *                            block_error = sqrt( Σ_B n_B Σ_c (T_Bc - R_Bc)² / Σ_B n_B Σ_c R_Bc² ),
 *                          sums over blocks and the 3 channels: the RMS over blocks of the block-mean
 *                          error divided by the RMS of the reference's block means, each block weighted
 *                          by its pixel count (all weights are equal when every block is full and
 *                          unmasked; a 1 x 1 block gives rel_rmse). Per-pixel noise that averages out
 *                          within a block does not count, a bias shared by a block's pixels does:
 *                          test = ref + d everywhere gives d / (the n_B-weighted RMS of the R_Bc);
 *                          test = ref (1 + k) gives |k|.
 *   mean_ratio           = Σ test / Σ ref over every unmasked pixel and all 3 channels (the ratio of
 *                          the mean (R + G + B) / 3; 1 = the same total energy).
 *   flip                 = mean HDR-FLIP (Andersson et al. 2020/2021), see FLIP below; computed by
 *                          glow_eval_flip, not by glow_eval_compare (one LDR-FLIP per exposure, 20-30
 *                          ms each at 320 x 180 on the VM of docs/results.md: 0.26 s for 14).
 *
 *   Edge cases: sums are in double and display() is evaluated in double (x · exposure clamped, then
 *   the curve), glow_eval_srgb_encode returns that rounded to float. rel_rmse and block_error of a
 *   reference that is 0 everywhere (in the mask) are 0 when the test is too, else +INFINITY;
 *   mean_ratio of a reference summing to 0 is 1 when the test sums to 0 too, else ±INFINITY.
 *
 * FLIP (tools/eval/flip.c; constants from the papers and NVlabs/flip, cited there):
 *   LDR-FLIP of two linear-RGB images clamped to [0,1]: both go to the YCxCz opponent space; each
 *   channel is filtered with its contrast sensitivity filter (Gaussians sized from the pixels per
 *   degree, ppd; default 67.02 = a 3840-pixel, 0.7 m wide monitor seen from 0.7 m); back to linear
 *   RGB clamped to [0,1]; to Hunt-adjusted CIELAB; HyAB distance ^ 0.7, remapped to [0,1] with
 *   p_c = 0.4, p_t = 0.95 and c_max = the green-blue distance (the largest); the feature difference
 *   ΔE_f (edges and points of the achromatic channel, Gaussian derivatives of σ = 0.041 ppd pixels,
 *   ^ 0.5); per pixel FLIP = ΔE_c ^ (1 - ΔE_f), in [0,1]; 0 for identical images. Borders are
 *   clamped to the edge (as the reference implementation).
 *   HDR-FLIP: exposures c_i evenly spaced from c_start = log2(x_max / Y_max) to c_stop =
 *   log2(x_max / Y_median) of the reference's luminance Y = 0.2126 R + 0.7152 G + 0.0722 B (over the
 *   unmasked pixels, negatives as 0; median = the sorted element at index n/2), x_max = 2.1189 the
 *   ACES input that maps to 0.85; n = max(2, ceil(c_stop - c_start)) exposures (1 when c_start =
 *   c_stop); both images × 2^c_i, negatives as 0, ACES filmic tone mapping (Narkowicz's fit with the
 *   0.6 pre-exposure folded in), clamped, LDR-FLIP; the per-pixel maximum over the exposures. The
 *   reported value is the mean over the unmasked pixels (filters still read masked pixels).
 *   Choices where the reference implementation is undefined: a black reference gives c_start =
 *   c_stop = 0 (as its Python version); a reference with more than half its pixels black (median 0)
 *   uses the median of its non-zero luminances for c_stop (the reference would give +inf).
 *
 * NON-FINITE PIXELS (NaN, ±Inf) anywhere in either image — masked or not, since SSIM windows read
 * masked pixels — are an error: glow_eval_compare returns GLOW_ERROR_INVALID_ARGUMENT with e.g.
 * "compare: reference image pixel (12, 7) channel G is NaN" (the first one, test image checked
 * first); the individual metric functions return NAN. A mask that leaves no pixel is also
 * INVALID_ARGUMENT for glow_eval_compare and NAN for the individual functions. The PNG writer maps
 * NaN to 0 and +Inf to 255 (the clamp).
 *
 * ON ERRORS: functions return a glow_result and write one line naming the file and the problem into
 * `message` (may be NULL): GLOW_ERROR_INVALID_ARGUMENT (NULL, size mismatch, zero size, non-finite
 * exposure), GLOW_ERROR_IO (cannot open/read/write: a writer never leaves a half-written file under
 * the final name — it writes PATH.tmp and renames), GLOW_ERROR_CORRUPT_DATA (not an EXR, or a layout
 * the reader does not handle), GLOW_ERROR_OUT_OF_MEMORY. Examples: "out.exr: cannot open (No such
 * file or directory)", "x.exr: not an OpenEXR file", "x.exr: truncated OpenEXR header (...)".
 * OpenEXR's own diagnostics are captured into `message`, never printed.
 */
#ifndef GLOW_EVAL_H
#define GLOW_EVAL_H

#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct glow_eval_image {
    uint32_t width, height;
    float *rgb; /* width * height * 3 floats, owned (malloc) */
} glow_eval_image;

/* Allocates a zeroed width x height image. */
glow_result glow_eval_image_alloc(glow_eval_image *img, uint32_t width, uint32_t height);
/* Frees and zeroes (NULL and zeroed images are no-ops). */
void glow_eval_image_free(glow_eval_image *img);

/* Writes RGB as 32-bit float channels "R", "G", "B", ZIP-compressed scanlines (zlib level 4; data
 * window = display window = the image), bit-exact on re-read. */
glow_result glow_eval_write_exr(const glow_eval_image *img, const char *path, char *message, size_t message_size);
/* Reads an RGB (or RGBA: A ignored; Y-only: grey) scanline or tiled EXR of half or float channels.
 * Part 0 only; channels named exactly "R", "G", "B" (or "Y"), no layer prefixes; tiled files: level 0
 * of mip/rip maps; any data window origin (the image is the data window). CORRUPT_DATA for deep
 * parts, subsampled or uint colour channels, and more than 2^26 pixels. *out is zeroed on failure. */
glow_result glow_eval_read_exr(const char *path, glow_eval_image *out, char *message, size_t message_size);
/* Reads a PFM (Portable Float Map, the referee's format): "PF" (RGB) or "Pf" (grey: R = G = B), the
 * width and height, a scale whose sign gives the byte order (negative: little-endian; its magnitude
 * is ignored) and one whitespace byte, then float32 rows stored bottom row first (flipped here to top
 * row first). Non-finite values are kept (the metrics report them); bytes after the pixels are
 * ignored. IO for open/read failures; CORRUPT_DATA for a bad header (not PF/Pf, sizes that are not
 * positive whole numbers, a zero or non-numeric scale), more than 2^26 pixels and truncated data,
 * e.g. "x.pfm: truncated PFM data (100 of 1200 bytes for 10x10 RGB)". *out is zeroed on failure. */
glow_result glow_eval_read_pfm(const char *path, glow_eval_image *out, char *message, size_t message_size);
/* Reads an OpenEXR or a PFM file, chosen by its first bytes (EXR magic 76 2f 31 01, or "PF"/"Pf"):
 * glow_eval_read_exr or glow_eval_read_pfm; anything else is CORRUPT_DATA "x: not an OpenEXR or PFM
 * file". */
glow_result glow_eval_read_image(const char *path, glow_eval_image *out, char *message, size_t message_size);
/* Writes an 8-bit sRGB PNG of display(x) with the given exposure (see METRICS), round(255 · v). */
glow_result glow_eval_write_png(const glow_eval_image *img, float exposure, const char *path, char *message,
                                size_t message_size);

/* The sRGB transfer curve of a linear value clamped to [0,1]. */
float glow_eval_srgb_encode(float linear);

typedef struct glow_eval_metrics {
    double rel_rmse;     /* HDR, see METRICS */
    double rmse_display; /* after exposure + sRGB */
    double psnr_db;
    double ssim;
    double mean_ref[3];  /* mean reference radiance per channel (masked) */
    double mean_test[3]; /* mean test radiance per channel (masked) */
    uint64_t pixels;     /* pixels compared (mask != 0) */
    double block_error;  /* relative RMS error of the block_size x block_size block means */
    uint32_t block_size; /* GLOW_EVAL_BLOCK_SIZE in glow_eval_compare */
    double mean_ratio;   /* Σ test / Σ ref over the unmasked pixels and channels */
} glow_eval_metrics;

#define GLOW_EVAL_BLOCK_SIZE 8u /* block_error's default block: 8 x 8 pixels */

/* Compares `test` with `ref` (same size). mask: optional width*height bytes, 0 = leave the pixel out
 * (of every metric; SSIM windows still read masked pixels, only their centres are skipped). */
glow_result glow_eval_compare(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                              float exposure, glow_eval_metrics *out, char *message, size_t message_size);

/* The individual metrics (NAN on a size mismatch or NULL). */
double glow_eval_rel_rmse(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask);
double glow_eval_psnr(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask, float exposure);
double glow_eval_ssim(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask, float exposure);
/* block_size 0 means GLOW_EVAL_BLOCK_SIZE; a block larger than the image is one (partial) block. */
double glow_eval_block_error(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                             uint32_t block_size);
double glow_eval_mean_ratio(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask);

/* ---- Blotches: errors that span more than one lightmap texel ----
 * A lightmap cache stands for its texel; an error confined to one texel is the texel's resolution, one
 * that spans neighbouring texels is a blotch (issue 13: "no blotch larger than a texel"). `texels` is
 * glow-render's PREFIX_texel.exr (glow_render_result.texel): per pixel R = texel x + 1, G = y + 1 (0 =
 * no lightmap texel: sky, grid, back faces). Pixels are grouped by texel; a texel region with at least
 * min_pixels pixels is judged: rel = (Σ T − Σ R) / max(Σ R, n · 1e-3 · the mean reference luma over
 * the image), luma 0.2126 R + 0.7152 G + 0.0722 B, as the --panels error map. It is bad when |rel| >
 * threshold. Bad texels of the same sign whose pixels touch (4-neighbours) join one set; a set of two
 * or more texels is a blotch larger than a texel. */
typedef struct glow_eval_blotch_params {
    double threshold;    /* 0 = 0.5 (an error an artist sees as a patch: half again, or half gone) */
    uint32_t min_pixels; /* 0 = 16: texels seen by fewer pixels are too small on screen to judge */
} glow_eval_blotch_params;

typedef struct glow_eval_blotch_result {
    uint32_t texels, judged, bad;  /* texel regions seen; with min_pixels; judged and |rel| > threshold */
    uint32_t blotches;             /* sets of >= 2 bad texels: blotches larger than a texel */
    uint64_t judged_pixels, bad_pixels, blotch_pixels;
    /* the largest set by pixels (a single texel when no blotch; all 0 when nothing is bad) */
    uint32_t largest_texels;
    uint64_t largest_pixels;
    double largest_rel;            /* (Σ T − Σ R) / Σ R over its pixels' luma */
    uint32_t largest_box[4];       /* x0, y0, x1, y1 of its pixels, inclusive */
    uint32_t largest_caches[8];    /* the caches of its texels with the most pixels (the texel image's B
                                      channel - 1; glow-stability audit --caches takes them), most first */
    uint32_t largest_cache_count;  /* up to 8; texels whose B is 0 are left out */
    double worst_rel;              /* the judged texel with the largest |rel|: its rel (0 when none) */
} glow_eval_blotch_result;

/* Fills *out (see above). GLOW_ERROR_INVALID_ARGUMENT on NULL, sizes that differ or a non-finite
 * pixel (message names it); GLOW_ERROR_OUT_OF_MEMORY. params may be NULL (defaults). */
glow_result glow_eval_blotches(const glow_eval_image *test, const glow_eval_image *ref, const glow_eval_image *texels,
                               const glow_eval_blotch_params *params, glow_eval_blotch_result *out, char *message,
                               size_t message_size);

/* ---- FLIP (see FLIP above) ---- */

typedef struct glow_eval_flip_params {
    double ppd;             /* pixels per degree; 0 = glow_eval_flip_ppd(0.7, 3840, 0.7) = 67.02 */
    int ldr;                /* nonzero: LDR-FLIP of the images as linear RGB clamped to [0,1] (no exposures) */
    int fixed_exposures;    /* nonzero: use start/stop_exposure instead of deriving them from the reference */
    double start_exposure;  /* log2 of the exposure factor, start <= stop */
    double stop_exposure;
    int num_exposures;      /* 0 = max(2, ceil(stop - start)) (1 when start == stop); 1 = start only; <= 1024 */
} glow_eval_flip_params;

typedef struct glow_eval_flip_result {
    double mean;            /* mean FLIP over the unmasked pixels, in [0,1] */
    double max;             /* largest per-pixel FLIP over the unmasked pixels */
    double ppd;             /* pixels per degree used */
    double start_exposure;  /* HDR: the exposure range and count used (0, 0, 0 for LDR) */
    double stop_exposure;
    int num_exposures;
    uint64_t pixels;        /* unmasked pixels */
} glow_eval_flip_result;

/* HDR-FLIP (or LDR-FLIP with params->ldr) of `test` against `ref` (same size; params NULL =
 * defaults). out_map: optional width*height floats receiving the per-pixel FLIP (top row first).
 * Errors as glow_eval_compare (size mismatch, non-finite pixels, empty mask, bad parameters:
 * INVALID_ARGUMENT; OUT_OF_MEMORY). Single-threaded; separable filters, 21 + 19 taps at 67 ppd. */
glow_result glow_eval_flip(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask,
                           const glow_eval_flip_params *params, float *out_map, glow_eval_flip_result *out,
                           char *message, size_t message_size);
/* Mean HDR-FLIP with the default parameters, NAN on an error. */
double glow_eval_hdr_flip(const glow_eval_image *test, const glow_eval_image *ref, const uint8_t *mask);
/* Pixels per degree of a monitor resolution_x pixels and monitor_width_m wide seen from distance_m. */
double glow_eval_flip_ppd(double distance_m, double resolution_x, double monitor_width_m);
/* HDR-FLIP's tone mapper: ACES filmic fit of x >= 0 (negatives as 0), clamped to [0,1]. */
double glow_eval_flip_aces(double x);

/* FLIP's 1D filters, for tests and documentation: writes the 2r+1 weights of `kind` at `ppd` when
 * capacity >= 2r+1, and returns the radius r (-1 on bad arguments). The 2D filters are their outer
 * products: CSF_A (achromatic, Y) and CSF_RG (red-green, Cx) sum to 1; the blue-yellow filter (Cz)
 * is BY1 ⊗ BY1 + BY2 ⊗ BY2 (sums to 1); FEATURE_GAUSS sums to 1; FEATURE_EDGE (1st derivative) and
 * FEATURE_POINT (2nd derivative) have positive weights summing to 1 and negative ones to -1, the 2D
 * detectors being EDGE ⊗ GAUSS and POINT ⊗ GAUSS and their transposes. */
typedef enum glow_eval_flip_kernel_kind {
    GLOW_EVAL_FLIP_KERNEL_CSF_A = 1,
    GLOW_EVAL_FLIP_KERNEL_CSF_RG,
    GLOW_EVAL_FLIP_KERNEL_CSF_BY1,
    GLOW_EVAL_FLIP_KERNEL_CSF_BY2,
    GLOW_EVAL_FLIP_KERNEL_FEATURE_GAUSS,
    GLOW_EVAL_FLIP_KERNEL_FEATURE_EDGE,
    GLOW_EVAL_FLIP_KERNEL_FEATURE_POINT
} glow_eval_flip_kernel_kind;
int glow_eval_flip_kernel(glow_eval_flip_kernel_kind kind, double ppd, float *weights, size_t capacity);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_EVAL_H */
