/* integrator_impl — an integrator as the driver holds it (the options, the
 * model, the scheme's table and workspace), shared with checkpoint.c and
 * the schemes' create; and the fixed-step schemes' entry points for a
 * switched circuit's windows (fixed.c, called by switched.c). Internal to
 * the library. */
#ifndef CUP_INTEGRATOR_IMPL_H
#define CUP_INTEGRATOR_IMPL_H

#include "catchup.h"
#include "scheme.h"

struct cup_integrator {
  const scheme_type *sch;   /* the scheme (scheme.h): the driver calls through it */
  void *ws;                 /* ... its workspace */
  const cup_input *u;
  cup_integrator_options o;
  int n, m, p;
  /* the model the front door described (the scheme's create copies what it keeps) */
  const cup_set *S;         /* a process's set, or NULL (an LCS's polyset) */
  const cup_polyset *K;     /* the polyset's rows, or NULL */
  const la_sparse *G;      /* the offset's motion, or NULL */
  int fixed;                /* the polyset does not move */
  la_sparse A_own, E_own;  /* a process's drift (an LCS's is borrowed) */
  const cup_lcs *L;         /* the LCS it was made from, or NULL */
  int restored;             /* a checkpoint was restored: cup_integrator_resume may run */
  cup_run_info *restored_info;   /* ... with the restored run's statistics: the first restore's
                               allocation, else NULL (inline, 1.2 KB that every integrator carried
                               zeroed: a switched run's each configuration's, made in the run) */
};

/* cup_integrator_create whose adaptive scheme takes its run scratch from
 * *scratch (adaptive.h, adaptive_scratch: a switched run's configurations
 * share one; NULL: its own). Other schemes ignore it. */
struct adaptive_scratch;
int integrator_create_shared(cup_integrator **out, const cup_lcs *L, const cup_input *u,
                             const cup_integrator_options *opt, struct adaptive_scratch **scratch, char *errmsg);

/* A fixed-step run's window (a switched circuit's stretch in one
 * configuration, switched.c): steps k0 + 1 .. k1 on the run's grid from
 * state x at t_k0 (first: k0 = 0, the run's own start and x0's sample),
 * the samples from *next_j on; *next_j advanced. hold: a switching at
 * t_k1 follows, the samples on t_k1 are held back for integrator_held. */
int integrator_window(cup_integrator *I, long k0, long k1, const double *x, int first, int hold, long *next_j,
                      cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* After a window that stopped (integrator_window < 0): 1 when it stopped
 * right after its last step k1 (the interrupt, the wall-time limit), the
 * samples it held on t_k1 then still to be given; *next_j, where its
 * samples stopped. */
int integrator_window_reached(const cup_integrator *I, long k1, long *next_j);
/* The wall-time limit of I's next runs (seconds; 0: none), through its
 * scheme's table: each run starts its clock afresh, so a caller running I
 * many times under one limit gives each run what is left (a switched
 * run's windows, switched.c; a steady state's period runs, pss.c). */
void integrator_wall_limit(cup_integrator *I, double seconds);
/* A switched circuit's split step (switched.c): step k - 1 -> k was
 * taken outside, piece after piece, by the configurations' exact flows,
 * the state jumping at each switching time between. A piece before the
 * last ends at tb < t_k with x (before the jump there), zeta its
 * multipliers there (m entries, kept by the caller while it runs), and
 * started at ta from xa (x_{k-1}, or the state after the jump at ta):
 * integrator_split_piece gives the samples in it, times before tb (those a
 * rounding short of it are tb's: the next piece's), x interpolated
 * linearly between its ends, never across a jump, from I, the
 * configuration in force on it; *next_j advanced. */
int integrator_split_piece(cup_integrator *I, long k, double ta, const double *xa, double tb, const double *x,
                           const double *zeta, long *next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* The last piece, from (ta, xa) to x at t_k, zeta at t_k: sets the
 * integrator there and gives step k's end as the loop does: the step
 * callback, the samples due at k (those before t_k interpolated in the
 * piece, as above; the pieces before gave theirs already); hold as
 * integrator_window's. */
int integrator_split_end(cup_integrator *I, long k, double ta, const double *xa, const double *x, const double *zeta,
                         int hold, long *next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* The time of output sample j, or INFINITY when none is due there (all
 * given, or not a run on samples). */
double integrator_sample_time(const cup_integrator *I, long j);
/* A switched circuit's jump at grid time t_k (switched.c): x, the state
 * after it, given to the sink as a second record at t_k (the first was
 * the step's end, before the jump); zeta as at a run's start (theta's LCP
 * at x, else 0). No step callback. */
int integrator_jump_sample(cup_integrator *I, long k, const double *x, cup_sample_fn sink, void *sink_ctx,
                           cup_run_info *info);
/* The samples on t_k held back by a window's or a split step's hold, after
 * the switching there: x, the state after its jump, given from I (the
 * configuration in force from t_k on) with zeta as at a run's start (the
 * right limit, as the adaptive scheme's samples at a switching time); x
 * NULL: from I as the window left it (the run stopped before the
 * switching), as the window would have given them. *next_j advanced. */
int integrator_held(cup_integrator *I, long k, const double *x, long *next_j, cup_sample_fn sink, void *sink_ctx,
                    cup_run_info *info);
/* A switched run's splitting check (splitcheck.h) over its configurations'
 * fixed-step integrators (child[0..count), NULL where none): reset at the
 * run's start; at its end, their sums together against the run's largest
 * state, the warning into info. */
void integrator_split_reset(cup_integrator *const *child, int count);
void integrator_split_verdict(cup_integrator *const *child, int count, cup_run_info *info);
/* Its grid's time t_k, and its step h = T / n. */
double integrator_grid_time(const cup_integrator *I, long k);
double integrator_grid_step(const cup_integrator *I);

#endif
