/* The figures of a render (RENDER_FIGURES in integrator.h) as a table, and the ways they combine: a pass's figures
 * into the run's, and the packing of those that the MPI reduction sums (or maxes) over the ranks. */
#include <stddef.h>

#include "dartspp/integrator.h"

#define FIGURE_TYPE(field) \
    _Generic(((render_stats *)0)->field, long: RENDER_FIGURE_LONG, int: RENDER_FIGURE_INT, default: RENDER_FIGURE_DOUBLE)
#define FIGURE_ENTRY(type, name, how, api, what) \
    {#name, offsetof(render_stats, name), FIGURE_TYPE(name), how, api, what},

const render_figure render_figures[RENDER_FIGURE_COUNT] = {RENDER_FIGURES(FIGURE_ENTRY)};

double render_figure_get(const render_stats *st, const render_figure *fg)
{
    const char *at = (const char *)st + fg->offset;
    switch (fg->type) {
    case RENDER_FIGURE_LONG: return (double)*(const long *)at;
    case RENDER_FIGURE_INT: return (double)*(const int *)at;
    default: return *(const double *)at;
    }
}

void render_figure_set(render_stats *st, const render_figure *fg, double v)
{
    char *at = (char *)st + fg->offset;
    switch (fg->type) {
    case RENDER_FIGURE_LONG: *(long *)at = (long)v; break;
    case RENDER_FIGURE_INT: *(int *)at = (int)v; break;
    default: *(double *)at = v;
    }
}

/* One figure of a pass into the run's value, as the figure combines. */
static double combine(render_combine how, double run, double pass)
{
    switch (how) {
    case RENDER_SUM: return run + pass;
    case RENDER_LAST: return pass;
    case RENDER_MAX: return pass > run ? pass : run;
    default: return run;
    }
}

void render_stats_add(render_stats *st, const render_stats *pass)
{
    for (int i = 0; i < RENDER_FIGURE_COUNT; i++) {
        const render_figure *fg = &render_figures[i];
        if (fg->how == RENDER_KEPT) continue;
        render_figure_set(st, fg, combine(fg->how, render_figure_get(st, fg), render_figure_get(pass, fg)));
    }
}

int render_stats_pack(const render_stats *st, render_combine how, double *v)
{
    int n = 0;
    for (int i = 0; i < RENDER_FIGURE_COUNT; i++)
        if (render_figures[i].how == how) v[n++] = render_figure_get(st, &render_figures[i]);
    return n;
}

void render_stats_unpack(render_stats *st, render_combine how, const double *v)
{
    int n = 0;
    for (int i = 0; i < RENDER_FIGURE_COUNT; i++)
        if (render_figures[i].how == how) render_figure_set(st, &render_figures[i], v[n++]);
}
