/* linalg — owned sparse matrices, small dense Cholesky, CHOLMOD set-up; growing arrays. */
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include "catchup.h"
#include "linalg.h"

int la_grow(void *arr, int *cap, int n, size_t size, int first) {
  if (n < *cap) return CUP_OK;
  if (*cap > INT_MAX / 2) return CUP_ERR_NOMEM;
  int nc = *cap ? 2 * *cap : first;
  void *p;
  memcpy(&p, arr, sizeof p);
  void *q = realloc(p, size * (size_t)nc);
  if (!q) return CUP_ERR_NOMEM;
  memcpy(arr, &q, sizeof q);
  *cap = nc;
  return CUP_OK;
}

/* x, then p and i, in one allocation that x owns (a switched run forms its
 * configurations inside the run: some 40 of these each, three mallocs and
 * three frees apiece). */
int la_sparse_alloc(la_sparse *A, int nrow, int ncol, int nnz) {
  A->nrow = nrow; A->ncol = ncol; A->nnz = nnz;
  size_t nx = (size_t)nnz + 1;
  A->x = malloc(sizeof(double) * nx + sizeof(int) * ((size_t)ncol + 1 + nx));
  A->p = A->x ? (int *)(A->x + nx) : NULL;
  A->i = A->p ? A->p + (size_t)ncol + 1 : NULL;
  if (!A->x) { la_sparse_free(A); return CUP_ERR_NOMEM; }
  A->p[0] = 0;
  return CUP_OK;
}

void la_sparse_free(la_sparse *A) {
  free(A->x);                                      /* (p and i in its block) */
  A->p = NULL; A->i = NULL; A->x = NULL;
  A->nnz = 0;
}

int la_sparse_copy(la_sparse *A, const cup_csc *v, const char *name,
                   int nrow, int ncol, char *errmsg) {
  memset(A, 0, sizeof *A);
  if (!v || !v->colptr || (v->colptr[v->ncol] > 0 && (!v->rowind || !v->values)))
    return fail_fmt(errmsg, CUP_ERR_ARG, "%s: missing colptr, rowind or values", name);
  if (v->nrow != nrow || v->ncol != ncol)
    return fail_fmt(errmsg, CUP_ERR_DIM, "%s is %d x %d, expected %d x %d",
                    name, v->nrow, v->ncol, nrow, ncol);
  if (v->colptr[0] != 0)
    return fail_fmt(errmsg, CUP_ERR_ARG, "%s: colptr[0] = %d, must be 0", name, v->colptr[0]);
  for (int j = 0; j < ncol; j++) {
    if (v->colptr[j + 1] < v->colptr[j])
      return fail_fmt(errmsg, CUP_ERR_ARG, "%s: colptr decreases at column %d", name, j);
    for (int k = v->colptr[j]; k < v->colptr[j + 1]; k++) {
      int r = v->rowind[k];
      if (r < 0 || r >= nrow)
        return fail_fmt(errmsg, CUP_ERR_ARG, "%s: column %d has row index %d outside [0, %d)",
                        name, j, r, nrow);
      if (k > v->colptr[j] && r <= v->rowind[k - 1])
        return fail_fmt(errmsg, CUP_ERR_ARG,
                        "%s: column %d row indices not strictly increasing (%d after %d)",
                        name, j, r, v->rowind[k - 1]);
      if (!isfinite(v->values[k]))
        return fail_fmt(errmsg, CUP_ERR_NONFINITE, "%s(%d,%d) is %g", name, r, j, v->values[k]);
    }
  }
  int nnz = v->colptr[ncol];
  if (la_sparse_alloc(A, nrow, ncol, nnz) != CUP_OK)
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "%s: out of memory copying %d entries", name, nnz);
  memcpy(A->p, v->colptr, sizeof(int) * ((size_t)ncol + 1));
  if (nnz) {
    memcpy(A->i, v->rowind, sizeof(int) * (size_t)nnz);
    memcpy(A->x, v->values, sizeof(double) * (size_t)nnz);
  }
  return CUP_OK;
}

