/* surfels.c — surfel placement (PIC 4.2).
 *
 * 1. Area-proportional spawning: every surfel has the same area a = scene area / n. Triangles are
 *    walked in order with a running cumulative area C (double); triangle t spawns
 *    floor(C_end / a) - floor(C_start / a) surfels, so the area of triangles too small to spawn one
 *    accumulates until it does (PIC: "the area of too-small triangles is accumulated"). The last
 *    triangle's end is pinned to n, so the total is exactly n whatever the rounding.
 * 2. Positions: surfel i (global index) takes the 2-d Halton point (radical inverses in bases 2 and
 *    3) of index i, shifted modulo 1 by a Cranley-Patterson rotation derived from a hash of the seed,
 *    and mapped to the triangle with the square-root warp. Consecutive Halton points are stratified,
 *    so the block of points a triangle receives covers it evenly.
 * 3. Tangential relaxation: each iteration bins the current positions into a grid; every
 *    surfel is pushed away from its K nearest neighbours that face the same way (dot > 0.5) and lie
 *    closer than 2r (r = sqrt(a/pi)), the push is projected onto its tangent plane, and the move is
 *    done in barycentric space and clamped to the surfel's own triangle (closest point), so no surfel
 *    ever leaves its triangle. Jacobi update: displacements are computed from the old positions into
 *    a new array, so the result does not depend on the thread count. Relaxation never changes area.
 *
 * Per surfel: position, interpolated shading normal, albedo (material albedo x texture sampled at
 * the interpolated uv0 with a footprint of one surfel), emission, triangle, barycentrics, material.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pc_internal.h"

#define RELAX_NEIGHBOURS 6u
#define RELAX_STEP 0.4      /* fraction of the overlap (2r - d) moved per neighbour and iteration (Jacobi:
                               * stable below ~0.5 for hexagonal neighbourhoods; 0.4 spread best in tests) */
#define RELAX_MAX_MOVE 0.5  /* a surfel moves at most this many radii per iteration */

/* ------------------------------------------------------------------ helpers */
static uint32_t hash32(uint32_t x) {
    /* lowbias32 (Chris Wellons) */
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

static double radical_inverse2(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return (double)i * (1.0 / 4294967296.0);
}

static double radical_inverse3(uint32_t i) {
    double inv = 1.0 / 3.0, f = inv, r = 0.0;
    while (i > 0) {
        r += f * (double)(i % 3u);
        i /= 3u;
        f *= inv;
    }
    return r;
}

static double frac1(double x) {
    x -= floor(x);
    return x >= 1.0 ? 0.0 : x;
}

double glow__tri_area(const glow__scene *scene, uint32_t t) {
    const float *p0 = scene->pos[3 * t], *p1 = scene->pos[3 * t + 1], *p2 = scene->pos[3 * t + 2];
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)p1[k] - p0[k];
        e2[k] = (double)p2[k] - p0[k];
    }
    double c0 = e1[1] * e2[2] - e1[2] * e2[1], c1 = e1[2] * e2[0] - e1[0] * e2[2], c2 = e1[0] * e2[1] - e1[1] * e2[0];
    return 0.5 * sqrt(c0 * c0 + c1 * c1 + c2 * c2);
}

/* Fills every field of s that follows from (tri, bary): position, normal, albedo, emission, material. */

/* Texture `tex` (an index into scene->textures; < 0: none, out stays) at barycentrics (b0, b1, b2) of
 * triangle t, from the mip level of a surfel's footprint: the texture's mean over the surfel. */
static void surfel_texture(const glow__scene *scene, uint32_t t, int tex, double b0, double b1, double b2,
                           double surfel_area, float out[3]) {
    if (tex < 0 || (uint32_t)tex >= scene->texture_count || !scene->uv0) return;
    const float *u0 = scene->uv0[3 * t], *u1 = scene->uv0[3 * t + 1], *u2 = scene->uv0[3 * t + 2];
    const double u = b0 * u0[0] + b1 * u1[0] + b2 * u2[0], v = b0 * u0[1] + b1 * u1[1] + b2 * u2[1];
    const double uv_area = 0.5 * fabs(((double)u1[0] - u0[0]) * ((double)u2[1] - u0[1]) -
                                      ((double)u2[0] - u0[0]) * ((double)u1[1] - u0[1]));
    const double ta = glow__tri_area(scene, t);
    const double footprint = ta > 0.0 ? sqrt(surfel_area * uv_area / ta) : 0.0;
    glow__texture_sample(&scene->textures[tex], (float)u, (float)v, (float)footprint, out);
}

/* A surfel's position, normal and material from its triangle and barycentrics (surfel_eval less the
 * textures, which the adaptive draw's candidates do not need). */
