/* sweep_steady — steady-state sweeps (sweep_steady.h, docs/sweep-format.md,
 * "Steady-state sweeps"). A task is catchup-run --steady-state without the
 * file: the period map is the task's integrator over one period (a
 * fixed-step scheme keeps its step, the adaptive one runs at the request's
 * map_tol), Newton's method on it (cup_pss_solve_map), then one period from
 * the steady state at the request's samples, measured by cup_measure_period
 * (the signals the request names, each element's power, the efficiency). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sweep_steady.h"
#include "analysis/pss_run.h"
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

/* One period from x0 at q->samples samples, measured into r->steady. */
static int measure(const sw_sweep *s, const sw_variant *v, const cup_scene_steady *q, cup_integrator_options mo,
                   const double *x0, sw_result *r) {
  cup_netlist *nl = cup_scene_netlist(v->scene);
  const cup_lcs *L = cup_scene_lcs(v->scene);
  period_samples p = {nl, NULL, cup_netlist_signal_count(nl), q->samples, 0, NULL, NULL};
  mo.output = CUP_OUTPUT_SAMPLES;
  mo.output_samples = q->samples;
  mo.output_t0 = 0;
  p.sig = malloc(sizeof(double) * (size_t)(p.N * p.ns + 1));
  p.zeta = calloc((size_t)(L ? cup_lcs_rows(L) : 0) + 1, sizeof(double));
  double *w = malloc(sizeof(double) * (size_t)p.N);
  char err[CUP_ERRMSG_LEN] = "";
  cup_integrator *I = NULL;
  int st = !p.sig || !p.zeta || !w ? CUP_ERR_NOMEM : cup_scene_integrator(v->scene, &mo, &I, err);
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
  cup_measure m;
  for (int j = 0; st >= 0 && j < s->ss_nm; j++) {
    for (long k = 0; k < p.N; k++) w[k] = p.sig[k * p.ns + s->ss_sig[j]];
    st = cup_measure_period(w, p.N, 0, &m, NULL, NULL, err);
    double *f = r->steady.fig[j];
    f[0] = m.avg, f[1] = m.rms, f[2] = m.min, f[3] = m.max, f[4] = m.pp;
  }
  double power[SW_SS_POWER];
  for (int j = 0; st >= 0 && j < s->ss_np; j++)
    st = measure_power(p.sig, p.N, p.ns, s->ss_pv[j], s->ss_pc[j], w, &power[j], err);
  if (st >= 0 && q->eff_out >= 0) r->steady.efficiency = power[q->eff_out] / -power[q->eff_in];
  if (st < 0) snprintf(r->message, sizeof r->message, "the steady state's period: %s: %s", cup_status_name(st), err);
  cup_integrator_free(&I);
  free(p.sig); free(p.zeta); free(w);
  return st;
}

/* The period, or an error in r. */
static int period_of(const sw_variant *v, const cup_scene_steady *q, double *T, sw_result *r) {
  char err[CUP_ERRMSG_LEN] = "";
  const cup_input *u = cup_scene_input(v->scene);
  int st = CUP_OK;
  *T = q->pss.period;
  if (!(*T > 0) && !u) {
    snprintf(err, sizeof err, "the scene has no input to take the period from: give steady_state.period");
    st = CUP_ERR_ARG;
  }
  if (!st && !(*T > 0)) st = cup_input_period(u, T, err);
  if (!st) st = cup_input_period_fits(u, *T, err);
  if (st) snprintf(r->message, sizeof r->message, "steady state: %s", err);
  return st;
}

void sw_steady_run(const sw_sweep *s, const sw_variant *v, const cup_integrator_options *o, sw_result *r) {
  const cup_scene_steady *q = cup_scene_steady_state(v->scene);
  struct sw_steady_result *ss = &r->steady;
  ss->period = ss->residual = ss->max_multiplier = ss->efficiency = NAN;
  for (int j = 0; j < SW_SS_SIGNALS; j++)
    for (int k = 0; k < SW_SS_FIGURES; k++) ss->fig[j][k] = NAN;
  r->err_est = NAN;
  double t0 = now_seconds(), T;
  if ((r->status = period_of(v, q, &T, r))) { r->wall += now_seconds() - t0; return; }
  ss->period = T;
  cup_integrator_options mo;               /* the period map: one period, its final state */
  pss_map_options(o, cup_scene_options(v->scene)->T, T, q->pss.map_tol, &mo);
  char err[CUP_ERRMSG_LEN] = "";
  cup_integrator *I = NULL;
  cup_pss *pss = NULL;
  int st = cup_scene_integrator(v->scene, &mo, &I, err);
  if (st) {
    r->status = st;
    snprintf(r->message, sizeof r->message, "set-up: %s", err);
  } else {
    st = cup_pss_solve_map(&pss, I, cup_scene_dim(v->scene), T, cup_scene_x0(v->scene), &q->pss, err);
    cup_integrator_free(&I);
    r->status = st;
    snprintf(r->message, sizeof r->message, "steady state: %s", err);
  }
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
      int ms = measure(s, v, q, mo, cup_pss_x0(pss), r);
      if (ms < 0) r->status = ms;
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
