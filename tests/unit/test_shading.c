/* test_shading.c — the runtime's shading maths (runtime/src/sh.c, glow.h "shading") and the
 * cache-lighting kernel (cache_lighting.c), each against an independent computation:
 *   - YCoCg: PIC Eq. 7 values and round trip;
 *   - glow_sh_eval: orthonormality by exact quadrature (Gauss-Legendre in z x uniform φ) for every
 *     band count 1..8, closed forms for l <= 3, the addition theorem;
 *   - glow_sh_cone_factor: 2π ∫_x^1 P_l(t) dt by quadrature (Funk-Hecke: the projection of a cone's
 *     indicator onto y_lm is k_l(x) y_lm(axis)), and a cone projected by quadrature in its own
 *     frame onto the basis;
 *   - SH projection and reconstruction of max(0, ω·a)^n against Funk-Hecke;
 *   - glow_sh_lobe_factor: the diffuse values 1, 2/3, 1/4, 0, -1/24 and (n+1) ∫_0^1 t^n P_l(t) dt;
 *   - glow_shade_sh: uniform (coloured) fields, linear fields, a distant cone of radiance against
 *     the exact irradiance (π L sin²α cos θ) and its band-limited value;
 *   - glow_sample_grid / glow_sample_lightmap on hand-made outputs;
 *   - the AVX2 and the portable kernel against each other and against a double-precision
 *     re-summation of a real bake's links. */
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

#include "bake/bake_format.h"
#include "cache_lighting.h"
#include "glow/glow.h"
#include "glow/glow_precompute.h"
#include "runtime_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define NB GLOW_MAX_SH_BANDS
#define NC (NB * NB)

/* ------------------------------------------------------------------------------ helpers */
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double rnd(void) { /* [0, 1) */
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}
static void rnd_dir(float d[3]) {
    double z = 2.0 * rnd() - 1.0, phi = 2.0 * M_PI * rnd(), r = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = (float)(r * cos(phi));
    d[1] = (float)(r * sin(phi));
    d[2] = (float)z;
}

static double legendre(int l, double x) {
    if (l == 0) return 1.0;
    double p0 = 1.0, p1 = x;
    for (int k = 2; k <= l; ++k) {
        double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    return p1;
}

/* Gauss-Legendre nodes/weights on [-1, 1] (Newton on P_n). */
static void gauss_legendre(int n, double *x, double *w) {
    for (int i = 0; i < n; ++i) {
        double t = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (t * p1 - p0) / (t * t - 1.0);
            double dt = p1 / dp;
            t -= dt;
            if (fabs(dt) < 1e-15) break;
        }
        x[i] = t;
        w[i] = 2.0 / ((1.0 - t * t) * dp * dp);
    }
}

/* ∫_a^b f(t) dt with an n-node Gauss-Legendre rule (n <= 128). */
static double gl_integrate(double (*f)(double, const double *), const double *par, double a, double b, int n) {
    double x[128], w[128], s = 0.0;
    gauss_legendre(n, x, w);
    for (int i = 0; i < n; ++i) s += w[i] * f(a + (b - a) * 0.5 * (x[i] + 1.0), par);
    return s * (b - a) * 0.5;
}
static double f_pl(double t, const double *par) { return legendre((int)par[0], t); }
static double f_tn_pl(double t, const double *par) { return pow(t, par[1]) * legendre((int)par[0], t); }

