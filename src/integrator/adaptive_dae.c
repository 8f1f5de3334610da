/* adaptive_dae — the adaptive scheme with D != 0 (adaptive_impl.h,
 * docs/adaptive.md): an active set's flow is a linear DAE, the choice of
 * the active set is an LCP with D, and a state that no multiplier makes
 * consistent jumps. With the rows J held,
 *     C_J x + D_JJ zeta_J + g_J = 0.
 * Split by the SVD D_JJ = U S V^T into Y (U's columns of the nonzero
 * singular values) and Z (the others, the left null space): the Y rows fix
 * zeta_J algebraically, Y^T (C_J x + g_J) + Y^T D_JJ zeta_J = 0, and the Z
 * rows are a manifold of the state, Z^T (C_J x + g_J) = 0, whose derivative
 * fixes the rest: Z^T C_J (A x + B_J zeta_J + E u) + Z^T G_J u' = 0. Both
 * together are N zeta_J = -(...), N = [Y^T D_JJ; Z^T C_J B_J]; with D = 0
 * this is the sweeping process's S = C_J B_J (the split and N's inverse:
 * adaptive_split.c). Allocates only in ad_dae_init. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "adaptive_impl.h"

static void *take(size_t count, size_t size, int *fail) {
  void *q = calloc(count ? count : 1, size);
  if (!q) *fail = 1;
  return q;
}

/* The arrays below, each its own (a workspace without a shared scratch). */
static int dae_arrays(adaptive_ws *A) {
  int n = A->n, m = A->m, na = A->na, fail = 0;
  size_t MM = (size_t)m * m;
  A->N = take(MM, sizeof(double), &fail);
  A->Ninv = take(MM, sizeof(double), &fail);
  A->svd_u = take(MM, sizeof(double), &fail);
  A->svd_v = take(MM, sizeof(double), &fail);
  A->svd_s = take((size_t)m, sizeof(double), &fail);
  A->svd_w = take((size_t)m, sizeof(double), &fail);
  A->jM = take(4 * MM, sizeof(double), &fail);
  A->jq = take(2 * (size_t)m, sizeof(double), &fail);
  A->dq0 = take((size_t)m, sizeof(double), &fail);
  A->dq1 = take((size_t)m, sizeof(double), &fail);
  A->Ry = take((size_t)n * m, sizeof(double), &fail);
  A->Ym = take(((size_t)m + 1) * na, sizeof(double), &fail);
  A->Zc = take((size_t)m * n, sizeof(double), &fail);
  double **vm[] = {&A->sz, &A->eqr, &A->eqc, &A->cg, &A->cd, &A->cd2, &A->cthr};
  for (size_t k = 0; k < sizeof vm / sizeof *vm; k++) *vm[k] = take((size_t)m, sizeof(double), &fail);
  A->cy = take((size_t)na, sizeof(double), &fail);
  A->cMy = take((size_t)na, sizeof(double), &fail);
  A->jx = take((size_t)n, sizeof(double), &fail);
  return fail;
}

int ad_dae_init(adaptive_ws *A) {
  /* (shared: the arrays are the scratch's, adaptive.c's scratch_carve; the SVDs' memo is the
   * workspace's own, written before it is read) */
  A->svd_memo_used = 0;
  if ((!A->scratch && dae_arrays(A)) || !(A->svd_memo = malloc(AD_SVD_MEMO * sizeof(double))) ||
      lcp_init(&A->jlcp, 2 * A->m) || lcp_monotone(&A->jlcp) || lcp_monotone(&A->lcp))
    return CUP_ERR_NOMEM;
  return CUP_OK;
}

void ad_dae_free(adaptive_ws *A) {
  lcp_free(&A->jlcp);
  free(A->svd_memo);
  if (A->scratch) return;
  free(A->N); free(A->Ninv); free(A->svd_u); free(A->svd_v); free(A->svd_s); free(A->svd_w);
  free(A->jM); free(A->jq); free(A->dq0); free(A->dq1); free(A->Ry); free(A->Ym); free(A->Zc);
  free(A->sz); free(A->eqr); free(A->eqc); free(A->cg); free(A->cd); free(A->cd2); free(A->cthr);
  free(A->cy); free(A->cMy); free(A->jx);
}

/* ---- the choice of the active set ----------------------------------------------- */

/* u, u' (A->ut, A->udot) and the slack q0 = C x + g with its rounding
 * bound (A->s, A->gam), and its velocity at zeta = 0, q1 = C (A x + E u) + G u'. */
