/* blotch.c — glow_eval_blotches: error regions of Glow's view that span more than one lightmap texel
 * (definitions in glow_eval.h, "Blotches"). Pixels are grouped by texel through a sort of their keys,
 * texels joined by a union-find over touching pixels; all in double, deterministic. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "eval_internal.h"
#include "glow_eval.h"

typedef struct texel_acc {
    double t, r;        /* Σ luma of the test and the reference over its pixels */
    uint64_t n;         /* pixels */
    double rel;         /* (t - r) / max(r, n floor) */
    int sign;           /* +1 / -1 when bad, 0 otherwise */
    uint32_t cache;     /* the texel image's B (cache + 1) at its first pixel; 0 = none */
} texel_acc;

static double luma(const float *p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

static uint64_t key_of(const float *p) {
    if (!(p[0] >= 1.0f) || !(p[1] >= 1.0f)) return 0;
    return ((uint64_t)(uint32_t)p[0] << 32) | (uint32_t)p[1];
}

typedef struct key_pixel {
    uint64_t key;
    uint32_t pixel;
} key_pixel;

static int cmp_key_pixel(const void *a, const void *b) {
    const key_pixel *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->pixel < y->pixel ? -1 : x->pixel > y->pixel;
}

static uint32_t find(uint32_t *parent, uint32_t i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static void join(uint32_t *parent, uint32_t a, uint32_t b) {
    a = find(parent, a);
    b = find(parent, b);
    if (a != b) parent[a < b ? b : a] = a < b ? a : b; /* the smaller index is the root: deterministic */
}

glow_result glow_eval_blotches(const glow_eval_image *test, const glow_eval_image *ref, const glow_eval_image *texels,
                               const glow_eval_blotch_params *params, glow_eval_blotch_result *out, char *message,
                               size_t message_size) {
    if (out) memset(out, 0, sizeof *out);
    const glow_eval_image *img[3] = {test, ref, texels};
    static const char *const names[3] = {"test image", "reference image", "texel image"};
    for (int k = 0; k < 3; k++)
        if (!out || !img[k] || !img[k]->rgb || img[k]->width == 0 || img[k]->height == 0) {
            glow__eval_set_message(message, message_size, "blotches: NULL or empty %s", !out ? "output" : names[k]);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    const uint32_t W = ref->width, H = ref->height;
    for (int k = 0; k < 3; k++) {
        if (img[k]->width != W || img[k]->height != H) {
            glow__eval_set_message(message, message_size, "blotches: %s is %ux%u, the reference %ux%u", names[k],
                                   img[k]->width, img[k]->height, W, H);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
        for (size_t i = 0; i < (size_t)W * H * 3; i++)
            if (!isfinite(img[k]->rgb[i])) {
                glow__eval_set_message(message, message_size, "blotches: %s pixel (%u, %u) is not finite", names[k],
                                       (unsigned)(i / 3 % W), (unsigned)(i / 3 / W));
                return GLOW_ERROR_INVALID_ARGUMENT;
            }
    }
    if ((uint64_t)W * H > UINT32_MAX) {
        glow__eval_set_message(message, message_size, "blotches: image %ux%u too large", W, H);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const double threshold = params && params->threshold > 0.0 ? params->threshold : 0.5;
    const uint64_t min_pixels = params && params->min_pixels ? params->min_pixels : 16u;
    const uint32_t n = W * H;
    double ref_sum = 0.0;
    for (uint32_t i = 0; i < n; i++) ref_sum += luma(ref->rgb + 3 * (size_t)i);
    const double floor_luma = 1e-3 * ref_sum / (double)n;

    key_pixel *kp = malloc(sizeof *kp * n);
    uint32_t *texel_of = malloc(sizeof *texel_of * n); /* pixel -> texel index, UINT32_MAX = none */
    texel_acc *acc = NULL;
    uint32_t *parent = NULL;
    glow_result r = GLOW_OK;
    if (!kp || !texel_of) goto oom;
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
        texel_of[i] = UINT32_MAX;
        const uint64_t key = key_of(texels->rgb + 3 * (size_t)i);
        if (key) kp[m++] = (key_pixel){key, i};
    }
    qsort(kp, m, sizeof *kp, cmp_key_pixel);
    uint32_t T = 0;
    for (uint32_t i = 0; i < m; i++) {
        if (i > 0 && kp[i].key != kp[i - 1].key) T++;
        texel_of[kp[i].pixel] = T;
    }
    if (m) T++;
    out->texels = T;
    acc = calloc(T ? T : 1, sizeof *acc);
    parent = malloc(sizeof *parent * (T ? T : 1));
    if (!acc || !parent) goto oom;
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t t = texel_of[i];
        if (t == UINT32_MAX) continue;
        acc[t].t += luma(test->rgb + 3 * (size_t)i);
        acc[t].r += luma(ref->rgb + 3 * (size_t)i);
        if (!acc[t].n++) {
            const float b = texels->rgb[3 * (size_t)i + 2];
            acc[t].cache = b >= 1.0f && b < 4294967296.0f ? (uint32_t)b : 0u;
        }
    }
    for (uint32_t t = 0; t < T; t++) {
        parent[t] = t;
        texel_acc *a = &acc[t];
        if (a->n < min_pixels) continue;
        out->judged++;
        out->judged_pixels += a->n;
        const double den = fmax(a->r, (double)a->n * floor_luma), diff = a->t - a->r;
        a->rel = den > 0.0 ? diff / den : (diff > 0.0 ? INFINITY : diff < 0.0 ? -INFINITY : 0.0);
        if (fabs(a->rel) > fabs(out->worst_rel)) out->worst_rel = a->rel;
        if (fabs(a->rel) > threshold) {
            a->sign = a->rel > 0.0 ? 1 : -1;
            out->bad++;
            out->bad_pixels += a->n;
        }
    }
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            const uint32_t a = texel_of[y * W + x];
            if (a == UINT32_MAX || !acc[a].sign) continue;
            const uint32_t nb[2] = {x + 1 < W ? texel_of[y * W + x + 1] : UINT32_MAX,
                                    y + 1 < H ? texel_of[(y + 1) * W + x] : UINT32_MAX};
            for (int k = 0; k < 2; k++)
                if (nb[k] != UINT32_MAX && nb[k] != a && acc[nb[k]].sign == acc[a].sign) join(parent, a, nb[k]);
        }
    /* per set, at its root: texels, pixels, Σ T and Σ R */
    uint32_t *count = calloc(T ? T : 1, sizeof *count);
    uint64_t *pixels = calloc(T ? T : 1, sizeof *pixels);
    double *st = calloc(2 * (size_t)(T ? T : 1), sizeof *st);
    if (!count || !pixels || !st) {
        free(count);
        free(pixels);
        free(st);
        goto oom;
    }
    for (uint32_t t = 0; t < T; t++) {
        if (!acc[t].sign) continue;
        const uint32_t root = find(parent, t);
        count[root]++;
        pixels[root] += acc[t].n;
        st[2 * root] += acc[t].t;
        st[2 * root + 1] += acc[t].r;
    }
    uint32_t best = UINT32_MAX;
    for (uint32_t t = 0; t < T; t++) {
        if (!count[t]) continue;
        if (count[t] >= 2) {
            out->blotches++;
            out->blotch_pixels += pixels[t];
        }
        if (best == UINT32_MAX || pixels[t] > pixels[best]) best = t;
    }
    if (best != UINT32_MAX) {
        out->largest_texels = count[best];
        out->largest_pixels = pixels[best];
        const double rr = st[2 * best + 1];
        out->largest_rel = rr > 0.0 ? (st[2 * best] - rr) / rr : 0.0;
        uint32_t box[4] = {W, H, 0, 0};
        for (uint32_t y = 0; y < H; y++)
            for (uint32_t x = 0; x < W; x++) {
                const uint32_t t = texel_of[y * W + x];
                if (t == UINT32_MAX || !acc[t].sign || find(parent, t) != best) continue;
                box[0] = x < box[0] ? x : box[0];
                box[1] = y < box[1] ? y : box[1];
                box[2] = x > box[2] ? x : box[2];
                box[3] = y > box[3] ? y : box[3];
            }
        memcpy(out->largest_box, box, sizeof box);
        /* its caches, by pixels (insertion into a short sorted list; ties: lower texel first) */
        uint32_t top[8];
        uint32_t k = 0;
        for (uint32_t t = 0; t < T; t++) {
            if (!acc[t].sign || !acc[t].cache || find(parent, t) != best) continue;
            uint32_t j = k < 8 ? k++ : 8;
            while (j > 0 && acc[top[j - 1]].n < acc[t].n) {
                if (j < 8) top[j] = top[j - 1];
                j--;
            }
            if (j < 8) top[j] = t;
        }
        for (uint32_t j = 0; j < k; j++) out->largest_caches[j] = acc[top[j]].cache - 1u;
        out->largest_cache_count = k;
    }
    free(count);
    free(pixels);
    free(st);
    goto done;
oom:
    glow__eval_set_message(message, message_size, "blotches: out of memory (%ux%u)", W, H);
    r = GLOW_ERROR_OUT_OF_MEMORY;
    memset(out, 0, sizeof *out);
done:
    free(kp);
    free(texel_of);
    free(acc);
    free(parent);
    return r;
}
