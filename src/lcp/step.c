/* step — see step.h. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "step.h"

static void small_init(cup_lcp_step *ls);

int cup_lcp_step_init(cup_lcp_step *ls, const cup_polyset *K, const double *W, double h) {
  return cup_lcp_step_init_bd(ls, K, W, h, NULL, NULL, 1);
}

int cup_lcp_step_init_bd(cup_lcp_step *ls, const cup_polyset *K, const double *W, double h,
                         const double *B, const double *D, double theta) {
  memset(ls, 0, sizeof *ls);
  if (!K->dense) return CUP_ERR_UNSUPPORTED;
  int n = ls->n = K->n, m = ls->m = K->m;
  ls->K = K;
  ls->h = h;
  size_t N = (size_t)n, M = (size_t)m + 1;
  ls->H = calloc(N * M, sizeof(double));
  ls->M = calloc(M * M, sizeof(double));
  ls->s = calloc(M, sizeof(double)); ls->gam = calloc(M, sizeof(double));
  ls->v = calloc(N, sizeof(double));
  ls->tau = calloc(M, sizeof(double)); ls->qs = calloc(M, sizeof(double));
  ls->sv = calloc(M, sizeof(double)); ls->gamv = calloc(M, sizeof(double));
  int fail = cup_lcp_init(&ls->lcp, m);
  if (fail || !ls->H || !ls->M || !ls->s || !ls->gam || !ls->v || !ls->tau || !ls->qs || !ls->sv ||
      !ls->gamv)
    return CUP_ERR_NOMEM;
  if (D) {
    ls->D = malloc(sizeof(double) * M * M);
    ls->geff = calloc(M, sizeof(double));
    ls->drow = calloc(M, 1);
    ls->Hprev = calloc(N * M, sizeof(double));
    ls->xpred = calloc(N, sizeof(double));
    if (!ls->D || !ls->geff || !ls->drow || !ls->Hprev || !ls->xpred || cup_lcp_monotone(&ls->lcp))
      return CUP_ERR_NOMEM;
    memcpy(ls->D, D, sizeof(double) * (size_t)m * m);
    for (int i = 0; i < m; i++)
      for (int j = 0; j < m; j++)
        if (D[i + (size_t)j * m] != 0) ls->drow[i] = ls->drow[j] = 1;
  }
  /* H = h W B with B = P^-1 C^T (the polyset's Bt, exact by P B = C^T), or
   * the B given */
  for (int i = 0; i < m; i++)
    for (int r = 0; r < n; r++) {
      const double *b = B ? B + (size_t)i * n : K->Bt + (size_t)i * n;
      double acc = 0;
      if (W)
        for (int c = 0; c < n; c++) acc += W[r + (size_t)c * n] * b[c];
      else
        acc = b[r];
      int trap = ls->drow && ls->drow[i];
      ls->H[r + (size_t)i * n] = h * (trap ? theta : 1) * acc;
      if (trap) ls->Hprev[r + (size_t)i * n] = h * (1 - theta) * acc;
    }
  for (int j = 0; j < m; j++)                      /* M = C H (+ D) */
    for (int i = 0; i < m; i++) {
      double acc = D ? D[i + (size_t)j * m] : 0;
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) acc += K->Ct.x[k] * ls->H[K->Ct.i[k] + (size_t)j * n];
      ls->M[i + (size_t)j * m] = acc;
    }
  small_init(ls);
  return CUP_OK;
}

void cup_lcp_step_free(cup_lcp_step *ls) {
  free(ls->H); free(ls->M); free(ls->s); free(ls->gam); free(ls->v); free(ls->tau); free(ls->qs);
  free(ls->sv); free(ls->gamv); free(ls->D); free(ls->geff); free(ls->drow); free(ls->Hprev);
  free(ls->xpred);
  cup_lcp_free(&ls->lcp);
  memset(ls, 0, sizeof *ls);
}

