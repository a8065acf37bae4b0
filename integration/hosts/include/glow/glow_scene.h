/*
 * glow_scene.h — the scene description file (JSON): which mesh, seen from where, lit by what.
 *
 * Part of glow_host (target glow::host, folder integration/hosts/cpu/). The schema, units, defaults and every
 * error are documented in docs/scene-format.md; in short:
 *
 *   { "mesh": "CornellBox-Original.obj",              (relative to the JSON file, or "builtin:NAME")
 *     "camera": { "position": [0,1,3.9], "target": [0,1,0], "up": [0,1,0],
 *                 "vfov_deg": 39.3, "width": 256, "height": 256 },
 *     "lights": [ { "type": "point", "position": [..], "intensity": [r,g,b] },          W/sr
 *                 { "type": "spot", "position": [..], "direction": [..], "intensity": [r,g,b],
 *                   "outer_deg": 40, "inner_deg": 30 },                                  W/sr on the axis
 *                 { "type": "sun", "direction": [..], "irradiance": [r,g,b] } ],         W/m²
 *     "environment": [r,g,b],                          constant sky radiance W/(m²·sr)
 *     "environment_map": {"path": "sky.exr", "rotation_deg": 0, "scale": 1},
 *                                                      lat-long HDR sky W/(m²·sr), added to environment
 *     "emission_scale": 1,                             multiplies material emission (Ke)
 *     "materials": { "floor": { "ggx": { "roughness": 0.3, "specular": [0.04,0.04,0.04] } } } }
 *                                                      optional per-material overrides by the mesh's
 *                                                      material name: a GGX specular layer (docs/glossy.md)
 *
 * WHAT IT DOES NOT DO: load the mesh (that is glow-bake / glow_pc_bake, which takes the resolved
 * `mesh` path as it is), or light anything (that is glow_host.h).
 *
 * USAGE
 *   glow_scene_desc scene; char msg[512];
 *   if (glow_scene_load("cornell.json", NULL, &scene, msg, sizeof msg) != GLOW_OK) { puts(msg); ... }
 *   glow_pc_bake(scene.mesh, "cornell.glow", &settings, NULL);    bake the mesh it names
 *   glow_system_params prm = GLOW_SYSTEM_PARAMS_INIT;  prm.emission_scale = scene.emission_scale;
 *   glow_system_set_params(sys, &prm);
 *   glow_host_desc hd = glow_host_desc_from_scene(&scene, bake, GLOW_HOST_KIND_EXACT);  (glow_host.h)
 *   if (!scene.has_camera) glow_scene_camera_default(info.bounds_min, info.bounds_max, &scene.camera);
 *   glow_scene_free(&scene);
 *
 * ON MEMORY: glow_scene_desc owns three heap blocks (mesh, lights, materials), malloc'd by the loader and
 * released by glow_scene_free. Nothing is kept after a failed load.
 *
 * ON ERRORS: the loaders return a glow_result and write one line naming the file and the problem
 * ("cornell.json: lights[1].inner_deg (50) > outer_deg (40)") into the caller's `message` buffer
 * (truncated to message_size; "" on success; may be NULL). The same line also goes to `logger`
 * (optional) as GLOW_LOG_ERROR with the same code; warnings (unknown keys) go only to the logger,
 * as GLOW_LOG_WARNING with code GLOW_OK, and are counted in glow_scene_desc.warning_count.
 *   GLOW_ERROR_INVALID_ARGUMENT  NULL path/out, or the JSON breaks the schema (missing required key,
 *                                wrong type, wrong array length, non-finite number, negative
 *                                intensity, inner_deg > outer_deg, zero-length vector, duplicate key)
 *   GLOW_ERROR_UNSUPPORTED       a light "type" other than "point", "spot", "sun"
 *   GLOW_ERROR_CORRUPT_DATA      not JSON (the message gives line and column), or not a JSON object
 *   GLOW_ERROR_IO                the file cannot be opened or read (or is larger than 64 MiB)
 *   GLOW_ERROR_OUT_OF_MEMORY
 *
 * ON THREADS: one load at a time per process — cJSON 1.7 records parse failures in a global.
 * glow_scene_light_validate and glow_scene_camera_default are pure and may run on any thread.
 */
