// Public headers compile alone as C++ (STYLE §2.11 habit 4): one TU per header, included first.
#include "glow/glow_gl_loader.h"
int glow_compile_test_glow_gl_loader_cc() { return 0; }
