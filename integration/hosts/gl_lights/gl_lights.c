/* gl_lights.c — glow_gl_lights (glow_gl_lights.h): GPU shadow-mapped lights as Glow's GLSL surfel
 * lighting hook.
 *
 * The maps are placed exactly as glow_host's software maps (integration/hosts/cpu/shadow_map.c: the same
 * bases, texel sizes, margins and near plane, set up here in the same float arithmetic), rendered by
 * the GPU rasteriser (pixel centres, like the software one) into GL_DEPTH_COMPONENT32F array layers
 * with the view-axis distance written by the fragment shader, and read by the hook
 * (gl_lights_hook.glsl) with the software lookup's arithmetic. Everything the hook needs besides the
 * maps is one std140 uniform block, rewritten by every set(). */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "glow/glow_gl_lights.h"
#include "glow/glow_glfns.h"
#include "host_math.h"
#include "host_log.h"
#include "shadow_map.h" /* the software maps' placement: the texel grids must coincide */

#define GLL_PI 3.14159265358979323846
#define SPOT_MAX_SINGLE_MAP_DEG 60.0f /* as glow_host: wider spots get a cube */
#define DEFAULT_MAX_LIGHTS 8u
#define FIRST_FREE_BINDING 8u        /* Glow's kernels use buffer bindings 0..7 and no texture units */

extern const char glow__gl_lights_hook_glsl[]; /* gl_lights_hook.glsl, embedded by CMakeLists.txt */

/* ------------------------------------------------------------------- the uniform block (std140) */

typedef struct ubo_light {
    float position[4];  /* xyz; w unused */
    float direction[4]; /* xyz unit; w: cos(outer) */
    float power[4];     /* rgb; w: cos(inner) */
    int32_t info[4];    /* type, first map, map count (0, 1, 6), unused */
} ubo_light;

typedef struct ubo_map {
    float origin[4];    /* w: 1 = perspective */
    float ax[4];        /* w: inv_s */
    float ay[4];        /* w: texel */
    float az[4];        /* w: near_z */
    float params[4];    /* off_x, off_y, depth at stored 0, depth range */
    int32_t info[4];    /* resolution, layer, array (0 maps, 1 cube faces), unused */
} ubo_map;

typedef struct ubo_head {
    float environment[4]; /* rgb · π; w: 1 = the sky is sky_sh (glow_gl_lights_set_environment_sh) */
    float shadow[4];      /* depth_bias, slope_bias, normal_offset, unused */
    int32_t counts[4];    /* lights, PCF radius, per-surfel sky values S (0 = none), per-surfel sky transfers T
                             (0 = none; the SSBO holds S[counts[2]] then T[counts[3]][9]) */
    float sky_sh[9][4];   /* the sky's radiance SH, rgb per coefficient (docs/sky.md) */
} ubo_head;

_Static_assert(sizeof(ubo_light) == 64, "std140 light");
_Static_assert(sizeof(ubo_map) == 96, "std140 map");
_Static_assert(sizeof(ubo_head) == 192, "std140 head");

/* --------------------------------------------------------------------------------- the object */

struct glow_gl_lights {
    glow_glfns gl;
    glow_logger logger;
    uint32_t max_lights, max_maps;
    uint32_t sm_size, cube_size;
    float depth_bias, slope_bias, normal_offset;
    int pcf_radius;
    uint32_t ubo_binding, unit_maps, unit_cube;
    uint32_t tri_count;
    float bmin[3], bmax[3], diag;
    GLuint vbo, vao, prog, fbo, ubo;
    GLuint sky;             /* SSBO float[sky_count + 9 transfer_count]: per-surfel sky visibility S, then
                               per-surfel sky transfer T (0 = none) */
    uint32_t sky_count, transfer_count;
    float *sky_s, *sky_t;   /* host copies of S and T, uploaded together (upload_sky) */
    bool sh_on;
    float sh[9][4];
    GLuint tex[2];          /* [0] sun / spot maps (sm_size), [1] cube faces (cube_size) */
    uint32_t tex_layers[2]; /* layers allocated; 0 = a 1 x 1 x 1 placeholder */
    GLint loc_origin, loc_ax, loc_ay, loc_az, loc_proj, loc_depth;
    size_t ubo_size;
    unsigned char *staging; /* ubo_size bytes */
    char *hook;
    uint32_t light_count, map_count;
    double set_ms;
};

/* One depth map's placement (glow__depth_map's, from shadow_map.c) and where it lives. */
typedef struct map_setup {
    bool persp;
    float origin[3], ax[3], ay[3], az[3];
    float inv_s, off_x, off_y, texel, near_z;
    float depth_lo, depth_range; /* stored depth d in [0, 1] means z = depth_lo + d · depth_range */
    uint32_t res, layer, array;
} map_setup;

/* ------------------------------------------------------------------------------------ helpers */

/* logf_(logger, level, code, fmt, ...): host_log.h with this file's prefix and the caller's line */
#define logf_(lg, level, code, ...) glow__host_log((lg), "glow_gl_lights: ", (level), (code), __FILE__, __LINE__, __VA_ARGS__)
#define GLL_FAIL(lg, code, ...) logf_((lg), GLOW_LOG_ERROR, (code), __VA_ARGS__)

#define now_ms glow__host_now_ms


/* GL errors raised since the last call, folded into one code (OUT_OF_MEMORY wins). */
static GLenum drain_errors(const glow_glfns *gl) {
    GLenum first = GL_NO_ERROR;
    for (int i = 0; i < 32; ++i) {
        GLenum e = gl->GetError();
        if (e == GL_NO_ERROR) break;
        if (first == GL_NO_ERROR || e == GL_OUT_OF_MEMORY) first = e;
    }
    return first;
}

/* ------------------------------------------------------------------------------ map placement */

/* The software maps' placement (shadow_map.c: the same axes, texel grid, margins and near plane, by
 * construction), plus where a stored depth in [0, 1] lies along the view axis. */
