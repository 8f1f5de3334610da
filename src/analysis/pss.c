/* pss — the periodic steady state by Newton's method on the period map
 * (catchup/pss.h, docs/steady-state.md). The map is a run of an integrator
 * over one period; its Jacobian (the monodromy matrix) comes from finite
 * differences of that map, one more run per state component, and its
 * eigenvalues (GSL's nonsymmetric solver) are the Floquet multipliers.
 * Nothing here knows the model: a switched topology's integrator is one
 * more period map. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include "catchup.h"
#include "catchup/pss.h"
#include "pss_run.h"
#include "integrator/adaptive.h"
#include "integrator/integrator_impl.h"
#include "model/input_impl.h"
#include "util/clock.h"
#include "util/fail.h"
#include "util/linalg.h"

/* A multiplier this close to 1 (relative) leaves Phi(x) - x singular. */
#define PSS_AT_ONE 1e-8
/* Multipliers are finite differences of a map computed to map_tol: a
 * modulus within this of 1 counts as 1 (an undamped mode). */
#define PSS_UNIT_CIRCLE 1e-6
/* Step halvings of a Newton step that does not lower the residual. */
#define PSS_HALVINGS 3

struct cup_pss {
  cup_pss_info info;
  double *x0, *res, *J, *mre, *mim;
  int have_J;
  double *t, *x, *zeta;     /* the trajectory: samples, samples x n, samples x m */
  pss_jumps jumps;          /* the trajectory's jump times (run clock; t0 + them: cup_pss_jumps) */
  long nj;                  /* their count (0: none, or more than the samples resolve) */
};

/* The period map and the Newton iteration's work. */
typedef struct pss_work {
  cup_pss *r;
  cup_integrator *I;
  adaptive_ws *tan;        /* the adaptive scheme carrying the map's tangent (exact monodromy), or NULL */
  adaptive_ws *ad;         /* ... the same while a step falls back to finite differences */
  const cup_pss_options *o;
  int n;
  double *x, *F, *xt, *Ft, *dx, *col;
  gsl_matrix *JI;
  gsl_permutation *perm;
  gsl_vector_view b, s;
  long ev_min, ev_max;      /* events per period over the iterations */
  double t0, limit;         /* the solve's start and the integrator's wall-time limit (0: none): the solve's */
} pss_work;

void cup_pss_options_default(cup_pss_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->max_iter = 20;
  o->tol = 1e-10;
  o->tol_floor = 1e-9;
  o->map_tol = 1e-12;
  o->fd_step = 1e-6;
}

__attribute__((format(printf, 3, 4)))
static int say(cup_pss *r, int status, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(r->info.message, sizeof r->info.message, fmt, ap);
  va_end(ap);
  return r->info.status = status;
}

/* out = Phi(x): one run over the period; an error ends the solve, naming
 * the run's message. */
static int phi(pss_work *w, const double *x, double *out, const char *what) {
  if (w->limit > 0) {                            /* the limit is the solve's: each run gets what is left */
    double left = w->limit - (now_seconds() - w->t0);
    if (!(left > 0))
      return say(w->r, CUP_ERR_TIME_LIMIT, "the steady state's wall-time limit (%g s) was reached after %ld "
                 "period runs, before %s", w->limit, w->r->info.period_runs, what);
    integrator_wall_limit(w->I, left);
  }
  cup_run_info ri;
  int st = cup_integrator_run(w->I, x, NULL, NULL, &ri);
  w->r->info.period_runs++;
  if (st < 0)
    return say(w->r, st, "the period map (%s) failed after %ld runs: %s", what, w->r->info.period_runs,
               ri.message[0] ? ri.message : cup_status_string(st));
  memcpy(out, cup_integrator_state(w->I), sizeof(double) * (size_t)w->n);
  w->r->info.events = ri.events;
  return CUP_OK;
}

/* The monodromy at x (Phi(x) = F) by forward differences, column j by a
 * step of fd_step times the state's scale (||x||_inf: a component that is
 * near 0 at t = 0 may swing through the period, and a step of its own size
 * would drown in the map's rounding), and its eigenvalues sorted by
 * decreasing modulus. */
