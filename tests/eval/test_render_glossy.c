/* test_render_glossy.c — glow-render's GGX layer (tools/render/lib/render_bsdf.h, docs/glossy.md):
 *   (a) sampling against evaluation: the mean of f cos / pdf over stratified samples is the directional
 *       albedo ρ (1 - E(cos θ_o)) + F0 A + B, A and B from the runtime's deterministic quadrature
 *       (glow_ggx_specular_albedo) at cos θ_o, E the layer's table; and the sampled directions'
 *       histogram over (cos θ, φ) bins matches the pdf that glow__render_lobe_eval returns, integrated
 *       over each bin;
 *   (b) reciprocity f(o, i) = f(i, o), non-negativity; the white furnace: a surface with ρ = 1 reflects
 *       all it receives (mean f cos / pdf = 1) at every view and roughness, the GGX lobe alone at most
 *       all (Smith G loses energy, never adds);
 *   (c) a glossy floor under a large emitting ceiling (OBJ + MTL written here, roughness 0.5, F0 0.5):
 *       the reference's indirect and specular images at a pixel seen at 22.6° elevation against the
 *       reflection integral ∫ L_e f cos θ_i cos θ_l / d² dA over the ceiling by a midpoint rule;
 *   (d) Glow's view of that scene (a low bake made here, 4 bands): finite, its direct image the
 *       reference's, its diffuse part within 5 % of the reference's, and its specular image within 10 %
 *       of what the split sum predicts with the exact incident field (the lobe's mean of the ceiling's
 *       radiance, by a midpoint rule), about the reflection vector and about the dominant direction; the
 *       split sum's own error at this grazing view (28 % and 13 % low) is printed, and the dominant
 *       direction must be the closer of the two;
 *   (e) a "materials" key naming a material the mesh lacks: an error naming the file and the name. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "glow/glow_precompute.h"
#include "glow_render.h"
#include "render_bsdf.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void lobe_at(glow__render_lobe *s, const glow__render_ggx *g, float mu, const float rho[3]) {
    const float ns[3] = {0.0f, 0.0f, 1.0f}, wo[3] = {sqrtf(1.0f - mu * mu), 0.0f, mu};
    glow__render_lobe_setup(s, g, ns, ns, wo, rho);
}

static glow__render_ggx ggx_of(float r, float f0) {
    glow__render_ggx g;
    glow__render_ggx_init(&g, r, (const float[3]){f0, f0, f0});
    return g;
}

/* (a) */
static void test_sampling_matches_eval(void **state) {
    (void)state;
    const float rs[] = {0.2f, 0.5f, 1.0f}, mus[] = {0.15f, 0.5f, 0.95f};
    const float rho[3] = {0.8f, 0.5f, 0.2f};
    enum { NT = 16, NP = 16, N = 512 }; /* bins in cos θ and φ ∈ [0, π] (mirror-symmetric); N x N strata */
    for (int ir = 0; ir < 3; ++ir)
        for (int im = 0; im < 3; ++im) {
            glow__render_ggx g = ggx_of(rs[ir], 0.04f);
            glow__render_lobe s;
            lobe_at(&s, &g, mus[im], rho);
            assert_non_null(s.g);
            double sum[3] = {0, 0, 0}, sum2 = 0.0;
            static double hist[NT][NP];
            memset(hist, 0, sizeof hist);
            for (int i = 0; i < N; ++i)
                for (int j = 0; j < N; ++j) {
                    float wi[3], w[3], ws[3], pdf;
                    if (!glow__render_lobe_sample(&s, ((float)i + 0.5f) / N, ((float)j + 0.5f) / N, wi, w, ws, &pdf)) continue;
                    for (int k = 0; k < 3; ++k) {
                        assert_true(w[k] >= 0.0f && ws[k] >= 0.0f && ws[k] <= w[k] && isfinite(w[k]));
                        sum[k] += w[k];
                    }
                    sum2 += (double)w[0] * w[0];
                    int bt = (int)(wi[2] * NT), bp = (int)(fabs(atan2((double)wi[1], (double)wi[0])) / M_PI * NP);
                    hist[bt < NT ? bt : NT - 1][bp < NP ? bp : NP - 1] += 1.0;
                }
            float ab[2];
            glow_ggx_specular_albedo(mus[im], rs[ir], ab);
            const double n = (double)N * N, se = sqrt(fmax(sum2 / n - (sum[0] / n) * (sum[0] / n), 0.0) / n);
            for (int k = 0; k < 3; ++k) {
                const double want = rho[k] * (1.0 - s.e_o[k]) + 0.04 * ab[0] + ab[1], got = sum[k] / n;
                if (fabs(got - want) > 5.0 * se + 2e-3 * want)
                    fail_msg("r=%g mu=%g channel %d: E[f cos/pdf] %.5f, albedo %.5f (se %.5f)", (double)rs[ir],
                             (double)mus[im], k, got, want, se);
            }
            /* the histogram against ∫ pdf over each bin (32 x 32 midpoint nodes per bin) */
            double worst = 0.0;
            for (int bt = 0; bt < NT; ++bt)
                for (int bp = 0; bp < NP; ++bp) {
                    double p = 0.0;
                    for (int a = 0; a < 32; ++a)
                        for (int b = 0; b < 32; ++b) {
                            const double ct = (bt + (a + 0.5) / 32.0) / NT, ph = (bp + (b + 0.5) / 32.0) / NP * M_PI;
                            const double st = sqrt(1.0 - ct * ct);
                            const float wi[3] = {(float)(st * cos(ph)), (float)(st * sin(ph)), (float)ct};
                            float fd[3], fs[3];
                            p += glow__render_lobe_eval(&s, wi, fd, fs);
                        }
                    const double expect = n * 2.0 * p / 1024.0 * (1.0 / NT) * (M_PI / NP); /* both φ signs */
                    const double d = fabs(hist[bt][bp] - expect) / (5.0 * sqrt(expect + 1.0) + 0.03 * expect);
                    if (d > worst) worst = d;
                    if (d > 1.0)
                        fail_msg("r=%g mu=%g bin (%d, %d): %.0f samples, pdf says %.1f", (double)rs[ir], (double)mus[im], bt,
                                 bp, hist[bt][bp], expect);
                }
        }
}

