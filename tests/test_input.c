/* input: waveform values and integrals against closed forms and GSL
 * quadrature with the jump points given, sign(0) = 0 at jump instants, the
 * callback path, breakpoints, validation. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>
#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>
#include "testutil.h"
#include "input_impl.h"                          /* input_next_break_memo, input_term_piece */

static cup_input *make(int p) {
  cup_input *u = NULL;
  assert_int_equal(cup_input_create(&u, p, NULL), CUP_OK);
  return u;
}

/* the paper's inputs */
static cup_input *case1(void) {
  cup_input *u = make(1);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 16, .frequency = 3};
  cup_wave c = {.kind = CUP_WAVE_CONSTANT, .value = -0.5};
  assert_int_equal(cup_input_add(u, 0, &s, NULL), CUP_OK);
  assert_int_equal(cup_input_add(u, 0, &c, NULL), CUP_OK);
  return u;
}
static cup_input *case2(void) {
  cup_input *u = make(1);
  cup_wave q = {.kind = CUP_WAVE_SQUARE, .amplitude = 1, .frequency = 2};
  assert_int_equal(cup_input_add(u, 0, &q, NULL), CUP_OK);
  return u;
}

static void test_case1_values_and_integrals(void **state) {
  (void)state;
  cup_input *u = case1();
  rng_t r = {1};
  for (int k = 0; k < 1000; k++) {
    double a = rng_unif(&r), b = a + 1e-6 + rng_unif(&r) * (k % 2 ? 1e-3 : 0.5), v, I;
    assert_int_equal(cup_input_eval(u, a, &v), CUP_OK);
    assert_close(v, 16 * sin(6 * M_PI * a) - 0.5, 1e-13);
    assert_int_equal(cup_input_integral(u, a, b, &I), CUP_OK);
    /* closed form in long double: 16 (cos 6 pi a - cos 6 pi b) / (6 pi) - 0.5 (b - a) */
    long double ref = 16.0L * (cosl(6 * M_PIl * a) - cosl(6 * M_PIl * b)) / (6 * M_PIl) - 0.5L * (b - a);
    assert_close(I, (double)ref, 1e-14 * (1 + fabs((double)ref)));   /* rounding of sin(6 pi t), t <= 1.5 */
  }
  assert_int_equal(cup_input_is_constant(u), 0);
  cup_input_free(&u);
  assert_null(u);
}

static void test_sign_of_zero_at_jumps(void **state) {
  (void)state;
  cup_input *u = case2();
  double v;
  /* sign(sin(4 pi t)) jumps at multiples of 1/4; the paper takes sign(0) = 0 */
  static const double jumps[] = {0, 0.25, 0.5, 0.75, 1.0};
  for (int k = 0; k < 5; k++) {
    assert_int_equal(cup_input_eval(u, jumps[k], &v), CUP_OK);
    assert_true(v == 0);
  }
  for (long n = 4; n <= 4000000; n *= 10) {   /* grid points t_k = k/n that are jumps */
    double h = 1.0 / (double)n;
    assert_int_equal(cup_input_eval(u, (double)(n / 4) * h, &v), CUP_OK);
    assert_true(v == 0);
  }
  cup_input_eval(u, 0.1, &v); assert_true(v == 1);
  cup_input_eval(u, 0.3, &v); assert_true(v == -1);
  cup_input_eval(u, 0.25 + 1e-12, &v); assert_true(v == -1);
  cup_input_free(&u);
}

static double square_fn(double t, void *p) {
  (void)p;
  double s = sin(4 * M_PI * t);
  return s > 0 ? 1 : s < 0 ? -1 : 0;
}

static void test_square_integral_against_quadrature(void **state) {
  (void)state;
  cup_input *u = case2();
  gsl_set_error_handler_off();                 /* GSL's default handler aborts */
  gsl_integration_workspace *w = gsl_integration_workspace_alloc(1000);
  rng_t r = {2};
  for (int k = 0; k < 300; k++) {
    double a = 2 * rng_unif(&r), b = a + rng_unif(&r) * (k % 3 ? 0.01 : 1.3), I;
    assert_int_equal(cup_input_integral(u, a, b, &I), CUP_OK);
    /* QAGP with every jump inside [a, b] as a break point */
    double pts[64];
    int np = 0;
    pts[np++] = a;
    for (int j = (int)ceil(4 * a); j / 4.0 < b; j++) if (j / 4.0 > a) pts[np++] = j / 4.0;
    pts[np++] = b;
    gsl_function F = {square_fn, NULL};
    double ref, err;
    gsl_integration_qagp(&F, pts, (size_t)np, 1e-12, 1e-12, 1000, w, &ref, &err);
    assert_close(I, ref, 1e-11);
  }
  gsl_integration_workspace_free(w);
  cup_input_free(&u);
}

