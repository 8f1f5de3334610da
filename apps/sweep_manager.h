/* sweep_manager — what rank 0 of catchup-sweep does with jobs and results,
 * MPI aside: the queue of jobs and its batches, the results of a message
 * into the results file at once (src/sweep/sweep_file.c), the tasks' errors
 * against their variant's reference
 * (held in memory until it is known when no trajectories are stored), the
 * regular flush and the progress line. The MPI protocol that brings the
 * results is sweep_mpi.c, the run itself catchup-sweep.c. */
#ifndef CUP_SWEEP_MANAGER_H
#define CUP_SWEEP_MANAGER_H

#include <stddef.h>
#include "sweep_file.h"
#include "util/clock.h"

enum { MAX_BATCH = 1024 };   /* jobs per batch, at most */

/* A result message, from a worker or from rank 0 computing alone: this
 * header, then `count` results (sw_result), each followed by its trajectory
 * (samples * dim doubles), in increasing job order. */
typedef struct {
  int64_t count;
  double cpu;                /* CPU seconds the computing rank spent on these jobs */
} msg_head;

typedef struct held { long task; sw_result r; double *traj; struct held *next; } held;

typedef struct {
  int quiet, log_progress;   /* the command line's --quiet, --log-progress */
  const sw_sweep *s;
  sw_file *f;                /* NULL until open_file made it */
  /* the results file, made once the workers have their first batches
   * (manager_file_ready); NULL: f was open before */
  int (*open_file)(void *ctx, sw_file **f, char *errmsg);
  void *open_ctx;
  long count;                /* samples * dim: the states, what the error measures */
  size_t one;                /* bytes of one job's answer: sw_result + trajectory */
  int max_batch;             /* jobs per batch: MAX_BATCH, fewer for long trajectories */
  long *queue;               /* jobs to dispatch, in order */
  long qhead, qlen;
  double *cost;              /* per job */
  double cost_left, cost_done;  /* work not done yet (queued or out), done */
  double cost_queued;        /* work still in the queue */
  long jobs_total, jobs_done, jobs_skipped, failures, not_certified;
  int workers;               /* ranks computing jobs */
  long rate_jobs;            /* jobs done that the cost model prices (cost > 0) */
  double rate_work, rate_cost;  /* their seconds (each on its rank) and cost units: the ETA's rate */
  double last_done;          /* when the last job came back (the ETA counts down from there) */
  double t_start, last_flush, last_progress, busy;
  double work_sum;           /* seconds of the jobs done, each on its rank's clock */
  double cpu_sum;            /* CPU seconds of the computing ranks in those jobs (msg_head.cpu) */
  double rank_cpu;           /* CPU seconds of every rank in the dispatch (workers' own count) */
  held **held;               /* per variant: results waiting for the reference (no /runs/x) */
  sw_task_out *out;          /* MAX_BATCH: the tasks of a message, written at once */
  int io_status;
  char io_msg[SW_ERR_LEN];
} manager_t;

/* One line "catchup-sweep: ..." on stderr. */
void say(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* The queue (jobs not done yet, in sw_schedule's order: all of them
 * while the file is still to be made) and its costs;
 * CUP_OK or CUP_ERR_NOMEM. free_manager releases what the manager holds. */
int setup_queue(manager_t *m);
void free_manager(manager_t *m);
/* Keep the first failure of the results file (or st, out of memory). */
void io_fail(manager_t *m, int st);
/* The results file before the first result is taken: made (open_file) if
 * it is still to be, its failure kept as io_status (the workers are then
 * stopped); then the errors of tasks written before their reference, in
 * an earlier run. */
void manager_file_ready(manager_t *m);
/* The reference of variant k is known: fill in its tasks' errors. */
void fill_errors(manager_t *m, int k);
/* Every result of one message (msg_head and what follows) into the file. */
void take_message(manager_t *m, const char *buf, size_t size);
/* The next batch for one of `workers` workers into ids; its length. */
int next_batch(manager_t *m, int workers, long *ids);
/* The progress line (final: the last one, always printed unless quiet; none
 * while the results file is not made, nor when it could not be). */
void progress(manager_t *m, int final);
/* Flush the results file every FLUSH_SECONDS (force: now). */
void maybe_flush(manager_t *m, int force);

#endif
