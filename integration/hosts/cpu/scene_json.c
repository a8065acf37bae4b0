/* scene_json.c — the scene description file (glow_scene.h, docs/scene-format.md).
 *
 * JSON is parsed with cJSON from Debian's libcjson-dev (pkg-config "libcjson"): a maintained,
 * fuzzed, security-patched distribution package beats a hand-written parser for a file that users
 * edit by hand. cJSON only tokenises; every schema rule (types, lengths, ranges, units) is checked
 * here, and every failure names the file and the JSON path of the offending value. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glow/glow_scene.h"

#define SCENE_MAX_FILE_SIZE (64u << 20)
#define SCENE_MAX_LIGHTS 65536u
#define SCENE_MAX_MATERIALS 65536u

typedef struct ctx {
    const char *name;
    const glow_logger *logger;
    char *message;
    size_t message_size;
    uint32_t warnings;
} ctx;

static void emit(ctx *c, glow_log_level level, glow_result code, const char *fmt, va_list ap) {
    char text[768];
    int n = snprintf(text, sizeof text, "%s: ", c->name);
    if (n < 0) n = 0;
    if ((size_t)n < sizeof text) vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
    if (level == GLOW_LOG_ERROR && c->message && c->message_size) snprintf(c->message, c->message_size, "%s", text);
    if (c->logger && c->logger->log) c->logger->log(c->logger->user, level, code, text, __FILE__, __LINE__);
}

#if defined(__GNUC__)
#define GLOW_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define GLOW_PRINTF(a, b)
#endif

static glow_result GLOW_PRINTF(3, 4) fail(ctx *c, glow_result code, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    emit(c, GLOW_LOG_ERROR, code, fmt, ap);
    va_end(ap);
    return code;
}

static void GLOW_PRINTF(2, 3) warn(ctx *c, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    emit(c, GLOW_LOG_WARNING, GLOW_OK, fmt, ap);
    va_end(ap);
    c->warnings++;
}

static const char *json_type_name(const cJSON *v) {
    if (cJSON_IsNumber(v)) return "a number";
    if (cJSON_IsString(v)) return "a string";
    if (cJSON_IsArray(v)) return "an array";
    if (cJSON_IsObject(v)) return "an object";
    if (cJSON_IsBool(v)) return "a boolean";
    if (cJSON_IsNull(v)) return "null";
    return "invalid";
}

/* ---------------------------------------------------------------- keys of one object */

/* Checks an object's keys: comments ("_...") skipped, duplicates rejected, keys outside `known`
 * (NULL-terminated) warned about and ignored. `where` is the object's JSON path ("" = root). */
static glow_result check_keys(ctx *c, const cJSON *obj, const char *where, const char *const *known) {
    for (const cJSON *it = obj->child; it; it = it->next) {
        const char *key = it->string ? it->string : "";
        if (key[0] == '_') continue;
        for (const cJSON *prev = obj->child; prev != it; prev = prev->next) {
            if (prev->string && strcmp(prev->string, key) == 0)
                return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s%s%.64s appears twice", where, where[0] ? "." : "",
                            key);
        }
        bool ok = false;
        for (const char *const *k = known; *k; ++k) ok = ok || strcmp(*k, key) == 0;
        if (!ok) warn(c, "%s%s%.64s is not a known key; ignored", where, where[0] ? "." : "", key);
    }
    return GLOW_OK;
}

static const cJSON *get(const cJSON *obj, const char *key) {
    for (const cJSON *it = obj->child; it; it = it->next)
        if (it->string && strcmp(it->string, key) == 0) return it;
    return NULL;
}

/* --------------------------------------------------------------------- typed readers */

static glow_result read_number(ctx *c, const cJSON *v, const char *path, float *out) {
    if (!cJSON_IsNumber(v))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s must be a number, not %s", path, json_type_name(v));
    double d = v->valuedouble;
    if (!isfinite(d) || fabs(d) > 3.0e38)
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s is not a finite number (%g)", path, d);
    *out = (float)d;
    return GLOW_OK;
}

