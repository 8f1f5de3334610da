/* sweep_run — one job of a sweep (sweep_run.h): a task, or a variant's
 * reference (Richardson extrapolation of two exact runs, or an adaptive run
 * at tol 1e-13), run by the integrator on the variant's scene and sampled at
 * the common times. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sweep_crowd.h"
#include "sweep_steady.h"
#include "sweep_run.h"
#include "util/clock.h"

/* The integrator samples the run at the common times t_j = j T / (S - 1)
 * (CUP_OUTPUT_SAMPLES: the step's state where t_j is a step time,
 * interpolated as the scheme's own dense output between steps otherwise,
 * as catchup-run's samples are); this keeps them in order. */
typedef struct {
  long S, next;
  int dim, stride;           /* the task's state, a sample's room (crowds: the sweep's largest 2N) */
  double *traj;
  /* a netlist's signals, after the S samples of the state: nsig a sample,
   * from x, u(t) and the zeta at t (as catchup-run) */
  cup_netlist *nl;
  const cup_integrator *I;
  int nsig;
  double *zeta;
} sampler;

/* Sample j is x (at t): the state, and the signals when there are any. */
static int keep(sampler *sp, long j, double t, const double *x) {
  memcpy(sp->traj + j * sp->stride, x, sizeof(double) * (size_t)sp->dim);
  if (!sp->nsig) return 0;
  cup_integrator_zeta(sp->I, sp->zeta);
  return cup_netlist_signals(sp->nl, t, x, sp->zeta, sp->traj + sp->S * sp->stride + j * sp->nsig) != CUP_OK
           ? CUP_ERR_CALLBACK : 0;
}

static int sample_sink(long k, double t, const double *x, void *ctx) {
  (void)k;
  sampler *sp = ctx;
  return sp->next < sp->S ? keep(sp, sp->next++, t, x) : 0;
}

/* Fails once t reaches T/2: exercises a real mid-run failure (tests). */
typedef struct { double half; int dim; } failing;

static int failing_rhs(double t, const double *x, double *f, void *ctx) {
  (void)x;
  const failing *fc = ctx;
  for (int i = 0; i < fc->dim; i++) f[i] = 0;
  return t >= fc->half;
}

typedef struct {
  long n;
  cup_schedule eps, eta;
  int scheme, projector;
  double time_limit;
  int inject;
  double tol_abs, tol_rel;
} run_params;

