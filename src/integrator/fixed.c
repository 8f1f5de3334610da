/* fixed — the fixed-step schemes' run: the inexact catching-up algorithm
 * (paper, Sec. 3, eq. for x_{k+1}) on the grid t_k = k T / n, a free step
 * (freestep.c), then an (eps_n, eta_n)-projection onto K(t_{k+1}) in the
 * P-metric (projector.c) or the step's exact LCP (lcp/step.c), stretches of
 * a small LCS's steps fused (faststep.c); the output samples
 * (fixed_output.h), the estimate's run at n/2, stops and their resumption;
 * and the table that makes the four schemes one entry (fixed_setup.c sets
 * them up, fixed_window.c takes a switched circuit's windows). A step
 * allocates nothing and a run keeps only the current state. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "fixed.h"
#include "fixed_setup.h"
#include "faststep.h"
#include "freestep.h"
#include "tally.h"
#include "lcp/step.h"
#include "model/lcs_impl.h"
#include "util/clock.h"
#include "util/fail.h"
#include "set/polyset_impl.h"
#include "set/set_impl.h"
#include "projector/projector.h"
#include "estimate.h"
#include "integrator_impl.h"
#include "fixed_impl.h"
#include "fixed_output.h"

/* The first step j >= k whose end the loop must see itself: a sample (and
 * the step before an interpolated one, whose zeta it keeps), the interrupt
 * check after each 1024th step, the last step (faststep.c runs the ones
 * before it). */
static long loop_stop(const fixed_ws *F, const sampler *sp, int sink, long k) {
  const cup_integrator_options *o = &F->o;
  long stop = k | 1023, next = LONG_MAX;       /* next: the first k' > k that selected() may take */
  if (stop > F->kend - 1) stop = F->kend - 1;
  if (sink && o->output == CUP_OUTPUT_EVERY)
    next = o->output_every == 1 ? k + 1 : (k / o->output_every + 1) * o->output_every;
  if (sink && o->output == CUP_OUTPUT_SAMPLES && sp->kdue != LONG_MAX) {
    next = sp->aligned ? sp->kdue : sp->kdue - 1;
    if (next <= k) next = k + 1;
  }
  return next - 1 < stop ? next - 1 : stop;
}

/* The estimate's run at n/2 from F->x0 (its states kept for the
 * comparisons). CUP_ERR_INTERRUPTED when the interrupt flag stopped it:
 * the run it serves stops too (a signal is not to wait for half the work). */
static int coarse_run(fixed_ws *F, cup_run_info *info) {
  cup_run_info hi;
  int st = fixed_run(F->half, F->x0, estimate_keep, &F->est, &hi);
  estimate_start(&F->est, st >= 0);
  info->err_est = estimate_value(&F->est);
  return st == CUP_ERR_INTERRUPTED && F->o.interrupt && *F->o.interrupt ? CUP_ERR_INTERRUPTED : CUP_OK;
}

/* A stop at the end of step k that a checkpoint can resume from: where,
 * the output schedule's place, and the status and message it replaces
 * (a warning met before it is the resumed run's, as the whole run's). */
static int halt(fixed_ws *F, cup_run_info *info, int status, long k, double t, const char *what, int phase,
                const sampler *sp) {
  F->stop.phase = phase;
  F->stop.k = k;
  F->stop.next_j = sp->next_j;
  F->stop.status = info->status;
  memcpy(F->stop.message, info->message, sizeof F->stop.message);
  return stop_at(info, status, k, t, what);
}

/* g = F + G u(t) for a moving polyset. */
int fixed_moving_offset(fixed_ws *F, double t) {
  if (F->gterms) input_eval_terms(F->u, F->gterms, F->ngterms, t, F->ut);   /* those with a column in G */
  else if (cup_input_eval(F->u, t, F->ut)) return CUP_ERR_CALLBACK;
  memcpy(F->g, F->K->g0, sizeof(double) * (size_t)F->m);
  la_sparse_gaxpy(F->G, F->ut, F->g);
  if (!F->use_theta) return cup_projector_set_offset(F->proj, F->g);
  for (int i = 0; i < F->m; i++)           /* the theta step reads g itself */
    if (!isfinite(F->g[i])) return CUP_ERR_NONFINITE;
  return CUP_OK;
}

