/* test_gl_shading.c — the GLSL shading include (shaders/include/glow_shading.glsl, as hosts get it from
 * glow_gl_shading_source) computes what the runtime's C reference computes:
 *   - glow_sh_eval for l = 8 bands at 256 random directions vs glow_sh_eval (C): |diff| <= 2e-5 (the
 *     basis values are <= 2.3 in magnitude; float recurrences on two compilers);
 *   - glow_sh_lobe_factor for l = 0..7 and exponents 1, 8, 100 vs glow_sh_lobe_factor: relative 1e-5;
 *   - glow_sample_grid + glow_shade_sh (diffuse and exponent 20) at 512 random points of the built-in
 *     Cornell box's grid (GVIS masks, empty cells, clamping at the border) vs glow_sample_grid +
 *     glow_shade_sh on the same caches (the GPU's, read back), glow_sample_grid_oriented (the random
 *     direction as the normal, diffuse) vs glow_sample_grid_oriented the same way, and glow_sample_lightmap at 512 random
 *     uvs vs glow_sample_lightmap: |diff| <= 1e-4 · (max |result|) — the two blend the same texels with
 *     weights renormalised in a different order; glow_sample_lightmap_detail at the same uvs on the
 *     GPU's lightmap detail vs glow_sample_lightmap_detail: |diff| <= 1e-5 · (max |result|);
 *   - a lightmap of pages (glow-bake --lightmap-max-size, format 1.7): glow_sample_lightmap_page and
 *     glow_sample_lightmap_detail_page at 512 random pages and uvs vs the C ones, the same bounds;
 *   - a CPU system's RGBA16F output planes uploaded as they are into RGBA16F textures hold what the GL
 *     system's textures hold (one page and several), to the halves' precision, and so do a GL system's
 *     own RGBA16F textures (GLOW_GL_FLAG_RGBA16F_OUTPUTS).
 * Exits 77 (skipped) without a GL 4.5 context. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "glow/glow.h"
#include "glow/glow_gl.h"
#include "glow/glow_glctx.h"
#include "glow/glow_glfns.h"
#include "glow/glow_precompute.h"

static glow_glctx *g_ctx;
static glow_glfns gl;

static uint32_t rng_state = 12345u;
static float frand(void) {
    rng_state = rng_state * 1664525u + 1013904223u;
    return (float)(rng_state >> 8) / 16777216.0f;
}

/* Compiles a compute shader: the shading include with `luma`/`chroma`, then `body`. */
static GLuint compute_program(uint32_t luma, uint32_t chroma, const char *body) {
    char head[256];
    snprintf(head, sizeof head, "#version 450 core\n#define GLOW_SH_BANDS_LUMA %u\n#define GLOW_SH_BANDS_CHROMA %u\n", luma,
             chroma);
    const char *src[3] = {head, glow_gl_shading_source(), body};
    GLuint sh = gl.CreateShader(GL_COMPUTE_SHADER);
    gl.ShaderSource(sh, 3, src, NULL);
    gl.CompileShader(sh);
    GLint ok = 0;
    gl.GetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096];
        gl.GetShaderInfoLog(sh, sizeof log, NULL, log);
        fail_msg("compute shader: %s", log);
    }
    GLuint p = gl.CreateProgram();
    gl.AttachShader(p, sh);
    gl.LinkProgram(p);
    gl.DeleteShader(sh);
    gl.GetProgramiv(p, GL_LINK_STATUS, &ok);
    assert_true(ok);
    return p;
}

static GLuint ssbo(size_t bytes, const void *data) {
    GLuint b;
    gl.CreateBuffers(1, &b);
    gl.NamedBufferStorage(b, (GLsizeiptr)bytes, data, GL_DYNAMIC_STORAGE_BIT);
    return b;
}

static void test_basis_and_lobes(void **state) {
    (void)state;
    enum { N = 256 };
    float dirs[N * 4];
    for (int i = 0; i < N; ++i) {
        float z = 2.0f * frand() - 1.0f, phi = 6.2831853f * frand(), r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        dirs[4 * i] = r * cosf(phi), dirs[4 * i + 1] = r * sinf(phi), dirs[4 * i + 2] = z, dirs[4 * i + 3] = 0.0f;
    }
    const char *body = "layout(local_size_x = 64) in;\n"
                       "layout(std430, binding = 0) readonly buffer D { vec4 d[]; };\n"
                       "layout(std430, binding = 1) writeonly buffer Y { float y[]; };\n"
                       "layout(std430, binding = 2) writeonly buffer S { float s[]; };\n"
                       "void main() { uint i = gl_GlobalInvocationID.x; float v[64]; glow_sh_eval(8, d[i].xyz, v);\n"
                       "  for (int k = 0; k < 64; ++k) y[i * 64u + uint(k)] = v[k];\n"
                       "  if (i < 24u) { float n = i / 8u == 0u ? 1.0 : (i / 8u == 1u ? 8.0 : 100.0); s[i] = glow_sh_lobe_factor(int(i % 8u), n); } }\n";
    GLuint p = compute_program(8, 8, body);
    GLuint bd = ssbo(sizeof dirs, dirs), by = ssbo(N * 64 * sizeof(float), NULL), bs = ssbo(24 * sizeof(float), NULL);
    gl.UseProgram(p);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, bd);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, by);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, bs);
    gl.DispatchCompute(N / 64, 1, 1);
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    static float y[N * 64];
    float s[24];
    gl.GetNamedBufferSubData(by, 0, sizeof y, y);
    gl.GetNamedBufferSubData(bs, 0, sizeof s, s);
    double worst = 0.0, worst_s = 0.0;
    for (int i = 0; i < N; ++i) {
        float ref[64];
        glow_sh_eval(8, dirs + 4 * i, ref);
        for (int k = 0; k < 64; ++k) worst = fmax(worst, fabs((double)y[i * 64 + k] - ref[k]));
    }
    const float ns[3] = {1.0f, 8.0f, 100.0f};
    for (int i = 0; i < 24; ++i) {
        float ref = glow_sh_lobe_factor((uint32_t)(i % 8), ns[i / 8]);
        worst_s = fmax(worst_s, fabs((double)s[i] - ref) / fmax(fabs(ref), 1e-6));
    }
    printf("  SH basis l = 8, %d directions: worst |GLSL - C| %.2e; lobe factors worst rel %.2e\n", N, worst, worst_s);
    assert_true(worst <= 2e-5);
    assert_true(worst_s <= 1e-5);
    GLuint bufs[3] = {bd, by, bs};
    gl.DeleteBuffers(3, bufs);
    gl.DeleteProgram(p);
}

