/* `dartspp render SCENE.json [options]`: the flags, then the render command (render_run, src/render). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/cli.h"

/* The most threads a render accepts (the table of options, src/render/options_check.c, holds the check). */
#define MAX_THREADS 1024

static void render_usage(FILE *f)
{
    fprintf(f, "usage: dartspp render SCENE.json [options]   (dartspp-mpi render: the same, on MPI ranks)\n"
               "  --output PATH       the image, .exr or .pfm (default: <scene>/<scene>.exr); the preview, frames,\n"
               "                      cube, viewer and checkpoint state go beside it\n"
               "  --spp N             progressive passes; --time SECONDS: a wall-time budget (--spp 0 --time 0:\n"
               "  --time SECONDS      until Ctrl-C)\n"
               "  --threads N         worker threads, 0 (all cores, the default) to %d\n"
               "  --seed S            an integer 0 to 18446744073709551615 (default 1)\n"
               "  --set KEY=VALUE     overrides an integrator or renderer key (repeatable; dartspp keys lists them)\n"
               "  --derivative POINTER  the derivative of every image with respect to the scene value the JSON\n"
               "                      Pointer names, e.g. /media/0/sigma_s (repeatable; docs/derivatives.md §1)\n"
               "  --checkpoint SECONDS  all outputs and the state <stem>.state every SECONDS of rendering (0: none)\n"
               "  --resume            goes on from the checkpoint state <stem>.state\n"
               "  --overwrite         replaces a checkpoint state holding more passes than this run renders\n"
               "  --reference REF.exr  with --log: the image's error against REF as the render goes\n"
               "  --log RUN.csv       the error log's CSV (with --reference)\n"
               "  --log-every SECONDS  between the log's rows (default 1; 0: every pass)\n"
               "  --max-memory SIZE   the memory guard's limit, e.g. 8G, 512M or 1e9\n"
               "  --reduce-every SECONDS  dartspp-mpi: the ranks' sums into the state this often (default 30; 0: never)\n"
               "  --no-cube           no transient cube <stem>_cube.npy (frame mode)\n"
               "  --no-viewer         no viewer page <stem>_viewer.html (frame mode)\n"
               "  --verbose           every ignored scene key and the resolved plan\n"
               "  --quiet             no progress line\n"
               "  -h, --help          this text\n"
               "See docs/cli.md for every option, the outputs and the exit status.\n", MAX_THREADS);
}

static int bad_arg(const char *opt, const char *val, const char *why)
{
    fprintf(stderr, "dartspp render: %s %s: %s\n", opt, val ? val : "", why);
    return dp_exit_status(DP_ERROR_INPUT);
}

/* An option of the table shared with the embedding API (render.h): parsed and range-checked there, so that
 * `dartspp render` and `dartspp.render()` refuse the same values with the same message. */
static int option(const char *o, const char *v, render_opt_value *out)
{
    dp_error err;
    if (!render_opt_parse((render_opt)render_opt_find(o), v, out, &err)) return 0;
    fprintf(stderr, "dartspp render: %s\n", err.msg);
    return dp_exit_status(DP_ERROR_INPUT);
}

/* The flags into rq; sets and derivs (argc entries each) receive the --set and --derivative values. 0, or the
 * exit status of bad input with
 * the message on stderr. */
