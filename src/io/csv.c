/* Frame sidecar CSV: the time window of every frame of a transient sequence, written exactly. */
#include "dartspp/io.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

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
        return dp_fail(err, "%s: invalid frame axis (%d frames, start %g, width %g)", path, frame_count,
                       start, width);
    char tmp[4096];
    int fd = atomic_open(path, tmp, sizeof tmp, err);
    if (fd < 0) return -1;
    int dup_fd = dup(fd);
    FILE *f = dup_fd >= 0 ? fdopen(dup_fd, "w") : NULL;
    if (!f) {
        int e = errno;
        if (dup_fd >= 0) close(dup_fd);
        atomic_abort(fd, tmp);
        return dp_fail(err, "%s: cannot open for writing: %s", path, strerror(e));
    }
    int bad = write_frames(f, frame_count, start, width) != 0 || ferror(f);
    if (fclose(f) != 0) bad = 1;
    if (bad) {
        int e = errno;
        atomic_abort(fd, tmp);
        return dp_fail(err, "%s: write failed: %s", path, strerror(e));
    }
    return atomic_commit(fd, tmp, path, err);
}
