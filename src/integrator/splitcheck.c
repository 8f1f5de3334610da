/* splitcheck — the implicit and exponential schemes' splitting error, a
 * step at a time (see splitcheck.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "splitcheck.h"
#include "util/fail.h"

#define SPLIT_DENSE_P 64   /* up to this dimension P is kept dense here */
#define SPLIT_PHI1_MAX 128 /* ... and phi_1(hA) computed (an exponential of twice the size) */

/* phi_1(hA), the top right block of exp([hA I; 0 0]) (2n x 2n), into out. */
static int phi1(const freestep_drift *A, double h, double *out) {
  int n = A->n, n2 = 2 * n;
  size_t N2 = (size_t)n2 * n2;
  double *big = calloc(5 * N2, sizeof(double));
  if (!big) return CUP_ERR_NOMEM;
  double *ex = big + N2, *work = big + 2 * N2;
  if (A->has_A)
    for (int j = 0; j < n; j++)
      for (int k = A->A.p[j]; k < A->A.p[j + 1]; k++) big[A->A.i[k] + (size_t)j * n2] = h * A->A.x[k];
  for (int i = 0; i < n; i++) big[i + (size_t)(n + i) * n2] = 1;
  la_dense_expm(big, n2, ex, work);
  for (int j = 0; j < n; j++) memcpy(out + (size_t)j * n, ex + (size_t)(n + j) * n2, sizeof(double) * (size_t)n);
  free(big);
  return CUP_OK;
}

/* y = a v, a n x n column-major. */
static void matvec(int n, const double *a, const double *v, double *y) {
  for (int i = 0; i < n; i++) y[i] = 0;
  for (int j = 0; j < n; j++) {
    double vj = v[j];
    if (vj != 0)
      for (int i = 0; i < n; i++) y[i] += a[i + (size_t)j * n] * vj;
  }
}

/* c_i^T v */
static double row_dot(const cup_polyset *K, int i, const double *v) {
  double acc = 0;
  for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) acc += K->Ct.x[k] * v[K->Ct.i[k]];
  return acc;
}

/* ||v||_P (P dense when small: a step's two norms cost 2 n^2, not two
 * sparse products through the metric's kind) */
static double normP(splitcheck *s, const double *v) {
  int n = s->n;
  double acc = 0;
  if (s->P) {
    for (int j = 0; j < n; j++) {
      double c = 0;
      for (int i = 0; i < n; i++) c += s->P[i + (size_t)j * n] * v[i];
      acc += c * v[j];
    }
  } else {
    polyset_metric_apply(s->K, v, s->Pv);
    for (int i = 0; i < n; i++) acc += v[i] * s->Pv[i];
  }
  return acc > 0 ? sqrt(acc) : 0;
}

/* z_J = (the J x J block of a, m x m)^-1 r_J, r in z; 1 when singular or
 * not finite (then z is not used). */
static int solve_block(splitcheck *s, const double *a, int nJ, double *z) {
  int m = s->K->m;
  if (nJ == 1) {                                   /* one row acting: the common case */
    z[0] /= a[s->J[0] + (size_t)s->J[0] * m];
    return !isfinite(z[0]);
  }
  for (int q = 0; q < nJ; q++)
    for (int p = 0; p < nJ; p++) s->blk[p + (size_t)q * nJ] = a[s->J[p] + (size_t)s->J[q] * m];
  if (la_dense_lu(s->blk, nJ, s->piv)) return 1;
  la_dense_lu_solve(s->blk, nJ, s->piv, z, s->zw);
  for (int q = 0; q < nJ; q++)
    if (!isfinite(z[q])) return 1;
  return 0;
}

