/* glow_cli.h — the small command-line helpers every tool of tools/ shares: strict number parsing
 * (the whole argument, no sign where none is allowed, in range, finite), medians, and the usage-error
 * convention (exit status 2 with "TOOL: problem" and a pointer to --help). Header-only, for this
 * repository's tools (not part of the SDK). glow-bake (precompute/tool) keeps its own few lines: it
 * sits a floor below tools/ (docs/architecture.md). */
#ifndef GLOW_CLI_H
#define GLOW_CLI_H

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "glow/glow.h"

/* An unsigned integer in [lo, hi]: digits only (no sign, no spaces, nothing after). */
static inline int glow_cli_u64(const char *s, uint64_t lo, uint64_t hi, uint64_t *out) {
    if (!s || *s < '0' || *s > '9') return 0;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (*end || errno || v < lo || v > hi) return 0;
    *out = (uint64_t)v;
    return 1;
}
static inline int glow_cli_u32(const char *s, uint32_t lo, uint32_t hi, uint32_t *out) {
    uint64_t v;
    if (!glow_cli_u64(s, lo, hi, &v)) return 0;
    *out = (uint32_t)v;
    return 1;
}
/* A finite number (the whole argument). */
static inline int glow_cli_double(const char *s, double *out) {
    if (!s || !*s) return 0;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (*end || errno || !isfinite(v)) return 0;
    *out = v;
    return 1;
}
/* ... that a float holds (|v| <= FLT_MAX). */
static inline int glow_cli_float(const char *s, float *out) {
    double v;
    if (!glow_cli_double(s, &v) || fabs(v) > FLT_MAX) return 0;
    *out = (float)v;
    return 1;
}

static inline int glow_cli_cmp_double(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
/* Median of v[0..n) (sorts v in place); NaN for n == 0. */
static inline double glow_cli_median(double *v, size_t n) {
    if (n == 0) return NAN;
    qsort(v, n, sizeof *v, glow_cli_cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* "TOOL: problem" and "(see TOOL --help)" on stderr; returns 2, the tools' usage-error status. */
static inline int glow_cli_usage_error(const char *tool, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static inline int glow_cli_usage_error(const char *tool, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "%s: ", tool);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\n(see %s --help)\n", tool);
    va_end(ap);
    return 2;
}

/* The tools' runtime logger: "TOOL: error: message (GLOW_ERROR_...)" always, warnings unless quiet,
 * nothing else. glow_cli_logger(&state) gives the glow_logger; state must outlive the context. */
typedef struct glow_cli_log {
    const char *tool;
    int quiet; /* 1: errors only */
} glow_cli_log;
static inline void glow_cli_log_fn(void *user, glow_log_level level, glow_result code, const char *msg, const char *file,
                                   int line) {
    (void)file;
    (void)line;
    const glow_cli_log *l = user;
    if (level == GLOW_LOG_ERROR || (level == GLOW_LOG_WARNING && !l->quiet))
        fprintf(stderr, "%s: %s: %s (%s)\n", l->tool, level == GLOW_LOG_ERROR ? "error" : "warning", msg,
                glow_result_string(code));
}
static inline glow_logger glow_cli_logger(glow_cli_log *state) { return (glow_logger){glow_cli_log_fn, state}; }

#endif /* GLOW_CLI_H */
