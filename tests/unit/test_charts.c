/* test_charts.c — Glow's lightmap chart packer (charts.c): charts never overlap, keep their
 * padding, stay in [0,1], are not flipped or stretched, fold-prone surfaces get split, huge charts
 * shrink the density, and a 60k-triangle scene (and Sponza, when present) charts quickly.
 * Scenes are built by hand (no dependency on the importer). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "charts.h"
#include "pc_internal.h"

/* ------------------------------------------------------------------ scene building */
typedef struct builder {
    uint32_t n, cap;
    float (*pos)[3];
} builder;

static void b_tri(builder *b, const double p0[3], const double p1[3], const double p2[3]) {
    if (b->n == b->cap) {
        b->cap = b->cap ? 2 * b->cap : 256;
        b->pos = realloc(b->pos, (size_t)b->cap * 3 * sizeof *b->pos);
        assert_non_null(b->pos);
    }
    const double *p[3] = {p0, p1, p2};
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) b->pos[3 * (size_t)b->n + (size_t)k][a] = (float)p[k][a];
    b->n++;
}

/* nu x nv quads spanning o + s*eu + t*ev; front side = eu x ev. */
static void b_grid(builder *b, const double o[3], const double eu[3], const double ev[3], int nu, int nv) {
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            double q[4][3];
            for (int a = 0; a < 3; ++a) {
                q[0][a] = o[a] + eu[a] * i / nu + ev[a] * j / nv;
                q[1][a] = o[a] + eu[a] * (i + 1) / nu + ev[a] * j / nv;
                q[2][a] = o[a] + eu[a] * (i + 1) / nu + ev[a] * (j + 1) / nv;
                q[3][a] = o[a] + eu[a] * i / nu + ev[a] * (j + 1) / nv;
            }
            b_tri(b, q[0], q[1], q[2]);
            b_tri(b, q[0], q[2], q[3]);
        }
}

/* Axis-aligned box, faces outward (or inward for a room), each face sub x sub quads. */
static void b_box(builder *b, const double lo[3], const double hi[3], bool outward, int sub) {
    double X[3] = {hi[0] - lo[0], 0, 0}, Y[3] = {0, hi[1] - lo[1], 0}, Z[3] = {0, 0, hi[2] - lo[2]};
    double hx[3] = {hi[0], lo[1], lo[2]}, hy[3] = {lo[0], hi[1], lo[2]}, hz[3] = {lo[0], lo[1], hi[2]};
    const double *faces[6][3] = {{lo, Z, Y}, {hx, Y, Z}, {lo, X, Z}, {hy, Z, X}, {lo, Y, X}, {hz, X, Y}};
    for (int f = 0; f < 6; ++f)
        if (outward)
            b_grid(b, faces[f][0], faces[f][1], faces[f][2], sub, sub);
        else
            b_grid(b, faces[f][0], faces[f][2], faces[f][1], sub, sub);
}

/* UV sphere, outward. */
static void b_sphere(builder *b, const double c[3], double r, int seg, int rings) {
    for (int j = 0; j < rings; ++j)
        for (int i = 0; i < seg; ++i) {
            double q[4][3];
            for (int k = 0; k < 4; ++k) {
                int ii = i + (k == 1 || k == 2), jj = j + (k >= 2);
                double th = GLOW__PI * jj / rings, ph = 2.0 * GLOW__PI * ii / seg;
                q[k][0] = c[0] + r * sin(th) * cos(ph);
                q[k][1] = c[1] + r * sin(th) * sin(ph);
                q[k][2] = c[2] + r * cos(th);
            }
            /* th grows downward: (q0, q3, q2) and (q0, q2, q1) face outward */
            if (j < rings - 1) b_tri(b, q[0], q[3], q[2]); /* q2 = q3 at the bottom pole */
            if (j > 0) b_tri(b, q[0], q[2], q[1]);         /* q0 = q1 at the top pole */
        }
}

/* Open cylinder around z, outward. */
static void b_cylinder(builder *b, const double c[3], double r, double h, int seg, int rings) {
    for (int j = 0; j < rings; ++j)
        for (int i = 0; i < seg; ++i) {
            double q[4][3];
            for (int k = 0; k < 4; ++k) {
                int ii = i + (k == 1 || k == 2), jj = j + (k >= 2);
                double ph = 2.0 * GLOW__PI * ii / seg;
                q[k][0] = c[0] + r * cos(ph);
                q[k][1] = c[1] + r * sin(ph);
                q[k][2] = c[2] + h * jj / rings;
            }
            b_tri(b, q[0], q[1], q[2]);
            b_tri(b, q[0], q[2], q[3]);
        }
}

/* A ramp winding `turns` times around z, rising `pitch` per turn: every normal is within ~20
 * degrees of +z, so it charts as one planar-ish piece whose projection overlaps itself. */
