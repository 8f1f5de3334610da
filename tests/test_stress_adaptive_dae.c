/* The adaptive scheme on an LCS with D != 0 under stress: the full-wave
 * bridge of examples/circuits/bridge.cir (a floating source V sin(w t)
 * with Rs into four ideal diodes and C || RL; x = v(C), rows D1..D4:
 * D1 fixed by the others' currents, a skew coupling in D) built here from
 * its matrices, against the exact piecewise solution of
 * C v' = max(0, (|u| - v) / Rs) - v / RL (tests/circuit_ref.h):
 *   stiff: Rs C = 10 ns against a 20 ms period (the conducting mode's
 *     eigenvalue -1e8 / s);
 *   ill-conditioned: Rs = 0.1 mOhm into RL = 1 MOhm (D's entries 1e-4 and
 *     1, N's Y rows 1e4 apart, the conducting mode's time constant 0.1 ns);
 *   scaled: the state in units of 1e-6 and 1e6 (x = s v: B, C, P as s B,
 *     C / s, P / s^2: the same trajectory, scaled, to rounding) and the
 *     rows by 1e-3 and 1e3 (w = r w: C, D, G, B as r C, r^2 D, r G, r B,
 *     zeta / r: within tol of it);
 *   a callback input that returns NaN from t = 25 ms: CUP_ERR_CALLBACK at
 *     the step that reaches it, every output before it delivered and right. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>
#include "stress_util.h"
#include "circuit_ref.h"

#define T_END 0.06
#define SAMPLES 601

typedef struct { tcsc A, B, C, D, G; cup_lcs *L; } bridge_lcs;

/* The bridge with source resistance Rs, C || RL, state scale s, row scale r. */
static void bridge_build(bridge_lcs *b, double Rs, double C, double RL, double s, double r) {
  double A[1] = {-1 / (RL * C)}, B[4] = {0, 0, s * r / C, s * r / C}, Cm[4] = {0, 0, r / s, r / s};
  double Dm[16] = {0, -1, 1, 1, 1, Rs, 0, -Rs, -1, 0, 0, 0, -1, -Rs, 0, Rs};   /* row-major */
  double G[4] = {0, r, 0, -r}, P[1] = {C / (s * s)};
  for (int k = 0; k < 16; k++) Dm[k] *= r * r;
  memset(b, 0, sizeof *b);
  cup_lcs_desc d;
  memset(&d, 0, sizeof d);
  d.n = 1; d.m = 4; d.p = 1;
  tcsc_from_dense(&b->A, A, 1, 1); d.A = b->A.view;
  tcsc_from_dense(&b->B, B, 1, 4); d.B = b->B.view;
  tcsc_from_dense(&b->C, Cm, 4, 1); d.C = b->C.view;
  tcsc_from_dense(&b->D, Dm, 4, 4); d.D = b->D.view;
  tcsc_from_dense(&b->G, G, 4, 1); d.G = b->G.view;
  d.P = (cup_metric){CUP_METRIC_DIAGONAL, P, {0}, 0};
  char msg[CUP_ERRMSG_LEN];
  if (cup_lcs_create(&b->L, &d, msg)) fail_msg("bridge: %s", msg);
}

static void bridge_free(bridge_lcs *b) {
  cup_lcs_free(&b->L);
  tcsc_free(&b->A); tcsc_free(&b->B); tcsc_free(&b->C); tcsc_free(&b->D); tcsc_free(&b->G);
}

/* The exact solution: conducting (C v' = (|u| - v) / Rs - v / RL) while the
 * current (|u| - v) / Rs >= 0, else C v' = -v / RL until |u| reaches v. */
static void bridge_ref(cr_traj *tr, double V, double Rs, double C, double RL, double hsub) {
  cr_circuit *c = calloc(1, sizeof *c);
  *c = (cr_circuit){.n = 1, .nmodes = 2, .w = 2 * M_PI * 50, .piece = cr_abs_sine, .par = {V}, .hsub = hsub};
  double on[4] = {-1 / (Rs * C) - 1 / (RL * C), 1 / (Rs * C), 0, 0}, off[4] = {-1 / (RL * C), 0, 0, 0};
  memcpy(c->mode[0].f[0], on, sizeof on);
  c->mode[0].ng = 1;
  memcpy(c->mode[0].g[0], (double[]){-1, 1, 0, 0}, 4 * sizeof(double));
  memcpy(c->mode[1].f[0], off, sizeof off);
  c->mode[1].ng = 1;
  memcpy(c->mode[1].g[0], (double[]){1, -1, 0, 0}, 4 * sizeof(double));
  assert_int_equal(cr_solve(c, (double[]){0}, T_END, tr), 0);
}

typedef struct { const cr_traj *ref; double s, err, xmax; long n; double x[SAMPLES]; } sink_ctx;

