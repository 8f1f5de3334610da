/* Shared helpers for the cmocka tests: a seeded generator, dense <-> CSC
 * conversion, and an independent dense projection reference built on GSL
 * (enumeration of active sets for m <= 10; dual coordinate ascent polished
 * by an SVD least-squares solve on the identified active set otherwise).
 * None of this calls the library's own numerics. */
#ifndef CUP_TESTUTIL_H
#define CUP_TESTUTIL_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_vector.h>
#include "catchup.h"

#ifndef M_PIl
#define M_PIl 3.141592653589793238462643383279502884L
#endif

/* |a - b| <= tol, with both values in the failure message (cmocka 1.1.5 has
 * no double comparison). Needs cmocka.h included before this header. */
#define assert_close(a, b, tol) do {                                          \
    double a_ = (a), b_ = (b), t_ = (tol);                                    \
    if (!(fabs(a_ - b_) <= t_))                                               \
      fail_msg("%s = %.17g vs %s = %.17g: differ by %.3g > %.3g", #a, a_, #b, b_, \
               fabs(a_ - b_), t_);                                            \
  } while (0)

typedef struct { uint64_t s; } rng_t;
static inline uint64_t rng_next(rng_t *r) {          /* splitmix64 */
  uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
static inline double rng_unif(rng_t *r) { return (rng_next(r) >> 11) * 0x1.0p-53; }
static inline double rng_normal(rng_t *r) {
  double u1 = rng_unif(r), u2 = rng_unif(r);
  return sqrt(-2 * log(u1 + 1e-300)) * cos(2 * M_PI * u2);
}
static inline int rng_int(rng_t *r, int lo, int hi) { return lo + (int)(rng_next(r) % (uint64_t)(hi - lo + 1)); }

/* A dense matrix (row-major, nr x nc) as an owned CSC. */
typedef struct { int nr, nc; int *p, *i; double *x; cup_csc view; } tcsc;
static inline void tcsc_from_dense(tcsc *A, const double *d, int nr, int nc) {
  A->nr = nr; A->nc = nc;
  A->p = malloc(sizeof(int) * (nc + 1));
  A->i = malloc(sizeof(int) * (nr * nc + 1));
  A->x = malloc(sizeof(double) * (nr * nc + 1));
  int q = 0;
  A->p[0] = 0;
  for (int j = 0; j < nc; j++) {
    for (int r = 0; r < nr; r++)
      if (d[r * nc + j] != 0) { A->i[q] = r; A->x[q++] = d[r * nc + j]; }
    A->p[j + 1] = q;
  }
  A->view = (cup_csc){nr, nc, A->p, A->i, A->x};
}
static inline void tcsc_free(tcsc *A) { free(A->p); free(A->i); free(A->x); }

/* The polyset {y : C y + g >= 0} of a dense C (m x n, row-major; its CSC
 * copy in *Ct, freed by the caller) in the metric diag(pdiag) (NULL: the
 * identity); the test fails, saying why, if it is refused. */
static inline cup_polyset *tpolyset_dense(tcsc *Ct, const double *C, int m, int n, const double *g,
                                          const double *pdiag) {
  tcsc_from_dense(Ct, C, m, n);
  cup_metric P = {.kind = CUP_METRIC_DIAGONAL, .diag = pdiag};
  cup_polyset *K = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_polyset_create(&K, &Ct->view, g, pdiag ? &P : NULL, msg)) fail_msg("polyset: %s", msg);
  return K;
}

/* ---- the independent reference --------------------------------------------- */

typedef struct {
  int n, m;
  const double *C;   /* m x n row-major */
  const double *g;   /* m */
  const double *P;   /* n x n row-major SPD */
} ref_problem;

static inline double ref_pnorm2(const ref_problem *q, const double *v) {
  double s = 0;
  for (int a = 0; a < q->n; a++)
    for (int b = 0; b < q->n; b++) s += v[a] * q->P[a * q->n + b] * v[b];
  return s;
}

/* The excess ||x - z||_P^2 - ||x - zr||_P^2 of z over zr, as the product
 * (zr - z)^T P (2x - z - zr) in long double: the difference of the two
 * squares cancels catastrophically when P is ill-conditioned (cond 1e8: an
 * error of 1e-14 S^2 on an excess of 1e-13), the product does not. */
static inline double ref_excess(const ref_problem *q, const double *x, const double *z,
                                const double *zr) {
  long double s = 0;
  for (int a = 0; a < q->n; a++) {
    long double da = (long double)zr[a] - z[a], pa = 0;
    for (int b = 0; b < q->n; b++)
      pa += (long double)q->P[a * q->n + b] * (2.0L * x[b] - z[b] - zr[b]);
    s += da * pa;
  }
  return (double)s;
}

