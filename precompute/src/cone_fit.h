/* cone_fit.h — irradiance-preserving cone fit for lightmap-cache links (see cone_fit.c). */
#ifndef GLOW_CONE_FIT_H
#define GLOW_CONE_FIT_H
#include <stdint.h>

/* The exact diffuse response per unit solid angle, max(0, t)/π: the fit's target (cone_fit.c). */
double glow__cos_kernel(double t);
/* The L-band diffuse response (E/π per unit radiance) of a cone of 1 - cos α = omc around an axis at
 * cos t to the normal, projected with the cone factors k_l and the cosine-lobe factors s_l:
 * Σ_{l<L} s_l k_l(1 - omc) (2l+1)/(4π) P_l(t). */
double glow__cone_irr(uint32_t bands, double omc, double t);
/* The omc in [omc/1000, min(2, 4 omc)] whose cone response equals `target` (bisection); 0 when the
 * target is 0 (every leaf at or below the horizon), omc/1000 when even that cone responds more,
 * `omc` unchanged when the target is negative, not finite, or beyond the largest cone's response
 * (an implausible target means the cluster is not cone-like). */
float glow__cone_fit_omc(uint32_t bands, float omc, double t, double target);
#endif
