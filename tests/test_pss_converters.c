/* The periodic steady state of switched converters (issue 32): cup_pss over
 * a switched integrator (the switches' gates from PULSE sources, the
 * adaptive scheme window by window) on the ideal CCM buck, the DCM buck and
 * the boost of examples/circuits, checked against what does not come from
 * catchup:
 *   - x0 is a fixed point of the exact period map (tests/pwl_ref.h: matrix
 *     exponentials, events bisected to ulps), and the brute-force transient
 *     by catchup's own adaptive scheme, run period after period from rest
 *     until the change is below 1e-12, ends there too;
 *   - the averages and ripples' closed forms over the exact flow from x0
 *     (pr_mean integrates exactly): the CCM buck's D Vin and (Vin - Vout)
 *     D Ts / L, the boost's Vin / (1 - D) over the off time, the DCM buck's
 *     2 / (1 + sqrt(1 + 8 L / (R D^2 Ts))) within its output ripple;
 *   - the Floquet multipliers (pss takes them by forward differences of
 *     catchup's map) against the closed form where the map is linear: the
 *     CCM buck's monodromy e^{A Ts} (both topologies share A: the multipliers
 *     e^{lambda Ts}), the boost's e^{A_off (1-D) Ts} e^{A_on D Ts}; and the
 *     DCM buck's against central differences of the exact period map (one
 *     multiplier 0: the inductor's current restarts from 0 every period);
 *   - the full bridge, whose gate VG3 repeats only from t0 = 25 us: the
 *     steady state through t0 against the brute-force transient of the
 *     netlist as written, sampled at t0 + k T, and its multipliers against
 *     e^{A T} of the filter.
 * Newton's iteration counts and the solve's time are printed. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "catchup.h"
#include "pwl_circuits.h"
#include <complex.h>
#undef I                     /* the integrators are I here; the imaginary unit is _Complex_I */

#define CIR CUP_EXAMPLES_DIR "/circuits/"

typedef struct {
  const char *name;
  cup_netlist *nl;
  pr_circuit c;
  double Ts;
  cup_pss *r;
  cup_pss_info info;
  double mu[2][2];           /* the multipliers (re, im), by decreasing modulus */
  double di;                 /* the exact flow's i(L)(Ts) - i(L)(0) from x0: 0 at the fixed point */
} conv;

static cup_integrator *period_map(conv *v, double tol) {
  char err[CUP_ERRMSG_LEN];
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = v->Ts;
  o.tol_abs = o.tol_rel = tol;
  o.output = CUP_OUTPUT_FINAL;
  cup_switching sw;
  cup_integrator *I = NULL;
  assert_true(cup_netlist_switching(v->nl, &sw));
  if (cup_integrator_create_switched(&I, &sw, cup_netlist_input(v->nl), &o, err)) fail_msg("%s: %s", v->name, err);
  return I;
}

/* Loads the example, its exact model, and solves its steady state from rest. */
static void solve(conv *v, const char *name) {
  char err[CUP_ERRMSG_LEN], file[512];
  double y0[PR_Y], T;
  memset(v, 0, sizeof *v);
  v->name = name;
  snprintf(file, sizeof file, CIR "%s.cir", name);
  if (cup_netlist_load(&v->nl, file, NULL, 0, err)) fail_msg("%s", err);
  assert_int_equal(pc_example(name, &v->c, y0, &T), 0);
  assert_int_equal(cup_lcs_dim(cup_netlist_lcs(v->nl)), 2);
  assert_int_equal(cup_input_period(cup_netlist_input(v->nl), &v->Ts, err), CUP_OK);
  assert_true(fabs(v->Ts - 1e-5) <= 1e-17);
  cup_integrator *I = period_map(v, 1e-12);
  cup_pss_options o;
  cup_pss_options_default(&o);
  int st = cup_pss_solve_map(&v->r, I, 2, v->Ts, cup_netlist_x0(v->nl), &o, err);
  cup_integrator_free(&I);
  if (!v->r) fail_msg("%s: %s", name, err);
  cup_pss_get_info(v->r, &v->info);
  double re[2], im[2];
  assert_int_equal(cup_pss_multipliers(v->r, re, im), CUP_OK);
  for (int k = 0; k < 2; k++) v->mu[k][0] = re[k], v->mu[k][1] = im[k];
  const double *x0 = cup_pss_x0(v->r);
  print_message("%-9s %s: %d Newton steps (residuals %.2g .. %.2g), %ld period runs, %.3f ms; x0 = (%.12g, %.12g); "
                "mu = %.9g%+.9gi, %.9g%+.9gi\n", name, cup_status_name(st), v->info.iterations,
                cup_pss_residuals(v->r)[0], v->info.residual, v->info.period_runs, 1e3 * v->info.seconds, x0[0], x0[1],
                re[0], im[0], re[1], im[1]);
  assert_int_equal(st, CUP_OK);
  assert_true(v->info.residual <= 1e-10 * (1 + fmax(fabs(x0[0]), fabs(x0[1]))));
}

