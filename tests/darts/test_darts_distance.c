/* DA distance sampling beyond the quick tier's case (tests/darts/test_darts.c, whose quadratures and checks
 * they share): infinite t_max, coloured σ, a barely reachable window, a thick medium, refractive index. */
#define DARTS_DISTANCE 1
#include "test_darts.c"
