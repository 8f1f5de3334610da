/* Exact projection for small sets (m <= 64): an active-set method on the dual
 *   min_{lambda >= 0}  1/2 lambda' M lambda + lambda' b,  M = C P^-1 C^T,
 * b = C x + g, with a dense M and cached pivoted Cholesky factors of M_FF;
 * the sparse path is in newton.c. The dense path falls back to FISTA
 * (which also detects an empty K) and restarts from its support, so the
 * method always ends certified or with the bounds reached. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include "catchup.h"
#include "certify.h"
#include "activeset.h"
#include "firstorder.h"

#define U DBL_EPSILON
#define DENSE_CACHE 4

/* A cached dense pivoted Cholesky of M_AA for one active set A (m <= 64). */
typedef struct dense_fact {
  uint64_t mask;      /* the active set; 0 = unused slot */
  int k, rank;        /* |A| and numerical rank */
  int *idx;           /* A's rows, increasing (k) */
  int *perm;          /* pivot order (k) */
  double *l;          /* k x k factor */
  unsigned stamp;     /* for least-recently-used replacement */
} dense_fact;

/* The method's workspace: the factors of the last active sets, the working
 * set, and FISTA's scratch, which its fallback bursts use and the active
 * set borrows between them (fo.wm: a subproblem's solution, fo.wm2: the
 * slack, fo.wm3: the entry tolerances, fo.wm4: FISTA's last answer). */
typedef struct dense_ws {
  fo_ws fo;
  double *lam_fista;    /* FISTA's own iterate across the bursts of a fallback */
  unsigned char *act;   /* the working set */
  int *iwm;             /* m: the inward anchor's working set */
  dense_fact cache[DENSE_CACHE];
  unsigned stamp;
  double *dwork;        /* m*m + 6 m scratch */
} dense_ws;

/* Row tolerances for entering the active set: rounding of b plus a tiny
 * scale-relative margin, so degenerate rows do not flip back and forth. */
static void entry_tolerances(cup_projector *p, double S, double *tolA) {
  for (int i = 0; i < p->m; i++) tolA[i] = 4 * p->gam[i] + 1e-14 * S * p->K->rownorm[i];
}

/* ---- dense (small sets) ------------------------------------------------------- */

static dense_fact *dense_factor(cup_projector *p, dense_ws *w, uint64_t mask) {
  const cup_polyset *K = p->K;
  int m = p->m;
  dense_fact *f = NULL, *lru = &w->cache[0];
  for (int c = 0; c < DENSE_CACHE; c++) {
    if (w->cache[c].mask == mask) { f = &w->cache[c]; break; }
    if (w->cache[c].stamp < lru->stamp) lru = &w->cache[c];
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
    f->rank = la_dense_pchol(f->l, k, f->perm, 1e-13);
  }
  f->stamp = ++w->stamp;
  return f;
}

static uint64_t mask_of(const unsigned char *act, int m) {
  uint64_t mask = 0;
  for (int i = 0; i < m; i++)
    if (act[i]) mask |= (uint64_t)1 << i;
  return mask;
}

