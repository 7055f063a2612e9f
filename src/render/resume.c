/* The checkpoint state "<stem>.state": the film's exact sums, so that `--resume` continues a render bit for
 * bit, and the refusal to overwrite a checkpoint holding more passes than a new run will render.
 *
 * Why this is enough: pass i draws only from streams keyed by (seed, i, pixel or path index) and uses the
 * radii and weight of iteration i (schedule_radius, plan_pass_weight); the film is the running sums of the
 * weighted pass layers (double for the gate image, float for the frames) and their weight sum. A render
 * resumed from the sums after N passes with the same plan and seed therefore adds exactly the passes
 * N, N+1, ... that the uninterrupted render adds, in the same order, to the same numbers.
 *
 * The file: a text header, then the raw sums in this machine's byte order, then the checksum of it all.
 *   dartspp-state 3
 *   byte-order 0x0102030405060708       (the uint64 1 2 3 4 5 6 7 8, written as it lies in memory, in hex)
 *   seed S
 *   resolution W H
 *   frames F
 *   orders K
 *   amcw F                              (version 5: renderer.amcw_frequencies' count, docs/amcw.md; 0 without)
 *   scene geometry G materials M media E lights L camera C   (scene_digest.c, in hex)
 *   passes N
 *   resumable 1|0                       (0: several ranks, one dropped a pass: not iterations 0..N−1)
 *   weight_sum %a   last_weight %a       (hexadecimal doubles: exact)
 *   nonfinite K
 *   derivatives D                       (the derivative films, include/dartspp/derivative.h; 0 without)
 *   derivative L POINTER                D lines, in the film's order: the pointer's length, then its bytes
 *   plan_bytes L     then the plan's JSON (L bytes) and a newline
 *   data_bytes B     then B bytes: W·H·3 doubles (gate sums), layers·W·H·3 floats (frame and order sums),
 *                    then the same two blocks for each derivative film in order, then the image's AMCW sums
 *                    (version 5: F·W·H·6 doubles, film.h's amcw_sum)
 *   checksum X       FNV-1a 64 of every byte before this line, in hex: an edited header field (a weight sum,
 *                    a pass count, a seed) is as damaged as an edited sum, and is refused the same way
 */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "run_internal.h"

#define STATE_VERSION 5 /* 3: the scene's digest, and the checksum over the whole file at its end; 4: the
                          * derivative films; 5: the AMCW sums (a state of version 4 is read as one without) */
#define STATE_VERSION_OLDEST 4
#define FNV_OFFSET 0xcbf29ce484222325ULL
#define TRAILER_BYTES 28 /* "checksum 0x" + 16 hex digits + "\n" */

static uint64_t fnv1a(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ULL;
    return h;
}

