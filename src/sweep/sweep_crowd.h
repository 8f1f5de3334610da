/* sweep_crowd — sweeps whose variants are crowd: scenes
 * (docs/sweep-format.md, "Crowd sweeps"): what differs from circuits, in
 * one place. A crowd has no reference, its tasks are watched for their
 * smallest gap and their evacuation, and /crowd holds one row per task.
 * Between the results file's layout (sweep_h5.h) below and the job and the
 * file's writers above. Internal. */
#ifndef CUP_SWEEP_CROWD_H
#define CUP_SWEEP_CROWD_H

#include "sweep_h5.h"

/* A crowd variant's reference job: nothing to compute (NaN, CUP_OK). */
void sw_crowd_no_reference(const sw_sweep *s, sw_result *r, double *traj);

/* Watches a crowd task's run: the smallest gap of its states (the step
 * callback, chained to the one already in o), then its evacuation. */
typedef struct sw_crowd_watch {
  cup_crowd *c;
  double min_gap;
  cup_step_fn next;
  void *next_ctx;
} sw_crowd_watch;
void sw_crowd_watch_begin(sw_crowd_watch *w, cup_crowd *c, cup_integrator_options *o);
void sw_crowd_watch_end(sw_crowd_watch *w, const double *q_end, sw_result *r);

/* /crowd in the results file: created with every task's pending row; the
 * rows of tasks t[0..count) written (staged in f->crows, ids in f->ids),
 * before their /summary rows. */
#define SW_CROWD_REFERENCE "none: the variants are crowds; each task's evacuation is in /crowd"
int sw_crowd_create(sw_file *f);
int sw_crowd_write(sw_file *f, const sw_task_out *t, long count);

#endif
