/* Exact projection onto large sparse sets: projected Newton on the dual
 *   min f(lam) = 1/2 lam' M lam + b' lam,  lam >= 0,  M = C P^-1 C^T,
 * with b = C x + g (Bertsekas 1982). The Newton directions on the free rows
 * come from the regularized dual factor of dual_factor.c (updated row by row
 * in warm-started sequences); once the free set settles, a finishing solve
 * on it aims the slack of those rows at a tiny positive target, so that the
 * answer is certainly feasible and certifies itself. The same solver, on
 * the rows near activity with a shifted offset, builds an inward anchor when
 * that is not enough. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "certify.h"
#include "dual_factor.h"
#include "newton.h"

/* Iterate and scratch of one projected-Newton solve. */
typedef struct pn_ws {
  double *lam, *y, *s, *gam;        /* iterate: lambda, y(lambda), slack, rounding */
  double *y2, *s2, *gam2;           /* line-search trial */
  double *d, *lt, *snap, *keep;     /* m each (snap: the main solve's only) */
  unsigned char *act, *prev;        /* free set, and the previous one */
  int *idx;                         /* m: the line search's rows that can reach their bound */
} pn_ws;

/* The method's workspace: the dual factor and the iterates of the main and
 * the inward-anchor solves. */
typedef struct newton_ws {
  struct dfact *df;
  pn_ws pmain;          /* the projection (lam, y, s, gam shared with the projector) */
  pn_ws pin;            /* the inward anchor's solve */
  double *gin, *bin;    /* shifted offset and its slack at z, for the inward solve */
  double *tau, *rhs;    /* slack targets of the finishing solve; a dual vector */
  double delta_peak;    /* largest Levenberg parameter of the last projection's steps */
  int stieltjes;        /* M = C P^-1 C^T has no positive off-diagonal (diagonal P); -1 unknown */
} newton_ws;

static const proj_method newton_method;

/* One dual problem: project xc onto {C y + g >= 0}, rows outside `rows`
 * ignored (NULL: all rows); the finishing solve aims the free rows' slack at
 * tau (NULL: 0). */
typedef struct pn_problem {
  const double *xc, *g;
  const unsigned char *rows;
  double *b;                     /* C xc + g */
  const double *tau;
  pn_ws *w;                      /* iterate and scratch */
  int finishing;                 /* inside the finishing solve (2: an early one) */
  newton_ws *nw;                 /* the method's workspace */
} pn_problem;

/* Scratch of a solve; with own = 0 (the main solve) the iterate buffers
 * are the projector's (attached per call), so only the scratch is
 * allocated, and the snapshot of the Farkas test, which only the main solve
 * (on all rows) makes. */
static int pn_alloc(pn_ws *w, int n, int m, int own) {
  size_t N = (size_t)n, M = (size_t)m + 1;
  int fail = 0;
  double **mv[] = {&w->d, &w->lt, &w->keep, &w->lam, &w->s, &w->gam, &w->s2, &w->gam2};
  for (int k = 0; k < (own ? 8 : 3); k++) fail |= !(*mv[k] = calloc(M, sizeof(double)));
  if (!own) fail |= !(w->snap = calloc(M, sizeof(double)));
  if (own) {
    fail |= !(w->y = calloc(N, sizeof(double)));
    fail |= !(w->y2 = calloc(N, sizeof(double)));
  }
  fail |= !(w->act = calloc(M, 1));
  fail |= !(w->prev = calloc(M, 1));
  fail |= !(w->idx = malloc(sizeof(int) * M));
  return fail ? CUP_ERR_NOMEM : CUP_OK;
}

static void pn_free(pn_ws *w, int own) {
  free(w->d); free(w->lt); free(w->snap); free(w->keep);
  if (own) { free(w->lam); free(w->s); free(w->gam); free(w->s2); free(w->gam2); free(w->y); free(w->y2); }
  free(w->act); free(w->prev); free(w->idx);
}

static void free_ws(cup_projector *p, void *ws) {
  (void)p;
  newton_ws *w = ws;
  if (!w) return;
  dfact_free(&w->df);
  pn_free(&w->pmain, 0);
  pn_free(&w->pin, 1);
  free(w->gin); free(w->bin); free(w->tau); free(w->rhs);
  free(w);
}

