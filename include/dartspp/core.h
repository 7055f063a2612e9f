/* dartspp core: vectors, errors, counter-based RNG, sampling helpers.
 * Everything here is small and inline-friendly; no module state.
 *
 * Naming rule for public symbols (every header in include/dartspp): a function or type is named for the
 * object or module it belongs to, as its first word, then what it does (scene_load, film_splat,
 * photon_map_query_beam, eda_table_build, plan_resolve, io_make_parent_dirs). The core's vocabulary is the
 * one exception, kept short because it is everywhere: vec3 with v3_*, dp_rng with rng_*, the samplers
 * sample_*; the process-wide utilities (errors, clock, the stop flag) carry dp_. */
#ifndef DARTSPP_CORE_H
#define DARTSPP_CORE_H

#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define DP_INV_PI (1.0 / M_PI)
#define DP_INV_4PI (1.0 / (4.0 * M_PI))

/* ---- errors: every fallible call fills one of these and returns non-zero ----
 * The kind says what went wrong, and decides the exit status of the process (dp_exit_status). */
typedef enum {
    DP_ERROR_INPUT,       /* bad input: the command line, the scene or a file it names; a render refused before any
                           * work (outputs, memory guard) counts as bad input too. Exit 2 */
    DP_ERROR_OUTPUT,      /* a file could not be written. Exit 1 */
    DP_ERROR_MEMORY,      /* an allocation failed. Exit 1 */
    DP_ERROR_INTERRUPTED, /* SIGINT or SIGTERM stopped the work. Exit 130 (128 + SIGINT, as shells report it) */
    DP_ERROR_RANK,        /* another rank of a cluster failed; that rank reports its own error. Exit 1 */
    DP_ERROR_INTERNAL,    /* a limit or an invariant of the program. Exit 1 */
    DP_ERROR_LOST,        /* a rank of a cluster was lost (a collective call failed, or the job was stopped while
                           * the ranks were exchanging): the last reduction's passes were kept. Exit 4 */
} dp_error_kind;

typedef struct {
    dp_error_kind kind;
    char msg[1024];
} dp_error;

