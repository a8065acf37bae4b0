/* bake_mpi.c — glow-bake --mpi: one bake split over the ranks of an MPI job (OpenMPI from Debian).
 *
 * The linker library knows nothing of MPI (glow_pc_distribution in glow_precompute.h): every rank
 * runs the whole pipeline with the same scene and settings, computes its share of the links stage and
 * hands it to the others through share() below; rank 0 writes the bake. Built only when CMake finds
 * MPI (GLOW_HAVE_MPI); without it glow-bake refuses --mpi with a message and bakes as before.
 *
 * A rank that fails: its own error is printed with its rank, then MPI_Abort ends the job, and the
 * launcher stops the other ranks (SIGTERM). Those print that another rank failed and exit 1 without
 * writing (rank 0 writes only after every rank's share has arrived, and then through a temporary file
 * and a rename, so a partial bake never appears under the output name). A rank that dies outright
 * (killed, crashed) is seen the same way by the launcher. GLOW_BAKE_MPI_FAIL_RANK=R makes rank R die
 * (SIGKILL) at its first exchange: the tests' way to check that path.
 *
 * A world bake (--system-area) writes its systems' files as the ranks bake them, before the manifest.
 * The library names them all to every rank first (glow_pc_distribution.will_write); until the manifest
 * is written (rank 0 says so; the others learn it at the closing barrier) a rank that fails or is
 * stopped removes every one of them and their temporaries (each rank's "<path>.tmp.<pid>", the pids
 * gathered at the start), with unlink(2) only in the signal handler. A failed job so leaves no part
 * of the new world, whichever rank died, and an old world at the same path keeps its files. Once the
 * manifest at -o is a new file (another inode than before the systems were written) the world is
 * written, and nothing is removed: a rank stopped after that keeps it. */
#include "bake_mpi.h"

#include <mpi.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int g_rank = -1, g_ranks = 0;
static char g_stop_msg[160];
static size_t g_stop_len;
static long *g_pids;              /* each rank's process id (the writers' temporaries' names) */
static char *g_files;             /* the world's files and their temporaries, each NUL-ended */
static size_t g_files_len;
static volatile sig_atomic_t g_armed; /* g_files is complete and not yet committed */
static const char *g_manifest;        /* -o: the world manifest */
static int g_had_manifest;            /* ... was there before the bake, as g_manifest_id */
static struct stat g_manifest_id;

/* Whether rank 0 has renamed the new manifest into place (a new file: another inode) */
static int manifest_committed(void) {
    struct stat st;
    if (!g_manifest || stat(g_manifest, &st) != 0) return 0;
    return !g_had_manifest || st.st_ino != g_manifest_id.st_ino || st.st_dev != g_manifest_id.st_dev;
}

/* async-signal-safe: stat(2) and unlink(2) only */
static void remove_files(void) {
    if (!g_armed || manifest_committed()) return;
    for (size_t at = 0; at < g_files_len;) {
        const char *p = g_files + at;
        unlink(p);
        while (at < g_files_len && g_files[at]) ++at;
        ++at;
    }
}

/* async-signal-safe: unlink(2), write(2) and _exit(2) only */
static void on_stop(int sig) {
    (void)sig;
    remove_files();
    if (g_stop_len) {
        ssize_t w = write(2, g_stop_msg, g_stop_len);
        (void)w;
    }
    _exit(1);
}

/* glow_pc_distribution.will_write: keep the names (NULL: the manifest is being written: disarm) */
static void will_write(void *user, const char *const *paths, uint32_t count) {
    (void)user;
    if (!paths) {
        g_armed = 0;
        return;
    }
    size_t len = 0;
    for (uint32_t i = 0; i < count; ++i) len += ((size_t)g_ranks + 1) * (strlen(paths[i]) + 24);
    char *b = malloc(len + 1);
    if (!b) return; /* nothing to remove then; the bake itself reports memory on its next allocation */
    size_t at = 0;
    for (uint32_t i = 0; i < count; ++i) {
        at += (size_t)snprintf(b + at, len + 1 - at, "%s", paths[i]) + 1;
        for (int r = 0; r < g_ranks; ++r)
            at += (size_t)snprintf(b + at, len + 1 - at, "%s.tmp.%ld", paths[i], g_pids[r]) + 1;
    }
    g_armed = 0;
    free(g_files);
    g_files = b;
    g_files_len = at;
    g_had_manifest = g_manifest && stat(g_manifest, &g_manifest_id) == 0;
    g_armed = 1;
}

