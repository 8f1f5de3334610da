/* test_outtol — output tol (CUP_OUTPUT_TOL, docs/run-output.md): the points
 * the adaptive scheme reports, joined by straight lines, against the exact
 * solution (the converters' reference of tests/pwl_ref.h; an RC's closed
 * form), within a small multiple of the tolerance; fewer of them than a
 * uniform grid of the same accuracy; a stopped run resumed with the same
 * points; the values and schemes it refuses. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "catchup.h"
#include "netlist_integrator.h"
#include "pwl_circuits.h"

#define CIR CUP_SOURCE_DIR "/examples/circuits/"
enum { CAP = 1 << 16, NX = 8 };

typedef struct {
  long n, refuse_at;                             /* points kept; the point the sink refuses (-1: none) */
  double t[CAP], x[CAP][NX];
  int dim;
} pts;

static int keep(long k, double t, const double *x, void *vp) {
  (void)k;
  pts *p = vp;
  if (p->n == p->refuse_at) {
    p->refuse_at = -1;
    return 1;
  }
  if (p->n >= CAP) return 1;
  p->t[p->n] = t;
  memcpy(p->x[p->n], x, sizeof(double) * (size_t)p->dim);
  p->n++;
  return 0;
}

/* The reported points' line at t, component i (t within their span). */
static double line_at(const pts *p, long *j, int i, double t) {
  while (*j + 2 < p->n && p->t[*j + 1] <= t) ++*j;
  double a = p->t[*j], b = p->t[*j + 1];
  if (!(b > a)) return p->x[*j + 1][i];
  double s = (t - a) / (b - a);
  return p->x[*j][i] + s * (p->x[*j + 1][i] - p->x[*j][i]);
}

/* A uniform grid of N points of the exact solution, joined by lines: its
 * worst state's error relative to its peak on the fine grid of G points. */
typedef void (*exact_fn)(const void *ctx, double t, double *x);

static double worst_error(int dim, double T, int G, exact_fn f, const void *ctx, const pts *p, long N) {
  double err[NX] = {0}, peak[NX] = {0}, x[NX], a[NX] = {0}, b[NX] = {0};
  long j = 0, kab = -1;                          /* (the uniform grid's interval whose ends a, b hold) */
  for (int g = 0; g < G; g++) {
    double t = T * g / (G - 1);
    f(ctx, t, x);
    double approx[NX];
    if (p) {
      for (int i = 0; i < dim; i++) approx[i] = line_at(p, &j, i, t);
    } else {                                     /* the uniform grid's line */
      long k = (long)floor(t / T * (double)(N - 1));
      if (k >= N - 1) k = N - 2;
      double ta = T * (double)k / (double)(N - 1), tb = T * (double)(k + 1) / (double)(N - 1);
      if (k != kab) {
        f(ctx, ta, a);
        f(ctx, tb, b);
        kab = k;
      }
      for (int i = 0; i < dim; i++) approx[i] = a[i] + (t - ta) / (tb - ta) * (b[i] - a[i]);
    }
    for (int i = 0; i < dim; i++) {
      err[i] = fmax(err[i], fabs(approx[i] - x[i]));
      peak[i] = fmax(peak[i], fabs(x[i]));
    }
  }
  double w = 0;
  for (int i = 0; i < dim; i++) w = fmax(w, err[i] / fmax(peak[i], 1e-300));
  return w;
}

static void exact_pwl(const void *ctx, double t, double *x) {
  const pr_traj *tr = ctx;
  double y[PR_Y];
  pr_eval_y(tr, t, y);
  for (int i = 0; i < tr->c->n; i++) x[i] = y[i];
}

static cup_integrator *make(cup_netlist *nl, double T, double otol) {
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = T;
  o.tol_abs = o.tol_rel = 1e-9;                  /* (the flow's own error well below the lines') */
  o.output = CUP_OUTPUT_TOL;
  o.output_tol = otol;
  return netlist_integrator(nl, &o);
}