static void run_one(const sw_sweep *s, const sw_variant *v, const run_params *rp, const sw_run_opts *ro,
                    sw_result *r, double *traj) {
  long S = s->samples;
  int dim = s->dim;
  for (long j = 0; j < sw_traj_len(s); j++) traj[j] = NAN;
  cup_integrator_options o = *cup_scene_options(v->scene);
  o.n = rp->n;
  o.eps = rp->eps;
  o.eta = rp->eta;
  o.scheme = (cup_scheme)rp->scheme;
  o.proj.method = (cup_proj_method)rp->projector;
  o.output = CUP_OUTPUT_SAMPLES;   /* at the common times from 0, whatever the scene asks (.tran's TSTART) */
  o.output_samples = S;
  o.output_t0 = 0;
  o.tol_abs = rp->tol_abs;
  o.tol_rel = rp->tol_rel;
  o.max_wall_seconds = rp->time_limit;
  o.interrupt = ro ? ro->interrupt : NULL;
  o.on_step = ro ? ro->on_step : NULL;
  o.step_ctx = ro ? ro->step_ctx : NULL;
  if (s->steady) { sw_steady_run(s, v, &o, r); return; }
  failing fc = {0.5 * o.T, cup_scene_dim(v->scene)};
  if (rp->inject) { o.f = failing_rhs; o.f_ctx = &fc; }
  sw_crowd_watch cw;
  if (s->crowd) sw_crowd_watch_begin(&cw, cup_scene_crowd(v->scene), &o);
  double t0 = now_seconds();
  cup_integrator *I = NULL;
  char err[CUP_ERRMSG_LEN] = "";
  r->status = cup_scene_integrator(v->scene, &o, &I, err);
  if (r->status < 0) {
    snprintf(r->message, sizeof r->message, "set-up: %s", err);
    r->wall += now_seconds() - t0;
    return;
  }
  sampler sp = {S, 0, cup_scene_dim(v->scene), dim, traj, cup_scene_netlist(v->scene), I, s->nsig, NULL};
  if (s->nsig && !(sp.zeta = calloc((size_t)cup_lcs_rows(cup_scene_lcs(v->scene)) + 1, sizeof(double)))) {
    cup_integrator_free(&I);
    r->status = CUP_ERR_NOMEM;
    snprintf(r->message, sizeof r->message, "set-up: out of memory");
    return;
  }
  cup_run_info info;
  r->status = cup_integrator_run(I, cup_scene_x0(v->scene), sample_sink, &sp, &info);
  free(sp.zeta);
  if (s->crowd) sw_crowd_watch_end(&cw, cup_integrator_state(I), r);
  cup_integrator_free(&I);
  r->wall += now_seconds() - t0;
  r->max_eps_cert = fmax(r->max_eps_cert, info.max_eps_cert);
  r->max_eta_cert = fmax(r->max_eta_cert, info.max_eta_cert);
  r->projected += info.projected;
  r->skipped += info.skipped;
  r->not_certified += info.not_certified;
  r->dual_iterations += info.dual_iterations;
  r->factorizations += info.factorizations;
  r->stopped_step = info.step;
  r->err_est = info.err_est;
  r->events = info.events;
  if (rp->inject && r->status == CUP_ERR_CALLBACK)
    snprintf(r->message, sizeof r->message, "injected failure (CATCHUP_SWEEP_INJECT_FAIL): %s",
             info.message);
  else
    snprintf(r->message, sizeof r->message, "%s", info.message);
}

/* Richardson: x_ref = 2 x(2 n_ref) - x(n_ref), both exact-projection
 * explicit runs; the scheme is first order, so this removes the 1/n term.
 * An LCS with D != 0 (a netlist's diode behind a resistance) is not for
 * the explicit scheme: its two runs are theta's, at theta = 1/2 second order there
 * (docs/netlist.md): x_ref = x(2 n_ref) + (x(2 n_ref) - x(n_ref)) / 3.
 * coarse: samples * dim doubles of scratch. */
static void richardson(const sw_sweep *s, const sw_variant *v, const sw_run_opts *ro, sw_result *r,
                       double *traj, double *coarse) {
  long count = s->samples * s->dim, len = sw_traj_len(s);   /* the states; with the signals (linear in them) */
  int theta = cup_lcs_has_D(cup_scene_lcs(v->scene)), order2 = theta && cup_scene_options(v->scene)->theta == 0.5;
  run_params rp = {v->n_ref, {0, 0}, {0, 0}, theta ? CUP_SCHEME_THETA : CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO,
                   0, 0, 0, 0};
  run_one(s, v, &rp, ro, r, coarse);
  if (r->status >= 0) {
    rp.n = 2 * v->n_ref;
    run_one(s, v, &rp, ro, r, traj);
  }
  if (r->status >= 0) {
    r->correction = sw_max_error(traj, coarse, count);
    for (long j = 0; j < len; j++)
      traj[j] = order2 ? traj[j] + (traj[j] - coarse[j]) / 3 : 2 * traj[j] - coarse[j];
  } else {
    for (long j = 0; j < len; j++) traj[j] = NAN;
  }
}

/* The adaptive scheme at tol 1e-13 (reference.method: adaptive); with
 * check: richardson also the Richardson limit, and how far the two are
 * apart (r->cross_check), which the sweep reports. The reference is the
 * adaptive run's, whatever the check gives. */
