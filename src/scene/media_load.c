/* The media of a scene file (docs/scene-format.md §2): the `media` array, their phase functions and EDA keys,
 * and medium references by name, null or inline object (surfaces, the camera and lights use them). */
#include "scene_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int find_medium(const scene *s, const char *name)
{
    for (int i = 0; i < s->medium_count; i++)
        if (!strcmp(s->media[i].name, name)) return i;
    return -2;
}

/* A tabulated phase function's file, relative to the scene file's folder (phase_table.c). */
static int load_phase_table(json_ctx *c, const cJSON *v, const char *w, const char *dir, const char *medium_name,
                            phase_function *pf)
{
    const char *file = NULL;
    int has = jget_string(c, v, w, "file", &file);
    if (has < 0) return -1;
    if (has == 0 || !file[0])
        return jfail(c, w, "file", "medium '%s': a tabulated phase function needs its table: \"file\": \"x.csv\" "
                     "(rows theta_deg,value; docs/scene-format.md §2.3)", medium_name);
    if (jget_item(c, v, "g"))
        return jfail(c, w, "g", "medium '%s': a tabulated phase function reads no g (its mean cosine comes from the "
                     "table); remove g", medium_name);
    char path[2100];
    snprintf(path, sizeof path, "%s%s%s", file[0] == '/' ? "" : dir, file[0] == '/' ? "" : "/", file);
    pf->table = calloc(1, sizeof *pf->table);
    if (!pf->table) return jfail(c, w, "file", "out of memory");
    dp_error e;
    if (phase_table_load(pf->table, path, &e)) {
        free(pf->table);
        pf->table = NULL;
        return jfail(c, w, "file", "medium '%s': %s", medium_name, e.msg);
    }
    pf->g = pf->table->g;
    return 0;
}

static int parse_phase(json_ctx *c, const cJSON *v, const char *where, const char *dir, const char *medium_name,
                       phase_function *pf)
{
    pf->type = PHASE_ISOTROPIC;
    pf->g = 0.0;
    pf->table = NULL;
    if (!v) return 0;
    if (!cJSON_IsObject(v)) return jfail(c, where, "phase_function", "expected an object");
    char w[256];
    snprintf(w, sizeof w, "%s.phase_function", where);
    const char *type = "isotropic";
    if (jget_string(c, v, w, "type", &type) < 0) return -1;
    if (!strcmp(type, "isotropic")) pf->type = PHASE_ISOTROPIC;
    else if (!strcmp(type, "henyey_greenstein")) pf->type = PHASE_HENYEY_GREENSTEIN;
    else if (!strcmp(type, "ida")) pf->type = PHASE_IDA;
    else if (!strcmp(type, "tabulated")) pf->type = PHASE_TABULATED;
    else return jfail(c, w, "type", "unsupported phase function '%s' (supported: isotropic, henyey_greenstein, ida, tabulated)", type);
    if (pf->type == PHASE_TABULATED) return load_phase_table(c, v, w, dir, medium_name, pf);
    if (pf->type != PHASE_ISOTROPIC && jget_number_range(c, v, w, "g", 0.0, -0.999, 0.999, &pf->g)) return -1;
    return 0;
}

/* The extinction a meteorological visibility V gives (docs/lidar.md §6): σt = −ln(ε)/V for the contrast threshold
 * ε of the convention, 5 % for the meteorological optical range (WMO; σt = ln 20/V ≈ 2.996/V), 2 % for Koschmieder's
 * original (σt = ln 50/V ≈ 3.912/V). */
double medium_visibility_extinction(double visibility, int koschmieder)
{
    return (koschmieder ? log(50.0) : log(20.0)) / visibility;
}

/* σs and σa from `visibility`, `visibility_convention` and `albedo`, instead of sigma_s, sigma_a and density. */
static int parse_visibility(json_ctx *c, const cJSON *v, const char *w, medium *m)
{
    const char *clash[3] = {"sigma_s", "sigma_a", "density"};
    for (int k = 0; k < 3; k++)
        if (jget_item(c, v, clash[k]))
            return jfail(c, w, clash[k], "medium '%s' gives both visibility and %s: visibility sets the extinction "
                         "(with albedo its split into scattering and absorption); give visibility or %s, not both",
                         m->name, clash[k], k == 2 ? "density" : "sigma_s and sigma_a");
    const cJSON *vv = jget_item(c, v, "visibility");
    if (!cJSON_IsNumber(vv) || !isfinite(vv->valuedouble) || !(vv->valuedouble > 0.0))
        return jfail(c, w, "visibility", "medium '%s': the visibility must be a finite number > 0 (metres, the scene's "
                     "unit)%s", m->name, cJSON_IsNumber(vv) ? "" : "; got no number");
    const char *conv = "mor";
    double albedo;
    if (jget_string(c, v, w, "visibility_convention", &conv) < 0 ||
        jget_number_range(c, v, w, "albedo", 1.0, 0.0, 1.0, &albedo))
        return -1;
    int kosch;
    if (!strcmp(conv, "mor")) kosch = 0;
    else if (!strcmp(conv, "koschmieder")) kosch = 1;
    else return jfail(c, w, "visibility_convention", "medium '%s': unsupported convention '%s' (supported: mor, the "
                      "meteorological optical range, 5 %% contrast, sigma_t = ln(20)/visibility; koschmieder, 2 %% "
                      "contrast, sigma_t = ln(50)/visibility)", m->name, conv);
    double st = medium_visibility_extinction(vv->valuedouble, kosch);
    m->sigma_s = v3s(albedo * st);
    m->sigma_a = v3s((1.0 - albedo) * st);
    return 0;
}

