/* adaptive_run — the run of the event-driven scheme (adaptive_impl.h,
 * docs/adaptive.md): steps of the exact flow that end on the input's
 * breakpoints (the output times inside them: adaptive_sample.c), events
 * located inside them, the certified projection or the jump where the
 * state is inconsistent, the error estimate carried along, and a stopped
 * run resumed (adaptive_ckpt.c saves and restores it). Allocates nothing. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include "catchup.h"
#include "adaptive.h"
#include "adaptive_impl.h"
#include "projector/projector.h"
#include "tally.h"
#include "util/clock.h"

/* The run's helpers that a switched converter calls once or twice a window
 * (the breakpoint's check, the choice of the set, the output, ...): inlined
 * in their few callers, where GCC kept them out of line and their calls'
 * register saves and restores were a fifth to a half of each. */
#define RUN_INLINE static inline __attribute__((always_inline))

/* Callback inputs: the interpolation error of a step may take this share of
 * tol (the exact flow has none of its own). */
#define AD_STEP_SHARE 0.1

/* The first warning is kept (status and message), as in the fixed-step run. */
__attribute__((format(printf, 3, 4)))
static void warn(ad_run *R, int status, const char *fmt, ...) {
  if (R->info->status != CUP_OK) return;
  R->info->status = status;
  va_list ap;
  va_start(ap, fmt);
  ad_say(R, fmt, ap);
  va_end(ap);
}

/* The absolute error target at the state x. */
static double tolw(const adaptive_ws *A, const double *x) {
  return A->o.tol_abs + A->o.tol_rel * la_norm_inf(x, A->n);
}

/* Where the next step must end at the latest: a breakpoint, T, or t + hlim
 * (hlim within hmax); with to_samples, an output time too (catching-up
 * steps: the other steps' samples come from their exact flow, emit_dense). */
static double next_stop(const adaptive_ws *A, const ad_run *R, double hlim, int to_samples) {
  double s = la_fmin(R->tb, A->tend);
  if (to_samples && A->o.output == CUP_OUTPUT_SAMPLES && R->next_sample < A->o.output_samples)
    s = la_fmin(s, ad_sample_time(A, R->next_sample));
  if (A->o.hmax > 0) hlim = la_fmin(hlim, A->o.hmax);
  return R->t + hlim < s ? R->t + hlim : s;
}

static double estimate_now(const adaptive_ws *A, const ad_run *R) {
  return la_norm_inf(A->e, A->n) + R->rloc + sqrt(R->r2);
}

/* A stop at a step's end that a checkpoint can resume from: the run's
 * place, and the status and message the stop replaces (adaptive.h). */
static int halt(adaptive_ws *A, ad_run *R, int status, int phase, const char *what) {
  ad_stop *s = A->stop;
  s->phase = phase;
  s->R = *R;
  s->md = R->md ? (int)(R->md - A->modes) : -1;
  s->pinned1 = A->pinned[1] ? (int)(A->pinned[1] - A->modes) : -1;
  s->carry = A->carry_md && A->carry_md == R->md && A->carry_t == R->t;
  s->status = R->info->status;
  memcpy(s->message, R->info->message, sizeof s->message);
  return ad_fail(R, status, "%s", what);
}

/* A sample inside the step refused by the sink (A->pend; A->zt its
 * time): the run stops at the step's end, the message naming both. */
static int halt_dense(adaptive_ws *A, ad_run *R) {
  char what[96];
  snprintf(what, sizeof what, "stopped by the output sink (its sample at t = %.17g)", A->zt);
  return halt(A, R, CUP_ERR_INTERRUPTED, AD_STOP_DENSE, what);
}

/* The sample at R->t to the sink: the state x (A->x, or x0 as given at a
 * start), zeta the active set's at A->x (adaptive_zeta; none before a set
 * is chosen, or under catching-up steps: pinned[1]). With put
 * (integrator_set_put), A->x's sample with its signals from the active
 * set's y goes there instead (ad_put_row: what the sink would do with
 * integrator_record's, without its calls). */
RUN_INLINE int offer_x(adaptive_ws *A, ad_run *R, const double *x) {
  R->info->samples++;
  A->zmd = A->pinned[1] ? NULL : R->md;
  A->zt = R->t;
  A->zx0 = x != A->x;
  int stopped = A->put && !A->put_off && A->zmd && !A->zx0 ? ad_put_row(A, R, x) : -1;
  if (stopped < 0) stopped = R->sink(R->steps, R->t, x, R->sink_ctx);
  A->zmd = NULL;
  A->zx0 = 0;
  if (stopped) return halt(A, R, CUP_ERR_INTERRUPTED, AD_STOP_SAMPLE, "stopped by the output sink");
  return CUP_OK;
}

static int offer(adaptive_ws *A, ad_run *R) { return offer_x(A, R, A->x); }

/* A switched run's window end before T (adaptive_hold_end): the sample
 * due there, or a rounding before it (ad_dense_end), waits for the next
 * window, after the switching's jump (give_held). */
static __attribute__((noinline)) int hold(adaptive_ws *A, ad_run *R) {
  const cup_integrator_options *o = &A->o;
  int due = 0;
  if (o->output == CUP_OUTPUT_EVERY) due = R->steps % o->output_every == 0;
  else if (o->output == CUP_OUTPUT_TOL) due = 1;
  else if (o->output == CUP_OUTPUT_SAMPLES && R->next_sample < o->output_samples) {
    double ts = ad_sample_time(A, R->next_sample);
    due = ts <= R->t && ts >= ad_dense_end(A, R->t);
  }
  if (due) {
    R->est_max = la_fmax(R->est_max, estimate_now(A, R));
    A->held_end = 1;
  }
  return CUP_OK;
}

/* est: R->est_max holds the estimate now already (step_done's, at a
 * step's end not at an event: the same sum, and its max again is a no-op) */
RUN_INLINE int emit_at(adaptive_ws *A, ad_run *R, const double *x, int est) {
  const cup_integrator_options *o = &A->o;
  int out = 0, last = R->t == o->T;
  if (A->hold_end && R->t == A->tend && !last && R->sink) return hold(A, R);
  switch (o->output) {
    case CUP_OUTPUT_EVERY: out = R->steps % o->output_every == 0 || last; break;
    case CUP_OUTPUT_SAMPLES:
      if (R->next_sample < o->output_samples && R->t == ad_sample_time(A, R->next_sample)) {
        out = 1;
        R->next_sample++;
      }
      break;
    case CUP_OUTPUT_TOL: out = 1; break;         /* (each step's end, as every 1: adaptive_outtol.c between) */
    case CUP_OUTPUT_FINAL: out = last; break;
    case CUP_OUTPUT_NONE: break;
  }
  if (!out) return CUP_OK;
  if (!est) R->est_max = la_fmax(R->est_max, estimate_now(A, R));
  return R->sink ? offer_x(A, R, x) : CUP_OK;
}

static int emit_x(adaptive_ws *A, ad_run *R, const double *x) { return emit_at(A, R, x, 0); }

/* The sample the window before held (hold), at this window's start: its
 * own time (a rounding before the switching's at most), the state after
 * the jump, zeta the active set chosen here. */
