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
 * and min L >= L(z) - ||grad L(z)||^2 / (4 lambda_min(P)) at any z. */
#include <float.h>
#include <math.h>
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

int cup_ellipsoid_project(const cup_set *S, const double *c, double r, const double *x, double *z,
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
  cup_copy(xs, x, n);
  if (q <= r * r) {                         /* inside to the raw test: z = x */
    if (z != x) cup_copy(z, x, n);
    info->skipped = 1;
  } else {
    for (int i = 0; i < n; i++) w[i] = cup_dot(S->VtP + (size_t)i * n, v, n);   /* y */
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
  cup_metric_norm_bounds(K, v, NULL, &vz_hi);
  info->eta_cert = qz_hi <= r * r ? 0 : (1 - r / sqrt(qz_hi) * (1 - 4 * U)) * vz_hi;
  for (int j = 0; j < n; j++) w[j] = z[j] - xs[j];
  double zx_lo, zx_hi, zx = cup_metric_norm_bounds(K, w, &zx_lo, &zx_hi);
  if (info->skipped) {
    info->eps_cert = 0;
    info->dual_value = 0;
  } else if (r == 0) {                      /* the set {c}: d(x) = ||x - c||_P */
    info->dual_value = zx_lo * zx_lo;
    info->eps_cert = zx_hi * zx_hi - zx_lo * zx_lo;
  } else {
    /* weak duality at mu: L(z) less the gradient correction and rounding */
    double mu = info->dual_value;
    cup_metric_apply(K, w, xs);             /* xs <- P (z - x): x is no longer needed */
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
