/* glctx_glfw.c — glow_glctx windows through GLFW 3 (GL 4.5 core, forward-compatible, optionally a
 * debug context). GLFW is initialised by the first window and terminated with the last one. GLFW
 * wants glfwInit, window creation/destruction and event polling on the main thread, so these are
 * too (no lock: the user count is main-thread state like GLFW's own).
 *
 * GLFW's error callback is process-global: it is set only for the duration of create (the host's
 * callback is put back after) and writes into a thread-local buffer that becomes the `why` text. */
#include <GLFW/glfw3.h>
#include <stdio.h>

#include "glctx_internal.h"

static _Thread_local char g_glfw_error[256];
static int g_glfw_users; /* live windows; glfwTerminate when it drops to 0 */

static void on_glfw_error(int code, const char *description) {
    snprintf(g_glfw_error, sizeof g_glfw_error, "%s (GLFW error 0x%X)", description ? description : "?",
             (unsigned)code);
}

static glow_gl_proc glfw_loader(const char *name) { return (glow_gl_proc)glfwGetProcAddress(name); }

static void glfw_release(void) {
    if (g_glfw_users > 0 && --g_glfw_users == 0) glfwTerminate();
}

glow_result glow__glctx_glfw_create(glow_glctx *ctx, const glow_glctx_desc *desc, char *why, size_t why_size) {
    g_glfw_error[0] = '\0';
    GLFWerrorfun previous = glfwSetErrorCallback(on_glfw_error);
    glow_result r = GLOW_ERROR_UNSUPPORTED;
    if (g_glfw_users == 0 && !glfwInit()) {
        glow__glctx_appendf(why, why_size, "glfwInit failed: %s",
                            g_glfw_error[0] ? g_glfw_error : "no reason given (no display?)");
        goto out;
    }
    g_glfw_users++;
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, desc->debug ? GLFW_TRUE : GLFW_FALSE);
    GLFWwindow *window = glfwCreateWindow((int)ctx->width, (int)ctx->height, desc->title ? desc->title : "Glow",
                                          NULL, NULL);
    if (!window) {
        glow__glctx_appendf(why, why_size, "glfwCreateWindow(GL 4.5 core) failed: %s",
                            g_glfw_error[0] ? g_glfw_error : "no reason given");
        glfw_release();
        goto out;
    }
    glfwMakeContextCurrent(window);
    glfwSwapInterval(desc->vsync ? 1 : 0);
    ctx->window = window;
    ctx->loader = glfw_loader;
    r = GLOW_OK;
out:
    glfwSetErrorCallback(previous);
    return r;
}

void glow__glctx_glfw_destroy(glow_glctx *ctx) {
    if (!ctx->window) return;
    glfwDestroyWindow((GLFWwindow *)ctx->window); /* detaches the context if current here */
    ctx->window = NULL;
    ctx->loader = NULL;
    glfw_release();
}

glow_result glow__glctx_glfw_make_current(glow_glctx *ctx) {
    glfwMakeContextCurrent((GLFWwindow *)ctx->window);
    return glfwGetCurrentContext() == (GLFWwindow *)ctx->window ? GLOW_OK : GLOW_ERROR_INVALID_OPERATION;
}

glow_result glow__glctx_glfw_release_current(glow_glctx *ctx) {
    if (glfwGetCurrentContext() == (GLFWwindow *)ctx->window) glfwMakeContextCurrent(NULL);
    return glfwGetCurrentContext() == (GLFWwindow *)ctx->window ? GLOW_ERROR_INVALID_OPERATION : GLOW_OK;
}

void glow__glctx_glfw_swap(glow_glctx *ctx) {
    glfwSwapBuffers((GLFWwindow *)ctx->window);
    glfwPollEvents();
}

int glow__glctx_glfw_should_close(const glow_glctx *ctx) {
    return glfwWindowShouldClose((GLFWwindow *)ctx->window) ? 1 : 0;
}

void glow__glctx_glfw_framebuffer_size(const glow_glctx *ctx, uint32_t *width, uint32_t *height) {
    int w = 0, h = 0;
    glfwGetFramebufferSize((GLFWwindow *)ctx->window, &w, &h);
    *width = w > 0 ? (uint32_t)w : 0;
    *height = h > 0 ? (uint32_t)h : 0;
}