int la_sparse_transpose(la_sparse *At, const la_sparse *A) {
  int st = la_sparse_alloc(At, A->ncol, A->nrow, A->nnz);
  if (st) return st;
  int *cnt = calloc((size_t)A->nrow + 1, sizeof(int));
  if (!cnt) { la_sparse_free(At); return CUP_ERR_NOMEM; }
  for (int k = 0; k < A->nnz; k++) cnt[A->i[k] + 1]++;
  for (int r = 0; r < A->nrow; r++) cnt[r + 1] += cnt[r];
  memcpy(At->p, cnt, sizeof(int) * ((size_t)A->nrow + 1));
  for (int j = 0; j < A->ncol; j++)       /* columns in order: rows of At sorted */
    for (int k = A->p[j]; k < A->p[j + 1]; k++) {
      int dst = cnt[A->i[k]]++;
      At->i[dst] = j;
      At->x[dst] = A->x[k];
    }
  free(cnt);
  return CUP_OK;
}

void la_sparse_gaxpy(const la_sparse *A, const double *x, double *y) {
  for (int j = 0; j < A->ncol; j++) {
    double xj = x[j];
    if (xj == 0) continue;
    for (int k = A->p[j]; k < A->p[j + 1]; k++) y[A->i[k]] += A->x[k] * xj;
  }
}

void la_sparse_gatxy(const la_sparse *A, const double *x, double *y) {
  for (int j = 0; j < A->ncol; j++) {
    double s = 0;
    for (int k = A->p[j]; k < A->p[j + 1]; k++) s += A->x[k] * x[A->i[k]];
    y[j] = s;
  }
}

int la_dense_pchol(double *a, int k, int *perm, double tol) {
  double dmax = 0;
  for (int j = 0; j < k; j++) {
    perm[j] = j;
    if (a[j + (size_t)j * k] > dmax) dmax = a[j + (size_t)j * k];
  }
  if (!(dmax > 0)) return 0;
  double floor_ = tol * dmax;
  /* Right-looking with symmetric pivoting on the largest remaining diagonal.
   * Rows and columns are swapped physically so that L is contiguous. */
  for (int j = 0; j < k; j++) {
    int piv = j;
    for (int i = j + 1; i < k; i++)
      if (a[i + (size_t)i * k] > a[piv + (size_t)piv * k]) piv = i;
    if (!(a[piv + (size_t)piv * k] > floor_)) return j;
    if (piv != j) {
      int t = perm[j]; perm[j] = perm[piv]; perm[piv] = t;
      for (int c = 0; c < k; c++) {           /* swap rows j, piv */
        double s = a[j + (size_t)c * k]; a[j + (size_t)c * k] = a[piv + (size_t)c * k];
        a[piv + (size_t)c * k] = s;
      }
      for (int r = 0; r < k; r++) {           /* swap columns j, piv */
        double s = a[r + (size_t)j * k]; a[r + (size_t)j * k] = a[r + (size_t)piv * k];
        a[r + (size_t)piv * k] = s;
      }
    }
    double d = sqrt(a[j + (size_t)j * k]);
    a[j + (size_t)j * k] = d;
    for (int i = j + 1; i < k; i++) a[i + (size_t)j * k] /= d;
    /* Update the whole trailing block (both triangles) so later symmetric
     * swaps see consistent entries. */
    for (int c = j + 1; c < k; c++) {
      double lc = a[c + (size_t)j * k];
      for (int i = j + 1; i < k; i++) a[i + (size_t)c * k] -= a[i + (size_t)j * k] * lc;
    }
  }
  return k;
}

