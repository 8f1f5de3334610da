/* integrator: the paper's two circuits against the reference limits (tests/data),
 * five closed-form sweeping processes / LCS (derived in the comments, and in
 * docs/closed-forms.md), the stiff rectifier, output modes, and errors that
 * say where they happened without losing the states before. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"
#include "stress_util.h"
#include "../bench/paper.h"
#include "closed_forms.h"
#include "refdata.h"

/* ---- helpers --------------------------------------------------------------------- */

typedef double (*exact_fn)(double t, int i, const void *par);

typedef struct {
  exact_fn exact;        /* closed form, or NULL: compare with ref[] on a 1/1000 grid */
  const void *par;
  const double *ref;     /* 1001 x 3 */
  int dim;
  long n;
  double err;            /* max over sampled grid points and components */
  long count;
} err_ctx;

static int err_sink(long k, double t, const double *x, void *vp) {
  err_ctx *c = vp;
  for (int i = 0; i < c->dim; i++) {
    double ex;
    if (c->exact) {
      ex = c->exact(t, i, c->par);
    } else {
      long stride = c->n / 1000;
      if (k % stride) return 0;
      ex = c->ref[(k / stride) * 3 + i];
    }
    c->err = fmax(c->err, fabs(x[i] - ex));
  }
  c->count++;
  return 0;
}

static double run_error(const cup_lcs *L, const cup_input *u, const double *x0, long n, double T,
                        int scheme, exact_fn exact, const void *par, const double *ref,
                        cup_run_info *info) {
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = n;
  o.T = T;
  o.scheme = scheme;
  o.eps = (cup_schedule){0, 0};          /* exact projections */
  o.eta = (cup_schedule){0, 0};
  cup_integrator *I = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_integrator_create(&I, L, u, &o, msg)) fail_msg("create: %s", msg);
  err_ctx c = {exact, par, ref, cup_lcs_dim(L), n, 0, 0};
  cup_run_info local;
  cup_run_info *ri = info ? info : &local;
  int st = cup_integrator_run(I, x0, err_sink, &c, ri);
  if (st < 0) fail_msg("run: %s", ri->message);
  cup_integrator_free(&I);
  return c.err;
}

static double order_of(double e1, double e2) { return log10(e1 / e2); }   /* n x10 */

/* ---- the paper's circuits ----------------------------------------------------------- */

static double ref1[1001 * 3], ref2[1001 * 3];

/* The paper's cases (bench/paper.h), which must build. */
static cup_input *case_input(int cas) {
  cup_input *u = paper_input(cas);
  assert_non_null(u);
  return u;
}

static cup_lcs *case_lcs(int cas) {
  cup_lcs *L = NULL;
  assert_int_equal(paper_lcs(&L, cas, NULL), CUP_OK);
  return L;
}

/* Exact-projection catching-up: max-norm error within 2% of 1.52/n (case 1)
 * and 1.79/n (case 2) at n = 10^3 and 10^4 (docs/design.md, measured here). */
static void test_paper_cases_exact_projection(void **state) {
  (void)state;
  ref_load("ref_case1_limit_richardson.csv", ref1);
  ref_load("ref_case2_limit_richardson.csv", ref2);
  static const double C[3] = {0, 1.52, 1.79};
  for (int cas = 1; cas <= 2; cas++) {
    cup_lcs *L = case_lcs(cas);
    cup_input *u = case_input(cas);
    double x0[3] = {0, 0, 0};
    for (long n = 1000; n <= 10000; n *= 10) {
      double e = run_error(L, u, x0, n, 1, CUP_SCHEME_EXPLICIT, NULL, NULL, cas == 1 ? ref1 : ref2, NULL);
      print_message("case %d n %ld: error %.6e = %.4f / n\n", cas, n, e, e * n);
      assert_true(fabs(e * n - C[cas]) <= 0.02 * C[cas]);
    }
    cup_input_free(&u);
    cup_lcs_free(&L);
  }
}

typedef struct { double *X; int dim; } store_ctx;   /* row k of X: x_k */
static int store_sink(long k, double t, const double *x, void *vp) {
  (void)t;
  store_ctx *c = vp;
  memcpy(c->X + (size_t)c->dim * (size_t)k, x, (size_t)c->dim * sizeof(double));
  return 0;
}

/* The paper's tolerances eps_n = n^-2.1, eta_n = n^-1.05 with the default
 * projector: the trajectory differs from the exact-projection run by <= 1%
 * of the discretization error. */
