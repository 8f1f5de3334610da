/* The fast paths of the time loop against the general ones they stand in
 * for (src/util/trig.h, the unrolled LCP step of src/lcp/step.h, the fused
 * steps of src/integrator/faststep.c): trig_sin against libm's sin in ulps,
 * its two-lane form, the square wave's lane helpers and its blocks
 * (input_square_block) against the scalar ones bit for bit;
 * the unrolled step against the general pivoting path on random small sets,
 * bit for bit; the warm step with D against the general path with its sums
 * whole, bit for bit; whole runs of the paper's circuits and variants through the
 * fused steps against the same runs through the loop (a step callback turns
 * the fused steps off), bit for bit, states and statistics; la_floor
 * against libm's floor; the adaptive scheme's check of an active set with
 * D (its slopes only where a value is at rounding) against the whole
 * check, and its choice where no row touches against the LCP's. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <float.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"
#include "lcp/step.h"
#include "lcp/lcp.h"
#include "integrator/adaptive.h"
#include "integrator/adaptive_impl.h"
#include "integrator/fixed_impl.h"
#include "integrator/integrator_impl.h"
#include "set/polyset_impl.h"
#include "model/input_impl.h"
#include "util/trig.h"

/* ---- trig_sin ------------------------------------------------------------------- */

static double ulps(double got, double want) {
  double u = nextafter(fabs(want), INFINITY) - fabs(want);
  return fabs(got - want) / fmax(u, DBL_TRUE_MIN);
}

static void test_sin_within_two_ulps(void **state) {
  (void)state;
  rng_t r = {42};
  double worst = 0, at = 0;
  for (int k = 0; k < 2000000; k++) {
    double x;
    switch (k % 4) {
      case 0: x = 200 * rng_unif(&r) - 100; break;                          /* the inputs' range */
      case 1: x = (rng_int(&r, -40000, 40000)) * (M_PI / 2) * (1 + 1e-15 * rng_normal(&r)); break;
      case 2: x = 131072 * rng_unif(&r) - 65536; break;                    /* up to the fallback */
      default: x = 6 * M_PI * (k / 4 + 0.5) * 1e-6 + 0.3; break;          /* case 1's w t_mid + phase */
    }
    double e = ulps(trig_sin(x), sin(x));
    if (e > worst) { worst = e; at = x; }
  }
  if (!(worst <= 2)) fail_msg("trig_sin is %.3g ulp from sin at x = %.17g", worst, at);
  double big[] = {65536, -65536, 1e10, -3e200, INFINITY, -INFINITY};   /* libm's, bit for bit */
  for (size_t k = 0; k < sizeof big / sizeof big[0]; k++) {
    double a = trig_sin(big[k]), b = sin(big[k]);
    assert_true(memcmp(&a, &b, sizeof a) == 0 || (isnan(a) && isnan(b)));
  }
  assert_true(isnan(trig_sin(NAN)));
  assert_true(trig_sin(0.0) == 0 && !signbit(trig_sin(0.0)) && signbit(trig_sin(-0.0)));
}

