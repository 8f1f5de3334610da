/* set: the projections onto balls, ellipsoids, half-spaces, a polyset and a
 * ball, a user oracle and a state-dependent polyset, against independent
 * references: closed forms and root finds in long double, the dense
 * reference projection of tests/testutil.h, and a fresh polyset projector
 * per step. Every certificate is checked to be true:
 * eps_cert >= ||x - z||_P^2 - d(x)^2 and eta_cert >= d(z). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"

#include "heap.h"
#include "set/rowpool.h"

/* ---- dense metrics in long double ------------------------------------------------ */

/* A random SPD n x n matrix (row-major): L L^T + n I/4 with L lower random. */
static void random_spd(rng_t *r, int n, double *P) {
  double L[64];
  for (int a = 0; a < n; a++)
    for (int b = 0; b < n; b++) L[a * n + b] = b <= a ? rng_normal(r) : 0;
  for (int a = 0; a < n; a++)
    for (int b = 0; b < n; b++) {
      double s = a == b ? 0.25 * n : 0;
      for (int k = 0; k < n; k++) s += L[a * n + k] * L[b * n + k];
      P[a * n + b] = s;
    }
}

static long double pnorm2l(const double *P, int n, const long double *v) {
  long double s = 0;
  for (int a = 0; a < n; a++)
    for (int b = 0; b < n; b++) s += v[a] * (long double)P[a * n + b] * v[b];
  return s;
}

static long double pdistl(const double *P, int n, const double *a, const double *b) {
  long double d[8];
  for (int j = 0; j < n; j++) d[j] = (long double)a[j] - b[j];
  return sqrtl(pnorm2l(P, n, d));
}

/* A dense row-major matrix as a CSC view kept alive by tcsc. */
static cup_metric dense_metric(tcsc *store, const double *P, int n) {
  tcsc_from_dense(store, P, n, n);
  return (cup_metric){CUP_METRIC_SPARSE, NULL, store->view, 0};
}

/* eps_cert and eta_cert are true against the reference answer zr (with
 * d(x)^2 = ||x - zr||^2) and d(z) (given). */
static void check_certs(const double *P, int n, const double *x, const double *z, const double *zr,
                        long double dz, const cup_proj_info *pi, double S) {
  long double dx = pdistl(P, n, x, zr), xz = pdistl(P, n, x, z);
  double excess = (double)(xz * xz - dx * dx);
  double slack = 1e-13 * S * S;          /* the reference's own rounding */
  if (!(excess <= pi->eps_cert + slack))
    fail_msg("eps_cert %.3g < true excess %.3g", pi->eps_cert, excess);
  if (!((double)dz <= pi->eta_cert + 1e-13 * S))
    fail_msg("eta_cert %.3g < true distance %.3g", pi->eta_cert, (double)dz);
}

/* ---- balls ---------------------------------------------------------------------- */

/* The set of d and its projection (default options); the test fails, saying
 * why, if either is refused. set_close frees both. */
static void set_open(cup_set **S, cup_setproj **sp, const cup_set_desc *d) {
  char err[CUP_ERRMSG_LEN];
  if (cup_set_create(S, d, err) != CUP_OK) fail_msg("cup_set_create: %s", err);
  if (cup_setproj_create(sp, *S, NULL, err) != CUP_OK) fail_msg("cup_setproj_create: %s", err);
}

/* set_open, then the set placed at time t (no parameters, no state). */
static void set_open_at(cup_set **S, cup_setproj **sp, const cup_set_desc *d, double t) {
  set_open(S, sp, d);
  assert_int_equal(cup_setproj_move(*sp, t, NULL, NULL), CUP_OK);
}

static void set_close(cup_set **S, cup_setproj **sp) {
  cup_setproj_free(sp);
  cup_set_free(S);
}

static void test_ball_against_closed_form(void **state) {
  (void)state;
  rng_t r = {11};
  for (int trial = 0; trial < 200; trial++) {
    int n = 1 + trial % 4;
    double P[16], c[4], x[4], z[4], zr[4];
    random_spd(&r, n, P);
    tcsc Ps;
    cup_metric M = dense_metric(&Ps, P, n);
    for (int j = 0; j < n; j++) { c[j] = rng_normal(&r); x[j] = c[j] + 3 * rng_normal(&r); }
    double rad = trial % 7 == 0 ? 0 : 0.5 + rng_unif(&r);
    cup_set_desc d = {.kind = CUP_SET_BALL, .n = n, .P = M, .center = c, .radius = rad};
    cup_set *S;
    char err[CUP_ERRMSG_LEN];
    assert_int_equal(cup_set_create(&S, &d, err), CUP_OK);
    cup_projector_options o;
    cup_projector_options_default(&o);
    cup_setproj *sp;
    assert_int_equal(cup_setproj_create(&sp, S, &o, err), CUP_OK);
    assert_int_equal(cup_setproj_move(sp, 0, NULL, NULL), CUP_OK);
    cup_proj_info pi;
    int st = cup_setproj_project(sp, x, z, &pi);
    long double dxc = pdistl(P, n, x, c);
    for (int j = 0; j < n; j++)
      zr[j] = dxc <= rad ? x[j] : (double)(c[j] + rad / dxc * ((long double)x[j] - c[j]));
    long double dz = fmaxl(pdistl(P, n, z, c) - rad, 0);
    double scale = (double)dxc + rad + 10;
    for (int j = 0; j < n; j++) assert_close(z[j], zr[j], 1e-13 * scale);
    check_certs(P, n, x, z, zr, dz, &pi, scale);
    assert_int_equal(st, CUP_OK);
    assert_true(pi.eta_cert == 0);          /* aimed inside: certainly in the ball */
    set_close(&S, &sp);
    tcsc_free(&Ps);
  }
}

