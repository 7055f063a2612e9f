/* `dartspp render SCENE.json [options]`: the flags, then the render command (render_run, src/render). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/cli.h"

/* "8G", "512M", "100000K", "1e9": bytes (binary suffixes), or -1. */
static double parse_bytes(const char *v)
{
    char *end;
    errno = 0;
    double d = v ? strtod(v, &end) : -1;
    if (!v || end == v || errno || !(d > 0) || !isfinite(d)) return -1;
    const char *units = "KMGT";
    const char *u = *end ? strchr(units, *end) : NULL;
    if (*end && (!u || end[1])) return -1;
    for (const char *p = units; u && p <= u; p++) d *= 1024.0;
    return d;
}

static int bad_arg(const char *opt, const char *val, const char *why)
{
    fprintf(stderr, "dartspp render: %s %s: %s\n", opt, val ? val : "", why);
    return dp_exit_status(DP_ERROR_INPUT);
}

static int parse_number(const char *opt, const char *val, double lo, double *out)
{
    char *end;
    errno = 0;
    double d = val ? strtod(val, &end) : 0;
    if (!val || end == val || *end || errno || !isfinite(d) || d < lo) return -1;
    (void)opt;
    *out = d;
    return 0;
}

/* The flags into rq; sets (argc entries) receives the --set values. 0, or the exit status of bad input with
 * the message on stderr. */
static int parse_args(int argc, char **argv, render_request *rq, const char **sets)
{
    *rq = (render_request){.seed = 1, .spp = -1, .time_limit = -1, .checkpoint = -1, .log_every = 1.0, .sets = sets};
    for (int i = 0; i < argc; i++) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        double d;
        if (!strcmp(o, "--verbose")) rq->verbose = 1;
        else if (!strcmp(o, "--quiet")) rq->quiet = 1;
        else if (!strcmp(o, "--no-cube")) rq->skip |= RENDER_SKIP_CUBE;
        else if (!strcmp(o, "--no-viewer")) rq->skip |= RENDER_SKIP_VIEWER;
        else if (!strcmp(o, "--resume")) rq->resume = 1;
        else if (!strcmp(o, "--overwrite")) rq->overwrite = 1;
        else if (!strcmp(o, "--threads") || !strcmp(o, "--seed") || !strcmp(o, "--spp") || !strcmp(o, "--time")) {
            if (parse_number(o, v, 0, &d)) return bad_arg(o, v, "expected a non-negative number");
            if (!strcmp(o, "--threads")) rq->threads = (int)d;
            else if (!strcmp(o, "--seed")) rq->seed = (uint64_t)d;
            else if (!strcmp(o, "--spp")) rq->spp = (long)d;
            else rq->time_limit = d;
            i++;
        } else if (!strcmp(o, "--checkpoint")) {
            if (parse_number(o, v, 0, &rq->checkpoint)) return bad_arg(o, v, "expected seconds (0: no checkpoints)");
            i++;
        } else if (!strcmp(o, "--max-memory")) {
            if ((rq->max_memory = parse_bytes(v)) < 0) return bad_arg(o, v, "expected a size such as 8G, 512M or 1e9");
            i++;
        } else if (!strcmp(o, "--log-every")) {
            if (parse_number(o, v, 0, &rq->log_every)) return bad_arg(o, v, "expected seconds (0: every pass)");
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
        } else if (o[0] == '-') return bad_arg(o, NULL, "unknown option");
        else if (rq->scene_path) return bad_arg(o, NULL, "only one scene file");
        else rq->scene_path = o;
    }
    if (!rq->scene_path) return bad_arg("", NULL, "missing SCENE.json");
    if (!rq->log != !rq->reference) return bad_arg(rq->log ? "--log" : "--reference", NULL, "--log and --reference go together");
    /* --time alone renders for that long; --spp alone renders that many passes */
    if (rq->time_limit >= 0 && rq->spp < 0) rq->spp = 0;
    if (rq->spp >= 0 && rq->time_limit < 0) rq->time_limit = 0;
    return 0;
}

int cli_render(int argc, char **argv) { return cli_render_cluster(argc, argv, NULL); }

int cli_render_cluster(int argc, char **argv, const render_cluster *cluster)
{
    render_request rq;
    const char **sets = calloc((size_t)argc + 1, sizeof(char *));
    int rc = parse_args(argc, argv, &rq, sets);
    rc = rc ? render_run_refused(cluster, rc) : render_run(&rq, cluster);
    free(sets);
    return rc;
}
