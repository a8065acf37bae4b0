/* import.c — scene import through assimp (any format it reads), material and texture
 * extraction, and the cleaning step shared with the built-in scenes (glow__scene_finalize). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "pc_internal.h"
#include "texture.h"

/* strncpy that always terminates (and keeps -Wformat-truncation quiet about long names). */
static void copy_str(char *dst, size_t size, const char *src) {
    size_t n = strlen(src);
    if (n >= size) n = size - 1;
    memcpy(dst, src, n);
    dst[n] = 0;
}

/* An aiString into a C string: bounded by its length (assimp does not always terminate data
 * within it), control and non-ASCII bytes replaced so log lines stay printable. */
static void copy_aistring(char *dst, size_t size, const struct aiString *src) {
    size_t n = src->length;
    if (n > sizeof src->data - 1) n = sizeof src->data - 1;
    if (n >= size) n = size - 1;
    size_t i = 0;
    for (; i < n && src->data[i]; i++) {
        unsigned char ch = (unsigned char)src->data[i];
        dst[i] = (ch < 32 || ch > 126) ? '?' : (char)ch;
    }
    dst[i] = 0;
}

/* Albedo ceiling: keeps every bounce strictly energy-losing (DESIGN: feedback must not diverge). */
#define ALBEDO_MAX 0.999f

void glow__scene_free(glow__scene *scene) {
    if (!scene) return;
    free(scene->pos);
    free(scene->nrm);
    free(scene->uv0);
    free(scene->uv1);
    free(scene->tri_material);
    free(scene->tri_source);
    free(scene->object_name);
    free(scene->source_object);
    free(scene->materials);
    if (scene->textures)
        for (uint32_t i = 0; i < scene->texture_count; i++) glow__texture_free(&scene->textures[i]);
    free(scene->textures);
    memset(scene, 0, sizeof *scene);
}

/* ================================================================== finalize */

static bool finite3(const float v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

static double tri_area2(const float a[3], const float b[3], const float c[3], double n[3]) {
    double e1[3] = {(double)b[0] - a[0], (double)b[1] - a[1], (double)b[2] - a[2]};
    double e2[3] = {(double)c[0] - a[0], (double)c[1] - a[1], (double)c[2] - a[2]};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]); /* twice the area */
}

/* Duplicate-face key: the three corners' bit patterns (with -0 folded onto +0), corners sorted,
 * so the same three positions match whatever the corner order or winding. */
typedef struct face_key {
    uint32_t w[9];
} face_key;

static uint32_t fbits(float f) {
    uint32_t u;
    if (f == 0.0f) f = 0.0f; /* -0 -> +0 */
    memcpy(&u, &f, sizeof u);
    return u;
}

static int corner_cmp(const uint32_t *a, const uint32_t *b) {
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}

/* Returns the winding parity of the sort (0 even, 1 odd). */
static int make_key(const float (*p)[3], face_key *key) {
    uint32_t c[3][3];
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) c[i][k] = fbits(p[i][k]);
    int order[3] = {0, 1, 2}, parity = 0;
    /* 3-element sorting network, counting swaps */
    static const int pairs[3][2] = {{0, 1}, {1, 2}, {0, 1}};
    for (int s = 0; s < 3; s++) {
        int i = pairs[s][0], j = pairs[s][1];
        if (corner_cmp(c[order[i]], c[order[j]]) > 0) {
            int t = order[i];
            order[i] = order[j];
            order[j] = t;
            parity ^= 1;
        }
    }
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) key->w[3 * i + k] = c[order[i]][k];
    return parity;
}

static uint64_t key_hash(const face_key *k) {
    uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int i = 0; i < 9; i++) {
        h ^= k->w[i];
        h *= 0xFF51AFD7ED558CCDull;
        h ^= h >> 33;
    }
    return h;
}

static void geometric_normal(const float (*p)[3], float out[3]) {
    double n[3];
    double len = tri_area2(p[0], p[1], p[2], n);
    if (len > 0.0) {
        for (int k = 0; k < 3; k++) out[k] = (float)(n[k] / len);
    } else {
        out[0] = 0.0f;
        out[1] = 1.0f;
        out[2] = 0.0f;
    }
}

static glow_result finalize_materials(glow__scene *s, glow__log *log) {
    uint32_t nonfinite = 0, clamped = 0, negative_emission = 0;
    const char *first_nonfinite = NULL, *first_clamped = NULL;
    for (uint32_t i = 0; i < s->material_count; i++) {
        glow__material *m = &s->materials[i];
        m->name[sizeof m->name - 1] = 0;
        for (int k = 0; k < 3; k++) {
            if (!isfinite(m->albedo[k]) || !isfinite(m->emission[k])) {
                if (!nonfinite++) first_nonfinite = m->name;
                if (!isfinite(m->albedo[k])) m->albedo[k] = 0.0f;
                if (!isfinite(m->emission[k])) m->emission[k] = 0.0f;
            }
            if (m->albedo[k] < 0.0f || m->albedo[k] > ALBEDO_MAX) {
                if (!clamped++) first_clamped = m->name;
                m->albedo[k] = m->albedo[k] < 0.0f ? 0.0f : ALBEDO_MAX;
            }
            if (m->emission[k] < 0.0f) {
                negative_emission++;
                m->emission[k] = 0.0f;
            }
        }
        if (m->texture < -1 || m->texture >= (int)s->texture_count) m->texture = -1;
        if (m->emission_texture < -1 || m->emission_texture >= (int)s->texture_count) m->emission_texture = -1;
    }
    if (nonfinite)
        glow__warnf(log, "%s: %u non-finite material colour values (first in material '%s') replaced by 0", s->source,
                    nonfinite, first_nonfinite);
    if (clamped)
        glow__warnf(log, "%s: %u albedo values outside [0, %.3f] clamped (first in material '%s'; energy conservation)",
                    s->source, clamped, (double)ALBEDO_MAX, first_clamped);
    if (negative_emission)
        glow__warnf(log, "%s: %u negative emission values replaced by 0", s->source, negative_emission);
    return GLOW_OK;
}


/* ---- consistent winding (issue 13: meshes as exporters leave them) ----
 * Glow lights the front face of a triangle only (surfels and lightmap texels sit on it), while a path
 * tracer reflects on both sides, so a triangle wound against its neighbours reads dark in Glow: a room
 * whose triangles were flipped at random (30 %) read 0.30 of the path tracer's indirect light. Where
 * the file gives no normals, the winding is the only orientation there is: triangles of one material
 * that share an edge (exactly two triangles on it, manifold) must traverse it in opposite directions,
 * so each such patch is made consistent by a walk over its edges, and the orientation of the larger
 * area of the patch's triangles as the file wound them wins, when it is clearly larger (a patch wound consistently keeps its
 * winding, even when it faces away from where it is seen: glow-bake warns about that, caches.c).
 * Emissive materials keep the file's winding (it says which side emits). Exporters also leave
 * T-junctions (a long edge of one triangle met by two shorter edges of others, the corner between them
 * lying on it): such edges are joined too (wind_tjunctions), so a wall cut around a window orients with
 * the rest of its room. */
#define WIND_MAJORITY 1.5 /* a patch turns its minority only when the majority's area is this many times larger */
typedef struct wind_edge {
    uint32_t key[6]; /* the two corners' position bits, the smaller first */
    uint32_t material, tri;
    uint8_t forward; /* the triangle runs from key[0..2] to key[3..5] */
} wind_edge;

