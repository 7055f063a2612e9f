/* The memory guard: what a render plan will hold at its peak, item by item with the key that drives each,
 * and what the machine can give (MemAvailable, and the cgroup limit when there is one). Everything of one
 * pass is alive at once, so the peak is the sum: here the runtime, the geometry, textures, the film and the
 * output images; the integrator's own items come from its row of the table (integrators.h; photon points:
 * src/photon_points/photon_points_memory.c). tests/cli/test_cli.c checks the estimate against the measured peak.
 * Written by hand: no library estimates this. */
#include "dartspp/io.h"
#include "dartspp/render.h"
#include "integrators.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Resident memory of the process before any scene data: the C and C++ runtimes, Embree, OpenEXR, FLANN,
 * OpenMP threads (measured, Debian 12: a 1-pixel path-traced render of the fog box peaks at 10.7-10.8 MiB with
 * 1 or 2 threads, 2026-11-28; 8.7 MiB of a fog scene without geometry on 2026-11-27, which the estimate of
 * 9.0 MiB then left 1.7 MiB under the peak of small path-traced renders). */
#define RUNTIME_BYTES (11.5 * 1048576.0)
/* Geometry per triangle: our float vertices and indices, Embree's BVH and its build scratch, and the corner
 * normals and UVs of smooth and textured meshes (60 bytes, counted for every triangle: an upper bound). */
#define BYTES_PER_TRIANGLE 220.0

void render_memory_estimate(const scene *s, const render_plan *p, int have_reference, memory_estimate *m)
{
    memset(m, 0, sizeof *m);
    double px = (double)s->cam.width * s->cam.height, image = px * 3 * sizeof(float);
    memory_item_add(m, "libraries and threads", NULL, RUNTIME_BYTES);
    memory_item_add(m, "geometry (triangles and Embree BVH)", NULL, s->tri_count * BYTES_PER_TRIANGLE);
    double texels = 0;
    for (int i = 0; i < s->texture_count; i++) texels += (double)s->textures[i].width * s->textures[i].height;
    memory_item_add(m, "albedo textures", NULL, texels * 3 * sizeof(float));
    /* film_bytes in double: frames × pixels can be large */
    int frames = p->window.frame_count, layers = time_window_layers(&p->window);
    double film = 2 * px * 3 * sizeof(double) + 2 * px * 3 * (double)layers * sizeof(float);
    memory_item_add(m, "film (sums and the pass in progress)",
        p->window.orders > 0 ? "integrator.bounce_orders" : frames > 0 ? "integrator.frame_num" : "camera.resolution", film);
    /* each derivative film (film.h: deriv) has the film's sums, frame and order layers and pass layers */
    if (s->diff_count > 0) memory_item_add(m, MEMORY_DERIV_FILMS, "--derivative", s->diff_count * film);
    memory_item_add(m, "output and reference images", "camera.resolution", image * (have_reference ? 3 : 2));
    if (frames > 0) { /* written at the end: the viewer's embedded frames and histogram (io.h) */
        viewer_layout l;
        viewer_layout_of(s->cam.width, s->cam.height, frames, &l);
        memory_item_add(m, "viewer page data", "integrator.frame_num",
            (double)l.embedded * l.dw * l.dh * 3 * sizeof(float) + VIEWER_HIST_BINS * sizeof(double));
    }
    const integrator_entry *row = integrator_entry_of(p->type);
    if (row->memory) row->memory(s, p, m);
}

const memory_item *memory_largest(const memory_estimate *m)
{
    const memory_item *best = NULL;
    for (int i = 0; i < m->count; i++)
        if (m->item[i].key && (!best || m->item[i].bytes > best->bytes)) best = &m->item[i];
    return best;
}

/* A value of /proc/meminfo in bytes, or -1. */
static double meminfo(const char *key)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (!f) return -1;
    char line[256];
    double v = -1;
    size_t n = strlen(key);
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, n) && line[n] == ':') {
            v = strtod(line + n + 1, NULL) * 1024.0;
            break;
        }
    fclose(f);
    return v;
}

/* A number from a one-line file ("max" or unreadable: -1). */
static double read_number(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[64] = "";
    double v = -1;
    if (fgets(line, sizeof line, f) && strncmp(line, "max", 3)) v = strtod(line, NULL);
    fclose(f);
    return v;
}

double memory_available(void)
{
    double avail = meminfo("MemAvailable");
    double limit = read_number("/sys/fs/cgroup/memory.max"), used = read_number("/sys/fs/cgroup/memory.current");
    if (limit > 0 && used >= 0 && (avail < 0 || limit - used < avail)) avail = limit - used;
    return avail;
}

void memory_format_bytes(double bytes, char *out, size_t n)
{
    static const char *unit[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 6) {
        bytes /= 1024.0;
        u++;
    }
    snprintf(out, n, u ? "%.1f %s" : "%.0f %s", bytes, unit[u]);
}

int render_memory_check(const scene *s, const render_plan *p, int have_reference, double max_memory, int ranks_on_node,
                        memory_estimate *m, dp_error *err)
{
    render_memory_estimate(s, p, have_reference, m);
    double limit = max_memory > 0 ? max_memory : memory_available();
    if (ranks_on_node > 1 && limit > 0) limit /= ranks_on_node;
    if (!(limit > 0) || m->total <= limit) return 0;
    const memory_item *big = memory_largest(m);
    char need[32], have[32], item[32], drives[256] = "";
    memory_format_bytes(m->total, need, sizeof need);
    memory_format_bytes(limit, have, sizeof have);
    if (big) {
        memory_format_bytes(big->bytes, item, sizeof item);
        snprintf(drives, sizeof drives, "; %s drives it (%s: %s)", big->key, big->what, item);
    }
    return dp_fail(err, "%s: the render needs about %s of memory, more than the %s %s%s%s", s->path, need, have,
                   max_memory > 0 ? "allowed by the memory limit (--max-memory)" : "available",
                   ranks_on_node > 1 ? " to each of the ranks on this machine" : "", drives);
}
