/* dartspp scene: the Tungsten JSON subset of the paper's scenes (docs/scene-format.md §2), `.wo3` and
 * `.obj` meshes, camera, emitters (include/dartspp/emitter.h), BSDFs, homogeneous media, phase functions, the time window and
 * the Embree 3 scene. A loaded scene is read-only: every later stage takes `const scene *`. */
#ifndef DARTSPP_SCENE_H
#define DARTSPP_SCENE_H

#include "dartspp/bsdf.h"
#include "dartspp/core.h"
#include "dartspp/emitter.h"
#include "dartspp/lidar.h"
#include "dartspp/sensor.h"

/* ---- materials: include/dartspp/bsdf.h; albedo textures ---- */
typedef struct {
    char path[1024];  /* as resolved from the scene file */
    int width, height;
    float *rgb;       /* linear RGB, 3 floats per texel, row 0 = the image's top row */
} texture;

/* ---- media ---- */
typedef enum { PHASE_ISOTROPIC, PHASE_HENYEY_GREENSTEIN, PHASE_IDA, PHASE_TABULATED } phase_type;
/* A tabulated phase function (phase_function type "tabulated", src/scene/phase_table.c): p(θ) piecewise linear in
 * the scattering angle θ between the file's knots, normalised so that 2π ∫₀^π p(θ) sinθ dθ = 1. */
typedef struct phase_table {
    int n;          /* knots, >= 2 */
    double *theta;  /* radians, strictly increasing, theta[0] = 0, theta[n − 1] = π */
    double *p;      /* p(θ_i) per steradian, normalised */
    double *cdf;    /* P(θ < theta[i]); cdf[0] = 0, cdf[n − 1] = 1 */
    double g;       /* ⟨cos θ⟩ of the interpolant */
    char path[1024];/* the file, as resolved from the scene file */
} phase_table;

typedef struct {
    phase_type type;
    double g; /* HG asymmetry; for `ida` the anisotropy the table is built for (0 unless given); for `tabulated`
               * the table's ⟨cos θ⟩, read only by the diffusion models that steer DARTS (DA, EDA) */
    phase_table *table; /* `tabulated` only; owned by the scene (scene_free) */
} phase_function;

/* The phase function is the constant 1/(4π) (isotropic, or HG with g = 0). */
static inline int phase_is_isotropic(const phase_function *pf)
{
    return pf->type == PHASE_ISOTROPIC || (pf->type != PHASE_TABULATED && pf->g == 0.0);
}

/* p(ω_in → ω_out) per steradian; both are propagation directions (Tungsten convention). */
double phase_eval(const phase_function *pf, vec3 w_in, vec3 w_out);
/* Samples ω_out ∝ phase; the weight phase/pdf is exactly 1. */
vec3 phase_sample(const phase_function *pf, vec3 w_in, double u1, double u2);
/* A tabulated phase function from a CSV file of "theta_deg,value" rows (a header line and '#' comment lines
 * allowed; θ strictly increasing from 0 to 180 degrees; values >= 0 and finite, relative): the interpolant linear
 * in θ between the rows, normalised. 0, or -1 with "<path>:<line>: phase function table: <reason>" in err. */
int phase_table_load(phase_table *t, const char *path, dp_error *err);
/* The same from arrays (θ in degrees): for tests and the loader. */
int phase_table_init(phase_table *t, const double *theta_deg, const double *value, int n, const char *name, dp_error *err);
void phase_table_free(phase_table *t);
/* The normalised interpolant at θ (radians, clamped to [0, π]) per steradian. */
double phase_table_eval(const phase_table *t, double theta);
/* θ ~ 2π p(θ) sinθ (u in [0, 1)): the interval by its CDF, then the exact inverse within it (Newton in a bracket). */
double phase_table_sample_theta(const phase_table *t, double u);

/* Free flight from a segment start with the next surface at tmax (may be INFINITY): one colour channel
 * picked uniformly, pdf averaged over channels (one-sample MIS), so coloured media stay unbiased. Returns
 * the distance; *event = 1 for a medium event (distance < tmax). beta is multiplied by Tr·σs/pdf at an
 * event and by Tr/P(pass) otherwise. */
