/* ellipsoid — the P-metric projection onto {(x - c)^T Q (x - c) <= r^2}.
 *
 * In the basis of the pencil (Q, P) (V^T P V = I, V^T Q V = diag(lam)),
 * x - c = V y and the projection is z = c + V w, w_i = y_i / (1 + mu lam_i),
 * with mu >= 0 the root of sum lam_i w_i^2 = r^2. That sum is the trust
 * region's secular function in disguise (b_i = y_i / sqrt(lam_i),
 * d_i = 1 / lam_i: sum b_i^2 / (mu + d_i)^2), so 1 / sqrt(sum) is concave
 * and increasing in mu and Newton's method on it from mu = 0 climbs to the
 * root without overshooting (More and Sorensen, 1983).
 *
 * Certificates in the original coordinates, so that the eigenbasis's own
 * rounding cannot fool them: eta from q(z) computed with a rounding bound
 * (and a shrink towards c if needed), eps by weak duality: for mu >= 0,
 *     d(x)^2 >= min_z L(z),  L(z) = ||z - x||_P^2 + mu (q(z) - r^2),
 * and min L >= L(z) - ||grad L(z)||^2 / (4 lambda_min(P)) at any z.
 * The kind's checks, its set-up (the eigenbasis) and its table end the file. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include "catchup.h"
#include "set_impl.h"

#define U DBL_EPSILON

/* q(v) = v^T Q v, *abs = |v|^T |Q| |v| for its rounding bound; Qv into qv. */
static double quad_form(const cup_set *S, const double *v, double *qv, double *abs) {
  int n = S->n;
  double q = 0, a = 0;
  for (int i = 0; i < n; i++) {
    double acc = 0, aa = 0;
    for (int j = 0; j < n; j++) {
      double t = S->Qd[i + (size_t)j * n] * v[j];
      acc += t;
      aa += fabs(t);
    }
    qv[i] = acc;
    q += v[i] * acc;
    a += fabs(v[i]) * aa;
  }
  *abs = a;
  return q;
}

/* Newton on psi(mu) = 1/sqrt(N(mu)) - 1/r, N = sum lam_i y_i^2 / (1 + mu lam_i)^2. */
static double secular_root(const cup_set *S, const double *y, double r, int *iters) {
  int n = S->n;
  double mu = 0;
  for (int it = 0; it < 200; it++) {
    double N = 0, dN = 0;
    for (int i = 0; i < n; i++) {
      double l = S->lam[i], f = 1 / (1 + mu * l), t = l * y[i] * y[i] * f * f;
      N += t;
      dN += l * t * f;                      /* -N'/2 */
    }
    double psi = 1 / sqrt(N) - 1 / r;
    *iters = it + 1;
    if (!(psi < 0)) break;                  /* at (or a rounding past) the root */
    double step = -psi * N * sqrt(N) / dN;
    mu += step;
    if (!(step > 4 * U * mu)) break;
  }
  return mu;
}

