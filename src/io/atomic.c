/* Output files: atomic writes (the data goes to "<path>.tmp.<pid>" in the same folder, is flushed to
 * disk, and then renamed over <path>, so a reader never sees a half-written file), file sets written to a
 * staging folder and moved into place (atomic_set_*), the cleanup of temporary files when a signal ends the
 * process and of those a killed process left behind, and creating the folders outputs go in. */
#include "dartspp/io.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

/* ---- the temporary files and staging folders of writes in progress, for a signal handler ---- */

#define LIVE_SLOTS 4
typedef struct {
    volatile sig_atomic_t used; /* 1: path holds a temporary file, 2: a staging folder */
    char path[4096 + 64];
} live_entry;
static live_entry live[LIVE_SLOTS];
static int live_claimed[LIVE_SLOTS]; /* a slot is taken atomically (two threads may write files at once) */

/* Best effort: with every slot taken the file is not tracked (a signal exit would leave it). */
static void live_add(const char *path, int kind)
{
    if (strlen(path) >= sizeof live[0].path) return;
    for (int i = 0; i < LIVE_SLOTS; i++)
        if (!__atomic_exchange_n(&live_claimed[i], 1, __ATOMIC_ACQ_REL)) {
            strcpy(live[i].path, path);
            __atomic_thread_fence(__ATOMIC_SEQ_CST);
            live[i].used = kind;
            return;
        }
}

static void live_remove(const char *path)
{
    for (int i = 0; i < LIVE_SLOTS; i++)
        if (live[i].used && !strcmp(live[i].path, path)) {
            live[i].used = 0;
            __atomic_store_n(&live_claimed[i], 0, __ATOMIC_RELEASE);
            return;
        }
}

/* Removes the files of a flat folder and the folder, with async-signal-safe system calls only (no
 * opendir/readdir: getdents64 directly). */
struct linux_dirent64 {
    unsigned long long d_ino;
    long long d_off;
    unsigned short d_reclen;
    unsigned char d_type;
    char d_name[];
};

static void remove_flat_dir(const char *dir)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        char buf[8192] __attribute__((aligned(8)));
        for (;;) {
            long n = syscall(SYS_getdents64, fd, buf, sizeof buf);
            if (n <= 0) break;
            for (long off = 0; off < n;) {
                struct linux_dirent64 *d = (struct linux_dirent64 *)(void *)(buf + off);
                if (strcmp(d->d_name, ".") && strcmp(d->d_name, "..")) (void)unlinkat(fd, d->d_name, 0);
                off += d->d_reclen;
            }
        }
        close(fd);
    }
    (void)rmdir(dir);
}

void atomic_cleanup_on_signal(void)
{
    for (int i = 0; i < LIVE_SLOTS; i++) {
        int kind = live[i].used;
        if (kind == 1) (void)unlink(live[i].path);
        if (kind == 2) remove_flat_dir(live[i].path);
    }
}

int atomic_open(const char *path, char *tmp_path, size_t tmp_len, dp_error *err)
{
    int n = snprintf(tmp_path, tmp_len, "%s.tmp.%ld", path, (long)getpid());
    if (n < 0 || (size_t)n >= tmp_len) {
        if (tmp_len) tmp_path[0] = '\0';
        dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: path too long", path);
        return -1;
    }
    live_add(tmp_path, 1);
    int fd = open(tmp_path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) live_remove(tmp_path);
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
    live_remove(tmp_path);
    if (ok) {
        sync_parent_dir(path);
        return 0;
    }
    unlink(tmp_path);
    return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: %s: %s%s", path, what, strerror(e), io_errno_hint(e));
}

void atomic_abort(int fd, const char *tmp_path)
{
    if (fd >= 0) close(fd);
    if (tmp_path && tmp_path[0]) {
        unlink(tmp_path);
        live_remove(tmp_path);
    }
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
        return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: write failed: %s%s", af->path, strerror(e), io_errno_hint(e));
    }
    return atomic_commit(af->fd, af->tmp_path, af->path, err);
}

