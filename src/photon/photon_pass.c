/* The photon pass (baseline photon points): light paths from the point lights, photons stored at medium
 * scattering vertices and Lambertian hits. Paths are traced in batches in parallel into per-thread buffers
 * and merged in path order, so budgets are cut by path index and the result is thread-count independent. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/photon.h"
#include "dartspp/scene.h"

#define BATCH 8192

typedef struct {
    photon *p;
    size_t n, cap;
} photon_buf;

static int buf_push(photon_buf *b, const photon *ph)
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 1024;
        photon *q = realloc(b->p, cap * sizeof(photon));
        if (!q) return -1;
        b->p = q;
        b->cap = cap;
    }
    b->p[b->n++] = *ph;
    return 0;
}

typedef struct {
    photon_buf vol, surf;
    long nonfinite;
    int oom;
} thread_bufs;

typedef struct {
    uint32_t n_vol, n_surf;    /* photons this path stored */
    int thread;                /* whose buffers hold them */
    size_t off_vol, off_surf;  /* where they start there */
} path_count;

static void make_photon(photon *ph, vec3 x, vec3 d, vec3 beta, int bounce, double time)
{
    ph->pos[0] = (float)x.x, ph->pos[1] = (float)x.y, ph->pos[2] = (float)x.z;
    ph->dir[0] = (float)d.x, ph->dir[1] = (float)d.y, ph->dir[2] = (float)d.z;
    ph->power[0] = (float)beta.x, ph->power[1] = (float)beta.y, ph->power[2] = (float)beta.z;
    ph->bounce = bounce;
    ph->time = time;
}

static void store(thread_bufs *tb, photon_buf *b, uint32_t *count, vec3 x, vec3 d, vec3 beta, int bounce, double t)
{
    if (!v3_is_finite(beta)) {
        tb->nonfinite++;
        return;
    }
    photon ph;
    make_photon(&ph, x, d, beta, bounce, t);
    if (buf_push(b, &ph)) tb->oom = 1;
    else (*count)++;
}

/* One light path; bounce = segments from the light. Stops when no later photon could count. */
static void trace_light_path(const scene *s, dp_rng *rng, thread_bufs *tb, path_count *pc)
{
    const integrator_settings *in = &s->integrator;
    int li = (int)(rng_uniform(rng) * s->light_count);
    if (li >= s->light_count) li = s->light_count - 1;
    const point_light *L = &s->lights[li];
    vec3 o = L->pos, d = sample_uniform_sphere(rng_uniform(rng), rng_uniform(rng));
    vec3 beta = v3_scale(L->intensity, 4.0 * M_PI * s->light_count);
    int med = L->medium, bounce = 0, medium_events = 0;
    double time = 0.0, t_end = in->window.gated ? time_window_end(&in->window) : INFINITY;
    while (bounce + 1 < in->max_bounces && time < t_end && !v3_is_zero(beta)) {
        hit_record h;
        int hit = scene_intersect(s, o, d, INFINITY, &h);
        double tmax = hit ? h.t : INFINITY;
        if (med != MEDIUM_VACUUM) {
            int event;
            double t = medium_sample_free_flight(&s->media[med], tmax, rng, &beta, &event);
            if (event) {
                o = v3_add(o, v3_scale(d, t));
                time += s->media[med].eta * t;
                bounce++;
                if (++medium_events > s->media[med].max_bounces) return;
                /* low_order_scattering off: no photon at the first medium vertex after a light or surface */
                if (time < t_end && (in->low_order_scattering || medium_events > 1))
                    store(tb, &tb->vol, &pc->n_vol, o, d, beta, bounce, time);
                d = phase_sample(&s->media[med].phase, d, rng_uniform(rng), rng_uniform(rng));
                goto roulette;
            }
        }
        if (!hit) return;
        time += medium_eta(s, med) * h.t;
        const surface *sf = &s->surfaces[h.surface];
        const bsdf *b = &s->bsdfs[sf->bsdf];
        vec3 n_in = v3_dot(d, h.ng) < 0.0 ? h.ng : v3_neg(h.ng);
        if (bsdf_is_passthrough(b)) {
            med = surface_next_medium(sf, med, d, h.ng);
            o = offset_ray_origin(h.p, v3_neg(n_in));
            continue;
        }
        bounce++;
        medium_events = 0;
        if (b->type == BSDF_MIRROR) d = v3_sub(d, v3_scale(h.ng, 2.0 * v3_dot(d, h.ng)));
        else {
            if (in->include_surfaces && time < t_end) store(tb, &tb->surf, &pc->n_surf, h.p, d, beta, bounce, time);
            vec3 l = sample_cosine_hemisphere(rng_uniform(rng), rng_uniform(rng)), t1, t2;
            v3_basis(n_in, &t1, &t2);
            d = v3_norm(v3_add(v3_add(v3_scale(t1, l.x), v3_scale(t2, l.y)), v3_scale(n_in, l.z)));
        }
        beta = v3_mul(beta, b->albedo);
        med = surface_next_medium(sf, med, d, h.ng);
        o = offset_ray_origin(h.p, n_in);
    roulette:
        if (bounce >= 5 && in->enable_rr) {
            double q = fmin(1.0, v3_max(beta));
            if (rng_uniform(rng) >= q) return;
            beta = v3_scale(beta, 1.0 / q);
        }
    }
}

