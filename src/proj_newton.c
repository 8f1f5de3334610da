/* Exact projection onto large sparse sets: projected Newton on the dual
 *   min f(lam) = 1/2 lam' M lam + b' lam,  lam >= 0,  M = C P^-1 C^T,
 * with b = C x + g (Bertsekas 1982). Newton directions on the free rows and
 * the finishing solve on the identified active set both come from one
 * quasi-definite KKT matrix
 *   [ P    C_F^T     ]
 *   [ C_F  -delta I  ]     (rows outside F: zero C row, -1 on the diagonal)
 * symmetrically permuted once (AMD/METIS) and stored upper, so that CHOLMOD
 * refactorizes it numerically, with the natural ordering, without
 * allocating. The same solver, on the rows near activity with a shifted
 * offset, gives the inward anchor that certifies eta. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "projector_impl.h"

/* One dual problem: project xc onto {C y + g >= 0}, rows outside `rows`
 * ignored (NULL: all rows). */
typedef struct pn_problem {
  const double *xc, *g;
  const unsigned char *rows;
  double *b;                     /* C xc + g */
  pn_ws *w;                      /* iterate and scratch */
} pn_problem;

/* Scratch of a solve; with own = 0 the iterate buffers are the projector's
 * (attached per call), so only the scratch is allocated. */
static int pn_alloc(pn_ws *w, int n, int m, int own) {
  size_t N = (size_t)n, M = (size_t)m + 1;
  int fail = 0;
  double **mv[] = {&w->d, &w->lt, &w->snap, &w->r, &w->keep, &w->lam, &w->s, &w->gam, &w->s2, &w->gam2};
  for (int k = 0; k < (own ? 10 : 5); k++) fail |= !(*mv[k] = calloc(M, sizeof(double)));
  if (own) {
    fail |= !(w->y = calloc(N, sizeof(double)));
    fail |= !(w->y2 = calloc(N, sizeof(double)));
  }
  fail |= !(w->act = calloc(M, 1));
  fail |= !(w->prev = calloc(M, 1));
  return fail ? CUP_ERR_NOMEM : CUP_OK;
}

static void pn_free(pn_ws *w, int own) {
  free(w->d); free(w->lt); free(w->snap); free(w->r); free(w->keep);
  if (own) { free(w->lam); free(w->s); free(w->gam); free(w->s2); free(w->gam2); free(w->y); free(w->y2); }
  free(w->act); free(w->prev);
}

