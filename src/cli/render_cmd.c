/* `dartspp render SCENE.json [options]`: load, render progressively, write the outputs. */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "dartspp/cli.h"
#include "dartspp/darts.h"
#include "dartspp/render.h"
#include "dartspp/surface.h"

typedef struct {
    const char *scene_path;
    const char *output;
    const char **sets;
    int set_count;
    int verbose, quiet;
    double checkpoint; /* seconds between checkpoints; < 0: as the scene says; 0: none */
    const char *reference, *log;
    double log_every;
    double max_memory; /* bytes; 0: what the machine has available */
    int skip;          /* RENDER_SKIP_CUBE, RENDER_SKIP_VIEWER: --no-cube, --no-viewer */
    render_options ro;
} render_args;

/* Exit status of a render ended by SIGINT/SIGTERM (128 + SIGINT, as shells report it). */
#define EXIT_INTERRUPTED 130

static dp_stop_flag stop_requested = 0; /* set by the signal handler, read by the passes */
static dp_stop_flag passes_started = 0; /* set by the driver: from then on an interrupt keeps the passes done */

static void say(const char *msg) { (void)!write(2, msg, strlen(msg)); }

/* First SIGINT/SIGTERM: the pass in progress stops within a batch or a row and is dropped, and the completed
 * passes are written. Before the first pass (loading, EDA tables) there is nothing to keep, and a second
 * signal means "now": both exit at once. Only async-signal-safe calls here. */
static void on_signal(int sig)
{
    (void)sig;
    if (!passes_started || stop_requested) {
        say("\ndartspp render: interrupted, exiting now\n");
        _exit(EXIT_INTERRUPTED);
    }
    stop_requested = 1;
    say("\ndartspp render: interrupted: stopping the pass in progress and writing the completed passes "
        "(interrupt again to exit at once)\n");
}

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
    return 2;
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

static int parse_args(int argc, char **argv, render_args *a)
{
    a->ro = (render_options){.threads = 0, .seed = 1, .spp = -1, .time_limit = -1, .progress = 1};
    a->checkpoint = -1;
    a->log_every = 1.0;
    a->sets = calloc((size_t)argc + 1, sizeof(char *));
    for (int i = 0; i < argc; i++) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        double d;
        if (!strcmp(o, "--verbose")) a->verbose = 1;
        else if (!strcmp(o, "--quiet")) a->quiet = 1;
        else if (!strcmp(o, "--no-cube")) a->skip |= RENDER_SKIP_CUBE;
        else if (!strcmp(o, "--no-viewer")) a->skip |= RENDER_SKIP_VIEWER;
        else if (!strcmp(o, "--threads") || !strcmp(o, "--seed") || !strcmp(o, "--spp") || !strcmp(o, "--time")) {
            if (parse_number(o, v, 0, &d)) return bad_arg(o, v, "expected a non-negative number");
            if (!strcmp(o, "--threads")) a->ro.threads = (int)d;
            else if (!strcmp(o, "--seed")) a->ro.seed = (uint64_t)d;
            else if (!strcmp(o, "--spp")) a->ro.spp = (long)d;
            else a->ro.time_limit = d;
            i++;
        } else if (!strcmp(o, "--checkpoint")) {
            if (parse_number(o, v, 0, &a->checkpoint)) return bad_arg(o, v, "expected seconds (0: no checkpoints)");
            i++;
        } else if (!strcmp(o, "--max-memory")) {
            if ((a->max_memory = parse_bytes(v)) < 0) return bad_arg(o, v, "expected a size such as 8G, 512M or 1e9");
            i++;
        } else if (!strcmp(o, "--log-every")) {
            if (parse_number(o, v, 0, &a->log_every)) return bad_arg(o, v, "expected seconds (0: every pass)");
            i++;
        } else if (!strcmp(o, "--reference") || !strcmp(o, "--log")) {
            if (!v) return bad_arg(o, v, "expected a path");
            *(!strcmp(o, "--log") ? &a->log : &a->reference) = argv[++i];
        } else if (!strcmp(o, "--output")) {
            if (!v) return bad_arg(o, v, "expected a path");
            a->output = argv[++i];
        } else if (!strcmp(o, "--set")) {
            if (!v || !strchr(v, '=')) return bad_arg(o, v, "expected key=value");
            a->sets[a->set_count++] = argv[++i];
        } else if (o[0] == '-') return bad_arg(o, NULL, "unknown option");
        else if (a->scene_path) return bad_arg(o, NULL, "only one scene file");
        else a->scene_path = o;
    }
    if (!a->scene_path) return bad_arg("", NULL, "missing SCENE.json");
    if (!a->log != !a->reference) return bad_arg(a->log ? "--log" : "--reference", NULL, "--log and --reference go together");
    /* --time alone renders for that long; --spp alone renders that many passes */
    if (a->ro.time_limit >= 0 && a->ro.spp < 0) a->ro.spp = 0;
    if (a->ro.spp >= 0 && a->ro.time_limit < 0) a->ro.time_limit = 0;
    return 0;
}

