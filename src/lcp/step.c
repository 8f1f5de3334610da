/* step — see step.h. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "step.h"

int cup_lcp_step_init(cup_lcp_step *th, const cup_polyset *K, const double *W, double h,
                      char *errmsg) {
  memset(th, 0, sizeof *th);
  int n = th->n = K->n, m = th->m = K->m;
  th->K = K;
  th->h = h;
  if (!K->dense)
    return cup_fail(errmsg, CUP_ERR_UNSUPPORTED,
                    "theta scheme: %d rows and %d states exceed the dense limits (%d rows, %d states); "
                    "use the explicit, implicit or exponential scheme", m, n, CUP_DENSE_MAX_ROWS,
                    CUP_DENSE_MAX_DIM);
  size_t N = (size_t)n, M = (size_t)m + 1;
  th->H = calloc(N * M, sizeof(double));
  th->M = calloc(M * M, sizeof(double));
  th->lam = calloc(M, sizeof(double)); th->w = calloc(M, sizeof(double));
  th->rhs = calloc(M, sizeof(double)); th->sol = calloc(M, sizeof(double));
  th->lu = calloc(M * M, sizeof(double)); th->work = calloc(M + N, sizeof(double));
  th->s = calloc(M, sizeof(double)); th->gam = calloc(M, sizeof(double));
  th->v = calloc(N, sizeof(double));
  th->tau = calloc(M, sizeof(double)); th->qs = calloc(M, sizeof(double));
  th->piv = calloc(M, sizeof(int)); th->idx = calloc(M, sizeof(int));
  th->act = calloc(M, 1); th->prev = calloc(M, 1);
  if (!th->H || !th->M || !th->lam || !th->w || !th->rhs || !th->sol || !th->lu || !th->work ||
      !th->s || !th->gam || !th->v || !th->tau || !th->qs || !th->piv || !th->idx || !th->act || !th->prev)
    return cup_fail(errmsg, CUP_ERR_NOMEM, "theta scheme: out of memory");
  /* H = h W B with B = P^-1 C^T (the polyset's Bt, exact by P B = C^T) */
  for (int i = 0; i < m; i++)
    for (int r = 0; r < n; r++) {
      double acc = 0;
      if (W)
        for (int c = 0; c < n; c++) acc += W[r + (size_t)c * n] * K->Bt[(size_t)i * n + c];
      else
        acc = K->Bt[(size_t)i * n + r];
      th->H[r + (size_t)i * n] = h * acc;
    }
  for (int j = 0; j < m; j++)                      /* M = C H */
    for (int i = 0; i < m; i++) {
      double acc = 0;
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) acc += K->Ct.x[k] * th->H[K->Ct.i[k] + (size_t)j * n];
      th->M[i + (size_t)j * m] = acc;
    }
  return CUP_OK;
}

void cup_lcp_step_free(cup_lcp_step *th) {
  free(th->H); free(th->M); free(th->lam); free(th->w); free(th->rhs); free(th->sol);
  free(th->lu); free(th->work); free(th->s); free(th->gam); free(th->v); free(th->piv);
  free(th->idx); free(th->act); free(th->prev); free(th->tau); free(th->qs);
  memset(th, 0, sizeof *th);
}

/* lambda on A from M_AA lambda_A = -q_A (closed form for one or two active
 * rows: Cramer's rule is forward stable for 2 x 2; else LU with partial
 * pivoting, M is not symmetric), w = q + M lambda. Returns nonzero for a
 * singular block. */