static glow_result read_vec3(ctx *c, const cJSON *v, const char *path, float out[3]) {
    if (!cJSON_IsArray(v))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s must be an array of 3 numbers, not %s", path,
                    json_type_name(v));
    int n = cJSON_GetArraySize(v);
    if (n != 3) return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s must have 3 numbers, has %d", path, n);
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, ++i) {
        char p[160];
        snprintf(p, sizeof p, "%s[%d]", path, i);
        glow_result r = read_number(c, e, p, &out[i]);
        if (r != GLOW_OK) return r;
    }
    return GLOW_OK;
}

static glow_result read_nonneg_vec3(ctx *c, const cJSON *v, const char *path, float out[3]) {
    glow_result r = read_vec3(c, v, path, out);
    if (r != GLOW_OK) return r;
    for (int i = 0; i < 3; ++i)
        if (out[i] < 0.0f)
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s[%d] (%g) is negative", path, i, (double)out[i]);
    return GLOW_OK;
}

static glow_result read_unit_vec3(ctx *c, const cJSON *v, const char *path, float out[3]) {
    glow_result r = read_vec3(c, v, path, out);
    if (r != GLOW_OK) return r;
    double len = sqrt((double)out[0] * out[0] + (double)out[1] * out[1] + (double)out[2] * out[2]);
    if (!(len > 1e-12))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s [%g, %g, %g] has zero length", path, (double)out[0],
                    (double)out[1], (double)out[2]);
    for (int i = 0; i < 3; ++i) out[i] = (float)(out[i] / len);
    return GLOW_OK;
}

static glow_result require(ctx *c, const cJSON *obj, const char *where, const char *key, const cJSON **out) {
    *out = get(obj, key);
    if (!*out)
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s%s%s is required but missing", where, where[0] ? "." : "",
                    key);
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------ lights */

const char *glow_scene_light_type_name(glow_scene_light_type type) {
    switch (type) {
    case GLOW_SCENE_LIGHT_POINT: return "point";
    case GLOW_SCENE_LIGHT_SPOT: return "spot";
    case GLOW_SCENE_LIGHT_SUN: return "sun";
    default: return "none";
    }
}

static bool finite3(const float v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

glow_result glow_scene_light_validate(const glow_scene_light *light, const char *what, char *message,
                                      size_t message_size) {
    ctx c = {.name = what ? what : "light", .message = message, .message_size = message_size};
    if (message && message_size) message[0] = '\0';
    if (!light) return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "NULL light");
    const glow_scene_light *l = light;
    if (l->type != GLOW_SCENE_LIGHT_POINT && l->type != GLOW_SCENE_LIGHT_SPOT && l->type != GLOW_SCENE_LIGHT_SUN)
        return fail(&c, GLOW_ERROR_UNSUPPORTED, "unknown light type %d (valid: point, spot, sun)", (int)l->type);
    const float *power = l->type == GLOW_SCENE_LIGHT_SUN ? l->irradiance : l->intensity;
    const char *pname = l->type == GLOW_SCENE_LIGHT_SUN ? "irradiance" : "intensity";
    if (!finite3(power)) return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "%s is not finite", pname);
    for (int i = 0; i < 3; ++i)
        if (power[i] < 0.0f)
            return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "%s[%d] (%g) is negative", pname, i, (double)power[i]);
    if (l->type != GLOW_SCENE_LIGHT_SUN && !finite3(l->position))
        return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "position is not finite");
    if (l->type != GLOW_SCENE_LIGHT_POINT) {
        const float *d = l->direction;
        if (!finite3(d)) return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "direction is not finite");
        if (!((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2] > 1e-24))
            return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "direction [%g, %g, %g] has zero length", (double)d[0],
                        (double)d[1], (double)d[2]);
    }
    if (l->type == GLOW_SCENE_LIGHT_SPOT) {
        if (!isfinite(l->outer_deg) || !(l->outer_deg > 0.0f) || l->outer_deg > 90.0f)
            return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "outer_deg (%g) is outside (0, 90]", (double)l->outer_deg);
        if (!isfinite(l->inner_deg) || l->inner_deg < 0.0f)
            return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "inner_deg (%g) is negative or not finite",
                        (double)l->inner_deg);
        if (l->inner_deg > l->outer_deg)
            return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "inner_deg (%g) > outer_deg (%g)", (double)l->inner_deg,
                        (double)l->outer_deg);
    }
    return GLOW_OK;
}

