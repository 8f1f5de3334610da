/* process: general sweeping processes x' in -N(C(t); x) + f(t, x) through
 * cup_integrator_create_process, against solutions derived by hand
 * (docs/closed-forms.md, "General sweeping processes"): a disc dragging a
 * point (the tractrix), a disc rotating on a circle (psi' = -(1 + k cos
 * psi)), the play operator on a triangle input, a state-dependent half-line,
 * a nonlinear f; each at first order (error n constant to 5% over a decade).
 * A user oracle gives the built-in ball's trajectory to rounding, and errors
 * (an oracle's NaN or lie, a negative radius) stop the run at the right step
 * with the states before it kept. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"

typedef double (*exact_fn)(double t, int i, const void *par);

typedef struct {
  exact_fn exact;
  const void *par;
  int dim;
  double err;            /* max over grid points and components */
  long count;
  double *traj;          /* optional: every state, (n + 1) x dim */
} err_ctx;

static int err_sink(long k, double t, const double *x, void *vp) {
  err_ctx *c = vp;
  for (int i = 0; i < c->dim; i++) {
    if (c->exact) c->err = fmax(c->err, fabs(x[i] - c->exact(t, i, c->par)));
    if (c->traj) c->traj[k * c->dim + i] = x[i];
  }
  c->count++;
  return 0;
}

/* Run the process at n steps with exact projections; returns the max error. */
static double run_error(const cup_process_desc *d, double T, long n, const double *x0, exact_fn exact,
                        const void *par, cup_run_info *info) {
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = T;
  o.n = n;
  o.eps = (cup_schedule){0, 0};
  o.eta = (cup_schedule){0, 0};
  cup_integrator *I;
  char err[CUP_ERRMSG_LEN];
  if (cup_integrator_create_process(&I, d, &o, err)) fail_msg("create: %s", err);
  err_ctx c = {exact, par, d->n, 0, 0, NULL};
  int st = cup_integrator_run(I, x0, err_sink, &c, info);
  if (st < 0) fail_msg("run: %s: %s", cup_status_name(st), info->message);
  assert_int_equal(c.count, n + 1);
  cup_integrator_free(&I);
  return c.err;
}

/* error n at n and 10 n agree to 5%: first order, already in its regime */
static void assert_first_order(const char *what, double e1, long n1, double e2, long n2) {
  double a = e1 * (double)n1, b = e2 * (double)n2;
  printf("  %s: error*n = %.4f (n = %ld), %.4f (n = %ld): order %.3f\n", what, a, n1, b, n2,
         log(e1 / e2) / log((double)n2 / (double)n1));
  if (!(fabs(a / b - 1) <= 0.05)) fail_msg("%s: error*n %.4g vs %.4g differ by more than 5%%", what, a, b);
}

/* A ball (in 2-D) whose centre moves with u through Gc = rad_c I. */
static cup_set *ball2(double r, double cscale, int p, tcsc *Gc) {
  double G[4] = {cscale, 0, 0, cscale};
  tcsc_from_dense(Gc, G, 2, p);
  cup_set_desc d = {.kind = CUP_SET_BALL, .n = 2, .p = p, .Gc = Gc->view, .radius = r};
  cup_set *S;
  char err[CUP_ERRMSG_LEN];
  if (cup_set_create(&S, &d, err)) fail_msg("ball: %s", err);
  return S;
}

/* ---- the tractrix ------------------------------------------------------------------- */

/* c(t) = (v t, 0), radius r, x0 = (0, r): the point is dragged along the
 * tractrix x(t) = (v t - r tanh(v t / r), r sech(v t / r)). */
typedef struct { double v, r; } drag_par;

static double tractrix(double t, int i, const void *vp) {
  const drag_par *q = vp;
  double s = q->v * t / q->r;
  return i == 0 ? q->v * t - q->r * tanh(s) : q->r / cosh(s);
}

static double tractrix_error(long n, cup_set *S, const cup_input *u, double *x0) {
  drag_par q = {1, 1};
  cup_process_desc d = {.n = 2, .p = 1, .C = S, .u = u};
  cup_run_info info;
  return run_error(&d, 3, n, x0, tractrix, &q, &info);
}

