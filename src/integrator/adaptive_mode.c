/* adaptive_mode — one active set's linear system and its exact flow, and
 * the choice of the active set by the velocity LCP (adaptive_impl.h). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_complex_math.h>
#include <gsl/gsl_errno.h>
#include "catchup.h"
#include "adaptive_impl.h"

/* Pivots of S_J below this share of its largest diagonal mark a row that
 * depends on the others: it is dropped from J (it holds when they do). */
#define AD_RANK_TOL 1e-12

/* Does ad_expm_mv read an exponential's input rows by their nonzeros (ep,
 * ei, ex)? Only past 8 flow states with at most 6 of the circuit's: up to
 * 8, ad_matvec's dense sums; with more circuit states, its generic ones.
 * Elsewhere expm_into leaves them unwritten, and they are not laid out
 * (NULL). */
static inline int expm_rows_read(const adaptive_ws *A) { return A->na > 8 && A->n <= 6; }

/* Exponential c of md's cache. */
static inline void cache_layout(const adaptive_ws *A, ad_mode *md, int c, size_t NA, block_arena *b) {
  md->Ec[c] = block_take(b, NA, sizeof(double));
  if (!expm_rows_read(A)) {
    md->ep[c] = md->ei[c] = NULL;
    md->ex[c] = NULL;
    return;
  }
  md->ep[c] = block_take(b, (size_t)A->na + 1, sizeof(int));
  md->ei[c] = block_take(b, NA, sizeof(int));
  md->ex[c] = block_take(b, NA, sizeof(double));
}

/* A slot's set and its first ncache exponentials. */
static inline void slot_layout(const adaptive_ws *A, ad_mode *md, int ncache, block_arena *b) {
  int n = A->n, m = A->m, na = A->na, nw = A->nw;
  size_t NA = (size_t)na * na;
  md->rows = block_take(b, (size_t)m + 1, sizeof(int));
  md->M = block_take(b, NA, sizeof(double));
  md->mp = block_take(b, (size_t)na + 1, sizeof(int));
  md->mi = block_take(b, NA, sizeof(int));
  md->mj = block_take(b, NA, sizeof(int));
  md->mx = block_take(b, NA, sizeof(double));
  md->lp = block_take(b, (size_t)m + 1, sizeof(int));
  md->li = block_take(b, (size_t)m * na, sizeof(int));
  md->lx = block_take(b, (size_t)m * na, sizeof(double));
  md->lmx = block_take(b, (size_t)m * na, sizeof(double));
  md->L = block_take(b, (size_t)m * na, sizeof(double));
  md->Lc = block_take(b, (size_t)m, sizeof(double));
  md->is_zeta = block_take(b, (size_t)m, 1);
  md->X = block_take(b, (size_t)n * na, sizeof(double));
  md->R = block_take(b, (size_t)n * m, sizeof(double));
  md->Zt = block_take(b, (size_t)m * m, sizeof(double));
  md->KU = block_take(b, (size_t)n * nw, sizeof(double));
  for (int c = 0; c < ncache; c++) cache_layout(A, md, c, NA, b);
}

/* The slots in the order the run first writes them (a page the run
 * touches first is a page fault, 2.3 us). The first set is built in the
 * spare (last), whose buffers go to slot 0 and stay there as long as it is
 * kept: a switched run's configuration with one set, whose cache takes
 * several step lengths; they come first, with its three exponentials.
 * Then slot 0's buffers, slot 1's, ..., each set written whole with its
 * first exponential; a second and a third come for other step lengths
 * only when a set is used long. Those are laid out apart, last: slot by
 * slot, the six-pulse bridge's 10 sets spread over 22 pages, each one
 * touched (12 now). */
void ad_modes_layout(adaptive_ws *A, block_arena *b) {
  size_t NA = (size_t)A->na * A->na;
  if (!b->base) {                                /* sizing: AD_MODES + 1 sets and 3 AD_MODES + 3 exponentials
                                                    (each piece rounded alone: the sum's order is free) */
    ad_mode md;
    block_arena one = {0}, cache = {0};
    slot_layout(A, &md, 0, &one);
    cache_layout(A, &md, 0, NA, &cache);
    b->used += (AD_MODES + 1) * one.used + (AD_MODES * AD_CACHE + AD_CACHE) * cache.used;
    return;
  }
  slot_layout(A, &A->modes[AD_MODES], AD_CACHE, b);
  for (int s = 0; s < AD_MODES; s++) slot_layout(A, &A->modes[s], 1, b);
  for (int s = 0; s < AD_MODES; s++)
    for (int c = 1; c < AD_CACHE; c++) cache_layout(A, &A->modes[s], c, NA, b);
}

/* (A run's first set is built at its start: the slots are taken with it,
 * in the run, where the six-pulse bridge's 12 pages of them faulted in
 * fresh at their first sets, 1.7 us each, laid out at set-up before
 * catchup-run made its file.) */
int ad_modes_take(adaptive_ws *A) {
  if (A->slots) return CUP_OK;
  block_arena b = {0};
  ad_modes_layout(A, &b);
  if (!(A->slots = malloc(b.used))) return CUP_ERR_NOMEM;
  b = (block_arena){A->slots, 0};
  ad_modes_layout(A, &b);
  return CUP_OK;
}

void ad_scratch_layout(adaptive_ws *A, block_arena *b) {
  int n = A->n, m = A->m, na = A->na;
  ad_series *ser[] = {&A->sy, &A->se};
  for (int k = 0; k < 2; k++) {
    ser[k]->mag = block_take(b, (size_t)na, sizeof(double));
    ser[k]->v = block_take(b, (size_t)na, sizeof(double));
    ser[k]->dim = k ? n : na;
  }
  size_t big = ((size_t)n + m + 1) * ((size_t)na + m + 1);
  A->S = block_take(b, (size_t)m * m, sizeof(double));
  A->Sl = block_take(b, (size_t)m * m, sizeof(double));
  A->Sinv = block_take(b, (size_t)m * m, sizeof(double));
  A->T1 = block_take(b, big, sizeof(double));
  A->T2 = block_take(b, big, sizeof(double));
  A->T3 = block_take(b, big, sizeof(double));
  A->perm = block_take(b, (size_t)m + 1, sizeof(int));
}

void ad_series_layout(adaptive_ws *A, ad_series *S, block_arena *b) {
  /* (one spare block of na past the last term: piece_build clears the next term's sums as it scales one) */
  S->c = block_take(b, (AD_SERIES_SEGS * (AD_SERIES_MAX + 1) + 1) * (size_t)(A->na ? A->na : 1), sizeof(double));
}

/* Up to this many states the step limit's eigenvalues are a closed form
 * (mode_hmax): GSL's workspace is not allocated, nor touched in the run
 * (its first eigenproblem faulted two fresh pages in, some 5 us of a
 * buck-boost's 160). */