static void test_table(void **state) {
  (void)state;
  cup_input *u = make(2);
  double t[3] = {0, 1, 3}, v[3] = {0, 2, -1};
  cup_wave pwl = {.kind = CUP_WAVE_PWL, .npoints = 3, .t = t, .v = v};
  cup_wave c = {.kind = CUP_WAVE_CONSTANT, .value = 5};
  assert_int_equal(cup_input_add(u, 1, &pwl, NULL), CUP_OK);
  assert_int_equal(cup_input_add(u, 0, &c, NULL), CUP_OK);
  double val[2], I[2];
  cup_input_eval(u, 2, val);
  assert_close(val[1], 0.5, 1e-15);              /* halfway between 2 and -1 */
  assert_close(val[0], 5, 0);
  cup_input_eval(u, -7, val); assert_close(val[1], 0, 0);
  cup_input_eval(u, 9, val); assert_close(val[1], -1, 0);
  /* over [-1, 4]: tail 0 + 1 (triangle to 2) + 1 (trapezoid 2 -> -1 over 2) - 1 (tail) */
  cup_input_integral(u, -1, 4, I);
  assert_close(I[1], 1, 1e-15);
  assert_close(I[0], 25, 1e-14);
  cup_input_integral(u, 0.5, 2, I);             /* 0.75*0.5... by hand: 1.5*0.5 + (2+0.5)/2*1 */
  assert_close(I[1], 0.5 * (1 + 2) * 0.5 + 0.5 * (2 + 0.5) * 1, 1e-15);
  assert_close(cup_input_next_break(u, 0.5), 1, 0);
  assert_close(cup_input_next_break(u, 1), 3, 0);
  assert_true(isinf(cup_input_next_break(u, 3)));
  cup_input_free(&u);
}

static void test_breaks_of_the_square_wave(void **state) {
  (void)state;
  cup_input *u = case2();
  double t = 0;
  for (int k = 1; k <= 8; k++) {
    t = cup_input_next_break(u, t);
    assert_close(t, k * 0.25, 1e-15);
  }
  cup_input_free(&u);
}

static int quad_cb(double t, double *out, void *ctx) {
  int *calls = ctx;
  (*calls)++;
  out[0] = t * t;
  out[1] = exp(t);
  return 0;
}
static int nan_cb(double t, double *out, void *ctx) {
  (void)ctx;
  out[0] = t > 0.5 ? NAN : 1;
  return 0;
}
static int fail_cb(double t, double *out, void *ctx) {
  (void)ctx; (void)t;
  out[0] = 0;
  return 7;
}

static void test_callback(void **state) {
  (void)state;
  cup_input *u = make(2);
  int calls = 0;
  assert_int_equal(cup_input_set_callback(u, quad_cb, &calls, 1e-13, 1e-12), CUP_OK);
  double I[2];
  assert_int_equal(cup_input_integral(u, 0, 1, I), CUP_OK);
  assert_close(I[0], 1.0 / 3, 1e-13);
  assert_close(I[1], M_E - 1, 1e-12);
  assert_true(calls > 0);
  assert_int_equal(cup_input_is_constant(u), 0);
  cup_input_free(&u);
  u = make(1);
  cup_input_set_callback(u, nan_cb, NULL, 1e-10, 0);
  assert_int_equal(cup_input_integral(u, 0, 1, I), CUP_ERR_CALLBACK);
  double v;
  assert_int_equal(cup_input_eval(u, 0.9, &v), CUP_ERR_CALLBACK);
  cup_input_set_callback(u, fail_cb, NULL, 1e-10, 0);
  assert_int_equal(cup_input_eval(u, 0.1, &v), CUP_ERR_CALLBACK);
  assert_int_equal(cup_input_set_callback(u, fail_cb, NULL, 0, 0), CUP_ERR_ARG);
  cup_input_free(&u);
}

