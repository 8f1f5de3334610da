/* lcp — a small dense linear complementarity problem
 *     0 <= lambda  _|_  w = q + M lambda >= 0,   M m x m, column-major,
 * solved exactly by Murty's least-index principal pivoting (finite for a
 * P-matrix). On the active set A, M_AA lambda_A = -q_A is solved in closed
 * form for one or two rows (Cramer's rule is forward stable for 2 x 2), else
 * by LU with partial pivoting (M need not be symmetric). Each solve starts
 * from the active set of the last solution and is retried cold (not when
 * that set was empty: the cold start it was fails the same way). Dense, for
 * the few rows of circuit models; allocation-free after lcp_init. */
#ifndef CUP_LCP_H
#define CUP_LCP_H

#include <string.h>
#include "lemke.h"

typedef struct lcp_solver {
  int m;
  double *lam, *w;          /* the solution and its slack w = q + M lambda */
  double *rhs, *lu, *work;  /* scratch of the block solves */
  int *piv, *idx;
  unsigned char *act;       /* active set of the current solve */
  unsigned char *prev;      /* active set of the last solution: the warm start */
  int monotone;             /* lcp_monotone: Lemke's method where pivoting fails */
  lemke_solver lemke;
} lcp_solver;

/* CUP_OK or CUP_ERR_NOMEM (then lcp_free releases what was taken). */
int lcp_init(lcp_solver *s, int m);
void lcp_free(lcp_solver *s);
/* For monotone LCPs (M + M^T positive semidefinite, as a passive circuit's
 * with D != 0) whose M need not be a P-matrix: when principal pivoting meets
 * a singular block, Lemke's method (lemke.h) solves the LCP instead.
 * CUP_OK or CUP_ERR_NOMEM. */
int lcp_monotone(lcp_solver *s);
/* lambda and w into s->lam, s->w; adds the pivots to *pivots. Returns CUP_OK,
 * or CUP_ERR_LINALG for a singular principal block or cycling (M is not a
 * P-matrix; after lcp_monotone: Lemke's method found no solution
 * either), leaving the warm start as it was. */
int lcp_solve(lcp_solver *s, const double *M, const double *q, int *pivots);
/* Is the active set act (m flags) the solution, as the first pass of
 * lcp_solve from it would find (the same block solve and tests)? Then its
 * lambda and w are in s->lam, s->w, act becomes the warm start and CUP_OK
 * is returned; else 1, with the warm start as it was (s->lam, s->w
 * overwritten). No pivot is counted: none is made. act may be s->prev. */
int lcp_try(lcp_solver *s, const double *M, const double *q, const unsigned char *act);
/* The next solve starts cold. */
static inline void lcp_forget(lcp_solver *s) { memset(s->prev, 0, (size_t)s->m); }
/* Does the next solve start cold (no row in the warm start)? */
static inline int lcp_cold(const lcp_solver *s) {
  for (int i = 0; i < s->m; i++)
    if (s->prev[i]) return 0;
  return 1;
}

#endif
