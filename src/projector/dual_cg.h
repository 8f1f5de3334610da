/* dual_cg — v <- (M_FF + delta I)^-1 v on the free rows F (rows outside F
 * unchanged), M = C P^-1 C^T with a diagonal P, by conjugate gradients that
 * apply M through the rows of C without forming it: the dual factor's way
 * when the factor of the free rows outgrows its packed room. */
#ifndef CUP_DUAL_CG_H
#define CUP_DUAL_CG_H

#include "set/polyset_impl.h"

/* w: five m-vectors of scratch; u: n entries, zero in and out. */
void dual_cg(const cup_polyset *K, const unsigned char *act, double delta, double *v,
             double *const w[5], double *u);

#endif