int cup_kkt_create(cup_projector *p, char *errmsg) {
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m, N = n + m;
  kkt_ws *w = calloc(1, sizeof *w);
  if (!w) return cup_fail(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  p->kkt = w;
  if (cup_cholmod_start(&w->cm))
    return cup_fail(errmsg, CUP_ERR_LINALG, "projector: CHOLMOD start failed");
  /* 1. The lower triangle in natural order, each entry tagged with where its
   *    value comes from: >= 0 an entry of C, -1 - i constraint i's diagonal,
   *    <= -1 - m a P entry (value kept in pval). */
  int nnzP = 0;
  if (K->pkind == CUP_METRIC_SPARSE) {
    for (int j = 0; j < n; j++)
      for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++) nnzP += K->Pfull.i[k] >= j;
  } else {
    nnzP = n;
  }
  int nnz = nnzP + K->C.nnz + m;
  int *Ap = malloc(sizeof(int) * ((size_t)N + 1));
  int *Ai = malloc(sizeof(int) * (size_t)nnz);
  int *tag = malloc(sizeof(int) * (size_t)nnz);
  double *Ax = malloc(sizeof(double) * (size_t)nnz);
  int *rowcnt = calloc((size_t)N + 1, sizeof(int));
  int *order = malloc(sizeof(int) * (size_t)nnz);
  w->cpos = malloc(sizeof(int) * ((size_t)K->C.nnz + 1));
  w->dpos = malloc(sizeof(int) * ((size_t)m + 1));
  w->iperm = malloc(sizeof(int) * (size_t)N);
  w->pperm = malloc(sizeof(int) * (size_t)N);
  w->rhs = malloc(sizeof(double) * (size_t)N);
  w->sol = malloc(sizeof(double) * (size_t)N);
  w->res = malloc(sizeof(double) * (size_t)N);
  w->work = malloc(sizeof(double) * 2 * (size_t)N);
  w->fact_act = calloc((size_t)m + 1, 1);
  int st = CUP_OK;
  if (!Ap || !Ai || !tag || !Ax || !rowcnt || !order || !w->cpos || !w->dpos || !w->iperm ||
      !w->pperm || !w->rhs || !w->sol || !w->res || !w->work || !w->fact_act) {
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "projector: out of memory for the KKT system");
    goto done;
  }
  int q = 0;
  Ap[0] = 0;
  for (int j = 0; j < n; j++) {
    if (K->pkind == CUP_METRIC_SPARSE) {
      for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++)
        if (K->Pfull.i[k] >= j) { Ai[q] = K->Pfull.i[k]; Ax[q] = K->Pfull.x[k]; tag[q++] = -1 - m; }
    } else {
      Ai[q] = j; Ax[q] = K->pd[j]; tag[q++] = -1 - m;
    }
    for (int k = K->C.p[j]; k < K->C.p[j + 1]; k++) {
      Ai[q] = n + K->C.i[k]; Ax[q] = K->C.x[k]; tag[q++] = k;
    }
    Ap[j + 1] = q;
  }
  for (int i = 0; i < m; i++) {
    Ai[q] = n + i; Ax[q] = -1; tag[q++] = -1 - i;
    Ap[n + i + 1] = q;
  }
  cholmod_sparse A = {0};
  A.nrow = A.ncol = (size_t)N; A.nzmax = (size_t)nnz;
  A.p = Ap; A.i = Ai; A.x = Ax; A.stype = -1;
  A.itype = CHOLMOD_INT; A.xtype = CHOLMOD_REAL; A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1; A.packed = 1;
  /* 2. A fill-reducing order (AMD or METIS, CHOLMOD's choice). */
  w->cm.supernodal = CHOLMOD_SIMPLICIAL;
  w->cm.final_ll = 0;
  cholmod_factor *L0 = cholmod_analyze(&A, &w->cm);
  if (!L0) { st = cup_fail(errmsg, CUP_ERR_LINALG, "KKT: CHOLMOD analysis failed (%d)", w->cm.status); goto done; }
  for (int k = 0; k < N; k++) {
    int orig = L0->Perm ? ((int *)L0->Perm)[k] : k;
    w->pperm[k] = orig;
    w->iperm[orig] = k;
  }
  cholmod_free_factor(&L0, &w->cm);
  /* 3. The permuted matrix, upper triangle: rows sorted within columns by a
   *    bucket pass over rows. */
  w->Ku = cholmod_allocate_sparse((size_t)N, (size_t)N, (size_t)nnz, 1, 1, 1,
                                  CHOLMOD_REAL, &w->cm);
  if (!w->Ku) { st = cup_fail(errmsg, CUP_ERR_NOMEM, "KKT: out of memory"); goto done; }
  int *Kp = w->Ku->p, *Ki = w->Ku->i;
  double *Kx = w->Ku->x;
  int *colcnt = calloc((size_t)N + 1, sizeof(int));
  if (!colcnt) { st = cup_fail(errmsg, CUP_ERR_NOMEM, "KKT: out of memory"); goto done; }
  for (int c = 0; c < N; c++)
    for (int e = Ap[c]; e < Ap[c + 1]; e++) {
      int pr = w->iperm[Ai[e]], pc = w->iperm[c];
      int row = pr < pc ? pr : pc, col = pr < pc ? pc : pr;
      rowcnt[row + 1]++;
      colcnt[col + 1]++;
    }
  for (int k = 0; k < N; k++) { rowcnt[k + 1] += rowcnt[k]; colcnt[k + 1] += colcnt[k]; }
  memcpy(Kp, colcnt, sizeof(int) * ((size_t)N + 1));
  for (int c = 0; c < N; c++)               /* entries bucketed by row */
    for (int e = Ap[c]; e < Ap[c + 1]; e++) {
      int pr = w->iperm[Ai[e]], pc = w->iperm[c];
      order[rowcnt[pr < pc ? pr : pc]++] = e;
    }
  int *colof = malloc(sizeof(int) * (size_t)nnz);
  if (!colof) { free(colcnt); st = cup_fail(errmsg, CUP_ERR_NOMEM, "KKT: out of memory"); goto done; }
  for (int c = 0; c < N; c++)
    for (int e = Ap[c]; e < Ap[c + 1]; e++) colof[e] = c;
  for (int t = 0; t < nnz; t++) {           /* rows ascending: append to columns */
    int e = order[t];
    int pr = w->iperm[Ai[e]], pc = w->iperm[colof[e]];
    int row = pr < pc ? pr : pc, col = pr < pc ? pc : pr;
    int pos = colcnt[col]++;
    Ki[pos] = row;
    Kx[pos] = Ax[e];
    if (tag[e] >= 0) w->cpos[tag[e]] = pos;
    else if (tag[e] > -1 - m) w->dpos[-1 - tag[e]] = pos;
  }
  free(colof);
  free(colcnt);
  /* 4. Symbolic factorization in that order, then one numeric factorization
   *    (all rows inactive) so that later refactorizations reuse L's memory. */
  w->cm.nmethods = 1;
  w->cm.method[0].ordering = CHOLMOD_NATURAL;
  w->cm.postorder = 0;
  w->L = cholmod_analyze(w->Ku, &w->cm);
  if (!w->L) { st = cup_fail(errmsg, CUP_ERR_LINALG, "KKT: CHOLMOD analysis failed (%d)", w->cm.status); goto done; }
  for (int k = 0; k < K->C.nnz; k++) Kx[w->cpos[k]] = 0;
  cholmod_factorize(w->Ku, w->L, &w->cm);
  if (w->cm.status < 0) { st = cup_fail(errmsg, CUP_ERR_LINALG, "KKT: CHOLMOD factorization failed (%d)", w->cm.status); goto done; }
  w->has_fact = 1;
  double mmax = 0;
  for (int i = 0; i < m; i++) mmax = fmax(mmax, K->rownorm[i] * K->rownorm[i]);
  w->delta = 1e-10 * (mmax > 0 ? mmax : 1);
  if (pn_alloc(&w->pmain, n, m, 0) || pn_alloc(&w->pin, n, m, 1) ||
      !(w->gin = malloc(sizeof(double) * (size_t)m)) ||
      !(w->bin = malloc(sizeof(double) * (size_t)m)))
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "KKT: out of memory");
done:
  free(Ap); free(Ai); free(tag); free(Ax); free(rowcnt); free(order);
  return st;
}