#define AD_EIG_CLOSED 2

int ad_modes_init(adaptive_ws *A) {
  size_t n = (size_t)A->n;
  if (A->n <= AD_EIG_CLOSED) return CUP_OK;
  A->eig = gsl_eigen_nonsymm_alloc(n);
  A->eigA = gsl_matrix_alloc(n, n);
  A->eigv = gsl_vector_complex_alloc(n);
  return A->eig && A->eigA && A->eigv ? CUP_OK : CUP_ERR_NOMEM;
}

void ad_modes_free(adaptive_ws *A) {
  if (A->eig) gsl_eigen_nonsymm_free(A->eig);
  if (A->eigA) gsl_matrix_free(A->eigA);
  if (A->eigv) gsl_vector_complex_free(A->eigv);
}

/* S = C_J P^-1 C_J^T from the set's dense M, and its pivoted Cholesky
 * factor in Sl; returns the rank. */
static int factor_S(adaptive_ws *A, const int *rows, int nj) {
  const double *Md = A->K->Md;
  int m = A->m;
  for (int b = 0; b < nj; b++)
    for (int a = 0; a < nj; a++) A->S[a + (size_t)b * nj] = Md[rows[a] + (size_t)rows[b] * m];
  memcpy(A->Sl, A->S, sizeof(double) * (size_t)nj * nj);
  return nj ? la_dense_pchol(A->Sl, nj, A->perm, AD_RANK_TOL) : 0;
}

void ad_row_of_C(const cup_polyset *K, int i, double *out) {
  la_zero(out, K->n);
  for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) out[K->Ct.i[k]] = K->Ct.x[k];
}

/* h within an eighth of the period of an eigenvalue's oscillation and the
 * time its growth takes to reach e. */
static double hmax_of(double h, double re, double im) {
  if (im > 0) h = fmin(h, M_PI / 4 / im);
  if (re > 0) h = fmin(h, 1 / re);
  return h;
}

/* mode_hmax of a 2 x 2 [a b; c d] (column-major in AJ): its eigenvalues
 * mid +- sqrt(p^2 + bc), p = (a - d) / 2, on entries scaled by a power of
 * 2 (exact) to 1; a real pair's larger one as det / (the other) when mid <
 * 0 (mid + r would cancel). */
static double hmax_2x2(double h, const double *AJ) {
  double s = fmax(fmax(fabs(AJ[0]), fabs(AJ[1])), fmax(fabs(AJ[2]), fabs(AJ[3])));
  if (!(s > 0) || !isfinite(s)) return h;
  int e = ilogb(s);
  double a = scalbn(AJ[0], -e), c = scalbn(AJ[1], -e), b = scalbn(AJ[2], -e), d = scalbn(AJ[3], -e);
  double mid = 0.5 * (a + d), p = 0.5 * (a - d), disc = p * p + b * c;
  if (disc < 0) return hmax_of(h, scalbn(mid, e), scalbn(sqrt(-disc), e));
  double r = sqrt(disc), lo = mid - r, hi = mid >= 0 || lo == 0 ? mid + r : (a * d - b * c) / lo;
  return hmax_of(h, scalbn(hi, e), 0);
}

/* The step limit of event detection for this active set: an eighth of the
 * period of its fastest oscillation (and of the input's), and the time an
 * unstable mode takes to grow by e; eigenvalues of Pi_J A by GSL (up to
 * AD_EIG_CLOSED states, closed forms). */
static double mode_hmax(adaptive_ws *A, const double *AJ) {
  int n = A->n;
  double h = A->hmax_input;
  if (n == 0) return h;
  if (n == 1) return hmax_of(h, AJ[0], 0);
  if (n == 2) return hmax_2x2(h, AJ);
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) gsl_matrix_set(A->eigA, (size_t)i, (size_t)j, AJ[i + (size_t)j * n]);
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  int bad = gsl_eigen_nonsymm(A->eigA, A->eigv, A->eig);
  gsl_set_error_handler(old);
  if (bad) return h;
  for (int i = 0; i < n; i++) {
    gsl_complex z = gsl_vector_complex_get(A->eigv, (size_t)i);
    h = hmax_of(h, GSL_REAL(z), fabs(GSL_IMAG(z)));
  }
  return h;
}

double ad_mode_hmax_first(adaptive_ws *A, ad_mode *md) {
  int n = A->n, na = A->na;                      /* Pi A, compact: an eigenproblem per mode used */
  double *AJ = A->T1;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) AJ[i + (size_t)j * n] = md->M[i + (size_t)j * na];
  return md->hmax = mode_hmax(A, AJ);
}

static ad_mode *kept(adaptive_ws *A, uint64_t mask);
static ad_mode *mode_get(adaptive_ws *A, uint64_t mask);

/* The rows of mask, an independent subset of them (the mode's mask says
 * which), and the inverse of S = C_J P^-1 C_J^T into A->Sinv; with D, of
 * N (ad_dae_factor) into A->Ninv, and Z^T into md->Zt. With lazy, a
 * subset that a kept mode holds already is left unfactored (ad_mode_get
 * takes that mode: a six-pulse bridge's commutations ask for three rows
 * that hold as two kept ones, which were factored again for nothing). */
static void mode_factor(adaptive_ws *A, ad_mode *md, uint64_t mask, int lazy) {
  int m = A->m, nj = 0;
  for (int i = 0; i < m; i++)
    if (mask >> i & 1) md->rows[nj++] = i;
  if (A->has_D) {
    int pending = 0;
    nj = ad_dae_factor(A, md->rows, nj, md->Zt, &md->nz, lazy ? &pending : NULL);
    if (pending) {
      uint64_t sub = 0;
      for (int k = 0; k < nj; k++) sub |= (uint64_t)1 << md->rows[k];
      if (!kept(A, sub)) ad_dae_refactor(A, md->rows, nj, md->Zt, &md->nz);
    }
  } else {
    int r = factor_S(A, md->rows, nj);
    if (r < nj) {                                /* keep an independent subset */
      int keep[CUP_DENSE_MAX_ROWS];
      for (int a = 0; a < r; a++) keep[a] = md->rows[A->perm[a]];
      mask = 0;
      for (int a = 0; a < r; a++) mask |= (uint64_t)1 << keep[a];
      nj = 0;
      for (int i = 0; i < m; i++)
        if (mask >> i & 1) md->rows[nj++] = i;
      factor_S(A, md->rows, nj);
    }
    double *work = A->T3;
    for (int k = 0; k < nj; k++) {               /* S^-1, column by column */
      double *col = A->Sinv + (size_t)k * nj, *ek = work + nj;
      la_zero(ek, nj);
      ek[k] = 1;
      la_dense_pchol_solve(A->Sl, nj, nj, A->perm, ek, col, work);
    }
    md->nz = nj;
  }
  md->mask = 0;
  for (int k = 0; k < nj; k++) md->mask |= (uint64_t)1 << md->rows[k];
  md->nj = nj;
}

