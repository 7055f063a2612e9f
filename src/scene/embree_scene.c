/* Ray queries through Embree 3: one triangle geometry per surface (geomID = surface index), robust
 * (watertight) traversal, hit points from barycentrics, self-intersection avoided by offsetting origins.
 * Shading normals and UVs come from the scene_rt corner arrays; `backface_culling` surfaces get an Embree
 * intersection filter that drops hits on their back (d·ng > 0), so other surfaces pay nothing. */
#include "scene_internal.h"

#include <embree3/rtcore.h>
#include <stdlib.h>
#include <string.h>

static void embree_error(void *user, enum RTCError code, const char *str)
{
    (void)user;
    (void)code;
    (void)str; /* reported through rtcGetDeviceError where it matters */
}

/* Embree's Ng is (p1 - p0) x (p2 - p0) for our triangles (counter-clockwise front), the same as hit.ng.
 * RTCRayN and RTCHitN are arrays of N-wide float columns (rtcore_ray.h: dir at columns 4-6 of the ray, Ng
 * at columns 0-2 of the hit); the accessor functions there are C++ only. */
static void cull_back_faces(const struct RTCFilterFunctionNArguments *args)
{
    const float *ray = (const float *)args->ray, *hit = (const float *)args->hit;
    unsigned n = args->N;
    for (unsigned i = 0; i < n; i++) {
        if (args->valid[i] != -1) continue;
        float d = ray[4 * n + i] * hit[i] + ray[5 * n + i] * hit[n + i] + ray[6 * n + i] * hit[2 * n + i];
        if (d > 0.0f) args->valid[i] = 0;
    }
}

int scene_build_embree(scene *s, dp_error *err)
{
    scene_rt *rt = scene_rt_get(s);
    if (!rt) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", s->path);
    s->ray_offset_scale = 0.0f;
    for (size_t i = 0; i < 3 * (size_t)s->vert_count; i++) s->ray_offset_scale = fmaxf(s->ray_offset_scale, fabsf(s->verts[i]));
    if (!(s->ray_offset_scale > 0.0f)) s->ray_offset_scale = 1.0f;
    RTCDevice dev = rtcNewDevice("threads=0");
    if (!dev) return dp_fail(err, "%s: cannot create the Embree device (error %d)", s->path, (int)rtcGetDeviceError(NULL));
    rtcSetDeviceErrorFunction(dev, embree_error, NULL);
    RTCScene sc = rtcNewScene(dev);
    rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
    for (int i = 0; i < s->surface_count; i++) {
        const surface *sf = &s->surfaces[i];
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                            3 * (size_t)sf->tri_count);
        unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                               sf->tri_count);
        if (!vb || !ib) {
            rtcReleaseGeometry(g);
            rtcReleaseScene(sc);
            rtcReleaseDevice(dev);
            return dp_fail_kind(err, DP_ERROR_MEMORY,
                                "%s: Embree could not allocate the geometry of '%s'", s->path, sf->name);
        }
        /* unshared vertices: each triangle's corners copied, so local index = 3·tri + corner */
        for (uint32_t t = 0; t < sf->tri_count; t++) {
            const uint32_t *tri = &s->tris[3 * (size_t)(sf->first_tri + t)];
            for (int k = 0; k < 3; k++) {
                memcpy(&vb[9 * (size_t)t + 3 * k], &s->verts[3 * (size_t)tri[k]], 3 * sizeof(float));
                ib[3 * (size_t)t + k] = 3 * t + (unsigned)k;
            }
        }
        if (i < rt->flag_cap && (rt->flags[i] & SURF_CULL)) {
            rtcSetGeometryIntersectFilterFunction(g, cull_back_faces);
            rtcSetGeometryOccludedFilterFunction(g, cull_back_faces);
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(sc, g, (unsigned)i);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(sc);
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        rtcReleaseScene(sc);
        rtcReleaseDevice(dev);
        return dp_fail(err, "%s: Embree failed to build the scene", s->path);
    }
    s->rt_device = dev;
    rt->rtc = sc;
    return 0;
}

void scene_release_embree(scene *s)
{
    scene_rt *rt = s->rt_scene;
    if (rt) {
        if (rt->rtc) rtcReleaseScene((RTCScene)rt->rtc);
        free(rt->corner_n);
        free(rt->corner_uv);
        free(rt->flags);
        free(rt);
    }
    if (s->rt_device) rtcReleaseDevice((RTCDevice)s->rt_device);
    s->rt_scene = s->rt_device = NULL;
}

static vec3 vert(const scene *s, uint32_t i)
{
    const float *p = &s->verts[3 * (size_t)i];
    return v3(p[0], p[1], p[2]);
}