/* The EDA keys of an `ida` phase function (docs/reference-renderer.md §7.2): table_path, alpha, dT_start, dT_end,
 * max_T. */
static int parse_eda_keys(json_ctx *c, const cJSON *pv, const char *where, medium *m)
{
    m->eda = m->phase.type == PHASE_IDA;
    m->eda_alpha = -1.0; /* unset: the integrator's eda_alpha */
    m->eda_r_lo = 0.2;
    m->eda_r_hi = 0.999;
    if (!m->eda) return 0;
    char w[256];
    snprintf(w, sizeof w, "%s.phase_function", where);
    const char *path = "";
    if (jget_string(c, pv, w, "table_path", &path) < 0 || jget_number_range(c, pv, w, "alpha", -1.0, -1.0, -1.0, &m->eda_alpha) ||
        jget_number_range(c, pv, w, "dT_start", 0.2, 0.0, 1.0, &m->eda_r_lo) ||
        jget_number_range(c, pv, w, "dT_end", 0.999, 0.0, 1.0, &m->eda_r_hi) ||
        jget_number_range(c, pv, w, "max_T", 0.0, 0.0, 0, &m->eda_s_max))
        return -1;
    if (m->eda_alpha != -1.0 && !(m->eda_alpha > 0.0)) return jfail(c, w, "alpha", "must be > 0 (got %g)", m->eda_alpha);
    if (!(m->eda_r_lo < m->eda_r_hi && m->eda_r_hi < 1.0))
        return jfail(c, w, "dT_end", "need dT_start < dT_end < 1 (got %g, %g)", m->eda_r_lo, m->eda_r_hi);
    if (strlen(path) >= sizeof m->eda_table_path) return jfail(c, w, "table_path", "path too long");
    if (path[0] && !(m->eda_s_max > 0.0))
        return jfail(c, w, "max_T", "a headerless table (table_path) needs its S range max_T > 0");
    snprintf(m->eda_table_path, sizeof m->eda_table_path, "%s", path);
    return 0;
}

static int parse_medium(json_ctx *c, const scene *s, const cJSON *v, int i, medium *m)
{
    char w[64];
    snprintf(w, sizeof w, "media[%d]", i);
    if (!cJSON_IsObject(v)) return jfail(c, w, NULL, "expected an object");
    size_t mark = jread_mark(c);
    const char *name = "", *type = "homogeneous";
    if (jget_string(c, v, w, "name", &name) < 0 || jget_string(c, v, w, "type", &type) < 0) return -1;
    if (strlen(name) >= sizeof m->name) return jfail(c, w, "name", "longer than %zu characters", sizeof m->name - 1);
    snprintf(m->name, sizeof m->name, "%s", name);
    if (!strcmp(type, "homogeneous")) m->guided = 0;
    else if (!strcmp(type, "guided_homo")) m->guided = 1;
    else return jfail(c, w, "type", "unsupported medium '%s' (supported: homogeneous, guided_homo)", type);
    double density = 1.0, speed;
    long maxb = 1024; /* set by jget_int; initialised for the flow analysis under LTO */
    int by_visibility = jget_item(c, v, "visibility") != NULL;
    if (by_visibility) {
        if (parse_visibility(c, v, w, m)) return -1;
    } else {
        const char *only[2] = {"visibility_convention", "albedo"};
        for (int k = 0; k < 2; k++)
            if (jget_item(c, v, only[k]))
                return jfail(c, w, only[k], "medium '%s': %s is read with visibility only (sigma_s and sigma_a give "
                             "the albedo themselves)", m->name, only[k]);
        if (jget_vec3(c, v, w, "sigma_s", v3s(0), &m->sigma_s) || jget_vec3(c, v, w, "sigma_a", v3s(0), &m->sigma_a) ||
            jget_number_range(c, v, w, "density", 1.0, 0.0, 0.0, &density))
            return -1;
    }
    if (jget_number(c, v, w, "speed_of_light", 1.0, &speed) || jget_int(c, v, w, "max_bounces", 1024, &maxb))
        return -1;
    if (m->sigma_s.x < 0 || m->sigma_s.y < 0 || m->sigma_s.z < 0)
        return jfail(c, w, "sigma_s", "must be >= 0 in every channel");
    if (m->sigma_a.x < 0 || m->sigma_a.y < 0 || m->sigma_a.z < 0)
        return jfail(c, w, "sigma_a", "must be >= 0 in every channel");
    if (!(speed > 0)) return jfail(c, w, "speed_of_light", "must be > 0 (got %g)", speed);
    if (maxb < 0) return jfail(c, w, "max_bounces", "must be >= 0");
    m->sigma_s = v3_scale(m->sigma_s, density);
    m->sigma_a = v3_scale(m->sigma_a, density);
    m->sigma_t = v3_add(m->sigma_s, m->sigma_a);
    if (m->guided && v3_max(m->sigma_s) <= 0)
        return jfail(c, w, by_visibility ? "albedo" : "sigma_s", "guided_homo needs sigma_s > 0");
    m->eta = 1.0 / speed;
    if (!v3_is_finite(m->sigma_t))
        return jfail(c, w, by_visibility ? "visibility" : "sigma_s",
                     by_visibility ? "too small: the extinction overflows" : "sigma_s + sigma_a times density overflows");
    if (!isfinite(m->eta)) return jfail(c, w, "speed_of_light", "too small (got %g)", speed);
    m->max_bounces = maxb > 1 << 30 ? 1 << 30 : (int)maxb;
    const cJSON *pv = jget_item(c, v, "phase_function");
    size_t phase_mark = jread_mark(c);
    if (parse_phase(c, pv, w, s->dir, m->name, &m->phase)) return -1;
    if (parse_eda_keys(c, pv, w, m)) {
        medium_free_phase(m);
        return -1;
    }
    char pw[256];
    snprintf(pw, sizeof pw, "%s.phase_function", w);
    jnote_unread_keys(c, pv, pw, phase_mark);
    jnote_unread_keys(c, v, w, mark);
    return 0;
}