static int wind_edge_cmp(const void *a, const void *b) {
    const wind_edge *x = a, *y = b;
    if (x->material != y->material) return x->material < y->material ? -1 : 1;
    for (int i = 0; i < 6; i++)
        if (x->key[i] != y->key[i]) return x->key[i] < y->key[i] ? -1 : 1;
    return x->tri < y->tri ? -1 : (x->tri > y->tri);
}

static void flip_triangle(glow__scene *s, uint32_t t) {
    float tmp3[3], tmp2[2];
    float (*c3[2])[3] = {s->pos, s->nrm};
    for (int k = 0; k < 2; k++) {
        if (!c3[k]) continue;
        memcpy(tmp3, c3[k][3 * (size_t)t + 1], sizeof tmp3);
        memcpy(c3[k][3 * (size_t)t + 1], c3[k][3 * (size_t)t + 2], sizeof tmp3);
        memcpy(c3[k][3 * (size_t)t + 2], tmp3, sizeof tmp3);
    }
    float (*uvs[2])[2] = {s->uv0, s->uv1};
    for (int k = 0; k < 2; k++) {
        if (!uvs[k]) continue;
        memcpy(tmp2, uvs[k][3 * (size_t)t + 1], sizeof tmp2);
        memcpy(uvs[k][3 * (size_t)t + 1], uvs[k][3 * (size_t)t + 2], sizeof tmp2);
        memcpy(uvs[k][3 * (size_t)t + 2], tmp2, sizeof tmp2);
    }
}

/* T-junctions: a boundary edge (no manifold partner) of one material that lies along another's — the
 * long edge of a T-junction and the pieces of other triangles that run along it — makes their triangles
 * neighbours across the overlap. Edge a is tested against the boundary edges that pass by its midpoint
 * (a grid of cells of about the mean boundary edge's length; every edge is entered in the cells of
 * points half a cell apart along it, a midpoint's cell and the 26 around it are searched): b must run
 * along a (the shorter's corners within WIND_TJ_TOL x (coordinate magnitude + the longer's length) of
 * the longer's line, a few float ulps) and cover a's midpoint. A midpoint covered by two or more such
 * edges (a non-manifold seam) joins nothing. Appends (tri a, tri b, same direction) to *pairs; returns
 * how many, or UINT32_MAX when out of memory. */
#define WIND_TJ_TOL 4e-6
#define WIND_TJ_MAX_ENTRIES (1u << 26)
typedef struct wind_cell {
    uint64_t cell;
    uint32_t edge;
} wind_cell;
static int wind_cell_cmp(const void *a, const void *b) {
    const wind_cell *x = a, *y = b;
    if (x->cell != y->cell) return x->cell < y->cell ? -1 : 1;
    return x->edge < y->edge ? -1 : (x->edge > y->edge);
}
static void wind_key_pos(const uint32_t key[3], double p[3]) {
    float f[3];
    memcpy(f, key, sizeof f);
    for (int i = 0; i < 3; i++) p[i] = f[i];
}
/* edge i's corners and length */
static double wind_edge_ends(const wind_edge *e, double p0[3], double p1[3]) {
    double l = 0.0;
    wind_key_pos(e->key, p0);
    wind_key_pos(e->key + 3, p1);
    for (int c = 0; c < 3; c++) l += (p1[c] - p0[c]) * (p1[c] - p0[c]);
    return sqrt(l);
}
static uint64_t wind_cell_key(int64_t x, int64_t y, int64_t z) { /* 21 bits each, wrapped */
    return ((uint64_t)x & 0x1FFFFFu) | ((uint64_t)y & 0x1FFFFFu) << 21 | ((uint64_t)z & 0x1FFFFFu) << 42;
}
/* whether edges a and b run along each other (see above) and b covers a's midpoint */
static bool wind_along(const double a0[3], const double a1[3], const double b0[3], const double b1[3]) {
    double da[3], db[3], la = 0.0, lb = 0.0, mag = 0.0;
    for (int c = 0; c < 3; c++) {
        da[c] = a1[c] - a0[c], db[c] = b1[c] - b0[c];
        la += da[c] * da[c], lb += db[c] * db[c];
        mag = fmax(mag, fmax(fmax(fabs(a0[c]), fabs(a1[c])), fmax(fabs(b0[c]), fabs(b1[c]))));
    }
    la = sqrt(la), lb = sqrt(lb);
    const bool a_short = la <= lb;
    const double *s0 = a_short ? a0 : b0, *s1 = a_short ? a1 : b1, *l0 = a_short ? b0 : a0, *dl = a_short ? db : da;
    const double ll = a_short ? lb : la, tol = WIND_TJ_TOL * (mag + ll);
    for (int k = 0; k < 2; k++) { /* the shorter edge's corners against the longer's line */
        const double *p = k ? s1 : s0;
        double r[3], t = 0.0, off = 0.0;
        for (int c = 0; c < 3; c++) r[c] = p[c] - l0[c], t += r[c] * dl[c];
        t /= ll * ll;
        for (int c = 0; c < 3; c++) off += (r[c] - t * dl[c]) * (r[c] - t * dl[c]);
        if (off > tol * tol) return false;
    }
    double t = 0.0; /* a's midpoint along b */
    for (int c = 0; c < 3; c++) t += (0.5 * (a0[c] + a1[c]) - b0[c]) * db[c];
    t /= lb * lb;
    return t > 0.0 && t < 1.0;
}
static uint32_t wind_tjunctions(const wind_edge *e, const uint8_t *boundary, size_t m, uint32_t (**pairs)[3]) {
    *pairs = NULL;
    size_t nb = 0;
    double mean = 0.0;
    for (size_t i = 0; i < m; i++) {
        if (!boundary[i]) continue;
        double p0[3], p1[3];
        mean += wind_edge_ends(&e[i], p0, p1);
        nb++;
    }
    if (nb < 2) return 0;
    double h = mean / (double)nb; /* the cell: doubled until the entries fit */
    size_t entries = 0;
    for (;;) {
        entries = 0;
        for (size_t i = 0; i < m; i++) {
            if (!boundary[i]) continue;
            double p0[3], p1[3];
            entries += (size_t)ceil(2.0 * wind_edge_ends(&e[i], p0, p1) / h) + 1;
        }
        if (entries <= WIND_TJ_MAX_ENTRIES && entries <= 64 * nb + 4096) break;
        h *= 2.0;
    }
    wind_cell *cells = malloc(entries * sizeof *cells);
    uint32_t(*out)[3] = malloc(nb * sizeof *out); /* at most one pair per edge */
    if (!cells || !out) {
        free(cells);
        free(out);
        return UINT32_MAX;
    }
    size_t k = 0;
    for (size_t i = 0; i < m; i++) {
        if (!boundary[i]) continue;
        double p0[3], p1[3];
        const size_t steps = (size_t)ceil(2.0 * wind_edge_ends(&e[i], p0, p1) / h);
        for (size_t q = 0; q <= steps && k < entries; q++) {
            const double t = steps ? (double)q / (double)steps : 0.0;
            cells[k].cell = wind_cell_key((int64_t)floor((p0[0] + t * (p1[0] - p0[0])) / h),
                                          (int64_t)floor((p0[1] + t * (p1[1] - p0[1])) / h),
                                          (int64_t)floor((p0[2] + t * (p1[2] - p0[2])) / h));
            cells[k++].edge = (uint32_t)i;
        }
    }
    qsort(cells, k, sizeof *cells, wind_cell_cmp);
    uint32_t count = 0;
    for (size_t i = 0; i < m; i++) {
        if (!boundary[i]) continue;
        double a0[3], a1[3], mid[3];
        wind_edge_ends(&e[i], a0, a1);
        for (int c = 0; c < 3; c++) mid[c] = 0.5 * (a0[c] + a1[c]);
        const int64_t cx = (int64_t)floor(mid[0] / h), cy = (int64_t)floor(mid[1] / h), cz = (int64_t)floor(mid[2] / h);
        uint32_t found = 0, partner = UINT32_MAX;
        for (int dz = -1; dz <= 1 && found < 2; dz++)
            for (int dy = -1; dy <= 1 && found < 2; dy++)
                for (int dx = -1; dx <= 1 && found < 2; dx++) {
                    const uint64_t key = wind_cell_key(cx + dx, cy + dy, cz + dz);
                    size_t lo = 0, hi = k; /* the first entry of the cell */
                    while (lo < hi) {
                        const size_t mi = (lo + hi) / 2;
                        if (cells[mi].cell < key) lo = mi + 1;
                        else hi = mi;
                    }
                    for (size_t q = lo; q < k && cells[q].cell == key && found < 2; q++) {
                        const uint32_t b = cells[q].edge;
                        if (b == i || b == partner || e[b].material != e[i].material || e[b].tri == e[i].tri) continue;
                        double b0[3], b1[3];
                        wind_edge_ends(&e[b], b0, b1);
                        if (!wind_along(a0, a1, b0, b1)) continue;
                        found++;
                        partner = b;
                    }
                }
        if (found != 1) continue;
        /* the wound directions along the line: key[0..2] -> key[3..5] when forward */
        double da[3], db[3], b0[3], b1[3], dot = 0.0;
        wind_edge_ends(&e[partner], b0, b1);
        for (int c = 0; c < 3; c++) {
            da[c] = (a1[c] - a0[c]) * (e[i].forward ? 1.0 : -1.0);
            db[c] = (b1[c] - b0[c]) * (e[partner].forward ? 1.0 : -1.0);
            dot += da[c] * db[c];
        }
        out[count][0] = e[i].tri;
        out[count][1] = e[partner].tri;
        out[count][2] = dot > 0.0; /* both run the same way along the overlap: one must turn */
        count++;
    }
    free(cells);
    *pairs = out;
    return count;
}

