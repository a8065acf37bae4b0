/* bake_mpi.h — glow-bake --mpi (bake_mpi.c; built when CMake finds MPI: GLOW_HAVE_MPI). */
#ifndef GLOW_BAKE_MPI_H
#define GLOW_BAKE_MPI_H

#include <stddef.h>

#include "glow/glow_precompute.h"

/* MPI_Init, this process's rank and the exchange; 0 with a message in err when MPI cannot start. */
int glow_bake_mpi_begin(int *argc, char ***argv, glow_pc_distribution *d, char *err, size_t n);
/* The world manifest's path (-o): once a new file is there, a stopped rank removes nothing. */
void glow_bake_mpi_output(const char *manifest);
/* failed: MPI_Abort (the launcher stops the other ranks); else MPI_Finalize. */
void glow_bake_mpi_end(int failed);

#endif