static void b_spiral(builder *b, double r0, double r1, double pitch, double turns, int seg_per_turn) {
    int seg = (int)(turns * seg_per_turn);
    for (int i = 0; i < seg; ++i) {
        double a0 = 2.0 * GLOW__PI * i / seg_per_turn, a1 = 2.0 * GLOW__PI * (i + 1) / seg_per_turn;
        double z0 = pitch * i / seg_per_turn, z1 = pitch * (i + 1) / seg_per_turn;
        double q[4][3] = {{r0 * cos(a0), r0 * sin(a0), z0},
                          {r1 * cos(a0), r1 * sin(a0), z0},
                          {r1 * cos(a1), r1 * sin(a1), z1},
                          {r0 * cos(a1), r0 * sin(a1), z1}};
        b_tri(b, q[0], q[1], q[2]);
        b_tri(b, q[0], q[2], q[3]);
    }
}

static void b_finish(builder *b, glow__scene *s) {
    memset(s, 0, sizeof *s);
    s->tri_count = b->n;
    s->pos = b->pos;
    s->nrm = calloc(3 * (size_t)b->n, sizeof *s->nrm);
    s->tri_material = calloc(b->n, sizeof *s->tri_material);
    assert_non_null(s->nrm);
    assert_non_null(s->tri_material);
    for (int a = 0; a < 3; ++a) {
        s->bounds_min[a] = INFINITY;
        s->bounds_max[a] = -INFINITY;
    }
    double area = 0.0;
    for (uint32_t t = 0; t < b->n; ++t) {
        float(*p)[3] = s->pos + 3 * (size_t)t;
        double e1[3], e2[3], n[3];
        for (int a = 0; a < 3; ++a) {
            e1[a] = (double)p[1][a] - p[0][a];
            e2[a] = (double)p[2][a] - p[0][a];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        area += 0.5 * l;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) {
                s->nrm[3 * (size_t)t + (size_t)k][a] = l > 0 ? (float)(n[a] / l) : 0.0f;
                if (p[k][a] < s->bounds_min[a]) s->bounds_min[a] = p[k][a];
                if (p[k][a] > s->bounds_max[a]) s->bounds_max[a] = p[k][a];
            }
    }
    s->area = area;
    s->material_count = 1;
    s->materials = calloc(1, sizeof *s->materials);
    assert_non_null(s->materials);
    s->materials[0].texture = -1;
    snprintf(s->source, sizeof s->source, "test");
    b->pos = NULL;
    b->n = b->cap = 0;
}

static void scene_free(glow__scene *s) {
    free(s->pos);
    free(s->nrm);
    free(s->uv1);
    free(s->tri_material);
    free(s->materials);
    memset(s, 0, sizeof *s);
}

/* Minimal OBJ reader (v and f only, polygons fan-triangulated) for the Sponza timing. */
static bool load_obj(const char *path, glow__scene *s) {
    FILE *f = fopen(path, "r");
    if (!f) return false;
    builder b = {0};
    size_t nv = 0, capv = 0;
    double(*v)[3] = NULL;
    char line[4096];
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'v' && line[1] == ' ') {
            if (nv == capv) {
                capv = capv ? 2 * capv : 4096;
                v = realloc(v, capv * sizeof *v);
                assert_non_null(v);
            }
            if (sscanf(line + 2, "%lf %lf %lf", &v[nv][0], &v[nv][1], &v[nv][2]) == 3) ++nv;
        } else if (line[0] == 'f' && line[1] == ' ') {
            long idx[64];
            int k = 0;
            char *p = line + 2;
            while (*p && k < 64) {
                while (*p == ' ' || *p == '\t') ++p;
                if (!*p || *p == '\n' || *p == '\r') break;
                char *end;
                long i = strtol(p, &end, 10);
                if (end == p) break;
                idx[k++] = i < 0 ? (long)nv + i : i - 1;
                p = end;
                while (*p && *p != ' ' && *p != '\t') ++p;
            }
            for (int j = 1; j + 1 < k; ++j) {
                if (idx[0] < 0 || idx[j] < 0 || idx[j + 1] < 0 || (size_t)idx[0] >= nv || (size_t)idx[j] >= nv ||
                    (size_t)idx[j + 1] >= nv)
                    continue;
                const double *a = v[idx[0]], *bb = v[idx[j]], *c = v[idx[j + 1]];
                double e1[3], e2[3];
                for (int q = 0; q < 3; ++q) {
                    e1[q] = bb[q] - a[q];
                    e2[q] = c[q] - a[q];
                }
                double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
                       cz = e1[0] * e2[1] - e1[1] * e2[0];
                if (cx * cx + cy * cy + cz * cz == 0.0) continue; /* zero area */
                b_tri(&b, a, bb, c);
            }
        }
    }
    fclose(f);
    free(v);
    b_finish(&b, s);
    return true;
}

/* ------------------------------------------------------------------ checks */
typedef struct report {
    uint32_t w, h, charts;
    double centre_fill; /* texels whose centre lies in (or on) a triangle / atlas */
    double stretch;     /* total UV area / (3-D area * density^2) */
    double foot_fill;   /* texels a triangle overlaps (conservative) / atlas */
    uint32_t merged;    /* texels shared by several small charts */
    uint32_t slots;     /* footprints packed */
} report;

