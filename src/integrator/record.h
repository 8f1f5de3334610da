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

/* count samples of step k with their signals, in order (catchup-run's
 * writer): times t (count), states x (count x n, row-major) and signals
 * sig by columns, signal j's count values at sig + j stride (stride >=
 * count: the writer's columns, a copy each). Returns how many it took,
 * the first ones; the one after them (if fewer than count) is refused,
 * as a sink's nonzero return refuses its sample, and the later ones were
 * not offered. */
typedef int (*record_put_fn)(void *ctx, long k, int count, const double *t, const double *x, const double *sig,
                             int stride);

/* From the next run or resume on, the samples whose signals I's scheme
 * knows from its own state (integrator_record's) go to put with nl's
 * signals (nl_signal_map's, the configuration in force) in batches, the
 * sink's context its context; the others to the sink, which computes them
 * itself. The same samples, signals and refusals as the sink alone gives,
 * in order, without two calls a sample: the adaptive scheme's samples
 * inside a step and at its ends (count 1), a switched run's under it too
 * (its windows whose sink is the user's) (NULL put: none). 1 if the
 * scheme takes it, else 0 (every sample to the sink); CUP_ERR_NOMEM. */
int integrator_set_put(cup_integrator *I, cup_netlist *nl, record_put_fn put);

#endif
