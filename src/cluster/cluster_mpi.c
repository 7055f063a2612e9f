/* The render_cluster operations over MPI (Open MPI from Debian; any MPI-3 library): one collective per
 * round (MPI_Allreduce of the go flags and rank 0's gather wish), MPI_Reduce of the films and statistics onto
 * rank 0. Errors are returned (MPI_ERRORS_RETURN), not fatal. Linked into dartspp-mpi only (Makefile): the library never calls MPI itself. */
#include <mpi.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/cluster.h"
#include "dartspp/render.h"

static int mpi_round(const render_cluster *c, int *go, int *gather)
{
    (void)c;
    /* MIN of the go flags; MIN of −gather is −1 exactly when rank 0 (the only one that may ask) asks */
    int in[2] = {*go ? 1 : 0, *gather && c->rank == 0 ? -1 : 0}, out[2];
    if (MPI_Allreduce(in, out, 2, MPI_INT, MPI_MIN, MPI_COMM_WORLD) != MPI_SUCCESS) return -1;
    *go = out[0];
    *gather = out[1] < 0;
    return 0;
}

/* Reduces n values of a type onto rank 0 in chunks (MPI counts are int). */
static int reduce_chunks(const void *mine, void *total, size_t n, MPI_Datatype type, size_t elem, int rank)
{
    const size_t chunk = (size_t)1 << 24;
    for (size_t off = 0; off < n; off += chunk) {
        int k = (int)(n - off < chunk ? n - off : chunk);
        const char *src = (const char *)mine + off * elem;
        char *dst = rank == 0 ? (char *)total + off * elem : NULL;
        if (MPI_Reduce(src, dst, k, type, MPI_SUM, 0, MPI_COMM_WORLD) != MPI_SUCCESS) return -1;
    }
    return 0;
}

/* The sums of a film and of its derivative films (film.h: deriv, each of the same size and layers; every rank
 * has the same K, from the same scene and --derivative list) onto rank 0. */
static int reduce_film_sums(const film *mine, film *total, int rank)
{
    size_t n = (size_t)mine->width * mine->height * 3, nf = n * (size_t)time_window_layers(&mine->window);
    if (reduce_chunks(mine->sum, total->sum, n, MPI_DOUBLE, sizeof(double), rank) ||
        (nf > 0 && reduce_chunks(mine->frame_sum, total->frame_sum, nf, MPI_FLOAT, sizeof(float), rank)))
        return -1;
    size_t na = n * 2 * (size_t)mine->window.amcw_count; /* the AMCW sums (docs/amcw.md), the image's only */
    if (na > 0 && reduce_chunks(mine->amcw_sum, total->amcw_sum, na, MPI_DOUBLE, sizeof(double), rank)) return -1;
    for (int k = 0; k < mine->deriv_count; k++)
        if (reduce_film_sums(&mine->deriv[k], &total->deriv[k], rank)) return -1;
    return 0;
}

/* A derivative film's passes and weights are its image's: the sums divide by the same weight sum. */
static void set_deriv_counts(film *total)
{
    for (int k = 0; k < total->deriv_count; k++) {
        film *d = &total->deriv[k];
        d->passes = total->passes;
        d->weight_sum = total->weight_sum;
        d->last_weight = total->last_weight;
        set_deriv_counts(d);
    }
}

static int mpi_reduce(const render_cluster *c, const film *mine, film *total, const render_stats *st_mine,
                      render_stats *st_total, dp_error *err)
{
    if (reduce_film_sums(mine, total, c->rank))
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "MPI: the reduction of the films failed");
    /* the scalars: the film's counts and weight sum, then the figures that add up over the ranks (RENDER_SUM),
     * and apart those of which the largest counts (RENDER_MAX); the other figures are rank 0's */
    double v[3 + RENDER_FIGURE_COUNT], w[3 + RENDER_FIGURE_COUNT], m[RENDER_FIGURE_COUNT], m_all[RENDER_FIGURE_COUNT];
    v[0] = (double)mine->passes;
    v[1] = mine->weight_sum;
    v[2] = (double)mine->nonfinite;
    int ns = 3 + render_stats_pack(st_mine, RENDER_SUM, v + 3), nm = render_stats_pack(st_mine, RENDER_MAX, m);
    if (MPI_Reduce(v, w, ns, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD) != MPI_SUCCESS ||
        MPI_Reduce(m, m_all, nm, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD) != MPI_SUCCESS)
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "MPI: the reduction of the statistics failed");
    if (c->rank != 0) return 0;
    total->passes = (long)w[0];
    total->weight_sum = w[1];
    total->nonfinite = (long)w[2];
    set_deriv_counts(total);
    *st_total = *st_mine;
    render_stats_unpack(st_total, RENDER_SUM, w + 3);
    render_stats_unpack(st_total, RENDER_MAX, m_all);
    st_total->passes = total->passes;
    st_total->nonfinite = total->nonfinite;
    return 0;
}

static int mpi_agree_rc(const render_cluster *c, int rc)
{
    (void)c;
    int all = rc;
    if (MPI_Allreduce(&rc, &all, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD) != MPI_SUCCESS) return rc ? rc : 1;
    return all;
}

static int mpi_share(const render_cluster *c, double *v, int n)
{
    (void)c;
    return MPI_Bcast(v, n, MPI_DOUBLE, 0, MPI_COMM_WORLD) == MPI_SUCCESS ? 0 : -1;
}

int cluster_mpi_start(int *argc, char ***argv, render_cluster *c)
{
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) return -1;
    memset(c, 0, sizeof *c);
    /* a failed call returns its error instead of aborting the job: an MPI that survives a lost rank lets the
     * driver end the render with the last reduction's passes (DP_ERROR_LOST) */
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, &c->rank);
    MPI_Comm_size(MPI_COMM_WORLD, &c->size);
    MPI_Comm node;
    c->ranks_on_node = 1;
    if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) == MPI_SUCCESS) {
        MPI_Comm_size(node, &c->ranks_on_node);
        MPI_Comm_free(&node);
    }
    c->round = mpi_round;
    c->reduce = mpi_reduce;
    c->agree_rc = mpi_agree_rc;
    c->share = mpi_share;
    return 0;
}

void cluster_mpi_stop(void) { MPI_Finalize(); }