/* Returns the number of triangles turned, or UINT32_MAX when out of memory. s->nrm must be NULL. */
static uint32_t orient_consistently(glow__scene *s) {
    const uint32_t n = s->tri_count;
    if (n < 2) return 0;
    wind_edge *e = malloc((size_t)n * 3 * sizeof *e);
    uint32_t *adj_first = calloc((size_t)n + 1, sizeof *adj_first), *adj = NULL, *queue = malloc((size_t)n * sizeof *queue);
    uint8_t *adj_flip = NULL, *state = calloc(n, 1); /* 0 unseen; else 1 + relative flip */
    double *area = malloc((size_t)n * sizeof *area);
    uint8_t *boundary = NULL;
    uint32_t(*tj_pairs)[3] = NULL;
    uint32_t turned = UINT32_MAX;
    if (!e || !adj_first || !queue || !state || !area) goto out;
    size_t m = 0;
    for (uint32_t t = 0; t < n; t++) {
        double nn[3];
        area[t] = 0.5 * tri_area2(s->pos[3 * (size_t)t], s->pos[3 * (size_t)t + 1], s->pos[3 * (size_t)t + 2], nn);
        const glow__material *mt = &s->materials[s->tri_material[t]];
        if (mt->emission[0] > 0.0f || mt->emission[1] > 0.0f || mt->emission[2] > 0.0f) continue;
        for (int i = 0; i < 3; i++) {
            uint32_t a[3], b[3];
            memcpy(a, s->pos[3 * (size_t)t + i], sizeof a);
            memcpy(b, s->pos[3 * (size_t)t + (i + 1) % 3], sizeof b);
            const bool fwd = memcmp(a, b, sizeof a) < 0;
            wind_edge *w = &e[m++];
            memcpy(w->key, fwd ? a : b, sizeof a);
            memcpy(w->key + 3, fwd ? b : a, sizeof a);
            w->material = s->tri_material[t];
            w->tri = t;
            w->forward = fwd;
        }
    }
    qsort(e, m, sizeof *e, wind_edge_cmp);
    /* manifold edges: exactly two entries with the same key and material; boundary edges: one */
    boundary = calloc(m ? m : 1, 1);
    if (!boundary) goto out;
    size_t pairs = 0;
    for (size_t i = 0; i < m;) {
        size_t j = i + 1;
        while (j < m && e[j].material == e[i].material && !memcmp(e[j].key, e[i].key, sizeof e[i].key)) j++;
        if (j - i == 2 && e[i].tri != e[i + 1].tri) {
            adj_first[e[i].tri]++;
            adj_first[e[i + 1].tri]++;
            pairs++;
        }
        boundary[i] = j - i == 1;
        i = j;
    }
    const uint32_t tj = wind_tjunctions(e, boundary, m, &tj_pairs);
    if (tj == UINT32_MAX) goto out;
    for (uint32_t k = 0; k < tj; k++) {
        adj_first[tj_pairs[k][0]]++;
        adj_first[tj_pairs[k][1]]++;
    }
    pairs += tj;
    adj = malloc((2 * pairs + 1) * sizeof *adj);
    adj_flip = malloc(2 * pairs + 1);
    if (!adj || !adj_flip) goto out;
    for (uint32_t t = 0, acc = 0; t <= n; t++) { /* counts -> exclusive prefix sums (fill positions) */
        const uint32_t c = t < n ? adj_first[t] : 0;
        adj_first[t] = acc;
        acc += c;
    }
    for (size_t i = 0; i + 1 < m;) {
        size_t j = i + 1;
        while (j < m && e[j].material == e[i].material && !memcmp(e[j].key, e[i].key, sizeof e[i].key)) j++;
        if (j - i == 2 && e[i].tri != e[i + 1].tri) {
            /* consistent neighbours run the shared edge in opposite directions: the same direction means
             * one of the two must turn */
            const uint8_t same = e[i].forward == e[i + 1].forward;
            const uint32_t a = e[i].tri, b = e[i + 1].tri;
            adj[adj_first[a]] = b;
            adj_flip[adj_first[a]++] = same;
            adj[adj_first[b]] = a;
            adj_flip[adj_first[b]++] = same;
        }
        i = j;
    }
    for (uint32_t k = 0; k < tj; k++) {
        const uint32_t a = tj_pairs[k][0], b = tj_pairs[k][1];
        adj[adj_first[a]] = b;
        adj_flip[adj_first[a]++] = (uint8_t)tj_pairs[k][2];
        adj[adj_first[b]] = a;
        adj_flip[adj_first[b]++] = (uint8_t)tj_pairs[k][2];
    }
    for (uint32_t t = n; t > 0; t--) adj_first[t] = adj_first[t - 1]; /* back to starts */
    adj_first[0] = 0;
    turned = 0;
    for (uint32_t seed = 0; seed < n; seed++) {
        if (state[seed]) continue;
        uint32_t head = 0, tail = 0;
        double keep = 0.0, flip = 0.0;
        state[seed] = 1;
        queue[tail++] = seed;
        while (head < tail) {
            const uint32_t t = queue[head++];
            if (state[t] == 2) flip += area[t];
            else keep += area[t];
            for (uint32_t k = adj_first[t]; k < adj_first[t + 1]; k++) {
                const uint32_t u = adj[k];
                if (state[u]) continue; /* a patch that cannot be oriented (a Moebius strip) keeps its first choice */
                state[u] = (uint8_t)(1 + ((state[t] - 1) ^ adj_flip[k]));
                queue[tail++] = u;
            }
        }
        /* the patch's larger area keeps the file's winding; a patch whose two orientations cover
         * similar areas (within 1.5x: a quad of two triangles, one of them turned) has no clear
         * majority and stays as the file has it */
        const uint8_t turn = flip > WIND_MAJORITY * keep ? 1 : keep > WIND_MAJORITY * flip ? 2 : 0;
        for (uint32_t q = 0; turn && q < tail; q++)
            if (state[queue[q]] == turn) {
                flip_triangle(s, queue[q]);
                turned++;
            }
    }
out:
    free(e);
    free(boundary);
    free(tj_pairs);
    free(adj_first);
    free(adj);
    free(adj_flip);
    free(queue);
    free(state);
    free(area);
    return turned;
}

