/* dartspp: entry point and sub-command dispatch. */
#include <limits.h>
#include <malloc.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "dartspp/cli.h"

/* The version, from one place: the Makefile's VERSION (and the commit it was built from, when built in a git
 * checkout). */
#ifndef DARTSPP_VERSION
#define DARTSPP_VERSION "unknown"
#endif
#ifndef DARTSPP_COMMIT
#define DARTSPP_COMMIT ""
#endif

static int version(const char *prog)
{
    printf("%s %s%s%s%s\n", prog, DARTSPP_VERSION, DARTSPP_COMMIT[0] ? " (commit " : "", DARTSPP_COMMIT,
           DARTSPP_COMMIT[0] ? ")" : "");
    return 0;
}

static int is_version_flag(const char *a) { return !strcmp(a, "--version") || !strcmp(a, "-V"); }

static void usage(FILE *f)
{
    fprintf(f,
            "usage: dartspp render SCENE.json [--threads N] [--seed S] [--spp N] [--time SECONDS]\n"
            "                      [--output PATH.exr|.pfm] [--checkpoint SECONDS] [--resume | --overwrite]\n"
            "                      [--set key=value ...] [--derivative POINTER ...]\n"
            "                      [--reference REF.exr --log RUN.csv [--log-every SECONDS]]\n"
            "                      [--max-memory SIZE] [--no-cube] [--no-viewer] [--verbose] [--quiet]\n"
            "                      [--reduce-every SECONDS]  (dartspp-mpi: the checkpoint state's interval)\n"
            "       dartspp compare IMAGE REFERENCE [--csv]      (EXR or PFM)\n"
            "       dartspp patch-mean IMAGE X0 Y0 X1 Y1 [--mask MASK]  (mean of a pixel rectangle)\n"
            "       dartspp merge OUTPUT IMAGE IMAGE [IMAGE...]   (mean of independent renders, its variance)\n"
            "       dartspp table --sigma-s S --sigma-a A --g G [--shape R,S,C] [--s-max X] --output FILE\n"
            "                                                     (EDA direction-sampling table)\n"
            "       dartspp keys [--markdown]                     (the scene's integrator and renderer keys)\n"
            "       dartspp counts CUBE.npy --output COUNTS.npy --pulses N --scale S [...]\n"
            "                                                     (photon-counting histograms of a cube)\n"
            "       dartspp --version | -V                        (the version and commit)\n"
            "`dartspp COMMAND --help` (or -h) lists every flag of a command. See docs/ for the scene keys, outputs\n"
            "and units.\n");
}

/* The process keeps the memory it frees. Every pass allocates and frees photon buffers, maps and splat lists
 * of tens to hundreds of MiB; handed back to the kernel each time (munmap, heap trims), they are paid again as
 * page faults, and each unmapping stops the other threads for a TLB shootdown — within one process only, so
 * two threads scaled worse than two processes (dragon 480², 10 passes, 2 threads ÷ 1: 1.77 before, 1.86 with
 * this). The peak resident size stays that of one pass (dragon 480², 25 passes: 179 MiB), since the next
 * pass reuses the same blocks — as long as nothing asks the heap for aligned huge-page blocks: the volume map
 * once did (2 MiB-aligned arrays with MADV_HUGEPAGE), and the peak then grew pass after pass to 610 MiB
 * (tests/cli/test_cli.c checks the peak against the memory guard's estimate). Set here, by the program that owns
 * the process, not by the library. */
static void keep_freed_memory(void)
{
    mallopt(M_MMAP_MAX, 0);
    mallopt(M_TRIM_THRESHOLD, INT_MAX);
}

#ifdef DARTSPP_MPI
/* dartspp-mpi: `mpirun -np N dartspp-mpi render SCENE.json [the options of dartspp render]`; the other
 * commands need no cluster and stay in dartspp. */
int main(int argc, char **argv)
{
    signal(SIGXFSZ, SIG_IGN); /* a file-size limit fails the write (EFBIG, reported) instead of killing */
    keep_freed_memory();
    render_cluster c;
    if (cluster_mpi_start(&argc, &argv, &c)) {
        fprintf(stderr, "dartspp-mpi: MPI did not start\n");
        return 1;
    }
    int rc;
    if (argc >= 2 && is_version_flag(argv[1])) rc = c.rank == 0 ? version("dartspp-mpi") : 0;
    else if (argc >= 2 && !strcmp(argv[1], "render")) rc = cli_render_cluster(argc - 2, argv + 2, &c);
    else {
        if (c.rank == 0) {
            fprintf(stderr, "dartspp-mpi: only 'render' runs on a cluster (the other commands: dartspp)\n");
            usage(stderr);
        }
        rc = 2;
    }
    cluster_mpi_stop();
    return rc;
}
#else
int main(int argc, char **argv)
{
    signal(SIGXFSZ, SIG_IGN); /* a file-size limit fails the write (EFBIG, reported) instead of killing */
    keep_freed_memory();
    if (argc < 2 || !strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (is_version_flag(argv[1])) return version("dartspp");
    if (!strcmp(argv[1], "render")) return cli_render(argc - 2, argv + 2);
    if (!strcmp(argv[1], "compare")) return cli_compare(argc - 2, argv + 2);
    if (!strcmp(argv[1], "patch-mean")) return cli_patch_mean(argc - 2, argv + 2);
    if (!strcmp(argv[1], "merge")) return cli_merge(argc - 2, argv + 2);
    if (!strcmp(argv[1], "table")) return cli_table(argc - 2, argv + 2);
    if (!strcmp(argv[1], "keys")) return cli_keys(argc - 2, argv + 2);
    if (!strcmp(argv[1], "counts")) return cli_counts(argc - 2, argv + 2);
    fprintf(stderr, "dartspp: unknown command '%s' (commands: render, compare, patch-mean, merge, table, keys, counts)\n", argv[1]);
    usage(stderr);
    return 2;
}
#endif
