/* image.c — glow_eval images and their files: OpenEXR through OpenEXR's C core library
 * (OpenEXRCore), PFM by hand (read only: the referee's renders, shared/referee/), 8-bit sRGB PNG
 * through stb_image_write (Debian's libstb carries the implementation, so no
 * STB_IMAGE_WRITE_IMPLEMENTATION here). Writers write PATH.tmp and rename
 * it over PATH, so a failure never leaves a half-written file under the final name. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <openexr.h>
#include <stb/stb_image_write.h>

#include "eval_internal.h"
#include "glow_eval.h"

/* Refuse images with more pixels than this (8192 x 8192): 768 MiB of floats. A corrupt header
 * must not make the reader allocate gigabytes. */
#define GLOW_EVAL_MAX_PIXELS ((uint64_t)1 << 26)

void glow__eval_set_message(char *message, size_t message_size, const char *fmt, ...) {
    if (!message || message_size == 0) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, message_size, fmt, ap);
    va_end(ap);
}
#define set_message glow__eval_set_message

glow_result glow_eval_image_alloc(glow_eval_image *img, uint32_t width, uint32_t height) {
    if (!img) return GLOW_ERROR_INVALID_ARGUMENT;
    img->width = img->height = 0;
    img->rgb = NULL;
    if (width == 0 || height == 0) return GLOW_ERROR_INVALID_ARGUMENT;
    uint64_t n = (uint64_t)width * height * 3;
    if (n > SIZE_MAX / sizeof(float)) return GLOW_ERROR_OUT_OF_MEMORY;
    float *p = calloc((size_t)n, sizeof(float));
    if (!p) return GLOW_ERROR_OUT_OF_MEMORY;
    img->width = width;
    img->height = height;
    img->rgb = p;
    return GLOW_OK;
}

void glow_eval_image_free(glow_eval_image *img) {
    if (!img) return;
    free(img->rgb);
    img->rgb = NULL;
    img->width = img->height = 0;
}

static glow_result check_image(const glow_eval_image *img, const char *path, char *message, size_t message_size) {
    if (!path) {
        set_message(message, message_size, "(null): no output path");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!img || !img->rgb || img->width == 0 || img->height == 0) {
        set_message(message, message_size, "%s: no image to write (NULL or zero size)", path);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (img->width > INT32_MAX / 16 || img->height > INT32_MAX / 16 ||
        (uint64_t)img->width * img->height > GLOW_EVAL_MAX_PIXELS) {
        set_message(message, message_size, "%s: image %ux%u is too large", path, (unsigned)img->width,
                    (unsigned)img->height);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    return GLOW_OK;
}

/* PATH.tmp, malloc'd; NULL when out of memory. */
static char *tmp_path_of(const char *path) {
    size_t n = strlen(path);
    char *tmp = malloc(n + 5);
    if (tmp) {
        memcpy(tmp, path, n);
        memcpy(tmp + n, ".tmp", 5);
    }
    return tmp;
}

/* Creates (truncates) PATH.tmp once with stdio so that an unwritable destination is reported with
 * errno's reason rather than a library's generic failure. */
static glow_result probe_writable(const char *path, const char *tmp, char *message, size_t message_size) {
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        set_message(message, message_size, "%s: cannot open for writing (%s)", path, strerror(errno));
        return GLOW_ERROR_IO;
    }
    fclose(f);
    return GLOW_OK;
}

static glow_result commit_tmp(const char *path, const char *tmp, char *message, size_t message_size) {
    if (rename(tmp, path) != 0) {
        int e = errno;
        remove(tmp);
        set_message(message, message_size, "%s: cannot rename %s into place (%s)", path, tmp, strerror(e));
        return GLOW_ERROR_IO;
    }
    return GLOW_OK;
}

/* ---------------------------------------------------------------------------------------------
 * OpenEXR: the library reports through an error handler that prints to stderr unless replaced.
 * Ours keeps the first message of the current call in a thread-local buffer instead. */

typedef struct exr_capture {
    char text[256];
    int has;
} exr_capture;

static _Thread_local exr_capture *tl_capture;

static void exr_capture_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
    (void)ctxt;
    if (!tl_capture || tl_capture->has) return;
    snprintf(tl_capture->text, sizeof tl_capture->text, "%s", msg ? msg : exr_get_default_error_message(code));
    tl_capture->has = 1;
}