static void from_depth_map(map_setup *m, const glow__depth_map *dm) {
    memset(m, 0, sizeof *m);
    m->persp = dm->persp;
    memcpy(m->origin, dm->origin, sizeof m->origin);
    memcpy(m->ax, dm->ax, sizeof m->ax);
    memcpy(m->ay, dm->ay, sizeof m->ay);
    memcpy(m->az, dm->az, sizeof m->az);
    m->inv_s = dm->inv_s, m->off_x = dm->off_x, m->off_y = dm->off_y;
    m->texel = dm->texel, m->near_z = dm->near_z, m->res = dm->res;
}

/* Orthographic: the depth range is the box's extent along the view axis with 1 % to spare. */
static void setup_ortho(map_setup *m, const float dir[3], const float bmin[3], const float bmax[3], uint32_t res,
                        uint32_t margin) {
    glow__depth_map dm = {0};
    glow__dm_setup_ortho(&dm, dir, bmin, bmax, res, margin);
    from_depth_map(m, &dm);
    const float zlo = dm.box_z[0], zhi = dm.box_z[1];
    float pad = 0.01f * (zhi - zlo) + 1e-6f * dm.extent + 1e-30f;
    m->depth_lo = zlo - pad;
    m->depth_range = (zhi + pad) - m->depth_lo;
}

/* Perspective: depth range [0, far], far = the farthest box corner along the view axis (geometry beyond
 * it cannot exist). */
static void setup_persp(map_setup *m, const float eye[3], const float axis[3], float tan_half, uint32_t res,
                        uint32_t margin, float near_z, const float bmin[3], const float bmax[3]) {
    glow__depth_map dm = {0};
    glow__dm_setup_persp(&dm, eye, axis, tan_half, res, margin, near_z);
    from_depth_map(m, &dm);
    float far_z = 0.0f;
    for (int c = 0; c < 8; ++c) {
        float p[3] = {(c & 1 ? bmax[0] : bmin[0]) - eye[0], (c & 2 ? bmax[1] : bmin[1]) - eye[1],
                      (c & 4 ? bmax[2] : bmin[2]) - eye[2]};
        far_z = fmaxf(far_z, glow__dot3(p, m->az));
    }
    far_z = fmaxf(far_z * 1.01f + near_z, 2.0f * near_z);
    m->depth_lo = 0.0f;
    m->depth_range = far_z;
}

/* ---------------------------------------------------------------------------------- shaders */

static const char *const DEPTH_VS =
    "#version 450 core\n"
    "// glow_gl_lights depth pass: the view-axis distance of every bake triangle, both faces.\n"
    "layout(location = 0) in vec3 a_position;\n"
    "uniform vec4 u_origin, u_ax, u_ay, u_az; // the map's eye / centre and axes (xyz)\n"
    "uniform vec4 u_proj;  // x: xy scale, y, z: xy offset, w: 1 = perspective (divide by z)\n"
    "uniform vec4 u_depth; // x: depth at stored 0, y: 1 / depth range, z: near plane, w: clip y sign\n"
    "out float v_z;\n"
    "out gl_PerVertex { vec4 gl_Position; float gl_ClipDistance[1]; };\n"
    "void main() {\n"
    "    vec3 q = a_position - u_origin.xyz;\n"
    "    vec3 v = vec3(dot(q, u_ax.xyz), dot(q, u_ay.xyz), dot(q, u_az.xyz));\n"
    "    vec2 xy = v.xy * u_proj.x + u_proj.yz;\n"
    "    float w = u_proj.w > 0.5 ? v.z : 1.0;\n"
    "    v_z = v.z;\n"
    "    gl_Position = vec4(xy.x, xy.y * u_depth.w, 0.5 * w, w); // clip z mid-range: no depth clipping\n"
    "    gl_ClipDistance[0] = u_proj.w > 0.5 ? v.z - u_depth.z : 1.0;\n"
    "}\n";

static const char *const DEPTH_FS =
    "#version 450 core\n"
    "in float v_z;\n"
    "uniform vec4 u_depth;\n"
    "void main() { gl_FragDepth = (v_z - u_depth.x) * u_depth.y; }\n";

/* Compiles one shader from `count` strings; 0 (message logged with the info log) on failure. */
static GLuint compile_shader(glow_gl_lights *g, GLenum type, const char *const *srcs, GLsizei count, const char *what) {
    const glow_glfns *gl = &g->gl;
    GLuint s = gl->CreateShader(type);
    if (!s) {
        GLL_FAIL(&g->logger, GLOW_ERROR_UNSUPPORTED, "glCreateShader failed for the %s (GL error 0x%04x)", what,
                 (unsigned)gl->GetError());
        return 0;
    }
    gl->ShaderSource(s, count, srcs, NULL);
    gl->CompileShader(s);
    GLint ok = 0, len = 0;
    gl->GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        gl->GetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
        char *log = malloc(len > 0 ? (size_t)len + 1 : 1);
        if (log) {
            log[0] = '\0';
            if (len > 0) gl->GetShaderInfoLog(s, len, NULL, log);
        }
        GLL_FAIL(&g->logger, GLOW_ERROR_UNSUPPORTED, "the %s does not compile:\n%s", what, log ? log : "(no memory for the log)");
        free(log);
        gl->DeleteShader(s);
        return 0;
    }
    return s;
}

/* Links the shaders into a program (they are deleted); 0 (message logged) on failure. */
static GLuint link_program(glow_gl_lights *g, const GLuint *shaders, int count, const char *what) {
    const glow_glfns *gl = &g->gl;
    GLuint p = gl->CreateProgram();
    for (int i = 0; i < count; ++i)
        if (p) gl->AttachShader(p, shaders[i]);
    if (p) gl->LinkProgram(p);
    for (int i = 0; i < count; ++i) gl->DeleteShader(shaders[i]);
    if (!p) {
        GLL_FAIL(&g->logger, GLOW_ERROR_UNSUPPORTED, "glCreateProgram failed for the %s", what);
        return 0;
    }
    GLint ok = 0, len = 0;
    gl->GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        gl->GetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
        char *log = malloc(len > 0 ? (size_t)len + 1 : 1);
        if (log) {
            log[0] = '\0';
            if (len > 0) gl->GetProgramInfoLog(p, len, NULL, log);
        }
        GLL_FAIL(&g->logger, GLOW_ERROR_UNSUPPORTED, "the %s does not link:\n%s", what, log ? log : "(no memory for the log)");
        free(log);
        gl->DeleteProgram(p);
        return 0;
    }
    return p;
}