static glow_result read_light(ctx *c, const cJSON *v, uint32_t index, glow_scene_light *out) {
    char where[64], p[96];
    snprintf(where, sizeof where, "lights[%u]", index);
    memset(out, 0, sizeof *out);
    if (!cJSON_IsObject(v))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s must be an object, not %s", where, json_type_name(v));
    const cJSON *t;
    glow_result r = require(c, v, where, "type", &t);
    if (r != GLOW_OK) return r;
    if (!cJSON_IsString(t))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s.type must be a string, not %s", where, json_type_name(t));
    static const char *const point_keys[] = {"type", "position", "intensity", NULL};
    static const char *const spot_keys[] = {"type", "position", "direction", "intensity", "outer_deg", "inner_deg",
                                            NULL};
    static const char *const sun_keys[] = {"type", "direction", "irradiance", NULL};
    const char *const *keys;
    if (strcmp(t->valuestring, "point") == 0) {
        out->type = GLOW_SCENE_LIGHT_POINT;
        keys = point_keys;
    } else if (strcmp(t->valuestring, "spot") == 0) {
        out->type = GLOW_SCENE_LIGHT_SPOT;
        keys = spot_keys;
    } else if (strcmp(t->valuestring, "sun") == 0) {
        out->type = GLOW_SCENE_LIGHT_SUN;
        keys = sun_keys;
    } else {
        return fail(c, GLOW_ERROR_UNSUPPORTED, "%s.type \"%.64s\" is not a light type (valid: point, spot, sun)", where,
                    t->valuestring);
    }
    if ((r = check_keys(c, v, where, keys)) != GLOW_OK) return r;
    const cJSON *e;
    if (out->type != GLOW_SCENE_LIGHT_SUN) {
        if ((r = require(c, v, where, "position", &e)) != GLOW_OK) return r;
        snprintf(p, sizeof p, "%s.position", where);
        if ((r = read_vec3(c, e, p, out->position)) != GLOW_OK) return r;
        if ((r = require(c, v, where, "intensity", &e)) != GLOW_OK) return r;
        snprintf(p, sizeof p, "%s.intensity", where);
        if ((r = read_nonneg_vec3(c, e, p, out->intensity)) != GLOW_OK) return r;
    } else {
        if ((r = require(c, v, where, "irradiance", &e)) != GLOW_OK) return r;
        snprintf(p, sizeof p, "%s.irradiance", where);
        if ((r = read_nonneg_vec3(c, e, p, out->irradiance)) != GLOW_OK) return r;
    }
    if (out->type != GLOW_SCENE_LIGHT_POINT) {
        if ((r = require(c, v, where, "direction", &e)) != GLOW_OK) return r;
        snprintf(p, sizeof p, "%s.direction", where);
        if ((r = read_unit_vec3(c, e, p, out->direction)) != GLOW_OK) return r;
    }
    if (out->type == GLOW_SCENE_LIGHT_SPOT) {
        out->outer_deg = 45.0f;
        out->inner_deg = 0.0f;
        if ((e = get(v, "outer_deg")) != NULL) {
            snprintf(p, sizeof p, "%s.outer_deg", where);
            if ((r = read_number(c, e, p, &out->outer_deg)) != GLOW_OK) return r;
            if (!(out->outer_deg > 0.0f) || out->outer_deg > 90.0f)
                return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s (%g) is outside (0, 90]", p, (double)out->outer_deg);
        }
        if ((e = get(v, "inner_deg")) != NULL) {
            snprintf(p, sizeof p, "%s.inner_deg", where);
            if ((r = read_number(c, e, p, &out->inner_deg)) != GLOW_OK) return r;
            if (out->inner_deg < 0.0f)
                return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s (%g) is negative", p, (double)out->inner_deg);
        }
        if (out->inner_deg > out->outer_deg)
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s.inner_deg (%g) > outer_deg (%g)", where,
                        (double)out->inner_deg, (double)out->outer_deg);
    }
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------ camera */