/* Area of triangle t (texel units) clipped to the unit square at (x, y): Sutherland-Hodgman. */
static double clip_area(const double t[3][2], double x, double y) {
    double poly[16][2], tmp[16][2];
    int n = 3;
    memcpy(poly, t, 3 * sizeof poly[0]);
    for (int e = 0; e < 4; ++e) {
        int m = 0;
        for (int i = 0; i < n; ++i) {
            const double *a = poly[i], *b = poly[(i + 1) % n];
            double da, db;
            switch (e) {
            case 0: da = a[0] - x; db = b[0] - x; break;
            case 1: da = x + 1 - a[0]; db = x + 1 - b[0]; break;
            case 2: da = a[1] - y; db = b[1] - y; break;
            default: da = y + 1 - a[1]; db = y + 1 - b[1]; break;
            }
            if (da >= 0) {
                tmp[m][0] = a[0];
                tmp[m][1] = a[1];
                ++m;
            }
            if ((da >= 0) != (db >= 0)) {
                double s = da / (da - db);
                tmp[m][0] = a[0] + s * (b[0] - a[0]);
                tmp[m][1] = a[1] + s * (b[1] - a[1]);
                ++m;
            }
        }
        n = m;
        memcpy(poly, tmp, (size_t)m * sizeof poly[0]);
        if (n == 0) return 0.0;
    }
    double area = 0;
    for (int i = 0; i < n; ++i) area += poly[i][0] * poly[(i + 1) % n][1] - poly[(i + 1) % n][0] * poly[i][1];
    return 0.5 * fabs(area);
}

/* Checks the packed UVs of chart set cs: in [0,1], positive orientation, no texel centre in two
 * charts (or twice in one chart), conservative footprints of different charts > padding apart and
 * >= padding from the border, no stretching. */
