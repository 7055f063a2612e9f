/* Wavefront `.obj`: `v` positions and `f` polygons (fan-triangulated; v, v/vt, v//vn, v/vt/vn; negative
 * indices relative to the end). Everything else (normals, uvs, groups, materials) is ignored. */
#include "scene_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int parse_index(const char *tok, uint32_t nv, uint32_t *out)
{
    char *end;
    long i = strtol(tok, &end, 10);
    if (end == tok || i == 0) return -1;
    long k = i > 0 ? i - 1 : (long)nv + i;
    if (k < 0 || k >= (long)nv) return -1;
    *out = (uint32_t)k;
    return 0;
}

static int parse_face(char *line, tri_mesh *m, const char *path, long lineno, dp_error *err)
{
    uint32_t first = 0, prev = 0;
    int n = 0;
    for (char *tok = strtok(line, " \t\r\n"); tok; tok = strtok(NULL, " \t\r\n"), n++) {
        uint32_t k;
        if (parse_index(tok, m->nv, &k)) return dp_fail(err, "%s:%ld: bad face index '%s'", path, lineno, tok);
        if (n == 0) first = k;
        else if (n >= 2 && tri_mesh_add_tri(m, first, prev, k)) return dp_fail(err, "%s: out of memory", path);
        prev = k;
    }
    if (n < 3) return dp_fail(err, "%s:%ld: a face needs at least 3 vertices", path, lineno);
    return 0;
}

int mesh_load_obj(const char *path, tri_mesh *m, dp_error *err)
{
    FILE *f = fopen(path, "r");
    if (!f) return dp_fail(err, "%s: cannot open mesh: %s", path, strerror(errno));
    char line[4096];
    long lineno = 0;
    int rc = 0;
    while (!rc && fgets(line, sizeof line, f)) {
        lineno++;
        if (line[0] == 'v' && (line[1] == ' ' || line[1] == '\t')) {
            double x, y, z;
            if (sscanf(line + 2, "%lf %lf %lf", &x, &y, &z) != 3 || !isfinite(x) || !isfinite(y) || !isfinite(z))
                rc = dp_fail(err, "%s:%ld: bad vertex line", path, lineno);
            else if (tri_mesh_add_vertex(m, x, y, z)) rc = dp_fail(err, "%s: out of memory", path);
        } else if (line[0] == 'f' && (line[1] == ' ' || line[1] == '\t')) {
            rc = parse_face(line + 2, m, path, lineno, err);
        }
    }
    fclose(f);
    if (!rc && m->nt == 0) rc = dp_fail(err, "%s: the mesh has no faces", path);
    return rc;
}
