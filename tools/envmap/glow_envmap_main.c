/* glow_envmap_main.c — glow-envmap: HDR environment maps from the command line (tools/eval/glow_envmap.h,
 * docs/envmap.md). `sky` writes a simple lat-long sky with a sun disc (glow-eval skymap runs it); `info`
 * prints a map's integral, its SH l <= 2 projection and its sun split as JSON, and can write the residual. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glow_cli.h"
#include "glow_envmap.h"

#define TOOL "glow-envmap"

static void usage(FILE *f) {
    fprintf(f,
            "usage: glow-envmap sky --out SKY.exr [--width W] [--sun-elevation DEG] [--sun-azimuth DEG]\n"
            "                       [--sun-radius DEG] [--sun-irradiance R,G,B] [--sun-scale S]\n"
            "                       [--zenith R,G,B] [--horizon R,G,B] [--ground R,G,B]\n"
            "       glow-envmap info MAP.exr [--rotation DEG] [--scale S] [--sun-max-radius DEG]\n"
            "                       [--sun-threshold T] [--residual OUT.exr]\n"
            "sky: an equirectangular sky, W x W/2 (default 512), Y up (docs/envmap.md): a gradient from the\n"
            "  horizon colour (default 0.45,0.5,0.55 W/(m2 sr)) to the zenith's (0.2,0.3,0.55), constant ground\n"
            "  below the horizon (0.08,0.07,0.06), and a sun disc of --sun-radius degrees (default 0.5) whose\n"
            "  radiance integrates to --sun-irradiance W/m2 (default 9,8.5,7.5; times --sun-scale, default 1;\n"
            "  0 = no sun), at --sun-elevation (default 35) and --sun-azimuth (default 30: degrees from -Z, the\n"
            "  image centre, towards +X).\n"
            "info: JSON on stdout: size, the integral of L over the sphere (W/m2), the 9 RGB SH coefficients\n"
            "  (runtime convention, rotation and scale applied) and the sun split (direction towards the sun,\n"
            "  irradiance W/m2, radius), and irradiance_check: at 64 normals, the largest error of the irradiance from\n"
            "  the map's SH9 alone and from the residual's SH9 + the sun as a directional light, relative to the\n"
            "  largest irradiance; --residual writes the map with the sun's texels replaced (texels before scale).\n");
}

static int parse3(const char *s, float out[3]) {
    if (!s) return 0;
    char buf[128];
    snprintf(buf, sizeof buf, "%s", s);
    char *save = NULL, *tok = strtok_r(buf, ",", &save);
    for (int k = 0; k < 3; ++k) {
        if (!tok || !glow_cli_float(tok, &out[k]) || out[k] < 0.0f) return 0;
        tok = strtok_r(NULL, ",", &save);
    }
    return tok == NULL;
}

static int cmd_sky(int argc, char **argv) {
    glow_eval_skymap_params p = glow_eval_skymap_defaults();
    const char *out = NULL;
    float sun_scale = 1.0f;
    for (int i = 2; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int ok = 1;
        if (!strcmp(a, "--out")) out = v;
        else if (!strcmp(a, "--width")) ok = glow_cli_u32(v, 4, 16384, &p.width) && p.width % 2 == 0;
        else if (!strcmp(a, "--sun-elevation")) ok = glow_cli_float(v, &p.sun_elevation_deg);
        else if (!strcmp(a, "--sun-azimuth")) ok = glow_cli_float(v, &p.sun_azimuth_deg);
        else if (!strcmp(a, "--sun-radius")) ok = glow_cli_float(v, &p.sun_radius_deg);
        else if (!strcmp(a, "--sun-scale")) ok = glow_cli_float(v, &sun_scale) && sun_scale >= 0.0f;
        else if (!strcmp(a, "--sun-irradiance")) ok = parse3(v, p.sun_irradiance);
        else if (!strcmp(a, "--zenith")) ok = parse3(v, p.zenith);
        else if (!strcmp(a, "--horizon")) ok = parse3(v, p.horizon);
        else if (!strcmp(a, "--ground")) ok = parse3(v, p.ground);
        else return glow_cli_usage_error(TOOL, "sky: unknown option %s", a);
        if (!ok || !v) return glow_cli_usage_error(TOOL, "sky: %s needs a valid value, not \"%s\"", a, v ? v : "nothing");
        ++i;
    }
    if (!out || !out[0]) return glow_cli_usage_error(TOOL, "sky: --out SKY.exr is required");
    for (int k = 0; k < 3; ++k) p.sun_irradiance[k] *= sun_scale;
    glow_eval_image img;
    char msg[512];
    if (glow_eval_skymap(&p, &img, msg, sizeof msg) != GLOW_OK) return glow_cli_usage_error(TOOL, "%s", msg);
    glow_result r = glow_eval_write_exr(&img, out, msg, sizeof msg);
    glow_eval_image_free(&img);
    if (r != GLOW_OK) {
        fprintf(stderr, TOOL ": %s\n", msg);
        return 1;
    }
    printf("%s: %ux%u sky, sun %g,%g,%g W/m2 at elevation %g, azimuth %g, radius %g deg\n", out, (unsigned)p.width,
           (unsigned)p.width / 2, (double)p.sun_irradiance[0], (double)p.sun_irradiance[1], (double)p.sun_irradiance[2],
           (double)p.sun_elevation_deg, (double)p.sun_azimuth_deg, (double)p.sun_radius_deg);
    return 0;
}

static int cmd_info(int argc, char **argv) {
    const char *path = NULL, *residual = NULL;
    float rot = 0.0f, scale = 1.0f;
    glow_eval_envmap_sun_params sp = {0};
    for (int i = 2; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (a[0] != '-') {
            if (path) return glow_cli_usage_error(TOOL, "info: one map, not %s and %s", path, a);
            path = a;
            continue;
        }
        int ok = 1;
        if (!strcmp(a, "--rotation")) ok = glow_cli_float(v, &rot);
        else if (!strcmp(a, "--scale")) ok = glow_cli_float(v, &scale) && scale >= 0.0f;
        else if (!strcmp(a, "--sun-max-radius")) ok = glow_cli_float(v, &sp.max_radius_deg) && sp.max_radius_deg > 0.0f;
        else if (!strcmp(a, "--sun-threshold")) ok = glow_cli_float(v, &sp.threshold) && sp.threshold >= 1.0f;
        else if (!strcmp(a, "--residual")) ok = v && v[0];
        else return glow_cli_usage_error(TOOL, "info: unknown option %s", a);
        if (!ok || !v) return glow_cli_usage_error(TOOL, "info: %s needs a valid value, not \"%s\"", a, v ? v : "nothing");
        if (!strcmp(a, "--residual")) residual = v;
        ++i;
    }
    if (!path) return glow_cli_usage_error(TOOL, "info: which map? (glow-envmap info MAP.exr)");
    glow_eval_envmap m, res;
    char msg[600];
    if (glow_eval_envmap_load(path, rot, scale, &m, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, TOOL ": %s\n", msg);
        return 1;
    }
    glow_eval_envmap_sun sun;
    if (glow_eval_envmap_extract_sun(&m, &sp, &sun, &res, msg, sizeof msg) != GLOW_OK) {
        fprintf(stderr, TOOL ": %s\n", msg);
        glow_eval_envmap_free(&m);
        return 1;
    }
    double I[3], sh[27];
    glow_eval_envmap_integral(&m, I);
    glow_eval_envmap_sh9(&m, sh);
    printf("{\"map\": \"%s\", \"width\": %u, \"height\": %u, \"rotation_deg\": %g, \"scale\": %g,\n", path,
           (unsigned)m.width, (unsigned)m.height, (double)rot, (double)scale);
    printf(" \"integral\": [%.6g, %.6g, %.6g],\n \"sh9\": [", I[0], I[1], I[2]);
    for (int k = 0; k < 9; ++k)
        printf("%s[%.6g, %.6g, %.6g]", k ? ", " : "", sh[3 * k], sh[3 * k + 1], sh[3 * k + 2]);
    printf("],\n \"sun\": {\"found\": %s, \"to_sun\": [%.6f, %.6f, %.6f], \"irradiance\": [%.6g, %.6g, %.6g],"
           " \"radius_deg\": %.4g, \"solid_angle_sr\": %.6g, \"texels\": %u, \"background\": [%.6g, %.6g, %.6g]},\n",
           sun.found ? "true" : "false", (double)sun.to_sun[0], (double)sun.to_sun[1], (double)sun.to_sun[2],
           (double)sun.irradiance[0], (double)sun.irradiance[1], (double)sun.irradiance[2], (double)sun.radius_deg,
           (double)sun.solid_angle_sr, (unsigned)sun.texel_count, (double)sun.background[0], (double)sun.background[1],
           (double)sun.background[2]);
    /* how well engines' split lights it: irradiance at 64 normals (a Fibonacci sphere), exact vs the map's
     * SH9 alone and vs the residual's SH9 + the sun as a directional light; the worst relative error
     * of the luminance, relative to the largest exact irradiance (normals facing away from the sun get
     * almost nothing, a relative error there says little) */
    double rsh[27], worst_map = 0.0, worst_split = 0.0, emax = 0.0, ex[64], em[64], es[64];
    glow_eval_envmap_sh9(&res, rsh);
    for (int i = 0; i < 64; ++i) {
        const double zc = 1.0 - (2.0 * i + 1.0) / 64.0, r = sqrt(1.0 - zc * zc), ph = 2.399963229728653 * i;
        const float n[3] = {(float)(r * cos(ph)), (float)zc, (float)(r * sin(ph))};
        double e[3], a[3], b[3];
        glow_eval_envmap_irradiance(&m, n, e);
        glow_eval_sh9_irradiance(sh, n, a);
        glow_eval_sh9_irradiance(rsh, n, b);
        const double c = sun.found ? fmax(0.0, n[0] * sun.to_sun[0] + n[1] * sun.to_sun[1] + n[2] * sun.to_sun[2]) : 0.0;
        for (int k = 0; k < 3; ++k) b[k] += c * sun.irradiance[k];
        ex[i] = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
        em[i] = 0.2126 * a[0] + 0.7152 * a[1] + 0.0722 * a[2];
        es[i] = 0.2126 * b[0] + 0.7152 * b[1] + 0.0722 * b[2];
        emax = fmax(emax, ex[i]);
    }
    for (int i = 0; i < 64; ++i) {
        worst_map = fmax(worst_map, fabs(em[i] - ex[i]) / fmax(emax, 1e-30));
        worst_split = fmax(worst_split, fabs(es[i] - ex[i]) / fmax(emax, 1e-30));
    }
    printf(" \"irradiance_check\": {\"normals\": 64, \"max_exact\": %.6g, \"sh9_error\": %.4f, \"residual_sh9_plus_sun_error\": %.4f}}\n",
           emax, worst_map, worst_split);
    int rc = 0;
    if (residual) {
        glow_eval_image img = {.width = res.width, .height = res.height, .rgb = res.rgb};
        if (glow_eval_write_exr(&img, residual, msg, sizeof msg) != GLOW_OK) {
            fprintf(stderr, TOOL ": %s\n", msg);
            rc = 1;
        }
    }
    glow_eval_envmap_free(&res);
    glow_eval_envmap_free(&m);
    return rc;
}

int main(int argc, char **argv) {
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "sky")) return cmd_sky(argc, argv);
    if (!strcmp(argv[1], "info")) return cmd_info(argc, argv);
    return glow_cli_usage_error(TOOL, "unknown command %s (sky, info)", argv[1]);
}