static int give_held(adaptive_ws *A, ad_run *R) {
  if (A->o.output != CUP_OUTPUT_SAMPLES) return offer(A, R);
  double t = R->t;
  R->t = ad_sample_time(A, R->next_sample++);
  int st = offer(A, R);
  R->t = t;
  return st;
}

static int emit(adaptive_ws *A, ad_run *R) { return emit_x(A, R, A->x); }

/* A step's callback, and the interrupt and wall-time checks. */
RUN_INLINE int step_checks(adaptive_ws *A, ad_run *R, const cup_proj_info *pi) {
  if (A->o.on_step && A->o.on_step(R->steps, R->t, pi, A->o.step_ctx))
    return halt(A, R, CUP_ERR_INTERRUPTED, AD_STOP_STEP, "stopped by the step callback");
  if ((R->steps & 1023) == 0) {
    if (A->o.interrupt && *A->o.interrupt) return halt(A, R, CUP_ERR_INTERRUPTED, AD_STOP_STEP, "interrupted");
    if (A->o.max_wall_seconds > 0 && now_seconds() - R->wall0 > A->o.max_wall_seconds)
      return halt(A, R, CUP_ERR_TIME_LIMIT, AD_STOP_STEP, "wall-time limit reached");
  }
  return CUP_OK;
}

/* The end of a step: statistics, the error estimate (not at the switch
 * instant of an event: there the error is the event's time localisation,
 * which decays with the new flow; at the output times after it counts),
 * the step callback. */
static int step_done(adaptive_ws *A, ad_run *R, const cup_proj_info *pi, int at_event) {
  cup_run_info *info = R->info;
  if (tally_state_beyond(A->x, A->n)) {          /* before the sink sees it, and the state stays the last good one */
    int w = tally_state_worst(A->x, A->n);
    snprintf(info->message, sizeof info->message, "step %ld (t = %.17g): the state left its range ||x||_1 <= "
             "%g (x[%d] = %.3g): the scheme diverged", R->steps + 1, R->t, CUP_STATE_MAX, w, A->x[w]);
    la_copy_few(A->x, A->xok, A->n);
    return info->status = CUP_ERR_DIVERGED;
  }
  la_copy_few(A->xok, A->x, A->n);
  R->steps++;
  info->step = R->steps;
  info->t = R->t;
  if (pi->skipped) info->skipped++;           /* projections are counted where they are made */
  double xn = la_norm_inf(A->x, A->n);
  R->r2 += (8 * DBL_EPSILON * xn) * (8 * DBL_EPSILON * xn);   /* rounding, as a random walk */
  if (!at_event) R->est_max = la_fmax(R->est_max, estimate_now(A, R));
  double tw = A->o.tol_abs + A->o.tol_rel * xn;  /* (tolw's at A->x) */
  if (!R->floor_warned && tw < 16 * DBL_EPSILON * xn) {
    R->floor_warned = 1;
    warn(R, CUP_WARN_TOL_FLOOR, "tol (abs %.3g, rel %.3g) gives %.3g at |x| = %.3g, below what double "
         "precision can deliver there (about %.3g)", A->o.tol_abs, A->o.tol_rel, tw, xn,
         16 * DBL_EPSILON * xn);
  }
  if (A->pend.active) {                          /* the sink refused a sample inside the step */
    A->stop->pi = *pi;
    return halt_dense(A, R);
  }
  return step_checks(A, R, pi);
}

/* ---- projection, active sets, events ------------------------------------------------- */

/* With D: x onto the consistent states Q(t) (adaptive_dae.c), exact up to
 * rounding (the LCP solved by pivoting); not certified by a projector. */
static int jump(adaptive_ws *A, ad_run *R, double *x, uint64_t *active, cup_proj_info *pi) {
  int piv = 0, st = ad_dae_jump(A, x, active, &piv);
  R->info->dual_iterations += piv;
  if (st < 0)
    return ad_fail(R, CUP_ERR_EMPTY_SET, "no state is consistent with the rows at this time: the jump's LCP "
                "(x + B mu with 0 <= mu _|_ C x + D zeta + g >= 0) has no solution");
  if (st == 0) return CUP_OK;
  pi->skipped = 0;
  pi->iterations = piv;
  R->info->projected++;
  R->rloc += 8 * DBL_EPSILON * la_norm_inf(x, A->n);
  return CUP_OK;
}

/* If x is outside {C x + g >= 0}, its certified P-projection (the exact
 * small-set LCP, as the explicit scheme's step); *active gets its active
 * rows (0 when nothing moved), A->inside whether x stayed as it was. x
 * inside: pi->skipped = 1 and the rest of *pi as it was (a caller that
 * hands pi on zeroes it first; a breakpoint's at a window's ends read
 * skipped alone, and the zeroing was a sixth of the check); else *pi the
 * projection's. */
static int move_inside(adaptive_ws *A, ad_run *R, const double *g, double *x, uint64_t *active,
                       cup_proj_info *pi);

RUN_INLINE int make_consistent(adaptive_ws *A, ad_run *R, const double *g, double *x, uint64_t *active,
                               cup_proj_info *pi) {
  *active = 0;
  pi->skipped = 1;
  double *s = A->has_D ? A->dq0 : A->s;          /* (with D, the jump's LCP reads it) */
  /* beyond rounding: a held row is at 0 (with D: zeta = 0 is consistent) */
  int outside = polyset_slack_outside(A->K, g, x, s, A->gam);
  A->inside = !outside;
  return outside ? move_inside(A, R, g, x, active, pi) : CUP_OK;
}

/* (make_consistent's check inline, its projection out of line.) */
static __attribute__((noinline)) int move_inside(adaptive_ws *A, ad_run *R, const double *g, double *x,
                                                 uint64_t *active, cup_proj_info *pi) {
  *pi = (cup_proj_info){0};
  pi->skipped = 1;
  if (A->has_D) {
    /* a conducting diode's row is below 0 with D: the jump's LCP finds x
     * consistent as it is (the bridge's dead time, each window), and
     * start_piece's check with the same offset would again */
    int st = jump(A, R, x, active, pi);
    A->inside = st == CUP_OK && pi->skipped;
    return st;
  }
  double S = cup_polyset_norm(A->K, x);
  la_copy_few(A->xr, x, A->n);
  int st = lcp_step_solve(&A->proj, g, A->xr, x, S, -1, 1e-10 * S, pi);
  const double *lam = A->proj.lcp.lam;
  if (st == CUP_ERR_LINALG) {
    /* pivoting found no nonsingular block (nearly dependent rows) or K(t)
     * is empty: the projector decides, as for the explicit scheme's step,
     * and proves an empty K(t) with a Farkas certificate */
    st = cup_projector_set_offset(A->projector, g);
    if (st == CUP_OK) st = cup_project(A->projector, A->xr, x, pi);
    lam = cup_projector_lambda(A->projector);
  }
  if (st < 0) {
    la_copy_few(x, A->xr, A->n);
    if (st == CUP_ERR_EMPTY_SET)
      return ad_fail(R, st, "K(t) is empty: Farkas certificate y >= 0 with g^T y = %.3g, ||C^T y||_{P^-1} = %.3g",
                  pi->farkas_gap, pi->farkas_residual);
    return ad_fail(R, st, "the projection onto K(t) failed: %s", cup_status_string(st));
  }
  cup_run_info *info = R->info;
  info->projected++;
  info->dual_iterations += pi->iterations;
  if (!(pi->eps_cert <= info->max_eps_cert)) info->max_eps_cert = pi->eps_cert;
  if (!(pi->eta_cert <= info->max_eta_cert)) info->max_eta_cert = pi->eta_cert;
  if (st == CUP_WARN_NOT_CERTIFIED && info->not_certified++ == 0)
    warn(R, st, "projection not certified: eps %.3g (target %.3g), eta %.3g (target %.3g)",
         pi->eps_cert, pi->eps_target, pi->eta_cert, pi->eta_target);
  /* what the projection may be off by, in the max norm: it is exact (the
   * LCP solved by pivoting) up to rounding, and eta_cert from K; its eps
   * certificate bounds the squared distance only (sqrt(eps) would be a
   * bound of 1e-7 for an answer right to 1e-16) */
  R->rloc += 8 * DBL_EPSILON * la_norm_inf(x, A->n) + (isfinite(pi->eta_cert) ? A->pinf * pi->eta_cert : 0);
  for (int i = 0; i < A->m; i++)
    if (lam[i] > 0) *active |= (uint64_t)1 << i;
  return CUP_OK;
}

