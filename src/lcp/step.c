/* step — see step.h. This file forms a step's matrices and owns what
 * forms them again: the set-up (H = h W B, M = C H, with D M = C H + D
 * and its arrays; the small set's dense rows) and its release; with D, the
 * mode, the support J of zeta: the kernel of D_JJ, the weights and H, M
 * made of it (set_mode), the trapezoid's carry Pi zeta (carry_of), and
 * what a step carries to the next, to or from a checkpoint. The step
 * solved is step_solve.c's. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "step.h"

static void small_init(lcp_step *ls);

int lcp_step_init(lcp_step *ls, const cup_polyset *K, const double *W, double h) {
  return lcp_step_init_bd(ls, K, W, h, NULL, NULL, 1);
}

/* H = h w W B column by column (w = 1 on a zero column of D, whose zeta no
 * row fixes, theta on the others, and the mode's kernel columns as
 * set_mode found them), then M = C H + D and its rows scaled. */
static void build_hm(lcp_step *ls) {
  const cup_polyset *K = ls->K;
  int n = ls->n, m = ls->m;
  double h = ls->h, theta = ls->theta;
  for (int i = 0; i < m; i++)
    for (int r = 0; r < n; r++) {
      int trap = !ls->dcol0[i];
      ls->H[r + (size_t)i * n] = h * (trap ? theta : 1) * ls->WB[r + (size_t)i * n];
    }
  /* a kernel column t: W B (theta e_t + (1 - theta) z_t), z_t = e_t + its part on the other columns */
  for (int k = 0; k < ls->nker; k++) {
    int t = ls->kcol[k];
    const double *z = ls->Z + (size_t)k * m;
    for (int r = 0; r < n; r++) {
      double acc = h * ls->WB[r + (size_t)t * n];
      for (int s = 0; s < m; s++)
        if (s != t && z[s] != 0) acc += h * (1 - theta) * z[s] * ls->WB[r + (size_t)s * n];
      ls->H[r + (size_t)t * n] = acc;
    }
  }
  for (int j = 0; j < m; j++)                      /* M = C H + D */
    for (int i = 0; i < m; i++) {
      double acc = ls->D[i + (size_t)j * m];
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) acc += K->Ct.x[k] * ls->H[K->Ct.i[k] + (size_t)j * n];
      ls->M[i + (size_t)j * m] = acc;
    }
  /* The LCP is solved with its rows scaled to largest entry 1: a row is
   * volts or amperes, and LU's residual and the pivoting's tolerance are
   * relative to the largest row; scaled, each row's are its own. */
  ls->lam_sparse = ls->warm;
  for (int i = 0; i < m; i++) {
    double r = 0;
    for (int j = 0; j < m; j++) r = la_max(r, fabs(ls->M[i + (size_t)j * m]));
    ls->rsc[i] = r > 0 ? 1 / r : 1;
    for (int j = 0; j < m; j++) {
      ls->Ms[i + (size_t)j * m] = ls->rsc[i] * ls->M[i + (size_t)j * m];
      ls->lam_sparse &= isfinite(ls->M[i + (size_t)j * m]) && isfinite(ls->D[i + (size_t)j * m]) &&
                       isfinite(ls->Ms[i + (size_t)j * m]);
    }
  }
  lcp_blocks_clear(&ls->blocks);                  /* they were the old M's */
}

/* The D path's arrays (lcp_step_free releases them on failure). */
static int init_d(lcp_step *ls, const double *D, double theta) {
  size_t N = (size_t)ls->n, M = (size_t)ls->m + 1;
  ls->D = malloc(sizeof(double) * M * M);
  ls->geff = calloc(M, sizeof(double));
  ls->WB = calloc(N * M, sizeof(double));
  ls->Hprev = calloc(N * M, sizeof(double));
  ls->carry = calloc(M, sizeof(double));
  ls->xpred = calloc(N, sizeof(double));
  ls->q0 = calloc(M, sizeof(double));
  ls->dcol0 = calloc(M, 1);
  ls->kcol = calloc(2 * M, sizeof(int));          /* the kernel in force, and a new one (set_mode) */
  ls->Z = calloc(2 * M * M, sizeof(double));
  ls->work = calloc(M * M + 2 * M, sizeof(double));
  ls->Ms = calloc(M * M, sizeof(double));
  ls->rsc = calloc(3 * M, sizeof(double));         /* and q, q - tau scaled */
  ls->kwork = calloc(3 * M, sizeof(int));
  ls->warm = ls->m <= LCP_BLOCKS_MAX_M;
  if (ls->warm && (lcp_blocks_init(&ls->blocks, ls->m) || lcp_modes_init(&ls->modes, ls->n, ls->m) ||
                   !(ls->wscr = calloc(5 * M, sizeof(double)))))
    return CUP_ERR_NOMEM;
  if (!ls->D || !ls->geff || !ls->WB || !ls->Hprev || !ls->carry || !ls->xpred || !ls->q0 || !ls->dcol0 ||
      !ls->kcol || !ls->Z || !ls->work || !ls->kwork || !ls->Ms || !ls->rsc || lcp_monotone(&ls->lcp))
    return CUP_ERR_NOMEM;
  int m = ls->m;
  memcpy(ls->D, D, sizeof(double) * (size_t)m * m);
  ls->theta = theta;
  for (int j = 0; j < m; j++) {
    ls->dcol0[j] = 1;
    for (int i = 0; i < m; i++)
      if (D[i + (size_t)j * m] != 0) ls->dcol0[j] = 0;
  }
  return CUP_OK;
}