static void test_ball_negative_radius(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  double c[2] = {0, 0};
  cup_set *S;
  cup_set_desc d = {.kind = CUP_SET_BALL, .n = 2, .center = c, .radius = -1};
  assert_int_equal(cup_set_create(&S, &d, err), CUP_ERR_EMPTY_SET);
  assert_non_null(strstr(err, "radius = -1"));
  /* a moving radius r = 1 - u that goes negative at the placement */
  double gr[1] = {-1};
  d.radius = 1;
  d.p = 1;
  d.gr = gr;
  assert_int_equal(cup_set_create(&S, &d, err), CUP_OK);
  cup_setproj *sp;
  assert_int_equal(cup_setproj_create(&sp, S, NULL, err), CUP_OK);
  double u = 0.5;
  assert_int_equal(cup_setproj_move(sp, 0.5, &u, NULL), CUP_OK);
  u = 1.25;
  assert_int_equal(cup_setproj_move(sp, 1.25, &u, NULL), CUP_ERR_EMPTY_SET);
  assert_non_null(strstr(cup_setproj_message(sp), "-0.25"));
  set_close(&S, &sp);
}

/* The one way errors travel: cup_setproj_place and _solve write a failure's
 * words into errmsg (the expected texts written out here), the same bytes
 * the older cup_setproj_move/_project leave for cup_setproj_message, and
 * leave errmsg alone on a success. */
static void test_setproj_errmsg_one_way(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN] = "untouched", err2[CUP_ERRMSG_LEN];
  double c[2] = {0, 0}, gr[1] = {-1}, u = 0.5, x[2] = {3, 4}, z[2];
  cup_set *S;
  cup_set_desc d = {.kind = CUP_SET_BALL, .n = 2, .p = 1, .center = c, .radius = 1, .gr = gr};
  assert_int_equal(cup_set_create(&S, &d, err2), CUP_OK);
  cup_setproj *sp;
  assert_int_equal(cup_setproj_create(&sp, S, NULL, err2), CUP_OK);
  assert_int_equal(cup_setproj_place(sp, 0.5, &u, NULL, err), CUP_OK);
  cup_proj_info info;
  assert_int_equal(cup_setproj_solve(sp, x, z, &info, err), CUP_OK);   /* onto radius 0.5: (0.3, 0.4) */
  assert_true(fabs(z[0] - 0.3) < 1e-14 && fabs(z[1] - 0.4) < 1e-14);   /* aimed a few ulps inside */
  assert_string_equal(err, "untouched");
  u = 1.25;
  assert_int_equal(cup_setproj_place(sp, 1.25, &u, NULL, err), CUP_ERR_EMPTY_SET);
  assert_string_equal(err, "the radius r(t) = -0.25 < 0: the ball is empty");
  assert_int_equal(cup_setproj_move(sp, 1.25, &u, NULL), CUP_ERR_EMPTY_SET);
  assert_string_equal(cup_setproj_message(sp), err);
  assert_int_equal(cup_setproj_place(sp, 1.25, NULL, NULL, err), CUP_ERR_ARG);
  assert_string_equal(err, "the set moves with 1 parameters but u is NULL");
  x[1] = NAN;
  assert_int_equal(cup_setproj_solve(sp, x, z, &info, err), CUP_ERR_NONFINITE);
  assert_string_equal(err, "x[1] is nan");
  assert_int_equal(cup_setproj_project(sp, x, z, &info), CUP_ERR_NONFINITE);
  assert_string_equal(cup_setproj_message(sp), err);
  assert_int_equal(cup_setproj_solve(sp, NULL, z, &info, err), CUP_ERR_ARG);
  assert_string_equal(err, "set projector: sp, x or z is NULL");
  assert_int_equal(cup_setproj_place(NULL, 0, &u, NULL, err), CUP_ERR_ARG);
  assert_string_equal(err, "set projector: sp is NULL");
  cup_setproj_free(&sp);
  cup_set_free(&S);
}

/* ---- half-spaces ----------------------------------------------------------------- */

