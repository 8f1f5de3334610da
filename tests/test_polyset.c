/* polyset: validation with messages that name the problem, the guaranteed
 * Lipschitz bound against eigenvalues computed by GSL (cold, revalued and
 * rebuilt warm), membership, norms and the interior direction. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include <gsl/gsl_eigen.h>
#include "testutil.h"
#include "set/polyset_impl.h"

/* The paper circuit: P = diag(1, L3, L2) = diag(1, 2, 1), C = [[0,1,-1],[0,1,0]]. */
static const int circ_p[4] = {0, 0, 2, 3};
static const int circ_i[3] = {0, 1, 0};
static const double circ_x[3] = {1, 1, -1};
static const double circ_d[3] = {1, 2, 1};

static cup_polyset *circuit(void) {
  cup_csc C = {2, 3, circ_p, circ_i, circ_x};
  cup_metric P = {CUP_METRIC_DIAGONAL, circ_d, {0}, 0};
  cup_polyset *K = NULL;
  assert_int_equal(cup_polyset_create(&K, &C, NULL, &P, NULL), CUP_OK);
  return K;
}

static void test_circuit_lipschitz_is_exact_eigenvalue(void **state) {
  (void)state;
  cup_polyset *K = circuit();
  /* M = C P^-1 C^T = [[1.5, .5], [.5, .5]]: lambda_max = 1 + sqrt(.5). */
  double lmax = 1 + sqrt(0.5);
  double L = cup_polyset_lipschitz(K);
  assert_true(L >= lmax);
  assert_true(L <= lmax * (1 + 1e-12));
  assert_int_equal(cup_polyset_dim(K), 3);
  assert_int_equal(cup_polyset_rows(K), 2);
  cup_polyset_free(&K);
  assert_null(K);
}

static void test_membership_and_norm(void **state) {
  (void)state;
  cup_polyset *K = circuit();
  double in[3] = {5, 1, 0.5}, out[3] = {0, 1, 2}, edge[3] = {0, 0, 0};
  assert_int_equal(cup_polyset_contains(K, NULL, in), 1);
  assert_int_equal(cup_polyset_contains(K, NULL, out), 0);
  assert_int_equal(cup_polyset_contains(K, NULL, edge), 1);   /* exact zeros */
  cup_projector *pr = NULL;                                     /* anchors offered */
  assert_int_equal(cup_projector_create(&pr, K, NULL, NULL), CUP_OK);
  assert_int_equal(cup_projector_offer_feasible(pr, in), 1);
  assert_int_equal(cup_projector_offer_feasible(pr, out), 0);
  cup_projector_free(&pr);
  double nan3[3] = {0, NAN, 0};
  assert_int_equal(cup_polyset_contains(K, NULL, nan3), 0);    /* NaN is never inside */
  double g[2] = {-1, 0};                                       /* x2 - x3 >= 1 */
  assert_int_equal(cup_polyset_contains(K, g, in), 0);
  double v[3] = {1, 2, 3};
  assert_close(cup_polyset_norm(K, v), sqrt(1 + 2 * 4 + 9), 1e-15);
  cup_polyset_free(&K);
}

static void test_interior_direction_enters_the_set(void **state) {
  (void)state;
  cup_polyset *K = circuit();
  const double *d = cup_polyset_interior_direction(K);
  assert_non_null(d);
  /* C d > 0 row by row, computed here from the matrix above */
  assert_true(d[1] - d[2] > 0);
  assert_true(d[1] > 0);
  cup_polyset_free(&K);
}

static int create_err(const cup_csc *C, const double *g, const cup_metric *P, char *msg) {
  cup_polyset *K = (cup_polyset *)0x1;
  int st = cup_polyset_create(&K, C, g, P, msg);
  assert_null(K);                 /* a failed create leaves nothing behind */
  return st;
}

