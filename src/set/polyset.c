/* polyset — K = {x : C x + g >= 0} with a metric P (paper, Sec. 7: the
 * polyhedron K(t) and the metric P with P B = C^T). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include "catchup.h"
#include "catchup/polyset.h"
#include "polyset_impl.h"
#include "util/block.h"

/* A small set's scratch (doubles) on the stack: a switched run makes its
 * sets inside its run, a malloc and a free each was some 250 instructions */
#define PS_SMALL 256

static int metric_setup(cup_polyset *K, const cup_metric *P, char *errmsg);
static int row_norms_and_lipschitz(cup_polyset *K, double *work, char *errmsg);
static int dense_setup(cup_polyset *K, char *errmsg);
static void find_interior_direction(cup_polyset *K);

int cup_polyset_create(cup_polyset **out, const cup_csc *C, const double *g,
                       const cup_metric *P, char *errmsg) {
  return polyset_create_ex(out, C, g, P, 0, NULL, errmsg);
}

int polyset_create_ex(cup_polyset **out, const cup_csc *C, const double *g,
                      const cup_metric *P, int mutable_values, double *work, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "polyset: output pointer is NULL");
  *out = NULL;
  if (!C) return fail_fmt(errmsg, CUP_ERR_ARG, "polyset: C is NULL");
  if (C->ncol < 1 || C->nrow < 0)
    return fail_fmt(errmsg, CUP_ERR_DIM, "polyset: C is %d x %d; need at least one column",
                    C->nrow, C->ncol);
  cup_polyset *K = calloc(1, sizeof *K);
  if (!K) return fail_fmt(errmsg, CUP_ERR_NOMEM, "polyset: out of memory");
  K->n = C->ncol;
  K->m = C->nrow;
  /* a bound recomputed at every step gets a few iterations (it is valid
   * after any number; more only tighten it) */
  K->mutable_values = mutable_values;
  K->cw_iters = mutable_values ? 6 : 40;
  int st = la_sparse_copy(&K->C, C, "C", K->m, K->n, errmsg);
  if (!st) st = la_sparse_transpose(&K->Ct, &K->C);
  if (!st) {
    size_t M = (size_t)K->m + 1;                  /* one zeroed block that g0 owns: rownorm, rowgam, rownnz */
    K->g0 = calloc(3 * M * sizeof(double) + M * sizeof(int), 1);
    if (!K->g0) st = CUP_ERR_NOMEM;
    else {
      K->rownorm = K->g0 + M;
      K->rowgam = K->rownorm + M;
      K->rownnz = (int *)(K->rowgam + M);
    }
  }
  if (st == CUP_ERR_NOMEM) fail_fmt(errmsg, st, "polyset: out of memory");
  for (int i = 0; !st && i < K->m; i++) {
    K->rownnz[i] = K->Ct.p[i + 1] - K->Ct.p[i];
    K->rowgam[i] = (K->rownnz[i] + 2) * DBL_EPSILON;
    if (g) {
      if (!isfinite(g[i])) st = fail_fmt(errmsg, CUP_ERR_NONFINITE, "g[%d] is %g", i, g[i]);
      K->g0[i] = g[i];
    }
  }
  if (!st) st = metric_setup(K, P, errmsg);
  K->solve_amp = 1;
  if (!st && K->pkind == CUP_METRIC_SPARSE) {
    double r = cholmod_rcond(K->LP, K->cm);
    K->solve_amp = r > 0 ? 1 / r : 1e16;
  }
  K->cw_warm = work != NULL;
  if (!st) st = row_norms_and_lipschitz(K, work, errmsg);
  if (!st && !mutable_values && K->m <= CUP_DENSE_MAX_ROWS && K->n <= CUP_DENSE_MAX_DIM)
    st = dense_setup(K, errmsg);
  if (st) { cup_polyset_free(&K); return st; }
  if (K->dense) find_interior_direction(K);
  *out = K;
  return CUP_OK;
}

