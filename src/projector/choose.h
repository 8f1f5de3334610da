/* choose — which method projects onto a set (choose.c): the registry of
 * the projector's methods, and the one question the modules above ask of
 * the projector's small-set path, and the options of a projector behind a
 * scheme's own step LCP. */
#ifndef CUP_CHOOSE_H
#define CUP_CHOOSE_H

#include "proj_ws.h"

/* The first method of the registry that takes K with the options o, or
 * NULL (a sparse set without rows, which needs none). */
const proj_method *proj_choose(const cup_polyset *K, const cup_projector_options *o);

/* 1 when projections onto K with the options o (NULL: the defaults) are
 * made by the exact small-set path, the dual LCP of lcp/step.c (W = I,
 * h = 1) solved by principal pivoting: K within the dense limits
 * (m <= 64 rows, dim <= 256, fixed values), the auto method, no feasible
 * point given and none asked for. The projector alone decides this; the
 * schemes whose step is that LCP (the explicit scheme on such a set, the
 * theta scheme for a circuit) ask here. */
int proj_small_lcp(const cup_polyset *K, const cup_projector_options *o);

/* The options of a projector that stands behind a scheme's own step LCP
 * (the theta step, the explicit step where proj_small_lcp says so, the
 * adaptive scheme's projection), for what that LCP cannot certify: where
 * the small-set path would be chosen, the method it falls back to (the
 * dense active set), so that a run builds one LCP; else o itself. */
cup_projector_options proj_backup_options(const cup_polyset *K, const cup_projector_options *o);

#endif
