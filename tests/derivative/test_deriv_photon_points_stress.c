/* tier: stress */
/* tests/derivative/test_deriv_photon_points.c with the passes that separate the derivative images' tiles
 * (path tracer 4000, photon points 300 per render): the same cases, about 10× the default tier's work. */
#define PP_STRESS_BUILD 1
#define PT_PASSES 4000
#define PP_PASSES 300
#include "test_deriv_photon_points.c"