double cup_lcp_step_eta(cup_lcp_step *ls, const double *g, const double *z) {
  const cup_polyset *K = ls->K;
  int n = ls->n, m = ls->m;
  double worst = INFINITY;
  for (int i = 0; i < m; i++) worst = cup_min(worst, ls->s[i] - ls->gam[i]);
  if (worst >= 0) return 0;
  if (!K->rdir) return INFINITY;
  double t = 0;
  for (int i = 0; i < m; i++)
    if (ls->s[i] - ls->gam[i] < 0) {
      if (!(K->Crdir[i] > 0)) return INFINITY;
      t = cup_max(t, (3 * ls->gam[i] - ls->s[i]) / K->Crdir[i]);
    }
  for (int j = 0; j < n; j++) ls->v[j] = z[j] + t * K->rdir[j];
  return cup_slack(K, g, ls->v, ls->sv, ls->gamv) >= 0 ? t * K->rdir_norm * (1 + 8 * DBL_EPSILON)
                                                        : INFINITY;
}

void cup_lcp_step_checkpoint(cup_lcp_step *ls, cup_ckpt *c) {
  cup_ckpt_io(c, ls->lcp.lam, sizeof(double) * (size_t)ls->m);
  cup_ckpt_io(c, ls->lcp.prev, (size_t)ls->m);
  CUP_CKPT_IO(c, ls->lq);
}

void cup_lcp_step_start(cup_lcp_step *ls, const double *x0, const double *g) {
  int m = ls->m, pivots = 0;
  double *lam = ls->lcp.lam;
  cup_zero(lam, m);
  if (!ls->D) return;
  cup_slack(ls->K, g, x0, ls->qs, NULL);          /* q = C x0 + g, M = D */
  if (cup_lemke_solve(&ls->lcp.lemke, ls->D, ls->qs, lam, ls->lcp.w, &pivots) != CUP_OK) cup_zero(lam, m);
  for (int i = 0; i < m; i++)
    if (!ls->drow[i]) lam[i] = 0;
}

/* (m + 2) eps sum_j |A_ij| lambda_j: the rounding of row i of A lambda. */
static double row_rounding(const cup_lcp_step *ls, const double *A, int i) {
  double mag = 0;
  for (int j = 0; j < ls->m; j++) mag += fabs(A[i + (size_t)j * ls->m]) * ls->lcp.lam[j];
  return (ls->m + 2) * DBL_EPSILON * mag;
}

/* With D, a row of w may not depend on z at all (a diode fixed by the
 * other diodes' currents): aim it beyond the rounding of (M lambda)_i too,
 * known only once lambda is; 1 if some tau_i grew. */
static int widen_aim(cup_lcp_step *ls, const double *q) {
  int m = ls->m, more = 0;
  for (int i = 0; i < m; i++) {
    double want = 16 * row_rounding(ls, ls->M, i);
    if (want > ls->tau[i]) {
      ls->tau[i] += want;
      ls->qs[i] = q[i] - ls->tau[i];
      more = 1;
    }
  }
  return more;
}

/* g + D lambda (D != 0), else g itself. */
static const double *effective_offset(cup_lcp_step *ls, const double *g) {
  if (!ls->D) return g;
  int m = ls->m;
  for (int i = 0; i < m; i++) {
    double acc = g[i];
    for (int j = 0; j < m; j++) acc += ls->D[i + (size_t)j * m] * ls->lcp.lam[j];
    ls->geff[i] = acc;
  }
  return ls->geff;
}

static int small_dispatch(cup_lcp_step *ls, const double *g, const double *xf, double *z, double scale,
                          double eps_target, double eta_target, cup_proj_info *info) {
#define CUP_SMALL_CASE(N, M) \
  case (N) * 8 + (M): return cup_small_step(ls, g, xf, z, scale, eps_target, eta_target, info, N, M);
  switch (ls->n * 8 + ls->m) {
    CUP_SMALL_CASE(1, 1) CUP_SMALL_CASE(2, 1) CUP_SMALL_CASE(3, 1) CUP_SMALL_CASE(4, 1)
    CUP_SMALL_CASE(1, 2) CUP_SMALL_CASE(2, 2) CUP_SMALL_CASE(3, 2) CUP_SMALL_CASE(4, 2)
  }
#undef CUP_SMALL_CASE
  return 0;
}