/* Each point's time after the last's, the first 0 and the last T. */
static void check_times(const pts *p, double T) {
  assert_true(p->n >= 2);
  assert_true(p->t[0] == 0 && p->t[p->n - 1] == T);
  for (long k = 1; k < p->n; k++)
    if (!(p->t[k] > p->t[k - 1])) fail_msg("point %ld at t = %.17g, not after %.17g", k, p->t[k], p->t[k - 1]);
}

/* The netlist at output tol 1e-2, 1e-3, 1e-4: the lines within 2 tol of
 * each state's peak, and a uniform grid of as many points worse by 1.5x. */
static void check_example(const char *name) {
  static pr_circuit c;
  static pts p;
  char err[CUP_ERRMSG_LEN], file[512];
  snprintf(file, sizeof file, CIR "%s.cir", name);
  cup_netlist *nl = NULL;
  if (cup_netlist_load(&nl, file, NULL, 0, err)) fail_msg("%s", err);
  double tstep, T, y0[PR_Y], Tref;
  assert_true(cup_netlist_tran(nl, &tstep, &T));
  assert_int_equal(pc_example(name, &c, y0, &Tref), 0);
  assert_true(c.n <= NX);
  pr_traj tr;
  assert_int_equal(pr_solve(&c, y0, T, &tr), 0);
  for (double otol = 1e-2; otol >= 0.99e-4; otol *= 0.1) {
    cup_integrator *I = make(nl, T, otol);
    p.n = 0;
    p.refuse_at = -1;
    p.dim = c.n;
    cup_run_info info;
    int st = cup_integrator_run(I, cup_netlist_x0(nl), keep, &p, &info);
    if (st != CUP_OK) fail_msg("%s: %s", cup_status_name(st), info.message);
    assert_int_equal(info.samples, p.n);
    check_times(&p, T);
    double e = worst_error(c.n, T, 40001, exact_pwl, &tr, &p, 0);
    double eu = worst_error(c.n, T, 40001, exact_pwl, &tr, NULL, p.n);
    print_message("%-20s output tol %.0e: %ld points (%ld steps), error %.3g (%.2f tol); %ld uniform: %.3g\n", name,
                  otol, p.n, info.step, e, e / otol, p.n, eu);
    assert_true(e <= 2 * otol);
    assert_true(eu >= 1.5 * e);
    cup_integrator_free(&I);
  }
  pr_free(&tr);
  cup_netlist_free(&nl);
}

static void test_precision_rectifier(void **state) { (void)state; check_example("precision-rectifier"); }
static void test_sixpulse(void **state) { (void)state; check_example("sixpulse"); }
/* a switched run: each window's steps, the configurations sharing the scales */
static void test_fullbridge(void **state) { (void)state; check_example("fullbridge"); }
static void test_buckboost(void **state) { (void)state; check_example("buckboost"); }

/* An RC charged through a diode from 1 V (tau = 1 ms, 5 tau): v(t) = 1 -
 * exp(-t / tau), closed form. */
static const char *rc_text = "rc\nV1 1 0 DC 1\nD1 1 2\nR1 2 3 1k\nC1 3 0 1u\n.tran 10u 5m\n.end\n";

static void exact_rc(const void *ctx, double t, double *x) {
  (void)ctx;
  x[0] = -expm1(-t / 1e-3);
}

