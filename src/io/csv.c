/* Frame sidecar CSV: the time window of every frame of a transient sequence, written exactly. */
#include "dartspp/io.h"

#include <stdio.h>

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