static int jacobian(pss_work *w, const double *x, const double *F) {
  cup_pss *r = w->r;
  int n = w->n;
  double scale = fmax(la_norm_inf(x, n), la_norm_inf(F, n));
  if (w->tan)                                    /* the last run was from x: its tangent is the monodromy */
    memcpy(r->J, adaptive_tangent_matrix(w->tan), sizeof(double) * (size_t)n * (size_t)n);
  for (int j = 0; !w->tan && j < n; j++) {
    double d = w->o->fd_step * fmax(fmax(fabs(x[j]), fabs(F[j])), scale);
    if (!(d > 0)) d = w->o->fd_step;
    int st = CUP_OK;
    for (int side = 0; side < 2; side++) {       /* a step the map refuses (no consistent state): the other side */
      memcpy(w->xt, x, sizeof(double) * (size_t)n);
      w->xt[j] += side ? -d : d;
      double dj = w->xt[j] - x[j];               /* the step as represented */
      st = phi(w, w->xt, w->col, "a finite difference of the monodromy");
      if (st >= 0) { d = dj; break; }
      if (side == 0) {                           /* the other side may do: forget this one's failure */
        r->info.status = CUP_OK;
        r->info.message[0] = '\0';
      }
    }
    if (st < 0) return st;
    for (int i = 0; i < n; i++) r->J[i + (size_t)j * n] = (w->col[i] - F[i]) / d;
  }
  r->have_J = 1;
  gsl_matrix *Jc = gsl_matrix_alloc((size_t)n, (size_t)n);
  gsl_vector_complex *ev = gsl_vector_complex_alloc((size_t)n);
  gsl_eigen_nonsymm_workspace *ws = gsl_eigen_nonsymm_alloc((size_t)n);
  if (!Jc || !ev || !ws) {
    if (ws) gsl_eigen_nonsymm_free(ws);
    if (ev) gsl_vector_complex_free(ev);
    if (Jc) gsl_matrix_free(Jc);
    return say(r, CUP_ERR_NOMEM, "out of memory for the Floquet multipliers");
  }
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) gsl_matrix_set(Jc, (size_t)i, (size_t)j, r->J[i + (size_t)j * n]);
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  int est = gsl_eigen_nonsymm(Jc, ev, ws);
  gsl_set_error_handler(old);
  for (int i = 0; i < n; i++) {
    gsl_complex z = gsl_vector_complex_get(ev, (size_t)i);
    r->mre[i] = est ? NAN : GSL_REAL(z);
    r->mim[i] = est ? NAN : GSL_IMAG(z);
  }
  gsl_eigen_nonsymm_free(ws);
  gsl_vector_complex_free(ev);
  gsl_matrix_free(Jc);
  for (int i = 1; i < n; i++)                    /* insertion sort by decreasing modulus */
    for (int k = i; k > 0 && hypot(r->mre[k], r->mim[k]) > hypot(r->mre[k - 1], r->mim[k - 1]); k--) {
      double a = r->mre[k], b = r->mim[k];
      r->mre[k] = r->mre[k - 1]; r->mim[k] = r->mim[k - 1];
      r->mre[k - 1] = a; r->mim[k - 1] = b;
    }
  r->info.max_multiplier = n ? hypot(r->mre[0], r->mim[0]) : 0;
  if (est) return say(r, CUP_ERR_LINALG, "the Floquet multipliers: GSL's eigensolver did not converge");
  return CUP_OK;
}