static void done(conv *v) {
  cup_pss_free(&v->r);
  cup_netlist_free(&v->nl);
}

/* The exact period map: x(Ts) from x (the reference's (x, 1)). */
static void exact_map(const conv *v, const double *x, double *out, pr_traj *keep) {
  double y[PR_Y] = {0};
  y[0] = x[0], y[1] = x[1], y[2] = 1;
  pr_traj tr;
  assert_int_equal(pr_solve(&v->c, y, v->Ts, &tr), 0);
  pr_eval_left(&tr, v->Ts, out);
  if (keep) *keep = tr;
  else pr_free(&tr);
}

/* x0 against the exact map's fixed point and catchup's brute force. */
static void check_fixed_point(conv *v, pr_traj *tr) {
  const double *x0 = cup_pss_x0(v->r);
  double y[2], scale = 1 + fmax(fabs(x0[0]), fabs(x0[1]));
  exact_map(v, x0, y, tr);
  double d = fmax(fabs(y[0] - x0[0]), fabs(y[1] - x0[1]));
  v->di = y[0] - x0[0];
  /* brute force: Phi from rest until the change is below 1e-12 relative */
  cup_integrator *I = period_map(v, 1e-12);
  double x[2] = {0, 0}, change = INFINITY;
  long k = 0;
  for (; k < 100000 && !(change <= 1e-12 * fmax(fabs(x[0]), fabs(x[1]))); k++) {
    cup_run_info ri;
    if (cup_integrator_run(I, x, NULL, NULL, &ri) < 0) fail_msg("%s: %s", v->name, ri.message);
    const double *z = cup_integrator_state(I);
    change = fmax(fabs(z[0] - x[0]), fabs(z[1] - x[1]));
    x[0] = z[0], x[1] = z[1];
  }
  cup_integrator_free(&I);
  double db = fmax(fabs(x[0] - x0[0]), fabs(x[1] - x0[1]));
  print_message("%-9s |Phi_exact(x0) - x0| = %.3g; brute force: %ld periods to a change of %.2g, |x - x0| = %.3g\n",
                v->name, d, k, change, db);
  assert_true(d <= 1e-9 * scale);
  /* Both are off the fixed point by their residual (Newton's, the brute
   * force's last change) times ||(I - M)^-1||: a residual of 1e-10 is 6e-9
   * of x0 on the boost, whose multipliers are 0.156 from 1 */
  const double *M = cup_pss_monodromy(v->r);
  double a = 1 - M[0], b = -M[2], c = -M[1], e = 1 - M[3], det = a * e - b * c;
  double inv = fmax(fabs(e) + fabs(b), fabs(c) + fabs(a)) / fabs(det);
  print_message("%-9s ||(I - M)^-1|| = %.3g: the bound %.3g\n", v->name, inv, 2 * inv * (v->info.residual + change));
  assert_true(db <= 2 * inv * (v->info.residual + change));
}

/* e^{A t} of a 2 x 2 A (the reference's matrix exponential, column by column). */
static void expm2(const double A[2][2], double t, double E[2][2]) {
  double M[PR_Y][PR_Y] = {{0}};
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) M[i][j] = A[i][j];
  for (int j = 0; j < 2; j++) {
    double e[PR_Y] = {0}, y[PR_Y];
    e[j] = 1;
    pr_flow(2, M, e, t, y);
    E[0][j] = y[0], E[1][j] = y[1];
  }
}