/* The paper's tolerances with the default projector (auto: on this small
 * set the step's dual by principal pivoting) against the exact projection
 * by the projector's dense active set (an independent path). The methods
 * that stop as soon as (eps_n, eta_n) are certified (pg, fista) drift by
 * 24-39% of the error over the run: documented in docs/closed-forms.md. */
static void test_paper_tolerances(void **state) {
  (void)state;
  static const int methods[] = {CUP_PROJ_AUTO};
  for (int cas = 1; cas <= 2; cas++)
    for (long n = 1000; n <= 10000; n *= 10) {
      cup_lcs *L = case_lcs(cas);
      cup_input *u = case_input(cas);
      double *X[2];
      for (int q = 0; q < 2; q++) X[q] = malloc(sizeof(double) * 3 * (size_t)(n + 1));
      for (int pass = -1; pass < 1; pass++) {     /* -1: the exact reference */
        cup_integrator_options o;
        cup_integrator_options_default(&o);           /* n^-2.1, n^-1.05 */
        o.n = n;
        if (pass < 0) {
          o.eps = (cup_schedule){0, 0};
          o.eta = (cup_schedule){0, 0};
          o.proj.method = CUP_PROJ_ACTIVESET;
        } else {
          o.proj.method = methods[pass];
        }
        cup_integrator *I = NULL;
        assert_int_equal(cup_integrator_create(&I, L, u, &o, NULL), CUP_OK);
        double x0[3] = {0, 0, 0};
        store_ctx sc = {X[pass < 0 ? 0 : 1], 3};
        cup_run_info info;
        assert_int_equal(cup_integrator_run(I, x0, store_sink, &sc, &info), CUP_OK);
        cup_integrator_free(&I);
        if (pass < 0) continue;
        assert_true(info.max_eps_cert <= pow((double)n, -2.1));
        assert_true(info.max_eta_cert <= pow((double)n, -1.05));
        double d = 0;
        for (long q = 0; q < 3 * (n + 1); q++) d = fmax(d, fabs(X[0][q] - X[1][q]));
        double err = (cas == 1 ? 1.52 : 1.79) / n;
        print_message("case %d n %5ld, paper tolerances, %-5s: %.3e from the exact run (%.2f%% of the error)\n",
                      cas, n, cup_proj_method_name(methods[pass]), d, 100 * d / err);
        assert_true(d <= 0.01 * err);
      }
      free(X[0]); free(X[1]);
      cup_input_free(&u);
      cup_lcs_free(&L);
    }
}

/* The theta scheme: theta = 0 is the explicit catching-up step (the LCP of
 * a symmetric M is the P-projection), and theta = 1/2 reproduces Siconos
 * 4.4's Moreau-Jean values on case 1 (measured with EulerMoreauOSI,
 * theta = 0.5, Lemke: 8.737e-6 at n = 10^3, 1.444e-7 at 10^4, 9.965e-10 at
 * 10^5). */
/* A run of n steps from x0 with the projector's dense active-set method
 * (explicit: the projector, not the theta path), its states into X; the
 * targets eps and eta absolute; on_step rows_step into rc unless NULL. */
typedef struct rows_ctx rows_ctx;
static int rows_step(long k, double t, const cup_proj_info *pi, void *vp);
static void run_store(const cup_lcs *L, const cup_input *u, long n, int scheme, double theta, double eps,
                      double eta, const double *x0, double *X, rows_ctx *rc) {
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = n;
  o.scheme = scheme;
  o.theta = theta;
  o.proj.method = CUP_PROJ_ACTIVESET;
  o.eps = (cup_schedule){eps, 0};
  o.eta = (cup_schedule){eta, 0};
  if (rc) {
    o.on_step = rows_step;
    o.step_ctx = rc;
  }
  cup_integrator *I = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_integrator_create(&I, L, u, &o, msg)) fail_msg("create: %s", msg);
  store_ctx sc = {X, cup_lcs_dim(L)};
  cup_run_info info;
  if (cup_integrator_run(I, x0, store_sink, &sc, &info) < 0) fail_msg("run: %s", info.message);
  cup_integrator_free(&I);
}

