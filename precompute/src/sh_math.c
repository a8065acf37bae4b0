/* sh_math.c — real orthonormal spherical harmonics and cone factors for the linker.
 * Convention (DESIGN §3): l bands -> l*l coefficients, index k*k + k + m, the usual real basis
 * y_k^m = sqrt(2) K_k^|m| P_k^|m|(cos t) {cos(m phi) | sin(|m| phi)} with the Condon-Shortley phase
 * left out, so y_1^{-1} = c*y, y_1^0 = c*z, y_1^1 = c*x with c = sqrt(3/(4 pi)). */
#include <math.h>

#include "pc_internal.h"

void glow__sh_eval(uint32_t bands, const float dir[3], float *out) {
    double x = dir[0], y = dir[1], z = dir[2];
    /* associated Legendre P_l^m(z) (no Condon-Shortley phase) by the standard recurrences, and
     * cos/sin(m phi) * sin^m(theta) as (x + iy)^m. */
    double cm[9], sm[9];
    cm[0] = 1.0; sm[0] = 0.0;
    for (uint32_t m = 1; m < bands; ++m) {
        cm[m] = cm[m - 1] * x - sm[m - 1] * y;
        sm[m] = sm[m - 1] * x + cm[m - 1] * y;
    }
    /* P_l^m without the sin^m factor (it is inside cm/sm): Q_m^m = (2m-1)!!, Q_{m+1}^m = z(2m+1)Q_m^m,
     * Q_l^m = ((2l-1) z Q_{l-1}^m - (l+m-1) Q_{l-2}^m)/(l-m). */
    for (uint32_t m = 0; m < bands; ++m) {
        double qmm = 1.0;
        for (uint32_t i = 1; i <= m; ++i) qmm *= (double)(2 * i - 1);
        double q_prev = 0.0, q = qmm;
        for (uint32_t l = m; l < bands; ++l) {
            if (l == m + 1) {
                q_prev = q;
                q = z * (2.0 * m + 1.0) * qmm;
            } else if (l > m + 1) {
                double qn = ((2.0 * l - 1.0) * z * q - (double)(l + m - 1) * q_prev) / (double)(l - m);
                q_prev = q;
                q = qn;
            }
            /* K_l^m = sqrt((2l+1)/(4pi) * (l-m)!/(l+m)!) */
            double ratio = 1.0;
            for (uint32_t i = l - m + 1; i <= l + m; ++i) ratio /= (double)i;
            double k = sqrt((2.0 * l + 1.0) / (4.0 * GLOW__PI) * ratio);
            if (m == 0) {
                out[l * l + l] = (float)(k * q);
            } else {
                out[l * l + l + m] = (float)(sqrt(2.0) * k * q * cm[m]);
                out[l * l + l - m] = (float)(sqrt(2.0) * k * q * sm[m]);
            }
        }
    }
}

static double legendre(uint32_t l, double x) {
    if (l == 0) return 1.0;
    double p0 = 1.0, p1 = x;
    for (uint32_t k = 2; k <= l; ++k) {
        double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / (double)k;
        p0 = p1;
        p1 = p2;
    }
    return p1;
}

double glow__cone_factor(uint32_t l, double x) {
    if (l == 0) return 2.0 * GLOW__PI * (1.0 - x);
    return 2.0 * GLOW__PI / (2.0 * l + 1.0) * (legendre(l - 1, x) - legendre(l + 1, x));
}
