/* The periodic steady state (catchup/pss.h) against independent references:
 * linear RC and RLC circuits driven by a sine or a pulse train (the steady
 * state from the closed-form response, the Floquet multipliers e^{lambda T}
 * of the circuit's eigenvalues); rectifiers with a diode that turns off
 * inside the period (D = 0 and D != 0, a bridge) against brute-force
 * transients run until the period-to-period change is below 1e-12, by the
 * adaptive scheme and by a fixed-step one, and the largest multiplier
 * against the brute force's contraction rate; the ideal LC driven at its
 * resonance (no steady state: a clear error); the inputs' common period
 * and its errors; the measurements against closed forms. Newton's
 * iteration counts are printed. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "catchup.h"
#include "testutil.h"

static double cup_test_inf(const double *v, int n) {
  double r = 0;
  for (int i = 0; i < n; i++) r = fmax(r, fabs(v[i]));
  return r;
}

typedef struct {
  cup_netlist *nl;
  cup_pss *r;
  cup_pss_info info;
  int n, m;
} solved;

static cup_netlist *load(const char *text) {
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (cup_netlist_load_string(&nl, text, "test.cir", NULL, 0, err)) fail_msg("%s", err);
  return nl;
}

static void opts_for(cup_integrator_options *io, int scheme, long n) {
  cup_integrator_options_default(io);
  io->scheme = scheme;
  io->n = n > 0 ? n : 100;                      /* the adaptive scheme does not use n */
  io->tol_abs = io->tol_rel = 1e-12;
}

/* The steady state of a netlist (status expected) over the period T (0: the
 * sources' common period), samples of it. */
static solved solve_over(const char *text, int scheme, long n, long samples, double T, int want) {
  solved s = {0};
  s.nl = load(text);
  const cup_lcs *L = cup_netlist_lcs(s.nl);
  s.n = cup_lcs_dim(L);
  s.m = cup_lcs_rows(L);
  cup_integrator_options io;
  opts_for(&io, scheme, n);
  cup_pss_options o;
  cup_pss_options_default(&o);
  o.samples = samples;
  o.period = T;
  char err[CUP_ERRMSG_LEN] = "";
  int st = cup_pss_solve(&s.r, L, cup_netlist_input(s.nl), &io, NULL, &o, err);
  if (!s.r) fail_msg("no result: %s", err);
  cup_pss_get_info(s.r, &s.info);
  print_message("  %s: %d Newton steps, %ld period runs, residual %.3g, |mu|max %.6g, %.3g ms: %s%s%s\n",
                cup_status_name(st), s.info.iterations, s.info.period_runs, s.info.residual, s.info.max_multiplier,
                1e3 * s.info.seconds, s.info.message[0] ? "\"" : "", s.info.message, s.info.message[0] ? "\"" : "");
  if (st != want) fail_msg("status %s, expected %s: %s", cup_status_name(st), cup_status_name(want), s.info.message);
  return s;
}

static solved solve(const char *text, int scheme, long n, long samples, int want) {
  return solve_over(text, scheme, n, samples, 0, want);
}

static void done(solved *s) {
  cup_pss_free(&s->r);
  cup_netlist_free(&s->nl);
}

/* A signal (probe) of the steady state's samples into v (samples entries). */
static void signal_of(solved *s, const char *probe, double *v) {
  char err[CUP_ERRMSG_LEN];
  int k = cup_netlist_probe(s->nl, probe, err);
  if (k < 0) fail_msg("%s", err);
  long S = s->info.samples;
  double *t = calloc((size_t)S, sizeof *t), *x = calloc((size_t)S * s->n, sizeof *x);
  double *z = calloc((size_t)S * (s->m + 1), sizeof *z), *out = calloc(64, sizeof *out);
  assert_int_equal(cup_pss_trajectory(s->r, t, x, z), CUP_OK);
  for (long j = 0; j < S; j++) {
    assert_int_equal(cup_netlist_signals(s->nl, t[j], x + j * s->n, z + j * s->m, out), CUP_OK);
    v[j] = out[k];
  }
  free(t); free(x); free(z); free(out);
}

/* The brute force: x <- Phi(x) from 0 until the period-to-period change is
 * below rel * ||x||_inf; the last two changes' ratio (the slowest mode's
 * multiplier) into *rate. Returns the periods run. */
static long brute_force(cup_netlist *nl, int scheme, long n, double T, double rel, double *x, double *rate) {
  const cup_lcs *L = cup_netlist_lcs(nl);
  int dim = cup_lcs_dim(L);
  cup_integrator_options io;
  opts_for(&io, scheme, n);
  io.T = T;
  io.output = CUP_OUTPUT_FINAL;
  char err[CUP_ERRMSG_LEN];
  cup_integrator *I = NULL;
  if (cup_integrator_create(&I, L, cup_netlist_input(nl), &io, err)) fail_msg("%s", err);
  for (int i = 0; i < dim; i++) x[i] = 0;
  double prev = 0, d = INFINITY;
  long k = 0;
  *rate = NAN;
  for (; k < 100000 && !(d <= rel * (cup_test_inf(x, dim))); k++) {
    cup_run_info ri;
    int st = cup_integrator_run(I, x, NULL, NULL, &ri);
    if (st < 0) fail_msg("%s", ri.message);
    const double *y = cup_integrator_state(I);
    d = 0;
    for (int i = 0; i < dim; i++) { d = fmax(d, fabs(y[i] - x[i])); x[i] = y[i]; }
    if (prev > 0 && d > 1e3 * rel * cup_test_inf(x, dim)) *rate = d / prev;   /* above the rounding */
    prev = d;
  }
  cup_integrator_free(&I);
  return k;
}

/* ---- linear circuits: closed forms ---- */

/* RC low-pass under a 50 Hz sine: v(out) = Vm |H| sin(w t + arg H), H =
 * 1 / (1 + j w R C), at every sample; the multiplier e^{-T / RC}; the
 * resistor's average power |I|^2 R / 2 measured from v and i. */
