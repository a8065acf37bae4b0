/* test_sky.c — the sky as SH (docs/sky.md): the runtime's pure sky functions against quadrature and
 * closed forms (rotation, triple products, constant sky), the linker's sky transfer (SKYT) against the
 * analytic cosine lobe on an open plane and against the CPU host's own traced S and T, a rotated sky
 * moving light from one wall to another, the section's round trip, determinism over thread counts,
 * validation of corrupted sections and bakes without the section. */
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
#include "glow/glow_host.h"
#include "glow/glow_precompute.h"
#include "runtime_internal.h"
#include "bake/bake_format.h"
#include "../fuzz/fuzz_reseal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct fixture {
    glow_context *ctx;
    char plane_obj[128], plane_bake[128], open_obj[128], open_bake[128], open_nosky[128], open_t1[128];
    glow_bake *plane, *open, *nosky;
} fixture;

/* ------------------------------------------------------------------------------ scenes */
static void wr_tri(FILE *f, int *nv, const double p[3][3]) {
    for (int k = 0; k < 3; ++k) fprintf(f, "v %.6f %.6f %.6f\n", p[k][0], p[k][1], p[k][2]);
    fprintf(f, "f %d %d %d\n", *nv + 1, *nv + 2, *nv + 3);
    *nv += 3;
}

/* A planar quad a b c d, wound so its normal points along `facing`. */
static void wr_quad(FILE *f, int *nv, const double a[3], const double b[3], const double c[3], const double d[3],
                    const double facing[3]) {
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    bool ok = n[0] * facing[0] + n[1] * facing[1] + n[2] * facing[2] > 0;
    const double t1[3][3] = {{a[0], a[1], a[2]}, {b[0], b[1], b[2]}, {c[0], c[1], c[2]}};
    const double t2[3][3] = {{a[0], a[1], a[2]}, {c[0], c[1], c[2]}, {d[0], d[1], d[2]}};
    const double u1[3][3] = {{a[0], a[1], a[2]}, {c[0], c[1], c[2]}, {b[0], b[1], b[2]}};
    const double u2[3][3] = {{a[0], a[1], a[2]}, {d[0], d[1], d[2]}, {c[0], c[1], c[2]}};
    wr_tri(f, nv, ok ? t1 : u1);
    wr_tri(f, nv, ok ? t2 : u2);
}

/* One upward quad [-2,2]² at y = 0: every surfel sees the whole sky above it. */
static void write_plane(const char *path) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    int nv = 0;
    const double up[3] = {0, 1, 0}, a[3] = {-2, 0, -2}, b[3] = {2, 0, -2}, c[3] = {2, 0, 2}, d[3] = {-2, 0, 2};
    wr_quad(f, &nv, a, b, c, d, up);
    fclose(f);
}

/* test_host.c's open scene: floor [-3,3]² at y = 0, a unit box [-0.5,0.5]x[0,1]x[-0.5,0.5] (5 outward
 * faces), a one-sided plate x in [1,2], z in [-2,-1] at y = 1.5 facing down. */
static void write_open(const char *path) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    int nv = 0;
    const double up[3] = {0, 1, 0}, down[3] = {0, -1, 0};
    const double f0[3] = {-3, 0, -3}, f1[3] = {3, 0, -3}, f2[3] = {3, 0, 3}, f3[3] = {-3, 0, 3};
    wr_quad(f, &nv, f0, f1, f2, f3, up);
    double c[8][3];
    for (int i = 0; i < 8; ++i) {
        c[i][0] = i & 1 ? 0.5 : -0.5;
        c[i][1] = i & 2 ? 1.0 : 0.0;
        c[i][2] = i & 4 ? 0.5 : -0.5;
    }
    const double px[3] = {1, 0, 0}, nx[3] = {-1, 0, 0}, pz[3] = {0, 0, 1}, nz[3] = {0, 0, -1};
    wr_quad(f, &nv, c[1], c[3], c[7], c[5], px);
    wr_quad(f, &nv, c[0], c[2], c[6], c[4], nx);
    wr_quad(f, &nv, c[4], c[5], c[7], c[6], pz);
    wr_quad(f, &nv, c[0], c[1], c[3], c[2], nz);
    wr_quad(f, &nv, c[2], c[3], c[7], c[6], up);
    const double q0[3] = {1, 1.5, -2}, q1[3] = {2, 1.5, -2}, q2[3] = {2, 1.5, -1}, q3[3] = {1, 1.5, -1};
    wr_quad(f, &nv, q0, q1, q2, q3, down);
    fclose(f);
}