void la_dense_pchol_solve(const double *l, int k, int r, const int *perm,
                          const double *b, double *x, double *w) {
  for (int j = 0; j < r; j++) w[j] = b[perm[j]];
  for (int j = 0; j < r; j++) {             /* L w = b */
    w[j] /= l[j + (size_t)j * k];
    for (int i = j + 1; i < r; i++) w[i] -= l[i + (size_t)j * k] * w[j];
  }
  for (int j = r - 1; j >= 0; j--) {        /* L^T w = w */
    for (int i = j + 1; i < r; i++) w[j] -= l[i + (size_t)j * k] * w[i];
    w[j] /= l[j + (size_t)j * k];
  }
  for (int j = 0; j < k; j++) x[perm[j]] = j < r ? w[j] : 0.0;
}

int la_cholmod_start(cholmod_common *c) {
  if (!cholmod_start(c)) return CUP_ERR_LINALG;
  c->print = 0;            /* the library never prints */
  c->error_handler = NULL;
  return CUP_OK;
}

void la_simplicial_solve(const cholmod_factor *L, double *x, double *w) {
  const int n = (int)L->n;
  const int *Lp = L->p, *Li = L->i, *Lnz = L->nz, *perm = L->Perm;
  const double *Lx = L->x;
  for (int k = 0; k < n; k++) w[k] = perm ? x[perm[k]] : x[k];
  if (L->is_ll) {
    for (int j = 0; j < n; j++) {                    /* L w = b */
      int p0 = Lp[j], p1 = Lp[j] + Lnz[j];
      double wj = w[j] / Lx[p0];
      w[j] = wj;
      for (int p = p0 + 1; p < p1; p++) w[Li[p]] -= Lx[p] * wj;
    }
    for (int j = n - 1; j >= 0; j--) {               /* L^T w = w */
      int p0 = Lp[j], p1 = Lp[j] + Lnz[j];
      double wj = w[j];
      for (int p = p0 + 1; p < p1; p++) wj -= Lx[p] * w[Li[p]];
      w[j] = wj / Lx[p0];
    }
  } else {
    for (int j = 0; j < n; j++) {                    /* unit L */
      int p0 = Lp[j], p1 = Lp[j] + Lnz[j];
      double wj = w[j];
      for (int p = p0 + 1; p < p1; p++) w[Li[p]] -= Lx[p] * wj;
    }
    for (int j = 0; j < n; j++) w[j] /= Lx[Lp[j]];  /* D */
    for (int j = n - 1; j >= 0; j--) {
      int p0 = Lp[j], p1 = Lp[j] + Lnz[j];
      double wj = w[j];
      for (int p = p0 + 1; p < p1; p++) wj -= Lx[p] * w[Li[p]];
      w[j] = wj;
    }
  }
  for (int k = 0; k < n; k++) {
    if (perm) x[perm[k]] = w[k]; else x[k] = w[k];
  }
}

/* (la_dense_lu's body, inlined for a constant k below: the same operations
 * in the same order, unrolled) */
static inline __attribute__((always_inline)) int lu_body(double *a, int k, int *piv) {
  for (int i = 0; i < k; i++) piv[i] = i;
  for (int j = 0; j < k; j++) {
    int p = j;
    for (int i = j + 1; i < k; i++)
      if (fabs(a[i + (size_t)j * k]) > fabs(a[p + (size_t)j * k])) p = i;
    if (a[p + (size_t)j * k] == 0) return j + 1;
    if (p != j) {
      int t = piv[j]; piv[j] = piv[p]; piv[p] = t;
      for (int c = 0; c < k; c++) {
        double s = a[j + (size_t)c * k]; a[j + (size_t)c * k] = a[p + (size_t)c * k];
        a[p + (size_t)c * k] = s;
      }
    }
    double d = a[j + (size_t)j * k];
    for (int i = j + 1; i < k; i++) a[i + (size_t)j * k] /= d;
    for (int c = j + 1; c < k; c++) {
      double f = a[j + (size_t)c * k];
      if (f == 0) continue;
      for (int i = j + 1; i < k; i++) a[i + (size_t)c * k] -= a[i + (size_t)j * k] * f;
    }
  }
  return 0;
}