/* e <- its P-orthogonal projection onto ker C_J (a perturbation of a state
 * held on C_J x + g = 0, or of one projected onto a face with rows J). */
static void error_onto(adaptive_ws *A, uint64_t mask, double *e) {
  if (!mask) return;
  ad_mode *md = ad_mode_get(A, mask);
  if (!md->nz) return;                           /* (ad_manifold's no-op: no manifold rows) */
  ad_manifold(A, md, A->zero, e);
  for (int j = 0; A->tan && j < A->n; j++) ad_manifold(A, md, A->zero, A->tan + (size_t)j * A->n);   /* as e */
}

/* v <- its propagation by the exact flow of md over tau (w = 0: the
 * homogeneous part). */
static void flow_vector(adaptive_ws *A, ad_mode *md, double tau, double *v) {
  la_zero_few(A->yr, A->na);
  la_copy_few(A->yr, v, A->n);
  ad_flow(A, md, tau, A->yr, A->yt);
  la_copy_few(v, A->yt, A->n);
}

static void error_flow(adaptive_ws *A, ad_mode *md, double tau) {
  if (!(tau > 0)) return;
  flow_vector(A, md, tau, A->e);
}

/* The tangent's columns (adaptive_tangent) over tau on md. */
static void tangent_flow(adaptive_ws *A, ad_mode *md, double tau) {
  for (int j = 0; A->tan && tau > 0 && j < A->n; j++) flow_vector(A, md, tau, A->tan + (size_t)j * A->n);
}

static int report(adaptive_ws *A, ad_run *R, uint64_t before, uint64_t after, double t) {
  if (before == after) return CUP_OK;            /* (most pieces: the mode goes on) */
  for (int i = 0; i < A->m; i++) {
    int was = before >> i & 1, now = after >> i & 1;
    if (was == now) continue;
    R->info->events++;
    A->zeno[A->nzeno % AD_ZENO_RING] = t;
    A->zeno_row[A->nzeno % AD_ZENO_RING] = i;
    A->nzeno++;
    if (A->o.on_event && A->o.on_event(t, i, now, A->o.event_ctx))
      return ad_fail(R, CUP_ERR_INTERRUPTED, "stopped by the event callback");
  }
  return CUP_OK;
}

/* The time scale of the choice of an active set with D at time t (its LCP
 * is a step of a millionth of it): the current mode's step limit, or the
 * input's, and no longer than what is left of the input's piece (a pulse's
 * 1 fs fall, linearised over 25 ns, drove the other pair of a bridge on). */
static double time_scale(adaptive_ws *A, ad_run *R, double t) {
  double s = la_fmin(R->md ? ad_mode_hmax(A, R->md) : A->hmax_input, A->o.T);   /* (fmin's bits, no call) */
  return R->tb > t ? la_fmin(s, R->tb - t) : s;
}

/* The active set that continues from (x, w) at R->t, made current, x put
 * on its manifold; changes reported at time t_event. A switched run's
 * window starts with none current: the set its configuration's last window
 * started with is tried before the LCP (the dead time of a bridge opens on
 * the same diodes each period while the current keeps its sign); it is
 * kept only when it continues, as the LCP's answer must. With at_offset,
 * A->g and A->ut hold w's offset and input already (start_piece's); 2:
 * and A->s the slack C x + g at A->x (D = 0). */
RUN_INLINE int choose(adaptive_ws *A, ad_run *R, const double *w, uint64_t hint, double t_event, int at_offset) {
  uint64_t mask = 0, before = R->md ? R->md->mask : 0, seed = !R->md && A->seed_on ? A->seed : 0;
  int piv = 0, st = A->has_D ? (at_offset ? ad_dae_select_at : ad_dae_select)(A, A->x, w, before, -1, hint, seed,
                                                                             time_scale(A, R, R->t), 0, &mask, &piv)
                    : at_offset == 2 ? ad_select_slack(A, A->x, w, hint, &mask, &piv)
                    : at_offset ? ad_select_at(A, A->x, w, hint, &mask, &piv) : ad_select(A, A->x, w, hint, &mask, &piv);
  R->info->dual_iterations += piv;
  if (st) return ad_fail(R, CUP_ERR_LINALG, A->has_D ? "no active set continues from this state: none that the "
                      "LCP with D proposes keeps its multipliers and slacks >= 0 on its own flow"
                      : "the velocity LCP that chooses the active set has no solution by pivoting (dependent rows?)");
  if (!R->md) A->seed = mask;
  A->carry_md = NULL;                            /* (x moves onto the set's manifold here) */
  A->pinned[0] = R->md = ad_mode_get(A, mask);
  /* (ad_select and ad_dae_select left g = F + G u(w) in A->g) */
  if (R->md->nz) ad_manifold(A, R->md, A->g, A->x);   /* (none: a no-op, its call saved) */
  error_onto(A, R->md->mask, A->e);
  return report(A, R, before, R->md->mask, t_event);
}

static int choose_mode(adaptive_ws *A, ad_run *R, const double *w, uint64_t hint, double t_event) {
  return choose(A, R, w, hint, t_event, 0);
}

/* ---- breakpoints ------------------------------------------------------------------- */

/* At a breakpoint t (or 0): the state onto K(t) with u(t) itself (a square
 * wave is 0 there), which is what the catching-up limit holds at t. g =
 * F + G u(t) by G's nonzeros, a waveform's terms those that reach them
 * (ad_offset's sums: the dense ones less terms that are zero; a switched
 * run's window starts and ends here, and a converter's gates, read by the
 * switches alone, were half of what it cost). */