static void describe_projection_error(char *buf, size_t size, int st, const cup_proj_info *pi) {
  if (st == CUP_ERR_EMPTY_SET)
    snprintf(buf, size, "K(t) is empty: Farkas certificate y >= 0 with g^T y = %.3g, "
             "||C^T y||_{P^-1} = %.3g (no point of K within %.3g of 0)",
             pi->farkas_gap, pi->farkas_residual,
             pi->farkas_residual > 0 ? -pi->farkas_gap / pi->farkas_residual : INFINITY);
  else if (st == CUP_ERR_NONFINITE || st == CUP_ERR_DIVERGED)
    snprintf(buf, size, "the free step produced NaN or Inf, or overflowed (the scheme diverged)");
  else if (st == CUP_ERR_LINALG)
    snprintf(buf, size, "the step's LCP has a singular principal block (M = h C W B is not a "
             "P-matrix at this step size)");
  else
    snprintf(buf, size, "projection failed: %s", cup_status_string(st));
}

/* A step's state beyond its range (tally.h): the scheme diverged. */
static __attribute__((noinline, cold)) int diverged(const fixed_ws *F, cup_run_info *info, long k, double t,
                                                    const double *x) {
  char what[200];
  int j = tally_state_worst(x, F->n);
  int len = snprintf(what, sizeof what, "the state left its range ||x||_1 <= %g (x[%d] = %.3g): the scheme "
                     "diverged", CUP_STATE_MAX, j, x[j]);
  if (F->o.scheme == CUP_SCHEME_EXPLICIT && F->h_rho > 2 && len > 0 && (size_t)len < sizeof what)
    snprintf(what + len, sizeof what - (size_t)len, "; explicit scheme with h*rho(A) = %.3g > 2", F->h_rho);
  return stop_at(info, CUP_ERR_DIVERGED, k, t, what);
}

/* A polyset step whose answer z (in xnew) has no certified distance to
 * K(t_{k+1}) (eta = inf) is not passed on as it is (issue 27, guarantee 6),
 * the projector's exact method (proj_exact) standing in whatever
 * method the options ask: first z's own distance from the projection v of z, d_K(z) <=
 * ||z - v||_P + eta(v) (z kept: the theta step's is not a projection, and
 * an exact step's is more accurate than a certified one); then, for a step
 * that projects xf, the projector's answer (its dual methods walk to known
 * feasible points), once more with the last state offered as one. Returns
 * the step's status; CUP_ERR_UNCERTIFIED (info->message naming step, time
 * and set) when z is provably farther than eta_n from K(t) and nothing
 * certifies. xf: the step's free point (recomputed by the caller when the
 * fused steps kept it in registers). */
static __attribute__((noinline, cold)) int certify_or_stop(fixed_ws *F, long k, double t, const double *g,
                                                           cup_proj_info *pi, int st, cup_run_info *info) {
  cup_proj_info pp = {0}, first = *pi;
  int ps = cup_projector_set_offset(F->proj, F->use_theta && F->th.D ? F->th.geff : g);   /* D: K shifted by D zeta */
  double own = INFINITY;
  if (ps == CUP_OK && (ps = proj_exact(F->proj, F->xnew, F->v, &pp)) >= 0 && pp.eta_cert < INFINITY)
    own = polyset_metric_dist_hi(F->K, F->xnew, F->v, NULL, F->v + F->n) + pp.eta_cert;
  if (own <= pi->eta_target) ps = CUP_OK;
  else if (ps >= 0 && (!F->use_theta || F->o.scheme == CUP_SCHEME_EXPLICIT)) {   /* z projects xf */
    for (int offer = !F->use_theta; offer < 2 && ps >= 0 && !(pi->eta_cert < INFINITY); offer++) {
      if (offer && !cup_projector_offer_feasible(F->proj, F->x)) break;
      if ((ps = proj_exact(F->proj, F->xf, F->v, &pp)) >= 0 && pp.eta_cert < own) {
        *pi = pp;
        st = ps;
        F->zeta_from = 2;
        la_copy(F->xnew, F->v, F->n);
      }
    }
  }
  if (!(pi->eta_cert < INFINITY) && own < INFINITY) {
    *pi = first;
    pi->eta_cert = own;
    st = pi->eps_cert <= pi->eps_target && own <= pi->eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  }
  if (pi->eta_cert < INFINITY) return pi->status = st;
  /* still none. Each row's half-space bounds d_K(z) from below: a z that
   * is farther than eta_n (or, below what rounding allows, 1e-10 of the
   * scale) from one of them is certainly no (eps, eta)-projection, and
   * stops the run; one nearer is kept, warned of (a set without interior,
   * as two opposite rows, has no point certainly in it but where they pin
   * a coordinate to 0, certify.c's snap_zeros, and no distance to it can be
   * certified: the answer may be right) */
  const double *sz = F->s0, *gam = F->sg;        /* z's slack and its rounding */
  if (F->use_theta && F->th.D) sz = F->th.s, gam = F->th.gam;   /* the step's own, with D zeta's rounding */
  else polyset_slack(F->K, g, F->xnew, F->s0, F->sg);
  int row = -1;
  double far = 0, tol = la_max(pi->eta_target, 1e-10 * cup_polyset_norm(F->K, F->xnew));
  for (int i = 0; i < F->m; i++) {
    double d = F->K->rownorm[i] > 0 ? (-sz[i] - gam[i]) / F->K->rownorm[i] : 0;   /* <= d_K(z) */
    if (d > far) { far = d; row = i; }
  }
  if (!(far > tol)) return pi->status = st > 0 ? st : CUP_WARN_NOT_CERTIFIED;
  char what[200];
  snprintf(what, sizeof what, "the answer is at least %.3g from K(t) (row %d), beyond eta_n = %.3g, and no method "
           "found a point within a certified distance of K(t)%s%s", far, row, pi->eta_target, ps < 0 ? ": " : "",
           ps < 0 ? cup_status_string(ps) : "");
  return stop_at(info, CUP_ERR_UNCERTIFIED, k, t, what);
}

