/* glctx.c — glow_glctx (glow_glctx.h): the front. Validates the desc, picks the back ends to try
 * (HEADLESS: EGL, then OSMesa; GLOW_GLCTX=egl|osmesa forces one), checks that what was made is
 * GL >= 4.5 (glGetString through the context's own loader: libGL is never linked) and composes
 * the one-line reason on failure ("EGL: ...; OSMesa: ..."). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glctx_internal.h"

#define GLCTX_DEFAULT_WIDTH 1280u
#define GLCTX_DEFAULT_HEIGHT 720u
#define GLCTX_MAX_SIZE 16384u
#define GLCTX_GL_RENDERER 0x1F01
#define GLCTX_GL_VERSION 0x1F02

typedef const unsigned char *(*glctx_get_string_fn)(unsigned int name);

void glow__glctx_appendf(char *buf, size_t size, const char *fmt, ...) {
    if (!buf || size == 0) return;
    size_t len = strnlen(buf, size);
    if (len >= size - 1) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + len, size - len, fmt, ap);
    va_end(ap);
}

static void set_why(char *why, size_t why_size, const char *text) {
    if (why && why_size) snprintf(why, why_size, "%s", text);
}

static void destroy_backend(glow_glctx *ctx) {
    switch (ctx->kind) {
    case GLOW_GLCTX_EGL: glow__glctx_egl_destroy(ctx); break;
    case GLOW_GLCTX_OSMESA: glow__glctx_osmesa_destroy(ctx); break;
    case GLOW_GLCTX_WINDOW: glow__glctx_glfw_destroy(ctx); break;
    default: break;
    }
}

/* Reads GL_RENDERER / GL_VERSION into ctx and checks the version is >= 4.5. */
static glow_result check_version(glow_glctx *ctx, char *why, size_t why_size) {
    glctx_get_string_fn get_string = (glctx_get_string_fn)ctx->loader("glGetString");
    if (!get_string) {
        glow__glctx_appendf(why, why_size, "glGetString not found by the context's GetProcAddress");
        return GLOW_ERROR_UNSUPPORTED;
    }
    const unsigned char *renderer = get_string(GLCTX_GL_RENDERER), *version = get_string(GLCTX_GL_VERSION);
    if (!version) {
        glow__glctx_appendf(why, why_size, "glGetString(GL_VERSION) returned NULL");
        return GLOW_ERROR_UNSUPPORTED;
    }
    snprintf(ctx->renderer, sizeof ctx->renderer, "%s", renderer ? (const char *)renderer : "");
    snprintf(ctx->version, sizeof ctx->version, "%s", (const char *)version);
    int major = 0, minor = 0;
    if (sscanf(ctx->version, "%d.%d", &major, &minor) != 2) {
        glow__glctx_appendf(why, why_size, "GL_VERSION \"%s\" does not start with <major>.<minor>", ctx->version);
        return GLOW_ERROR_UNSUPPORTED;
    }
    if (major < 4 || (major == 4 && minor < 5)) {
        glow__glctx_appendf(why, why_size, "GL_VERSION \"%s\" is below 4.5 (renderer \"%s\")", ctx->version,
                            ctx->renderer);
        return GLOW_ERROR_UNSUPPORTED;
    }
    return GLOW_OK;
}

/* One back end: create, then check the version (destroying on a failed check). */
static glow_result try_kind(glow_glctx *ctx, glow_glctx_kind kind, const glow_glctx_desc *desc, char *why,
                            size_t why_size) {
    glow_result r;
    switch (kind) {
    case GLOW_GLCTX_EGL: r = glow__glctx_egl_create(ctx, desc, why, why_size); break;
    case GLOW_GLCTX_OSMESA: r = glow__glctx_osmesa_create(ctx, desc, why, why_size); break;
    default: r = glow__glctx_glfw_create(ctx, desc, why, why_size); break;
    }
    if (r != GLOW_OK) return r;
    ctx->kind = kind;
    r = check_version(ctx, why, why_size);
    if (r != GLOW_OK) {
        destroy_backend(ctx);
        ctx->kind = GLOW_GLCTX_HEADLESS;
        ctx->loader = NULL;
    }
    return r;
}

static const char *kind_label(glow_glctx_kind kind) {
    switch (kind) {
    case GLOW_GLCTX_EGL: return "EGL";
    case GLOW_GLCTX_OSMESA: return "OSMesa";
    default: return "GLFW";
    }
}