RUN_INLINE int at_break(adaptive_ws *A, ad_run *R, int first, cup_proj_info *pi) {
  int gbrk = 0;
  if (A->u && A->u->fn) {
    if (cup_input_eval(A->u, R->t, A->ut))
      return ad_fail(R, CUP_ERR_CALLBACK, "the input u(t) failed or returned NaN/Inf");
    ad_offset_of(A, A->ut, A->g);
  } else if ((gbrk = A->gbrk_const)) {           /* the terms G reads are constants: made once (u(t) */
    la_copy_few(A->g, A->gbrk, A->m);            /* in A->ut is not read past here) */
  } else {
    if (A->u) input_eval_terms(A->u, A->gterm, A->ngterm, R->t, A->ut);
    ad_offset_of(A, A->ut, A->g);
  }
  uint64_t active;
  double x0n = first ? la_norm_inf(A->x, A->n) : 0;   /* (the warning's) */
  int st = make_consistent(A, R, A->g, A->x, &active, pi);
  if (st < 0) return st;
  R->kept = A->inside ? 1 + gbrk : 0;             /* (2: g is gbrk, not copied to gk) */
  if (R->kept == 1) la_copy_few(A->gk, A->g, A->m);
  if (first && !pi->skipped)
    warn(R, CUP_WARN_X0_OUTSIDE, "x0 is outside K(0) (|x0| = %.3g); it is projected", x0n);
  error_onto(A, active, A->e);
  return CUP_OK;
}

/* The piece after a breakpoint: its exosystem states, the jump of K onto
 * K(t+) (a projection, certified), and the active set by the velocity LCP.
 * fresh: at_break has just checked A->x (nothing between, as at a window's
 * start): with the same offset its slack in A->s is the choice's too. */
RUN_INLINE int start_piece(adaptive_ws *A, ad_run *R, int fresh, int quiet) {
  /* (a record here asked already; quiet, a switched run's window: the
   * model knows the input has no breakpoint before its end, the min's) */
  double tb = quiet ? A->tend : ad_next_break(A, R->t);
  R->tb = tb < A->tend ? tb : A->tend;
  /* a callback is taken continuous: only u(t+) and u'(t+) matter here */
  double h = A->callback ? la_fmin(R->h_cb, R->tb - R->t) : R->tb - R->t;
  if (A->w_const) {                              /* (DC sources alone: ad_inputs_on's and ad_offset's */
    la_copy_few(A->wt, A->wc, A->nw);            /* answers, made at set-up, without their checks) */
    la_copy_few(A->ut, A->uc, A->p);
    la_copy_few(A->g, A->gc, A->m);
  } else {
    if (ad_inputs_on(A, R->t, R->t + h, A->wt, A->uerr))
      return ad_fail(R, CUP_ERR_CALLBACK, "the input u(t) failed or returned NaN/Inf");
    ad_offset(A, A->wt, A->g);
  }
  uint64_t active = 0;
  /* at_break left x inside K(t) (nothing moved it since): with the same
   * offset at t+ (the input that jumps here reaches no row: a converter's
   * gates, read by the switches alone) the check finds it inside again */
  int kept = R->kept == 2 ? A->gc_brk || ad_same_bits(A->g, A->gbrk, A->m)
             : R->kept && ad_same_bits(A->g, A->gk, A->m);
  if (!kept) {
    cup_proj_info pi;
    int st = make_consistent(A, R, A->g, A->x, &active, &pi);
    if (st < 0) return st;
    error_onto(A, active, A->e);
  }
  R->kept = 0;
  /* (A->g, A->ut: w's still; A->s: at_break's when fresh, D = 0) */
  return choose(A, R, A->wt, active, R->t, kept && fresh && !A->has_D ? 2 : 1);
}

/* ---- steps ------------------------------------------------------------------------ */

/* Callback inputs: the step's interpolation error carried to x through the
 * flow: X E's column of a component's constant state is the response of x
 * to a unit step of that input (X, not only E: on a manifold the input
 * moves x directly, x = v - K_J u, while v stays put; a clamp holding its
 * capacitor to the source took steps of 0.6 ms at 1 kHz with no error
 * seen). */
static double interp_error(const adaptive_ws *A, const ad_mode *md, const double *E) {
  int n = A->n, na = A->na;
  double worst = 0;
  for (int i = 0; i < n; i++) {
    double acc = 0;
    for (int c = 0; c < A->p; c++) {
      const double *col = E + (size_t)(n + c * (AD_DEGREE + 1)) * na;
      acc += fabs(la_dot(md->X + (size_t)i * na, col, na)) * A->uerr[c];
    }
    worst = fmax(worst, acc);
  }
  return worst;
}

/* The end of a step at R->t: a breakpoint's projection, the output, the
 * next piece. */
static int end_of_step(adaptive_ws *A, ad_run *R, const cup_proj_info *pi, int at_event) {
  int at_tb = R->t == R->tb, st;
  cup_proj_info pb;
  if (at_tb) {
    R->after_event = 0;
    if ((st = at_break(A, R, 0, &pb)) < 0) return st;
    if (!pb.skipped) pi = &pb;
  }
  int ev = at_event && !at_tb;
  if ((st = step_done(A, R, pi, ev)) < 0 || (st = emit_at(A, R, A->x, !ev)) < 0) return st;
  if (at_tb && R->t < A->tend && (st = start_piece(A, R, 0, 0)) < 0) return st;
  return CUP_OK;
}

/* The step's end t1 (a breakpoint, an output time, T, or the mode's step
 * limit), the input's states, and exp(h M). Callback inputs: the step
 * shrinks until the interpolation error is within its share of tol.
 * NULL with *t1 set when t1 is within rounding of t (nothing to flow), with
 * *series set when the step takes the flow's series instead (ad_series_at),
 * or with the status set on an error. */
static const double *begin_step(adaptive_ws *A, ad_run *R, double *t1, int *snap, int *series) {
  ad_mode *md = R->md;
  *snap = *series = 0;
  for (;;) {
    double hm = ad_mode_hmax(A, md), hl = A->callback ? la_fmin(hm, R->h_cb) : hm;
    *t1 = next_stop(A, R, hl, 0);
    double h = *t1 - R->t, tiny = 4 * DBL_EPSILON * la_fmax(fabs(R->t), DBL_MIN);
    if (!(h > tiny)) {
      if (*t1 < R->t + hl) { *snap = 1; return NULL; }   /* a stop point a rounding away */
      ad_fail(R, CUP_ERR_STEP_SIZE, "the step size %.3g underflows", h);
      return NULL;
    }
    if (ad_inputs_on(A, R->t, *t1, A->wa, A->uerr)) {
      ad_fail(R, CUP_ERR_CALLBACK, "the input u(t) failed or returned NaN/Inf on [%.17g, %.17g]", R->t, *t1);
      return NULL;
    }
    /* a step from an event to a breakpoint has a length of its own: the
     * flow's series (two of them: y and the error) cost less than the
     * exponential, where h ||M|| <= 2 (its length limit's recurs) */
    double hlim = A->o.hmax > 0 ? la_fmin(hl, A->o.hmax) : hl;
    if (R->after_event && !A->callback && !A->tan && *t1 != R->t + hlim && h * md->mnorm <= 2 &&
        !ad_expm_cached(A, md, h, *t1)) {
      *series = 1;
      return NULL;
    }
    const double *E = ad_expm(A, md, h, *t1);
    if (!A->callback) return E;
    double ie = interp_error(A, md, E), errn = ie / (AD_STEP_SHARE * tolw(A, A->x));
    double fac = errn > 0 ? 0.9 * pow(errn, -1.0 / (AD_DEGREE + 2)) : 5;
    if (errn <= 1) {
      R->h_cb = h * fmin(5, fac);
      R->rloc += ie;
      return E;
    }
    R->info->rejected++;
    R->h_cb = h * fmax(0.2, fmin(0.9, fac));
  }
}

