/* scene_set: scenes with set: and f: (the examples), run through
 * cup_scene_integrator, against closed forms (docs/closed-forms.md) and
 * against the same process built through the C API or as an LCS:
 *  - tractrix.yaml and rotating-disc.yaml: the closed forms, first order;
 *  - interval-relaxation.yaml (a ball in 1-D, f = -x) gives the trajectory
 *    of the same problem as an LCS (two rows, G u = sin t) to rounding;
 *  - walker.yaml: every state in the room, no step longer than h * speed
 *    (the projection onto a convex set that holds x_k moves no point away
 *    from x_k), and the C API with the test's own `towards` callback gives
 *    the same trajectory to 1e-12;
 *  - an ellipsoid, a half-space and a polyset with moving offsets. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"

#define EX CUP_EXAMPLES_DIR

typedef struct {
  long n;
  int dim;
  double *traj;          /* (n + 1) x dim */
} traj_ctx;

static int keep(long k, double t, const double *x, void *vp) {
  (void)t;
  traj_ctx *c = vp;
  memcpy(c->traj + k * c->dim, x, sizeof(double) * (size_t)c->dim);
  return 0;
}

/* Load, run with output every step; returns the trajectory (caller frees). */
static double *run_scene(const char *path, const char *const *ovr, int nov, long *n, int *dim,
                         cup_run_info *info) {
  char err[CUP_ERRMSG_LEN];
  cup_scene *s;
  if (cup_scene_load(&s, path, ovr, nov, err)) fail_msg("%s", err);
  cup_integrator_options o = *cup_scene_options(s);
  o.output = CUP_OUTPUT_EVERY;
  o.output_every = 1;
  cup_integrator *I;
  if (cup_scene_integrator(s, &o, &I, err)) fail_msg("%s", err);
  *n = o.n;
  *dim = cup_scene_dim(s);
  traj_ctx c = {o.n, *dim, calloc((size_t)(o.n + 1) * (size_t)*dim, sizeof(double))};
  int st = cup_integrator_run(I, cup_scene_x0(s), keep, &c, info);
  if (st < 0) fail_msg("%s: %s", cup_status_name(st), info->message);
  cup_integrator_free(&I);
  cup_scene_free(&s);
  return c.traj;
}

static void test_tractrix_scene(void **state) {
  (void)state;
  long n;
  int dim;
  cup_run_info info;
  double *x = run_scene(EX "/tractrix.yaml", NULL, 0, &n, &dim, &info);
  assert_int_equal(dim, 2);
  double err = 0, h = 5.0 / (double)n;
  for (long k = 0; k <= n; k++) {
    double t = (double)k * h;
    err = fmax(err, fmax(fabs(x[2 * k] - (t - tanh(t))), fabs(x[2 * k + 1] - 1 / cosh(t))));
  }
  printf("  tractrix.yaml (n = %ld): error*n/T = %.4f\n", n, err * (double)n / 5);
  /* the C test's error*n is 0.518 for T = 3 (error ~ (T/n) * 0.17); here T = 5 */
  assert_true(err * (double)n / 5 > 0.15 && err * (double)n / 5 < 0.19);
  free(x);
}

static void test_rotating_disc_scene(void **state) {
  (void)state;
  long n;
  int dim;
  cup_run_info info;
  double *x = run_scene(EX "/rotating-disc.yaml", NULL, 0, &n, &dim, &info);
  double k = 2, a = sqrt((k + 1) / (k - 1)), beta = sqrt(k * k - 1), err = 0, h = 12.0 / (double)n;
  for (long q = 0; q <= n; q++) {
    double t = (double)q * h, psi = 2 * atan(a * tanh(atanh(-1 / a) - 0.5 * beta * t)), th = t + psi;
    err = fmax(err, fmax(fabs(x[2 * q] - (2 * cos(t) + cos(th))), fabs(x[2 * q + 1] - (2 * sin(t) + sin(th)))));
  }
  printf("  rotating-disc.yaml (n = %ld): error %.3g, error*n %.4f\n", n, err, err * (double)n);
  /* error*n grows with T until the lag settles: 3.0 at T = 6 (the C test) */
  assert_true(err * (double)n / 12 > 0.45 && err * (double)n / 12 < 0.55);
  free(x);
}