static void surfel_geom(const glow__scene *scene, glow__surfel *s) {
    uint32_t t = s->tri;
    double b1 = s->bary[0], b2 = s->bary[1], b0 = 1.0 - b1 - b2;
    const float *p0 = scene->pos[3 * t], *p1 = scene->pos[3 * t + 1], *p2 = scene->pos[3 * t + 2];
    for (int k = 0; k < 3; ++k)
        s->pos[k] = (float)((double)p0[k] + b1 * ((double)p1[k] - p0[k]) + b2 * ((double)p2[k] - p0[k]));
    double n[3];
    const float *n0 = scene->nrm[3 * t], *n1 = scene->nrm[3 * t + 1], *n2 = scene->nrm[3 * t + 2];
    for (int k = 0; k < 3; ++k) n[k] = b0 * n0[k] + b1 * n1[k] + b2 * n2[k];
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-12)) {
        /* corner normals cancel here: fall back to the geometric normal */
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)p1[k] - p0[k];
            e2[k] = (double)p2[k] - p0[k];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len > 0.0)) { n[0] = 0.0; n[1] = 0.0; n[2] = 1.0; len = 1.0; }
    }
    for (int k = 0; k < 3; ++k) s->nrm[k] = (float)(n[k] / len);
    s->material = scene->tri_material[t];
}

static void surfel_eval(const glow__scene *scene, double surfel_area, glow__surfel *s) {
    s->area = (float)surfel_area;
    surfel_geom(scene, s);
    const uint32_t t = s->tri;
    const double b1 = s->bary[0], b2 = s->bary[1], b0 = 1.0 - b1 - b2;
    const glow__material *mat = &scene->materials[s->material];
    float tex[3] = {1.0f, 1.0f, 1.0f}, etex[3] = {1.0f, 1.0f, 1.0f};
    surfel_texture(scene, t, mat->texture, b0, b1, b2, surfel_area, tex);
    surfel_texture(scene, t, mat->emission_texture, b0, b1, b2, surfel_area, etex);
    for (int k = 0; k < 3; ++k) {
        s->albedo[k] = mat->albedo[k] * tex[k];
        s->emission[k] = mat->emission[k] * etex[k]; /* the emission texture's mean over the surfel */
    }
}

/* Closest point of triangle (a, a+e1, a+e2) to q (relative to a: d = q - a), as barycentrics
 * (v, w) of corners 1 and 2 (Ericson, Real-Time Collision Detection 5.1.5). */
static void closest_bary(const double e1[3], const double e2[3], const double d[3], double *out_v, double *out_w) {
    double d1 = e1[0] * d[0] + e1[1] * d[1] + e1[2] * d[2];
    double d2 = e2[0] * d[0] + e2[1] * d[1] + e2[2] * d[2];
    if (d1 <= 0.0 && d2 <= 0.0) { *out_v = 0.0; *out_w = 0.0; return; }
    double e11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    double e22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    double e12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
    /* vertex region B: q - b = d - e1 */
    double d3 = d1 - e11, d4 = d2 - e12;
    if (d3 >= 0.0 && d4 <= d3) { *out_v = 1.0; *out_w = 0.0; return; }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) { *out_v = d1 / (d1 - d3); *out_w = 0.0; return; }
    /* vertex region C: q - c = d - e2 */
    double d5 = d1 - e12, d6 = d2 - e22;
    if (d6 >= 0.0 && d5 <= d6) { *out_v = 0.0; *out_w = 1.0; return; }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) { *out_v = 0.0; *out_w = d2 / (d2 - d6); return; }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        *out_v = 1.0 - w;
        *out_w = w;
        return;
    }
    double denom = 1.0 / (va + vb + vc);
    *out_v = vb * denom;
    *out_w = vc * denom;
}

static void clamp_bary(double *v, double *w) {
    if (!(*v >= 0.0)) *v = 0.0;
    if (!(*w >= 0.0)) *w = 0.0;
    if (*v > 1.0) *v = 1.0;
    if (*w > 1.0) *w = 1.0;
    double s = *v + *w;
    if (s > 1.0) { *v /= s; *w /= s; }
}

/* Stores clamped barycentrics as floats, keeping v + w <= 1 after rounding. */
static void set_bary(glow__surfel *s, double v, double w) {
    float fv = (float)v, fw = (float)w;
    if (fv + fw > 1.0f) fw = 1.0f - fv;
    if (fw < 0.0f) fw = 0.0f;
    s->bary[0] = fv;
    s->bary[1] = fw;
}

/* Point i of the rotated 2-d Halton sequence on s->tri, through the square-root warp (surfels,
 * adaptive candidates and area points alike). */
static void halton_bary(glow__surfel *s, uint32_t i, const double rot[2]) {
    double u1 = frac1(radical_inverse2(i) + rot[0]);
    double u2 = frac1(radical_inverse3(i) + rot[1]);
    double su = sqrt(u1);
    double v = su * (1.0 - u2), w = su * u2;
    clamp_bary(&v, &w);
    set_bary(s, v, w);
}

/* ------------------------------------------------------------------ placement */
typedef struct place_ctx {
    const glow__scene *scene;
    const uint32_t *surfel_tri;
    glow__surfel *s;
    double area;
    double rot[2];
} place_ctx;

static void place_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    place_ctx *c = vctx;
    for (uint32_t i = begin; i < end; ++i) {
        glow__surfel *s = &c->s[i];
        memset(s, 0, sizeof *s);
        s->tri = c->surfel_tri[i];
        halton_bary(s, i, c->rot);
        surfel_eval(c->scene, c->area, s);
    }
}

