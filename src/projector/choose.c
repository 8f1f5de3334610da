/* choose — the registry of the projector's methods, in the order they are
 * chosen: the first whose `takes` accepts a set and the options projects
 * onto it (as OSQP picks a linear-system solver once at set-up). A new
 * method is its own file with its table, and one line here. */
#include "catchup.h"
#include "choose.h"
#include "small.h"
#include "activeset.h"
#include "newton.h"
#include "firstorder.h"

const proj_method *proj_choose(const cup_polyset *K, const cup_projector_options *o) {
  const proj_method *const methods[] = {
    proj_small,     /* auto, small dense sets: the dual LCP, exactly */
    proj_dense,     /* auto and activeset, small dense sets: the dense active set */
    proj_newton,    /* auto and activeset beyond: projected Newton with a sparse factor */
    proj_pg,        /* the paper's projected gradient */
    proj_fista,     /* FISTA with restart */
  };
  for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++)
    if (methods[k]->takes(K, o)) return methods[k];
  return NULL;
}

int proj_small_lcp(const cup_polyset *K, const cup_projector_options *o) {
  const cup_projector_options defaults = {.method = CUP_PROJ_AUTO};   /* what the choice reads of them */
  return proj_choose(K, o ? o : &defaults) == proj_small;
}

cup_projector_options proj_backup_options(const cup_polyset *K, const cup_projector_options *o) {
  cup_projector_options b = *o;
  if (proj_choose(K, o) == proj_small) b.method = CUP_PROJ_ACTIVESET;   /* proj_dense: small's fallback */
  return b;
}
