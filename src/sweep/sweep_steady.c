/* sweep_steady — steady-state sweeps (sweep_steady.h, docs/sweep-format.md,
 * "Steady-state sweeps"). A task is catchup-run --steady-state without the
 * file, solved the same way (io/scene_pss.h: the period and its phase, the
 * period map of the task's integrator options, Newton's method on it), then
 * one period from the steady state sampled in memory and measured as
 * catchup-run measures it (pss_measure: the signals the request names,
 * each element's power, the efficiency). */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sweep_steady.h"
#include "analysis/pss_run.h"
#include "io/scene_pss.h"
#include "util/clock.h"

void sw_steady_no_reference(const sw_sweep *s, sw_result *r, double *traj) {
  for (long j = 0; j < sw_traj_len(s); j++) traj[j] = NAN;
  r->status = CUP_OK;
  r->correction = r->cross_check = r->max_eps_cert = r->max_eta_cert = NAN;
  snprintf(r->message, sizeof r->message, "%s", SW_STEADY_REFERENCE);
}

typedef struct {
  cup_netlist *nl;
  const cup_integrator *I;
  int ns;
  long N, k;
  double *sig, *zeta;        /* N x ns signals; the step's multipliers */
} period_samples;

static int keep_sample(long k, double t, const double *x, void *ctx) {
  (void)k;
  period_samples *p = ctx;
  if (p->k >= p->N) return 0;
  cup_integrator_zeta(p->I, p->zeta);
  return cup_netlist_signals(p->nl, t, x, p->zeta, p->sig + p->k++ * p->ns) != CUP_OK ? CUP_ERR_CALLBACK : 0;
}

/* One period from x0 (options mo: scene_pss_solve's), measured into r->steady. */
static int measure(const sw_sweep *s, const sw_variant *v, const cup_scene_steady *q, const cup_integrator_options *mo,
                   const double *x0, sw_result *r) {
  cup_netlist *nl = cup_scene_netlist(v->scene);
  const cup_lcs *L = cup_scene_lcs(v->scene);
  period_samples p = {nl, NULL, cup_netlist_signal_count(nl), q->samples, 0, NULL, NULL};
  p.sig = malloc(sizeof(double) * (size_t)(p.N * p.ns + 1));
  p.zeta = calloc((size_t)(L ? cup_lcs_rows(L) : 0) + 1, sizeof(double));
  double *w = malloc(sizeof(double) * (size_t)p.N);
  char err[CUP_ERRMSG_LEN] = "";
  cup_integrator *I = NULL;
  pss_jumps J;
  int st = pss_jumps_init(&J, mo->T, p.N);
  if (!st) st = !p.sig || !p.zeta || !w ? CUP_ERR_NOMEM : scene_pss_period_integrator(v->scene, mo, &J, &I, err);
  cup_run_info info = {0};
  if (!st) {
    p.I = I;
    st = cup_integrator_run(I, x0, keep_sample, &p, &info);
    snprintf(err, sizeof err, "%s", info.message);
    if (st >= 0 && p.k != p.N) {
      snprintf(err, sizeof err, "%ld of its %ld samples recorded", p.k, p.N);
      st = CUP_ERR_ARG;
    }
  }
  cup_measure me[SW_SS_SIGNALS];
  double power[SW_SS_POWER];
  for (int j = 0; j < SW_SS_SIGNALS; j++) me[j] = (cup_measure){NAN, NAN, NAN, NAN, NAN, NAN};   /* not measured */
  pss_figures f = {s->ss_nm, s->ss_sig, 0, s->ss_np, s->ss_pv, s->ss_pc, q->eff_out, q->eff_in, me, NULL, NULL,
                       power, r->steady.efficiency, NULL, 0, 0, 0};
  pss_jumps_finish(&J, &f);
  if (st >= 0) st = pss_measure(p.sig, p.N, p.ns, &f, w, err);
  for (int j = 0; j < s->ss_nm; j++) {         /* those measured before an error too */
    double *fig = r->steady.fig[j];
    fig[0] = me[j].avg, fig[1] = me[j].rms, fig[2] = me[j].min, fig[3] = me[j].max, fig[4] = me[j].pp;
  }
  r->steady.efficiency = f.efficiency;
  if (st < 0) snprintf(r->message, sizeof r->message, "the steady state's period: %s: %s", cup_status_name(st), err);
  else if (J.overflow) {                       /* the figures are the samples' own: the task says so */
    size_t n = strlen(r->message);
    snprintf(r->message + n, sizeof r->message - n, "%smore than %ld switchings and events in the period, 4 a "
             "sample: the measurements place none of them (O(h) where a signal jumps; raise steady_state.samples)",
             n ? "; " : "", J.cap);
    st = CUP_WARN_COARSE_MEASURE;
  }
  cup_integrator_free(&I);
  pss_jumps_free(&J);
  free(p.sig); free(p.zeta); free(w);
  return st;
}

