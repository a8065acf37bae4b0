/* fuzz_scene_json.c — libFuzzer target for the scene JSON reader (glow_scene_parse, issue 15 D10).
 *
 * Each input is parsed as a scene file. When the reader accepts it, what it returns must be what its
 * header promises: every light passes glow_scene_light_validate, the camera's numbers and the
 * environment are finite, emission_scale >= 0, the mesh path is a NUL-terminated string, the
 * environment_map's path fits its buffer and its rotation and scale are finite (scale >= 0). Seed
 * corpus: the JSON files in scenes/ and ../shared/scenes (tools/fuzz-smoke.sh).
 * Build: -DGLOW_FUZZ=ON with CC=clang (tests/fuzz/CMakeLists.txt), or tools/fuzz-smoke.sh. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "glow/glow_scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static volatile size_t sink;

static void check_finite(const float *v, int n) {
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    glow_scene_desc scene;
    char msg[512];
    const glow_result r =
        glow_scene_parse((const char *)data, size, "fuzz.json", "/nonexistent", NULL, &scene, msg, sizeof msg);
    if (r == GLOW_OK) {
        if (!scene.mesh) abort();
        sink += strlen(scene.mesh);
        if (scene.light_count && !scene.lights) abort();
        for (uint32_t i = 0; i < scene.light_count; ++i) {
            char why[256];
            if (glow_scene_light_validate(&scene.lights[i], "fuzz", why, sizeof why) != GLOW_OK) abort();
        }
        check_finite(scene.environment, 3);
        if (!(scene.emission_scale >= 0.0f) || !isfinite(scene.emission_scale)) abort();
        const glow_scene_environment_map *em = &scene.environment_map;
        if (!memchr(em->path, 0, sizeof em->path)) abort();
        if (!isfinite(em->rotation_deg) || !isfinite(em->scale) || !(em->scale >= 0.0f)) abort();
        check_finite(scene.camera.position, 3);
        check_finite(scene.camera.target, 3);
        if (scene.has_camera) {
            const float *u = scene.camera.up;
            if (fabsf(u[0] * u[0] + u[1] * u[1] + u[2] * u[2] - 1.0f) > 1e-3f) abort();
            if (!(scene.camera.vfov_deg > 0.0f && scene.camera.vfov_deg < 180.0f)) abort();
            if (scene.camera.width < 1 || scene.camera.width > 16384 || scene.camera.height < 1 ||
                scene.camera.height > 16384)
                abort();
        }
    } else {
        if (!memchr(msg, 0, sizeof msg) || !msg[0]) abort(); /* a failure names its problem */
        if (scene.mesh || scene.lights || scene.light_count) abort(); /* zeroed on failure */
    }
    glow_scene_free(&scene);
    return 0;
}
