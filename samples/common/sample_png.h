/* sample_png.h — small helpers shared by the samples (header-only, all static): tone-mapped 8-bit
 * sRGB PNGs through stb_image_write (Debian's libstb carries its implementation; the samples link
 * it) and a top-down picture of Glow's grid caches.
 * Not part of Glow's API: copy what you need. */
#ifndef GLOW_SAMPLE_PNG_H
#define GLOW_SAMPLE_PNG_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <glow/glow.h>
#include <stb/stb_image_write.h>

/* Linear radiance -> display: exposure, Reinhard x/(1+x), sRGB encoding, 8 bits. */
static inline uint8_t sample_tonemap(float linear, float exposure) {
    float x = linear > 0.0f && isfinite(linear) ? linear * exposure : 0.0f;
    x = x / (1.0f + x);
    x = x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
    return (uint8_t)lrintf(fminf(fmaxf(x, 0.0f), 1.0f) * 255.0f);
}

/* Writes `rgb` (width x height x 3 floats, linear, row 0 at the top) as a PNG. 0 on success, -1 on
 * failure (out of memory or the file could not be written). */
static inline int sample_write_png(const char *path, int width, int height, const float *rgb, float exposure) {
    uint8_t *px = malloc((size_t)width * (size_t)height * 3);
    if (!px) return -1;
    for (size_t i = 0; i < (size_t)width * (size_t)height * 3; i++) px[i] = sample_tonemap(rgb[i], exposure);
    int ok = stbi_write_png(path, width, height, 3, px, width * 3);
    free(px);
    return ok ? 0 : -1;
}

/* Writes DIR/frame_NNN.png: a top-down slice of the grid caches at height `y` (m) across the bake's
 * bounds (x to the right, z downwards, 128 pixels along the longer side). Each pixel is
 * glow_sample_grid there, shaded by glow_shade_sh for an upward-facing (+Y) diffuse surface: E/π, the
 * radiance a white floor there would reflect (W/(m²·sr)), tone-mapped at exposure 1. Cells without
 * caches (inside solids) come out black. 0 on success; -1 after printing why (the message names the
 * file) when the bake has no grid, memory runs out or the file cannot be written. */
static inline int sample_write_grid_slice(const char *dir, long frame, const glow_cache_outputs *out,
                                   const glow_bake_info *info, float y) {
    char path[4096];
    snprintf(path, sizeof path, "%s/frame_%03ld.png", dir, frame);
    float ext_x = info->bounds_max[0] - info->bounds_min[0], ext_z = info->bounds_max[2] - info->bounds_min[2];
    int w = ext_x >= ext_z ? 128 : (int)fmaxf(1.0f, 128.0f * ext_x / ext_z);
    int h = ext_z >= ext_x ? 128 : (int)fmaxf(1.0f, 128.0f * ext_z / ext_x);
    float *rgb = out->grid_sh ? calloc((size_t)w * (size_t)h * 3, sizeof(float)) : NULL;
    if (!rgb) {
        fprintf(stderr, "%s: not written: %s\n", path, out->grid_sh ? "out of memory" : "the bake has no grid");
        return -1;
    }
    const float up[3] = {0.0f, 1.0f, 0.0f};
    float coeffs[3 * GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS];
    for (int j = 0; j < h; j++) {
        for (int i = 0; i < w; i++) {
            float p[3] = {info->bounds_min[0] + ext_x * (i + 0.5f) / (float)w, y,
                          info->bounds_min[2] + ext_z * (j + 0.5f) / (float)h};
            float *px = rgb + 3 * ((size_t)j * (size_t)w + (size_t)i);
            if (glow_sample_grid(out, p, coeffs) == GLOW_OK)
                glow_shade_sh(coeffs, out->sh_bands_luma, out->sh_bands_chroma, up, 1.0f, px);
        }
    }
    int result = sample_write_png(path, w, h, rgb, 1.0f);
    if (result != 0) fprintf(stderr, "%s: cannot write the PNG\n", path);
    free(rgb);
    return result;
}

#endif /* GLOW_SAMPLE_PNG_H */
