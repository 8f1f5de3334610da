/* set — the moving sets of a general sweeping process (catchup/set.h):
 * validation, copies, and the parameters c(t), r(t), g(t) at u(t). The
 * closed-form projections are in ball.c and ellipsoid.c. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include "catchup.h"
#include "set_impl.h"

#define NAME4_(e, v, name, doc) [v] = name,
static const char *const kinds[CUP_SET_COUNT] = {CUP_SET_LIST(NAME4_)};
#undef NAME4_

const char *cup_set_kind_name(int kind) {
  return kind >= 0 && kind < CUP_SET_COUNT ? kinds[kind] : "unknown";
}

int cup_set_kind_parse(const char *name) {
  for (int k = 0; name && k < CUP_SET_COUNT; k++)
    if (!strcmp(name, kinds[k])) return k;
  return -1;
}

int cup_set_dim(const cup_set *S) { return S ? S->n : 0; }
int cup_set_params(const cup_set *S) { return S ? S->p : 0; }
int cup_set_kind_of(const cup_set *S) { return S ? S->kind : -1; }

static int present(const cup_csc *c) { return c->ncol > 0 && c->colptr; }

static int has_rows(int kind) {
  return kind == CUP_SET_POLYSET || kind == CUP_SET_HALFSPACE || kind == CUP_SET_INTERSECTION;
}

static int has_ball(int kind) {
  return kind == CUP_SET_BALL || kind == CUP_SET_ELLIPSOID || kind == CUP_SET_INTERSECTION;
}

void cup_set_free(cup_set **Sp) {
  if (!Sp || !*Sp) return;
  cup_set *S = *Sp;
  if (S->owns_K) cup_polyset_free(&S->K);
  if (S->owns_G) cup_sparse_free(&S->G);
  cup_sparse_free(&S->Gc);
  free(S->center); free(S->gr); free(S->Qd); free(S->V); free(S->VtP); free(S->lam); free(S->pa);
  free(S);
  *Sp = NULL;
}

int cup_set_wrap_polyset(cup_set **out, const cup_polyset *K, const cup_sparse *G, int p,
                         char *errmsg) {
  *out = NULL;
  cup_set *S = calloc(1, sizeof *S);
  if (!S) return cup_fail(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  S->kind = CUP_SET_POLYSET;
  S->n = K->n;
  S->p = p;
  S->K = (cup_polyset *)K;           /* borrowed: never freed or written through S */
  if (G) { S->G = *G; S->has_G = 1; }
  *out = S;
  return CUP_OK;
}

/* ---- validation and copies ---------------------------------------------------- */

static int finite_vector(const double *v, int len, const char *name, char *errmsg) {
  for (int k = 0; v && k < len; k++)
    if (!isfinite(v[k])) return cup_fail(errmsg, CUP_ERR_NONFINITE, "set: %s[%d] is %g", name, k, v[k]);
  return CUP_OK;
}

