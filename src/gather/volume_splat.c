/* The volume gather on the primary lines, photon by photon: every primary line starts at the camera (or, for
 * an orthographic camera, runs parallel to its axis from its film point), so the pixels whose line can pass
 * within r of a photon are those its ball covers on the image, a small rectangle. Each photon is binned into the image tiles its rectangle meets; a tile then tests its photons
 * against its own pixels' lines. The same pairs as one beam query per segment, without a tree walk per
 * ray, and the lines of a tile stay in cache. Written by hand: no library does this. */
#include <stdint.h>
#include <stdlib.h>

#include "primary_line.h"

#define TILE 16                      /* tile side in pixels */
#define TILE_ENTRIES_MAX (1u << 26)  /* photon-in-tile entries at most (256 MiB of indices), else -1 */
#define RASTER_PAD 1e-6              /* pixels added around a footprint against rounding */

typedef struct {
    int x0, y0, x1, y1; /* inclusive pixel range; x1 < x0 when the photon is seen by no pixel */
} footprint;

int volume_splat_applies(const scene *s, const gather_input *g)
{
    const camera *c = &s->cam;
    if (!g->vol_photons || g->n_vol == 0) return 0;
    double e = fabs(v3_dot(c->right, c->up)) + fabs(v3_dot(c->up, c->forward)) + fabs(v3_dot(c->right, c->forward));
    return e < 1e-9 && fabs(v3_len(c->right) - 1.0) < 1e-9 && fabs(v3_len(c->up) - 1.0) < 1e-9 &&
           fabs(v3_len(c->forward) - 1.0) < 1e-9;
}

size_t volume_splat_bytes(int width, int height)
{
    return (size_t)width * (size_t)height * sizeof(primary_line);
}

/* Image-plane range [lo, hi] of a/z over a disc of radius r centred at (a, z) in the plane of the camera
 * axis (the tangents from the camera); 0 when the disc lies behind the camera. ±HUGE_VAL for an open side. */
static int tangent_range(double a, double z, double r, double *lo, double *hi)
{
    double rho = sqrt(a * a + z * z);
    if (!(rho > r)) { /* the disc holds the camera's axis line: every direction of this plane */
        *lo = -HUGE_VAL;
        *hi = HUGE_VAL;
        return 1;
    }
    double theta = atan2(a, z), alpha = asin(r / rho);
    double t_lo = theta - alpha, t_hi = theta + alpha;
    if (t_hi <= -M_PI_2 || t_lo >= M_PI_2) return 0;
    *lo = t_lo <= -M_PI_2 ? -HUGE_VAL : tan(t_lo);
    *hi = t_hi >= M_PI_2 ? HUGE_VAL : tan(t_hi);
    return 1;
}

static int clamp_pixel(double v, int n)
{
    if (!(v > 0.0)) return 0;
    if (v >= n - 1) return n - 1;
    return (int)v;
}

/* The pixel range [lo, hi] of an orthographic camera whose lines pass within r of x: its film point
 * (cx, cy) ± r (camera_ray's film point inverted), or 0 when x lies more than r behind the camera's plane. */
static int ortho_range(const camera *c, double cx, double cy, double cz, double r, double px[2], double py[2])
{
    if (cz < -r) return 0;
    double a = camera_ortho_pixel(c), h = c->ortho_size * c->width / c->height;
    px[0] = (cx - r + h) / a - RASTER_PAD, px[1] = (cx + r + h) / a + RASTER_PAD;
    py[0] = (c->ortho_size - cy - r) / a - RASTER_PAD, py[1] = (c->ortho_size - cy + r) / a + RASTER_PAD;
    return 1;
}

/* The pixels whose jittered ray can pass within r of x (camera_ray inverted; right, up and forward
 * orthonormal). */