/* With D: Y^T (C_J X + G_J U) and Y^T F_J (the rows that fix zeta_J
 * algebraically, r = nj - nz of them) into A->Ym (r x na, row-major) and
 * A->Ym + r na; the columns of Y are A->svd_v's first r. */
static inline __attribute__((always_inline)) void y_rows(adaptive_ws *A, const ad_mode *md, const double *CJ, int n,
                                                          int m, int na) {
  int nj = md->nj, r = nj - md->nz;
  const int *J = md->rows;
  double *Yc = A->Ym + (size_t)r * na;
  for (int b = 0; b < r; b++) {
    double *row = A->Ym + (size_t)b * na;
    Yc[b] = 0;
    for (int j = 0; j < na; j++) row[j] = 0;
    for (int a = 0; a < nj; a++) {
      double y = A->svd_v[(size_t)a * nj + b];
      if (y == 0) continue;
      Yc[b] += y * A->F[J[a]];
      for (int j = 0; j < na; j++) {
        double acc = 0;
        for (int l = 0; l < n; l++) acc += CJ[(size_t)a * n + l] * md->X[(size_t)l * na + j];
        for (int k = j >= n ? A->up[j - n] : 0; j >= n && k < A->up[j - n + 1]; k++)   /* G_J U */
          acc += A->G[J[a] + (size_t)A->ui[k] * m] * A->ux[k];
        row[j] += y * acc;
      }
    }
  }
}

/* R = B_J N^-1 on the Z rows (or S^-1), Pi = I - R Z^T C_J, KU, Q, X, and
 * the generator M; with D also Ry = B_J N^-1 on the Y rows (A->Ry) and the
 * Y rows' own terms of M. C_J goes to A->T1 (nj x n), Q to A->T3. */
static inline __attribute__((always_inline)) void mode_flow(adaptive_ws *A, ad_mode *md, int n, int m, int nw, int na) {
  const cup_polyset *K = A->K;
  int nj = md->nj, nz = md->nz, r = nj - nz;
  const int *J = md->rows;
  const double *Sinv = A->has_D ? A->Ninv : A->Sinv;
  const double *Bcol = A->has_D ? A->Bd : K->Bt;  /* column J_l of B: Bcol + J_l n (P^-1 C^T is K's Bt) */
  for (int k = 0; k < nz; k++)                   /* R = B_J S^-1 */
    for (int i = 0; i < n; i++) {
      double acc = 0;
      for (int l = 0; l < nj; l++) acc += Bcol[(size_t)J[l] * n + i] * Sinv[l + (size_t)(r + k) * nj];
      md->R[i + (size_t)k * n] = acc;
    }
  for (int k = 0; k < r; k++)                    /* Ry = B_J N^-1 on the Y rows */
    for (int i = 0; i < n; i++) {
      double acc = 0;
      for (int l = 0; l < nj; l++) acc += Bcol[(size_t)J[l] * n + i] * Sinv[l + (size_t)k * nj];
      A->Ry[i + (size_t)k * n] = acc;
    }
  double *CJ = A->T1, *Pi = A->T2;               /* C_J (nj x n, row-major), Pi = I - R C_J */
  for (int k = 0; k < nj; k++) ad_row_of_C(K, J[k], CJ + (size_t)k * n);
  const double *Zc = CJ;                         /* Z^T C_J (nz x n, row-major) */
  if (A->has_D) {
    for (int b = 0; b < nz; b++)
      for (int l = 0; l < n; l++) {
        double acc = 0;
        for (int a = 0; a < nj; a++) acc += md->Zt[(size_t)b * nj + a] * CJ[(size_t)a * n + l];
        A->Zc[(size_t)b * n + l] = acc;
      }
    Zc = A->Zc;
  }
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double acc = i == j;
      for (int k = 0; k < nz; k++) acc -= md->R[i + (size_t)k * n] * Zc[(size_t)k * n + j];
      Pi[i + (size_t)j * n] = acc;
    }
  for (int c = 0; c < nw; c++) {                 /* KU = R Z^T G_J U */
    double gu[CUP_DENSE_MAX_ROWS];               /* Z^T G_J U's column c */
    for (int k = 0; k < nz; k++) {
      gu[k] = 0;
      if (A->has_D)
        for (int a = 0; a < nj; a++)
          for (int e = A->up[c]; e < A->up[c + 1]; e++)
            gu[k] += md->Zt[(size_t)k * nj + a] * A->G[J[a] + (size_t)A->ui[e] * m] * A->ux[e];
      else
        for (int e = A->up[c]; e < A->up[c + 1]; e++) gu[k] += A->G[J[k] + (size_t)A->ui[e] * m] * A->ux[e];
    }
    for (int i = 0; i < n; i++) {
      double acc = 0;
      for (int k = 0; k < nz; k++) acc += md->R[i + (size_t)k * n] * gu[k];
      md->KU[i + (size_t)c * n] = acc;
    }
  }
  /* Q = [A, E U - A K U]: the free field A x + E u in terms of y = (v, w) */
  double *Q = A->T3;
  for (int j = 0; j < na; j++)
    for (int i = 0; i < n; i++) {
      double acc = 0;
      if (j < n) {
        acc = A->A[i + (size_t)j * n];
      } else {
        int c = j - n;
        for (int e = A->up[c]; e < A->up[c + 1]; e++) acc += A->E[i + (size_t)A->ui[e] * n] * A->ux[e];
        for (int k = 0; k < n; k++) acc -= A->A[i + (size_t)k * n] * md->KU[k + (size_t)c * n];
      }
      Q[i + (size_t)j * n] = acc;
    }
  memset(md->M, 0, sizeof(double) * (size_t)na * na);   /* M = [Pi Q; 0 W] */
  for (int j = 0; j < na; j++)
    for (int i = 0; i < n; i++) {
      double acc = 0;
      for (int k = 0; k < n; k++) acc += Pi[i + (size_t)k * n] * Q[k + (size_t)j * n];
      md->M[i + (size_t)j * na] = acc;
    }
  for (int j = 0; j < nw; j++)
    for (int i = 0; i < nw; i++) md->M[(n + i) + (size_t)(n + j) * na] = A->W[i + (size_t)j * nw];
  for (int i = 0; i < n; i++)                    /* X = [I, -KU], row-major */
    for (int j = 0; j < na; j++)
      md->X[(size_t)i * na + j] = j < n ? (i == j) : -md->KU[i + (size_t)(j - n) * n];
  if (r == 0) return;
  /* with D, the Y rows fix zeta: v' gains -Ry (Y^T (C_J x + G_J u + F_J)) */
  y_rows(A, md, CJ, n, m, na);
  const double *Yc = A->Ym + (size_t)r * na;
  for (int j = 0; j < na; j++)
    for (int i = 0; i < n; i++) {
      double acc = 0;
      for (int b = 0; b < r; b++) acc += A->Ry[i + (size_t)b * n] * A->Ym[(size_t)b * na + j];
      md->M[i + (size_t)j * na] -= acc;
    }
  if (A->one >= 0)
    for (int i = 0; i < n; i++) {
      double acc = 0;
      for (int b = 0; b < r; b++) acc += A->Ry[i + (size_t)b * n] * Yc[b];
      md->M[i + (size_t)(n + A->one) * na] -= acc;
    }
}