static int solve_on(cup_lcp_step *th, const double *q) {
  int m = th->m, k = 0;
  const double *M = th->M;
  for (int i = 0; i < m; i++) if (th->act[i]) th->idx[k++] = i;
  for (int i = 0; i < m; i++) th->lam[i] = 0;
  if (k == 1) {
    int a = th->idx[0];
    double d = M[a + (size_t)a * m];
    if (!(d != 0)) return 1;
    th->lam[a] = -q[a] / d;
  } else if (k == 2) {
    int a = th->idx[0], b = th->idx[1];
    double maa = M[a + (size_t)a * m], mab = M[a + (size_t)b * m];
    double mba = M[b + (size_t)a * m], mbb = M[b + (size_t)b * m];
    double det = maa * mbb - mab * mba;
    if (!(det != 0)) return 1;
    th->lam[a] = (-q[a] * mbb + q[b] * mab) / det;
    th->lam[b] = (-q[b] * maa + q[a] * mba) / det;
  } else if (k) {
    for (int b = 0; b < k; b++) {
      th->rhs[b] = -q[th->idx[b]];
      for (int a = 0; a < k; a++) th->lu[a + (size_t)b * k] = M[th->idx[a] + (size_t)th->idx[b] * m];
    }
    if (cup_dense_lu(th->lu, k, th->piv)) return 1;
    cup_dense_lu_solve(th->lu, k, th->piv, th->rhs, th->work);
    for (int b = 0; b < k; b++) th->lam[th->idx[b]] = th->rhs[b];
  }
  for (int i = 0; i < m; i++) {
    double acc = q[i];
    for (int b = 0; b < k; b++) acc += M[i + (size_t)th->idx[b] * m] * th->lam[th->idx[b]];
    th->w[i] = acc;
  }
  return 0;
}

/* Murty's least-index principal pivoting: finite for a P-matrix. */
static int lcp(cup_lcp_step *th, const double *q, int *pivots) {
  int m = th->m;
  double scale = 0;
  for (int i = 0; i < m; i++) scale = cup_max(scale, fabs(q[i]));
  for (int it = 0; it < 16 * m + 64; it++) {
    if (solve_on(th, q)) return CUP_ERR_LINALG;
    double lmax = 0;
    for (int i = 0; i < m; i++) lmax = cup_max(lmax, fabs(th->lam[i]));
    double tol_l = 64 * DBL_EPSILON * lmax, tol_w = 64 * DBL_EPSILON * scale;
    int flip = -1;
    for (int i = 0; i < m && flip < 0; i++)
      if ((th->act[i] && th->lam[i] < -tol_l) || (!th->act[i] && th->w[i] < -tol_w)) flip = i;
    if (flip < 0) return CUP_OK;
    th->act[flip] = !th->act[flip];
    (*pivots)++;
  }
  return CUP_ERR_LINALG;                          /* cycling: not a P-matrix */
}

/* A certified distance of z to K from its slack s (with rounding bounds
 * gam): 0 when z is certainly in K, else a push along the polyset's
 * direction into K, verified; INFINITY when neither works. */
static double certified_eta(cup_lcp_step *th, const double *g, const double *z) {
  const cup_polyset *K = th->K;
  int n = th->n, m = th->m;
  double worst = INFINITY;
  for (int i = 0; i < m; i++) worst = cup_min(worst, th->s[i] - th->gam[i]);
  if (worst >= 0) return 0;
  if (!K->rdir) return INFINITY;
  double t = 0;
  for (int i = 0; i < m; i++)
    if (th->s[i] - th->gam[i] < 0) {
      if (!(K->Crdir[i] > 0)) return INFINITY;
      t = cup_max(t, (3 * th->gam[i] - th->s[i]) / K->Crdir[i]);
    }
  for (int j = 0; j < n; j++) th->v[j] = z[j] + t * K->rdir[j];
  return cup_slack(K, g, th->v, th->w, th->work) >= 0 ? t * K->rdir_norm * (1 + 8 * DBL_EPSILON)
                                                      : INFINITY;
}

