/* 01_cornell — Glow on the GPU: the Cornell box drawn with OpenGL 4.5, its indirect light solved by
 * the GL backend (glow_gl.h) every frame, two kinds of dynamic light at once:
 *   1. a moving, colour-changing point light (or --spot) with GPU shadow maps (glow_gl_lights.h). Its
 *      GLSL hook lights Glow's surfels on the GPU AND the screen's pixels: one light function for both;
 *   2. an ANIMATED TEXTURED AREA LIGHT: the ceiling lamp's emission changes every frame, a travelling
 *      stripe pattern written into an emission texture that Glow samples at the lamp's surfels
 *      (glow_system_set_emission_texture, through the bake's material UVs: builtin:cornell's lamp
 *      spans [0,1]²) and, the same pattern in GLSL, at its pixels. A bake whose lamp has no UVs, or
 *      UVs that do not run along x, gets the pattern per surfel instead (glow_system_set_surfel_emission).
 *      Area lights need no shadow maps: Glow's bounce carries their light.
 * Every frame: move the light (renders its cube shadow map), write the lamp's emission, update the GL
 * system, draw (sample_gl.h: direct from the hook, indirect from the lightmap SH, emission), show it or
 * write DIR/frame_NNN.png, and print the GPU ms per stage.
 *
 * Usage: sample-01_cornell BAKE [--headless] [--frames N] [--out DIR] [--view V] [--width W --height H]
 *        [--scene JSON] [--spot] [--static-light] [...]   (--help; keys in samples/common/sample_gl.h)
 * Without --scene: camera glow_scene_camera_default on the bake's bounds, lamp on (emission scale 1),
 * one point light circling under the ceiling. With --scene (e.g. scenes/cornell-builtin-point.json):
 * its camera, lights (the first point/spot one circles around its position), sky and emission_scale.
 * Exit: 0 ok, 1 file or runtime error, 2 usage, 77 no OpenGL 4.5 context. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SAMPLE_GL_APP
#include "sample_gl.h" /* samples/common: the renderer and the frame loop the GL samples share */

/* The lamp's pattern: stripes across x travelling at 0.25 m/s, 0.15x .. 1.85x the lamp's own
 * emission (mean 1), tinted: the bands run from warm to cool. One function, twice: in C for the
 * surfels (what Glow bounces), in GLSL for the pixels (what the camera sees). Keep them equal. */
#define STRIPE_PERIOD_M 0.24f
#define STRIPE_SPEED_MPS 0.25f
static void lamp_pattern(const float p[3], float t, float out[3]) {
    float s = 0.5f + 0.5f * sinf(2.0f * 3.14159265f * (p[0] - STRIPE_SPEED_MPS * t) / STRIPE_PERIOD_M);
    float k = 0.15f + 1.7f * s;
    out[0] = k * (0.8f + 0.4f * s), out[1] = k, out[2] = k * (1.2f - 0.4f * s);
}
static const char *const LAMP_GLSL =
    "#define SAMPLE_EMISSION_DEFINED\n"
    "vec3 sample_emission(vec3 p, vec3 n, uint material, vec3 base) {\n"
    "    float s = 0.5 + 0.5 * sin(2.0 * 3.14159265 * (p.x - 0.25 * u_time) / 0.24);\n"
    "    float k = 0.15 + 1.7 * s;\n"
    "    return base * vec3(k * (0.8 + 0.4 * s), k, k * (1.2 - 0.4 * s));\n"
    "}\n";

/* The emission texture: TEX_W texels along u (the pattern's x), TEX_H rows (the same values). */
#define TEX_W 64u
#define TEX_H 4u

/* Whether the lamp's surfels (one emissive material) have UVs with x = a + b u (to 1 mm): then the
 * pattern, a function of x, is a function of u and one texture drives the whole lamp. */
