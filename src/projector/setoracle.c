/* setoracle — the kind oracle of a set projector: the user's projection at
 * the time the set was placed, checked by set/oracle.c, the targets at the
 * scale of x. Nothing to place: the oracle knows its set at t. */
#include "catchup.h"
#include "setproj_impl.h"

static int project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  setproj_targets(sp, cup_polyset_norm(sp->S->K, x), info);
  return oracle_project(sp->S, sp->t, x, z, sp->work, info, sp->message, sizeof sp->message);
}

const setproj_kind setproj_oracle = {.project = project};