static void test_validation(void **state) {
  (void)state;
  char msg[CUP_ERRMSG_LEN];
  cup_input *u = make(1);
  double t[3] = {0, 2, 1}, v[3] = {0, 1, 2};
  cup_wave bad = {.kind = CUP_WAVE_PWL, .npoints = 3, .t = t, .v = v};
  assert_int_equal(cup_input_add(u, 0, &bad, msg), CUP_ERR_ARG);
  assert_non_null(strstr(msg, "point 2"));
  cup_wave neg = {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = -1};
  assert_int_equal(cup_input_add(u, 0, &neg, msg), CUP_ERR_ARG);
  assert_non_null(strstr(msg, "frequency"));
  cup_wave nan = {.kind = CUP_WAVE_CONSTANT, .value = NAN};
  assert_int_equal(cup_input_add(u, 0, &nan, msg), CUP_ERR_NONFINITE);
  cup_wave ok = {.kind = CUP_WAVE_CONSTANT, .value = 2};
  assert_int_equal(cup_input_add(u, 1, &ok, msg), CUP_ERR_DIM);
  assert_int_equal(cup_input_add(u, 0, &ok, msg), CUP_OK);
  assert_int_equal(cup_input_is_constant(u), 1);
  double I;
  cup_input_integral(u, 1, 4, &I);
  assert_close(I, 6, 0);
  cup_input_free(&u);
}

/* SPICE's PULSE(0 5 1m 0.5m 0.25m 2m 5m): values by hand, the period's
 * integral in closed form (flat parts and trapezoids), integrals across
 * periods against long-double sums of the same pieces, breakpoints. */
static void test_pulse(void **state) {
  (void)state;
  cup_input *u = make(1);
  cup_wave w = {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 5, .delay = 1e-3, .rise = 0.5e-3, .fall = 0.25e-3,
                .width = 2e-3, .period = 5e-3};
  assert_int_equal(cup_input_add(u, 0, &w, NULL), CUP_OK);
  assert_int_equal(cup_input_is_constant(u), 0);
  const double t[] = {0, 1e-3, 1.25e-3, 2e-3, 3.5e-3, 3.625e-3, 4e-3, 6.25e-3, 11e-3 + 0.1e-3};
  const double v[] = {0, 0, 2.5, 5, 5, 2.5, 0, 2.5, 1};
  for (size_t k = 0; k < sizeof t / sizeof t[0]; k++) {
    double out;
    cup_input_eval(u, t[k], &out);
    assert_close(out, v[k], 1e-12);
  }
  /* one period: 5 (2m) + 2.5 (0.5m + 0.25m) */
  double per = 5 * 2e-3 + 2.5 * 0.75e-3, out;
  cup_input_integral(u, 1e-3, 6e-3, &out);
  assert_close(out, per, 1e-15);
  cup_input_integral(u, 1e-3, 1e-3 + 7 * 5e-3, &out);
  assert_close(out, 7 * per, 1e-14);
  /* [0.5m, 2m]: 0 until 1m, the ramp to 5 (0.5m), 5 for 0.5m */
  cup_input_integral(u, 0.5e-3, 2e-3, &out);
  assert_close(out, 2.5 * 0.5e-3 + 5 * 0.5e-3, 1e-15);
  const double brk[][2] = {{0, 1e-3}, {1e-3, 1.5e-3}, {1.6e-3, 3.5e-3}, {3.5e-3, 3.75e-3}, {3.8e-3, 6e-3},
                           {6e-3, 6.5e-3}};
  for (size_t k = 0; k < sizeof brk / sizeof brk[0]; k++)
    assert_close(cup_input_next_break(u, brk[k][0]), brk[k][1], 1e-15);
  /* walked from break to break, every corner of 20 periods in turn: 1m +
   * 5m j + (0, 0.5m, 2.5m, 2.75m) (a period's end that rounds onto the
   * next period, 11m, once skipped that whole period) */
  double tb = 0;
  for (int j = 0; j < 20; j++)
    for (int k = 0; k < 4; k++) {
      const double knot[4] = {0, 0.5e-3, 2.5e-3, 2.75e-3};
      tb = cup_input_next_break(u, tb);
      if (fabs(tb - (1e-3 + 5e-3 * j + knot[k])) > 1e-15)
        fail_msg("period %d, corner %d: break at %.17g", j, k, tb);
    }
  cup_input_free(&u);
  /* a one-shot pulse (period 0) with a jump up (rise 0) */
  u = make(1);
  cup_wave one = {.kind = CUP_WAVE_PULSE, .value = 1, .value2 = 3, .delay = 1, .width = 2, .fall = 1};
  assert_int_equal(cup_input_add(u, 0, &one, NULL), CUP_OK);
  cup_input_eval(u, 1, &out);
  assert_close(out, 3, 0);                      /* right-continuous at the jump */
  cup_input_integral(u, 0, 10, &out);
  assert_close(out, 1 * 1 + 3 * 2 + 2 * 1 + 1 * 6, 1e-14);
  assert_true(isinf(cup_input_next_break(u, 4.5)));
  cup_input_free(&u);
  cup_wave bad = w;
  bad.period = 2e-3;                            /* shorter than rise + width + fall */
  char msg[CUP_ERRMSG_LEN];
  u = make(1);
  assert_int_equal(cup_input_add(u, 0, &bad, msg), CUP_ERR_ARG);
  assert_non_null(strstr(msg, "period"));
  cup_input_free(&u);
}