static void camera_defaults(glow_scene_camera *cam) {
    memset(cam, 0, sizeof *cam);
    cam->up[1] = 1.0f;
    cam->vfov_deg = 60.0f;
    cam->width = 640;
    cam->height = 360;
}

static glow_result read_size(ctx *c, const cJSON *v, const char *path, uint32_t *out) {
    float f;
    glow_result r = read_number(c, v, path, &f);
    if (r != GLOW_OK) return r;
    double d = v->valuedouble;
    if (d != floor(d) || d < 1.0 || d > 16384.0)
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s (%g) must be a whole number in 1..16384", path, d);
    *out = (uint32_t)d;
    return GLOW_OK;
}

static glow_result read_camera(ctx *c, const cJSON *v, glow_scene_camera *cam) {
    if (!cJSON_IsObject(v))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "camera must be an object, not %s", json_type_name(v));
    static const char *const keys[] = {"position", "target", "up", "vfov_deg", "width", "height", NULL};
    glow_result r = check_keys(c, v, "camera", keys);
    if (r != GLOW_OK) return r;
    const cJSON *e;
    if ((r = require(c, v, "camera", "position", &e)) != GLOW_OK) return r;
    if ((r = read_vec3(c, e, "camera.position", cam->position)) != GLOW_OK) return r;
    if ((r = require(c, v, "camera", "target", &e)) != GLOW_OK) return r;
    if ((r = read_vec3(c, e, "camera.target", cam->target)) != GLOW_OK) return r;
    if ((e = get(v, "up")) != NULL && (r = read_unit_vec3(c, e, "camera.up", cam->up)) != GLOW_OK) return r;
    if ((e = get(v, "vfov_deg")) != NULL) {
        if ((r = read_number(c, e, "camera.vfov_deg", &cam->vfov_deg)) != GLOW_OK) return r;
        if (!(cam->vfov_deg > 0.0f) || !(cam->vfov_deg < 180.0f))
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "camera.vfov_deg (%g) is outside (0, 180)",
                        (double)cam->vfov_deg);
    }
    if ((e = get(v, "width")) != NULL && (r = read_size(c, e, "camera.width", &cam->width)) != GLOW_OK) return r;
    if ((e = get(v, "height")) != NULL && (r = read_size(c, e, "camera.height", &cam->height)) != GLOW_OK) return r;
    double f[3], len2 = 0.0;
    for (int i = 0; i < 3; ++i) {
        f[i] = (double)cam->target[i] - cam->position[i];
        len2 += f[i] * f[i];
    }
    if (!(len2 > 1e-18)) return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "camera.target equals camera.position");
    double len = sqrt(len2);
    double cr[3] = {f[1] * cam->up[2] - f[2] * cam->up[1], f[2] * cam->up[0] - f[0] * cam->up[2],
                    f[0] * cam->up[1] - f[1] * cam->up[0]};
    if (!(sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) > 1e-6 * len))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "camera.up is parallel to the view direction (target - position)");
    return GLOW_OK;
}

