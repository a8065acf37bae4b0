/* test_glctx.c — glow_glctx (glow_glctx.h): headless GL 4.5 core contexts through EGL and OSMesa
 * (each kind explicitly, HEADLESS's pick, the GLOW_GLCTX override), GL reached only through the
 * context's loader (renderer/version strings, compute limits, a 64-float SSBO doubled by a GLSL 450
 * compute shader and read back two ways), two contexts alive at once and in sequence (run under ASan
 * for leaks), moving a context to another thread and back, and bad input: NULL desc/out, unknown kind, oversize, a bad GLOW_GLCTX, a WINDOW with
 * no display (UNSUPPORTED with a reason, no crash).
 *
 * Exit 77 (skipped) when no headless GL 4.5 context can be made; the no-GL checks run first and still
 * fail the test if they fail.
 *
 * Under ASan: LSAN_OPTIONS=suppressions=tests/gpu/lsan.supp (leaks inside Mesa's OSMesa only). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <GL/glcorearb.h>

#include "glow/glow_glctx.h"

static int g_backends_ok; /* explicit EGL / OSMesa contexts that passed */

/* ------------------------------------------------------------------------------ helpers */

static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* Sets (value non-NULL) or unsets an environment variable; returns a malloc'd copy of the old value. */
static char *swap_env(const char *name, const char *value) {
    const char *old = getenv(name);
    char *saved = old ? strdup(old) : NULL;
    if (value)
        setenv(name, value, 1);
    else
        unsetenv(name);
    return saved;
}

static void restore_env(const char *name, char *saved) {
    if (saved)
        setenv(name, saved, 1);
    else
        unsetenv(name);
    free(saved);
}

#define LOAD(type, name) type name = (type)load(#name); assert_non_null(name)

/* The current context's strings and limits, through its own loader. */
static void check_context(glow_glctx *gl) {
    const char *renderer = glow_glctx_renderer(gl), *version = glow_glctx_version(gl);
    assert_non_null(renderer);
    assert_non_null(version);
    assert_true(renderer[0] != '\0');
    assert_true(version[0] != '\0');
    int major = 0, minor = 0;
    assert_int_equal(sscanf(version, "%d.%d", &major, &minor), 2);
    assert_true(major > 4 || (major == 4 && minor >= 5));

    glow_gl_loader load = glow_glctx_get_proc_address(gl);
    assert_non_null(load);
    LOAD(PFNGLGETINTEGERVPROC, glGetIntegerv);
    LOAD(PFNGLDISPATCHCOMPUTEPROC, glDispatchCompute);
    LOAD(PFNGLGETSTRINGPROC, glGetString);
    LOAD(PFNGLGETERRORPROC, glGetError);
    (void)glDispatchCompute;
    /* The strings kept by glow_glctx are the live context's. */
    assert_string_equal((const char *)glGetString(GL_VERSION), version);
    GLint invocations = 0, profile = 0;
    glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, &invocations);
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    assert_int_equal(glGetError(), GL_NO_ERROR);
    assert_true(invocations >= 1024);
    assert_true(profile & GL_CONTEXT_CORE_PROFILE_BIT);

    /* Headless: no window, framebuffer size = desc size or the default. */
    assert_null(glow_glctx_window(gl));
    assert_int_equal(glow_glctx_should_close(gl), 0);
    glow_glctx_swap(gl); /* no-op */
}

/* 64 floats in an SSBO, doubled by a compute shader, read back with glGetNamedBufferSubData and
 * glMapNamedBufferRange. Returns NULL, or what went wrong (no cmocka asserts: runs on other threads
 * too). */
