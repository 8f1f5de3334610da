/* fixed_window — a switched circuit's windows under a fixed-step scheme
 * (switched.c drives them): a window of grid steps from a configuration's
 * state after a jump, the pieces of a step split by a switching time (each
 * by its configuration's exact flow, its samples from the piece's ends),
 * the step at a switching whose samples wait for the jump, and the sample
 * right after a jump. The steps themselves are fixed.c's. */
#include <float.h>
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "integrator_impl.h"
#include "lcp/step.h"
#include "projector/projector.h"
#include "util/linalg.h"
#include "fixed_impl.h"
#include "fixed_output.h"

double integrator_grid_time(const cup_integrator *I, long k) { return grid_time(I->ws, k); }

double integrator_grid_step(const cup_integrator *I) { return ((const fixed_ws *)I->ws)->h; }

/* A window's (or a split step's) statistics, from nothing. */
static void window_info(const fixed_ws *F, cup_run_info *info) {
  memset(info, 0, sizeof *info);
  info->err_est = NAN;
  info->eps_target = F->eps_n;
  info->eta_target = F->eta_n;
  info->h_rho = F->h_rho;
}

/* The theta step's start at t_k from F->x: zeta_k by the LCP there (0
 * with D = 0), its support's weights. */
static void theta_start(fixed_ws *F, long k) {
  int fixed = F->fixed || !F->u;
  const double *g = !fixed && fixed_moving_offset(F, grid_time(F, k)) == CUP_OK ? F->g : F->K->g0;
  lcp_step_start(&F->th, F->x, g);
}

int integrator_window(cup_integrator *I, long k0, long k1, const double *x, int first, int hold, long *next_j,
                      cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  fixed_ws *F = I->ws;
  F->stop.phase = CUP_STOP_NONE;                 /* (integrator_window_reached reads its stop) */
  F->kend = k1;
  F->hold = hold;
  F->window = 1;
  int st;
  if (first) {
    st = fixed_run(F, x, sink, sink_ctx, info);
  } else {                                         /* as a run starts, at t_k0 (no x0 checks: the jump was the model's) */
    window_info(F, info);
    memcpy(F->x, x, sizeof(double) * (size_t)F->n);
    memcpy(F->xnew, x, sizeof(double) * (size_t)F->n);   /* x_{k-1} of a sample between t_k0 and t_k0+1 */
    int fixed = F->fixed || !F->u;
    F->zeta_from = 0;
    F->jump = 0;
    F->zs = 1;
    if (F->zprev) la_zero(F->zprev, F->m);
    if (F->K && fixed) cup_projector_set_offset(F->proj, F->K->g0);
    if (F->K && F->use_theta) theta_start(F, k0);  /* theta's zeta_k0 at the window's start */
    F->restart = F->K && F->use_theta && F->th.D && F->th.theta < 1;   /* ... its mode checked (restart_again) */
    if (F->restart) F->mode0 = fixed_theta_support(F);
    st = fixed_steps(F, k0, *next_j, sink, sink_ctx, info);
  }
  *next_j = F->next_j;
  F->kend = F->o.n;
  F->hold = F->window = 0;
  return st;
}

int integrator_window_reached(const cup_integrator *I, long k1, long *next_j) {
  const fixed_ws *F = I->ws;
  if (F->stop.phase != CUP_STOP_NONE) *next_j = F->stop.next_j;
  return F->stop.phase == CUP_STOP_STEP_DONE && F->stop.k == k1;
}

/* The samples due at the end of step k outside the loop (a split step's
 * last piece's, a held one's): as the loop gives them. */
static int step_samples(fixed_ws *F, sampler *sp, long k, int piece, cup_sample_fn sink, void *sink_ctx,
                        cup_run_info *info) {
  const cup_integrator_options *o = &F->o;
  double t = grid_time(F, k);
  if (sink && o->output == CUP_OUTPUT_SAMPLES) {
    if (piece ? emit_in(F, sp, k, 1, sink, sink_ctx, info) : emit_samples(F, sp, k, sink, sink_ctx, info))
      return stop_at(info, CUP_ERR_INTERRUPTED, k, t, "stopped by the output sink");
    keep_zeta(F, sp, k);
  } else if (sink && selected(F, sp, k) && !(F->hold && k == F->kend)) {
    info->samples++;
    if (sink(k, t, F->x, sink_ctx)) return stop_at(info, CUP_ERR_INTERRUPTED, k, t, "stopped by the output sink");
  }
  return CUP_OK;
}