/* The same moving interval as an LCS: C = [1; -1], F = [1/2; 1/2],
 * G = [-1; 1] (K(t) = {|x - sin t| <= 1/2}), A = -1, P = 1. */
static void interval_against_lcs(const char *scheme) {
  long n;
  int dim;
  cup_run_info info;
  char ovr[64];
  snprintf(ovr, sizeof ovr, "scheme=%s", scheme);
  const char *ovrs[1] = {ovr};
  double *x = run_scene(EX "/interval-relaxation.yaml", ovrs, 1, &n, &dim, &info);
  double A[1] = {-1}, C[2] = {1, -1}, F[2] = {0.5, 0.5}, G[2] = {-1, 1};
  tcsc As, Cs, Gs;
  tcsc_from_dense(&As, A, 1, 1);
  tcsc_from_dense(&Cs, C, 2, 1);
  tcsc_from_dense(&Gs, G, 2, 1);
  cup_lcs_desc d = {.n = 1, .m = 2, .p = 1, .A = As.view, .C = Cs.view, .F = F, .G = Gs.view};
  cup_lcs *L;
  cup_input *u;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_lcs_create(&L, &d, err), CUP_OK);
  assert_int_equal(cup_input_create(&u, 1, err), CUP_OK);
  cup_wave w = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = 1 / (2 * M_PI)};
  assert_int_equal(cup_input_add(u, 0, &w, err), CUP_OK);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 4 * M_PI;
  o.n = n;
  o.scheme = (cup_scheme)cup_scheme_parse(scheme);
  cup_integrator *I;
  assert_int_equal(cup_integrator_create(&I, L, u, &o, err), CUP_OK);
  traj_ctx c = {n, 1, calloc((size_t)n + 1, sizeof(double))};
  assert_true(cup_integrator_run(I, (double[]){0}, keep, &c, &info) >= 0);
  double diff = 0;
  for (long k = 0; k <= n; k++) diff = fmax(diff, fabs(x[k] - c.traj[k]));
  printf("  interval-relaxation.yaml (%s) against the LCS: max difference %.3g\n", scheme, diff);
  assert_true(diff <= 1e-14);
  free(c.traj);
  free(x);
  cup_integrator_free(&I);
  cup_input_free(&u);
  cup_lcs_free(&L);
  tcsc_free(&As); tcsc_free(&Cs); tcsc_free(&Gs);
}

/* The free step of each scheme, then the ball's projection or the LCS's. */
static void test_interval_scene_is_the_lcs(void **state) {
  (void)state;
  interval_against_lcs("explicit");
  interval_against_lcs("implicit");
  interval_against_lcs("exponential");
}

/* The walker's f, written here: speed (target - x)/max(|target - x|, slow). */
static int towards(double t, const double *x, double *f, void *ctx) {
  (void)ctx;
  double w = 0.2 * M_PI * t, tx = 4 * sin(w + M_PI / 2), ty = 4 * sin(w);
  double dx = tx - x[0], dy = ty - x[1], d = hypot(dx, dy), s = d > 0 ? 1 / fmax(d, 0.1) : 0;
  f[0] = s * dx;
  f[1] = s * dy;
  return 0;
}