static cup_input *ramp_input(double T, double v) {
  cup_input *u;
  char err[CUP_ERRMSG_LEN];
  double tp[2] = {0, T}, vp[2] = {0, v * T};
  cup_wave w = {.kind = CUP_WAVE_PWL, .npoints = 2, .t = tp, .v = vp};
  assert_int_equal(cup_input_create(&u, 1, err), CUP_OK);
  assert_int_equal(cup_input_add(u, 0, &w, err), CUP_OK);
  return u;
}

static void test_tractrix(void **state) {
  (void)state;
  tcsc Gc;
  cup_set *S = ball2(1, 1, 1, &Gc);
  cup_input *u = ramp_input(3, 1);
  double x0[2] = {0, 1};
  double e1 = tractrix_error(1000, S, u, x0), e2 = tractrix_error(10000, S, u, x0);
  assert_first_order("tractrix", e1, 1000, e2, 10000);
  cup_input_free(&u);
  cup_set_free(&S);
  tcsc_free(&Gc);
}

/* ---- the rotating disc ---------------------------------------------------------------- */

/* c(t) = R (cos wt, sin wt), radius r, k = R / r > 1, x0 = (R, -r). With
 * x = c + r (cos th, sin th) and psi = th - wt in contact:
 * dpsi/d(wt) = -(1 + k cos psi), solved by tan(psi/2) =
 * a tanh(artanh(tan(psi0/2)/a) - beta w t / 2), a = sqrt((k+1)/(k-1)),
 * beta = sqrt(k^2 - 1); psi0 = -pi/2, and psi falls to the lagging steady
 * angle acos(-1/k). */
typedef struct { double R, r, w; } rot_par;

static double rotating(double t, int i, const void *vp) {
  const rot_par *q = vp;
  double k = q->R / q->r, a = sqrt((k + 1) / (k - 1)), beta = sqrt(k * k - 1);
  double tau = q->w * t;
  double psi = 2 * atan(a * tanh(atanh(-1 / a) - 0.5 * beta * tau));
  double th = tau + psi;
  return i == 0 ? q->R * cos(tau) + q->r * cos(th) : q->R * sin(tau) + q->r * sin(th);
}

static void test_rotating_disc(void **state) {
  (void)state;
  rot_par q = {2, 1, 1};
  tcsc Gc;
  cup_set *S = ball2(q.r, q.R, 2, &Gc);
  cup_input *u;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_input_create(&u, 2, err), CUP_OK);
  double f = q.w / (2 * M_PI);
  cup_wave cw = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = f, .phase = M_PI / 2};
  cup_wave sw = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = f};
  assert_int_equal(cup_input_add(u, 0, &cw, err), CUP_OK);
  assert_int_equal(cup_input_add(u, 1, &sw, err), CUP_OK);
  cup_process_desc d = {.n = 2, .p = 2, .C = S, .u = u};
  double x0[2] = {q.R, -q.r};
  cup_run_info info;
  double e1 = run_error(&d, 6, 1000, x0, rotating, &q, &info);
  double e2 = run_error(&d, 6, 10000, x0, rotating, &q, &info);
  assert_first_order("rotating disc", e1, 1000, e2, 10000);
  cup_input_free(&u);
  cup_set_free(&S);
  tcsc_free(&Gc);
}

/* ---- the play operator ------------------------------------------------------------------ */

/* C(t) = [u(t) - 1/4, u(t) + 1/4], u the triangle through (0, 0), (1/3, 1),
 * (1, -1/3), x0 = 0: x = 0 until 1/12, u - 1/4 until 1/3, 3/4 until 7/12,
 * u + 1/4 after. The scheme misses the peak between grid points: with n = 1
 * mod 3 the last grid point before it is h/3 early, so the plateau is low by
 * exactly 3 h/3 = h (error n = 1). */
static double play(double t, int i, const void *vp) {
  (void)i; (void)vp;
  if (t <= 1.0 / 12) return 0;
  if (t <= 1.0 / 3) return 3 * t - 0.25;
  if (t <= 7.0 / 12) return 0.75;
  return 1 - 2 * (t - 1.0 / 3) + 0.25;
}

