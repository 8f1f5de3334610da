/* record — a record's signals from the scheme's own state (integrator.c,
 * through the scheme's table): the adaptive scheme's samples inside a step
 * are a linear function of the step's flow state y, and so are x, u and
 * zeta there, so a map of signals over (x, u, zeta) composed with them once
 * per active set is one sum a signal at each sample (adaptive_sample.c).
 * For catchup-run's sink, in place of cup_integrator_zeta and
 * cup_netlist_signals (which return the same to rounding). Internal. */
#ifndef CUP_RECORD_H
#define CUP_RECORD_H

#include "catchup.h"
#include "model/signal_map.h"

/* Called inside the sink: S's signals at the sample it was given into out
 * (S->ns) and 1; 0 when the scheme cannot say here (the caller computes
 * them itself: a fixed-step scheme, a step's end, the first sample, an
 * input of the signals the scheme's exosystem does not hold, no memory). */
int integrator_record(const cup_integrator *I, const signal_map *S, double *out);

#endif