static void test_halfspace_against_closed_form(void **state) {
  (void)state;
  rng_t r = {12};
  for (int trial = 0; trial < 200; trial++) {
    int n = 1 + trial % 4;
    double P[16], a[4], x[4], z[4], zr[4], Pinv_a[4];
    random_spd(&r, n, P);
    tcsc Ps, As;
    cup_metric M = dense_metric(&Ps, P, n);
    for (int j = 0; j < n; j++) { a[j] = rng_normal(&r); x[j] = 2 * rng_normal(&r); }
    double b = rng_normal(&r);
    tcsc_from_dense(&As, a, 1, n);
    cup_set_desc d = {.kind = CUP_SET_HALFSPACE, .n = n, .P = M, .C = As.view, .F = &b};
    cup_set *S;
    cup_setproj *sp;
    set_open_at(&S, &sp, &d, 0);
    cup_proj_info pi;
    assert_int_equal(cup_setproj_project(sp, x, z, &pi), CUP_OK);
    /* reference: z = x + max(0, -s) / (a^T P^-1 a) P^-1 a, in GSL then long double */
    gsl_matrix *Lm = gsl_matrix_alloc(n, n);
    gsl_vector *v = gsl_vector_alloc(n);
    for (int i = 0; i < n; i++) {
      gsl_vector_set(v, i, a[i]);
      for (int j = 0; j < n; j++) gsl_matrix_set(Lm, i, j, P[i * n + j]);
    }
    gsl_linalg_cholesky_decomp1(Lm);
    gsl_linalg_cholesky_svx(Lm, v);
    long double s = b, apa = 0;
    for (int j = 0; j < n; j++) {
      Pinv_a[j] = gsl_vector_get(v, j);
      s += (long double)a[j] * x[j];
      apa += (long double)a[j] * Pinv_a[j];
    }
    for (int j = 0; j < n; j++) zr[j] = s >= 0 ? x[j] : (double)(x[j] - s / apa * Pinv_a[j]);
    long double sz = b;
    for (int j = 0; j < n; j++) sz += (long double)a[j] * z[j];
    long double dz = sz >= 0 ? 0 : -sz / sqrtl(apa);
    double scale = 10 + fabs(b) + 5;
    for (int j = 0; j < n; j++) assert_close(z[j], zr[j], 1e-12 * scale);
    check_certs(P, n, x, z, zr, dz, &pi, scale);
    assert_true(pi.eta_cert == 0);
    gsl_matrix_free(Lm);
    gsl_vector_free(v);
    set_close(&S, &sp);
    tcsc_free(&Ps);
    tcsc_free(&As);
  }
}

/* ---- ellipsoids ------------------------------------------------------------------ */

/* (P + mu Q) w = P v in long double by Gaussian elimination (n <= 4). */
static void solve_l(int n, const double *P, const double *Q, long double mu, const long double *v,
                    long double *w) {
  long double A[4][5];
  for (int a = 0; a < n; a++) {
    long double rhs = 0;
    for (int b = 0; b < n; b++) {
      A[a][b] = P[a * n + b] + mu * Q[a * n + b];
      rhs += P[a * n + b] * v[b];
    }
    A[a][n] = rhs;
  }
  for (int k = 0; k < n; k++) {
    int piv = k;
    for (int a = k + 1; a < n; a++) if (fabsl(A[a][k]) > fabsl(A[piv][k])) piv = a;
    for (int b = 0; b <= n; b++) { long double t = A[k][b]; A[k][b] = A[piv][b]; A[piv][b] = t; }
    for (int a = k + 1; a < n; a++) {
      long double f = A[a][k] / A[k][k];
      for (int b = k; b <= n; b++) A[a][b] -= f * A[k][b];
    }
  }
  for (int k = n - 1; k >= 0; k--) {
    long double s = A[k][n];
    for (int b = k + 1; b < n; b++) s -= A[k][b] * w[b];
    w[k] = s / A[k][k];
  }
}

static long double qforml(int n, const double *Q, const long double *w) {
  long double s = 0;
  for (int a = 0; a < n; a++)
    for (int b = 0; b < n; b++) s += w[a] * (long double)Q[a * n + b] * w[b];
  return s;
}