void medium_free_phase(medium *m)
{
    if (m->phase.table) {
        phase_table_free(m->phase.table);
        free(m->phase.table);
        m->phase.table = NULL;
    }
}

int parse_media(json_ctx *c, const cJSON *root, scene *s)
{
    const cJSON *arr = jget_item(c, root, "media");
    if (!arr) return 0;
    if (!cJSON_IsArray(arr)) return jfail(c, "media", NULL, "expected an array");
    s->medium_count = cJSON_GetArraySize(arr);
    s->media = calloc((size_t)s->medium_count + 1, sizeof(medium));
    for (int i = 0; i < s->medium_count; i++) {
        if (parse_medium(c, s, cJSON_GetArrayItem(arr, i), i, &s->media[i])) return -1;
        for (int j = 0; j < i; j++)
            if (s->media[i].name[0] && !strcmp(s->media[i].name, s->media[j].name))
                return jfail(c, "media", NULL, "two media are named '%s'", s->media[i].name);
    }
    return 0;
}

/* A medium reference: a name or an inline object (appended to s->media). */
int medium_ref(json_ctx *c, scene *s, const cJSON *v, const char *where, const char *key, int *out)
{
    if (cJSON_IsNull(v)) {
        *out = MEDIUM_VACUUM;
        return 0;
    }
    if (cJSON_IsString(v)) {
        if (!v->valuestring[0]) {
            *out = MEDIUM_VACUUM;
            return 0;
        }
        int k = find_medium(s, v->valuestring);
        if (k < 0) return jfail(c, where, key, "no medium named '%s' in media[]", v->valuestring);
        *out = k;
        return 0;
    }
    if (cJSON_IsObject(v)) {
        medium *grown = realloc(s->media, ((size_t)s->medium_count + 1) * sizeof(medium));
        if (!grown) return jfail(c, where, key, "out of memory");
        s->media = grown;
        memset(&s->media[s->medium_count], 0, sizeof(medium));
        if (parse_medium(c, s, v, s->medium_count, &s->media[s->medium_count])) return -1;
        *out = s->medium_count++;
        return 0;
    }
    return jfail(c, where, key, "expected a medium name or object");
}

int clear_region(json_ctx *c, scene *s, double speed, const char *where, const char *key, int *out)
{
    char name[64];
    snprintf(name, sizeof name, "(clear, speed_of_light %.9g)", speed);
    int k = find_medium(s, name);
    if (k >= 0) {
        *out = k;
        return 0;
    }
    if (!(1.0 / speed < INFINITY)) return jfail(c, where, key, "too small (got %g)", speed);
    medium *grown = realloc(s->media, ((size_t)s->medium_count + 1) * sizeof(medium));
    if (!grown) return jfail(c, where, key, "out of memory");
    s->media = grown;
    medium *m = &s->media[s->medium_count];
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%s", name);
    m->eta = 1.0 / speed;
    m->max_bounces = 1024;
    m->phase.type = PHASE_ISOTROPIC;
    *out = s->medium_count++;
    return 0;
}
