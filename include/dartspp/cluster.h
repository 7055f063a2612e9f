/* dartspp cluster: rendering on several processes (MPI ranks) as one render. Every iteration is an
 * independent draw whose random numbers and radii depend only on the seed and the iteration index, so rank r
 * of N renders iterations r, r + N, r + 2N, ... ("rounds": in round k every rank renders iteration kN + r),
 * rank 0 decides after each round whether the render goes on, and the films are summed onto rank 0, which
 * alone writes. The render driver only sees this table of operations; the MPI implementation lives in
 * src/cluster/cluster_mpi.c and is linked into dartspp-mpi only, so the library and dartspp need no MPI. */
#ifndef DARTSPP_CLUSTER_H
#define DARTSPP_CLUSTER_H

#include "dartspp/film.h"

struct render_stats;

typedef struct render_cluster render_cluster;
struct render_cluster {
    int rank, size;          /* this process, and how many render together */
    int ranks_on_node;       /* processes sharing this machine (the memory guard counts them all) */
    void *ctx;
    /* After every round, on every rank (collective): *go is 1 on entry if this rank would go on (rank 0:
     * its budget allows another round; any rank: not interrupted, no error); on return, 1 only if every rank
     * said 1. *gather is rank 0's wish (ignored elsewhere) to have the films summed now (a checkpoint); on
     * return, rank 0's wish on every rank. 0, or -1 when the communication failed. */
    int (*round)(const render_cluster *c, int *go, int *gather);
    /* Sums the films' pass sums, weight sums, pass counts and non-finite counts, and the statistics, onto
     * rank 0 (collective; total and st_total are written on rank 0 only, total already initialised like
     * mine). 0, or -1 with err. */
    int (*reduce)(const render_cluster *c, const film *mine, film *total,
                  const struct render_stats *st_mine, struct render_stats *st_total, dp_error *err);
    /* Whether any rank had rc != 0 (collective): the largest rc of all ranks, on every rank. */
    int (*agree_rc)(const render_cluster *c, int rc);
    /* Rank 0's values of n doubles, on every rank (collective). */
    int (*share)(const render_cluster *c, double *v, int n);
};

/* dartspp-mpi only (src/cluster/cluster_mpi.c): MPI_Init_thread and the operations over MPI_COMM_WORLD;
 * 0, or -1 when MPI does not start. cluster_mpi_stop: MPI_Finalize. */
int cluster_mpi_start(int *argc, char ***argv, render_cluster *c);
void cluster_mpi_stop(void);

#endif