struct medium;
double medium_sample_free_flight(const struct medium *m, double tmax, dp_rng *rng, vec3 *beta, int *event);
/* The same sampler before the next surface is known, for a grey medium (equal σt in every channel):
 * returns t ~ σt e^{−σt t} (INFINITY where σt = 0), drawing what medium_sample_free_flight draws. The caller
 * traces the ray to t: a surface before t is reached with weight 1, else a medium event at t, where beta
 * becomes medium_grey_event_beta(m, beta) (σs/σt). 0 when the medium is not grey (then the caller needs
 * the surface first). */
int medium_free_flight_grey(const struct medium *m, dp_rng *rng, double *t);
vec3 medium_grey_event_beta(const struct medium *m, vec3 beta);

/* σt of a medium given by its meteorological visibility V (medium keys `visibility`, `visibility_convention`;
 * docs/lidar.md §6): ln(20)/V for the meteorological optical range (5 % contrast threshold, WMO), ln(50)/V for
 * Koschmieder's 2 % (koschmieder != 0). */
double medium_visibility_extinction(double visibility, int koschmieder);

#define MEDIUM_VACUUM (-1)
typedef struct medium {
    char name[64];
    int guided;        /* "guided_homo": DARTS samplers allowed */
    vec3 sigma_s;      /* per unit length, density applied */
    vec3 sigma_a;
    vec3 sigma_t;
    double eta;        /* refractive index = vacuum speed / `speed_of_light` (time per length) */
    int max_bounces;   /* medium events since the last surface */
    phase_function phase;
    /* EDA direction sampling (phase "ida", or integrator eda = true on a guided medium) */
    int eda;                   /* on at this medium's vertices when the DARTS pass runs */
    double eda_alpha;          /* γ = (C/S)/(C/S + α); phase key alpha, else integrator eda_alpha */
    double eda_r_lo, eda_r_hi; /* C/S range of the table (phase keys dT_start, dT_end; 0.2, 0.999) */
    double eda_s_max;          /* S range [0, s_max) (phase key max_T); 0: from the time window */
    char eda_table_path[512];  /* the authors' headerless table (phase key table_path); "": our cache */
} medium;

/* ---- geometry ---- */
typedef struct {
    char name[64];
    int bsdf;                     /* index into scene.bsdfs */
    int overrides_media;          /* 0: a crossing keeps the current medium */
    int int_medium, ext_medium;   /* medium index or MEDIUM_VACUUM, used when overrides_media */
    uint32_t first_tri, tri_count;
    int emitter;                  /* index into scene.lights of the area light it is, or -1 */
    int smooth;                   /* `smooth` (and spheres): interpolated vertex normals shade it */
} surface;

/* medium on the far side of `s` for a ray leaving the hit point in direction d (Tungsten selectMedium) */
static inline int surface_next_medium(const surface *s, int current, vec3 d, vec3 ng)
{
    if (!s->overrides_media) return current;
    return v3_dot(d, ng) < 0.0 ? s->int_medium : s->ext_medium;
}

typedef enum { CAMERA_PINHOLE, CAMERA_ORTHOGRAPHIC, CAMERA_LIDAR } camera_type;

typedef struct {
    int width, height;
    int type;               /* camera_type */
    double fov_deg;         /* pinhole: horizontal */
    vec3 pos;
    vec3 right, up, forward; /* world axes of the image plane: +right = screen right, +up = screen up */
    double plane_dist;      /* pinhole: 1 / tan(fov/2): image plane spans x in [-1,1] */
    double ortho_size;      /* orthographic (Tungsten's orthographic_size): half the film's height in scene units;
                             * the film is 2·ortho_size·width/height × 2·ortho_size, centred on pos, in the plane
                             * through pos perpendicular to forward (the camera's plane) */
    int medium;
    sensor_response response; /* its time response, from the integrator's sensor_* keys (sensor.h) */
    lidar_params lidar;     /* lidar (include/dartspp/lidar.h): width = azimuth_steps, height = channels; the
                             * receiver at pos, the transmitter at pos + offset; lights[0] is its beam's template */
} camera;

/* The camera ray through the image-plane point (px, py) in pixel units: pixel (x, y) covers [x, x+1) × [y, y+1),
 * row 0 at the top; px = x + u with u uniform in [0,1) is the box filter. Pinhole: every ray starts at pos, its
 * direction through Tungsten's image plane at distance plane_dist. Orthographic (Tungsten's
 * OrthographicCamera): the rays are parallel to forward and start on the camera's plane, at the film point of
 * (px, py). Sets *o and returns the unit direction. */
