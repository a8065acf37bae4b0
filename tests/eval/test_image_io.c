/* test_image_io.c — glow_eval's EXR, PFM and PNG files: bit-exact float round trip (noisy, incompressible
 * and smooth content, heights that end in a partial 16-line ZIP chunk, and chunks whose deflate
 * stream is exactly as long as the raw chunk: OpenEXR 3.1 kept those, readers took them for raw
 * floats), reading layouts written here directly with OpenEXR's C core (half, RGBA, Y-only, tiled,
 * offset data window), error paths (missing, garbage, truncated, unwritable) and the PATH.tmp +
 * rename discipline; PFM reading (both byte orders, RGB and grey, orientation, bad headers, huge
 * sizes, zero scale, truncation) and glow_eval_read_image's choice between the two formats. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <OpenEXR/openexr.h>
#include <stb/stb_image.h>

#include "glow_eval.h"

static char g_path[256];

static const char *tmp_name(const char *stem) {
    snprintf(g_path, sizeof g_path, "/tmp/glow_test_image_io_%ld_%s", (long)getpid(), stem);
    return g_path;
}

static int file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static long file_size(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static void assert_no_tmp(const char *path) {
    char tmp[300];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_false(file_exists(tmp));
}

static unsigned char *slurp(const char *path, long *size) {
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    *size = file_size(path);
    assert_true(*size > 0);
    unsigned char *buf = malloc((size_t)*size);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)*size, f), (size_t)*size);
    fclose(f);
    return buf;
}

static void spit(const char *path, const void *data, size_t size) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    if (size) assert_int_equal(fwrite(data, 1, size, f), size);
    fclose(f);
}

static uint32_t lcg_state;
static uint32_t lcg(void) {
    lcg_state = lcg_state * 1664525u + 1013904223u;
    return lcg_state;
}

/* ---- a small independent EXR writer (OpenEXR core, straight calls) for reader tests ---- */

typedef struct custom_exr {
    int w, h, x0, y0;          /* data window size and origin */
    int nch;                   /* channels, names sorted as EXR stores them */
    const char *names[4];
    exr_pixel_type_t types[4];
    int tile;                  /* 0 = scanlines, else square tile size */
    const float *planes[4];    /* w*h floats per channel, top row first */
} custom_exr;

static void quiet_handler(exr_const_context_t c, exr_result_t code, const char *msg) {
    (void)c;
    (void)code;
    (void)msg;
}

static void encode_block(exr_context_t ctx, const custom_exr *d, exr_chunk_info_t *cinfo, int px, int py) {
    exr_encode_pipeline_t enc;
    memset(&enc, 0, sizeof enc);
    assert_int_equal(exr_encoding_initialize(ctx, 0, cinfo, &enc), EXR_ERR_SUCCESS);
    assert_int_equal(enc.channel_count, d->nch);
    for (int c = 0; c < d->nch; c++) {
        assert_string_equal(enc.channels[c].channel_name, d->names[c]);
        enc.channels[c].user_pixel_stride = 4;
        enc.channels[c].user_line_stride = 4 * d->w;
        enc.channels[c].user_data_type = EXR_PIXEL_FLOAT;
        enc.channels[c].user_bytes_per_element = 4;
        enc.channels[c].encode_from_ptr = (const uint8_t *)(d->planes[c] + (size_t)py * d->w + px);
    }
    assert_int_equal(exr_encoding_choose_default_routines(ctx, 0, &enc), EXR_ERR_SUCCESS);
    assert_int_equal(exr_encoding_run(ctx, 0, &enc), EXR_ERR_SUCCESS);
    exr_encoding_destroy(ctx, &enc);
}

static void write_custom_exr(const char *path, const custom_exr *d) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet_handler;
    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init), EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_part(ctx, NULL, d->tile ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE, NULL),
                     EXR_ERR_SUCCESS);
    exr_attr_box2i_t dw;
    dw.min.x = d->x0;
    dw.min.y = d->y0;
    dw.max.x = d->x0 + d->w - 1;
    dw.max.y = d->y0 + d->h - 1;
    exr_attr_v2f_t swc;
    swc.x = swc.y = 0.0f;
    assert_int_equal(exr_initialize_required_attr(ctx, 0, &dw, &dw, 1.0f, &swc, 1.0f, EXR_LINEORDER_INCREASING_Y,
                                                  EXR_COMPRESSION_ZIP),
                     EXR_ERR_SUCCESS);
    if (d->tile)
        assert_int_equal(exr_set_tile_descriptor(ctx, 0, (uint32_t)d->tile, (uint32_t)d->tile, EXR_TILE_ONE_LEVEL,
                                                 EXR_TILE_ROUND_DOWN),
                         EXR_ERR_SUCCESS);
    for (int c = 0; c < d->nch; c++)
        assert_int_equal(exr_add_channel(ctx, 0, d->names[c], d->types[c], EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
                         EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctx), EXR_ERR_SUCCESS);
    exr_chunk_info_t cinfo;
    if (d->tile) {
        for (int ty = 0; ty * d->tile < d->h; ty++)
            for (int tx = 0; tx * d->tile < d->w; tx++) {
                assert_int_equal(exr_write_tile_chunk_info(ctx, 0, tx, ty, 0, 0, &cinfo), EXR_ERR_SUCCESS);
                encode_block(ctx, d, &cinfo, tx * d->tile, ty * d->tile);
            }
    } else {
        int32_t lines = 0;
        assert_int_equal(exr_get_scanlines_per_chunk(ctx, 0, &lines), EXR_ERR_SUCCESS);
        for (int y = 0; y < d->h; y += lines) {
            assert_int_equal(exr_write_scanline_chunk_info(ctx, 0, d->y0 + y, &cinfo), EXR_ERR_SUCCESS);
            encode_block(ctx, d, &cinfo, 0, y);
        }
    }
    assert_int_equal(exr_finish(&ctx), EXR_ERR_SUCCESS);
}

