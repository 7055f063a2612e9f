/* The table of emitter types, light selection and set-up (include/dartspp/emitter.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emitter_internal.h"

/* The table: one row per emitter type, X(t) naming the emitter_ops emitter_<t>_ops that src/emitter/<t>.c
 * defines. Its order is the order in which messages list the primitive types. */
#define EMITTER_TYPES(X) \
    X(point)             \
    X(spot)              \
    X(collimated)        \
    X(area)

#define DECLARE_OPS(t) extern const emitter_ops emitter_##t##_ops;
EMITTER_TYPES(DECLARE_OPS)
#define ROW(t) &emitter_##t##_ops,
static const emitter_ops *const emitter_table[] = {EMITTER_TYPES(ROW)};
#define EMITTER_TYPE_COUNT ((int)(sizeof emitter_table / sizeof emitter_table[0]))

const emitter_ops *emitter_ops_find(const char *type)
{
    for (int i = 0; i < EMITTER_TYPE_COUNT; i++)
        for (const char *const *p = emitter_table[i]->primitives; p && *p; p++)
            if (!strcmp(*p, type)) return emitter_table[i];
    return NULL;
}

const emitter_ops *emitter_ops_shape(void)
{
    for (int i = 0; i < EMITTER_TYPE_COUNT; i++)
        if (!emitter_table[i]->primitives) return emitter_table[i];
    return NULL;
}

void emitter_primitive_list(char *buf, size_t size, const char *last)
{
    const char *names[32];
    int n = 0;
    for (int i = 0; i < EMITTER_TYPE_COUNT; i++)
        for (const char *const *p = emitter_table[i]->primitives; p && *p && n < 32; p++) names[n++] = *p;
    size_t len = 0;
    buf[0] = '\0';
    for (int k = 0; k < n && len < size; k++) {
        const char *sep = k == 0 ? "" : k == n - 1 ? last : ", ";
        int w = snprintf(buf + len, size - len, "%s%s", sep, names[k]);
        if (w < 0) break;
        len += (size_t)w;
    }
}

int emitter_beam_frame(emitter *e, const emitter_keys *k)
{
    if (!(v3_len(k->z) > 0.0)) return k->fail(k, "transform", "gives no direction (set look_at away from position)");
    e->axis = v3_norm(k->z);
    vec3 up = v3_len(k->y) > 0.0 ? k->y : v3(0, 1, 0);
    vec3 e1 = v3_cross(up, e->axis);
    if (!(v3_len(e1) > 1e-12)) {
        vec3 a, b;
        v3_basis(e->axis, &a, &b);
        e1 = a;
    }
    e->e1 = v3_norm(e1);
    e->e2 = v3_norm(v3_cross(e->axis, e->e1));
    return 0;
}

void emitter_point_at_pos(const scene *s, const emitter *e, const double u[2], emitter_point *pt)
{
    (void)s, (void)u;
    *pt = (emitter_point){.y = e->pos, .pdf_a = 1.0};
}

static double selection_weight(const emitter *e, int by_power)
{
    return by_power ? dp_fmax(0.0, v3_avg(e->flux)) : 1.0;
}

double emitter_selection_pdf(const scene *s, int i, int by_power)
{
    double sum = 0.0;
    for (int k = 0; k < s->light_count; k++) sum += selection_weight(&s->lights[k], by_power);
    return sum > 0.0 ? selection_weight(&s->lights[i], by_power) / sum : 1.0 / s->light_count;
}

int emitter_select(const scene *s, double u, int by_power, double *pdf)
{
    int n = s->light_count;
    if (n <= 0) return -1;
    if (n == 1) {
        *pdf = 1.0;
        return 0;
    }
    double sum = 0.0;
    for (int k = 0; k < n; k++) sum += selection_weight(&s->lights[k], by_power);
    if (!(sum > 0.0)) { /* every light black: uniform, as the paths carry nothing anyway */
        int i = (int)(u * n);
        *pdf = 1.0 / n;
        return i < n ? i : n - 1;
    }
    double target = u * sum, acc = 0.0;
    int i = 0;
    for (; i < n - 1; i++) {
        acc += selection_weight(&s->lights[i], by_power);
        if (target < acc) break;
    }
    while (i > 0 && !(selection_weight(&s->lights[i], by_power) > 0.0)) i--; /* rounding past the last lit one */
    *pdf = selection_weight(&s->lights[i], by_power) / sum;
    return i;
}

int emitter_prepare(const scene *s, emitter *e)
{
    e->extent = 0.0;
    e->flags = 0;
    return e->ops->prepare(s, e);
}

void emitter_free(emitter *e)
{
    free(e->tri_cdf);
    e->tri_cdf = NULL;
}
