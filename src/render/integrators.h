/* Inside the render module: the table of integrators. Each row says, for one integrator type, everything the
 * driver, the memory guard, the run summary and the warnings do differently for it; nothing else in the
 * render module tests an integrator's type. A new integrator is one module of its own (its public header with
 * its pass) and one row of integrators.c. */
#ifndef DARTSPP_RENDER_INTEGRATORS_H
#define DARTSPP_RENDER_INTEGRATORS_H

#include <stdio.h>

#include "dartspp/darts.h"
#include "dartspp/render.h"

typedef struct {
    integrator_type type;
    /* One pass (iteration `pass`) into f's pass layer; its figures added to *st. 0, or -1 with err. Once stop
     * is set it returns early and the driver drops the pass. */
    int (*pass)(const scene *s, const render_plan *p, const eda_set *eda, film *f, uint64_t seed, long pass,
                const dp_stop_flag *stop, render_stats *st, dp_error *err);
    /* Its figures after `passes` passes that are not sums over passes (the radii of the last pass), set after
     * the ranks' figures were summed (render.c); NULL: none. */
    void (*last_pass_figures)(const render_plan *p, long passes, render_stats *st);
    /* The memory it needs beyond the scene and the film (its module); NULL: none. */
    void (*memory)(const scene *s, const render_plan *p, memory_estimate *m);
    /* Its line of the run summary: the method and the samplers that run (summary.c). */
    void (*print_method)(const scene *s, const render_plan *p);
    /* How it reaches light e (docs/emitters.md §7), for the summary's list of lights (summary.c). */
    const char *(*light_technique)(const emitter *e, const render_plan *p);
    /* Before the first pass, choices its passes need that cost work (surface_paths "auto": a pilot); it may
     * set fields of *p that plan_resolve leaves at their defaults. NULL: none. */
    int (*prepare)(const scene *s, render_plan *p, const eda_set *eda, uint64_t seed, const dp_stop_flag *stop,
                   FILE *messages, render_stats *st, dp_error *err);
    /* The warnings only it needs (warnings.c); NULL: none. */
    void (*warn)(FILE *out, const scene *s, const render_plan *p);
} integrator_entry;

/* The row of type t (every integrator_type has one). */
const integrator_entry *integrator_entry_of(integrator_type t);

/* The rows' functions, in the files named. */
void summary_print_photon_pass(const scene *s, const render_plan *p);                     /* summary.c */
void summary_print_path_method(const scene *s, const render_plan *p);                     /* summary.c */
const char *summary_photon_points_light(const emitter *e, const render_plan *p);          /* summary.c */
const char *summary_path_tracer_light(const emitter *e, const render_plan *p);            /* summary.c */
void warn_path_tracer(FILE *out, const scene *s, const render_plan *p);                   /* warnings.c */
void warn_photon_points(FILE *out, const scene *s, const render_plan *p);                 /* warnings.c */

#endif
