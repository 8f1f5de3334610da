/* Stress: NaN and Inf never pass silently. Each case here is one the other
 * tests do not already cover (their list is in the stress report; scene
 * files are in tests/scenes/bad): NaN/Inf in every matrix of an LCS; user
 * callbacks (input u(t) under each scheme and moving K, perturbation f)
 * that start returning NaN/Inf mid-run stop the run with CUP_ERR_CALLBACK at
 * the right step and time, after delivering every state before it; overflow
 * during a run stops it with CUP_ERR_DIVERGED; the projector never reports a
 * non-finite answer as converged or feasible; options and overrides. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <float.h>
#include <cmocka.h>
#include "stress_util.h"

static void assert_contains(const char *msg, const char *want) {
  if (!strstr(msg, want)) fail_msg("message\n  %s\ndoes not contain\n  %s", msg, want);
}

/* ---- the LCS refuses NaN/Inf in every matrix, naming it ------------------------- */

static void test_lcs_matrices(void **state) {
  (void)state;
  const char *names[] = {"A", "B", "C", "E", "G", "F", "P", "P"};
  for (int which = 0; which < 8; which++)
    for (int inf = 0; inf < 2; inf++) {
      double A[4] = {-1, 0, 0, -2}, B[2] = {1, 0}, C[2] = {1, 0}, E[2] = {0, 1}, G[1] = {1};
      double F[1] = {0}, Pd[2] = {1, 1}, Pf[4] = {2, 0.5, 0.5, 1};
      double bad = inf ? -INFINITY : NAN;
      double *slot[] = {&A[3], &B[0], &C[0], &E[1], &G[0], &F[0], &Pd[1], &Pf[3]};
      /* P B = C^T holds for the finite data (P = I, B = C^T); the dense P
       * case is given without B */
      *slot[which] = bad;
      lcs_built b;
      char msg[CUP_ERRMSG_LEN] = "";
      int st = build_lcs(&b, 2, 1, 1, A, which == 7 ? NULL : B, C, E, F, G,
                         which == 7 ? NULL : Pd, which == 7 ? Pf : NULL, msg);
      if (st != CUP_ERR_NONFINITE)
        fail_msg("%s with %s: status %s (%s)", names[which], inf ? "-inf" : "nan", cup_status_name(st), msg);
      assert_null(b.L);
      assert_contains(msg, names[which]);
      assert_contains(msg, inf ? "inf" : "nan");
      unbuild_lcs(&b);
    }
}

/* ---- callbacks that turn non-finite mid-run ---------------------------------------- */

typedef struct { int mode; double t_bad; long calls; } cb_ctx;   /* mode 0: NaN, 1: +Inf, 2: return 1 */

static int bad_input(double t, double *u, void *vp) {
  cb_ctx *c = vp;
  c->calls++;
  u[0] = sin(2 * M_PI * t);
  if (t > c->t_bad) {
    if (c->mode == 2) return 1;
    u[0] = c->mode == 0 ? NAN : INFINITY;
  }
  return 0;
}

static int bad_rhs(double t, const double *x, double *f, void *vp) {
  cb_ctx *c = vp;
  c->calls++;
  f[0] = -x[0];
  f[1] = 0.5;
  if (t > c->t_bad) {
    if (c->mode == 2) return 1;
    f[1] = c->mode == 0 ? NAN : -INFINITY;
  }
  return 0;
}

typedef struct { long count, last_k; int all_finite; } seen;
static int seen_sink(long k, double t, const double *x, void *vp) {
  seen *s = vp;
  s->count++;
  s->last_k = k;
  if (!isfinite(t) || !isfinite(x[0]) || !isfinite(x[1])) s->all_finite = 0;
  return 0;
}

/* Run a 2-state system with K = {x1 >= -0.2 + g u} for n = 100, T = 1; the
 * callback goes bad for t > 0.5, so the step [0.5, 0.51] (step 51) is the
 * first that evaluates it there: the run must stop at step 51, t = 0.51. */