static void test_validation_messages(void **state) {
  (void)state;
  char msg[CUP_ERRMSG_LEN];
  int p[4] = {0, 0, 2, 3}, ri[3] = {0, 1, 0};
  double x[3] = {1, 1, -1};
  cup_csc C = {2, 3, p, ri, x};

  int bad_row[3] = {0, 5, 0};
  cup_csc Cb = {2, 3, p, bad_row, x};
  assert_int_equal(create_err(&Cb, NULL, NULL, msg), CUP_ERR_ARG);
  assert_non_null(strstr(msg, "row index 5"));

  int unsorted[3] = {1, 0, 0};
  cup_csc Cu = {2, 3, p, unsorted, x};
  assert_int_equal(create_err(&Cu, NULL, NULL, msg), CUP_ERR_ARG);
  assert_non_null(strstr(msg, "column 1"));

  double xn[3] = {1, NAN, -1};
  cup_csc Cn = {2, 3, p, ri, xn};
  assert_int_equal(create_err(&Cn, NULL, NULL, msg), CUP_ERR_NONFINITE);
  assert_non_null(strstr(msg, "C(1,1)"));

  double gbad[2] = {0, INFINITY};
  assert_int_equal(create_err(&C, gbad, NULL, msg), CUP_ERR_NONFINITE);
  assert_non_null(strstr(msg, "g[1]"));

  double dneg[3] = {1, -2, 1};
  cup_metric Pneg = {CUP_METRIC_DIAGONAL, dneg, {0}, 0};
  assert_int_equal(create_err(&C, NULL, &Pneg, msg), CUP_ERR_NOT_SPD);
  assert_non_null(strstr(msg, "P(1,1)"));

  /* sparse P refused: not symmetric; symmetric but indefinite (eigenvalues
   * 3 and -1 in the first block) */
  const struct { double P[9]; const char *why; } bad_P[] = {
    {{2, 1, 0, 0, 2, 0, 0, 0, 2}, "not symmetric"},
    {{1, 2, 0, 2, 1, 0, 0, 0, 1}, "not positive definite"},
  };
  for (size_t k = 0; k < sizeof bad_P / sizeof bad_P[0]; k++) {
    tcsc Ps; tcsc_from_dense(&Ps, bad_P[k].P, 3, 3);
    cup_metric Pm = {CUP_METRIC_SPARSE, NULL, Ps.view, 0};
    assert_int_equal(create_err(&C, NULL, &Pm, msg), CUP_ERR_NOT_SPD);
    assert_non_null(strstr(msg, bad_P[k].why));
    tcsc_free(&Ps);
  }

  cup_csc Cdim = {2, 3, p, ri, x};
  Cdim.ncol = 0;
  assert_int_equal(create_err(&Cdim, NULL, NULL, msg), CUP_ERR_DIM);
  assert_int_equal(create_err(NULL, NULL, NULL, msg), CUP_ERR_ARG);
}

/* Random sets, diagonal and non-diagonal P: L >= lambda_max(M) always. */
static void test_lipschitz_bound_is_guaranteed(void **state) {
  (void)state;
  rng_t r = {12345};
  for (int trial = 0; trial < 300; trial++) {
    int n = rng_int(&r, 1, 12), m = rng_int(&r, 1, 90);
    double *C = calloc((size_t)m * n, sizeof(double)), *P = calloc((size_t)n * n, sizeof(double));
    for (int k = 0; k < m * n; k++) if (rng_unif(&r) < 0.5) C[k] = rng_normal(&r);
    int dense_p = trial % 2;
    for (int a = 0; a < n; a++) P[a * n + a] = 0.2 + 3 * rng_unif(&r);
    if (dense_p) {
      for (int a = 0; a < n; a++)
        for (int b = 0; b < a; b++) if (rng_unif(&r) < 0.4) {
          double v = 0.3 * rng_normal(&r);
          P[a * n + b] = P[b * n + a] = v;
          P[a * n + a] += fabs(v); P[b * n + b] += fabs(v);   /* diagonally dominant */
        }
    }
    tcsc Ct, Pt;
    tcsc_from_dense(&Ct, C, m, n);
    tcsc_from_dense(&Pt, P, n, n);
    cup_metric Pm = {CUP_METRIC_SPARSE, NULL, Pt.view, 0};
    cup_polyset *K = NULL;
    char msg[CUP_ERRMSG_LEN];
    assert_int_equal(cup_polyset_create(&K, &Ct.view, NULL, &Pm, msg), CUP_OK);
    ref_problem q = {n, m, C, NULL, P};
    ref_work w; ref_setup(&q, &w);
    gsl_matrix *A = gsl_matrix_alloc(m, m);
    for (int i = 0; i < m; i++) for (int j = 0; j < m; j++) gsl_matrix_set(A, i, j, w.M[i * m + j]);
    gsl_vector *ev = gsl_vector_alloc(m);
    gsl_eigen_symm_workspace *ws = gsl_eigen_symm_alloc(m);
    gsl_eigen_symm(A, ev, ws);
    double lmax = gsl_vector_max(ev);
    double L = cup_polyset_lipschitz(K);
    assert_true(L >= lmax * (1 - 1e-13));
    assert_true(L <= (m + 1.0) * fmax(lmax, 1e-300) * 1.01 + 1e-12);   /* a bound, not a wild one */
    gsl_eigen_symm_free(ws); gsl_vector_free(ev); gsl_matrix_free(A); ref_free(&w);
    cup_polyset_free(&K);
    tcsc_free(&Ct); tcsc_free(&Pt); free(C); free(P);
  }
}

