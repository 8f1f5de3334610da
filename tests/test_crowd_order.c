/* test_crowd_order — the crowd's internal orders (agents binned by cell,
 * src/model/crowd.c; numbered along a Hilbert curve, crowd_order.c) are
 * invisible: a step's rows are those of an O(N^2) enumeration of all pairs
 * and walls, mapped back to the user's numbering, in the order of the
 * internal index; the same agents numbered in another order by the user
 * walk the same trajectories bit for bit (the internal numbering depends on
 * the positions alone) and leave at the same steps (the reference is the
 * run in the other numbering); and a step's callbacks (rows, desired
 * velocity) allocate nothing. The rows callback is read through the set's
 * insides (src/set/set_impl.h). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <cmocka.h>
#include "heap.h"
#include "testutil.h"
#include "set/rowpool.h"
#include "set/set_impl.h"

/* Before the internal numbering, the user's order was the order of the
 * projection's sums and rounding differences grew about tenfold in 8 steps
 * once agents queued at the door (1e-14 m at step 20, 4e-10 at 60, 0.6 m at
 * 300); now the runs are the same bit for bit, compared over 60 steps. */
enum { N = 160, STEPS = 60 };

static const double room[8] = {0, 0, 10, 0, 10, 10, 0, 10}, door[4] = {10, 4, 10, 6};

/* A jittered grid on the right 7 m, up to the door's wall, radii 0.2 ..
 * 0.27; agent k of the run is agent perm[k] of this list. */
static void place(const int *perm, double *q0, double *r) {
  double q[2 * N], rr[N];
  rng_t g = {11};
  for (int i = 0; i < N; i++) {
    rr[i] = 0.2 + 0.07 * rng_unif(&g);
    q[2 * i] = 3.0 + 0.64 * (i % 11) + 0.08 * (rng_unif(&g) - 0.5);
    q[2 * i + 1] = 0.5 + 0.64 * (i / 11);
  }
  for (int k = 0; k < N; k++) {
    q0[2 * k] = q[2 * perm[k]];
    q0[2 * k + 1] = q[2 * perm[k] + 1];
    r[k] = rr[perm[k]];
  }
}

static cup_crowd *make_crowd(const double *q0, const double *r) {
  cup_crowd_desc d = {.agents = N, .q0 = q0, .radius = r, .room_points = 4, .room = room, .doors = 1,
                      .door = door, .speed = 1.2};
  char err[CUP_ERRMSG_LEN];
  cup_crowd *c = NULL;
  if (cup_crowd_create(&c, &d, 0.05, err)) fail_msg("%s", err);
  return c;
}

typedef struct track { double *X; } track;   /* (STEPS + 1) x 2N states */

static int keep(long k, double t, const double *q, void *ctx) {
  (void)t;
  memcpy(((track *)ctx)->X + (size_t)k * 2 * N, q, sizeof(double) * 2 * N);
  return 0;
}

/* The states at every step and the exit times of the crowd numbered perm. */
static void run(const int *perm, double *X, double *exit_time) {
  double q0[2 * N], r[N];
  place(perm, q0, r);
  cup_crowd *c = make_crowd(q0, r);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = STEPS;
  o.T = 0.05 * STEPS;
  cup_integrator *I;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_integrator_create_process(&I, cup_crowd_process(c), &o, err), CUP_OK);
  track tr = {X};
  cup_run_info info;
  int st = cup_integrator_run(I, q0, keep, &tr, &info);
  if (st) fail_msg("%s: %s", cup_status_name(st), info.message);
  memcpy(exit_time, cup_crowd_exit_times(c), sizeof(double) * N);
  cup_integrator_free(&I);
  cup_crowd_free(&c);
}

/* A random numbering of the N agents (Fisher-Yates). */
static void shuffle(int *perm, uint64_t seed) {
  rng_t g = {seed};
  for (int k = 0; k < N; k++) perm[k] = k;
  for (int k = N - 1; k > 0; k--) {
    int j = (int)(rng_unif(&g) * (k + 1)), t = perm[k];
    perm[k] = perm[j];
    perm[j] = t;
  }
}