static void test_play_operator(void **state) {
  (void)state;
  double one = 1, tp[3] = {0, 1.0 / 3, 1}, vp[3] = {0, 1, -1.0 / 3};
  tcsc Gc;
  tcsc_from_dense(&Gc, &one, 1, 1);
  cup_set_desc sd = {.kind = CUP_SET_BALL, .n = 1, .p = 1, .Gc = Gc.view, .radius = 0.25};
  cup_set *S;
  cup_input *u;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_wave w = {.kind = CUP_WAVE_PWL, .npoints = 3, .t = tp, .v = vp};
  assert_int_equal(cup_input_create(&u, 1, err), CUP_OK);
  assert_int_equal(cup_input_add(u, 0, &w, err), CUP_OK);
  cup_process_desc d = {.n = 1, .p = 1, .C = S, .u = u};
  double x0 = 0;
  cup_run_info info;
  double e1 = run_error(&d, 1, 1000, &x0, play, NULL, &info);
  double e2 = run_error(&d, 1, 10000, &x0, play, NULL, &info);
  assert_first_order("play operator", e1, 1000, e2, 10000);
  assert_close(e1 * 1000, 1, 1e-9);
  cup_input_free(&u);
  cup_set_free(&S);
  tcsc_free(&Gc);
}

/* ---- a state-dependent half-line ------------------------------------------------------- */

/* C(t, x) = {y : y >= t + x/2}: in contact x = t + x/2, so x(t) = 2t (from
 * x0 = 0). The step projects onto C(t_{k+1}, x_k): x_{k+1} = t_{k+1} + x_k/2,
 * whose lag settles at x_k = 2 t_k - 2h: error n -> 2T. */
static int halfline_rows(double t, const double *x, cup_rowbuf *rows, void *ctx) {
  (void)ctx;
  int col = 0;
  double one = 1;
  return cup_rowbuf_add(rows, 1, &col, &one, -(t + 0.5 * x[0]));
}

static double twice_t(double t, int i, const void *vp) { (void)i; (void)vp; return 2 * t; }

static void test_state_dependent_halfline(void **state) {
  (void)state;
  cup_set_desc sd = {.kind = CUP_SET_STATE_POLYSET, .n = 1, .rows = halfline_rows};
  cup_set *S;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_process_desc d = {.n = 1, .C = S};
  double x0 = 0;
  cup_run_info info;
  double e1 = run_error(&d, 1, 1000, &x0, twice_t, NULL, &info);
  assert_int_equal(info.set_rebuilds, 1);     /* one pattern: analysed at t = 0, reused since */
  assert_int_equal(info.max_rows, 1);
  double e2 = run_error(&d, 1, 10000, &x0, twice_t, NULL, &info);
  assert_first_order("state-dependent half-line", e1, 1000, e2, 10000);
  assert_close(e1 * 1000, 2, 1e-6);
  cup_set_free(&S);
}

/* ---- f: a nonlinear callback, an exact integral ----------------------------------------- */

/* x' = -x^3 inside a ball it never reaches: x = x0 / sqrt(1 + 2 x0^2 t);
 * explicit Euler's error is first order. */
static int cubic(double t, const double *x, double *f, void *ctx) {
  (void)t; (void)ctx;
  f[0] = -x[0] * x[0] * x[0];
  return 0;
}

static double cubic_exact(double t, int i, const void *vp) {
  (void)i; (void)vp;
  return 1 / sqrt(1 + 2 * t);
}

/* f = (cos t, 0) by its exact integral: the scheme is exact at grid points. */
static int cos_integral(double t0, double t1, const double *x, double *F, void *ctx) {
  (void)x; (void)ctx;
  F[0] = sin(t1) - sin(t0);
  F[1] = 0;
  return 0;
}

static double sin_exact(double t, int i, const void *vp) { (void)vp; return i == 0 ? sin(t) : 0.5; }

static void test_nonlinear_f_and_exact_integral(void **state) {
  (void)state;
  double c0[2] = {0, 0};
  cup_set_desc sd = {.kind = CUP_SET_BALL, .n = 1, .center = c0, .radius = 10};
  cup_set *S;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_process_desc d = {.n = 1, .C = S, .f = cubic};
  double x0 = 1;
  cup_run_info info;
  double e1 = run_error(&d, 2, 1000, &x0, cubic_exact, NULL, &info);
  double e2 = run_error(&d, 2, 10000, &x0, cubic_exact, NULL, &info);
  assert_first_order("x' = -x^3", e1, 1000, e2, 10000);
  cup_set_free(&S);
  sd.n = 2;
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_process_desc d2 = {.n = 2, .C = S, .f_integral = cos_integral};
  double y0[2] = {0, 0.5};
  double e = run_error(&d2, 10, 777, y0, sin_exact, NULL, &info);
  assert_true(e <= 1e-13);
  cup_set_free(&S);
}