static void rc_sine(void **state) {
  (void)state;
  const double Vm = 10, R = 1e3, C = 10e-6, f = 50, w = 2 * M_PI * f, T = 1 / f;
  solved s = solve("RC low-pass\nV1 in 0 SIN(0 10 50)\nR1 in out 1k\nC1 out 0 10u\n.end\n", CUP_SCHEME_ADAPTIVE, 0,
                   1025, CUP_OK);
  assert_close(s.info.period, T, 1e-17);
  double re[4], im[4];
  assert_int_equal(cup_pss_multipliers(s.r, re, im), CUP_OK);
  assert_close(re[0], exp(-T / (R * C)), 1e-12);   /* the adaptive scheme's tangent: exact */
  assert_close(im[0], 0, 1e-12);
  assert_true(s.info.iterations <= 2);          /* linear: one Newton step, exact to the FD error */
  long S = s.info.samples;
  double *v = calloc((size_t)S, sizeof *v), *vr = calloc((size_t)S, sizeof *vr), *i = calloc((size_t)S, sizeof *i);
  signal_of(&s, "v(out)", v);
  double a = w * R * C, mag = Vm / sqrt(1 + a * a), ph = -atan(a), err = 0;
  for (long j = 0; j < S; j++) err = fmax(err, fabs(v[j] - mag * sin(w * T * (double)j / (double)(S - 1) + ph)));
  print_message("  RC: max |v - closed form| over the period %.3g V (|v| <= %.3g)\n", err, mag);
  assert_true(err <= 1e-9 * Vm);
  signal_of(&s, "v(in,out)", vr);
  signal_of(&s, "i(R1)", i);
  for (long j = 0; j < S; j++) vr[j] *= i[j];
  cup_measure mp;
  char e2[CUP_ERRMSG_LEN];
  assert_int_equal(cup_measure_period(vr, S, 0, &mp, NULL, NULL, e2), CUP_OK);
  double P = Vm * Vm / (R * R + 1 / (w * w * C * C)) * R / 2;
  print_message("  RC: resistor power %.15g W, closed form %.15g W\n", mp.avg, P);
  assert_close(mp.avg, P, 1e-9 * P);
  free(v); free(vr); free(i);
  done(&s);
}

/* x' = A x + b u, A 2 x 2, u a pulse train V2 on [0, width), 0 after: the
 * fixed point x0 = (I - e^{AT})^-1 A^-1 (e^{A(T-on)} - e^{A(T-off)}) b V2 for a
 * pulse on [on, off), by GSL's matrix exponential. */
static void pulse_fixed_point(const double A[4], const double b[2], double V2, double on, double off, double T,
                              double x0[2]) {
  gsl_matrix *Am = gsl_matrix_alloc(2, 2), *E1 = gsl_matrix_alloc(2, 2), *E2 = gsl_matrix_alloc(2, 2);
  gsl_matrix *S = gsl_matrix_alloc(2, 2);
  for (int k = 0; k < 4; k++) Am->data[k] = A[k] * (T - on);
  gsl_linalg_exponential_ss(Am, E1, GSL_PREC_DOUBLE);
  for (int k = 0; k < 4; k++) Am->data[k] = A[k] * (T - off);
  gsl_linalg_exponential_ss(Am, E2, GSL_PREC_DOUBLE);
  double d[2], y[2];
  for (int i = 0; i < 2; i++) d[i] = ((E1->data[2 * i] - E2->data[2 * i]) * b[0] + (E1->data[2 * i + 1] - E2->data[2 * i + 1]) * b[1]) * V2;
  double det = A[0] * A[3] - A[1] * A[2];          /* y = A^-1 d */
  y[0] = (A[3] * d[0] - A[1] * d[1]) / det;
  y[1] = (-A[2] * d[0] + A[0] * d[1]) / det;
  for (int k = 0; k < 4; k++) Am->data[k] = A[k] * T;
  gsl_linalg_exponential_ss(Am, S, GSL_PREC_DOUBLE);
  double M[4] = {1 - S->data[0], -S->data[1], -S->data[2], 1 - S->data[3]};
  double dm = M[0] * M[3] - M[1] * M[2];
  x0[0] = (M[3] * y[0] - M[1] * y[1]) / dm;
  x0[1] = (-M[2] * y[0] + M[0] * y[1]) / dm;
  gsl_matrix_free(Am); gsl_matrix_free(E1); gsl_matrix_free(E2); gsl_matrix_free(S);
}

/* Series RLC under a 5 V, 10 us pulse every 25 us: i(L1) and v(C1) at
 * t = 0 against the closed form, the multipliers e^{lambda T} with
 * lambda = -R/2L +- j sqrt(1/LC - R^2/4L^2) (complex: their modulus and
 * angle). By the adaptive scheme and by theta at 4000 steps a period. */
static void rlc_pulse(void **state) {
  (void)state;
  const double R = 2, L = 100e-6, C = 1e-6, T = 25e-6, wid = 10e-6;   /* 1 fs edges */
  const char *cir = "RLC\nV1 in 0 PULSE(0 5 0 1f 1f 10u 25u)\nR1 in a 2\nL1 a b 100u\nC1 b 0 1u\n.end\n";
  double A[4] = {-R / L, -1 / L, 1 / C, 0}, b[2] = {1 / L, 0}, x0[2];
  pulse_fixed_point(A, b, 5, 0.5e-15, 1.5e-15 + wid, T, x0);   /* the 1 fs edges' middles */
  double sig = -R / (2 * L), om = sqrt(1 / (L * C) - R * R / (4 * L * L));
  for (int k = 0; k < 2; k++) {
    int scheme = k ? CUP_SCHEME_THETA : CUP_SCHEME_ADAPTIVE;
    print_message("  RLC pulse, %s:\n", cup_scheme_name(scheme));
    solved s = solve(cir, scheme, 4000, 101, CUP_OK);
    double iL[101], vC[101], re[2], im[2];
    signal_of(&s, "i(L1)", iL);
    signal_of(&s, "v(b)", vC);
    double tol = k ? 1e-3 : 1e-9;               /* theta: second order, h = T / 4000 */
    print_message("  i(L1)(0) = %.15g (closed form %.15g), v(C1)(0) = %.15g (%.15g)\n", iL[0], x0[0], vC[0], x0[1]);
    assert_close(iL[0], x0[0], tol * fabs(x0[0]));
    assert_close(vC[0], x0[1], tol * fabs(x0[1]));
    assert_close(iL[100], iL[0], tol * fabs(x0[0]));
    assert_int_equal(cup_pss_multipliers(s.r, re, im), CUP_OK);
    assert_close(hypot(re[0], im[0]), exp(sig * T), k ? 1e-5 : 1e-12);
    assert_close(fabs(atan2(im[0], re[0])), om * T, k ? 1e-3 : 1e-11);
    assert_close(im[0], -im[1], 1e-12);
    done(&s);
  }
}