static void test_order_invisible(void **state) {
  (void)state;
  int id[N], rev[N], shuf[N];
  for (int k = 0; k < N; k++) id[k] = k, rev[k] = N - 1 - k;
  shuffle(shuf, 5);
  const int *perms[2] = {rev, shuf};
  size_t sz = (size_t)(STEPS + 1) * 2 * N;
  double *X0 = malloc(sizeof(double) * sz), *X1 = malloc(sizeof(double) * sz), e0[N], e1[N];
  run(id, X0, e0);
  int left = 0;
  for (int i = 0; i < N; i++) left += !isnan(e0[i]);
  assert_true(left > N / 8);                 /* exit times worth comparing */
  for (int p = 0; p < 2; p++) {
    run(perms[p], X1, e1);
    double worst = 0;
    for (int k = 0; k <= STEPS; k++)
      for (int a = 0; a < N; a++)            /* agent a of this run is agent perm[a] of the first */
        for (int d = 0; d < 2; d++)
          worst = fmax(worst, fabs(X1[(size_t)k * 2 * N + 2 * a + d] - X0[(size_t)k * 2 * N + 2 * perms[p][a] + d]));
    int same = 0;
    for (int a = 0; a < N; a++)
      same += (isnan(e1[a]) && isnan(e0[perms[p][a]])) || e1[a] == e0[perms[p][a]];
    printf("%s order: %d of %d left; largest difference of a position over %d steps %.3g m; "
           "exit times equal for %d of %d agents\n", p ? "shuffled" : "reversed", left, N, STEPS, worst, same, N);
    assert_true(worst == 0);                 /* the same sums in the same order */
    assert_int_equal(same, N);
  }
  free(X0);
  free(X1);
}

/* Exit times and positions come in the user's numbering, whatever the
 * crowd's: with the user's agents shuffled against space, each agent's exit
 * time is the first t_k at which its own reported centre is past the door's
 * wall (x > 10), NaN if none. */
static void test_exits_match_positions(void **state) {
  (void)state;
  int shuf[N];
  shuffle(shuf, 17);
  double *X = malloc(sizeof(double) * (size_t)(STEPS + 1) * 2 * N), e[N];
  run(shuf, X, e);
  int left = 0;
  for (int a = 0; a < N; a++) {
    int first = -1;
    for (int k = 0; k <= STEPS && first < 0; k++)
      if (X[(size_t)k * 2 * N + 2 * a] > 10) first = k;
    if (first < 0) assert_true(isnan(e[a]));
    else { assert_true(fabs(e[a] - 0.05 * first) < 1e-12); left++; }
  }
  assert_true(left > N / 8);
  free(X);
}

/* An input error names the user's agents: two agents overlapping by 0.1 in
 * a shuffled grid are "agents 7 and 31" whichever lies first in space. */
static void test_overlap_names_user_index(void **state) {
  (void)state;
  enum { M = 40 };
  double q0[2 * M], r[M];
  for (int side = 0; side < 2; side++) {
    for (int i = 0; i < M; i++) {
      int cell = (i * 17 + 5) % M;           /* the user's numbering, scattered over the grid */
      q0[2 * i] = 1.5 + (cell % 8);
      q0[2 * i + 1] = 1.5 + (cell / 8);
      r[i] = 0.25;
    }
    q0[2 * 31] = q0[2 * 7] + (side ? 0.4 : -0.4);   /* 0.1 of overlap, on either side of agent 7 */
    q0[2 * 31 + 1] = q0[2 * 7 + 1];
    cup_crowd_desc d = {.agents = M, .q0 = q0, .radius = r, .room_points = 4, .room = room, .doors = 1,
                        .door = door, .speed = 1.2};
    char err[CUP_ERRMSG_LEN] = "";
    cup_crowd *c = NULL;
    assert_int_equal(cup_crowd_create(&c, &d, 0.05, err), CUP_ERR_ARG);
    assert_null(c);
    printf("%s\n", err);
    assert_non_null(strstr(err, "agents 7 and 31 overlap by 0.1"));
  }
}

/* A step's rows and desired velocity allocate nothing once the pool knows
 * the patterns: the rows (cup_setproj_move at the same state) and the walk
 * (the process's f_integral), counted by the interposed allocator. */