/* (b) */
static void test_reciprocity_and_energy(void **state) {
    (void)state;
    const float rho[3] = {0.9f, 0.6f, 0.3f};
    static glow__render_ggx mats[8]; /* roughness 0.1 .. 1, F0 0.02 .. 0.9 */
    for (int m = 0; m < 8; ++m) mats[m] = ggx_of(0.1f + 0.9f * (float)m / 7.0f, 0.02f + 0.88f * (float)((m * 5) % 8) / 7.0f);
    uint32_t x = 12345u;
    for (int t = 0; t < 2000; ++t) {
        float u[4];
        for (int k = 0; k < 4; ++k) {
            x = x * 1664525u + 1013904223u;
            u[k] = (float)(x >> 8) * 0x1p-24f;
        }
        const float ca = 0.02f + 0.98f * u[0], cb = 0.02f + 0.98f * u[1], pa = 6.2831853f * u[2], pb = 6.2831853f * u[3];
        const float a[3] = {sqrtf(1 - ca * ca) * cosf(pa), sqrtf(1 - ca * ca) * sinf(pa), ca};
        const float b[3] = {sqrtf(1 - cb * cb) * cosf(pb), sqrtf(1 - cb * cb) * sinf(pb), cb};
        const float ns[3] = {0, 0, 1};
        const glow__render_ggx *g = &mats[t & 7];
        glow__render_lobe la, lb;
        glow__render_lobe_setup(&la, g, ns, ns, a, rho);
        glow__render_lobe_setup(&lb, g, ns, ns, b, rho);
        float fda[3], fsa[3], fdb[3], fsb[3];
        glow__render_lobe_eval(&la, b, fda, fsa);
        glow__render_lobe_eval(&lb, a, fdb, fsb);
        for (int k = 0; k < 3; ++k) {
            const float fab = (fda[k] + fsa[k]) / cb, fba = (fdb[k] + fsb[k]) / ca;
            assert_true(fab >= 0.0f && fba >= 0.0f && fsa[k] >= 0.0f);
            if (fabsf(fab - fba) > 1e-4f * fmaxf(fab, fba) + 1e-7f)
                fail_msg("f(o, i) %.7g != f(i, o) %.7g (cos %g, %g)", (double)fab, (double)fba, (double)ca, (double)cb);
        }
    }
    /* the white furnace: ρ = 1 reflects everything at every view (the diffuse layer takes what the GGX
     * layer leaves); the glossy floor of scenes/cornell-builtin-glossy.json (ρ 0.725, F0 0.04) printed */
    const float fr[] = {0.1f, 0.3f, 0.7f, 1.0f}, fm[] = {1.0f, 0.5f, 0.2f, 0.1f, 0.03f};
    for (int j = 0; j < 4; ++j) {
        const glow__render_ggx g = ggx_of(fr[j], 0.04f);
        printf("albedo, r %.1f, cos θ_o 1 / 0.5 / 0.2 / 0.1 / 0.03: ρ = 1:", (double)fr[j]);
        double floor_alb[5];
        for (int i = 0; i < 5; ++i) {
            for (int pass = 0; pass < 2; ++pass) {
                const float rho1[3] = {1.0f, 1.0f, 1.0f}, rhof[3] = {0.725f, 0.725f, 0.725f};
                glow__render_lobe s;
                lobe_at(&s, &g, fm[i], pass ? rhof : rho1);
                enum { M = 256 };
                double sum = 0.0, sum2 = 0.0;
                for (int a = 0; a < M; ++a)
                    for (int b = 0; b < M; ++b) {
                        float wi[3], w[3], ws[3], pdf;
                        if (!glow__render_lobe_sample(&s, ((float)a + 0.5f) / M, ((float)b + 0.5f) / M, wi, w, ws, &pdf)) continue;
                        sum += w[0];
                        sum2 += (double)w[0] * w[0];
                    }
                const double mean = sum / (M * M), se = sqrt(fmax(sum2 / (M * M) - mean * mean, 0.0) / (M * M));
                if (pass) {
                    floor_alb[i] = mean;
                    assert_true(mean <= 1.0 + 5.0 * se);
                } else {
                    printf(" %.4f", mean);
                    if (fabs(mean - 1.0) > 5.0 * se + 3e-3)
                        fail_msg("white furnace r=%g cos=%g: albedo %.5f (se %.5f)", (double)fr[j], (double)fm[i], mean, se);
                }
            }
        }
        printf("; ρ = 0.725:");
        for (int i = 0; i < 5; ++i) printf(" %.4f", floor_alb[i]);
        printf("\n");
    }
    /* the GGX lobe alone (F0 = 1, kd = 0) reflects at most what arrives */
    const float mus[] = {0.05f, 0.3f, 1.0f}, rs[] = {0.05f, 0.3f, 0.7f, 1.0f};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) {
            float ab[2];
            glow_ggx_specular_albedo(mus[i], rs[j], ab);
            assert_true(ab[0] + ab[1] <= 1.0f + 1e-4f);
        }
}

