/* fixed_output — the fixed-step schemes' output samples and the cause of
 * a stop, shared by fixed.c (the run on the grid) and fixed_window.c (a
 * switched circuit's windows and split steps), and the run's entry points
 * that the windows take. Internal to the library. */
#ifndef CUP_FIXED_OUTPUT_H
#define CUP_FIXED_OUTPUT_H

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include "catchup.h"
#include "fixed_impl.h"
#include "fixed_setup.h"
#include "tally.h"

static inline double grid_time(const fixed_ws *F, long k) { return tally_grid_time(k, F->o.n, F->o.T, F->h); }

/* The output: every k-th step, the last, none; or samples at
 * tau_j = output_t0 + j (T - output_t0) / (N - 1), each due at kdue, the
 * first step that reaches it: on a step (aligned: that step's state, as it
 * always was) or between two (interpolated linearly, the scheme's own
 * order at most two: x and zeta both). */
typedef struct { long next_j, kdue; int aligned; double tau; } sampler;

static inline void sampler_next(const fixed_ws *F, sampler *sp) {
  const cup_integrator_options *o = &F->o;
  long S = o->output_samples, n = o->n, j = sp->next_j;
  if (o->output != CUP_OUTPUT_SAMPLES || j >= S) { sp->kdue = LONG_MAX; return; }
  double t0 = o->output_t0;
  sp->tau = j == S - 1 ? o->T : t0 + (o->T - t0) * (double)j / (double)(S - 1);
  long k;
  if (t0 == 0 && S > 1 && S < (1L << 31) && n < (1L << 31)) {
    /* on a step when k (S - 1) = j n exactly, in integers, for k = llround(tau / h): that is when
     * S - 1 divides j n, and then llround gives k = j n / (S - 1) (tau / h is within a few ulps
     * of it, k < 2^31), so the remainder decides, in 64 bits, without llround's call a sample */
    long jn = j * n;
    sp->aligned = jn % (S - 1) == 0;
    k = sp->aligned ? jn / (S - 1) : (long)ceil(sp->tau / F->h);
  } else {
    k = (long)llround(sp->tau / F->h);
    if (t0 == 0) sp->aligned = (__int128)k * (S - 1) == (__int128)j * n;   /* exactly, in integers */
    else sp->aligned = grid_time(F, k) == sp->tau;
    if (!sp->aligned) k = (long)ceil(sp->tau / F->h);
  }
  if (k < 0) k = 0;
  if (k > n) k = n;
  sp->kdue = k;
}

static inline int selected(const fixed_ws *F, sampler *sp, long k) {
  const cup_integrator_options *o = &F->o;
  switch (o->output) {
    case CUP_OUTPUT_EVERY: return o->output_every == 1 || k % o->output_every == 0 || k == o->n;   /* 1: no division */
    case CUP_OUTPUT_FINAL: return k == o->n;
    case CUP_OUTPUT_NONE:
    case CUP_OUTPUT_TOL: return 0;                 /* (refused by options_check) */
    case CUP_OUTPUT_SAMPLES: return sp->kdue <= k;
  }
  return 0;
}

/* The samples due at step k (x_k in F->x, x_{k-1} in F->xnew): on the step,
 * or interpolated between the two; in a split step's piece (piece: F->x
 * and F->xnew its ends, at F->piece.ta and .tb), those before its cut,
 * interpolated between the piece's ends (never across a jump). */
static inline int emit_in(fixed_ws *F, sampler *sp, long k, int piece,
                          cup_sample_fn sink, void *ctx, cup_run_info *info) {
  while (selected(F, sp, k) && !(sp->aligned && F->hold && k == F->kend)) {   /* (held: integrator_held) */
    if (piece && !(sp->tau < F->piece.cut)) break;
    const double *x = F->x;
    double t = grid_time(F, k);
    if (!sp->aligned && k > 0) {
      double t_prev = piece ? F->piece.ta : grid_time(F, k - 1), t_end = piece ? F->piece.tb : t;
      double s = (sp->tau - t_prev) / (t_end - t_prev);
      if (s < 1) {
        for (int i = 0; i < F->n; i++) F->xs[i] = F->xnew[i] + s * (F->x[i] - F->xnew[i]);
        x = F->xs;
        F->zs = s;
      }
      t = sp->tau;
    }
    info->samples++;
    int stopped = sink(k, t, x, ctx);
    F->zs = 1;
    if (stopped) return 1;
    sp->next_j++;
    sampler_next(F, sp);
  }
  return 0;
}

static inline int emit_samples(fixed_ws *F, sampler *sp, long k, cup_sample_fn sink, void *ctx, cup_run_info *info) {
  return emit_in(F, sp, k, 0, sink, ctx, info);
}

/* After the samples of step k: zeta_k kept when the next sample falls
 * between steps k and k + 1 (its zeta is interpolated from it). */
static inline void keep_zeta(fixed_ws *F, const sampler *sp, long k) {
  if (!sp->aligned && k + 1 == sp->kdue && F->zprev) fixed_zeta(F, F->zprev);
}

/* The cause of a stop, whole: the message's prefix "step K (t = T): " takes
 * at most 5 + 20 + 6 + 24 + 3 characters, the rest of CUP_RUN_MSG_LEN is
 * the cause's (fixed.c's what[WHAT_LEN] buffers). */
enum { WHAT_LEN = CUP_RUN_MSG_LEN - 64 };

static inline int stop_at(cup_run_info *info, int status, long k, double t, const char *what) {
  info->status = status;
  snprintf(info->message, sizeof info->message, "step %ld (t = %.17g): %s", k, t, what);
  return status;
}

/* fixed.c: the run from x0 (the scheme table's run), the steps from k0
 * with the sampler at next_j to F->kend, g = F + G u(t) for a moving
 * polyset, and the support of the theta step's last zeta (a bit a row). */
int fixed_run(void *ws, const double *x0, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
int fixed_steps(fixed_ws *F, long k0, long next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
int fixed_moving_offset(fixed_ws *F, double t);
unsigned long long fixed_theta_support(const fixed_ws *F);

#endif
