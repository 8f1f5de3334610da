/* adaptive_series — a step's flow from one vector as Taylor series pieces
 * (ad_series, adaptive_impl.h): built once a step by M's nonzeros, or its
 * dense columns for a converter's few components, and valued at any time of
 * the step by Horner's rule (an event's probes, its root's Newton steps,
 * the error's flows). Allocates nothing. */
#include <float.h>
#include <math.h>
#include "catchup.h"
#include "adaptive_impl.h"

/* c_k = (hs M)^k y / k! into c (dim components: M's first dim columns'
 * nonzeros, rows < dim, the whole product for a y whose rest is 0: the
 * terms it leaves out add +-0) until two terms in a row are below a
 * quarter ulp of each component's largest term (what its sum already rounds
 * at: a component through zero stops too); hs snorm <= 1: the terms
 * decrease (the diagonal blocks' as 1/k!, the input's coupling block's as
 * hs ||Pi Q_w|| / (k - 1)!: a norm of the whole M, which counts that
 * coupling, cut the precision rectifier's pieces 5x too short), and the
 * sum rounds as they do. Their count, or 0. */
static inline __attribute__((always_inline)) int piece_sparse(const ad_mode *md, int dim, double hs,
                                                              const double *restrict y, double *restrict c,
                                                              double *restrict mag) {
  int quiet = 0, nnz = md->mp[dim];
  /* each pass clears the next term's sums (past the last term of the last
   * piece: the buffer's spare dim; of another piece: the next piece's start,
   * written when that piece is made) */
  for (int i = 0; i < dim; i++) {
    c[i] = y[i];
    mag[i] = fabs(c[i]);
    c[dim + i] = 0;
  }
  for (int k = 1; k <= AD_SERIES_MAX; k++) {
    double *ck = c + (size_t)k * dim, f = hs / k;
    const double *cp = ck - dim;
    for (int q = 0; q < nnz; q++) ck[md->mi[q]] += md->mx[q] * cp[md->mj[q]];
    int small = 1;
    for (int i = 0; i < dim; i++) {
      double v = ck[i] *= f, a = fabs(v);
      small &= a <= 0.25 * DBL_EPSILON * mag[i];
      if (a > mag[i]) mag[i] = a;
      ck[dim + i] = 0;
    }
    quiet = small ? quiet + 1 : 0;
    if (quiet == 2) return k;
  }
  return 0;
}

/* The same terms for a small dim (a converter's states, or its states and
 * sources: 1 to 6) by M's dense columns, dim a constant: the loops
 * unrolled, the largest terms in registers (the sparse loop's indices and
 * bookkeeping cost more than the zeros at these sizes: the flyback's
 * pieces took 0.44 M instructions, now 0.30 M). The same sums, bit for
 * bit: row i's products in M's column order from +0, less those of a
 * c_j = 0; a product of a zero entry is +-0, which leaves a sum started
 * at +0 as it was (it is never -0). A non-finite c_j spreads to more rows
 * than the sparse sums', and the piece is not usable either way (0).
 * lo > 0 (a constant): the first lo components are the states and the
 * rest the input's, whose rows of M are 0 in the states' columns (M = [Pi
 * Q; 0 W], mode_flow): those columns' products are the states' rows' alone
 * (the rest are +-0 by the same argument; the six-pulse bridge's 2 + 2). */
static inline __attribute__((always_inline)) int piece_dense(const double *restrict M, int lda, int dim, int lo,
                                                             double hs, const double *restrict y,
                                                             double *restrict c) {
  double mag[6];
  int quiet = 0;
  for (int i = 0; i < dim; i++) {
    c[i] = y[i];
    mag[i] = fabs(c[i]);
  }
  for (int k = 1; k <= AD_SERIES_MAX; k++) {
    double *ck = c + (size_t)k * dim, f = hs / k;
    const double *cp = ck - dim;
    for (int i = 0; i < dim; i++) ck[i] = 0;
    for (int j = 0; j < dim; j++) {
      double cj = cp[j];
      if (cj == 0) continue;
      const double *col = M + (size_t)j * lda;
      int rows = j < lo ? lo : dim;
      for (int i = 0; i < rows; i++) ck[i] += col[i] * cj;
    }
    int small = 1;
    for (int i = 0; i < dim; i++) {
      double v = ck[i] *= f, a = fabs(v);
      small &= a <= 0.25 * DBL_EPSILON * mag[i];
      mag[i] = a > mag[i] ? a : mag[i];
    }
    quiet = small ? quiet + 1 : 0;
    if (quiet == 2) return k;
  }
  return 0;
}

/* ... for 7 or 8 components (a six-pulse bridge's 2 states and 6 input
 * states), dim a constant: the largest terms in registers and the terms'
 * scaling unrolled (270 instructions a term, 200 so); M's nonzeros still
 * (its dense columns cost more: the bridge's M has 22 of 64 entries).
 * Apart from piece_build's body, as horner8 is from piece_at's. */
static __attribute__((noinline)) int piece_sparse8(const ad_mode *md, int dim, double hs, const double *y,
                                                   double *c) {
  double mag[8];
  return dim == 8 ? piece_sparse(md, 8, hs, y, c, mag) : piece_sparse(md, 7, hs, y, c, mag);
}

