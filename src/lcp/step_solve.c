/* step_solve — lcp_step_solve (step.h): the LCP of one step solved and
 * certified, its warm start from a run's first zeta (lcp_step_start), the
 * unrolled small-set dispatch, the aimed solves, with D the warm step
 * (warm_d, a block of block.h) and the general one (solve_d), and the
 * certificates (lcp_step_eta, eps); the matrices and the mode they are
 * solved with are step.c's (set_mode, carry_of). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "step.h"

double lcp_step_eta(lcp_step *ls, const double *g, const double *z) {
  const cup_polyset *K = ls->K;
  int n = ls->n, m = ls->m;
  double worst = INFINITY;
  for (int i = 0; i < m; i++) worst = la_min(worst, ls->s[i] - ls->gam[i]);
  if (worst >= 0) return 0;
  if (!K->rdir) return INFINITY;
  double t = 0;
  for (int i = 0; i < m; i++)
    if (ls->s[i] - ls->gam[i] < 0) {
      if (!(K->Crdir[i] > 0)) return INFINITY;
      t = la_max(t, (3 * ls->gam[i] - ls->s[i]) / K->Crdir[i]);
    }
  for (int j = 0; j < n; j++) ls->v[j] = z[j] + t * K->rdir[j];
  return polyset_slack(K, g, ls->v, ls->sv, ls->gamv) >= 0 ? t * K->rdir_norm * (1 + 8 * DBL_EPSILON)
                                                        : INFINITY;
}

/* The support of the last zeta, a bit per row. */
static unsigned long long support(const lcp_step *ls) {
  unsigned long long J = 0;
  for (int i = 0; i < ls->m; i++)
    if (ls->lcp.lam[i] > 0) J |= 1ull << i;
  return J;
}

int lcp_step_start(lcp_step *ls, const double *x0, const double *g) {
  int m = ls->m, pivots = 0;
  double *lam = ls->lcp.lam;
  la_zero(lam, m);
  if (!ls->D) return polyset_slack(ls->K, g, x0, ls->qs, NULL) >= 0;
  polyset_slack(ls->K, g, x0, ls->qs, NULL);          /* q = C x0 + g, M = D */
  int consistent = lemke_solve(&ls->lcp.lemke, ls->D, ls->qs, lam, ls->lcp.w, &pivots) == CUP_OK;
  if (!consistent) la_zero(lam, m);
  set_mode(ls, support(ls));
  carry_of(ls, 0);
  return consistent;
}

/* (m + 2) eps sum_j |A_ij| lambda_j: the rounding of row i of A lambda. */
static double row_rounding(const lcp_step *ls, const double *A, const double *lam, int i) {
  double mag = 0;
  for (int j = 0; j < ls->m; j++) mag += fabs(A[i + (size_t)j * ls->m]) * lam[j];
  return (ls->m + 2) * DBL_EPSILON * mag;
}

/* The entries of lambda that the sums over it must see, into nz: the
 * nonzero ones (all of them unless lam_sparse). A zero lambda_j adds a
 * zero to each sum (A finite), which changes it only where it is zero,
 * and then at most its sign. Returns their count. */
CUP_ALWAYS_INLINE int lam_support(const lcp_step *ls, const double *lam, int *nz, const int m) {
  int p = 0;
  for (int j = 0; j < m; j++)
    if (lam[j] != 0 || !ls->lam_sparse) nz[p++] = j;
  return p;
}

/* row_rounding of every row into out, over lambda's support nz (p
 * entries): a sum of magnitudes starts at +0 and is never -0, so the zeros
 * left out change none of its bits. */
CUP_ALWAYS_INLINE void rows_rounding(const double *restrict A, const double *restrict lam, const int *restrict nz,
                                     int p, double *restrict out, const int m) {
  for (int i = 0; i < m; i++) {
    double mag = 0;
    for (int t = 0; t < p; t++) mag += fabs(A[i + (size_t)nz[t] * m]) * lam[nz[t]];
    out[i] = (m + 2) * DBL_EPSILON * mag;
  }
}

