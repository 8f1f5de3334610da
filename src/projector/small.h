/* small — the exact path for small dense sets: the dual LCP by principal
 * pivoting (small.c), the method proj_small, falling back to the dense
 * active set. */
#ifndef CUP_SMALL_H
#define CUP_SMALL_H

#include "proj_ws.h"

extern const proj_method *const proj_small;

#endif
