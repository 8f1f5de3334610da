/* switched — a switched LCS (cup_switching, catchup/lcs.h) run one
 * configuration at a time (docs/netlist.md, "Switches"; docs/design.md,
 * "Switched circuits"). Each configuration has its own integrator, made
 * from its LCS the first time the configuration is in force and kept: a
 * run allocates nothing once every configuration has occurred. The
 * integrator steps to the switching times, which the sources alone fix
 * for switches gated by them (breakpoints, found by the model), and at each
 * one the state jumps onto the new configuration's constraints (the model's
 * projection in the energy metric), then its integrator goes on from there
 * (projecting onto its K(t) first, as at any breakpoint).
 *
 * The adaptive scheme runs switched circuits: its steps end on breakpoints
 * already, and a window [ta, tb] of one configuration is its run from ta
 * to tb (cup_adaptive_window). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "integrator_impl.h"
#include "adaptive.h"

#define SW_MAX 64          /* configurations (the model forms at most this many) */

struct cup_swrun {
  cup_switching ops;
  const cup_input *u;
  cup_integrator_options o;
  int n;
  cup_integrator *child[SW_MAX];
  int cur;                 /* the configuration in force (its child answers state and zeta) */
  double *x;
};

static int child_of(cup_swrun *S, int topo, char *errmsg) {
  if (topo < 0 || topo >= SW_MAX) return cup_fail(errmsg, CUP_ERR_UNSUPPORTED, "more than %d switch configurations", SW_MAX);
  if (S->child[topo]) return CUP_OK;
  const cup_lcs *L = S->ops.lcs(S->ops.ctx, topo);
  char msg[CUP_ERRMSG_LEN];
  int st = cup_integrator_create(&S->child[topo], L, S->u, &S->o, msg);
  return st ? cup_fail(errmsg, st, "switch configuration %d: %s", topo, msg) : CUP_OK;
}


static void sw_free(cup_swrun **Sp) {
  cup_swrun *S = *Sp;
  if (!S) return;
  for (int k = 0; k < SW_MAX; k++) cup_integrator_free(&S->child[k]);
  free(S->x);
  free(S);
  *Sp = NULL;
}

static const cup_integrator *sw_child(const cup_swrun *S) { return S->child[S->cur]; }

/* One window's statistics into the run's. */
static void add_info(cup_run_info *info, const cup_run_info *w) {
  info->status = cup_status_merge(info->status, w->status);
  if (w->status != CUP_OK && info->message[0] == '\0') memcpy(info->message, w->message, sizeof info->message);
  if (w->status < 0) memcpy(info->message, w->message, sizeof info->message);
  info->step = w->step;
  info->t = w->t;
  info->projected += w->projected;
  info->skipped += w->skipped;
  info->not_certified += w->not_certified;
  info->dual_iterations += w->dual_iterations;
  info->factorizations += w->factorizations;
  info->max_eps_cert = fmax(info->max_eps_cert, w->max_eps_cert);
  info->max_eta_cert = fmax(info->max_eta_cert, w->max_eta_cert);
  info->samples += w->samples;
  info->events += w->events;
  info->rejected += w->rejected;
  if (!(info->err_est >= w->err_est)) info->err_est = isnan(w->err_est) ? info->err_est : w->err_est;
}

static int sw_run(cup_integrator *I, const double *x0, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  cup_swrun *S = I->swr;
  const cup_switching *sw = &S->ops;
  double T = S->o.T, t = 0;
  memset(info, 0, sizeof *info);
  info->err_est = NAN;
  cup_copy(S->x, x0, S->n);
  int topo = 0, st = sw->settle(sw->ctx, &topo, 0, x0, NULL, info->message);
  long steps = 0, next_sample = 0;
  for (int first = 1; st >= 0 && t < T; first = 0) {
    sw->jump(sw->ctx, topo, S->x);               /* onto the configuration's constraints */
    if (first && memcmp(S->x, x0, sizeof(double) * (size_t)S->n)) {
      info->status = CUP_WARN_X0_OUTSIDE;
      snprintf(info->message, sizeof info->message, "x0 is off the constraints of the switches' configuration at "
               "t = 0 (a loop of capacitors or a cut of inductors): it is projected onto them, and the first "
               "sample is the projection");
    }
    st = child_of(S, topo, info->message);
    if (st) break;
    S->cur = topo;
    if (sw->state_gated(sw->ctx, topo)) {
      st = cup_fail(info->message, CUP_ERR_UNSUPPORTED, "t = %g: a switch's control depends on the circuit's "
                    "state in this configuration (circuit-gated switches are not run yet; gate it from sources)", t);
      break;
    }
    double tb;
    st = sw->next(sw->ctx, topo, t, T, &tb);
    if (st) { st = cup_fail(info->message, CUP_ERR_CALLBACK, "t = %g: the input u(t) failed", t); break; }
    cup_run_info w;
    cup_integrator *C = S->child[topo];
    int wst = cup_adaptive_window(C->ad, t, tb, S->x, first, &steps, &next_sample, sink, sink_ctx, &w);
    add_info(info, &w);
    if (wst < 0) { st = wst; break; }
    cup_copy(S->x, cup_adaptive_state(C->ad), S->n);
    t = tb;
    if (t < T) {
      st = sw->settle(sw->ctx, &topo, t, S->x, NULL, info->message);
      if (st) break;
    }
  }
  if (st < 0) info->status = st;
  info->step = steps;
  info->t = t;
  return info->status;
}


static const cup_swops ops = {sw_run, sw_free, sw_child};

int cup_integrator_create_switched(cup_integrator **out, const cup_switching *sw, const cup_input *u,
                                   const cup_integrator_options *o, char *errmsg) {
  if (!out || !sw || !o || !sw->settle || !sw->next || !sw->lcs || !sw->jump || !sw->state_gated)
    return cup_fail(errmsg, CUP_ERR_ARG, "switched integrator: NULL argument");
  *out = NULL;
  if (o->scheme != CUP_SCHEME_ADAPTIVE)
    return cup_fail(errmsg, CUP_ERR_UNSUPPORTED, "a circuit with switches runs under the adaptive scheme (it steps "
                    "to the switching times); the %s scheme does not switch yet", cup_scheme_name(o->scheme));
  if (o->estimate)
    return cup_fail(errmsg, CUP_ERR_UNSUPPORTED, "a circuit with switches: the adaptive scheme estimates its error "
                    "itself (estimate is for the fixed-step schemes)");
  cup_integrator *I = calloc(1, sizeof *I);
  cup_swrun *S = calloc(1, sizeof *S);
  if (!I || !S) { free(I); free(S); return cup_fail(errmsg, CUP_ERR_NOMEM, "out of memory"); }
  I->swr = S;
  I->swo = &ops;
  S->ops = *sw;
  S->u = u;
  S->o = *o;
  int st = child_of(S, 0, errmsg);
  if (!st) {
    const cup_lcs *L = sw->lcs(sw->ctx, 0);
    I->o = *o;
    I->L = L;
    I->u = u;
    I->n = S->n = cup_lcs_dim(L);
    I->m = cup_lcs_rows(L);
    I->p = cup_lcs_inputs(L);
    if (!(S->x = malloc(sizeof(double) * ((size_t)S->n + 1)))) st = cup_fail(errmsg, CUP_ERR_NOMEM, "out of memory");
  }
  if (st) { cup_integrator_free(&I); return st; }
  *out = I;
  return CUP_OK;
}
