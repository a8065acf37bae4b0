/* 02_sponza — a real scene through a whole day: the Dabrovic Sponza atrium lit by a SUN that rises in
 * the east, crosses the sky and sets in the west (dimmer and warmer near the horizon, off below it),
 * under a SKY that follows it (blue by day, dark at night), and a flickering TORCH by a column, lit
 * from dusk to dawn (or switched with the T key).
 *
 * Both lights are GPU lights with shadow maps (glow_gl_lights.h). Whenever they change — every frame
 * here: the sun moves, the flame flickers — the sample hands them to glow_gl_lights_set, which
 * re-renders their maps: sun + torch, 2 lights; a sun below the horizon or a torch that is out is
 * simply not passed. The lights' GLSL hook then lights both Glow's surfels on the GPU (the bounce,
 * glow_gl.h) and the pixels on screen (samples/common/sample_gl.h): one light function for both.
 * Nothing else is needed for the indirect light to follow the day: Glow re-gathers it every update.
 *
 * Usage: sample-02_sponza BAKE [--scene JSON] [--day-seconds S] [--day-frames N] [--start-hour H]
 *        [--torch on|off|auto] [--torch-at X,Y,Z]  and the GL samples' options (--headless --frames N
 *        --out DIR --view V --width W --height H --exposure E --bounce B ...; --help lists them)
 *
 *   build/bin/glow-bake ../shared/scenes/sponza/dabrovic/sponza.obj -o /tmp/sponza.glow --quality low
 *   build/bin/sample-02_sponza /tmp/sponza.glow --scene ../shared/scenes/sponza/sponza-sun.json
 *   build/bin/sample-02_sponza /tmp/sponza.glow --headless --frames 8 --out /tmp/day    (a day in 8 PNGs)
 *
 * TIME OF DAY: hour = --start-hour (default 9) + 24 x elapsed / day length, where the day lasts
 * --day-seconds (default 60) of wall time in a window and --day-frames frames headless (default: the
 * run's --frames, so a headless run spans one day). Sunrise is at 6:00, noon at 12:00, sunset at 18:00.
 * Headless frames are hours apart while Glow adds one bounce per update: the previous frame's indirect
 * light fades over a few frames (at dusk the atrium stays bright a while). --iterations 4 brings each
 * frame close to converged, at 4x the update's cost; in a window, at real-time rates, the lag is not seen.
 * THE SUN: with --scene, the scene's first sun light is the sun at NOON (its direction and irradiance)
 * and its environment the day sky; its camera is used (other lights are not). Without --scene: noon
 * 70 degrees up towards -Z (east is +X), 9 W/m², a blue sky, and a camera inside the bounds at one end
 * of the longest horizontal axis looking along it (in Sponza the scene file's view; the GL samples'
 * glow_scene_camera_default view from outside would see Sponza's outer walls).
 * THE TORCH: a warm point light (W/sr, Sponza is in metres) 0.65 m in front of the column at x = -2.2,
 * z = 2.85 — placed as fractions of the bake's bounds, so it stays inside any bake — or at --torch-at.
 * --torch auto (default) lights it while the sun is below 4 degrees; on / off force it.
 * Keys (window), besides the GL samples' ones (samples/common/sample_gl.h): T torch on/off, B / N one
 * hour back / on. P pauses the day.
 * The atrium is drawn with its albedo textures (the bake names them; --no-textures: base colours) under
 * the sky. In a window a HUD shows the hour, the sun's elevation, the torch, Glow's GPU ms per stage,
 * the bounces and the view with its legend (H hides it; --hud on|off); headless runs print the same
 * per frame, with the frame's mean display luminance (0..1), and write PNGs without the HUD unless
 * --hud on.
 * Exit: 0 ok, 1 file or runtime error, 2 usage, 77 no OpenGL 4.5 context. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SAMPLE_GL_APP
#include "sample_gl.h" /* samples/common: the renderer and the frame loop the GL samples share */

#define PI 3.14159265f
#define TORCH_AUTO_BELOW_DEG 4.0f /* auto: the torch burns while the sun is lower than this */
static const float TORCH_INTENSITY[3] = {6.0f, 3.3f, 1.3f}; /* W/sr, a flame's orange */
static const float NIGHT_SKY[3] = {0.003f, 0.004f, 0.008f}; /* W/(m²·sr) */

/* ------------------------------------------------------------------------------- the sun's day */
/* The sun moves on a great circle through `east` (6:00, rising), `noon` (12:00) and -east (18:00,
 * setting); the other half of the circle, below the horizon, is the night. */
