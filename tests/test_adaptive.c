/* The adaptive scheme against closed forms (tests/closed_forms.h,
 * docs/closed-forms.md) and the paper's circuits against their reference
 * limits (tests/data): the error is below tol and follows it, the a
 * posteriori estimate is within 10x of the true error, and the events come
 * at the exact switching times. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "stress_util.h"
#include "closed_forms.h"

typedef double (*exact_fn)(double t, int i, const void *par);

#define MAX_EV 256
typedef struct {
  exact_fn exact;
  const void *par;
  int dim;
  double err, xmax;
  int nev;
  double tev[MAX_EV];
  int row[MAX_EV], on[MAX_EV];
} ad_ctx;

static int ad_sink(long k, double t, const double *x, void *vp) {
  (void)k;
  ad_ctx *c = vp;
  for (int i = 0; i < c->dim; i++) {
    c->err = fmax(c->err, fabs(x[i] - c->exact(t, i, c->par)));
    c->xmax = fmax(c->xmax, fabs(x[i]));
  }
  return 0;
}

static int ad_event(double t, int row, int on, void *vp) {
  ad_ctx *c = vp;
  if (c->nev < MAX_EV) { c->tev[c->nev] = t; c->row[c->nev] = row; c->on[c->nev] = on; c->nev++; }
  return 0;
}

/* One adaptive run with `samples` output times; the error over them. */
static ad_ctx run_adaptive(const cup_lcs *L, const cup_input *u, const double *x0, double T, double tol,
                           long samples, exact_fn ex, const void *par, cup_run_info *info) {
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = T;
  o.tol_abs = o.tol_rel = tol;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_samples = samples;
  ad_ctx c = {.exact = ex, .par = par, .dim = cup_lcs_dim(L)};
  o.on_event = ad_event;
  o.event_ctx = &c;
  cup_integrator *I = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_integrator_create(&I, L, u, &o, msg)) fail_msg("create: %s", msg);
  int st = cup_integrator_run(I, x0, ad_sink, &c, info);
  if (st < 0) fail_msg("run: %s: %s", cup_status_name(st), info->message);
  assert_int_equal(info->samples, samples);
  cup_integrator_free(&I);
  return c;
}

/* The error is within tol (as measured: tol_abs + tol_rel max |x|) and the
 * estimate within 10x of it, unless both are at rounding level. */
static void check_run(const char *name, const ad_ctx *c, const cup_run_info *info, double tol) {
  double target = tol * (1 + c->xmax), floor_ = 1e-13 * (1 + c->xmax);
  print_message("%-30s tol %.0e: error %.3e (%.2f tol), estimate %.3e, %ld steps, %ld events\n", name, tol,
                c->err, c->err / target, info->err_est, info->step, info->events);
  assert_true(c->err <= target);
  if (c->err > floor_ || info->err_est > floor_) {
    assert_true(info->err_est <= 10 * fmax(c->err, floor_));
    assert_true(info->err_est >= 0.1 * c->err);
  }
}

/* Each exact switching time has an event of that row within tol of it. */
static void check_events(const char *name, const ad_ctx *c, int n, const double *t, const int *row, double tol) {
  for (int k = 0; k < n; k++) {
    double best = INFINITY;
    for (int e = 0; e < c->nev; e++)
      if (c->row[e] == row[k]) best = fmin(best, fabs(c->tev[e] - t[k]));
    if (!(best <= tol)) fail_msg("%s: switching time %.17g (row %d): nearest event %.3g away", name, t[k], row[k], best);
  }
}

static cup_input *sine(double amp, double f) {
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = amp, .frequency = f};
  return input_terms(1, &s);
}

static cup_input *constant(double v) {
  cup_wave c = {.kind = CUP_WAVE_CONSTANT, .value = v};
  return input_terms(1, &c);
}

/* The play operator: rate independent, so each phase is exact and the
 * events are where sin t - 1/2 and sin t + 1/2 turn. */