static void expect_callback_stop(const char *what, int scheme, int moving, int via_rhs, int mode) {
  double A[4] = {-1, 3, -3, -1}, C[2] = {1, 0}, F[1] = {0.2}, E[2] = {0, 1}, G[1] = {-0.1};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 2, 1, 1, A, NULL, C, moving ? NULL : E, F, moving ? G : NULL, NULL, NULL, msg))
    fail_msg("lcs: %s", msg);
  cb_ctx c = {mode, 0.5, 0};
  cup_input *u = NULL;
  assert_int_equal(cup_input_create(&u, 1, NULL), CUP_OK);
  if (via_rhs) {
    cup_wave k = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = 1};
    assert_int_equal(cup_input_add(u, 0, &k, NULL), CUP_OK);
  } else {
    assert_int_equal(cup_input_set_callback(u, bad_input, &c, 1e-12, 1e-10), CUP_OK);
  }
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = 100;
  o.scheme = scheme;
  if (via_rhs) { o.f = bad_rhs; o.f_ctx = &c; }
  cup_integrator *I = NULL;
  if (cup_integrator_create(&I, b.L, u, &o, msg)) fail_msg("%s: create: %s", what, msg);
  seen s = {0, -1, 1};
  cup_run_info info;
  double x0[2] = {0.3, 0};
  int st = cup_integrator_run(I, x0, seen_sink, &s, &info);
  if (st != CUP_ERR_CALLBACK) fail_msg("%s: status %s (%s)", what, cup_status_name(st), info.message);
  assert_int_equal(info.step, 50);                  /* steps 1..50 completed */
  assert_true(info.t == 0.5);
  assert_contains(info.message, "step 51 (t = 0.51");
  assert_contains(info.message, "failed or returned NaN/Inf");
  assert_int_equal(s.count, 51);                    /* states 0..50, all finite */
  assert_int_equal(s.last_k, 50);
  assert_true(s.all_finite);
  assert_true(c.calls > 0);
  const double *xf = cup_integrator_state(I);       /* the state kept is the last good one */
  assert_true(isfinite(xf[0]) && isfinite(xf[1]));
  cup_integrator_free(&I);
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static void test_callbacks_mid_run(void **state) {
  (void)state;
  const char *modes[] = {"NaN", "Inf", "failure"};
  char what[96];
  for (int mode = 0; mode < 3; mode++)
    for (int scheme = 0; scheme < 3; scheme++) {
      snprintf(what, sizeof what, "input u(t) %s, %s, E", modes[mode], cup_scheme_name(scheme));
      expect_callback_stop(what, scheme, 0, 0, mode);
      snprintf(what, sizeof what, "input u(t) %s, %s, moving K (G)", modes[mode], cup_scheme_name(scheme));
      expect_callback_stop(what, scheme, 1, 0, mode);
      snprintf(what, sizeof what, "perturbation f %s, %s", modes[mode], cup_scheme_name(scheme));
      expect_callback_stop(what, scheme, 0, 1, mode);
    }
}

/* ---- overflow during a run ---------------------------------------------------------- */

/* x' = 1000 x with h = 0.01: the explicit step multiplies by 11, and the
 * state leaves its range (||x||_1 <= CUP_STATE_MAX = 1e150) at step 145.
 * The run stops with CUP_ERR_DIVERGED at that step, says where and why,
 * and every state before it was delivered, within the range. */
static void test_overflow_mid_run(void **state) {
  (void)state;
  double A[4] = {1000, 0, 0, -1}, C[2] = {1, 0}, F[1] = {1};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 2, 1, 0, A, NULL, C, NULL, F, NULL, NULL, NULL, msg)) fail_msg("lcs: %s", msg);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = 1000;
  o.T = 10;
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, b.L, NULL, &o, msg), CUP_OK);
  seen s = {0, -1, 1};
  cup_run_info info;
  double x0[2] = {1, 1};
  int st = cup_integrator_run(I, x0, seen_sink, &s, &info);
  print_message("x' = 1000 x, explicit, h = 0.01: %s: %s\n", cup_status_name(st), info.message);
  assert_int_equal(st, CUP_ERR_DIVERGED);
  char want[64];
  snprintf(want, sizeof want, "step %ld (t = ", info.step + 1);
  assert_contains(info.message, want);
  assert_contains(info.message, "h*rho(A)");
  assert_int_equal(s.count, info.step + 1);
  assert_true(s.all_finite);
  /* independently: x_k = (11^k, 0.99^k) (x2' = -x); the first step whose
   * state has |x1| + |x2| > 1e150 is the one named, the state returned is
   * the one before it */
  long k_out = 0;
  for (double x1 = 1, x2 = 1; x1 + x2 <= 1e150; x1 = x1 + 1000 * (0.01 * x1), x2 = x2 - 0.01 * x2) k_out++;
  assert_int_equal(k_out, 145);
  assert_int_equal(info.step + 1, k_out);
  const double *xl = cup_integrator_state(I);
  assert_true(fabs(xl[0]) + fabs(xl[1]) <= 1e150 && xl[0] > 1e148);
  cup_integrator_free(&I);
  unbuild_lcs(&b);
}

