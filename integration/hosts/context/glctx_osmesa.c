/* glctx_osmesa.c — glow_glctx on OSMesa (Mesa's off-screen interface; llvmpipe in Mesa >= 20):
 * OSMesaCreateContextAttribs for a 4.5 core profile, made current on a small private RGBA8 buffer
 * (OSMesaMakeCurrent needs one; Glow draws into framebuffer objects, never into it). OSMesa has no
 * debug-context attribute: desc->debug is ignored (Mesa's KHR_debug works without it).
 *
 * libOSMesa is opened with dlopen on first use, not linked: it pulls in Mesa's LLVM (about 130 MB),
 * which a GPU host that only ever uses EGL should not have to ship or load. A machine without it
 * gets GLOW_ERROR_UNSUPPORTED with the loader's message, and HEADLESS falls through as before. */
#include <GL/osmesa.h>
#include <dlfcn.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "glctx_internal.h"

static struct {
    void *lib;
    char error[160];
    OSMesaContext (*create)(const int *, OSMesaContext);
    GLboolean (*make_current)(OSMesaContext, void *, GLenum, GLsizei, GLsizei);
    void (*destroy)(OSMesaContext);
    OSMesaContext (*get_current)(void);
    OSMESAproc (*get_proc)(const char *);
} osm;
static pthread_once_t osm_once = PTHREAD_ONCE_INIT;

static void osm_open(void) {
    /* The soname Mesa has shipped since 2013 first, then the development link. */
    static const char *const names[] = {"libOSMesa.so.8", "libOSMesa.so"};
    for (size_t i = 0; i < sizeof names / sizeof names[0] && !osm.lib; i++) osm.lib = dlopen(names[i], RTLD_NOW | RTLD_LOCAL);
    if (!osm.lib) {
        const char *e = dlerror();
        glow__glctx_appendf(osm.error, sizeof osm.error, "cannot load libOSMesa.so.8: %s", e ? e : "unknown error");
        return;
    }
    /* POSIX allows the object-to-function pointer conversion dlsym needs; C11 does not, hence the copy. */
#define GLOW__OSM_SYM(field, name)                                                                                    \
    do {                                                                                                              \
        void *p = dlsym(osm.lib, name);                                                                              \
        if (!p) {                                                                                                     \
            glow__glctx_appendf(osm.error, sizeof osm.error, "libOSMesa has no %s", name);                          \
            dlclose(osm.lib);                                                                                         \
            osm.lib = NULL;                                                                                           \
            return;                                                                                                   \
        }                                                                                                             \
        memcpy(&osm.field, &p, sizeof p);                                                                            \
    } while (0)
    GLOW__OSM_SYM(create, "OSMesaCreateContextAttribs");
    GLOW__OSM_SYM(make_current, "OSMesaMakeCurrent");
    GLOW__OSM_SYM(destroy, "OSMesaDestroyContext");
    GLOW__OSM_SYM(get_current, "OSMesaGetCurrentContext");
    GLOW__OSM_SYM(get_proc, "OSMesaGetProcAddress");
#undef GLOW__OSM_SYM
}

static glow_gl_proc osmesa_loader(const char *name) { return (glow_gl_proc)osm.get_proc(name); }

static GLboolean make_current(glow_glctx *ctx) {
    return osm.make_current((OSMesaContext)ctx->osmesa_context, ctx->osmesa_buffer, GL_UNSIGNED_BYTE,
                            GLOW__OSMESA_SIZE, GLOW__OSMESA_SIZE);
}

glow_result glow__glctx_osmesa_create(glow_glctx *ctx, const glow_glctx_desc *desc, char *why, size_t why_size) {
    (void)desc;
    pthread_once(&osm_once, osm_open);
    if (!osm.lib) {
        glow__glctx_appendf(why, why_size, "%s", osm.error);
        return GLOW_ERROR_UNSUPPORTED;
    }
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
    OSMesaContext context = osm.create(attribs, NULL);
    if (!context) {
        glow__glctx_appendf(why, why_size, "OSMesaCreateContextAttribs(core 4.5) returned NULL");
        free(buffer);
        return GLOW_ERROR_UNSUPPORTED;
    }
    ctx->osmesa_context = context;
    ctx->osmesa_buffer = buffer;
    if (!make_current(ctx)) {
        glow__glctx_appendf(why, why_size, "OSMesaMakeCurrent failed");
        osm.destroy(context);
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
    osm.destroy((OSMesaContext)ctx->osmesa_context);
    free(ctx->osmesa_buffer);
    ctx->osmesa_context = NULL;
    ctx->osmesa_buffer = NULL;
    ctx->loader = NULL;
}

glow_result glow__glctx_osmesa_make_current(glow_glctx *ctx) {
    return make_current(ctx) ? GLOW_OK : GLOW_ERROR_INVALID_OPERATION;
}

glow_result glow__glctx_osmesa_release_current(glow_glctx *ctx) {
    if (osm.get_current() != (OSMesaContext)ctx->osmesa_context) return GLOW_OK;
    /* A NULL context and NULL buffer unbind the thread's context. */
    return osm.make_current(NULL, NULL, GL_UNSIGNED_BYTE, 0, 0) ? GLOW_OK : GLOW_ERROR_INVALID_OPERATION;
}
