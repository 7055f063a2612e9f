/* The emitter module's helpers shared by the types' files (one file per emitter type, each defining its row
 * of the table in emitter.c). */
#ifndef DARTSPP_EMITTER_INTERNAL_H
#define DARTSPP_EMITTER_INTERNAL_H

#include "dartspp/emitter.h"
#include "dartspp/scene.h"

/* The geometry of a connection from x to the emitter point y: out->y, the unit direction out->wi from x
 * toward y, the length out->dist and out->denom = |x − y|² (the callers' 1/d², kept as one division);
 * 0 when x is y. */
static inline int emitter_leg(vec3 y, vec3 x, emitter_direct *out)
{
    vec3 to = v3_sub(y, x);
    double d2 = v3_dot(to, to);
    if (!(d2 > 0.0)) return 0;
    out->y = y;
    out->dist = sqrt(d2);
    out->wi = v3_scale(to, 1.0 / out->dist);
    out->denom = d2;
    return 1;
}

/* A beam's axis (the transform's local +z: toward look_at) and the unit axes across it, e1 = up × axis,
 * e2 = axis × e1 (spot, collimated); -1 with the loader's message when the transform gives no direction. */
int emitter_beam_frame(emitter *e, const emitter_keys *k);

/* The position itself as the emitter's point (point, spot: pdf_a 1). */
void emitter_point_at_pos(const scene *s, const emitter *e, const double u[2], emitter_point *pt);

#endif