static glow_result build_depth_program(glow_gl_lights *g) {
    GLuint sh[2];
    if (!(sh[0] = compile_shader(g, GL_VERTEX_SHADER, &DEPTH_VS, 1, "depth-pass vertex shader")))
        return GLOW_ERROR_UNSUPPORTED;
    if (!(sh[1] = compile_shader(g, GL_FRAGMENT_SHADER, &DEPTH_FS, 1, "depth-pass fragment shader"))) {
        g->gl.DeleteShader(sh[0]);
        return GLOW_ERROR_UNSUPPORTED;
    }
    if (!(g->prog = link_program(g, sh, 2, "depth-pass program"))) return GLOW_ERROR_UNSUPPORTED;
    const glow_glfns *gl = &g->gl;
    g->loc_origin = gl->GetUniformLocation(g->prog, "u_origin");
    g->loc_ax = gl->GetUniformLocation(g->prog, "u_ax");
    g->loc_ay = gl->GetUniformLocation(g->prog, "u_ay");
    g->loc_az = gl->GetUniformLocation(g->prog, "u_az");
    g->loc_proj = gl->GetUniformLocation(g->prog, "u_proj");
    g->loc_depth = gl->GetUniformLocation(g->prog, "u_depth");
    if (g->loc_origin < 0 || g->loc_ax < 0 || g->loc_ay < 0 || g->loc_az < 0 || g->loc_proj < 0 || g->loc_depth < 0)
        return GLL_FAIL(&g->logger, GLOW_ERROR_UNSUPPORTED, "the depth-pass program lacks one of its uniforms");
    return GLOW_OK;
}

/* The hook text: this object's sizes and bindings, then gl_lights_hook.glsl. */
static glow_result build_hook(glow_gl_lights *g) {
    char head[512];
    int n = snprintf(head, sizeof head,
                     "// glow_gl_lights hook (glow_gl_lights.h): this object's sizes and bindings\n"
                     "#define GLOW_GL_LIGHTS_LIGHTS %u\n"
                     "#define GLOW_GL_LIGHTS_MAPS %u\n"
                     "#define GLOW_GL_LIGHTS_UBO_BINDING %u\n"
                     "#define GLOW_GL_LIGHTS_MAP_UNIT %u\n"
                     "#define GLOW_GL_LIGHTS_CUBE_UNIT %u\n",
                     g->max_lights, g->max_maps, g->ubo_binding, g->unit_maps, g->unit_cube);
    size_t body = strlen(glow__gl_lights_hook_glsl);
    g->hook = malloc((size_t)n + body + 1);
    if (!g->hook) return GLL_FAIL(&g->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for the hook source");
    memcpy(g->hook, head, (size_t)n);
    memcpy(g->hook + n, glow__gl_lights_hook_glsl, body + 1);

    /* compile it once in a compute shader, as Glow will, so a broken hook fails here with its log */
    const char *srcs[3] = {"#version 450 core\nlayout(local_size_x = 1) in;\n", g->hook,
                           "\nlayout(std430, binding = 0) buffer glow_gl_lights_check { vec4 glow_gl_lights_out; };\n"
                           "void main() {\n"
                           "    glow_gl_lights_out = vec4(glow_host_surfel_irradiance(vec3(0.0), vec3(0.0, 1.0, 0.0), 0u), 1.0);\n"
                           "}\n"};
    GLuint sh = compile_shader(g, GL_COMPUTE_SHADER, srcs, 3, "hook (checked in a compute shader)");
    if (!sh) return GLOW_ERROR_UNSUPPORTED;
    GLuint p = link_program(g, &sh, 1, "hook check program");
    if (!p) return GLOW_ERROR_UNSUPPORTED;
    g->gl.DeleteProgram(p);
    return GLOW_OK;
}

/* -------------------------------------------------------------------------------- map textures */

/* A GL_DEPTH_COMPONENT32F 2D array of `layers` (0: a 1 x 1 x 1 placeholder), or 0 on GL failure. */
static GLuint make_array(const glow_glfns *gl, uint32_t res, uint32_t layers) {
    GLuint t = 0;
    gl->CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &t);
    if (!t) return 0;
    gl->TextureStorage3D(t, 1, GL_DEPTH_COMPONENT32F, layers ? (GLsizei)res : 1, layers ? (GLsizei)res : 1,
                         layers ? (GLsizei)layers : 1);
    gl->TextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->TextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl->TextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    gl->TextureParameteri(t, GL_TEXTURE_COMPARE_MODE, GL_NONE);
    if (!layers) {
        const float one = 1.0f; /* "nothing there" */
        gl->TextureSubImage3D(t, 0, 0, 0, 0, 1, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &one);
    }
    return t;
}

/* Makes texture `which` hold exactly `layers` layers; the old one is kept until the new one exists. */
static glow_result ensure_layers(glow_gl_lights *g, int which, uint32_t layers) {
    if (g->tex[which] && g->tex_layers[which] == layers) return GLOW_OK;
    const glow_glfns *gl = &g->gl;
    uint32_t res = which ? g->cube_size : g->sm_size;
    drain_errors(gl);
    GLuint t = make_array(gl, res, layers);
    GLenum e = drain_errors(gl);
    if (!t || e != GL_NO_ERROR) {
        if (t) gl->DeleteTextures(1, &t);
        return GLL_FAIL(&g->logger, e == GL_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_UNSUPPORTED,
                        "cannot allocate %u depth layers of %u x %u (GL error 0x%04x)", layers, res, res, (unsigned)e);
    }
    if (g->tex[which]) gl->DeleteTextures(1, &g->tex[which]);
    g->tex[which] = t;
    g->tex_layers[which] = layers;
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------------ lifetime */

static glow_result check_desc(const glow_gl_lights_desc *d, const glow_logger *lg) {
    if (!d->loader) return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "desc.loader is NULL");
    if (!d->bake) return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "desc.bake is NULL");
    if (d->max_lights > GLOW_GL_LIGHTS_MAX_LIGHTS)
        return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "max_lights %u outside 1..%u", d->max_lights,
                        GLOW_GL_LIGHTS_MAX_LIGHTS);
    if (d->shadow_map_size && (d->shadow_map_size < 16 || d->shadow_map_size > 8192))
        return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "shadow_map_size %u outside 16..8192", d->shadow_map_size);
    if (d->cube_map_size && (d->cube_map_size < 16 || d->cube_map_size > 8192))
        return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "cube_map_size %u outside 16..8192", d->cube_map_size);
    if (d->pcf_size && (d->pcf_size > 9 || (d->pcf_size & 1) == 0))
        return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "pcf_size %u is not odd in 1..9", d->pcf_size);
    const float b[3] = {d->depth_bias, d->slope_bias, d->normal_offset};
    static const char *const names[3] = {"depth_bias", "slope_bias", "normal_offset"};
    for (int i = 0; i < 3; ++i)
        if (!isfinite(b[i]) || b[i] < 0.0f || b[i] > 1000.0f)
            return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "%s (%g) outside [0, 1000]", names[i], (double)b[i]);
    if (d->ubo_binding && d->ubo_binding < FIRST_FREE_BINDING)
        return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "ubo_binding %u < %u (Glow's kernels use 0..7)", d->ubo_binding,
                        FIRST_FREE_BINDING);
    if (d->texture_unit && d->texture_unit < FIRST_FREE_BINDING)
        return GLL_FAIL(lg, GLOW_ERROR_INVALID_ARGUMENT, "texture_unit %u < %u", d->texture_unit, FIRST_FREE_BINDING);
    return GLOW_OK;
}