void glow_bake_mpi_output(const char *manifest) { g_manifest = manifest; }

/* GLOW_BAKE_MPI_FAIL_RANK=R: rank R dies (SIGKILL) here; GLOW_BAKE_MPI_FAIL_AT=end moves that from the
 * first exchange to the end, after the bake (the tests' ways to check those paths) */
static void maybe_die(int at_end) {
    const char *f = getenv("GLOW_BAKE_MPI_FAIL_RANK"), *w = getenv("GLOW_BAKE_MPI_FAIL_AT");
    if (!(w && strcmp(w, "end") == 0) != !at_end) return;
    if (f && *f && atoi(f) == g_rank) {
        fprintf(stderr, "glow-bake: rank %d of %d: GLOW_BAKE_MPI_FAIL_RANK: dying now (test)\n", g_rank, g_ranks);
        fflush(stderr);
        raise(SIGKILL);
    }
}

static glow_result share(void *user, void *buf, const size_t *offsets) {
    (void)user;
    static int first = 1;
    if (first) {
        first = 0;
        maybe_die(0);
    }
    /* each rank's part from that rank, in pieces that fit an int count */
    const size_t piece = (size_t)1 << 30;
    for (int r = 0; r < g_ranks; ++r)
        for (size_t o = offsets[r]; o < offsets[r + 1]; o += piece) {
            const size_t n = offsets[r + 1] - o < piece ? offsets[r + 1] - o : piece;
            if (MPI_Bcast((char *)buf + o, (int)n, MPI_BYTE, r, MPI_COMM_WORLD) != MPI_SUCCESS) return GLOW_ERROR_IO;
        }
    return GLOW_OK;
}

int glow_bake_mpi_begin(int *argc, char ***argv, glow_pc_distribution *d, char *err, size_t n) {
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
        snprintf(err, n, "MPI_Init failed (run it with mpirun -np N)");
        return 0;
    }
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_ranks);
    int len = snprintf(g_stop_msg, sizeof g_stop_msg,
                       "glow-bake: rank %d of %d: stopped: another rank of this MPI bake failed (its message above "
                       "says why); no bake written\n",
                       g_rank, g_ranks);
    g_stop_len = len > 0 && (size_t)len < sizeof g_stop_msg ? (size_t)len : 0;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    long pid = (long)getpid();
    if (!(g_pids = calloc((size_t)g_ranks, sizeof *g_pids)) ||
        MPI_Allgather(&pid, 1, MPI_LONG, g_pids, 1, MPI_LONG, MPI_COMM_WORLD) != MPI_SUCCESS) {
        snprintf(err, n, "the ranks' process ids could not be gathered");
        return 0;
    }
    *d = (glow_pc_distribution){.rank = (uint32_t)g_rank, .ranks = (uint32_t)g_ranks, .share = share,
                                .will_write = will_write};
    return 1;
}

void glow_bake_mpi_end(int failed) {
    if (failed) remove_files(); /* no part of the new world; the other ranks do the same when stopped */
    if (failed && g_ranks > 1) {
        fflush(stdout);
        fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, 1); /* the launcher stops the other ranks */
    }
    if (!failed) maybe_die(1);
    if (!failed && g_ranks > 1) MPI_Barrier(MPI_COMM_WORLD); /* rank 0 is here once the manifest is written */
    g_armed = 0;
    free(g_files);
    free(g_pids);
    g_files = NULL;
    g_pids = NULL;
    MPI_Finalize();
}