/* ---- an oracle gives the built-in ball's trajectory ----------------------------------------- */

typedef struct { double r; const cup_input *u; int nan_at_call, lie; int calls; } disc_oracle_ctx;

/* The projection onto the disc of radius r at c(t) = (u(t), 0), as the
 * built-in ball computes it (the same formula, a few ulps inside). */
static int disc_oracle(double t, const double *x, double eps, double eta, double *z,
                       double *eps_cert, double *eta_cert, void *vp) {
  (void)eps; (void)eta;
  disc_oracle_ctx *o = vp;
  double c[1];
  cup_input_eval(o->u, t, c);
  double v0 = x[0] - c[0], v1 = x[1], d = sqrt(v0 * v0 + v1 * v1);
  double s = d <= o->r ? 1 : o->r * (1 - 4 * (2 + 8) * DBL_EPSILON) / d;
  z[0] = d <= o->r ? x[0] : c[0] + s * v0;
  z[1] = d <= o->r ? x[1] : s * v1;
  *eps_cert = 1e-30;
  *eta_cert = 0;
  o->calls++;
  if (o->nan_at_call && o->calls == o->nan_at_call) z[0] = NAN;
  if (o->lie && o->calls > o->lie && o->calls % 2 && d > o->r) z[1] += 0.01;   /* outside, eta claimed 0 */
  return 0;
}

static int count_sink(long k, double t, const double *x, void *vp) {
  (void)t; (void)x;
  long *last = vp;
  *last = k;
  return 0;
}

static void test_oracle_matches_builtin_ball(void **state) {
  (void)state;
  tcsc Gc;
  cup_set *B = ball2(1, 1, 1, &Gc);
  cup_input *u = ramp_input(3, 1);
  disc_oracle_ctx oc = {1, u, 0, 0, 0};
  cup_set_desc od = {.kind = CUP_SET_ORACLE, .n = 2, .oracle = disc_oracle, .oracle_ctx = &oc};
  cup_set *O;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_set_create(&O, &od, err), CUP_OK);
  long n = 2000;
  double *tb = calloc((size_t)(n + 1) * 2, sizeof(double)), *to = calloc((size_t)(n + 1) * 2, sizeof(double));
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 3;
  o.n = n;
  double x0[2] = {0, 1};
  cup_process_desc db = {.n = 2, .p = 1, .C = B, .u = u}, dor = {.n = 2, .p = 1, .C = O, .u = u};
  cup_integrator *I;
  cup_run_info info;
  err_ctx cb = {NULL, NULL, 2, 0, 0, tb}, co = {NULL, NULL, 2, 0, 0, to};
  assert_int_equal(cup_integrator_create_process(&I, &db, &o, err), CUP_OK);
  assert_int_equal(cup_integrator_run(I, x0, err_sink, &cb, &info), CUP_OK);
  cup_integrator_free(&I);
  assert_int_equal(cup_integrator_create_process(&I, &dor, &o, err), CUP_OK);
  assert_int_equal(cup_integrator_run(I, x0, err_sink, &co, &info), CUP_OK);
  assert_true(info.max_eps_cert == 1e-30);     /* the oracle's claims, reported */
  double diff = 0;
  for (long q = 0; q < 2 * (n + 1); q++) diff = fmax(diff, fabs(tb[q] - to[q]));
  printf("  oracle vs built-in ball: max difference %.3g over %ld steps\n", diff, n);
  assert_true(diff <= 1e-14);
  cup_integrator_free(&I);
  /* a NaN at the 101st call (step 50: two calls a step, two for x0): an
   * error naming the step, the 49 states before it kept */
  oc.nan_at_call = 101;
  oc.calls = 0;
  long last = -1;
  assert_int_equal(cup_integrator_create_process(&I, &dor, &o, err), CUP_OK);
  assert_int_equal(cup_integrator_run(I, x0, count_sink, &last, &info), CUP_ERR_CALLBACK);
  printf("  an oracle returning NaN: %s\n", info.message);
  assert_non_null(strstr(info.message, "step 50 (t = 0.0749999"));
  assert_non_null(strstr(info.message, "z[0] = nan"));
  assert_int_equal(last, 49);
  cup_integrator_free(&I);
  /* a point outside the disc, claimed to be in it: caught by its re-projection */
  oc.nan_at_call = 0;
  oc.lie = 300;
  oc.calls = 0;
  assert_int_equal(cup_integrator_create_process(&I, &dor, &o, err), CUP_OK);
  assert_int_equal(cup_integrator_run(I, x0, count_sink, &last, &info), CUP_ERR_CALLBACK);
  assert_non_null(strstr(info.message, "farther than its claims allow"));
  printf("  a lying oracle: %s\n", info.message);
  cup_integrator_free(&I);
  free(tb);
  free(to);
  cup_set_free(&O);
  cup_set_free(&B);
  cup_input_free(&u);
  tcsc_free(&Gc);
}

