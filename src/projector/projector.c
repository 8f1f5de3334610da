/* projector — certified (eps, eta)-approximate projections onto a polyset
 * (paper, Sec. 2 definition; Sec. 7 dual method). This file: set-up, the
 * skip path, and the choice of method; the certificates every method
 * returns through are in certify.c, below the methods. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "catchup/projector.h"
#include "certify.h"
#include "firstorder.h"
#include "activeset.h"
#include "newton.h"
#include "dual_factor.h"
#include "projector.h"
#include "lcp/step.h"

void cup_projector_options_default(cup_projector_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->method = CUP_PROJ_AUTO;
  o->eps_abs = 0;
  o->eps_rel = 1e-10;
  o->eta_abs = 0;
  o->eta_rel = 1e-10;
  o->max_iter = 100000;
  o->warm_start = 1;
  o->return_feasible = 0;
  o->lipschitz = 0;
  o->feasible_point = NULL;
  o->factor_updates = 1;
}

static void offset_changed(cup_projector *p) {
  const cup_polyset *K = p->K;
  p->gscale = 0;
  p->empty_row = -1;
  for (int i = 0; i < p->m; i++) {
    if (K->rownorm[i] > 0) {
      p->gscale = fmax(p->gscale, fabs(p->g[i]) / K->rownorm[i]);
    } else if (p->g[i] < 0 && p->empty_row < 0) {
      p->empty_row = i;              /* 0 >= -g_i > 0 is impossible */
    }
  }
  p->origin_ok = p->m > 0;
  for (int i = 0; i < p->m; i++) p->origin_ok &= p->g[i] > 0;
  p->anchor_ok = -1;                 /* -1: to be rechecked against the new g */
  p->user_ok = p->user_pt ? -1 : 0;
}

static void *xalloc(size_t count, size_t size, int *fail) {
  void *q = calloc(count ? count : 1, size);
  if (!q) *fail = 1;
  return q;
}