/* The range check in every path: x' = diag(1000, -1) x, whose exact
 * solution itself leaves any range, under each scheme and projector, a
 * general set (a half-space, through the set projector) and the adaptive
 * scheme, with every state stored and with strides (the fused steps of a
 * small LCS check the range once per run of steps, then find the step
 * again). Each run stops with CUP_ERR_DIVERGED at the first step whose
 * state has ||x||_1 > 1e150, the one the scheme's own growth factor gives
 * (computed here by the scalar recurrence), having delivered only states
 * within the range; a stride names the same step. */
typedef struct { long count, last_k; double worst; } range_seen;

static int range_sink(long k, double t, const double *x, void *vp) {
  (void)t;
  range_seen *s = vp;
  s->count++;
  s->last_k = k;
  double n1 = fabs(x[0]) + fabs(x[1]);
  if (!(n1 <= s->worst)) s->worst = n1;
  return 0;
}

/* The first k with |x1_k| + |x2_k| > 1e150 for x_{k+1} = (a x1_k, b x2_k). */
static long first_out(double a, double b) {
  long k = 0;
  for (double x1 = 1, x2 = 1; fabs(x1) + fabs(x2) <= 1e150; x1 *= a, x2 *= b) k++;
  return k;
}

static int diverging_run(int scheme, int method, int process, cup_output_kind out, long every, long *named,
                         range_seen *s) {
  double A[4] = {1000, 0, 0, -1}, C[2] = {1, 0}, F[1] = {1};
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = scheme;
  o.proj.method = method;
  o.n = 2000;
  o.T = 1;
  o.output = out;
  o.output_every = every;
  o.output_samples = 0;
  char msg[CUP_ERRMSG_LEN];
  cup_integrator *I = NULL;
  lcs_built b = {0};
  cup_set *S = NULL;
  tcsc Am, Cm;
  tcsc_from_dense(&Am, A, 2, 2);
  tcsc_from_dense(&Cm, C, 1, 2);
  if (process) {                          /* K as a half-space: the set projector's path */
    cup_set_desc d = {.kind = CUP_SET_HALFSPACE, .n = 2, .C = Cm.view, .F = F};
    if (cup_set_create(&S, &d, msg)) fail_msg("set: %s", msg);
    cup_process_desc pd = {.n = 2, .C = S, .A = Am.view};
    if (cup_integrator_create_process(&I, &pd, &o, msg)) fail_msg("process: %s", msg);
  } else {
    if (build_lcs(&b, 2, 1, 0, A, NULL, C, NULL, F, NULL, NULL, NULL, msg)) fail_msg("lcs: %s", msg);
    if (cup_integrator_create(&I, b.L, NULL, &o, msg)) fail_msg("integrator: %s", msg);
  }
  *s = (range_seen){0, -1, 0};
  cup_run_info info;
  double x0[2] = {1, 1};
  int st = cup_integrator_run(I, x0, range_sink, s, &info);
  if (st != CUP_ERR_DIVERGED)
    fail_msg("scheme %d, method %d, process %d: %s (%s)", scheme, method, process, cup_status_name(st), info.message);
  assert_contains(info.message, "left its range");
  char want[64];
  snprintf(want, sizeof want, "step %ld (t = ", info.step + 1);
  assert_contains(info.message, want);
  assert_true(s->worst <= 1e150);
  const double *xl = cup_integrator_state(I);
  assert_true(fabs(xl[0]) + fabs(xl[1]) <= 1e150);
  *named = info.step + 1;
  cup_integrator_free(&I);
  cup_set_free(&S);
  tcsc_free(&Am);
  tcsc_free(&Cm);
  if (!process) unbuild_lcs(&b);
  return st;
}

