/* Translations of a primitive, a light or the camera (include/dartspp/derivative.h; docs/derivatives.md §6):
 * the ray-space sliding of the camera path's vertices, the silhouette edges of the scene as seen from each
 * point light (the shadow boundaries that path_geometry_deriv.c and boundary_shadow.c estimate), and the
 * refusals of what the boundary terms do not cover. */
#include <stdlib.h>
#include <string.h>

#include "dartspp/bsdf.h"
#include "dartspp/derivative.h"
#include "dartspp/emitter.h"

int deriv_has_geometry(const deriv_plan *d)
{
    for (int k = 0; d && k < d->count; k++)
        if (d->param[k].kind == DIFF_TRANSLATE) return 1;
    return 0;
}

vec3 deriv_surface_velocity(const diff_param *q, int surface)
{
    int moves = q->kind == DIFF_TRANSLATE && q->target == DIFF_TARGET_SURFACES && surface >= q->first_surface &&
                surface < q->first_surface + q->surface_count;
    return moves ? q->axis : v3s(0.0);
}

vec3 deriv_light_velocity(const diff_param *q, int light)
{
    return q->kind == DIFF_TRANSLATE && q->light == light && light >= 0 ? q->axis : v3s(0.0);
}

vec3 deriv_camera_velocity(const diff_param *q)
{
    return q->kind == DIFF_TRANSLATE && q->target == DIFF_TARGET_CAMERA ? q->axis : v3s(0.0);
}

void deriv_camera_start(const deriv_plan *d, deriv_path *p)
{
    for (int k = 0; k < d->count; k++) p->dx[k] = deriv_camera_velocity(&d->param[k]);
}

void deriv_hit_distance(const deriv_plan *d, const deriv_path *p, vec3 dir, vec3 n, int surface, double dD[DIFF_PARAM_MAX])
{
    double nd = v3_dot(n, dir);
    for (int k = 0; k < d->count; k++) {
        dD[k] = 0.0;
        if (d->param[k].kind != DIFF_TRANSLATE || surface < 0 || nd == 0.0) continue;
        /* the hit x = o + D·dir stays on the plane n·(x − p(θ)) = 0 that moves with its surface */
        dD[k] = v3_dot(n, v3_sub(deriv_surface_velocity(&d->param[k], surface), p->dx[k])) / nd;
    }
}

void deriv_slide(const deriv_plan *d, deriv_path *p, vec3 dir, double t, double D, const double dD[DIFF_PARAM_MAX],
                 vec3 sigma_t, double eta, int timed, int surface)
{
    if (!(D < INFINITY)) return; /* no surface ahead: the vertex keeps its distance and moves with its origin */
    double s = t / D;
    for (int k = 0; k < d->count; k++) {
        if (d->param[k].kind != DIFF_TRANSLATE || dD[k] == 0.0) continue;
        double dt = s * dD[k]; /* ∂t/∂θ of the vertex at the fixed fraction s */
        p->dx[k] = v3_add(p->dx[k], v3_scale(dir, dt));
        vec3 dl = v3_scale(sigma_t, -dt); /* ∂ ln e^{−σt·t} */
        if (!surface) dl = v3_add(dl, v3s(dD[k] / D)); /* the Jacobian dt = D·ds of the fraction */
        p->dlog[k] = v3_add(p->dlog[k], dl);
        if (timed) p->dtof[k] += eta * dt;
    }
}

/* ---- edges ---- */

typedef struct {
    uint32_t lo, hi, tri, corner; /* position ids of the ends; the triangle; its corner the edge starts at */
} edge_rec;

static int edge_cmp(const void *a, const void *b)
{
    const edge_rec *x = a, *y = b;
    if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi) return x->hi < y->hi ? -1 : 1;
    return (x->tri > y->tri) - (x->tri < y->tri);
}

static vec3 vertex(const scene *s, uint32_t i)
{
    return v3(s->verts[3 * (size_t)i], s->verts[3 * (size_t)i + 1], s->verts[3 * (size_t)i + 2]);
}

/* (p1 − p0) × (p2 − p0) of triangle t */
static vec3 tri_normal(const scene *s, uint32_t t)
{
    const uint32_t *v = &s->tris[3 * (size_t)t];
    vec3 p0 = vertex(s, v[0]);
    return v3_cross(v3_sub(vertex(s, v[1]), p0), v3_sub(vertex(s, v[2]), p0));
}