glow_result glow__scene_finalize(glow__scene *s, glow__log *log) {
    if (!s) return GLOW_ERROR_INVALID_ARGUMENT;
    if (!s->source[0]) snprintf(s->source, sizeof s->source, "%s", "scene");
    if (s->tri_count && (!s->pos || !s->tri_material)) {
        glow__errorf(log, "%s: scene has triangles but no positions or materials", s->source);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (s->tri_count > UINT32_MAX / 3) {
        glow__errorf(log, "%s: too many triangles (%u)", s->source, s->tri_count);
        return GLOW_ERROR_UNSUPPORTED;
    }
    for (uint32_t t = 0; t < s->tri_count; t++) {
        if (s->tri_material[t] >= s->material_count) {
            glow__errorf(log, "%s: triangle %u uses material %u of %u", s->source, t, s->tri_material[t],
                         s->material_count);
            return GLOW_ERROR_CORRUPT_DATA;
        }
    }
    if (!s->tri_source && s->tri_count) {
        s->tri_source = malloc((size_t)s->tri_count * sizeof *s->tri_source);
        if (!s->tri_source) goto oom;
        for (uint32_t t = 0; t < s->tri_count; t++) s->tri_source[t] = t;
    }
    if (!s->source_tri_count) s->source_tri_count = s->tri_count;
    finalize_materials(s, log);

    const uint32_t n = s->tri_count;
    uint8_t *drop = calloc(n ? n : 1, 1); /* 0 keep, 1 non-finite, 2 degenerate, 3 duplicate */
    if (!drop) goto oom;

    /* A triangle is degenerate when it is so relative to its own size, never because it is small in
     * scene units: the held-out office (modelled in ~3 mm units) lost 68,617 of its 331,179 triangles
     * to the old test (area below 1e-12 of the squared scene diagonal). Reasons, counted apart:
     * repeated corners (two corners the same point), and collinear corners (height below 2^-20 of the
     * longest edge, where float corners no longer define a plane). The area is computed in double
     * from the float corners, so the test itself is exact to ~1e-16 of the edge lengths. */
    uint32_t first_nonfinite = 0;
    for (uint32_t t = 0; t < n; t++) {
        const float (*p)[3] = s->pos + 3 * (size_t)t;
        if (!finite3(p[0]) || !finite3(p[1]) || !finite3(p[2])) {
            if (!s->skipped_nonfinite++) first_nonfinite = s->tri_source[t];
            drop[t] = 1;
        }
    }
    for (uint32_t t = 0; t < n; t++) {
        if (drop[t]) continue;
        const float (*p)[3] = s->pos + 3 * (size_t)t;
        double lmax2 = 0.0;
        bool repeated = false;
        for (int i = 0; i < 3; i++) {
            const float *a = p[i], *b = p[(i + 1) % 3];
            double d2 = 0.0;
            for (int k = 0; k < 3; k++) d2 += ((double)b[k] - a[k]) * ((double)b[k] - a[k]);
            repeated |= d2 == 0.0;
            lmax2 = d2 > lmax2 ? d2 : lmax2;
        }
        double nn[3];
        const double area2 = tri_area2(p[0], p[1], p[2], nn); /* twice the area = longest edge x height */
        if (repeated) {
            drop[t] = 2;
            s->skipped_repeated++;
        } else if (!(area2 > 0x1p-20 * lmax2)) {
            drop[t] = 2;
            s->skipped_collinear++;
        }
    }
    s->skipped_degenerate = s->skipped_repeated + s->skipped_collinear;

    /* coincident duplicates: open-addressing hash over the sorted corner bit patterns; the
     * first triangle in order is kept, so the result does not depend on anything but the input */
    {
        uint32_t cap = 16;
        while (cap < 2u * n && cap < 0x80000000u) cap <<= 1;
        uint32_t *table = malloc((size_t)cap * sizeof *table);
        face_key *keys = malloc((size_t)(n ? n : 1) * sizeof *keys);
        uint8_t *parity = malloc(n ? n : 1);
        if (!table || !keys || !parity) {
            free(table);
            free(keys);
            free(parity);
            free(drop);
            goto oom;
        }
        memset(table, 0xFF, (size_t)cap * sizeof *table);
        uint32_t opposite = 0, first_dup = 0;
        for (uint32_t t = 0; t < n; t++) {
            if (drop[t]) continue;
            parity[t] = (uint8_t)make_key((const float (*)[3])(s->pos + 3 * (size_t)t), &keys[t]);
            uint32_t slot = (uint32_t)key_hash(&keys[t]) & (cap - 1);
            for (;;) {
                uint32_t o = table[slot];
                if (o == UINT32_MAX) {
                    table[slot] = t;
                    break;
                }
                if (memcmp(&keys[o], &keys[t], sizeof keys[t]) == 0) {
                    drop[t] = 3;
                    if (!s->skipped_duplicate++) first_dup = s->tri_source[t];
                    if (parity[o] != parity[t]) opposite++;
                    break;
                }
                slot = (slot + 1) & (cap - 1);
            }
        }
        free(table);
        free(keys);
        free(parity);
        if (s->skipped_duplicate && opposite)
            glow__warnf(log,
                        "%s: %u coincident duplicate triangles skipped (first: triangle %u; %u of them with opposite "
                        "winding, so those surfaces are kept one-sided)",
                        s->source, s->skipped_duplicate, first_dup, opposite);
        else if (s->skipped_duplicate)
            glow__warnf(log, "%s: %u coincident duplicate triangles skipped (first: triangle %u)", s->source,
                        s->skipped_duplicate, first_dup);
    }
    if (s->skipped_nonfinite)
        glow__warnf(log, "%s: %u triangles with a non-finite (NaN/Inf) vertex skipped (first: triangle %u)", s->source,
                    s->skipped_nonfinite, first_nonfinite);
    if (s->skipped_degenerate)
        glow__warnf(log, "%s: %u degenerate triangles skipped (%u with repeated corners, %u with collinear corners)",
                    s->source, s->skipped_degenerate, s->skipped_repeated, s->skipped_collinear);

    /* compact every per-triangle and per-corner array in place */
    uint32_t kept = 0;
    for (uint32_t t = 0; t < n; t++) {
        if (drop[t]) continue;
        if (kept != t) {
            memcpy(s->pos[3 * (size_t)kept], s->pos[3 * (size_t)t], sizeof(float[3][3]));
            if (s->nrm) memcpy(s->nrm[3 * (size_t)kept], s->nrm[3 * (size_t)t], sizeof(float[3][3]));
            if (s->uv0) memcpy(s->uv0[3 * (size_t)kept], s->uv0[3 * (size_t)t], sizeof(float[3][2]));
            if (s->uv1) memcpy(s->uv1[3 * (size_t)kept], s->uv1[3 * (size_t)t], sizeof(float[3][2]));
            s->tri_material[kept] = s->tri_material[t];
            s->tri_source[kept] = s->tri_source[t];
        }
        kept++;
    }
    free(drop);
    s->tri_count = kept;
    if (kept == 0) {
        glow__errorf(log,
                     "%s: no usable triangles (%u in the file; %u degenerate, %u non-finite, %u duplicate skipped)",
                     s->source, s->source_tri_count, s->skipped_degenerate, s->skipped_nonfinite,
                     s->skipped_duplicate);
        return GLOW_ERROR_EMPTY_SCENE;
    }

    /* winding: consistent across shared edges where no normals say which side is the front */
    if (!s->nrm) {
        const uint32_t turned = orient_consistently(s);
        if (turned == UINT32_MAX) goto oom;
        s->turned_triangles = turned;
        if (turned)
            glow__warnf(log,
                        "%s: %u triangles turned to agree with the winding of their neighbours (inconsistent winding; "
                        "each surface keeps the orientation of most of its area)",
                        s->source, turned);
    }

    /* normals: flat geometric ones when absent; given ones normalised, bad ones replaced */
    if (!s->nrm) {
        s->nrm = malloc((size_t)kept * 3 * sizeof *s->nrm);
        if (!s->nrm) goto oom;
        for (uint32_t t = 0; t < kept; t++) {
            float g[3];
            geometric_normal((const float (*)[3])(s->pos + 3 * (size_t)t), g);
            for (int i = 0; i < 3; i++) memcpy(s->nrm[3 * (size_t)t + i], g, sizeof g);
        }
        s->normals_generated = true;
    } else {
        uint32_t bad = 0, first_bad = 0;
        for (uint32_t t = 0; t < kept; t++) {
            for (int i = 0; i < 3; i++) {
                float *v = s->nrm[3 * (size_t)t + i];
                double len = finite3(v) ? sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]) : 0.0;
                if (len > 1e-20 && isfinite(len)) {
                    for (int k = 0; k < 3; k++) v[k] = (float)(v[k] / len);
                } else {
                    if (!bad++) first_bad = s->tri_source[t];
                    geometric_normal((const float (*)[3])(s->pos + 3 * (size_t)t), v);
                }
            }
        }
        if (bad)
            glow__warnf(log, "%s: %u zero or non-finite vertex normals replaced by the face normal (first: triangle %u)",
                        s->source, bad, first_bad);
        /* winding: where the file gives normals they say which side is the front (Glow's surfels and
         * texels sit on the wound front; orient_consistently above): a triangle wound against its own
         * corners' normals turns (emissive materials keep the file's winding: it says which side emits) */
        uint32_t turned = 0;
        for (uint32_t t = 0; t < kept; t++) {
            const glow__material *mt = &s->materials[s->tri_material[t]];
            if (mt->emission[0] > 0.0f || mt->emission[1] > 0.0f || mt->emission[2] > 0.0f) continue;
            float g[3];
            geometric_normal((const float (*)[3])(s->pos + 3 * (size_t)t), g);
            double d = 0.0;
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++) d += (double)g[k] * s->nrm[3 * (size_t)t + i][k];
            if (d < 0.0) {
                flip_triangle(s, t);
                turned++;
            }
        }
        s->turned_triangles = turned;
        if (turned)
            glow__warnf(log, "%s: %u triangles turned to face along their vertex normals (wound against them)", s->source,
                        turned);
    }

    /* UVs: non-finite -> 0 */
    float (*uvs[2])[2] = {s->uv0, s->uv1};
    for (int set = 0; set < 2; set++) {
        if (!uvs[set]) continue;
        uint32_t bad = 0;
        for (size_t c = 0; c < (size_t)kept * 3; c++)
            for (int k = 0; k < 2; k++)
                if (!isfinite(uvs[set][c][k])) {
                    uvs[set][c][k] = 0.0f;
                    bad++;
                }
        if (bad) glow__warnf(log, "%s: %u non-finite UV%d coordinates replaced by 0", s->source, bad, set);
    }

    /* bounds and area of what is kept */
    double area = 0.0;
    for (int k = 0; k < 3; k++) {
        s->bounds_min[k] = INFINITY;
        s->bounds_max[k] = -INFINITY;
    }
    for (uint32_t t = 0; t < kept; t++) {
        const float (*p)[3] = s->pos + 3 * (size_t)t;
        double nn[3];
        area += 0.5 * tri_area2(p[0], p[1], p[2], nn);
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++) {
                if (p[i][k] < s->bounds_min[k]) s->bounds_min[k] = p[i][k];
                if (p[i][k] > s->bounds_max[k]) s->bounds_max[k] = p[i][k];
            }
    }
    s->area = area;
    return GLOW_OK;