/* The eigenvalues of a 2 x 2 matrix, by decreasing modulus. */
static void eig2(const double M[2][2], double complex mu[2]) {
  double tr = M[0][0] + M[1][1], det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
  double complex s = csqrt((double complex)(tr * tr / 4 - det));
  mu[0] = tr / 2 + s, mu[1] = tr / 2 - s;
  if (cabs(mu[1]) > cabs(mu[0])) { double complex w = mu[0]; mu[0] = mu[1]; mu[1] = w; }
}

static void check_multipliers(const conv *v, const double M[2][2], double tol) {
  double complex want[2];
  eig2(M, want);
  for (int k = 0; k < 2; k++) {
    double complex got = v->mu[k][0] + _Complex_I * v->mu[k][1];
    /* a complex pair comes in either order of its imaginary parts */
    double d = fmin(cabs(got - want[k]), cabs(got - conj(want[k])));
    print_message("%-9s mu_%d = %.9f%+.9fi, closed form %.9f%+.9fi: %.2g\n", v->name, k, creal(got), cimag(got),
                  creal(want[k]), cimag(want[k]), d);
    assert_true(d <= tol);
  }
}

/* The steady state of examples/circuits/NAME.cir, solved and checked
 * against the exact map and brute force (check_fixed_point); tr keeps the
 * exact period from x0. */
static void solve_checked(conv *v, const char *name, pr_traj *tr) {
  solve(v, name);
  check_fixed_point(v, tr);
}

/* The extremes of v(out) = x[1] over the period, on 2001 points. */
static void vout_range(const pr_traj *tr, double Ts, double *vmin, double *vmax) {
  *vmin = INFINITY, *vmax = -INFINITY;
  for (int k = 0; k <= 2000; k++) {
    double x[2];
    pr_eval(tr, k * Ts / 2000, x);
    *vmin = fmin(*vmin, x[1]), *vmax = fmax(*vmax, x[1]);
  }
}

/* ---- the CCM buck: 12 V, D = 0.5, 100 uH, 10 uF || 5 ohm ---- */
static void buck_ccm(void **state) {
  (void)state;
  const double Vin = 12, D = 0.5, L = 100e-6, C = 10e-6, R = 5;
  conv v;
  pr_traj tr;
  solve_checked(&v, "buck-ccm", &tr);
  const double rv[PR_Y] = {0, 1, 0}, Ts = v.Ts;
  double vavg = pr_mean(&tr, rv, 0, Ts), von = pr_mean(&tr, rv, 0, D * Ts);
  double a[2], b[2];
  pr_eval(&tr, 0, a);
  pr_eval(&tr, D * Ts, b);
  double ripple = b[0] - a[0], closed = (Vin - vavg) * D * Ts / L;
  /* the output's own ripple bounds how far the mean over the on time is from the mean */
  double vmin, vmax;
  vout_range(&tr, Ts, &vmin, &vmax);
  print_message("buck-ccm  mean v(out) %.12f V (D Vin = %.12f); i(L) ripple %.9f A, (Vin - Vout) D Ts / L = %.9f A, "
                "exact (Vin - mean_on v) D Ts / L = %.9f A; v(out) p-p %.6g V\n", vavg, D * Vin, ripple, closed,
                (Vin - von) * D * Ts / L, vmax - vmin);
  assert_true(fabs(vavg - D * Vin) <= 1e-9 * Vin);
  assert_true(fabs(ripple - (Vin - von) * D * Ts / L) <= 1e-9);
  assert_true(fabs(ripple - closed) <= D * Ts / L * (vmax - vmin));
  /* the monodromy: e^{A Ts}, A the L-C-R filter's (the same in both topologies) */
  const double A[2][2] = {{0, -1 / L}, {1 / C, -1 / (R * C)}};
  double E[2][2];
  expm2(A, Ts, E);
  check_multipliers(&v, E, 1e-6);
  pr_free(&tr);
  done(&v);
}

