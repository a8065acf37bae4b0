/* test_scene_json.c — the scene description loader (glow_scene.h, docs/scene-format.md): every key and
 * default, every error path with its exact result code and a message naming the file and the
 * problem, the shared scene files, this repository's scenes/ and the examples in the doc itself. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "glow/glow_scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define REPO_DIR GLOW_TEST_DATA_DIR "/../.."

/* A logger that records what it is told. */
typedef struct capture {
    int errors, warnings;
    glow_result last_code;
    char last[768];
} capture;

static void capture_log(void *user, glow_log_level level, glow_result code, const char *message, const char *file,
                        int line) {
    (void)file;
    (void)line;
    capture *c = user;
    if (level == GLOW_LOG_ERROR) c->errors++;
    if (level == GLOW_LOG_WARNING) c->warnings++;
    c->last_code = code;
    snprintf(c->last, sizeof c->last, "%s", message);
}

static glow_result parse(const char *json, glow_scene_desc *s, char *msg, size_t msg_size) {
    return glow_scene_parse(json, strlen(json), "t.json", "/base/dir", NULL, s, msg, msg_size);
}

static void assert_vec3(const float *v, double x, double y, double z, double tol) {
    assert_true(fabs(v[0] - x) <= tol);
    assert_true(fabs(v[1] - y) <= tol);
    assert_true(fabs(v[2] - z) <= tol);
}

static void test_full_document(void **state) {
    (void)state;
    const char *json =
        "{\"_c\": 1, \"mesh\": \"meshes/a.obj\",\n"
        " \"camera\": {\"position\": [1, 2, 3], \"target\": [1, 2, -1], \"up\": [0, 2, 0], \"vfov_deg\": 50,\n"
        "            \"width\": 320, \"height\": 200, \"_note\": \"x\"},\n"
        " \"lights\": [ {\"type\": \"point\", \"position\": [0, 1.5, 0], \"intensity\": [2, 3, 4]},\n"
        "   {\"type\": \"spot\", \"position\": [0, 1.9, 0], \"direction\": [0, -2, 0], \"intensity\": [10, 9, 8],\n"
        "    \"outer_deg\": 40, \"inner_deg\": 30},\n"
        "   {\"type\": \"spot\", \"position\": [1, 1, 1], \"direction\": [1, 0, 0], \"intensity\": [0, 0, 0]},\n"
        "   {\"type\": \"sun\", \"direction\": [0, -3, 4], \"irradiance\": [9, 8.5, 7.5], \"_x\": []} ],\n"
        " \"environment\": [0.25, 0.3, 0.4], \"emission_scale\": 2.5 }";
    glow_scene_desc s;
    char msg[256] = "junk";
    assert_int_equal(parse(json, &s, msg, sizeof msg), GLOW_OK);
    assert_string_equal(msg, "");
    assert_string_equal(s.mesh, "/base/dir/meshes/a.obj");
    assert_true(s.has_camera);
    assert_vec3(s.camera.position, 1, 2, 3, 0);
    assert_vec3(s.camera.target, 1, 2, -1, 0);
    assert_vec3(s.camera.up, 0, 1, 0, 1e-7); /* normalised */
    assert_true(s.camera.vfov_deg == 50.0f);
    assert_int_equal(s.camera.width, 320);
    assert_int_equal(s.camera.height, 200);
    assert_int_equal(s.light_count, 4);
    assert_int_equal(s.lights[0].type, GLOW_SCENE_LIGHT_POINT);
    assert_vec3(s.lights[0].position, 0, 1.5, 0, 0);
    assert_vec3(s.lights[0].intensity, 2, 3, 4, 0);
    assert_int_equal(s.lights[1].type, GLOW_SCENE_LIGHT_SPOT);
    assert_vec3(s.lights[1].direction, 0, -1, 0, 1e-7);
    assert_true(s.lights[1].outer_deg == 40.0f && s.lights[1].inner_deg == 30.0f);
    /* spot defaults: outer 45, inner 0 */
    assert_true(s.lights[2].outer_deg == 45.0f && s.lights[2].inner_deg == 0.0f);
    assert_int_equal(s.lights[3].type, GLOW_SCENE_LIGHT_SUN);
    assert_vec3(s.lights[3].direction, 0, -0.6, 0.8, 1e-7);
    assert_vec3(s.lights[3].irradiance, 9, 8.5, 7.5, 0);
    assert_vec3(s.lights[3].intensity, 0, 0, 0, 0); /* unused fields are zero */
    assert_vec3(s.environment, 0.25, 0.3, 0.4, 1e-7);
    assert_true(s.emission_scale == 2.5f);
    assert_int_equal(s.warning_count, 0);
    glow_scene_free(&s);
    assert_null(s.mesh);
    assert_null(s.lights);
    glow_scene_free(&s); /* twice is fine */
    glow_scene_free(NULL);
}