static void slack_and_velocity(adaptive_ws *A, const double *x, const double *w) {
  const cup_polyset *K = A->K;
  int m = A->m;
  ad_offset(A, w, A->g);
  ad_free_velocity(A, x, w);
  polyset_slack(K, A->g, x, A->dq0, A->gam);
  for (int i = 0; i < m; i++) {
    double acc = 0;
    for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) acc += K->Ct.x[k] * A->xf[K->Ct.i[k]];
    for (int k = A->gp[i]; k < A->gp[i + 1]; k++) acc += A->gx[k] * A->udot[A->gi[k]];   /* G_i u' */
    A->dq1[i] = acc;
  }
}

/* Does the mode md continue from (x, w)? x on its manifold to rounding
 * (or, near > 0, its move onto it within near in the P-norm), and
 * every event function (multipliers of the held rows, slacks of the
 * others) nonnegative, lexicographically in its value and its first two
 * derivatives on the mode's own flow from x put on the manifold. The
 * slopes are needed only where a value is at rounding: a row below it
 * fails the mode, and with every row above it the mode fits (nearly every
 * try, at a window's start). A->g holds ad_offset of w (ad_dae_select's). */
static int mode_fits(adaptive_ws *A, ad_mode *md, const double *x, const double *w, double near) {
  int n = A->n, na = A->na, m = A->m;
  double xn = md->nz ? la_norm_inf(x, n) : 0;    /* (the residual's alone) */
  int off = 0;
  for (int b = 0; b < md->nz; b++) {             /* the manifold's residual against its rounding */
    double res = 0, mag = 0;
    for (int a = 0; a < md->nj; a++) {
      int i = md->rows[a];
      double s = A->g[i], sm = fabs(A->g[i]) + A->c1[i] * xn + A->gscale[i];
      for (int k = A->K->Ct.p[i]; k < A->K->Ct.p[i + 1]; k++) s += A->K->Ct.x[k] * x[A->K->Ct.i[k]];
      res += md->Zt[(size_t)b * md->nj + a] * s;
      mag += fabs(md->Zt[(size_t)b * md->nj + a]) * sm;
    }
    if (fabs(res) > 1024 * DBL_EPSILON * mag) {
      if (!(near > 0)) return 0;
      off = 1;
    }
  }
  double *xm = A->jx, *y = A->cy, *My = A->cMy, *g = A->cg, *d = A->cd, *d2 = A->cd2, *thr = A->cthr;
  const double *xl = x;                          /* (no manifold rows, a bridge's modes with D: x as it is) */
  if (md->nz) {
    la_copy(xm, x, n);
    ad_manifold(A, md, A->g, xm);
    xl = xm;
  }
  if (off) {
    for (int j = 0; j < n; j++) y[j] = xm[j] - x[j];
    if (!(cup_polyset_norm(A->K, y) <= near)) return 0;
  }
  ad_lift(A, md, xl, w, y);
  const double *wsc = A->wscale;                 /* the input's rounding: a sine's zero is an ulp off */
  int edge = 0;                                  /* a value at rounding */
  const int *lp = md->lp, *li = md->li;          /* (Lm's nonzeros: the dense sums of terms >= 0, +0 */
  const double *lx = md->lx, *lmx = md->lmx;     /* left out) */
  double vmax = la_norm_inf(y, n);
  for (int i = 0; i < m; i++) {
    /* ad_events_eval's value and rounding and the input's, one pass over
     * the row's nonzeros, the same sums; a row below its rounding ends the
     * check there (a window's start tries the empty set first: half the
     * bridge's dead times have a diode on) */
    double acc = md->Lc[i], mag = fabs(md->Lc[i]), tw = 0;
    for (int q = lp[i]; q < lp[i + 1]; q++) {
      int j = li[q];
      double yj = y[j];
      acc += lx[q] * yj;
      mag += lmx[q] * fabs(yj);
      if (j >= n) tw += lmx[q] * la_max(fabs(yj), wsc[j - n]);   /* (at each use: a bridge's one DC state) */
    }
    g[i] = acc;
    thr[i] = ad_row_rounding(A, md, i, mag, vmax);
    thr[i] = 16 * thr[i] + 64 * DBL_EPSILON * tw;
    if (g[i] < -thr[i]) return 0;
    edge |= !(g[i] > thr[i]);
  }
  if (!edge) return 1;
  ad_events_deriv(A, md, y, d);                  /* leaves M y in A->My */
  la_copy(My, A->My, na);
  ad_events_deriv(A, md, My, d2);                /* L M (M y) */
  for (int i = 0; i < m; i++) {
    if (g[i] > thr[i]) continue;
    double dm = 0, d2m = 0;                      /* the rounding of the slopes */
    for (int q = lp[i]; q < lp[i + 1]; q++) {
      dm += lmx[q] * fabs(My[li[q]]);
      d2m += lmx[q] * fabs(A->My[li[q]]);
    }
    if (d[i] < -1024 * DBL_EPSILON * dm) return 0;
    if (d[i] <= 1024 * DBL_EPSILON * dm && d2[i] < -1024 * DBL_EPSILON * d2m) return 0;
  }
  return 1;
}