static glow_bake *bake(fixture *fx, const char *scene, const char *out, bool no_sky, uint32_t threads) {
    glow_pc_settings s = {.surfels = 4096, .links = 16, .bands = 2, .grid_spacing = 0.5f, .texel_density = 2.0f,
                          .threads = threads, .seed = 1, .no_sky = no_sky};
    glow_pc_stats st;
    glow_result r = glow_pc_bake(scene, out, &s, &st);
    if (r != GLOW_OK) fail_msg("bake of %s failed: %s", scene, st.error);
    assert_int_equal(st.sky_rays, no_sky ? 0u : 128u);
    glow_bake *b = NULL;
    assert_int_equal(glow_bake_load_file(fx->ctx, out, &b), GLOW_OK);
    return b;
}

static int setup(void **state) {
    fixture *fx = calloc(1, sizeof *fx);
    assert_non_null(fx);
    glow_context_desc cd = {.api_version = GLOW_VERSION};
    assert_int_equal(glow_context_create(&cd, &fx->ctx), GLOW_OK);
    const int pid = (int)getpid();
    snprintf(fx->plane_obj, sizeof fx->plane_obj, "/tmp/glow_sky_plane_%d.obj", pid);
    snprintf(fx->plane_bake, sizeof fx->plane_bake, "/tmp/glow_sky_plane_%d.glow", pid);
    snprintf(fx->open_obj, sizeof fx->open_obj, "/tmp/glow_sky_open_%d.obj", pid);
    snprintf(fx->open_bake, sizeof fx->open_bake, "/tmp/glow_sky_open_%d.glow", pid);
    snprintf(fx->open_nosky, sizeof fx->open_nosky, "/tmp/glow_sky_open_nosky_%d.glow", pid);
    snprintf(fx->open_t1, sizeof fx->open_t1, "/tmp/glow_sky_open_t1_%d.glow", pid);
    write_plane(fx->plane_obj);
    write_open(fx->open_obj);
    fx->plane = bake(fx, fx->plane_obj, fx->plane_bake, false, 2);
    fx->open = bake(fx, fx->open_obj, fx->open_bake, false, 2);
    fx->nosky = bake(fx, fx->open_obj, fx->open_nosky, true, 2);
    *state = fx;
    return 0;
}

static int teardown(void **state) {
    fixture *fx = *state;
    glow_bake_destroy(fx->plane);
    glow_bake_destroy(fx->open);
    glow_bake_destroy(fx->nosky);
    glow_context_destroy(fx->ctx);
    unlink(fx->plane_obj);
    unlink(fx->plane_bake);
    unlink(fx->open_obj);
    unlink(fx->open_bake);
    unlink(fx->open_nosky);
    unlink(fx->open_t1);
    free(fx);
    return 0;
}

/* Gauss-Legendre nodes on [-1, 1] (Newton on P_n). */
static void gauss_legendre(int n, double *x, double *w) {
    for (int i = 0; i < n; ++i) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), p0 = 1, p1 = z, dp = 1;
        for (int it = 0; it < 100; ++it) {
            p0 = 1;
            p1 = z;
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1);
            z -= p1 / dp;
        }
        x[i] = z;
        w[i] = 2 / ((1 - z * z) * dp * dp);
    }
}

/* -------------------------------------------------------------------------- pure functions */

/* The triple products against quadrature (exact for these degrees), and the product of a fully visible
 * cache (V = √(4π) y_0) with any sky is that sky. */
