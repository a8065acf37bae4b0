/* sample_gl.h — the GL 4.5 renderer the GL samples share (header-only, all static), and, with
 * SAMPLE_GL_APP defined before the include, the frame loop around it (context, bake, CPU + GL
 * systems, glow_gl_lights, window keys, PNGs). Not part of Glow's API: copy what you need.
 *
 * THE RENDERER (sample_gl_*) draws the bake's triangles (glow_bake_get_geometry: positions, the
 * geometric normal, lightmap uv, material) and spheres (dynamic objects) into its own framebuffer
 * object, per pixel:
 *     radiance = emission + direct + indirect
 *     direct   = glow_host_surfel_irradiance(p, n, material) · albedo/π      (the lights' GLSL hook:
 *                glow_gl_lights_hook_source — the same function that lights Glow's surfels on the GPU)
 *     indirect = albedo · (glow_shade_sh(SH, n, 1) + detail)                    (glow_shading.glsl: SH =
 *                glow_sample_lightmap_page at the triangle's lightmap page and uv, detail =
 *                glow_sample_lightmap_detail_page
 *                there for bakes with a lightmap detail; spheres: glow_sample_grid_oriented at p, n, no detail)
 *     emission = the material's (front faces), through an optional GLSL hook (animated emitters)
 * albedo and emission are the bake's materials (glow_bake_get_material) times the CPU system's scales
 * (glow_system_params.emission_scale, glow_system_set_material; effective albedo clamped to 0.999 as
 * the solver does), times the material's albedo texture at the pixel (desc.textures: the paths and
 * material UVs a format-1.1 bake carries, glow_material_info.albedo_texture and
 * glow_bake_geometry.material_uv; loaded with stb_image into one sRGB texture array). Glow's surfels
 * hold the texture's mean over each surfel, so the bounce sees the same colours. Then exposure,
 * Reinhard x/(1+x) and the sRGB curve, in the shader (sample_png.h's sample_tonemap, in GLSL), into an
 * RGBA8 target. Behind the scene, the final view shows sample_gl_frame.sky (the scene's sky radiance).
 * sample_gl_hud writes text (stats, the view's legend: sample_view_legend) over the display target.
 *
 * VIEWS (sample_view_parse, `--view NAME`):
 *   final     the sum above (direct and indirect can be switched off: sample_gl_frame.direct/indirect)
 *   indirect  albedo · glow_shade_sh(...) alone, unclamped (ringing below 0 shows black)
 *   direct    the hook's direct light alone
 *   surfels   the scene dimmed, and every surfel a point coloured by the light it starts the bounce
 *             with: its direct irradiance E/π (the hook at the surfel, or the irradiance pushed to the
 *             CPU system when there is no hook) plus its emission (W/(m²·sr))
 *   charts    lightmap uv as colour (red = u, green = v, texels in a checker) and texels without a
 *             cache (lightmap_valid = 0) in magenta; spheres grey
 *   links     the links of one cache (grid or lightmap, the one nearest sample_gl_frame.pick): lines
 *             from it to the centre of each node it gathers from (glow_solver_tables: cache_positions,
 *             link_blocks, node_positions), coloured by the node's level (blue = single surfels ...
 *             red = large clusters); the cache itself is a white dot
 *   clusters  every surfel coloured by its ancestor at hierarchy level sample_gl_frame.cluster_level
 *             (glow_solver_tables.node_children / level_starts): the clusters links gather from
 *   lit-clusters  the same clusters, each coloured by its radiance after the last GPU update (flux ·
 *             1/(π area) from glow_gl_outputs.flux_buffer, YCoCg -> RGB, exposed and tone-mapped): the
 *             light the caches gather, as the hierarchy sees it
 *
 * TARGETS: colour 0 is the display image (RGBA8, tone-mapped, what the window shows and the PNGs
 * hold). With desc.aux_targets four RGBA32F targets follow, for tests and tools:
 *   1 hdr   the view's linear radiance before exposure (W/(m²·sr)); debug colours as displayed
 *   2 aux0  (lightmap u, v, material index, kind): kind 0 = nothing drawn, 1 = bake triangle, 2 = sphere
 *   3 aux1  (shading normal xyz, 1 when the SH lookup found caches else 0)
 *   4 aux2  (world position xyz, 1)
 *
 * GL STATE: sample_gl_draw binds its framebuffer, program, vertex arrays, texture units 0-6, the
 * material SSBO at SAMPLE_GL_MATERIAL_BINDING and sets depth test, culling, polygon offset, viewport;
 * it leaves them so. The lights' hook resources (UBO 8, texture units 8 and 9) are the caller's to
 * bind (glow_gl_lights_bind) before drawing.
 */
#ifndef GLOW_SAMPLE_GL_H
#define GLOW_SAMPLE_GL_H

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <glow/glow.h>
#include <glow/glow_backend.h> /* the debug views read the solver's tables (not public API) */
#include <glow/glow_gl.h>
#include <glow/glow_glfns.h>
#include <glow/glow_scene.h>
#include <stb/stb_image.h>        /* albedo textures (Debian's libstb) */
#include <stb/stb_image_resize.h> /* ... resized to one texture array */

#include "sample_png.h" /* sample_tonemap: the sky behind the scene */
#include <stb/stb_easy_font.h> /* the HUD's text: quads of a small bitmap font (header-only, public domain) */

#define SAMPLE_GL_PI 3.14159265358979323846f
#define SAMPLE_GL_MATERIAL_BINDING 12 /* SSBO binding of the material table (Glow's kernels use 0-7) */
#define SAMPLE_GL_TARGETS 5           /* colour + hdr + aux0..2 */
#define SAMPLE_GL_TEXTURE_SIZE 512    /* albedo textures are resampled to this square, one array layer each */

typedef enum sample_view {
    SAMPLE_VIEW_FINAL = 0,
    SAMPLE_VIEW_INDIRECT,
    SAMPLE_VIEW_DIRECT,
    SAMPLE_VIEW_SURFELS,
    SAMPLE_VIEW_CHARTS,
    SAMPLE_VIEW_LINKS,
    SAMPLE_VIEW_CLUSTERS,
    SAMPLE_VIEW_LIT_CLUSTERS,
    SAMPLE_VIEW_COUNT
} sample_view;

static inline const char *sample_view_name(int view) {
    static const char *const names[SAMPLE_VIEW_COUNT] = {"final", "indirect", "direct", "surfels",
                                                         "charts", "links", "clusters", "lit-clusters"};
    return view >= 0 && view < SAMPLE_VIEW_COUNT ? names[view] : "?";
}

/* The view called `name`, or -1. */
static inline int sample_view_parse(const char *name) {
    for (int v = 0; v < SAMPLE_VIEW_COUNT; v++)
        if (!strcmp(name, sample_view_name(v))) return v;
    return -1;
}

/* ------------------------------------------------------------------------------------------ maths */
/* Column-major 4x4 (GL's layout). */
static inline void sample_mat4_mul(float out[16], const float a[16], const float b[16]) {
    float r[16];
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float s = 0.0f;
            for (int k = 0; k < 4; k++) s += a[k * 4 + row] * b[c * 4 + k];
            r[c * 4 + row] = s;
        }
    memcpy(out, r, sizeof r);
}

static inline void sample_vec3_normalize(float v[3]) {
    float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0.0f)
        for (int a = 0; a < 3; a++) v[a] /= l;
}

static inline void sample_vec3_cross(const float a[3], const float b[3], float out[3]) {
    float r[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(out, r, sizeof r);
}

/* View-projection of `cam` for an image of aspect w/h, near/far planes from `scene_size` (m). */
static inline void sample_camera_matrix(const glow_scene_camera *cam, float aspect, float scene_size, float out[16]) {
    float f[3] = {cam->target[0] - cam->position[0], cam->target[1] - cam->position[1], cam->target[2] - cam->position[2]};
    sample_vec3_normalize(f);
    float s[3], u[3];
    sample_vec3_cross(f, cam->up, s);
    sample_vec3_normalize(s);
    sample_vec3_cross(s, f, u);
    const float *e = cam->position;
    float view[16] = {s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
                      -(s[0] * e[0] + s[1] * e[1] + s[2] * e[2]), -(u[0] * e[0] + u[1] * e[1] + u[2] * e[2]),
                      f[0] * e[0] + f[1] * e[1] + f[2] * e[2], 1};
    float zn = fmaxf(scene_size * 1e-3f, 1e-4f), zf = scene_size * 8.0f + 1.0f;
    float t = 1.0f / tanf(0.5f * cam->vfov_deg * SAMPLE_GL_PI / 180.0f);
    float proj[16] = {t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (zf + zn) / (zn - zf), -1, 0, 0, 2.0f * zf * zn / (zn - zf), 0};
    sample_mat4_mul(out, proj, view);
}

/* ------------------------------------------------------------------------------------ renderer */
typedef struct sample_gl_desc {
    glow_gl_loader loader;          /* required: the current context's GetProcAddress */
    const glow_bake *bake;          /* required: triangles and materials */
    const glow_system *system;      /* required: the CPU system (surfels, params, material scales) */
    const glow_gl_outputs *outputs; /* required: glow_gl_system_outputs (textures, band counts) */
    const char *light_hook;         /* GLSL defining glow_host_surfel_irradiance (glow_gl_lights_hook_source);
                                       NULL = no direct light on screen (surfels: the pushed irradiance) */
    const char *emission_glsl;      /* optional GLSL: #define SAMPLE_EMISSION_DEFINED and
                                       vec3 sample_emission(vec3 p, vec3 n, uint material, vec3 base)
                                       (base = the material's scaled emission; may read uniform u_time) */
    uint32_t width, height;         /* target size (pixels) */
    bool aux_targets;               /* also the four RGBA32F targets (see TARGETS) */
    bool no_cull;                   /* draw back faces too (default: culled, so a closed room seen from
                                       outside shows its inside) */
    bool textures;                  /* draw the albedo textures the bake names (format 1.1: TEXP, TUV0),
                                       loaded from those paths; materials whose file cannot be read keep
                                       their base albedo (a warning in r->warning) */
} sample_gl_desc;

typedef struct sample_gl_sphere {
    float center[3], radius, albedo[3];
} sample_gl_sphere;

typedef struct sample_gl_frame {
    int view;                        /* sample_view */
    bool direct, indirect;           /* terms of the final view */
    float exposure;                  /* multiplies radiance before the tone map */
    const glow_scene_camera *camera; /* required */
    const sample_gl_sphere *spheres; /* dynamic objects, shaded from the grid */
    uint32_t sphere_count;
    float pick[3];                   /* links view: the cache nearest this point */
    uint32_t cluster_level;          /* clusters view: hierarchy level (clamped) */
    float time;                      /* seconds, uniform u_time of the emission hook */
    float sky[3];                    /* final view: radiance (W/(m²·sr)) behind the scene, brighter towards
                                        the zenith; 0 = black */
} sample_gl_frame;

typedef struct sample_gl {
    glow_glfns gl;
    const glow_bake *bake;
    const glow_system *system;
    const glow_gl_outputs *out;
    bool has_hook, aux, cull;
    uint32_t width, height;
    GLuint fbo, depth_rb, targets[SAMPLE_GL_TARGETS];
    GLuint prog_scene, prog_points, prog_lines;
    GLuint vao_scene, vbo_scene, vao_sphere, vbo_sphere, ibo_sphere, vao_points, vbo_points[5], vao_lines, vbo_lines;
    GLuint ssbo_materials, query[2], sampler;
    GLuint sky_tex;             /* R32F lightmap-space sky visibility for the screen (0 = none: S = 1) */
    GLuint albedo_tex, albedo_sampler; /* SRGB8_ALPHA8 array, one layer per textured material (0 = none) */
    GLuint prog_hud, vao_hud, vbo_hud;  /* sample_gl_hud, created on first use */
    uint32_t textured_materials;
    char warning[640];          /* the first texture that could not be loaded, "" when none */
    uint32_t vertex_count, sphere_index_count, material_count, surfel_count;
    float scene_size, bounds_min[3], bounds_max[3];
    float *material_base;   /* [M][6] the bake's albedo, emission */
    int *material_layer;    /* [M] albedo texture layer, -1 none */
    float *staging;         /* [S][3] */
    uint64_t direct_revision_seen;
    /* hierarchy (links, clusters), built on first use */
    uint32_t *node_parent;  /* [N] */
    uint8_t *node_level;    /* [N] */
    uint32_t cluster_level_seen, line_vertices, picked_cache;
    float picked_pos[3];
    double draw_ms;         /* GPU time of the last draw (timer query) */
    char error[1024];
} sample_gl;

static inline int sample_gl__fail(sample_gl *r, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->error, sizeof r->error, fmt, ap);
    va_end(ap);
    return -1;
}

