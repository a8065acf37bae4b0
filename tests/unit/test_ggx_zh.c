/* test_ggx_zh.c — the GGX lobe in zonal harmonics (runtime/src/ggx.c, docs/glossy.md) against an
 * independent computation:
 *   - the brute-force integrator below (midpoint rule in θ_i, the lobe written in the incident
 *     direction, not the half vector) reproduces glow_sh_lobe_factor for Phong lobes (so it is right);
 *   - glow_sh_ggx_lobe_factors against it, r = 0.05 .. 1;
 *   - glow_ggx_specular_albedo against a midpoint rule over (θ_i, φ_i), and its normal-incidence sum
 *     A + B against the brute-force lobe's zeroth moment; 0 <= A + B <= 1 (Smith G loses energy);
 *   - properties: s_0 = 1, |s_l| < 1, s_1 and s_2 fall with roughness, a mirror keeps every band;
 *   - glow_shade_sh_factors: the same numbers as glow_shade_sh with Phong factors, and a linear
 *     field L(ω) = a + b·ω averaged to a + s_1 b·axis;
 * and prints (not asserts) the band-limited lobe's relative L2 error and peak for l = 2..8 per
 * roughness: where SH cannot represent the lobe (docs/glossy.md quotes this table). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "glow/glow.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define NB GLOW_MAX_SH_BANDS

static double g1(double c, double a2) { return c > 0.0 ? 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c)) : 0.0; }
static double ggx_d(double ch, double a2) {
    const double t = ch * ch * (a2 - 1.0) + 1.0;
    return a2 / (M_PI * t * t);
}

/* The lobe at normal incidence as a function of θ_i (o = n): f_s cos θ_i with F = 1,
 * = D(θ_i / 2) G1(o) G1(i) / (4 cos θ_o cos θ_i) cos θ_i, cos θ_o = 1. */
static double ggx_lobe(double theta, double a2) {
    if (theta >= 0.5 * M_PI) return 0.0;
    return ggx_d(cos(0.5 * theta), a2) * g1(cos(theta), a2) / 4.0;
}
static double phong_lobe(double theta, double n) {
    return theta >= 0.5 * M_PI ? 0.0 : (n + 1.0) / (2.0 * M_PI) * pow(cos(theta), n);
}

/* m_l = 2π ∫ lobe P_l(cos θ) sin θ dθ (l < bands) and q = 2π ∫ lobe² sin θ dθ, midpoint rule with
 * `steps` steps on [0, π/2]. */
static void brute_moments(double (*lobe)(double, double), double param, int bands, long steps, double *m, double *q) {
    for (int l = 0; l < bands; ++l) m[l] = 0.0;
    double qq = 0.0;
    const double h = 0.5 * M_PI / (double)steps;
    for (long i = 0; i < steps; ++i) {
        const double t = (i + 0.5) * h, x = cos(t), w = 2.0 * M_PI * sin(t) * h, f = lobe(t, param) * w;
        double p0 = 1.0, p1 = x;
        m[0] += f;
        if (bands > 1) m[1] += f * x;
        for (int l = 1; l + 1 < bands; ++l) {
            const double p2 = ((2.0 * l + 1.0) * x * p1 - l * p0) / (l + 1.0);
            m[l + 1] += f * p2;
            p0 = p1;
            p1 = p2;
        }
        qq += f * lobe(t, param);
    }
    if (q) *q = qq;
}

static void test_brute_force_is_right(void **state) {
    (void)state;
    const double ns[] = {1.0, 5.0, 30.0, 200.0};
    for (size_t k = 0; k < sizeof ns / sizeof ns[0]; ++k) {
        double m[NB];
        brute_moments(phong_lobe, ns[k], NB, 400000, m, NULL);
        assert_true(fabs(m[0] - 1.0) < 1e-6);
        for (int l = 0; l < (int)NB; ++l) {
            const double want = glow_sh_lobe_factor((uint32_t)l, (float)ns[k]);
            if (fabs(m[l] / m[0] - want) > 2e-5) fail_msg("Phong n=%g l=%d: brute %.7f, App. B %.7f", ns[k], l, m[l] / m[0], want);
        }
    }
}

static const float roughness[] = {0.05f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.7f, 1.0f};
#define NR (sizeof roughness / sizeof roughness[0])

