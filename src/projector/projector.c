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
#ifdef __SANITIZE_ADDRESS__
#include <sanitizer/asan_interface.h>
#define CARVE_GAP 32   /* poisoned bytes after each of the projector's vectors */
#else
#define CARVE_GAP 0
#endif

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
      p->gscale = cup_max(fabs(p->g[i]) / K->rownorm[i], p->gscale);   /* NaN passed over */
    } else if (p->g[i] < 0 && p->empty_row < 0) {
      p->empty_row = i;              /* 0 >= -g_i > 0 is impossible */
    }
  }
  p->origin_ok = p->m > 0;
  for (int i = 0; i < p->m; i++) p->origin_ok &= p->g[i] > 0;
  p->anchor_ok = -1;                 /* -1: to be rechecked against the new g */
  p->user_ok = p->user_pt ? -1 : 0;
}

/* The projector's vectors live in one block, carved in two passes over
 * lay_out: the first (base NULL) sums the sizes, the second hands out the
 * pieces. One allocation instead of about forty: on small sets (the paper
 * circuit's, 3 x 2) a third of the projector's heap was malloc's minimum
 * chunk and header per vector. Under ASan each piece is followed by a
 * poisoned gap, so that an overrun into the next vector is still caught. */
typedef struct { char *base; size_t used; } carve_t;

static void *carve(carve_t *a, size_t count, size_t size) {
  size_t at = a->used, bytes = (count ? count : 1) * size;
  a->used += (bytes + CARVE_GAP + 15) & ~(size_t)15;    /* 16-byte aligned pieces */
  if (!a->base) return NULL;
#ifdef __SANITIZE_ADDRESS__
  ASAN_POISON_MEMORY_REGION(a->base + at + bytes, a->used - at - bytes);
#endif
  return a->base + at;
}

static void lay_out(cup_projector *p, carve_t *a, int user_point) {
  const cup_polyset *K = p->K;
  size_t N = (size_t)p->n, M = (size_t)p->m, D = sizeof(double);
  p->g = carve(a, M, D);
  p->lam = carve(a, M, D);
  p->lam_warm = carve(a, M, D);
  p->b = carve(a, M, D);
  p->s = carve(a, M, D);
  p->gam = carve(a, M, D);
  p->sv = carve(a, M, D);
  p->gamv = carve(a, M, D);
  p->y = carve(a, N, D);
  p->u = carve(a, N, D);
  p->y2 = carve(a, N, D);
  p->s2 = carve(a, M, D);
  p->gam2 = carve(a, M, D);
  p->v = carve(a, N, D);
  p->s_v = carve(a, M, D);
  p->anchor = carve(a, N, D);
  p->s_anchor = carve(a, M, D);
  p->inward = carve(a, N, D);
  p->s_inward = carve(a, M, D);
  p->origin = carve(a, N, D);
  p->farkas = carve(a, M, D);
  p->wn = carve(a, N, D);
  p->wn2 = carve(a, N, D);
  p->act2 = carve(a, M, 1);
  /* the first-order methods' and the dense active set's (with its FISTA
   * fallback): the sparse exact path never touches them (a tenth of the
   * projector's vectors) */
  if (K->dense || (p->opt.method != CUP_PROJ_AUTO && p->opt.method != CUP_PROJ_ACTIVESET)) {
    p->lam_fista = carve(a, M, D);
    p->wm = carve(a, M, D);
    p->wm2 = carve(a, M, D);
    p->wm3 = carve(a, M, D);
    p->wm4 = carve(a, M, D);
    p->iwm = carve(a, M, sizeof(int));
    p->act = carve(a, M, 1);
  }
  if (user_point) {
    p->user_pt = carve(a, N, D);
    p->s_user = carve(a, M, D);
  }
  if (K->dense) {
    p->dwork = carve(a, M * M + 6 * M, D);
    for (int c = 0; c < CUP_DENSE_CACHE; c++) {
      p->cache[c].idx = carve(a, M, sizeof(int));
      p->cache[c].perm = carve(a, M, sizeof(int));
      p->cache[c].l = carve(a, M * M, D);
    }
  }
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
  int n = p->n = K->n, m = p->m = K->m;
  size_t N = (size_t)n, M = (size_t)m;
  carve_t a = {NULL, 0};
  lay_out(p, &a, opt && opt->feasible_point);         /* sizes */
  a.base = p->block = calloc(1, a.used);
  p->block_bytes = a.used;
  a.used = 0;
  if (!p->block) {
    cup_projector_free(&p);
    return cup_fail(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  }
  lay_out(p, &a, opt && opt->feasible_point);         /* pieces */
  if (p->user_pt) memcpy(p->user_pt, opt->feasible_point, sizeof(double) * N);
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
#ifdef __SANITIZE_ADDRESS__
  if (p->block) ASAN_UNPOISON_MEMORY_REGION(p->block, p->block_bytes);
#endif
  free(p->block);
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

void cup_projector_checkpoint(cup_projector *p, cup_ckpt *c) {
  size_t M = sizeof(double) * (size_t)p->m, N = sizeof(double) * (size_t)p->n;
  cup_ckpt_io(c, p->g, M);
  CUP_CKPT_IO(c, p->gscale);
  CUP_CKPT_IO(c, p->empty_row);
  CUP_CKPT_IO(c, p->origin_ok);
  CUP_CKPT_IO(c, p->user_ok);
  cup_ckpt_io(c, p->lam, M);
  cup_ckpt_io(c, p->lam_warm, M);
  cup_ckpt_io(c, p->anchor, N);
  cup_ckpt_io(c, p->s_anchor, M);
  CUP_CKPT_IO(c, p->anchor_ok);
  if (p->small) cup_lcp_step_checkpoint(p->small, c);
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

int cup_project_exact(cup_projector *p, const double *x, double *z, cup_proj_info *info) {
  if (!p) return CUP_ERR_ARG;
  int method = p->opt.method;
  if (p->K->dense || p->nw) p->opt.method = CUP_PROJ_ACTIVESET;   /* the small path is AUTO's alone */
  int st = cup_project(p, x, z, info);
  p->opt.method = method;
  return st;
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