/* The surfels' irradiance: a position-dependent colour, so the SH vary. */
static void light_cornell(glow_system *sys) {
    glow_surfel_view v;
    glow_system_get_surfels(sys, &v);
    float *e = malloc((size_t)v.count * 3 * sizeof *e);
    for (uint32_t i = 0; i < v.count; ++i) {
        const float *p = v.positions + 4 * (size_t)i;
        e[3 * i] = 4.0f + 3.0f * p[0], e[3 * i + 1] = 2.0f + p[1], e[3 * i + 2] = 3.0f - 2.0f * p[2];
        for (int c = 0; c < 3; ++c) e[3 * i + c] = fmaxf(e[3 * i + c], 0.0f);
    }
    assert_int_equal(glow_system_set_surfel_irradiance(sys, 0, v.count, e), GLOW_OK);
    free(e);
}

/* A CPU system's RGBA16F output planes (glow_system_desc.output_planes) uploaded as they are (one
 * glTextureSubImage3D each, GL_RGBA, GL_HALF_FLOAT) into RGBA16F textures of the GL system's sizes hold,
 * read back as floats, what the GL system's own RGBA32F textures hold for the same bake and light, texel
 * for texel and plane for plane (pages included): so they are in the layout glow_shading.glsl reads.
 * Bound: the halves' rounding (2^-11 relative, checked at 2^-10) plus the CPU/GPU agreement (1e-4 of the
 * largest value). */
static void check_rgba16f_upload(glow_context *ctx, const glow_bake *bake, glow_system *sys, uint32_t luma,
                                 uint32_t chroma, const glow_gl_outputs *go) {
    glow_system *h;
    assert_int_equal(glow_system_create(ctx, &(glow_system_desc){.bake = bake, .sh_bands_luma = luma, .sh_bands_chroma = chroma,
                                                                 .output_planes = GLOW_OUTPUT_PLANES_RGBA16F},
                                        &h),
                     GLOW_OK);
    light_cornell(h);
    for (int u = 0; u < 3; ++u) assert_int_equal(glow_system_update(h, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(h);
    const uint32_t Q = go->planes, nc = o->coeff_count, P = o->lightmap_pages;
    assert_int_equal(Q, (nc + 3u) / 4u);
    assert_non_null(o->grid_rgba16f);
    assert_non_null(o->lightmap_rgba16f);
    const GLsizei dims[2][3] = {{(GLsizei)go->grid_dims[0], (GLsizei)go->grid_dims[1], (GLsizei)(go->grid_dims[2] * Q)},
                                {(GLsizei)go->lightmap_width, (GLsizei)go->lightmap_height, (GLsizei)(Q * P)}};
    const GLenum target[2] = {GL_TEXTURE_3D, GL_TEXTURE_2D_ARRAY};
    const uint16_t *src[2] = {o->grid_rgba16f, o->lightmap_rgba16f};
    const GLuint theirs[2] = {go->grid_texture, go->lightmap_texture};
    for (int w = 0; w < 2; ++w) {
        GLuint t;
        gl.CreateTextures(target[w], 1, &t);
        gl.TextureStorage3D(t, 1, GL_RGBA16F, dims[w][0], dims[w][1], dims[w][2]);
        gl.TextureSubImage3D(t, 0, 0, 0, 0, dims[w][0], dims[w][1], dims[w][2], GL_RGBA, GL_HALF_FLOAT, src[w]);
        const size_t n = (size_t)dims[w][0] * dims[w][1] * dims[w][2] * 4u;
        float *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
        gl.GetTextureImage(t, 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof *a), a);
        gl.GetTextureImage(theirs[w], 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof *b), b);
        assert_int_equal(gl.GetError(), GL_NO_ERROR);
        double scale = 0.0, worst = 0.0;
        for (size_t i = 0; i < n; ++i) scale = fmax(scale, fabs((double)b[i]));
        const size_t per_plane = n / 4u / ((size_t)Q * (w ? P : 1u)); /* texels of one plane (of a page) */
        size_t checked = 0;
        for (size_t i = 0; i < n; ++i) {
            const size_t q = (i / 4u / per_plane) % Q, k = 4u * q + i % 4u; /* the coefficient */
            if (k >= nc) continue;
            const double d = fabs((double)a[i] - b[i]);
            if (d > ldexp(fabs((double)b[i]), -10) + 1e-4 * scale)
                fail_msg("%s value %zu (plane %zu, coefficient %zu): RGBA16F upload %g, GL system %g", w ? "lightmap" : "grid",
                         i, q, k, (double)a[i], (double)b[i]);
            worst = fmax(worst, d);
            checked += b[i] != 0.0f;
        }
        printf("  RGBA16F %s planes uploaded as they are: %zu values agree with the GL system's, worst %.2e (max %.3g)\n",
               w ? "lightmap" : "grid", checked, worst, scale);
        assert_true(scale > 0.0 && checked > n / 16u);
        free(a), free(b);
        gl.DeleteTextures(1, &t);
    }
    glow_system_destroy(h);
    /* The GL system's own textures in RGBA16F (GLOW_GL_FLAG_RGBA16F_OUTPUTS): the float textures' values,
     * rounded to halves, everywhere (padding and empty texels included); a host RGBA32F texture is then
     * refused */
    assert_int_equal(go->output_internal_format, GL_RGBA32F);
    glow_gl_system *g16;
    const glow_gl_loader load = glow_glctx_get_proc_address(g_ctx);
    assert_int_equal(glow_gl_system_create(&(glow_gl_desc){.system = sys, .get_proc_address = load,
                                                           .flags = GLOW_GL_FLAG_RGBA16F_OUTPUTS},
                                           &g16),
                     GLOW_OK);
    for (int u = 0; u < 3; ++u) assert_int_equal(glow_gl_system_update(g16, NULL), GLOW_OK);
    const glow_gl_outputs *o16 = glow_gl_system_outputs(g16);
    assert_int_equal(o16->output_internal_format, GL_RGBA16F);
    const GLuint mine[2] = {o16->grid_texture, o16->lightmap_texture};
    for (int w = 0; w < 2; ++w) {
        GLint fmt = 0;
        gl.GetTextureLevelParameteriv(mine[w], 0, GL_TEXTURE_INTERNAL_FORMAT, &fmt);
        assert_int_equal(fmt, GL_RGBA16F);
        const size_t n = (size_t)dims[w][0] * dims[w][1] * dims[w][2] * 4u;
        float *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
        gl.GetTextureImage(mine[w], 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof *a), a);
        gl.GetTextureImage(theirs[w], 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof *b), b);
        double worst = 0.0, scale = 0.0;
        size_t nonzero = 0;
        for (size_t i = 0; i < n; ++i) {
            const double d = fabs((double)a[i] - b[i]);
            if (d > ldexp(fabs((double)b[i]), -10) + 1e-7)
                fail_msg("GL RGBA16F %s value %zu: %g, the RGBA32F texture's %g", w ? "lightmap" : "grid", i, (double)a[i],
                         (double)b[i]);
            worst = fmax(worst, d), scale = fmax(scale, fabs((double)b[i]));
            nonzero += a[i] != 0.0f;
        }
        printf("  GL system's own RGBA16F %s texture: %zu values within a half's rounding of RGBA32F, worst %.2e (max %.3g)\n",
               w ? "lightmap" : "grid", nonzero, worst, scale);
        assert_true(nonzero > n / 16u);
        free(a), free(b);
    }
    GLuint f32tex;
    gl.CreateTextures(GL_TEXTURE_3D, 1, &f32tex);
    gl.TextureStorage3D(f32tex, 1, GL_RGBA32F, dims[0][0], dims[0][1], dims[0][2]);
    glow_gl_system *bad = NULL;
    assert_int_equal(glow_gl_system_create(&(glow_gl_desc){.system = sys, .get_proc_address = load,
                                                           .flags = GLOW_GL_FLAG_RGBA16F_OUTPUTS, .grid_texture = f32tex},
                                           &bad),
                     GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(bad);
    gl.DeleteTextures(1, &f32tex);
    glow_gl_system_destroy(g16);
}