/* With D, a row of w may not depend on z at all (a diode fixed by the
 * other diodes' currents): aim it beyond the rounding of (M lambda)_i too,
 * known only once lambda is; 1 if some tau_i grew. */
static int widen_aim(lcp_step *ls, const double *q) {
  int m = ls->m, more = 0;
  double *r = ls->work;
  int *nz = ls->kwork;
  rows_rounding(ls->M, ls->lcp.lam, nz, lam_support(ls, ls->lcp.lam, nz, m), r, m);
  for (int i = 0; i < m; i++) {
    double want = 16 * r[i];
    if (want > ls->tau[i]) {
      ls->tau[i] += want;
      ls->qs[i] = q[i] - ls->tau[i];
      more = 1;
    }
  }
  return more;
}

/* g + D lambda (D != 0), else g itself, over lambda's support nz (p
 * entries, lam_support): a row whose sum is zero, whose sign the zeros
 * left out may have changed, is summed whole again. */
CUP_ALWAYS_INLINE const double *effective_offset(lcp_step *ls, const double *g, const int *restrict nz, int p,
                                                 const int m) {
  if (!ls->D) return g;
  const double *restrict lam = ls->lcp.lam, *restrict D = ls->D;
  for (int i = 0; i < m; i++) {
    double acc = g[i];
    for (int t = 0; t < p; t++) acc += D[i + (size_t)nz[t] * m] * lam[nz[t]];
    if (acc == 0) {
      acc = g[i];
      for (int j = 0; j < m; j++) acc += D[i + (size_t)j * m] * lam[j];
    }
    ls->geff[i] = acc;
  }
  return ls->geff;
}

static int small_dispatch(lcp_step *ls, const double *g, const double *xf, double *z, double scale,
                          double eps_target, double eta_target, cup_proj_info *info) {
#define CUP_SMALL_CASE(N, M) \
  case (N) * 8 + (M): return lcp_small_step(ls, g, xf, z, scale, eps_target, eta_target, info, N, M);
  switch (ls->n * 8 + ls->m) {
    CUP_SMALL_CASE(1, 1) CUP_SMALL_CASE(2, 1) CUP_SMALL_CASE(3, 1) CUP_SMALL_CASE(4, 1)
    CUP_SMALL_CASE(1, 2) CUP_SMALL_CASE(2, 2) CUP_SMALL_CASE(3, 2) CUP_SMALL_CASE(4, 2)
  }
#undef CUP_SMALL_CASE
  return 0;
}

/* The LCP aimed at slack tau (qs = q - tau), warm, then cold; an aim that
 * makes it unsolvable (a set without interior) gives way to the exact one.
 * With D, a row that z does not move is aimed past (M lambda)_i's rounding
 * too (widen_aim). */
static int aimed_solve(lcp_step *ls, const double *q, int *pivots) {
  int m = ls->m, st = CUP_ERR_LINALG, aimed = 0;
  double *tau = ls->tau, *qs = ls->qs;
  const double *M = ls->M, *qa = q, *qb = qs;
  if (ls->D) {                                    /* rows scaled (build_hm) */
    double *sq = ls->rsc + m, *sqs = sq + m;
    for (int i = 0; i < m; i++) {
      sq[i] = ls->rsc[i] * q[i];
      sqs[i] = ls->rsc[i] * qs[i];
    }
    M = ls->Ms, qa = sq, qb = sqs;
  }
  for (int aim = 1; aim >= 0 && st == CUP_ERR_LINALG; aim--) {
    if (!aim) la_zero(tau, m);
    st = lcp_solve(&ls->lcp, M, aim ? qb : qa, pivots);
    aimed = aim && !st;
  }
  if (aimed && ls->D && widen_aim(ls, q)) {
    for (int i = 0; i < m; i++) ls->rsc[2 * m + i] = ls->rsc[i] * qs[i];
    if (lcp_solve(&ls->lcp, M, qb, pivots) != CUP_OK) {
      la_zero(tau, m);
      st = lcp_solve(&ls->lcp, M, qa, pivots);
    }
  }
  return st;
}