static int same(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* trig_sin2 is trig_sin in each lane, bit for bit: the inputs' range, near
 * multiples of pi/2, tiny and zero arguments, and pairs where one lane goes
 * to libm (65536 and beyond, Inf, NaN) and the other does not. */
static void test_sin2_is_sin(void **state) {
  (void)state;
  rng_t r = {11};
  double special[] = {0.0, -0.0, 1e-300, -1e-9, 0x1p-26, -0x1p-27, 65535.9, 65536, -1e10, INFINITY, NAN,
                      M_PI / 2, -M_PI, 3 * M_PI / 2};
  int ns = sizeof special / sizeof special[0];
  for (int k = 0; k < 500000; k++) {
    double a[2];
    for (int l = 0; l < 2; l++) {
      int pick = rng_int(&r, 0, 9);
      a[l] = pick == 0 ? special[rng_int(&r, 0, ns - 1)]
           : pick == 1 ? rng_int(&r, -40000, 40000) * (M_PI / 2) * (1 + 1e-15 * rng_normal(&r))
           : 200 * rng_unif(&r) - 100;
    }
    v2d s = trig_sin2((v2d){a[0], a[1]});
    for (int l = 0; l < 2; l++) {
      double want = trig_sin(a[l]);
      if (!same(s[l], want) && !(isnan(s[l]) && isnan(want)))
        fail_msg("trig_sin2 lane %d at %.17g: %.17g, trig_sin %.17g", l, a[l], s[l], want);
    }
  }
}

/* The square wave's lane helpers (model/input_impl.h) against the scalar
 * ones, bit for bit, along increasing positions q as the fused steps meet
 * them (steps across the jumps at integers, exact integers, negative
 * phases, a huge q) with the floor carried from pair to pair, and on
 * unordered pairs and NaN. */
static void test_square_lanes_are_scalar(void **state) {
  (void)state;
  rng_t r = {5};
  double starts[] = {-3.0, -0.25, 0.0, 0.999999999, 1e6 + 0.5, 0x1p52};
  for (size_t c = 0; c < sizeof starts / sizeof starts[0]; c++)
    for (int trial = 0; trial < 200; trial++) {
      double fl = NAN, d = ldexp(rng_unif(&r), -rng_int(&r, 1, 30)), q0 = starts[c];
      for (int k = 0; k < 400; k++) {
        double qa = q0 + (2 * k) * d, qb = q0 + (2 * k + 1) * d;
        if (k % 37 == 5) qa = qb = floor(qa) + 1;                /* on a jump, twice */
        if (trial == 7 && k == 9) { qa = 2.5; qb = 1.5; }       /* not increasing */
        if (trial == 8 && k == 3) qb = NAN;
        v2d q = {qa, qb}, rr = input_mod2_2(q, &fl), tri = input_triangle_r2(rr), sg = input_sign_sin_qr2(q, rr);
        for (int l = 0; l < 2; l++) {
          double want = input_mod2(q[l]);
          assert_true(same(rr[l], want) || (isnan(rr[l]) && isnan(want)));
          assert_true(same(tri[l], input_triangle_r(want)) || (isnan(tri[l]) && isnan(want)));
          assert_true(same(sg[l], input_sign_sin_qr(q[l], want)));
        }
      }
    }
}

enum { BLOCK = 16 };   /* positions in a block, as faststep.c's CUP_FAST_AHEAD */

/* One block of input_square_block against the scalar input_mod2 and
 * input_sign_sin_qr, position by position, bit for bit; a block it calls
 * jump-free must have one sign throughout. Returns what it returned. */
static int check_square_block(const double *q, int np) {
  v2d qv[BLOCK / 2], r[BLOCK / 2], sg[BLOCK / 2];
  for (int p = 0; p < np; p++) qv[p] = (v2d){q[2 * p], q[2 * p + 1]};
  int one_sign = input_square_block(qv, np, r, sg);
  for (int j = 0; j < 2 * np; j++) {
    double want = input_mod2(q[j]), got = r[j >> 1][j & 1], s = sg[j >> 1][j & 1];
    if (!(same(got, want) || (isnan(got) && isnan(want))))
      fail_msg("input_square_block: r = %.17g at q = %.17g, input_mod2 %.17g", got, q[j], want);
    if (!same(s, input_sign_sin_qr(q[j], want)))
      fail_msg("input_square_block: sign %g at q = %.17g (block from %.17g), input_sign_sin_qr %g", s, q[j], q[0],
               input_sign_sin_qr(q[j], want));
    if (one_sign && !same(s, sg[0][0])) fail_msg("input_square_block: one sign claimed, %g and %g", s, sg[0][0]);
  }
  return one_sign;
}

/* The square wave's blocks (input_square_block, model/input_impl.h) against
 * the scalar functions: the positions q = omega t / pi + phase / pi of 16
 * steps t = (k + j) h as the fused steps form them, for frequencies, steps
 * and phases (negative ones too) that put jumps inside blocks, at their ends
 * and on exact integers, from k = 0 to k near 2^50 (where q is huge and the
 * tolerance coarse); then rising sequences with ties, signed zeros, jumps
 * at the first or last position, huge q and Inf. Both ways through it must
 * be taken often. */
static void test_square_block_is_scalar(void **state) {
  (void)state;
  rng_t r = {19};
  long blocks = 0, jump_free = 0;
  double q[BLOCK];
  for (int trial = 0; trial < 20000; trial++) {
    double freq = trial % 3 == 0 ? 2 : ldexp(1 + rng_unif(&r), rng_int(&r, -4, 8));
    double omega = 2 * M_PI * freq, h = 1.0 / (trial % 5 == 0 ? 100 : rng_int(&r, 10, 100000000));
    double phase = trial % 4 == 0 ? 0 : (trial % 4 == 1 ? -M_PI * rng_int(&r, 1, 9) : 20 * rng_unif(&r) - 10);
    long k = trial % 7 == 0 ? (long)ldexp(rng_unif(&r), rng_int(&r, 20, 50)) : rng_int(&r, 0, 200000);
    if (trial % 11 == 0) {                    /* a block starting or ending on a jump: q an integer there */
      double tj = (rng_int(&r, 1, 40) * M_PI - phase) / omega;
      k = (long)fmax(0, floor(tj / h) - (trial % 2 ? 0 : BLOCK - 1));
    }
    for (int j = 0; j < BLOCK; j++) q[j] = omega * ((double)(k + j + 1) * h) / M_PI + phase / M_PI;
    jump_free += check_square_block(q, BLOCK / 2);
    blocks++;
  }
  double special[] = {0.0, -0.0, 1.0, 2.0, 0x1p52, 0x1p53 + 2, INFINITY};
  for (int trial = 0; trial < 20000; trial++) {
    int np = rng_int(&r, 1, BLOCK / 2);
    double v = trial % 3 ? 8 * rng_unif(&r) - 4 : special[rng_int(&r, 0, 6)] - (trial % 2 ? 0 : 1e-300);
    for (int j = 0; j < 2 * np; j++) {
      q[j] = v;
      int pick = rng_int(&r, 0, 5);           /* ties, ulps, small steps, onto the next integer */
      v = pick == 0 ? v : pick == 1 ? nextafter(v, INFINITY) : pick == 2 ? v + 1e-3 * rng_unif(&r)
        : pick == 3 ? floor(v) + 1 : v + rng_unif(&r) * 0.2;
    }
    if (trial % 13 == 0) { q[0] = trial % 2 ? -0.0 : 0.0; q[1] = trial % 2 ? 0.0 : -0.0; }   /* equal zeros */
    if (trial % 17 == 0) q[2 * np - 1] = INFINITY;
    if (trial % 19 == 0)               /* ending within the last position's tolerance of 2, not the first's */
      for (int j = 0; j < 2 * np; j++) q[j] = j == 2 * np - 1 ? 2 - 6 * DBL_EPSILON : 1.1 + 0.05 * j;
    jump_free += check_square_block(q, np);
    blocks++;
  }
  if (!(jump_free > blocks / 4 && jump_free < blocks * 3 / 4))
    fail_msg("%ld of %ld blocks jump-free: one way through is hardly tested", jump_free, blocks);
}

/* la_floor (the square wave's, util/linalg.h) is libm's floor bit for bit. */
static void test_floor_is_libm(void **state) {
  (void)state;
  rng_t r = {3};
  double special[] = {0.0, -0.0, 0.5, -0.5, 1, -1, 0x1p52, -0x1p52, 0x1p52 - 0.5, -0x1p52 + 0.5, 1e300, -1e300,
                      DBL_TRUE_MIN, -DBL_TRUE_MIN, INFINITY, -INFINITY};
  for (size_t k = 0; k < sizeof special / sizeof special[0]; k++)
    assert_true(same(la_floor(special[k]), floor(special[k])));
  assert_true(isnan(la_floor(NAN)));
  for (int k = 0; k < 1000000; k++) {
    double x = ldexp(rng_normal(&r), rng_int(&r, -60, 60));
    if (!same(la_floor(x), floor(x))) fail_msg("la_floor(%.17g) = %.17g, floor %.17g", x, la_floor(x), floor(x));
  }
}

/* ---- the unrolled LCP step against the general path ---------------------------- */

static void assert_same_info(const cup_proj_info *a, const cup_proj_info *b) {
  assert_int_equal(a->status, b->status);
  assert_int_equal(a->iterations, b->iterations);
  assert_int_equal(a->skipped, b->skipped);
  assert_int_equal(a->active, b->active);
  assert_true(same(a->eps_cert, b->eps_cert));
  assert_true(same(a->eta_cert, b->eta_cert));
  assert_true(same(a->violation, b->violation));
  assert_true(same(a->eps_target, b->eps_target));
  assert_true(same(a->scale, b->scale));
}

/* Random sets of 1..4 states and 1..2 rows (zeros in C, a diagonal P, a W
 * near I as the theta scheme's), stepped along a random walk of free points
 * in and out of K, once unrolled and once by the general path: z, lambda,
 * the warm start and every certificate agree bit for bit. */
static void test_unrolled_step_is_the_general_one(void **state) {
  (void)state;
  rng_t r = {7};
  long unrolled = 0, projected = 0;
  for (int trial = 0; trial < 400; trial++) {
    int n = rng_int(&r, 1, 4), m = rng_int(&r, 1, 2);
    double C[8] = {0}, g[2], pd[4], W[16], h = 0.001 * (1 + rng_unif(&r));
    for (int q = 0; q < m * n; q++) C[q] = rng_unif(&r) < 0.3 ? 0 : rng_normal(&r);
    for (int i = 0; i < m; i++) { C[i * n + rng_int(&r, 0, n - 1)] = 1 + rng_unif(&r); g[i] = rng_normal(&r); }
    for (int j = 0; j < n; j++) pd[j] = 0.5 + rng_unif(&r);
    for (int i = 0; i < n; i++)
      for (int j = 0; j < n; j++) W[i + j * n] = (i == j) + 0.01 * rng_normal(&r);
    tcsc Cc;
    cup_polyset *K = tpolyset_dense(&Cc, C, m, n, g, pd);
    lcp_step fast, slow;
    int use_w = trial % 2;
    assert_int_equal(lcp_step_init(&fast, K, use_w ? W : NULL, use_w ? h : 1), CUP_OK);
    assert_int_equal(lcp_step_init(&slow, K, use_w ? W : NULL, use_w ? h : 1), CUP_OK);
    assert_int_equal(fast.small, 1);
    slow.small = 0;
    double x[4], za[4], zb[4];
    for (int j = 0; j < n; j++) x[j] = rng_normal(&r);
    for (int step = 0; step < 50; step++) {
      for (int j = 0; j < n; j++) x[j] += 0.3 * rng_normal(&r);
      double S = cup_polyset_norm(K, x), eps = step % 5 ? 1e-20 : 1e-9, eta = 1e-9;
      cup_proj_info ia, ib;
      int sa = lcp_step_solve(&fast, g, x, za, S, eps, eta, &ia);
      int sb = lcp_step_solve(&slow, g, x, zb, S, eps, eta, &ib);
      assert_int_equal(sa, sb);
      assert_same_info(&ia, &ib);
      for (int j = 0; j < n; j++) assert_true(same(za[j], zb[j]));
      for (int i = 0; i < m; i++) {
        assert_true(same(fast.lcp.lam[i], slow.lcp.lam[i]));
        assert_int_equal(fast.lcp.prev[i], slow.lcp.prev[i]);
      }
      assert_true(same(fast.lq, slow.lq));
      unrolled++;
      projected += !ia.skipped;
      if (step % 3 == 0) for (int j = 0; j < n; j++) x[j] = za[j];   /* walk on from z now and then */
    }
    lcp_step_free(&fast);
    lcp_step_free(&slow);
    cup_polyset_free(&K);
    tcsc_free(&Cc);
  }
  if (!(projected > unrolled / 10 && projected < unrolled * 9 / 10))  /* both branches were exercised */
    fail_msg("%ld of %ld steps projected", projected, unrolled);
}

/* Random LCS steps with D != 0 (1..4 states, 1..6 rows: D a resistive part
 * R R^T, a skew part as a bridge's cutsets give, and zero columns, theta
 * 1/2 or 1), along a random walk of free points, once with the warm step
 * (lcp/step.c's warm_d: the last active set's cached block, the sums over
 * lambda's support; each mode's kernel and matrices cached, lcp/mode.h)
 * and once by the general path with every sum whole, every mode's made anew:
 * z, lambda, the warm start, the trapezoid's carry, the mode and every
 * certificate agree bit for bit. */
static void warm_runs(uint64_t seed, int rank, double walk, long *steps, long *warm, long *returns) {
  rng_t r = {seed};
  for (int trial = 0; trial < 300; trial++) {
    int n = rng_int(&r, 1, 4), m = rng_int(&r, 1, 6);
    double C[24] = {0}, g[6], pd[4], W[16], D[36] = {0}, R[36], h = 0.001 * (1 + rng_unif(&r));
    for (int q = 0; q < m * n; q++) C[q] = rng_unif(&r) < 0.3 ? 0 : rng_normal(&r);
    for (int i = 0; i < m; i++) { C[i * n + rng_int(&r, 0, n - 1)] = 1 + rng_unif(&r); g[i] = rng_normal(&r); }
    for (int j = 0; j < n; j++) pd[j] = 0.5 + rng_unif(&r);
    for (int i = 0; i < n; i++)
      for (int j = 0; j < n; j++) W[i + j * n] = (i == j) + 0.01 * rng_normal(&r);
    for (int q = 0; q < m * m; q++) R[q] = rng_unif(&r) < 0.5 ? 0 : rng_normal(&r);
    for (int i = 0; i < m; i++)                   /* D = R R^T + S, S skew */
      for (int j = 0; j < m; j++) {
        double acc = 0;
        for (int c = 0; c < m && c < rank; c++) acc += R[i + c * m] * R[j + c * m];
        D[i + j * m] = acc;
      }
    for (int i = 0; i < m; i++)
      for (int j = i + 1; j < m; j++)
        if (rng_unif(&r) < 0.3) {
          double s = rng_unif(&r) < 0.5 ? 1 : -1;
          D[i + j * m] += s;
          D[j + i * m] -= s;
        }
    int zc = rng_int(&r, -1, m - 1);              /* a zero column (a diode D does not fix), or none */
    for (int i = 0; zc >= 0 && i < m; i++) D[i + zc * m] = D[zc + i * m] = 0;
    tcsc Cc;
    cup_polyset *K = tpolyset_dense(&Cc, C, m, n, g, pd);
    double theta = trial % 3 ? 0.5 : 1;
    lcp_step fast, slow;
    assert_int_equal(lcp_step_init_bd(&fast, K, W, h, NULL, D, theta), CUP_OK);
    assert_int_equal(lcp_step_init_bd(&slow, K, W, h, NULL, D, theta), CUP_OK);
    assert_int_equal(fast.warm, 1);
    slow.warm = slow.lam_sparse = 0;
    double x[4], za[4], zb[4];
    for (int j = 0; j < n; j++) x[j] = rng_normal(&r);
    assert_int_equal(lcp_step_start(&fast, x, g), lcp_step_start(&slow, x, g));
    unsigned long long seen[64];
    int nseen = 0;
    for (int step = 0; step < 60; step++) {
      for (int j = 0; j < n; j++) x[j] += walk * rng_normal(&r);
      double S = cup_polyset_norm(K, x), eps = step % 7 ? 1e-9 : -1, eta = 1e-9;
      cup_proj_info ia, ib;
      int sa = lcp_step_solve(&fast, g, x, za, S, eps, eta, &ia);
      int sb = lcp_step_solve(&slow, g, x, zb, S, eps, eta, &ib);
      assert_int_equal(sa, sb);
      assert_same_info(&ia, &ib);
      if (sa < 0) break;
      for (int j = 0; j < n; j++) assert_true(same(za[j], zb[j]));
      for (int i = 0; i < m; i++) {
        assert_true(same(fast.lcp.lam[i], slow.lcp.lam[i]));
        assert_int_equal(fast.lcp.prev[i], slow.lcp.prev[i]);
        assert_true(same(fast.carry[i], slow.carry[i]));
        assert_true(same(fast.geff[i], slow.geff[i]));
      }
      assert_true(same(fast.lq, slow.lq));
      assert_true(fast.mode == slow.mode);
      (*steps)++;
      *warm += !ia.skipped && fast.blocks.blk[0].state;
      int old = 0;                                /* back in a mode met before, with weights (theta < 1) */
      for (int e = 0; e < nseen; e++) old |= seen[e] == fast.mode;
      if (!old && nseen < 64) seen[nseen++] = fast.mode;
      *returns += old && theta < 1;
      for (int j = 0; j < n; j++) x[j] = za[j];   /* walk on from z */
    }
    lcp_step_free(&fast);
    lcp_step_free(&slow);
    cup_polyset_free(&K);
    tcsc_free(&Cc);
  }
}

static void test_warm_step_is_the_general_one(void **state) {
  (void)state;
  long steps = 0, warm = 0, returns = 0;
  warm_runs(11, 6, 0.05, &steps, &warm, &returns);
  if (!(warm > steps / 4)) fail_msg("%ld of %ld steps solved an LCP with the warm step's blocks built", warm, steps);
}

/* The same with D_JJ singular on most supports (R of rank 1: kernels) and
 * longer strides, so that the steps move between modes and back: the
 * mode's matrices copied from lcp/mode.h's cache are build_hm's. */
static void test_cached_modes_are_the_general_ones(void **state) {
  (void)state;
  long steps = 0, warm = 0, returns = 0;
  warm_runs(12, 1, 0.5, &steps, &warm, &returns);
  if (!(returns > steps / 10)) fail_msg("%ld of %ld steps back in a mode met before", returns, steps);
}

/* ---- fused steps against the loop ----------------------------------------------- */

typedef struct { double *x; long count, cap; int dim; long stop_at; } keep;

/* Keeps the samples; refuses the stop_at-th (0: none). */
static int keep_sink(long k, double t, const double *x, void *vp) {
  (void)k; (void)t;
  keep *c = vp;
  if (c->count < c->cap) memcpy(c->x + c->count * c->dim, x, sizeof(double) * (size_t)c->dim);
  c->count++;
  return c->count == c->stop_at;
}

static int quiet_step(long k, double t, const cup_proj_info *pi, void *ctx) {
  (void)k; (void)t; (void)pi; (void)ctx;
  return 0;
}

static cup_run_info run(const cup_lcs *L, const cup_input *u, const cup_integrator_options *o, int loop,
                        keep *c) {
  cup_integrator_options oo = *o;
  if (loop) oo.on_step = quiet_step;       /* the fused steps stay off with a step callback */
  cup_integrator *I = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_integrator_create(&I, L, u, &oo, msg)) fail_msg("create: %s", msg);
  double x0[3] = {0, 0, 0};
  cup_run_info info;
  c->count = 0;
  cup_integrator_run(I, x0, c->dim ? keep_sink : NULL, c, &info);
  cup_integrator_free(&I);
  return info;
}