static int sink(long k, double t, const double *x, void *vp) {
  (void)k;
  sink_ctx *c = vp;
  double v;
  cr_eval(c->ref, t, &v);
  c->err = fmax(c->err, fabs(x[0] / c->s - v));
  c->xmax = fmax(c->xmax, fabs(v));
  if (c->n < SAMPLES) c->x[c->n++] = x[0];
  return 0;
}

static int run(const cup_lcs *L, const cup_input *u, double tol_abs, double tol_rel, sink_ctx *c, cup_run_info *info) {
  cup_integrator_options o;
  adaptive_options(&o, T_END, tol_abs, tol_rel, SAMPLES);
  cup_integrator *I = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_integrator_create(&I, L, u, &o, msg)) fail_msg("create: %s", msg);
  int st = cup_integrator_run(I, (double[]){0}, sink, c, info);
  cup_integrator_free(&I);
  return st;
}

/* At tol 1e-4, 1e-7, 1e-10 the error is within tol (1 + max |v|) and the
 * estimate within 10x of it. */
static void check_tols(const char *name, double Rs, double C, double RL, double hsub) {
  bridge_lcs b;
  bridge_build(&b, Rs, C, RL, 1, 1);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 10, .frequency = 50};
  cup_input *u = input_terms(1, &s);
  cr_traj ref;
  bridge_ref(&ref, 10, Rs, C, RL, hsub);
  for (double tol = 1e-4; tol >= 0.99e-10; tol *= 1e-3) {
    sink_ctx c = {&ref, 1, 0, 0, 0, {0}};
    cup_run_info info;
    int st = run(b.L, u, tol, tol, &c, &info);
    double target = tol * (1 + c.xmax), floor_ = 1e-12 * (1 + c.xmax);
    print_message("%-28s tol %.0e: %s, error %.3e (%.2f tol), estimate %.3e, %ld steps, %ld events\n", name, tol,
                  cup_status_name(st), c.err, c.err / target, info.err_est, info.step, info.events);
    assert_int_equal(st, CUP_OK);
    assert_true(c.err <= target);
    if (c.err > floor_) assert_true(info.err_est <= 10 * c.err && info.err_est >= 0.1 * c.err);
  }
  cr_free(&ref);
  free((void *)ref.c);
  cup_input_free(&u);
  bridge_free(&b);
}

static void test_stiff_bridge(void **state) {
  (void)state;
  check_tols("stiff bridge (Rs C = 10 ns)", 1e-3, 10e-6, 100, 2e-5);
}

static void test_illcond_bridge(void **state) {
  (void)state;
  check_tols("bridge Rs 0.1 mOhm, RL 1 MOhm", 1e-4, 1e-6, 1e6, 2e-5);
}

/* The state's unit and the rows' scale change nothing but the scale: x and
 * the estimate in units of s, to 1e-10 of the scale (the tolerance's part
 * in absolute units scaled too). */
static void test_scaled_bridge(void **state) {
  (void)state;
  cup_wave w = {.kind = CUP_WAVE_SINE, .amplitude = 10, .frequency = 50};
  cup_input *u = input_terms(1, &w);
  cr_traj ref;
  bridge_ref(&ref, 10, 1, 100e-6, 1000, 2e-5);
  static sink_ctx base;
  base = (sink_ctx){&ref, 1, 0, 0, 0, {0}};
  cup_run_info info;
  bridge_lcs b;
  bridge_build(&b, 1, 100e-6, 1000, 1, 1);
  assert_int_equal(run(b.L, u, 1e-9, 1e-9, &base, &info), CUP_OK);
  double est0 = info.err_est;
  bridge_free(&b);
  const double scales[4][2] = {{1e-6, 1}, {1e6, 1}, {1, 1e-3}, {1, 1e3}};
  for (int k = 0; k < 4; k++) {
    double s = scales[k][0], r = scales[k][1];
    bridge_build(&b, 1, 100e-6, 1000, s, r);
    static sink_ctx c;
    c = (sink_ctx){&ref, s, 0, 0, 0, {0}};
    int st = run(b.L, u, 1e-9 * s, 1e-9, &c, &info);
    if (st != CUP_OK) fail_msg("state x %g, rows x %g: %s: %s", s, r, cup_status_name(st), info.message);
    double worst = 0;
    for (long j = 0; j < SAMPLES; j++) worst = fmax(worst, fabs(c.x[j] / s - base.x[j]));
    print_message("bridge, state x %g, rows x %g: error %.3e, estimate %.3e (unscaled %.3e), max |x / s - x_1| %.3e\n",
                  s, r, c.err, info.err_est / s, est0, worst);
    assert_int_equal(c.n, SAMPLES);
    assert_true(c.err <= 1e-9 * (1 + c.xmax));
    /* the state's unit changes only rounding; the rows' scale may move an
     * event's switch within its tolerance (the error is tol's either way) */
    assert_true(worst <= (r == 1 ? 1e-12 : 1e-9) * (1 + c.xmax));
    assert_true(info.err_est / s <= 10 * c.err && info.err_est / s >= 0.1 * c.err);
    bridge_free(&b);
  }
  cr_free(&ref);
  free((void *)ref.c);
  cup_input_free(&u);
}