glow_result glow_glctx_create(const glow_glctx_desc *desc, glow_glctx **out, char *why, size_t why_size) {
    if (why && why_size) why[0] = '\0';
    if (out) *out = NULL;
    if (!desc || !out) {
        set_why(why, why_size, !desc ? "glow_glctx_create: desc is NULL" : "glow_glctx_create: out is NULL");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if ((uint32_t)desc->kind > (uint32_t)GLOW_GLCTX_WINDOW) {
        char msg[96];
        snprintf(msg, sizeof msg, "glow_glctx_create: unknown kind %u", (unsigned)desc->kind);
        set_why(why, why_size, msg);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (desc->width > GLCTX_MAX_SIZE || desc->height > GLCTX_MAX_SIZE) {
        char msg[128];
        snprintf(msg, sizeof msg, "glow_glctx_create: size %u x %u is larger than %u", (unsigned)desc->width,
                 (unsigned)desc->height, GLCTX_MAX_SIZE);
        set_why(why, why_size, msg);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }

    glow_glctx_kind order[2] = {desc->kind, GLOW_GLCTX_HEADLESS};
    int count = 1;
    if (desc->kind == GLOW_GLCTX_HEADLESS) {
        const char *env = getenv("GLOW_GLCTX");
        if (!env || !env[0] || strcmp(env, "auto") == 0) {
            order[0] = GLOW_GLCTX_EGL;
            order[1] = GLOW_GLCTX_OSMESA;
            count = 2;
        } else if (strcmp(env, "egl") == 0) {
            order[0] = GLOW_GLCTX_EGL;
        } else if (strcmp(env, "osmesa") == 0) {
            order[0] = GLOW_GLCTX_OSMESA;
        } else {
            char msg[160];
            snprintf(msg, sizeof msg, "GLOW_GLCTX=\"%.64s\" in the environment: expected egl, osmesa or auto", env);
            set_why(why, why_size, msg);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    }

    glow_glctx *ctx = calloc(1, sizeof *ctx); /* host code: plain malloc, see glctx_internal.h */
    if (!ctx) {
        set_why(why, why_size, "glow_glctx_create: out of memory");
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    ctx->width = desc->width ? desc->width : GLCTX_DEFAULT_WIDTH;
    ctx->height = desc->height ? desc->height : GLCTX_DEFAULT_HEIGHT;

    char reasons[1024] = "";
    glow_result r = GLOW_ERROR_UNSUPPORTED;
    for (int i = 0; i < count; ++i) {
        char one[768] = "";
        r = try_kind(ctx, order[i], desc, one, sizeof one);
        if (r == GLOW_OK) break;
        glow__glctx_appendf(reasons, sizeof reasons, "%s%s: %s", i ? "; " : "", kind_label(order[i]),
                            one[0] ? one : "failed");
        if (r == GLOW_ERROR_OUT_OF_MEMORY) break;
    }
    if (r != GLOW_OK) {
        set_why(why, why_size, reasons);
        free(ctx);
        return r;
    }
    *out = ctx;
    return GLOW_OK;
}

void glow_glctx_destroy(glow_glctx *ctx) {
    if (!ctx) return;
    destroy_backend(ctx);
    free(ctx);
}

glow_result glow_glctx_make_current(glow_glctx *ctx) {
    if (!ctx) return GLOW_ERROR_INVALID_ARGUMENT;
    switch (ctx->kind) {
    case GLOW_GLCTX_EGL: return glow__glctx_egl_make_current(ctx);
    case GLOW_GLCTX_OSMESA: return glow__glctx_osmesa_make_current(ctx);
    case GLOW_GLCTX_WINDOW: return glow__glctx_glfw_make_current(ctx);
    default: return GLOW_ERROR_INVALID_OPERATION;
    }
}

glow_result glow_glctx_release_current(glow_glctx *ctx) {
    if (!ctx) return GLOW_ERROR_INVALID_ARGUMENT;
    switch (ctx->kind) {
    case GLOW_GLCTX_EGL: return glow__glctx_egl_release_current(ctx);
    case GLOW_GLCTX_OSMESA: return glow__glctx_osmesa_release_current(ctx);
    case GLOW_GLCTX_WINDOW: return glow__glctx_glfw_release_current(ctx);
    default: return GLOW_ERROR_INVALID_OPERATION;
    }
}

glow_gl_loader glow_glctx_get_proc_address(const glow_glctx *ctx) { return ctx ? ctx->loader : NULL; }

glow_glctx_kind glow_glctx_get_kind(const glow_glctx *ctx) { return ctx ? ctx->kind : GLOW_GLCTX_HEADLESS; }

const char *glow_glctx_kind_name(glow_glctx_kind kind) {
    switch (kind) {
    case GLOW_GLCTX_HEADLESS: return "headless";
    case GLOW_GLCTX_EGL: return "egl";
    case GLOW_GLCTX_OSMESA: return "osmesa";
    case GLOW_GLCTX_WINDOW: return "glfw";
    default: return "unknown";
    }
}

const char *glow_glctx_renderer(const glow_glctx *ctx) { return ctx ? ctx->renderer : ""; }
const char *glow_glctx_version(const glow_glctx *ctx) { return ctx ? ctx->version : ""; }

void *glow_glctx_window(const glow_glctx *ctx) { return ctx ? ctx->window : NULL; }

void glow_glctx_swap(glow_glctx *ctx) {
    if (ctx && ctx->kind == GLOW_GLCTX_WINDOW) glow__glctx_glfw_swap(ctx);
}

int glow_glctx_should_close(const glow_glctx *ctx) {
    return ctx && ctx->kind == GLOW_GLCTX_WINDOW ? glow__glctx_glfw_should_close(ctx) : 0;
}

void glow_glctx_framebuffer_size(const glow_glctx *ctx, uint32_t *width, uint32_t *height) {
    uint32_t w = 0, h = 0;
    if (ctx && ctx->kind == GLOW_GLCTX_WINDOW) {
        glow__glctx_glfw_framebuffer_size(ctx, &w, &h);
    } else if (ctx) {
        w = ctx->width;
        h = ctx->height;
    }
    if (width) *width = w;
    if (height) *height = h;
}