/* The event rows: zeta_J = -S^-1 (C_J Q y + G_J U W w) for the active rows
 * (with D, -N^-1 [Y^T (C_J X y + G_J U w + F_J); Z^T (C_J Q y + G_J U W w)]),
 * slack_i = C_i X y + G_i U w + F_i (+ D_iJ zeta_J) for the others; and the
 * magnitudes of their terms into Lm (m x na, row-major: |C_i| |X| for a
 * slack, a row that depends on the active ones has a tiny L_i but its slack
 * rounds at that), scratch: the slot keeps their nonzeros alone (lmx). */
static inline __attribute__((always_inline)) void mode_events(adaptive_ws *A, ad_mode *md, double *Lm, int n, int m,
                                                               int nw, int na) {
  const cup_polyset *K = A->K;
  int p = A->p, nj = md->nj, nz = md->nz, r = nj - nz;
  const int *J = md->rows;
  const double *Sinv = A->has_D ? A->Ninv : A->Sinv, *Q = A->T3;
  const double *Zc = A->has_D ? A->Zc : A->T1;
  double *crow = A->T1 + (size_t)nj * n, *CQ = A->T2;          /* nz x na, row-major */
  for (int k = 0; k < nz; k++)
    for (int j = 0; j < na; j++) {
      double acc = 0;
      for (int l = 0; l < n; l++) acc += Zc[(size_t)k * n + l] * Q[l + (size_t)j * n];
      if (j >= n) {
        int c = j - n;
        for (int q = 0; q < p; q++) {
          int live = 0;                          /* G_J's column q (else the terms are +-0) */
          for (int a = 0; a < nj && !live; a++) live = A->G[J[A->has_D ? a : k] + (size_t)q * m] != 0;
          if (!live) continue;
          double uw = 0;
          for (int d = 0; d < nw; d++) uw += A->U[q + (size_t)d * p] * A->W[d + (size_t)c * nw];
          if (A->has_D)
            for (int a = 0; a < nj; a++) acc += md->Zt[(size_t)k * nj + a] * A->G[J[a] + (size_t)q * m] * uw;
          else
            acc += A->G[J[k] + (size_t)q * m] * uw;
        }
      }
      CQ[(size_t)k * na + j] = acc;
    }
  const double *Yc = r > 0 ? A->Ym + (size_t)r * na : NULL;   /* NULL without D (no Y rows) */
  int kj[CUP_DENSE_MAX_ROWS];                    /* row i's place in J, or -1 */
  for (int i = 0; i < m; i++) kj[i] = -1;
  for (int a = 0; a < nj; a++) kj[J[a]] = a;
  for (int i = 0; i < m; i++) {                  /* the active rows first: the slacks use them */
    int k = kj[i];
    md->is_zeta[i] = k >= 0;
    if (k < 0) continue;
    double *Li = md->L + (size_t)i * na, *Lmi = Lm + (size_t)i * na;
    for (int j = 0; j < na; j++) {
      double acc = 0, mag = 0;
      for (int l = 0; l < nz; l++) {
        acc -= Sinv[k + (size_t)(r + l) * nj] * CQ[(size_t)l * na + j];
        mag += fabs(Sinv[k + (size_t)(r + l) * nj] * CQ[(size_t)l * na + j]);
      }
      for (int b = 0; b < r; b++) {
        acc -= Sinv[k + (size_t)b * nj] * A->Ym[(size_t)b * na + j];
        mag += fabs(Sinv[k + (size_t)b * nj] * A->Ym[(size_t)b * na + j]);
      }
      Li[j] = acc;
      /* with D, the terms' size: a multiplier that vanishes on this set (a
       * bridge diode held at zero current) is rounding of them */
      Lmi[j] = A->has_D ? mag : fabs(acc);
    }
    double lc = 0;
    for (int b = 0; b < r; b++) lc -= Sinv[k + (size_t)b * nj] * Yc[b];
    md->Lc[i] = lc;
  }
  for (int i = 0; i < m; i++) {
    if (kj[i] >= 0) continue;
    double *Li = md->L + (size_t)i * na, *Lmi = Lm + (size_t)i * na;
    ad_row_of_C(K, i, crow);
    for (int j = 0; j < na; j++) {
      double acc = 0, mag = 0;
      for (int l = 0; l < n; l++) {
        acc += crow[l] * md->X[(size_t)l * na + j];
        mag += fabs(crow[l] * md->X[(size_t)l * na + j]);
      }
      for (int e = j >= n ? A->up[j - n] : 0; j >= n && e < A->up[j - n + 1]; e++) {   /* G_i U */
        double gu = A->G[i + (size_t)A->ui[e] * m] * A->ux[e];
        acc += gu;
        mag += fabs(gu);
      }
      Li[j] = acc;
      Lmi[j] = mag;
    }
    md->Lc[i] = A->F[i];
    if (!A->has_D) continue;
    for (int a = 0; a < nj; a++) {               /* + D_iJ zeta_J */
      double d = A->Dd[i + (size_t)J[a] * m];
      if (d == 0) continue;
      const double *La = md->L + (size_t)J[a] * na, *Lma = Lm + (size_t)J[a] * na;
      for (int j = 0; j < na; j++) { Li[j] += d * La[j]; Lmi[j] += fabs(d) * Lma[j]; }
      md->Lc[i] += d * md->Lc[J[a]];
    }
  }
}

/* M's and the event rows' nonzeros, and Lm's (mode_events') where L or Lm
 * has one (the products over them skip only terms that are exactly 0: the
 * same sums, bit for bit). */
