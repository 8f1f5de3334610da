/* la_dense_expm_stiff (src/util/linalg.c), the adaptive scheme's matrix
 * exponential, against closed forms: a rotation (cos, sin), a Jordan block
 * (the finite series), and a stiff upper triangular block, whose corner
 * c (e^l - e^u) / (l - u) is tiny against the diagonal's 1 and is what the
 * carried X = exp - I keeps (each entry to a relative 1e-13; a stiff
 * generator's |lambda| h of 3e4 takes 16 squarings). */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"
#include "util/linalg.h"

/* |got - want| <= rel |want| in every entry (column-major k x k). */
static void check(const double *got, const double *want, int k, double rel) {
  for (int q = 0; q < k * k; q++)
    if (!(fabs(got[q] - want[q]) <= rel * fabs(want[q]))) {
      printf("entry %d: %.17g, closed form %.17g (relative %.3g)\n", q, got[q], want[q],
             fabs(got[q] - want[q]) / fabs(want[q]));
      fail();
    }
}

static void test_rotation(void **state) {
  (void)state;
  double work[5 * 4], out[4];
  for (double w = 0.1; w < 40; w *= 3.7) {
    double a[4] = {0, -w, w, 0};                 /* [[0, w], [-w, 0]] */
    la_dense_expm_stiff(a, 2, out, work);
    double want[4] = {cos(w), -sin(w), sin(w), cos(w)};
    /* an entry near a zero of cos or sin rounds at the size of the others */
    for (int q = 0; q < 4; q++) assert_true(fabs(out[q] - want[q]) <= 1e-14 * fmax(1, w));
  }
}

static void test_jordan(void **state) {
  (void)state;
  double work[5 * 9], out[9];
  for (double s = 0.25; s < 20; s *= 2.3) {
    double a[9] = {0, 0, 0, s, 0, 0, 0, s, 0};   /* s on the superdiagonal */
    la_dense_expm_stiff(a, 3, out, work);
    double want[9] = {1, 0, 0, s, 1, 0, s * s / 2, s, 1};
    for (int q = 0; q < 9; q++) assert_true(fabs(out[q] - want[q]) <= 1e-14 * fabs(want[q]));
  }
}

static void test_stiff_triangle(void **state) {
  (void)state;
  double work[5 * 4], out[4];
  const double lam[] = {-3e4, -400, -2.5}, mu[] = {-2, -1e-3, 0.75}, c[] = {5, 1e3, -7};
  for (int k = 0; k < 3; k++) {
    double l = lam[k], u = mu[k];
    double a[4] = {l, 0, c[k], u};
    la_dense_expm_stiff(a, 2, out, work);
    /* the diagonal rounds at 1 (I + X); the corner, e^l - e^u = e^u
     * expm1(l - u) with no cancellation, to its own size */
    assert_true(out[1] == 0);
    assert_true(fabs(out[0] - exp(l)) <= 1e-15 * fmax(1, exp(l)));
    assert_true(fabs(out[3] - exp(u)) <= 1e-15 * fmax(1, exp(u)));
    double want = c[k] * exp(u) * expm1(l - u) / (l - u);
    check(out + 2, &want, 1, 1e-13);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_rotation),
    cmocka_unit_test(test_jordan),
    cmocka_unit_test(test_stiff_triangle),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