/* Values exactly representable in half: k / 8 for k in [-64, 64). */
static float half_exact(void) { return (float)((int)(lcg() >> 25) - 64) / 8.0f; }

/* ---- EXR ---- */

static void test_exr_roundtrip_bit_exact(void **state) {
    (void)state;
    const char *path = tmp_name("rt.exr");
    char keep[256];
    snprintf(keep, sizeof keep, "%s", path);
    glow_eval_image img, back;
    assert_int_equal(glow_eval_image_alloc(&img, 37, 23), GLOW_OK); /* 23 rows: a partial 16-line ZIP chunk */
    lcg_state = 42;
    for (size_t i = 0; i < (size_t)37 * 23 * 3; i++) {
        uint32_t bits = lcg();
        bits = (bits & 0x807fffffu) | ((uint32_t)(1 + (lcg() % 253)) << 23); /* any finite normal float */
        memcpy(&img.rgb[i], &bits, 4);
    }
    img.rgb[0] = -0.0f;
    img.rgb[1] = 1e-40f; /* denormal */
    img.rgb[2] = 3.4e38f;
    img.rgb[3] = 0.0f;
    char msg[512] = "";
    assert_int_equal(glow_eval_write_exr(&img, keep, msg, sizeof msg), GLOW_OK);
    assert_no_tmp(keep);
    assert_int_equal(glow_eval_read_exr(keep, &back, msg, sizeof msg), GLOW_OK);
    assert_int_equal(back.width, 37);
    assert_int_equal(back.height, 23);
    assert_memory_equal(back.rgb, img.rgb, sizeof(float) * 37 * 23 * 3);
    glow_eval_image_free(&back);

    /* Overwriting an existing file with a different image works. */
    glow_eval_image small;
    assert_int_equal(glow_eval_image_alloc(&small, 2, 1), GLOW_OK);
    for (int i = 0; i < 6; i++) small.rgb[i] = (float)i * 0.5f;
    assert_int_equal(glow_eval_write_exr(&small, keep, msg, sizeof msg), GLOW_OK);
    assert_int_equal(glow_eval_read_exr(keep, &back, msg, sizeof msg), GLOW_OK);
    assert_int_equal(back.width, 2);
    assert_int_equal(back.height, 1);
    assert_memory_equal(back.rgb, small.rgb, sizeof(float) * 6);
    glow_eval_image_free(&back);
    glow_eval_image_free(&small);
    assert_no_tmp(keep);

    /* A 1x1 image. */
    assert_int_equal(glow_eval_image_alloc(&small, 1, 1), GLOW_OK);
    small.rgb[0] = 1.5f, small.rgb[1] = -2.0f, small.rgb[2] = 1e6f;
    assert_int_equal(glow_eval_write_exr(&small, keep, msg, sizeof msg), GLOW_OK);
    assert_int_equal(glow_eval_read_exr(keep, &back, msg, sizeof msg), GLOW_OK);
    assert_memory_equal(back.rgb, small.rgb, sizeof(float) * 3);
    glow_eval_image_free(&back);
    glow_eval_image_free(&small);
    remove(keep);
    glow_eval_image_free(&img);
}

/* ---- ZIP chunks: noisy, incompressible and smooth content, partial last chunks ---- */

static uint64_t xs_state;
static uint32_t xs32(void) { /* xorshift64*: every bit random (an LCG's low bits are not) */
    xs_state ^= xs_state >> 12;
    xs_state ^= xs_state << 25;
    xs_state ^= xs_state >> 27;
    return (uint32_t)((xs_state * 0x2545F4914F6CDD1Dull) >> 32);
}

enum { FILL_SMOOTH, FILL_NOISE, FILL_BITS, FILL_RENDER };

/* n floats: a smooth ramp (compresses well), uniform noise in [0, 1) (barely compresses), random
 * finite bit patterns of any sign and exponent (does not compress: stored raw), or a path tracer's
 * indirect image (a smooth mean times heavy-tailed noise, many exact zeros). */
static void fill(float *dst, size_t n, int kind) {
    for (size_t i = 0; i < n; i++) {
        uint32_t u = xs32();
        switch (kind) {
            case FILL_SMOOTH: dst[i] = 0.25f + 1e-4f * (float)(i % 997) + 1e-7f * (float)i; break;
            case FILL_NOISE: dst[i] = (float)(u >> 8) * 0x1p-24f; break;
            case FILL_BITS:
                u &= 0xbfffffffu; /* exponent below 128: finite */
                memcpy(&dst[i], &u, 4);
                break;
            default: {
                float x = (float)(u >> 8) * 0x1p-24f;
                dst[i] = x < 0.3f ? 0.0f : 0.05f * (1.0f + 0.5f * sinf((float)i * 1e-3f)) / (1.0001f - x);
            }
        }
    }
}