void glow_scene_camera_default(const float bounds_min[3], const float bounds_max[3], glow_scene_camera *camera) {
    if (!camera) return;
    float vfov = camera->vfov_deg, w = (float)camera->width, h = (float)camera->height;
    bool keep_fov = isfinite(vfov) && vfov > 0.0f && vfov < 180.0f;
    bool keep_size = camera->width >= 1 && camera->width <= 16384 && camera->height >= 1 && camera->height <= 16384;
    camera_defaults(camera);
    if (keep_fov) camera->vfov_deg = vfov;
    if (keep_size) {
        camera->width = (uint32_t)w;
        camera->height = (uint32_t)h;
    }
    if (!bounds_min || !bounds_max) return;
    double radius2 = 0.0;
    for (int i = 0; i < 3; ++i) {
        double lo = bounds_min[i], hi = bounds_max[i];
        if (!isfinite(lo) || !isfinite(hi) || hi < lo) lo = hi = 0.0;
        camera->target[i] = (float)(0.5 * (lo + hi));
        radius2 += 0.25 * (hi - lo) * (hi - lo);
    }
    double radius = sqrt(radius2);
    if (!(radius > 0.0)) radius = 1.0;
    double dist = radius / sin(0.5 * (double)camera->vfov_deg * 3.14159265358979323846 / 180.0);
    camera->position[0] = camera->target[0];
    camera->position[1] = camera->target[1];
    camera->position[2] = (float)(camera->target[2] + dist);
}

/* ------------------------------------------------------------------------------- scene */

void glow_scene_free(glow_scene_desc *scene) {
    if (!scene) return;
    free(scene->mesh);
    free(scene->lights);
    free(scene->materials);
    memset(scene, 0, sizeof *scene);
}

static glow_result resolve_mesh(ctx *c, const char *mesh, const char *base_dir, char **out) {
    size_t n = strlen(mesh);
    bool keep = strncmp(mesh, "builtin:", 8) == 0 || mesh[0] == '/' || !base_dir || !base_dir[0];
    size_t bn = keep ? 0 : strlen(base_dir);
    bool slash = bn > 0 && base_dir[bn - 1] == '/';
    char *s = malloc(bn + 1 + n + 1);
    if (!s) return fail(c, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for the mesh path");
    if (keep)
        memcpy(s, mesh, n + 1);
    else
        snprintf(s, bn + 1 + n + 1, "%s%s%s", base_dir, slash ? "" : "/", mesh);
    *out = s;
    return GLOW_OK;
}

/* 1-based line and column of byte `off` in `text`. */
static void line_col(const char *text, size_t off, unsigned *line, unsigned *col) {
    *line = 1;
    *col = 1;
    for (size_t i = 0; i < off; ++i) {
        if (text[i] == '\n') {
            ++*line;
            *col = 1;
        } else {
            ++*col;
        }
    }
}

/* ---------------------------------------------------------------------------- materials */

/* "materials": {"NAME": {"ggx": {"roughness": r, "specular": [r, g, b]}}, ...} */
static glow_result read_material(ctx *c, const cJSON *v, glow_scene_material *out) {
    const char *name = v->string ? v->string : "";
    char where[96], path[128];
    snprintf(where, sizeof where, "materials.%.64s", name);
    if (!name[0]) return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "materials has an empty material name");
    if (strlen(name) >= sizeof out->name)
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s...: the material name is longer than %zu bytes", where,
                    sizeof out->name - 1);
    if (!cJSON_IsObject(v))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s must be an object, not %s", where, json_type_name(v));
    static const char *const keys[] = {"ggx", NULL};
    glow_result r = check_keys(c, v, where, keys);
    if (r != GLOW_OK) return r;
    snprintf(out->name, sizeof out->name, "%s", name);
    const cJSON *g = get(v, "ggx");
    if (!g) return GLOW_OK;
    snprintf(path, sizeof path, "%s.ggx", where);
    if (!cJSON_IsObject(g))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s must be an object, not %s", path, json_type_name(g));
    static const char *const ggx_keys[] = {"roughness", "specular", NULL};
    if ((r = check_keys(c, g, path, ggx_keys)) != GLOW_OK) return r;
    const cJSON *e;
    if ((r = require(c, g, path, "roughness", &e)) != GLOW_OK) return r;
    char p2[160];
    snprintf(p2, sizeof p2, "%s.roughness", path);
    if ((r = read_number(c, e, p2, &out->roughness)) != GLOW_OK) return r;
    if (!(out->roughness > 0.0f && out->roughness <= 1.0f))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s (%g) is outside (0, 1]", p2, (double)out->roughness);
    out->specular[0] = out->specular[1] = out->specular[2] = 0.04f;
    if ((e = get(g, "specular")) != NULL) {
        snprintf(p2, sizeof p2, "%s.specular", path);
        if ((r = read_nonneg_vec3(c, e, p2, out->specular)) != GLOW_OK) return r;
        for (int i = 0; i < 3; ++i)
            if (out->specular[i] > 1.0f)
                return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "%s[%d] (%g) is above 1", p2, i, (double)out->specular[i]);
    }
    out->ggx = true;
    return GLOW_OK;
}