static void test_ellipsoid_against_bisection(void **state) {
  (void)state;
  rng_t r = {13};
  for (int trial = 0; trial < 200; trial++) {
    int n = 1 + trial % 4;
    double P[16], Q[16], c[4], x[4], z[4], zr[4];
    random_spd(&r, n, P);
    random_spd(&r, n, Q);
    if (trial % 3 == 0)                     /* a diagonal metric too */
      for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) if (a != b) P[a * n + b] = 0;
    tcsc Ps, Qs;
    cup_metric M = dense_metric(&Ps, P, n);
    tcsc_from_dense(&Qs, Q, n, n);
    for (int j = 0; j < n; j++) { c[j] = rng_normal(&r); x[j] = c[j] + 3 * rng_normal(&r); }
    double rad = 0.3 + rng_unif(&r);
    cup_set_desc d = {.kind = CUP_SET_ELLIPSOID, .n = n, .P = M, .center = c, .radius = rad, .Q = Qs.view};
    cup_set *S;
    cup_setproj *sp;
    set_open_at(&S, &sp, &d, 0);
    cup_proj_info pi;
    int st = cup_setproj_project(sp, x, z, &pi);
    /* reference: mu by bisection on q(w(mu)) = r^2, w = (P + mu Q)^-1 P (x - c) */
    long double v[4], w[4];
    for (int j = 0; j < n; j++) v[j] = (long double)x[j] - c[j];
    long double r2 = (long double)rad * rad;
    if (qforml(n, Q, v) <= r2) {
      for (int j = 0; j < n; j++) w[j] = v[j];
    } else {
      long double lo = 0, hi = 1;
      for (solve_l(n, P, Q, hi, v, w); qforml(n, Q, w) > r2; solve_l(n, P, Q, hi, v, w)) hi *= 2;
      for (int it = 0; it < 200; it++) {
        long double mid = 0.5L * (lo + hi);
        solve_l(n, P, Q, mid, v, w);
        if (qforml(n, Q, w) > r2) lo = mid; else hi = mid;
      }
      solve_l(n, P, Q, hi, v, w);
    }
    for (int j = 0; j < n; j++) zr[j] = (double)(c[j] + w[j]);
    long double wz[4];
    for (int j = 0; j < n; j++) wz[j] = (long double)z[j] - c[j];
    long double qz = qforml(n, Q, wz);
    /* d(z) <= the shrink towards c: (1 - r/sqrt(q)) ||z - c||_P */
    long double dz = qz <= r2 ? 0 : (1 - rad / sqrtl(qz)) * sqrtl(pnorm2l(P, n, wz));
    double scale = 20;
    for (int j = 0; j < n; j++) assert_close(z[j], zr[j], 1e-11 * scale);
    check_certs(P, n, x, z, zr, dz, &pi, scale);
    assert_int_equal(st, CUP_OK);
    assert_true(pi.eps_cert <= 1e-11);
    set_close(&S, &sp);
    tcsc_free(&Ps);
    tcsc_free(&Qs);
  }
}

/* ---- a polyset and a ball ---------------------------------------------------------- */

static void test_intersection_against_reference(void **state) {
  (void)state;
  rng_t r = {14};
  int certified = 0;
  for (int trial = 0; trial < 150; trial++) {
    int n = 2 + trial % 3, m = 1 + trial % 4;
    double P[16], C[16], g[4], c[4], x[4], z[4], zr[4], y[4], zy[4];
    random_spd(&r, n, P);
    for (int i = 0; i < m * n; i++) C[i] = rng_normal(&r);
    for (int j = 0; j < n; j++) { c[j] = 0.3 * rng_normal(&r); x[j] = 3 * rng_normal(&r); }
    for (int i = 0; i < m; i++) g[i] = 0.5 + rng_unif(&r);   /* 0 in K, and c near it */
    double rad = 0.8 + rng_unif(&r);
    tcsc Ps, Cs;
    cup_metric M = dense_metric(&Ps, P, n);
    tcsc_from_dense(&Cs, C, m, n);
    cup_set_desc d = {.kind = CUP_SET_INTERSECTION, .n = n, .P = M, .C = Cs.view, .F = g,
                      .center = c, .radius = rad};
    cup_set *S;
    cup_setproj *sp;
    set_open_at(&S, &sp, &d, 0);
    cup_proj_info pi;
    int st = cup_setproj_project(sp, x, z, &pi);
    /* reference: s in [0, 1] by bisection on ||proj_K((1-s) x + s c) - c|| = r,
     * each projection by the independent dense reference */
    ref_problem q = {n, m, C, g, P};
    ref_project(&q, x, zr);
    if ((double)pdistl(P, n, zr, c) > rad) {
      double lo = 0, hi = 1;
      for (int it = 0; it < 60; it++) {
        double s = 0.5 * (lo + hi);
        for (int j = 0; j < n; j++) y[j] = (1 - s) * x[j] + s * c[j];
        ref_project(&q, y, zy);
        if ((double)pdistl(P, n, zy, c) > rad) lo = s; else hi = s;
      }
      for (int j = 0; j < n; j++) y[j] = (1 - hi) * x[j] + hi * c[j];
      ref_project(&q, y, zr);
    }
    /* z is certainly in both: check its slack and ball distance */
    for (int i = 0; i < m; i++) {
      long double s = g[i];
      for (int j = 0; j < n; j++) s += (long double)C[i * n + j] * z[j];
      assert_true(s >= 0);
    }
    assert_true(pdistl(P, n, z, c) <= rad);
    double scale = 20;
    for (int j = 0; j < n; j++) assert_close(z[j], zr[j], 1e-6 * scale);
    check_certs(P, n, x, z, zr, 0, &pi, scale);
    assert_true(st == CUP_OK || st == CUP_WARN_NOT_CERTIFIED);
    certified += st == CUP_OK;
    set_close(&S, &sp);
    tcsc_free(&Ps);
    tcsc_free(&Cs);
  }
  assert_true(certified >= 145);
}

