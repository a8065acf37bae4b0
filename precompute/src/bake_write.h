/*
 * bake_write.h — the bake container writer (runtime/src/bake/bake_format.h). It knows the
 * container only (header, section table, alignment, CRCs); the pipeline builds each section's
 * payload and hands them over in the order they should appear in the file.
 */
#ifndef GLOW_BAKE_WRITE_H
#define GLOW_BAKE_WRITE_H

#include <stdint.h>

#include "bake_format.h"
#include "pc_internal.h"

typedef struct glow__section_data {
    uint32_t fourcc;  /* GLOW_SECTION_*; each at most once */
    uint32_t version; /* per-section layout version (1) */
    const void *data; /* may be NULL only when size == 0 */
    uint64_t size;    /* payload bytes */
} glow__section_data;

/* Builds the complete file image: 64-byte header, the section table, then each payload at the
 * next 64-byte aligned offset in the given order, zero padding in between (the image ends right
 * after the last payload), all CRC-32s filled in. Deterministic: the same sections give the same
 * bytes. *out_data is malloc'ed (free() it).
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL outputs, count > GLOW_BAKE_MAX_SECTIONS,
 * duplicate fourcc, NULL data with size > 0, overflow); GLOW_ERROR_OUT_OF_MEMORY;
 * GLOW_ERROR_UNSUPPORTED on a big-endian host. */
glow_result glow__bake_write_memory(const glow__section_data *sections, uint32_t count, void **out_data,
                                    uint64_t *out_size);

/* Before the work (issue 15, D7/D8/D9): can `path` be written as the writer will (a temporary file
 * beside it, created and removed again), and is it not the same file as `input` (the scene the bake
 * reads; NULL or a built-in name skips that check)? Logs the path and the reason. Also removes the
 * temporaries "<path>.tmp.<pid>" of earlier writers that were killed (their pid is gone).
 * \returns GLOW_OK; GLOW_ERROR_IO when the folder cannot take the file; GLOW_ERROR_INVALID_ARGUMENT
 * when path names the input. */
glow_result glow__bake_write_check(const char *path, const char *input, glow__log *log);

/* Writes the image of glow__bake_write_memory to `path` atomically: the bytes go to
 * "<path>.tmp.<pid>" in the same directory (fwrite, fflush, fsync, fclose, every return checked),
 * which is then rename()d over `path`. On any failure the temporary file is removed, an existing
 * file at `path` is left untouched, an error "PATH: <what> failed: <strerror>" is logged and
 * GLOW_ERROR_IO returned (errors of glow__bake_write_memory are passed through).
 * out_size (may be NULL) receives the file size on success.
 *
 * Test hook: when the environment variable GLOW_TEST_WRITE_FAIL_AFTER=N is set (N a decimal byte
 * count), the write behaves as if the disk filled up after N bytes of the temporary file: the
 * failure path runs with errno = ENOSPC ("PATH: write failed: No space left on device"). */
glow_result glow__bake_write_file(const char *path, const glow__section_data *sections, uint32_t count,
                                  glow__log *log, uint64_t *out_size);

#endif /* GLOW_BAKE_WRITE_H */