int cup_projector_create(cup_projector **out, const cup_polyset *K,
                         const cup_projector_options *opt, char *errmsg) {
  if (!out) return cup_fail(errmsg, CUP_ERR_ARG, "projector: output pointer is NULL");
  *out = NULL;
  if (!K) return cup_fail(errmsg, CUP_ERR_ARG, "projector: polyset is NULL");
  cup_projector_options o;
  if (opt) o = *opt; else cup_projector_options_default(&o);
  if (o.method < CUP_PROJ_AUTO || o.method > CUP_PROJ_ACTIVESET)
    return cup_fail(errmsg, CUP_ERR_ARG, "projector: unknown method %d", (int)o.method);
  if (!(o.eps_abs >= 0) || !(o.eps_rel >= 0) || !(o.eta_abs >= 0) || !(o.eta_rel >= 0))
    return cup_fail(errmsg, CUP_ERR_ARG,
                    "projector: tolerances must be >= 0 (eps_abs %g, eps_rel %g, eta_abs %g, eta_rel %g)",
                    o.eps_abs, o.eps_rel, o.eta_abs, o.eta_rel);
  if (o.max_iter < 1)
    return cup_fail(errmsg, CUP_ERR_ARG, "projector: max_iter = %d, must be >= 1", o.max_iter);
  if (!(o.lipschitz >= 0) || isinf(o.lipschitz))
    return cup_fail(errmsg, CUP_ERR_ARG, "projector: lipschitz = %g, must be finite and >= 0", o.lipschitz);
  cup_projector *p = calloc(1, sizeof *p);
  if (!p) return cup_fail(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  p->K = K;
  p->opt = o;
  p->opt.feasible_point = NULL;
  int n = p->n = K->n, m = p->m = K->m, fail = 0;
  size_t N = (size_t)n, M = (size_t)m;
  p->g = xalloc(M, sizeof(double), &fail);
  p->lam = xalloc(M, sizeof(double), &fail);
  p->lam_warm = xalloc(M, sizeof(double), &fail);
  p->b = xalloc(M, sizeof(double), &fail);
  p->s = xalloc(M, sizeof(double), &fail);
  p->gam = xalloc(M, sizeof(double), &fail);
  p->sv = xalloc(M, sizeof(double), &fail);
  p->gamv = xalloc(M, sizeof(double), &fail);
  p->y = xalloc(N, sizeof(double), &fail);
  p->u = xalloc(N, sizeof(double), &fail);
  p->y2 = xalloc(N, sizeof(double), &fail);
  p->s2 = xalloc(M, sizeof(double), &fail);
  p->gam2 = xalloc(M, sizeof(double), &fail);
  p->v = xalloc(N, sizeof(double), &fail);
  p->s_v = xalloc(M, sizeof(double), &fail);
  p->anchor = xalloc(N, sizeof(double), &fail);
  p->s_anchor = xalloc(M, sizeof(double), &fail);
  p->inward = xalloc(N, sizeof(double), &fail);
  p->s_inward = xalloc(M, sizeof(double), &fail);
  p->origin = xalloc(N, sizeof(double), &fail);
  p->farkas = xalloc(M, sizeof(double), &fail);
  p->wn = xalloc(N, sizeof(double), &fail);
  p->wn2 = xalloc(N, sizeof(double), &fail);
  p->act2 = xalloc(M, 1, &fail);
  /* the first-order methods' and the dense active set's (with its FISTA
   * fallback): the sparse exact path never touches them (a tenth of the
   * projector's vectors) */
  if (K->dense || (o.method != CUP_PROJ_AUTO && o.method != CUP_PROJ_ACTIVESET)) {
    p->lam_fista = xalloc(M, sizeof(double), &fail);
    p->wm = xalloc(M, sizeof(double), &fail);
    p->wm2 = xalloc(M, sizeof(double), &fail);
    p->wm3 = xalloc(M, sizeof(double), &fail);
    p->wm4 = xalloc(M, sizeof(double), &fail);
    p->iwm = xalloc(M, sizeof(int), &fail);
    p->act = xalloc(M, 1, &fail);
  }
  if (opt && opt->feasible_point) {
    p->user_pt = xalloc(N, sizeof(double), &fail);
    p->s_user = xalloc(M, sizeof(double), &fail);
    if (!fail) memcpy(p->user_pt, opt->feasible_point, sizeof(double) * N);
  }
  if (K->dense) {
    p->dwork = xalloc(M * M + 6 * M, sizeof(double), &fail);
    for (int c = 0; c < CUP_DENSE_CACHE; c++) {
      p->cache[c].idx = xalloc(M, sizeof(int), &fail);
      p->cache[c].perm = xalloc(M, sizeof(int), &fail);
      p->cache[c].l = xalloc(M * M, sizeof(double), &fail);
    }
  }
  if (fail) {
    cup_projector_free(&p);
    return cup_fail(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  }
  memcpy(p->g, K->g0, sizeof(double) * M);
  offset_changed(p);
  if (p->user_pt) {
    for (int j = 0; j < n; j++)
      if (!isfinite(p->user_pt[j])) {
        cup_projector_free(&p);
        return cup_fail(errmsg, CUP_ERR_NONFINITE, "projector: feasible_point[%d] is not finite", j);
      }
  }
  int needs_newton = !K->dense && m > 0 &&
                     (o.method == CUP_PROJ_AUTO || o.method == CUP_PROJ_ACTIVESET);
  if (needs_newton) {
    int st = cup_newton_create(p, errmsg);
    if (st) { cup_projector_free(&p); return st; }
  }
  if (K->dense && m > 0 && o.method == CUP_PROJ_AUTO) {
    p->small = calloc(1, sizeof *p->small);
    int st = p->small ? cup_lcp_step_init(p->small, K, NULL, 1.0) : CUP_ERR_NOMEM;
    if (st) { cup_projector_free(&p); return cup_fail(errmsg, st, "projector: out of memory"); }
  }
  *out = p;
  return CUP_OK;
}

void cup_projector_free(cup_projector **pp) {
  if (!pp || !*pp) return;
  cup_projector *p = *pp;
  cup_newton_free(p);
  if (p->small) cup_lcp_step_free(p->small);
  free(p->small);
  free(p->g); free(p->lam); free(p->lam_warm); free(p->lam_fista); free(p->b); free(p->s); free(p->gam);
  free(p->sv); free(p->gamv); free(p->y); free(p->u); free(p->y2); free(p->s2); free(p->gam2); free(p->v); free(p->s_v); free(p->anchor);
  free(p->s_anchor); free(p->user_pt); free(p->s_user); free(p->inward); free(p->s_inward); free(p->origin); free(p->farkas);
  free(p->wn); free(p->wn2); free(p->wm); free(p->wm2); free(p->wm3); free(p->wm4);
  free(p->iwm); free(p->act); free(p->act2); free(p->dwork);
  for (int c = 0; c < CUP_DENSE_CACHE; c++) {
    free(p->cache[c].idx); free(p->cache[c].perm); free(p->cache[c].l);
  }
  free(p);
  *pp = NULL;
}

int cup_projector_set_offset(cup_projector *p, const double *g) {
  if (!p || (!g && p->m > 0)) return CUP_ERR_ARG;
  for (int i = 0; i < p->m; i++)
    if (!isfinite(g[i])) return CUP_ERR_NONFINITE;
  if (p->m) memcpy(p->g, g, sizeof(double) * (size_t)p->m);
  offset_changed(p);
  return CUP_OK;
}

int cup_projector_set_tolerances(cup_projector *p, double eps_abs, double eps_rel,
                                 double eta_abs, double eta_rel) {
  if (!p) return CUP_ERR_ARG;
  if (!(eps_abs >= 0) || !(eps_rel >= 0) || !(eta_abs >= 0) || !(eta_rel >= 0))
    return CUP_ERR_ARG;
  p->opt.eps_abs = eps_abs; p->opt.eps_rel = eps_rel;
  p->opt.eta_abs = eta_abs; p->opt.eta_rel = eta_rel;
  return CUP_OK;
}

int cup_projector_offer_feasible(cup_projector *p, const double *w) {
  if (!p || !w) return 0;
  for (int j = 0; j < p->n; j++)
    if (!isfinite(w[j])) return 0;
  if (cup_slack(p->K, p->g, w, p->s_anchor, p->gamv) < 0) return 0;
  cup_copy(p->anchor, w, p->n);
  p->anchor_ok = 1;
  return 1;
}

void cup_projector_reset(cup_projector *p) {
  if (p && p->m) memset(p->lam_warm, 0, sizeof(double) * (size_t)p->m);
  if (p && p->small) cup_lcp_forget(&p->small->lcp);
}

void cup_projector_revalue(cup_projector *p) {
  offset_changed(p);                      /* row norms changed: scale, empty rows, anchors */
  for (int i = 0; i < p->m; i++)
    if (!(p->K->rownorm[i] > 0)) p->lam_warm[i] = 0;   /* a row that is off holds nothing */
  p->has_fista = 0;
  for (int c = 0; c < CUP_DENSE_CACHE; c++) p->cache[c].mask = 0;
  if (p->nw) {
    cup_dfact_revalue(p->nw->df);
    cup_newton_revalue(p);
  }
}

const double *cup_projector_lambda(const cup_projector *p) { return p ? p->lam : NULL; }
const double *cup_projector_feasible(const cup_projector *p) {
  return p && p->has_v ? p->v : NULL;
}
const double *cup_projector_farkas(const cup_projector *p) { return p ? p->farkas : NULL; }

/* ---- the projection ----------------------------------------------------------- */

/* Small dense sets, auto method: the dual LCP solved exactly by principal
 * pivoting (closed form on one or two active rows), the rows aimed a few
 * ulps inside K: the LCP step (lcp/step.h) with W = I and h = 1. z is then
 * certainly in K (eta = 0) and eps is the weak-duality gap, as cup_certify
 * computes it. Returns 1 with z and info filled when that certifies the
 * targets; 0 leaves everything to the general path (a singular block, a
 * set without interior, a tolerance below rounding). */
static int project_small(cup_projector *p, const double *x, double *z, cup_proj_info *info) {
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  if (!p->opt.warm_start) cup_lcp_forget(&p->small->lcp);
  cup_proj_info ti;
  if (cup_lcp_step_solve(p->small, p->g, x, p->y, info->scale, info->eps_target, info->eta_target,
                         &ti))
    return 0;
  double un = ti.skipped ? 0 : cup_step_norm(p, p->y, x);   /* ||z - x||_P */
  double ebound = ti.skipped ? 0 : cup_z_rounding(K, info->scale, un);
  double eps = ti.eps_cert + ebound * ebound;
  if (!(eps <= info->eps_target)) return 0;
  info->eps_cert = eps;
  info->eta_cert = ti.eta_cert;
  info->violation = ti.violation;
  info->dual_value = -2 * p->small->lq - un * un;
  info->skipped = ti.skipped;
  info->iterations = ti.iterations;
  info->active = ti.active;
  info->method = ti.skipped ? p->opt.method : CUP_PROJ_ACTIVESET;
  memcpy(p->lam, p->small->lcp.lam, sizeof(double) * (size_t)m);
  if (p->opt.warm_start && !ti.skipped) memcpy(p->lam_warm, p->lam, sizeof(double) * (size_t)m);
  memcpy(z, p->y, sizeof(double) * (size_t)n);
  info->status = CUP_OK;
  return 1;
}

int cup_project(cup_projector *p, const double *x, double *z, cup_proj_info *info_out) {
  cup_proj_info local;
  cup_proj_info *info = info_out ? info_out : &local;
  *info = (cup_proj_info){.eta_cert = INFINITY};
  if (!p || !x || !z) return info->status = CUP_ERR_ARG;
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  for (int j = 0; j < n; j++)
    if (!isfinite(x[j])) return info->status = CUP_ERR_NONFINITE;
  p->has_v = 0;
  p->has_inward = 0;
  p->make_inward = NULL;
  p->iters = p->facts = p->updates = 0;
  double S = cup_max(cup_polyset_norm(K, x), p->gscale);
  if (!isfinite(S)) return info->status = CUP_ERR_DIVERGED;   /* ||x||_P overflowed */
  info->scale = S;
  info->eps_target = p->opt.eps_abs + (p->opt.eps_rel > 0 ? p->opt.eps_rel * S * S : 0);
  info->eta_target = p->opt.eta_abs + (p->opt.eta_rel > 0 ? p->opt.eta_rel * S : 0);
  info->method = p->opt.method;
  if (p->empty_row >= 0) {                 /* a row 0 >= -g_i with g_i < 0 */
    memset(p->farkas, 0, sizeof(double) * (size_t)m);
    p->farkas[p->empty_row] = 1;
    info->farkas_gap = p->g[p->empty_row];
    info->farkas_residual = 0;
    return info->status = CUP_ERR_EMPTY_SET;
  }
  if (p->small && !p->user_pt && !p->opt.return_feasible && project_small(p, x, z, info))
    return CUP_OK;
  cup_slack(K, p->g, x, p->b, p->gam);
  double worst_raw = INFINITY;
  for (int i = 0; i < m; i++) worst_raw = cup_min(worst_raw, p->b[i]);
  if (worst_raw >= 0) {                    /* x in K: returned unchanged, exactly */
    if (z != x) cup_copy(z, x, n);
    cup_zero(p->lam, m);
    info->skipped = 1;
    double worst = INFINITY;
    for (int i = 0; i < m; i++) worst = cup_min(worst, p->b[i] - p->gam[i]);
    if (worst >= 0) {                      /* certainly inside: nothing to certify */
      info->eta_cert = info->eps_cert = 0;
      cup_copy(p->anchor, x, n);           /* and a good anchor for later */
      cup_copy(p->s_anchor, p->b, m);
      p->anchor_ok = 1;
      return info->status = CUP_OK;
    }
    cup_copy(p->s, p->b, m);
    cup_certify(p, x, p->lam, x, info);
    info->eps_cert = 0;                    /* z = x exactly: no excess at all */
    info->status = info->eta_cert <= info->eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
    return info->status;
  }
  int method = p->opt.method, st;
  if (method == CUP_PROJ_AUTO || method == CUP_PROJ_ACTIVESET)
    st = K->dense ? cup_proj_dense_activeset(p, x, info) : cup_proj_sparse_newton(p, x, info);
  else {
    if (p->opt.warm_start) memcpy(p->lam, p->lam_warm, sizeof(double) * (size_t)m);
    else memset(p->lam, 0, sizeof(double) * (size_t)m);
    st = cup_proj_firstorder(p, x, method == CUP_PROJ_FISTA, p->opt.max_iter, info);
  }
  info->iterations = p->iters;
  info->factorizations = p->facts;
  info->row_updates = p->updates;
  info->status = st;
  if (st < 0) return st;
  const double *res = (p->opt.return_feasible && p->has_v) ? p->v : p->y;
  for (int j = 0; j < n; j++)              /* an overflowed iterate is an error, never an answer */
    if (!isfinite(res[j])) return info->status = CUP_ERR_DIVERGED;
  int active = 0;
  for (int i = 0; i < m; i++) active += p->lam[i] > 0;
  info->active = active;
  if (p->opt.warm_start) memcpy(p->lam_warm, p->lam, sizeof(double) * (size_t)m);
  memcpy(z, res, sizeof(double) * (size_t)n);
  return st;
}
