/* pss_measure with the period's jump times (src/analysis/pss_run.h;
 * docs/steady-state.md, "Signals that jump") on signals made here, whose
 * figures are closed forms, no integrator in between:
 *   - the sawtooth frac(t/T - tau): average 1/2, RMS 1/sqrt(3), extremes 0
 *     and 1 (its left side at the jump), harmonics 1/(pi k), THD
 *     sqrt(sum_{k=2..K} 1/k^2); piecewise linear, so exact to rounding,
 *     with tau between two samples and on one;
 *   - the rectangle 1 on [0, D T), 0 after (jumps at the period's start and
 *     inside it): average D, RMS sqrt(D), fundamental 2 sin(pi D) / pi, and
 *     the power of the rectangle times the sawtooth;
 *   - a sine, continuous at the jump times given: the figures of
 *     cup_measure_period bit for bit.
 * Before the jumps were measured as jumps the sawtooth's average was off by
 * up to h/2 (the trapezoid rule across the jump). */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>
#include "catchup.h"
#include "analysis/pss_run.h"

#define N 101                   /* samples: M = 100 intervals of h = T / 100 */
#define K 6                     /* harmonics */
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const double T = 2e-3;

static double saw(double t, double tau) {
  double x = t / T - tau;
  return x - floor(x);
}

/* One signal's figures by pss_measure with the jump times jt. */
static void measure(const double *v, const double *jt, int nj, cup_measure *m, double *amp) {
  int idx = 0;
  double phase[K + 1], w[N];
  pss_figures f = {1, &idx, K, 0, NULL, NULL, -1, -1, m, amp, phase, NULL, NAN, jt, nj, T, 0};
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(pss_measure(v, N, 1, &f, w, err), CUP_OK);
}

static void sawtooth(void **state) {
  (void)state;
  const double taus[2] = {0.3731, 0.4};          /* between samples 37 and 38; on sample 40 */
  for (int c = 0; c < 2; c++) {
    double tau = taus[c], v[N], jt = tau * T, amp[K + 1];
    for (int k = 0; k < N; k++) v[k] = saw(k * T / (N - 1), tau);
    cup_measure m;
    measure(v, &jt, 1, &m, amp);
    double thd = 0;
    for (int k = 2; k <= K; k++) thd += 1.0 / (k * k);
    thd = sqrt(thd);
    print_message("tau %.4f: avg %.17g rms %.17g (1/sqrt 3 %+.2g) min %.3g max %.17g A1 %.17g (1/pi %+.2g) "
                  "THD %.15g (%+.2g)\n", tau, m.avg, m.rms, m.rms - 1 / sqrt(3), m.min, m.max, amp[1],
                  amp[1] - 1 / M_PI, m.thd, m.thd - thd);
    assert_true(fabs(m.avg - 0.5) <= 1e-14);
    assert_true(fabs(m.rms - 1 / sqrt(3)) <= 1e-14);
    assert_true(fabs(m.min) <= 1e-14 && fabs(m.max - 1) <= 1e-13 && fabs(m.pp - 1) <= 1e-13);
    for (int k = 1; k <= K; k++) assert_true(fabs(amp[k] - 1 / (M_PI * k)) <= 1e-13);
    assert_true(fabs(m.thd - thd) <= 1e-12);
    /* without the jump time: the samples' trapezoid rule, off by up to h/2 */
    cup_measure p;
    measure(v, NULL, 0, &p, amp);
    print_message("           without the time: avg %.17g (%+.2g)\n", p.avg, p.avg - 0.5);
  }
}

static void rectangle_and_power(void **state) {
  (void)state;
  const double D = 0.3137, tau = 0.3731;
  double v[2 * N], jt[2] = {D * T, tau * T}, amp[K + 1];   /* v(t), then the sawtooth as current */
  for (int k = 0; k < N; k++) v[2 * k] = k < N - 1 && k * T / (N - 1) < D * T ? 1 : 0;   /* v[M]: the left side at T */
  for (int k = 0; k < N; k++) v[2 * k + 1] = saw(k * T / (N - 1), tau);
  cup_measure m;
  int idx = 0, pv = 0, pc = 1;
  double phase[K + 1], w[N], power;
  pss_figures f = {1, &idx, K, 1, &pv, &pc, -1, -1, &m, amp, phase, &power, NAN, jt, 2, T, 0};
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(pss_measure(v, N, 2, &f, w, err), CUP_OK);
  /* the power: the sawtooth's integral over [0, D): from 1 - tau to 1 over [0, tau), 0 to D - tau after */
  double P = D < tau ? (1 - tau) * D + D * D / 2 : (1 - tau / 2) * tau + (D - tau) * (D - tau) / 2;
  print_message("rectangle D %.4f: avg %.17g rms %.17g A1 %.17g (2 sin(pi D)/pi %+.2g); power %.17g (%+.2g)\n", D,
                m.avg, m.rms, amp[1], amp[1] - 2 * sin(M_PI * D) / M_PI, power, power - P);
  assert_true(fabs(m.avg - D) <= 1e-14);
  assert_true(fabs(m.rms - sqrt(D)) <= 1e-14);
  assert_true(fabs(amp[1] - 2 * sin(M_PI * D) / M_PI) <= 1e-13);
  assert_true(m.min == 0 && m.max == 1);
  assert_true(fabs(power - P) <= 1e-14);
}

static void continuous(void **state) {
  (void)state;
  double v[N], jt[3] = {0.25 * T, 0.5 * T, 0.61 * T}, amp[K + 1], amp0[K + 1], ph0[K + 1], w[N];
  for (int k = 0; k < N; k++) v[k] = 3 + sin(2 * M_PI * k / (N - 1)) + 0.1 * cos(6 * M_PI * k / (N - 1));
  cup_measure m, m0;
  measure(v, jt, 3, &m, amp);
  char err[CUP_ERRMSG_LEN];
  (void)w;
  assert_int_equal(cup_measure_period(v, N, K, &m0, amp0, ph0, err), CUP_OK);
  assert_memory_equal(&m, &m0, sizeof m);
  assert_memory_equal(amp, amp0, sizeof amp);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(sawtooth),
      cmocka_unit_test(rectangle_and_power),
      cmocka_unit_test(continuous),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
