/* projector (internal) — what the dispatcher offers the modules built on
 * it (the set projections of setproj.c), beyond the public
 * include/catchup/projector.h. */
#ifndef CUP_PROJECTOR_INTERNAL_H
#define CUP_PROJECTOR_INTERNAL_H

#include "proj_ws.h"
#include "catchup/set.h"
#include "util/ckpt.h"

/* The projector's state between projections, to or from a checkpoint
 * (util/ckpt.h): the offset it holds, its warm start, the anchor of its
 * certificates. What it keeps besides (the dense factors of active sets,
 * the sparse factor) depends on the rows alone and is made again as
 * needed. */
void projector_checkpoint(cup_projector *p, ckpt *c);

/* The values of the (sparse, diagonal-metric) polyset changed in place:
 * forget what depended on them, keep the warm start of rows still on.
 * Allocation-free. */
void projector_revalue(cup_projector *p);

/* cup_project by the exact method whatever the options ask (the method
 * chosen when it is exact: the small LCP with the dense active set behind
 * it, the dense active set, the sparse Newton path; the dense active set
 * beside a first-order method on a dense set), reported as activeset:
 * another method for a step whose answer was not certified (the
 * integrator's fallback, issue 27); the configured one where no exact
 * method was set up (a first-order method on a sparse set).
 * Allocation-free. */
int proj_exact(cup_projector *p, const double *x, double *z, cup_proj_info *info);

/* After the projection z of a step from the state x at t onto a
 * state-dependent set whose rows can be rechecked (a crowd's): 1 when the
 * rows missed a constraint z violates and were built again at (t, x) with
 * it (project the step again), 0 when they missed none (every other kind of
 * set), or an error status (cup_setproj_message says what). */
int setproj_recheck(cup_setproj *sp, double t, const double *x, const double *z);

#endif
