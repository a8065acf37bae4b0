/* gl_system.c — glow_gl_system (glow_gl.h): the GL 4.5 compute backend of the solver.
 *
 * Buffers (created once; an update allocates nothing, host or GPU):
 *   geom, mat (glow_shared.h structs), direct (vec4/surfel), feedback weights, cache_sh, nodes (uvec4),
 *   flux (vec4/node), links (the bake's blocks verbatim), output pairs (uvec2), status, params (UBO)
 * Host memory: staging arrays for the re-uploads (surfel material state, direct light), sized at create.
 * Kernels: shaders/NAME.comp embedded by cmake/glow_embed.cmake, compiled here with the band counts as
 * #defines (so every SH loop has constant bounds), the hook spliced into surfel_direct.
 *
 * Allocation: host memory with malloc (integration code, like glow_host; the runtime's allocator hooks
 * are not public). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "glow/glow_gl.h"
#include "glow/glow_backend.h"
#include "glow/glow_glfns.h"

#include "glow_shared.h" /* shaders/include: layouts and bindings shared with the kernels */

#define PI_F 3.14159265358979323846f
#define ALBEDO_MAX 0.999f
#define MAP_EMPTY 0xFFFFFFFFu

extern const char glow__shading_glsl[];
extern const struct { const char *name, *source; } glow__kernels[];

enum { K_DIRECT, K_FLUX, K_PULL, K_PULL_TAIL, K_CACHE, K_OUTPUT, K_DETAIL, K_PROXY, K_DRIFT, K_GRAD, K_SKY, K_COUNT };
static const char *const kernel_names[K_COUNT] = {"surfel_direct", "surfel_flux", "pull", "pull_tail", "cache_light",
                                                  "outputs", "detail", "proxy_fill", "drift", "gradient_u", "sky_add"};
enum { B_GEOM, B_MAT, B_DIRECT, B_FBW, B_CACHE, B_NODES, B_FLUX, B_LINKS, B_PAIRS, B_STATUS, B_PARAMS, B_LEVELS, B_SUBSETS,
       B_DET_TEXELS, B_DET_LINKS, B_PROXY_MAP, B_LIST, B_RAD_PREV, B_DRIFT, B_DELTA, B_MOM, B_GRAD_NODES, B_GRAD_CM,
       B_GRAD_U, B_SKY, B_SKY_BACKUP, B_COUNT };
#define MAX_DEPS 64u /* GLOW_BAKE_MAX_DEPENDENCIES */
enum { T_BEGIN, T_DIRECT, T_FLUX, T_PULL, T_CACHE, T_OUTPUT, T_COUNT };

struct glow_gl_system {
    glow_glfns gl;
    glow_system *sys;
    glow_logger logger;
    char label[64];
    uint32_t flags;
    glow_solver_tables t;
    uint32_t S, N, C, levels, planes;
    GLenum out_fmt;     /* the output textures' format: GL_RGBA32F, or GL_RGBA16F (GLOW_GL_FLAG_RGBA16F_OUTPUTS) */
    uint32_t out_texel; /* its bytes a texel */
    GLuint prog[K_COUNT];
    GLint level_loc, tail_loc, proxy_loc, list_loc, delta_loc, drift_loc, grad_loc, sky_loc;
    /* the visible sky of the grid caches (glow_gl_system_set_sky), as the CPU solver's glow_system_set_sky:
     * V ⊗ L per grid cache computed on the CPU at each call (sky_staging, cache_sh's layout) and uploaded
     * to SKY; after the bounce sky_add.comp saves the grid caches' rows to SKY_BACKUP and adds SKY; the
     * next update copies SKY_BACKUP back before the surfel flux reads the caches. Buffers and staging
     * are made at the first call (a system that never gets a sky holds none). */
    float *sky_staging;  /* [grid caches][coeffs] */
    int sky_on, sky_applied;
    /* a budget (glow_update_desc max_caches, focus): groups of GLOW_BUDGET_GROUP caches chosen by
     * glow_budget_choose, as the CPU solver chooses; LIST holds their caches for the cache kernel */
    uint32_t groups;
    float *grp_centre;   /* [groups][3] */
    uint32_t *grp_age;   /* [groups] */
    uint64_t *grp_pack;  /* [groups] scratch */
    uint32_t *grp_sel;   /* [groups] */
    uint32_t *list;      /* [C] the chosen caches */
    uint32_t list_count, caches_gathered;
    uint32_t sel_groups;         /* groups the last budgeted update gathered */
    /* converged_epsilon, as the CPU solver (runtime/src/system.c schedule): each group's change at its last
     * gather (cache_light writes (|new - old|, |new|) of each listed cache's luma DC to DELTA; read back at
     * the next budgeted update, when the GPU has long finished it) and the drift of the node luma
     * (drift.comp, read back at once: the one wait of a converging update) */
    float *grp_delta;            /* [groups] INFINITY: never gathered under a budget, or reset */
    double *grp_drift_at;        /* [groups] */
    uint8_t *grp_skip;           /* [groups] */
    double drift;
    float *delta_read;           /* [C][2] */
    float *drift_read;           /* [drift groups][2] */
    uint32_t drift_groups, caches_converged;
    int delta_pending;           /* DELTA holds the last budgeted update's changes, not yet read */
    int timed_budget;            /* the last update was budgeted: its timings may teach the budget */
    double ema_other_ms;          /* budget_ms: GPU times of earlier updates (0 = none yet), */
    glow_budget_cost gather_cost; /* and the gathers' model, as the CPU solver's (one iteration's times) */
    /* light across systems: proxy node N + p reads a neighbour's flux (proxy_fill.comp); PROXY_MAP holds
     * (neighbour node, N + p) sorted by dependency, dependency d's entries at [dep_first[d], dep_first[d+1]) */
    uint32_t P, deps, dep_first[MAX_DEPS + 1];
    glow_gl_system *nbr[MAX_DEPS];
    uint32_t attached; /* GL systems that read this one as a neighbour */
    uint32_t tail_level; /* levels [tail_level, levels) run in one pull_tail dispatch */
    GLuint buf[B_COUNT];
    GLuint grid_tex, grid_mask_tex, lm_tex, lm_valid_tex, det_tex;
    GLuint brick_tex, fine_tex, fine_mask_tex; /* a refined grid (GFIN) */
    uint32_t fine_used, fine_ax;
    int own_grid, own_lm;
    GLuint queries[T_COUNT];
    double cpu_ts[T_COUNT]; /* GLOW_GL_FLAG_FINISH_TIMERS */
    int queries_pending;
    uint32_t pull_dispatches;
    glow_gl_outputs out;
    glow_gl_params params;
    /* what the material state was last computed from */
    uint64_t emission_rev_seen, direct_rev_seen, material_rev_seen; /* the tables' revisions uploaded */
    float emission_scale_seen;
    int mat_valid, direct_valid;
    glow_gl_surfel_mat *mat_staging; /* [S] */
    float *direct_staging;           /* [S][4] */
    uint64_t updates, gpu_bytes;
    char renderer[96];
};

/* ------------------------------------------------------------------------------------------ log */
static void logf_(const glow_gl_system *s, const glow_logger *lg, glow_log_level level, glow_result code,
                  const char *fmt, ...) {
    const glow_logger *l = s ? &s->logger : lg;
    if (!l || !l->log) return;
    char msg[4096];
    int n = snprintf(msg, sizeof msg, "glow_gl(%s): ", s ? s->label : "gl");
    va_list ap;
    va_start(ap, fmt);
    if (n > 0 && (size_t)n < sizeof msg) vsnprintf(msg + n, sizeof msg - (size_t)n, fmt, ap);
    va_end(ap);
    l->log(l->user, level, code, msg, __FILE__, __LINE__);
}
#define LOG_ERR(s, code, ...) logf_((s), NULL, GLOW_LOG_ERROR, (code), __VA_ARGS__)
#define LOG_WARN(s, code, ...) logf_((s), NULL, GLOW_LOG_WARNING, (code), __VA_ARGS__)

/* ------------------------------------------------------------------------------------ programs */
static const char *kernel_source(const char *name) {
    for (size_t i = 0; glow__kernels[i].name; ++i)
        if (!strcmp(glow__kernels[i].name, name)) return glow__kernels[i].source;
    return NULL;
}

static uint32_t count_lines(const char *p, size_t n) {
    uint32_t c = 0;
    for (size_t i = 0; i < n; ++i) c += p[i] == '\n';
    return c;
}

/* Compiles kernel `k` with the prelude; for surfel_direct the hook replaces GLOW_HOST_HOOK_SOURCE.
 * Returns 0 on failure (logged, with the info log). */
