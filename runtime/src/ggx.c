/* ggx.c — a GGX (Trowbridge-Reitz) specular lobe shaded from SH caches: its zonal-harmonic lobe factors
 * about the reflection vector (DDISH-GI App. A) and its directional albedo (the split sum's second
 * integral). The derivation is in docs/glossy.md; tests/unit/test_ggx_zh.c checks both against an
 * independent quadrature.
 *
 * Conventions: roughness r is glTF's perceptual roughness, α = r²; D(h) = α² / (π (cos²θ_h (α² - 1) + 1)²);
 * G = G1(o) G1(i) (separable Smith), G1(c) = 2c / (c + sqrt(α² + (1 - α²) c²));
 * f_s = D G F / (4 cos θ_o cos θ_i); Schlick F = F0 + (1 - F0)(1 - o·h)⁵.
 *
 * Both integrals use the half vector's GGX parametrisation: with s = tan θ_h / α, the measure
 * D(h) cos θ_h dω_h is du dφ / 2π, u = s² / (1 + s²), du = 2s / (1 + s²)² ds. The integrands then vary
 * on the scale s ~ 1 (the lobe) with a tail to s = 1/α (θ_h = 45°, the horizon at normal incidence), so
 * s is cut into panels that double in width from 1/8, each integrated with 16-node Gauss-Legendre. */
#include <math.h>
#include <string.h>

#include "runtime_internal.h"
#include "sh_kernel.h"

#define PI_D 3.14159265358979323846

/* 16-node Gauss-Legendre on [-1, 1]: nodes ±x, weights w (Abramowitz & Stegun 25.4.30). */
static const double gl_x[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
                               0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
static const double gl_w[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
                               0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};

static double g1(double c, double a2) { return c > 0.0 ? 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c)) : 0.0; }

static double roughness_alpha(float roughness) {
    double r = isfinite(roughness) ? (double)roughness : 1.0;
    if (r < 1e-3) r = 1e-3; /* α = 1e-6: a mirror to float precision */
    if (r > 1.0) r = 1.0;
    return r * r;
}

/* Calls fn(s, weight) for the quadrature nodes of ∫_0^smax ... ds. */
typedef void (*panel_fn)(void *user, double s, double weight);
static void integrate_s(double smax, panel_fn fn, void *user) {
    double a = 0.0, b = smax < 0.125 ? smax : 0.125;
    while (a < smax) {
        const double h = 0.5 * (b - a), m = 0.5 * (b + a);
        for (int i = 0; i < 8; ++i) {
            fn(user, m - h * gl_x[i], h * gl_w[i]);
            fn(user, m + h * gl_x[i], h * gl_w[i]);
        }
        a = b;
        b = 2.0 * b > smax ? smax : 2.0 * b;
    }
}

/* ---- zonal lobe at normal incidence: o = n = the reflection vector, θ_i = 2 θ_h, G1(o) = 1.
 * The lobe f_s cos θ_i (F left out) as a function of θ_i has the moments
 *   m_l = 2π ∫ f_s cos θ_i P_l(cos θ_i) sin θ_i dθ_i = ∫_0^{u_c} G1(cos θ_i) P_l(cos θ_i) du
 * (the D cos θ_h measure above, dω_i = 4 (o·h) dω_h, f_s cos θ_i · 4 cos θ_h = D G1(i) cos θ_h), and
 * the lobe factors are s_l = m_l / m_0. */
typedef struct zh_acc {
    double a2;
    uint32_t bands;
    double m[GLOW__MAX_BANDS];
} zh_acc;