vec3 camera_ray(const camera *c, double px, double py, vec3 *o);
/* The axis of a lidar's beam at pixel (x, y) (docs/lidar.md §1). */
vec3 camera_lidar_beam(const camera *c, int x, int y);
/* Its direction alone (the same for every pixel of an orthographic camera). */
vec3 camera_ray_dir(const camera *c, double px, double py);
/* The least distance light at p travels to reach the sensor: to pos (pinhole), to the camera's plane
 * (orthographic: a lower bound, the film being part of that plane). */
double camera_distance(const camera *c, vec3 p);
/* The side of one pixel on an orthographic camera's film, in scene units (2·ortho_size / height). */
static inline double camera_ortho_pixel(const camera *c) { return 2.0 * c->ortho_size / c->height; }

/* ---- time ---- */
#define AMCW_FREQ_MAX 4 /* modulation frequencies of the AMCW output (docs/amcw.md) */
typedef struct {
    int gated;        /* 0: steady state, no time weighting (transient_time_width == 0, no frames) */
    int frame_count;  /* 0: one gate image; N >= 1: frames [start + k w, start + (k+1) w) */
    double start;     /* window start */
    double width;     /* gate width, or frame width */
    int camera_unwarp; /* integrator key camera_unwarp: a path's time leaves out the camera segment adjacent to the
                        * sensor (docs/time.md §2.2); 0: camera-warped (the default) */
    int orders;        /* integrator key bounce_orders K: K + 1 more layers of the gate image or of every frame, the
                        * paths of 0, 1, ..., K − 1 and of K or more scattering events (docs/time.md §7); 0: none */
    int delta;         /* delta_time_gate: the gate is a Dirac delta at `center` (docs/time.md §3.1); start and width
                        * hold the box of the first iteration, [center − w₀/2, center + w₀/2), and a film holds the box
                        * of its pass in progress (film_set_pass_gate); never with frames */
    double center;     /* the delta gate's instant (transient_time_center); 0 without a delta gate */
    int amcw_count;    /* renderer key amcw_frequencies: 0 (none), or 1 to AMCW_FREQ_MAX modulation frequencies whose
                        * correlation the film accumulates per contribution (docs/amcw.md) */
    double amcw_mhz[AMCW_FREQ_MAX]; /* those frequencies in MHz, the scene unit taken as the metre */
} time_window;

/* The film's float layers: the frames, then per order the frames (the gate image when there are none). */
static inline int time_window_layers(const time_window *tw)
{
    return tw->frame_count + tw->orders * (tw->frame_count > 0 ? tw->frame_count : 1);
}

static inline double time_window_end(const time_window *tw)
{
    return tw->start + tw->width * (tw->frame_count > 0 ? tw->frame_count : 1);
}

/* The bounds an image's header gives: [start, end) of a box gate; a delta gate's instant twice. */
static inline void time_window_bounds(const time_window *tw, double *start, double *end)
{
    *start = tw->delta ? tw->center : tw->start;
    *end = tw->delta ? tw->center : time_window_end(tw);
}

/* ---- settings ----
 * The integrator and renderer keys are declared once, in the key table (src/scene/keys.c): name, JSON type,
 * default, range or choices, the integrators that read it, whether it changes the image and its meaning.
 * Parsing, validation, `--set`, the unknown/unread-key notes, the plan's JSON and `dartspp keys` all iterate
 * that table; the resolved values land in the structs below, which the plan reads. */
typedef enum { INTEGRATOR_PATH_TRACER, INTEGRATOR_PHOTON_POINTS, INTEGRATOR_COUNT } integrator_type;
/* The other choice keys, in the order of their choices in the key table. */
typedef enum { LIGHT_SELECTION_POWER, LIGHT_SELECTION_UNIFORM } light_selection_choice;
typedef enum { TIME_SAMPLING_NONE, TIME_SAMPLING_UNIFORM } time_sampling_choice;
/* points, beams (src/photon_beams), then Liu et al. 2022's sliced primitives (src/sliced_primitives; the key
 * table's choices in this order) */