/* The paper assumes x0 in K(0); say so when it is not (the first step
 * projects it), by the raw slack so that a point on the boundary passes.
 * With D != 0 the state is consistent when some zeta >= 0 makes
 * C x0 + D zeta + g >= 0 (the theta step's LCP at x0): a rectifier's
 * capacitor at rest is, though C x0 + g alone may be negative. 1 when x0
 * is not: the first step jumps (jump_size tells by how much). */
static int polyset_x0(fixed_ws *F, int fixed, cup_run_info *info) {
  const double *g0 = !fixed && fixed_moving_offset(F, 0) == CUP_OK ? F->g : F->K->g0;
  int consistent = F->use_theta ? lcp_step_start(&F->th, F->x, g0)
                                : polyset_slack(F->K, g0, F->x, F->s0, NULL) >= 0;
  if (consistent) return 0;
  info->status = CUP_WARN_X0_OUTSIDE;
  snprintf(info->message, sizeof info->message, "step 0 (t = 0): x0 is %s; the first step projects it",
           F->L && F->L->has_D ? "not consistent (no zeta >= 0 makes C x0 + D zeta + g >= 0)" : "outside K(0)");
  return 1;
}

/* After the first step (status st) from an x0 that was not consistent: the
 * jump's size, as far as that step moved x beyond its free step (the jump
 * itself, to O(h)), into the warning's message if it is still the run's
 * status. Such a run takes the general path (bit for bit the fused one's),
 * where this is called; out of line and cold, since inlined it cost the
 * fused loop an instruction a step (callgrind, paper-fig2, n = 1e5). */
__attribute__((noinline, cold)) static void jump_size(fixed_ws *F, int st, cup_run_info *info) {
  F->jump = 0;
  double big = 0;
  int at = 0;
  for (int j = 0; j < F->n; j++)
    if (fabs(F->xnew[j] - F->xf[j]) > big) big = fabs(F->xnew[j] - F->xf[j]), at = j;
  if (st < 0 || info->status != CUP_WARN_X0_OUTSIDE) return;
  size_t len = strlen(info->message);
  snprintf(info->message + len, sizeof info->message - len, ", a jump of %.3g in x[%d] (max-norm)", big, at);
}

/* Projections of one step again after rows were found missing (each adds
 * at least one row; a crowd needs one in the jams seen). */
enum { RECHECKS = 8 };

