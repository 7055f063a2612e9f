/* The digest of a loaded scene, one 64-bit FNV-1a per part (geometry, materials, media, lights, camera), kept in
 * the checkpoint state so that `--resume` refuses the sums of another scene instead of blending them into this
 * one. It hashes what the integrators read after loading (positions, parameters, texture texels, the sensor's
 * response table), field by field and never whole structs: padding bytes and pointers differ from run to run.
 * Derived values (a BSDF's cached terms, an area light's CDF) follow from the hashed ones and are left out;
 * the camera's resolution is compared on its own (resume.c), with a message of its own. */
#include <string.h>

#include "run_internal.h"

#define FNV_OFFSET 0xcbf29ce484222325ULL

static void h_bytes(uint64_t *h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) *h = (*h ^ b[i]) * 0x100000001b3ULL;
}

/* -0.0 and 0.0 render alike: one digest */
static void h_d(uint64_t *h, double v)
{
    if (v == 0.0) v = 0.0;
    h_bytes(h, &v, sizeof v);
}

static void h_i(uint64_t *h, long v) { h_bytes(h, &v, sizeof v); }
static void h_v3(uint64_t *h, vec3 v) { h_d(h, v.x), h_d(h, v.y), h_d(h, v.z); }
static void h_str(uint64_t *h, const char *s) { h_bytes(h, s, strlen(s) + 1); }

static uint64_t geometry(const scene *s)
{
    uint64_t h = FNV_OFFSET;
    h_i(&h, s->vert_count), h_i(&h, s->tri_count);
    if (s->verts) h_bytes(&h, s->verts, (size_t)s->vert_count * 3 * sizeof(float));
    if (s->tris) h_bytes(&h, s->tris, (size_t)s->tri_count * 3 * sizeof(uint32_t));
    h_i(&h, s->surface_count);
    for (int i = 0; i < s->surface_count; i++) {
        const surface *f = &s->surfaces[i];
        h_str(&h, f->name), h_i(&h, f->bsdf), h_i(&h, f->overrides_media), h_i(&h, f->int_medium);
        h_i(&h, f->ext_medium), h_i(&h, f->first_tri), h_i(&h, f->tri_count), h_i(&h, f->emitter);
    }
    return h;
}

static uint64_t materials(const scene *s)
{
    uint64_t h = FNV_OFFSET;
    h_i(&h, s->bsdf_count);
    for (int i = 0; i < s->bsdf_count; i++) {
        const bsdf *b = &s->bsdfs[i];
        h_i(&h, b->type), h_str(&h, b->name), h_v3(&h, b->albedo), h_i(&h, b->texture), h_i(&h, b->distribution);
        h_d(&h, b->roughness), h_v3(&h, b->eta), h_v3(&h, b->k), h_d(&h, b->ior), h_i(&h, b->enable_refraction);
        h_d(&h, b->thickness), h_v3(&h, b->sigma_a), h_d(&h, b->ks);
    }
    h_i(&h, s->texture_count);
    for (int i = 0; i < s->texture_count; i++) {
        const texture *t = &s->textures[i];
        h_i(&h, t->width), h_i(&h, t->height);
        if (t->rgb) h_bytes(&h, t->rgb, (size_t)t->width * t->height * 3 * sizeof(float));
    }
    return h;
}

static uint64_t media(const scene *s)
{
    uint64_t h = FNV_OFFSET;
    h_i(&h, s->medium_count);
    for (int i = 0; i < s->medium_count; i++) {
        const medium *m = &s->media[i];
        h_str(&h, m->name), h_i(&h, m->guided), h_v3(&h, m->sigma_s), h_v3(&h, m->sigma_a), h_v3(&h, m->sigma_t);
        h_d(&h, m->eta), h_i(&h, m->max_bounces), h_i(&h, m->phase.type), h_d(&h, m->phase.g), h_i(&h, m->eda);
        h_d(&h, m->eda_alpha), h_d(&h, m->eda_r_lo), h_d(&h, m->eda_r_hi), h_d(&h, m->eda_s_max);
        h_str(&h, m->eda_table_path);
        const phase_table *t = m->phase.type == PHASE_TABULATED ? m->phase.table : NULL;
        if (t) { /* the table's knots, normalised (its CDF follows from them) */
            h_i(&h, t->n);
            for (int k = 0; k < t->n; k++) h_d(&h, t->theta[k]), h_d(&h, t->p[k]);
        }
    }
    return h;
}

static uint64_t lights(const scene *s)
{
    uint64_t h = FNV_OFFSET;
    h_i(&h, s->light_count);
    for (int i = 0; i < s->light_count; i++) {
        const emitter *e = &s->lights[i];
        h_str(&h, e->name), h_str(&h, e->type_name), h_i(&h, e->flags), h_i(&h, e->medium);
        h_d(&h, e->pulse.start), h_d(&h, e->pulse.width), h_i(&h, e->pulse.shape), h_v3(&h, e->value);
        h_v3(&h, e->flux), h_v3(&h, e->pos), h_v3(&h, e->axis), h_v3(&h, e->e1), h_v3(&h, e->e2);
        h_d(&h, e->cos_end), h_d(&h, e->cos_start), h_d(&h, e->radius), h_d(&h, e->cos_div), h_i(&h, e->surface);
        h_i(&h, e->first_tri), h_i(&h, e->tri_count), h_d(&h, e->area), h_d(&h, e->extent);
    }
    return h;
}

static uint64_t camera_part(const scene *s)
{
    const camera *c = &s->cam;
    uint64_t h = FNV_OFFSET;
    h_d(&h, c->fov_deg), h_v3(&h, c->pos), h_v3(&h, c->right), h_v3(&h, c->up), h_v3(&h, c->forward);
    h_d(&h, c->plane_dist), h_i(&h, c->medium);
    if (c->type == CAMERA_ORTHOGRAPHIC) h_i(&h, c->type), h_d(&h, c->ortho_size); /* pinhole digests as before */
    if (c->type == CAMERA_LIDAR) { /* its beams, receiver, bins and echo keys (the light part holds its pulse) */
        const lidar_params *l = &c->lidar;
        h_i(&h, c->type), h_i(&h, l->channels), h_i(&h, l->azimuth_steps), h_d(&h, l->elevation[0]);
        h_d(&h, l->elevation[1]), h_d(&h, l->azimuth[0]), h_d(&h, l->azimuth[1]), h_d(&h, l->beam_divergence);
        h_d(&h, l->receiver_fov), h_d(&h, l->power), h_d(&h, l->max_range), h_d(&h, l->range_bin);
        h_v3(&h, l->offset), h_i(&h, l->echoes), h_d(&h, l->echo_threshold), h_i(&h, l->max_echoes);
    }
    const sensor_response *r = &c->response;
    h_i(&h, r->on), h_d(&h, r->sigma), h_d(&h, r->tail), h_i(&h, r->n);
    for (int i = 0; i < r->n && r->t && r->p; i++) h_d(&h, r->t[i]), h_d(&h, r->p[i]);
    return h;
}

const char *const SCENE_DIGEST_NAMES[SCENE_DIGEST_PARTS] = {"geometry", "materials", "media", "lights", "camera"};

void scene_digest(const scene *s, uint64_t part[SCENE_DIGEST_PARTS])
{
    part[0] = geometry(s);
    part[1] = materials(s);
    part[2] = media(s);
    part[3] = lights(s);
    part[4] = camera_part(s);
}
