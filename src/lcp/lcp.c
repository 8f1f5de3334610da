/* lcp — see lcp.h. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "util/block.h"
#include "util/linalg.h"
#include "lcp.h"

static void layout(lcp_solver *s, block_arena *b) {
  size_t M = (size_t)s->m + 1;
  s->lam = block_take(b, M, sizeof(double)); s->w = block_take(b, M, sizeof(double));
  s->rhs = block_take(b, M, sizeof(double)); s->lu = block_take(b, M * M, sizeof(double));
  s->work = block_take(b, M, sizeof(double));
  s->piv = block_take(b, M, sizeof(int)); s->idx = block_take(b, M, sizeof(int));
  s->act = block_take(b, M, 1); s->prev = block_take(b, M, 1);
}

/* One zeroed block (lam is its start): an integrator has several solvers,
 * and a switched run makes them per configuration inside its run. */
int lcp_init(lcp_solver *s, int m) {
  memset(s, 0, sizeof *s);
  s->m = m;
  block_arena b = {0};
  layout(s, &b);
  if (!(b.base = calloc(1, b.used))) return CUP_ERR_NOMEM;
  b.used = 0;
  layout(s, &b);
  return CUP_OK;
}

void lcp_free(lcp_solver *s) {
  free(s->lam);
  lemke_free(&s->lemke);
  memset(s, 0, sizeof *s);
}

int lcp_monotone(lcp_solver *s) {
  if (!s->monotone && lemke_init(&s->lemke, s->m)) return CUP_ERR_NOMEM;
  s->monotone = 1;
  return CUP_OK;
}

/* lambda on A from M_AA lambda_A = -q_A, 0 elsewhere, and w = q + M lambda
 * (inlined in murty and lcp_try: a call each cost the full bridge's run
 * 5 k instructions).
 * Returns nonzero for a singular block. */
static inline __attribute__((always_inline)) int solve_on(lcp_solver *s, const double *M, const double *q) {
  int m = s->m, k = 0;
  for (int i = 0; i < m; i++) if (s->act[i]) s->idx[k++] = i;
  for (int i = 0; i < m; i++) s->lam[i] = 0;
  if (k == 1) {
    int a = s->idx[0];
    double d = M[a + (size_t)a * m];
    if (!(d != 0)) return 1;
    s->lam[a] = -q[a] / d;
  } else if (k == 2) {
    int a = s->idx[0], b = s->idx[1];
    double maa = M[a + (size_t)a * m], mab = M[a + (size_t)b * m];
    double mba = M[b + (size_t)a * m], mbb = M[b + (size_t)b * m];
    double det = maa * mbb - mab * mba;
    if (!(det != 0)) return 1;
    s->lam[a] = (-q[a] * mbb + q[b] * mab) / det;
    s->lam[b] = (-q[b] * maa + q[a] * mba) / det;
  } else if (k) {
    for (int b = 0; b < k; b++) {
      s->rhs[b] = -q[s->idx[b]];
      for (int a = 0; a < k; a++) s->lu[a + (size_t)b * k] = M[s->idx[a] + (size_t)s->idx[b] * m];
    }
    if (la_dense_lu(s->lu, k, s->piv)) return 1;
    la_dense_lu_solve(s->lu, k, s->piv, s->rhs, s->work);
    for (int b = 0; b < k; b++) s->lam[s->idx[b]] = s->rhs[b];
  }
  /* one or two columns (a circuit's event LCPs): the same sums, in the
   * same order, with the columns found once */
  if (k == 1 || k == 2) {
    const double *ca = M + (size_t)s->idx[0] * m, *cb = M + (size_t)s->idx[k - 1] * m;
    double la = s->lam[s->idx[0]], lb = s->lam[s->idx[k - 1]];
    for (int i = 0; i < m; i++) s->w[i] = k == 1 ? q[i] + ca[i] * la : q[i] + ca[i] * la + cb[i] * lb;
    return 0;
  }
  if (k == 3 || k == 4) {                       /* (a six-pulse bridge's: the same sums) */
    const double *c0 = M + (size_t)s->idx[0] * m, *c1 = M + (size_t)s->idx[1] * m, *c2 = M + (size_t)s->idx[2] * m;
    const double *c3 = M + (size_t)s->idx[k - 1] * m;
    double l0 = s->lam[s->idx[0]], l1 = s->lam[s->idx[1]], l2 = s->lam[s->idx[2]], l3 = s->lam[s->idx[k - 1]];
    for (int i = 0; i < m; i++) {
      double acc = q[i] + c0[i] * l0 + c1[i] * l1 + c2[i] * l2;
      s->w[i] = k == 3 ? acc : acc + c3[i] * l3;
    }
    return 0;
  }
  for (int i = 0; i < m; i++) {
    double acc = q[i];
    for (int b = 0; b < k; b++) acc += M[i + (size_t)s->idx[b] * m] * s->lam[s->idx[b]];
    s->w[i] = acc;
  }
  return 0;
}