void cup_polyset_free(cup_polyset **Kp) {
  if (!Kp || !*Kp) return;
  cup_polyset *K = *Kp;
  la_sparse_free(&K->C);
  la_sparse_free(&K->Ct);
  la_sparse_free(&K->Pfull);
  if (K->cm) {   /* started: holds workspace even if analysis failed */
    if (K->LP) cholmod_free_factor(&K->LP, K->cm);
    cholmod_finish(K->cm);
    free(K->cm);
  }
  free(K->g0); free(K->pd);                        /* (rownorm, rowgam, rownnz in g0's block; pdinv in pd's) */
  free(K->Bt); free(K->rdir);                      /* (Md in Bt's block, Crdir in rdir's) */
  free(K);
  *Kp = NULL;
}

int cup_polyset_dim(const cup_polyset *K) { return K ? K->n : 0; }
int cup_polyset_rows(const cup_polyset *K) { return K ? K->m : 0; }
double cup_polyset_lipschitz(const cup_polyset *K) { return K ? K->lip : 0; }
const double *cup_polyset_interior_direction(const cup_polyset *K) {
  return K ? K->rdir : NULL;
}

/* ---- metric ---------------------------------------------------------------- */

static int diag_setup(cup_polyset *K, const double *d, char *errmsg) {
  K->pd = malloc(sizeof(double) * 2 * (size_t)K->n);   /* pdinv in its block */
  if (!K->pd) return fail_fmt(errmsg, CUP_ERR_NOMEM, "P: out of memory");
  K->pdinv = K->pd + K->n;
  for (int j = 0; j < K->n; j++) {
    double v = d ? d[j] : 1.0;
    if (!isfinite(v)) return fail_fmt(errmsg, CUP_ERR_NONFINITE, "P(%d,%d) is %g", j, j, v);
    if (!(v > 0))
      return fail_fmt(errmsg, CUP_ERR_NOT_SPD,
                      "P(%d,%d) = %g: a positive definite P needs a positive diagonal", j, j, v);
    K->pd[j] = v;
    K->pdinv[j] = 1.0 / v;
  }
  return CUP_OK;
}

/* Full symmetric storage of a sparse P given as both triangles or the lower
 * one; checks symmetry, and reports whether any off-diagonal is nonzero. */
static int sparse_metric_full(cup_polyset *K, const cup_metric *P, int *offdiag,
                              char *errmsg) {
  la_sparse A, At;
  int st = la_sparse_copy(&A, &P->matrix, "P", K->n, K->n, errmsg);
  if (st) return st;
  *offdiag = 0;
  if (P->lower_only) {
    for (int j = 0; j < K->n && !st; j++)
      for (int k = A.p[j]; k < A.p[j + 1]; k++)
        if (A.i[k] < j) {
          st = fail_fmt(errmsg, CUP_ERR_ARG,
                        "P: lower_only is set but entry (%d,%d) is above the diagonal", A.i[k], j);
          break;
        }
    if (!st) st = la_sparse_transpose(&At, &A);
    if (st) { la_sparse_free(&A); return st; }
    /* full = A + A^T - diag(A): merge sorted columns */
    st = la_sparse_alloc(&K->Pfull, K->n, K->n, 2 * A.nnz);
    int nz = 0;
    for (int j = 0; !st && j < K->n; j++) {
      int a = At.p[j], b = A.p[j];     /* At column j: rows <= j; A column j: rows >= j */
      for (; a < At.p[j + 1]; a++) {
        if (At.i[a] == j) continue;    /* the diagonal comes from A */
        K->Pfull.i[nz] = At.i[a]; K->Pfull.x[nz++] = At.x[a];
      }
      for (; b < A.p[j + 1]; b++) { K->Pfull.i[nz] = A.i[b]; K->Pfull.x[nz++] = A.x[b]; }
      K->Pfull.p[j + 1] = nz;
    }
    if (!st) K->Pfull.nnz = nz;
    la_sparse_free(&At);
    la_sparse_free(&A);
    if (st) return fail_fmt(errmsg, st, "P: out of memory");
  } else {
    st = la_sparse_transpose(&At, &A);
    if (st) { la_sparse_free(&A); return fail_fmt(errmsg, st, "P: out of memory"); }
    double amax = 0;
    for (int k = 0; k < A.nnz; k++) amax = fmax(amax, fabs(A.x[k]));
    /* Same pattern and values as the transpose, to rounding. */
    for (int j = 0; j < K->n && !st; j++) {
      if (A.p[j + 1] - A.p[j] != At.p[j + 1] - At.p[j]) {
        st = fail_fmt(errmsg, CUP_ERR_NOT_SPD,
                      "P is not symmetric: row %d and column %d have different patterns", j, j);
        break;
      }
      for (int k = A.p[j]; k < A.p[j + 1]; k++)
        if (A.i[k] != At.i[k] || fabs(A.x[k] - At.x[k]) > 1e-12 * amax) {
          st = fail_fmt(errmsg, CUP_ERR_NOT_SPD,
                        "P is not symmetric: P(%d,%d) = %.17g but P(%d,%d) = %.17g",
                        A.i[k], j, A.x[k], j, A.i[k], At.x[k]);
          break;
        }
    }
    la_sparse_free(&At);
    if (st) { la_sparse_free(&A); return st; }
    K->Pfull = A;
  }
  for (int j = 0; j < K->n; j++) {
    int has_diag = 0;
    for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++) {
      if (K->Pfull.i[k] == j) {
        has_diag = 1;
        if (!(K->Pfull.x[k] > 0))
          return fail_fmt(errmsg, CUP_ERR_NOT_SPD,
                          "P(%d,%d) = %g: a positive definite P needs a positive diagonal",
                          j, j, K->Pfull.x[k]);
      } else if (K->Pfull.x[k] != 0) {
        *offdiag = 1;
      }
    }
    if (!has_diag)
      return fail_fmt(errmsg, CUP_ERR_NOT_SPD, "P(%d,%d) is missing: the diagonal must be positive", j, j);
  }
  return CUP_OK;
}