/* ---- the boost: 5 V, 50 uH, D = 0.5, 20 uF || 10 ohm (in CCM) ---- */
static void boost(void **state) {
  (void)state;
  const double Vin = 5, D = 0.5, L = 50e-6, C = 20e-6, R = 10;
  conv v;
  pr_traj tr;
  solve_checked(&v, "boost", &tr);
  const double rv[PR_Y] = {0, 1, 0}, Ts = v.Ts;
  double voff = pr_mean(&tr, rv, D * Ts, Ts), vavg = pr_mean(&tr, rv, 0, Ts);
  print_message("boost     mean v(out) over the off time %.12f V (Vin / (1 - D) = %.12f), over the period %.9f V\n", voff,
                Vin / (1 - D), vavg);
  /* the inductor's volt-seconds: L (i(Ts) - i(0)) = (Vin - voff) (1 - D) Ts, so x0's
   * residual moves voff by L di / ((1 - D) Ts) (5.5e-9 V here) */
  assert_true(fabs(voff - Vin / (1 - D)) <= L * fabs(v.di) / ((1 - D) * Ts) + 1e-12 * Vin);
  /* CCM (the diode conducts the whole off time): Phi' = e^{A_off (1-D) Ts} e^{A_on D Ts} */
  const double Aon[2][2] = {{0, 0}, {0, -1 / (R * C)}}, Aoff[2][2] = {{0, -1 / L}, {1 / C, -1 / (R * C)}};
  double Eon[2][2], Eoff[2][2], M[2][2];
  expm2(Aon, D * Ts, Eon);
  expm2(Aoff, (1 - D) * Ts, Eoff);
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) M[i][j] = Eoff[i][0] * Eon[0][j] + Eoff[i][1] * Eon[1][j];
  check_multipliers(&v, M, 1e-6);
  pr_free(&tr);
  done(&v);
}

/* ---- the DCM buck: 12 V, D = 0.3, 10 uH, 10 uF || 20 ohm ---- */
static void buck_dcm(void **state) {
  (void)state;
  const double Vin = 12, D = 0.3, L = 10e-6, R = 20;
  conv v;
  pr_traj tr;
  solve_checked(&v, "buck-dcm", &tr);
  const double rv[PR_Y] = {0, 1, 0}, Ts = v.Ts;
  double M = pr_mean(&tr, rv, 0, Ts) / Vin, closed = 2 / (1 + sqrt(1 + 8 * L / (R * D * D * Ts)));
  double vmin, vmax;
  vout_range(&tr, Ts, &vmin, &vmax);
  print_message("buck-dcm  M = %.9f against 2 / (1 + sqrt(1 + 8 L / (R D^2 Ts))) = %.9f; v(out) p-p / Vin %.6g; "
                "%d events a period\n", M, closed, (vmax - vmin) / Vin, tr.events);
  assert_true(fabs(M - closed) <= (vmax - vmin) / Vin);
  assert_true(tr.events >= 1);                      /* the diode blocks inside the period: DCM */
  /* the exact map's Jacobian by central differences (its pieces' events move with x) */
  const double *x0 = cup_pss_x0(v.r);
  double J[2][2];
  for (int j = 0; j < 2; j++) {
    double h = 1e-6 * fmax(1, fabs(x0[j])), xp[2] = {x0[0], x0[1]}, xm[2] = {x0[0], x0[1]}, yp[2], ym[2];
    xp[j] += h, xm[j] -= h;
    exact_map(&v, xp, yp, NULL);
    exact_map(&v, xm, ym, NULL);
    for (int i = 0; i < 2; i++) J[i][j] = (yp[i] - ym[i]) / (2 * h);
  }
  check_multipliers(&v, J, 1e-5);
  assert_true(hypot(v.mu[1][0], v.mu[1][1]) <= 1e-5);   /* the current's reset: a multiplier 0 */
  pr_free(&tr);
  done(&v);
}

/* ---- the full bridge: 100 V, phase-shifted legs, 1 mH, 2.2 uF || 20 ohm ---- */

/* Its gate VG3 (delay 76 us, width 49 us, period 100 us) runs past its
 * period's end: the sources repeat from t0 = 76 + 49 - 100 = 25 us on, not
 * from 0. The steady state is the orbit through t0 (the netlist's sources
 * read from t0, cup_netlist_set_time_origin), checked against the brute
 * force of the netlist as written: the transient from rest, sampled at
 * t0 + k T, until the change from one period to the next is below 1e-12;
 * and the multipliers against e^{A T}: the bridge only switches the
 * voltage across the filter (its diodes carry the current in the dead
 * times, which never reaches 0 there), so the map is e^{A T} x + c. */