/* 10 sin(2 pi 50 t), NaN from t = 25 ms on. */
static int nan_sine(double t, double *u, void *ctx) {
  (void)ctx;
  u[0] = t < 0.025 ? 10 * sin(2 * M_PI * 50 * t) : NAN;
  return 0;
}

static void test_nan_input(void **state) {
  (void)state;
  bridge_lcs b;
  bridge_build(&b, 1, 100e-6, 1000, 1, 1);
  cup_input *u = NULL;
  assert_int_equal(cup_input_create(&u, 1, NULL), CUP_OK);
  assert_int_equal(cup_input_set_callback(u, nan_sine, NULL, 1e-12, 1e-10), CUP_OK);
  cr_traj ref;
  bridge_ref(&ref, 10, 1, 100e-6, 1000, 2e-5);
  static sink_ctx c;
  c = (sink_ctx){&ref, 1, 0, 0, 0, {0}};
  cup_run_info info;
  int st = run(b.L, u, 1e-8, 1e-8, &c, &info);
  print_message("bridge, a NaN input from 25 ms: %s: %s; %ld samples, error %.3e before it\n", cup_status_name(st),
                info.message, c.n, c.err);
  /* it stops at the step whose interpolation points first reach 25 ms,
   * having delivered every sample up to that step's start */
  assert_int_equal(st, CUP_ERR_CALLBACK);
  assert_true(strstr(info.message, "NaN") != NULL);
  assert_true(info.t <= 0.025 && info.t > 0.015);
  assert_int_equal(c.n, (long)floor(info.t / 1e-4 + 1e-9) + 1);
  assert_true(c.err <= 1e-8 * (1 + c.xmax));
  cr_free(&ref);
  free((void *)ref.c);
  cup_input_free(&u);
  bridge_free(&b);
}

/* Events that accumulate with D != 0: a diode behind Rs = 1e-4 (D = Rs)
 * lets a zigzag input (slopes +-10) whose teeth shrink geometrically to
 * t = 1/2 push x up against a drift x' = zeta - 1, conducting on each rise
 * and blocking on each fall until the teeth are shorter than Rs (the D = 0
 * case is test_adaptive's test_zeno); with max_event_rate 200 that is an
 * accumulation: CUP_WARN_ZENO, catching-up steps on the active set of each
 * step's start, then x settles where w = x + Rs zeta = 0 with zeta = 1:
 * x(1) = -Rs (to e^-5000: the time constant is Rs). */
static void test_zeno_with_D(void **state) {
  (void)state;
  double Rs = 1e-4, B[1] = {1}, C[1] = {1}, D[1] = {Rs}, G[2] = {-1, 0}, E[2] = {0, 1};
  tcsc tB, tC, tD, tG, tE;
  tcsc_from_dense(&tB, B, 1, 1);
  tcsc_from_dense(&tC, C, 1, 1);
  tcsc_from_dense(&tD, D, 1, 1);
  tcsc_from_dense(&tG, G, 1, 2);
  tcsc_from_dense(&tE, E, 1, 2);
  cup_lcs_desc desc;
  memset(&desc, 0, sizeof desc);
  desc.n = 1; desc.m = 1; desc.p = 2;
  desc.B = tB.view; desc.C = tC.view; desc.D = tD.view; desc.G = tG.view; desc.E = tE.view;
  cup_lcs *L = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_lcs_create(&L, &desc, msg)) fail_msg("lcs: %s", msg);
  cup_input *u = zigzag_input(0.5, 5);             /* up at slope 10, down at -10 */
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = 1;
  o.tol_abs = o.tol_rel = 1e-8;
  o.max_event_rate = 200;                       /* 64 switches within 0.32: an accumulation */
  o.output = CUP_OUTPUT_FINAL;
  cup_integrator *I = NULL;
  if (cup_integrator_create(&I, L, u, &o, msg)) fail_msg("create: %s", msg);
  cup_run_info info;
  int st = cup_integrator_run(I, (double[]){0}, NULL, NULL, &info);
  double xT = cup_integrator_state(I)[0];
  print_message("zigzag to t* = 1/2 behind Rs: %s: %s; %ld events, %ld steps, x(1) = %.12g\n", cup_status_name(st),
                info.message, info.events, info.step, xT);
  assert_int_equal(st, CUP_WARN_ZENO);
  assert_true(info.t == 1);
  assert_true(fabs(xT + Rs) <= 1e-9);
  cup_integrator_free(&I);
  cup_lcs_free(&L);
  cup_input_free(&u);
  tcsc_free(&tB); tcsc_free(&tC); tcsc_free(&tD); tcsc_free(&tG); tcsc_free(&tE);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_stiff_bridge),
    cmocka_unit_test(test_illcond_bridge),
    cmocka_unit_test(test_scaled_bridge),
    cmocka_unit_test(test_nan_input),
    cmocka_unit_test(test_zeno_with_D),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
