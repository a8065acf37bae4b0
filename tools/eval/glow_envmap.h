/*
 * glow_envmap.h — HDR environment maps for the evaluation tools (glow-render, glow-envmap, their tests):
 * loading an equirectangular (latitude-longitude) OpenEXR sky, looking it up by direction, importance
 * sampling it (with the pdf MIS needs), projecting it into real SH l <= 2 and splitting it into a
 * directional sun and a smooth rest. Tool code (tools/eval/, target glow_eval), not part of the runtime:
 * it allocates with malloc and does no threading of its own. docs/envmap.md has the derivations and the
 * measurements.
 *
 * ORIENTATION (scenes are Y-up; the scene key "environment_map", docs/scene-format.md). Texel (i, j) of a
 * W x H image (W = 2H; i the column from the left, j the row from the top) covers
 *     u = i/W .. (i+1)/W,   v = j/H .. (j+1)/H,   φ = 2π u,   θ = π v   (θ from +Y),
 * and the direction of (θ, φ) in the map's frame is
 *     d = (-sin θ sin φ,  cos θ,  sin θ cos φ):
 * the top row looks up (+Y), the bottom row down (-Y); u = 0 (and 1) faces +Z, u = 0.25 faces -X, the
 * centre column u = 0.5 faces -Z (the direction glow_scene_camera_default looks), u = 0.75 faces +X, so a
 * viewer inside looking along -Z with +Y up sees the image unmirrored, its centre straight ahead.
 * rotation_deg = α turns the map about +Y by the right-hand rule (+Z towards +X, +X towards -Z): the
 * world direction of map direction d is R_y(α) d, i.e. the map's φ = φ_world + α. A feature at u in
 * the image appears at world φ = 2π u - α.
 *
 * RADIANCE: texels are linear RGB radiance in W/(m²·sr), multiplied by `scale`. The map is
 * PIECEWISE CONSTANT: a direction's radiance is its texel's (nearest lookup, no filtering), so the
 * function the sampler draws from, the pdf, the SH projection, the integrals and the sun split all
 * describe exactly the function glow-render evaluates.
 *
 * SAMPLING: texels are drawn with probability ∝ Y · Ω (Y = 0.2126 R + 0.7152 G + 0.0722 B of the texel,
 * Ω its exact solid angle 2π/W · (cos θ_j - cos θ_{j+1}), the "luminance × sin θ" of the usual
 * formulation, integrated), by a marginal CDF over rows and a conditional CDF over each row's columns
 * (binary searches); the direction is then uniform in solid angle inside the texel (uniform φ and
 * cos θ). The solid-angle pdf is Y_texel / Σ Y Ω, constant over a texel and 0 where Y = 0.
 *
 * SH: real orthonormal SH l <= 2 in the runtime's convention (runtime/src/sh_kernel.h, glow_sh_eval;
 * DESIGN.md §3): index k = l² + l + m, no Condon-Shortley phase, evaluated on WORLD (x, y, z) (the
 * runtime's basis functions take world directions as they are: y_1^{-1} = c·y is the up axis here),
 *   y0 = 0.2820948, y1 = 0.4886025 y, y2 = 0.4886025 z, y3 = 0.4886025 x, y4 = 1.0925484 xy,
 *   y5 = 1.0925484 yz, y6 = 0.3153916 (3z² - 1), y7 = 1.0925484 xz, y8 = 0.5462742 (x² - y²).
 * c_k = ∫ L(ω) y_k(ω) dω, integrated exactly over each texel (closed forms of the monomials over the
 * texel's θ and φ ranges), rotation and scale applied.
 *
 * SUN SPLIT (glow_eval_envmap_extract_sun): see the struct below and docs/envmap.md.
 *
 * ON ERRORS: functions that can fail return a glow_result and write one line naming the file (or the
 * `name` given) and the problem into `message` (may be NULL): GLOW_ERROR_INVALID_ARGUMENT (NULL,
 * non-finite rotation, negative or non-finite scale, bad generator parameters), GLOW_ERROR_IO (cannot
 * open/read the file), GLOW_ERROR_CORRUPT_DATA (not an EXR, a layout glow_eval_read_exr refuses, an image
 * that is not 2:1 or smaller than 4 x 2, a negative or non-finite texel: "sky.exr: texel (12, 7)
 * channel G is -0.5 (negative)"), GLOW_ERROR_OUT_OF_MEMORY. Out-structs are zeroed on failure.
 * ON THREADS: a loaded map is read-only; lookups and samples may run on any number of threads.
 */
