/* lemke — see lemke.h. The scheme of Cottle, Pang and Stone (The Linear
 * Complementarity Problem, Sec. 4.4): the tableau w - M z - e z0 = q starts
 * from the basis w; z0 enters at the row of the most negative q, and then
 * the complement of each leaving variable enters, until z0 leaves. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "lemke.h"

int lemke_init(lemke_solver *s, int m) {
  memset(s, 0, sizeof *s);
  s->m = m;
  size_t M = (size_t)m + 1;
  s->T = calloc(M * (2 * M + 2), sizeof(double));
  s->basis = calloc(M, sizeof(int));
  if (!s->T || !s->basis) { lemke_free(s); return CUP_ERR_NOMEM; }
  return CUP_OK;
}

void lemke_free(lemke_solver *s) {
  free(s->T);
  free(s->basis);
  memset(s, 0, sizeof *s);
}

#define TAB(s, i, j) ((s)->T[(size_t)(i) * (2 * (size_t)(s)->m + 2) + (j)])   /* row-major: a pivot runs along rows */

/* fmax(s, |v|) for an s that is not NaN (a NaN v leaves s), without the
 * call */
static inline double max_abs(double s, double v) {
  double a = fabs(v);
  return a > s ? a : s;
}

/* The leaving row for entering column e: the least ratio q_i / a_ie over
 * a_ie > tol, ties broken lexicographically by the rows of B^-1 (the w
 * columns) over a_ie: a strict order, so no basis repeats. When z0's row
 * ties with that row to rounding, z0 leaves (the method ends there):
 * ratios that are equal in exact arithmetic differ by rounding after some
 * pivots, and the lexicographic order then follows the rounding, which can
 * end on a ray although the LCP is feasible. -1: a ray. */
static int ratio_test(const lemke_solver *s, int e, double tol) {
  int m = s->m, qc = 2 * m + 1, best = -1, zrow = -1;
  for (int i = 0; i < m; i++) {
    if (s->basis[i] == 2 * m) zrow = i;
    double a = TAB(s, i, e);
    if (!(a > tol)) continue;
    if (best < 0) { best = i; continue; }
    double ab = TAB(s, best, e);
    double d = TAB(s, i, qc) / a - TAB(s, best, qc) / ab;
    for (int j = 0; d == 0 && j < m; j++) d = TAB(s, i, j) / a - TAB(s, best, j) / ab;
    if (d < 0) best = i;
  }
  if (best >= 0 && zrow >= 0 && zrow != best && TAB(s, zrow, e) > tol) {
    double qscale = 0;                             /* (here alone: most tests end before) */
    for (int i = 0; i < m; i++) qscale = max_abs(qscale, TAB(s, i, qc));
    double az = TAB(s, zrow, e), rz = TAB(s, zrow, qc) / az, rb = TAB(s, best, qc) / TAB(s, best, e);
    if (rz - rb <= 64 * DBL_EPSILON * (fabs(rb) + qscale / az)) return zrow;
  }
  return best;
}

static void pivot(lemke_solver *s, int r, int e) {
  int m = s->m, nc = 2 * m + 2;
  double p = TAB(s, r, e);
  for (int j = 0; j < nc; j++) TAB(s, r, j) /= p;
  for (int i = 0; i < m; i++) {
    if (i == r) continue;
    double f = TAB(s, i, e);
    if (f == 0) continue;
    for (int j = 0; j < nc; j++) TAB(s, i, j) -= f * TAB(s, r, j);
    TAB(s, i, e) = 0;
  }
  TAB(s, r, e) = 1;
  s->basis[r] = e;
}

int lemke_solve(lemke_solver *s, const double *M, const double *q, double *z, double *w, int *pivots) {
  int m = s->m, z0 = 2 * m, qc = 2 * m + 1;
  double scale = 0, qmin = 0;
  int r = -1;
  for (int i = 0; i < m; i++)
    if (q[i] < 0 && q[i] <= qmin) { qmin = q[i]; r = i; }   /* ties: the last row, lexicographically least */
  for (int i = 0; i < m; i++) z[i] = 0;
  if (r < 0) {                                     /* q >= 0: z = 0 */
    for (int i = 0; i < m; i++) w[i] = q[i];
    return CUP_OK;
  }
  /* every entry of the tableau's m rows written (no memset first); M's
   * largest entry on the way (a max, in any order the same; a NaN passed
   * over as before) */
  for (int i = 0; i < m; i++) {
    for (int j = 0; j < m; j++) {
      double v = M[i + (size_t)j * m];
      scale = max_abs(scale, v);
      TAB(s, i, j) = 0;
      TAB(s, i, m + j) = -v;
    }
    TAB(s, i, i) = 1;
    TAB(s, i, z0) = -1;
    TAB(s, i, qc) = q[i];
    s->basis[i] = i;
  }
  double tol = 64 * DBL_EPSILON * fmax(scale, 1);
  int e = z0;
  for (int it = 0; it < 50 * m + 100; it++) {
    int leaving = it == 0 ? r : ratio_test(s, e, tol);
    if (leaving < 0) return CUP_ERR_LINALG;        /* a secondary ray */
    int out = s->basis[leaving];
    pivot(s, leaving, e);
    (*pivots)++;
    if (out == z0) {
      for (int i = 0; i < m; i++)
        if (s->basis[i] >= m && s->basis[i] < z0) z[s->basis[i] - m] = fmax(TAB(s, i, qc), 0);
      for (int i = 0; i < m; i++) {
        double acc = q[i];
        for (int j = 0; j < m; j++) acc += M[i + (size_t)j * m] * z[j];
        w[i] = acc;
      }
      return CUP_OK;
    }
    e = out < m ? out + m : out - m;               /* the complement enters */
  }
  return CUP_ERR_LINALG;
}
