/* Background commands for the command-line tests: see child_process.h. */
#include "child_process.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>

double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

void child_start(child *c, const char *dir, const char *const *argv, const char *tmpdir, long fsize_limit)
{
    snprintf(c->log, sizeof c->log, "%s/render.log", dir);
    c->pid = fork();
    assert_true(c->pid >= 0);
    if (c->pid == 0) {
        int fd = open(c->log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd < 0) _exit(127);
        dup2(fd, 1);
        dup2(fd, 2);
        if (tmpdir) setenv("TMPDIR", tmpdir, 1);
        if (fsize_limit > 0) {
            struct rlimit rl = {(rlim_t)fsize_limit, (rlim_t)fsize_limit};
            if (setrlimit(RLIMIT_FSIZE, &rl) != 0) _exit(126);
        }
        execv(argv[0], (char *const *)argv);
        _exit(127);
    }
}

int child_wait(child *c, double bound, double *waited)
{
    double t0 = now_s();
    int st, rc = 0;
    for (;;) {
        pid_t r = waitpid(c->pid, &st, WNOHANG);
        if (r == c->pid) break;
        if (now_s() - t0 > bound) {
            kill(c->pid, SIGKILL);
            waitpid(c->pid, &st, 0);
            rc = -1;
            break;
        }
        usleep(5000);
    }
    if (waited) *waited = now_s() - t0;
    if (rc) return rc;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return strdup("");
    char *buf = calloc(1 << 20, 1);
    size_t n = buf ? fread(buf, 1, (1 << 20) - 1, f) : 0;
    (void)n;
    fclose(f);
    return buf;
}

int log_wait_for(const child *c, const char *what, double bound)
{
    double t0 = now_s();
    while (now_s() - t0 < bound) {
        char *t = read_text(c->log);
        int found = strstr(t, what) != NULL;
        free(t);
        if (found) return 1;
        usleep(20000);
    }
    return 0;
}

void print_tail(const char *what)
{
    size_t n = strlen(what);
    const char *t = n > 700 ? what + n - 700 : what;
    print_message("%s%s", t, n && what[n - 1] == '\n' ? "" : "\n");
}

int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}
