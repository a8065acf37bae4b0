/* shadow_map.h — software depth maps for glow_host's shadow-map kind (internal to glow_host).
 *
 * A map is a square depth image seen from a light: orthographic (sun) or perspective (spot, cube
 * faces). Each texel holds the smallest view-axis distance z = (p - origin)·axis of the triangles
 * covering the texel's centre (both faces), +INF where none does. Rendering is single-threaded,
 * lookups are read-only and thread-safe. */
#ifndef GLOW_INTEGRATION_SHADOW_MAP_H
#define GLOW_INTEGRATION_SHADOW_MAP_H

#include <stdbool.h>
#include <stdint.h>

typedef struct glow__depth_map {
    bool persp;
    float origin[3];         /* ortho: reference point (bounds centre); persp: the eye */
    float ax[3], ay[3], az[3]; /* right, up, view axis (unit, orthonormal) */
    float inv_s;             /* persp: 1 / tan(half field of view) */
    float off_x, off_y;      /* ortho: view-plane coordinates of texel corner (0, 0) */
    float texel;             /* ortho: texel size in m; persp: texel size at z = 1 */
    float near_z;            /* persp: near plane (m); geometry closer is clipped away */
    float box_z[2];          /* ortho: view-axis distance of the box's nearest and farthest corner */
    float extent;            /* ortho: the box's larger side across the view axis (m) */
    uint32_t res;
    float *depth;            /* res*res, row-major, +INF = empty */
} glow__depth_map;

typedef struct glow__shadow_params {
    float depth_bias, slope_bias, normal_offset; /* in texels */
    int pcf_radius;                              /* kernel is (2r+1)² texels */
} glow__shadow_params;

/* An orthographic map looking along unit `dir` that covers the box [bmin, bmax] with `margin`
 * texels to spare on each side. */
void glow__dm_setup_ortho(glow__depth_map *m, const float dir[3], const float bmin[3], const float bmax[3], uint32_t res,
                          uint32_t margin);
/* A perspective map from `eye` along unit `axis`, covering the cone of half-angle atan(tan_half) with
 * `margin` texels to spare. */
void glow__dm_setup_persp(glow__depth_map *m, const float eye[3], const float axis[3], float tan_half, uint32_t res,
                          uint32_t margin, float near_z);
/* The 6 faces of a cube map around `eye` (m[0..5] = +x, -x, +y, -y, +z, -z). */
void glow__dm_setup_cube(glow__depth_map m[6], const float eye[3], uint32_t res, uint32_t margin, float near_z);
/* Allocates (or keeps) m->depth for m->res and renders the triangles (9 floats each) into it.
 * Returns false when out of memory (m->depth is then NULL). */
bool glow__dm_render(glow__depth_map *m, const float *tris, uint32_t tri_count);
void glow__dm_free(glow__depth_map *m);

/* Fraction of PCF taps in which the point p (unit normal n, unit direction to the light l) is lit. */
float glow__dm_visibility(const glow__depth_map *m, const float p[3], const float n[3], const float l[3],
                          const glow__shadow_params *sp);
/* The face of a cube map (setup_cube order) that direction d (from the eye) falls in. */
int glow__dm_cube_face(const float d[3]);

#endif