static void test_intersection_empty(void **state) {
  (void)state;
  /* {x_1 >= 2} and the unit ball at 0 do not meet */
  double C[2] = {1, 0}, F[1] = {-2}, c[2] = {0, 0}, x[2] = {3, 3}, z[2] = {7, 7};
  tcsc Cs;
  tcsc_from_dense(&Cs, C, 1, 2);
  cup_set_desc d = {.kind = CUP_SET_INTERSECTION, .n = 2, .C = Cs.view, .F = F, .center = c, .radius = 1};
  cup_set *S;
  cup_setproj *sp;
  set_open_at(&S, &sp, &d, 0);
  cup_proj_info pi;
  assert_int_equal(cup_setproj_project(sp, x, z, &pi), CUP_ERR_EMPTY_SET);
  assert_non_null(strstr(cup_setproj_message(sp), "do not meet"));
  assert_true(z[0] == 7 && z[1] == 7);      /* unchanged on an error */
  set_close(&S, &sp);
  tcsc_free(&Cs);
}

/* ---- oracles ------------------------------------------------------------------------- */

typedef struct { double c[2], r; int mode, calls; } oracle_ctx;
enum { ORACLE_EXACT, ORACLE_NAN, ORACLE_BOASTS, ORACLE_LIES, ORACLE_FAILS };

/* The unit disc's projection, honest or not. */
static int disc_oracle(double t, const double *x, double eps, double eta, double *z,
                       double *eps_cert, double *eta_cert, void *vp) {
  (void)t; (void)eta;
  oracle_ctx *o = vp;
  o->calls++;
  double d = hypot(x[0] - o->c[0], x[1] - o->c[1]);
  double s = d <= o->r ? 1 : o->r / d;
  for (int j = 0; j < 2; j++) z[j] = o->c[j] + s * (x[j] - o->c[j]);
  *eps_cert = 0;
  *eta_cert = 1e-15;
  switch (o->mode) {
    case ORACLE_NAN: z[1] = NAN; break;
    case ORACLE_BOASTS: *eps_cert = 2 * eps + 1; break;           /* claims less than asked */
    case ORACLE_LIES: if (d > o->r) z[0] += 0.1; break;           /* outside, eta claimed 1e-15 */
    case ORACLE_FAILS: return 7;
    default: break;
  }
  return 0;
}

static int oracle_run(int mode, double *z, cup_proj_info *pi, char *msg, size_t size) {
  oracle_ctx o = {{0, 0}, 1, mode, 0};
  cup_set_desc d = {.kind = CUP_SET_ORACLE, .n = 2, .oracle = disc_oracle, .oracle_ctx = &o};
  cup_set *S;
  cup_setproj *sp;
  set_open_at(&S, &sp, &d, 0.25);
  double x[2] = {3, 4};
  int st = cup_setproj_project(sp, x, z, pi);
  snprintf(msg, size, "%s", cup_setproj_message(sp));
  set_close(&S, &sp);
  return st;
}

static void test_oracle_checks(void **state) {
  (void)state;
  double z[2] = {9, 9};
  cup_proj_info pi;
  char msg[256];
  assert_int_equal(oracle_run(ORACLE_EXACT, z, &pi, msg, sizeof msg), CUP_OK);
  assert_close(z[0], 0.6, 1e-15);
  assert_close(z[1], 0.8, 1e-15);
  z[0] = z[1] = 9;
  assert_int_equal(oracle_run(ORACLE_NAN, z, &pi, msg, sizeof msg), CUP_ERR_CALLBACK);
  assert_non_null(strstr(msg, "z[1] = nan"));
  assert_true(z[0] == 9 && z[1] == 9);
  assert_int_equal(oracle_run(ORACLE_BOASTS, z, &pi, msg, sizeof msg), CUP_WARN_NOT_CERTIFIED);
  assert_true(pi.eps_cert > pi.eps_target);
  z[0] = z[1] = 9;
  assert_int_equal(oracle_run(ORACLE_LIES, z, &pi, msg, sizeof msg), CUP_ERR_CALLBACK);
  assert_non_null(strstr(msg, "farther than its claims allow"));
  assert_true(z[0] == 9 && z[1] == 9);
  assert_int_equal(oracle_run(ORACLE_FAILS, z, &pi, msg, sizeof msg), CUP_ERR_CALLBACK);
  assert_non_null(strstr(msg, "returned 7"));
}

/* ---- state-dependent polysets -------------------------------------------------------- */

/* Rows from the state: the tangent half-plane of the unit disc at the
 * direction of x, -(x/|x|) . y + 1 >= 0, and (by mode) more. */
typedef struct { int mode; int calls; } rows_ctx;

static int tangent_rows(double t, const double *x, cup_rowbuf *rows, void *vp) {
  rows_ctx *c = vp;
  c->calls++;
  double nx = hypot(x[0], x[1]), u[2] = {x[0] / nx, x[1] / nx};
  int cols[2] = {0, 1};
  double v[2] = {-u[0], -u[1]};
  int st = cup_rowbuf_add(rows, 2, cols, v, 1);
  if (c->mode == 1 && t < 2.5) {             /* a second pattern, then it goes away */
    int c1[1] = {1};
    double v1[1] = {1};
    st |= cup_rowbuf_add(rows, 1, c1, v1, 0.5);   /* y_2 >= -0.5 */
  }
  if (c->mode == 1 && t >= 3.5) {            /* a third pattern: a rebuild */
    int c0[1] = {0};
    double v0[1] = {1};
    st |= cup_rowbuf_add(rows, 1, c0, v0, 2);     /* y_1 >= -2 */
  }
  if (c->mode == 2) {                        /* a bad row */
    int bad[2] = {1, 0};
    st |= cup_rowbuf_add(rows, 2, bad, v, 0);
  }
  return 0 * st;
}

