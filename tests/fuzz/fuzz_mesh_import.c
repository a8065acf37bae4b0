/* fuzz_mesh_import.c — libFuzzer target for mesh import (glow__scene_load: assimp, then our cleaning,
 * issue 15 D10).
 *
 * Each input is written to a private temporary folder as a file whose extension follows its content
 * ("glTF" magic: .glb; '{': .gltf; anything else: .obj) and imported as glow-bake would. When the
 * import succeeds the scene must be what the linker assumes: at least one triangle, every kept
 * corner finite, unit normals, material indices in range, a finite positive area and bounds that
 * hold every corner. Seed corpus: tests/data/scenes and the shared Cornell boxes (tools/fuzz-smoke.sh).
 *
 * assimp 5.2.5 leaks on some malformed OBJ files (about 1.6 KB inside its OBJ reader, issue 15);
 * tests/fuzz/lsan.supp suppresses leaks whose allocation stack is inside libassimp only.
 * Build: -DGLOW_FUZZ=ON with CC=clang (tests/fuzz/CMakeLists.txt), or tools/fuzz-smoke.sh. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "pc_internal.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char dir[128];

int LLVMFuzzerInitialize(int *argc, char ***argv) {
    (void)argc;
    (void)argv;
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/glow_fuzz_import_%d", tmp && tmp[0] ? tmp : "/tmp", (int)getpid());
    if (mkdir(dir, 0700) != 0) {
        perror(dir);
        abort();
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *ext = size >= 4 && !memcmp(data, "glTF", 4) ? "glb" : (size && data[0] == '{') ? "gltf" : "obj";
    char path[192];
    snprintf(path, sizeof path, "%s/mesh.%s", dir, ext);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) abort();
    glow__log log;
    memset(&log, 0, sizeof log);
    glow__scene sc;
    const glow_result r = glow__scene_load(path, &log, &sc);
    if (r == GLOW_OK) {
        if (sc.tri_count == 0 || !sc.pos || !sc.nrm || !sc.tri_material) abort();
        if (!(sc.area > 0.0) || !isfinite(sc.area)) abort();
        for (size_t i = 0; i < 3 * (size_t)sc.tri_count; ++i) {
            for (int k = 0; k < 3; ++k) {
                const float p = sc.pos[i][k];
                if (!isfinite(p) || p < sc.bounds_min[k] || p > sc.bounds_max[k]) abort();
            }
            const float *n = sc.nrm[i];
            if (!(fabsf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0f) < 1e-3f)) abort();
        }
        for (uint32_t t = 0; t < sc.tri_count; ++t)
            if (sc.tri_material[t] >= sc.material_count) abort();
    } else if (!log.last_error[0]) {
        abort(); /* a failure names its problem */
    }
    glow__scene_free(&sc);
    unlink(path);
    return 0;
}
