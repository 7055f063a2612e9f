/* EDA table files: our headered format (save, load with checks), the authors' headerless float32 table,
 * and the cache folder that builds a table once per medium and shape. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dartspp/darts.h"
#include "dartspp/io.h"

#define EDA_MAGIC "DPEDATAB"
#define EDA_VERSION 1u
#define EDA_HEADER_BYTES (8 + 4 * 4 + 6 * 8 + 8)
#define RAW_SHAPE 128

/* FNV-1a over the payload bytes: detects corruption, not tampering. */
static uint64_t fnv1a(const void *data, size_t n)
{
    const unsigned char *p = data;
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 1099511628211ULL;
    return h;
}

static size_t table_values(const eda_table *t) { return (size_t)t->n_ratio * t->n_s * t->n_cos; }

/* Every cell a CDF: finite, within [0, 1], non-decreasing, last value 1. Returns the first bad cell or -1. */
static long first_bad_cell(const eda_table *t)
{
    size_t cells = (size_t)t->n_ratio * t->n_s;
    for (size_t c = 0; c < cells; c++) {
        const float *F = t->cdf + c * t->n_cos;
        float prev = 0.0f;
        for (int k = 0; k < t->n_cos; k++) {
            if (!(F[k] >= prev && F[k] <= 1.0f)) return (long)c;
            prev = F[k];
        }
        if (F[t->n_cos - 1] != 1.0f) return (long)c;
    }
    return -1;
}

static int write_all(int fd, const void *data, size_t n)
{
    const char *p = data;
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

static void put(unsigned char **p, const void *v, size_t n)
{
    memcpy(*p, v, n);
    *p += n;
}

int eda_table_save(const eda_table *t, const char *path, dp_error *err)
{
    unsigned char head[EDA_HEADER_BYTES], *p = head;
    uint32_t u[4] = {EDA_VERSION, (uint32_t)t->n_ratio, (uint32_t)t->n_s, (uint32_t)t->n_cos};
    double d[6] = {t->sigma_s, t->sigma_a, t->g, t->s_max, t->r_lo, t->r_hi};
    uint64_t h = fnv1a(t->cdf, table_values(t) * sizeof(float));
    put(&p, EDA_MAGIC, 8);
    put(&p, u, sizeof u);
    put(&p, d, sizeof d);
    put(&p, &h, sizeof h);
    char tmp[4200];
    if (io_make_parent_dirs(path, err)) return -1;
    int fd = atomic_open(path, tmp, sizeof tmp, err);
    if (fd < 0) return -1;
    if (write_all(fd, head, sizeof head) || write_all(fd, t->cdf, table_values(t) * sizeof(float))) {
        atomic_abort(fd, tmp);
        return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: write failed: %s", path, strerror(errno));
    }
    return atomic_commit(fd, tmp, path, err);
}

/* Reads a whole file into memory; *size is its length. */
static unsigned char *read_all(const char *path, size_t *size, dp_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        dp_fail(err, "%s: cannot open EDA table: %s", path, strerror(errno));
        return NULL;
    }
    struct stat st;
    unsigned char *buf = NULL;
    if (fstat(fileno(f), &st) == 0 && st.st_size >= 0 && (buf = malloc((size_t)st.st_size + 1)))
        *size = fread(buf, 1, (size_t)st.st_size, f);
    fclose(f);
    if (!buf) dp_fail(err, "%s: cannot read EDA table", path);
    return buf;
}

static int check_cdfs(eda_table *t, const char *path, dp_error *err)
{
    long bad = first_bad_cell(t);
    if (bad < 0) return 0;
    eda_table_free(t);
    return dp_fail(err, "%s: corrupted EDA table: cell (row %ld, column %ld) is not a CDF (non-decreasing, "
                        "in [0, 1], ending at 1)", path, bad / (t->n_s ? t->n_s : 1), bad % (t->n_s ? t->n_s : 1));
}