static int metric_setup(cup_polyset *K, const cup_metric *P, char *errmsg) {
  if (!P || P->kind == CUP_METRIC_IDENTITY) {
    K->pkind = CUP_METRIC_IDENTITY;
    return diag_setup(K, NULL, errmsg);
  }
  if (P->kind == CUP_METRIC_DIAGONAL) {
    if (!P->diag) return fail_fmt(errmsg, CUP_ERR_ARG, "P: kind is DIAGONAL but diag is NULL");
    K->pkind = CUP_METRIC_DIAGONAL;
    return diag_setup(K, P->diag, errmsg);
  }
  if (P->kind != CUP_METRIC_SPARSE)
    return fail_fmt(errmsg, CUP_ERR_ARG, "P: unknown metric kind %d", (int)P->kind);
  int offdiag = 0;
  int st = sparse_metric_full(K, P, &offdiag, errmsg);
  if (st) return st;
  if (!offdiag) {                   /* a diagonal matrix given in sparse form */
    double *d = malloc(sizeof(double) * (size_t)K->n);
    if (!d) return fail_fmt(errmsg, CUP_ERR_NOMEM, "P: out of memory");
    for (int j = 0; j < K->n; j++)
      for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++)
        if (K->Pfull.i[k] == j) d[j] = K->Pfull.x[k];
    la_sparse_free(&K->Pfull);
    K->pkind = CUP_METRIC_DIAGONAL;
    st = diag_setup(K, d, errmsg);
    free(d);
    return st;
  }
  K->pkind = CUP_METRIC_SPARSE;
  K->cm = malloc(sizeof *K->cm);
  if (!K->cm) return fail_fmt(errmsg, CUP_ERR_NOMEM, "P: out of memory");
  if (la_cholmod_start(K->cm)) {
    free(K->cm);
    K->cm = NULL;
    return fail_fmt(errmsg, CUP_ERR_LINALG, "P: CHOLMOD start failed");
  }
  K->cm->final_ll = 1;               /* L L^T so that ||L^-1 Pi c|| = ||c||_{P^-1} */
  K->cm->supernodal = CHOLMOD_SIMPLICIAL;  /* solved by la_simplicial_solve, no allocation */
  cholmod_sparse A = {0};
  A.nrow = A.ncol = (size_t)K->n;
  A.nzmax = (size_t)K->Pfull.nnz;
  A.p = K->Pfull.p; A.i = K->Pfull.i; A.x = K->Pfull.x;
  A.stype = 1;                      /* use the upper triangle of the full matrix */
  A.itype = CHOLMOD_INT; A.xtype = CHOLMOD_REAL; A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1; A.packed = 1;
  K->LP = cholmod_analyze(&A, K->cm);
  if (!K->LP) return fail_fmt(errmsg, CUP_ERR_LINALG, "P: CHOLMOD analysis failed (status %d)", K->cm->status);
  cholmod_factorize(&A, K->LP, K->cm);
  if (K->cm->status == CHOLMOD_NOT_POSDEF) {
    int bad = (int)K->LP->minor;
    int col = K->LP->Perm ? ((int *)K->LP->Perm)[bad] : bad;
    return fail_fmt(errmsg, CUP_ERR_NOT_SPD,
                    "P is not positive definite: the Cholesky factorization breaks down at column %d", col);
  }
  if (K->cm->status < 0)
    return fail_fmt(errmsg, CUP_ERR_LINALG, "P: CHOLMOD factorization failed (status %d)", K->cm->status);
  return CUP_OK;
}