/* g + D lambda and the rounding of D lambda (rows_rounding) into r over
 * the block's active columns, which hold lambda's nonzero entries (the
 * others add zeros, as lam_support says). */
CUP_ALWAYS_INLINE const double *block_offset(lcp_step *ls, const lcp_block *B, const double *g, double *restrict r,
                                             const int m) {
  const int k = B->k, *restrict idx = B->idx;
  const double *restrict lam = ls->lcp.lam;
  double acc[LCP_BLOCKS_MAX_M], mag[LCP_BLOCKS_MAX_M];
  for (int i = 0; i < m; i++) acc[i] = g[i], mag[i] = 0;
  for (int b = 0; b < k; b++) {
    const double *restrict dg = B->Dg + (size_t)b * m, *restrict da = B->Da + (size_t)b * m, l = lam[idx[b]];
    for (int i = 0; i < m; i++) {
      acc[i] += dg[i] * l;
      mag[i] += da[i] * l;
    }
  }
  for (int i = 0; i < m; i++) {
    if (acc[i] == 0) {
      acc[i] = g[i];
      for (int j = 0; j < m; j++) acc[i] += ls->D[i + (size_t)j * m] * lam[j];
    }
    ls->geff[i] = acc[i];
    r[i] = (m + 2) * DBL_EPSILON * mag[i];
  }
  return ls->geff;
}

/* lambda >= 0, lambda^T q, z = xf + H lambda, and z's slack and its rounding
 * in ls->s, ls->gam for the offset returned (g, or g + D lambda); B: the
 * block of lambda's support (warm_d), or NULL. */
CUP_ALWAYS_INLINE const double *finish_m(lcp_step *ls, const double *q, const double *g, const double *xf, double *z,
                                         const lcp_block *B, const int m) {
  int n = ls->n;
  double *lam = ls->lcp.lam, lq = 0;
  for (int i = 0; i < m; i++) {
    lam[i] = la_max(lam[i], 0);
    lq += lam[i] * q[i];
  }
  ls->lq = lq;
  la_copy(z, xf, n);
  for (int i = 0; i < m; i++) {
    if (lam[i] == 0) continue;
    for (int r = 0; r < n; r++) z[r] += ls->H[r + (size_t)i * n] * lam[i];
  }
  /* certificates from the slack of z itself; with D, in K shifted by D lambda */
  if (!ls->D) {
    polyset_slack(ls->K, g, z, ls->s, ls->gam);
    return g;
  }
  double *r = ls->work;
  if (B) {
    g = block_offset(ls, B, g, r, m);
  } else {
    int *nz = ls->kwork, p = lam_support(ls, lam, nz, m);
    g = effective_offset(ls, g, nz, p, m);
    rows_rounding(ls->D, lam, nz, p, r, m);
  }
  polyset_slack(ls->K, g, z, ls->s, ls->gam);
  for (int i = 0; i < m; i++) ls->gam[i] += r[i];
  return g;
}

static const double *finish(lcp_step *ls, const double *q, const double *g, const double *xf, double *z) {
  return finish_m(ls, q, g, xf, z, NULL, ls->m);
}

/* The most solves again for a new support's weights (mode_solve), and for
 * rows aimed further in (solve_d). */
enum { MODE_PASSES = 4, AIM_PASSES = 3 };

/* Solves again while the solution's support asks for other weights than
 * those it was solved with (set_mode). */

static int mode_solve(lcp_step *ls, const double *q, int *pivots) {
  for (int pass = 0;; pass++) {
    if (pass)
      for (int i = 0; i < ls->m; i++) ls->qs[i] = q[i] - ls->tau[i];
    int st = aimed_solve(ls, q, pivots);
    unsigned long long J = support(ls);
    if (st || J == ls->mode || pass == MODE_PASSES || !set_mode(ls, J)) return st;
  }
}

/* Rows whose slack at z is below its rounding bound are aimed further in
 * by twice the shortfall, and start the next solve active: the pivoting
 * accepts w_i >= -64 eps max |q| (a tolerance of the largest row), which
 * on a row of small scale, or one tied to another that is aimed in (two
 * diodes whose rows leave K no interior), is no rounding at all. 1 if some
 * row was. */