static void roundtrip_exact(const glow_eval_image *img, const char *path) {
    char msg[512] = "";
    glow_eval_image back;
    assert_int_equal(glow_eval_write_exr(img, path, msg, sizeof msg), GLOW_OK);
    assert_int_equal(glow_eval_read_exr(path, &back, msg, sizeof msg), GLOW_OK);
    assert_int_equal(back.width, img->width);
    assert_int_equal(back.height, img->height);
    size_t n = (size_t)img->width * img->height * 3, bad = 0, first = 0;
    for (size_t i = 0; i < n; i++)
        if (memcmp(&back.rgb[i], &img->rgb[i], 4) != 0 && bad++ == 0) first = i;
    if (bad)
        fail_msg("%ux%u: %zu of %zu floats differ after the round trip, the first at row %zu (%g read, %g written)",
                 img->width, img->height, bad, n, first / 3 / img->width, (double)back.rgb[first],
                 (double)img->rgb[first]);
    glow_eval_image_free(&back);
}

static void test_exr_roundtrip_chunks(void **state) {
    (void)state;
    static const uint32_t sizes[][2] = {{320, 180}, {320, 17}, {320, 33}, {64, 64}, {320, 16}, {1, 17}, {3, 1}};
    char path[256];
    snprintf(path, sizeof path, "%s", tmp_name("chunks.exr"));
    xs_state = 0x9E3779B97F4A7C15ull;
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (int kind = FILL_SMOOTH; kind <= FILL_RENDER; kind++) {
            glow_eval_image img;
            assert_int_equal(glow_eval_image_alloc(&img, sizes[s][0], sizes[s][1]), GLOW_OK);
            fill(img.rgb, (size_t)img.width * img.height * 3, kind);
            roundtrip_exact(&img, path);
            /* smooth rows with one noisy chunk in the middle, and the other way round */
            if (img.height > 16) {
                const uint32_t lines = img.height - 16 < 16 ? img.height - 16 : 16;
                fill(img.rgb + (size_t)16 * img.width * 3, (size_t)img.width * 3 * lines,
                     kind == FILL_SMOOTH ? FILL_BITS : FILL_SMOOTH);
                roundtrip_exact(&img, path);
            }
            glow_eval_image_free(&img);
        }
    assert_no_tmp(path);
    remove(path);
}

/* ---- chunks whose deflate stream is exactly as long as the raw chunk ----
 * OpenEXR 3.1's ZIP encoder stores a chunk raw only when its deflate stream is longer than the raw
 * chunk; a stream of exactly the raw size was written as it is, and every reader takes a chunk of raw
 * size for raw floats (NaN and ±3e38 in glow-render's indirect images). probe_chunk() runs the
 * library's own encoder on one chunk's rows, with glow_eval's settings (float R, G, B, ZIP level 4)
 * and a write step that writes nothing, and says what the library would have stored. */

enum { PROBE_SMALLER, PROBE_RAW, PROBE_RAW_SIZE_STREAM };

static exr_result_t probe_write(exr_encode_pipeline_t *enc) {
    int *verdict = enc->encoding_user_data;
    if (enc->compressed_bytes < enc->packed_bytes) *verdict = PROBE_SMALLER;
    else if (enc->compressed_buffer == enc->packed_buffer ||
             memcmp(enc->compressed_buffer, enc->packed_buffer, (size_t)enc->packed_bytes) == 0)
        *verdict = PROBE_RAW;
    else *verdict = PROBE_RAW_SIZE_STREAM;
    return EXR_ERR_SUCCESS;
}

/* rows: w x lines interleaved RGB floats (lines <= 16), probed as an image of their own: its one chunk
 * packs the same bytes, so compresses the same, as those rows do inside a larger image. */
static int probe_chunk(const char *path, const float *rows, int w, int lines) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet_handler;
    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init), EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, NULL), EXR_ERR_SUCCESS);
    assert_int_equal(exr_initialize_required_attr_simple(ctx, 0, w, lines, EXR_COMPRESSION_ZIP), EXR_ERR_SUCCESS);
    static const char *const names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; c++)
        assert_int_equal(exr_add_channel(ctx, 0, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
                         EXR_ERR_SUCCESS);
    assert_int_equal(exr_set_zip_compression_level(ctx, 0, 4), EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctx), EXR_ERR_SUCCESS);
    exr_chunk_info_t cinfo;
    assert_int_equal(exr_write_scanline_chunk_info(ctx, 0, 0, &cinfo), EXR_ERR_SUCCESS);
    exr_encode_pipeline_t enc;
    memset(&enc, 0, sizeof enc);
    assert_int_equal(exr_encoding_initialize(ctx, 0, &cinfo, &enc), EXR_ERR_SUCCESS);
    for (int c = 0; c < enc.channel_count; c++) {
        exr_coding_channel_info_t *ch = &enc.channels[c];
        int k = ch->channel_name[0] == 'R' ? 0 : ch->channel_name[0] == 'G' ? 1 : 2;
        ch->user_pixel_stride = 12;
        ch->user_line_stride = 12 * w;
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = 4;
        ch->encode_from_ptr = (const uint8_t *)(rows + k);
    }
    assert_int_equal(exr_encoding_choose_default_routines(ctx, 0, &enc), EXR_ERR_SUCCESS);
    int verdict = -1;
    enc.encoding_user_data = &verdict;
    enc.write_fn = probe_write;
    assert_int_equal(exr_encoding_run(ctx, 0, &enc), EXR_ERR_SUCCESS);
    exr_encoding_destroy(ctx, &enc);
    exr_finish(&ctx); /* no chunk written: the file is incomplete, and removed */
    remove(path);
    assert_int_not_equal(verdict, -1);
    return verdict;
}

/* Rows [y0, y0 + lines) of img: noise whose deflate stream the library makes exactly as long as the
 * raw chunk. Mantissa noise (20 random bits: compresses a little) with a fraction p of random bit
 * patterns (incompressible); p walks up while the stream is shorter than the chunk, down while the
 * library stores it raw. Returns whether the case was reached (1 to 3 % of the tries near the edge). */