static void revalue(cup_projector *p, void *ws);

/* The dual factor and the solves' vectors. */
static int create(cup_projector *p, void **ws, char *errmsg) {
  int n = p->n, m = p->m;
  newton_ws *w = calloc(1, sizeof *w);
  if (!w) return fail_fmt(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  *ws = w;
  int st = dfact_create(&w->df, p->K, p->opt.factor_updates, -1, errmsg);
  if (st) return st;
  size_t M = (size_t)m + 1;
  if (pn_alloc(&w->pmain, n, m, 0) || pn_alloc(&w->pin, n, m, 1) ||
      !(w->gin = malloc(sizeof(double) * M)) || !(w->bin = malloc(sizeof(double) * M)) ||
      !(w->tau = malloc(sizeof(double) * M)) || !(w->rhs = malloc(sizeof(double) * M)))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  revalue(p, w);
  return CUP_OK;
}

/* Whether M = C P^-1 C^T (diagonal P) has no positive off-diagonal entry:
 * row by row, M(i, k) summed in the scratch acc (m entries, left zero).
 * Sums that cancel to rounding count as zero. */
static int stieltjes(const cup_polyset *K, double *acc) {
  if (!K->pdinv || K->pkind == CUP_METRIC_SPARSE) return 0;
  const la_sparse *C = &K->C, *Ct = &K->Ct;
  int ok = 1;
  memset(acc, 0, sizeof(double) * (size_t)K->m);   /* the scratch holds a solve's leftovers */
  for (int i = 0; i < K->m; i++) {
    for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) {
      int j = Ct->i[a];
      double cij = Ct->x[a] * K->pdinv[j];
      for (int b = C->p[j]; b < C->p[j + 1]; b++) acc[C->i[b]] += C->x[b] * cij;
    }
    for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) {
      int j = Ct->i[a];
      for (int b = C->p[j]; b < C->p[j + 1]; b++) {
        int k = C->i[b];
        if (k != i && acc[k] > 64 * DBL_EPSILON * K->rownorm[i] * K->rownorm[k]) ok = 0;
        acc[k] = 0;
      }
    }
  }
  return ok;
}

/* C's values changed: M's values with them (the same symbolic analysis),
 * and its signs are to be checked again. That check waits until a cold
 * projection needs it, not done at every revalue: a state-dependent set (a
 * crowd) revalues at every step and projects warm, and the check costs a
 * pass over M (1.6 M cache misses a step on a crowd of 10^5 agents). */
static void revalue(cup_projector *p, void *ws) {
  (void)p;
  newton_ws *w = ws;
  if (w) w->stieltjes = -1;
}

static void revalue_values(cup_projector *p, void *ws) {
  newton_ws *w = ws;
  if (w) dfact_revalue(w->df);
  revalue(p, ws);
}

/* in the dual scratch rhs: free between solves */
static int is_stieltjes(cup_projector *p, newton_ws *nw) {
  if (nw->stieltjes < 0) nw->stieltjes = stieltjes(p->K, nw->rhs);
  return nw->stieltjes;
}

static int factor(cup_projector *p, newton_ws *nw, const unsigned char *act, double delta) {
  return dfact_factor(nw->df, act, delta, &p->facts, &p->updates);
}

/* f(lam) = lam'(s + b)/2 (since s = M lam + b), with y and s at lam. */
static double dual_eval(cup_projector *p, const pn_problem *q, const double *lam,
                        double *y, double *s, double *gam) {
  certify_eval_primal(p, q->xc, q->g, lam, y, s, gam);
  double f = 0;
  for (int i = 0; i < p->m; i++) f += lam[i] * (s[i] + q->b[i]);
  return 0.5 * f;
}