/* "environment_map": {"path": "sky.exr", "rotation_deg": F, "scale": F} */
static glow_result read_environment_map(ctx *c, const cJSON *v, const char *base_dir, glow_scene_environment_map *out) {
    if (!cJSON_IsObject(v))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "environment_map must be an object ({\"path\": ...}), not %s",
                    json_type_name(v));
    static const char *const keys[] = {"path", "rotation_deg", "scale", NULL};
    glow_result r = check_keys(c, v, "environment_map", keys);
    if (r != GLOW_OK) return r;
    const cJSON *e;
    if ((r = require(c, v, "environment_map", "path", &e)) != GLOW_OK) return r;
    if (!cJSON_IsString(e))
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "environment_map.path must be a string, not %s", json_type_name(e));
    const char *p = e->valuestring;
    if (!p[0]) return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "environment_map.path is an empty string");
    const bool keep = p[0] == '/' || !base_dir || !base_dir[0];
    const size_t bn = keep ? 0 : strlen(base_dir);
    const bool slash = bn > 0 && base_dir[bn - 1] == '/';
    const size_t need = (keep ? 0 : bn + !slash) + strlen(p);
    if (need >= sizeof out->path)
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "environment_map.path is too long (%zu bytes with the scene's folder, at most %zu)",
                    need, sizeof out->path - 1);
    if (keep)
        snprintf(out->path, sizeof out->path, "%s", p);
    else
        snprintf(out->path, sizeof out->path, "%s%s%s", base_dir, slash ? "" : "/", p);
    out->rotation_deg = 0.0f;
    out->scale = 1.0f;
    if ((e = get(v, "rotation_deg")) != NULL &&
        (r = read_number(c, e, "environment_map.rotation_deg", &out->rotation_deg)) != GLOW_OK)
        return r;
    if ((e = get(v, "scale")) != NULL) {
        if ((r = read_number(c, e, "environment_map.scale", &out->scale)) != GLOW_OK) return r;
        if (out->scale < 0.0f)
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "environment_map.scale (%g) is negative", (double)out->scale);
    }
    return GLOW_OK;
}

