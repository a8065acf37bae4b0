/* glow_tool_json.h — the tools' JSON output through cJSON (Debian's libcjson, which the scene loader
 * already links): numbers keep the tools' convention for non-finite values (NaN -> null, ±Inf ->
 * ±1e999, which Python's json reads as ±inf), and documents print as one line on stdout. Header-only,
 * for the command-line tools of this repository (not part of the SDK). */
#ifndef GLOW_TOOL_JSON_H
#define GLOW_TOOL_JSON_H

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static inline cJSON *glow_json_num(cJSON *object, const char *key, double value) {
    if (isfinite(value)) return cJSON_AddNumberToObject(object, key, value);
    return cJSON_AddRawToObject(object, key, isnan(value) ? "null" : (value > 0 ? "1e999" : "-1e999"));
}

static inline cJSON *glow_json_array3(cJSON *object, const char *key, const double v[3]) {
    cJSON *a = cJSON_AddArrayToObject(object, key);
    for (int i = 0; a && i < 3; ++i) cJSON_AddItemToArray(a, isfinite(v[i]) ? cJSON_CreateNumber(v[i]) : cJSON_CreateNull());
    return a;
}

/* Prints `root` as one line and frees it. 0 on success; 1 when it could not be built or printed (out
 * of memory: a cJSON_Add* returned NULL somewhere leaves the document short, so the caller checks). */
static inline int glow_json_print(cJSON *root) {
    char *text = root ? cJSON_PrintUnformatted(root) : NULL;
    cJSON_Delete(root);
    if (!text) {
        fprintf(stderr, "out of memory for the JSON output\n");
        return 1;
    }
    int ok = puts(text) >= 0;
    cJSON_free(text);
    return ok ? 0 : 1;
}

#endif /* GLOW_TOOL_JSON_H */