static void test_radius_turning_negative_stops_the_run(void **state) {
  (void)state;
  double gr[1] = {-1}, c[2] = {0, 0};
  cup_set_desc sd = {.kind = CUP_SET_BALL, .n = 2, .p = 1, .center = c, .radius = 1, .gr = gr};
  cup_set *S;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_input *u = ramp_input(2, 1);                /* r(t) = 1 - t: empty after t = 1 */
  cup_process_desc d = {.n = 2, .p = 1, .C = S, .u = u};
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 2;
  o.n = 8;
  cup_integrator *I;
  assert_int_equal(cup_integrator_create_process(&I, &d, &o, err), CUP_OK);
  double x0[2] = {0.5, 0};
  long last = -1;
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, x0, count_sink, &last, &info), CUP_ERR_EMPTY_SET);
  assert_non_null(strstr(info.message, "step 5 (t = 1.25)"));
  assert_non_null(strstr(info.message, "radius r(t) = -0.25"));
  assert_int_equal(last, 4);
  cup_integrator_free(&I);
  /* the theta scheme needs a polyset */
  o.scheme = CUP_SCHEME_THETA;
  assert_int_equal(cup_integrator_create_process(&I, &d, &o, err), CUP_ERR_UNSUPPORTED);
  assert_non_null(strstr(err, "the set is a ball"));
  /* {x_1 >= 0} and the unit disc at (-u(t), 0), u = t: apart once t > 1 */
  double C[2] = {1, 0}, Gc[2] = {-1, 0};
  tcsc Cs, Gcs;
  tcsc_from_dense(&Cs, C, 1, 2);
  tcsc_from_dense(&Gcs, Gc, 2, 1);
  cup_set_desc bd = {.kind = CUP_SET_INTERSECTION, .n = 2, .p = 1, .C = Cs.view, .center = c,
                     .Gc = Gcs.view, .radius = 1};
  cup_set *B;
  assert_int_equal(cup_set_create(&B, &bd, err), CUP_OK);
  cup_process_desc db = {.n = 2, .p = 1, .C = B, .u = u};
  o.scheme = CUP_SCHEME_EXPLICIT;
  assert_int_equal(cup_integrator_create_process(&I, &db, &o, err), CUP_OK);
  double y0[2] = {0.25, 0};
  /* at t = 1 (step 4) they touch in one point, which no point is certainly
   * in: no answer can be certified, and the run stops there (main stored a
   * stale point with a warning, issue 27); from 1.25 on they are apart */
  assert_int_equal(cup_integrator_run(I, y0, count_sink, &last, &info), CUP_ERR_UNCERTIFIED);
  assert_non_null(strstr(info.message, "step 4 (t = 1)"));
  assert_non_null(strstr(info.message, "no point certainly in both"));
  assert_int_equal(last, 3);
  /* apart: on a grid that skips the touching */
  cup_integrator_free(&I);
  o.n = 7;
  o.T = 2.1;                             /* h = 0.3: 0.9, then 1.2 */
  assert_int_equal(cup_integrator_create_process(&I, &db, &o, err), CUP_OK);
  assert_int_equal(cup_integrator_run(I, y0, count_sink, &last, &info), CUP_ERR_EMPTY_SET);
  assert_non_null(strstr(info.message, "step 4 (t = 1.2"));
  assert_non_null(strstr(info.message, "do not meet"));
  assert_int_equal(last, 3);
  cup_integrator_free(&I);
  cup_set_free(&B);
  tcsc_free(&Cs);
  tcsc_free(&Gcs);
  cup_input_free(&u);
  cup_set_free(&S);
}

/* The state and zeta (m entries) of each sample, by step. */
typedef struct {
  const cup_integrator *I;
  int dim, m;
  double *x, *z;
} zeta_rec;