oom:
    glow__errorf(log, "%s: out of memory while cleaning the scene", s->source);
    return GLOW_ERROR_OUT_OF_MEMORY;
}

/* ================================================================== assimp import */

typedef struct tex_slot {
    char key[4200]; /* resolved path, or "*N" for embedded textures */
} tex_slot;

typedef struct import_ctx {
    const char *path;
    char dir[4096];
    const struct aiScene *ai;
    glow__scene *s;
    glow__log *log;
    tex_slot *slots;        /* parallel to s->textures */
    char (*missing)[512];   /* distinct texture names that failed */
    uint32_t missing_count, missing_cap;
} import_ctx;

static bool note_missing(import_ctx *c, const char *name) {
    for (uint32_t i = 0; i < c->missing_count; i++)
        if (strcmp(c->missing[i], name) == 0) return false; /* already reported */
    c->s->textures_missing++;
    if (c->missing_count == c->missing_cap) {
        uint32_t cap = c->missing_cap ? 2 * c->missing_cap : 8;
        void *p = realloc(c->missing, (size_t)cap * sizeof *c->missing);
        if (!p) return true; /* cannot remember it: at worst it is reported twice */
        c->missing = p;
        c->missing_cap = cap;
    }
    copy_str(c->missing[c->missing_count++], sizeof *c->missing, name);
    return true;
}

/* Returns the texture index, -1 when it could not be loaded (reported, counted), or -2 when out
 * of memory. */