/* A split step's piece in I, from (ta, xa) to (tb, x) with zeta its
 * multipliers, no jump inside it: x the state there (x_k for the last). */
static void piece_set(fixed_ws *F, double ta, const double *xa, double tb, const double *x, const double *zeta) {
  memcpy(F->x, x, sizeof(double) * (size_t)F->n);
  memcpy(F->xnew, xa, sizeof(double) * (size_t)F->n);
  F->zeta_from = 3;
  F->zeta_ext = zeta;
  F->zs = 1;
  if (F->zprev) memcpy(F->zprev, zeta, sizeof(double) * (size_t)F->m);   /* zeta: the piece's, at every sample in it */
  F->piece.ta = ta;
  F->piece.tb = tb;
  F->piece.cut = INFINITY;
}

int integrator_split_piece(cup_integrator *I, long k, double ta, const double *xa, double tb, const double *x,
                           const double *zeta, long *next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  fixed_ws *F = I->ws;
  window_info(F, info);
  info->step = k - 1;
  info->t = tb;
  piece_set(F, ta, xa, tb, x, zeta);
  F->piece.cut = tb - 8 * DBL_EPSILON * fabs(tb);   /* (a sample time a rounding short of tb: tb's, the next piece's) */
  sampler sp = {*next_j, 0, 0, 0};
  sampler_next(F, &sp);
  int st = CUP_OK;
  if (emit_in(F, &sp, k, 1, sink, sink_ctx, info)) st = stop_at(info, CUP_ERR_INTERRUPTED, k - 1, tb,
                                                                "stopped by the output sink");
  *next_j = sp.next_j;
  return st;
}

double integrator_sample_time(const cup_integrator *I, long j) {
  sampler sp = {j, 0, 0, 0};
  sampler_next(I->ws, &sp);
  return sp.kdue == LONG_MAX ? INFINITY : sp.tau;
}

int integrator_split_end(cup_integrator *I, long k, double ta, const double *xa, const double *x, const double *zeta,
                         int hold, long *next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  fixed_ws *F = I->ws;
  const cup_integrator_options *o = &F->o;
  double t = grid_time(F, k);
  window_info(F, info);
  info->step = k;
  info->t = t;
  piece_set(F, ta, xa, t, x, zeta);                /* the last piece: from the last switching time to t_k */
  sampler sp = {*next_j, 0, 0, 0};
  sampler_next(F, &sp);
  cup_proj_info pi = {0};
  int st = CUP_OK;
  if (o->on_step && o->on_step(k, t, &pi, o->step_ctx)) {
    st = stop_at(info, CUP_ERR_INTERRUPTED, k, t, "stopped by the step callback");
  } else {
    F->kend = k;                                   /* (emit_samples' hold) */
    F->hold = hold;
    st = step_samples(F, &sp, k, 1, sink, sink_ctx, info);
    F->kend = F->o.n;
    F->hold = 0;
  }
  *next_j = sp.next_j;
  return st;
}

/* The state x after a switching's jump at t_k, as a run's start has it:
 * zeta theta's LCP at x, else 0. */
static void jumped_to(fixed_ws *F, long k, const double *x) {
  memcpy(F->x, x, sizeof(double) * (size_t)F->n);
  F->zeta_from = 0;
  F->zs = 1;
  if (F->K && F->use_theta) {
    theta_start(F, k);
    F->zeta_from = 1;
  }
}

int integrator_jump_sample(cup_integrator *I, long k, const double *x, cup_sample_fn sink, void *sink_ctx,
                           cup_run_info *info) {
  fixed_ws *F = I->ws;
  double t = grid_time(F, k);
  window_info(F, info);
  info->step = k;
  info->t = t;
  jumped_to(F, k, x);
  info->samples++;
  if (sink(k, t, F->x, sink_ctx)) return stop_at(info, CUP_ERR_INTERRUPTED, k, t, "stopped by the output sink");
  return CUP_OK;
}

int integrator_held(cup_integrator *I, long k, const double *x, long *next_j, cup_sample_fn sink, void *sink_ctx,
                    cup_run_info *info) {
  fixed_ws *F = I->ws;
  window_info(F, info);
  info->step = k;
  info->t = grid_time(F, k);
  if (x) jumped_to(F, k, x);
  sampler sp = {*next_j, 0, 0, 0};
  sampler_next(F, &sp);
  int st = step_samples(F, &sp, k, 0, sink, sink_ctx, info);
  *next_j = sp.next_j;
  return st;
}