/* dx = -(J - I)^-1 (F - x); CUP_ERR_NO_STEADY_STATE when a multiplier is at 1. */
static int newton_step(pss_work *w, const double *x, const double *F) {
  cup_pss *r = w->r;
  int n = w->n;
  for (int i = 0; i < n; i++) {
    double d = hypot(r->mre[i] - 1, r->mim[i]);
    if (d <= PSS_AT_ONE * fmax(1, hypot(r->mre[i], r->mim[i])))
      return say(r, CUP_ERR_NO_STEADY_STATE, "a Floquet multiplier is at 1 (%.12g%+.3gi): Phi(x) - x is singular, "
                 "no isolated periodic orbit (an undamped mode driven at its resonance grows without bound; a "
                 "state no dissipation ever corrects drifts); residual %.3g after %d Newton steps",
                 r->mre[i], r->mim[i], r->res[r->info.iterations], r->info.iterations);
  }
  for (int i = 0; i < n; i++) {
    for (int j = 0; j < n; j++) gsl_matrix_set(w->JI, (size_t)i, (size_t)j, r->J[i + (size_t)j * n] - (i == j));
    w->b.vector.data[i] = -(F[i] - x[i]);
  }
  int sgn;
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  int st = gsl_linalg_LU_decomp(w->JI, w->perm, &sgn);
  if (!st) st = gsl_linalg_LU_solve(w->JI, w->perm, &w->b.vector, &w->s.vector);
  gsl_set_error_handler(old);
  for (int i = 0; i < n && !st; i++) st = !isfinite(w->dx[i]);
  if (st)
    return say(r, CUP_ERR_NO_STEADY_STATE, "Phi(x) - x is singular to working precision (the monodromy minus I "
               "has no inverse): no isolated periodic orbit; residual %.3g after %d Newton steps",
               r->res[r->info.iterations], r->info.iterations);
  return CUP_OK;
}

static int converged(const pss_work *w, double res, const double *x) {
  return res <= w->o->tol * (la_norm_inf(x, w->n) + w->o->tol_floor);
}

/* The residuals so far, "r0, r1, ..." (the last ones if many). */
static void residual_list(const cup_pss *r, char *buf, size_t size) {
  size_t len = 0;
  int k0 = r->info.iterations > 8 ? r->info.iterations - 8 : 0;
  buf[0] = '\0';
  for (int k = k0; k <= r->info.iterations && len < size; k++)
    len += (size_t)snprintf(buf + len, size - len, "%s%.3g", k > k0 ? ", " : k0 ? "..., " : "", r->res[k]);
}

/* One Newton step from (x, F) with step halvings (an iterate the map
 * cannot run from, an inconsistent state the integrator refuses, counts as
 * no descent); when none lowers the residual, one transient period
 * (x <- F), which a stable orbit contracts. */
static int advance(pss_work *w) {
  cup_pss *r = w->r;
  int n = w->n, k = r->info.iterations, st;
  double rt = INFINITY, lam = 1;
  for (int h = 0; h <= PSS_HALVINGS; h++, lam *= 0.5) {
    for (int i = 0; i < n; i++) w->xt[i] = w->x[i] + lam * w->dx[i];
    rt = INFINITY;
    if ((st = phi(w, w->xt, w->Ft, "a Newton iterate")) < 0) {
      r->info.status = CUP_OK;
      r->info.message[0] = '\0';
      continue;
    }
    rt = 0;
    for (int i = 0; i < n; i++) rt = fmax(rt, fabs(w->Ft[i] - w->xt[i]));
    if (rt < r->res[k]) break;
  }
  int descended = rt < r->res[k];
  if (!descended && w->tan) {                    /* the exact step did not descend: finite differences from here */
    w->tan = NULL;
    return 1;
  }
  if (!descended) {
    memcpy(w->xt, w->F, sizeof(double) * (size_t)n);
    if ((st = phi(w, w->xt, w->Ft, "a transient period")) < 0) return st;
    rt = 0;
    for (int i = 0; i < n; i++) rt = fmax(rt, fabs(w->Ft[i] - w->xt[i]));
  }
  memcpy(w->x, w->xt, sizeof(double) * (size_t)n);
  memcpy(w->F, w->Ft, sizeof(double) * (size_t)n);
  r->info.iterations = k + 1;
  r->res[k + 1] = rt;
  r->info.residual = rt;
  if (r->info.events < w->ev_min) w->ev_min = r->info.events;
  if (r->info.events > w->ev_max) w->ev_max = r->info.events;
  return CUP_OK;
}