int ellipsoid_project(const cup_set *S, const double *c, double r, const double *x, double *z,
                      double *work, cup_proj_info *info) {
  const cup_polyset *K = S->K;
  int n = S->n;
  double gq = (2 * n + 8) * U;              /* relative rounding of a quadratic form */
  info->method = CUP_PROJ_AUTO;
  if (!(r >= 0)) return info->status = CUP_ERR_EMPTY_SET;
  double *v = work, *xs = work + n, *w = work + 2 * (size_t)n, *t = work + 3 * (size_t)n;
  for (int j = 0; j < n; j++) v[j] = x[j] - c[j];
  double qa, q = quad_form(S, v, t, &qa);
  if (!isfinite(q)) return info->status = CUP_ERR_NONFINITE;
  info->violation = fmax(0, sqrt(q) - r);
  la_copy(xs, x, n);
  if (q <= r * r) {                         /* inside to the raw test: z = x */
    if (z != x) la_copy(z, x, n);
    info->skipped = 1;
  } else {
    for (int i = 0; i < n; i++) w[i] = la_dot(S->VtP + (size_t)i * n, v, n);   /* y */
    double ra = r * (1 - 4 * gq), mu = ra > 0 ? secular_root(S, w, ra, &info->iterations) : INFINITY;
    for (int i = 0; i < n; i++) w[i] = ra > 0 ? w[i] / (1 + mu * S->lam[i]) : 0;
    for (int j = 0; j < n; j++) {             /* z = c + V w */
      double acc = c[j];
      for (int i = 0; i < n; i++) acc += S->V[j + (size_t)i * n] * w[i];
      z[j] = acc;
    }
    info->active = 1;
    info->dual_value = mu;                  /* replaced by the bound below */
  }
  /* eta: q(z) from above; else shrink towards c until certainly inside */
  for (int j = 0; j < n; j++) v[j] = z[j] - c[j];
  double qz_abs, qz = quad_form(S, v, t, &qz_abs), qz_hi = qz + gq * qz_abs;
  double vz_hi;
  polyset_metric_norm_bounds(K, v, NULL, &vz_hi);
  info->eta_cert = qz_hi <= r * r ? 0 : (1 - r / sqrt(qz_hi) * (1 - 4 * U)) * vz_hi;
  for (int j = 0; j < n; j++) w[j] = z[j] - xs[j];
  double zx_lo, zx_hi, zx = polyset_metric_norm_bounds(K, w, &zx_lo, &zx_hi);
  if (info->skipped) {
    info->eps_cert = 0;
    info->dual_value = 0;
  } else if (r == 0) {                      /* the set {c}: d(x) = ||x - c||_P */
    info->dual_value = zx_lo * zx_lo;
    info->eps_cert = zx_hi * zx_hi - zx_lo * zx_lo;
  } else {
    /* weak duality at mu: L(z) less the gradient correction and rounding */
    double mu = info->dual_value;
    polyset_metric_apply(K, w, xs);             /* xs <- P (z - x): x is no longer needed */
    double g2 = 0;
    for (int j = 0; j < n; j++) {
      double gj = 2 * xs[j] + 2 * mu * t[j];   /* t = Q (z - c) from quad_form */
      g2 += gj * gj;
    }
    double Lz = zx * zx + mu * (qz - r * r);
    double lb = Lz - g2 / (4 * S->pmin) - gq * (zx * zx + mu * (qz_abs + r * r)) - 4 * U * zx * zx;
    info->dual_value = fmax(lb, 0);
    info->eps_cert = fmax(0, zx_hi * zx_hi - info->dual_value);
  }
  info->status = info->eps_cert <= info->eps_target && info->eta_cert <= info->eta_target
                     ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  return info->status;
}

/* ---- the kind: its checks, the eigenbasis, its table --------------------------- */

static int ellipsoid_check(const cup_set_desc *d, char *errmsg) {
  if (d->n > CUP_DENSE_MAX_DIM)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "set ellipsoid: n = %d exceeds the dense limit %d",
                    d->n, CUP_DENSE_MAX_DIM);
  if (!set_present(&d->Q))
    return fail_fmt(errmsg, CUP_ERR_ARG, "set ellipsoid: the shape Q is missing");
  return CUP_OK;
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
  la_sparse Q = {0};
  st = la_sparse_copy(&Q, &d->Q, "Q", n, n, errmsg);
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
    st = fail_fmt(errmsg, CUP_ERR_NOMEM, "set ellipsoid: out of memory");
    goto done;
  }
  for (int j = 0; j < n; j++)
    for (int k = Q.p[j]; k < Q.p[j + 1]; k++) S->Qd[Q.i[k] + (size_t)j * n] = Q.x[k];
  double qmax = 0;
  for (size_t q = 0; q < NN; q++) qmax = fmax(qmax, fabs(S->Qd[q]));
  for (int j = 0; j < n && !st; j++)
    for (int i = j + 1; i < n; i++)
      if (fabs(S->Qd[i + (size_t)j * n] - S->Qd[j + (size_t)i * n]) > 1e-12 * qmax) {
        st = fail_fmt(errmsg, CUP_ERR_NOT_SPD, "set ellipsoid: Q is not symmetric: Q(%d,%d) = %.17g, Q(%d,%d) = %.17g",
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
  if (rc) { st = fail_fmt(errmsg, CUP_ERR_LINALG, "set ellipsoid: the eigenproblem Q v = lam P v failed"); goto done; }
  for (int i = 0; i < n; i++) {
    double l = gsl_vector_get(ev, (size_t)i);
    if (!(l > 0)) { st = fail_fmt(errmsg, CUP_ERR_NOT_SPD, "set ellipsoid: Q is not positive definite (eigenvalue %g)", l); goto done; }
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
  if (!(S->pmin > 0)) st = fail_fmt(errmsg, CUP_ERR_NOT_SPD, "set ellipsoid: no positive lower bound on lambda_min(P)");
done:
  if (w) gsl_eigen_gensymmv_free(w);
  if (evec) gsl_matrix_free(evec);
  if (ev) gsl_vector_free(ev);
  free(Pd); free(A); free(B);
  la_sparse_free(&Q);
  return st;
}

const set_kind set_kind_ellipsoid = {.ball = 1, .check = ellipsoid_check, .setup = ellipsoid_setup};