static void test_theta_scheme(void **state) {
  (void)state;
  for (int cas = 1; cas <= 2; cas++) {
    cup_lcs *L = case_lcs(cas);
    cup_input *u = case_input(cas);
    long n = 1000;
    double *X0 = malloc(sizeof(double) * 3 * (size_t)(n + 1)), *Xe = malloc(sizeof(double) * 3 * (size_t)(n + 1));
    static const double x0[3] = {0, 0, 0};
    run_store(L, u, n, CUP_SCHEME_THETA, 0, 0, 0, x0, X0, NULL);
    run_store(L, u, n, CUP_SCHEME_EXPLICIT, 0, 0, 0, x0, Xe, NULL);
    double d = 0;
    for (long q = 0; q < 3 * (n + 1); q++) d = fmax(d, fabs(X0[q] - Xe[q]));
    print_message("case %d: theta = 0 vs explicit projection: max difference %.3e\n", cas, d);
    assert_true(d <= 1e-12);
    free(X0); free(Xe);
    cup_input_free(&u);
    cup_lcs_free(&L);
  }
  cup_lcs *L = case_lcs(1);
  cup_input *u = case_input(1);
  static const double siconos[3] = {8.737e-6, 1.444e-7, 9.965e-10};
  double e[3];
  for (int k = 0; k < 3; k++) {
    long n = 1000 * (long)pow(10, k);
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.n = n;
    o.scheme = CUP_SCHEME_THETA;
    o.theta = 0.5;
    o.eps = (cup_schedule){0, 0};
    o.eta = (cup_schedule){0, 0};
    o.output = CUP_OUTPUT_EVERY;
    o.output_every = n / 1000;
    cup_integrator *I = NULL;
    assert_int_equal(cup_integrator_create(&I, L, u, &o, NULL), CUP_OK);
    err_ctx c = {NULL, NULL, ref1, 3, n, 0, 0};
    double x0[3] = {0, 0, 0};
    cup_run_info info;
    assert_true(cup_integrator_run(I, x0, err_sink, &c, &info) >= 0);
    e[k] = c.err;
    print_message("theta = 1/2, case 1, n %7ld: error %.4e (Siconos %.4e)\n", n, e[k], siconos[k]);
    assert_true(fabs(e[k] - siconos[k]) <= 0.01 * siconos[k]);
    cup_integrator_free(&I);
  }
  assert_true(order_of(e[1], e[2]) > 1.9);        /* second order once the kinks resolve */
  cup_input_free(&u);
  cup_lcs_free(&L);
}

/* ---- closed forms --------------------------------------------------------------- */

/* A small LCS from dense row-major matrices (absent ones: NULL;
 * stress_util.h), which must be valid. */
static void build(lcs_built *b, int n, int m, int p, const double *A, const double *B,
                  const double *C, const double *E, const double *F, const double *G,
                  const double *Pdiag) {
  char msg[CUP_ERRMSG_LEN];
  if (build_lcs(b, n, m, p, A, B, C, E, F, G, Pdiag, NULL, msg)) fail_msg("lcs: %s", msg);
}

/* The theta step's LCP with up to four rows active at once (the paper's
 * circuit has two rows, so this is what exercises the LU path): a 4-state
 * system whose rows x1 >= 0, x1 + x2 >= 0, x2 + x3 >= 0, x3 + x4 >= 0 are
 * pushed on together by E u. theta = 0 must equal the explicit step with the
 * exact projection (the projector's dense active-set method: an independent
 * solver), theta = 1/2 must certify complementarity at every step. */
