/* render_scene.c — glow_render's scene: the description file, the mesh (glow-bake's importer), the
 * Embree scene, the emitter distribution; and writing a result's files. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_internal.h"

glow_result glow__render_fail(char *message, size_t message_size, glow_result code, const char *fmt, ...) {
    if (message && message_size) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(message, message_size, fmt, ap);
        va_end(ap);
    }
    return code;
}

static float luminance(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

void glow_render_scene_destroy(glow_render_scene *s) {
    if (!s) return;
    glow__rt_destroy(s->rt);
    glow__scene_free(&s->mesh);
    glow_scene_free(&s->desc);
    free(s->ng);
    free(s->tri_area);
    free(s->emitter_tri);
    free(s->emitter_cdf);
    free(s->light_pdf_area);
    free(s->ggx);
    glow_eval_envmap_free(&s->envmap);
    free(s);
}

glow_result glow_render_scene_load(const char *path, glow_render_scene **out, char *message, size_t message_size) {
    if (message && message_size) message[0] = 0;
    if (out) *out = NULL;
    if (!path || !out) return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render_scene_load: NULL argument");
    glow_render_scene *s = calloc(1, sizeof *s);
    if (!s) return glow__render_fail(message, message_size, GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    snprintf(s->path, sizeof s->path, "%s", path);
    glow_result r = glow_scene_load(path, NULL, &s->desc, message, message_size);
    if (r != GLOW_OK) {
        glow_render_scene_destroy(s);
        return r;
    }
    if (s->desc.environment_map.path[0]) { /* the sky image, before the (slower) mesh */
        char why[600] = "";
        const glow_scene_environment_map *em = &s->desc.environment_map;
        r = glow_eval_envmap_load(em->path, em->rotation_deg, em->scale, &s->envmap, why, sizeof why);
        if (r != GLOW_OK) {
            glow__render_fail(message, message_size, r, "%s: environment_map: %s", path, why);
            glow_render_scene_destroy(s);
            return r;
        }
        s->has_envmap = true;
    }
    r = glow__scene_load(s->desc.mesh, &s->log, &s->mesh);
    if (r != GLOW_OK) {
        glow__render_fail(message, message_size, r, "%s: mesh: %s", path,
                          s->log.last_error[0] ? s->log.last_error : glow_result_string(r));
        glow_render_scene_destroy(s);
        return r;
    }
    const glow__scene *m = &s->mesh;
    if (m->tri_count == 0) {
        glow__render_fail(message, message_size, GLOW_ERROR_EMPTY_SCENE, "%s: mesh %s has no usable triangles", path,
                          s->desc.mesh);
        glow_render_scene_destroy(s);
        return GLOW_ERROR_EMPTY_SCENE;
    }
    for (uint32_t t = 0; t < m->tri_count; ++t)
        if (m->tri_material[t] >= m->material_count) {
            glow__render_fail(message, message_size, GLOW_ERROR_CORRUPT_DATA, "%s: mesh %s: triangle %u has material %u of %u",
                              path, s->desc.mesh, t, m->tri_material[t], m->material_count);
            glow_render_scene_destroy(s);
            return GLOW_ERROR_CORRUPT_DATA;
        }
    if (s->desc.material_count) { /* the scene's per-material overrides, by the mesh's material names */
        s->ggx = calloc(m->material_count ? m->material_count : 1, sizeof *s->ggx);
        if (!s->ggx) goto oom;
        for (uint32_t i = 0; i < s->desc.material_count; ++i) {
            const glow_scene_material *sm = &s->desc.materials[i];
            uint32_t hits = 0;
            for (uint32_t j = 0; j < m->material_count; ++j) {
                if (strcmp(m->materials[j].name, sm->name) != 0) continue;
                hits++;
                if (!sm->ggx) continue;
                glow__render_ggx_init(&s->ggx[j], sm->roughness, sm->specular);
            }
            if (!hits) {
                char names[256] = "";
                for (uint32_t j = 0; j < m->material_count && strlen(names) < 200; ++j)
                    snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", j ? ", " : "", m->materials[j].name);
                glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                  "%s: materials.%s: the mesh %s has no material of that name (it has: %s)", path, sm->name,
                                  s->desc.mesh, names);
                glow_render_scene_destroy(s);
                return GLOW_ERROR_INVALID_ARGUMENT;
            }
        }
        for (uint32_t j = 0; j < m->material_count; ++j) s->glossy_count += s->ggx[j].alpha > 0.0f;
        if (!s->glossy_count) {
            free(s->ggx);
            s->ggx = NULL;
        }
    }
    r = glow__rt_create(m, &s->log, &s->rt);
    if (r != GLOW_OK) {
        glow__render_fail(message, message_size, r, "%s: %s", path, s->log.last_error[0] ? s->log.last_error : "embree failed");
        glow_render_scene_destroy(s);
        return r;
    }
    s->ng = malloc((size_t)m->tri_count * sizeof *s->ng);
    s->tri_area = malloc((size_t)m->tri_count * sizeof *s->tri_area);
    s->light_pdf_area = calloc(m->tri_count, sizeof *s->light_pdf_area);
    if (!s->ng || !s->tri_area || !s->light_pdf_area) goto oom;
    uint32_t emitters = 0;
    for (uint32_t t = 0; t < m->tri_count; ++t) {
        const float(*p)[3] = m->pos + 3 * (size_t)t;
        float e1[3], e2[3], n[3];
        glow__sub(p[1], p[0], e1);
        glow__sub(p[2], p[0], e2);
        glow__cross(e1, e2, n);
        float len = sqrtf(glow__dot(n, n));
        s->tri_area[t] = 0.5f * len;
        for (int k = 0; k < 3; ++k) s->ng[t][k] = len > 0.0f ? n[k] / len : (k == 2 ? 1.0f : 0.0f);
        const float *e = m->materials[m->tri_material[t]].emission;
        if ((e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f) && len > 0.0f) emitters++;
    }
    if (emitters) {
        s->emitter_tri = malloc((size_t)emitters * sizeof *s->emitter_tri);
        s->emitter_cdf = malloc((size_t)emitters * sizeof *s->emitter_cdf);
        if (!s->emitter_tri || !s->emitter_cdf) goto oom;
        double total = 0.0;
        for (uint32_t t = 0; t < m->tri_count; ++t) {
            const float *e = m->materials[m->tri_material[t]].emission;
            if (!((e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f) && s->tri_area[t] > 0.0f)) continue;
            /* a tiny floor so an emitter of (say) pure blue-ish luminance still gets samples */
            double w = (double)s->tri_area[t] * fmax((double)luminance(e), 1e-6);
            total += w;
            s->emitter_cdf[s->emitter_count] = total;
            s->emitter_tri[s->emitter_count++] = t;
        }
        for (uint32_t i = 0; i < s->emitter_count; ++i) {
            uint32_t t = s->emitter_tri[i];
            const float *e = m->materials[m->tri_material[t]].emission;
            s->emitter_cdf[i] /= total;
            s->light_pdf_area[t] = (float)(fmax((double)luminance(e), 1e-6) / total);
        }
        s->emitter_cdf[s->emitter_count - 1] = 1.0;
    }
    float d2 = 0.0f;
    for (int k = 0; k < 3; ++k) d2 += (m->bounds_max[k] - m->bounds_min[k]) * (m->bounds_max[k] - m->bounds_min[k]);
    s->diag = sqrtf(d2);
    s->eps = 1e-4f * s->diag;
    s->camera = s->desc.camera;
    if (!s->desc.has_camera) glow_scene_camera_default(m->bounds_min, m->bounds_max, &s->camera);
    *out = s;
    return GLOW_OK;