static report check_atlas(const glow__scene *s, const glow__chart_set *cs, const float (*uv)[2], uint32_t w,
                          uint32_t h, float density, uint32_t padding, const uint32_t *unit_of) {
    report r = {.w = w, .h = h, .charts = cs->chart_count};
    assert_true(w % 4 == 0 && h % 4 == 0 && w >= 4 && h >= 4);
    assert_true(w <= GLOW__CHART_MAX_ATLAS && h <= GLOW__CHART_MAX_ATLAS);
    uint32_t *chart_of = malloc((size_t)s->tri_count * sizeof *chart_of);
    uint32_t *centre = malloc((size_t)w * h * sizeof *centre);
    uint32_t *foot = malloc((size_t)w * h * sizeof *foot);
    uint8_t *covered = calloc((size_t)w * h, 1);
    assert_non_null(covered);
    assert_non_null(chart_of);
    assert_non_null(centre);
    assert_non_null(foot);
    memset(chart_of, 0xFF, (size_t)s->tri_count * sizeof *chart_of);
    for (uint32_t c = 0; c < cs->chart_count; ++c)
        for (uint32_t j = cs->chart_start[c]; j < cs->chart_start[c + 1]; ++j) {
            assert_true(chart_of[cs->chart_tris[j]] == UINT32_MAX); /* each triangle in one chart */
            chart_of[cs->chart_tris[j]] = unit_of ? unit_of[c] : c; /* merged small charts: one footprint */
        }
    for (uint32_t t = 0; t < s->tri_count; ++t) assert_true(chart_of[t] != UINT32_MAX);
    /* multi[u]: footprint u holds several (merged) charts; texels[u]: texels it touches */
    uint32_t *multi = calloc((size_t)cs->chart_count + 1, sizeof *multi);
    uint32_t *texels = calloc((size_t)cs->chart_count + 1, sizeof *texels);
    assert_non_null(multi);
    assert_non_null(texels);
    for (uint32_t c = 0; c < cs->chart_count && unit_of; ++c) multi[unit_of[c]]++;
    for (uint32_t c = 0; c < cs->chart_count; ++c) multi[c] = multi[c] > 1;
    memset(centre, 0xFF, (size_t)w * h * sizeof *centre);
    memset(foot, 0xFF, (size_t)w * h * sizeof *foot);
    double uv_area = 0.0, area3 = 0.0;
    uint64_t centres = 0;
    for (uint32_t t = 0; t < s->tri_count; ++t) {
        double tc[3][2];
        for (int k = 0; k < 3; ++k) {
            float u = uv[3 * (size_t)t + (size_t)k][0], v = uv[3 * (size_t)t + (size_t)k][1];
            assert_true(u >= 0.0f && u <= 1.0f && v >= 0.0f && v <= 1.0f);
            tc[k][0] = (double)u * w;
            tc[k][1] = (double)v * h;
        }
        double a2 = (tc[1][0] - tc[0][0]) * (tc[2][1] - tc[0][1]) - (tc[1][1] - tc[0][1]) * (tc[2][0] - tc[0][0]);
        const float(*p)[3] = s->pos + 3 * (size_t)t;
        double e1[3], e2[3];
        for (int a = 0; a < 3; ++a) {
            e1[a] = (double)p[1][a] - p[0][a];
            e2[a] = (double)p[2][a] - p[0][a];
        }
        double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2], cz = e1[0] * e2[1] - e1[1] * e2[0];
        double tri3 = 0.5 * sqrt(cx * cx + cy * cy + cz * cz) * density * density;
        /* float UVs: each coordinate is off by up to ~6e-8 * atlas size texels */
        double perim = 0.0;
        for (int k = 0; k < 3; ++k) perim += hypot(tc[(k + 1) % 3][0] - tc[k][0], tc[(k + 1) % 3][1] - tc[k][1]);
        double tol = 2.0 * perim * 1.2e-7 * (w > h ? w : h);
        if (0.5 * a2 < -tol) fail_msg("triangle %u is flipped in UV space (area %g)", t, a2);
        if (0.5 * a2 > tri3 * 1.001 + tol) fail_msg("triangle %u is stretched: %g texels for %g", t, 0.5 * a2, tri3);
        uv_area += 0.5 * fabs(a2);
        area3 += tri3;
        long x0 = (long)floor(fmin(fmin(tc[0][0], tc[1][0]), tc[2][0])), x1 = (long)floor(fmax(fmax(tc[0][0], tc[1][0]), tc[2][0]));
        long y0 = (long)floor(fmin(fmin(tc[0][1], tc[1][1]), tc[2][1])), y1 = (long)floor(fmax(fmax(tc[0][1], tc[1][1]), tc[2][1]));
        for (long y = y0; y <= y1; ++y)
            for (long x = x0; x <= x1; ++x) {
                if (x < 0 || y < 0 || x >= (long)w || y >= (long)h) continue;
                size_t i = (size_t)y * w + (size_t)x;
                double px = x + 0.5, py = y + 0.5;
                double w0 = (tc[1][0] - px) * (tc[2][1] - py) - (tc[1][1] - py) * (tc[2][0] - px);
                double w1 = (tc[2][0] - px) * (tc[0][1] - py) - (tc[2][1] - py) * (tc[0][0] - px);
                double w2 = (tc[0][0] - px) * (tc[1][1] - py) - (tc[0][1] - py) * (tc[1][0] - px);
                double ctol = 1e-7 * fabs(a2);
                bool centre_in = w0 > ctol && w1 > ctol && w2 > ctol;
                if (centre_in || clip_area((const double(*)[2])tc, (double)x, (double)y) > 1e-9) {
                    if (foot[i] != UINT32_MAX && foot[i] != chart_of[t])
                        fail_msg("texel %ld,%ld touched by charts %u and %u", x, y, foot[i], chart_of[t]);
                    foot[i] = chart_of[t];
                }
                /* texel centre strictly inside (a triangle touching the centre on its edge may share it) */
                if (w0 >= 0 && w1 >= 0 && w2 >= 0 && covered[i] == 0) {
                    covered[i] = 1;
                    ++centres;
                }
                if (centre_in) { /* merged small charts may overlap inside their shared texel */
                    if (centre[i] != UINT32_MAX && !(chart_of[centre[i]] == chart_of[t] && multi[chart_of[t]]))
                        fail_msg("texel %ld,%ld is inside triangles %u and %u", x, y, centre[i], t);
                    centre[i] = t;
                }
            }
    }
    /* footprints of different charts are more than `padding` texels apart, and padding from the border */
    long P = (long)padding;
    for (long y = 0; y < (long)h; ++y)
        for (long x = 0; x < (long)w; ++x) {
            uint32_t c = foot[(size_t)y * w + (size_t)x];
            if (c == UINT32_MAX) continue;
            if (x < P || y < P || x >= (long)w - P || y >= (long)h - P)
                fail_msg("chart %u reaches texel %ld,%ld within the %u-texel border", c, x, y, padding);
            for (long dy = -P; dy <= P; ++dy)
                for (long dx = -P; dx <= P; ++dx) {
                    long qx = x + dx, qy = y + dy;
                    if (qx < 0 || qy < 0 || qx >= (long)w || qy >= (long)h) continue;
                    uint32_t d = foot[(size_t)qy * w + (size_t)qx];
                    if (d != UINT32_MAX && d != c) fail_msg("charts %u and %u are closer than %u texels", c, d, padding);
                }
        }
    r.centre_fill = (double)centres / ((double)w * h);
    uint64_t feet = 0;
    for (size_t i = 0; i < (size_t)w * h; ++i) {
        feet += foot[i] != UINT32_MAX;
        if (foot[i] != UINT32_MAX) texels[foot[i]]++;
    }
    /* merged charts share exactly one texel */
    for (uint32_t u = 0; u < cs->chart_count; ++u) {
        if (multi[u] && texels[u] != 1) fail_msg("merged footprint %u touches %u texels", u, texels[u]);
        r.merged += multi[u];
    }
    free(multi);
    free(texels);
    r.foot_fill = (double)feet / ((double)w * h);
    r.stretch = uv_area / area3;
    free(chart_of);
    free(centre);
    free(foot);
    free(covered);
    return r;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct capture {
    uint32_t warnings;
    char last[512];
} capture;
static void capture_log(void *user, glow_log_level level, const char *msg) {
    capture *c = user;
    if (level == GLOW_LOG_WARNING) {
        c->warnings++;
        snprintf(c->last, sizeof c->last, "%s", msg);
    }
}