int scene_intersect(const scene *s, vec3 o, vec3 d, double tmax, hit_record *h)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    rh.ray.org_x = (float)o.x;
    rh.ray.org_y = (float)o.y;
    rh.ray.org_z = (float)o.z;
    rh.ray.dir_x = (float)d.x;
    rh.ray.dir_y = (float)d.y;
    rh.ray.dir_z = (float)d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = tmax > 3e38 ? INFINITY : (float)tmax;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.ray.time = 0.0f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    const scene_rt *rt = s->rt_scene;
    rtcIntersect1((RTCScene)rt->rtc, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    const surface *sf = &s->surfaces[rh.hit.geomID];
    uint32_t t = sf->first_tri + rh.hit.primID;
    const uint32_t *tri = &s->tris[3 * (size_t)t];
    vec3 p0 = vert(s, tri[0]), p1 = vert(s, tri[1]), p2 = vert(s, tri[2]);
    double u = rh.hit.u, v = rh.hit.v, w = 1.0 - u - v;
    h->t = rh.ray.tfar;
    h->p = v3_add(v3_scale(p0, w), v3_add(v3_scale(p1, u), v3_scale(p2, v)));
    h->ng = v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
    h->ns = h->ng;
    h->uv[0] = h->uv[1] = 0.0;
    h->tri = t;
    h->surface = (int)rh.hit.geomID;
    unsigned flags = (int)rh.hit.geomID < rt->flag_cap ? rt->flags[rh.hit.geomID] : 0u;
    if (flags & SURF_SMOOTH) {
        const float *c = &rt->corner_n[9 * (size_t)t];
        vec3 n = v3(w * c[0] + u * c[3] + v * c[6], w * c[1] + u * c[4] + v * c[7], w * c[2] + u * c[5] + v * c[8]);
        double l = v3_len(n);
        if (l > 1e-12) { /* a zero normal (absent, or opposite corners cancelling) leaves ng */
            n = v3_scale(n, 1.0 / l);
            h->ns = v3_dot(n, h->ng) < 0.0 ? v3_neg(n) : n;
        }
    }
    if (flags & SURF_UV) {
        const float *c = &rt->corner_uv[6 * (size_t)t];
        h->uv[0] = w * c[0] + u * c[2] + v * c[4];
        h->uv[1] = w * c[1] + u * c[3] + v * c[5];
    }
    return 1;
}

/* Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray Tracing Gems, ch. 6):
 * move the float position by a few ulps along n, or, near the origin where ulps are tinier than the
 * intersection error (which follows the size of the scene's coordinates), by a fixed amount. Their
 * constants 1/32 and 1/65536 suit coordinates of order 1; here they are multiplied by the scene's largest
 * coordinate, so that scaling a scene scales its offsets too. */
static float offset_component(float p, double n, float scale)
{
    const float origin = scale / 32.0f, float_scale = scale / 65536.0f, int_scale = 256.0f;
    if (fabsf(p) < origin) return p + float_scale * (float)n;
    int32_t of = (int32_t)(int_scale * n), bits;
    memcpy(&bits, &p, 4);
    bits += (p < 0) ? -of : of;
    float r;
    memcpy(&r, &bits, 4);
    return r;
}

vec3 scene_offset_ray_origin(const scene *s, vec3 p, vec3 n)
{
    float k = s->ray_offset_scale > 0.0f ? s->ray_offset_scale : 1.0f;
    return v3(offset_component((float)p.x, n.x, k), offset_component((float)p.y, n.y, k),
              offset_component((float)p.z, n.z, k));
}

int scene_transmittance(const scene *s, vec3 p, int med, vec3 q, vec3 *tr, double *time)
{
    int end;
    return scene_transmittance_region(s, p, med, q, tr, time, &end);
}

int scene_transmittance_region(const scene *s, vec3 p, int med, vec3 q, vec3 *tr, double *time, int *end)
{
    return scene_transmittance_segments(s, p, med, q, tr, time, end, NULL, NULL);
}

int scene_transmittance_segments(const scene *s, vec3 p, int med, vec3 q, vec3 *tr, double *time, int *end,
                                 scene_segment_fn on_segment, void *ctx)
{
    *end = med;
    *tr = v3s(1.0);
    for (int crossing = 0; crossing < 256; crossing++) {
        vec3 dq = v3_sub(q, p);
        double dist = v3_len(dq);
        if (dist <= 0.0) return 1;
        vec3 d = v3_scale(dq, 1.0 / dist);
        hit_record h;
        int hit = scene_intersect(s, p, d, dist * (1.0 - 1e-7), &h);
        double seg = hit ? h.t : dist;
        if (med != MEDIUM_VACUUM) *tr = v3_mul(*tr, v3_exp_neg(v3_scale(s->media[med].sigma_t, seg)));
        *time += medium_eta(s, med) * seg;
        if (on_segment) on_segment(ctx, med, seg);
        if (!hit) return 1;
        const surface *sf = &s->surfaces[h.surface];
        if (!bsdf_is_passthrough(&s->bsdfs[sf->bsdf])) break;
        med = surface_next_medium(sf, med, d, h.ng);
        *end = med;
        p = scene_offset_ray_origin(s, h.p, v3_dot(d, h.ng) > 0 ? h.ng : v3_neg(h.ng));
    }
    *tr = v3s(0.0);
    return 0;
}
