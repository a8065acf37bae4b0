/* bake_write.c — writes the bake container (runtime/src/bake/bake_format.h): header, section
 * table, 64-byte aligned payloads, CRC-32s; and puts it on disk atomically (temp + rename). */
#include "bake_write.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static uint64_t align_up(uint64_t v) { return (v + (GLOW_BAKE_ALIGN - 1u)) & ~(uint64_t)(GLOW_BAKE_ALIGN - 1u); }

glow_result glow__bake_write_memory(const glow__section_data *sections, uint32_t count, void **out_data,
                                    uint64_t *out_size) {
    if (out_data) *out_data = NULL;
    if (out_size) *out_size = 0;
    if (!out_data || !out_size || (count && !sections) || count > GLOW_BAKE_MAX_SECTIONS)
        return GLOW_ERROR_INVALID_ARGUMENT;
    const uint32_t one = 1;
    unsigned char first_byte;
    memcpy(&first_byte, &one, 1);
    if (first_byte != 1) return GLOW_ERROR_UNSUPPORTED; /* the format is little-endian, written by memcpy */

    glow_bake_section table[GLOW_BAKE_MAX_SECTIONS];
    memset(table, 0, sizeof table);
    uint64_t pos = sizeof(glow_bake_header) + (uint64_t)count * sizeof(glow_bake_section);
    for (uint32_t i = 0; i < count; i++) {
        const glow__section_data *s = &sections[i];
        if (!s->data && s->size) return GLOW_ERROR_INVALID_ARGUMENT;
        for (uint32_t j = 0; j < i; j++)
            if (sections[j].fourcc == s->fourcc) return GLOW_ERROR_INVALID_ARGUMENT;
        pos = align_up(pos);
        if (s->size > UINT64_MAX - pos || pos + s->size > (uint64_t)SIZE_MAX) return GLOW_ERROR_INVALID_ARGUMENT;
        table[i].fourcc = s->fourcc;
        table[i].version = s->version;
        table[i].offset = pos;
        table[i].size = s->size;
        table[i].crc32 = glow__crc32(0, s->data, (size_t)s->size);
        pos += s->size;
    }
    uint64_t total = pos;

    unsigned char *img = calloc(1, (size_t)total);
    if (!img) return GLOW_ERROR_OUT_OF_MEMORY;
    memcpy(img + sizeof(glow_bake_header), table, (size_t)count * sizeof(glow_bake_section));
    for (uint32_t i = 0; i < count; i++)
        if (sections[i].size) memcpy(img + table[i].offset, sections[i].data, (size_t)sections[i].size);

    glow_bake_header h;
    memset(&h, 0, sizeof h);
    memcpy(h.magic, GLOW_BAKE_MAGIC, 4);
    h.major = (uint16_t)GLOW_BAKE_FORMAT_VERSION_MAJOR;
    h.minor = (uint16_t)GLOW_BAKE_FORMAT_VERSION_MINOR;
    h.header_size = (uint32_t)sizeof(glow_bake_header);
    h.section_count = count;
    h.file_size = total;
    h.flags = 0;
    h.table_crc32 = glow__crc32(0, img + sizeof(glow_bake_header), (size_t)count * sizeof(glow_bake_section));
    h.header_crc32 = 0;
    h.header_crc32 = glow__crc32(0, &h, sizeof h);
    memcpy(img, &h, sizeof h);

    *out_data = img;
    *out_size = total;
    return GLOW_OK;
}

/* GLOW_TEST_WRITE_FAIL_AFTER (see bake_write.h): bytes allowed before a simulated ENOSPC, or -1. */
static long long fail_after_bytes(void) {
    const char *s = getenv("GLOW_TEST_WRITE_FAIL_AFTER");
    if (!s || !*s) return -1;
    char *end = NULL;
    long long n = strtoll(s, &end, 10);
    return (end && *end == 0 && n >= 0) ? n : -1;
}

/* Best effort: make the rename durable. Failure here does not fail the write. */
static void sync_parent_dir(const char *path) {
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (!slash) {
        snprintf(dir, sizeof dir, ".");
    } else {
        size_t n = (size_t)(slash - path);
        if (n == 0) n = 1; /* "/file" */
        if (n >= sizeof dir) return;
        memcpy(dir, path, n);
        dir[n] = 0;
    }
    int fd = open(dir, O_RDONLY);
    if (fd < 0) return;
    (void)fsync(fd);
    close(fd);
}

/* Removes "<path>.tmp.<pid>[.check]" files left by a writer that was killed (kill -9 or a crash
 * between create and rename; issue 15, D9): only when that process no longer exists on this host
 * (kill(pid, 0) fails with ESRCH), so a bake writing the same output at the same time keeps its
 * file. A folder shared between hosts can hold another host's live temporary: its pid means nothing
 * here, which is why only ESRCH counts and any other doubt keeps the file. */
