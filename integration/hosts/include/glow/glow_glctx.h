/*
 * glow_glctx.h — OpenGL 4.5 core contexts for hosts, samples and tests: headless (EGL surfaceless or
 * OSMesa, Mesa's llvmpipe on machines without a GPU, the vendor driver through EGL where there is one)
 * or a GLFW window. Part of glow_glctx (target glow::glctx, integration/hosts/context/).
 *
 * WHAT IT DOES NOT DO: load GL functions for you (glow_glctx_get_proc_address gives the loader the GL
 * backend, glow_gl.h, and samples use), render, or read pixels: a headless context has no default
 * framebuffer, so draw into a framebuffer object.
 *
 * USAGE
 *   glow_glctx *gl; char why[256];
 *   if (glow_glctx_create(&(glow_glctx_desc){ .kind = GLOW_GLCTX_HEADLESS }, &gl, why, sizeof why) != GLOW_OK)
 *       { fprintf(stderr, "no GL 4.5: %s\n", why); return 77; }
 *   glow_gl_loader load = glow_glctx_get_proc_address(gl);      (current on this thread after create)
 *   ... GL calls ...
 *   glow_glctx_destroy(gl);
 *
 * KINDS: HEADLESS tries EGL first, then OSMesa; EGL and OSMESA force one. EGL tries, in order, a
 * hardware device (EGL_EXT_platform_device: NVIDIA, a Mesa DRM device), Mesa's surfaceless platform
 * (llvmpipe without a GPU), then the default display; it never calls eglTerminate (displays are
 * process-wide, possibly shared with the host; libEGL releases them at exit). WINDOW opens a GLFW
 * window (fails without a display: $DISPLAY / $WAYLAND_DISPLAY unset or unreachable). The
 * environment variable GLOW_GLCTX=egl|osmesa (or auto) overrides what HEADLESS picks (for tests of
 * both paths).
 *
 * ON ERRORS: create returns GLOW_ERROR_UNSUPPORTED when no context of that kind with GL >= 4.5 core
 * can be made (why[] says which step failed for each kind tried, with the EGL/OSMesa/GLFW error),
 * GLOW_ERROR_INVALID_ARGUMENT for NULL, a bad desc or a GLOW_GLCTX value other than egl/osmesa/auto,
 * GLOW_ERROR_OUT_OF_MEMORY. Never exits, never prints (hosts decide; Mesa itself may still log).
 *
 * ON THREADS: a context is current on the thread that created it; to move it, release_current on
 * the old thread, then make_current on the new one (EGL refuses a context current elsewhere). WINDOW
 * contexts follow GLFW's rules: create, destroy, swap (it polls events) on the main thread only.
 */
#ifndef GLOW_GLOW_GLCTX_H
#define GLOW_GLOW_GLCTX_H

#include <stddef.h>
#include <stdint.h>

#include "glow/glow.h"
#include "glow/glow_gl_loader.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum glow_glctx_kind {
    GLOW_GLCTX_HEADLESS = 0, /* EGL, else OSMesa (GLOW_GLCTX=egl|osmesa overrides) */
    GLOW_GLCTX_EGL,          /* EGL device / EGL_PLATFORM_SURFACELESS_MESA / default display, no surface */
    GLOW_GLCTX_OSMESA,       /* OSMesa core profile, drawing into a small private buffer (debug ignored) */
    GLOW_GLCTX_WINDOW,       /* a GLFW window with a GL 4.5 core context */
    GLOW_GLCTX_KIND_FORCE_U32 = 0x7FFFFFFF
} glow_glctx_kind;

typedef struct glow_glctx_desc {
    glow_glctx_kind kind;
    uint32_t width, height; /* window size (default 1280 x 720); unused headless */
    const char *title;      /* window title (default "Glow") */
    int debug;              /* non-zero: request a debug context (KHR_debug messages are the host's to read) */
    int vsync;              /* window only: swap interval 1 (default 0) */
} glow_glctx_desc;

typedef struct glow_glctx glow_glctx;

/** Creates a GL >= 4.5 core context and makes it current on the calling thread. On failure *out is
 * NULL and `why` (may be NULL) holds a one-line reason naming each kind tried ("EGL: surfaceless:
 * eglCreateContext(GL 4.5 core) failed (EGL_BAD_MATCH 0x3009); OSMesa: ..."); on success it is "".
 * \returns GLOW_OK, GLOW_ERROR_UNSUPPORTED, GLOW_ERROR_INVALID_ARGUMENT, GLOW_ERROR_OUT_OF_MEMORY. */
glow_result glow_glctx_create(const glow_glctx_desc *desc, glow_glctx **out, char *why, size_t why_size);
/** Destroys the context (NULL is a no-op); releases it from the calling thread if current. */
void glow_glctx_destroy(glow_glctx *ctx);
/** Makes the context current on the calling thread. \returns GLOW_OK, GLOW_ERROR_INVALID_OPERATION
 * (the driver refused, e.g. current on another thread), GLOW_ERROR_INVALID_ARGUMENT for NULL. */
glow_result glow_glctx_make_current(glow_glctx *ctx);
/** Releases the context from the calling thread if it is current there (no-op otherwise), so that
 * another thread can make it current. \returns GLOW_OK, GLOW_ERROR_INVALID_OPERATION (the driver
 * refused), GLOW_ERROR_INVALID_ARGUMENT for NULL. */
glow_result glow_glctx_release_current(glow_glctx *ctx);
/** The loader for this context's GL functions (valid while it lives; NULL for NULL). Functions from
 * one kind's loader must not be called while another kind's context is current. */
glow_gl_loader glow_glctx_get_proc_address(const glow_glctx *ctx);
/** The kind actually created (EGL, OSMESA or WINDOW; HEADLESS for NULL) and a kind's name ("headless",
 * "egl", "osmesa", "glfw"; "unknown" out of range). */
glow_glctx_kind glow_glctx_get_kind(const glow_glctx *ctx);
const char *glow_glctx_kind_name(glow_glctx_kind kind);
/** GL_RENDERER and GL_VERSION strings of the context (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"),
 * copied at create (valid while it lives, readable when not current; "" for NULL). */
const char *glow_glctx_renderer(const glow_glctx *ctx);
const char *glow_glctx_version(const glow_glctx *ctx);

/* Windows (kind WINDOW); on a headless context these do nothing and should_close returns 0. */
/** The GLFWwindow* (as void*) for input callbacks, or NULL headless. */
void *glow_glctx_window(const glow_glctx *ctx);
/** Presents the back buffer and polls events. */
void glow_glctx_swap(glow_glctx *ctx);
/** Non-zero once the user asked to close the window. */
int glow_glctx_should_close(const glow_glctx *ctx);
/** Framebuffer size in pixels (headless: desc size or 1280 x 720). */
void glow_glctx_framebuffer_size(const glow_glctx *ctx, uint32_t *width, uint32_t *height);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_GLCTX_H */