/* ---------------------------------------------------------------- the floor under a glowing ceiling */
typedef struct fixture {
    char dir[256], json[300], bake[300], bad_json[300];
    glow_render_scene *scene;
} fixture;

static int write_file(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fputs(text, f);
    return fclose(f);
}

#define CEIL_H 1.0f
#define HALF 4.0f
#define ROUGH 0.5f
#define F0 0.5f
#define RHO 0.5f
#define LE 1.0f

static int setup(void **state) {
    static fixture f;
    snprintf(f.dir, sizeof f.dir, "/tmp/glow_render_glossy_%d", (int)getpid());
    if (mkdir(f.dir, 0755) != 0) return -1;
    char path[300];
    snprintf(path, sizeof path, "%s/room.mtl", f.dir);
    if (write_file(path, "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl sky\nKd 0 0 0\nKe 1 1 1\n")) return -1;
    snprintf(path, sizeof path, "%s/room.obj", f.dir);
    /* an 8 x 8 m floor at y = 0 facing +y, an 8 x 8 m ceiling at y = 1 facing -y that emits L_e = 1 */
    if (write_file(path, "mtllib room.mtl\n"
                         "v -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\n"
                         "v -4 1 -4\nv 4 1 -4\nv 4 1 4\nv -4 1 4\n"
                         "usemtl floor\nf 1 4 3\nf 1 3 2\n"
                         "usemtl sky\nf 5 6 7\nf 5 7 8\n"))
        return -1;
    snprintf(f.json, sizeof f.json, "%s/room.json", f.dir);
    /* looking at the floor's centre from 22.6° above it through a 2° field */
    if (write_file(f.json, "{\"mesh\": \"room.obj\", \"camera\": {\"position\": [0, 0.5, 1.2], \"target\": [0, 0, 0],"
                           " \"vfov_deg\": 2, \"width\": 8, \"height\": 8},"
                           " \"materials\": {\"floor\": {\"ggx\": {\"roughness\": 0.5, \"specular\": [0.5, 0.5, 0.5]}}}}\n"))
        return -1;
    snprintf(f.bad_json, sizeof f.bad_json, "%s/bad.json", f.dir);
    if (write_file(f.bad_json, "{\"mesh\": \"room.obj\", \"materials\": {\"flor\": {\"ggx\": {\"roughness\": 0.5}}}}\n")) return -1;
    char msg[1024];
    if (glow_render_scene_load(f.json, &f.scene, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, "%s\n", msg);
        return -1;
    }
    snprintf(f.bake, sizeof f.bake, "%s/room.glow", f.dir);
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 4096, .links = 96, .bands = 4, .threads = 2, .seed = 1};
    glow_pc_stats st;
    if (glow_pc_bake(path, f.bake, &s, &st) != GLOW_OK) return -1;
    *state = &f;
    return 0;
}