struct rows_ctx { int max_active; double max_eps; int bad; };
static int rows_step(long k, double t, const cup_proj_info *pi, void *vp) {
  (void)k; (void)t;
  rows_ctx *c = vp;
  if (pi->active > c->max_active) c->max_active = pi->active;
  if (pi->eps_cert > c->max_eps) c->max_eps = pi->eps_cert;
  if (pi->status != CUP_OK) c->bad++;
  return 0;
}
static void test_theta_many_rows(void **state) {
  (void)state;
  const double A[16] = {-1, 2, 0, 0,  -2, -1, 1, 0,  0, -1, -0.5, 3,  0, 0, -3, -0.2};
  const double C[16] = {1, 0, 0, 0,  1, 1, 0, 0,  0, 1, 1, 0,  0, 0, 1, 1};
  const double Pd[4] = {2, 1, 2, 1};
  double B[16];                                   /* B = P^-1 C^T */
  for (int r = 0; r < 4; r++)
    for (int i = 0; i < 4; i++) B[r * 4 + i] = C[i * 4 + r] / Pd[r];
  const double E[4] = {-1, -1, -1.5, -1};
  lcs_built b;
  build(&b, 4, 4, 1, A, B, C, E, NULL, NULL, Pd);
  cup_input *u = NULL;
  cup_input_create(&u, 1, NULL);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 3, .frequency = 1.5};
  cup_wave c = {.kind = CUP_WAVE_CONSTANT, .value = 1};
  cup_input_add(u, 0, &s, NULL);
  cup_input_add(u, 0, &c, NULL);
  long n = 2000;
  size_t len = 4 * (size_t)(n + 1);
  double *Xt = malloc(sizeof(double) * len), *Xe = malloc(sizeof(double) * len);
  rows_ctx rt = {0, 0, 0}, re = {0, 0, 0};
  static const double x0[4] = {1, 0, 0, 0};
  /* targets absolute: the state passes near 0, where relative ones fall below rounding */
  run_store(b.L, u, n, CUP_SCHEME_THETA, 0, 1e-14, 1e-12, x0, Xt, &rt);
  run_store(b.L, u, n, CUP_SCHEME_EXPLICIT, 0, 1e-14, 1e-12, x0, Xe, &re);
  double d = 0;
  for (size_t q = 0; q < len; q++) d = fmax(d, fabs(Xt[q] - Xe[q]));
  print_message("4 rows: theta = 0 vs explicit projection: max difference %.3e, "
                "at most %d rows active\n", d, rt.max_active);
  assert_true(rt.max_active >= 3);
  assert_int_equal(rt.bad + re.bad, 0);
  assert_true(d <= 1e-12);
  rows_ctx rh = {0, 0, 0};
  run_store(b.L, u, n, CUP_SCHEME_THETA, 0.5, 1e-14, 1e-12, x0, Xt, &rh);
  print_message("4 rows: theta = 1/2: at most %d rows active, largest gap %.3e, %d uncertified\n",
                rh.max_active, rh.max_eps, rh.bad);
  assert_true(rh.max_active >= 3);
  assert_int_equal(rh.bad, 0);
  for (size_t q = 0; q < len; q += 4) {           /* every state in K */
    const double *x = Xt + q;
    assert_true(x[0] >= -1e-13 && x[0] + x[1] >= -1e-13 && x[1] + x[2] >= -1e-13 && x[2] + x[3] >= -1e-13);
  }
  /* theta = 1/2 and the explicit step converge to one solution */
  double dt = 0;
  for (size_t q = 0; q < len; q++) dt = fmax(dt, fabs(Xt[q] - Xe[q]));
  print_message("4 rows: theta = 1/2 vs explicit at n = %ld: %.3e\n", n, dt);
  assert_true(dt > 0 && dt <= 2e-2);
  free(Xt); free(Xe);
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static cup_input *const_input(double v) {
  cup_input *u = NULL;
  cup_input_create(&u, 1, NULL);
  cup_wave c = {.kind = CUP_WAVE_CONSTANT, .value = v};
  cup_input_add(u, 0, &c, NULL);
  return u;
}

/* Observed order between n and 10 n in [0.9, 1.15]. */
static void check_order(const char *name, const lcs_built *b, const cup_input *u, const double *x0,
                        double T, exact_fn ex, const void *par, long n) {
  double e1 = run_error(b->L, u, x0, n, T, CUP_SCHEME_EXPLICIT, ex, par, NULL, NULL);
  double e2 = run_error(b->L, u, x0, 10 * n, T, CUP_SCHEME_EXPLICIT, ex, par, NULL, NULL);
  double p = order_of(e1, e2);
  print_message("%-28s n %6ld: %.3e, n %7ld: %.3e, order %.3f\n", name, n, e1, 10 * n, e2, p);
  assert_true(p >= 0.9 && p <= 1.15);
}