/* an orthonormal frame (u, v) around unit a */
static void frame(const double a[3], double u[3], double v[3]) {
    double h[3] = {fabs(a[0]) < 0.9 ? 1.0 : 0.0, fabs(a[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    u[0] = h[1] * a[2] - h[2] * a[1];
    u[1] = h[2] * a[0] - h[0] * a[2];
    u[2] = h[0] * a[1] - h[1] * a[0];
    double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; ++k) u[k] /= l;
    v[0] = a[1] * u[2] - a[2] * u[1];
    v[1] = a[2] * u[0] - a[0] * u[2];
    v[2] = a[0] * u[1] - a[1] * u[0];
}

/* c[k] = ∫_{ω·a >= x} g(ω·a) y_k(ω) dω for k < bands², by quadrature in a's frame: Gauss-Legendre
 * in t = ω·a on [x, 1] (nt nodes), uniform in φ (np nodes; exact for trigonometric degree < np). */
static void project_zonal(double (*g)(double, const double *), const double *par, const double a[3], double x,
                          uint32_t bands, int nt, int np, double *c) {
    double u[3], v[3], tx[128], tw[128];
    frame(a, u, v);
    gauss_legendre(nt, tx, tw);
    memset(c, 0, bands * bands * sizeof *c);
    float y[NC];
    for (int i = 0; i < nt; ++i) {
        double t = x + (1.0 - x) * 0.5 * (tx[i] + 1.0), st = sqrt(fmax(0.0, 1.0 - t * t));
        double w = tw[i] * (1.0 - x) * 0.5 * (2.0 * M_PI / np) * g(t, par);
        for (int j = 0; j < np; ++j) {
            double phi = (j + 0.5) * 2.0 * M_PI / np, cp = cos(phi), sp = sin(phi);
            float d[3];
            for (int k = 0; k < 3; ++k) d[k] = (float)(t * a[k] + st * (cp * u[k] + sp * v[k]));
            glow_sh_eval(bands, d, y);
            for (uint32_t k = 0; k < bands * bands; ++k) c[k] += w * y[k];
        }
    }
}
static double g_one(double t, const double *par) {
    (void)t;
    (void)par;
    return 1.0;
}
static double g_pow(double t, const double *par) { return pow(t, par[0]); }

/* ------------------------------------------------------------------------------ YCoCg */
static void test_ycocg(void **state) {
    (void)state;
    /* PIC Eq. 7 on the primaries and white */
    const float prim[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    const float expect[4][3] = {{0.25f, 0.5f, -0.25f}, {0.5f, 0.0f, 0.5f}, {0.25f, -0.5f, -0.25f}, {1.0f, 0.0f, 0.0f}};
    for (int i = 0; i < 4; ++i) {
        float ycc[3], rgb[3];
        glow_rgb_to_ycocg(prim[i], ycc);
        for (int k = 0; k < 3; ++k) assert_true(fabsf(ycc[k] - expect[i][k]) < 1e-7f);
        glow_ycocg_to_rgb(ycc, rgb);
        for (int k = 0; k < 3; ++k) assert_true(fabsf(rgb[k] - prim[i][k]) < 1e-7f);
    }
    /* random colours, also negative (SH values ring below zero) and large */
    for (int i = 0; i < 10000; ++i) {
        double scale = i < 5000 ? 1.0 : 1000.0;
        float rgb[3] = {(float)((rnd() * 1.2 - 0.1) * scale), (float)((rnd() * 1.2 - 0.1) * scale),
                        (float)((rnd() * 1.2 - 0.1) * scale)};
        float ycc[3], back[3];
        glow_rgb_to_ycocg(rgb, ycc);
        /* against Eq. 7 in double */
        double y = 0.25 * rgb[0] + 0.5 * rgb[1] + 0.25 * rgb[2], co = 0.5 * rgb[0] - 0.5 * rgb[2],
               cg = -0.25 * rgb[0] + 0.5 * rgb[1] - 0.25 * rgb[2];
        assert_true(fabs(ycc[0] - y) <= 1e-6 * scale && fabs(ycc[1] - co) <= 1e-6 * scale && fabs(ycc[2] - cg) <= 1e-6 * scale);
        glow_ycocg_to_rgb(ycc, back);
        for (int k = 0; k < 3; ++k)
            if (fabsf(back[k] - rgb[k]) > 1e-6f * (float)scale)
                fail_msg("round trip (%g %g %g) -> (%g %g %g)", rgb[0], rgb[1], rgb[2], back[0], back[1], back[2]);
    }
}

/* ------------------------------------------------------------------------------ SH basis */
/* Gram matrix by quadrature that is exact for the products (degree <= 14 in z, trigonometric
 * degree <= 14 in φ): 16 Gauss-Legendre nodes in z, 32 uniform in φ. What remains is float
 * rounding of the basis evaluation: tolerance 2e-6. */
static void test_sh_orthonormal(void **state) {
    (void)state;
    enum { NZ = 16, NPHI = 32 };
    double zx[NZ], zw[NZ];
    gauss_legendre(NZ, zx, zw);
    static double gram[NC][NC];
    for (uint32_t bands = 1; bands <= NB; ++bands) {
        const uint32_t n = bands * bands;
        memset(gram, 0, sizeof gram);
        float y[NC], y8[NC];
        for (int i = 0; i < NZ; ++i) {
            double z = zx[i], r = sqrt(1.0 - z * z);
            for (int j = 0; j < NPHI; ++j) {
                double phi = (j + 0.5) * 2.0 * M_PI / NPHI;
                float d[3] = {(float)(r * cos(phi)), (float)(r * sin(phi)), (float)z};
                for (uint32_t k = 0; k < NC; ++k) y[k] = 1e30f; /* nothing beyond bands² may be written */
                glow_sh_eval(bands, d, y);
                for (uint32_t k = n; k < NC; ++k) assert_true(y[k] == 1e30f);
                /* fewer bands = a prefix of more bands */
                glow_sh_eval(NB, d, y8);
                for (uint32_t k = 0; k < n; ++k) assert_true(y[k] == y8[k]);
                double w = zw[i] * 2.0 * M_PI / NPHI;
                for (uint32_t a = 0; a < n; ++a)
                    for (uint32_t b = a; b < n; ++b) gram[a][b] += w * y[a] * y[b];
            }
        }
        double worst = 0.0;
        for (uint32_t a = 0; a < n; ++a)
            for (uint32_t b = a; b < n; ++b) {
                double e = fabs(gram[a][b] - (a == b ? 1.0 : 0.0));
                if (e > worst) worst = e;
                if (e > 2e-6) fail_msg("bands %u: <y%u, y%u> = %.9f", bands, a, b, gram[a][b]);
            }
        if (bands == NB) print_message("Gram matrix, 8 bands: max |G - I| = %.2e\n", worst);
    }
}

static void test_sh_closed_forms(void **state) {
    (void)state;
    for (int i = 0; i < 200; ++i) {
        float d[3], y[NC];
        rnd_dir(d);
        glow_sh_eval(NB, d, y);
        const double x = d[0], yy = d[1], z = d[2];
        const double c1 = sqrt(3.0 / (4.0 * M_PI));
        const double expect[16] = {
            0.5 / sqrt(M_PI), /* 0.282095 */
            c1 * yy, c1 * z, c1 * x,
            /* l = 2: 1/2 sqrt(15/π) xy, yz; 1/4 sqrt(5/π) (3z² - 1); 1/2 sqrt(15/π) xz; 1/4 sqrt(15/π) (x² - y²) */
            0.5 * sqrt(15.0 / M_PI) * x * yy, 0.5 * sqrt(15.0 / M_PI) * yy * z, 0.25 * sqrt(5.0 / M_PI) * (3.0 * z * z - 1.0),
            0.5 * sqrt(15.0 / M_PI) * x * z, 0.25 * sqrt(15.0 / M_PI) * (x * x - yy * yy),
            /* l = 3 (no Condon-Shortley phase): 1/4 sqrt(35/2π) y(3x² - y²); 1/2 sqrt(105/π) xyz;
             * 1/4 sqrt(21/2π) y(5z² - 1); 1/4 sqrt(7/π) z(5z² - 3); 1/4 sqrt(21/2π) x(5z² - 1);
             * 1/4 sqrt(105/π) z(x² - y²); 1/4 sqrt(35/2π) x(x² - 3y²) */
            0.25 * sqrt(35.0 / (2.0 * M_PI)) * yy * (3.0 * x * x - yy * yy), 0.5 * sqrt(105.0 / M_PI) * x * yy * z,
            0.25 * sqrt(21.0 / (2.0 * M_PI)) * yy * (5.0 * z * z - 1.0), 0.25 * sqrt(7.0 / M_PI) * z * (5.0 * z * z - 3.0),
            0.25 * sqrt(21.0 / (2.0 * M_PI)) * x * (5.0 * z * z - 1.0), 0.25 * sqrt(105.0 / M_PI) * z * (x * x - yy * yy),
            0.25 * sqrt(35.0 / (2.0 * M_PI)) * x * (x * x - 3.0 * yy * yy)};
        for (int k = 0; k < 16; ++k)
            if (fabs(y[k] - expect[k]) > 2e-6) fail_msg("y_%d(%g, %g, %g) = %.8f, expected %.8f", k, x, yy, z, y[k], expect[k]);
    }
    /* the spot values the brief names */
    const float up[3] = {0, 0, 1};
    float y[NC];
    glow_sh_eval(3, up, y);
    assert_true(fabs(y[0] - 0.282095) < 1e-6);
    assert_true(fabs(y[2] - 0.488603) < 1e-6);
    assert_true(fabs(y[6] - 0.630783) < 1e-6); /* y_2^0(z) = 1/4 sqrt(5/π) * 2 */
    /* addition theorem, independent of the basis' sign and ordering conventions:
     * Σ_m y_lm(a) y_lm(b) = (2l+1)/(4π) P_l(a·b) */
    for (int i = 0; i < 500; ++i) {
        float a[3], b[3], ya[NC], yb[NC];
        rnd_dir(a);
        rnd_dir(b);
        glow_sh_eval(NB, a, ya);
        glow_sh_eval(NB, b, yb);
        double ab = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
        for (int l = 0; l < (int)NB; ++l) {
            double s = 0.0;
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) s += (double)ya[k] * yb[k];
            double e = (2.0 * l + 1.0) / (4.0 * M_PI) * legendre(l, ab);
            if (fabs(s - e) > 5e-6) fail_msg("addition theorem l = %d: %.8f vs %.8f", l, s, e);
        }
    }
}

/* The cache-lighting kernel's scaled basis (sh_kernel.h): factor(k) ỹ_k must be y_k for every
 * band up to 8, and the factors must not be trivial (ỹ_k = y_k would pass the first check). */
static void test_sh_scaled_basis(void **state) {
    (void)state;
    double worst = 0.0;
    for (int i = 0; i < 500; ++i) {
        float d[3], y[64];
        rnd_dir(d);
        glow_sh_eval(8, d, y);
        glow__v8f x = {d[0]}, yy = {d[1]}, z = {d[2]}, ys[64];
        glow__sh_eval_scaled_v8_unrolled(8, &x, &yy, &z, ys);
        for (uint32_t k = 0; k < 64; ++k) {
            const double v = glow__sh_scaled_factor(k) * ys[k][0];
            worst = fmax(worst, fabs(v - y[k]));
            if (fabs(v - y[k]) > 2e-6) fail_msg("scaled y_%u(%g, %g, %g) = %.8f, expected %.8f", k, d[0], d[1], d[2], v, y[k]);
        }
        glow__sh_eval_scaled_v8(5, &x, &yy, &z, ys); /* run-time band count: same values */
        for (uint32_t k = 0; k < 25; ++k) assert_true(fabs(glow__sh_scaled_factor(k) * ys[k][0] - y[k]) <= 2e-6);
    }
    print_message("scaled basis: worst |factor ỹ - y| %.2e over 500 directions, l < 8\n", worst);
    assert_true(fabs(glow__sh_scaled_factor(6) - 0.25 * sqrt(5.0 / M_PI) * 3.0) < 1e-6); /* y_20 = K (3z²-1)/2 = 3K (z² - 1/3)/2 */
    assert_true(fabs(glow__sh_scaled_factor(3) - sqrt(3.0 / (4.0 * M_PI))) < 1e-6);      /* ỹ_11 = x */
}

/* ------------------------------------------------------------------------------ cone factors */
/* By Funk-Hecke, ∫_{ω·a >= x} y_lm(ω) dω = λ_l y_lm(a) with λ_l = 2π ∫_x^1 P_l(t) dt, which is
 * what glow_sh_cone_factor(l, x) must return (DESIGN §3: k_0 = 2π(1-x), k_l = 2π/(2l+1)
 * (P_{l-1}(x) - P_{l+1}(x)), from (2l+1) P_l = P'_{l+1} - P'_{l-1}). */
static void test_cone_factor(void **state) {
    (void)state;
    const double xs[] = {1.0, 0.99999, 0.9999, 0.999, 0.99, 0.95, 0.9, 0.7, 0.5, 0.2, 0.0, -0.3, -0.7, -0.99, -1.0};
    for (int l = 0; l <= 9; ++l)
        for (size_t i = 0; i < sizeof xs / sizeof xs[0]; ++i) {
            const float xf = (float)xs[i]; /* the quadrature runs at the float the function receives */
            double par[2] = {l, 0};
            double q = 2.0 * M_PI * gl_integrate(f_pl, par, xf, 1.0, 24); /* exact for degree <= 47 */
            double k = glow_sh_cone_factor((uint32_t)l, xf);
            if (fabs(k - q) > 1e-6 * fabs(q) + 1e-12) fail_msg("k_%d(%.9g) = %.9g, quadrature %.9g", l, (double)xf, k, q);
        }
    assert_true(fabsf(glow_sh_cone_factor(0, -1.0f) - (float)(4.0 * M_PI)) < 1e-5f);
    assert_true(fabsf(glow_sh_cone_factor(1, 0.0f) - (float)M_PI) < 1e-6f); /* hemisphere: 2π ∫_0^1 t dt */
    for (uint32_t l = 1; l <= 8; ++l) assert_true(fabsf(glow_sh_cone_factor(l, -1.0f)) < 1e-6f);
    for (uint32_t l = 0; l <= 8; ++l) assert_true(glow_sh_cone_factor(l, 1.0f) == 0.0f);
    /* a tiny cone: k_l -> ω for every l (a delta of weight ω) */
    const double omc = 1e-4, w = 2.0 * M_PI * omc;
    for (uint32_t l = 0; l < 8; ++l) assert_true(fabs(glow_sh_cone_factor(l, (float)(1.0 - omc)) - w) < 0.01 * w);
    (void)w;

    /* the full projection: a cone of arbitrary axis projected onto the basis by quadrature in the
     * cone's own frame (exact: polynomial in t after the φ sum) equals k_l(x) y_lm(axis) */
    for (int i = 0; i < 20; ++i) {
        float af[3], ya[NC];
        rnd_dir(af);
        const double a[3] = {af[0], af[1], af[2]};
        const double x = 2.0 * rnd() - 1.0;
        double c[NC];
        project_zonal(g_one, NULL, a, x, NB, 12, 24, c);
        glow_sh_eval(NB, af, ya);
        for (int l = 0; l < (int)NB; ++l)
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
                double e = glow_sh_cone_factor((uint32_t)l, (float)x) * ya[k];
                if (fabs(c[k] - e) > 1e-5) fail_msg("cone x = %g: c_%d = %.8f vs k_l y = %.8f", x, k, c[k], e);
            }
    }
}

/* Project f(ω) = max(0, ω·a)^n by quadrature (over the hemisphere where f > 0, in a's frame, so
 * the kink lies on the integration boundary), evaluate Σ c_k y_k(b), and compare with Funk-Hecke:
 * Σ_l (2l+1)/(4π) λ_l P_l(a·b), λ_l = 2π ∫_0^1 t^n P_l(t) dt. */
static void test_sh_projection(void **state) {
    (void)state;
    const double ns[] = {1.0, 4.0, 2.5};
    for (size_t ni = 0; ni < 3; ++ni) {
        float af[3];
        rnd_dir(af);
        const double a[3] = {af[0], af[1], af[2]};
        double par[1] = {ns[ni]};
        double c[NC];
        project_zonal(g_pow, par, a, 0.0, NB, 64, 24, c);
        double lambda[NB];
        for (int l = 0; l < (int)NB; ++l) {
            double p2[2] = {l, ns[ni]};
            lambda[l] = 2.0 * M_PI * gl_integrate(f_tn_pl, p2, 0.0, 1.0, 64);
        }
        for (int i = 0; i < 50; ++i) {
            float b[3], yb[NC];
            rnd_dir(b);
            glow_sh_eval(NB, b, yb);
            double ab = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
            for (uint32_t bands = 1; bands <= NB; ++bands) {
                double rec = 0.0, fh = 0.0;
                for (uint32_t k = 0; k < bands * bands; ++k) rec += c[k] * yb[k];
                for (uint32_t l = 0; l < bands; ++l) fh += (2.0 * l + 1.0) / (4.0 * M_PI) * lambda[l] * legendre((int)l, ab);
                if (fabs(rec - fh) > 1e-5) fail_msg("n = %g, %u bands: reconstruction %.8f vs Funk-Hecke %.8f", ns[ni], bands, rec, fh);
            }
        }
        /* and the 8-band reconstruction approximates f itself where f is smooth (n = 4: away from
         * the horizon the truncation error is small) */
        if (ns[ni] == 4.0) {
            float yb[NC];
            glow_sh_eval(NB, af, yb);
            double rec = 0.0;
            for (uint32_t k = 0; k < NC; ++k) rec += c[k] * yb[k];
            assert_true(fabs(rec - 1.0) < 0.05); /* f(a) = 1 */
        }
    }
}

/* ------------------------------------------------------------------------------ lobe factors */
static void test_lobe_factor(void **state) {
    (void)state;
    const float diffuse[5] = {1.0f, 2.0f / 3.0f, 0.25f, 0.0f, -1.0f / 24.0f};
    for (uint32_t l = 0; l < 5; ++l) assert_true(fabsf(glow_sh_lobe_factor(l, 1.0f) - diffuse[l]) < 1e-7f);
    /* s_l = ∫_hemisphere (n+1)/(2π) cos^n θ P_l(cos θ) dω = (n+1) ∫_0^1 t^n P_l(t) dt */
    const double ns[] = {0.0, 1.0, 2.0, 2.5, 5.0, 10.0, 20.0, 50.5, 100.0, 400.0};
    for (size_t i = 0; i < sizeof ns / sizeof ns[0]; ++i)
        for (uint32_t l = 0; l < 16; ++l) {
            double par[2] = {l, ns[i]};
            /* composite: t^n is steep near 1 for large n, and t^2.5 has a weak singularity at 0 */
            double q = 0.0;
            for (int p = 0; p < 16; ++p) q += gl_integrate(f_tn_pl, par, p / 16.0, (p + 1) / 16.0, 48);
            q *= ns[i] + 1.0;
            double s = glow_sh_lobe_factor(l, (float)ns[i]);
            if (fabs(s - q) > 1e-6 * (1.0 + fabs(q))) fail_msg("s_%u(n = %g) = %.9g, quadrature %.9g", l, ns[i], s, q);
        }
}

/* ------------------------------------------------------------------------------ shading */
/* coefficients for (luma, chroma) bands: Y luma², Co chroma², Cg chroma² */
static void put_uniform(float *coeffs, uint32_t luma, uint32_t chroma, const float rgb[3]) {
    /* L(ω) = rgb: the DC coefficient is L / y_00 = L sqrt(4π); Eq. 7 written out */
    const double s = sqrt(4.0 * M_PI);
    const uint32_t n = luma * luma + 2 * chroma * chroma;
    memset(coeffs, 0, n * sizeof *coeffs);
    coeffs[0] = (float)(s * (0.25 * rgb[0] + 0.5 * rgb[1] + 0.25 * rgb[2]));
    coeffs[luma * luma] = (float)(s * (0.5 * rgb[0] - 0.5 * rgb[2]));
    coeffs[luma * luma + chroma * chroma] = (float)(s * (-0.25 * rgb[0] + 0.5 * rgb[1] - 0.25 * rgb[2]));
}

/* Lanczos sigma factors, and what they are for: a narrow cone (a small bright source) projected into
 * L bands rings, its reconstruction dips below zero away from the cone; windowed, the dip shrinks
 * while the DC term (the mean, so the energy) is untouched. */
static void test_sh_window(void **state) {
    (void)state;
    assert_true(glow_sh_window_factor(0, 3) == 1.0f);
    assert_true(fabsf(glow_sh_window_factor(1, 2) - (float)(2.0 / M_PI)) < 1e-6f); /* sin(pi/2)/(pi/2) */
    assert_true(fabsf(glow_sh_window_factor(1, 3) - (float)(sin(M_PI / 3.0) / (M_PI / 3.0))) < 1e-6f);
    assert_true(glow_sh_window_factor(3, 3) == 0.0f && glow_sh_window_factor(9, 3) == 0.0f);
    for (uint32_t L = 2; L <= GLOW_MAX_SH_BANDS; ++L)
        for (uint32_t l = 1; l < L; ++l) {
            float w = glow_sh_window_factor(l, L);
            assert_true(w > 0.0f && w < glow_sh_window_factor(l - 1, L));
        }
    for (uint32_t L = 3; L <= GLOW_MAX_SH_BANDS; ++L) {
        /* a cone of half-angle 10 degrees around +z, unit radiance: c_l0 = k_l(cos a) y_l0(z) */
        float up[3] = {0, 0, 1}, y[GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS];
        glow_sh_eval(L, up, y);
        float c[GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS] = {0}, cw[GLOW_MAX_SH_BANDS * GLOW_MAX_SH_BANDS] = {0};
        for (uint32_t l = 0; l < L; ++l) {
            c[l * l + l] = glow_sh_cone_factor(l, cosf(10.0f * (float)M_PI / 180.0f)) * y[l * l + l];
            cw[l * l + l] = c[l * l + l] * glow_sh_window_factor(l, L);
        }
        float lo = 0.0f, lo_w = 0.0f;
        for (int k = 0; k <= 180; ++k) { /* along a meridian */
            float th = (float)k * (float)M_PI / 180.0f, d[3] = {sinf(th), 0.0f, cosf(th)};
            glow_sh_eval(L, d, y);
            float v = 0.0f, vw = 0.0f;
            for (uint32_t q = 0; q < L * L; ++q) {
                v += c[q] * y[q];
                vw += cw[q] * y[q];
            }
            lo = fminf(lo, v);
            lo_w = fminf(lo_w, vw);
        }
        assert_true(lo < 0.0f);          /* it rings */
        assert_true(lo_w > 0.5f * lo);   /* windowed: less than half the dip */
        assert_true(cw[0] == c[0]);      /* same mean */
    }
}

static void test_shade_uniform(void **state) {
    (void)state;
    const uint32_t combos[][2] = {{1, 1}, {2, 1}, {3, 1}, {3, 3}, {4, 2}, {8, 2}, {8, 8}};
    const float exps[] = {0.0f, 1.0f, 3.5f, 20.0f, 100.0f};
    float coeffs[3 * NC];
    for (size_t c = 0; c < sizeof combos / sizeof combos[0]; ++c)
        for (int i = 0; i < 20; ++i) {
            float rgb[3] = {(float)(rnd() * 5.0), (float)(rnd() * 5.0), (float)(rnd() * 5.0)}, axis[3], out[3];
            put_uniform(coeffs, combos[c][0], combos[c][1], rgb);
            rnd_dir(axis);
            for (size_t e = 0; e < sizeof exps / sizeof exps[0]; ++e) {
                glow_shade_sh(coeffs, combos[c][0], combos[c][1], axis, exps[e], out);
                for (int k = 0; k < 3; ++k)
                    if (fabsf(out[k] - rgb[k]) > 2e-6f * (1.0f + rgb[k]))
                        fail_msg("uniform field (%g %g %g), bands %u/%u, n = %g: got (%g %g %g)", rgb[0], rgb[1], rgb[2],
                                 combos[c][0], combos[c][1], exps[e], out[0], out[1], out[2]);
            }
        }
    /* NULL / bad band counts: zero, no crash */
    float out[3] = {1, 1, 1};
    const float up[3] = {0, 0, 1};
    glow_shade_sh(NULL, 3, 3, up, 1.0f, out);
    assert_true(out[0] == 0.0f && out[1] == 0.0f && out[2] == 0.0f);
    put_uniform(coeffs, 3, 3, (const float[3]){1, 1, 1});
    out[0] = 1.0f;
    glow_shade_sh(coeffs, 3, 4, up, 1.0f, out); /* chroma > luma */
    assert_true(out[0] == 0.0f);
}

/* L(ω) = a + b·ω per YCoCg channel; the normalised Phong lobe around `axis` averages it to
 * a + (b·axis) (n+1)/(n+2) (∫ (n+1)/(2π) t^n t dω = (n+1)/(n+2)). Luma 3 / chroma 2: both use band 1. */
static void test_shade_linear(void **state) {
    (void)state;
    const double c1 = sqrt(3.0 / (4.0 * M_PI)), s = sqrt(4.0 * M_PI);
    const uint32_t L = 3, C = 2;
    for (int i = 0; i < 50; ++i) {
        double a[3], b[3][3];
        float coeffs[3 * NC] = {0};
        float *plane[3] = {coeffs, coeffs + L * L, coeffs + L * L + C * C};
        for (int ch = 0; ch < 3; ++ch) {
            a[ch] = ch == 0 ? 1.0 + rnd() : rnd() - 0.5;
            for (int k = 0; k < 3; ++k) b[ch][k] = 0.5 * (rnd() - 0.5);
            plane[ch][0] = (float)(a[ch] * s);
            plane[ch][1] = (float)(b[ch][1] / c1); /* y_1^{-1} = c1 y */
            plane[ch][2] = (float)(b[ch][2] / c1); /* y_1^0 = c1 z */
            plane[ch][3] = (float)(b[ch][0] / c1); /* y_1^1 = c1 x */
        }
        /* band 2 of luma: a zonal l = 2 term that the lobe weighs by s_2 = (n+2-2)/(n+1+2) */
        coeffs[6] = 0.3f;
        float axis[3];
        rnd_dir(axis);
        const double n = 1.0 + 10.0 * rnd();
        float out[3];
        glow_shade_sh(coeffs, L, C, axis, (float)n, out);
        double ycc[3];
        for (int ch = 0; ch < 3; ++ch)
            ycc[ch] = a[ch] + (b[ch][0] * axis[0] + b[ch][1] * axis[1] + b[ch][2] * axis[2]) * (n + 1.0) / (n + 2.0);
        /* y_2^0 = 1/4 sqrt(5/π) (3z² - 1) */
        ycc[0] += 0.3 * n / (n + 3.0) * 0.25 * sqrt(5.0 / M_PI) * (3.0 * axis[2] * axis[2] - 1.0);
        const double rgb[3] = {ycc[0] + ycc[1] - ycc[2], ycc[0] + ycc[2], ycc[0] - ycc[1] - ycc[2]};
        for (int k = 0; k < 3; ++k)
            if (fabs(out[k] - rgb[k]) > 1e-5) fail_msg("linear field, n = %g: channel %d %.7f vs %.7f", n, k, out[k], rgb[k]);
    }
}

/* A distant cone of uniform radiance L (axis d at angle θ to the normal, half-angle α, fully above
 * the horizon) gives exactly E = π L sin²α cos θ. Its SH (projected here by quadrature) shaded with
 * the cosine lobe must give the band-limited value Σ_{l<B} s_l λ_l (2l+1)/(4π) P_l(cos θ) L tightly,
 * and E/π itself within the truncation error of B bands. */
static void test_shade_cone(void **state) {
    (void)state;
    const float normal[3] = {0.0f, 0.0f, 1.0f};
    const struct {
        double alpha_deg, theta_deg;
        uint32_t bands;
        double tol_exact; /* relative, vs π L sin²α cos θ: the truncation error of `bands` bands */
    } cases[] = {
        {30.0, 20.0, 8, 0.005}, {30.0, 20.0, 3, 0.03}, {45.0, 10.0, 8, 0.005}, {45.0, 10.0, 3, 0.02},
        {10.0, 40.0, 8, 0.01},  {60.0, 25.0, 8, 0.005}, {60.0, 25.0, 4, 0.01},
    };
    const double L = 2.0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        const double al = cases[i].alpha_deg * M_PI / 180.0, th = cases[i].theta_deg * M_PI / 180.0, x = cos(al);
        const double d[3] = {sin(th), 0.0, cos(th)};
        const uint32_t B = cases[i].bands;
        double c[NC];
        project_zonal(g_one, NULL, d, x, B, 12, 24, c);
        float coeffs[3 * NC] = {0};
        for (uint32_t k = 0; k < B * B; ++k) coeffs[k] = (float)(L * c[k]); /* grey: Co = Cg = 0 */
        float out[3];
        glow_shade_sh(coeffs, B, 1, normal, 1.0f, out);
        double band = 0.0;
        for (uint32_t l = 0; l < B; ++l) {
            double p1[2] = {l, 0}, p2[2] = {l, 1.0};
            double lambda = 2.0 * M_PI * gl_integrate(f_pl, p1, x, 1.0, 24);
            double sl = 2.0 * gl_integrate(f_tn_pl, p2, 0.0, 1.0, 24);
            band += sl * lambda * (2.0 * l + 1.0) / (4.0 * M_PI) * legendre((int)l, cos(th)) * L;
        }
        const double exact = L * sin(al) * sin(al) * cos(th); /* E / π */
        print_message("cone α = %g°, θ = %g°, %u bands: shade %.6f, band-limited %.6f, exact E/π %.6f (%+.2f %%)\n",
                      cases[i].alpha_deg, cases[i].theta_deg, B, out[1], band, exact, 100.0 * (out[1] / exact - 1.0));
        for (int k = 0; k < 3; ++k) assert_true(fabs(out[k] - band) < 1e-5 * (1.0 + band));
        assert_true(fabs(out[1] / exact - 1.0) < cases[i].tol_exact);
    }
    /* small cones (α = 2°) built with the cone factors, c_lm = L k_l(cos α) y_lm(d), shaded diffusely,
     * against L ω cos θ / π: 8 bands leave the clamped cosine's truncation, for a delta
     * Σ_{l<8} s_l (2l+1)/4 P_l(cos θ) / cos θ - 1 = +1.95 % (0°), -1.03 % (30°), +0.89 % (60°): within 2.5 %,
     * and within 0.05 % of that truncated value (computed here with quadrature s_l) */
    for (int ti = 0; ti < 3; ++ti) {
        const double th = (double)(ti * 30) * M_PI / 180.0, omc = 1.0 - cos(2.0 * M_PI / 180.0), w = 2.0 * M_PI * omc;
        const float d[3] = {(float)sin(th), 0.0f, (float)cos(th)};
        float coeffs[3 * NC] = {0}, yd[NC], out[3];
        glow_sh_eval(NB, d, yd);
        for (uint32_t l = 0; l < NB; ++l)
            for (uint32_t k = l * l; k < (l + 1) * (l + 1); ++k)
                coeffs[k] = (float)L * glow_sh_cone_factor(l, (float)(1.0 - omc)) * yd[k];
        glow_shade_sh(coeffs, NB, 1, normal, 1.0f, out);
        const double exact = L * w * cos(th) / M_PI;
        double trunc = 0.0;
        for (uint32_t l = 0; l < NB; ++l) {
            double p2[2] = {l, 1.0};
            trunc += 2.0 * gl_integrate(f_tn_pl, p2, 0.0, 1.0, 24) * (2.0 * l + 1.0) / 4.0 * legendre((int)l, cos(th));
        }
        trunc /= cos(th); /* the truncated response to a delta, relative to cos θ */
        print_message("small cone α = 2°, θ = %d°, 8 bands: %+.3f %% vs L ω cos θ / π (delta truncation %+.3f %%)\n", ti * 30,
                      100.0 * (out[1] / exact - 1.0), 100.0 * (trunc - 1.0));
        assert_true(fabs(out[1] / exact - 1.0) < 0.025);
        assert_true(fabs(out[1] / exact - trunc) < 5e-4);
    }
    /* a tiny cone at the zenith, 3 bands: the known L2 overshoot of the clamped cosine at its peak,
     * (1 + 3·2/3 + 5·1/4) / 4 = 1.0625 times L ω / π */
    const double omc = 1e-4, w = 2.0 * M_PI * omc;
    float coeffs[3 * NC] = {0}, yz[NC], out[3];
    glow_sh_eval(3, normal, yz);
    for (uint32_t l = 0; l < 3; ++l)
        for (uint32_t k = l * l; k < (l + 1) * (l + 1); ++k) coeffs[k] = glow_sh_cone_factor(l, (float)(1.0 - omc)) * yz[k];
    glow_shade_sh(coeffs, 3, 1, normal, 1.0f, out);
    assert_true(fabs(out[1] / (w / M_PI) - 1.0625) < 2e-3);
}