static inline __attribute__((always_inline)) void mode_sparse(ad_mode *md, const double *Lm, int m, int na) {
  int k = 0;
  for (int j = 0; j < na; j++) {
    md->mp[j] = k;
    for (int i = 0; i < na; i++) {
      double v = md->M[i + (size_t)j * na];
      if (v != 0) { md->mi[k] = i; md->mj[k] = j; md->mx[k++] = v; }
    }
  }
  md->mp[na] = k;
  k = 0;
  for (int i = 0; i < m; i++) {
    md->lp[i] = k;
    for (int j = 0; j < na; j++) {
      double l = md->L[(size_t)i * na + j], lm = Lm[(size_t)i * na + j];
      if (l != 0 || lm != 0) { md->li[k] = j; md->lx[k] = l; md->lmx[k++] = lm; }
    }
  }
  md->lp[m] = k;
}

/* (Terms with y_j = 0 are added too: +-0, which leaves a sum started at +0
 * as it was.) */
static inline void mode_mv_sparse(int na, const ad_mode *md, const double *y, double *out) {
  int nnz = md->mp[na];
  for (int i = 0; i < na; i++) out[i] = 0;
  for (int k = 0; k < nnz; k++) out[md->mi[k]] += md->mx[k] * y[md->mj[k]];
}

/* (A few components: ad_mode_mv_few's dense sums; the buck-boost's event
 * functions took 66 instructions a product by the nonzeros.) */
void ad_mode_mv(const adaptive_ws *A, const ad_mode *md, const double *y, double *out) {
  if (ad_mode_mv_few(A->na, md->M, y, out)) return;
  mode_mv_sparse(A->na, md, y, out);
}

/* The rest of a mode once mode_factor has chosen its rows, for the sizes
 * given (constants below). */
static inline __attribute__((always_inline)) void finish_sized(adaptive_ws *A, ad_mode *md, int n, int m, int nw,
                                                                int na) {
  /* (Lm past C_J and a row of C in T1: (m + 1) n + m na fits in its (n + m + 1) (na + m + 1)) */
  double *Lm = A->T1 + (size_t)(m + 1) * n;
  mode_flow(A, md, n, m, nw, na);
  mode_events(A, md, Lm, n, m, nw, na);
  mode_sparse(md, Lm, m, na);
  md->mnorm = md->snorm = 0;
  for (int i = 0; i < na; i++) {
    double r_ = 0, d_ = 0;
    for (int j = 0; j < na; j++) {
      r_ += fabs(md->M[i + (size_t)j * na]);
      if ((i < n) == (j < n)) d_ += fabs(md->M[i + (size_t)j * na]);
    }
    md->mnorm = la_fmax(md->mnorm, r_);
    md->snorm = la_fmax(md->snorm, d_);
  }
  md->hmax = -1;
  for (int c = 0; c < AD_CACHE; c++) { md->hc[c] = -1; md->cstamp[c] = 0; }
}

/* (A six-pulse bridge's 2 states, 2 input states and 6 rows as constants:
 * the same sums, unrolled; its 10 modes took 6 k instructions each here.) */
static void mode_finish(adaptive_ws *A, ad_mode *md) {
  if (A->n == 2 && A->nw == 2 && A->na == 4 && A->m == 6) { finish_sized(A, md, 2, 6, 2, 4); return; }
  finish_sized(A, md, A->n, A->m, A->nw, A->na);
}

static void mode_build(adaptive_ws *A, ad_mode *md, uint64_t mask) {
  mode_factor(A, md, mask, 0);
  mode_finish(A, md);
}

/* The kept mode whose rows are mask, or NULL. */
static ad_mode *kept(adaptive_ws *A, uint64_t mask) {
  for (int s = 0; s < AD_MODES; s++) {
    ad_mode *md = &A->modes[s];
    if (md->stamp && md->mask == mask) return md;
  }
  return NULL;
}

/* A set with a dependent row is built as an independent subset of it: the
 * subset is remembered (the same rows give the same subset), so that asking
 * for the set again finds the subset's mode without factoring the rows
 * again (a six-pulse bridge's commutation tries 3 rows that hold as 2, at
 * each event: 40 % of its run went to that). */
static uint64_t alias_of(const adaptive_ws *A, uint64_t mask) {
  for (int k = 0; k < AD_ALIASES; k++)
    if (A->alias_from[k] == mask && A->alias_to[k] != mask) return A->alias_to[k];
  return mask;
}

ad_mode *ad_mode_get_other(adaptive_ws *A, uint64_t mask) {
  ad_mode *md = A->got2;                 /* (a window's start with D tries the empty set, then its seed) */
  A->got2 = A->got;
  if (md && md->stamp && md->mask == mask) { md->stamp = ++A->clock; return A->got = md; }
  return A->got = mode_get(A, mask);
}

/* (A set's slot is the one with its mask and a stamp: kept's first.) */
static ad_mode *mode_get(adaptive_ws *A, uint64_t mask) {
  ad_mode *md = kept(A, mask);
  if (!md) {                             /* (a kept mode's rows are independent: no alias) */
    uint64_t sub = alias_of(A, mask);
    if (sub != mask) md = kept(A, mask = sub);
  }
  if (md) { md->stamp = ++A->clock; return md; }
  /* built in the spare slot first: a subset that is kept already takes
   * nothing from the others */
  ad_mode *spare = &A->modes[AD_MODES];
  mode_factor(A, spare, mask, 1);
  if (spare->mask != mask) {
    A->alias_from[A->nalias % AD_ALIASES] = mask;
    A->alias_to[A->nalias % AD_ALIASES] = spare->mask;
    A->nalias++;
    if ((md = kept(A, spare->mask))) { md->stamp = ++A->clock; return md; }
  }
  mode_finish(A, spare);
  ad_mode *oldest = NULL;                /* AD_MODES > 2: a slot that is not pinned exists */
  for (int s = 0; s < AD_MODES; s++) {
    md = &A->modes[s];
    if (md != A->pinned[0] && md != A->pinned[1] && (!oldest || md->stamp < oldest->stamp)) oldest = md;
  }
  ad_mode t = *oldest;                   /* the least recently used gives its slot (and its buffers to the spare) */
  *oldest = *spare;
  *spare = t;
  spare->stamp = 0;
  oldest->stamp = ++A->clock;
  return oldest;
}

/* exp(h M_J) into slot c of md's cache. */
static void expm_into(adaptive_ws *A, ad_mode *md, double h, int c) {
  size_t NA = (size_t)A->na * A->na;
  double *hM = A->ework + 5 * NA;
  for (size_t q = 0; q < NA; q++) hM[q] = h * md->M[q];
  /* a stiff generator needs the small entries of exp - I kept (linalg.h):
   * the run reuses this exponential on every step */
  la_dense_expm_stiff(hM, A->na, md->Ec[c], A->ework);
  if (!expm_rows_read(A)) return;
  int n = A->n, na = A->na, k = 0;             /* the input states' rows' nonzeros (ad_expm_mv) */
  const double *E = md->Ec[c];
  for (int j = 0; j < na; j++) {
    md->ep[c][j] = k;
    for (int i = n; i < na; i++)
      if (E[i + (size_t)j * na] != 0) { md->ei[c][k] = i; md->ex[c][k++] = E[i + (size_t)j * na]; }
  }
  md->ep[c][na] = k;
}