static void test_step_allocates_nothing(void **state) {
  (void)state;
  int id[N];
  for (int k = 0; k < N; k++) id[k] = k;
  double q0[2 * N], r[N], F[2 * N];
  place(id, q0, r);
  cup_crowd *c = make_crowd(q0, r);
  const cup_process_desc *pd = cup_crowd_process(c);
  cup_setproj *sp;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_setproj_create(&sp, pd->C, NULL, err), CUP_OK);
  long allocs = 0;
  for (int k = 0; k < 4; k++) {
#if HEAP_INTERPOSED
    if (k >= 2) { heap_calls = 0; heap_counting = 1; }
#endif
    int st = cup_setproj_move(sp, 0.05 * (k + 1), NULL, q0);
    if (!st) st = pd->f_integral(0.05 * k, 0.05 * (k + 1), q0, F, pd->f_integral_ctx);
#if HEAP_INTERPOSED
    heap_counting = 0;
    allocs += heap_calls;
#endif
    assert_int_equal(st, CUP_OK);
  }
  assert_true(cup_crowd_rows(c) > N);        /* a packed crowd: contacts and walls */
  assert_int_equal(allocs, 0);
  cup_setproj_free(&sp);
  cup_crowd_free(&c);
}

/* A row of the reference: its columns, values and offset (expected: no values). */
typedef struct ref_row { int nnz, col[4]; double val[4], off; } ref_row;

static int cmp_pattern(const void *a, const void *b) {
  const ref_row *x = a, *y = b;
  if (x->nnz != y->nnz) return x->nnz - y->nnz;
  for (int k = 0; k < x->nnz; k++)
    if (x->col[k] != y->col[k]) return x->col[k] - y->col[k];
  return 0;
}

/* The distance from (x, y) to segment s and its nearest point. */
static double seg_nearest(const double *s, double x, double y, double *px, double *py) {
  double dx = s[2] - s[0], dy = s[3] - s[1], t = ((x - s[0]) * dx + (y - s[1]) * dy) / (dx * dx + dy * dy);
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  *px = s[0] + t * dx;
  *py = s[1] + t * dy;
  return hypot(x - *px, y - *py);
}

/* Every pair and every wall (crowd.h's rows: a row within the margin, a
 * pattern to come within reach, the default margin max(4 speed h, mean
 * radius) and reach 1.5 margin), into rows and expected, sorted. */
static void reference_rows(const cup_crowd *c, const double *q, const double *r, ref_row *rows, int *m,
                           ref_row *exp, int *me) {
  double rsum = 0;
  for (int i = 0; i < N; i++) rsum += r[i];
  double margin = fmax(4 * 1.2 * 0.05, rsum / N), reach = 1.5 * margin;
  const double *seg;
  int nseg = cup_crowd_walls(c, &seg);
  *m = *me = 0;
  for (int i = 0; i < N; i++) {
    for (int s = 0; s < nseg; s++) {
      double px, py, d = seg_nearest(seg + 4 * s, q[2 * i], q[2 * i + 1], &px, &py), gap = d - r[i];
      if (!(gap < reach)) continue;
      double nx = (q[2 * i] - px) / d, ny = (q[2 * i + 1] - py) / d;
      ref_row w = {2, {2 * i, 2 * i + 1}, {nx, ny}, -(r[i] + nx * px + ny * py)};
      if (gap < margin) rows[(*m)++] = w;
      else exp[(*me)++] = w;
    }
    for (int j = i + 1; j < N; j++) {
      double dx = q[2 * i] - q[2 * j], dy = q[2 * i + 1] - q[2 * j + 1], d = hypot(dx, dy), gap = d - r[i] - r[j];
      if (!(gap < reach)) continue;
      ref_row w = {4, {2 * i, 2 * i + 1, 2 * j, 2 * j + 1}, {dx / d, dy / d, -dx / d, -dy / d}, -(r[i] + r[j])};
      if (gap < margin) rows[(*m)++] = w;
      else exp[(*me)++] = w;
    }
  }
  qsort(rows, (size_t)*m, sizeof *rows, cmp_pattern);
  qsort(exp, (size_t)*me, sizeof *exp, cmp_pattern);
}

/* A row in the crowd's numbering (column k is x[perm[k]]) in the user's:
 * its columns mapped and sorted, the values with them. */