void polyset_metric_apply(const cup_polyset *K, const double *v, double *out) {
  if (K->pkind == CUP_METRIC_SPARSE) {
    memset(out, 0, sizeof(double) * (size_t)K->n);
    la_sparse_gaxpy(&K->Pfull, v, out);
  } else {
    for (int j = 0; j < K->n; j++) out[j] = K->pd[j] * v[j];
  }
}

double cup_polyset_norm(const cup_polyset *K, const double *v) {
  double s = 0;
  if (K->pkind == CUP_METRIC_SPARSE) {
    for (int j = 0; j < K->n; j++) {
      double pv = 0;
      for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++) pv += K->Pfull.x[k] * v[K->Pfull.i[k]];
      s += v[j] * pv;
    }
  } else {
    for (int j = 0; j < K->n; j++) s += K->pd[j] * v[j] * v[j];
  }
  return isnan(s) ? NAN : s > 0 ? sqrt(s) : 0;   /* rounding may make s < 0; NaN must show */
}

double polyset_metric_norm_bounds(const cup_polyset *K, const double *v, double *lo, double *hi) {
  double s = 0, a = 0;
  int n = K->n;
  if (K->pkind == CUP_METRIC_SPARSE) {
    for (int j = 0; j < n; j++) {
      double pv = 0, pa = 0;
      for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++) {
        pv += K->Pfull.x[k] * v[K->Pfull.i[k]];
        pa += fabs(K->Pfull.x[k] * v[K->Pfull.i[k]]);
      }
      s += v[j] * pv;
      a += fabs(v[j]) * pa;
    }
  } else {
    for (int j = 0; j < n; j++) s += K->pd[j] * v[j] * v[j];
    a = s;
  }
  /* recursive sums of n terms of products: (n + 2) u of the absolute sum,
   * and v itself one subtraction away from the exact difference: 2 u more */
  double err = (n + 6) * DBL_EPSILON * a;
  double val = s > 0 ? sqrt(s) : 0;
  if (lo) *lo = s - err > 0 ? sqrt(s - err) : 0;
  if (hi) *hi = sqrt(s + err) * (1 + 2 * DBL_EPSILON);
  return isnan(s) ? NAN : val;
}

double polyset_metric_dist_hi(const cup_polyset *K, const double *a, const double *b, double *lo, double *w) {
  for (int j = 0; j < K->n; j++) w[j] = a[j] - b[j];
  double hi;
  polyset_metric_norm_bounds(K, w, lo, &hi);
  return hi;
}

double polyset_slack(const cup_polyset *K, const double *g, const double *x,
                     double *s, double *gam) {
  return polyset_slack_rows(K, g, x, s, gam, 0);
}

int cup_polyset_contains(const cup_polyset *K, const double *g, const double *x) {
  if (!K || !x) return 0;
  double *s = malloc(sizeof(double) * ((size_t)K->m * 2 + 1));
  if (!s) return 0;
  double worst = polyset_slack(K, g ? g : K->g0, x, s, s + K->m);
  free(s);
  return worst >= 0;                 /* false for NaN */
}

/* ---- row norms and the guaranteed Lipschitz bound ----------------------------- */

