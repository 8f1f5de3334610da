/* newton — the exact projection onto large sparse sets by projected Newton
 * on the dual (newton.c). b = s(x) in p->b; fills p->lam (>= 0) and p->y = z
 * with certificates in info. Returns a status. */
#ifndef CUP_NEWTON_H
#define CUP_NEWTON_H

#include "proj_ws.h"

int cup_proj_sparse_newton(cup_projector *p, const double *x, cup_proj_info *info);
/* Its workspace (p->nw) and dual factor; cup_newton_free undoes either. */
int cup_newton_create(cup_projector *p, char *errmsg);
void cup_newton_free(cup_projector *p);

#endif