/* The set at t_{k+1} (and x_k), then the projection of the free point. */
static int general_step(fixed_ws *F, long k, double t, const double *xk, const double *xf,
                        double *z, cup_proj_info *pi, cup_run_info *info) {
  if (F->p > 0 && F->u && cup_input_eval(F->u, t, F->ut))
    return stop_at(info, CUP_ERR_CALLBACK, k, t, "the input u(t) that moves the set failed");
  int st = cup_setproj_move(F->sp, t, F->ut, xk);
  if (st == CUP_ERR_NONFINITE) {
    char what[WHAT_LEN];
    snprintf(what, sizeof what, "the set's parameters from u(t) are not finite: %s", cup_setproj_message(F->sp));
    return stop_at(info, CUP_ERR_CALLBACK, k, t, what);
  }
  if (st == CUP_OK && (st = cup_setproj_project(F->sp, xf, z, pi)) == CUP_ERR_NONFINITE) {
    char what[WHAT_LEN];                 /* as on the polyset path: the state overflowed */
    snprintf(what, sizeof what, "the free step produced NaN or Inf, or overflowed (the scheme diverged): %s",
             cup_setproj_message(F->sp));
    return stop_at(info, CUP_ERR_DIVERGED, k, t, what);
  }
  /* a state-dependent set may find that the step's rows missed a
   * constraint its answer violates (a crowd: a pair that closed more than
   * the contact margin in one step); the step is then projected again, warm,
   * with that row, its work added to the step's */
  for (int again = 0; st >= 0 && again < RECHECKS; again++) {
    int rc = setproj_recheck(F->sp, t, xk, z);
    if (rc <= 0) {
      if (rc < 0) st = rc;
      break;
    }
    cup_proj_info first = *pi;
    st = cup_setproj_project(F->sp, xf, z, pi);
    pi->iterations += first.iterations;
    pi->factorizations += first.factorizations;
    pi->row_updates += first.row_updates;
  }
  if (st < 0) return stop_at(info, st, k, t, cup_setproj_message(F->sp));
  /* never a point without a certified distance passed on (issue 27); a
   * state polyset's projector keeps the polyset's rule (an answer within
   * rounding of a set without interior is warned of), not applied here yet */
  if (!(pi->eta_cert < INFINITY) && F->S->kind != CUP_SET_STATE_POLYSET) {
    char what[200];
    snprintf(what, sizeof what, "the %s: no point within a certified distance of the set was found (eta = inf)%s%s",
             cup_set_kind_name(F->S->kind), cup_setproj_message(F->sp)[0] ? ": " : "", cup_setproj_message(F->sp));
    return stop_at(info, CUP_ERR_UNCERTIFIED, k, t, what);
  }
  long rows = cup_setproj_rows(F->sp);
  if (rows > info->max_rows) info->max_rows = rows;
  return st;
}

/* x0 against C(0, x0), by its projection: warn when it moves. */
static int general_x0(fixed_ws *F, cup_run_info *info) {
  cup_proj_info pi;
  int st = general_step(F, 0, 0, F->x, F->x, F->xf, &pi, info);
  if (st < 0) return st;
  if (!pi.skipped) {
    info->status = CUP_WARN_X0_OUTSIDE;
    snprintf(info->message, sizeof info->message,
             "step 0 (t = 0): x0 is outside C(0); the first step projects it");
  }
  return CUP_OK;
}


/* The run's start (x0's checks and warnings, the estimate's run at n/2,
 * x0's sample), then its steps. */