static void test_defaults_and_paths(void **state) {
    (void)state;
    glow_scene_desc s;
    char msg[256];
    assert_int_equal(parse("{\"mesh\": \"builtin:cornell\"}", &s, msg, sizeof msg), GLOW_OK);
    assert_string_equal(s.mesh, "builtin:cornell"); /* not joined to the base folder */
    assert_false(s.has_camera);
    assert_vec3(s.camera.up, 0, 1, 0, 0);
    assert_true(s.camera.vfov_deg == 60.0f);
    assert_int_equal(s.camera.width, 640);
    assert_int_equal(s.camera.height, 360);
    assert_int_equal(s.light_count, 0);
    assert_null(s.lights);
    assert_vec3(s.environment, 0, 0, 0, 0);
    assert_true(s.emission_scale == 1.0f);
    glow_scene_free(&s);

    assert_int_equal(parse("{\"mesh\": \"/abs/x.obj\", \"lights\": []}", &s, msg, sizeof msg), GLOW_OK);
    assert_string_equal(s.mesh, "/abs/x.obj");
    assert_int_equal(s.light_count, 0);
    glow_scene_free(&s);

    /* camera with only the required keys */
    assert_int_equal(parse("{\"mesh\": \"a\", \"camera\": {\"position\": [0,0,5], \"target\": [0,0,0]}}", &s, msg,
                           sizeof msg),
                     GLOW_OK);
    assert_true(s.has_camera);
    assert_vec3(s.camera.up, 0, 1, 0, 0);
    assert_true(s.camera.vfov_deg == 60.0f);
    assert_int_equal(s.camera.width, 640);
    glow_scene_free(&s);

    /* no base folder: the relative path stays relative (to the cwd); a trailing slash is not doubled */
    const char *j = "{\"mesh\": \"m.obj\"}";
    assert_int_equal(glow_scene_parse(j, strlen(j), NULL, NULL, NULL, &s, NULL, 0), GLOW_OK);
    assert_string_equal(s.mesh, "m.obj");
    glow_scene_free(&s);
    assert_int_equal(glow_scene_parse(j, strlen(j), NULL, "dir/", NULL, &s, NULL, 0), GLOW_OK);
    assert_string_equal(s.mesh, "dir/m.obj");
    glow_scene_free(&s);
}

static void test_unknown_keys_warn(void **state) {
    (void)state;
    capture cap = {0};
    glow_logger lg = {capture_log, &cap};
    const char *j = "{\"mesh\": \"a\", \"meshes\": 1, \"camera\": {\"position\": [0,0,1], \"target\": [0,0,0], "
                    "\"fov\": 3}, \"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": [1,1,1], "
                    "\"irradiance\": [1,1,1]}]}";
    glow_scene_desc s;
    char msg[256];
    assert_int_equal(glow_scene_parse(j, strlen(j), "w.json", NULL, &lg, &s, msg, sizeof msg), GLOW_OK);
    assert_int_equal(s.warning_count, 3);
    assert_int_equal(cap.warnings, 3);
    assert_int_equal(cap.errors, 0);
    assert_int_equal(cap.last_code, GLOW_OK);
    assert_string_equal(cap.last, "w.json: lights[0].irradiance is not a known key; ignored");
    assert_string_equal(msg, ""); /* warnings do not go to the error buffer */
    glow_scene_free(&s);
}

typedef struct bad_case {
    const char *json;
    glow_result code;
    const char *message; /* the full expected message, after "t.json: " */
} bad_case;

#define POINT "{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": [1,1,1]}"
#define CAM(extra) "{\"mesh\": \"a\", \"camera\": {\"position\": [0,0,5], \"target\": [0,0,0]" extra "}}"
#define SPOT(extra) \
    "{\"mesh\": \"a\", \"lights\": [" POINT ", {\"type\": \"spot\", \"position\": [0,0,0], \"direction\": [0,-1,0], " \
    "\"intensity\": [1,1,1]" extra "}]}"