/* The bound a state polyset recomputes at every step (polyset_revalue,
 * started from the last step's vector) stays above lambda_max(C C^T) (GSL's
 * symmetric eigensolver) while the rows' values change and rows go off and
 * on again, and within 15 % of the bound of a fresh polyset of the same
 * values (6 iterations from the ones vector). */
static void test_revalued_lipschitz_bound(void **state) {
  (void)state;
  enum { M = 80, N = 60, STEPS = 12 };
  rng_t r = {777};
  double *C0 = calloc(M * N, sizeof(double)), *C = calloc(M * N, sizeof(double));
  for (int i = 0; i < M; i++)                /* contact-like rows: 2 or 4 entries */
    for (int e = 0; e < (i % 3 ? 4 : 2); e++) C0[i * N + rng_int(&r, 0, N - 1)] = rng_normal(&r);
  tcsc Cs;
  tcsc_from_dense(&Cs, C0, M, N);            /* the pattern (every entry of C0) */
  char msg[CUP_ERRMSG_LEN];
  cup_polyset *K = NULL;
  assert_int_equal(polyset_create_ex(&K, &Cs.view, NULL, NULL, 1, NULL, msg), CUP_OK);
  double *work = malloc(sizeof(double) * (2 * M + N)), f[M];
  gsl_matrix *A = gsl_matrix_alloc(M, M);
  gsl_vector *ev = gsl_vector_alloc(M);
  gsl_eigen_symm_workspace *ws = gsl_eigen_symm_alloc(M);
  for (int step = 0; step < STEPS; step++) {
    for (int i = 0; i < M; i++) f[i] = (i + step) % 7 == 0 ? 0 : 0.5 + rng_unif(&r);   /* some rows off */
    for (int i = 0; i < M; i++)
      for (int j = 0; j < N; j++) C[i * N + j] = f[i] * C0[i * N + j];
    for (int j = 0; j < N; j++)              /* the new values in place, C and C^T */
      for (int k = K->C.p[j]; k < K->C.p[j + 1]; k++) K->C.x[k] = C[K->C.i[k] * N + j];
    for (int i = 0; i < M; i++)
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) K->Ct.x[k] = C[i * N + K->Ct.i[k]];
    polyset_revalue(K, work);
    for (int i = 0; i < M; i++)
      for (int j = 0; j < M; j++) {
        double s = 0;
        for (int k = 0; k < N; k++) s += C[i * N + k] * C[j * N + k];
        gsl_matrix_set(A, i, j, s);
      }
    gsl_eigen_symm(A, ev, ws);
    double lmax = gsl_vector_max(ev);
    tcsc Cf;
    tcsc_from_dense(&Cf, C, M, N);
    cup_polyset *F = NULL;
    assert_int_equal(polyset_create_ex(&F, &Cf.view, NULL, NULL, 1, NULL, msg), CUP_OK);
    printf("step %d: lambda_max %.6g, revalued bound %.6g, fresh bound %.6g\n", step, lmax, K->lip, F->lip);
    assert_true(K->lip >= lmax * (1 - 1e-13));
    assert_true(K->lip <= 1.15 * F->lip);
    assert_int_equal(K->cw_warm, 1);
    cup_polyset_free(&F);
    tcsc_free(&Cf);
  }
  gsl_eigen_symm_free(ws); gsl_vector_free(ev); gsl_matrix_free(A);
  cup_polyset_free(&K);
  tcsc_free(&Cs);
  free(C0); free(C); free(work);
}