/* --output, else the scene's hdr_output_file, else <scene stem>.exr; relative to the working folder. */
static void output_path(const render_args *a, const scene *s, char *out, size_t n)
{
    if (a->output) snprintf(out, n, "%s", a->output);
    else if (s->renderer.hdr_output_file[0]) snprintf(out, n, "%s", s->renderer.hdr_output_file);
    else {
        const char *base = strrchr(a->scene_path, '/');
        base = base ? base + 1 : a->scene_path;
        const char *dot = strrchr(base, '.');
        snprintf(out, n, "%.*s.exr", (int)(dot ? dot - base : (long)strlen(base)), base);
    }
}

static void print_written(const char *path) { printf("wrote %s\n", path); }

/* Checkpoints: every `every` seconds of rendering, the outputs of all completed passes, written atomically
 * (an interrupted or killed render keeps the last complete set). */
typedef struct {
    const render_plan *p;
    const char *plan_json;
    const char *out;
    double every, last;
    int quiet;
    int skip;          /* render_write_outputs */
    error_log *log;    /* --log: error against --reference (may be NULL) */
} after_pass_ctx;

static int after_pass(void *ctx, const film *f, const render_stats *st, dp_error *err)
{
    after_pass_ctx *c = ctx;
    if (error_log_pass(c->log, f, st, 0, err)) return -1;
    if (c->every <= 0 || st->seconds - c->last < c->every) return 0;
    c->last = st->seconds;
    dp_error werr;
    if (render_write_outputs(f, c->out, c->p->type_name, c->plan_json, c->skip, NULL, &werr)) {
        /* the render goes on: its end writes again, to a rescue folder if need be */
        fprintf(stderr, "%swarning: checkpoint not written: %s\n", isatty(2) ? "\r\033[K" : "", werr.msg);
        return 0;
    }
    if (!c->quiet)
        fprintf(stderr, "%scheckpoint: %ld passes, %.1f s -> %s\n", isatty(2) ? "\r\033[K" : "", st->passes,
                st->seconds, c->out);
    return 0;
}

/* Specular and near-specular surfaces break two assumptions, and the user should hear which one applies
 * (src/darts/README.md, mirrors): the path tracer cannot reach a point light through a delta lobe (mirror,
 * smooth metal or glass, a plastic's coat), so light that takes one before any diffuse, glossy or medium
 * vertex is missing; DARTS's time bounds and control vertices assume a straight camera leg, so what the
 * camera sees through a surface it continues through (surface_photon_split) is biased. */