/* The mode of mask if it continues from (x, w); NULL if not. */
static ad_mode *try_mode(adaptive_ws *A, uint64_t mask, const double *x, const double *w, double near) {
  ad_mode *md = ad_mode_get(A, mask);
  return md && mode_fits(A, md, x, w, near) ? md : NULL;
}

/* The LCP of a short implicit step of length h with D: on the rows that
 * may be active (those D couples, and the others whose slack is at
 * rounding or that are hinted), w = q0 + h q1 + (D + h C B) zeta, q0 zero
 * where it is at rounding; a shift of 1e-10 of each row's scale picks the
 * multipliers of least norm where they are not unique. The rows with
 * zeta > 0 into *mask; the degenerate ones (zeta and w both at zero) into
 * *degen. */
static int lcp_rows(adaptive_ws *A, const double *x, uint64_t hint, double h, uint64_t *mask, uint64_t *degen,
                    int *pivots) {
  int n = A->n, m = A->m;
  double xn = la_norm_inf(x, n);
  unsigned char *touch = A->touch;
  for (int i = 0; i < m; i++) {
    double round_ = 64 * DBL_EPSILON * (fabs(A->g[i]) + A->c1[i] * xn) + 16 * A->gam[i];
    int zero = fabs(A->dq0[i]) <= round_ || (!A->dcpl[i] && (hint >> i & 1));
    touch[i] = A->dcpl[i] || zero || (hint >> i & 1);
    A->lcpq[i] = touch[i] ? (zero ? 0 : A->dq0[i]) + h * A->dq1[i] : 1;
  }
  for (int j = 0; j < m; j++)
    for (int i = 0; i < m; i++)
      A->lcpM[i + (size_t)j * m] = touch[i] && touch[j] ? A->Dd[i + (size_t)j * m] + h * A->CB[i + (size_t)j * m]
                                                        : (i == j);
  for (int i = 0; i < m; i++) {
    if (!touch[i]) continue;
    double sc = 0;
    for (int j = 0; j < m; j++) sc += fabs(A->lcpM[i + (size_t)j * m]) + fabs(A->lcpM[j + (size_t)i * m]);
    A->lcpM[i + (size_t)i * m] += 1e-10 * sc;
  }
  int st = lcp_solve(&A->lcp, A->lcpM, A->lcpq, pivots);
  if (st) return st;
  double lmax = 0, wmax = 0;
  for (int i = 0; i < m; i++) {
    lmax = la_max(fabs(A->lcp.lam[i]), lmax);   /* (fmax without the call: a NaN passed over) */
    if (touch[i]) wmax = la_max(fabs(A->lcpq[i]), wmax);
  }
  *mask = *degen = 0;
  for (int i = 0; i < m; i++) {
    if (A->lcp.lam[i] > 1e-8 * lmax) *mask |= (uint64_t)1 << i;
    else if (touch[i] && A->lcp.w[i] <= 1e-8 * wmax) *degen |= (uint64_t)1 << i;
  }
  return CUP_OK;
}

/* The mode of J if it continues from (x, w); else, when J's rows are
 * dependent (the mode keeps the first independent ones: two rows of a
 * bridge alike, their multipliers split evenly by the LCP's least norm),
 * the kept rows with one exchanged for a dropped one. */