static void test_divergence_every_scheme(void **state) {
  (void)state;
  const double h = 1.0 / 2000, l = 1000;
  struct { int scheme; double a, b; } sc[] = {
      {CUP_SCHEME_EXPLICIT, 1 + h * l, 1 - h},
      {CUP_SCHEME_IMPLICIT, 1 / (1 - h * l), 1 / (1 + h)},
      {CUP_SCHEME_EXPONENTIAL, exp(h * l), exp(-h)},
      {CUP_SCHEME_THETA, (1 + 0.5 * h * l) / (1 - 0.5 * h * l), (1 - 0.5 * h) / (1 + 0.5 * h)}};
  for (int i = 0; i < 4; i++) {
    long want = first_out(sc[i].a, sc[i].b);
    for (int method = 0; method < (sc[i].scheme == CUP_SCHEME_THETA ? 1 : 4); method++)
      for (int process = 0; process < (sc[i].scheme == CUP_SCHEME_THETA ? 1 : 2); process++) {
        range_seen s;
        long named, strided;
        diverging_run(sc[i].scheme, method, process, CUP_OUTPUT_EVERY, 1, &named, &s);
        if (named != want) fail_msg("scheme %d, method %d, process %d: step %ld, expected %ld", sc[i].scheme,
                                    method, process, named, want);
        assert_int_equal(s.count, named);            /* rows 0 .. named - 1 */
        diverging_run(sc[i].scheme, method, process, CUP_OUTPUT_EVERY, 300, &strided, &s);
        assert_int_equal(strided, want);
        assert_int_equal(s.last_k, (want - 1) / 300 * 300);
        diverging_run(sc[i].scheme, method, process, CUP_OUTPUT_FINAL, 1, &strided, &s);
        assert_int_equal(strided, want);
        assert_int_equal(s.count, 0);
      }
  }
  /* the adaptive scheme: the exact flow passes 1e150 at t = ln(1e150) / 1000 = 0.345 */
  range_seen s;
  long named;
  diverging_run(CUP_SCHEME_ADAPTIVE, 0, 0, CUP_OUTPUT_EVERY, 1, &named, &s);
  assert_true(s.count >= 2);
}

/* ---- the projector ------------------------------------------------------------------- */

/* A non-finite x, a huge x whose norm overflows, and a problem whose dual
 * multiplier overflows: an error, z untouched, never a NaN/Inf answer with
 * CUP_OK or a warning. */
static void test_projector_never_returns_nonfinite(void **state) {
  (void)state;
  /* K = {x1 >= 1e10}, P = diag(1e300, 1): lambda = 1e10 / ||c||^2_{P^-1} = 1e310 */
  double C[2] = {1, 0}, g[1] = {-1e10}, Pd[2] = {1e300, 1};
  tcsc Ct;
  cup_polyset *K = tpolyset_dense(&Ct, C, 1, 2, g, Pd);
  for (int method = 0; method < 4; method++) {
    cup_projector_options o;
    cup_projector_options_default(&o);
    o.method = method;
    o.max_iter = 1000;
    cup_projector *pr = NULL;
    assert_int_equal(cup_projector_create(&pr, K, &o, NULL), CUP_OK);
    const double xs[][2] = {{0, 0}, {NAN, 0}, {0, INFINITY}, {1e200, 1e200}};
    for (int c = 0; c < 4; c++) {
      double z[2] = {7, 7};
      cup_proj_info info;
      int st = cup_project(pr, xs[c], z, &info);
      if (st >= 0) {
        /* an answer: finite and truly what it claims (here z1 >= 1e10 is K) */
        if (!isfinite(z[0]) || !isfinite(z[1]))
          fail_msg("%s, x = (%g, %g): %s with z = (%g, %g)", cup_proj_method_name(method), xs[c][0],
                   xs[c][1], cup_status_name(st), z[0], z[1]);
        assert_false(isnan(info.eps_cert) || isnan(info.eta_cert));
        if (st == CUP_OK) assert_true(z[0] >= 1e10 * (1 - 1e-12));
      } else {
        assert_true(z[0] == 7 && z[1] == 7);          /* untouched on an error */
        assert_true(st == CUP_ERR_NONFINITE || st == CUP_ERR_DIVERGED);
      }
      if (c == 1 || c == 2) assert_int_equal(st, CUP_ERR_NONFINITE);
      if (getenv("CUP_TEST_VERBOSE"))
        fprintf(stderr, "%s x=(%g,%g): %s z=(%g,%g) eps %g eta %g\n", cup_proj_method_name(method),
                xs[c][0], xs[c][1], cup_status_name(st), z[0], z[1], info.eps_cert, info.eta_cert);
    }
    cup_projector_free(&pr);
  }
  cup_polyset_free(&K);
  tcsc_free(&Ct);
}

