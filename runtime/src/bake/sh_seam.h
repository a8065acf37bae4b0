/* sh_seam.h — the SH helpers the linker shares with the runtime (implemented in runtime/src/sh.c), so
 * that cone factors and lobe convolutions come from one recurrence. With bake_format.h, the only
 * private runtime headers the linker may include: precompute's include path holds runtime/src/bake
 * and nothing else of the runtime (docs/architecture.md). */
#ifndef GLOW_SH_SEAM_H
#define GLOW_SH_SEAM_H

#include <stdint.h>

/* Legendre polynomials P_0..P_n at x into p[0..n] (n <= 9), in double. */
void glow__legendre_all(uint32_t n, double x, double *p);
/* Cone factor k_l from 1 - cos α directly, in double (no rounding of cos α to float first). */
double glow__cone_factor_omc(uint32_t l, double one_minus_cos);

#endif /* GLOW_SH_SEAM_H */