int splitcheck_init(splitcheck *s, const freestep_ws *fs, const cup_polyset *K, char *errmsg) {
  memset(s, 0, sizeof *s);
  if ((fs->scheme != CUP_SCHEME_IMPLICIT && fs->scheme != CUP_SCHEME_EXPONENTIAL) || !K || K->m == 0 ||
      !K->dense || !fs->d.has_A)
    return CUP_OK;
  int n = s->n = fs->n, m = K->m;
  s->K = K;
  size_t N = (size_t)n, M = (size_t)m;
  size_t NP = N <= SPLIT_DENSE_P ? N * N : 0;
  s->buf = calloc(2 * N * N + NP + N * M + M * M + M * M + 6 * N + 3 * M, sizeof(double));
  s->J = calloc(2 * M, sizeof(int));
  if (!s->buf || !s->J) {
    splitcheck_free(s);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "splitting check: out of memory");
  }
  s->piv = s->J + m;
  s->lin = s->buf;
  double *phi = s->lin + N * N;
  s->phib = phi + N * N;
  s->g = s->phib + N * M;
  s->blk = s->g + M * M;
  s->e = s->blk + M * M;
  s->d = s->e + N;
  s->v = s->d + N;
  s->Pv = s->v + N;
  s->w = s->Pv + N;
  s->z = s->w + 2 * N;
  s->zw = s->z + M;
  if (NP) {                                        /* P, column by column */
    double *P = s->zw + M;
    for (int j = 0; j < n; j++) {
      s->v[j] = 1;
      polyset_metric_apply(K, s->v, P + (size_t)j * n);
      s->v[j] = 0;
    }
    s->P = P;
  }
  if (fs->scheme == CUP_SCHEME_IMPLICIT) {       /* W = (I - h A)^-1, column by column: both maps */
    for (int j = 0; j < n; j++) {
      double *col = s->lin + (size_t)j * n;
      col[j] = 1;
      la_dense_lu_solve(fs->lu, n, fs->piv, col, s->w);
    }
    memcpy(phi, s->lin, sizeof(double) * N * N);
  } else {                                       /* e^{hA}, the generators' block left out; phi_1(hA) */
    for (int j = 0; j < n; j++) memcpy(s->lin + (size_t)j * n, fs->Eh + (size_t)j * fs->na, sizeof(double) * N);
    if (n > SPLIT_PHI1_MAX) memcpy(phi, s->lin, sizeof(double) * N * N);   /* e^{hA}: about twice the estimate */
    else if (phi1(&fs->d, fs->h, phi)) {
      splitcheck_free(s);
      return fail_fmt(errmsg, CUP_ERR_NOMEM, "splitting check: out of memory");
    }
  }
  /* Phi B and G = C Phi B: the consistent step's correction and its rows */
  int leak = 0;
  for (int i = 0; i < m; i++) {
    const double *b = K->Bt + (size_t)i * n;
    double *pb = s->phib + (size_t)i * n;
    matvec(n, phi, b, pb);
    for (int r = 0; r < m; r++) s->g[r + (size_t)i * m] = row_dot(K, r, pb);
    /* it leaves b's line (by more than rounding): else the two corrections agree up to scale */
    double bb = row_dot(K, i, b), c = bb > 0 ? row_dot(K, i, pb) / bb : 0;
    for (int j = 0; j < n; j++) s->v[j] = pb[j] - c * b[j];
    if (bb > 0 && normP(s, s->v) > CUP_SPLIT_LEAK_MIN * fabs(c) * sqrt(bb)) leak = 1;
  }
  if (!leak) {
    splitcheck_free(s);
    return CUP_OK;
  }
  s->on = 1;
  return CUP_OK;
}

void splitcheck_free(splitcheck *s) {
  free(s->buf);
  free(s->J);
  memset(s, 0, sizeof *s);
}

void splitcheck_reset(splitcheck *s) {
  if (!s->on) return;
  memset(s->e, 0, sizeof(double) * (size_t)s->n);
  s->live = 0;
  s->emax = s->eone = s->peak = 0;
  s->first = s->worst = 0;
  s->tfirst = s->tworst = 0;
}