/* SPICE's SIN with delay and damping: values by hand; integrals against the
 * antiderivative A e^{-d s} (-d sin - w cos)(w s + p)/(d^2 + w^2) evaluated
 * in long double, over long and very short intervals. */
static long double damped_F(long double A, long double d, long double w, long double p, long double s) {
  return A * expl(-d * s) * (-d * sinl(w * s + p) - w * cosl(w * s + p)) / (d * d + w * w);
}

/* A PULSE with jump edges (the buck's gate, PULSE(0 1 0 jump jump 5u 10u),
 * its 10u read as 10 * 1e-6): walked from break to break over 200 periods,
 * the value is the piece before each corner an ulp below it and the piece
 * after it from the corner on, so that a switching time found from the
 * value is the breakpoint itself (it fell an ulp off, the window after it
 * paying a piece of length 0; and a time an ulp short of a period's start
 * whose quotient rounded up read the rise of length 0 as -inf). */
static void test_pulse_corners(void **state) {
  (void)state;
  cup_input *u = make(1);
  cup_wave w = {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .width = 5 * 1e-6, .period = 10 * 1e-6};
  assert_int_equal(cup_input_add(u, 0, &w, NULL), CUP_OK);
  double tb = 0, out;
  for (int k = 0; k < 400; k++) {
    double prev = tb;
    tb = cup_input_next_break(u, tb);
    if (!(tb > prev && tb - prev < 5.0001e-6 && tb - prev > 4.9999e-6))
      fail_msg("corner %d: break at %.17g after %.17g", k, tb, prev);
    cup_input_eval(u, nextafter(tb, 0), &out);
    if (out != (k % 2 ? 0 : 1)) fail_msg("corner %d (%.17g): %g an ulp before it", k, tb, out);
    cup_input_eval(u, tb, &out);
    if (out != (k % 2 ? 1 : 0)) fail_msg("corner %d (%.17g): %g at it", k, tb, out);
  }
  cup_input_free(&u);
}

static void test_damped_sine(void **state) {
  (void)state;
  double A = 2, f = 50, d = 30, p = 0.4, td = 3e-3;
  cup_input *u = make(1);
  cup_wave w = {.kind = CUP_WAVE_DAMPED_SINE, .amplitude = A, .frequency = f, .phase = p, .delay = td,
                .damping = d};
  assert_int_equal(cup_input_add(u, 0, &w, NULL), CUP_OK);
  double out;
  cup_input_eval(u, 1e-3, &out);
  assert_close(out, A * sin(p), 1e-15);
  cup_input_eval(u, 10e-3, &out);
  assert_close(out, A * exp(-d * 7e-3) * sin(2 * M_PI * f * 7e-3 + p), 1e-14);
  long double om = 2 * M_PIl * f;
  const double iv[][2] = {{td, td + 0.1}, {0.02, 0.02 + 1e-9}, {0.011, 0.037}};
  for (size_t k = 0; k < sizeof iv / sizeof iv[0]; k++) {
    long double ref = damped_F(A, d, om, p, iv[k][1] - td) - damped_F(A, d, om, p, iv[k][0] - td);
    cup_input_integral(u, iv[k][0], iv[k][1], &out);
    assert_close(out, (double)ref, 1e-14 * fabs((double)ref) + 1e-17);
  }
  cup_input_integral(u, 0, td, &out);                    /* before the delay: A sin(p) */
  assert_close(out, A * sin(p) * td, 1e-17);
  assert_close(cup_input_next_break(u, 0), td, 0);
  assert_true(isinf(cup_input_next_break(u, td)));
  cup_input_free(&u);
}

