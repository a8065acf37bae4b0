/* glctx_egl.c — glow_glctx on EGL, with no window system and no surface.
 *
 * Displays tried, in order, until one gives a current GL 4.5 core context:
 *   1. hardware devices of EGL_EXT_platform_device (a device whose extensions lack
 *      EGL_MESA_device_software: NVIDIA's driver, a Mesa DRM device), so a real GPU wins over llvmpipe;
 *   2. EGL_PLATFORM_SURFACELESS_MESA (Mesa: render nodes, else llvmpipe);
 *   3. the software devices of (1), only when (2) does not exist;
 *   4. eglGetDisplay(EGL_DEFAULT_DISPLAY).
 * On each: eglInitialize, eglBindAPI(EGL_OPENGL_API), a configless context (EGL_KHR_no_config_context)
 * made current with EGL_NO_SURFACE (EGL_KHR_surfaceless_context); without those, a pbuffer config and,
 * without surfaceless contexts, a 16 x 16 pbuffer.
 *
 * eglTerminate is never called. EGL displays are per-process singletons (one per platform + native
 * display, possibly shared with the host), eglInitialize on an initialised one is a no-op, and
 * terminating the last one would unload the driver: with Mesa 22 every terminate + re-initialise
 * cycle leaks 128 bytes inside the reloaded DRI driver (a pthread_once allocation; LeakSanitizer shows
 * it as "<unknown module>", so it cannot even be suppressed) and costs the driver start-up again
 * (llvmpipe: ~5-10 ms). So an initialised display (llvmpipe's screen and its rasteriser threads)
 * stays until exit, where libEGL's own exit handler releases it. */
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "glctx_internal.h"

#define EGL_MAX_DEVICES 16

/* ------------------------------------------------------------------------------ helpers */

static const char *egl_error_name(EGLint e) {
    switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
    }
}

/* Whole-word search in a space-separated extension string (NULL: none). */
static bool has_extension(const char *list, const char *name) {
    if (!list) return false;
    size_t n = strlen(name);
    for (const char *p = list; (p = strstr(p, name)) != NULL; p += n) {
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    }
    return false;
}

/* "<what> failed (EGL_BAD_MATCH 0x3009)" with the thread's pending EGL error. */
static void egl_fail(char *buf, size_t size, const char *what) {
    EGLint e = eglGetError();
    glow__glctx_appendf(buf, size, "%s failed (%s 0x%04X)", what, egl_error_name(e), (unsigned)e);
}

static glow_gl_proc egl_loader(const char *name) { return (glow_gl_proc)eglGetProcAddress(name); }

/* ------------------------------------------------------------------------------ one display */

/* Initialises `display` and makes a GL 4.5 core context current on it. */
static glow_result try_display(glow_glctx *ctx, EGLDisplay display, const glow_glctx_desc *desc, char *why,
                               size_t why_size) {
    if (display == EGL_NO_DISPLAY) {
        egl_fail(why, why_size, "getting the display");
        return GLOW_ERROR_UNSUPPORTED;
    }
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) {
        egl_fail(why, why_size, "eglInitialize");
        return GLOW_ERROR_UNSUPPORTED;
    }

    EGLContext context = EGL_NO_CONTEXT;
    EGLSurface surface = EGL_NO_SURFACE;
    const char *ext = eglQueryString(display, EGL_EXTENSIONS);
    bool egl15 = major > 1 || minor >= 5;
    if (!egl15 && !has_extension(ext, "EGL_KHR_create_context")) {
        glow__glctx_appendf(why, why_size, "EGL %d.%d without EGL_KHR_create_context", major, minor);
        goto fail;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        egl_fail(why, why_size, "eglBindAPI(EGL_OPENGL_API)");
        goto fail;
    }
    bool configless = has_extension(ext, "EGL_KHR_no_config_context") ||
                      has_extension(ext, "EGL_MESA_configless_context");
    bool surfaceless = has_extension(ext, "EGL_KHR_surfaceless_context");
    EGLConfig config = (EGLConfig)0; /* EGL_NO_CONFIG_KHR */
    if (!configless || !surfaceless) {
        const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                         EGL_RED_SIZE,     8,               EGL_GREEN_SIZE,      8,
                                         EGL_BLUE_SIZE,    8,               EGL_ALPHA_SIZE,      8,
                                         EGL_NONE};
        EGLint n = 0;
        if (!eglChooseConfig(display, config_attribs, &config, 1, &n)) {
            egl_fail(why, why_size, "eglChooseConfig");
            goto fail;
        }
        if (n < 1) {
            glow__glctx_appendf(why, why_size, "no configless context and no RGBA8 pbuffer config for OpenGL");
            goto fail;
        }
    }
    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION_KHR,
                                      4,
                                      EGL_CONTEXT_MINOR_VERSION_KHR,
                                      5,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK_KHR,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT_KHR,
                                      EGL_CONTEXT_FLAGS_KHR,
                                      desc->debug ? EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR : 0,
                                      EGL_NONE};
    context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
    if (context == EGL_NO_CONTEXT) {
        egl_fail(why, why_size, "eglCreateContext(GL 4.5 core)");
        goto fail;
    }
    if (!surfaceless) {
        const EGLint pbuffer_attribs[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
        surface = eglCreatePbufferSurface(display, config, pbuffer_attribs);
        if (surface == EGL_NO_SURFACE) {
            egl_fail(why, why_size, "eglCreatePbufferSurface (no EGL_KHR_surfaceless_context)");
            goto fail;
        }
    }
    if (!eglMakeCurrent(display, surface, surface, context)) {
        egl_fail(why, why_size, "eglMakeCurrent");
        goto fail;
    }
    ctx->egl_display = display;
    ctx->egl_context = context;
    ctx->egl_surface = surface;
    ctx->loader = egl_loader;
    return GLOW_OK;

fail:
    if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
    if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
    return GLOW_ERROR_UNSUPPORTED; /* display stays initialised: see the top of this file */
}

