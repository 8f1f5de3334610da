/* crowd_log — what catchup-run keeps of a crowd scene's run besides /t and
 * /x: per step the agents inside, the rows and active contacts, the
 * certified (eps, eta), the smallest gap, the projector's work, the
 * seconds and the contacts the rows missed (added, then projected again);
 * at the end the exit times, radii and walls (docs/crowd.md). */
#ifndef CUP_CROWD_LOG_H
#define CUP_CROWD_LOG_H

#include "catchup.h"
#include "catchup/h5run.h"

typedef struct crowd_log crowd_log;

/* Bytes the log keeps (and writes) per step: 11 float64 columns. */
#define CROWD_LOG_STEP_BYTES 88

/* Room for n steps; NULL when out of memory. */
crowd_log *crowd_log_create(cup_crowd *c, long n);
void crowd_log_free(crowd_log **L);
/* A cup_step_fn (ctx: the log). */
int crowd_log_step(long k, double t, const cup_proj_info *pi, void *ctx);
/* Write /crowd/radius, /crowd/walls and the attribute agents (before the run). */
int crowd_log_begin(crowd_log *L, cup_h5run *w);
/* Write /crowd/exit_time and /steps/... (steps 0..last, last the steps taken),
 * with q the final state. */
int crowd_log_write(crowd_log *L, cup_h5run *w, long last, const double *q);
/* "1000 agents, 1000 out (last at t = 201.3), ..." into buf. */
void crowd_log_summary(const crowd_log *L, char *buf, size_t size);
/* 1 and a message naming the step, its time and the overlap when a state
 * written overlaps beyond the eta certified by the step that made it (the
 * worst one), else 0. */
int crowd_log_overlap(const crowd_log *L, char *buf, size_t size);

#endif