static int any_negative(const adaptive_ws *A) {
  const double *ga = A->ga, *ta = A->ta;
  for (int i = 0; i < A->m; i++)                 /* (ga < -ta needs ga < 0, ta >= 0: the test first) */
    if (ga[i] < 0 && ga[i] < -ta[i]) return 1;
  return 0;
}

/* The tolerance an event's local error is held to: tolw at the state, less
 * as the estimate of what the run has already spent of it grows past half
 * (events accumulate: a resonant converter switches 86 times in 200 us),
 * down to 1/16 of it. */
static double event_budget(const adaptive_ws *A, const ad_run *R) {
  double tw = tolw(A, A->x), left = tw - estimate_now(A, R);
  return left >= 0.5 * tw ? tw : tw * fmax(1.0 / 16, left / (0.5 * tw));
}

/* The reported time of the event of row k: Newton steps on its function
 * along the old flow from tau (the state at the last one in A->yr). */
static double refine_root(adaptive_ws *A, ad_mode *md, int k, double tau, double tmax, double h) {
  for (int it = 0; it < 4; it++) {
    ad_series_at(A, &A->sy, md, h, A->ya, tau, A->yr);
    if (k < 0) break;
    double g = md->Lc[k] + la_dot(md->L + (size_t)k * A->na, A->yr, A->na);
    ad_events_deriv(A, md, A->yr, A->dt);
    double d = A->dt[k], next = d != 0 ? tau - g / d : tau;
    if (!(next >= 0 && next <= tmax) || fabs(next - tau) <= 4 * DBL_EPSILON * fabs(tau)) break;
    tau = next;
  }
  return tau;
}

/* How far the state at the switch tau_sw may be from the root's (which
 * lies in the bracket [tau_lo, tau_sw]), in the P-norm: twice its move
 * across the bracket to first order, from its velocity there on md (y). */
static double bracket_move(adaptive_ws *A, ad_mode *md, const ad_event *ev, const double *y) {
  ad_mode_mv(A, md, y, A->yt);
  ad_state(A, md, A->yt, A->xr);
  return 2 * (ev->tau_sw - ev->tau_lo) * cup_polyset_norm(A->K, A->xr);
}

/* An event inside the step from R->t (bracketed by ad_detect): locate it,
 * switch past it (state made consistent, the next active set by the
 * velocity LCP), and estimate what switching there rather than at the root
 * changed in x: the same switch done at the root estimate, carried to the
 * switch time by the new flow (docs/adaptive.md). A model that underrates
 * that error has its factor raised and the location resumed. */
static int event(adaptive_ws *A, ad_run *R, ad_event *ev, double h, double t1) {
  int n = A->n, nw = A->nw, st;
  ad_mode *old = R->md, *nm = NULL;
  A->pinned[1] = old;
  double tw = event_budget(A, R), tau_rep = 0;
  uint64_t before = old->mask, active = 0;
  cup_proj_info pi = {0};
  for (int attempt = 0;; attempt++) {
    ad_locate(A, old, tw, ev);
    double tsw = ev->tau_sw;
    if (ev->hi_ok) la_copy_few(A->yb, A->yhi, A->na);   /* the run's path: ad_locate's probe there */
    else ad_series_at(A, &A->sy, old, h, A->ya, tsw, A->yb);
    ad_state(A, old, A->yb, A->xs);
    la_copy_few(A->wt, A->yb + n, nw);
    ad_offset(A, A->wt, A->g);
    ad_manifold(A, old, A->g, A->xs);
    pi = (cup_proj_info){0};                     /* (end_of_step's and the step callback's) */
    if ((st = make_consistent(A, R, A->g, A->xs, &active, &pi)) < 0) return st;
    uint64_t mask = 0;
    int piv = 0;
    uint64_t hint = before | active | (ev->row >= 0 ? (uint64_t)1 << ev->row : 0);
    /* (A->g and A->ut: wt's offset still, which make_consistent reads and
     * leaves; the choice leaves them so too: its own offsets of wt, two a
     * six-pulse event, were 16 k instructions of that run) */
    if (A->has_D ? ad_dae_select_at(A, A->xs, A->wt, before, ev->row, hint, 0, time_scale(A, R, R->t + tsw),
                                    bracket_move(A, old, ev, A->yb), &mask, &piv)
                 : ad_select_at(A, A->xs, A->wt, hint, &mask, &piv))
      return ad_fail(R, CUP_ERR_LINALG, A->has_D ? "no active set continues after the event of row %d: none that "
                  "the LCP with D proposes keeps its multipliers and slacks >= 0 on its own flow"
                  : "the velocity LCP that chooses the active set after the event of row %d has no solution by "
                  "pivoting (dependent rows?)", ev->row);
    R->info->dual_iterations += piv;
    nm = ad_mode_get(A, mask);
    A->pinned[0] = nm;
    ad_manifold(A, nm, A->g, A->xs);
    tau_rep = refine_root(A, old, ev->row, ev->tau_est, tsw, h);   /* the reference path */
    ad_state(A, old, A->yr, A->xr);
    la_copy_few(A->wa, A->yr + n, nw);
    ad_offset(A, A->wa, A->g);
    ad_manifold(A, nm, A->g, A->xr);
    ad_lift(A, nm, A->xr, A->wa, A->yt);
    ad_flow(A, nm, tsw - tau_rep, A->yt, A->yr);
    ad_state(A, nm, A->yr, A->xr);
    for (int i = 0; i < n; i++) A->et[i] = A->xs[i] - A->xr[i];
    double err = ad_energy_bound(A, A->et, A->xf);
    /* A switch that leaves the active set as it was, although a row
     * crossed well before it, has stepped over the row's whole excursion
     * (a diode that conducts for a moment inside a long step: the error is
     * its charge, first order): the bracket is closed further, 16x a try. */
    double width = ev->tau_sw - ev->tau_lo;
    if (nm->mask == before) {
      if (width <= ldexp(h, -20) || attempt >= 8) break;
      ev->cmin = fmax(ev->cmin, 2 * AD_EVENT_SHARE * tw * 256 / (width * width));
      continue;
    }
    if (err <= 4 * AD_EVENT_SHARE * tw || attempt >= 3) break;
    ev->cfac *= fmax(4, err / (0.25 * AD_EVENT_SHARE * tw));
    /* a model of 0 (another row switching with this one, D's coupling) is
     * raised by nothing: the measured error over the delay is a floor */
    double delay = tsw - tau_rep;
    if (delay > 0) ev->cmin = fmax(ev->cmin, 4 * err / (delay * delay));
  }
  /* samples before the root on the old flow, after it on the new one from
   * the root's state made consistent (A->yt, what the local error was
   * measured against): the run's own path there would show the violation
   * the late switch lets through, first order in its delay */
  double t0 = R->t, tend = ev->tau_sw >= h ? t1 : t0 + ev->tau_sw, troot = fmin(t0 + tau_rep, tend);
  A->oevent = 1;                                 /* (output tol: these pieces do not end on A->yb) */
  if ((st = ad_emit_dense(A, R, old, A->ya, A->e, t0, troot)) < 0) {
    A->oevent = 0;
    return st;
  }
  la_copy_few(A->ed, A->e, n);                      /* the error at the root, on the new manifold */
  la_zero_few(A->se.v, A->na);                      /* (e, 0): its flow to the root and to the switch */
  la_copy_few(A->se.v, A->e, n);
  if (troot > t0) {
    ad_series_at(A, &A->se, old, h, A->se.v, troot - t0, A->de);
    la_copy_few(A->ed, A->de, n);
  }
  ad_manifold(A, nm, A->zero, A->ed);
  st = ad_emit_dense(A, R, nm, A->yt, A->ed, troot, tend);
  A->oevent = 0;
  if (st < 0) return st;
  if (ev->tau_sw > 0) {
    ad_series_at(A, &A->se, old, h, A->se.v, ev->tau_sw, A->yt);
    la_copy_few(A->e, A->yt, n);
  }
  if (A->tan) {   /* the tangent: the old flow to the root, its saltation (the new manifold's projection), the new flow */
    double tr = fmin(fmax(tau_rep, 0), ev->tau_sw);
    tangent_flow(A, old, tr);
    for (int j = 0; j < n; j++) ad_manifold(A, nm, A->zero, A->tan + (size_t)j * n);
    tangent_flow(A, nm, ev->tau_sw - tr);
  }
  A->pinned[0] = R->md = nm;
  A->pinned[1] = NULL;
  error_onto(A, nm->mask, A->e);
  if (nm->mask != before)
    for (int i = 0; i < n; i++) A->e[i] += A->et[i];
  la_copy_few(A->x, A->xs, n);
  R->t = ev->tau_sw >= h ? t1 : t0 + ev->tau_sw;
  R->after_event = 1;
  if ((st = report(A, R, before, nm->mask, t0 + tau_rep)) < 0) return st;
  return end_of_step(A, R, &pi, 1);
}

