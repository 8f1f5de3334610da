/* scene_pss — a scene's steady state, solved the one way catchup-run and
 * the steady-state sweeps solve it, and the integrator of its period that
 * notes where a signal may jump (scene_pss.h). */
#include <stddef.h>
#include "catchup.h"
#include "scene_pss.h"
#include "analysis/pss_run.h"

int scene_pss_solve(cup_scene *s, const cup_integrator_options *o, cup_pss **r, double *T, double *t0,
                    cup_integrator_options *period, int *stage, char *errmsg) {
  const cup_scene_steady *q = cup_scene_steady_state(s);
  *r = NULL;
  *stage = SCENE_PSS_PHASE;
  int st = cup_scene_steady_phase(s, q->pss.period, T, t0, errmsg);   /* the sources from t0 on */
  if (st) return st;
  *stage = SCENE_PSS_SETUP;
  cup_integrator_options mo;                      /* the period map: the run's, over one period */
  pss_map_options(o, cup_scene_options(s)->T, *T, q->pss.map_tol, &mo);
  mo.on_step = NULL;
  cup_integrator *I = NULL;
  st = cup_scene_integrator(s, &mo, &I, errmsg);
  if (!st) {
    *stage = SCENE_PSS_NEWTON;
    st = cup_pss_solve_map(r, I, cup_scene_dim(s), *T, cup_scene_x0(s), &q->pss, errmsg);
  }
  cup_integrator_free(&I);
  if (st < 0) {
    cup_scene_set_time_origin(s, 0, NULL);       /* no steady state: the sources as written */
    return st;
  }
  *period = mo;                                   /* one period, as accurate as the steady state */
  period->output = CUP_OUTPUT_SAMPLES;
  period->output_samples = q->samples;
  period->output_t0 = 0;
  return st;
}

/* The model's switching, each change of configuration at t noted as a
 * jump time (the one at t = 0 is the period's start: pss_jumps_add drops it). */
static int noted_settle(void *ctx, int *topo, double t, const double *x, const double *zeta, char *errmsg) {
  pss_jumps *J = ctx;
  int before = *topo, st = J->sw.settle(J->sw.ctx, topo, t, x, zeta, errmsg);
  if (!st && *topo != before) pss_jumps_add(J, t);
  return st;
}
static int noted_next(void *ctx, int topo, double t, double tmax, double *tnext) {
  pss_jumps *J = ctx;
  return J->sw.next(J->sw.ctx, topo, t, tmax, tnext);
}
static const cup_lcs *noted_lcs(void *ctx, int topo) {
  pss_jumps *J = ctx;
  return J->sw.lcs(J->sw.ctx, topo);
}
static void noted_jump(void *ctx, int topo, double *x) {
  pss_jumps *J = ctx;
  J->sw.jump(J->sw.ctx, topo, x);
}
static int noted_state_gated(void *ctx, int topo) {
  pss_jumps *J = ctx;
  return J->sw.state_gated(J->sw.ctx, topo);
}
static int noted_crossed(void *ctx, int topo, double t, const double *x) {
  pss_jumps *J = ctx;
  return J->sw.crossed(J->sw.ctx, topo, t, x);
}

int scene_pss_period_integrator(cup_scene *s, const cup_integrator_options *period, pss_jumps *J,
                                cup_integrator **I, char *errmsg) {
  cup_integrator_options o = *period;
  pss_jumps_breaks(J, cup_scene_input(s));       /* the sources' own jumps and corners (PULSE edges, PWL knots) */
  J->on_event = o.on_event;                       /* the run's own, after the time is noted */
  J->event_ctx = o.event_ctx;
  o.on_event = pss_jumps_event;
  o.event_ctx = J;
  cup_netlist *nl = cup_scene_netlist(s);
  if (!nl || !cup_netlist_switching(nl, &J->sw)) return cup_scene_integrator(s, &o, I, errmsg);
  cup_switching noted = {.ctx = J, .settle = noted_settle, .next = noted_next, .lcs = noted_lcs, .jump = noted_jump,
                         .state_gated = noted_state_gated, .crossed = noted_crossed};
  return cup_integrator_create_switched(I, &noted, cup_scene_input(s), &o, errmsg);
}
