/* fixed_impl — the fixed-step schemes' workspace, behind their entry of the
 * scheme table (fixed.c runs it, fixed_setup.c sets it up): the model as
 * the driver handed it over, the grid, the free step, the projector or the
 * exact LCP step, the buffers, the estimate's run at n/2 and where the last
 * run stopped. Internal to the library. */
#ifndef CUP_FIXED_IMPL_H
#define CUP_FIXED_IMPL_H

#include "catchup.h"
#include "faststep.h"
#include "freestep.h"
#include "estimate.h"
#include "splitcheck.h"
#include "lcp/step.h"

/* Where a run stopped before its end, at a step's end, and how far that
 * step's tail went: a checkpoint resumes from there (cup_integrator_resume). */
enum {
  CUP_STOP_NONE,            /* not stopped, or stopped where it cannot resume (an error) */
  CUP_STOP_SAMPLE_DUE,      /* the step callback stopped it: the step's sample (if selected) is next */
  CUP_STOP_SAMPLE_REFUSED,  /* the sink refused the step's sample: offered again first */
  CUP_STOP_STEP_DONE        /* the interrupt flag or the wall-time limit, after the step's sample */
};

typedef struct fixed_stop {
  int phase;                /* CUP_STOP_* */
  long k;                   /* the step taken last */
  long next_j;              /* the output schedule's place (samples: the next j) */
  int status;               /* the run's status and message before the stop replaced them */
  char message[CUP_RUN_MSG_LEN];
} fixed_stop;

typedef struct fixed_ws fixed_ws;
struct fixed_ws {
  const cup_input *u;
  cup_integrator_options o; /* the integrator's (the estimate's: at n/2) */
  int n, m, p;
  double h, eps_n, eta_n, h_rho, split;
  int split_row;
  /* the set: a polyset is stepped here (K, G, the projector or the LCP
   * step), any other set through its cup_setproj */
  const cup_set *S;
  cup_set *S_own;           /* an LCS's polyset, wrapped */
  const cup_polyset *K;     /* the polyset's rows, or NULL */
  const la_sparse *G;      /* the offset's motion, or NULL */
  int *gterms, ngterms;     /* the input's terms with a column in G, when others have none (else NULL) */
  int fixed;                /* the polyset does not move */
  cup_setproj *sp;          /* other sets */
  const cup_lcs *L;         /* the LCS it was made from (its B and D for the theta step), or NULL */
  freestep_ws fs;
  cup_projector *proj;
  lcp_step th;          /* the theta scheme's LCP step (used instead of the projector) */
  int use_theta;
  long kend;                /* the run's last step: n, or a switched circuit's window's end */
  int hold;                 /* a switching at t_kend: its samples on t_kend held back (integrator_held) */
  long next_j;              /* where the last run left the output samples (a window's next one) */
  fixed_ws *half;           /* estimate: the same run at n/2 (step doubling), or NULL */
  estimate_ws est;         /* ... and the comparison with it */
  int zeta_from;            /* the last step's multipliers: 0 none yet, 1 theta step, 2 projector,
                               3 zeta_ext (a switched circuit's split step, switched.c) */
  const double *zeta_ext;
  int jump;                 /* x0 was not consistent and the first step is yet to measure the jump */
  int restart;              /* theta with D: a window's first step, its end's support against mode0 (fixed.c) */
  unsigned long long mode0; /* ... the support of zeta at the window's start */
  int restart_iters;        /* ... the pivots of its solves before the last */
  faststep_ws fast;        /* a small LCS's whole step in one function, or fast.on = 0 */
  splitcheck chk;          /* implicit, exponential: the splitting error a step at a time, or chk.on = 0 */
  int window;               /* a switched run's window: its run judges the splitting (switched.c) */
  double *x, *xnew, *xf, *g, *ut, *s0, *sg;
  double *v;                /* 2 n: a projection of the step's answer and scratch (certify_or_stop) */
  double *xs, *zprev;       /* a sample between two steps: its x, and zeta at the step before it */
  double zs;                /* ... and its place between them (1: on a step) */
  struct {                  /* a split step's piece (switched.c): its samples between its own ends, */
    double ta, tb, cut;     /* xnew at ta (after the jump there) and x at tb (before the next one); those
                               before cut alone (at and after a switching time: the next piece's) */
  } piece;
  long rebuilds0;           /* a state polyset's rebuilds before the run */
  double *x0;               /* the estimate's: x0 of the run, for a resumed run's coarse one */
  fixed_stop stop;          /* where the last run stopped, for a checkpoint (checkpoint.c) */
};

#endif
