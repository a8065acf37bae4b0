/*
 * glow_gl_loader.h — the one type every GL-side Glow header shares: a GL entry point, and a function
 * returning one by name. eglGetProcAddress, OSMesaGetProcAddress, glfwGetProcAddress and
 * glow_glctx_get_proc_address have this shape. Included by glow_gl.h, glow_gl_lights.h, glow_glctx.h
 * and glow_glfns.h; no GL header is pulled in.
 */
#ifndef GLOW_GLOW_GL_LOADER_H
#define GLOW_GLOW_GL_LOADER_H

#ifdef __cplusplus
extern "C" {
#endif

typedef void (*glow_gl_proc)(void);
typedef glow_gl_proc (*glow_gl_loader)(const char *name);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_GL_LOADER_H */
