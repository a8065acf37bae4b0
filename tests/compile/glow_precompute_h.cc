#include "glow/glow_precompute.h"
int glow_compile_test_glow_precompute_h_cc() { glow_pc_settings s = {}; return (int)s.quality; }
