/* builtin.c — procedural test scenes ("builtin:cornell", "builtin:furnace", "builtin:two-rooms",
 * "builtin:pillar-hall", "builtin:pillar-court", "builtin:wall-gap").
 *
 * Metres, +Y up, counter-clockwise front faces (geometric normal (p1-p0)x(p2-p0)). Room walls face
 * into the rooms, solid blocks face outwards. Every quad is two triangles (p0,p1,p2), (p0,p2,p3).
 * Faces of one closed shell are cut along shared grid lines, so every edge of a closed shell is
 * shared by exactly two triangles (no T-junctions). Normals are generated (flat) by
 * glow__scene_finalize, which every builtin goes through. Only builtin:cornell has material UVs
 * (cornell_uvs): its lamp spans [0,1]² so that a host can drive it with an emission texture
 * (glow_system_set_emission_texture; samples/01_cornell); the others have none. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pc_internal.h"

typedef struct builder {
    uint32_t count, cap;
    float (*pos)[3];
    uint32_t *mat;
    bool failed;
} builder;

static void add_tri(builder *b, const float p0[3], const float p1[3], const float p2[3], uint32_t mat) {
    if (b->failed) return;
    if (b->count == b->cap) {
        uint32_t cap = b->cap ? 2 * b->cap : 64;
        void *np = realloc(b->pos, (size_t)cap * 3 * sizeof *b->pos);
        if (!np) {
            b->failed = true;
            return;
        }
        b->pos = np;
        void *nm = realloc(b->mat, (size_t)cap * sizeof *b->mat);
        if (!nm) {
            b->failed = true;
            return;
        }
        b->mat = nm;
        b->cap = cap;
    }
    memcpy(b->pos[3 * (size_t)b->count + 0], p0, sizeof(float[3]));
    memcpy(b->pos[3 * (size_t)b->count + 1], p1, sizeof(float[3]));
    memcpy(b->pos[3 * (size_t)b->count + 2], p2, sizeof(float[3]));
    b->mat[b->count++] = mat;
}

/* Quad p0..p3 (a planar convex loop), wound so that its normal points along `facing`. */
static void add_quad_facing(builder *b, const float p0[3], const float p1[3], const float p2[3], const float p3[3],
                            const float facing[3], uint32_t mat) {
    float e1[3], e2[3], n[3];
    glow__sub(p1, p0, e1);
    glow__sub(p2, p0, e2);
    glow__cross(e1, e2, n);
    if (glow__dot(n, facing) >= 0.0f) {
        add_tri(b, p0, p1, p2, mat);
        add_tri(b, p0, p2, p3, mat);
    } else {
        add_tri(b, p0, p3, p2, mat);
        add_tri(b, p0, p2, p1, mat);
    }
}

/* An axis-aligned box shell cut along the grid lines splits[axis][0..n[axis]-1] (ascending, the
 * first and last are the box's extent). inward: faces point into the box (a room), else out.
 * face_mat[2*axis + side] (side 0 = min, 1 = max). An optional emitter cell: the cell of face
 * `light_face` whose lower corner (in the face's two other axes, in axis order) equals
 * light_lo gets light_mat. */
typedef struct box_desc {
    const float *splits[3];
    uint32_t n[3];
    bool inward;
    uint32_t face_mat[6];
    int light_face; /* -1 = none */
    float light_lo[2], light_hi[2];
    uint32_t light_mat;
    uint32_t skip_faces; /* bit 2*axis + side: that face is left out (an open shell); 0 = a closed box */
} box_desc;