static void test_gaunt_and_product(void **state) {
    (void)state;
    enum { NZ = 12, NP = 32 };
    double zx[NZ], zw[NZ];
    gauss_legendre(NZ, zx, zw);
    static double G[9][9][9];
    memset(G, 0, sizeof G);
    for (int a = 0; a < NZ; ++a)
        for (int b = 0; b < NP; ++b) {
            const double z = zx[a], s = sqrt(1 - z * z), ph = 2 * M_PI * (b + 0.5) / NP;
            const float d[3] = {(float)(s * cos(ph)), (float)(s * sin(ph)), (float)z};
            float y[9];
            glow_sh_eval(3, d, y);
            const double w = zw[a] * 2 * M_PI / NP;
            for (int i = 0; i < 9; ++i)
                for (int j = 0; j < 9; ++j)
                    for (int k = 0; k < 9; ++k) G[i][j][k] += w * y[i] * y[j] * y[k];
        }
    for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 9; ++j)
            for (int k = 0; k < 9; ++k)
                if (fabs(glow_sh_gaunt_l2((uint32_t)i, (uint32_t)j, (uint32_t)k) - G[i][j][k]) > 2e-6)
                    fail_msg("gaunt %d %d %d: %g, quadrature %g", i, j, k, (double)glow_sh_gaunt_l2((uint32_t)i, (uint32_t)j, (uint32_t)k), G[i][j][k]);
    float V[9] = {(float)sqrt(4 * M_PI)}, L[GLOW_SKY_SH_FLOATS], out[GLOW_SKY_SH_FLOATS];
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k) L[k] = (float)sin(1.0 + k);
    glow_sh_sky_visible(V, L, out);
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k) assert_true(fabsf(out[k] - L[k]) < 1e-5f);
    /* a hemisphere visible (upper +Y half), constant sky: the product is that hemisphere's SH,
     * i.e. L · V */
    float Vh[9] = {0}, C[GLOW_SKY_SH_FLOATS];
    Vh[0] = (float)(2 * M_PI * 0.28209479177387814);       /* ∫_hemi y_0 */
    Vh[1] = (float)(M_PI * 0.4886025119029199);            /* ∫_hemi y_1 = c ∫ y dω over y > 0 */
    const float one[3] = {1, 2, 3};
    glow_sh_sky_constant(one, C);
    glow_sh_sky_visible(Vh, C, out);
    for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c) assert_true(fabsf(out[3 * k + c] - one[c] * Vh[k]) < 1e-5f);
}

/* Rotation: the rotated SH evaluated at R d equals the original at d (exact for l <= 2), 90° about +Y
 * turns +X into -Z, and rotation keeps the irradiance of a rotated normal. */
static void eval_sky(const float *L, const float d[3], float out[3]) {
    float y[9];
    glow_sh_eval(3, d, y);
    out[0] = out[1] = out[2] = 0;
    for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c) out[c] += y[k] * L[3 * k + c];
}

static void test_rotation(void **state) {
    (void)state;
    float L[GLOW_SKY_SH_FLOATS], Lr[GLOW_SKY_SH_FLOATS];
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k) L[k] = (float)cos(0.7 * k + 0.3);
    const float angles[] = {0.0f, 0.4f, (float)(M_PI / 2), 2.5f, -1.0f};
    for (size_t a = 0; a < sizeof angles / sizeof angles[0]; ++a) {
        const float t = angles[a];
        glow_sh_rotate_y(L, t, Lr);
        for (int i = 0; i < 40; ++i) {
            const double th = acos(1 - 2 * (i + 0.5) / 40), ph = 2.39996 * i;
            const float d[3] = {(float)(sin(th) * cos(ph)), (float)cos(th), (float)(sin(th) * sin(ph))};
            const float Rd[3] = {cosf(t) * d[0] + sinf(t) * d[2], d[1], -sinf(t) * d[0] + cosf(t) * d[2]};
            float want[3], got[3];
            eval_sky(L, d, want);
            eval_sky(Lr, Rd, got);
            for (int c = 0; c < 3; ++c)
                if (fabsf(want[c] - got[c]) > 2e-5f)
                    fail_msg("angle %g dir %d channel %d: %g vs %g", (double)t, i, c, (double)got[c], (double)want[c]);
        }
    }
    /* a delta towards +X turned 90° points to -Z */
    const float px[3] = {1, 0, 0}, mz[3] = {0, 0, -1};
    float y[9], D[GLOW_SKY_SH_FLOATS], ym[9];
    glow_sh_eval(3, px, y);
    for (int k = 0; k < 9; ++k) D[3 * k] = D[3 * k + 1] = D[3 * k + 2] = y[k];
    glow_sh_rotate_y(D, (float)(M_PI / 2), Lr);
    glow_sh_eval(3, mz, ym);
    for (int k = 0; k < 9; ++k) assert_true(fabsf(Lr[3 * k] - ym[k]) < 1e-6f);
    /* in place */
    memcpy(Lr, L, sizeof L);
    glow_sh_rotate_y(Lr, 0.0f, Lr);
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k) assert_true(fabsf(Lr[k] - L[k]) < 1e-6f);
    /* irradiance clamps at 0 and ignores NaN */
    float T[9] = {1}, S[GLOW_SKY_SH_FLOATS] = {-1, 2, NAN}, e[3];
    glow_sh_sky_irradiance(T, S, e);
    assert_true(e[0] == 0.0f && e[1] == 2.0f && e[2] == 0.0f);
}

