/* splitcheck — the splitting error of the implicit and exponential
 * schemes, estimated a step at a time.
 *
 * Both move by the free step and then project along B = P^-1 C^T: the
 * multiplier acts at the step's end. In the solution it acts throughout
 * the step and the flow carries what it does into the other states: the
 * consistent step corrects along Phi B, Phi = W = (I - h A)^-1 for the
 * implicit scheme (the theta step at theta = 1) and phi_1(hA) = (e^{hA} -
 * I) / (hA) for the exponential one (the flow of a multiplier constant over
 * the step; e^{hA} beyond 128 states, which about doubles the estimate).
 * Where a source drives a blocked diode's state fast (a
 * flyback's leakage inductance) the correction is large and A carries it
 * into the other states: the flyback at n = 20000 lost 1.2 V of its
 * capacitor in each 4 us on-time, first order with a constant of
 * 24 V / (L_leak C). Each step whose projection acted on rows J (lambda > 0)
 * adds the difference between the two corrections of the free point,
 *     delta_k = Phi B_J y - d,  C_J Phi B_J y = C_J d,  d = x_{k+1} - x_free,
 * to an error e that the steps carry as they carry the state, linearized:
 * the free step's linear part (W, or e^{hA}), then the projection onto the
 * rows that acted, e - B_J M_JJ^-1 C_J e. The run compares the largest
 * ||e||_P with the state's largest ||x||_P: an estimate of the first order
 * error the splitting makes, not a bound (the consistent step is first
 * order too; rows that change set within a step are not followed). Small
 * dense sets only (the polyset's dense form: Md and Bt); a row whose Phi b_i
 * stays on b_i's line moves nothing else, and without one the check is off. */
#ifndef CUP_SPLITCHECK_H
#define CUP_SPLITCHECK_H

#include "freestep.h"

/* The estimate above this fraction of the state's largest P-norm warns
 * (CUP_WARN_SPLITTING). */
#define CUP_SPLIT_ERR_WARN 0.05

typedef struct splitcheck {
  int on;                   /* the scheme and the rows can have the defect */
  int n;
  const cup_polyset *K;
  double *buf;              /* everything below, one allocation */
  double *lin;              /* the free step's linear part, n x n column-major */
  double *phib, *g;         /* Phi B (n x m) and C Phi B (m x m) */
  double *blk, *z, *zw;     /* a J x J block, its right-hand side and scratch */
  double *e, *d, *v, *Pv, *w;   /* the error, the step's correction, scratch (n, n, n, n, 2 n) */
  double *P;                /* the metric, n x n, when n is small (else NULL: through the polyset) */
  int *J, *piv;             /* the rows that acted, the block's pivots */
  int live;                 /* e is not 0 */
  double emax, peak;        /* the largest ||e||_P and ||x||_P */
  double eone;              /* merged: the largest of one configuration's emax */
  long worst, first;        /* the step of emax; the first of the last stretch with e > the limit (0: none) */
  double tworst, tfirst;
} splitcheck;

/* Set up for the free step fs (its scheme, h, A) and the polyset K (NULL:
 * off). Off for the explicit and theta schemes (consistent: the multiplier
 * enters where the scheme puts it). Returns CUP_OK or CUP_ERR_NOMEM. */
int splitcheck_init(splitcheck *s, const freestep_ws *fs, const cup_polyset *K, char *errmsg);
void splitcheck_free(splitcheck *s);
/* A run's start: nothing accumulated. */
void splitcheck_reset(splitcheck *s);
/* Step k (ending at t) went from the free point xf to x, lam the
 * projection's multipliers (NULL: none acted). */
void splitcheck_step(splitcheck *s, long k, double t, const double *xf, const double *x, const double *lam);
/* a's estimate with b's (a switched run's configurations: their errors
 * added, each carried through its own windows only). */
void splitcheck_merge(splitcheck *a, const splitcheck *b);
/* At a run's end (n steps of the scheme): when the estimate exceeds the
 * limit, CUP_WARN_SPLITTING into info (an error or a splitting warning
 * already there is kept; another warning keeps its status and gets this
 * message after its own). */
void splitcheck_verdict(const splitcheck *s, int scheme, long n, cup_run_info *info);

#endif