static void add_box(builder *b, const box_desc *d) {
    for (int axis = 0; axis < 3; axis++) {
        int ua = (axis + 1) % 3, va = (axis + 2) % 3;
        int lo_a = ua < va ? ua : va, hi_a = ua < va ? va : ua; /* the face's axes in x, y, z order */
        for (int side = 0; side < 2; side++) {
            int face = 2 * axis + side;
            if (d->skip_faces >> face & 1u) continue;
            float coord = d->splits[axis][side ? d->n[axis] - 1 : 0];
            float facing[3] = {0.0f, 0.0f, 0.0f};
            facing[axis] = (side ? 1.0f : -1.0f) * (d->inward ? -1.0f : 1.0f);
            for (uint32_t i = 0; i + 1 < d->n[ua]; i++) {
                for (uint32_t j = 0; j + 1 < d->n[va]; j++) {
                    float p[4][3];
                    float u0 = d->splits[ua][i], u1 = d->splits[ua][i + 1];
                    float v0 = d->splits[va][j], v1 = d->splits[va][j + 1];
                    const float uu[4] = {u0, u1, u1, u0}, vv[4] = {v0, v0, v1, v1};
                    for (int k = 0; k < 4; k++) {
                        p[k][axis] = coord;
                        p[k][ua] = uu[k];
                        p[k][va] = vv[k];
                    }
                    uint32_t mat = d->face_mat[face];
                    if (face == d->light_face) {
                        float cell_lo[3], cell_hi[3]; /* the cell's extent along x, y, z */
                        cell_lo[axis] = cell_hi[axis] = coord;
                        cell_lo[ua] = u0;
                        cell_hi[ua] = u1;
                        cell_lo[va] = v0;
                        cell_hi[va] = v1;
                        if (cell_lo[lo_a] == d->light_lo[0] && cell_lo[hi_a] == d->light_lo[1] &&
                            cell_hi[lo_a] == d->light_hi[0] && cell_hi[hi_a] == d->light_hi[1])
                            mat = d->light_mat;
                    }
                    add_quad_facing(b, p[0], p[1], p[2], p[3], facing, mat);
                }
            }
        }
    }
}

/* A solid block standing on y = 0: square footprint (half-size `half`) centred on (cx, cz),
 * rotated by `angle` about +Y, `height` tall; 4 sides and a top facing out, no bottom. */
static void add_block(builder *b, float cx, float cz, float half, float height, float angle, uint32_t mat) {
    float ca = cosf(angle), sa = sinf(angle);
    float ax[2] = {ca * half, sa * half}, az[2] = {-sa * half, ca * half};
    const float sx[4] = {1.0f, 1.0f, -1.0f, -1.0f}, sz[4] = {1.0f, -1.0f, -1.0f, 1.0f};
    float lo[4][3], hi[4][3];
    for (int k = 0; k < 4; k++) {
        lo[k][0] = hi[k][0] = cx + sx[k] * ax[0] + sz[k] * az[0];
        lo[k][2] = hi[k][2] = cz + sx[k] * ax[1] + sz[k] * az[1];
        lo[k][1] = 0.0f;
        hi[k][1] = height;
    }
    for (int k = 0; k < 4; k++) {
        int l = (k + 1) & 3;
        float out[3] = {0.5f * (lo[k][0] + lo[l][0]) - cx, 0.0f, 0.5f * (lo[k][2] + lo[l][2]) - cz};
        add_quad_facing(b, lo[k], lo[l], hi[l], hi[k], out, mat);
    }
    const float up[3] = {0.0f, 1.0f, 0.0f};
    add_quad_facing(b, hi[0], hi[1], hi[2], hi[3], up, mat);
}

static void set_material(glow__material *m, const char *name, float r, float g, float bl, float e0, float e1,
                         float e2) {
    snprintf(m->name, sizeof m->name, "%s", name);
    m->albedo[0] = r;
    m->albedo[1] = g;
    m->albedo[2] = bl;
    m->emission[0] = e0;
    m->emission[1] = e1;
    m->emission[2] = e2;
    m->texture = -1;
}

enum { CB_FLOOR, CB_CEILING, CB_BACK, CB_FRONT, CB_LEFT, CB_RIGHT, CB_SHORT, CB_TALL, CB_LIGHT, CB_COUNT };

/* McGuire-style 2 m Cornell box, closed on all six sides (a closed room keeps every ray inside,
 * which the tests and the grid-cache inside/outside logic like better than the open original). */