/* The fixture of the tests of tangent_rows: its state polyset in the mode
 * the test's prestate names, and its projector. */
typedef struct { rows_ctx c; cup_set *S; cup_setproj *sp; } tangent;
static const int tangent_modes[3] = {0, 1, 2};

static int tangent_open(void **state) {
  tangent *T = calloc(1, sizeof *T);
  T->c = (rows_ctx){*(const int *)*state, 0};
  cup_set_desc d = {.kind = CUP_SET_STATE_POLYSET, .n = 2, .rows = tangent_rows, .rows_ctx = &T->c};
  set_open(&T->S, &T->sp, &d);
  *state = T;
  return 0;
}

static int tangent_close(void **state) {
  tangent *T = *state;
  set_close(&T->S, &T->sp);
  free(T);
  return 0;
}

/* The same rows, in a fresh polyset and projector. */
static void fresh_projection(double t, const double *xk, const double *x, double *z, int mode) {
  double nx = hypot(xk[0], xk[1]);
  double Cm[3 * 2] = {-xk[0] / nx, -xk[1] / nx}, gm[3] = {1};
  int m = 1;
  if (mode == 1 && t < 2.5) { Cm[2 * m] = 0; Cm[2 * m + 1] = 1; gm[m++] = 0.5; }
  if (mode == 1 && t >= 3.5) { Cm[2 * m] = 1; Cm[2 * m + 1] = 0; gm[m++] = 2; }
  tcsc Cs;
  cup_polyset *K = tpolyset_dense(&Cs, Cm, m, 2, gm, NULL);
  cup_projector *p;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_projector_create(&p, K, NULL, err), CUP_OK);
  cup_proj_info pi;
  assert_int_equal(cup_project(p, x, z, &pi), CUP_OK);
  cup_projector_free(&p);
  cup_polyset_free(&K);
  tcsc_free(&Cs);
}

static void test_state_polyset_reuse_and_rebuild(void **state) {
  cup_setproj *sp = ((tangent *)*state)->sp;
  double xk[2] = {0.3, 0.2}, x[2], z[2], zr[2];
  long rebuilds_at[6];
  for (int k = 0; k < 6; k++) {
    double t = k;
    double ang = 0.4 * k;
    xk[0] = cos(ang); xk[1] = sin(ang);
    x[0] = 1.7 * cos(ang + 0.3); x[1] = 1.7 * sin(ang + 0.3) - 0.2 * k;
    assert_int_equal(cup_setproj_move(sp, t, NULL, xk), CUP_OK);
    cup_proj_info pi;
    assert_int_equal(cup_setproj_project(sp, x, z, &pi), CUP_OK);
    fresh_projection(t, xk, x, zr, 1);
    /* both certified: ||z - z*|| <= sqrt(eps_cert) + eta_cert (a convex set) */
    double tol = sqrt(pi.eps_cert) + pi.eta_cert + 1e-13;
    for (int j = 0; j < 2; j++) assert_close(z[j], zr[j], tol);
    rebuilds_at[k] = cup_setproj_rebuilds(sp);
  }
  /* steps 0-2: two rows (one rebuild); 3: the second row is off (reused);
   * 4-5: a new pattern (one more rebuild), then it repeats */
  assert_int_equal(rebuilds_at[0], 1);
  assert_int_equal(rebuilds_at[3], 1);
  assert_int_equal(rebuilds_at[4], 2);
  assert_int_equal(rebuilds_at[5], 2);
}

/* Three points in the plane (x: 6 coordinates) kept 1 apart in pairs (0, 1)
 * and (1, 2) along the directions at x_k, and point 2 left of the line
 * x = 1; given in the numbering of perms[gen] (column k is the user's
 * coordinate of point perm[k / 2]) when numbered, else in the user's. */
typedef struct { int numbered, gen; } trio_ctx;
static const int trio_perms[3][3] = {{0, 1, 2}, {2, 0, 1}, {1, 2, 0}};

static int trio_rows(double t, const double *x, cup_rowbuf *rows, void *vp) {
  (void)t;
  trio_ctx *c = vp;
  const int *perm = trio_perms[c->gen % 3];
  static int colmap[3][6];
  int inv[3];
  for (int k = 0; k < 3; k++) {
    inv[perm[k]] = k;
    colmap[c->gen % 3][2 * k] = 2 * perm[k];
    colmap[c->gen % 3][2 * k + 1] = 2 * perm[k] + 1;
  }
  if (c->numbered) rowbuf_order(rows, colmap[c->gen % 3], c->gen);
  for (int p = 0; p < 2; p++) {
    int i = p, j = p + 1;
    double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1], d = hypot(dx, dy);
    int a = c->numbered ? inv[i] : i, b = c->numbered ? inv[j] : j;
    double e = a < b ? 1 : -1;                /* the lower column first */
    int lo = a < b ? a : b, hi = a < b ? b : a;
    int cols[4] = {2 * lo, 2 * lo + 1, 2 * hi, 2 * hi + 1};
    double v[4] = {e * dx / d, e * dy / d, -e * dx / d, -e * dy / d};
    cup_rowbuf_add(rows, 4, cols, v, -1);
  }
  int w = c->numbered ? inv[2] : 2, cw[1] = {2 * w};
  double vw[1] = {-1};
  cup_rowbuf_add(rows, 1, cw, vw, 1);
  return 0;
}

