/* The lidar camera's keys (docs/lidar.md §2), declared once in the tables below — reading, ranges, defaults and
 * the docs' list come from them — and what a lidar sets in the rest of the scene: its beam as the scene's one
 * light (a diverging collimated emitter of radius 0, re-aimed per beam by the path tracer) and the time window
 * whose frames are its range bins (docs/lidar.md §1). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_internal.h"

#define DEG (M_PI / 180.0)

/* A number key of the lidar: where it goes in lidar_params, its default, its range [lo, hi] (lo excluded
 * when open_lo), whether it is a whole number, and its meaning. */
typedef struct {
    const char *key;
    size_t offset; /* of a double, or of an int when whole */
    int whole, open_lo;
    double def, lo, hi;
    const char *meaning;
} lidar_number_key;

#define AT(f) offsetof(lidar_params, f)
static const lidar_number_key NUMBER_KEYS[] = {
    {"channels", AT(channels), 1, 0, 32, 1, 4096, "elevations (rings), evenly spaced over `elevation`"},
    {"azimuth_steps", AT(azimuth_steps), 1, 0, 360, 1, 65536, "azimuths per scan, at the centres of equal steps of `azimuth`"},
    {"beam_divergence", AT(beam_divergence), 0, 1, 0.003, 0, 1.5, "full angle of the transmitted cone, radians"},
    {"receiver_fov", AT(receiver_fov), 0, 1, 0.006, 0, 1.5, "full angle of the receiver's field of view, radians"},
    {"power", AT(power), 0, 0, 1.0, 0, 1e30, "the pulse's energy Φ (emitted flux × the pulse, a density in time)"},
    {"pulse_width", AT(pulse.width), 0, 0, 1.5, 0, 1e30, "the pulse's width as path length (box: its length; gaussian: FWHM)"},
    {"max_range", AT(max_range), 0, 1, 100.0, 0, 1e30, "range of the last bin's end, scene units"},
    {"range_bin", AT(range_bin), 0, 1, 0.1, 0, 1e30, "bin width in range, scene units (a bin is 2·range_bin of path time)"},
    {"echo_threshold", AT(echo_threshold), 0, 1, 0.1, 0, 1e30,
     "detection threshold, as a fraction of the peak bin of a white Lambertian target at max_range in clear air"},
    {"max_echoes", AT(max_echoes), 1, 0, 5, 1, 255, "echoes kept per beam with echoes = all"},
};
#define NUMBER_KEY_COUNT (int)(sizeof NUMBER_KEYS / sizeof NUMBER_KEYS[0])

static const char *const ECHO_MODES[] = {"first", "strongest", "last", "all"}; /* lidar_echo_mode's order */

static int read_number_key(json_ctx *c, const cJSON *v, const lidar_number_key *k, lidar_params *l)
{
    double x;
    if (jget_number(c, v, "camera", k->key, k->def, &x)) return -1;
    if (!(k->open_lo ? x > k->lo : x >= k->lo) || !(x <= k->hi))
        return jfail(c, "camera", k->key, "must be in %s%g, %g] (%s; got %g)", k->open_lo ? "(" : "[", k->lo, k->hi,
                     k->meaning, x);
    if (k->whole && x != floor(x)) return jfail(c, "camera", k->key, "must be a whole number (got %.17g)", x);
    char *field = (char *)l + k->offset;
    if (k->whole) *(int *)field = (int)x;
    else *(double *)field = x;
    return 0;
}

/* [min, max] in degrees into radians; min <= max */
static int read_span(json_ctx *c, const cJSON *v, const char *key, double lo, double hi, const double def[2],
                     double out[2])
{
    const cJSON *a = jget_item(c, v, key);
    out[0] = def[0] * DEG;
    out[1] = def[1] * DEG;
    if (!a) return 0;
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != 2 || !cJSON_IsNumber(cJSON_GetArrayItem(a, 0)) ||
        !cJSON_IsNumber(cJSON_GetArrayItem(a, 1)))
        return jfail(c, "camera", key, "expected [min, max] in degrees");
    double x0 = cJSON_GetArrayItem(a, 0)->valuedouble, x1 = cJSON_GetArrayItem(a, 1)->valuedouble;
    if (!(x0 >= lo && x1 <= hi && x0 <= x1))
        return jfail(c, "camera", key, "must be [min, max] with %g <= min <= max <= %g degrees (got [%g, %g])", lo, hi,
                     x0, x1);
    out[0] = x0 * DEG;
    out[1] = x1 * DEG;
    return 0;
}

