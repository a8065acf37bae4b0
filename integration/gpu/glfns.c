/* glfns.c — glow_glfns_load (glow_glfns.h). */
#include <stdio.h>
#include <string.h>

#include "glow/glow_glfns.h"

int glow_glfns_load(glow_glfns *fns, glow_gl_loader load, char *missing, size_t missing_size) {
    if (missing && missing_size) missing[0] = '\0';
    if (!fns || !load) {
        if (missing && missing_size) snprintf(missing, missing_size, "no loader");
        return 0;
    }
    memset(fns, 0, sizeof *fns);
    int ok = 1;
    size_t used = 0;
#define GLOW__GLFN_LOAD(type, name)                                                                   \
    {                                                                                                  \
        glow_gl_proc p = load("gl" #name);                                                             \
        if (!p) {                                                                                      \
            ok = 0;                                                                                    \
            if (missing && used + 1 < missing_size) {                                                  \
                int n = snprintf(missing + used, missing_size - used, "%sgl%s", used ? " " : "", #name); \
                if (n > 0) used += (size_t)n < missing_size - used ? (size_t)n : missing_size - used - 1; \
            }                                                                                          \
        }                                                                                              \
        memcpy(&fns->name, &p, sizeof p); /* function-pointer to function-pointer: one representation */ \
    }
    GLOW_GLFNS_LIST(GLOW__GLFN_LOAD)
#undef GLOW__GLFN_LOAD
    return ok;
}