/* Pinv = P^-1 (n x n), B = P^-1 C^T (n x m), M = C P^-1 C^T (m x m) via GSL. */
typedef struct { int n, m; double *B, *M; } ref_work;
static inline void ref_setup(const ref_problem *q, ref_work *w) {
  int n = q->n, m = q->m;
  gsl_matrix *L = gsl_matrix_alloc(n, n);
  for (int a = 0; a < n; a++)
    for (int b = 0; b < n; b++) gsl_matrix_set(L, a, b, q->P[a * n + b]);
  gsl_linalg_cholesky_decomp1(L);
  w->n = n; w->m = m;
  w->B = calloc((size_t)n * m + 1, sizeof(double));
  w->M = calloc((size_t)m * m + 1, sizeof(double));
  gsl_vector *col = gsl_vector_alloc(n);
  for (int i = 0; i < m; i++) {
    for (int a = 0; a < n; a++) gsl_vector_set(col, a, q->C[i * n + a]);
    gsl_linalg_cholesky_svx(L, col);
    for (int a = 0; a < n; a++) w->B[a * m + i] = gsl_vector_get(col, a);
  }
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) {
      double s = 0;
      for (int a = 0; a < n; a++) s += q->C[i * n + a] * w->B[a * m + j];
      w->M[i * m + j] = s;
    }
  gsl_vector_free(col);
  gsl_matrix_free(L);
}
static inline void ref_free(ref_work *w) { free(w->B); free(w->M); }

/* Solve M_AA lam_A = -b_A by SVD least squares (rank-deficient allowed). */
static inline void ref_solve_active(const ref_work *w, const int *A, int k,
                                    const double *b, double *lam) {
  int m = w->m;
  memset(lam, 0, sizeof(double) * m);
  if (k == 0) return;
  gsl_matrix *U = gsl_matrix_alloc(k, k), *V = gsl_matrix_alloc(k, k);
  gsl_vector *S = gsl_vector_alloc(k), *work = gsl_vector_alloc(k);
  gsl_vector *rhs = gsl_vector_alloc(k), *sol = gsl_vector_alloc(k);
  for (int a = 0; a < k; a++) {
    for (int c = 0; c < k; c++) gsl_matrix_set(U, a, c, w->M[A[a] * m + A[c]]);
    gsl_vector_set(rhs, a, -b[A[a]]);
  }
  gsl_linalg_SV_decomp(U, V, S, work);
  double smax = gsl_vector_get(S, 0);
  for (int a = 0; a < k; a++)                       /* truncate tiny singular values */
    if (gsl_vector_get(S, a) < 1e-13 * smax) gsl_vector_set(S, a, 0);
  gsl_linalg_SV_solve(U, V, S, rhs, sol);
  for (int a = 0; a < k; a++) lam[A[a]] = gsl_vector_get(sol, a);
  gsl_matrix_free(U); gsl_matrix_free(V); gsl_vector_free(S); gsl_vector_free(work);
  gsl_vector_free(rhs); gsl_vector_free(sol);
}

/* z = x + B lam; returns min slack scaled by the row norms. */
static inline double ref_primal(const ref_problem *q, const ref_work *w, const double *x,
                                const double *lam, double *z) {
  int n = q->n, m = q->m;
  for (int a = 0; a < n; a++) {
    double s = x[a];
    for (int i = 0; i < m; i++) s += w->B[a * m + i] * lam[i];
    z[a] = s;
  }
  double worst = INFINITY;
  for (int i = 0; i < m; i++) {
    double s = q->g[i], rn = sqrt(fmax(w->M[i * m + i], 1e-300));
    for (int a = 0; a < n; a++) s += q->C[i * n + a] * z[a];
    worst = fmin(worst, s / rn);
  }
  return worst;
}

/* Exact projection by enumerating the 2^m active sets (m <= 12), in long
 * double and in whitened coordinates: with P = R R^T, yh = R^T y and rows
 * ch_i = R^-1 c_i, the minimizer on an active set A is the Euclidean
 * projection onto the affine set {Ch_A yh = -g_A}, computed from a
 * Householder QR of Ch_A^T (sqrt of the conditioning of the normal
 * equations). Among candidates with lambda >= 0 that are feasible, the one
 * nearest x. Returns 0 on success, -1 if no candidate is feasible. */
