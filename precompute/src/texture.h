/*
 * texture.h — albedo textures for the linker's scene import (texture.c). Internal, not installed.
 *
 * glow__texture (pc_internal.h) holds a linear-RGB float mip chain. Level k is
 * max(1, width>>k) x max(1, height>>k) texels (the header's "width>>k * height>>k" with the
 * 1-texel floor made explicit); level_count runs down to 1x1 (at most 16 levels).
 * Rows are stored top row first (as images are stored); glow__texture_sample maps v = 1 to the top
 * row, so UVs follow the OpenGL / OBJ convention that assimp delivers for every format.
 */
#ifndef GLOW_PC_TEXTURE_H
#define GLOW_PC_TEXTURE_H

#include <stddef.h>
#include <stdint.h>

#include "pc_internal.h"

/* Width/height of mip level `level` (max(1, size >> level)). */
int glow__texture_level_width(const glow__texture *tex, int level);
int glow__texture_level_height(const glow__texture *tex, int level);

/* Decodes an image file (any format stb_image reads: PNG, JPEG, BMP, TGA, PNM, ...), converts
 * 8-bit sRGB to linear and builds the mip chain. On failure returns GLOW_ERROR_IO (cannot open /
 * read), GLOW_ERROR_UNSUPPORTED (cannot decode) or GLOW_ERROR_OUT_OF_MEMORY, writes a short reason
 * to `why` and leaves *out zeroed. Logs nothing (the caller names the scene and material). */
glow_result glow__texture_load_file(const char *path, glow__texture *out, char *why, size_t why_size);
/* Same, from a compressed image in memory (embedded glTF / FBX textures). `name` fills out->path. */
glow_result glow__texture_load_memory(const void *data, size_t size, const char *name, glow__texture *out,
                                      char *why, size_t why_size);
/* Same, from raw 8-bit sRGB texels: `texels` has width*height pixels of `components` bytes with the
 * red, green, blue bytes at offsets r_offset, g_offset, b_offset (assimp's aiTexel is BGRA:
 * components 4, offsets 2, 1, 0). */
glow_result glow__texture_from_srgb8(const uint8_t *texels, int width, int height, int components, int r_offset,
                                     int g_offset, int b_offset, const char *name, glow__texture *out, char *why,
                                     size_t why_size);
void glow__texture_free(glow__texture *tex);

/* Finds the file a scene refers to as `name` (relative to `dir`, or absolute). Accepts '\\' as a
 * separator and, when the exact name does not exist, matches each path component
 * case-insensitively (the lexicographically first match when several differ only in case).
 * Writes the path to out and returns true when a regular file was found. */
bool glow__texture_resolve(const char *dir, const char *name, char *out, size_t out_size);

#endif /* GLOW_PC_TEXTURE_H */