typedef enum {
    VOLUME_PHOTON_POINTS,
    VOLUME_PHOTON_BEAMS,
    VOLUME_PHOTON_BALLS,
    VOLUME_PHOTON_VOLUMES,
    VOLUME_PHOTON_HYPERVOLUMES,
    VOLUME_PHOTON_VOLUMES_BALLS,
    VOLUME_PHOTON_MIS_VOLUMES_BALLS,
    VOLUME_PHOTON_PLANES,
    VOLUME_PHOTON_PLANES_1D,
} volume_photon_type_choice;
/* Whether a volume photon type is one of the sliced primitives (which also keep beams for their fallback). */
static inline int volume_type_sliced(int t) { return t >= VOLUME_PHOTON_BALLS; }
typedef enum { CAMERA_LEG_EUCLIDEAN, CAMERA_LEG_PROJECTED } camera_leg_choice;
typedef enum { VOLUME_GATHER_SPLAT, VOLUME_GATHER_BEAM } volume_gather_choice;
typedef enum { RADIUS_SCHEDULE_2D, RADIUS_SCHEDULE_3D } radius_schedule_choice;
typedef enum { PASS_WEIGHTS_KERNEL_AREA, PASS_WEIGHTS_EQUAL } pass_weights_choice;
typedef enum { SURFACE_PATHS_AUTO, SURFACE_PATHS_ALL } surface_paths_choice;
typedef enum { DARTS_MIRRORS_FULL, DARTS_MIRRORS_STRAIGHT } darts_mirrors_choice;

typedef struct {
    /* Every field is named as its key; choice keys hold the index of their choice in the key table (the
     * enums above) */
    int type;                       /* type: integrator_type */
    char type_name[64];             /* the chosen type's name */
    long min_bounces, max_bounces;  /* path segments incl. the light connection (docs/design.md §5.1) */
    /* the time keys as written, and the window they resolve to */
    double transient_time_center, transient_time_width, start_time;
    long frame_num, bounce_orders;
    int delta_time_gate, camera_unwarp;
    time_window window;
    double sensor_jitter_fwhm, sensor_jitter_tail; /* the sensor's time response (sensor.h) */
    char sensor_response_file[512];
    double vaccum_speed_of_light;   /* the format's spelling */
    double vacuum_eta;              /* 1 / vaccum_speed_of_light */
    int light_selection;            /* light_selection_choice: by flux or uniform */
    int enable_rr;                  /* path tracer: Russian roulette on throughput */
    int time_sampling;              /* path tracer: time_sampling_choice (uniform: Jarabo et al. 2014) */
    double time_angular_share;      /* path tracer, uniform time: share of time-angular directions */
    int ellipse_directions;         /* DARTS path tracer: directions toward the next control vertex (docs/darts.md §14.3) */
    double ellipse_direction_share; /* and their share in the MIS */
    int ellipse_surface_directions; /* and at surface vertices too (docs/darts.md §14.4) */
    /* photon points */
    double photon_count, volume_photon_count;
    long gather_photon_count;
    double gather_radius, volume_gather_radius, alpha, volume_alpha;
    int fixed_volume_radius, include_surfaces, low_order_scattering;
    int enable_guiding, enable_elliptical, strict_time_width;
    int volume_photon_type;         /* volume_photon_type_choice */
    int camera_leg;                 /* camera_leg_choice */
    int volume_gather;              /* volume_gather_choice */
    int radius_schedule;            /* radius_schedule_choice */
    int pass_weights;               /* pass_weights_choice */
    int eda;
    double eda_alpha;
    char eda_table_dir[512];
    int eda_shape[3];               /* [C/S rows, S columns, cos bins] */
    double da_defensive;
    int darts_mirrors;              /* darts_mirrors_choice */
    double mirror_defensive;
    int surface_chains;
    int surface_direct_connections;
    int surface_paths;              /* surface_paths_choice */
    int early_exit;
    int control_vertex_mis;
    int camera_control_vertices;
    int ellipse_residual;           /* residual_sampling (darts.h): uniform or exponential */
    int enable_two_sided_shading;
    int enable_consistency_checks;
    double glossy_gather_alpha;
    double glossy_regularization;
} integrator_settings;

/* A key's list of 0 to KEY_LIST_MAX numbers (KEY_NUMBER_LIST). */
#define KEY_LIST_MAX AMCW_FREQ_MAX
typedef struct {
    int count;
    double v[KEY_LIST_MAX];
} key_number_list;

