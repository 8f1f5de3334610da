/* adaptive — the event-driven scheme CUP_SCHEME_ADAPTIVE behind
 * cup_integrator_create/run (integrator.c dispatches here). */
#ifndef CUP_ADAPTIVE_H
#define CUP_ADAPTIVE_H

#include "catchup/integrator.h"

typedef struct cup_adaptive cup_adaptive;

/* Requires a small dense set (K in dense form), no perturbation f, and
 * state plus input generators within the dense limit; errmsg says which
 * does not hold. */
int cup_adaptive_create(cup_adaptive **A, const cup_lcs *L, const cup_input *u,
                        const cup_integrator_options *o, char *errmsg);
void cup_adaptive_free(cup_adaptive **A);
int cup_adaptive_run(cup_adaptive *A, const double *x0, cup_sample_fn sink, void *sink_ctx,
                     cup_run_info *info);
const double *cup_adaptive_state(const cup_adaptive *A);

#endif
