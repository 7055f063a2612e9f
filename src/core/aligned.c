/* Storage on cache lines for data that threads write side by side (core.h). */
#include <stdlib.h>
#include <string.h>

#include "dartspp/core.h"

void *dp_calloc_cache_aligned(size_t n, size_t size)
{
    if (n == 0 || size == 0 || size > (SIZE_MAX - DP_CACHE_LINE) / n) return NULL;
    size_t bytes = (n * size + DP_CACHE_LINE - 1) / DP_CACHE_LINE * DP_CACHE_LINE;
    void *p = aligned_alloc(DP_CACHE_LINE, bytes);
    if (p) memset(p, 0, bytes);
    return p;
}
