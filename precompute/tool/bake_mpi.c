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
 * (SIGKILL) at its first exchange: the tests' way to check that path. */
#include "bake_mpi.h"

#include <mpi.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int g_rank = -1, g_ranks = 0;
static char g_stop_msg[160];
static size_t g_stop_len;

/* async-signal-safe: write(2) and _exit(2) only */
static void on_stop(int sig) {
    (void)sig;
    if (g_stop_len) {
        ssize_t w = write(2, g_stop_msg, g_stop_len);
        (void)w;
    }
    _exit(1);
}

static glow_result share(void *user, void *buf, const size_t *offsets) {
    (void)user;
    static int first = 1;
    if (first) {
        first = 0;
        const char *f = getenv("GLOW_BAKE_MPI_FAIL_RANK");
        if (f && *f && atoi(f) == g_rank) {
            fprintf(stderr, "glow-bake: rank %d of %d: GLOW_BAKE_MPI_FAIL_RANK: dying now (test)\n", g_rank, g_ranks);
            fflush(stderr);
            raise(SIGKILL);
        }
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
    *d = (glow_pc_distribution){.rank = (uint32_t)g_rank, .ranks = (uint32_t)g_ranks, .share = share};
    return 1;
}

void glow_bake_mpi_end(int failed) {
    if (failed && g_ranks > 1) {
        fflush(stdout);
        fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, 1); /* the launcher stops the other ranks */
    }
    MPI_Finalize();
}
