/* host_log.h — the logging and clock helpers of the CPU hosts (host.c) and the GPU lights
 * (../gl_lights/gl_lights.c): one copy instead of one per file. Not installed. */
#ifndef GLOW_HOST_LOG_H
#define GLOW_HOST_LOG_H

#include <stdarg.h>
#include <stdio.h>
#include <time.h>

#include "glow/glow.h"

/* Formats "prefix" + fmt and hands it to the logger (nothing without one); returns `code`, so a
 * failing path can `return glow__host_log(...)`. file/line are the caller's (the macros below). */
#if defined(__GNUC__)
__attribute__((format(printf, 7, 8)))
#endif
static inline glow_result glow__host_log(const glow_logger *lg, const char *prefix, glow_log_level level,
                                         glow_result code, const char *file, int line, const char *fmt, ...) {
    if (lg && lg->log) {
        char text[4096];
        int n = snprintf(text, sizeof text, "%s", prefix);
        if (n < 0 || (size_t)n >= sizeof text) n = 0;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
        va_end(ap);
        lg->log(lg->user, level, code, text, file, line);
    }
    return code;
}

static inline double glow__host_now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

#endif /* GLOW_HOST_LOG_H */