/* NaN never counts as inside; a refused offset leaves the previous one. */
static void test_nan_is_never_feasible(void **state) {
  (void)state;
  double C[4] = {1, 0, 0, 1}, g[2] = {0, 0};
  tcsc Ct;
  cup_polyset *K = tpolyset_dense(&Ct, C, 2, 2, g, NULL);
  double in[2] = {1, 1}, gn[2] = {0, NAN}, gi[2] = {INFINITY, 0};
  assert_int_equal(cup_polyset_contains(K, NULL, in), 1);
  assert_int_equal(cup_polyset_contains(K, gn, in), 0);     /* NaN offset: not inside */
  double xinf[2] = {INFINITY, 1};
  assert_int_equal(cup_polyset_contains(K, NULL, xinf), 0);
  cup_projector *pr = NULL;
  assert_int_equal(cup_projector_create(&pr, K, NULL, NULL), CUP_OK);
  double x[2] = {-1, 2}, z1[2], z2[2];
  assert_int_equal(cup_project(pr, x, z1, NULL), CUP_OK);
  /* the quadrant: exact but for the few ulps by which the dense exact path
   * aims inside (16 rounding bounds of the row at x: certainly feasible) */
  assert_true(z1[0] >= 0 && z1[0] <= 16 * 3 * DBL_EPSILON * 1 && z1[1] == 2);
  assert_int_equal(cup_projector_set_offset(pr, gn), CUP_ERR_NONFINITE);
  assert_int_equal(cup_projector_set_offset(pr, gi), CUP_ERR_NONFINITE);
  assert_int_equal(cup_project(pr, x, z2, NULL), CUP_OK);
  assert_memory_equal(z1, z2, sizeof z1);                    /* the old offset still holds */
  assert_int_equal(cup_projector_offer_feasible(pr, xinf), 0);
  assert_int_equal(cup_projector_set_tolerances(pr, NAN, 0, 0, 0), CUP_ERR_ARG);
  assert_int_equal(cup_projector_set_tolerances(pr, 0, 0, 0, NAN), CUP_ERR_ARG);
  cup_projector_free(&pr);
  cup_projector_options o;
  cup_projector_options_default(&o);
  double fp[2] = {1, NAN};
  o.feasible_point = fp;
  char msg[CUP_ERRMSG_LEN];
  assert_int_equal(cup_projector_create(&pr, K, &o, msg), CUP_ERR_NONFINITE);
  assert_null(pr);
  assert_contains(msg, "feasible_point[1]");
  cup_projector_options_default(&o);
  o.lipschitz = NAN;
  assert_int_equal(cup_projector_create(&pr, K, &o, msg), CUP_ERR_ARG);
  cup_polyset_free(&K);
  tcsc_free(&Ct);
}

/* ---- options and overrides --------------------------------------------------------- */