static const char *exr_reason(const exr_capture *cap, exr_result_t rv) {
    return cap->has ? cap->text : exr_get_default_error_message(rv);
}

static exr_context_initializer_t exr_quiet_init(void) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_capture_handler;
    init.flags |= EXR_CONTEXT_FLAG_SILENT_HEADER_PARSE;
    return init;
}

/* OpenEXR's chunk-size convention: a chunk stored at exactly its unpacked size holds raw pixel data,
 * and every reader (OpenEXR's own, glow_eval_read_exr) takes it as uncompressed. OpenEXR 3.1's ZIP
 * encoder (internal_zip.c, apply_zip_impl) falls back to raw data only when the deflate stream is
 * LONGER than the packed chunk (`compbufsz > packed_bytes`; newer upstream code tests >=), so a stream of
 * exactly the packed size is written as it is and read back as raw floats: NaN, ±3e38 and garbage in
 * one whole chunk (16 rows, or the last partial chunk's rows). Data that barely compresses (the noisy
 * indirect image of a path tracer) hits that in a few percent of its chunks, the same ones every time
 * for the same pixels. This wraps the library's compress step and stores the packed (raw) chunk
 * whenever compression did not make it smaller, as the format requires. */
typedef struct exr_zip_guard {
    exr_result_t (*compress)(exr_encode_pipeline_t *enc); /* the library's compress_fn */
} exr_zip_guard;

static exr_result_t exr_compress_or_store_raw(exr_encode_pipeline_t *enc) {
    const exr_zip_guard *g = enc->encoding_user_data;
    exr_result_t rv = g->compress(enc);
    if (rv != EXR_ERR_SUCCESS) return rv;
    if (enc->compressed_bytes >= enc->packed_bytes && enc->compressed_buffer != enc->packed_buffer) {
        if (!enc->compressed_buffer || !enc->packed_buffer || enc->compressed_alloc_size < enc->packed_bytes)
            return EXR_ERR_INVALID_ARGUMENT;
        memcpy(enc->compressed_buffer, enc->packed_buffer, (size_t)enc->packed_bytes);
        enc->compressed_bytes = (size_t)enc->packed_bytes;
    }
    return EXR_ERR_SUCCESS;
}

static glow_result exr_write_body(exr_context_t ctx, const glow_eval_image *img) {
    exr_result_t rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, NULL);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctx, 0, (int32_t)img->width, (int32_t)img->height,
                                                 EXR_COMPRESSION_ZIP);
    static const char *const names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; c++)
        rv = exr_add_channel(ctx, 0, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_ERR_SUCCESS) rv = exr_set_zip_compression_level(ctx, 0, 4);
    if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
    if (rv != EXR_ERR_SUCCESS) return rv == EXR_ERR_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_IO;

    int32_t lines = 1;
    rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    if (rv != EXR_ERR_SUCCESS || lines < 1) return GLOW_ERROR_IO;
    const size_t line_bytes = (size_t)img->width * 3 * sizeof(float);
    for (int32_t y = 0; y < (int32_t)img->height; y += lines) {
        exr_chunk_info_t cinfo;
        exr_encode_pipeline_t enc;
        memset(&enc, 0, sizeof enc);
        rv = exr_write_scanline_chunk_info(ctx, 0, y, &cinfo);
        if (rv != EXR_ERR_SUCCESS) return GLOW_ERROR_IO;
        rv = exr_encoding_initialize(ctx, 0, &cinfo, &enc);
        if (rv != EXR_ERR_SUCCESS) {
            exr_encoding_destroy(ctx, &enc);
            return rv == EXR_ERR_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_IO;
        }
        const float *row = img->rgb + (size_t)y * img->width * 3;
        for (int c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int k = ch->channel_name[0] == 'R' ? 0 : ch->channel_name[0] == 'G' ? 1 : 2;
            ch->user_pixel_stride = (int32_t)(3 * sizeof(float));
            ch->user_line_stride = (int32_t)line_bytes;
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->encode_from_ptr = (const uint8_t *)(row + k);
        }
        rv = exr_encoding_choose_default_routines(ctx, 0, &enc);
        exr_zip_guard guard = {enc.compress_fn};
        if (rv == EXR_ERR_SUCCESS && enc.compress_fn) {
            enc.encoding_user_data = &guard;
            enc.compress_fn = exr_compress_or_store_raw;
        }
        if (rv == EXR_ERR_SUCCESS) rv = exr_encoding_run(ctx, 0, &enc);
        exr_encoding_destroy(ctx, &enc);
        if (rv != EXR_ERR_SUCCESS) return rv == EXR_ERR_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_IO;
    }
    return GLOW_OK;
}

