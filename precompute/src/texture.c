/* texture.c — albedo textures: decode (stb_image), sRGB -> linear, box-filtered mip chain,
 * bilinear/trilinear wrapped lookup, and the forgiving file-name resolution scene files need. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <stb/stb_image.h>

#include "texture.h"

/* 8192 x 8192: level 0 alone is then 768 MiB of floats; refuse anything bigger. */
#define MAX_TEXELS ((size_t)1 << 26)

int glow__texture_level_width(const glow__texture *tex, int level) {
    int w = tex->width >> level;
    return w > 0 ? w : 1;
}

int glow__texture_level_height(const glow__texture *tex, int level) {
    int h = tex->height >> level;
    return h > 0 ? h : 1;
}

void glow__texture_free(glow__texture *tex) {
    if (!tex) return;
    for (int k = 0; k < 16; k++) free(tex->levels[k]);
    memset(tex, 0, sizeof *tex);
}

static void set_why(char *why, size_t why_size, const char *msg) {
    if (why && why_size) snprintf(why, why_size, "%s", msg);
}

static float srgb_to_linear(double c) {
    return (float)(c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4));
}

/* Box filter: each texel of the smaller level averages the (up to) 2x2 texels above it; a
 * dimension that is already 1 is not halved (its index is clamped). Odd sizes drop the last
 * row/column, as GL's default mip generation does. */
static void downsample(const float *src, int sw, int sh, float *dst, int dw, int dh) {
    for (int y = 0; y < dh; y++) {
        int y0 = 2 * y < sh ? 2 * y : sh - 1;
        int y1 = 2 * y + 1 < sh ? 2 * y + 1 : sh - 1;
        for (int x = 0; x < dw; x++) {
            int x0 = 2 * x < sw ? 2 * x : sw - 1;
            int x1 = 2 * x + 1 < sw ? 2 * x + 1 : sw - 1;
            const float *a = src + 3 * ((size_t)y0 * sw + x0), *b = src + 3 * ((size_t)y0 * sw + x1);
            const float *c = src + 3 * ((size_t)y1 * sw + x0), *d = src + 3 * ((size_t)y1 * sw + x1);
            float *o = dst + 3 * ((size_t)y * dw + x);
            for (int k = 0; k < 3; k++) o[k] = 0.25f * ((a[k] + b[k]) + (c[k] + d[k]));
        }
    }
}

glow_result glow__texture_from_srgb8(const uint8_t *texels, int width, int height, int components, int r_offset,
                                     int g_offset, int b_offset, const char *name, glow__texture *out, char *why,
                                     size_t why_size) {
    memset(out, 0, sizeof *out);
    if (!texels || width <= 0 || height <= 0 || components < 1 || r_offset < 0 || g_offset < 0 || b_offset < 0 ||
        r_offset >= components || g_offset >= components || b_offset >= components) {
        set_why(why, why_size, "invalid image");
        return GLOW_ERROR_CORRUPT_DATA;
    }
    if ((size_t)width * (size_t)height > MAX_TEXELS) {
        set_why(why, why_size, "image too large (more than 8192 x 8192 texels)");
        return GLOW_ERROR_UNSUPPORTED;
    }
    snprintf(out->path, sizeof out->path, "%s", name ? name : "");
    out->width = width;
    out->height = height;
    int count = 1;
    while (count < 16 && ((width >> (count - 1)) > 1 || (height >> (count - 1)) > 1)) count++;
    out->level_count = count;
    for (int k = 0; k < count; k++) {
        size_t n = (size_t)glow__texture_level_width(out, k) * (size_t)glow__texture_level_height(out, k) * 3;
        out->levels[k] = malloc(n * sizeof(float));
        if (!out->levels[k]) {
            glow__texture_free(out);
            set_why(why, why_size, "out of memory");
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
    }
    float lut[256];
    for (int i = 0; i < 256; i++) lut[i] = srgb_to_linear(i / 255.0);
    size_t n = (size_t)width * (size_t)height;
    float *l0 = out->levels[0];
    for (size_t i = 0; i < n; i++) {
        const uint8_t *t = texels + i * (size_t)components;
        l0[3 * i + 0] = lut[t[r_offset]];
        l0[3 * i + 1] = lut[t[g_offset]];
        l0[3 * i + 2] = lut[t[b_offset]];
    }
    for (int k = 1; k < count; k++)
        downsample(out->levels[k - 1], glow__texture_level_width(out, k - 1), glow__texture_level_height(out, k - 1),
                   out->levels[k], glow__texture_level_width(out, k), glow__texture_level_height(out, k));
    return GLOW_OK;
}

static glow_result from_stbi(stbi_uc *pixels, int w, int h, const char *name, glow__texture *out, char *why,
                             size_t why_size) {
    if (!pixels) {
        const char *r = stbi_failure_reason();
        char msg[256];
        snprintf(msg, sizeof msg, "cannot decode image (%s)", r ? r : "unknown reason");
        set_why(why, why_size, msg);
        memset(out, 0, sizeof *out);
        return GLOW_ERROR_UNSUPPORTED;
    }
    glow_result r = glow__texture_from_srgb8(pixels, w, h, 3, 0, 1, 2, name, out, why, why_size);
    stbi_image_free(pixels);
    return r;
}

glow_result glow__texture_load_file(const char *path, glow__texture *out, char *why, size_t why_size) {
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f) {
        char msg[256];
        snprintf(msg, sizeof msg, "cannot open (%s)", strerror(errno));
        set_why(why, why_size, msg);
        return GLOW_ERROR_IO;
    }
    int w = 0, h = 0, comp = 0;
    stbi_uc *pixels = stbi_load_from_file(f, &w, &h, &comp, 3);
    fclose(f);
    return from_stbi(pixels, w, h, path, out, why, why_size);
}

