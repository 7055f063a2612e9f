/* Photon points' single scattering beyond the quick tier's (tests/photon_points/test_photon_single_scatter.c,
 * whose quadrature and checks it shares): camera-unwarped time, baseline and DARTS with sphere control
 * vertices. */
#define SINGLE_SCATTER_MODES 1
#include "test_photon_single_scatter.c"