static glow_result parse_root(ctx *c, const cJSON *root, const char *base_dir, glow_scene_desc *s) {
    if (!cJSON_IsObject(root))
        return fail(c, GLOW_ERROR_CORRUPT_DATA, "the document must be a JSON object, not %s", json_type_name(root));
    static const char *const keys[] = {"mesh", "camera", "lights", "environment", "emission_scale", "materials",
                                       "environment_map", NULL};
    glow_result r = check_keys(c, root, "", keys);
    if (r != GLOW_OK) return r;
    const cJSON *e;
    if ((r = require(c, root, "", "mesh", &e)) != GLOW_OK) return r;
    if (!cJSON_IsString(e)) return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "mesh must be a string, not %s", json_type_name(e));
    if (!e->valuestring[0]) return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "mesh is an empty string");
    if (strcmp(e->valuestring, "builtin:") == 0)
        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "mesh \"builtin:\" names no built-in scene");
    if ((r = resolve_mesh(c, e->valuestring, base_dir, &s->mesh)) != GLOW_OK) return r;

    camera_defaults(&s->camera);
    if ((e = get(root, "camera")) != NULL) {
        if ((r = read_camera(c, e, &s->camera)) != GLOW_OK) return r;
        s->has_camera = true;
    }

    if ((e = get(root, "lights")) != NULL) {
        if (!cJSON_IsArray(e))
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "lights must be an array, not %s", json_type_name(e));
        int n = cJSON_GetArraySize(e);
        if ((uint32_t)n > SCENE_MAX_LIGHTS)
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "lights has %d entries (at most %u)", n, SCENE_MAX_LIGHTS);
        if (n > 0) {
            s->lights = calloc((size_t)n, sizeof *s->lights);
            if (!s->lights) return fail(c, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %d lights", n);
            uint32_t i = 0;
            for (const cJSON *l = e->child; l; l = l->next, ++i)
                if ((r = read_light(c, l, i, &s->lights[i])) != GLOW_OK) return r;
            s->light_count = (uint32_t)n;
        }
    }
    if ((e = get(root, "environment")) != NULL && (r = read_nonneg_vec3(c, e, "environment", s->environment)) != GLOW_OK)
        return r;
    s->environment_map.scale = 1.0f;
    if ((e = get(root, "environment_map")) != NULL &&
        (r = read_environment_map(c, e, base_dir, &s->environment_map)) != GLOW_OK)
        return r;
    s->emission_scale = 1.0f;
    if ((e = get(root, "emission_scale")) != NULL) {
        if ((r = read_number(c, e, "emission_scale", &s->emission_scale)) != GLOW_OK) return r;
        if (s->emission_scale < 0.0f)
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "emission_scale (%g) is negative", (double)s->emission_scale);
    }
    if ((e = get(root, "materials")) != NULL) {
        if (!cJSON_IsObject(e))
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "materials must be an object (material name -> override), not %s",
                        json_type_name(e));
        uint32_t n = 0;
        for (const cJSON *m = e->child; m; m = m->next) n += !(m->string && m->string[0] == '_');
        if (n > SCENE_MAX_MATERIALS)
            return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "materials has %u entries (at most %u)", n, SCENE_MAX_MATERIALS);
        if (n > 0) {
            for (const cJSON *m = e->child; m; m = m->next) /* names are free; only duplicates are errors */
                for (const cJSON *prev = e->child; prev != m; prev = prev->next)
                    if (m->string && prev->string && strcmp(prev->string, m->string) == 0)
                        return fail(c, GLOW_ERROR_INVALID_ARGUMENT, "materials.%.64s appears twice", m->string);
            s->materials = calloc(n, sizeof *s->materials);
            if (!s->materials) return fail(c, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u materials", n);
            uint32_t i = 0;
            for (const cJSON *m = e->child; m; m = m->next) {
                if (m->string && m->string[0] == '_') continue;
                if ((r = read_material(c, m, &s->materials[i++])) != GLOW_OK) return r;
            }
            s->material_count = n;
        }
    }
    return GLOW_OK;
}