static int reaim(lcp_step *ls, const double *q) {
  int more = 0;
  for (int i = 0; i < ls->m; i++) {
    if (ls->s[i] >= ls->gam[i]) continue;
    ls->tau[i] += 2 * (ls->gam[i] - ls->s[i]) + 16 * ls->gam[i] + DBL_MIN;
    ls->lcp.prev[i] = 1;
    more = 1;
  }
  for (int i = 0; more && i < ls->m; i++) ls->qs[i] = q[i] - ls->tau[i];
  return more;
}

/* One step of iterative refinement of lambda on its support J: the aimed,
 * scaled LCP's rows on J, (R qs)_J + (Ms lambda)_J, should be 0. LU on a
 * nearly singular block (an op-amp's loop gain in D) leaves them at
 * cond(Ms_JJ) eps, which an aim could only cover by moving the answer by
 * cond times the aim; one correction in working precision brings them to
 * the rounding of the block's entries. */
static void refine(lcp_step *ls, const double *q) {
  int m = ls->m, p = 0;
  int *idx = ls->kwork, *piv = idx + m;
  double *A = ls->work, *r = A + (size_t)m * m, *w = r + m, *lam = ls->lcp.lam;
  for (int i = 0; i < m; i++)
    if (lam[i] > 0) idx[p++] = i;
  for (int a = 0; a < p; a++) {
    int i = idx[a];
    double acc = ls->rsc[i] * (q[i] - ls->tau[i]);  /* R (q - tau): tau is 0 if the aim gave way */
    for (int j = 0; j < m; j++) acc += ls->Ms[idx[a] + (size_t)j * m] * lam[j];
    r[a] = -acc;
    for (int b = 0; b < p; b++) A[a + (size_t)b * p] = ls->Ms[idx[a] + (size_t)idx[b] * m];
  }
  if (!p || la_dense_lu(A, p, piv)) return;
  la_dense_lu_solve(A, p, piv, r, w);
  for (int a = 0; a < p; a++) lam[idx[a]] += r[a];
}

/* 1 when some row's slack at z is below its rounding bound; *active: one
 * of them has lambda > 0. */
static int short_rows(const lcp_step *ls, int *active) {
  int any = 0;
  *active = 0;
  for (int i = 0; i < ls->m; i++)
    if (ls->s[i] < ls->gam[i]) {
      any = 1;
      *active |= ls->lcp.lam[i] > 0;
    }
  return any;
}

/* The step with D: the mode's weights, then until z certainly satisfies
 * every row (a row that z does not move, a bridge's diode fixed by the
 * others' currents, cannot be pushed into K afterwards): first lambda
 * refined on its support if an active row falls short, then aims moved
 * further in (reaim), keeping the last solution if a solve fails; the
 * trapezoid's carry. *g: the offset of z's certificates. */
static int solve_d(lcp_step *ls, const double *q, const double **g, const double *xf, double *z,
                   int *pivots) {
  int st = mode_solve(ls, q, pivots), m = ls->m, active;
  if (st) return st;
  const double *g0 = *g;
  *g = finish(ls, q, g0, xf, z);
  int short_ = short_rows(ls, &active);
  if (short_ && active) {
    refine(ls, q);
    *g = finish(ls, q, g0, xf, z);
    short_ = short_rows(ls, &active);
  }
  for (int r = 0; r < AIM_PASSES && short_ && reaim(ls, q); r++) {
    la_copy(ls->sv, ls->lcp.lam, m);
    int ok = aimed_solve(ls, q, pivots) == CUP_OK;
    if (!ok) la_copy(ls->lcp.lam, ls->sv, m);
    *g = finish(ls, q, g0, xf, z);
    if (!ok) break;
    short_ = short_rows(ls, &active);
  }
  carry_of(ls, 1);
  return CUP_OK;
}

/* solve_d's common case, taken without its general machinery: the last
 * step's active set solves both aimed LCPs (aimed_solve and widen_aim's
 * second solve) with no pivot, its support is the mode in force, and z
 * satisfies every row with room for its rounding. Then z, lambda, the aims
 * and the carry are solve_d's, bit for bit, and it returns 1 (*g: the
 * offset of z's certificates); else 0, having changed only what solve_d
 * computes again (lambda, z, the slacks). The sums over lambda run over
 * the block's active columns: the others hold zeros (finish_m). */