static void test_options_and_overrides(void **state) {
  (void)state;
  cup_lcs *L = NULL;
  cup_circuit circ = {1, 2, 1, 1, 2, 1, {0, 0}};
  assert_int_equal(cup_lcs_circuit(&L, &circ, NULL), CUP_OK);
  cup_input *u = NULL;
  cup_input_create(&u, 1, NULL);
  cup_integrator *I = NULL;
  char msg[CUP_ERRMSG_LEN];
  for (int c = 0; c < 6; c++) {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    switch (c) {
      case 0: o.T = NAN; break;
      case 1: o.T = INFINITY; break;
      case 2: o.eps.coef = NAN; break;
      case 3: o.eta.power = NAN; break;
      case 4: o.max_wall_seconds = NAN; break;
      case 5: o.eps = (cup_schedule){1e300, 2}; break;   /* eps_n = 1e304: finite, fine */
    }
    int st = cup_integrator_create(&I, L, u, &o, msg);
    if (c < 5) {
      if (st != CUP_ERR_ARG) fail_msg("case %d: %s", c, cup_status_name(st));
      assert_null(I);
    } else {
      assert_int_equal(st, CUP_OK);
      cup_integrator_free(&I);
    }
  }
  {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.eps = (cup_schedule){1e300, 10};                  /* eps_n = 1e320: overflows */
    assert_int_equal(cup_integrator_create(&I, L, u, &o, msg), CUP_ERR_ARG);
    assert_contains(msg, "eps_n = inf");
  }
  cup_input_free(&u);
  cup_lcs_free(&L);
  /* overrides carry NaN/Inf too: the message cites the override */
  const char *text = "circuit: {R1: 1, R2: 2, R3: 1, L2: 1, L3: 2, C4: 1}\n"
                     "input: [{type: sine, amplitude: 16, frequency: 3}, -0.5]\nT: 1\nn: 100\n";
  struct { const char *ovr, *want; } cases[] = {
    {"x0=[0, .nan, 0]", "override 'x0=[0, .nan, 0]': x0.1: must be finite (got nan)"},
    {"input.0.amplitude=.inf", "override 'input.0.amplitude=.inf': input.0.amplitude: must be finite (got inf)"},
    {"circuit.C4=-.Inf", "circuit.C4: must be finite (got -inf)"},
    {"T=1e400", "T: must be finite (got inf)"},
    {"input.1=.NAN", "input.1: must be finite (got nan)"},
  };
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    cup_scene *s = NULL;
    const char *ov[1] = {cases[k].ovr};
    int st = cup_scene_load_string(&s, text, "nan.yaml", NULL, ov, 1, msg);
    if (st != CUP_ERR_NONFINITE) fail_msg("override %s: status %s (%s)", cases[k].ovr, cup_status_name(st), msg);
    assert_null(s);
    assert_contains(msg, cases[k].want);
  }
}

/* ---- the adaptive scheme ---------------------------------------------------------- */

/* The 2-state system above by the adaptive scheme with a callback input
 * fn (on E, or on a moving K through G), its states at t = j/100 counted in
 * sn; returns the status. */
static int run_adaptive_callback(int moving, cup_input_fn fn, void *ctx, seen *sn, cup_run_info *info) {
  double A[4] = {-1, 3, -3, -1}, C[2] = {1, 0}, F[1] = {0.2}, E[2] = {0, 1}, G[1] = {-0.1};
  lcs_built b;
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(&b, 2, 1, 1, A, NULL, C, moving ? NULL : E, F, moving ? G : NULL, NULL, NULL, msg))
    fail_msg("lcs: %s", msg);
  cup_input *u = NULL;
  assert_int_equal(cup_input_create(&u, 1, NULL), CUP_OK);
  assert_int_equal(cup_input_set_callback(u, fn, ctx, 1e-12, 1e-10), CUP_OK);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_samples = 101;
  cup_integrator *I = NULL;
  if (cup_integrator_create(&I, b.L, u, &o, msg)) fail_msg("create: %s", msg);
  double x0[2] = {0.3, 0};
  int st = cup_integrator_run(I, x0, seen_sink, sn, info);
  const double *xl = cup_integrator_state(I);      /* the state kept is the last good one */
  assert_true(isfinite(xl[0]) && isfinite(xl[1]));
  cup_integrator_free(&I);
  cup_input_free(&u);
  unbuild_lcs(&b);
  return st;
}

/* A callback input that goes bad after t = 0.5 (NaN, Inf, a failure), on
 * E and on a moving K: the adaptive run stops with CUP_ERR_CALLBACK at the
 * step that first samples it there, names that time, and has delivered
 * every output time before it, all finite. */
static void test_adaptive_callbacks(void **state) {
  (void)state;
  for (int mode = 0; mode < 3; mode++)
    for (int moving = 0; moving < 2; moving++) {
      cb_ctx c = {mode, 0.5, 0};
      seen sn = {0, -1, 1};
      cup_run_info info;
      int st = run_adaptive_callback(moving, bad_input, &c, &sn, &info);
      print_message("adaptive, input %s%s: %s: %s (%ld samples)\n", mode == 0 ? "NaN" : mode == 1 ? "Inf" : "fails",
                    moving ? ", moving K" : "", cup_status_name(st), info.message, sn.count);
      assert_int_equal(st, CUP_ERR_CALLBACK);
      assert_contains(info.message, "the input u(t) failed or returned NaN/Inf");
      assert_true(info.t <= 0.5 && info.t > 0.4);
      assert_true(sn.count >= 41 && sn.count <= 51);  /* t = 0 .. t_stop, on the grid j / 100 */
      assert_true(sn.all_finite);
    }
}