#define NEED(type, name)                                                                                 \
    type name = (type)load(#name);                                                                      \
    if (!name) return "loader returned NULL for " #name

static const char *compute_round_trip_err(glow_glctx *gl, char *msg, size_t msg_size) {
    glow_gl_loader load = glow_glctx_get_proc_address(gl);
    if (!load) return "no loader";
    NEED(PFNGLCREATESHADERPROC, glCreateShader);
    NEED(PFNGLSHADERSOURCEPROC, glShaderSource);
    NEED(PFNGLCOMPILESHADERPROC, glCompileShader);
    NEED(PFNGLGETSHADERIVPROC, glGetShaderiv);
    NEED(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog);
    NEED(PFNGLCREATEPROGRAMPROC, glCreateProgram);
    NEED(PFNGLATTACHSHADERPROC, glAttachShader);
    NEED(PFNGLLINKPROGRAMPROC, glLinkProgram);
    NEED(PFNGLGETPROGRAMIVPROC, glGetProgramiv);
    NEED(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog);
    NEED(PFNGLDELETESHADERPROC, glDeleteShader);
    NEED(PFNGLDELETEPROGRAMPROC, glDeleteProgram);
    NEED(PFNGLUSEPROGRAMPROC, glUseProgram);
    NEED(PFNGLCREATEBUFFERSPROC, glCreateBuffers);
    NEED(PFNGLNAMEDBUFFERSTORAGEPROC, glNamedBufferStorage);
    NEED(PFNGLBINDBUFFERBASEPROC, glBindBufferBase);
    NEED(PFNGLDISPATCHCOMPUTEPROC, glDispatchCompute);
    NEED(PFNGLMEMORYBARRIERPROC, glMemoryBarrier);
    NEED(PFNGLGETNAMEDBUFFERSUBDATAPROC, glGetNamedBufferSubData);
    NEED(PFNGLMAPNAMEDBUFFERRANGEPROC, glMapNamedBufferRange);
    NEED(PFNGLUNMAPNAMEDBUFFERPROC, glUnmapNamedBuffer);
    NEED(PFNGLDELETEBUFFERSPROC, glDeleteBuffers);
    NEED(PFNGLGETERRORPROC, glGetError);

    static const char *src = "#version 450\n"
                             "layout(local_size_x = 32) in;\n"
                             "layout(std430, binding = 0) buffer Data { float v[]; };\n"
                             "void main() { v[gl_GlobalInvocationID.x] *= 2.0; }\n";
    GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
    if (!shader) return "glCreateShader returned 0 (context not current?)";
    glShaderSource(shader, 1, &src, NULL);
    glCompileShader(shader);
    GLint ok = 0;
    char log[512] = "";
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        glGetShaderInfoLog(shader, sizeof log, NULL, log);
        snprintf(msg, msg_size, "compute shader did not compile: %s", log);
        return msg;
    }
    GLuint program = glCreateProgram();
    glAttachShader(program, shader);
    glLinkProgram(program);
    glDeleteShader(shader);
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(program, sizeof log, NULL, log);
        snprintf(msg, msg_size, "compute program did not link: %s", log);
        return msg;
    }

    float in[64], out[64];
    for (int i = 0; i < 64; ++i) in[i] = (float)i * 0.75f - 11.0f;
    GLuint buffer = 0;
    glCreateBuffers(1, &buffer);
    if (!buffer) return "glCreateBuffers gave 0";
    glNamedBufferStorage(buffer, sizeof in, in, GL_MAP_READ_BIT);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffer);
    glUseProgram(program);
    glDispatchCompute(2, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    memset(out, 0, sizeof out);
    glGetNamedBufferSubData(buffer, 0, sizeof out, out);
    const char *err = NULL;
    for (int i = 0; i < 64 && !err; ++i) {
        if (out[i] != 2.0f * in[i]) {
            snprintf(msg, msg_size, "glGetNamedBufferSubData: v[%d] = %g, expected %g", i, out[i], 2.0f * in[i]);
            err = msg;
        }
    }
    const float *mapped = glMapNamedBufferRange(buffer, 0, sizeof out, GL_MAP_READ_BIT);
    if (!mapped && !err) err = "glMapNamedBufferRange returned NULL";
    for (int i = 0; mapped && i < 64 && !err; ++i) {
        if (mapped[i] != 2.0f * in[i]) {
            snprintf(msg, msg_size, "glMapNamedBufferRange: v[%d] = %g, expected %g", i, mapped[i], 2.0f * in[i]);
            err = msg;
        }
    }
    if (mapped && !glUnmapNamedBuffer(buffer) && !err) err = "glUnmapNamedBuffer failed";
    glUseProgram(0);
    glDeleteBuffers(1, &buffer);
    glDeleteProgram(program);
    GLenum e = glGetError();
    if (e != GL_NO_ERROR && !err) {
        snprintf(msg, msg_size, "glGetError 0x%04X after the round trip", (unsigned)e);
        err = msg;
    }
    return err;
}

static void compute_round_trip(glow_glctx *gl) {
    char msg[640];
    const char *err = compute_round_trip_err(gl, msg, sizeof msg);
    if (err) fail_msg("%s compute round trip: %s", glow_glctx_kind_name(glow_glctx_get_kind(gl)), err);
}

