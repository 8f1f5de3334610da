/* activeset — the exact dual active-set method for small dense sets
 * (activeset.c), falling back to FISTA. b = s(x) in p->b; fills p->lam (>= 0)
 * and p->y = z with certificates in info. Returns a status. */
#ifndef CUP_ACTIVESET_H
#define CUP_ACTIVESET_H

#include "proj_ws.h"

int cup_proj_dense_activeset(cup_projector *p, const double *x, cup_proj_info *info);

#endif