void cup_kkt_free(cup_projector *p) {
  kkt_ws *w = p->kkt;
  if (!w) return;
  if (w->L) cholmod_free_factor(&w->L, &w->cm);
  if (w->Ku) cholmod_free_sparse(&w->Ku, &w->cm);
  cholmod_finish(&w->cm);
  pn_free(&w->pmain, 0);
  pn_free(&w->pin, 1);
  free(w->gin); free(w->bin);
  free(w->cpos); free(w->dpos); free(w->iperm); free(w->pperm);
  free(w->rhs); free(w->sol); free(w->res); free(w->work); free(w->fact_act);
  free(w);
  p->kkt = NULL;
}

static int kkt_factor(cup_projector *p, const unsigned char *act, double delta) {
  kkt_ws *w = p->kkt;
  const cup_sparse *C = &p->K->C;
  int m = p->m;
  if (w->has_fact && w->fact_delta == delta && memcmp(act, w->fact_act, (size_t)m) == 0)
    return CUP_OK;
  double *Kx = w->Ku->x;
  for (int j = 0; j < C->ncol; j++)
    for (int k = C->p[j]; k < C->p[j + 1]; k++) Kx[w->cpos[k]] = act[C->i[k]] ? C->x[k] : 0;
  for (int i = 0; i < m; i++) Kx[w->dpos[i]] = act[i] ? -delta : -1;
  cholmod_factorize(w->Ku, w->L, &w->cm);
  p->facts++;
  if (w->cm.status < 0 || w->cm.status == CHOLMOD_NOT_POSDEF) { w->has_fact = 0; return CUP_ERR_LINALG; }
  memcpy(w->fact_act, act, (size_t)m);
  w->fact_delta = delta;
  w->has_fact = 1;
  return CUP_OK;
}

