#include "glow/glow_precompute.h"
int glow_compile_test_glow_precompute_h_c(void);
int glow_compile_test_glow_precompute_h_c(void) { glow_pc_settings s = {0}; return (int)s.quality; }