static int fill_raw_size_stream(glow_eval_image *img, uint32_t y0, int lines, const char *probe_path) {
    float *rows = img->rgb + (size_t)y0 * img->width * 3;
    const size_t n = (size_t)img->width * 3 * (size_t)lines;
    double p = 0.8;
    for (int tries = 0; tries < 4000; tries++) {
        for (size_t i = 0; i < n; i++) {
            uint32_t u = 0x3f800000u | (xs32() & 0xffu);
            if ((double)(xs32() >> 8) * 0x1p-24 < p) u = xs32() & 0xbfffffffu;
            memcpy(&rows[i], &u, 4);
        }
        int v = probe_chunk(probe_path, rows, (int)img->width, lines);
        if (v == PROBE_RAW_SIZE_STREAM) return 1;
        p += v == PROBE_SMALLER ? 0.004 : -0.004;
        if (p < 0.0) p = 0.0;
        if (p > 1.0) p = 1.0;
    }
    return 0;
}

/* The chunk of img that holds row y, as written: 1 when stored at its raw size. */
static int chunk_stored_raw(const char *path, int y) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet_handler;
    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    exr_chunk_info_t cinfo;
    assert_int_equal(exr_read_scanline_chunk_info(ctx, 0, y, &cinfo), EXR_ERR_SUCCESS);
    exr_finish(&ctx);
    return cinfo.packed_size == cinfo.unpacked_size;
}

static void test_exr_raw_size_deflate_stream(void **state) {
    (void)state;
    int maj = 0, min = 0, patch = 0;
    exr_get_library_version(&maj, &min, &patch, NULL);
    /* the last, partial chunk of 320 x 180 (rows 176-179: glow-render's held-out scenes), of 320 x 17
     * and 320 x 33, and a full chunk inside 64 x 64 (rows 32-47: glow-render's Cornell box, seed 2) */
    static const uint32_t cases[][3] = {{320, 180, 176}, {320, 17, 16}, {320, 33, 32}, {64, 64, 32}};
    char path[256], probe[256];
    snprintf(path, sizeof path, "%s", tmp_name("rawsize.exr"));
    snprintf(probe, sizeof probe, "%s", tmp_name("probe.exr"));
    xs_state = 0xD1B54A32D192ED03ull;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        glow_eval_image img;
        assert_int_equal(glow_eval_image_alloc(&img, cases[c][0], cases[c][1]), GLOW_OK);
        fill(img.rgb, (size_t)img.width * img.height * 3, FILL_RENDER);
        const uint32_t y0 = cases[c][2];
        const int lines = (int)(img.height - y0 < 16 ? img.height - y0 : 16);
        int reached = fill_raw_size_stream(&img, y0, lines, probe);
        if (maj == 3 && min == 1) /* the library this was found with: the case must be exercised */
            assert_true(reached);
        else if (!reached)
            print_message("OpenEXR %d.%d.%d never kept a deflate stream of raw size for %ux%u (fixed library?)\n",
                          maj, min, patch, img.width, img.height);
        roundtrip_exact(&img, path);
        if (reached) assert_true(chunk_stored_raw(path, (int)y0)); /* stored raw, as the format requires */
        glow_eval_image_free(&img);
    }
    remove(path);
}

static void check_planes(const glow_eval_image *img, int w, int h, const float *r, const float *g, const float *b) {
    assert_int_equal(img->width, (uint32_t)w);
    assert_int_equal(img->height, (uint32_t)h);
    for (int i = 0; i < w * h; i++) {
        assert_true(img->rgb[3 * i + 0] == r[i]);
        assert_true(img->rgb[3 * i + 1] == g[i]);
        assert_true(img->rgb[3 * i + 2] == b[i]);
    }
}

