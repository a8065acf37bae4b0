/* render_bsdf.h — glow-render's surface model with a GGX layer (scene "materials", docs/glossy.md):
 *   f(o, i) = kd ρ/π + D(h) G1(o) G1(i) F(o·h) / (4 cos θ_o cos θ_i),
 * the conventions of runtime/src/ggx.c: α = roughness² (glTF), D = GGX (Trowbridge-Reitz), separable
 * Smith G, Schlick F with F0 = the scene's "specular", kd = 1 - max F0. Symmetric in o and i
 * (reciprocal) and non-negative. Sampled as a mixture of the GGX visible normals (Heitz 2018) and the
 * cosine lobe. Not installed; tests/eval/test_render_glossy.c checks it. */
#ifndef GLOW_RENDER_BSDF_H
#define GLOW_RENDER_BSDF_H

#include <stdbool.h>

/* A material's GGX layer. */
typedef struct glow__render_ggx {
    float roughness;  /* perceptual (scene file), (0, 1]; 0 = no layer */
    float alpha;      /* roughness² */
    float f0[3];      /* Schlick's F0 (the scene's "specular") */
    float kd;         /* 1 - max(f0): the diffuse layer's weight */
} glow__render_ggx;

/* A surface point with a GGX layer, seen from wo. */
typedef struct glow__render_lobe {
    const glow__render_ggx *g; /* NULL: no layer (or a view below the shading hemisphere: Lambertian) */
    float ns[3], ng[3];        /* unit shading and geometric normals, on the viewer's side */
    float wo[3];               /* unit, towards the viewer */
    float rho[3];              /* diffuse albedo */
    float cos_o;               /* ns·wo > 0 */
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