static const bad_case bad_cases[] = {
    {"", GLOW_ERROR_CORRUPT_DATA, "not JSON: the document is empty"},
    {"{\"mesh\": \"a\",\n  \"lights\": [1,]}", GLOW_ERROR_CORRUPT_DATA, "not JSON: syntax error at line 2, column 16"},
    {"not json", GLOW_ERROR_CORRUPT_DATA, "not JSON: syntax error at line 1, column 1"},
    {"{\"mesh\": NaN}", GLOW_ERROR_CORRUPT_DATA, "not JSON: syntax error at line 1, column 10"},
    {"{\"mesh\": \"a\"}\n x", GLOW_ERROR_CORRUPT_DATA, "not JSON: unexpected text after the document at line 2, column 2"},
    {"[1, 2]", GLOW_ERROR_CORRUPT_DATA, "the document must be a JSON object, not an array"},
    {"{}", GLOW_ERROR_INVALID_ARGUMENT, "mesh is required but missing"},
    {"{\"mesh\": 3}", GLOW_ERROR_INVALID_ARGUMENT, "mesh must be a string, not a number"},
    {"{\"mesh\": \"\"}", GLOW_ERROR_INVALID_ARGUMENT, "mesh is an empty string"},
    {"{\"mesh\": \"builtin:\"}", GLOW_ERROR_INVALID_ARGUMENT, "mesh \"builtin:\" names no built-in scene"},
    {"{\"mesh\": \"a\", \"mesh\": \"b\"}", GLOW_ERROR_INVALID_ARGUMENT, "mesh appears twice"},
    {"{\"mesh\": \"a\", \"camera\": [1]}", GLOW_ERROR_INVALID_ARGUMENT, "camera must be an object, not an array"},
    {"{\"mesh\": \"a\", \"camera\": {\"target\": [0,0,0]}}", GLOW_ERROR_INVALID_ARGUMENT,
     "camera.position is required but missing"},
    {"{\"mesh\": \"a\", \"camera\": {\"position\": [0,0,5]}}", GLOW_ERROR_INVALID_ARGUMENT,
     "camera.target is required but missing"},
    {"{\"mesh\": \"a\", \"camera\": {\"position\": [0,5], \"target\": [0,0,0]}}", GLOW_ERROR_INVALID_ARGUMENT,
     "camera.position must have 3 numbers, has 2"},
    {"{\"mesh\": \"a\", \"camera\": {\"position\": [0,\"5\",0], \"target\": [0,0,0]}}", GLOW_ERROR_INVALID_ARGUMENT,
     "camera.position[1] must be a number, not a string"},
    {"{\"mesh\": \"a\", \"camera\": {\"position\": {}, \"target\": [0,0,0]}}", GLOW_ERROR_INVALID_ARGUMENT,
     "camera.position must be an array of 3 numbers, not an object"},
    {CAM(", \"vfov_deg\": 0"), GLOW_ERROR_INVALID_ARGUMENT, "camera.vfov_deg (0) is outside (0, 180)"},
    {CAM(", \"vfov_deg\": 180"), GLOW_ERROR_INVALID_ARGUMENT, "camera.vfov_deg (180) is outside (0, 180)"},
    {CAM(", \"vfov_deg\": true"), GLOW_ERROR_INVALID_ARGUMENT, "camera.vfov_deg must be a number, not a boolean"},
    {CAM(", \"width\": 1.5"), GLOW_ERROR_INVALID_ARGUMENT, "camera.width (1.5) must be a whole number in 1..16384"},
    {CAM(", \"width\": 0"), GLOW_ERROR_INVALID_ARGUMENT, "camera.width (0) must be a whole number in 1..16384"},
    {CAM(", \"height\": 20000"), GLOW_ERROR_INVALID_ARGUMENT, "camera.height (20000) must be a whole number in 1..16384"},
    {CAM(", \"height\": null"), GLOW_ERROR_INVALID_ARGUMENT, "camera.height must be a number, not null"},
    {CAM(", \"up\": [0,0,0]"), GLOW_ERROR_INVALID_ARGUMENT, "camera.up [0, 0, 0] has zero length"},
    {CAM(", \"up\": [0,0,-3]"), GLOW_ERROR_INVALID_ARGUMENT,
     "camera.up is parallel to the view direction (target - position)"},
    {"{\"mesh\": \"a\", \"camera\": {\"position\": [1,2,3], \"target\": [1,2,3]}}", GLOW_ERROR_INVALID_ARGUMENT,
     "camera.target equals camera.position"},
    {CAM(", \"width\": 10, \"width\": 20"), GLOW_ERROR_INVALID_ARGUMENT, "camera.width appears twice"},
    {"{\"mesh\": \"a\", \"lights\": {}}", GLOW_ERROR_INVALID_ARGUMENT, "lights must be an array, not an object"},
    {"{\"mesh\": \"a\", \"lights\": [" POINT ", 7]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[1] must be an object, not a number"},
    {"{\"mesh\": \"a\", \"lights\": [{\"position\": [0,0,0]}]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[0].type is required but missing"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": 1}]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[0].type must be a string, not a number"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"area\"}]}", GLOW_ERROR_UNSUPPORTED,
     "lights[0].type \"area\" is not a light type (valid: point, spot, sun)"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"point\", \"intensity\": [1,1,1]}]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[0].position is required but missing"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"point\", \"position\": [0,0,0]}]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[0].intensity is required but missing"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": [1,1,-1]}]}",
     GLOW_ERROR_INVALID_ARGUMENT, "lights[0].intensity[2] (-1) is negative"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": [1e999,1,1]}]}",
     GLOW_ERROR_INVALID_ARGUMENT, "lights[0].intensity[0] is not a finite number (inf)"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"point\", \"position\": [0,-1e39,0], \"intensity\": [1,1,1]}]}",
     GLOW_ERROR_INVALID_ARGUMENT, "lights[0].position[1] is not a finite number (-1e+39)"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": [1,1]}]}",
     GLOW_ERROR_INVALID_ARGUMENT, "lights[0].intensity must have 3 numbers, has 2"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"point\", \"type\": \"sun\"}]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[0].type appears twice"},
    {SPOT(", \"outer_deg\": 40, \"inner_deg\": 50"), GLOW_ERROR_INVALID_ARGUMENT,
     "lights[1].inner_deg (50) > outer_deg (40)"},
    {SPOT(", \"inner_deg\": 50"), GLOW_ERROR_INVALID_ARGUMENT, "lights[1].inner_deg (50) > outer_deg (45)"},
    {SPOT(", \"outer_deg\": 120"), GLOW_ERROR_INVALID_ARGUMENT, "lights[1].outer_deg (120) is outside (0, 90]"},
    {SPOT(", \"outer_deg\": 0"), GLOW_ERROR_INVALID_ARGUMENT, "lights[1].outer_deg (0) is outside (0, 90]"},
    {SPOT(", \"inner_deg\": -1"), GLOW_ERROR_INVALID_ARGUMENT, "lights[1].inner_deg (-1) is negative"},
    {SPOT(", \"outer_deg\": \"40\""), GLOW_ERROR_INVALID_ARGUMENT, "lights[1].outer_deg must be a number, not a string"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"spot\", \"position\": [0,0,0], \"direction\": [0,0,0], "
     "\"intensity\": [1,1,1]}]}",
     GLOW_ERROR_INVALID_ARGUMENT, "lights[0].direction [0, 0, 0] has zero length"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"spot\", \"position\": [0,0,0], \"intensity\": [1,1,1]}]}",
     GLOW_ERROR_INVALID_ARGUMENT, "lights[0].direction is required but missing"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"sun\", \"direction\": [0,-1,0]}]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[0].irradiance is required but missing"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"sun\", \"irradiance\": [1,1,1]}]}", GLOW_ERROR_INVALID_ARGUMENT,
     "lights[0].direction is required but missing"},
    {"{\"mesh\": \"a\", \"lights\": [{\"type\": \"sun\", \"direction\": [0,-1,0], \"irradiance\": [1,-1,1]}]}",
     GLOW_ERROR_INVALID_ARGUMENT, "lights[0].irradiance[1] (-1) is negative"},
    {"{\"mesh\": \"a\", \"environment\": [1,1,1,1]}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment must have 3 numbers, has 4"},
    {"{\"mesh\": \"a\", \"environment\": [1,-0.5,1]}", GLOW_ERROR_INVALID_ARGUMENT, "environment[1] (-0.5) is negative"},
    {"{\"mesh\": \"a\", \"environment\": 1}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment must be an array of 3 numbers, not a number"},
    {"{\"mesh\": \"a\", \"emission_scale\": -1}", GLOW_ERROR_INVALID_ARGUMENT, "emission_scale (-1) is negative"},
    {"{\"mesh\": \"a\", \"emission_scale\": [1]}", GLOW_ERROR_INVALID_ARGUMENT,
     "emission_scale must be a number, not an array"},
    {"{\"mesh\": \"a\", \"materials\": []}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials must be an object (material name -> override), not an array"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": 1}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor must be an object, not a number"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {}}}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor.ggx.roughness is required but missing"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {\"roughness\": 0}}}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor.ggx.roughness (0) is outside (0, 1]"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {\"roughness\": 1.5}}}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor.ggx.roughness (1.5) is outside (0, 1]"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {\"roughness\": 1e999}}}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor.ggx.roughness is not a finite number (inf)"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {\"roughness\": \"0.3\"}}}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor.ggx.roughness must be a number, not a string"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {\"roughness\": 0.3, \"specular\": [0.04, 1.2, 0]}}}}",
     GLOW_ERROR_INVALID_ARGUMENT, "materials.floor.ggx.specular[1] (1.2) is above 1"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {\"roughness\": 0.3, \"specular\": [0.04, -1, 0]}}}}",
     GLOW_ERROR_INVALID_ARGUMENT, "materials.floor.ggx.specular[1] (-1) is negative"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": {\"roughness\": 0.3, \"specular\": [0.04]}}}}",
     GLOW_ERROR_INVALID_ARGUMENT, "materials.floor.ggx.specular must have 3 numbers, has 1"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {\"ggx\": 0.3}}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor.ggx must be an object, not a number"},
    {"{\"mesh\": \"a\", \"materials\": {\"floor\": {}, \"floor\": {}}}", GLOW_ERROR_INVALID_ARGUMENT,
     "materials.floor appears twice"},
    {"{\"mesh\": \"a\", \"materials\": {\"\": {}}}", GLOW_ERROR_INVALID_ARGUMENT, "materials has an empty material name"},
    {"{\"mesh\": \"a\", \"environment_map\": \"sky.exr\"}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment_map must be an object ({\"path\": ...}), not a string"},
    {"{\"mesh\": \"a\", \"environment_map\": {}}", GLOW_ERROR_INVALID_ARGUMENT, "environment_map.path is required but missing"},
    {"{\"mesh\": \"a\", \"environment_map\": {\"path\": \"\"}}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment_map.path is an empty string"},
    {"{\"mesh\": \"a\", \"environment_map\": {\"path\": 3}}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment_map.path must be a string, not a number"},
    {"{\"mesh\": \"a\", \"environment_map\": {\"path\": \"s.exr\", \"scale\": -0.5}}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment_map.scale (-0.5) is negative"},
    {"{\"mesh\": \"a\", \"environment_map\": {\"path\": \"s.exr\", \"scale\": 1e999}}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment_map.scale is not a finite number (inf)"},
    {"{\"mesh\": \"a\", \"environment_map\": {\"path\": \"s.exr\", \"rotation_deg\": -1e999}}",
     GLOW_ERROR_INVALID_ARGUMENT, "environment_map.rotation_deg is not a finite number (-inf)"},
    {"{\"mesh\": \"a\", \"environment_map\": {\"path\": \"s.exr\", \"rotation_deg\": \"90\"}}",
     GLOW_ERROR_INVALID_ARGUMENT, "environment_map.rotation_deg must be a number, not a string"},
    {"{\"mesh\": \"a\", \"environment_map\": {\"path\": \"s.exr\", \"path\": \"t.exr\"}}", GLOW_ERROR_INVALID_ARGUMENT,
     "environment_map.path appears twice"},
};

static void test_bad_input(void **state) {
    (void)state;
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; ++i) {
        const bad_case *b = &bad_cases[i];
        glow_scene_desc s;
        char msg[512], want[600];
        capture cap = {0};
        glow_logger lg = {capture_log, &cap};
        glow_result r = glow_scene_parse(b->json, strlen(b->json), "t.json", "/base", &lg, &s, msg, sizeof msg);
        snprintf(want, sizeof want, "t.json: %s", b->message);
        if (r != b->code || strcmp(msg, want) != 0)
            fail_msg("case %zu (%s): got %d \"%s\", want %d \"%s\"", i, b->json, (int)r, msg, (int)b->code, want);
        /* the logger hears the same line with the same code */
        assert_int_equal(cap.errors, 1);
        assert_int_equal(cap.last_code, b->code);
        assert_string_equal(cap.last, want);
        /* nothing left behind (ASan checks the leak) */
        assert_null(s.mesh);
        assert_null(s.lights);
        assert_int_equal(s.light_count, 0);
        assert_null(s.materials);
        assert_int_equal(s.material_count, 0);
    }
    /* a tiny message buffer truncates, a NULL one is fine */
    glow_scene_desc s;
    char small[8];
    assert_int_equal(parse("{}", &s, small, sizeof small), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(small, "t.json:");
    assert_int_equal(parse("{}", &s, NULL, 0), GLOW_ERROR_INVALID_ARGUMENT);
    /* NULL arguments */
    char msg[256];
    assert_int_equal(glow_scene_parse("{}", 2, "t.json", NULL, NULL, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_scene_load(NULL, NULL, &s, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(glow_scene_load("x.json", NULL, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
}

/* "materials": per-material GGX layers by name, optional; comments skipped; unknown keys warned. */
static void test_materials(void **state) {
    (void)state;
    glow_scene_desc s;
    char msg[512];
    capture cap = {0};
    glow_logger lg = {capture_log, &cap};
    const char *json = "{\"mesh\": \"a\", \"materials\": {\"_c\": 1, \"floor\": {\"ggx\": {\"roughness\": 0.3}},"
                       " \"metal\": {\"ggx\": {\"roughness\": 1, \"specular\": [0.9, 0.6, 0.2], \"ior\": 1.5}},"
                       " \"plain\": {}}}";
    assert_int_equal(glow_scene_parse(json, strlen(json), "t.json", NULL, &lg, &s, msg, sizeof msg), GLOW_OK);
    assert_int_equal(s.material_count, 3);
    assert_string_equal(s.materials[0].name, "floor");
    assert_true(s.materials[0].ggx);
    assert_true(s.materials[0].roughness == 0.3f);
    assert_vec3(s.materials[0].specular, 0.04, 0.04, 0.04, 1e-7);
    assert_string_equal(s.materials[1].name, "metal");
    assert_vec3(s.materials[1].specular, 0.9, 0.6, 0.2, 1e-7);
    assert_true(s.materials[1].roughness == 1.0f);
    assert_string_equal(s.materials[2].name, "plain");
    assert_false(s.materials[2].ggx);
    assert_int_equal(s.warning_count, 1); /* "ior" */
    assert_non_null(strstr(cap.last, "materials.metal.ggx.ior is not a known key"));
    glow_scene_free(&s);
    assert_null(s.materials);
    /* without the key: none; an empty object: none */
    assert_int_equal(parse("{\"mesh\": \"a\", \"materials\": {}}", &s, msg, sizeof msg), GLOW_OK);
    assert_int_equal(s.material_count, 0);
    assert_null(s.materials);
    glow_scene_free(&s);
    /* a name of 64 bytes does not fit */
    char long_json[256];
    snprintf(long_json, sizeof long_json, "{\"mesh\": \"a\", \"materials\": {\"%064d\": {}}}", 7);
    assert_int_equal(parse(long_json, &s, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "the material name is longer than 63 bytes"));
    /* the repository's glossy scene */
    assert_int_equal(glow_scene_load(REPO_DIR "/scenes/cornell-builtin-glossy.json", NULL, &s, msg, sizeof msg), GLOW_OK);
    assert_int_equal(s.material_count, 1);
    assert_string_equal(s.materials[0].name, "floor");
    assert_int_equal(s.warning_count, 0);
    glow_scene_free(&s);
}

static void write_file(const char *path, const char *text) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void test_files(void **state) {
    (void)state;
    char dir[128], path[256], msg[512], want[512];
    snprintf(dir, sizeof dir, "/tmp/glow_scene_json_%d", (int)getpid());
    assert_int_equal(mkdir(dir, 0700), 0);
    glow_scene_desc s;

    snprintf(path, sizeof path, "%s/missing.json", dir);
    assert_int_equal(glow_scene_load(path, NULL, &s, msg, sizeof msg), GLOW_ERROR_IO);
    snprintf(want, sizeof want, "%s: cannot open the file", path);
    assert_string_equal(msg, want);

    snprintf(path, sizeof path, "%s/ok.json", dir);
    write_file(path, "{\"mesh\": \"sub/m.obj\", \"emission_scale\": 0}\n");
    assert_int_equal(glow_scene_load(path, NULL, &s, msg, sizeof msg), GLOW_OK);
    snprintf(want, sizeof want, "%s/sub/m.obj", dir);
    assert_string_equal(s.mesh, want);
    assert_true(s.emission_scale == 0.0f);
    glow_scene_free(&s);
    unlink(path);

    snprintf(path, sizeof path, "%s/bad.json", dir);
    write_file(path, "{\"mesh\": \"m.obj\",\n \"lights\": [{\"type\": \"spot\", \"position\": [0,0,0], "
                     "\"direction\": [0,-1,0], \"intensity\": [1,1,1], \"outer_deg\": 40, \"inner_deg\": 50}]}");
    assert_int_equal(glow_scene_load(path, NULL, &s, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    snprintf(want, sizeof want, "%s: lights[0].inner_deg (50) > outer_deg (40)", path);
    assert_string_equal(msg, want);
    unlink(path);

    /* a directory is not a readable file */
    assert_int_not_equal(glow_scene_load(dir, NULL, &s, msg, sizeof msg), GLOW_OK);
    assert_non_null(strstr(msg, dir));
    assert_int_equal(rmdir(dir), 0);
}

static bool file_exists(const char *p) {
    FILE *f = fopen(p, "rb");
    if (!f) return false;
    fclose(f);
    return true;
}

static void test_shared_scenes(void **state) {
    (void)state;
    const char *cornell = GLOW_SHARED_DIR "/scenes/cornell-box/cornell.json";
    const char *sponza = GLOW_SHARED_DIR "/scenes/sponza/sponza-sun.json";
    if (!file_exists(cornell) || !file_exists(sponza)) skip();
    glow_scene_desc s;
    char msg[512];
    assert_int_equal(glow_scene_load(cornell, NULL, &s, msg, sizeof msg), GLOW_OK);
    assert_non_null(strstr(s.mesh, "cornell-box/CornellBox-Original.obj"));
    assert_true(file_exists(s.mesh));
    assert_true(s.has_camera);
    assert_vec3(s.camera.position, 0, 1, 3.9, 1e-6);
    assert_true(fabsf(s.camera.vfov_deg - 39.3077f) < 1e-4f);
    assert_int_equal(s.camera.width, 256);
    assert_int_equal(s.light_count, 0);
    assert_true(s.emission_scale == 1.0f);
    assert_int_equal(s.warning_count, 0);
    glow_scene_free(&s);

    assert_int_equal(glow_scene_load(sponza, NULL, &s, msg, sizeof msg), GLOW_OK);
    assert_non_null(strstr(s.mesh, "sponza/dabrovic/sponza.obj"));
    assert_true(file_exists(s.mesh));
    assert_int_equal(s.light_count, 1);
    assert_int_equal(s.lights[0].type, GLOW_SCENE_LIGHT_SUN);
    double len = sqrt(0.2 * 0.2 + 1.0 + 0.3 * 0.3);
    assert_vec3(s.lights[0].direction, 0.2 / len, -1.0 / len, 0.3 / len, 1e-6);
    assert_vec3(s.lights[0].irradiance, 9.0, 8.5, 7.5, 0);
    assert_vec3(s.environment, 0.25, 0.3, 0.4, 1e-7);
    assert_int_equal(s.camera.width, 320);
    assert_int_equal(s.camera.height, 180);
    assert_int_equal(s.warning_count, 0);
    glow_scene_free(&s);
}

static void test_repo_scenes(void **state) {
    (void)state;
    glow_scene_desc s;
    char msg[512];
    assert_int_equal(glow_scene_load(REPO_DIR "/scenes/cornell-builtin.json", NULL, &s, msg, sizeof msg), GLOW_OK);
    assert_string_equal(s.mesh, "builtin:cornell");
    assert_true(s.has_camera);
    assert_int_equal(s.light_count, 0);
    assert_int_equal(s.warning_count, 0);
    /* the camera is inside the closed room (x, z in [-1, 1], y in [0, 2]) and sees the whole back wall */
    for (int i = 0; i < 3; ++i) assert_true(s.camera.position[i] > (i == 1 ? 0.0f : -1.0f) && s.camera.position[i] < (i == 1 ? 2.0f : 1.0f));
    double half = atan(1.0 / (s.camera.position[2] + 1.0)) * 180.0 / M_PI;
    assert_true(s.camera.vfov_deg >= 2.0 * half);
    glow_scene_free(&s);

    assert_int_equal(glow_scene_load(REPO_DIR "/scenes/cornell-builtin-point.json", NULL, &s, msg, sizeof msg), GLOW_OK);
    assert_int_equal(s.light_count, 1);
    assert_int_equal(s.lights[0].type, GLOW_SCENE_LIGHT_POINT);
    /* the lamp's on-axis intensity: radiance (17, 12, 4) x area 0.48 x 0.44 m² */
    assert_vec3(s.lights[0].intensity, 17 * 0.2112, 12 * 0.2112, 4 * 0.2112, 1e-5);
    assert_true(s.emission_scale == 0.0f);
    glow_scene_free(&s);
}

/* Every ```json block of docs/scene-format.md parses without warnings. */
static void test_doc_examples(void **state) {
    (void)state;
    FILE *f = fopen(REPO_DIR "/docs/scene-format.md", "rb");
    assert_non_null(f);
    static char doc[65536];
    size_t n = fread(doc, 1, sizeof doc - 1, f);
    fclose(f);
    doc[n] = '\0';
    int blocks = 0;
    for (const char *p = doc; (p = strstr(p, "```json\n")) != NULL;) {
        p += 8;
        const char *end = strstr(p, "```");
        assert_non_null(end);
        glow_scene_desc s;
        char msg[512];
        glow_result r = glow_scene_parse(p, (size_t)(end - p), "scene-format.md", NULL, NULL, &s, msg, sizeof msg);
        if (r != GLOW_OK) fail_msg("doc example %d: %s", blocks, msg);
        assert_int_equal(s.warning_count, 0);
        glow_scene_free(&s);
        blocks++;
        p = end + 3;
    }
    assert_int_equal(blocks, 2);
}

/* "environment_map": the path joined to the JSON's folder, rotation and scale with their defaults, the
 * length limit of the fixed-size path, unknown keys warned about. */
static void test_environment_map(void **state) {
    (void)state;
    glow_scene_desc s;
    char msg[512];
    /* absent: no path, scale 1 */
    assert_int_equal(parse("{\"mesh\": \"a\"}", &s, msg, sizeof msg), GLOW_OK);
    assert_string_equal(s.environment_map.path, "");
    assert_true(s.environment_map.scale == 1.0f && s.environment_map.rotation_deg == 0.0f);
    glow_scene_free(&s);
    /* defaults, and the path joined to the base folder */
    assert_int_equal(parse("{\"mesh\": \"a\", \"environment\": [0.1, 0.2, 0.3], \"environment_map\": {\"path\": \"skies/s.exr\"}}",
                           &s, msg, sizeof msg),
                     GLOW_OK);
    assert_string_equal(s.environment_map.path, "/base/dir/skies/s.exr");
    assert_true(s.environment_map.scale == 1.0f && s.environment_map.rotation_deg == 0.0f);
    assert_vec3(s.environment, 0.1, 0.2, 0.3, 1e-7); /* coexists with the constant sky */
    glow_scene_free(&s);
    /* every key; an absolute path stays; scale 0 is allowed (a switched-off sky) */
    capture cap = {0};
    glow_logger lg = {capture_log, &cap};
    const char *json = "{\"mesh\": \"a\", \"environment_map\": {\"path\": \"/abs/s.exr\", \"rotation_deg\": -90.5,"
                       " \"scale\": 0, \"_c\": 1, \"gamma\": 2.2}}";
    assert_int_equal(glow_scene_parse(json, strlen(json), "t.json", "/base", &lg, &s, msg, sizeof msg), GLOW_OK);
    assert_string_equal(s.environment_map.path, "/abs/s.exr");
    assert_true(s.environment_map.rotation_deg == -90.5f && s.environment_map.scale == 0.0f);
    assert_int_equal(s.warning_count, 1);
    assert_string_equal(cap.last, "t.json: environment_map.gamma is not a known key; ignored");
    glow_scene_free(&s);
    /* no base folder: kept relative */
    json = "{\"mesh\": \"a\", \"environment_map\": {\"path\": \"s.exr\", \"scale\": 2.5}}";
    assert_int_equal(glow_scene_parse(json, strlen(json), "t.json", NULL, NULL, &s, msg, sizeof msg), GLOW_OK);
    assert_string_equal(s.environment_map.path, "s.exr");
    assert_true(s.environment_map.scale == 2.5f);
    glow_scene_free(&s);
    /* too long for the fixed-size path: 1023 bytes fit, 1024 do not (with the folder) */
    static char big[2200], name[1100];
    memset(name, 'x', sizeof name);
    name[1023 - 10] = '\0'; /* "/base/dir/" (10) + 1013 = 1023 */
    snprintf(big, sizeof big, "{\"mesh\": \"a\", \"environment_map\": {\"path\": \"%s\"}}", name);
    assert_int_equal(parse(big, &s, msg, sizeof msg), GLOW_OK);
    assert_int_equal(strlen(s.environment_map.path), 1023);
    glow_scene_free(&s);
    name[1023 - 10] = 'x';
    name[1024 - 10] = '\0';
    snprintf(big, sizeof big, "{\"mesh\": \"a\", \"environment_map\": {\"path\": \"%s\"}}", name);
    assert_int_equal(parse(big, &s, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(msg, "t.json: environment_map.path is too long (1024 bytes with the scene's folder, at most 1023)");
    assert_string_equal(s.environment_map.path, "");
}

static void test_light_validate(void **state) {
    (void)state;
    char msg[256];
    glow_scene_light l = {.type = GLOW_SCENE_LIGHT_SPOT, .direction = {0, -1, 0}, .intensity = {1, 1, 1},
                          .outer_deg = 30, .inner_deg = 10};
    assert_int_equal(glow_scene_light_validate(&l, "lights[3]", msg, sizeof msg), GLOW_OK);
    assert_string_equal(msg, "");
    l.inner_deg = 31;
    assert_int_equal(glow_scene_light_validate(&l, "lights[3]", msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(msg, "lights[3]: inner_deg (31) > outer_deg (30)");
    l.inner_deg = NAN;
    assert_int_equal(glow_scene_light_validate(&l, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(msg, "light: inner_deg (nan) is negative or not finite");
    l.inner_deg = 0;
    l.position[0] = INFINITY;
    assert_int_equal(glow_scene_light_validate(&l, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(msg, "light: position is not finite");
    l.position[0] = 0;
    l.direction[1] = 0;
    assert_int_equal(glow_scene_light_validate(&l, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(msg, "light: direction [0, 0, 0] has zero length");
    glow_scene_light sun = {.type = GLOW_SCENE_LIGHT_SUN, .direction = {0, -1, 0}, .irradiance = {1, NAN, 1}};
    assert_int_equal(glow_scene_light_validate(&sun, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(msg, "light: irradiance is not finite");
    sun.irradiance[1] = 1;
    sun.intensity[0] = -5; /* unused by a sun: not checked */
    assert_int_equal(glow_scene_light_validate(&sun, NULL, msg, sizeof msg), GLOW_OK);
    glow_scene_light bad = {.type = (glow_scene_light_type)7};
    assert_int_equal(glow_scene_light_validate(&bad, NULL, msg, sizeof msg), GLOW_ERROR_UNSUPPORTED);
    assert_int_equal(glow_scene_light_validate(NULL, NULL, msg, sizeof msg), GLOW_ERROR_INVALID_ARGUMENT);
    assert_string_equal(glow_scene_light_type_name(GLOW_SCENE_LIGHT_SPOT), "spot");
    assert_string_equal(glow_scene_light_type_name((glow_scene_light_type)9), "none");
}

static void test_camera_default(void **state) {
    (void)state;
    glow_scene_camera cam = {.vfov_deg = 90.0f, .width = 100, .height = 50};
    const float lo[3] = {-1, 0, -2}, hi[3] = {1, 2, 2};
    glow_scene_camera_default(lo, hi, &cam);
    assert_true(cam.vfov_deg == 90.0f);
    assert_int_equal(cam.width, 100);
    assert_int_equal(cam.height, 50);
    assert_vec3(cam.target, 0, 1, 0, 0);
    assert_vec3(cam.up, 0, 1, 0, 0);
    /* radius sqrt(1 + 1 + 4) = sqrt 6 at sin(45°) */
    assert_vec3(cam.position, 0, 1, sqrt(6.0) / sin(M_PI / 4), 1e-5);
    glow_scene_camera junk = {.vfov_deg = NAN};
    glow_scene_camera_default(lo, hi, &junk);
    assert_true(junk.vfov_deg == 60.0f);
    assert_int_equal(junk.width, 640);
    assert_int_equal(junk.height, 360);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_document), cmocka_unit_test(test_defaults_and_paths),
        cmocka_unit_test(test_unknown_keys_warn), cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_files), cmocka_unit_test(test_shared_scenes),
        cmocka_unit_test(test_repo_scenes), cmocka_unit_test(test_doc_examples),
        cmocka_unit_test(test_light_validate), cmocka_unit_test(test_camera_default), cmocka_unit_test(test_materials),
        cmocka_unit_test(test_environment_map),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
