/* Exact projection for small sets (m <= 64): an active-set method on the dual
 *   min_{lambda >= 0}  1/2 lambda' M lambda + lambda' b,  M = C P^-1 C^T,
 * b = C x + g, with a dense M and cached pivoted Cholesky factors of M_FF;
 * the sparse path is in newton.c. The dense path falls back to FISTA
 * (which also detects an empty K) and restarts from its support, so the
 * method always ends certified or with the bounds reached. */
#include <float.h>
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "certify.h"
#include "activeset.h"
#include "firstorder.h"

#define U DBL_EPSILON

/* Row tolerances for entering the active set: rounding of b plus a tiny
 * scale-relative margin, so degenerate rows do not flip back and forth. */
static void entry_tolerances(cup_projector *p, double S, double *tolA) {
  for (int i = 0; i < p->m; i++) tolA[i] = 4 * p->gam[i] + 1e-14 * S * p->K->rownorm[i];
}

/* ---- dense (small sets) ------------------------------------------------------- */

static dense_fact *dense_factor(cup_projector *p, uint64_t mask) {
  const cup_polyset *K = p->K;
  int m = p->m;
  dense_fact *f = NULL, *lru = &p->cache[0];
  for (int c = 0; c < CUP_DENSE_CACHE; c++) {
    if (p->cache[c].mask == mask) { f = &p->cache[c]; break; }
    if (p->cache[c].stamp < lru->stamp) lru = &p->cache[c];
  }
  if (!f) {
    f = lru;
    f->mask = mask;
    int k = 0;
    for (int i = 0; i < m; i++)
      if (mask >> i & 1) f->idx[k++] = i;
    f->k = k;
    for (int b = 0; b < k; b++)
      for (int a = 0; a < k; a++) f->l[a + b * k] = K->Md[f->idx[a] + (size_t)f->idx[b] * m];
    f->rank = cup_dense_pchol(f->l, k, f->perm, 1e-13);
  }
  f->stamp = ++p->stamp;
  return f;
}

static uint64_t mask_of(const unsigned char *act, int m) {
  uint64_t mask = 0;
  for (int i = 0; i < m; i++)
    if (act[i]) mask |= (uint64_t)1 << i;
  return mask;
}

/* lambda on A from M_AA lambda_A = rhs_A (rhs indexed by row), 0 elsewhere. */
static void dense_solve(cup_projector *p, uint64_t mask, const double *rhs, double *lam) {
  int m = p->m;
  memset(lam, 0, sizeof(double) * (size_t)m);
  if (!mask) return;
  dense_fact *f = dense_factor(p, mask);
  double *r = p->dwork, *sol = r + m, *w = sol + m;
  for (int a = 0; a < f->k; a++) r[a] = rhs[f->idx[a]];
  cup_dense_pchol_solve(f->l, f->k, f->rank, f->perm, r, sol, w);
  for (int a = 0; a < f->k; a++) lam[f->idx[a]] = sol[a];
}

/* Primal active-set method on the dual  min 1/2 l'M l + b'l, l >= 0, over
 * the rows flagged in `rows` (others ignored). The working set F stays
 * linearly independent, so each subproblem M_FF l_F = -b_F is nonsingular:
 *  - move from l toward the subproblem solution, stopping where a
 *    component reaches 0 (that row leaves F);
 *  - at a subproblem optimum, the row j with the most negative scaled slack
 *    s_j = (M l + b)_j enters; if c_j depends on the rows of F
 *    (c_j = sum alpha_i c_i), the exchange direction d = e_j - alpha keeps
 *    M d = 0 and lowers the objective at rate s_j: step until some l_i with
 *    alpha_i > 0 reaches 0 and swap i for j. If no alpha_i > 0, d >= 0 is an
 *    exact Farkas ray (C^T d = 0, g^T d = s_j < 0): K is empty.
 * The objective never increases, which rules out cycling except on ties.
 * Returns 1 optimal, 0 iteration limit, -1 empty (ray in p->dwork + 4m). */
