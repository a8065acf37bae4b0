/* 00_minimal_cpu — the smallest complete Glow integration: CPU only, glow.h only.
 *   1. load a bake (made offline: glow-bake builtin:cornell -o cornell.glow --quality low),
 *   2. light its surfels through a callback (your engine's direct light),
 *   3. update once per frame: Glow turns that direct light into multi-bounce indirect light,
 *   4. read the caches (what your shaders sample once you upload the outputs as textures).
 * Usage: sample-00_minimal_cpu BAKE [--frames N] [--headless] [--out DIR]; exit 0 ok, 1 error, 2 usage. */
#include <math.h>
#include <stdio.h>

#include <glow/glow.h>

#include "sample_args.h" /* samples/common: the command line every sample shares */
#include "sample_png.h"  /* samples/common: --out pictures of the caches */

typedef struct toy_light { float position[3], intensity[3]; } toy_light; /* a point light; W/sr, RGB */

/* THE CONTRACT. Glow hands you batches of surfels (small patches of the baked static scene); you write
 * for each the DIRECT irradiance E (W/m², RGB) your lights deliver to its front face. Not radiance, no
 * albedo, no emission, no indirect light: Glow adds the bake's emission and the bounces itself.
 * Called on several worker threads at once: read shared state, never write it.
 * A real engine samples its shadow maps here (or traces rays); this toy light casts no shadows. */
static glow_result light_surfels(void *user, const glow_surfel_batch *batch, float *out_irradiance, uint32_t worker) {
    const toy_light *light = user;
    for (uint32_t i = 0; i < batch->count; i++) {
        const float *p = batch->positions + 4 * i, *n = batch->normals + 4 * i; /* {x y z area}, {x y z 0} */
        float d[3] = {light->position[0] - p[0], light->position[1] - p[1], light->position[2] - p[2]};
        float dist2 = fmaxf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1e-4f);
        float cos_theta = fmaxf((n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / sqrtf(dist2), 0.0f);
        for (int c = 0; c < 3; c++) out_irradiance[3 * i + c] = light->intensity[c] * cos_theta / dist2; /* I·cosθ/r² */
    }
    return GLOW_OK;
}

/* The runtime explains each failed call here (the detail behind the glow_result it returns). */
static void log_to_stderr(void *user, glow_log_level level, glow_result code, const char *msg, const char *file,
                          int line) {
    if (level <= GLOW_LOG_WARNING) fprintf(stderr, "glow: %s\n", msg);
}

int main(int argc, char **argv) {
    sample_args args;
    int status = sample_parse_args(argc, argv, "BAKE", 8, &args);
    if (status >= 0) return status;

    /* 1. A context (allocator, logger, threads: zero = defaults), then the bake: validated on load.
     * 2. A system, the per-bake solver, with our hook and `light` as its user pointer (we move the
     *    light between updates, never during one). */
    toy_light light = {{0, 0, 0}, {3.6f, 2.5f, 0.85f}};
    glow_context *ctx = NULL;
    glow_bake *bake = NULL;
    glow_system *sys = NULL;
    glow_bake_info info = {0};
    glow_result r = glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION, .logger = {log_to_stderr}},
                                        &ctx);
    if (r == GLOW_OK) r = glow_bake_load_file(ctx, args.input, &bake);
    if (r == GLOW_OK) r = glow_bake_get_info(bake, &info);
    glow_system_desc desc = {.bake = bake, .lighting = {.light_surfels = light_surfels, .user = &light}};
    if (r == GLOW_OK) r = glow_system_create(ctx, &desc, &sys);
    /* The artist controls at their defaults but emission_scale: our light replaces the bake's emissive
     * surfaces (Cornell's ceiling lamp), so all the light in the caches comes from the callback. */
    glow_system_params params = {.bounce_intensity = 1, .emission_scale = 0, .bounce_iterations = 1};
    if (r == GLOW_OK) r = glow_system_set_params(sys, &params);
    if (r != GLOW_OK) fprintf(stderr, "%s: %s\n", args.input, glow_result_string(r));
    else printf("%s: %u surfels, %u caches\n", args.input, info.surfel_count, info.cache_count);
    float centre[3], size[3];
    for (int a = 0; a < 3; a++) {
        centre[a] = 0.5f * (info.bounds_min[a] + info.bounds_max[a]);
        size[a] = info.bounds_max[a] - info.bounds_min[a];
    }

    for (long f = 0; r == GLOW_OK && f < args.frames; f++) {
        /* 3. Every frame: move the light on a circle under the ceiling, then update. Each update also
         * feeds the last one's indirect light back in (one more bounce per frame), so the first
         * frames brighten while the bounces converge. */
        light.position[0] = centre[0] + 0.3f * size[0] * cosf(0.8f * (float)f);
        light.position[1] = centre[1] + 0.3f * size[1];
        light.position[2] = centre[2] + 0.3f * size[2] * sinf(0.8f * (float)f);
        if ((r = glow_system_update(sys, NULL)) != GLOW_OK) {
            fprintf(stderr, "%s: update: %s\n", args.input, glow_result_string(r));
            break;
        }
        glow_update_stats stats;
        glow_system_get_stats(sys, &stats);
        printf("frame %ld  light (%.2f %.2f %.2f)  update %.2f ms  indirect E (W/m2) facing up:", f, light.position[0],
               light.position[1], light.position[2], stats.total_ms);

        /* 4. Read the caches. An engine uploads `out` (grid_sh as 3D textures, lightmap_sh as a texture
         * array) and its shaders do this lookup: sample at the point, convolve with the normal's cosine
         * lobe: E/π. Here: three points on the vertical axis through the middle of the bake. */
        const glow_cache_outputs *out = glow_system_outputs(sys);
        const float up[3] = {0, 1, 0}, heights[3] = {0.25f, 0.5f, 0.75f}, pi = 3.14159265f;
        const char *names[3] = {"low", "centre", "high"};
        for (int k = 0; k < 3; k++) {
            float p[3] = {centre[0], info.bounds_min[1] + heights[k] * size[1], centre[2]}, rgb[3] = {0, 0, 0};
            float coeffs[3 * GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS]; /* coeff_count floats, at most this */
            if (glow_sample_grid(out, p, coeffs) == GLOW_OK) /* fails where no cache is near (inside solids) */
                glow_shade_sh(coeffs, out->sh_bands_luma, out->sh_bands_chroma, up, 1.0f, rgb);
            printf("  %s %.4f %.4f %.4f", names[k], pi * rgb[0], pi * rgb[1], pi * rgb[2]);
        }
        printf("\n");
        if (args.out_dir && sample_write_grid_slice(args.out_dir, f, out, &info, centre[1]) != 0) r = GLOW_ERROR_IO;
    }
    glow_system_destroy(sys); /* systems first, then their bake, then the context */
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    return r == GLOW_OK ? 0 : 1;
}