/* The dual along the projected path lt(alpha) = max(lam + alpha d, 0),
 * valued from f and s at lam, for a diagonal metric (the KKT form would
 * need a solve with P). With D = lt - lam = alpha d + e, e nonzero only on
 * the rows whose bound a trial reaches (lam_i + alpha d_i < 0: e_i = -lam_i
 * - alpha d_i),
 *   f(lt) = f + s'D + |C^T D|^2_{P^-1} / 2,
 *   |C^T D|^2 = alpha^2 |v|^2 + 2 alpha v'P^-1 C^T e + |C^T e|^2,  v = C^T d,
 * so that a trial costs a pass over the rows that can reach their bound
 * and C's entries of those that do, not a pass over C (in a jam, 4-5 trials
 * a Newton step each cost about what the step's solve does). Rows at 0 that
 * d pushes down do not move and count for nothing. */
typedef struct line_model {
  double sd, sd_held;   /* s'd over the rows that move; over those not free (held) */
  double vv;            /* |v|^2_{P^-1} */
  int nneg;             /* rows that can reach their bound (d_i < 0 < lam_i), in w->idx */
} line_model;

static int moves(const pn_ws *w, int i) { return w->d[i] > 0 || (w->d[i] < 0 && w->lam[i] > 0); }

/* v = C^T d over the rows that move, into v (n entries). */
static void line_setup(const cup_projector *p, pn_ws *w, line_model *L, double *v) {
  const la_sparse *Ct = &p->K->Ct;
  const double *pdinv = p->K->pdinv;
  memset(v, 0, sizeof(double) * (size_t)p->n);
  L->sd = L->sd_held = 0;
  L->nneg = 0;
  for (int i = 0; i < p->m; i++) {
    if (!moves(w, i)) continue;
    double di = w->d[i];
    L->sd += w->s[i] * di;
    if (!w->act[i]) L->sd_held += w->s[i] * di;
    if (di < 0) w->idx[L->nneg++] = i;
    for (int k = Ct->p[i]; k < Ct->p[i + 1]; k++) v[Ct->i[k]] += Ct->x[k] * di;
  }
  double vv = 0;
  for (int j = 0; j < p->n; j++) vv += v[j] * v[j] * pdinv[j];
  L->vv = vv;
}

/* f at the trial alpha, and into *bound the decrease the rows held at
 * their bound promise, sum over them of s_i (lam_i - lt_i); u (n entries)
 * comes in zero and goes back zero. */
static double line_value(const cup_projector *p, const pn_ws *w, const line_model *L, double f,
                         double alpha, const double *v, double *u, double *bound) {
  const la_sparse *Ct = &p->K->Ct;
  const double *pdinv = p->K->pdinv;
  double lin = alpha * L->sd, held = alpha * L->sd_held, cross = 0, ee = 0;
  int reached = 0;
  for (int t = 0; t < L->nneg; t++) {
    int i = w->idx[t];
    double ei = -w->lam[i] - alpha * w->d[i];
    if (!(ei > 0)) continue;
    reached = 1;
    lin += w->s[i] * ei;
    if (!w->act[i]) held += w->s[i] * ei;
    for (int k = Ct->p[i]; k < Ct->p[i + 1]; k++) u[Ct->i[k]] += Ct->x[k] * ei;
  }
  for (int t = 0; reached && t < L->nneg; t++) {
    int i = w->idx[t];
    if (!(-w->lam[i] - alpha * w->d[i] > 0)) continue;
    for (int k = Ct->p[i]; k < Ct->p[i + 1]; k++) {
      int j = Ct->i[k];
      cross += v[j] * u[j] * pdinv[j];  /* each coordinate once: */
      ee += u[j] * u[j] * pdinv[j];
      u[j] = 0;                         /* a second visit adds 0 */
    }
  }
  *bound = -held;
  return f + (lin + 0.5 * (alpha * alpha * L->vv + 2 * alpha * cross + ee));
}

/* The Levenberg schedule: a step shorter than LM_SHORT that still changes
 * f multiplies delta by LM_UP, a full step divides it by LM_DOWN. */
#define LM_SHORT 1e-2
#define LM_UP 100
#define LM_DOWN 10

typedef int (*pn_stop_fn)(cup_projector *p, const pn_problem *q, cup_proj_info *info);

