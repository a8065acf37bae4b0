/* Public headers compile alone as C11 (STYLE §2.11 habit 4). */
#include "glow/glow_gl_loader.h"
int glow_compile_test_glow_gl_loader_c(void);
int glow_compile_test_glow_gl_loader_c(void) { return 0; }
