/* render_internal.h — what the glow_render library's files share (not installed). */
#ifndef GLOW_RENDER_INTERNAL_H
#define GLOW_RENDER_INTERNAL_H

#include <stdarg.h>
#include <stdbool.h>

#include "glow_render.h"
#include "render_bsdf.h"
#include "glow/glow_pc_kit.h" /* the linker's scene kit: scene, rays, pool (not precompute/src) */

struct glow_render_scene {
    char path[512];            /* the scene description file, as given */
    glow_scene_desc desc;
    glow_scene_camera camera;  /* resolved */
    glow__scene mesh;
    glow__rt *rt;
    glow__log log;
    float (*ng)[3];            /* [tri_count] unit geometric normal (p1-p0)x(p2-p0) */
    float *tri_area;           /* [tri_count] */
    /* emitters (material emission > 0, front face), sampled by area x luminance */
    uint32_t emitter_count;
    uint32_t *emitter_tri;     /* [emitter_count] */
    double *emitter_cdf;       /* [emitter_count], last = 1 */
    float *light_pdf_area;     /* [tri_count]: luminance / Σ(area x luminance), the area-measure pdf of
                                  next-event estimation on that triangle (0 for non-emitters) */
    glow__render_ggx *ggx;     /* [material_count]: the material's GGX layer (roughness 0 = none), or NULL
                                  when no material has one */
    uint32_t glossy_count;     /* materials with a GGX layer */
    float eps;                 /* ray offset: 1e-4 x bounds diagonal (glow_host's) */
    float diag;
};

/* Writes "fmt..." into message (truncated; message may be NULL). Returns `code`. */
glow_result glow__render_fail(char *message, size_t message_size, glow_result code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

#endif /* GLOW_RENDER_INTERNAL_H */