static void remove_stale_temporaries(const char *path, glow__log *log) {
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    size_t dir_len = slash ? (size_t)(slash - path) : 0;
    char dir[4096];
    if (dir_len >= sizeof dir) return;
    if (slash) {
        memcpy(dir, path, dir_len);
        dir[dir_len] = 0;
        if (dir_len == 0) snprintf(dir, sizeof dir, "/");
    } else {
        snprintf(dir, sizeof dir, ".");
    }
    DIR *d = opendir(dir);
    if (!d) return;
    const size_t bl = strlen(base);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        const char *n = e->d_name;
        if (strncmp(n, base, bl) != 0 || strncmp(n + bl, ".tmp.", 5) != 0) continue;
        const char *q = n + bl + 5;
        char *end = NULL;
        errno = 0;
        long pid = strtol(q, &end, 10);
        if (errno || end == q || pid <= 0 || (*end && strcmp(end, ".check") != 0)) continue;
        if (pid == (long)getpid() || kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;
        char full[4096 + 256];
        snprintf(full, sizeof full, "%s/%s", dir, n);
        if (remove(full) == 0) glow__infof(log, "%s: removed %s, left by a bake that was killed (pid %ld)", path, full, pid);
    }
    closedir(d);
}

glow_result glow__bake_write_check(const char *path, const char *input, glow__log *log) {
    if (!path || !*path) {
        glow__errorf(log, "bake writer: no output path");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    struct stat so, si;
    if (input && stat(path, &so) == 0 && stat(input, &si) == 0 && so.st_dev == si.st_dev && so.st_ino == si.st_ino) {
        glow__errorf(log, "%s: is the scene being baked; refusing to overwrite the input (choose another -o)", path);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (stat(path, &so) == 0 && S_ISDIR(so.st_mode)) {
        glow__errorf(log, "%s: is a directory, not a bake file", path);
        return GLOW_ERROR_IO;
    }
    size_t tmp_len = strlen(path) + 40;
    char *tmp = malloc(tmp_len);
    if (!tmp) {
        glow__errorf(log, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    remove_stale_temporaries(path, log);
    snprintf(tmp, tmp_len, "%s.tmp.%ld.check", path, (long)getpid());
    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL, 0644);
    if (fd < 0) {
        int err = errno;
        glow__errorf(log, "%s: cannot be written (a temporary file beside it fails: %s)", path, strerror(err));
        free(tmp);
        return GLOW_ERROR_IO;
    }
    close(fd);
    remove(tmp);
    free(tmp);
    return GLOW_OK;
}

glow_result glow__bake_write_file(const char *path, const glow__section_data *sections, uint32_t count,
                                  glow__log *log, uint64_t *out_size) {
    if (out_size) *out_size = 0;
    if (!path || !*path) {
        glow__errorf(log, "bake writer: no output path");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    void *img = NULL;
    uint64_t size = 0;
    glow_result r = glow__bake_write_memory(sections, count, &img, &size);
    if (r != GLOW_OK) {
        glow__errorf(log, "%s: cannot build the bake image (%s)", path, glow_result_string(r));
        return r;
    }

    size_t tmp_len = strlen(path) + 32;
    char *tmp = malloc(tmp_len);
    if (!tmp) {
        free(img);
        glow__errorf(log, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    snprintf(tmp, tmp_len, "%s.tmp.%ld", path, (long)getpid());

    const char *what = NULL; /* the step that failed */
    int err = 0;
    FILE *f = fopen(tmp, "wb");
    const int created = f != NULL;
    if (!created) {
        what = "cannot create temporary file";
        err = errno;
    } else {
        long long limit = fail_after_bytes();
        size_t want = (size_t)size;
        size_t allowed = (limit >= 0 && (unsigned long long)limit < (unsigned long long)want) ? (size_t)limit : want;
        size_t wrote = allowed ? fwrite(img, 1, allowed, f) : 0;
        if (wrote != allowed) {
            what = "write failed";
            err = errno;
        } else if (allowed != want) {
            what = "write failed"; /* simulated disk full (test hook) */
            err = ENOSPC;
        } else if (fflush(f) != 0) {
            what = "write failed";
            err = errno;
        } else if (fsync(fileno(f)) != 0) {
            what = "fsync failed";
            err = errno;
        }
        if (fclose(f) != 0 && !what) {
            what = "close failed";
            err = errno;
        }
        if (!what && rename(tmp, path) != 0) {
            what = "rename failed";
            err = errno;
        }
        if (what) remove(tmp);
    }
    free(img);
    if (what) {
        if (!created)
            glow__errorf(log, "%s: cannot create temporary file %s: %s", path, tmp, err ? strerror(err) : "unknown error");
        else
            glow__errorf(log, "%s: %s: %s", path, what, err ? strerror(err) : "unknown error");
        free(tmp);
        return GLOW_ERROR_IO;
    }
    free(tmp);
    sync_parent_dir(path);
    if (out_size) *out_size = size;
    return GLOW_OK;
}