int atomic_write_text(const char *path, const char *text, dp_error *err)
{
    if (!text) return dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", path);
    atomic_file af;
    FILE *f = atomic_fopen(path, "w", &af, err);
    return f ? atomic_fclose(&af, fprintf(f, "%s\n", text) < 0, err) : -1;
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

const char *io_errno_hint(int e)
{
    return e == EFBIG ? " (the file-size limit of this process: see `ulimit -f`)" : "";
}

/* ---- file sets: all-or-nothing from the reader's side ---- */

static void split_dir(const char *path, char *dir, size_t n, const char **base)
{
    const char *slash = strrchr(path, '/');
    *base = slash ? slash + 1 : path;
    if (!slash) snprintf(dir, n, ".");
    else if (slash == path) snprintf(dir, n, "/");
    else snprintf(dir, n, "%.*s", (int)(slash - path), path);
}

int atomic_set_open(atomic_set *s, const char *stem, dp_error *err)
{
    const char *base;
    split_dir(stem, s->dir, sizeof s->dir, &base);
    int n1 = snprintf(s->base, sizeof s->base, "%s", base);
    int n2 = snprintf(s->stage, sizeof s->stage, "%s/.%s.set.tmp.%ld", s->dir, base, (long)getpid());
    int n3 = snprintf(s->stem, sizeof s->stem, "%s/%s", s->stage, base);
    if (n1 < 0 || n2 < 0 || n3 < 0 || (size_t)n1 >= sizeof s->base || (size_t)n2 >= sizeof s->stage ||
        (size_t)n3 >= sizeof s->stem)
        return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: path too long", stem);
    snprintf(s->manifest, sizeof s->manifest, "%s" ATOMIC_SET_MANIFEST, s->base);
    live_add(s->stage, 2);
    remove_flat_dir(s->stage); /* a folder of a previous process with this pid */
    if (mkdir(s->stage, 0777) != 0) {
        int e = errno;
        live_remove(s->stage);
        return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot create the staging folder %s: %s", stem, s->stage,
                            strerror(e));
    }
    return 0;
}

void atomic_set_abort(atomic_set *s)
{
    remove_flat_dir(s->stage);
    live_remove(s->stage);
}

