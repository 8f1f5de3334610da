/* lemke — Lemke's complementary pivoting for a small dense LCP
 *     0 <= z  _|_  w = q + M z >= 0,   M m x m, column-major.
 * It solves every feasible LCP whose M is copositive-plus, positive
 * semidefinite M among them: the monotone LCPs of passive circuits whose
 * M is not a P-matrix (a bridge's diode-only cutset gives a zero diagonal,
 * series diodes a singular block), where principal pivoting (lcp.h) can
 * meet a singular block. Ties in the ratio test are broken
 * lexicographically, so degenerate problems cannot cycle. Dense tableau,
 * m x (2m + 2); allocation-free after lemke_init. */
#ifndef CUP_LCP_LEMKE_H
#define CUP_LCP_LEMKE_H

typedef struct lemke_solver {
  int m;
  double *T;          /* m x (2m + 2) tableau, row-major: w | z | z0 | q */
  int *basis;         /* basic variable of each row: 0..m-1 w, m..2m-1 z, 2m z0 */
} lemke_solver;

/* CUP_OK or CUP_ERR_NOMEM (then lemke_free releases what was taken). */
int lemke_init(lemke_solver *s, int m);
void lemke_free(lemke_solver *s);
/* z (m entries) and w = q + M z recomputed from M and q; adds the pivots to
 * *pivots. Returns CUP_OK, or CUP_ERR_LINALG when the method ends on a
 * secondary ray (no solution for this M and q, or M not copositive-plus)
 * or runs out of pivots. */
int lemke_solve(lemke_solver *s, const double *M, const double *q, double *z, double *w, int *pivots);

#endif