static void test_rc(void **state) {
  (void)state;
  static pts p;
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (cup_netlist_load_string(&nl, rc_text, "rc.cir", NULL, 0, err)) fail_msg("%s", err);
  assert_int_equal(cup_lcs_dim(cup_netlist_lcs(nl)), 1);
  for (double otol = 1e-2; otol >= 0.99e-5; otol *= 0.1) {
    cup_integrator *I = make(nl, 5e-3, otol);
    p.n = 0;
    p.refuse_at = -1;
    p.dim = 1;
    cup_run_info info;
    assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &p, &info), CUP_OK);
    check_times(&p, 5e-3);
    double e = worst_error(1, 5e-3, 100001, exact_rc, NULL, &p, 0);
    double eu = worst_error(1, 5e-3, 100001, exact_rc, NULL, NULL, p.n);
    print_message("rc output tol %.0e: %ld points, error %.3g (%.2f tol); uniform %.3g\n", otol, p.n, e, e / otol, eu);
    assert_true(e <= 2 * otol);
    assert_true(e >= 0.05 * otol);               /* (no more points than the tolerance asks) */
    assert_true(eu >= 1.5 * e);
    cup_integrator_free(&I);
  }
  cup_netlist_free(&nl);
}

/* A sink that refuses a point stops the run (inside a step, or at one's
 * end); resumed from its checkpoint (into the same integrator and into a
 * new one), the points are those of the run never stopped, bit for bit. */
static void check_resume(const char *name) {
  static pts a, b, c;
  char err[CUP_ERRMSG_LEN], file[512];
  snprintf(file, sizeof file, CIR "%s.cir", name);
  cup_netlist *nl = NULL;
  if (cup_netlist_load(&nl, file, NULL, 0, err)) fail_msg("%s", err);
  int n = cup_lcs_dim(cup_netlist_lcs(nl));
  double tstep, T;
  assert_true(cup_netlist_tran(nl, &tstep, &T));
  cup_integrator *I = make(nl, T, 1e-3);
  int st;
  cup_run_info info;
  a.n = 0; a.refuse_at = -1; a.dim = n;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &a, &info), CUP_OK);
  assert_true(a.n > 200);
  for (long at = 7; at < a.n; at += a.n / 5) {
    b.n = 0; b.refuse_at = at; b.dim = n;
    assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &b, &info), CUP_ERR_INTERRUPTED);
    assert_int_equal(b.n, at);
    long size = cup_integrator_checkpoint_size(I);
    void *buf = malloc((size_t)size);
    assert_non_null(buf);
    assert_int_equal(cup_integrator_checkpoint_save(I, &info, buf, (unsigned long)size), CUP_OK);
    c = b;
    assert_int_equal(cup_integrator_checkpoint_restore(I, buf, (unsigned long)size, err), CUP_OK);
    st = cup_integrator_resume(I, keep, &b, &info);
    if (st != CUP_OK) fail_msg("resume at %ld: %s: %s", at, cup_status_name(st), info.message);
    cup_integrator *J = make(nl, T, 1e-3);
    assert_int_equal(cup_integrator_checkpoint_restore(J, buf, (unsigned long)size, err), CUP_OK);
    assert_int_equal(cup_integrator_resume(J, keep, &c, &info), CUP_OK);
    cup_integrator_free(&J);
    free(buf);
    print_message("%s: refused point %ld (t = %.9g): resumed to %ld points of %ld\n", name, at, a.t[at], b.n, a.n);
    assert_int_equal(b.n, a.n);
    assert_int_equal(c.n, a.n);
    assert_memory_equal(a.t, b.t, sizeof(double) * (size_t)a.n);
    assert_memory_equal(a.x, b.x, sizeof a.x[0] * (size_t)a.n);
    assert_memory_equal(a.t, c.t, sizeof(double) * (size_t)a.n);
    assert_memory_equal(a.x, c.x, sizeof a.x[0] * (size_t)a.n);
  }
  /* a checkpoint of another output tol is another run's */
  b.n = 0; b.refuse_at = 20; b.dim = n;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &b, &info), CUP_ERR_INTERRUPTED);
  long size = cup_integrator_checkpoint_size(I);
  void *buf = malloc((size_t)size);
  assert_int_equal(cup_integrator_checkpoint_save(I, &info, buf, (unsigned long)size), CUP_OK);
  cup_integrator *J = make(nl, T, 2e-3);
  assert_int_equal(cup_integrator_checkpoint_restore(J, buf, (unsigned long)size, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "output.tol"));
  cup_integrator_free(&J);
  free(buf);
  cup_integrator_free(&I);
  cup_netlist_free(&nl);
}