#ifndef GLOW_ENVMAP_H
#define GLOW_ENVMAP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "glow_eval.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct glow_eval_envmap {
    uint32_t width, height; /* width = 2 height */
    float *rgb;             /* owned: width * height * 3 texels as stored (before scale), top row first */
    float scale;            /* radiance = scale × texel */
    float rotation_deg;     /* about +Y, right-handed (see ORIENTATION) */
    double rot_rad;         /* rotation_deg in radians */
    double *cos_theta;      /* owned: [height + 1], cos(π j / H) */
    float *row_cdf;         /* owned: [height + 1] marginal CDF over rows (0 ... 1) */
    float *col_cdf;         /* owned: [height * (width + 1)] conditional CDF over each row's columns */
    double lum_integral;    /* Σ Y Ω over the texels (before scale); 0: nothing to sample */
} glow_eval_envmap;

/* Loads an RGB / RGBA (A ignored) / Y half or float, scanline or tiled OpenEXR (glow_eval_read_exr)
 * and builds the map (glow_eval_envmap_from_image). */
glow_result glow_eval_envmap_load(const char *path, float rotation_deg, float scale, glow_eval_envmap *out,
                                  char *message, size_t message_size);
/* Builds a map from a copy of img's texels; `name` names it in messages (NULL = "envmap"). */
glow_result glow_eval_envmap_from_image(const glow_eval_image *img, float rotation_deg, float scale, const char *name,
                                        glow_eval_envmap *out, char *message, size_t message_size);
/* Frees and zeroes (NULL and zeroed maps are no-ops). */
void glow_eval_envmap_free(glow_eval_envmap *map);

/* The world direction of image coordinates (u, v) in [0,1]² (rotation applied). */
void glow_eval_envmap_direction(const glow_eval_envmap *map, double u, double v, float out_dir[3]);
/* Radiance arriving from unit world direction dir (scale applied), W/(m²·sr). */
void glow_eval_envmap_eval(const glow_eval_envmap *map, const float dir[3], float out_rgb[3]);
/* Draws a direction from u1, u2 in [0, 1): out_dir (unit, world), out_rgb its radiance (scale applied);
 * returns the solid-angle pdf (0, with out_* zeroed, when the map has nothing to sample). */
float glow_eval_envmap_sample(const glow_eval_envmap *map, float u1, float u2, float out_dir[3], float out_rgb[3]);
/* The solid-angle pdf with which glow_eval_envmap_sample draws unit world direction dir. */
float glow_eval_envmap_pdf(const glow_eval_envmap *map, const float dir[3]);
/* ∫ L dω over the sphere (scale applied), W/m² ("the map's energy"; a uniform map L gives 4π L). */
void glow_eval_envmap_integral(const glow_eval_envmap *map, double out_rgb[3]);
/* The real SH l <= 2 projection: out[3 k + c] = c_k of channel c (R, G, B), k = 0..8 (see SH). */
void glow_eval_envmap_sh9(const glow_eval_envmap *map, double out[27]);

/* The irradiance on a surface with unit world normal n from the whole map, W/m²:
 * Σ L_texel max(0, n·d_texel) Ω_texel with d_texel the texel's centre direction (the cosine at the centre:
 * exact to O(texel²), no visibility). */
void glow_eval_envmap_irradiance(const glow_eval_envmap *map, const float n[3], double out_rgb[3]);
/* The irradiance at normal n of the SH l <= 2 radiance sh (glow_eval_envmap_sh9's layout): the clamped
 * cosine's zonal factors π, 2π/3, π/4 (Ramamoorthi & Hanrahan 2001). */
void glow_eval_sh9_irradiance(const double sh[27], const float n[3], double out_rgb[3]);

/* ---- Sun split ----
 * RULE: (1) the brightest texel (largest Y; the first in row-major order on a tie) and its centre
 * direction d0; (2) the surroundings: the texels whose centres lie between R and 2R from d0 (R =
 * max_radius_deg, raised to 2 texel heights when smaller), their solid-angle-weighted mean radiance
 * L_bg; (3) the sun's texels: centre within R of d0 and Y > threshold × Y(L_bg) (Y > 0 when L_bg is
 * black); no sun when the brightest texel itself is not above that; (4) each sun texel keeps
 * min(L, L_bg) per channel in the residual map (the surroundings' level: the sky behind the sun) and
 * gives the rest, L - min(L, L_bg), to the sun. So residual + sun = the map exactly, per channel:
 *   irradiance  = Σ (L - min(L, L_bg)) Ω over the sun texels (× scale): ∫ L_sun dω, the irradiance a
 *                 surface facing the sun receives from it to within 1 - cos(radius) (< 0.4 % for R = 5°),
 *   to_sun      = the direction of Σ Y(L - min(L, L_bg)) Ω · d_texel (the sun's luminance centroid),
 *   radius_deg  = the angular radius of the cap with the sun texels' total solid angle,
 *                 acos(1 - Ω_sun / 2π) (quantised to texels: an upper bound for a sub-texel sun).
 * Engines light the sun with a directional light and shadow maps and the residual, smooth, with SH. */