/* (The LCPs' principal blocks and the split's N of a circuit are 3 x 3 and
 * 4 x 4: a six-pulse bridge's run factors ~60 of them.) */
int la_dense_lu(double *a, int k, int *piv) {
  switch (k) {
    case 3: return lu_body(a, 3, piv);
    case 4: return lu_body(a, 4, piv);
  }
  return lu_body(a, k, piv);
}

static inline __attribute__((always_inline)) void lu_solve_body(const double *lu, int k, const int *piv, double *b,
                                                                double *w) {
  for (int i = 0; i < k; i++) w[i] = b[piv[i]];
  for (int i = 0; i < k; i++) b[i] = w[i];
  for (int j = 0; j < k; j++)               /* L y = Pb, unit diagonal */
    for (int i = j + 1; i < k; i++) b[i] -= lu[i + (size_t)j * k] * b[j];
  for (int j = k - 1; j >= 0; j--) {        /* U x = y */
    b[j] /= lu[j + (size_t)j * k];
    for (int i = 0; i < j; i++) b[i] -= lu[i + (size_t)j * k] * b[j];
  }
}

void la_dense_lu_solve(const double *lu, int k, const int *piv, double *b, double *w) {
  switch (k) {
    case 3: lu_solve_body(lu, 3, piv, b, w); return;
    case 4: lu_solve_body(lu, 4, piv, b, w); return;
  }
  lu_solve_body(lu, k, piv, b, w);
}

/* c's column j for a constant k (up to 8), its sums in registers: from +0
 * over l in order, a term of b_lj = 0 left out, as the generic loop's. */
static inline __attribute__((always_inline)) void dense_mul_few(const double *restrict a,
                                                                const double *restrict b, int k,
                                                                double *restrict c) {
  for (int j = 0; j < k; j++) {
    double v[8] = {0};
    for (int l = 0; l < k; l++) {
      double blj = b[l + (size_t)j * k];
      if (blj == 0) continue;
      for (int i = 0; i < k; i++) v[i] += a[i + (size_t)l * k] * blj;
    }
    for (int i = 0; i < k; i++) c[i + (size_t)j * k] = v[i];
  }
}

/* (A converter's exponentials are of 2 to 7 states and sources: the
 * loops unrolled, the same sums; the six-pulse bridge's 8 x 8, before
 * 865d3b5 made it 4 x 4, took 12 k instructions an exponential, 9 k so.) */
static void dense_mul(const double *restrict a, const double *restrict b, int k, double *restrict c) {
  switch (k) {
    case 2: dense_mul_few(a, b, 2, c); return;
    case 3: dense_mul_few(a, b, 3, c); return;
    case 4: dense_mul_few(a, b, 4, c); return;
    case 5: dense_mul_few(a, b, 5, c); return;
    case 6: dense_mul_few(a, b, 6, c); return;
    case 7: dense_mul_few(a, b, 7, c); return;
  }
  memset(c, 0, sizeof(double) * (size_t)k * k);
  for (int j = 0; j < k; j++)
    for (int l = 0; l < k; l++) {
      double blj = b[l + (size_t)j * k];
      if (blj == 0) continue;
      for (int i = 0; i < k; i++) c[i + (size_t)j * k] += a[i + (size_t)l * k] * blj;
    }
}

/* s = a / 2^sq with ||s||_inf <= 1/2: the scaling of both exponentials;
 * returns sq. */
static int expm_scale(const double *a, int k, double *s) {
  double norm = 0;                          /* infinity norm */
  for (int i = 0; i < k; i++) {
    double r = 0;
    for (int j = 0; j < k; j++) r += fabs(a[i + (size_t)j * k]);
    norm = fmax(norm, r);
  }
  int sq = 0;
  while (norm > 0.5 && sq < 1000) { norm *= 0.5; sq++; }
  double scale = ldexp(1.0, -sq);
  for (size_t q = 0; q < (size_t)k * k; q++) s[q] = a[q] * scale;
  return sq;
}