/* printf-style, kind DP_ERROR_INPUT; returns -1 so callers can `return dp_fail(err, ...)`. */
int dp_fail(dp_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The same with another kind. */
int dp_fail_kind(dp_error *err, dp_error_kind kind, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* The exit status of a process that ends with an error of this kind. */
int dp_exit_status(dp_error_kind kind);

/* Monotonic wall-clock seconds (for budgets, progress and stage timings). */
double dp_seconds(void);

/* ---- memory written by several threads ----
 * Data that threads write side by side goes on cache lines of its own: two threads writing one line make
 * each other wait (false sharing), which cost two-thread passes up to 10 % (bench/results/peer.md). */
#define DP_CACHE_LINE 64
/* Zeroed storage for n objects of `size` bytes starting on a cache line (the total rounded up to whole
 * lines); NULL when n or size is 0, on overflow, or out of memory. Freed with free(). */
void *dp_calloc_cache_aligned(size_t n, size_t size);

/* ---- Morton order (morton.c): the order of the linear BVHs ----
 * order[0, n) = the indices of the n points c[i·stride + 0..dims−1] (dims 3: space, 21 bits per axis; 4: space
 * and time, 16 bits each) sorted by their Morton code over the points' bounds, ties by index. 0, or -1 out of
 * memory. */
int dp_morton_order(const float *c, size_t stride, size_t n, int dims, uint32_t *order);

/* ---- interruption ----
 * A stop flag is set asynchronously (SIGINT/SIGTERM handler) and read by the long loops once per batch of
 * light paths or row of pixels; NULL means "never stops". */
typedef volatile sig_atomic_t dp_stop_flag;
static inline int dp_stopped(const dp_stop_flag *stop) { return stop && *stop; }

/* ---- 3-vectors (double: geometry and time are accumulated in double) ---- */
typedef struct {
    double x, y, z;
} vec3;

static inline vec3 v3(double x, double y, double z) { vec3 r = {x, y, z}; return r; }
static inline vec3 v3s(double s) { return v3(s, s, s); }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v3_scale(vec3 a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_neg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
static inline double v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_len(vec3 a) { return sqrt(v3_dot(a, a)); }
static inline vec3 v3_norm(vec3 a)
{
    double l = v3_len(a);
    return l > 0.0 ? v3_scale(a, 1.0 / l) : a;
}
static inline vec3 v3_exp_neg(vec3 a) { return v3(exp(-a.x), exp(-a.y), exp(-a.z)); }
/* fmax and fmin with their NaN rule (a NaN argument yields the other one), inlined: glibc's are calls,
 * which cost 3 % of a render in the hot loops. */
static inline double dp_fmax(double a, double b) { return (a > b || b != b) ? a : b; }
static inline double dp_fmin(double a, double b) { return (a < b || b != b) ? a : b; }
static inline double v3_max(vec3 a) { return dp_fmax(a.x, dp_fmax(a.y, a.z)); }
static inline double v3_avg(vec3 a) { return (a.x + a.y + a.z) / 3.0; }
static inline double v3_comp(vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }
static inline int v3_is_finite(vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
static inline int v3_is_zero(vec3 a) { return a.x == 0.0 && a.y == 0.0 && a.z == 0.0; }
/* Mirror reflection of d about the plane of unit normal n (either side). */
static inline vec3 v3_reflect(vec3 d, vec3 n) { return v3_sub(d, v3_scale(n, 2.0 * v3_dot(d, n))); }

/* Orthonormal basis around unit n (Duff et al. 2017, "Building an orthonormal basis, revisited"). */
void v3_basis(vec3 n, vec3 *s, vec3 *t);

/* ---- counter-based RNG ----
 * A stream is keyed by (seed, a, b) — e.g. (seed, iteration, pixel) — so that a sample's random numbers
 * do not depend on which thread computes it or in which order. */
typedef struct rng_replay rng_replay;
typedef struct {
    uint64_t state;
    rng_replay *replay; /* NULL: the stream itself; else rng_uniform reads the replay (primary sample space) */
} dp_rng;

dp_rng rng_stream(uint64_t seed, uint64_t a, uint64_t b);
uint64_t rng_next_u64(dp_rng *r);
/* uniform in [0, 1) with 53 random bits */
double rng_uniform(dp_rng *r);

/* ---- primary-sample-space replay (Kelemen et al. 2002) ----
 * A sample's random numbers as a vector u: rng_uniform on a dp_rng whose `replay` is set makes the next
 * value (fresh from `fresh`, or another sample's value moved, rng_replay_mutate) and records it in u, so
 * that `used` ends as the number of values the sample consumed. A Markov chain over samples mutates u. */
struct rng_replay {
    double *u;               /* the values consumed so far */
    int used;                /* how many */
    int cap;
    int oom;                 /* a record failed: the sample is not reproducible (the chain rejects it) */
    const double *src;       /* rng_replay_mutate: the sample moved (read as this one is consumed) */
    int src_n;               /* its length: values past it are fresh */
    double s_max, log_ratio; /* the step's largest size and ln(s_min/s_max) */
    dp_rng fresh;            /* a plain stream (replay NULL): fresh values and the steps' draws */
};
void rng_replay_free(rng_replay *r);
/* Starts a fresh sample: every value drawn from r->fresh. */
void rng_replay_restart(rng_replay *r);
/* Starts the sample `src` moved by a symmetric step: each of its used values u ± s_max·(s_min/s_max)^ξ
 * (sign and ξ uniform, from r->fresh; Kelemen et al. 2002, eq. 11), wrapped into [0, 1); values past
 * src->used are drawn fresh. The kernel is symmetric, so a Metropolis step accepts with the ratio of the
 * targets alone. s_max = 0 replays src exactly. The values are made as they are consumed, so src must stay
 * unchanged until r's sample is done. */
void rng_replay_mutate(rng_replay *r, const rng_replay *src, double s_min, double s_max);

/* ---- non-uniform variates (variates.c): exact at every parameter ---- */
double rng_normal(dp_rng *r);                   /* standard normal */
double rng_gamma(dp_rng *r, double shape);      /* Gamma(shape, 1); 0 for shape <= 0 */
double rng_beta(dp_rng *r, double a, double b); /* Beta(a, b), a, b > 0 */
long rng_binomial(dp_rng *r, long n, double p); /* Binomial(n, p); p is clamped to [0, 1] */
long rng_poisson(dp_rng *r, double mean);       /* Poisson(mean); 0 for mean <= 0 */

/* ---- sampling helpers (pdfs in solid angle) ---- */
vec3 sample_uniform_sphere(double u1, double u2);
vec3 sample_cosine_hemisphere(double u1, double u2); /* local frame, +z up */
/* Cosine-weighted direction about the unit normal n, in world space (pdf cosθ/π). */
vec3 sample_cosine_about(vec3 n, double u1, double u2);

#endif