static int teardown(void **state) {
    fixture *f = *state;
    glow_render_scene_destroy(f->scene);
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf %s", f->dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* The floor's reflection at the origin towards the camera: ∫ L_e f cos θ_i cos θ_l / d² dA over the
 * ceiling (midpoint rule, 800 x 800), total and GGX part. */
static void reflection_integral(double *total, double *spec) {
    const glow__render_ggx g = ggx_of(ROUGH, F0);
    const float rho[3] = {RHO, RHO, RHO}, ns[3] = {0.0f, 1.0f, 0.0f};
    float wo[3] = {0.0f, 0.5f, 1.2f};
    const float l = sqrtf(0.25f + 1.44f);
    for (int k = 0; k < 3; ++k) wo[k] /= l;
    glow__render_lobe s;
    glow__render_lobe_setup(&s, &g, ns, ns, wo, rho);
    const int n = 800;
    const double h = 2.0 * HALF / n;
    double t = 0.0, sp = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double px = -HALF + (i + 0.5) * h, pz = -HALF + (j + 0.5) * h, d2 = px * px + CEIL_H * CEIL_H + pz * pz;
            const double d = sqrt(d2);
            const float wi[3] = {(float)(px / d), (float)(CEIL_H / d), (float)(pz / d)};
            float fd[3], fs[3];
            glow__render_lobe_eval(&s, wi, fd, fs); /* f cos θ_i */
            const double geo = LE * (CEIL_H / d) / d2 * h * h;
            t += (fd[0] + fs[0]) * geo;
            sp += fs[0] * geo;
        }
    *total = t;
    *spec = sp;
}

/* What the split sum predicts with the exact incident field: (F0 A + B)(cos θ_o) × the mean of L_in
 * under the normalised normal-incidence GGX lobe about `axis` (the ceiling's directions carry L_e,
 * all others 0), by the same midpoint rule. No SH: the model's own error, apart from the caches'. */