static void zh_node(void *user, double s, double w) {
    zh_acc *z = user;
    const double t2 = z->a2 * s * s;            /* tan² θ_h */
    const double ci = (1.0 - t2) / (1.0 + t2);  /* cos θ_i = cos 2θ_h */
    if (!(ci > 0.0)) return;
    const double du = 2.0 * s / ((1.0 + s * s) * (1.0 + s * s));
    const double f = w * du * g1(ci, z->a2);
    double p0 = 1.0, p1 = ci;
    z->m[0] += f;
    if (z->bands > 1) z->m[1] += f * ci;
    for (uint32_t l = 1; l + 1 < z->bands; ++l) {
        const double p2 = ((2.0 * l + 1.0) * ci * p1 - l * p0) / (l + 1.0);
        z->m[l + 1] += f * p2;
        p0 = p1;
        p1 = p2;
    }
}

void glow_sh_ggx_lobe_factors(float roughness, uint32_t bands, float *out) {
    if (!out || bands == 0) return;
    if (bands > GLOW__MAX_BANDS) bands = GLOW__MAX_BANDS;
    zh_acc z;
    memset(&z, 0, sizeof z);
    z.a2 = roughness_alpha(roughness);
    z.a2 *= z.a2;
    z.bands = bands;
    integrate_s(1.0 / sqrt(z.a2), zh_node, &z); /* tan θ_h <= 1 (θ_i <= 90°) */
    for (uint32_t l = 0; l < bands; ++l) out[l] = z.m[0] > 0.0 ? (float)(z.m[l] / z.m[0]) : (l == 0 ? 1.0f : 0.0f);
}

/* ---- directional albedo at cos θ_o = mu: ∫ f_s cos θ_i dω_i = F0 · A + B with
 *   A = ∫ D G (o·h) / (cos θ_o) (1 - (1 - o·h)⁵) dω_h,  B = the same with (1 - o·h)⁵,
 * over half vectors whose reflection lies above the surface; in (s, φ), D cos θ_h dω_h = du dφ / 2π. */
typedef struct alb_acc {
    double a2, mu, so; /* so = sin θ_o */
    double A, B;
} alb_acc;

#define ALB_PHI 64 /* φ nodes on [0, π] (the lobe is symmetric about the plane of o and n) */

static void alb_node(void *user, double s, double w) {
    alb_acc *q = user;
    const double t2 = q->a2 * s * s, ch = 1.0 / sqrt(1.0 + t2), sh = sqrt(t2) * ch;
    const double du = 2.0 * s / ((1.0 + s * s) * (1.0 + s * s));
    const double g1o = g1(q->mu, q->a2);
    for (int j = 0; j < ALB_PHI; ++j) {
        const double phi = PI_D * (j + 0.5) / ALB_PHI;
        /* o = (so, 0, mu), h = (sh cos φ, sh sin φ, ch) */
        const double oh = q->so * sh * cos(phi) + q->mu * ch;
        if (!(oh > 0.0)) continue;
        const double ci = 2.0 * oh * ch - q->mu; /* i = 2 (o·h) h - o, its z */
        if (!(ci > 0.0)) continue;
        const double f = w * du * (1.0 / ALB_PHI) * g1o * g1(ci, q->a2) * oh / (q->mu * ch);
        const double k = pow(1.0 - oh, 5.0);
        q->A += f * (1.0 - k);
        q->B += f * k;
    }
}

void glow_ggx_specular_albedo(float cos_view, float roughness, float out_ab[2]) {
    if (!out_ab) return;
    out_ab[0] = out_ab[1] = 0.0f;
    double mu = isfinite(cos_view) ? (double)cos_view : 0.0;
    if (!(mu > 0.0)) return;
    if (mu > 1.0) mu = 1.0;
    if (mu < 1e-4) mu = 1e-4;
    alb_acc q;
    memset(&q, 0, sizeof q);
    q.a2 = roughness_alpha(roughness);
    q.a2 *= q.a2;
    q.mu = mu;
    q.so = sqrt(fmax(0.0, 1.0 - mu * mu));
    /* the reflection stays above the surface up to θ_h = 90°; beyond s = 64/α the GGX tail holds less
     * than 1/(1 + 64²) = 0.02 % of the half vectors */
    integrate_s(64.0 / sqrt(q.a2), alb_node, &q);
    out_ab[0] = (float)q.A;
    out_ab[1] = (float)q.B;
}