/* Creates kind `kind`; on UNSUPPORTED prints why and returns NULL (caller skips). */
static glow_glctx *create_or_null(glow_glctx_kind kind, int debug) {
    glow_glctx *gl = (glow_glctx *)0x1;
    char why[512];
    double t0 = now_ms();
    glow_result r = glow_glctx_create(&(glow_glctx_desc){.kind = kind, .debug = debug}, &gl, why, sizeof why);
    double t1 = now_ms();
    if (r == GLOW_ERROR_UNSUPPORTED) {
        assert_null(gl);
        assert_true(why[0] != '\0');
        printf("[ info ] %s: unsupported here: %s\n", glow_glctx_kind_name(kind), why);
        return NULL;
    }
    assert_int_equal(r, GLOW_OK);
    assert_non_null(gl);
    assert_string_equal(why, "");
    printf("[ info ] %s -> %s: \"%s\", \"%s\" (create %.1f ms)\n", glow_glctx_kind_name(kind),
           glow_glctx_kind_name(glow_glctx_get_kind(gl)), glow_glctx_renderer(gl), glow_glctx_version(gl), t1 - t0);
    return gl;
}

/* ------------------------------------------------------------------------------ no GL needed */

static void test_bad_input(void **state) {
    (void)state;
    glow_glctx *gl = (glow_glctx *)0x1;
    char why[256];
    assert_int_equal(glow_glctx_create(NULL, &gl, why, sizeof why), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(gl);
    assert_non_null(strstr(why, "desc"));
    glow_glctx_desc desc = {.kind = GLOW_GLCTX_HEADLESS};
    assert_int_equal(glow_glctx_create(&desc, NULL, why, sizeof why), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(why, "out"));
    assert_int_equal(glow_glctx_create(&desc, NULL, NULL, 0), GLOW_ERROR_INVALID_ARGUMENT); /* why may be NULL */
    desc.kind = (glow_glctx_kind)42;
    gl = (glow_glctx *)0x1;
    assert_int_equal(glow_glctx_create(&desc, &gl, why, sizeof why), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(gl);
    assert_non_null(strstr(why, "kind"));
    desc = (glow_glctx_desc){.kind = GLOW_GLCTX_WINDOW, .width = 100000, .height = 10};
    assert_int_equal(glow_glctx_create(&desc, &gl, why, sizeof why), GLOW_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(why, "100000"));
    /* A tiny why buffer is truncated, not overrun. */
    char tiny[4] = {'x', 'x', 'x', 'x'};
    assert_int_equal(glow_glctx_create(NULL, &gl, tiny, sizeof tiny), GLOW_ERROR_INVALID_ARGUMENT);
    assert_int_equal(tiny[3], '\0');

    /* A misspelt override is an error naming the variable, not a silent fallback. */
    char *saved = swap_env("GLOW_GLCTX", "vulkan");
    desc = (glow_glctx_desc){.kind = GLOW_GLCTX_HEADLESS};
    assert_int_equal(glow_glctx_create(&desc, &gl, why, sizeof why), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(gl);
    assert_non_null(strstr(why, "GLOW_GLCTX"));
    assert_non_null(strstr(why, "vulkan"));
    restore_env("GLOW_GLCTX", saved);

    /* NULL-safe accessors. */
    glow_glctx_destroy(NULL);
    assert_int_equal(glow_glctx_make_current(NULL), GLOW_ERROR_INVALID_ARGUMENT);
    assert_null(glow_glctx_get_proc_address(NULL));
    assert_null(glow_glctx_window(NULL));
    assert_int_equal(glow_glctx_should_close(NULL), 0);
    glow_glctx_swap(NULL);
    assert_string_equal(glow_glctx_renderer(NULL), "");
    assert_string_equal(glow_glctx_version(NULL), "");
    uint32_t w = 7, h = 7;
    glow_glctx_framebuffer_size(NULL, &w, &h);
    assert_int_equal(w, 0);
    assert_int_equal(h, 0);
    assert_string_equal(glow_glctx_kind_name(GLOW_GLCTX_HEADLESS), "headless");
    assert_string_equal(glow_glctx_kind_name(GLOW_GLCTX_EGL), "egl");
    assert_string_equal(glow_glctx_kind_name(GLOW_GLCTX_OSMESA), "osmesa");
    assert_string_equal(glow_glctx_kind_name(GLOW_GLCTX_WINDOW), "glfw");
    assert_string_equal(glow_glctx_kind_name((glow_glctx_kind)42), "unknown");
}

static void test_window_without_display(void **state) {
    (void)state;
    char *display = swap_env("DISPLAY", NULL), *wayland = swap_env("WAYLAND_DISPLAY", NULL);
    glow_glctx *gl = (glow_glctx *)0x1;
    char why[256] = "";
    glow_result r = glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_WINDOW, .title = "test_glctx"}, &gl, why,
                                      sizeof why);
    printf("[ info ] window without a display: %s: %s\n", glow_result_string(r), why);
    assert_int_equal(r, GLOW_ERROR_UNSUPPORTED);
    assert_null(gl);
    assert_true(why[0] != '\0');
    assert_non_null(strstr(why, "GLFW"));
    /* Twice: GLFW stays usable after a failed init. */
    r = glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_WINDOW}, &gl, why, sizeof why);
    assert_int_equal(r, GLOW_ERROR_UNSUPPORTED);
    assert_null(gl);
    restore_env("DISPLAY", display);
    restore_env("WAYLAND_DISPLAY", wayland);
}

