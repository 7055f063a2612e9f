/* The BSDF checks beyond the quick tier's (tests/bsdf/test_bsdf.c, whose χ² machinery they share): χ² of
 * sampling against the pdf for the plastics (each lobe) and the rough dielectrics from both sides, and no NaN or
 * Inf from any model over a sweep of directions. */
#define BSDF_COATED_AND_DIELECTRIC 1
#include "test_bsdf.c"
