/* sweep_crowd — sweeps whose variants are crowd: scenes (sweep_crowd.h,
 * docs/sweep-format.md, "Crowd sweeps"): what differs from circuits. A crowd has no reference
 * (its evacuation is the result, not a trajectory to converge), its
 * variants may have different numbers of agents, and each task reports its
 * evacuation in /crowd, one row per task, written before its /summary row
 * so that a row marked done there still means a complete task. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "sweep_crowd.h"

void sw_crowd_no_reference(const sw_sweep *s, sw_result *r, double *traj) {
  for (long j = 0; j < s->samples * s->dim; j++) traj[j] = NAN;
  r->status = CUP_OK;
  r->correction = r->cross_check = r->max_eps_cert = r->max_eta_cert = NAN;
  snprintf(r->message, sizeof r->message, "%s", SW_CROWD_REFERENCE);
}

/* cup_crowd_gap is the gap of x_{k-1}, measured while step k built its rows. */
static int watch_step(long k, double t, const cup_proj_info *pi, void *ctx) {
  sw_crowd_watch *w = ctx;
  if (k >= 1) w->min_gap = fmin(w->min_gap, cup_crowd_gap(w->c));
  return w->next ? w->next(k, t, pi, w->next_ctx) : 0;
}

void sw_crowd_watch_begin(sw_crowd_watch *w, cup_crowd *c, cup_integrator_options *o) {
  *w = (sw_crowd_watch){c, INFINITY, o->on_step, o->step_ctx};
  o->on_step = watch_step;
  o->step_ctx = w;
}

void sw_crowd_watch_end(sw_crowd_watch *w, const double *q_end, sw_result *r) {
  int N = cup_crowd_agents(w->c), out = 0;
  const double *et = cup_crowd_exit_times(w->c);
  double last = -INFINITY;
  for (int i = 0; i < N; i++)
    if (!isnan(et[i])) { out++; last = fmax(last, et[i]); }
  r->crowd.agents = N;
  r->crowd.agents_out = out;
  r->crowd.evacuation_time = out == N ? last : NAN;
  r->crowd.min_gap = q_end ? fmin(w->min_gap, cup_crowd_min_gap(w->c, q_end)) : w->min_gap;
}

/* ---- /crowd in the results file ---- */

static void pending(const sw_sweep *s, long id, void *vrow) {
  sw_crowd_row *row = vrow;
  memset(row, 0, sizeof *row);
  row->task_id = id;
  row->variant = (int32_t)(id / s->per_variant);
  row->agents = (int32_t)(cup_scene_dim(s->var[row->variant].scene) / 2);
  row->evacuation_time = row->min_gap = NAN;
}

int sw_crowd_create(sw_file *f) {
  return sw_h5_task_table(f, "crowd", f->crowd_row_t, sizeof(sw_crowd_row), pending, &f->crowd);
}

int sw_crowd_write(sw_file *f, const sw_task_out *t, long count) {
  sw_crowd_row *rows = f->crows;
  for (long j = 0; j < count; j++) {
    pending(f->s, t[j].task, &rows[j]);
    const struct sw_crowd_result *c = &t[j].r->crowd;
    if (c->agents > 0) {                /* 0: the run never started (its set-up failed) */
      rows[j].agents_out = c->agents_out;
      rows[j].evacuation_time = c->evacuation_time;
      rows[j].min_gap = c->min_gap;
    }
    rows[j].done = 1;
  }
  return sw_h5_task_io(f, f->crowd, f->crowd_row_t, count, rows, H5P_DEFAULT, 1, "write /crowd in");
}