/* Two runs' statistics and samples, bit for bit. */
static void assert_same_runs(const cup_run_info *ia, const cup_run_info *ib, const keep *a, const keep *b) {
  assert_int_equal(ia->status, ib->status);
  assert_int_equal(ia->step, ib->step);
  assert_true(same(ia->t, ib->t));
  assert_int_equal(ia->projected, ib->projected);
  assert_int_equal(ia->skipped, ib->skipped);
  assert_int_equal(ia->not_certified, ib->not_certified);
  assert_true(ia->dual_iterations == ib->dual_iterations);
  assert_true(same(ia->max_eps_cert, ib->max_eps_cert));
  assert_true(same(ia->max_eta_cert, ib->max_eta_cert));
  assert_string_equal(ia->message, ib->message);
  assert_int_equal(ia->samples, ib->samples);
  assert_int_equal(a->count, b->count);
  long kept = a->count < a->cap ? a->count : a->cap;
  assert_true(memcmp(a->x, b->x, sizeof(double) * (size_t)a->dim * (size_t)kept) == 0);
}

static cup_input *input_of(int kind) {
  cup_input *u = NULL;
  assert_int_equal(cup_input_create(&u, 1, NULL), CUP_OK);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 16, .frequency = 3};
  cup_wave c = {.kind = CUP_WAVE_CONSTANT, .value = -0.5};
  cup_wave q = {.kind = CUP_WAVE_SQUARE, .amplitude = 1, .frequency = 2};
  if (kind == 0) { cup_input_add(u, 0, &s, NULL); cup_input_add(u, 0, &c, NULL); }   /* case 1 */
  if (kind == 1) cup_input_add(u, 0, &q, NULL);                                      /* case 2 */
  if (kind == 2) { cup_input_add(u, 0, &q, NULL); cup_input_add(u, 0, &s, NULL); }
  if (kind == 3) cup_input_add(u, 0, &c, NULL);                                      /* constant */
  return u;
}

