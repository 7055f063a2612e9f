/* BSDF objects of the scene file (docs/scene-format.md §2.4): the type by its scene name, the defaults of
 * that type (bsdf_defaults), then the keys as Tungsten's Bsdf subclasses read them, then bsdf_prepare.
 * `albedo` is a number, [r, g, b] or a texture file (texture.c). A conductor's `material` names a complex
 * index and wins over `eta`/`k`, as in Tungsten's ConductorBsdf::fromJson. */
#include "scene_internal.h"

#include <stdio.h>
#include <string.h>

static void supported_types(char *out, size_t n)
{
    out[0] = 0;
    for (int t = 0; t < BSDF_TYPE_COUNT; t++) {
        size_t len = strlen(out);
        snprintf(out + len, n - len, "%s%s", t ? ", " : "", bsdf_type_name((bsdf_type)t));
    }
}

static int parse_distribution(json_ctx *c, const cJSON *v, const char *where, bsdf *b)
{
    const char *name = NULL;
    int rc = jget_string(c, v, where, "distribution", &name);
    if (rc <= 0) return rc;
    if (!strcmp(name, "ggx")) b->distribution = MICROFACET_GGX;
    else if (!strcmp(name, "beckmann")) b->distribution = MICROFACET_BECKMANN;
    else if (!strcmp(name, "pbrt-ggx")) b->distribution = MICROFACET_PBRT_GGX;
    else return jfail(c, where, "distribution", "unsupported distribution '%s' (supported: ggx, beckmann, pbrt-ggx)", name);
    return 0;
}

static int parse_albedo(json_ctx *c, const cJSON *v, const char *where, scene *s, bsdf *b)
{
    const cJSON *a = jget_item(c, v, "albedo");
    b->texture = -1;
    if (cJSON_IsString(a)) {
        /* the constant albedo: 0.5 for a missing file (the average of Tungsten's stand-in checkerboard),
         * else the texture's mean, for any code that does not look textures up */
        b->albedo = v3s(0.5);
        if (texture_fetch(c, s, where, "albedo", a->valuestring, &b->texture)) return -1;
        if (b->texture >= 0) b->albedo = texture_mean(&s->textures[b->texture]);
        return 0;
    }
    if (cJSON_IsObject(a)) return jfail(c, where, "albedo", "texture objects are not supported (give the file name)");
    if (jget_vec3(c, v, where, "albedo", b->albedo, &b->albedo)) return -1;
    if (b->albedo.x < 0 || b->albedo.y < 0 || b->albedo.z < 0) return jfail(c, where, "albedo", "must be >= 0");
    if (b->albedo.x > 1 || b->albedo.y > 1 || b->albedo.z > 1)
        jwarn(c, "%s.albedo: bsdf '%s' has albedo (%g, %g, %g), above 1 in a channel: it reflects more light than "
                 "it receives, so the render gains energy (an albedo is a fraction, 0 to 1)", where, b->name,
              b->albedo.x, b->albedo.y, b->albedo.z);
    return 0;
}

/* material, or eta and k */
static int parse_conductor(json_ctx *c, const cJSON *v, const char *where, bsdf *b)
{
    const char *material = NULL;
    if (jget_vec3(c, v, where, "eta", b->eta, &b->eta) || jget_vec3(c, v, where, "k", b->k, &b->k)) return -1;
    int rc = jget_string(c, v, where, "material", &material);
    if (rc < 0) return -1;
    if (rc > 0 && !bsdf_conductor_preset(material, &b->eta, &b->k))
        return jfail(c, where, "material", "unknown material '%s' (see src/bsdf/complex_ior.c for the names)", material);
    return 0;
}

int bsdf_parse(json_ctx *c, const cJSON *v, const char *where, scene *s, bsdf *b)
{
    if (!cJSON_IsObject(v)) return jfail(c, where, NULL, "expected a BSDF object");
    size_t mark = jread_mark(c);
    const char *type = "lambert", *name = "";
    if (jget_string(c, v, where, "type", &type) < 0 || jget_string(c, v, where, "name", &name) < 0) return -1;
    int t = bsdf_type_from_name(type);
    if (t < 0) {
        char list[512];
        supported_types(list, sizeof list);
        return jfail(c, where, "type", "unsupported BSDF '%s' (supported: %s)", type, list);
    }
    bsdf_defaults(b, (bsdf_type)t);
    snprintf(b->name, sizeof b->name, "%s", name[0] ? name : where);
    const cJSON *rough = jget_item(c, v, "roughness");
    if (rough && !cJSON_IsNumber(rough))
        return jfail(c, where, "roughness", "expected a number (roughness textures are not supported)");
    if (parse_albedo(c, v, where, s, b) || parse_distribution(c, v, where, b) ||
        jget_number(c, v, where, "roughness", b->roughness, &b->roughness) || parse_conductor(c, v, where, b) ||
        jget_number(c, v, where, "ior", b->ior, &b->ior) ||
        jget_bool(c, v, where, "enable_refraction", b->enable_refraction, &b->enable_refraction) ||
        jget_number(c, v, where, "thickness", b->thickness, &b->thickness) ||
        jget_vec3(c, v, where, "sigma_a", b->sigma_a, &b->sigma_a) || jget_number(c, v, where, "Ks", b->ks, &b->ks))
        return -1;
    dp_error perr;
    memset(&perr, 0, sizeof perr);
    if (bsdf_prepare(b, &perr)) return jfail(c, where, NULL, "%s", perr.msg);
    jnote_unread_keys(c, v, where, mark);
    return 0;
}