/* segment + pack + check; also checks glow__charts_build gives the same UVs. */
static report run(const glow__scene *s, float density, uint32_t padding, double *seconds, uint32_t *evicted) {
    glow__log log = {0};
    glow__chart_set cs;
    float(*uv)[2] = malloc(3 * (size_t)s->tri_count * sizeof *uv);
    float(*uv2)[2] = malloc(3 * (size_t)s->tri_count * sizeof *uv2);
    assert_non_null(uv);
    assert_non_null(uv2);
    double t0 = now();
    assert_int_equal(glow__charts_segment(s, NULL, &log, &cs), GLOW_OK);
    uint32_t w, h;
    float used;
    uint32_t *unit_of = malloc(((size_t)cs.chart_count + 1) * sizeof *unit_of);
    assert_non_null(unit_of);
    glow__chart_pack_stats st = {.unit_of = unit_of};
    assert_int_equal(glow__charts_pack(&cs, density, padding, &log, uv, &w, &h, &used, &st), GLOW_OK);
    if (seconds) *seconds = now() - t0;
    if (evicted) *evicted = cs.evicted;
    report r = check_atlas(s, &cs, (const float(*)[2])uv, w, h, used, padding, unit_of);
    r.slots = st.slots;
    free(unit_of);
    uint32_t w2, h2, charts2;
    assert_int_equal(glow__charts_build(s, density, padding, &log, uv2, &w2, &h2, &charts2), GLOW_OK);
    assert_int_equal(w2, w);
    assert_int_equal(h2, h);
    assert_int_equal(charts2, cs.chart_count);
    assert_memory_equal(uv, uv2, 3 * (size_t)s->tri_count * sizeof *uv);
    glow__charts_free(&cs);
    free(uv);
    free(uv2);
    return r;
}

/* ------------------------------------------------------------------ tests */
static void test_cube_six_charts(void **state) {
    (void)state;
    builder b = {0};
    b_box(&b, (double[3]){0, 0, 0}, (double[3]){1, 1, 1}, true, 1);
    glow__scene s;
    b_finish(&b, &s);
    report r = run(&s, 10.0f, 2, NULL, NULL);
    assert_int_equal(r.charts, 6);
    /* every face is a 10x10-texel square centred in an 11x11 footprint: its edges run through texel
     * centres, so at least the 9x9 strictly inside are covered */
    assert_true(r.centre_fill * r.w * r.h >= 6 * 81 - 1e-9);
    assert_true(r.foot_fill * r.w * r.h == 6 * 121);
    assert_true(r.stretch > 0.999);
    /* six 11x11 footprints + padding fit 4 to a row: the atlas is no bigger than 56 x 56 */
    assert_true(r.w <= 56 && r.h <= 56);
    print_message("cube: %ux%u atlas, %u charts, %.1f%% of texels inside a triangle\n", r.w, r.h, r.charts,
                  100.0 * r.centre_fill);
    scene_free(&s);
}

static void test_mixed_scene(void **state) {
    (void)state;
    builder b = {0};
    b_box(&b, (double[3]){-2, 0, -2}, (double[3]){2, 3, 2}, false, 6);         /* room, inward */
    b_box(&b, (double[3]){-1, 0, -1}, (double[3]){0, 1.2, 0.3}, true, 2);      /* block */
    b_sphere(&b, (double[3]){1, 1, 1}, 0.5, 24, 12);
    b_cylinder(&b, (double[3]){1, -1, 0}, 0.2, 2.5, 16, 4);
    glow__scene s;
    b_finish(&b, &s);
    double secs;
    report r = run(&s, 12.0f, 2, &secs, NULL);
    double aspect = (double)(r.w > r.h ? r.w : r.h) / (r.w > r.h ? r.h : r.w);
    print_message("mixed (%u tris): %ux%u atlas, %u charts, centre fill %.1f%%, footprint fill %.1f%%, UV/3-D area "
                  "%.3f, aspect %.2f, %.1f ms\n", s.tri_count, r.w, r.h, r.charts, 100.0 * r.centre_fill,
                  100.0 * r.foot_fill, r.stretch, aspect, 1e3 * secs);
    assert_true(r.stretch > 0.85);
    assert_true(aspect <= 2.0);
    assert_true(r.centre_fill > 0.4);
    /* the 6x6-subdivided room walls are flat: one chart each; the block has six faces */
    assert_true(r.charts >= 12 && r.charts < 80);
    scene_free(&s);
}

static void test_spiral_is_split(void **state) {
    (void)state;
    builder b = {0};
    b_spiral(&b, 0.5, 1.5, 0.3, 2.5, 48);
    glow__scene s;
    b_finish(&b, &s);
    uint32_t evicted = 0;
    report r = run(&s, 20.0f, 2, NULL, &evicted);
    print_message("spiral: %u charts, %u triangles evicted from overlapping projections\n", r.charts, evicted);
    assert_true(evicted > 0);
    assert_true(r.charts >= 3); /* 2.5 turns: at least three non-overlapping pieces */
    scene_free(&s);
}