static int parse_args(int argc, char **argv, render_request *rq, const char **sets, const char **derivs)
{
    *rq = (render_request){.seed = 1, .spp = -1, .time_limit = -1, .checkpoint = -1, .log_every = 1.0, .reduce_every = 30.0,
                          .sets = sets, .derivatives = derivs};
    for (int i = 0; i < argc; i++) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "--verbose")) rq->verbose = 1;
        else if (!strcmp(o, "--quiet")) rq->quiet = 1;
        else if (!strcmp(o, "--no-cube")) rq->skip |= RENDER_SKIP_CUBE;
        else if (!strcmp(o, "--no-viewer")) rq->skip |= RENDER_SKIP_VIEWER;
        else if (!strcmp(o, "--resume")) rq->resume = 1;
        else if (!strcmp(o, "--overwrite")) rq->overwrite = 1;
        else if (render_opt_find(o) >= 0) {
            render_opt_value x;
            int rc = option(o, v, &x);
            if (rc) return rc;
            switch (render_opt_find(o)) {
            case RENDER_OPT_THREADS: rq->threads = (int)x.u; break;
            case RENDER_OPT_SEED: rq->seed = x.u; break;
            case RENDER_OPT_SPP: rq->spp = (long)x.u; break;
            case RENDER_OPT_TIME: rq->time_limit = x.d; break;
            case RENDER_OPT_CHECKPOINT: rq->checkpoint = x.d; break;
            case RENDER_OPT_LOG_EVERY: rq->log_every = x.d; break;
            case RENDER_OPT_REDUCE_EVERY: rq->reduce_every = x.d; break;
            default: rq->max_memory = x.d; break;
            }
            i++;
        } else if (!strcmp(o, "--reference") || !strcmp(o, "--log")) {
            if (!v) return bad_arg(o, v, "expected a path");
            *(!strcmp(o, "--log") ? &rq->log : &rq->reference) = argv[++i];
        } else if (!strcmp(o, "--output")) {
            if (!v) return bad_arg(o, v, "expected a path");
            rq->output = argv[++i];
        } else if (!strcmp(o, "--set")) {
            if (!v || !strchr(v, '=')) return bad_arg(o, v, "expected key=value");
            sets[rq->set_count++] = argv[++i];
        } else if (!strcmp(o, "--derivative")) {
            /* checked against the scene when it loads (src/scene/diff_params.c) */
            if (!v) return bad_arg(o, v, "expected a JSON Pointer, e.g. /media/0/sigma_s");
            derivs[rq->derivative_count++] = argv[++i];
        } else if (o[0] == '-') return bad_arg(o, NULL, "unknown option");
        else if (rq->scene_path) return bad_arg(o, NULL, "only one scene file");
        else rq->scene_path = o;
    }
    if (!rq->scene_path) return bad_arg("", NULL, "missing SCENE.json");
    if (!rq->log != !rq->reference) return bad_arg(rq->log ? "--log" : "--reference", NULL, "--log and --reference go together");
    /* 0 is "no limit": one budget flag alone at 0 leaves nothing to end the render (docs/cli.md §2.1) */
    if (rq->time_limit == 0 && rq->spp < 0)
        return bad_arg("--time", "0", "0 is no time limit, and without --spp nothing would end the render (give "
                                      "seconds > 0, or --spp N; --spp 0 --time 0 renders until Ctrl-C)");
    if (rq->spp == 0 && rq->time_limit < 0)
        return bad_arg("--spp", "0", "0 is no pass limit, and without --time nothing would end the render (give "
                                     "N > 0, or --time S; --spp 0 --time 0 renders until Ctrl-C)");
    /* --time alone renders for that long; --spp alone renders that many passes */
    if (rq->time_limit >= 0 && rq->spp < 0) rq->spp = 0;
    if (rq->spp >= 0 && rq->time_limit < 0) rq->time_limit = 0;
    return 0;
}

int cli_render(int argc, char **argv) { return cli_render_cluster(argc, argv, NULL); }

int cli_render_cluster(int argc, char **argv, const render_cluster *cluster)
{
    if (cli_help_asked(argc, argv)) {
        if (!cluster || cluster->rank == 0) render_usage(stdout);
        return 0;
    }
    render_request rq;
    const char **sets = calloc((size_t)argc + 1, sizeof(char *));
    const char **derivs = calloc((size_t)argc + 1, sizeof(char *));
    int rc = sets && derivs ? parse_args(argc, argv, &rq, sets, derivs) : dp_exit_status(DP_ERROR_MEMORY);
    /* --reduce-every paces dartspp-mpi's reductions; one process has none (accepted, so that one command line
     * serves both binaries, but said) */
    for (int i = 0; !rc && !cluster && i < argc; i++)
        if (!strcmp(argv[i], "--reduce-every"))
            fprintf(stderr, "warning: --reduce-every has no effect in dartspp (one process: no reductions); it paces "
                            "dartspp-mpi's\n");
    rc = rc ? render_run_refused(cluster, rc) : render_run(&rq, cluster);
    free(sets);
    free(derivs);
    return rc;
}
