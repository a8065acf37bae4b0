/* 03_dynamic_object — a dynamic object lit by Glow: a sphere moving through the baked scene, shaded
 * per pixel from the GRID caches (glow_sample_grid_oriented in GLSL: the trilinear lookup of the 3D texture of
 * SH caches at the pixel's position, convolved with its normal's cosine lobe) plus the direct light of
 * the GPU lights' hook, drawn with the static scene (lightmap caches) by samples/common/sample_gl.h.
 *
 * The sphere is not part of the bake: it receives indirect light but neither casts shadows (the lights'
 * maps hold the bake's triangles only) nor blocks or bounces light for the static scene.
 *
 * Usage: sample-03_dynamic_object BAKE [--headless] [--frames N] [--out DIR] [--view V] [--width W --height H]
 *        [--scene JSON] [...]   (--help; keys in samples/common/sample_gl.h). The links view shows the
 *        links of the cache nearest the sphere's centre (unless --pick).
 * Without --scene: lamp on and one static point light 20% of the height under the ceiling.
 * Exit: 0 ok, 1 file or runtime error, 2 usage, 77 no OpenGL 4.5 context. */
#include <math.h>
#include <stdio.h>

#define SAMPLE_GL_APP
#include "sample_gl.h" /* samples/common: the renderer and the frame loop the GL samples share */

int main(int argc, char **argv) {
    sample_app a;
    int status = sample_app_init(&a, argc, argv, NULL);
    if (status >= 0) return status;

    glow_scene_light def = {.type = GLOW_SCENE_LIGHT_POINT,
                            .position = {a.centre[0], a.info.bounds_min[1] + 0.8f * a.size[1], a.centre[2]},
                            .intensity = {1.8f, 1.3f, 0.45f}};
    const glow_scene_light *lights = a.has_scene ? a.scene.lights : &def;
    const uint32_t light_count = a.has_scene ? a.scene.light_count : 1;
    if (sample_app_set_lights(&a, lights, light_count) != 0) status = 1; /* static: shadow maps rendered once */

    /* The sphere's path: a horizontal figure in the front half of the bounds, 60-75% up (in the Cornell
     * box: x in +-0.55 m, 0.9-1.5 m high, z 0.44 m: clear of both blocks), one lap in about 9 s. */
    const float radius = 0.1f * fminf(a.size[0], fminf(a.size[1], a.size[2]));
    sample_gl_sphere sphere = {.radius = radius, .albedo = {0.8f, 0.8f, 0.8f}};
    printf("sphere: radius %.3f m, albedo %.2f, shaded from the grid (%ux%ux%u cells)\n", radius, sphere.albedo[0],
           a.info.grid_dims[0], a.info.grid_dims[1], a.info.grid_dims[2]);
    for (long f = 0; status < 0; f++) {
        float t = sample_app_time(&a, f);
        sphere.center[0] = a.centre[0] + 0.275f * a.size[0] * sinf(0.7f * t);
        sphere.center[1] = a.info.bounds_min[1] + a.size[1] * (0.6f + 0.15f * cosf(1.4f * t));
        sphere.center[2] = a.centre[2] + 0.22f * a.size[2];
        status = sample_app_frame(&a, f, &sphere, 1, sphere.center);
    }
    sample_app_destroy(&a);
    return status;
}
