/* consumer.c — the smallest engine integration, built out of tree against an installed Glow
 * (tests/consumer/CMakeLists.txt, tools/consumer-test.sh): load a bake, light it with a point light,
 * update a few times, check that light arrived and every output is finite.
 * Usage: glow_consumer BAKE; exit 0 ok, 1 failure. */
#include <math.h>
#include <stdio.h>

#include <glow/glow.h>

static glow_result light(void *user, const glow_surfel_batch *b, float *out, uint32_t worker) {
    (void)worker;
    const float *pos = user;
    for (uint32_t i = 0; i < b->count; ++i) {
        const float *p = b->positions + 4 * i, *n = b->normals + 4 * i;
        const float d[3] = {pos[0] - p[0], pos[1] - p[1], pos[2] - p[2]};
        const float d2 = fmaxf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1e-4f);
        const float c = fmaxf((n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / sqrtf(d2), 0.0f);
        for (int k = 0; k < 3; ++k) out[3 * i + k] = 10.0f * c / d2;
    }
    return GLOW_OK;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: glow_consumer BAKE\n");
        return 1;
    }
    glow_context *ctx = NULL;
    glow_bake *bake = NULL;
    glow_system *sys = NULL;
    glow_bake_info info;
    float pos[3] = {0, 0, 0};
    glow_result r = glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION}, &ctx);
    if (r == GLOW_OK) r = glow_bake_load_file(ctx, argv[1], &bake);
    if (r == GLOW_OK) r = glow_bake_get_info(bake, &info);
    if (r == GLOW_OK)
        for (int k = 0; k < 3; ++k) pos[k] = 0.5f * (info.bounds_min[k] + info.bounds_max[k]);
    if (r == GLOW_OK)
        r = glow_system_create(ctx, &(glow_system_desc){.bake = bake, .lighting = {light, pos}}, &sys);
    for (int f = 0; f < 4 && r == GLOW_OK; ++f) r = glow_system_update(sys, NULL);
    int ok = r == GLOW_OK;
    double sum = 0.0;
    if (ok) {
        const glow_cache_outputs *o = glow_system_outputs(sys);
        for (size_t i = 0; i < (size_t)o->cache_count * o->coeff_count; ++i) {
            if (!isfinite(o->cache_sh[i])) ok = 0;
            sum += fabs(o->cache_sh[i]);
        }
        ok = ok && sum > 0.0;
        printf("glow_consumer: Glow %d.%d, %u caches, sum |SH| %.4g\n", GLOW_VERSION_MAJOR, GLOW_VERSION_MINOR,
               o->cache_count, sum);
    } else {
        fprintf(stderr, "glow_consumer: %s: %s\n", argv[1], glow_result_string(r));
    }
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
    return ok ? 0 : 1;
}
