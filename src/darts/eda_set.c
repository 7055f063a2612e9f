/* The EDA tables a render needs, one per medium that uses EDA, loaded or built once per render. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/darts.h"

/* The medium's table: the authors' headerless file (relative to the scene's folder), or our cache. The
 * table is scalar: σs and σa are averaged over the colour channels (it only steers directions, the
 * weights stay exact). S range: max_T, else the latest residual any vertex in the medium can have. */
static int load_for_medium(const scene *s, const darts_plan *d, const time_window *w, const medium *m, eda_table *t, FILE *messages,
                           dp_error *err)
{
    if (m->eda_table_path[0]) {
        char path[2048];
        if (m->eda_table_path[0] == '/') snprintf(path, sizeof path, "%s", m->eda_table_path);
        else snprintf(path, sizeof path, "%s/%s", s->dir, m->eda_table_path);
        return eda_table_load_raw(t, path, m->eda_s_max, m->eda_r_lo, m->eda_r_hi, err);
    }
    double s_max = m->eda_s_max > 0.0 ? m->eda_s_max : time_window_end(w) / m->eta;
    double g = m->phase.type == PHASE_ISOTROPIC ? 0.0 : m->phase.g;
    if (!(v3_avg(m->sigma_s) > 0.0))
        return dp_fail(err, "%s: medium '%s': EDA needs sigma_s > 0 (the diffusion approximation is undefined "
                            "without scattering)", s->path, m->name);
    if (!(s_max > 0.0))
        return dp_fail(err, "%s: medium '%s': EDA needs a gate that ends after time 0", s->path, m->name);
    return eda_table_cached(t, d->eda_table_dir, v3_avg(m->sigma_s), v3_avg(m->sigma_a), g, d->eda_shape[0],
                            d->eda_shape[1], d->eda_shape[2], s_max, m->eda_r_lo, m->eda_r_hi, messages, err);
}

int eda_set_prepare(const scene *s, const darts_plan *d, const time_window *w, eda_set *set, FILE *messages, dp_error *err)
{
    memset(set, 0, sizeof *set);
    int n = s->medium_count;
    if (n == 0) return 0;
    set->tables = calloc((size_t)n, sizeof(eda_table));
    set->table = calloc((size_t)n, sizeof(eda_table *));
    set->alpha = calloc((size_t)n, sizeof(double));
    set->count = n;
    if (!set->tables || !set->table || !set->alpha) {
        eda_set_free(set);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the EDA tables", s->path);
    }
    for (int i = 0; i < n; i++) {
        const medium *m = &s->media[i];
        if (!d->eda[i].on) continue;
        if (load_for_medium(s, d, w, m, &set->tables[i], messages, err)) {
            eda_set_free(set);
            return -1;
        }
        set->table[i] = &set->tables[i];
        set->alpha[i] = d->eda[i].alpha;
        set->active = 1;
    }
    return 0;
}

size_t eda_set_bytes(const scene *s, const darts_plan *d)
{
    size_t bytes = 0;
    const int *shape = d->eda_shape;
    for (int i = 0; i < s->medium_count; i++) {
        const medium *m = &s->media[i];
        if (!d->eda[i].on) continue;
        size_t cells = m->eda_table_path[0] ? (size_t)128 * 128 * 256 : (size_t)shape[0] * shape[1] * shape[2];
        bytes += cells * sizeof(float);
    }
    return bytes;
}

void eda_set_free(eda_set *set)
{
    for (int i = 0; set->tables && i < set->count; i++) eda_table_free(&set->tables[i]);
    free(set->tables);
    free(set->table);
    free(set->alpha);
    memset(set, 0, sizeof *set);
}