int eda_table_load(eda_table *t, const char *path, dp_error *err)
{
    memset(t, 0, sizeof *t);
    size_t n = 0;
    unsigned char *buf = read_all(path, &n, err);
    if (!buf) return -1;
    int rc = 0;
    uint32_t u[4];
    double d[6];
    uint64_t h;
    if (n < EDA_HEADER_BYTES || memcmp(buf, EDA_MAGIC, 8)) {
        rc = dp_fail(err, "%s: not a dartspp EDA table (no '" EDA_MAGIC "' header; a headerless 128x128x256 "
                          "table is read with the medium's table_path and max_T)", path);
    } else {
        memcpy(u, buf + 8, sizeof u);
        memcpy(d, buf + 8 + sizeof u, sizeof d);
        memcpy(&h, buf + 8 + sizeof u + sizeof d, sizeof h);
        *t = (eda_table){(int)u[1], (int)u[2], (int)u[3], d[0], d[1], d[2], d[3], d[4], d[5], NULL};
        size_t want = EDA_HEADER_BYTES + sizeof(float) * (size_t)u[1] * u[2] * u[3];
        if (u[0] != EDA_VERSION) rc = dp_fail(err, "%s: EDA table version %u (this build reads %u)", path, u[0], EDA_VERSION);
        else if (u[1] < 1 || u[2] < 1 || u[3] < 2 || u[1] > 4096 || u[2] > 4096 || u[3] > 4096)
            rc = dp_fail(err, "%s: EDA table header has an impossible shape %ux%ux%u", path, u[1], u[2], u[3]);
        else if (n != want)
            rc = dp_fail(err, "%s: EDA table is %zu bytes, its header says %zu (truncated or padded)", path, n, want);
        else if (!(t->s_max > 0.0 && isfinite(t->s_max) && t->r_lo >= 0.0 && t->r_lo < t->r_hi && t->r_hi < 1.0))
            rc = dp_fail(err, "%s: EDA table header has an invalid S or C/S range", path);
        else if (fnv1a(buf + EDA_HEADER_BYTES, n - EDA_HEADER_BYTES) != h)
            rc = dp_fail(err, "%s: EDA table payload does not match its checksum (corrupted)", path);
    }
    if (!rc && !(t->cdf = malloc(n - EDA_HEADER_BYTES)))
        rc = dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    if (!rc) memcpy(t->cdf, buf + EDA_HEADER_BYTES, n - EDA_HEADER_BYTES);
    free(buf);
    if (rc) {
        t->cdf = NULL;
        return -1;
    }
    return check_cdfs(t, path, err);
}

int eda_table_load_raw(eda_table *t, const char *path, double s_max, double r_lo, double r_hi, dp_error *err)
{
    memset(t, 0, sizeof *t);
    const size_t want = sizeof(float) * RAW_SHAPE * RAW_SHAPE * 2 * RAW_SHAPE;
    size_t n = 0;
    unsigned char *buf = read_all(path, &n, err);
    if (!buf) return -1;
    if (n != want) {
        free(buf);
        return dp_fail(err, "%s: a headerless EDA table must be exactly %zu bytes (128x128x256 float32), this "
                            "one is %zu", path, want, n);
    }
    if (!(s_max > 0.0 && isfinite(s_max)) || !(r_lo >= 0.0 && r_lo < r_hi && r_hi < 1.0)) {
        free(buf);
        return dp_fail(err, "%s: invalid max_T %g or C/S range [%g, %g)", path, s_max, r_lo, r_hi);
    }
    *t = (eda_table){RAW_SHAPE, RAW_SHAPE, 2 * RAW_SHAPE, 0.0, 0.0, 0.0, s_max, r_lo, r_hi, (float *)buf};
    return check_cdfs(t, path, err);
}

/* Progress in place on a terminal; nothing in logs (the start and end lines say enough there). ctx: the
 * messages' stream. */
static void build_progress(void *ctx, int done, int rows)
{
    FILE *out = ctx;
    if (isatty(fileno(out)) && (done % 8 == 0 || done == rows)) fprintf(out, "\rEDA table: row %d of %d", done, rows);
}

int eda_table_cached(eda_table *t, const char *dir, double sigma_s, double sigma_a, double g, int n_ratio, int n_s,
                     int n_cos, double s_max, double r_lo, double r_hi, FILE *messages, dp_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/eda-s%.9g-a%.9g-g%.9g-S%.9g-r%.9g-%.9g-%dx%dx%d.bin", dir, sigma_s, sigma_a, g,
             s_max, r_lo, r_hi, n_ratio, n_s, n_cos);
    if (access(path, F_OK) == 0) return eda_table_load(t, path, err);
    double t0 = dp_seconds();
    if (messages) fprintf(messages, "EDA table: building %s\n", path);
    if (eda_table_build(t, sigma_s, sigma_a, g, n_ratio, n_s, n_cos, s_max, r_lo, r_hi,
                        messages ? build_progress : NULL, messages, err))
        return -1;
    if (messages)
        fprintf(messages, "%sEDA table: built in %.1f s\n", isatty(fileno(messages)) ? "\r" : "", dp_seconds() - t0);
    /* the table is built and correct: a folder that cannot keep it costs the next render a rebuild, not
     * this render its work */
    dp_error save_err;
    int saved = !eda_table_save(t, path, &save_err);
    if (messages && !saved)
        fprintf(messages, "warning: cannot store the EDA table in %s: %s; using it from memory\n", dir, save_err.msg);
    else if (messages)
        fprintf(messages, "EDA table: stored for later renders\n");
    return 0;
}