/* ---- rectifiers: brute-force transients ---- */

static const char *halfwave_rc =
  "Half-wave rectifier with an RC load\nV1 in 0 SIN(0 10 50)\nRs in a 1\nD1 a out\nC1 out 0 100u\nRL out 0 1k\n.end\n";
static const char *bridge_rc =
  "Bridge\nV1 in1 x SIN(0 10 50)\nRs x in2 1\nD1 in1 out\nD2 in2 out\nD3 0 in1\nD4 0 in2\nC1 out 0 100u\n"
  "RL out 0 1k\n.end\n";
static const char *rl_halfwave = "RL half-wave\nV1 in 0 SIN(0 10 50)\nD1 in a\nR1 a b 10\nL1 b 0 50m\n.end\n";

/* The steady state by Newton against the brute force of the same scheme
 * (the same period map: they agree to its accuracy), and the largest
 * multiplier against the brute force's contraction rate. */
static void against_brute_force(const char *cir, int scheme, long n, double rate_tol) {
  solved s = solve(cir, scheme, n, 0, CUP_OK);
  double xb[16], rate, re[16], im[16];
  long periods = brute_force(s.nl, scheme, n, s.info.period, 1e-12, xb, &rate);
  const double *x0 = cup_pss_x0(s.r);
  double diff = 0, sc = cup_test_inf(xb, s.n);
  for (int i = 0; i < s.n; i++) diff = fmax(diff, fabs(x0[i] - xb[i]));
  assert_int_equal(cup_pss_multipliers(s.r, re, im), CUP_OK);
  print_message("  %s: brute force %ld periods (to a change below 1e-12), |x0 - x_bf| = %.3g (|x| %.3g); "
                "multipliers %.9g%+.3gi, %.9g%+.3gi; contraction rate %.9g\n", cup_scheme_name(scheme), periods, diff,
                sc, re[0], im[0], s.n > 1 ? re[1] : 0., s.n > 1 ? im[1] : 0., rate);
  assert_true(diff <= 1e-9 * sc);
  if (rate_tol > 0 && isfinite(rate)) assert_close(hypot(re[0], im[0]), rate, rate_tol);
  assert_true(s.info.max_multiplier < 1);
  done(&s);
}

static void halfwave_rc_adaptive(void **state) { (void)state; against_brute_force(halfwave_rc, CUP_SCHEME_ADAPTIVE, 0, 1e-4); }
static void halfwave_rc_theta(void **state) { (void)state; against_brute_force(halfwave_rc, CUP_SCHEME_THETA, 2000, 1e-4); }
/* Rs = 20 ohm: the capacitor charges through 2 ms, its mode survives a
 * period (a multiplier the brute force's contraction shows). */
static void halfwave_slow(void **state) {
  (void)state;
  against_brute_force("Half-wave, 20 ohm\nV1 in 0 SIN(0 10 50)\nRs in a 20\nD1 a out\nC1 out 0 100u\nRL out 0 1k\n.end\n",
                      CUP_SCHEME_ADAPTIVE, 0, 1e-4);
}
static void bridge_adaptive(void **state) { (void)state; against_brute_force(bridge_rc, CUP_SCHEME_ADAPTIVE, 0, 1e-4); }

/* D = 0 in DCM: the current dies inside every period, so the orbit starts
 * at i = 0 and every perturbation is forgotten (multipliers 0); the
 * current is the closed form (Vm/Z)(sin(w t - phi) + sin(phi) e^{-t R/L})
 * while positive (docs/closed-forms.md), 0 after. */
static void rl_halfwave_dcm(void **state) {
  (void)state;
  solved s = solve(rl_halfwave, CUP_SCHEME_ADAPTIVE, 0, 2001, CUP_OK);
  double i[2001], re[1], im[1];
  signal_of(&s, "i(L1)", i);
  const double Vm = 10, R = 10, L = 50e-3, w = 2 * M_PI * 50, Z = hypot(R, w * L), phi = atan2(w * L, R);
  double err = 0;
  int off = 0;
  for (long j = 0; j < 2001; j++) {
    double t = 0.02 * (double)j / 2000, ref = Vm / Z * (sin(w * t - phi) + sin(phi) * exp(-t * R / L));
    if (ref <= 0 || off) { off = j > 0; ref = 0; }
    err = fmax(err, fabs(i[j] - ref));
  }
  assert_int_equal(cup_pss_multipliers(s.r, re, im), CUP_OK);
  print_message("  RL half-wave: max |i - closed form| %.3g A, multiplier %.3g\n", err, re[0]);
  assert_true(err <= 1e-9);
  assert_true(fabs(re[0]) <= 1e-6);
  assert_true(fabs(cup_pss_x0(s.r)[0]) <= 1e-12);
  done(&s);
}

/* The exact monodromy (the adaptive scheme's tangent with D = 0: flows and
 * saltation projections) against finite differences of the period map, on
 * the example circuits with D = 0 (clamp, doubler, rl-halfwave, ladder;
 * events inside the period): the same steady state, and the matrices within
 * the differences' accuracy. With D != 0 (the others) both are differences
 * (the tangent gave resonant.cir's slowest multiplier as 0.997 against the
 * differences' 0.903, a switch that D couples not being a projection), and
 * the two solves must agree all the same. Run counts printed. */