static int cmp_names(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Moves every file of the folder `from` to s->dir (names sorted, so frames go in order), then removes
 * `from`; wrote() gets each final path. */
static int move_all(const atomic_set *s, const char *from, void (*wrote)(const char *), dp_error *err)
{
    DIR *d = opendir(from);
    if (!d) return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot read: %s", from, strerror(errno));
    size_t n = 0, cap = 64;
    char **names = malloc(cap * sizeof *names);
    int rc = names ? 0 : dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", from);
    for (struct dirent *e; !rc && (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        if (n == cap) {
            char **m = realloc(names, 2 * cap * sizeof *names);
            if (!m) {
                rc = dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", from);
                break;
            }
            names = m;
            cap *= 2;
        }
        if (!(names[n] = strdup(e->d_name))) rc = dp_fail_kind(err, DP_ERROR_MEMORY, "%s: out of memory", from);
        else n++;
    }
    closedir(d);
    if (!rc) qsort(names, n, sizeof *names, cmp_names);
    char src[8400], dst[8400];
    size_t last = n; /* the manifest's index: moved last, its old copy removed first */
    for (size_t i = 0; i < n; i++)
        if (s->manifest[0] && !strcmp(names[i], s->manifest)) last = i;
    if (!rc && last < n) {
        snprintf(dst, sizeof dst, "%s/%s", s->dir, names[last]);
        if (unlink(dst) != 0 && errno != ENOENT)
            rc = dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot remove the old manifest: %s", dst, strerror(errno));
        if (!rc && last != n - 1) { /* to the end of the list */
            char *m = names[last];
            memmove(&names[last], &names[last + 1], (n - 1 - last) * sizeof *names);
            names[n - 1] = m;
        }
        sync_parent_dir(dst);
    }
    for (size_t i = 0; !rc && i < n; i++) {
        snprintf(src, sizeof src, "%s/%s", from, names[i]);
        snprintf(dst, sizeof dst, "%s/%s", s->dir, names[i]);
        if (rename(src, dst) != 0)
            rc = dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot move into place from %s: %s", dst, from,
                              strerror(errno));
        else if (wrote)
            wrote(dst);
    }
    for (size_t i = 0; i < n; i++) free(names[i]);
    free(names);
    if (!rc) {
        rmdir(from);
        sync_parent_dir(dst);
    }
    return rc;
}

int atomic_set_commit(atomic_set *s, void (*wrote)(const char *), dp_error *err)
{
    char commit[sizeof s->stem];
    snprintf(commit, sizeof commit, "%s/.%s.set.commit.%ld", s->dir, s->base, (long)getpid());
    sync_parent_dir(s->stem); /* the staged names are durable before the commit point */
    if (rename(s->stage, commit) != 0) {
        int e = errno;
        atomic_set_abort(s);
        return dp_fail_kind(err, DP_ERROR_OUTPUT, "%s: cannot rename the staging folder %s: %s", s->dir, s->stage,
                            strerror(e));
    }
    live_remove(s->stage); /* from here the commit folder is the journal: a later run completes the move */
    sync_parent_dir(commit);
    return move_all(s, commit, wrote, err);
}

/* ---- what killed processes left behind ---- */

/* The pid at the end of name after `tag` ("<...><tag><digits>"), or 0. */
static long trailing_pid(const char *name, const char *tag)
{
    const char *t = strstr(name, tag), *last = NULL;
    while (t) {
        last = t;
        t = strstr(t + 1, tag);
    }
    if (!last) return 0;
    const char *p = last + strlen(tag);
    char *end;
    if (*p < '1' || *p > '9') return 0;
    long pid = strtol(p, &end, 10);
    return *end == '\0' ? pid : 0;
}

static int pid_alive(long pid) { return pid == (long)getpid() || kill((pid_t)pid, 0) == 0 || errno != ESRCH; }

int atomic_clean_stale(const char *stem, void (*note)(const char *msg))
{
    char dir[4096], msg[9800], path[8400];
    const char *base;
    split_dir(stem, dir, sizeof dir, &base);
    size_t bl = strlen(base);
    char set_prefix[4200];
    snprintf(set_prefix, sizeof set_prefix, ".%s.set.", base);
    DIR *d = opendir(dir);
    if (!d) return 0;
    int found = 0;
    for (struct dirent *e; (e = readdir(d));) {
        const char *nm = e->d_name;
        int is_set = !strncmp(nm, set_prefix, strlen(set_prefix));
        if (!is_set && strncmp(nm, base, bl)) continue;
        long pid = trailing_pid(nm, ".tmp."), commit_pid = is_set ? trailing_pid(nm, ".set.commit.") : 0;
        if (!pid && !commit_pid) continue;
        snprintf(path, sizeof path, "%s/%s", dir, nm);
        found++;
        if (pid_alive(pid ? pid : commit_pid)) {
            snprintf(msg, sizeof msg, "%s belongs to the running process %ld: left alone", path, pid ? pid : commit_pid);
        } else if (commit_pid) {
            atomic_set s = {0};
            dp_error err;
            snprintf(s.dir, sizeof s.dir, "%s", dir);
            snprintf(s.manifest, sizeof s.manifest, "%.*s" ATOMIC_SET_MANIFEST, (int)bl, base);
            if (move_all(&s, path, NULL, &err))
                snprintf(msg, sizeof msg, "%s: a killed run (pid %ld) was moving its files into place; completing "
                         "that failed: %s", path, commit_pid, err.msg);
            else
                snprintf(msg, sizeof msg, "completed the move of the files of a run (pid %ld) killed while moving "
                         "them into place from %s", commit_pid, path);
        } else {
            if (is_set) remove_flat_dir(path);
            else unlink(path);
            snprintf(msg, sizeof msg, "removed %s, left by a run (pid %ld) that ended while writing it", path, pid);
        }
        if (note) note(msg);
    }
    closedir(d);
    return found;
}