/* ---------------------------------------------------------------------------------- shaders */
static const char sample_gl__common_glsl[] =
    "#define SAMPLE_VIEW_FINAL 0\n#define SAMPLE_VIEW_INDIRECT 1\n#define SAMPLE_VIEW_DIRECT 2\n"
    "#define SAMPLE_VIEW_SURFELS 3\n#define SAMPLE_VIEW_CHARTS 4\n#define SAMPLE_VIEW_LINKS 5\n"
    "#define SAMPLE_VIEW_CLUSTERS 6\n#define SAMPLE_VIEW_LIT_CLUSTERS 7\n"
    "uniform int u_view;\n"
    "uniform float u_exposure;\n"
    "uniform float u_time;\n"
    /* sample_png.h's sample_tonemap: exposure, Reinhard, sRGB */
    "vec3 sample_display(vec3 x) {\n"
    "    x = x * u_exposure;\n"
    "    bvec3 bad = bvec3(isnan(x.r) || isinf(x.r), isnan(x.g) || isinf(x.g), isnan(x.b) || isinf(x.b));\n"
    "    x = mix(max(x, vec3(0.0)), vec3(0.0), bvec3(bad));\n"
    "    x = x / (1.0 + x);\n"
    "    return mix(1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055, 12.92 * x, lessThanEqual(x, vec3(0.0031308)));\n"
    "}\n"
    "layout(location = 0) out vec4 o_color;\n"
    "layout(location = 1) out vec4 o_hdr;\n"
    "layout(location = 2) out vec4 o_aux0;\n"
    "layout(location = 3) out vec4 o_aux1;\n"
    "layout(location = 4) out vec4 o_aux2;\n";

static const char sample_gl__no_hook_glsl[] =
    "#define GLOW_HOST_SURFEL_IRRADIANCE_DEFINED\n"
    "vec3 glow_host_surfel_irradiance(vec3 position, vec3 normal, uint material) { return vec3(0.0); }\n";

static const char sample_gl__scene_vs[] =
    "#version 450 core\n"
    "layout(location = 0) in vec3 a_pos;\n"
    "layout(location = 1) in vec3 a_nrm;\n"
    "layout(location = 2) in vec2 a_uv;\n"
    "layout(location = 3) in uint a_mat;\n"
    "layout(location = 4) in vec2 a_uv0;\n"
    "layout(location = 5) in uint a_page;\n" /* the triangle's lightmap page (glow_bake_geometry.lightmap_page) */
    "uniform mat4 u_view_proj;\n"
    "uniform vec4 u_sphere;\n"      /* xyz centre, w radius; w = 0: bake triangles */
    "out vec3 v_pos;\nout vec3 v_nrm;\nout vec2 v_uv;\nout vec2 v_uv0;\nflat out uint v_mat;\nflat out uint v_page;\n"
    "void main() {\n"
    "    v_pos = u_sphere.w > 0.0 ? u_sphere.xyz + u_sphere.w * a_pos : a_pos;\n"
    "    v_nrm = a_nrm;\n"
    "    v_uv = a_uv;\n"
    "    v_uv0 = a_uv0;\n"
    "    v_mat = u_sphere.w > 0.0 ? 0u : a_mat;\n"
    "    v_page = u_sphere.w > 0.0 ? 0u : a_page;\n"
    "    gl_Position = u_view_proj * vec4(v_pos, 1.0);\n"
    "}\n";

static const char sample_gl__scene_fs[] =
    "layout(binding = 0) uniform sampler3D u_grid;\n"
    "layout(binding = 1) uniform usampler3D u_grid_mask;\n"
    "layout(binding = 2) uniform sampler2DArray u_lightmap;\n"
    "layout(binding = 3) uniform usampler2D u_lightmap_valid;\n"
    "layout(binding = 6) uniform sampler2D u_lightmap_detail;\n"
    "struct sample_material { vec4 albedo; vec4 emission; };\n"
    "layout(std430, binding = SAMPLE_GL_MATERIAL_BINDING) readonly buffer sample_materials { sample_material sample_mat[]; };\n"
    "uniform int u_direct, u_indirect, u_object, u_has_grid, u_has_lightmap, u_has_detail, u_lightmap_pages;\n"
    "uniform vec3 u_object_albedo, u_grid_origin;\n"
    "uniform float u_grid_spacing;\n"
    "uniform uvec3 u_grid_dims;\n"
    "layout(binding = 4) uniform sampler2D u_sky;\n"
    "layout(binding = 5) uniform sampler2DArray u_albedo_tex;\n" /* material albedo textures (sRGB, linear when read) */
    "uniform int u_has_sky, u_textures;\n"
    "in vec3 v_pos;\nin vec3 v_nrm;\nin vec2 v_uv;\nin vec2 v_uv0;\nflat in uint v_mat;\nflat in uint v_page;\n"
    "void main() {\n"
    /* the sky's visible fraction at this pixel, for the light hook's sky term (GLOW_GL_LIGHTS_PIXEL_SKY) */
    "    if (u_has_sky != 0 && u_object == 0) sample_pixel_sky = textureLod(u_sky, v_uv, 0.0).r;\n"
    "    vec3 n = normalize(v_nrm);\n"
    "    if (!gl_FrontFacing) n = -n;\n"
    "    vec3 albedo = u_object != 0 ? u_object_albedo : sample_mat[v_mat].albedo.rgb;\n"
    /* albedo.w: the material's texture layer, -1 none; v = 1 is the image's top row (the linker's convention) */
    "    if (u_object == 0 && u_textures != 0 && sample_mat[v_mat].albedo.w >= 0.0)\n"
    "        albedo *= texture(u_albedo_tex, vec3(v_uv0.x, 1.0 - v_uv0.y, sample_mat[v_mat].albedo.w)).rgb;\n"
    "    vec3 emission = vec3(0.0);\n"
    "    if (u_object == 0 && gl_FrontFacing) emission = sample_emission(v_pos, n, v_mat, sample_mat[v_mat].emission.rgb);\n"
    "    vec4 sh[GLOW_SH_PLANES];\n"
    "    bool has = false;\n"
    "    if (u_object != 0) { if (u_has_grid != 0) has = glow_sample_grid_oriented(u_grid, u_grid_mask, u_grid_origin, u_grid_spacing, ivec3(u_grid_dims), v_pos, n, sh); }\n"
    "    else if (u_has_lightmap != 0) has = glow_sample_lightmap_page(u_lightmap, u_lightmap_valid, int(v_page), v_uv, sh);\n"
    "    vec3 e_ind = has ? glow_shade_sh(sh, n, 1.0) : vec3(0.0);\n"
    "    if (has && u_object == 0 && u_has_detail != 0)\n"
    "        e_ind += glow_sample_lightmap_detail_page(u_lightmap_detail, u_lightmap_pages, int(v_page), v_uv);\n"
    "    vec3 indirect = albedo * e_ind;\n"
    "    vec3 direct = vec3(0.0);\n"
    "    if (u_view == SAMPLE_VIEW_DIRECT || (u_view == SAMPLE_VIEW_FINAL && u_direct != 0))\n"
    "        direct = glow_host_surfel_irradiance(v_pos, n, v_mat) * albedo * (1.0 / GLOW_PI);\n"
    "    vec3 c;\n"
    "    bool display = false;\n"
    "    if (u_view == SAMPLE_VIEW_INDIRECT) c = indirect;\n"
    "    else if (u_view == SAMPLE_VIEW_DIRECT) c = direct;\n"
    "    else if (u_view == SAMPLE_VIEW_CHARTS) {\n"
    "        display = true;\n"
    "        if (u_object != 0 || u_has_lightmap == 0) c = vec3(0.5);\n"
    "        else {\n"
    "            ivec2 size = textureSize(u_lightmap_valid, 0);\n"
    "            ivec2 t = clamp(ivec2(floor(v_uv * vec2(size))), ivec2(0), size - 1);\n"
    "            bool valid = texelFetch(u_lightmap_valid, t, 0).x != 0u;\n"
    "            float checker = ((t.x + t.y) & 1) == 0 ? 1.0 : 0.75;\n"
    "            c = valid ? vec3(0.15 + 0.85 * v_uv, 0.2) * checker : vec3(1.0, 0.0, 1.0);\n"
    "        }\n"
    "    } else if (u_view != SAMPLE_VIEW_FINAL) { c = 0.08 * albedo; display = true; }\n"
    "    else c = emission + (u_direct != 0 ? direct : vec3(0.0)) + (u_indirect != 0 ? max(indirect, vec3(0.0)) : vec3(0.0));\n"
    "    o_color = vec4(display ? c : sample_display(c), 1.0);\n"
    "    o_hdr = vec4(c, 1.0);\n"
    "    o_aux0 = vec4(v_uv, float(v_mat), u_object != 0 ? 2.0 : 1.0);\n"
    "    o_aux1 = vec4(n, has ? 1.0 : 0.0);\n"
    "    o_aux2 = vec4(v_pos, 1.0);\n"
    "}\n";

static const char sample_gl__points_vs[] =
    "#version 450 core\n"
    "layout(location = 0) in vec4 a_pos;\n"     /* xyz, area */
    "layout(location = 1) in vec4 a_nrm;\n"
    "layout(location = 2) in vec3 a_emission;\n"
    "layout(location = 3) in vec3 a_pushed;\n"
    "layout(location = 4) in vec3 a_cluster;\n"
    "uniform mat4 u_view_proj;\n"
    "uniform vec3 u_eye;\n"
    "flat out vec3 f_pos, f_nrm, f_emission, f_pushed, f_cluster;\n"
    "void main() {\n"
    "    f_pos = a_pos.xyz; f_nrm = a_nrm.xyz; f_emission = a_emission; f_pushed = a_pushed; f_cluster = a_cluster;\n"
    /* surfels facing away are dropped (culled walls would otherwise show their surfels) */
    "    gl_Position = dot(a_nrm.xyz, u_eye - a_pos.xyz) > 0.0 ? u_view_proj * vec4(a_pos.xyz, 1.0) : vec4(2.0, 2.0, 2.0, 1.0);\n"
    "}\n";

static const char sample_gl__points_fs[] =
    "uniform int u_hook;\n"
    "flat in vec3 f_pos, f_nrm, f_emission, f_pushed, f_cluster;\n"
    "void main() {\n"
    "    vec3 c;\n"
    "    bool display = u_view == SAMPLE_VIEW_CLUSTERS;\n"
    "    if (display || u_view == SAMPLE_VIEW_LIT_CLUSTERS) c = f_cluster;\n"
    "    else c = (u_hook != 0 ? glow_host_surfel_irradiance(f_pos, normalize(f_nrm), 0u) : f_pushed) * (1.0 / GLOW_PI) + f_emission;\n"
    "    o_color = vec4(display ? c : sample_display(c), 1.0);\n"
    "    o_hdr = vec4(c, 1.0); o_aux0 = vec4(0.0); o_aux1 = vec4(0.0); o_aux2 = vec4(f_pos, 1.0);\n"
    "}\n";

static const char sample_gl__lines_vs[] =
    "#version 450 core\n"
    "layout(location = 0) in vec3 a_pos;\n"
    "layout(location = 1) in vec3 a_color;\n"
    "uniform mat4 u_view_proj;\n"
    "out vec3 f_color;\n"
    "void main() { f_color = a_color; gl_Position = u_view_proj * vec4(a_pos, 1.0); }\n";

static const char sample_gl__lines_fs[] =
    "in vec3 f_color;\n"
    "void main() { o_color = vec4(f_color, 1.0); o_hdr = o_color; o_aux0 = vec4(0.0); o_aux1 = vec4(0.0); o_aux2 = vec4(0.0); }\n";

static inline GLuint sample_gl__shader(sample_gl *r, GLenum kind, const char *const *parts, int count, const char *what) {
    glow_glfns *gl = &r->gl;
    GLuint s = gl->CreateShader(kind);
    gl->ShaderSource(s, count, parts, NULL);
    gl->CompileShader(s);
    GLint ok = 0;
    gl->GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[768] = "";
        gl->GetShaderInfoLog(s, sizeof log, NULL, log);
        sample_gl__fail(r, "%s shader does not compile: %s", what, log);
        gl->DeleteShader(s);
        return 0;
    }
    return s;
}

/* A program: vs, and the fragment stage = prelude (version, bands, shading include, light hook,
 * common declarations, emission hook) + fs_body. */
static inline GLuint sample_gl__program(sample_gl *r, const char *vs_src, const char *fs_body, const char *hook,
                                        const char *emission, const char *what) {
    glow_glfns *gl = &r->gl;
    char prelude[256];
    snprintf(prelude, sizeof prelude,
             "#version 450 core\n#define GLOW_SH_BANDS_LUMA %u\n#define GLOW_SH_BANDS_CHROMA %u\n"
             "#define SAMPLE_GL_MATERIAL_BINDING %d\n"
             "#define GLOW_GL_LIGHTS_PIXEL_SKY sample_pixel_sky\nfloat sample_pixel_sky = 1.0;\n",
             r->out->sh_bands_luma, r->out->sh_bands_chroma, SAMPLE_GL_MATERIAL_BINDING);
    const char *fs_parts[] = {prelude, glow_gl_shading_source(), "\n#line 1 1\n", hook, "\n#line 1 2\n",
                              sample_gl__common_glsl, "\n#line 1 3\n",
                              emission ? emission : "",
                              "\n#ifndef SAMPLE_EMISSION_DEFINED\n"
                              "vec3 sample_emission(vec3 p, vec3 n, uint material, vec3 base) { return base; }\n"
                              "#endif\n#line 1 4\n",
                              fs_body};
    GLuint vs = sample_gl__shader(r, GL_VERTEX_SHADER, &vs_src, 1, what);
    GLuint fs = vs ? sample_gl__shader(r, GL_FRAGMENT_SHADER, fs_parts, (int)(sizeof fs_parts / sizeof *fs_parts), what) : 0;
    if (!fs) {
        if (vs) gl->DeleteShader(vs);
        return 0;
    }
    GLuint p = gl->CreateProgram();
    gl->AttachShader(p, vs);
    gl->AttachShader(p, fs);
    gl->LinkProgram(p);
    gl->DeleteShader(vs);
    gl->DeleteShader(fs);
    GLint ok = 0;
    gl->GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[768] = "";
        gl->GetProgramInfoLog(p, sizeof log, NULL, log);
        sample_gl__fail(r, "%s program does not link: %s", what, log);
        gl->DeleteProgram(p);
        return 0;
    }
    return p;
}