static void build_cornell(builder *b, glow__material *m) {
    const float white[3] = {0.725f, 0.71f, 0.68f};
    set_material(&m[CB_FLOOR], "floor", white[0], white[1], white[2], 0, 0, 0);
    set_material(&m[CB_CEILING], "ceiling", white[0], white[1], white[2], 0, 0, 0);
    set_material(&m[CB_BACK], "back", white[0], white[1], white[2], 0, 0, 0);
    set_material(&m[CB_FRONT], "front", white[0], white[1], white[2], 0, 0, 0);
    set_material(&m[CB_LEFT], "left", 0.63f, 0.065f, 0.05f, 0, 0, 0);
    set_material(&m[CB_RIGHT], "right", 0.14f, 0.45f, 0.091f, 0, 0, 0);
    set_material(&m[CB_SHORT], "short", white[0], white[1], white[2], 0, 0, 0);
    set_material(&m[CB_TALL], "tall", white[0], white[1], white[2], 0, 0, 0);
    set_material(&m[CB_LIGHT], "light", 0.78f, 0.78f, 0.78f, 17.0f, 12.0f, 4.0f);

    static const float xs[2] = {-1.0f, 1.0f}, ys[2] = {0.0f, 2.0f}, zs[2] = {-1.0f, 1.0f};
    box_desc room = {.splits = {xs, ys, zs},
                     .n = {2, 2, 2},
                     .inward = true,
                     .face_mat = {CB_LEFT, CB_RIGHT, CB_FLOOR, CB_CEILING, CB_BACK, CB_FRONT},
                     .light_face = -1};
    add_box(b, &room);
    /* blocks placed and turned as in CornellBox-Original.obj (0.6 m footprints, ~17 degrees) */
    add_block(b, 0.33f, 0.37f, 0.3f, 0.6f, atan2f(0.17f, 0.57f), CB_SHORT);
    add_block(b, -0.335f, -0.29f, 0.3f, 1.2f, atan2f(-0.18f, 0.57f), CB_TALL);
    /* emitter 2 cm below the ceiling, facing down */
    const float l0[3] = {-0.24f, 1.98f, -0.22f}, l1[3] = {0.24f, 1.98f, -0.22f};
    const float l2[3] = {0.24f, 1.98f, 0.22f}, l3[3] = {-0.24f, 1.98f, 0.22f};
    const float down[3] = {0.0f, -1.0f, 0.0f};
    add_quad_facing(b, l0, l1, l2, l3, down, CB_LIGHT);
}

/* builtin:cornell's material UVs: the lamp (material CB_LIGHT) spans [0,1]² with u along +x and v
 * along +z (u = (x + 0.24) / 0.48, v = (z + 0.22) / 0.44); every other face is box-mapped in metres
 * (the two axes other than its normal's largest, 0.5 u per metre about the box's centre, so the 2 m
 * room spans [0,1]). Untextured materials ignore them. false: out of memory. */
static bool cornell_uvs(glow__scene *s) {
    s->uv0 = malloc((size_t)s->tri_count * 3 * sizeof *s->uv0);
    if (!s->uv0) return false;
    for (uint32_t t = 0; t < s->tri_count; t++) {
        const float *p0 = s->pos[3 * (size_t)t], *p1 = s->pos[3 * (size_t)t + 1], *p2 = s->pos[3 * (size_t)t + 2];
        float e1[3], e2[3], n[3];
        glow__sub(p1, p0, e1);
        glow__sub(p2, p0, e2);
        glow__cross(e1, e2, n);
        int axis = fabsf(n[0]) >= fabsf(n[1]) && fabsf(n[0]) >= fabsf(n[2]) ? 0 : fabsf(n[1]) >= fabsf(n[2]) ? 1 : 2;
        int ua = axis == 0 ? 2 : 0, va = axis == 1 ? 2 : 1;
        for (int k = 0; k < 3; k++) {
            const float *p = s->pos[3 * (size_t)t + k];
            float *uv = s->uv0[3 * (size_t)t + k];
            if (s->tri_material[t] == CB_LIGHT) {
                uv[0] = (p[0] + 0.24f) / 0.48f;
                uv[1] = (p[2] + 0.22f) / 0.44f;
            } else {
                uv[0] = 0.5f + 0.5f * p[ua];
                uv[1] = 0.5f + 0.5f * (p[va] - (va == 1 ? 1.0f : 0.0f));
            }
        }
    }
    return true;
}

/* White furnace: a closed cube, uniformly emissive and grey; radiance inside converges to
 * E / (1 - albedo) = 2 everywhere. */
static void build_furnace(builder *b, glow__material *m) {
    set_material(&m[0], "wall", 0.5f, 0.5f, 0.5f, 1.0f, 1.0f, 1.0f);
    static const float s[5] = {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f};
    box_desc cube = {.splits = {s, s, s}, .n = {5, 5, 5}, .inward = true, .face_mat = {0, 0, 0, 0, 0, 0}, .light_face = -1};
    add_box(b, &cube);
}