#ifndef GLOW_GLOW_SCENE_H
#define GLOW_GLOW_SCENE_H

#include "glow/glow.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum glow_scene_light_type {
    GLOW_SCENE_LIGHT_NONE = 0, /* invalid: every light has a type */
    GLOW_SCENE_LIGHT_POINT,    /* "point" */
    GLOW_SCENE_LIGHT_SPOT,     /* "spot" */
    GLOW_SCENE_LIGHT_SUN,      /* "sun" */
    GLOW_SCENE_LIGHT_FORCE_U32 = 0x7FFFFFFF
} glow_scene_light_type;

/* One light. Fields a type does not use are ignored (and zero after a load). */
typedef struct glow_scene_light {
    glow_scene_light_type type;
    float position[3];  /* point, spot: m */
    float direction[3]; /* spot: cone axis (the way the light shines); sun: the way the light travels.
                           Unit length after a load; the host normalises what it is given */
    float intensity[3]; /* point, spot: radiant intensity, W/sr (spot: on its axis); >= 0 */
    float irradiance[3];/* sun: W/m² on a surface facing it; >= 0 */
    float outer_deg;    /* spot: half-angle from the axis where the light ends, (0, 90]; default 45 */
    float inner_deg;    /* spot: half-angle where the falloff starts, [0, outer_deg]; default 0 */
} glow_scene_light;

typedef struct glow_scene_camera {
    float position[3], target[3]; /* m; required in a "camera" object */
    float up[3];                  /* default (0, 1, 0); unit length after a load */
    float vfov_deg;               /* full vertical field of view, (0, 180); default 60 */
    uint32_t width, height;       /* pixels, 1..16384; default 640 x 360 */
} glow_scene_camera;

/* A per-material override ("materials" key), matched by name against the mesh's materials by the tool
 * that loads the mesh (glow-render); the loader does not open the mesh. Only a GGX specular layer
 * exists: the surface is then diffuse × (1 - max(specular)) + GGX (docs/glossy.md). */
typedef struct glow_scene_material {
    char name[64];      /* the mesh's material name (MTL newmtl, glTF material name), 1..63 bytes */
    bool ggx;           /* has a "ggx" object (false: the entry changes nothing) */
    float roughness;    /* GGX perceptual roughness in (0, 1] (α = roughness², glTF); required in "ggx" */
    float specular[3];  /* F0, Schlick's reflectance at normal incidence, each in [0, 1]; default 0.04 */
} glow_scene_material;

/* An HDR environment map ("environment_map" key): an equirectangular (latitude-longitude) image of the
 * radiance arriving from every direction, W/(m²·sr) per texel, linear RGB, +Y up; the image's centre
 * column faces -Z, its left/right edge (u = 0 / 1) faces +Z, u = 0.75 faces +X; the top row looks
 * up (+Y). It ADDS to the constant `environment`. The loader does not open the image (glow-render
 * does, tools/eval/glow_envmap.h); docs/scene-format.md and docs/envmap.md have the details. */
typedef struct glow_scene_environment_map {
    char path[1024];    /* the JSON's "path" joined to the JSON file's folder (absolute stays absolute),
                           1..1023 bytes; "" = no map */
    float rotation_deg; /* turns the map about +Y, right-handed (+Z towards +X); default 0; finite */
    float scale;        /* multiplies every texel; default 1; finite and >= 0 */
} glow_scene_environment_map;

