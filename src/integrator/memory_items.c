/* The items of a memory estimate (integrator.h). */
#include "dartspp/integrator.h"

void memory_item_add(memory_estimate *m, const char *what, const char *key, double bytes)
{
    if (m->count < MEMORY_ITEMS_MAX) m->item[m->count++] = (memory_item){what, key, bytes};
    m->total += bytes;
}