/* The context's version and limits against what this object will use. */
static glow_result check_limits(glow_gl_lights *g) {
    const glow_glfns *gl = &g->gl;
    GLint major = 0, minor = 0, v = 0;
    gl->GetIntegerv(GL_MAJOR_VERSION, &major);
    gl->GetIntegerv(GL_MINOR_VERSION, &minor);
    if (major < 4 || (major == 4 && minor < 5))
        return GLL_FAIL(&g->logger, GLOW_ERROR_UNSUPPORTED, "needs OpenGL 4.5, the context has %d.%d", major, minor);
    struct {
        GLenum pname;
        uint64_t need;
        const char *name, *what;
    } lim[] = {
        {GL_MAX_UNIFORM_BUFFER_BINDINGS, (uint64_t)g->ubo_binding + 1, "GL_MAX_UNIFORM_BUFFER_BINDINGS", "ubo_binding + 1"},
        {GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS, (uint64_t)g->unit_cube + 1, "GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS",
         "texture_unit + 2"},
        {GL_MAX_TEXTURE_SIZE, g->sm_size > g->cube_size ? g->sm_size : g->cube_size, "GL_MAX_TEXTURE_SIZE",
         "the map size"},
        {GL_MAX_ARRAY_TEXTURE_LAYERS, g->max_maps, "GL_MAX_ARRAY_TEXTURE_LAYERS", "6 x max_lights"},
        {GL_MAX_UNIFORM_BLOCK_SIZE, g->ubo_size, "GL_MAX_UNIFORM_BLOCK_SIZE", "the light block's bytes"},
    };
    for (size_t i = 0; i < sizeof lim / sizeof lim[0]; ++i) {
        v = 0;
        gl->GetIntegerv(lim[i].pname, &v);
        if ((uint64_t)(v > 0 ? v : 0) < lim[i].need)
            return GLL_FAIL(&g->logger, GLOW_ERROR_INVALID_ARGUMENT, "%s (%llu) exceeds %s (%d)", lim[i].what,
                            (unsigned long long)lim[i].need, lim[i].name, v);
    }
    return GLOW_OK;
}