/* The task's steady state (scene_pss_solve), its period measured. */
void sw_steady_run(const sw_sweep *s, const sw_variant *v, const cup_integrator_options *o, sw_result *r) {
  const cup_scene_steady *q = cup_scene_steady_state(v->scene);
  struct sw_steady_result *ss = &r->steady;
  ss->period = ss->residual = ss->max_multiplier = ss->efficiency = NAN;
  for (int j = 0; j < SW_SS_SIGNALS; j++)
    for (int k = 0; k < SW_SS_FIGURES; k++) ss->fig[j][k] = NAN;
  r->err_est = NAN;
  double t0 = now_seconds(), T, phase;
  char err[CUP_ERRMSG_LEN] = "";
  cup_integrator_options period;
  cup_pss *pss = NULL;
  int stage;
  int st = scene_pss_solve(v->scene, o, &pss, &T, &phase, &period, &stage, err);
  r->status = st;
  if (stage > SCENE_PSS_PHASE) ss->period = T;   /* the period found */
  snprintf(r->message, sizeof r->message, "%s%s", stage == SCENE_PSS_SETUP ? "set-up: " : "steady state: ", err);
  if (pss) {
    cup_pss_info info;
    cup_pss_get_info(pss, &info);
    snprintf(r->message, sizeof r->message, "%s", info.message);
    ss->iterations = info.iterations;
    ss->period_runs = info.period_runs;
    ss->residual = info.residual;
    ss->max_multiplier = info.max_multiplier;
    r->events = info.events;
    r->stopped_step = info.period_runs;
    if (st >= 0) {
      ss->solved = 1;
      if (period.max_wall_seconds > 0)           /* the task's limit: what the solve left */
        period.max_wall_seconds = fmax(period.max_wall_seconds - (now_seconds() - t0), DBL_MIN);
      int ms = measure(s, v, q, &period, cup_pss_x0(pss), r);
      if (ms < 0 || (ms > 0 && r->status == CUP_OK)) r->status = ms;
    }
  }
  cup_pss_free(&pss);
  r->wall += now_seconds() - t0;
}

/* ---- /steady_state in the results file ---- */

static void pending(const sw_sweep *s, long id, void *vrow) {
  sw_steady_row *row = vrow;
  memset(row, 0, sizeof *row);
  row->task_id = id;
  row->variant = (int32_t)(id / s->per_variant);
  row->status = CUP_ERR_INTERRUPTED;
  row->period = row->residual = row->max_multiplier = row->efficiency = NAN;
  for (int j = 0; j < SW_SS_SIGNALS; j++)
    for (int k = 0; k < SW_SS_FIGURES; k++) row->fig[j][k] = NAN;
}

int sw_steady_create(sw_file *f) {
  return sw_h5_task_table(f, "steady_state", f->ss_row_t, sizeof(sw_steady_row), pending, &f->steady);
}

int sw_steady_write(sw_file *f, const sw_task_out *t, long count) {
  sw_steady_row *rows = f->ssrows;
  for (long j = 0; j < count; j++) {
    const struct sw_steady_result *ss = &t[j].r->steady;
    pending(f->s, t[j].task, &rows[j]);
    rows[j].status = t[j].r->status;
    rows[j].solved = ss->solved;
    rows[j].newton_iterations = ss->iterations;
    rows[j].period_runs = ss->period_runs;
    rows[j].period = ss->period;
    rows[j].residual = ss->residual;
    rows[j].max_multiplier = ss->max_multiplier;
    rows[j].efficiency = ss->efficiency;
    memcpy(rows[j].fig, ss->fig, sizeof rows[j].fig);
    rows[j].done = 1;
  }
  return sw_h5_task_io(f, f->steady, f->ss_row_t, count, rows, H5P_DEFAULT, 1, "write /steady_state in");
}