static int read_choice(json_ctx *c, const cJSON *v, const char *key, const char *const *names, int n, int def,
                       int *out)
{
    const char *name = names[def];
    if (jget_string(c, v, "camera", key, &name) < 0) return -1;
    for (int i = 0; i < n; i++)
        if (!strcmp(name, names[i])) return *out = i, 0;
    return jfail(c, "camera", key, "unknown choice '%s' (supported: %s, %s%s%s%s%s)", name, names[0], names[1],
                 n > 2 ? ", " : "", n > 2 ? names[2] : "", n > 3 ? ", " : "", n > 3 ? names[3] : "");
}

static int read_keys(json_ctx *c, const cJSON *v, lidar_params *l)
{
    for (int i = 0; i < NUMBER_KEY_COUNT; i++)
        if (read_number_key(c, v, &NUMBER_KEYS[i], l)) return -1;
    static const double el_def[2] = {-15.0, 15.0}, az_def[2] = {-180.0, 180.0};
    static const char *const shapes[] = {"box", "gaussian"}; /* pulse_shape's order */
    int shape = PULSE_GAUSSIAN, echoes = LIDAR_ECHO_STRONGEST;
    if (read_span(c, v, "elevation", -90.0, 90.0, el_def, l->elevation) ||
        read_span(c, v, "azimuth", -360.0, 360.0, az_def, l->azimuth) ||
        read_choice(c, v, "pulse_shape", shapes, 2, PULSE_GAUSSIAN, &shape) ||
        read_choice(c, v, "echoes", ECHO_MODES, 4, LIDAR_ECHO_STRONGEST, &echoes) ||
        jget_vec3(c, v, "camera", "transmitter_offset", v3s(0.0), &l->offset))
        return -1;
    l->pulse = (emitter_pulse){.start = -0.5 * l->pulse.width, .width = l->pulse.width, .shape = (pulse_shape)shape};
    l->echoes = (lidar_echo_mode)echoes;
    return 0;
}

static int check_keys(json_ctx *c, const lidar_params *l)
{
    if (l->azimuth[1] - l->azimuth[0] > 2.0 * M_PI + 1e-12)
        return jfail(c, "camera", "azimuth", "spans more than 360 degrees (%g): beams would repeat",
                     (l->azimuth[1] - l->azimuth[0]) / DEG);
    double bins = ceil(l->max_range / l->range_bin * (1.0 - 1e-12));
    if (!(bins <= 1 << 20))
        return jfail(c, "camera", "range_bin", "max_range / range_bin = %g bins; at most %d are supported",
                     l->max_range / l->range_bin, 1 << 20);
    if (l->receiver_fov < l->beam_divergence)
        jwarn(c, "camera.receiver_fov: %g rad is narrower than beam_divergence %g rad: a coaxial receiver sees only the "
                 "centre of its own spot (legal, but most lidars have receiver_fov >= beam_divergence)",
              l->receiver_fov, l->beam_divergence);
    return 0;
}

int lidar_parse_camera(json_ctx *c, const cJSON *v, camera *cam)
{
    if (jget_item(c, v, "resolution"))
        return jfail(c, "camera", "resolution", "a lidar's resolution is set by azimuth_steps × channels: remove it");
    lidar_params *l = &cam->lidar;
    if (read_keys(c, v, l) || check_keys(c, l)) return -1;
    l->bins = (int)ceil(l->max_range / l->range_bin * (1.0 - 1e-12));
    cam->width = l->azimuth_steps;
    cam->height = l->channels;
    if ((double)cam->width * cam->height > 1 << 28)
        return jfail(c, "camera", "azimuth_steps", "azimuth_steps × channels = %g beams; at most 2^28 are supported",
                     (double)cam->width * cam->height);
    return 0;
}