static uint64_t byte_order_mark(void)
{
    const unsigned char b[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    uint64_t v;
    memcpy(&v, b, sizeof v);
    return v;
}

void resume_state_path(const char *out, char *path, size_t n)
{
    const char *dot = strrchr(out, '.'), *slash = strrchr(out, '/');
    int stem = dot && (!slash || dot > slash) ? (int)(dot - out) : (int)strlen(out);
    if (snprintf(path, n, "%.*s.state", stem, out) >= (int)n) path[n - 1] = '\0';
}

static size_t gate_count(int w, int h) { return (size_t)w * h * 3; }

/* Writes n bytes and adds them to the running checksum; 1 when the write failed. */
static int put(FILE *o, uint64_t *h, const void *p, size_t n)
{
    *h = fnv1a(*h, p, n);
    return fwrite(p, 1, n, o) != n;
}

/* The text header (up to the plan's JSON and the data_bytes line) in memory, so that it is checksummed as
 * written. NULL when out of memory. */
static char *header_text(const film *f, const char *plan_json, uint64_t seed, const uint64_t *digest, int resumable,
                         size_t data, size_t *len)
{
    char *text = NULL;
    FILE *m = open_memstream(&text, len);
    if (!m) return NULL;
    fprintf(m, "dartspp-state %d\nbyte-order 0x%016" PRIx64 "\nseed %" PRIu64 "\nresolution %d %d\nframes %d\n"
            "orders %d\namcw %d\nscene", STATE_VERSION, byte_order_mark(), seed, f->width, f->height,
            f->window.frame_count, f->window.orders, f->window.amcw_count);
    for (int i = 0; i < SCENE_DIGEST_PARTS; i++) fprintf(m, " %s 0x%016" PRIx64, SCENE_DIGEST_NAMES[i], digest[i]);
    fprintf(m, "\npasses %ld\nresumable %d\nweight_sum %a\nlast_weight %a\nnonfinite %ld\n", f->passes,
            resumable ? 1 : 0, f->weight_sum, f->last_weight, f->nonfinite);
    fprintf(m, "derivatives %d\n", f->deriv_count);
    for (int k = 0; k < f->deriv_count; k++) {
        const char *label = f->deriv[k].label ? f->deriv[k].label : "";
        fprintf(m, "derivative %zu %s\n", strlen(label), label);
    }
    fprintf(m, "plan_bytes %zu\n%s\ndata_bytes %zu\n", strlen(plan_json), plan_json, data);
    if (fclose(m)) {
        free(text);
        return NULL;
    }
    return text;
}

/* The sums of f, then of each derivative film, into the running checksum; 1 when a write failed. */
static int put_sums(FILE *o, uint64_t *h, const film *f, size_t n, size_t nf)
{
    if (put(o, h, f->sum, n * sizeof(double)) || (nf && put(o, h, f->frame_sum, nf * sizeof(float)))) return 1;
    for (int k = 0; k < f->deriv_count; k++)
        if (put_sums(o, h, &f->deriv[k], n, nf)) return 1;
    return 0;
}

int resume_state_write(const char *path, const film *f, const char *plan_json, uint64_t seed, const uint64_t *digest,
                       int resumable, dp_error *err)
{
    size_t n = gate_count(f->width, f->height), nf = n * (size_t)time_window_layers(&f->window), len = 0;
    size_t na = n * 2 * (size_t)f->window.amcw_count;
    size_t data = (1 + (size_t)f->deriv_count) * (n * sizeof(double) + nf * sizeof(float)) + na * sizeof(double);
    char *head = header_text(f, plan_json, seed, digest, resumable, data, &len);
    if (!head) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the checkpoint state", path);
    atomic_file af;
    FILE *o = atomic_fopen(path, "wb", &af, err);
    if (!o) {
        free(head);
        return -1;
    }
    uint64_t h = FNV_OFFSET;
    int failed = put(o, &h, head, len) || put_sums(o, &h, f, n, nf) || (na && put(o, &h, f->amcw_sum, na * sizeof(double)));
    free(head);
    if (!failed) failed = fprintf(o, "checksum 0x%016" PRIx64 "\n", h) != TRAILER_BYTES;
    return atomic_fclose(&af, failed, err);
}

void resume_state_free(resume_state *s)
{
    free(s->plan);
    for (int k = 0; k < s->deriv_count; k++) free(s->deriv[k]);
    free(s->sum);
    free(s->frame_sum);
    free(s->amcw_sum);
    memset(s, 0, sizeof *s);
}

/* The trailer's checksum against every byte before it; *body: where the trailer starts. 0: intact; 1: not a
 * state of this version (first line); 2: damaged or truncated. Leaves the file at its start. */
static int check_whole_file(FILE *in, long *body)
{
    int version = 0;
    if (fscanf(in, "dartspp-state %d", &version) != 1 || version < STATE_VERSION_OLDEST || version > STATE_VERSION)
        return 1;
    if (fseek(in, 0, SEEK_END)) return 2;
    long size = ftell(in);
    char tail[TRAILER_BYTES + 1] = {0};
    uint64_t want = 0;
    if (size < TRAILER_BYTES || fseek(in, size - TRAILER_BYTES, SEEK_SET) ||
        fread(tail, 1, TRAILER_BYTES, in) != TRAILER_BYTES || sscanf(tail, "checksum 0x%16" SCNx64, &want) != 1 ||
        tail[TRAILER_BYTES - 1] != '\n')
        return 2;
    rewind(in);
    uint64_t h = FNV_OFFSET;
    unsigned char buf[1 << 16];
    for (long left = size - TRAILER_BYTES; left > 0;) {
        size_t k = fread(buf, 1, left < (long)sizeof buf ? (size_t)left : sizeof buf, in);
        if (k == 0) return 2;
        h = fnv1a(h, buf, k);
        left -= (long)k;
    }
    rewind(in);
    *body = size - TRAILER_BYTES;
    return h == want ? 0 : 2;
}

/* The derivative films' pointers (header lines "derivatives D" and D lines "derivative L POINTER"). 1 when
 * read. */
static int read_derivs(FILE *in, resume_state *s)
{
    int d = -1;
    if (fscanf(in, " derivatives %d", &d) != 1 || d < 0 || d > DIFF_PARAM_MAX) return 0;
    for (int k = 0; k < d; k++) {
        size_t len = 0;
        if (fscanf(in, " derivative %zu", &len) != 1 || len >= 4096 || fgetc(in) != ' ') return 0;
        if (!(s->deriv[k] = malloc(len + 1))) return 0;
        s->deriv_count = k + 1;
        if (fread(s->deriv[k], 1, len, in) != len) return 0;
        s->deriv[k][len] = '\0';
    }
    return 1;
}

static int read_digest(FILE *in, uint64_t *digest)
{
    int at = -1;
    if (fscanf(in, " scene%n", &at) < 0 || at < 0) return 0;
    for (int i = 0; i < SCENE_DIGEST_PARTS; i++) {
        char name[32];
        if (fscanf(in, " %31s 0x%" SCNx64, name, &digest[i]) != 2 || strcmp(name, SCENE_DIGEST_NAMES[i])) return 0;
    }
    return 1;
}

int resume_state_read(const char *path, int with_data, resume_state *s, dp_error *err)
{
    memset(s, 0, sizeof *s);
    FILE *in = fopen(path, "rb");
    if (!in) return dp_fail(err, "%s: cannot read the checkpoint state: %s", path, strerror(errno));
    long body = 0;
    int whole = check_whole_file(in, &body);
    if (whole) {
        fclose(in);
        if (whole == 1)
            return dp_fail(err, "%s: not a dartspp checkpoint state of version %d to %d (an older dartspp wrote it, "
                           "or it is another file): cannot resume from it", path, STATE_VERSION_OLDEST, STATE_VERSION);
        return dp_fail(err, "%s: the checkpoint state is damaged: its checksum does not match its contents (a byte "
                       "was changed, or the file was cut short): cannot resume from it", path);
    }
    int version = 0;
    uint64_t bom = 0;
    size_t plan_bytes = 0, data_bytes = 0;
    int ok = fscanf(in, "dartspp-state %d", &version) == 1 && version >= STATE_VERSION_OLDEST && version <= STATE_VERSION &&
             fscanf(in, " byte-order 0x%" SCNx64, &bom) == 1 && bom == byte_order_mark() &&
             fscanf(in, " seed %" SCNu64, &s->seed) == 1 &&
             fscanf(in, " resolution %d %d", &s->width, &s->height) == 2 && s->width > 0 && s->height > 0 &&
             fscanf(in, " frames %d", &s->frames) == 1 && s->frames >= 0 &&
             fscanf(in, " orders %d", &s->orders) == 1 && s->orders >= 0 && s->orders <= 64 &&
             (version < 5 || (fscanf(in, " amcw %d", &s->amcw) == 1 && s->amcw >= 0 && s->amcw <= AMCW_FREQ_MAX)) &&
             read_digest(in, s->digest) &&
             fscanf(in, " passes %ld", &s->passes) == 1 && s->passes >= 0 &&
             fscanf(in, " resumable %d", &s->resumable) == 1 && (s->resumable == 0 || s->resumable == 1) &&
             fscanf(in, " weight_sum %la", &s->weight_sum) == 1 &&
             fscanf(in, " last_weight %la", &s->last_weight) == 1 &&
             fscanf(in, " nonfinite %ld", &s->nonfinite) == 1 && read_derivs(in, s) &&
             fscanf(in, " plan_bytes %zu", &plan_bytes) == 1 && plan_bytes < (1u << 24) && fgetc(in) == '\n';
    if (ok && (s->plan = malloc(plan_bytes + 1)) != NULL) {
        ok = fread(s->plan, 1, plan_bytes, in) == plan_bytes && fgetc(in) == '\n';
        s->plan[plan_bytes] = '\0';
    } else ok = 0;
    time_window layers = {.frame_count = s->frames, .orders = s->orders};
    size_t n = ok ? gate_count(s->width, s->height) : 0, nf = n * (size_t)time_window_layers(&layers);
    size_t films = 1 + (size_t)s->deriv_count, na = n * 2 * (size_t)s->amcw;
    ok = ok && fscanf(in, "data_bytes %zu", &data_bytes) == 1 && fgetc(in) == '\n' &&
         data_bytes == films * (n * sizeof(double) + nf * sizeof(float)) + na * sizeof(double) &&
         ftell(in) + (long)data_bytes == body;
    if (ok && with_data) {
        s->sum = malloc(films * n * sizeof(double));
        s->frame_sum = nf ? malloc(films * nf * sizeof(float)) : NULL;
        s->amcw_sum = na ? malloc(na * sizeof(double)) : NULL;
        if (!s->sum || (nf && !s->frame_sum) || (na && !s->amcw_sum)) {
            fclose(in);
            resume_state_free(s);
            return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the checkpoint state", path);
        }
        for (size_t k = 0; ok && k < films; k++)
            ok = fread(s->sum + k * n, sizeof(double), n, in) == n &&
                 (!nf || fread(s->frame_sum + k * nf, sizeof(float), nf, in) == nf);
        ok = ok && (!na || fread(s->amcw_sum, sizeof(double), na, in) == na);
    }
    fclose(in);
    if (!ok) {
        resume_state_free(s);
        return dp_fail(err, "%s: the checkpoint state (version %d, its checksum intact) is not one this machine "
                       "reads: another byte order, or fields out of range", path, STATE_VERSION);
    }
    return 0;
}

/* The first place where two plans differ, as "…text…" of the checkpoint's plan around it. */
static void plan_difference(const char *a, const char *b, char *out, size_t n)
{
    size_t i = 0;
    while (a[i] && a[i] == b[i]) i++;
    size_t from = i > 40 ? i - 40 : 0;
    snprintf(out, n, "checkpoint \"...%.80s...\", this run \"...%.80s...\"", a + from, b + from);
}

/* "(k pointer, ...)" of n pointers, or "(none)". */
static void deriv_list(char *out, size_t size, const char *const *ptr, int n)
{
    snprintf(out, size, "%s", n ? "(" : "(none)");
    for (int k = 0; k < n; k++)
        snprintf(out + strlen(out), size - strlen(out), "%sd%d %s%s", k ? ", " : "", k, ptr[k], k == n - 1 ? ")" : "");
}

/* The derivative films of the state against the run's --derivative list: the same pointers in the same order
 * (film k of the one is film k of the other), else a refusal naming both lists. */
static int resume_check_derivs(const resume_state *s, const char *path, const scene *sc, dp_error *err)
{
    const char *mine[DIFF_PARAM_MAX];
    int same = s->deriv_count == sc->diff_count;
    for (int k = 0; k < sc->diff_count; k++) {
        mine[k] = sc->diffs[k].pointer;
        same = same && k < s->deriv_count && !strcmp(s->deriv[k], mine[k]);
    }
    if (same) return 0;
    char held[1200], asked[1200];
    deriv_list(held, sizeof held, (const char *const *)s->deriv, s->deriv_count);
    deriv_list(asked, sizeof asked, mine, sc->diff_count);
    return dp_fail(err, "%s: the checkpoint holds the derivatives %s, this run asks for %s (--derivative, in that "
                   "order): their sums would be mixed with other images: cannot resume (the same --derivative list "
                   "resumes; --overwrite renders anew)", path, held, asked);
}

int resume_check(const resume_state *s, const char *path, const render_run_job *j, long spp, dp_error *err)
{
    if (!s->resumable)
        return dp_fail(err, "%s: the checkpoint holds the %ld passes of a render in which a rank dropped a pass: not "
                       "the passes 0..%ld a resume continues from: cannot resume (--overwrite renders anew)", path,
                       s->passes, s->passes - 1);
    if (s->seed != j->ro.seed)
        return dp_fail(err, "%s: the checkpoint was rendered with seed %" PRIu64 ", this run has seed %" PRIu64
                       " (--seed): cannot resume", path, s->seed, j->ro.seed);
    if (s->width != j->s.cam.width || s->height != j->s.cam.height)
        return dp_fail(err, "%s: the checkpoint is %dx%d, this run renders %dx%d (camera.resolution): cannot resume",
                       path, s->width, s->height, j->s.cam.width, j->s.cam.height);
    if (s->frames != j->p.window.frame_count)
        return dp_fail(err, "%s: the checkpoint has %d frames, this run %d (integrator.frame_num): cannot resume",
                       path, s->frames, j->p.window.frame_count);
    if (s->orders != j->p.window.orders)
        return dp_fail(err, "%s: the checkpoint has %d scattering-order layers, this run %d (integrator.bounce_orders): "
                       "cannot resume", path, s->orders, j->p.window.orders);
    if (s->amcw != j->p.window.amcw_count)
        return dp_fail(err, "%s: the checkpoint has the AMCW sums of %d modulation frequencies, this run %d "
                       "(renderer.amcw_frequencies): cannot resume", path, s->amcw, j->p.window.amcw_count);
    char parts[128] = "";
    for (int i = 0; i < SCENE_DIGEST_PARTS; i++)
        if (s->digest[i] != j->digest[i])
            snprintf(parts + strlen(parts), sizeof parts - strlen(parts), "%s%s", parts[0] ? ", " : "",
                     SCENE_DIGEST_NAMES[i]);
    if (parts[0])
        return dp_fail(err, "%s: the checkpoint was rendered from another scene (this run's scene differs in: %s): "
                       "its sums would be blended into this scene's image: cannot resume", path, parts);
    if (resume_check_derivs(s, path, &j->s, err)) return -1;
    if (strcmp(s->plan, j->plan_json)) {
        char diff[256];
        plan_difference(s->plan, j->plan_json, diff, sizeof diff);
        return dp_fail(err, "%s: the checkpoint was rendered with another plan (%s): cannot resume", path, diff);
    }
    if (spp > 0 && s->passes > spp)
        return dp_fail(err, "%s: the checkpoint holds %ld passes, more than the %ld this run renders (--spp): "
                       "cannot resume", path, s->passes, spp);
    return 0;
}

int resume_overwrite_check(const char *path, long spp, dp_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0) return 0;
    resume_state s;
    dp_error why;
    if (resume_state_read(path, 0, &s, &why)) /* damaged, or of an older version: how many passes is unknown */
        return dp_fail(err, "%s; this run would overwrite it, and the passes it holds are unknown: --overwrite "
                       "replaces it", why.msg);
    long held = s.passes;
    resume_state_free(&s);
    if (held == 0 || (spp > 0 && held <= spp)) return 0;
    char will[96];
    if (spp > 0) snprintf(will, sizeof will, "%ld passes", spp);
    else snprintf(will, sizeof will, "an unknown number of passes (no pass count, only a time budget or none)");
    return dp_fail(err, "%s holds a checkpoint of %ld passes; this run renders %s and would overwrite it: "
                   "--resume continues it, --overwrite replaces it", path, held, will);
}