int fixed_run(void *ws, const double *x0, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  fixed_ws *F = ws;
  memset(info, 0, sizeof *info);
  info->err_est = NAN;
  const cup_integrator_options *o = &F->o;
  int n = F->n;
  info->eps_target = F->eps_n;
  info->eta_target = F->eta_n;
  info->h_rho = F->h_rho;
  if (tally_state_beyond(x0, n)) {
    int w = tally_state_worst(x0, n);
    char what[160];
    if (isfinite(x0[w])) snprintf(what, sizeof what, "x0 is beyond the range of a state, ||x||_1 <= %g "
                                  "(CUP_STATE_MAX): x0[%d] = %g", CUP_STATE_MAX, w, x0[w]);
    else snprintf(what, sizeof what, "x0[%d] is %g", w, x0[w]);
    return stop_at(info, isfinite(x0[w]) ? CUP_ERR_ARG : CUP_ERR_NONFINITE, 0, 0, what);
  }
  memcpy(F->x, x0, sizeof(double) * (size_t)n);
  cup_projector_reset(F->proj);
  F->zeta_from = 0;
  F->restart = 0;
  int fixed = F->fixed || !F->u;
  F->stop.phase = CUP_STOP_NONE;
  F->rebuilds0 = cup_setproj_rebuilds(F->sp);
  splitcheck_reset(&F->chk);
  if (F->K && fixed) cup_projector_set_offset(F->proj, F->K->g0);
  F->jump = F->K && polyset_x0(F, fixed, info);
  /* zeta at t = 0 (x0's sample, and the left end of the samples inside
   * the first step): theta's LCP at x0, which polyset_x0 solved and its
   * first step starts from (with D, the multipliers the state fixes: a
   * bridge's pair carrying an inductor's current; 0 with D = 0 and where
   * x0 is not consistent); the other schemes' 0 (no step has acted yet) */
  if (F->K && F->use_theta) F->zeta_from = 1;
  if (!F->K && general_x0(F, info) < 0) return info->status;
  int stiff = o->scheme == CUP_SCHEME_EXPLICIT && F->h_rho > 2;
  if (stiff) {
    info->status = CUP_WARN_STIFF;
    snprintf(info->message, sizeof info->message,
             "explicit scheme with h*rho(A) = %.3g > 2: the free step is unstable; use the theta "
             "scheme, or implicit/exponential if no constraint acts on the fast states", F->h_rho);
  }
  if (F->split > CUP_SPLIT_WARN) {   /* NaN (no memory to tell) does not warn */
    info->status = CUP_WARN_SPLITTING;
    snprintf(info->message, sizeof info->message,
             "%s scheme: one step relaxes a fraction %.4g of constraint direction %d (h above its "
             "time constant); projecting along B loses what that relaxation moved, an error of "
             "that order: use the theta scheme, or h well below that time constant", cup_scheme_name(o->scheme),
             F->split, F->split_row);
  }
  sampler sp = {0};
  sampler_next(F, &sp);
  F->zs = 1;
  if (F->zprev) {
    la_zero(F->zprev, F->m);
    if (F->zeta_from) fixed_zeta(F, F->zprev);
  }
  if (F->half) {
    memcpy(F->x0, x0, sizeof(double) * (size_t)n);      /* a resumed run runs the coarse one again */
    if (coarse_run(F, info) == CUP_ERR_INTERRUPTED)
      return halt(F, info, CUP_ERR_INTERRUPTED, 0, 0, "interrupted (in the estimate's run at n/2)",
                  CUP_STOP_SAMPLE_DUE, &sp);
    estimate_anchor(&F->est, 0, F->x);             /* the samples of step 1 start from x0 */
  }
  if (sink && o->output != CUP_OUTPUT_SAMPLES && selected(F, &sp, 0)) {
    info->samples++;
    if (sink(0, 0.0, F->x, sink_ctx))
      return halt(F, info, CUP_ERR_INTERRUPTED, 0, 0, "stopped by the output sink", CUP_STOP_SAMPLE_REFUSED, &sp);
  }
  if (sink && o->output == CUP_OUTPUT_SAMPLES && emit_samples(F, &sp, 0, sink, sink_ctx, info))
    return halt(F, info, CUP_ERR_INTERRUPTED, 0, 0, "stopped by the output sink", CUP_STOP_SAMPLE_REFUSED, &sp);
  return fixed_steps(F, 0, sp.next_j, sink, sink_ctx, info);
}

/* The step's answer without a certified distance to K(t), or its error:
 * the run's stop (negative), or the step's status. fused: the free point
 * stayed in faststep.c's registers (xf computed again when needed). */
static inline int step_checked(fixed_ws *F, long k, double t0, double t1, int fixed, int fused, int stiff,
                               cup_proj_info *pi, int st, cup_run_info *info) {
  if (st >= 0 && F->K && !(pi->eta_cert < INFINITY)) {   /* no certified distance: another method, or stop */
    if (fused && freestep_apply(&F->fs, t0, t1, F->x, F->xf) < 0) st = CUP_ERR_CALLBACK;
    else if ((st = certify_or_stop(F, k + 1, t1, fixed ? F->K->g0 : F->g, pi, st, info)) < 0) return st;
  }
  if (st < 0) {                          /* the polyset path's errors */
    char what[WHAT_LEN];
    describe_projection_error(what, sizeof what, st, pi);
    if (stiff && (st == CUP_ERR_NONFINITE || st == CUP_ERR_DIVERGED)) {  /* keep the cause in view */
      size_t len = strlen(what);
      snprintf(what + len, sizeof what - len, "; explicit scheme with h*rho(A) = %.3g > 2", F->h_rho);
    }
    return stop_at(info, st == CUP_ERR_NONFINITE ? CUP_ERR_DIVERGED : st, k + 1, t1, what);
  }
  return st;
}

/* Step k + 1 as faststep.c does not take it: the free step, then the
 * projection onto a general set, the theta step's LCP or the projector's
 * projection, checked. */