static void test_moving_interval(void **state) {
  (void)state;
  double C[2] = {1, -1}, F[2] = {0.5, 0.5}, G[2] = {-1, 1};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 1, 2, 1, NULL, NULL, C, NULL, F, G, NULL, NULL, msg)) fail_msg("%s", msg);
  cup_input *u = sine(1, 1 / (2 * M_PI));
  double x0[1] = {0}, T = 2.5 * M_PI;
  const double tsw[] = {M_PI / 6, M_PI / 2, M_PI, 1.5 * M_PI, 2 * M_PI};
  const int rows[] = {0, 0, 1, 1, 0};
  for (double tol = 1e-4; tol >= 1e-10; tol *= 1e-3) {
    cup_run_info info;
    ad_ctx c = run_adaptive(b.L, u, x0, T, tol, 1001, interval_exact, NULL, &info);
    check_run("moving interval", &c, &info, tol);
    check_events("moving interval", &c, 5, tsw, rows, tol);
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static void test_interval_with_relaxation(void **state) {
  (void)state;
  double A[1] = {-1}, C[2] = {1, -1}, F[2] = {0.5, 0.5}, G[2] = {-1, 1};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 1, 2, 1, A, NULL, C, NULL, F, G, NULL, NULL, msg)) fail_msg("%s", msg);
  cup_input *u = sine(1, 1 / (2 * M_PI));
  double x0[1] = {0}, T = 2.5 * M_PI;
  relax_par q;
  relax_setup(&q, T);
  double tsw[RELAX_MAX];
  int rows[RELAX_MAX], nsw = 0;
  for (int k = 1; k < q.nev && q.t[k] < T; k++) {
    tsw[nsw] = (double)q.t[k];
    int ph = q.phase[k] ? q.phase[k] : q.phase[k - 1];   /* the row that switches */
    rows[nsw++] = ph == 1 ? 0 : 1;
  }
  for (double tol = 1e-4; tol >= 1e-10; tol *= 1e-3) {
    cup_run_info info;
    ad_ctx c = run_adaptive(b.L, u, x0, T, tol, 1001, relax_exact, &q, &info);
    check_run("interval with relaxation", &c, &info, tol);
    check_events("interval with relaxation", &c, nsw, tsw, rows, tol);
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static void test_cone(void **state) {
  (void)state;
  double A[4] = {-1, 0, 0, -1}, C[4] = {1, 0, 0, 1}, E[2] = {1, -1};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 2, 2, 1, A, NULL, C, E, NULL, NULL, NULL, NULL, msg)) fail_msg("%s", msg);
  cup_input *u = constant(1);
  double x0[2] = {0, 1};
  const double tsw[] = {log(2)};
  const int rows[] = {1};
  for (double tol = 1e-4; tol >= 1e-10; tol *= 1e-3) {
    cup_run_info info;
    ad_ctx c = run_adaptive(b.L, u, x0, 2, tol, 1001, cone_exact, NULL, &info);
    check_run("cone, f = -x + c", &c, &info, tol);
    check_events("cone", &c, 1, tsw, rows, tol);
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static void test_rectifier(void **state) {
  (void)state;
  rect_par q = {1, 0.2, 1, 2 * M_PI, 0};
  rect_setup(&q);
  double A[1] = {-q.R / q.L}, B[1] = {1 / q.L}, C[1] = {1}, E[1] = {q.V / q.L}, P[1] = {q.L};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 1, 1, 1, A, B, C, E, NULL, NULL, P, NULL, msg)) fail_msg("%s", msg);
  cup_input *u = sine(1, 1);
  double x0[1] = {0};
  /* conducting from 0 (row on: zeta > 0 holds i = 0? no: i > 0, the row is
   * off) until t_off, held at 0 until the period ends */
  const double tsw[] = {(double)q.toff, 1, 1 + (double)q.toff};
  const int rows[] = {0, 0, 0};
  for (double tol = 1e-4; tol >= 1e-10; tol *= 1e-3) {
    cup_run_info info;
    ad_ctx c = run_adaptive(b.L, u, x0, 2, tol, 1001, rect_exact, &q, &info);
    check_run("RL half-wave rectifier", &c, &info, tol);
    check_events("RL half-wave rectifier", &c, 3, tsw, rows, tol);
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static void test_corner(void **state) {
  (void)state;
  double A[4] = {-1, 0, 0, -2}, C[4] = {1, 0, 0, 1}, E[2] = {-1, -1}, P[2] = {2, 3};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 2, 2, 1, A, NULL, C, E, NULL, NULL, P, NULL, msg)) fail_msg("%s", msg);
  cup_input *u = constant(1);
  double x0[2] = {1, 1};
  const double tsw[] = {log(2), 0.5 * log(3)};
  const int rows[] = {0, 1};
  for (double tol = 1e-4; tol >= 1e-10; tol *= 1e-3) {
    cup_run_info info;
    ad_ctx c = run_adaptive(b.L, u, x0, 1.5, tol, 1001, corner_exact, NULL, &info);
    check_run("corner of a quadrant", &c, &info, tol);
    check_events("corner", &c, 2, tsw, rows, tol);
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

/* The set jumps at the square wave's breakpoints: the steps end there and
 * the jump is a certified projection, exact. */
static void test_jumping_set(void **state) {
  (void)state;
  double A[1] = {-1}, C[1] = {1}, G[1] = {-1};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 1, 1, 1, A, NULL, C, NULL, NULL, G, NULL, NULL, msg)) fail_msg("%s", msg);
  cup_wave w = {.kind = CUP_WAVE_SQUARE, .amplitude = 1, .frequency = 1};
  cup_input *u = input_terms(1, &w);
  double x0[1] = {1};
  for (double tol = 1e-4; tol >= 1e-10; tol *= 1e-3) {
    cup_run_info info;
    ad_ctx c = run_adaptive(b.L, u, x0, 1.75, tol, 701, jump_exact, NULL, &info);
    check_run("jumping set", &c, &info, tol);
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_moving_interval),
    cmocka_unit_test(test_interval_with_relaxation),
    cmocka_unit_test(test_cone),
    cmocka_unit_test(test_rectifier),
    cmocka_unit_test(test_corner),
    cmocka_unit_test(test_jumping_set),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
