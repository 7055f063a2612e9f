/* Shared helpers for the cmocka tests: temp folders, paths of the shipped scenes, running the CLI. */
#ifndef DARTSPP_TEST_UTIL_H
#define DARTSPP_TEST_UTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

/* The paper's scenes live beside the checkout (../shared), as in CI. */
#define SHARED_SCENES "../shared/scenes/cbox-trans"
/* The sanitized command-line binary built by `make test`. */
#define DARTSPP_BIN "build/san/dartspp"

/* A fresh temp folder for one test; the caller frees the string. */
static inline char *test_tmpdir(void)
{
    char *d = strdup("/tmp/dartspp-test-XXXXXX");
    if (!mkdtemp(d)) { free(d); return NULL; }
    return d;
}

static inline void test_write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* Runs a shell command and returns its exit status (0..255), capturing stderr+stdout into out. */
static inline int test_run(const char *cmd, char *out, size_t out_len)
{
    char full[4096];
    snprintf(full, sizeof full, "%s 2>&1", cmd);
    FILE *p = popen(full, "r");
    if (!p) return -1;
    size_t n = 0;
    if (out && out_len) {
        out[0] = 0;
        n = fread(out, 1, out_len - 1, p);
        out[n] = 0;
    } else {
        char buf[4096];
        while (fread(buf, 1, sizeof buf, p) > 0) {}
    }
    int st = pclose(p);
    return (st >= 0 && WIFEXITED(st)) ? WEXITSTATUS(st) : -1;
}

#endif