glow_result glow_eval_write_exr(const glow_eval_image *img, const char *path, char *message, size_t message_size) {
    glow_result r = check_image(img, path, message, message_size);
    if (r != GLOW_OK) return r;
    char *tmp = tmp_path_of(path);
    if (!tmp) {
        set_message(message, message_size, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    r = probe_writable(path, tmp, message, message_size);
    if (r != GLOW_OK) {
        free(tmp);
        return r;
    }

    exr_capture cap = {{0}, 0};
    tl_capture = &cap;
    exr_context_initializer_t init = exr_quiet_init();
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS) {
        r = rv == EXR_ERR_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_IO;
    } else {
        r = exr_write_body(ctx, img);
        rv = exr_finish(&ctx); /* flushes the chunk offset table */
        if (r == GLOW_OK && rv != EXR_ERR_SUCCESS) r = GLOW_ERROR_IO;
    }
    if (r != GLOW_OK) {
        remove(tmp);
        if (r == GLOW_ERROR_OUT_OF_MEMORY)
            set_message(message, message_size, "%s: out of memory", path);
        else
            set_message(message, message_size, "%s: cannot write OpenEXR (%s)", path, exr_reason(&cap, rv));
    } else {
        r = commit_tmp(path, tmp, message, message_size);
    }
    tl_capture = NULL;
    free(tmp);
    return r;
}

/* Decodes the chunk `cinfo` whose top-left pixel is (x0, y0) of the output image. dst[k] is the
 * channel index feeding output channel k (-1: none). */
static exr_result_t exr_decode_chunk(exr_context_t ctx, const exr_chunk_info_t *cinfo, glow_eval_image *out,
                                     uint32_t x0, uint32_t y0, const int dst_of_channel[], int nchannels) {
    exr_decode_pipeline_t dec;
    memset(&dec, 0, sizeof dec);
    exr_result_t rv = exr_decoding_initialize(ctx, 0, cinfo, &dec);
    if (rv != EXR_ERR_SUCCESS) {
        exr_decoding_destroy(ctx, &dec);
        return rv;
    }
    if (dec.channel_count != nchannels) {
        exr_decoding_destroy(ctx, &dec);
        return EXR_ERR_CORRUPT_CHUNK;
    }
    float *base = out->rgb + ((size_t)y0 * out->width + x0) * 3;
    for (int c = 0; c < dec.channel_count; c++) {
        exr_coding_channel_info_t *ch = &dec.channels[c];
        int k = dst_of_channel[c];
        if (k < 0) {
            ch->decode_to_ptr = NULL;
            continue;
        }
        if (ch->width != cinfo->width || ch->height != cinfo->height) {
            exr_decoding_destroy(ctx, &dec);
            return EXR_ERR_CORRUPT_CHUNK;
        }
        ch->user_pixel_stride = (int32_t)(3 * sizeof(float));
        ch->user_line_stride = (int32_t)((size_t)out->width * 3 * sizeof(float));
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
        ch->decode_to_ptr = (uint8_t *)(base + k);
    }
    rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
    if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(ctx, 0, &dec);
    exr_decoding_destroy(ctx, &dec);
    return rv;
}

/* Reads part 0 of an open context into *out (allocated here). */
static glow_result exr_read_body(exr_context_t ctx, const char *path, glow_eval_image *out, const exr_capture *cap,
                                 char *message, size_t message_size) {
    int parts = 0;
    exr_storage_t storage = EXR_STORAGE_SCANLINE;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *chlist = NULL;
    exr_result_t rv = exr_get_count(ctx, &parts);
    if (rv == EXR_ERR_SUCCESS && parts < 1) rv = EXR_ERR_FILE_BAD_HEADER;
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_storage(ctx, 0, &storage);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_data_window(ctx, 0, &dw);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_channels(ctx, 0, &chlist);
    if (rv != EXR_ERR_SUCCESS || !chlist) {
        set_message(message, message_size, "%s: bad OpenEXR header (%s)", path, exr_reason(cap, rv));
        return GLOW_ERROR_CORRUPT_DATA;
    }
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
        set_message(message, message_size, "%s: deep OpenEXR images are not supported", path);
        return GLOW_ERROR_CORRUPT_DATA;
    }
    int64_t w64 = (int64_t)dw.max.x - dw.min.x + 1, h64 = (int64_t)dw.max.y - dw.min.y + 1;
    if (w64 <= 0 || h64 <= 0 || w64 > INT32_MAX / 16 || h64 > INT32_MAX / 16 ||
        (uint64_t)w64 * (uint64_t)h64 > GLOW_EVAL_MAX_PIXELS) {
        set_message(message, message_size, "%s: unsupported data window %lldx%lld", path, (long long)w64,
                    (long long)h64);
        return GLOW_ERROR_CORRUPT_DATA;
    }

    /* Map channels (sorted by name, the order the decoder lists them) to R, G, B. */
    int nch = chlist->num_channels;
    if (nch <= 0 || nch > 1024) {
        set_message(message, message_size, "%s: bad channel list (%d channels)", path, nch);
        return GLOW_ERROR_CORRUPT_DATA;
    }
    int *dst = malloc((size_t)nch * sizeof(int));
    if (!dst) {
        set_message(message, message_size, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    int have_r = 0, have_g = 0, have_b = 0, have_y = 0;
    for (int c = 0; c < nch; c++) {
        const char *n = chlist->entries[c].name.str;
        dst[c] = -1;
        if (!n) continue;
        if (strcmp(n, "R") == 0) dst[c] = 0, have_r = 1;
        else if (strcmp(n, "G") == 0) dst[c] = 1, have_g = 1;
        else if (strcmp(n, "B") == 0) dst[c] = 2, have_b = 1;
        else if (strcmp(n, "Y") == 0) have_y = 1;
    }
    int grey = 0;
    if (!(have_r && have_g && have_b)) {
        if (!have_y) {
            free(dst);
            set_message(message, message_size, "%s: no R, G, B (or Y) channels", path);
            return GLOW_ERROR_CORRUPT_DATA;
        }
        grey = 1;
        for (int c = 0; c < nch; c++)
            dst[c] = (chlist->entries[c].name.str && strcmp(chlist->entries[c].name.str, "Y") == 0) ? 0 : -1;
    }
    for (int c = 0; c < nch; c++) {
        if (dst[c] < 0) continue;
        const exr_attr_chlist_entry_t *e = &chlist->entries[c];
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT) {
            set_message(message, message_size, "%s: channel %s is not half or float", path, e->name.str);
            free(dst);
            return GLOW_ERROR_CORRUPT_DATA;
        }
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            set_message(message, message_size, "%s: channel %s is subsampled (not supported)", path, e->name.str);
            free(dst);
            return GLOW_ERROR_CORRUPT_DATA;
        }
    }

    glow_result r = glow_eval_image_alloc(out, (uint32_t)w64, (uint32_t)h64);
    if (r != GLOW_OK) {
        free(dst);
        set_message(message, message_size, "%s: out of memory", path);
        return r;
    }

    const uint32_t W = out->width, H = out->height;
    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lines = 0;
        rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
        if (rv == EXR_ERR_SUCCESS && lines < 1) rv = EXR_ERR_FILE_BAD_HEADER;
        for (int64_t y = dw.min.y; rv == EXR_ERR_SUCCESS && y <= dw.max.y; y += lines) {
            exr_chunk_info_t cinfo;
            rv = exr_read_scanline_chunk_info(ctx, 0, (int)y, &cinfo);
            if (rv != EXR_ERR_SUCCESS) break;
            int64_t y0 = (int64_t)cinfo.start_y - dw.min.y, x0 = (int64_t)cinfo.start_x - dw.min.x;
            if (x0 != 0 || y0 < 0 || cinfo.width != (int32_t)W || cinfo.height <= 0 || y0 + cinfo.height > H) {
                rv = EXR_ERR_CORRUPT_CHUNK;
                break;
            }
            rv = exr_decode_chunk(ctx, &cinfo, out, 0, (uint32_t)y0, dst, nch);
        }
    } else {
        int32_t tw = 0, th = 0;
        rv = exr_get_tile_sizes(ctx, 0, 0, 0, &tw, &th);
        if (rv == EXR_ERR_SUCCESS && (tw < 1 || th < 1)) rv = EXR_ERR_FILE_BAD_HEADER;
        int ty = 0;
        for (int64_t y = 0; rv == EXR_ERR_SUCCESS && y < H; y += th, ty++) {
            int tx = 0;
            for (int64_t x = 0; rv == EXR_ERR_SUCCESS && x < W; x += tw, tx++) {
                exr_chunk_info_t cinfo;
                rv = exr_read_tile_chunk_info(ctx, 0, tx, ty, 0, 0, &cinfo);
                if (rv != EXR_ERR_SUCCESS) break;
                if (cinfo.width <= 0 || cinfo.height <= 0 || x + cinfo.width > W || y + cinfo.height > H) {
                    rv = EXR_ERR_CORRUPT_CHUNK;
                    break;
                }
                rv = exr_decode_chunk(ctx, &cinfo, out, (uint32_t)x, (uint32_t)y, dst, nch);
            }
        }
    }
    free(dst);
    if (rv != EXR_ERR_SUCCESS) {
        glow_eval_image_free(out);
        if (rv == EXR_ERR_OUT_OF_MEMORY) {
            set_message(message, message_size, "%s: out of memory", path);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        set_message(message, message_size, "%s: corrupt OpenEXR pixel data (%s)", path, exr_reason(cap, rv));
        return GLOW_ERROR_CORRUPT_DATA;
    }
    if (grey) {
        float *p = out->rgb;
        for (size_t i = 0, n = (size_t)W * H; i < n; i++, p += 3) p[1] = p[2] = p[0];
    }
    return GLOW_OK;
}

