/* Wavefront `.obj`: `v` positions, `vt` texture coordinates, `vn` normals and `f` polygons (fan-triangulated;
 * v, v/vt, v//vn, v/vt/vn; negative indices relative to the end). As in Tungsten's ObjLoader, each distinct
 * (position, uv, normal) triple of the faces becomes one vertex. Everything else (groups, materials) is
 * ignored. */
#include "scene_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    float *v;            /* n floats per entry */
    uint32_t count, cap;
} float_list;

/* the file's v / vt / vn lists and the triple -> vertex map */
typedef struct {
    float_list pos, uv, nrm;
    uint32_t *keys;      /* 3 per slot: (pos, uv, nrm) 1-based, 0 = absent; slot empty when keys[0] == 0 */
    uint32_t *vert;      /* vertex of each slot */
    uint32_t slots, used;
} obj_state;

static int list_push(float_list *l, const double *x, int n)
{
    if (l->count == l->cap) {
        uint32_t c = l->cap ? l->cap * 2 : 256;
        if (c > (1u << 28)) return -1;
        float *g = realloc(l->v, (size_t)c * (size_t)n * sizeof(float));
        if (!g) return -1;
        l->v = g;
        l->cap = c;
    }
    for (int i = 0; i < n; i++) l->v[(size_t)l->count * (size_t)n + (size_t)i] = (float)x[i];
    l->count++;
    return 0;
}

static uint32_t hash3(const uint32_t k[3])
{
    uint64_t h = k[0] * 0x9E3779B97F4A7C15ULL ^ (k[1] + 0x632BE59BD9B4E019ULL) * 0xC2B2AE3D27D4EB4FULL ^ k[2] * 0x165667B19E3779F9ULL;
    return (uint32_t)(h ^ (h >> 29));
}

static int map_grow(obj_state *o)
{
    uint32_t n = o->slots ? o->slots * 2 : 1024;
    if (n > (1u << 30)) return -1;
    uint32_t *keys = calloc((size_t)n * 3, sizeof(uint32_t)), *vert = malloc((size_t)n * sizeof(uint32_t));
    if (!keys || !vert) {
        free(keys);
        free(vert);
        return -1;
    }
    for (uint32_t i = 0; i < o->slots; i++) {
        if (!o->keys[3 * (size_t)i]) continue;
        uint32_t j = hash3(&o->keys[3 * (size_t)i]) & (n - 1);
        while (keys[3 * (size_t)j]) j = (j + 1) & (n - 1);
        memcpy(&keys[3 * (size_t)j], &o->keys[3 * (size_t)i], 3 * sizeof(uint32_t));
        vert[j] = o->vert[i];
    }
    free(o->keys);
    free(o->vert);
    o->keys = keys;
    o->vert = vert;
    o->slots = n;
    return 0;
}

/* The mesh vertex of a (pos, uv, nrm) triple (1-based, 0 = absent), created on first use. */
static int fetch_vertex(obj_state *o, tri_mesh *m, const uint32_t k[3], uint32_t *out)
{
    if ((uint64_t)(o->used + 1) * 2 > o->slots && map_grow(o)) return -1;
    uint32_t j = hash3(k) & (o->slots - 1);
    for (; o->keys[3 * (size_t)j]; j = (j + 1) & (o->slots - 1))
        if (!memcmp(&o->keys[3 * (size_t)j], k, 3 * sizeof(uint32_t))) {
            *out = o->vert[j];
            return 0;
        }
    const float *p = &o->pos.v[3 * (size_t)(k[0] - 1)];
    if (tri_mesh_add_vertex(m, p[0], p[1], p[2])) return -1;
    uint32_t v = m->nv - 1;
    if (k[1]) memcpy(&m->uv[2 * (size_t)v], &o->uv.v[2 * (size_t)(k[1] - 1)], 2 * sizeof(float));
    if (k[2]) memcpy(&m->nrm[3 * (size_t)v], &o->nrm.v[3 * (size_t)(k[2] - 1)], 3 * sizeof(float));
    m->has_uvs |= k[1] != 0;
    m->has_normals |= k[2] != 0;
    memcpy(&o->keys[3 * (size_t)j], k, 3 * sizeof(uint32_t));
    o->vert[j] = v;
    o->used++;
    *out = v;
    return 0;
}