static void adaptive_reference(const sw_sweep *s, const sw_variant *v, const sw_run_opts *ro, sw_result *r,
                               double *traj, double *scratch, double *coarse) {
  sw_result rr;
  memset(&rr, 0, sizeof rr);
  if (s->ref_check) richardson(s, v, ro, &rr, scratch, coarse);
  run_params rp = {s->samples - 1, {0, 0}, {0, 0}, CUP_SCHEME_ADAPTIVE, CUP_PROJ_AUTO, 0, 0,
                   SW_REF_ADAPTIVE_TOL, SW_REF_ADAPTIVE_TOL};    /* n: unused by the scheme */
  run_one(s, v, &rp, ro, r, traj);
  r->correction = r->err_est;      /* the run's own estimate of its error */
  if (!s->ref_check) return;
  r->wall += rr.wall;
  r->cross_check = r->status >= 0 && rr.status >= 0 ? sw_max_error(traj, scratch, s->samples * s->dim) : NAN;
  if (rr.status < 0 && r->status >= 0)
    snprintf(r->message, sizeof r->message, "the Richardson check failed: %s: %.200s", cup_status_name(rr.status),
             rr.message);
}

static void run_reference(const sw_sweep *s, const sw_variant *v, const sw_run_opts *ro, sw_result *r,
                          double *traj) {
  long count = sw_traj_len(s);
  double *scratch = malloc(sizeof(double) * (size_t)count * 2);
  r->cross_check = NAN;
  if (!scratch) {
    r->status = CUP_ERR_NOMEM;
    snprintf(r->message, sizeof r->message, "reference: out of memory");
    return;
  }
  if (s->ref_method == SW_REF_ADAPTIVE) adaptive_reference(s, v, ro, r, traj, scratch, scratch + count);
  else richardson(s, v, ro, r, traj, scratch);
  free(scratch);
}

void sw_scene_slot_free(sw_scene_slot *slot) {
  cup_scene_free(&slot->scene);
  slot->variant = -1;
}

/* Variant k with its scene: as resolved, or a lazy one's loaded (into the
 * slot, kept for the next job, or into *own, the caller's to free). */
static int with_scene(const sw_sweep *s, int k, const sw_run_opts *ro, sw_variant *v, cup_scene **own,
                      sw_result *r) {
  *v = s->var[k];
  if (v->scene) return CUP_OK;
  sw_scene_slot *slot = ro ? ro->slot : NULL;
  if (slot && slot->variant == k) { v->scene = slot->scene; return CUP_OK; }
  char err[SW_ERR_LEN];
  double t0 = now_seconds();
  cup_scene *sc = NULL;
  int st = sw_variant_load(s, k, &sc, err);
  r->wall += now_seconds() - t0;            /* the job's own: every rank loads what it runs */
  if (st) {
    r->status = st;
    snprintf(r->message, sizeof r->message, "set-up: %.*s", (int)sizeof r->message - 16, err);
    return st;
  }
  if (slot) {
    sw_scene_slot_free(slot);
    slot->variant = k;
    slot->scene = sc;
  } else {
    *own = sc;
  }
  v->scene = sc;
  return CUP_OK;
}

void sw_run_job(const sw_sweep *s, long job, const sw_run_opts *ro, sw_result *r, double *traj) {
  memset(r, 0, sizeof *r);
  r->job = job;
  if (job < s->n_variants && s->crowd) { sw_crowd_no_reference(s, r, traj); return; }
  if (job < s->n_variants && s->steady) { sw_steady_no_reference(s, r, traj); return; }
  sw_variant v;
  cup_scene *own = NULL;
  if (job < s->n_variants) {
    if (!with_scene(s, (int)job, ro, &v, &own, r)) run_reference(s, &v, ro, r, traj);
    cup_scene_free(&own);
    return;
  }
  sw_task t;
  if (sw_task_get(s, job - s->n_variants, &t)) {
    r->status = CUP_ERR_ARG;
    snprintf(r->message, sizeof r->message, "no such task %ld", (long)(job - s->n_variants));
    return;
  }
  run_params rp = {t.n, t.eps_s, t.eta_s, t.scheme, t.projector, ro ? ro->task_time_limit : 0,
                   ro ? ro->inject_fail : 0, t.tol_abs, t.tol_rel};
  if (!with_scene(s, t.variant, ro, &v, &own, r)) run_one(s, &v, &rp, ro, r, traj);
  cup_scene_free(&own);
}