glow_result glow_scene_parse(const char *json, size_t json_size, const char *name, const char *base_dir,
                             const glow_logger *logger, glow_scene_desc *out_scene, char *message,
                             size_t message_size) {
    ctx c = {.name = name ? name : "scene", .logger = logger, .message = message, .message_size = message_size};
    if (message && message_size) message[0] = '\0';
    if (out_scene) memset(out_scene, 0, sizeof *out_scene);
    if (!out_scene || (!json && json_size))
        return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "NULL %s", out_scene ? "json" : "out_scene");
    const char *end = NULL;
    cJSON *root = json_size ? cJSON_ParseWithLengthOpts(json, json_size, &end, false) : NULL;
    if (!root) {
        size_t off = end && end >= json && end <= json + json_size ? (size_t)(end - json) : 0;
        if (!json_size) return fail(&c, GLOW_ERROR_CORRUPT_DATA, "not JSON: the document is empty");
        unsigned line, col;
        line_col(json, off, &line, &col);
        return fail(&c, GLOW_ERROR_CORRUPT_DATA, "not JSON: syntax error at line %u, column %u", line, col);
    }
    /* cJSON stops after the first value; anything but whitespace after it is an error. */
    size_t off = end && end >= json && end <= json + json_size ? (size_t)(end - json) : json_size;
    while (off < json_size && (json[off] == ' ' || json[off] == '\t' || json[off] == '\n' || json[off] == '\r'))
        ++off;
    if (off < json_size && json[off] != '\0') {
        unsigned line, col;
        line_col(json, off, &line, &col);
        cJSON_Delete(root);
        return fail(&c, GLOW_ERROR_CORRUPT_DATA, "not JSON: unexpected text after the document at line %u, column %u",
                    line, col);
    }
    glow_result r = parse_root(&c, root, base_dir, out_scene);
    cJSON_Delete(root);
    if (r != GLOW_OK) {
        glow_scene_free(out_scene);
        return r;
    }
    out_scene->warning_count = c.warnings;
    return GLOW_OK;
}

glow_result glow_scene_load(const char *path, const glow_logger *logger, glow_scene_desc *out_scene, char *message,
                            size_t message_size) {
    ctx c = {.name = path ? path : "(null)", .logger = logger, .message = message, .message_size = message_size};
    if (message && message_size) message[0] = '\0';
    if (out_scene) memset(out_scene, 0, sizeof *out_scene);
    if (!path || !out_scene) return fail(&c, GLOW_ERROR_INVALID_ARGUMENT, "NULL %s", path ? "out_scene" : "path");
    FILE *f = fopen(path, "rb");
    if (!f) return fail(&c, GLOW_ERROR_IO, "cannot open the file");
    char *buf = NULL;
    size_t size = 0, cap = 0;
    glow_result r = GLOW_OK;
    for (;;) {
        if (size == cap) {
            if (cap >= SCENE_MAX_FILE_SIZE) {
                r = fail(&c, GLOW_ERROR_IO, "file is larger than %u MiB", SCENE_MAX_FILE_SIZE >> 20);
                break;
            }
            size_t ncap = cap ? 2 * cap : 4096;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                r = fail(&c, GLOW_ERROR_OUT_OF_MEMORY, "out of memory reading the file");
                break;
            }
            buf = nb;
            cap = ncap;
        }
        size_t got = fread(buf + size, 1, cap - size, f);
        size += got;
        if (got == 0) {
            if (ferror(f)) r = fail(&c, GLOW_ERROR_IO, "read error");
            break;
        }
    }
    fclose(f);
    if (r != GLOW_OK) {
        free(buf);
        return r;
    }
    /* the folder of `path`, for a relative "mesh" */
    char *dir = NULL;
    const char *slash = strrchr(path, '/');
    if (slash) {
        size_t dn = (size_t)(slash - path);
        dir = malloc(dn + 2);
        if (!dir) {
            free(buf);
            return fail(&c, GLOW_ERROR_OUT_OF_MEMORY, "out of memory");
        }
        if (dn == 0) {
            dir[0] = '/';
            dir[1] = '\0';
        } else {
            memcpy(dir, path, dn);
            dir[dn] = '\0';
        }
    }
    r = glow_scene_parse(buf, size, path, dir, logger, out_scene, message, message_size);
    free(dir);
    free(buf);
    return r;
}