static void monodromy_against_fd(void **state) {
  (void)state;
  static const char *const names[] = {"halfwave-rc", "bridge", "bridge-lc", "series-resonant", "resonant", "clamp",
                                      "doubler", "rl-halfwave", "ladder"};
  for (size_t c = 0; c < sizeof names / sizeof *names; c++) {
    char path[512], err[CUP_ERRMSG_LEN];
    snprintf(path, sizeof path, "%s/circuits/%s.cir", CUP_EXAMPLES_DIR, names[c]);
    cup_netlist *nl = NULL;
    if (cup_netlist_load(&nl, path, NULL, 0, err)) fail_msg("%s", err);
    const cup_lcs *L = cup_netlist_lcs(nl);
    int n = cup_lcs_dim(L);
    cup_integrator_options io;
    opts_for(&io, CUP_SCHEME_ADAPTIVE, 0);
    cup_pss *r[2] = {NULL, NULL};
    cup_pss_info info[2];
    for (int k = 0; k < 2; k++) {
      cup_pss_options o;
      cup_pss_options_default(&o);
      o.jacobian = k ? CUP_PSS_JACOBIAN_FD : CUP_PSS_JACOBIAN_AUTO;
      int st = cup_pss_solve(&r[k], L, cup_netlist_input(nl), &io, NULL, &o, err);
      if (st != CUP_OK) fail_msg("%s (%s): %s %s", names[c], k ? "fd" : "exact", cup_status_name(st),
                                 r[k] ? cup_pss_x0(r[k]) ? "" : "" : err);
      cup_pss_get_info(r[k], &info[k]);
    }
    const double *J0 = cup_pss_monodromy(r[0]), *J1 = cup_pss_monodromy(r[1]);
    const double *x0 = cup_pss_x0(r[0]), *x1 = cup_pss_x0(r[1]);
    double dJ = 0, Jm = 1, dx = 0, xm = 0;
    for (int i = 0; i < n * n; i++) { dJ = fmax(dJ, fabs(J0[i] - J1[i])); Jm = fmax(Jm, fabs(J0[i])); }
    for (int i = 0; i < n; i++) { dx = fmax(dx, fabs(x0[i] - x1[i])); xm = fmax(xm, fabs(x0[i])); }
    print_message("  %-16s n = %d: exact %d Newton steps, %ld runs; fd %d steps, %ld runs; |J - J_fd| %.2e "
                  "(|J| %.2e), |mu|max %.9g vs %.9g, |x0 - x0_fd| %.2e\n", names[c], n, info[0].iterations,
                  info[0].period_runs, info[1].iterations, info[1].period_runs, dJ, Jm, info[0].max_multiplier,
                  info[1].max_multiplier, dx);
    assert_true(dJ <= 1e-4 * Jm);
    assert_true(dx <= 1e-9 * (xm + 1e-9));
    cup_pss_free(&r[0]);
    cup_pss_free(&r[1]);
    cup_netlist_free(&nl);
  }
}

/* ---- no steady state, bad input ---- */

/* An ideal LC driven at its resonance grows without bound: the multipliers
 * e^{+-j w0 T} are 1, Phi(x) - x is singular; the error says so, with the
 * residual, at once. */
static void lc_resonance(void **state) {
  (void)state;
  char cir[256];
  snprintf(cir, sizeof cir, "LC\nV1 in 0 SIN(0 1 %.17g)\nL1 in a 1m\nC1 a 0 1u\n.end\n", 1 / (2 * M_PI * sqrt(1e-9)));
  solved s = solve(cir, CUP_SCHEME_ADAPTIVE, 0, 0, CUP_ERR_NO_STEADY_STATE);
  assert_non_null(strstr(s.info.message, "multiplier is at 1"));
  assert_true(s.info.period_runs <= 4);
  done(&s);
}

/* An undamped LC off resonance has a periodic orbit, but it does not
 * attract: a warning, the orbit and the multipliers on the unit circle. */
static void lc_off_resonance(void **state) {
  (void)state;
  solved s = solve("LC\nV1 in 0 SIN(0 1 3000)\nL1 in a 1m\nC1 a 0 1u\n.end\n", CUP_SCHEME_ADAPTIVE, 0, 0,
                   CUP_WARN_UNSTABLE_ORBIT);
  assert_close(s.info.max_multiplier, 1, 1e-6);
  done(&s);
}

static void periods(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  double T;
  cup_netlist *nl = load("two\nV1 in 0 SIN(0 1 50)\nV2 b 0 SIN(0 1 150)\nR1 in c 1\nC1 c b 1u\n.end\n");
  assert_int_equal(cup_input_period(cup_netlist_input(nl), &T, err), CUP_OK);
  assert_close(T, 0.02, 1e-17);
  cup_netlist_free(&nl);
  nl = load("two\nV1 in 0 SIN(0 1 60)\nV2 b 0 PULSE(0 1 0 1u 1u 1m 2.5m)\nR1 in c 1\nC1 c b 1u\n.end\n");
  assert_int_equal(cup_input_period(cup_netlist_input(nl), &T, err), CUP_OK);
  assert_close(T, 0.05, 1e-16);                 /* 3 periods of 60 Hz, 20 of the pulse */
  cup_netlist_free(&nl);
  nl = load("none\nV1 in 0 SIN(0 1 50)\nV2 b 0 SIN(0 1 70.71067811865476)\nR1 in c 1\nC1 c b 1u\n.end\n");
  assert_int_equal(cup_input_period(cup_netlist_input(nl), &T, err), CUP_ERR_ARG);
  print_message("  %s\n", err);
  assert_non_null(strstr(err, "no common period"));
  cup_netlist_free(&nl);
  nl = load("damped\nV1 in 0 SIN(0 1 50 0 3)\nR1 in b 1\nC1 b 0 1u\n.end\n");
  assert_int_equal(cup_input_period(cup_netlist_input(nl), &T, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "decays"));
  cup_netlist_free(&nl);
}

/* A given period must be one over which every source repeats: a whole
 * number of their common period, and no source that does not repeat from
 * t = 0. Before, a source with no period of its own let any given period
 * through, and the run over [0, T) was taken for a period map (the full
 * bridge's delayed gate: CUP_ERR_LINALG at t = 0 after three runs). */