/* The paper's circuit with each input on a fixed and on a moving set (case
 * 1 and case 2 among them), the explicit step and theta 1/2 and 1, every
 * output mode, n across several 1024-step stretches: the same states at
 * every sample and the same statistics, bit for bit, with the fused steps
 * and without. */
static void test_fused_steps_are_the_loop(void **state) {
  (void)state;
  struct { int kind; double g2; } model[] = {{0, 0}, {1, 1}, {2, 1}, {0, 1}, {3, 1}, {3, 0}};
  struct { cup_output_kind out; long every, samples; } outs[] = {
    {CUP_OUTPUT_EVERY, 1, 0}, {CUP_OUTPUT_EVERY, 7, 0}, {CUP_OUTPUT_SAMPLES, 0, 13}, {CUP_OUTPUT_FINAL, 0, 0},
    {CUP_OUTPUT_NONE, 0, 0}};
  long n = 3000, projected = 0, skipped = 0;
  keep a = {malloc(sizeof(double) * 3 * (n + 1)), 0, n + 1, 3, 0},
       b = {malloc(sizeof(double) * 3 * (n + 1)), 0, n + 1, 3, 0};
  for (size_t q = 0; q < sizeof model / sizeof model[0]; q++) {
    cup_circuit cc = {1, 2, 1, 1, 2, 1, {0, model[q].g2}};
    cup_lcs *L = NULL;
    assert_int_equal(cup_lcs_circuit(&L, &cc, NULL), CUP_OK);
    cup_input *u = input_of(model[q].kind);
    for (int sch = 0; sch < 3; sch++)
      for (size_t oi = 0; oi < sizeof outs / sizeof outs[0]; oi++) {
        cup_integrator_options o;
        cup_integrator_options_default(&o);
        o.n = n;
        o.scheme = sch ? CUP_SCHEME_THETA : CUP_SCHEME_EXPLICIT;
        o.theta = sch == 1 ? 0.5 : 1;
        o.output = outs[oi].out;
        o.output_every = outs[oi].every;
        o.output_samples = outs[oi].samples;
        cup_run_info ia = run(L, u, &o, 0, &a), ib = run(L, u, &o, 1, &b);
        assert_same_runs(&ia, &ib, &a, &b);
        projected += ia.projected;
        skipped += ia.skipped;
      }
    cup_input_free(&u);
    cup_lcs_free(&L);
  }
  free(a.x);
  free(b.x);
  assert_true(projected > 0 && skipped > 0);
}