/* The event functions at the last step's end as this one's start (three
 * copies of m in one plain loop: la_copy's three loops took 67
 * instructions for m = 4, a full bridge's rows). */
static void events_from_end(adaptive_ws *A) {
  double *ga = A->ga, *ta = A->ta, *da = A->da;
  const double *gb = A->gb, *tb = A->tb, *db = A->db;
  for (int i = 0; i < A->m; i++) {
    ga[i] = gb[i];
    ta[i] = tb[i];
    da[i] = db[i];
    __asm__ volatile("");                        /* (a loop, not a vectorized one with its set-up) */
  }
}

/* A step's projection info when it made none (a flow step's). */
static const cup_proj_info no_projection = {.skipped = 1};

static int take_step(adaptive_ws *A, ad_run *R) {
  ad_mode *md = R->md;
  int n = A->n, na = A->na, snap;
  double t1;
  int series;
  const double *E = begin_step(A, R, &t1, &snap, &series);
  A->sy.md = A->se.md = NULL;                    /* (the flow's series are this step's) */
  int carry = A->carry_md == md && A->carry_t == R->t;
  int ended = A->end_md == md && md->mask == A->end_mask && A->end_t == R->t;
  A->carry_md = A->end_md = NULL;
  if (!E && !series) {
    if (!snap) return R->info->status;
    R->t = t1;
    return end_of_step(A, R, &no_projection, 0);
  }
  if (carry) {                                   /* the last step's end (A->carry_md) */
    la_copy_few(A->ya, A->yb, na);
    events_from_end(A);
    A->carried++;
  } else {
    ad_lift(A, md, A->x, A->wa, A->ya);
    if (ended && ad_same_bits(A->ya, A->yb, na)) events_from_end(A);   /* (A->end_md) */
    else ad_events_both(A, md, A->ya, A->ga, A->ta, A->da);
    A->carried = 0;
  }
  if (any_negative(A)) {                         /* an inconsistent start: choose again */
    uint64_t was = md->mask;
    int st = choose_mode(A, R, A->wa, 0, R->t);
    if (st < 0 || R->md->mask != was) return st;
  }
  double h = t1 - R->t;
  if (series) {
    ad_series_at(A, &A->sy, md, h, A->ya, h, A->yb);
  } else {
    ad_expm_mv(A, md, E, A->ya, A->yb);
  }
  ad_events_both(A, md, A->yb, A->gb, A->tb, A->db);
  if (ad_detect_may(A)) {
    ad_event ev = {.t0 = R->t, .h = h, .cfac = 1, .row = -1};
    if (ad_detect(A, md, h, &ev)) return event(A, R, &ev, h, t1);
  }
  int st = ad_emit_dense(A, R, md, A->ya, A->e, R->t, t1);
  if (st < 0) return st;
  ad_state(A, md, A->yb, A->x);
  if (md->nz) {                                  /* (a mode with no manifold rows: the bridges' with D) */
    ad_offset(A, A->yb + n, A->g);
    ad_manifold(A, md, A->g, A->x);
  }
  if (series) {                                  /* (e, 0) by its series */
    la_zero_few(A->se.v, na);
    la_copy_few(A->se.v, A->e, n);
    ad_series_at(A, &A->se, md, h, A->se.v, h, A->yt);
    la_copy_few(A->et, A->yt, n);
  } else {
    ad_matvec_few(n, na, E, A->e, A->et);
  }
  la_copy_few(A->e, A->et, n);
  for (int c = 0; A->tan && c < n; c++) {        /* the tangent's columns, as e */
    double *v = A->tan + (size_t)c * n;
    ad_matvec(n, na, E, v, A->et);
    la_copy_few(v, A->et, n);
  }
  R->t = t1;
  A->end_md = md;                                /* (gb, tb, db: the events at yb) */
  A->end_mask = md->mask;
  A->end_t = t1;
  if (A->has_D && !A->callback && t1 != R->tb && A->carried < AD_CARRY - 1) {
    A->carry_md = md;                            /* (a breakpoint's projection and choice move x) */
    A->carry_t = t1;
  }
  return end_of_step(A, R, &no_projection, 0);
}

/* ---- accumulating events: catching-up steps across them --------------------------- */

/* With D, a catching-up step's active set: the one that continues from the
 * step's start (NULL with the status set on an error). */
static ad_mode *catch_up_mode(adaptive_ws *A, ad_run *R, double h) {
  uint64_t mask;
  int piv = 0;
  if (ad_inputs_on(A, R->t, fmin(R->tb, R->t + h), A->wt, A->uerr)) {
    ad_fail(R, CUP_ERR_CALLBACK, "the input u(t) failed or returned NaN/Inf");
    return NULL;
  }
  if (ad_dae_select(A, A->x, A->wt, R->md->mask, -1, 0, 0, time_scale(A, R, R->t), 0, &mask, &piv)) {
    ad_fail(R, CUP_ERR_LINALG, "the LCP that chooses the active set has no solution by pivoting");
    return NULL;
  }
  R->info->dual_iterations += piv;
  return ad_mode_get(A, mask);
}

static int catch_up_from(adaptive_ws *A, ad_run *R, int at_tb);