typedef struct sun_path {
    float noon[3];            /* unit vector towards the sun at noon (y > 0) */
    float east[3];            /* unit, horizontal, perpendicular to noon */
    float noon_irradiance[3]; /* W/m² facing the sun */
    float day_sky[3];         /* sky radiance at noon, W/(m²·sr) */
} sun_path;

/* `light_dir` is where the noon sun's light travels (a scene's sun "direction"). */
static void sun_path_init(sun_path *p, const float light_dir[3], const float irradiance[3], const float sky[3]) {
    float n[3] = {-light_dir[0], -light_dir[1], -light_dir[2]};
    sample_vec3_normalize(n);
    if (!(n[1] > 0.1f)) n[0] = 0.0f, n[1] = 1.0f, n[2] = -0.364f, sample_vec3_normalize(n); /* keep noon up */
    const float up[3] = {0.0f, 1.0f, 0.0f};
    sample_vec3_cross(n, up, p->east);
    if (p->east[0] * p->east[0] + p->east[2] * p->east[2] < 1e-6f) /* noon at the zenith: any east */
        p->east[0] = 1.0f, p->east[2] = 0.0f;
    sample_vec3_normalize(p->east);
    memcpy(p->noon, n, sizeof n);
    memcpy(p->noon_irradiance, irradiance, 3 * sizeof(float));
    memcpy(p->day_sky, sky, 3 * sizeof(float));
}

typedef struct sky_state {
    float to_sun[3];      /* unit vector towards the sun */
    float elevation_deg;  /* above the horizon; < 0 at night */
    float irradiance[3];  /* the sun's, W/m² facing it (0 below the horizon) */
    float environment[3]; /* the sky's constant radiance, W/(m²·sr) */
} sky_state;

