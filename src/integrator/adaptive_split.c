/* adaptive_split — with D != 0, an active set's rows split by the SVD of
 * D_JJ into those that fix zeta_J algebraically (Y) and the manifold of the
 * state (Z), and the inverse of N = [Y^T D_JJ; Z^T C_J B_J] (adaptive_dae.c
 * says why; adaptive_impl.h, ad_dae_factor). Allocates nothing. */
#include <float.h>
#include <math.h>
#include <string.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include "catchup.h"
#include "adaptive_impl.h"

/* Singular values of D_JJ below this share of the largest are zero; N is
 * singular when its condition (rows and columns equilibrated, 1-norm)
 * exceeds the inverse of AD_N_RCOND. */
#define AD_D_RANK_TOL 1e-12
#define AD_N_RCOND 1e-11

/* The SVD of the k x k row-major matrix a (overwritten by U, row-major);
 * V row-major into v, the singular values (decreasing) into s. */
static int svd(double *a, double *v, double *s, double *work, int k) {
  gsl_matrix_view av = gsl_matrix_view_array(a, (size_t)k, (size_t)k);
  gsl_matrix_view vv = gsl_matrix_view_array(v, (size_t)k, (size_t)k);
  gsl_vector_view sv = gsl_vector_view_array(s, (size_t)k), wv = gsl_vector_view_array(work, (size_t)k);
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  int st = gsl_linalg_SV_decomp(&av.matrix, &vv.matrix, &sv.vector, &wv.vector);
  gsl_set_error_handler(old);
  return st;
}

/* svd() of the k x k matrix a as it was for the same values, bit for bit
 * (a row set's D_JJ is often another's: a six-pulse bridge's 14 SVDs are
 * of 6 matrices, ~5 k instructions each): 1 if found (a, v, s its
 * answers), else 0. An entry: k, a's values, then U, V and s. */
static int svd_memo_find(const adaptive_ws *A, double *a, double *v, double *s, int k) {
  size_t kk = (size_t)k * k;
  for (int e = 0; e < A->svd_memo_used;) {
    const double *q = A->svd_memo + e;
    int kq = (int)q[0];
    if (kq == k && !memcmp(q + 1, a, kk * sizeof(double))) {
      memcpy(a, q + 1 + kk, kk * sizeof(double));
      memcpy(v, q + 1 + 2 * kk, kk * sizeof(double));
      memcpy(s, q + 1 + 3 * kk, (size_t)k * sizeof(double));
      return 1;
    }
    e += 3 * kq * kq + kq + 1;
  }
  return 0;
}

/* Keep the SVD of key (k x k) whose answers are a, v and s; a full memo
 * starts again from its beginning. */
static void svd_memo_keep(adaptive_ws *A, const double *key, const double *a, const double *v, const double *s,
                          int k) {
  size_t kk = (size_t)k * k, len = 3 * kk + (size_t)k + 1;
  if (len > AD_SVD_MEMO) return;
  if ((size_t)A->svd_memo_used + len > AD_SVD_MEMO) A->svd_memo_used = 0;
  double *q = A->svd_memo + A->svd_memo_used;
  q[0] = k;
  memcpy(q + 1, key, kk * sizeof(double));
  memcpy(q + 1 + kk, a, kk * sizeof(double));
  memcpy(q + 1 + 2 * kk, v, kk * sizeof(double));
  memcpy(q + 1 + 3 * kk, s, (size_t)k * sizeof(double));
  A->svd_memo_used += (int)len;
}

/* N for the rows J, its inverse into A->Ninv and Z^T into Zt; 1 if N is
 * singular (or the SVD failed). The SVD is D_JJ^T's, U' S V'^T (GSL leaves
 * the columns of U for zero singular values zero; V is complete): D_JJ's
 * left singular vectors are V', kept in A->svd_v (row-major, nj x nj). */