void splitcheck_step(splitcheck *s, long k, double t, const double *xf, const double *x, const double *lam) {
  const cup_polyset *K = s->K;
  int n = s->n, m = K->m, nJ = 0;
  if (s->live) {                                   /* carried by the free step's linear part */
    matvec(n, s->lin, s->e, s->v);
    double *e = s->v;
    s->v = s->e;
    s->e = e;
  }
  int moved = 0;
  for (int i = 0; i < n; i++) moved |= (s->d[i] = x[i] - xf[i]) != 0;
  if (moved && lam)
    for (int i = 0; i < m; i++)
      if (lam[i] > 0) s->J[nJ++] = i;
  if (nJ) {
    /* the error's part the projection takes back: e - B_J M_JJ^-1 C_J e */
    if (s->live) {
      for (int q = 0; q < nJ; q++) s->z[q] = row_dot(K, s->J[q], s->e);
      if (!solve_block(s, K->Md, nJ, s->z))
        for (int q = 0; q < nJ; q++)
          for (int j = 0; j < n; j++) s->e[j] -= K->Bt[j + (size_t)s->J[q] * n] * s->z[q];
    }
    /* the consistent step's correction Phi B_J y, C_J Phi B_J y = C_J d, less the scheme's d */
    for (int q = 0; q < nJ; q++) s->z[q] = row_dot(K, s->J[q], s->d);
    if (!solve_block(s, s->g, nJ, s->z)) {
      for (int j = 0; j < n; j++) s->e[j] -= s->d[j];
      for (int q = 0; q < nJ; q++)
        for (int j = 0; j < n; j++) s->e[j] += s->phib[j + (size_t)s->J[q] * n] * s->z[q];
      s->live = 1;
    }
  }
  /* the norms at the steps that project and at every 8th between: the
   * flow between is linear, the largest of either barely missed */
  if (!nJ && (k & 7)) return;
  double xn = normP(s, x);
  if (xn > s->peak) s->peak = xn;
  if (!s->live) return;
  double en = normP(s, s->e);
  if (en > s->emax) s->emax = en, s->worst = k, s->tworst = t;
  if (!(en > CUP_SPLIT_ERR_WARN * s->peak)) s->first = 0;   /* below: a later stretch above starts anew */
  else if (!s->first) s->first = k, s->tfirst = t;
}

void splitcheck_merge(splitcheck *a, const splitcheck *b) {
  if (!b->on) return;
  a->on = 1;
  a->emax += b->emax;                              /* each configuration's own: together at most their sum */
  a->peak = fmax(a->peak, b->peak);
  if (b->first && (!a->first || b->tfirst < a->tfirst)) a->first = b->first, a->tfirst = b->tfirst;
  if (b->emax > a->eone) a->eone = b->emax, a->worst = b->worst, a->tworst = b->tworst;
}

void splitcheck_verdict(const splitcheck *s, int scheme, long n, cup_run_info *info) {
  if (!s->on || !(s->emax > CUP_SPLIT_ERR_WARN * s->peak) || info->status < 0 ||
      info->status == CUP_WARN_SPLITTING)
    return;
  double r = s->emax / s->peak;
  double nmin = ceil((double)n * r / CUP_SPLIT_ERR_WARN);   /* first order: e falls as 1 / n */
  char msg[640];
  snprintf(msg, sizeof msg,
           "%s scheme: each step's projection puts back at its end what the constraints do throughout "
           "it, and the free step carried the difference into other states (a source driving a blocked "
           "state fast within a step): an error of about %.3g in the energy norm ||x||_P, %.3g%% of the "
           "state's largest (%.3g), at step %ld (t = %.9g)", cup_scheme_name(scheme), s->emax, 100 * r, s->peak,
           s->worst, s->tworst);
  size_t at = strlen(msg);
  if (s->first && at < sizeof msg)
    snprintf(msg + at, sizeof msg - at, "; above %g%% of the state's largest so far from step %ld (t = %.9g) on",
             100 * CUP_SPLIT_ERR_WARN, s->first, s->tfirst);
  at = strlen(msg);
  if (at < sizeof msg) snprintf(msg + at, sizeof msg - at, "; use the theta or adaptive scheme, or n >= %.3g", nmin);
  if (info->status == CUP_OK) {
    info->status = CUP_WARN_SPLITTING;
    memcpy(info->message, msg, sizeof msg);
    return;
  }
  size_t len = strlen(info->message), add = strlen(msg);   /* another warning came first: it keeps the status */
  if (len + add + 6 < sizeof info->message) {
    memcpy(info->message + len, "; and ", 6);
    memcpy(info->message + len + 6, msg, add + 1);
  }
}