static ad_mode *try_rows(adaptive_ws *A, uint64_t J, const double *x, const double *w, double near) {
  ad_mode *md = ad_mode_get(A, J);
  if (!md) return NULL;
  if (mode_fits(A, md, x, w, near)) return md;
  uint64_t kept = md->mask, dropped = J & ~kept;
  for (int r = 0; r < A->m; r++) {
    if (!(dropped >> r & 1)) continue;
    for (int k = 0; k < A->m; k++)
      if ((kept >> k & 1) && (md = try_mode(A, (kept & ~((uint64_t)1 << k)) | (uint64_t)1 << r, x, w, near)))
        return md;
  }
  return NULL;
}

int ad_dae_select(adaptive_ws *A, const double *x, const double *w, uint64_t cur, int row, uint64_t hint,
                  uint64_t seed, double tscale, double near, uint64_t *mask, int *pivots) {
  ad_offset(A, w, A->g);                         /* for mode_fits; left there for the caller */
  return ad_dae_select_at(A, x, w, cur, row, hint, seed, tscale, near, mask, pivots);
}

int ad_dae_select_at(adaptive_ws *A, const double *x, const double *w, uint64_t cur, int row, uint64_t hint,
                     uint64_t seed, double tscale, double near, uint64_t *mask, int *pivots) {
  int m = A->m;
  ad_mode *md;
  if ((row >= 0 && (md = try_mode(A, cur ^ (uint64_t)1 << row, x, w, near))) ||   /* the event row alone */
      (row < 0 && (md = try_mode(A, cur, x, w, near))) ||                      /* the same set, still right */
      (seed && seed != cur && (md = try_mode(A, seed, x, w, near)))) {          /* the caller's guess */
    *mask = md->mask;
    return CUP_OK;
  }
  for (int level = 0; level < 3; level++) {
    uint64_t J, degen;
    slack_and_velocity(A, x, w);
    int st = lcp_rows(A, x, hint | cur, 1e-6 * pow(1e-3, level) * tscale, &J, &degen, pivots);
    if (st) continue;
    if ((md = try_rows(A, J, x, w, near))) { *mask = md->mask; return CUP_OK; }
    for (int i = 0; i < m; i++)                  /* a degenerate row in or out */
      if ((degen >> i & 1) && (md = try_rows(A, J ^ (uint64_t)1 << i, x, w, near))) { *mask = md->mask; return CUP_OK; }
    for (int i = 0; i < m; i++)
      for (int k = i + 1; k < m; k++)
        if ((degen >> i & 1) && (degen >> k & 1) &&
            (md = try_rows(A, J ^ (uint64_t)1 << i ^ (uint64_t)1 << k, x, w, near))) {
          *mask = md->mask;
          return CUP_OK;
        }
  }
  /* none checks out: going on with a mode whose multipliers or slacks are
   * negative would be a wrong answer that nothing detects later */
  return CUP_ERR_LINALG;
}

/* ---- the state jump --------------------------------------------------------------- */

static uint64_t set_mask(const unsigned char *set, int m) {
  uint64_t mask = 0;
  for (int i = 0; i < m; i++)
    if (set[i]) mask |= (uint64_t)1 << i;
  return mask;
}

/* The set the jump's LCP was solved at the last time it started from
 * `from` (from itself when not known). */
static uint64_t jump_seen(const adaptive_ws *A, uint64_t from) {
  long have = A->njump < AD_JUMPS ? A->njump : AD_JUMPS;
  for (long k = 0; k < have; k++)
    if (A->jfrom[k] == from) return A->jto[k];
  return from;
}

static void jump_keep(adaptive_ws *A, uint64_t from, uint64_t to) {
  long have = A->njump < AD_JUMPS ? A->njump : AD_JUMPS, k = 0;
  while (k < have && A->jfrom[k] != from) k++;
  if (k == have) k = A->njump++ % AD_JUMPS;
  A->jfrom[k] = from;
  A->jto[k] = to;
}

/* The multipliers' LCP of the jump, 0 <= zeta _|_ C x + D zeta + g >= 0,
 * from A->lcp's warm start; 1 if solved. D of ideal diodes in loops with
 * sources alone is skew (a six-pulse bridge's), whose principal blocks of
 * odd order are singular: principal pivoting, one row a pivot, fails
 * unless its warm start is the answer, and Lemke's method solved it (5
 * of 6 of the bridge's event cost in this LCP). The set solved at the
 * last time from the same warm start is tried first, as it stands: a
 * converter's commutations follow each other in the same order each
 * period. */
