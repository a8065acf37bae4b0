/* Public headers compile alone as C11 (STYLE §2.11 habit 4). */
#include "glow/glow.h"
int glow_compile_test_glow_h_c(void);
int glow_compile_test_glow_h_c(void) { return (int)GLOW_ERROR_TRUNCATED; }
float glow_compile_test_params_c(void);
float glow_compile_test_params_c(void) {
    glow_system_params p = GLOW_SYSTEM_PARAMS_INIT;
    return p.bounce_intensity + p.emission_scale + (float)p.bounce_iterations;
}
