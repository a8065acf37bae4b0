/* sh_math.c — real orthonormal spherical harmonics and cone factors for the linker.
 * Convention (DESIGN §3): l bands -> l*l coefficients, index k*k + k + m, the usual real basis
 * y_k^m = sqrt(2) K_k^|m| P_k^|m|(cos t) {cos(m phi) | sin(|m| phi)} with the Condon-Shortley phase
 * left out, so y_1^{-1} = c*y, y_1^0 = c*z, y_1^1 = c*x with c = sqrt(3/(4 pi)). */
#include <math.h>

#include "pc_internal.h"
#include "sh_seam.h"

/* The runtime's basis evaluation (DESIGN §3: one routine shared by every caller). */
void glow__sh_eval(uint32_t bands, const float dir[3], float *out) { glow_sh_eval(bands, dir, out); }

double glow__cone_factor(uint32_t l, double x) { return glow__cone_factor_omc(l, 1.0 - x); }