static void test_closed_form_moving_interval(void **state) {
  (void)state;
  double C[2] = {1, -1}, F[2] = {0.5, 0.5}, G[2] = {-1, 1};   /* x - sin t + r >= 0, -x + sin t + r >= 0 */
  lcs_built b;
  build(&b, 1, 2, 1, NULL, NULL, C, NULL, F, G, NULL);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = 1 / (2 * M_PI)};   /* sin t */
  cup_input *u = input_terms(1, &s);
  double x0[1] = {0};
  /* Rate independent: the catching-up iterate equals the solution at every
   * grid point (a projection of the previous value is exactly what the play
   * operator does), so the grid error is rounding. */
  for (long n = 1000; n <= 100000; n *= 10) {
    double e = run_error(b.L, u, x0, n, 2.5 * M_PI, CUP_SCHEME_EXPLICIT, interval_exact, NULL, NULL, NULL);
    print_message("moving interval n %6ld: error %.3e (exact at grid points)\n", n, e);
    assert_true(e <= 1e-12);
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static void test_closed_form_interval_with_relaxation(void **state) {
  (void)state;
  double A[1] = {-1}, C[2] = {1, -1}, F[2] = {0.5, 0.5}, G[2] = {-1, 1};
  lcs_built b;
  build(&b, 1, 2, 1, A, NULL, C, NULL, F, G, NULL);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = 1 / (2 * M_PI)};   /* sin t */
  cup_input *u = input_terms(1, &s);
  double T = 2.5 * M_PI, x0[1] = {0};
  relax_par q;
  relax_setup(&q, T);
  assert_true(q.nev >= 4);                        /* free, pushed, free, pushed, ... */
  check_order("moving interval, relaxation", &b, u, x0, T, relax_exact, &q, 1000);
  cup_input_free(&u);
  unbuild_lcs(&b);
}

/* x' = A x + E with u = 1 onto the quadrant x >= 0 (C = I, P diagonal or
 * NULL), against its exact solution. */
static void quadrant_case(const char *name, const double *A, const double *E, const double *P,
                          const double *x0, double T, exact_fn ex) {
  static const double C[4] = {1, 0, 0, 1};
  lcs_built b;
  build(&b, 2, 2, 1, A, NULL, C, E, NULL, NULL, P);
  cup_input *u = const_input(1);
  check_order(name, &b, u, x0, T, ex, NULL, 1000);
  cup_input_free(&u);
  unbuild_lcs(&b);
}

static void test_closed_form_cone(void **state) {
  (void)state;
  double A[4] = {-1, 0, 0, -1}, E[2] = {1, -1}, x0[2] = {0, 1};
  quadrant_case("cone, f = -x + c", A, E, NULL, x0, 2, cone_exact);
}

static void rect_build(lcs_built *b, const rect_par *q, double *P) {
  double A[1] = {-q->R / q->L}, B[1] = {1 / q->L}, C[1] = {1}, E[1] = {q->V / q->L};
  P[0] = q->L;
  build(b, 1, 1, 1, A, B, C, E, NULL, NULL, P);
}

static cup_input *sine_input(double f) {
  cup_input *u = NULL;
  cup_input_create(&u, 1, NULL);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = f};
  cup_input_add(u, 0, &s, NULL);
  return u;
}

/* The RL half-wave rectifier of q under a unit sine, as the tests below run it. */
typedef struct { lcs_built b; double P[1]; cup_input *u; } rect_case;
static void rect_open(rect_case *c, rect_par *q) {
  rect_setup(q);
  rect_build(&c->b, q, c->P);
  c->u = sine_input(1);
}
static void rect_close(rect_case *c) {
  cup_input_free(&c->u);
  unbuild_lcs(&c->b);
}

static void test_closed_form_rectifier(void **state) {
  (void)state;
  rect_par q = {1, 0.2, 1, 2 * M_PI, 0};
  rect_case rc;
  rect_open(&rc, &q);
  double x0[1] = {0};
  check_order("RL half-wave rectifier", &rc.b, rc.u, x0, 2, rect_exact, &q, 1000);
  rect_close(&rc);
}

static void test_closed_form_corner(void **state) {
  (void)state;
  double A[4] = {-1, 0, 0, -2}, E[2] = {-1, -1}, P[2] = {2, 3}, x0[2] = {1, 1};
  quadrant_case("corner of a quadrant", A, E, P, x0, 1.5, corner_exact);
}

static void test_closed_form_jumping_set(void **state) {
  (void)state;
  double A[1] = {-1}, C[1] = {1}, G[1] = {-1};
  lcs_built b;
  build(&b, 1, 1, 1, A, NULL, C, NULL, NULL, G, NULL);
  cup_input *u = NULL;
  cup_input_create(&u, 1, NULL);
  cup_wave q = {.kind = CUP_WAVE_SQUARE, .amplitude = 1, .frequency = 1};
  cup_input_add(u, 0, &q, NULL);
  double x0[1] = {1};
  for (long n = 1000; n <= 100000; n *= 10) {
    double e = run_error(b.L, u, x0, n, 1.75, CUP_SCHEME_EXPLICIT, jump_exact, NULL, NULL, NULL);
    print_message("jumping set n %6ld: error %.3e = %.3f h\n", n, e, e * n / 1.75);
    assert_true(e <= 1.0 * 1.75 / n);            /* C = 1 */
  }
  cup_input_free(&u);
  unbuild_lcs(&b);
}