/* ------------------------------------------------------------------ relaxation */
typedef struct relax_ctx {
    const glow__scene *scene;
    const glow__pointgrid *grid;
    const glow__surfel *old;
    float (*new_bary)[2];
    double radius;            /* interaction radius 2r */
    double max_move;
    const float *rad;         /* adaptive density: per-surfel radius r_i (pairs interact within
                               * r_i + r_j, a surfel moves at most RELAX_MAX_MOVE r_i); NULL: uniform */
} relax_ctx;

static void relax_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    relax_ctx *c = vctx;
    const glow__scene *scene = c->scene;
    uint32_t nb[RELAX_NEIGHBOURS];
    float nd2[RELAX_NEIGHBOURS];
    for (uint32_t i = begin; i < end; ++i) {
        const glow__surfel *s = &c->old[i];
        c->new_bary[i][0] = s->bary[0];
        c->new_bary[i][1] = s->bary[1];
        uint32_t found = glow__pointgrid_knn(c->grid, s->pos, RELAX_NEIGHBOURS, i, nb, nd2);
        double disp[3] = {0.0, 0.0, 0.0};
        bool any = false;
        for (uint32_t k = 0; k < found; ++k) {
            const glow__surfel *o = &c->old[nb[k]];
            if (glow__dot(s->nrm, o->nrm) <= 0.5f) continue;
            const double R = c->rad ? (double)c->rad[i] + (double)c->rad[nb[k]] : c->radius;
            double dv[3] = {(double)s->pos[0] - o->pos[0], (double)s->pos[1] - o->pos[1], (double)s->pos[2] - o->pos[2]};
            double d = sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]);
            if (d >= R) continue;
            double f;
            if (d < 1e-9 * R) {
                /* coincident: push along a deterministic pseudo-random direction from the pair's
                 * indices (any vector will do; it is made tangential below) */
                uint32_t h = hash32(i * 0x9e3779b9u ^ hash32(nb[k]));
                double ang = (double)h * (2.0 * GLOW__PI / 4294967296.0);
                dv[0] = cos(ang);
                dv[1] = sin(ang);
                dv[2] = cos(3.0 * ang);
                f = RELAX_STEP * R;
            } else {
                f = RELAX_STEP * (R - d) / d;
            }
            for (int a = 0; a < 3; ++a) disp[a] += f * dv[a];
            any = true;
        }
        if (!any) continue;
        /* tangential: remove the component along the surfel's normal */
        double dn = disp[0] * s->nrm[0] + disp[1] * s->nrm[1] + disp[2] * s->nrm[2];
        for (int a = 0; a < 3; ++a) disp[a] -= dn * s->nrm[a];
        double len = sqrt(disp[0] * disp[0] + disp[1] * disp[1] + disp[2] * disp[2]);
        const double max_move = c->rad ? RELAX_MAX_MOVE * (double)c->rad[i] : c->max_move;
        if (len > max_move) for (int a = 0; a < 3; ++a) disp[a] *= max_move / len;
        /* move in barycentric space, clamped to the surfel's own triangle */
        uint32_t t = s->tri;
        const float *p0 = scene->pos[3 * t], *p1 = scene->pos[3 * t + 1], *p2 = scene->pos[3 * t + 2];
        double e1[3], e2[3], q[3];
        for (int a = 0; a < 3; ++a) {
            e1[a] = (double)p1[a] - p0[a];
            e2[a] = (double)p2[a] - p0[a];
            q[a] = (double)s->bary[0] * e1[a] + (double)s->bary[1] * e2[a] + disp[a];
        }
        double v, w;
        closest_bary(e1, e2, q, &v, &w);
        clamp_bary(&v, &w);
        c->new_bary[i][0] = (float)v;
        c->new_bary[i][1] = (float)w;
    }
}

typedef struct eval_ctx {
    const glow__scene *scene;
    const float (*bary)[2];
    glow__surfel *s;
    double area;
    const float *areas;       /* adaptive density: per-surfel areas; NULL: `area` for all */
    bool force;               /* re-evaluate every surfel where it is (bary unused) */
} eval_ctx;

static void eval_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    eval_ctx *c = vctx;
    for (uint32_t i = begin; i < end; ++i) {
        glow__surfel *s = &c->s[i];
        if (c->force) {
            surfel_eval(c->scene, c->areas ? (double)c->areas[i] : c->area, s);
            continue;
        }
        if (s->bary[0] == c->bary[i][0] && s->bary[1] == c->bary[i][1]) continue;
        set_bary(s, c->bary[i][0], c->bary[i][1]);
        surfel_eval(c->scene, c->areas ? (double)c->areas[i] : c->area, s);
    }
}

/* ------------------------------------------------------------------ adaptive density */
/* A surfel stands for the light of its patch; where surfaces face each other within a few surfel
 * radii (a capital over its shaft, an arch's springing, a moulding on a wall) that light changes
 * within a patch and is seen from close by, so the sources must be finer there than on open ground.
 * Candidates are spawned ADAPT_OVERSAMPLE times as dense as the surfels (the same area-uniform
 * Halton scheme), each is weighted w = 1 + (adapt - 1) f, with f the fraction of ADAPT_RAYS
 * cosine-distributed rays from it that meet a surface within ADAPT_RADII nominal radii (the links'
 * near field), and exactly n are drawn by order sampling with inclusion probabilities about
 * p_i = min(1, tau w_i) (sum n). Each drawn surfel's area is its Horvitz-Thompson
 * share A / (M p_i), normalised so the areas sum to the scene's area exactly: the flux a node
 * pulls up stays an unbiased integral of radiosity over its surface. */