static int dual_activeset_dense(cup_projector *p, const double *b, const unsigned char *rows,
                                unsigned char *F, double *lam, const double *tolA) {
  const cup_polyset *K = p->K;
  int m = p->m;
  const double *Md = K->Md;
  double *sol = p->wm, *sl = p->wm2;
  double *rhs = p->dwork + 3 * (size_t)m, *alpha = p->dwork + 4 * (size_t)m;
  /* keep F independent: drop rows beyond the numerical rank */
  uint64_t mask = mask_of(F, m);
  if (mask) {
    dense_fact *f = dense_factor(p, mask);
    for (int a = f->rank; a < f->k; a++) {
      int i = f->idx[f->perm[a]];
      F[i] = 0;
      lam[i] = 0;
    }
    mask = mask_of(F, m);
  }
  for (int it = 0; it < 4 * m + 20; it++) {
    p->iters++;
    for (int i = 0; i < m; i++) rhs[i] = -b[i];
    dense_solve(p, mask, rhs, sol);              /* subproblem optimum on F */
    double t = 1;
    int leave = -1;
    for (int i = 0; i < m; i++)
      if (F[i] && sol[i] < 0) {
        double ti = lam[i] / (lam[i] - sol[i]);
        if (ti < t || (ti == t && leave >= 0 && i < leave)) { t = ti; leave = i; }
      }
    for (int i = 0; i < m; i++) if (F[i]) lam[i] += t * (sol[i] - lam[i]);
    if (leave >= 0) {                             /* blocked: that row leaves F */
      lam[leave] = 0;
      F[leave] = 0;
      mask &= ~((uint64_t)1 << leave);
      continue;
    }
    int enter = -1;
    double worst = 0;
    for (int i = 0; i < m; i++) {
      double si = b[i];
      for (int j = 0; j < m; j++) if (F[j]) si += Md[i + (size_t)j * m] * lam[j];
      sl[i] = si;
      if (F[i] || (rows && !rows[i]) || !(K->rownorm[i] > 0) || !(si < -tolA[i])) continue;
      double sc = si / K->rownorm[i];
      if (sc < worst) { worst = sc; enter = i; }
    }
    if (enter < 0) return 1;
    /* dependence of c_enter on the rows of F: alpha = M_FF^-1 M_F,enter */
    double rho = Md[enter + (size_t)enter * m];
    if (mask) {
      for (int i = 0; i < m; i++) rhs[i] = F[i] ? Md[i + (size_t)enter * m] : 0;
      dense_solve(p, mask, rhs, alpha);
      for (int i = 0; i < m; i++) if (F[i]) rho -= Md[i + (size_t)enter * m] * alpha[i];
    }
    if (rho > 1e3 * DBL_EPSILON * Md[enter + (size_t)enter * m]) {
      F[enter] = 1;                               /* independent: enters with l = 0 */
      mask |= (uint64_t)1 << enter;
      continue;
    }
    double tx = INFINITY;
    int out = -1;
    for (int i = 0; i < m; i++)
      if (F[i] && alpha[i] > 0) {
        double ti = lam[i] / alpha[i];
        if (ti < tx || (ti == tx && i < out)) { tx = ti; out = i; }
      }
    if (out < 0) {                                /* Farkas ray: e_enter - alpha >= 0 */
      for (int i = 0; i < m; i++) alpha[i] = F[i] ? -alpha[i] : 0;
      alpha[enter] = 1;
      return -1;
    }
    for (int i = 0; i < m; i++) if (F[i]) lam[i] -= tx * alpha[i];
    lam[enter] = tx;
    lam[out] = 0;
    F[out] = 0;
    F[enter] = 1;
    mask = (mask & ~((uint64_t)1 << out)) | ((uint64_t)1 << enter);
  }
  return 0;
}

/* Iterative refinement on A with the primal residual: s_A(z) computed from
 * z = x + P^-1 C^T lambda is accurate to rounding even when M_AA is
 * ill-conditioned (thin wedges square the conditioning of C_A), so
 * M_AA dlam = tau_A - s_A(z) restores z to working accuracy in a step or
 * two (tau: the slack targets, or 0). */
static int refine_dense(cup_projector *p, const double *x, const double *tau) {
  int m = p->m;
  uint64_t mask = mask_of(p->act, m);
  if (!mask) return 0;
  double *rhs = p->wm, *dl = p->wm2;
  for (int step = 0; step < 3; step++) {
    cup_eval_primal(p, x, p->g, p->lam, p->y, p->s, p->gam);
    int small = 1, nonneg = 1;
    for (int i = 0; i < m; i++) {
      double target = tau ? tau[i] : 0;
      rhs[i] = p->act[i] ? target - p->s[i] : 0;
      if (p->act[i] && fabs(p->s[i] - target) > 2 * p->gam[i]) small = 0;
      nonneg &= p->lam[i] >= 0;
    }
    if (small) return nonneg;              /* y, s, gam are those of lam */
    dense_solve(p, mask, rhs, dl);
    for (int i = 0; i < m; i++) p->lam[i] += dl[i];
  }
  return 0;
}

/* An inward anchor: the P-nearest point w to z with slack >= 16 gam on the
 * rows that are active or nearly so (the same dual active-set solver on
 * b' = s(z) - 16 gam over those rows), then one refinement of its slack. */