static int copy_vector(double **dst, const double *src, int len, const char *name, char *errmsg) {
  int st = finite_vector(src, len, name, errmsg);
  if (st) return st;
  *dst = calloc((size_t)len + 1, sizeof(double));
  if (!*dst) return cup_fail(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  if (src) memcpy(*dst, src, sizeof(double) * (size_t)len);
  return CUP_OK;
}

static int check_kind_fields(const cup_set_desc *d, char *errmsg) {
  if ((int)d->kind < 0 || (int)d->kind >= (int)CUP_SET_COUNT)
    return cup_fail(errmsg, CUP_ERR_ARG, "set: unknown kind %d", (int)d->kind);
  const char *name = cup_set_kind_name(d->kind);
  if (d->n < 1 || d->p < 0)
    return cup_fail(errmsg, CUP_ERR_DIM, "set %s: n = %d, p = %d; need n >= 1 and p >= 0", name, d->n, d->p);
  if (has_rows(d->kind) && !present(&d->C))
    return cup_fail(errmsg, CUP_ERR_ARG, "set %s: C is missing", name);
  if (has_rows(d->kind) && (d->C.ncol != d->n || (d->kind == CUP_SET_HALFSPACE && d->C.nrow != 1)))
    return cup_fail(errmsg, CUP_ERR_DIM, "set %s: C is %d x %d, expected %s x %d", name, d->C.nrow,
                    d->C.ncol, d->kind == CUP_SET_HALFSPACE ? "1" : "m", d->n);
  if (d->kind == CUP_SET_ORACLE && !d->oracle)
    return cup_fail(errmsg, CUP_ERR_ARG, "set oracle: the oracle callback is NULL");
  if (d->kind == CUP_SET_STATE_POLYSET && !d->rows)
    return cup_fail(errmsg, CUP_ERR_ARG, "set state-polyset: the rows callback is NULL");
  if (d->kind == CUP_SET_STATE_POLYSET && d->P.kind == CUP_METRIC_SPARSE)
    return cup_fail(errmsg, CUP_ERR_UNSUPPORTED,
                    "set state-polyset: the metric must be the identity or diagonal (the rows' "
                    "dual matrix C P^-1 C^T is refactored in place at every step)");
  if (d->kind == CUP_SET_ELLIPSOID && d->n > CUP_DENSE_MAX_DIM)
    return cup_fail(errmsg, CUP_ERR_UNSUPPORTED, "set ellipsoid: n = %d exceeds the dense limit %d",
                    d->n, CUP_DENSE_MAX_DIM);
  if (d->kind == CUP_SET_ELLIPSOID && !present(&d->Q))
    return cup_fail(errmsg, CUP_ERR_ARG, "set ellipsoid: the shape Q is missing");
  if (has_ball(d->kind) && !isfinite(d->radius))
    return cup_fail(errmsg, CUP_ERR_NONFINITE, "set %s: radius is %g", name, d->radius);
  if (has_ball(d->kind) && !d->gr && !present(&d->Gc) && d->radius < 0)
    return cup_fail(errmsg, CUP_ERR_EMPTY_SET, "set %s: radius = %g < 0: the set is empty", name, d->radius);
  return CUP_OK;
}

/* The rows (or none) and the metric, as a polyset. */
static int make_polyset(cup_set *S, const cup_set_desc *d, char *errmsg) {
  int zero = 0;
  int *cp = calloc((size_t)d->n + 1, sizeof(int));
  if (!cp) return cup_fail(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  cup_csc none = {0, d->n, cp, &zero, NULL};
  int st = cup_polyset_create(&S->K, has_rows(d->kind) ? &d->C : &none,
                              has_rows(d->kind) ? d->F : NULL, &d->P, errmsg);
  free(cp);
  S->owns_K = 1;
  return st;
}

static int copy_motion(cup_set *S, const cup_set_desc *d, char *errmsg) {
  int st = CUP_OK, m = S->K->m;
  if (has_rows(d->kind) && present(&d->G)) {
    if (d->p == 0) return cup_fail(errmsg, CUP_ERR_DIM, "set: G is given but p = 0");
    st = cup_sparse_copy(&S->G, &d->G, "G", m, d->p, errmsg);
    S->has_G = S->owns_G = !st;
  }
  if (st || !has_ball(d->kind)) return st;
  st = copy_vector(&S->center, d->center, d->n, "center", errmsg);
  if (!st && present(&d->Gc)) {
    if (d->p == 0) return cup_fail(errmsg, CUP_ERR_DIM, "set: Gc is given but p = 0");
    st = cup_sparse_copy(&S->Gc, &d->Gc, "Gc", d->n, d->p, errmsg);
    S->has_Gc = !st;
  }
  S->radius = d->radius;
  if (!st && d->gr && d->p > 0) st = copy_vector(&S->gr, d->gr, d->p, "gr", errmsg);
  return st;
}

/* P as a dense column-major matrix. */
static void dense_metric(const cup_polyset *K, double *Pd) {
  int n = K->n;
  memset(Pd, 0, sizeof(double) * (size_t)n * n);
  if (K->pkind != CUP_METRIC_SPARSE) {
    for (int j = 0; j < n; j++) Pd[j + (size_t)j * n] = K->pd[j];
    return;
  }
  for (int j = 0; j < n; j++)
    for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++) Pd[K->Pfull.i[k] + (size_t)j * n] = K->Pfull.x[k];
}

/* lambda_min(P) from below: exact for a diagonal P; for a sparse one the
 * dense eigenvalue less its backward error bound. */
static double metric_min_eig(const cup_polyset *K, const double *Pd, gsl_vector *ev, double *work) {
  int n = K->n;
  if (K->pkind != CUP_METRIC_SPARSE) {
    double m = INFINITY;
    for (int j = 0; j < n; j++) m = fmin(m, K->pd[j]);
    return m;
  }
  gsl_eigen_symm_workspace *w = gsl_eigen_symm_alloc((size_t)n);
  if (!w) return NAN;
  memcpy(work, Pd, sizeof(double) * (size_t)n * n);
  gsl_matrix_view A = gsl_matrix_view_array(work, (size_t)n, (size_t)n);
  double fro = 0;
  for (size_t q = 0; q < (size_t)n * n; q++) fro += Pd[q] * Pd[q];
  int rc = gsl_eigen_symm(&A.matrix, ev, w);
  gsl_eigen_symm_free(w);
  return rc ? NAN : gsl_vector_min(ev) - 16.0 * (n + 1) * DBL_EPSILON * sqrt(fro);
}

/* The generalized eigenbasis of (Q, P): V^T P V = I, V^T Q V = diag(lam). */
static int ellipsoid_setup(cup_set *S, const cup_set_desc *d, char *errmsg) {
  int n = d->n, st = CUP_OK;
  size_t NN = (size_t)n * n;
  cup_sparse Q = {0};
  st = cup_sparse_copy(&Q, &d->Q, "Q", n, n, errmsg);
  if (st) return st;
  S->Qd = calloc(NN, sizeof(double));
  S->V = calloc(NN, sizeof(double));
  S->VtP = calloc(NN, sizeof(double));
  S->lam = calloc((size_t)n, sizeof(double));
  double *Pd = calloc(NN, sizeof(double)), *A = calloc(NN, sizeof(double)), *B = calloc(NN, sizeof(double));
  gsl_vector *ev = gsl_vector_alloc((size_t)n);
  gsl_matrix *evec = gsl_matrix_alloc((size_t)n, (size_t)n);
  gsl_eigen_gensymmv_workspace *w = gsl_eigen_gensymmv_alloc((size_t)n);
  if (!S->Qd || !S->V || !S->VtP || !S->lam || !Pd || !A || !B || !ev || !evec || !w) {
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "set ellipsoid: out of memory");
    goto done;
  }
  for (int j = 0; j < n; j++)
    for (int k = Q.p[j]; k < Q.p[j + 1]; k++) S->Qd[Q.i[k] + (size_t)j * n] = Q.x[k];
  double qmax = 0;
  for (size_t q = 0; q < NN; q++) qmax = fmax(qmax, fabs(S->Qd[q]));
  for (int j = 0; j < n && !st; j++)
    for (int i = j + 1; i < n; i++)
      if (fabs(S->Qd[i + (size_t)j * n] - S->Qd[j + (size_t)i * n]) > 1e-12 * qmax) {
        st = cup_fail(errmsg, CUP_ERR_NOT_SPD, "set ellipsoid: Q is not symmetric: Q(%d,%d) = %.17g, Q(%d,%d) = %.17g",
                      i, j, S->Qd[i + (size_t)j * n], j, i, S->Qd[j + (size_t)i * n]);
        break;
      }
  if (st) goto done;
  dense_metric(S->K, Pd);
  memcpy(A, S->Qd, NN * sizeof(double));
  memcpy(B, Pd, NN * sizeof(double));
  gsl_matrix_view Av = gsl_matrix_view_array(A, (size_t)n, (size_t)n);
  gsl_matrix_view Bv = gsl_matrix_view_array(B, (size_t)n, (size_t)n);
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  int rc = gsl_eigen_gensymmv(&Av.matrix, &Bv.matrix, ev, evec, w);
  gsl_set_error_handler(old);
  if (rc) { st = cup_fail(errmsg, CUP_ERR_LINALG, "set ellipsoid: the eigenproblem Q v = lam P v failed"); goto done; }
  for (int i = 0; i < n; i++) {
    double l = gsl_vector_get(ev, (size_t)i);
    if (!(l > 0)) { st = cup_fail(errmsg, CUP_ERR_NOT_SPD, "set ellipsoid: Q is not positive definite (eigenvalue %g)", l); goto done; }
    S->lam[i] = l;
    double *v = S->V + (size_t)i * n, pvv = 0;          /* column i, normalized in the P-norm */
    for (int r = 0; r < n; r++) v[r] = gsl_matrix_get(evec, (size_t)r, (size_t)i);
    for (int r = 0; r < n; r++)
      for (int c = 0; c < n; c++) pvv += v[r] * Pd[r + (size_t)c * n] * v[c];
    for (int r = 0; r < n; r++) v[r] /= sqrt(pvv);
  }
  for (int i = 0; i < n; i++)                             /* row i of V^T P, stored row-major */
    for (int c = 0; c < n; c++) {
      double acc = 0;
      for (int r = 0; r < n; r++) acc += S->V[r + (size_t)i * n] * Pd[r + (size_t)c * n];
      S->VtP[(size_t)i * n + c] = acc;
    }
  gsl_vector *pev = gsl_vector_alloc((size_t)n);
  old = gsl_set_error_handler_off();
  S->pmin = pev ? metric_min_eig(S->K, Pd, pev, A) : NAN;
  gsl_set_error_handler(old);
  if (pev) gsl_vector_free(pev);
  if (!(S->pmin > 0)) st = cup_fail(errmsg, CUP_ERR_NOT_SPD, "set ellipsoid: no positive lower bound on lambda_min(P)");
done:
  if (w) gsl_eigen_gensymmv_free(w);
  if (evec) gsl_matrix_free(evec);
  if (ev) gsl_vector_free(ev);
  free(Pd); free(A); free(B);
  cup_sparse_free(&Q);
  return st;
}

