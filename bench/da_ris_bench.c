/* DA-RIS micro-benchmark (docs/darts.md §6.5): the time per call of da_sample_distance, and of
 * da_sample_distance_rev (the same file at another revision, renamed by bench/da_ris_bench.sh), on inputs recorded from
 * a render (bench/data/da_inputs_cbox_fog.txt: every 97th call of the DARTS path tracer on the fog Cornell
 * box, scenes/cbox-fog/transient.json at 64², one per line: valid, x, e, C, S_lo, S_hi, T, 1/p(T), S_reach,
 * d, t_max), and how many of the calls draw the medium and fall back.
 *
 *   da_ris_bench INPUTS SIGMA_S SIGMA_A ROUNDS
 *
 * Runs ROUNDS passes over the inputs with one thread, 15 times for each version, alternating (so that a
 * machine shared with other work slows both alike), and prints the best ns per call of each. */
#include "dartspp/darts.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define MAX_INPUTS 100000

typedef struct {
    ellipse_record r;
    vec3 d;
    double tmax;
} da_input;

static int read_inputs(const char *path, da_input *in, int cap)
{
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    int n = 0;
    while (n < cap) {
        da_input *a = &in[n];
        ellipse_record *r = &a->r;
        int k = fscanf(f, "%d %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &r->valid, &r->x.x,
                       &r->x.y, &r->x.z, &r->e.x, &r->e.y, &r->e.z, &r->C, &r->S_lo, &r->S_hi, &r->T, &r->inv_pdf_T,
                       &r->S_reach, &a->d.x, &a->d.y, &a->d.z, &a->tmax);
        if (k != 17) break;
        n++;
    }
    fclose(f);
    return n;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

typedef void (*da_fn)(const medium *, const ellipse_record *, vec3, double, double, dp_rng *, da_sample *);
void da_sample_distance_rev(const medium *m, const ellipse_record *r, vec3 d, double tmax, double defensive,
                            dp_rng *rng, da_sample *out);

/* one timed run: ROUNDS passes over the inputs; the medium and fallback shares into *med, *fb */
static double run(da_fn fn, const medium *m, const da_input *in, int n, int rounds, int rep, double *med, double *fb)
{
    dp_rng rng = rng_stream(7, rep, 0);
    long medium_events = 0, fallbacks = 0;
    double t0 = now(), sink = 0.0;
    for (int k = 0; k < rounds; k++)
        for (int i = 0; i < n; i++) {
            da_sample out;
            fn(m, &in[i].r, in[i].d, in[i].tmax, 0.2, &rng, &out);
            sink += out.t;
            medium_events += out.medium_event;
            fallbacks += out.fallback;
        }
    double dt = (now() - t0) / ((double)rounds * n);
    *med = (double)medium_events / ((double)rounds * n);
    *fb = (double)fallbacks / ((double)rounds * n);
    return sink == -1.0 ? 0.0 : dt;
}

int main(int argc, char **argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: %s INPUTS SIGMA_S SIGMA_A ROUNDS\n", argv[0]);
        return 2;
    }
    da_input *in = malloc(MAX_INPUTS * sizeof *in);
    int n = in ? read_inputs(argv[1], in, MAX_INPUTS) : -1;
    if (n <= 0) {
        fprintf(stderr, "%s: no inputs read\n", argv[1]);
        return 2;
    }
    double ss = atof(argv[2]), sa = atof(argv[3]);
    int rounds = atoi(argv[4]);
    medium m = {.sigma_s = v3s(ss), .sigma_a = v3s(sa), .sigma_t = v3s(ss + sa), .eta = 1.0, .max_bounces = 1000,
                .phase = {PHASE_ISOTROPIC, 0.0, NULL}};
    da_fn fns[2] = {da_sample_distance_rev, da_sample_distance};
    const char *names[2] = {"revision", "working tree"};
    double best[2] = {INFINITY, INFINITY}, med[2], fb[2];
    for (int rep = 0; rep < 15; rep++)
        for (int v = 0; v < 2; v++) {
            double dt = run(fns[v], &m, in, n, rounds, rep, &med[v], &fb[v]);
            if (dt < best[v]) best[v] = dt;
        }
    for (int v = 0; v < 2; v++)
        printf("%-12s %d inputs x %d rounds: %.1f ns per call (best of 15); medium %.3f, fallback %.4f\n", names[v], n,
               rounds, 1e9 * best[v], med[v], fb[v]);
    free(in);
    return 0;
}