/* The first row (least index) whose sign is wrong on s->act's solution,
 * or -1: it solves the LCP. */
static inline __attribute__((always_inline)) int wrong_sign(const lcp_solver *s, double scale) {
  int m = s->m;
  double lmax = 0;
  for (int i = 0; i < m; i++) lmax = la_max(lmax, fabs(s->lam[i]));
  double tol_l = 64 * DBL_EPSILON * lmax, tol_w = 64 * DBL_EPSILON * scale;
  for (int i = 0; i < m; i++)
    if ((s->act[i] && s->lam[i] < -tol_l) || (!s->act[i] && s->w[i] < -tol_w)) return i;
  return -1;
}

static double q_scale(const double *q, int m) {
  double scale = 0;
  for (int i = 0; i < m; i++) scale = la_max(scale, fabs(q[i]));
  return scale;
}

/* Murty's least-index principal pivoting from the active set in s->act. */
static int murty(lcp_solver *s, const double *M, const double *q, int *pivots) {
  double scale = q_scale(q, s->m);
  for (int it = 0; it < 16 * s->m + 64; it++) {
    if (solve_on(s, M, q)) return CUP_ERR_LINALG;
    int flip = wrong_sign(s, scale);
    if (flip < 0) return CUP_OK;
    s->act[flip] = !s->act[flip];
    (*pivots)++;
  }
  return CUP_ERR_LINALG;                          /* cycling: not a P-matrix */
}

int lcp_try(lcp_solver *s, const double *M, const double *q, const unsigned char *act) {
  memcpy(s->act, act, (size_t)s->m);
  if (solve_on(s, M, q) || wrong_sign(s, q_scale(q, s->m)) >= 0) return 1;
  memcpy(s->prev, s->act, (size_t)s->m);
  return CUP_OK;
}

static int lemke(lcp_solver *s, const double *M, const double *q, int *pivots) {
  int st = lemke_solve(&s->lemke, M, q, s->lam, s->w, pivots);
  if (st) return st;
  for (int i = 0; i < s->m; i++) s->act[i] = s->lam[i] > 0;
  memcpy(s->prev, s->act, (size_t)s->m);
  return CUP_OK;
}

int lcp_solve(lcp_solver *s, const double *M, const double *q, int *pivots) {
  memcpy(s->act, s->prev, (size_t)s->m);
  for (int cold = 0;; cold++) {                   /* one call site: murty is inlined */
    int st = murty(s, M, q, pivots);
    if (st == CUP_OK) memcpy(s->prev, s->act, (size_t)s->m);
    if (st != CUP_ERR_LINALG) return st;
    /* (from an empty warm start, the cold one would fail the same way) */
    if (cold || lcp_cold(s)) return s->monotone ? lemke(s, M, q, pivots) : st;
    memset(s->act, 0, (size_t)s->m);
  }
}
