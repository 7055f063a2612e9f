/* tier: stress */
/* tests/derivative/test_deriv_geometry.c with every case (camera x and z, light x and y, the wall, the occluder
 * along y and x) for the plain, DARTS and uniform-time path tracers, 1000–4000 passes per render. */
#define GEO_FULL 1
#include "test_deriv_geometry.c"