static void warn_mirrors(const scene *s, const render_plan *p)
{
    const char *delta = NULL, *continued = NULL;
    for (int i = 0; i < s->surface_count; i++) {
        const bsdf *b = &s->bsdfs[s->surfaces[i].bsdf];
        if (s->surfaces[i].tri_count == 0 || bsdf_is_passthrough(b)) continue;
        if (!delta && (bsdf_lobes(b) & BSDF_LOBE_SPECULAR)) delta = s->surfaces[i].name;
        if (!continued && surface_photon_split(b, &p->shading).cont) continued = s->surfaces[i].name;
    }
    if (delta && p->type == INTEGRATOR_PATH_TRACER && s->light_count > 0)
        fprintf(stderr, "warning: %s: surface '%s' is specular: the path tracer cannot connect to point lights "
                "through it, so light reflected or refracted by it before any diffuse or medium vertex (caustics) "
                "is missing from the image; photon points render it\n", s->path, delta);
    const darts_plan *d = &p->darts;
    if (continued && p->type == INTEGRATOR_PHOTON_POINTS && d->active && d->mirrors == DARTS_MIRRORS_STRAIGHT &&
        d->side.seen)
        fprintf(stderr, "warning: %s: the camera sees surface '%s', which is specular or near-specular: camera paths "
                "continue through it, but with darts_mirrors \"straight\" the DARTS time bounds and control vertices "
                "assume a straight camera leg, so what the camera sees through it is too dark; darts_mirrors \"full\" "
                "(the default) renders it without that bias\n", s->path, d->side.first);
}

/* Elliptical control vertices assume one refractive index along the camera leg; when the media and vacuum
 * present in the scene differ in η, the photon pass turns them off (darts_guide.control_vertices) and the
 * user should hear why and how to get them back. */
static void warn_mixed_eta(const scene *s, const render_plan *p)
{
    if (!p->darts.active || !p->darts.elliptical_asked || p->darts.control_vertices) return;
    char list[1024] = "";
    size_t len = 0;
    int media = 0, medium = MEDIUM_VACUUM, vacuum = 0;
    for (int r = MEDIUM_VACUUM; r < s->medium_count; r++) {
        if (!scene_region_present(s, r)) continue;
        if (r == MEDIUM_VACUUM) vacuum = 1;
        else media++, medium = r;
        int n = snprintf(list + len, sizeof list - len, "%s%s%s%s η = %g", len ? ", " : "", r == MEDIUM_VACUUM ? "" : "'",
                         r == MEDIUM_VACUUM ? "vacuum" : s->media[r].name, r == MEDIUM_VACUUM ? "" : "'", medium_eta(s, r));
        if (n > 0 && (size_t)n < sizeof list - len) len += (size_t)n;
    }
    fprintf(stderr, "warning: %s: the refractive index differs between the regions of the scene (%s): elliptical "
            "control vertices are off, since they need one η along the whole camera leg (DA distance sampling and "
            "the other DARTS samplers stay on)", s->path, list);
    if (vacuum && media == 1)
        fprintf(stderr, "; if the camera, the lights and every light path stay inside '%s', "
                "vaccum_speed_of_light = %g (its speed_of_light) restores them", s->media[medium].name,
                1.0 / s->media[medium].eta);
    fprintf(stderr, "\n");
}