static void given_periods(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  static const struct { const char *text; double T; const char *says; } cases[] = {
      {"sine\nV1 in 0 SIN(0 1 50)\nR1 in b 1\nC1 b 0 1u\n.end\n", 0.04, NULL},
      {"sine\nV1 in 0 SIN(0 1 50)\nR1 in b 1\nC1 b 0 1u\n.end\n", 0.03, "not a whole number"},
      {"dc\nV1 in 0 5\nR1 in b 1\nC1 b 0 1u\n.end\n", 0.03, NULL},            /* constant: any period */
      {"gate\nV1 in 0 PULSE(0 1 76u jump jump 49u 100u)\nR1 in b 1\nC1 b 0 1u\n.end\n", 1e-4,
       "its delay 7.6e-05 makes [0, 0.0001) unlike later periods"},
      {"gate\nV1 in 0 PULSE(0 1 51u jump jump 49u 100u)\nR1 in b 1\nC1 b 0 1u\n.end\n", 2e-4, NULL},
      {"ramp\nV1 in 0 PWL(0 0 1m 1)\nR1 in b 1\nC1 b 0 1u\n.end\n", 1e-3, "a PWL source is not periodic"},
      {"two\nV1 in 0 SIN(0 1 50)\nV2 b 0 SIN(0 1 70.71067811865476)\nR1 in c 1\nC1 c b 1u\n.end\n", 0.02,
       "no common period"},
      {"one\nV1 in 0 PULSE(0 1 0 1u 1u 1m)\nR1 in b 1\nC1 b 0 1u\n.tran 1u 10m\n.end\n", 1e-3, "not a whole number"},
  };
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    cup_netlist *nl = load(cases[k].text);
    err[0] = '\0';
    int st = cup_input_period_fits(cup_netlist_input(nl), cases[k].T, err);
    print_message("  T = %g: %s %s\n", cases[k].T, cup_status_name(st), err);
    assert_int_equal(st, cases[k].says ? CUP_ERR_ARG : CUP_OK);
    if (cases[k].says) {
      assert_non_null(strstr(err, cases[k].says));
      assert_non_null(strstr(err, "repeat"));
    }
    cup_netlist_free(&nl);
  }
}

/* ---- the phase t0: sources that repeat only from a later time ---- */

/* The least phase from which every source repeats, against its closed form
 * per waveform: a PULSE whose pulse of the period before runs past t = 0
 * (delay + rise + width + fall - period), a delayed SIN (its delay), a PWL
 * (its last knot); a pulse ending on its period's end keeps t0 = 0. */
static void steady_phases(void **state) {
  (void)state;
  static const struct { const char *text; double T, want_T, want_t0; const char *says; } cases[] = {
      {"gate\nV1 in 0 PULSE(0 1 76u jump jump 49u 100u)\nR1 in b 1\nC1 b 0 1u\n.end\n", 0, 100e-6,
       76e-6 + 49e-6 - 100e-6, NULL},
      {"ramps\nV1 in 0 PULSE(0 1 80u 2u 3u 44u 100u)\nR1 in b 1\nC1 b 0 1u\n.end\n", 200e-6, 200e-6,
       80e-6 + 2e-6 + 44e-6 + 3e-6 - 100e-6, NULL},
      {"ends\nV1 in 0 PULSE(0 1 51u jump jump 49u 100u)\nR1 in b 1\nC1 b 0 1u\n.end\n", 0, 100e-6, 0, NULL},
      {"sin\nV1 in 0 SIN(0 1 50 3m)\nR1 in b 1\nC1 b 0 1u\n.end\n", 0, 0.02, 3e-3, NULL},
      {"soft\nV1 in 0 PWL(0 0 1m 1)\nV2 b 0 SIN(0 1 50)\nR1 in c 1\nC1 c b 1u\n.end\n", 0, 0.02, 1e-3, NULL},
      {"ramp\nV1 in 0 PWL(0 0 1m 1)\nR1 in b 1\nC1 b 0 1u\n.end\n", 0, 0, 0, "constant"},
      {"ramp\nV1 in 0 PWL(0 0 1m 1)\nR1 in b 1\nC1 b 0 1u\n.end\n", 5e-3, 5e-3, 1e-3, NULL},
      {"damped\nV1 in 0 SIN(0 1 50 0 3)\nR1 in b 1\nC1 b 0 1u\n.end\n", 0, 0, 0, "decays"},
      {"gate\nV1 in 0 PULSE(0 1 76u jump jump 49u 100u)\nR1 in b 1\nC1 b 0 1u\n.end\n", 150e-6, 0, 0,
       "not a whole number"},
  };
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    cup_netlist *nl = load(cases[k].text);
    char err[CUP_ERRMSG_LEN] = "";
    double T = -1, t0 = -1;
    int st = cup_input_steady_phase(cup_netlist_input(nl), cases[k].T, &T, &t0, err);
    print_message("  %.*s, T = %g: %s, T %.17g, t0 %.17g %s\n", (int)strcspn(cases[k].text, "\n"), cases[k].text,
                  cases[k].T, cup_status_name(st), T, t0, err);
    if (cases[k].says) {
      assert_int_equal(st, CUP_ERR_ARG);
      assert_non_null(strstr(err, cases[k].says));
    } else {
      assert_int_equal(st, CUP_OK);
      assert_close(T, cases[k].want_T, 1e-12 * cases[k].want_T);
      assert_true(fabs(t0 - cases[k].want_t0) <= 1e-12 * T);
    }
    cup_netlist_free(&nl);
  }
}

/* A netlist read from t0 on (cup_netlist_set_time_origin): its input v(t)
 * = u(t0 + t), integrals and breakpoints, against the same netlist as
 * written at the later times, for every waveform a netlist makes (a PULSE
 * with ramps delayed into the next period, one spent, a delayed SIN, a
 * PWL, a sine, a single pulse); the origin 0 again gives u back. */