/* Collatz-Wielandt: for any v > 0 and nonnegative N, rho(N) <= max_i (Nv)_i/v_i.
 * With N >= |M| entrywise, this bounds lambda_max(M). apply(N) is a callback
 * over either |C| D^-1 |C|^T or |W|^T |W| (W = L^-1 Pi C^T). */
typedef void (*abs_apply_fn)(const cup_polyset *K, const void *W, const double *v,
                             double *out, double *tmp);

static void abs_apply_diag(const cup_polyset *K, const void *W, const double *v,
                           double *out, double *tmp) {
  (void)W;
  for (int j = 0; j < K->n; j++) {              /* tmp = D^-1 |C|^T v */
    double s = 0;
    for (int k = K->C.p[j]; k < K->C.p[j + 1]; k++) s += fabs(K->C.x[k]) * v[K->C.i[k]];
    tmp[j] = s * K->pdinv[j];
  }
  for (int i = 0; i < K->m; i++) {              /* out = |C| tmp */
    double s = 0;
    for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) s += fabs(K->Ct.x[k]) * tmp[K->Ct.i[k]];
    out[i] = s;
  }
}

static void abs_apply_w(const cup_polyset *K, const void *Wv, const double *v,
                        double *out, double *tmp) {
  const cholmod_sparse *W = Wv;                 /* n x m, columns = constraints */
  const int *p = W->p, *ri = W->i;
  const double *x = W->x;
  memset(tmp, 0, sizeof(double) * (size_t)K->n);
  for (int i = 0; i < K->m; i++)
    for (int k = p[i]; k < p[i + 1]; k++) tmp[ri[k]] += fabs(x[k]) * v[i];
  for (int i = 0; i < K->m; i++) {
    double s = 0;
    for (int k = p[i]; k < p[i + 1]; k++) s += fabs(x[k]) * tmp[ri[k]];
    out[i] = s;
  }
}

/* A bound started from the last one's vector (revalue, or a set rebuilt
 * with the last one's rows; its largest entry is 1): any positive vector
 * gives a valid bound, and the last one's is nearly the Perron vector of
 * this step's |M| but for the rows that came on since (near 0: their ratio
 * would be huge), hence the floor. On crowds of 10^3 and 10^4 agents, 2
 * iterations from it gave 0.985 to 1.09 times the bound of 6 from the ones
 * vector (median 1.000). */
enum { CW_WARM_ITERS = 2 };
#define CW_WARM_FLOOR 0.25

/* la_max, not fmax (a libm call), with the new value first: a NaN one is
 * passed over, as fmax would. */
static double collatz_wielandt(const cup_polyset *K, abs_apply_fn apply, const void *W,
                               double *v, double *w, double *tmp, int warm) {
  for (int i = 0; i < K->m; i++) v[i] = warm ? la_max(v[i], CW_WARM_FLOOR) : 1.0;
  for (int it = 0; it < (warm ? CW_WARM_ITERS : K->cw_iters); it++) {
    apply(K, W, v, w, tmp);
    double wmax = 0;
    for (int i = 0; i < K->m; i++) wmax = la_max(w[i], wmax);
    if (!(wmax > 0)) return 0;
    for (int i = 0; i < K->m; i++) v[i] = la_max(w[i] / wmax, 1e-12);
  }
  apply(K, W, v, w, tmp);
  double bound = 0;
  for (int i = 0; i < K->m; i++) bound = la_max(w[i] / v[i], bound);
  return bound * (1 + 1e-12);
}