int lcp_step_init_bd(lcp_step *ls, const cup_polyset *K, const double *W, double h,
                     const double *B, const double *D, double theta) {
  memset(ls, 0, sizeof *ls);
  if (!K->dense) return CUP_ERR_UNSUPPORTED;
  int n = ls->n = K->n, m = ls->m = K->m;
  ls->K = K;
  ls->h = h;
  size_t N = (size_t)n, M = (size_t)m + 1;
  /* H, M, s, gam, v, tau, qs, sv, gamv: one zeroed block that H owns (a
   * switched run makes one of these a configuration) */
  ls->H = calloc(N * M + M * M + 6 * M + N + 1, sizeof(double));
  if (ls->H) {
    ls->M = ls->H + N * M;
    ls->s = ls->M + M * M; ls->gam = ls->s + M; ls->v = ls->gam + M;
    ls->tau = ls->v + N; ls->qs = ls->tau + M; ls->sv = ls->qs + M; ls->gamv = ls->sv + M;
  }
  int fail = lcp_init(&ls->lcp, m);
  if (fail || !ls->H) return CUP_ERR_NOMEM;
  if (D && init_d(ls, D, theta)) return CUP_ERR_NOMEM;
  /* H = h W B with B = P^-1 C^T (the polyset's Bt, exact by P B = C^T), or
   * the B given; with D, the weights of build_hm */
  for (int i = 0; i < m; i++)
    for (int r = 0; r < n; r++) {
      const double *b = B ? B + (size_t)i * n : K->Bt + (size_t)i * n;
      double acc = 0;
      if (W)
        for (int c = 0; c < n; c++) acc += W[r + (size_t)c * n] * b[c];
      else
        acc = b[r];
      if (!D) {
        ls->H[r + (size_t)i * n] = h * acc;
        continue;
      }
      ls->WB[r + (size_t)i * n] = acc;
      if (!ls->dcol0[i]) ls->Hprev[r + (size_t)i * n] = h * (1 - theta) * acc;
    }
  if (D) {
    build_hm(ls);
  } else {
    for (int j = 0; j < m; j++)                    /* M = C H */
      for (int i = 0; i < m; i++) {
        double acc = 0;
        for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) acc += K->Ct.x[k] * ls->H[K->Ct.i[k] + (size_t)j * n];
        ls->M[i + (size_t)j * m] = acc;
      }
  }
  small_init(ls);
  return CUP_OK;
}

void lcp_step_free(lcp_step *ls) {
  free(ls->H);                                     /* (M, s, gam, v, tau, qs, sv, gamv in its block) */
  free(ls->D); free(ls->geff); free(ls->WB); free(ls->Hprev);
  free(ls->carry); free(ls->xpred); free(ls->q0); free(ls->dcol0); free(ls->kcol); free(ls->Z);
  free(ls->work); free(ls->kwork); free(ls->Ms); free(ls->rsc); free(ls->wscr);
  lcp_blocks_free(&ls->blocks);
  lcp_modes_free(&ls->modes);
  lcp_free(&ls->lcp);
  memset(ls, 0, sizeof *ls);
}

/* A pivot of D_JJ, equilibrated (every row's and column's largest entry 1),
 * below this is a zero: D's entries are resistances and the +-1 of a
 * bridge's cutsets, whose cancellations leave rounding only. */
#define KER_TOL 1e-12

/* ker D_JJ for the support J (a bit per row), by complete pivoting on D_JJ
 * equilibrated by rows, then columns (w_i and zeta_j are volts or amperes
 * by row and column, so only a scaled pivot means anything): its free
 * columns T, less those of dcol0, into nk, kc, and the vectors z_t
 * (z_t[t] = 1, 0 on the other free columns) into Zn, m x nk. */