static int step(fixed_ws *F, long k, double t0, double t1, int fixed, long rebuilds0, int stiff,
                cup_proj_info *pi, cup_run_info *info) {
  int st = freestep_apply(&F->fs, t0, t1, F->x, F->xf);
  if (st < 0)
    return stop_at(info, st, k + 1, t1, st == CUP_ERR_CALLBACK
                   ? "a user callback (input or perturbation) failed or returned NaN/Inf"
                   : cup_status_string(st));
  if (st > 0 && info->status == CUP_OK) {
    info->status = st;
    snprintf(info->message, sizeof info->message, "step %ld (t = %.17g): %s", k + 1, t1, cup_status_string(st));
  }
  if (F->sp) {
    st = general_step(F, k + 1, t1, F->x, F->xf, F->xnew, pi, info);
    info->set_rebuilds = cup_setproj_rebuilds(F->sp) - rebuilds0;
    return st;                           /* stopped already when negative */
  }
  if (!fixed && (st = fixed_moving_offset(F, t1)) != CUP_OK)
    return stop_at(info, st == CUP_ERR_NONFINITE ? CUP_ERR_CALLBACK : st, k + 1, t1,
                   "the input u(t) that moves K failed or returned NaN/Inf");
  if (F->use_theta) {
    double S = cup_polyset_norm(F->K, F->xf);
    const double *g = fixed ? F->K->g0 : F->g;
    st = lcp_step_solve(&F->th, g, F->xf, F->xnew, S, F->eps_n > 0 ? F->eps_n : -1,
                        F->eta_n > 0 ? F->eta_n : 1e-10 * S, pi);
    if (st == CUP_ERR_LINALG) {
      /* pivoting failed: an empty K(t) (the projector proves it with a
       * Farkas certificate) or, for theta > 0, M not a P-matrix; for the
       * explicit step the projector's answer is the step */
      cup_proj_info pp = {0};
      int ps = cup_projector_set_offset(F->proj, g);
      if (ps == CUP_OK) ps = cup_project(F->proj, F->xf, F->xnew, &pp);
      if (ps == CUP_ERR_EMPTY_SET || F->o.scheme == CUP_SCHEME_EXPLICIT) { st = ps; *pi = pp; F->zeta_from = 2; }
    } else {
      F->zeta_from = 1;
    }
    if (F->jump) jump_size(F, st, info);
  } else {
    st = cup_project(F->proj, F->xf, F->xnew, pi);
    F->zeta_from = 2;
    if (F->jump) jump_size(F, st, info);
    if (F->chk.on && st >= 0) splitcheck_step(&F->chk, k + 1, t1, F->xf, F->xnew, cup_projector_lambda(F->proj));
  }
  return step_checked(F, k, t0, t1, fixed, 0, stiff, pi, st, info);
}

/* The support of the theta step's last zeta (with D), a bit per row. */
unsigned long long fixed_theta_support(const fixed_ws *F) {
  unsigned long long J = 0;
  for (int i = 0; i < F->m; i++)
    if (F->th.lcp.lam[i] > 0) J |= 1ull << i;
  return J;
}

/* Steps taken again at most after a window's first (restart_again). */
enum { RESTARTS = 3 };

/* A window's first step with D and theta < 1 (integrator_window armed
 * it). Its carry h (1 - theta) W B Pi zeta_k took zeta_k from the LCP at
 * x_k alone, whose support (the mode) the state does not always fix: at a
 * switching that leaves a bridge's leg open with i(L1) = 0 (or a diode at
 * zero current) zeta_k may be any point of a segment (both diodes off,
 * the leg's node anywhere between the rails), and the pivoting's pick,
 * often a rounding's sign (i = -8e-17: D4 on), is not the mode the flow
 * takes from t_k. That carry moved the first step by O(h) (i(L1) by
 * 100 V h / (2 L) in the full bridge), an error that stays: first order.
 * Within one mode Pi zeta is a function of the state, so only a support
 * that the step's end does not keep can be wrong: then the step is taken
 * again from x_k with the carry of its own end's zeta (solve_d leaves it),
 * until the support holds (1: again; *again counts). zeta at t_k+ to O(h)
 * is a local error O(h^2) once, as an event inside a step makes, and
 * theta = 1/2 stays second order. A support that holds leaves the step as
 * it was, bit for bit. (steps calls step once, in a loop, so that step
 * stays inlined there: a second call site cost the bridge's theta run 3 %.) */