static int newton(pss_work *w, const double *x_guess) {
  cup_pss *r = w->r;
  const cup_pss_options *o = w->o;
  int n = w->n, st;
  for (int i = 0; i < n; i++) w->x[i] = x_guess ? x_guess[i] : 0;
  if ((st = phi(w, w->x, w->F, "the first iterate")) < 0) return st;
  for (int k = 0; k < o->warmup_periods; k++) {
    memcpy(w->x, w->F, sizeof(double) * (size_t)n);
    if ((st = phi(w, w->x, w->F, "a warm-up period")) < 0) return st;
  }
  double res = 0;
  for (int i = 0; i < n; i++) res = fmax(res, fabs(w->F[i] - w->x[i]));
  r->res[0] = r->info.residual = res;
  w->ev_min = w->ev_max = r->info.events;
  while (!converged(w, r->res[r->info.iterations], w->x)) {
    memcpy(r->x0, w->x, sizeof(double) * (size_t)n);   /* a failure below leaves the last iterate */
    if (r->info.iterations >= o->max_iter) {
      char list[200];
      residual_list(r, list, sizeof list);
      if (w->ev_min != w->ev_max)
        return say(r, CUP_ERR_NO_STEADY_STATE, "Newton's method did not converge in %d steps (residuals %s; "
                   "target %.3g): the events per period kept changing (%ld to %ld), the mode sequence does not "
                   "settle", o->max_iter, list, o->tol * (la_norm_inf(w->x, n) + o->tol_floor), w->ev_min, w->ev_max);
      return say(r, CUP_ERR_NO_STEADY_STATE, "Newton's method did not converge in %d steps (residuals %s; target "
                 "%.3g, largest Floquet multiplier %.6g): the period map is not accurate enough for the target "
                 "(tighten map_tol) or the orbit is not isolated", o->max_iter, list,
                 o->tol * (la_norm_inf(w->x, n) + o->tol_floor), r->info.max_multiplier);
    }
    if ((st = jacobian(w, w->x, w->F)) < 0) return st;
    if ((st = newton_step(w, w->x, w->F)) < 0) return st;
    if ((st = advance(w)) < 0) return st;
    if (st == 1) {                               /* again from x with the differences' Jacobian, once */
      if ((st = phi(w, w->x, w->F, "the iterate again")) < 0) return st;
      if ((st = jacobian(w, w->x, w->F)) < 0) return st;
      if ((st = newton_step(w, w->x, w->F)) < 0) return st;
      if ((st = advance(w)) < 0) return st;
      w->tan = w->ad;                            /* the next step exact again (every run carries the tangent) */
    }
  }
  memcpy(r->x0, w->x, sizeof(double) * (size_t)n);
  /* the monodromy at the orbit itself (the last one was one step before) */
  if ((st = jacobian(w, w->x, w->F)) < 0) return st;
  double mu = r->info.max_multiplier;
  if (mu >= 1 - PSS_UNIT_CIRCLE)
    return say(r, CUP_WARN_UNSTABLE_ORBIT, "the periodic orbit (residual %.3g after %d Newton steps) has a Floquet "
               "multiplier of modulus %.9g (%.9g%+.9gi), %s: a transient does not settle on it", r->info.residual,
               r->info.iterations, mu, r->mre[0], r->mim[0], mu > 1 + PSS_UNIT_CIRCLE ? "outside the unit circle "
               "(an unstable orbit)" : "on the unit circle (an undamped mode)");
  return CUP_OK;
}

static cup_pss *result_new(int n, int m) {
  cup_pss *r = calloc(1, sizeof *r);
  if (!r) return NULL;
  size_t N = (size_t)n + 1;
  r->x0 = calloc(N, sizeof(double));
  r->res = calloc(CUP_PSS_MAX_ITER + 1, sizeof(double));
  r->J = calloc(N * N, sizeof(double));
  r->mre = calloc(N, sizeof(double));
  r->mim = calloc(N, sizeof(double));
  if (!r->x0 || !r->res || !r->J || !r->mre || !r->mim) { cup_pss_free(&r); return NULL; }
  r->info.n = n;
  r->info.m = m;
  r->info.max_multiplier = NAN;
  return r;
}