static double split_sum_prediction(const float axis_in[3]) {
    const double a = (double)ROUGH * ROUGH, a2 = a * a;
    float axis[3] = {axis_in[0], axis_in[1], axis_in[2]};
    const float al = sqrtf(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    for (int k = 0; k < 3; ++k) axis[k] /= al;
    /* the lobe p(θ) = D(θ/2) G1(cos θ) / 4 / m0, m0 its integral (midpoint rule in θ) */
    double m0 = 0.0;
    const int nt = 200000;
    for (int i = 0; i < nt; ++i) {
        const double t = (i + 0.5) * 0.5 * M_PI / nt, ch = cos(0.5 * t), c = cos(t);
        const double dd = ch * ch * (a2 - 1.0) + 1.0, d = a2 / (M_PI * dd * dd);
        const double g1 = 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
        m0 += d * g1 / 4.0 * 2.0 * M_PI * sin(t) * 0.5 * M_PI / nt;
    }
    const int n = 800;
    const double h = 2.0 * HALF / n;
    double acc = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double px = -HALF + (i + 0.5) * h, pz = -HALF + (j + 0.5) * h, d2 = px * px + CEIL_H * CEIL_H + pz * pz;
            const double d = sqrt(d2);
            const double c = (px * axis[0] + CEIL_H * axis[1] + pz * axis[2]) / d;
            if (!(c > 0.0)) continue;
            const double ch2 = 0.5 * (1.0 + c), dd = ch2 * (a2 - 1.0) + 1.0, dv = a2 / (M_PI * dd * dd);
            const double g1 = 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
            acc += dv * g1 / 4.0 / m0 * LE * (CEIL_H / d) / d2 * h * h;
        }
    float ab[2];
    glow_ggx_specular_albedo(0.5f / sqrtf(0.25f + 1.44f), ROUGH, ab);
    return (F0 * ab[0] + ab[1]) * acc;
}

static void image_stats(const glow_eval_image *im, double *mean, double *se) {
    const size_t n = (size_t)im->width * im->height;
    double s = 0.0, s2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double v = im->rgb[3 * i];
        s += v;
        s2 += v * v;
    }
    *mean = s / n;
    *se = sqrt(fmax(s2 / n - *mean * *mean, 0.0) / n);
}

/* (c) */
static void test_reference_vs_integral(void **state) {
    fixture *f = *state;
    double total, spec;
    reflection_integral(&total, &spec);
    glow_render_settings st = {.spp = 1024, .seed = 5, .threads = 2};
    glow_render_result r;
    char msg[512];
    assert_int_equal(glow_render_reference(f->scene, &st, &r, msg, sizeof msg), GLOW_OK);
    assert_non_null(r.specular.rgb);
    double mi, si, ms, ss;
    image_stats(&r.indirect, &mi, &si);
    image_stats(&r.specular, &ms, &ss);
    printf("glossy floor: reference indirect %.5f (se %.5f), integral %.5f; specular %.5f (se %.5f), integral %.5f\n", mi,
           si, total, ms, ss, spec);
    assert_true(r.mean_direct[0] == 0.0);
    /* the pixels see a 12 cm strip of the floor around the origin: 0.5 % for the integral's point */
    if (fabs(mi - total) > 5.0 * si + 5e-3 * total) fail_msg("indirect %.5f vs integral %.5f", mi, total);
    if (fabs(ms - spec) > 5.0 * ss + 5e-3 * spec) fail_msg("specular %.5f vs integral %.5f", ms, spec);
    glow_render_result_free(&r);
}