int cup_lcp_step_solve(cup_lcp_step *th, const double *g, const double *xf, double *z,
                       double scale, double eps_target, double eta_target, cup_proj_info *info) {
  const cup_polyset *K = th->K;
  int n = th->n, m = th->m;
  *info = (cup_proj_info){0};
  info->eps_target = eps_target < 0 ? 1e-12 * scale * scale : eps_target;
  info->eta_target = eta_target;
  info->method = CUP_PROJ_ACTIVESET;
  double probe = 0;                               /* NaN iff some entry is NaN or Inf */
  for (int j = 0; j < n; j++) probe += 0 * xf[j];
  if (isnan(probe)) return info->status = CUP_ERR_NONFINITE;
  double *q = th->s;                              /* q = C x_free + g */
  cup_slack(K, g, xf, q, th->gam);
  info->scale = scale;
  double qmin = INFINITY;
  for (int i = 0; i < m; i++) qmin = cup_min(qmin, q[i]);
  if (qmin >= 0) {                                /* the free point is in K: lambda = 0 */
    cup_copy(z, xf, n);
    cup_zero(th->lam, m);
    th->lq = 0;
    info->skipped = 1;
    info->eta_cert = certified_eta(th, g, z);
    return info->status = info->eta_cert <= eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  }
  /* Aim the rows at slack tau = 16 gam (K shrunk by a few ulps): then z is
   * certainly in K and certifies itself, as the projector's dense path does.
   * A set without interior makes the shrunk problem unsolvable: then solve
   * the exact one. Each try is warm-started, then retried cold. */
  double *tau = th->tau, *qs = th->qs;
  for (int i = 0; i < m; i++) {
    tau[i] = 16 * th->gam[i] + DBL_MIN;
    qs[i] = q[i] - tau[i];
  }
  int pivots = 0, st = CUP_ERR_LINALG;
  for (int aim = 1; aim >= 0 && st == CUP_ERR_LINALG; aim--) {
    if (!aim) cup_zero(tau, m);
    memcpy(th->act, th->prev, (size_t)m);         /* warm start: the last active set */
    st = lcp(th, aim ? qs : q, &pivots);
    if (st == CUP_ERR_LINALG) {
      memset(th->act, 0, (size_t)m);
      st = lcp(th, aim ? qs : q, &pivots);
    }
  }
  info->iterations = pivots + 1;
  if (st) return info->status = st;
  memcpy(th->prev, th->act, (size_t)m);
  double lq = 0;
  for (int i = 0; i < m; i++) {
    th->lam[i] = cup_max(th->lam[i], 0);
    lq += th->lam[i] * q[i];
  }
  th->lq = lq;
  cup_copy(z, xf, n);
  for (int i = 0; i < m; i++) {
    if (th->lam[i] == 0) continue;
    for (int r = 0; r < n; r++) z[r] += th->H[r + (size_t)i * n] * th->lam[i];
  }
  /* certificates from the slack of z itself */
  cup_slack(K, g, z, th->s, th->gam);
  double gap = 0, viol = 0;
  int active = 0;
  for (int i = 0; i < m; i++) {
    gap += 2 * th->h * th->lam[i] * (th->s[i] + th->gam[i]);   /* impulse mu = h lambda */
    viol = cup_max(viol, -th->s[i]);
    active += th->lam[i] > 0;
  }
  info->active = active;
  info->violation = viol;
  info->eps_cert = isnan(gap) ? NAN : cup_max(gap, 0);
  if (eps_target < 0) {
    /* exact: the active slacks are zero up to the rounding of forming
     * z = xf + H lambda and its slack: rowgam_i (|g_i| + |c_i| (|xf| + |H| lambda)),
     * with a factor 2 for the LU residual of lambda itself */
    double *zmag = th->v, floor = 0;
    for (int r = 0; r < n; r++) zmag[r] = fabs(xf[r]);
    for (int i = 0; i < m; i++)
      if (th->lam[i] > 0)
        for (int r = 0; r < n; r++) zmag[r] += fabs(th->H[r + (size_t)i * n]) * th->lam[i];
    for (int i = 0; i < m; i++) {
      if (!(th->lam[i] > 0)) continue;
      double mag = fabs(g[i]);
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) mag += fabs(K->Ct.x[k]) * zmag[K->Ct.i[k]];
      floor += 2 * th->h * th->lam[i] * (th->gam[i] + 2 * K->rowgam[i] * mag + tau[i]);
    }
    info->eps_target = eps_target = cup_max(1e-12 * scale * scale, floor);
  }
  info->eta_cert = certified_eta(th, g, z);
  return info->status = info->eps_cert <= eps_target && info->eta_cert <= eta_target
                            ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
}