static void test_zh_factors_vs_quadrature(void **state) {
    (void)state;
    double worst = 0.0;
    for (size_t k = 0; k < NR; ++k) {
        const double a = (double)roughness[k] * roughness[k], a2 = a * a;
        double m[NB];
        brute_moments(ggx_lobe, a2, NB, 2000000, m, NULL);
        float s[NB];
        glow_sh_ggx_lobe_factors(roughness[k], NB, s);
        assert_true(s[0] == 1.0f);
        for (int l = 0; l < (int)NB; ++l) {
            const double want = m[l] / m[0], d = fabs(s[l] - want);
            if (d > worst) worst = d;
            if (d > 1e-4) fail_msg("GGX r=%g l=%d: ggx.c %.6f, brute force %.6f", (double)roughness[k], l, (double)s[l], want);
        }
        /* the normal-incidence albedo (F0 = 1: A + B) is the lobe's zeroth moment */
        float ab[2];
        glow_ggx_specular_albedo(1.0f, roughness[k], ab);
        if (fabs(ab[0] + ab[1] - m[0]) > 1e-3 * m[0])
            fail_msg("GGX r=%g: A+B at normal incidence %.6f, lobe integral %.6f", (double)roughness[k], (double)(ab[0] + ab[1]), m[0]);
    }
    printf("ZH-GGX factors: largest difference from the brute-force quadrature %.2e\n", worst);
}

static void test_zh_factors_properties(void **state) {
    (void)state;
    float prev[NB] = {0};
    for (size_t k = 0; k < NR; ++k) {
        float s[NB];
        glow_sh_ggx_lobe_factors(roughness[k], NB, s);
        /* a lobe of positive width damps every band; rougher lobes damp bands 1 and 2 more (higher bands of
         * rough lobes oscillate about 0, as the diffuse lobe's 1, 2/3, 1/4, 0, -1/24 do) */
        for (int l = 1; l < (int)NB; ++l) assert_true(s[l] > -0.2f && s[l] < 1.0f);
        assert_true(s[1] < s[0] && s[2] < s[1]);
        if (k > 0) assert_true(s[1] < prev[1] && s[2] < prev[2]);
        memcpy(prev, s, sizeof s);
    }
    float s[NB];
    glow_sh_ggx_lobe_factors(0.001f, NB, s); /* α = 1e-6: a mirror */
    for (int l = 0; l < (int)NB; ++l) assert_true(fabsf(s[l] - 1.0f) < 1e-4f);
    /* fewer bands: the same leading factors; bad input is clamped, not NaN */
    float t[3];
    glow_sh_ggx_lobe_factors(0.3f, 3, t);
    glow_sh_ggx_lobe_factors(0.3f, NB, s);
    assert_memory_equal(t, s, sizeof t);
    glow_sh_ggx_lobe_factors(NAN, 3, t);
    for (int l = 0; l < 3; ++l) assert_true(isfinite(t[l]));
}

/* ∫ f_s cos θ_i dω_i by a midpoint rule over (θ_i, φ_i), F = F0 + (1 - F0)(1 - o·h)⁵ split as A, B. */
static void brute_albedo(double mu, double a2, int nt, int np, double *A, double *B) {
    const double so = sqrt(1.0 - mu * mu), o[3] = {so, 0.0, mu};
    double sa = 0.0, sb = 0.0;
    for (int i = 0; i < nt; ++i) {
        const double t = (i + 0.5) * 0.5 * M_PI / nt, ct = cos(t), st = sin(t);
        for (int j = 0; j < np; ++j) {
            const double p = (j + 0.5) * M_PI / np; /* [0, π], doubled: symmetric in φ */
            const double w[3] = {st * cos(p), st * sin(p), ct};
            double h[3] = {o[0] + w[0], o[1] + w[1], o[2] + w[2]};
            const double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            for (int c = 0; c < 3; ++c) h[c] /= hl;
            const double oh = o[0] * h[0] + o[1] * h[1] + o[2] * h[2];
            const double f = ggx_d(h[2], a2) * g1(mu, a2) * g1(ct, a2) / (4.0 * mu * ct) * ct;
            const double dw = st * (0.5 * M_PI / nt) * (M_PI / np) * 2.0, k = pow(1.0 - oh, 5.0);
            sa += f * dw * (1.0 - k);
            sb += f * dw * k;
        }
    }
    *A = sa;
    *B = sb;
}

static void test_albedo_vs_quadrature(void **state) {
    (void)state;
    const float mus[] = {0.1f, 0.3f, 0.6f, 1.0f};
    const float rs[] = {0.3f, 0.5f, 0.8f, 1.0f};
    for (size_t i = 0; i < 4; ++i)
        for (size_t k = 0; k < 4; ++k) {
            const double a = (double)rs[k] * rs[k];
            double A, B;
            brute_albedo(mus[i], a * a, 1500, 800, &A, &B);
            float ab[2];
            glow_ggx_specular_albedo(mus[i], rs[k], ab);
            if (fabs(ab[0] - A) > 2e-3 * (A + B) + 2e-4 || fabs(ab[1] - B) > 2e-3 * (A + B) + 2e-4)
                fail_msg("albedo mu=%g r=%g: ggx.c A %.5f B %.5f, quadrature A %.5f B %.5f", (double)mus[i], (double)rs[k],
                         (double)ab[0], (double)ab[1], A, B);
            assert_true(ab[0] + ab[1] <= 1.0f + 1e-4f && ab[0] > 0.0f && ab[1] >= 0.0f);
        }
    float ab[2];
    glow_ggx_specular_albedo(0.0f, 0.5f, ab);
    assert_true(ab[0] == 0.0f && ab[1] == 0.0f);
    glow_ggx_specular_albedo(1.0f, 0.001f, ab); /* a mirror reflects F0 at normal incidence */
    assert_true(fabsf(ab[0] - 1.0f) < 2e-3f && ab[1] < 1e-3f);
}

