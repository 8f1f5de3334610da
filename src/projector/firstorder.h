/* firstorder — the paper's projected gradient on the dual and FISTA with
 * restart (firstorder.c). Starts from p->lam, b = s(x) in p->b; fills p->lam
 * (>= 0) and p->y = z with certificates in info; stops after `budget`
 * iterations. Returns a status. */
#ifndef CUP_FIRSTORDER_H
#define CUP_FIRSTORDER_H

#include "proj_ws.h"

int cup_proj_firstorder(cup_projector *p, const double *x, int accelerated,
                        int budget, cup_proj_info *info);

#endif