/* Which photon-pass samplers run (docs/design.md §4.3: the summary says which parts are active). */
static void print_samplers(const scene *s, const render_plan *p)
{
    const darts_plan *d = &p->darts;
    if (!d->active) {
        printf("photon pass: baseline (free-flight distances, photons at scattering vertices)%s\n",
               (d->distance_sampling || d->elliptical_asked) ? "; DARTS samplers off: the scene has no medium or no gate" : "");
        return;
    }
    printf("photon pass: DARTS, %s target bins; DA distance sampling %s; elliptical control vertices %s (residual %s); "
           "strict time %s", p->window.frame_count ? "per-frame" : "gate", d->distance_sampling ? "on" : "off",
           d->unwarped ? "off (camera-unwarped time)" : d->control_vertices ? "on"
           : d->elliptical_asked ? "off: refractive index not uniform" : "off",
           d->residual == RESIDUAL_EXPONENTIAL ? "exponential" : "uniform", d->strict ? "on" : "off");
    if (d->side.seen && d->mirrors == DARTS_MIRRORS_FULL) {
        printf("; behind continued surfaces (the camera sees '%s'):", d->side.first);
        if (d->cv_multi) {
            printf(" control vertices %.0f %% straight", 100.0 * d->cv_share[0]);
            for (int k = 0; k < d->side.mirror_count; k++)
                printf(", %.0f %% at the mirror image in '%s'", 100.0 * d->cv_share[1 + k],
                       s->surfaces[d->side.mirror_surface[k]].name);
            printf(", %.0f %% defensive free flight", 100.0 * d->cv_defensive);
        }
        if (d->strict) printf("%s strict mode keeps every surface photon a camera path could gather", d->cv_multi ? ";" : "");
    }
    if (d->unwarped) {
        printf("; camera-unwarped time: control vertices %s", d->control_vertices ? "on the light leg's equal-time "
               "spheres" : d->unwarped_mirror_off ? "off (the camera sees a continued surface, whose later camera "
               "segments count)" : "off");
        if (s->integrator.enable_guiding) printf(", DA distance sampling off (it aims at the camera's ellipsoid)");
    }
    for (int i = 0; i < s->medium_count; i++)
        if (p->eda[i].asked_unwarped) printf("; EDA off in '%s' (camera-unwarped time)", s->media[i].name);
    const char *sep = "; EDA direction sampling in ";
    for (int i = 0; i < s->medium_count; i++) {
        if (!p->eda[i].on) continue;
        printf("%s'%s' (alpha %g)", sep, s->media[i].name, p->eda[i].alpha);
        sep = ", ";
    }
    printf("%s", sep[0] == ';' ? "; EDA off" : "");
    sep = "; no DARTS sampling in the non-scattering media ";
    for (int i = 0; i < s->medium_count; i++) {
        if (medium_scatters(&s->media[i])) continue;
        printf("%s'%s'", sep, s->media[i].name);
        sep = ", ";
    }
    printf("\n");
}

static void print_summary(const scene *s, const render_plan *p, const render_stats *st, double load_seconds)
{
    const time_window *tw = &p->window;
    printf("scene %s (loaded in %.2f s: %u triangles, %d textures): %s, %dx%d, ", s->path, load_seconds, s->tri_count,
           s->texture_count, p->type_name, s->cam.width, s->cam.height);
    if (!tw->gated) printf("steady state (no gate)\n");
    else if (tw->frame_count) printf("%d frames of width %g from %g (%s optical path length)\n", tw->frame_count, tw->width,
                                     tw->start, tw->camera_unwarp ? "camera-unwarped" : "camera-warped");
    else printf("gate [%g, %g) (%s optical path length)\n", tw->start, time_window_end(tw),
                tw->camera_unwarp ? "camera-unwarped" : "camera-warped");
    printf("rendered %ld passes in %.2f s (%.2f M camera rays/s, %.2f M rays/s)%s; non-finite samples suppressed: %ld\n",
           st->passes, st->seconds, st->seconds > 0 ? st->camera_rays / st->seconds * 1e-6 : 0.0,
           st->seconds > 0 ? st->rays / st->seconds * 1e-6 : 0.0, st->interrupted ? " (interrupted)" : "", st->nonfinite);
    if (p->type == INTEGRATOR_PHOTON_POINTS) print_samplers(s, p);
    if (st->early_exits > 0)
        printf("early exit: %.1f%% of the light paths ended as soon as no photon could reach their bin\n",
               100.0 * st->early_exits / st->photon_paths);
    if (st->aimed_paths > 0 && st->aimed_paths < st->photon_paths)
        printf("volume budget: full after %.1f%% of the light paths; the rest fed only the surface map "
               "(free flight, no control vertices)\n",
               100.0 * st->aimed_paths / st->photon_paths);
    if (st->chain_paths > 0)
        printf("surface chains: %.1f%% of the light paths; %.2f%% of the independent ones stored a surface photon "
               "that can count; %.1f%% of the small steps accepted\n",
               100.0 * st->chain_paths / st->photon_paths, 100.0 * st->chain_visible / fmax(st->chain_large, 1.0),
               100.0 * st->chain_accepted / fmax(st->chain_small, 1.0));
    if (st->photon_paths > 0)
        printf("photon points: %.3g photon paths (%.2f M/s in the photon pass), %.3g photons stored; "
               "time in photon pass %.2f s, map builds %.2f s, sensor pass %.2f s; last radii r_vol %.4g, R_surf %.4g\n",
               st->photon_paths, st->t_photon > 0 ? st->photon_paths / st->t_photon * 1e-6 : 0.0, st->stored_photons,
               st->t_photon, st->t_maps, st->t_gather, st->r_vol, st->r_surf);
    if (st->reductions > 0) {
        double px = (double)s->cam.width * s->cam.height;
        char each[32];
        memory_format_bytes(px * 3 * sizeof(double) + px * 3 * sizeof(float) * tw->frame_count + 12 * sizeof(double), each,
                            sizeof each);
        printf("cluster: %ld film reductions of %s from each rank; rank 0 spent %.3f s in the rounds' agreement and "
               "the reductions (%.2f%% of the render); photon-pass and sensor-pass times above are summed over the ranks\n",
               st->reductions, each, st->t_cluster, st->seconds > 0 ? 100.0 * st->t_cluster / st->seconds : 0.0);
    }
}

