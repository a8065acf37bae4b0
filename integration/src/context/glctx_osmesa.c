/* glctx_osmesa.c — glow_glctx on OSMesa (Mesa's off-screen interface; llvmpipe in Mesa >= 20):
 * OSMesaCreateContextAttribs for a 4.5 core profile, made current on a small private RGBA8 buffer
 * (OSMesaMakeCurrent needs one; Glow draws into framebuffer objects, never into it). OSMesa has no
 * debug-context attribute: desc->debug is ignored (Mesa's KHR_debug works without it). */
#include <GL/osmesa.h>
#include <stdlib.h>

#include "glctx_internal.h"

static glow_gl_proc osmesa_loader(const char *name) { return (glow_gl_proc)OSMesaGetProcAddress(name); }

static GLboolean make_current(glow_glctx *ctx) {
    return OSMesaMakeCurrent((OSMesaContext)ctx->osmesa_context, ctx->osmesa_buffer, GL_UNSIGNED_BYTE,
                             GLOW__OSMESA_SIZE, GLOW__OSMESA_SIZE);
}

glow_result glow__glctx_osmesa_create(glow_glctx *ctx, const glow_glctx_desc *desc, char *why, size_t why_size) {
    (void)desc;
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           0,
                           OSMESA_STENCIL_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           4,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           5,
                           0};
    unsigned char *buffer = malloc((size_t)GLOW__OSMESA_SIZE * GLOW__OSMESA_SIZE * 4);
    if (!buffer) {
        glow__glctx_appendf(why, why_size, "out of memory for the colour buffer");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    OSMesaContext context = OSMesaCreateContextAttribs(attribs, NULL);
    if (!context) {
        glow__glctx_appendf(why, why_size, "OSMesaCreateContextAttribs(core 4.5) returned NULL");
        free(buffer);
        return GLOW_ERROR_UNSUPPORTED;
    }
    ctx->osmesa_context = context;
    ctx->osmesa_buffer = buffer;
    if (!make_current(ctx)) {
        glow__glctx_appendf(why, why_size, "OSMesaMakeCurrent failed");
        OSMesaDestroyContext(context);
        free(buffer);
        ctx->osmesa_context = NULL;
        ctx->osmesa_buffer = NULL;
        return GLOW_ERROR_UNSUPPORTED;
    }
    ctx->loader = osmesa_loader;
    return GLOW_OK;
}

void glow__glctx_osmesa_destroy(glow_glctx *ctx) {
    if (!ctx->osmesa_context) return;
    glow__glctx_osmesa_release_current(ctx);
    OSMesaDestroyContext((OSMesaContext)ctx->osmesa_context);
    free(ctx->osmesa_buffer);
    ctx->osmesa_context = NULL;
    ctx->osmesa_buffer = NULL;
    ctx->loader = NULL;
}

glow_result glow__glctx_osmesa_make_current(glow_glctx *ctx) {
    return make_current(ctx) ? GLOW_OK : GLOW_ERROR_INVALID_OPERATION;
}

glow_result glow__glctx_osmesa_release_current(glow_glctx *ctx) {
    if (OSMesaGetCurrentContext() != (OSMesaContext)ctx->osmesa_context) return GLOW_OK;
    /* A NULL context and NULL buffer unbind the thread's context. */
    return OSMesaMakeCurrent(NULL, NULL, GL_UNSIGNED_BYTE, 0, 0) ? GLOW_OK : GLOW_ERROR_INVALID_OPERATION;
}