static int factor_rows(adaptive_ws *A, const int *J, int nj, double *Zt, int *nz) {
  int m = A->m;
  *nz = 0;
  if (nj == 0) return 0;
  double *U = A->svd_u, *V = A->svd_v, *s = A->svd_s, *N = A->N;
  for (int a = 0; a < nj; a++)
    for (int c = 0; c < nj; c++) U[(size_t)a * nj + c] = A->Dd[J[c] + (size_t)J[a] * m];
  int r = 0, zero = 1;
  for (size_t q = 0; q < (size_t)nj * nj && zero; q++) zero = U[q] == 0;
  if (zero) {
    /* D_JJ = 0 (rows whose multipliers D couples to none of theirs: 9
     * of a six-pulse bridge's 23 factorings): no rank and Z = I, V as
     * GSL's SVD gives it bit for bit (its Householder steps are the
     * identity on zero columns; one column: V = 1), without its 3 k
     * instructions */
    for (int a = 0; a < nj; a++)
      for (int b = 0; b < nj; b++) V[(size_t)a * nj + b] = a == b;
  } else {
    if (!svd_memo_find(A, U, V, s, nj)) {
      double *key = A->N;                        /* (N is written after: D_JJ's values kept there) */
      memcpy(key, U, sizeof(double) * (size_t)nj * nj);
      if (svd(U, V, s, A->svd_w, nj)) return 1;
      svd_memo_keep(A, key, U, V, s, nj);
    }
    while (r < nj && s[r] > AD_D_RANK_TOL * nj * s[0]) r++;
  }
  *nz = nj - r;
  /* N, column-major: Y^T D_JJ = S_Y U'_Y^T, then Z^T C_J B_J */
  for (int c = 0; c < nj; c++) {
    for (int b = 0; b < r; b++) N[b + (size_t)c * nj] = s[b] * U[(size_t)c * nj + b];
    for (int b = r; b < nj; b++) {
      double acc = 0;
      for (int a = 0; a < nj; a++) acc += V[(size_t)a * nj + b] * A->CB[J[a] + (size_t)J[c] * m];
      N[b + (size_t)c * nj] = acc;
    }
  }
  for (int b = 0; b < *nz; b++)
    for (int a = 0; a < nj; a++) Zt[(size_t)b * nj + a] = V[(size_t)a * nj + r + b];
  /* equilibrate (Y rows are in D's units, Z rows in C B's; zeta's columns
   * are currents or voltages) */
  double *dr = A->eqr, *dc = A->eqc;
  for (int b = 0; b < nj; b++) {
    dr[b] = 0;
    for (int c = 0; c < nj; c++) dr[b] = la_fmax(dr[b], fabs(N[b + (size_t)c * nj]));
    if (!(dr[b] > 0)) return 1;
    dr[b] = 1 / dr[b];
  }
  for (int c = 0; c < nj; c++) {
    dc[c] = 0;
    for (int b = 0; b < nj; b++) dc[c] = la_fmax(dc[c], fabs(dr[b] * N[b + (size_t)c * nj]));
    if (!(dc[c] > 0)) return 1;
    dc[c] = 1 / dc[c];
  }
  /* N^-1 = Dc (Dr N Dc)^-1 Dr by LU of the equilibrated matrix, whose
   * condition in the 1-norm, ||Dr N Dc||_1 ||(Dr N Dc)^-1||_1, from the
   * inverse's columns, says whether N is singular (an SVD of it said so
   * before, at twice the cost of the rows' factoring: within a factor nj
   * of the 2-norm's, and dependent rows are 1e16 off the bound either way) */
  double *lu = A->Sl, *col = A->Sinv, tmp_w[CUP_DENSE_MAX_ROWS], norm = 0, inorm = 0;
  for (int c = 0; c < nj; c++) {
    double sum = 0;
    for (int b = 0; b < nj; b++) {
      lu[b + (size_t)c * nj] = dr[b] * N[b + (size_t)c * nj] * dc[c];
      sum += fabs(lu[b + (size_t)c * nj]);
    }
    norm = la_fmax(norm, sum);
  }
  if (la_dense_lu(lu, nj, A->perm)) return 1;
  for (int k = 0; k < nj; k++) {
    for (int b = 0; b < nj; b++) col[b] = b == k ? dr[k] : 0;
    la_dense_lu_solve(lu, nj, A->perm, col, tmp_w);
    double sum = 0;
    for (int c = 0; c < nj; c++) {
      sum += fabs(col[c]);
      A->Ninv[c + (size_t)k * nj] = dc[c] * col[c];
    }
    inorm = la_fmax(inorm, sum / dr[k]);
  }
  if (!(norm * inorm < 1 / AD_N_RCOND)) return 1;
  return 0;
}

/* Is N of the rows J singular? As factor_rows says, or as it said when
 * these rows were factored before (D and C B are the workspace's own, set
 * once): *fresh says whether the buffers hold J's factors now. */
static int singular(adaptive_ws *A, const int *J, int nj, double *Zt, int *nz, int *fresh) {
  uint64_t mask = 0;
  for (int a = 0; a < nj; a++) mask |= (uint64_t)1 << J[a];
  long have = A->nknown < AD_KNOWN ? A->nknown : AD_KNOWN;
  for (long k = 0; k < have; k++)
    if (A->known[k] == mask) { *fresh = 0; return A->known_singular[k]; }
  int s = factor_rows(A, J, nj, Zt, nz);
  A->known[A->nknown % AD_KNOWN] = mask;
  A->known_singular[A->nknown % AD_KNOWN] = (unsigned char)s;
  A->nknown++;
  *fresh = 1;
  return s;
}

void ad_dae_refactor(adaptive_ws *A, const int *rows, int nj, double *Zt, int *nz) { factor_rows(A, rows, nj, Zt, nz); }

int ad_dae_factor(adaptive_ws *A, int *rows, int nj, double *Zt, int *nz, int *pending) {
  int fresh;
  if (!singular(A, rows, nj, Zt, nz, &fresh)) {
    if (!fresh) factor_rows(A, rows, nj, Zt, nz);
    return nj;
  }
  /* dependent rows: keep, in order, each row that leaves N nonsingular;
   * the buffers for the kept rows, unless the last try made them (a
   * commutation's three rows of a six-pulse bridge hold as the last two;
   * its tries ask for the same first rows at each commutation: 15 of 45
   * factorings in the bridge's first 5 periods were of sets seen before) */
  int keep[CUP_DENSE_MAX_ROWS], nk = 0, held = 0;
  for (int a = 0; a < nj; a++) {
    keep[nk] = rows[a];
    int ok = !singular(A, keep, nk + 1, Zt, nz, &fresh);
    /* a known answer leaves the buffers as they were: the kept rows' still
     * when this row is dropped (a bridge's dependent row, last: the kept
     * rows were factored again) */
    held = fresh ? ok : held && !ok;
    nk += ok;
  }
  if (!held && pending) *pending = 1;
  else if (!held) factor_rows(A, keep, nk, Zt, nz);
  memcpy(rows, keep, sizeof(int) * (size_t)nk);
  return nk;
}