typedef struct {
    long spp;                /* progressive passes; 0 = no limit */
    double timeout;  /* seconds; 0 = no limit */
    char timeout_negative[32]; /* a negative timeout as written ("-1", "-5s"): no limit, with a warning; else "" */
    double checkpoint_interval; /* seconds */
    char output_file[1024];  /* LDR preview as written in the scene (not written by dartspp) */
    char hdr_output_file[1024];
    int ground_truth;        /* also write depth, first arrival, normal and albedo images (docs/sensor.md §3) */
    key_number_list amcw_frequencies; /* MHz; count 0: no AMCW output (docs/amcw.md) */
} renderer_settings;

/* One key of the table. */
typedef enum { KEY_SECTION_INTEGRATOR, KEY_SECTION_RENDERER } scene_key_section;
typedef enum {
    KEY_BOOL,     /* int 0/1; also 0/1 and "true"/"false" as the format's files write them */
    KEY_INT,      /* long; an integral number */
    KEY_NUMBER,   /* double; finite */
    KEY_CHOICE,   /* int: index into choices */
    KEY_STRING,   /* char[size] */
    KEY_DURATION, /* double seconds; a bare number means minutes, suffixes ms, s, m, h, d; negative: no limit (0) */
    KEY_SHAPE3,   /* int[3], integers in [lo, hi] (the last at least lo + 1) */
    KEY_NUMBER_LIST, /* key_number_list: [] or 1 to KEY_LIST_MAX distinct numbers, each in the range (a bare number: a
                      * list of one) */
    KEY_ANY       /* accepted as the format writes it and not read (no field) */
} scene_key_type;

enum { KEY_LO = 1, KEY_HI = 2, KEY_LO_OPEN = 4 }; /* lo <= v (lo < v with KEY_LO_OPEN); v <= hi */
#define KEY_READ_BY(t) (1u << (t))
#define KEY_READ_BY_ALL ((1u << INTEGRATOR_COUNT) - 1u)

typedef struct {
    const char *name;
    scene_key_section section;
    scene_key_type type;
    unsigned read_by;            /* KEY_READ_BY bits of the integrators that read it; 0: accepted, never read */
    int changes_image;           /* its value changes the pixels at a fixed seed (it is then in the plan's JSON) */
    double def;                  /* default of bool/int/number/choice keys (choice: index) */
    const char *def_from;        /* default: the value of this earlier key instead (NULL: def) */
    const char *def_text;        /* default of string, duration and shape keys, as documented */
    double lo, hi;               /* range of numbers and integers, as bounds says */
    unsigned bounds;             /* KEY_LO | KEY_HI | KEY_LO_OPEN */
    int integral;                /* KEY_NUMBER: a whole number (a count that files write as 1000000.0) */
    const char *const *choices;  /* KEY_CHOICE: NULL-terminated */
    size_t offset, size;         /* the resolved value in integrator_settings or renderer_settings */
    const char *meaning;
} scene_key;

/* The table, in the order the keys are documented; *count gets its length. */
const scene_key *scene_keys(int *count);
/* The key called name in either section, or NULL. */
const scene_key *scene_key_find(const char *name);
/* "integrator" or "renderer": the scene file's object that holds the section's keys. */
const char *scene_key_section_name(scene_key_section s);
/* The choice names of integrator_type (the table's `type` key). */
const char *integrator_type_name(integrator_type t);
/* The table's columns as text (`dartspp keys`, docs/keys.md): "number", "0.3" or "= alpha", "[0, 1]" or the
 * choices, "all" or the integrators that read the key ("none": accepted, never read). */
const char *scene_key_type_name(scene_key_type t);
void scene_key_default_text(const scene_key *k, char *out, size_t n);
void scene_key_range_text(const scene_key *k, char *out, size_t n);
void scene_key_readers_text(const scene_key *k, char *out, size_t n);
/* Whether integrator type t reads the key. */
static inline int scene_key_read_by(const scene_key *k, int t)
{
    return (k->read_by & KEY_READ_BY(t)) != 0;
}

/* ---- derivatives (docs/derivatives.md; Yi et al. 2021) ----
 * A parameter θ a render differentiates (`--derivative POINTER`, the Python API's derivatives=[...]): a JSON
 * Pointer (RFC 6901) into the scene file, resolved when the scene loads (src/scene/diff_params.c) to what θ
 * moves, as the derivative of the scene's internal values with respect to it. The derivative images are
 * ∂I/∂θ in the units of the value the pointer names. */