/* ------------------------------------------------------------------------------ the bake */

/* On an open plane every surfel's T is the cosine lobe's projection Â_l y_k(n), Â = (π, 2π/3, π/4),
 * within the 128 rays' quadrature error (T_0 exactly); for a constant sky Σ T L = π L exactly. */
static void test_open_plane(void **state) {
    fixture *fx = *state;
    glow_bake_sky_transfer st;
    assert_int_equal(glow_bake_get_sky_transfer(fx->plane, &st), GLOW_OK);
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(fx->plane, &info), GLOW_OK);
    assert_non_null(st.surfel_transfer);
    assert_int_equal(st.surfel_count, info.surfel_count);
    assert_int_equal(st.grid_cache_count, info.grid_cache_count);
    assert_int_equal(st.rays, 128);
    assert_int_equal(st.grid_rays, 1024);
    const glow_bake_surfel *sf = glow__bake_surfels(fx->plane);
    const double Ahat[3] = {M_PI, 2 * M_PI / 3, M_PI / 4};
    double worst = 0;
    for (uint32_t i = 0; i < st.surfel_count; ++i) {
        float y[9];
        glow_sh_eval(3, sf[i].normal, y);
        const float *T = st.surfel_transfer + 9 * (size_t)i;
        for (int k = 0; k < 9; ++k) {
            const double want = Ahat[k == 0 ? 0 : k < 4 ? 1 : 2] * y[k], err = fabs(T[k] - want);
            if (err > worst) worst = err;
        }
        assert_true(fabs(T[0] - M_PI * 0.28209479177387814) < 1e-5);
        const float env[3] = {1, 2, 3};
        float L[GLOW_SKY_SH_FLOATS], e[3];
        glow_sh_sky_constant(env, L);
        glow_sh_sky_irradiance(T, L, e);
        for (int c = 0; c < 3; ++c) assert_true(fabsf(e[c] - (float)M_PI * env[c]) < 1e-4f * env[c]);
    }
    print_message("open plane: %u surfels, worst |T - analytic| %.2e (128 rays)\n", st.surfel_count, worst);
    assert_true(worst < 0.02);
    /* the grid: every cache sees at least the upper half of the sphere, none more than all of it */
    const double full = sqrt(4 * M_PI);
    for (uint32_t c = 0; c < st.grid_cache_count; ++c) {
        const float *V = st.grid_visibility + 9 * (size_t)c;
        assert_true(V[0] <= full + 1e-4 && V[0] >= 0.45 * full);
    }
}

typedef struct surfels {
    uint32_t n;
    float *pos, *nor, *out;
} surfels;

static surfels get_surfels(const glow_bake *b) {
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(b, &info), GLOW_OK);
    const glow_bake_surfel *sf = glow__bake_surfels(b);
    surfels s = {info.surfel_count, malloc(sizeof(float) * 4 * info.surfel_count),
                 malloc(sizeof(float) * 4 * info.surfel_count), malloc(sizeof(float) * 3 * info.surfel_count)};
    assert_true(s.pos && s.nor && s.out);
    for (uint32_t i = 0; i < s.n; ++i) {
        memcpy(s.pos + 4 * i, sf[i].position, 12);
        s.pos[4 * i + 3] = glow__bake_nodes(b)[i].area;
        memcpy(s.nor + 4 * i, sf[i].normal, 12);
        s.nor[4 * i + 3] = 0;
    }
    return s;
}

static void free_surfels(surfels *s) {
    free(s->pos);
    free(s->nor);
    free(s->out);
}

static void run_hook(glow_host *h, const surfels *s, float *out) {
    glow_lighting_hooks hk = glow_host_hooks(h);
    glow_surfel_batch b = {.first = 0, .count = s->n, .positions = s->pos, .normals = s->nor};
    assert_int_equal(hk.light_surfels(hk.user, &b, out, 0), GLOW_OK);
}