#define ADAPT_OVERSAMPLE 4u
#define ADAPT_RAYS GLOW__NEAR_RAYS
#define ADAPT_RADII 4.0

typedef struct adapt_ctx {
    const glow__scene *scene;
    const glow__rt *rt;
    const uint32_t *cand_tri;
    float (*cand_bary)[2];
    float *w;
    double rot[2];
    float reach, eps, adapt;
    uint32_t hash;
} adapt_ctx;

uint32_t glow__near_hits(const glow__rt *rt, const float org[3], const double n[3], double phi0, float reach, float eps) {
    const double golden = GLOW__PI * (3.0 - sqrt(5.0));
    float dirs[GLOW__NEAR_RAYS][3], tfar[GLOW__NEAR_RAYS];
    uint8_t occ[GLOW__NEAR_RAYS];
    double ta[3], tb[3];
    glow__tangent_frame(n, ta, tb);
    for (uint32_t k = 0; k < GLOW__NEAR_RAYS; ++k) { /* cosine-distributed Fibonacci spiral */
        const double r = sqrt((k + 0.5) / GLOW__NEAR_RAYS), z = sqrt(fmax(0.0, 1.0 - r * r)), phi = phi0 + golden * k;
        for (int a = 0; a < 3; ++a) dirs[k][a] = (float)(r * cos(phi) * ta[a] + r * sin(phi) * tb[a] + z * n[a]);
        tfar[k] = reach;
    }
    glow__rt_occluded16(rt, org, (const float (*)[3])dirs, tfar, GLOW__NEAR_RAYS, eps, occ);
    uint32_t hits = 0;
    for (uint32_t k = 0; k < GLOW__NEAR_RAYS; ++k) hits += occ[k];
    return hits;
}

static void adapt_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    (void)worker;
    adapt_ctx *c = vctx;
    for (uint32_t i = begin; i < end; ++i) {
        glow__surfel t;
        memset(&t, 0, sizeof t);
        t.tri = c->cand_tri[i];
        halton_bary(&t, i, c->rot);
        surfel_geom(c->scene, &t);
        c->cand_bary[i][0] = t.bary[0];
        c->cand_bary[i][1] = t.bary[1];
        const double n[3] = {t.nrm[0], t.nrm[1], t.nrm[2]};
        const double phi0 = (double)hash32(i ^ c->hash) * (2.0 * GLOW__PI / 4294967296.0);
        const uint32_t hits = glow__near_hits(c->rt, t.pos, n, phi0, c->reach, c->eps);
        c->w[i] = 1.0f + (c->adapt - 1.0f) * (float)hits / (float)ADAPT_RAYS;
    }
}

/* Area-proportional spawning with the running cumulative area (in units of the total, so the
 * triangles' own sum is the reference and the last triangle ends exactly at count). */
void glow__spawn_tris(const glow__scene *scene, double total, uint32_t count, uint32_t *out_tri) {
    double cum = 0.0;
    uint32_t spawned = 0;
    const uint32_t tri_count = scene->tri_count;
    for (uint32_t t = 0; t < tri_count; ++t) {
        cum += glow__tri_area(scene, t);
        double e = floor(cum / total * (double)count);
        uint32_t upto = e >= (double)count ? count : (uint32_t)e;
        if (t + 1 == tri_count) upto = count;
        while (spawned < upto) out_tri[spawned++] = t;
    }
}

typedef struct cand_key {
    double key;
    uint32_t idx;
} cand_key;

static int cmp_cand_key(const void *a, const void *b) {
    const cand_key *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->idx < y->idx ? -1 : (x->idx > y->idx);
}

/* Quickselect by (key, index): afterwards k[r] has rank r, lower ranks before it. */
static void select_cand(cand_key *k, uint32_t count, uint32_t r) {
    uint32_t lo = 0, hi = count - 1;
    while (hi > lo) {
        const uint32_t mid = lo + (hi - lo) / 2;
        cand_key t;
        if (cmp_cand_key(&k[mid], &k[lo]) < 0) { t = k[mid]; k[mid] = k[lo]; k[lo] = t; }
        if (cmp_cand_key(&k[hi], &k[lo]) < 0) { t = k[hi]; k[hi] = k[lo]; k[lo] = t; }
        if (cmp_cand_key(&k[hi], &k[mid]) < 0) { t = k[hi]; k[hi] = k[mid]; k[mid] = t; }
        const cand_key pivot = k[mid];
        uint32_t i = lo, j = hi;
        for (;;) {
            while (cmp_cand_key(&k[i], &pivot) < 0) ++i;
            while (cmp_cand_key(&pivot, &k[j]) < 0) --j;
            if (i >= j) break;
            t = k[i]; k[i] = k[j]; k[j] = t;
            ++i;
            --j;
        }
        if (r <= j) hi = j;
        else lo = j + 1;
    }
}