/* ------------------------------------------------------------------------------ back end */

glow_result glow__glctx_egl_create(glow_glctx *ctx, const glow_glctx_desc *desc, char *why, size_t why_size) {
    /* Client extensions (EGL_EXT_client_extensions): NULL when the implementation has none. */
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    (void)eglGetError();
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display = NULL;
    if (has_extension(client, "EGL_EXT_platform_base"))
        get_platform_display = (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");

    EGLDeviceEXT devices[EGL_MAX_DEVICES];
    bool software[EGL_MAX_DEVICES];
    EGLint device_count = 0;
    if (get_platform_display && has_extension(client, "EGL_EXT_platform_device")) {
        PFNEGLQUERYDEVICESEXTPROC query_devices = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
        PFNEGLQUERYDEVICESTRINGEXTPROC query_device_string =
            (PFNEGLQUERYDEVICESTRINGEXTPROC)eglGetProcAddress("eglQueryDeviceStringEXT");
        if (query_devices && query_device_string && query_devices(EGL_MAX_DEVICES, devices, &device_count)) {
            for (EGLint i = 0; i < device_count; ++i)
                software[i] = has_extension(query_device_string(devices[i], EGL_EXTENSIONS), "EGL_MESA_device_software");
        } else {
            device_count = 0;
        }
        (void)eglGetError();
    }
    bool have_surfaceless = get_platform_display && has_extension(client, "EGL_MESA_platform_surfaceless");

    glow_result r = GLOW_ERROR_UNSUPPORTED;
    int tried = 0;
#define GLCTX_TRY(label, display_expr)                                                                  \
    do {                                                                                                \
        glow__glctx_appendf(why, why_size, "%s%s: ", tried++ ? ", " : "", label);                        \
        r = try_display(ctx, (display_expr), desc, why, why_size);                                      \
        if (r == GLOW_OK) goto done;                                                                    \
    } while (0)

    for (EGLint i = 0; i < device_count; ++i) {
        if (software[i]) continue;
        char label[32];
        snprintf(label, sizeof label, "device %d", (int)i);
        GLCTX_TRY(label, get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], NULL));
    }
    if (have_surfaceless) {
        GLCTX_TRY("surfaceless", get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL));
    } else {
        for (EGLint i = 0; i < device_count; ++i) {
            if (!software[i]) continue;
            char label[40];
            snprintf(label, sizeof label, "software device %d", (int)i);
            GLCTX_TRY(label, get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], NULL));
        }
    }
    GLCTX_TRY("default display", eglGetDisplay(EGL_DEFAULT_DISPLAY));
#undef GLCTX_TRY
done:
    if (r == GLOW_OK && why && why_size) why[0] = '\0';
    return r;
}

void glow__glctx_egl_destroy(glow_glctx *ctx) {
    EGLDisplay display = ctx->egl_display;
    if (!display) return;
    glow__glctx_egl_release_current(ctx);
    if (ctx->egl_surface != EGL_NO_SURFACE) eglDestroySurface(display, ctx->egl_surface);
    eglDestroyContext(display, ctx->egl_context);
    ctx->egl_display = ctx->egl_context = ctx->egl_surface = NULL;
    ctx->loader = NULL;
}

glow_result glow__glctx_egl_make_current(glow_glctx *ctx) {
    if (!eglBindAPI(EGL_OPENGL_API)) return GLOW_ERROR_INVALID_OPERATION;
    return eglMakeCurrent(ctx->egl_display, ctx->egl_surface, ctx->egl_surface, ctx->egl_context)
               ? GLOW_OK
               : GLOW_ERROR_INVALID_OPERATION;
}

glow_result glow__glctx_egl_release_current(glow_glctx *ctx) {
    eglBindAPI(EGL_OPENGL_API); /* eglGetCurrentContext answers for the thread's bound API */
    if (eglGetCurrentContext() != (EGLContext)ctx->egl_context) return GLOW_OK;
    return eglMakeCurrent(ctx->egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT)
               ? GLOW_OK
               : GLOW_ERROR_INVALID_OPERATION;
}
