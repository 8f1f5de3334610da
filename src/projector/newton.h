/* newton — the exact projection onto large sparse sets by projected Newton
 * on the dual (newton.c): the method proj_newton. */
#ifndef CUP_NEWTON_H
#define CUP_NEWTON_H

#include "proj_ws.h"

extern const proj_method *const proj_newton;

/* The cold start of the sparse exact path for a Stieltjes M = C P^-1 C^T
 * (projected Newton from lam = 0 otherwise): its multipliers for the point
 * x, below lam*, on the active set once its free set settles. Returns the
 * number of solves it made, 0 (lam untouched) when the set does not take
 * this start or the projector has no sparse exact path. For the tests. */
int newton_cold_start(cup_projector *p, const double *x, double *lam);

#endif