/* X = exp(s) - I = sum_{d=1}^{15} s^d / d! (||s|| <= 1/2: the rest is
 * below 1e-18 of ||X||) by Paterson-Stockmeyer, a Horner scheme in s^4
 * whose coefficients are the blocks sum_i s^i / (4j + i)!, i < 4: 6
 * products instead of the 17 of the terms one by one; then X carried
 * through the squarings as (I + X)^2 = I + (2 X + X^2). */
void la_dense_expm_stiff(const double *a, int k, double *out, double *work) {
  size_t K2 = (size_t)k * k;
  double *s = work, *s2 = s + K2, *s3 = s2 + K2, *s4 = s3 + K2, *tmp = s4 + K2, *x = out;
  double c[16];                             /* 1 / d!, each rounded once */
  double f = 1;
  for (int d = 0; d < 16; d++) {
    if (d > 0) f *= d;
    c[d] = 1 / f;
  }
  c[0] = 0;                                 /* X: no identity */
  int sq = expm_scale(a, k, s);
  dense_mul(s, s, k, s2);
  dense_mul(s2, s, k, s3);
  dense_mul(s2, s2, k, s4);
  for (int j = 3; j >= 0; j--) {            /* x = x s^4 + block j */
    const double *cj = c + 4 * j;
    if (j < 3) dense_mul(x, s4, k, tmp);
    else la_zero(tmp, (int)K2);             /* (0 + c1 s: a -0 term makes +0) */
    for (size_t q = 0; q < K2; q++) x[q] = tmp[q] + cj[1] * s[q] + cj[2] * s2[q] + cj[3] * s3[q];
    for (int i = 0; i < k; i++) x[i + (size_t)i * k] += cj[0];
  }
  for (int r = 0; r < sq; r++) {            /* X <- 2 X + X^2 */
    dense_mul(x, x, k, tmp);
    for (size_t q = 0; q < K2; q++) x[q] = 2 * x[q] + tmp[q];
  }
  for (int i = 0; i < k; i++) out[i + (size_t)i * k] += 1;
}

void la_dense_expm(const double *a, int k, double *out, double *work) {
  double *s = work, *term = work + (size_t)k * k, *tmp = term + (size_t)k * k;
  int sq = expm_scale(a, k, s);
  /* Taylor to degree 18: remainder < 0.5^19 / 19! relative */
  memset(out, 0, sizeof(double) * (size_t)k * k);
  for (int i = 0; i < k; i++) out[i + (size_t)i * k] = 1;
  memcpy(term, out, sizeof(double) * (size_t)k * k);
  for (int d = 1; d <= 18; d++) {
    dense_mul(term, s, k, tmp);
    for (size_t q = 0; q < (size_t)k * k; q++) { term[q] = tmp[q] / d; out[q] += term[q]; }
  }
  for (int r = 0; r < sq; r++) {
    dense_mul(out, out, k, tmp);
    memcpy(out, tmp, sizeof(double) * (size_t)k * k);
  }
}

int la_dense_symm_eig(double *a, int k, double *ev, double *w) {
  if (k < 1) return 0;                           /* (a view of none is GSL's error) */
  gsl_matrix_view A = gsl_matrix_view_array(a, (size_t)k, (size_t)k);
  gsl_vector_view v = gsl_vector_view_array(ev, (size_t)k);
  gsl_eigen_symm_workspace ws = {(size_t)k, w, w + k};   /* (gsl_eigen_symm_alloc's: size, d, sd) */
  gsl_error_handler_t *old = gsl_set_error_handler_off();   /* GSL would abort */
  int rc = gsl_eigen_symm(&A.matrix, &v.vector, &ws);
  gsl_set_error_handler(old);
  return rc;
}