static int catch_up(adaptive_ws *A, ad_run *R) {
  double rate = A->o.max_event_rate > 0 ? A->o.max_event_rate : 1e5 / A->o.T;
  double window = AD_ZENO_RING / rate, tend = fmin(A->tend, R->t + window);
  char rows[96] = "";
  size_t len = 0;
  for (int k = 0, shown = 0; k < AD_ZENO_RING && shown < 8; k++) {
    int r = A->zeno_row[k], seen = 0;
    for (int j = 0; j < k; j++) seen |= A->zeno_row[j] == r;
    if (seen) continue;
    int w = snprintf(rows + len, sizeof rows - len, "%s%d", shown++ ? ", " : "", r);
    if (w > 0 && len + (size_t)w < sizeof rows) len += (size_t)w;
  }
  warn(R, CUP_WARN_ZENO, "rows %s switched %d times within %.3g (over max_event_rate = %.3g per unit "
       "time): catching-up steps across [%.17g, %.17g]", rows, AD_ZENO_RING,
       R->t - A->zeno[A->nzeno % AD_ZENO_RING], rate, R->t, tend);
  R->tend = tend;
  return catch_up_from(A, R, 0);
}

/* The catching-up steps until R->tend (a resumed run may start inside
 * them; at_tb: its last step ended on a breakpoint). */
static int catch_up_from(adaptive_ws *A, ad_run *R, int at_tb) {
  double rate = A->o.max_event_rate > 0 ? A->o.max_event_rate : 1e5 / A->o.T;
  double window = AD_ZENO_RING / rate, tend = R->tend;
  int n = A->n, na = A->na, st;
  while (R->t < tend) {
    /* the free system's flow, then the certified projection: the paper's
     * scheme with an exact free step, through breakpoints too (which pick
     * an active set that this loop does not use); with D, whose multipliers
     * act through the step, the flow of the active set chosen at its start */
    ad_mode *md0 = A->has_D ? catch_up_mode(A, R, fmin(window / 16, tend - R->t)) : ad_mode_get(A, 0);
    if (!md0) return R->info->status;
    A->pinned[1] = md0;
    double t1 = fmin(next_stop(A, R, fmin(ad_mode_hmax(A, md0), window / 16), 1), tend);
    if (!(t1 > R->t)) break;
    if (ad_inputs_on(A, R->t, t1, A->wa, A->uerr))
      return ad_fail(R, CUP_ERR_CALLBACK, "the input u(t) failed or returned NaN/Inf");
    const double *E = ad_expm(A, md0, t1 - R->t, t1);
    A->end_md = NULL;                            /* (yb is this step's) */
    ad_lift(A, md0, A->x, A->wa, A->ya);
    for (int i = 0; i < na; i++) {
      double acc = 0;
      for (int j = 0; j < na; j++) acc += E[i + (size_t)j * na] * A->ya[j];
      A->yb[i] = acc;
    }
    ad_state(A, md0, A->yb, A->x);
    la_copy_few(A->xf, A->x, n);
    ad_offset(A, A->yb + n, A->g);
    uint64_t active;
    cup_proj_info pi = {0};                        /* (end_of_step's and the step callback's) */
    if ((st = make_consistent(A, R, A->g, A->x, &active, &pi)) < 0) return st;
    double moved = 0;
    for (int i = 0; i < n; i++) moved = fmax(moved, fabs(A->x[i] - A->xf[i]));
    R->rloc += 0.5 * moved;                      /* a catching-up step's error is below its move */
    error_flow(A, md0, t1 - R->t);
    tangent_flow(A, md0, t1 - R->t);
    error_onto(A, active, A->e);
    R->t = t1;
    at_tb = R->t == R->tb;
    if ((st = end_of_step(A, R, &pi, 0)) < 0) return st;
  }
  R->tend = 0;
  A->pinned[1] = NULL;
  A->nzeno = 0;
  if (R->t >= A->tend || at_tb) return CUP_OK;    /* at a breakpoint start_piece chose the active set */
  if (ad_inputs_on(A, R->t, fmin(R->tb, R->t + ad_mode_hmax(A, R->md)), A->wt, A->uerr))
    return ad_fail(R, CUP_ERR_CALLBACK, "the input u(t) failed or returned NaN/Inf");
  return choose_mode(A, R, A->wt, 0, R->t);
}

static int zeno_check(adaptive_ws *A, ad_run *R) {
  if (A->nzeno < AD_ZENO_RING) return CUP_OK;
  double rate = A->o.max_event_rate > 0 ? A->o.max_event_rate : 1e5 / A->o.T;
  double oldest = A->zeno[A->nzeno % AD_ZENO_RING];
  return R->t - oldest < AD_ZENO_RING / rate ? catch_up(A, R) : CUP_OK;
}

/* ---- the run ----------------------------------------------------------------------- */

/* From where a run is (its start, or a resumed stop) to T. */
static int run_to_end(adaptive_ws *A, ad_run *R, int st) {
  while (st >= 0 && R->t < A->tend) {
    R->ev0 = R->info->events;
    st = take_step(A, R);
    if (st >= 0 && R->info->events > R->ev0) st = zeno_check(A, R);
  }
  R->info->err_est = R->est_max;
  return R->info->status;
}

/* A window's statistics from zero but for the message's tail past its
 * first byte (switched.c reads the message as a string): its 1 KiB was
 * half of what a window's start cost on a converter's (800 a run). */
static void info_clear(cup_run_info *info) {
  memset(info, 0, offsetof(cup_run_info, message) + 1);
  memset(&info->set_rebuilds, 0, sizeof *info - offsetof(cup_run_info, set_rebuilds));
}

/* What a run and a window start from: nothing pending, stopped or pinned
 * from before, the end at tend, the state xa at R's time (x0 refused when
 * beyond a state's range: check, the run's). */
RUN_INLINE int run_begin(adaptive_ws *A, ad_run *R, double tend, const double *xa, int check) {
  A->stop->phase = AD_STOP_NONE;
  A->pend.active = 0;
  A->piece_ok = A->nb_own.ok = 0;                /* (the input may have changed between runs) */
  A->tend = tend;
  if (check) memset(R->info, 0, sizeof *R->info);
  else info_clear(R->info);
  R->info->err_est = NAN;
  if (!A->slots && ad_modes_take(A))              /* (a window: in its block, a load and a branch) */
    return ad_fail(R, CUP_ERR_NOMEM, "out of memory for the active sets' slots");
  if (check && tally_state_beyond(xa, A->n)) {
    int w = tally_state_worst(xa, A->n);
    if (!isfinite(xa[w])) return ad_fail(R, CUP_ERR_NONFINITE, "x0[%d] is %g", w, xa[w]);
    return ad_fail(R, CUP_ERR_ARG, "x0 is beyond the range of a state, ||x||_1 <= %g (CUP_STATE_MAX): x0[%d] = %g",
                CUP_STATE_MAX, w, xa[w]);
  }
  la_copy_few(A->x, xa, A->n);
  la_copy_few(A->xok, xa, A->n);
  la_zero_few(A->e, A->n);
  A->nzeno = 0;
  A->pinned[0] = A->pinned[1] = NULL;
  A->carry_md = NULL;
  lcp_forget(&A->lcp);
  return CUP_OK;
}

/* ... then, after its first sample (first: x0's), the breakpoint there and
 * the first piece (the steps to tend follow: run_to_end); quiet: the input
 * has no breakpoint before tend (adaptive_window's jumped & 4). */
