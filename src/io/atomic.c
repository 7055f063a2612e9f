/* Output files: atomic writes (the data goes to "<path>.tmp.<pid>" in the same folder, is flushed to
 * disk, and then renamed over <path>, so a reader never sees a half-written file) and creating the
 * folders they go in. */
#include "dartspp/io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int atomic_open(const char *path, char *tmp_path, size_t tmp_len, dp_error *err)
{
    int n = snprintf(tmp_path, tmp_len, "%s.tmp.%ld", path, (long)getpid());
    if (n < 0 || (size_t)n >= tmp_len) {
        if (tmp_len) tmp_path[0] = '\0';
        dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: path too long", path);
        return -1;
    }
    int fd = open(tmp_path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot open for writing: %s", path, strerror(errno));
    return fd;
}

/* Best effort: make the rename itself durable by syncing the folder that holds the file. */
static void sync_parent_dir(const char *path)
{
    const char *slash = strrchr(path, '/');
    char dir[4096];
    if (!slash) {
        strcpy(dir, ".");
    } else {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        if (n >= sizeof dir) return;
        memcpy(dir, path, n);
        dir[n] = '\0';
    }
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;
    (void)fsync(fd);
    close(fd);
}

int atomic_commit(int fd, const char *tmp_path, const char *path, dp_error *err)
{
    const char *what = "cannot flush to disk";
    int ok = fsync(fd) == 0;
    int e = errno;
    if (close(fd) != 0 && ok) {
        ok = 0;
        e = errno;
        what = "cannot close";
    }
    if (ok && rename(tmp_path, path) != 0) {
        ok = 0;
        e = errno;
        what = "cannot rename the temporary file into place";
    }
    if (ok) {
        sync_parent_dir(path);
        return 0;
    }
    unlink(tmp_path);
    return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: %s: %s", path, what, strerror(e));
}

void atomic_abort(int fd, const char *tmp_path)
{
    if (fd >= 0) close(fd);
    if (tmp_path && tmp_path[0]) unlink(tmp_path);
}

FILE *atomic_fopen(const char *path, const char *mode, atomic_file *af, dp_error *err)
{
    af->path = path;
    af->f = NULL;
    af->fd = atomic_open(path, af->tmp_path, sizeof af->tmp_path, err);
    if (af->fd < 0) return NULL;
    int dup_fd = dup(af->fd);
    af->f = dup_fd >= 0 ? fdopen(dup_fd, mode) : NULL;
    if (!af->f) {
        int e = errno;
        if (dup_fd >= 0) close(dup_fd);
        atomic_abort(af->fd, af->tmp_path);
        dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot open for writing: %s", path, strerror(e));
    }
    return af->f;
}

int atomic_fclose(atomic_file *af, int failed, dp_error *err)
{
    int bad = failed || ferror(af->f);
    if (fclose(af->f) != 0) bad = 1;
    af->f = NULL;
    if (bad) {
        int e = errno;
        atomic_abort(af->fd, af->tmp_path);
        return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: write failed: %s", af->path, strerror(e));
    }
    return atomic_commit(af->fd, af->tmp_path, af->path, err);
}

void atomic_fabort(atomic_file *af)
{
    if (af->f) fclose(af->f);
    af->f = NULL;
    atomic_abort(af->fd, af->tmp_path);
}

/* mkdir of one prefix of the path; an existing folder is fine. */
static int mkdir_one(const char *dir, const char *path, dp_error *err)
{
    struct stat st;
    if (mkdir(dir, 0777) == 0) return 0;
    int e = errno;
    if (e == EEXIST && stat(dir, &st) == 0 && S_ISDIR(st.st_mode)) return 0;
    if (e == EEXIST) e = ENOTDIR;
    return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot create folder %s: %s", path, dir, strerror(e));
}

int io_make_parent_dirs(const char *path, dp_error *err)
{
    const char *slash = strrchr(path, '/');
    if (!slash || slash == path) return 0;
    char *dir = strndup(path, (size_t)(slash - path));
    if (!dir) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    int rc = 0;
    for (char *p = dir + 1; rc == 0; ++p) {
        if (*p != '/' && *p != '\0') continue;
        char c = *p;
        *p = '\0';
        if (p[-1] != '/') rc = mkdir_one(dir, path, err);
        *p = c;
        if (c == '\0') break;
    }
    free(dir);
    return rc;
}
