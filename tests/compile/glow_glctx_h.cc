// Public headers compile alone as C++ (STYLE §2.11 habit 4): one TU per header, included first.
#include "glow/glow_glctx.h"
int glow_compile_test_glow_glctx_cc() { return 0; }