void ad_mode_restore(adaptive_ws *A, int s, uint64_t mask, long stamp, const double *hc, const long *cstamp) {
  ad_mode *md = &A->modes[s];
  md->stamp = 0;
  if (!stamp) return;
  if (ad_modes_take(A)) { A->slots_lost = 1; return; }   /* (adaptive_resume refuses to go on) */
  mode_build(A, md, mask);
  for (int c = 0; c < AD_CACHE; c++) {
    if (hc[c] >= 0) expm_into(A, md, hc[c], c);
    md->hc[c] = hc[c];
    md->cstamp[c] = cstamp[c];
  }
  md->stamp = stamp;
}

const double *ad_expm_miss(adaptive_ws *A, ad_mode *md, double h) {
  int slot = 0;
  for (int c = 1; c < AD_CACHE; c++)
    if (md->cstamp[c] < md->cstamp[slot]) slot = c;
  expm_into(A, md, h, slot);
  md->hc[slot] = h;
  md->cstamp[slot] = ++A->clock;
  return md->Ec[slot];
}

/* ad_matvec for n of 7 or 8, apart from its body (inline there, the
 * registers cost the full bridge's sizes 3 and 4 3 k instructions). */
static __attribute__((noinline)) void matvec8(int n, int lda, const double *E, const double *y, double *out) {
  if (n == 7) ad_matvec_sums(7, lda, E, y, out);
  else ad_matvec_sums(8, lda, E, y, out);
}

void ad_matvec(int n, int lda, const double *E, const double *y, double *out) {
  switch (n) {                                   /* (a converter's states and sources: the loops unrolled) */
    case 1: ad_matvec_sums(1, lda, E, y, out); return;
    case 2: ad_matvec_sums(2, lda, E, y, out); return;
    case 3: ad_matvec_sums(3, lda, E, y, out); return;
    case 4: ad_matvec_sums(4, lda, E, y, out); return;
    case 5: ad_matvec_sums(5, lda, E, y, out); return;
    case 6: ad_matvec_sums(6, lda, E, y, out); return;
    case 7: case 8: matvec8(n, lda, E, y, out); return;
  }
  for (int i = 0; i < n; i++) out[i] = 0;
  for (int j = 0; j < n; j++) {
    double yj = y[j];
    if (yj == 0) continue;
    const double *col = E + (size_t)j * lda;
    for (int i = 0; i < n; i++) out[i] += col[i] * yj;
  }
}

/* The rows of the state (i < n, a constant: their sums in registers, over
 * every column) and those of the input's states over their nonzeros (from
 * expm_into): ad_matvec's generic sums less the terms of E's zeros, +-0
 * each, which leave a sum started at +0 as it was. */
static inline __attribute__((always_inline)) void expm_mv_sums(int n, int na, const double *E, const int *ep,
                                                               const int *ei, const double *ex,
                                                               const double *y, double *out) {
  double v[6] = {0};
  for (int i = n; i < na; i++) out[i] = 0;
  for (int j = 0; j < na; j++) {
    double yj = y[j];
    if (yj == 0) continue;
    for (int i = 0; i < n; i++) v[i] += E[i + (size_t)j * na] * yj;
    for (int k = ep[j]; k < ep[j + 1]; k++) out[ei[k]] += ex[k] * yj;
  }
  for (int i = 0; i < n; i++) out[i] = v[i];
}

void ad_expm_mv(const adaptive_ws *A, const ad_mode *md, const double *E, const double *y, double *out) {
  int n = A->n, na = A->na, c = 0;
  switch (na) {                                  /* (a converter's few states: ad_matvec's sums here, */
    case 1: ad_matvec_sums(1, 1, E, y, out); return;   /* without its call and register saves and the slot's */
    case 2: ad_matvec_sums(2, 2, E, y, out); return;   /* search, 70 of a full bridge's 116 instructions a */
    case 3: ad_matvec_sums(3, 3, E, y, out); return;   /* product) */
    case 4: ad_matvec_sums(4, 4, E, y, out); return;
  }
  while (c < AD_CACHE && md->Ec[c] != E) c++;
  /* (up to 8 rows, every sum in a register: a six-pulse bridge's 2 states
   * and 6 input states took 320 instructions a product by the input rows'
   * nonzeros, 260 so; E's zeros add +-0 to sums started at +0, which
   * leaves them as they were) */
  if (!expm_rows_read(A) || c == AD_CACHE) { ad_matvec(na, na, E, y, out); return; }
  const int *ep = md->ep[c], *ei = md->ei[c];
  const double *ex = md->ex[c];
  switch (n) {                                   /* (ad_lift's sizes) */
    case 1: expm_mv_sums(1, na, E, ep, ei, ex, y, out); return;
    case 2: expm_mv_sums(2, na, E, ep, ei, ex, y, out); return;
    case 3: expm_mv_sums(3, na, E, ep, ei, ex, y, out); return;
    case 4: expm_mv_sums(4, na, E, ep, ei, ex, y, out); return;
    case 5: expm_mv_sums(5, na, E, ep, ei, ex, y, out); return;
    default: expm_mv_sums(6, na, E, ep, ei, ex, y, out); return;
  }
}

/* ad_flow's Taylor substeps (na a constant for the few: M y by
 * ad_mode_mv_few's dense sums in registers, the terms' loops unrolled; the
 * same sums as ad_mode_mv's). */
static inline __attribute__((always_inline)) void flow_taylor(adaptive_ws *A, const ad_mode *md, int na, int sub,
                                                              double dt, const double *y_in, double *y_out) {
  double *term = A->fa, *tmp = A->fb;
  la_copy(y_out, y_in, na);
  for (int s = 0; s < sub; s++) {
    la_copy(term, y_out, na);
    for (int k = 1; k <= 30; k++) {
      if (na > 4 || !ad_mode_mv_few(na, md->M, term, tmp)) mode_mv_sparse(na, md, term, tmp);
      /* done when every component's term is below its rounding: a callback's
       * Taylor states (u, u', ..., u^(7)) span 20 orders of magnitude, and a
       * test against the largest stopped x's series at 1e-5 of x */
      int done = 1;
      for (int i = 0; i < na; i++) {
        term[i] = tmp[i] * dt / k;
        y_out[i] += term[i];
        done &= fabs(term[i]) <= 0.25 * DBL_EPSILON * fabs(y_out[i]);
      }
      if (done) break;
    }
  }
}

