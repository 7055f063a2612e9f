/* DA-RIS micro-benchmark (docs/darts.md §6.5): the time per call of da_sample_distance on inputs recorded from
 * a render (bench/data/da_inputs_cbox_fog.txt: every 97th call of the DARTS path tracer on the fog Cornell
 * box, scenes/cbox-fog/transient.json at 64², one per line: valid, x, e, C, S_lo, S_hi, T, 1/p(T), S_reach,
 * d, t_max), and how many of the calls draw the medium and fall back.
 *
 *   da_ris_bench INPUTS SIGMA_S SIGMA_A ROUNDS
 *
 * Runs ROUNDS passes over the inputs with one thread, 5 times, and prints the best ns per call. */
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
    double best = INFINITY, sink = 0.0;
    long medium_events = 0, fallbacks = 0;
    for (int rep = 0; rep < 5; rep++) {
        dp_rng rng = rng_stream(7, rep, 0);
        medium_events = fallbacks = 0;
        double t0 = now();
        for (int k = 0; k < rounds; k++)
            for (int i = 0; i < n; i++) {
                da_sample out;
                da_sample_distance(&m, &in[i].r, in[i].d, in[i].tmax, 0.2, &rng, &out);
                sink += out.t + out.weight.x;
                medium_events += out.medium_event;
                fallbacks += out.fallback;
            }
        double dt = (now() - t0) / ((double)rounds * n);
        if (dt < best) best = dt;
    }
    long calls = (long)rounds * n;
    printf("%d inputs, %ld calls: %.1f ns per call (best of 5); medium %.3f, fallback %.4f (checksum %.6g)\n", n, calls,
           1e9 * best, (double)medium_events / calls, (double)fallbacks / calls, sink);
    free(in);
    return 0;
}