static footprint photon_footprint(const camera *c, vec3 x, double r)
{
    footprint fp = {0, 0, -1, -1};
    vec3 w = v3_sub(x, c->pos);
    double cx = v3_dot(w, c->right), cy = v3_dot(w, c->up), cz = v3_dot(w, c->forward);
    double px_lo, px_hi, py_lo, py_hi;
    if (c->type == CAMERA_ORTHOGRAPHIC) {
        double px[2], py[2];
        if (!ortho_range(c, cx, cy, cz, r, px, py)) return fp;
        px_lo = px[0], px_hi = px[1], py_lo = py[0], py_hi = py[1];
    } else {
        double xl, xh, yl, yh;
        if (!tangent_range(cx, cz, r, &xl, &xh) || !tangent_range(cy, cz, r, &yl, &yh)) return fp;
        /* image plane: X = plane_dist·tan = -1 + px·sx, Y = plane_dist·tan = h/w - py·sx */
        double sx = 2.0 / c->width, aspect = (double)c->height / c->width;
        px_lo = (c->plane_dist * xl + 1.0) / sx - RASTER_PAD, px_hi = (c->plane_dist * xh + 1.0) / sx + RASTER_PAD;
        py_lo = (aspect - c->plane_dist * yh) / sx - RASTER_PAD, py_hi = (aspect - c->plane_dist * yl) / sx + RASTER_PAD;
    }
    if (px_hi < 0.0 || py_hi < 0.0 || px_lo >= c->width || py_lo >= c->height) return fp;
    fp.x0 = clamp_pixel(px_lo, c->width);
    fp.x1 = clamp_pixel(px_hi, c->width);
    fp.y0 = clamp_pixel(py_lo, c->height);
    fp.y1 = clamp_pixel(py_hi, c->height);
    return fp;
}

/* The tiles a footprint meets (0 when no pixel sees the photon). */
static size_t footprint_tiles(const footprint *f)
{
    if (f->x1 < f->x0) return 0;
    return (size_t)(f->y1 / TILE - f->y0 / TILE + 1) * (size_t)(f->x1 / TILE - f->x0 / TILE + 1);
}

typedef struct {
    int tiles_x, tiles_y;
    footprint *fp;    /* per photon */
    size_t *start;    /* per tile: first entry; start[tiles] = entry count */
    uint32_t *entry;  /* photon indices, ascending within a tile */
} tile_bins;

static void tile_bins_free(tile_bins *b)
{
    free(b->fp);
    free(b->start);
    free(b->entry);
}

/* Footprints in parallel, then a counting sort by tile (sequential: photon order within every tile). */
static int tile_bins_build(tile_bins *b, const camera *c, const photon *ph, size_t n, double r)
{
    b->tiles_x = (c->width + TILE - 1) / TILE;
    b->tiles_y = (c->height + TILE - 1) / TILE;
    size_t tiles = (size_t)b->tiles_x * b->tiles_y;
    b->fp = malloc(n * sizeof *b->fp);
    b->start = calloc(tiles + 1, sizeof *b->start);
    b->entry = NULL;
    if (!b->fp || !b->start) return -1;
#pragma omp parallel for schedule(static) default(none) shared(b, c, ph, n, r)
    for (size_t i = 0; i < n; i++) b->fp[i] = photon_footprint(c, v3(ph[i].pos[0], ph[i].pos[1], ph[i].pos[2]), r);
    size_t total = 0;
    for (size_t i = 0; i < n; i++) {
        const footprint *f = &b->fp[i];
        if (f->x1 < f->x0) continue;
        for (int ty = f->y0 / TILE; ty <= f->y1 / TILE; ty++)
            for (int tx = f->x0 / TILE; tx <= f->x1 / TILE; tx++) b->start[(size_t)ty * b->tiles_x + tx + 1]++;
        total += footprint_tiles(f);
        if (total > TILE_ENTRIES_MAX) return -1;
    }
    for (size_t t = 0; t < tiles; t++) b->start[t + 1] += b->start[t];
    b->entry = malloc((total ? total : 1) * sizeof *b->entry);
    size_t *next = malloc((tiles ? tiles : 1) * sizeof *next);
    if (!b->entry || !next) {
        free(next);
        return -1;
    }
    for (size_t t = 0; t < tiles; t++) next[t] = b->start[t];
    for (size_t i = 0; i < n; i++) {
        const footprint *f = &b->fp[i];
        if (f->x1 < f->x0) continue;
        for (int ty = f->y0 / TILE; ty <= f->y1 / TILE; ty++)
            for (int tx = f->x0 / TILE; tx <= f->x1 / TILE; tx++) b->entry[next[(size_t)ty * b->tiles_x + tx]++] = (uint32_t)i;
    }
    free(next);
    return 0;
}