typedef struct {
    float p[3];
    uint32_t corner;
} corner_rec;

static int corner_cmp(const void *a, const void *b)
{
    const corner_rec *x = a, *y = b;
    for (int j = 0; j < 3; j++)
        if (x->p[j] != y->p[j]) return x->p[j] < y->p[j] ? -1 : 1;
    return (x->corner > y->corner) - (x->corner < y->corner);
}

/* Per corner of surface i's triangles, the id of its position (meshes that split vertices per face, as the
 * cube does, share edges by position); NULL when out of memory. */
static uint32_t *corner_ids(const scene *s, const surface *sf)
{
    size_t n = 3 * (size_t)sf->tri_count;
    corner_rec *c = malloc((n ? n : 1) * sizeof *c);
    uint32_t *id = malloc((n ? n : 1) * sizeof *id);
    if (!c || !id) {
        free(c), free(id);
        return NULL;
    }
    for (size_t j = 0; j < n; j++) {
        uint32_t v = s->tris[3 * (size_t)sf->first_tri + j];
        c[j] = (corner_rec){{s->verts[3 * (size_t)v], s->verts[3 * (size_t)v + 1], s->verts[3 * (size_t)v + 2]}, (uint32_t)j};
    }
    qsort(c, n, sizeof *c, corner_cmp);
    uint32_t g = 0;
    for (size_t j = 0; j < n; j++) {
        if (j > 0 && memcmp(c[j].p, c[j - 1].p, sizeof c[j].p)) g++;
        id[c[j].corner] = g;
    }
    free(c);
    return id;
}

/* The edges of surface i (by position ids), sorted so that the triangles sharing one are adjacent; NULL when
 * out of memory. */
static edge_rec *surface_edges(const scene *s, int i, size_t *n)
{
    const surface *sf = &s->surfaces[i];
    *n = 3 * (size_t)sf->tri_count;
    edge_rec *e = malloc((*n ? *n : 1) * sizeof *e);
    uint32_t *id = corner_ids(s, sf);
    if (!e || !id) {
        free(e), free(id);
        return NULL;
    }
    for (uint32_t t = 0; t < sf->tri_count; t++)
        for (int j = 0; j < 3; j++) {
            uint32_t a = id[3 * (size_t)t + j], b = id[3 * (size_t)t + (j + 1) % 3];
            e[3 * (size_t)t + j] = (edge_rec){a < b ? a : b, a < b ? b : a, sf->first_tri + t, 3 * t + (uint32_t)j};
        }
    free(id);
    qsort(e, *n, sizeof *e, edge_cmp);
    return e;
}

/* The ends of edge record r: the corners j and j + 1 of its triangle. */
static void edge_ends(const scene *s, const edge_rec *r, vec3 *a, vec3 *b)
{
    const uint32_t *v = &s->tris[3 * (size_t)r->tri];
    int j = (int)(r->corner % 3);
    *a = vertex(s, v[j]);
    *b = vertex(s, v[(j + 1) % 3]);
}

/* Whether every edge of surface i is shared by exactly two triangles (a closed mesh): -1 out of memory. */
static int surface_closed(const scene *s, int i)
{
    size_t n, j = 0;
    edge_rec *e = surface_edges(s, i, &n);
    if (!e) return -1;
    int closed = 1;
    while (j < n && closed) {
        size_t k = j;
        while (k < n && e[k].lo == e[j].lo && e[k].hi == e[j].hi) k++;
        closed = k - j == 2;
        j = k;
    }
    free(e);
    return closed;
}

typedef struct {
    deriv_edge *e;
    int n, cap;
} edge_list;

static int edge_push(edge_list *l, deriv_edge e)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 64;
        deriv_edge *m = realloc(l->e, (size_t)cap * sizeof *m);
        if (!m) return -1;
        l->e = m, l->cap = cap;
    }
    l->e[l->n++] = e;
    return 0;
}

/* The silhouette edges of surface i as seen from y: an open edge, or one between a triangle facing y and one
 * facing away (a non-manifold edge counts as open). Appends them to l; -1 out of memory. */
