/* block — what a small dense LCP with a fixed M needs of one active set,
 * cached by active set: its rows, the closed form's entries or the LU
 * factors of its principal block (as lcp.c's pivoting forms them, so that
 * a pass here is bit for bit one of lcp.c's), and the matrices' columns on
 * it, gathered. The theta step with D (step.c's warm step) keeps the few
 * active sets a circuit moves between (a bridge's commutations) and solves
 * a step from the last one in a pass. Allocation-free after
 * lcp_blocks_init. */
#ifndef CUP_LCP_BLOCK_H
#define CUP_LCP_BLOCK_H

#include <float.h>
#include <math.h>
#include "util/linalg.h"

/* Active sets kept, and the most rows a cache is made for (larger LCPs
 * take the general path). */
#define LCP_BLOCKS 4
#define LCP_BLOCKS_MAX_M 16

typedef struct lcp_block {
  unsigned long long act;   /* the active set, a bit per row */
  int state;                /* 0 empty, 1 ready, 2 singular block */
  int k;                    /* active rows */
  double d[5];              /* k = 1: Ms_aa; k = 2: Ms_aa, Ms_ab, Ms_ba, Ms_bb and the determinant */
  int *idx;                 /* m: the k active rows ascending, then the others */
  int *piv;                 /* k >= 3: la_dense_lu's pivots */
  double *lu;               /* k >= 3: its factors, k x k */
  double *Ws, *Ma, *Dg, *Da;   /* m x k each: Ms, |M|, D and |D| on the active columns */
} lcp_block;

typedef struct lcp_blocks {
  int m, next;              /* rows; the entry to replace next */
  lcp_block blk[LCP_BLOCKS];
  double *mem;
  int *imem;
} lcp_blocks;

/* 0, or 1 when out of memory (lcp_blocks_free releases what was taken). */
int lcp_blocks_init(lcp_blocks *c, int m);
void lcp_blocks_free(lcp_blocks *c);
/* After M, Ms or D changed. */
static inline void lcp_blocks_clear(lcp_blocks *c) {
  for (int b = 0; b < LCP_BLOCKS; b++) c->blk[b].state = 0;
}
/* The block of the active set act of the LCP whose pivoting solves Ms
 * (M with rows scaled), its rounding bounds reading |M| and its offset D:
 * m x m, column-major. From the cache, or built into it. */
const lcp_block *lcp_blocks_get(lcp_blocks *c, unsigned long long act, const double *Ms, const double *M,
                                const double *D);

/* The first pass of lcp.c's Murty pivoting on the scaled LCP (Ms, qv) at
 * the block's active set, its arithmetic in its order: 0 with lambda in
 * lam when no index flips (the pass that lcp_solve ends with, its warm
 * start kept), 1 when one does or the block is singular. y: k scratch. */
static inline __attribute__((always_inline)) int lcp_block_pass(const lcp_block *B, const double *restrict qv,
                                                                double *restrict lam, double *restrict y,
                                                                const int m) {
  if (B->state != 1) return 1;
  const int k = B->k, *restrict idx = B->idx;
  const double *restrict d = B->d;
  double scale = 0;
  for (int i = 0; i < m; i++) {
    scale = la_max(scale, fabs(qv[i]));
    lam[i] = 0;
  }
  if (k == 1) {
    lam[idx[0]] = -qv[idx[0]] / d[0];
  } else if (k == 2) {
    int a = idx[0], b = idx[1];
    lam[a] = (-qv[a] * d[3] + qv[b] * d[1]) / d[4];
    lam[b] = (-qv[b] * d[0] + qv[a] * d[2]) / d[4];
  } else if (k) {                                 /* la_dense_lu_solve's arithmetic, on -q permuted */
    const double *restrict lu = B->lu;
    for (int b = 0; b < k; b++) y[b] = -qv[idx[B->piv[b]]];
    for (int j = 0; j < k; j++)
      for (int i = j + 1; i < k; i++) y[i] -= lu[i + j * k] * y[j];
    for (int j = k - 1; j >= 0; j--) {
      y[j] /= lu[j + j * k];
      for (int i = 0; i < j; i++) y[i] -= lu[i + j * k] * y[j];
    }
    for (int b = 0; b < k; b++) lam[idx[b]] = y[b];
  }
  double lmax = 0;
  for (int i = 0; i < m; i++) lmax = la_max(lmax, fabs(lam[i]));
  double tol_l = 64 * DBL_EPSILON * lmax, tol_w = 64 * DBL_EPSILON * scale;
  for (int b = 0; b < k; b++)
    if (lam[idx[b]] < -tol_l) return 1;
  double w[LCP_BLOCKS_MAX_M];                     /* w = q + M lambda on the active columns, row by row */
  for (int i = 0; i < m; i++) w[i] = qv[i];
  for (int b = 0; b < k; b++) {
    const double *restrict col = B->Ws + (size_t)b * m, l = lam[idx[b]];
    for (int i = 0; i < m; i++) w[i] += col[i] * l;
  }
  for (int r = k; r < m; r++)
    if (w[idx[r]] < -tol_w) return 1;
  return 0;
}

#endif