void ad_flow(adaptive_ws *A, ad_mode *md, double tau, const double *y_in, double *y_out) {
  int na = A->na;
  for (int c = 0; c < AD_CACHE; c++)
    if (md->hc[c] == tau) { ad_expm_mv(A, md, md->Ec[c], y_in, y_out); return; }
  double norm = fabs(tau) * md->mnorm;
  if (norm > 4) {                                /* stiff or long: the full exponential */
    size_t NA = (size_t)na * na;
    double *hM = A->ework + 5 * NA, *Et = A->ework + 6 * NA;
    for (size_t q = 0; q < NA; q++) hM[q] = tau * md->M[q];
    la_dense_expm_stiff(hM, na, Et, A->ework);
    ad_matvec(na, na, Et, y_in, y_out);
    return;
  }
  /* substeps of norm <= 1/2, each a Taylor series to its last term below
   * eps: na^2 per term instead of na^3 per matrix product */
  int sub = norm > 0.5 ? (int)ceil(norm / 0.5) : 1;
  double dt = tau / sub;
  if (na == 4) flow_taylor(A, md, 4, sub, dt, y_in, y_out);   /* (the six-pulse bridge's 2 + 2: 748
                                                                 instructions an event's flow, 379 so) */
  else flow_taylor(A, md, na, sub, dt, y_in, y_out);
}

/* ad_lift with nw a constant too, the input's states copied unrolled (two
 * states and 1 to 3 input states, the sizes the examples and tests reach;
 * the six-pulse bridge's 6 input states before 865d3b5, whose lift, a
 * record's and a mode check's, was 143 instructions, 104 so). */
static inline __attribute__((always_inline)) void lift_fixed(int n, int nw, const ad_mode *md, const double *x,
                                                             const double *w, double *y) {
  ad_lift_sums(n, nw, md->KU, x, w, y);
  for (int c = 0; c < nw; c++) y[n + c] = w[c];
}

/* (Each y_i its sum in a register, over the columns in order: a record's
 * lift on the six-pulse bridge, 2 states and 9 input states then, spent more
 * on the loops' set-up than on its 18 products.) */
static __attribute__((noinline)) void lift_any(const adaptive_ws *A, const ad_mode *md, const double *x,
                                                const double *w, double *y) {
  int n = A->n, nw = A->nw;
  if (n == 2 && nw >= 1 && nw <= 3) {
    switch (nw) {
      case 1: lift_fixed(2, 1, md, x, w, y); return;
      case 2: lift_fixed(2, 2, md, x, w, y); return;
      case 3: lift_fixed(2, 3, md, x, w, y); return;
    }
  }
  switch (n) {                                   /* (a converter's few states: the loops unrolled) */
    case 1: ad_lift_sums(1, nw, md->KU, x, w, y); break;
    case 2: ad_lift_sums(2, nw, md->KU, x, w, y); break;
    case 3: ad_lift_sums(3, nw, md->KU, x, w, y); break;
    case 4: ad_lift_sums(4, nw, md->KU, x, w, y); break;
    case 5: ad_lift_sums(5, nw, md->KU, x, w, y); break;
    case 6: ad_lift_sums(6, nw, md->KU, x, w, y); break;
    default:
      la_copy(y, x, n);
      for (int c = 0; c < nw; c++) {
        double wc = w[c];
        if (wc == 0) continue;
        for (int i = 0; i < n; i++) y[i] += md->KU[i + (size_t)c * n] * wc;
      }
  }
  la_copy_few(y + n, w, nw);
}

/* Two states and one or two input states (the bridges': a DC source, a
 * pair of a sine's) here, the rest in lift_any: its switches' registers,
 * saved and restored a call, were a third of a full bridge's lift. */
void ad_lift(const adaptive_ws *A, const ad_mode *md, const double *x, const double *w, double *y) {
  if (A->n == 2 && A->nw == 1) { lift_fixed(2, 1, md, x, w, y); return; }
  if (A->n == 2 && A->nw == 2) { lift_fixed(2, 2, md, x, w, y); return; }
  lift_any(A, md, x, w, y);
}

/* x = X y for a constant na: la_dot's sums, unrolled. */
static inline __attribute__((always_inline)) void state_sums(int n, int na, const double *X, const double *y,
                                                             double *x) {
  for (int i = 0; i < n; i++) x[i] = la_dot(X + (size_t)i * na, y, na);
}

static __attribute__((noinline)) void state_any(const adaptive_ws *A, const ad_mode *md, const double *y,
                                                 double *x) {
  int n = A->n, na = A->na;
  switch (na) {                                  /* (ad_lift's sizes; two states: both loops unrolled) */
    case 1: state_sums(n, 1, md->X, y, x); return;
    case 2: if (n == 2) state_sums(2, 2, md->X, y, x); else state_sums(n, 2, md->X, y, x); return;
    case 3: if (n == 2) state_sums(2, 3, md->X, y, x); else state_sums(n, 3, md->X, y, x); return;
    case 4: if (n == 2) state_sums(2, 4, md->X, y, x); else state_sums(n, 4, md->X, y, x); return;
    case 5: state_sums(n, 5, md->X, y, x); return;
    case 6: state_sums(n, 6, md->X, y, x); return;
  }
  state_sums(n, na, md->X, y, x);
}

/* Two states and one or two input states (the bridges') here, the rest in
 * state_any: its switch's register saves were a third of the call. */
void ad_state(const adaptive_ws *A, const ad_mode *md, const double *y, double *x) {
  if (A->n == 2 && A->na == 3) { state_sums(2, 3, md->X, y, x); return; }
  if (A->n == 2 && A->na == 4) { state_sums(2, 4, md->X, y, x); return; }
  state_any(A, md, y, x);
}

/* U w and F + G u by their nonzeros (offset_pattern), in the dense
 * products' order: the same sums, less the terms that are zero. */
void ad_offset(const adaptive_ws *A, const double *w, double *g) {
  int m = A->m, nw = A->nw;
  if (A->w_const && ad_same_bits(w, A->wc, nw)) {   /* DC sources alone: made once (constant_inputs) */
    la_copy_few(A->ut, A->uc, A->p);
    la_copy_few(g, A->gc, m);
    return;
  }
  la_zero_few(A->ut, A->p);                      /* (a few inputs: no memset call) */
  for (int c = 0; c < nw; c++)
    for (int k = A->up[c]; k < A->up[c + 1]; k++) A->ut[A->ui[k]] += A->ux[k] * w[c];
  ad_offset_of(A, A->ut, g);
}

void ad_offset_of(const adaptive_ws *A, const double *u, double *g) {
  for (int i = 0; i < A->m; i++) {
    double acc = A->F[i];
    for (int k = A->gp[i]; k < A->gp[i + 1]; k++) acc += A->gx[k] * u[A->gi[k]];
    g[i] = acc;
  }
}

