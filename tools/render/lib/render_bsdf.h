/* render_bsdf.h — glow-render's surface model with a GGX layer (scene "materials", docs/glossy.md):
 *   f(o, i) = ρ/π (1 - E(cos θ_o)) (1 - E(cos θ_i)) / (1 - Ē) + D(h) G1(o) G1(i) F(o·h) / (4 cos θ_o cos θ_i),
 * per channel, with the conventions of runtime/src/ggx.c: α = roughness² (glTF), D = GGX
 * (Trowbridge-Reitz), separable Smith G, Schlick F with F0 = the scene's "specular"; E(μ) = F0 A(μ) + B(μ)
 * the GGX layer's directional albedo (glow_ggx_specular_albedo) and Ē = 2 ∫ E(μ) μ dμ its cosine-weighted
 * mean. The diffuse layer gets the energy the GGX layer leaves (Kelemen & Szirmay-Kalos 2001): its albedo
 * at cos θ_o is exactly ρ (1 - E(cos θ_o)), so the total is ρ + (1 - ρ) E <= 1. Symmetric in o and i
 * (reciprocal) and non-negative. Sampled as a mixture of the GGX visible normals (Heitz 2018) and the
 * cosine lobe. Not installed; tests/eval/test_render_glossy.c checks it. */
#ifndef GLOW_RENDER_BSDF_H
#define GLOW_RENDER_BSDF_H

#include <stdbool.h>

#define GLOW__RENDER_GGX_TABLE 33 /* A, B at sqrt(cos θ) = 0, 1/32, ..., 1 (dense at grazing, where E
                                     changes fastest), linear in sqrt(cos θ) in between */

/* A material's GGX layer. */
typedef struct glow__render_ggx {
    float roughness;  /* perceptual (scene file), (0, 1]; 0 = no layer */
    float alpha;      /* roughness² */
    float f0[3];      /* Schlick's F0 (the scene's "specular") */
    float ab[GLOW__RENDER_GGX_TABLE][2]; /* glow_ggx_specular_albedo(cos θ, roughness) */
    float e_mean[3];  /* Ē per channel, of the interpolated table */
} glow__render_ggx;

/* Fills g from roughness and F0 (the tables: about 2 M evaluations). */
void glow__render_ggx_init(glow__render_ggx *g, float roughness, const float f0[3]);
/* E(cos θ) = F0 A + B per channel, from the table. */
void glow__render_ggx_albedo(const glow__render_ggx *g, float cos_theta, float out[3]);

/* A surface point with a GGX layer, seen from wo. */
typedef struct glow__render_lobe {
    const glow__render_ggx *g; /* NULL: no layer (or a view below the shading hemisphere: Lambertian) */
    float ns[3], ng[3];        /* unit shading and geometric normals, on the viewer's side */
    float wo[3];               /* unit, towards the viewer */
    float rho[3];              /* diffuse albedo */
    float cos_o;               /* ns·wo > 0 */
    float e_o[3];              /* E(cos_o) */
    float p_spec;              /* the probability that glow__render_lobe_sample picks the GGX lobe */
} glow__render_lobe;

/* Fills *lobe; lobe->g stays NULL (shade as Lambertian) when ns·wo <= 1e-6. */
void glow__render_lobe_setup(glow__render_lobe *lobe, const glow__render_ggx *g, const float ns[3], const float ng[3],
                             const float wo[3], const float rho[3]);
/* f(o, wi) cos θ_i split into the diffuse part fd and the GGX part fs (RGB); returns the solid-angle
 * pdf with which glow__render_lobe_sample draws wi (0 below the shading hemisphere). */
float glow__render_lobe_eval(const glow__render_lobe *lobe, const float wi[3], float fd[3], float fs[3]);
/* Draws wi from p_spec · (GGX visible normals) + (1 - p_spec) · (cosine lobe), r1 choosing the lobe
 * and then reused. Out: w = f cos / pdf (RGB), ws = its GGX part, *pdf. Returns false (weights 0)
 * when wi falls below the shading or the geometric surface. */
bool glow__render_lobe_sample(const glow__render_lobe *lobe, float r1, float r2, float wi[3], float w[3], float ws[3],
                              float *pdf);

/* Orthonormal basis around unit n (Duff et al. 2017). */
void glow__render_onb(const float n[3], float t[3], float b[3]);
/* Cosine-weighted direction around unit n; returns cos θ (pdf = cos θ / π). */
float glow__render_sample_cosine(const float n[3], float r1, float r2, float out[3]);

#endif /* GLOW_RENDER_BSDF_H */