void cup_pss_free(cup_pss **r) {
  if (!r || !*r) return;
  cup_pss *p = *r;
  free(p->x0); free(p->res); free(p->J); free(p->mre); free(p->mim);
  free(p->t); free(p->x); free(p->zeta);
  pss_jumps_free(&p->jumps);
  free(p);
  *r = NULL;
}

static int check_options(const cup_pss_options *o, char *errmsg) {
  if (o->max_iter < 1 || o->max_iter > CUP_PSS_MAX_ITER)
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: max_iter = %d must be in 1 .. %d", o->max_iter,
                    CUP_PSS_MAX_ITER);
  if (!(o->tol > 0) || !isfinite(o->tol) || !(o->tol_floor >= 0) || !isfinite(o->tol_floor))
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: tol = %g must be > 0 and tol_floor = %g >= 0", o->tol,
                    o->tol_floor);
  if (!(o->fd_step > 0) || !(o->fd_step < 1))
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: fd_step = %g must be in (0, 1)", o->fd_step);
  if (o->jacobian != CUP_PSS_JACOBIAN_AUTO && o->jacobian != CUP_PSS_JACOBIAN_FD)
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: jacobian = %d must be CUP_PSS_JACOBIAN_AUTO or _FD",
                    o->jacobian);
  if (!(o->map_tol >= 0) || !isfinite(o->map_tol))
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: map_tol = %g must be finite and >= 0", o->map_tol);
  if (o->warmup_periods < 0 || o->samples < 0 || o->samples == 1)
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: warmup_periods = %d must be >= 0 and samples = %ld 0 or "
                    ">= 2", o->warmup_periods, o->samples);
  return CUP_OK;
}

int cup_pss_solve_map(cup_pss **out, cup_integrator *I, int n, double period, const double *x_guess,
                      const cup_pss_options *o, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: NULL result");
  *out = NULL;
  cup_pss_options def;
  if (!o) { cup_pss_options_default(&def); o = &def; }
  if (!I || n < 1) return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: no integrator, or n = %d < 1", n);
  if (!(period > 0) || !isfinite(period))
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: the period %g must be finite and > 0", period);
  int st = check_options(o, errmsg);
  if (st) return st;
  double t0 = now_seconds();
  pss_work w = {.I = I, .o = o, .n = n, .t0 = t0, .limit = I->o.max_wall_seconds};
  w.r = result_new(n, 0);
  size_t N = (size_t)n;
  double *buf = calloc(6 * N, sizeof(double));
  w.JI = gsl_matrix_alloc(N, N);
  w.perm = gsl_permutation_alloc(N);
  if (!w.r || !buf || !w.JI || !w.perm) {
    cup_pss_free(&w.r);
    free(buf);
    if (w.JI) gsl_matrix_free(w.JI);
    if (w.perm) gsl_permutation_free(w.perm);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "steady state: out of memory");
  }
  w.x = buf; w.F = buf + N; w.xt = buf + 2 * N; w.Ft = buf + 3 * N; w.dx = buf + 4 * N; w.col = buf + 5 * N;
  w.b = gsl_vector_view_array(w.col, N);         /* the right-hand side (col is free between Jacobians) */
  w.s = gsl_vector_view_array(w.dx, N);
  w.r->info.period = period;
  adaptive_ws *ad = adaptive_of(I);
  int ts = o->jacobian == CUP_PSS_JACOBIAN_AUTO && ad ? adaptive_tangent(ad, 1) : CUP_ERR_UNSUPPORTED;
  if (ts != CUP_ERR_UNSUPPORTED) {               /* D != 0: finite differences */
    if (ts) {
      cup_pss_free(&w.r);
      free(buf);
      gsl_matrix_free(w.JI);
      gsl_permutation_free(w.perm);
      return fail_fmt(errmsg, CUP_ERR_NOMEM, "steady state: out of memory");
    }
    w.tan = w.ad = ad;
  }
  int tangent_on = w.tan != NULL;
  newton(&w, x_guess);
  if (tangent_on) adaptive_tangent(ad, 0);
  if (w.limit > 0) integrator_wall_limit(I, w.limit);   /* I's own again */
  w.r->info.seconds = now_seconds() - t0;
  free(buf);
  gsl_matrix_free(w.JI);
  gsl_permutation_free(w.perm);
  *out = w.r;
  return w.r->info.status;
}

