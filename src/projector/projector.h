/* projector (internal) — what the dispatcher offers the modules built on
 * it (the set projections of setproj.c), beyond the public
 * include/catchup/projector.h. */
#ifndef CUP_PROJECTOR_INTERNAL_H
#define CUP_PROJECTOR_INTERNAL_H

#include "proj_ws.h"

/* The values of the (sparse, diagonal-metric) polyset changed in place:
 * forget what depended on them, keep the warm start of rows still on.
 * Allocation-free. */
void cup_projector_revalue(cup_projector *p);

#endif