/* The largest eigenvalue of C C^T (C dense, m x n, by rows), by GSL. */
static double lambda_max_cct(const double *C, int m, int n) {
  gsl_matrix *A = gsl_matrix_alloc((size_t)m, (size_t)m);
  gsl_vector *ev = gsl_vector_alloc((size_t)m);
  gsl_eigen_symm_workspace *ws = gsl_eigen_symm_alloc((size_t)m);
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) {
      double s = 0;
      for (int k = 0; k < n; k++) s += C[i * n + k] * C[j * n + k];
      gsl_matrix_set(A, (size_t)i, (size_t)j, s);
    }
  gsl_eigen_symm(A, ev, ws);
  double lmax = gsl_vector_max(ev);
  gsl_eigen_symm_free(ws); gsl_vector_free(ev); gsl_matrix_free(A);
  return lmax;
}

/* A state polyset rebuilt with rows of the last one (some gone, the rest
 * in another order, new ones) starts its bound from the last one's vector,
 * row by row, 0 for the new rows: the bound stays above lambda_max(C C^T)
 * (GSL) and within 15 % of a cold one's, and the set revalues warm. */
static void test_rebuilt_lipschitz_bound(void **state) {
  (void)state;
  enum { M = 80, N = 60, KEEP = 60 };
  rng_t r = {4242};
  double *C = calloc(M * N, sizeof(double)), *Cn = calloc(M * N, sizeof(double));
  for (int i = 0; i < M; i++)
    for (int e = 0; e < (i % 3 ? 4 : 2); e++) C[i * N + rng_int(&r, 0, N - 1)] = rng_normal(&r);
  tcsc Cs;
  tcsc_from_dense(&Cs, C, M, N);
  char msg[CUP_ERRMSG_LEN];
  cup_polyset *K = NULL;
  assert_int_equal(polyset_create_ex(&K, &Cs.view, NULL, NULL, 1, NULL, msg), CUP_OK);
  assert_int_equal(K->cw_warm, 0);
  double *work = malloc(sizeof(double) * (2 * M + N)), *wnew = malloc(sizeof(double) * (2 * M + N));
  polyset_revalue(K, work);               /* the last set's vector, in work */
  int old_of[M];
  for (int s = 0; s < M; s++) old_of[s] = s < KEEP ? (7 * s + 3) % M : -1;   /* 60 of the 80 rows */
  for (int s = 0; s < M; s++) {
    for (int k = 0; k < N; k++)
      Cn[s * N + k] = old_of[s] >= 0 ? (0.8 + 0.4 * rng_unif(&r)) * C[old_of[s] * N + k] : 0;
    if (old_of[s] < 0)
      for (int e = 0; e < 4; e++) Cn[s * N + rng_int(&r, 0, N - 1)] = rng_normal(&r);
    wnew[s] = old_of[s] >= 0 ? work[old_of[s]] : 0;
  }
  tcsc Cf;
  tcsc_from_dense(&Cf, Cn, M, N);
  cup_polyset *W = NULL, *F = NULL;
  assert_int_equal(polyset_create_ex(&W, &Cf.view, NULL, NULL, 1, wnew, msg), CUP_OK);
  assert_int_equal(polyset_create_ex(&F, &Cf.view, NULL, NULL, 1, NULL, msg), CUP_OK);
  double lmax = lambda_max_cct(Cn, M, N);
  printf("rebuilt: lambda_max %.6g, warm bound %.6g, cold bound %.6g\n", lmax, W->lip, F->lip);
  assert_true(W->lip >= lmax * (1 - 1e-13));
  assert_true(W->lip <= 1.15 * F->lip);
  assert_int_equal(W->cw_warm, 1);
  for (int k = 0; k < W->Ct.nnz; k++) W->Ct.x[k] *= 1.1;   /* the next step: revalued warm */
  for (int k = 0; k < W->C.nnz; k++) W->C.x[k] *= 1.1;
  polyset_revalue(W, wnew);
  assert_true(W->lip >= 1.21 * lmax * (1 - 1e-13));
  assert_true(W->lip <= 1.21 * 1.15 * F->lip);
  cup_polyset_free(&K); cup_polyset_free(&W); cup_polyset_free(&F);
  tcsc_free(&Cs); tcsc_free(&Cf);
  free(C); free(Cn); free(work); free(wnew);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_circuit_lipschitz_is_exact_eigenvalue),
    cmocka_unit_test(test_membership_and_norm),
    cmocka_unit_test(test_interior_direction_enters_the_set),
    cmocka_unit_test(test_validation_messages),
    cmocka_unit_test(test_lipschitz_bound_is_guaranteed),
    cmocka_unit_test(test_revalued_lipschitz_bound),
    cmocka_unit_test(test_rebuilt_lipschitz_bound),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