static void test_shade_factors(void **state) {
    (void)state;
    const uint32_t L = 4, C = 2, n = L * L + 2 * C * C;
    float coeffs[L * L + 2 * C * C];
    for (uint32_t k = 0; k < n; ++k) coeffs[k] = sinf(1.7f * (float)k + 0.3f);
    const float axis[3] = {0.48f, 0.6f, 0.64f};
    float a[3], b[3], s[NB];
    for (uint32_t l = 0; l < L; ++l) s[l] = glow_sh_lobe_factor(l, 7.0f);
    glow_shade_sh(coeffs, L, C, axis, 7.0f, a);
    glow_shade_sh_factors(coeffs, L, C, axis, s, b);
    assert_memory_equal(a, b, sizeof a);
    /* L(ω) = a0 + b·ω in luma only: y_00 = 1/(2 sqrt π), y_1 = sqrt(3/4π) (y, z, x) */
    float lin[16] = {0};
    const double a0 = 2.0, bv[3] = {0.3, -0.5, 0.7};
    lin[0] = (float)(a0 * 2.0 * sqrt(M_PI));
    const double k1 = sqrt(4.0 * M_PI / 3.0);
    lin[1] = (float)(bv[1] * k1);
    lin[2] = (float)(bv[2] * k1);
    lin[3] = (float)(bv[0] * k1);
    glow_sh_ggx_lobe_factors(0.4f, 2, s);
    glow_shade_sh_factors(lin, 2, 0, axis, s, a);
    const double want = a0 + s[1] * (bv[0] * axis[0] + bv[1] * axis[1] + bv[2] * axis[2]);
    for (int c = 0; c < 3; ++c) assert_true(fabs(a[c] - want) < 1e-5);
}

/* Printed for docs/glossy.md: how much of the (normalised) lobe l bands hold. */
static void test_print_truncation(void **state) {
    (void)state;
    printf("ZH-GGX lobe factors s_0..s_7 (glow_sh_ggx_lobe_factors) and the Phong exponent glow-render maps r to:\n");
    for (size_t k = 0; k < NR; ++k) {
        float s[NB];
        glow_sh_ggx_lobe_factors(roughness[k], NB, s);
        const double a = (double)roughness[k] * roughness[k];
        printf("  r %.2f:", (double)roughness[k]);
        for (int l = 0; l < (int)NB; ++l) printf(" %7.4f", (double)s[l]);
        printf("   Phong n %.1f:", fmax(1.0, 0.25 * (2.0 / (a * a) - 2.0)));
        for (int l = 0; l < (int)NB; ++l) printf(" %7.4f", (double)glow_sh_lobe_factor((uint32_t)l, (float)fmax(1.0, 0.25 * (2.0 / (a * a) - 2.0))));
        printf("\n");
    }
    printf("GGX lobe (normal incidence) in l bands: relative L2 error | band-limited peak / true peak\n");
    printf("roughness  alpha  ");
    for (int l = 2; l <= (int)NB; ++l) printf("     l=%d      ", l);
    printf("\n");
    for (size_t k = 0; k < NR; ++k) {
        const double a = (double)roughness[k] * roughness[k], a2 = a * a;
        double m[NB], q;
        brute_moments(ggx_lobe, a2, NB, 1000000, m, &q);
        const double pp = q / (m[0] * m[0]), peak = ggx_lobe(0.0, a2) / m[0];
        printf("%8.2f %6.4f  ", (double)roughness[k], a);
        double prev_err = 2.0;
        for (int l = 2; l <= (int)NB; ++l) {
            double held = 0.0, pk = 0.0;
            for (int j = 0; j < l; ++j) {
                const double s = m[j] / m[0];
                held += (2.0 * j + 1.0) / (4.0 * M_PI) * s * s;
                pk += (2.0 * j + 1.0) / (4.0 * M_PI) * s;
            }
            const double err = sqrt(fmax(0.0, 1.0 - held / pp));
            assert_true(err <= prev_err + 1e-12); /* more bands never hold less */
            prev_err = err;
            printf("  %5.3f | %5.3f", err, pk / peak);
        }
        printf("\n");
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_brute_force_is_right), cmocka_unit_test(test_zh_factors_vs_quadrature),
        cmocka_unit_test(test_zh_factors_properties), cmocka_unit_test(test_albedo_vs_quadrature),
        cmocka_unit_test(test_shade_factors),         cmocka_unit_test(test_print_truncation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
