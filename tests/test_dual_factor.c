/* dual factor (src/projector/dual_factor.c): solves with M~ = M_FF + delta I
 * on the free rows F (identity elsewhere), M = C P^-1 C^T, against a dense
 * Cholesky of the same matrix formed here from C and P (GSL), along
 * sequences of free sets that change by a few rows (row updates) and by many
 * (refactorizations), and with delta changing. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include <gsl/gsl_linalg.h>
#include "testutil.h"
#include "heap.h"
#include "projector/dual_factor.h"

/* M~ v by a dense GSL Cholesky of M~ built from C (dense, row-major) and d. */
static void dense_reference(const double *C, const double *d, int m, int n,
                            const unsigned char *act, double delta, const double *v, double *out) {
  gsl_matrix *A = gsl_matrix_alloc((size_t)m, (size_t)m);
  gsl_vector *b = gsl_vector_alloc((size_t)m), *x = gsl_vector_alloc((size_t)m);
  for (int i = 0; i < m; i++) {
    for (int k = 0; k < m; k++) {
      double s = 0;
      if (act[i] && act[k])
        for (int j = 0; j < n; j++) s += C[i * n + j] * C[k * n + j] / d[j];
      if (i == k) s = act[i] ? s + delta : 1;
      gsl_matrix_set(A, (size_t)i, (size_t)k, s);
    }
    gsl_vector_set(b, (size_t)i, v[i]);
  }
  assert_int_equal(gsl_linalg_cholesky_decomp1(A), 0);
  gsl_linalg_cholesky_solve(A, b, x);
  for (int i = 0; i < m; i++) out[i] = gsl_vector_get(x, (size_t)i);
  gsl_matrix_free(A);
  gsl_vector_free(b);
  gsl_vector_free(x);
}

/* Random sparse C: each row touches 2-4 of a few neighbouring columns, like
 * contacts between nearby bodies; some rows repeat others (a singular M). */
static void random_rows(rng_t *r, double *C, int m, int n) {
  for (int i = 0; i < m; i++) {
    if (i > 4 && rng_unif(r) < 0.05) {          /* a duplicate row */
      int src = rng_int(r, 0, i - 1);
      for (int j = 0; j < n; j++) C[i * n + j] = C[src * n + j];
      continue;
    }
    int c0 = rng_int(r, 0, n - 1), nz = rng_int(r, 2, 4);
    for (int t = 0; t < nz; t++) C[i * n + (c0 + rng_int(r, 0, 6)) % n] = rng_normal(r);
  }
}

/* room: -1 the automatic room (all of M's factor here); large: every
 * factor fits; small: most free sets' factors do not fit and are solved by
 * CG (a larger delta keeps M~ well conditioned enough for CG to reach the
 * dense answer to 1e-8); per_row > 0: room = per_row * m, where layouts for
 * all rows do not fit and those for the free set and the last layout's rows
 * do (rows outside the layout refactor, rows inside are row updates).
 * Returns the row updates made. */
static long solves_against_dense(long room, double per_row) {
  rng_t r = {2026};
  int cg_solves = 0;
  long all_updates = 0;
  for (int trial = 0; trial < 6; trial++) {
    int n = rng_int(&r, 40, 120), m = rng_int(&r, n / 2, 2 * n);
    if (per_row > 0) room = (long)(per_row * m);
    double *C = calloc((size_t)m * n, sizeof(double)), *d = malloc(sizeof(double) * n);
    random_rows(&r, C, m, n);
    for (int j = 0; j < n; j++) d[j] = 0.5 + 4 * rng_unif(&r);
    tcsc Ct;
    cup_polyset *K = tpolyset_dense(&Ct, C, m, n, NULL, d);
    dfact *f = NULL;
    assert_int_equal(dfact_create(&f, K, 1, room, NULL), CUP_OK);
    unsigned char *act = calloc((size_t)m, 1);
    double *v = malloc(sizeof(double) * m), *w = malloc(sizeof(double) * m);
    double *ref = malloc(sizeof(double) * m);
    int facts = 0, updates = 0;
    /* M_FF may be singular: keep M~ well posed */
    double delta = dfact_delta_min(f) * (room >= 0 && room < 1000 ? 1e7 : 1e4);
    for (int step = 0; step < 40; step++) {
      /* mostly a few rows change; every 8th step a new free set; delta changes twice */
      if (step % 8 == 0) for (int i = 0; i < m; i++) act[i] = rng_unif(&r) < 0.4;
      else for (int c = rng_int(&r, 1, 4); c > 0; c--) act[rng_int(&r, 0, m - 1)] ^= 1;
      if (step == 13 || step == 29) delta *= 10;
      for (int i = 0; i < m; i++) v[i] = rng_normal(&r);
      memcpy(w, v, sizeof(double) * m);
#if HEAP_INTERPOSED
      long before = heap_calls;      /* nothing allocated: CHOLMOD's row updates */
      heap_counting = 1;             /* never outgrow the layout's room */
#endif
      assert_int_equal(dfact_factor(f, act, delta, &facts, &updates), CUP_OK);
      dfact_solve(f, w);
#if HEAP_INTERPOSED
      heap_counting = 0;
      assert_int_equal(heap_calls - before, 0);
#endif
      cg_solves += dfact_by_cg(f);
      dense_reference(C, d, m, n, act, delta, v, ref);
      double err = 0, scale = 0;
      for (int i = 0; i < m; i++) {
        err = fmax(err, fabs(w[i] - ref[i]));
        scale = fmax(scale, fabs(ref[i]));
        if (!act[i]) assert_true(w[i] == v[i]);   /* rows outside F come back unchanged */
      }
      if (err > 1e-8 * scale)
        fail_msg("trial %d step %d: |solve - dense| = %.3e (scale %.3e)", trial, step, err, scale);
    }
    assert_true(facts >= 5);       /* both paths ran */
    all_updates += updates;
    dfact_free(&f);
    assert_null(f);
    cup_polyset_free(&K);
    tcsc_free(&Ct);
    free(C); free(d); free(act); free(v); free(w); free(ref);
  }
  if (room < 0 || room >= 1000) assert_int_equal(cg_solves, 0);
  else if (per_row == 0) assert_true(cg_solves > 100);
  return all_updates;
}

static void test_solves_against_dense(void **state) {
  (void)state;
  assert_true(solves_against_dense(-1, 0) > 50);
}

static void test_packed_room(void **state) {
  (void)state;
  assert_true(solves_against_dense(1L << 20, 0) > 50);
}

static void test_packed_room_too_small(void **state) {
  (void)state;
  solves_against_dense(0, 0);    /* at least m: the diagonal alone fits */
}

/* Row updates in layouts that do not hold every row as well: 96 here, 35
 * when only layouts for all rows were updated (those trials where they fit). */
static void test_room_for_some_layouts(void **state) {
  (void)state;
  assert_true(solves_against_dense(0, 4) > 60);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_solves_against_dense),
    cmocka_unit_test(test_packed_room),
    cmocka_unit_test(test_packed_room_too_small),
    cmocka_unit_test(test_room_for_some_layouts),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
