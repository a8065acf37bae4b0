/* fuzz_reseal.h — shared by the bake fuzzers: recompute a bake image's CRCs so that mutations reach
 * the content checks instead of dying at a checksum. Header-only (each fuzzer is one translation
 * unit with the runtime sources compiled in). */
#ifndef GLOW_FUZZ_RESEAL_H
#define GLOW_FUZZ_RESEAL_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "bake/bake_format.h"
#include "runtime_internal.h"

static inline uint32_t fuzz_rd32(const uint8_t *p) { uint32_t v; memcpy(&v, p, 4); return v; }
static inline uint64_t fuzz_rd64(const uint8_t *p) { uint64_t v; memcpy(&v, p, 8); return v; }
static inline void fuzz_wr32(uint8_t *p, uint32_t v) { memcpy(p, &v, 4); }

/* Recomputes section, table and header CRCs in place; entries that do not fit are left alone. */
static inline void fuzz_fix_crcs(uint8_t *img, size_t size) {
    if (size < 64) return;
    uint32_t n = fuzz_rd32(img + 12);
    if (n > GLOW_BAKE_MAX_SECTIONS || 64u + 32u * (uint64_t)n > size) return;
    for (uint32_t i = 0; i < n; i++) {
        uint8_t *e = img + 64 + 32 * i;
        uint64_t off = fuzz_rd64(e + 8), sz = fuzz_rd64(e + 16);
        if (off <= size && sz <= size - off) fuzz_wr32(e + 24, glow__crc32(0, img + off, (size_t)sz));
    }
    fuzz_wr32(img + 28, glow__crc32(0, img + 64, 32u * (size_t)n));
    fuzz_wr32(img + 32, 0);
    fuzz_wr32(img + 32, glow__crc32(0, img, 64));
}

#endif