/* Bakes builtin:cornell with `st`, loads it into a CPU system with `luma`/`chroma` bands (0: the bake's)
 * lit by a position-dependent colour (so the SH vary), and a GL system on it updated 3 times. */
static void lit_cornell(const glow_pc_settings *st, uint32_t luma, uint32_t chroma, glow_context **ctx, glow_bake **bake,
                        glow_system **sys, glow_gl_system **gs) {
    char path[256];
    snprintf(path, sizeof path, "/tmp/glow_gl_shading_%d.glow", (int)getpid());
    glow_pc_stats stats;
    assert_int_equal(glow_pc_bake("builtin:cornell", path, st, &stats), GLOW_OK);
    assert_int_equal(glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION}, ctx), GLOW_OK);
    assert_int_equal(glow_bake_load_file(*ctx, path, bake), GLOW_OK);
    remove(path);
    assert_int_equal(glow_system_create(*ctx, &(glow_system_desc){.bake = *bake, .sh_bands_luma = luma, .sh_bands_chroma = chroma}, sys),
                     GLOW_OK);
    light_cornell(*sys);
    assert_int_equal(glow_gl_system_create(&(glow_gl_desc){.system = *sys, .get_proc_address = glow_glctx_get_proc_address(g_ctx)}, gs),
                     GLOW_OK);
    for (int u = 0; u < 3; ++u) assert_int_equal(glow_gl_system_update(*gs, NULL), GLOW_OK);
}