static GLuint build_program(glow_gl_system *s, int k, const char *hook, glow_result *err) {
    glow_glfns *gl = &s->gl;
    const char *src = kernel_source(kernel_names[k]);
    if (!src) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED, "kernel %s is not embedded (build problem)", kernel_names[k]);
        *err = GLOW_ERROR_UNSUPPORTED;
        return 0;
    }
    char prelude[360];
    snprintf(prelude, sizeof prelude,
             "#version 450 core\n#define GLOW_GLSL 1\n#define GLOW_LUMA_BANDS %u\n#define GLOW_CHROMA_BANDS %u\n%s%s%s#line 1 0\n",
             s->t.sh_bands_luma, s->t.sh_bands_chroma, s->t.link_subsets ? "#define GLOW_LINK_SUBSETS 1\n" : "",
             s->t.link_gradients ? "#define GLOW_LINK_GRADIENT 1\n" : "",
             s->out_fmt == GL_RGBA16F ? "#define GLOW_OUTPUT_RGBA16F 1\n" : "");
    const char *strings[6];
    GLint lengths[6];
    int n = 0;
    char line_hook[32], line_back[32];
    strings[n] = prelude, lengths[n++] = -1;
    const char *mark = k == K_DIRECT ? strstr(src, "GLOW_HOST_HOOK_SOURCE") : NULL;
    if (mark) {
        size_t before = (size_t)(mark - src);
        const char *after = mark + strlen("GLOW_HOST_HOOK_SOURCE");
        snprintf(line_hook, sizeof line_hook, "\n#line 1 1\n");
        snprintf(line_back, sizeof line_back, "\n#line %u 0\n", count_lines(src, before) + 1u);
        strings[n] = src, lengths[n++] = (GLint)before;
        strings[n] = line_hook, lengths[n++] = -1;
        strings[n] = hook, lengths[n++] = -1;
        strings[n] = line_back, lengths[n++] = -1;
        strings[n] = after, lengths[n++] = -1;
    } else {
        strings[n] = src, lengths[n++] = -1;
    }
    GLuint sh = gl->CreateShader(GL_COMPUTE_SHADER);
    gl->ShaderSource(sh, n, strings, lengths);
    gl->CompileShader(sh);
    GLint ok = 0;
    gl->GetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    char info[3000];
    info[0] = '\0';
    if (!ok) {
        gl->GetShaderInfoLog(sh, sizeof info, NULL, info);
        gl->DeleteShader(sh);
        *err = k == K_DIRECT ? GLOW_ERROR_HOST_CALLBACK : GLOW_ERROR_UNSUPPORTED;
        LOG_ERR(s, *err, "%s.comp does not compile%s:\n%s", kernel_names[k],
                k == K_DIRECT ? " with the host hook (GLSL source string 1 = the hook, its own line numbers)" : "", info);
        return 0;
    }
    GLuint p = gl->CreateProgram();
    gl->AttachShader(p, sh);
    gl->LinkProgram(p);
    gl->DeleteShader(sh);
    gl->GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        gl->GetProgramInfoLog(p, sizeof info, NULL, info);
        gl->DeleteProgram(p);
        *err = k == K_DIRECT ? GLOW_ERROR_HOST_CALLBACK : GLOW_ERROR_UNSUPPORTED;
        LOG_ERR(s, *err, "%s.comp does not link: %s", kernel_names[k], info);
        return 0;
    }
    return p;
}

/* ------------------------------------------------------------------------------------- buffers */
static GLuint make_buffer(glow_gl_system *s, size_t size, const void *data, GLbitfield flags) {
    GLuint b = 0;
    s->gl.CreateBuffers(1, &b);
    s->gl.NamedBufferStorage(b, (GLsizeiptr)(size ? size : 16), data, flags);
    s->gpu_bytes += size;
    return b;
}

/* Per-surfel material state from the CPU system's tables (task_flux's arithmetic, folded per surfel). */
static void fill_mat(glow_gl_system *s, float emission_scale) {
    const glow_solver_tables *t = &s->t;
    for (uint32_t i = 0; i < s->S; ++i) {
        const uint32_t m = t->materials[i];
        const float *ms = t->material_albedo_scale + 3 * (size_t)m, *me = t->material_emission_scale + 3 * (size_t)m;
        const float rmax = t->indirect_albedo_max[i];
        glow_gl_surfel_mat *g = &s->mat_staging[i];
        float rho[3], rho_ind[3], emit[3];
        for (int c = 0; c < 3; ++c) {
            float r = t->albedo[3 * (size_t)i + c] * ms[c];
            r = r < 0.0f ? 0.0f : (r > ALBEDO_MAX ? ALBEDO_MAX : r);
            rho[c] = r;
            rho_ind[c] = r < rmax ? r : rmax;
            emit[c] = PI_F * t->emission[3 * (size_t)i + c] * emission_scale * me[c];
        }
        g->rho = (glow_vec4){rho[0], rho[1], rho[2], 0.0f};
        g->rho_ind = (glow_vec4){rho_ind[0], rho_ind[1], rho_ind[2], 0.0f};
        g->emit = (glow_vec4){emit[0], emit[1], emit[2], 0.0f};
        g->feedback = t->feedback[i];
        g->material = m;
        g->reserved0 = g->reserved1 = 0;
    }
}

static void free_system(glow_gl_system *s) {
    if (!s) return;
    glow_glfns *gl = &s->gl;
    if (gl->DeleteProgram)
        for (int k = 0; k < K_COUNT; ++k)
            if (s->prog[k]) gl->DeleteProgram(s->prog[k]);
    if (gl->DeleteBuffers) gl->DeleteBuffers(B_COUNT, s->buf);
    if (gl->DeleteTextures) {
        GLuint tex[5] = {s->own_grid ? s->grid_tex : 0u, s->grid_mask_tex, s->own_lm ? s->lm_tex : 0u, s->lm_valid_tex,
                         s->det_tex};
        gl->DeleteTextures(5, tex);
        GLuint ftex[3] = {s->brick_tex, s->fine_tex, s->fine_mask_tex};
        gl->DeleteTextures(3, ftex);
    }
    if (gl->DeleteQueries && s->queries[0]) gl->DeleteQueries(T_COUNT, s->queries);
    free(s->mat_staging);
    free(s->direct_staging);
    free(s->grp_centre);
    free(s->grp_age);
    free(s->grp_pack);
    free(s->grp_sel);
    free(s->list);
    free(s->grp_delta);
    free(s->grp_drift_at);
    free(s->grp_skip);
    free(s->delta_read);
    free(s->drift_read);
    free(s->sky_staging);
    free(s);
}

/* A cell's RG32UI mask texel: byte o (x: octants 0-3, y: 4-7) = the corners visible from octant o
 * (vis8, the bake's GVIS bytes, NULL = all) that hold a cache (filled). */
static void pack_mask(const uint8_t *vis8, uint32_t filled, uint32_t out[2]) {
    out[0] = out[1] = 0;
    for (uint32_t o = 0; o < 8; ++o) out[o >> 2] |= ((vis8 ? vis8[o] : 0xFFu) & filled) << (8u * (o & 3u));
}

/* Lookups use texelFetch; NEAREST also makes the integer textures complete (an integer texture with a
 * linear filter — GL's default minification filter — is incomplete and reads as 0). */