static void user_row(ref_row *w, int nnz, const int *col, const double *val, const int *perm) {
  w->nnz = nnz;
  for (int e = 0; e < nnz; e++) {
    int c = perm[col[e]], q = e;
    double v = val ? val[e] : 0;
    for (; q > 0 && w->col[q - 1] > c; q--) { w->col[q] = w->col[q - 1]; w->val[q] = w->val[q - 1]; }
    w->col[q] = c;
    w->val[q] = v;
  }
}

/* The rows of a step from the cell list against the reference, at the start
 * and at a state shaken by up to 0.15 m (gaps on both sides of the margin
 * and of reach), mapped from the crowd's numbering to the user's; and in
 * the order of the internal index. */
static void test_rows_against_all_pairs(void **state) {
  (void)state;
  int id[N];
  for (int k = 0; k < N; k++) id[k] = k;
  double q0[2 * N], r[N], q[2 * N];
  place(id, q0, r);
  cup_crowd *c = make_crowd(q0, r);
  const cup_set *S = cup_crowd_process(c)->C;
  enum { CAP = 40 * N };
  ref_row *rows = malloc(sizeof(ref_row) * CAP), *exp = malloc(sizeof(ref_row) * CAP);
  ref_row *got = malloc(sizeof(ref_row) * CAP), *gexp = malloc(sizeof(ref_row) * CAP);
  rng_t g = {3};
  for (int trial = 0; trial < 2; trial++) {
    for (int k = 0; k < 2 * N; k++) q[k] = q0[k] + (trial ? 0.15 * (2 * rng_unif(&g) - 1) : 0);
    int m, me;
    reference_rows(c, q, r, rows, &m, exp, &me);
    cup_rowbuf rb;
    assert_int_equal(rowbuf_init(&rb, 2 * N, 16, 64), CUP_OK);
    assert_int_equal(S->rows(0.05, q, &rb, S->rows_ctx), 0);
    assert_int_equal(rb.status, CUP_OK);
    printf("shaken by %.2f m: %d rows, %d patterns to come (reference %d, %d)\n", trial ? 0.15 : 0, rb.m, rb.me, m, me);
    assert_int_equal(rb.m, m);
    assert_int_equal(rb.me, me);
    assert_true(m > N);
    assert_non_null(rb.perm);                /* the crowd's own numbering, a permutation */
    int seen[2 * N] = {0};
    for (int k = 0; k < 2 * N; k++) seen[rb.perm[k]]++;
    for (int k = 0; k < 2 * N; k++) assert_int_equal(seen[k], 1);
    for (int k = 0; k < rb.m; k++) {
      if (k > 0) assert_true(rb.col[rb.ptr[k]] >= rb.col[rb.ptr[k - 1]]);   /* by the internal index */
      user_row(&got[k], rb.ptr[k + 1] - rb.ptr[k], rb.col + rb.ptr[k], rb.val + rb.ptr[k], rb.perm);
      got[k].off = rb.off[k];
    }
    for (int k = 0; k < rb.me; k++) user_row(&gexp[k], rb.eptr[k + 1] - rb.eptr[k], rb.ecol + rb.eptr[k], NULL, rb.perm);
    qsort(got, (size_t)m, sizeof *got, cmp_pattern);
    qsort(gexp, (size_t)me, sizeof *gexp, cmp_pattern);
    for (int k = 0; k < m; k++) {
      assert_int_equal(cmp_pattern(&got[k], &rows[k]), 0);
      for (int e = 0; e < got[k].nnz; e++) assert_close(got[k].val[e], rows[k].val[e], 1e-14);
      assert_close(got[k].off, rows[k].off, 1e-12);
    }
    for (int k = 0; k < me; k++) assert_int_equal(cmp_pattern(&gexp[k], &exp[k]), 0);
    rowbuf_free(&rb);
  }
  free(rows); free(exp); free(got); free(gexp);
  cup_crowd_free(&c);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_rows_against_all_pairs),
    cmocka_unit_test(test_order_invisible),
    cmocka_unit_test(test_exits_match_positions),
    cmocka_unit_test(test_overlap_names_user_index),
    cmocka_unit_test(test_step_allocates_nothing),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