/* The adaptive draw (above): fills s[0, n) with tri, bary and evaluated fields at their own area,
 * and *out_areas (malloc'd, n) with the areas. */
static glow_result place_adaptive(const glow__scene *scene, const glow__surfel_settings *settings, double total,
                                  double a, const double rot[2], glow__pool *pool, glow__log *log, glow__surfel *s,
                                  float **out_areas) {
    const char *src = scene->source[0] ? scene->source : "scene";
    const uint32_t n = settings->count;
    const float adapt = settings->adapt < (float)ADAPT_OVERSAMPLE ? settings->adapt : (float)ADAPT_OVERSAMPLE;
    if (n > UINT32_MAX / ADAPT_OVERSAMPLE) {
        glow__errorf(log, "%s: %u surfels are too many for an adaptive density (at most %u)", src, n,
                     UINT32_MAX / ADAPT_OVERSAMPLE);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const uint32_t M = n * ADAPT_OVERSAMPLE;
    uint32_t *cand_tri = malloc((size_t)M * sizeof *cand_tri);
    float (*cand_bary)[2] = malloc((size_t)M * sizeof *cand_bary);
    float *w = malloc((size_t)M * sizeof *w);
    double *p = malloc((size_t)n * sizeof *p); /* the picks' inclusion probabilities */
    float *areas = malloc((size_t)n * sizeof *areas);
    uint32_t *pick = malloc((size_t)n * sizeof *pick);
    if (!cand_tri || !cand_bary || !w || !p || !areas || !pick) {
        free(cand_tri); free(cand_bary); free(w); free(p); free(areas); free(pick);
        glow__errorf(log, "%s: out of memory for %u surfel candidates", src, M);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    glow__spawn_tris(scene, total, M, cand_tri);
    float ext[3];
    glow__sub(scene->bounds_max, scene->bounds_min, ext);
    const float diag = sqrtf(glow__dot(ext, ext));
    /* the candidates sit on a grid ADAPT_OVERSAMPLE times as fine: their Halton points are those of
     * their own index, rotated by the same seed */
    adapt_ctx ac = {.scene = scene, .rt = settings->rt, .cand_tri = cand_tri, .cand_bary = cand_bary, .w = w,
                    .rot = {rot[0], rot[1]},
                    .reach = (float)(ADAPT_RADII * sqrt(a / GLOW__PI)), .eps = 1e-4f * (diag > 0.0f ? diag : 1.0f),
                    .adapt = adapt, .hash = hash32(settings->seed ^ 0x3c6ef372u)};
    glow__parallel_for(pool, M, 0, adapt_range, &ac);

    /* Order sampling: candidate i draws u_i uniform in (0, 1) and the n smallest u_i / w_i are
     * taken; with tau the n-th smallest, each is taken with probability about p_i = min(1, tau w_i)
     * (Rosen's uniform order sampling). Not systematic sampling in candidate order: every k-th
     * candidate of a triangle has Halton points in one stripe of it (Sponza 0.33 block error). In a
     * random order within each triangle it was a little worse than this on Sponza (0.105 against
     * 0.102, surfel seeds 0-3) and the same on the miniatures. Relaxation then evens out the
     * random spacing, as it does the Halton points'. */
    {
        cand_key *keys = malloc((size_t)M * sizeof *keys);
        if (!keys) {
            free(cand_tri); free(cand_bary); free(w); free(p); free(areas); free(pick);
            glow__errorf(log, "%s: out of memory for %u surfel candidates", src, M);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        double *kv = malloc((size_t)M * sizeof *kv);
        if (!kv) {
            free(keys);
            free(cand_tri); free(cand_bary); free(w); free(p); free(areas); free(pick);
            glow__errorf(log, "%s: out of memory for %u surfel candidates", src, M);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        const uint32_t hk = hash32(settings->seed ^ 0x1b873593u);
        for (uint32_t i = 0; i < M; ++i) {
            const double u = ((double)hash32(i * 0x9e3779b9u ^ hk ^ hash32(i)) + 0.5) / 4294967296.0;
            kv[i] = u / (double)w[i];
            keys[i].key = kv[i];
            keys[i].idx = i;
        }
        /* the n smallest by (key, index), in index order: a selection of the n-th, not a sort of all
         * (a sort of the 2M candidates and one of the picks took 0.4 s of 524,288 surfels' placement) */
        select_cand(keys, M, n - 1);
        const cand_key last = keys[n - 1];
        free(keys);
        const double tau = last.key;
        uint32_t taken = 0;
        for (uint32_t i = 0; i < M && taken < n; ++i)
            if (kv[i] < last.key || (kv[i] == last.key && i <= last.idx)) pick[taken++] = i;
        free(kv);
        for (uint32_t j = 0; j < n; ++j) {
            const double q = (double)w[pick[j]] * tau;
            p[j] = q < 1.0 ? q : 1.0;
        }
    }
    double inv_sum = 0.0;
    for (uint32_t j = 0; j < n; ++j) inv_sum += 1.0 / p[j];
    for (uint32_t j = 0; j < n; ++j) {
        const uint32_t i = pick[j];
        areas[j] = (float)(scene->area * (1.0 / p[j]) / inv_sum);
        memset(&s[j], 0, sizeof s[j]);
        s[j].tri = cand_tri[i];
        set_bary(&s[j], cand_bary[i][0], cand_bary[i][1]);
        surfel_eval(scene, areas[j], &s[j]);
    }
    free(cand_tri); free(cand_bary); free(w); free(p); free(pick);
    *out_areas = areas;
    return GLOW_OK;
}

/* ------------------------------------------------------------------ areas from the placement */
/* Each surfel's area is the surface closer to it than to any other surfel of its surface (a
 * Voronoi cell on the mesh), estimated with AREA_SAMPLES area-uniform points per surfel (Halton,
 * spawned like the surfels): every point goes to the nearest of its AREA_KNN nearest surfels that
 * faces its way (dot > 0.5) and has its material (or of the AREA_KNN_MORE nearest, when none of
 * those does), else to the nearest that faces its way, else to the nearest. A point stands for total / P of the surface, so every material's (and every connected
 * surface's) surfels carry its area exactly up to the points' own stratification, whatever
 * relaxation did to their spacing. One point is added to each cell, so that none is empty, and no
 * cell holds less than AREA_MIN_POINTS. */
#define AREA_SAMPLES 32u
#define AREA_KNN 8u
#define AREA_KNN_MORE 32u       /* when none of the AREA_KNN nearest is of the point's surface */
#define AREA_MIN_POINTS (AREA_SAMPLES / 8.0) /* no cell below 1/8 of the nominal area */

typedef struct area_ctx {
    const glow__scene *scene;
    const glow__surfel *s;
    const glow__pointgrid *grid;
    const uint32_t *tri_end;  /* per triangle: one past its last point */
    uint32_t *counts;         /* [workers][n] */
    uint64_t *fallback;       /* [workers]: points that went to a surfel of another material or facing */
    uint32_t n;
    double rot[2];
} area_ctx;

static void area_range(void *vctx, uint32_t begin, uint32_t end, uint32_t worker) {
    area_ctx *c = vctx;
    const glow__scene *scene = c->scene;
    uint32_t *cnt = c->counts + (size_t)worker * c->n;
    uint32_t nb[AREA_KNN_MORE];
    float nd2[AREA_KNN_MORE];
    /* the first triangle whose points reach past `begin` */
    uint32_t lo = 0, hi = scene->tri_count;
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (c->tri_end[mid] > begin) hi = mid;
        else lo = mid + 1;
    }
    uint32_t t = lo;
    for (uint32_t j = begin; j < end; ++j) {
        while (t < scene->tri_count && c->tri_end[t] <= j) ++t;
        if (t >= scene->tri_count) break;
        glow__surfel q;
        memset(&q, 0, sizeof q);
        q.tri = t;
        halton_bary(&q, j, c->rot);
        /* position and normal as surfel_eval has them (without the textures) */
        const float *p0 = scene->pos[3 * t], *p1 = scene->pos[3 * t + 1], *p2 = scene->pos[3 * t + 2];
        const float *n0 = scene->nrm[3 * t], *n1 = scene->nrm[3 * t + 1], *n2 = scene->nrm[3 * t + 2];
        const double b1 = q.bary[0], b2 = q.bary[1], b0 = 1.0 - b1 - b2;
        float pos[3], nrm[3];
        for (int k = 0; k < 3; ++k) {
            pos[k] = (float)((double)p0[k] + b1 * ((double)p1[k] - p0[k]) + b2 * ((double)p2[k] - p0[k]));
            nrm[k] = (float)(b0 * n0[k] + b1 * n1[k] + b2 * n2[k]);
        }
        const uint32_t m = scene->tri_material[t];
        uint32_t best = UINT32_MAX, facing = UINT32_MAX, first = UINT32_MAX;
        const float nl = 0.5f * sqrtf(glow__dot(nrm, nrm));
        /* Most points lie on the surface of their nearest surfel: when that one faces the point's way
         * and has its material, it is what the k-nearest scan below would pick first, and a 1-nearest
         * query (whose bound shrinks at once) finds it for a fraction of the cost. */
        float d0;
        const uint32_t near0 = glow__pointgrid_nearest(c->grid, pos, &d0);
        if (near0 != UINT32_MAX && glow__dot(c->s[near0].nrm, nrm) > nl && c->s[near0].material == m) best = near0;
        for (uint32_t k_want = AREA_KNN; best == UINT32_MAX && k_want <= AREA_KNN_MORE; k_want *= 4) {
            const uint32_t found = glow__pointgrid_knn(c->grid, pos, k_want, UINT32_MAX, nb, nd2);
            if (found) first = nb[0];
            for (uint32_t k = 0; k < found; ++k) { /* nearest first */
                const glow__surfel *o = &c->s[nb[k]];
                if (!(glow__dot(o->nrm, nrm) > nl)) continue; /* the other side of a thin wall, or another face */
                if (facing == UINT32_MAX) facing = nb[k];
                if (o->material == m) { best = nb[k]; break; }
            }
            if (found < k_want) break;
        }
        if (best == UINT32_MAX) best = facing;
        if (best == UINT32_MAX) best = first;
        c->fallback[worker] += best != UINT32_MAX && (c->s[best].material != m || !(glow__dot(c->s[best].nrm, nrm) > nl));
        if (best != UINT32_MAX) cnt[best]++;
    }
}

/* areas[i] for s[0, n): see above. */
static glow_result voronoi_areas(const glow__scene *scene, double total, const glow__surfel *s, uint32_t n,
                                 uint32_t seed, glow__pool *pool, float *areas, uint64_t *out_fallback,
                                 uint32_t *out_points) {
    const uint64_t P64 = (uint64_t)n * AREA_SAMPLES;
    const uint32_t P = P64 > UINT32_MAX ? UINT32_MAX : (uint32_t)P64;
    const uint32_t workers = glow__pool_threads(pool);
    uint32_t *tri_end = malloc((size_t)scene->tri_count * sizeof *tri_end);
    uint32_t *counts = calloc((size_t)workers * n, sizeof *counts);
    float (*pts)[3] = malloc((size_t)n * sizeof *pts);
    if (!tri_end || !counts || !pts) {
        free(tri_end); free(counts); free(pts);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    double cum = 0.0;
    for (uint32_t t = 0; t < scene->tri_count; ++t) { /* as spawn_tris */
        cum += glow__tri_area(scene, t);
        const double e = floor(cum / total * (double)P);
        tri_end[t] = e >= (double)P ? P : (uint32_t)e;
    }
    tri_end[scene->tri_count - 1] = P;
    for (uint32_t i = 0; i < n; ++i) memcpy(pts[i], s[i].pos, sizeof pts[i]);
    /* a grid, not a tree: n x AREA_SAMPLES queries (16.8M at 524,288 surfels) took 73 % of the surfel
     * stage in the tree's descent; cells of about two spacings hold the 8 nearest within one ring */
    glow__pointgrid *grid = glow__pointgrid_build((const float (*)[3])pts, n, scene->bounds_min, scene->bounds_max,
                                                  2.0f * (float)sqrt(total / (double)n));
    free(pts);
    if (!grid) {
        free(tri_end); free(counts);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    const uint32_t h0 = hash32(seed ^ 0x85ebca6bu), h1 = hash32(h0 ^ 0xc2b2ae35u);
    uint64_t *fallback = calloc(workers, sizeof *fallback);
    if (!fallback) {
        glow__pointgrid_free(grid);
        free(tri_end); free(counts);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    area_ctx ac = {.scene = scene, .s = s, .grid = grid, .tri_end = tri_end, .counts = counts, .n = n, .fallback = fallback,
                   .rot = {(double)h0 / 4294967296.0, (double)h1 / 4294967296.0}};
    glow__parallel_for(pool, P, 4096, area_range, &ac);
    glow__pointgrid_free(grid);
    uint64_t fell = 0;
    for (uint32_t k = 0; k < workers; ++k) fell += fallback[k];
    free(fallback);
    *out_fallback = fell;
    *out_points = P;
    /* a cell of c points holds c + 1 (so that none is empty), at least AREA_MIN_POINTS, scaled to
     * the scene's area */
    double sum = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
        uint64_t c = 0;
        for (uint32_t k = 0; k < workers; ++k) c += counts[(size_t)k * n + i];
        const double cc = (double)c + 1.0 < AREA_MIN_POINTS ? AREA_MIN_POINTS : (double)c + 1.0;
        areas[i] = (float)cc;
        sum += cc;
    }
    for (uint32_t i = 0; i < n; ++i) areas[i] = (float)((double)areas[i] * scene->area / sum);
    free(tri_end);
    free(counts);
    return GLOW_OK;
}

/* ------------------------------------------------------------------ entry point */
glow_result glow__surfels_place(const glow__scene *scene, const glow__surfel_settings *settings,
                                glow__pool *pool, glow__log *log, glow__surfels *out) {
    if (!out) return GLOW_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!scene || !settings) {
        glow__errorf(log, "surfels: no scene or settings");
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    const char *src = scene->source[0] ? scene->source : "scene";
    if (settings->count == 0) {
        glow__errorf(log, "%s: surfel count must be at least 1", src);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (scene->tri_count == 0 || !scene->pos || !scene->nrm || !scene->tri_material || !scene->materials) {
        glow__errorf(log, "%s: no triangles to place surfels on", src);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    if (!(scene->area > 0.0) || !isfinite(scene->area)) {
        glow__errorf(log, "%s: scene area %g is not positive and finite", src, scene->area);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    for (uint32_t t = 0; t < scene->tri_count; ++t) {
        if (scene->tri_material[t] >= scene->material_count) {
            glow__errorf(log, "%s: triangle %u has material %u of %u", src, t, scene->tri_material[t],
                         scene->material_count);
            return GLOW_ERROR_INVALID_ARGUMENT;
        }
    }
    const uint32_t n = settings->count, tri_count = scene->tri_count;
    const double a = scene->area / (double)n;

    glow__surfel *s = malloc((size_t)n * sizeof *s);
    uint32_t *surfel_tri = malloc((size_t)n * sizeof *surfel_tri);
    if (!s || !surfel_tri) {
        free(s);
        free(surfel_tri);
        glow__errorf(log, "%s: out of memory for %u surfels", src, n);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }

    /* area-proportional spawning with the running cumulative area (in units of the total, so the
     * triangles' own sum is the reference and the last triangle ends exactly at n) */
    double total = 0.0;
    for (uint32_t t = 0; t < tri_count; ++t) total += glow__tri_area(scene, t);
    if (!(total > 0.0) || !isfinite(total)) {
        free(s);
        free(surfel_tri);
        glow__errorf(log, "%s: triangles have no area", src);
        return GLOW_ERROR_INVALID_ARGUMENT;
    }
    uint32_t h0 = hash32(settings->seed ^ 0x68bc21ebu), h1 = hash32(h0 ^ 0x02e5be93u);
    const double rot[2] = {(double)h0 / 4294967296.0, (double)h1 / 4294967296.0};
    float *areas = NULL;      /* adaptive density: each surfel's area */
    const bool adaptive = settings->adapt > 1.0f && settings->rt && n > 1;
    if (!adaptive) {
        glow__spawn_tris(scene, total, n, surfel_tri);
        place_ctx pc = {.scene = scene, .surfel_tri = surfel_tri, .s = s, .area = a, .rot = {rot[0], rot[1]}};
        glow__parallel_for(pool, n, 0, place_range, &pc);
        free(surfel_tri);
    } else {
        free(surfel_tri);
        glow_result r = place_adaptive(scene, settings, total, a, rot, pool, log, s, &areas);
        if (r != GLOW_OK) {
            free(s);
            return r;
        }
    }

    if (settings->relax_iterations > 0 && n > 1) {
        float (*bary)[2] = malloc((size_t)n * sizeof *bary);
        float (*pts)[3] = malloc((size_t)n * sizeof *pts);
        float *rad = areas ? malloc((size_t)n * sizeof *rad) : NULL;
        if (!bary || !pts || (areas && !rad)) {
            free(bary);
            free(pts);
            free(rad);
            free(areas);
            free(s);
            glow__errorf(log, "%s: out of memory relaxing %u surfels", src, n);
            return GLOW_ERROR_OUT_OF_MEMORY;
        }
        double r = sqrt(a / GLOW__PI);
        if (rad) for (uint32_t i = 0; i < n; ++i) rad[i] = (float)sqrt((double)areas[i] / GLOW__PI);
        for (uint32_t it = 0; it < settings->relax_iterations; ++it) {
            for (uint32_t i = 0; i < n; ++i) memcpy(pts[i], s[i].pos, sizeof pts[i]);
            /* a grid, as for the areas below: n 6-nearest queries each iteration */
            glow__pointgrid *grid = glow__pointgrid_build((const float (*)[3])pts, n, scene->bounds_min,
                                                          scene->bounds_max, 2.0f * (float)sqrt(a));
            if (!grid) {
                free(bary);
                free(pts);
                free(rad);
                free(areas);
                free(s);
                glow__errorf(log, "%s: out of memory building the surfel grid", src);
                return GLOW_ERROR_OUT_OF_MEMORY;
            }
            relax_ctx rc = {.scene = scene, .grid = grid, .old = s, .new_bary = bary,
                            .radius = 2.0 * r, .max_move = RELAX_MAX_MOVE * r, .rad = rad};
            glow__parallel_for(pool, n, 0, relax_range, &rc);
            glow__pointgrid_free(grid);
            eval_ctx ec = {.scene = scene, .bary = (const float (*)[2])bary, .s = s, .area = a, .areas = areas};
            glow__parallel_for(pool, n, 0, eval_range, &ec);
        }
        free(bary);
        free(pts);
        free(rad);
    }
    if (adaptive) {
        uint64_t fell = 0;
        uint32_t points = 0;
        glow_result r = voronoi_areas(scene, total, s, n, settings->seed, pool, areas, &fell, &points);
        if (r != GLOW_OK) {
            free(areas);
            free(s);
            glow__errorf(log, "%s: out of memory measuring %u surfels' areas", src, n);
            return r;
        }
        eval_ctx ec = {.scene = scene, .s = s, .area = a, .areas = areas, .force = true};
        glow__parallel_for(pool, n, 0, eval_range, &ec);
        float amin = areas[0], amax = areas[0];
        for (uint32_t i = 1; i < n; ++i) {
            amin = areas[i] < amin ? areas[i] : amin;
            amax = areas[i] > amax ? areas[i] : amax;
        }
        glow__infof(log, "%s: surfels: density adapted to concavity (up to %gx); areas %.3g..%.3gx the nominal %.4g, "
                    "measured with %u points (%.2f %% went to another surface's surfel)", src, (double)settings->adapt,
                    amin / a, amax / a, a, points, points ? 100.0 * (double)fell / points : 0.0);
    }
    free(areas);

    out->count = n;
    out->s = s;
    out->area = (float)a;
    out->adapted = adaptive ? 1u : 0u;
    return GLOW_OK;
}

void glow__surfels_free(glow__surfels *s) {
    if (!s) return;
    free(s->s);
    memset(s, 0, sizeof *s);
}
