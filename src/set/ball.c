/* ball — closed-form projections onto a ball {||x - c||_P <= r} and a
 * half-space {a^T x + b >= 0} in the P-metric, certified like the
 * polyset's: the answer is aimed a few ulps inside, so that it is
 * certainly in the set (eta = 0), and eps is the excess of ||x - z||_P^2,
 * bounded above, over a lower bound on d(x)^2 that allows for rounding.
 * The kinds ball and halfspace (set_impl.h's set_kind) end the file. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include "catchup.h"
#include "set_impl.h"

#define U DBL_EPSILON

static int settle(cup_proj_info *info) {
  info->status = info->eps_cert <= info->eps_target && info->eta_cert <= info->eta_target
                     ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  return info->status;
}

/* x already in the set (to the raw test): z = x exactly, eps = 0. */
static int keep_x(const double *x, double *z, int n, double eta, cup_proj_info *info) {
  if (z != x) la_copy(z, x, n);
  info->skipped = 1;
  info->eps_cert = 0;
  info->eta_cert = eta;
  info->dual_value = 0;
  return settle(info);
}

int ball_project(const cup_set *S, const double *c, double r, const double *x, double *z,
                 double *work, cup_proj_info *info) {
  const cup_polyset *K = S->K;
  int n = S->n;
  info->method = CUP_PROJ_AUTO;
  if (!(r >= 0)) return info->status = CUP_ERR_EMPTY_SET;
  double *v = work, *xs = work + n, *w = work + 2 * (size_t)n;
  for (int j = 0; j < n; j++) v[j] = x[j] - c[j];
  double lo, hi, d = polyset_metric_norm_bounds(K, v, &lo, &hi);
  if (!isfinite(d)) return info->status = CUP_ERR_NONFINITE;
  info->violation = fmax(0, d - r);
  if (d <= r) return keep_x(x, z, n, fmax(0, hi - r), info);
  la_copy(xs, x, n);                       /* z may alias x */
  double s = r * (1 - 4 * (n + 8) * U) / d;
  for (int j = 0; j < n; j++) z[j] = c[j] + s * v[j];
  double zc = polyset_metric_dist_hi(K, z, c, NULL, w), xz = polyset_metric_dist_hi(K, xs, z, NULL, w);
  double dlo = fmax(0, lo - r);             /* d(x) = ||x - c||_P - r exactly */
  info->active = 1;
  info->iterations = 1;
  info->eta_cert = zc <= r ? 0 : zc - r;
  info->dual_value = dlo * dlo;
  info->eps_cert = fmax(0, xz * xz - dlo * dlo);
  return settle(info);
}

int halfspace_project(const cup_set *S, const double *g, const double *x, double *z,
                      double *work, cup_proj_info *info) {
  const cup_polyset *K = S->K;
  int n = S->n;
  info->method = CUP_PROJ_AUTO;
  double s, gam, s2, gam2;
  double a = K->rownorm[0], arel = (K->rownnz[0] + 4) * U;
  if (!(a > 0)) {                           /* 0 >= -b: everything, or nothing */
    if (g[0] >= 0) return keep_x(x, z, n, 0, info);
    info->farkas_gap = g[0];
    return info->status = CUP_ERR_EMPTY_SET;
  }
  double *xs = work, *w = work + n;
  polyset_slack(K, g, x, &s, &gam);
  if (!isfinite(s)) return info->status = CUP_ERR_NONFINITE;
  info->violation = fmax(0, -s);
  if (s >= 0) return keep_x(x, z, n, s - gam >= 0 ? 0 : (gam - s) / (a * (1 - arel)), info);
  la_copy(xs, x, n);
  /* aim at slack 16 gam: certainly inside after the rounding of the step */
  double lam = (16 * gam + DBL_MIN - s) / (a * a);
  for (int j = 0; j < n; j++) z[j] = xs[j] + lam * S->pa[j];
  polyset_slack(K, g, z, &s2, &gam2);
  double xz = polyset_metric_dist_hi(K, xs, z, NULL, w);
  double dlo = fmax(0, (-s - gam) / (a * (1 + arel)));   /* d(x) = -(a^T x + b) / ||a||_{P^-1} */
  info->active = 1;
  info->iterations = 1;
  info->eta_cert = s2 - gam2 >= 0 ? 0 : (gam2 - s2) / (a * (1 - arel));
  info->dual_value = dlo * dlo;
  info->eps_cert = fmax(0, xz * xz - dlo * dlo);
  return settle(info);
}

/* P^-1 a for the half-space's step. */
static int halfspace_setup(cup_set *S, const cup_set_desc *d, char *errmsg) {
  (void)d;
  const cup_polyset *K = S->K;
  int n = S->n;
  S->pa = calloc((size_t)n, sizeof(double));
  double *w = calloc((size_t)n, sizeof(double));
  if (!S->pa || !w) { free(w); return fail_fmt(errmsg, CUP_ERR_NOMEM, "set halfspace: out of memory"); }
  for (int k = K->Ct.p[0]; k < K->Ct.p[1]; k++) S->pa[K->Ct.i[k]] = K->Ct.x[k];
  if (K->pkind == CUP_METRIC_SPARSE) la_simplicial_solve(K->LP, S->pa, w);
  else polyset_metric_solve_diag(K, S->pa);
  free(w);
  return CUP_OK;
}

const set_kind set_kind_ball = {.ball = 1};
const set_kind set_kind_halfspace = {.rows = 1, .setup = halfspace_setup};