static void shift_values(void **state) {
  (void)state;
  static const char *text = "shift\nV1 a 0 PULSE(0 1 76u 1u 2u 47u 100u)\nV2 b 0 PULSE(-1 2 1u 3u 1u 40u 100u)\n"
                            "V3 c 0 SIN(0.5 1 10k 30u)\nV4 d 0 PWL(0 0 20u 1 25u 3)\nV5 e 0 SIN(0 2 20k)\n"
                            "V6 f 0 PULSE(0 1 5u 1u 1u 30u)\nR1 a x 1\nR2 b x 1\nR3 c x 1\nR4 d x 1\nR5 e x 1\n"
                            "R6 f x 1\nC1 x 0 1u\n.tran 1u 20u\n.end\n";   /* V6: PER = TSTOP < its pulse: one pulse */
  cup_netlist *nl = load(text), *as_written = load(text);
  const cup_input *u = cup_netlist_input(as_written);
  char err[CUP_ERRMSG_LEN];
  double T = 0, t0 = 0;
  assert_int_equal(cup_input_steady_phase(u, 0, &T, &t0, err), CUP_OK);
  assert_close(T, 100e-6, 1e-18);
  assert_close(t0, 37e-6, 1e-18);               /* the single pulse's end: 5u + 1u + 30u + 1u */
  for (int pass = 0; pass < 3; pass++) {
    double s0 = pass == 0 ? t0 : pass == 1 ? 250e-6 : 0;   /* the phase, a later one, back to 0 */
    assert_int_equal(cup_netlist_set_time_origin(nl, s0, err), CUP_OK);
    const cup_input *v = cup_netlist_input(nl);
    double a[6], b[6], ia[6], ib[6], worst = 0;
    for (int j = 0; j <= 1000; j++) {
      double t = j * 0.7e-6 + 0.013e-6;
      assert_int_equal(cup_input_eval(v, t, a), CUP_OK);
      assert_int_equal(cup_input_eval(u, s0 + t, b), CUP_OK);
      assert_int_equal(cup_input_integral(v, t, t + 0.9e-6, ia), CUP_OK);
      assert_int_equal(cup_input_integral(u, s0 + t, s0 + t + 0.9e-6, ib), CUP_OK);
      for (int c = 0; c < 6; c++) worst = fmax(worst, fmax(fabs(a[c] - b[c]), fabs(ia[c] - ib[c]) / 0.9e-6));
      double bv = cup_input_next_break(v, t), bu = cup_input_next_break(u, s0 + t);
      if (isfinite(bu) || isfinite(bv)) assert_true(fabs(bv + s0 - bu) <= 1e-15);
    }
    print_message("  t0 = %g: |v(t) - u(t0 + t)| and its integrals' mean: %.3g at most\n", s0, worst);
    assert_true(pass < 2 ? worst <= 1e-11 : worst == 0);
  }
  cup_netlist_free(&nl);
  cup_netlist_free(&as_written);
}

/* A damped SIN read from an origin past its delay: v(t) = u(t0 + t), its
 * amplitude decayed by exp(-theta (t0 - td)) (no steady phase exists for it,
 * but cup_netlist_set_time_origin takes any t0 >= 0). */
static void shift_damped(void **state) {
  (void)state;
  static const char *text = "damped\nV1 a 0 SIN(0.5 2 10k 30u 2e4 45)\nR1 a x 1\nC1 x 0 1u\n.tran 1u 20u\n.end\n";
  cup_netlist *nl = load(text), *as_written = load(text);
  const cup_input *u = cup_netlist_input(as_written);
  char err[CUP_ERRMSG_LEN];
  const double origins[] = {0, 10e-6, 30e-6, 73.3e-6};
  for (int pass = 0; pass < 4; pass++) {
    double s0 = origins[pass], worst = 0, a, b, ia, ib;
    assert_int_equal(cup_netlist_set_time_origin(nl, s0, err), CUP_OK);
    const cup_input *v = cup_netlist_input(nl);
    for (int j = 0; j <= 1000; j++) {
      double t = j * 0.7e-6 + 0.013e-6;
      assert_int_equal(cup_input_eval(v, t, &a), CUP_OK);
      assert_int_equal(cup_input_eval(u, s0 + t, &b), CUP_OK);
      assert_int_equal(cup_input_integral(v, t, t + 0.9e-6, &ia), CUP_OK);
      assert_int_equal(cup_input_integral(u, s0 + t, s0 + t + 0.9e-6, &ib), CUP_OK);
      worst = fmax(worst, fmax(fabs(a - b), fabs(ia - ib) / 0.9e-6));
    }
    print_message("  damped SIN, t0 = %g: |v(t) - u(t0 + t)| and its integrals' mean: %.3g at most\n", s0, worst);
    assert_true(worst <= 1e-11);
  }
  cup_netlist_free(&nl);
  cup_netlist_free(&as_written);
}

/* An RC under a pulse train whose pulse runs past its period's end (the
 * full bridge's VG3): the steady state from the phase t0 = 25 us, where
 * the pulse ends, is its maximum (1 - e^{-Ton/RC}) / (1 - e^{-T/RC}), the
 * trajectory starts at t0 and its v(out) is the closed form at each
 * sample. Before, the solve refused the source (CUP_ERR_ARG). */
static void rc_delayed_pulse(void **state) {
  (void)state;
  const double T = 100e-6, Ton = 49e-6, tau = 50e-6, t0 = 25e-6;
  solved s = solve("RC\nV1 in 0 PULSE(0 1 76u jump jump 49u 100u)\nR1 in out 1\nC1 out 0 50u\n.end\n",
                   CUP_SCHEME_ADAPTIVE, 0, 101, CUP_OK);
  assert_close(s.info.period, T, 1e-18);
  assert_close(s.info.t0, t0, 1e-18);
  double top = (1 - exp(-Ton / tau)) / (1 - exp(-T / tau));
  print_message("  x0 %.15g, closed form %.15g\n", cup_pss_x0(s.r)[0], top);
  assert_close(cup_pss_x0(s.r)[0], top, 1e-10);
  double t[101], x[101];
  assert_int_equal(cup_pss_trajectory(s.r, t, x, NULL), CUP_OK);
  assert_close(t[0], t0, 1e-18);
  assert_close(t[100], t0 + T, 1e-18);
  for (int j = 0; j <= 100; j++) {              /* off on [25, 76) us, on on [76, 125) us */
    double off = fmin(t[j], 76e-6) - t0, v = top * exp(-off / tau);
    if (t[j] > 76e-6) v = 1 + (v - 1) * exp(-(t[j] - 76e-6) / tau);
    assert_close(x[j], v, 1e-9);
  }
  done(&s);
}

/* ---- measurements ---- */