/* ------------------------------------------------------------------------------ GL */

static void test_headless(void **state) {
    (void)state;
    glow_glctx *gl = create_or_null(GLOW_GLCTX_HEADLESS, 0);
    assert_non_null(gl); /* main() skipped the whole group otherwise */
    glow_glctx_kind kind = glow_glctx_get_kind(gl);
    assert_true(kind == GLOW_GLCTX_EGL || kind == GLOW_GLCTX_OSMESA);
    uint32_t w = 0, h = 0;
    glow_glctx_framebuffer_size(gl, &w, &h);
    assert_int_equal(w, 1280);
    assert_int_equal(h, 720);
    check_context(gl);
    compute_round_trip(gl);
    assert_int_equal(glow_glctx_make_current(gl), GLOW_OK);
    glow_glctx_destroy(gl);

    /* desc size is reported back headless. */
    char why[256];
    assert_int_equal(glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_HEADLESS, .width = 64, .height = 32},
                                       &gl, why, sizeof why),
                     GLOW_OK);
    glow_glctx_framebuffer_size(gl, &w, &h);
    assert_int_equal(w, 64);
    assert_int_equal(h, 32);
    glow_glctx_destroy(gl);
}

static void test_kind(glow_glctx_kind kind) {
    glow_glctx *gl = create_or_null(kind, 1);
    if (!gl) {
        skip();
        return;
    }
    assert_int_equal(glow_glctx_get_kind(gl), kind);
    check_context(gl);
    if (kind == GLOW_GLCTX_EGL) { /* OSMesa has no debug-context attribute */
        glow_gl_loader load = glow_glctx_get_proc_address(gl);
        LOAD(PFNGLGETINTEGERVPROC, glGetIntegerv);
        GLint flags = 0;
        glGetIntegerv(GL_CONTEXT_FLAGS, &flags);
        assert_true(flags & GL_CONTEXT_FLAG_DEBUG_BIT);
    }
    compute_round_trip(gl);
    glow_glctx_destroy(gl);
    g_backends_ok++;
}

static void test_egl(void **state) {
    (void)state;
    test_kind(GLOW_GLCTX_EGL);
}

static void test_osmesa(void **state) {
    (void)state;
    test_kind(GLOW_GLCTX_OSMESA);
}

static void test_some_backend_worked(void **state) {
    (void)state;
    assert_true(g_backends_ok >= 1); /* HEADLESS worked, so EGL or OSMesa must work explicitly too */
}

/* GLOW_GLCTX=egl|osmesa forces HEADLESS's pick. */
static void test_env_override(void **state) {
    (void)state;
    static const struct { const char *value; glow_glctx_kind kind; } cases[] = {
        {"egl", GLOW_GLCTX_EGL}, {"osmesa", GLOW_GLCTX_OSMESA}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char *saved = swap_env("GLOW_GLCTX", cases[i].value);
        glow_glctx *gl = NULL;
        char why[512];
        glow_result r = glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_HEADLESS}, &gl, why, sizeof why);
        restore_env("GLOW_GLCTX", saved);
        if (r == GLOW_ERROR_UNSUPPORTED) {
            /* The reason names only the forced kind. */
            printf("[ info ] GLOW_GLCTX=%s: %s\n", cases[i].value, why);
            assert_true(strncmp(why, cases[i].kind == GLOW_GLCTX_EGL ? "EGL: " : "OSMesa: ", 5) == 0);
            assert_null(strstr(why, cases[i].kind == GLOW_GLCTX_EGL ? "OSMesa" : "EGL:"));
            continue;
        }
        assert_int_equal(r, GLOW_OK);
        assert_int_equal(glow_glctx_get_kind(gl), cases[i].kind);
        glow_glctx_destroy(gl);
    }
}

/* Two contexts alive at once (switching between them), then in sequence; under ASan this is the
 * leak check for create/destroy. */