typedef struct glow_scene_desc {
    char *mesh;                 /* owned: "builtin:NAME" as written, else the JSON's "mesh" joined to the
                                   JSON file's folder (absolute stays absolute; relative to the cwd when
                                   the JSON path has no folder) */
    bool has_camera;            /* false: "camera" was absent and `camera` holds the defaults with
                                   position = target = 0: call glow_scene_camera_default */
    glow_scene_camera camera;
    glow_scene_light *lights;   /* owned, light_count entries (NULL when 0) */
    uint32_t light_count;
    float environment[3];       /* constant sky radiance W/(m²·sr), default 0 */
    float emission_scale;       /* default 1; >= 0; pass to glow_system_set_params */
    uint32_t warning_count;     /* unknown keys that were ignored */
    glow_scene_material *materials; /* owned, material_count entries (NULL when 0), in file order */
    uint32_t material_count;
    glow_scene_environment_map environment_map; /* "environment_map"; path "" = none (added in 0.1, at the end) */
} glow_scene_desc;

/**
 * Loads and validates a scene description file.
 *
 * \param path          the JSON file; named in every message as given.
 * \param logger        optional (NULL = none): receives the warnings and the error.
 * \param out_scene     filled on success; zeroed on failure (glow_scene_free is then a no-op).
 * \param message       optional buffer for the error line ("" on success).
 * \param message_size  its size in bytes.
 * \returns GLOW_OK or one of the codes in the header preamble (ON ERRORS).
 * \threadsafety One load at a time per process (cJSON global). \ownership out_scene owns its
 * mesh and lights until glow_scene_free. \since 0.1
 */
GLOW_API glow_result glow_scene_load(const char *path, const glow_logger *logger, glow_scene_desc *out_scene,
                                     char *message, size_t message_size);

/**
 * glow_scene_load on JSON text in memory.
 *
 * \param json      the text (need not be NUL-terminated); \param json_size its length in bytes.
 * \param name      names the document in messages (e.g. "cornell.json"); NULL = "scene".
 * \param base_dir  folder a relative "mesh" is joined to; NULL or "" = keep it relative.
 * \returns as glow_scene_load (never GLOW_ERROR_IO). \since 0.1
 */
GLOW_API glow_result glow_scene_parse(const char *json, size_t json_size, const char *name, const char *base_dir,
                                      const glow_logger *logger, glow_scene_desc *out_scene, char *message,
                                      size_t message_size);

/** Frees what a load allocated and zeroes *scene (NULL and a zeroed desc are no-ops). \since 0.1 */
GLOW_API void glow_scene_free(glow_scene_desc *scene);

/**
 * Checks one light against the schema's rules (type known; finite numbers; intensity/irradiance
 * >= 0; direction non-zero for spot and sun; 0 < outer_deg <= 90 and 0 <= inner_deg <= outer_deg
 * for spot). Used by the loader and by glow_host_set_light.
 *
 * \param what     names the light in the message, e.g. "lights[2]" (NULL = "light").
 * \returns GLOW_OK; GLOW_ERROR_INVALID_ARGUMENT (NULL light or a broken rule: message says which);
 * GLOW_ERROR_UNSUPPORTED for an unknown type. \threadsafety Any thread. \since 0.1
 */
GLOW_API glow_result glow_scene_light_validate(const glow_scene_light *light, const char *what, char *message,
                                               size_t message_size);

/**
 * The default framing for a scene without "camera": looks along -Z at the centre of the box
 * [bounds_min, bounds_max] from far enough (+Z side) that its bounding sphere fits the vertical
 * field of view, up +Y. Keeps camera->vfov_deg, width and height when they are valid (else 60°,
 * 640 x 360). \threadsafety Any thread. \since 0.1
 */
GLOW_API void glow_scene_camera_default(const float bounds_min[3], const float bounds_max[3],
                                        glow_scene_camera *camera);

/** "point", "spot", "sun", or "none" for anything else. \since 0.1 */
GLOW_API const char *glow_scene_light_type_name(glow_scene_light_type type);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_SCENE_H */