/* The finishing solve on the current free set F (already factored):
 * multipliers with s_F(lambda) = tau_F, by iterative refinement on the
 * primal slack (s computed from y = xc + P^-1 C^T lambda stays accurate when
 * M_FF is ill-conditioned); accepted if `stop` says so (an early one, before
 * the Levenberg parameter is back at its least, only if certainly feasible),
 * else the iterate stays. */
static int pn_finish(cup_projector *p, const pn_problem *q, pn_stop_fn stop,
                     cup_proj_info *info, int early) {
  int m = p->m;
  pn_ws *w = q->w;
  newton_ws *nw = q->nw;
  double *rhs = nw->rhs;
  /* the least regularized factor on F, and the iterate as the first guess
   * (refinement from zero with a large delta crawls on ill-conditioned M_FF) */
  if (factor(p, nw, w->act, dfact_delta_min(nw->df))) return 0;
  memcpy(w->keep, w->lam, sizeof(double) * (size_t)m);
  for (int i = 0; i < m; i++) if (!w->act[i]) w->lam[i] = 0;
  double prev = INFINITY;
  for (int step = 0; step < 30; step++) {
    certify_eval_primal(p, q->xc, q->g, w->lam, w->y, w->s, w->gam);
    double worst = 0;
    for (int i = 0; i < m; i++) {
      double target = q->tau ? q->tau[i] : 0;
      rhs[i] = w->act[i] ? target - w->s[i] : 0;
      if (w->act[i]) worst = la_max(worst, fabs(rhs[i]) / (w->gam[i] + DBL_MIN));
    }
    if (!(worst > 1) || !(worst < 0.5 * prev)) break;  /* at rounding, or no longer gaining */
    prev = worst;
    dfact_solve(nw->df, rhs);
    for (int i = 0; i < m; i++) if (w->act[i]) w->lam[i] += rhs[i];
  }
  /* Multipliers left slightly negative stay in z = y(lam): on a singular
   * M_FF (a jam's redundant contacts) the refinement moves lam along its
   * kernel by the residual's rounding over delta (1e-7 on the door test),
   * which changes no slack but turns small multipliers negative; clipping
   * them first would move z off those rows by |lam_i| ||c_i||, above eta's
   * target, and the corrections below would cycle on them. The
   * certificate takes lam's positive part (certify_candidate). */
  ((pn_problem *)q)->finishing = early ? 2 : 1;
  int ok = stop(p, q, info);
  ((pn_problem *)q)->finishing = 0;
  int neg = 0;
  for (int i = 0; i < m; i++)
    if (w->lam[i] < 0) { w->lam[i] = 0; neg = 1; w->d[i] = -1; } else w->d[i] = 0;   /* d marks rows to drop */
  if (ok) return 1;
  if (neg) certify_eval_primal(p, q->xc, q->g, w->lam, w->y, w->s, w->gam);
  memcpy(w->s2, w->s, sizeof(double) * (size_t)m);      /* the finished point's slack, */
  memcpy(w->gam2, w->gam, sizeof(double) * (size_t)m);  /* for pn_correct */
  memcpy(w->lam, w->keep, sizeof(double) * (size_t)m);
  certify_eval_primal(p, q->xc, q->g, w->lam, w->y, w->s, w->gam);
  return 0;
}

/* f stopped decreasing above its rounding while a few rows may still be
 * misclassified: finish on F, then correct F like a primal-dual active set
 * (rows the finished point violates join, rows with negative multipliers
 * leave) and finish again, a few times. */
static int pn_correct(cup_projector *p, const pn_problem *q, pn_stop_fn stop,
                      cup_proj_info *info) {
  pn_ws *w = q->w;
  for (int round = 0; round < 8; round++) {
    if (pn_finish(p, q, stop, info, 0)) return CUP_OK;
    /* pn_finish left the finished point's signs in d and slack in s2/gam2 */
    int changed = 0;
    for (int i = 0; i < p->m; i++) {
      if (w->act[i] && w->d[i] < 0) { w->act[i] = 0; changed = 1; }
      else if (!w->act[i] && w->s2[i] < -w->gam2[i] && (!q->rows || q->rows[i]) &&
               p->K->rownorm[i] > 0) { w->act[i] = 1; changed = 1; }
    }
    if (!changed || factor(p, q->nw, w->act, dfact_delta_min(q->nw->df))) break;
  }
  return CUP_WARN_NOT_CERTIFIED;
}