static void kernel_of(lcp_step *ls, unsigned long long J, int *nk, int *kc, double *Zn) {
  int m = ls->m, p = 0;
  int *idx = ls->kwork, *pr = idx + m, *pc = pr + m;
  double *A = ls->work, *cs = A + (size_t)m * m, *z = cs + m;
  for (int i = 0; i < m; i++)
    if (J >> i & 1) idx[p++] = i;
  for (int b = 0; b < p; b++) {
    pr[b] = pc[b] = b;
    for (int a = 0; a < p; a++) A[a + (size_t)b * p] = ls->D[idx[a] + (size_t)idx[b] * m];
  }
  for (int a = 0; a < p; a++) {                   /* rows, then columns, to largest entry 1 */
    double r = 0;
    for (int b = 0; b < p; b++) r = la_max(r, fabs(A[a + (size_t)b * p]));
    for (int b = 0; r > 0 && b < p; b++) A[a + (size_t)b * p] /= r;
  }
  for (int b = 0; b < p; b++) {
    double c = 0;
    for (int a = 0; a < p; a++) c = la_max(c, fabs(A[a + (size_t)b * p]));
    cs[b] = c > 0 ? c : 1;
    for (int a = 0; a < p; a++) A[a + (size_t)b * p] /= cs[b];
  }
  int r = 0;
  for (; r < p; r++) {                            /* eliminate, the largest remaining entry first */
    int bi = r, bj = r;
    double best = 0;
    for (int j = r; j < p; j++)
      for (int i = r; i < p; i++)
        if (fabs(A[pr[i] + (size_t)pc[j] * p]) > best) best = fabs(A[pr[i] + (size_t)pc[j] * p]), bi = i, bj = j;
    if (!(best > KER_TOL)) break;
    int t = pr[r]; pr[r] = pr[bi]; pr[bi] = t;
    t = pc[r]; pc[r] = pc[bj]; pc[bj] = t;
    double piv = A[pr[r] + (size_t)pc[r] * p];
    for (int i = r + 1; i < p; i++) {
      double f = A[pr[i] + (size_t)pc[r] * p] / piv;
      if (f == 0) continue;
      for (int j = r; j < p; j++) A[pr[i] + (size_t)pc[j] * p] -= f * A[pr[r] + (size_t)pc[j] * p];
    }
  }
  *nk = 0;
  for (int f = r; f < p; f++) {                   /* back substitution on the pivot rows */
    int t = idx[pc[f]];
    if (ls->dcol0[t]) continue;                   /* z_t = e_t, weighted whole already */
    for (int b = 0; b < p; b++) z[b] = 0;
    z[pc[f]] = 1;
    for (int k = r - 1; k >= 0; k--) {
      double acc = 0;
      for (int j = k + 1; j < p; j++) acc += A[pr[k] + (size_t)pc[j] * p] * z[pc[j]];
      z[pc[k]] = -acc / A[pr[k] + (size_t)pc[k] * p];
    }
    double *out = Zn + (size_t)*nk * m;           /* D_JJ diag(1/cs) z' = 0: z = z' / cs, z_t = 1 */
    for (int i = 0; i < m; i++) out[i] = 0;
    for (int b = 0; b < p; b++) out[idx[b]] = z[b] / cs[b] * cs[pc[f]];
    out[t] = 1;
    kc[(*nk)++] = t;
  }
}

/* The weights for the support J: 1 when H and M changed (another kernel),
 * 0 when those in force are J's. With theta = 1 every weight is 1. A
 * warm step keeps each mode's kernel and matrices (mode.h): functions of
 * J alone, copied they are the same bits. */
