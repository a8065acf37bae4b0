// Public headers compile alone as C++ (STYLE §2.11 habit 4): one TU per header, included first.
#include "glow/glow.h"
static_assert(GLOW_OK == 0, "GLOW_OK is zero");
int glow_compile_test_glow_h_cc() { return (int)GLOW_ERROR_TRUNCATED; }
// GLOW_SYSTEM_PARAMS_INIT is an initialiser C++ accepts too
float glow_compile_test_params_cc() {
    glow_system_params p = GLOW_SYSTEM_PARAMS_INIT;
    return p.bounce_intensity + p.emission_scale + (float)p.bounce_iterations;
}
