/* glctx_internal.h — what the glow_glctx back ends (glctx_egl.c, glctx_osmesa.c, glctx_glfw.c) share
 * with the front (glctx.c). Native handles are kept as void * so that no file needs another's headers. */
#ifndef GLOW_GLCTX_INTERNAL_H
#define GLOW_GLCTX_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "glow/glow_glctx.h"

/* Host-side object: plain malloc/free like glow_host (the runtime's allocator hooks are for the
 * runtime's own memory; a GL context helper lives outside it). */
struct glow_glctx {
    glow_glctx_kind kind;   /* EGL, OSMESA or WINDOW once created */
    glow_gl_loader loader;  /* the back end's GetProcAddress (wrapped to glow_gl_loader) */
    uint32_t width, height; /* headless: desc size or 1280 x 720 (a window asks GLFW) */
    char renderer[160], version[160];
    /* EGL */
    void *egl_display, *egl_context, *egl_surface; /* surface: EGL_NO_SURFACE unless a pbuffer was needed */
    /* OSMesa */
    void *osmesa_context;
    unsigned char *osmesa_buffer; /* GLOW__OSMESA_SIZE^2 RGBA8: OSMesaMakeCurrent needs a colour buffer */
    /* GLFW */
    void *window;
};

#define GLOW__OSMESA_SIZE 16

/* Each create makes the context current on the calling thread and sets ctx->loader; on failure it
 * leaves nothing behind (ctx fields back to zero) and writes a reason (without "EGL: " etc.) to why.
 * \returns GLOW_OK, GLOW_ERROR_UNSUPPORTED or GLOW_ERROR_OUT_OF_MEMORY. */
glow_result glow__glctx_egl_create(glow_glctx *ctx, const glow_glctx_desc *desc, char *why, size_t why_size);
void glow__glctx_egl_destroy(glow_glctx *ctx);
glow_result glow__glctx_egl_make_current(glow_glctx *ctx);
glow_result glow__glctx_egl_release_current(glow_glctx *ctx);

glow_result glow__glctx_osmesa_create(glow_glctx *ctx, const glow_glctx_desc *desc, char *why, size_t why_size);
void glow__glctx_osmesa_destroy(glow_glctx *ctx);
glow_result glow__glctx_osmesa_make_current(glow_glctx *ctx);
glow_result glow__glctx_osmesa_release_current(glow_glctx *ctx);

glow_result glow__glctx_glfw_create(glow_glctx *ctx, const glow_glctx_desc *desc, char *why, size_t why_size);
void glow__glctx_glfw_destroy(glow_glctx *ctx);
glow_result glow__glctx_glfw_make_current(glow_glctx *ctx);
glow_result glow__glctx_glfw_release_current(glow_glctx *ctx);
void glow__glctx_glfw_swap(glow_glctx *ctx);
int glow__glctx_glfw_should_close(const glow_glctx *ctx);
void glow__glctx_glfw_framebuffer_size(const glow_glctx *ctx, uint32_t *width, uint32_t *height);

/* Appends printf-style text to a NUL-terminated buffer, truncating silently. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
void glow__glctx_appendf(char *buf, size_t size, const char *fmt, ...);

#endif /* GLOW_GLCTX_INTERNAL_H */