/* Stiff: the rectifier with L = 1e-3 (time constant 1e-3) at n = 100 over two
 * periods (h / tau = 20): explicit is flagged; implicit and exponential stay
 * within 2x of their own error at n = 10^4 scaled by 100 (first order). */
static void test_stiff_rectifier(void **state) {
  (void)state;
  rect_par q = {1, 1e-3, 1, 2 * M_PI, 0};
  rect_case rc;
  rect_open(&rc, &q);
  const cup_lcs *L = rc.b.L;
  const cup_input *u = rc.u;
  double x0[1] = {0};
  cup_run_info info;
  double ex = run_error(L, u, x0, 100, 2, CUP_SCHEME_EXPLICIT, rect_exact, &q, NULL, &info);
  assert_int_equal(info.status, CUP_WARN_STIFF);
  assert_true(info.h_rho > 2);
  assert_non_null(strstr(info.message, "h*rho(A)"));
  print_message("stiff explicit n 100: h*rho = %.1f, error %.3e\n", info.h_rho, ex);
  for (int scheme = CUP_SCHEME_IMPLICIT; scheme <= CUP_SCHEME_EXPONENTIAL; scheme++) {
    double e100 = run_error(L, u, x0, 100, 2, scheme, rect_exact, &q, NULL, &info);
    assert_int_equal(info.status, CUP_OK);
    double e1e4 = run_error(L, u, x0, 10000, 2, scheme, rect_exact, &q, NULL, NULL);
    print_message("stiff %-11s: n 100 error %.3e, n 1e4 error %.3e (x100 = %.3e)\n",
                  cup_scheme_name(scheme), e100, e1e4, 100 * e1e4);
    assert_true(e100 <= 2 * 100 * e1e4);
  }
  rect_close(&rc);
}

/* ---- output, schedules, errors ------------------------------------------------------ */

typedef struct { long count, last_k; double last_t; long ks[64]; } count_ctx;
static int count_sink(long k, double t, const double *x, void *vp) {
  (void)x;
  count_ctx *c = vp;
  if (c->count < 64) c->ks[c->count] = k;
  c->count++;
  c->last_k = k;
  c->last_t = t;
  return 0;
}

static void test_output_modes_and_exact_time(void **state) {
  (void)state;
  cup_lcs *L = case_lcs(1);
  cup_input *u = case_input(1);
  double x0[3] = {0, 0, 0};
  struct { cup_output_kind kind; long every, samples, expect; } cases[] = {
    {CUP_OUTPUT_EVERY, 1, 0, 1001}, {CUP_OUTPUT_EVERY, 7, 0, 144},  /* 0,7,..,994 and 1000 */
    {CUP_OUTPUT_SAMPLES, 0, 11, 11}, {CUP_OUTPUT_FINAL, 0, 0, 1}, {CUP_OUTPUT_NONE, 0, 0, 0},
  };
  for (int c = 0; c < 5; c++) {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.n = 1000; o.T = 3;
    o.output = cases[c].kind;
    o.output_every = cases[c].every ? cases[c].every : 1;
    o.output_samples = cases[c].samples;
    cup_integrator *I = NULL;
    assert_int_equal(cup_integrator_create(&I, L, u, &o, NULL), CUP_OK);
    count_ctx cc = {0};
    cup_run_info info;
    assert_int_equal(cup_integrator_run(I, x0, count_sink, &cc, &info), CUP_OK);
    assert_int_equal(cc.count, cases[c].expect);
    assert_int_equal(info.samples, cases[c].expect);
    if (cc.count) {
      assert_int_equal(cc.last_k, 1000);
      assert_true(cc.last_t == 3.0);                /* t_n = T exactly */
    }
    if (cases[c].kind == CUP_OUTPUT_SAMPLES)
      for (int j = 0; j < 11; j++) assert_int_equal(cc.ks[j], 100 * j);
    assert_int_equal(info.step, 1000);
    assert_true(info.t == 3.0);
    assert_int_equal(info.projected + info.skipped, 1000);
    cup_integrator_free(&I);
  }
  cup_input_free(&u);
  cup_lcs_free(&L);
}