static int start_from(adaptive_ws *A, ad_run *R, int first, int quiet, int st) {
  cup_proj_info pi;
  if (st >= 0) st = at_break(A, R, first, &pi);
  if (st >= 0 && R->t < A->tend) st = start_piece(A, R, 1, quiet);
  return st;
}

/* A run's start (a switched run's first window's): the breakpoint and the
 * first piece, then x0's sample, x0 as given (A->xok, which nothing moved
 * yet; like the fixed-step schemes) with zeta the right limit at t+: the
 * multipliers of the active set chosen there, at the state the start left
 * (x0 put on that set's manifold; after a jump at t, the state after it).
 * Taken before the start, it had none (zeta = 0: a full bridge's diode
 * carrying an inductor's current at t = 0 showed i(D) = -i(L)). A start
 * that fails still gives x0's sample (zeta = 0 unless a set was chosen). */
static int start_sampled(adaptive_ws *A, ad_run *R) {
  int st = start_from(A, R, 1, 0, CUP_OK);
  if (st >= 0) return emit_x(A, R, A->xok);
  cup_run_info *info = R->info;
  char message[sizeof info->message];
  memcpy(message, info->message, sizeof message);
  if (emit_x(A, R, A->xok) < 0) {                /* refused: the start's error stays the run's */
    A->stop->phase = AD_STOP_NONE;
    memcpy(info->message, message, sizeof message);
  }
  return info->status = st;
}

int adaptive_run(adaptive_ws *A, const double *x0, cup_sample_fn sink, void *sink_ctx,
                 cup_run_info *info) {
  ad_run R = {.info = info, .sink = sink, .sink_ctx = sink_ctx, .h_cb = A->hmax_input, .wall0 = now_seconds()};
  int st = run_begin(A, &R, A->o.T, x0, 1);
  if (st) return st;
  adaptive_tol_reset(A);                         /* (output tol's scales: a run's own) */
  for (int j = 0; A->tan && j < A->n; j++)       /* V(0) = I */
    for (int i = 0; i < A->n; i++) A->tan[i + (size_t)j * A->n] = i == j;
  return run_to_end(A, &R, start_sampled(A, &R));
}

/* A switched run's window (switched.c): from xa at ta to tb, the samples
 * (x0's when first) and steps counted on from *next_sample and *steps.
 * The clock is read only under a wall-time limit (step_checks' is the only
 * use): a fixed-step run's split steps take two windows or more each. */
int adaptive_window(adaptive_ws *A, double ta, double tb, const double *xa, int first, int jumped,
                    long *steps, long *next_sample, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  ad_run R = {.info = info, .sink = sink, .sink_ctx = sink_ctx, .h_cb = A->hmax_input,
              .wall0 = A->o.max_wall_seconds > 0 ? now_seconds() : 0, .t = ta, .steps = *steps,
              .next_sample = *next_sample};
  int st = run_begin(A, &R, tb, xa, 0);          /* (no memory for the slots: an error) */
  if (st >= 0) st = first ? start_sampled(A, &R) : start_from(A, &R, 0, jumped >> 2 & 1, CUP_OK);
  /* every step recorded: the state after the jump too, at the same time
   * (after the window's projections, with the active set chosen there, so
   * that zeta is the new configuration's); a line drawn through the
   * records then shows the jump, not a ramp across the next step (a
   * window of length 0 chooses none: its state is the next window's) */
  if (st >= 0 && jumped & 2 && !first && ta < tb && sink)   /* the sample the window before held, here */
    st = give_held(A, &R);
  else if (st >= 0 && jumped & 3 && !first && ta < tb && sink &&
           ((A->o.output == CUP_OUTPUT_EVERY && A->o.output_every == 1) || A->o.output == CUP_OUTPUT_TOL))
    st = offer(A, &R);
  st = run_to_end(A, &R, st);
  A->tend = A->o.T;
  *steps = R.steps;
  *next_sample = R.next_sample;
  return st;
}

int adaptive_offer_held(adaptive_ws *A, double t, long steps, long *next_sample, cup_sample_fn sink,
                        void *sink_ctx, cup_run_info *info) {
  ad_run R = {.info = info, .sink = sink, .sink_ctx = sink_ctx, .t = t, .steps = steps,
              .next_sample = *next_sample, .md = (ad_mode *)A->pinned[0]};   /* (the window's last) */
  int st = CUP_OK;
  if (A->o.output == CUP_OUTPUT_SAMPLES) {         /* (held: a rounding before t at most) */
    if (R.next_sample < A->o.output_samples && ad_sample_time(A, R.next_sample) <= t) st = give_held(A, &R);
  } else {
    st = offer(A, &R);
  }
  *next_sample = R.next_sample;
  return st;
}

/* A restored stop goes on: the stopped step's sample (again, when the sink
 * refused it) and what followed it in its step (the next piece at a
 * breakpoint, the catching-up steps under way, the accumulation check),
 * then the steps to T. */
int adaptive_resume(adaptive_ws *A, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  ad_stop *s = A->stop;
  if (s->phase == AD_STOP_NONE) return info->status = CUP_ERR_ARG;
  A->tend = A->o.T;
  ad_run R = s->R;
  R.info = info;
  R.sink = sink;
  R.sink_ctx = sink_ctx;
  if (A->slots_lost || ad_modes_take(A))          /* (the restore's kept sets need them) */
    return ad_fail(&R, CUP_ERR_NOMEM, "out of memory for the active sets' slots");
  R.wall0 = now_seconds();
  R.kept = 0;                                    /* (A->gk is not the checkpoint's) */
  R.md = s->md >= 0 ? &A->modes[s->md] : NULL;
  A->pinned[0] = R.md;
  A->pinned[1] = s->pinned1 >= 0 ? &A->modes[s->pinned1] : NULL;
  A->carry_md = s->carry ? R.md : NULL;          /* (its vectors and count: the checkpoint's) */
  A->end_md = NULL;
  A->carry_t = R.t;
  int phase = s->phase, at_tb = R.t == R.tb, st = CUP_OK;
  s->phase = AD_STOP_NONE;
  if (phase == AD_STOP_SAMPLE && R.steps == 0) {   /* x0's sample after the start (start_sampled): again */
    info->samples--;
    if (sink) st = offer_x(A, &R, A->xok);
    return run_to_end(A, &R, st);
  }
  la_copy_few(A->xok, A->x, A->n);                  /* the last state within range: the stop's */
  if (phase == AD_STOP_SAMPLE) {
    info->samples--;                             /* counted when the sink refused it */
    if (sink) st = offer(A, &R);
  } else if (phase == AD_STOP_DENSE) {           /* the step's samples from the refused one, its callback */
    info->samples--;
    st = ad_dense_resume(A, &R);
    if (st == 1) return halt_dense(A, &R);
    if (st >= 0) st = step_checks(A, &R, &s->pi);
    if (st >= 0) st = emit(A, &R);
  } else {
    st = emit(A, &R);
  }
  if (st >= 0 && at_tb && R.t < A->tend) st = start_piece(A, &R, 0, 0);
  if (st >= 0 && R.tend > 0) st = catch_up_from(A, &R, at_tb);
  else if (st >= 0 && info->events > R.ev0) st = zeno_check(A, &R);
  return run_to_end(A, &R, st);
}