/* v <- K_delta^-1 v (v in KKT order, n + m entries). */
static void kkt_solve(cup_projector *p, double *v) {
  kkt_ws *w = p->kkt;
  int N = p->n + p->m;
  double *t = w->work, *scratch = w->work + N;
  for (int k = 0; k < N; k++) t[k] = v[w->pperm[k]];
  cup_simplicial_solve(w->L, t, scratch);
  for (int k = 0; k < N; k++) v[w->pperm[k]] = t[k];
}

/* The exact subproblem on the factored set F: [P C_F^T; C_F 0][y; nu] =
 * [P xc; r_F], by the regularized factor with iterative refinement against
 * the exact matrix until the residual reaches rounding or stops shrinking.
 * Returns y in sol[0..n) and nu = -lambda in sol[n..n+m). */
static void kkt_exact(cup_projector *p, const double *xc, const unsigned char *act,
                      const double *r) {
  const cup_polyset *K = p->K;
  kkt_ws *w = p->kkt;
  int n = p->n, m = p->m, N = n + m;
  double *rhs = w->rhs, *sol = w->sol, *res = w->res;
  cup_metric_apply(K, xc, rhs);
  for (int i = 0; i < m; i++) rhs[n + i] = act[i] ? r[i] : 0;
  memcpy(sol, rhs, sizeof(double) * (size_t)N);
  kkt_solve(p, sol);
  double rprev = INFINITY;
  for (int ref = 0; ref < 30; ref++) {
    const double *yv = sol, *nu = sol + n;
    cup_metric_apply(K, yv, res);
    for (int j = 0; j < n; j++) {            /* res_top = rhs - P y - C_F^T nu */
      double acc = res[j];
      for (int k = K->C.p[j]; k < K->C.p[j + 1]; k++)
        if (act[K->C.i[k]]) acc += K->C.x[k] * nu[K->C.i[k]];
      res[j] = rhs[j] - acc;
    }
    for (int i = 0; i < m; i++) {
      if (!act[i]) { res[n + i] = 0; continue; }
      double acc = 0;
      for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) acc += K->Ct.x[k] * yv[K->Ct.i[k]];
      res[n + i] = rhs[n + i] - acc;
    }
    double rn = 0, sn = 0;
    for (int k = 0; k < N; k++) { rn = fmax(rn, fabs(res[k])); sn = fmax(sn, fabs(rhs[k])); }
    if (!(rn > 4 * DBL_EPSILON * sn) || !(rn < 0.5 * rprev)) break;
    rprev = rn;
    kkt_solve(p, res);
    for (int k = 0; k < N; k++) sol[k] += res[k];
  }
}

/* f(lam) = lam'(s + b)/2 (since s = M lam + b), with y and s at lam. */
static double dual_eval(cup_projector *p, const pn_problem *q, const double *lam,
                        double *y, double *s, double *gam) {
  cup_eval_primal(p, q->xc, q->g, lam, y, s, gam);
  double f = 0;
  for (int i = 0; i < p->m; i++) f += lam[i] * (s[i] + q->b[i]);
  return 0.5 * f;
}

typedef int (*pn_stop_fn)(cup_projector *p, const pn_problem *q, cup_proj_info *info);

/* The finishing solve on the current free set (already factored): exact
 * multipliers, clipped; accepted if `stop` says so, else the iterate stays. */
static int pn_finish(cup_projector *p, const pn_problem *q, pn_stop_fn stop,
                     cup_proj_info *info) {
  int m = p->m, n = p->n;
  pn_ws *w = q->w;
  for (int i = 0; i < m; i++) w->r[i] = -q->g[i];
  kkt_exact(p, q->xc, w->act, w->r);
  memcpy(w->keep, w->lam, sizeof(double) * (size_t)m);
  const double *nu = p->kkt->sol + n;
  for (int i = 0; i < m; i++) w->lam[i] = w->act[i] ? fmax(0, -nu[i]) : 0;
  cup_eval_primal(p, q->xc, q->g, w->lam, w->y, w->s, w->gam);
  if (stop(p, q, info)) return 1;
  memcpy(w->lam, w->keep, sizeof(double) * (size_t)m);
  cup_eval_primal(p, q->xc, q->g, w->lam, w->y, w->s, w->gam);
  return 0;
}

