/* schemes — the registry of the schemes the options choose from. Internal
 * to the library. */
#ifndef CUP_SCHEMES_H
#define CUP_SCHEMES_H

#include "scheme.h"

/* The scheme for the options (checked: their scheme is one of
 * CUP_SCHEME_LIST). */
const scheme_type *scheme_choose(const cup_integrator_options *o);

#endif