static int surface_silhouettes(const scene *s, int i, vec3 y, edge_list *l)
{
    size_t n, j = 0;
    edge_rec *e = surface_edges(s, i, &n);
    if (!e) return -1;
    int rc = 0;
    while (j < n && !rc) {
        size_t k = j;
        while (k < n && e[k].lo == e[j].lo && e[k].hi == e[j].hi) k++;
        vec3 a, b;
        edge_ends(s, &e[j], &a, &b);
        int sil = k - j != 2;
        if (!sil) sil = (v3_dot(tri_normal(s, e[j].tri), v3_sub(y, a)) > 0.0) !=
                        (v3_dot(tri_normal(s, e[j + 1].tri), v3_sub(y, a)) > 0.0);
        if (sil) rc = edge_push(l, (deriv_edge){a, b, i});
        j = k;
    }
    free(e);
    return rc;
}

/* ---- refusals ---- */

static int is_opaque(const scene *s, int i)
{
    return !bsdf_is_passthrough(&s->bsdfs[s->surfaces[i].bsdf]);
}

static int gfail(const scene *s, const diff_param *q, dp_error *err, const char *why)
{
    return dp_fail(err, "%s: --derivative %s: %s", s->path, q->pointer, why);
}

/* Whether a point of segment [a, b] projects into the pinhole camera's image (a pixel's margin around it). */
static int edge_in_view(const camera *c, vec3 a, vec3 b)
{
    for (int j = 0; j <= 64; j++) {
        vec3 p = v3_sub(v3_add(a, v3_scale(v3_sub(b, a), j / 64.0)), c->pos);
        double z = v3_dot(p, c->forward);
        if (!(z > 0.0)) continue;
        double x = v3_dot(p, c->right) * c->plane_dist / z, y = v3_dot(p, c->up) * c->plane_dist / z;
        double sx = 2.0 / c->width, px = (x + 1.0) / sx, py = ((double)c->height / c->width - y) / sx;
        if (px > -1.0 && px < c->width + 1.0 && py > -1.0 && py < c->height + 1.0) return 1;
    }
    return 0;
}

/* The primary visibility's boundary: the silhouettes, as seen from the camera, of the opaque surfaces that
 * move relative to it (all of them when the camera moves) must be out of view. */
static int check_primary(const scene *s, const diff_param *q, dp_error *err)
{
    int cam = q->target == DIFF_TARGET_CAMERA;
    for (int i = 0; i < s->surface_count; i++) {
        if (!is_opaque(s, i) || (!cam && v3_is_zero(deriv_surface_velocity(q, i)))) continue;
        edge_list l = {0};
        if (surface_silhouettes(s, i, s->cam.pos, &l)) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for the silhouettes");
        int seen = 0;
        for (int j = 0; j < l.n && !seen; j++) seen = edge_in_view(&s->cam, l.e[j].a, l.e[j].b);
        free(l.e);
        if (seen) {
            char why[512];
            snprintf(why, sizeof why, "the silhouette of surface '%s' is in the camera's view and moves relative to it: "
                                      "the primary visibility's boundary term is not implemented (docs/derivatives.md §6.4)",
                     s->surfaces[i].name);
            return gfail(s, q, err, why);
        }
    }
    return 0;
}