/* A switched netlist's run with the fused steps (into a) and without (into
 * b: a step callback turns them off in every configuration): the same
 * samples, statistics, and state and zeta at its end, bit for bit. */
static void switched_both(cup_netlist *nl, const cup_integrator_options *o, keep *a, keep *b, cup_run_info *info) {
  char err[CUP_ERRMSG_LEN];
  cup_switching sw;
  assert_int_equal(cup_netlist_switching(nl, &sw), 1);
  int dim = cup_lcs_dim(cup_netlist_lcs(nl)), m = cup_lcs_rows(cup_netlist_lcs(nl));
  double xe[2][8], ze[2][8];
  assert_true(dim <= 8 && m <= 8);
  for (int loop = 0; loop < 2; loop++) {
    cup_integrator_options oo = *o;
    if (loop) oo.on_step = quiet_step;
    cup_integrator *I = NULL;
    if (cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), &oo, err)) fail_msg("%s", err);
    keep *k = loop ? b : a;
    k->count = 0;
    cup_integrator_run(I, cup_netlist_x0(nl), keep_sink, k, &info[loop]);
    memcpy(xe[loop], cup_integrator_state(I), sizeof(double) * (size_t)dim);
    assert_int_equal(cup_integrator_zeta(I, ze[loop]), CUP_OK);
    cup_integrator_free(&I);
  }
  assert_same_runs(&info[0], &info[1], a, b);
  assert_memory_equal(xe[0], xe[1], sizeof(double) * (size_t)dim);
  assert_memory_equal(ze[0], ze[1], sizeof(double) * (size_t)m);
}

