/* cone_fit.c — irradiance-preserving cone fit (runtime projection, PIC 4.6).
 *
 * A link stands for a cluster of leaves by a cone with the cluster's visible solid angle ω around
 * its mean direction. A cone is the most compact shape of that solid angle, so its first moment
 * ω (1 + cos α)/2 exceeds the cluster's |Σ ω_i d_i| whenever the cluster is spread out; for a
 * lightmap cache that means too much irradiance (measured: +2.2 % of π in the closed furnace cube,
 * which multi-bounce amplifies to +22 % radiosity at albedo 0.9). For lightmap caches — whose SH is
 * used with the cosine lobe around their normal — the linker therefore picks the cone's 1 - cos α so
 * that the cone's diffuse response at the cache normal, with the bake's band count, equals the
 * cluster's exact cosine-weighted response Σ ω_i max(0, d_i·n)/π; the direction stays the cluster's
 * mean direction. The target is the exact cosine, not the band-limited kernel K_L: K_L overstates
 * light near a cache's horizon (K_3(0.1) is 2.4x the cosine's 0.1/π), and a bright source there (the
 * Cornell box's lamp seen edge-on from the tall block's front face) read +22 % with K_L as the
 * target; the fit shrinks such cones until their truncated response is the true one. Grid caches keep
 * ω (their use is any direction, and ω is what the l = 0 band needs). */
#include <math.h>

#include "cone_fit.h"
#include "glow/glow.h" /* glow_sh_lobe_factor */
#include "sh_seam.h"

#define PI_D 3.14159265358979323846

static double lobe(uint32_t l) { return glow_sh_lobe_factor(l, 1.0f); } /* s_l of the cosine lobe */

double glow__cos_kernel(double t) { return t > 0.0 ? t / PI_D : 0.0; }

double glow__cone_irr(uint32_t L, double omc, double t) {
    double px[11], pt[10];
    if (L > 8) L = 8;
    glow__legendre_all(L + 1, 1.0 - omc, px);
    glow__legendre_all(L, t, pt);
    double r = 0.0;
    for (uint32_t l = 0; l < L; ++l) {
        double kl = l == 0 ? 2.0 * PI_D * omc : 2.0 * PI_D / (2.0 * l + 1.0) * (px[l - 1] - px[l + 1]);
        r += lobe(l) * kl * (2.0 * l + 1.0) / (4.0 * PI_D) * pt[l];
    }
    return r;
}

float glow__cone_fit_omc(uint32_t L, float omc, double t, double target) {
    if (!(omc > 0.0f) || L == 0 || !(target >= 0.0)) return omc;
    if (target == 0.0) return 0.0f; /* every leaf at or below the horizon: no light, where K_L gave some */
    double lo = 1e-3 * omc, hi = 4.0 * omc; /* lo: a grazing cluster shrinks a lot (above) */
    if (hi > 2.0) hi = 2.0;
    double flo = glow__cone_irr(L, lo, t) - target, fhi = glow__cone_irr(L, hi, t) - target;
    if (flo > 0.0) return (float)lo; /* a sliver above the horizon: the smallest cone tried */
    if (!(fhi >= 0.0)) return omc;
    for (int it = 0; it < 40; ++it) {
        double mid = 0.5 * (lo + hi), fm = glow__cone_irr(L, mid, t) - target;
        if (fm < 0.0) lo = mid; else hi = mid;
    }
    return (float)(0.5 * (lo + hi));
}
