/* The options of a render as a user gives them (`dartspp render --threads 4`, `dartspp.render(threads=4)`):
 * one table, one parser and one range check for both, so that the command line and the Python package refuse
 * the same values with the same message (issue 48: Python rendered with max_memory=-1 that the CLI refused). */
#include <errno.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dartspp/render.h"

typedef enum { OPT_COUNT_OF, OPT_UINT64, OPT_SECONDS, OPT_BYTES } opt_kind;

typedef struct {
    const char *name, *flag; /* the API's keyword and the command line's flag */
    opt_kind kind;
    double lo, hi;           /* the accepted range, inclusive; for OPT_BYTES lo is exclusive */
    const char *expected;    /* the reason of a refusal */
} opt_row;

/* The most threads a render accepts: more than this are no speed-up on any machine this runs on, only memory
 * (per-thread buffers) and scheduling overhead. The largest memory limit: 2^60 bytes (1 EiB), far above any
 * machine; beyond it a limit is a typo (2**70), not a limit. */
#define MAX_THREADS 1024
#define MAX_MEMORY_BYTES 1152921504606846976.0

static const opt_row options[RENDER_OPT_COUNT] = {
    [RENDER_OPT_THREADS] = {"threads", "--threads", OPT_COUNT_OF, 0, MAX_THREADS,
                            "expected a whole number of threads from 0 (all cores) to 1024"},
    [RENDER_OPT_SEED] = {"seed", "--seed", OPT_UINT64, 0, 0,
                         "expected an integer from 0 to 18446744073709551615 (2^64 - 1)"},
    [RENDER_OPT_SPP] = {"spp", "--spp", OPT_COUNT_OF, 0, 9.2233720368547e18,
                        "expected a whole number of passes from 0 to 2^63 - 1"},
    [RENDER_OPT_TIME] = {"time", "--time", OPT_SECONDS, 0, 0, "expected a finite number of seconds >= 0"},
    [RENDER_OPT_CHECKPOINT] = {"checkpoint", "--checkpoint", OPT_SECONDS, 0, 0,
                               "expected a finite number of seconds >= 0 (0: no checkpoints)"},
    [RENDER_OPT_LOG_EVERY] = {"log_every", "--log-every", OPT_SECONDS, 0, 0,
                              "expected a finite number of seconds >= 0 (0: every pass)"},
    [RENDER_OPT_REDUCE_EVERY] = {"reduce_every", "--reduce-every", OPT_SECONDS, 0, 0,
                                 "expected a finite number of seconds >= 0 (0: no periodic reductions)"},
    [RENDER_OPT_MAX_MEMORY] = {"max_memory", "--max-memory", OPT_BYTES, 0, MAX_MEMORY_BYTES,
                               "expected a size above 0 and at most 1 EiB (2^60 bytes), such as 8G, 512M or 1e9"},
};

int render_opt_find(const char *name)
{
    for (int i = 0; name && i < RENDER_OPT_COUNT; i++)
        if (!strcmp(name, options[i].name) || !strcmp(name, options[i].flag)) return i;
    return -1;
}

static int refuse(render_opt o, const char *text, dp_error *err)
{
    return dp_fail(err, "%s (%s) %s: %s", options[o].name, options[o].flag, text ? text : "(none)", options[o].expected);
}

/* digits only: no sign, fraction, exponent or hexadecimal (strtoull would take "-1" and " 7") */
static int whole_number(const char *t, uint64_t *out)
{
    if (!*t) return -1;
    for (const char *p = t; *p; p++)
        if (*p < '0' || *p > '9') return -1;
    char *end;
    errno = 0;
    unsigned long long u = strtoull(t, &end, 10);
    if (*end || errno == ERANGE) return -1;
    *out = u;
    return 0;
}

/* a decimal number (strtod's syntax, "inf" and "nan" included so that the range check names them), then for
 * sizes a binary suffix K, M, G or T */
static int number(const char *t, int suffix, double *out)
{
    char *end;
    double d = strtod(t, &end);
    if (end == t) return -1;
    if (suffix && *end) {
        const char *u = strchr("KMGT", *end);
        if (!u || end[1]) return -1;
        for (const char *p = "KMGT"; p <= u; p++) d *= 1024.0;
        end++;
    }
    if (*end) return -1;
    *out = d;
    return 0;
}

int render_opt_check(render_opt o, double v, const char *text, dp_error *err)
{
    const opt_row *r = &options[o];
    int ok;
    switch (r->kind) {
    case OPT_COUNT_OF: ok = v >= r->lo && v <= r->hi && v == floor(v); break;
    case OPT_UINT64: ok = v >= 0 && v <= 18446744073709551615.0 && v == floor(v); break;
    case OPT_SECONDS: ok = v >= r->lo && isfinite(v); break;
    default: ok = v > r->lo && v <= r->hi; break;
    }
    if (ok) return 0;
    char own[64];
    if (!text) snprintf(own, sizeof own, "%.17g", v);
    return refuse(o, text ? text : own, err);
}

int render_opt_parse(render_opt o, const char *text, render_opt_value *out, dp_error *err)
{
    const opt_row *r = &options[o];
    *out = (render_opt_value){0};
    if (!text) return refuse(o, text, err);
    if (r->kind == OPT_COUNT_OF || r->kind == OPT_UINT64) {
        if (whole_number(text, &out->u)) return refuse(o, text, err);
        if (r->kind == OPT_COUNT_OF && out->u > (uint64_t)r->hi) return refuse(o, text, err);
        out->d = (double)out->u;
        return 0;
    }
    if (number(text, r->kind == OPT_BYTES, &out->d)) return refuse(o, text, err);
    return render_opt_check(o, out->d, text, err);
}