typedef struct {
  double prev[2], change;
  long k, settled;
} bf_watch;

static int bf_sink(long k, double t, const double *x, void *ctx) {
  (void)k, (void)t;
  bf_watch *w = ctx;
  w->change = fmax(fabs(x[0] - w->prev[0]), fabs(x[1] - w->prev[1]));
  w->prev[0] = x[0], w->prev[1] = x[1];
  if (w->k++ > 0 && w->change <= 1e-12 * fmax(fabs(x[0]), fabs(x[1]))) return 1;   /* settled: stop */
  return 0;
}

static void fullbridge(void **state) {
  (void)state;
  const double L = 1e-3, C = 2.2e-6, R = 20;
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (cup_netlist_load(&nl, CIR "fullbridge.cir", NULL, 0, err)) fail_msg("%s", err);
  double T = 0, t0;
  assert_int_equal(cup_input_steady_phase(cup_netlist_input(nl), 0, &T, &t0, err), CUP_OK);
  assert_true(fabs(T - 100e-6) <= 1e-18 && fabs(t0 - 25e-6) <= 1e-18);
  /* brute force: the netlist as written from rest, a sample at t0 + k T, up to 1000 periods */
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.tol_abs = o.tol_rel = 1e-12;
  o.T = t0 + 1000 * T;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_samples = 1001;
  o.output_t0 = t0;
  cup_switching sw;
  cup_integrator *I = NULL;
  assert_true(cup_netlist_switching(nl, &sw));
  if (cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), &o, err)) fail_msg("%s", err);
  bf_watch bw = {{0, 0}, INFINITY, 0, 0};
  cup_run_info ri;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), bf_sink, &bw, &ri), CUP_ERR_INTERRUPTED);
  cup_integrator_free(&I);
  /* the steady state from t0 */
  assert_int_equal(cup_netlist_set_time_origin(nl, t0, err), CUP_OK);
  conv v = {.name = "fullbridge", .nl = nl, .Ts = T};
  I = period_map(&v, 1e-12);
  cup_pss_options po;
  cup_pss_options_default(&po);
  int st = cup_pss_solve_map(&v.r, I, 2, T, cup_netlist_x0(nl), &po, err);
  cup_integrator_free(&I);
  if (!v.r) fail_msg("%s", err);
  cup_pss_get_info(v.r, &v.info);
  const double *x0 = cup_pss_x0(v.r);
  double re[2], im[2];
  assert_int_equal(cup_pss_multipliers(v.r, re, im), CUP_OK);
  for (int k = 0; k < 2; k++) v.mu[k][0] = re[k], v.mu[k][1] = im[k];
  double d = fmax(fabs(x0[0] - bw.prev[0]), fabs(x0[1] - bw.prev[1]));
  const double *M = cup_pss_monodromy(v.r);
  double a = 1 - M[0], b = -M[2], c = -M[1], e = 1 - M[3], det = a * e - b * c;
  double inv = fmax(fabs(e) + fabs(b), fabs(c) + fabs(a)) / fabs(det);
  print_message("fullbridge %s: t0 = %.17g, %d Newton steps (residuals %.2g .. %.2g), %ld period runs, %.3f ms; "
                "x0 = (%.12g, %.12g); brute force %ld periods to a change of %.2g, |x - x0| = %.3g (bound %.3g)\n",
                cup_status_name(st), t0, v.info.iterations, cup_pss_residuals(v.r)[0], v.info.residual,
                v.info.period_runs, 1e3 * v.info.seconds, x0[0], x0[1], bw.k - 1, bw.change, d,
                2 * inv * (v.info.residual + bw.change));
  assert_int_equal(st, CUP_OK);
  assert_true(d <= 2 * inv * (v.info.residual + bw.change));
  const double A[2][2] = {{0, -1 / L}, {1 / C, -1 / (R * C)}};
  double E[2][2];
  expm2(A, T, E);
  check_multipliers(&v, E, 1e-6);
  cup_pss_free(&v.r);
  cup_netlist_free(&nl);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(buck_ccm),
      cmocka_unit_test(boost),
      cmocka_unit_test(buck_dcm),
      cmocka_unit_test(fullbridge),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