CUP_ALWAYS_INLINE int warm_d(lcp_step *ls, const double *q, const double **g, const double *xf, double *z,
                             const int m) {
  if (m > LCP_BLOCKS_MAX_M || !ls->lam_sparse) return 0;   /* lam_sparse implies warm */
  double *restrict sqs = ls->wscr, *restrict tau = sqs + m, *restrict qs = tau + m, *restrict lam = qs + m;
  double *restrict y = lam + m;
  unsigned long long act = 0;
  for (int i = 0; i < m; i++) {
    act |= (unsigned long long)(ls->lcp.prev[i] != 0) << i;
    sqs[i] = ls->rsc[i] * ls->qs[i];
  }
  const lcp_block *B = lcp_blocks_get(&ls->blocks, act, ls->Ms, ls->M, ls->D);
  if (lcp_block_pass(B, sqs, lam, y, m)) return 0;
  const int k = B->k, *restrict idx = B->idx;
  int more = 0, active;                           /* widen_aim, on copies of the aims */
  double mag[LCP_BLOCKS_MAX_M];
  for (int i = 0; i < m; i++) mag[i] = 0;
  for (int b = 0; b < k; b++) {
    const double *restrict col = B->Ma + (size_t)b * m, l = lam[idx[b]];
    for (int i = 0; i < m; i++) mag[i] += col[i] * l;
  }
  for (int i = 0; i < m; i++) {
    double want = 16 * ((m + 2) * DBL_EPSILON * mag[i]);
    tau[i] = ls->tau[i];
    qs[i] = ls->qs[i];
    if (want > tau[i]) {
      tau[i] += want;
      qs[i] = q[i] - tau[i];
      more = 1;
    }
  }
  if (more) {
    for (int i = 0; i < m; i++) sqs[i] = ls->rsc[i] * qs[i];
    if (lcp_block_pass(B, sqs, lam, y, m)) return 0;
  }
  unsigned long long J = 0;
  for (int i = 0; i < m; i++)
    if (lam[i] > 0) J |= 1ull << i;
  if (J != ls->mode) return 0;
  for (int i = 0; i < m; i++) ls->lcp.lam[i] = lam[i];
  const double *geff = finish_m(ls, q, *g, xf, z, B, m);
  if (short_rows(ls, &active)) return 0;
  *g = geff;
  for (int i = 0; i < m; i++) {
    ls->tau[i] = tau[i];
    ls->qs[i] = qs[i];
  }
  carry_of(ls, 1);
  return 1;
}