/* The free set F of the iterate, into w->act: rows at (or within eps_k of)
 * zero with a positive gradient are held, the others free; the right side
 * s_F of the direction into nw->rhs. Returns the projected gradient's
 * residual, its largest multiplier into *lmax. */
static double pn_free_set(cup_projector *p, const pn_problem *q, double tau, double *lmax) {
  const cup_polyset *K = p->K;
  int m = p->m;
  pn_ws *w = q->w;
  double resid = 0, lm = 0;
  for (int i = 0; i < m; i++) {
    /* la_max(v, 0) is fmax(0, v) (0 for a NaN v) without a libm call */
    resid = la_max(fabs(w->lam[i] - la_max(w->lam[i] - tau * w->s[i], 0)), resid);
    lm = la_max(w->lam[i], lm);
  }
  double epsk = fmin(resid, 1e-3 * lm);
  double *rhs = q->nw->rhs;
  for (int i = 0; i < m; i++) {
    w->act[i] = K->rownorm[i] > 0 && (!q->rows || q->rows[i]) &&
                !(w->lam[i] <= epsk && w->s[i] > 0);
    rhs[i] = w->act[i] ? w->s[i] : 0;
  }
  *lmax = lm;
  return resid;
}

/* The projected Armijo search along w->d from f (slope: the free rows'
 * s'd): 1 with the step's alpha and f there in *alpha, *ft and the trial
 * lt, y2, s2, gam2 at it; 0 when no trial decreased f enough, and the
 * last ones no longer moved f above its rounding. */