/* x -= R s, each x_i in a register for a constant n. */
static inline __attribute__((always_inline)) void manifold_sums(int n, int nz, const double *R, const double *s,
                                                                double *x) {
  double v[6];
  for (int i = 0; i < n; i++) v[i] = x[i];
  for (int k = 0; k < nz; k++)
    for (int i = 0; i < n; i++) v[i] -= R[i + (size_t)k * n] * s[k];
  for (int i = 0; i < n; i++) x[i] = v[i];
}

void ad_manifold(const adaptive_ws *A, const ad_mode *md, const double *g, double *x) {
  const cup_polyset *K = A->K;
  int n = A->n;
  if (!md->nz) return;                           /* (with D, rows that fix zeta alone: nothing to move) */
  for (int k = 0; k < md->nj; k++) {
    int i = md->rows[k];
    double r_ = g[i];
    for (int q = K->Ct.p[i]; q < K->Ct.p[i + 1]; q++) r_ += K->Ct.x[q] * x[K->Ct.i[q]];
    A->s[k] = r_;
  }
  const double *s = A->s;
  if (A->has_D) {                                /* the manifold's rows are Z^T's */
    for (int b = 0; b < md->nz; b++) {
      double acc = 0;
      for (int a = 0; a < md->nj; a++) acc += md->Zt[(size_t)b * md->nj + a] * A->s[a];
      A->sz[b] = acc;
    }
    s = A->sz;
  }
  switch (n) {                                   /* (ad_lift's sizes) */
    case 1: manifold_sums(1, md->nz, md->R, s, x); return;
    case 2: manifold_sums(2, md->nz, md->R, s, x); return;
    case 3: manifold_sums(3, md->nz, md->R, s, x); return;
    case 4: manifold_sums(4, md->nz, md->R, s, x); return;
    case 5: manifold_sums(5, md->nz, md->R, s, x); return;
    case 6: manifold_sums(6, md->nz, md->R, s, x); return;
  }
  for (int k = 0; k < md->nz; k++)
    for (int i = 0; i < n; i++) x[i] -= md->R[i + (size_t)k * n] * s[k];
}

void ad_free_velocity(adaptive_ws *A, const double *x, const double *w) {
  int n = A->n, p = A->p, nw = A->nw;
  for (int q = 0; q < p; q++) A->udot[q] = 0;
  for (int c = 0; c < nw; c++) {                 /* u' = U (W w) by U's nonzeros */
    if (A->up[c] == A->up[c + 1]) continue;
    double wd = 0;
    for (int d = 0; d < nw; d++) wd += A->W[c + (size_t)d * nw] * w[d];
    for (int e = A->up[c]; e < A->up[c + 1]; e++) A->udot[A->ui[e]] += A->ux[e] * wd;
  }
  for (int i = 0; i < n; i++) {
    double acc = 0;
    for (int j = 0; j < n; j++) acc += A->A[i + (size_t)j * n] * x[j];
    for (int q = 0; q < p; q++) acc += A->E[i + (size_t)q * n] * A->ut[q];
    A->xf[i] = acc;
  }
}

int ad_select(adaptive_ws *A, const double *x, const double *w, uint64_t hint, uint64_t *mask,
              int *pivots) {
  ad_offset(A, w, A->g);                         /* also leaves u in A->ut */
  return ad_select_at(A, x, w, hint, mask, pivots);
}

int ad_select_at(adaptive_ws *A, const double *x, const double *w, uint64_t hint, uint64_t *mask,
                 int *pivots) {
  polyset_slack(A->K, A->g, x, A->s, NULL);
  return ad_select_slack(A, x, w, hint, mask, pivots);
}

int ad_select_slack(adaptive_ws *A, const double *x, const double *w, uint64_t hint, uint64_t *mask,
                    int *pivots) {
  const cup_polyset *K = A->K;
  int n = A->n, m = A->m, p = A->p;
  /* touching rows: slack at the level a certified projection leaves (it
   * aims a few rounding bounds inside), on the scale of the whole state (a
   * row whose own terms vanish still rounds at that scale) */
  double xn = 0;
  for (int j = 0; j < n; j++) xn = la_max(fabs(x[j]), xn);   /* (fmax without the call) */
  const double *Md = K->Md;
  unsigned char *touch = A->touch;
  int touching = 0;
  for (int i = 0; i < m; i++) {
    touch[i] = (hint >> i & 1) || A->s[i] <= 64 * DBL_EPSILON * (fabs(A->g[i]) + A->c1[i] * xn);
    touching |= touch[i];
  }
  if (!touching && lcp_cold(&A->lcp)) {
    /* the LCP is lambda + 1 (every row decoupled): lambda = 0, as
     * lcp_solve finds it from a cold start with no pivot (the usual case:
     * a window starts cold, and no row touches between a PWM's edges) */
    for (int i = 0; i < m; i++) { A->lcp.lam[i] = 0; A->lcp.w[i] = 1; }
    *mask = 0;
    return CUP_OK;
  }
  /* u', and the free velocity f = A x + E u: the touching rows' q (none
   * touches between a PWM's edges in most windows) */
  double *f = A->xf;
  if (touching) ad_free_velocity(A, x, w);
  for (int i = 0; i < m; i++) {
    double qi = 1;
    if (touch[i]) {
      qi = 0;
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) qi += K->Ct.x[k] * f[K->Ct.i[k]];
      for (int q = 0; q < p; q++) qi += A->G[i + (size_t)q * m] * A->udot[q];
    }
    A->lcpq[i] = qi;
    /* rows that do not touch are decoupled (identity, q = 1: lambda = 0) */
    for (int j = 0; j < m; j++)
      A->lcpM[i + (size_t)j * m] = touch[i] && touch[j] ? Md[i + (size_t)j * m] : (i == j);
  }
  int st = m ? lcp_solve(&A->lcp, A->lcpM, A->lcpq, pivots) : CUP_OK;
  if (st) {
    /* More touching rows than independent directions (a degenerate corner)
     * make M singular, and pivoting may find no nonsingular block. The
     * velocity, a projection onto the tangent cone, is unique all the same:
     * a shift of 1e-10 of the diagonal picks one set of multipliers for it
     * (the mode then keeps an independent subset of their rows). */
    double dmax = 0;
    for (int i = 0; i < m; i++) dmax = fmax(dmax, A->lcpM[i + (size_t)i * m]);
    for (int i = 0; i < m; i++)
      if (touch[i]) A->lcpM[i + (size_t)i * m] += 1e-10 * dmax;
    lcp_forget(&A->lcp);
    st = lcp_solve(&A->lcp, A->lcpM, A->lcpq, pivots);
  }
  if (st) return st;
  uint64_t J = 0;
  for (int i = 0; i < m; i++)
    if (A->lcp.lam[i] > 0) J |= (uint64_t)1 << i;
  *mask = J;
  return CUP_OK;
}
