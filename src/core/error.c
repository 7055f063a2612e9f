/* Error messages: one formatted string carried back to the command line. */
#include "dartspp/core.h"

#include <stdarg.h>
#include <stdio.h>

int dp_fail(dp_error *err, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
    }
    return -1;
}
