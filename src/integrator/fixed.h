/* fixed — the fixed-step schemes (explicit, implicit, exponential, theta)
 * as one entry of the scheme table (scheme.h). Internal to the library. */
#ifndef CUP_FIXED_H
#define CUP_FIXED_H

#include "scheme.h"

extern const scheme_type *const scheme_fixed;

#endif