static __attribute__((noinline, cold)) int restart_again(fixed_ws *F, cup_proj_info *pi, int *again) {
  unsigned long long now = fixed_theta_support(F);
  if (*again == 0) F->restart_iters = 0;
  if (now == F->mode0 || *again == RESTARTS) {
    F->restart = 0;
    pi->iterations += F->restart_iters;            /* the step's work, all its solves */
    return 0;
  }
  F->restart_iters += pi->iterations;
  F->mode0 = now;
  (*again)++;
  return 1;
}

/* The steps from k0 (the sampler at next_j) to kend, as a run takes them
 * after its start; a window and a resumed run go on through them. */
int fixed_steps(fixed_ws *F, long k0, long next_j, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  const cup_integrator_options *o = &F->o;
  sampler sp = {next_j, 0, 0, 0};
  sampler_next(F, &sp);
  int n = F->n, fixed = F->fixed || !F->u, stiff = o->scheme == CUP_SCHEME_EXPLICIT && F->h_rho > 2;
  long rebuilds0 = F->rebuilds0;
  double start = o->max_wall_seconds > 0 ? now_seconds() : 0;
  int fast = F->fast.on && !o->on_step && !F->half && !F->jump;   /* the estimate compares every step */
  F->fast.hold = F->restart ? k0 + 1 : 0;          /* (a window's first step checked: restart_again) */
  /* a record every step: a konst run records its steps itself, as below */
  F->fast.recording = fast && F->fast.konst && sink && o->output == CUP_OUTPUT_EVERY && o->output_every == 1;
  F->fast.rec = (faststep_rec){sink, sink_ctx, &F->zeta_from};
  for (long k = k0; k < F->kend; k++) {
    cup_proj_info pi;
    int st = CUP_FAST_DECLINED;
    if (fast && k >= F->fast.hold) {     /* hold: a run of steps that left the range, stepped here */
      long stop = loop_stop(F, &sp, sink && !F->fast.recording, k);
      /* a recording run books the loop's last step too, but for one the interrupt check follows */
      F->fast.book_last = F->fast.recording && stop == F->kend - 1 && (stop & 1023) != 1023;
      k = faststep_run(&F->fast, k, stop, F->x, F->xnew, &pi, &st, info);
      if (st == CUP_FAST_REFUSED)
        return halt(F, info, CUP_ERR_INTERRUPTED, k, grid_time(F, k), "stopped by the output sink",
                    CUP_STOP_SAMPLE_REFUSED, &sp);
      if (st == CUP_FAST_DONE) break;
    }
    double t0 = grid_time(F, k), t1 = grid_time(F, k + 1);
    if (st != CUP_FAST_DECLINED) {       /* fused: all that step() does, done by faststep.c */
      F->zeta_from = 1;
      st = step_checked(F, k, t0, t1, fixed, 1, stiff, &pi, st, info);
    } else {
      int again = 0;
      do st = step(F, k, t0, t1, fixed, rebuilds0, stiff, &pi, info);
      while (__builtin_expect(F->restart, 0) && st >= 0 && restart_again(F, &pi, &again));
    }
    if (st < 0) return st;
    if (tally_state_beyond(F->xnew, n)) return diverged(F, info, k + 1, t1, F->xnew);
    double *t = F->x; F->x = F->xnew; F->xnew = t;
    if (F->half) {
      estimate_compare(&F->est, k + 1, F->x);
      info->err_est = estimate_value(&F->est);
    }
    info->step = k + 1;
    info->t = t1;
    tally_projection(info, &pi);
    if (st == CUP_WARN_NOT_CERTIFIED) {
      if (info->not_certified++ == 0 && info->status == CUP_OK) {
        info->status = st;
        snprintf(info->message, sizeof info->message,
                 "step %ld (t = %.17g): projection not certified: eps %.3g (target %.3g), eta %.3g (target %.3g)",
                 k + 1, t1, pi.eps_cert, pi.eps_target, pi.eta_cert, pi.eta_target);
      }
    }
    if (o->on_step && o->on_step(k + 1, t1, &pi, o->step_ctx))
      return halt(F, info, CUP_ERR_INTERRUPTED, k + 1, t1, "stopped by the step callback", CUP_STOP_SAMPLE_DUE, &sp);
    if (sink && o->output == CUP_OUTPUT_SAMPLES) {
      if (emit_samples(F, &sp, k + 1, sink, sink_ctx, info))
        return halt(F, info, CUP_ERR_INTERRUPTED, k + 1, t1, "stopped by the output sink", CUP_STOP_SAMPLE_REFUSED, &sp);
      keep_zeta(F, &sp, k + 1);
    } else if (sink && selected(F, &sp, k + 1) && !(F->hold && k + 1 == F->kend)) {
      info->samples++;
      if (sink(k + 1, t1, F->x, sink_ctx))
        return halt(F, info, CUP_ERR_INTERRUPTED, k + 1, t1, "stopped by the output sink", CUP_STOP_SAMPLE_REFUSED, &sp);
    }
    if ((k & 1023) == 1023) {
      if (o->interrupt && *o->interrupt)
        return halt(F, info, CUP_ERR_INTERRUPTED, k + 1, t1, "interrupted", CUP_STOP_STEP_DONE, &sp);
      if (start > 0 && now_seconds() - start > o->max_wall_seconds)
        return halt(F, info, CUP_ERR_TIME_LIMIT, k + 1, t1, "wall-time limit reached", CUP_STOP_STEP_DONE, &sp);
    }
  }
  F->next_j = sp.next_j;
  if (F->chk.on && !F->window) splitcheck_verdict(&F->chk, o->scheme, o->n, info);
  return info->status;
}

