/* newton — the exact projection onto large sparse sets by projected Newton
 * on the dual (newton.c). b = s(x) in p->b; fills p->lam (>= 0) and p->y = z
 * with certificates in info. Returns a status. */
#ifndef CUP_NEWTON_H
#define CUP_NEWTON_H

#include "proj_ws.h"

/* C's values changed (cup_projector_revalue): recheck what depends on M's signs. */
void cup_newton_revalue(cup_projector *p);
/* The cold start of the sparse exact path for a Stieltjes M = C P^-1 C^T
 * (projected Newton from lam = 0 otherwise): its multipliers for the point
 * x, below lam*, on the active set once its free set settles. Returns the
 * number of solves it made, 0 (lam untouched) when the set does not take
 * this start. For the tests. */
int cup_newton_cold_start(cup_projector *p, const double *x, double *lam);
int cup_proj_sparse_newton(cup_projector *p, const double *x, cup_proj_info *info);
/* Its workspace (p->nw) and dual factor; cup_newton_free undoes either. */
int cup_newton_create(cup_projector *p, char *errmsg);
void cup_newton_free(cup_projector *p);

#endif
