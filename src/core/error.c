/* Error messages: one formatted string and its kind, carried back to the command line. */
#include "dartspp/core.h"

#include <stdarg.h>
#include <stdio.h>

static int fail(dp_error *err, dp_error_kind kind, const char *fmt, va_list ap)
{
    if (err) {
        err->kind = kind;
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    }
    return -1;
}

int dp_fail(dp_error *err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail(err, DP_ERROR_INPUT, fmt, ap);
    va_end(ap);
    return -1;
}

int dp_fail_kind(dp_error *err, dp_error_kind kind, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail(err, kind, fmt, ap);
    va_end(ap);
    return -1;
}

int dp_exit_status(dp_error_kind kind)
{
    switch (kind) {
    case DP_ERROR_INPUT: return 2;
    case DP_ERROR_INTERRUPTED: return 130;
    case DP_ERROR_LOST: return 4;
    case DP_ERROR_OUTPUT:
    case DP_ERROR_MEMORY:
    case DP_ERROR_RANK:
    case DP_ERROR_INTERNAL: break;
    }
    return 1;
}