/* The full bridge's gates: PULSE(0 1 d jump jump 49u 100u), d = 1u, 51u,
 * 76u, 26u. */
static const double fb_delay[4] = {1e-6, 51e-6, 76e-6, 26e-6}, fb_width = 49e-6, fb_period = 100e-6;

static cup_input *full_bridge_gates(void) {
  cup_input *u = make(5);
  cup_wave dc = {.kind = CUP_WAVE_CONSTANT, .value = 100};
  assert_int_equal(cup_input_add(u, 0, &dc, NULL), CUP_OK);
  for (int g = 0; g < 4; g++) {
    cup_wave w = {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .delay = fb_delay[g], .width = fb_width,
                  .period = fb_period};
    assert_int_equal(cup_input_add(u, 1 + g, &w, NULL), CUP_OK);
  }
  return u;
}

/* The first corner of the full bridge's gates after t in closed form:
 * SPICE's PULSE corners d + P j (rise) and d + P j + (0 + width) (fall),
 * summed in that order. */
static double fb_corner_after(double t) {
  double best = INFINITY;
  for (int g = 0; g < 4; g++)
    for (int j = 0; j < 200; j++) {
      double base = fb_delay[g] + fb_period * j, c[2] = {base, base + (0 + fb_width)};
      for (int k = 0; k < 2; k++)
        if (c[k] > t && c[k] < best) best = c[k];
    }
  return best;
}

/* input_next_break_memo, term by term from memos a run keeps, against the
 * closed form of the full bridge's gates walked from corner to corner over
 * 100 periods (800 corners), and against cup_input_next_break (no memo) at
 * random times, forwards and backwards, at every corner and an ulp either
 * side of it, for a mix of every kind of term: ramps, a pulse whose period
 * is rise + width + fall (a period's last corner and the next's first
 * round either way), a one-shot pulse, a table, a damped sine's delay, a
 * square wave (asked afresh) and terms past the memos' room (nm). */