typedef long double ld;
static inline int ref_project_enum(const ref_problem *q, const double *x, double *z,
                                   double ftol) {
  int n = q->n, m = q->m;
  ld *R = calloc((size_t)n * n, sizeof(ld));       /* lower: P = R R^T */
  for (int a = 0; a < n; a++)
    for (int b = 0; b <= a; b++) {
      ld s = q->P[a * n + b];
      for (int k = 0; k < b; k++) s -= R[a * n + k] * R[b * n + k];
      R[a * n + b] = a == b ? sqrtl(s) : s / R[b * n + b];
    }
  ld *ch = calloc((size_t)m * n + 1, sizeof(ld)), *xh = calloc(n, sizeof(ld));
  ld *rn = calloc((size_t)m + 1, sizeof(ld));
  for (int i = 0; i < m; i++) {                     /* ch_i = R^-1 c_i (forward solve) */
    for (int a = 0; a < n; a++) {
      ld s = q->C[i * n + a];
      for (int k = 0; k < a; k++) s -= R[a * n + k] * ch[i * n + k];
      ch[i * n + a] = s / R[a * n + a];
    }
    ld t = 0;
    for (int a = 0; a < n; a++) t += ch[i * n + a] * ch[i * n + a];
    rn[i] = sqrtl(t);
  }
  for (int a = 0; a < n; a++) {                     /* xh = R^T x */
    ld s = 0;
    for (int k = a; k < n; k++) s += R[k * n + a] * x[k];
    xh[a] = s;
  }
  ld xs = 0;
  for (int a = 0; a < n; a++) xs += xh[a] * xh[a];
  xs = sqrtl(xs);
  for (int i = 0; i < m; i++) if (rn[i] > 0) xs = fmaxl(xs, fabsl((ld)q->g[i]) / rn[i]);
  ld *Qr = malloc(sizeof(ld) * (size_t)n * (m + 1)), *v = malloc(sizeof(ld) * n);
  ld *w = malloc(sizeof(ld) * (m + 1)), *yh = malloc(sizeof(ld) * n), *best_y = malloc(sizeof(ld) * n);
  ld *beta = malloc(sizeof(ld) * (m + 1));
  int *A = malloc(sizeof(int) * (m + 1));
  ld best = INFINITY;
  for (uint32_t mask = 0; mask < (1u << m); mask++) {
    int k = 0;
    for (int i = 0; i < m; i++) if (mask >> i & 1) A[k++] = i;
    if (k > n) continue;
    /* Qr = Ch_A^T (n x k, column-major), Householder in place */
    for (int c = 0; c < k; c++)
      for (int a = 0; a < n; a++) Qr[c * n + a] = ch[A[c] * n + a];
    int ok = 1;
    for (int c = 0; c < k && ok; c++) {
      ld nrm = 0;
      for (int a = c; a < n; a++) nrm += Qr[c * n + a] * Qr[c * n + a];
      nrm = sqrtl(nrm);
      if (!(nrm > 1e-9L * rn[A[c]])) { ok = 0; break; }  /* dependent: another subset covers it */
      ld alpha = Qr[c * n + c] > 0 ? -nrm : nrm;
      for (int a = 0; a < n; a++) v[a] = a < c ? 0 : Qr[c * n + a];
      v[c] -= alpha;
      ld vv = 0;
      for (int a = c; a < n; a++) vv += v[a] * v[a];
      beta[c] = vv > 0 ? 2 / vv : 0;
      for (int cc = c; cc < k; cc++) {
        ld d = 0;
        for (int a = c; a < n; a++) d += v[a] * Qr[cc * n + a];
        d *= beta[c];
        for (int a = c; a < n; a++) Qr[cc * n + a] -= d * v[a];
      }
      for (int a = c + 1; a < n; a++) Qr[c * n + a] = v[a];   /* keep v below the diagonal */
      Qr[c * n + c] = alpha;
      w[c] = v[c];                                            /* v's head */
    }
    if (!ok) continue;
    /* r = Ch_A xh + g_A; solve R_q^T u = r; correction = Q [u; 0] */
    ld *u = malloc(sizeof(ld) * (k + 1));
    for (int c = 0; c < k; c++) {
      ld s = q->g[A[c]];
      for (int a = 0; a < n; a++) s += ch[A[c] * n + a] * xh[a];
      for (int cc = 0; cc < c; cc++) s -= Qr[c * n + cc] * u[cc];
      u[c] = s / Qr[c * n + c];
    }
    /* lambda = -R_q^-1 u: back substitution, sign check only */
    ld *lam = malloc(sizeof(ld) * (k + 1));
    for (int c = k - 1; c >= 0; c--) {
      ld s = -u[c];
      for (int cc = c + 1; cc < k; cc++) s -= Qr[cc * n + c] * lam[cc];
      lam[c] = s / Qr[c * n + c];
    }
    for (int c = 0; c < k && ok; c++) ok = lam[c] >= -1e-14L * (1 + fabsl(lam[c]));
    if (ok) {
      /* correction vector t = Q [u; 0] = H_0 ... H_{k-1} [u; 0] */
      ld *t = calloc(n, sizeof(ld));
      for (int c = 0; c < k; c++) t[c] = u[c];
      for (int c = k - 1; c >= 0; c--) {
        v[c] = w[c];
        for (int a = c + 1; a < n; a++) v[a] = Qr[c * n + a];
        ld d = 0;
        for (int a = c; a < n; a++) d += v[a] * t[a];
        d *= beta[c];
        for (int a = c; a < n; a++) t[a] -= d * v[a];
      }
      ld obj = 0;
      for (int a = 0; a < n; a++) { yh[a] = xh[a] - t[a]; obj += t[a] * t[a]; }
      for (int i = 0; i < m && ok; i++) {       /* feasibility in whitened coordinates */
        if (rn[i] == 0) { ok = q->g[i] >= 0; continue; }
        ld s = q->g[i];
        for (int a = 0; a < n; a++) s += ch[i * n + a] * yh[a];
        ok = s / rn[i] >= -(ld)ftol * (1 + xs);
      }
      if (ok && obj < best) { best = obj; memcpy(best_y, yh, sizeof(ld) * n); }
      free(t);
    }
    free(u); free(lam);
  }
  if (isfinite((double)best)) {
    for (int a = n - 1; a >= 0; a--) {               /* y = R^-T yh (back solve) */
      ld s = best_y[a];
      for (int k = a + 1; k < n; k++) s -= R[k * n + a] * yh[k];
      yh[a] = s / R[a * n + a];
    }
    for (int a = 0; a < n; a++) z[a] = (double)yh[a];
  }
  int ret = isfinite((double)best) ? 0 : -1;
  free(R); free(ch); free(xh); free(rn); free(Qr); free(v); free(w); free(yh); free(best_y);
  free(beta); free(A);
  return ret;
}

