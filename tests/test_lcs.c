/* lcs: the paper's circuit, the P B = C^T check and its message, sizes. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>
#include "testutil.h"

static void test_circuit_set_and_metric(void **state) {
  (void)state;
  cup_circuit c = {1, 2, 1, 1, 2, 1, {0, 0}};
  cup_lcs *L = NULL;
  char msg[CUP_ERRMSG_LEN];
  assert_int_equal(cup_lcs_circuit(&L, &c, msg), CUP_OK);
  assert_int_equal(cup_lcs_dim(L), 3);
  assert_int_equal(cup_lcs_rows(L), 2);
  assert_int_equal(cup_lcs_inputs(L), 1);
  assert_int_equal(cup_lcs_fixed_set(L), 1);
  const cup_polyset *K = cup_lcs_polyset(L);
  /* P = diag(1, L3, L2): M = C P^-1 C^T = [[1/L3 + 1/L2, 1/L3], [1/L3, 1/L3]] */
  double a = 1.0 / 2 + 1, b = 1.0 / 2, d = 1.0 / 2;
  double lmax = 0.5 * (a + d) + sqrt(0.25 * (a - d) * (a - d) + b * b);
  assert_close(cup_polyset_lipschitz(K), lmax, 1e-12 * lmax);
  double v[3] = {1, 1, 1};
  assert_close(cup_polyset_norm(K, v), sqrt(1 + 2 + 1), 1e-15);   /* P-norm */
  double in[3] = {0, 1, 0.5}, out[3] = {0, 0.5, 1};
  assert_int_equal(cup_polyset_contains(K, NULL, in), 1);       /* x2 >= x3, x2 >= 0 */
  assert_int_equal(cup_polyset_contains(K, NULL, out), 0);
  cup_lcs_free(&L);
  cup_circuit c2 = c;
  c2.G[1] = 1;                                  /* the paper's case 2 */
  assert_int_equal(cup_lcs_circuit(&L, &c2, msg), CUP_OK);
  assert_int_equal(cup_lcs_fixed_set(L), 0);
  cup_lcs_free(&L);
  cup_circuit bad = c;
  bad.L3 = -1;
  assert_int_equal(cup_lcs_circuit(&L, &bad, msg), CUP_ERR_ARG);
  assert_non_null(strstr(msg, "L3"));
  assert_null(L);
}

/* The general constructor with the paper's matrices written out, and a B
 * that breaks P B = C^T in one entry: the message names it. */
static void test_pb_check(void **state) {
  (void)state;
  double A[9] = {0, 1, 0, -0.5, -1, 0.5, 0, 1, -3};
  double B[6] = {0, 0, 0.5, 0.5, -1, 0};
  double C[6] = {0, 1, -1, 0, 1, 0};
  double E[3] = {0, 0.5, 1};
  double P[3] = {1, 2, 1};
  tcsc At, Bt, Ct, Et;
  tcsc_from_dense(&At, A, 3, 3);
  tcsc_from_dense(&Bt, B, 3, 2);
  tcsc_from_dense(&Ct, C, 2, 3);
  tcsc_from_dense(&Et, E, 3, 1);
  cup_lcs_desc d = {0};
  d.n = 3; d.m = 2; d.p = 1;
  d.A = At.view; d.B = Bt.view; d.C = Ct.view; d.E = Et.view;
  d.P = (cup_metric){CUP_METRIC_DIAGONAL, P, {0}, 0};
  cup_lcs *L = NULL;
  char msg[CUP_ERRMSG_LEN];
  assert_int_equal(cup_lcs_create(&L, &d, msg), CUP_OK);
  cup_lcs_free(&L);
  B[2] = 0.5 * (1 + 1e-6);                      /* (P B)(1,0) = 2 * B(1,0) = 1 + 1e-6 */
  tcsc_free(&Bt);
  tcsc_from_dense(&Bt, B, 3, 2);
  d.B = Bt.view;
  assert_int_equal(cup_lcs_create(&L, &d, msg), CUP_ERR_PB_CT);
  assert_non_null(strstr(msg, "(1,0)"));
  assert_null(L);
  d.pb_tol = 1e-5;                              /* the relative tolerance is honoured */
  assert_int_equal(cup_lcs_create(&L, &d, msg), CUP_OK);
  cup_lcs_free(&L);
  d.n = 4;                                      /* C is 2 x 3 */
  assert_int_equal(cup_lcs_create(&L, &d, msg), CUP_ERR_DIM);
  assert_non_null(strstr(msg, "C is 2 x 3"));
  tcsc_free(&At); tcsc_free(&Bt); tcsc_free(&Ct); tcsc_free(&Et);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_circuit_set_and_metric),
    cmocka_unit_test(test_pb_check),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