static void measure_closed_forms(void **state) {
  (void)state;
  enum { N = 257, H = 4097 };
  double v[N], amp[6], ph[6], w[H];
  cup_measure m;
  char err[CUP_ERRMSG_LEN];
  for (int j = 0; j < N; j++) {
    double a = 2 * M_PI * j / (N - 1);
    v[j] = 3 + 2 * cos(a + 0.3) + 0.5 * sin(3 * a);
  }
  assert_int_equal(cup_measure_period(v, N, 5, &m, amp, ph, err), CUP_OK);
  assert_close(m.avg, 3, 1e-14);
  assert_close(m.rms, sqrt(9 + 2 + 0.125), 1e-14);
  assert_close(m.thd, 0.25, 1e-14);
  assert_close(amp[1], 2, 1e-14);
  assert_close(ph[1], 0.3, 1e-14);
  assert_close(amp[3], 0.5, 1e-14);
  assert_close(ph[3], -M_PI / 2, 1e-13);
  /* a half-wave rectified sine: kinks, O(h^2) */
  for (int j = 0; j < H; j++) w[j] = fmax(0, sin(2 * M_PI * j / (H - 1)));
  double a10[11];
  assert_int_equal(cup_measure_period(w, H, 10, &m, a10, NULL, err), CUP_OK);
  double h2 = 0;
  for (int k = 1; k <= 5; k++) h2 += pow(2 / (M_PI * (4.0 * k * k - 1)), 2);
  print_message("  half-wave sine: avg %.12g (1/pi %.12g), rms %.12g (1/2), thd %.12g (%.12g)\n", m.avg, 1 / M_PI,
                m.rms, m.thd, sqrt(h2) / 0.5);
  assert_close(m.avg, 1 / M_PI, 1e-7);
  assert_close(m.rms, 0.5, 1e-7);
  assert_close(m.max, 1, 1e-6);
  assert_close(m.min, 0, 0);
  assert_close(m.thd, sqrt(h2) / 0.5, 1e-6);
  assert_int_equal(cup_measure_period(v, N, 128, &m, NULL, NULL, err), CUP_ERR_ARG);
}

/* The ideal buck through the library alone: V1 a 0 PULSE (Vin for D Ts,
 * ideal edges) through the ideal diode D1 a -> sw, which is the switch and
 * the freewheeling path at once (V1 = 0: D1 carries i(L1) at v(sw) = 0, and
 * in DCM blocks inside the period, an event, v(sw) then v(out)). Lossless:
 * the efficiency P(RL) / -P(V1) is 1; the inductor's average voltage is 0,
 * so the average v(sw) is the average v(out); in CCM it is D Vin. v(sw),
 * i(V1) and the input power jump at the PULSE's edges and the diode's
 * turn-off: cup_measure_period_jumps with cup_pss_jumps' times measures
 * them to rounding, cup_measure_period (the samples' trapezoid rule) only
 * to O(h) (printed beside). */
typedef struct { double avg_sw, avg_out, eff; } buck_figs;

static buck_figs buck_measure(solved *s, const double *jt, long nj, int with_jumps) {
  long S = s->info.samples;
  double *sw = calloc((size_t)S, sizeof *sw), *out = calloc((size_t)S, sizeof *out);
  double *pin = calloc((size_t)S, sizeof *pin), *pout = calloc((size_t)S, sizeof *pout);
  double *w = calloc((size_t)S, sizeof *w);
  signal_of(s, "v(sw)", sw);
  signal_of(s, "v(out)", out);
  signal_of(s, "v(a)", pin);
  signal_of(s, "i(V1)", w);
  for (long j = 0; j < S; j++) pin[j] *= w[j];
  signal_of(s, "i(RL)", w);
  for (long j = 0; j < S; j++) pout[j] = out[j] * w[j];
  double *sig[4] = {sw, out, pin, pout}, avg[4];
  char err[CUP_ERRMSG_LEN];
  for (int k = 0; k < 4; k++) {
    cup_measure m;
    int st = with_jumps ? cup_measure_period_jumps(sig[k], S, jt, nj, s->info.t0, s->info.period, 0, &m, NULL, NULL,
                                                   err)
                        : cup_measure_period(sig[k], S, 0, &m, NULL, NULL, err);
    if (st) fail_msg("%s", err);
    avg[k] = m.avg;
  }
  free(sw); free(out); free(pin); free(pout); free(w);
  return (buck_figs){avg[0], avg[1], avg[3] / -avg[2]};
}

static void buck_library(const char *what, double D, double L, double R, int ccm) {
  const double Vin = 12, Ts = 10e-6;
  char cir[512];
  snprintf(cir, sizeof cir, "ideal buck\nV1 a 0 PULSE(0 %.17g 0 jump jump %.17g %.17g)\nD1 a sw\nL1 sw out %.17g\n"
           "C1 out 0 10u\nRL out 0 %.17g\n.end\n", Vin, D * Ts, Ts, L, R);
  solved s = solve(cir, CUP_SCHEME_ADAPTIVE, 0, 2001, CUP_OK);
  long nj = cup_pss_jumps(s.r, NULL);
  double jt[64];
  assert_true(nj >= 2 && nj <= 64);
  assert_int_equal(s.info.jumps, nj);
  assert_int_equal(cup_pss_jumps(s.r, jt), nj);
  for (long q = 1; q < nj; q++) assert_true(jt[q] > s.info.t0 && jt[q] < s.info.t0 + Ts);
  assert_true(jt[0] == s.info.t0);               /* the PULSE's rising edge at t0 (and t0 + Ts) */
  assert_true(fabs(jt[1] - D * Ts) <= 1e-20);     /* its falling edge */
  buck_figs b = buck_measure(&s, NULL, 0, 0), j = buck_measure(&s, jt, nj, 1);
  double M = 2 / (1 + sqrt(1 + 8 * L / (R * D * D * Ts)));   /* DCM's conversion ratio, within the ripple */
  print_message("  %s: %ld jump times (the second %.6g us); avg v(sw) %.12f -> %.12f (%s %.12f), avg v(out) %.12f, "
                "efficiency %.9f -> 1 %+.3g\n", what, nj, jt[1] * 1e6, b.avg_sw, j.avg_sw,
                ccm ? "D Vin" : "DCM's M Vin", ccm ? D * Vin : M * Vin, j.avg_out, b.eff, j.eff - 1);
  assert_close(j.eff, 1, 1e-7);
  assert_true(fabs(b.eff - 1) > 1e-4);           /* the samples alone: O(h), h = Ts / 2000 */
  assert_close(j.avg_sw, j.avg_out, 1e-7 * Vin);  /* the inductor's average voltage is 0 */
  assert_true(fabs(b.avg_sw - b.avg_out) > 1e-5 * Vin);
  if (ccm) assert_close(j.avg_sw, D * Vin, 1e-9 * Vin);
  else assert_close(j.avg_out, M * Vin, 2e-2 * Vin);
  cup_measure m;
  char err[CUP_ERRMSG_LEN];
  double rev[2] = {jt[1], jt[0]}, off[1] = {s.info.t0 + 2 * Ts};
  double v[3] = {0, 1, 0};
  assert_int_equal(cup_measure_period_jumps(v, 3, rev, 2, 0, Ts, 0, &m, NULL, NULL, err),
                   CUP_ERR_ARG);
  assert_int_equal(cup_measure_period_jumps(v, 3, off, 1, 0, Ts, 0, &m, NULL, NULL, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "jump time 0"));
  done(&s);
}

