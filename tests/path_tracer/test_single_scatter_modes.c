/* tier: stress */
/* The path tracer's single-scattering cases beyond the quick tier's (tests/path_tracer/test_single_scatter.c,
 * whose quadratures and checks they share): the plain path tracer under HG with η = 4/3 (gated) and backward HG
 * (steady state), the DARTS and uniform-time path tracers under HG with η = 4/3, box pulses, camera-unwarped
 * time, the sensor's time response and the order-1 layer of bounce_orders. */
#define SINGLE_SCATTER_MODES 1
#include "test_single_scatter.c"