/* Two closed 4 x 2.5 x 4 m rooms along x, 0.1 m apart. The gap is the separating wall: room A's
 * +x wall (x = -0.05, facing -x into A) and room B's -x wall (x = +0.05, facing +x into B) are its
 * two faces, each pointing out of the wall into its room. The wall's top, bottom and end caps are
 * not modelled: they would face away from both rooms and break the rooms' edge-manifoldness.
 * Light: a 1 x 1 m cell of room A's ceiling, cut into the ceiling's grid (no T-junctions). */
static void build_two_rooms(builder *b, glow__material *m) {
    set_material(&m[0], "wall", 0.7f, 0.7f, 0.7f, 0, 0, 0);
    set_material(&m[1], "light", 0.7f, 0.7f, 0.7f, 10.0f, 10.0f, 10.0f);
    static const float xa[4] = {-4.05f, -2.55f, -1.55f, -0.05f}, xb[4] = {0.05f, 1.55f, 2.55f, 4.05f};
    static const float ys[3] = {0.0f, 1.25f, 2.5f}, zs[4] = {-2.0f, -0.5f, 0.5f, 2.0f};
    box_desc a = {.splits = {xa, ys, zs},
                  .n = {4, 3, 4},
                  .inward = true,
                  .face_mat = {0, 0, 0, 0, 0, 0},
                  .light_face = 3, /* +y (ceiling); its cells span x (lo axis) and z (hi axis) */
                  .light_lo = {-2.55f, -0.5f},
                  .light_hi = {-1.55f, 0.5f},
                  .light_mat = 1};
    add_box(b, &a);
    box_desc rb = {.splits = {xb, ys, zs}, .n = {4, 3, 4}, .inward = true, .face_mat = {0, 0, 0, 0, 0, 0}, .light_face = -1};
    add_box(b, &rb);
}

/* A hall with a row of pillars down its middle and a bench standing on its floor: the failures of
 * real architecture in miniature (issue 13). Lit from one side (scenes/pillar-hall.json: a point
 * light near the -z wall), every cache on the far side sees pillars whose lit and unlit faces the
 * hierarchy may cluster together (partly visible nodes), and the bench's foot and the pillars' feet
 * meet the floor (contact leaks). "pillar-court" is the same without its ceiling: an open shell lit
 * by a sun and sky (scenes/pillar-court.json), where the hidden side of a node is the sunlit outside.
 * The hall is 12 x 3.5 x 6 m; five 0.5 m pillars 3.3 m tall (clear of the ceiling: no coplanar
 * faces); a 0.8 x 0.45 x 0.8 m bench. */
static void build_pillars(builder *b, glow__material *m, bool ceiling) {
    set_material(&m[0], "wall", 0.7f, 0.7f, 0.7f, 0, 0, 0);
    set_material(&m[1], "floor", 0.6f, 0.55f, 0.5f, 0, 0, 0);
    set_material(&m[2], "pillar", 0.75f, 0.72f, 0.68f, 0, 0, 0);
    set_material(&m[3], "bench", 0.5f, 0.3f, 0.2f, 0, 0, 0);
    static const float xs[7] = {-6.0f, -4.0f, -2.0f, 0.0f, 2.0f, 4.0f, 6.0f}, ys[3] = {0.0f, 1.75f, 3.5f};
    static const float zs[5] = {-3.0f, -1.5f, 0.0f, 1.5f, 3.0f};
    box_desc hall = {.splits = {xs, ys, zs},
                     .n = {7, 3, 5},
                     .inward = true,
                     .face_mat = {0, 0, 1, 0, 0, 0},
                     .light_face = -1,
                     .skip_faces = ceiling ? 0u : 1u << 3}; /* +y: the ceiling */
    add_box(b, &hall);
    for (int k = -2; k <= 2; k++) add_block(b, 2.0f * (float)k, 0.0f, 0.25f, 3.3f, 0.0f, 2);
    add_block(b, -3.0f, 1.8f, 0.4f, 0.45f, 0.0f, 3);
}
/* A thin wall with a gap (issue 13): one closed 8 x 2.5 x 4 m room split at x = 0 by a 0.1 m wall
 * that stands on the floor and meets the ceiling (no top face: the wall's sides end at the ceiling,
 * a contact as exporters leave it) and stops 1 m short of the +z wall, leaving a doorway. Lit in the
 * -x half (scenes/wall-gap.json), the +x half gets light only through the gap; caches and texels next
 * to the wall on the +x side must not read the -x side's light through the wall (the wall is thinner
 * than a texel, a grid cell and a surfel). */