/* The dense rows of a small set without D; small stays 0 otherwise (or
 * where a row repeats a column, whose sparse sum would round differently). */
static void small_init(cup_lcp_step *ls) {
  const cup_polyset *K = ls->K;
  if (ls->D || ls->n > CUP_STEP_SMALL_N || ls->m > CUP_STEP_SMALL_M || ls->m < 1) return;
  for (int i = 0; i < ls->m; i++) {
    for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) {
      if (k > K->Ct.p[i] && K->Ct.i[k] <= K->Ct.i[k - 1]) return;
      ls->Ccol[K->Ct.i[k]][i] = K->Ct.x[k];
    }
    ls->rowgam[i] = K->rowgam[i];
    for (int r = 0; r < ls->n; r++) ls->Hcol[i][r >> 1][r & 1] = ls->H[r + (size_t)i * ls->n];
  }
  if (ls->m == 2) ls->det = ls->M[0] * ls->M[3] - ls->M[2] * ls->M[1];
  ls->small = 1;
}

int cup_lcp_step_solve(cup_lcp_step *ls, const double *g, const double *xf, double *z,
                       double scale, double eps_target, double eta_target, cup_proj_info *info) {
  if (ls->small && eps_target >= 0 && small_dispatch(ls, g, xf, z, scale, eps_target, eta_target, info))
    return info->status;
  const cup_polyset *K = ls->K;
  int n = ls->n, m = ls->m;
  double *lam = ls->lcp.lam;
  *info = (cup_proj_info){0};
  info->eps_target = eps_target < 0 ? 1e-12 * scale * scale : eps_target;
  info->eta_target = eta_target;
  info->method = CUP_PROJ_ACTIVESET;
  if (ls->D) {                                    /* the trapezoid's old half: h (1 - theta) W B zeta_k */
    cup_copy(ls->xpred, xf, n);
    for (int i = 0; i < m; i++)
      if (lam[i] != 0)
        for (int r = 0; r < n; r++) ls->xpred[r] += ls->Hprev[r + (size_t)i * n] * lam[i];
    xf = ls->xpred;
  }
  double probe = 0;                               /* NaN iff some entry is NaN or Inf */
  for (int j = 0; j < n; j++) probe += 0 * xf[j];
  if (isnan(probe)) return info->status = CUP_ERR_NONFINITE;
  double *q = ls->s;                              /* q = C x_free + g */
  cup_slack(K, g, xf, q, ls->gam);
  info->scale = scale;
  double qmin = INFINITY;
  for (int i = 0; i < m; i++) qmin = cup_min(qmin, q[i]);
  if (qmin >= 0) {                                /* the free point is in K: lambda = 0 */
    cup_copy(z, xf, n);
    cup_zero(lam, m);
    ls->lq = 0;
    info->skipped = 1;
    info->eta_cert = cup_lcp_step_eta(ls, g, z);
    return info->status = info->eta_cert <= eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  }
  /* Aim the rows at slack tau = 16 gam (K shrunk by a few ulps): then z is
   * certainly in K and certifies itself, as the projector's dense path does.
   * A set without interior makes the shrunk problem unsolvable: then solve
   * the exact one. Each try is warm-started, then retried cold. */
  double *tau = ls->tau, *qs = ls->qs;
  for (int i = 0; i < m; i++) {
    tau[i] = 16 * ls->gam[i] + DBL_MIN;
    qs[i] = q[i] - tau[i];
  }
  int pivots = 0, st = CUP_ERR_LINALG, aimed = 0;
  for (int aim = 1; aim >= 0 && st == CUP_ERR_LINALG; aim--) {
    if (!aim) cup_zero(tau, m);
    st = cup_lcp_solve(&ls->lcp, ls->M, aim ? qs : q, &pivots);
    aimed = aim && !st;
  }
  if (aimed && ls->D && widen_aim(ls, q) && cup_lcp_solve(&ls->lcp, ls->M, qs, &pivots) != CUP_OK) {
    cup_zero(tau, m);
    st = cup_lcp_solve(&ls->lcp, ls->M, q, &pivots);
  }
  info->iterations = pivots + 1;
  if (st) return info->status = st;
  double lq = 0;
  for (int i = 0; i < m; i++) {
    lam[i] = cup_max(lam[i], 0);
    lq += lam[i] * q[i];
  }
  ls->lq = lq;
  cup_copy(z, xf, n);
  for (int i = 0; i < m; i++) {
    if (lam[i] == 0) continue;
    for (int r = 0; r < n; r++) z[r] += ls->H[r + (size_t)i * n] * lam[i];
  }
  /* certificates from the slack of z itself; with D, in K shifted by D lambda */
  g = effective_offset(ls, g);
  cup_slack(K, g, z, ls->s, ls->gam);
  for (int i = 0; ls->D && i < m; i++) ls->gam[i] += row_rounding(ls, ls->D, i);
  double gap = 0, viol = 0;
  int active = 0;
  for (int i = 0; i < m; i++) {
    gap += 2 * ls->h * lam[i] * (ls->s[i] + ls->gam[i]);   /* impulse mu = h lambda */
    viol = cup_max(viol, -ls->s[i]);
    active += lam[i] > 0;
  }
  info->active = active;
  info->violation = viol;
  info->eps_cert = isnan(gap) ? NAN : cup_max(gap, 0);
  if (eps_target < 0) {
    /* exact: the active slacks are zero up to the rounding of forming
     * z = xf + H lambda and its slack: rowgam_i (|g_i| + |c_i| (|xf| + |H| lambda)),
     * with a factor 2 for the LU residual of lambda itself */
    double *zmag = ls->v, floor = 0;
    for (int r = 0; r < n; r++) zmag[r] = fabs(xf[r]);
    for (int i = 0; i < m; i++)
      if (lam[i] > 0)
        for (int r = 0; r < n; r++) zmag[r] += fabs(ls->H[r + (size_t)i * n]) * lam[i];
    for (int i = 0; i < m; i++) {
      if (!(lam[i] > 0)) continue;
      double mag = fabs(g[i]);
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) mag += fabs(K->Ct.x[k]) * zmag[K->Ct.i[k]];
      double lcp_round = ls->D ? row_rounding(ls, ls->M, i) : 0;   /* with D: the LCP's own */
      floor += 2 * ls->h * lam[i] * (ls->gam[i] + 2 * K->rowgam[i] * mag + tau[i] + lcp_round);
    }
    info->eps_target = eps_target = cup_max(1e-12 * scale * scale, floor);
  }
  info->eta_cert = cup_lcp_step_eta(ls, g, z);
  return info->status = info->eps_cert <= eps_target && info->eta_cert <= eta_target
                            ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
}

/* step.h's cup_small_pass until no index flips */
int cup_small_murty_loop(unsigned *actp, const double *M, double det, double q0, double q1, double tol_w,
                         cup_v2d *lam, int *pivots, int m) {
  unsigned act = *actp;
  for (int it = 0; it < 16 * m + 64; it++) {
    double l0, l1;
    int flip = cup_small_pass(act, M, det, q0, q1, tol_w, &l0, &l1, m);
    if (flip == -2) return 1;
    if (flip < 0) {
      *lam = (cup_v2d){l0, l1};
      *actp = act;
      return 0;
    }
    act ^= 1u << flip;
    (*pivots)++;
  }
  return 1;
}