/* (d) */
static void test_glow_view(void **state) {
    fixture *f = *state;
    glow_render_settings st = {.spp = 256, .seed = 5, .threads = 2};
    glow_render_result ref, gv, ph, dd;
    char msg[512];
    assert_int_equal(glow_render_reference(f->scene, &st, &ref, msg, sizeof msg), GLOW_OK);
    glow_render_glow_settings gs = {.bounce_iterations = 8};
    if (glow_render_glow(f->scene, f->bake, &st, &gs, &gv, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    gs.glossy = GLOW_RENDER_GLOSSY_PHONG;
    if (glow_render_glow(f->scene, f->bake, &st, &gs, &ph, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    gs.glossy = GLOW_RENDER_GLOSSY_ZH_GGX_DOMINANT;
    if (glow_render_glow(f->scene, f->bake, &st, &gs, &dd, msg, sizeof msg) != GLOW_OK) fail_msg("%s", msg);
    const size_t n = (size_t)gv.width * gv.height * 3;
    for (size_t i = 0; i < n; ++i)
        assert_true(isfinite(gv.final.rgb[i]) && isfinite(gv.specular.rgb[i]) && gv.specular.rgb[i] >= 0.0f);
    assert_int_equal(gv.nonfinite_samples, 0);
    assert_memory_equal(gv.direct.rgb, ref.direct.rgb, n * sizeof(float));
    double integral, spec;
    reflection_integral(&integral, &spec);
    const float wo[3] = {0.0f, 0.5f, 1.2f}, r[3] = {-wo[0], wo[1], -wo[2]}; /* the reflection vector about +y */
    const double pred = split_sum_prediction(r);
    const float al = ROUGH * ROUGH, sm = 1.0f - al, t = sm * (sqrtf(sm) + al);
    const float lr = sqrtf(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    const float dom[3] = {t * r[0] / lr, 1.0f + t * (r[1] / lr - 1.0f), t * r[2] / lr};
    const double pred_dom = split_sum_prediction(dom);
    printf("split sum with the exact field: about the reflection vector %.5f, about the dominant direction %.5f\n", pred,
           pred_dom);
    printf("glossy floor, Glow's view: specular ZH-GGX %.5f, dominant direction %.5f, Phong %.5f, reference %.5f, "
           "integral %.5f; diffuse %.5f vs %.5f\n",
           gv.mean_specular[0], dd.mean_specular[0], ph.mean_specular[0], ref.mean_specular[0], spec, gv.mean_indirect[0] - gv.mean_specular[0],
           ref.mean_indirect[0] - ref.mean_specular[0]);
    /* Glow computes the split sum from band-limited caches: within 10 % of the split sum with the exact
     * field (measured -4.7 % and -5.0 % with this 4-band bake); the split sum itself is 28 % (about the
     * reflection vector) and 13 % (dominant direction) below the true reflection at this grazing view */
    if (fabs(gv.mean_specular[0] - pred) > 0.10 * pred) fail_msg("Glow's specular %.5f vs split sum %.5f", gv.mean_specular[0], pred);
    if (fabs(dd.mean_specular[0] - pred_dom) > 0.10 * pred_dom)
        fail_msg("Glow's specular (dominant direction) %.5f vs split sum %.5f", dd.mean_specular[0], pred_dom);
    assert_true(fabs(dd.mean_specular[0] - spec) < fabs(gv.mean_specular[0] - spec));
    const double dg = gv.mean_indirect[0] - gv.mean_specular[0], dr = ref.mean_indirect[0] - ref.mean_specular[0];
    if (fabs(dg - dr) > 0.05 * dr) fail_msg("Glow's diffuse %.5f vs the reference's %.5f", dg, dr);
    glow_render_result_free(&ref);
    glow_render_result_free(&gv);
    glow_render_result_free(&ph);
    glow_render_result_free(&dd);
}

/* (e) */
static void test_unknown_material(void **state) {
    fixture *f = *state;
    glow_render_scene *s = NULL;
    char msg[1024];
    assert_int_equal(glow_render_scene_load(f->bad_json, &s, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(s);
    assert_non_null(strstr(msg, "bad.json"));
    assert_non_null(strstr(msg, "materials.flor"));
    assert_non_null(strstr(msg, "floor")); /* the names it has */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sampling_matches_eval), cmocka_unit_test(test_reciprocity_and_energy),
        cmocka_unit_test(test_reference_vs_integral), cmocka_unit_test(test_glow_view),
        cmocka_unit_test(test_unknown_material),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