/* The switched converters of examples/circuits (a DC supply, a PULSE
 * gate: each configuration's input has two components, the gate's moving
 * neither state nor set) take the fused steps in their configurations'
 * windows: each configuration's integrator has them on (with the input
 * the same at every step), and whole switched runs, theta 1 and 1/2, every
 * output mode, give the same as the loop (switched_both); so do a run
 * whose sink refuses a sample inside a run of recorded steps (every step's
 * sample given by faststep.c) or at its end (t = 440 us, a window's end),
 * and one whose state leaves its range in one (a supply of 1.3e150 V: step
 * 51, the first of a window). */
static void test_fused_switched_steps_are_the_loop(void **state) {
  (void)state;
  const char *names[] = {"buck-dcm", "buckboost", "boost", "buck-ccm", "flyback"};
  struct { cup_output_kind out; long every, samples, stop_at; } outs[] = {
    {CUP_OUTPUT_EVERY, 1, 0, 0}, {CUP_OUTPUT_EVERY, 7, 0, 0}, {CUP_OUTPUT_SAMPLES, 0, 333, 0},
    {CUP_OUTPUT_FINAL, 0, 0, 0}, {CUP_OUTPUT_EVERY, 1, 0, 437}, {CUP_OUTPUT_EVERY, 1, 0, 441}};
  long n = 1000, projected = 0, skipped = 0;
  char err[CUP_ERRMSG_LEN], path[512];
  keep a = {malloc(sizeof(double) * 3 * (size_t)(n + 1)), 0, n + 1, 3, 0}, b = a;
  b.x = malloc(sizeof(double) * 3 * (size_t)(n + 1));
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_THETA;
  o.n = n;
  o.T = 1e-3;                                      /* 100 switching periods */
  cup_run_info info[2];
  for (size_t c = 0; c < sizeof names / sizeof names[0]; c++) {
    cup_netlist *nl = NULL;
    snprintf(path, sizeof path, CUP_SOURCE_DIR "/examples/circuits/%s.cir", names[c]);
    if (cup_netlist_load(&nl, path, NULL, 0, err)) fail_msg("%s", err);
    a.dim = b.dim = cup_lcs_dim(cup_netlist_lcs(nl));
    for (int th = 0; th < 2; th++)
      for (size_t oi = 0; oi < sizeof outs / sizeof outs[0]; oi++) {
        o.theta = th ? 0.5 : 1;
        o.output = outs[oi].out;
        o.output_every = outs[oi].every;
        o.output_samples = outs[oi].samples;
        a.stop_at = b.stop_at = outs[oi].stop_at;
        switched_both(nl, &o, &a, &b, info);
        assert_int_equal(info[0].status, outs[oi].stop_at ? CUP_ERR_INTERRUPTED : CUP_OK);
        assert_int_equal(a.count, outs[oi].stop_at ? outs[oi].stop_at : info[0].samples);
        projected += info[0].projected;
        skipped += info[0].skipped;
      }
    cup_switching sw;
    cup_netlist_switching(nl, &sw);
    for (int topo = 0; topo < 2; topo++) {         /* every converter forms two configurations at least */
      cup_integrator *I = NULL;
      if (cup_integrator_create(&I, sw.lcs(sw.ctx, topo), cup_netlist_input(nl), &o, err)) fail_msg("%s", err);
      const fixed_ws *F = I->ws;
      if (!F->fast.on || !F->fast.konst) fail_msg("%s, configuration %d: fused steps off", names[c], topo);
      cup_integrator_free(&I);
    }
    cup_netlist_free(&nl);
  }
  assert_true(projected > 0 && skipped > 0);
  cup_netlist *nl = NULL;
  if (cup_netlist_load_string(&nl, "buck-boost, its supply huge\nV1 in 0 1.3e150\n"
                              "VG g 0 PULSE(0 1 0 jump jump 5u 10u)\nS1 in sw g 0 SWI\nL1 sw 0 50u\nD1 out sw\n"
                              "C1 out 0 20u\nRL out 0 10\n.model SWI SW(VT=0.5 VH=0)\n.end\n", "huge.cir", NULL, 0,
                              err))
    fail_msg("%s", err);
  a.dim = b.dim = 2;
  a.stop_at = b.stop_at = 0;
  o.theta = 1;
  o.output = CUP_OUTPUT_EVERY;
  o.output_every = 1;
  switched_both(nl, &o, &a, &b, info);
  assert_int_equal(info[0].status, CUP_ERR_DIVERGED);
  assert_int_equal(a.count, 51);                   /* x_0 .. x_50 */
  cup_netlist_free(&nl);
  free(a.x);
  free(b.x);
}

/* ---- the choice of an active set with D ------------------------------------------- */

/* Lm's entry (i, j), dense, from the nonzeros the mode keeps (lmx). */
static double lm_at(const ad_mode *md, int i, int j) {
  for (int q = md->lp[i]; q < md->lp[i + 1]; q++)
    if (md->li[q] == j) return md->lmx[q];
  return 0;
}

/* The check of a mode with D as it was written before its slopes were
 * taken only where a value is at rounding (adaptive_dae.c's mode_fits):
 * every row's value, slopes and thresholds computed, then the rows in
 * order. *edge: a row's value was at rounding (its slopes checked);
 * *slope: a slope failed it. */