/* ---- what a lidar sets in the rest of the scene ---- */

/* The integrator keys a lidar sets itself, or that do not apply to it. */
static int refuse_integrator_keys(json_ctx *c, const cJSON *root, const scene *s, int derivatives)
{
    static const char *const time_keys[] = {"transient_time_center", "transient_time_width", "frame_num", "start_time",
                                            "delta_time_gate"};
    const cJSON *in = cJSON_GetObjectItemCaseSensitive(root, "integrator");
    for (size_t i = 0; i < sizeof time_keys / sizeof time_keys[0]; i++)
        if (cJSON_GetObjectItemCaseSensitive(in, time_keys[i]))
            return jfail(c, "integrator", time_keys[i], "a lidar camera sets the time window itself: its frames are the "
                         "range bins of max_range and range_bin (docs/lidar.md §1); remove the key");
    if (s->integrator.camera_unwarp)
        return jfail(c, "integrator", "camera_unwarp", "a lidar's range is half the whole path time, the receiver's "
                     "leg included: camera_unwarp must be false");
    if (s->integrator.type != INTEGRATOR_PATH_TRACER)
        return jfail(c, "integrator", "type", "a lidar camera renders with the path tracers (type path_tracer, with "
                     "or without DARTS or uniform time sampling), not %s: every beam has its own light, and a photon "
                     "map per beam would not pay", s->integrator.type_name);
    if (derivatives)
        return jfail(c, "camera", "type", "derivatives are not available with a lidar camera (docs/lidar.md §2)");
    return 0;
}

/* The beam's template (docs/lidar.md §3): a point at the transmitter with intensity Φ·cosθ/(π sin²δ) in the cone
 * of half-angle δ = beam_divergence/2 (the collimated type of radius 0 with that divergence), its pulse centred
 * on t = 0; the path tracer gives each beam its own axis. */
static int add_beam_light(json_ctx *c, scene *s)
{
    const camera *cam = &s->cam;
    const lidar_params *l = &cam->lidar;
    if (s->light_count > 0)
        return jfail(c, "primitives", NULL, "a lidar camera is its own light; light '%s' would light every beam "
                     "with no time of emission the lidar knows (ambient light is not modelled): remove it",
                     s->lights[0].name);
    emitter L = {.ops = emitter_ops_find("collimated"), .medium = cam->medium, .pulse = l->pulse, .surface = -1,
                 .value = v3s(l->power), .cos_div = cos(0.5 * l->beam_divergence)};
    snprintf(L.name, sizeof L.name, "lidar beam");
    snprintf(L.type_name, sizeof L.type_name, "collimated");
    vec3 left = v3_neg(cam->right);
    L.pos = v3_add(cam->pos, v3_add(v3_scale(cam->right, l->offset.x),
                                    v3_add(v3_scale(cam->up, l->offset.y), v3_scale(cam->forward, l->offset.z))));
    lidar_beam_set(&L, lidar_beam_dir(l, cam->forward, left, cam->up, 0, 0));
    if (emitter_prepare(s, &L)) return jfail(c, "camera", NULL, "out of memory");
    s->lights = calloc(1, sizeof *s->lights);
    if (!s->lights) return jfail(c, "camera", NULL, "out of memory");
    s->lights[0] = L;
    s->light_count = 1;
    return 0;
}

int lidar_finish_scene(json_ctx *c, const cJSON *root, scene *s, int derivatives)
{
    if (s->cam.type != CAMERA_LIDAR) return 0;
    if (refuse_integrator_keys(c, root, s, derivatives) || add_beam_light(c, s)) return -1;
    const lidar_params *l = &s->cam.lidar;
    time_window *tw = &s->integrator.window;
    tw->gated = 1;
    tw->frame_count = l->bins;
    tw->start = 0.0;
    tw->width = 2.0 * l->range_bin;
    return 0;
}