/* High-accuracy projection for larger m: Hildreth's dual coordinate ascent,
 * polished by least squares on its support, repeated until the KKT
 * conditions hold to 1e-13 relative. Returns 0, or -1 if not converged. */
static inline int ref_project_hildreth(const ref_problem *q, const double *x, double *z) {
  int n = q->n, m = q->m;
  ref_work w; ref_setup(q, &w);
  double *b = malloc(sizeof(double) * m), *lam = calloc(m, sizeof(double));
  double *pol = malloc(sizeof(double) * m), *r = malloc(sizeof(double) * m);
  int *A = malloc(sizeof(int) * m);
  for (int i = 0; i < m; i++) {
    double s = q->g[i];
    for (int a = 0; a < n; a++) s += q->C[i * n + a] * x[a];
    b[i] = s;
  }
  double scale = sqrt(ref_pnorm2(q, x)) + 1e-300;
  int done = -1;
  for (int round = 0; round < 400 && done; round++) {
    for (int sweep = 0; sweep < 200; sweep++)
      for (int i = 0; i < m; i++) {
        if (!(w.M[i * m + i] > 0)) continue;
        double gi = b[i];
        for (int j = 0; j < m; j++) gi += w.M[i * m + j] * lam[j];
        lam[i] = fmax(0, lam[i] - gi / w.M[i * m + i]);
      }
    int k = 0;
    for (int i = 0; i < m; i++) if (lam[i] > 0) A[k++] = i;
    ref_solve_active(&w, A, k, b, pol);
    int ok = 1;
    for (int a = 0; a < k && ok; a++) ok = pol[A[a]] >= -1e-13 * (1 + fabs(pol[A[a]]));
    for (int i = 0; i < m; i++) {
      double s = b[i];
      for (int j = 0; j < m; j++) s += w.M[i * m + j] * pol[j];
      r[i] = s;
      if (s < -1e-13 * (scale * sqrt(fmax(w.M[i * m + i], 0)) + fabs(q->g[i]))) ok = 0;
    }
    if (ok) {
      for (int i = 0; i < m; i++) pol[i] = fmax(pol[i], 0);
      ref_primal(q, &w, x, pol, z);
      done = 0;
    }
  }
  free(b); free(lam); free(pol); free(r); free(A);
  ref_free(&w);
  return done;
}

static inline int ref_project(const ref_problem *q, const double *x, double *z) {
  if (q->m <= 10) return ref_project_enum(q, x, z, 1e-13);
  return ref_project_hildreth(q, x, z);
}

#endif