/* The memory guard (before any work): the plan's estimate against the limit; exit 2 naming the key that
 * drives it when it does not fit. */
/* What one render command works on: the scene, its plan, and where the images go. */
typedef struct {
    scene s;
    render_plan p;
    char plan_json[8192];
    char out[OUTPUT_PATH_MAX];
    memory_estimate mem;
    double load_seconds;  /* scene_load: JSON, meshes, textures, Embree build */
    int skip;             /* render_write_outputs */
} render_job;

/* The memory guard (before any work): the plan's estimate against the limit; exit 2 naming the key that
 * drives it when it does not fit. */
static int check_memory(render_job *j, const render_args *a, int ranks_on_node)
{
    render_memory_estimate(&j->s, &j->p, a->reference != NULL, &j->mem);
    const memory_estimate *m = &j->mem;
    double limit = a->max_memory > 0 ? a->max_memory : memory_available();
    if (ranks_on_node > 1 && limit > 0) limit /= ranks_on_node; /* every rank on this machine needs as much */
    if (!(limit > 0) || m->total <= limit) return 0;
    const memory_item *big = memory_largest(m);
    char need[32], have[32], item[32];
    memory_format_bytes(m->total, need, sizeof need);
    memory_format_bytes(limit, have, sizeof have);
    fprintf(stderr, "dartspp render: %s: the render needs about %s of memory, more than the %s %s%s", j->s.path, need,
            have, a->max_memory > 0 ? "allowed by --max-memory" : "available",
            ranks_on_node > 1 ? " to each of the ranks on this machine" : "");
    if (big) {
        memory_format_bytes(big->bytes, item, sizeof item);
        fprintf(stderr, "; %s drives it (%s: %s)", big->key, big->what, item);
    }
    fprintf(stderr, "\n");
    return 2;
}

static void print_memory(const memory_estimate *m)
{
    struct rusage ru;
    char est[32], peak[32] = "unknown";
    memory_format_bytes(m->total, est, sizeof est);
    if (getrusage(RUSAGE_SELF, &ru) == 0) memory_format_bytes(ru.ru_maxrss * 1024.0, peak, sizeof peak);
    printf("memory: estimated %s before the render, peak resident %s\n", est, peak);
}

/* Writes the completed passes to the output, or to a rescue folder when that fails: finished work is never
 * thrown away. 0, or 1 when the images had to go elsewhere (or nowhere). */