oom:
    glow_render_scene_destroy(s);
    return glow__render_fail(message, message_size, GLOW_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
}

glow_result glow_render_scene_get_info(const glow_render_scene *s, glow_render_scene_info *o) {
    if (o) memset(o, 0, sizeof *o);
    if (!s || !o) return GLOW_ERROR_INVALID_ARGUMENT;
    o->triangle_count = s->mesh.tri_count;
    o->material_count = s->mesh.material_count;
    o->texture_count = s->mesh.texture_count;
    o->emissive_triangle_count = s->emitter_count;
    o->light_count = s->desc.light_count;
    memcpy(o->environment, s->desc.environment, sizeof o->environment);
    o->emission_scale = s->desc.emission_scale;
    o->camera = s->camera;
    memcpy(o->bounds_min, s->mesh.bounds_min, sizeof o->bounds_min);
    memcpy(o->bounds_max, s->mesh.bounds_max, sizeof o->bounds_max);
    o->mesh = s->desc.mesh;
    if (s->has_envmap) {
        o->environment_map = s->desc.environment_map.path;
        o->environment_map_width = s->envmap.width;
        o->environment_map_height = s->envmap.height;
        o->environment_map_rotation_deg = s->envmap.rotation_deg;
        o->environment_map_scale = s->envmap.scale;
    }
    return GLOW_OK;
}