static void test_break_memos(void **state) {
  (void)state;
  cup_input *u = full_bridge_gates();
  input_break_memo m[8] = {{0}};
  double t = 0;
  for (int k = 0; k < 800; k++) {
    double want = fb_corner_after(t), got = input_next_break_memo(u, m, 8, t);
    if (got != want) fail_msg("corner %d after %.17g: %.17g, the closed form %.17g", k, t, got, want);
    t = got;
  }
  cup_input_free(&u);

  u = make(3);
  double pt[4] = {0.2e-3, 1e-3, 1.7e-3, 4e-3}, pv[4] = {0, 1, -1, 2};
  const cup_wave w[] = {
    {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 5, .delay = 1e-3, .rise = 0.5e-3, .fall = 0.25e-3,
     .width = 2e-3, .period = 5e-3},
    {.kind = CUP_WAVE_PULSE, .value = -1, .value2 = 1, .delay = 0.1e-3, .rise = 0.3e-3, .fall = 0.3e-3,
     .width = 0.4e-3, .period = 1e-3},
    {.kind = CUP_WAVE_PULSE, .value = 1, .value2 = 3, .delay = 1e-3, .width = 2e-3, .fall = 1e-3},
    {.kind = CUP_WAVE_PWL, .npoints = 4, .t = pt, .v = pv},
    {.kind = CUP_WAVE_DAMPED_SINE, .amplitude = 1, .frequency = 1e3, .delay = 2.5e-3, .damping = 10},
    {.kind = CUP_WAVE_SQUARE, .amplitude = 1, .frequency = 700},
    {.kind = CUP_WAVE_SINE, .amplitude = 1, .frequency = 50},
    {.kind = CUP_WAVE_CONSTANT, .value = 2},
    {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .delay = 0.05e-3, .width = 0.3e-3, .period = 0.7e-3},
  };
  for (size_t k = 0; k < sizeof w / sizeof w[0]; k++) assert_int_equal(cup_input_add(u, (int)k % 3, &w[k], NULL), CUP_OK);
  double corner[4096];
  int nc = 0;
  for (double b = cup_input_next_break(u, 0); b < 12e-3 && nc < 4096; b = cup_input_next_break(u, b)) corner[nc++] = b;
  assert_true(nc > 100 && nc < 4096);
  for (int nm = 0; nm <= 9; nm += 3) {
    input_break_memo mm[9];
    memset(mm, 0, sizeof mm);
    rng_t r = {7 + (uint64_t)nm};
    long checked = 0;
    for (int pass = 0; pass < 3; pass++)
      for (int c = 0; c < nc; c++) {
        /* each corner, an ulp either side, and a random time (now and then far back) */
        double tq[4] = {nextafter(corner[c], 0), corner[c], nextafter(corner[c], 1), rng_unif(&r) * 12e-3};
        if (pass == 2) tq[3] = corner[c] * rng_unif(&r);
        for (int q = 0; q < 4; q++) {
          double want = cup_input_next_break(u, tq[q]), got = input_next_break_memo(u, mm, nm, tq[q]);
          if (memcmp(&got, &want, sizeof got))
            fail_msg("nm %d, t = %.17g: %.17g, without memos %.17g", nm, tq[q], got, want);
          checked++;
        }
      }
    assert_int_equal(checked, 12L * nc);
  }
  cup_input_free(&u);
}

/* input_term_piece: a jump PULSE's value and the end of its piece, against
 * the closed form (value2 on [d + P j, d + P j + width), value else; the
 * piece ends at the next corner) and against input_term_value at the
 * piece's start, middle and last double; a constant's for ever; other
 * kinds no piece (hi = t) with input_term_value's value. */
static void test_term_piece(void **state) {
  (void)state;
  cup_input *u = full_bridge_gates();
  rng_t r = {3};
  for (int k = 0; k < 4000; k++) {
    double t = k < 800 ? fb_corner_after(k ? fb_corner_after(k * 12.5e-6 - 1e-9) - 1e-9 : 0) : rng_unif(&r) * 1e-2;
    if (k >= 400 && k < 800) t = nextafter(t, 0);
    for (int g = 0; g < 4; g++) {
      const input_term *w = &u->terms[1 + g];
      double hi, v = input_term_piece(w, t, &hi);
      double s = t - fb_delay[g], j = floor(s / fb_period), on = s >= 0 && s - j * fb_period < fb_width;
      /* (the closed form's own rounding aside: only where t is clear of a corner) */
      double base = fb_delay[g] + fb_period * j;
      int clear = fabs(t - base) > 1e-12 && fabs(t - (base + fb_width)) > 1e-12 &&
                  fabs(t - (base + fb_period)) > 1e-12;
      if (clear && v != on) fail_msg("gate %d at %.17g: %g, the closed form %g", g, t, v, on);
      double next_corner = INFINITY;
      for (int jj = 0; jj < 110; jj++) {
        double b0 = fb_delay[g] + fb_period * jj, c[2] = {b0, b0 + (0 + fb_width)};
        for (int q = 0; q < 2; q++)
          if (c[q] > t && c[q] < next_corner) next_corner = c[q];
      }
      if (hi != next_corner) fail_msg("gate %d at %.17g: piece to %.17g, next corner %.17g", g, t, hi, next_corner);
      double mid = t + (hi - t) / 2;                /* (an ulp's piece: its middle rounds to hi) */
      const double at[3] = {t, mid < hi ? mid : t, nextafter(hi, t)};
      for (int q = 0; q < 3; q++)
        if (input_term_value(w, at[q]) != v)
          fail_msg("gate %d: %g on [%.17g, %.17g) but %g at %.17g", g, v, t, hi, input_term_value(w, at[q]), at[q]);
      if (input_term_value(w, hi) == v) fail_msg("gate %d: the same value after its corner %.17g", g, hi);
    }
    double hi, v = input_term_piece(&u->terms[0], rng_unif(&r), &hi);
    assert_true(v == 100 && isinf(hi));
  }
  cup_input_free(&u);
  u = make(1);
  cup_wave ramp = {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .rise = 1e-6, .fall = 1e-6, .width = 3e-6,
                   .period = 10e-6};
  assert_int_equal(cup_input_add(u, 0, &ramp, NULL), CUP_OK);
  double hi, v = input_term_piece(&u->terms[0], 0.5e-6, &hi);
  assert_true(hi == 0.5e-6 && v == input_term_value(&u->terms[0], 0.5e-6) && v > 0.49 && v < 0.51);
  cup_input_free(&u);
}