static void test_two_contexts(void **state) {
    (void)state;
    static const glow_glctx_kind kinds[] = {GLOW_GLCTX_EGL, GLOW_GLCTX_OSMESA};
    for (size_t k = 0; k < 2; ++k) {
        char why[512];
        glow_glctx *a = NULL, *b = NULL;
        if (glow_glctx_create(&(glow_glctx_desc){.kind = kinds[k]}, &a, why, sizeof why) != GLOW_OK) continue;
        assert_int_equal(glow_glctx_create(&(glow_glctx_desc){.kind = kinds[k]}, &b, why, sizeof why), GLOW_OK);
        compute_round_trip(b);            /* b is current after its create */
        assert_int_equal(glow_glctx_make_current(a), GLOW_OK);
        compute_round_trip(a);
        glow_glctx_destroy(a);            /* current: released first */
        assert_int_equal(glow_glctx_make_current(b), GLOW_OK);
        compute_round_trip(b);            /* b survives a's destruction (shared EGL display) */
        glow_glctx_destroy(b);
        for (int round = 0; round < 2; ++round) { /* in sequence */
            assert_int_equal(glow_glctx_create(&(glow_glctx_desc){.kind = kinds[k]}, &a, why, sizeof why), GLOW_OK);
            compute_round_trip(a);
            glow_glctx_destroy(a);
        }
    }
}

/* Moving a context between threads: release_current on one, make_current on the other. */
typedef struct thread_job {
    glow_glctx *gl;
    glow_result made_current, released;
    const char *err;
    char msg[640];
} thread_job;

static void *thread_main(void *arg) {
    thread_job *job = arg;
    job->made_current = glow_glctx_make_current(job->gl);
    if (job->made_current == GLOW_OK) {
        job->err = compute_round_trip_err(job->gl, job->msg, sizeof job->msg);
        job->released = glow_glctx_release_current(job->gl);
    }
    return NULL;
}

static void run_thread(thread_job *job) {
    pthread_t thread;
    assert_int_equal(pthread_create(&thread, NULL, thread_main, job), 0);
    assert_int_equal(pthread_join(thread, NULL), 0);
}

static void test_threads(void **state) {
    (void)state;
    static const glow_glctx_kind kinds[] = {GLOW_GLCTX_EGL, GLOW_GLCTX_OSMESA};
    for (size_t k = 0; k < 2; ++k) {
        glow_glctx *gl = NULL;
        char why[512];
        if (glow_glctx_create(&(glow_glctx_desc){.kind = kinds[k]}, &gl, why, sizeof why) != GLOW_OK) continue;
        thread_job job = {.gl = gl, .released = GLOW_ERROR_HOST_CALLBACK};
        if (kinds[k] == GLOW_GLCTX_EGL) { /* still current here: EGL refuses it elsewhere */
            run_thread(&job);
            assert_int_equal(job.made_current, GLOW_ERROR_INVALID_OPERATION);
        }
        assert_int_equal(glow_glctx_release_current(gl), GLOW_OK);
        assert_int_equal(glow_glctx_release_current(gl), GLOW_OK); /* not current: no-op */
        run_thread(&job);
        assert_int_equal(job.made_current, GLOW_OK);
        if (job.err) fail_msg("%s on a second thread: %s", glow_glctx_kind_name(kinds[k]), job.err);
        assert_int_equal(job.released, GLOW_OK);
        assert_int_equal(glow_glctx_make_current(gl), GLOW_OK); /* and back */
        compute_round_trip(gl);
        glow_glctx_destroy(gl);
    }
    assert_int_equal(glow_glctx_release_current(NULL), GLOW_ERROR_INVALID_ARGUMENT);
}

int main(void) {
    const struct CMUnitTest no_gl[] = {
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_window_without_display),
    };
    int failed = cmocka_run_group_tests_name("glctx_no_gl", no_gl, NULL, NULL);
    if (failed) return failed;

    glow_glctx *gl = NULL;
    char why[512];
    glow_result r = glow_glctx_create(&(glow_glctx_desc){.kind = GLOW_GLCTX_HEADLESS}, &gl, why, sizeof why);
    if (r != GLOW_OK) {
        printf("test_glctx: skipped: no headless GL 4.5 core context (%s): %s\n", glow_result_string(r), why);
        return r == GLOW_ERROR_UNSUPPORTED ? 77 : 1;
    }
    glow_glctx_destroy(gl);

    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_headless),
        cmocka_unit_test(test_egl),
        cmocka_unit_test(test_osmesa),
        cmocka_unit_test(test_some_backend_worked),
        cmocka_unit_test(test_env_override),
        cmocka_unit_test(test_two_contexts),
        cmocka_unit_test(test_threads),
    };
    return cmocka_run_group_tests_name("glctx", tests, NULL, NULL);
}