static glow_host *host(const glow_bake *b, const float env[3]) {
    glow_host_desc d = {.kind = GLOW_HOST_KIND_EXACT, .bake = b};
    if (env) memcpy(d.environment, env, sizeof d.environment);
    glow_host *h = NULL;
    assert_int_equal(glow_host_create(&d, &h), GLOW_OK);
    return h;
}

/* A constant sky through the SH path equals the constant environment's L π S: exactly (ray for ray)
 * with T traced by the host for a bake without SKYT, within the rays' noise with the bake's T. */
static void test_constant_sky_matches_S(void **state) {
    fixture *fx = *state;
    const float env[3] = {0.5f, 1.0f, 2.0f};
    float L[GLOW_SKY_SH_FLOATS];
    glow_sh_sky_constant(env, L);
    const glow_bake *bakes[2] = {fx->nosky, fx->open};
    for (int which = 0; which < 2; ++which) {
        surfels s = get_surfels(bakes[which]);
        float *ref = malloc(sizeof(float) * 3 * s.n);
        glow_host *a = host(bakes[which], env), *b = host(bakes[which], NULL);
        run_hook(a, &s, ref);
        assert_int_equal(glow_host_set_environment_sh(b, L), GLOW_OK);
        glow_host_stats hs;
        assert_int_equal(glow_host_get_stats(b, &hs), GLOW_OK);
        assert_int_equal(hs.sky_sh, 1);
        assert_int_equal(hs.sky_transfer_baked, which == 1);
        run_hook(b, &s, s.out);
        double sum_ref = 0, sum = 0, worst = 0;
        uint32_t differ = 0;
        for (uint32_t i = 0; i < 3 * s.n; ++i) {
            sum_ref += ref[i];
            sum += s.out[i];
            const double d = fabs((double)s.out[i] - ref[i]) / (M_PI * env[i % 3]); /* in units of S */
            if (d > worst) worst = d;
            differ += d > 1e-5;
        }
        print_message("constant sky via SH (%s T): mean %.5f vs %.5f (S path), worst |ΔS| %.4f, %u of %u values "
                      "differ by > 1e-5\n", which ? "baked" : "traced", sum / s.n, sum_ref / s.n, worst, differ, 3 * s.n);
        if (which == 0) {
            assert_true(worst < 1e-5);
        } else { /* a few rays may flip between linker and host; each is 1/128 of S */
            assert_true(fabs(sum - sum_ref) < 2e-3 * sum_ref);
            assert_true(worst < 4.5 / 128.0);
            assert_true(differ < 3 * s.n / 20);
        }
        /* back to the constant sky: the same as before */
        assert_int_equal(glow_host_set_environment_sh(b, NULL), GLOW_OK);
        assert_int_equal(glow_host_set_environment(b, env), GLOW_OK);
        run_hook(b, &s, s.out);
        assert_memory_equal(s.out, ref, sizeof(float) * 3 * s.n);
        glow_host_destroy(a);
        glow_host_destroy(b);
        free(ref);
        free_surfels(&s);
    }
}

/* The bake's T against the host's traced T on the same surfels (the bakes differ only in SKYT), and
 * the same SKYT bytes from a one-thread bake. */
static void test_roundtrip_and_threads(void **state) {
    fixture *fx = *state;
    glow_bake_sky_transfer bt, nt;
    assert_int_equal(glow_bake_get_sky_transfer(fx->open, &bt), GLOW_OK);
    assert_int_equal(glow_bake_get_sky_transfer(fx->nosky, &nt), GLOW_OK);
    assert_null(nt.surfel_transfer);
    assert_null(nt.grid_visibility);
    assert_int_equal(nt.surfel_count, 0);
    assert_non_null(bt.grid_visibility);
    surfels s = get_surfels(fx->nosky);
    assert_int_equal(s.n, bt.surfel_count);
    float *T = malloc(sizeof(float) * 9 * s.n);
    glow_host *h = host(fx->nosky, NULL);
    glow_surfel_view v = {.count = s.n, .positions = s.pos, .normals = s.nor};
    assert_int_equal(glow_host_sky_transfer(h, &v, T, s.n), GLOW_OK);
    uint32_t same = 0;
    double worst = 0;
    for (uint32_t i = 0; i < 9 * s.n; ++i) {
        const double d = fabs((double)T[i] - bt.surfel_transfer[i]);
        same += d < 1e-5;
        if (d > worst) worst = d;
    }
    print_message("baked T vs host-traced T: %u of %u values equal, worst difference %.4f\n", same, 9 * s.n, worst);
    assert_true(same > 9 * s.n * 9 / 10);
    assert_true(worst < 0.2);
    glow_host_destroy(h);
    free(T);
    free_surfels(&s);
    /* one thread, the same bytes */
    glow_bake *t1 = bake(fx, fx->open_obj, fx->open_t1, false, 1);
    glow_bake_sky_transfer ot;
    assert_int_equal(glow_bake_get_sky_transfer(t1, &ot), GLOW_OK);
    assert_int_equal(ot.surfel_count, bt.surfel_count);
    assert_int_equal(ot.grid_cache_count, bt.grid_cache_count);
    assert_memory_equal(ot.surfel_transfer, bt.surfel_transfer, sizeof(float) * 9 * bt.surfel_count);
    assert_memory_equal(ot.grid_visibility, bt.grid_visibility, sizeof(float) * 9 * bt.grid_cache_count);
    glow_bake_destroy(t1);
}