/* The trajectory's sink: t, x and zeta of each sample. */
typedef struct traj {
  cup_pss *r;
  const cup_integrator *I;
  long k;
  double t0;                /* the phase: the samples' times are t0 + t */
} traj;

static int traj_sink(long step, double t, const double *x, void *ctx) {
  (void)step;
  traj *c = ctx;
  cup_pss *r = c->r;
  if (c->k >= r->info.samples) return 1;
  r->t[c->k] = c->t0 + t;
  memcpy(r->x + (size_t)c->k * r->info.n, x, sizeof(double) * (size_t)r->info.n);
  if (r->info.m > 0 && cup_integrator_zeta(c->I, r->zeta + (size_t)c->k * r->info.m) < 0) return 1;
  c->k++;
  return 0;
}

/* One period from x0 at o->samples samples into r (an error into its info);
 * u is read from the phase t0 on, the times written t0 + t. */
static int trajectory(cup_pss *r, const cup_lcs *L, const cup_input *u, const cup_integrator_options *io,
                      long samples, double t0) {
  int n = r->info.n, m = r->info.m;
  r->t = calloc((size_t)samples, sizeof(double));
  r->x = calloc((size_t)samples * n, sizeof(double));
  r->zeta = calloc((size_t)samples * (m ? m : 1), sizeof(double));
  if (!r->t || !r->x || !r->zeta || pss_jumps_init(&r->jumps, io->T, samples))
    return say(r, CUP_ERR_NOMEM, "out of memory for the trajectory");
  cup_integrator_options so = *io;
  so.output = CUP_OUTPUT_SAMPLES;
  so.output_samples = samples;
  pss_jumps *J = &r->jumps;                      /* the times a signal may jump, as catchup-run notes them */
  pss_jumps_breaks(J, u);
  J->on_event = so.on_event;
  J->event_ctx = so.event_ctx;
  so.on_event = pss_jumps_event;
  so.event_ctx = J;
  char e2[CUP_ERRMSG_LEN];
  cup_integrator *I = NULL;
  int st = cup_integrator_create(&I, L, u, &so, e2);
  if (st) return say(r, st, "the trajectory's integrator: %s", e2);
  r->info.samples = samples;
  traj c = {r, I, 0, t0};
  cup_run_info ri;
  st = cup_integrator_run(I, r->x0, traj_sink, &c, &ri);
  r->info.period_runs++;
  cup_integrator_free(&I);
  if (st < 0) {
    r->info.samples = c.k;
    return say(r, st, "the steady state's period run failed: %s", ri.message);
  }
  pss_figures f;
  pss_jumps_finish(J, &f);                       /* (a break at T is one at 0 too: a jump at t0) */
  r->nj = J->overflow ? 0 : J->n;
  r->info.jumps = J->overflow ? -1 : J->n;
  for (long q = 0; q < r->nj; q++) J->t[q] += t0;   /* the samples' clock */
  return CUP_OK;
}

