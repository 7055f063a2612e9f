/* The checkpoint state's lock: two runs resuming (or writing) one state at once would each write their own
 * passes over the other's, and the last to finish would win with the fewer passes. So a run that may write
 * "<stem>.state" first takes an exclusive flock() on "<stem>.state.lock" (not on the state itself: the state
 * is replaced by a rename at every write, and a lock lives on one inode). The lock file holds the holder's
 * process id, for the message of the run refused. The kernel drops a flock when its process dies, so a lock
 * file left by a killed run blocks nothing; the file itself is removed at the end of the run. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "run_internal.h"

/* The process id written in the lock file by its holder, or 0 when unreadable. */
static long holder(int fd)
{
    char buf[32] = {0};
    ssize_t n = pread(fd, buf, sizeof buf - 1, 0);
    long pid = 0;
    if (n > 0 && sscanf(buf, "%ld", &pid) == 1 && pid > 0) return pid;
    return 0;
}

/* Whether fd is still the file at path: the holder before us may have removed it between our open and our
 * flock, and a lock on a removed file guards nothing. */
static int same_file(int fd, const char *path)
{
    struct stat a, b;
    return fstat(fd, &a) == 0 && stat(path, &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

int state_lock_take(const char *lock_path, const char *state_path, int *fd, dp_error *err)
{
    for (int attempt = 0; attempt < 8; attempt++) {
        int f = open(lock_path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (f < 0)
            return dp_fail(err, "%s: cannot create the lock of the checkpoint state %s: %s", lock_path, state_path,
                           strerror(errno));
        if (flock(f, LOCK_EX | LOCK_NB) != 0) {
            int e = errno;
            long pid = e == EWOULDBLOCK ? holder(f) : 0;
            close(f);
            if (e != EWOULDBLOCK)
                return dp_fail(err, "%s: cannot lock the checkpoint state %s: %s", lock_path, state_path, strerror(e));
            char who[64] = "another render";
            if (pid > 0) snprintf(who, sizeof who, "another render (process %ld)", pid);
            return dp_fail(err, "%s is in use: %s renders to this output (its lock %s is held); two runs to one "
                           "output would overwrite each other's images and checkpoint state: wait for it to end, or "
                           "render to another --output", state_path, who, lock_path);
        }
        if (!same_file(f, lock_path)) { /* removed by its last holder meanwhile: take the new one */
            close(f);
            continue;
        }
        char pid[32];
        int n = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
        if (ftruncate(f, 0) != 0 || pwrite(f, pid, (size_t)n, 0) != n) {
            /* the lock holds without the id; only the other run's message loses the process id */
        }
        *fd = f;
        return 0;
    }
    return dp_fail(err, "%s: the lock of the checkpoint state %s keeps changing hands: another render is starting "
                   "and ending on it", lock_path, state_path);
}

void state_lock_release(const char *lock_path, int fd)
{
    unlink(lock_path); /* while still holding it: a run waiting on this file sees it removed (same_file) */
    close(fd);
}