#define DIFF_PARAM_MAX 8
typedef enum {
    DIFF_MEDIUM,      /* index: a medium, or MEDIUM_VACUUM (its speed of light only): dsigma_s, dsigma_a, deta */
    DIFF_PHASE_G,     /* index: a medium with a Henyey–Greenstein (or isotropic, g = 0) phase function; dg/dθ = 1 */
    DIFF_EMISSION,    /* index: a light; dlog: ∂ ln(its emitted radiance)/∂θ per channel */
    DIFF_ALBEDO,      /* index: a BSDF linear in its constant albedo; dlog: ∂ ln(albedo)/∂θ per channel */
    DIFF_PULSE_START, /* index: a light; its pulse's start */
    DIFF_PULSE_WIDTH, /* index: a light; its pulse's width (> 0) */
    DIFF_WINDOW,      /* the time window: d_start, d_width (gate [start, start + width), or the frames) */
    DIFF_TRANSLATE    /* target: what moves, along `axis` (a unit vector): a primitive, a light, the camera */
} diff_kind;
typedef enum { DIFF_TARGET_SURFACES, DIFF_TARGET_LIGHT, DIFF_TARGET_CAMERA } diff_target;
typedef struct {
    char pointer[256];       /* as given */
    diff_kind kind;
    int index;               /* medium, light or BSDF index, as kind says; -1 where none */
    vec3 dsigma_s, dsigma_a; /* DIFF_MEDIUM: ∂σs/∂θ, ∂σa/∂θ per channel (density applied) */
    double deta;             /* DIFF_MEDIUM: ∂η/∂θ (η = 1/speed_of_light: time per length) */
    vec3 dlog;               /* DIFF_EMISSION, DIFF_ALBEDO */
    double d_start, d_width; /* DIFF_WINDOW: ∂start/∂θ and ∂width/∂θ of the window (gate centre: 1, 0; gate
                              * width, centred: −1/2, 1; frame start: 1, 0; frame width: 0, 1) */
    int target;              /* DIFF_TRANSLATE: diff_target */
    int first_surface, surface_count; /* DIFF_TRANSLATE of a primitive: its surfaces [first, first + count) */
    int light;               /* DIFF_TRANSLATE: the light that moves with it (a point light, or the primitive's
                              * area light), else -1 */
    vec3 axis;               /* DIFF_TRANSLATE: ∂position/∂θ */
} diff_param;

/* ---- the scene ---- */
typedef struct scene scene;
struct scene {
    char path[1024];         /* scene file as given */
    char dir[1024];          /* its folder: meshes are relative to it */
    bsdf *bsdfs;
    int bsdf_count;
    texture *textures;       /* albedo bitmaps referenced by bsdfs[].texture */
    int texture_count;
    medium *media;
    int medium_count;
    surface *surfaces;
    int surface_count;
    emitter *lights;         /* include/dartspp/emitter.h */
    int light_count;
    camera cam;
    integrator_settings integrator;
    renderer_settings renderer;
    /* triangles in world space (float, as Embree holds them) */
    float *verts;            /* 3 per vertex */
    uint32_t *tris;          /* 3 global vertex indices per triangle */
    uint32_t vert_count, tri_count;
    float ray_offset_scale;  /* largest |coordinate| of the geometry (1 without geometry): ray offsets scale with it */
    char *notes;             /* warnings and (with verbose) ignored keys, one per line; may be NULL */
    char *mesh_files;        /* the mesh files read, one resolved path per line (a render's outputs must not
                              * overwrite them); may be NULL */
    void *rt_device, *rt_scene; /* Embree handles */
    diff_param diffs[DIFF_PARAM_MAX]; /* the derivatives asked for (scene_load_options.derivatives), in order */
    int diff_count;
};

typedef struct {
    const char *const *sets; /* "key=value" overrides of integrator/renderer keys (--set) */
    int set_count;
    int verbose;             /* also list ignored keys in notes */
    const char *const *derivatives; /* JSON Pointers of the parameters to differentiate (at most DIFF_PARAM_MAX) */
    int derivative_count;
} scene_load_options;

int scene_load(const char *path, const scene_load_options *opt, scene *s, dp_error *err);
/* The same from the scene's JSON text (the Python API's dict scenes): `name` stands for the file in messages
 * (e.g. "<dict>"), and relative mesh, texture and table paths resolve against base_dir (NULL: "."). */