static int zeta_sink(long k, double t, const double *x, void *vp) {
  (void)t;
  zeta_rec *r = vp;
  memcpy(r->x + k * r->dim, x, sizeof(double) * (size_t)r->dim);
  return cup_integrator_zeta(r->I, r->z + k * r->m) != CUP_OK;
}

/* A polyset process is the LCS path: same trajectory and zeta as the LCS
 * itself (its normal cone is P^-1 C^T zeta, the LCS's B zeta). */
static void test_polyset_process_is_the_lcs(void **state) {
  (void)state;
  cup_circuit c = {1, 2, 1, 1, 2, 1, {0, 1}};
  cup_lcs *L;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_lcs_circuit(&L, &c, err), CUP_OK);
  cup_input *u;
  assert_int_equal(cup_input_create(&u, 1, err), CUP_OK);
  cup_wave w = {.kind = CUP_WAVE_SQUARE, .amplitude = 1, .frequency = 2};
  assert_int_equal(cup_input_add(u, 0, &w, err), CUP_OK);
  /* the same model as a set and a drift */
  double A[9] = {0, 1, 0, -0.5, -1, 0.5, 0, 1, -3}, C[6] = {0, 1, -1, 0, 1, 0};
  double E[3] = {0, 0.5, 1}, G[2] = {0, 1}, Pd[3] = {1, 2, 1};
  tcsc As, Cs, Es, Gs;
  tcsc_from_dense(&As, A, 3, 3);
  tcsc_from_dense(&Cs, C, 2, 3);
  tcsc_from_dense(&Es, E, 3, 1);
  tcsc_from_dense(&Gs, G, 2, 1);
  cup_set_desc sd = {.kind = CUP_SET_POLYSET, .n = 3, .p = 1, .C = Cs.view, .G = Gs.view,
                     .P = {CUP_METRIC_DIAGONAL, Pd, {0}, 0}};
  cup_set *S;
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_process_desc d = {.n = 3, .p = 1, .C = S, .u = u, .A = As.view, .E = Es.view};
  for (int scheme = 0; scheme < CUP_SCHEME_COUNT; scheme++) {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.n = 500;
    o.scheme = scheme;
    long n = o.n;
    size_t N = (size_t)(n + 1) * 3, M = (size_t)(n + 1) * 2;
    zeta_rec ra = {NULL, 3, 2, calloc(N, sizeof(double)), calloc(M, sizeof(double))};
    zeta_rec rb = {NULL, 3, 2, calloc(N, sizeof(double)), calloc(M, sizeof(double))};
    cup_integrator *I;
    cup_run_info ia, ib;
    double x0[3] = {0, 0, 0};
    assert_int_equal(cup_integrator_create(&I, L, u, &o, err), CUP_OK);
    ra.I = I;
    cup_integrator_run(I, x0, zeta_sink, &ra, &ia);
    cup_integrator_free(&I);
    assert_int_equal(cup_integrator_create_process(&I, &d, &o, err), CUP_OK);
    rb.I = I;
    cup_integrator_run(I, x0, zeta_sink, &rb, &ib);
    cup_integrator_free(&I);
    assert_int_equal(ia.status, ib.status);
    assert_int_equal(ia.samples, ib.samples);
    for (size_t q = 0; q < N; q++)
      if (ra.x[q] != rb.x[q])
        fail_msg("%s: entry %zu differs: %.17g vs %.17g", cup_scheme_name(scheme), q, ra.x[q], rb.x[q]);
    double zmax = 0;
    for (size_t q = 0; q < M; q++) {
      if (ra.z[q] != rb.z[q])
        fail_msg("%s: zeta entry %zu differs: %.17g vs %.17g", cup_scheme_name(scheme), q, ra.z[q], rb.z[q]);
      zmax = fmax(zmax, fabs(ra.z[q]));
    }
    if (!(zmax > 0.1)) fail_msg("%s: the diodes never conduct (max zeta %g)", cup_scheme_name(scheme), zmax);
    free(ra.x); free(ra.z); free(rb.x); free(rb.z);
  }
  cup_set_free(&S);
  tcsc_free(&As); tcsc_free(&Cs); tcsc_free(&Es); tcsc_free(&Gs);
  cup_input_free(&u);
  cup_lcs_free(&L);
}

/* The samples in order: time, state (1-D) and zeta (1 row). */
typedef struct {
  const cup_integrator *I;
  int count;
  double t[64], x[64], z[64];
} line_rec;

