/*
 * glow_sh.glsl — spherical harmonics for Glow's kernels and for hosts' material shaders: the same maths
 * as the runtime's C (glow.h: glow_sh_eval, glow_sh_cone_factor, glow_sh_lobe_factor, glow_rgb_to_ycocg).
 *
 * Convention (DESIGN §3): real orthonormal SH, l bands -> l² values, index k² + k + m, no Condon-Shortley
 * phase: y_1 = sqrt(3/4π) (y, z, x). Evaluated with the associated-Legendre recurrence in sin^m-free form,
 * the same recurrence and constants as runtime/src/sh_kernel.h (tests/gpu compares the table).
 *
 * USAGE (GLSL 4.50)
 *   #define GLOW_SH_MAX_BANDS 3          (optional, default 8: sizes the y[] arrays below)
 *   #include "glow_sh.glsl"
 *   float y[GLOW_SH_MAX_BANDS * GLOW_SH_MAX_BANDS]; glow_sh_eval(3, dir, y);
 */
#ifndef GLOW_SH_GLSL
#define GLOW_SH_GLSL

#ifndef GLOW_SH_MAX_BANDS
#define GLOW_SH_MAX_BANDS 8
#endif
#define GLOW_PI 3.14159265358979323846

/* K_l^|m| (times sqrt 2 for m != 0), index l*l + l + m: runtime/src/sh_kernel.h glow__sh_k */
const float glow_sh_k[64] = float[64](
    2.820947918e-01, 4.886025119e-01, 4.886025119e-01, 4.886025119e-01,
    1.820914051e-01, 3.641828102e-01, 6.307831305e-01, 3.641828102e-01,
    1.820914051e-01, 3.933623933e-02, 9.635371475e-02, 3.046971996e-01,
    7.463526652e-01, 3.046971996e-01, 9.635371475e-02, 3.933623933e-02,
    5.960340338e-03, 1.685838828e-02, 6.307831305e-02, 2.676186174e-01,
    8.462843753e-01, 2.676186174e-01, 6.307831305e-02, 1.685838828e-02,
    5.960340338e-03, 6.945841871e-04, 2.196468058e-03, 9.318824751e-03,
    4.565273129e-02, 2.415715473e-01, 9.356025796e-01, 2.415715473e-01,
    4.565273129e-02, 9.318824751e-03, 2.196468058e-03, 6.945841871e-04,
    6.572237664e-05, 2.276689911e-04, 1.067862224e-03, 5.848922283e-03,
    3.509353370e-02, 2.219509952e-01, 1.017107236e+00, 2.219509952e-01,
    3.509353370e-02, 5.848922283e-03, 1.067862224e-03, 2.276689911e-04,
    6.572237664e-05, 5.233009454e-06, 1.958012848e-05, 9.983945719e-05,
    5.990367431e-04, 3.973560225e-03, 2.809731381e-02, 2.064722459e-01,
    1.092548431e+00, 2.064722459e-01, 2.809731381e-02, 3.973560225e-03,
    5.990367431e-04, 9.983945719e-05, 1.958012848e-05, 5.233009454e-06);

/** y[k] = y_k(d) for k < bands² (bands <= GLOW_SH_MAX_BANDS); d unit length. */
void glow_sh_eval(int bands, vec3 d, out float y[GLOW_SH_MAX_BANDS * GLOW_SH_MAX_BANDS]) {
    float cm = 1.0, sm = 0.0, qmm = 1.0;
    for (int m = 0; m < bands; ++m) {
        if (m > 0) {
            float c = cm * d.x - sm * d.y;
            sm = sm * d.x + cm * d.y;
            cm = c;
            qmm *= float(2 * m - 1);
        }
        float q_prev = 0.0, q = qmm;
        for (int l = m; l < bands; ++l) {
            if (l == m + 1) {
                q_prev = q;
                q = d.z * (float(2 * m + 1) * qmm);
            } else if (l > m + 1) {
                float qn = (d.z * q * float(2 * l - 1) - q_prev * float(l + m - 1)) * (1.0 / float(l - m));
                q_prev = q;
                q = qn;
            }
            float k = glow_sh_k[l * l + l + m];
            if (m == 0) {
                y[l * l + l] = q * k;
            } else {
                float qk = q * k;
                y[l * l + l + m] = qk * cm;
                y[l * l + l - m] = qk * sm;
            }
        }
    }
}

/** Lobe factor s_l of the normalised Phong lobe of exponent n (PIC App. B): s_0 = 1, s_1 = (n+1)/(n+2),
 * s_l = s_(l-2) (n+2-l)/(n+1+l). n = 1: the diffuse cosine lobe (1, 2/3, 1/4, 0, ...). */
float glow_sh_lobe_factor(int l, float n) {
    float s_even = 1.0, s_odd = (n + 1.0) / (n + 2.0);
    for (int k = 2; k <= l; ++k) {
        if ((k & 1) == 0) s_even *= (n + 2.0 - float(k)) / (n + 1.0 + float(k));
        else s_odd *= (n + 2.0 - float(k)) / (n + 1.0 + float(k));
    }
    return (l & 1) == 0 ? s_even : s_odd;
}

/** YCoCg (PIC Eq. 7): Y = R/4 + G/2 + B/4, Co = R/2 - B/2, Cg = -R/4 + G/2 - B/4. */
vec3 glow_rgb_to_ycocg(vec3 c) {
    return vec3(0.25 * c.r + 0.5 * c.g + 0.25 * c.b, 0.5 * c.r - 0.5 * c.b, -0.25 * c.r + 0.5 * c.g - 0.25 * c.b);
}
vec3 glow_ycocg_to_rgb(vec3 c) {
    return vec3(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

/** 12-bit octahedral direction of a link (runtime glow__oct_decode12): q in [0, 4095] <-> s = q*2/4095 - 1. */
vec3 glow_oct_decode12(uint u, uint v) {
    vec2 s = vec2(float(u & 4095u), float(v & 4095u)) * (2.0 / 4095.0) - 1.0;
    vec3 n = vec3(s, 1.0 - abs(s.x) - abs(s.y));
    float t = max(-n.z, 0.0);
    n.x -= s.x >= 0.0 ? t : -t;
    n.y -= s.y >= 0.0 ? t : -t;
    return normalize(n);
}

#endif /* GLOW_SH_GLSL */