static void test_sampling(void **state) {
    (void)state;
    glow_context *ctx;
    glow_bake *bake;
    glow_system *sys;
    glow_gl_system *gs;
    const glow_pc_settings st = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 96, .bands = 3, .threads = 2, .seed = 1};
    lit_cornell(&st, 3, 2, &ctx, &bake, &sys, &gs);
    const glow_gl_outputs *go = glow_gl_system_outputs(gs);
    check_rgba16f_upload(ctx, bake, sys, 3, 2, go);
    /* the C reference on the GPU's caches */
    glow_cache_outputs co = *glow_system_outputs(sys);
    const size_t ncs = (size_t)co.cache_count * co.coeff_count;
    float *sh = malloc(ncs * sizeof *sh);
    assert_int_equal(glow_gl_system_read_cache_sh(gs, sh, ncs), GLOW_OK);
    co.cache_sh = sh;
    enum { N = 512 };
    float pts[N * 4], uvs[N * 4];
    for (int i = 0; i < N; ++i) {
        for (int a = 0; a < 3; ++a) { /* a little outside the grid too: clamping */
            float lo = co.grid_origin[a] - 0.5f * co.grid_spacing;
            float hi = co.grid_origin[a] + ((float)co.grid_dims[a] - 0.5f) * co.grid_spacing;
            pts[4 * i + a] = lo + (hi - lo) * frand();
        }
        pts[4 * i + 3] = 0.0f;
        uvs[4 * i] = frand(), uvs[4 * i + 1] = frand();
        float z = 2.0f * frand() - 1.0f, phi = 6.2831853f * frand(), r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        uvs[4 * i + 2] = phi, uvs[4 * i + 3] = z; /* a direction for the shading axis, rebuilt below */
        (void)r;
    }
    const char *body =
        "layout(local_size_x = 64) in;\n"
        "layout(std430, binding = 0) readonly buffer P { vec4 pts[]; };\n"
        "layout(std430, binding = 1) readonly buffer U { vec4 uvs[]; };\n"
        "layout(std430, binding = 2) writeonly buffer R { vec4 res[]; };\n"
        "layout(binding = 0) uniform sampler3D grid; layout(binding = 1) uniform usampler3D grid_mask;\n"
        "layout(binding = 2) uniform sampler2DArray lm; layout(binding = 3) uniform usampler2D lm_valid;\n"
        "uniform vec3 origin; uniform float spacing; uniform ivec3 dims;\n"
        "void main() { uint i = gl_GlobalInvocationID.x; vec4 sh[GLOW_SH_PLANES];\n"
        "  float phi = uvs[i].z, z = uvs[i].w, r = sqrt(max(0.0, 1.0 - z * z)); vec3 axis = vec3(r * cos(phi), r * sin(phi), z);\n"
        "  bool g = glow_sample_grid(grid, grid_mask, origin, spacing, dims, pts[i].xyz, sh);\n"
        "  res[5u * i] = vec4(glow_shade_sh(sh, axis, 1.0), g ? 1.0 : 0.0);\n"
        "  res[5u * i + 1u] = vec4(glow_shade_sh(sh, axis, 20.0), 0.0);\n"
        "  bool l = glow_sample_lightmap(lm, lm_valid, uvs[i].xy, sh);\n"
        "  res[5u * i + 2u] = vec4(glow_shade_sh(sh, axis, 1.0), l ? 1.0 : 0.0);\n"
        "  res[5u * i + 3u] = vec4(glow_shade_sh(sh, axis, 20.0), 0.0);\n"
        "  bool o = glow_sample_grid_oriented(grid, grid_mask, origin, spacing, dims, pts[i].xyz, axis, sh);\n"
        "  res[5u * i + 4u] = vec4(glow_shade_sh(sh, axis, 1.0), o ? 1.0 : 0.0); }\n";
    GLuint p = compute_program(3, 2, body);
    GLuint bp = ssbo(sizeof pts, pts), bu = ssbo(sizeof uvs, uvs), br = ssbo(N * 5 * 16, NULL);
    gl.UseProgram(p);
    gl.Uniform3f(gl.GetUniformLocation(p, "origin"), go->grid_origin[0], go->grid_origin[1], go->grid_origin[2]);
    gl.Uniform1f(gl.GetUniformLocation(p, "spacing"), go->grid_spacing);
    gl.Uniform3i(gl.GetUniformLocation(p, "dims"), (GLint)go->grid_dims[0], (GLint)go->grid_dims[1], (GLint)go->grid_dims[2]);
    gl.BindTextureUnit(0, go->grid_texture);
    gl.BindTextureUnit(1, go->grid_mask_texture);
    gl.BindTextureUnit(2, go->lightmap_texture);
    gl.BindTextureUnit(3, go->lightmap_valid_texture);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, bp);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, bu);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, br);
    gl.DispatchCompute(N / 64, 1, 1);
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    static float res[N * 20];
    gl.GetNamedBufferSubData(br, 0, sizeof res, res);
    double worst[3] = {0, 0, 0}, scale[3] = {0, 0, 0};
    int hits[3] = {0, 0, 0}, mismatched_ok = 0;
    float *coeffs = malloc(co.coeff_count * sizeof *coeffs);
    for (int i = 0; i < N; ++i) {
        const float phi = uvs[4 * i + 2], z = uvs[4 * i + 3], r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        const float axis[3] = {r * cosf(phi), r * sinf(phi), z};
        for (int which = 0; which < 2; ++which) {
            glow_result rr = which == 0 ? glow_sample_grid(&co, pts + 4 * i, coeffs)
                                        : glow_sample_lightmap(&co, uvs[4 * i], uvs[4 * i + 1], coeffs);
            const float *g = res + 20 * i + 8 * which;
            if ((rr == GLOW_OK) != (g[3] == 1.0f)) mismatched_ok++;
            if (rr != GLOW_OK) continue;
            hits[which]++;
            for (int lobe = 0; lobe < 2; ++lobe) {
                float ref[3];
                glow_shade_sh(coeffs, 3, 2, axis, lobe ? 20.0f : 1.0f, ref);
                for (int c = 0; c < 3; ++c) {
                    worst[which] = fmax(worst[which], fabs((double)g[4 * lobe + c] - ref[c]));
                    scale[which] = fmax(scale[which], fabs(ref[c]));
                }
            }
        }
        /* the oriented lookup with the axis as the normal, diffuse */
        const glow_result ro = glow_sample_grid_oriented(&co, pts + 4 * i, axis, coeffs);
        const float *g = res + 20 * i + 16;
        if ((ro == GLOW_OK) != (g[3] == 1.0f)) mismatched_ok++;
        if (ro != GLOW_OK) continue;
        hits[2]++;
        float ref[3];
        glow_shade_sh(coeffs, 3, 2, axis, 1.0f, ref);
        for (int c = 0; c < 3; ++c) {
            worst[2] = fmax(worst[2], fabs((double)g[c] - ref[c]));
            scale[2] = fmax(scale[2], fabs(ref[c]));
        }
    }
    printf("  oriented grid: %d/%d lookups hit a cache, worst |GLSL - C| %.2e (max %.3g)\n", hits[2], N, worst[2], scale[2]);
    assert_true(hits[2] > N / 2 && scale[2] > 0.0);
    assert_true(worst[2] <= 1e-4 * scale[2]);
    printf("  grid: %d/%d lookups hit a cache, worst |GLSL - C| %.2e (max %.3g); lightmap: %d/%d, worst %.2e (max %.3g)\n",
           hits[0], N, worst[0], scale[0], hits[1], N, worst[1], scale[1]);
    assert_int_equal(mismatched_ok, 0);
    assert_true(hits[0] > N / 2 && hits[1] > N / 10);
    assert_true(scale[0] > 0.0 && scale[1] > 0.0);
    assert_true(worst[0] <= 1e-4 * scale[0]);
    assert_true(worst[1] <= 1e-4 * scale[1]);
    free(coeffs);
    /* the lightmap detail: glow_sample_lightmap_detail (GLSL) on the GPU's detail texture vs the C one on
     * the same texels, read back */
    {
        assert_int_not_equal(go->lightmap_detail_texture, 0);
        const size_t dn = (size_t)go->detail_width * go->detail_height * 4u;
        float *det = malloc(dn * sizeof *det);
        gl.GetTextureImage(go->lightmap_detail_texture, 0, GL_RGBA, GL_FLOAT, (GLsizei)(dn * sizeof *det), det);
        co.lightmap_detail = det;
        co.detail_width = go->detail_width;
        co.detail_height = go->detail_height;
        const char *dbody =
            "layout(local_size_x = 64) in;\n"
            "layout(std430, binding = 1) readonly buffer U { vec4 uvs[]; };\n"
            "layout(std430, binding = 2) writeonly buffer R { vec4 res[]; };\n"
            "layout(binding = 4) uniform sampler2D det;\n"
            "void main() { uint i = gl_GlobalInvocationID.x; res[i] = vec4(glow_sample_lightmap_detail(det, uvs[i].xy), 0.0); }\n";
        GLuint dp = compute_program(3, 2, dbody), dr = ssbo(N * 16, NULL);
        gl.UseProgram(dp);
        gl.BindTextureUnit(4, go->lightmap_detail_texture);
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, bu);
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, dr);
        gl.DispatchCompute(N / 64, 1, 1);
        gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        static float dres[N * 4];
        gl.GetNamedBufferSubData(dr, 0, sizeof dres, dres);
        double dworst = 0.0, dscale = 0.0;
        int dhits = 0;
        for (int i = 0; i < N; ++i) {
            float ref[3];
            dhits += glow_sample_lightmap_detail(&co, uvs[4 * i], uvs[4 * i + 1], ref) == GLOW_OK;
            for (int c = 0; c < 3; ++c) {
                dworst = fmax(dworst, fabs((double)dres[4 * i + c] - ref[c]));
                dscale = fmax(dscale, fabs(ref[c]));
            }
        }
        printf("  lightmap detail %ux%u: %d/%d lookups cover a surface, worst |GLSL - C| %.2e (max %.3g)\n",
               go->detail_width, go->detail_height, dhits, N, dworst, dscale);
        assert_true(dhits > N / 10 && dscale > 0.0);
        assert_true(dworst <= 1e-5 * dscale);
        gl.DeleteBuffers(1, &dr);
        gl.DeleteProgram(dp);
        free(det);
    }
    free(sh);
    /* host-owned output textures: a second GL system writing into textures the host made gives the same texels */
    {
        GLuint host_grid, host_lm;
        gl.CreateTextures(GL_TEXTURE_3D, 1, &host_grid);
        gl.TextureStorage3D(host_grid, 1, GL_RGBA32F, (GLsizei)go->grid_dims[0], (GLsizei)go->grid_dims[1],
                            (GLsizei)(go->grid_dims[2] * go->planes));
        gl.CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &host_lm);
        gl.TextureStorage3D(host_lm, 1, GL_RGBA32F, (GLsizei)go->lightmap_width, (GLsizei)go->lightmap_height, (GLsizei)go->planes);
        glow_gl_system *gs2;
        assert_int_equal(glow_gl_system_create(&(glow_gl_desc){.system = sys, .get_proc_address = glow_glctx_get_proc_address(g_ctx),
                                                               .grid_texture = host_grid, .lightmap_texture = host_lm},
                                               &gs2),
                         GLOW_OK);
        const glow_gl_outputs *o2 = glow_gl_system_outputs(gs2);
        assert_int_equal(o2->grid_texture, host_grid);
        assert_int_equal(o2->lightmap_texture, host_lm);
        for (int u = 0; u < 3; ++u) assert_int_equal(glow_gl_system_update(gs2, NULL), GLOW_OK);
        const size_t gbytes = (size_t)go->grid_dims[0] * go->grid_dims[1] * go->grid_dims[2] * go->planes * 16u;
        const size_t lbytes = (size_t)go->lightmap_width * go->lightmap_height * go->planes * 16u;
        float *a = malloc(gbytes), *b = malloc(gbytes), *c = malloc(lbytes), *d = malloc(lbytes);
        gl.GetTextureImage(go->grid_texture, 0, GL_RGBA, GL_FLOAT, (GLsizei)gbytes, a);
        gl.GetTextureImage(host_grid, 0, GL_RGBA, GL_FLOAT, (GLsizei)gbytes, b);
        gl.GetTextureImage(go->lightmap_texture, 0, GL_RGBA, GL_FLOAT, (GLsizei)lbytes, c);
        gl.GetTextureImage(host_lm, 0, GL_RGBA, GL_FLOAT, (GLsizei)lbytes, d);
        assert_memory_equal(a, b, gbytes);
        assert_memory_equal(c, d, lbytes);
        double sum = 0.0;
        for (size_t i = 0; i < lbytes / 4; ++i) sum += fabs(d[i]);
        assert_true(sum > 0.0); /* written, not left at zero */
        printf("  host-owned textures: grid %zu and lightmap %zu bytes identical to Glow's own\n", gbytes, lbytes);
        free(a), free(b), free(c), free(d);
        glow_gl_system_destroy(gs2);
        GLuint tex[2] = {host_grid, host_lm};
        gl.DeleteTextures(2, tex); /* Glow did not delete them: still valid names until here */
    }
    GLuint bufs[3] = {bp, bu, br};
    gl.DeleteBuffers(3, bufs);
    gl.DeleteProgram(p);
    glow_gl_system_destroy(gs);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
}