static int check_scene(const scene *s, const diff_param *q, dp_error *err)
{
    char why[512];
    if (s->integrator.type != INTEGRATOR_PATH_TRACER)
        return gfail(s, q, err, "translations are differentiated by the path tracers only (docs/derivatives.md §6.4)");
    if (s->cam.type != CAMERA_PINHOLE) return gfail(s, q, err, "translations need a pinhole camera (docs/derivatives.md §6.4)");
    for (int i = 0; i < s->light_count; i++)
        if (strcmp(s->lights[i].type_name, "point")) {
            snprintf(why, sizeof why, "light %d is a '%s' light: translations are differentiated with point lights only "
                                      "(the edges of beams, cones and area lights are boundaries not estimated; "
                                      "docs/derivatives.md §6.4)", i, s->lights[i].type_name);
            return gfail(s, q, err, why);
        }
    int opaque = 0;
    for (int i = 0; i < s->surface_count; i++) {
        const bsdf *b = &s->bsdfs[s->surfaces[i].bsdf];
        if (is_opaque(s, i)) {
            opaque = 1;
            if (s->surfaces[i].smooth) {
                snprintf(why, sizeof why, "surface '%s' is smooth (interpolated vertex normals, as spheres are): the "
                                          "shading normal's change as a hit slides over it is not differentiated; use a "
                                          "flat mesh (docs/derivatives.md §6.4)", s->surfaces[i].name);
                return gfail(s, q, err, why);
            }
            if (b->texture >= 0) {
                snprintf(why, sizeof why, "surface '%s' has a textured albedo: its derivative as a hit slides over it is "
                                          "not implemented", s->surfaces[i].name);
                return gfail(s, q, err, why);
            }
            continue;
        }
        if (!v3_is_zero(deriv_surface_velocity(q, i)))
            return gfail(s, q, err, "a null or forward surface moves the media it bounds: not implemented");
        int closed = surface_closed(s, i);
        if (closed < 0) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for the edges");
        if (!closed) {
            snprintf(why, sizeof why, "null or forward surface '%s' is not a closed mesh: the media it separates "
                                      "change across its open edges, a boundary not estimated", s->surfaces[i].name);
            return gfail(s, q, err, why);
        }
    }
    if (opaque && s->integrator.max_bounces > 2)
        return gfail(s, q, err, "with opaque surfaces translations need max_bounces <= 2 (direct light): the boundary terms "
                                "of the shadows that longer paths see on surfaces, and of their visibility, are not "
                                "estimated (docs/derivatives.md §6.4)");
    return check_primary(s, q, err);
}

/* The silhouette edges of the opaque surfaces as seen from point light i, with their CDF by length. */
static int light_edges(deriv_geometry *g, const scene *s, int i)
{
    edge_list l = {0};
    for (int j = 0; j < s->surface_count; j++)
        if (is_opaque(s, j) && surface_silhouettes(s, j, s->lights[i].pos, &l)) {
            free(l.e);
            return -1;
        }
    g->edge[i] = l.e;
    g->edge_count[i] = l.n;
    g->edge_cdf[i] = malloc((size_t)(l.n ? l.n : 1) * sizeof(double));
    if (!g->edge_cdf[i]) return -1;
    double acc = 0.0;
    for (int j = 0; j < l.n; j++) g->edge_cdf[i][j] = acc += v3_len(v3_sub(l.e[j].b, l.e[j].a));
    for (int j = 0; j < l.n; j++) g->edge_cdf[i][j] /= acc;
    if (l.n) g->edge_cdf[i][l.n - 1] = 1.0;
    g->edge_total[i] = acc;
    return 0;
}

int deriv_geometry_init(deriv_plan *d, const scene *s, dp_error *err)
{
    if (!deriv_has_geometry(d)) return 0;
    for (int k = 0; k < d->count; k++)
        if (d->param[k].kind == DIFF_TRANSLATE && check_scene(s, &d->param[k], err)) return -1;
    deriv_geometry *g = calloc(1, sizeof *g);
    int n = s->light_count;
    if (g) {
        d->geom = g;
        g->light_count = n;
        g->eps = 1e-4 * s->ray_offset_scale;
        g->boundary = getenv("DARTSPP_DERIV_NO_BOUNDARY") == NULL;
        g->edge = calloc((size_t)(n ? n : 1), sizeof *g->edge);
        g->edge_count = calloc((size_t)(n ? n : 1), sizeof *g->edge_count);
        g->edge_cdf = calloc((size_t)(n ? n : 1), sizeof *g->edge_cdf);
        g->edge_total = calloc((size_t)(n ? n : 1), sizeof *g->edge_total);
    }
    int ok = g && g->edge && g->edge_count && g->edge_cdf && g->edge_total;
    for (int i = 0; ok && i < n; i++) ok = !light_edges(g, s, i);
    if (!ok) {
        deriv_geometry_free(d);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for the silhouette edges");
    }
    return 0;
}

void deriv_geometry_free(deriv_plan *d)
{
    deriv_geometry *g = d->geom;
    if (!g) return;
    for (int i = 0; i < g->light_count; i++) {
        if (g->edge) free(g->edge[i]);
        if (g->edge_cdf) free(g->edge_cdf[i]);
    }
    free(g->edge), free(g->edge_count), free(g->edge_cdf), free(g->edge_total);
    free(g);
    d->geom = NULL;
}