/* A sky bright towards +X lights the box's +X wall; turned 90° about +Y it lights the -Z wall. */
static double wall_mean(const surfels *s, const float *out, const float n[3]) {
    double sum = 0;
    uint32_t cnt = 0;
    for (uint32_t i = 0; i < s->n; ++i) {
        const float *p = s->pos + 4 * i, *m = s->nor + 4 * i;
        if (m[0] * n[0] + m[1] * n[1] + m[2] * n[2] < 0.99f) continue;
        if (fabsf(p[0]) > 0.51f || fabsf(p[2]) > 0.51f || p[1] < 0.05f || p[1] > 0.95f) continue; /* the box's walls */
        sum += out[3 * i];
        cnt++;
    }
    assert_true(cnt > 20);
    return sum / cnt;
}

static void test_rotated_sky(void **state) {
    fixture *fx = *state;
    surfels s = get_surfels(fx->open);
    glow_host *h = host(fx->open, NULL);
    /* a lobe towards +X: the SH of max(0, x)² scaled, plus a little constant, white */
    const float px[3] = {1, 0, 0};
    float y[9], L[GLOW_SKY_SH_FLOATS], Lr[GLOW_SKY_SH_FLOATS];
    glow_sh_eval(3, px, y);
    const float band[3] = {1.0f, 2.0f / 3.0f, 0.25f};
    for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c) L[3 * k + c] = 2.0f * band[k == 0 ? 0 : k < 4 ? 1 : 2] * y[k];
    L[0] += 0.1f;
    L[1] += 0.1f;
    L[2] += 0.1f;
    const float wx[3] = {1, 0, 0}, wmx[3] = {-1, 0, 0}, wz[3] = {0, 0, 1}, wmz[3] = {0, 0, -1};
    assert_int_equal(glow_host_set_environment_sh(h, L), GLOW_OK);
    run_hook(h, &s, s.out);
    const double a_px = wall_mean(&s, s.out, wx), a_mx = wall_mean(&s, s.out, wmx), a_pz = wall_mean(&s, s.out, wz),
                 a_mz = wall_mean(&s, s.out, wmz);
    glow_sh_rotate_y(L, (float)(M_PI / 2), Lr);
    assert_int_equal(glow_host_set_environment_sh(h, Lr), GLOW_OK);
    run_hook(h, &s, s.out);
    const double b_px = wall_mean(&s, s.out, wx), b_mx = wall_mean(&s, s.out, wmx), b_pz = wall_mean(&s, s.out, wz),
                 b_mz = wall_mean(&s, s.out, wmz);
    print_message("sky towards +X: walls +X %.3f -X %.3f +Z %.3f -Z %.3f; turned 90° about +Y: +X %.3f -X %.3f "
                  "+Z %.3f -Z %.3f\n", a_px, a_mx, a_pz, a_mz, b_px, b_mx, b_pz, b_mz);
    assert_true(a_px > 3 * a_mx && a_px > 2 * a_pz && a_px > 2 * a_mz);
    assert_true(b_mz > 3 * b_pz && b_mz > 2 * b_px && b_mz > 2 * b_mx);
    assert_true(fabs(b_mz - a_px) < 0.1 * a_px); /* the same wall, turned (the scene is symmetric) */
    glow_host_destroy(h);
    free_surfels(&s);
}