/* The fixed-step schemes' samples on the .tran grid: sample j (tau_j =
 * T j / (S - 1)) lies on step k when k (S - 1) = j n in integers, and is
 * then that step's (t = k h, T at the end); otherwise it is interpolated,
 * given to the sink at step ceil(j n / (S - 1)) with t = tau_j. Checked in
 * integers against the schedule fixed.c finds by remainders (llround
 * before), over grids finer and coarser than the steps. */
typedef struct { long count, *k; double *t; } grid_ctx;
static int grid_sink(long k, double t, const double *x, void *vp) {
  (void)x;
  grid_ctx *c = vp;
  c->k[c->count] = k;
  c->t[c->count++] = t;
  return 0;
}

static void test_sample_steps(void **state) {
  (void)state;
  cup_lcs *L = case_lcs(1);
  cup_input *u = case_input(1);
  double x0[3] = {0, 0, 0};
  const long cases[][2] = {{1000, 10001}, {997, 10001}, {1000, 11}, {12, 5}, {3, 11}, {7, 7}, {4096, 1025}};
  for (int c = 0; c < 7; c++) {
    long n = cases[c][0], S = cases[c][1];
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.n = n; o.T = 3;
    o.scheme = CUP_SCHEME_THETA;                   /* (stable at n = 3) */
    o.output = CUP_OUTPUT_SAMPLES;
    o.output_samples = S;
    cup_integrator *I = NULL;
    assert_int_equal(cup_integrator_create(&I, L, u, &o, NULL), CUP_OK);
    grid_ctx g = {0, malloc(sizeof(long) * (size_t)S), malloc(sizeof(double) * (size_t)S)};
    cup_run_info info;
    assert_int_equal(cup_integrator_run(I, x0, grid_sink, &g, &info), CUP_OK);
    assert_int_equal(g.count, S);
    double h = 3.0 / (double)n;
    for (long j = 0; j < S; j++) {
      long k = (j * n + S - 2) / (S - 1);          /* ceil(j n / (S - 1)) */
      double tau = j == S - 1 ? 3.0 : 3.0 * (double)j / (double)(S - 1);
      assert_int_equal(g.k[j], k);
      if (j * n % (S - 1) == 0) assert_true(g.t[j] == (k == n ? 3.0 : (double)k * h));
      else assert_true(g.t[j] == tau);
    }
    free(g.k);
    free(g.t);
    cup_integrator_free(&I);
  }
  cup_input_free(&u);
  cup_lcs_free(&L);
}

static void test_schedules(void **state) {
  (void)state;
  cup_schedule s;
  char msg[CUP_ERRMSG_LEN], buf[64];
  assert_int_equal(cup_schedule_parse("n^-2.1", &s, msg), CUP_OK);
  assert_close(cup_schedule_value(&s, 1000), pow(1000, -2.1), 1e-30);
  assert_int_equal(cup_schedule_parse(" 0.5 * n^-1.05 ", &s, msg), CUP_OK);
  assert_close(cup_schedule_value(&s, 100), 0.5 * pow(100, -1.05), 1e-18);
  cup_schedule_format(&s, buf, sizeof buf);
  assert_string_equal(buf, "0.5*n^-1.05");
  assert_int_equal(cup_schedule_parse("n^-2.1", &s, msg), CUP_OK);
  cup_schedule_format(&s, buf, sizeof buf);
  assert_string_equal(buf, "n^-2.1");           /* the shortest text that reads back */
  assert_int_equal(cup_schedule_parse("3e-7", &s, msg), CUP_OK);
  assert_close(cup_schedule_value(&s, 12345), 3e-7, 0);
  static const char *bad[] = {"", "n^", "x^2", "1e-3 n", "n^-2.1x", "-1", "nan", "2*", NULL};
  for (int k = 0; bad[k]; k++) {
    assert_int_equal(cup_schedule_parse(bad[k], &s, msg), CUP_ERR_PARSE);
    assert_non_null(strstr(msg, "schedule"));
  }
  assert_int_equal(cup_scheme_parse("implicit"), CUP_SCHEME_IMPLICIT);
  assert_int_equal(cup_scheme_parse("theta"), CUP_SCHEME_THETA);
  assert_int_equal(cup_scheme_parse("rk4"), -1);
}