static int write_outputs(const render_job *j, const film *f)
{
    dp_error err;
    if (!render_write_outputs(f, j->out, j->p.type_name, j->plan_json, j->skip, print_written, &err)) return 0;
    fprintf(stderr, "dartspp render: %s\n", err.msg);
    char rescue[OUTPUT_PATH_MAX];
    if (render_write_rescue(f, j->out, j->p.type_name, j->plan_json, j->skip, print_written, rescue, sizeof rescue, &err))
        fprintf(stderr, "dartspp render: no rescue folder took the images either (%s): they are lost\n", err.msg);
    else
        fprintf(stderr, "dartspp render: the images of the %ld completed passes were written to %s instead\n",
                f->passes, rescue);
    return 1;
}

/* Loads the scene, resolves its plan and checks the outputs and the memory: everything that can refuse the
 * render before any work is spent (exit 2). On success the job holds the scene and the plan. */
static int prepare(const render_args *a, render_job *j, int check_outputs, int ranks_on_node)
{
    dp_error err;
    scene_load_options lo = {.sets = a->sets, .set_count = a->set_count, .verbose = a->verbose};
    double t0 = dp_seconds();
    if (scene_load(a->scene_path, &lo, &j->s, &err)) {
        fprintf(stderr, "dartspp render: %s\n", err.msg);
        return 2;
    }
    j->load_seconds = dp_seconds() - t0;
    int rc = 0;
    if (plan_resolve(&j->s, &j->p, &err) ||
        (plan_json(&j->p, &j->s, j->plan_json, sizeof j->plan_json) && dp_fail(&err, "%s: plan too long", j->s.path))) {
        fprintf(stderr, "dartspp render: %s\n", err.msg);
        rc = 2;
    }
    output_path(a, &j->s, j->out, sizeof j->out);
    j->skip = a->skip;
    if (!rc && check_outputs &&
        render_outputs_check(j->out, j->s.cam.width, j->s.cam.height, j->p.window.frame_count, j->skip, &err)) {
        fprintf(stderr, "dartspp render: %s\n", err.msg);
        rc = 2;
    }
    if (!rc) rc = check_memory(j, a, ranks_on_node);
    if (rc) {
        plan_free(&j->p);
        scene_free(&j->s);
    }
    return rc;
}

int cli_render(int argc, char **argv) { return cli_render_cluster(argc, argv, NULL); }

/* Rank 0's seed, pass count and time budget on every rank: the ranks render one job whatever their own
 * command lines say (the seed as two 32-bit halves, exact in doubles). */
static int share_options(const render_cluster *c, render_args *a)
{
    double v[4] = {(double)(a->ro.seed >> 32), (double)(a->ro.seed & 0xffffffffu), (double)a->ro.spp, a->ro.time_limit};
    if (c->share(c, v, 4)) return -1;
    a->ro.seed = ((uint64_t)v[0] << 32) | (uint64_t)v[1];
    a->ro.spp = (long)v[2];
    a->ro.time_limit = v[3];
    return 0;
}

