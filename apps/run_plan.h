/* run_plan — what a run will do, known before its first step: the steps it
 * takes, the samples it stores and the bytes they take, checked against the
 * step limit (the scene key max_steps, --max-steps) and the free space of
 * the output's device (CUP_H5_SPACE_MARGIN kept beside it). Shared by
 * catchup-run (one run) and catchup-sweep (every task and reference). */
#ifndef CUP_RUN_PLAN_H
#define CUP_RUN_PLAN_H

#include <stddef.h>
#include "catchup.h"

typedef struct run_plan {
  double steps;        /* fixed-step schemes: n (x 1.5 with the step-doubling estimate's run at n/2);
                          NAN for the adaptive scheme, which chooses its own */
  double samples;      /* rows of /t and /x, the stop's flagged row included; NAN when not known before
                          the run (the adaptive scheme storing every K-th of its steps) */
  double bytes;        /* what the file takes (NAN with samples) */
} run_plan;

/* The plan of a run with options o: states of dimension dim, nsig signals
 * per sample, per_step bytes logged per step (a crowd's /steps). */
void run_plan_make(run_plan *p, const cup_integrator_options *o, int dim, int nsig, double per_step);
/* 1, with a one-line message in msg, when a fixed-step run takes more than
 * max_steps steps; `n_from` says where n came from ("the scene's n",
 * ".tran 1f 1k ..."), `adaptive` how to ask for the adaptive scheme
 * ("--scheme adaptive --tol 1e-6"). 0 otherwise. */
int run_plan_too_long(const run_plan *p, const cup_integrator_options *o, long max_steps, const char *n_from,
                      const char *adaptive, char *msg, size_t size);
/* 1, with the numbers in msg, when `bytes` (a planned file's size) and the
 * margin do not fit the free space of the device that will hold out. */
int run_plan_no_room(double bytes, const char *out, char *msg, size_t size);

#endif