/* A lightmap of several pages (issue 16 item 5): the GPU's lightmap texture holds page g's planes at layers
 * g · planes + p and its valid mask and detail texture the pages one above another; the GLSL lookups of a
 * page (glow_sample_lightmap_page, glow_sample_lightmap_detail_page) on them equal the C ones on the GPU's
 * caches and detail, read back, at random pages and uvs (so outputs.comp's placement is checked too). */
static void test_sampling_pages(void **state) {
    (void)state;
    glow_context *ctx;
    glow_bake *bake;
    glow_system *sys;
    glow_gl_system *gs;
    const glow_pc_settings st = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 1024, .links = 32, .bands = 3, .threads = 2,
                                 .seed = 1, .grid_spacing = 0.5f, .lightmap_caches = 1000, .no_sky = true,
                                 .lightmap_max_size = 28};
    lit_cornell(&st, 3, 2, &ctx, &bake, &sys, &gs);
    const glow_gl_outputs *go = glow_gl_system_outputs(gs);
    glow_cache_outputs co = *glow_system_outputs(sys);
    const uint32_t P = co.lightmap_pages;
    printf("  %u lightmap pages of %ux%u (GL: %u), detail %ux%u a page\n", P, co.lightmap_width, co.lightmap_height,
           go->lightmap_pages, go->detail_width, go->detail_height);
    assert_true(P >= 3);
    assert_int_equal(go->lightmap_pages, P);
    assert_int_not_equal(go->lightmap_detail_texture, 0);
    check_rgba16f_upload(ctx, bake, sys, 3, 2, go);
    const size_t ncs = (size_t)co.cache_count * co.coeff_count;
    float *sh = malloc(ncs * sizeof *sh);
    assert_int_equal(glow_gl_system_read_cache_sh(gs, sh, ncs), GLOW_OK);
    co.cache_sh = sh;
    const size_t dn = (size_t)go->detail_width * go->detail_height * P * 4u;
    float *det = malloc(dn * sizeof *det);
    gl.GetTextureImage(go->lightmap_detail_texture, 0, GL_RGBA, GL_FLOAT, (GLsizei)(dn * sizeof *det), det);
    co.lightmap_detail = det;
    enum { N = 512 };
    float uvs[N * 4];
    for (int i = 0; i < N; ++i) {
        uvs[4 * i] = frand(), uvs[4 * i + 1] = frand();
        uvs[4 * i + 2] = (float)(uint32_t)(frand() * (float)P); /* the page */
        uvs[4 * i + 3] = 2.0f * frand() - 1.0f;                 /* a normal's z */
    }
    const char *body =
        "layout(local_size_x = 64) in;\n"
        "layout(std430, binding = 1) readonly buffer U { vec4 uvs[]; };\n"
        "layout(std430, binding = 2) writeonly buffer R { vec4 res[]; };\n"
        "layout(binding = 2) uniform sampler2DArray lm; layout(binding = 3) uniform usampler2D lm_valid;\n"
        "layout(binding = 4) uniform sampler2D det; uniform int pages;\n"
        "void main() { uint i = gl_GlobalInvocationID.x; vec4 sh[GLOW_SH_PLANES]; int page = int(uvs[i].z);\n"
        "  float z = uvs[i].w; vec3 n = vec3(sqrt(max(0.0, 1.0 - z * z)), 0.0, z);\n"
        "  bool l = glow_sample_lightmap_page(lm, lm_valid, page, uvs[i].xy, sh);\n"
        "  res[2u * i] = vec4(glow_shade_sh(sh, n, 1.0), l ? 1.0 : 0.0);\n"
        "  res[2u * i + 1u] = vec4(glow_sample_lightmap_detail_page(det, pages, page, uvs[i].xy), 0.0); }\n";
    GLuint p = compute_program(3, 2, body);
    GLuint bu = ssbo(sizeof uvs, uvs), br = ssbo(N * 2 * 16, NULL);
    gl.UseProgram(p);
    gl.Uniform1i(gl.GetUniformLocation(p, "pages"), (GLint)go->lightmap_pages);
    gl.BindTextureUnit(2, go->lightmap_texture);
    gl.BindTextureUnit(3, go->lightmap_valid_texture);
    gl.BindTextureUnit(4, go->lightmap_detail_texture);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, bu);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, br);
    gl.DispatchCompute(N / 64, 1, 1);
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    static float res[N * 8];
    gl.GetNamedBufferSubData(br, 0, sizeof res, res);
    float *coeffs = malloc(co.coeff_count * sizeof *coeffs);
    double worst = 0.0, scale = 0.0, dworst = 0.0, dscale = 0.0;
    int hits = 0, dhits = 0, mismatched_ok = 0, pages_hit[64] = {0};
    for (int i = 0; i < N; ++i) {
        const uint32_t page = (uint32_t)uvs[4 * i + 2];
        const float z = uvs[4 * i + 3], n[3] = {sqrtf(fmaxf(0.0f, 1.0f - z * z)), 0.0f, z};
        const glow_result rr = glow_sample_lightmap_page(&co, page, uvs[4 * i], uvs[4 * i + 1], coeffs);
        const float *g = res + 8 * i;
        if ((rr == GLOW_OK) != (g[3] == 1.0f)) mismatched_ok++;
        if (rr == GLOW_OK) {
            hits++;
            if (page < 64) pages_hit[page] = 1;
            float ref[3];
            glow_shade_sh(coeffs, 3, 2, n, 1.0f, ref);
            for (int c = 0; c < 3; ++c) {
                worst = fmax(worst, fabs((double)g[c] - ref[c]));
                scale = fmax(scale, fabs(ref[c]));
            }
        }
        float dref[3];
        dhits += glow_sample_lightmap_detail_page(&co, page, uvs[4 * i], uvs[4 * i + 1], dref) == GLOW_OK;
        for (int c = 0; c < 3; ++c) {
            dworst = fmax(dworst, fabs((double)g[4 + c] - dref[c]));
            dscale = fmax(dscale, fabs(dref[c]));
        }
    }
    int npages_hit = 0;
    for (int k = 0; k < 64; ++k) npages_hit += pages_hit[k];
    printf("  paged lightmap: %d/%d lookups hit a cache on %d pages, worst |GLSL - C| %.2e (max %.3g); detail %d/%d, "
           "worst %.2e (max %.3g)\n", hits, N, npages_hit, worst, scale, dhits, N, dworst, dscale);
    assert_int_equal(mismatched_ok, 0);
    assert_true(hits > N / 10 && scale > 0.0 && npages_hit == (int)(P < 64 ? P : 64));
    assert_true(worst <= 1e-4 * scale);
    assert_true(dhits > N / 20 && dscale > 0.0);
    assert_true(dworst <= 1e-5 * dscale);
    /* a page beyond the lightmap's is refused by the C lookup */
    assert_int_equal(glow_sample_lightmap_page(&co, P, 0.5f, 0.5f, coeffs), GLOW_ERROR_INVALID_ARGUMENT);
    free(coeffs), free(sh), free(det);
    GLuint bufs[2] = {bu, br};
    gl.DeleteBuffers(2, bufs);
    gl.DeleteProgram(p);
    glow_gl_system_destroy(gs);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
}

