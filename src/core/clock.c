/* Wall-clock time for budgets and stage timings. */
#include "dartspp/core.h"

#include <time.h>

double dp_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