/* The same set numbered the callback's way, renumbered every other step,
 * projects as in the user's numbering (answers in the user's order); a
 * renumbering costs one rebuild, a step in the same numbering none. */
static void test_state_polyset_own_numbering(void **state) {
  (void)state;
  trio_ctx cn = {1, 0}, cp = {0, 0};
  cup_set_desc dn = {.kind = CUP_SET_STATE_POLYSET, .n = 6, .rows = trio_rows, .rows_ctx = &cn};
  cup_set_desc dp = dn;
  dp.rows_ctx = &cp;
  cup_set *Sn, *Sp;
  cup_setproj *spn, *spp;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_set_create(&Sn, &dn, err), CUP_OK);
  assert_int_equal(cup_set_create(&Sp, &dp, err), CUP_OK);
  assert_int_equal(cup_setproj_create(&spn, Sn, NULL, err), CUP_OK);
  assert_int_equal(cup_setproj_create(&spp, Sp, NULL, err), CUP_OK);
  for (int k = 0; k < 8; k++) {
    cn.gen = k / 2;                          /* a new numbering every other step */
    double xk[6] = {0, 0, 1.1, 0.1 * k, 2.2, -0.05 * k}, x[6], zn[6], zp[6];
    for (int j = 0; j < 6; j++) x[j] = xk[j] + (j % 2 ? 0.3 : -0.4) * (j / 2 == 1 ? -1 : 1);
    x[4] += 0.6;                             /* point 2 pushed past the line */
    cup_proj_info pn, pp;
    assert_int_equal(cup_setproj_move(spn, 0.1 * k, NULL, xk), CUP_OK);
    assert_int_equal(cup_setproj_move(spp, 0.1 * k, NULL, xk), CUP_OK);
    assert_int_equal(cup_setproj_project(spn, x, zn, &pn), CUP_OK);
    assert_int_equal(cup_setproj_project(spp, x, zp, &pp), CUP_OK);
    assert_true(pn.active > 0);
    double tol = sqrt(pn.eps_cert) + pn.eta_cert + sqrt(pp.eps_cert) + pp.eta_cert + 1e-13;
    for (int j = 0; j < 6; j++) assert_close(zn[j], zp[j], tol);
    assert_true(zn[4] <= 1 + 1e-12);         /* point 2 back left of the line */
    assert_int_equal(cup_setproj_rebuilds(spn), 1 + k / 2);
  }
  assert_int_equal(cup_setproj_rebuilds(spp), 1);
  cup_setproj_free(&spn);
  cup_setproj_free(&spp);
  cup_set_free(&Sn);
  cup_set_free(&Sp);
}

static void test_state_polyset_no_allocation_when_patterns_repeat(void **state) {
  cup_setproj *sp = ((tangent *)*state)->sp;
  double xk[2], x[2], z[2];
  long allocs = 0;
  for (int k = 0; k < 50; k++) {
    xk[0] = cos(0.1 * k); xk[1] = sin(0.1 * k);
    x[0] = 2 * cos(0.1 * k + 0.05); x[1] = 2 * sin(0.1 * k + 0.05);
#if HEAP_INTERPOSED
    if (k >= 2) { heap_calls = 0; heap_counting = 1; }
#endif
    cup_proj_info pi;
    int st = cup_setproj_move(sp, 0.1 * k, NULL, xk);
    if (!st) st = cup_setproj_project(sp, x, z, &pi);
#if HEAP_INTERPOSED
    heap_counting = 0;
    allocs += heap_calls;
#endif
    assert_int_equal(st, CUP_OK);
    /* the answer: the tangent line's point nearest to x */
    double u0 = xk[0], u1 = xk[1], s = u0 * x[0] + u1 * x[1] - 1;
    assert_close(z[0], x[0] - s * u0, 1e-12);
    assert_close(z[1], x[1] - s * u1, 1e-12);
  }
  assert_int_equal(allocs, 0);
  assert_int_equal(cup_setproj_rebuilds(sp), 1);
}

static void test_state_polyset_bad_row(void **state) {
  cup_setproj *sp = ((tangent *)*state)->sp;
  double xk[2] = {1, 0};
  assert_int_equal(cup_setproj_move(sp, 0, NULL, xk), CUP_ERR_CALLBACK);
  assert_non_null(strstr(cup_setproj_message(sp), "row 1: column 0 after column 1"));
}