/* Projected Newton: rows at (or within eps_k of) zero with a positive
 * gradient are held by a scaled gradient step; on the free rows F a
 * Levenberg-regularized Newton direction (M_FF + delta I) d_F = -s_F; a
 * projected Armijo search keeps f decreasing, so the iteration converges
 * from any start. Once a full step leaves F unchanged, the finishing solve
 * on F is tried. Returns CUP_OK when `stop` accepted the iterate,
 * CUP_WARN_NOT_CERTIFIED at the iteration limit or when f no longer
 * decreases above rounding, CUP_ERR_EMPTY_SET for a Farkas ray. */
static int pn_solve(cup_projector *p, const pn_problem *q, pn_stop_fn stop, int max_iter,
                    cup_proj_info *info) {
  const cup_polyset *K = p->K;
  int m = p->m, n = p->n;
  size_t msz = sizeof(double) * (size_t)m;
  kkt_ws *kw = p->kkt;
  pn_ws *w = q->w;
  double f = dual_eval(p, q, w->lam, w->y, w->s, w->gam);
  double tau = K->lip > 0 ? 1 / K->lip : 0;
  double delta = kw->delta;
  int settled = 0;
  memcpy(w->snap, w->lam, msz);
  memset(w->prev, 0, (size_t)m);
  for (int it = 0;; it++) {
    if (!isfinite(f)) return CUP_ERR_DIVERGED;
    if (stop(p, q, info)) return CUP_OK;
    if (it >= max_iter) return CUP_WARN_NOT_CERTIFIED;
    if (it % 8 == 7 && !q->rows) {          /* an empty K: lam grows along a Farkas ray */
      for (int i = 0; i < m; i++) w->d[i] = fmax(0, w->lam[i] - w->snap[i]);
      if (cup_farkas_test(p, w->d, info)) return CUP_ERR_EMPTY_SET;
      memcpy(w->snap, w->lam, msz);
    }
    double resid = 0, lmax = 0;
    for (int i = 0; i < m; i++) {
      resid = fmax(resid, fabs(w->lam[i] - fmax(0, w->lam[i] - tau * w->s[i])));
      lmax = fmax(lmax, w->lam[i]);
    }
    double epsk = fmin(resid, 1e-3 * lmax);
    for (int i = 0; i < m; i++)
      w->act[i] = K->rownorm[i] > 0 && (!q->rows || q->rows[i]) &&
                  !(w->lam[i] <= epsk && w->s[i] > 0);
    int st = kkt_factor(p, w->act, delta);
    if (st) return st;
    if (settled && memcmp(w->act, w->prev, (size_t)m) == 0 && pn_finish(p, q, stop, info))
      return CUP_OK;
    memcpy(w->prev, w->act, (size_t)m);
    double *rhs = kw->sol;                  /* [0; s_F] -> [v; d_F] */
    memset(rhs, 0, sizeof(double) * (size_t)n);
    for (int i = 0; i < m; i++) rhs[n + i] = w->act[i] ? w->s[i] : 0;
    kkt_solve(p, rhs);
    p->iters++;
    double slope = 0;
    for (int i = 0; i < m; i++) {
      int allowed = !q->rows || q->rows[i];
      w->d[i] = w->act[i] ? rhs[n + i] : allowed ? -tau * w->s[i] : -w->lam[i];
      if (w->act[i]) slope += w->s[i] * w->d[i];
    }
    double alpha = 1, ft = f;
    int accepted = 0;
    for (int ls = 0; ls < 40 && !accepted; ls++) {
      double bound = 0;
      for (int i = 0; i < m; i++) {
        w->lt[i] = fmax(0, w->lam[i] + alpha * w->d[i]);
        if (!w->act[i]) bound += w->s[i] * (w->lam[i] - w->lt[i]);
      }
      ft = dual_eval(p, q, w->lt, w->y2, w->s2, w->gam2);
      accepted = f - ft >= 1e-4 * (-alpha * slope + bound);
      if (!accepted) alpha *= 0.5;
    }
    if (!accepted)                          /* no decrease above rounding */
      return pn_finish(p, q, stop, info) ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
    settled = alpha == 1;
    /* Levenberg: short steps mean the model is poor; trust it less */
    delta = alpha < 0.1 ? fmin(delta * 100, 1e-2 * K->lip) : fmax(delta * 0.1, kw->delta);
    memcpy(w->lam, w->lt, msz);
    double *t;
    t = w->y; w->y = w->y2; w->y2 = t;
    t = w->s; w->s = w->s2; w->s2 = t;
    t = w->gam; w->gam = w->gam2; w->gam2 = t;
    f = ft;
  }
}