/* Copies the bake's triangles into the vertex buffer and takes their bounds. */
static glow_result upload_geometry(glow_gl_lights *g, const glow_bake *bake) {
    glow_bake_geometry geo;
    glow_result r = glow_bake_get_geometry(bake, &geo);
    if (r != GLOW_OK) return GLL_FAIL(&g->logger, r, "cannot read the bake's geometry");
    if (geo.triangle_count == 0 || !geo.positions)
        return GLL_FAIL(&g->logger, GLOW_ERROR_EMPTY_SCENE, "the bake carries no triangles to cast shadows");
    g->tri_count = geo.triangle_count;
    float *tris = malloc((size_t)g->tri_count * 9 * sizeof(float));
    if (!tris) return GLL_FAIL(&g->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u triangles", g->tri_count);
    for (int i = 0; i < 3; ++i) {
        g->bmin[i] = INFINITY;
        g->bmax[i] = -INFINITY;
    }
    for (uint32_t t = 0; t < g->tri_count; ++t) {
        const float *src = (const float *)((const char *)geo.positions + (size_t)t * geo.stride);
        for (int k = 0; k < 9; ++k) {
            float v = src[k];
            if (!isfinite(v)) {
                free(tris);
                return GLL_FAIL(&g->logger, GLOW_ERROR_CORRUPT_DATA, "bake triangle %u has a non-finite corner", t);
            }
            tris[9 * (size_t)t + k] = v;
            g->bmin[k % 3] = fminf(g->bmin[k % 3], v);
            g->bmax[k % 3] = fmaxf(g->bmax[k % 3], v);
        }
    }
    float ext[3] = {g->bmax[0] - g->bmin[0], g->bmax[1] - g->bmin[1], g->bmax[2] - g->bmin[2]};
    g->diag = sqrtf(glow__dot3(ext, ext));
    if (!(g->diag > 0.0f)) g->diag = 1.0f;

    const glow_glfns *gl = &g->gl;
    drain_errors(gl);
    gl->CreateBuffers(1, &g->vbo);
    gl->NamedBufferStorage(g->vbo, (GLsizeiptr)((size_t)g->tri_count * 9 * sizeof(float)), tris, 0);
    free(tris);
    gl->CreateVertexArrays(1, &g->vao);
    gl->VertexArrayVertexBuffer(g->vao, 0, g->vbo, 0, 3 * sizeof(float));
    gl->EnableVertexArrayAttrib(g->vao, 0);
    gl->VertexArrayAttribFormat(g->vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
    gl->VertexArrayAttribBinding(g->vao, 0, 0);
    GLenum e = drain_errors(gl);
    if (!g->vbo || !g->vao || e != GL_NO_ERROR)
        return GLL_FAIL(&g->logger, e == GL_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_UNSUPPORTED,
                        "cannot create the vertex buffer of %u triangles (GL error 0x%04x)", g->tri_count, (unsigned)e);
    return GLOW_OK;
}

void glow_gl_lights_destroy(glow_gl_lights *g) {
    if (!g) return;
    const glow_glfns *gl = &g->gl;
    if (gl->DeleteBuffers) { /* NULL when the loader failed: nothing was created */
        if (g->vbo) gl->DeleteBuffers(1, &g->vbo);
        if (g->ubo) gl->DeleteBuffers(1, &g->ubo);
        if (g->sky) gl->DeleteBuffers(1, &g->sky);
        free(g->sky_s);
        free(g->sky_t);
        if (g->vao) gl->DeleteVertexArrays(1, &g->vao);
        if (g->fbo) gl->DeleteFramebuffers(1, &g->fbo);
        if (g->prog) gl->DeleteProgram(g->prog);
        for (int i = 0; i < 2; ++i)
            if (g->tex[i]) gl->DeleteTextures(1, &g->tex[i]);
    }
    free(g->staging);
    free(g->hook);
    free(g);
}

glow_result glow_gl_lights_create(const glow_gl_lights_desc *desc, glow_gl_lights **out) {
    if (out) *out = NULL;
    if (!desc || !out) return GLOW_ERROR_INVALID_ARGUMENT;
    const glow_logger *lg = &desc->logger;
    glow_result r = check_desc(desc, lg);
    if (r != GLOW_OK) return r;

    glow_gl_lights *g = calloc(1, sizeof *g);
    if (!g) return GLL_FAIL(lg, GLOW_ERROR_OUT_OF_MEMORY, "out of memory");
    g->logger = desc->logger;
    g->max_lights = desc->max_lights ? desc->max_lights : DEFAULT_MAX_LIGHTS;
    g->max_maps = 6 * g->max_lights;
    g->sm_size = desc->shadow_map_size ? desc->shadow_map_size : 1024;
    g->cube_size = desc->cube_map_size ? desc->cube_map_size : 512;
    g->depth_bias = desc->depth_bias > 0.0f ? desc->depth_bias : 1.0f;
    g->slope_bias = desc->slope_bias > 0.0f ? desc->slope_bias : 2.0f;
    g->normal_offset = desc->normal_offset > 0.0f ? desc->normal_offset : 1.0f;
    g->pcf_radius = desc->pcf_size ? (int)desc->pcf_size / 2 : 1;
    g->ubo_binding = desc->ubo_binding ? desc->ubo_binding : FIRST_FREE_BINDING;
    g->unit_maps = desc->texture_unit ? desc->texture_unit : FIRST_FREE_BINDING;
    g->unit_cube = g->unit_maps + 1;
    g->ubo_size = sizeof(ubo_head) + (size_t)g->max_lights * sizeof(ubo_light) + (size_t)g->max_maps * sizeof(ubo_map);
    g->staging = calloc(1, g->ubo_size);
    if (!g->staging) {
        glow_gl_lights_destroy(g);
        return GLL_FAIL(lg, GLOW_ERROR_OUT_OF_MEMORY, "out of memory");
    }

    char missing[256];
    if (!glow_glfns_load(&g->gl, desc->loader, missing, sizeof missing)) {
        memset(&g->gl, 0, sizeof g->gl);
        glow_gl_lights_destroy(g);
        return GLL_FAIL(lg, GLOW_ERROR_UNSUPPORTED, "the loader lacks GL entry points: %s", missing);
    }
    const glow_glfns *gl = &g->gl;
    drain_errors(gl); /* errors the host left behind are not ours */
    if ((r = check_limits(g)) != GLOW_OK || (r = upload_geometry(g, desc->bake)) != GLOW_OK ||
        (r = build_depth_program(g)) != GLOW_OK || (r = build_hook(g)) != GLOW_OK) {
        glow_gl_lights_destroy(g);
        return r;
    }

    /* the light block starts empty: no lights, no sky; shadow settings already in */
    ubo_head *head = (ubo_head *)g->staging;
    head->shadow[0] = g->depth_bias;
    head->shadow[1] = g->slope_bias;
    head->shadow[2] = g->normal_offset;
    head->counts[1] = g->pcf_radius;
    drain_errors(gl);
    gl->CreateBuffers(1, &g->ubo);
    gl->NamedBufferStorage(g->ubo, (GLsizeiptr)g->ubo_size, g->staging, GL_DYNAMIC_STORAGE_BIT);
    gl->CreateFramebuffers(1, &g->fbo);
    GLenum e = drain_errors(gl);
    if (!g->ubo || !g->fbo || e != GL_NO_ERROR) {
        glow_gl_lights_destroy(g);
        return GLL_FAIL(lg, e == GL_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_UNSUPPORTED,
                        "cannot create the light block or the framebuffer (GL error 0x%04x)", (unsigned)e);
    }
    gl->NamedFramebufferDrawBuffer(g->fbo, GL_NONE);
    gl->NamedFramebufferReadBuffer(g->fbo, GL_NONE);
    if ((r = ensure_layers(g, 0, 0)) != GLOW_OK || (r = ensure_layers(g, 1, 0)) != GLOW_OK) {
        glow_gl_lights_destroy(g);
        return r;
    }
    *out = g;
    return GLOW_OK;
}

/* ---------------------------------------------------------------------------------- rendering */

typedef struct saved_state {
    GLint draw_fbo, viewport[4], program, vao, depth_func, depth_mask;
    GLboolean depth_test, cull, scissor, clip0;
} saved_state;

static void save_state(const glow_glfns *gl, saved_state *s) {
    gl->GetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &s->draw_fbo);
    gl->GetIntegerv(GL_VIEWPORT, s->viewport);
    gl->GetIntegerv(GL_CURRENT_PROGRAM, &s->program);
    gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &s->vao);
    gl->GetIntegerv(GL_DEPTH_FUNC, &s->depth_func);
    gl->GetIntegerv(GL_DEPTH_WRITEMASK, &s->depth_mask);
    s->depth_test = gl->IsEnabled(GL_DEPTH_TEST);
    s->cull = gl->IsEnabled(GL_CULL_FACE);
    s->scissor = gl->IsEnabled(GL_SCISSOR_TEST);
    s->clip0 = gl->IsEnabled(GL_CLIP_DISTANCE0);
}