static int line_sink(long k, double t, const double *x, void *vp) {
  (void)k;
  line_rec *r = vp;
  if (r->count == 64) return 1;
  r->t[r->count] = t;
  r->x[r->count] = x[0];
  return cup_integrator_zeta(r->I, &r->z[r->count++]) != CUP_OK;
}

/* zeta of a process: on the half-line {x >= 0} with x' = u = -1 from
 * x0 = 1/2, x reaches 0 at t = 1/2 and stays there, held by the
 * multiplier of x' = u + zeta = 0: zeta = 0 before, 1 after, under every
 * scheme. A ball has no rows to give multipliers of: CUP_ERR_UNSUPPORTED. */
static void test_zeta_of_a_process(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  double one = 1;
  tcsc Cs, Es;
  tcsc_from_dense(&Cs, &one, 1, 1);
  tcsc_from_dense(&Es, &one, 1, 1);
  cup_set_desc sd = {.kind = CUP_SET_POLYSET, .n = 1, .C = Cs.view};
  cup_set *S;
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_input *u;
  cup_wave w = {.kind = CUP_WAVE_CONSTANT, .value = -1};
  assert_int_equal(cup_input_create(&u, 1, err), CUP_OK);
  assert_int_equal(cup_input_add(u, 0, &w, err), CUP_OK);
  cup_process_desc d = {.n = 1, .p = 1, .C = S, .u = u, .E = Es.view};
  double x0 = 0.5;
  for (int scheme = 0; scheme < CUP_SCHEME_COUNT; scheme++) {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.n = 10;
    o.scheme = scheme;
    cup_integrator *I;
    assert_int_equal(cup_integrator_create_process(&I, &d, &o, err), CUP_OK);
    line_rec r = {.I = I};
    cup_run_info info;
    int st = cup_integrator_run(I, &x0, line_sink, &r, &info);
    if (st < 0) fail_msg("%s: %s", cup_scheme_name(scheme), info.message);
    int before = 0, after = 0;
    for (int j = 0; j < r.count; j++) {
      if (r.t[j] <= 0.45) {
        before++;
        if (r.z[j] != 0) fail_msg("%s: zeta(%g) = %.17g before the contact", cup_scheme_name(scheme), r.t[j], r.z[j]);
      } else if (r.t[j] >= 0.65) {
        after++;
        if (!(fabs(r.z[j] - 1) <= 1e-12) || !(fabs(r.x[j]) <= 1e-12))
          fail_msg("%s: at t = %g x = %.3g, zeta = %.17g (1 on the boundary)", cup_scheme_name(scheme), r.t[j],
                   r.x[j], r.z[j]);
      }
    }
    if (before < 2 || after < 1) fail_msg("%s: %d samples before, %d after", cup_scheme_name(scheme), before, after);
    cup_integrator_free(&I);
  }
  /* the unit disc: no rows */
  double c[1] = {0};
  cup_set_desc bd = {.kind = CUP_SET_BALL, .n = 1, .center = c, .radius = 1};
  cup_set *B;
  assert_int_equal(cup_set_create(&B, &bd, err), CUP_OK);
  cup_process_desc db = {.n = 1, .C = B};
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  cup_integrator *I;
  assert_int_equal(cup_integrator_create_process(&I, &db, &o, err), CUP_OK);
  line_rec r = {.I = I};
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, &x0, line_sink, &r, &info), CUP_ERR_INTERRUPTED);   /* the sink stops */
  double z = -1;
  assert_int_equal(cup_integrator_zeta(I, &z), CUP_ERR_UNSUPPORTED);
  assert_true(z == -1);
  cup_integrator_free(&I);
  cup_set_free(&B);
  cup_input_free(&u);
  cup_set_free(&S);
  tcsc_free(&Cs);
  tcsc_free(&Es);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_tractrix),
    cmocka_unit_test(test_rotating_disc),
    cmocka_unit_test(test_play_operator),
    cmocka_unit_test(test_state_dependent_halfline),
    cmocka_unit_test(test_nonlinear_f_and_exact_integral),
    cmocka_unit_test(test_oracle_matches_builtin_ball),
    cmocka_unit_test(test_radius_turning_negative_stops_the_run),
    cmocka_unit_test(test_polyset_process_is_the_lcs),
    cmocka_unit_test(test_zeta_of_a_process),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