static void inward_dense(cup_projector *p) {
  const cup_polyset *K = p->K;
  int m = p->m, n = p->n;
  unsigned char *a2 = p->act2;
  int any = 0;
  for (int i = 0; i < m; i++) {
    a2[i] = K->rownorm[i] > 0 && (p->act[i] || p->s[i] < 4 * p->gam[i]);
    any |= a2[i];
  }
  if (!any) return;
  double *bp = p->sv, *mu = p->s2, *tol = p->s_inward;   /* free at this point */
  unsigned char *F2 = (unsigned char *)p->iwm;
  for (int i = 0; i < m; i++) {
    bp[i] = p->s[i] - (16 * p->gam[i] + DBL_MIN);
    tol[i] = 0;
    mu[i] = 0;
    F2[i] = a2[i] && p->act[i];
  }
  if (dual_activeset_dense(p, bp, a2, F2, mu, tol) != 1) return;
  memcpy(p->inward, p->y, sizeof(double) * (size_t)n);
  for (int i = 0; i < m; i++) {
    if (mu[i] == 0) continue;
    const double *bt = K->Bt + (size_t)i * n;
    for (int j = 0; j < n; j++) p->inward[j] += bt[j] * mu[i];
  }
  p->has_inward = 1;
}

/* Clip lambda, recover z (unless y, s, gam already belong to lambda >= 0),
 * certify. */
static int finish(cup_projector *p, const double *x, cup_proj_info *info,
                  void (*inward)(cup_projector *), int evaluated) {
  if (!evaluated) {
    for (int i = 0; i < p->m; i++) p->lam[i] = cup_max(p->lam[i], 0);
    cup_eval_primal(p, x, p->g, p->lam, p->y, p->s, p->gam);
  }
  p->has_inward = 0;
  p->make_inward = inward;
  int ok = cup_certify(p, x, p->lam, p->y, info);
  p->make_inward = NULL;
  return ok;
}

int cup_proj_dense_activeset(cup_projector *p, const double *x, cup_proj_info *info) {
  int m = p->m;
  info->method = CUP_PROJ_ACTIVESET;
  double *tolA = p->wm3;
  entry_tolerances(p, info->scale, tolA);
  /* warm start: the previous support, from lambda = 0 (always feasible) */
  for (int i = 0; i < m; i++) {
    p->act[i] = p->opt.warm_start && p->lam_warm[i] > 0;
    p->lam[i] = 0;
  }
  /* First aim the active rows' slack at tau = 16 gam (the projection onto
   * K shrunk by a few ulps): then the answer is certainly feasible and
   * certifies itself. A set without interior makes the shrunk problem
   * infeasible: then solve the exact one. */
  double *bs = p->sv, *tau = p->s_inward;
  for (int i = 0; i < m; i++) {
    tau[i] = 16 * p->gam[i] + DBL_MIN;
    bs[i] = p->b[i] - tau[i];
  }
  int st = dual_activeset_dense(p, bs, NULL, p->act, p->lam, tolA);
  if (st == 1 && finish(p, x, info, inward_dense, refine_dense(p, x, tau))) return CUP_OK;
  for (int i = 0; i < m; i++) p->lam[i] = 0;
  st = dual_activeset_dense(p, p->b, NULL, p->act, p->lam, tolA);
  if (st < 0 && cup_farkas_test(p, p->dwork + 4 * (size_t)m, info)) return CUP_ERR_EMPTY_SET;
  if (st == 1) {
    if (finish(p, x, info, inward_dense, refine_dense(p, x, NULL))) return CUP_OK;
    /* The exact optimum, certified only to what rounding allows (a set
     * without interior, or a thin wedge): iterating cannot do better. */
    return CUP_WARN_NOT_CERTIFIED;
  }
  /* Ties, rounding or an unconvincing Farkas ray: alternate FISTA bursts
   * (which detect emptiness) with active-set restarts from FISTA's support. */
  for (int burst = 32; p->iters < p->opt.max_iter; burst *= 2) {
    if (burst > 32) memcpy(p->lam, p->lam_fista, sizeof(double) * (size_t)m);
    int fst = cup_proj_firstorder(p, x, 1, burst, info);
    if (fst != CUP_WARN_NOT_CERTIFIED) { info->method = CUP_PROJ_FISTA; return fst; }
    memcpy(p->lam_fista, p->lam, sizeof(double) * (size_t)m);
    memcpy(p->wm4, p->lam, sizeof(double) * (size_t)m);   /* keep FISTA's answer */
    for (int i = 0; i < m; i++) { p->act[i] = p->lam[i] > 0; p->lam[i] = 0; }
    entry_tolerances(p, info->scale, tolA);
    if (dual_activeset_dense(p, p->b, NULL, p->act, p->lam, tolA) == 1 &&
        finish(p, x, info, inward_dense, refine_dense(p, x, NULL)))
      return CUP_OK;
    memcpy(p->lam, p->wm4, sizeof(double) * (size_t)m);
  }
  finish(p, x, info, NULL, 0);
  return CUP_WARN_NOT_CERTIFIED;
}