/* The first (up to) 4 bytes of a file, with the reader's messages for a file that cannot be opened or read. */
static glow_result read_magic(const char *path, unsigned char magic[4], size_t *got, char *message, size_t message_size) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        set_message(message, message_size, "%s: cannot open (%s)", path, strerror(errno));
        return GLOW_ERROR_IO;
    }
    *got = fread(magic, 1, 4, f);
    const int read_error = ferror(f), e = errno;
    fclose(f);
    if (read_error) {
        set_message(message, message_size, "%s: cannot read (%s)", path, strerror(e));
        return GLOW_ERROR_IO;
    }
    return GLOW_OK;
}

glow_result glow_eval_read_exr(const char *path, glow_eval_image *out, char *message, size_t message_size) {
    if (out) {
        out->width = out->height = 0;
        out->rgb = NULL;
    }
    if (!path || !out) {
        set_message(message, message_size, "%s: NULL argument to glow_eval_read_exr", path ? path : "(null)");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    /* Open and check the magic number ourselves: clearer messages (errno) than the library's. */
    unsigned char magic[4] = {0};
    size_t got = 0;
    glow_result mr = read_magic(path, magic, &got, message, message_size);
    if (mr != GLOW_OK) return mr;
    if (got != 4 || magic[0] != 0x76 || magic[1] != 0x2f || magic[2] != 0x31 || magic[3] != 0x01) {
        set_message(message, message_size, "%s: not an OpenEXR file", path);
        return GLOW_ERROR_CORRUPT_DATA;
    }

    exr_capture cap = {{0}, 0};
    tl_capture = &cap;
    exr_context_initializer_t init = exr_quiet_init();
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    glow_result r;
    if (rv != EXR_ERR_SUCCESS) {
        if (rv == EXR_ERR_OUT_OF_MEMORY) {
            set_message(message, message_size, "%s: out of memory", path);
            r = GLOW_ERROR_OUT_OF_MEMORY;
        } else if (rv == EXR_ERR_FILE_ACCESS) {
            set_message(message, message_size, "%s: cannot read (%s)", path, exr_reason(&cap, rv));
            r = GLOW_ERROR_IO;
        } else if (rv == EXR_ERR_READ_IO) { /* we just read its first bytes: a short read is truncation */
            set_message(message, message_size, "%s: truncated OpenEXR header (%s)", path, exr_reason(&cap, rv));
            r = GLOW_ERROR_CORRUPT_DATA;
        } else {
            set_message(message, message_size, "%s: bad OpenEXR header (%s)", path, exr_reason(&cap, rv));
            r = GLOW_ERROR_CORRUPT_DATA;
        }
        if (ctx) exr_finish(&ctx);
    } else {
        r = exr_read_body(ctx, path, out, &cap, message, message_size);
        exr_finish(&ctx);
    }
    tl_capture = NULL;
    return r;
}

/* ---------------------------------------------------------------------------------------------
 * PFM (Portable Float Map): "PF" (RGB) or "Pf" (grey), whitespace, width, whitespace, height,
 * whitespace, scale, ONE whitespace byte, then float32 pixels, bottom row first. The scale's sign is
 * the byte order (negative: little-endian); its magnitude is ignored (Blender, the referee and most
 * readers write and take 1). Bytes are assembled explicitly, so the host's byte order does not
 * matter. Trailing bytes after the pixels are ignored. */

#define PFM_MAX_TOKEN 63 /* longer header fields are not numbers a writer would produce */

/* Reads the next whitespace-delimited token of at most PFM_MAX_TOKEN bytes into tok; *sep receives
 * the byte that ended it (EOF at end of file). Returns 0 at end of file before a token, -1 when the
 * token is too long, 1 on success. */
static int pfm_token(FILE *f, char tok[PFM_MAX_TOKEN + 1], int *sep) {
    int c;
    do c = getc(f);
    while (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f');
    if (c == EOF) return 0;
    size_t n = 0;
    while (c != EOF && c != ' ' && c != '\t' && c != '\n' && c != '\r' && c != '\v' && c != '\f') {
        if (n == PFM_MAX_TOKEN) return -1;
        tok[n++] = (char)c;
        c = getc(f);
    }
    tok[n] = '\0';
    *sep = c;
    return 1;
}

/* A decimal whole number (digits only), saturating at 2^40; 0 when tok is not one. */
static uint64_t pfm_dimension(const char *tok) {
    uint64_t v = 0;
    if (!*tok) return 0;
    for (const char *p = tok; *p; p++) {
        if (*p < '0' || *p > '9') return 0;
        v = v * 10 + (uint64_t)(*p - '0');
        if (v > ((uint64_t)1 << 40)) v = (uint64_t)1 << 40;
    }
    return v;
}

glow_result glow_eval_read_pfm(const char *path, glow_eval_image *out, char *message, size_t message_size) {
    if (out) {
        out->width = out->height = 0;
        out->rgb = NULL;
    }
    if (!path || !out) {
        set_message(message, message_size, "%s: NULL argument to glow_eval_read_pfm", path ? path : "(null)");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        set_message(message, message_size, "%s: cannot open (%s)", path, strerror(errno));
        return GLOW_ERROR_IO;
    }
    glow_result r = GLOW_OK;
    unsigned char *row = NULL;
    char tok[3][PFM_MAX_TOKEN + 1];
    int sep = EOF, channels = 0;
    int got = pfm_token(f, tok[0], &sep);
    if (ferror(f)) goto read_error;
    if (got == 1 && strcmp(tok[0], "PF") == 0) channels = 3;
    else if (got == 1 && strcmp(tok[0], "Pf") == 0) channels = 1;
    else {
        set_message(message, message_size, "%s: not a PFM file (no \"PF\" or \"Pf\" header)", path);
        r = GLOW_ERROR_CORRUPT_DATA;
        goto done;
    }
    static const char *const field[3] = {"width", "height", "scale"};
    for (int k = 0; k < 3; k++) {
        got = pfm_token(f, tok[k], &sep);
        if (ferror(f)) goto read_error;
        if (got != 1) {
            set_message(message, message_size, "%s: bad PFM header (%s %s)", path,
                        got == 0 ? "no" : "overlong", field[k]);
            r = GLOW_ERROR_CORRUPT_DATA;
            goto done;
        }
    }
    const uint64_t w64 = pfm_dimension(tok[0]), h64 = pfm_dimension(tok[1]);
    if (w64 == 0 || h64 == 0) {
        set_message(message, message_size, "%s: bad PFM header (size '%s' x '%s' is not two positive whole numbers)",
                    path, tok[0], tok[1]);
        r = GLOW_ERROR_CORRUPT_DATA;
        goto done;
    }
    if (w64 > GLOW_EVAL_MAX_PIXELS || h64 > GLOW_EVAL_MAX_PIXELS || w64 * h64 > GLOW_EVAL_MAX_PIXELS) {
        set_message(message, message_size, "%s: PFM image %sx%s is too large (more than %llu pixels)", path, tok[0],
                    tok[1], (unsigned long long)GLOW_EVAL_MAX_PIXELS);
        r = GLOW_ERROR_CORRUPT_DATA;
        goto done;
    }
    const uint32_t w = (uint32_t)w64, h = (uint32_t)h64;
    char *end = NULL;
    const double scale = strtod(tok[2], &end);
    if (!end || *end || !isfinite(scale) || scale == 0.0) {
        set_message(message, message_size,
                    "%s: bad PFM header (scale '%s': a non-zero number is needed, its sign gives the byte order)",
                    path, tok[2]);
        r = GLOW_ERROR_CORRUPT_DATA;
        goto done;
    }
    if (sep == EOF) {
        set_message(message, message_size, "%s: truncated PFM file (no pixel data after the header)", path);
        r = GLOW_ERROR_CORRUPT_DATA;
        goto done;
    }
    const int little = scale < 0.0;

    /* Refuse a header promising more data than a regular file holds before allocating for it. */
    const size_t row_bytes = (size_t)w * (size_t)channels * sizeof(float);
    const uint64_t need = (uint64_t)row_bytes * h;
    struct stat st;
    long pos = ftell(f);
    if (pos >= 0 && fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode) && (uint64_t)st.st_size >= (uint64_t)pos &&
        (uint64_t)st.st_size - (uint64_t)pos < need) {
        set_message(message, message_size, "%s: truncated PFM data (%llu of %llu bytes for %ux%u %s)", path,
                    (unsigned long long)((uint64_t)st.st_size - (uint64_t)pos), (unsigned long long)need,
                    (unsigned)w, (unsigned)h, channels == 3 ? "RGB" : "grey");
        r = GLOW_ERROR_CORRUPT_DATA;
        goto done;
    }
    row = malloc(row_bytes);
    if (!row || glow_eval_image_alloc(out, w, h) != GLOW_OK) {
        set_message(message, message_size, "%s: out of memory", path);
        r = GLOW_ERROR_OUT_OF_MEMORY;
        goto done;
    }
    for (uint32_t fy = 0; fy < h; fy++) { /* file row fy (0 = bottom) is image row h - 1 - fy */
        size_t n = fread(row, 1, row_bytes, f);
        if (n != row_bytes) {
            if (ferror(f)) goto read_error;
            set_message(message, message_size, "%s: truncated PFM data (%llu of %llu bytes for %ux%u %s)", path,
                        (unsigned long long)((uint64_t)fy * row_bytes + n), (unsigned long long)need, (unsigned)w,
                        (unsigned)h, channels == 3 ? "RGB" : "grey");
            r = GLOW_ERROR_CORRUPT_DATA;
            goto done;
        }
        float *dst = out->rgb + (size_t)(h - 1 - fy) * w * 3;
        const unsigned char *b = row;
        for (size_t i = 0; i < (size_t)w * (size_t)channels; i++, b += 4) {
            uint32_t u = little ? (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24
                                : (uint32_t)b[3] | (uint32_t)b[2] << 8 | (uint32_t)b[1] << 16 | (uint32_t)b[0] << 24;
            float v;
            memcpy(&v, &u, sizeof v); /* non-finite values are kept: the metrics report them */
            if (channels == 3) dst[i] = v;
            else dst[3 * i] = dst[3 * i + 1] = dst[3 * i + 2] = v;
        }
    }
    goto done;

read_error:
    set_message(message, message_size, "%s: cannot read (%s)", path, strerror(errno));
    r = GLOW_ERROR_IO;
done:
    if (r != GLOW_OK) glow_eval_image_free(out);
    free(row);
    fclose(f);
    return r;
}

glow_result glow_eval_read_image(const char *path, glow_eval_image *out, char *message, size_t message_size) {
    if (out) {
        out->width = out->height = 0;
        out->rgb = NULL;
    }
    if (!path || !out) {
        set_message(message, message_size, "%s: NULL argument to glow_eval_read_image", path ? path : "(null)");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    unsigned char magic[4] = {0};
    size_t got = 0;
    glow_result mr = read_magic(path, magic, &got, message, message_size);
    if (mr != GLOW_OK) return mr;
    if (got == 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01)
        return glow_eval_read_exr(path, out, message, message_size);
    if (got >= 2 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f'))
        return glow_eval_read_pfm(path, out, message, message_size);
    set_message(message, message_size, "%s: not an OpenEXR or PFM file", path);
    return GLOW_ERROR_CORRUPT_DATA;
}

/* --------------------------------------------------------------------------------------------- */

glow_result glow_eval_write_png(const glow_eval_image *img, float exposure, const char *path, char *message,
                                size_t message_size) {
    glow_result r = check_image(img, path, message, message_size);
    if (r != GLOW_OK) return r;
    if (!isfinite(exposure)) {
        set_message(message, message_size, "%s: exposure %g is not finite", path, (double)exposure);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    size_t n = (size_t)img->width * img->height * 3;
    unsigned char *px = malloc(n);
    char *tmp = tmp_path_of(path);
    if (!px || !tmp) {
        free(px);
        free(tmp);
        set_message(message, message_size, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < n; i++) {
        float v = glow_eval_srgb_encode(img->rgb[i] * exposure); /* NaN encodes as 0 */
        px[i] = (unsigned char)lrintf(v * 255.0f);
    }
    r = probe_writable(path, tmp, message, message_size);
    if (r == GLOW_OK) {
        if (!stbi_write_png(tmp, (int)img->width, (int)img->height, 3, px, (int)img->width * 3)) {
            remove(tmp);
            set_message(message, message_size, "%s: cannot write PNG", path);
            r = GLOW_ERROR_IO;
        } else {
            r = commit_tmp(path, tmp, message, message_size);
        }
    }
    free(px);
    free(tmp);
    return r;
}
