/* sweep_steady — steady-state sweeps (docs/sweep-format.md, "Steady-state
 * sweeps"): each task solves its variant's periodic steady state (cup_pss,
 * the scene's steady_state: request; a netlist's switches run through the
 * switched integrator) and measures one period of it; /steady_state holds
 * one row per task, written before its /summary row (as /crowd), so that a
 * row marked done in /summary still means a complete task. Between the
 * results file's layout (sweep_h5.h) and the job and file writers above.
 * Internal. */
#ifndef CUP_SWEEP_STEADY_H
#define CUP_SWEEP_STEADY_H

#include "sweep_h5.h"

#define SW_STEADY_REFERENCE "none: each task's steady state and its period's figures are in /steady_state"

/* A variant's reference job: nothing to compute (NaN, CUP_OK). */
void sw_steady_no_reference(const sw_sweep *s, sw_result *r, double *traj);
/* A task: the steady state of v's scene with the task's integrator options
 * o (scheme, n, tol, the wall-time limit, the interrupt flag), then one
 * period sampled and measured; fills r (status, message, r->steady, wall). */
void sw_steady_run(const sw_sweep *s, const sw_variant *v, const cup_integrator_options *o, sw_result *r);

/* /steady_state in the results file: created with every task's pending
 * row; the rows of tasks t[0..count) written (staged in f->ssrows, ids in
 * f->ids), before their /summary rows. */
int sw_steady_create(sw_file *f);
int sw_steady_write(sw_file *f, const sw_task_out *t, long count);

#endif