int cli_render_cluster(int argc, char **argv, const render_cluster *cluster)
{
    const render_cluster *cl = cluster && cluster->size > 1 ? cluster : NULL;
    int rank = cl ? cl->rank : 0;
    render_args a = {0};
    int rc = parse_args(argc, argv, &a);
    if (rank != 0) a.quiet = 1; /* rank 0 speaks for the job */
    /* Interrupts count from here: while loading, an interrupt exits at once (nothing to keep yet). */
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    static render_job j; /* large (the plan's JSON, paths): not on the stack */
    dp_error err;
    after_pass_ctx cp = {0};
    int prepared = !rc && !(rc = prepare(&a, &j, rank == 0, cl ? cl->ranks_on_node : 1));
    if (prepared) {
        cp = (after_pass_ctx){.p = &j.p, .plan_json = j.plan_json, .out = j.out, .quiet = a.quiet, .skip = j.skip,
                              .every = rank != 0 ? 0 : a.checkpoint >= 0 ? a.checkpoint : j.p.checkpoint_seconds};
        /* the error log is rank 0's; its reference is read here, before any rank renders */
        if (rank == 0 && a.log && !(cp.log = error_log_open(a.log, a.reference, j.s.cam.width, j.s.cam.height,
                                                            j.p.window.frame_count, a.log_every, &err))) {
            fprintf(stderr, "dartspp render: %s\n", err.msg);
            rc = 2;
        }
    }
    if (cl) { /* every rank is ready, or none renders */
        int all = cl->agree_rc(cl, rc);
        if (all && !rc && rank == 0) fprintf(stderr, "dartspp render: another rank could not start the render (its message is above)\n");
        rc = all;
        if (!rc && share_options(cl, &a)) rc = 1;
        /* the ranks on one machine share its cores: without --threads each takes its share */
        long cores = sysconf(_SC_NPROCESSORS_ONLN);
        if (!rc && a.ro.threads == 0 && cores > 0) a.ro.threads = cores / cl->ranks_on_node > 0 ? (int)(cores / cl->ranks_on_node) : 1;
    }
    if (rc) {
        if (prepared) {
            error_log_close(cp.log);
            plan_free(&j.p);
            scene_free(&j.s);
        }
        free(a.sets);
        return rc;
    }
    if (rank == 0) {
        if (j.s.notes) fputs(j.s.notes, stderr);
        if (a.verbose) fprintf(stderr, "plan: %s\n", j.plan_json);
        warn_mirrors(&j.s, &j.p);
        warn_mixed_eta(&j.s, &j.p);
        if (cl && !a.quiet)
            fprintf(stderr, "cluster: %d ranks (%d on this machine, %d threads each); iteration i runs on rank i mod %d\n",
                    cl->size, cl->ranks_on_node, a.ro.threads, cl->size);
    }
    a.ro.plan = &j.p;
    a.ro.progress = !a.quiet;
    a.ro.stop = &stop_requested;
    a.ro.passes_started = &passes_started;
    a.ro.after_pass = after_pass;
    a.ro.after_pass_ctx = &cp;
    a.ro.cluster = cl;
    /* with several ranks the films are summed for checkpoints and log rows only when one is due */
    a.ro.gather_every = cp.every > 0 ? cp.every : 0.0;
    if (cp.log && (a.ro.gather_every == 0.0 || a.log_every < a.ro.gather_every))
        a.ro.gather_every = a.log_every > 0 ? a.log_every : 1e-9;
    film f;
    render_stats st;
    int failed = render_scene(&j.s, &a.ro, &f, &st, &err) != 0;
    if (failed && (rank == 0 || strncmp(err.msg, "another rank", 12))) fprintf(stderr, "dartspp render: %s%s\n", err.msg, cl && rank ? " (a rank other than 0)" : "");
    else if (cp.log && error_log_pass(cp.log, &f, &st, 1, &err)) {
        fprintf(stderr, "dartspp render: %s\n", err.msg);
        failed = 1;
    }
    if (!failed && rank == 0) {
        print_summary(&j.s, &j.p, &st, j.load_seconds);
        print_memory(&j.mem);
        if (cp.log)
            printf("error log: %s (%.3f s spent logging, %.2f%% of the render)\n", a.log, error_log_overhead(cp.log),
                   st.seconds > 0 ? 100.0 * error_log_overhead(cp.log) / st.seconds : 0.0);
    }
    if (rank != 0) {
        /* nothing to write here: rank 0 holds the summed film */
    } else if (f.passes > 0) failed |= write_outputs(&j, &f);
    else if (st.interrupted) fprintf(stderr, "dartspp render: interrupted before the first pass completed: nothing written\n");
    rc = failed ? 1 : st.interrupted ? EXIT_INTERRUPTED : 0;
    error_log_close(cp.log);
    film_free(&f);
    plan_free(&j.p);
    scene_free(&j.s);
    free(a.sets);
    return rc;
}
