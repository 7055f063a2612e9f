/* The geometry of Liu et al. 2022's temporally sliced photon primitives: its types, functions and conventions
 * moved to the module's public header (include/dartspp/sliced_primitives.h) so that the tests can reach them;
 * this file keeps every name of the first version working for the code that includes it. */
#ifndef DARTSPP_SLICE_GEOMETRY_H
#define DARTSPP_SLICE_GEOMETRY_H

#include "dartspp/sliced_primitives.h"

#endif