static void fixed_wall_limit(void *ws, double seconds) { ((fixed_ws *)ws)->o.max_wall_seconds = seconds; }

/* A restored checkpoint (checkpoint.c) goes on from the step it stopped
 * after: the coarse run of the estimate again (the same states), the
 * stopped step's sample when it was still due or the sink refused it, then
 * the steps as a run takes them. */
static int fixed_resume(void *ws, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  fixed_ws *F = ws;
  int phase = F->stop.phase;
  long k = F->stop.k;
  sampler sp = {F->stop.next_j, 0, 0, 0};
  sampler_next(F, &sp);
  if (F->half) {
    double err = F->est.err;                     /* the comparisons made before the stop */
    int cst = coarse_run(F, info);
    F->est.err = err;
    info->err_est = estimate_value(&F->est);
    if (cst == CUP_ERR_INTERRUPTED)
      return halt(F, info, CUP_ERR_INTERRUPTED, k, grid_time(F, k), "interrupted (in the estimate's run at n/2)",
                  phase, &sp);
  }
  F->stop.phase = CUP_STOP_NONE;
  if (phase == CUP_STOP_SAMPLE_REFUSED) info->samples--;          /* counted when it was refused */
  if (F->o.output == CUP_OUTPUT_SAMPLES) {      /* the samples due at k, from x_k, x_{k-1} and zeta_{k-1} */
    if (sink && phase != CUP_STOP_STEP_DONE) {
      if (emit_samples(F, &sp, k, sink, sink_ctx, info))
        return halt(F, info, CUP_ERR_INTERRUPTED, k, grid_time(F, k), "stopped by the output sink",
                    CUP_STOP_SAMPLE_REFUSED, &sp);
      if (k > 0) keep_zeta(F, &sp, k);
    }
    return fixed_steps(F, k, sp.next_j, sink, sink_ctx, info);
  }
  int offer = phase == CUP_STOP_SAMPLE_REFUSED || (phase == CUP_STOP_SAMPLE_DUE && sink && selected(F, &sp, k));
  if (sink && offer) {
    info->samples++;
    if (sink(k, grid_time(F, k), F->x, sink_ctx))
      return halt(F, info, CUP_ERR_INTERRUPTED, k, grid_time(F, k), "stopped by the output sink",
                  CUP_STOP_SAMPLE_REFUSED, &sp);
  }
  return fixed_steps(F, k, sp.next_j, sink, sink_ctx, info);
}

static int takes(const cup_integrator_options *o) {
  return o->scheme == CUP_SCHEME_EXPLICIT || o->scheme == CUP_SCHEME_IMPLICIT ||
         o->scheme == CUP_SCHEME_EXPONENTIAL || o->scheme == CUP_SCHEME_THETA;
}

static const scheme_type fixed_type = {
  .name = "fixed-step", .takes = takes, .create = fixed_create, .free = fixed_free, .run = fixed_run,
  .state = fixed_state, .zeta = fixed_zeta, .grid = fixed_grid, .saves = fixed_saves, .stopped = fixed_stopped,
  .checkpoint = fixed_checkpoint, .resume = fixed_resume, .wall_limit = fixed_wall_limit,
};
const scheme_type *const scheme_fixed = &fixed_type;
