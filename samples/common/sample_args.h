/* sample_args.h — the command line every sample shares (header-only, all static):
 *   sample-NN_name INPUT [--frames N] [--headless] [--out DIR] [--help]
 * --frames N   frames to run (1..100000; default: the sample's own)
 * --headless   no window (samples that open one render offscreen instead; CPU samples ignore it)
 * --out DIR    write PNGs there (sample_parse_args creates it if missing, one level)
 * Exit statuses of the samples: 0 ok, 1 runtime or file error (the message names the file), 2 usage.
 * Not part of Glow's API. */
#ifndef GLOW_SAMPLE_ARGS_H
#define GLOW_SAMPLE_ARGS_H

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

typedef struct sample_args {
    const char *input;   /* the positional argument (a bake, a scene file) */
    const char *out_dir; /* NULL without --out */
    long frames;
    bool headless;
} sample_args;

/* Creates `dir` (one level) unless it is already a directory. 0 on success, else -1 with errno set. */
static inline int sample_make_dir(const char *dir) {
    struct stat st;
    if (stat(dir, &st) == 0) {
        if (S_ISDIR(st.st_mode)) return 0;
        errno = ENOTDIR;
        return -1;
    }
    return mkdir(dir, 0777) == 0 ? 0 : -1;
}

static inline void sample_usage(FILE *f, const char *argv0, const char *input_name) {
    fprintf(f, "usage: %s %s [--frames N] [--headless] [--out DIR]\n", argv0, input_name);
}

/* Consumes the common option at argv[*i] (and its value, advancing *i). Returns 1 when it took it,
 * 0 when argv[*i] is not a common option (the sample's own, or the positional), 2 after printing why
 * the value is bad. For samples with options of their own: call it first in their loop. */
static inline int sample_arg_common(int argc, char **argv, int *i, sample_args *args) {
    const char *a = argv[*i];
    if (!strcmp(a, "--headless")) return args->headless = true, 1;
    if (strcmp(a, "--frames") && strcmp(a, "--out")) return 0;
    if (*i + 1 >= argc) return fprintf(stderr, "%s: %s needs a value\n", argv[0], a), 2;
    const char *v = argv[++*i];
    if (!strcmp(a, "--out")) return args->out_dir = v, 1;
    char *end;
    args->frames = strtol(v, &end, 10);
    if (end == v || *end || args->frames < 1 || args->frames > 100000)
        return fprintf(stderr, "%s: --frames '%s': wants 1..100000\n", argv[0], v), 2;
    return 1;
}

/* Parses a sample's whole command line (common options and one positional INPUT) and creates the
 * --out directory. Returns -1 to go on, or the status main should exit with: 0 after --help, 2 after
 * a usage message, 1 when the --out directory cannot be made (the message names it). */
static inline int sample_parse_args(int argc, char **argv, const char *input_name, long default_frames,
                                    sample_args *args) {
    *args = (sample_args){.frames = default_frames};
    for (int i = 1; i < argc; i++) {
        int took = sample_arg_common(argc, argv, &i, args);
        if (took == 2) return sample_usage(stderr, argv[0], input_name), 2;
        if (took) continue;
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) return sample_usage(stdout, argv[0], input_name), 0;
        if (argv[i][0] == '-' || args->input) {
            fprintf(stderr, "%s: unexpected argument '%s'\n", argv[0], argv[i]);
            return sample_usage(stderr, argv[0], input_name), 2;
        }
        args->input = argv[i];
    }
    if (!args->input) {
        fprintf(stderr, "%s: no %s given\n", argv[0], input_name);
        return sample_usage(stderr, argv[0], input_name), 2;
    }
    if (args->out_dir && sample_make_dir(args->out_dir) != 0)
        return fprintf(stderr, "%s: %s: %s\n", argv[0], args->out_dir, strerror(errno)), 1;
    return -1;
}

#endif /* GLOW_SAMPLE_ARGS_H */
