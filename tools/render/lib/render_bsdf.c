/* render_bsdf.c — glow-render's GGX layer: evaluation, sampling (render_bsdf.h; docs/glossy.md). */
#include <math.h>
#include <string.h>

#include "glow/glow.h"
#include "render_bsdf.h"

#define PI_F 3.14159265358979323846f
#define INV_PI_F 0.31830988618379067154f

static inline float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline float norm3(float v[3]) {
    float l = sqrtf(dot3(v, v));
    if (l > 0.0f)
        for (int k = 0; k < 3; ++k) v[k] /= l;
    return l;
}
static inline void cross3(const float a[3], const float b[3], float o[3]) {
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

void glow__render_onb(const float n[3], float t[3], float b[3]) {
    float sign = copysignf(1.0f, n[2]);
    float a = -1.0f / (sign + n[2]);
    float c = n[0] * n[1] * a;
    t[0] = 1.0f + sign * n[0] * n[0] * a; t[1] = sign * c; t[2] = -sign * n[0];
    b[0] = c; b[1] = sign + n[1] * n[1] * a; b[2] = -n[1];
}

float glow__render_sample_cosine(const float n[3], float r1, float r2, float out[3]) {
    float t[3], b[3];
    glow__render_onb(n, t, b);
    float phi = 2.0f * PI_F * r1, sr = sqrtf(r2), z = sqrtf(fmaxf(0.0f, 1.0f - r2));
    float x = sr * cosf(phi), y = sr * sinf(phi);
    for (int k = 0; k < 3; ++k) out[k] = x * t[k] + y * b[k] + z * n[k];
    norm3(out);
    return z;
}

static inline float ggx_d(float a2, float ch) {
    const float t = ch * ch * (a2 - 1.0f) + 1.0f;
    return a2 / (PI_F * t * t);
}
static inline float ggx_g1(float a2, float c) { return c > 0.0f ? 2.0f * c / (c + sqrtf(a2 + (1.0f - a2) * c * c)) : 0.0f; }

void glow__render_ggx_init(glow__render_ggx *g, float roughness, const float f0[3]) {
    memset(g, 0, sizeof *g);
    g->roughness = roughness;
    g->alpha = roughness * roughness;
    memcpy(g->f0, f0, sizeof g->f0);
    for (int j = 0; j < GLOW__RENDER_GGX_TABLE; ++j) {
        const float x = (float)j / (GLOW__RENDER_GGX_TABLE - 1);
        glow_ggx_specular_albedo(x * x, roughness, g->ab[j]);
    }
    /* Ē = 2 ∫ E(μ) μ dμ of the piecewise-linear table (midpoint rule, 64 steps a segment: exact to 1e-6) */
    double e[3] = {0, 0, 0};
    const int n = 64 * (GLOW__RENDER_GGX_TABLE - 1);
    for (int i = 0; i < n; ++i) {
        const float mu = ((float)i + 0.5f) / (float)n;
        float v[3];
        glow__render_ggx_albedo(g, mu, v);
        for (int k = 0; k < 3; ++k) e[k] += 2.0 * v[k] * mu / n;
    }
    for (int k = 0; k < 3; ++k) g->e_mean[k] = (float)e[k];
}

void glow__render_ggx_albedo(const glow__render_ggx *g, float c, float out[3]) {
    const float x = sqrtf(fminf(fmaxf(c, 0.0f), 1.0f)) * (float)(GLOW__RENDER_GGX_TABLE - 1);
    const int i0 = x < (float)(GLOW__RENDER_GGX_TABLE - 1) ? (int)x : GLOW__RENDER_GGX_TABLE - 2;
    const float t = x - (float)i0;
    const float a = g->ab[i0][0] + t * (g->ab[i0 + 1][0] - g->ab[i0][0]);
    const float b = g->ab[i0][1] + t * (g->ab[i0 + 1][1] - g->ab[i0][1]);
    for (int k = 0; k < 3; ++k) out[k] = g->f0[k] * a + b;
}

void glow__render_lobe_setup(glow__render_lobe *s, const glow__render_ggx *g, const float ns[3], const float ng[3],
                             const float wo[3], const float rho[3]) {
    memset(s, 0, sizeof *s);
    memcpy(s->ns, ns, sizeof s->ns);
    memcpy(s->ng, ng, sizeof s->ng);
    memcpy(s->wo, wo, sizeof s->wo);
    memcpy(s->rho, rho, sizeof s->rho);
    s->cos_o = dot3(ns, wo);
    if (!g || !(g->alpha > 0.0f) || !(s->cos_o > 1e-6f)) return;
    s->g = g;
    glow__render_ggx_albedo(g, s->cos_o, s->e_o);
    /* pick the lobes by their albedo at this view, E for the GGX lobe, ρ (1 - E) for the diffuse one,
     * kept within [0.25, 0.9] so that f cos / pdf stays bounded (f_s cos / pdf_s = F G1(i) <= 1 and
     * f_d cos / pdf_d <= ρ / (1 - Ē), each divided by its share >= 0.25) */
    float fs = 0.0f, fd = 0.0f;
    for (int k = 0; k < 3; ++k) {
        fs = fmaxf(fs, s->e_o[k]);
        fd = fmaxf(fd, rho[k] * (1.0f - s->e_o[k]));
    }
    s->p_spec = fminf(fmaxf(fs + fd > 0.0f ? fs / (fs + fd) : 0.5f, 0.25f), 0.9f);
}

float glow__render_lobe_eval(const glow__render_lobe *s, const float wi[3], float fd[3], float fs[3]) {
    const float ci = dot3(s->ns, wi);
    for (int k = 0; k < 3; ++k) fd[k] = fs[k] = 0.0f;
    if (!(ci > 0.0f) || !s->g) return 0.0f;
    const glow__render_ggx *g = s->g;
    const float a2 = g->alpha * g->alpha, co = s->cos_o;
    float h[3] = {s->wo[0] + wi[0], s->wo[1] + wi[1], s->wo[2] + wi[2]};
    float pdf_s = 0.0f;
    if (norm3(h) > 0.0f) {
        const float ch = dot3(s->ns, h), oh = fmaxf(dot3(s->wo, h), 0.0f);
        if (ch > 0.0f) {
            const float d = ggx_d(a2, ch), g1o = ggx_g1(a2, co);
            const float x = 1.0f - oh, x5 = x * x * x * x * x;
            const float common = d * g1o * ggx_g1(a2, ci) / (4.0f * co); /* D G / (4 cos_o cos_i) · cos_i */
            for (int k = 0; k < 3; ++k) fs[k] = common * (g->f0[k] + (1.0f - g->f0[k]) * x5);
            pdf_s = d * g1o / (4.0f * co); /* visible normals: D_o(h) / (4 o·h), D_o(h) = G1(o) (o·h) D(h) / cos_o */
        }
    }
    float e_i[3];
    glow__render_ggx_albedo(g, ci, e_i);
    for (int k = 0; k < 3; ++k)
        fd[k] = s->rho[k] * INV_PI_F * ci * (1.0f - s->e_o[k]) * (1.0f - e_i[k]) / fmaxf(1.0f - g->e_mean[k], 1e-6f);
    return s->p_spec * pdf_s + (1.0f - s->p_spec) * ci * INV_PI_F;
}

/* Heitz 2018, "Sampling the GGX distribution of visible normals": a half vector h ~ D_o(h) around n
 * (frame t, b, n) for the view o; u1, u2 in [0, 1). */
static void ggx_sample_vndf(const float n[3], const float t[3], const float b[3], const float o[3], float alpha, float u1,
                            float u2, float h[3]) {
    const float ol[3] = {dot3(o, t), dot3(o, b), dot3(o, n)};
    float vh[3] = {alpha * ol[0], alpha * ol[1], ol[2]};
    norm3(vh);
    const float lensq = vh[0] * vh[0] + vh[1] * vh[1];
    float t1[3] = {1.0f, 0.0f, 0.0f}, t2[3];
    if (lensq > 0.0f) {
        const float il = 1.0f / sqrtf(lensq);
        t1[0] = -vh[1] * il;
        t1[1] = vh[0] * il;
        t1[2] = 0.0f;
    }
    cross3(vh, t1, t2);
    const float r = sqrtf(u1), phi = 2.0f * PI_F * u2;
    const float p1 = r * cosf(phi), sv = 0.5f * (1.0f + vh[2]);
    const float p2 = (1.0f - sv) * sqrtf(fmaxf(0.0f, 1.0f - p1 * p1)) + sv * r * sinf(phi);
    const float pz = sqrtf(fmaxf(0.0f, 1.0f - p1 * p1 - p2 * p2));
    float nh[3];
    for (int k = 0; k < 3; ++k) nh[k] = p1 * t1[k] + p2 * t2[k] + pz * vh[k];
    const float hl[3] = {alpha * nh[0], alpha * nh[1], fmaxf(nh[2], 0.0f)};
    for (int k = 0; k < 3; ++k) h[k] = hl[0] * t[k] + hl[1] * b[k] + hl[2] * n[k];
    norm3(h);
}

bool glow__render_lobe_sample(const glow__render_lobe *s, float r1, float r2, float wi[3], float w[3], float ws[3],
                              float *pdf) {
    for (int k = 0; k < 3; ++k) w[k] = ws[k] = 0.0f;
    *pdf = 0.0f;
    if (!s->g) return false;
    if (r1 < s->p_spec) {
        float t[3], b[3], h[3];
        glow__render_onb(s->ns, t, b);
        ggx_sample_vndf(s->ns, t, b, s->wo, s->g->alpha, r1 / s->p_spec, r2, h);
        const float oh = dot3(s->wo, h);
        for (int k = 0; k < 3; ++k) wi[k] = 2.0f * oh * h[k] - s->wo[k];
        norm3(wi);
    } else {
        glow__render_sample_cosine(s->ns, fminf((r1 - s->p_spec) / (1.0f - s->p_spec), 0x1.fffffep-1f), r2, wi);
    }
    if (!(dot3(s->ns, wi) > 0.0f) || dot3(s->ng, wi) <= 0.0f) return false;
    float fd[3], fs[3];
    const float p = glow__render_lobe_eval(s, wi, fd, fs);
    if (!(p > 0.0f) || !isfinite(p)) return false;
    for (int k = 0; k < 3; ++k) {
        w[k] = (fd[k] + fs[k]) / p;
        ws[k] = fs[k] / p;
    }
    *pdf = p;
    return true;
}