/* P^-1 a for the half-space's step. */
static int halfspace_setup(cup_set *S, char *errmsg) {
  const cup_polyset *K = S->K;
  int n = S->n;
  S->pa = calloc((size_t)n, sizeof(double));
  double *w = calloc((size_t)n, sizeof(double));
  if (!S->pa || !w) { free(w); return cup_fail(errmsg, CUP_ERR_NOMEM, "set halfspace: out of memory"); }
  for (int k = K->Ct.p[0]; k < K->Ct.p[1]; k++) S->pa[K->Ct.i[k]] = K->Ct.x[k];
  if (K->pkind == CUP_METRIC_SPARSE) cup_simplicial_solve(K->LP, S->pa, w);
  else cup_metric_solve_diag(K, S->pa);
  free(w);
  return CUP_OK;
}

int cup_set_create(cup_set **out, const cup_set_desc *d, char *errmsg) {
  if (!out) return cup_fail(errmsg, CUP_ERR_ARG, "set: output pointer is NULL");
  *out = NULL;
  if (!d) return cup_fail(errmsg, CUP_ERR_ARG, "set: description is NULL");
  int st = check_kind_fields(d, errmsg);
  if (st) return st;
  cup_set *S = calloc(1, sizeof *S);
  if (!S) return cup_fail(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  S->kind = d->kind;
  S->n = d->n;
  S->p = d->p;
  S->oracle = d->oracle;
  S->oracle_ctx = d->oracle_ctx;
  S->rows = d->rows;
  S->rows_ctx = d->rows_ctx;
  st = make_polyset(S, d, errmsg);
  if (!st) st = copy_motion(S, d, errmsg);
  if (!st && d->kind == CUP_SET_ELLIPSOID) st = ellipsoid_setup(S, d, errmsg);
  if (!st && d->kind == CUP_SET_HALFSPACE) st = halfspace_setup(S, errmsg);
  if (st) { cup_set_free(&S); return st; }
  *out = S;
  return CUP_OK;
}

int set_on_recheck(cup_set *S, int (*recheck)(double t, const double *x, const double *z, void *ctx)) {
  if (!S || S->kind != CUP_SET_STATE_POLYSET) return CUP_ERR_ARG;
  S->recheck = recheck;
  return CUP_OK;
}

void cup_set_place(const cup_set *S, const double *u, double *g, double *c, double *r) {
  int use_u = S->p > 0 && u;
  if (g && S->K->m) {
    cup_copy(g, S->K->g0, S->K->m);
    if (S->has_G && use_u) cup_sparse_gaxpy(&S->G, u, g);
  }
  if (c && S->center) {
    cup_copy(c, S->center, S->n);
    if (S->has_Gc && use_u) cup_sparse_gaxpy(&S->Gc, u, c);
  }
  if (r) {
    double rr = S->radius;
    if (S->gr && use_u)
      for (int k = 0; k < S->p; k++) rr += S->gr[k] * u[k];
    *r = rr;
  }
}

double cup_metric_norm_bounds(const cup_polyset *K, const double *v, double *lo, double *hi) {
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

double cup_metric_dist_hi(const cup_polyset *K, const double *a, const double *b, double *lo, double *w) {
  for (int j = 0; j < K->n; j++) w[j] = a[j] - b[j];
  double hi;
  cup_metric_norm_bounds(K, w, lo, &hi);
  return hi;
}