void glow_render_result_free(glow_render_result *r) {
    if (!r) return;
    glow_eval_image_free(&r->final);
    glow_eval_image_free(&r->direct);
    glow_eval_image_free(&r->indirect);
    glow_eval_image_free(&r->indirect_near);
    glow_eval_image_free(&r->texel);
    glow_eval_image_free(&r->specular);
    memset(r, 0, sizeof *r);
}

glow_result glow_render_write(const glow_render_result *res, const char *prefix, float exposure, char *message,
                              size_t message_size) {
    if (message && message_size) message[0] = 0;
    if (!res || !prefix || !prefix[0] || !res->final.rgb || !res->direct.rgb || !res->indirect.rgb)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "glow_render_write: nothing to write");
    if (!isfinite(exposure) || exposure < 0.0f)
        return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT,
                                 "glow_render_write: exposure %g must be finite and >= 0", (double)exposure);
    /* the near part of the indirect light (glow_render_settings.near_split) and the texel image (glow
     * view with a lightmap) only when they were rendered */
    static const char *all_suffix[7] = {".exr", "_direct.exr", "_indirect.exr", ".png", "_indirect_near.exr", "_texel.exr",
                                        "_specular.exr"};
    const glow_eval_image *all_img[7] = {&res->final, &res->direct, &res->indirect, &res->final, &res->indirect_near, &res->texel,
                                         &res->specular};
    const char *suffix[7];
    const glow_eval_image *img[7];
    int N = 0;
    for (int i = 0; i < 7; ++i)
        if (i < 4 || all_img[i]->rgb) {
            suffix[N] = all_suffix[i];
            img[N++] = all_img[i];
        }
    char path[7][1024], part[7][1040];
    for (int i = 0; i < N; ++i) {
        int n = snprintf(path[i], sizeof path[i], "%s%s", prefix, suffix[i]);
        int n2 = snprintf(part[i], sizeof part[i], "%s%s.part", prefix, suffix[i]);
        if (n < 0 || (size_t)n >= sizeof path[i] || n2 < 0 || (size_t)n2 >= sizeof part[i])
            return glow__render_fail(message, message_size, GLOW_ERROR_INVALID_ARGUMENT, "%s: output prefix too long", prefix);
    }
    glow_result r = GLOW_OK;
    for (int i = 0; i < N && r == GLOW_OK; ++i) {
        char why[512] = "";
        r = i != 3 ? glow_eval_write_exr(img[i], part[i], why, sizeof why)
                   : glow_eval_write_png(img[i], exposure, part[i], why, sizeof why);
        if (r != GLOW_OK) glow__render_fail(message, message_size, r, "%s: cannot write it (%s)", path[i], why);
    }
    if (r == GLOW_OK) {
        for (int i = 0; i < N; ++i)
            if (rename(part[i], path[i]) != 0) {
                r = glow__render_fail(message, message_size, GLOW_ERROR_IO, "%s: cannot rename %s into place", path[i], part[i]);
                for (int j = 0; j < i; ++j) remove(path[j]); /* all or nothing */
                break;
            }
        if (r == GLOW_OK) return GLOW_OK;
    }
    for (int i = 0; i < N; ++i) remove(part[i]);
    return r;
}