/* lambda on A from M_AA lambda_A = rhs_A (rhs indexed by row), 0 elsewhere. */
static void dense_solve(cup_projector *p, dense_ws *ws, uint64_t mask, const double *rhs, double *lam) {
  int m = p->m;
  memset(lam, 0, sizeof(double) * (size_t)m);
  if (!mask) return;
  dense_fact *f = dense_factor(p, ws, mask);
  double *r = ws->dwork, *sol = r + m, *w = sol + m;
  for (int a = 0; a < f->k; a++) r[a] = rhs[f->idx[a]];
  la_dense_pchol_solve(f->l, f->k, f->rank, f->perm, r, sol, w);
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
 * Returns 1 optimal, 0 iteration limit, -1 empty (ray in w->dwork + 4m). */
static int dual_activeset_dense(cup_projector *p, dense_ws *w, const double *b, const unsigned char *rows,
                                unsigned char *F, double *lam, const double *tolA) {
  const cup_polyset *K = p->K;
  int m = p->m;
  const double *Md = K->Md;
  double *sol = w->fo.wm, *sl = w->fo.wm2;
  double *rhs = w->dwork + 3 * (size_t)m, *alpha = w->dwork + 4 * (size_t)m;
  /* keep F independent: drop rows beyond the numerical rank */
  uint64_t mask = mask_of(F, m);
  if (mask) {
    dense_fact *f = dense_factor(p, w, mask);
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
    dense_solve(p, w, mask, rhs, sol);           /* subproblem optimum on F */
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
      dense_solve(p, w, mask, rhs, alpha);
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
static int refine_dense(cup_projector *p, dense_ws *w, const double *x, const double *tau) {
  int m = p->m;
  const unsigned char *act = w->act;
  uint64_t mask = mask_of(act, m);
  if (!mask) return 0;
  double *rhs = w->fo.wm, *dl = w->fo.wm2;
  for (int step = 0; step < 3; step++) {
    certify_eval_primal(p, x, p->g, p->lam, p->y, p->s, p->gam);
    int small = 1, nonneg = 1;
    for (int i = 0; i < m; i++) {
      double target = tau ? tau[i] : 0;
      rhs[i] = act[i] ? target - p->s[i] : 0;
      if (act[i] && fabs(p->s[i] - target) > 2 * p->gam[i]) small = 0;
      nonneg &= p->lam[i] >= 0;
    }
    if (small) return nonneg;              /* y, s, gam are those of lam */
    dense_solve(p, w, mask, rhs, dl);
    for (int i = 0; i < m; i++) p->lam[i] += dl[i];
  }
  return 0;
}

/* An inward anchor: the P-nearest point w to z with slack >= 16 gam on the
 * rows that are active or nearly so (the same dual active-set solver on
 * b' = s(z) - 16 gam over those rows), then one refinement of its slack. */
static void inward_dense(cup_projector *p, void *ws) {
  const cup_polyset *K = p->K;
  dense_ws *w = ws;
  int m = p->m, n = p->n;
  unsigned char *a2 = p->act2;
  int any = 0;
  for (int i = 0; i < m; i++) {
    a2[i] = K->rownorm[i] > 0 && (w->act[i] || p->s[i] < 4 * p->gam[i]);
    any |= a2[i];
  }
  if (!any) return;
  double *bp = p->sv, *mu = p->s2, *tol = p->s_inward;   /* free at this point */
  unsigned char *F2 = (unsigned char *)w->iwm;
  for (int i = 0; i < m; i++) {
    bp[i] = p->s[i] - (16 * p->gam[i] + DBL_MIN);
    tol[i] = 0;
    mu[i] = 0;
    F2[i] = a2[i] && w->act[i];
  }
  if (dual_activeset_dense(p, w, bp, a2, F2, mu, tol) != 1) return;
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
static int finish(cup_projector *p, dense_ws *w, const double *x, cup_proj_info *info,
                  void (*inward)(cup_projector *, void *), int evaluated) {
  if (!evaluated) {
    for (int i = 0; i < p->m; i++) p->lam[i] = la_max(p->lam[i], 0);
    certify_eval_primal(p, x, p->g, p->lam, p->y, p->s, p->gam);
  }
  p->has_inward = 0;
  p->make_inward = inward;
  p->inward_ws = w;
  int ok = certify_candidate(p, x, p->lam, p->y, info);
  p->make_inward = NULL;
  return ok;
}

static int solve(cup_projector *p, void *ws, const double *x, cup_proj_info *info) {
  dense_ws *w = ws;
  int m = p->m;
  info->method = CUP_PROJ_ACTIVESET;
  double *tolA = w->fo.wm3;
  entry_tolerances(p, info->scale, tolA);
  /* warm start: the previous support, from lambda = 0 (always feasible) */
  for (int i = 0; i < m; i++) {
    w->act[i] = p->opt.warm_start && p->lam_warm[i] > 0;
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
  int st = dual_activeset_dense(p, w, bs, NULL, w->act, p->lam, tolA);
  if (st == 1 && finish(p, w, x, info, inward_dense, refine_dense(p, w, x, tau))) return CUP_OK;
  for (int i = 0; i < m; i++) p->lam[i] = 0;
  st = dual_activeset_dense(p, w, p->b, NULL, w->act, p->lam, tolA);
  if (st < 0 && certify_farkas_test(p, w->dwork + 4 * (size_t)m, info)) return CUP_ERR_EMPTY_SET;
  if (st == 1) {
    if (finish(p, w, x, info, inward_dense, refine_dense(p, w, x, NULL))) return CUP_OK;
    /* The exact optimum, certified only to what rounding allows (a set
     * without interior, or a thin wedge): iterating cannot do better. */
    return CUP_WARN_NOT_CERTIFIED;
  }
  /* Ties, rounding or an unconvincing Farkas ray: alternate FISTA bursts
   * (which detect emptiness) with active-set restarts from FISTA's support. */
  for (int burst = 32; p->iters < p->opt.max_iter; burst *= 2) {
    if (burst > 32) memcpy(p->lam, w->lam_fista, sizeof(double) * (size_t)m);
    int fst = proj_firstorder(p, &w->fo, x, 1, burst, info);
    if (fst != CUP_WARN_NOT_CERTIFIED) { info->method = CUP_PROJ_FISTA; return fst; }
    memcpy(w->lam_fista, p->lam, sizeof(double) * (size_t)m);
    memcpy(w->fo.wm4, p->lam, sizeof(double) * (size_t)m);   /* keep FISTA's answer */
    for (int i = 0; i < m; i++) { w->act[i] = p->lam[i] > 0; p->lam[i] = 0; }
    entry_tolerances(p, info->scale, tolA);
    if (dual_activeset_dense(p, w, p->b, NULL, w->act, p->lam, tolA) == 1 &&
        finish(p, w, x, info, inward_dense, refine_dense(p, w, x, NULL)))
      return CUP_OK;
    memcpy(p->lam, w->fo.wm4, sizeof(double) * (size_t)m);
  }
  finish(p, w, x, info, NULL, 0);
  return CUP_WARN_NOT_CERTIFIED;
}

/* ---- the method --------------------------------------------------------------- */

static void lay_out(cup_projector *p, proj_carve *a, void **ws) {
  dense_ws scratch, *w = PROJ_WS_CARVE(a, *ws, dense_ws, &scratch);
  size_t M = (size_t)p->m, D = sizeof(double);
  proj_fo_lay_out(p, a, &w->fo);
  w->lam_fista = proj_carve_piece(a, M, D);
  w->iwm = proj_carve_piece(a, M, sizeof(int));
  w->act = proj_carve_piece(a, M, 1);
  w->dwork = proj_carve_piece(a, M * M + 6 * M, D);
  for (int c = 0; c < DENSE_CACHE; c++) {
    w->cache[c].idx = proj_carve_piece(a, M, sizeof(int));
    w->cache[c].perm = proj_carve_piece(a, M, sizeof(int));
    w->cache[c].l = proj_carve_piece(a, M * M, D);
  }
}

/* The factors were of the old values. */
static void revalue(cup_projector *p, void *ws) {
  (void)p;
  dense_ws *w = ws;
  for (int c = 0; c < DENSE_CACHE; c++) w->cache[c].mask = 0;
}

/* The exact method for small dense sets (K->dense: m <= 64 rows, dim <= 256). */
static int takes(const cup_polyset *K, const cup_projector_options *o) {
  return K->dense && (o->method == CUP_PROJ_AUTO || o->method == CUP_PROJ_ACTIVESET);
}

static const proj_method dense_method = {
  .name = "dense active set", .exact = 1, .standby = 1, .takes = takes, .lay_out = lay_out,
  .revalue = revalue, .solve = solve,
};
const proj_method *const proj_dense = &dense_method;