static int load_texture(import_ctx *c, const char *name, const char *material) {
    glow__scene *s = c->s;
    char key[4200], why[256] = "";
    const struct aiTexture *embedded = NULL;
    char resolved[4096];
    if (name[0] == '*') { /* embedded: "*N" indexes aiScene::mTextures */
        char *end = NULL;
        unsigned long idx = strtoul(name + 1, &end, 10);
        if (end && *end == 0 && end != name + 1 && idx < c->ai->mNumTextures) embedded = c->ai->mTextures[idx];
        copy_str(key, sizeof key, name);
    } else {
        for (unsigned i = 0; i < c->ai->mNumTextures; i++) /* some formats embed by file name */
            if (c->ai->mTextures[i] && c->ai->mTextures[i]->mFilename.length == strlen(name) &&
                strncmp(c->ai->mTextures[i]->mFilename.data, name, sizeof c->ai->mTextures[i]->mFilename.data) == 0) {
                embedded = c->ai->mTextures[i];
                break;
            }
        if (embedded) {
            key[0] = '*';
            copy_str(key + 1, sizeof key - 1, name);
        } else if (glow__texture_resolve(c->dir, name, resolved, sizeof resolved)) {
            copy_str(key, sizeof key, resolved);
        } else {
            if (note_missing(c, name))
                glow__warnf(c->log, "%s: texture '%s' (material '%s') not found; using the material colour", c->path,
                            name, material);
            return -1;
        }
    }
    for (uint32_t i = 0; i < s->texture_count; i++)
        if (strcmp(c->slots[i].key, key) == 0) return (int)i;

    glow__texture tex;
    glow_result r;
    if (name[0] == '*' && !embedded) {
        r = GLOW_ERROR_CORRUPT_DATA;
        snprintf(why, sizeof why, "no such embedded texture (the file has %u)", c->ai->mNumTextures);
        memset(&tex, 0, sizeof tex);
    } else if (embedded && embedded->mHeight == 0) {
        r = glow__texture_load_memory(embedded->pcData, embedded->mWidth, key, &tex, why, sizeof why);
    } else if (embedded) {
        if ((size_t)embedded->mWidth * embedded->mHeight > ((size_t)1 << 26)) {
            r = GLOW_ERROR_UNSUPPORTED;
            snprintf(why, sizeof why, "embedded image too large");
            memset(&tex, 0, sizeof tex);
        } else {
            /* aiTexel is b, g, r, a */
            r = glow__texture_from_srgb8((const uint8_t *)embedded->pcData, (int)embedded->mWidth,
                                         (int)embedded->mHeight, 4, 2, 1, 0, key, &tex, why, sizeof why);
        }
    } else {
        r = glow__texture_load_file(resolved, &tex, why, sizeof why);
    }
    if (r == GLOW_ERROR_OUT_OF_MEMORY) return -2;
    if (r != GLOW_OK) {
        if (note_missing(c, name))
            glow__warnf(c->log, "%s: texture '%s' (material '%s'): %s; using the material colour", c->path, name,
                        material, why);
        return -1;
    }
    void *nt = realloc(s->textures, ((size_t)s->texture_count + 1) * sizeof *s->textures);
    if (!nt) {
        glow__texture_free(&tex);
        return -2;
    }
    s->textures = nt;
    void *ns = realloc(c->slots, ((size_t)s->texture_count + 1) * sizeof *c->slots);
    if (!ns) {
        glow__texture_free(&tex);
        return -2;
    }
    c->slots = ns;
    copy_str(c->slots[s->texture_count].key, sizeof c->slots[s->texture_count].key, key);
    s->textures[s->texture_count] = tex;
    return (int)s->texture_count++;
}

/* The first texture of slot `type` of material am: load_texture's index (-1: named but not loaded,
 * -2: out of memory), or -3 when the slot names none. File names keep their bytes (UTF-8 names must
 * still resolve); they are only bounded. */
static int slot_texture(import_ctx *c, const struct aiMaterial *am, enum aiTextureType type, const char *material) {
    struct aiString tpath;
    if (type == aiTextureType_NONE ||
        aiGetMaterialTexture(am, type, 0, &tpath, NULL, NULL, NULL, NULL, NULL, NULL) != aiReturn_SUCCESS || !tpath.length)
        return -3;
    char tname[sizeof tpath.data];
    size_t tl = tpath.length < sizeof tname - 1 ? tpath.length : sizeof tname - 1;
    memcpy(tname, tpath.data, tl);
    tname[tl] = 0;
    return load_texture(c, tname, material);
}

static glow_result import_materials(import_ctx *c) {
    glow__scene *s = c->s;
    const struct aiScene *ai = c->ai;
    uint32_t count = ai->mNumMaterials ? ai->mNumMaterials : 1;
    s->materials = calloc(count, sizeof *s->materials);
    if (!s->materials) return GLOW_ERROR_OUT_OF_MEMORY;
    s->material_count = count;
    for (uint32_t i = 0; i < count; i++) {
        glow__material *m = &s->materials[i];
        m->texture = -1;
        m->emission_texture = -1;
        m->albedo[0] = m->albedo[1] = m->albedo[2] = 0.5f;
        snprintf(m->name, sizeof m->name, "material%u", i);
        if (!ai->mNumMaterials) {
            snprintf(m->name, sizeof m->name, "%s", "default");
            continue;
        }
        const struct aiMaterial *am = ai->mMaterials[i];
        if (!am) continue;
        struct aiString name;
        if (aiGetMaterialString(am, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && name.length)
            copy_aistring(m->name, sizeof m->name, &name);
        struct aiColor4D col;
        /* glTF's baseColorFactor when present (assimp also mirrors it as the diffuse colour),
         * else OBJ's Kd / the format's diffuse colour */
        bool pbr = aiGetMaterialColor(am, AI_MATKEY_BASE_COLOR, &col) == aiReturn_SUCCESS;
        if (pbr || aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &col) == aiReturn_SUCCESS) {
            m->albedo[0] = col.r;
            m->albedo[1] = col.g;
            m->albedo[2] = col.b;
        }
        if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &col) == aiReturn_SUCCESS) {
            float intensity = 1.0f;
            unsigned int one = 1;
            if (aiGetMaterialFloatArray(am, AI_MATKEY_EMISSIVE_INTENSITY, &intensity, &one) != aiReturn_SUCCESS)
                intensity = 1.0f;
            m->emission[0] = col.r * intensity;
            m->emission[1] = col.g * intensity;
            m->emission[2] = col.b * intensity;
        }
        enum aiTextureType type = aiTextureType_NONE;
        if (aiGetMaterialTextureCount(am, aiTextureType_BASE_COLOR) > 0) type = aiTextureType_BASE_COLOR;
        else if (aiGetMaterialTextureCount(am, aiTextureType_DIFFUSE) > 0) type = aiTextureType_DIFFUSE;
        int t = slot_texture(c, am, type, m->name);
        if (t == -2) return GLOW_ERROR_OUT_OF_MEMORY;
        if (t != -3) {
            m->texture = t;
            /* Albedo = factor x texture. glTF defines the factor as a multiplier. For OBJ/MTL we
             * use the texture alone (factor 1, kept just below 1 by ALBEDO_MAX) and ignore Kd
             * when map_Kd loads: exporters such as 3ds Max (Sponza's) and Blender write the
             * colour swatch that the map replaces, and Sponza's Kd (0.53..1.0, roughly each
             * map's own tint) times its maps (linear means 0.27..0.73) would darken and
             * double-tint every surface to 0.2..0.5. Kd remains the fallback when the map
             * is missing or undecodable. */
            if (t >= 0 && !pbr) m->albedo[0] = m->albedo[1] = m->albedo[2] = ALBEDO_MAX;
        }
        /* Emission texture (MTL map_Ke, glTF emissiveTexture): emission = factor x texture. glTF's factor
         * is the multiplier it defines (0 keeps it dark); OBJ exporters leave Ke black beside map_Ke, so
         * for OBJ a black or absent Ke means the texture alone. */
        t = aiGetMaterialTextureCount(am, aiTextureType_EMISSIVE) > 0 ? slot_texture(c, am, aiTextureType_EMISSIVE, m->name)
                                                                       : -3;
        if (t == -2) return GLOW_ERROR_OUT_OF_MEMORY;
        if (t != -3) {
            m->emission_texture = t;
            if (t >= 0 && !pbr && !(m->emission[0] > 0.0f || m->emission[1] > 0.0f || m->emission[2] > 0.0f))
                m->emission[0] = m->emission[1] = m->emission[2] = 1.0f;
        }
    }
    return GLOW_OK;
}