/* ------------------------------------------------------------------------------ sampling */
#define E GLOW_MAP_EMPTY
/* cache i's row: (i+1, 10(i+1), 100(i+1)) */
static float g_rows[16][3];
static void fill_rows(void) {
    for (int i = 0; i < 16; ++i)
        for (int k = 0; k < 3; ++k) g_rows[i][k] = (float)((i + 1) * pow(10.0, k));
}
/* expected: Σ w_i row_i / Σ w_i over non-empty */
static void expect_blend(const uint32_t *idx, const double *w, int n, float *out) {
    double acc[3] = {0, 0, 0}, ws = 0.0;
    for (int i = 0; i < n; ++i)
        if (idx[i] != E && w[i] > 0.0) {
            ws += w[i];
            for (int k = 0; k < 3; ++k) acc[k] += w[i] * g_rows[idx[i]][k];
        }
    for (int k = 0; k < 3; ++k) out[k] = (float)(acc[k] / ws);
}
static void assert_row(const float *got, const float *want) {
    for (int k = 0; k < 3; ++k)
        if (fabsf(got[k] - want[k]) > 1e-5f * (1.0f + fabsf(want[k])))
            fail_msg("sample (%g %g %g), expected (%g %g %g)", got[0], got[1], got[2], want[0], want[1], want[2]);
}

