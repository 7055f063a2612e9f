/* `dartspp table --sigma-s S --sigma-a A --g G [--shape R,S,C] [--s-max X] [--r-range LO,HI] --output FILE`:
 * builds an EDA table (darts.h) with OpenMP and stores it in our headered format. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "dartspp/cli.h"
#include "dartspp/darts.h"
#include "dartspp/io.h"

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v)) return -1;
    *out = v;
    return 0;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: dartspp table --sigma-s S --sigma-a A --g G [options] --output FILE.bin   (an EDA table)\n"
               "  --sigma-s S       the medium's scattering coefficient (required)\n"
               "  --sigma-a A       its absorption coefficient (required)\n"
               "  --g G             its Henyey-Greenstein g (required)\n"
               "  --shape R,S,C     cells along C/S, S and the cosine (default 128,128,256)\n"
               "  --s-max X         the S range [0, X) (default 16)\n"
               "  --r-range LO,HI   the C/S range (default 0.2,0.999)\n"
               "  --output FILE.bin where the table goes (required)\n"
               "  -h, --help        this text\n");
}

static void progress(void *ctx, int done, int rows)
{
    (void)ctx;
    if (isatty(2)) fprintf(stderr, "\rdartspp table: row %d of %d", done, rows);
}

int cli_table(int argc, char **argv)
{
    double ss = NAN, sa = NAN, g = 0, s_max = 16.0, r_lo = EDA_DEFAULT_R_LO, r_hi = EDA_DEFAULT_R_HI;
    int shape[3] = {128, 128, 256}, have_g = 0;
    const char *out = NULL;
    if (cli_help_asked(argc, argv)) {
        usage(stdout);
        return 0;
    }
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (!v) bad = 1;
        else if (!strcmp(a, "--sigma-s")) bad = parse_double(v, &ss);
        else if (!strcmp(a, "--sigma-a")) bad = parse_double(v, &sa);
        else if (!strcmp(a, "--g")) bad = parse_double(v, &g), have_g = 1;
        else if (!strcmp(a, "--s-max")) bad = parse_double(v, &s_max);
        else if (!strcmp(a, "--r-range")) bad = sscanf(v, "%lf,%lf", &r_lo, &r_hi) != 2;
        else if (!strcmp(a, "--shape")) bad = sscanf(v, "%d,%d,%d", &shape[0], &shape[1], &shape[2]) != 3;
        else if (!strcmp(a, "--output")) out = v;
        else {
            fprintf(stderr, "dartspp table: unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        }
        if (bad) {
            fprintf(stderr, "dartspp table: bad value for %s: '%s'\n", a, v ? v : "(missing)");
            return 2;
        }
        i++;
    }
    if (isnan(ss) || isnan(sa) || !have_g || !out) {
        fprintf(stderr, "dartspp table: --sigma-s, --sigma-a, --g and --output are required\n");
        usage(stderr);
        return 2;
    }
    /* the table is our headered binary format (docs/darts.md §8.3), named .bin like the render's cache: a name of
     * another format (x.exr) would hold what its readers cannot read */
    if (!io_has_extension(out, ".bin")) {
        fprintf(stderr, "dartspp table: --output %s: an EDA table is a binary file of its own format: the name must "
                        "end in .bin\n", out);
        return 2;
    }
    eda_table t;
    dp_error err;
    double t0 = dp_seconds();
    if (eda_table_build(&t, ss, sa, g, shape[0], shape[1], shape[2], s_max, r_lo, r_hi, progress, NULL, &err)) {
        fprintf(stderr, "dartspp table: %s\n", err.msg);
        return 2;
    }
    double secs = dp_seconds() - t0;
    int rc = eda_table_save(&t, out, &err);
    if (isatty(2)) fputc('\n', stderr);
    if (rc) fprintf(stderr, "dartspp table: %s\n", err.msg);
    else fprintf(stderr, "dartspp table: %dx%dx%d built in %.2f s; wrote %s\n", shape[0], shape[1], shape[2], secs, out);
    eda_table_free(&t);
    return rc ? 1 : 0;
}