/* The grid: glow_system_set_sky adds the visible sky to the grid caches, not to the lightmap's and not
 * into the surfels' bounce; above the floor a lookup facing up sees the whole sky, facing down little. */
static void test_system_sky(void **state) {
    fixture *fx = *state;
    glow_system *sys = NULL;
    assert_int_equal(glow_system_create(fx->ctx, &(glow_system_desc){.bake = fx->open}, &sys), GLOW_OK);
    const float env[3] = {1.0f, 2.0f, 4.0f};
    float L[GLOW_SKY_SH_FLOATS];
    glow_sh_sky_constant(env, L);
    assert_int_equal(glow_system_set_sky(sys, L), GLOW_OK);
    for (int u = 0; u < 3; ++u) assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    const glow_cache_outputs *o = glow_system_outputs(sys);
    const uint32_t nc = o->coeff_count;
    float *sh = malloc(sizeof(float) * nc), rgb[3];
    const float p[3] = {1.5f, 0.6f, 1.5f}, up[3] = {0, 1, 0}, down[3] = {0, -1, 0};
    assert_int_equal(glow_sample_grid(o, p, sh), GLOW_OK);
    glow_shade_sh(sh, o->sh_bands_luma, o->sh_bands_chroma, up, 1.0f, rgb);
    print_message("grid sky, constant (1, 2, 4): facing up %.3f %.3f %.3f", rgb[0], rgb[1], rgb[2]);
    for (int c = 0; c < 3; ++c) assert_true(fabsf(rgb[c] - env[c]) < 0.15f * env[c]); /* l <= 1 here (bands 2) */
    glow_shade_sh(sh, o->sh_bands_luma, o->sh_bands_chroma, down, 1.0f, rgb);
    print_message(", facing down %.3f %.3f %.3f\n", rgb[0], rgb[1], rgb[2]);
    for (int c = 0; c < 3; ++c) assert_true(rgb[c] < 0.35f * env[c]);
    /* nothing else is lit: no lights, and the sky does not bounce through the runtime */
    for (uint64_t i = (uint64_t)o->grid_cache_count * nc; i < (uint64_t)o->cache_count * nc; ++i)
        assert_true(o->cache_sh[i] == 0.0f);
    /* removed: the grid is dark again after the next update */
    assert_int_equal(glow_system_set_sky(sys, NULL), GLOW_OK);
    assert_int_equal(glow_system_update(sys, NULL), GLOW_OK);
    for (uint64_t i = 0; i < (uint64_t)o->cache_count * nc; ++i) assert_true(o->cache_sh[i] == 0.0f);
    L[4] = NAN;
    assert_int_equal(glow_system_set_sky(sys, L), GLOW_ERROR_INVALID_ARGUMENT);
    glow_system_destroy(sys);
    /* a bake without SKYT cannot */
    assert_int_equal(glow_system_create(fx->ctx, &(glow_system_desc){.bake = fx->nosky}, &sys), GLOW_OK);
    L[4] = 0;
    assert_int_equal(glow_system_set_sky(sys, L), GLOW_ERROR_UNSUPPORTED);
    glow_system_destroy(sys);
    free(sh);
}

/* ----------------------------------------------------------------------- validation */

static unsigned char *read_all(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)n);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return buf;
}

static uint8_t *find_section(uint8_t *img, uint32_t fourcc, uint64_t *size) {
    const uint32_t n = fuzz_rd32(img + 12);
    for (uint32_t i = 0; i < n; ++i) {
        uint8_t *e = img + 64 + 32 * i;
        if (fuzz_rd32(e) == fourcc) {
            *size = fuzz_rd64(e + 16);
            return img + fuzz_rd64(e + 8);
        }
    }
    return NULL;
}

static void expect_load(fixture *fx, uint8_t *img, size_t size, glow_result want) {
    fuzz_fix_crcs(img, size);
    glow_bake *b = NULL;
    assert_int_equal(glow_bake_load(fx->ctx, img, size, &b), want);
    if (b) glow_bake_destroy(b);
}