static void build_wall_gap(builder *b, glow__material *m) {
    set_material(&m[0], "wall", 0.7f, 0.7f, 0.7f, 0, 0, 0);
    set_material(&m[1], "floor", 0.6f, 0.55f, 0.5f, 0, 0, 0);
    set_material(&m[2], "partition", 0.75f, 0.72f, 0.68f, 0, 0, 0);
    static const float xs[5] = {-4.0f, -2.0f, 0.0f, 2.0f, 4.0f}, ys[3] = {0.0f, 1.25f, 2.5f};
    static const float zs[5] = {-2.0f, -1.0f, 0.0f, 1.0f, 2.0f};
    box_desc room = {.splits = {xs, ys, zs}, .n = {5, 3, 5}, .inward = true, .face_mat = {0, 0, 1, 0, 0, 0},
                     .light_face = -1};
    add_box(b, &room);
    const float x0 = -0.05f, x1 = 0.05f, z0 = -2.0f, z1 = 1.0f, h = 2.5f;
    const float a[3] = {x0, 0.0f, z0}, bq[3] = {x0, 0.0f, z1}, c[3] = {x0, h, z1}, d[3] = {x0, h, z0};
    const float e[3] = {x1, 0.0f, z0}, f[3] = {x1, 0.0f, z1}, g[3] = {x1, h, z1}, k[3] = {x1, h, z0};
    const float mx[3] = {-1.0f, 0.0f, 0.0f}, px[3] = {1.0f, 0.0f, 0.0f}, pz[3] = {0.0f, 0.0f, 1.0f};
    add_quad_facing(b, a, bq, c, d, mx, 2); /* the -x face */
    add_quad_facing(b, e, f, g, k, px, 2);  /* the +x face */
    add_quad_facing(b, bq, f, g, c, pz, 2); /* the end at the doorway */
}
static void build_pillar_hall(builder *b, glow__material *m) { build_pillars(b, m, true); }
static void build_pillar_court(builder *b, glow__material *m) { build_pillars(b, m, false); }

glow_result glow__scene_builtin(const char *name, glow__log *log, glow__scene *out) {
    if (!out) return GLOW_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!name) name = "";
    uint32_t material_count;
    void (*build)(builder *, glow__material *);
    if (strcmp(name, "cornell") == 0) {
        material_count = CB_COUNT;
        build = build_cornell;
    } else if (strcmp(name, "furnace") == 0) {
        material_count = 1;
        build = build_furnace;
    } else if (strcmp(name, "two-rooms") == 0) {
        material_count = 2;
        build = build_two_rooms;
    } else if (strcmp(name, "pillar-hall") == 0) {
        material_count = 4;
        build = build_pillar_hall;
    } else if (strcmp(name, "pillar-court") == 0) {
        material_count = 4;
        build = build_pillar_court;
    } else if (strcmp(name, "wall-gap") == 0) {
        material_count = 3;
        build = build_wall_gap;
    } else {
        glow__errorf(log, "builtin:%s: unknown built-in scene (valid: builtin:cornell, builtin:furnace, builtin:two-rooms, "
                     "builtin:pillar-hall, builtin:pillar-court, builtin:wall-gap)", name);
        return GLOW_ERROR_UNSUPPORTED;
    }
    snprintf(out->source, sizeof out->source, "builtin:%s", name);
    out->materials = calloc(material_count, sizeof *out->materials);
    if (!out->materials) {
        glow__errorf(log, "%s: out of memory", out->source);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    out->material_count = material_count;
    builder b = {0};
    build(&b, out->materials);
    out->pos = b.pos;
    out->tri_material = b.mat;
    out->tri_count = b.count;
    if (b.failed) {
        glow__errorf(log, "%s: out of memory", out->source);
        glow__scene_free(out);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    out->source_tri_count = b.count;
    if (build == build_cornell && !cornell_uvs(out)) {
        glow__errorf(log, "%s: out of memory", out->source);
        glow__scene_free(out);
        return GLOW_ERROR_OUT_OF_MEMORY;
    }
    glow_result r = glow__scene_finalize(out, log);
    if (r != GLOW_OK) glow__scene_free(out);
    return r;
}
