/* Public headers compile alone as C11 (STYLE §2.11 habit 4). */
#include "glow/glow_scene.h"
int glow_compile_test_glow_scene_c(void);
int glow_compile_test_glow_scene_c(void) { return (int)GLOW_OK; }