static void test_huge_chart_reduces_density(void **state) {
    (void)state;
    builder b = {0};
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){100, 0, 0}, (double[3]){0, 0, -3}, 4, 1); /* a 100 m strip */
    b_box(&b, (double[3]){10, 0, -10}, (double[3]){11, 1, -9}, true, 1);
    glow__scene s;
    b_finish(&b, &s);
    capture cap = {0};
    glow__log log = {.fn = capture_log, .user = &cap};
    glow__chart_set cs;
    assert_int_equal(glow__charts_segment(&s, NULL, &log, &cs), GLOW_OK);
    float(*uv)[2] = malloc(3 * (size_t)s.tri_count * sizeof *uv);
    assert_non_null(uv);
    uint32_t w, h;
    float used;
    assert_int_equal(glow__charts_pack(&cs, 100.0f, 2, &log, uv, &w, &h, &used, NULL), GLOW_OK);
    assert_true(w <= 4096 && h <= 4096);
    assert_true(used < 100.0f && used > 20.0f); /* 100 m at <= 4096 texels: ~40 texels per m */
    assert_int_equal(cap.warnings, 1);
    assert_non_null(strstr(cap.last, "4096"));
    report r = check_atlas(&s, &cs, (const float(*)[2])uv, w, h, used, 2, NULL);
    print_message("huge: requested 100 texels/m, got %.2f, atlas %ux%u\n", (double)used, r.w, r.h);
    glow__charts_free(&cs);
    free(uv);
    scene_free(&s);
}

/* Pages (issue 16 item 5): 40 boxes (240 charts of about 12x12 texels) do not fit one 64x64 atlas; with
 * 64 pages allowed they go onto several 64x64 pages at the density asked for, no warning, every
 * triangle's UVs in [0,1] of its page, and on each page the charts' footprints `padding` apart; the
 * page count capped at 2 lowers the density (warning), and a 4096 side gives glow__charts_pack's one
 * atlas, byte for byte. */
static void test_pages(void **state) {
    (void)state;
    builder b = {0};
    for (int i = 0; i < 40; ++i) {
        const double x = 3.0 * (i % 8), z = -3.0 * (i / 8);
        b_box(&b, (double[3]){x, 0, z}, (double[3]){x + 1, 1, z + 1}, true, 1);
    }
    glow__scene s;
    b_finish(&b, &s);
    capture cap = {0};
    glow__log log = {.fn = capture_log, .user = &cap};
    glow__chart_set cs;
    assert_int_equal(glow__charts_segment(&s, NULL, &log, &cs), GLOW_OK);
    const size_t n3 = 3 * (size_t)s.tri_count;
    float(*uv)[2] = malloc(n3 * sizeof *uv), (*uv1)[2] = malloc(n3 * sizeof *uv1);
    uint32_t *page = malloc((size_t)s.tri_count * sizeof *page);
    assert_true(uv && uv1 && page);
    uint32_t w, h, pages;
    float used;
    assert_int_equal(glow__charts_pack_pages(&cs, 10.0f, 2, 64, GLOW__CHART_MAX_PAGES, &log, uv, page, &pages, &w, &h,
                                             &used, NULL), GLOW_OK);
    print_message("pages: %u charts on %u pages of %ux%u at %.3g texels/m\n", cs.chart_count, pages, w, h, (double)used);
    assert_true(pages >= 3 && w == 64 && h == 64);
    assert_true(used == 10.0f);
    assert_int_equal(cap.warnings, 0);
    /* each chart on one page; its texel bounding box inside the page, and 2 texels from other charts' there */
    double(*box)[4] = malloc((size_t)cs.chart_count * sizeof *box);
    uint32_t *cpage = malloc((size_t)cs.chart_count * sizeof *cpage);
    assert_true(box && cpage);
    for (uint32_t c = 0; c < cs.chart_count; ++c) {
        box[c][0] = box[c][1] = INFINITY, box[c][2] = box[c][3] = -INFINITY;
        cpage[c] = page[cs.chart_tris[cs.chart_start[c]]];
        for (uint32_t j = cs.chart_start[c]; j < cs.chart_start[c + 1]; ++j) {
            const uint32_t t = cs.chart_tris[j];
            assert_int_equal(page[t], cpage[c]);
            assert_true(page[t] < pages);
            for (int k = 0; k < 3; ++k) {
                const float u = uv[3 * (size_t)t + k][0], v = uv[3 * (size_t)t + k][1];
                assert_true(u >= 0.0f && u <= 1.0f && v >= 0.0f && v <= 1.0f);
                box[c][0] = fmin(box[c][0], u * w), box[c][1] = fmin(box[c][1], v * h);
                box[c][2] = fmax(box[c][2], u * w), box[c][3] = fmax(box[c][3], v * h);
            }
        }
    }
    uint32_t used_pages = 0;
    for (uint32_t p = 0; p < pages; ++p) {
        bool any = false;
        for (uint32_t c = 0; c < cs.chart_count; ++c) any |= cpage[c] == p;
        used_pages += any;
    }
    assert_int_equal(used_pages, pages);
    for (uint32_t a = 0; a < cs.chart_count; ++a)
        for (uint32_t c = a + 1; c < cs.chart_count; ++c) {
            if (cpage[a] != cpage[c]) continue;
            const double gap = fmax(fmax(box[c][0] - box[a][2], box[a][0] - box[c][2]),
                                    fmax(box[c][1] - box[a][3], box[a][1] - box[c][3]));
            if (!(gap >= 2.0 - 1e-3)) fail_msg("charts %u and %u on page %u are %g texels apart", a, c, cpage[a], gap);
        }
    /* at most 2 pages: the density is lowered, with the warning */
    assert_int_equal(glow__charts_pack_pages(&cs, 10.0f, 2, 64, 2, &log, uv1, page, &pages, &w, &h, &used, NULL), GLOW_OK);
    assert_true(pages <= 2 && used < 10.0f && cap.warnings == 1);
    /* one atlas of up to 4096: glow__charts_pack's */
    cap.warnings = 0;
    uint32_t w1, h1;
    float used1;
    assert_int_equal(glow__charts_pack_pages(&cs, 10.0f, 2, 4096, GLOW__CHART_MAX_PAGES, &log, uv, page, &pages, &w, &h,
                                             &used, NULL), GLOW_OK);
    assert_int_equal(glow__charts_pack(&cs, 10.0f, 2, &log, uv1, &w1, &h1, &used1, NULL), GLOW_OK);
    assert_true(pages == 1 && w == w1 && h == h1 && used == used1 && cap.warnings == 0);
    assert_memory_equal(uv, uv1, n3 * sizeof *uv);
    for (uint32_t t = 0; t < s.tri_count; ++t) assert_int_equal(page[t], 0);
    free(box), free(cpage), free(uv), free(uv1), free(page);
    glow__charts_free(&cs);
    scene_free(&s);
}

