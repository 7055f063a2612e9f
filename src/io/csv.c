/* Frame sidecar CSV: the time window of every frame of a transient sequence, written exactly. */
#include "dartspp/io.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static int write_frames(FILE *f, int frame_count, double start, double width)
{
    int ok = fprintf(f, "index,start,end\n") > 0;
    for (int k = 0; ok && k < frame_count; ++k)
        ok = fprintf(f, "%d,%.17g,%.17g\n", k, start + k * width, start + (k + 1) * width) > 0;
    return ok ? 0 : -1;
}

int frames_csv_write(const char *path, int frame_count, double start, double width, dp_error *err)
{
    if (frame_count < 0 || !isfinite(start) || !isfinite(width))
        return dp_fail_kind(err, DP_ERROR_INTERNAL,
                            "%s: invalid frame axis (%d frames, start %g, width %g)", path, frame_count,
                       start, width);
    atomic_file af;
    FILE *f = atomic_fopen(path, "w", &af, err);
    if (!f) return -1;
    return atomic_fclose(&af, write_frames(f, frame_count, start, width) != 0, err);
}

int frames_csv_read(const char *path, double *start, double *end, int max, int *count, dp_error *err)
{
    FILE *f = fopen(path, "r");
    if (!f) return dp_fail(err, "%s: cannot open the frames' time axis: %s", path, strerror(errno));
    char line[256];
    int n = 0, rc = 0;
    if (!fgets(line, sizeof line, f) || strncmp(line, "index,start,end", 15)) {
        rc = dp_fail(err, "%s: line 1 is not the header \"index,start,end\"", path);
    }
    while (!rc && fgets(line, sizeof line, f)) {
        int k;
        double a, b;
        if (line[0] == '\n' || line[0] == 0) continue;
        if (sscanf(line, "%d,%lf,%lf", &k, &a, &b) != 3 || k != n || !isfinite(a) || !isfinite(b) || !(b > a))
            rc = dp_fail(err, "%s: line %d: expected \"%d,START,END\" with START < END", path, n + 2, n);
        else if (n >= max)
            rc = dp_fail(err, "%s: more than %d frames", path, max);
        else
            start[n] = a, end[n] = b, n++;
    }
    fclose(f);
    *count = n;
    return rc;
}