/* What a photon's estimate on a line segment that starts at the camera does not owe to the pixel: with
 * the Euclidean camera leg, the leg |x − camera| and so the path time and whether the film counts it
 * (volume_photon_splat, computed the same way: the segment origin is the camera itself). Not for an
 * orthographic camera, whose lines start at their own film points: there every pixel computes its own. */
typedef struct {
    int valid;        /* the camera sits in a medium and the leg is Euclidean */
    film_slot slot;   /* slot.counts: the bounce count and the path time are counted */
} camera_leg_time;

static camera_leg_time photon_camera_time(const scene *s, const gather_input *g, const film *f, const photon *p)
{
    camera_leg_time c = {0};
    if (s->cam.medium == MEDIUM_VACUUM || g->camera_leg_projected || s->cam.type == CAMERA_ORTHOGRAPHIC) return c;
    vec3 x = v3(p->pos[0], p->pos[1], p->pos[2]);
    double leg = v3_len(v3_sub(x, s->cam.pos));
    c.valid = 1;
    if (g->camera_unwarp) leg = 0.0; /* as volume_photon_splat: the sensor's own segment takes no time */
    c.slot = film_time_slot(f, 0.0 + p->time + s->media[s->cam.medium].eta * leg, p->frame, p->bounce); /* b_cam 1 */
    c.slot.counts = c.slot.counts && bounces_count(&g->bounces, p->bounce + 1);
    return c;
}

/* Photon p against one pixel's line: the segment holding its projection, if within r (the beam test). */
static void splat_photon_on_line(const scene *s, const gather_input *g, film_pixel *pix, const primary_line *L,
                                 const photon *p, vec3 x, const camera_leg_time *ct)
{
    vec3 lo = v3(L->o[0], L->o[1], L->o[2]), w = v3_sub(x, lo);
    double t = w.x * L->d[0] + w.y * L->d[1] + w.z * L->d[2];
    double vx = w.x - t * L->d[0], vy = w.y - t * L->d[1], vz = w.z - t * L->d[2];
    double d2 = vx * vx + vy * vy + vz * vz;
    if (d2 > g->r_vol * g->r_vol) return;
    for (int k = 0; k < L->n; k++) {
        const line_segment *sg = &L->seg[k];
        if (t < sg->t0 || t > sg->t1) continue;
        vec3 d = v3(L->d[0], L->d[1], L->d[2]);
        if (ct->valid && sg->t0 == 0.0 && sg->t_cam == 0.0 && sg->medium == s->cam.medium) { /* from the camera */
            if (ct->slot.counts)
                volume_photon_splat_slot(g, pix, &s->media[sg->medium], d, v3(sg->thr[0], sg->thr[1], sg->thr[2]), p,
                                         t, d2, &ct->slot);
            return;
        }
        vec3 o = v3_add(lo, v3_scale(d, sg->t0));
        volume_photon_splat(g, pix, &s->media[sg->medium], o, d, v3(sg->thr[0], sg->thr[1], sg->thr[2]), sg->t_cam, 1,
                            p, t - sg->t0, d2);
        return;
    }
}