static void test_bad_density_rejected(void **state) {
    (void)state;
    builder b = {0};
    b_box(&b, (double[3]){0, 0, 0}, (double[3]){1, 1, 1}, true, 1);
    glow__scene s;
    b_finish(&b, &s);
    glow__log log = {0};
    float(*uv)[2] = malloc(3 * (size_t)s.tri_count * sizeof *uv);
    assert_non_null(uv);
    uint32_t w = 7, h = 7, n = 7;
    assert_int_equal(glow__charts_build(&s, 0.0f, 2, &log, uv, &w, &h, &n), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(w, 0);
    assert_non_null(strstr(log.last_error, "density"));
    assert_int_equal(glow__charts_build(&s, NAN, 2, &log, uv, &w, &h, &n), GLOW_ERROR_INVALID_ARGUMENT);
    free(uv);
    scene_free(&s);
}

/* Duplicate welded corners, a non-manifold fin and a flipped triangle must not break charting. */
static void test_messy_topology(void **state) {
    (void)state;
    builder b = {0};
    b_grid(&b, (double[3]){0, 0, 0}, (double[3]){1, 0, 0}, (double[3]){0, 1, 0}, 4, 4);
    /* three fins on the edge x = 0.5 .. 0.75 of the plane (non-manifold), one flipped */
    double a[3] = {0.5, 0.0, 0.0}, c[3] = {0.75, 0.0, 0.0};
    b_tri(&b, a, c, (double[3]){0.6, 0.0, 0.3});
    b_tri(&b, c, a, (double[3]){0.6, 0.0, -0.3});
    b_tri(&b, a, c, (double[3]){0.6, -0.2, 0.2});
    /* a triangle overlapping the plane, coplanar and sharing an edge on the same side */
    b_tri(&b, (double[3]){0, 0, 0}, (double[3]){0.25, 0, 0}, (double[3]){0.1, 0.1, 0});
    /* a sliver */
    b_tri(&b, (double[3]){2, 0, 0}, (double[3]){3, 0, 0}, (double[3]){2.5, 1e-4, 0});
    glow__scene s;
    b_finish(&b, &s);
    report r = run(&s, 16.0f, 2, NULL, NULL);
    assert_true(r.charts >= 4);
    scene_free(&s);
}

static void test_60k_triangles(void **state) {
    (void)state;
    builder b = {0};
    b_sphere(&b, (double[3]){0, 0, 0}, 3.0, 160, 100);           /* 31,680 */
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j)
            b_box(&b, (double[3]){4 + i * 0.5, j * 0.5, 0}, (double[3]){4.3 + i * 0.5, j * 0.5 + 0.3, 0.2}, true, 3); /* 15,552 */
    for (int i = 0; i < 8; ++i) b_cylinder(&b, (double[3]){-6, i * 1.0, 0}, 0.3, 3.0, 40, 20); /* 12,800 */
    glow__scene s;
    b_finish(&b, &s);
    double secs;
    report r = run(&s, 8.0f, 2, &secs, NULL);
    print_message("synthetic %u tris: %u charts in %.0f ms, atlas %ux%u, centre fill %.1f%%, footprint fill %.1f%%, "
                  "UV/3-D area %.3f\n",
                  s.tri_count, r.charts, 1e3 * secs, r.w, r.h, 100.0 * r.centre_fill, 100.0 * r.foot_fill, r.stretch);
    assert_true(s.tri_count >= 60000);
    assert_true(r.stretch > 0.8);
    scene_free(&s);
}

