/* integrator_impl — an integrator's state: the driver's (the options, the
 * model, the scheme's table and workspace) and the fixed-step schemes'
 * (fixed.c, fixed_setup.c, whose workspace is the integrator itself),
 * shared with checkpoint.c and switched.c. Internal to the library. */
#ifndef CUP_INTEGRATOR_IMPL_H
#define CUP_INTEGRATOR_IMPL_H

#include "catchup.h"
#include "faststep.h"
#include "freestep.h"
#include "estimate.h"
#include "scheme.h"
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

typedef struct integrator_ckpt_stop {
  int phase;                /* CUP_STOP_* */
  long k;                   /* the step taken last */
  long next_j;              /* the output schedule's place (samples: the next j) */
  int status;               /* the run's status and message before the stop replaced them */
  char message[CUP_RUN_MSG_LEN];
  int restored;             /* a checkpoint was restored: cup_integrator_resume may run */
  cup_run_info info;        /* the restored run's statistics */
} integrator_ckpt_stop;

struct cup_integrator {
  const scheme_type *sch;   /* the scheme (scheme.h): the driver calls through it */
  void *ws;                 /* ... its workspace (the fixed-step schemes': this integrator) */
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
  const la_sparse *G;      /* the offset's motion, or NULL */
  int fixed;                /* the polyset does not move */
  cup_setproj *sp;          /* other sets */
  la_sparse A_own, E_own;  /* a process's drift (an LCS's is borrowed) */
  const cup_lcs *L;         /* the LCS it was made from (its B and D for the theta step), or NULL */
  /* the fixed-step schemes' (fixed_setup.c, fixed.c) from here on, with
   * h .. split_row above; the other schemes keep theirs in their workspace */
  freestep_ws fs;
  cup_projector *proj;
  lcp_step th;          /* the theta scheme's LCP step (used instead of the projector) */
  int use_theta;
  long kend;                /* the run's last step: n, or a switched circuit's window's end */
  long next_j;              /* where the last run left the output samples (a window's next one) */
  cup_integrator *half;     /* estimate: the same run at n/2 (step doubling), or NULL */
  estimate_ws est;         /* ... and the comparison with it */
  int zeta_from;            /* the last step's multipliers: 0 none yet, 1 theta step, 2 projector,
                               3 zeta_ext (a switched circuit's split step, switched.c) */
  const double *zeta_ext;
  int jump;                 /* x0 was not consistent and the first step is yet to measure the jump */
  faststep_ws fast;        /* a small LCS's whole step in one function, or fast.on = 0 */
  double *x, *xnew, *xf, *g, *ut, *s0, *sg;
  double *v;                /* 2 n: a projection of the step's answer and scratch (certify_or_stop) */
  double *xs, *zprev;       /* a sample between two steps: its x, and zeta at the step before it */
  double zs;                /* ... and its place between them (1: on a step) */
  long rebuilds0;           /* a state polyset's rebuilds before the run */
  double *x0;               /* the estimate's: x0 of the run, for a resumed run's coarse one */
  /* where the last run stopped, for a checkpoint (checkpoint.c) */
  integrator_ckpt_stop stop;
};

/* A fixed-step run's window (a switched circuit's stretch in one
 * configuration, switched.c): steps k0 + 1 .. k1 on the run's grid from
 * state x at t_k0 (first: k0 = 0, the run's own start and x0's sample),
 * the samples from *next_j on; *next_j advanced. */
int integrator_window(cup_integrator *I, long k0, long k1, const double *x, int first, long *next_j,
                      cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* A switched circuit's split step (switched.c): step k - 1 -> k was
 * taken outside, by the configurations' exact flows from xprev (at
 * t_{k-1}) to x (at t_k), zeta its multipliers at t_k (m entries, kept by
 * the caller until the next step). Sets the integrator there and gives
 * step k's end as the loop does: the step callback, the samples due at k
 * (between t_{k-1} and t_k: x interpolated linearly, zeta the step's);
 * *next_j advanced. */
int integrator_split_end(cup_integrator *I, long k, const double *xprev, const double *x, const double *zeta,
                         long *next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* Its grid's time t_k. */
double integrator_grid_time(const cup_integrator *I, long k);

#endif