static void test_sample_grid(void **state) {
    (void)state;
    fill_rows();
    /* 3 x 2 x 2 grid, origin (1, 2, 3), spacing 0.5; cell (x, y, z) -> map[z][y][x] */
    const uint32_t map[2][2][3] = {{{0, 1, 2}, {3, E, 4}}, {{5, 6, 7}, {E, E, 8}}};
    glow_cache_outputs o = {.sh_bands_luma = 1, .sh_bands_chroma = 1, .coeff_count = 3, .cache_count = 9,
                            .grid_cache_count = 9, .cache_sh = &g_rows[0][0], .grid_dims = {3, 2, 2},
                            .grid_origin = {1.0f, 2.0f, 3.0f}, .grid_spacing = 0.5f, .grid_map = &map[0][0][0]};
    float out[3], want[3];
    /* cell centres: exactly the cell's row */
    for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 3; ++x) {
                float p[3] = {1.0f + 0.5f * x, 2.0f + 0.5f * y, 3.0f + 0.5f * z};
                glow_result r = glow_sample_grid(&o, p, out);
                if (map[z][y][x] == E) continue; /* neighbours at weight 0: see below */
                assert_int_equal(r, GLOW_OK);
                assert_row(out, g_rows[map[z][y][x]]);
            }
    /* a general interior point: trilinear weights of the 8 corners of cell block (0..1, 0..1, 0..1),
     * which holds one empty corner (1, 1, 0) and two more at z = 1 (0, 1, 1), (1, 1, 1) */
    {
        const double t[3] = {0.3, 0.6, 0.25};
        float p[3] = {(float)(1.0 + 0.5 * t[0]), (float)(2.0 + 0.5 * t[1]), (float)(3.0 + 0.5 * t[2])};
        uint32_t idx[8];
        double w[8];
        for (int cidx = 0; cidx < 8; ++cidx) {
            int x = cidx & 1, y = (cidx >> 1) & 1, z = (cidx >> 2) & 1;
            idx[cidx] = map[z][y][x];
            w[cidx] = (x ? t[0] : 1 - t[0]) * (y ? t[1] : 1 - t[1]) * (z ? t[2] : 1 - t[2]);
        }
        expect_blend(idx, w, 8, want);
        assert_int_equal(glow_sample_grid(&o, p, out), GLOW_OK);
        assert_row(out, want);
        /* hand-computed for one channel as a sanity check of the helper: weights of caches 0,1,3,5,6,7 */
        double w0 = 0.7 * 0.4 * 0.75, w1 = 0.3 * 0.4 * 0.75, w3 = 0.7 * 0.6 * 0.75, w5 = 0.7 * 0.4 * 0.25,
               w6 = 0.3 * 0.4 * 0.25;
        double ch0 = (w0 * 1 + w1 * 2 + w3 * 4 + w5 * 6 + w6 * 7) / (w0 + w1 + w3 + w5 + w6);
        assert_true(fabs(out[0] - ch0) < 1e-5);
        /* grid visibility (GVIS): the point is in octant (t >= 0.5 per axis) 0b010 of cell (0, 0, 0);
         * hiding corners 1 (x+1) and 5 (x+1, z+1) there leaves caches 0, 3, 5 blended; other octants
         * and other cells keep everything */
        uint8_t vis[12][8];
        memset(vis, 0xFF, sizeof vis);
        vis[0][2] = (uint8_t)~((1u << 1) | (1u << 5));
        glow_cache_outputs ov = o;
        ov.grid_visibility = &vis[0][0];
        assert_int_equal(glow_sample_grid(&ov, p, out), GLOW_OK);
        double ch0v = (w0 * 1 + w3 * 4 + w5 * 6) / (w0 + w3 + w5);
        assert_true(fabs(out[0] - ch0v) < 1e-5);
        vis[0][2] = 0xFF;
        vis[0][0] = 0x01; /* another octant: no effect at p */
        assert_int_equal(glow_sample_grid(&ov, p, out), GLOW_OK);
        assert_true(fabs(out[0] - ch0) < 1e-5);
    }
    /* block (1..2, 0..1, 0..1) */
    {
        const double t[3] = {0.8, 0.1, 0.9};
        float p[3] = {(float)(1.5 + 0.5 * t[0]), (float)(2.0 + 0.5 * t[1]), (float)(3.0 + 0.5 * t[2])};
        uint32_t idx[8];
        double w[8];
        for (int cidx = 0; cidx < 8; ++cidx) {
            int x = 1 + (cidx & 1), y = (cidx >> 1) & 1, z = (cidx >> 2) & 1;
            idx[cidx] = map[z][y][x];
            w[cidx] = ((cidx & 1) ? t[0] : 1 - t[0]) * (y ? t[1] : 1 - t[1]) * (z ? t[2] : 1 - t[2]);
        }
        expect_blend(idx, w, 8, want);
        assert_int_equal(glow_sample_grid(&o, p, out), GLOW_OK);
        assert_row(out, want);
    }
    /* outside: clamped to the grid (far below the corner (0,0,0) -> cache 0; beyond the +x, -y,
     * -z corner -> cache 2; beyond +x only, mid y/z -> bilinear on the x = 2 face) */
    float far_lo[3] = {-100.0f, -100.0f, -100.0f}, far_x[3] = {100.0f, 1.0f, -7.0f};
    assert_int_equal(glow_sample_grid(&o, far_lo, out), GLOW_OK);
    assert_row(out, g_rows[0]);
    assert_int_equal(glow_sample_grid(&o, far_x, out), GLOW_OK);
    assert_row(out, g_rows[2]);
    {
        float p[3] = {50.0f, 2.0f + 0.5f * 0.4f, 3.0f + 0.5f * 0.7f};
        uint32_t idx[4] = {map[0][0][2], map[0][1][2], map[1][0][2], map[1][1][2]};
        double w[4] = {0.6 * 0.3, 0.4 * 0.3, 0.6 * 0.7, 0.4 * 0.7};
        expect_blend(idx, w, 4, want);
        assert_int_equal(glow_sample_grid(&o, p, out), GLOW_OK);
        assert_row(out, want);
    }
    /* all neighbours empty: the (x=1, y=1) column's empties with t pointing only at them */
    {
        const uint32_t map2[2][2][2] = {{{E, E}, {E, 3}}, {{E, E}, {E, E}}};
        glow_cache_outputs o2 = o;
        o2.grid_dims[0] = o2.grid_dims[1] = o2.grid_dims[2] = 2;
        o2.grid_map = &map2[0][0][0];
        float p[3] = {1.1f, 2.1f, 3.2f}; /* weights on cache 3 at (1,1,0): 0.2*0.2*0.6 > 0 */
        assert_int_equal(glow_sample_grid(&o2, p, out), GLOW_OK);
        assert_row(out, g_rows[3]);
        const uint32_t map3[2][2][2] = {{{E, E}, {E, E}}, {{E, E}, {E, E}}};
        o2.grid_map = &map3[0][0][0];
        out[0] = out[1] = out[2] = 123.0f;
        assert_int_equal(glow_sample_grid(&o2, p, out), GLOW_ERROR_OUT_OF_RANGE);
        assert_true(out[0] == 0.0f && out[1] == 0.0f && out[2] == 0.0f); /* zeroed */
    }
    /* NULL and no grid */
    float p0[3] = {1, 2, 3};
    assert_int_equal(glow_sample_grid(NULL, p0, out), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_grid(&o, NULL, out), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_grid(&o, p0, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    glow_cache_outputs none = o;
    none.grid_map = NULL;
    none.grid_dims[0] = none.grid_dims[1] = none.grid_dims[2] = 0;
    assert_int_equal(glow_sample_grid(&none, p0, out), GLOW_ERROR_INVALID_ARGUMENT);
}

/* glow_sample_grid_oriented: the lookup moves GLOW_GRID_NORMAL_BIAS spacings along the normal, and
 * each corner's weight is also scaled by ((1 + cos θ)/2)² + GLOW_GRID_BACKFACE_FLOOR, θ between the
 * normal and the direction from the (unmoved) point to the corner. Hand-computed on a 2 x 1 x 1 grid. */
static void test_sample_grid_oriented(void **state) {
    (void)state;
    fill_rows();
    const uint32_t map[2] = {0, 1};
    glow_cache_outputs o = {.sh_bands_luma = 1, .sh_bands_chroma = 1, .coeff_count = 3, .cache_count = 2,
                            .grid_cache_count = 2, .cache_sh = &g_rows[0][0], .grid_dims = {2, 1, 1},
                            .grid_origin = {0.0f, 0.0f, 0.0f}, .grid_spacing = 2.0f, .grid_map = map};
    float out[3], want[3];
    /* a wall at x = 1 facing +x: the point moves to x = 1 + 0.25·2 = 1.5 (t = 0.75); corner 0 is
     * straight behind (cos −1: weight 0.2), corner 1 straight ahead (cos 1: 1.2) */
    const float p[3] = {1.0f, 0.0f, 0.0f}, nx[3] = {3.0f, 0.0f, 0.0f}; /* any length */
    {
        const uint32_t idx[2] = {0, 1};
        const double b = GLOW_GRID_NORMAL_BIAS * 2.0 / 2.0 + 0.5, f = GLOW_GRID_BACKFACE_FLOOR;
        const double w[2] = {(1.0 - b) * f, b * (1.0 + f)};
        expect_blend(idx, w, 2, want);
    }
    assert_int_equal(glow_sample_grid_oriented(&o, p, nx, out), GLOW_OK);
    assert_row(out, want);
    assert_true(fabs(out[0] - (0.25 * 0.2 * 1 + 0.75 * 1.2 * 2) / (0.25 * 0.2 + 0.75 * 1.2)) < 1e-5);
    /* facing −x: moves to x = 0.5 (t = 0.25), corner 0 ahead, corner 1 behind: the mirror image */
    const float mx[3] = {-1.0f, 0.0f, 0.0f};
    assert_int_equal(glow_sample_grid_oriented(&o, p, mx, out), GLOW_OK);
    assert_true(fabs(out[0] - (0.75 * 1.2 * 1 + 0.25 * 0.2 * 2) / (0.75 * 1.2 + 0.25 * 0.2)) < 1e-5);
    /* a normal across the grid's only axis: no move along x, both corners at cos 0 (weight 0.45):
     * glow_sample_grid's value */
    const float ny[3] = {0.0f, 1.0f, 0.0f};
    float plain[3];
    assert_int_equal(glow_sample_grid_oriented(&o, p, ny, out), GLOW_OK);
    assert_int_equal(glow_sample_grid(&o, p, plain), GLOW_OK);
    assert_row(out, plain);
    /* GVIS still applies, in the moved point's octant: cell 0's octant 1 (t >= 0.5 along x) hides
     * corner 1, so facing +x reads cache 0 alone */
    uint8_t vis[2][8];
    memset(vis, 0xFF, sizeof vis);
    vis[0][1] = 0x01;
    glow_cache_outputs ov = o;
    ov.grid_visibility = &vis[0][0];
    assert_int_equal(glow_sample_grid_oriented(&ov, p, nx, out), GLOW_OK);
    assert_row(out, g_rows[0]);
    /* bad normals */
    const float zero[3] = {0, 0, 0}, nan3[3] = {NAN, 0, 0}, inf3[3] = {INFINITY, 0, 0};
    assert_int_equal(glow_sample_grid_oriented(&o, p, NULL, out), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_grid_oriented(&o, p, zero, out), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_grid_oriented(&o, p, nan3, out), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_grid_oriented(&o, p, inf3, out), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_grid_oriented(NULL, p, nx, out), GLOW_ERROR_INVALID_ARGUMENT);
}

/* A refined grid (GFIN): a 2 x 2 x 2 coarse grid of spacing 2 whose one cell is a brick of 2³ fine
 * cells (spacing 1). Lookups inside the brick blend the fine cell's corners (coarse caches at the
 * brick's corners, fine ones elsewhere, empty ones weighted 0); a fine cell without any cache falls
 * back to the coarse cell; GVIS masks of the fine cells apply; the oriented lookup moves a quarter of
 * the fine spacing. Hand-computed. */
static void test_sample_grid_refined(void **state) {
    (void)state;
    fill_rows();
    const uint32_t map[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    uint32_t brick[27];
    for (int k = 0; k < 27; ++k) brick[k] = E;
    /* corners of the brick's lattice (x fastest, 3 a side): coarse points at 0 / 2 along each axis */
    for (int c = 0; c < 8; ++c) brick[(c & 1 ? 2 : 0) + (c & 2 ? 6 : 0) + (c & 4 ? 18 : 0)] = (uint32_t)c;
    brick[1] = 8;   /* (1, 0, 0) */
    brick[3] = 9;   /* (0, 1, 0) */
    brick[9] = 10;  /* (0, 0, 1) */
    brick[13] = 11; /* (1, 1, 1), the centre */
    const uint32_t of[8] = {0, E, E, E, E, E, E, E};
    glow_cache_outputs o = {.sh_bands_luma = 1, .sh_bands_chroma = 1, .coeff_count = 3, .cache_count = 12,
                            .grid_cache_count = 12, .cache_sh = &g_rows[0][0], .grid_dims = {2, 2, 2},
                            .grid_origin = {0.0f, 0.0f, 0.0f}, .grid_spacing = 2.0f, .grid_map = map,
                            .grid_refine = 2, .grid_brick_count = 1, .grid_brick_of_cell = of, .grid_bricks = brick};
    float out[3], want[3];
    /* fine cell (0, 0, 0) at t = (0.3, 0.6, 0.2): corners 0 (cache 0), 1 (8), 2 (9), 4 (10), 7 (11) */
    {
        const float p[3] = {0.3f, 0.6f, 0.2f};
        const double t[3] = {0.3, 0.6, 0.2};
        const uint32_t idx[8] = {0, 8, 9, E, 10, E, E, 11};
        double w[8];
        for (int c = 0; c < 8; ++c) w[c] = (c & 1 ? t[0] : 1 - t[0]) * (c & 2 ? t[1] : 1 - t[1]) * (c & 4 ? t[2] : 1 - t[2]);
        expect_blend(idx, w, 8, want);
        assert_int_equal(glow_sample_grid(&o, p, out), GLOW_OK);
        assert_row(out, want);
        /* GVIS of that fine cell's octant (t < 0.5, >= 0.5, < 0.5: octant 2): hide cache 9's corner 2 */
        uint8_t vis[8][8];
        memset(vis, 0xFF, sizeof vis);
        vis[0][2] = (uint8_t)~(1u << 2);
        glow_cache_outputs ov = o;
        ov.grid_brick_visibility = &vis[0][0];
        w[2] = 0.0;
        expect_blend(idx, w, 8, want);
        assert_int_equal(glow_sample_grid(&ov, p, out), GLOW_OK);
        assert_row(out, want);
    }
    /* fine cell (1, 1, 1) (x, y, z in [1, 2]): corners (1,1,1) = cache 11 and the coarse corner 7 hold
     * caches, the rest of its corners are empty */
    {
        const float p[3] = {1.5f, 1.25f, 1.75f};
        const double t[3] = {0.5, 0.25, 0.75};
        const uint32_t idx[8] = {11, E, E, E, E, E, E, 7};
        double w[8];
        for (int c = 0; c < 8; ++c) w[c] = (c & 1 ? t[0] : 1 - t[0]) * (c & 2 ? t[1] : 1 - t[1]) * (c & 4 ? t[2] : 1 - t[2]);
        expect_blend(idx, w, 8, want);
        assert_int_equal(glow_sample_grid(&o, p, out), GLOW_OK);
        assert_row(out, want);
    }
    /* a fine cell whose corners hold no cache: the coarse cell's trilinear lookup */
    {
        uint32_t b2[27];
        memcpy(b2, brick, sizeof b2);
        for (int k = 0; k < 27; ++k) b2[k] = E;
        b2[26] = 7; /* only the far corner: fine cell (0,0,0) is empty */
        glow_cache_outputs o2 = o;
        o2.grid_bricks = b2;
        glow_cache_outputs oc = o;
        oc.grid_refine = 0;
        const float p[3] = {0.3f, 0.6f, 0.2f};
        float coarse[3];
        assert_int_equal(glow_sample_grid(&oc, p, coarse), GLOW_OK);
        assert_int_equal(glow_sample_grid(&o2, p, out), GLOW_OK);
        assert_row(out, coarse);
        /* outside the grid's box: the clamped coarse lookup, as without bricks */
        const float far[3] = {-5.0f, 0.5f, 0.5f};
        assert_int_equal(glow_sample_grid(&oc, far, coarse), GLOW_OK);
        assert_int_equal(glow_sample_grid(&o, far, out), GLOW_OK);
        assert_row(out, coarse);
    }
    /* oriented: a wall at x = 0.5 facing +x moves the point to x = 0.75 (a quarter of the fine spacing),
     * and corners behind it (x = 0) weigh ((1 + cos)/2)² + 0.2 of the direction from the wall point */
    {
        const float p[3] = {0.5f, 0.5f, 0.5f}, nx[3] = {1.0f, 0.0f, 0.0f};
        const double t[3] = {0.75, 0.5, 0.5};
        const uint32_t idx[8] = {0, 8, 9, E, 10, E, E, 11};
        const double cx[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
        double w[8];
        for (int c = 0; c < 8; ++c) {
            w[c] = (c & 1 ? t[0] : 1 - t[0]) * (c & 2 ? t[1] : 1 - t[1]) * (c & 4 ? t[2] : 1 - t[2]);
            const double d[3] = {cx[c][0] - 0.5, cx[c][1] - 0.5, cx[c][2] - 0.5};
            const double h = 0.5 * (1.0 + d[0] / sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
            w[c] *= h * h + GLOW_GRID_BACKFACE_FLOOR;
        }
        expect_blend(idx, w, 8, want);
        assert_int_equal(glow_sample_grid_oriented(&o, p, nx, out), GLOW_OK);
        assert_row(out, want);
    }
}

static void test_sample_lightmap(void **state) {
    (void)state;
    fill_rows();
    /* 4 x 3 texels, row-major, v = 0 is row 0 */
    const uint32_t map[3][4] = {{0, 1, 2, 3}, {4, E, 5, 6}, {7, 8, E, E}};
    glow_cache_outputs o = {.sh_bands_luma = 1, .sh_bands_chroma = 1, .coeff_count = 3, .cache_count = 9,
                            .lightmap_cache_count = 9, .cache_sh = &g_rows[0][0], .lightmap_width = 4,
                            .lightmap_height = 3, .lightmap_map = &map[0][0]};
    float out[3], want[3];
    /* texel centres (i + 0.5) / W */
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) {
            if (map[y][x] == E) continue;
            assert_int_equal(glow_sample_lightmap(&o, (x + 0.5f) / 4.0f, (y + 0.5f) / 3.0f, out), GLOW_OK);
            assert_row(out, g_rows[map[y][x]]);
        }
    /* bilinear between texels (0,0) (1,0) (0,1) (1,1)=empty at fractions (0.25, 0.5) */
    {
        float u = (0.5f + 0.25f) / 4.0f, v = (0.5f + 0.5f) / 3.0f;
        uint32_t idx[4] = {map[0][0], map[0][1], map[1][0], map[1][1]};
        double w[4] = {0.75 * 0.5, 0.25 * 0.5, 0.75 * 0.5, 0.25 * 0.5};
        expect_blend(idx, w, 4, want);
        assert_int_equal(glow_sample_lightmap(&o, u, v, out), GLOW_OK);
        assert_row(out, want);
        /* by hand: (0.375*1 + 0.125*2 + 0.375*5) / 0.875 */
        assert_true(fabs(out[0] - (0.375 * 1 + 0.125 * 2 + 0.375 * 5) / 0.875) < 1e-5);
    }
    /* a full 4-texel footprint: texels (2,0) (3,0) (2,1) (3,1) at (0.6, 0.3) */
    {
        float u = (2.5f + 0.6f) / 4.0f, v = (0.5f + 0.3f) / 3.0f;
        uint32_t idx[4] = {map[0][2], map[0][3], map[1][2], map[1][3]};
        double w[4] = {0.4 * 0.7, 0.6 * 0.7, 0.4 * 0.3, 0.6 * 0.3};
        expect_blend(idx, w, 4, want);
        assert_int_equal(glow_sample_lightmap(&o, u, v, out), GLOW_OK);
        assert_row(out, want);
    }
    /* clamped at the edges: u = 0 and v = 0 are inside texel (0,0)'s half -> exactly cache 0;
     * u, v far outside -> the corner texels */
    assert_int_equal(glow_sample_lightmap(&o, 0.0f, 0.0f, out), GLOW_OK);
    assert_row(out, g_rows[0]);
    assert_int_equal(glow_sample_lightmap(&o, -3.0f, 0.5f / 3.0f, out), GLOW_OK);
    assert_row(out, g_rows[0]);
    assert_int_equal(glow_sample_lightmap(&o, 5.0f, -2.0f, out), GLOW_OK);
    assert_row(out, g_rows[3]);
    assert_int_equal(glow_sample_lightmap(&o, 0.0f, 1.0f, out), GLOW_OK);
    assert_row(out, g_rows[7]);
    /* NaN coordinates do not crash or read outside: clamped to 0 */
    assert_int_equal(glow_sample_lightmap(&o, NAN, NAN, out), GLOW_OK);
    assert_row(out, g_rows[0]);
    /* the empty corner (2..3, 2): texels (2,2) and (3,2) empty, at v = 1 (clamped to row 2) the
     * footprint holds only empties -> OUT_OF_RANGE, zeroed */
    out[0] = out[1] = out[2] = 7.0f;
    assert_int_equal(glow_sample_lightmap(&o, (2.5f + 0.5f) / 4.0f, 1.0f, out), GLOW_ERROR_OUT_OF_RANGE);
    assert_true(out[0] == 0.0f && out[1] == 0.0f && out[2] == 0.0f);
    /* NULL and no lightmap */
    assert_int_equal(glow_sample_lightmap(NULL, 0.5f, 0.5f, out), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_sample_lightmap(&o, 0.5f, 0.5f, NULL), GLOW_ERROR_INVALID_ARGUMENT);
    glow_cache_outputs none = o;
    none.lightmap_map = NULL;
    none.lightmap_width = none.lightmap_height = 0;
    assert_int_equal(glow_sample_lightmap(&none, 0.5f, 0.5f, out), GLOW_ERROR_INVALID_ARGUMENT);
}
#undef E

/* ------------------------------------------------------------------------------ kernels */
/* Both builds of the cache-lighting kernel on a real (small) bake's links with random node
 * radiances, against each other and against the links re-summed in double here:
 *     L_lm = Σ_j R[node_j] k_l(1 - omc_j) y_lm(dir_j). */
/* Output planes (glow__cl_write_planes): every ISA build this CPU runs gives exactly cache_sh's value
 * for mapped texels and 0 for empty ones, in ranges that start anywhere and leave vector tails,
 * with a coefficient count that leaves a partial block of four, into planes that are not 32-byte
 * aligned, and writes nothing outside its range. */
static void test_write_plane(void **state) {
    (void)state;
    enum { WC = 301, WNC = 27, WN = 1000 + 13, WS = WN + 5 };
    float *sh = malloc((size_t)WC * WNC * sizeof *sh), *dst = malloc(((size_t)WNC * WS + 1) * sizeof *dst);
    uint32_t *map = malloc(WN * sizeof *map);
    assert_true(sh && dst && map);
    for (size_t i = 0; i < (size_t)WC * WNC; ++i) sh[i] = (float)(rnd() * 10.0 - 3.0);
    for (uint32_t t = 0; t < WN; ++t) map[t] = rnd() < 0.1 ? 0xFFFFFFFFu : (uint32_t)(rnd() * WC) % WC;
    map[WN - 1] = 0xFFFFFFFFu;
    map[WN - 2] = WC - 1; /* the array's last row, in the scalar tail */
    map[8] = WC - 1;      /* and in a vector step: its masked last block must not read past the array */
    const glow__cl_isa isas[] = {GLOW__CL_GENERIC, GLOW__CL_AVX2, GLOW__CL_AVX512};
    const size_t ranges[][2] = {{0, WN}, {3, WN - 17}, {8, 16}, {WN - 5, WN}, {7, 7}};
    for (size_t ii = 0; ii < 3; ++ii) {
        if (!glow__cl_isa_supported(isas[ii])) continue;
        for (uint32_t nc = WNC - 2; nc <= WNC; ++nc) /* 25, 26, 27: partial blocks of 1, 2 and 3 */
            for (size_t ri = 0; ri < sizeof ranges / sizeof ranges[0]; ++ri) {
                const size_t first = ranges[ri][0], end = ranges[ri][1];
                for (size_t q = 0; q < (size_t)WNC * WS + 1; ++q) dst[q] = -777.0f;
                glow__cl_write_planes(isas[ii], dst + 1, WS, map, first, end, sh, nc); /* dst + 1: unaligned */
                assert_true(dst[0] == -777.0f);
                for (uint32_t k = 0; k < WNC; ++k)
                    for (size_t t = 0; t < WS; ++t) {
                        const bool in = k < nc && t >= first && t < end;
                        const float want = !in ? -777.0f : map[t] == 0xFFFFFFFFu ? 0.0f : sh[(size_t)map[t] * nc + k];
                        if (dst[1 + (size_t)k * WS + t] != want)
                            fail_msg("write_planes %s nc %u [%zu, %zu) plane %u texel %zu: %g, want %g",
                                     glow__cl_isa_name(isas[ii]), nc, first, end, k, t, (double)dst[1 + (size_t)k * WS + t],
                                     (double)want);
                    }
            }
    }
    free(sh), free(dst), free(map);
}

static void test_kernels(void **state) {
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "/tmp/glow_test_shading_%d.glow", (int)getpid());
    /* 144 links: 18 lane groups of 8, so the AVX2 kernel runs a chunk of 16 groups and a partial one */
    glow_pc_settings s = {.quality = GLOW_PC_QUALITY_LOW, .surfels = 2048, .links = 144, .bands = 3,
                          .grid_spacing = 0.5f, .texel_density = 3.0f, .threads = 2, .seed = 7};
    glow_pc_stats st;
    if (glow_pc_bake("builtin:cornell", path, &s, &st) != GLOW_OK) fail_msg("bake failed: %s", st.error);
    glow_context *ctx;
    glow_bake *bake;
    glow_context_desc cd = {.api_version = GLOW_VERSION, .tasks = {.worker_count = 1}};
    assert_int_equal(glow_context_create(&cd, &ctx), GLOW_OK);
    assert_int_equal(glow_bake_load_file(ctx, path, &bake), GLOW_OK);
    unlink(path);
    const glow_bake_meta *m = glow__bake_meta(bake);
    const glow_bake_link_block *lb = glow__bake_link_blocks(bake);
    const uint32_t N = m->node_count, C = m->cache_count, bpc = m->link_blocks_per_cache;
    float *rad = malloc(3 * (size_t)N * sizeof *rad);
    assert_non_null(rad);
    for (uint32_t i = 0; i < N; ++i) {
        rad[i] = (float)(rnd() * 2.0);
        rad[N + i] = (float)(rnd() - 0.5);
        rad[2 * (size_t)N + i] = (float)(rnd() - 0.5);
    }
    /* every kernel build this CPU runs; the portable one first (the others are compared with it) */
    const glow__cl_isa isas[] = {GLOW__CL_GENERIC, GLOW__CL_AVX2, GLOW__CL_AVX512};
    enum { NISA = sizeof isas / sizeof isas[0] };
    bool run[NISA];
    for (int i = 0; i < NISA; ++i) {
        run[i] = glow__cl_isa_supported(isas[i]) != 0;
        if (!run[i]) print_message("kernel %s: not supported by this CPU, skipped\n", glow__cl_isa_name(isas[i]));
    }
    assert_true(run[0]);
    assert_true(glow__cl_isa_supported(glow__cl_best_isa()));
    /* link subsets (LSUB): the bake's weights (the builtin Cornell box has some on most caches) and
     * random per-node luma ratios, as the system's pull leaves them */
    const uint16_t *lsub = glow__bake_link_subsets(bake);
    assert_non_null(lsub);
    uint32_t n_sub = 0;
    for (size_t j = 0; j < (size_t)C * bpc * GLOW_LINK_BLOCK; ++j) n_sub += lsub[j] != 0;
    assert_true(n_sub > (uint32_t)C); /* the kernel's subset path is exercised */
    /* the system's interleaved layout (Y Co Cg pad per node, the ISAs' pair gathers), used in the
     * subset passes; the plain passes read planar arrays */
    float *rad4 = malloc(4 * (size_t)N * sizeof *rad4);
    assert_non_null(rad4);
    for (uint32_t i = 0; i < N; ++i) {
        rad4[4 * (size_t)i] = rad[i];
        rad4[4 * (size_t)i + 1] = rad[N + i];
        rad4[4 * (size_t)i + 2] = rad[2 * (size_t)N + i];
        rad4[4 * (size_t)i + 3] = -1.0f; /* never read */
    }
    uint16_t *ratio = malloc(4 * (size_t)N * sizeof *ratio);
    assert_non_null(ratio);
    for (size_t i = 0; i < 4 * (size_t)N; ++i) ratio[i] = i % 7 == 3 ? 0u : glow__half_from_float((float)(rnd() * 4.0));
    /* link gradients (a.link_gradient): random codes (a quarter 0) and per node u_x u_y u_z 0 as signed
     * halves in [-3, 3], so that some scales clamp at 0 */
    const size_t n_links = (size_t)C * bpc * GLOW_LINK_BLOCK;
    uint16_t *gcode = malloc(n_links * sizeof *gcode), *gu = malloc(4 * (size_t)N * sizeof *gu);
    assert_true(gcode && gu);
    for (size_t j = 0; j < n_links; ++j) {
        const uint32_t kx = (uint32_t)(rnd() * 31.0) % 31u, ky = (uint32_t)(rnd() * 31.0) % 31u, kz = (uint32_t)(rnd() * 31.0) % 31u;
        gcode[j] = rnd() < 0.25 ? 0u : (uint16_t)(0x8000u | kx | (ky << 5) | (kz << 10));
    }
    for (size_t i = 0; i < 4 * (size_t)N; ++i) {
        const float x = (float)(rnd() * 6.0 - 3.0); /* normal halves or 0, as the system writes them */
        gu[i] = i % 4 == 3 || i % 11 == 5 || fabsf(x) < 1e-3f ? 0u : glow__half_from_float(x);
    }
    /* the system's folded layout (a.grad_uz): u_x u_y in the bits of each record's fourth float, u_z
     * beside, padded for the kernel's 32-bit reads */
    float *rad4g = malloc(4 * (size_t)N * sizeof *rad4g);
    uint16_t *guz = malloc(((size_t)N + 2) * sizeof *guz);
    assert_true(rad4g && guz);
    for (uint32_t i = 0; i < N; ++i) {
        const uint32_t xy = (uint32_t)gu[4 * (size_t)i] | (uint32_t)gu[4 * (size_t)i + 1] << 16;
        memcpy(rad4g + 4 * (size_t)i, rad4 + 4 * (size_t)i, 3 * sizeof *rad4g);
        memcpy(rad4g + 4 * (size_t)i + 3, &xy, sizeof xy);
        guz[i] = gu[4 * (size_t)i + 2];
    }
    guz[N] = guz[N + 1] = 0x7BFFu; /* past the end: must not matter */
    const uint32_t combos[][2] = {{1, 1}, {2, 1}, {3, 3}, {4, 2}, {5, 3}, {8, 8}};
    float *gsave[NISA] = {NULL};
    for (size_t cw = 0; cw < 4 * sizeof combos / sizeof combos[0]; ++cw) {
        const size_t ci = cw / 4;
        /* plain, subsets, gradients (u in sub_ratio), gradients folded (u in the records, grad_uz) */
        const bool ws = cw % 4 != 0, grad = cw % 4 >= 2, fold = cw % 4 == 3;
        const uint32_t L = combos[ci][0], Cb = combos[ci][1], nco = L * L + 2 * Cb * Cb, stride = nco + 3; /* padding */
        float *out[NISA];
        for (int i = 0; i < NISA; ++i) {
            out[i] = malloc((size_t)C * stride * sizeof *out[i]);
            assert_non_null(out[i]);
            for (size_t q = 0; q < (size_t)C * stride; ++q) out[i][q] = -777.0f;
        }
        double *ref = malloc((size_t)C * nco * sizeof *ref), *scale = malloc((size_t)C * 3 * sizeof *scale);
        assert_true(ref && scale);
        for (int i = 0; i < NISA; ++i) {
            if (!run[i]) continue;
            const float *r4 = fold ? rad4g : rad4;
            glow__cl_args a = {.blocks = lb, .blocks_per_cache = bpc, .rad_y = ws ? r4 : rad,
                               .rad_co = ws ? r4 + 1 : rad + N, .rad_cg = ws ? r4 + 2 : rad + 2 * (size_t)N,
                               .rad_stride = ws ? 4u : 0u, .luma = L, .chroma = Cb, .coeffs = stride,
                               .cache_sh = out[i], .isa = isas[i], .subsets = ws ? (grad ? gcode : lsub) : NULL,
                               .sub_ratio = fold ? NULL : (const uint32_t *)(const void *)(grad ? gu : ratio),
                               .grad_uz = fold ? guz : NULL,
                               .link_gradient = grad};
            /* in uneven ranges: the result must not depend on how the caches are split */
            for (uint32_t first = 0; first < C;) {
                uint32_t cnt = 1 + (uint32_t)(rnd() * 37.0);
                if (cnt > C - first) cnt = C - first;
                glow__cl_light_caches(&a, first, cnt);
                first += cnt;
            }
        }
        /* reference */
        for (uint32_t c = 0; c < C; ++c) {
            double *r = ref + (size_t)c * nco, *sc = scale + 3 * (size_t)c;
            memset(r, 0, nco * sizeof *r);
            sc[0] = sc[1] = sc[2] = 0.0;
            for (uint32_t j = 0; j < bpc * GLOW_LINK_BLOCK; ++j) {
                const glow_bake_link_block *b = lb + (size_t)c * bpc + j / GLOW_LINK_BLOCK;
                const uint32_t lane = j % GLOW_LINK_BLOCK, node = glow_bake_link_node(b, lane);
                const double omc = glow__half_to_float(b->one_minus_cos[lane]);
                if (omc == 0.0) continue;
                uint32_t du, dv;
                float d[3], y[NC];
                glow_bake_link_dir12(b, lane, &du, &dv);
                glow__oct_decode12(du, dv, d);
                glow_sh_eval(L, d, y);
                double sr = 1.0; /* LSUB: R[node] x sum_i q_i r_i / sum_i q_i */
                const uint16_t q = ws ? (grad ? gcode : lsub)[(size_t)c * bpc * GLOW_LINK_BLOCK + j] : 0u;
                if (q && grad) { /* max(0, 1 + k . u / 15) */
                    double dot = 0.0;
                    for (int k = 0; k < 3; ++k)
                        dot += ((double)((q >> (5 * k)) & 31u) - 15.0) * glow__half_to_float(gu[4 * (size_t)node + (size_t)k]);
                    sr = fmax(0.0, 1.0 + dot / 15.0);
                } else if (q) {
                    double num = 0.0, den = 0.0;
                    for (int k = 0; k < 4; ++k) {
                        num += ((q >> (4 * k)) & 15u) * (double)glow__half_to_float(ratio[4 * (size_t)node + (size_t)k]);
                        den += (q >> (4 * k)) & 15u;
                    }
                    sr = num / den;
                }
                const double x = 1.0 - omc,
                             R[3] = {rad[node] * sr, rad[N + node] * sr, rad[2 * (size_t)N + node] * sr};
                for (uint32_t l = 0; l < L; ++l) {
                    const double kl = l == 0 ? 2.0 * M_PI * omc
                                             : 2.0 * M_PI / (2.0 * l + 1.0) * (legendre((int)l - 1, x) - legendre((int)l + 1, x));
                    for (uint32_t k = l * l; k < (l + 1) * (l + 1); ++k) {
                        r[k] += R[0] * kl * y[k];
                        if (l < Cb) {
                            r[L * L + k] += R[1] * kl * y[k];
                            r[L * L + Cb * Cb + k] += R[2] * kl * y[k];
                        }
                    }
                    /* per-channel scale Σ |R| ω, for relative tolerances */
                    if (l == 0)
                        for (int ch = 0; ch < 3; ++ch) sc[ch] += fabs(R[ch]) * kl;
                }
            }
        }
        double worst_ref[NISA] = {0}, worst_gen[NISA] = {0};
        for (uint32_t c = 0; c < C; ++c) {
            for (uint32_t k = 0; k < nco; ++k) {
                const int ch = k < L * L ? 0 : (k < L * L + Cb * Cb ? 1 : 2);
                const double sc = scale[3 * (size_t)c + ch] + 1e-12, rv = ref[(size_t)c * nco + k];
                for (int i = 0; i < NISA; ++i) {
                    if (!run[i]) continue;
                    const double v = out[i][(size_t)c * stride + k];
                    worst_ref[i] = fmax(worst_ref[i], fabs(v - rv) / sc);
                    worst_gen[i] = fmax(worst_gen[i], fabs(v - out[0][(size_t)c * stride + k]) / sc);
                }
            }
            for (uint32_t k = nco; k < stride; ++k) /* the padding is not written */
                for (int i = 0; i < NISA; ++i)
                    if (run[i]) assert_true(out[i][(size_t)c * stride + k] == -777.0f);
        }
        for (int i = 0; i < NISA; ++i) {
            if (!run[i]) continue;
            print_message("kernel %-14s luma %u chroma %u%s, %u caches x %u links: vs double %.2e, vs generic %.2e "
                          "(relative to Σ|R| ω)\n",
                          glow__cl_isa_name(isas[i]), L, Cb, fold ? " gradients folded" : grad ? " gradients" : (ws ? " subsets" : ""), C, m->links_per_cache, worst_ref[i],
                          worst_gen[i]);
            assert_true(worst_ref[i] < 1e-5);
            assert_true(worst_gen[i] < 1e-5);
        }
        /* the folded layout gives the same bytes as u in sub_ratio (the pass before it), each ISA */
        for (int i = 0; i < NISA; ++i) {
            if (!run[i] || !grad) continue;
            const size_t bytes = (size_t)C * stride * sizeof(float);
            if (!fold) {
                assert_non_null(gsave[i] = malloc(bytes));
                memcpy(gsave[i], out[i], bytes);
            } else {
                assert_memory_equal(gsave[i], out[i], bytes);
                free(gsave[i]);
                gsave[i] = NULL;
            }
        }
        /* a sub-range writes only its own rows */
        for (int i = 0; i < NISA; ++i) {
            if (!run[i]) continue;
            for (size_t q = 0; q < (size_t)C * stride; ++q) out[i][q] = -777.0f;
            glow__cl_args a = {.blocks = lb, .blocks_per_cache = bpc, .rad_y = rad, .rad_co = rad + N,
                               .rad_cg = rad + 2 * (size_t)N, .luma = L, .chroma = Cb, .coeffs = stride,
                               .cache_sh = out[i], .isa = isas[i]};
            glow__cl_light_caches(&a, C / 3, 5);
            for (uint32_t c = 0; c < C; ++c)
                for (uint32_t k = 0; k < stride; ++k) {
                    const float v = out[i][(size_t)c * stride + k];
                    if (c >= C / 3 && c < C / 3 + 5 && k < nco)
                        assert_true(v != -777.0f);
                    else
                        assert_true(v == -777.0f);
                }
        }
        for (int i = 0; i < NISA; ++i) free(out[i]);
        free(ref);
        free(scale);
    }
    assert_string_equal(glow__cl_isa_name(GLOW__CL_GENERIC), "generic");
    free(rad);
    free(rad4);
    free(rad4g);
    free(guz);
    free(ratio);
    free(gcode);
    free(gu);
    glow_bake_destroy(bake);
    glow_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ycocg),          cmocka_unit_test(test_sh_orthonormal), cmocka_unit_test(test_sh_closed_forms), cmocka_unit_test(test_sh_scaled_basis),
        cmocka_unit_test(test_cone_factor),    cmocka_unit_test(test_sh_projection),  cmocka_unit_test(test_lobe_factor),
        cmocka_unit_test(test_sh_window),      cmocka_unit_test(test_shade_uniform),  cmocka_unit_test(test_shade_linear),   cmocka_unit_test(test_shade_cone),
        cmocka_unit_test(test_sample_grid),    cmocka_unit_test(test_sample_grid_oriented), cmocka_unit_test(test_sample_grid_refined), cmocka_unit_test(test_sample_lightmap), cmocka_unit_test(test_kernels), cmocka_unit_test(test_write_plane),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
