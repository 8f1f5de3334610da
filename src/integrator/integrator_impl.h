/* integrator_impl — the fixed-step driver's state, shared by integrator.c
 * (set-up, the run) and checkpoint.c (saving and restoring a stopped run).
 * Internal to the library. */
#ifndef CUP_INTEGRATOR_IMPL_H
#define CUP_INTEGRATOR_IMPL_H

#include "catchup.h"
#include "faststep.h"
#include "freestep.h"
#include "estimate.h"
#include "adaptive.h"
#include "lcp/step.h"
#include "util/ckpt.h"

/* Where a run stopped before its end, at a step's end, and how far that
 * step's tail went: a checkpoint resumes from there (cup_integrator_resume). */
enum {
  CUP_STOP_NONE,            /* not stopped, or stopped where it cannot resume (an error) */
  CUP_STOP_SAMPLE_DUE,      /* the step callback stopped it: the step's sample (if selected) is next */
  CUP_STOP_SAMPLE_REFUSED,  /* the sink refused the step's sample: offered again first */
  CUP_STOP_STEP_DONE        /* the interrupt flag or the wall-time limit, after the step's sample */
};

typedef struct cup_ckpt_stop {
  int phase;                /* CUP_STOP_* */
  long k;                   /* the step taken last */
  long next_j;              /* the output schedule's place (samples: the next j) */
  int status;               /* the run's status and message before the stop replaced them */
  char message[CUP_RUN_MSG_LEN];
  int restored;             /* a checkpoint was restored: cup_integrator_resume may run */
  cup_run_info info;        /* the restored run's statistics */
} cup_ckpt_stop;

/* A switched LCS's driver (switched.c), reached through a table: it makes
 * integrators, so integrator.c must not depend on it. */
typedef struct cup_swrun cup_swrun;
typedef struct cup_swops {
  int (*run)(cup_integrator *I, const double *x0, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
  void (*free)(cup_swrun **S);
  const cup_integrator *(*child)(const cup_swrun *S);   /* the configuration in force's integrator */
} cup_swops;

struct cup_integrator {
  const cup_input *u;
  cup_integrator_options o;
  int n, m, p;
  double h, eps_n, eta_n, h_rho, split;
  int split_row;
  /* the set: a polyset is stepped here (K, G, the projector or the LCP
   * step), any other set through its cup_setproj */
  const cup_set *S;
  cup_set *S_own;           /* an LCS's polyset, wrapped */
  const cup_polyset *K;     /* the polyset's rows, or NULL */
  const cup_sparse *G;      /* the offset's motion, or NULL */
  int fixed;                /* the polyset does not move */
  cup_setproj *sp;          /* other sets */
  cup_sparse A_own, E_own;  /* a process's drift (an LCS's is borrowed) */
  const cup_lcs *L;         /* the LCS it was made from (its B and D for the theta step), or NULL */
  cup_freestep fs;
  cup_projector *proj;
  cup_lcp_step th;          /* the theta scheme's LCP step (used instead of the projector) */
  int use_theta;
  cup_adaptive *ad;         /* the adaptive scheme: everything else unused */
  long kend;                /* the run's last step: n, or a switched circuit's window's end */
  long next_j;              /* where the last run left the output samples (a window's next one) */
  cup_swrun *swr;           /* a switched LCS (switched.c): its configurations' integrators */
  const cup_swops *swo;     /* ... and its driver */
  cup_integrator *half;     /* estimate: the same run at n/2 (step doubling), or NULL */
  cup_estimate est;         /* ... and the comparison with it */
  int zeta_from;            /* the last step's multipliers: 0 none yet, 1 theta step, 2 projector,
                               3 zeta_ext (a switched circuit's split step, switched.c) */
  const double *zeta_ext;
  int jump;                 /* x0 was not consistent and the first step is yet to measure the jump */
  cup_faststep fast;        /* a small LCS's whole step in one function, or fast.on = 0 */
  double *x, *xnew, *xf, *g, *ut, *s0, *sg;
  double *v;                /* 2 n: a projection of the step's answer and scratch (certify_or_stop) */
  double *xs, *zprev;       /* a sample between two steps: its x, and zeta at the step before it */
  double zs;                /* ... and its place between them (1: on a step) */
  long rebuilds0;           /* a state polyset's rebuilds before the run */
  double *x0;               /* the estimate's: x0 of the run, for a resumed run's coarse one */
  /* where the last run stopped, for a checkpoint (checkpoint.c) */
  cup_ckpt_stop stop;
};

/* integrator.c: the steps from k0 (the sampler at next_j) to n, as
 * cup_integrator_run takes them after its start (the run's warnings and
 * first sample, the coarse run of the estimate); checkpoint.c resumes
 * through it. */
int cup_integrator_steps_(cup_integrator *I, long k0, long next_j, cup_sample_fn sink, void *sink_ctx,
                          cup_run_info *info);
/* A fixed-step run's window (a switched circuit's stretch in one
 * configuration, switched.c): steps k0 + 1 .. k1 on the run's grid from
 * state x at t_k0 (first: k0 = 0, the run's own start and x0's sample),
 * the samples from *next_j on; *next_j advanced. */
int cup_integrator_window_(cup_integrator *I, long k0, long k1, const double *x, int first, long *next_j,
                           cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* A switched circuit's split step (switched.c): step k - 1 -> k was
 * taken outside, by the configurations' exact flows from xprev (at
 * t_{k-1}) to x (at t_k), zeta its multipliers at t_k (m entries, kept by
 * the caller until the next step). Sets the integrator there and gives
 * step k's end as the loop does: the step callback, the samples due at k
 * (between t_{k-1} and t_k: x interpolated linearly, zeta the step's);
 * *next_j advanced. */
int cup_integrator_split_end_(cup_integrator *I, long k, const double *xprev, const double *x, const double *zeta,
                              long *next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* Its grid's time t_k. */
double cup_integrator_grid_time_(const cup_integrator *I, long k);

#endif