static void test_names_and_bad_descriptions(void **state) {
  (void)state;
  for (int k = 0; k < CUP_SET_COUNT; k++) assert_int_equal(cup_set_kind_parse(cup_set_kind_name(k)), k);
  assert_int_equal(cup_set_kind_parse("disc"), -1);
  assert_string_equal(cup_set_kind_name(CUP_SET_COUNT), "unknown");
  char err[CUP_ERRMSG_LEN];
  cup_set *S;
  cup_set_desc d = {.kind = CUP_SET_ORACLE, .n = 2};
  assert_int_equal(cup_set_create(&S, &d, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "oracle callback is NULL"));
  double c[2] = {0, NAN};
  d = (cup_set_desc){.kind = CUP_SET_BALL, .n = 2, .center = c, .radius = 1};
  assert_int_equal(cup_set_create(&S, &d, err), CUP_ERR_NONFINITE);
  assert_non_null(strstr(err, "center[1]"));
  double Q[4] = {1, 2, 2, 1};                /* symmetric, indefinite */
  tcsc Qs;
  tcsc_from_dense(&Qs, Q, 2, 2);
  c[1] = 0;
  d = (cup_set_desc){.kind = CUP_SET_ELLIPSOID, .n = 2, .center = c, .radius = 1, .Q = Qs.view};
  assert_int_equal(cup_set_create(&S, &d, err), CUP_ERR_NOT_SPD);
  tcsc_free(&Qs);
}

/* Each kind's own checks, reached through set.c's registry (set_impl.h's
 * set_kind): the rows a kind carries (any number, exactly one, none), its
 * own fields, then the radius of a kind with a ball; each message whole,
 * kind by kind (a wrong registry line gives another kind's checks). */
static void test_kind_checks(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  cup_set *S = NULL;
  double A[6] = {1, 0, 0, 1, 1, 1}, c[2] = {0, 0};
  tcsc C22, C13;
  tcsc_from_dense(&C22, A, 2, 2);
  tcsc_from_dense(&C13, A, 1, 3);
  struct { cup_set_desc d; int st; const char *msg; } cases[] = {
    {{.kind = CUP_SET_POLYSET, .n = 2}, CUP_ERR_ARG, "set polyset: C is missing"},
    {{.kind = CUP_SET_HALFSPACE, .n = 2, .C = C22.view}, CUP_ERR_DIM, "set halfspace: C is 2 x 2, expected 1 x 2"},
    {{.kind = CUP_SET_INTERSECTION, .n = 2, .C = C13.view, .radius = 1}, CUP_ERR_DIM,
     "set intersection: C is 1 x 3, expected m x 2"},
    {{.kind = CUP_SET_INTERSECTION, .n = 2, .C = C22.view, .center = c, .radius = NAN}, CUP_ERR_NONFINITE,
     "set intersection: radius is nan"},
    {{.kind = CUP_SET_ELLIPSOID, .n = 257, .radius = 1}, CUP_ERR_UNSUPPORTED,
     "set ellipsoid: n = 257 exceeds the dense limit 256"},
    {{.kind = CUP_SET_ELLIPSOID, .n = 2, .radius = -1}, CUP_ERR_ARG, "set ellipsoid: the shape Q is missing"},
    {{.kind = CUP_SET_BALL, .n = 2, .center = c, .radius = -1}, CUP_ERR_EMPTY_SET,
     "set ball: radius = -1 < 0: the set is empty"},
    {{.kind = CUP_SET_STATE_POLYSET, .n = 2}, CUP_ERR_ARG, "set state-polyset: the rows callback is NULL"},
    {{.kind = CUP_SET_STATE_POLYSET, .n = 2, .rows = tangent_rows, .P = {.kind = CUP_METRIC_SPARSE}},
     CUP_ERR_UNSUPPORTED, "set state-polyset: the metric must be the identity or diagonal (the rows' dual "
     "matrix C P^-1 C^T is refactored in place at every step)"},
  };
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    err[0] = '\0';
    assert_int_equal(cup_set_create(&S, &cases[k].d, err), cases[k].st);
    assert_null(S);
    assert_string_equal(err, cases[k].msg);
  }
  tcsc_free(&C22);
  tcsc_free(&C13);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_ball_against_closed_form),
    cmocka_unit_test(test_ball_negative_radius),
    cmocka_unit_test(test_halfspace_against_closed_form),
    cmocka_unit_test(test_ellipsoid_against_bisection),
    cmocka_unit_test(test_intersection_against_reference),
    cmocka_unit_test(test_intersection_empty),
    cmocka_unit_test(test_oracle_checks),
    cmocka_unit_test(test_state_polyset_own_numbering),
    cmocka_unit_test_prestate_setup_teardown(test_state_polyset_reuse_and_rebuild, tangent_open, tangent_close,
                                             (void *)&tangent_modes[1]),
    cmocka_unit_test_prestate_setup_teardown(test_state_polyset_no_allocation_when_patterns_repeat, tangent_open, tangent_close,
                                             (void *)&tangent_modes[0]),
    cmocka_unit_test_prestate_setup_teardown(test_state_polyset_bad_row, tangent_open, tangent_close,
                                             (void *)&tangent_modes[2]),
    cmocka_unit_test(test_names_and_bad_descriptions),
    cmocka_unit_test(test_kind_checks),
    cmocka_unit_test(test_setproj_errmsg_one_way),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