static bool lamp_u_maps_x(const glow_surfel_view *sv, const uint32_t *emitters, uint32_t n, float *a, float *b) {
    if (!sv->uv0 || n < 2) return false;
    double su = 0, sx = 0, suu = 0, sux = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (sv->materials[emitters[i]] != sv->materials[emitters[0]]) return false;
        double u = sv->uv0[2 * (size_t)emitters[i]], x = sv->positions[4 * (size_t)emitters[i]];
        su += u, sx += x, suu += u * u, sux += u * x;
    }
    double det = n * suu - su * su;
    if (!(fabs(det) > 1e-12)) return false;
    *b = (float)((n * sux - su * sx) / det);
    *a = (float)((sx - *b * su) / n);
    for (uint32_t i = 0; i < n; i++)
        if (fabsf(*a + *b * sv->uv0[2 * (size_t)emitters[i]] - sv->positions[4 * (size_t)emitters[i]]) > 1e-3f)
            return false;
    return true;
}

/* A hue on the colour wheel, with a constant luma (Y = R/4 + G/2 + B/4) of 1/2. */
static void hue(float h, float out[3]) {
    for (int c = 0; c < 3; c++) out[c] = 0.5f + 0.5f * cosf(2.0f * 3.14159265f * (h - (float)c / 3.0f));
    float y = 0.25f * out[0] + 0.5f * out[1] + 0.25f * out[2];
    for (int c = 0; c < 3; c++) out[c] *= 0.5f / fmaxf(y, 1e-3f);
}