/* A piece's terms: dim a constant in each small case. */
static int piece_build(const adaptive_ws *A, const ad_mode *md, int dim, double hs, const double *y, double *c,
                       double *mag) {
  switch (dim) {
    case 1: return piece_dense(md->M, A->na, 1, 0, hs, y, c);
    case 2: return piece_dense(md->M, A->na, 2, 0, hs, y, c);
    case 3: return piece_dense(md->M, A->na, 3, 0, hs, y, c);
    case 4:
      if (A->n == 2 && A->na == 4) return piece_dense(md->M, 4, 4, 2, hs, y, c);
      return piece_dense(md->M, A->na, 4, 0, hs, y, c);
    case 5: return piece_dense(md->M, A->na, 5, 0, hs, y, c);
    case 6: return piece_dense(md->M, A->na, 6, 0, hs, y, c);
    case 7: case 8: return piece_sparse8(md, dim, hs, y, c);
    default: return piece_sparse(md, dim, hs, y, c, mag);
  }
}

/* sum_k c_k theta^k (K + 1 terms) into y, by Horner's rule, every
 * component's sum in a register (dim a constant: piece_build's sizes, 7
 * and 8 too). */
static inline __attribute__((always_inline)) void horner(int dim, const double *restrict c, int K, double theta,
                                                         double *restrict y) {
  double a[8];
  const double *ck = c + (size_t)K * dim;
  for (int i = 0; i < dim; i++) a[i] = ck[i];
  for (int k = K - 1; k >= 0; k--) {
    ck -= dim;
    for (int i = 0; i < dim; i++) a[i] = a[i] * theta + ck[i];
  }
  for (int i = 0; i < dim; i++) y[i] = a[i];
}

/* ... for 7 or 8 components (a six-pulse bridge's 2 states and 6 input
 * states: 340 instructions a value two at a time, 230 so), apart from
 * piece_at's body, whose small cases' code its registers would cost. */
static __attribute__((noinline)) void horner8(int dim, const double *restrict c, int K, double theta,
                                              double *restrict y) {
  if (dim == 8) horner(8, c, K, theta, y);
  else horner(7, c, K, theta, y);
}

/* The same, two components at a time for a larger dim. */
static void piece_at(int dim, const double *c, int K, double theta, double *y) {
  switch (dim) {
    case 1: horner(1, c, K, theta, y); return;
    case 2: horner(2, c, K, theta, y); return;
    case 3: horner(3, c, K, theta, y); return;
    case 4: horner(4, c, K, theta, y); return;
    case 5: horner(5, c, K, theta, y); return;
    case 6: horner(6, c, K, theta, y); return;
    case 7: case 8: horner8(dim, c, K, theta, y); return;
  }
  int i = 0;
  for (; i + 1 < dim; i += 2) {
    const double *ck = c + (size_t)K * dim + i;
    double a0 = ck[0], a1 = ck[1];
    for (int k = K - 1; k >= 0; k--) {
      ck -= dim;
      a0 = a0 * theta + ck[0];
      a1 = a1 * theta + ck[1];
    }
    y[i] = a0;
    y[i + 1] = a1;
  }
  if (i < dim) {
    double acc = c[(size_t)K * dim + i];
    for (int k = K - 1; k >= 0; k--) acc = acc * theta + c[(size_t)k * dim + i];
    y[i] = acc;
  }
}

/* Pieces up to j made: 0 if one is not usable (the series is then not). */
static int series_upto(adaptive_ws *A, ad_series *S, int j) {
  int dim = S->dim;
  size_t stride = (size_t)(AD_SERIES_MAX + 1) * dim;
  double hs = S->h / S->nseg;
  for (; S->built <= j; S->built++) {
    int b = S->built;
    double *c = S->c + b * stride;
    if (b > 0) piece_at(dim, c - stride, S->K[b - 1], 1, A->fa);
    if (!(S->K[b] = piece_build(A, S->md, dim, hs, b > 0 ? A->fa : S->y0, c, S->mag))) return S->nseg = 0;
  }
  return 1;
}

void ad_series_at(adaptive_ws *A, ad_series *S, ad_mode *md, double h, const double *y0, double tau,
                  double *y_out) {
  if (S->md != md || S->y0 != y0 || S->h != h) {
    double norm = fabs(h) * md->snorm;
    S->md = md;
    S->y0 = y0;
    S->h = h;
    S->nseg = !(norm <= AD_SERIES_SEGS) ? 0 : norm > 1 ? (int)ceil(norm) : 1;
    S->built = 0;
  }
  int j = 0;
  double hs = h / (S->nseg ? S->nseg : 1);
  if (S->nseg) {
    j = (int)(tau / hs);
    if (j >= S->nseg) j = S->nseg - 1;
  }
  if (!S->nseg || !(tau >= 0 && tau <= h) || !series_upto(A, S, j)) { ad_flow(A, md, tau, y0, y_out); return; }
  piece_at(S->dim, S->c + (size_t)j * (AD_SERIES_MAX + 1) * S->dim, S->K[j], (tau - j * hs) / hs, y_out);
}