glow_result glow__texture_load_memory(const void *data, size_t size, const char *name, glow__texture *out,
                                      char *why, size_t why_size) {
    memset(out, 0, sizeof *out);
    if (!data || size == 0 || size > (size_t)0x7FFFFFFF) {
        set_why(why, why_size, size ? "embedded image too large" : "empty embedded image");
        return GLOW_ERROR_CORRUPT_DATA;
    }
    int w = 0, h = 0, comp = 0;
    stbi_uc *pixels = stbi_load_from_memory(data, (int)size, &w, &h, &comp, 3);
    return from_stbi(pixels, w, h, name, out, why, why_size);
}

/* ------------------------------------------------------------------ lookup */

static void bilinear(const glow__texture *tex, int level, float u, float v, float out[3]) {
    int w = glow__texture_level_width(tex, level), h = glow__texture_level_height(tex, level);
    const float *t = tex->levels[level];
    /* texel centres at (i + 0.5) / w; v = 1 is the image's top row */
    float x = u * (float)w - 0.5f, y = (1.0f - v) * (float)h - 0.5f;
    float fx0 = floorf(x), fy0 = floorf(y);
    float fx = x - fx0, fy = y - fy0;
    int x0 = (int)fx0 % w, y0 = (int)fy0 % h;
    if (x0 < 0) x0 += w;
    if (y0 < 0) y0 += h;
    int x1 = x0 + 1 == w ? 0 : x0 + 1, y1 = y0 + 1 == h ? 0 : y0 + 1;
    const float *a = t + 3 * ((size_t)y0 * w + x0), *b = t + 3 * ((size_t)y0 * w + x1);
    const float *c = t + 3 * ((size_t)y1 * w + x0), *d = t + 3 * ((size_t)y1 * w + x1);
    for (int k = 0; k < 3; k++) {
        float top = a[k] + (b[k] - a[k]) * fx, bottom = c[k] + (d[k] - c[k]) * fx;
        out[k] = top + (bottom - top) * fy;
    }
}

void glow__texture_sample(const glow__texture *tex, float u, float v, float footprint, float out_rgb[3]) {
    if (!tex || tex->level_count <= 0 || !tex->levels[0]) {
        out_rgb[0] = out_rgb[1] = out_rgb[2] = 0.0f;
        return;
    }
    /* wrap into [0, 1) first so the float -> int conversions below cannot overflow */
    if (!isfinite(u)) u = 0.0f;
    if (!isfinite(v)) v = 0.0f;
    u -= floorf(u);
    v -= floorf(v);
    /* level from the footprint in texels (the larger dimension: never under-filter) */
    int size = tex->width > tex->height ? tex->width : tex->height;
    float level = 0.0f;
    if (footprint > 0.0f && isfinite(footprint)) {
        level = log2f(footprint * (float)size);
        if (!(level > 0.0f)) level = 0.0f;
        if (level > (float)(tex->level_count - 1)) level = (float)(tex->level_count - 1);
    }
    int l0 = (int)level;
    float t = level - (float)l0;
    bilinear(tex, l0, u, v, out_rgb);
    if (t > 0.0f && l0 + 1 < tex->level_count) { /* trilinear between the two nearest levels */
        float o1[3];
        bilinear(tex, l0 + 1, u, v, o1);
        for (int k = 0; k < 3; k++) out_rgb[k] += (o1[k] - out_rgb[k]) * t;
    }
}