static float smoothstep(float a, float b, float x) {
    float t = fminf(fmaxf((x - a) / (b - a), 0.0f), 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

static void sky_at(const sun_path *p, float hour, sky_state *s) {
    const float th = PI * (hour - 6.0f) / 12.0f; /* 0 at sunrise, pi/2 at noon, pi at sunset */
    for (int c = 0; c < 3; c++) s->to_sun[c] = p->east[c] * cosf(th) + p->noon[c] * sinf(th);
    const float m = s->to_sun[1], m_noon = p->noon[1]; /* sines of the elevations */
    s->elevation_deg = asinf(fminf(fmaxf(m, -1.0f), 1.0f)) * 180.0f / PI;
    /* The air the light crosses grows as 1/sin(elevation) and scatters blue more than red
     * (optical depths 0.1, 0.2, 0.4 per air mass), relative to noon: dimmer and warmer low down. */
    const float tau[3] = {0.1f, 0.2f, 0.4f};
    const float extra_air = m > 0.0f ? 1.0f / fmaxf(m, 0.01f) - 1.0f / m_noon : 0.0f;
    /* the sky: day light fades out through a twilight down to ~6 degrees under the horizon, warmer
     * while the sun is low; then the night's faint blue */
    const float day = smoothstep(-0.10f, 0.30f, m), warm = smoothstep(0.0f, 0.4f, m);
    const float dusk[3] = {1.0f, 0.7f, 0.5f};
    for (int c = 0; c < 3; c++) {
        s->irradiance[c] = m > 0.0f ? p->noon_irradiance[c] * expf(-tau[c] * extra_air) : 0.0f;
        float tint = dusk[c] + (1.0f - dusk[c]) * warm;
        s->environment[c] = NIGHT_SKY[c] + fmaxf(p->day_sky[c] - NIGHT_SKY[c], 0.0f) * day * tint;
    }
}

/* The flame: a few incommensurate waves around 1 (0.75 .. 1.25). */
static float flicker(float t) {
    return 1.0f + 0.12f * sinf(11.3f * t) + 0.08f * sinf(23.7f * t + 1.3f) + 0.05f * sinf(41.9f * t + 0.4f);
}

static float luma(const float c[3]) { return 0.25f * c[0] + 0.5f * c[1] + 0.25f * c[2]; }


/* The frame's mean display luminance (Rec. 709 weights of the tone-mapped sRGB values, 0..1): the
 * test compares frames with it. */
static double mean_luminance(sample_app *a, uint8_t *rgba) {
    if (sample_gl_read(&a->r, 0, rgba) != 0) return -1.0;
    double sum = 0.0;
    const size_t n = (size_t)a->r.width * a->r.height;
    for (size_t i = 0; i < n; i++) sum += 0.2126 * rgba[4 * i] + 0.7152 * rgba[4 * i + 1] + 0.0722 * rgba[4 * i + 2];
    return sum / (255.0 * (double)n);
}

/* ------------------------------------------------------------------------------ command line */
typedef enum torch_mode { TORCH_AUTO, TORCH_ON, TORCH_OFF } torch_mode;

typedef struct day_options {
    float day_seconds, start_hour, torch_at[3];
    long day_frames; /* 0: the run's --frames */
    torch_mode torch;
    bool has_torch_at;
} day_options;

static int bad(const char *argv0, const char *opt, const char *value, const char *want) {
    fprintf(stderr, "%s: %s '%s': %s (--help)\n", argv0, opt, value, want);
    return 2;
}

/* Takes this sample's options out of argv (the rest goes to sample_app_init, in `rest`). -1 to go
 * on, else the exit status. */
static int parse_day_options(int argc, char **argv, day_options *o, char **rest, int *rest_count) {
    *o = (day_options){.day_seconds = 60.0f, .start_hour = 9.0f, .torch = TORCH_AUTO};
    bool headless = false, sized = false;
    int n = 0;
    for (int i = 0; i < argc; i++) {
        static const char *const own[] = {"--day-seconds", "--day-frames", "--start-hour", "--torch", "--torch-at"};
        int k = -1;
        for (int j = 0; i > 0 && j < 5; j++)
            if (!strcmp(argv[i], own[j])) k = j;
        if (k < 0) { /* not ours: passed on */
            headless |= !strcmp(argv[i], "--headless");
            sized |= !strcmp(argv[i], "--width") || !strcmp(argv[i], "--height");
            rest[n++] = argv[i];
            continue;
        }
        if (i + 1 >= argc) return fprintf(stderr, "%s: %s needs a value\n", argv[0], argv[i]), 2;
        const char *a = argv[i], *v = argv[++i];
        char *end;
        if (k == 0 || k == 2) {
            float x = strtof(v, &end);
            if (end == v || *end || !isfinite(x)) return bad(argv[0], a, v, "wants a number");
            if (k == 0 && !(x >= 0.1f && x <= 1e6f)) return bad(argv[0], a, v, "wants 0.1 .. 1e6 seconds");
            if (k == 2 && !(x >= 0.0f && x < 24.0f)) return bad(argv[0], a, v, "wants an hour 0 .. 24");
            *(k == 0 ? &o->day_seconds : &o->start_hour) = x;
        } else if (k == 1) {
            o->day_frames = strtol(v, &end, 10);
            if (end == v || *end || o->day_frames < 1 || o->day_frames > 100000)
                return bad(argv[0], a, v, "wants 1..100000");
        } else if (k == 3) {
            if (!strcmp(v, "auto")) o->torch = TORCH_AUTO;
            else if (!strcmp(v, "on")) o->torch = TORCH_ON;
            else if (!strcmp(v, "off")) o->torch = TORCH_OFF;
            else return bad(argv[0], a, v, "wants on, off or auto");
        } else {
            char extra;
            float *p = o->torch_at;
            if (sscanf(v, "%f,%f,%f%c", &p[0], &p[1], &p[2], &extra) != 3 || !isfinite(p[0]) || !isfinite(p[1]) ||
                !isfinite(p[2]))
                return bad(argv[0], a, v, "wants X,Y,Z (m)");
            o->has_torch_at = true;
        }
    }
    /* Sponza is wide: 16:9 offscreen frames (the shared default is 320x240) unless a size is given */
    static char w[] = "--width", w_value[] = "320", h[] = "--height", h_value[] = "180";
    if (headless && !sized) rest[n++] = w, rest[n++] = w_value, rest[n++] = h, rest[n++] = h_value;
    rest[n] = NULL;
    *rest_count = n;
    return -1;
}

/* ------------------------------------------------------------------------------------- main */
int main(int argc, char **argv) {
    day_options o;
    char **args = malloc(((size_t)argc + 5) * sizeof *args);
    if (!args) return fprintf(stderr, "%s: out of memory\n", argv[0]), 1;
    int n = 0;
    int status = parse_day_options(argc, argv, &o, args, &n);
    if (status >= 0) return free(args), status;
    bool help = false;
    for (int i = 1; i < n; i++) help |= !strcmp(args[i], "--help") || !strcmp(args[i], "-h");
    sample_app a;
    status = sample_app_init(&a, n, args, NULL);
    if (status == 0 && help)
        printf("and: --scene JSON (its first sun is the noon sun, its environment the day sky)\n"
               "  --day-seconds S  a day lasts S seconds in a window (default 60)\n"
               "  --day-frames N   a day lasts N frames headless (default: --frames)\n"
               "  --start-hour H   time of day at the start, 0..24 (default 9; sunrise 6, sunset 18)\n"
               "  --torch on|off|auto  the torch (default auto: lit while the sun is below %.0f degrees)\n"
               "  --torch-at X,Y,Z the torch's position (m; default by the column at x -2.2, z 2.85 in Sponza)\n"
               "keys (window): T torch on/off, B / N one hour back / on (P pauses the day)\n",
               (double)TORCH_AUTO_BELOW_DEG);
    if (status >= 0) return free(args), status;

    /* Without a scene camera: glow_scene_camera_default (sample_app_init) sees a closed building from
     * outside, and Sponza's outer shell faces that way. Stand inside instead, at one end of the longest
     * horizontal axis, looking along it (in Sponza: sponza-sun.json's camera, at the west end). */
    if (!a.has_scene || !a.scene.has_camera) {
        const int ax = a.size[0] >= a.size[2] ? 0 : 2; /* the longest horizontal axis */
        memcpy(a.camera.position, a.centre, sizeof a.centre);
        memcpy(a.camera.target, a.centre, sizeof a.centre);
        a.camera.position[1] = a.info.bounds_min[1] + 0.24f * a.size[1]; /* Sponza: 3 m up */
        a.camera.target[1] = a.info.bounds_min[1] + 0.33f * a.size[1];
        a.camera.position[ax] = a.info.bounds_min[ax] + 0.18f * a.size[ax];
        a.camera.target[ax] = a.info.bounds_min[ax] + 0.79f * a.size[ax];
        a.camera.vfov_deg = 60.0f;
    }
    /* The sun's path: noon from the scene's first sun, else 70 degrees up towards -Z. */
    sun_path path;
    const glow_scene_light *scene_sun = NULL;
    uint32_t other_lights = 0;
    for (uint32_t i = 0; a.has_scene && i < a.scene.light_count; i++) {
        if (!scene_sun && a.scene.lights[i].type == GLOW_SCENE_LIGHT_SUN) scene_sun = &a.scene.lights[i];
        else other_lights++;
    }
    const float default_dir[3] = {0.0f, -1.0f, 0.364f}, default_irradiance[3] = {9.0f, 8.5f, 7.5f},
                default_sky[3] = {0.25f, 0.3f, 0.4f};
    sun_path_init(&path, scene_sun ? scene_sun->direction : default_dir,
                  scene_sun ? scene_sun->irradiance : default_irradiance, a.has_scene ? a.scene.environment : default_sky);
    /* The torch: by a column of the Sponza atrium, as fractions of the bounds (inside any bake) */
    float torch[3];
    const float torch_frac[3] = {0.437f, 0.163f, 0.641f};
    for (int c = 0; c < 3; c++)
        torch[c] = o.has_torch_at ? o.torch_at[c] : a.info.bounds_min[c] + torch_frac[c] * a.size[c];
    bool inside = true;
    for (int c = 0; c < 3; c++) inside &= torch[c] > a.info.bounds_min[c] && torch[c] < a.info.bounds_max[c];
    const long day_frames = o.day_frames ? o.day_frames : a.opt.args.frames > 0 ? a.opt.args.frames : 8;
    printf("day: sunrise 6:00 towards (%.2f, %.2f, %.2f), noon %.1f deg up, %.2f W/m2 (%s), sunset 18:00; "
           "a day lasts %g %s\n",
           (double)(path.east[0] + 0.0f), (double)(path.east[1] + 0.0f), (double)(path.east[2] + 0.0f),
           (double)(asinf(path.noon[1]) * 180.0f / PI), (double)luma(path.noon_irradiance),
           scene_sun ? "the scene's sun" : "default sun",
           a.window ? (double)o.day_seconds : (double)day_frames, a.window ? "s" : day_frames == 1 ? "frame" : "frames");
    printf("torch: at (%.2f, %.2f, %.2f)%s, %.1f W/sr, %s\n", (double)torch[0], (double)torch[1], (double)torch[2],
           inside ? "" : " - OUTSIDE the bake's bounds", (double)luma(TORCH_INTENSITY),
           o.torch == TORCH_AUTO ? "auto (lit while the sun is low)" : o.torch == TORCH_ON ? "on" : "off");
    if (other_lights) printf("note: the scene's %u other light(s) are not used\n", other_lights);

    uint8_t *rgba = a.window ? NULL : malloc((size_t)a.r.width * a.r.height * 4);
    if (!a.window && !rgba) status = 1, fprintf(stderr, "%s: out of memory\n", a.name);
    glow_scene_light lights[2], sent[2];
    uint32_t sent_count = UINT32_MAX;
    float sent_env[3] = {-1.0f, -1.0f, -1.0f}, hour_offset = 0.0f;
    torch_mode mode = o.torch;
    for (long f = 0; status < 0; f++) {
        /* 1. the time of day and the sky */
        float t = sample_app_time(&a, f);
        if (a.window) {
            if (sample_app_key(&a, GLFW_KEY_B)) hour_offset -= 1.0f;
            if (sample_app_key(&a, GLFW_KEY_N)) hour_offset += 1.0f;
        }
        float hour = o.start_hour + hour_offset + 24.0f * (a.window ? t / o.day_seconds : (float)f / (float)day_frames);
        hour = fmodf(hour, 24.0f);
        if (hour < 0.0f) hour += 24.0f;
        sky_state sky;
        sky_at(&path, hour, &sky);
        /* 2. the torch: auto follows the sun; T switches it by hand (and leaves auto) */
        bool lit = mode == TORCH_ON || (mode == TORCH_AUTO && sky.elevation_deg < TORCH_AUTO_BELOW_DEG);
        if (a.window && sample_app_key(&a, GLFW_KEY_T)) mode = lit ? TORCH_OFF : TORCH_ON, lit = !lit;
        /* 3. the lights: the sun while it is up, the torch while it burns; to the GPU when they change */
        memset(lights, 0, sizeof lights);
        uint32_t count = 0;
        if (sky.elevation_deg > 0.0f) {
            glow_scene_light *s = &lights[count++];
            s->type = GLOW_SCENE_LIGHT_SUN;
            for (int c = 0; c < 3; c++) s->direction[c] = -sky.to_sun[c], s->irradiance[c] = sky.irradiance[c];
        }
        if (lit) {
            glow_scene_light *l = &lights[count++];
            l->type = GLOW_SCENE_LIGHT_POINT;
            const float k = flicker(t);
            for (int c = 0; c < 3; c++) l->position[c] = torch[c], l->intensity[c] = k * TORCH_INTENSITY[c];
        }
        if (count != sent_count || memcmp(lights, sent, count * sizeof *lights) ||
            memcmp(sky.environment, sent_env, sizeof sent_env)) {
            glow_result r = glow_gl_lights_set(a.lights, count ? lights : NULL, count, sky.environment);
            if (r != GLOW_OK) {
                fprintf(stderr, "%s: frame %ld: glow_gl_lights_set: %s\n", a.name, f, glow_result_string(r));
                status = 1;
                break;
            }
            memcpy(sent, lights, sizeof sent);
            memcpy(sent_env, sky.environment, sizeof sent_env);
            sent_count = count;
        }
        /* 4. Glow's update, the draw, the window or the PNG (sample_gl.h) */
        char state[160];
        const float elevation = roundf(10.0f * sky.elevation_deg) / 10.0f + 0.0f; /* no "-0.0" at 18:00 */
        snprintf(state, sizeof state,
                 "%02d:%02d  sun elevation %+.1f deg (%.2f W/m2)  sky %.3f W/(m2 sr)  torch %s (%s)",
                 (int)hour, (int)(60.0f * (hour - floorf(hour))), (double)elevation, (double)luma(sky.irradiance),
                 (double)luma(sky.environment), lit ? "on" : "off", mode == TORCH_AUTO ? "auto" : "manual");
        snprintf(a.title, sizeof a.title, "Glow 02_sponza  %s", state); /* the window's title starts with it */
        memcpy(a.sky, sky.environment, sizeof a.sky); /* the final view's background: the same sky */
        status = sample_app_frame(&a, f, NULL, 0, NULL);
        if (!a.window && status != 1)
            printf("time %s  mean luminance %.4f  (frame %ld)\n", state, mean_luminance(&a, rgba), f);
    }
    free(rgba);
    sample_app_destroy(&a);
    free(args);
    return status;
}