/* spice_jump_pulse_next: a jump PULSE's pieces walked one after another
 * from the period each was in, bit for bit spice_jump_pulse's (value and
 * end) at each piece's start and at the end of the last (and its breaks by
 * spice_jump_break, spice_term_break's), and each end the
 * closed form's next corner d + P j or d + P j + (0 + width) (a width
 * below P): the full bridge's gates, a buck's gate (width P / 2 from 0),
 * awkward decimals over 100,000 periods, a width of 0 and of P (the most
 * spice_term_init takes), and a one-shot pulse. */
static void test_jump_pulse_walk(void **state) {
  (void)state;
  const cup_wave w[] = {
    {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .delay = 1e-6, .width = 49e-6, .period = 100e-6},
    {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .delay = 51e-6, .width = 49e-6, .period = 100e-6},
    {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .delay = 0, .width = 5e-6, .period = 10e-6},
    {.kind = CUP_WAVE_PULSE, .value = -3, .value2 = 7, .delay = 0.3e-6, .width = 1.1e-6, .period = 3.3e-6},
    {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .delay = 2e-6, .width = 0, .period = 3e-6},
    {.kind = CUP_WAVE_PULSE, .value = 0, .value2 = 1, .delay = 1e-6, .width = 3e-6, .period = 3e-6},
    {.kind = CUP_WAVE_PULSE, .value = 1, .value2 = 2, .delay = 1e-6, .width = 2e-6},
  };
  const long pieces[] = {2000, 2000, 2000, 200000, 2000, 2000, 5};
  for (size_t q = 0; q < sizeof w / sizeof w[0]; q++) {
    cup_input *u = make(1);
    assert_int_equal(cup_input_add(u, 0, &w[q], NULL), CUP_OK);
    const input_term *tm = &u->terms[0];
    double t = 0, j, hi, hw, v = spice_jump_pulse_j(tm, t, &j, &hi);
    for (long k = 0; k < pieces[q] && isfinite(hi); k++) {
      double want = spice_jump_pulse(tm, t, &hw);
      if (v != want || hi != hw) fail_msg("pulse %zu, piece %ld at %.17g: %g to %.17g, spice_jump_pulse %g to %.17g",
                                          q, k, t, v, hi, want, hw);
      double corner = INFINITY, P = w[q].period, d = w[q].delay;   /* the closed form's next corner */
      for (double jj = P > 0 ? fmax(floor((t - d) / P) - 2, 0) : 0; jj < (P > 0 ? floor((t - d) / P) + 3 : 1); jj++) {
        double c[2] = {d + P * jj, d + P * jj + (0 + w[q].width)};
        for (int e = 0; e < 2; e++)
          if (c[e] > t && c[e] < corner) corner = c[e];
      }
      /* (a width of P is on from d: its pieces are periods, and a top's
       * end may round an ulp past the next period's start) */
      if (hi != corner && !(P > 0 && w[q].width == P))
        fail_msg("pulse %zu, piece %ld at %.17g: ends at %.17g, the next corner %.17g", q, k, t, hi, corner);
      t = hi;
      v = spice_jump_pulse_next(tm, t, &j, &hi);
    }
    double per = 0, b = 0;                         /* the breaks likewise, against spice_term_break's */
    for (long k = 0; k < pieces[q] && isfinite(b); k++) {
      double want = spice_term_break(tm, b), got = spice_jump_break(tm, b, &per);
      if (memcmp(&got, &want, sizeof got)) fail_msg("pulse %zu, break %ld after %.17g: %.17g, spice_term_break %.17g",
                                                    q, k, b, got, want);
      b = got;
    }
    cup_input_free(&u);
  }
}

