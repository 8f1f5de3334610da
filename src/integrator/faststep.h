/* faststep — one whole fixed step of a small LCS in one function: the free
 * step's affine map with its input integral, the moving offset g = F + G u
 * and the LCP step with its certificates (lcp/step.h), each unrolled for the
 * sizes, which are known at set-up. It is what integrator.c's loop would do
 * for that step, the same arithmetic in the same order (the states, lambda
 * and the certificates are bit for bit the loop's), without the calls,
 * switches and passes through memory between them, and many steps per
 * call: the loop hands over the stretch of steps up to the next one whose
 * end it must see (a sample, its interrupt check, the last step). Taken
 * when the theta step (or the explicit step solved as one) runs on a set of
 * up to CUP_STEP_SMALL_N states and CUP_STEP_SMALL_M rows without D, with
 * no f term, the paper's tolerances (eps_n, eta_n > 0), no step callback
 * (the only reader of pi.scale, which is not computed here) nor step-doubling
 * estimate (which compares every step; integrator.c checks both), and an input
 * of which one component alone moves the state or the set (a switched
 * circuit's gate sources move neither), built from constant, sine and
 * square terms. A step it cannot take as the loop would (NaN, a singular
 * block, an offset that is not finite) it declines, and the loop takes it. */
#ifndef CUP_FASTSTEP_H
#define CUP_FASTSTEP_H

#include "freestep.h"
#include "lcp/step.h"
#include "model/input_impl.h"

#define CUP_FAST_TERMS 8
#define CUP_FAST_AHEAD 16        /* steps whose inputs are computed together */
#define CUP_FAST_DECLINED 1000   /* not a status: the general loop takes the step */
#define CUP_FAST_REFUSED 1001    /* not a status: the sink refused a recorded step's sample */
#define CUP_FAST_DONE 1002       /* not a status: step stop booked and recorded, none pending */

/* A run's records: fixed.c's sink, output every step, and where its loop
 * keeps which multipliers zeta is (1: the LCP step's). */
typedef struct faststep_rec {
  cup_sample_fn sink;
  void *ctx;
  int *zeta_from;
} faststep_rec;

typedef struct faststep_ws {
  int on;
  lcp_step *th;
  /* the free step xf = Phi x + Gam int u, copied from freestep.c's, the
   * states in lanes (util/lanes.h): Phi[j] column j */
  v2d Phi[CUP_STEP_SMALL_N][2], Gam[2];
  int has;                  /* an input enters through E */
  int integrate;            /* ... and is integrated at every step (not constant) */
  double uconst;            /* a constant input's h u */
  /* the input's terms (one component: comp, the one with a column in E or G) */
  int comp, nterms;
  const input_term *term[CUP_FAST_TERMS];
  double term_h[CUP_FAST_TERMS];   /* freestep.c's step-length factors */
  /* the moving offset g = F + G u(t_{k+1}), the rows in lanes */
  v2d g0, gdir;         /* F and G's one column */
  v2l grows;            /* all ones in the lanes of G's rows */
  double *g;                /* the integrator's offset buffer, written at the end of a run */
  int moving;
  int konst;                /* the input the same at every step: its integral uconst, the offset gk */
  v2d gk;
  int key;                  /* the steps' variant: n * 8 + m + 64 konst (dispatch) */
  long (*go)(struct faststep_ws *, long, long, double *, double *, cup_proj_info *, int *, cup_run_info *);
  double eps_n, eta_n;
  long steps;               /* the grid: t_k = k T / steps, step h */
  double T, h;
  /* the square terms' antiderivatives at the last step's end (its start now) */
  double last_t;
  double last_tri[CUP_FAST_TERMS];
  /* a run of steps that left the state's range (CUP_STATE_MAX) is declined
   * whole: the loop takes its steps up to this one itself, checking each */
  long hold;
  /* konst runs give each step's sample to rec.sink themselves (set by the
   * loop before each stretch of its steps) */
  int recording, book_last;   /* book_last: ... and step stop too, when it is the loop's last */
  faststep_rec rec;
} faststep_ws;

/* on = 1 when the steps qualify (the caller checks for a step callback);
 * G: the set's motion, NULL for a fixed set; allocates nothing. */
void faststep_init(faststep_ws *f, const freestep_ws *fs, lcp_step *th, const cup_polyset *K,
                   const la_sparse *G, double *g, int use_theta, double eps_n, double eta_n, long steps,
                   double T);
/* Steps k, k + 1, ... from x: each one before stop that ends CUP_OK is
 * booked in info as cup_integrator_run books it (tally, step, t), its state
 * written into x; the first one that does not, or step stop, is left
 * pending: its state in xnew, its status in *st and *pi (not booked), or
 * *st = CUP_FAST_DECLINED, nothing taken. Returns the pending step's index.
 * The state is checked against its range once, at the end of the run of
 * steps (not in each step, the time loop's cost): when the last booked one
 * is beyond it, nothing is taken (*st = CUP_FAST_DECLINED, k returned) and
 * hold is set to the pending step, so that the loop finds the first state
 * beyond the range itself. Recording (f->recording, a konst run), each
 * booked step's sample goes to rec.sink as the loop gives it, its state
 * checked first (one beyond is declined); a refusal returns the refused
 * step's end, *st = CUP_FAST_REFUSED; with book_last, step stop is booked
 * and recorded as the others, stop + 1 returned, *st = CUP_FAST_DONE. */
long faststep_run(faststep_ws *f, long k, long stop, double *x, double *xnew, cup_proj_info *pi, int *st,
                  cup_run_info *info);

#endif