/* A refined grid (glow-bake --grid-refine 2) on the GPU: glow_sample_grid_refined (GLSL, plain and
 * oriented) at 512 random points of the built-in Cornell box (a little outside the grid too) against
 * glow_sample_grid / glow_sample_grid_oriented (C) on the same caches, read back: the brick atlas, the
 * brick index and the fine masks hold what the CPU's bricks do. |diff| <= 1e-4 · (max |result|), and most
 * lookups must land in a brick (the fine cells differ from the coarse ones there, checked below). */
static void test_refined(void **state) {
    (void)state;
    glow_context *ctx;
    glow_bake *bake;
    glow_system *sys;
    glow_gl_system *gs;
    const glow_pc_settings st = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 2048, .links = 32, .bands = 3, .threads = 2, .seed = 1,
                                 .grid_spacing = 0.2f, .grid_refine = 2};
    lit_cornell(&st, 0, 0, &ctx, &bake, &sys, &gs);
    const glow_gl_outputs *go = glow_gl_system_outputs(gs);
    glow_cache_outputs co = *glow_system_outputs(sys);
    assert_int_equal(co.grid_refine, 2);
    assert_int_equal(go->grid_refine, 2);
    assert_true(go->grid_brick_texture && go->grid_fine_texture && go->grid_fine_mask_texture);
    const size_t ncs = (size_t)co.cache_count * co.coeff_count;
    float *sh = malloc(ncs * sizeof *sh);
    assert_int_equal(glow_gl_system_read_cache_sh(gs, sh, ncs), GLOW_OK);
    co.cache_sh = sh;
    enum { N = 512 };
    static float pts[N * 4], nrm[N * 4];
    for (int i = 0; i < N; ++i) {
        for (int a = 0; a < 3; ++a) {
            float lo = co.grid_origin[a] - 0.2f * co.grid_spacing;
            float hi = co.grid_origin[a] + ((float)co.grid_dims[a] - 0.8f) * co.grid_spacing;
            pts[4 * i + a] = lo + (hi - lo) * frand();
        }
        float z = 2.0f * frand() - 1.0f, phi = 6.2831853f * frand(), r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        nrm[4 * i] = r * cosf(phi), nrm[4 * i + 1] = r * sinf(phi), nrm[4 * i + 2] = z;
        pts[4 * i + 3] = nrm[4 * i + 3] = 0.0f;
    }
    const char *body =
        "layout(local_size_x = 64) in;\n"
        "layout(std430, binding = 0) readonly buffer P { vec4 pts[]; };\n"
        "layout(std430, binding = 1) readonly buffer Q { vec4 nrm[]; };\n"
        "layout(std430, binding = 2) writeonly buffer R { vec4 res[]; };\n"
        "layout(binding = 0) uniform sampler3D grid; layout(binding = 1) uniform usampler3D grid_mask;\n"
        "layout(binding = 2) uniform usampler3D bricks; layout(binding = 3) uniform sampler3D fine;\n"
        "layout(binding = 4) uniform usampler3D fine_mask;\n"
        "uniform vec3 origin; uniform float spacing; uniform ivec3 dims; uniform int refine; uniform int atlas_x;\n"
        "void main() { uint i = gl_GlobalInvocationID.x; vec4 sh[GLOW_SH_PLANES];\n"
        "  vec3 n = nrm[i].xyz;\n"
        "  bool a = glow_sample_grid_refined(grid, grid_mask, bricks, fine, fine_mask, refine, atlas_x, origin, spacing, dims, pts[i].xyz, false, n, sh);\n"
        "  res[2u * i] = vec4(glow_shade_sh(sh, n, 1.0), a ? 1.0 : 0.0);\n"
        "  bool b = glow_sample_grid_refined(grid, grid_mask, bricks, fine, fine_mask, refine, atlas_x, origin, spacing, dims, pts[i].xyz, true, n, sh);\n"
        "  res[2u * i + 1u] = vec4(glow_shade_sh(sh, n, 1.0), b ? 1.0 : 0.0); }\n";
    GLuint p = compute_program(co.sh_bands_luma, co.sh_bands_chroma, body);
    GLuint bp = ssbo(sizeof pts, pts), bn = ssbo(sizeof nrm, nrm), br = ssbo(N * 2 * 16, NULL);
    gl.UseProgram(p);
    gl.Uniform3f(gl.GetUniformLocation(p, "origin"), go->grid_origin[0], go->grid_origin[1], go->grid_origin[2]);
    gl.Uniform1f(gl.GetUniformLocation(p, "spacing"), go->grid_spacing);
    gl.Uniform3i(gl.GetUniformLocation(p, "dims"), (GLint)go->grid_dims[0], (GLint)go->grid_dims[1], (GLint)go->grid_dims[2]);
    gl.Uniform1i(gl.GetUniformLocation(p, "refine"), (GLint)go->grid_refine);
    gl.Uniform1i(gl.GetUniformLocation(p, "atlas_x"), (GLint)go->grid_fine_atlas_x);
    gl.BindTextureUnit(0, go->grid_texture);
    gl.BindTextureUnit(1, go->grid_mask_texture);
    gl.BindTextureUnit(2, go->grid_brick_texture);
    gl.BindTextureUnit(3, go->grid_fine_texture);
    gl.BindTextureUnit(4, go->grid_fine_mask_texture);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, bp);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, bn);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, br);
    gl.DispatchCompute(N / 64, 1, 1);
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    static float res[N * 8];
    gl.GetNamedBufferSubData(br, 0, sizeof res, res);
    float *coeffs = malloc(co.coeff_count * sizeof *coeffs);
    double worst = 0.0, scale = 0.0;
    int hits = 0, mismatched = 0, in_brick_differs = 0;
    glow_cache_outputs coarse = co; /* the same caches without the bricks: the lookups must differ inside them */
    coarse.grid_refine = 0;
    for (int i = 0; i < N; ++i)
        for (int which = 0; which < 2; ++which) {
            const glow_result rr = which ? glow_sample_grid_oriented(&co, pts + 4 * i, nrm + 4 * i, coeffs)
                                         : glow_sample_grid(&co, pts + 4 * i, coeffs);
            const float *g = res + 8 * i + 4 * which;
            if ((rr == GLOW_OK) != (g[3] == 1.0f)) mismatched++;
            if (rr != GLOW_OK) continue;
            hits++;
            float ref[3], alt[3];
            glow_shade_sh(coeffs, co.sh_bands_luma, co.sh_bands_chroma, nrm + 4 * i, 1.0f, ref);
            for (int c = 0; c < 3; ++c) {
                worst = fmax(worst, fabs((double)g[c] - ref[c]));
                scale = fmax(scale, fabs(ref[c]));
            }
            if (!which && glow_sample_grid(&coarse, pts + 4 * i, coeffs) == GLOW_OK) {
                glow_shade_sh(coeffs, co.sh_bands_luma, co.sh_bands_chroma, nrm + 4 * i, 1.0f, alt);
                in_brick_differs += fabsf(alt[0] - ref[0]) > 1e-3f * (fabsf(ref[0]) + 1e-3f);
            }
        }
    printf("  refined grid (%u bricks, atlas %u a row): %d/%d lookups hit a cache, worst |GLSL - C| %.2e (max %.3g); "
           "%d of the plain lookups differ from the coarse grid's\n",
           co.grid_brick_count, go->grid_fine_atlas_x, hits, 2 * N, worst, scale, in_brick_differs);
    assert_int_equal(mismatched, 0);
    assert_true(hits > N && scale > 0.0);
    assert_true(worst <= 1e-4 * scale);
    assert_true(in_brick_differs > N / 4); /* the bricks are read, not the coarse cells */
    free(coeffs);
    free(sh);
    GLuint bufs[3] = {bp, bn, br};
    gl.DeleteBuffers(3, bufs);
    gl.DeleteProgram(p);
    glow_gl_system_destroy(gs);
    glow_system_destroy(sys);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
}

int main(void) {
    char why[512];
    glow_result r = glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_HEADLESS}, &g_ctx, why, sizeof why);
    if (r != GLOW_OK) {
        printf("SKIP: no OpenGL 4.5 context (%s): %s\n", glow_result_string(r), why);
        return 77;
    }
    if (!glow_glfns_load(&gl, glow_glctx_get_proc_address(g_ctx), why, sizeof why)) {
        printf("SKIP: GL entry points missing: %s\n", why);
        glow_glctx_destroy(g_ctx);
        return 77;
    }
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_basis_and_lobes), cmocka_unit_test(test_sampling),
                                       cmocka_unit_test(test_sampling_pages), cmocka_unit_test(test_refined)};
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    glow_glctx_destroy(g_ctx);
    return rc;
}