/* ---------------------------------------------------------------------------------- targets */
static inline void sample_gl__free_targets(sample_gl *r) {
    glow_glfns *gl = &r->gl;
    if (r->fbo) gl->DeleteFramebuffers(1, &r->fbo);
    if (r->depth_rb) gl->DeleteRenderbuffers(1, &r->depth_rb);
    for (int i = 0; i < SAMPLE_GL_TARGETS; i++)
        if (r->targets[i]) gl->DeleteTextures(1, &r->targets[i]);
    r->fbo = r->depth_rb = 0;
    memset(r->targets, 0, sizeof r->targets);
}

/* (Re)creates the framebuffer at w x h. 0 on success; -1 with r->error. */
static inline int sample_gl_resize(sample_gl *r, uint32_t w, uint32_t h) {
    glow_glfns *gl = &r->gl;
    if (w < 1 || h < 1 || w > 16384 || h > 16384) return sample_gl__fail(r, "target size %ux%u out of range", w, h);
    sample_gl__free_targets(r);
    r->width = w, r->height = h;
    gl->CreateFramebuffers(1, &r->fbo);
    gl->CreateRenderbuffers(1, &r->depth_rb);
    gl->NamedRenderbufferStorage(r->depth_rb, GL_DEPTH_COMPONENT32F, (GLsizei)w, (GLsizei)h);
    gl->NamedFramebufferRenderbuffer(r->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, r->depth_rb);
    GLenum bufs[SAMPLE_GL_TARGETS];
    int n = r->aux ? SAMPLE_GL_TARGETS : 1;
    for (int i = 0; i < n; i++) {
        gl->CreateTextures(GL_TEXTURE_2D, 1, &r->targets[i]);
        gl->TextureStorage2D(r->targets[i], 1, i == 0 ? GL_RGBA8 : GL_RGBA32F, (GLsizei)w, (GLsizei)h);
        gl->TextureParameteri(r->targets[i], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        gl->TextureParameteri(r->targets[i], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        gl->NamedFramebufferTexture(r->fbo, GL_COLOR_ATTACHMENT0 + (GLenum)i, r->targets[i], 0);
        bufs[i] = GL_COLOR_ATTACHMENT0 + (GLenum)i;
    }
    for (int i = n; i < SAMPLE_GL_TARGETS; i++) bufs[i] = GL_NONE;
    gl->NamedFramebufferDrawBuffers(r->fbo, SAMPLE_GL_TARGETS, bufs);
    GLenum status = gl->CheckNamedFramebufferStatus(r->fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        return sample_gl__fail(r, "framebuffer %ux%u incomplete (status 0x%x)", w, h, (unsigned)status);
    return 0;
}

/* ---------------------------------------------------------------------------------- create */
typedef struct sample_gl__vertex {
    float pos[3], nrm[3];
    uint16_t uv[2];
    uint32_t mat;
    float uv0[2]; /* material UV (glow_bake_geometry.material_uv), 0 when the bake has none */
    uint32_t page; /* lightmap page (glow_bake_geometry.lightmap_page), 0 with one page */
} sample_gl__vertex;

static inline int sample_gl__upload_scene(sample_gl *r) {
    glow_glfns *gl = &r->gl;
    glow_bake_geometry g;
    if (glow_bake_get_geometry(r->bake, &g) != GLOW_OK || g.triangle_count == 0)
        return sample_gl__fail(r, "the bake carries no triangles (glow_bake_get_geometry)");
    glow_bake_info info;
    glow_bake_get_info(r->bake, &info);
    r->material_count = info.material_count;
    r->vertex_count = 3 * g.triangle_count;
    sample_gl__vertex *v = calloc(r->vertex_count, sizeof *v);
    if (!v) return sample_gl__fail(r, "out of memory (%u vertices)", r->vertex_count);
    for (uint32_t t = 0; t < g.triangle_count; t++) {
        const float *p = (const float *)((const unsigned char *)g.positions + (size_t)t * g.stride);
        const uint16_t *uv = (const uint16_t *)((const unsigned char *)g.lightmap_uv + (size_t)t * g.stride);
        uint32_t mat = *(const uint32_t *)((const unsigned char *)g.materials + (size_t)t * g.stride);
        float e1[3] = {p[3] - p[0], p[4] - p[1], p[5] - p[2]}, e2[3] = {p[6] - p[0], p[7] - p[1], p[8] - p[2]}, n[3];
        sample_vec3_cross(e1, e2, n);
        sample_vec3_normalize(n);
        for (int k = 0; k < 3; k++) {
            sample_gl__vertex *o = &v[3 * (size_t)t + (size_t)k];
            memcpy(o->pos, p + 3 * k, sizeof o->pos);
            memcpy(o->nrm, n, sizeof n);
            o->uv[0] = uv[2 * k], o->uv[1] = uv[2 * k + 1];
            o->mat = mat < info.material_count ? mat : 0;
            o->page = g.lightmap_page ? g.lightmap_page[t] : 0u;
            if (g.material_uv) o->uv0[0] = g.material_uv[6 * (size_t)t + 2 * k], o->uv0[1] = g.material_uv[6 * (size_t)t + 2 * k + 1];
        }
    }
    gl->CreateBuffers(1, &r->vbo_scene);
    gl->NamedBufferStorage(r->vbo_scene, (GLsizeiptr)(r->vertex_count * sizeof *v), v, 0);
    free(v);
    gl->CreateVertexArrays(1, &r->vao_scene);
    gl->VertexArrayVertexBuffer(r->vao_scene, 0, r->vbo_scene, 0, sizeof(sample_gl__vertex));
    for (GLuint a = 0; a < 6; a++) {
        gl->EnableVertexArrayAttrib(r->vao_scene, a);
        gl->VertexArrayAttribBinding(r->vao_scene, a, 0);
    }
    gl->VertexArrayAttribFormat(r->vao_scene, 4, 2, GL_FLOAT, GL_FALSE, offsetof(sample_gl__vertex, uv0));
    gl->VertexArrayAttribFormat(r->vao_scene, 0, 3, GL_FLOAT, GL_FALSE, offsetof(sample_gl__vertex, pos));
    gl->VertexArrayAttribFormat(r->vao_scene, 1, 3, GL_FLOAT, GL_FALSE, offsetof(sample_gl__vertex, nrm));
    gl->VertexArrayAttribFormat(r->vao_scene, 2, 2, GL_UNSIGNED_SHORT, GL_TRUE, offsetof(sample_gl__vertex, uv));
    gl->VertexArrayAttribIFormat(r->vao_scene, 3, 1, GL_UNSIGNED_INT, offsetof(sample_gl__vertex, mat));
    gl->VertexArrayAttribIFormat(r->vao_scene, 5, 1, GL_UNSIGNED_INT, offsetof(sample_gl__vertex, page));
    /* materials: the bake's, scaled per draw */
    r->material_base = calloc((size_t)r->material_count * 6 + 6, sizeof(float));
    if (!r->material_base) return sample_gl__fail(r, "out of memory");
    for (uint32_t m = 0; m < r->material_count; m++) {
        glow_material_info mi;
        if (glow_bake_get_material(r->bake, m, &mi) != GLOW_OK) continue;
        memcpy(r->material_base + 6 * (size_t)m, mi.albedo, 3 * sizeof(float));
        memcpy(r->material_base + 6 * (size_t)m + 3, mi.emission, 3 * sizeof(float));
    }
    gl->CreateBuffers(1, &r->ssbo_materials);
    gl->NamedBufferStorage(r->ssbo_materials, (GLsizeiptr)(((size_t)r->material_count + 1) * 8 * sizeof(float)), NULL,
                           GL_DYNAMIC_STORAGE_BIT);
    for (int a = 0; a < 3; a++) {
        r->bounds_min[a] = info.bounds_min[a], r->bounds_max[a] = info.bounds_max[a];
        float d = info.bounds_max[a] - info.bounds_min[a];
        r->scene_size += d * d;
    }
    r->scene_size = sqrtf(r->scene_size);
    return 0;
}

/* A unit UV sphere (positions = normals), 32 x 16 segments. */
static inline void sample_gl__upload_sphere(sample_gl *r) {
    glow_glfns *gl = &r->gl;
    enum { SEG = 32, RINGS = 16 };
    static float vtx[(SEG + 1) * (RINGS + 1) * 6];
    static uint32_t idx[SEG * RINGS * 6];
    uint32_t nv = 0, ni = 0;
    for (int j = 0; j <= RINGS; j++) {
        float th = SAMPLE_GL_PI * (float)j / RINGS;
        for (int i = 0; i <= SEG; i++) {
            float ph = 2.0f * SAMPLE_GL_PI * (float)i / SEG;
            float p[3] = {sinf(th) * cosf(ph), cosf(th), -sinf(th) * sinf(ph)};
            memcpy(vtx + 6 * nv, p, sizeof p);
            memcpy(vtx + 6 * nv + 3, p, sizeof p);
            nv++;
        }
    }
    for (int j = 0; j < RINGS; j++)
        for (int i = 0; i < SEG; i++) {
            uint32_t a = (uint32_t)(j * (SEG + 1) + i), b = a + SEG + 1;
            uint32_t q[6] = {a, b, a + 1, a + 1, b, b + 1};
            memcpy(idx + ni, q, sizeof q);
            ni += 6;
        }
    r->sphere_index_count = ni;
    gl->CreateBuffers(1, &r->vbo_sphere);
    gl->NamedBufferStorage(r->vbo_sphere, (GLsizeiptr)(nv * 6 * sizeof(float)), vtx, 0);
    gl->CreateBuffers(1, &r->ibo_sphere);
    gl->NamedBufferStorage(r->ibo_sphere, (GLsizeiptr)(ni * sizeof(uint32_t)), idx, 0);
    gl->CreateVertexArrays(1, &r->vao_sphere);
    gl->VertexArrayVertexBuffer(r->vao_sphere, 0, r->vbo_sphere, 0, 6 * sizeof(float));
    gl->VertexArrayElementBuffer(r->vao_sphere, r->ibo_sphere);
    for (GLuint a = 0; a < 2; a++) {
        gl->EnableVertexArrayAttrib(r->vao_sphere, a);
        gl->VertexArrayAttribBinding(r->vao_sphere, a, 0);
        gl->VertexArrayAttribFormat(r->vao_sphere, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
    }
}

static inline int sample_gl__upload_surfels(sample_gl *r) {
    glow_glfns *gl = &r->gl;
    glow_surfel_view sv;
    if (glow_system_get_surfels(r->system, &sv) != GLOW_OK) return sample_gl__fail(r, "glow_system_get_surfels failed");
    r->surfel_count = sv.count;
    r->staging = calloc((size_t)sv.count * 3 + 3, sizeof(float));
    if (!r->staging) return sample_gl__fail(r, "out of memory (%u surfels)", sv.count);
    gl->CreateBuffers(5, r->vbo_points);
    if (sv.count == 0) return sample_gl__fail(r, "the system has no surfels");
    gl->NamedBufferStorage(r->vbo_points[0], (GLsizeiptr)((size_t)sv.count * 16), sv.positions, 0);
    gl->NamedBufferStorage(r->vbo_points[1], (GLsizeiptr)((size_t)sv.count * 16), sv.normals, 0);
    for (int b = 2; b < 5; b++)
        gl->NamedBufferStorage(r->vbo_points[b], (GLsizeiptr)((size_t)sv.count * 12), r->staging, GL_DYNAMIC_STORAGE_BIT);
    gl->CreateVertexArrays(1, &r->vao_points);
    for (GLuint a = 0; a < 5; a++) {
        gl->VertexArrayVertexBuffer(r->vao_points, a, r->vbo_points[a], 0, a < 2 ? 16 : 12);
        gl->EnableVertexArrayAttrib(r->vao_points, a);
        gl->VertexArrayAttribBinding(r->vao_points, a, a);
        gl->VertexArrayAttribFormat(r->vao_points, a, a < 2 ? 4 : 3, GL_FLOAT, GL_FALSE, 0);
    }
    gl->CreateBuffers(1, &r->vbo_lines);
    gl->CreateVertexArrays(1, &r->vao_lines);
    gl->VertexArrayVertexBuffer(r->vao_lines, 0, r->vbo_lines, 0, 6 * sizeof(float));
    for (GLuint a = 0; a < 2; a++) {
        gl->EnableVertexArrayAttrib(r->vao_lines, a);
        gl->VertexArrayAttribBinding(r->vao_lines, a, 0);
        gl->VertexArrayAttribFormat(r->vao_lines, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
    }
    return 0;
}

static inline void sample_gl_destroy(sample_gl *r) {
    if (!r->gl.DeleteBuffers) return;
    glow_glfns *gl = &r->gl;
    sample_gl__free_targets(r);
    GLuint progs[3] = {r->prog_scene, r->prog_points, r->prog_lines};
    for (int i = 0; i < 3; i++)
        if (progs[i]) gl->DeleteProgram(progs[i]);
    GLuint bufs[9] = {r->vbo_scene, r->vbo_sphere, r->ibo_sphere, r->vbo_lines, r->ssbo_materials,
                      r->vbo_points[0], r->vbo_points[1], r->vbo_points[2], r->vbo_points[3]};
    for (int i = 0; i < 9; i++)
        if (bufs[i]) gl->DeleteBuffers(1, &bufs[i]);
    if (r->vbo_points[4]) gl->DeleteBuffers(1, &r->vbo_points[4]);
    GLuint vaos[4] = {r->vao_scene, r->vao_sphere, r->vao_points, r->vao_lines};
    for (int i = 0; i < 4; i++)
        if (vaos[i]) gl->DeleteVertexArrays(1, &vaos[i]);
    if (r->query[0]) gl->DeleteQueries(2, r->query);
    if (r->sampler) gl->DeleteSamplers(1, &r->sampler);
    if (r->sky_tex) gl->DeleteTextures(1, &r->sky_tex);
    if (r->albedo_tex) gl->DeleteTextures(1, &r->albedo_tex);
    if (r->prog_hud) gl->DeleteProgram(r->prog_hud);
    if (r->vbo_hud) gl->DeleteBuffers(1, &r->vbo_hud);
    if (r->vao_hud) gl->DeleteVertexArrays(1, &r->vao_hud);
    if (r->albedo_sampler) gl->DeleteSamplers(1, &r->albedo_sampler);
    free(r->material_layer);
    free(r->material_base);
    free(r->staging);
    free(r->node_parent);
    free(r->node_level);
    memset(r, 0, sizeof *r);
}

/* The sky's visible fraction S per surfel (glow_host_sky_visibility) turned into a lightmap-space texture
 * for the screen: each texel gets the mean S of the surfels that feed its cache (glow_solver_tables.feedback),
 * texels without a cache the mean of all; linear filtering. 0 on success. */
static inline int sample_gl_set_sky_visibility(sample_gl *r, const float *S, uint32_t count) {
    const glow_cache_outputs *co = glow_system_outputs(r->system);
    glow_solver_tables t;
    glow_system_get_solver_tables(r->system, &t);
    if (!co->lightmap_map || count != t.surfel_count) return 0; /* no lightmap: the screen keeps S = 1 */
    const uint32_t W = co->lightmap_width, H = co->lightmap_height, C = t.cache_count;
    double *sum = calloc((size_t)C + 1, sizeof *sum);
    uint32_t *cnt = calloc((size_t)C + 1, sizeof *cnt);
    float *tex = malloc((size_t)W * H * sizeof *tex);
    if (!sum || !cnt || !tex) {
        free(sum), free(cnt), free(tex);
        return sample_gl__fail(r, "out of memory for the sky texture");
    }
    double all = 0.0;
    for (uint32_t i = 0; i < count; i++) {
        const uint32_t c = t.feedback[i] < C ? t.feedback[i] : C;
        sum[c] += S[i], cnt[c]++, all += S[i];
    }
    const float mean = count ? (float)(all / count) : 1.0f;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        const uint32_t c = co->lightmap_map[i];
        tex[i] = c < C && cnt[c] ? (float)(sum[c] / cnt[c]) : mean;
    }
    glow_glfns *gl = &r->gl;
    if (!r->sky_tex) {
        gl->CreateTextures(GL_TEXTURE_2D, 1, &r->sky_tex);
        gl->TextureStorage2D(r->sky_tex, 1, GL_R32F, (GLsizei)W, (GLsizei)H);
        gl->TextureParameteri(r->sky_tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        gl->TextureParameteri(r->sky_tex, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        gl->TextureParameteri(r->sky_tex, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        gl->TextureParameteri(r->sky_tex, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    gl->TextureSubImage2D(r->sky_tex, 0, 0, 0, (GLsizei)W, (GLsizei)H, GL_RED, GL_FLOAT, tex);
    free(sum), free(cnt), free(tex);
    return 0;
}

/* Loads the GL functions, compiles the programs, uploads the bake's triangles and surfels and creates
 * the targets. 0 on success; -1 with the reason in r->error (r is then destroyed). */
/* The materials' albedo textures (glow_material_info.albedo_texture), each resampled to
 * SAMPLE_GL_TEXTURE_SIZE² in sRGB and stored as one layer of an SRGB8_ALPHA8 array with mipmaps;
 * materials naming the same file share a layer. A file that cannot be read leaves its material
 * untextured and is named in r->warning. */
static inline int sample_gl__load_textures(sample_gl *r) {
    const uint32_t M = r->material_count, T = SAMPLE_GL_TEXTURE_SIZE;
    r->material_layer = malloc(((size_t)M + 1) * sizeof *r->material_layer);
    if (!r->material_layer) return sample_gl__fail(r, "out of memory");
    for (uint32_t m = 0; m < M; m++) r->material_layer[m] = -1;
    glow_material_info *mi = calloc((size_t)M + 1, sizeof *mi);
    unsigned char *layers = NULL;
    uint32_t count = 0;
    if (!mi) return sample_gl__fail(r, "out of memory");
    for (uint32_t m = 0; m < M; m++) {
        if (glow_bake_get_material(r->bake, m, &mi[m]) != GLOW_OK || !mi[m].albedo_texture[0]) continue;
        for (uint32_t k = 0; k < m && r->material_layer[m] < 0; k++)
            if (r->material_layer[k] >= 0 && !strcmp(mi[k].albedo_texture, mi[m].albedo_texture))
                r->material_layer[m] = r->material_layer[k];
        if (r->material_layer[m] >= 0) continue;
        int w = 0, h = 0, n = 0;
        unsigned char *px = stbi_load(mi[m].albedo_texture, &w, &h, &n, 4);
        unsigned char *grown = px ? realloc(layers, ((size_t)count + 1) * T * T * 4) : NULL;
        if (!px || !grown) {
            if (!r->warning[0])
                snprintf(r->warning, sizeof r->warning, "%.400s: cannot read the albedo texture (%.40s); material '%.31s' drawn untextured",
                         mi[m].albedo_texture, px ? "out of memory" : stbi_failure_reason(), mi[m].name);
            stbi_image_free(px);
            continue;
        }
        layers = grown;
        stbir_resize_uint8_srgb(px, w, h, 0, layers + (size_t)count * T * T * 4, (int)T, (int)T, 0, 4, 3, 0);
        stbi_image_free(px);
        r->material_layer[m] = (int)count++;
    }
    free(mi);
    r->textured_materials = 0;
    for (uint32_t m = 0; m < M; m++) r->textured_materials += r->material_layer[m] >= 0;
    if (count) {
        glow_glfns *gl = &r->gl;
        GLsizei levels = 1;
        while ((T >> levels) > 0) levels++;
        gl->CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &r->albedo_tex);
        gl->TextureStorage3D(r->albedo_tex, levels, GL_SRGB8_ALPHA8, (GLsizei)T, (GLsizei)T, (GLsizei)count);
        gl->TextureSubImage3D(r->albedo_tex, 0, 0, 0, 0, (GLsizei)T, (GLsizei)T, (GLsizei)count, GL_RGBA, GL_UNSIGNED_BYTE,
                              layers);
        gl->GenerateTextureMipmap(r->albedo_tex);
        gl->CreateSamplers(1, &r->albedo_sampler);
        gl->SamplerParameteri(r->albedo_sampler, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        gl->SamplerParameteri(r->albedo_sampler, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        gl->SamplerParameteri(r->albedo_sampler, GL_TEXTURE_WRAP_S, GL_REPEAT);
        gl->SamplerParameteri(r->albedo_sampler, GL_TEXTURE_WRAP_T, GL_REPEAT);
    }
    free(layers);
    return 0;
}

static inline int sample_gl_create(sample_gl *r, const sample_gl_desc *d) {
    memset(r, 0, sizeof *r);
    if (!d || !d->loader || !d->bake || !d->system || !d->outputs)
        return sample_gl__fail(r, "sample_gl_create: loader, bake, system and outputs are required");
    char missing[128] = "";
    if (!glow_glfns_load(&r->gl, d->loader, missing, sizeof missing))
        return sample_gl__fail(r, "GL entry points missing: %s", missing);
    r->bake = d->bake, r->system = d->system, r->out = d->outputs;
    r->has_hook = d->light_hook != NULL;
    r->aux = d->aux_targets;
    r->cull = !d->no_cull;
    r->cluster_level_seen = UINT32_MAX;
    r->picked_cache = UINT32_MAX;
    const char *hook = d->light_hook ? d->light_hook : sample_gl__no_hook_glsl;
    int rc = 0;
    if (!(r->prog_scene = sample_gl__program(r, sample_gl__scene_vs, sample_gl__scene_fs, hook, d->emission_glsl, "scene")) ||
        !(r->prog_points = sample_gl__program(r, sample_gl__points_vs, sample_gl__points_fs, hook, d->emission_glsl, "surfel")) ||
        !(r->prog_lines = sample_gl__program(r, sample_gl__lines_vs, sample_gl__lines_fs, hook, d->emission_glsl, "lines")))
        rc = -1;
    if (rc == 0) rc = sample_gl__upload_scene(r);
    if (rc == 0 && d->textures) rc = sample_gl__load_textures(r);
    if (rc == 0) rc = sample_gl__upload_surfels(r);
    if (rc == 0) {
        sample_gl__upload_sphere(r);
        r->gl.CreateQueries(GL_TIMESTAMP, 2, r->query);
        /* Glow's outputs are read with texelFetch, but an integer texture (the grid mask RG32UI, the
         * lightmap valid R8UI) whose filter is LINEAR — GL's default magnification filter — is
         * incomplete, and texelFetch of an incomplete texture returns 0 (everything "empty"). The GL
         * system leaves its textures' filters at the defaults, so the draw binds this NEAREST sampler
         * object on the four units instead of touching Glow's texture state. */
        r->gl.CreateSamplers(1, &r->sampler);
        r->gl.SamplerParameteri(r->sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        r->gl.SamplerParameteri(r->sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        rc = sample_gl_resize(r, d->width, d->height);
    }
    if (rc == 0 && r->gl.GetError() != GL_NO_ERROR) rc = sample_gl__fail(r, "GL error while creating the renderer");
    if (rc != 0) {
        char why[sizeof r->error];
        memcpy(why, r->error, sizeof why);
        sample_gl_destroy(r);
        memcpy(r->error, why, sizeof why);
    }
    return rc;
}

/* ---------------------------------------------------------------------------- hierarchy views */
static inline int sample_gl__hierarchy(sample_gl *r, glow_solver_tables *t) {
    if (r->node_parent) return 0;
    const uint32_t N = t->node_count;
    r->node_parent = malloc(((size_t)N + 1) * sizeof(uint32_t));
    r->node_level = calloc((size_t)N + 1, 1);
    if (!r->node_parent || !r->node_level) return sample_gl__fail(r, "out of memory (%u nodes)", N);
    for (uint32_t n = 0; n < N; n++) r->node_parent[n] = UINT32_MAX;
    for (uint32_t lv = 1; lv < t->level_count; lv++)
        for (uint32_t n = t->level_starts[lv]; n < t->level_starts[lv + 1] && n < N; n++) {
            r->node_level[n] = (uint8_t)(lv < 255 ? lv : 255);
            for (int k = 0; k < 2; k++) {
                uint32_t c = t->node_children[(size_t)n * t->node_stride + (size_t)k];
                if (c < N) r->node_parent[c] = n;
            }
        }
    return 0;
}

/* A colour for level `lv` of `levels`: blue (leaves) -> green -> red (top). */
static inline void sample_gl__level_color(uint32_t lv, uint32_t levels, float out[3]) {
    float x = levels > 1 ? (float)lv / (float)(levels - 1) : 0.0f;
    out[0] = fminf(fmaxf(2.0f * x - 0.5f, 0.0f), 1.0f);
    out[1] = fminf(fmaxf(1.5f - fabsf(4.0f * x - 2.0f), 0.0f), 1.0f);
    out[2] = fminf(fmaxf(1.5f - 2.0f * x, 0.0f), 1.0f);
}

/* Lines from the cache nearest `pick` to its links' nodes. */
static inline void sample_gl__build_links(sample_gl *r, glow_solver_tables *t, const float pick[3]) {
    r->line_vertices = 0;
    if (!t->cache_positions || !t->node_positions || sample_gl__hierarchy(r, t) != 0) return;
    uint32_t best = UINT32_MAX;
    float best_d = INFINITY, pos[3] = {0, 0, 0};
    for (uint32_t c = 0; c < t->cache_count; c++) {
        const float *p = t->cache_positions + (size_t)c * t->cache_stride;
        float d = (p[0] - pick[0]) * (p[0] - pick[0]) + (p[1] - pick[1]) * (p[1] - pick[1]) + (p[2] - pick[2]) * (p[2] - pick[2]);
        if (d < best_d) best_d = d, best = c, memcpy(pos, p, sizeof pos);
    }
    r->picked_cache = best;
    memcpy(r->picked_pos, pos, sizeof pos);
    if (best == UINT32_MAX || best >= t->cache_count) return;
    size_t nv = 2 * (size_t)t->links_per_cache + 1;
    float *v = malloc(nv * 6 * sizeof(float));
    if (!v) return;
    const unsigned char *blocks = (const unsigned char *)t->link_blocks + (size_t)best * t->link_blocks_per_cache * 128;
    uint32_t n = 0;
    for (uint32_t j = 0; j < t->links_per_cache; j++) {
        const unsigned char *b = blocks + (size_t)(j / 16) * 128;
        uint32_t node_dir;
        uint16_t omc;
        memcpy(&node_dir, b + 4 * (j % 16), 4);
        memcpy(&omc, b + 64 + 2 * (j % 16), 2);
        uint32_t node = node_dir & 0xFFFFFFu;
        if ((omc & 0x7FFFu) == 0 || node >= t->node_count) continue; /* unused lane */
        float col[3];
        sample_gl__level_color(r->node_level[node], t->level_count, col);
        float *a = v + 6 * (size_t)n;
        memcpy(a, pos, 3 * sizeof(float));
        memcpy(a + 3, col, sizeof col);
        memcpy(a + 6, t->node_positions + (size_t)node * t->node_stride, 3 * sizeof(float));
        memcpy(a + 9, col, sizeof col);
        n += 2;
    }
    float *m = v + 6 * (size_t)n; /* the cache itself: a white point */
    memcpy(m, pos, sizeof pos);
    m[3] = m[4] = m[5] = 1.0f;
    n++;
    r->gl.NamedBufferData(r->vbo_lines, (GLsizeiptr)(n * 6 * sizeof(float)), v, GL_DYNAMIC_DRAW);
    r->line_vertices = n;
    free(v);
}

static inline void sample_gl__build_clusters(sample_gl *r, glow_solver_tables *t, uint32_t level) {
    if (sample_gl__hierarchy(r, t) != 0) return;
    if (level >= t->level_count) level = t->level_count ? t->level_count - 1 : 0;
    if (level == r->cluster_level_seen) return;
    r->cluster_level_seen = level;
    for (uint32_t s = 0; s < r->surfel_count; s++) {
        uint32_t a = s;
        while (r->node_level[a] < level && r->node_parent[a] != UINT32_MAX) a = r->node_parent[a];
        uint32_t h = a * 2654435761u;
        h ^= h >> 15;
        h *= 2246822519u;
        h ^= h >> 13;
        for (int c = 0; c < 3; c++) r->staging[3 * (size_t)s + c] = 0.2f + 0.8f * (float)((h >> (8 * c)) & 255u) / 255.0f;
    }
    r->gl.NamedBufferSubData(r->vbo_points[4], 0, (GLsizeiptr)((size_t)r->surfel_count * 12), r->staging);
}

/* lit-clusters: each surfel gets its level-`level` ancestor's radiance (RGB W/(m²·sr)) from the GPU's node
 * flux (read back: a debug view, not a per-frame path of an engine). */
static inline void sample_gl__build_lit_clusters(sample_gl *r, glow_solver_tables *t, uint32_t level) {
    if (sample_gl__hierarchy(r, t) != 0 || !r->out || !r->out->flux_buffer) return;
    if (level >= t->level_count) level = t->level_count ? t->level_count - 1 : 0;
    const size_t N = t->node_count;
    float *flux = malloc(N * 4 * sizeof(float));
    if (!flux) return;
    r->gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    r->gl.GetNamedBufferSubData(r->out->flux_buffer, 0, (GLsizeiptr)(N * 16), flux);
    for (uint32_t s = 0; s < r->surfel_count; s++) {
        uint32_t a = s;
        while (r->node_level[a] < level && r->node_parent[a] != UINT32_MAX) a = r->node_parent[a];
        const float *f = flux + 4 * (size_t)a;
        const float y = f[0] * f[3], co = f[1] * f[3], cg = f[2] * f[3];
        r->staging[3 * (size_t)s] = y + co - cg;
        r->staging[3 * (size_t)s + 1] = y + cg;
        r->staging[3 * (size_t)s + 2] = y - co - cg;
    }
    free(flux);
    r->cluster_level_seen = UINT32_MAX; /* the clusters view must rebuild its colours */
    r->gl.NamedBufferSubData(r->vbo_points[4], 0, (GLsizeiptr)((size_t)r->surfel_count * 12), r->staging);
}

/* ---------------------------------------------------------------------------------- draw */
static inline void sample_gl__upload_materials(sample_gl *r, const glow_solver_tables *t) {
    glow_system_params prm;
    glow_system_get_params(r->system, &prm);
    float *m = malloc(((size_t)r->material_count + 1) * 8 * sizeof(float));
    if (!m) return;
    for (uint32_t i = 0; i < r->material_count; i++) {
        const float *base = r->material_base + 6 * (size_t)i;
        for (int c = 0; c < 3; c++) {
            float as = t->material_albedo_scale ? t->material_albedo_scale[3 * (size_t)i + (size_t)c] : 1.0f;
            float es = t->material_emission_scale ? t->material_emission_scale[3 * (size_t)i + (size_t)c] : 1.0f;
            m[8 * (size_t)i + (size_t)c] = fminf(fmaxf(base[c] * as, 0.0f), 0.999f);
            m[8 * (size_t)i + 4 + (size_t)c] = base[3 + c] * es * prm.emission_scale;
        }
        m[8 * (size_t)i + 3] = r->material_layer && r->material_layer[i] >= 0 ? (float)r->material_layer[i] : -1.0f;
        m[8 * (size_t)i + 7] = 0.0f;
    }
    r->gl.NamedBufferSubData(r->ssbo_materials, 0, (GLsizeiptr)((size_t)r->material_count * 8 * sizeof(float)), m);
    free(m);
}

/* The surfel colours: emission (scaled) and, without a hook, the pushed direct irradiance. */
static inline void sample_gl__upload_surfel_light(sample_gl *r, const glow_solver_tables *t) {
    glow_system_params prm;
    glow_system_get_params(r->system, &prm);
    const size_t S = r->surfel_count;
    for (size_t s = 0; s < S; s++) {
        uint32_t mat = t->materials[s] < t->material_count ? t->materials[s] : 0;
        for (int c = 0; c < 3; c++)
            r->staging[3 * s + (size_t)c] = t->emission[3 * s + (size_t)c] * prm.emission_scale *
                                            (t->material_emission_scale ? t->material_emission_scale[3 * (size_t)mat + (size_t)c] : 1.0f);
    }
    r->gl.NamedBufferSubData(r->vbo_points[2], 0, (GLsizeiptr)(S * 12), r->staging);
    if (!r->has_hook && t->direct_irradiance && t->direct_revision != r->direct_revision_seen) {
        r->gl.NamedBufferSubData(r->vbo_points[3], 0, (GLsizeiptr)(S * 12), t->direct_irradiance);
        r->direct_revision_seen = t->direct_revision;
    }
}

static inline void sample_gl__set_common(sample_gl *r, GLuint prog, const sample_gl_frame *f, const float vp[16]) {
    glow_glfns *gl = &r->gl;
    gl->UseProgram(prog);
    gl->UniformMatrix4fv(gl->GetUniformLocation(prog, "u_view_proj"), 1, GL_FALSE, vp);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_view"), f->view);
    gl->Uniform1f(gl->GetUniformLocation(prog, "u_exposure"), f->exposure);
    gl->Uniform1f(gl->GetUniformLocation(prog, "u_time"), f->time);
}

/* The legend of each view, for the HUD. */
static inline const char *sample_view_legend(int view) {
    switch (view) {
    case SAMPLE_VIEW_FINAL: return "final: emission + direct (the lights' hook) + indirect (albedo x Glow's SH)";
    case SAMPLE_VIEW_INDIRECT: return "indirect: albedo x Glow's SH alone, unclamped (SH ringing below 0 shows black)";
    case SAMPLE_VIEW_DIRECT: return "direct: the lights' hook alone (shadow-mapped sun, point and spot lights, sky)";
    case SAMPLE_VIEW_SURFELS: return "surfels: each dot the light its surfel starts the bounce with (E/pi + emission)";
    case SAMPLE_VIEW_CHARTS: return "charts: red = lightmap u, green = v, checker = texels; magenta = a texel without a cache";
    case SAMPLE_VIEW_LINKS: return "links: one cache (white dot) to the nodes it gathers from; blue = one surfel ... red = large clusters";
    case SAMPLE_VIEW_CLUSTERS: return "clusters: surfels coloured by their ancestor at level K (K / L: down / up)";
    case SAMPLE_VIEW_LIT_CLUSTERS: return "lit-clusters: each cluster's radiance after the last GPU update";
    default: return "";
    }
}

/* Draws `text` (lines split at '\n') at the top left of the display target (colour 0 of the
 * renderer's framebuffer, also in the PNGs), white on a translucent dark box, through stb_easy_font's
 * quads scaled 2x. Leaves blending and depth test off. 0, or -1 with r->error. */
static inline int sample_gl_hud(sample_gl *r, const char *text) {
    glow_glfns *gl = &r->gl;
    if (!r->prog_hud) {
        static const char vs[] = "#version 450 core\n"
                                 "layout(location = 0) in vec2 a_px;\n"
                                 "uniform vec2 u_size;\n"
                                 "void main() { gl_Position = vec4(a_px.x / u_size.x * 2.0 - 1.0, 1.0 - a_px.y / u_size.y * 2.0, 0.0, 1.0); }\n";
        static const char fs[] = "#version 450 core\n"
                                 "uniform vec4 u_color;\n"
                                 "layout(location = 0) out vec4 o_color;\n"
                                 "void main() { o_color = u_color; }\n";
        GLuint sh[2] = {gl->CreateShader(GL_VERTEX_SHADER), gl->CreateShader(GL_FRAGMENT_SHADER)};
        const char *src[2] = {vs, fs};
        r->prog_hud = gl->CreateProgram();
        for (int i = 0; i < 2; i++) {
            gl->ShaderSource(sh[i], 1, &src[i], NULL);
            gl->CompileShader(sh[i]);
            gl->AttachShader(r->prog_hud, sh[i]);
        }
        gl->LinkProgram(r->prog_hud);
        for (int i = 0; i < 2; i++) gl->DeleteShader(sh[i]);
        GLint ok = 0;
        gl->GetProgramiv(r->prog_hud, GL_LINK_STATUS, &ok);
        if (!ok) return sample_gl__fail(r, "the HUD program does not link");
        gl->CreateVertexArrays(1, &r->vao_hud);
        gl->CreateBuffers(1, &r->vbo_hud);
        gl->NamedBufferData(r->vbo_hud, 1 << 20, NULL, GL_STREAM_DRAW);
        gl->VertexArrayVertexBuffer(r->vao_hud, 0, r->vbo_hud, 0, 2 * sizeof(float));
        gl->EnableVertexArrayAttrib(r->vao_hud, 0);
        gl->VertexArrayAttribBinding(r->vao_hud, 0, 0);
        gl->VertexArrayAttribFormat(r->vao_hud, 0, 2, GL_FLOAT, GL_FALSE, 0);
    }
    enum { MAX_QUADS = 8192 };
    static char quads[MAX_QUADS * 64];   /* stb_easy_font: 4 vertices of 16 bytes per quad */
    static float tri[MAX_QUADS * 12 + 12]; /* 2 triangles per quad, 2 floats a vertex; the box first */
    const float scale = r->height >= 480 ? 2.0f : 1.0f, margin = 6.0f;
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", text);
    /* the box: the widest line x the line count */
    float wmax = 0.0f, y = margin;
    uint32_t nq = 0, nv = 6;
    for (char *line = buf, *next; line; line = next) {
        next = strchr(line, '\n');
        if (next) *next++ = 0;
        const float lw = (float)stb_easy_font_width(line) * scale;
        if (lw > wmax) wmax = lw;
        const int q = stb_easy_font_print(0.0f, 0.0f, line, NULL, quads + (size_t)nq * 64, (int)((MAX_QUADS - nq) * 64));
        for (int k = 0; k < q; k++) { /* quad corners 0 1 2 3 -> triangles 0 1 2, 0 2 3; scaled and placed */
            const float *v = (const float *)(quads + ((size_t)nq + (size_t)k) * 64);
            static const int order[6] = {0, 1, 2, 0, 2, 3};
            for (int c = 0; c < 6; c++) {
                tri[2 * nv] = margin + scale * v[4 * order[c]];
                tri[2 * nv + 1] = y + scale * v[4 * order[c] + 1];
                nv++;
            }
        }
        nq += (uint32_t)q;
        y += 10.0f * scale;
        if (nq + 256 > MAX_QUADS) break;
    }
    const float x0 = margin - 3.0f, y0 = margin - 3.0f, x1 = margin + wmax + 3.0f, y1 = y + 1.0f;
    const float box[12] = {x0, y0, x1, y0, x1, y1, x0, y0, x1, y1, x0, y1};
    memcpy(tri, box, sizeof box);
    gl->NamedBufferSubData(r->vbo_hud, 0, (GLsizeiptr)((size_t)nv * 2 * sizeof(float)), tri);
    gl->BindFramebuffer(GL_FRAMEBUFFER, r->fbo);
    gl->NamedFramebufferDrawBuffer(r->fbo, GL_COLOR_ATTACHMENT0); /* the display target only */
    gl->Viewport(0, 0, (GLsizei)r->width, (GLsizei)r->height);
    gl->Disable(GL_DEPTH_TEST);
    gl->Disable(GL_CULL_FACE);
    gl->Enable(GL_BLEND);
    gl->BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gl->UseProgram(r->prog_hud);
    gl->Uniform2f(gl->GetUniformLocation(r->prog_hud, "u_size"), (float)r->width, (float)r->height);
    const GLint col = gl->GetUniformLocation(r->prog_hud, "u_color");
    gl->BindVertexArray(r->vao_hud);
    gl->Uniform4f(col, 0.0f, 0.0f, 0.0f, 0.55f);
    gl->DrawArrays(GL_TRIANGLES, 0, 6);
    gl->Uniform4f(col, 1.0f, 1.0f, 0.92f, 1.0f);
    gl->DrawArrays(GL_TRIANGLES, 6, (GLsizei)(nv - 6));
    gl->Disable(GL_BLEND);
    GLenum bufs[SAMPLE_GL_TARGETS];
    for (int i = 0; i < SAMPLE_GL_TARGETS; i++) bufs[i] = (r->aux || i == 0) ? GL_COLOR_ATTACHMENT0 + (GLenum)i : GL_NONE;
    gl->NamedFramebufferDrawBuffers(r->fbo, SAMPLE_GL_TARGETS, bufs);
    return gl->GetError() == GL_NO_ERROR ? 0 : sample_gl__fail(r, "GL error while drawing the HUD");
}

/* Draws one frame into the targets. Call after the GL system's update (and glow_gl_lights_bind when a
 * light hook was given). 0 on success; -1 with r->error on a GL error. */
static inline int sample_gl_draw(sample_gl *r, const sample_gl_frame *f) {
    glow_glfns *gl = &r->gl;
    glow_solver_tables t;
    glow_system_get_solver_tables(r->system, &t);
    float vp[16];
    sample_camera_matrix(f->camera, (float)r->width / (float)r->height, r->scene_size, vp);
    const glow_gl_outputs *o = r->out;

    gl->QueryCounter(r->query[0], GL_TIMESTAMP);
    gl->MemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    gl->BindFramebuffer(GL_FRAMEBUFFER, r->fbo);
    gl->Viewport(0, 0, (GLsizei)r->width, (GLsizei)r->height);
    const float zero[4] = {0, 0, 0, 0}, one = 1.0f;
    for (int i = 0; i < (r->aux ? SAMPLE_GL_TARGETS : 1); i++) gl->ClearNamedFramebufferfv(r->fbo, GL_COLOR, i, zero);
    if (f->view == SAMPLE_VIEW_FINAL && (f->sky[0] > 0.0f || f->sky[1] > 0.0f || f->sky[2] > 0.0f)) {
        /* the sky behind the scene: its radiance, tone-mapped as the pixels are (display target, and
         * the hdr target with the radiance itself) */
        float disp[4] = {0, 0, 0, 1}, hdr[4] = {f->sky[0], f->sky[1], f->sky[2], 1};
        for (int c = 0; c < 3; c++) disp[c] = (float)sample_tonemap(f->sky[c], f->exposure) / 255.0f;
        gl->ClearNamedFramebufferfv(r->fbo, GL_COLOR, 0, disp);
        if (r->aux) gl->ClearNamedFramebufferfv(r->fbo, GL_COLOR, 1, hdr);
    }
    gl->ClearNamedFramebufferfv(r->fbo, GL_DEPTH, 0, &one);
    gl->Enable(GL_DEPTH_TEST);
    gl->DepthFunc(GL_LEQUAL);
    gl->DepthMask(GL_TRUE);
    gl->Disable(GL_BLEND);
    if (r->cull) {
        gl->Enable(GL_CULL_FACE);
        gl->CullFace(GL_BACK);
        gl->FrontFace(GL_CCW);
    } else {
        gl->Disable(GL_CULL_FACE);
    }
    const bool overlay = f->view == SAMPLE_VIEW_SURFELS || f->view == SAMPLE_VIEW_LINKS || f->view == SAMPLE_VIEW_CLUSTERS ||
                         f->view == SAMPLE_VIEW_LIT_CLUSTERS;
    if (overlay) { /* the dim scene behind the points and lines */
        gl->Enable(GL_POLYGON_OFFSET_FILL);
        gl->PolygonOffset(1.0f, 4.0f);
    } else {
        gl->Disable(GL_POLYGON_OFFSET_FILL);
    }

    sample_gl__upload_materials(r, &t);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, SAMPLE_GL_MATERIAL_BINDING, r->ssbo_materials);
    gl->BindTextureUnit(0, o->grid_texture);
    gl->BindTextureUnit(1, o->grid_mask_texture);
    gl->BindTextureUnit(2, o->lightmap_texture);
    gl->BindTextureUnit(3, o->lightmap_valid_texture);
    gl->BindTextureUnit(4, r->sky_tex);
    gl->BindTextureUnit(5, r->albedo_tex);
    gl->BindTextureUnit(6, o->lightmap_detail_texture);
    gl->BindSampler(5, r->albedo_sampler);
    gl->BindSampler(4, 0);
    for (GLuint u = 0; u < 4; u++) gl->BindSampler(u, r->sampler); /* NEAREST: see sample_gl_create */
    gl->BindSampler(6, r->sampler);

    GLuint p = r->prog_scene;
    sample_gl__set_common(r, p, f, vp);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_direct"), f->direct ? 1 : 0);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_indirect"), f->indirect ? 1 : 0);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_has_grid"), o->grid_texture != 0);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_has_lightmap"), o->lightmap_texture != 0);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_has_detail"), o->lightmap_detail_texture != 0);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_lightmap_pages"), o->lightmap_pages ? (GLint)o->lightmap_pages : 1);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_has_sky"), r->sky_tex ? 1 : 0);
    gl->Uniform1i(gl->GetUniformLocation(p, "u_textures"), r->albedo_tex ? 1 : 0);
    gl->Uniform3fv(gl->GetUniformLocation(p, "u_grid_origin"), 1, o->grid_origin);
    gl->Uniform1f(gl->GetUniformLocation(p, "u_grid_spacing"), o->grid_spacing);
    gl->Uniform3ui(gl->GetUniformLocation(p, "u_grid_dims"), o->grid_dims[0], o->grid_dims[1], o->grid_dims[2]);
    const GLint loc_object = gl->GetUniformLocation(p, "u_object"), loc_sphere = gl->GetUniformLocation(p, "u_sphere"),
                loc_albedo = gl->GetUniformLocation(p, "u_object_albedo");
    gl->Uniform1i(loc_object, 0);
    gl->Uniform4f(loc_sphere, 0, 0, 0, 0);
    gl->BindVertexArray(r->vao_scene);
    gl->DrawArrays(GL_TRIANGLES, 0, (GLsizei)r->vertex_count);
    gl->Uniform1i(loc_object, 1);
    gl->BindVertexArray(r->vao_sphere);
    for (uint32_t i = 0; i < f->sphere_count; i++) {
        const sample_gl_sphere *s = &f->spheres[i];
        gl->Uniform4f(loc_sphere, s->center[0], s->center[1], s->center[2], s->radius);
        gl->Uniform3fv(loc_albedo, 1, s->albedo);
        gl->DrawElements(GL_TRIANGLES, (GLsizei)r->sphere_index_count, GL_UNSIGNED_INT, NULL);
    }

    if (f->view == SAMPLE_VIEW_SURFELS || f->view == SAMPLE_VIEW_CLUSTERS || f->view == SAMPLE_VIEW_LIT_CLUSTERS) {
        if (f->view == SAMPLE_VIEW_SURFELS) sample_gl__upload_surfel_light(r, &t);
        else if (f->view == SAMPLE_VIEW_LIT_CLUSTERS) sample_gl__build_lit_clusters(r, &t, f->cluster_level);
        else sample_gl__build_clusters(r, &t, f->cluster_level);
        p = r->prog_points;
        sample_gl__set_common(r, p, f, vp);
        gl->Uniform1i(gl->GetUniformLocation(p, "u_hook"), r->has_hook ? 1 : 0);
        gl->Uniform3fv(gl->GetUniformLocation(p, "u_eye"), 1, f->camera->position);
        gl->PointSize(fmaxf(2.0f, floorf((float)r->height / 180.0f)));
        gl->BindVertexArray(r->vao_points);
        gl->DrawArrays(GL_POINTS, 0, (GLsizei)r->surfel_count);
    } else if (f->view == SAMPLE_VIEW_LINKS) {
        sample_gl__build_links(r, &t, f->pick);
        if (r->line_vertices > 1) {
            p = r->prog_lines;
            sample_gl__set_common(r, p, f, vp);
            gl->BindVertexArray(r->vao_lines);
            gl->DrawArrays(GL_LINES, 0, (GLsizei)(r->line_vertices - 1));
            gl->PointSize(fmaxf(4.0f, floorf((float)r->height / 60.0f)));
            gl->Disable(GL_DEPTH_TEST);
            gl->DrawArrays(GL_POINTS, (GLint)(r->line_vertices - 1), 1);
        }
    }
    gl->QueryCounter(r->query[1], GL_TIMESTAMP);
    gl->BindVertexArray(0);
    gl->Disable(GL_POLYGON_OFFSET_FILL);
    GLuint64 ns[2] = {0, 0};
    gl->GetQueryObjectui64v(r->query[0], GL_QUERY_RESULT, &ns[0]);
    gl->GetQueryObjectui64v(r->query[1], GL_QUERY_RESULT, &ns[1]);
    r->draw_ms = ns[1] > ns[0] ? (double)(ns[1] - ns[0]) * 1e-6 : 0.0;
    GLenum err = gl->GetError();
    if (err != GL_NO_ERROR) return sample_gl__fail(r, "GL error 0x%x while drawing", (unsigned)err);
    return 0;
}

/* Copies the display target onto the default framebuffer (a window) of fb_w x fb_h. */
static inline void sample_gl_blit(sample_gl *r, uint32_t fb_w, uint32_t fb_h) {
    r->gl.NamedFramebufferReadBuffer(r->fbo, GL_COLOR_ATTACHMENT0);
    r->gl.BlitNamedFramebuffer(r->fbo, 0, 0, 0, (GLint)r->width, (GLint)r->height, 0, 0, (GLint)fb_w, (GLint)fb_h,
                               GL_COLOR_BUFFER_BIT, GL_LINEAR);
}

/* Reads target `index` (0 = display RGBA8 -> 4 bytes a pixel; 1..4 = RGBA32F -> 4 floats) into
 * `out`, row 0 at the TOP. 0 on success, -1 with r->error. */
static inline int sample_gl_read(sample_gl *r, int index, void *out) {
    if (index < 0 || index >= SAMPLE_GL_TARGETS || !r->targets[index])
        return sample_gl__fail(r, "target %d does not exist (aux_targets off?)", index);
    const size_t px = index == 0 ? 4 : 16, row = px * r->width, size = row * r->height;
    unsigned char *tmp = malloc(size), *dst = out;
    if (!tmp) return sample_gl__fail(r, "out of memory");
    r->gl.BindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    r->gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    r->gl.GetTextureImage(r->targets[index], 0, GL_RGBA, index == 0 ? GL_UNSIGNED_BYTE : GL_FLOAT, (GLsizei)size, tmp);
    for (uint32_t y = 0; y < r->height; y++) memcpy(dst + row * y, tmp + row * (r->height - 1 - y), row);
    free(tmp);
    GLenum err = r->gl.GetError();
    return err == GL_NO_ERROR ? 0 : sample_gl__fail(r, "GL error 0x%x reading target %d", (unsigned)err, index);
}

/* =========================================================================================== app
 * The frame loop of the GL samples (#define SAMPLE_GL_APP before the include; links glow_glctx,
 * glow_gl_lights, GLFW and stb):
 *
 *   sample_app a;
 *   int status = sample_app_init(&a, argc, argv, emission_glsl);    (-1 = go on, else exit status)
 *   for (long f = 0; status < 0; f++) {
 *       float t = sample_app_time(&a, f);
 *       ... move lights: sample_app_set_lights(&a, lights, n); animate emission ...
 *       status = sample_app_frame(&a, f, spheres, n);             (update, draw, show / write, keys)
 *   }
 *   sample_app_destroy(&a);
 *
 * Command line (sample_args.h's common options plus):
 *   BAKE [--headless] [--frames N] [--out DIR] [--view NAME] [--width W] [--height H] [--scene JSON]
 *        [--exposure E] [--bounce B] [--iterations N] [--no-direct] [--no-indirect] [--pick X,Y,Z] [--level L]
 * Exit status: 0 ok, 1 runtime or file error (the message names the file), 2 usage, 77 no OpenGL 4.5
 * context (the message says why).
 * Keys (window): 1-8 views (final indirect direct surfels charts links clusters lit-clusters), D direct on/off,
 * I indirect on/off, Z / X bounce intensity -/+ 0.1, C / V exposure / x 1.25, K / L cluster level -/+,
 * R reset the bounce, P pause, Esc quit. */
#ifdef SAMPLE_GL_APP
#include <time.h>

#include <glow/glow_gl_lights.h>
#include <glow/glow_glctx.h>
#include <glow/glow_host.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "sample_args.h"
#include "sample_png.h"

#define SAMPLE_APP_EXIT_NO_GL 77

typedef struct sample_app_options {
    sample_args args;
    const char *scene_path;
    int view;
    uint32_t width, height;
    float exposure, bounce;
    uint32_t iterations;
    bool direct, indirect, has_pick;
    bool textures;     /* draw the bake's albedo textures (default; --no-textures) */
    int hud;           /* on-screen text: -1 default (on in a window, off headless), 0 off, 1 on (--hud on|off) */
    float pick[3];
    int cluster_level; /* -1: a third of the levels */
} sample_app_options;

typedef struct sample_app {
    sample_app_options opt;
    const char *name;
    glow_context *ctx;
    glow_bake *bake;
    glow_bake_info info;
    glow_system *sys;
    glow_glctx *glctx;
    glow_gl_lights *lights;
    glow_gl_system *gsys;
    sample_gl r;
    glow_scene_desc scene;
    bool has_scene, window, paused, reset;
    glow_scene_camera camera;
    float centre[3], size[3];
    double anim_time, last_wall;
    unsigned char key_latch[GLFW_KEY_LAST + 1]; /* set by GLFW's key callback, cleared when read */
    uint32_t levels;
    char title[512];
    float sky[3]; /* the final view's background radiance (W/(m²·sr)); the sample sets it (0 = black) */
} sample_app;

static inline double sample_app_now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static inline void sample_app_usage(FILE *f, const char *argv0) {
    fprintf(f,
            "usage: %s BAKE [--headless] [--frames N] [--out DIR] [--view NAME] [--width W] [--height H]\n"
            "       [--scene JSON] [--exposure E] [--bounce B] [--iterations N] [--no-direct] [--no-indirect]\n"
            "       [--pick X,Y,Z] [--level L] [--no-textures] [--hud on|off]\n"
            "  --view      final (default), indirect, direct, surfels, charts, links, clusters, lit-clusters\n"
            "  --width/--height  image size (default 320x240 headless, 1280x720 in a window)\n"
            "  --scene     a scene JSON (docs/scene-format.md): camera, lights, environment, emission_scale\n"
            "  --exposure  multiplies radiance before the tone map (default 1)\n"
            "  --no-textures  draw the materials' base albedo, not the textures the bake names (format 1.1)\n"
            "  --hud       on-screen stats, view name and legend (default: on in a window, off headless; H toggles)\n"
            "  --bounce    bounce intensity 0..1 (default 1); --iterations: bounce iterations per update (default 1)\n"
            "  --pick      links view: the cache nearest this point; --level: clusters view level\n"
            "keys (window): 1-8 views, D direct, I indirect, Z/X bounce -/+, C/V exposure -/+, K/L level -/+,\n"
            "  R reset bounce, P pause, Esc quit\n"
            "exit status: 0 ok, 1 runtime or file error, 2 usage, 77 no OpenGL 4.5 context\n",
            argv0);
}

static inline int sample_app__bad(const char *argv0, const char *opt, const char *value, const char *want) {
    fprintf(stderr, "%s: %s '%s': %s\n", argv0, opt, value, want);
    return 2;
}

/* Parses the command line. -1 to go on, else the exit status. */
static inline int sample_app_parse(int argc, char **argv, sample_app_options *o) {
    *o = (sample_app_options){.view = SAMPLE_VIEW_FINAL, .exposure = 1.0f, .bounce = 1.0f, .iterations = 1,
                              .direct = true, .indirect = true, .textures = true, .hud = -1, .cluster_level = -1};
    long w = 0, h = 0;
    for (int i = 1; i < argc; i++) {
        int took = sample_arg_common(argc, argv, &i, &o->args);
        if (took == 2) return sample_app_usage(stderr, argv[0]), 2;
        if (took) continue;
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return sample_app_usage(stdout, argv[0]), 0;
        if (!strcmp(a, "--no-direct")) { o->direct = false; continue; }
        if (!strcmp(a, "--no-indirect")) { o->indirect = false; continue; }
        if (!strcmp(a, "--no-textures")) { o->textures = false; continue; }
        if (!strcmp(a, "--hud") && i + 1 < argc && (!strcmp(argv[i + 1], "on") || !strcmp(argv[i + 1], "off"))) {
            o->hud = !strcmp(argv[++i], "on");
            continue;
        }
        static const char *const valued[] = {"--view", "--width", "--height", "--scene", "--exposure", "--bounce",
                                             "--iterations", "--pick", "--level"};
        int k = -1;
        for (int j = 0; j < (int)(sizeof valued / sizeof *valued); j++)
            if (!strcmp(a, valued[j])) k = j;
        if (k < 0) {
            if (a[0] == '-' || o->args.input) {
                fprintf(stderr, "%s: unexpected argument '%s'\n", argv[0], a);
                return sample_app_usage(stderr, argv[0]), 2;
            }
            o->args.input = a;
            continue;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, "%s: %s needs a value\n", argv[0], a);
            return 2;
        }
        const char *v = argv[++i];
        char *end = NULL;
        switch (k) {
        case 0:
            if ((o->view = sample_view_parse(v)) < 0)
                return sample_app__bad(argv[0], a, v, "wants final, indirect, direct, surfels, charts, links, clusters or lit-clusters");
            break;
        case 1: case 2: {
            long x = strtol(v, &end, 10);
            if (end == v || *end || x < 16 || x > 8192) return sample_app__bad(argv[0], a, v, "wants 16..8192");
            *(k == 1 ? &w : &h) = x;
            break;
        }
        case 3: o->scene_path = v; break;
        case 4: case 5: {
            float x = strtof(v, &end);
            if (end == v || *end || !isfinite(x) || x < 0.0f || (k == 5 && x > 1.0f))
                return sample_app__bad(argv[0], a, v, k == 4 ? "wants a number >= 0" : "wants 0..1");
            *(k == 4 ? &o->exposure : &o->bounce) = x;
            break;
        }
        case 6: case 8: {
            long x = strtol(v, &end, 10);
            if (end == v || *end || x < (k == 6 ? 1 : 0) || x > 64) return sample_app__bad(argv[0], a, v, k == 6 ? "wants 1..64" : "wants 0..64");
            if (k == 6) o->iterations = (uint32_t)x;
            else o->cluster_level = (int)x;
            break;
        }
        case 7:
            if (sscanf(v, "%f,%f,%f", &o->pick[0], &o->pick[1], &o->pick[2]) != 3 || !isfinite(o->pick[0]) ||
                !isfinite(o->pick[1]) || !isfinite(o->pick[2]))
                return sample_app__bad(argv[0], a, v, "wants X,Y,Z (m)");
            o->has_pick = true;
            break;
        default: break;
        }
    }
    if (!o->args.input) {
        fprintf(stderr, "%s: no BAKE given\n", argv[0]);
        return sample_app_usage(stderr, argv[0]), 2;
    }
    if ((w != 0) != (h != 0)) {
        fprintf(stderr, "%s: give both --width and --height\n", argv[0]);
        return 2;
    }
    o->width = w ? (uint32_t)w : o->args.headless ? 320u : 1280u;
    o->height = h ? (uint32_t)h : o->args.headless ? 240u : 720u;
    if (o->args.frames == 0 && o->args.headless) o->args.frames = 8;
    if (o->args.out_dir && sample_make_dir(o->args.out_dir) != 0) {
        fprintf(stderr, "%s: %s: %s\n", argv[0], o->args.out_dir, strerror(errno));
        return 1;
    }
    return -1;
}

static inline void sample_app__log(void *user, glow_log_level level, glow_result code, const char *msg, const char *file,
                                   int line) {
    (void)user, (void)code, (void)file, (void)line;
    if (level <= GLOW_LOG_WARNING) fprintf(stderr, "glow: %s\n", msg);
}

static inline void sample_app_destroy(sample_app *a) {
    sample_gl_destroy(&a->r);
    glow_gl_system_destroy(a->gsys);
    glow_gl_lights_destroy(a->lights);
    glow_glctx_destroy(a->glctx);
    glow_system_destroy(a->sys);
    glow_bake_destroy(a->bake);
    glow_context_destroy(a->ctx);
    glow_scene_free(&a->scene);
    a->gsys = NULL, a->lights = NULL, a->glctx = NULL, a->sys = NULL, a->bake = NULL, a->ctx = NULL;
}

/* Everything up to the first frame. -1 to go on, else the exit status (the message printed; on
 * failure everything made is destroyed). */
/* GLFW key callback: latches presses (not repeats: the keys toggle) for sample_app_key. The window's user pointer is
 * the sample_app, set when the window is made. */
static void sample_app__key_callback(GLFWwindow *w, int key, int scancode, int action, int mods) {
    (void)scancode;
    (void)mods;
    sample_app *a = (sample_app *)glfwGetWindowUserPointer(w);
    if (a && action == GLFW_PRESS && key >= 0 && key <= GLFW_KEY_LAST) a->key_latch[key] = 1;
}

static inline int sample_app_init(sample_app *a, int argc, char **argv, const char *emission_glsl) {
    memset(a, 0, sizeof *a);
    a->name = argv[0];
    int status = sample_app_parse(argc, argv, &a->opt);
    if (status >= 0) return status;
    const char *in = a->opt.args.input;
    /* 1. the bake, and the scene file when given (both before any GL: a bad file is exit 1 anywhere) */
    glow_result r = glow_context_create(&(glow_context_desc){.api_version = GLOW_VERSION, .logger = {sample_app__log, NULL}},
                                        &a->ctx);
    if (r == GLOW_OK) r = glow_bake_load_file(a->ctx, in, &a->bake);
    if (r == GLOW_OK) r = glow_bake_get_info(a->bake, &a->info);
    if (r != GLOW_OK) {
        fprintf(stderr, "%s: %s: %s\n", a->name, in, glow_result_string(r));
        sample_app_destroy(a);
        return 1;
    }
    for (int k = 0; k < 3; k++) {
        a->centre[k] = 0.5f * (a->info.bounds_min[k] + a->info.bounds_max[k]);
        a->size[k] = a->info.bounds_max[k] - a->info.bounds_min[k];
    }
    if (a->opt.scene_path) {
        char msg[512];
        r = glow_scene_load(a->opt.scene_path, NULL, &a->scene, msg, sizeof msg);
        if (r != GLOW_OK) {
            fprintf(stderr, "%s: %s\n", a->name, msg);
            sample_app_destroy(a);
            return 1;
        }
        a->has_scene = true;
        a->camera = a->scene.camera;
    }
    if (!a->has_scene || !a->scene.has_camera) {
        /* glow_scene_camera_default (looks along -Z at the centre, from outside the bounds), moved in
         * until the bounds' +Z face fills the image: with back faces culled, a closed room shows its
         * inside through its near wall */
        a->camera = (glow_scene_camera){.vfov_deg = 50.0f};
        glow_scene_camera_default(a->info.bounds_min, a->info.bounds_max, &a->camera);
        float half = fmaxf(0.5f * a->size[1], 0.5f * a->size[0] * (float)a->opt.height / (float)a->opt.width);
        a->camera.position[2] = a->info.bounds_max[2] + 1.02f * half / tanf(0.5f * a->camera.vfov_deg * SAMPLE_GL_PI / 180.0f);
    }
    /* 2. GL 4.5: offscreen (EGL, else OSMesa) or a GLFW window */
    char why[512] = "";
    snprintf(a->title, sizeof a->title, "Glow %s", a->name);
    r = glow_glctx_create(&(glow_glctx_desc){.kind = a->opt.args.headless ? GLOW_GLCTX_HEADLESS : GLOW_GLCTX_WINDOW,
                                             .width = a->opt.width, .height = a->opt.height, .title = a->title},
                          &a->glctx, why, sizeof why);
    if (r != GLOW_OK) {
        fprintf(stderr, "%s: no OpenGL 4.5 %s (%s): %s%s\n", a->name, a->opt.args.headless ? "context" : "window",
                glow_result_string(r), why, a->opt.args.headless ? "" : " (try --headless)");
        sample_app_destroy(a);
        return SAMPLE_APP_EXIT_NO_GL;
    }
    a->window = glow_glctx_window(a->glctx) != NULL;
    if (a->window) { /* key presses through GLFW's callback: a tap shorter than a frame still counts */
        GLFWwindow *w = (GLFWwindow *)glow_glctx_window(a->glctx);
        glfwSetWindowUserPointer(w, a);
        glfwSetKeyCallback(w, sample_app__key_callback);
    }
    glow_gl_loader load = glow_glctx_get_proc_address(a->glctx);
    /* 3. the CPU system (the artist controls live there), the GPU lights (shadow maps + their GLSL
     * hook) and the GL system lit by that hook; then the renderer, with the same hook for the screen */
    glow_system_params params = {.bounce_intensity = a->opt.bounce,
                                 .emission_scale = a->has_scene ? a->scene.emission_scale : 1.0f,
                                 .bounce_iterations = a->opt.iterations};
    r = glow_system_create(a->ctx, &(glow_system_desc){.bake = a->bake, .label = "sample"}, &a->sys);
    if (r == GLOW_OK) r = glow_system_set_params(a->sys, &params);
    const glow_logger lg = {sample_app__log, NULL};
    if (r == GLOW_OK)
        r = glow_gl_lights_create(&(glow_gl_lights_desc){.loader = load, .bake = a->bake, .cube_map_size = a->window ? 512 : 256,
                                                         .shadow_map_size = a->window ? 1024 : 512, .logger = lg},
                                  &a->lights);
    if (r == GLOW_OK)
        r = glow_gl_system_create(&(glow_gl_desc){.system = a->sys, .get_proc_address = load,
                                                  .hook_glsl = glow_gl_lights_hook_source(a->lights), .label = "sample",
                                                  .logger = lg,
                                                  /* llvmpipe resolves timestamps on its rasteriser thread, out of order with
                                                     compute: time its stages with glFinish instead (GPUs: timer queries) */
                                                  .flags = strstr(glow_glctx_renderer(a->glctx), "llvmpipe")
                                                               ? GLOW_GL_FLAG_FINISH_TIMERS : 0u},
                                  &a->gsys);
    if (r != GLOW_OK) {
        fprintf(stderr, "%s: %s: GL setup failed: %s\n", a->name, in, glow_result_string(r));
        sample_app_destroy(a);
        return 1;
    }
    uint32_t fw = a->opt.width, fh = a->opt.height;
    if (a->window) glow_glctx_framebuffer_size(a->glctx, &fw, &fh);
    sample_gl_desc rd = {.loader = load, .bake = a->bake, .system = a->sys, .outputs = glow_gl_system_outputs(a->gsys),
                         .light_hook = glow_gl_lights_hook_source(a->lights), .emission_glsl = emission_glsl,
                         .width = fw, .height = fh, .textures = a->opt.textures};
    if (sample_gl_create(&a->r, &rd) != 0) {
        fprintf(stderr, "%s: renderer: %s\n", a->name, a->r.error);
        sample_app_destroy(a);
        return 1;
    }
    if (a->r.warning[0]) fprintf(stderr, "%s: warning: %s\n", a->name, a->r.warning);
    { /* the sky's visible fraction per surfel, traced once on the CPU (glow_host, Embree) as the CPU host does: for
       * the GPU hook (Glow's surfels) and, through a lightmap-space texture, for the screen; without it the sky
       * would light arcades and room interiors as if they were open (S = 1) */
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        glow_host *sky_host = NULL;
        glow_surfel_view sv;
        glow_system_get_surfels(a->sys, &sv);
        float *S = malloc(((size_t)sv.count + 1) * sizeof *S);
        glow_result sr = S ? glow_host_create(&(glow_host_desc){.kind = GLOW_HOST_KIND_EXACT, .bake = a->bake, .logger = lg}, &sky_host)
                           : GLOW_ERROR_OUT_OF_MEMORY;
        if (sr == GLOW_OK) sr = glow_host_sky_visibility(sky_host, &sv, S, sv.count);
        if (sr == GLOW_OK) sr = glow_gl_lights_set_sky_visibility(a->lights, S, sv.count);
        if (sr == GLOW_OK && sample_gl_set_sky_visibility(&a->r, S, sv.count) != 0) sr = GLOW_ERROR_UNSUPPORTED;
        glow_host_destroy(sky_host);
        free(S);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        if (sr != GLOW_OK)
            fprintf(stderr, "%s: sky visibility not traced (%s): the sky lights unshadowed\n", a->name, glow_result_string(sr));
        else
            printf("sky visibility: %u surfels traced in %.0f ms\n", sv.count,
                   (double)(t1.tv_sec - t0.tv_sec) * 1e3 + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-6);
    }
    glow_solver_tables t;
    glow_system_get_solver_tables(a->sys, &t);
    a->levels = t.level_count;
    if (a->opt.cluster_level < 0) a->opt.cluster_level = (int)(t.level_count / 3);
    printf("%s: %s: %u surfels, %u caches (grid %u, lightmap %u), %u levels; GL %s (%s); %ux%u%s\n", a->name, in,
           a->info.surfel_count, a->info.cache_count, a->info.grid_cache_count, a->info.lightmap_cache_count, t.level_count,
           glow_glctx_renderer(a->glctx), glow_glctx_kind_name(glow_glctx_get_kind(a->glctx)), fw, fh,
           a->window ? " window (keys: 1-8 views, D direct, I indirect, Z/X bounce, C/V exposure, K/L level, R reset, P pause, Esc)" : "");
    a->last_wall = sample_app_now_ms();
    return -1;
}

/* Animation time of frame f (s): 0.1 s a frame headless (reproducible frames), wall time in a window. */
static inline float sample_app_time(sample_app *a, long frame) {
    if (!a->window) return (float)(0.1 * (double)frame);
    double now = sample_app_now_ms();
    if (!a->paused) a->anim_time += (now - a->last_wall) * 1e-3;
    a->last_wall = now;
    return (float)a->anim_time;
}

/* Sets the lights (and the scene's sky): renders their shadow maps on the GPU. 0 or 1 (printed). */
static inline int sample_app_set_lights(sample_app *a, const glow_scene_light *lights, uint32_t count) {
    glow_result r = glow_gl_lights_set(a->lights, lights, count, a->has_scene ? a->scene.environment : NULL);
    if (r != GLOW_OK) fprintf(stderr, "%s: glow_gl_lights_set: %s\n", a->name, glow_result_string(r));
    return r == GLOW_OK ? 0 : 1;
}

/* Whether `key` went down since the last call for it (latched by sample_app__key_callback, so a press
 * and release within one frame is not lost as it was when the keys were polled with glfwGetKey). */
static inline bool sample_app_key(sample_app *a, int key) {
    if (key < 0 || key > GLFW_KEY_LAST || !a->key_latch[key]) return false;
    a->key_latch[key] = 0;
    return true;
}
static inline bool sample_app__pressed(sample_app *a, int key) { return sample_app_key(a, key); }

static inline void sample_app__keys(sample_app *a) {
    for (int v = 0; v < SAMPLE_VIEW_COUNT; v++)
        if (sample_app__pressed(a, GLFW_KEY_1 + v)) a->opt.view = v;
    if (sample_app__pressed(a, GLFW_KEY_D)) a->opt.direct = !a->opt.direct;
    if (sample_app__pressed(a, GLFW_KEY_I)) a->opt.indirect = !a->opt.indirect;
    if (sample_app__pressed(a, GLFW_KEY_C)) a->opt.exposure /= 1.25f;
    if (sample_app__pressed(a, GLFW_KEY_V)) a->opt.exposure *= 1.25f;
    if (sample_app__pressed(a, GLFW_KEY_K) && a->opt.cluster_level > 0) a->opt.cluster_level--;
    if (sample_app__pressed(a, GLFW_KEY_L) && a->opt.cluster_level + 1 < (int)a->levels) a->opt.cluster_level++;
    if (sample_app__pressed(a, GLFW_KEY_P)) a->paused = !a->paused;
    if (sample_app__pressed(a, GLFW_KEY_R)) a->reset = true;
    if (sample_app__pressed(a, GLFW_KEY_H)) a->opt.hud = a->opt.hud < 0 ? 0 : !a->opt.hud;
    int db = sample_app__pressed(a, GLFW_KEY_X) - sample_app__pressed(a, GLFW_KEY_Z);
    if (db) {
        glow_system_params p;
        glow_system_get_params(a->sys, &p);
        p.bounce_intensity = fminf(fmaxf(roundf((p.bounce_intensity + 0.1f * (float)db) * 10.0f) / 10.0f, 0.0f), 1.0f);
        glow_system_set_params(a->sys, &p);
    }
    if (sample_app__pressed(a, GLFW_KEY_ESCAPE)) glfwSetWindowShouldClose((GLFWwindow *)glow_glctx_window(a->glctx), 1);
}

/* Writes the display target as DIR/frame_NNN.png. 0 or -1 (printed). */
static inline int sample_app_write_png(sample_app *a, long frame) {
    char path[4096];
    snprintf(path, sizeof path, "%s/frame_%03ld.png", a->opt.args.out_dir, frame);
    const uint32_t w = a->r.width, h = a->r.height;
    uint8_t *rgba = malloc((size_t)w * h * 4);
    int ok = rgba && sample_gl_read(&a->r, 0, rgba) == 0;
    if (ok) {
        for (size_t i = 0; i < (size_t)w * h; i++) memmove(rgba + 3 * i, rgba + 4 * i, 3); /* RGBA -> RGB in place */
        ok = stbi_write_png(path, (int)w, (int)h, 3, rgba, (int)w * 3) != 0;
    }
    free(rgba);
    if (!ok) fprintf(stderr, "%s: %s: cannot write the PNG%s%s\n", a->name, path, a->r.error[0] ? ": " : "", a->r.error);
    return ok ? 0 : -1;
}

/* One frame after the sample moved its lights and objects: the GL update, the draw, then the window
 * (blit, title, keys) or the PNG, and the stats line. -1 to go on, else the exit status. */
static inline int sample_app_frame(sample_app *a, long frame, const sample_gl_sphere *spheres, uint32_t sphere_count,
                                   const float default_pick[3]) {
    const double t0 = sample_app_now_ms();
    glow_gl_lights_bind(a->lights);
    glow_update_desc ud = {.flags = a->reset ? GLOW_UPDATE_FLAG_RESET_BOUNCE : 0u};
    a->reset = false;
    glow_result r = glow_gl_system_update(a->gsys, &ud);
    if (r != GLOW_OK) {
        fprintf(stderr, "%s: frame %ld: glow_gl_system_update: %s\n", a->name, frame, glow_result_string(r));
        return 1;
    }
    if (a->window) {
        uint32_t fw, fh;
        glow_glctx_framebuffer_size(a->glctx, &fw, &fh);
        if (fw > 0 && fh > 0 && (fw != a->r.width || fh != a->r.height) && sample_gl_resize(&a->r, fw, fh) != 0) {
            fprintf(stderr, "%s: %s\n", a->name, a->r.error);
            return 1;
        }
    }
    sample_gl_frame f = {.view = a->opt.view, .direct = a->opt.direct, .indirect = a->opt.indirect,
                         .exposure = a->opt.exposure, .camera = &a->camera, .spheres = spheres,
                         .sphere_count = sphere_count, .cluster_level = (uint32_t)a->opt.cluster_level,
                         .time = (float)(a->window ? a->anim_time : 0.1 * (double)frame),
                         .sky = {a->sky[0], a->sky[1], a->sky[2]}};
    memcpy(f.pick, a->opt.has_pick ? a->opt.pick : default_pick ? default_pick : a->centre, sizeof f.pick);
    if (sample_gl_draw(&a->r, &f) != 0) {
        fprintf(stderr, "%s: frame %ld: %s\n", a->name, frame, a->r.error);
        return 1;
    }
    glow_gl_stats st;
    glow_gl_system_get_stats(a->gsys, &st);
    glow_system_params p;
    glow_system_get_params(a->sys, &p);
    const uint64_t bounces = p.bounce_intensity > 0.0f ? st.updates * p.bounce_iterations : 1u;
    int status = -1;
    const bool hud = a->opt.hud < 0 ? a->window : a->opt.hud != 0;
    if (hud) { /* the on-screen HUD: what the sample shows, Glow's GPU stages, the view and its legend */
        char text[2048];
        snprintf(text, sizeof text,
                 "%s\n"
                 "Glow GPU ms: surfels %.2f (hook %.2f)  pull %.2f  caches %.2f  outputs %.2f  total %.2f  |  draw %.2f\n"
                 "bounces %llu  intensity %.2f  iterations %u per update  exposure %.2f  textures %u%s%s\n"
                 "view %d %s\n%s",
                 a->title[0] ? a->title : a->name, st.surfel_lighting_ms, st.host_ms, st.pull_ms, st.cache_lighting_ms,
                 st.output_ms, st.total_ms, a->r.draw_ms, (unsigned long long)bounces, p.bounce_intensity,
                 p.bounce_iterations, a->opt.exposure, a->r.textured_materials, a->opt.direct ? "" : "  direct off",
                 a->opt.indirect ? "" : "  indirect off", a->opt.view + 1, sample_view_legend(a->opt.view),
                 a->window ? "keys: 1-8 view  D direct  I indirect  Z/X bounce  C/V exposure  K/L level  R reset  P pause  "
                             "H HUD  Esc quit"
                           : "");
        if (sample_gl_hud(&a->r, text) != 0) {
            fprintf(stderr, "%s: frame %ld: %s\n", a->name, frame, a->r.error);
            return 1;
        }
    }
    if (a->opt.args.out_dir && sample_app_write_png(a, frame) != 0) status = 1;
    const double ms = sample_app_now_ms() - t0;
    char line[512];
    snprintf(line, sizeof line,
             "frame %ld  %.1f ms  GPU ms: surfels %.2f (hook %.2f) pull %.2f caches %.2f outputs %.2f total %.2f "
             "draw %.2f  bounces %llu  intensity %.2f  view %s%s%s",
             frame, ms, st.surfel_lighting_ms, st.host_ms, st.pull_ms, st.cache_lighting_ms, st.output_ms, st.total_ms,
             a->r.draw_ms, (unsigned long long)bounces, p.bounce_intensity, sample_view_name(a->opt.view),
             a->opt.direct ? "" : "  direct off", a->opt.indirect ? "" : "  indirect off");
    if (a->window) {
        sample_gl_blit(&a->r, a->r.width, a->r.height);
        char title[sizeof a->title + 520];
        if (hud) snprintf(title, sizeof title, "%s", a->title[0] ? a->title : a->name); /* the stats are on screen */
        else snprintf(title, sizeof title, "%s  |  %s", a->title, line);
        glfwSetWindowTitle((GLFWwindow *)glow_glctx_window(a->glctx), title);
        glow_glctx_swap(a->glctx);
        sample_app__keys(a);
        if (glow_glctx_should_close(a->glctx)) status = status < 0 ? 0 : status;
    } else {
        printf("%s\n", line);
        fflush(stdout);
    }
    if (status < 0 && a->opt.args.frames > 0 && frame + 1 >= a->opt.args.frames) status = 0;
    return status;
}

#endif /* SAMPLE_GL_APP */

#endif /* GLOW_SAMPLE_GL_H */