int cup_pss_solve(cup_pss **out, const cup_lcs *L, const cup_input *u, const cup_integrator_options *io,
                  const double *x_guess, const cup_pss_options *o, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: NULL result");
  *out = NULL;
  if (!L || !io) return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: NULL LCS or integrator options");
  cup_pss_options def;
  if (!o) { cup_pss_options_default(&def); o = &def; }
  int st = check_options(o, errmsg);
  if (st) return st;
  double T = o->period, t0 = 0;
  cup_input *v = NULL;                           /* u from the phase t0 on, when t0 > 0 */
  if (cup_lcs_inputs(L) > 0 && u) {
    if ((st = cup_input_steady_phase(u, o->period, &T, &t0, errmsg))) return st;
    if (t0 > 0 && (st = input_shift(u, t0, &v, errmsg))) return st;
    if (v) u = v;
  } else if (!(T > 0) || !isfinite(T)) {
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: the circuit has no input to take the period from: give "
                    "the period");
  }
  cup_integrator_options mo;                      /* the period map: the final state only */
  pss_map_options(io, T, T, o->map_tol, &mo);
  mo.on_step = NULL;
  cup_integrator *I = NULL;
  if ((st = cup_integrator_create(&I, L, u, &mo, errmsg))) { cup_input_free(&v); return st; }
  st = cup_pss_solve_map(out, I, cup_lcs_dim(L), T, x_guess, o, errmsg);
  cup_integrator_free(&I);
  if (*out) {
    (*out)->info.m = cup_lcs_rows(L);
    (*out)->info.t0 = t0;
  }
  if (*out && st >= 0 && o->samples >= 2) {
    double w0 = now_seconds();
    mo.on_event = io->on_event;                  /* the events of the period shown */
    if (mo.max_wall_seconds > 0)                 /* the solve's limit: what the Newton left */
      mo.max_wall_seconds = fmax(mo.max_wall_seconds - (*out)->info.seconds, DBL_MIN);
    int ts = trajectory(*out, L, u, &mo, o->samples, t0);
    (*out)->info.seconds += now_seconds() - w0;
    if (ts < 0) st = ts;
  }
  cup_input_free(&v);
  return *out ? (*out)->info.status : st;
}

void pss_map_options(const cup_integrator_options *run, double run_T, double T, double map_tol,
                     cup_integrator_options *mo) {
  *mo = *run;
  if (mo->scheme != CUP_SCHEME_ADAPTIVE && run_T > 0 && run_T != T)   /* a fixed-step scheme keeps its step */
    mo->n = (long)fmax(1, ceil((double)mo->n * T / run_T * (1 - 1e-12)));
  mo->T = T;
  mo->output = CUP_OUTPUT_FINAL;
  mo->output_t0 = 0;
  mo->on_event = NULL;
  if (mo->scheme == CUP_SCHEME_ADAPTIVE && map_tol > 0) mo->tol_abs = mo->tol_rel = map_tol;
}

void cup_pss_get_info(const cup_pss *r, cup_pss_info *info) {
  if (r && info) *info = r->info;
}

const double *cup_pss_x0(const cup_pss *r) { return r ? r->x0 : NULL; }

const double *cup_pss_residuals(const cup_pss *r) { return r ? r->res : NULL; }

const double *cup_pss_monodromy(const cup_pss *r) { return r && r->have_J ? r->J : NULL; }

int cup_pss_multipliers(const cup_pss *r, double *re, double *im) {
  if (!r || !r->have_J) return CUP_ERR_ARG;
  if (re) memcpy(re, r->mre, sizeof(double) * (size_t)r->info.n);
  if (im) memcpy(im, r->mim, sizeof(double) * (size_t)r->info.n);
  return CUP_OK;
}

long cup_pss_jumps(const cup_pss *r, double *t) {
  if (!r || !r->info.samples) return 0;
  if (t && r->nj) memcpy(t, r->jumps.t, sizeof(double) * (size_t)r->nj);
  return r->nj;
}

int cup_pss_trajectory(const cup_pss *r, double *t, double *x, double *zeta) {
  if (!r || !r->info.samples) return CUP_ERR_ARG;
  size_t S = (size_t)r->info.samples;
  if (t) memcpy(t, r->t, sizeof(double) * S);
  if (x) memcpy(x, r->x, sizeof(double) * S * (size_t)r->info.n);
  if (zeta && r->info.m) memcpy(zeta, r->zeta, sizeof(double) * S * (size_t)r->info.m);
  return CUP_OK;
}