/* u(t) = 1 / (1/2 - t) has no polynomial approximation near 1/2: the
 * callback's steps shrink until they underflow, and the run says so with
 * the time, keeping what it computed. */
static int pole_input(double t, double *u, void *vp) {
  (void)vp;
  u[0] = 1 / (0.5 - t);
  return 0;
}

static void test_adaptive_step_underflow(void **state) {
  (void)state;
  seen sn = {0, -1, 1};
  cup_run_info info;
  int st = run_adaptive_callback(0, pole_input, NULL, &sn, &info);
  print_message("adaptive, u = 1/(1/2 - t): %s: %s (%ld samples, %ld rejected steps)\n", cup_status_name(st),
                info.message, sn.count, info.rejected);
  assert_int_equal(st, CUP_ERR_STEP_SIZE);
  assert_contains(info.message, "underflows");
  assert_true(info.t > 0.49 && info.t < 0.5);
  assert_int_equal(sn.count, 50);                    /* t = 0, 0.01, ..., 0.49 */
  assert_true(sn.all_finite);
}

/* Bad tolerances are refused at creation, naming the value; one below
 * double precision at the state's scale is a warning that names it. */
static void test_adaptive_tolerances(void **state) {
  (void)state;
  cup_lcs *L = NULL;
  cup_circuit circ = {1, 2, 1, 1, 2, 1, {0, 0}};
  assert_int_equal(cup_lcs_circuit(&L, &circ, NULL), CUP_OK);
  cup_wave w[2] = {{.kind = CUP_WAVE_SINE, .amplitude = 16, .frequency = 3},
                   {.kind = CUP_WAVE_CONSTANT, .value = -0.5}};
  cup_input *u = input_terms(2, w);
  struct { double abs, rel, rate; const char *want; } bad[] = {
    {NAN, 1e-6, 0, "tol_abs = nan"}, {1e-6, -1, 0, "tol_rel = -1"}, {INFINITY, 1e-6, 0, "tol_abs = inf"},
    {0, 0, 0, "tol_rel = 0 with tol_abs = 0"}, {0, 1e-17, 0, "below what double precision"},
    {1e-6, 1e-6, NAN, "max_event_rate = nan"},
  };
  char msg[CUP_ERRMSG_LEN];
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.scheme = CUP_SCHEME_ADAPTIVE;
    o.tol_abs = bad[k].abs;
    o.tol_rel = bad[k].rel;
    o.max_event_rate = bad[k].rate;
    cup_integrator *I = NULL;
    assert_int_equal(cup_integrator_create(&I, L, u, &o, msg), CUP_ERR_ARG);
    assert_null(I);
    assert_contains(msg, bad[k].want);
  }
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.tol_abs = 1e-300;
  o.tol_rel = 1e-15;
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, L, u, &o, msg), CUP_OK);
  double x0[3] = {0, 0, 0}, xnan[3] = {0, NAN, 0};
  cup_run_info info;
  int st = cup_integrator_run(I, x0, NULL, NULL, &info);
  print_message("adaptive, tol_rel = 1e-15: %s: %s\n", cup_status_name(st), info.message);
  assert_int_equal(st, CUP_WARN_TOL_FLOOR);
  assert_contains(info.message, "rel 1e-15");
  assert_int_equal(info.step > 0 && info.t == 1, 1);
  assert_int_equal(cup_integrator_run(I, xnan, NULL, NULL, &info), CUP_ERR_NONFINITE);
  assert_contains(info.message, "x0[1] is nan");
  cup_integrator_free(&I);
  cup_input_free(&u);
  cup_lcs_free(&L);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_lcs_matrices),
    cmocka_unit_test(test_callbacks_mid_run),
    cmocka_unit_test(test_overflow_mid_run),
    cmocka_unit_test(test_divergence_every_scheme),
    cmocka_unit_test(test_projector_never_returns_nonfinite),
    cmocka_unit_test(test_nan_is_never_feasible),
    cmocka_unit_test(test_options_and_overrides),
    cmocka_unit_test(test_adaptive_callbacks),
    cmocka_unit_test(test_adaptive_step_underflow),
    cmocka_unit_test(test_adaptive_tolerances),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