typedef struct glow_eval_envmap_sun_params {
    float max_radius_deg; /* R; 0 = 5 */
    float threshold;      /* 0 = 8: a sun texel is more than 8 times as bright as the surroundings */
} glow_eval_envmap_sun_params;

typedef struct glow_eval_envmap_sun {
    bool found;             /* false: no texel stands out (residual = the map) */
    float to_sun[3];        /* unit, world, towards the sun (a scene "sun" light's direction is -to_sun) */
    float irradiance[3];    /* W/m², scale applied (see RULE) */
    float radius_deg;       /* see RULE */
    float solid_angle_sr;   /* Ω_sun */
    uint32_t texel_count;
    float background[3];    /* L_bg, scale applied */
    float brightest[3];     /* the brightest texel's radiance, scale applied */
} glow_eval_envmap_sun;

/* Splits `map` by the RULE: *out_sun, and (optional, NULL = not wanted) *out_residual, a new map with the
 * same rotation and scale whose texels are the map's with the sun's replaced. params NULL = defaults. */
glow_result glow_eval_envmap_extract_sun(const glow_eval_envmap *map, const glow_eval_envmap_sun_params *params,
                                         glow_eval_envmap_sun *out_sun, glow_eval_envmap *out_residual, char *message,
                                         size_t message_size);

/* What a host that lights the sky with SH and the sun with shadows needs, in one call: with split false,
 * out_sh_rgb = the whole map's SH (no sun: *out_sun zeroed); with split true, the sun split by `params`
 * (NULL = defaults) into *out_sun and out_sh_rgb = the residual's SH. out_sh_rgb is float, 9 coefficients
 * x RGB, COEFFICIENT-MAJOR (out_sh_rgb[3 k + c]), the layout of glow_eval_envmap_sh9 and of the SH sky
 * the host side takes (issue 18: glow_host_set_environment_sh's sh_rgb); a constant `environment` is
 * not included (add its radiance × √(4π) to coefficient 0). out_sun may be NULL when split is false. */
glow_result glow_eval_envmap_sky_sh(const glow_eval_envmap *map, bool split, const glow_eval_envmap_sun_params *params,
                                    float out_sh_rgb[27], glow_eval_envmap_sun *out_sun, char *message,
                                    size_t message_size);

/* ---- A simple sky (glow-envmap sky, glow-eval skymap) ----
 * Above the horizon (direction d, d.y >= 0): horizon + (zenith - horizon) · d.y^0.4 (a smooth gradient,
 * brightest near the horizon when horizon > zenith); below: ground (constant). Plus a sun disc of
 * angular radius sun_radius_deg towards (sin az cos el, sin el, -cos az cos el) (azimuth from -Z, the
 * image centre, towards +X: u_sun = 0.5 + az/360, v_sun = 0.5 - el/180), whose radiance is spread
 * over the texels by their covered fraction (8 x 8 sub-samples) so that ∫ L_sun dω = sun_irradiance
 * exactly (a disc smaller than the sub-samples goes to the texel holding its centre). Rotation 0. */
typedef struct glow_eval_skymap_params {
    uint32_t width;           /* 0 = 512; height = width / 2; even, 4..16384 */
    float sun_elevation_deg;  /* [-90, 90] */
    float sun_azimuth_deg;    /* any finite value */
    float sun_radius_deg;     /* 0 = 0.5; (0, 45] */
    float sun_irradiance[3];  /* W/m², >= 0 (0: no sun) */
    float zenith[3], horizon[3], ground[3]; /* W/(m²·sr), >= 0 */
} glow_eval_skymap_params;

/* The defaults: 512 wide, sun at 35° elevation, azimuth 30°, radius 0.5°, irradiance (9, 8.5, 7.5);
 * zenith (0.2, 0.3, 0.55), horizon (0.45, 0.5, 0.55), ground (0.08, 0.07, 0.06). */
glow_eval_skymap_params glow_eval_skymap_defaults(void);
/* Renders the sky into *out (allocated here; zeroed on failure). INVALID_ARGUMENT on bad parameters. */
glow_result glow_eval_skymap(const glow_eval_skymap_params *params, glow_eval_image *out, char *message,
                             size_t message_size);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_ENVMAP_H */