static void enable(const glow_glfns *gl, GLenum cap, GLboolean on) {
    if (on) gl->Enable(cap);
    else gl->Disable(cap);
}

static void restore_state(const glow_glfns *gl, const saved_state *s) {
    gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)s->draw_fbo);
    gl->Viewport(s->viewport[0], s->viewport[1], s->viewport[2], s->viewport[3]);
    gl->UseProgram((GLuint)s->program);
    gl->BindVertexArray((GLuint)s->vao);
    gl->DepthFunc((GLenum)s->depth_func);
    gl->DepthMask(s->depth_mask ? GL_TRUE : GL_FALSE);
    enable(gl, GL_DEPTH_TEST, s->depth_test);
    enable(gl, GL_CULL_FACE, s->cull);
    enable(gl, GL_SCISSOR_TEST, s->scissor);
    enable(gl, GL_CLIP_DISTANCE0, s->clip0);
}

/* Renders one map into its layer; the depth state is set by the caller. */
static glow_result render_map(glow_gl_lights *g, const map_setup *m, float y_sign) {
    const glow_glfns *gl = &g->gl;
    gl->NamedFramebufferTextureLayer(g->fbo, GL_DEPTH_ATTACHMENT, g->tex[m->array], 0, (GLint)m->layer);
    GLenum status = gl->CheckNamedFramebufferStatus(g->fbo, GL_DRAW_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        return GLL_FAIL(&g->logger, GLOW_ERROR_UNSUPPORTED,
                        "the shadow framebuffer (depth layer %u of %u x %u) is not complete: status 0x%04x", m->layer,
                        m->res, m->res, (unsigned)status);
    const float one = 1.0f;
    gl->ClearNamedFramebufferfv(g->fbo, GL_DEPTH, 0, &one);
    float v[4] = {m->origin[0], m->origin[1], m->origin[2], 0.0f};
    gl->ProgramUniform4fv(g->prog, g->loc_origin, 1, v);
    float a[3][4] = {{m->ax[0], m->ax[1], m->ax[2], 0}, {m->ay[0], m->ay[1], m->ay[2], 0}, {m->az[0], m->az[1], m->az[2], 0}};
    gl->ProgramUniform4fv(g->prog, g->loc_ax, 1, a[0]);
    gl->ProgramUniform4fv(g->prog, g->loc_ay, 1, a[1]);
    gl->ProgramUniform4fv(g->prog, g->loc_az, 1, a[2]);
    float proj[4];
    if (m->persp) { /* NDC = v.xy · inv_s / v.z (shadow_map.c's project) */
        proj[0] = m->inv_s;
        proj[1] = proj[2] = 0.0f;
        proj[3] = 1.0f;
    } else { /* NDC = 2 (v.xy - off) / (texel · res) - 1 */
        float sc = 2.0f / (m->texel * (float)m->res);
        proj[0] = sc;
        proj[1] = -m->off_x * sc - 1.0f;
        proj[2] = -m->off_y * sc - 1.0f;
        proj[3] = 0.0f;
    }
    gl->ProgramUniform4fv(g->prog, g->loc_proj, 1, proj);
    float depth[4] = {m->depth_lo, 1.0f / m->depth_range, m->near_z, y_sign};
    gl->ProgramUniform4fv(g->prog, g->loc_depth, 1, depth);
    gl->DrawArrays(GL_TRIANGLES, 0, (GLsizei)(3 * g->tri_count));
    return GLOW_OK;
}

static void put_map(ubo_map *u, const map_setup *m) {
    memcpy(u->origin, m->origin, 12);
    u->origin[3] = m->persp ? 1.0f : 0.0f;
    memcpy(u->ax, m->ax, 12);
    u->ax[3] = m->inv_s;
    memcpy(u->ay, m->ay, 12);
    u->ay[3] = m->texel;
    memcpy(u->az, m->az, 12);
    u->az[3] = m->near_z;
    u->params[0] = m->off_x;
    u->params[1] = m->off_y;
    u->params[2] = m->depth_lo;
    u->params[3] = m->depth_range;
    u->info[0] = (int32_t)m->res;
    u->info[1] = (int32_t)m->layer;
    u->info[2] = (int32_t)m->array;
    u->info[3] = 0;
}

glow_result glow_gl_lights_set(glow_gl_lights *g, const glow_scene_light *lights, uint32_t count,
                               const float environment[3]) {
    if (!g) return GLOW_ERROR_INVALID_ARGUMENT;
    double t0 = now_ms();
    if (count && !lights)
        return GLL_FAIL(&g->logger, GLOW_ERROR_INVALID_ARGUMENT, "lights is NULL with count %u", count);
    if (count > g->max_lights)
        return GLL_FAIL(&g->logger, GLOW_ERROR_INVALID_ARGUMENT, "%u lights, more than max_lights (%u)", count,
                        g->max_lights);
    if (environment)
        for (int c = 0; c < 3; ++c)
            if (!isfinite(environment[c]) || environment[c] < 0.0f)
                return GLL_FAIL(&g->logger, GLOW_ERROR_INVALID_ARGUMENT, "environment[%d] (%g) is negative or not finite",
                                c, (double)environment[c]);

    /* validate everything and lay out the block before touching GL state */
    unsigned char *blk = calloc(1, g->ubo_size);
    map_setup *maps = calloc(g->max_maps, sizeof *maps);
    if (!blk || !maps) {
        free(blk);
        free(maps);
        return GLL_FAIL(&g->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory");
    }
    ubo_head *head = (ubo_head *)blk;
    ubo_light *ul = (ubo_light *)(blk + sizeof(ubo_head));
    ubo_map *um = (ubo_map *)(blk + sizeof(ubo_head) + (size_t)g->max_lights * sizeof(ubo_light));
    memcpy(head, g->staging, sizeof *head); /* shadow settings */
    for (int c = 0; c < 3; ++c) head->environment[c] = environment ? environment[c] * (float)GLL_PI : 0.0f;
    head->counts[0] = (int32_t)count;
    head->counts[2] = (int32_t)g->sky_count; /* set_sky_visibility persists across set() */
    head->counts[3] = (int32_t)g->transfer_count; /* ... and so do the sky transfer and the SH sky */
    head->environment[3] = g->sh_on ? 1.0f : 0.0f;
    memcpy(head->sky_sh, g->sh, sizeof head->sky_sh);

    uint32_t margin = (uint32_t)g->pcf_radius + 2, nmaps = 0, layers[2] = {0, 0};
    float near_z = 1e-3f * g->diag;
    glow_result r = GLOW_OK;
    for (uint32_t i = 0; i < count && r == GLOW_OK; ++i) {
        const glow_scene_light *L = &lights[i];
        char what[48], msg[512];
        snprintf(what, sizeof what, "lights[%u]", i);
        r = glow_scene_light_validate(L, what, msg, sizeof msg);
        if (r != GLOW_OK) {
            GLL_FAIL(&g->logger, r, "%s", msg);
            break;
        }
        ubo_light *u = &ul[i];
        float dir[3] = {0.0f, 0.0f, 0.0f};
        if (L->type != GLOW_SCENE_LIGHT_POINT) glow__normalize3(L->direction, dir);
        memcpy(u->position, L->position, 12);
        memcpy(u->direction, dir, 12);
        memcpy(u->power, L->type == GLOW_SCENE_LIGHT_SUN ? L->irradiance : L->intensity, 12);
        if (L->type == GLOW_SCENE_LIGHT_SPOT) {
            u->direction[3] = cosf(L->outer_deg * (float)(GLL_PI / 180.0));
            u->power[3] = cosf(L->inner_deg * (float)(GLL_PI / 180.0));
        }
        bool cube = L->type == GLOW_SCENE_LIGHT_POINT ||
                    (L->type == GLOW_SCENE_LIGHT_SPOT && L->outer_deg > SPOT_MAX_SINGLE_MAP_DEG);
        u->info[0] = (int32_t)L->type;
        u->info[1] = (int32_t)nmaps;
        u->info[2] = cube ? 6 : 1;
        if (L->type == GLOW_SCENE_LIGHT_SUN) {
            setup_ortho(&maps[nmaps], dir, g->bmin, g->bmax, g->sm_size, margin);
        } else if (cube) {
            for (int f = 0; f < 6; ++f) {
                float axis[3] = {0.0f, 0.0f, 0.0f};
                axis[f >> 1] = (f & 1) ? -1.0f : 1.0f;
                setup_persp(&maps[nmaps + (uint32_t)f], L->position, axis, 1.0f, g->cube_size, margin, near_z, g->bmin,
                            g->bmax);
            }
        } else {
            setup_persp(&maps[nmaps], L->position, dir, tanf(L->outer_deg * (float)(GLL_PI / 180.0)), g->sm_size,
                        margin, near_z, g->bmin, g->bmax);
        }
        for (uint32_t k = 0; k < (cube ? 6u : 1u); ++k) {
            map_setup *m = &maps[nmaps + k];
            m->array = cube ? 1u : 0u;
            m->layer = layers[m->array]++;
            put_map(&um[nmaps + k], m);
        }
        nmaps += cube ? 6 : 1;
    }
    if (r == GLOW_OK) r = ensure_layers(g, 0, layers[0]);
    if (r == GLOW_OK) r = ensure_layers(g, 1, layers[1]);
    if (r != GLOW_OK) {
        free(blk);
        free(maps);
        return r;
    }

    const glow_glfns *gl = &g->gl;
    drain_errors(gl);
    if (nmaps) {
        saved_state st;
        save_state(gl, &st);
        GLint origin = GL_LOWER_LEFT;
        gl->GetIntegerv(GL_CLIP_ORIGIN, &origin);
        float y_sign = origin == GL_UPPER_LEFT ? -1.0f : 1.0f; /* keep texel rows bottom-up either way */
        gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, g->fbo);
        gl->UseProgram(g->prog);
        gl->BindVertexArray(g->vao);
        gl->Enable(GL_DEPTH_TEST);
        gl->DepthFunc(GL_LESS);
        gl->DepthMask(GL_TRUE);
        gl->Disable(GL_CULL_FACE); /* both faces cast shadows */
        gl->Disable(GL_SCISSOR_TEST);
        gl->Enable(GL_CLIP_DISTANCE0); /* the perspective maps' near plane */
        for (uint32_t k = 0; k < nmaps && r == GLOW_OK; ++k) {
            gl->Viewport(0, 0, (GLsizei)maps[k].res, (GLsizei)maps[k].res);
            r = render_map(g, &maps[k], y_sign);
        }
        gl->NamedFramebufferTextureLayer(g->fbo, GL_DEPTH_ATTACHMENT, 0, 0, 0);
        restore_state(gl, &st);
    }
    if (r == GLOW_OK) gl->NamedBufferSubData(g->ubo, 0, (GLsizeiptr)g->ubo_size, blk);
    GLenum e = drain_errors(gl);
    if (r == GLOW_OK && e != GL_NO_ERROR)
        r = GLL_FAIL(&g->logger, e == GL_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_UNSUPPORTED,
                     "rendering %u shadow maps raised GL error 0x%04x", nmaps, (unsigned)e);
    free(maps);
    if (r != GLOW_OK) {
        free(blk);
        return r;
    }
    free(g->staging);
    g->staging = blk;
    g->light_count = count;
    g->map_count = nmaps;
    g->set_ms = now_ms() - t0;
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------------- queries */

const char *glow_gl_lights_hook_source(const glow_gl_lights *g) { return g ? g->hook : NULL; }

glow_result glow_gl_lights_bind(const glow_gl_lights *g) {
    if (!g) return GLOW_ERROR_INVALID_ARGUMENT;
    const glow_glfns *gl = &g->gl;
    gl->BindBufferBase(GL_UNIFORM_BUFFER, g->ubo_binding, g->ubo);
    if (g->sky) gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, g->ubo_binding, g->sky);
    gl->BindTextureUnit(g->unit_maps, g->tex[0]);
    gl->BindTextureUnit(g->unit_cube, g->tex[1]);
    gl->BindSampler(g->unit_maps, 0);
    gl->BindSampler(g->unit_cube, 0);
    return GLOW_OK;
}

/* (Re)creates the sky SSBO from the host copies: S[sky_count] then T[transfer_count][9]; the counts go
 * into the block (and its staging copy, which set() starts from). */
static glow_result upload_sky(glow_gl_lights *g) {
    const glow_glfns *gl = &g->gl;
    if (g->sky) gl->DeleteBuffers(1, &g->sky);
    g->sky = 0;
    const size_t n = (size_t)g->sky_count + 9u * (size_t)g->transfer_count;
    glow_result r = GLOW_OK;
    if (n) {
        gl->CreateBuffers(1, &g->sky);
        gl->NamedBufferStorage(g->sky, (GLsizeiptr)(n * 4u), NULL, GL_DYNAMIC_STORAGE_BIT);
        if (g->sky_count) gl->NamedBufferSubData(g->sky, 0, (GLsizeiptr)g->sky_count * 4, g->sky_s);
        if (g->transfer_count)
            gl->NamedBufferSubData(g->sky, (GLintptr)g->sky_count * 4, (GLsizeiptr)g->transfer_count * 36, g->sky_t);
        GLenum e = gl->GetError();
        if (e != GL_NO_ERROR) {
            gl->DeleteBuffers(1, &g->sky);
            g->sky = 0;
            g->sky_count = g->transfer_count = 0;
            r = GLL_FAIL(&g->logger, e == GL_OUT_OF_MEMORY ? GLOW_ERROR_OUT_OF_MEMORY : GLOW_ERROR_UNSUPPORTED,
                         "sky buffer of %zu values: GL error 0x%04x", n, e);
        }
    }
    const int32_t c[2] = {(int32_t)g->sky_count, (int32_t)g->transfer_count};
    ubo_head *head = (ubo_head *)g->staging;
    head->counts[2] = c[0];
    head->counts[3] = c[1];
    gl->NamedBufferSubData(g->ubo, (GLintptr)offsetof(ubo_head, counts) + 2 * (GLintptr)sizeof(int32_t), sizeof c, c);
    return r;
}

glow_result glow_gl_lights_set_sky_visibility(glow_gl_lights *g, const float *visibility, uint32_t count) {
    if (!g || (visibility && count == 0)) return GLOW_ERROR_INVALID_ARGUMENT;
    float *copy = NULL;
    if (visibility) {
        for (uint32_t i = 0; i < count; ++i)
            if (!(visibility[i] >= 0.0f && visibility[i] <= 1.0f))
                return GLL_FAIL(&g->logger, GLOW_ERROR_INVALID_ARGUMENT, "sky visibility[%u] (%g) is outside [0, 1]", i,
                                (double)visibility[i]);
        if (!(copy = malloc((size_t)count * sizeof *copy)))
            return GLL_FAIL(&g->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for %u sky values", count);
        memcpy(copy, visibility, (size_t)count * sizeof *copy);
    }
    free(g->sky_s);
    g->sky_s = copy;
    g->sky_count = visibility ? count : 0u;
    return upload_sky(g);
}

glow_result glow_gl_lights_set_sky_transfer(glow_gl_lights *g, const float *transfer, uint32_t count) {
    if (!g || (transfer && count == 0)) return GLOW_ERROR_INVALID_ARGUMENT;
    float *copy = NULL;
    if (transfer) {
        for (size_t i = 0; i < 9u * (size_t)count; ++i)
            if (!(fabsf(transfer[i]) <= 16.0f))
                return GLL_FAIL(&g->logger, GLOW_ERROR_INVALID_ARGUMENT,
                                "sky transfer of surfel %zu, coefficient %zu (%g): not finite or beyond 16", i / 9, i % 9,
                                (double)transfer[i]);
        if (!(copy = malloc(9u * (size_t)count * sizeof *copy)))
            return GLL_FAIL(&g->logger, GLOW_ERROR_OUT_OF_MEMORY, "out of memory for the sky transfer of %u surfels", count);
        memcpy(copy, transfer, 9u * (size_t)count * sizeof *copy);
    }
    free(g->sky_t);
    g->sky_t = copy;
    g->transfer_count = transfer ? count : 0u;
    return upload_sky(g);
}

glow_result glow_gl_lights_set_environment_sh(glow_gl_lights *g, const float *sh_rgb) {
    if (!g) return GLOW_ERROR_INVALID_ARGUMENT;
    if (sh_rgb)
        for (int k = 0; k < 27; ++k)
            if (!isfinite(sh_rgb[k]) || fabsf(sh_rgb[k]) > GLOW_MAX_IRRADIANCE)
                return GLL_FAIL(&g->logger, GLOW_ERROR_INVALID_ARGUMENT,
                                "environment SH coefficient %d channel %d (%g) is not finite or beyond %g", k / 3, k % 3,
                                (double)sh_rgb[k], (double)GLOW_MAX_IRRADIANCE);
    memset(g->sh, 0, sizeof g->sh);
    if (sh_rgb)
        for (int k = 0; k < 9; ++k)
            for (int c = 0; c < 3; ++c) g->sh[k][c] = sh_rgb[3 * k + c];
    g->sh_on = sh_rgb != NULL;
    ubo_head *head = (ubo_head *)g->staging;
    head->environment[3] = g->sh_on ? 1.0f : 0.0f;
    memcpy(head->sky_sh, g->sh, sizeof head->sky_sh);
    g->gl.NamedBufferSubData(g->ubo, 0, (GLsizeiptr)sizeof *head, head);
    return GLOW_OK;
}

glow_result glow_gl_lights_get_stats(const glow_gl_lights *g, glow_gl_lights_stats *out_stats) {
    if (!g || !out_stats) return GLOW_ERROR_INVALID_ARGUMENT;
    memset(out_stats, 0, sizeof *out_stats);
    out_stats->light_count = g->light_count;
    out_stats->triangle_count = g->tri_count;
    out_stats->map_count = g->map_count;
    out_stats->map_bytes = (uint64_t)g->tex_layers[0] * g->sm_size * g->sm_size * 4u +
                           (uint64_t)g->tex_layers[1] * g->cube_size * g->cube_size * 4u;
    out_stats->set_ms = g->set_ms;
    out_stats->ubo_binding = g->ubo_binding;
    out_stats->texture_units[0] = g->unit_maps;
    out_stats->texture_units[1] = g->unit_cube;
    return GLOW_OK;
}