/* One index of a face corner: 1-based into a list of n entries (negative: from the end); 0 when empty. */
static int parse_index(const char *tok, const char **rest, uint32_t n, uint32_t *out)
{
    char *end;
    long i = strtol(tok, &end, 10);
    *rest = end;
    if (end == tok || i == 0) return -1;
    long k = i > 0 ? i : (long)n + i + 1;
    if (k < 1 || k > (long)n) return -1;
    *out = (uint32_t)k;
    return 0;
}

/* "v", "v/vt", "v//vn" or "v/vt/vn" into 1-based (pos, uv, nrm), 0 for an absent part */
static int parse_corner(const char *tok, const obj_state *o, uint32_t k[3])
{
    const char *s = tok;
    k[0] = k[1] = k[2] = 0;
    if (parse_index(s, &s, o->pos.count, &k[0])) return -1;
    if (*s == 0) return 0;
    if (*s++ != '/') return -1;
    if (*s != '/' && parse_index(s, &s, o->uv.count, &k[1])) return -1;
    if (*s == 0) return 0;
    if (*s++ != '/') return -1;
    return parse_index(s, &s, o->nrm.count, &k[2]) || *s ? -1 : 0;
}

static int parse_face(char *line, obj_state *o, tri_mesh *m, const char *path, long lineno, dp_error *err)
{
    uint32_t first = 0, prev = 0;
    int n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(line, " \t\r\n", &save); tok; tok = strtok_r(NULL, " \t\r\n", &save), n++) {
        uint32_t k[3], v;
        if (parse_corner(tok, o, k)) return dp_fail(err, "%s:%ld: bad face index '%s'", path, lineno, tok);
        if (fetch_vertex(o, m, k, &v)) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
        if (n == 0) first = v;
        else if (n >= 2 && tri_mesh_add_tri(m, first, prev, v))
            return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
        prev = v;
    }
    if (n < 3) return dp_fail(err, "%s:%ld: a face needs at least 3 vertices", path, lineno);
    return 0;
}

/* A `v`, `vt` or `vn` line with `n` numbers (a `vt` may carry a third, ignored). */
static int parse_numbers(const char *s, int n, float_list *l, const char *path, long lineno, const char *what,
                         dp_error *err)
{
    double x[3] = {0, 0, 0};
    int got = sscanf(s, "%lf %lf %lf", &x[0], &x[1], &x[2]);
    if (got < n || !isfinite(x[0]) || !isfinite(x[1]) || (n == 3 && !isfinite(x[2])))
        return dp_fail(err, "%s:%ld: bad %s line", path, lineno, what);
    if (!strcmp(what, "vertex") &&
        !(fabs(x[0]) <= SCENE_COORD_MAX && fabs(x[1]) <= SCENE_COORD_MAX && fabs(x[2]) <= SCENE_COORD_MAX))
        return dp_fail(err, "%s:%ld: vertex beyond the supported coordinates (|x| <= %g)", path, lineno,
                       SCENE_COORD_MAX);
    if (list_push(l, x, n)) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    return 0;
}

int mesh_load_obj(const char *path, tri_mesh *m, dp_error *err)
{
    FILE *f = fopen(path, "r");
    if (!f) return dp_fail(err, "%s: cannot open mesh: %s", path, strerror(errno));
    obj_state o = {0};
    char line[4096];
    long lineno = 0;
    int rc = 0;
    while (!rc && fgets(line, sizeof line, f)) {
        lineno++;
        int sp1 = line[1] == ' ' || line[1] == '\t', sp2 = line[2] == ' ' || line[2] == '\t';
        if (line[0] == 'v' && sp1) rc = parse_numbers(line + 2, 3, &o.pos, path, lineno, "vertex", err);
        else if (line[0] == 'v' && line[1] == 't' && sp2) rc = parse_numbers(line + 3, 2, &o.uv, path, lineno, "vt", err);
        else if (line[0] == 'v' && line[1] == 'n' && sp2) rc = parse_numbers(line + 3, 3, &o.nrm, path, lineno, "vn", err);
        else if (line[0] == 'f' && sp1) rc = parse_face(line + 2, &o, m, path, lineno, err);
    }
    fclose(f);
    free(o.pos.v);
    free(o.uv.v);
    free(o.nrm.v);
    free(o.keys);
    free(o.vert);
    if (!rc && m->nt == 0) rc = dp_fail(err, "%s: the mesh has no faces", path);
    return rc;
}