static void test_sponza(void **state) {
    (void)state;
    glow__scene s;
    if (!load_obj(GLOW_SHARED_DIR "/scenes/sponza/dabrovic/sponza.obj", &s)) {
        print_message("sponza not found; skipped\n");
        skip();
    }
    const float densities[] = {1.5f, 6.0f};
    for (int k = 0; k < 2; ++k) {
        double secs;
        uint32_t evicted;
        report r = run(&s, densities[k], 2, &secs, &evicted);
        print_message("sponza %u tris at %.1f texels/m: %u charts (%u evicted) in %.0f ms, atlas %ux%u, centre fill "
                      "%.1f%%, footprint fill %.1f%%, UV/3-D area %.3f\n",
                      s.tri_count, (double)densities[k], r.charts, evicted, 1e3 * secs, r.w, r.h,
                      100.0 * r.centre_fill, 100.0 * r.foot_fill, r.stretch);
        assert_true(r.stretch > 0.8);
    }
    scene_free(&s);
}

/* Charts narrower than a texel share texels: pieces facing the same way in the same texel-sized cell
 * share one, pieces facing away from each other never do, and charts wider than a texel keep their
 * own footprint. */
static void test_small_charts_merge(void **state) {
    (void)state;
    builder b = {0};
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) {
            const double x = 0.1 * i + 0.01, z = 0.1 * j + 0.01;
            /* a 5 cm tile facing +y, and one 1 cm below it facing -y */
            b_grid(&b, (double[3]){x, 0, z}, (double[3]){0, 0, 0.05}, (double[3]){0.05, 0, 0}, 1, 1);
            b_grid(&b, (double[3]){x, -0.01, z}, (double[3]){0.05, 0, 0}, (double[3]){0, 0, 0.05}, 1, 1);
        }
    glow__scene s;
    b_finish(&b, &s);
    glow__log log = {0};
    glow__chart_set cs;
    assert_int_equal(glow__charts_segment(&s, NULL, &log, &cs), GLOW_OK);
    assert_int_equal(cs.chart_count, 200);
    for (uint32_t c = 0; c < cs.chart_count; ++c) assert_true(fabs(fabs(cs.normal[c][1]) - 1.0) < 1e-9);
    glow__charts_free(&cs);

    /* 2 texels per m: the 1 m square spans at most 3 x 3 cells a side, twice (up and down) */
    report r = run(&s, 2.0f, 2, NULL, NULL);
    print_message("small charts: 200 tiles at 2 texels/m: %u footprints, %u shared texels\n", r.slots, r.merged);
    assert_true(r.slots <= 18 && r.slots >= 2);
    assert_true(r.merged >= 2);
    /* no footprint mixes up- and down-facing tiles */
    assert_int_equal(glow__charts_segment(&s, NULL, &log, &cs), GLOW_OK);
    uint32_t *unit_of = malloc(cs.chart_count * sizeof *unit_of);
    float(*uv)[2] = malloc(3 * (size_t)s.tri_count * sizeof *uv);
    assert_non_null(unit_of);
    assert_non_null(uv);
    glow__chart_pack_stats st = {.unit_of = unit_of};
    uint32_t w, h;
    float used;
    assert_int_equal(glow__charts_pack(&cs, 2.0f, 2, &log, uv, &w, &h, &used, &st), GLOW_OK);
    assert_int_equal(st.small, 200);
    for (uint32_t a = 0; a < cs.chart_count; ++a)
        for (uint32_t c = 0; c < cs.chart_count; ++c)
            if (unit_of[a] == unit_of[c]) assert_true(cs.normal[a][1] * cs.normal[c][1] > 0.0);
    /* 40 texels per m: a 5 cm tile is 2 texels wide, no longer small */
    assert_int_equal(glow__charts_pack(&cs, 40.0f, 2, &log, uv, &w, &h, &used, &st), GLOW_OK);
    assert_int_equal(st.small, 0);
    assert_int_equal(st.slots, 200);
    r = run(&s, 40.0f, 2, NULL, NULL);
    assert_int_equal(r.merged, 0);
    free(unit_of);
    free(uv);
    glow__charts_free(&cs);
    scene_free(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cube_six_charts),  cmocka_unit_test(test_mixed_scene),
        cmocka_unit_test(test_spiral_is_split),  cmocka_unit_test(test_huge_chart_reduces_density),
        cmocka_unit_test(test_bad_density_rejected), cmocka_unit_test(test_messy_topology),
        cmocka_unit_test(test_60k_triangles),    cmocka_unit_test(test_sponza),
        cmocka_unit_test(test_small_charts_merge), cmocka_unit_test(test_pages),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
