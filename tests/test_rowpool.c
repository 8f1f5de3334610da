/* test_rowpool — the slot pool of the state-dependent polyset
 * (src/set/rowpool.h) against a linear scan: after a rebuild, each row of a
 * later step gets a free slot of its own pattern, no slot holds two rows,
 * and the rows without one are those whose pattern has no free slot left;
 * when no pattern is in the pool twice, the slot is the only one with the
 * pattern. Rows come in the rebuild's order, shuffled, with some dropped and
 * some new, with and without repeated patterns (which the pool's in-order
 * guess must not take for the hash lookup's answer). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"
#include "set/rowpool.h"

enum { NCOL = 600, NPAT = 300 };

/* Pattern p: two or four increasing columns, distinct for distinct p. */
static int pattern(int p, int *col) {
  if (p % 3 == 0) { col[0] = p; col[1] = p + 1; return 2; }
  col[0] = p % 97; col[1] = 100 + p % 89; col[2] = 200 + p / 7 % 50; col[3] = 260 + p;
  return 4;
}

static void add(cup_rowbuf *rb, int p) {
  int col[4];
  double val[4] = {1, 2, 3, 4};
  assert_int_equal(cup_rowbuf_add(rb, pattern(p, col), col, val, 0), CUP_OK);
}

static int same(const row_pool *P, int s, const cup_rowbuf *rb, int r) {
  int len = rb->ptr[r + 1] - rb->ptr[r];
  return P->ptr[s + 1] - P->ptr[s] == len && !memcmp(P->col + P->ptr[s], rb->col + rb->ptr[r], sizeof(int) * (size_t)len);
}

/* The match of rb against a linear scan of the pool; returns its misses. */
static int check_match(row_pool *P, const cup_rowbuf *rb, long step) {
  int missing = rowpool_match(P, rb, step), expect_missing = 0;
  assert_true(missing >= 0);
  int *taken = calloc((size_t)P->m + 1, sizeof(int));
  for (int r = 0; r < rb->m; r++) {
    int s = P->slot_of[r];
    if (s >= 0) {
      assert_true(same(P, s, rb, r));
      assert_int_equal(taken[s]++, 0);
      assert_int_equal(P->row_of[s], r);
    }
  }
  for (int r = 0; r < rb->m; r++) {           /* unmatched: every slot of its pattern is taken */
    if (P->slot_of[r] >= 0) continue;
    expect_missing++;
    for (int s = 0; s < P->m; s++)
      if (same(P, s, rb, r)) assert_true(taken[s]);
  }
  if (P->unique)                              /* the only slot of the pattern */
    for (int r = 0; r < rb->m; r++) {
      int count = 0, only = -1;
      for (int s = 0; s < P->m; s++)
        if (same(P, s, rb, r)) { count++; only = s; }
      assert_true(count <= 1);
      if (P->slot_of[r] >= 0) assert_int_equal(P->slot_of[r], only);
    }
  free(taken);
  assert_int_equal(missing, expect_missing);
  return missing;
}

static void run(int repeats) {
  cup_rowbuf rb;
  row_pool P;
  assert_int_equal(rowbuf_init(&rb, NCOL, 16, 64), CUP_OK);
  assert_int_equal(rowpool_init(&P, NCOL), CUP_OK);
  rng_t g = {repeats ? 9 : 4};
  for (int p = 0; p < NPAT; p++) {            /* the first step: every pattern, some twice */
    add(&rb, p);
    if (repeats && p % 10 == 0) add(&rb, p);
  }
  assert_int_equal(rowpool_match(&P, &rb, 1), rb.m);
  assert_int_equal(rowpool_rebuild(&P, &rb, 1), CUP_OK);
  assert_int_equal(P.unique, !repeats);
  int order[NPAT];
  for (long step = 2; step < 8; step++) {
    rowbuf_clear(&rb);
    for (int p = 0; p < NPAT; p++) order[p] = p;
    for (int k = 0; step % 2 && k < 40; k++) {   /* odd steps: some neighbours swap */
      int a = (int)(rng_unif(&g) * (NPAT - 1)), t = order[a];
      order[a] = order[a + 1];
      order[a + 1] = t;
    }
    for (int p = 0; p < NPAT; p++) {
      if (rng_unif(&g) < 0.1) continue;        /* a contact that broke */
      add(&rb, order[p]);
      if (repeats && rng_unif(&g) < 0.05) add(&rb, order[p]);
    }
    if (step == 5) add(&rb, NPAT + 3);         /* a new pattern */
    int missing = check_match(&P, &rb, step);
    if (step == 5) assert_true(missing >= 1);
    if (missing) assert_int_equal(rowpool_rebuild(&P, &rb, step), CUP_OK);
  }
  /* a step repeating a row just after the slot before its own: the guess
   * then points at the taken slot */
  rowbuf_clear(&rb);
  int at[3] = {5, 4, 5};
  double val[4] = {1, 2, 3, 4};
  for (int k = 0; k < 3; k++)
    assert_int_equal(cup_rowbuf_add(&rb, P.ptr[at[k] + 1] - P.ptr[at[k]], P.col + P.ptr[at[k]], val, 0), CUP_OK);
  int miss = check_match(&P, &rb, 9);
  if (!repeats) assert_int_equal(miss, 1);     /* the pattern's one slot is taken */
  rowbuf_free(&rb);
  rowpool_free(&P);
}

static void test_match_unique(void **state) { (void)state; run(0); }
static void test_match_repeated(void **state) { (void)state; run(1); }

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_match_unique),
    cmocka_unit_test(test_match_repeated),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
