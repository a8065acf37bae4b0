/* log.c — the linker's message sink: one formatted line per event, to the host's callback. */
#include <stdarg.h>
#include <stdio.h>

#include "pc_internal.h"

static void emit(glow__log *log, glow_log_level level, const char *fmt, va_list ap) {
    char buf[1024];
    vsnprintf(buf, sizeof buf, fmt, ap);
    if (!log) return;
    if (level == GLOW_LOG_ERROR) snprintf(log->last_error, sizeof log->last_error, "%s", buf);
    if (level == GLOW_LOG_WARNING) log->warning_count++;
    if (log->fn) log->fn(log->user, level, buf);
}

void glow__errorf(glow__log *log, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    emit(log, GLOW_LOG_ERROR, fmt, ap);
    va_end(ap);
}

void glow__warnf(glow__log *log, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    emit(log, GLOW_LOG_WARNING, fmt, ap);
    va_end(ap);
}

void glow__infof(glow__log *log, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    emit(log, GLOW_LOG_INFO, fmt, ap);
    va_end(ap);
}