/* The six-pulse bridge's points come from its Taylor series (na > 4), the
 * precision rectifier's from the halving levels' exponentials (na 3), the
 * voltage doubler's pieces' middles often from their own Taylor series
 * (short pieces of modes and lengths new to the levels: adaptive_outtol.c's
 * otaylor, the choice a refused piece made kept for its resumed run). */
static void test_resume(void **state) {
  (void)state;
  check_resume("sixpulse");
  check_resume("precision-rectifier");
  check_resume("doubler");
}

/* A switched run stopped by its sink: the points before the refused one
 * are the uninterrupted run's, and it has no checkpoint (as with every
 * output: switched.c), refused with a status, not a blob. */
static void test_switched_stop(void **state) {
  (void)state;
  static pts a, b;
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (cup_netlist_load(&nl, CIR "fullbridge.cir", NULL, 0, err)) fail_msg("%s", err);
  double tstep, T;
  assert_true(cup_netlist_tran(nl, &tstep, &T));
  cup_integrator *I = make(nl, T, 1e-3);
  cup_run_info info;
  a.n = 0; a.refuse_at = -1; a.dim = 2;
  b.n = 0; b.refuse_at = 1234; b.dim = 2;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &a, &info), CUP_OK);
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &b, &info), CUP_ERR_INTERRUPTED);
  assert_int_equal(b.n, 1234);
  assert_memory_equal(a.t, b.t, sizeof(double) * (size_t)b.n);
  assert_memory_equal(a.x, b.x, sizeof a.x[0] * (size_t)b.n);
  assert_true(cup_integrator_checkpoint_size(I) < 0);
  cup_integrator_free(&I);
  cup_netlist_free(&nl);
}

/* What is refused, with a message naming it: bad values, a fixed-step
 * scheme (a switched circuit's too). */
static void test_refused(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (cup_netlist_load_string(&nl, rc_text, "rc.cir", NULL, 0, err)) fail_msg("%s", err);
  const double bad[] = {0, -1e-3, NAN, INFINITY};
  for (size_t q = 0; q < sizeof bad / sizeof *bad; q++) {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.scheme = CUP_SCHEME_ADAPTIVE;
    o.T = 5e-3;
    o.output = CUP_OUTPUT_TOL;
    o.output_tol = bad[q];
    cup_integrator *I = NULL;
    err[0] = 0;
    assert_int_equal(cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), &o, err), CUP_ERR_ARG);
    assert_null(I);
    assert_non_null(strstr(err, "output tol"));
  }
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_THETA;
  o.T = 5e-3;
  o.output = CUP_OUTPUT_TOL;
  o.output_tol = 1e-3;
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), &o, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "adaptive"));
  cup_netlist_free(&nl);
  if (cup_netlist_load(&nl, CIR "fullbridge.cir", NULL, 0, err)) fail_msg("%s", err);
  cup_switching sw;
  assert_int_equal(cup_netlist_switching(nl, &sw), 1);
  assert_int_equal(cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), &o, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "adaptive"));
  assert_int_equal(cup_output_parse("tol"), CUP_OUTPUT_TOL);
  assert_string_equal(cup_output_name(CUP_OUTPUT_TOL), "tol");
  cup_netlist_free(&nl);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rc),
      cmocka_unit_test(test_precision_rectifier),
      cmocka_unit_test(test_sixpulse),
      cmocka_unit_test(test_fullbridge),
      cmocka_unit_test(test_buckboost),
      cmocka_unit_test(test_resume),
      cmocka_unit_test(test_switched_stop),
      cmocka_unit_test(test_refused),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