int main(int argc, char **argv) {
    /* --spot and --static-light are this sample's own options: take them out before the shared parser
     * sees the line */
    bool spot = false, still = false, help = false;
    int n = 0;
    for (int i = 0; i < argc; i++) {
        help |= i > 0 && (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h"));
        if (i > 0 && !strcmp(argv[i], "--spot")) spot = true;
        else if (i > 0 && !strcmp(argv[i], "--static-light")) still = true;
        else argv[n++] = argv[i];
    }
    argc = n;
    sample_app a;
    int status = sample_app_init(&a, argc, argv, LAMP_GLSL);
    if (status == 0 && help)
        printf("and: --spot (a spot light instead of the point light), --static-light (light 0 stays where it is, in\n"
               "  its colour: only the lamp's animated emission changes)\n");
    if (status >= 0) return status;

    /* The lights: the scene's, or one point (spot) light. Light 0 moves when it is a point or spot. */
    glow_scene_light def = {.type = spot ? GLOW_SCENE_LIGHT_SPOT : GLOW_SCENE_LIGHT_POINT,
                            .position = {a.centre[0], a.info.bounds_min[1] + 0.8f * a.size[1], a.centre[2]},
                            .direction = {0, -1, 0}, .intensity = {2.0f, 2.0f, 2.0f}, .outer_deg = 30.0f, .inner_deg = 20.0f};
    if (spot) def.position[1] = a.info.bounds_min[1] + 0.95f * a.size[1], def.intensity[0] = def.intensity[1] = def.intensity[2] = 8.0f;
    uint32_t light_count = a.has_scene ? a.scene.light_count : 1;
    glow_scene_light *lights = calloc(light_count ? light_count : 1, sizeof *lights);
    if (!lights) {
        fprintf(stderr, "%s: out of memory\n", argv[0]);
        sample_app_destroy(&a);
        return 1;
    }
    if (a.has_scene) memcpy(lights, a.scene.lights, light_count * sizeof *lights);
    else lights[0] = def;
    const glow_scene_light base = lights[0];
    const bool moving = !still && light_count > 0 && (base.type == GLOW_SCENE_LIGHT_POINT || base.type == GLOW_SCENE_LIGHT_SPOT);
    const float radius = 0.25f * fminf(a.size[0], a.size[2]);

    /* The lamp: every surfel whose material emits. Its base emission is kept; each frame writes
     * base x pattern for those surfels (runs of consecutive indices, one call per run). */
    glow_surfel_view sv;
    glow_solver_tables tables;
    glow_system_get_surfels(a.sys, &sv);
    glow_system_get_solver_tables(a.sys, &tables);
    uint32_t *emitters = malloc(((size_t)sv.count + 1) * sizeof *emitters);
    float *base_emission = malloc(((size_t)sv.count + 1) * 3 * sizeof *base_emission);
    float *emission = malloc(((size_t)sv.count + 1) * 3 * sizeof *emission);
    uint32_t emitter_count = 0;
    if (!emitters || !base_emission || !emission) status = 1;
    for (uint32_t s = 0; status < 0 && s < sv.count; s++) {
        const float *e = tables.emission + 3 * (size_t)s;
        if (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f) {
            memcpy(base_emission + 3 * (size_t)emitter_count, e, 3 * sizeof(float));
            emitters[emitter_count++] = s;
        }
    }
    float ua = 0.0f, ub = 0.0f;
    const bool textured = status < 0 && lamp_u_maps_x(&sv, emitters, emitter_count, &ua, &ub);
    float *texture = textured ? malloc((size_t)TEX_W * TEX_H * 3 * sizeof *texture) : NULL;
    if (textured && !texture) status = 1;
    if (status < 0) {
        glow_system_params p;
        glow_system_get_params(a.sys, &p);
        printf("lamp: %u emissive surfels, animated (emission scale %.2f)%s; %s; light 0: %s, %s\n", emitter_count,
               p.emission_scale, p.emission_scale == 0.0f ? " - off in this scene: the pattern has no effect" : "",
               textured ? "an emission texture of 64 x 4 texels through its UVs" : "per surfel (its UVs do not run along x)",
               light_count ? glow_scene_light_type_name(base.type) : "none", moving ? "moving, changing colour" : "static");
    }

    for (long f = 0; status < 0; f++) {
        float t = sample_app_time(&a, f);
        if (moving) { /* circle around the base position, one turn in 9 s, hue cycling every 12 s */
            glow_scene_light *l = &lights[0];
            l->position[0] = base.position[0] + radius * cosf(0.7f * t);
            l->position[2] = base.position[2] + radius * sinf(0.7f * t);
            float h[3], power = a.has_scene ? 0.25f * base.intensity[0] + 0.5f * base.intensity[1] + 0.25f * base.intensity[2]
                                            : 2.0f;
            hue(t / 12.0f, h);
            for (int c = 0; c < 3; c++) l->intensity[c] = 2.0f * power * h[c];
        }
        if ((f == 0 || moving) && sample_app_set_lights(&a, lights, light_count) != 0) {
            status = 1;
            break;
        }
        if (textured) { /* the pattern at each texel's u, times the lamp's own emission: W/(m²·sr) */
            for (uint32_t i = 0; i < TEX_W; i++) {
                const float p[3] = {ua + ub * ((float)i + 0.5f) / (float)TEX_W, 0.0f, 0.0f};
                float k[3];
                lamp_pattern(p, t, k);
                for (uint32_t r = 0; r < TEX_H; r++)
                    for (int c = 0; c < 3; c++) texture[3 * ((size_t)r * TEX_W + i) + c] = k[c] * base_emission[c];
            }
            if (glow_system_set_emission_texture(a.sys, sv.materials[emitters[0]], texture, TEX_W, TEX_H, 1.0f) != GLOW_OK) {
                fprintf(stderr, "%s: glow_system_set_emission_texture failed\n", argv[0]);
                status = 1;
            }
        } else {
            for (uint32_t i = 0; i < emitter_count; i++)
                lamp_pattern(sv.positions + 4 * (size_t)emitters[i], t, emission + 3 * (size_t)i);
            for (uint32_t i = 0; i < emitter_count; i++) emission[3 * i] *= base_emission[3 * i],
                                                         emission[3 * i + 1] *= base_emission[3 * i + 1],
                                                         emission[3 * i + 2] *= base_emission[3 * i + 2];
            for (uint32_t i = 0, j; i < emitter_count; i = j) { /* one call per run of consecutive surfels */
                for (j = i + 1; j < emitter_count && emitters[j] == emitters[j - 1] + 1; j++) {}
                if (glow_system_set_surfel_emission(a.sys, emitters[i], j - i, emission + 3 * (size_t)i) != GLOW_OK) {
                    fprintf(stderr, "%s: glow_system_set_surfel_emission failed\n", argv[0]);
                    status = 1;
                }
            }
        }
        if (status < 0) status = sample_app_frame(&a, f, NULL, 0, NULL);
    }
    free(texture);
    free(emitters);
    free(base_emission);
    free(emission);
    free(lights);
    sample_app_destroy(&a);
    return status;
}