static int fits_whole(adaptive_ws *A, ad_mode *md, const double *x, const double *w, int *edge, int *slope) {
  int n = A->n, na = A->na, m = A->m;
  double xn = 0, xm[16], y[16], My[16], g[64], d[64], d2[64], thr[64];
  assert_true(na <= 16 && m <= 64);
  for (int j = 0; j < n; j++) xn = fmax(xn, fabs(x[j]));
  ad_offset(A, w, A->g);
  for (int b = 0; b < md->nz; b++) {
    double res = 0, mag = 0;
    for (int a = 0; a < md->nj; a++) {
      int i = md->rows[a];
      double s = A->g[i], sm = fabs(A->g[i]) + A->c1[i] * xn + A->gscale[i];
      for (int k = A->K->Ct.p[i]; k < A->K->Ct.p[i + 1]; k++) s += A->K->Ct.x[k] * x[A->K->Ct.i[k]];
      res += md->Zt[(size_t)b * md->nj + a] * s;
      mag += fabs(md->Zt[(size_t)b * md->nj + a]) * sm;
    }
    if (fabs(res) > 1024 * DBL_EPSILON * mag) return 0;
  }
  memcpy(xm, x, sizeof(double) * (size_t)n);
  ad_manifold(A, md, A->g, xm);
  ad_lift(A, md, xm, w, y);
  ad_events_eval(A, md, y, g, thr);
  ad_events_deriv(A, md, y, d);
  memcpy(My, A->My, sizeof(double) * (size_t)na);
  ad_events_deriv(A, md, My, d2);
  for (int i = 0; i < m; i++) {
    double tw = 0;
    for (int j = A->n; j < na; j++) tw += lm_at(md, i, j) * fmax(fabs(y[j]), A->wscale[j - A->n]);
    double th = 16 * thr[i] + 64 * DBL_EPSILON * tw;
    if (g[i] < -th) return 0;
    if (g[i] > th) continue;
    *edge = 1;
    double dm = 0, d2m = 0;
    for (int j = 0; j < na; j++) {
      dm += lm_at(md, i, j) * fabs(My[j]);
      d2m += lm_at(md, i, j) * fabs(A->My[j]);
    }
    *slope = 1;
    if (d[i] < -1024 * DBL_EPSILON * dm) return 0;
    if (d[i] <= 1024 * DBL_EPSILON * dm && d2[i] < -1024 * DBL_EPSILON * d2m) return 0;
    *slope = 0;
  }
  return 1;
}

/* A run's states and times (the ends of its steps: at events a row at zero). */
typedef struct { double t[4096], x[4096 * 8]; int n, dim; } trace;

static int trace_sink(long k, double t, const double *x, void *vp) {
  (void)k;
  trace *c = vp;
  if (c->n < 4096) {
    c->t[c->n] = t;
    memcpy(c->x + (size_t)c->n * 8, x, sizeof(double) * (size_t)c->dim);
    c->n++;
  }
  return 0;
}

/* ad_dae_select keeps the current set exactly when it fits (a set that
 * does not fit is never the answer of the LCP's candidates either). On the
 * six-pulse rectifier (D from the sources' star), at the ends of the steps
 * of a run over a period (the diodes commutating: rows at zero, where the
 * slopes decide) and at random states put on the manifold of a set, every
 * set of one or two rows whose mode is its own is kept iff the whole check
 * passes; the whole check fails on a slope many times. */
static void test_mode_fits_is_the_whole_check(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (cup_netlist_load(&nl, CUP_SOURCE_DIR "/examples/circuits/sixpulse.cir", NULL, 0, err)) fail_msg("%s", err);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = 0.02;
  o.tol_abs = o.tol_rel = 1e-6;
  o.output = CUP_OUTPUT_EVERY;
  o.output_every = 1;
  cup_integrator *I = NULL;
  if (cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), &o, err)) fail_msg("%s", err);
  adaptive_ws *A = adaptive_of(I);
  assert_non_null(A);
  assert_true(A->has_D && A->m == 6 && A->n <= 8);
  static trace run;
  run.dim = A->n;
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), trace_sink, &run, &info), CUP_OK);
  assert_true(info.events > 4 && run.n > 20 && run.n < 4096);
  uint64_t sets[32];
  int nsets = 0;
  for (uint64_t J = 0; J < 64; J++) {
    ad_mode *md = __builtin_popcountll(J) <= 2 ? ad_mode_get(A, J) : NULL;
    if (md && md->mask == J) sets[nsets++] = J;
  }
  assert_true(nsets >= 5);
  srand(7);
  double x[8], w[16], err_w[16];
  long kept = 0, dropped = 0, edges = 0, slopes = 0;
  for (int trial = 0; trial < run.n + 200; trial++) {
    double t = trial < run.n ? run.t[trial] : 0.02 * rand() / RAND_MAX;
    assert_int_equal(ad_inputs_on(A, t, t + 1e-6, w, err_w), CUP_OK);
    if (trial < run.n) {
      memcpy(x, run.x + (size_t)trial * 8, sizeof(double) * (size_t)A->n);
    } else {                                       /* onto a set's manifold: its rows at zero */
      for (int j = 0; j < A->n; j++) x[j] = 200.0 * rand() / RAND_MAX - 100;
      ad_mode *on = ad_mode_get(A, sets[rand() % nsets]);
      ad_offset(A, w, A->g);
      ad_manifold(A, on, A->g, x);
    }
    for (int s = 0; s < nsets; s++) {
      int edge = 0, slope = 0, piv = 0;
      int want = fits_whole(A, ad_mode_get(A, sets[s]), x, w, &edge, &slope);
      uint64_t got = 0;
      int st = ad_dae_select(A, x, w, sets[s], -1, 0, 0, 1e-3, 0, &got, &piv);
      if (want != (st == CUP_OK && got == sets[s]))
        fail_msg("state %d, set %#llx: the whole check says %d, the choice %s %#llx", trial,
                 (unsigned long long)sets[s], want, st == CUP_OK ? "keeps" : "fails,", (unsigned long long)got);
      kept += want;
      dropped += !want;
      edges += edge;
      slopes += slope;
    }
  }
  if (!(kept > 50 && dropped > 500 && edges > 100 && slopes > 30))
    fail_msg("kept %ld, dropped %ld, a row at rounding %ld, failed on a slope %ld", kept, dropped, edges, slopes);
  cup_integrator_free(&I);
  cup_netlist_free(&nl);
}