/* work: 2 m + n doubles, or NULL to allocate them. */
static int row_norms_and_lipschitz(cup_polyset *K, double *work, char *errmsg) {
  if (K->m == 0) { K->lip = 0; return CUP_OK; }
  /* a small set's scratch on the stack (a switched run makes a set a configuration) */
  double small[PS_SMALL], *v = work;
  if (!v && !(v = scratch_take(small, sizeof small, sizeof(double) * (2 * (size_t)K->m + (size_t)K->n), 0)))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "polyset: out of memory");
  double *w = v + K->m, *tmp = w + K->m;
  if (K->pkind != CUP_METRIC_SPARSE) {
    for (int i = 0; i < K->m; i++) {
      double s = 0;
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) {
        double c = K->Ct.x[k];
        s += c * c * K->pdinv[K->Ct.i[k]];
      }
      K->rownorm[i] = sqrt(s);
    }
    K->lip = collatz_wielandt(K, abs_apply_diag, NULL, v, w, tmp, work && K->cw_warm);
    if (work) K->cw_warm = 1;
  } else {
    /* W = L^-1 Pi C^T, so that M = W^T W and ||W(:,i)|| = ||c_i||_{P^-1}. */
    cholmod_sparse Ct = {0};
    Ct.nrow = (size_t)K->n; Ct.ncol = (size_t)K->m; Ct.nzmax = (size_t)K->Ct.nnz;
    Ct.p = K->Ct.p; Ct.i = K->Ct.i; Ct.x = K->Ct.x;
    Ct.stype = 0; Ct.itype = CHOLMOD_INT; Ct.xtype = CHOLMOD_REAL;
    Ct.dtype = CHOLMOD_DOUBLE; Ct.sorted = 1; Ct.packed = 1;
    cholmod_sparse *PC = cholmod_spsolve(CHOLMOD_P, K->LP, &Ct, K->cm);
    cholmod_sparse *W = PC ? cholmod_spsolve(CHOLMOD_L, K->LP, PC, K->cm) : NULL;
    cholmod_free_sparse(&PC, K->cm);
    if (!W) {
      if (!work) scratch_free(v, small);
      return fail_fmt(errmsg, CUP_ERR_LINALG, "P: CHOLMOD solve for ||c_i||_{P^-1} failed");
    }
    const int *p = W->p;
    const double *x = W->x;
    for (int i = 0; i < K->m; i++) {
      double s = 0;
      for (int k = p[i]; k < p[i + 1]; k++) s += x[k] * x[k];
      K->rownorm[i] = sqrt(s);
    }
    K->lip = collatz_wielandt(K, abs_apply_w, W, v, w, tmp, 0);
    cholmod_free_sparse(&W, K->cm);
  }
  if (!work) scratch_free(v, small);
  return CUP_OK;
}

void polyset_revalue(cup_polyset *K, double *work) {
  row_norms_and_lipschitz(K, work, NULL);   /* diagonal metric: allocation-free, cannot fail */
}

/* ---- small sets: dense M and P^-1 C^T ------------------------------------------- */

static int dense_setup(cup_polyset *K, char *errmsg) {
  int n = K->n, m = K->m;
  K->Bt = calloc((size_t)n * m + 1 + (size_t)m * m + 1, sizeof(double));   /* Md in its block */
  if (!K->Bt) return fail_fmt(errmsg, CUP_ERR_NOMEM, "polyset: out of memory");
  K->Md = K->Bt + (size_t)n * m + 1;
  for (int i = 0; i < m; i++) {            /* column i of Bt = P^-1 c_i */
    double *b = K->Bt + (size_t)i * n;
    for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) b[K->Ct.i[k]] = K->Ct.x[k];
  }
  if (K->pkind == CUP_METRIC_SPARSE) {
    cholmod_dense B = {0};
    B.nrow = (size_t)n; B.ncol = (size_t)m; B.nzmax = (size_t)n * m; B.d = (size_t)n;
    B.x = K->Bt; B.xtype = CHOLMOD_REAL; B.dtype = CHOLMOD_DOUBLE;
    cholmod_dense *X = cholmod_solve(CHOLMOD_A, K->LP, &B, K->cm);
    if (!X) return fail_fmt(errmsg, CUP_ERR_LINALG, "P: CHOLMOD solve failed");
    memcpy(K->Bt, X->x, sizeof(double) * (size_t)n * m);
    cholmod_free_dense(&X, K->cm);
  } else {
    for (int i = 0; i < m; i++) polyset_metric_solve_diag(K, K->Bt + (size_t)i * n);
  }
  for (int j = 0; j < m; j++)              /* M(:,j) = C Bt(:,j) */
    for (int i = 0; i < m; i++) {
      double s = 0;
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) s += K->Ct.x[k] * K->Bt[(size_t)j * n + K->Ct.i[k]];
      K->Md[i + (size_t)j * m] = s;
    }
  for (int j = 0; j < m; j++)              /* exact symmetry */
    for (int i = j + 1; i < m; i++) {
      double a = 0.5 * (K->Md[i + (size_t)j * m] + K->Md[j + (size_t)i * m]);
      K->Md[i + (size_t)j * m] = K->Md[j + (size_t)i * m] = a;
    }
  /* A backward-stable eigenvalue is within c u ||M||_F of the true one. */
  if (m > 0) {                             /* (A row-major, ev, the workspace: one block) */
    size_t need = (size_t)m * m + 3 * (size_t)m;   /* (on the stack for a small set) */
    double small[PS_SMALL], *A = scratch_take(small, sizeof small, sizeof(double) * need, 0);
    double *ev = A ? A + (size_t)m * m : NULL;
    if (!A) return fail_fmt(errmsg, CUP_ERR_NOMEM, "polyset: out of memory");
    double fro = 0;
    for (int j = 0; j < m; j++)
      for (int i = 0; i < m; i++) {
        double a = K->Md[i + (size_t)j * m];
        A[(size_t)i * m + j] = a;
        fro += a * a;
      }
    int rc = la_dense_symm_eig(A, m, ev, ev + m);
    gsl_vector_view evv = gsl_vector_view_array(ev, (size_t)m);
    double lmax = rc ? INFINITY : gsl_vector_max(&evv.vector);
    double bound = lmax + 16.0 * (m + 1) * DBL_EPSILON * sqrt(fro);
    if (bound < K->lip) K->lip = bound;
    scratch_free(A, small);
  }
  K->dense = 1;
  return CUP_OK;
}

