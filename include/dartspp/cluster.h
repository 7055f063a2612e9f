/* dartspp cluster: rendering on several processes (MPI ranks) as one render. The render driver sees only
 * the table of operations it needs (render_cluster, include/dartspp/render.h: how the ranks share the
 * iterations and sum the films); this module implements it. The MPI implementation lives in
 * src/cluster/cluster_mpi.c and is linked into dartspp-mpi only, so the library and dartspp need no MPI. */
#ifndef DARTSPP_CLUSTER_H
#define DARTSPP_CLUSTER_H

#include "dartspp/render.h"

/* dartspp-mpi only (src/cluster/cluster_mpi.c): MPI_Init_thread and the operations over MPI_COMM_WORLD;
 * 0, or -1 when MPI does not start. cluster_mpi_stop: MPI_Finalize. */
int cluster_mpi_start(int *argc, char ***argv, render_cluster *c);
void cluster_mpi_stop(void);

#endif