/* ---- the inward anchor ---------------------------------------------------------- */

/* Rows near activity with slack >= 32 gam: project z onto
 * {C_A' w + g_A' - 32 gam_A' >= 0}; done when every such row is at least
 * half way there (verification happens in cup_certify). */
static int inward_stop(cup_projector *p, const pn_problem *q, cup_proj_info *info) {
  (void)info;
  pn_ws *w = q->w;
  for (int i = 0; i < p->m; i++)
    if (q->rows[i] && !(w->s[i] >= -16 * p->gam[i])) return 0;
  return 1;
}

static void inward_sparse(cup_projector *p) {
  int m = p->m, n = p->n;
  kkt_ws *kw = p->kkt;
  pn_ws *w = &kw->pin;
  unsigned char *a2 = p->act2;
  int any = 0;
  for (int i = 0; i < m; i++) {
    a2[i] = p->K->rownorm[i] > 0 && (p->lam[i] > 0 || p->s[i] < 4 * p->gam[i]);
    any |= a2[i];
    kw->gin[i] = p->g[i] - (32 * p->gam[i] + DBL_MIN);
    w->lam[i] = 0;
  }
  if (!any) return;
  cup_slack(p->K, kw->gin, p->y, kw->bin, NULL);
  pn_problem q = {p->y, kw->gin, a2, kw->bin, w};
  cup_proj_info scratch = {0};
  if (pn_solve(p, &q, inward_stop, 50, &scratch) != CUP_OK) return;
  memcpy(p->inward, w->y, sizeof(double) * (size_t)n);
  p->has_inward = 1;
}

/* ---- the projection ------------------------------------------------------------- */

/* The iterate buffers of the main solve are the projector's own; the
 * line search swaps y/y2 (etc.), so re-attach them in both directions. */
static void attach(cup_projector *p, pn_ws *w) {
  w->lam = p->lam; w->y = p->y; w->s = p->s; w->gam = p->gam;
  w->y2 = p->y2; w->s2 = p->s2; w->gam2 = p->gam2;
}
static void detach(cup_projector *p, const pn_ws *w) {
  p->y = w->y; p->s = w->s; p->gam = w->gam;
  p->y2 = w->y2; p->s2 = w->s2; p->gam2 = w->gam2;
}

static int main_stop(cup_projector *p, const pn_problem *q, cup_proj_info *info) {
  pn_ws *w = q->w;
  double eq = 0;
  for (int i = 0; i < p->m; i++) eq += 2 * w->lam[i] * (w->s[i] + w->gam[i]);
  if (!(eq <= info->eps_target)) return 0;
  detach(p, w);                             /* cup_certify reads p->y, p->s, p->gam */
  p->has_inward = 0;                        /* an anchor belongs to one candidate */
  p->make_inward = inward_sparse;
  int ok = cup_certify(p, q->xc, w->lam, w->y, info);
  p->make_inward = NULL;
  return ok;
}

int cup_proj_sparse_newton(cup_projector *p, const double *x, cup_proj_info *info) {
  int m = p->m;
  kkt_ws *kw = p->kkt;
  pn_ws *w = &kw->pmain;
  info->method = CUP_PROJ_ACTIVESET;
  attach(p, w);
  if (p->opt.warm_start) memcpy(w->lam, p->lam_warm, sizeof(double) * (size_t)m);
  else memset(w->lam, 0, sizeof(double) * (size_t)m);
  pn_problem q = {x, p->g, NULL, p->b, w};
  int st = pn_solve(p, &q, main_stop, p->opt.max_iter, info);
  detach(p, w);
  if (st == CUP_WARN_NOT_CERTIFIED) cup_certify(p, x, w->lam, w->y, info);
  return st;
}