/* Each mesh's object: the name of the first node (depth first, in the file's order) that holds it, else
 * the mesh's own name; objects of the same name are one. mesh_object[m] = its index in s->object_name. */
static void name_node_meshes(const struct aiNode *nd, const struct aiScene *ai, const char **mesh_name, unsigned depth) {
    if (!nd || depth > 256) return;
    for (unsigned i = 0; i < nd->mNumMeshes; i++) {
        const unsigned m = nd->mMeshes[i];
        if (m < ai->mNumMeshes && !mesh_name[m] && nd->mName.length) mesh_name[m] = nd->mName.data;
    }
    for (unsigned i = 0; i < nd->mNumChildren; i++) name_node_meshes(nd->mChildren[i], ai, mesh_name, depth + 1);
}

static glow_result import_objects(import_ctx *c, uint32_t **out_mesh_object) {
    const struct aiScene *ai = c->ai;
    glow__scene *s = c->s;
    const char **mesh_name = calloc(ai->mNumMeshes + 1u, sizeof *mesh_name);
    uint32_t *mo = malloc((ai->mNumMeshes + 1u) * sizeof *mo);
    s->object_name = malloc((ai->mNumMeshes + 1u) * sizeof *s->object_name);
    if (!mesh_name || !mo || !s->object_name) {
        free(mesh_name);
        free(mo);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    name_node_meshes(ai->mRootNode, ai, mesh_name, 0);
    s->object_count = 0;
    for (unsigned m = 0; m < ai->mNumMeshes; m++) {
        const struct aiMesh *me = ai->mMeshes[m];
        char name[64];
        snprintf(name, sizeof name, "%.63s", mesh_name[m] ? mesh_name[m] : (me && me->mName.length ? me->mName.data : ""));
        uint32_t k = 0;
        while (k < s->object_count && strcmp(s->object_name[k], name) != 0) k++;
        if (k == s->object_count) memcpy(s->object_name[s->object_count++], name, sizeof name);
        mo[m] = k;
    }
    free(mesh_name);
    *out_mesh_object = mo;
    return GLOW_OK;
}

static glow_result import_meshes(import_ctx *c) {
    glow__scene *s = c->s;
    const struct aiScene *ai = c->ai;
    uint64_t total = 0;
    uint32_t meshes_with_tris = 0, with_uv0 = 0, with_uv1 = 0, with_nrm = 0;
    for (unsigned m = 0; m < ai->mNumMeshes; m++) {
        const struct aiMesh *me = ai->mMeshes[m];
        if (!me || !me->mVertices) continue;
        uint32_t tris = 0;
        for (unsigned f = 0; f < me->mNumFaces; f++)
            if (me->mFaces[f].mNumIndices == 3) tris++;
        if (!tris) continue;
        total += tris;
        meshes_with_tris++;
        if (me->mTextureCoords[0]) with_uv0++;
        if (me->mTextureCoords[1]) with_uv1++;
        if (me->mNormals) with_nrm++;
    }
    if (total == 0) return GLOW_OK; /* finalize reports the empty scene */
    if (total > UINT32_MAX / 3) {
        glow__errorf(c->log, "%s: too many triangles (%llu)", c->path, (unsigned long long)total);
        return GLOW_ERROR_UNSUPPORTED;
    }
    const size_t n = (size_t)total;
    bool has_uv1 = with_uv1 == meshes_with_tris;
    if (with_uv1 && !has_uv1)
        glow__warnf(c->log,
                    "%s: only %u of %u meshes have a second UV set; ignoring it (lightmap UVs will be generated)",
                    c->path, with_uv1, meshes_with_tris);
    s->pos = malloc(n * 3 * sizeof *s->pos);
    s->tri_material = malloc(n * sizeof *s->tri_material);
    s->tri_source = malloc(n * sizeof *s->tri_source);
    s->source_object = malloc(n * sizeof *s->source_object);
    uint32_t *mesh_object = NULL;
    if (!s->source_object || import_objects(c, &mesh_object) != GLOW_OK) return GLOW_ERROR_OUT_OF_MEMORY;
    if (with_nrm) s->nrm = malloc(n * 3 * sizeof *s->nrm);
    if (with_uv0) s->uv0 = malloc(n * 3 * sizeof *s->uv0);
    if (has_uv1) s->uv1 = malloc(n * 3 * sizeof *s->uv1);
    if (!s->pos || !s->tri_material || !s->tri_source || (with_nrm && !s->nrm) || (with_uv0 && !s->uv0) ||
        (has_uv1 && !s->uv1)) {
        free(mesh_object);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }

    uint32_t t = 0, bad_index = 0, bad_material = 0;
    for (unsigned m = 0; m < ai->mNumMeshes; m++) {
        const struct aiMesh *me = ai->mMeshes[m];
        if (!me || !me->mVertices) continue;
        uint32_t mat = me->mMaterialIndex;
        if (mat >= s->material_count) {
            bad_material++;
            mat = 0;
        }
        for (unsigned f = 0; f < me->mNumFaces; f++) {
            const struct aiFace *face = &me->mFaces[f];
            if (face->mNumIndices != 3) continue;
            bool ok = face->mIndices[0] < me->mNumVertices && face->mIndices[1] < me->mNumVertices &&
                      face->mIndices[2] < me->mNumVertices;
            if (!ok) bad_index++;
            for (int i = 0; i < 3; i++) {
                size_t corner = 3 * (size_t)t + (size_t)i;
                /* an out-of-range index collapses the triangle: finalize counts it as degenerate */
                unsigned v = ok ? face->mIndices[i] : 0;
                s->pos[corner][0] = me->mVertices[v].x;
                s->pos[corner][1] = me->mVertices[v].y;
                s->pos[corner][2] = me->mVertices[v].z;
                if (s->uv0) {
                    const struct aiVector3D *uv = me->mTextureCoords[0];
                    s->uv0[corner][0] = uv ? uv[v].x : 0.0f;
                    s->uv0[corner][1] = uv ? uv[v].y : 0.0f;
                }
                if (s->uv1) {
                    s->uv1[corner][0] = me->mTextureCoords[1][v].x;
                    s->uv1[corner][1] = me->mTextureCoords[1][v].y;
                }
            }
            if (s->nrm) {
                if (me->mNormals) {
                    for (int i = 0; i < 3; i++) {
                        unsigned v = ok ? face->mIndices[i] : 0;
                        s->nrm[3 * (size_t)t + i][0] = me->mNormals[v].x;
                        s->nrm[3 * (size_t)t + i][1] = me->mNormals[v].y;
                        s->nrm[3 * (size_t)t + i][2] = me->mNormals[v].z;
                    }
                } else { /* this mesh has none while others do: its face normals */
                    float g[3];
                    geometric_normal((const float (*)[3])(s->pos + 3 * (size_t)t), g);
                    for (int i = 0; i < 3; i++) memcpy(s->nrm[3 * (size_t)t + i], g, sizeof g);
                }
            }
            s->tri_material[t] = mat;
            s->tri_source[t] = t;
            s->source_object[t] = mesh_object[m];
            t++;
        }
    }
    free(mesh_object);
    s->tri_count = t;
    s->source_tri_count = t;
    if (bad_index)
        glow__warnf(c->log, "%s: %u triangles reference vertices out of range (dropped as degenerate)", c->path,
                    bad_index);
    if (bad_material) glow__warnf(c->log, "%s: %u meshes reference a missing material", c->path, bad_material);
    return GLOW_OK;
}

/* Assimp 5.2.4 (Debian 12) dereferences NULL in its glTF 2 importer when an image's media type
 * (a data URI's, or "mimeType") is not empty and has no '/' ("data:imagepng;base64,..."): a one-bit
 * change the fuzz smoke found. Such a media type is malformed (RFC 2046 type/subtype), so glTF text
 * (.gltf, or a .glb's JSON chunk) is scanned for "uri" and "mimeType" string values first and
 * refused with a message before assimp reads it. A plain scan, not a JSON parse: the library does
 * not link cJSON, and only these two keys' string values matter. Returns false when one is bad. */
static bool gltf_media_types_ok(const char *path, const unsigned char *buf, size_t n, glow__log *log) {
    const char *keys[2] = {"\"uri\"", "\"mimeType\""};
    for (int k = 0; k < 2; ++k) {
        const size_t kl = strlen(keys[k]);
        for (size_t i = 0; i + kl <= n; ++i) {
            if (memcmp(buf + i, keys[k], kl) != 0) continue;
            size_t j = i + kl;
            while (j < n && (buf[j] == ' ' || buf[j] == '\t' || buf[j] == '\r' || buf[j] == '\n')) ++j;
            if (j >= n || buf[j] != ':') continue;
            ++j;
            while (j < n && (buf[j] == ' ' || buf[j] == '\t' || buf[j] == '\r' || buf[j] == '\n')) ++j;
            if (j >= n || buf[j] != '"') continue;
            size_t a = ++j;
            if (k == 0) {
                if (n - a < 5 || memcmp(buf + a, "data:", 5) != 0) continue;
                a += 5;
            }
            size_t b = a;
            bool slash = false;
            while (b < n && buf[b] != '"' && buf[b] != ';' && buf[b] != ',') slash |= buf[b++] == '/';
            if (b > a && !slash) {
                const int len = (int)(b - a < 40 ? b - a : 40);
                glow__errorf(log, "%s: glTF %s media type '%.*s' has no '/': malformed (type/subtype)", path,
                             k == 0 ? "data URI" : "mimeType", len, (const char *)(buf + a));
                return false;
            }
        }
    }
    return true;
}

/* The glTF text of path (all of a .gltf, the JSON chunk of a .glb), checked by gltf_media_types_ok. */
static glow_result gltf_precheck(const char *path, FILE *f, int first, glow__log *log) {
    if (first != '{' && first != 'g') return GLOW_OK;
    if (fseek(f, 0, SEEK_END) != 0) return GLOW_OK;
    const long size = ftell(f);
    if (size <= 0 || fseek(f, 0, SEEK_SET) != 0) return GLOW_OK;
    unsigned char *buf = malloc((size_t)size);
    if (!buf) {
        glow__errorf(log, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    const size_t n = fread(buf, 1, (size_t)size, f);
    bool ok = true;
    if (n >= 20 && !memcmp(buf, "glTF", 4)) {
        const uint32_t len = (uint32_t)buf[12] | (uint32_t)buf[13] << 8 | (uint32_t)buf[14] << 16 | (uint32_t)buf[15] << 24;
        const size_t json = len < n - 20 ? len : n - 20;
        ok = gltf_media_types_ok(path, buf + 20, json, log);
    } else if (buf[0] == '{') {
        ok = gltf_media_types_ok(path, buf, n, log);
    }
    free(buf);
    return ok ? GLOW_OK : GLOW_ERROR_UNSUPPORTED;
}

static glow_result load_file(const char *path, glow__log *log, glow__scene *out) {
    struct stat st;
    if (stat(path, &st) != 0) {
        if (errno == ENOENT || errno == ENOTDIR) glow__errorf(log, "%s: no such file", path);
        else glow__errorf(log, "%s: cannot access (%s)", path, strerror(errno));
        return GLOW_ERROR_IO;
    }
    if (S_ISDIR(st.st_mode)) {
        glow__errorf(log, "%s: is a directory, not a scene file", path);
        return GLOW_ERROR_IO;
    }
    if (!S_ISREG(st.st_mode)) {
        glow__errorf(log, "%s: not a regular file", path);
        return GLOW_ERROR_IO;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        glow__errorf(log, "%s: cannot open (%s)", path, strerror(errno));
        return GLOW_ERROR_IO;
    }
    int byte = fgetc(f);
    bool read_error = ferror(f) != 0;
    const glow_result pre = read_error || byte == EOF ? GLOW_OK : gltf_precheck(path, f, byte, log);
    fclose(f);
    if (pre != GLOW_OK) return pre;
    if (read_error) {
        glow__errorf(log, "%s: cannot read", path);
        return GLOW_ERROR_IO;
    }
    if (byte == EOF) {
        glow__errorf(log, "%s: file is empty (no triangles)", path);
        return GLOW_ERROR_EMPTY_SCENE;
    }

    /* Triangulate + pre-transform into world space; keep the hierarchy so meshes keep the
     * file's order (tri_source); drop point and line primitives. No JoinIdenticalVertices,
     * FindDegenerates or GenNormals: duplicates, degenerates and normals are handled (and
     * counted) deterministically by glow__scene_finalize. No GenUVCoords either: it only
     * matters for formats with procedural (spherical, box...) mappings. */
    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (!props) {
        glow__errorf(log, "%s: out of memory", path);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_PTV_KEEP_HIERARCHY, 1);
    const struct aiScene *ai = aiImportFileExWithProperties(
        path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType, NULL, props);
    aiReleasePropertyStore(props);
    if (!ai) {
        const char *err = aiGetErrorString();
        glow__errorf(log, "%s: unsupported or unreadable scene format (assimp: %s)", path,
                     err && err[0] ? err : "unknown error");
        return GLOW_ERROR_UNSUPPORTED;
    }

    import_ctx c;
    memset(&c, 0, sizeof c);
    c.path = path;
    c.ai = ai;
    c.s = out;
    c.log = log;
    const char *slash = strrchr(path, '/');
    if (slash) snprintf(c.dir, sizeof c.dir, "%.*s", (int)(slash - path) + (slash == path ? 1 : 0), path);
    else snprintf(c.dir, sizeof c.dir, "%s", ".");

    glow_result r = import_materials(&c);
    if (r == GLOW_OK) r = import_meshes(&c);
    if (r == GLOW_ERROR_OUT_OF_MEMORY) glow__errorf(log, "%s: out of memory while importing", path);
    aiReleaseImport(ai);
    free(c.slots);
    free(c.missing);
    if (r != GLOW_OK) return r;
    return glow__scene_finalize(out, log);
}

glow_result glow__scene_load(const char *path, glow__log *log, glow__scene *out) {
    if (!out) return GLOW_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!path || !path[0]) {
        glow__errorf(log, "scene path is empty");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (strncmp(path, "builtin:", 8) == 0) return glow__scene_builtin(path + 8, log, out);
    snprintf(out->source, sizeof out->source, "%s", path);
    glow_result r = load_file(path, log, out);
    if (r != GLOW_OK) {
        glow__scene_free(out);
        return r;
    }
    glow__infof(log,
                "%s: %u triangles (%u in the file: %u degenerate, %u duplicate, %u non-finite skipped), %u materials, "
                "%u textures (%u missing), normals %s, %s",
                path, out->tri_count, out->source_tri_count, out->skipped_degenerate, out->skipped_duplicate,
                out->skipped_nonfinite, out->material_count, out->texture_count, out->textures_missing,
                out->normals_generated ? "generated" : "from the file",
                out->uv1 ? "lightmap UVs from the file" : "no lightmap UVs");
    return GLOW_OK;
}