static void splat_tile(const scene *s, const gather_input *g, film *f, const primary_line *lines,
                       const tile_bins *b, int tx, int ty, long *nonfinite)
{
    const camera *c = &s->cam;
    size_t tile = (size_t)ty * b->tiles_x + tx;
    int X0 = tx * TILE, Y0 = ty * TILE, X1 = X0 + TILE - 1, Y1 = Y0 + TILE - 1;
    for (size_t e = b->start[tile]; e < b->start[tile + 1]; e++) {
        uint32_t i = b->entry[e];
        const photon *p = &g->vol_photons[i];
        const footprint *fp = &b->fp[i];
        vec3 xp = v3(p->pos[0], p->pos[1], p->pos[2]);
        camera_leg_time ct = photon_camera_time(s, g, f, p);
        int x0 = fp->x0 > X0 ? fp->x0 : X0, x1 = fp->x1 < X1 ? fp->x1 : X1;
        int y0 = fp->y0 > Y0 ? fp->y0 : Y0, y1 = fp->y1 < Y1 ? fp->y1 : Y1;
        for (int y = y0; y <= y1; y++)
            for (int x = x0; x <= x1; x++) {
                size_t px = (size_t)y * c->width + x;
                if (lines[px].n == 0) continue;
                film_pixel pix = {.f = f, .px = px};
                splat_photon_on_line(s, g, &pix, &lines[px], p, xp, &ct);
                *nonfinite += pix.nonfinite;
            }
    }
}

typedef struct {
    size_t entries;
    int tile;
} tile_load;

static int cmp_load(const void *x, const void *y)
{
    const tile_load *a = x, *b = y;
    if (a->entries != b->entries) return a->entries > b->entries ? -1 : 1;
    return (a->tile > b->tile) - (a->tile < b->tile);
}

/* The tiles by their photon entries, most first (longest processing time first): a tile's pixels are its
 * own, so the order changes nothing in the image, and heavy tiles near the light no longer end a pass with
 * one thread working and the other waiting. NULL when out of memory. */
static tile_load *heaviest_first(const tile_bins *b, int tiles)
{
    tile_load *l = malloc((size_t)(tiles ? tiles : 1) * sizeof *l);
    if (!l) return NULL;
    for (int t = 0; t < tiles; t++) l[t] = (tile_load){b->start[t + 1] - b->start[t], t};
    qsort(l, (size_t)tiles, sizeof *l, cmp_load);
    return l;
}

int volume_splat(const scene *s, const gather_input *g, film *f, const primary_line *lines)
{
    tile_bins b;
    if (tile_bins_build(&b, &s->cam, g->vol_photons, g->n_vol, g->r_vol)) {
        tile_bins_free(&b);
        return -1;
    }
    int tiles = b.tiles_x * b.tiles_y;
    tile_load *order = heaviest_first(&b, tiles);
    if (!order) {
        tile_bins_free(&b);
        return -1;
    }
    long bad = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : bad) default(none) shared(s, g, f, lines, b, tiles, order)
    for (int k = 0; k < tiles; k++) {
        if (dp_stopped(g->stop)) continue;
        int t = order[k].tile;
        splat_tile(s, g, f, lines, &b, t % b.tiles_x, t / b.tiles_x, &bad);
    }
    f->nonfinite += bad;
    free(order);
    tile_bins_free(&b);
    return 0;
}

double volume_splat_scratch_bytes(const camera *c, const photon *sample, size_t n, double r, double photons)
{
    double tiles = (double)((c->width + TILE - 1) / TILE) * (double)((c->height + TILE - 1) / TILE), entries = 0.0;
    for (size_t i = 0; i < n; i++) {
        footprint f = photon_footprint(c, v3(sample[i].pos[0], sample[i].pos[1], sample[i].pos[2]), r);
        entries += (double)footprint_tiles(&f);
    }
    entries = n > 0 ? fmin(entries * photons / (double)n, (double)TILE_ENTRIES_MAX) : 0.0;
    return photons * sizeof(footprint) + tiles * (2 * sizeof(size_t) + sizeof(tile_load)) + entries * sizeof(uint32_t);
}

void primary_line_gather_beam(const scene *s, const gather_input *g, film_pixel *pix, const primary_line *line)
{
    vec3 d = v3(line->d[0], line->d[1], line->d[2]), o = v3(line->o[0], line->o[1], line->o[2]);
    for (int k = 0; k < line->n; k++) {
        const line_segment *sg = &line->seg[k];
        volume_beam_gather(g, pix, &s->media[sg->medium], v3_add(o, v3_scale(d, sg->t0)), d, sg->t1 - sg->t0,
                           v3(sg->thr[0], sg->thr[1], sg->thr[2]), sg->t_cam, 1, NULL);
    }
}
