/* activeset — the exact dual active-set method for small dense sets
 * (activeset.c), falling back to FISTA: the method proj_dense. */
#ifndef CUP_ACTIVESET_H
#define CUP_ACTIVESET_H

#include "proj_ws.h"

extern const proj_method *const proj_dense;

#endif