/* A callback that fails at t > 0.5: the run stops there, says where, and every
 * state before was delivered. */
static int f_fails_late(double t, const double *x, double *f, void *ctx) {
  (void)x; (void)ctx;
  f[0] = f[1] = f[2] = 0;
  return t > 0.5 ? 1 : 0;
}

static void test_errors_say_where(void **state) {
  (void)state;
  cup_lcs *L = case_lcs(1);
  cup_input *u = case_input(1);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = 1000;
  o.f = f_fails_late;
  o.f_order = 1;                                 /* node at the step's midpoint */
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, L, u, &o, NULL), CUP_OK);
  count_ctx cc = {0};
  cup_run_info info;
  double x0[3] = {0, 0, 0};
  assert_int_equal(cup_integrator_run(I, x0, count_sink, &cc, &info), CUP_ERR_CALLBACK);
  /* the step [0.5, 0.501] has its node at 0.5005 > 0.5: step 501 fails */
  assert_int_equal(info.step, 500);
  assert_non_null(strstr(info.message, "step 501"));
  assert_non_null(strstr(info.message, "t = 0.501"));
  assert_int_equal(cc.count, 501);               /* states 0..500 delivered */
  assert_int_equal(cc.last_k, 500);
  cup_integrator_free(&I);
  double bad[3] = {0, NAN, 0};
  o.f = NULL;
  assert_int_equal(cup_integrator_create(&I, L, u, &o, NULL), CUP_OK);
  assert_int_equal(cup_integrator_run(I, bad, NULL, NULL, &info), CUP_ERR_NONFINITE);
  assert_non_null(strstr(info.message, "x0[1]"));
  cup_integrator_free(&I);
  char msg[CUP_ERRMSG_LEN];
  o.T = -1;
  assert_int_equal(cup_integrator_create(&I, L, u, &o, msg), CUP_ERR_ARG);
  assert_non_null(strstr(msg, "T = -1"));
  assert_null(I);
  cup_input_free(&u);
  cup_lcs_free(&L);
}

/* An empty K(t) at one step: x >= u(t) and x <= 0 with u a table rising to 1
 * at t = 0.5: the run stops at the first step with u > 0, with a Farkas
 * certificate, after delivering every earlier state. */
static void test_empty_set_at_a_step(void **state) {
  (void)state;
  double C[2] = {1, -1}, G[2] = {-1, 0};
  lcs_built b;
  build(&b, 1, 2, 1, NULL, NULL, C, NULL, NULL, G, NULL);
  cup_input *u = NULL;
  cup_input_create(&u, 1, NULL);
  double tt[3] = {0, 0.5, 0.6}, vv[3] = {-1, 0, 1};
  cup_wave w = {.kind = CUP_WAVE_PWL, .npoints = 3, .t = tt, .v = vv};
  cup_input_add(u, 0, &w, NULL);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = 100;
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, b.L, u, &o, NULL), CUP_OK);
  count_ctx cc = {0};
  cup_run_info info;
  double x0[1] = {-0.5};
  assert_int_equal(cup_integrator_run(I, x0, count_sink, &cc, &info), CUP_ERR_EMPTY_SET);
  assert_int_equal(info.step, 50);               /* u(0.51) = 0.1 > 0: step 51 fails */
  assert_non_null(strstr(info.message, "step 51"));
  assert_non_null(strstr(info.message, "Farkas"));
  assert_int_equal(cc.count, 51);
  cup_integrator_free(&I);
  cup_input_free(&u);
  unbuild_lcs(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_paper_cases_exact_projection),
    cmocka_unit_test(test_paper_tolerances),
    cmocka_unit_test(test_theta_scheme),
    cmocka_unit_test(test_theta_many_rows),
    cmocka_unit_test(test_closed_form_moving_interval),
    cmocka_unit_test(test_closed_form_interval_with_relaxation),
    cmocka_unit_test(test_closed_form_cone),
    cmocka_unit_test(test_closed_form_rectifier),
    cmocka_unit_test(test_closed_form_corner),
    cmocka_unit_test(test_closed_form_jumping_set),
    cmocka_unit_test(test_stiff_rectifier),
    cmocka_unit_test(test_output_modes_and_exact_time),
    cmocka_unit_test(test_sample_steps),
    cmocka_unit_test(test_schedules),
    cmocka_unit_test(test_errors_say_where),
    cmocka_unit_test(test_empty_set_at_a_step),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
