/* sweep_run — one job of a sweep (sweep.h): a task, or a variant's
 * reference, run by the integrator on the variant's scene and sampled at
 * the common times. Internal to catchup-sweep and the tests. */
#ifndef CUP_SWEEP_RUN_H
#define CUP_SWEEP_RUN_H

#include "sweep.h"

/* The last lazy variant's scene a rank loaded (sw_variant_load), kept for
 * its next job: a variant's tasks go out in one block of ids. */
typedef struct sw_scene_slot {
  int variant;                    /* -1: none */
  cup_scene *scene;
} sw_scene_slot;
void sw_scene_slot_free(sw_scene_slot *slot);

typedef struct sw_run_opts {
  const volatile int *interrupt;  /* the integrator's interrupt flag (signals) */
  cup_step_fn on_step;            /* e.g. polling for a stop message; may be NULL */
  void *step_ctx;
  double task_time_limit;         /* seconds per task (not references); 0: none */
  int inject_fail;                /* make this task fail with CUP_ERR_CALLBACK (tests) */
  sw_scene_slot *slot;            /* a lazy variant's scene kept between jobs; NULL: loaded each time */
} sw_run_opts;

/* Run job `job` (a reference or a task); fills r and traj (samples * dim). */
void sw_run_job(const sw_sweep *s, long job, const sw_run_opts *o, sw_result *r, double *traj);

#endif