static void test_exr_read_layouts(void **state) {
    (void)state;
    enum { W = 29, H = 19, N = W * H };
    float r[N], g[N], b[N], a[N];
    lcg_state = 7;
    for (int i = 0; i < N; i++) r[i] = half_exact(), g[i] = half_exact(), b[i] = half_exact(), a[i] = 0.5f;
    char path[256];
    snprintf(path, sizeof path, "%s", tmp_name("layout.exr"));
    glow_eval_image img;
    char msg[512] = "";

    /* Half RGBA scanlines, data window not at the origin: A ignored, half converted exactly. */
    custom_exr d = {W, H, 5, -3, 4, {"A", "B", "G", "R"},
                    {EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF}, 0, {a, b, g, r}};
    write_custom_exr(path, &d);
    assert_int_equal(glow_eval_read_exr(path, &img, msg, sizeof msg), GLOW_OK);
    check_planes(&img, W, H, r, g, b);
    glow_eval_image_free(&img);

    /* Mixed half / float RGB. */
    custom_exr m = {W, H, 0, 0, 3, {"B", "G", "R"}, {EXR_PIXEL_FLOAT, EXR_PIXEL_HALF, EXR_PIXEL_FLOAT}, 0, {b, g, r}};
    write_custom_exr(path, &m);
    assert_int_equal(glow_eval_read_exr(path, &img, msg, sizeof msg), GLOW_OK);
    check_planes(&img, W, H, r, g, b);
    glow_eval_image_free(&img);

    /* Y only: grey. */
    custom_exr y = {W, H, 0, 0, 1, {"Y"}, {EXR_PIXEL_FLOAT}, 0, {g}};
    write_custom_exr(path, &y);
    assert_int_equal(glow_eval_read_exr(path, &img, msg, sizeof msg), GLOW_OK);
    check_planes(&img, W, H, g, g, g);
    glow_eval_image_free(&img);

    /* Tiled (8 x 8 tiles, partial ones at the right and bottom), float and half, with an offset. */
    custom_exr t = {W, H, -2, 4, 3, {"B", "G", "R"}, {EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT}, 8, {b, g, r}};
    write_custom_exr(path, &t);
    assert_int_equal(glow_eval_read_exr(path, &img, msg, sizeof msg), GLOW_OK);
    check_planes(&img, W, H, r, g, b);
    glow_eval_image_free(&img);
    custom_exr th = {W, H, 0, 0, 4, {"A", "B", "G", "R"},
                     {EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF}, 16, {a, b, g, r}};
    write_custom_exr(path, &th);
    assert_int_equal(glow_eval_read_exr(path, &img, msg, sizeof msg), GLOW_OK);
    check_planes(&img, W, H, r, g, b);
    glow_eval_image_free(&img);

    /* No colour channels at all: refused, naming the file. */
    custom_exr z = {W, H, 0, 0, 1, {"Z"}, {EXR_PIXEL_FLOAT}, 0, {g}};
    write_custom_exr(path, &z);
    img.rgb = (float *)1; /* must be reset */
    assert_int_equal(glow_eval_read_exr(path, &img, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    assert_null(img.rgb);
    assert_non_null(strstr(msg, path));
    assert_non_null(strstr(msg, "no R, G, B"));
    remove(path);
}

static void test_exr_missing_file(void **state) {
    (void)state;
    const char *path = tmp_name("does_not_exist.exr");
    glow_eval_image img;
    char msg[512] = "";
    assert_int_equal(glow_eval_read_exr(path, &img, msg, sizeof msg), GLOW_ERROR_IO);
    assert_null(img.rgb);
    assert_non_null(strstr(msg, path));
    assert_non_null(strstr(msg, "cannot open"));
    assert_non_null(strstr(msg, "No such file"));
    assert_int_equal(glow_eval_read_exr(path, &img, NULL, 0), GLOW_ERROR_IO); /* NULL message is fine */
    assert_int_equal(glow_eval_read_exr(NULL, &img, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_read_exr(path, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
}

static void test_exr_garbage_and_truncated(void **state) {
    (void)state;
    char path[256], bad[256];
    snprintf(path, sizeof path, "%s", tmp_name("good.exr"));
    snprintf(bad, sizeof bad, "%s", tmp_name("bad.exr"));
    glow_eval_image img;
    char msg[512] = "";

    spit(bad, "this is not an image, just some text\n", 37);
    assert_int_equal(glow_eval_read_exr(bad, &img, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    assert_non_null(strstr(msg, bad));
    assert_non_null(strstr(msg, "not an OpenEXR file"));
    spit(bad, "", 0);
    assert_int_equal(glow_eval_read_exr(bad, &img, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    assert_null(img.rgb);

    /* A real file cut short at many lengths, and with bytes flipped: never a crash or leak;
     * truncation is CORRUPT_DATA. */
    assert_int_equal(glow_eval_image_alloc(&img, 40, 40), GLOW_OK);
    lcg_state = 3;
    for (size_t i = 0; i < (size_t)40 * 40 * 3; i++) img.rgb[i] = (float)(lcg() % 1000) / 100.0f;
    assert_int_equal(glow_eval_write_exr(&img, path, msg, sizeof msg), GLOW_OK);
    glow_eval_image_free(&img);
    long size = 0;
    unsigned char *data = slurp(path, &size);
    const long cuts[] = {4, 5, 8, 20, 60, 150, 300, size / 3, size / 2, size - 100, size - 1};
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
        if (cuts[k] <= 0 || cuts[k] >= size) continue;
        spit(bad, data, (size_t)cuts[k]);
        glow_result r = glow_eval_read_exr(bad, &img, msg, sizeof msg);
        if (r != GLOW_ERROR_CORRUPT_DATA) print_error("cut at %ld: %d %s\n", cuts[k], (int)r, msg);
        assert_int_equal(r, GLOW_ERROR_CORRUPT_DATA);
        assert_null(img.rgb);
        assert_non_null(strstr(msg, bad));
    }
    for (int k = 0; k < 40; k++) {
        unsigned char *copy = malloc((size_t)size);
        assert_non_null(copy);
        memcpy(copy, data, (size_t)size);
        for (int j = 0; j < 4; j++) copy[lcg() % (uint32_t)size] ^= (unsigned char)(1 + lcg() % 255);
        spit(bad, copy, (size_t)size);
        free(copy);
        glow_result r = glow_eval_read_exr(bad, &img, msg, sizeof msg);
        assert_true(r == GLOW_OK || r == GLOW_ERROR_CORRUPT_DATA);
        if (r == GLOW_OK) {
            assert_non_null(img.rgb);
            glow_eval_image_free(&img);
        } else {
            assert_null(img.rgb);
        }
    }
    free(data);
    remove(bad);
    remove(path);
}

static void test_exr_write_errors(void **state) {
    (void)state;
    glow_eval_image img;
    assert_int_equal(glow_eval_image_alloc(&img, 3, 2), GLOW_OK);
    char dir_path[300], msg[512] = "";
    snprintf(dir_path, sizeof dir_path, "%s/out.exr", tmp_name("no_such_dir"));
    assert_int_equal(glow_eval_write_exr(&img, dir_path, msg, sizeof msg), GLOW_ERROR_IO);
    assert_non_null(strstr(msg, dir_path));
    assert_false(file_exists(dir_path));
    assert_int_equal(glow_eval_write_png(&img, 1.0f, dir_path, msg, sizeof msg), GLOW_ERROR_IO);
    assert_non_null(strstr(msg, dir_path));
    assert_int_equal(glow_eval_write_exr(NULL, "/tmp/x.exr", msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_write_exr(&img, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    glow_eval_image empty = {0, 0, NULL};
    assert_int_equal(glow_eval_write_exr(&empty, "/tmp/x.exr", msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_write_png(&empty, 1.0f, "/tmp/x.png", msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    const char *png = tmp_name("nan_exposure.png");
    assert_int_equal(glow_eval_write_png(&img, NAN, png, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_false(file_exists(png));
    glow_eval_image_free(&img);
}

/* ---- PNG ---- */

static void test_png_values(void **state) {
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "%s", tmp_name("out.png"));
    glow_eval_image img;
    assert_int_equal(glow_eval_image_alloc(&img, 4, 3), GLOW_OK);
    /* exposure 2: linear x -> display encode(2x) -> round(255 v). */
    const float in[12] = {0.0f, 0.5f, 0.1f, -1.0f, NAN, 1e9f, 0.0009f, 0.25f, 0.09f, 0.02f, 0.3f, 0.45f};
    /* Expected bytes, computed independently: encode(0.2) = 0.484529 -> 123.56 -> 124;
     * encode(0.0018) = 12.92 * 0.0018 = 0.023256 -> 5.93 -> 6; encode(0.5) = 0.735357 -> 187.52 -> 188;
     * encode(0.18) = 0.461356 -> 117.65 -> 118; encode(0.04) = 0.220769 -> 56.30 -> 56;
     * encode(0.6) = 0.797738 -> 203.42 -> 203; encode(0.9) = 0.954687 -> 243.45 -> 243. */
    const unsigned char want[12] = {0, 255, 124, 0, 0, 255, 6, 188, 118, 56, 203, 243};
    for (int p = 0; p < 12; p++)
        for (int c = 0; c < 3; c++) img.rgb[3 * p + c] = c == 1 ? in[p] : in[(p + 1) % 12];
    char msg[512] = "";
    assert_int_equal(glow_eval_write_png(&img, 2.0f, path, msg, sizeof msg), GLOW_OK);
    assert_no_tmp(path);
    int w = 0, h = 0, comp = 0;
    unsigned char *px = stbi_load(path, &w, &h, &comp, 3);
    assert_non_null(px);
    assert_int_equal(w, 4);
    assert_int_equal(h, 3);
    assert_int_equal(comp, 3);
    for (int p = 0; p < 12; p++) {
        assert_int_equal(px[3 * p + 1], want[p]);
        assert_int_equal(px[3 * p + 0], want[(p + 1) % 12]);
        assert_int_equal(px[3 * p + 2], want[(p + 1) % 12]);
    }
    stbi_image_free(px);
    remove(path);
    glow_eval_image_free(&img);
}

/* ---- PFM ---- */

/* Writes `header` then n floats in the given byte order (written byte by byte, so the test does not
 * depend on the host's order either). */
static void write_pfm_raw(const char *path, const char *header, const float *v, size_t n, int little) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(header, 1, strlen(header), f), strlen(header));
    for (size_t i = 0; i < n; i++) {
        uint32_t u;
        memcpy(&u, &v[i], 4);
        unsigned char b[4];
        for (int k = 0; k < 4; k++) b[little ? k : 3 - k] = (unsigned char)(u >> (8 * k));
        assert_int_equal(fwrite(b, 1, 4, f), 4);
    }
    fclose(f);
}

static int same_float(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; } /* NaN too */

static void test_pfm_roundtrip(void **state) {
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "%s", tmp_name("rt.pfm"));
    enum { W = 5, H = 3 };
    float file[W * H * 3]; /* file order: bottom row first */
    lcg_state = 11;
    for (int i = 0; i < W * H * 3; i++) file[i] = (float)((int)(lcg() >> 20) - 2048) / 64.0f;
    file[4] = NAN; /* kept as they are: the metrics report them */
    file[9] = INFINITY;
    file[20] = -0.0f;
    static const char *const rgb_headers[2] = {"PF\n5 3\n1.0\n", "PF\n5 3\n-1.0\n"};
    static const char *const grey_headers[2] = {"Pf 5\t3\r2.5\n", "Pf\n5 3\n-1\n"}; /* any whitespace */
    for (int grey = 0; grey < 2; grey++)
        for (int little = 0; little < 2; little++) {
            const char *header = grey ? grey_headers[little] : rgb_headers[little];
            const int ch = grey ? 1 : 3;
            write_pfm_raw(path, header, file, (size_t)W * H * ch, little);
            for (int via_image = 0; via_image < 2; via_image++) {
                glow_eval_image img;
                char msg[512] = "";
                glow_result r = via_image ? glow_eval_read_image(path, &img, msg, sizeof msg)
                                          : glow_eval_read_pfm(path, &img, msg, sizeof msg);
                if (r != GLOW_OK) print_error("%s\n", msg);
                assert_int_equal(r, GLOW_OK);
                assert_int_equal(img.width, W);
                assert_int_equal(img.height, H);
                /* The image's top row is the file's last row. */
                for (int y = 0; y < H; y++)
                    for (int x = 0; x < W; x++)
                        for (int c = 0; c < 3; c++) {
                            float want = file[((size_t)(H - 1 - y) * W + x) * ch + (grey ? 0 : c)];
                            assert_true(same_float(img.rgb[((size_t)y * W + x) * 3 + c], want));
                        }
                if (!grey) {
                    assert_true(same_float(img.rgb[0], file[(size_t)(H - 1) * W * 3])); /* top-left = last row */
                    assert_true(isnan(img.rgb[((size_t)(H - 1) * W + 1) * 3 + 1]));    /* file[4]: bottom row */
                }
                glow_eval_image_free(&img);
            }
        }
    /* Bytes after the pixels are ignored. */
    float extra[W * H * 3 + 2];
    memcpy(extra, file, sizeof file);
    extra[W * H * 3] = extra[W * H * 3 + 1] = 7.0f;
    write_pfm_raw(path, "PF\n5 3\n-1.0\n", extra, (size_t)W * H * 3 + 2, 1);
    glow_eval_image img;
    assert_int_equal(glow_eval_read_pfm(path, &img, NULL, 0), GLOW_OK);
    assert_true(same_float(img.rgb[0], file[(size_t)(H - 1) * W * 3]));
    glow_eval_image_free(&img);
    remove(path);
}

/* Expects `header` + n little-endian floats to fail to read as PFM with `code` and a message naming
 * the file and containing `text`. */
static void expect_pfm_error(const char *path, const char *header, size_t n, glow_result code, const char *text) {
    float *v = calloc(n + 1, sizeof(float));
    assert_non_null(v);
    write_pfm_raw(path, header, v, n, 1);
    free(v);
    glow_eval_image img = {7, 7, (float *)&img};
    char msg[512] = "";
    glow_result r = glow_eval_read_pfm(path, &img, msg, sizeof msg);
    if (r != code || !strstr(msg, text)) print_error("header %s: %d '%s'\n", header, (int)r, msg);
    assert_int_equal(r, code);
    assert_null(img.rgb);
    assert_int_equal(img.width, 0);
    assert_int_equal(img.height, 0);
    assert_non_null(strstr(msg, path));
    assert_non_null(strstr(msg, text));
}

static void test_pfm_bad_input(void **state) {
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "%s", tmp_name("bad.pfm"));
    /* Bad headers. */
    expect_pfm_error(path, "P6\n4 4\n255\n", 48, GLOW_ERROR_CORRUPT_DATA, "not a PFM file");
    expect_pfm_error(path, "PFM\n4 4\n-1\n", 48, GLOW_ERROR_CORRUPT_DATA, "not a PFM file");
    expect_pfm_error(path, "", 0, GLOW_ERROR_CORRUPT_DATA, "not a PFM file");
    expect_pfm_error(path, "PF\n", 0, GLOW_ERROR_CORRUPT_DATA, "bad PFM header (no width)");
    expect_pfm_error(path, "PF\n4", 0, GLOW_ERROR_CORRUPT_DATA, "bad PFM header (no height)");
    expect_pfm_error(path, "PF\n4 4\n", 0, GLOW_ERROR_CORRUPT_DATA, "bad PFM header (no scale)");
    expect_pfm_error(path, "PF\n-4 4\n-1\n", 48, GLOW_ERROR_CORRUPT_DATA, "not two positive whole numbers");
    expect_pfm_error(path, "PF\n4x 4\n-1\n", 48, GLOW_ERROR_CORRUPT_DATA, "not two positive whole numbers");
    expect_pfm_error(path, "PF\n4 0\n-1\n", 48, GLOW_ERROR_CORRUPT_DATA, "not two positive whole numbers");
    expect_pfm_error(path, "PF\n4 4\nabc\n", 48, GLOW_ERROR_CORRUPT_DATA, "scale 'abc'");
    expect_pfm_error(path, "PF\n4 4\n-1x\n", 48, GLOW_ERROR_CORRUPT_DATA, "scale '-1x'");
    expect_pfm_error(path, "PF\n4 4\n1234567890123456789012345678901234567890123456789012345678901234567890\n", 48,
                     GLOW_ERROR_CORRUPT_DATA, "overlong scale");
    /* Zero (or non-finite) scale: no byte order. */
    expect_pfm_error(path, "PF\n4 4\n0.0\n", 48, GLOW_ERROR_CORRUPT_DATA, "scale '0.0'");
    expect_pfm_error(path, "PF\n4 4\n-0\n", 48, GLOW_ERROR_CORRUPT_DATA, "scale '-0'");
    expect_pfm_error(path, "PF\n4 4\nnan\n", 48, GLOW_ERROR_CORRUPT_DATA, "scale 'nan'");
    /* Absurd sizes are refused before anything is allocated. */
    expect_pfm_error(path, "PF\n100000 100000\n-1\n", 48, GLOW_ERROR_CORRUPT_DATA, "too large");
    expect_pfm_error(path, "Pf\n8193 8192\n-1\n", 48, GLOW_ERROR_CORRUPT_DATA, "too large");
    expect_pfm_error(path, "PF\n99999999999999999999999 1\n-1\n", 48, GLOW_ERROR_CORRUPT_DATA, "too large");
    /* Truncated: no data, a short row, one float short; grey files need w*h floats. */
    expect_pfm_error(path, "PF\n4 4\n-1", 0, GLOW_ERROR_CORRUPT_DATA, "truncated PFM");
    expect_pfm_error(path, "PF\n4 4\n-1\n", 0, GLOW_ERROR_CORRUPT_DATA, "truncated PFM data (0 of 192 bytes");
    expect_pfm_error(path, "PF\n4 4\n-1\n", 7, GLOW_ERROR_CORRUPT_DATA, "truncated PFM data (28 of 192 bytes");
    expect_pfm_error(path, "PF\n4 4\n-1\n", 47, GLOW_ERROR_CORRUPT_DATA, "(188 of 192 bytes for 4x4 RGB)");
    expect_pfm_error(path, "Pf\n4 4\n-1\n", 15, GLOW_ERROR_CORRUPT_DATA, "(60 of 64 bytes for 4x4 grey)");

    /* A good file cut at every length is CORRUPT_DATA, never a crash. */
    float v[2 * 3 * 3];
    for (int i = 0; i < 18; i++) v[i] = (float)i;
    write_pfm_raw(path, "PF\n2 3\n-1.0\n", v, 18, 1);
    long size = 0;
    unsigned char *data = slurp(path, &size);
    assert_int_equal(size, 12 + 72);
    for (long cut = 0; cut < size; cut++) {
        spit(path, data, (size_t)cut);
        glow_eval_image img;
        char msg[512] = "";
        assert_int_equal(glow_eval_read_pfm(path, &img, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
        assert_null(img.rgb);
        assert_non_null(strstr(msg, path));
    }
    free(data);
    remove(path);

    /* Missing file and NULL arguments. */
    glow_eval_image img;
    char msg[512] = "";
    const char *missing = tmp_name("does_not_exist.pfm");
    assert_int_equal(glow_eval_read_pfm(missing, &img, msg, sizeof msg), GLOW_ERROR_IO);
    assert_null(img.rgb);
    assert_non_null(strstr(msg, missing));
    assert_non_null(strstr(msg, "cannot open"));
    assert_int_equal(glow_eval_read_pfm(NULL, &img, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_eval_read_pfm(missing, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    /* A folder opens but cannot be read: IO. */
    assert_int_equal(glow_eval_read_pfm("/tmp", &img, msg, sizeof msg), GLOW_ERROR_IO);
    assert_non_null(strstr(msg, "cannot read"));
}

static void test_read_image_dispatch(void **state) {
    (void)state;
    char exr[256], pfm[256], bad[256];
    snprintf(exr, sizeof exr, "%s", tmp_name("any.exr"));
    snprintf(pfm, sizeof pfm, "%s", tmp_name("any.pfm"));
    snprintf(bad, sizeof bad, "%s", tmp_name("any.bin"));
    glow_eval_image a, b;
    char msg[512] = "";
    assert_int_equal(glow_eval_image_alloc(&a, 3, 2), GLOW_OK);
    for (int i = 0; i < 18; i++) a.rgb[i] = 0.25f * (float)i;
    assert_int_equal(glow_eval_write_exr(&a, exr, msg, sizeof msg), GLOW_OK);
    /* The same image as a big-endian PFM, rows flipped. */
    float file[18];
    for (int y = 0; y < 2; y++) memcpy(file + (size_t)(1 - y) * 9, a.rgb + (size_t)y * 9, 9 * sizeof(float));
    write_pfm_raw(pfm, "PF\n3 2\n1\n", file, 18, 0);
    const char *paths[2] = {exr, pfm};
    for (int k = 0; k < 2; k++) {
        assert_int_equal(glow_eval_read_image(paths[k], &b, msg, sizeof msg), GLOW_OK);
        assert_int_equal(b.width, 3);
        assert_int_equal(b.height, 2);
        assert_memory_equal(b.rgb, a.rgb, 18 * sizeof(float));
        glow_eval_image_free(&b);
    }
    /* Anything else, an empty file, a missing file. */
    spit(bad, "P6\n3 2\n255\n", 11);
    assert_int_equal(glow_eval_read_image(bad, &b, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    assert_null(b.rgb);
    assert_non_null(strstr(msg, bad));
    assert_non_null(strstr(msg, "not an OpenEXR or PFM file"));
    spit(bad, "", 0);
    assert_int_equal(glow_eval_read_image(bad, &b, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    assert_non_null(strstr(msg, "not an OpenEXR or PFM file"));
    /* Errors of the chosen reader come through: a PF file cut short, an EXR magic with nothing after. */
    spit(bad, "PF\n3 2\n-1\n\0\0", 12);
    assert_int_equal(glow_eval_read_image(bad, &b, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    assert_non_null(strstr(msg, "truncated PFM data"));
    spit(bad, "\x76\x2f\x31\x01", 4);
    assert_int_equal(glow_eval_read_image(bad, &b, msg, sizeof msg), GLOW_ERROR_CORRUPT_DATA);
    assert_non_null(strstr(msg, "OpenEXR"));
    assert_null(b.rgb);
    remove(bad);
    assert_int_equal(glow_eval_read_image(bad, &b, msg, sizeof msg), GLOW_ERROR_IO);
    assert_non_null(strstr(msg, "cannot open"));
    assert_int_equal(glow_eval_read_image(NULL, &b, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    glow_eval_image_free(&a);
    remove(exr);
    remove(pfm);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exr_roundtrip_bit_exact), cmocka_unit_test(test_exr_read_layouts),
        cmocka_unit_test(test_exr_missing_file),        cmocka_unit_test(test_exr_garbage_and_truncated),
        cmocka_unit_test(test_exr_write_errors),        cmocka_unit_test(test_png_values),
        cmocka_unit_test(test_exr_roundtrip_chunks),    cmocka_unit_test(test_exr_raw_size_deflate_stream),
        cmocka_unit_test(test_pfm_roundtrip),           cmocka_unit_test(test_pfm_bad_input),
        cmocka_unit_test(test_read_image_dispatch),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