static void nearest(glow_gl_system *s, GLuint tex) {
    s->gl.TextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    s->gl.TextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    s->gl.TextureParameteri(tex, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    s->gl.TextureParameteri(tex, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    s->gl.TextureParameteri(tex, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

/* Checks a host texture: target, format (RGBA32F, or RGBA16F with GLOW_GL_FLAG_RGBA16F_OUTPUTS), size. */
static int check_host_texture(glow_gl_system *s, GLuint tex, GLenum target, int w, int h, int d, const char *what) {
    glow_glfns *gl = &s->gl;
    while (gl->GetError() != GL_NO_ERROR) {}
    GLint fmt = 0, tw = 0, th = 0, td = 0;
    gl->GetTextureLevelParameteriv(tex, 0, GL_TEXTURE_INTERNAL_FORMAT, &fmt);
    gl->GetTextureLevelParameteriv(tex, 0, GL_TEXTURE_WIDTH, &tw);
    gl->GetTextureLevelParameteriv(tex, 0, GL_TEXTURE_HEIGHT, &th);
    gl->GetTextureLevelParameteriv(tex, 0, GL_TEXTURE_DEPTH, &td);
    if (gl->GetError() != GL_NO_ERROR || fmt != (GLint)s->out_fmt || tw != w || th != h || td != d) {
        LOG_ERR(s, GLOW_ERROR_INVALID_ARGUMENT,
                "host %s texture %u: need %s %s %d x %d x %d, it is format 0x%x %d x %d x %d", what, tex,
                target == GL_TEXTURE_3D ? "GL_TEXTURE_3D" : "GL_TEXTURE_2D_ARRAY",
                s->out_fmt == GL_RGBA16F ? "RGBA16F" : "RGBA32F", w, h, d, fmt, tw, th, td);
        return 0;
    }
    return 1;
}

glow_result glow_gl_system_create(const glow_gl_desc *desc, glow_gl_system **out) {
    if (out) *out = NULL;
    if (!desc || !out || !desc->system || !desc->get_proc_address) {
        logf_(NULL, desc ? &desc->logger : NULL, GLOW_LOG_ERROR, GLOW_ERROR_INVALID_ARGUMENT,
              "glow_gl_system_create: desc, out, desc->system and desc->get_proc_address are required");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    glow_gl_system *s = calloc(1, sizeof *s);
    if (!s) return GLOW_ERROR_OUT_OF_MEMORY;
    s->sys = desc->system;
    s->logger = desc->logger;
    s->flags = desc->flags;
    s->out_fmt = (s->flags & GLOW_GL_FLAG_RGBA16F_OUTPUTS) ? GL_RGBA16F : GL_RGBA32F;
    s->out_texel = s->out_fmt == GL_RGBA16F ? 8u : 16u;
    snprintf(s->label, sizeof s->label, "%s", desc->label ? desc->label : "gl");
    { /* before any GL call: what the bake needs that this backend lacks */
        glow_solver_tables tt;
        if (glow_system_get_solver_tables(desc->system, &tt) == GLOW_OK && tt.link_gradients &&
            (tt.link_subsets || (tt.gradient_node_count && (!tt.gradient_nodes || !tt.gradient_cm)))) {
            LOG_ERR(s, GLOW_ERROR_UNSUPPORTED,
                    "the bake has link gradients but the system's solver tables are inconsistent (gradient_nodes / "
                    "gradient_cm missing, or link subsets as well): cannot read its link gradients");
            free_system(s);
            return GLOW_ERROR_UNSUPPORTED;
        }
    }
    char missing[256];
    if (!glow_glfns_load(&s->gl, desc->get_proc_address, missing, sizeof missing)) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED, "the GL context lacks GL 4.5 entry points: %s", missing);
        free_system(s);
        return GLOW_ERROR_UNSUPPORTED;
    }
    glow_glfns *gl = &s->gl;
    while (gl->GetError() != GL_NO_ERROR) {}
    GLint major = 0, minor = 0;
    gl->GetIntegerv(GL_MAJOR_VERSION, &major);
    gl->GetIntegerv(GL_MINOR_VERSION, &minor);
    const char *rend = (const char *)gl->GetString(GL_RENDERER);
    snprintf(s->renderer, sizeof s->renderer, "%s", rend ? rend : "?");
    if (major * 10 + minor < 45) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED, "needs OpenGL 4.5, the current context is %d.%d (%s)", major, minor,
                s->renderer);
        free_system(s);
        return GLOW_ERROR_UNSUPPORTED;
    }
    glow_system_get_solver_tables(desc->system, &s->t);
    const glow_solver_tables *t = &s->t;
    if (t->proxy_count && (!t->proxy_pairs || t->dependency_count > MAX_DEPS)) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED, "the system's proxy tables are missing or name %u dependencies (at most %u)",
                t->dependency_count, MAX_DEPS);
        free_system(s);
        return GLOW_ERROR_UNSUPPORTED;
    }
    s->P = t->proxy_count;
    s->deps = t->dependency_count;
    const glow_cache_outputs *co = glow_system_outputs(desc->system);
    s->S = t->surfel_count;
    s->N = t->node_count;
    s->C = t->cache_count;
    s->levels = t->level_count;
    s->planes = (t->coeff_count + 3u) / 4u;
    GLint64 max_ssbo_size = 0;
    GLint max_3d = 0, max_layers = 0, max_shared = 0, max_bindings = 0;
    gl->GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_ssbo_size);
    gl->GetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_3d);
    gl->GetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    gl->GetIntegerv(GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, &max_shared);
    gl->GetIntegerv(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS, &max_bindings);
    const size_t links_bytes = (size_t)s->C * t->link_blocks_per_cache * 128u;
    const size_t big = links_bytes > (size_t)s->C * t->coeff_count * 4u ? links_bytes : (size_t)s->C * t->coeff_count * 4u;
    if (max_ssbo_size > 0 && (uint64_t)max_ssbo_size < (uint64_t)big) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED, "GL_MAX_SHADER_STORAGE_BLOCK_SIZE %lld < %zu bytes needed (links / cache SH)",
                (long long)max_ssbo_size, big);
        free_system(s);
        return GLOW_ERROR_UNSUPPORTED;
    }
    if (co->grid_map && (int64_t)co->grid_dims[2] * s->planes > max_3d) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED,
                "the grid texture needs depth %u x %u planes = %u > GL_MAX_3D_TEXTURE_SIZE %d (use fewer bands)",
                co->grid_dims[2], s->planes, co->grid_dims[2] * s->planes, max_3d);
        free_system(s);
        return GLOW_ERROR_UNSUPPORTED;
    }
    const uint32_t lm_pages = co->lightmap_map && co->lightmap_pages ? co->lightmap_pages : 1u; /* format 1.7 */
    if ((int64_t)s->planes * lm_pages > max_layers || max_shared < (int)(GLOW_REDUCE_CHUNK * (GLOW_CACHE_GROUP + 1) * 4) ||
        max_bindings < GLOW_BINDING_HOST_FIRST) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED, "GL limits too small (array layers %d, compute shared memory %d, SSBO bindings %d)",
                max_layers, max_shared, max_bindings);
        free_system(s);
        return GLOW_ERROR_UNSUPPORTED;
    }

    /* programs */
    glow_result err = GLOW_OK;
    for (int k = 0; k < K_COUNT; ++k) {
        if ((k == K_DIRECT && !desc->hook_glsl) || (k == K_DETAIL && !t->detail_texels) || (k == K_PROXY && !t->proxy_count) ||
            (k == K_GRAD && !t->link_gradients) || (k == K_SKY && !(t->sky_grid_visibility && t->grid_cache_count)))
            continue;
        s->prog[k] = build_program(s, k, desc->hook_glsl, &err);
        if (!s->prog[k]) {
            free_system(s);
            return err;
        }
    }
    s->level_loc = gl->GetUniformLocation(s->prog[K_PULL], "glow_level");
    s->tail_loc = gl->GetUniformLocation(s->prog[K_PULL_TAIL], "glow_tail");
    if (s->prog[K_PROXY]) s->proxy_loc = gl->GetUniformLocation(s->prog[K_PROXY], "glow_proxy_range");
    s->list_loc = gl->GetUniformLocation(s->prog[K_CACHE], "glow_cache_list_count");
    s->delta_loc = gl->GetUniformLocation(s->prog[K_CACHE], "glow_cache_delta");
    s->drift_loc = gl->GetUniformLocation(s->prog[K_DRIFT], "glow_drift_count");
    if (s->prog[K_GRAD]) s->grad_loc = gl->GetUniformLocation(s->prog[K_GRAD], "glow_gradient_count");
    if (s->prog[K_SKY]) s->sky_loc = gl->GetUniformLocation(s->prog[K_SKY], "glow_sky_count");
    /* the narrow top: the lowest level from which every level up has at most GLOW_PULL_TAIL_MAX nodes */
    s->tail_level = s->levels;
    while (s->tail_level > 1 && t->level_starts[s->tail_level] - t->level_starts[s->tail_level - 1] <= GLOW_PULL_TAIL_MAX)
        s->tail_level--;

    /* host staging */
    s->mat_staging = malloc((size_t)(s->S ? s->S : 1u) * sizeof *s->mat_staging);
    s->direct_staging = malloc((size_t)(s->S ? s->S : 1u) * 4u * sizeof(float));
    void *geom = malloc((size_t)(s->S ? s->S : 1u) * sizeof(glow_gl_surfel_geom));
    uint32_t *nodes = malloc((size_t)(s->N ? s->N : 1u) * 4u * sizeof(uint32_t));
    /* a refined grid's brick corners that hold a cache follow the grid cells and lightmap texels */
    const uint32_t R = co->grid_refine >= 2 && co->grid_bricks ? co->grid_refine : 0u, S3 = (R + 1u) * (R + 1u) * (R + 1u);
    s->fine_used = 0;
    for (size_t i = 0; R && i < (size_t)co->grid_brick_count * S3; ++i) s->fine_used += co->grid_bricks[i] != MAP_EMPTY;
    const size_t pairs_n = (size_t)t->grid_used + t->lightmap_used + s->fine_used;
    uint32_t *pairs = malloc((pairs_n ? pairs_n : 1u) * 2u * sizeof(uint32_t));
    if (!s->mat_staging || !s->direct_staging || !geom || !nodes || !pairs) {
        free(geom), free(nodes), free(pairs);
        LOG_ERR(s, GLOW_ERROR_OUT_OF_MEMORY, "out of host memory (%u surfels)", s->S);
        free_system(s);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    glow_surfel_view sv;
    glow_system_get_surfels(desc->system, &sv);
    glow_gl_surfel_geom *g = geom;
    for (uint32_t i = 0; i < s->S; ++i) {
        g[i].position_area = (glow_vec4){sv.positions[4 * i], sv.positions[4 * i + 1], sv.positions[4 * i + 2],
                                         sv.positions[4 * i + 3]};
        g[i].normal = (glow_vec4){sv.normals[4 * i], sv.normals[4 * i + 1], sv.normals[4 * i + 2], 0.0f};
    }
    for (uint32_t n = 0; n < s->N; ++n) {
        const int leaf = n < s->S;
        nodes[4 * n] = leaf ? 0u : t->node_children[(size_t)n * t->node_stride];
        nodes[4 * n + 1] = leaf ? 0u : t->node_children[(size_t)n * t->node_stride + 1];
        memcpy(&nodes[4 * n + 2], &t->node_inv_pi_area[n], 4);
        nodes[4 * n + 3] = 0u;
    }
    for (size_t i = 0; i < (size_t)t->grid_used + t->lightmap_used; ++i) {
        pairs[2 * i] = t->output_index[i];
        pairs[2 * i + 1] = t->output_cache[i];
    }
    for (size_t i = 0, k = (size_t)t->grid_used + t->lightmap_used; R && i < (size_t)co->grid_brick_count * S3; ++i)
        if (co->grid_bricks[i] != MAP_EMPTY) {
            pairs[2 * k] = (uint32_t)i; /* brick * S³ + corner */
            pairs[2 * k + 1] = co->grid_bricks[i];
            k++;
        }
    fill_mat(s, 1.0f);
    const GLbitfield dyn = GL_DYNAMIC_STORAGE_BIT;
    s->buf[B_GEOM] = make_buffer(s, (size_t)s->S * sizeof(glow_gl_surfel_geom), geom, 0);
    s->buf[B_MAT] = make_buffer(s, (size_t)s->S * sizeof(glow_gl_surfel_mat), s->mat_staging, dyn);
    s->buf[B_DIRECT] = make_buffer(s, (size_t)s->S * 16u, NULL, dyn);
    s->buf[B_FBW] = make_buffer(s, (size_t)s->S * t->sh_bands_luma * t->sh_bands_luma * 4u, t->feedback_weights, 0);
    s->buf[B_CACHE] = make_buffer(s, (size_t)s->C * t->coeff_count * 4u, NULL, dyn);
    s->buf[B_NODES] = make_buffer(s, (size_t)s->N * 16u, nodes, 0);
    s->buf[B_FLUX] = make_buffer(s, ((size_t)s->N + s->P) * 16u, NULL, dyn); /* + the proxy nodes */
    if (s->P) {
        uint32_t *map = malloc((size_t)s->P * 2u * sizeof *map);
        if (!map) {
            free(geom), free(nodes), free(pairs);
            LOG_ERR(s, GLOW_ERROR_OUT_OF_MEMORY, "out of host memory (%u proxy nodes)", s->P);
            free_system(s);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        memset(s->dep_first, 0, sizeof s->dep_first);
        for (uint32_t p = 0; p < s->P; ++p) s->dep_first[t->proxy_pairs[2 * (size_t)p] + 1]++;
        for (uint32_t d = 0; d < s->deps; ++d) s->dep_first[d + 1] += s->dep_first[d];
        uint32_t at[MAX_DEPS];
        memcpy(at, s->dep_first, sizeof at);
        for (uint32_t p = 0; p < s->P; ++p) { /* counting sort by dependency, proxies in order within one */
            const uint32_t d = t->proxy_pairs[2 * (size_t)p], k = at[d]++;
            map[2 * (size_t)k] = t->proxy_pairs[2 * (size_t)p + 1];
            map[2 * (size_t)k + 1] = s->N + p;
        }
        s->buf[B_PROXY_MAP] = make_buffer(s, (size_t)s->P * 8u, map, 0);
        free(map);
    }
    { /* the budget's groups: their centres, every one stale */
        s->groups = (s->C + GLOW_BUDGET_GROUP - 1u) / GLOW_BUDGET_GROUP;
        s->grp_centre = malloc(((size_t)s->groups + 1u) * 3u * sizeof *s->grp_centre);
        s->grp_age = calloc((size_t)s->groups + 1u, sizeof *s->grp_age);
        s->grp_pack = malloc(((size_t)s->groups + 1u) * sizeof *s->grp_pack);
        s->grp_sel = malloc(((size_t)s->groups + 1u) * sizeof *s->grp_sel);
        s->list = malloc(((size_t)s->C + 1u) * sizeof *s->list);
        s->grp_delta = malloc(((size_t)s->groups + 1u) * sizeof *s->grp_delta);
        s->grp_drift_at = calloc((size_t)s->groups + 1u, sizeof *s->grp_drift_at);
        s->grp_skip = calloc((size_t)s->groups + 1u, sizeof *s->grp_skip);
        s->delta_read = malloc(((size_t)s->C + 1u) * 2u * sizeof *s->delta_read);
        s->drift_groups = (s->N + s->P + GLOW_DRIFT_GROUP - 1u) / GLOW_DRIFT_GROUP;
        s->drift_read = malloc(((size_t)s->drift_groups + 1u) * 2u * sizeof *s->drift_read);
        if (!s->grp_centre || !s->grp_age || !s->grp_pack || !s->grp_sel || !s->list || !s->grp_delta || !s->grp_drift_at ||
            !s->grp_skip || !s->delta_read || !s->drift_read) {
            free(geom), free(nodes), free(pairs);
            LOG_ERR(s, GLOW_ERROR_OUT_OF_MEMORY, "out of host memory (%u cache groups)", s->groups);
            free_system(s);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        for (uint32_t q = 0; q < s->groups; ++q) { /* as the CPU solver: the mean of its caches' positions */
            const uint32_t first = q * GLOW_BUDGET_GROUP, end = first + GLOW_BUDGET_GROUP < s->C ? first + GLOW_BUDGET_GROUP : s->C;
            double c[3] = {0, 0, 0};
            for (uint32_t i = first; i < end; ++i)
                for (int k = 0; k < 3; ++k) c[k] += t->cache_positions[(size_t)i * t->cache_stride + (size_t)k];
            for (int k = 0; k < 3; ++k) s->grp_centre[3 * (size_t)q + (size_t)k] = (float)(c[k] / (double)(end - first));
        }
        s->buf[B_LIST] = make_buffer(s, ((size_t)s->C + 1u) * 4u, NULL, dyn);
        for (uint32_t q = 0; q < s->groups; ++q) s->grp_delta[q] = INFINITY;
        s->buf[B_DELTA] = make_buffer(s, ((size_t)s->C + 1u) * 8u, NULL, 0);
        s->buf[B_DRIFT] = make_buffer(s, ((size_t)s->drift_groups + 1u) * 8u, NULL, 0);
        s->buf[B_RAD_PREV] = make_buffer(s, ((size_t)s->N + s->P + 1u) * 4u, NULL, 0);
        const float zero = 0.0f; /* as the CPU's rad_prev: the first drift is 1 */
        gl->ClearNamedBufferData(s->buf[B_RAD_PREV], GL_R32F, GL_RED, GL_FLOAT, &zero);
    }
    s->buf[B_LINKS] = make_buffer(s, links_bytes, t->link_blocks, 0);
    s->buf[B_PAIRS] = make_buffer(s, pairs_n * 8u, pairs, 0);
    s->buf[B_STATUS] = make_buffer(s, sizeof(glow_gl_status), NULL, dyn);
    s->buf[B_PARAMS] = make_buffer(s, sizeof(glow_gl_params), NULL, dyn);
    s->buf[B_LEVELS] = make_buffer(s, ((size_t)s->levels + 1u) * 4u, t->level_starts, 0);
    if (t->link_subsets) s->buf[B_SUBSETS] = make_buffer(s, links_bytes / 4u, t->link_subsets, 0); /* 2 of 8 bytes per link */
    if (t->link_gradients) { /* link gradients: the codes, the moments, c and M of the coded nodes, their u */
        const uint32_t gn = t->gradient_node_count;
        s->buf[B_SUBSETS] = make_buffer(s, links_bytes / 4u, t->link_gradients, 0);
        s->buf[B_MOM] = make_buffer(s, (size_t)s->N * 16u, NULL, 0);
        s->buf[B_GRAD_U] = make_buffer(s, ((size_t)s->N + s->P) * 16u, NULL, 0); /* 0: scale 1 */
        s->buf[B_GRAD_NODES] = make_buffer(s, (size_t)gn * 4u, gn ? t->gradient_nodes : NULL, 0);
        s->buf[B_GRAD_CM] = make_buffer(s, ((size_t)gn + 3u) / 4u * 192u, gn ? t->gradient_cm : NULL, 0); /* blocks of 4 */
        const float zero = 0.0f;
        gl->ClearNamedBufferData(s->buf[B_MOM], GL_R32F, GL_RED, GL_FLOAT, &zero);
        gl->ClearNamedBufferData(s->buf[B_GRAD_U], GL_R32F, GL_RED, GL_FLOAT, &zero);
    }
    free(geom), free(nodes), free(pairs);
    if (t->detail_texels) { /* the lightmap detail's tables (glow_shared.h GLOW_BINDING_DETAIL_*) */
        uint32_t *dt = malloc(((size_t)t->detail_texels + 1u) * 2u * sizeof(uint32_t));
        uint32_t *dl = malloc(((size_t)t->detail_links + 1u) * 2u * sizeof(uint32_t));
        if (!dt || !dl) {
            free(dt), free(dl);
            free_system(s);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        for (uint32_t i = 0; i <= t->detail_texels; ++i) {
            dt[2 * (size_t)i] = i < t->detail_texels ? t->detail_texel[i] : 0u;
            dt[2 * (size_t)i + 1] = t->detail_first[i];
        }
        for (uint32_t k = 0; k < t->detail_links; ++k) {
            dl[2 * (size_t)k] = t->detail_surfel[k];
            memcpy(&dl[2 * (size_t)k + 1], &t->detail_weight[k], 4);
        }
        dl[2 * (size_t)t->detail_links] = dl[2 * (size_t)t->detail_links + 1] = 0u; /* no empty buffer */
        s->buf[B_DET_TEXELS] = make_buffer(s, ((size_t)t->detail_texels + 1u) * 8u, dt, 0);
        s->buf[B_DET_LINKS] = make_buffer(s, ((size_t)t->detail_links + 1u) * 8u, dl, 0);
        free(dt), free(dl);
    }
    const float zero = 0.0f;
    gl->ClearNamedBufferData(s->buf[B_DIRECT], GL_R32F, GL_RED, GL_FLOAT, &zero);
    gl->ClearNamedBufferData(s->buf[B_CACHE], GL_R32F, GL_RED, GL_FLOAT, &zero);
    gl->ClearNamedBufferData(s->buf[B_FLUX], GL_R32F, GL_RED, GL_FLOAT, &zero);
    s->mat_valid = 0; /* first update computes it with the real params */

    /* output textures */
    s->out = (glow_gl_outputs){.sh_bands_luma = t->sh_bands_luma,
                               .sh_bands_chroma = t->sh_bands_chroma,
                               .coeff_count = t->coeff_count,
                               .planes = s->planes,
                               .output_internal_format = s->out_fmt,
                               .cache_sh_buffer = s->buf[B_CACHE],
                               .flux_buffer = s->buf[B_FLUX],
                               .cache_count = s->C,
                               .hook_program = s->prog[K_DIRECT]};
    const float zero4[4] = {0, 0, 0, 0};
    if (co->grid_map) {
        const uint32_t dx = co->grid_dims[0], dy = co->grid_dims[1], dz = co->grid_dims[2];
        memcpy(s->out.grid_dims, co->grid_dims, sizeof s->out.grid_dims);
        memcpy(s->out.grid_origin, co->grid_origin, sizeof s->out.grid_origin);
        s->out.grid_spacing = co->grid_spacing;
        if (desc->grid_texture) {
            if (!check_host_texture(s, desc->grid_texture, GL_TEXTURE_3D, (int)dx, (int)dy, (int)(dz * s->planes), "grid")) {
                free_system(s);
                return GLOW_ERROR_INVALID_ARGUMENT;
            }
            s->grid_tex = desc->grid_texture;
        } else {
            gl->CreateTextures(GL_TEXTURE_3D, 1, &s->grid_tex);
            gl->TextureStorage3D(s->grid_tex, 1, s->out_fmt, (GLsizei)dx, (GLsizei)dy, (GLsizei)(dz * s->planes));
            s->own_grid = 1;
            s->gpu_bytes += (size_t)dx * dy * dz * s->planes * s->out_texel;
        }
        gl->ClearTexImage(s->grid_tex, 0, GL_RGBA, GL_FLOAT, zero4);
        /* mask: per cell and octant, the corners that hold a cache and are visible (GVIS) */
        const size_t cells = (size_t)dx * dy * dz;
        uint32_t *mask = malloc(cells * 2u * sizeof(uint32_t));
        if (!mask) {
            free_system(s);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        for (uint32_t z = 0; z < dz; ++z)
            for (uint32_t y = 0; y < dy; ++y)
                for (uint32_t x = 0; x < dx; ++x) {
                    const size_t cell = ((size_t)z * dy + y) * dx + x;
                    const uint32_t x1 = x + 1 < dx ? x + 1 : x, y1 = y + 1 < dy ? y + 1 : y, z1 = z + 1 < dz ? z + 1 : z;
                    uint32_t filled = 0;
                    for (uint32_t c = 0; c < 8; ++c) {
                        const uint32_t cx = (c & 1) ? x1 : x, cy = (c & 2) ? y1 : y, cz = (c & 4) ? z1 : z;
                        if (co->grid_map[((size_t)cz * dy + cy) * dx + cx] != MAP_EMPTY) filled |= 1u << c;
                    }
                    pack_mask(co->grid_visibility ? co->grid_visibility + cell * 8u : NULL, filled, mask + 2 * cell);
                }
        gl->CreateTextures(GL_TEXTURE_3D, 1, &s->grid_mask_tex);
        gl->TextureStorage3D(s->grid_mask_tex, 1, GL_RG32UI, (GLsizei)dx, (GLsizei)dy, (GLsizei)dz);
        gl->TextureSubImage3D(s->grid_mask_tex, 0, 0, 0, 0, (GLsizei)dx, (GLsizei)dy, (GLsizei)dz, GL_RG_INTEGER,
                              GL_UNSIGNED_INT, mask);
        s->gpu_bytes += cells * 8u;
        free(mask);
        nearest(s, s->grid_mask_tex);
        if (s->own_grid) nearest(s, s->grid_tex);
        s->out.grid_texture = s->grid_tex;
        s->out.grid_mask_texture = s->grid_mask_tex;
        if (R) { /* the refined grid: brick index, brick atlas, fine masks (GVIS and filled corners) */
            const uint32_t nb = co->grid_brick_count, S = R + 1u, ax = nb < 128u ? nb : 128u, ay = (nb + ax - 1u) / ax;
            s->fine_ax = ax;
            uint32_t *bi = malloc(cells * sizeof *bi), *fm = malloc((size_t)ax * ay * R * R * R * 2u * sizeof *fm);
            if (!bi || !fm) {
                free(bi), free(fm);
                free_system(s);
                return GLOW_ERROR_OUT_OF_MEMORY;
            }
            for (size_t c = 0; c < cells; ++c) bi[c] = co->grid_brick_of_cell[c];
            memset(fm, 0, (size_t)ax * ay * R * R * R * 2u * sizeof *fm);
            for (uint32_t b = 0; b < nb; ++b)
                for (uint32_t l = 0; l < R * R * R; ++l) {
                    const uint32_t lx = l % R, ly = (l / R) % R, lz = l / (R * R);
                    uint32_t filled = 0;
                    for (uint32_t c = 0; c < 8; ++c) {
                        const uint32_t k = ((lz + (c >> 2)) * S + ly + ((c >> 1) & 1u)) * S + lx + (c & 1u);
                        if (co->grid_bricks[(size_t)b * S3 + k] != MAP_EMPTY) filled |= 1u << c;
                    }
                    const size_t at = ((size_t)lz * ay * R + (size_t)(b / ax) * R + ly) * ax * R + (size_t)(b % ax) * R + lx;
                    pack_mask(co->grid_brick_visibility ? co->grid_brick_visibility + ((size_t)b * R * R * R + l) * 8u : NULL,
                              filled, fm + 2 * at);
                }
            gl->CreateTextures(GL_TEXTURE_3D, 1, &s->brick_tex);
            gl->TextureStorage3D(s->brick_tex, 1, GL_R32UI, (GLsizei)dx, (GLsizei)dy, (GLsizei)dz);
            gl->TextureSubImage3D(s->brick_tex, 0, 0, 0, 0, (GLsizei)dx, (GLsizei)dy, (GLsizei)dz, GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, bi);
            gl->CreateTextures(GL_TEXTURE_3D, 1, &s->fine_mask_tex);
            gl->TextureStorage3D(s->fine_mask_tex, 1, GL_RG32UI, (GLsizei)(ax * R), (GLsizei)(ay * R), (GLsizei)R);
            gl->TextureSubImage3D(s->fine_mask_tex, 0, 0, 0, 0, (GLsizei)(ax * R), (GLsizei)(ay * R), (GLsizei)R,
                                  GL_RG_INTEGER, GL_UNSIGNED_INT, fm);
            gl->CreateTextures(GL_TEXTURE_3D, 1, &s->fine_tex);
            gl->TextureStorage3D(s->fine_tex, 1, s->out_fmt, (GLsizei)(ax * S), (GLsizei)(ay * S), (GLsizei)(S * s->planes));
            gl->ClearTexImage(s->fine_tex, 0, GL_RGBA, GL_FLOAT, zero4);
            free(bi), free(fm);
            nearest(s, s->brick_tex), nearest(s, s->fine_mask_tex), nearest(s, s->fine_tex);
            s->gpu_bytes += cells * 4u + (size_t)ax * ay * R * R * R * 8u + (size_t)ax * ay * S * S * S * s->planes * s->out_texel;
            s->out.grid_refine = R;
            s->out.grid_fine_atlas_x = ax;
            s->out.grid_brick_texture = s->brick_tex;
            s->out.grid_fine_texture = s->fine_tex;
            s->out.grid_fine_mask_texture = s->fine_mask_tex;
        }
    }
    if (co->lightmap_map) {
        /* pages (format 1.7): planes of page g at layers g * planes + p; the valid mask's pages stacked */
        const uint32_t W = co->lightmap_width, H = co->lightmap_height, HP = H * lm_pages;
        s->out.lightmap_width = W;
        s->out.lightmap_height = H;
        s->out.lightmap_pages = lm_pages;
        if (desc->lightmap_texture) {
            if (!check_host_texture(s, desc->lightmap_texture, GL_TEXTURE_2D_ARRAY, (int)W, (int)H,
                                    (int)(s->planes * lm_pages), "lightmap")) {
                free_system(s);
                return GLOW_ERROR_INVALID_ARGUMENT;
            }
            s->lm_tex = desc->lightmap_texture;
        } else {
            gl->CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &s->lm_tex);
            gl->TextureStorage3D(s->lm_tex, 1, s->out_fmt, (GLsizei)W, (GLsizei)H, (GLsizei)(s->planes * lm_pages));
            s->own_lm = 1;
            s->gpu_bytes += (size_t)W * HP * s->planes * s->out_texel;
        }
        gl->ClearTexImage(s->lm_tex, 0, GL_RGBA, GL_FLOAT, zero4);
        uint8_t *valid = malloc((size_t)W * HP);
        if (!valid) {
            free_system(s);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        for (size_t i = 0; i < (size_t)W * HP; ++i) valid[i] = co->lightmap_map[i] != MAP_EMPTY;
        gl->CreateTextures(GL_TEXTURE_2D, 1, &s->lm_valid_tex);
        gl->TextureStorage2D(s->lm_valid_tex, 1, GL_R8UI, (GLsizei)W, (GLsizei)HP);
        gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
        gl->TextureSubImage2D(s->lm_valid_tex, 0, 0, 0, (GLsizei)W, (GLsizei)HP, GL_RED_INTEGER, GL_UNSIGNED_BYTE, valid);
        gl->PixelStorei(GL_UNPACK_ALIGNMENT, 4);
        s->gpu_bytes += (size_t)W * HP;
        free(valid);
        nearest(s, s->lm_valid_tex);
        if (s->own_lm) nearest(s, s->lm_tex);
        s->out.lightmap_texture = s->lm_tex;
        s->out.lightmap_valid_texture = s->lm_valid_tex;
    }
    if (t->detail_texels) { /* RGBA32F, (0, 0, 0, 0) where no detail texel covers a surface */
        gl->CreateTextures(GL_TEXTURE_2D, 1, &s->det_tex);
        /* the pages one above another: detail texel page * w * h + y * w + x is row y + page * h */
        gl->TextureStorage2D(s->det_tex, 1, GL_RGBA32F, (GLsizei)t->detail_width, (GLsizei)(t->detail_height * lm_pages));
        gl->ClearTexImage(s->det_tex, 0, GL_RGBA, GL_FLOAT, zero4);
        s->gpu_bytes += (size_t)t->detail_width * t->detail_height * lm_pages * 16u;
        nearest(s, s->det_tex);
        s->out.lightmap_detail_texture = s->det_tex;
        s->out.detail_width = t->detail_width;
        s->out.detail_height = t->detail_height;
    }
    if (!(s->flags & (GLOW_GL_FLAG_NO_TIMERS | GLOW_GL_FLAG_FINISH_TIMERS))) gl->CreateQueries(GL_TIMESTAMP, T_COUNT, s->queries);
    GLenum e = gl->GetError();
    if (e != GL_NO_ERROR) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED, "GL error 0x%x while creating buffers/textures (%.1f MB)", e,
                (double)s->gpu_bytes / 1048576.0);
        free_system(s);
        return GLOW_ERROR_UNSUPPORTED;
    }
    s->params = (glow_gl_params){.surfel_count = s->S,
                                 .node_count = s->N,
                                 .cache_count = s->C,
                                 .coeff_count = t->coeff_count,
                                 .blocks_per_cache = t->link_blocks_per_cache,
                                 .grid_used = t->grid_used,
                                 .lightmap_used = t->lightmap_used,
                                 .planes = s->planes,
                                 .grid_dx = co->grid_dims[0],
                                 .grid_dy = co->grid_dims[1],
                                 .grid_dz = co->grid_dims[2],
                                 .lightmap_width = co->lightmap_width,
                                 .lightmap_height = co->lightmap_height,
                                 .detail_texels = t->detail_texels,
                                 .detail_width = t->detail_width,
                                 .surfel_area = t->surfel_area,
                                 .fine_used = s->fine_used,
                                 .grid_refine = R,
                                 .fine_atlas_x = s->fine_ax};
    *out = s;
    return GLOW_OK;
}

void glow_gl_system_destroy(glow_gl_system *s) {
    if (!s) return;
    if (s->attached) {
        LOG_ERR(s, GLOW_ERROR_INVALID_OPERATION,
                "glow_gl_system_destroy(%s): %u GL system(s) read it as a neighbour; detach it first "
                "(glow_gl_system_set_neighbour with NULL); not destroyed", s->label, s->attached);
        return;
    }
    for (uint32_t d = 0; d < s->deps; ++d)
        if (s->nbr[d]) s->nbr[d]->attached--;
    free_system(s);
}

glow_result glow_gl_system_set_neighbour(glow_gl_system *s, uint32_t dependency, glow_gl_system *nb) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    /* the checks (range, key, node count) and the CPU system's own attachment: glow_system_set_neighbour */
    glow_result r = glow_system_set_neighbour(s->sys, dependency, nb ? nb->sys : NULL);
    if (r != GLOW_OK) return r;
    if (nb) nb->attached++;
    if (s->nbr[dependency]) s->nbr[dependency]->attached--;
    s->nbr[dependency] = nb;
    return GLOW_OK;
}

/* ------------------------------------------------------------------------------------- update */
static void dispatch(glow_gl_system *s, uint32_t groups) {
    if (groups == 0) return;
    uint32_t x = groups < GLOW_MAX_GROUPS_X ? groups : GLOW_MAX_GROUPS_X;
    uint32_t y = (groups + GLOW_MAX_GROUPS_X - 1u) / GLOW_MAX_GROUPS_X;
    s->gl.DispatchCompute(x, y, 1);
}

static void stamp(glow_gl_system *s, int q) {
    if (s->flags & GLOW_GL_FLAG_FINISH_TIMERS) {
        s->gl.Finish();
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        s->cpu_ts[q] = (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
    } else if (s->queries[0]) {
        s->gl.QueryCounter(s->queries[q], GL_TIMESTAMP);
    }
}

/* budget_ms: learns from the last budgeted update's GPU times once they are there (never waits: a
 * timestamp not yet available is skipped), as the CPU solver learns from its own: the stages other than
 * cache lighting, and cache lighting per group from selections large enough to amortise the dispatch.
 * The GPU's time, not the CPU's: a host budgets the GPU frame. */
static void learn_budget(glow_gl_system *s) {
    if (!s->timed_budget || !s->sel_groups) return;
    double t_begin, t_pull, t_cache, t_out;
    if (s->flags & GLOW_GL_FLAG_FINISH_TIMERS) {
        t_begin = s->cpu_ts[T_BEGIN], t_pull = s->cpu_ts[T_PULL], t_cache = s->cpu_ts[T_CACHE], t_out = s->cpu_ts[T_OUTPUT];
    } else if (s->queries[0] && s->queries_pending) {
        GLint ready = 0;
        s->gl.GetQueryObjectiv(s->queries[T_OUTPUT], GL_QUERY_RESULT_AVAILABLE, &ready);
        if (!ready) return;
        GLuint64 ts[T_COUNT];
        for (int q = 0; q < T_COUNT; ++q) s->gl.GetQueryObjectui64v(s->queries[q], GL_QUERY_RESULT, &ts[q]);
        t_begin = 0.0, t_pull = (double)(ts[T_PULL] - ts[T_BEGIN]) * 1e-6, t_cache = (double)(ts[T_CACHE] - ts[T_BEGIN]) * 1e-6,
        t_out = (double)(ts[T_OUTPUT] - ts[T_BEGIN]) * 1e-6;
    } else {
        return;
    }
    s->timed_budget = 0;
    const double cache = t_cache - t_pull, other = (t_out - t_begin) - cache;
    if (s->updates > 1)
        s->ema_other_ms = s->ema_other_ms > 0.0 ? 0.8 * s->ema_other_ms + 0.2 * fmin(other, 2.0 * s->ema_other_ms) : other;
    /* every selection teaches (glow_budget_cost_learn: a small one upwards only in proportion to its size);
     * the GPU's groups are not timed one by one, so the wall time is their time (workers 1) */
    const uint32_t enough = s->groups / 8u > 32u ? s->groups / 8u : (s->groups < 32u ? s->groups : 32u);
    glow_budget_cost_learn(&s->gather_cost, s->sel_groups, enough, 1u, 1u, cache, cache);
}

static void bind(glow_gl_system *s, int binding, int b) { s->gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, (GLuint)binding, s->buf[b]); }

glow_result glow_gl_system_update(glow_gl_system *s, const glow_update_desc *desc) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    const uint32_t flags = desc ? desc->flags : 0u;
    if (flags & ~(GLOW_UPDATE_FLAG_RESET_BOUNCE | GLOW_UPDATE_FLAG_KEEP_LIGHTING)) {
        LOG_ERR(s, GLOW_ERROR_INVALID_ARGUMENT, "glow_gl_system_update: unknown flags 0x%x", flags);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (desc && (!(desc->focus_radius >= 0.0f) || !isfinite(desc->focus_radius) || (desc->focus_count && !desc->focus) ||
                 !(desc->budget_ms >= 0.0f) || !isfinite(desc->budget_ms) || !(desc->converged_epsilon >= 0.0f) ||
                 !isfinite(desc->converged_epsilon))) {
        LOG_ERR(s, GLOW_ERROR_INVALID_ARGUMENT,
                "glow_gl_system_update: budget_ms %g, focus_radius %g and converged_epsilon %g must be finite and >= 0, "
                "and focus_count %u needs focus points",
                (double)desc->budget_ms, (double)desc->focus_radius, (double)desc->converged_epsilon, desc->focus_count);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    for (uint32_t i = 0; desc && i < 3 * desc->focus_count; ++i)
        if (!isfinite(desc->focus[i])) {
            LOG_ERR(s, GLOW_ERROR_INVALID_ARGUMENT, "glow_gl_system_update: focus point %u is not finite", i / 3);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    const bool budgeted = desc && (desc->max_caches || desc->budget_ms > 0.0f || desc->converged_epsilon > 0.0f);
    const double eps = desc ? (double)desc->converged_epsilon : 0.0;
    if (budgeted) learn_budget(s);
    glow_glfns *gl = &s->gl;
    glow_system_params prm;
    glow_system_get_params(s->sys, &prm);
    glow_system_get_solver_tables(s->sys, &s->t);
    const glow_solver_tables *t = &s->t;
    /* material state: recomputed when emission, material scales or the emission scale changed */
    if (!s->mat_valid || t->emission_revision != s->emission_rev_seen || t->material_revision != s->material_rev_seen ||
        prm.emission_scale != s->emission_scale_seen) {
        fill_mat(s, prm.emission_scale);
        gl->NamedBufferSubData(s->buf[B_MAT], 0, (GLsizeiptr)((size_t)s->S * sizeof(glow_gl_surfel_mat)), s->mat_staging);
        s->emission_rev_seen = t->emission_revision;
        s->material_rev_seen = t->material_revision;
        s->emission_scale_seen = prm.emission_scale;
        s->mat_valid = 1;
    }
    s->params.bounce_intensity = prm.bounce_intensity;
    gl->NamedBufferSubData(s->buf[B_PARAMS], 0, sizeof s->params, &s->params);
    gl->BindBufferBase(GL_UNIFORM_BUFFER, GLOW_BINDING_PARAMS, s->buf[B_PARAMS]);
    const uint32_t sgroups = (s->S + GLOW_SURFEL_GROUP - 1u) / GLOW_SURFEL_GROUP;

    stamp(s, T_BEGIN);
    /* 1. direct light */
    if (!(flags & GLOW_UPDATE_FLAG_KEEP_LIGHTING)) {
        if (s->prog[K_DIRECT]) {
            const glow_gl_status st0 = {0, 0, 0xFFFFFFFFu, 0};
            gl->NamedBufferSubData(s->buf[B_STATUS], 0, sizeof st0, &st0);
            gl->UseProgram(s->prog[K_DIRECT]);
            bind(s, GLOW_BINDING_SURFEL_GEOM, B_GEOM);
            bind(s, GLOW_BINDING_SURFEL_MAT, B_MAT);
            bind(s, GLOW_BINDING_DIRECT, B_DIRECT);
            bind(s, GLOW_BINDING_STATUS, B_STATUS);
            dispatch(s, sgroups);
            gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
            if (s->flags & GLOW_GL_FLAG_CHECK_HOOK) {
                glow_gl_status st;
                gl->GetNamedBufferSubData(s->buf[B_STATUS], 0, sizeof st, &st);
                if (st.nonfinite) {
                    LOG_ERR(s, GLOW_ERROR_HOST_CALLBACK,
                            "glow_gl_system_update: the hook returned NaN/Inf for %u surfel(s) (first: %u); the update "
                            "was abandoned and the previous outputs kept",
                            st.nonfinite, st.first_bad);
                    s->direct_valid = 0;
                    return GLOW_ERROR_HOST_CALLBACK;
                }
            }
        } else if (!s->direct_valid || t->direct_revision != s->direct_rev_seen) {
            for (uint32_t i = 0; i < s->S; ++i) {
                memcpy(s->direct_staging + 4 * (size_t)i, t->direct_irradiance + 3 * (size_t)i, 3 * sizeof(float));
                s->direct_staging[4 * (size_t)i + 3] = 0.0f;
            }
            gl->NamedBufferSubData(s->buf[B_DIRECT], 0, (GLsizeiptr)((size_t)s->S * 16u), s->direct_staging);
            s->direct_rev_seen = t->direct_revision;
            s->direct_valid = 1;
        }
    }
    if (s->sky_applied) { /* the grid caches' rows without the sky, bit for bit, before the flux reads them */
        gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        gl->CopyNamedBufferSubData(s->buf[B_SKY_BACKUP], s->buf[B_CACHE], 0, 0,
                                   (GLsizeiptr)((size_t)s->t.grid_cache_count * s->t.coeff_count * 4u));
        s->sky_applied = 0;
    }
    if (flags & GLOW_UPDATE_FLAG_RESET_BOUNCE) {
        const float zero = 0.0f;
        gl->ClearNamedBufferData(s->buf[B_CACHE], GL_R32F, GL_RED, GL_FLOAT, &zero);
        for (uint32_t g = 0; g < s->groups; ++g) s->grp_delta[g] = INFINITY; /* nothing is converged now */
        s->delta_pending = 0;
    }
    stamp(s, T_DIRECT);
    const uint32_t iters = prm.bounce_iterations ? prm.bounce_iterations : 1u;
    s->pull_dispatches = 0;
    for (uint32_t it = 0; it < iters; ++it) {
        /* 2. surfel flux */
        gl->UseProgram(s->prog[K_FLUX]);
        bind(s, GLOW_BINDING_SURFEL_GEOM, B_GEOM); /* each surfel's area (position_area.w) */
        bind(s, GLOW_BINDING_SURFEL_MAT, B_MAT);
        bind(s, GLOW_BINDING_DIRECT, B_DIRECT);
        bind(s, GLOW_BINDING_FEEDBACK_W, B_FBW);
        bind(s, GLOW_BINDING_CACHE_SH, B_CACHE);
        bind(s, GLOW_BINDING_NODES, B_NODES);
        bind(s, GLOW_BINDING_FLUX, B_FLUX);
        if (s->prog[K_GRAD]) bind(s, GLOW_BINDING_MOMENTS, B_MOM); /* also the pull's */
        dispatch(s, sgroups);
        gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        if (it == 0) stamp(s, T_FLUX);
        /* 3. pull: one dispatch per wide level, then the narrow top in one workgroup */
        gl->UseProgram(s->prog[K_PULL]);
        for (uint32_t lv = 1; lv < s->tail_level; ++lv) {
            const uint32_t first = t->level_starts[lv], count = t->level_starts[lv + 1] - first;
            gl->Uniform2ui(s->level_loc, first, count);
            dispatch(s, (count + GLOW_PULL_GROUP - 1u) / GLOW_PULL_GROUP);
            gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            s->pull_dispatches++;
        }
        if (s->tail_level < s->levels) {
            gl->UseProgram(s->prog[K_PULL_TAIL]);
            bind(s, GLOW_BINDING_LEVELS, B_LEVELS);
            if (s->prog[K_GRAD]) bind(s, GLOW_BINDING_MOMENTS_TAIL, B_MOM);
            gl->Uniform2ui(s->tail_loc, s->tail_level > 1 ? s->tail_level : 1u, s->levels);
            gl->DispatchCompute(1, 1, 1);
            gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            s->pull_dispatches++;
        }
        if (s->prog[K_GRAD] && t->gradient_node_count) { /* link gradients: u of the coded nodes (the CPU's pull) */
            gl->UseProgram(s->prog[K_GRAD]);
            bind(s, GLOW_BINDING_FLUX, B_FLUX);
            bind(s, GLOW_BINDING_MOMENTS, B_MOM);
            bind(s, GLOW_BINDING_GRADIENT_NODES, B_GRAD_NODES);
            bind(s, GLOW_BINDING_GRADIENT_CM, B_GRAD_CM);
            bind(s, GLOW_BINDING_GRADIENT_U, B_GRAD_U);
            gl->Uniform1ui(s->grad_loc, t->gradient_node_count);
            dispatch(s, (t->gradient_node_count + GLOW_GRADIENT_GROUP - 1u) / GLOW_GRADIENT_GROUP);
            gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        if (it == 0) stamp(s, T_PULL);
        /* 4. the proxy nodes from the attached neighbours' flux (a detached one's stay as last read) */
        if (s->prog[K_PROXY]) {
            int any = 0;
            for (uint32_t d = 0; d < s->deps; ++d) {
                const uint32_t first = s->dep_first[d], count = s->dep_first[d + 1] - first;
                if (!s->nbr[d] || !count) continue;
                if (!any) {
                    gl->UseProgram(s->prog[K_PROXY]);
                    bind(s, GLOW_BINDING_PROXY_MAP, B_PROXY_MAP);
                    bind(s, GLOW_BINDING_FLUX, B_FLUX);
                    any = 1;
                }
                gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, GLOW_BINDING_PROXY_SRC, s->nbr[d]->buf[B_FLUX]);
                gl->Uniform2ui(s->proxy_loc, first, count);
                dispatch(s, (count + GLOW_PROXY_GROUP - 1u) / GLOW_PROXY_GROUP);
            }
            if (any) gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        /* 5. cache lighting: one workgroup per cache, all or the budget's (chosen once per update, as the
         * CPU solver chooses: glow_budget_choose) */
        if (budgeted && it == 0) {
            const float r = desc->focus_radius > 0.0f ? desc->focus_radius : 0.1f * t->scene_diag; /* as on the CPU */
            uint32_t kmax = desc->max_caches ? (desc->max_caches + GLOW_BUDGET_GROUP - 1u) / GLOW_BUDGET_GROUP : s->groups;
            if (desc->budget_ms > 0.0f && s->gather_cost.group_ms > 0.0) { /* as the CPU solver */
                const uint32_t kt = glow_budget_cost_fit(&s->gather_cost, (double)desc->budget_ms - s->ema_other_ms, 1u, iters);
                if (kt < kmax) kmax = kt;
            }
            if (s->delta_pending) { /* the last budgeted gather's change per group (long finished: no wait) */
                gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
                gl->GetNamedBufferSubData(s->buf[B_DELTA], 0, (GLsizeiptr)((size_t)s->list_count * 8u), s->delta_read);
                for (uint32_t i = 0, at = 0; i < s->sel_groups; ++i) { /* the list: its groups' caches in order */
                    const uint32_t g = s->grp_sel[i], first = g * GLOW_BUDGET_GROUP;
                    const uint32_t count = s->C - first < GLOW_BUDGET_GROUP ? s->C - first : GLOW_BUDGET_GROUP;
                    double d = 0.0, v = 0.0;
                    for (uint32_t c = 0; c < count; ++c, ++at) {
                        d += (double)s->delta_read[2 * (size_t)at];
                        v += (double)s->delta_read[2 * (size_t)at + 1];
                    }
                    s->grp_delta[g] = v > 0.0 ? (float)(d / v) : (d > 0.0 ? INFINITY : 0.0f);
                }
                s->delta_pending = 0;
            }
            if (eps > 0.0) { /* the drift of the light the caches read: this update's, so a moved light is seen now */
                gl->UseProgram(s->prog[K_DRIFT]);
                bind(s, GLOW_BINDING_FLUX, B_FLUX);
                bind(s, GLOW_BINDING_RAD_PREV, B_RAD_PREV);
                bind(s, GLOW_BINDING_DRIFT_PARTIAL, B_DRIFT);
                gl->Uniform1ui(s->drift_loc, s->N + s->P);
                dispatch(s, s->drift_groups);
                gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
                gl->GetNamedBufferSubData(s->buf[B_DRIFT], 0, (GLsizeiptr)((size_t)s->drift_groups * 8u), s->drift_read);
                double dn = 0.0, dv = 0.0;
                for (uint32_t q = 0; q < s->drift_groups; ++q) {
                    dn += (double)s->drift_read[2 * (size_t)q];
                    dv += (double)s->drift_read[2 * (size_t)q + 1];
                }
                s->drift += dv > 0.0 ? dn / dv : (dn > 0.0 ? 1.0 : 0.0);
            }
            uint32_t live = 0;
            for (uint32_t g = 0; g < s->groups; ++g) {
                s->grp_skip[g] = eps > 0.0 && s->grp_delta[g] < eps && s->drift - s->grp_drift_at[g] < eps;
                live += !s->grp_skip[g];
            }
            if (live < kmax) kmax = live;
            const uint32_t k = glow_budget_choose(s->grp_centre, s->grp_age, eps > 0.0 ? s->grp_skip : NULL, s->groups,
                                                  desc->focus, desc->focus_count, r, kmax, s->grp_pack, s->grp_sel);
            s->sel_groups = k;
            for (uint32_t i = 0; i < k; ++i) s->grp_drift_at[s->grp_sel[i]] = s->drift;
            s->caches_converged = 0;
            for (uint32_t g = 0; g < s->groups && eps > 0.0; ++g)
                if (s->grp_delta[g] < eps && s->drift - s->grp_drift_at[g] < eps && s->grp_age[g] > 0) {
                    const uint32_t first = g * GLOW_BUDGET_GROUP;
                    s->caches_converged += s->C - first < GLOW_BUDGET_GROUP ? s->C - first : GLOW_BUDGET_GROUP;
                }
            s->list_count = 0;
            for (uint32_t i = 0; i < k; ++i)
                for (uint32_t c = s->grp_sel[i] * GLOW_BUDGET_GROUP; c < s->C && c < (s->grp_sel[i] + 1u) * GLOW_BUDGET_GROUP; ++c)
                    s->list[s->list_count++] = c;
            if (s->list_count) gl->NamedBufferSubData(s->buf[B_LIST], 0, (GLsizeiptr)((size_t)s->list_count * 4u), s->list);
        }
        gl->UseProgram(s->prog[K_CACHE]);
        gl->Uniform1ui(s->list_loc, budgeted ? s->list_count : 0u);
        gl->Uniform1ui(s->delta_loc, budgeted ? 1u : 0u);
        if (budgeted) {
            bind(s, GLOW_BINDING_CACHE_LIST, B_LIST);
            bind(s, GLOW_BINDING_CACHE_DELTA, B_DELTA);
        }
        bind(s, GLOW_BINDING_LINKS, B_LINKS);
        bind(s, GLOW_BINDING_FLUX, B_FLUX);
        bind(s, GLOW_BINDING_CACHE_SH, B_CACHE);
        if (t->link_subsets) {
            bind(s, GLOW_BINDING_LINK_SUBSETS, B_SUBSETS);
            bind(s, GLOW_BINDING_NODES, B_NODES);
        }
        if (t->link_gradients) {
            bind(s, GLOW_BINDING_LINK_SUBSETS, B_SUBSETS);
            bind(s, GLOW_BINDING_GRADIENT_U, B_GRAD_U);
        }
        if (!budgeted) dispatch(s, s->C);
        else if (s->list_count) dispatch(s, s->list_count);
        gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    s->caches_gathered = budgeted ? s->list_count : s->C;
    if (!budgeted) s->caches_converged = 0;
    if (budgeted) s->delta_pending = s->list_count > 0; /* an unbudgeted update writes no changes: they wait */
    stamp(s, T_CACHE);
    if (s->sky_on) { /* the visible sky into the grid caches, after the bounce (it is not fed back) */
        const uint32_t n = t->grid_cache_count * t->coeff_count;
        gl->UseProgram(s->prog[K_SKY]);
        bind(s, GLOW_BINDING_CACHE_SH, B_CACHE);
        bind(s, GLOW_BINDING_SKY, B_SKY);
        bind(s, GLOW_BINDING_SKY_BACKUP, B_SKY_BACKUP);
        gl->Uniform1ui(s->sky_loc, n);
        dispatch(s, (n + GLOW_SKY_GROUP - 1u) / GLOW_SKY_GROUP);
        gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        s->sky_applied = 1;
    }
    /* 5. outputs (seam/gutter texels are pairs too) */
    if (t->grid_used + t->lightmap_used + s->fine_used) {
        gl->UseProgram(s->prog[K_OUTPUT]);
        if (s->fine_tex) gl->BindImageTexture(GLOW_IMAGE_GRID_FINE, s->fine_tex, 0, GL_TRUE, 0, GL_WRITE_ONLY, s->out_fmt);
        bind(s, GLOW_BINDING_OUTPUT_PAIRS, B_PAIRS);
        bind(s, GLOW_BINDING_CACHE_SH, B_CACHE);
        if (s->grid_tex) gl->BindImageTexture(GLOW_IMAGE_GRID, s->grid_tex, 0, GL_TRUE, 0, GL_WRITE_ONLY, s->out_fmt);
        if (s->lm_tex) gl->BindImageTexture(GLOW_IMAGE_LIGHTMAP, s->lm_tex, 0, GL_TRUE, 0, GL_WRITE_ONLY, s->out_fmt);
        dispatch(s, (t->grid_used + t->lightmap_used + s->fine_used + GLOW_OUTPUT_GROUP - 1u) / GLOW_OUTPUT_GROUP);
        gl->MemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                          GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    }
    if (s->prog[K_DETAIL]) { /* the lightmap detail, from the leaves' flux */
        gl->UseProgram(s->prog[K_DETAIL]);
        bind(s, GLOW_BINDING_DETAIL_TEXELS, B_DET_TEXELS);
        bind(s, GLOW_BINDING_DETAIL_LINKS, B_DET_LINKS);
        bind(s, GLOW_BINDING_FLUX, B_FLUX);
        gl->BindImageTexture(GLOW_IMAGE_DETAIL, s->det_tex, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(s, (t->detail_texels + GLOW_DETAIL_GROUP - 1u) / GLOW_DETAIL_GROUP);
        gl->MemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                          GL_TEXTURE_UPDATE_BARRIER_BIT);
    }
    stamp(s, T_OUTPUT);
    gl->UseProgram(0);
    s->queries_pending = s->queries[0] != 0;
    s->timed_budget = budgeted;
    s->updates++;
    s->out.update_index = s->updates;
    return GLOW_OK;
}

glow_result glow_gl_system_set_sky(glow_gl_system *s, const float sh_rgb[GLOW_SKY_SH_FLOATS]) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    if (!sh_rgb) { /* the next update restores the rows and adds nothing */
        s->sky_on = 0;
        return GLOW_OK;
    }
    const glow_solver_tables *t = &s->t;
    const uint32_t G = t->grid_cache_count, nc = t->coeff_count;
    if (!s->prog[K_SKY]) {
        LOG_ERR(s, GLOW_ERROR_UNSUPPORTED,
                "glow_gl_system_set_sky: the bake carries no sky visibility of its grid caches (format 1.6 SKYT; "
                "baked with --no-sky, before 1.6, or without a grid)");
        return GLOW_ERROR_UNSUPPORTED;
    }
    for (int k = 0; k < GLOW_SKY_SH_FLOATS; ++k)
        if (!isfinite(sh_rgb[k]) || fabsf(sh_rgb[k]) > GLOW_MAX_IRRADIANCE) {
            LOG_ERR(s, GLOW_ERROR_INVALID_ARGUMENT,
                    "glow_gl_system_set_sky: coefficient %d channel %d (%g) is not finite or beyond %g", k / 3, k % 3,
                    (double)sh_rgb[k], (double)GLOW_MAX_IRRADIANCE);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    glow_glfns *gl = &s->gl;
    const size_t bytes = (size_t)G * nc * sizeof(float);
    if (!s->sky_staging) { /* once: a system that never gets a sky holds none */
        s->sky_staging = malloc(bytes);
        if (!s->sky_staging) {
            LOG_ERR(s, GLOW_ERROR_OUT_OF_MEMORY, "glow_gl_system_set_sky: out of host memory for %u grid caches", G);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        while (gl->GetError() != GL_NO_ERROR) {}
        s->buf[B_SKY] = make_buffer(s, bytes, NULL, GL_DYNAMIC_STORAGE_BIT);
        s->buf[B_SKY_BACKUP] = make_buffer(s, bytes, NULL, 0);
        const GLenum e = gl->GetError();
        if (e != GL_NO_ERROR) {
            LOG_ERR(s, GLOW_ERROR_OUT_OF_MEMORY, "glow_gl_system_set_sky: GL error 0x%x creating 2 x %zu bytes", e, bytes);
            gl->DeleteBuffers(2, &s->buf[B_SKY]);
            s->buf[B_SKY] = s->buf[B_SKY_BACKUP] = 0;
            s->gpu_bytes -= 2 * bytes;
            free(s->sky_staging);
            s->sky_staging = NULL;
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
    }
    /* the CPU solver's rows (glow_system_set_sky), so both add the same floats */
    glow_sky_grid_rows(t->sky_grid_visibility, G, sh_rgb, t->sh_bands_luma, t->sh_bands_chroma, s->sky_staging);
    gl->NamedBufferSubData(s->buf[B_SKY], 0, (GLsizeiptr)bytes, s->sky_staging);
    s->sky_on = 1;
    return GLOW_OK;
}

glow_result glow_gl_system_get_stats(glow_gl_system *s, glow_gl_stats *out) {
    if (!s || !out) return GLOW_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    glow_glfns *gl = &s->gl;
    if (s->queries_pending || ((s->flags & GLOW_GL_FLAG_FINISH_TIMERS) && s->updates)) {
        GLuint64 ts[T_COUNT];
        double ms = 1e-6;
        if (s->flags & GLOW_GL_FLAG_FINISH_TIMERS) {
            for (int q = 0; q < T_COUNT; ++q) ts[q] = (GLuint64)((s->cpu_ts[q] - s->cpu_ts[T_BEGIN]) * 1e6);
        } else {
            for (int q = 0; q < T_COUNT; ++q) gl->GetQueryObjectui64v(s->queries[q], GL_QUERY_RESULT, &ts[q]);
        }
        out->host_ms = (double)(ts[T_DIRECT] - ts[T_BEGIN]) * ms;
        out->surfel_lighting_ms = (double)(ts[T_FLUX] - ts[T_BEGIN]) * ms;
        out->pull_ms = (double)(ts[T_PULL] - ts[T_FLUX]) * ms;
        out->cache_lighting_ms = (double)(ts[T_CACHE] - ts[T_PULL]) * ms;
        out->output_ms = (double)(ts[T_OUTPUT] - ts[T_CACHE]) * ms;
        out->total_ms = (double)(ts[T_OUTPUT] - ts[T_BEGIN]) * ms;
    }
    if (s->prog[K_DIRECT]) {
        glow_gl_status st;
        gl->GetNamedBufferSubData(s->buf[B_STATUS], 0, sizeof st, &st);
        out->hook_nonfinite = st.nonfinite;
        out->hook_negative = st.negative;
        if (st.nonfinite)
            LOG_WARN(s, GLOW_ERROR_HOST_CALLBACK, "the hook returned NaN/Inf for %u surfel(s) (first: %u); stored as 0",
                     st.nonfinite, st.first_bad);
    }
    out->pull_dispatches = s->pull_dispatches;
    out->caches_gathered = s->caches_gathered;
    out->caches_skipped_converged = s->caches_converged;
    out->updates = s->updates;
    out->gpu_memory_bytes = s->gpu_bytes;
    snprintf(out->renderer, sizeof out->renderer, "%s", s->renderer);
    return GLOW_OK;
}

const glow_gl_outputs *glow_gl_system_outputs(const glow_gl_system *s) { return s ? &s->out : NULL; }

glow_result glow_gl_system_read_cache_sh(glow_gl_system *s, float *out, size_t count) {
    if (!s || !out || count != (size_t)s->C * s->t.coeff_count) {
        if (s)
            LOG_ERR(s, GLOW_ERROR_INVALID_ARGUMENT, "glow_gl_system_read_cache_sh: need %zu floats, got %zu",
                    (size_t)s->C * s->t.coeff_count, count);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    s->gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    s->gl.GetNamedBufferSubData(s->buf[B_CACHE], 0, (GLsizeiptr)(count * sizeof(float)), out);
    return GLOW_OK;
}

const char *glow_gl_shading_source(void) { return glow__shading_glsl; }