/* Three phases of one frequency, a fourth sine of another and a silent
 * one (input_gen_rot_plan): the first sine of a frequency with an
 * amplitude has states; the others of its frequency share them, and their
 * values u = U w and slopes U W w stay within the rounding of the direct
 * form's own argument (an ulp of omega a + phi, a few ulps of the
 * amplitude) of amp sin(omega a + phi) and amp omega cos(omega a + phi)
 * over 100 periods. */
static void test_gen_shared_sines(void **state) {
  (void)state;
  enum { NT = 5 };
  cup_input *u = make(NT);
  const double ph[NT] = {0.7, 0.3, 0.3 - 2 * M_PI / 3, 0.3 + 2 * M_PI / 3, 1.1}, amp[NT] = {0, 100, 230, 50, 7},
               hz[NT] = {50, 50, 50, 50, 60};
  for (int k = 0; k < NT; k++) {
    cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = amp[k], .frequency = hz[k], .phase = ph[k]};
    assert_int_equal(cup_input_add(u, k, &s, NULL), CUP_OK);
  }
  input_gen_rot rot[NT];
  input_gen_rot_plan(u, rot);
  /* the silent sine keeps states of its own and is nobody's base */
  assert_true(rot[0].base == -1 && rot[1].base == -1 && rot[2].base == 1 && rot[3].base == 1 && rot[4].base == -1);
  int first[NT], own[NT];
  assert_int_equal(input_gen_dim(u, NULL, own), 10);
  int nw = input_gen_dim(u, rot, first);
  assert_int_equal(nw, 6);
  assert_true(first[2] == first[1] && first[3] == first[1]);
  double U[NT * 6] = {0}, W[6 * 6] = {0};
  input_gen_output(u, rot, first, U, NT);
  input_gen_dynamics(u, rot, first, W, 6);
  rng_t r = {11};
  double worst = 0;
  for (int i = 0; i < 20000; i++) {
    double a = rng_unif(&r) * 2.0, w[6], dw[6] = {0};
    input_gen_piece(u, first, rot, a, a + 1e-4, w);
    for (int c = 0; c < 6; c++)
      for (int q = 0; q < 6; q++) dw[q] += W[q + 6 * c] * w[c];
    for (int k = 0; k < NT; k++) {
      const input_term *t = &u->terms[k];
      double v = 0, dv = 0, x = t->omega * a + t->phase;
      for (int c = 0; c < nw; c++) {
        v += U[k + NT * c] * w[c];
        dv += U[k + NT * c] * dw[c];
      }
      double bound = 8 * DBL_EPSILON * (fabs(t->omega * a) + fabs(t->phase) + 1) * amp[k];
      double e0 = fabs(v - t->amp * sin(x)), e1 = fabs(dv - t->amp * t->omega * cos(x)) / t->omega;
      if (rot[k].base < 0) {                     /* a base's value is its own sine, bit for bit */
        assert_true(v == t->amp * sin(x));
        continue;
      }
      worst = fmax(worst, fmax(e0, e1) / t->amp);
      if (!(e0 <= bound && e1 <= bound))
        fail_msg("sine %d at a = %.17g: %.3g and %.3g off the direct form (bound %.3g)", k, a, e0, e1, bound);
    }
  }
  printf("shared sines: %.3g of their amplitude off the direct form at worst\n", worst);
  cup_input_free(&u);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_case1_values_and_integrals),
    cmocka_unit_test(test_sign_of_zero_at_jumps),
    cmocka_unit_test(test_square_integral_against_quadrature),
    cmocka_unit_test(test_table),
    cmocka_unit_test(test_breaks_of_the_square_wave),
    cmocka_unit_test(test_callback),
    cmocka_unit_test(test_validation),
    cmocka_unit_test(test_pulse),
    cmocka_unit_test(test_pulse_corners),
    cmocka_unit_test(test_break_memos),
    cmocka_unit_test(test_term_piece),
    cmocka_unit_test(test_jump_pulse_walk),
    cmocka_unit_test(test_damped_sine),
    cmocka_unit_test(test_gen_shared_sines),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