static void test_walker_scene(void **state) {
  (void)state;
  long n;
  int dim;
  cup_run_info info;
  double *x = run_scene(EX "/walker.yaml", NULL, 0, &n, &dim, &info);
  double h = 20.0 / (double)n, worst_out = 0, longest = 0;
  for (long k = 0; k <= n; k++) {
    double a = x[2 * k], b = x[2 * k + 1];
    worst_out = fmax(worst_out, fmax(fmax(-a, -b), hypot(a, b) - 3));
    if (k) longest = fmax(longest, hypot(a - x[2 * k - 2], b - x[2 * k - 1]));
  }
  printf("  walker.yaml: outside the room by at most %.3g, longest step %.6f (h * speed = %.6f)\n",
         worst_out, longest, h);
  assert_true(worst_out <= 0);                 /* answers certainly in the set */
  assert_true(longest <= h * (1 + 1e-12));
  /* the same process through the C API, with this file's f */
  double C[4] = {1, 0, 0, 1}, c0[2] = {0, 0}, off[2] = {0, 0};
  tcsc Cs;
  tcsc_from_dense(&Cs, C, 2, 2);
  cup_set_desc sd = {.kind = CUP_SET_INTERSECTION, .n = 2, .C = Cs.view, .F = off, .center = c0, .radius = 3};
  cup_set *S;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_set_create(&S, &sd, err), CUP_OK);
  cup_process_desc d = {.n = 2, .C = S, .f = towards};
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 20;
  o.n = n;
  cup_integrator *I;
  assert_int_equal(cup_integrator_create_process(&I, &d, &o, err), CUP_OK);
  traj_ctx c = {n, 2, calloc((size_t)(n + 1) * 2, sizeof(double))};
  assert_true(cup_integrator_run(I, (double[]){0.5, 0.5}, keep, &c, &info) >= 0);
  double diff = 0;
  for (long k = 0; k < 2 * (n + 1); k++) diff = fmax(diff, fabs(x[k] - c.traj[k]));
  printf("  walker.yaml against the C API: max difference %.3g\n", diff);
  assert_true(diff <= 1e-12);
  free(c.traj);
  free(x);
  cup_integrator_free(&I);
  cup_set_free(&S);
  tcsc_free(&Cs);
}

/* An ellipsoid, a half-space, a polyset with moving offsets, f: b and cubic:
 * each scene loads, runs, and its states are where the set says. */
static void test_other_sets(void **state) {
  (void)state;
  const char *text[] = {
    "set: {ellipsoid: {center: [0, {type: sine, amplitude: 1, frequency: 0.5}], radius: 1,\n"
    "      Q: [[4, 0], [0, 1]]}}\nx0: [0, 0]\nT: 2\nn: 400\n",
    "set: {halfspace: {normal: [1, 1], offset: {type: pwl, points: [[0, 0], [2, -2]]}}}\n"
    "f: {b: [0, -1]}\nx0: [0, 0]\nT: 2\nn: 400\n",
    "set: {polyset: {C: [[1, 0], [0, 1]], offset: [{type: sine, amplitude: 1, frequency: 1}, 0.5]}}\n"
    "f: {cubic: [1, 1]}\nx0: [1, 1]\nT: 2\nn: 400\n",
  };
  for (int q = 0; q < 3; q++) {
    char err[CUP_ERRMSG_LEN];
    cup_scene *s;
    if (cup_scene_load_string(&s, text[q], "inline.yaml", NULL, NULL, 0, err)) fail_msg("%s", err);
    assert_null(cup_scene_lcs(s));
    assert_non_null(cup_scene_process(s));
    cup_integrator *I;
    assert_int_equal(cup_scene_integrator(s, NULL, &I, err), CUP_OK);
    cup_run_info info;
    int st = cup_integrator_run(I, cup_scene_x0(s), NULL, NULL, &info);
    assert_true(st >= 0);
    const double *x = cup_integrator_state(I);
    double t = 2;
    if (q == 0) {                              /* in the ellipsoid at t = 2 */
      double c1 = sin(2 * M_PI * 0.5 * t);
      assert_true(4 * x[0] * x[0] + (x[1] - c1) * (x[1] - c1) <= 1 + 1e-12);
    } else if (q == 1) {                       /* pushed down by b, held by x + y >= 2 */
      assert_true(x[0] + x[1] - 2 >= -1e-12);
    } else {                                   /* x1 >= -sin(2 pi t), x2 >= -0.5 */
      assert_true(x[0] + sin(2 * M_PI * t) >= -1e-12 && x[1] + 0.5 >= -1e-12);
    }
    cup_integrator_free(&I);
    cup_scene_free(&s);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_tractrix_scene),
    cmocka_unit_test(test_rotating_disc_scene),
    cmocka_unit_test(test_interval_scene_is_the_lcs),
    cmocka_unit_test(test_walker_scene),
    cmocka_unit_test(test_other_sets),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
