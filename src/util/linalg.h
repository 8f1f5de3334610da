/* linalg — owned sparse matrices, small dense Cholesky, CHOLMOD set-up;
 * growing arrays. Internal to the library. Its users report errors too: it
 * includes fail.h (fail_fmt). */
#ifndef CUP_LINALG_H
#define CUP_LINALG_H

#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <cholmod.h>
#include "catchup/sparse.h"
#include "fail.h"

/* An owned CSC matrix. */
typedef struct la_sparse {
  int nrow, ncol, nnz;
  int *p;       /* ncol+1 */
  int *i;       /* nnz */
  double *x;    /* nnz */
} la_sparse;

/* Room for one more element in the array *(T **)arr of *cap elements of
 * size bytes, n of them in use: doubles *cap (from first) when n == *cap.
 * CUP_ERR_NOMEM leaves the array and *cap as they were. */
int la_grow(void *arr, int *cap, int n, size_t size, int first);

/* Copy and validate a view: sizes, index ranges, strictly increasing rows in
 * each column, finite values. `name` is used in messages ("C", "P"). */
int la_sparse_copy(la_sparse *A, const cup_csc *view, const char *name,
                   int nrow, int ncol, char *errmsg);
int la_sparse_alloc(la_sparse *A, int nrow, int ncol, int nnz);
void la_sparse_free(la_sparse *A);
/* At = A^T (allocates At). */
int la_sparse_transpose(la_sparse *At, const la_sparse *A);
/* y += A x */
void la_sparse_gaxpy(const la_sparse *A, const double *x, double *y);
/* y = A^T x computed by column gathers (y has A->ncol entries). */
void la_sparse_gatxy(const la_sparse *A, const double *x, double *y);

/* Dense pivoted Cholesky of the k x k symmetric matrix a (column-major,
 * lower triangle used, overwritten by L). perm receives the pivot order; the
 * returned rank r counts pivots above tol * (largest diagonal). Rows beyond
 * the rank are treated as linearly dependent. */
int la_dense_pchol(double *a, int k, int *perm, double tol);
/* Solve with the first r pivots of a factor from la_dense_pchol: x[perm[j]]
 * for j < r is set, x[perm[j]] = 0 for j >= r. b is not modified. */
void la_dense_pchol_solve(const double *l, int k, int r, const int *perm,
                          const double *b, double *x, double *work);

/* A CHOLMOD common that never prints and uses our memory routines. */
int la_cholmod_start(cholmod_common *c);

/* max/min without a libm call (fmax is not inlined at -O2); with a NaN
 * argument they return the second argument, so callers that must not let
 * NaN through use explicit comparisons instead. */
static inline double la_max(double a, double b) { return a > b ? a : b; }
static inline double la_min(double a, double b) { return a < b ? a : b; }
/* fmax and fmin themselves without the call, to the bit (glibc's: maxsd
 * and minsd give b when a == b; a NaN argument gives the other one). */
static inline double la_fmax(double a, double b) { return a > b || b != b ? a : b; }
static inline double la_fmin(double a, double b) { return a < b || b != b ? a : b; }
/* max |v_i| from 0, as fmax(r, |v_i|) sums it (a NaN entry passed over),
 * without a libm call an entry. */
static inline double la_norm_inf(const double *v, int n) {
  double r = 0;
  for (int i = 0; i < n; i++) r = la_max(fabs(v[i]), r);
  return r;
}
/* floor(x) without a libm call (x86-64's baseline has no rounding
 * instruction): the same value, zeros, Inf and NaN included. */
static inline double la_floor(double x) {
  if (!(fabs(x) < 0x1p52) || x == 0) return x;   /* already an integer, or NaN */
  double t = (double)(long long)x;               /* x truncated toward 0, exact */
  return t > x ? t - 1 : t;
}

/* Copies and fills of short vectors: loops beat a libc call for the tiny
 * sizes of circuit models and are no worse for long ones. */
static inline void la_copy(double *dst, const double *src, int n) {
  for (int k = 0; k < n; k++) dst[k] = src[k];
}
static inline void la_zero(double *dst, int n) {
  for (int k = 0; k < n; k++) dst[k] = 0;
}
/* The same for a few entries (a sample's inputs, state, multipliers): GCC
 * turns la_zero's loop (and some of la_copy's) into a libc call of about
 * 20 instructions, or vectorizes it with as many of set-up; the empty asm
 * in the body keeps each a plain loop of 2 or 3 instructions an entry. */
static inline void la_copy_few(double *dst, const double *src, int n) {
  for (int k = 0; k < n; k++) {
    dst[k] = src[k];
    __asm__ volatile("");
  }
}
static inline void la_zero_few(double *dst, int n) {
  for (int k = 0; k < n; k++) {
    dst[k] = 0;
    __asm__ volatile("");
  }
}

/* cup_status_merge for the library's own hot paths (the exported function
 * is the same rule). */
static inline int status_merge(int first, int second) {
  if (first < 0) return first;
  if (second < 0) return second;
  return first > 0 ? first : second;
}

static inline double la_dot(const double *a, const double *b, int n) {
  double s = 0;
  for (int k = 0; k < n; k++) s += a[k] * b[k];
  return s;
}

#endif

/* In-place solve with a simplicial CHOLMOD factor (LL^T or LDL^T) including
 * its fill-reducing permutation: x <- A^-1 x. w is n entries of scratch.
 * Allocation-free (cholmod_solve2 allocates on every call). */
void la_simplicial_solve(const cholmod_factor *L, double *x, double *w);

/* ---- small dense matrices (column-major, k x k), allocation-free ---------- */

/* LU with partial pivoting in place; piv gets the row order. Returns 0, or
 * j+1 if the pivot in column j is exactly zero. */
int la_dense_lu(double *a, int k, int *piv);
/* Solve with the factor from la_dense_lu, in place; w: k doubles. */
void la_dense_lu_solve(const double *lu, int k, const int *piv, double *b, double *w);
/* The eigenvalues of the symmetric k x k matrix a (overwritten) into ev, by
 * GSL's gsl_eigen_symm with its error handler off, its workspace in w (2 k
 * doubles): no allocation (gsl_eigen_symm_alloc and gsl_*_alloc were six
 * mallocs and six frees a call, some 2 k instructions for each switch
 * configuration formed). Returns GSL's status (0: done). */
int la_dense_symm_eig(double *a, int k, double *ev, double *w);
/* out = exp(a) by scaling and squaring of a degree-18 Taylor polynomial;
 * work holds 3 k*k doubles. a and out must differ. */
void la_dense_expm(const double *a, int k, double *out, double *work);
/* exp(a) with X = exp(a/2^s) - I carried through the squarings,
 * (I + X)^2 = I + (2 X + X^2): forming I + X rounds X's small entries
 * against 1 and each squaring doubles that, 2^s eps in all (1e-11 on a
 * generator with |lambda| ~ 1e5); this keeps them. X itself: the degree-15
 * Taylor polynomial by Paterson-Stockmeyer (6 products). work: 5 k*k
 * doubles; a and out must differ. */
void la_dense_expm_stiff(const double *a, int k, double *out, double *work);