static void test_corrupt_section(void **state) {
    fixture *fx = *state;
    size_t size;
    uint8_t *img = read_all(fx->open_bake, &size), *work = malloc(size);
    uint64_t ssz = 0;
    assert_non_null(find_section(img, GLOW_SECTION_SKYT, &ssz));
    glow_bake_info info;
    assert_int_equal(glow_bake_get_info(fx->open, &info), GLOW_OK);
    assert_int_equal(ssz, sizeof(glow_bake_sky) + 36ull * (info.surfel_count + info.grid_cache_count));
    assert_int_equal(info.format_minor, GLOW_BAKE_FORMAT_VERSION_MINOR); /* SKYT since 1.6 */
    /* resealed unchanged: loads */
    memcpy(work, img, size);
    expect_load(fx, work, size, GLOW_OK);
    /* a NaN, an Inf and a huge value in a surfel's T; one in a grid cache's V */
    const float bad[3] = {NAN, INFINITY, 1e6f};
    for (int k = 0; k < 3; ++k) {
        memcpy(work, img, size);
        uint8_t *p = find_section(work, GLOW_SECTION_SKYT, &ssz);
        memcpy(p + sizeof(glow_bake_sky) + 4 * 9 * 7 + 4 * 2, &bad[k], 4);
        expect_load(fx, work, size, GLOW_ERROR_CORRUPT_DATA);
    }
    memcpy(work, img, size);
    uint8_t *p = find_section(work, GLOW_SECTION_SKYT, &ssz);
    memcpy(p + ssz - 4, &bad[0], 4);
    expect_load(fx, work, size, GLOW_ERROR_CORRUPT_DATA);
    /* counts that do not fit the bake */
    const size_t fields[5] = {offsetof(glow_bake_sky, coeffs), offsetof(glow_bake_sky, surfel_count),
                              offsetof(glow_bake_sky, grid_count), offsetof(glow_bake_sky, rays),
                              offsetof(glow_bake_sky, grid_rays)};
    for (int f = 0; f < 5; ++f) {
        memcpy(work, img, size);
        p = find_section(work, GLOW_SECTION_SKYT, &ssz);
        uint32_t x = fuzz_rd32(p + fields[f]);
        fuzz_wr32(p + fields[f], f >= 3 ? 0u : x + 1u);
        expect_load(fx, work, size, GLOW_ERROR_CORRUPT_DATA);
    }
    /* a payload shorter than its counts: the section's size shrunk by one float */
    memcpy(work, img, size);
    const uint32_t n = fuzz_rd32(work + 12);
    for (uint32_t i = 0; i < n; ++i) {
        uint8_t *e = work + 64 + 32 * i;
        if (fuzz_rd32(e) == GLOW_SECTION_SKYT) {
            const uint64_t sz = fuzz_rd64(e + 16) - 4;
            memcpy(e + 16, &sz, 8);
        }
    }
    expect_load(fx, work, size, GLOW_ERROR_CORRUPT_DATA);
    free(work);
    free(img);
}

/* A bake without SKYT (--no-sky, or one before 1.6: the golden 1.0 file) loads, and its host traces T. */
static void test_old_bakes(void **state) {
    fixture *fx = *state;
    glow_bake *b = NULL;
    assert_int_equal(glow_bake_load_file(fx->ctx, GLOW_TEST_DATA_DIR "/golden_v1.glow", &b), GLOW_OK);
    glow_bake_sky_transfer st;
    assert_int_equal(glow_bake_get_sky_transfer(b, &st), GLOW_OK);
    assert_null(st.surfel_transfer);
    glow_bake_destroy(b);
    uint64_t ssz;
    size_t size;
    uint8_t *img = read_all(fx->open_nosky, &size);
    assert_null(find_section(img, GLOW_SECTION_SKYT, &ssz));
    free(img);
    assert_int_equal(glow_bake_get_sky_transfer(NULL, &st), GLOW_ERROR_INVALID_ARGUMENT);
    /* bad SH input */
    glow_host *h = host(fx->nosky, NULL);
    float L[GLOW_SKY_SH_FLOATS] = {0};
    L[5] = NAN;
    assert_int_equal(glow_host_set_environment_sh(h, L), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_host_set_environment_sh(NULL, L), GLOW_ERROR_INVALID_ARGUMENT);
    glow_host_destroy(h);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gaunt_and_product),   cmocka_unit_test(test_rotation),
        cmocka_unit_test(test_open_plane),          cmocka_unit_test(test_constant_sky_matches_S),
        cmocka_unit_test(test_roundtrip_and_threads), cmocka_unit_test(test_rotated_sky),
        cmocka_unit_test(test_system_sky),
        cmocka_unit_test(test_corrupt_section),     cmocka_unit_test(test_old_bakes),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