typedef struct {
    size_t budget;
    int full;      /* a path did not fit: no more paths are counted or stored */
    long paths;    /* complete leading paths */
} budget_state;

/* Appends the photons of one path from a thread buffer in path order, or closes the budget. */
static int merge_path(photon_buf *dst, budget_state *bs, const photon_buf *src, size_t off, uint32_t n)
{
    if (bs->full) return 0;
    if (dst->n + n > bs->budget) {
        bs->full = 1;
        return 0;
    }
    for (uint32_t i = 0; i < n; i++)
        if (buf_push(dst, &src->p[off + i])) return -1;
    bs->paths++;
    return 0;
}

static void scale_powers(photon *p, size_t n, long paths)
{
    float inv = paths > 0 ? (float)(1.0 / paths) : 0.0f;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) p[i].power[c] *= inv;
}

int photon_pass(const scene *s, uint64_t seed, long iteration, photon_set *out, dp_error *err)
{
    memset(out, 0, sizeof *out);
    if (s->light_count == 0) return 0;
    long max_paths = (long)s->integrator.photon_count;
    budget_state bv = {.budget = (size_t)s->integrator.volume_photon_count};
    budget_state bsf = {.budget = (size_t)s->integrator.photon_count};
    photon_buf vol = {0}, surf = {0};
    int nt = omp_get_max_threads();
    thread_bufs *tb = calloc((size_t)nt, sizeof(thread_bufs));
    path_count *pc = malloc(BATCH * sizeof(path_count));
    int rc = (!tb || !pc) ? -1 : 0;
    long next = 0;
    while (!rc && next < max_paths && !(bv.full && bsf.full)) {
        long nb = max_paths - next < BATCH ? max_paths - next : BATCH;
#pragma omp parallel num_threads(nt)
        {
            thread_bufs *mine = &tb[omp_get_thread_num()];
            mine->vol.n = mine->surf.n = 0;
#pragma omp for schedule(static)
            for (long i = 0; i < nb; i++) {
                dp_rng rng = rng_stream(seed ^ 0x70686f746f6eULL, (uint64_t)iteration, (uint64_t)(next + i));
                pc[i] = (path_count){.thread = omp_get_thread_num(), .off_vol = mine->vol.n, .off_surf = mine->surf.n};
                trace_light_path(s, &rng, mine, &pc[i]);
            }
        }
        for (long i = 0; i < nb && !rc; i++) { /* merge in path order */
            const thread_bufs *src = &tb[pc[i].thread];
            rc |= merge_path(&vol, &bv, &src->vol, pc[i].off_vol, pc[i].n_vol);
            rc |= merge_path(&surf, &bsf, &src->surf, pc[i].off_surf, pc[i].n_surf);
        }
        next += nb;
    }
    for (int t = 0; t < nt && tb; t++) {
        out->nonfinite += tb[t].nonfinite;
        rc |= tb[t].oom ? -1 : 0;
        free(tb[t].vol.p);
        free(tb[t].surf.p);
    }
    free(tb);
    free(pc);
    if (rc) {
        free(vol.p);
        free(surf.p);
        return dp_fail(err, "%s: out of memory in the photon pass", s->path);
    }
    out->paths = next;
    out->vol_paths = bv.full ? bv.paths : next;
    out->surf_paths = bsf.full ? bsf.paths : next;
    scale_powers(vol.p, vol.n, out->vol_paths);
    scale_powers(surf.p, surf.n, out->surf_paths);
    out->vol = vol.p;
    out->n_vol = vol.n;
    out->surf = surf.p;
    out->n_surf = surf.n;
    return 0;
}

void photon_set_free(photon_set *ps)
{
    free(ps->vol);
    free(ps->surf);
    memset(ps, 0, sizeof *ps);
}