int scene_load_text(const char *text, const char *name, const char *base_dir, const scene_load_options *opt, scene *s,
                    dp_error *err);
void scene_free(scene *s);

/* ---- ray queries ---- */
typedef struct {
    double t;
    vec3 p;      /* hit point from barycentrics */
    vec3 ng;     /* unit geometric normal (p1-p0)x(p2-p0) */
    vec3 ns;     /* unit shading normal: interpolated vertex normals of a `smooth` mesh, flipped to ng's
                  * side; ng otherwise */
    double uv[2];/* texture coordinates interpolated from the mesh's vertex UVs (0 without UVs) */
    uint32_t tri;/* global triangle index */
    int surface;
} hit_record;

/* Closest hit with t in (0, tmax); returns 1 on a hit. */
int scene_intersect(const scene *s, vec3 o, vec3 d, double tmax, hit_record *h);
/* Origin for a ray leaving surface point p on the side of n (Wächter & Binder, Ray Tracing Gems ch. 6), with
 * their near-origin constants scaled by the scene's size so that a scene scaled by any factor is offset alike. */
vec3 scene_offset_ray_origin(const scene *s, vec3 p, vec3 n);

/* Albedo of bsdf b at hit h: its texture sampled bilinearly at h->uv (wrapping), else b->albedo. */
vec3 scene_albedo(const scene *s, const bsdf *b, const hit_record *h);

/* Transmittance and time from p (in medium `med`) to the point q, crossing only null/forward surfaces;
 * returns 0 (and tr = 0) when an opaque surface is in the way. time accumulates eta * length. */
int scene_transmittance(const scene *s, vec3 p, int med, vec3 q, vec3 *tr, double *time);
/* scene_transmittance, with *end the region at q (the sliced primitives' displaced vertices: σs and the phase
 * function there). */
int scene_transmittance_region(const scene *s, vec3 p, int med, vec3 q, vec3 *tr, double *time, int *end);
/* scene_transmittance_region, calling on_segment(ctx, region, length) for every straight piece it crosses
 * (the derivatives' transmittance and time per region; NULL: none). */
typedef void (*scene_segment_fn)(void *ctx, int region, double len);
int scene_transmittance_segments(const scene *s, vec3 p, int med, vec3 q, vec3 *tr, double *time, int *end,
                                 scene_segment_fn on_segment, void *ctx);

/* Whether a region (medium index or MEDIUM_VACUUM) occurs in the scene: the camera's, a light's, or a side
 * of a surface that sets media (a surface that sets none keeps the medium it is crossed from). */
int scene_region_present(const scene *s, int region);
/* Whether every region present in the scene has the same refractive index (control vertices need it). */
int scene_eta_uniform(const scene *s);
/* Whether every straight unoccluded segment (scene_transmittance's: crossing only null and forward surfaces)
 * stays at one refractive index: no pass-through surface separates regions of different speed_of_light.
 * Weaker than scene_eta_uniform: a glass sphere of another speed in fog passes (its surface stops segments). */
int scene_eta_uniform_along_segments(const scene *s);

/* Whether the medium scatters in any channel (the DARTS samplers and EDA only run where it does). */
static inline int medium_scatters(const medium *m)
{
    return m->sigma_s.x > 0.0 || m->sigma_s.y > 0.0 || m->sigma_s.z > 0.0;
}

static inline double medium_eta(const scene *s, int med)
{
    return med == MEDIUM_VACUUM ? s->integrator.vacuum_eta : s->media[med].eta;
}

/* A medium's name for messages, "vacuum" for none. */
static inline const char *medium_name(const scene *s, int med)
{
    return med == MEDIUM_VACUUM ? "vacuum" : s->media[med].name;
}

/* The time a path starts with: the emission time drawn from light L's pulse (emitter.h) plus the sensor's
 * response offset (sensor.h). Both shift a path's time as a whole, so they are drawn together, where the
 * path starts (docs/sensor.md §2); a delta pulse and a perfect sensor draw nothing. */
static inline double path_time_offset(const scene *s, const emitter *L, dp_rng *rng)
{
    double t = emitter_pulse_sample(&L->pulse, rng);
    return t + sensor_response_sample(&s->cam.response, rng);
}

#endif