/* ad_select's choice where no row touches, from a cold start: the LCP
 * lambda + q with q > 0, which lcp_solve answers with lambda = 0, w = q
 * and no pivot, leaving the start cold. */
static void test_decoupled_lcp_is_zero(void **state) {
  (void)state;
  srand(11);
  for (int m = 1; m <= 8; m++) {
    lcp_solver s;
    assert_int_equal(lcp_init(&s, m), CUP_OK);
    double M[64] = {0}, q[8];
    for (int i = 0; i < m; i++) M[i + i * m] = 1;
    for (int trial = 0; trial < 20; trial++) {
      for (int i = 0; i < m; i++) q[i] = trial ? 1e-3 + (double)rand() / RAND_MAX : 1;
      int piv = 0;
      assert_true(lcp_cold(&s));
      assert_int_equal(lcp_solve(&s, M, q, &piv), CUP_OK);
      assert_int_equal(piv, 0);
      for (int i = 0; i < m; i++) {
        assert_true(s.lam[i] == 0 && !signbit(s.lam[i]));
        assert_true(s.w[i] == q[i]);
      }
    }
    assert_true(lcp_cold(&s));
    lcp_free(&s);
  }
}

/* lcp_try on a six-pulse bridge's jump LCP (adaptive_dae.c): D skew, two
 * blocks [0 -1 -1; 1 0 0; 1 0 0] (a top and a bottom diode group), q at
 * a commutation. Closed form: rows 2 and 4 negative make zeta_0 = -q_2
 * and zeta_3 = -q_4; then w_0 = q_0 - zeta_2 = 0 and w_3 = q_3 - zeta_4
 * = 0 give zeta_2 = q_0, zeta_4 = q_3, the others 0. Principal pivoting
 * from nothing meets a singular 1 x 1 block (Lemke's method then); the
 * set itself, tried, is that solution at once (its block is a signed
 * permutation: exact), and a wrong or odd set is refused, the warm start
 * left as it was. */
static void test_tried_set_is_the_closed_form(void **state) {
  (void)state;
  enum { m = 6 };
  double D[m * m] = {0}, q[m] = {13.0004, 8.64887e-06, -150, 13.0004, -8.64887e-06, 150};
  for (int b = 0; b < 2; b++) {
    int o = 3 * b;
    D[o + (o + 1) * m] = D[o + (o + 2) * m] = -1;   /* w_o = q_o - zeta_{o+1} - zeta_{o+2} */
    D[(o + 1) + o * m] = D[(o + 2) + o * m] = 1;
  }
  const double want[m] = {150, 0, 13.0004, 8.64887e-06, 13.0004, 0};
  lcp_solver s;
  assert_int_equal(lcp_init(&s, m), CUP_OK);
  assert_int_equal(lcp_monotone(&s), CUP_OK);
  int piv = 0;
  assert_int_equal(lcp_solve(&s, D, q, &piv), CUP_OK);   /* (Lemke's: a few pivots) */
  assert_true(piv > 0);
  for (int i = 0; i < m; i++) assert_true(fabs(s.lam[i] - want[i]) <= 1e-12 * 150);
  const unsigned char right[m] = {1, 0, 1, 1, 1, 0}, wrong[m] = {1, 1, 0, 0, 0, 0}, odd[m] = {1, 0, 0, 0, 0, 0};
  lcp_forget(&s);
  assert_int_equal(lcp_try(&s, D, q, wrong), 1);
  assert_true(lcp_cold(&s));
  assert_int_equal(lcp_try(&s, D, q, odd), 1);     /* singular */
  assert_true(lcp_cold(&s));
  assert_int_equal(lcp_try(&s, D, q, right), CUP_OK);
  for (int i = 0; i < m; i++) {
    assert_true(s.lam[i] == want[i]);
    assert_int_equal(s.prev[i], right[i]);
    double w = q[i];
    for (int j = 0; j < m; j++) w += D[i + j * m] * want[j];
    assert_true(fabs(s.w[i] - w) <= 1e-12 * 150 && s.w[i] >= -1e-12 * 150);
  }
  piv = 0;                                          /* the set is the warm start now */
  assert_int_equal(lcp_solve(&s, D, q, &piv), CUP_OK);
  assert_int_equal(piv, 0);
  lcp_free(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_sin_within_two_ulps),
    cmocka_unit_test(test_sin2_is_sin),
    cmocka_unit_test(test_square_lanes_are_scalar),
    cmocka_unit_test(test_square_block_is_scalar),
    cmocka_unit_test(test_floor_is_libm),
    cmocka_unit_test(test_unrolled_step_is_the_general_one),
    cmocka_unit_test(test_warm_step_is_the_general_one),
    cmocka_unit_test(test_cached_modes_are_the_general_ones),
    cmocka_unit_test(test_fused_steps_are_the_loop),
    cmocka_unit_test(test_fused_switched_steps_are_the_loop),
    cmocka_unit_test(test_mode_fits_is_the_whole_check),
    cmocka_unit_test(test_decoupled_lcp_is_zero),
    cmocka_unit_test(test_tried_set_is_the_closed_form),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
