/* The checkpoint state "<stem>.state": the film's exact sums, so that `--resume` continues a render bit for
 * bit, and the refusal to overwrite a checkpoint holding more passes than a new run will render.
 *
 * Why this is enough: pass i draws only from streams keyed by (seed, i, pixel or path index) and uses the
 * radii and weight of iteration i (schedule_radius, plan_pass_weight); the film is the running sums of the
 * weighted pass layers (double for the gate image, float for the frames) and their weight sum. A render
 * resumed from the sums after N passes with the same plan and seed therefore adds exactly the passes
 * N, N+1, ... that the uninterrupted render adds, in the same order, to the same numbers.
 *
 * The file: a text header, then the raw sums in this machine's byte order.
 *   dartspp-state 1
 *   byte-order 0x0102030405060708       (the uint64 1 2 3 4 5 6 7 8, written as it lies in memory, in hex)
 *   seed S
 *   resolution W H
 *   frames F
 *   passes N
 *   weight_sum %a   last_weight %a       (hexadecimal doubles: exact)
 *   nonfinite K
 *   plan_bytes L     then the plan's JSON (L bytes) and a newline
 *   data_bytes D     then D bytes: W·H·3 doubles (gate sums), F·W·H·3 floats (frame sums)
 *   checksum X       FNV-1a 64 of the data, in hex
 */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "run_internal.h"

#define STATE_VERSION 2 /* 2: the line "orders N" and the order layers after the frames */

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

int resume_state_write(const char *path, const film *f, const char *plan_json, uint64_t seed, dp_error *err)
{
    atomic_file af;
    FILE *o = atomic_fopen(path, "wb", &af, err);
    if (!o) return -1;
    size_t n = gate_count(f->width, f->height), nf = n * (size_t)time_window_layers(&f->window);
    size_t data = n * sizeof(double) + nf * sizeof(float);
    uint64_t sum = fnv1a(0xcbf29ce484222325ULL, f->sum, n * sizeof(double));
    if (nf) sum = fnv1a(sum, f->frame_sum, nf * sizeof(float));
    fprintf(o, "dartspp-state %d\nbyte-order 0x%016" PRIx64 "\nseed %" PRIu64 "\nresolution %d %d\nframes %d\norders %d\n",
            STATE_VERSION, byte_order_mark(), seed, f->width, f->height, f->window.frame_count, f->window.orders);
    fprintf(o, "passes %ld\nweight_sum %a\nlast_weight %a\nnonfinite %ld\nchecksum 0x%016" PRIx64 "\n", f->passes,
            f->weight_sum, f->last_weight, f->nonfinite, sum);
    fprintf(o, "plan_bytes %zu\n%s\ndata_bytes %zu\n", strlen(plan_json), plan_json, data);
    int failed = fwrite(f->sum, sizeof(double), n, o) != n;
    if (!failed && nf) failed = fwrite(f->frame_sum, sizeof(float), nf, o) != nf;
    return atomic_fclose(&af, failed, err);
}

void resume_state_free(resume_state *s)
{
    free(s->plan);
    free(s->sum);
    free(s->frame_sum);
    memset(s, 0, sizeof *s);
}

int resume_state_read(const char *path, int with_data, resume_state *s, dp_error *err)
{
    memset(s, 0, sizeof *s);
    FILE *in = fopen(path, "rb");
    if (!in) return dp_fail(err, "%s: cannot read the checkpoint state: %s", path, strerror(errno));
    int version = 0;
    uint64_t bom = 0, checksum = 0;
    size_t plan_bytes = 0, data_bytes = 0;
    int ok = fscanf(in, "dartspp-state %d", &version) == 1 && version == STATE_VERSION &&
             fscanf(in, " byte-order 0x%" SCNx64, &bom) == 1 && bom == byte_order_mark() &&
             fscanf(in, " seed %" SCNu64, &s->seed) == 1 &&
             fscanf(in, " resolution %d %d", &s->width, &s->height) == 2 && s->width > 0 && s->height > 0 &&
             fscanf(in, " frames %d", &s->frames) == 1 && s->frames >= 0 &&
             fscanf(in, " orders %d", &s->orders) == 1 && s->orders >= 0 && s->orders <= 64 &&
             fscanf(in, " passes %ld", &s->passes) == 1 && s->passes >= 0 &&
             fscanf(in, " weight_sum %la", &s->weight_sum) == 1 &&
             fscanf(in, " last_weight %la", &s->last_weight) == 1 &&
             fscanf(in, " nonfinite %ld", &s->nonfinite) == 1 &&
             fscanf(in, " checksum 0x%" SCNx64, &checksum) == 1 &&
             fscanf(in, " plan_bytes %zu", &plan_bytes) == 1 && plan_bytes < (1u << 24) && fgetc(in) == '\n';
    if (ok && (s->plan = malloc(plan_bytes + 1)) != NULL) {
        ok = fread(s->plan, 1, plan_bytes, in) == plan_bytes && fgetc(in) == '\n';
        s->plan[plan_bytes] = '\0';
    } else ok = 0;
    time_window layers = {.frame_count = s->frames, .orders = s->orders};
    size_t n = ok ? gate_count(s->width, s->height) : 0, nf = n * (size_t)time_window_layers(&layers);
    ok = ok && fscanf(in, "data_bytes %zu", &data_bytes) == 1 && fgetc(in) == '\n' &&
         data_bytes == n * sizeof(double) + nf * sizeof(float);
    if (ok && with_data) {
        s->sum = malloc(n * sizeof(double));
        s->frame_sum = nf ? malloc(nf * sizeof(float)) : NULL;
        if (!s->sum || (nf && !s->frame_sum)) {
            fclose(in);
            resume_state_free(s);
            return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory for the checkpoint state", path);
        }
        ok = fread(s->sum, sizeof(double), n, in) == n && (!nf || fread(s->frame_sum, sizeof(float), nf, in) == nf) &&
             fgetc(in) == EOF;
        uint64_t h = fnv1a(0xcbf29ce484222325ULL, s->sum, n * sizeof(double));
        if (ok && nf) h = fnv1a(h, s->frame_sum, nf * sizeof(float));
        if (ok && h != checksum) {
            fclose(in);
            resume_state_free(s);
            return dp_fail(err, "%s: the checkpoint state is damaged (checksum mismatch)", path);
        }
    }
    fclose(in);
    if (!ok) {
        resume_state_free(s);
        return dp_fail(err, "%s: not a dartspp checkpoint state of version %d written on a machine of this byte "
                       "order, or truncated", path, STATE_VERSION);
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

int resume_check(const resume_state *s, const char *path, const render_run_job *j, long spp, dp_error *err)
{
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
    dp_error ignored;
    if (resume_state_read(path, 0, &s, &ignored)) return 0; /* not a state this version reads: replaced */
    long held = s.passes;
    resume_state_free(&s);
    if (held == 0 || (spp > 0 && held <= spp)) return 0;
    char will[96];
    if (spp > 0) snprintf(will, sizeof will, "%ld passes", spp);
    else snprintf(will, sizeof will, "an unknown number of passes (no pass count, only a time budget or none)");
    return dp_fail(err, "%s holds a checkpoint of %ld passes; this run renders %s and would overwrite it: "
                   "--resume continues it, --overwrite replaces it", path, held, will);
}
