/* schemes — the registry of the integration schemes: the first whose
 * `takes` accepts the options is the integrator's (as the projector's
 * choose.c picks a method). A new scheme is its own file with its table,
 * its name in CUP_SCHEME_LIST (catchup/integrator.h), and one line here. */
#include "catchup.h"
#include "schemes.h"
#include "fixed.h"
#include "adaptive.h"

const scheme_type *scheme_choose(const cup_integrator_options *o) {
  const scheme_type *const schemes[] = {
    scheme_fixed,      /* explicit, implicit, exponential, theta: the catching-up steps on a grid */
    scheme_adaptive,   /* adaptive: the exact flow of each active set, events located */
  };
  for (size_t k = 0; k < sizeof schemes / sizeof schemes[0]; k++)
    if (schemes[k]->takes(o)) return schemes[k];
  return NULL;
}