/* ------------------------------------------------------------------ file-name resolution */

static bool is_regular(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

static bool is_dir(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static bool join(char *out, size_t out_size, const char *a, const char *b) {
    int n;
    if (!a[0]) n = snprintf(out, out_size, "%s", b);
    else if (a[strlen(a) - 1] == '/') n = snprintf(out, out_size, "%s%s", a, b);
    else n = snprintf(out, out_size, "%s/%s", a, b);
    return n >= 0 && (size_t)n < out_size;
}

/* Walks `rel` ('/'-separated) from `base`, matching each component exactly or, failing that,
 * case-insensitively (lexicographically first candidate of the right kind). */
static bool resolve_components(const char *base, const char *rel, char *out, size_t out_size) {
    char cur[4096], comp[1024], cand[4096];
    if (snprintf(cur, sizeof cur, "%s", base) >= (int)sizeof cur) return false;
    const char *p = rel;
    while (*p) {
        while (*p == '/') p++;
        if (!*p) break;
        size_t len = strcspn(p, "/");
        if (len >= sizeof comp) return false;
        memcpy(comp, p, len);
        comp[len] = 0;
        p += len;
        while (*p == '/') p++;
        bool last = *p == 0;
        if (strcmp(comp, ".") == 0) continue;
        if (!join(cand, sizeof cand, cur, comp)) return false;
        if (last ? is_regular(cand) : is_dir(cand)) {
            memcpy(cur, cand, strlen(cand) + 1);
            continue;
        }
        DIR *d = opendir(cur[0] ? cur : ".");
        if (!d) return false;
        char best[1024];
        best[0] = 0;
        bool found = false;
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (strcasecmp(e->d_name, comp) != 0) continue;
            if (found && strcmp(e->d_name, best) >= 0) continue;
            char full[4096];
            if (!join(full, sizeof full, cur, e->d_name)) continue;
            if (last ? !is_regular(full) : !is_dir(full)) continue;
            snprintf(best, sizeof best, "%s", e->d_name);
            found = true;
        }
        closedir(d);
        if (!found || !join(cand, sizeof cand, cur, best)) return false;
        memcpy(cur, cand, strlen(cand) + 1);
    }
    if (!is_regular(cur)) return false;
    return snprintf(out, out_size, "%s", cur) < (int)out_size;
}

bool glow__texture_resolve(const char *dir, const char *name, char *out, size_t out_size) {
    char rel[2048];
    if (!name || !name[0] || snprintf(rel, sizeof rel, "%s", name) >= (int)sizeof rel) return false;
    for (char *c = rel; *c; c++)
        if (*c == '\\') *c = '/';
    const char *base = (dir && dir[0]) ? dir : ".";
    char path[4096];
    /* 1. as written (absolute, or relative to the scene's folder) */
    if (rel[0] == '/') {
        if (is_regular(rel)) return snprintf(out, out_size, "%s", rel) < (int)out_size;
    } else if (join(path, sizeof path, base, rel) && is_regular(path)) {
        return snprintf(out, out_size, "%s", path) < (int)out_size;
    }
    /* 2. component by component, case-insensitively */
    if (rel[0] == '/' ? resolve_components("/", rel + 1, out, out_size)
                      : resolve_components(base, rel, out, out_size))
        return true;
    /* 3. last resort for paths from another machine ("C:/maps/x.jpg", "/home/a/x.jpg"):
     *    the bare file name in the scene's folder */
    const char *slash = strrchr(rel, '/');
    const char *file = slash ? slash + 1 : rel;
    if (file != rel && file[0]) return resolve_components(base, file, out, out_size);
    return false;
}
