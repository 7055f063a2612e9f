/* Tungsten's `.wo3` binary mesh (docs/scene-format.md §1): uint64 vertex count, 32-byte vertices
 * (pos, normal, uv as float32), uint64 triangle count, 16-byte triangles (3 × uint32 index, int32 material).
 * Little-endian; the file size must be exactly 16 + 32·nv + 16·nt. Normals and UVs are kept (has_normals and
 * has_uvs are set when some vertex has a non-zero one; a non-finite one counts as absent). */
#include "scene_internal.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static uint64_t le64(const unsigned char *b)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = (v << 8) | b[i];
    return v;
}

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

static float lef32(const unsigned char *b)
{
    uint32_t u = le32(b);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

static int read_vertices(FILE *f, const char *path, uint64_t nv, tri_mesh *m, dp_error *err)
{
    unsigned char v[32];
    for (uint64_t i = 0; i < nv; i++) {
        if (fread(v, 1, 32, f) != 32) return dp_fail(err, "%s: truncated .wo3 (vertex %llu)", path, (unsigned long long)i);
        float x = lef32(v), y = lef32(v + 4), z = lef32(v + 8);
        if (!isfinite(x) || !isfinite(y) || !isfinite(z))
            return dp_fail(err, "%s: vertex %llu has a non-finite position", path, (unsigned long long)i);
        if (!(fabsf(x) <= SCENE_COORD_MAX && fabsf(y) <= SCENE_COORD_MAX && fabsf(z) <= SCENE_COORD_MAX))
            return dp_fail(err, "%s: vertex %llu is beyond the supported coordinates (|x| <= %g)", path,
                           (unsigned long long)i, SCENE_COORD_MAX);
        if (tri_mesh_add_vertex(m, x, y, z)) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
        float *n = &m->nrm[3 * (size_t)i], *uv = &m->uv[2 * (size_t)i];
        for (int k = 0; k < 3; k++) n[k] = lef32(v + 12 + 4 * k);
        uv[0] = lef32(v + 24);
        uv[1] = lef32(v + 28);
        /* exporters write NaN normals for degenerate faces: such a normal or UV counts as absent */
        if (!isfinite(n[0]) || !isfinite(n[1]) || !isfinite(n[2])) n[0] = n[1] = n[2] = 0.0f;
        if (!isfinite(uv[0]) || !isfinite(uv[1])) uv[0] = uv[1] = 0.0f;
        m->has_normals |= n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f;
        m->has_uvs |= uv[0] != 0.0f || uv[1] != 0.0f;
    }
    return 0;
}

static int read_triangles(FILE *f, const char *path, uint64_t nt, uint64_t nv, tri_mesh *m, dp_error *err)
{
    unsigned char t[16];
    for (uint64_t i = 0; i < nt; i++) {
        if (fread(t, 1, 16, f) != 16) return dp_fail(err, "%s: truncated .wo3 (triangle %llu)", path, (unsigned long long)i);
        uint32_t a = le32(t), b = le32(t + 4), c = le32(t + 8);
        if (a >= nv || b >= nv || c >= nv)
            return dp_fail(err, "%s: triangle %llu refers to vertex %u of %llu", path, (unsigned long long)i,
                           a >= nv ? a : (b >= nv ? b : c), (unsigned long long)nv);
        if (tri_mesh_add_tri(m, a, b, c)) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    }
    return 0;
}

int mesh_load_wo3(const char *path, tri_mesh *m, dp_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return dp_fail(err, "%s: cannot open mesh: %s", path, strerror(errno));
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char b8[8];
    int rc = -1;
    if (size < 16 || fread(b8, 1, 8, f) != 8) {
        dp_fail(err, "%s: not a .wo3 mesh (file of %ld bytes is too short)", path, size);
        goto done;
    }
    uint64_t nv = le64(b8);
    if (nv > (uint64_t)(size - 16) / 32) {
        dp_fail(err, "%s: not a .wo3 mesh (declares %llu vertices in %ld bytes)", path, (unsigned long long)nv, size);
        goto done;
    }
    if (read_vertices(f, path, nv, m, err)) goto done;
    if (fread(b8, 1, 8, f) != 8) {
        dp_fail(err, "%s: truncated .wo3 (no triangle count)", path);
        goto done;
    }
    uint64_t nt = le64(b8);
    if ((uint64_t)size != 16 + 32 * nv + 16 * nt) {
        dp_fail(err, "%s: not a .wo3 mesh (size %ld != 16 + 32*%llu + 16*%llu)", path, size,
                (unsigned long long)nv, (unsigned long long)nt);
        goto done;
    }
    rc = read_triangles(f, path, nt, nv, m, err);
done:
    fclose(f);
    return rc;
}