static void buck_library_ccm(void **state) {
  (void)state;
  buck_library("CCM D = 0.3137 (edge between samples)", 0.3137, 100e-6, 5, 1);
}

static void buck_library_dcm(void **state) {
  (void)state;
  buck_library("DCM D = 0.3 (D1 blocks inside the period)", 0.3, 10e-6, 20, 0);
}

/* cup_pss_jumps gives none both when there are none and when there are
 * more than 4 a sample + 64; the info's jumps tells the two apart (-1).
 * The DCM buck over 10 of its periods at 2001 samples: each period's jump
 * times ten times over (its steady state repeats them: the edges at 0
 * and D Ts, D1's turn-off), each once (D1's turn-on at an edge is the
 * edge's time: it was counted twice); over 30 periods at 3 samples more
 * than 76, so none given and jumps = -1. */
static void jumps_overflow_is_said(void **state) {
  (void)state;
  const double Ts = 10e-6;
  const char *buck = "ideal buck\nV1 a 0 PULSE(0 12 0 jump jump 3u 10u)\nD1 a sw\nL1 sw out 10u\n"
                     "C1 out 0 10u\nRL out 0 20\n.end\n";
  solved one = solve(buck, CUP_SCHEME_ADAPTIVE, 0, 2001, CUP_OK);
  solved ten = solve_over(buck, CUP_SCHEME_ADAPTIVE, 0, 2001, 10 * Ts, CUP_OK);
  solved few = solve_over(buck, CUP_SCHEME_ADAPTIVE, 0, 3, 30 * Ts, CUP_OK);
  print_message("  jump times: one period %ld, ten periods %ld, 30 periods at 3 samples %ld (cup_pss_jumps %ld)\n",
                one.info.jumps, ten.info.jumps, few.info.jumps, cup_pss_jumps(few.r, NULL));
  assert_int_equal(one.info.jumps, 3);           /* the PULSE's two edges and D1's turn-off */
  assert_int_equal(cup_pss_jumps(one.r, NULL), one.info.jumps);
  assert_int_equal(ten.info.jumps, 10 * one.info.jumps);
  double jt[64];
  assert_int_equal(cup_pss_jumps(ten.r, jt), ten.info.jumps);
  for (long q = 1; q < ten.info.jumps; q++) assert_true(jt[q] > jt[q - 1]);
  assert_int_equal(few.info.jumps, -1);
  assert_int_equal(cup_pss_jumps(few.r, NULL), 0);
  done(&one);
  done(&ten);
  done(&few);
}

/* A wall-time limit is the solve's, not each period run's: Newton's
 * finite-difference monodromy on an 8-state RC ladder takes 9 period runs
 * a step, each well inside the limit; a fifth of the unlimited solve's
 * time stops it with CUP_ERR_TIME_LIMIT, before it has run as many
 * periods (it returned CUP_OK after every run when each run had the
 * limit afresh). */
static void time_limit_is_the_solves(void **state) {
  (void)state;
  const char *ladder = "RC ladder\nV1 in 0 SIN(0 1 50)\nR1 in 1 1k\nC1 1 0 1u\nR2 1 2 1k\nC2 2 0 1u\n"
                       "R3 2 3 1k\nC3 3 0 1u\nR4 3 4 1k\nC4 4 0 1u\nR5 4 5 1k\nC5 5 0 1u\nR6 5 6 1k\nC6 6 0 1u\n"
                       "R7 6 7 1k\nC7 7 0 1u\nR8 7 8 1k\nC8 8 0 1u\n.end\n";
  cup_netlist *nl = load(ladder);
  const cup_lcs *L = cup_netlist_lcs(nl);
  assert_int_equal(cup_lcs_dim(L), 8);
  cup_integrator_options io;
  opts_for(&io, CUP_SCHEME_THETA, 20000);
  cup_pss_options o;
  cup_pss_options_default(&o);
  char err[CUP_ERRMSG_LEN] = "";
  cup_pss *r = NULL;
  cup_pss_info free_run, limited;
  assert_int_equal(cup_pss_solve(&r, L, cup_netlist_input(nl), &io, NULL, &o, err), CUP_OK);
  cup_pss_get_info(r, &free_run);
  cup_pss_free(&r);
  assert_true(free_run.period_runs >= 10);
  io.max_wall_seconds = 0.2 * free_run.seconds;
  int st = cup_pss_solve(&r, L, cup_netlist_input(nl), &io, NULL, &o, err);
  assert_non_null(r);
  cup_pss_get_info(r, &limited);
  print_message("  unlimited: %ld period runs in %.3g ms; limit %.3g ms: %s after %ld runs, %.3g ms: \"%s\"\n",
                free_run.period_runs, 1e3 * free_run.seconds, 1e3 * io.max_wall_seconds, cup_status_name(st),
                limited.period_runs, 1e3 * limited.seconds, limited.message);
  assert_int_equal(st, CUP_ERR_TIME_LIMIT);
  assert_true(limited.period_runs < free_run.period_runs);
  cup_pss_free(&r);
  cup_netlist_free(&nl);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(rc_sine),
    cmocka_unit_test(rlc_pulse),
    cmocka_unit_test(halfwave_rc_adaptive),
    cmocka_unit_test(halfwave_rc_theta),
    cmocka_unit_test(halfwave_slow),
    cmocka_unit_test(bridge_adaptive),
    cmocka_unit_test(rl_halfwave_dcm),
    cmocka_unit_test(monodromy_against_fd),
    cmocka_unit_test(lc_resonance),
    cmocka_unit_test(lc_off_resonance),
    cmocka_unit_test(periods),
    cmocka_unit_test(given_periods),
    cmocka_unit_test(steady_phases),
    cmocka_unit_test(shift_values),
    cmocka_unit_test(shift_damped),
    cmocka_unit_test(rc_delayed_pulse),
    cmocka_unit_test(measure_closed_forms),
    cmocka_unit_test(buck_library_ccm),
    cmocka_unit_test(buck_library_dcm),
    cmocka_unit_test(jumps_overflow_is_said),
    cmocka_unit_test(time_limit_is_the_solves),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