/* lcp_step_solve beyond the unrolled step, for m rows. */
CUP_ALWAYS_INLINE int solve_general_m(lcp_step *ls, const double *g, const double *xf, double *z, double scale,
                                      double eps_target, double eta_target, cup_proj_info *info, const int m) {
  const cup_polyset *K = ls->K;
  int n = ls->n;
  double *lam = ls->lcp.lam;
  *info = (cup_proj_info){0};
  info->eps_target = eps_target < 0 ? 1e-12 * scale * scale : eps_target;
  info->eta_target = eta_target;
  info->method = CUP_PROJ_ACTIVESET;
  if (ls->D) {                                    /* the trapezoid's old half: h (1 - theta) W B Pi zeta_k */
    la_copy(ls->xpred, xf, n);
    for (int i = 0; i < m; i++)
      if (ls->carry[i] != 0)
        for (int r = 0; r < n; r++) ls->xpred[r] += ls->Hprev[r + (size_t)i * n] * ls->carry[i];
    xf = ls->xpred;
  }
  double probe = 0;                               /* NaN iff some entry is NaN or Inf */
  for (int j = 0; j < n; j++) probe += 0 * xf[j];
  if (isnan(probe)) return info->status = CUP_ERR_NONFINITE;
  double *q = ls->s;                              /* q = C x_free + g */
  polyset_slack(K, g, xf, q, ls->gam);
  info->scale = scale;
  double qmin = INFINITY;
  for (int i = 0; i < m; i++) qmin = la_min(qmin, q[i]);
  if (qmin >= 0) {                                /* the free point is in K: lambda = 0 */
    la_copy(z, xf, n);
    la_zero(lam, m);
    if (ls->D) la_zero(ls->carry, m);
    ls->lq = 0;
    info->skipped = 1;
    info->eta_cert = lcp_step_eta(ls, g, z);
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
  int pivots = 0, st;
  if (ls->D) {                                    /* q outlives the slack of z (ls->s) */
    la_copy(ls->q0, q, m);
    q = ls->q0;
    st = warm_d(ls, q, &g, xf, z, m) ? CUP_OK : solve_d(ls, q, &g, xf, z, &pivots);
  } else {
    st = aimed_solve(ls, q, &pivots);
    if (!st) g = finish(ls, q, g, xf, z);
  }
  info->iterations = pivots + 1;
  if (st) return info->status = st;
  double gap = 0, viol = 0;
  int active = 0;
  for (int i = 0; i < m; i++) {
    gap += 2 * ls->h * lam[i] * (ls->s[i] + ls->gam[i]);   /* impulse mu = h lambda */
    viol = la_max(viol, -ls->s[i]);
    active += lam[i] > 0;
  }
  info->active = active;
  info->violation = viol;
  info->eps_cert = isnan(gap) ? NAN : la_max(gap, 0);
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
      double lcp_round = ls->D ? row_rounding(ls, ls->M, lam, i) : 0;   /* with D: the LCP's own */
      floor += 2 * ls->h * lam[i] * (ls->gam[i] + 2 * K->rowgam[i] * mag + tau[i] + lcp_round);
    }
    info->eps_target = eps_target = la_max(1e-12 * scale * scale, floor);
  }
  info->eta_cert = lcp_step_eta(ls, g, z);
  return info->status = info->eps_cert <= eps_target && info->eta_cert <= eta_target
                            ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
}

/* solve_general_m out of line, so that the unrolled step's callers pay for
 * none of its registers (35 instructions a call on the paper circuit's
 * projections); with the row counts of small circuits with D known at
 * compile time, their steps being mostly warm_d's short loops. */
static __attribute__((noinline)) int solve_general(lcp_step *ls, const double *g, const double *xf, double *z,
                                                   double scale, double eps_target, double eta_target,
                                                   cup_proj_info *info) {
#define CUP_GENERAL_CASE(M) \
  case M: return solve_general_m(ls, g, xf, z, scale, eps_target, eta_target, info, M);
  if (ls->D) switch (ls->m) { CUP_GENERAL_CASE(1) CUP_GENERAL_CASE(2) CUP_GENERAL_CASE(3) CUP_GENERAL_CASE(4)
                              CUP_GENERAL_CASE(6) }
#undef CUP_GENERAL_CASE
  return solve_general_m(ls, g, xf, z, scale, eps_target, eta_target, info, ls->m);
}

int lcp_step_solve(lcp_step *ls, const double *g, const double *xf, double *z,
                   double scale, double eps_target, double eta_target, cup_proj_info *info) {
  if (ls->small && eps_target >= 0 && small_dispatch(ls, g, xf, z, scale, eps_target, eta_target, info))
    return info->status;
  return solve_general(ls, g, xf, z, scale, eps_target, eta_target, info);
}

/* step.h's lcp_small_pass until no index flips */
int lcp_small_murty_loop(unsigned *actp, const double *M, double det, double q0, double q1, double tol_w,
                         v2d *lam, int *pivots, int m) {
  unsigned act = *actp;
  for (int it = 0; it < 16 * m + 64; it++) {
    double l0, l1;
    int flip = lcp_small_pass(act, M, det, q0, q1, tol_w, &l0, &l1, m);
    if (flip == -2) return 1;
    if (flip < 0) {
      *lam = (v2d){l0, l1};
      *actp = act;
      return 0;
    }
    act ^= 1u << flip;
    (*pivots)++;
  }
  return 1;
}