static int pn_line_search(cup_projector *p, const pn_problem *q, double f, double slope, double *alpha,
                          double *ft) {
  int m = p->m;
  pn_ws *w = q->w;
  double a = 1, t = f;
  int accepted = 0, cheap = p->K->pdinv != NULL;
  line_model L = {0};
  if (cheap) {                            /* v in y2, the trials' scratch in wn */
    line_setup(p, w, &L, w->y2);
    memset(p->wn, 0, sizeof(double) * (size_t)p->n);
  }
  for (int ls = 0; ls < 40 && !accepted; ls++) {
    double bound = 0;
    if (cheap) {
      t = line_value(p, w, &L, f, a, w->y2, p->wn, &bound);
    } else {
      for (int i = 0; i < m; i++) {
        w->lt[i] = la_max(w->lam[i] + a * w->d[i], 0);
        if (!w->act[i]) bound += w->s[i] * (w->lam[i] - w->lt[i]);
      }
      t = dual_eval(p, q, w->lt, w->y2, w->s2, w->gam2);
    }
    accepted = f - t >= 1e-4 * (-a * slope + bound);
    /* a short trial that no longer moves f above its rounding: shorter
     * ones cannot either) */
    if (!accepted && a < 0.1 && !(fabs(f - t) > 1e3 * DBL_EPSILON * fabs(f))) break;
    if (!accepted) a *= 0.5;
  }
  if (accepted && cheap) {                /* the step, and y, s, gam there */
    for (int i = 0; i < m; i++) w->lt[i] = la_max(w->lam[i] + a * w->d[i], 0);
    t = dual_eval(p, q, w->lt, w->y2, w->s2, w->gam2);
  }
  *alpha = a;
  *ft = t;
  return accepted;
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
  int m = p->m;
  size_t msz = sizeof(double) * (size_t)m;
  pn_ws *w = q->w;
  newton_ws *nw = q->nw;
  double f = dual_eval(p, q, w->lam, w->y, w->s, w->gam);
  double tau = K->lip > 0 ? 1 / K->lip : 0;
  /* the main solve starts from a hundredth of the largest delta the last
   * projection needed (a jam stays degenerate from one step to the next) */
  double dmin = dfact_delta_min(nw->df), dmax = 1e-2 * K->lip;
  double delta = q->rows ? dmin : fmin(fmax(dmin, 1e-2 * nw->delta_peak), dmax), peak = delta;
  int settled = 0, early = 0;
  if (!q->rows) memcpy(w->snap, w->lam, msz);
  memset(w->prev, 0, (size_t)m);
  for (int it = 0;; it++) {
    if (!isfinite(f)) return CUP_ERR_DIVERGED;
    if (stop(p, q, info)) return CUP_OK;
    if (it >= max_iter) return CUP_WARN_NOT_CERTIFIED;
    if (it % 8 == 7 && !q->rows) {          /* an empty K: lam grows along a Farkas ray */
      for (int i = 0; i < m; i++) w->d[i] = la_max(w->lam[i] - w->snap[i], 0);
      if (certify_farkas_test(p, w->d, info)) return CUP_ERR_EMPTY_SET;
      memcpy(w->snap, w->lam, msz);
    }
    double lmax, resid = pn_free_set(p, q, tau, &lmax);
    double *rhs = nw->rhs;                  /* the right side s_F of the direction */
    int st = factor(p, nw, w->act, delta);
    if (st) return st;
    /* finish once F repeats after a full step, or once the iterate is
     * stationary to rounding (then steps shrink for reasons of rounding) */
    int stationary = resid <= 64 * DBL_EPSILON * (lmax + DBL_MIN);
    if ((settled || stationary || early) && memcmp(w->act, w->prev, (size_t)m) == 0) {
      if (pn_finish(p, q, stop, info, !(settled || stationary))) return CUP_OK;
      for (int i = 0; i < m; i++) rhs[i] = w->act[i] ? w->s[i] : 0;   /* pn_finish used rhs */
    }
    memcpy(w->prev, w->act, (size_t)m);
    dfact_solve(nw->df, rhs);           /* d_F = -(M_FF + delta I)^-1 s_F */
    p->iters++;
    double slope = 0;
    for (int i = 0; i < m; i++) {
      int allowed = !q->rows || q->rows[i];
      w->d[i] = w->act[i] ? -rhs[i] : allowed ? -tau * w->s[i] : -w->lam[i];
      if (w->act[i]) slope += w->s[i] * w->d[i];
    }
    double alpha, ft;
    int accepted = pn_line_search(p, q, f, slope, &alpha, &ft);
    if (!accepted && delta > dmin) {        /* a regularized direction stalls near the */
      delta = dmin;                         /* answer: the exact one first */
      settled = 0;
      continue;
    }
    if (!accepted)                          /* no decrease above rounding */
      return pn_correct(p, q, stop, info);
    /* a full step settles F only at the least regularization: a full
     * damped step is short of the answer, and a finishing solve on a wrong
     * F returns a point outside K (certified, but not exact) */
    settled = alpha == 1 && delta == dmin;
    /* ... but the Levenberg parameter comes down a tenth a full step, with a
     * refactorization each (4-5 in a jam's projection): an early finishing
     * solve once a full damped step leaves F as it was, kept only if its
     * answer is certainly feasible (then as exact as an iterate main_stop
     * takes: F was right) */
    early = !q->rows && alpha == 1 && delta > dmin;
    /* Levenberg: a very short step that still changes f means the model is
     * poor: trust it less at once (steps cut short by rounding say
     * nothing); a full step trusts it more, a tenth at a time. On the
     * redundant contacts of a jam (more free rows than coordinates, M_FF
     * singular) the direction at the smallest delta is huge along M_FF's
     * kernel and steps of 1e-9 follow; waiting for 8 of them, or falling
     * back to the smallest delta after one full step, cost a third of the
     * iterations there (docs/crowd.md). */
    int measurable = f - ft > 1e3 * DBL_EPSILON * fabs(f);
    if (alpha < LM_SHORT && measurable) delta = fmin(delta * LM_UP, dmax);
    else if (alpha == 1) delta = fmax(delta / LM_DOWN, dmin);
    peak = fmax(peak, delta);
    if (!q->rows) nw->delta_peak = peak;
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
 * half way there (verification happens in certify_candidate). */
static int inward_stop(cup_projector *p, const pn_problem *q, cup_proj_info *info) {
  (void)info;
  pn_ws *w = q->w;
  for (int i = 0; i < p->m; i++)
    if (q->rows[i] && !(w->s[i] >= -16 * p->gam[i])) return 0;
  return 1;
}

static void inward_sparse(cup_projector *p, void *ws) {
  int m = p->m, n = p->n;
  newton_ws *nw = ws;
  pn_ws *w = &nw->pin;
  unsigned char *a2 = p->act2;
  int any = 0;
  for (int i = 0; i < m; i++) {
    a2[i] = p->K->rownorm[i] > 0 && (p->lam[i] > 0 || p->s[i] < 4 * p->gam[i]);
    any |= a2[i];
    nw->gin[i] = p->g[i] - (32 * p->gam[i] + DBL_MIN);
    w->lam[i] = 0;
  }
  if (!any) return;
  polyset_slack(p->K, nw->gin, p->y, nw->bin, NULL);
  pn_problem q = {p->y, nw->gin, a2, nw->bin, NULL, w, 0, nw};
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

/* The exact path returns an exact answer: a finishing solve's, or an
 * iterate that is already certainly feasible with eps met (then ||z - z*||
 * <= sqrt(eps)); an iterate certified only through an anchor's eta would be
 * accurate to sqrt(eta ||x - z||) at best. */
static int main_stop(cup_projector *p, const pn_problem *q, cup_proj_info *info) {
  pn_ws *w = q->w;
  double eq = 0, worst = INFINITY;
  for (int i = 0; i < p->m; i++) {
    eq += 2 * w->lam[i] * (w->s[i] + w->gam[i]);
    worst = la_min(worst, w->s[i] - w->gam[i]);
  }
  if (!(eq <= info->eps_target) || !(q->finishing == 1 || worst >= 0)) return 0;
  detach(p, w);                             /* certify_candidate reads p->y, p->s, p->gam */
  p->has_inward = 0;                        /* an anchor belongs to one candidate */
  p->make_inward = inward_sparse;
  p->inward_ws = q->nw;
  int ok = certify_candidate(p, q->xc, w->lam, w->y, info);
  p->make_inward = NULL;
  return ok;
}

/* A forward and a backward sweep of projected SOR on the dual, exact
 * minimization along one row at a time, over-relaxed by omega; y = x +
 * P^-1 C^T lam kept along (a row costs its nonzeros twice; M is never
 * formed). */
static void sor_sweeps(cup_projector *p, double omega, double *lam, double *y) {
  const cup_polyset *K = p->K;
  const la_sparse *Ct = &K->Ct;
  const double *pdinv = K->pdinv, *g = p->g;
  int m = p->m;
  for (int t = 0; t < 2 * m; t++) {
    int i = t < m ? t : 2 * m - 1 - t;
    double mii = K->rownorm[i] * K->rownorm[i];
    if (!(mii > 0)) continue;
    double si = g[i];
    for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) si += Ct->x[a] * y[Ct->i[a]];
    double li = la_max(lam[i] - omega * si / mii, 0), dl = li - lam[i];
    if (dl == 0) continue;
    lam[i] = li;
    for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) y[Ct->i[a]] += pdinv[Ct->i[a]] * Ct->x[a] * dl;
  }
}

/* A cold start for a Stieltjes M (an M-matrix: a chain of diodes). From
 * lam = 0 the projected Newton finds the active runs of a chain a row or
 * two at each of their ends per factorization (70 of them on a ladder of
 * 10^5 diodes). For an M-matrix, the solution lam_F of
 * (M_FF + delta I) lam_F = -b_F on ANY set of rows F (zero elsewhere) is
 * below lam* (each row has lam_i <= 0 or s_i <= 0, and such a point cannot
 * exceed the least feasible point lam* anywhere: on the rows where it did,
 * M_DD (lam - lam*)_D <= 0 with M_DD^-1 >= 0), so every row positive in
 * some lam_F is active at the answer: the proved rows only grow. The next F
 * is the proved rows and the support of a few over-relaxed Gauss-Seidel
 * sweeps from lam_F, which carry each active run along the chain much
 * further than a solve does (on ladder_100000, 10 refactorizations at
 * omega = 1.9 against 23 at omega = 1). Stops when F repeats; the projected
 * Newton finishes from the last lam_F, clipped at 0. */
#define GROW_ROUNDS 30
#define GROW_OMEGA 1.9
static void grow_start(cup_projector *p, newton_ws *nw, const double *x, pn_ws *w) {
  int m = p->m;
  double *lam = w->lam, *lamF = w->keep, *rhs = nw->rhs;
  unsigned char *F = w->act, *proved = w->prev;
  const double *rn = p->K->rownorm;
  for (int i = 0; i < m; i++) {
    lamF[i] = 0;
    proved[i] = 0;
    F[i] = rn[i] > 0 && p->b[i] < 0;
  }
  for (int round = 0; round < GROW_ROUNDS; round++) {
    if (factor(p, nw, F, dfact_delta_min(nw->df))) { memset(lamF, 0, sizeof(double) * (size_t)m); break; }
    for (int i = 0; i < m; i++) rhs[i] = F[i] ? -p->b[i] : 0;
    dfact_solve(nw->df, rhs);
    p->iters++;                             /* a solve on a free set, as a Newton step */
    for (int i = 0; i < m; i++) lam[i] = lamF[i] = F[i] ? rhs[i] : 0;
    la_sparse_gatxy(&p->K->C, lam, w->y);
    for (int j = 0; j < p->n; j++) w->y[j] = x[j] + w->y[j] * p->K->pdinv[j];
    sor_sweeps(p, GROW_OMEGA, lam, w->y);
    int changed = 0;
    for (int i = 0; i < m; i++) {
      proved[i] |= lamF[i] > 0;
      unsigned char next = rn[i] > 0 && (proved[i] || lam[i] > 0);
      changed += next != F[i];
      F[i] = next;
    }
    if (!changed) break;
  }
  for (int i = 0; i < m; i++) lam[i] = la_max(lamF[i], 0);
}

int newton_cold_start(cup_projector *p, const double *x, double *lam) {
  newton_ws *nw = proj_ws_of(p, &newton_method);
  if (!nw || !is_stieltjes(p, nw)) return 0;
  pn_ws *w = &nw->pmain;
  attach(p, w);
  polyset_slack(p->K, p->g, x, p->b, p->gam);
  p->iters = p->facts = p->updates = 0;
  grow_start(p, nw, x, w);
  memcpy(lam, w->lam, sizeof(double) * (size_t)p->m);
  detach(p, w);
  return p->iters;
}

static int solve(cup_projector *p, void *ws, const double *x, cup_proj_info *info) {
  int m = p->m;
  newton_ws *nw = ws;
  pn_ws *w = &nw->pmain;
  info->method = CUP_PROJ_ACTIVESET;
  attach(p, w);
  if (p->opt.warm_start) memcpy(w->lam, p->lam_warm, sizeof(double) * (size_t)m);
  else memset(w->lam, 0, sizeof(double) * (size_t)m);
  if (nw->stieltjes) {                      /* the scan only where the start may apply */
    int cold = 1;
    for (int i = 0; i < m && cold; i++) cold = w->lam[i] == 0;
    if (cold && is_stieltjes(p, nw)) grow_start(p, nw, x, w);
  }
  /* finishing target: a slack well above its rounding bound (the bound at x
   * is a fair estimate of the one at the answer) */
  for (int i = 0; i < m; i++) nw->tau[i] = 16 * p->gam[i] + DBL_MIN;
  pn_problem q = {x, p->g, NULL, p->b, nw->tau, w, 0, nw};
  int st = pn_solve(p, &q, main_stop, p->opt.max_iter, info);
  detach(p, w);
  if (st == CUP_WARN_NOT_CERTIFIED) certify_candidate(p, x, w->lam, w->y, info);
  return st;
}

/* The exact method for sets beyond the dense limits. */
static int takes(const cup_polyset *K, const cup_projector_options *o) {
  return !K->dense && K->m > 0 && (o->method == CUP_PROJ_AUTO || o->method == CUP_PROJ_ACTIVESET);
}

static const proj_method newton_method = {
  .name = "sparse Newton", .exact = 1, .takes = takes, .create = create, .free = free_ws,
  .revalue = revalue_values, .solve = solve,
};
const proj_method *const proj_newton = &newton_method;