static int jump_multipliers(adaptive_ws *A, int *pivots) {
  int m = A->m;
  /* the warm start itself first (lcp_solve's first pass): a full bridge's */
  if (lcp_try(&A->lcp, A->Dd, A->dq0, A->lcp.prev) == CUP_OK) return 1;
  uint64_t from = set_mask(A->lcp.prev, m), to = jump_seen(A, from);
  int solved = 0;
  if (to != from) {
    unsigned char *act = A->touch;
    for (int i = 0; i < m; i++) act[i] = to >> i & 1;
    solved = lcp_try(&A->lcp, A->Dd, A->dq0, act) == CUP_OK;
  }
  if (!solved) solved = lcp_solve(&A->lcp, A->Dd, A->dq0, pivots) == CUP_OK;
  if (solved) jump_keep(A, from, set_mask(A->lcp.prev, m));
  return solved;
}

int ad_dae_jump(adaptive_ws *A, double *x, uint64_t *active, int *pivots) {
  int n = A->n, m = A->m, m2 = 2 * m;
  *active = 0;
  /* the multipliers alone, x as it is: 0 <= zeta _|_ C x + D zeta + g >= 0
   * (a diode behind a resistance takes any slack; and there B need not be
   * P^-1 C^T, which the jump below assumes). An empty warm start (A->lcp's
   * is the active-set choice's, and a switched run's window starts cold)
   * gives way to the jump's own last set: a bridge's dead time opens on
   * the same diodes each period, and from nothing D's zero diagonal sent
   * principal pivoting into Lemke's method. A->lcp's warm start is left as
   * the solve leaves it, or empty when it fails. */
  int empty = lcp_cold(&A->lcp);
  if (empty) memcpy(A->lcp.prev, A->jseed, (size_t)m);
  int solved = jump_multipliers(A, pivots);
  if (solved) memcpy(A->jseed, A->lcp.prev, (size_t)m);
  else if (empty) lcp_forget(&A->lcp);
  if (solved) {
    /* w to the rounding of the solve: its residual is eps (|q| + |D| |zeta|)
     * in every row (a bridge behind a 10 kOhm shunt: 38 kV terms, a 2 V
     * row off by 2.4e-12); a w within the slack's own rounding is inside
     * that bound whatever it is (the usual case) */
    int in = 1;
    for (int i = 0; i < m; i++) in &= A->lcp.w[i] >= -16 * A->gam[i];
    if (in) return 0;
    double sc = 0;
    for (int i = 0; i < m; i++) {
      double r = fabs(A->dq0[i]);
      for (int j = 0; j < m; j++) r += fabs(A->Dd[i + (size_t)j * m] * A->lcp.lam[j]);
      sc = la_max(r, sc);
    }
    int ok = 1;
    for (int i = 0; i < m; i++) ok &= A->lcp.w[i] >= -16 * A->gam[i] - 64 * DBL_EPSILON * sc;
    if (ok) return 0;
  }
  /* x+ = x + B mu with 0 <= mu _|_ C x+ + D zeta + g >= 0 and
   * 0 <= zeta _|_ -D^T mu >= 0: the KKT conditions of the P-projection onto
   * Q(t) when P B = C^T; M = [C B, D; -D^T, 0] is monotone then */
  for (int j = 0; j < m2; j++)
    for (int i = 0; i < m2; i++) {
      double v = 0;
      if (i < m && j < m) v = A->CB[i + (size_t)j * m];
      else if (i < m) v = A->Dd[i + (size_t)(j - m) * m];
      else if (j < m) v = -A->Dd[j + (size_t)(i - m) * m];
      A->jM[i + (size_t)j * m2] = v;
    }
  for (int i = 0; i < m; i++) { A->jq[i] = A->dq0[i]; A->jq[m + i] = 0; }
  int st = lcp_solve(&A->jlcp, A->jM, A->jq, pivots);
  if (st) return CUP_ERR_LINALG;
  double xn = la_norm_inf(x, n), move = 0;
  for (int r = 0; r < n; r++) {
    double acc = 0;
    for (int i = 0; i < m; i++) acc += A->Bd[r + (size_t)i * n] * A->jlcp.lam[i];
    A->jx[r] = acc;
    move = la_max(fabs(acc), move);
  }
  if (move <= 64 * DBL_EPSILON * xn) return 0;  /* the multipliers absorb it */
  for (int r = 0; r < n; r++) x[r] += A->jx[r];
  for (int i = 0; i < m; i++)
    if (A->jlcp.lam[i] > 0) *active |= (uint64_t)1 << i;
  return 1;
}