int set_mode(lcp_step *ls, unsigned long long J) {
  ls->mode = J;
  if (ls->theta == 1) return 0;
  int m = ls->m, nk;
  int *kc = ls->kcol + m + 1;                     /* the second halves: J's kernel, to compare */
  double *Zn = ls->Z + (size_t)(m + 1) * (m + 1);
  lcp_mode *E = ls->warm ? lcp_modes_get(&ls->modes, J) : NULL;
  if (E && E->state) {
    nk = E->nk, kc = E->kc, Zn = E->Z;
  } else {
    kernel_of(ls, J, &nk, kc, Zn);
    if (E) {
      E->nk = nk;
      memcpy(E->kc, kc, sizeof(int) * (size_t)nk);
      memcpy(E->Z, Zn, sizeof(double) * (size_t)nk * m);
      E->state = 1;
    }
  }
  if (nk == ls->nker && !memcmp(kc, ls->kcol, sizeof(int) * (size_t)nk) &&
      !memcmp(Zn, ls->Z, sizeof(double) * (size_t)nk * m))
    return 0;
  ls->nker = nk;
  memcpy(ls->kcol, kc, sizeof(int) * (size_t)nk);
  memcpy(ls->Z, Zn, sizeof(double) * (size_t)nk * m);
  if (E && E->state == 2) {
    lcp_mode_copy(E, ls->H, ls->M, ls->Ms, ls->rsc, &ls->lam_sparse, 0);
    lcp_blocks_clear(&ls->blocks);                /* they were the old M's */
  } else {
    build_hm(ls);
    if (E) lcp_mode_copy(E, ls->H, ls->M, ls->Ms, ls->rsc, &ls->lam_sparse, 1), E->state = 2;
  }
  return 1;
}

/* carry = Pi zeta: zeta less its part in the kernel, sum_t zeta_t z_t
 * (0 on D's zero columns), for the nk kernel vectors Z (free columns kc)
 * of the support J; zeta_j off J counts as 0. */
static void carry_on(lcp_step *ls, unsigned long long J, int nk, const int *kc, const double *Z) {
  int m = ls->m;
  const double *lam = ls->lcp.lam;
  for (int j = 0; j < m; j++) ls->carry[j] = ls->dcol0[j] || !(J >> j & 1) ? 0 : lam[j];
  for (int k = 0; k < nk; k++) {
    double zt = lam[kc[k]];
    if (zt == 0) continue;
    const double *z = Z + (size_t)k * m;
    for (int j = 0; j < m; j++)
      if (z[j] != 0) ls->carry[j] -= zt * z[j];
    ls->carry[kc[k]] = 0;
  }
}

/* The carry of the last zeta (aimed: solved with the aims tau). An entry
 * zeta_j whose every effect on the rows, |M_ij| zeta_j, is within 4 tau_i
 * is the aims', not the state's: a row pinned by two others (a bridge
 * that blocks, i(L1) = 0 between D1-D3's and D2-D4's rows, a set without
 * interior) holds z within its aims only through such a zeta_j (D4's
 * 1e-15 A at i = -5e-16). Counted in the support, it made the leg's
 * voltage multiplier a function of the state (D_JJ nonsingular on {D3,
 * D4}), and its carry pushed i(L1) off 0 by 100 V h / (2 L) in the next
 * step. The part of zeta that is a function of the state is that of the
 * support without them (their kernel), and they carry nothing. */
void carry_of(lcp_step *ls, int aimed) {
  int m = ls->m;
  const double *lam = ls->lcp.lam;
  unsigned long long J = 0, keep = 0;
  for (int j = 0; aimed && j < m; j++) {
    if (!(lam[j] > 0)) continue;
    J |= 1ull << j;
    int moves = 0, beyond = 0;                    /* (a column that moves no row is kept: it is no aim's) */
    for (int i = 0; i < m && !beyond; i++) {
      double e = fabs(ls->M[i + (size_t)j * m]) * lam[j];
      beyond = e > 4 * ls->tau[i];
      moves |= e > 0;
    }
    if (beyond || !moves) keep |= 1ull << j;
  }
  if (keep == J) {
    carry_on(ls, ~0ull, ls->nker, ls->kcol, ls->Z);
    return;
  }
  int nk, *kc = ls->kcol + m + 1;                 /* (set_mode's second halves: free after it) */
  double *Z = ls->Z + (size_t)(m + 1) * (m + 1);
  kernel_of(ls, keep, &nk, kc, Z);
  carry_on(ls, keep, nk, kc, Z);
}

/* With D, a step carries the weights in force (the support they were set
 * for: its kernel makes H and M) and Pi zeta to the next as well. */
void lcp_step_checkpoint(lcp_step *ls, ckpt *c) {
  ckpt_io(c, ls->lcp.lam, sizeof(double) * (size_t)ls->m);
  ckpt_io(c, ls->lcp.prev, (size_t)ls->m);
  CUP_CKPT_IO(c, ls->lq);
  if (!ls->D) return;
  unsigned long long mode = ls->mode;
  CUP_CKPT_IO(c, mode);
  ckpt_io(c, ls->carry, sizeof(double) * (size_t)ls->m);
  if (!c->saving && c->buf && !c->bad) set_mode(ls, mode);
}

/* The dense rows of a small set without D; small stays 0 otherwise (or
 * where a row repeats a column, whose sparse sum would round differently). */
static void small_init(lcp_step *ls) {
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