/* A direction d = P^-1 C^T mu with C d > 0 lets any point be pushed into K
 * (x + theta d), which certifies distances on cones and unbounded sets. We
 * look for C d >= ||c_i|| / 2 by FISTA on min 1/2 mu'M mu - r'mu, mu >= 0. */
static void find_interior_direction(cup_polyset *K) {
  int m = K->m, n = K->n;
  if (m == 0 || !(K->lip > 0)) return;
  size_t need = (size_t)5 * m + 2 * (size_t)n;     /* (zeroed; on the stack for a small set) */
  double small[PS_SMALL], *buf = scratch_take(small, sizeof small, sizeof(double) * need, 1);
  if (!buf) return;
  double *mu = buf, *mu_old = mu + m, *yv = mu_old + m, *grad = yv + m, *cd = grad + m;
  double *d = cd + m, *pdv = d + n;
  double t = 1, step = 1.0 / K->lip;
  int found = 0;
  for (int it = 0; it < 5000 && !found; it++) {
    for (int i = 0; i < m; i++) {          /* gradient at yv: M yv - r */
      double s = -K->rownorm[i];
      for (int j = 0; j < m; j++) s += K->Md[i + (size_t)j * m] * yv[j];
      grad[i] = s;
    }
    memcpy(mu_old, mu, sizeof(double) * (size_t)m);
    for (int i = 0; i < m; i++) mu[i] = fmax(0, yv[i] - step * grad[i]);
    double tn = 0.5 * (1 + sqrt(1 + 4 * t * t));
    for (int i = 0; i < m; i++) yv[i] = mu[i] + (t - 1) / tn * (mu[i] - mu_old[i]);
    t = tn;
    if (it % 10 == 9) {
      memset(d, 0, sizeof(double) * (size_t)n);
      for (int i = 0; i < m; i++)
        for (int j = 0; j < n; j++) d[j] += K->Bt[(size_t)i * n + j] * mu[i];
      memset(cd, 0, sizeof(double) * (size_t)m);
      la_sparse_gaxpy(&K->C, d, cd);
      found = 1;
      for (int i = 0; i < m && found; i++)
        if (K->rownorm[i] > 0 && !(cd[i] >= 0.5 * K->rownorm[i])) found = 0;
    }
  }
  if (found) {
    K->rdir = malloc(sizeof(double) * ((size_t)n + (size_t)m));   /* Crdir in its block */
    if (K->rdir) {
      K->Crdir = K->rdir + n;
      memcpy(K->rdir, d, sizeof(double) * (size_t)n);
      memcpy(K->Crdir, cd, sizeof(double) * (size_t)m);
      K->rdir_norm = cup_polyset_norm(K, d);
    }
  }
  (void)pdv;
  scratch_free(buf, small);
}
